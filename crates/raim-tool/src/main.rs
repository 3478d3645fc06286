//! `raim`: host tools for the raim-core integrity monitor.

mod araim_cmd;
mod arl;
mod campaign;
mod config_args;
mod epoch_json;
mod link;
mod outcome;
mod pci;
mod pf_table;
mod provision_cmd;
mod qemu;
mod replay;
mod result_json;
mod rtcm_fault;
mod runfile;
mod snapshot;

use std::process::ExitCode;

use anyhow::Result;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use raim_core::stats::dist;

use config_args::ConfigArgs;
use outcome::Tally;

/// `println!` that returns the write error (a closed pipe: `raim ... | head`)
/// instead of panicking, so the caller can end quietly.
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($t)*)
    }};
}

/// `print!` that returns the write error; see [`outln!`].
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout(), $($t)*)
    }};
}

#[derive(Parser)]
#[command(
    name = "raim",
    version,
    about = "GNSS integrity monitor (RAIM) host tools",
    after_help = outcome::HELP,
    next_line_help = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Read epochs as JSON lines on stdin (docs/FORMATS.md); print one result per epoch.
    #[command(after_help = examples::SNAPSHOT)]
    Snapshot {
        #[command(flatten, next_help_heading = "Monitor (docs/CORE.md)")]
        config: ConfigArgs,
        /// Print one JSON object per line instead of text.
        #[arg(long)]
        json: bool,
        /// Read from this file instead of stdin.
        #[arg(long)]
        input: Option<std::path::PathBuf>,
        /// Exit 0 even when some epochs were refused (they are still
        /// reported in the output and counted on stderr).
        #[arg(long)]
        keep_going: bool,
    },
    /// ARAIM (docs/ARAIM.md) on ARAIM epochs as JSON lines (docs/FORMATS.md).
    #[command(after_help = examples::ARAIM)]
    Araim(araim_cmd::AraimArgs),
    /// ARAIM availability over a user grid from almanacs: coverage, per-user availability and PLs (docs/AVAILABILITY.md).
    Availability(raim_availability::cli::AvailabilityArgs),
    /// Seeded Monte Carlo validation campaigns (false-alarm rate; single-fault identification).
    #[command(after_help = examples::CAMPAIGN)]
    Campaign {
        #[command(subcommand)]
        which: campaign::CampaignCmd,
    },
    /// Probability of correct identification per satellite, MLE vs L-RAIM (exact and Monte Carlo), P_D, MDB.
    #[command(after_help = examples::PCI)]
    Pci(pci::PciArgs),
    /// MCUSUM average run lengths (docs/MCRAIM.md): ARL0(h) / h(ARL0) by the integral equation, ARL1 by simulation, the device table.
    #[command(after_help = examples::ARL)]
    Arl(arl::ArlArgs),
    /// The particle-filter RAIM's threshold table from an allocated false-alarm probability (docs/PF.md "Thresholds").
    #[command(after_help = examples::PF_TABLE)]
    PfTable(pf_table::PfTableArgs),
    /// Replay RINEX data through the monitor with seeded faults (docs/REPLAY.md).
    #[command(after_help = examples::REPLAY, args_override_self = true)]
    Replay(Box<replay::ReplayArgs>),
    /// Replay a JSON-lines epoch file through the firmware under QEMU; print decisions and NMEA (docs/PROTOCOL.md).
    #[command(after_help = examples::QEMU)]
    Qemu(qemu::QemuArgs),
    /// The chi-square detection threshold; with --pmd, lambda and pbias too.
    #[command(after_help = examples::THRESHOLD)]
    Threshold {
        /// Probability of false alarm per sample, e.g. 3.3333e-7.
        #[arg(long)]
        pfa: f64,
        /// Degrees of freedom of the chi-square test (satellites - unknowns).
        #[arg(long)]
        dof: u32,
        /// Probability of missed detection: also print the non-centrality
        /// lambda and pbias = sqrt(lambda) (docs/CORE.md).
        #[arg(long)]
        pmd: Option<f64>,
        /// Print one JSON object instead of text (docs/FORMATS.md).
        #[arg(long)]
        json: bool,
    },
    /// Print a shell completion script for raim (bash, zsh, fish, elvish, powershell).
    #[command(after_help = examples::COMPLETIONS)]
    Completions {
        /// The shell to complete for.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the raim(1) man page (roff), from the same definitions as --help.
    #[command(after_help = examples::MAN)]
    Man,
    /// Talk to a unit over a serial port: Status, Configure, Lock (docs/RECEIVERS.md).
    #[command(after_help = examples::LINK)]
    Link(link::LinkArgs),
    /// Seal a unit configuration into a firmware image: the installation step (docs/PROTOCOL.md "Configuration authority").
    #[command(after_help = examples::PROVISION)]
    Provision(provision_cmd::ProvisionArgs),
    /// Re-encode an RTCM 3 stream with seeded faults on its MSM pseudoranges, as replay --fault (docs/RECEIVERS.md "Faults in a stream").
    #[command(after_help = examples::RTCM_FAULT)]
    RtcmFault(rtcm_fault::RtcmFaultArgs),
}

/// The examples that end each subcommand's `--help`.
mod examples {
    pub const LINK: &str = "Examples:
  raim link --port /dev/ttyUSB0 status
  raim link --port /dev/pts/3 configure lock status --pfa 1e-5
  raim link --port /dev/ttyUSB0 epochs -- --rtcm3 GMSD7_20121014.rtcm3 --systems GR --mask-deg 0";
    pub const RTCM_FAULT: &str = "Examples:
  raim rtcm-fault --in esbc.rtcm3 --out esbc_e11.rtcm3 --fault step:E11:30@+600
  raim rtcm-fault --in GMSD7_20121014.rtcm3 --out ramp.rtcm3 --fault ramp:G06:0.5@00:10:00 --fault noise:G:t3:0.5 --seed 7";
    pub const PROVISION: &str = "Examples:
  raim provision --config unit.toml -o unit.elf firmware/target/thumbv7em-none-eabihf/release/raim-firmware
  raim provision --config unit.toml --key $(cat unit42.key) -o unit42.elf raim-firmware";
    pub const SNAPSHOT: &str = "Examples:
  raim snapshot --input host-tests/vectors/snapshot_example.jsonl
  raim snapshot --json --phase terminal < epochs.jsonl
  raim snapshot --mcusum --multifault-t-max 2 --input epochs.jsonl

Text columns: t (s), decision, D2 = all-in-view test statistic (chi-square, no unit), T2 = its threshold, dof,
excluded satellites, alarm cause, HPL/VPL (m; inf when unbounded). JSON keys: docs/FORMATS.md.";
    pub const ARAIM: &str = "Examples:
  raim araim --input host-tests/vectors/add_v3_appendix_d.json
  raim araim --json --input epochs.jsonl";
    pub const CAMPAIGN: &str = "Examples:
  raim campaign false-alarm --pfa 1e-3 --pfa 1e-5
  raim campaign single-fault --json";
    pub const PCI: &str = "Examples:
  raim pci --az 0,45,100,160,220,280,330 --el 85,30,50,20,60,15,40
  raim pci --json < host-tests/vectors/snapshot_example.jsonl";
    pub const ARL: &str = "Examples:
  raim arl --dim 2 --k 1 --arl0 1e5
  raim arl --dim 2 --k 1 --h 8.5
  raim arl --seed001";
    pub const REPLAY: &str = "Examples:
  raim replay --obs 07590920.05o --nav 07590920.05n --systems G --fault step:G24:50@00:20:00 --plot replay.png
  raim replay --config docs/runs/replay_0759_g24_step50.toml --pos run.pos --kml run.kml
  raim replay --obs esbc.rnx --nav esbc.nav --araim --araim-plot araim.png --mask-deg -5

Text columns: time of day (GPS time), decision, n = satellites, D2 = all-in-view test statistic (chi-square,
no unit), T2 = its threshold, dof = degrees of freedom, excl = excluded satellites, cause = why an alarm,
errH/errV = horizontal/vertical position error against the reference (m), HPL/VPL = protection levels (m; inf
when unbounded), fault = injected biases (m). Every column and JSON key: docs/FORMATS.md.";
    pub const PF_TABLE: &str = "Examples:
  raim pf-table --out crates/raim-core/src/pf/threshold_table.rs
  raim pf-table --only gapf --epochs 2000";
    pub const QEMU: &str = "Examples:
  raim qemu --input host-tests/vectors/snapshot_example.jsonl
  raim qemu --nmea --input epochs.jsonl";
    pub const THRESHOLD: &str = "Examples:
  raim threshold --pfa 3.3333e-7 --dof 4
  raim threshold --pfa 1e-5 --dof 3 --pmd 1e-3 --json";
    pub const COMPLETIONS: &str = "Examples:
  raim completions bash > /etc/bash_completion.d/raim
  raim completions zsh > ~/.zfunc/_raim";
    pub const MAN: &str = "Examples:
  raim man > raim.1 && man ./raim.1";
}

/// A usage error: printed as clap prints its own, exit 2.
fn usage_error(sub: &str, msg: String) -> ExitCode {
    let mut cmd = Cli::command();
    let e = match cmd.find_subcommand_mut(sub) {
        Some(c) => c.error(clap::error::ErrorKind::ArgumentConflict, msg),
        None => cmd.error(clap::error::ErrorKind::ArgumentConflict, msg),
    };
    let _ = e.print();
    ExitCode::from(outcome::EXIT_USAGE)
}

fn main() -> ExitCode {
    // A run file (`raim replay --config run.toml`) becomes options placed
    // before the command line's, which override them.
    let argv = match runfile::expand(std::env::args_os().collect()) {
        Ok(a) => a,
        Err(e) => return outcome::fail(&e),
    };
    let parsed = Cli::command()
        .try_get_matches_from(argv)
        .and_then(|m| Cli::from_arg_matches(&m).map(|c| (c, m)));
    let cli = match parsed {
        Ok((c, m)) => {
            let refused = match (&c.command, m.subcommand()) {
                (Command::Replay(a), Some((_, sub))) => replay::usage::check(a, sub),
                (Command::Snapshot { config, .. }, Some((_, sub))) => {
                    let given = |id: &str| {
                        sub.try_contains_id(id).unwrap_or(false)
                            && sub.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
                    };
                    config.ignored(&given)
                }
                _ => None,
            };
            if let (Some(msg), Some((name, _))) = (refused, m.subcommand()) {
                return usage_error(name, msg);
            }
            c
        }
        Err(e) => {
            // --help and --version print to stdout and succeed; usage
            // errors print to stderr and give 2.
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() {
                outcome::EXIT_USAGE
            } else {
                outcome::EXIT_OK
            });
        }
    };
    let keep_going = match &cli.command {
        Command::Snapshot { keep_going, .. } => *keep_going,
        Command::Replay(a) => a.keep_going,
        Command::Qemu(a) => a.keep_going,
        _ => false,
    };
    match run(cli.command) {
        Ok(tally) => tally.finish(keep_going),
        Err(e) if outcome::is_broken_pipe(&e) => ExitCode::from(outcome::EXIT_OK),
        Err(e) => outcome::fail(&e),
    }
}

fn run(command: Command) -> Result<Tally> {
    let none = |r: Result<()>| r.map(|()| Tally::default());
    match command {
        Command::Snapshot {
            config,
            json,
            input,
            keep_going: _,
        } => snapshot::run(&config, json, input.as_deref()),
        Command::Threshold {
            pfa,
            dof,
            pmd,
            json,
        } => none(threshold(pfa, dof, pmd, json)),
        Command::Araim(args) => none(araim_cmd::run(&args)),
        Command::Availability(args) => none(raim_availability::cli::run(&args)),
        Command::Qemu(args) => qemu::run(&args),
        Command::Link(args) => none(link::run(&args)),
        Command::Replay(args) => replay::run(&args),
        Command::Pci(args) => none(pci::run(&args)),
        Command::Arl(args) => none(arl::run(&args)),
        Command::PfTable(args) => none(pf_table::run(&args)),
        Command::Campaign { which } => none(campaign::run(&which)),
        Command::Completions { shell } => none(completions(shell)),
        Command::Man => none(man()),
        Command::Provision(args) => none(provision_cmd::run(&args)),
        Command::RtcmFault(args) => none(rtcm_fault::run(&args)),
    }
}

/// `raim completions SHELL`: the completion script on stdout.
fn completions(shell: clap_complete::Shell) -> Result<()> {
    let mut buf = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "raim", &mut buf);
    crate::out!("{}", String::from_utf8_lossy(&buf))?;
    Ok(())
}

/// `raim man`: the raim(1) page with every subcommand's options.
fn man() -> Result<()> {
    let cmd = Cli::command();
    let mut buf = Vec::new();
    clap_mangen::Man::new(cmd.clone()).render(&mut buf)?;
    for sub in cmd.get_subcommands() {
        if sub.get_name() == "help" {
            continue;
        }
        let name = format!("raim {}", sub.get_name());
        // Each subcommand as a section of the one page.
        buf.extend_from_slice(format!(".SH \"{}\"\n", name.to_uppercase()).as_bytes());
        let sub = sub.clone().bin_name(name);
        let m = clap_mangen::Man::new(sub);
        m.render_description_section(&mut buf)?;
        m.render_options_section(&mut buf)?;
        m.render_subcommands_section(&mut buf)?;
        m.render_extra_section(&mut buf)?;
    }
    crate::out!("{}", String::from_utf8_lossy(&buf))?;
    Ok(())
}

fn threshold(pfa: f64, dof: u32, pmd: Option<f64>, json: bool) -> Result<()> {
    let t2 = dist::chi2_quantile_upper(pfa, dof).map_err(|e| anyhow::anyhow!("{e}"))?;
    let lambda = match pmd {
        Some(pmd) => Some(dist::ncx2_lambda(pfa, pmd, dof).map_err(|e| anyhow::anyhow!("{e}"))?),
        None => None,
    };
    if json {
        let v = serde_json::json!({
            "pfa": pfa, "dof": dof, "threshold_chi2": t2, "threshold": t2.sqrt(),
            "pmd": pmd, "lambda": lambda, "pbias": lambda.map(f64::sqrt),
        });
        crate::outln!("{v}")?;
    } else {
        crate::outln!("pfa={pfa:e} dof={dof} T^2={t2:.6} T={:.6}", t2.sqrt())?;
        if let (Some(pmd), Some(l)) = (pmd, lambda) {
            crate::outln!("pmd={pmd:e} lambda={l:.6} pbias={:.6}", l.sqrt())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Every subcommand, depth first, with its path ("raim campaign false-alarm").
    fn all_commands() -> Vec<(String, clap::Command)> {
        fn walk(path: String, c: &clap::Command, out: &mut Vec<(String, clap::Command)>) {
            out.push((path.clone(), c.clone()));
            for s in c.get_subcommands() {
                if s.get_name() != "help" {
                    walk(format!("{path} {}", s.get_name()), s, out);
                }
            }
        }
        let mut out = Vec::new();
        walk("raim".into(), &Cli::command(), &mut out);
        out
    }

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    /// Every option of every subcommand has a description, and
    /// the descriptions are one paragraph (so `-h` and `--help` give the
    /// same one layout everywhere).
    #[test]
    fn every_option_is_described_in_one_layout() {
        let mut missing = Vec::new();
        for (path, c) in all_commands() {
            assert!(c.get_about().is_some() || path == "raim", "{path}");
            for a in c.get_arguments() {
                let id = a.get_id().as_str();
                if id == "help" || id == "version" {
                    continue;
                }
                match a.get_help() {
                    Some(h) if !h.to_string().trim().is_empty() => {}
                    _ => missing.push(format!("{path} --{id}")),
                }
                assert!(
                    a.get_long_help().is_none(),
                    "{path} --{id}: multi-paragraph help"
                );
                for v in a.get_possible_values() {
                    assert!(
                        v.get_help().is_none(),
                        "{path} --{id}: value docs switch to the long layout"
                    );
                }
            }
        }
        assert!(missing.is_empty(), "options without help: {missing:?}");
    }

    /// Defaults print as users write them: no long runs of zeros
    /// (3.3333e-7, not 0.00000033333); and the string defaults equal the
    /// core's constants they stand for.
    #[test]
    fn defaults_print_as_users_write_them() {
        for (path, c) in all_commands() {
            for a in c.get_arguments() {
                for d in a.get_default_values() {
                    let d = d.to_string_lossy();
                    assert!(!d.contains("0.000"), "{path} --{}: {d}", a.get_id());
                    assert!(!d.contains(' '), "{path} --{}: {d}", a.get_id());
                }
            }
        }
        let min_s_ii: f64 = "1e-4".parse().unwrap();
        assert_eq!(min_s_ii, raim_core::config::DEFAULT_MIN_S_II);
        let pfa_hour: f64 = "1e-6".parse().unwrap();
        assert_eq!(pfa_hour, raim_core::consistency::DEFAULT_P_FA_PER_HOUR);
        let cli = Cli::try_parse_from(["raim", "snapshot"]).unwrap();
        let Command::Snapshot { config, .. } = cli.command else {
            panic!()
        };
        assert_eq!(config.pfa, 3.3333e-7);
        assert_eq!(config.pmd, 1e-3);
        let cli = Cli::try_parse_from(["raim", "campaign", "false-alarm"]).unwrap();
        let Command::Campaign {
            which: campaign::CampaignCmd::FalseAlarm(fa),
        } = cli.command
        else {
            panic!()
        };
        assert_eq!(fa.pfa, vec![1e-3, 1e-5]);
    }
}
