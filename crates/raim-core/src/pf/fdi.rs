//! The FDI structure of seed 004 Fig. 1 (SPEC §10): one main filter on all
//! satellites and one auxiliary filter per satellite left out, the
//! accumulated LLR test (eqs. 9-15), isolation (eq. 14), exclusion and
//! reinitialisation. Generic over the filter ([`Estimator`]): the same
//! structure and test run the EKF, the SIR PF and the GA-PF.
//!
//! Per epoch ([`PfRaim::process`]):
//! 1. validate (finite, no duplicates, capacity, enough satellites); a
//!    refused epoch leaves every filter untouched;
//! 2. drop the auxiliary filter of a satellite that left view, spawn one
//!    (a copy of the main filter) for a satellite that entered;
//! 3. predict every filter over dt; reduce the measurements against the
//!    shared f64 reference (a constellation-wide residual beyond
//!    `clock_jump_m` moves that clock's reference: a receiver clock jump);
//! 4. update the main filter and each auxiliary filter; s_k(q) =
//!    ln p_q(y^{-q}) - ln p_A(y) - ln(sqrt(2 pi e v) sigma_q) into q's
//!    window (eqs. 9, 11, 12, 15; docs/PF.md "the LLR");
//! 5. a collapsed filter is reinitialised and reported: the main one from
//!    the prior about the reference (no position this epoch, all windows
//!    cleared), an auxiliary one from the main filter;
//! 6. D_k = max_q max_j S_j^k(q) > threshold is an alarm (a NaN statistic
//!    alarms); the isolated satellite is the argmax (eq. 14); with
//!    `exclude`, its auxiliary filter (which never used it) becomes the
//!    main filter and the other auxiliaries restart from it;
//! 7. recentre the reference on the main estimate.

use core::marker::PhantomData;

use crate::measurement::{RangeObservation, SatId, MAX_SYSTEMS};
use crate::real::Real;

use super::config::PfConfig;
use super::error::PfError;
use super::init::{fix, FixInput};
use super::llr::LlrWindow;
use super::model::{Estimator, Reference, SatTerm, CLOCK0, DIM, DRIFT};
use super::rng::{self, PfRng};
use super::threshold;

/// One auxiliary filter's line in the output.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SatLlr {
    /// The satellite the auxiliary filter leaves out.
    pub id: SatId,
    /// This epoch's s_k(q) (eq. 15).
    pub llr: f64,
    /// max_j S_j^k(q) over the window (eq. 13).
    pub windowed: f64,
}

/// The monitor's answer for one epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct PfOutput<const S: usize> {
    /// Epoch time, s.
    pub time_s: f64,
    /// The main filter's position; `None` when it collapsed this epoch.
    pub position_m: Option<[f64; 3]>,
    /// Clock bias per constellation (System::index), m.
    pub clock_m: [f64; MAX_SYSTEMS],
    /// Clock drift, m/s.
    pub drift_m_s: f64,
    /// D_k (eq. 13); -inf before any LLR exists.
    pub decision: f64,
    /// The alarm threshold on D_k.
    pub threshold: f64,
    /// D_k above the threshold this epoch.
    pub alarm: bool,
    /// argmax_q of the windowed LLR at an alarm (eq. 14).
    pub isolated: Option<SatId>,
    /// The satellite excluded this epoch (with `exclude`).
    pub excluded: Option<SatId>,
    /// The main filter's N_eff of the weights entering resampling (after
    /// the genetic step for the GA-PF; 0 for the EKF).
    pub n_eff: f64,
    /// The main filter's N_eff before the genetic step (the likelihood
    /// weights; equal to `n_eff` for the SIR filter, 0 for the EKF).
    pub n_eff_before_ga: f64,
    /// Satellites used by the main filter.
    pub used: usize,
    /// The main filter collapsed and was reinitialised.
    pub main_collapsed: bool,
    /// Auxiliary filters that collapsed and were reinitialised.
    pub aux_collapsed: usize,
    /// A receiver clock jump moved a clock reference.
    pub clock_jump: bool,
    /// Per satellite, its accumulated LLR.
    pub llr: heapless::Vec<SatLlr, S>,
}

/// The satellite an auxiliary filter leaves out, or none. Not an
/// `Option<SatId>`: its `None` is a niche value, while "none" here is all
/// zero bytes, so that [`PfRaim::EMPTY`] is.
#[derive(Debug, Clone, Copy, PartialEq)]
struct AuxSlot {
    id: SatId,
    used: bool,
}

impl AuxSlot {
    /// No satellite.
    const NONE: Self = AuxSlot {
        id: SatId::DEFAULT,
        used: false,
    };

    /// Satellite `id`.
    fn of(id: SatId) -> Self {
        AuxSlot { id, used: true }
    }

    /// The satellite, if any.
    fn get(self) -> Option<SatId> {
        self.used.then_some(self.id)
    }
}

/// Particle-filter RAIM with filter `E` in precision `T` and room for `S`
/// satellites (main filter + `S` auxiliary filters, all fixed arrays).
pub struct PfRaim<T: Real, E: Estimator<T>, const S: usize> {
    main: E,
    aux: [E; S],
    aux_id: [AuxSlot; S],
    windows: [LlrWindow; S],
    reference: Reference,
    time_s: Option<f64>,
    /// Excluded satellites with the time of their exclusion.
    excluded: heapless::Vec<(SatId, f64), S>,
    /// `None` in [`PfRaim::EMPTY`] until first use, then seeded with 0.
    rng: Option<PfRng>,
    _t: PhantomData<T>,
}

impl<T: Real, E: Estimator<T>, const S: usize> PfRaim<T, E, S> {
    /// A monitor whose randomness is seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        PfRaim {
            rng: Some(rng::seeded(seed)),
            ..Self::EMPTY
        }
    }

    /// A monitor built at compile time, equal in behaviour to
    /// [`PfRaim::new`]`(0)` (its generator is seeded with 0 on first use;
    /// test `empty_equals_new_zero`). Every byte of it is zero, so a
    /// `static` initialised with it takes no flash image and is never
    /// built on the stack: the device's engine storage.
    pub const EMPTY: Self = PfRaim {
        main: E::BLANK,
        aux: [E::BLANK; S],
        aux_id: [AuxSlot::NONE; S],
        windows: [LlrWindow::EMPTY; S],
        reference: Reference::ZERO,
        time_s: None,
        excluded: heapless::Vec::new(),
        rng: None,
        _t: PhantomData,
    };

    /// Forgets everything in place (no temporary copy of the filters, so a
    /// monitor in static storage can be restarted without stack): the next
    /// epoch initialises from its own first fix, exactly as in a monitor
    /// made by [`PfRaim::new`] with the same `seed` (test
    /// `restart_equals_new`). The filters' arrays are left as they are:
    /// the first epoch overwrites the main filter (`Estimator::init`) and
    /// every auxiliary filter is copied from it before its first use.
    pub fn restart(&mut self, seed: u64) {
        self.aux_id = [AuxSlot::NONE; S];
        for w in self.windows.iter_mut() {
            w.clear();
        }
        self.reference = Reference::ZERO;
        self.time_s = None;
        self.excluded.clear();
        self.rng = Some(rng::seeded(seed));
    }

    /// Bytes of state (filters, windows, reference).
    pub const BYTES: usize = core::mem::size_of::<Self>();

    /// The satellites excluded now, with the time of their exclusion.
    pub fn excluded(&self) -> &[(SatId, f64)] {
        &self.excluded
    }

    /// The current reference (the main estimate after each epoch).
    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    /// The main filter.
    pub fn main(&self) -> &E {
        &self.main
    }

    fn validate(
        &self,
        cfg: &PfConfig,
        time_s: f64,
        obs: &[RangeObservation],
    ) -> Result<(), PfError> {
        cfg.validate()?;
        if !time_s.is_finite() {
            return Err(PfError::NotFinite {
                field: "time_s",
                index: 0,
                value: time_s,
            });
        }
        let era = crate::measurement::EPOCH_TIME_S;
        if !era.contains(time_s) {
            return Err(PfError::OutOfRange {
                field: era.field,
                value: time_s,
                min: era.min,
                max: era.max,
            });
        }
        if let Some(prev) = self.time_s {
            if !(time_s > prev) {
                return Err(PfError::TimeNotIncreasing {
                    previous_s: prev,
                    now_s: time_s,
                });
            }
        }
        if obs.len() > S {
            return Err(PfError::Capacity {
                field: "observations",
                have: obs.len(),
                max: S,
            });
        }
        for (i, o) in obs.iter().enumerate() {
            let bad = |field: &'static str, value: f64| {
                if value.is_finite() {
                    Ok(())
                } else {
                    Err(PfError::NotFinite {
                        field,
                        index: i,
                        value,
                    })
                }
            };
            if !crate::measurement::prn_in_range(o.id) {
                return Err(PfError::PrnOutOfRange {
                    index: i,
                    id: o.id,
                    max: o.id.system.max_prn(),
                });
            }
            bad("pseudorange_m", o.pseudorange_m)?;
            for &p in o.position_m.iter() {
                bad("position_m", p)?;
            }
            if let Some(s) = o.sigma_m {
                bad("sigma_m", s)?;
                if !(s > 0.0) {
                    return Err(PfError::InvalidConfig {
                        field: "sigma_m",
                        value: s,
                    });
                }
                let b = crate::config_bounds::SIGMA_M;
                if !b.contains(s) {
                    return Err(PfError::SigmaOutOfRange {
                        index: i,
                        sigma_m: s,
                        min_m: b.min,
                        max_m: b.max,
                    });
                }
            }
            if obs.iter().take(i).any(|p| p.id == o.id) {
                return Err(PfError::DuplicateSatellite { id: o.id });
            }
        }
        Ok(())
    }

    /// Processes one epoch of corrected pseudoranges at `time_s`, with the
    /// decision threshold of eq. 13 looked up in the calibrated table for
    /// this filter, particle count and `cfg` at the allocated `cfg.pfa`
    /// ([`threshold::lookup`]); a configuration the table does not cover
    /// is refused with `PfError::NotCalibrated`, and a threshold above the
    /// detectability ceiling (`config_bounds::pf::threshold_bound`) with
    /// `PfError::OutOfRange`; nothing changes then.
    pub fn process(
        &mut self,
        cfg: &PfConfig,
        time_s: f64,
        obs: &[RangeObservation],
    ) -> Result<PfOutput<S>, PfError> {
        cfg.validate()?;
        let threshold = threshold::lookup(E::KIND, E::PARTICLES, cfg)?;
        crate::config_bounds::pf::threshold_bound(&cfg.likelihood, cfg.window)
            .check_pf(threshold)?;
        self.process_at(cfg, threshold, time_s, obs)
    }

    /// [`PfRaim::process`] at an explicit decision threshold (steps 1-7 of
    /// the module doc, one function each): for the calibration of the
    /// table itself (fault-free runs, threshold +inf) and for experiments;
    /// an integrity output takes `process`.
    pub fn process_at(
        &mut self,
        cfg: &PfConfig,
        threshold: f64,
        time_s: f64,
        obs: &[RangeObservation],
    ) -> Result<PfOutput<S>, PfError> {
        if threshold.is_nan() {
            return Err(PfError::InvalidConfig {
                field: "threshold",
                value: threshold,
            });
        }
        // 1.
        self.validate(cfg, time_s, obs)?;
        if cfg.readmit_s > 0.0 {
            self.excluded.retain(|(_, t)| time_s - *t < cfg.readmit_s);
        }
        let used = self.usable(obs)?;
        let dt_s = self.start_or_advance(cfg, time_s, &used)?;
        self.time_s = Some(time_s);
        // 2.
        self.follow_satellites(&used);
        // 3.
        self.predict_all(cfg, dt_s);
        let clock_jump = self.absorb_clock_jump(cfg, &used, dt_s);
        let terms = self.reduce(cfg, &used);
        // 4. The main filter.
        let main_step = self
            .main
            .update(cfg, &terms, None, rng::or_seed_zero(&mut self.rng));
        let mut out = PfOutput {
            time_s,
            position_m: None,
            clock_m: [0.0; MAX_SYSTEMS],
            drift_m_s: 0.0,
            decision: f64::NEG_INFINITY,
            threshold,
            alarm: false,
            isolated: None,
            excluded: None,
            n_eff: main_step.n_eff,
            n_eff_before_ga: main_step.n_eff_before_ga,
            used: used.len(),
            main_collapsed: main_step.collapsed,
            aux_collapsed: 0,
            clock_jump,
            llr: heapless::Vec::new(),
        };
        if main_step.collapsed {
            // 5. Never a position from a collapsed filter: restart
            // everything from the prior about the last reference.
            self.main.init(cfg, rng::or_seed_zero(&mut self.rng));
            self.restart_auxiliaries();
            out.clock_m = self.reference.clock_m;
            return Ok(out);
        }
        // 4-5. The auxiliary filters and their LLRs.
        self.update_auxiliaries(cfg, &terms, main_step.ln_predictive, &mut out);
        // 6.
        self.decide(cfg, threshold, time_s, &mut out)?;
        // 7.
        self.recentre(&mut out);
        Ok(out)
    }

    /// Step 1's satellite count: the observations not excluded, refused
    /// with `TooFewSatellites` below 3 + clocks + 1 (each auxiliary filter
    /// must still see 3 + clocks satellites).
    fn usable(
        &self,
        obs: &[RangeObservation],
    ) -> Result<heapless::Vec<RangeObservation, S>, PfError> {
        let mut used: heapless::Vec<RangeObservation, S> = heapless::Vec::new();
        let mut systems = [false; MAX_SYSTEMS];
        for o in obs
            .iter()
            .filter(|o| !self.excluded.iter().any(|(e, _)| *e == o.id))
        {
            if used.push(*o).is_err() {
                return Err(PfError::Capacity {
                    field: "observations",
                    have: obs.len(),
                    max: S,
                });
            }
            if let Some(f) = systems.get_mut(o.id.system.index()) {
                *f = true;
            }
        }
        let need = 3 + systems.iter().filter(|&&f| f).count() + 1;
        if used.len() < need {
            return Err(PfError::TooFewSatellites {
                have: used.len(),
                need,
            });
        }
        Ok(used)
    }

    /// The reference on the first epoch (the least-squares fix, the main
    /// filter from its prior), else the clock references advanced with the
    /// reference drift (the state keeps only the offsets, small enough for
    /// f32). Returns dt (0 on the first epoch).
    fn start_or_advance(
        &mut self,
        cfg: &PfConfig,
        time_s: f64,
        used: &[RangeObservation],
    ) -> Result<f64, PfError> {
        match self.time_s {
            None => {
                let mut inputs: heapless::Vec<FixInput, S> = heapless::Vec::new();
                for o in used.iter() {
                    let pushed = inputs.push(FixInput {
                        sat_m: o.position_m,
                        pseudorange_m: o.pseudorange_m,
                        sigma_m: o.sigma_m.unwrap_or(cfg.sigma_m),
                        sys: o.id.system.index(),
                    });
                    // Cannot fill: one input per used satellite, at most S.
                    debug_assert!(pushed.is_ok());
                }
                self.reference = fix(&inputs, [0.0; 3])?;
                self.main.init(cfg, rng::or_seed_zero(&mut self.rng));
                self.aux_id = [AuxSlot::NONE; S];
                for w in self.windows.iter_mut() {
                    w.clear();
                }
                Ok(0.0)
            }
            Some(prev) => {
                let dt_s = time_s - prev;
                for c in self.reference.clock_m.iter_mut() {
                    *c += self.reference.drift_m_s * dt_s;
                }
                Ok(dt_s)
            }
        }
    }

    /// Step 2: the auxiliary filter of a satellite that left view is
    /// dropped; a satellite that entered gets one, a copy of the main
    /// filter.
    fn follow_satellites(&mut self, used: &[RangeObservation]) {
        for (id, w) in self.aux_id.iter_mut().zip(self.windows.iter_mut()) {
            if let Some(i) = id.get() {
                if !used.iter().any(|o| o.id == i) {
                    *id = AuxSlot::NONE;
                    w.clear();
                }
            }
        }
        for o in used.iter() {
            if self.aux_id.iter().any(|s| s.get() == Some(o.id)) {
                continue;
            }
            if let Some(slot) = self.aux_id.iter().position(|s| s.get().is_none()) {
                if let (Some(a), Some(id), Some(w)) = (
                    self.aux.get_mut(slot),
                    self.aux_id.get_mut(slot),
                    self.windows.get_mut(slot),
                ) {
                    a.copy_from(&self.main);
                    *id = AuxSlot::of(o.id);
                    w.clear();
                }
            }
        }
    }

    /// Step 3's prediction of every filter over dt (none on the first
    /// epoch).
    fn predict_all(&mut self, cfg: &PfConfig, dt_s: f64) {
        if dt_s > 0.0 {
            self.main
                .predict(cfg, dt_s, rng::or_seed_zero(&mut self.rng));
            for (a, id) in self.aux.iter_mut().zip(self.aux_id.iter()) {
                if id.get().is_some() {
                    a.predict(cfg, dt_s, rng::or_seed_zero(&mut self.rng));
                }
            }
        }
    }

    /// Step 3's reduction of each used measurement against the shared f64
    /// reference.
    fn reduce(&self, cfg: &PfConfig, used: &[RangeObservation]) -> heapless::Vec<SatTerm<T>, S> {
        let mut terms: heapless::Vec<SatTerm<T>, S> = heapless::Vec::new();
        for o in used.iter() {
            let pushed = terms.push(SatTerm::new(
                o.id,
                o.pseudorange_m,
                &o.position_m,
                o.sigma_m.unwrap_or(cfg.sigma_m),
                &self.reference,
            ));
            // Cannot fill: one term per used satellite, at most S.
            debug_assert!(pushed.is_ok());
        }
        terms
    }

    /// Every auxiliary filter restarts from the main one, every window
    /// cleared (steps 5 and 6).
    fn restart_auxiliaries(&mut self) {
        for ((a, id), w) in self
            .aux
            .iter_mut()
            .zip(self.aux_id.iter())
            .zip(self.windows.iter_mut())
        {
            w.clear();
            if id.get().is_some() {
                a.copy_from(&self.main);
            }
        }
    }

    /// Steps 4-5 for the auxiliary filters: each updates without its
    /// satellite q (a collapsed one restarts from the main filter), and
    /// s_k(q) = ln p_q(y^{-q}) - ln p_A(y) - ln(c_norm sigma_q) (eq. 15,
    /// the left-out satellite's density replaced by its expected value
    /// under no fault; docs/PF.md, "the LLR") enters q's window and
    /// `out.llr`.
    fn update_auxiliaries(
        &mut self,
        cfg: &PfConfig,
        terms: &[SatTerm<T>],
        ln_predictive_main: f64,
        out: &mut PfOutput<S>,
    ) {
        // sqrt(2 pi e var_factor): E[-ln p(y_q)] = ln(c_norm sigma_q) for a
        // Gaussian of the law's variance.
        let c_norm = libm::sqrt(
            2.0 * core::f64::consts::PI * core::f64::consts::E * cfg.likelihood.variance_factor(),
        );
        for ((a, id), w) in self
            .aux
            .iter_mut()
            .zip(self.aux_id.iter())
            .zip(self.windows.iter_mut())
        {
            let Some(id) = id.get() else { continue };
            let Some(q) = terms.iter().position(|t| t.id == id) else {
                continue;
            };
            let step = a.update(cfg, terms, Some(q), rng::or_seed_zero(&mut self.rng));
            if step.collapsed {
                a.copy_from(&self.main);
                w.clear();
                out.aux_collapsed += 1;
                continue;
            }
            let sigma_q = terms.get(q).map_or(f64::NAN, |t| t.sigma.to_f64());
            let s = step.ln_predictive - ln_predictive_main - libm::log(c_norm * sigma_q);
            w.push(s);
            let pushed = out.llr.push(SatLlr {
                id,
                llr: s,
                windowed: w.windowed_max(cfg.window),
            });
            // Cannot fill: one entry per auxiliary filter, S of them.
            debug_assert!(pushed.is_ok());
        }
    }

    /// Step 6: D_k = max_q max_j S_j^k(q) against `threshold` (eq. 13; a
    /// NaN statistic alarms), the argmax isolated (eq. 14) and, with
    /// `exclude`, excluded.
    fn decide(
        &mut self,
        cfg: &PfConfig,
        threshold: f64,
        time_s: f64,
        out: &mut PfOutput<S>,
    ) -> Result<(), PfError> {
        let mut best: Option<SatLlr> = None;
        for l in out.llr.iter() {
            let better = match best {
                None => true,
                Some(b) => l.windowed.is_nan() || l.windowed > b.windowed,
            };
            if better && !best.is_some_and(|b| b.windowed.is_nan()) {
                best = Some(*l);
            }
        }
        if let Some(b) = best {
            out.decision = b.windowed;
            out.alarm = !(b.windowed <= threshold);
            if out.alarm {
                out.isolated = Some(b.id);
                if cfg.exclude {
                    self.exclude(b.id, time_s)?;
                    out.excluded = Some(b.id);
                }
            }
        }
        Ok(())
    }

    /// Step 7: the reference moves to the main estimate, every filter
    /// shifts by minus it; the output takes the new reference.
    fn recentre(&mut self, out: &mut PfOutput<S>) {
        let m = self.main.mean();
        let mut delta = [T::zero(); DIM];
        for (d, &v) in delta.iter_mut().zip(m.iter()) {
            *d = -v;
        }
        self.reference.drift_m_s += m[DRIFT].to_f64();
        for (p, &v) in self.reference.position_m.iter_mut().zip(m.iter()) {
            *p += v.to_f64();
        }
        for (c, &v) in self.reference.clock_m.iter_mut().zip(m.iter().skip(CLOCK0)) {
            *c += v.to_f64();
        }
        self.main.shift(&delta);
        for (a, id) in self.aux.iter_mut().zip(self.aux_id.iter()) {
            if id.get().is_some() {
                a.shift(&delta);
            }
        }
        out.position_m = Some(self.reference.position_m);
        out.clock_m = self.reference.clock_m;
        out.drift_m_s = self.reference.drift_m_s;
    }

    /// Excludes `id`: its auxiliary filter becomes the main filter, the
    /// others restart from it, all windows are cleared. Refused with
    /// `Capacity` when S satellites are held excluded already (none has
    /// reached `readmit_s`).
    fn exclude(&mut self, id: SatId, time_s: f64) -> Result<(), PfError> {
        if self.excluded.push((id, time_s)).is_err() {
            return Err(PfError::Capacity {
                field: "excluded",
                have: S + 1,
                max: S,
            });
        }
        if let Some(slot) = self.aux_id.iter().position(|s| s.get() == Some(id)) {
            if let Some(a) = self.aux.get(slot) {
                self.main.copy_from(a);
            }
            if let Some(s) = self.aux_id.get_mut(slot) {
                *s = AuxSlot::NONE;
            }
        }
        self.restart_auxiliaries();
        Ok(())
    }

    /// Per constellation, the median residual at the predicted main state;
    /// beyond `clock_jump_m` it moves the clock reference (all filters
    /// alike, so the LLRs are unaffected). Returns whether it did.
    fn absorb_clock_jump(&mut self, cfg: &PfConfig, used: &[RangeObservation], dt_s: f64) -> bool {
        if !(cfg.clock_jump_m > 0.0) {
            return false;
        }
        let mut x = self.main.mean();
        let drift = x[DRIFT];
        for v in x.iter_mut().take(DRIFT).skip(CLOCK0) {
            *v += drift * T::of(dt_s);
        }
        let mut jumped = false;
        for sys in 0..MAX_SYSTEMS {
            let mut r: heapless::Vec<f64, S> = heapless::Vec::new();
            for o in used.iter().filter(|o| o.id.system.index() == sys) {
                let t =
                    SatTerm::<f64>::new(o.id, o.pseudorange_m, &o.position_m, 1.0, &self.reference);
                let xf: [f64; DIM] = x.map(|v| v.to_f64());
                let pushed = r.push(t.residual(&xf));
                // Cannot fill: at most the used satellites, S.
                debug_assert!(pushed.is_ok());
            }
            if r.is_empty() {
                continue;
            }
            // The median: the two middle order statistics, by the checked
            // quickselect (no sort, so no panic path in the firmware).
            let n = r.len();
            let upper = super::resample::kth_smallest(&mut r, n / 2);
            let lower = super::resample::kth_smallest(&mut r, n.div_ceil(2) - 1);
            let med = match (upper, lower) {
                (Some(a), Some(b)) => 0.5 * (a + b),
                _ => 0.0,
            };
            if med.abs() > cfg.clock_jump_m {
                if let Some(c) = self.reference.clock_m.get_mut(sys) {
                    *c += med;
                    jumped = true;
                }
            }
        }
        jumped
    }
}

#[cfg(test)]
#[path = "fdi_cov_tests.rs"]
mod cov_tests;
