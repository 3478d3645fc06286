//! `raim replay --pf {ekf,pf,gapf}`: the particle-filter RAIM of seed 004
//! (raim_core::pf, docs/PF.md) on the replay's corrected pseudoranges,
//! with the same fault injection. Per epoch: position error, N_eff, the
//! decision statistic D_k against the threshold, alarm, isolation and
//! exclusion; a summary in the shape of seed 004 Table 1 (with N_eff
//! before and after the genetic step); the threshold from the calibrated
//! table at the allocated Pfa (`raim_core::pf::threshold`); a plot of the LLRs and the position error.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use plotters::prelude::*;
use raim_core::pf::{
    Ekf, Estimator, GaPf, Likelihood, PfConfig, PfOutput, PfRaim, ProcessModel, SirPf,
};
use raim_core::Real;
use raim_gnss::faults::FaultPlan;
use raim_gnss::ranging::PreparedEpoch;
use serde::Serialize;

use super::{checked_fault_plan, mean_position, prepare, record, run_core, ReplayArgs, Target};

/// Satellite capacity of the PF monitor in replays (GEOP G+E has up to ~20).
pub const PF_CAPACITY: usize = 32;

/// The filter: `ekf` (extended Kalman filter baseline), `pf` (plain SIR
/// particle filter baseline), `gapf` (genetic-resampling particle filter,
/// seed 004's method). Plain comments on the variants: value docs would
/// switch `--help` to clap's long layout (one help layout for every subcommand).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
pub enum PfKind {
    // Extended Kalman filter baseline.
    Ekf,
    // Plain SIR particle filter baseline.
    Pf,
    // Genetic-resampling particle filter (seed 004's method).
    Gapf,
}

#[derive(Debug, Clone, Args)]
pub struct PfArgs {
    /// Run the particle-filter RAIM (Wang et al. 2014, docs/PF.md) instead of the snapshot monitor: ekf (EKF baseline), pf (plain SIR PF baseline) or gapf (genetic-resampling PF).
    #[arg(long, value_enum)]
    pub pf: Option<PfKind>,
    /// Particles per filter: 50, 100, 300 or 1000. The default, 300, is the smallest count whose calibrated thresholds the default model (phone_1hz) accepts at every Pfa node and window (docs/PF.md "The detectability ceiling"); 100 is refused there.
    #[arg(long, default_value_t = 300)]
    pub particles: usize,
    /// Seed of the filters' random generator.
    #[arg(long, default_value_t = 1)]
    pub pf_seed: u64,
    /// Ranging sigma, m.
    #[arg(long, default_value_t = 10.0)]
    pub pf_sigma_m: f64,
    /// Likelihood: gauss, t:NU (Student-t), mix:EPS:K (Gaussian mixture).
    #[arg(long, default_value = "gauss")]
    pub pf_likelihood: String,
    /// Position random walk, m/sqrt(s).
    #[arg(long, default_value_t = 2.0)]
    pub pf_q_pos: f64,
    /// Clock random walk, m/sqrt(s).
    #[arg(long, default_value_t = 5.0)]
    pub pf_q_clock: f64,
    /// Clock-drift random walk, (m/s)/sqrt(s).
    #[arg(long, default_value_t = 0.5)]
    pub pf_q_drift: f64,
    /// Window U of the decision function (eq. 13), epochs.
    #[arg(long, default_value_t = 10)]
    pub pf_window: usize,
    /// False-alarm probability per epoch allocated to the PF monitor: the threshold is the calibrated table's (docs/PF.md "Thresholds").
    #[arg(long, default_value_t = 1e-3)]
    pub pf_pfa: f64,
    /// Experiments only: this decision threshold instead of the table's (not an allocation).
    #[arg(long)]
    pub pf_threshold: Option<f64>,
    /// Run this many filter seeds (pf_seed, pf_seed+1, ...) and print the aggregate: false alarms against the allocation's binomial 99 % bound, detections, delays, wrong isolations, RMSE (docs/PF.md "Verification").
    #[arg(long, default_value_t = 1)]
    pub pf_seeds: u64,
    /// With --pf-seeds: shift the satellite faults' onset of seed i by S (i + 0.5) / N seconds, spreading onsets uniformly over S.
    #[arg(long, default_value_t = 0.0)]
    pub pf_onset_spread_s: f64,
    /// Readmit an excluded satellite after this many seconds (0: never).
    #[arg(long, default_value_t = 0.0)]
    pub pf_readmit_s: f64,
    /// f32 particle state (the device precision) instead of f64.
    #[arg(long)]
    pub pf_f32: bool,
    /// Do not exclude the isolated satellite (detection only).
    #[arg(long)]
    pub pf_no_exclude: bool,
    /// Plot D_k against the threshold, the per-satellite LLRs and the
    /// position error into this PNG.
    #[arg(long, value_name = "FILE", help_heading = super::heading::PLOTS)]
    pub pf_plot: Option<PathBuf>,
}

impl PfKind {
    /// The filter's name in the calibrated threshold table
    /// (`Estimator::KIND`).
    pub fn table_kind(self) -> &'static str {
        match self {
            PfKind::Ekf => "ekf",
            PfKind::Pf => "pf",
            PfKind::Gapf => "gapf",
        }
    }

    /// The filter's plain name for captions.
    pub fn name(self) -> &'static str {
        match self {
            PfKind::Ekf => "extended Kalman",
            PfKind::Pf => "SIR particle",
            PfKind::Gapf => "genetic-resampling particle",
        }
    }
}

impl PfArgs {
    /// The particle count of the table row (0 for the EKF).
    pub fn table_particles(&self, kind: PfKind) -> usize {
        if kind == PfKind::Ekf {
            0
        } else {
            self.particles
        }
    }

    pub fn choice(&self, kind: PfKind) -> FilterChoice {
        FilterChoice {
            kind,
            particles: self.particles,
            f32_state: self.pf_f32,
            threshold: self.pf_threshold,
        }
    }

    pub fn likelihood(&self) -> Result<Likelihood> {
        let s = self.pf_likelihood.as_str();
        let parts: Vec<&str> = s.split(':').collect();
        Ok(match parts.as_slice() {
            ["gauss"] => Likelihood::Gaussian,
            ["t", nu] => Likelihood::StudentT { nu: nu.parse()? },
            ["mix", e, k] => Likelihood::Mixture {
                outlier_prob: e.parse()?,
                outlier_scale: k.parse()?,
            },
            _ => bail!("--pf-likelihood {s}: expected gauss, t:NU or mix:EPS:K"),
        })
    }

    pub fn config(&self) -> Result<PfConfig> {
        let c = PfConfig {
            process: ProcessModel {
                position_m_per_sqrt_s: self.pf_q_pos,
                clock_m_per_sqrt_s: self.pf_q_clock,
                drift_m_s_per_sqrt_s: self.pf_q_drift,
            },
            likelihood: self.likelihood()?,
            sigma_m: self.pf_sigma_m,
            init_position_m: self.pf_sigma_m,
            init_clock_m: self.pf_sigma_m,
            init_drift_m_s: 2.0,
            mutation_m: 0.5 * self.pf_sigma_m,
            window: self.pf_window,
            pfa: self.pf_pfa,
            exclude: !self.pf_no_exclude,
            readmit_s: self.pf_readmit_s,
            ..PfConfig::default()
        };
        c.validate().map_err(|e| anyhow!("pf configuration: {e}"))?;
        Ok(c)
    }
}

/// One epoch of a PF replay.
#[derive(Debug, Clone, Serialize)]
pub struct PfRecord {
    pub epoch: usize,
    pub time_gps_s: f64,
    pub sats: usize,
    pub used: usize,
    pub faulted: Vec<String>,
    pub error_3d_m: Option<f64>,
    pub error_h_m: Option<f64>,
    pub n_eff: f64,
    /// N_eff before the genetic step (the GA-PF; = n_eff for the PF).
    pub n_eff_before_ga: f64,
    pub decision: Option<f64>,
    pub threshold: f64,
    pub alarm: bool,
    pub isolated: Option<String>,
    pub excluded: Option<String>,
    pub main_collapsed: bool,
    pub aux_collapsed: usize,
    pub clock_jump: bool,
    pub drift_m_s: f64,
    /// (satellite, s_k, windowed max) per auxiliary filter.
    pub llr: Vec<(String, f64, f64)>,
    pub error: Option<String>,
}

/// The seed 004 Table 1 line of a run, with the detection results.
#[derive(Debug, Clone, Serialize)]
pub struct PfSummary {
    pub filter: PfKind,
    pub particles: usize,
    pub seed: u64,
    pub epochs: usize,
    /// 3D position RMSE over epochs with a position (eq. 17), m.
    pub rmse_3d_m: f64,
    /// Mean N_eff of the main filter (eq. 16) after the genetic step; 0
    /// for the EKF.
    pub mean_n_eff: f64,
    /// Mean N_eff of the main filter before the genetic step.
    pub mean_n_eff_before_ga: f64,
    pub threshold: f64,
    pub fault_epoch: Option<usize>,
    pub first_alarm_epoch: Option<usize>,
    pub isolated: Option<String>,
    pub false_alarms_before_fault: usize,
    pub max_decision_before_fault: f64,
    pub collapses: usize,
    pub errors: usize,
    pub host_ms_per_epoch: f64,
}

type Prepared = (Vec<PreparedEpoch>, FaultPlan, Option<[f64; 3]>);

fn load(args: &ReplayArgs) -> Result<Prepared> {
    let (epochs, header, first) = prepare(args)?;
    let plan = checked_fault_plan(args, first, &epochs)?;
    let reference = match args.reference {
        super::Reference::Header => header,
        super::Reference::CleanMean => {
            let clean = run_core(
                Target::Host,
                &args.core_config(),
                &epochs,
                &FaultPlan::default(),
                None,
                None,
            )?;
            mean_position(&clean)
        }
    };
    Ok((epochs, plan, reference))
}

fn run_typed<T: Real, E: Estimator<T>>(
    cfg: &PfConfig,
    threshold: Option<f64>,
    seed: u64,
    epochs: &[PreparedEpoch],
    plan: &FaultPlan,
    reference: Option<[f64; 3]>,
) -> Vec<PfRecord> {
    let mut m: Box<PfRaim<T, E, PF_CAPACITY>> = Box::new(PfRaim::new(seed));
    let mut out = Vec::with_capacity(epochs.len());
    for (k, e) in epochs.iter().enumerate() {
        let mut sats = e.observations();
        let injected = plan.apply(e.time_gps_s, &mut sats);
        let faulted = injected
            .faulted
            .iter()
            .map(|(id, b)| format!("{id}:{b:.1}"))
            .collect();
        let mut rec = PfRecord {
            epoch: k,
            time_gps_s: e.time_gps_s,
            sats: sats.len(),
            used: 0,
            faulted,
            error_3d_m: None,
            error_h_m: None,
            n_eff: 0.0,
            n_eff_before_ga: 0.0,
            decision: None,
            threshold: f64::NAN,
            alarm: false,
            isolated: None,
            excluded: None,
            main_collapsed: false,
            aux_collapsed: 0,
            clock_jump: false,
            drift_m_s: 0.0,
            llr: Vec::new(),
            error: None,
        };
        let o = match threshold {
            Some(t) => m.process_at(cfg, t, e.time_gps_s, &sats),
            None => m.process(cfg, e.time_gps_s, &sats),
        };
        match o {
            Ok(o) => fill(&mut rec, &o, reference),
            Err(err) => rec.error = Some(err.to_string()),
        }
        out.push(rec);
    }
    out
}

fn fill(rec: &mut PfRecord, o: &PfOutput<PF_CAPACITY>, reference: Option<[f64; 3]>) {
    rec.used = o.used;
    if let (Some(p), Some(r)) = (o.position_m, reference) {
        let e = record::error_enu(p, r);
        rec.error_3d_m = Some((e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt());
        rec.error_h_m = Some(e[0].hypot(e[1]));
    }
    rec.n_eff = o.n_eff;
    rec.n_eff_before_ga = o.n_eff_before_ga;
    rec.threshold = o.threshold;
    rec.decision = o.decision.is_finite().then_some(o.decision);
    rec.alarm = o.alarm;
    rec.isolated = o.isolated.map(|s| s.to_string());
    rec.excluded = o.excluded.map(|s| s.to_string());
    rec.main_collapsed = o.main_collapsed;
    rec.aux_collapsed = o.aux_collapsed;
    rec.clock_jump = o.clock_jump;
    rec.drift_m_s = o.drift_m_s;
    rec.llr = o
        .llr
        .iter()
        .map(|l| (l.id.to_string(), l.llr, l.windowed))
        .collect();
}

/// Which filter runs: method, particle count, state precision.
#[derive(Debug, Clone, Copy)]
pub struct FilterChoice {
    pub kind: PfKind,
    pub particles: usize,
    /// f32 particle state (the device precision) instead of f64.
    pub f32_state: bool,
    /// An explicit decision threshold (experiments); `None`: the
    /// calibrated table's at the configured Pfa.
    pub threshold: Option<f64>,
}

/// One run of the chosen filter.
pub fn run_once(
    choice: FilterChoice,
    cfg: &PfConfig,
    seed: u64,
    epochs: &[PreparedEpoch],
    plan: &FaultPlan,
    reference: Option<[f64; 3]>,
) -> Result<Vec<PfRecord>> {
    let FilterChoice {
        kind,
        particles,
        f32_state,
        threshold,
    } = choice;
    macro_rules! pick {
        ($t:ty) => {
            match (kind, particles) {
                (PfKind::Ekf, _) => {
                    run_typed::<$t, Ekf<$t>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Pf, 50) => {
                    run_typed::<$t, SirPf<$t, 50>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Pf, 100) => {
                    run_typed::<$t, SirPf<$t, 100>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Pf, 300) => {
                    run_typed::<$t, SirPf<$t, 300>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Pf, 1000) => {
                    run_typed::<$t, SirPf<$t, 1000>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Gapf, 50) => {
                    run_typed::<$t, GaPf<$t, 50>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Gapf, 100) => {
                    run_typed::<$t, GaPf<$t, 100>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Gapf, 300) => {
                    run_typed::<$t, GaPf<$t, 300>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (PfKind::Gapf, 1000) => {
                    run_typed::<$t, GaPf<$t, 1000>>(cfg, threshold, seed, epochs, plan, reference)
                }
                (_, n) => bail!("--particles {n}: supported counts are 50, 100, 300, 1000"),
            }
        };
    }
    // The filters hold up to (1 + 32) x 1000 particles: give the run a big stack.
    std::thread::scope(|scope| {
        let h = std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(scope, || -> Result<Vec<PfRecord>> {
                Ok(if f32_state { pick!(f32) } else { pick!(f64) })
            })?;
        h.join().map_err(|_| anyhow!("pf run thread panicked"))?
    })
}

/// The summary of a run (fault onset: the first epoch with an injected
/// satellite fault).
pub fn summarise(
    kind: PfKind,
    particles: usize,
    seed: u64,
    recs: &[PfRecord],
    host_ms_per_epoch: f64,
) -> PfSummary {
    let fault_epoch = recs.iter().position(|r| !r.faulted.is_empty());
    let before = |r: &&PfRecord| fault_epoch.is_none_or(|f| r.epoch < f);
    let errs: Vec<f64> = recs.iter().filter_map(|r| r.error_3d_m).collect();
    let rmse = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
    let with_pos = recs
        .iter()
        .filter(|r| r.error.is_none() && !r.main_collapsed);
    let neffs: Vec<f64> = with_pos.clone().map(|r| r.n_eff).collect();
    let neffs_before: Vec<f64> = with_pos.map(|r| r.n_eff_before_ga).collect();
    let threshold = recs
        .iter()
        .map(|r| r.threshold)
        .find(|t| !t.is_nan())
        .unwrap_or(f64::NAN);
    let first = fault_epoch.and_then(|f| recs.iter().find(|r| r.epoch >= f && r.alarm));
    PfSummary {
        filter: kind,
        particles: if kind == PfKind::Ekf { 0 } else { particles },
        seed,
        epochs: recs.len(),
        rmse_3d_m: rmse,
        mean_n_eff: neffs.iter().sum::<f64>() / neffs.len().max(1) as f64,
        mean_n_eff_before_ga: neffs_before.iter().sum::<f64>() / neffs_before.len().max(1) as f64,
        threshold,
        fault_epoch,
        first_alarm_epoch: first.map(|r| r.epoch),
        isolated: first.and_then(|r| r.isolated.clone()),
        false_alarms_before_fault: recs.iter().filter(before).filter(|r| r.alarm).count(),
        max_decision_before_fault: recs
            .iter()
            .filter(before)
            .filter_map(|r| r.decision)
            .fold(f64::NEG_INFINITY, f64::max),
        collapses: recs.iter().filter(|r| r.main_collapsed).count(),
        errors: recs.iter().filter(|r| r.error.is_some()).count(),
        host_ms_per_epoch,
    }
}

/// `raim replay --pf ...`: runs, prints records (text or JSON) and the summary.
pub fn run(args: &ReplayArgs) -> Result<()> {
    let pf = &args.pf;
    let kind = pf.pf.context("--pf not given")?;
    let cfg = pf.config()?;
    if pf.pf_threshold.is_none() {
        // The monitor would refuse every epoch: say so before loading.
        let t = raim_core::pf::threshold::lookup(kind.table_kind(), pf.table_particles(kind), &cfg)
            .map_err(|e| anyhow!("pf configuration refused: {e}"))?;
        raim_core::config_bounds::pf::threshold_bound(&cfg.likelihood, cfg.window)
            .check_pf(t)
            .map_err(|e| {
                anyhow!("pf configuration refused: the calibrated threshold is above the detectability ceiling ({e})")
            })?;
    }
    let (epochs, plan, reference) = load(args)?;
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    if pf.pf_seeds > 1 {
        let v = verify(pf, kind, &cfg, &epochs, &plan, reference)?;
        if args.json {
            writeln!(w, "{}", serde_json::json!({ "pf_verification": v }))?;
        } else {
            writeln!(w, "{}", verification_header())?;
            writeln!(w, "{}", verification_row(&v))?;
        }
        return Ok(());
    }
    let t0 = std::time::Instant::now();
    let recs = run_once(pf.choice(kind), &cfg, pf.pf_seed, &epochs, &plan, reference)?;
    let ms = t0.elapsed().as_secs_f64() * 1e3 / recs.len().max(1) as f64;
    if !args.quiet {
        for r in &recs {
            if args.json {
                writeln!(w, "{}", serde_json::to_string(r)?)?;
            } else {
                writeln!(w, "{}", text_line(r))?;
            }
        }
    }
    let s = summarise(kind, pf.particles, pf.pf_seed, &recs, ms);
    if args.json {
        writeln!(w, "{}", serde_json::json!({ "pf_summary": s }))?;
    } else {
        writeln!(w, "{}", summary_header())?;
        writeln!(w, "{}", summary_row(&s))?;
    }
    if let Some(p) = &pf.pf_plot {
        plot(&recs, &s, p, args.font.as_deref(), &super::run_title(args))?;
    }
    Ok(())
}

fn text_line(r: &PfRecord) -> String {
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    format!(
        "{:4} t={:.0} n={}/{} err3d={} neff={:.1} D={} alarm={} iso={} excl={}{}{}{}",
        r.epoch,
        r.time_gps_s,
        r.used,
        r.sats,
        f(r.error_3d_m),
        r.n_eff,
        f(r.decision),
        r.alarm as u8,
        r.isolated.as_deref().unwrap_or("-"),
        r.excluded.as_deref().unwrap_or("-"),
        if r.main_collapsed { " COLLAPSED" } else { "" },
        if r.faulted.is_empty() {
            String::new()
        } else {
            format!(" fault={}", r.faulted.join(","))
        },
        r.error
            .as_deref()
            .map_or(String::new(), |e| format!(" error: {e}")),
    )
}

pub fn summary_header() -> String {
    "| filter | N | RMSE 3D (m) | mean N_eff before GA | mean N_eff after GA | threshold | fault at | alarm at | isolated | false alarms before | max D before | collapses | ms/epoch |\n\
     | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
        .to_string()
}

pub fn summary_row(s: &PfSummary) -> String {
    let o = |v: Option<usize>| v.map_or("-".to_string(), |v| v.to_string());
    format!(
        "| {} | {} | {:.2} | {:.1} | {:.1} | {:.2} | {} | {} | {} | {} | {:.2} | {} | {:.2} |",
        s.filter
            .to_possible_value()
            .map_or_else(String::new, |v| v.get_name().to_string()),
        if s.particles == 0 {
            "-".to_string()
        } else {
            s.particles.to_string()
        },
        s.rmse_3d_m,
        s.mean_n_eff_before_ga,
        s.mean_n_eff,
        s.threshold,
        o(s.fault_epoch),
        o(s.first_alarm_epoch),
        s.isolated.as_deref().unwrap_or("-"),
        s.false_alarms_before_fault,
        s.max_decision_before_fault,
        s.collapses,
        s.host_ms_per_epoch,
    )
}

fn perr<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// A title naming the file, the faults and the window, then two panels on
/// GPS time: every auxiliary filter's windowed accumulated LLR (one legend
/// entry per satellite) against the threshold, the fault onset marked, and
/// the 3D position error. Values outside the drawn range are clipped to its
/// edge, and the caption says so.
pub fn plot(
    recs: &[PfRecord],
    s: &PfSummary,
    path: &Path,
    font: Option<&Path>,
    title: &str,
) -> Result<()> {
    super::plot::register_font(font)?;
    let root = BitMapBackend::new(path, (1600, 1100)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let root = root
        .titled(&format!("raim replay --pf: {title}"), ("sans-serif", 26))
        .map_err(perr)?;
    let (top, bottom) = root.split_vertically(620);
    let ax = super::plot::TimeAxis::new(
        recs.first().map_or(0.0, |r| r.time_gps_s),
        recs.last().map_or(0.0, |r| r.time_gps_s),
    );
    let all = || {
        recs.iter()
            .flat_map(|r| r.llr.iter().map(|l| l.2))
            .filter(|v| v.is_finite())
    };
    let dmax = all()
        .fold(s.threshold * 1.5, f64::max)
        .min(s.threshold * 20.0);
    let dmin = all().fold(0.0, f64::min).max(-s.threshold * 5.0);
    let clipped_low = all().filter(|&v| v < dmin).count();
    let clipped_high = all().filter(|&v| v > dmax).count();
    let mut note = String::new();
    if clipped_low > 0 {
        note.push_str(&format!(
            "; {clipped_low} values below {dmin:.0} drawn at {dmin:.0}"
        ));
    }
    if clipped_high > 0 {
        note.push_str(&format!(
            "; {clipped_high} values above {dmax:.0} drawn at {dmax:.0}"
        ));
    }
    let mut c = ChartBuilder::on(&top)
        .caption(
            format!(
                "{} filter, {} particles: windowed accumulated LLR per left-out satellite{note}",
                s.filter.name(),
                s.particles
            ),
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), dmin..dmax)
        .map_err(perr)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("windowed accumulated LLR")
        .draw()
        .map_err(perr)?;
    let mut names: Vec<String> = recs
        .iter()
        .flat_map(|r| r.llr.iter().map(|l| l.0.clone()))
        .collect();
    names.sort();
    names.dedup();
    for (i, name) in names.iter().enumerate() {
        let col = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = recs
            .iter()
            .filter_map(|r| {
                r.llr
                    .iter()
                    .find(|l| &l.0 == name)
                    .map(|l| (ax.x(r.time_gps_s), l.2.clamp(dmin, dmax)))
            })
            .collect();
        c.draw_series(LineSeries::new(pts, col.stroke_width(1)))
            .map_err(perr)?
            .label(format!("without {name}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
    }
    c.draw_series(LineSeries::new(
        [(ax.first_h, s.threshold), (ax.last_h, s.threshold)],
        RED.stroke_width(2),
    ))
    .map_err(perr)?
    .label(format!("decision threshold {:.1}", s.threshold))
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    if let Some(r) = s
        .fault_epoch
        .and_then(|f| recs.iter().find(|r| r.epoch == f))
    {
        let x = ax.x(r.time_gps_s);
        c.draw_series(LineSeries::new(
            [(x, dmin), (x, dmax)],
            BLACK.stroke_width(1),
        ))
        .map_err(perr)?
        .label(format!(
            "fault onset {} (epoch {})",
            raim_gnss::time::time_of_day(r.time_gps_s),
            r.epoch
        ))
        .legend(|(x, y)| PathElement::new(vec![(x, y - 6), (x, y + 6)], BLACK));
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(perr)?;
    let emax = recs
        .iter()
        .filter_map(|r| r.error_3d_m)
        .fold(1.0, f64::max)
        .min(200.0);
    let clipped = recs
        .iter()
        .filter_map(|r| r.error_3d_m)
        .filter(|&e| e > emax)
        .count();
    let mut c = ChartBuilder::on(&bottom)
        .caption(
            if clipped > 0 {
                format!("3D position error of the main filter ({clipped} epochs above {emax:.0} m drawn at {emax:.0} m)")
            } else {
                "3D position error of the main filter".to_string()
            },
            ("sans-serif", 20),
        )
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), 0.0..emax)
        .map_err(perr)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("m")
        .draw()
        .map_err(perr)?;
    c.draw_series(LineSeries::new(
        recs.iter()
            .filter_map(|r| r.error_3d_m.map(|e| (ax.x(r.time_gps_s), e.min(emax)))),
        BLUE.stroke_width(1),
    ))
    .map_err(perr)?
    .label("3D error")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    root.present().map_err(perr)?;
    Ok(())
}

/// The multi-seed verification of one configuration (`--pf-seeds`).
#[derive(Debug, Clone, Serialize)]
pub struct PfVerification {
    pub filter: PfKind,
    pub particles: usize,
    pub window: usize,
    pub pfa: f64,
    pub threshold: f64,
    pub seeds: u64,
    /// Fault-free epochs with a decision (before the onset, or all).
    pub clean_epochs: usize,
    pub false_alarms: usize,
    /// The largest false-alarm count the allocation allows at 99 %: the
    /// smallest k with P(Bin(clean_epochs, pfa) <= k) >= 0.99.
    pub false_alarm_bound_99: usize,
    /// Runs with a satellite fault.
    pub faulted_runs: usize,
    pub detected: usize,
    /// Wilson 95 % interval of the detection probability.
    pub detection_ci95: (f64, f64),
    /// Detection delay, epochs: median and 95th percentile.
    pub delay_median_epochs: Option<f64>,
    pub delay_p95_epochs: Option<f64>,
    /// Detections whose isolated satellite is not the faulted one.
    pub wrong_isolations: usize,
    pub wrong_isolation_ci95: (f64, f64),
    /// 3D RMSE over the seeds: mean and the 2.5-97.5 % range of the runs.
    pub rmse_mean_m: f64,
    pub rmse_p025_m: f64,
    pub rmse_p975_m: f64,
    pub mean_n_eff_before_ga: f64,
    pub mean_n_eff: f64,
    pub collapses: usize,
    pub errors: usize,
}

/// Wilson score interval (95 %) of k successes in n trials.
pub fn wilson95(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_964f64;
    let n_f = n as f64;
    let p = k as f64 / n_f;
    let d = 1.0 + z * z / n_f;
    let c = (p + z * z / (2.0 * n_f)) / d;
    let h = z * (p * (1.0 - p) / n_f + z * z / (4.0 * n_f * n_f)).sqrt() / d;
    ((c - h).max(0.0), (c + h).min(1.0))
}

/// The smallest k with P(Bin(n, p) <= k) >= q.
pub fn binomial_upper(n: usize, p: f64, q: f64) -> usize {
    let mut k = 0;
    while k < n && crate::pf_table::binomial_cdf(k, n, p) < q {
        k += 1;
    }
    k
}

fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    if sorted.is_empty() {
        return None;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted.get(i).copied()
}

/// Runs `pf.pf_seeds` seeds; the satellite faults of seed i start
/// `pf_onset_spread_s (i + 0.5) / N` later.
pub fn verify(
    pf: &PfArgs,
    kind: PfKind,
    cfg: &PfConfig,
    epochs: &[PreparedEpoch],
    plan: &FaultPlan,
    reference: Option<[f64; 3]>,
) -> Result<PfVerification> {
    let n = pf.pf_seeds;
    let mut v = PfVerification {
        filter: kind,
        particles: if kind == PfKind::Ekf { 0 } else { pf.particles },
        window: cfg.window,
        pfa: cfg.pfa,
        threshold: f64::NAN,
        seeds: n,
        clean_epochs: 0,
        false_alarms: 0,
        false_alarm_bound_99: 0,
        faulted_runs: 0,
        detected: 0,
        detection_ci95: (0.0, 1.0),
        delay_median_epochs: None,
        delay_p95_epochs: None,
        wrong_isolations: 0,
        wrong_isolation_ci95: (0.0, 1.0),
        rmse_mean_m: 0.0,
        rmse_p025_m: 0.0,
        rmse_p975_m: 0.0,
        mean_n_eff_before_ga: 0.0,
        mean_n_eff: 0.0,
        collapses: 0,
        errors: 0,
    };
    let (mut delays, mut rmses) = (Vec::new(), Vec::new());
    for i in 0..n {
        let mut p = plan.clone();
        let shift = pf.pf_onset_spread_s * (i as f64 + 0.5) / n as f64;
        for f in p.faults.iter_mut().filter(|f| f.is_satellite_fault()) {
            f.start_gps_s += shift;
            if let Some(e) = f.end_gps_s.as_mut() {
                *e += shift;
            }
        }
        let seed = pf.pf_seed + i;
        let recs = run_once(pf.choice(kind), cfg, seed, epochs, &p, reference)?;
        let s = summarise(kind, pf.particles, seed, &recs, 0.0);
        if v.threshold.is_nan() {
            v.threshold = s.threshold;
        }
        let onset = s.fault_epoch.unwrap_or(recs.len());
        v.clean_epochs += recs
            .iter()
            .take(onset)
            .filter(|r| r.decision.is_some())
            .count();
        v.false_alarms += s.false_alarms_before_fault;
        if let Some(f) = s.fault_epoch {
            v.faulted_runs += 1;
            if let Some(a) = s.first_alarm_epoch {
                v.detected += 1;
                delays.push((a - f) as f64);
                let faulted: Vec<&str> = recs
                    .get(a)
                    .map(|r| {
                        r.faulted
                            .iter()
                            .filter_map(|x| x.split(':').next())
                            .collect()
                    })
                    .unwrap_or_default();
                if !s
                    .isolated
                    .as_deref()
                    .is_some_and(|id| faulted.contains(&id))
                {
                    v.wrong_isolations += 1;
                }
            }
        }
        rmses.push(s.rmse_3d_m);
        v.mean_n_eff_before_ga += s.mean_n_eff_before_ga / n as f64;
        v.mean_n_eff += s.mean_n_eff / n as f64;
        v.collapses += s.collapses;
        v.errors += s.errors;
    }
    v.false_alarm_bound_99 = binomial_upper(v.clean_epochs, cfg.pfa, 0.99);
    v.detection_ci95 = wilson95(v.detected, v.faulted_runs);
    v.wrong_isolation_ci95 = wilson95(v.wrong_isolations, v.detected);
    delays.sort_by(|a, b| a.total_cmp(b));
    v.delay_median_epochs = quantile(&delays, 0.5);
    v.delay_p95_epochs = quantile(&delays, 0.95);
    rmses.sort_by(|a, b| a.total_cmp(b));
    v.rmse_mean_m = rmses.iter().sum::<f64>() / rmses.len().max(1) as f64;
    v.rmse_p025_m = quantile(&rmses, 0.025).unwrap_or(f64::NAN);
    v.rmse_p975_m = quantile(&rmses, 0.975).unwrap_or(f64::NAN);
    Ok(v)
}

pub fn verification_header() -> String {
    "| filter | N | U | threshold | seeds | false alarms / clean epochs | 99 % bound | detected (95 % CI) | delay median / p95 (epochs) | wrong isolations (95 % CI) | RMSE mean [2.5-97.5 %] (m) | N_eff before / after GA | collapses |\n\
     | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
        .to_string()
}

pub fn verification_row(v: &PfVerification) -> String {
    let o = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.0}"));
    let pass = if v.false_alarms <= v.false_alarm_bound_99 {
        "within"
    } else {
        "EXCEEDS"
    };
    format!(
        "| {:?} | {} | {} | {:.2} | {} | {} / {} | {} ({pass}) | {}/{} ({:.2}-{:.2}) | {} / {} | {}/{} ({:.2}-{:.2}) | {:.2} [{:.2}-{:.2}] | {:.1} / {:.1} | {} |",
        v.filter,
        if v.particles == 0 { "-".to_string() } else { v.particles.to_string() },
        v.window,
        v.threshold,
        v.seeds,
        v.false_alarms,
        v.clean_epochs,
        v.false_alarm_bound_99,
        v.detected,
        v.faulted_runs,
        v.detection_ci95.0,
        v.detection_ci95.1,
        o(v.delay_median_epochs),
        o(v.delay_p95_epochs),
        v.wrong_isolations,
        v.detected,
        v.wrong_isolation_ci95.0,
        v.wrong_isolation_ci95.1,
        v.rmse_mean_m,
        v.rmse_p025_m,
        v.rmse_p975_m,
        v.mean_n_eff_before_ga,
        v.mean_n_eff,
        v.collapses,
    )
}
