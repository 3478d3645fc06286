//! The normal tail Q(z) = P(Z > z) and the density phi(z) from one `exp`
//! (for speed: the PL search evaluates both for every mode,
//! and `libm::erfc` alone calls `exp` twice).
//!
//! Q(|z|) = exp(-z^2 / 2) R(|z|) with W. J. Cody's rational Chebyshev
//! approximations (Math. Comp. 23 (1969) 631-637) in the normal-scaled form
//! used by R's `pnorm` (the coefficients are published numbers):
//!
//! - |z| < 0.67449 (the quartile): Q = 1/2 - z A(z^2) / B(z^2), and the
//!   density from its own `exp` (no cancellation at small z^2);
//! - 0.67449 <= |z| <= sqrt(32): R = C(|z|) / D(|z|);
//! - |z| > sqrt(32): R = (1/sqrt(2 pi) - P(1/z^2) / (z^2 Q(1/z^2))) / |z|;
//!
//! and Q(z) = 1 - Q(|z|) for negative z. The common factor
//! exp(-z^2 / 2) is formed with z^2 split exactly (Dekker: z = z_h + z_l
//! with z_h holding 26 bits, so z_h^2 is exact) as
//! exp(-z_h^2 / 2) (1 + b + b^2/2 + b^3/6), b = -z_l (z + z_h) / 2, |b| <
//! 2^-26 z^2: the rounding of z^2 (relative z^2 u, 1.4e-15 at z = 5) does
//! not reach the result. Relative accuracy against statrs over
//! z in [-5, 37]: a few 1e-16 (the unit test below, `TAIL_REL_TOL`).

// The coefficients are written with the digits their sources publish (the
// compiler rounds them to f64), so they can be checked against the source.
#![allow(clippy::excessive_precision)]

const INV_SQRT_2PI: f64 = 0.398_942_280_401_432_7;
/// Below this |z| (Q^-1(1/4)) the small-argument form.
const Z_SMALL: f64 = 0.674_48;
/// Above this |z| (sqrt 32) the asymptotic form.
const Z_LARGE: f64 = 5.656_854_249_492_381;

/// exp(-Y_MAX^2 / 2) is below the smallest subnormal f64.
const Y_MAX: f64 = 38.6;

const A: [f64; 5] = [
    2.235_252_035_460_683_928_7,
    161.028_231_068_555_878_81,
    1_067.689_485_460_370_958_2,
    18_154.981_253_343_561_249,
    0.065_682_337_918_207_449_113,
];
const B: [f64; 4] = [
    47.202_581_904_688_241_87,
    976.098_551_737_776_693_22,
    10_260.932_208_618_978_205,
    45_507.789_335_026_729_956,
];
const C: [f64; 9] = [
    0.398_941_512_088_134_667_64,
    8.883_149_794_388_375_941_2,
    93.506_656_132_177_855_979,
    597.270_276_394_800_262_26,
    2_494.537_585_290_372_671_1,
    6_848.190_450_536_282_332_6,
    11_602.651_437_647_350_124,
    9_842.714_838_383_978_021_8,
    1.076_557_677_372_019_231_7e-8,
];
const D: [f64; 8] = [
    22.266_688_044_328_115_691,
    235.387_901_782_624_998_61,
    1_519.377_599_407_554_805,
    6_485.558_298_266_760_755,
    18_615.571_640_885_098_091,
    34_900.952_721_145_977_266,
    38_912.003_286_093_271_411,
    19_685.429_676_859_990_727,
];
const P: [f64; 6] = [
    0.215_898_534_057_956_99,
    0.127_401_161_160_247_363_9,
    0.022_235_277_870_649_807,
    0.001_421_619_193_227_893_466,
    2.911_287_495_116_879_2e-5,
    0.023_073_441_764_940_173_03,
];
const Q: [f64; 5] = [
    1.284_260_096_144_911_21,
    0.468_238_212_480_865_118,
    0.065_988_137_868_928_551_5,
    0.003_782_396_332_027_582_44,
    7.297_515_550_839_662_05e-5,
];

/// ln 2 / 64 in two parts (Cody-Waite, fdlibm's split of ln 2 divided by
/// 64, exactly): the high part has 32 significant bits, so k LN2_64_HI is
/// exact for |k| < 2^20 (here |k| <= 68,800).
const LN2_64_HI: f64 = 0.693_147_180_369_123_816_49 / 64.0;
const LN2_64_LO: f64 = 1.908_214_929_270_587_7e-10 / 64.0;
/// 64 / ln 2 (correctly rounded; it only picks k).
const INV_LN2_64: f64 = 92.332_482_616_893_66;
const ROUND_SHIFT: f64 = 6_755_399_441_055_744.0;

/// 2^(j/64), j = 0..63, as the correctly rounded value and the rounding
/// remainder (2^(j/64) - hi, rounded): computed in 60-digit decimal
/// arithmetic (Python's `decimal`, `Decimal(2) ** (Decimal(j) / 64)`),
/// and checked by `exp_table_is_exact` against libm's exp2 (entry 32,
/// sqrt 2, written as `SQRT_2`: the same value).
const EXP2_64: [(f64, f64); 64] = [
    (1.0, 0.0),
    (1.0108892860517005, -1.5234778603368577e-17),
    (1.0218971486541166, 5.109225028973444e-17),
    (1.0330248790212284, 7.600838874027088e-18),
    (1.0442737824274138, 8.551889705537965e-17),
    (1.0556451783605572, 1.759325738772092e-18),
    (1.0671404006768237, -7.899853966841582e-17),
    (1.0787607977571199, -6.656660436056593e-17),
    (1.0905077326652577, -3.046782079812471e-17),
    (1.102382583307841, 5.2660368715706944e-17),
    (1.1143867425958924, 1.0410278456845571e-16),
    (1.1265216186082418, 5.165856758795457e-17),
    (1.1387886347566916, 8.912812676025408e-17),
    (1.1511892299529827, 3.250710218863827e-17),
    (1.1637248587775775, 3.8292048369240935e-17),
    (1.1763969916502812, 5.554203254218079e-17),
    (1.189207115002721, 3.982015231465646e-17),
    (1.202156731452703, 6.644981499252301e-17),
    (1.215247359980469, -7.712630692681488e-17),
    (1.22848053610687, -1.89878163130253e-17),
    (1.241857812073484, 4.658027591836937e-17),
    (1.255380757024691, -6.7113898212968784e-18),
    (1.2690509571917332, 2.667932131342186e-18),
    (1.2828700160787783, 1.713594918243561e-17),
    (1.2968395546510096, 2.5382502794888315e-17),
    (1.3109612115247644, -7.181536135519454e-17),
    (1.3252366431597413, -2.8587312100388614e-17),
    (1.339667524053303, 8.927282594831732e-17),
    (1.3542555469368927, 7.70094837980299e-17),
    (1.3690024229745905, 9.593797919118849e-17),
    (1.383909881963832, -6.770511658794786e-17),
    (1.3989796725383112, -9.614213209051323e-17),
    (core::f64::consts::SQRT_2, -9.667293313452913e-17),
    (1.42961333839197, -1.2031642489053655e-17),
    (1.4451808069770467, -3.0237581349939873e-17),
    (1.460917794180647, -5.600377186075216e-17),
    (1.4768261459394993, -3.483994556892796e-17),
    (1.4929077282912648, 1.4192920154284036e-17),
    (1.5091644275934228, -1.016455327754295e-16),
    (1.5255981507445384, -1.1024941712342561e-16),
    (1.5422108254079407, 7.949834809697621e-17),
    (1.559004400237837, 3.7812070533575275e-17),
    (1.5759808451078865, -1.0136916471278304e-17),
    (1.593142151342267, -1.0094406542311964e-16),
    (1.6104903319492543, 2.4707192569797888e-17),
    (1.6280274218573478, -6.712955084707084e-17),
    (1.645755478153965, -1.0125679913674773e-16),
    (1.6636765803267364, 5.8909926967131e-17),
    (1.681792830507429, 8.199010020581497e-17),
    (1.7001063537185235, -8.0237193703977e-18),
    (1.718619298122478, -1.851380418263111e-17),
    (1.7373338352737062, 3.164389299292957e-17),
    (1.7562521603732995, 2.960140695448873e-17),
    (1.7753764925265212, 6.429731796556572e-17),
    (1.7947090750031072, 1.8227458427912087e-17),
    (1.8142521755003989, -9.969531538920349e-17),
    (1.8340080864093424, 3.283107224245627e-17),
    (1.8539791250833855, 9.761887490727594e-17),
    (1.8741676341103, -6.122763413004143e-17),
    (1.8945759815869656, 3.4034035352165297e-17),
    (1.9152065613971474, -1.0619946056195963e-16),
    (1.9360617934922943, 1.0332385960676326e-16),
    (1.9571441241754002, 8.960767791036668e-17),
    (1.978456026387951, 4.0388753109278167e-17),
];

/// exp(x) for x <= 0 (the only arguments here), table-driven and without
/// a division (the fdlibm form's (r c) / (2 - c) was the longest step of
/// the PL search's per-term work): x = (64 m + j) ln 2 / 64 + r with
/// |r| <= ln 2 / 128 (k = 64 m + j by the 1.5 * 2^52 shift, ln 2 / 64 in
/// two parts), e^r - 1 = r + r^2/2 + ... + r^6/720 (truncation below
/// 3e-20 relative), then 2^(j/64) e^r = hi + (lo + hi (e^r - 1)) from the
/// two-part table and 2^m from the exponent bits (in two factors below
/// 2^-1022, where the result is subnormal). Within 1 ulp of
/// `libm::exp` (the unit test). Below -745.2 it is 0; NaN stays NaN.
#[inline]
fn exp_neg(x: f64) -> f64 {
    if !(x >= -745.2) {
        return if x.is_nan() { x } else { 0.0 };
    }
    let kf = (x * INV_LN2_64 + ROUND_SHIFT) - ROUND_SHIFT;
    let r = (x - kf * LN2_64_HI) - kf * LN2_64_LO;
    let r2 = r * r;
    let q = r + r2
        * ((0.5 + r * (1.0 / 6.0)) + r2 * ((1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0)));
    let k = kf as i64;
    // k & 63 < 64, the table's length.
    #[allow(clippy::indexing_slicing)]
    let (hi, lo) = EXP2_64[(k & 63) as usize];
    let p = hi + (lo + hi * q);
    // m = floor(k / 64) in [-1076, 0]: 2^m as one or two normal powers
    // of two.
    let m = k >> 6;
    let pow2 = |e: i64| f64::from_bits(((e + 1023) as u64) << 52);
    if m >= -1022 {
        p * pow2(m)
    } else {
        p * pow2(m + 100) * pow2(-100)
    }
}

/// exp(-z^2 / 2) with z^2 split exactly (module doc).
#[inline]
fn half_gauss(z: f64) -> f64 {
    let zh = f64::from_bits(z.to_bits() & !((1u64 << 27) - 1));
    let zl = z - zh;
    let b = -0.5 * zl * (z + zh);
    exp_neg(-0.5 * zh * zh) * (1.0 + b * (1.0 + b * (0.5 + b * (1.0 / 6.0))))
}

/// Q(z) and phi(z). NaN in, NaN out.
#[inline(always)]
pub fn q_and_pdf(z: f64) -> (f64, f64) {
    let y = z.abs();
    if y < Z_SMALL {
        let s = z * z;
        let mut num = A[4] * s;
        let mut den = s;
        for (a, b) in A.iter().zip(B.iter()).take(3) {
            num = (num + a) * s;
            den = (den + b) * s;
        }
        let t = z * (num + A[3]) / (den + B[3]);
        return (0.5 - t, INV_SQRT_2PI * exp_neg(-0.5 * s));
    }
    // Beyond Y_MAX both Q and phi are below the smallest subnormal.
    let e = if y > Y_MAX { 0.0 } else { half_gauss(y) };
    let r = if y <= Z_LARGE {
        let mut num = C[8] * y;
        let mut den = y;
        for (c, d) in C.iter().zip(D.iter()).take(7) {
            num = (num + c) * y;
            den = (den + d) * y;
        }
        (num + C[7]) / (den + D[7])
    } else {
        let s = 1.0 / (y * y);
        let mut num = P[5] * s;
        let mut den = s;
        for (p, q) in P.iter().zip(Q.iter()).take(4) {
            num = (num + p) * s;
            den = (den + q) * s;
        }
        let t = s * (num + P[4]) / (den + Q[4]);
        (INV_SQRT_2PI - t) / y
    };
    let tail = e * r;
    let q = if z < 0.0 { 1.0 - tail } else { tail };
    (q, INV_SQRT_2PI * e)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use statrs::distribution::{ContinuousCDF, Normal};

    /// Relative accuracy asked of Q and phi.
    const TAIL_REL_TOL: f64 = 1e-15;
    /// Unit roundoff.
    const U: f64 = f64::EPSILON / 2.0;

    fn rel(a: f64, b: f64) -> f64 {
        if a == b {
            0.0
        } else {
            (a - b).abs() / b.abs()
        }
    }

    /// The density where z^2 / 2 is exact (z a multiple of 2^-10 below
    /// 64): one correctly rounded product and libm's exp, < 1 ulp.
    fn exact_pdf(z: f64) -> f64 {
        INV_SQRT_2PI * libm::exp(-0.5 * z * z)
    }

    /// Against fdlibm's erfc (the `libm` crate: its own rational
    /// approximations, < 1 ulp) of z / sqrt 2 on [-5, 5]. The reference
    /// carries the rounding of x = z / sqrt 2 (relative u: the constant and
    /// the product), which erfc turns into 2 x^2 u = z^2 u relative, and
    /// its own ulp: 2 z^2 u is added to the tolerance. (Where the two
    /// differ most, z = 2.88, by 2e-15, the continued fraction below sides
    /// with ours to 6e-16.) (statrs' `Normal::sf` is no reference here: it
    /// is off by about 1e-10 relative between 0.7 and 5.)
    #[test]
    fn matches_fdlibm_erfc_near_the_centre() {
        let mut worst = 0.0f64;
        let mut zs: std::vec::Vec<f64> =
            (-5 * 1024..=5 * 1024).map(|j| j as f64 / 1024.0).collect();
        for b in [Z_SMALL, Z_LARGE] {
            for s in [-1.0, 1.0] {
                let x = s * b;
                zs.extend([x, x.next_up(), x.next_down()]);
            }
        }
        for z in zs {
            let (q, _) = q_and_pdf(z);
            let want = 0.5 * libm::erfc(z * core::f64::consts::FRAC_1_SQRT_2);
            let e = rel(q, want);
            assert!(
                e <= TAIL_REL_TOL + 2.0 * z * z * U,
                "z {z}: {q:e} vs {want:e}"
            );
            worst = worst.max(e);
        }
        std::println!("worst relative difference from fdlibm on [-5, 5]: {worst:e}");
    }

    /// statrs (the dense reference of the ARAIM tests) agrees to 1e-9
    /// relative, which the 1e-9 m PL tolerance absorbs.
    #[test]
    fn statrs_agrees_to_its_own_accuracy() {
        let n = Normal::standard();
        for j in -5 * 64..=8 * 64 {
            let z = j as f64 / 64.0;
            assert!(rel(q_and_pdf(z).0, n.sf(z)) <= 1e-9, "z {z}");
        }
    }

    /// The density on [-5, 38.5] against the exact-exponent form.
    #[test]
    fn density_is_accurate() {
        for j in -5 * 1024..=38 * 1024 + 512 {
            let z = j as f64 / 1024.0;
            let (_, p) = q_and_pdf(z);
            assert!(rel(p, exact_pdf(z)) <= TAIL_REL_TOL, "z {z}");
        }
    }

    /// An independent check of the tail: the Laplace continued fraction
    /// Q(z) = phi(z) / (z + 1/(z + 2/(z + 3/(z + ...)))), summed from 4000
    /// levels down (converged to the last bit for z >= 1.5), times the
    /// exact-exponent density.
    #[test]
    fn matches_the_continued_fraction_in_the_tail() {
        let mut worst = 0.0f64;
        for j in 96..=37 * 64 {
            let z = j as f64 / 64.0;
            let mut cf = z;
            for k in (1..=4000).rev() {
                cf = z + k as f64 / cf;
            }
            let want = exact_pdf(z) / cf;
            let (q, _) = q_and_pdf(z);
            let e = rel(q, want);
            worst = worst.max(e);
            assert!(e <= TAIL_REL_TOL, "z {z}: {q:e} vs {want:e} ({e:e})");
        }
        std::println!("worst relative error of Q on [1.5, 37]: {worst:e}");
    }

    /// exp_neg against libm's exp over [-745, 0]: within 1 ulp (measured: identical).
    #[test]
    fn exp_neg_matches_libm() {
        let mut worst = 0.0f64;
        for j in 0..=745_000 {
            let x = -(j as f64) * 1e-3 - 1e-7 * (j % 7) as f64;
            let (a, b) = (exp_neg(x), libm::exp(x));
            if b >= f64::MIN_POSITIVE {
                let e = rel(a, b);
                worst = worst.max(e);
                assert!(e <= 2.0 * U, "x {x}: {a:e} vs {b:e}");
            } else {
                // Subnormal: absolute, in units of the smallest subnormal.
                assert!((a - b).abs() <= 2.0 * 4.9e-324, "x {x}: {a:e} vs {b:e}");
            }
        }
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-800.0), 0.0);
        assert!(exp_neg(f64::NAN).is_nan());
        std::println!("exp_neg: worst relative difference from libm {worst:e}");
    }

    /// The table's two parts against libm's exp2 (within 1 ulp for the
    /// high part) and each other (the low part below half an ulp of the
    /// high one).
    #[test]
    fn exp_table_is_exact() {
        for (j, &(hi, lo)) in EXP2_64.iter().enumerate() {
            let want = libm::exp2(j as f64 / 64.0);
            assert!(rel(hi, want) <= 2.0 * U, "j {j}: {hi:e} vs {want:e}");
            assert!(lo.abs() <= 0.5 * hi * 2.0 * U, "j {j}: lo {lo:e}");
        }
    }

    #[test]
    fn nan_and_infinities() {
        assert!(q_and_pdf(f64::NAN).0.is_nan());
        assert!(q_and_pdf(f64::NAN).1.is_nan());
        assert_eq!(q_and_pdf(f64::INFINITY), (0.0, 0.0));
        assert_eq!(q_and_pdf(f64::NEG_INFINITY), (1.0, 0.0));
        assert_eq!(q_and_pdf(50.0), (0.0, 0.0));
    }
}
