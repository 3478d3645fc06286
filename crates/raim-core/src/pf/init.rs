//! The first-epoch fix that places the filters' reference point: weighted
//! Gauss-Newton on the pseudoranges in f64 (SPEC §1), on the same state
//! layout as the filters (position + one clock per constellation present).
//! It is a starting point only; the filters' prior spread covers its error.

use nalgebra::{SMatrix, SVector};

use super::error::PfError;
use super::model::{Reference, CLOCK0, DIM};
use crate::measurement::MAX_SYSTEMS;

/// One satellite for the fix: position, pseudorange, sigma, constellation.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FixInput {
    /// Satellite ECEF position, m.
    pub sat_m: [f64; 3],
    /// Pseudorange, m.
    pub pseudorange_m: f64,
    /// Pseudorange sigma, m.
    pub sigma_m: f64,
    /// Constellation index (`System::index`).
    pub sys: usize,
}

const MAX_ITER: u32 = 20;
const CONVERGED_M: f64 = 1e-4;

/// Iterates from `start` (the Earth's centre when nothing better is
/// known); states without a measurement (clocks of absent constellations,
/// the drift) are pinned by a unit prior at zero.
pub fn fix(sats: &[FixInput], start: [f64; 3]) -> Result<Reference, PfError> {
    // A clock state per constellation: CLOCK0 + sys < CLOCK0 + MAX_SYSTEMS
    // <= DIM for every satellite below.
    if let Some(s) = sats.iter().find(|s| s.sys >= MAX_SYSTEMS) {
        return Err(PfError::Capacity {
            field: "sys",
            have: s.sys,
            max: MAX_SYSTEMS - 1,
        });
    }
    let mut x = [0.0f64; DIM];
    let [x0, y0, z0] = start;
    x[0] = x0;
    x[1] = y0;
    x[2] = z0;
    let mut step_m = f64::INFINITY;
    for it in 0..MAX_ITER {
        let mut a = SMatrix::<f64, DIM, DIM>::zeros();
        let mut b = SVector::<f64, DIM>::zeros();
        let mut seen = [false; DIM];
        for s in sats {
            let d = [s.sat_m[0] - x[0], s.sat_m[1] - x[1], s.sat_m[2] - x[2]];
            let r = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if !(r > 0.0) {
                continue;
            }
            let mut h = [0.0f64; DIM];
            h[0] = -d[0] / r;
            h[1] = -d[1] / r;
            h[2] = -d[2] / r;
            let ci = CLOCK0 + s.sys;
            // ci < CLOCK0 + MAX_SYSTEMS <= DIM (`sys` checked on entry).
            let Some(&clock) = x.get(ci) else {
                continue;
            };
            if let Some(c) = h.get_mut(ci) {
                *c = 1.0;
            }
            if let Some(f) = seen.get_mut(ci) {
                *f = true;
            }
            let h = SVector::<f64, DIM>::from(h);
            let w = 1.0 / (s.sigma_m * s.sigma_m);
            let z = s.pseudorange_m - r - clock;
            a += h * h.transpose() * w;
            b += h * (z * w);
        }
        for (i, &f) in seen.iter().enumerate().skip(CLOCK0) {
            if !f {
                if let Some(v) = a.get_mut((i, i)) {
                    *v += 1.0;
                }
            }
        }
        let Some(ch) = a.cholesky() else {
            return Err(PfError::NoInitialFix {
                iterations: it,
                step_m,
            });
        };
        let dx: [f64; DIM] = ch.solve(&b).into();
        for (v, d) in x.iter_mut().zip(dx.iter()) {
            *v += d;
        }
        step_m = libm::sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
        if !step_m.is_finite() {
            break;
        }
        if step_m < CONVERGED_M {
            let mut r = Reference {
                position_m: [x[0], x[1], x[2]],
                ..Reference::default()
            };
            for (c, v) in r.clock_m.iter_mut().zip(x.iter().skip(CLOCK0)) {
                *c = *v;
            }
            return Ok(r);
        }
    }
    Err(PfError::NoInitialFix {
        iterations: MAX_ITER,
        step_m,
    })
}
