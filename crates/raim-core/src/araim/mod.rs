//! ARAIM: multiple-hypothesis solution separation per the WG-C ARAIM
//! Algorithm Description Document baseline (SPEC §9.1, seed 003).
//!
//! One call per epoch, [`Araim::process`], on the linearised form: per
//! satellite the ENU part of its geometry row (the clock column is implied
//! by its constellation), C_int and C_acc (given, or from
//! [`error_model`]), b_nom, P_sat and the range residual; per
//! constellation P_const ([`Ism`]); and the [`AraimConfig`] (LPV-200
//! defaults). It returns the fault modes with their subset statistics and
//! tests, the protection levels (exact root and the ADD's bracket output),
//! EMT, sigma_v,acc and the availability, or a typed [`AraimError`].
//!
//! - [`modes`]: fault-mode enumeration to P_THRES, nothing skipped.
//! - [`subset`]: all subsets from one factorisation (bases + downdates).
//! - [`pl`]: the PL equation, exact and ADD bracket.
//! - [`error_model`]: C_int and C_acc from the elevation.
//! - [`ism`]: the ISM, the configuration and their range checks.
//! - [`monitor`]: the whole epoch once ([`Monitor`]): the ISM join, the
//!   error model, the linearisation of pseudoranges, FDE within its
//!   budget, the decision and the excluded satellites.
//!
//! Capacity: `N` satellites (at most 64, the width of a mode's mask) and
//! `K` fault modes. A mode list that does not fit `K` makes the epoch
//! unavailable with [`Unavailable::ModeCapacity`]; it is never truncated.
//! Generic over `T: Real` (geometry, subset statistics); probabilities, the
//! K_fa quantiles and the PL search are `f64` (precision policy, `real.rs`).
//! - [`fde`]: exclusion after a detection (unique consistent candidate).

pub mod error;
pub mod error_model;
pub mod esq;
pub mod fde;
pub mod ism;
pub mod modes;
pub mod monitor;
pub mod pca;
pub mod pl;
pub mod subset;
pub mod tail;
#[cfg(test)]
pub(crate) mod tests;

pub use error::AraimError;
pub use error_model::Curves;
pub use fde::{FdeAlarm, FdeDecision};
pub use ism::{AraimConfig, AraimSat, Ism, PlOutput};
pub use modes::{ModeEvents, MAX_EVENTS};
pub use monitor::{Exclusion, FdeLimits, Monitor, MonitorError, SatIsm, SatelliteModels, Verdict};
pub use subset::SubsetStats;

use crate::measurement::{MAX_STATES, MAX_SYSTEMS};
use crate::real::Real;
use crate::stats::dist::normal_q_inv;
use heapless::Vec;
use modes::{EnumerationLimit, Events};
use subset::{Base, Deficient, Geometry};

/// Widest satellite set a mode's bit mask holds.
pub const MAX_SATS: usize = 64;

/// Whether a fault mode's subset could be solved.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModeStatus {
    /// Solved and tested; its prior enters the PL sum.
    #[default]
    Monitored,
    /// The subset is rank-deficient (`column`: the geometry column, or for
    /// a downdate the satellite index, whose pivot `pivot` collapsed); its
    /// prior is added to the unmonitored probability.
    Unmonitorable {
        /// The geometry column (or, for a downdate, the satellite index) whose pivot collapsed.
        column: usize,
        /// The pivot relative to its column norm or diagonal.
        pivot: f64,
    },
}

/// One fault mode: its events and prior, its subset statistics, the
/// thresholds T_k,q = K_fa,q sigma_ss,q and the outcome of its test.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FaultMode<T> {
    /// The satellites and constellations this mode assumes faulty, and its prior.
    pub events: ModeEvents,
    /// Whether the subset was solved.
    pub status: ModeStatus,
    /// sigma, bias, sigma_ss and separation of the subset solution per axis.
    pub stats: SubsetStats<T>,
    /// Thresholds T_k,q = K_fa,q sigma_ss,q per axis E, N, U, m.
    pub threshold_m: [T; 3],
    /// |x_q^(k) - x_q^(0)| <= T_k,q on every axis (false for NaN, and for
    /// unmonitorable modes, which have no test).
    pub passed: bool,
}

/// Why the epoch gives no ARAIM service.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Unavailable {
    /// The mode list needs `needed` entries; the engine holds `capacity`.
    ModeCapacity {
        /// Modes the epoch needs.
        needed: usize,
        /// Modes the engine holds (`K`).
        capacity: usize,
    },
    /// More than `MAX_EVENTS` simultaneous faults would have to be
    /// monitored to bring P(more faults) to P_THRES.
    TooManyEvents {
        /// P(more than `MAX_EVENTS` events) at `MAX_EVENTS`.
        p_exceed_at_max: f64,
    },
    /// The unmonitored probability (beyond N_fault,max, plus the
    /// unmonitorable modes) exceeds P_THRES.
    Unmonitored {
        /// The unmonitored probability.
        p_unmon: f64,
        /// The allocation it exceeds, P_THRES.
        p_thres: f64,
    },
    /// The PL equation of `axis` (0 E, 1 N, 2 U) could not be bracketed.
    PlNotSolved {
        /// The axis (0 E, 1 N, 2 U).
        axis: usize,
    },
    /// One or more of the LPV-200 limits fails (see `Limits`).
    Limits,
}

/// The availability limits, each true when met.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Limits {
    /// VPL <= VAL.
    pub vpl: bool,
    /// HPL <= HAL.
    pub hpl: bool,
    /// EMT <= EMT_max.
    pub emt: bool,
    /// sigma_v,acc <= its maximum.
    pub sigma_acc: bool,
}

/// Protection levels, in metres. +infinity where no level was computed
/// (the epoch stopped before step 5: enumeration limit, unmonitored
/// probability, FDE candidate tests, a PL equation not bracketed): an
/// unbounded level is never reported as 0.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ProtectionLevels {
    /// Vertical protection level, m.
    pub vpl_m: f64,
    /// Horizontal protection level, m.
    pub hpl_m: f64,
    /// The east and north roots (HPL = their root-sum-square).
    pub hpl_axes_m: [f64; 2],
}

impl ProtectionLevels {
    /// No bound: every level +infinity.
    pub const UNBOUNDED: Self = Self {
        vpl_m: f64::INFINITY,
        hpl_m: f64::INFINITY,
        hpl_axes_m: [f64::INFINITY; 2],
    };
}

impl Default for ProtectionLevels {
    /// [`Self::UNBOUNDED`]: a level not computed bounds nothing.
    fn default() -> Self {
        Self::UNBOUNDED
    }
}

/// Everything one epoch produces.
#[derive(Debug, Clone)]
pub struct AraimOutput<T, const K: usize> {
    /// The fault modes of the epoch, monitored or not.
    pub modes: Vec<FaultMode<T>, K>,
    /// Modes solved and tested (N_modes of K_fa).
    pub n_monitored: usize,
    /// N_fault,max.
    pub max_faults: usize,
    /// P(more than N_fault,max events).
    pub p_exceed: f64,
    /// p_exceed plus the priors of the unmonitorable modes.
    pub p_unmon: f64,
    /// K_fa for east, north, up.
    pub k_fa: [f64; 3],
    /// All in view: sigma_q^(0), b_q^(0) and the position correction S0 y.
    pub sigma0_m: [T; 3],
    /// All-in-view nominal bias b_q^(0) per axis E, N, U, m.
    pub bias0_m: [T; 3],
    /// All-in-view position correction S0 y, ENU, m.
    pub correction_enu_m: [T; 3],
    /// Vertical accuracy sigma_v,acc of the all-in-view solution, m.
    pub sigma_v_acc_m: T,
    /// Effective monitor threshold EMT, m.
    pub emt_m: T,
    /// The exact roots.
    pub pl_exact: ProtectionLevels,
    /// The ADD's bracket outputs at TOL_PL.
    pub pl_add: ProtectionLevels,
    /// Every monitored mode passed its solution-separation test.
    pub detection_passed: bool,
    /// Which availability limits are met.
    pub limits: Limits,
    /// None when available.
    pub unavailable: Option<Unavailable>,
}

impl<T: Real, const K: usize> Default for AraimOutput<T, K> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real, const K: usize> AraimOutput<T, K> {
    /// No epoch evaluated yet (the derived-`Default` values).
    pub const fn empty() -> Self {
        let z = T::ZERO;
        Self {
            modes: Vec::new(),
            n_monitored: 0,
            max_faults: 0,
            p_exceed: 0.0,
            p_unmon: 0.0,
            k_fa: [0.0; 3],
            sigma0_m: [z; 3],
            bias0_m: [z; 3],
            correction_enu_m: [z; 3],
            sigma_v_acc_m: z,
            emt_m: z,
            pl_exact: ProtectionLevels::UNBOUNDED,
            pl_add: ProtectionLevels::UNBOUNDED,
            detection_passed: false,
            limits: Limits::NONE,
            unavailable: None,
        }
    }
}

impl<T: Real, const K: usize> AraimOutput<T, K> {
    /// Every field to its default, the mode list emptied in place.
    fn reset(&mut self) {
        let z = T::of(0.0);
        self.modes.clear();
        self.n_monitored = 0;
        self.max_faults = 0;
        self.p_exceed = 0.0;
        self.p_unmon = 0.0;
        self.k_fa = [0.0; 3];
        self.sigma0_m = [z; 3];
        self.bias0_m = [z; 3];
        self.correction_enu_m = [z; 3];
        self.sigma_v_acc_m = z;
        self.emt_m = z;
        self.pl_exact = ProtectionLevels::default();
        self.pl_add = ProtectionLevels::default();
        self.detection_passed = false;
        self.limits = Limits::default();
        self.unavailable = None;
    }

    /// ARAIM service: no structural cause and every limit met.
    pub fn available(&self) -> bool {
        self.unavailable.is_none()
    }

    /// The epoch's one verdict, for a user of the position: `Alarm` when a
    /// monitored mode failed its solution-separation test (whatever the
    /// availability), `Unavailable` when the test passed but the service
    /// is not available, `Ok` otherwise. `available()` alone is the
    /// service availability and must not be read as "all clear".
    pub fn decision(&self) -> crate::result::Decision {
        use crate::result::Decision;
        if !self.detection_passed {
            Decision::Alarm
        } else if !self.available() {
            Decision::Unavailable
        } else {
            Decision::Ok
        }
    }
}

/// The ARAIM engine: `N` satellites, `K` fault modes, precision `T`. It
/// owns its scratch and its output, so one epoch allocates nothing.
pub struct Araim<T, const N: usize, const K: usize> {
    geo: Geometry<T, N>,
    s0: [[T; N]; 3],
    base0: Base<T, N>,
    /// What the all-in-view base's downdates read (subset::Coupling).
    coupled: subset::Coupling<T, N>,
    const_bases: [Base<T, N>; MAX_SYSTEMS],
    const_status: [Option<Deficient>; MAX_SYSTEMS],
    scratch: Base<T, N>,
    events: Vec<ModeEvents, K>,
    /// The PL search's active terms (pl.rs, the fold).
    pl_terms: [pl::Active; K],
    /// The PL search's quantile memos (horizontal, vertical), kept across
    /// epochs (pl.rs, `BracketCache`: each answers only for its own
    /// right-hand side and mode count).
    pl_quantiles: [pl::BracketCache; 2],
    /// The false-alert multipliers' memo: (P_FA,H, P_FA,V, modes) and
    /// Q^-1(P_FA,H / 4 n), Q^-1(P_FA,V / 2 n), None where undefined.
    k_fa_memo: KfaMemo,
    out: AraimOutput<T, K>,
    budget_share: f64,
}

impl<T: Real, const N: usize, const K: usize> Default for Araim<T, N, K> {
    fn default() -> Self {
        Self::new()
    }
}

fn bit(i: usize) -> u64 {
    if i < 64 {
        1u64 << i
    } else {
        0
    }
}

/// The memo of [`k_fa`]: its key (P_FA,H and P_FA,V bits, modes) and answer.
type KfaMemo = Option<((u64, u64, usize), [Option<f64>; 2])>;

/// Q^-1(P_FA,H / 4 n) and Q^-1(P_FA,V / 2 n) for n modes (SPEC
/// ARAIM thresholds), memoised: the same configuration and mode count
/// as the last epoch costs no quantile.
fn k_fa(memo: &mut KfaMemo, cfg: &AraimConfig, n: usize) -> [Option<f64>; 2] {
    let key = (cfg.pfa_hor.to_bits(), cfg.pfa_vert.to_bits(), n);
    if let Some((k, v)) = *memo {
        if k == key {
            return v;
        }
    }
    let nm = n as f64;
    let v = [
        normal_q_inv(cfg.pfa_hor / (4.0 * nm)).ok(),
        normal_q_inv(cfg.pfa_vert / (2.0 * nm)).ok(),
    ];
    *memo = Some((key, v));
    v
}

impl<T: Real, const N: usize, const K: usize> Araim<T, N, K> {
    /// An engine with empty outputs, ready for its first epoch (`const`:
    /// a device builds it in place in a static).
    pub const fn new() -> Self {
        Self {
            geo: Geometry::empty(),
            s0: [[T::ZERO; N]; 3],
            base0: Base::empty(),
            coupled: subset::Coupling::empty(),
            const_bases: [Base::empty(); MAX_SYSTEMS],
            const_status: [None; MAX_SYSTEMS],
            scratch: Base::empty(),
            events: Vec::new(),
            pl_terms: [pl::Active::ZERO; K],
            pl_quantiles: [pl::BracketCache::new(0.0, 0); 2],
            k_fa_memo: None,
            out: AraimOutput::empty(),
            budget_share: 1.0,
        }
    }

    /// Validates the inputs (every ISM and configuration field, NaN,
    /// duplicates, capacity, constellations) and builds the geometry.
    fn load(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
    ) -> Result<(), AraimError> {
        cfg.validate()?;
        ism.validate()?;
        let capacity = N.min(MAX_SATS);
        if sats.len() > capacity {
            return Err(AraimError::CapacityExceeded {
                have: sats.len(),
                capacity,
            });
        }
        for (i, s) in sats.iter().enumerate() {
            s.validate(i)?;
            if ism
                .p_const
                .get(s.id.system.index())
                .copied()
                .flatten()
                .is_none()
            {
                return Err(AraimError::MissingConstellationIsm {
                    system: s.id.system,
                    index: i,
                });
            }
            if let Some(j) = sats.iter().take(i).position(|o| o.id == s.id) {
                return Err(AraimError::DuplicateSatellite {
                    system: s.id.system,
                    prn: s.id.prn,
                    first: j,
                    second: i,
                });
            }
        }
        // One clock column per constellation in use, in System::ALL order.
        let mut col_of = [0usize; MAX_SYSTEMS];
        let mut m = 3;
        for (j, p) in ism.p_const.iter().enumerate() {
            if p.is_some() {
                let system = crate::measurement::System::ALL
                    .get(j)
                    .copied()
                    .unwrap_or_default();
                if !sats.iter().any(|s| s.id.system.index() == j) {
                    return Err(AraimError::EmptyConstellation { system });
                }
                if let Some(c) = col_of.get_mut(j) {
                    *c = m;
                }
                m += 1;
            }
        }
        if sats.len() < m {
            return Err(AraimError::TooFewSatellites {
                have: sats.len(),
                need: m,
            });
        }
        let zero = T::of(0.0);
        let geo = &mut self.geo;
        geo.n = sats.len();
        geo.m = m;
        for (i, s) in sats.iter().enumerate() {
            let col = col_of.get(s.id.system.index()).copied().unwrap_or(3);
            if let Some(g) = geo.g.get_mut(i) {
                *g = [zero; MAX_STATES];
                for (x, v) in g.iter_mut().zip(s.g_enu.iter()) {
                    *x = *v;
                }
                if let Some(x) = g.get_mut(col) {
                    *x = T::of(1.0);
                }
            }
            if let Some(x) = geo.col.get_mut(i) {
                *x = col;
            }
            if let Some(x) = geo.w.get_mut(i) {
                *x = T::of(1.0) / s.c_int_m2;
            }
            if let Some(x) = geo.c_int.get_mut(i) {
                *x = s.c_int_m2;
            }
            if let Some(x) = geo.c_acc.get_mut(i) {
                *x = s.c_acc_m2;
            }
            if let Some(x) = geo.b_nom.get_mut(i) {
                *x = s.b_nom_m;
            }
            if let Some(x) = geo.y.get_mut(i) {
                *x = s.residual_m;
            }
        }
        Ok(())
    }

    /// Processes one epoch (SPEC §9.1 steps 1-6).
    ///
    /// # Errors
    /// A typed [`AraimError`] for invalid input or a singular all-in-view
    /// geometry. A valid epoch without service is `Ok` with
    /// `unavailable` set.
    pub fn process(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
    ) -> Result<&AraimOutput<T, K>, AraimError> {
        self.process_scaled(cfg, ism, sats, 1.0)
    }

    /// The share of the integrity budget the last `process` gave its PL
    /// equations: 1 for an epoch, 1 / N_ex for the subset after an
    /// exclusion (fde.rs, the exclusion risk).
    pub fn integrity_budget_share(&self) -> f64 {
        self.budget_share
    }

    /// `process` with the right-hand side of the PL equations (step 5)
    /// multiplied by `budget_share` in (0, 1] (fde.rs).
    pub(crate) fn process_scaled(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        budget_share: f64,
    ) -> Result<&AraimOutput<T, K>, AraimError> {
        self.process_impl(cfg, ism, sats, budget_share, true)
    }

    /// Steps 1-4 only (modes, subsets, tests, EMT): the FDE's consistency
    /// check of a candidate needs no PLs. The output is marked
    /// `PlNotSolved { axis: 0 }` (never read as available).
    pub(crate) fn process_tests_only(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
    ) -> Result<&AraimOutput<T, K>, AraimError> {
        self.process_impl(cfg, ism, sats, 1.0, false)
    }

    fn process_impl(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        budget_share: f64,
        with_pls: bool,
    ) -> Result<&AraimOutput<T, K>, AraimError> {
        self.budget_share = budget_share;
        self.load(cfg, ism, sats)?;
        let zero = T::of(0.0);
        let n = self.geo.n;
        // In place: `AraimOutput::default()` would build and copy the
        // whole K-mode list.
        self.out.reset();

        // Step 2: all in view.
        let zeros = [[zero; N]; 3];
        subset::factor(&self.geo, 0, 0, &zeros, &mut self.base0).map_err(|d| {
            AraimError::RankDeficient {
                column: d.column,
                pivot: d.pivot,
            }
        })?;
        self.s0 = self.base0.d;
        self.base0.d = zeros;
        subset::pack(&self.geo, &self.s0, &mut self.base0);
        subset::coupling(&self.geo, &self.base0, &self.s0, &mut self.coupled);
        let out = &mut self.out;
        for q in 0..3 {
            let row = self.s0.get(q).copied().unwrap_or([zero; N]);
            let var = self
                .base0
                .p
                .get(q)
                .and_then(|r| r.get(q))
                .copied()
                .unwrap_or(zero);
            let mut b = zero;
            let mut x = zero;
            for (i, s) in row.iter().enumerate().take(n) {
                b += s.abs() * self.geo.b_nom.get(i).copied().unwrap_or(zero);
                x += *s * self.geo.y.get(i).copied().unwrap_or(zero);
            }
            if let (Some(a), Some(bb), Some(c)) = (
                out.sigma0_m.get_mut(q),
                out.bias0_m.get_mut(q),
                out.correction_enu_m.get_mut(q),
            ) {
                *a = var.sqrt();
                *bb = b;
                *c = x;
            }
        }
        let mut acc = zero;
        if let Some(row) = self.s0.get(2) {
            for (i, s) in row.iter().enumerate().take(n) {
                acc += *s * *s * self.geo.c_acc.get(i).copied().unwrap_or(zero);
            }
        }
        out.sigma_v_acc_m = acc.sqrt();

        // Constellation bases: clock column dropped.
        let mut const_sats = [0u64; MAX_SYSTEMS];
        for (i, s) in sats.iter().enumerate() {
            if let Some(x) = const_sats.get_mut(s.id.system.index()) {
                *x |= bit(i);
            }
        }
        let mut const_cols = [0u16; MAX_SYSTEMS];
        for (j, p) in ism.p_const.iter().enumerate() {
            if p.is_none() {
                continue;
            }
            let removed = const_sats.get(j).copied().unwrap_or(0);
            let col = sats
                .iter()
                .zip(self.geo.col.iter())
                .find(|(s, _)| s.id.system.index() == j)
                .map(|(_, c)| *c)
                .unwrap_or(0);
            let dropped = 1u16 << col;
            if let Some(x) = const_cols.get_mut(j) {
                *x = dropped;
            }
            if let (Some(base), Some(st)) =
                (self.const_bases.get_mut(j), self.const_status.get_mut(j))
            {
                *st = subset::factor(&self.geo, removed, dropped, &self.s0, base).err();
                subset::pack(&self.geo, &self.s0, base);
            }
        }

        // Step 1: the fault modes.
        let mut p_sat = [0.0f64; MAX_SATS];
        let mut sat_system = [0u8; MAX_SATS];
        for (i, s) in sats.iter().enumerate() {
            if let (Some(p), Some(sys)) = (p_sat.get_mut(i), sat_system.get_mut(i)) {
                *p = s.p_sat;
                *sys = s.id.system.index() as u8;
            }
        }
        let mut p_const: Vec<(u8, f64), MAX_SYSTEMS> = Vec::new();
        for (j, p) in ism.p_const.iter().enumerate() {
            if let Some(p) = *p {
                let _ = p_const.push((j as u8, p));
            }
        }
        let events = Events {
            p_sat: p_sat.get(..n).unwrap_or(&[]),
            sat_system: sat_system.get(..n).unwrap_or(&[]),
            p_const: &p_const,
        };
        let enumeration = match modes::enumerate(&events, cfg.p_thres, &mut self.events) {
            Ok(e) => e,
            Err(limit) => {
                out.unavailable = Some(match limit {
                    EnumerationLimit::TooManyEvents { p_exceed_at_max } => {
                        Unavailable::TooManyEvents { p_exceed_at_max }
                    }
                    EnumerationLimit::Capacity { needed, capacity } => {
                        Unavailable::ModeCapacity { needed, capacity }
                    }
                });
                return Ok(&self.out);
            }
        };
        out.max_faults = enumeration.max_faults;
        out.p_exceed = enumeration.p_exceed;

        // Step 3: per mode, from its base.
        let mut p_unmon = enumeration.p_exceed;
        // Tests only (FDE candidates): a mode whose separation exceeds the
        // threshold at K_fa for *all* the enumerated modes (>= the
        // monitored ones, so that K_fa is at least the true one) fails its
        // test whatever the rest: the subset is inconsistent, stop there.
        let k_upper = if with_pls {
            [zero; 3]
        } else {
            let [kh, kv] = k_fa(&mut self.k_fa_memo, cfg, self.events.len().max(1));
            let (kh, kv) = (kh.unwrap_or(f64::INFINITY), kv.unwrap_or(f64::INFINITY));
            [T::of(kh), T::of(kh), T::of(kv)]
        };
        for ev in self.events.iter() {
            let mut consts = ev.consts;
            for (j, &cs) in const_sats.iter().enumerate() {
                if cs != 0 && cs & ev.sats == cs {
                    consts |= 1u8 << j;
                }
            }
            let mut removed = 0u64;
            let mut dropped = 0u16;
            let mut count = 0;
            let mut single = 0usize;
            for j in 0..MAX_SYSTEMS {
                if consts & (1u8 << j) != 0 {
                    removed |= const_sats.get(j).copied().unwrap_or(0);
                    dropped |= const_cols.get(j).copied().unwrap_or(0);
                    count += 1;
                    single = j;
                }
            }
            let extra = ev.sats & !removed;
            let result = match count {
                0 => {
                    subset::downdate_coupled(&self.geo, &self.base0, extra, Some(&mut self.coupled))
                }
                1 => match self.const_status.get(single).copied().flatten() {
                    Some(d) => Err(d),
                    None => match self.const_bases.get(single) {
                        Some(base) => subset::downdate(&self.geo, base, extra),
                        None => Err(Deficient {
                            column: 0,
                            pivot: 0.0,
                        }),
                    },
                },
                _ => subset::factor(&self.geo, removed, dropped, &self.s0, &mut self.scratch)
                    .and_then(|()| {
                        subset::pack(&self.geo, &self.s0, &mut self.scratch);
                        subset::downdate(&self.geo, &self.scratch, extra)
                    }),
            };
            let mode = match result {
                Ok(stats) => FaultMode {
                    events: *ev,
                    status: ModeStatus::Monitored,
                    stats,
                    threshold_m: [zero; 3],
                    passed: false,
                },
                Err(d) => {
                    p_unmon += ev.prior;
                    FaultMode {
                        events: *ev,
                        status: ModeStatus::Unmonitorable {
                            column: d.column,
                            pivot: d.pivot,
                        },
                        ..FaultMode::default()
                    }
                }
            };
            let certain_failure = !with_pls
                && mode.status == ModeStatus::Monitored
                && (0..3).any(|q| {
                    let sep = mode.stats.separation_m.get(q).copied().unwrap_or(zero);
                    let ss = mode.stats.sigma_ss_m.get(q).copied().unwrap_or(zero);
                    sep.abs() > k_upper.get(q).copied().unwrap_or(zero) * ss
                });
            // Cannot fail: `events` and `modes` share the capacity K.
            let _ = out.modes.push(mode);
            if certain_failure {
                out.detection_passed = false;
                out.unavailable = Some(Unavailable::PlNotSolved { axis: 0 });
                return Ok(&self.out);
            }
        }
        out.p_unmon = p_unmon;
        let n_mon = out
            .modes
            .iter()
            .filter(|m| m.status == ModeStatus::Monitored)
            .count();
        out.n_monitored = n_mon;

        // Step 4: thresholds and the solution-separation tests.
        if n_mon > 0 {
            let [kh, kv] = k_fa(&mut self.k_fa_memo, cfg, n_mon);
            let (kh, kv) = (kh.unwrap_or(f64::NAN), kv.unwrap_or(f64::NAN));
            out.k_fa = [kh, kh, kv];
        }
        let k_fa = [T::of(out.k_fa[0]), T::of(out.k_fa[1]), T::of(out.k_fa[2])];
        let mut all_passed = true;
        let mut emt = zero;
        for mode in out.modes.iter_mut() {
            if mode.status != ModeStatus::Monitored {
                continue;
            }
            let mut passed = true;
            for q in 0..3 {
                let k = k_fa.get(q).copied().unwrap_or(zero);
                let t = k * mode.stats.sigma_ss_m.get(q).copied().unwrap_or(zero);
                if let Some(x) = mode.threshold_m.get_mut(q) {
                    *x = t;
                }
                let sep = mode.stats.separation_m.get(q).copied().unwrap_or(zero);
                if !(sep.abs() <= t) {
                    passed = false;
                }
            }
            mode.passed = passed;
            all_passed &= passed;
            // Step 6: EMT over the modes with p_k >= P_EMT.
            if mode.events.prior >= cfg.p_emt && mode.threshold_m[2] > emt {
                emt = mode.threshold_m[2];
            }
        }
        out.detection_passed = all_passed;
        out.emt_m = emt;

        if p_unmon > cfg.p_thres {
            out.unavailable = Some(Unavailable::Unmonitored {
                p_unmon,
                p_thres: cfg.p_thres,
            });
            return Ok(&self.out);
        }
        if !with_pls {
            out.unavailable = Some(Unavailable::PlNotSolved { axis: 0 });
            return Ok(&self.out);
        }

        // Step 5: protection levels.
        let factor = 1.0 - p_unmon / (cfg.phmi_vert + cfg.phmi_hor);
        // One bracket memo for east and north (same rhs and priors).
        let [horizontal, vertical] = &mut self.pl_quantiles;
        let mut exact = [0.0f64; 3];
        let mut add = [0.0f64; 3];
        for q in 0..3 {
            let rhs = budget_share
                * if q == 2 {
                    cfg.phmi_vert * factor
                } else {
                    0.5 * cfg.phmi_hor * factor
                };
            let modes = &out.modes;
            let eq = pl::Equation {
                fault_free: pl::Term {
                    p: 2.0,
                    offset_m: out.bias0_m.get(q).copied().unwrap_or(zero).to_f64(),
                    sigma_m: out.sigma0_m.get(q).copied().unwrap_or(zero).to_f64(),
                },
                modes: || {
                    modes
                        .iter()
                        .filter(|m| m.status == ModeStatus::Monitored)
                        .map(move |m| pl::Term {
                            p: m.events.prior,
                            offset_m: (m.threshold_m.get(q).copied().unwrap_or(zero)
                                + m.stats.bias_m.get(q).copied().unwrap_or(zero))
                            .to_f64(),
                            sigma_m: m.stats.sigma_m.get(q).copied().unwrap_or(zero).to_f64(),
                        })
                },
                n_modes: n_mon,
                rhs,
            };
            let cache = if q == 2 {
                &mut *vertical
            } else {
                &mut *horizontal
            };
            match eq.solve_cached(cfg.tol_pl_m, cache, &mut self.pl_terms) {
                Some(s) => {
                    if let (Some(e), Some(a)) = (exact.get_mut(q), add.get_mut(q)) {
                        *e = s.exact_m;
                        *a = s.add_m;
                    }
                }
                None => {
                    out.unavailable = Some(Unavailable::PlNotSolved { axis: q });
                    return Ok(&self.out);
                }
            }
        }
        let [e0, e1, e2] = exact;
        let [a0, a1, a2] = add;
        out.pl_exact = ProtectionLevels {
            vpl_m: e2,
            hpl_m: libm::hypot(e0, e1),
            hpl_axes_m: [e0, e1],
        };
        out.pl_add = ProtectionLevels {
            vpl_m: a2,
            hpl_m: libm::hypot(a0, a1),
            hpl_axes_m: [a0, a1],
        };
        let pl = match cfg.pl_output {
            PlOutput::AddBracket => out.pl_add,
            PlOutput::Exact => out.pl_exact,
        };
        out.limits = Limits {
            vpl: pl.vpl_m <= cfg.val_m,
            hpl: pl.hpl_m <= cfg.hal_m,
            emt: emt.to_f64() <= cfg.emt_max_m,
            sigma_acc: out.sigma_v_acc_m.to_f64() <= cfg.sigma_acc_max_m,
        };
        let l = out.limits;
        if !(l.vpl && l.hpl && l.emt && l.sigma_acc) {
            out.unavailable = Some(Unavailable::Limits);
        }
        Ok(&self.out)
    }
}

impl Limits {
    /// No limit met (the derived `Default`), for `const fn` constructors.
    pub const NONE: Self = Limits {
        vpl: false,
        hpl: false,
        emt: false,
        sigma_acc: false,
    };
}
