//! The elementary functions, through `libm` on every target, so that the
//! host and the device compute the same bits (no_std has no `f64::sin`, and
//! the host's `std` would call the platform's C library instead).

pub(crate) fn sin(x: f64) -> f64 {
    libm::sin(x)
}

pub(crate) fn cos(x: f64) -> f64 {
    libm::cos(x)
}

pub(crate) fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

pub(crate) fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}

pub(crate) fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

pub(crate) fn exp(x: f64) -> f64 {
    libm::exp(x)
}

pub(crate) fn pow(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

pub(crate) fn floor(x: f64) -> f64 {
    libm::floor(x)
}

pub(crate) fn round(x: f64) -> f64 {
    libm::round(x)
}

/// The least non-negative remainder of `x / y` (`f64::rem_euclid`; `%`
/// is the exact IEEE remainder of truncated division).
pub(crate) fn rem_euclid(x: f64, y: f64) -> f64 {
    let r = x % y;
    if r < 0.0 {
        r + y.abs()
    } else {
        r
    }
}
