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

pub mod adjusted;
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

pub use adjusted::Estimator;
pub use error::AraimError;
pub use error_model::Curves;
pub use fde::{FdeAlarm, FdeDecision};
pub use ism::{AraimConfig, AraimSat, Ism, PlOutput};
pub use modes::{ModeEvents, MAX_EVENTS};
pub use monitor::{
    Decided, Exclusion, FdeLimits, FdeScratch, Monitor, MonitorCore, MonitorError, Runs, SatIsm,
    SatelliteModels, Verdict,
};
pub use subset::SubsetStats;

use crate::measurement::{System, MAX_STATES, MAX_SYSTEMS};
use crate::real::Real;
use crate::stats::dist::normal_q_inv;
use core::ops::ControlFlow;
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

/// Which availability criteria a service level judges (SPEC §14,
/// docs/AVAILABILITY.md "Service levels"). The core computes every level
/// whatever the criteria; a horizontal-only level just does not judge the
/// vertical ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Criteria {
    /// LPV (ADD v3.0): VPL <= VAL, HPL <= HAL, EMT <= EMT_max and
    /// sigma_v,acc <= its maximum.
    #[default]
    Vertical,
    /// H-ARAIM (en route to non-precision approach, HAL only): HPL <= HAL;
    /// VAL, EMT and sigma_v,acc are not judged.
    HorizontalOnly,
}

impl Limits {
    /// The limits `criteria` judges are all met.
    pub fn met(&self, criteria: Criteria) -> bool {
        match criteria {
            Criteria::Vertical => self.vpl && self.hpl && self.emt && self.sigma_acc,
            Criteria::HorizontalOnly => self.hpl,
        }
    }
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
    /// The adjusted estimator's t per axis E, N, U ([`adjusted`]) when
    /// its output is the one in force; all 0 for the weighted least
    /// squares of step 2.
    pub adjusted_t: [f64; 3],
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
            adjusted_t: [0.0; 3],
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
        self.adjusted_t = [0.0; 3];
    }

    /// ARAIM service: no structural cause and every limit met.
    pub fn available(&self) -> bool {
        self.unavailable.is_none()
    }

    /// ARAIM service under `criteria`: no structural cause (mode capacity,
    /// events, unmonitored probability, a PL not bracketed: unavailable
    /// whatever the criteria) and the limits `criteria` judges met.
    /// `available_for(Criteria::Vertical)` is [`Self::available`].
    pub fn available_for(&self, criteria: Criteria) -> bool {
        match self.unavailable {
            None => true,
            Some(Unavailable::Limits) => self.limits.met(criteria),
            Some(_) => false,
        }
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
    /// The all-in-view estimator ([`Estimator`]; the weighted least
    /// squares unless set).
    estimator: Estimator,
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
            estimator: Estimator::AllInView,
        }
    }

    /// Validates the inputs (every ISM and configuration field, NaN,
    /// duplicates, capacity, constellations) and builds the geometry: after
    /// it, `sats.len() = geo.n <= min(N, MAX_SATS)` and every constellation
    /// of the ISM has a satellite and one clock column.
    fn load(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
    ) -> Result<Constellations, AraimError> {
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
            if s.id.system.entry(&ism.p_const).is_none() {
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
        let mut layout = Constellations {
            sats: [0; MAX_SYSTEMS],
            clock_column: [0; MAX_SYSTEMS],
        };
        let mut m = 3;
        for (((&system, p), col), dropped) in System::ALL
            .iter()
            .zip(ism.p_const.iter())
            .zip(col_of.iter_mut())
            .zip(layout.clock_column.iter_mut())
        {
            if p.is_some() {
                if !sats.iter().any(|s| s.id.system == system) {
                    return Err(AraimError::EmptyConstellation { system });
                }
                *col = m;
                *dropped = 1u16 << m;
                m += 1;
            }
        }
        if sats.len() < m {
            return Err(AraimError::TooFewSatellites {
                have: sats.len(),
                need: m,
            });
        }
        let (zero, one) = (T::of(0.0), T::of(1.0));
        let geo = &mut self.geo;
        geo.n = sats.len();
        geo.m = m;
        let rows = geo
            .g
            .iter_mut()
            .zip(geo.col.iter_mut())
            .zip(geo.w.iter_mut().zip(geo.c_int.iter_mut()))
            .zip(geo.c_acc.iter_mut().zip(geo.b_nom.iter_mut()))
            .zip(geo.y.iter_mut());
        for (i, (((((g, col), (w, c_int)), (c_acc, b_nom)), y), s)) in rows.zip(sats).enumerate() {
            let clock = *s.id.system.entry(&col_of);
            // G row: ENU, then the one-hot clock column of its constellation.
            *g = [zero; MAX_STATES];
            for (x, v) in g.iter_mut().zip(s.g_enu.iter()) {
                *x = *v;
            }
            // In range: a clock column is 3 + the number of constellations
            // before it, < 3 + MAX_SYSTEMS = MAX_STATES.
            if let Some(x) = g.get_mut(clock) {
                *x = one;
            }
            *col = clock;
            *w = one / s.c_int_m2;
            *c_int = s.c_int_m2;
            *c_acc = s.c_acc_m2;
            *b_nom = s.b_nom_m;
            *y = s.residual_m;
            *s.id.system.entry_mut(&mut layout.sats) |= bit(i);
        }
        Ok(layout)
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

    /// The geometry of the last epoch processed (rows, C_acc, residuals):
    /// what the model check's accuracy fit reads
    /// ([`crate::consistency::fit::accuracy_fit`]).
    pub fn geometry(&self) -> &Geometry<T, N> {
        &self.geo
    }

    /// The share of the integrity budget the last `process` gave its PL
    /// equations: 1 for an epoch, 1 / N_ex for the subset after an
    /// exclusion (fde.rs, the exclusion risk).
    pub fn integrity_budget_share(&self) -> f64 {
        self.budget_share
    }

    /// Sets the all-in-view estimator of every later epoch ([`Estimator`],
    /// module [`adjusted`]); an FDE's or an exclusion's subsets, processed
    /// in a scratch engine, take this engine's.
    ///
    /// # Errors
    /// [`AraimError::OutOfRange`] for an accuracy limit outside the
    /// operational bound of `sigma_acc_max_m`; the estimator is then
    /// unchanged.
    pub fn set_estimator(&mut self, estimator: Estimator) -> Result<(), AraimError> {
        estimator.validate()?;
        self.estimator = estimator;
        Ok(())
    }

    /// The all-in-view estimator in use.
    pub fn estimator(&self) -> Estimator {
        self.estimator
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

    /// The epoch ([`Self::plain`]), then, with the PLs and the
    /// [`Estimator::Adjusted`] estimator, the adjusted estimator where it
    /// applies ([`adjusted`]): kept when it lowers the VPL or the HPL,
    /// else the plain epoch processed again (the same bits as without the
    /// attempt).
    fn process_impl(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        budget_share: f64,
        with_pls: bool,
    ) -> Result<&AraimOutput<T, K>, AraimError> {
        let layout = self.plain(cfg, ism, sats, budget_share, with_pls)?;
        // Not even entered with the plain estimator (the device's case):
        // its frame holds three gain rows.
        let adjusting = matches!(self.estimator, Estimator::Adjusted { .. });
        if with_pls && adjusting && self.adjust(cfg, &layout) == adjusted::Attempt::Dirty {
            self.plain(cfg, ism, sats, budget_share, with_pls)?;
        }
        Ok(&self.out)
    }

    /// The epoch in the ADD's order: the all-in-view solution and the
    /// constellation bases (step 2), the modes (step 1), their subsets
    /// (step 3), the tests and EMT (steps 4 and 6), then, unless the
    /// unmonitored probability already denies service, the protection
    /// levels (step 5) and the availability limits. Each step that ends
    /// the epoch early leaves its cause in `out.unavailable`. Returns the
    /// constellation layout.
    fn plain(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        budget_share: f64,
        with_pls: bool,
    ) -> Result<Constellations, AraimError> {
        self.budget_share = budget_share;
        let layout = self.load(cfg, ism, sats)?;
        // In place: `AraimOutput::default()` would build and copy the
        // whole K-mode list.
        self.out.reset();
        self.all_in_view()?;
        self.constellation_bases(ism, &layout);
        let Some(p_exceed) = self.fault_modes(cfg, ism, sats) else {
            return Ok(layout);
        };
        if self
            .subset_modes(cfg, &layout, p_exceed, with_pls)
            .is_break()
        {
            return Ok(layout);
        }
        self.separation_tests(cfg);
        let p_unmon = self.out.p_unmon;
        if p_unmon > cfg.p_thres {
            self.out.unavailable = Some(Unavailable::Unmonitored {
                p_unmon,
                p_thres: cfg.p_thres,
            });
            return Ok(layout);
        }
        if !with_pls {
            self.out.unavailable = Some(Unavailable::PlNotSolved { axis: 0 });
            return Ok(layout);
        }
        if let Err(axis) = self.protection_levels(cfg, budget_share) {
            self.out.unavailable = Some(Unavailable::PlNotSolved { axis });
            return Ok(layout);
        }
        self.availability(cfg);
        Ok(layout)
    }

    /// Step 2, all in view: P0 = (G^T W G)^-1 and S^(0) = P0 G^T W
    /// (`subset::factor`), then per axis q sigma_q^(0) = sqrt((P0)_qq)
    /// (= sqrt(sum_i S_qi^2 C_int,ii)), b_q^(0) = sum_i |S_qi| b_nom,i and
    /// the correction sum_i S_qi y_i; and step 6's sigma_v,acc =
    /// sqrt(sum_i S_3i^2 C_acc,ii). Fills what every mode's downdate reads
    /// (the all-in-view base, its packed rows and coupling).
    fn all_in_view(&mut self) -> Result<(), AraimError> {
        let zeros = [[T::of(0.0); N]; 3];
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
        let geo = &self.geo;
        let out = &mut self.out;
        // MAX_STATES >= 3: the position block of P0 is its first three rows.
        let [p_e, p_n, p_u, ..] = &self.base0.p;
        let variance = [p_e[0], p_n[1], p_u[2]];
        let axes = self
            .s0
            .iter()
            .zip(variance)
            .zip(out.sigma0_m.iter_mut())
            .zip(out.bias0_m.iter_mut().zip(out.correction_enu_m.iter_mut()));
        for (((row, var), sigma), (bias, correction)) in axes {
            *sigma = var.sqrt();
            (*bias, *correction) = nominal_bias_and_correction(geo, row);
        }
        let [_, _, s_up] = &self.s0;
        out.sigma_v_acc_m = accuracy_sigma(geo, s_up);
        Ok(())
    }

    /// Step 3's constellation bases: per constellation of the ISM, the
    /// subset without its satellites and its clock column, factored once;
    /// every mode that removes that constellation downdates it. A singular
    /// base is kept as its [`Deficient`] (those modes are unmonitorable).
    fn constellation_bases(&mut self, ism: &Ism, layout: &Constellations) {
        let per_system = ism
            .p_const
            .iter()
            .zip(layout.sats.iter().zip(layout.clock_column.iter()))
            .zip(
                self.const_bases
                    .iter_mut()
                    .zip(self.const_status.iter_mut()),
            );
        for ((p, (&removed, &dropped)), (base, status)) in per_system {
            if p.is_none() {
                continue;
            }
            *status = subset::factor(&self.geo, removed, dropped, &self.s0, base).err();
            subset::pack(&self.geo, &self.s0, base);
        }
    }

    /// Step 1, the fault modes: every combination of at most N_fault,max
    /// satellite and constellation events, N_fault,max the smallest r with
    /// P(more than r events) <= P_THRES (`modes::enumerate`), into
    /// `self.events`. Returns P(more than N_fault,max events); None, with
    /// the cause in `out.unavailable`, when the list cannot be built.
    fn fault_modes(&mut self, cfg: &AraimConfig, ism: &Ism, sats: &[AraimSat<T>]) -> Option<f64> {
        // `load` bounds sats.len() by MAX_SATS: the zips below keep them all.
        let mut p_sat = [0.0f64; MAX_SATS];
        let mut sat_system = [0u8; MAX_SATS];
        for ((p, sys), s) in p_sat.iter_mut().zip(sat_system.iter_mut()).zip(sats) {
            *p = s.p_sat;
            *sys = s.id.system.index() as u8;
        }
        let mut p_const: Vec<(u8, f64), MAX_SYSTEMS> = Vec::new();
        for (j, p) in ism.p_const.iter().enumerate() {
            if let Some(p) = *p {
                let pushed = p_const.push((j as u8, p));
                debug_assert!(pushed.is_ok(), "one entry per system: MAX_SYSTEMS");
            }
        }
        let n = sats.len().min(MAX_SATS);
        let (p_sat, _) = p_sat.split_at(n);
        let (sat_system, _) = sat_system.split_at(n);
        let events = Events {
            p_sat,
            sat_system,
            p_const: &p_const,
        };
        let out = &mut self.out;
        match modes::enumerate(&events, cfg.p_thres, &mut self.events) {
            Ok(enumeration) => {
                out.max_faults = enumeration.max_faults;
                out.p_exceed = enumeration.p_exceed;
                Some(enumeration.p_exceed)
            }
            Err(limit) => {
                out.unavailable = Some(match limit {
                    EnumerationLimit::TooManyEvents { p_exceed_at_max } => {
                        Unavailable::TooManyEvents { p_exceed_at_max }
                    }
                    EnumerationLimit::Capacity { needed, capacity } => {
                        Unavailable::ModeCapacity { needed, capacity }
                    }
                });
                None
            }
        }
    }

    /// Step 3 for every mode: its subset statistics (sigma^(k), b^(k),
    /// sigma_ss^(k) and the separation) by a downdate of its base
    /// ([`ModeBases::subset`]); an unmonitorable mode adds its prior to
    /// P_unmon = P(more than N_fault,max events) + those priors. Fills
    /// `out.modes`, `out.p_unmon` and `out.n_monitored`.
    ///
    /// Tests only (FDE candidates, `!with_pls`): a mode whose separation
    /// exceeds the threshold at K_fa for *all* the enumerated modes (>=
    /// the monitored ones, so that K_fa is at least the true one) fails its
    /// test whatever the rest: the subset is inconsistent, and the epoch
    /// stops there (`Break`, marked `PlNotSolved { axis: 0 }`).
    fn subset_modes(
        &mut self,
        cfg: &AraimConfig,
        layout: &Constellations,
        p_exceed: f64,
        with_pls: bool,
    ) -> ControlFlow<()> {
        let zero = T::of(0.0);
        let k_upper = if with_pls {
            [zero; 3]
        } else {
            let [kh, kv] = k_fa(&mut self.k_fa_memo, cfg, self.events.len().max(1));
            let (kh, kv) = (kh.unwrap_or(f64::INFINITY), kv.unwrap_or(f64::INFINITY));
            [T::of(kh), T::of(kh), T::of(kv)]
        };
        let bases = ModeBases {
            geo: &self.geo,
            s0: &self.s0,
            base0: &self.base0,
            const_bases: &self.const_bases,
            const_status: &self.const_status,
        };
        let out = &mut self.out;
        let mut p_unmon = p_exceed;
        for ev in self.events.iter() {
            let mode = match bases.subset(layout, ev, &mut self.coupled, &mut self.scratch) {
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
                && mode
                    .stats
                    .separation_m
                    .iter()
                    .zip(mode.stats.sigma_ss_m.iter())
                    .zip(k_upper.iter())
                    .any(|((sep, ss), k)| sep.abs() > *k * *ss);
            if out.modes.push(mode).is_err() {
                // `events` and `modes` share the capacity K, so this is
                // unreachable; were it reached, the epoch has no service
                // rather than a shortened mode list.
                debug_assert!(false, "events and modes share the capacity K");
                out.unavailable = Some(Unavailable::ModeCapacity {
                    needed: self.events.len(),
                    capacity: K,
                });
                return ControlFlow::Break(());
            }
            if certain_failure {
                out.detection_passed = false;
                out.unavailable = Some(Unavailable::PlNotSolved { axis: 0 });
                return ControlFlow::Break(());
            }
        }
        out.p_unmon = p_unmon;
        out.n_monitored = out
            .modes
            .iter()
            .filter(|m| m.status == ModeStatus::Monitored)
            .count();
        ControlFlow::Continue(())
    }

    /// Step 4: K_fa,q = Q^-1(P_FA_HOR / (4 N_modes)) for q = E, N and
    /// Q^-1(P_FA_VERT / (2 N_modes)) for U, the thresholds T_k,q = K_fa,q
    /// sigma_ss,q^(k) and the tests |x_q^(k) - x_q^(0)| <= T_k,q
    /// ([`FaultMode::test`]); step 6: EMT = max T_k,3 over the modes with
    /// p_k >= P_EMT.
    fn separation_tests(&mut self, cfg: &AraimConfig) {
        let out = &mut self.out;
        if out.n_monitored > 0 {
            let [kh, kv] = k_fa(&mut self.k_fa_memo, cfg, out.n_monitored);
            let (kh, kv) = (kh.unwrap_or(f64::NAN), kv.unwrap_or(f64::NAN));
            out.k_fa = [kh, kh, kv];
        }
        let k_fa = out.k_fa.map(T::of);
        let mut all_passed = true;
        let mut emt = T::of(0.0);
        for mode in out.modes.iter_mut() {
            if mode.status != ModeStatus::Monitored {
                continue;
            }
            all_passed &= mode.test(&k_fa);
            let [_, _, t_up] = mode.threshold_m;
            if mode.events.prior >= cfg.p_emt && t_up > emt {
                emt = t_up;
            }
        }
        out.detection_passed = all_passed;
        out.emt_m = emt;
    }

    /// Step 5: per axis the PL equation 2 Q((PL - b_q^(0)) / sigma_q^(0))
    /// plus sum_k p_k Q((PL - T_k,q - b_q^(k)) / sigma_q^(k)) = rhs_q, with
    /// rhs = PHMI_VERT (1 - P_unmon / (PHMI_VERT + PHMI_HOR)) for U and
    /// PHMI_HOR / 2 times the same factor for E and N, scaled by
    /// `budget_share`; HPL = sqrt(HPL_E^2 + HPL_N^2). Fills `out.pl_exact`
    /// and `out.pl_add`, or returns the axis whose equation could not be
    /// bracketed.
    fn protection_levels(&mut self, cfg: &AraimConfig, budget_share: f64) -> Result<(), usize> {
        let out = &mut self.out;
        let factor = 1.0 - out.p_unmon / (cfg.phmi_vert + cfg.phmi_hor);
        // One bracket memo for east and north (same rhs and priors).
        let [horizontal, vertical] = &mut self.pl_quantiles;
        let mut exact = [0.0f64; 3];
        let mut add = [0.0f64; 3];
        for ((axis, exact_m), add_m) in Axis::ALL.iter().zip(exact.iter_mut()).zip(add.iter_mut()) {
            let rhs = budget_share
                * if *axis == Axis::Up {
                    cfg.phmi_vert * factor
                } else {
                    0.5 * cfg.phmi_hor * factor
                };
            let modes = &out.modes;
            let eq = pl::Equation {
                fault_free: pl::Term {
                    p: 2.0,
                    offset_m: axis.of(&out.bias0_m).to_f64(),
                    sigma_m: axis.of(&out.sigma0_m).to_f64(),
                },
                modes: || {
                    modes
                        .iter()
                        .filter(|m| m.status == ModeStatus::Monitored)
                        .map(move |m| pl::Term {
                            p: m.events.prior,
                            offset_m: (axis.of(&m.threshold_m) + axis.of(&m.stats.bias_m)).to_f64(),
                            sigma_m: axis.of(&m.stats.sigma_m).to_f64(),
                        })
                },
                n_modes: out.n_monitored,
                rhs,
            };
            let cache = if *axis == Axis::Up {
                &mut *vertical
            } else {
                &mut *horizontal
            };
            let s = eq
                .solve_cached(cfg.tol_pl_m, cache, &mut self.pl_terms)
                .ok_or(*axis as usize)?;
            *exact_m = s.exact_m;
            *add_m = s.add_m;
        }
        out.pl_exact = ProtectionLevels::from_axes(exact);
        out.pl_add = ProtectionLevels::from_axes(add);
        Ok(())
    }

    /// The LPV-200 availability limits on the configured PL output: VPL <=
    /// VAL, HPL <= HAL, EMT <= EMT_max, sigma_v,acc <= its maximum.
    fn availability(&mut self, cfg: &AraimConfig) {
        let out = &mut self.out;
        let pl = match cfg.pl_output {
            PlOutput::AddBracket => out.pl_add,
            PlOutput::Exact => out.pl_exact,
        };
        out.limits = Limits {
            vpl: pl.vpl_m <= cfg.val_m,
            hpl: pl.hpl_m <= cfg.hal_m,
            emt: out.emt_m.to_f64() <= cfg.emt_max_m,
            sigma_acc: out.sigma_v_acc_m.to_f64() <= cfg.sigma_acc_max_m,
        };
        if !out.limits.met(Criteria::Vertical) {
            out.unavailable = Some(Unavailable::Limits);
        }
    }
}

/// Per constellation (in [`System::ALL`] order), what its events remove:
/// its satellites (bit i = satellite i) and its clock column (bit c =
/// column c; 0 for a constellation not in the ISM).
#[derive(Debug, Clone, Copy)]
struct Constellations {
    sats: [u64; MAX_SYSTEMS],
    clock_column: [u16; MAX_SYSTEMS],
}

/// The factorisations a mode's subset is downdated from.
struct ModeBases<'a, T, const N: usize> {
    geo: &'a Geometry<T, N>,
    s0: &'a [[T; N]; 3],
    base0: &'a Base<T, N>,
    const_bases: &'a [Base<T, N>; MAX_SYSTEMS],
    const_status: &'a [Option<Deficient>; MAX_SYSTEMS],
}

/// Which base a mode's subset is downdated from.
enum ModeBase<'a, T, const N: usize> {
    /// No constellation removed: the all-in-view base.
    AllInView,
    /// One constellation removed: its base, or why it is singular.
    Constellation(&'a Base<T, N>, Option<Deficient>),
    /// Several constellations removed: a base factored for the mode.
    Refactor,
}

impl<T: Real, const N: usize> ModeBases<'_, T, N> {
    /// Step 3 for one mode: the constellations it removes are its
    /// constellation events plus any constellation all of whose satellites
    /// it removes; the remaining satellites are a Woodbury downdate of
    /// that base (subset.rs). `Err` for a singular subset.
    fn subset(
        &self,
        layout: &Constellations,
        ev: &ModeEvents,
        coupled: &mut subset::Coupling<T, N>,
        scratch: &mut Base<T, N>,
    ) -> Result<SubsetStats<T>, Deficient> {
        let mut consts = ev.consts;
        for (j, &cs) in layout.sats.iter().enumerate() {
            if cs != 0 && cs & ev.sats == cs {
                consts |= 1u8 << j;
            }
        }
        if consts == 0 {
            // Satellites only (most modes): the all-in-view base.
            return subset::downdate_coupled(self.geo, self.base0, ev.sats, Some(coupled));
        }
        let mut removed = 0u64;
        let mut dropped = 0u16;
        let mut base = ModeBase::AllInView;
        let per_system = layout
            .sats
            .iter()
            .zip(layout.clock_column.iter())
            .zip(self.const_bases.iter().zip(self.const_status.iter()));
        for (j, ((&cs, &col), (const_base, status))) in per_system.enumerate() {
            if consts & (1u8 << j) != 0 {
                removed |= cs;
                dropped |= col;
                base = match base {
                    ModeBase::AllInView => ModeBase::Constellation(const_base, *status),
                    _ => ModeBase::Refactor,
                };
            }
        }
        let extra = ev.sats & !removed;
        match base {
            ModeBase::AllInView => {
                subset::downdate_coupled(self.geo, self.base0, extra, Some(coupled))
            }
            ModeBase::Constellation(_, Some(d)) => Err(d),
            ModeBase::Constellation(b, None) => subset::downdate(self.geo, b, extra),
            ModeBase::Refactor => subset::factor(self.geo, removed, dropped, self.s0, scratch)
                .and_then(|()| {
                    subset::pack(self.geo, self.s0, scratch);
                    subset::downdate(self.geo, scratch, extra)
                }),
        }
    }
}

impl<T: Real> FaultMode<T> {
    /// Step 4 for one monitored mode: T_k,q = K_fa,q sigma_ss,q^(k) into
    /// `threshold_m`, and the test |x_q^(k) - x_q^(0)| <= T_k,q on every
    /// axis (false for NaN) into `passed`, which it returns.
    fn test(&mut self, k_fa: &[T; 3]) -> bool {
        let mut passed = true;
        let axes = self.threshold_m.iter_mut().zip(k_fa.iter()).zip(
            self.stats
                .sigma_ss_m
                .iter()
                .zip(self.stats.separation_m.iter()),
        );
        for ((t, &k), (&sigma_ss, &sep)) in axes {
            *t = k * sigma_ss;
            if !(sep.abs() <= *t) {
                passed = false;
            }
        }
        self.passed = passed;
        passed
    }
}

impl ProtectionLevels {
    /// VPL from the up root, HPL = sqrt(HPL_E^2 + HPL_N^2) from the east
    /// and north roots.
    fn from_axes([east_m, north_m, up_m]: [f64; 3]) -> Self {
        Self {
            vpl_m: up_m,
            hpl_m: libm::hypot(east_m, north_m),
            hpl_axes_m: [east_m, north_m],
        }
    }
}

/// A position axis of the ENU frame (SPEC §9.1: q = 1, 2, 3).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Axis {
    East,
    North,
    Up,
}

impl Axis {
    const ALL: [Axis; 3] = [Axis::East, Axis::North, Axis::Up];

    /// This axis's component of a per-axis triple (E, N, U order).
    // In range: the discriminants are 0, 1 and 2, so the index needs (and
    // compiles to) no check.
    #[allow(clippy::indexing_slicing)]
    fn of<T: Copy>(self, v: &[T; 3]) -> T {
        v[self as usize]
    }
}

/// Step 2's b_q^(0) = sum_i |S_qi| b_nom,i and the position correction
/// sum_i S_qi y_i, for one row of S^(0) (its first `geo.n` entries).
fn nominal_bias_and_correction<T: Real, const N: usize>(
    geo: &Geometry<T, N>,
    row: &[T; N],
) -> (T, T) {
    let mut b = T::of(0.0);
    let mut x = T::of(0.0);
    for ((s, b_nom), y) in row
        .iter()
        .zip(geo.b_nom.iter())
        .zip(geo.y.iter())
        .take(geo.n)
    {
        b += s.abs() * *b_nom;
        x += *s * *y;
    }
    (b, x)
}

/// Step 6's sigma_v,acc = sqrt(sum_i S_3i^2 C_acc,ii), from the up row of
/// S^(0) (its first `geo.n` entries).
fn accuracy_sigma<T: Real, const N: usize>(geo: &Geometry<T, N>, s_up: &[T; N]) -> T {
    let mut acc = T::of(0.0);
    for (s, c_acc) in s_up.iter().zip(geo.c_acc.iter()).take(geo.n) {
        acc += *s * *s * *c_acc;
    }
    acc.sqrt()
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

#[cfg(test)]
#[path = "araim_cov_tests.rs"]
mod cov_tests;

#[cfg(test)]
#[path = "monitor_cov_tests.rs"]
mod monitor_cov_tests;
