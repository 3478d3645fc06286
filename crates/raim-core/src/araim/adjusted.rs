//! The adjusted all-in-view position estimator of Blanch, Walter, Enge and
//! Kropp, "A Simple Position Estimator that Improves Advanced RAIM
//! Performance", IEEE TAES 51(3), 2015 (SPEC §9.1 leaves the all-in-view
//! estimator to the ADD's weighted least squares; this is the option of
//! the paper, as MAAST for ARAIM 2 applies it: `mhss_raim_baseline_v5.m`,
//! `compute_adjusted_position_1D.m`, `usr_vhpl_araim.m`).
//!
//! The weighted least squares is the most accurate unbiased estimator, but
//! the protection level is often driven by one "weak" fault mode whose
//! subset solution is far from it. Trading accuracy the service does not
//! need for a smaller separation from that mode lowers the PL. Per axis q
//! (east, north, up, each on its own):
//!
//! 1. The weak mode w: among the monitored modes with prior p_k >=
//!    [`WEAK_MODE_MIN_PRIOR`], the one with the largest sigma_q^(k) (the
//!    first such mode in list order on a tie).
//! 2. With d_w = S^(w)_q - S^(0)_q (its gain row minus the all-in-view
//!    one, over every satellite, zero gain at the satellites it removes)
//!    and the all-in-view row s0 = S^(0)_q, the candidate row
//!    s0' = s0 + t d_w has the accuracy variance
//!    sigma_acc(t)^2 = sigma_acc^2 + 2 t b + t^2 a with
//!    a = sum_i d_wi^2 C_acc,i, b = sum_i s0_i d_wi C_acc,i (the paper's
//!    eq. for the accuracy constraint). t is the positive root of
//!    sigma_acc(t) = sigma_acc,max,q - [`ACC_MARGIN_M`], capped at 1
//!    (s0' = the weak subset's own row), and 0 when sigma_acc already
//!    reaches it.
//! 3. s0' is still unbiased: s0 G = e_q and S^(w) G = e_q (the weak subset
//!    estimates every column it keeps; a column it drops is a clock, whose
//!    e_q entry is 0), so s0' G = e_q for every t.
//! 4. With s0' in place of s0 on that axis: sigma_q^(0) = sqrt(sum s0'^2
//!    C_int), b_q^(0) = sum |s0'| b_nom, the correction s0' y, sigma_v,acc
//!    (up), and for every mode k, with d_k = S^(k)_q - s0 its difference
//!    row, the separation and its sigma against s0': d_k - t d_w, so
//!    sigma_ss,q^(k) = sqrt(sum (d_k - t d_w)^2 C_acc) and
//!    x^(k) - x^(0)' = sum (d_k - t d_w) y. The subset solutions themselves
//!    (sigma_q^(k), b_q^(k)) do not change. Thresholds, tests, EMT, PLs
//!    and the limits follow by the same steps 4-6 as the plain epoch.
//!
//! When it is tried and kept (`usr_vhpl_araim.m`): only after a plain
//! epoch whose VPL, HPL or EMT fails its limit (its cause
//! `Unavailable::Limits`) while its sigma_v,acc is below the vertical
//! accuracy limit of the estimator; the adjusted output replaces the plain
//! one when its VPL or its HPL (the configured PL output) is lower, and
//! the plain one is restored otherwise. Every quantity in that choice is a
//! function of the geometry and the ISM only, never of the measurements,
//! so the chosen estimator is fixed before the measurements, and the PL
//! equation bounds its error as it does the plain one's: under mode k,
//! x^(0)' - x = (x^(k) - x) + (x^(0)' - x^(k)), the first term the
//! subset's nominal error (sigma_q^(k), b_q^(k)), the second at most
//! T_k,q when the test against s0' passes; fault-free, x^(0)' - x has
//! sigma_q^(0) and b_q^(0) of s0'.
//!
//! The difference rows are formed densely, one factorisation per mode
//! ([`subset::factor`]): the adjustment runs on the unavailable epochs
//! only, and the dense rows are their own check of the downdates: at
//! t = 0 they give every mode's sigma_ss and separation to rounding
//! (test `the_dense_rows_give_the_downdates_sigma_ss`).

use super::subset::{self, Deficient, Geometry};
use super::{
    Araim, AraimConfig, AraimError, Constellations, ModeEvents, ModeStatus, PlOutput,
    ProtectionLevels, Unavailable,
};
use crate::config_bounds::araim::SIGMA_ACC_MAX_M;
use crate::real::Real;

/// Fault modes with a prior below this are not candidates for the weak
/// mode (the floor of `compute_adjusted_position_1D.m`, MAAST for ARAIM 2):
/// a mode that rare drives no PL term worth trading accuracy for.
pub const WEAK_MODE_MIN_PRIOR: f64 = 1e-11;

/// The adjusted sigma_acc is aimed this far below its limit, m (MAAST for
/// ARAIM 2's `sig_acc_max - 1e-5`), so that rounding cannot lift it above
/// the limit the availability judges.
pub const ACC_MARGIN_M: f64 = 1e-5;

/// The all-in-view position estimator the engine uses.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Estimator {
    /// The weighted least squares of SPEC §9.1 step 2 (the ADD's).
    #[default]
    AllInView,
    /// The adjusted estimator of Blanch et al. 2015 (module doc), with the
    /// accuracy limit per axis (E, N, U), m, that it may spend: MAAST for
    /// ARAIM 2 uses [3, 3, 1.86] for LPV-200 (its `sig_acc_max_hor1`,
    /// `_hor2`, `_vert`).
    Adjusted {
        /// sigma_acc,max per axis E, N, U, m.
        sigma_acc_max_m: [f64; 3],
    },
}

impl Estimator {
    /// Range-checks the accuracy limits against the operational bound of
    /// the sigma_v,acc limit (`config_bounds::araim::SIGMA_ACC_MAX_M`),
    /// field `adjusted_sigma_acc_max_m`, index the axis (0 E, 1 N, 2 U).
    pub fn validate(&self) -> Result<(), AraimError> {
        if let Estimator::Adjusted { sigma_acc_max_m } = self {
            for (axis, &v) in sigma_acc_max_m.iter().enumerate() {
                if !(SIGMA_ACC_MAX_M.min..=SIGMA_ACC_MAX_M.max).contains(&v) {
                    return Err(AraimError::OutOfRange {
                        field: "adjusted_sigma_acc_max_m",
                        index: axis,
                        value: v,
                        min: SIGMA_ACC_MAX_M.min,
                        max: SIGMA_ACC_MAX_M.max,
                    });
                }
            }
        }
        Ok(())
    }
}

/// What an adjustment attempt left in the output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Attempt {
    /// Not tried, or t = 0 on every axis: the plain output, untouched.
    Untouched,
    /// The adjusted output is in place and kept.
    Kept,
    /// The output was changed and is not kept: the plain epoch must be
    /// processed again.
    Dirty,
}

/// The satellites and clock columns a mode's subset removes: its
/// satellites, plus every constellation of its events or all of whose
/// satellites it removes, with that constellation's clock column (as
/// `ModeBases::subset` chooses its base).
fn removed_and_dropped(layout: &Constellations, ev: &ModeEvents) -> (u64, u16) {
    let mut removed = ev.sats;
    let mut dropped = 0u16;
    for (j, (&cs, &col)) in layout
        .sats
        .iter()
        .zip(layout.clock_column.iter())
        .enumerate()
    {
        let by_event = ev.consts & (1u8 << j) != 0;
        let emptied = cs != 0 && cs & ev.sats == cs;
        if by_event || emptied {
            removed |= cs;
            dropped |= col;
        }
    }
    (removed, dropped)
}

/// t of the module doc's step 2 from a = |d_w|^2, b = <s0, d_w> and
/// c = sigma_acc^2 - target^2 (all C_acc-weighted): the positive root of
/// a t^2 + 2 b t + c = 0 capped at 1, or 0 when c >= 0 or the quadratic is
/// degenerate (a not positive, a NaN anywhere).
pub fn adjustment_t(a: f64, b: f64, c: f64) -> f64 {
    if !(c < 0.0) || !(a > 0.0) || !b.is_finite() {
        return 0.0;
    }
    // c < 0 < a: the discriminant exceeds b^2, so the root is positive.
    let t = (-b + libm::sqrt(b * b - a * c)) / a;
    if t < 1.0 {
        t
    } else {
        1.0
    }
}

/// sum_i u_i v_i c_i over the epoch's satellites.
fn weighted_dot<T: Real, const N: usize>(n: usize, u: &[T; N], v: &[T; N], c: &[T; N]) -> T {
    u.iter()
        .zip(v.iter())
        .zip(c.iter())
        .take(n)
        .fold(T::of(0.0), |acc, ((&x, &y), &w)| acc + x * y * w)
}

/// The index of the weak mode of axis `q` (module doc, step 1), if any.
fn weak_mode<T: Real>(modes: &[super::FaultMode<T>], q: usize) -> Option<usize> {
    let mut best: Option<(usize, T)> = None;
    for (k, m) in modes.iter().enumerate() {
        if m.status != ModeStatus::Monitored || m.events.prior < WEAK_MODE_MIN_PRIOR {
            continue;
        }
        let Some(&s) = m.stats.sigma_m.get(q) else {
            continue;
        };
        if !s.to_f64().is_finite() {
            continue;
        }
        if best.is_none_or(|(_, b)| s > b) {
            best = Some((k, s));
        }
    }
    best.map(|(k, _)| k)
}

/// The configured PL output.
fn configured(
    cfg: &AraimConfig,
    pl_add: ProtectionLevels,
    pl_exact: ProtectionLevels,
) -> ProtectionLevels {
    match cfg.pl_output {
        PlOutput::AddBracket => pl_add,
        PlOutput::Exact => pl_exact,
    }
}

impl<T: Real, const N: usize, const K: usize> Araim<T, N, K> {
    /// The difference rows S^(k) - S^(0) (E, N, U) of the subset that mode
    /// `ev` leaves, densely, into `self.scratch.d`.
    fn difference_rows(
        &mut self,
        layout: &Constellations,
        ev: &ModeEvents,
    ) -> Result<(), Deficient> {
        let (removed, dropped) = removed_and_dropped(layout, ev);
        subset::factor(&self.geo, removed, dropped, &self.s0, &mut self.scratch)
    }

    /// The adjusted estimator after a plain epoch (module doc): tried when
    /// `estimator` is `Adjusted`, the PLs were computed and the epoch is
    /// unavailable for its VPL, HPL or EMT with sigma_v,acc below the
    /// vertical accuracy limit.
    #[inline(never)]
    pub(super) fn adjust(&mut self, cfg: &AraimConfig, layout: &Constellations) -> Attempt {
        let Estimator::Adjusted { sigma_acc_max_m } = self.estimator else {
            return Attempt::Untouched;
        };
        let out = &self.out;
        let l = out.limits;
        let [_, _, max_up_m] = sigma_acc_max_m;
        let tried = out.unavailable == Some(Unavailable::Limits)
            && !(l.vpl && l.hpl && l.emt)
            && out.sigma_v_acc_m.to_f64() < max_up_m;
        if !tried {
            return Attempt::Untouched;
        }
        let plain = configured(cfg, out.pl_add, out.pl_exact);
        let n = self.geo.n.min(N);
        let zero = T::of(0.0);
        // Step 2 per axis: the weak mode's difference row and t.
        let mut t = [0.0f64; 3];
        let mut d_w = [[zero; N]; 3];
        for q in 0..3 {
            let Some(w) = weak_mode(&self.out.modes, q) else {
                continue;
            };
            let Some(mode) = self.out.modes.get(w) else {
                continue;
            };
            let ev = mode.events;
            if self.difference_rows(layout, &ev).is_err() {
                continue;
            }
            let (Some(row), Some(s0), Some(dq), Some(&lim)) = (
                self.scratch.d.get(q),
                self.s0.get(q),
                d_w.get_mut(q),
                sigma_acc_max_m.get(q),
            ) else {
                continue;
            };
            *dq = *row;
            let c_acc = &self.geo.c_acc;
            let a = weighted_dot(n, dq, dq, c_acc).to_f64();
            let b = weighted_dot(n, s0, dq, c_acc).to_f64();
            let acc2 = weighted_dot(n, s0, s0, c_acc).to_f64();
            let target = lim - ACC_MARGIN_M;
            if let Some(tq) = t.get_mut(q) {
                *tq = adjustment_t(a, b, acc2 - target * target);
            }
        }
        if t.iter().all(|&x| x == 0.0) {
            return Attempt::Untouched;
        }
        let tt = t.map(T::of);
        // Step 4, all in view: s0' on the adjusted axes.
        for q in 0..3 {
            let (Some(&tq), Some(s0), Some(dq)) = (tt.get(q), self.s0.get(q), d_w.get(q)) else {
                continue;
            };
            if tq == zero {
                continue;
            }
            let geo: &Geometry<T, N> = &self.geo;
            let (mut var, mut bias, mut corr, mut acc) = (zero, zero, zero, zero);
            let sats = s0
                .iter()
                .zip(dq.iter())
                .zip(geo.c_int.iter().zip(geo.c_acc.iter()))
                .zip(geo.b_nom.iter().zip(geo.y.iter()))
                .take(n);
            for (((&s, &d), (&ci, &ca)), (&bn, &y)) in sats {
                let s1 = s + tq * d;
                var += s1 * s1 * ci;
                bias += s1.abs() * bn;
                corr += s1 * y;
                acc += s1 * s1 * ca;
            }
            let out = &mut self.out;
            if let (Some(sg), Some(b), Some(c)) = (
                out.sigma0_m.get_mut(q),
                out.bias0_m.get_mut(q),
                out.correction_enu_m.get_mut(q),
            ) {
                *sg = var.sqrt();
                *b = bias;
                *c = corr;
            }
            if q == 2 {
                out.sigma_v_acc_m = acc.sqrt();
            }
        }
        // Step 4, every monitored mode: sigma_ss and the separation
        // against s0'.
        for k in 0..self.out.modes.len() {
            let Some(mode) = self.out.modes.get(k) else {
                break;
            };
            if mode.status != ModeStatus::Monitored {
                continue;
            }
            let ev = mode.events;
            if self.difference_rows(layout, &ev).is_err() {
                // A mode the downdate solved but the dense factor calls
                // singular: no adjusted estimate for this epoch.
                return Attempt::Dirty;
            }
            let Some(mode) = self.out.modes.get_mut(k) else {
                break;
            };
            for q in 0..3 {
                let (Some(&tq), Some(dk), Some(dq), Some(ss), Some(sep)) = (
                    tt.get(q),
                    self.scratch.d.get(q),
                    d_w.get(q),
                    mode.stats.sigma_ss_m.get_mut(q),
                    mode.stats.separation_m.get_mut(q),
                ) else {
                    continue;
                };
                if tq == zero {
                    continue;
                }
                let mut ss2 = zero;
                let mut x = zero;
                let sats = dk
                    .iter()
                    .zip(dq.iter())
                    .zip(self.geo.c_acc.iter().zip(self.geo.y.iter()))
                    .take(n);
                for ((&a, &b), (&ca, &y)) in sats {
                    let d = a - tq * b;
                    ss2 += d * d * ca;
                    x += d * y;
                }
                *ss = ss2.sqrt();
                *sep = x;
            }
        }
        // Steps 4-6 again on the adjusted quantities.
        self.out.unavailable = None;
        self.out.limits = super::Limits::default();
        self.separation_tests(cfg);
        if self.protection_levels(cfg, self.budget_share).is_err() {
            return Attempt::Dirty;
        }
        self.availability(cfg);
        let adjusted = configured(cfg, self.out.pl_add, self.out.pl_exact);
        if adjusted.vpl_m < plain.vpl_m || adjusted.hpl_m < plain.hpl_m {
            self.out.adjusted_t = t;
            Attempt::Kept
        } else {
            Attempt::Dirty
        }
    }
}

#[cfg(test)]
#[path = "adjusted_tests.rs"]
mod tests;
