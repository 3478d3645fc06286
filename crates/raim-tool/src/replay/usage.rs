//! Option combinations `raim replay` refuses as usage errors (exit 2, both
//! options named) rather than running with one of them silently ignored.
//!
//! A replay runs one monitor: the snapshot RAIM (default), `--araim`,
//! `--pf` or the ESQ/PCA studies (`--esq`, `--pca`, `--esq-mcusum`). Each
//! monitor's own options (the flattened argument groups) only mean
//! something with it, and the per-epoch outputs that only the snapshot
//! monitor produces (`.pos`, CSV, KML, GPX, `--plot`; NMEA also with
//! `--araim`) are refused with the others. The firmware runs the snapshot
//! monitor and ARAIM (`--target qemu`). Only options given on the command line count: a
//! default, or a value taken from a `--config` run file, never conflicts.

use clap::parser::ValueSource;
use clap::{ArgMatches, Args, Command};

use super::{ReplayArgs, Target};

/// The monitor a replay runs, in the order `replay::run` picks it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Monitor {
    Snapshot,
    Araim,
    Pf,
    Esq,
}

impl Monitor {
    pub fn of(args: &ReplayArgs) -> Self {
        if args.esq.any() {
            Monitor::Esq
        } else if args.araim.araim {
            Monitor::Araim
        } else if args.pf.pf.is_some() {
            Monitor::Pf
        } else {
            Monitor::Snapshot
        }
    }

    /// The option that selects the monitor, as the user wrote it.
    fn flag(self, args: &ReplayArgs) -> &'static str {
        match self {
            Monitor::Snapshot => "the snapshot monitor (no --araim, --pf, --esq or --pca)",
            Monitor::Araim => "--araim",
            Monitor::Pf => "--pf",
            Monitor::Esq if args.esq.esq => "--esq",
            Monitor::Esq if args.esq.pca => "--pca",
            Monitor::Esq => "--esq-mcusum",
        }
    }
}

/// The long names of a flattened argument group's options.
fn ids_of(augment: fn(Command) -> Command) -> Vec<String> {
    augment(Command::new("group"))
        .get_arguments()
        .map(|a| a.get_id().to_string())
        .collect()
}

fn long(id: &str) -> String {
    format!("--{}", id.replace('_', "-"))
}

/// The first refused combination, as a one-line message naming both
/// options, or None.
pub fn check(args: &ReplayArgs, m: &ArgMatches) -> Option<String> {
    let given = |id: &str| {
        m.try_contains_id(id).unwrap_or(false)
            && m.value_source(id) == Some(ValueSource::CommandLine)
    };
    let monitor = Monitor::of(args);
    let mon = monitor.flag(args);

    if args.nmea.is_some() && args.json {
        return Some(
            "'--nmea' cannot be used with '--json': both write stdout (write the NMEA \
             stream to a file with --nmea-file beside --json)"
                .into(),
        );
    }
    if args.nmea.is_some() && args.quiet {
        return Some(
            "'--nmea' cannot be used with '--quiet': --quiet prints only the summary \
             (use --nmea-file to keep the stream)"
                .into(),
        );
    }
    if args.araim.araim && args.pf.pf.is_some() {
        return Some(
            "'--araim' cannot be used with '--pf': they are two different monitors, choose one"
                .into(),
        );
    }
    if args.esq.any() && args.pf.pf.is_some() {
        return Some(format!(
            "'{mon}' cannot be used with '--pf': the ESQ/PCA studies run on the ARAIM \
             engine, not the particle filter; run them separately"
        ));
    }
    if !matches!(monitor, Monitor::Snapshot | Monitor::Araim) && args.target == Target::Qemu {
        return Some(format!(
            "'{mon}' cannot be used with '--target qemu': the firmware runs the snapshot \
             monitor and ARAIM; {mon} runs on the host only"
        ));
    }
    if monitor == Monitor::Araim && args.target == Target::Qemu && given("araim_iono_m") {
        return Some(
            "'--araim-iono-m' cannot be used with '--target qemu': the device's error \
             model is its ISM with the ADD elevation curves, without a residual \
             ionosphere term"
                .into(),
        );
    }
    if monitor != Monitor::Snapshot {
        // ARAIM epochs write NMEA (on the device as on the host).
        let nmea: &[&str] = if monitor == Monitor::Araim {
            &[]
        } else {
            &["nmea", "nmea_file"]
        };
        for &id in nmea
            .iter()
            .chain(&["pos", "csv", "kml", "gpx", "plot", "keep_going"])
        {
            if given(id) {
                let hint = match (id, monitor) {
                    ("plot", Monitor::Araim) => " (use --araim-plot)",
                    ("plot", Monitor::Pf) => " (use --pf-plot)",
                    ("plot", Monitor::Esq) => " (use --esq-plot)",
                    _ => "",
                };
                return Some(format!(
                    "'{}' cannot be used with '{mon}': it is an output of the snapshot \
                     monitor{hint}",
                    long(id)
                ));
            }
        }
    }
    // Each monitor's own options, given while another monitor runs.
    let groups: [(Monitor, &str, Vec<String>); 3] = [
        (Monitor::Pf, "--pf", ids_of(super::pf::PfArgs::augment_args)),
        (
            Monitor::Araim,
            "--araim",
            ids_of(super::araim::AraimReplayArgs::augment_args),
        ),
        (
            Monitor::Esq,
            "--esq, --pca or --esq-mcusum",
            ids_of(super::esq::EsqArgs::augment_args),
        ),
    ];
    for (owner, owner_flag, ids) in &groups {
        if *owner == monitor {
            continue;
        }
        for id in ids {
            // The selecting flags themselves were handled above.
            if matches!(id.as_str(), "pf" | "araim" | "esq" | "pca" | "esq_mcusum") {
                continue;
            }
            if given(id) {
                let runs = if monitor == Monitor::Snapshot {
                    format!("it needs {owner_flag}")
                } else {
                    format!("it belongs to {owner_flag}, and {mon} runs instead")
                };
                return Some(format!("'{}' would be ignored: {runs}", long(id)));
            }
        }
    }
    if args.araim.araim && monitor == Monitor::Esq {
        // `--araim --esq`: the ESQ/PCA studies run; --araim only selects
        // their ARAIM engine, so its own outputs would be ignored.
        if given("araim_plot") {
            return Some(format!(
                "'--araim-plot' cannot be used with '{mon}': the ESQ/PCA studies run \
                 instead of the ARAIM replay (use --esq-plot)"
            ));
        }
    }
    if let Some(m) = model_check(args, monitor, mon, &given) {
        return Some(m);
    }
    if let Some(m) = args.config.ignored(&given) {
        return Some(m);
    }
    if given("pf_onset_spread_s") && args.pf.pf_seeds < 2 {
        return Some(
            "'--pf-onset-spread-s' would be ignored: it needs --pf-seeds 2 or more".into(),
        );
    }
    None
}

/// `--model-check` (docs/MODEL_CHECK.md): a host study beside the snapshot
/// monitor or `--araim`, with its own report only; its options need it.
fn model_check(
    args: &ReplayArgs,
    monitor: Monitor,
    mon: &str,
    given: &dyn Fn(&str) -> bool,
) -> Option<String> {
    let mc = &args.model_check;
    if !mc.model_check {
        for id in ids_of(super::model_check::ModelCheckArgs::augment_args) {
            if id != "model_check" && given(&id) {
                return Some(format!(
                    "'{}' would be ignored: it needs --model-check",
                    long(&id)
                ));
            }
        }
        return None;
    }
    if !matches!(monitor, Monitor::Snapshot | Monitor::Araim) {
        return Some(format!(
            "'--model-check' cannot be used with '{mon}': it runs beside the snapshot \
             monitor or --araim"
        ));
    }
    if args.target == Target::Qemu {
        return Some(
            "'--model-check' cannot be used with '--target qemu': it runs on the host".into(),
        );
    }
    for id in [
        "pos",
        "csv",
        "kml",
        "gpx",
        "plot",
        "nmea",
        "nmea_file",
        "araim_plot",
        "keep_going",
        "quiet",
    ] {
        if given(id) {
            return Some(format!(
                "'{}' cannot be used with '--model-check': the model check prints its \
                 report only",
                long(id)
            ));
        }
    }
    None
}
