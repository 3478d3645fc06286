//! S202-S203: the SVD of the window covariance (nalgebra) and the number k
//! of leading components whose singular values cover the requested share.

use crate::real::Real;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimMin, DimSub, U1};

/// Sweeps allowed to the SVD (nalgebra's implicit-shift QR); it converges
/// in a few per singular value on a symmetric PSD matrix.
const SVD_MAX_ITER: usize = 2000;

/// The principal components of a covariance matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Principal<T, const N: usize> {
    /// Singular values, descending (m^2 for a range covariance).
    pub values: [f64; N],
    /// The right-singular vectors V: `v[j]` is column j, in the same order.
    pub v: [[T; N]; N],
    /// The smallest k with sum_{i<k} s_i >= share * sum s_i (0 when the
    /// sum is 0).
    pub k: usize,
    /// The share the k components cover.
    pub covered: f64,
}

/// The SVD of `sigma` (symmetric positive semi-definite: U = V), sorted by
/// singular value, and k for `share`. None when the SVD does not converge
/// or produces non-finite values.
pub fn principal<T: Real, const N: usize>(
    sigma: nalgebra::OMatrix<T, Const<N>, Const<N>>,
    share: f64,
) -> Option<Principal<T, N>>
where
    Const<N>: DimMin<Const<N>, Output = Const<N>> + DimSub<U1>,
    DefaultAllocator: nalgebra::allocator::Allocator<DimDiff<Const<N>, U1>>
        + nalgebra::allocator::Allocator<Const<N>, Const<N>>
        + nalgebra::allocator::Allocator<Const<N>>
        + nalgebra::allocator::Allocator<U1, Const<N>>,
{
    let svd = nalgebra::SVD::<T, Const<N>, Const<N>>::try_new_unordered(
        sigma,
        false,
        true,
        T::default_epsilon(),
        SVD_MAX_ITER,
    )?;
    let v_t = svd.v_t?;
    let mut order = [0usize; N];
    for (i, o) in order.iter_mut().enumerate() {
        *o = i;
    }
    let s = |i: usize| svd.singular_values.get(i).map_or(f64::NAN, |x| x.to_f64());
    // Insertion sort, descending (N is small).
    for i in 1..N {
        let mut j = i;
        while j > 0 {
            let (a, b) = (order.get(j - 1).copied()?, order.get(j).copied()?);
            if s(a) < s(b) {
                order.swap(j - 1, j);
                j -= 1;
            } else {
                break;
            }
        }
    }
    let mut values = [0.0; N];
    let mut v = [[T::of(0.0); N]; N];
    for (dst, &src) in order.iter().enumerate() {
        let x = s(src);
        if !x.is_finite() {
            return None;
        }
        if let Some(d) = values.get_mut(dst) {
            *d = x;
        }
        if let Some(col) = v.get_mut(dst) {
            for (c, x) in col.iter_mut().zip(v_t.row(src).iter()) {
                *c = *x;
            }
        }
    }
    let total: f64 = values.iter().sum();
    let mut k = 0;
    let mut acc = 0.0;
    if total > 0.0 {
        for x in values.iter() {
            acc += *x;
            k += 1;
            if acc >= share * total {
                break;
            }
        }
    }
    Some(Principal {
        values,
        v,
        k,
        covered: if total > 0.0 { acc / total } else { 0.0 },
    })
}

#[cfg(test)]
#[path = "svd_cov_tests.rs"]
mod cov_tests;
