//! The extended Kalman filter baseline of seed 004 (its "EKF-based FDI"),
//! on the same state, process model and measurement function as the
//! particle filters. The measurement update is sequential (one scalar
//! update per satellite; the ranging errors are independent), so no matrix
//! is inverted, and the predictive density ln p(z | Z_{k-1}) is the sum of
//! the scalar innovation densities (the chain rule; exact for the
//! linearised model). A non-Gaussian likelihood is replaced by the Gaussian
//! of the same variance ([`Likelihood::variance_factor`]).
//!
//! [`Likelihood::variance_factor`]: super::config::Likelihood::variance_factor

use nalgebra::{ArrayStorage, SMatrix, SVector};

use crate::real::Real;

use super::config::PfConfig;
use super::model::{init_sigmas, process_sigmas, Estimator, SatTerm, Step, CLOCK0, DIM, DRIFT};
use super::rng::PfRng;

type Vector<T> = SVector<T, DIM>;
type Matrix<T> = SMatrix<T, DIM, DIM>;

/// The EKF: mean and covariance of the state offset.
#[derive(Debug, Clone)]
pub struct Ekf<T: Real> {
    x: Vector<T>,
    p: Matrix<T>,
}

impl<T: Real> Ekf<T> {
    /// The covariance (for tests).
    pub fn covariance(&self) -> &Matrix<T> {
        &self.p
    }

    /// One scalar measurement update; returns the innovation's
    /// log-density, or `None` when the innovation variance is not positive.
    fn scalar(x: &mut Vector<T>, p: &mut Matrix<T>, t: &SatTerm<T>, var_factor: T) -> Option<T> {
        let arr: [T; DIM] = (*x).into();
        let h = Vector::<T>::from(t.jacobian(&arr));
        let nu = t.residual(&arr);
        let r = t.sigma * t.sigma * var_factor;
        let ph = *p * h;
        let s = h.dot(&ph) + r;
        if !(s > T::zero()) || !s.is_finite() {
            return None;
        }
        let k = ph / s;
        *x += k * nu;
        *p -= k * ph.transpose();
        *p = (*p + p.transpose()) * T::of(0.5);
        let two_pi = T::of(2.0 * core::f64::consts::PI);
        Some(-T::of(0.5) * (nu * nu / s + (two_pi * s).ln_m()))
    }

    fn run(
        x: &mut Vector<T>,
        p: &mut Matrix<T>,
        terms: &[SatTerm<T>],
        skip: Option<usize>,
        var_factor: T,
    ) -> Option<f64> {
        let mut l = 0.0f64;
        for (k, t) in terms.iter().enumerate() {
            if Some(k) != skip {
                l += Self::scalar(x, p, t, var_factor)?.to_f64();
            }
        }
        Some(l)
    }
}

impl<T: Real> Estimator<T> for Ekf<T> {
    const KIND: &'static str = "ekf";
    const PARTICLES: usize = 0;

    /// Zero mean and zero covariance: [`Estimator::init`] sets both before
    /// the first update reads them.
    const BLANK: Self = Ekf {
        x: Vector::from_array_storage(ArrayStorage([[T::ZERO; DIM]; 1])),
        p: Matrix::from_array_storage(ArrayStorage([[T::ZERO; DIM]; DIM])),
    };

    fn init(&mut self, cfg: &PfConfig, _rng: &mut PfRng) {
        let s = init_sigmas(cfg);
        self.x = Vector::zeros();
        self.p = Matrix::from_diagonal(&Vector::from(s.map(|v| T::of(v * v))));
    }

    fn copy_from(&mut self, other: &Self) {
        self.x = other.x;
        self.p = other.p;
    }

    fn predict(&mut self, cfg: &PfConfig, dt_s: f64, _rng: &mut PfRng) {
        let mut f = Matrix::<T>::identity();
        f.fixed_view_mut::<{ DRIFT - CLOCK0 }, 1>(CLOCK0, DRIFT)
            .fill(T::of(dt_s));
        let q = process_sigmas(cfg, dt_s);
        let q = Matrix::from_diagonal(&Vector::from(q.map(|v| T::of(v * v))));
        self.x = f * self.x;
        self.p = f * self.p * f.transpose() + q;
    }

    fn update(
        &mut self,
        cfg: &PfConfig,
        terms: &[SatTerm<T>],
        skip: Option<usize>,
        _rng: &mut PfRng,
    ) -> Step {
        let vf = T::of(cfg.likelihood.variance_factor());
        match Self::run(&mut self.x, &mut self.p, terms, skip, vf) {
            Some(l) if l.is_finite() && self.x.iter().all(|v| v.is_finite()) => Step {
                ln_predictive: l,
                n_eff: 0.0,
                n_eff_before_ga: 0.0,
                collapsed: false,
            },
            other => Step {
                ln_predictive: other.unwrap_or(f64::NAN),
                n_eff: 0.0,
                n_eff_before_ga: 0.0,
                collapsed: true,
            },
        }
    }

    fn mean(&self) -> [T; DIM] {
        self.x.into()
    }

    fn shift(&mut self, delta: &[T; DIM]) {
        self.x += Vector::from(*delta);
    }
}
