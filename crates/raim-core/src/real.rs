//! The precision policy, in one place (docs/CORE.md, "Precision").
//!
//! The M4F's FPU is single precision: every `f64` operation there is a
//! software call (20-60 instructions for + and x, hundreds for sqrt, ln,
//! exp). So the core computes in `f64` only where `f32` cannot hold the
//! quantity, and everything else is written once, generic over [`Real`],
//! and run in the engine's precision `T` (`f32` on the device, `f64` on the
//! host; [`Stat`], f64, is the default type parameter):
//!
//! - `f64` always: the range prediction and the residual formation
//!   (ranges of 2e7 m at millimetre resolution; the f32 spacing there is
//!   2 m), satellite and receiver ECEF positions, time, and the Gauss-Newton
//!   state. A particle filter's state is stored as an offset from an `f64`
//!   reference point, so it may be `T`.
//! - `T`: the unit lines of sight, the whitened geometry, the QR and parity
//!   space, the test statistics, the identification scores, the
//!   reconstructions, the ARAIM subset solutions and protection levels,
//!   and the particle weights.
//! - Thresholds (chi-square and normal quantiles) are computed in `f64`
//!   once per configuration and dof, cached, and then compared in `T`.
//!
//! An engine is generic over `T: Real`; host tests run it at `f64` against
//! independent references, and at `f32` against the `f64` run with a
//! stated relative tolerance.

/// A floating-point scalar the numeric engines are generic over: `f32` or
/// `f64`. nalgebra's `RealField` supplies the arithmetic and the elementary
/// functions (through `libm` in no_std); this adds the conversions the
/// policy needs at its edges.
///
/// The linear algebra's choice of kernels per precision (one-pass QR norms,
/// summation in lanes) is not a precision question: it lives in
/// [`crate::linalg::Kernels`], which every `Real` type implements.
pub trait Real:
    nalgebra::RealField
    + crate::linalg::Kernels
    + Copy
    + Default
    + PartialOrd
    + core::fmt::Debug
    + Send
    + Sync
    + 'static
{
    /// The name of the precision, for reports.
    const NAME: &'static str;
    /// The machine epsilon.
    const EPS: Self;
    /// The smallest positive normal number.
    const MIN_POSITIVE: Self;
    /// The largest finite number.
    const MAX: Self;
    /// Zero, for `const fn` constructors (the initial value of engine
    /// storage built in place in a static).
    const ZERO: Self;
    /// Converts from `f64`, rounding to nearest for `f32`.
    fn of(x: f64) -> Self;
    /// Widens (or passes) to `f64`.
    fn to_f64(self) -> f64;
    /// ln x through `libm` on every target, so that the host and the
    /// device round alike (nalgebra's `ln` is the platform's on a std host).
    fn ln_m(self) -> Self;
    /// ln(1 + x) through `libm` (see [`Real::ln_m`]).
    fn ln_1p_m(self) -> Self;
    /// Whether the value is NaN.
    fn is_nan_m(self) -> bool;
    /// sin x through `libm` (see [`Real::ln_m`]).
    fn sin_m(self) -> Self;
    /// cos x through `libm`.
    fn cos_m(self) -> Self;
    /// e^x through `libm`.
    fn exp_m(self) -> Self;
    /// atan2(self, x) through `libm`.
    fn atan2_m(self, x: Self) -> Self;
    /// atan(self) through `libm`.
    fn atan_m(self) -> Self;
    /// asin(self) through `libm`.
    fn asin_m(self) -> Self;
    /// The square root of a squared range `r2` (m^2), in f64 whatever `T`:
    /// ranges are f64 quantities (the policy). In an f64 engine, `libm`'s
    /// correctly rounded sqrt; in an f32 engine (the M4F, where an f64 sqrt
    /// is a long software routine) the FPU's f32 sqrt refined by one
    /// Newton step in f64, which leaves an error of about half the square
    /// of the seed's (<= 9e-8) relative: below 2e-7 m at 2.7e7 m (test
    /// `f32_range_sqrt_is_f64_accurate`), against millimetre ranging.
    fn range_sqrt(r2: f64) -> f64;
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const NAME: &'static str = "f64";
    const EPS: Self = f64::EPSILON;
    const MIN_POSITIVE: Self = f64::MIN_POSITIVE;
    const MAX: Self = f64::MAX;
    #[inline(always)]
    fn of(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn ln_m(self) -> Self {
        libm::log(self)
    }
    #[inline(always)]
    fn ln_1p_m(self) -> Self {
        libm::log1p(self)
    }
    #[inline(always)]
    fn is_nan_m(self) -> bool {
        self.is_nan()
    }
    #[inline(always)]
    fn sin_m(self) -> Self {
        libm::sin(self)
    }
    #[inline(always)]
    fn cos_m(self) -> Self {
        libm::cos(self)
    }
    #[inline(always)]
    fn exp_m(self) -> Self {
        libm::exp(self)
    }
    #[inline(always)]
    fn atan2_m(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
    #[inline(always)]
    fn atan_m(self) -> Self {
        libm::atan(self)
    }
    #[inline(always)]
    fn asin_m(self) -> Self {
        libm::asin(self)
    }
    #[inline(always)]
    fn range_sqrt(r2: f64) -> f64 {
        libm::sqrt(r2)
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const NAME: &'static str = "f32";
    const EPS: Self = f32::EPSILON;
    const MIN_POSITIVE: Self = f32::MIN_POSITIVE;
    const MAX: Self = f32::MAX;
    #[inline(always)]
    fn of(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn ln_m(self) -> Self {
        libm::logf(self)
    }
    #[inline(always)]
    fn ln_1p_m(self) -> Self {
        libm::log1pf(self)
    }
    #[inline(always)]
    fn is_nan_m(self) -> bool {
        self.is_nan()
    }
    #[inline(always)]
    fn sin_m(self) -> Self {
        libm::sinf(self)
    }
    #[inline(always)]
    fn cos_m(self) -> Self {
        libm::cosf(self)
    }
    #[inline(always)]
    fn exp_m(self) -> Self {
        libm::expf(self)
    }
    #[inline(always)]
    fn atan2_m(self, x: Self) -> Self {
        libm::atan2f(self, x)
    }
    #[inline(always)]
    fn atan_m(self) -> Self {
        libm::atanf(self)
    }
    #[inline(always)]
    fn asin_m(self) -> Self {
        libm::asinf(self)
    }
    #[inline]
    fn range_sqrt(r2: f64) -> f64 {
        let r0 = libm::sqrtf(r2 as f32) as f64;
        if !(r0 > 0.0) || !r0.is_finite() {
            // 0, NaN, or beyond f32 (r2 > 3.4e38): the exact routine.
            return libm::sqrt(r2);
        }
        0.5 * (r0 + r2 / r0)
    }
}

/// The default precision of the engines' statistics path (`Raim<N>` is
/// `Raim<N, Stat>`): `f64`, the host's reference. Both precisions are
/// always available as types (`Raim<N, f64>`, `Raim<N, f32>`); the device
/// names its own (the protocol server's `raim_proto::DevicePrecision`,
/// f32, the M4F's FPU), so no feature changes a type any dependent sees.
#[cfg(not(all(test, feature = "test-f32")))]
pub type Stat = f64;
/// In this crate's own unit tests with the `test-f32` feature, the whole
/// unit suite runs its default-precision engines in f32, the device's
/// precision (`cargo test -p raim-core --features test-f32 --lib`).
#[cfg(all(test, feature = "test-f32"))]
pub type Stat = f32;

#[cfg(test)]
mod tests {
    use super::*;

    fn hypot<T: Real>(a: T, b: T) -> T {
        (a * a + b * b).sqrt()
    }

    /// The same generic code runs in both precisions and agrees to the
    /// f32 epsilon (relative).
    #[test]
    fn generic_code_runs_in_both_precisions() {
        let d = hypot(3.0f64, 4.0);
        let s = hypot(f32::of(3.0), f32::of(4.0));
        assert_eq!(d, 5.0);
        assert!((s.to_f64() - d).abs() <= 5.0 * f32::EPSILON as f64);
        assert_eq!(f32::of(1e-40).to_f64(), 1e-40f32 as f64);
        assert_eq!(<Stat as Real>::NAME.len(), 3);
    }

    /// The f32 engine's range square root (an f32 seed plus one f64 Newton
    /// step) against the correctly rounded f64 sqrt, over GNSS ranges
    /// (1.9e7-2.7e7 m) and short ones: within 2e-7 m; the f64 engine's is
    /// the f64 sqrt itself.
    #[test]
    fn f32_range_sqrt_is_f64_accurate() {
        const RANGE_TOL_M: f64 = 2e-7;
        let mut r = 1.0f64;
        while r < 3.0e7 {
            for f in [1.0, 1.000_000_123, 1.37, 1.999_999_9] {
                let x = r * f;
                let r2 = x * x;
                assert!(
                    (f32::range_sqrt(r2) - libm::sqrt(r2)).abs() < RANGE_TOL_M,
                    "{x}"
                );
                assert_eq!(f64::range_sqrt(r2), libm::sqrt(r2));
            }
            r *= 1.7;
        }
        for k in 0..1000 {
            let x = 1.9e7 + k as f64 * 8_000.123_456;
            assert!((f32::range_sqrt(x * x) - x).abs() < RANGE_TOL_M, "{x}");
        }
        assert!(f32::range_sqrt(f64::NAN).is_nan());
        assert_eq!(f32::range_sqrt(0.0), 0.0);
    }
}

#[cfg(test)]
#[path = "real_cov_tests.rs"]
mod cov_tests;
