//! Protection levels (SPEC §9.1 step 5): the root in x of
//!
//!   2 Q((x - b0) / sigma0) + sum_k p_k Q((x - T_k - b_k) / sigma_k) = rhs,
//!
//! per axis, where the left side decreases strictly in x. Two outputs:
//! the exact root (safeguarded Newton on the logarithm of the left side
//! inside the ADD's bracket, to `EXACT_TOL_M`), and the ADD's output, the
//! upper end of its bisection bracket once narrower than TOL_PL (SPEC
//! §9.1: why the published HPL is 14.5 m where the root is 14.416 m).
//! Evaluated in `f64`: the terms are handed over as `f64` whatever the
//! engine's precision, since they sit deep in the normal tail.

use crate::stats::dist::{normal_q, normal_q_inv};

/// Convergence of the exact root (m).
pub const EXACT_TOL_M: f64 = 1e-10;
/// Iteration cap of either search (never reached on valid input: the
/// bisection halves a bracket of at most a few hundred metres).
const MAX_ITER: usize = 200;

const INV_SQRT_2PI: f64 = 0.398_942_280_401_432_7;

/// One term p Q((x - offset) / sigma) of the PL equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Term {
    pub p: f64,
    pub offset_m: f64,
    pub sigma_m: f64,
}

/// The PL equation of one axis: the fault-free term (weight 2), the
/// monitored modes and the right-hand side.
pub struct Equation<F> {
    pub fault_free: Term,
    /// Returns an iterator over the modes' terms; called once per
    /// evaluation.
    pub modes: F,
    /// The number of modes (for the ADD's upper bound).
    pub n_modes: usize,
    pub rhs: f64,
}

/// The two answers for one axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Solution {
    /// The root, to `EXACT_TOL_M`.
    pub exact_m: f64,
    /// The ADD's bracket output at TOL_PL.
    pub add_m: f64,
}

impl<F, I> Equation<F>
where
    F: Fn() -> I,
    I: Iterator<Item = Term>,
{
    /// The left side and its derivative at `x`.
    fn eval(&self, x: f64) -> (f64, f64) {
        let t = self.fault_free;
        let z = (x - t.offset_m) / t.sigma_m;
        let mut f = t.p * normal_q(z);
        let mut d = -t.p * INV_SQRT_2PI * libm::exp(-0.5 * z * z) / t.sigma_m;
        for t in (self.modes)() {
            let z = (x - t.offset_m) / t.sigma_m;
            f += t.p * normal_q(z);
            d -= t.p * INV_SQRT_2PI * libm::exp(-0.5 * z * z) / t.sigma_m;
        }
        (f, d)
    }

    /// The x at which one term alone equals `target`, or None when the
    /// term never reaches it (p <= target).
    fn term_root(t: &Term, target: f64) -> Option<f64> {
        if !(t.p > target) {
            return None;
        }
        normal_q_inv(target / t.p)
            .ok()
            .map(|k| t.offset_m + k * t.sigma_m)
    }

    /// The ADD's initial bracket: the left side is at least any one term
    /// (lower end) and at most n_modes + 1 times the largest (upper end).
    pub fn bracket(&self) -> Option<(f64, f64)> {
        let share = self.rhs / (self.n_modes as f64 + 1.0);
        let mut lo = Self::term_root(&self.fault_free, self.rhs)?;
        let mut hi = Self::term_root(&self.fault_free, share)?;
        for t in (self.modes)() {
            if let Some(x) = Self::term_root(&t, self.rhs) {
                lo = lo.max(x);
            }
            if let Some(x) = Self::term_root(&t, share) {
                hi = hi.max(x);
            }
        }
        if lo.is_finite() && hi.is_finite() && lo <= hi {
            Some((lo, hi))
        } else {
            None
        }
    }

    /// Both answers; None if the bracket cannot be formed (non-finite
    /// terms), which the caller reports as unavailable.
    pub fn solve(&self, tol_pl_m: f64) -> Option<Solution> {
        let (lo0, hi0) = self.bracket()?;
        // The ADD's bisection: keep the upper end.
        let (mut lo, mut hi) = (lo0, hi0);
        for _ in 0..MAX_ITER {
            if hi - lo <= tol_pl_m {
                break;
            }
            let mid = 0.5 * (lo + hi);
            if self.eval(mid).0 > self.rhs {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let add_m = hi;
        // The exact root: Newton on ln f inside the bracket.
        let (mut lo, mut hi) = (lo0, hi0);
        let ln_rhs = libm::log(self.rhs);
        let mut x = 0.5 * (lo + hi);
        for _ in 0..MAX_ITER {
            let (f, d) = self.eval(x);
            if f > self.rhs {
                lo = x;
            } else {
                hi = x;
            }
            let mut next = if f > 0.0 && d < 0.0 {
                x - (libm::log(f) - ln_rhs) * f / d
            } else {
                f64::NAN
            };
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let step = (next - x).abs();
            x = next;
            if step <= EXACT_TOL_M || hi - lo <= EXACT_TOL_M {
                break;
            }
        }
        Some(Solution { exact_m: x, add_m })
    }
}

