//! Probability distributions for detection (SPEC §3) and protection levels
//! (SPEC §6), computed on the device: no tables per degree of freedom, no
//! allocation, no panics, and every loop has a fixed iteration cap.
//!
//! * Standard normal upper tail `Q(x)` and its inverse (starting points, and
//!   the closed forms for one degree of freedom).
//! * Regularised incomplete gamma `P(a, x)`, `Q(a, x)`: power series below
//!   `x = a + 1`, modified-Lentz continued fraction above. The common factor
//!   `x^a e^-x / Gamma(a + 1)` is evaluated in Loader's saddle-point form
//!   (`stirlerr` + `bd0`, C. Loader, "Fast and accurate computation of binomial
//!   probabilities", 2000) so it keeps full relative precision for large `a`
//!   instead of losing the digits of `a ln x - x - lgamma(a)`.
//! * Chi-square CDF, survival function and upper quantile (the detection
//!   threshold `T^2`, SPEC §3).
//! * Non-central chi-square CDF (Poisson mixture of central chi-squares) and
//!   the non-centrality `lambda` that gives a missed-detection probability
//!   `Pmd` at the threshold (the protection-level bias, SPEC §6).

use crate::error::RaimError;

/// Largest number of degrees of freedom (`n - m`) accepted by the chi-square
/// functions. Far above any receiver's channel count; it bounds the work.
pub const MAX_DOF: u32 = 200;

/// Largest non-centrality accepted by [`ncx2_cdf`]. The Poisson mixture needs
/// about `lambda / 2 + 9 sqrt(lambda / 2)` terms, so this bounds the work
/// (protection levels need `lambda` below about 1e4).
pub const MAX_LAMBDA: f64 = 1.0e5;

/// `1 / sqrt(2)` rounded to double.
const FRAC_1_SQRT_2: f64 = core::f64::consts::FRAC_1_SQRT_2;
/// `1 / sqrt(2) - FRAC_1_SQRT_2`: the rounding error of the constant above,
/// so `x / sqrt(2)` can be formed to about twice double precision.
const FRAC_1_SQRT_2_LO: f64 = -4.833_646_656_726_457e-17;
/// `1 / sqrt(pi)`.
const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;
/// `sqrt(2 pi)`.
const SQRT_2PI: f64 = 2.506_628_274_631_000_7;
/// `ln(sqrt(2 pi))`.
const LN_SQRT_2PI: f64 = 0.918_938_533_204_672_8;

/// Iteration cap of the incomplete-gamma series and continued fraction. Both
/// need about `9 sqrt(a)` terms in the worst case (`x` near `a`); this covers
/// `a` up to about 5e6, far beyond `MAX_DOF / 2 + MAX_LAMBDA / 2 + tail`.
const GAMMA_MAX_ITER: u32 = 20_000;
/// Iteration cap of the `bd0` series (it converges like `0.1^(2j)`).
const BD0_MAX_ITER: u32 = 64;
/// Newton/Halley iteration cap of the quantile functions (typically 2-6 are used).
const QUANTILE_MAX_ITER: u32 = 30;
/// Iteration cap of the root finder in [`ncx2_lambda`] (typically 8-12 are used).
const LAMBDA_MAX_ITER: u32 = 100;
/// Cap on the number of Poisson weights summed above (and, for the
/// normalisation, below) the mode in [`ncx2_cdf`]; `9 sqrt(MAX_LAMBDA / 2) + 50`
/// would do.
const NCX2_MAX_UPPER_TERMS: u32 = 10_000;
/// Relative size of the Poisson tails that [`ncx2_cdf`] drops.
const NCX2_TAIL_EPS: f64 = 1.0e-17;
/// Absolute size of a lower Poisson tail that is negligible whatever the sum.
const NCX2_TAIL_ABS: f64 = 1.0e-300;
/// In [`ncx2_cdf`], `ln g` below which the gamma density term is treated as
/// zero (it would be subnormal and the recurrence could not restart from it).
const NCX2_LN_G_START: f64 = -600.0;
/// Steps of the downward gamma-density recurrence between direct
/// re-evaluations: bounds the drift of the recurrence to ~16 ulp (64 steps
/// were measured to cost 1.3e-14 absolute in the CDF, 8 steps 2e-15).
const NCX2_RESYNC: u32 = 8;
/// Smallest magnitude the Lentz algorithm lets a denominator take.
const LENTZ_TINY: f64 = 1.0e-300;

// ---------------------------------------------------------------------------
// Input checks
// ---------------------------------------------------------------------------

/// Accept a probability strictly inside (0, 1); NaN is rejected.
fn check_probability(field: &'static str, p: f64) -> Result<f64, RaimError> {
    if p > 0.0 && p < 1.0 {
        Ok(p)
    } else {
        Err(RaimError::OutOfRange {
            field,
            value: p,
            min: 0.0,
            max: 1.0,
        })
    }
}

/// Accept 1..=MAX_DOF degrees of freedom.
fn check_dof(dof: u32) -> Result<f64, RaimError> {
    if dof == 0 || dof > MAX_DOF {
        Err(RaimError::InvalidDof { dof, max: MAX_DOF })
    } else {
        Ok(f64::from(dof))
    }
}

/// Accept any argument of a CDF except NaN (infinities have obvious limits).
fn check_x(x: f64) -> Result<f64, RaimError> {
    if x.is_nan() {
        Err(RaimError::OutOfRange {
            field: "x",
            value: x,
            min: f64::NEG_INFINITY,
            max: f64::INFINITY,
        })
    } else {
        Ok(x)
    }
}

// ---------------------------------------------------------------------------
// Standard normal
// ---------------------------------------------------------------------------

/// Upper tail of the standard normal, `Q(x) = 1 - Phi(x) = erfc(x / sqrt 2) / 2`.
///
/// Accurate to a few ulp relative in the far upper tail (down to the
/// underflow near `x = 38`): the rounding error of `x / sqrt 2`, which would
/// otherwise cost `x^2` ulp, is corrected to first order. NaN gives NaN.
pub fn normal_q(x: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x.is_infinite() {
        return if x > 0.0 { 0.0 } else { 1.0 };
    }
    let z = x * FRAC_1_SQRT_2;
    // Exact rounding error of the product plus the error of the constant.
    let z_err = libm::fma(x, FRAC_1_SQRT_2, -z) + x * FRAC_1_SQRT_2_LO;
    // erfc(z + e) = erfc(z) - e * 2/sqrt(pi) * exp(-z^2) + O(e^2); halved.
    0.5 * libm::erfc(z) - z_err * FRAC_1_SQRT_PI * libm::exp(-z * z)
}

/// Standard normal density.
fn normal_pdf(x: f64) -> f64 {
    libm::exp(-0.5 * x * x) / SQRT_2PI
}

/// Inverse of [`normal_q`]: the `x` with `Q(x) = p`, for `p` in (0, 1).
///
/// Acklam's rational approximation (relative error 1.2e-9) as the start,
/// then Halley steps on `Q` itself, so the result is the root of the
/// erfc-based `Q` to a few ulp, down to `p = 1e-300`. Below the normal range
/// (`p` subnormal) the density underflows and the start is returned.
/// Used for starting values and the one-dof closed form (SPEC §3).
///
/// # Errors
/// `OutOfRange { field: "p" }` if `p` is NaN or outside (0, 1).
pub fn normal_q_inv(p: f64) -> Result<f64, RaimError> {
    let p = check_probability("p", p)?;
    Ok(q_inv(p))
}

/// [`normal_q_inv`] without the range check; `p` must be in (0, 1).
fn q_inv(p: f64) -> f64 {
    // Work with the smaller tail: Q(-x) = 1 - Q(x), and 1 - p is exact for
    // p in [0.5, 1) (Sterbenz), so nothing is lost.
    let (tail, sign) = if p > 0.5 { (1.0 - p, -1.0) } else { (p, 1.0) };
    let mut x = -acklam_phi_inv(tail);
    for _ in 0..4 {
        let phi = normal_pdf(x);
        if phi <= 0.0 || !phi.is_finite() {
            break;
        }
        let u = (normal_q(x) - tail) / phi;
        // Halley: f = Q - p, f' = -phi, f'' = x phi.
        let step = u / (1.0 - 0.5 * x * u);
        if !step.is_finite() {
            break;
        }
        x += step;
        if step.abs() <= f64::EPSILON * x.abs() {
            break;
        }
    }
    sign * x
}

/// Acklam's approximation to `Phi^-1(p)` for `p` in (0, 0.5]
/// (relative error below 1.15e-9).
fn acklam_phi_inv(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    const P_LOW: f64 = 0.024_25;
    if p < P_LOW {
        let q = libm::sqrt(-2.0 * libm::log(p));
        let num = C.iter().fold(0.0, |acc, &c| acc * q + c);
        let den = D.iter().fold(0.0, |acc, &d| acc * q + d) * q + 1.0;
        num / den
    } else {
        let q = p - 0.5;
        let r = q * q;
        let num = A.iter().fold(0.0, |acc, &a| acc * r + a) * q;
        let den = B.iter().fold(0.0, |acc, &b| acc * r + b) * r + 1.0;
        num / den
    }
}

// ---------------------------------------------------------------------------
// Incomplete gamma
// ---------------------------------------------------------------------------

/// `stirlerr(a) = ln Gamma(a + 1) - (a + 1/2) ln a + a - ln sqrt(2 pi)` for
/// `a = 1/2, 1, 3/2, ..., 15` (computed with mpmath at 50 digits), the
/// half-integers that every chi-square shape `dof / 2 + j` hits.
const STIRLERR_HALVES: [f64; 30] = [
    0.153_426_409_720_027_36,    // 0.5
    0.081_061_466_795_327_26,    // 1.0
    0.054_814_121_051_917_65,    // 1.5
    0.041_340_695_955_409_3,     // 2.0
    0.033_162_873_519_936_29,    // 2.5
    0.027_677_925_684_998_34,    // 3.0
    0.023_746_163_656_297_496,   // 3.5
    0.020_790_672_103_765_093,   // 4.0
    0.018_488_450_532_673_187,   // 4.5
    0.016_644_691_189_821_193,   // 5.0
    0.015_134_973_221_917_378,   // 5.5
    0.013_876_128_823_070_748,   // 6.0
    0.012_810_465_242_920_227,   // 6.5
    0.011_896_709_945_891_77,    // 7.0
    0.011_104_559_758_206_917,   // 7.5
    0.010_411_265_261_972_096,   // 8.0
    0.009_799_416_126_158_804,   // 8.5
    0.009_255_462_182_712_733,   // 9.0
    0.008_768_700_134_139_386,   // 9.5
    0.008_330_563_433_362_87,    // 10.0
    0.007_934_114_564_314_02,    // 10.5
    0.007_573_675_487_951_841,   // 11.0
    0.007_244_554_301_320_383,   // 11.5
    0.006_942_840_107_209_53,    // 12.0
    0.006_665_247_032_707_682,   // 12.5
    0.006_408_994_188_004_207,   // 13.0
    0.006_171_712_263_039_458,   // 13.5
    0.005_951_370_112_758_847_5, // 14.0
    0.005_746_216_513_010_115_5, // 14.5
    0.005_554_733_551_962_801,   // 15.0
];

/// Stirling-series error `ln Gamma(a + 1) - (a + 1/2) ln a + a - ln sqrt(2 pi)`
/// for `a > 0`: table for half-integers up to 15, `lgamma` for other small
/// `a`, asymptotic series above 15 (Loader 2000).
fn stirlerr(a: f64) -> f64 {
    if a <= 15.0 {
        let twice = 2.0 * a;
        if twice == libm::floor(twice) {
            // 1 <= twice <= 30 here, so the cast is exact.
            if let Some(v) = (twice as usize)
                .checked_sub(1)
                .and_then(|i| STIRLERR_HALVES.get(i))
            {
                return *v;
            }
        }
        return libm::lgamma(a + 1.0) - (a + 0.5) * libm::log(a) + a - LN_SQRT_2PI;
    }
    const S0: f64 = 1.0 / 12.0;
    const S1: f64 = 1.0 / 360.0;
    const S2: f64 = 1.0 / 1260.0;
    const S3: f64 = 1.0 / 1680.0;
    const S4: f64 = 1.0 / 1188.0;
    let nn = a * a;
    if a > 500.0 {
        (S0 - S1 / nn) / a
    } else if a > 80.0 {
        (S0 - (S1 - S2 / nn) / nn) / a
    } else if a > 35.0 {
        (S0 - (S1 - (S2 - S3 / nn) / nn) / nn) / a
    } else {
        (S0 - (S1 - (S2 - (S3 - S4 / nn) / nn) / nn) / nn) / a
    }
}

/// Deviance term `bd0(a, x) = a ln(a / x) + x - a >= 0` for `a, x > 0`,
/// without cancellation (Loader 2000): a series in `(a - x) / (a + x)` near
/// `a = x`, and `a ((t - 1) - ln t)` with `t = x / a` elsewhere.
fn bd0(a: f64, x: f64) -> f64 {
    let diff = a - x;
    let total = a + x;
    if diff.abs() < 0.1 * total {
        let mut v = diff / total;
        let mut s = diff * v;
        let mut ej = 2.0 * a * v;
        v *= v;
        for j in 1..BD0_MAX_ITER {
            ej *= v;
            let next = s + ej / f64::from(2 * j + 1);
            if next == s {
                return next;
            }
            s = next;
        }
        return s;
    }
    let t = x / a;
    if t <= 0.0 || !t.is_finite() {
        return f64::INFINITY;
    }
    a * ((t - 1.0) - libm::log(t))
}

/// `x^a e^-x / Gamma(a + 1)` for `a >= 0` and finite `x > 0` (the Poisson
/// probability of `a` events at mean `x`), to a few ulp relative whenever the
/// result is not tiny.
fn poisson_term(a: f64, x: f64) -> f64 {
    if a < 0.5 {
        // Small shape: the logarithmic terms are small, no cancellation.
        return libm::exp(a * libm::log(x) - x - libm::lgamma(a + 1.0));
    }
    libm::exp(-stirlerr(a) - bd0(a, x)) / libm::sqrt(core::f64::consts::TAU * a)
}

/// Regularised incomplete gamma `(P(a, x), Q(a, x), x^a e^-x / Gamma(a + 1))`
/// for finite `a > 0` and finite `x > 0`.
///
/// Below `x = a + 1` the series `P = t * sum_n x^n / ((a+1)...(a+n))` (all
/// terms positive); above it the continued fraction for `Q` (modified Lentz).
/// The other tail is `1 - ` the computed one, which there is >= ~0.08, so
/// both tails keep near-full relative precision.
fn gamma_pq(a: f64, x: f64) -> (f64, f64, f64) {
    let t = poisson_term(a, x);
    if x < a + 1.0 {
        let mut term = 1.0;
        let mut sum = 1.0;
        let mut denom = a;
        for _ in 0..GAMMA_MAX_ITER {
            denom += 1.0;
            term *= x / denom;
            sum += term;
            if term <= sum * (0.5 * f64::EPSILON) {
                break;
            }
        }
        let p = (t * sum).min(1.0);
        (p, 1.0 - p, t)
    } else {
        // Q = x^a e^-x / Gamma(a) * 1/(x+1-a- 1(1-a)/(x+3-a- 2(2-a)/(x+5-a- ...)))
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / LENTZ_TINY;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..GAMMA_MAX_ITER {
            let fi = f64::from(i);
            let an = -fi * (fi - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < LENTZ_TINY {
                d = LENTZ_TINY;
            }
            c = b + an / c;
            if c.abs() < LENTZ_TINY {
                c = LENTZ_TINY;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() <= f64::EPSILON {
                break;
            }
        }
        let q = (a * t * h).clamp(0.0, 1.0);
        (1.0 - q, q, t)
    }
}

/// Regularised lower incomplete gamma `P(a, x) = gamma(a, x) / Gamma(a)`.
///
/// Series below `x = a + 1`, Lentz continued fraction above; relative
/// accuracy ~1e-14 in both tails for `a` up to ~1e5 (work grows like
/// `sqrt(a)`, capped). The chi-square CDF is `P(dof/2, x/2)` (SPEC §3).
/// Returns NaN if `a` is not finite and positive or `x` is NaN; `x <= 0`
/// gives 0 and `x = inf` gives 1.
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if !(a > 0.0 && a.is_finite()) || x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    if x.is_infinite() {
        return 1.0;
    }
    gamma_pq(a, x).0
}

/// Regularised upper incomplete gamma `Q(a, x) = 1 - P(a, x)`, computed
/// directly in its own tail (see [`gamma_p`] for accuracy and edge cases).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if !(a > 0.0 && a.is_finite()) || x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x.is_infinite() {
        return 0.0;
    }
    gamma_pq(a, x).1
}

// ---------------------------------------------------------------------------
// Central chi-square
// ---------------------------------------------------------------------------

/// `(cdf, sf, x^a e^-x / Gamma(a + 1))` of chi-square with `k` dof at
/// finite `x > 0`, where `a = k / 2` and the last term is at `x / 2`.
fn chi2_parts(x: f64, k: f64) -> (f64, f64, f64) {
    let y = 0.5 * x;
    if y <= 0.0 {
        return (0.0, 1.0, 0.0);
    }
    gamma_pq(0.5 * k, y)
}

/// Chi-square CDF `P(X <= x)` with `dof` degrees of freedom, `P(dof/2, x/2)`.
/// `x <= 0` gives 0, `x = inf` gives 1.
///
/// # Errors
/// `InvalidDof` for `dof` outside 1..=MAX_DOF; `OutOfRange { field: "x" }`
/// for NaN `x`.
pub fn chi2_cdf(x: f64, dof: u32) -> Result<f64, RaimError> {
    let k = check_dof(dof)?;
    let x = check_x(x)?;
    if x <= 0.0 {
        Ok(0.0)
    } else if x.is_infinite() {
        Ok(1.0)
    } else {
        Ok(chi2_parts(x, k).0)
    }
}

/// Chi-square survival function (upper tail) `P(X > x)`, `Q(dof/2, x/2)`,
/// accurate to ~1e-14 relative far into the tail: this is the false-alarm
/// probability of the detection test statistic (SPEC §3).
///
/// # Errors
/// As [`chi2_cdf`].
pub fn chi2_sf(x: f64, dof: u32) -> Result<f64, RaimError> {
    let k = check_dof(dof)?;
    let x = check_x(x)?;
    if x <= 0.0 {
        Ok(1.0)
    } else if x.is_infinite() {
        Ok(0.0)
    } else {
        Ok(chi2_parts(x, k).1)
    }
}

/// Detection threshold `T^2` (SPEC §3): the `x` with `chi2_sf(x, dof) = pfa`.
///
/// Start: exact closed forms for one dof (`Q^-1(pfa/2)^2`) and two dof
/// (`-2 ln pfa`), Wilson-Hilferty otherwise (small-`x` power law when
/// Wilson-Hilferty goes negative). Then Halley steps on `ln sf(x) - ln pfa`
/// (or `ln cdf - ln(1 - pfa)` for `pfa > 1/2`), safeguarded by a bracket.
/// The log makes the function nearly linear in the far tail, so at most a
/// handful of steps are needed; the result is the root of this module's `sf`
/// to ~1e-15 relative.
///
/// # Errors
/// `OutOfRange { field: "pfa" }` for `pfa` NaN or outside (0, 1);
/// `InvalidDof` for `dof` outside 1..=MAX_DOF.
pub fn chi2_quantile_upper(pfa: f64, dof: u32) -> Result<f64, RaimError> {
    let pfa = check_probability("pfa", pfa)?;
    let k = check_dof(dof)?;
    Ok(chi2_quantile_upper_iter(pfa, k).0)
}

/// Starting value for the upper chi-square quantile, `pfa` in (0, 1).
fn chi2_quantile_start(pfa: f64, k: f64) -> f64 {
    if k == 1.0 {
        let z = q_inv(0.5 * pfa);
        return z * z;
    }
    if k == 2.0 {
        return -2.0 * libm::log(pfa);
    }
    let h = 2.0 / (9.0 * k);
    let c = 1.0 - h + q_inv(pfa) * libm::sqrt(h);
    if c > 0.1 {
        return k * c * c * c;
    }
    // Lower tail, small x: cdf ~ (x/2)^a / Gamma(a + 1).
    let a = 0.5 * k;
    2.0 * libm::exp((libm::log(1.0 - pfa) + libm::lgamma(a + 1.0)) / a)
}

/// Upper chi-square quantile and the number of Halley steps taken; `pfa` in
/// (0, 1) and `k` in 1..=MAX_DOF already checked.
fn chi2_quantile_upper_iter(pfa: f64, k: f64) -> (f64, u32) {
    let a = 0.5 * k;
    // Solve in the smaller tail: T(x) = sf(x) (upper) or cdf(x) (lower).
    let upper = pfa <= 0.5;
    let target = if upper { pfa } else { 1.0 - pfa };
    let ln_target = libm::log(target);
    let mut lo = 0.0_f64;
    let mut hi = f64::INFINITY;
    let mut x = chi2_quantile_start(pfa, k);
    if !(x > 0.0 && x.is_finite()) {
        x = k;
    }
    let mut iterations = 0;
    while iterations < QUANTILE_MAX_ITER {
        iterations += 1;
        let (cdf, sf, t) = chi2_parts(x, k);
        let tail = if upper { sf } else { cdf };
        // Density: 0.5 (x/2)^(a-1) e^(-x/2) / Gamma(a) = t a / x.
        let pdf = t * a / x;
        let usable = tail > 0.0 && pdf > 0.0;
        if !usable {
            // Underflow: the tail is far from the target; bisect.
            if (tail > 0.0) == upper {
                lo = x;
            } else {
                hi = x;
            }
            x = bisect(lo, hi, x);
            continue;
        }
        // ln(T / target) resolves f near the root to ~1 ulp of 1 (the
        // difference of the two logarithms would be quantised to ulp(ln p)).
        let ratio = tail / target;
        let f = if ratio > 0.0 && ratio.is_finite() {
            libm::log(ratio)
        } else {
            libm::log(tail) - ln_target
        };
        if f == 0.0 {
            break;
        }
        // f > 0: the tail is too large; for the upper tail x is too small.
        if (f > 0.0) == upper {
            lo = x;
        } else {
            hi = x;
        }
        // d/dx ln T = -+ pdf / T; second derivative via pdf'/pdf = (a-1)/x - 1/2.
        let r = if upper { -pdf / tail } else { pdf / tail };
        let r2_over_r = ((a - 1.0) / x - 0.5) - r; // f'' / f'
        let newton = -f / r;
        let denom = 1.0 + 0.5 * newton * r2_over_r;
        let step = if denom > 0.5 && denom < 2.0 {
            newton / denom
        } else {
            newton
        };
        if step.abs() <= 2.0 * f64::EPSILON * x {
            // Converged: the step is below rounding of x.
            x += step;
            break;
        }
        if hi - lo <= 4.0 * f64::EPSILON * x {
            // Bracketed to a few ulp: rounding noise in f decides the rest.
            break;
        }
        let next = x + step;
        x = if next > lo && next < hi && next.is_finite() {
            next
        } else {
            bisect(lo, hi, x)
        };
    }
    (x, iterations)
}

/// A point strictly inside `(lo, hi)`, with `hi` possibly infinite.
fn bisect(lo: f64, hi: f64, x: f64) -> f64 {
    if hi.is_finite() {
        0.5 * (lo + hi)
    } else {
        2.0 * x.max(lo).max(1.0)
    }
}

// ---------------------------------------------------------------------------
// Non-central chi-square
// ---------------------------------------------------------------------------

/// Non-central chi-square CDF `P(X <= x)`, `X ~ ncx2(dof, lambda)`: the
/// missed-detection probability of a fault of non-centrality `lambda` at
/// threshold `x = T^2` (SPEC §3, §6).
///
/// `F = sum_j Pois(j; lambda/2) P(dof/2 + j, x/2)`. The range of `j` is set
/// by the Poisson weights around the mode (dropping relative tails below
/// 1e-17, Ding 1992 / Benton-Krishnamoorthy 2003); `P` is evaluated directly
/// only at the top of the range and then carried down with the exact,
/// cancellation-free recurrence `P(a - 1, y) = P(a, y) + y^(a-1) e^-y / Gamma(a)`,
/// so every term is positive and the sum keeps ~1e-14 relative accuracy.
/// `x <= 0` gives 0, `x = inf` gives 1, `lambda = 0` is the central CDF.
///
/// # Errors
/// `InvalidDof` for `dof` outside 1..=MAX_DOF; `OutOfRange` for NaN `x`
/// (`field: "x"`) or `lambda` NaN, negative or above [`MAX_LAMBDA`]
/// (`field: "lambda"`).
pub fn ncx2_cdf(x: f64, dof: u32, lambda: f64) -> Result<f64, RaimError> {
    let k = check_dof(dof)?;
    let x = check_x(x)?;
    if !(0.0..=MAX_LAMBDA).contains(&lambda) {
        return Err(RaimError::OutOfRange {
            field: "lambda",
            value: lambda,
            min: 0.0,
            max: MAX_LAMBDA,
        });
    }
    if x <= 0.0 {
        Ok(0.0)
    } else if x.is_infinite() {
        Ok(1.0)
    } else {
        Ok(ncx2_cdf_unchecked(x, k, lambda))
    }
}

/// [`ncx2_cdf`] for finite `x > 0`, checked `k` and `0 <= lambda <= MAX_LAMBDA`.
fn ncx2_cdf_unchecked(x: f64, k: f64, lambda: f64) -> f64 {
    let mu = 0.5 * lambda;
    if mu <= 0.0 {
        return chi2_parts(x, k).0;
    }
    let y = 0.5 * x;
    if y <= 0.0 {
        return 0.0;
    }
    let a0 = 0.5 * k;
    let mode = libm::floor(mu);
    let w_mode = if mode == 0.0 {
        libm::exp(-mu)
    } else {
        poisson_term(mode, mu)
    };

    // Upper end of the Poisson range: sum_{i > j} w_i <= w_{j+1} / (1 - mu/(j+2)).
    // Dropping it costs at most that fraction of the sum, since P(a, y)
    // decreases with a.
    // The weights are also summed, over the same range and the matching
    // lower range, to normalise the mixture: that cancels the rounding of
    // w_mode, a factor common to all weights.
    let mut j_hi = mode;
    let mut w = w_mode;
    let mut w_total = w_mode;
    for _ in 0..NCX2_MAX_UPPER_TERMS {
        let w_next = w * mu / (j_hi + 1.0);
        let bound = w_next / (1.0 - mu / (j_hi + 2.0));
        if bound <= NCX2_TAIL_EPS {
            break;
        }
        j_hi += 1.0;
        w = w_next;
        w_total += w;
    }
    let mut w_low = w_mode;
    let mut j_low = mode;
    for _ in 0..NCX2_MAX_UPPER_TERMS {
        if j_low <= 0.0 {
            break;
        }
        // sum_{i < j} w_i <= w_{j-1} / (1 - (j-1)/mu) below the mode.
        w_low *= j_low / mu;
        w_total += w_low;
        j_low -= 1.0;
        if w_low / (1.0 - (j_low - 1.0).max(0.0) / mu) <= NCX2_TAIL_EPS {
            break;
        }
    }

    // Walk down from j_hi. `g` is y^(a-1) e^-y / Gamma(a) at a = a0 + j.
    // While g would underflow (a far above y) the terms are negligible and
    // only ln g is tracked; the recurrence starts where g is representable.
    // j_hi <= MAX_LAMBDA / 2 + NCX2_MAX_UPPER_TERMS, so the cast is exact.
    let mut j = j_hi as u32;
    let mut a = a0 + j_hi;
    let ln_y = libm::log(y);
    // ln of x^a e^-x / Gamma(a + 1) in Loader's form (a >= 1/2 here), which
    // stays finite where the term itself underflows.
    let mut ln_g = -stirlerr(a) - bd0(a, y) - 0.5 * libm::log(core::f64::consts::TAU * a)
        + libm::log(a)
        - ln_y;
    let mut started = false;
    let mut p = 0.0;
    let mut g = 0.0;
    let mut since_sync = 0;
    let mut sum = 0.0;
    let steps = j;
    for _ in 0..=steps {
        if !started && (ln_g >= NCX2_LN_G_START || a <= y + 1.0) {
            let (pj, _, t) = gamma_pq(a, y);
            p = pj;
            g = t * a / y;
            started = true;
            since_sync = 0;
        }
        if started {
            sum += w * p;
        }
        if j == 0 {
            break;
        }
        let jf = f64::from(j);
        if jf <= mode {
            // Lower tail: sum_{i < j} w_i <= w_{j-1} / (1 - (j-1)/mu), each P <= 1.
            let w_prev = w * jf / mu;
            let bound = w_prev / (1.0 - (jf - 1.0) / mu);
            if bound <= NCX2_TAIL_EPS * sum || bound <= NCX2_TAIL_ABS {
                break;
            }
        }
        // Step a -> a - 1.
        if started {
            p += g;
            since_sync += 1;
            if since_sync >= NCX2_RESYNC {
                g = poisson_term(a - 1.0, y) * (a - 1.0) / y;
                since_sync = 0;
            } else {
                g *= (a - 1.0) / y;
            }
        } else {
            ln_g += libm::log((a - 1.0) / y);
        }
        j -= 1;
        a -= 1.0;
        let jf = f64::from(j);
        w = if jf == mode {
            w_mode
        } else {
            w * (jf + 1.0) / mu
        };
    }
    (sum / w_total).clamp(0.0, 1.0)
}

/// Protection-level non-centrality (SPEC §6): the `lambda` with
/// `ncx2_cdf(T^2, dof, lambda) = pmd`, `T^2 = chi2_quantile_upper(pfa, dof)`.
///
/// Brent's method on `s = sqrt(lambda)` for `ln F(s^2) - ln pmd`, bracketed by
/// `[0, T + Q^-1(pmd)]` (the upper end is safe: the mean-direction component
/// alone gives `F <= Phi(T - s)`). Converged to 1e-13 relative in `s`,
/// typically within 10-15 CDF evaluations. If `pmd >= 1 - pfa` even a zero
/// bias is missed that often, and 0 is returned.
///
/// # Errors
/// `OutOfRange` for `pfa` or `pmd` NaN or outside (0, 1) (`field: "pfa"` /
/// `"pmd"`); `InvalidDof` for `dof` outside 1..=MAX_DOF.
pub fn ncx2_lambda(pfa: f64, pmd: f64, dof: u32) -> Result<f64, RaimError> {
    let pfa = check_probability("pfa", pfa)?;
    let pmd = check_probability("pmd", pmd)?;
    let k = check_dof(dof)?;
    Ok(ncx2_lambda_iter(pfa, pmd, k).0)
}

/// [`ncx2_lambda`] on checked inputs; also returns the number of CDF evaluations.
fn ncx2_lambda_iter(pfa: f64, pmd: f64, k: f64) -> (f64, u32) {
    let threshold = chi2_quantile_upper_iter(pfa, k).0;
    let f_zero = chi2_parts(threshold, k).0;
    if pmd >= f_zero {
        return (0.0, 1);
    }
    let ln_pmd = libm::log(pmd);
    let mut evaluations = 1;
    let mut objective = |s: f64| -> f64 {
        evaluations += 1;
        let f = ncx2_cdf_unchecked(threshold, k, (s * s).min(MAX_LAMBDA));
        // ln(smallest subnormal) is -744.4, so -800 keeps the sign right.
        let ln_f = if f > 0.0 { libm::log(f) } else { -800.0 };
        ln_f - ln_pmd
    };
    let s_hi = (libm::sqrt(threshold) + q_inv(pmd)).max(f64::MIN_POSITIVE);
    let root = brent(&mut objective, 0.0, libm::log(f_zero) - ln_pmd, s_hi);
    (root * root, evaluations)
}

/// Brent's root finder on `[a, b]` with `f(a) = fa > 0` given; relative
/// tolerance 1e-13 and [`LAMBDA_MAX_ITER`] iterations at most. Returns the
/// best estimate of the root (the bracket end where `f` is smallest).
fn brent(f: &mut impl FnMut(f64) -> f64, a: f64, fa: f64, b: f64) -> f64 {
    const REL_TOL: f64 = 1.0e-13;
    let mut a = a;
    let mut fa = fa;
    let mut b = b;
    let mut fb = f(b);
    if fb >= 0.0 {
        // F(b) <= pmd in exact arithmetic (see ncx2_lambda), so this is
        // rounding: for one dof the bound is tight up to Phi(-T - s) ~ 1e-30,
        // and `b` is then the root to rounding.
        return b;
    }
    let mut c = b;
    let mut fc = fb;
    let mut d = b - a;
    let mut e = d;
    for _ in 0..LAMBDA_MAX_ITER {
        if (fb > 0.0 && fc > 0.0) || (fb < 0.0 && fc < 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = REL_TOL * b.abs() + f64::MIN_POSITIVE;
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            return b;
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q) = if a == c {
                (2.0 * xm * s, 1.0 - s)
            } else {
                let q = fa / fc;
                let r = fb / fc;
                (
                    s * (2.0 * xm * q * (q - r) - (b - a) * (r - 1.0)),
                    (q - 1.0) * (r - 1.0) * (s - 1.0),
                )
            };
            if p > 0.0 {
                q = -q;
            }
            p = p.abs();
            let min1 = 3.0 * xm * q - (tol * q).abs();
            let min2 = (e * q).abs();
            if 2.0 * p < min1.min(min2) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        if d.abs() > tol {
            b += d;
        } else {
            b += if xm > 0.0 { tol } else { -tol };
        }
        fb = f(b);
    }
    b
}

/// Protection-level bias factor `pbias = sqrt(lambda)` (SPEC §6), the fault
/// size in units of the test-statistic sigma that is missed with probability
/// `pmd` at false-alarm probability `pfa`.
///
/// # Errors
/// As [`ncx2_lambda`].
pub fn pbias(pfa: f64, pmd: f64, dof: u32) -> Result<f64, RaimError> {
    Ok(libm::sqrt(ncx2_lambda(pfa, pmd, dof)?))
}

#[cfg(test)]
#[path = "dist_edge_tests.rs"]
mod edge_tests;

#[cfg(test)]
#[allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    /// SPEC §3 false-alarm probability per sample (1e-5/h over ~30 samples).
    const PFA_SPEC: f64 = 3.3333e-7;
    /// SPEC §6 missed-detection probability.
    const PMD_SPEC: f64 = 1.0e-3;
    /// SPEC §3 exact sqrt(T^2) for dof 1..=10, rounded to 5 decimals.
    const SQRT_T2_EXACT: [f64; 10] = [
        5.10356, 5.46153, 5.73840, 5.97506, 6.18611, 6.37884, 6.55756, 6.72508, 6.88335, 7.03383,
    ];
    /// SPEC §3 l3nav table of sqrt(T^2), dof 1..=10 (good to ~3e-4 only).
    const SQRT_T2_L3NAV: [f64; 10] = [
        5.10383, 5.46152, 5.73854, 5.97522, 6.18628, 6.37900, 6.55774, 6.72514, 6.88354, 7.03383,
    ];
    /// SPEC §6 pbias for PFA_SPEC, PMD_SPEC, dof 1..=10, rounded to 3 decimals.
    const PBIAS_SPEC: [f64; 10] = [
        8.194, 8.479, 8.687, 8.860, 9.009, 9.142, 9.263, 9.375, 9.479, 9.576,
    ];
    /// Absolute tolerance on sqrt(T^2) (sigma units) against 5-decimal values.
    const TOL_SQRT_T2_EXACT: f64 = 6.0e-6;
    /// Absolute tolerance on sqrt(T^2) (sigma units) against the l3nav table.
    const TOL_SQRT_T2_L3NAV: f64 = 3.0e-4;
    /// Absolute tolerance on pbias (sigma units) against 3-decimal values.
    const TOL_PBIAS: f64 = 6.0e-4;

    /// Relative tolerance (dimensionless) of chi2 cdf/sf against statrs.
    const TOL_STATRS_REL: f64 = 1.0e-12;
    /// Relative tolerance (dimensionless) of the quantile against statrs.
    const TOL_STATRS_QUANTILE_REL: f64 = 1.0e-9;
    /// Relative tolerance (dimensionless) of the round trip sf(quantile(p)) = p.
    const TOL_ROUND_TRIP_REL: f64 = 1.0e-12;
    /// Relative tolerance (dimensionless) against 17-digit mpmath references.
    const TOL_MPMATH_REL: f64 = 1.0e-13;
    /// Absolute tolerance (probability) of the non-central CDF.
    const TOL_NCX2_ABS: f64 = 1.0e-12;
    /// Relative tolerance (dimensionless) of the non-central CDF where the
    /// reference is small.
    const TOL_NCX2_REL: f64 = 1.0e-12;
    /// Relative tolerance (dimensionless) of the normal round trip Q(Q^-1(p)) = p,
    /// on top of the unavoidable |x| * ulp(x) from rounding x itself.
    const TOL_NORMAL_ROUND_TRIP_REL: f64 = 1.0e-13;
    /// Absolute tolerance (probability) of Q(-x) = 1 - Q(x): one ulp of 1.
    const TOL_SYMMETRY_ABS: f64 = f64::EPSILON;
    /// Absolute tolerance (probability) of cdf + sf = 1.
    const TOL_CDF_PLUS_SF: f64 = 1.0e-14;
    /// Relative tolerance (dimensionless) of the non-centrality root.
    const TOL_LAMBDA_ROOT_REL: f64 = 1.0e-10;

    fn rel_err(value: f64, reference: f64) -> f64 {
        ((value - reference) / reference).abs()
    }

    /// Verifies: SPEC-3
    #[test]
    fn threshold_matches_spec_tables() {
        for dof in 1..=10u32 {
            let t = chi2_quantile_upper(PFA_SPEC, dof).unwrap().sqrt();
            let i = (dof - 1) as usize;
            assert!(
                (t - SQRT_T2_EXACT[i]).abs() <= TOL_SQRT_T2_EXACT,
                "dof {dof}: {t} vs exact {}",
                SQRT_T2_EXACT[i]
            );
            assert!(
                (t - SQRT_T2_L3NAV[i]).abs() <= TOL_SQRT_T2_L3NAV,
                "dof {dof}: {t} vs l3nav {}",
                SQRT_T2_L3NAV[i]
            );
        }
    }

    /// Verifies: SPEC-6
    #[test]
    fn pbias_matches_spec_table() {
        for dof in 1..=10u32 {
            let p = pbias(PFA_SPEC, PMD_SPEC, dof).unwrap();
            let reference = PBIAS_SPEC[(dof - 1) as usize];
            assert!(
                (p - reference).abs() <= TOL_PBIAS,
                "dof {dof}: {p} vs {reference}"
            );
        }
    }

    #[test]
    fn ncx2_lambda_is_a_root() {
        for dof in [1u32, 2, 3, 7, 10, 30, 100, MAX_DOF] {
            for (pfa, pmd) in [
                (PFA_SPEC, PMD_SPEC),
                (1e-9, 1e-7),
                (1e-2, 0.3),
                (1e-12, 1e-9),
            ] {
                let (lambda, evaluations) = ncx2_lambda_iter(pfa, pmd, f64::from(dof));
                let t2 = chi2_quantile_upper(pfa, dof).unwrap();
                let f = ncx2_cdf(t2, dof, lambda).unwrap();
                // dF/dlambda is O(F), so F's relative error bounds lambda's.
                assert!(
                    rel_err(f, pmd) <= TOL_LAMBDA_ROOT_REL,
                    "dof {dof} pfa {pfa} pmd {pmd}: F = {f}"
                );
                assert!(evaluations <= 30, "{evaluations} CDF evaluations");
            }
        }
        // A miss probability above 1 - pfa is met with no bias at all.
        assert_eq!(ncx2_lambda(0.1, 0.95, 3).unwrap(), 0.0);
    }

    #[test]
    fn normal_q_known_values() {
        assert_eq!(normal_q(0.0), 0.5);
        assert!(rel_err(normal_q(1.959_963_984_540_054), 0.025) <= 1e-15);
        // Published two-decimal-place z for 1e-7: 5.1993376 (8 digits).
        assert!(rel_err(normal_q(5.199_337_6), 1e-7) <= 1e-7);
        assert_eq!(normal_q(f64::INFINITY), 0.0);
        assert_eq!(normal_q(f64::NEG_INFINITY), 1.0);
        assert!(normal_q(f64::NAN).is_nan());
        for i in 0..=400 {
            let x = f64::from(i) * 0.02;
            let asymmetry = (normal_q(-x) - (1.0 - normal_q(x))).abs();
            assert!(asymmetry <= TOL_SYMMETRY_ABS, "x = {x}");
        }
    }

    #[test]
    fn normal_q_inv_round_trip() {
        // Log grid from 1e-300 to 0.5, 20 points per decade.
        for i in 0..=6000 {
            let p = 10f64.powf(-300.0 + f64::from(i) * 0.05).min(0.5);
            let x = normal_q_inv(p).unwrap();
            // Q changes by |x| ulp(x) relative per ulp of x: the floor of any
            // round trip (1.3e-13 at p = 1e-300).
            let ulp_floor = x.abs() * (x.abs() * f64::EPSILON);
            let err = rel_err(normal_q(x), p);
            assert!(
                err <= TOL_NORMAL_ROUND_TRIP_REL.max(ulp_floor),
                "p = {p:e}: x = {x}, rel err {err:e}"
            );
            if p >= 1e-16 {
                // 1 - p is rounded; its exact complement is 1 - (1 - p).
                let minus = normal_q_inv(1.0 - p).unwrap();
                let plus = normal_q_inv(1.0 - (1.0 - p)).unwrap();
                assert_eq!(minus, -plus, "p = {p:e}");
            }
        }
        assert_eq!(normal_q_inv(0.5).unwrap(), 0.0);
        assert!((normal_q_inv(0.025).unwrap() - 1.959_963_984_540_054).abs() <= 4e-16);
    }

    #[test]
    fn chi2_matches_statrs() {
        let xs = [
            1e-3, 0.1, 0.5, 1.0, 2.0, 3.7, 5.0, 10.0, 20.0, 33.3, 40.0, 70.0, 100.0, 150.0, 250.0,
        ];
        for dof in 1..=60u32 {
            let reference = ChiSquared::new(f64::from(dof)).unwrap();
            for &x in &xs {
                let (cdf, sf) = (chi2_cdf(x, dof).unwrap(), chi2_sf(x, dof).unwrap());
                let (rc, rs) = (reference.cdf(x), reference.sf(x));
                if rc > 1e-300 {
                    assert!(
                        rel_err(cdf, rc) <= TOL_STATRS_REL,
                        "cdf dof {dof} x {x}: {cdf:e} vs {rc:e}"
                    );
                }
                if rs > 1e-300 {
                    assert!(
                        rel_err(sf, rs) <= TOL_STATRS_REL,
                        "sf dof {dof} x {x}: {sf:e} vs {rs:e}"
                    );
                }
            }
        }
    }

    /// Verifies: SPEC-3
    #[test]
    fn chi2_far_tails_match_mpmath() {
        // (dof, x, cdf, sf) from mpmath 1.3 gammainc at 40 digits.
        const CASES: [(u32, f64, f64, f64); 5] = [
            (3, 400.0, 1.0, 2.213_886_593_101_117_7e-86),
            (30, 1000.0, 1.0, 5.131_435_321_572_533e-191),
            (60, 1.0, 2.164_467_298_149_864_5e-42, 1.0),
            (200, 30.0, 1.564585768929862e-47, 1.0),
            (1, 1400.0, 1.0, 2.101_014_516_264_217_5e-306),
        ];
        for (dof, x, cdf, sf) in CASES {
            assert!(
                rel_err(chi2_cdf(x, dof).unwrap(), cdf) <= TOL_MPMATH_REL,
                "dof {dof} x {x}"
            );
            assert!(
                rel_err(chi2_sf(x, dof).unwrap(), sf) <= TOL_MPMATH_REL,
                "dof {dof} x {x}"
            );
        }
        // (dof, pfa, quantile) from mpmath findroot at 40 digits.
        const QUANTILES: [(u32, f64, f64); 8] = [
            (1, 1e-12, 50.844_127_911_818_156),
            (4, 1e-9, 47.87945573114795),
            (10, 1e-12, 78.47164656283849),
            (37, 1e-6, 93.05055051639779),
            (100, 1e-12, 233.810_567_959_207_81),
            (200, 1e-12, 374.495_910_727_132_9),
            (200, 1e-3, 267.5405278227572),
            (3, 1e-15, 72.94251784144284),
        ];
        for (dof, pfa, q) in QUANTILES {
            let got = chi2_quantile_upper(pfa, dof).unwrap();
            assert!(
                rel_err(got, q) <= TOL_MPMATH_REL,
                "dof {dof} pfa {pfa}: {got} vs {q}"
            );
        }
    }

    #[test]
    fn quantile_matches_statrs_and_round_trips() {
        for dof in 1..=MAX_DOF {
            let reference = ChiSquared::new(f64::from(dof)).unwrap();
            for pfa in [1e-1, 1e-2, 1e-3] {
                let q = chi2_quantile_upper(pfa, dof).unwrap();
                let r = reference.inverse_cdf(1.0 - pfa);
                assert!(
                    rel_err(q, r) <= TOL_STATRS_QUANTILE_REL,
                    "dof {dof} pfa {pfa}: {q} vs statrs {r}"
                );
                // Ours is the better root of the shared survival function.
                let ours = rel_err(chi2_sf(q, dof).unwrap(), pfa);
                assert!(ours <= TOL_ROUND_TRIP_REL, "dof {dof} pfa {pfa}: {ours:e}");
            }
            for e in 6..=15 {
                let pfa = 10f64.powi(-e);
                let q = chi2_quantile_upper(pfa, dof).unwrap();
                let err = rel_err(chi2_sf(q, dof).unwrap(), pfa);
                assert!(err <= TOL_ROUND_TRIP_REL, "dof {dof} pfa {pfa}: {err:e}");
            }
        }
    }

    #[test]
    fn quantile_takes_few_iterations() {
        let mut worst = 0;
        for dof in 1..=MAX_DOF {
            for e in 0..=60 {
                // pfa from 0.9 down to 1e-15 in quarter decades, plus 0.9.
                let pfa = if e == 0 {
                    0.9
                } else {
                    10f64.powf(-0.25 * f64::from(e))
                };
                let (_, iterations) = chi2_quantile_upper_iter(pfa, f64::from(dof));
                worst = worst.max(iterations);
            }
        }
        assert!(worst <= 10, "worst case {worst} iterations");
    }

    #[test]
    fn ncx2_dof1_closed_form() {
        // X = (Z + sqrt(lambda))^2: P(X <= x) = Q(sqrt(lambda) - sqrt(x)) - Q(sqrt(x) + sqrt(lambda)).
        for lambda in [1e-6, 0.3, 1.0, 9.0, 67.0, 150.0, 500.0, 5000.0] {
            for factor in [0.01, 0.3, 0.6, 0.9, 1.0, 1.1, 1.5, 3.0] {
                let x = factor * (1.0 + lambda);
                let (rx, rl) = (libm::sqrt(x), libm::sqrt(lambda));
                let exact = normal_q(rl - rx) - normal_q(rx + rl);
                let got = ncx2_cdf(x, 1, lambda).unwrap();
                assert!(
                    (got - exact).abs()
                        <= TOL_NCX2_ABS.min(TOL_NCX2_REL * exact.max(1e-300) + 1e-300)
                        || (got - exact).abs() <= 1e-15,
                    "x {x} lambda {lambda}: {got:e} vs {exact:e}"
                );
            }
        }
    }

    #[test]
    fn ncx2_zero_lambda_is_central() {
        for dof in [1u32, 2, 5, 17, 60, MAX_DOF] {
            for x in [0.1, 1.0, 4.0, 20.0, 80.0, 300.0] {
                assert_eq!(ncx2_cdf(x, dof, 0.0).unwrap(), chi2_cdf(x, dof).unwrap());
                let tiny = ncx2_cdf(x, dof, 1e-12).unwrap();
                assert!((tiny - chi2_cdf(x, dof).unwrap()).abs() <= 1e-12);
            }
        }
    }

    #[test]
    fn ncx2_matches_scipy() {
        // (x, dof, lambda, F) from scipy.stats.ncx2.cdf, scipy version 1.17.1;
        // each also checked against a 40-digit mpmath Poisson sum (agreement
        // 5e-15 relative or better).
        const CASES: [(f64, u32, f64, f64); 14] = [
            (26.0459, 1, 67.14, 0.000_999_496_837_683_437_7),
            (40.0, 4, 78.5, 0.003_113_612_563_401_034_6),
            (49.47, 10, 91.7, 0.000_999_437_274_873_407),
            (5.0, 2, 0.1, 0.907_592_192_401_350_6),
            (12.0, 3, 3.0, 0.906_974_512_444_8),
            (150.0, 60, 20.0, 0.999_975_354_168_786),
            (450.0, 1, 500.0, 0.125_592_403_219_976_78),
            (500.0, 3, 500.0, 0.482_158_758_838_471_54),
            (600.0, 20, 500.0, 0.958_036_697_258_275_3),
            (380.0, 5, 500.0, 0.001_524_026_544_880_121_6),
            (5000.0, 10, 5000.0, 0.474_627_751_774_853_06),
            (4800.0, 1, 5000.0, 0.076_553_029_339_367_2),
            (5300.0, 50, 5000.0, 0.959_850_382_116_039_1),
            (4400.0, 4, 5000.0, 5.410_512_160_670_023e-6),
        ];
        for (x, dof, lambda, reference) in CASES {
            let got = ncx2_cdf(x, dof, lambda).unwrap();
            assert!(
                (got - reference).abs() <= TOL_NCX2_ABS,
                "x {x} dof {dof} lambda {lambda}: {got:e} vs {reference:e}"
            );
            assert!(
                rel_err(got, reference) <= 1e-11,
                "x {x} dof {dof} lambda {lambda}"
            );
        }
    }

    #[test]
    fn ncx2_edge_values() {
        assert_eq!(ncx2_cdf(0.0, 3, 10.0).unwrap(), 0.0);
        assert_eq!(ncx2_cdf(-5.0, 3, 10.0).unwrap(), 0.0);
        assert_eq!(ncx2_cdf(f64::INFINITY, 3, 10.0).unwrap(), 1.0);
        // Far below the bulk with a large non-centrality: tiny but not lost
        // (mpmath: 1.2481549798562144e-95).
        let tiny = ncx2_cdf(2502.0, 4, 5000.0).unwrap();
        assert!(
            rel_err(tiny, 1.248_154_979_856_214_4e-95) <= 1e-12,
            "{tiny:e}"
        );
        let top = ncx2_cdf(1.0e6, MAX_DOF, MAX_LAMBDA).unwrap();
        assert!((top - 1.0).abs() <= 1e-15);
        let bottom = ncx2_cdf(1.0, MAX_DOF, MAX_LAMBDA).unwrap();
        assert_eq!(bottom, 0.0);
        let mid = ncx2_cdf(MAX_LAMBDA + 200.0, MAX_DOF, MAX_LAMBDA).unwrap();
        assert!(mid > 0.4 && mid < 0.6, "{mid}");
    }

    #[test]
    fn gamma_edge_values() {
        assert_eq!(gamma_p(2.0, 0.0), 0.0);
        assert_eq!(gamma_q(2.0, -1.0), 1.0);
        assert_eq!(gamma_p(2.0, f64::INFINITY), 1.0);
        assert_eq!(gamma_q(2.0, f64::INFINITY), 0.0);
        assert!(gamma_p(0.0, 1.0).is_nan());
        assert!(gamma_q(-1.0, 1.0).is_nan());
        assert!(gamma_p(f64::NAN, 1.0).is_nan());
        assert!(gamma_q(1.0, f64::NAN).is_nan());
        // P(1, x) = 1 - e^-x; non-half-integer shape via lgamma path.
        assert!(rel_err(gamma_q(1.0, 3.0), libm::exp(-3.0)) <= 1e-15);
        assert!(rel_err(gamma_p(1.0, 1e-3), -libm::expm1(-1e-3)) <= 1e-15);
        assert!((gamma_p(3.3, 2.0) + gamma_q(3.3, 2.0) - 1.0).abs() <= 1e-16);
    }

    fn assert_out_of_range(result: Result<f64, RaimError>, expected_field: &str) {
        match result {
            Err(RaimError::OutOfRange { field, .. }) => assert_eq!(field, expected_field),
            other => panic!("expected OutOfRange {{ {expected_field} }}, got {other:?}"),
        }
    }

    fn assert_invalid_dof(result: Result<f64, RaimError>, expected_dof: u32) {
        match result {
            Err(RaimError::InvalidDof { dof, max }) => {
                assert_eq!(dof, expected_dof);
                assert_eq!(max, MAX_DOF);
            }
            other => panic!("expected InvalidDof, got {other:?}"),
        }
    }

    #[test]
    fn bad_inputs_give_typed_errors() {
        for p in [
            f64::NAN,
            0.0,
            -0.1,
            1.0,
            1.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            assert_out_of_range(normal_q_inv(p), "p");
            assert_out_of_range(chi2_quantile_upper(p, 3), "pfa");
            assert_out_of_range(ncx2_lambda(p, 1e-3, 3), "pfa");
            assert_out_of_range(ncx2_lambda(1e-5, p, 3), "pmd");
            assert_out_of_range(pbias(p, 1e-3, 3), "pfa");
            assert_out_of_range(pbias(1e-5, p, 3), "pmd");
        }
        match normal_q_inv(f64::NAN) {
            Err(RaimError::OutOfRange {
                value, min, max, ..
            }) => {
                assert!(value.is_nan());
                assert_eq!((min, max), (0.0, 1.0));
            }
            other => panic!("{other:?}"),
        }
        assert_out_of_range(chi2_cdf(f64::NAN, 3), "x");
        assert_out_of_range(chi2_sf(f64::NAN, 3), "x");
        assert_out_of_range(ncx2_cdf(f64::NAN, 3, 1.0), "x");
        for lambda in [f64::NAN, -1.0, f64::INFINITY, MAX_LAMBDA * 1.01] {
            assert_out_of_range(ncx2_cdf(10.0, 3, lambda), "lambda");
        }
        for dof in [0, MAX_DOF + 1, u32::MAX] {
            assert_invalid_dof(chi2_cdf(1.0, dof), dof);
            assert_invalid_dof(chi2_sf(1.0, dof), dof);
            assert_invalid_dof(chi2_quantile_upper(1e-5, dof), dof);
            assert_invalid_dof(ncx2_cdf(1.0, dof, 1.0), dof);
            assert_invalid_dof(ncx2_lambda(1e-5, 1e-3, dof), dof);
            assert_invalid_dof(pbias(1e-5, 1e-3, dof), dof);
        }
        // Extreme but valid inputs stay finite.
        for dof in [1, MAX_DOF] {
            for p in [f64::MIN_POSITIVE, 5e-324, 1.0 - f64::EPSILON / 2.0, 0.5] {
                assert!(chi2_quantile_upper(p, dof).unwrap().is_finite());
                assert!(pbias(p, p, dof).unwrap().is_finite());
                assert!(normal_q_inv(p).unwrap().is_finite());
            }
        }
    }

    proptest! {
        #[test]
        fn cdf_plus_sf_is_one(x in 0.0f64..2000.0, dof in 1u32..=MAX_DOF) {
            let sum = chi2_cdf(x, dof).unwrap() + chi2_sf(x, dof).unwrap();
            prop_assert!((sum - 1.0).abs() <= TOL_CDF_PLUS_SF, "sum {}", sum);
        }

        #[test]
        fn quantile_monotone_in_pfa(
            log_p1 in -15.0f64..-0.01,
            log_p2 in -15.0f64..-0.01,
            dof in 1u32..=MAX_DOF,
        ) {
            let (p1, p2) = (10f64.powf(log_p1), 10f64.powf(log_p2));
            let (q1, q2) = (chi2_quantile_upper(p1, dof).unwrap(), chi2_quantile_upper(p2, dof).unwrap());
            if p1 < p2 {
                prop_assert!(q1 >= q2, "q({}) = {} < q({}) = {}", p1, q1, p2, q2);
            } else if p1 > p2 {
                prop_assert!(q1 <= q2, "q({}) = {} > q({}) = {}", p1, q1, p2, q2);
            }
        }

        #[test]
        fn ncx2_decreasing_in_lambda(x in 0.1f64..400.0, dof in 1u32..=MAX_DOF, l1 in 0.0f64..300.0, dl in 0.0f64..50.0) {
            let f1 = ncx2_cdf(x, dof, l1).unwrap();
            let f2 = ncx2_cdf(x, dof, l1 + dl).unwrap();
            prop_assert!(f2 <= f1 * (1.0 + 1e-13) + 1e-300, "{} > {}", f2, f1);
            prop_assert!((0.0..=1.0).contains(&f1));
        }
    }
}

#[cfg(test)]
#[path = "dist_cov_tests.rs"]
mod cov_tests;
