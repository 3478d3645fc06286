//! `raim replay --esq` and `--pca` (seed 003's own claims;
//! docs/ESQ.md): the ARAIM engine run on the replay's corrected
//! pseudoranges, with
//!
//! - `--esq`: per epoch N* = P_Sigma / P_max and dT_e = T / N*
//!   (raim_core::araim::esq), the resampler's emit/skip decision and the
//!   separation test on the emitted epochs; a summary of the solves saved
//!   and of what the saving costs (detection delay, missed epochs);
//! - `--pca`: the PCA monitor (raim_core::araim::pca) beside the ARAIM
//!   test and the snapshot monitor on the same epochs (module `pca`);
//! - `--esq-mcusum`: the MCUSUM fed decorrelated samples (module
//!   `decorrelate`).
//!
//! ARAIM inputs, per satellite: the geometry row from the replay's azimuth
//! and elevation, the residual rho - |sat - x_ref| at the observation
//! header's position (the linearisation point; a constant offset there
//! moves every solution alike and no separation), C_acc = the replay's
//! sigma model squared (`--ura-m`, `--iono-vertical-m`, `--noise-m`),
//! C_int = C_acc + 0.75^2 - 0.5^2 m^2 (the ADD's URA/URE gap), b_nom 0.5 m,
//! P_sat 1e-5, P_const `--esq-pconst` (1e-4) per constellation in use.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use plotters::prelude::*;
use raim_core::araim::esq::{self, EffectiveSamples, Resampler, Sample};
use raim_core::araim::pca::{Pca, PcaConfig, PcaOutcome, PcaTest};
use raim_core::araim::{Araim, AraimConfig, AraimSat, Ism, ModeStatus, PlOutput};
use raim_core::{Config, Decision, Epoch, Raim, RangeObservation, System};
use raim_gnss::faults::{ephemeris_radial_error_m, FaultPlan};
use raim_gnss::ranging::PreparedEpoch;

use super::{checked_fault_plan, prepare_full, ReplayArgs, REPLAY_CAPACITY};

/// ARAIM capacity for replays: satellites, fault modes.
pub const ARAIM_SATS: usize = 64;
pub const ARAIM_MODES: usize = 2048;
/// PCA window (epochs) and slots.
pub const PCA_WINDOW: usize = 60;
pub const PCA_SLOTS: usize = 48;

/// ADD's URA/URE gap, sigma_URA^2 - sigma_URE^2 (m^2).
const C_INT_MINUS_C_ACC_M2: f64 = 0.75 * 0.75 - 0.5 * 0.5;
const B_NOM_M: f64 = 0.5;
const P_SAT: f64 = 1e-5;

#[derive(Debug, Clone, Args)]
pub struct EsqArgs {
    /// The effective sample quantity on ARAIM: N*, dT_e and the resampled separation test (US 10,436,912 claims 1-5; docs/ESQ.md).
    #[arg(long)]
    pub esq: bool,
    /// The constellation-fault monitor by principal components (PCA), beside ARAIM and the snapshot test (docs/ESQ.md).
    #[arg(long)]
    pub pca: bool,
    /// The MCUSUM fed decorrelated samples: before/after false alarms and delays (docs/ESQ.md).
    #[arg(long)]
    pub esq_mcusum: bool,
    /// Window T of the effective sample quantity, s.
    #[arg(long, default_value_t = 300.0)]
    pub esq_window_s: f64,
    /// Share of the singular values the PCA keeps.
    #[arg(long, default_value_t = 0.99)]
    pub pca_share: f64,
    /// False-alert probability per epoch of the PCA separation test.
    #[arg(long, default_value = "3.9e-6")]
    pub pca_pfa: f64,
    /// An ephemeris-like fault: SYS:RADIAL_M@START, a radial orbit error on every satellite of SYS, projected on each line of sight.
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true, help_heading = super::heading::FAULTS)]
    pub eph_fault: Vec<String>,
    /// P_const of every constellation in use (ADD: 1e-4; 1e-8 for a GPS-only sky, which otherwise has an unmonitorable constellation mode and no PL).
    #[arg(long, default_value = "1e-4")]
    pub esq_pconst: f64,
    /// Decimation interval of --esq-mcusum, s (default: the measured correlation time).
    #[arg(long)]
    pub esq_decimate_s: Option<f64>,
    /// The PCA threshold's empirical-null scale c: alarm when max_q |dx_q| / T_q > c (1: the nominal Gaussian null; docs/ESQ.md fits c on clean ESBC).
    #[arg(long, default_value_t = 1.0)]
    pub pca_null_scale: f64,
    /// With --esq: repeat the run with the fault's onset shifted by N stratified uniform offsets over the window T (and so over the epoch), and report detection probability and delays with confidence intervals.
    #[arg(long, value_name = "N")]
    pub esq_onset_sweep: Option<usize>,
    /// Seed of the --esq-onset-sweep offsets.
    #[arg(long, default_value_t = 1)]
    pub esq_onset_seed: u64,
    /// Plot N*, dT_e and the separation test (--esq), or the PCA statistic (--pca), into this PNG.
    #[arg(long, value_name = "FILE", help_heading = super::heading::PLOTS)]
    pub esq_plot: Option<PathBuf>,
}

impl EsqArgs {
    pub fn any(&self) -> bool {
        self.esq || self.pca || self.esq_mcusum
    }
}

/// A parsed ephemeris-like fault.
#[derive(Debug, Clone, Copy)]
pub struct EphFault {
    pub system: System,
    pub radial_m: f64,
    pub start_gps_s: f64,
}

fn parse_eph(spec: &str, first: f64) -> Result<EphFault> {
    let (what, start) = spec
        .split_once('@')
        .with_context(|| format!("--eph-fault {spec}: expected SYS:RADIAL_M@START"))?;
    let (sys, radial) = what
        .split_once(':')
        .with_context(|| format!("--eph-fault {spec}: expected SYS:RADIAL_M@START"))?;
    let system = raim_gnss::parse_system(sys.chars().next().unwrap_or(' '))?;
    let radial_m: f64 = radial
        .parse()
        .with_context(|| format!("--eph-fault {spec}: radial error is a number"))?;
    if !radial_m.is_finite() {
        bail!("--eph-fault {spec}: radial error must be finite");
    }
    Ok(EphFault {
        system,
        radial_m,
        start_gps_s: raim_gnss::time::resolve(start, first)?,
    })
}

/// Everything the three monitors see: epochs, faults, linearisation point.
pub struct Setup {
    pub epochs: Vec<PreparedEpoch>,
    pub plan: FaultPlan,
    pub eph: Vec<EphFault>,
    pub receiver_m: [f64; 3],
    pub cfg: Config,
    pub p_const: f64,
    /// Earliest onset of a satellite fault (step, ramp, ephemeris), GPS s.
    pub onset_gps_s: Option<f64>,
}

pub fn setup(args: &ReplayArgs) -> Result<Setup> {
    let mut cfg = args.core_config();
    cfg.validate().map_err(|e| anyhow!("configuration: {e}"))?;
    let p = prepare_full(args)?;
    // A single-frequency receiver stream without an ionospheric model: the
    // residual-ionosphere sigma doubled, as in the snapshot replay.
    if p.iono_inflate {
        cfg.sigma_model.iono_vertical_m *= super::receiver::NO_MODEL_IONO_FACTOR;
    }
    let (epochs, header, first) = (p.epochs, p.header, p.first);
    let plan = checked_fault_plan(args, first, &epochs)?;
    let eph = args
        .esq
        .eph_fault
        .iter()
        .map(|s| parse_eph(s, first))
        .collect::<Result<Vec<_>>>()?;
    // The linearisation point: the header's position, or, for a stream
    // without one (no RTCM 1005/1006, a UBX log), the mean position of the
    // clean snapshot run, as `--reference clean-mean` takes it.
    let receiver_m = match header {
        Some(h) => h,
        None => {
            let clean = super::run_core(
                super::Target::Host,
                &cfg,
                &epochs,
                &FaultPlan::default(),
                None,
                None,
            )?;
            super::mean_position(&clean).with_context(|| {
                format!(
                    "{}: no station position and no usable clean epoch to take a mean position from",
                    p.source_name
                )
            })?
        }
    };
    let onset = plan
        .faults
        .iter()
        .filter(|f| f.is_satellite_fault())
        .map(|f| f.start_gps_s)
        .chain(eph.iter().map(|f| f.start_gps_s))
        .fold(None, |a: Option<f64>, s| Some(a.map_or(s, |a| a.min(s))));
    Ok(Setup {
        epochs,
        plan,
        eph,
        receiver_m,
        cfg,
        p_const: args.esq.esq_pconst,
        onset_gps_s: onset,
    })
}

impl Setup {
    /// The epoch's observations with every fault applied.
    pub fn observations(&self, e: &PreparedEpoch) -> Vec<RangeObservation> {
        let mut sats = e.observations();
        self.plan.apply(e.time_gps_s, &mut sats);
        for f in &self.eph {
            if e.time_gps_s < f.start_gps_s {
                continue;
            }
            for s in sats.iter_mut().filter(|s| s.id.system == f.system) {
                s.pseudorange_m +=
                    ephemeris_radial_error_m(s.position_m, self.receiver_m, f.radial_m);
            }
        }
        sats
    }

    /// A satellite's one-sigma range error, m: its own (an iono-free
    /// combination of a receiver stream) or the sigma model's at its
    /// elevation, as the snapshot monitor takes it.
    pub fn sigma_m(&self, elevation_rad: f64, o: &RangeObservation) -> f64 {
        o.sigma_m
            .unwrap_or_else(|| self.cfg.sigma_model.sigma_m(elevation_rad))
    }

    /// The ARAIM satellites and ISM of one epoch (module doc).
    pub fn araim_inputs(
        &self,
        e: &PreparedEpoch,
        obs: &[RangeObservation],
    ) -> (Vec<AraimSat<f64>>, Ism) {
        let mut systems: Vec<System> = Vec::new();
        let sats = e
            .sats
            .iter()
            .zip(obs)
            .map(|(p, o)| {
                if !systems.contains(&o.id.system) {
                    systems.push(o.id.system);
                }
                let c_acc = self.sigma_m(p.elevation_rad, o).powi(2);
                let d = [0, 1, 2].map(|k| o.position_m[k] - self.receiver_m[k]);
                let range = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                AraimSat {
                    id: o.id,
                    g_enu: AraimSat::g_from_az_el(p.azimuth_rad, p.elevation_rad),
                    c_int_m2: c_acc + C_INT_MINUS_C_ACC_M2,
                    c_acc_m2: c_acc,
                    b_nom_m: B_NOM_M,
                    p_sat: P_SAT,
                    residual_m: o.pseudorange_m - range,
                }
            })
            .collect();
        (sats, Ism::with(&systems, self.p_const))
    }
}

/// One epoch through ARAIM (+ N*), the PCA monitor and the snapshot monitor.
#[derive(Debug, Clone)]
pub struct Row {
    pub t_gps_s: f64,
    pub n_sats: usize,
    /// N* on the vertical axis (None: no PL this epoch, or ARAIM refused it).
    pub esq: Option<EffectiveSamples>,
    /// The largest |x^(k) - x^(0)| / T_k (NaN when ARAIM refused the epoch).
    pub araim_ratio: f64,
    pub araim_alarm: bool,
    /// Some constellation-only mode failed its test.
    pub araim_const_alarm: bool,
    pub pca: Option<PcaTest<PCA_SLOTS>>,
    pub snapshot_alarm: bool,
    pub faulted: bool,
    /// What a monitor refused this epoch (typed error, printed), or why N*
    /// is missing.
    pub errors: Vec<String>,
}

/// Run the monitors over every epoch. `with_pca` / `with_snapshot` skip
/// the parts not needed.
pub fn rows(s: &Setup, args: &EsqArgs, with_pca: bool, with_snapshot: bool) -> Result<Vec<Row>> {
    let acfg = AraimConfig::default();
    let mut araim: Box<Araim<f64, ARAIM_SATS, ARAIM_MODES>> = Box::new(Araim::new());
    let mut pca: Box<Pca<f64, PCA_SLOTS, PCA_WINDOW>> = Box::new(Pca::new());
    let pcfg = PcaConfig {
        variance_share: args.pca_share,
        p_fa: args.pca_pfa,
    };
    let mut snap = Box::new(Raim::<REPLAY_CAPACITY>::new());
    let mut out = Vec::with_capacity(s.epochs.len());
    for e in &s.epochs {
        let obs = s.observations(e);
        let faulted = s.onset_gps_s.is_some_and(|t| e.time_gps_s >= t);
        let (sats, ism) = s.araim_inputs(e, &obs);
        let mut row = Row {
            t_gps_s: e.time_gps_s,
            n_sats: sats.len(),
            esq: None,
            araim_ratio: f64::NAN,
            araim_alarm: false,
            araim_const_alarm: false,
            pca: None,
            snapshot_alarm: false,
            faulted,
            errors: Vec::new(),
        };
        match araim.process(&acfg, &ism, &sats) {
            Err(e) => row.errors.push(format!("ARAIM: {e}")),
            Ok(a) => {
                match esq::effective_samples(a, 2, PlOutput::AddBracket) {
                    Ok(v) => row.esq = Some(v),
                    Err(e) => row.errors.push(format!("N*: {e}")),
                }
                let st = esq::statistic(a);
                row.araim_ratio = st.ratio;
                row.araim_alarm = !a.detection_passed;
                row.araim_const_alarm = a.modes.iter().any(|m| {
                    m.status == ModeStatus::Monitored
                        && m.events.sats == 0
                        && m.events.consts != 0
                        && !m.passed
                });
            }
        }
        if with_pca {
            match pca.process(&pcfg, e.time_gps_s, &sats) {
                Ok(PcaOutcome::Tested(t)) => row.pca = Some(t),
                Ok(PcaOutcome::WarmingUp { .. }) => {}
                Err(e) => row.errors.push(format!("PCA: {e}")),
            }
        }
        if with_snapshot {
            let ep = Epoch::ranges(e.time_gps_s, &obs, e.reference_m);
            match snap.process(&s.cfg, &ep) {
                Ok(r) => {
                    row.snapshot_alarm = matches!(r.decision, Decision::Alarm | Decision::Excluded)
                }
                Err(e) => row.errors.push(format!("snapshot: {e}")),
            }
        }
        out.push(row);
    }
    Ok(out)
}

/// First epoch at or after `onset` where `hit` holds: (delay s, epoch index).
pub fn first_after(rows: &[Row], onset: Option<f64>, hit: impl Fn(&Row) -> bool) -> Option<f64> {
    let t0 = onset?;
    rows.iter()
        .filter(|r| r.t_gps_s >= t0 - 1e-3)
        .find(|r| hit(r))
        .map(|r| r.t_gps_s - t0)
}

/// Alarms before the onset (all of them on a clean run).
pub fn false_alarms(rows: &[Row], hit: impl Fn(&Row) -> bool) -> usize {
    rows.iter().filter(|r| !r.faulted && hit(r)).count()
}

fn fmt_delay(d: Option<f64>) -> String {
    d.map_or("never".into(), |d| format!("{d:.0} s"))
}

/// The resampler's decisions over a run.
struct Schedule {
    /// The epoch is evaluated.
    emitted: Vec<bool>,
    /// dT_e in force at the epoch, s.
    dte: Vec<f64>,
    /// Windows opened with an emitted sample.
    windows: usize,
}

/// Runs the resampler (window `window_s`) over the rows: N* is taken at
/// the epoch opening each window; an epoch with no N* at a window opening
/// is evaluated, and the window waits for the next epoch with a PL.
fn schedule(rows: &[Row], window_s: f64) -> Result<Schedule> {
    let mut rs = Resampler::new(window_s).map_err(|e| anyhow!("--esq-window-s: {e}"))?;
    let mut emitted = vec![false; rows.len()];
    let mut dte = vec![f64::NAN; rows.len()];
    let mut windows = 0usize;
    for ((r, em), d) in rows.iter().zip(emitted.iter_mut()).zip(dte.iter_mut()) {
        let opens = rs.opens_window(r.t_gps_s);
        let n_star = r.esq.map(|e| e.n_star);
        let sample = if opens && n_star.is_none() {
            Sample::Skip
        } else {
            rs.offer(r.t_gps_s, n_star)
                .map_err(|e| anyhow!("resampler: {e}"))?
        };
        if opens && matches!(sample, Sample::Emit { .. }) {
            windows += 1;
        }
        *em = matches!(sample, Sample::Emit { .. }) || (opens && n_star.is_none());
        *d = rs.interval_s();
    }
    Ok(Schedule {
        emitted,
        dte,
        windows,
    })
}

/// Delay from `onset` to the first emitted epoch (every epoch when
/// `emitted` is None) at or after it on which ARAIM alarmed, s.
fn first_alarm(rows: &[Row], emitted: Option<&[bool]>, onset: f64) -> Option<f64> {
    rows.iter()
        .enumerate()
        .filter(|(_, r)| r.t_gps_s >= onset - 1e-3)
        .find(|(i, r)| r.araim_alarm && emitted.is_none_or(|e| e.get(*i).copied().unwrap_or(false)))
        .map(|(_, r)| r.t_gps_s - onset)
}

/// `--esq --esq-onset-sweep N`: the fault's onset moved by N stratified
/// uniform offsets over the window T, (j + u_j) T / N with u_j ~ U[0, 1)
/// seeded; T is a multiple of the epoch interval, so the onsets are also
/// uniform over the epoch. Per onset, the first ARAIM alarm on every epoch
/// and on the resampled epochs; then the detection probability
/// (Clopper-Pearson 95 %) and the delays' median and 95th percentile
/// (distribution-free 95 % intervals from the order statistics), measured
/// from the true onset.
fn run_sweep(args: &ReplayArgs, n: usize, w: &mut impl Write) -> Result<()> {
    use rand::{Rng, SeedableRng};
    if n == 0 {
        bail!("--esq-onset-sweep needs at least one onset");
    }
    let mut s = setup(args)?;
    let t0 = s
        .onset_gps_s
        .context("--esq-onset-sweep needs a satellite fault (--fault or --eph-fault)")?;
    let window = args.esq.esq_window_s;
    let starts: Vec<f64> = s.plan.faults.iter().map(|f| f.start_gps_s).collect();
    let eph_starts: Vec<f64> = s.eph.iter().map(|f| f.start_gps_s).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.esq.esq_onset_seed);
    let mut every = Vec::with_capacity(n);
    let mut sampled = Vec::with_capacity(n);
    for j in 0..n {
        let u: f64 = rng.random();
        let off = (j as f64 + u) * window / n as f64;
        for (f, t) in s.plan.faults.iter_mut().zip(&starts) {
            f.start_gps_s = t + off;
        }
        for (f, t) in s.eph.iter_mut().zip(&eph_starts) {
            f.start_gps_s = t + off;
        }
        s.onset_gps_s = Some(t0 + off);
        let rows = rows(&s, &args.esq, false, false)?;
        let sch = schedule(&rows, window)?;
        let a = first_alarm(&rows, None, t0 + off);
        let b = first_alarm(&rows, Some(&sch.emitted), t0 + off);
        if !args.quiet {
            writeln!(
                w,
                "onset {} (+{off:6.1} s): first alarm every epoch {}, effective samples {}",
                raim_gnss::time::time_of_day(t0 + off),
                fmt_delay(a),
                fmt_delay(b)
            )?;
        }
        every.push(a);
        sampled.push(b);
    }
    writeln!(
        w,
        "ESQ onset sweep: {n} onsets over T {window:.0} s (seed {}), delays from the true onset",
        args.esq.esq_onset_seed
    )?;
    for (name, d) in [("every epoch", &every), ("effective samples", &sampled)] {
        let mut det: Vec<f64> = d.iter().flatten().copied().collect();
        det.sort_by(f64::total_cmp);
        let (lo, hi) = super::stats::clopper_pearson(det.len(), n, 0.95);
        let q = |p: f64| {
            let (e, l, h) = super::stats::quantile_ci(&det, p, 0.95);
            let f = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.0}"));
            format!("{} s [{}, {}]", f(e), f(l), f(h))
        };
        writeln!(
            w,
            "  {name:18} detected {}/{n} = {:.3} [{lo:.3}, {hi:.3}] | delay median {} | p95 {}",
            det.len(),
            det.len() as f64 / n as f64,
            q(0.5),
            q(0.95)
        )?;
    }
    Ok(())
}

/// `--esq`: N*, dT_e, resampling, the separation test.
fn run_esq(args: &ReplayArgs, s: &Setup, rows: &[Row], w: &mut impl Write) -> Result<()> {
    let window = args.esq.esq_window_s;
    let Schedule {
        emitted,
        dte,
        windows,
    } = schedule(rows, window)?;
    for (i, r) in rows.iter().enumerate() {
        if !args.quiet && !args.json {
            writeln!(
                w,
                "{} n {:2} N* {} dTe {:7.1} s {} ARAIM ratio {:6.3}{}{}",
                raim_gnss::time::time_of_day(r.t_gps_s),
                r.n_sats,
                r.esq
                    .map_or("   -  ".into(), |e| format!("{:6.3}", e.n_star)),
                dte[i],
                if emitted[i] { "emit" } else { "skip" },
                r.araim_ratio,
                if r.araim_alarm { " ALARM" } else { "" },
                if r.errors.is_empty() {
                    String::new()
                } else {
                    format!(" [{}]", r.errors.join("; "))
                },
            )?;
        } else if args.json {
            writeln!(
                w,
                "{}",
                serde_json::json!({
                    "time_gps_s": r.t_gps_s, "n_sats": r.n_sats,
                    "n_star": r.esq.map(|e| e.n_star), "p_sigma": r.esq.map(|e| e.p_sigma),
                    "p_max": r.esq.map(|e| e.p_max), "dte_s": dte[i], "emitted": emitted[i],
                    "araim_ratio": r.araim_ratio, "araim_alarm": r.araim_alarm,
                })
            )?;
        }
    }
    let n = rows.len();
    let solves = emitted.iter().filter(|&&e| e).count();
    let ns: Vec<f64> = rows
        .iter()
        .filter_map(|r| r.esq.map(|e| e.n_star))
        .collect();
    let mut sorted = ns.clone();
    sorted.sort_by(f64::total_cmp);
    let q = |p: f64| {
        sorted
            .get(((sorted.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    let all_alarm = |r: &Row| r.araim_alarm;
    let d_all = first_after(rows, s.onset_gps_s, all_alarm);
    let d_esq = s
        .onset_gps_s
        .and_then(|t0| first_alarm(rows, Some(&emitted), t0));
    let faulted_alarmed = rows.iter().filter(|r| r.faulted && r.araim_alarm).count();
    let faulted_alarmed_emitted = rows
        .iter()
        .zip(&emitted)
        .filter(|(r, e)| r.faulted && r.araim_alarm && **e)
        .count();
    let faulted = rows.iter().filter(|r| r.faulted).count();
    writeln!(
        w,
        "ESQ summary: {n} epochs, window T {window:.0} s, {windows} windows; N* (vertical) min {:.3} median {:.3} max {:.3} ({} epochs with a PL)",
        q(0.0), q(0.5), q(1.0), ns.len()
    )?;
    writeln!(
        w,
        "  solves: every epoch {n}, effective samples {solves} ({:.1} % saved; {:.2} per window against {:.2})",
        100.0 * (1.0 - solves as f64 / n.max(1) as f64),
        solves as f64 / windows.max(1) as f64,
        n as f64 / windows.max(1) as f64
    )?;
    writeln!(
        w,
        "  ARAIM alarms before onset: every epoch {}, effective samples {}",
        false_alarms(rows, all_alarm),
        rows.iter()
            .zip(&emitted)
            .filter(|(r, e)| !r.faulted && r.araim_alarm && **e)
            .count()
    )?;
    if s.onset_gps_s.is_some() {
        writeln!(
            w,
            "  after onset ({faulted} faulted epochs): first alarm every epoch {}, effective samples {}; faulted epochs alarmed {} of which evaluated {} (missed by skipping {})",
            fmt_delay(d_all),
            fmt_delay(d_esq),
            faulted_alarmed,
            faulted_alarmed_emitted,
            faulted_alarmed - faulted_alarmed_emitted
        )?;
    }
    let refused = rows.iter().filter(|r| !r.errors.is_empty()).count();
    if refused > 0 {
        writeln!(
            w,
            "  epochs with a refusal or no N* (listed per epoch): {refused}"
        )?;
    }
    if let Some(p) = &args.esq.esq_plot {
        plot_esq(
            rows,
            &dte,
            &emitted,
            p,
            args.font.as_deref(),
            &super::run_title(args),
        )?;
    }
    Ok(())
}

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// The legend of a panel, upper right on a light background.
fn legend<'a, DB: DrawingBackend + 'a>(
    c: &mut ChartContext<
        'a,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)
}

/// A title naming the file, the faults and the window; three panels on
/// GPS time: N*, dT_e in force, and the ARAIM solution-separation ratio at
/// every epoch against the effective samples the schedule emits, each with
/// its legend.
fn plot_esq(
    rows: &[Row],
    dte: &[f64],
    emitted: &[bool],
    path: &Path,
    font: Option<&Path>,
    title: &str,
) -> Result<()> {
    super::plot::register_font(font)?;
    let root = BitMapBackend::new(path, (1400, 1250)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(&format!("raim replay --esq: {title}"), ("sans-serif", 26))
        .map_err(err)?;
    let panels = root.split_evenly((3, 1));
    let ax = super::plot::TimeAxis::new(
        rows.first().map_or(0.0, |r| r.t_gps_s),
        rows.last().map_or(0.0, |r| r.t_gps_s),
    );
    let ns: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| r.esq.map(|e| (ax.x(r.t_gps_s), e.n_star)))
        .collect();
    let n_max = ns.iter().map(|p| p.1).fold(1.0, f64::max) * 1.3;
    let mut c = ChartBuilder::on(&panels[0])
        .caption(
            "effective sample quantity N* = P_Sigma / P_max (vertical)",
            ("sans-serif", 22),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), 0.0..n_max)
        .map_err(err)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("N*")
        .draw()
        .map_err(err)?;
    c.draw_series(LineSeries::new(ns, &BLUE))
        .map_err(err)?
        .label("N*")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    legend(&mut c)?;
    let d: Vec<(f64, f64)> = rows
        .iter()
        .zip(dte)
        .filter(|(_, d)| d.is_finite())
        .map(|(r, d)| (ax.x(r.t_gps_s), *d))
        .collect();
    let d_max = d.iter().map(|p| p.1).fold(1.0, f64::max) * 1.3;
    let mut c = ChartBuilder::on(&panels[1])
        .caption(
            "effective sample interval dT_e = T / N* in force",
            ("sans-serif", 22),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), 0.0..d_max)
        .map_err(err)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("s")
        .draw()
        .map_err(err)?;
    c.draw_series(LineSeries::new(d, &RED))
        .map_err(err)?
        .label("dT_e")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    legend(&mut c)?;
    let r_max = rows
        .iter()
        .map(|r| r.araim_ratio)
        .filter(|r| r.is_finite())
        .fold(1.5, f64::max)
        * 1.3;
    let mut c = ChartBuilder::on(&panels[2])
        .caption(
            "ARAIM solution separation: max over modes |x(k) - x(0)| / T_k",
            ("sans-serif", 22),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), 0.0..r_max)
        .map_err(err)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("ratio")
        .draw()
        .map_err(err)?;
    let grey = RGBColor(170, 170, 170);
    c.draw_series(LineSeries::new(
        rows.iter()
            .filter(|r| r.araim_ratio.is_finite())
            .map(|r| (ax.x(r.t_gps_s), r.araim_ratio)),
        &grey,
    ))
    .map_err(err)?
    .label("every epoch")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
    c.draw_series(
        rows.iter()
            .zip(emitted)
            .filter(|(r, e)| **e && r.araim_ratio.is_finite())
            .map(|(r, _)| Circle::new((ax.x(r.t_gps_s), r.araim_ratio), 3, BLUE.filled())),
    )
    .map_err(err)?
    .label("effective samples (emitted)")
    .legend(|(x, y)| Circle::new((x + 10, y), 3, BLUE.filled()));
    c.draw_series(LineSeries::new(
        [(ax.first_h, 1.0), (ax.range().end, 1.0)],
        RED.stroke_width(2),
    ))
    .map_err(err)?
    .label("threshold (ratio 1)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    legend(&mut c)?;
    root.present().map_err(err)?;
    Ok(())
}

/// `raim replay --esq | --pca | --esq-mcusum`.
pub fn run(args: &ReplayArgs) -> Result<()> {
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    if args.esq.esq_mcusum {
        super::decorrelate::run(args, &mut w)?;
    }
    if args.esq.esq_onset_sweep.is_some() && !args.esq.esq {
        bail!("--esq-onset-sweep needs --esq");
    }
    if let (true, Some(n)) = (args.esq.esq, args.esq.esq_onset_sweep) {
        run_sweep(args, n, &mut w)?;
    } else if args.esq.esq || args.esq.pca {
        let s = setup(args)?;
        let rows = rows(&s, &args.esq, args.esq.pca, args.esq.pca)?;
        if args.esq.esq {
            run_esq(args, &s, &rows, &mut w)?;
        }
        if args.esq.pca {
            super::pca::run(args, &s, &rows, &mut w)?;
        }
    }
    w.flush()?;
    Ok(())
}
