//! f32's arcsine and the range square root beyond f32's range.

extern crate std;

use super::*;

#[test]
fn f32_asin_matches_the_f64_one() {
    for x in [-1.0f64, -0.5, 0.0, 0.3, 0.99, 1.0] {
        let s = f32::of(x).asin_m().to_f64();
        assert!((s - x.asin()).abs() <= 4.0 * f32::EPSILON as f64, "{x}");
    }
    assert!(f32::of(1.5).asin_m().is_nan());
}

/// r2 above f32::MAX: the f32 seed is +inf, so the exact f64 root is
/// taken; 0 and NaN likewise.
#[test]
fn f32_range_sqrt_beyond_f32() {
    assert_eq!(<f32 as Real>::range_sqrt(1e80), 1e40);
    assert_eq!(<f32 as Real>::range_sqrt(0.0), 0.0);
    assert!(<f32 as Real>::range_sqrt(f64::NAN).is_nan());
}
