//! `raim replay --model-check`: the run-time model check
//! (`raim_core::consistency`, docs/MODEL_CHECK.md) beside the monitor the
//! replay runs: the snapshot monitor (its sigma model, q = D^2 of the
//! solution in force), or ARAIM with `--araim` (its accuracy model C_acc,
//! q of the C_acc-weighted fit of the solution in force). Every answered
//! epoch (not an alarm, not refused) is offered; the check takes a sample
//! every `--model-check-spacing-s` and tests its window at each.
//!
//! The report, per run: the configuration and its allocation (P_h, the
//! evaluations an hour can hold, p per evaluation), the epochs answered
//! and offered, the samples (= evaluations), the rejections, the first
//! declaration (time, and samples after the first injected fault's onset),
//! the smallest p-value seen, the count of false declarations the
//! allocation allows at 99 % confidence (binomial, evaluations at p per
//! evaluation; on a clean file every rejection is false), and the mean of
//! q / dof over the answered epochs (how the model fits the data: a
//! diagnostic, no threshold uses it).

use std::io::Write;

use anyhow::{anyhow, Result};
use clap::Args;
use raim_core::araim::AraimConfig;
use raim_core::consistency::{
    ModelCheck, ModelCheckConfig, Offer, DEFAULT_SPACING_S, DEFAULT_WINDOW,
};
use raim_core::{Decision, Epoch, Raim};
use serde::Serialize;

use super::esq::{setup, Setup};
use super::{ReplayArgs, REPLAY_CAPACITY};

/// Window capacity of the host's model check (samples).
pub const MODEL_CHECK_CAPACITY: usize = 64;

#[derive(Debug, Clone, Args)]
pub struct ModelCheckArgs {
    /// Run the model check beside the monitor (the snapshot monitor, or ARAIM with --araim): does the error model fit the residuals? (docs/MODEL_CHECK.md)
    #[arg(long)]
    pub model_check: bool,
    /// Model check: least time between two samples, s (default: the longest measured correlation time of the parity vector, docs/ESQ.md).
    #[arg(long, default_value_t = DEFAULT_SPACING_S)]
    pub model_check_spacing_s: f64,
    /// Model check: samples in the window (at most 64).
    #[arg(long, default_value_t = DEFAULT_WINDOW)]
    pub model_check_window: usize,
    /// Model check: allocated false-declaration probability per hour of operation (the core's DEFAULT_P_FA_PER_HOUR).
    #[arg(long, default_value = "1e-6")]
    pub model_check_pfa_hour: f64,
}

impl ModelCheckArgs {
    pub fn config(&self) -> ModelCheckConfig {
        ModelCheckConfig {
            spacing_s: self.model_check_spacing_s,
            window: self.model_check_window,
            p_fa_per_hour: self.model_check_pfa_hour,
        }
    }
}

/// One run's result.
#[derive(Debug, Clone, Serialize)]
pub struct ModelCheckReport {
    /// "snapshot" or "araim".
    pub monitor: &'static str,
    pub spacing_s: f64,
    pub window: usize,
    pub p_fa_per_hour: f64,
    pub evaluations_per_hour: f64,
    pub p_fa_per_evaluation: f64,
    pub epochs: usize,
    /// Epochs answered with a solution (offered).
    pub offered: usize,
    /// Epochs answered Alarm (not offered).
    pub alarms: usize,
    /// Epochs refused by the monitor (not offered).
    pub refused: usize,
    pub hours: f64,
    pub evaluations: u64,
    pub rejections: u64,
    /// GPS seconds of the first rejection.
    pub first_rejection_gps_s: Option<f64>,
    /// Samples taken from the first fault's onset to the first rejection,
    /// inclusive (None without a fault or a rejection).
    pub samples_to_declaration: Option<usize>,
    pub min_p_value: f64,
    /// The 99 % binomial upper bound of the false declarations.
    pub allowed_99: u64,
    pub mean_q_per_dof: f64,
}

impl ModelCheckReport {
    pub fn line(&self) -> String {
        format!(
            "model check ({}): spacing {} s, window {}, P_h {:.1e} / h, {} evaluations / h at most, p {:.3e} per evaluation; \
             {} epochs, {} answered (offered), {} alarms, {} refused, {:.2} h; \
             {} evaluations, {} rejections (99 % bound for a clean run: {}), smallest p {:.3e}; first declaration {}; \
             mean q/dof {:.3}",
            self.monitor,
            self.spacing_s,
            self.window,
            self.p_fa_per_hour,
            self.evaluations_per_hour,
            self.p_fa_per_evaluation,
            self.epochs,
            self.offered,
            self.alarms,
            self.refused,
            self.hours,
            self.evaluations,
            self.rejections,
            self.allowed_99,
            self.min_p_value,
            match (self.first_rejection_gps_s, self.samples_to_declaration) {
                (Some(t), Some(k)) => format!(
                    "{} ({k} samples after the onset)",
                    raim_gnss::time::time_of_day(t)
                ),
                (Some(t), None) => raim_gnss::time::time_of_day(t),
                _ => "none".into(),
            },
            self.mean_q_per_dof,
        )
    }
}

/// The smallest k with P(Bin(n, p) > k) <= 1 - confidence.
pub fn binomial_upper(n: u64, p: f64, confidence: f64) -> u64 {
    // P(X <= k) accumulated from k = 0 with the pmf's recurrence, in logs
    // for the first term.
    if n == 0 || p <= 0.0 {
        return 0;
    }
    let nf = n as f64;
    let mut pmf = (nf * (-p).ln_1p()).exp();
    let mut cdf = pmf;
    let mut k = 0u64;
    while cdf < confidence && k < n {
        let kf = k as f64;
        pmf *= (nf - kf) / (kf + 1.0) * p / (1.0 - p);
        cdf += pmf;
        k += 1;
    }
    k
}

/// What the run accumulates.
struct Tally {
    mc: ModelCheck<MODEL_CHECK_CAPACITY>,
    cfg: ModelCheckConfig,
    offered: usize,
    alarms: usize,
    refused: usize,
    q_sum: f64,
    dof_sum: f64,
    min_p: f64,
    onset_gps_s: Option<f64>,
    samples_from_onset: usize,
    samples_to_declaration: Option<usize>,
}

impl Tally {
    fn new(cfg: ModelCheckConfig, onset_gps_s: Option<f64>) -> Self {
        Tally {
            mc: ModelCheck::new(),
            cfg,
            offered: 0,
            alarms: 0,
            refused: 0,
            q_sum: 0.0,
            dof_sum: 0.0,
            min_p: 1.0,
            onset_gps_s,
            samples_from_onset: 0,
            samples_to_declaration: None,
        }
    }

    fn offer(&mut self, t: f64, q: f64, dof: u32) -> Result<()> {
        self.offered += 1;
        self.q_sum += q;
        self.dof_sum += f64::from(dof);
        let out = self
            .mc
            .offer(&self.cfg, t, q, dof)
            .map_err(|e| anyhow!("model check at {}: {e:?}", raim_gnss::time::time_of_day(t)))?;
        if let Offer::Evaluated(e) = out {
            self.min_p = self.min_p.min(e.p_value);
            if self.onset_gps_s.is_some_and(|t0| t >= t0 - 1e-3) {
                self.samples_from_onset += 1;
                if e.rejects && self.samples_to_declaration.is_none() {
                    self.samples_to_declaration = Some(self.samples_from_onset);
                }
            }
        }
        Ok(())
    }

    fn report(self, monitor: &'static str, s: &Setup) -> ModelCheckReport {
        let (first, last) = (
            s.epochs.first().map_or(0.0, |e| e.time_gps_s),
            s.epochs.last().map_or(0.0, |e| e.time_gps_s),
        );
        let c = self.cfg;
        ModelCheckReport {
            monitor,
            spacing_s: c.spacing_s,
            window: c.window,
            p_fa_per_hour: c.p_fa_per_hour,
            evaluations_per_hour: c.evaluations_per_hour(),
            p_fa_per_evaluation: c.p_fa_per_evaluation(),
            epochs: s.epochs.len(),
            offered: self.offered,
            alarms: self.alarms,
            refused: self.refused,
            hours: (last - first) / 3600.0,
            evaluations: self.mc.evaluations(),
            rejections: self.mc.rejections(),
            first_rejection_gps_s: self.mc.broken_at_s(),
            samples_to_declaration: self.samples_to_declaration,
            min_p_value: self.min_p,
            allowed_99: binomial_upper(self.mc.evaluations(), c.p_fa_per_evaluation(), 0.99),
            mean_q_per_dof: self.q_sum / self.dof_sum,
        }
    }
}

/// The earliest start of any injected fault (noise included), GPS s.
fn onset(s: &Setup) -> Option<f64> {
    s.plan
        .faults
        .iter()
        .map(|f| f.start_gps_s)
        .fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.min(t))))
}

/// The model check beside the snapshot monitor.
fn snapshot(s: &Setup, cfg: ModelCheckConfig) -> Result<ModelCheckReport> {
    let mut raim = Box::new(Raim::<REPLAY_CAPACITY>::new());
    let mut t = Tally::new(cfg, onset(s));
    for e in &s.epochs {
        let obs = s.observations(e);
        let ep = Epoch::ranges(e.time_gps_s, &obs, e.reference_m);
        match raim.process(&s.cfg, &ep) {
            Ok(r) => match r.model_sample() {
                Some((q, dof)) => t.offer(e.time_gps_s, q, dof)?,
                None if r.decision == Decision::Alarm => t.alarms += 1,
                None => t.refused += 1,
            },
            Err(_) => t.refused += 1,
        }
    }
    Ok(t.report("snapshot", s))
}

/// The model check beside ARAIM (the replay's host monitor and models).
fn araim(args: &ReplayArgs, s: &Setup, cfg: ModelCheckConfig) -> Result<ModelCheckReport> {
    let a = &args.araim;
    let acfg = AraimConfig::default();
    let systems = args.ranging()?.systems;
    let ism = a.ism(&systems)?;
    let mut monitor: Box<super::araim::Engine> = Box::default();
    let mut t = Tally::new(cfg, onset(s));
    for e in &s.epochs {
        let obs = s.observations(e);
        match super::araim::host_verdict(a, &s.cfg, &acfg, &ism, e, &obs, &mut monitor) {
            Ok(v) if v.decision == Decision::Alarm => t.alarms += 1,
            Ok(_) => match monitor.accuracy_sample() {
                Ok(f) => t.offer(e.time_gps_s, f.q, f.dof)?,
                Err(_) => t.refused += 1,
            },
            Err(_) => t.refused += 1,
        }
    }
    Ok(t.report("araim", s))
}

/// The run without printing (used by the tests too).
pub fn replay(args: &ReplayArgs) -> Result<ModelCheckReport> {
    let cfg = args.model_check.config();
    cfg.validate(MODEL_CHECK_CAPACITY)
        .map_err(|e| anyhow!("model check configuration: {e:?}"))?;
    let s = setup(args)?;
    if args.araim.araim {
        araim(args, &s, cfg)
    } else {
        snapshot(&s, cfg)
    }
}

pub fn run(args: &ReplayArgs, w: &mut impl Write) -> Result<()> {
    let r = replay(args)?;
    if args.json {
        writeln!(w, "{}", serde_json::json!({ "model_check": r }))?;
    } else {
        writeln!(w, "{}", r.line())?;
    }
    Ok(())
}
