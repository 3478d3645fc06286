//! Measurement model and position (SPEC §1): the whitened linear model in
//! local ENU, from either input form, and weighted Gauss-Newton in f64 for
//! pseudoranges with one receiver clock per constellation present.

use crate::config::Config;
use crate::error::RaimError;
use crate::frames::{ecef_to_geodetic, enu_rotation, rotate, unrotate, Geodetic};
use crate::linalg::parity::Parity;
use crate::linalg::qr::Householder;
use crate::measurement::{
    Epoch, LinearObservation, Observations, RangeObservation, SatId, System, MAX_STATES,
    MAX_SYSTEMS,
};

/// Below this norm (m) an a-priori position is "unknown" for the elevation
/// model: elevations are meaningless near the Earth's centre.
const SURFACE_RADIUS_MIN_M: f64 = 5.0e6;

/// A satellite closer than this to the receiver is an input error.
const MIN_RANGE_M: f64 = 1.0;

/// One solved subset of an epoch's satellites: the parity quantities of its
/// whitened ENU model, and the position.
#[derive(Debug, Clone)]
pub struct Solution<const N: usize> {
    pub parity: Parity<N>,
    /// Row k of the model is the epoch's satellite `source[k]`.
    pub source: [usize; N],
    pub ids: [SatId; N],
    pub sigma_m: [f64; N],
    pub elevation_rad: [f64; N],
    /// Which system each clock column (state 3 + j) belongs to.
    pub clocks: [Option<System>; MAX_SYSTEMS],
    /// ECEF position (pseudorange input) after Gauss-Newton.
    pub position_ecef_m: Option<[f64; 3]>,
    pub geodetic: Option<Geodetic>,
    /// ENU correction to the linearisation point, m (linear input), or zero
    /// after convergence (pseudorange input).
    pub correction_enu_m: [f64; 3],
    /// Receiver clock bias per system, m, in `System::ALL` order.
    pub clock_m: [Option<f64>; MAX_SYSTEMS],
    pub iterations: u32,
}

impl<const N: usize> Solution<N> {
    /// An empty solution, to be filled by [`solve_into`].
    pub fn empty() -> Self {
        Solution {
            parity: Parity::empty(),
            source: [0; N],
            ids: [SatId::default(); N],
            sigma_m: [0.0; N],
            elevation_rad: [0.0; N],
            clocks: [None; MAX_SYSTEMS],
            position_ecef_m: None,
            geodetic: None,
            correction_enu_m: [0.0; 3],
            clock_m: [None; MAX_SYSTEMS],
            iterations: 0,
        }
    }

    pub fn rows(&self) -> usize {
        self.parity.rows()
    }

    /// Row of the epoch satellite `index`, if it is in this subset.
    pub fn row_of(&self, index: usize) -> Option<usize> {
        self.source
            .iter()
            .take(self.rows())
            .position(|&s| s == index)
    }
}

/// Clock columns for the systems present among the selected satellites.
fn clock_columns(systems: impl Iterator<Item = System>) -> ([Option<System>; MAX_SYSTEMS], usize) {
    let mut present = [false; MAX_SYSTEMS];
    for s in systems {
        if let Some(p) = present.get_mut(s.index()) {
            *p = true;
        }
    }
    let mut cols = [None; MAX_SYSTEMS];
    let mut k = 0;
    for (sys, _) in System::ALL.iter().zip(present.iter()).filter(|(_, p)| **p) {
        if let Some(c) = cols.get_mut(k) {
            *c = Some(*sys);
        }
        k += 1;
    }
    (cols, k)
}

fn clock_column(cols: &[Option<System>; MAX_SYSTEMS], sys: System) -> Option<usize> {
    cols.iter().position(|c| *c == Some(sys))
}

/// Solve the subset `mask` (indexed like the epoch's satellites).
pub fn solve<const N: usize>(
    cfg: &Config,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
) -> Result<Solution<N>, RaimError> {
    let mut out = Solution::empty();
    solve_into(cfg, epoch, mask, &mut out)?;
    Ok(out)
}

/// [`solve`] into existing storage: nothing N-sized is built on the stack
/// but the model builder (the firmware's stack budget, BENCHMARKS.md). On
/// error, `out` holds no usable solution.
pub fn solve_into<const N: usize>(
    cfg: &Config,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
    out: &mut Solution<N>,
) -> Result<(), RaimError> {
    match epoch.observations {
        Observations::Linear { sats } => solve_linear(cfg, sats, mask, out),
        Observations::Ranges { sats, apriori_m } => {
            let (x, clock, cols, iterations) = gauss_newton(cfg, sats, apriori_m, mask)?;
            // Re-linearise once more at the converged point so the reported
            // model (residuals, parity) is exactly at x.
            finish_ranges(cfg, epoch, mask, x, clock, &cols, iterations, out)
        }
    }
}

// The helpers below are kept out of line so that their large locals
// (model buffers of N rows) occupy the stack one call at a time.

/// The linearised form: one least-squares solve at the given point.
#[inline(never)]
fn solve_linear<const N: usize>(
    cfg: &Config,
    sats: &[LinearObservation],
    mask: &[bool; N],
    out: &mut Solution<N>,
) -> Result<(), RaimError> {
    let mut b = Builder::<N>::new(
        sats.iter()
            .zip(mask.iter())
            .filter(|(_, m)| **m)
            .map(|(s, _)| s.id.system),
    );
    for (i, s) in sats
        .iter()
        .enumerate()
        .filter(|(i, _)| mask.get(*i).copied().unwrap_or(false))
    {
        let norm = libm::sqrt(s.los_enu.iter().map(|v| v * v).sum::<f64>());
        let u = [
            s.los_enu[0] / norm,
            s.los_enu[1] / norm,
            s.los_enu[2] / norm,
        ];
        let el = crate::frames::elevation_rad(u);
        let sigma = s.sigma_m.unwrap_or_else(|| cfg.sigma_model.sigma_m(el));
        b.push(i, s.id, u, s.residual_m, sigma, el)?;
    }
    b.parity_into(&mut out.parity)?;
    let dx = *out.parity.dx();
    let mut clock_m = [None; MAX_SYSTEMS];
    for (j, sys) in b.cols.iter().enumerate() {
        if let (Some(sys), Some(v)) = (sys, dx.get(3 + j)) {
            if let Some(c) = clock_m.get_mut(sys.index()) {
                *c = Some(*v);
            }
        }
    }
    b.fill(out);
    out.position_ecef_m = None;
    out.geodetic = None;
    out.correction_enu_m = [dx[0], dx[1], dx[2]];
    out.clock_m = clock_m;
    out.iterations = 1;
    Ok(())
}

/// Weighted Gauss-Newton from the a-priori point (or the Earth's centre):
/// position, clock per system, clock columns and the iteration count.
#[inline(never)]
#[allow(clippy::type_complexity)]
fn gauss_newton<const N: usize>(
    cfg: &Config,
    sats: &[RangeObservation],
    apriori_m: Option<[f64; 3]>,
    mask: &[bool; N],
) -> Result<
    (
        [f64; 3],
        [f64; MAX_SYSTEMS],
        [Option<System>; MAX_SYSTEMS],
        u32,
    ),
    RaimError,
> {
    let selected = || {
        sats.iter()
            .enumerate()
            .filter(|(i, _)| mask.get(*i).copied().unwrap_or(false))
    };
    let (cols, _) = clock_columns(selected().map(|(_, s)| s.id.system));
    let mut x = apriori_m.unwrap_or([0.0; 3]);
    let mut clock = [0.0; MAX_SYSTEMS];
    let mut last_step_m = f64::INFINITY;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < cfg.max_iterations {
        iterations += 1;
        let radius = libm::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        let on_surface = radius > SURFACE_RADIUS_MIN_M;
        let g = ecef_to_geodetic(x);
        let rot = enu_rotation(&g);
        let mut b = Builder::<N>::new(selected().map(|(_, s)| s.id.system));
        for (i, s) in selected() {
            let d = [
                s.position_m[0] - x[0],
                s.position_m[1] - x[1],
                s.position_m[2] - x[2],
            ];
            let range = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if !(range > MIN_RANGE_M) {
                return Err(RaimError::OutOfRange {
                    field: "range_m",
                    value: range,
                    min: MIN_RANGE_M,
                    max: f64::INFINITY,
                });
            }
            let u_ecef = [d[0] / range, d[1] / range, d[2] / range];
            // On the surface, use ENU so the model is final; near the
            // centre, ECEF axes are as good as any (position columns
            // are rotated back below).
            let u = if on_surface {
                rotate(&rot, u_ecef)
            } else {
                u_ecef
            };
            let el = if on_surface {
                crate::frames::elevation_rad(u)
            } else {
                core::f64::consts::FRAC_PI_2
            };
            let col = clock_column(&cols, s.id.system).unwrap_or(0);
            let z = s.pseudorange_m - range - clock.get(col).copied().unwrap_or(0.0);
            let sigma = match s.sigma_m {
                Some(v) => v,
                None if on_surface => cfg.sigma_model.sigma_m(el),
                None => 1.0,
            };
            b.push(i, s.id, u, z, sigma, el)?;
        }
        // A step needs only the least-squares solution, not the
        // parity quantities (those come once, at the solution).
        let dx = b.least_squares()?;
        let step_local = [dx[0], dx[1], dx[2]];
        let step = if on_surface {
            unrotate(&rot, step_local)
        } else {
            step_local
        };
        for (xk, dk) in x.iter_mut().zip(step.iter()) {
            *xk += dk;
        }
        for (j, c) in clock.iter_mut().enumerate() {
            *c += dx.get(3 + j).copied().unwrap_or(0.0);
        }
        last_step_m = libm::sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]);
        if !last_step_m.is_finite() {
            break;
        }
        if on_surface && last_step_m < cfg.convergence_m {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(RaimError::NoConvergence {
            iterations,
            step_m: last_step_m,
        });
    }
    Ok((x, clock, cols, iterations))
}

/// Build the final model at the converged position `x`.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn finish_ranges<const N: usize>(
    cfg: &Config,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
    x: [f64; 3],
    clock: [f64; MAX_SYSTEMS],
    cols: &[Option<System>; MAX_SYSTEMS],
    iterations: u32,
    out: &mut Solution<N>,
) -> Result<(), RaimError> {
    let Observations::Ranges { sats, .. } = epoch.observations else {
        return Err(RaimError::TooFewSatellites { have: 0, need: 1 });
    };
    let g = ecef_to_geodetic(x);
    let rot = enu_rotation(&g);
    let mut b = Builder::<N>::new(
        sats.iter()
            .enumerate()
            .filter(|(i, _)| mask.get(*i).copied().unwrap_or(false))
            .map(|(_, s)| s.id.system),
    );
    for (i, s) in sats
        .iter()
        .enumerate()
        .filter(|(i, _)| mask.get(*i).copied().unwrap_or(false))
    {
        let d = [
            s.position_m[0] - x[0],
            s.position_m[1] - x[1],
            s.position_m[2] - x[2],
        ];
        let range = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        let u = rotate(&rot, [d[0] / range, d[1] / range, d[2] / range]);
        let el = crate::frames::elevation_rad(u);
        let col = clock_column(cols, s.id.system).unwrap_or(0);
        let z = s.pseudorange_m - range - clock.get(col).copied().unwrap_or(0.0);
        let sigma = s.sigma_m.unwrap_or_else(|| cfg.sigma_model.sigma_m(el));
        b.push(i, s.id, u, z, sigma, el)?;
    }
    b.parity_into(&mut out.parity)?;
    let dx = *out.parity.dx();
    let mut clock_m = [None; MAX_SYSTEMS];
    for (j, sys) in cols.iter().enumerate() {
        if let Some(sys) = sys {
            let v = clock.get(j).copied().unwrap_or(0.0) + dx.get(3 + j).copied().unwrap_or(0.0);
            if let Some(c) = clock_m.get_mut(sys.index()) {
                *c = Some(v);
            }
        }
    }
    b.fill(out);
    out.clocks = *cols;
    out.position_ecef_m = Some(x);
    out.geodetic = Some(g);
    out.correction_enu_m = [dx[0], dx[1], dx[2]];
    out.clock_m = clock_m;
    out.iterations = iterations;
    Ok(())
}

/// Accumulates whitened rows [-u, onehot] / sigma and z / sigma.
struct Builder<const N: usize> {
    n: usize,
    m: usize,
    cols: [Option<System>; MAX_SYSTEMS],
    h: [[f64; N]; MAX_STATES],
    z: [f64; N],
    source: [usize; N],
    ids: [SatId; N],
    sigma: [f64; N],
    el: [f64; N],
}

impl<const N: usize> Builder<N> {
    fn new(systems: impl Iterator<Item = System>) -> Self {
        let (cols, k) = clock_columns(systems);
        Builder {
            n: 0,
            m: 3 + k,
            cols,
            h: [[0.0; N]; MAX_STATES],
            z: [0.0; N],
            source: [0; N],
            ids: [SatId::default(); N],
            sigma: [0.0; N],
            el: [0.0; N],
        }
    }

    fn push(
        &mut self,
        index: usize,
        id: SatId,
        u: [f64; 3],
        z: f64,
        sigma: f64,
        el: f64,
    ) -> Result<(), RaimError> {
        let k = self.n;
        if k >= N {
            return Err(RaimError::CapacityExceeded {
                have: k + 1,
                capacity: N,
            });
        }
        if !(sigma > 0.0) || !sigma.is_finite() {
            return Err(RaimError::NonPositiveSigma {
                index,
                sigma_m: sigma,
            });
        }
        let w = 1.0 / sigma;
        let clock = clock_column(&self.cols, id.system).map(|c| 3 + c);
        for (j, col) in self.h.iter_mut().enumerate() {
            let v = match j {
                0..=2 => -u.get(j).copied().unwrap_or(0.0) * w,
                _ if Some(j) == clock => w,
                _ => 0.0,
            };
            if let Some(cell) = col.get_mut(k) {
                *cell = v;
            }
        }
        let set = |a: &mut [f64; N], v: f64| {
            if let Some(c) = a.get_mut(k) {
                *c = v;
            }
        };
        set(&mut self.z, z * w);
        set(&mut self.sigma, sigma);
        set(&mut self.el, el);
        if let Some(c) = self.source.get_mut(k) {
            *c = index;
        }
        if let Some(c) = self.ids.get_mut(k) {
            *c = id;
        }
        self.n += 1;
        Ok(())
    }

    #[inline(never)]
    fn parity_into(&self, out: &mut Parity<N>) -> Result<(), RaimError> {
        out.compute(&self.h, &self.z, self.n, self.m)
    }

    /// Copy the per-row bookkeeping into a solution.
    fn fill(&self, out: &mut Solution<N>) {
        out.source = self.source;
        out.ids = self.ids;
        out.sigma_m = self.sigma;
        out.elevation_rad = self.el;
        out.clocks = self.cols;
    }

    /// The least-squares correction alone (a Gauss-Newton step).
    #[inline(never)]
    fn least_squares(&self) -> Result<[f64; MAX_STATES], RaimError> {
        if self.n <= self.m {
            return Err(RaimError::TooFewSatellites {
                have: self.n,
                need: self.m + 1,
            });
        }
        let qr = Householder::factor(&self.h, self.n, self.m)?;
        let mut z = self.z;
        qr.apply_ut(&mut z);
        let mut rhs = [0.0; MAX_STATES];
        for (r, v) in rhs.iter_mut().zip(z.iter()).take(self.m) {
            *r = *v;
        }
        Ok(qr.solve_t(&rhs))
    }
}
