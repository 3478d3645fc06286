//! `raim replay`: recorded RINEX data through the integrity monitor, with
//! deterministic, seeded faults added on purpose (docs/REPLAY.md).
//!
//! Pipeline: RINEX obs + nav -> raim-gnss (orbits, clocks, corrections,
//! mask) -> a clean run (the reference position is its mean) -> the faulted
//! run -> per-epoch text / JSON lines / NMEA, a summary table and a plot.

pub mod araim;
mod checks;
mod decorrelate;
pub mod engine;
pub mod esq;
mod export;
mod input;
pub mod model_check;
mod pca;
pub mod pf;
mod plot;
pub mod receiver;
pub mod record;
pub mod stanford;
pub mod stats;
pub mod summary;
pub mod usage;
pub mod velocity;

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use raim_core::snapshot::fde::AlarmCause;
use raim_core::{Config, Epoch, Raim};
use raim_gnss::faults::{FaultPlan, Scenario};
use raim_gnss::parse_system;
use raim_gnss::ranging::{default_codes, prepare_epoch, PreparedEpoch, RangingOptions};

use crate::config_args::ConfigArgs;
use crate::outcome::Tally;
use engine::Engine;
use record::EpochRecord;
use summary::Summary;

/// Satellite capacity of the host engine for replays (ESBC G+E+C+J can
/// exceed the core's default 32).
pub const REPLAY_CAPACITY: usize = 48;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Target {
    // The core on the host.
    Host,
    // The firmware under QEMU (mps2-an386), through raim-qemu.
    Qemu,
}

/// What `--nmea` prints: in both cases the monitor's own sentences (RMC,
/// GGA, GSA, GST, GBS; from the firmware's second UART with `--target qemu`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum NmeaMode {
    // NMEA sentences only, no text and no summary: a stream for NMEA readers.
    Only,
    // Each epoch's text line followed by its sentences (indented), then the summary.
    WithText,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Reference {
    // Mean position of the clean run's usable epochs.
    CleanMean,
    // APPROX POSITION XYZ of the observation header.
    Header,
}

/// `--help` headings of the replay's options; a run file's sections
/// (docs/REPLAY.md, "Run files") are their first words, lower case.
pub mod heading {
    pub const SOURCES: &str = "Sources";
    pub const MODELS: &str = "Models";
    pub const FAULTS: &str = "Faults";
    pub const SNAPSHOT: &str = "Monitors: snapshot RAIM (docs/CORE.md)";
    pub const ARAIM: &str = "Monitors: ARAIM (docs/ARAIM.md)";
    pub const PF: &str = "Monitors: particle filter (docs/PF.md)";
    pub const ESQ: &str = "Monitors: effective sample quantity and PCA (docs/ESQ.md)";
    pub const MODEL_CHECK: &str = "Monitors: model check (docs/MODEL_CHECK.md)";
    pub const OUTPUTS: &str = "Outputs";
    pub const PLOTS: &str = "Plots";
}

#[derive(Debug, Clone, Args)]
pub struct ReplayArgs {
    /// A run file (TOML) holding any of these options by section; options
    /// on the command line override it (docs/REPLAY.md, "Run files").
    #[arg(long = "config", id = "run_config", value_name = "FILE", help_heading = heading::SOURCES)]
    pub run_config: Option<PathBuf>,
    /// RINEX observation file (2 or 3, optionally .gz).
    #[arg(long, value_name = "FILE", required_unless_present_any = ["rtcm3", "ubx"], help_heading = heading::SOURCES)]
    pub obs: Option<PathBuf>,
    /// RINEX navigation file (broadcast ephemerides; optionally .gz).
    #[arg(long, value_name = "FILE", required_unless_present_any = ["rtcm3", "ubx"], help_heading = heading::SOURCES)]
    pub nav: Option<PathBuf>,
    /// An RTCM 3 stream instead of RINEX: a FILE, tcp://HOST:PORT or
    /// serial:PATH:BAUD (docs/RECEIVERS.md). A file is read whole (its
    /// ephemerides serve every epoch); a live source prints each decision
    /// as it arrives and stops at the end of the stream or on Ctrl-C.
    #[arg(long, value_name = "SRC", conflicts_with_all = ["obs", "nav", "ubx"], help_heading = heading::SOURCES)]
    pub rtcm3: Option<String>,
    /// A u-blox UBX stream instead of RINEX (RXM-RAWX/SFRBX or the legacy
    /// RXM-RAW/SFRB): FILE, tcp://HOST:PORT or serial:PATH:BAUD.
    #[arg(long, value_name = "SRC", conflicts_with_all = ["obs", "nav"], help_heading = heading::SOURCES)]
    pub ubx: Option<String>,
    /// A live source that has sent no ephemeris after this many seconds is
    /// given up, with a message saying so.
    #[arg(long, value_name = "S", default_value_t = 300.0, help_heading = heading::SOURCES)]
    pub ephemeris_timeout_s: f64,
    /// Systems to use, as RINEX letters (G, R, E, C, J).
    #[arg(long, default_value = "GEC", help_heading = heading::SOURCES)]
    pub systems: String,
    /// Pseudorange code for a system, e.g. `--code C=C2I` (repeatable;
    /// defaults: G C1C/C1, R C1C/C1, E C1C/C1X/C1B, C C2I/C1I).
    #[arg(long = "code", value_name = "SYS=CODE", help_heading = heading::SOURCES)]
    pub codes: Vec<String>,
    /// First epoch: HH:MM or HH:MM:SS (GPS time of day) or +SECONDS from the first.
    #[arg(long, help_heading = heading::SOURCES)]
    pub start: Option<String>,
    /// Last epoch (inclusive), same forms.
    #[arg(long, help_heading = heading::SOURCES)]
    pub end: Option<String>,
    /// Elevation mask, degrees (may be negative, down to -90).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true, help_heading = heading::MODELS)]
    pub mask_deg: f64,
    /// Skip the Klobuchar ionospheric correction.
    #[arg(long, help_heading = heading::MODELS)]
    pub no_iono: bool,
    /// Skip the Saastamoinen tropospheric correction.
    #[arg(long, help_heading = heading::MODELS)]
    pub no_tropo: bool,
    /// Skip the broadcast group delays (TGD/BGD).
    #[arg(long, help_heading = heading::MODELS)]
    pub no_group_delay: bool,
    /// Sigma model: signal-in-space (URA) sigma, m.
    #[arg(long, allow_negative_numbers = true, help_heading = heading::MODELS)]
    pub ura_m: Option<f64>,
    /// Sigma model of GLONASS satellites: their URA, m (default: the URA
    /// x 1.9 / 0.7, the published GLONASS / GPS broadcast SISRE ratio,
    /// docs/GLONASS.md).
    #[arg(long, allow_negative_numbers = true, help_heading = heading::MODELS)]
    pub glonass_ura_m: Option<f64>,
    /// Sigma model: vertical residual ionosphere sigma, m.
    #[arg(long, allow_negative_numbers = true, help_heading = heading::MODELS)]
    pub iono_vertical_m: Option<f64>,
    /// Sigma model: receiver noise sigma, m.
    #[arg(long, allow_negative_numbers = true, help_heading = heading::MODELS)]
    pub noise_m: Option<f64>,
    /// Where the position error is measured from: clean-mean (the mean
    /// position of the clean run's usable epochs) or header (the
    /// observation header's APPROX POSITION XYZ).
    #[arg(long, value_enum, default_value_t = Reference::CleanMean, help_heading = heading::MODELS)]
    pub reference: Reference,
    /// A fault (repeatable): step:G24:50@00:20:00, ramp:G24:0.1@00:20:00,
    /// step:G15+G28:50@01:00:00, step:E:20@01:00 (whole constellation),
    /// clock:300@00:30:00, noise:all:t3:1.0 (Student-t 3 dof, or laplace);
    /// an optional ..END after the start time; the bias may be negative.
    #[arg(long = "fault", value_name = "SPEC", allow_hyphen_values = true, help_heading = heading::FAULTS)]
    pub faults: Vec<String>,
    /// A TOML scenario file: a seed and fault tables (TOML arrays of tables named fault) (format and
    /// example: docs/REPLAY.md, section "Scenario files").
    #[arg(long, value_name = "FILE", help_heading = heading::FAULTS)]
    pub scenario: Option<PathBuf>,
    /// Seed of the injected noise (overrides the scenario's).
    #[arg(long, help_heading = heading::FAULTS)]
    pub seed: Option<u64>,
    /// One JSON object per epoch, then a final {"summary": ...} line
    /// (keys: docs/FORMATS.md).
    #[arg(long, help_heading = heading::OUTPUTS)]
    pub json: bool,
    /// The monitor's NMEA 0183 output per epoch (RMC, VTG, GGA, GSA, GSV, GST, GBS, ZDA, CRLF-terminated;
    /// from the firmware's second UART with --target qemu; also with
    /// --araim): `only` the sentences (a stream for NMEA readers, no
    /// summary), or `with-text` after each epoch's text line.
    #[arg(long, value_enum, value_name = "MODE", help_heading = heading::OUTPUTS)]
    pub nmea: Option<NmeaMode>,
    /// Write the NMEA stream to this file (beside any stdout output).
    #[arg(long, value_name = "FILE", help_heading = heading::OUTPUTS)]
    pub nmea_file: Option<PathBuf>,
    /// Write an RTKLIB-compatible solution file (.pos), with the integrity
    /// decision and protection levels as extra columns (docs/FORMATS.md).
    #[arg(long, value_name = "FILE", help_heading = heading::OUTPUTS)]
    pub pos: Option<PathBuf>,
    /// Write one CSV row per epoch, with a header (docs/FORMATS.md).
    #[arg(long, value_name = "FILE", help_heading = heading::OUTPUTS)]
    pub csv: Option<PathBuf>,
    /// Write a KML track, placemarks coloured by decision, excluded
    /// satellites in each.
    #[arg(long, value_name = "FILE", help_heading = heading::OUTPUTS)]
    pub kml: Option<PathBuf>,
    /// Write a GPX track; each point names its decision and exclusions.
    #[arg(long, value_name = "FILE", help_heading = heading::OUTPUTS)]
    pub gpx: Option<PathBuf>,
    /// Print only the summary table.
    #[arg(long, help_heading = heading::OUTPUTS)]
    pub quiet: bool,
    /// Exit 0 even when some epochs were refused by the monitor (they are
    /// still in the output and counted on stderr).
    #[arg(long, help_heading = heading::OUTPUTS)]
    pub keep_going: bool,
    /// Draw the statistic, exclusions, errors and PLs, and the horizontal
    /// and vertical Stanford diagrams, into this PNG.
    #[arg(long, value_name = "FILE", help_heading = heading::PLOTS)]
    pub plot: Option<PathBuf>,
    /// TrueType font for the plots (default: DejaVu Sans where installed).
    #[arg(long, value_name = "FILE", help_heading = heading::PLOTS)]
    pub font: Option<PathBuf>,
    #[command(flatten, next_help_heading = heading::SNAPSHOT)]
    pub config: ConfigArgs,
    /// Where the monitor runs: host (the core on this machine) or qemu (the
    /// firmware under QEMU, mps2-an386; built on first use or taken from
    /// $RAIM_FIRMWARE_ELF). The snapshot monitor and --araim (the
    /// device's ARAIM, in its precision: docs/REPLAY.md).
    #[arg(long, value_enum, default_value_t = Target::Host, help_heading = heading::SNAPSHOT)]
    pub target: Target,
    /// Particle-filter RAIM (docs/PF.md): --pf {ekf,pf,gapf}.
    #[command(flatten, next_help_heading = heading::PF)]
    pub pf: pf::PfArgs,
    /// ARAIM (docs/ARAIM.md): --araim and its options.
    #[command(flatten, next_help_heading = heading::ARAIM)]
    pub araim: araim::AraimReplayArgs,
    /// Effective sample quantity and PCA constellation monitor (docs/ESQ.md).
    #[command(flatten, next_help_heading = heading::ESQ)]
    pub esq: esq::EsqArgs,
    /// The run-time model check beside the snapshot monitor or ARAIM
    /// (docs/MODEL_CHECK.md).
    #[command(flatten, next_help_heading = heading::MODEL_CHECK)]
    pub model_check: model_check::ModelCheckArgs,
}

/// Everything a replay produces.
pub struct ReplayOutput {
    pub records: Vec<EpochRecord>,
    pub summary: Summary,
    pub reference_m: Option<[f64; 3]>,
}

impl ReplayArgs {
    fn ranging(&self) -> Result<RangingOptions> {
        let systems = self
            .systems
            .chars()
            .map(parse_system)
            .collect::<Result<Vec<_>, _>>()?;
        let mut codes = default_codes();
        for c in &self.codes {
            let (sys, code) = c
                .split_once('=')
                .with_context(|| format!("--code {c}: expected SYS=CODE"))?;
            let sys = parse_system(sys.chars().next().unwrap_or(' '))?;
            codes.insert(sys, vec![code.to_string()]);
        }
        if !(-90.0..=90.0).contains(&self.mask_deg) {
            bail!("--mask-deg {} is outside [-90, 90]", self.mask_deg);
        }
        let glonass_sigma = systems.contains(&raim_core::System::Glonass).then(|| {
            let mut m = self.core_config().sigma_model;
            m.ura_m = self
                .glonass_ura_m
                .unwrap_or_else(|| raim_gnss::glonass::glonass_ura_m(m.ura_m));
            m
        });
        if let Some(m) = &glonass_sigma {
            if !(m.ura_m.is_finite() && m.ura_m > 0.0) {
                bail!("--glonass-ura-m {} is not a positive length", m.ura_m);
            }
        }
        Ok(RangingOptions {
            glonass_sigma,
            systems,
            codes,
            elevation_mask_rad: self.mask_deg.to_radians(),
            iono: !self.no_iono,
            tropo: !self.no_tropo,
            group_delay: !self.no_group_delay,
        })
    }

    pub fn core_config(&self) -> Config {
        let mut c = self.config.config();
        if let Some(v) = self.ura_m {
            c.sigma_model.ura_m = v;
        }
        if let Some(v) = self.iono_vertical_m {
            c.sigma_model.iono_vertical_m = v;
        }
        if let Some(v) = self.noise_m {
            c.sigma_model.noise_m = v;
        }
        c
    }
}

/// The prepared epochs of a replay and what the monitor's configuration
/// needs to know about them.
struct Prepared {
    epochs: Vec<PreparedEpoch>,
    /// The header's approximate position (RINEX) or the station position
    /// (RTCM 1005/1006).
    header: Option<[f64; 3]>,
    first: f64,
    /// A receiver stream with single-frequency ranges and no ionospheric
    /// model: the residual-ionosphere sigma is doubled (`receiver`).
    iono_inflate: bool,
    /// What the source is called in messages.
    source_name: String,
}

/// Load, prepare and select the epochs; reject a `--start`/`--end` window
/// that is reversed or selects nothing.
fn prepare(args: &ReplayArgs) -> Result<(Vec<PreparedEpoch>, Option<[f64; 3]>, f64)> {
    let p = prepare_full(args)?;
    Ok((p.epochs, p.header, p.first))
}

fn prepare_full(args: &ReplayArgs) -> Result<Prepared> {
    let mut opts = args.ranging()?;
    let stream = receiver::source(args)?;
    let (obs, nav, source_name) = match (&stream, &args.obs, &args.nav) {
        (Some((format, spec)), _, _) => {
            let raim_recv::source::Spec::File(path) = spec else {
                bail!(
                    "{} is a live source: it is run epoch by epoch (the snapshot monitor only)",
                    spec.name()
                );
            };
            let rec = receiver::load_file(*format, path)?;
            if args.codes.is_empty() {
                opts.codes = receiver::receiver_codes();
            }
            (rec.obs, rec.nav, spec.name())
        }
        (None, Some(o), Some(n)) => (
            input::load_obs(o)?,
            input::load_nav(n)?,
            o.display().to_string(),
        ),
        _ => bail!("give --obs and --nav, or --rtcm3 SRC, or --ubx SRC"),
    };
    let (first, last) = match (obs.epochs.first(), obs.epochs.last()) {
        (Some(a), Some(b)) => (a.time_gps_s, b.time_gps_s),
        _ => bail!("no epochs in the observation file {source_name}"),
    };
    let start = args
        .start
        .as_deref()
        .map(|s| raim_gnss::time::resolve(s, first))
        .transpose()?;
    let end = args
        .end
        .as_deref()
        .map(|s| raim_gnss::time::resolve(s, first))
        .transpose()?;
    checks::window(
        start,
        end,
        (
            args.start.as_deref().unwrap_or(""),
            args.end.as_deref().unwrap_or(""),
        ),
    )?;
    let selected: Vec<&raim_gnss::ObsEpoch> = obs
        .epochs
        .iter()
        .filter(|e| start.is_none_or(|s| e.time_gps_s >= s - 0.5))
        .filter(|e| end.is_none_or(|s| e.time_gps_s <= s + 0.5))
        .collect();
    let mut epochs: Vec<PreparedEpoch> = selected
        .iter()
        .map(|e| prepare_epoch(&nav, e, &opts, obs.approx_position_m))
        .collect();
    if epochs.is_empty() {
        bail!(
            "no epochs between --start and --end: the file covers {}..{}",
            raim_gnss::time::time_of_day(first),
            raim_gnss::time::time_of_day(last)
        );
    }
    if epochs.iter().all(|e| e.sats.is_empty()) {
        bail!(
            "{source_name}: no epoch has a usable satellite: {}",
            checks::why_nothing(&selected, &nav, &epochs, &opts)
        );
    }
    let mut iono_inflate = false;
    if stream.is_some() {
        let model = args.core_config().sigma_model;
        let f = receiver::single_iono_factor(args, &nav);
        for e in &mut epochs {
            if args.araim.araim {
                // ARAIM: the unit's stream sigmas under ARAIM (the pair's
                // curves, no signal-in-space term: the ISM's).
                receiver::set_araim_sigmas(e, &model, f);
            } else {
                receiver::set_sigmas(e, &model, opts.glonass_sigma.as_ref(), f);
            }
        }
        let mut probe = args.core_config();
        let before = probe.sigma_model.iono_vertical_m;
        receiver::adjust_config(&mut probe, args, &nav, &epochs);
        iono_inflate = probe.sigma_model.iono_vertical_m != before;
    }
    Ok(Prepared {
        epochs,
        header: obs.approx_position_m,
        first,
        iono_inflate,
        source_name,
    })
}

/// The plan, with each fault's label (its spec as written) for the checks.
fn fault_plan(args: &ReplayArgs, first: f64) -> Result<(FaultPlan, Vec<String>)> {
    let (mut plan, mut labels) = match &args.scenario {
        Some(p) => {
            let scen = Scenario::load(p)?;
            let labels = (1..=scen.fault.len())
                .map(|k| format!("{} [[fault]] #{k}", p.display()))
                .collect();
            (scen.plan(first)?, labels)
        }
        None => (FaultPlan::default(), Vec::new()),
    };
    for f in &args.faults {
        plan.faults.push(FaultPlan::parse_cli(f, first)?);
        labels.push(f.clone());
    }
    if let Some(s) = args.seed {
        plan.seed = s;
    }
    Ok((plan, labels))
}

/// Run the monitor over the epochs with `plan`'s faults on a fresh engine.
/// For an ambiguity alarm, both candidate subsets are re-tested on a
/// separate host engine (a diagnostic that must not touch the monitor's
/// state across epochs).
fn run_core(
    target: Target,
    cfg: &Config,
    epochs: &[PreparedEpoch],
    plan: &FaultPlan,
    reference: Option<[f64; 3]>,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Vec<EpochRecord>> {
    let mut start = |c: &Config| Engine::start(target, c);
    run_core_on(&mut start, cfg, epochs, plan, reference, progress)
}

/// [`run_core`] on an engine from `start`.
fn run_core_on(
    start: &mut dyn FnMut(&Config) -> Result<Engine>,
    cfg: &Config,
    epochs: &[PreparedEpoch],
    plan: &FaultPlan,
    reference: Option<[f64; 3]>,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<Vec<EpochRecord>> {
    let mut engine = start(cfg)?;
    let mut scratch = Raim::<REPLAY_CAPACITY>::new();
    let mut out = Vec::with_capacity(epochs.len());
    for e in epochs {
        let mut sats = e.observations();
        let injected = plan.apply(e.time_gps_s, &mut sats);
        // The monitor gets UTC Unix seconds, the protocol's epoch time, so
        // the firmware's NMEA carries the right time and date.
        let wire_epoch = Epoch::ranges(
            raim_gnss::time::unix_utc_s(e.time_gps_s),
            &sats,
            e.reference_m,
        );
        let cn0: Vec<u8> = e.sats.iter().map(|s| s.cn0_dbhz).collect();
        let speed =
            |w: &raim_proto::WireResult| velocity::ground_velocity(w, e, &sats, &cfg.sigma_model);
        let (outcome, nmea) = engine.process(cfg, &wire_epoch, &cn0, &speed)?;
        let mut rec = match outcome {
            Ok(r) => {
                let mut rec = EpochRecord::from_result(
                    &r,
                    e.time_gps_s,
                    sats.len(),
                    &injected.faulted,
                    reference,
                );
                if let Some(AlarmCause::Ambiguous { best, runner_up }) = r.alarm_cause {
                    rec.ambiguity = [best, runner_up]
                        .iter()
                        .filter_map(|&id| {
                            let subset: Vec<_> =
                                sats.iter().copied().filter(|s| s.id != id).collect();
                            let sub = scratch
                                .process(cfg, &Epoch::ranges(e.time_gps_s, &subset, e.reference_m))
                                .ok()?;
                            let t = sub.initial_test;
                            Some((id.to_string(), t.statistic, t.threshold, t.dof))
                        })
                        .collect();
                }
                rec
            }
            Err(err) => EpochRecord::from_error(e.time_gps_s, sats.len(), &injected.faulted, &err),
        };
        rec.nmea = nmea;
        out.push(rec);
        if let Some(p) = progress {
            p.inc(1);
        }
    }
    Ok(out)
}

/// Mean ECEF position of the usable epochs.
fn mean_position(records: &[EpochRecord]) -> Option<[f64; 3]> {
    let ps: Vec<[f64; 3]> = records
        .iter()
        .filter(|r| r.usable())
        .filter_map(|r| r.position_ecef_m)
        .collect();
    if ps.is_empty() {
        return None;
    }
    let n = ps.len() as f64;
    Some([0, 1, 2].map(|k| ps.iter().map(|p| p[k]).sum::<f64>() / n))
}

/// The whole replay, without printing (used by the tests too).
/// The fault plan, refused when a fault touches no epoch of the window
///; a fault that touches only part of its target is a warning on
/// stderr. Shared by the snapshot replay and `--pf`.
fn checked_fault_plan(
    args: &ReplayArgs,
    first: f64,
    epochs: &[PreparedEpoch],
) -> Result<FaultPlan> {
    let (plan, labels) = fault_plan(args, first)?;
    let warnings = {
        let labelled: Vec<checks::LabelledFault<'_>> = plan
            .faults
            .iter()
            .zip(labels)
            .map(|(fault, label)| checks::LabelledFault { label, fault })
            .collect();
        checks::faults(&labelled, epochs)?
    };
    for w in warnings {
        let _ = writeln!(std::io::stderr(), "{w}");
    }
    Ok(plan)
}

pub fn replay(args: &ReplayArgs) -> Result<ReplayOutput> {
    replay_on(args, &mut |cfg| Engine::start(args.target, cfg))
}

/// The replay with each run's engine from `start` (given the monitor
/// configuration it must run with): `raim link` runs the same epochs on a
/// unit over a serial port.
pub fn replay_on(
    args: &ReplayArgs,
    start: &mut dyn FnMut(&Config) -> Result<Engine>,
) -> Result<ReplayOutput> {
    let mut cfg = args.core_config();
    cfg.validate()
        .map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    let p = prepare_full(args)?;
    if p.iono_inflate {
        cfg.sigma_model.iono_vertical_m *= receiver::NO_MODEL_IONO_FACTOR;
    }
    if args.reference == Reference::Header && p.header.is_none() {
        let what = if args.obs.is_some() {
            "its header has no APPROX POSITION XYZ (absent or zero)"
        } else {
            "the stream has no station position (RTCM 1005/1006)"
        };
        bail!(
            "--reference header: {}: {what}; use --reference clean-mean (the mean of the clean run)",
            p.source_name
        );
    }
    let (epochs, header, first) = (p.epochs, p.header, p.first);
    let plan = checked_fault_plan(args, first, &epochs)?;
    let show = std::io::stderr().is_terminal();
    let total = if plan.is_empty() {
        epochs.len()
    } else {
        2 * epochs.len()
    } as u64;
    let bar = show.then(|| {
        let b = indicatif::ProgressBar::new(total);
        b.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} epochs {elapsed}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let clean = run_core_on(
        start,
        &cfg,
        &epochs,
        &FaultPlan::default(),
        None,
        bar.as_ref(),
    )?;
    let reference = match args.reference {
        Reference::CleanMean => mean_position(&clean),
        Reference::Header => header,
    };
    let mut records = if plan.is_empty() {
        clean
    } else {
        run_core_on(start, &cfg, &epochs, &plan, reference, bar.as_ref())?
    };
    if plan.is_empty() {
        // Recompute the errors of the clean run against the reference.
        for r in records.iter_mut() {
            if let (Some(p), Some(rf)) = (r.position_ecef_m, reference) {
                let e = record::error_enu(p, rf);
                r.error_enu_m = Some(e);
                r.error_h_m = Some(e[0].hypot(e[1]));
                r.error_v_m = Some(e[2].abs());
            }
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let fault_start = plan
        .faults
        .iter()
        .filter(|f| f.is_satellite_fault())
        .map(|f| f.start_gps_s)
        .fold(None, |a: Option<f64>, s| Some(a.map_or(s, |a| a.min(s))));
    let summary = summary::summarise(&records, fault_start, args.config.pfa);
    Ok(ReplayOutput {
        records,
        summary,
        reference_m: reference,
    })
}

/// `raim replay`: the output, and the count of epochs the monitor refused
/// (a closed pipe is handled by the caller, crate::outcome).
pub fn run(args: &ReplayArgs) -> Result<Tally> {
    check_output_folders(args)?;
    if let Some((format, spec)) = receiver::source(args)? {
        if spec.is_live() {
            return receiver::run_live(args, format, &spec);
        }
    }
    if args.model_check.model_check {
        // The model check beside the snapshot monitor or ARAIM
        // (docs/MODEL_CHECK.md): its own report.
        let stdout = std::io::stdout();
        model_check::run(args, &mut stdout.lock())?;
        return Ok(Tally::default());
    }
    if args.esq.any() {
        // Seed 003's own claims (docs/ESQ.md), built on its ARAIM modes:
        // their own per-epoch output; `--araim --esq` and `--araim --pca`
        // run these (the ESQ/PCA options set their ARAIM inputs).
        esq::run(args)?;
        return Ok(Tally::default());
    }
    if args.araim.araim {
        // ARAIM (docs/ARAIM.md): its own per-epoch output.
        araim::run(args)?;
        return Ok(Tally::default());
    }
    if args.pf.pf.is_some() {
        // Particle-filter RAIM (docs/PF.md): its own per-epoch output.
        pf::run(args)?;
        return Ok(Tally::default());
    }
    let out = replay(args)?;
    write_outputs(args, &out)?;
    let mut tally = Tally::default();
    for r in &out.records {
        match &r.error {
            Some(e) => {
                tally.refuse(|| format!("{} {e}", raim_gnss::time::time_of_day(r.time_gps_s)))
            }
            None => tally.answered(),
        }
    }
    Ok(tally)
}

/// Every output file's folder exists (checked before the run, which can
/// take minutes).
fn check_output_folders(args: &ReplayArgs) -> Result<()> {
    let outputs = [
        ("--plot", &args.plot),
        ("--pf-plot", &args.pf.pf_plot),
        ("--araim-plot", &args.araim.araim_plot),
        ("--esq-plot", &args.esq.esq_plot),
        ("--pos", &args.pos),
        ("--csv", &args.csv),
        ("--kml", &args.kml),
        ("--gpx", &args.gpx),
        ("--nmea-file", &args.nmea_file),
    ];
    for (what, p) in outputs {
        if let Some(p) = p {
            plot::check_folder(p, what)?;
        }
    }
    Ok(())
}

/// A run's name for titles: the observation file, the faults, the window.
pub fn run_title(args: &ReplayArgs) -> String {
    let src = args
        .obs
        .clone()
        .or_else(|| args.rtcm3.as_ref().or(args.ubx.as_ref()).map(PathBuf::from))
        .unwrap_or_default();
    let file = src
        .file_name()
        .map_or_else(|| src.display().to_string(), |f| f.to_string_lossy().into());
    let mut faults: Vec<String> = args.faults.clone();
    if let Some(s) = &args.scenario {
        faults.push(format!("scenario {}", s.display()));
    }
    faults.extend(args.esq.eph_fault.iter().map(|f| format!("eph:{f}")));
    faults.extend(args.araim.araim_const_faults.iter().cloned());
    let fault = if faults.is_empty() {
        "no fault".to_string()
    } else {
        faults.join(" + ")
    };
    let window = match (&args.start, &args.end) {
        (None, None) => "whole file".to_string(),
        (a, b) => format!(
            "{}..{}",
            a.as_deref().unwrap_or("start"),
            b.as_deref().unwrap_or("end")
        ),
    };
    format!("{file}, {}, {fault}, {window}", args.systems)
}

pub(crate) fn write_outputs(args: &ReplayArgs, out: &ReplayOutput) -> Result<()> {
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    if !args.quiet {
        for r in &out.records {
            match args.nmea {
                _ if args.json => writeln!(w, "{}", serde_json::to_string(r)?)?,
                Some(NmeaMode::Only) => {
                    // NMEA 0183 ends every sentence with CR LF.
                    for s in &r.nmea {
                        write!(w, "{}\r\n", s.trim_end())?;
                    }
                }
                Some(NmeaMode::WithText) => {
                    writeln!(w, "{}", r.text_line())?;
                    for s in &r.nmea {
                        writeln!(w, "    {}", s.trim_end())?;
                    }
                }
                None => writeln!(w, "{}", r.text_line())?,
            }
        }
    }
    if args.json {
        writeln!(
            w,
            "{}",
            serde_json::json!({ "summary": out.summary, "reference_ecef_m": out.reference_m })
        )?;
    } else if args.nmea != Some(NmeaMode::Only) {
        writeln!(w, "{}", out.summary.table())?;
    }
    w.flush()?;
    let title = run_title(args);
    if let Some(p) = &args.pos {
        let inputs: Vec<PathBuf> = [&args.obs, &args.nav]
            .into_iter()
            .flatten()
            .cloned()
            .chain(args.rtcm3.iter().chain(&args.ubx).map(PathBuf::from))
            .collect();
        let inputs: Vec<&std::path::Path> = inputs.iter().map(PathBuf::as_path).collect();
        export::write_pos(p, &out.records, &inputs)?;
    }
    if let Some(p) = &args.csv {
        export::write_csv(p, &out.records)?;
    }
    if let Some(p) = &args.kml {
        export::write_kml(p, &out.records, &title)?;
    }
    if let Some(p) = &args.gpx {
        export::write_gpx(p, &out.records, &title)?;
    }
    if let Some(p) = &args.nmea_file {
        export::write_nmea(p, out.records.iter().flat_map(|r| &r.nmea))?;
    }
    if let Some(p) = &args.plot {
        plot::draw(out, &args.core_config(), p, args.font.as_deref(), &title)?;
    }
    Ok(())
}
