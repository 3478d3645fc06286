//! The f32/f64 equivalence suite (docs/CORE.md "Precision";
//! results in docs/F32_EQUIVALENCE.md): the same epochs through
//! `Raim::<N, f32>` (the firmware's precision) and `Raim::<N, f64>` (the
//! host's), side by side in one process. Decisions, alarm causes, the
//! identified satellite and the exclusions must be identical; every
//! disagreement is listed and classified (a near-threshold tie, counted, or
//! unexplained); the statistics and the PLs must agree within the stated
//! relative tolerances. Shared by the short form (`tests/f32_equivalence.rs`,
//! in CI) and the full form (`examples/f32_equivalence.rs`).
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::PathBuf;

use raim_core::{
    Config, Decision, Epoch, EpochResult, FiRule, LinearObservation, Raim, RaimError,
    RangeObservation, SatId, System,
};
use raim_gnss::faults::FaultPlan;
use raim_gnss::ranging::{prepare_epoch, RangingOptions};
use raim_gnss::{time, NavData, ObsData};

/// Satellite capacity of both engines (ESBC has up to ~30 in G+E+C).
pub const CAP: usize = 48;

/// Relative agreement of D^2 (all-in-view and in force) between f32 and
/// f64, where both take the same decisions (dimensionless). The parity
/// study measured 5.6e-5 on ill-conditioned skies (docs/CORE.md).
pub const STAT_REL_TOL: f64 = 2e-3;
/// Absolute floor for D^2 near zero (chi-square units).
pub const STAT_ABS_TOL: f64 = 1e-4;
/// Relative agreement of HPL and VPL where the PLs are within the alert
/// limits (decisions Ok and Excluded), dimensionless. The slope's S_ii =
/// 1 - ||T1^-T h_i||^2 and gain T1^-1 T1^-T h_i carry eps x cond(H)^2 in
/// f32: ~1e-3 on ordinary skies (docs/F32_EQUIVALENCE.md).
pub const PL_REL_TOL: f64 = 1e-2;
/// The same where a PL exceeds its limit or the epoch alarms (weak
/// geometry: S_ii near `min_s_ii`, cond(H) in the hundreds).
pub const PL_REL_TOL_WEAK: f64 = 1e-1;
/// A disagreement is a near-threshold tie when the f64 quantity that
/// decides it lies within this relative distance of its threshold (or of
/// the runner-up, for identification). f32 carries ~1e-7 relative per
/// operation and the statistics ~1e-5 (eps x cond), so 1e-3 is generous.
pub const TIE_REL: f64 = 1e-3;

/// Where a disagreement comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Tie {
    /// The all-in-view D^2 within TIE_REL of T^2.
    Detection,
    /// The best two identification scores within TIE_REL.
    Identification,
    /// A subset's D^2 (after an exclusion) within TIE_REL of its T^2.
    SubsetTest,
    /// A PL within PL_REL_TOL of its alert limit.
    AlertLimit,
    /// A satellite's S_ii within a factor 10 of `min_s_ii`.
    Identifiability,
    /// None of the above.
    Unexplained,
}

/// The tally of one source of epochs.
#[derive(Debug, Default, Clone)]
pub struct Tally {
    pub name: String,
    pub epochs: usize,
    /// Epochs where both precisions returned an error (the same error).
    pub both_errors: usize,
    pub agree: usize,
    pub disagreements: Vec<(String, Tie, String)>,
    /// Largest relative D^2 and PL differences on agreeing epochs.
    pub max_stat_rel: f64,
    pub max_pl_rel: f64,
    pub max_pl_rel_weak: f64,
    /// Largest position difference, m (pseudorange input).
    pub max_position_m: f64,
    /// Count per decision (f64 run): Ok, Excluded, Unavailable, Alarm.
    pub decisions: [usize; 4],
    /// Agreeing epochs whose statistics or PLs exceeded the tolerances.
    pub out_of_tolerance: Vec<String>,
}

impl Tally {
    pub fn new(name: &str) -> Self {
        Tally {
            name: name.to_string(),
            ..Default::default()
        }
    }

    pub fn ties(&self, kind: Tie) -> usize {
        self.disagreements.iter().filter(|d| d.1 == kind).count()
    }

    pub fn merge(&mut self, o: &Tally) {
        self.epochs += o.epochs;
        self.both_errors += o.both_errors;
        self.agree += o.agree;
        self.disagreements.extend(o.disagreements.iter().cloned());
        self.max_stat_rel = self.max_stat_rel.max(o.max_stat_rel);
        self.max_pl_rel = self.max_pl_rel.max(o.max_pl_rel);
        self.max_pl_rel_weak = self.max_pl_rel_weak.max(o.max_pl_rel_weak);
        self.max_position_m = self.max_position_m.max(o.max_position_m);
        for (a, b) in self.decisions.iter_mut().zip(o.decisions) {
            *a += b;
        }
        self.out_of_tolerance
            .extend(o.out_of_tolerance.iter().cloned());
    }

    /// One Markdown table row.
    pub fn row(&self) -> String {
        format!(
            "| {} | {} | {} / {} / {} / {} | {} | {} | {} | {} | {} | {} | {:.1e} | {:.1e} | {:.1e} | {:.1e} |",
            self.name,
            self.epochs,
            self.decisions[0],
            self.decisions[1],
            self.decisions[2],
            self.decisions[3],
            self.both_errors,
            self.disagreements.len(),
            self.ties(Tie::Detection),
            self.ties(Tie::Identification) + self.ties(Tie::SubsetTest),
            self.ties(Tie::AlertLimit) + self.ties(Tie::Identifiability),
            self.ties(Tie::Unexplained),
            self.max_stat_rel,
            self.max_pl_rel,
            self.max_pl_rel_weak,
            self.max_position_m,
        )
    }
}

pub const TABLE_HEAD: &str = "| source | epochs | f64 decisions Ok / Excl / Unav / Alarm | both errors | disagreements | detection ties | identification / subset ties | alert-limit / S_ii-bound ties | unexplained | max D^2 rel | max PL rel (Ok, Excluded) | max PL rel (Unavailable, Alarm) | max position diff (m) |\n| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |";

fn decision_index(d: Decision) -> usize {
    match d {
        Decision::Ok => 0,
        Decision::Excluded => 1,
        Decision::Unavailable => 2,
        Decision::Alarm => 3,
    }
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b || (a.is_infinite() && b.is_infinite() && a.signum() == b.signum()) {
        return 0.0;
    }
    (a - b).abs() / a.abs().max(b.abs())
}

/// The verdict an epoch's result stands for: what must be identical.
fn verdict<const N: usize>(r: &EpochResult<N>) -> String {
    let ex: Vec<String> = r.exclusions.iter().map(|e| e.id.to_string()).collect();
    format!(
        "{:?} cause {:?} identified {:?} exclusions [{}] mcusum {:?}",
        r.decision,
        r.alarm_cause,
        r.identified.map(|s| s.to_string()),
        ex.join(","),
        r.mcusum
            .map(|m| (m.alarm, m.identified.map(|s| s.to_string()))),
    )
}

/// Why a disagreement is a tie (from the f64 result `r`; `a` is the f32
/// one), or Unexplained.
fn classify<const N: usize>(cfg: &Config, a: &EpochResult<N>, r: &EpochResult<N>) -> Tie {
    use raim_core::snapshot::fde::AlarmCause::Ambiguous;
    // The same two candidates named Ambiguous in the other order: their
    // statistics tie (the decision and the cause are the same).
    if matches!(
        (a.alarm_cause, r.alarm_cause),
        (Some(Ambiguous { .. }), Some(Ambiguous { .. }))
    ) && a.decision == r.decision
        && a.identified == r.identified
    {
        // The same decision, cause kind and identified satellite; the two
        // names differ: several pairs (or singles) explain the data about
        // equally (with a small dof, pairs spanning the same parity
        // subspace have the same RSS exactly), and rounding picks which
        // two are named.
        return Tie::Identification;
    }
    // dof 1, NoRedundancy on both sides: the alarm and its cause agree and
    // only the diagnostic `identified` differs. In a one-dimensional parity
    // space every w_i^2 equals D^2, so MLE ranks by rounding alone and the
    // L-RAIM score depends on S_ii alone, whose f32 error is eps x cond^2.
    use raim_core::snapshot::fde::AlarmCause::NoRedundancy;
    if a.decision == r.decision
        && a.alarm_cause == Some(NoRedundancy)
        && r.alarm_cause == Some(NoRedundancy)
    {
        return Tie::Identification;
    }
    // Ok / Excluded against Unavailable: a PL at its alert limit, or a
    // satellite's S_ii at the identifiability bound (the PL is finite on
    // one side and infinite on the other).
    let availability_only = matches!(
        (a.decision, r.decision),
        (Decision::Ok, Decision::Unavailable)
            | (Decision::Unavailable, Decision::Ok)
            | (Decision::Excluded, Decision::Unavailable)
            | (Decision::Unavailable, Decision::Excluded)
    );
    if availability_only {
        let near_val = cfg
            .alert
            .val_m
            .is_some_and(|v| rel(r.protection.vpl_m, v) < PL_REL_TOL);
        if rel(r.protection.hpl_m, cfg.alert.hal_m) < PL_REL_TOL || near_val {
            return Tie::AlertLimit;
        }
        // A satellite's S_ii at the identifiability bound (`min_s_ii`): f32
        // carries eps x cond(H)^2 on S_ii, so the bound itself is the tie,
        // and the PL is finite on one side and infinite on the other.
        let weakest = a
            .satellites
            .iter()
            .chain(r.satellites.iter())
            .filter(|s| s.used && s.s_ii.is_finite())
            .map(|s| s.s_ii)
            .fold(f64::INFINITY, f64::min);
        if weakest < 10.0 * cfg.min_s_ii {
            return Tie::Identifiability;
        }
    }
    let t = &r.initial_test;
    if rel(t.statistic, t.threshold) < TIE_REL {
        return Tie::Detection;
    }
    let mut scores: Vec<f64> = r
        .satellites
        .iter()
        .filter(|s| s.identifiable)
        .map(|s| s.score)
        .collect();
    scores.sort_by(|a, b| b.total_cmp(a));
    if scores.len() >= 2 && rel(scores[0], scores[1]) < TIE_REL {
        return Tie::Identification;
    }
    if r.exclusions
        .iter()
        .any(|e| rel(e.after.statistic, e.after.threshold) < TIE_REL)
        || rel(r.test.statistic, r.test.threshold) < TIE_REL
    {
        return Tie::SubsetTest;
    }
    // The uniqueness check (docs/CORE.md, FDE 3): an alternative subset's
    // statistic D^2 - w_j^2 within TIE_REL of the chi-square quantile at
    // 1 - pwe (dof - 1). f32 carries ~1e-4 relative on w_j^2.
    if t.dof >= 2 {
        if let Ok(t2_we) = raim_core::stats::dist::chi2_quantile_upper(cfg.pwe, t.dof - 1) {
            let near = a
                .satellites
                .iter()
                .chain(r.satellites.iter())
                .any(|s| s.identifiable && rel(t.statistic - s.w * s.w, t2_we) < TIE_REL);
            if near {
                return Tie::SubsetTest;
            }
        }
    }
    let near_val = cfg
        .alert
        .val_m
        .is_some_and(|v| rel(r.protection.vpl_m, v) < PL_REL_TOL);
    if rel(r.protection.hpl_m, cfg.alert.hal_m) < PL_REL_TOL || near_val {
        return Tie::AlertLimit;
    }
    Tie::Unexplained
}

/// The pair of engines, persistent across the epochs of one source (the
/// threshold caches and, with the MCUSUM, its state).
pub struct Pair {
    pub f32: Box<Raim<CAP, f32>>,
    pub f64: Box<Raim<CAP, f64>>,
}

impl Default for Pair {
    fn default() -> Self {
        Pair {
            f32: Box::new(Raim::new()),
            f64: Box::new(Raim::new()),
        }
    }
}

impl Pair {
    /// Run one epoch through both and tally it.
    pub fn compare(&mut self, cfg: &Config, epoch: &Epoch<'_>, label: &str, tally: &mut Tally) {
        tally.epochs += 1;
        let a = self.f32.process(cfg, epoch);
        let b = self.f64.process(cfg, epoch);
        match (a, b) {
            (Err(ea), Err(eb)) => {
                tally.both_errors += 1;
                if core::mem::discriminant(&ea) != core::mem::discriminant(&eb) {
                    tally.disagreements.push((
                        label.to_string(),
                        Tie::Unexplained,
                        format!("errors differ: f32 {ea:?}, f64 {eb:?}"),
                    ));
                }
            }
            (Ok(ra), Ok(rb)) => self.tally_results(cfg, &ra, &rb, label, tally),
            (ra, rb) => tally.disagreements.push((
                label.to_string(),
                Tie::Unexplained,
                format!(
                    "f32 {:?}, f64 {:?}",
                    ra.map(|r| verdict(&r)).map_err(|e: RaimError| e),
                    rb.map(|r| verdict(&r))
                ),
            )),
        }
    }

    fn tally_results<const N: usize>(
        &self,
        cfg: &Config,
        a: &EpochResult<N>,
        b: &EpochResult<N>,
        label: &str,
        tally: &mut Tally,
    ) {
        tally.decisions[decision_index(b.decision)] += 1;
        let (va, vb) = (verdict(a), verdict(b));
        if va != vb {
            let kind = classify(cfg, a, b);
            tally.disagreements.push((
                label.to_string(),
                kind,
                format!(
                    "f32: {va}; f64: {vb}; f64 D^2 {:.6} T^2 {:.6}, HPL {:.3} m",
                    b.initial_test.statistic, b.initial_test.threshold, b.protection.hpl_m
                ),
            ));
            return;
        }
        tally.agree += 1;
        let stat = |x: f64, y: f64| {
            if (x - y).abs() <= STAT_ABS_TOL {
                0.0
            } else {
                rel(x, y)
            }
        };
        let s = stat(a.initial_test.statistic, b.initial_test.statistic)
            .max(stat(a.test.statistic, b.test.statistic));
        let pl = rel(a.protection.hpl_m, b.protection.hpl_m)
            .max(rel(a.protection.vpl_m, b.protection.vpl_m));
        tally.max_stat_rel = tally.max_stat_rel.max(s);
        let available = matches!(b.decision, Decision::Ok | Decision::Excluded);
        let pl_tol = if available {
            tally.max_pl_rel = tally.max_pl_rel.max(pl);
            PL_REL_TOL
        } else {
            tally.max_pl_rel_weak = tally.max_pl_rel_weak.max(pl);
            PL_REL_TOL_WEAK
        };
        if let (Some(pa), Some(pb)) = (a.position_ecef_m, b.position_ecef_m) {
            let d = ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2) + (pa[2] - pb[2]).powi(2))
                .sqrt();
            tally.max_position_m = tally.max_position_m.max(d);
        }
        if s > STAT_REL_TOL || pl > pl_tol {
            tally.out_of_tolerance.push(format!(
                "{label}: D^2 rel {s:.2e}, PL rel {pl:.2e} ({:?}, HPL {} / {} m)",
                b.decision, a.protection.hpl_m, b.protection.hpl_m
            ));
        }
    }
}

// ---------------------------------------------------------------- replay

pub fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/data")
        .join(name)
}

/// The sigma model fitted to the geodetic receivers (docs/REPLAY.md).
pub fn geodetic_config() -> Config {
    let mut c = Config::default();
    c.sigma_model.ura_m = 0.3;
    c.sigma_model.iono_vertical_m = 0.5;
    c.sigma_model.noise_m = 0.2;
    c
}

/// One replay case: a data pair, its options, configuration and faults.
pub struct ReplayCase {
    pub name: &'static str,
    pub obs: &'static str,
    pub nav: &'static str,
    pub systems: Option<Vec<System>>,
    pub geodetic: bool,
    pub mcusum: bool,
    pub faults: Vec<&'static str>,
    /// Time-of-day window, or the whole file.
    pub window: Option<(&'static str, &'static str)>,
}

pub const OBS_0759: &str = "07590920.05o";
pub const NAV_0759: &str = "07590920.05n";
pub const OBS_ESBC: &str = "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz";
pub const NAV_ESBC: &str = "ESBC00DNK_R_20201770000_01D_MN.rnx.gz";
pub const OBS_GEOP: &str = "GEOP092I.24o.gz";
pub const NAV_GEOP: &str = "CORD00ARG_R_20240920000_01D_MN.rnx.gz";

/// Every replay case the full form runs (each over the whole file); the
/// short form takes windows of some of them.
pub fn replay_cases() -> Vec<ReplayCase> {
    let c = |name, obs, nav, systems, geodetic, mcusum, faults| ReplayCase {
        name,
        obs,
        nav,
        systems,
        geodetic,
        mcusum,
        faults,
        window: None,
    };
    let ge = || Some(vec![System::Gps, System::Galileo]);
    vec![
        c("0759 clean", OBS_0759, NAV_0759, None, true, false, vec![]),
        c(
            "0759 50 m G24",
            OBS_0759,
            NAV_0759,
            None,
            true,
            false,
            vec!["step:G24:50@00:20:00"],
        ),
        c(
            "0759 ramp G24 0.1 m/s",
            OBS_0759,
            NAV_0759,
            None,
            true,
            false,
            vec!["ramp:G24:0.1@00:20:00"],
        ),
        c(
            "0759 50 m G24, MCUSUM",
            OBS_0759,
            NAV_0759,
            None,
            true,
            true,
            vec!["step:G24:50@00:20:00"],
        ),
        c("ESBC clean", OBS_ESBC, NAV_ESBC, None, true, false, vec![]),
        c(
            "ESBC 20 m G15",
            OBS_ESBC,
            NAV_ESBC,
            None,
            true,
            false,
            vec!["step:G15:20@01:00:00"],
        ),
        c(
            "ESBC 50 m G15+G28",
            OBS_ESBC,
            NAV_ESBC,
            None,
            true,
            false,
            vec!["step:G15+G28:50@01:00:00"],
        ),
        c(
            "ESBC 5 m G15, MCUSUM",
            OBS_ESBC,
            NAV_ESBC,
            None,
            true,
            true,
            vec!["step:G15:5@01:00:00"],
        ),
        c(
            "GEOP G+E clean",
            OBS_GEOP,
            NAV_GEOP,
            ge(),
            false,
            false,
            vec![],
        ),
        c(
            "GEOP G+E 60 m G12 + t3 noise",
            OBS_GEOP,
            NAV_GEOP,
            ge(),
            false,
            false,
            vec!["step:G12:60@+10", "noise:all:t3:0.5"],
        ),
    ]
}

/// Replay a case through both precisions.
pub fn run_replay(case: &ReplayCase) -> Tally {
    let obs = ObsData::load(&data(case.obs)).unwrap();
    let nav = NavData::load(&data(case.nav)).unwrap();
    let first = obs.epochs[0].time_gps_s;
    let (t0, t1) = match case.window {
        Some((a, b)) => (
            time::resolve(a, first).unwrap(),
            time::resolve(b, first).unwrap(),
        ),
        None => (f64::NEG_INFINITY, f64::INFINITY),
    };
    let plan = FaultPlan {
        faults: case
            .faults
            .iter()
            .map(|f| FaultPlan::parse_cli(f, first).unwrap())
            .collect(),
        seed: 1,
    };
    let opts = RangingOptions {
        systems: case
            .systems
            .clone()
            .unwrap_or_else(|| RangingOptions::default().systems),
        ..Default::default()
    };
    let mut cfg = if case.geodetic {
        geodetic_config()
    } else {
        Config::default()
    };
    cfg.mcusum.enabled = case.mcusum;
    let mut pair = Pair::default();
    let mut tally = Tally::new(case.name);
    for e in obs
        .epochs
        .iter()
        .filter(|e| e.time_gps_s >= t0 - 0.5 && e.time_gps_s <= t1 + 0.5)
    {
        let p = prepare_epoch(&nav, e, &opts, obs.approx_position_m);
        let mut sats = p.observations();
        plan.apply(e.time_gps_s, &mut sats);
        let epoch = Epoch::ranges(e.time_gps_s, &sats, p.reference_m);
        let label = format!("{} {}", case.name, time::time_of_day(e.time_gps_s));
        pair.compare(&cfg, &epoch, &label, &mut tally);
    }
    tally
}

// ---------------------------------------------------------------- vectors

/// The committed cross-crate vectors (seed-style linearised epochs and
/// pseudorange epochs), under the default configuration and under MLE.
pub fn run_vectors() -> Tally {
    let mut tally = Tally::new("vectors (snapshot_example, ranges_example)");
    for rule in [FiRule::default(), FiRule::Mle] {
        let cfg = Config {
            rule,
            ..Config::default()
        };
        for file in ["snapshot_example.jsonl", "ranges_example.jsonl"] {
            let mut pair = Pair::default();
            for e in host_tests::read_vector(file) {
                let sats = e.sats();
                let epoch = match &sats {
                    host_tests::Sats::Ranges(v) => Epoch::ranges(e.time_s, v, e.apriori_m),
                    host_tests::Sats::Linear(v) => Epoch::linear(e.time_s, v),
                };
                let label = format!("{file} {rule:?} t={}", e.time_s);
                pair.compare(&cfg, &epoch, &label, &mut tally);
            }
        }
    }
    tally
}

// ---------------------------------------------------------- Monte Carlo

/// xorshift64*, seeded.
pub struct Rng(u64);
impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform().max(1e-300), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
    pub fn below(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n - 1)
    }
}

/// A receiver on the surface (the 0759 station).
const RX_ECEF_M: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];
const ORBIT_RADIUS_M: f64 = 26_560_000.0;

/// One Monte Carlo epoch, from its index (seeded by it, so any epoch can be
/// regenerated alone): 5-20 satellites, elevations 5-88 deg, GPS or
/// GPS + Galileo, sigmas from the elevation model (or fixed 0.5-3 m),
/// Gaussian noise, and 0, 1 or 2 faults of 0-15 sigma; one epoch in four
/// is given as pseudoranges (a-priori 0-300 m off), the rest linearised.
pub struct McEpoch {
    pub cfg: Config,
    pub linear: Vec<LinearObservation>,
    pub ranges: Vec<RangeObservation>,
    pub apriori_m: Option<[f64; 3]>,
}

pub fn mc_epoch(seed: u64, index: u64) -> McEpoch {
    let mut rng = Rng::new(seed ^ index.wrapping_mul(0xD1B5_4A32_D192_ED03));
    let n = 5 + rng.below(16);
    let two = rng.uniform() < 0.5;
    let fixed_sigma = rng.uniform() < 0.5;
    let faults = match rng.uniform() {
        u if u < 0.4 => 0,
        u if u < 0.8 => 1,
        _ => 2,
    };
    let mut cfg = Config::default();
    if rng.uniform() < 0.25 {
        cfg.rule = FiRule::Mle;
    }
    let sigma_model = cfg.sigma_model;
    let mut fault_m = vec![0.0; n];
    let mut sky = Vec::with_capacity(n);
    for i in 0..n {
        let az = rng.uniform() * std::f64::consts::TAU;
        let el = (5.0 + rng.uniform() * 83.0).to_radians();
        let sigma = if fixed_sigma {
            0.5 + 2.5 * rng.uniform()
        } else {
            sigma_model.sigma_m(el)
        };
        let system = if two && i % 2 == 1 {
            System::Galileo
        } else {
            System::Gps
        };
        sky.push((az, el, sigma, SatId::new(system, i as u8 + 1)));
    }
    for _ in 0..faults {
        let k = rng.below(n);
        fault_m[k] += rng.uniform() * 15.0 * sky[k].2;
    }
    let ranges_form = index % 4 == 3;
    let mut linear = Vec::new();
    let mut ranges = Vec::new();
    let mut apriori_m = None;
    if ranges_form {
        let g = raim_core::frames::ecef_to_geodetic(RX_ECEF_M);
        let (sl, cl, so, co) = (
            g.lat_rad.sin(),
            g.lat_rad.cos(),
            g.lon_rad.sin(),
            g.lon_rad.cos(),
        );
        let r = [
            [-so, co, 0.0],
            [-sl * co, -sl * so, cl],
            [cl * co, cl * so, sl],
        ];
        let rx = RX_ECEF_M;
        let rx_norm = rx.iter().map(|v| v * v).sum::<f64>().sqrt();
        let clock = [1234.5, -87.25];
        for (i, &(az, el, sigma, id)) in sky.iter().enumerate() {
            let enu = [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()];
            let los: Vec<f64> = (0..3)
                .map(|k| r[0][k] * enu[0] + r[1][k] * enu[1] + r[2][k] * enu[2])
                .collect();
            let b = (0..3).map(|k| rx[k] * los[k]).sum::<f64>();
            let d = -b + (b * b - rx_norm * rx_norm + ORBIT_RADIUS_M * ORBIT_RADIUS_M).sqrt();
            let pos = [rx[0] + d * los[0], rx[1] + d * los[1], rx[2] + d * los[2]];
            let c = clock[usize::from(id.system == System::Galileo)];
            ranges.push(RangeObservation {
                id,
                pseudorange_m: d + c + sigma * rng.normal() + fault_m[i],
                position_m: pos,
                sigma_m: if fixed_sigma { Some(sigma) } else { None },
            });
        }
        let off = 300.0 * rng.uniform();
        apriori_m = Some([rx[0] + off, rx[1] - 0.5 * off, rx[2] + 0.25 * off]);
    } else {
        for (i, &(az, el, sigma, id)) in sky.iter().enumerate() {
            let mut o =
                LinearObservation::from_az_el(id, az, el, sigma * rng.normal() + fault_m[i]);
            o.sigma_m = if fixed_sigma { Some(sigma) } else { None };
            linear.push(o);
        }
    }
    McEpoch {
        cfg,
        linear,
        ranges,
        apriori_m,
    }
}

/// Epochs `range` of the seeded Monte Carlo through both precisions.
pub fn run_monte_carlo(seed: u64, range: std::ops::Range<u64>) -> Tally {
    let mut tally = Tally::new(&format!(
        "Monte Carlo seed {seed}, epochs {}..{}",
        range.start, range.end
    ));
    let mut pair = Pair::default();
    for index in range {
        let e = mc_epoch(seed, index);
        let epoch = if e.ranges.is_empty() {
            Epoch::linear(index as f64, &e.linear)
        } else {
            Epoch::ranges(index as f64, &e.ranges, e.apriori_m)
        };
        let label = format!("MC seed {seed} epoch {index}");
        pair.compare(&e.cfg, &epoch, &label, &mut tally);
    }
    tally
}

/// The report: the table and every disagreement.
pub fn report(tallies: &[Tally]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{TABLE_HEAD}");
    let mut total = Tally::new("**total**");
    for t in tallies {
        let _ = writeln!(s, "{}", t.row());
        total.merge(t);
    }
    let _ = writeln!(s, "{}", total.row());
    let _ = writeln!(s, "\nDisagreements ({}):\n", total.disagreements.len());
    for (label, kind, what) in &total.disagreements {
        let _ = writeln!(s, "- {label}: {kind:?}: {what}");
    }
    let _ = writeln!(
        s,
        "\nAgreeing epochs outside the stated tolerances (D^2 {STAT_REL_TOL:e}, PL {PL_REL_TOL:e} / {PL_REL_TOL_WEAK:e} relative): {}\n",
        total.out_of_tolerance.len()
    );
    for o in &total.out_of_tolerance {
        let _ = writeln!(s, "- {o}");
    }
    s
}
