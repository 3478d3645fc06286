//! Protection levels (SPEC §9.1 step 5): the root in x of
//!
//!   2 Q((x - b0) / sigma0) + sum_k p_k Q((x - T_k - b_k) / sigma_k) = rhs,
//!
//! per axis, where the left side decreases strictly in x. Two outputs:
//! the exact root (safeguarded Halley on the logarithm of the left side
//! inside the ADD's bracket, to `EXACT_TOL_M`), and the ADD's output, the
//! upper end of its bisection bracket once narrower than TOL_PL (SPEC
//! §9.1: why the published HPL is 14.5 m where the root is 14.416 m).
//! Evaluated in `f64`: the terms are handed over as `f64` whatever the
//! engine's precision, since they sit deep in the normal tail.

use super::tail::q_and_pdf;
use crate::stats::dist::normal_q_inv;

/// Convergence of the exact root (m).
pub const EXACT_TOL_M: f64 = 1e-10;
/// A Halley (or Newton) step this small is the last one (see `solve`).
const LAST_STEP_M: f64 = 1e-6;
/// Iteration cap of either search (never reached on valid input: the
/// bisection halves a bracket of at most a few hundred metres).
const MAX_ITER: usize = 200;

/// One term p Q((x - offset) / sigma) of the PL equation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Term {
    /// Weight p of the term (a probability).
    pub p: f64,
    /// Offset (the mode's bias or threshold), m.
    pub offset_m: f64,
    /// Standard deviation of the term, m.
    pub sigma_m: f64,
}

/// The PL equation of one axis: the fault-free term (weight 2), the
/// monitored modes and the right-hand side.
pub struct Equation<F> {
    /// The fault-free term, counted twice (both tails).
    pub fault_free: Term,
    /// Returns an iterator over the modes' terms; called once per
    /// evaluation.
    pub modes: F,
    /// The number of modes (for the ADD's upper bound).
    pub n_modes: usize,
    /// The right-hand side, the integrity budget of the axis.
    pub rhs: f64,
}

/// A term as the search's later evaluations read it (`FOLD_REL`): the
/// reciprocal of sigma formed once at the first evaluation, so that each
/// later evaluation multiplies instead of dividing three times per term
/// (z = (x - offset) / sigma, the slope p phi / sigma and f'' = slope z /
/// sigma). The same size as a [`Term`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Active {
    /// Weight p of the term (a probability).
    pub p: f64,
    /// Offset of the term, m.
    pub offset_m: f64,
    /// 1 / sigma (1/m).
    pub inv_sigma_per_m: f64,
}

impl Active {
    /// All zero (the derived `Default`), for `const fn` constructors.
    pub const ZERO: Self = Active {
        p: 0.0,
        offset_m: 0.0,
        inv_sigma_per_m: 0.0,
    };
    /// A mode's value, slope and f'' contribution at `x`: p Q(z),
    /// p phi(z) / sigma and p z phi(z) / sigma^2 with z = (x - offset) /
    /// sigma; beyond `Z_CUT`, the bound p Q(Z_CUT) and no slope.
    #[inline]
    fn at(&self, x: f64) -> (f64, f64, f64) {
        let z = (x - self.offset_m) * self.inv_sigma_per_m;
        if z > Z_CUT {
            return (self.p * Q_CUT, 0.0, 0.0);
        }
        self.at_z(z)
    }

    /// [`Self::at`] without the cut (the fault-free term).
    #[inline]
    fn at_uncut(&self, x: f64) -> (f64, f64, f64) {
        self.at_z((x - self.offset_m) * self.inv_sigma_per_m)
    }

    #[inline]
    fn at_z(&self, z: f64) -> (f64, f64, f64) {
        let (q, pdf) = q_and_pdf(z);
        let slope = self.p * pdf * self.inv_sigma_per_m;
        (self.p * q, slope, slope * z * self.inv_sigma_per_m)
    }
}

impl From<Term> for Active {
    fn from(t: Term) -> Self {
        Self {
            p: t.p,
            offset_m: t.offset_m,
            inv_sigma_per_m: 1.0 / t.sigma_m,
        }
    }
}

/// The left side, its first and second derivatives at one x.
#[derive(Debug, Clone, Copy)]
struct Eval {
    f: f64,
    d: f64,
    dd: f64,
}

/// The two answers for one axis.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Solution {
    /// The root, to `EXACT_TOL_M`.
    pub exact_m: f64,
    /// The ADD's bracket output at TOL_PL.
    pub add_m: f64,
}

/// Above this z a term p Q(z) is not evaluated: it is replaced by its
/// bound p Q(Z_CUT) (Q(10) = 7.6e-24), so the left side can only grow and
/// the PL only rise, by at most n_modes * Q(Z_CUT) / rhs relative in
/// probability (below 1e-12 for 1000 modes and rhs >= 1e-9).
const Z_CUT: f64 = 10.0;
/// Q(Z_CUT).
const Q_CUT: f64 = 7.619_853_024_160_527e-24;
/// A mode's term whose value at the bracket's lower end is at most
/// FOLD_REL rhs / (n_modes + 1) is *folded*: replaced by that value, a
/// constant, for the rest of the search. Every later evaluation is at
/// x >= the lower end, where the term is smaller (it decreases in x), so
/// the left side can only grow and the PL only rise; the folded terms
/// together add at most FOLD_REL rhs, i.e. the root moves up by at most
/// FOLD_REL rhs / |f'|, about FOLD_REL sigma / z (1e-13 m per metre of
/// sigma). At 30 satellites with pairs about 450 of 500 terms fold, so
/// the Halley iterations after the first touch only the ~40 that matter.
const FOLD_REL: f64 = 1e-13;
/// Distinct priors whose quantiles are cached per bracket.
const CACHE: usize = 16;

/// The two quantile memos of one right-hand side (the bracket's lower and
/// upper ends). The east and north axes share one: same right-hand side,
/// same priors, so the same quantiles. The fault-free term's quantiles
/// (prior 2) are memoised with the modes'. The engine keeps its memos
/// across epochs: a memo answers only for its own right-hand side and mode
/// count (replaced otherwise), so a repeated epoch configuration costs no
/// quantile at all.
#[derive(Clone, Copy)]
pub struct BracketCache {
    lo: QuantileCache,
    hi: QuantileCache,
}

impl BracketCache {
    /// Empty memos for `rhs` and `n_modes`.
    pub const fn new(rhs: f64, n_modes: usize) -> Self {
        Self {
            lo: QuantileCache::new(rhs),
            hi: QuantileCache::new(rhs / (n_modes as f64 + 1.0)),
        }
    }
}

/// A small memo of Q^-1(target / p) by p: the priors take few distinct
/// values (products of the ISM's probabilities).
#[derive(Clone, Copy)]
struct QuantileCache {
    keys: [f64; CACHE],
    vals: [Option<f64>; CACHE],
    len: usize,
    target: f64,
    /// The last prior asked and its answer (consecutive modes mostly share
    /// their prior: pairs, then satellite + constellation).
    last: (f64, Option<f64>),
}

impl QuantileCache {
    const fn new(target: f64) -> Self {
        Self {
            keys: [0.0; CACHE],
            vals: [None; CACHE],
            len: 0,
            target,
            last: (f64::NAN, None),
        }
    }

    /// Q^-1(target / p), or None if p <= target (the term never reaches it).
    fn get(&mut self, p: f64) -> Option<f64> {
        if !(p > self.target) {
            return None;
        }
        if p == self.last.0 {
            return self.last.1;
        }
        for (k, v) in self.keys.iter().zip(self.vals.iter()).take(self.len) {
            if *k == p {
                self.last = (p, *v);
                return *v;
            }
        }
        let v = normal_q_inv(self.target / p).ok();
        self.last = (p, v);
        if self.len < CACHE {
            if let (Some(k), Some(x)) = (self.keys.get_mut(self.len), self.vals.get_mut(self.len)) {
                *k = p;
                *x = v;
                self.len += 1;
            }
        }
        v
    }
}

impl<F, I> Equation<F>
where
    F: Fn() -> I,
    I: Iterator<Item = Term>,
{
    /// The left side and its derivative at `x` (terms beyond `Z_CUT`
    /// bounded, see there): over every mode, or, once folded (`FOLD_REL`),
    /// over the active terms plus the folded constant.
    fn eval(&self, x: f64, folded: Option<(&[Active], f64)>) -> Eval {
        let (f, d, dd) = Active::from(self.fault_free).at_uncut(x);
        let mut e = Eval { f, d: -d, dd };
        let mut add = |t: &Active| {
            let (f, d, dd) = t.at(x);
            e.f += f;
            e.d -= d;
            e.dd += dd;
        };
        match folded {
            Some((active, constant)) => {
                active.iter().for_each(&mut add);
                e.f += constant;
            }
            None => (self.modes)().for_each(|t| add(&Active::from(t))),
        }
        e
    }

    /// The first evaluation, at the bracket's lower end `x`: every mode,
    /// and the fold (`FOLD_REL`): the terms that stay active are copied to
    /// `scratch`. Returns f, f' and (active count, folded constant), or
    /// None for the latter if `scratch` is too small (then nothing folds).
    fn eval_and_fold(&self, x: f64, scratch: &mut [Active]) -> (Eval, Option<(usize, f64)>) {
        let (mut f, d0, mut dd) = Active::from(self.fault_free).at_uncut(x);
        let mut d = -d0;
        let limit = FOLD_REL * self.rhs / (self.n_modes as f64 + 1.0);
        let mut constant = 0.0;
        let mut n = 0usize;
        let mut fits = true;
        for t in (self.modes)() {
            let a = Active::from(t);
            let (v, slope, curv) = a.at(x);
            f += v;
            d -= slope;
            dd += curv;
            if v <= limit {
                constant += v;
            } else if let Some(slot) = scratch.get_mut(n) {
                *slot = a;
                n += 1;
            } else {
                fits = false;
            }
        }
        (
            Eval { f, d, dd },
            if fits { Some((n, constant)) } else { None },
        )
    }

    /// The ADD's initial bracket: the left side is at least any one term
    /// (lower end) and at most n_modes + 1 times the largest (upper end).
    pub fn bracket(&self) -> Option<(f64, f64)> {
        self.bracket_cached(&mut BracketCache::new(self.rhs, self.n_modes))
    }

    /// [`Self::bracket`] with memos that may already hold quantiles of the
    /// same right-hand side (replaced if they belong to another one).
    pub fn bracket_cached(&self, cache: &mut BracketCache) -> Option<(f64, f64)> {
        let share = self.rhs / (self.n_modes as f64 + 1.0);
        if cache.lo.target != self.rhs || cache.hi.target != share {
            *cache = BracketCache::new(self.rhs, self.n_modes);
        }
        let ff = self.fault_free;
        let BracketCache { lo: k_lo, hi: k_hi } = cache;
        // Q^-1(rhs / p_ff) and Q^-1(share / p_ff), through the memos (the
        // same expressions; None where the quantile does not exist).
        let mut lo = ff.offset_m + ff.sigma_m * k_lo.get(ff.p)?;
        let mut hi = ff.offset_m + ff.sigma_m * k_hi.get(ff.p)?;
        for t in (self.modes)() {
            if let Some(k) = k_lo.get(t.p) {
                lo = lo.max(t.offset_m + k * t.sigma_m);
            }
            if let Some(k) = k_hi.get(t.p) {
                hi = hi.max(t.offset_m + k * t.sigma_m);
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
    ///
    /// The exact root first (Halley on ln f from the lower end, safeguarded
    /// by bisection). The ADD's bisection is then replayed against it
    /// without evaluating: since f decreases, f(mid) > rhs exactly when
    /// mid < root, except within `GUARD_M` of the root, where f is
    /// evaluated as the ADD does.
    ///
    /// Without scratch nothing folds (`FOLD_REL`).
    pub fn solve(&self, tol_pl_m: f64) -> Option<Solution> {
        self.solve_cached(
            tol_pl_m,
            &mut BracketCache::new(self.rhs, self.n_modes),
            &mut [],
        )
    }

    /// [`Self::solve`] with shared bracket memos ([`BracketCache`]) and
    /// room for the active terms (`scratch`, at least `n_modes` long for
    /// the fold to apply whatever the sky).
    pub fn solve_cached(
        &self,
        tol_pl_m: f64,
        cache: &mut BracketCache,
        scratch: &mut [Active],
    ) -> Option<Solution> {
        const GUARD_M: f64 = 1e-6;
        let (lo0, hi0) = self.bracket_cached(cache)?;
        let (mut lo, mut hi) = (lo0, hi0);
        let ln_rhs = libm::log(self.rhs);
        let mut x = lo0;
        let (e0, fold) = self.eval_and_fold(lo0, scratch);
        let folded = match fold {
            Some((n, constant)) => scratch.get(..n).map(|a| (a as &[Active], constant)),
            None => None,
        };
        let mut first = Some(e0);
        for _ in 0..MAX_ITER {
            let Eval { f, d, dd } = match first.take() {
                Some(e) => e,
                None => self.eval(x, folded),
            };
            if f > self.rhs {
                lo = x;
            } else {
                hi = x;
            }
            // Halley on g = ln f - ln rhs (g' = f'/f, g'' = f''/f - g'^2,
            // cubic convergence), Newton where Halley's denominator is not
            // of the Newton step's sign, bisection outside the bracket.
            let newton = if f > 0.0 && d < 0.0 {
                let g = libm::log(f) - ln_rhs;
                let g1 = d / f;
                let g2 = dd / f - g1 * g1;
                let den = 2.0 * g1 * g1 - g * g2;
                if den > 0.0 {
                    -2.0 * g * g1 / den
                } else {
                    -g / g1
                }
            } else {
                f64::NAN
            };
            // Converged: the step is below the tolerance
            // (checked before the safeguard, which would otherwise bisect
            // when rounding puts x a hair on the wrong side of the root).
            // Halley converges cubically, Newton on ln f (its fallback)
            // quadratically: after a step below
            // `LAST_STEP_M` the error is about K step^2, with
            // K = |(ln f)'' / 2 (ln f)'| ~ 1 / (2 z sigma) per metre, which
            // is below 100 for any sigma above 5 mm at z > 1: under 1e-10 m
            // = EXACT_TOL_M. Take it and stop (one evaluation fewer than
            // checking it); the dense-reference tests hold it to 1e-9 m.
            if newton.abs() <= LAST_STEP_M {
                x += newton;
                break;
            }
            let mut next = x + newton;
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            x = next;
            if hi - lo <= EXACT_TOL_M {
                break;
            }
        }
        let root = x;
        // The ADD's bisection: keep the upper end.
        let (mut lo, mut hi) = (lo0, hi0);
        for _ in 0..MAX_ITER {
            if hi - lo <= tol_pl_m {
                break;
            }
            let mid = 0.5 * (lo + hi);
            let above = if (mid - root).abs() > GUARD_M {
                mid < root
            } else {
                self.eval(mid, folded).f > self.rhs
            };
            if above {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(Solution {
            exact_m: root,
            add_m: hi,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 200 modes, a dozen dominant and the rest far in the tail: the fold
    /// takes the negligible ones out, and the root with it equals the
    /// root without it (no scratch: nothing folds) to EXACT_TOL_M, never
    /// below it by more than that (the PL may only rise), and both agree
    /// with a plain bisection of the full equation.
    #[test]
    fn folding_keeps_the_root() {
        let mut terms = [Term::default(); 200];
        for (k, t) in terms.iter_mut().enumerate() {
            let kf = k as f64;
            *t = Term {
                p: 1e-5 * (1.0 + (kf * 0.37).sin().abs()),
                offset_m: if k < 12 { 4.0 + 0.3 * kf } else { 0.5 },
                sigma_m: if k < 12 {
                    2.0 + 0.1 * kf
                } else {
                    0.4 + 0.001 * kf
                },
            };
        }
        let eq = Equation {
            fault_free: Term {
                p: 2.0,
                offset_m: 0.3,
                sigma_m: 1.5,
            },
            modes: || terms.iter().copied(),
            n_modes: terms.len(),
            rhs: 1e-7,
        };
        let plain = eq.solve(0.01).unwrap();
        let mut scratch = [Active::default(); 200];
        let mut cache = BracketCache::new(eq.rhs, eq.n_modes);
        let (lo, _) = eq.bracket().unwrap();
        let (_, fold) = eq.eval_and_fold(lo, &mut scratch);
        let (active, constant) = fold.unwrap();
        assert!(active < 40 && constant > 0.0, "{active} active");
        let folded = eq.solve_cached(0.01, &mut cache, &mut scratch).unwrap();
        assert!(folded.exact_m >= plain.exact_m - EXACT_TOL_M);
        assert!((folded.exact_m - plain.exact_m).abs() <= EXACT_TOL_M);
        assert_eq!(folded.add_m, plain.add_m);
        // Independent: bisection of the full left side to 1e-12 m.
        let f = |x: f64| {
            2.0 * q_and_pdf((x - 0.3) / 1.5).0
                + terms
                    .iter()
                    .map(|t| t.p * q_and_pdf((x - t.offset_m) / t.sigma_m).0)
                    .sum::<f64>()
        };
        let (mut a, mut b) = (0.0f64, 100.0f64);
        while b - a > 1e-12 {
            let m = 0.5 * (a + b);
            if f(m) > eq.rhs {
                a = m;
            } else {
                b = m;
            }
        }
        assert!(
            (folded.exact_m - a).abs() <= 1e-9,
            "{} vs {a}",
            folded.exact_m
        );
    }
}

#[cfg(test)]
#[path = "pl_cov_tests.rs"]
mod cov_tests;
