//! Measurement model and position (SPEC §1): the whitened linear model in
//! local ENU, from either input form, and weighted Gauss-Newton in f64 for
//! pseudoranges with one receiver clock per constellation present.

use crate::config::Config;
use crate::error::RaimError;
use crate::frames::{
    bowring_latitude_rad, ecef_to_geodetic_from, enu_rotation, rotate, unrotate, Geodetic,
    WGS84_A_M, WGS84_F,
};
use crate::linalg::parity::Parity;
use crate::linalg::qr::Householder;
use crate::measurement::{
    Epoch, LinearObservation, Observations, RangeObservation, SatId, System, MAX_STATES,
    MAX_SYSTEMS,
};
use crate::real::{Real, Stat};
use nalgebra::Matrix3;

/// Below this norm (m) an a-priori position is "unknown" for the elevation
/// model: elevations are meaningless near the Earth's centre.
const SURFACE_RADIUS_MIN_M: f64 = 5.0e6;

/// A satellite closer than this to the receiver is an input error.
const MIN_RANGE_M: f64 = 1.0;

/// How far (m) Gauss-Newton's point may move from the linearisation point
/// before the geodetic conversion, the ENU rotation, the elevations and the
/// sigma model are evaluated again. 100 m tilts the local frame by at most
/// 100 m / 6.36e6 m = 1.6e-5 rad and turns a line of sight to a satellite
/// (>= 1.9e7 m away) by at most 5.3e-6 rad, so an elevation is off by at
/// most [`RELINEARISE_EL_RAD`]; the sigma model then moves by less than
/// 3e-4 relative (test `sigma_model_is_flat_within_the_relinearisation_bound`),
/// and the protection levels, whose axes tilt by 1.6e-5 rad, by less than
/// 2e-5 relative. The test statistic does not depend on the frame at all.
pub const RELINEARISE_M: f64 = 100.0;

/// The largest elevation error that reusing a linearisation within
/// [`RELINEARISE_M`] makes, rad (frame tilt plus line-of-sight turn).
pub const RELINEARISE_EL_RAD: f64 = RELINEARISE_M / 6.356e6 + RELINEARISE_M / 1.9e7;

/// The reported position's geodetic coordinates come from the final
/// linearisation's by a first-order update when the position is within this
/// distance of it (m): see `Linearisation::geodetic_of`.
pub const GEODETIC_LINEAR_MAX_M: f64 = 1.0;

/// After a Gauss-Newton step s, the next step is of the order of the
/// model's curvature times s^2, s^2 / (2 rho) with rho >= 1.9e7 m the range,
/// times the geometry's amplification (a few). When s^2 is below
/// `convergence_m` times this scale (m), i.e. 5e6 m = rho / 4 (an
/// amplification of 8 allowed for), the next step is expected to be below
/// `convergence_m` (s < 22 m at the default 1e-4 m): the next iteration
/// builds the full parity model, which is then final. A wrong guess costs
/// one more parity iteration, never a different answer.
pub const PARITY_STEP_SCALE_M: f64 = 5.0e6;

/// The rounding floor of a Gauss-Newton step computed in precision `T`,
/// as a length scale (m) times `T::EPS`. The residuals are formed in f64 at
/// every iteration (so the iteration is an iterative refinement and the
/// position converges), but the step solved from them in `T` carries an
/// error of about eps x cond(H) x |r| that does not shrink with the step:
/// |r| up to 1e3 m (a large fault) and cond(H) up to 100 give eps x 1e5 m.
/// In f32 that is 1.2e-2 m, above the default `convergence_m` (1e-4 m),
/// which an f32 step could then never reach; in f64 it is 2.2e-11 m, below
/// every configurable `convergence_m`, so the f64 engine is unchanged.
pub const STEP_ROUNDING_SCALE_M: f64 = 1.0e5;

/// Gauss-Newton in a precision coarser than f64 has stalled at its
/// rounding floor, and has converged, when a parity iteration's step (m)
/// after another parity iteration is below [`STALL_MAX_M`] and no smaller
/// than this fraction of the previous step: in the quadratic regime a real
/// step shrinks by orders of magnitude per iteration, so a step that does
/// not halve is rounding noise (eps x cond(H) x |r|, which on a weak f32
/// geometry reaches centimetres: 3 epochs in 10^6 of the equivalence
/// Monte Carlo stalled at 4-13 cm, docs/F32_EQUIVALENCE.md).
pub const STALL_RATIO: f64 = 0.5;

/// The largest step (m) that can count as stalled at the rounding floor
/// (a diverging iteration is never accepted: its steps grow).
pub const STALL_MAX_M: f64 = 1.0;

/// The step (m) below which Gauss-Newton in precision `T` has converged:
/// `convergence_m`, floored at the step's rounding noise
/// ([`STEP_ROUNDING_SCALE_M`]). The reported position is the last model's
/// least-squares estimate, within about the f32 noise (1e-4 m) of the f64
/// one; the parity quantities do not depend on where in that neighbourhood
/// the model is linearised (the difference lies in the column space of H).
pub fn convergence_bound_m<T: Real>(convergence_m: f64) -> f64 {
    let floor = T::EPS.to_f64() * STEP_ROUNDING_SCALE_M;
    if convergence_m > floor {
        convergence_m
    } else {
        floor
    }
}

/// One solved subset of an epoch's satellites: the parity quantities of its
/// whitened ENU model (in precision `T`, [`Stat`] by default),
/// and the position, elevations and sigmas (f64: docs/CORE.md, "Precision").
#[derive(Debug, Clone)]
pub struct Solution<const N: usize, T: Real = Stat> {
    /// The parity space of the weighted geometry.
    pub parity: Parity<N, T>,
    /// Row k of the model is the epoch's satellite `source[k]`.
    pub source: [usize; N],
    /// Satellite of each row.
    pub ids: [SatId; N],
    /// Sigma of each row, m.
    pub sigma_m: [f64; N],
    /// Elevation of each row, rad.
    pub elevation_rad: [f64; N],
    /// Which system each clock column (state 3 + j) belongs to.
    pub clocks: [Option<System>; MAX_SYSTEMS],
    /// ECEF position (pseudorange input) after Gauss-Newton.
    pub position_ecef_m: Option<[f64; 3]>,
    /// Geodetic position (pseudorange input).
    pub geodetic: Option<Geodetic>,
    /// The point whose local frame, elevations and sigmas the model uses
    /// (within [`RELINEARISE_M`] of the position; pseudorange input).
    pub linearisation: Option<Linearisation>,
    /// ENU correction to the linearisation point, m (linear input), or zero
    /// after convergence (pseudorange input).
    pub correction_enu_m: [f64; 3],
    /// Receiver clock bias per system, m, in `System::ALL` order.
    pub clock_m: [Option<f64>; MAX_SYSTEMS],
    /// Gauss-Newton iterations run (0 for linear input).
    pub iterations: u32,
}

impl<const N: usize, T: Real> Solution<N, T> {
    /// An empty solution, to be filled by [`solve_into`].
    pub const fn empty() -> Self {
        Solution {
            parity: Parity::empty(),
            source: [0; N],
            ids: [SatId::DEFAULT; N],
            sigma_m: [0.0; N],
            elevation_rad: [0.0; N],
            clocks: [None; MAX_SYSTEMS],
            position_ecef_m: None,
            geodetic: None,
            linearisation: None,
            correction_enu_m: [0.0; 3],
            clock_m: [None; MAX_SYSTEMS],
            iterations: 0,
        }
    }

    /// Number of rows (satellites) in the model.
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
    clock_columns_of(&present)
}

/// [`clock_columns`] from the systems present, by `System::index`.
fn clock_columns_of(present: &[bool; MAX_SYSTEMS]) -> ([Option<System>; MAX_SYSTEMS], usize) {
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

/// Where Gauss-Newton starts, and what it may reuse (docs/CORE.md, "Do the
/// work once").
#[derive(Debug, Clone, Copy)]
pub enum Start<'a, const N: usize, T: Real = Stat> {
    /// From the epoch's a-priori position, or the Earth's centre.
    Cold,
    /// From a previous epoch's solution (the engine's warm start).
    Fix(Fix),
    /// From another solution of the *same* epoch (an FDE subset): its
    /// position and clocks, and its per-satellite elevations and sigmas,
    /// which stay valid while the point moves less than [`RELINEARISE_M`].
    Sibling(&'a Solution<N, T>),
}

/// A position and receiver clocks to start Gauss-Newton from.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fix {
    /// Epoch time, s.
    pub time_s: f64,
    /// ECEF position, m.
    pub position_ecef_m: [f64; 3],
    /// Receiver clock bias per system, m, in `System::ALL` order.
    pub clock_m: [Option<f64>; MAX_SYSTEMS],
}

impl Fix {
    /// The fix of a pseudorange solution (none for the linearised form).
    pub fn of<const N: usize, T: Real>(time_s: f64, sol: &Solution<N, T>) -> Option<Fix> {
        sol.position_ecef_m.map(|position_ecef_m| Fix {
            time_s,
            position_ecef_m,
            clock_m: sol.clock_m,
        })
    }
}

/// Solve the subset `mask` (indexed like the epoch's satellites), cold, in
/// the default precision [`Stat`] (f64; any precision: [`solve_into`]).
pub fn solve<const N: usize>(
    cfg: &Config,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
) -> Result<Solution<N, Stat>, RaimError> {
    let mut out = Solution::empty();
    solve_into(cfg, epoch, mask, &mut out)?;
    Ok(out)
}

/// [`solve`] into existing storage: nothing N-sized is built on the stack
/// but the model builder (the firmware's stack budget, BENCHMARKS.md). On
/// error, `out` holds no usable solution.
pub fn solve_into<const N: usize, T: Real>(
    cfg: &Config,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
    out: &mut Solution<N, T>,
) -> Result<(), RaimError> {
    solve_from(cfg, epoch, mask, Start::Cold, out)
}

/// [`solve_into`] from a [`Start`]: a warm start from the last epoch's fix,
/// or from a solution of the same epoch whose per-satellite model is reused.
pub fn solve_from<const N: usize, T: Real>(
    cfg: &Config,
    epoch: &Epoch<'_>,
    mask: &[bool; N],
    start: Start<'_, N, T>,
    out: &mut Solution<N, T>,
) -> Result<(), RaimError> {
    let sibling = match start {
        Start::Sibling(s) => Some(s),
        _ => None,
    };
    match epoch.observations {
        Observations::Linear { sats } => solve_linear(cfg, sats, mask, sibling, out),
        Observations::Ranges { sats, apriori_m } => {
            gauss_newton(cfg, sats, apriori_m, mask, start, out)
        }
    }
}

// The helpers below are kept out of line so that their large locals
// (model buffers of N rows) occupy the stack one call at a time.

/// The elevation and sigma of epoch satellites as a sibling solution of
/// the same epoch has them (same line of sight, same model), for indices
/// asked in increasing order: a cursor over the sibling's rows, which
/// `Builder` fills in increasing epoch order, so a subset's lookups cost
/// O(n) in all instead of a search per row. A row the cursor
/// does not find where expected is searched for in full, so the answer
/// never depends on that order.
struct SiblingModel<'a, const N: usize, T: Real> {
    sibling: Option<&'a Solution<N, T>>,
    next_row: usize,
}

impl<'a, const N: usize, T: Real> SiblingModel<'a, N, T> {
    fn new(sibling: Option<&'a Solution<N, T>>) -> Self {
        SiblingModel {
            sibling,
            next_row: 0,
        }
    }

    /// The sibling's (elevation, sigma) of the epoch satellite `index`.
    fn get(&mut self, index: usize) -> Option<(f64, f64)> {
        let s = self.sibling?;
        let rows = s.rows();
        let mut row = self.next_row;
        while row < rows && s.source.get(row).is_some_and(|&src| src < index) {
            row += 1;
        }
        let row = if row < rows && s.source.get(row) == Some(&index) {
            row
        } else {
            s.row_of(index)?
        };
        self.next_row = row + 1;
        Some((*s.elevation_rad.get(row)?, *s.sigma_m.get(row)?))
    }
}

/// The linearised form: one least-squares solve at the given point.
///
/// The model is built in passes over the selected rows rather than one
/// satellite at a time, so that the arithmetic passes are straight-line
/// loops the compiler vectorises and the elevations' `atan` calls run in a
/// loop of their own: (1) [`gather`] the selected satellites and their
/// unit lines of sight in `T`; (2) [`elevations_and_sigmas`] (a sibling's
/// where given); (3) [`check_sigmas`], in row order, so that the first
/// offender is named; (4) [`whiten`]: the weights and the whitened rows
/// [-u, clock] / sigma and z / sigma. Each row's operations are those of
/// `Builder::push`, so the bits are the same. In the f64 engine
/// ([`Kernels::LANE_SUMS`](crate::linalg::Kernels::LANE_SUMS)); the f32
/// engine keeps [`solve_linear_by_row`].
#[inline(never)]
fn solve_linear<const N: usize, T: Real>(
    cfg: &Config,
    sats: &[LinearObservation],
    mask: &[bool; N],
    sibling: Option<&Solution<N, T>>,
    out: &mut Solution<N, T>,
) -> Result<(), RaimError> {
    if !T::LANE_SUMS {
        return solve_linear_by_row(cfg, sats, mask, sibling, out);
    }
    let mut h = [[T::zero(); N]; MAX_STATES];
    let mut z = [T::zero(); N];
    // Whether the satellite carries its own sigma (then in `sigma_m`).
    let mut given = [false; N];
    let (n, present) = gather(sats, mask, out, &mut h, &mut z, &mut given);
    let (cols, clocks) = clock_columns_of(&present);
    let m = 3 + clocks;
    // Rows n.. as a fresh builder leaves them (the storage is reused
    // across epochs; nothing reads past `rows()`, but nothing stale stays).
    out.source.iter_mut().skip(n).for_each(|v| *v = 0);
    out.ids
        .iter_mut()
        .skip(n)
        .for_each(|v| *v = SatId::default());
    out.sigma_m.iter_mut().skip(n).for_each(|v| *v = 0.0);
    out.elevation_rad.iter_mut().skip(n).for_each(|v| *v = 0.0);
    elevations_and_sigmas(cfg, sibling, out, &h, &given, n);
    // n <= N: `gather` counts rows zipped with the N-row arrays.
    #[allow(clippy::indexing_slicing)]
    let sigmas = &out.sigma_m[..n.min(N)];
    check_sigmas(sigmas, &out.source)?;
    whiten(sigmas, &out.ids, &cols, &mut h, &mut z, n);
    out.parity.compute(&h, &z, n, m)?;
    out.clocks = cols;
    finish_linear(out);
    Ok(())
}

/// Pass (1) of [`solve_linear`]: the selected satellites in epoch order
/// into `out`'s source, ID and (given) sigma rows, their unit lines of
/// sight in `T` into `h`'s first three columns (the same operations as in
/// f64) and their residuals into `z` (whitened in pass (4)). Returns the
/// row count and the systems present (their clock columns).
#[inline(always)]
fn gather<const N: usize, T: Real>(
    sats: &[LinearObservation],
    mask: &[bool; N],
    out: &mut Solution<N, T>,
    h: &mut [[T; N]; MAX_STATES],
    z: &mut [T; N],
    given: &mut [bool; N],
) -> (usize, [bool; MAX_SYSTEMS]) {
    let mut present = [false; MAX_SYSTEMS];
    let mut n = 0;
    let [he, hn, hu, ..] = h;
    let rows = out
        .source
        .iter_mut()
        .zip(out.ids.iter_mut())
        .zip(
            z.iter_mut()
                .zip(given.iter_mut())
                .zip(out.sigma_m.iter_mut()),
        )
        .zip(he.iter_mut().zip(hn.iter_mut()).zip(hu.iter_mut()));
    let selected = sats
        .iter()
        .enumerate()
        .zip(mask.iter())
        .filter(|(_, m)| **m)
        .map(|(s, _)| s);
    for ((((src, id), ((r, g), sg)), ((e, nn), u)), (i, s)) in rows.zip(selected) {
        let l = s.los_enu.map(T::of);
        let norm = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        *e = l[0] / norm;
        *nn = l[1] / norm;
        *u = l[2] / norm;
        *src = i;
        *id = s.id;
        *r = T::of(s.residual_m);
        (*g, *sg) = match s.sigma_m {
            Some(v) => (true, v),
            None => (false, 0.0),
        };
        if let Some(p) = present.get_mut(s.id.system.index()) {
            *p = true;
        }
        n += 1;
    }
    (n, present)
}

/// Pass (2) of [`solve_linear`]: each row's elevation and sigma (its own
/// where `given`, else the configuration's model). They depend on the line
/// of sight alone, so a sibling's are bit for bit what would be computed
/// here, and are taken from it.
#[inline(always)]
fn elevations_and_sigmas<const N: usize, T: Real>(
    cfg: &Config,
    sibling: Option<&Solution<N, T>>,
    out: &mut Solution<N, T>,
    h: &[[T; N]; MAX_STATES],
    given: &[bool; N],
    n: usize,
) {
    let [he, hn, hu, ..] = h;
    let units = he.iter().zip(hn.iter()).zip(hu.iter()).take(n);
    let model = out
        .elevation_rad
        .iter_mut()
        .zip(out.sigma_m.iter_mut())
        .zip(given.iter())
        .zip(units);
    let mut sibling_model = SiblingModel::new(sibling);
    for ((((el, sigma), g), ((&e, &nn), &u)), &src) in model.zip(out.source.iter()) {
        let from_sibling = match sibling {
            Some(_) => sibling_model.get(src),
            None => None,
        };
        (*el, *sigma) = match from_sibling {
            Some(v) => v,
            None => {
                let elev = crate::frames::elevation([e, nn, u]);
                let sg = if *g {
                    *sigma
                } else {
                    cfg.sigma_model.sigma(elev).to_f64()
                };
                (elev.to_f64(), sg)
            }
        };
    }
}

/// Pass (3) of [`solve_linear`]: every sigma positive and finite (NaN
/// fails both comparisons), in one branch-free pass; the first offender in
/// row order is named (by its epoch index in `source`) only when there is
/// one.
#[inline(always)]
fn check_sigmas(sigmas: &[f64], source: &[usize]) -> Result<(), RaimError> {
    if !sigmas
        .iter()
        .fold(true, |ok, &s| ok & (s > 0.0) & (s <= f64::MAX))
    {
        for (&sigma_m, &index) in sigmas.iter().zip(source.iter()) {
            if !(sigma_m > 0.0 && sigma_m < f64::INFINITY) {
                return Err(RaimError::NonPositiveSigma { index, sigma_m });
            }
        }
    }
    Ok(())
}

/// Pass (4) of [`solve_linear`]: the weight 1 / sigma in `T`, the rows
/// -u / sigma, z / sigma, and column 3 + j, the clock of system `cols[j]`:
/// the weight on its satellites' rows, zero elsewhere (the storage is
/// fresh). These are `Builder::push`'s operations.
#[inline(always)]
fn whiten<const N: usize, T: Real>(
    sigmas: &[f64],
    ids: &[SatId; N],
    cols: &[Option<System>; MAX_SYSTEMS],
    h: &mut [[T; N]; MAX_STATES],
    z: &mut [T; N],
    n: usize,
) {
    let mut wt = [T::zero(); N];
    for (w, &sg) in wt.iter_mut().zip(sigmas.iter()) {
        *w = T::one() / T::of(sg);
    }
    for col in h.iter_mut().take(3) {
        for (v, &w) in col.iter_mut().zip(wt.iter()).take(n) {
            *v = -*v * w;
        }
    }
    for (zk, &w) in z.iter_mut().zip(wt.iter()).take(n) {
        *zk *= w;
    }
    for (col, sys) in h.iter_mut().skip(3).zip(cols.iter()) {
        let Some(sys) = sys else {
            continue;
        };
        for ((v, id), &w) in col.iter_mut().zip(ids.iter()).zip(wt.iter()).take(n) {
            if id.system == *sys {
                *v = w;
            }
        }
    }
}

/// The linearised solution's outputs from its parity space: the ENU
/// correction, each clock column's estimate by system, and no ECEF
/// position (both linear forms; `out.clocks` already set).
fn finish_linear<const N: usize, T: Real>(out: &mut Solution<N, T>) {
    let dx = out.parity.dx().map(T::to_f64);
    let mut clock_m = [None; MAX_SYSTEMS];
    for (j, sys) in out.clocks.iter().enumerate() {
        if let (Some(sys), Some(v)) = (sys, dx.get(3 + j)) {
            if let Some(c) = clock_m.get_mut(sys.index()) {
                *c = Some(*v);
            }
        }
    }
    out.position_ecef_m = None;
    out.geodetic = None;
    out.linearisation = None;
    out.correction_enu_m = [dx[0], dx[1], dx[2]];
    out.clock_m = clock_m;
    out.iterations = 1;
}

/// [`solve_linear`] one satellite at a time through `Builder::push`: the
/// f32 engine's form (the M4F, where the passes' code would cost flash and
/// nothing vectorises); the same results bit for bit (test
/// `linear_passes_equal_the_row_builder`).
#[inline(never)]
fn solve_linear_by_row<const N: usize, T: Real>(
    cfg: &Config,
    sats: &[LinearObservation],
    mask: &[bool; N],
    sibling: Option<&Solution<N, T>>,
    out: &mut Solution<N, T>,
) -> Result<(), RaimError> {
    let mut b = Builder::<N, T>::new(
        sats.iter()
            .zip(mask.iter())
            .filter(|(_, m)| **m)
            .map(|(s, _)| s.id.system),
    );
    let mut sibling_model = SiblingModel::new(sibling);
    for (i, s) in sats
        .iter()
        .zip(mask.iter())
        .enumerate()
        .filter(|(_, (_, m))| **m)
        .map(|(i, (s, _))| (i, s))
    {
        // The unit line of sight, its elevation and the sigma model in `T`
        // (the same operations as in f64).
        let l = s.los_enu.map(T::of);
        let norm = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        let u = [l[0] / norm, l[1] / norm, l[2] / norm];
        // The elevation and sigma depend on the line of sight alone, so a
        // sibling's are bit for bit what would be computed here.
        let (el, sigma) = match sibling_model.get(i) {
            Some(v) => v,
            None => {
                let el = crate::frames::elevation(u);
                let sigma = match s.sigma_m {
                    Some(v) => v,
                    None => cfg.sigma_model.sigma(el).to_f64(),
                };
                (el.to_f64(), sigma)
            }
        };
        b.push(i, s.id, u, s.residual_m, sigma, el)?;
    }
    b.parity_into(&mut out.parity)?;
    b.fill(out);
    finish_linear(out);
    Ok(())
}

/// The local frame of one linearisation point: the point, its geodetic
/// coordinates and the ECEF-to-ENU rotation. Elevations and sigmas are
/// computed in it and reused until the point moves by [`RELINEARISE_M`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linearisation {
    /// The linearisation point, ECEF m.
    pub point_ecef_m: [f64; 3],
    /// Its geodetic coordinates.
    pub geodetic: Geodetic,
    /// The ECEF-to-ENU rotation at the point.
    pub rotation: Matrix3<f64>,
}

impl Linearisation {
    fn at(point_ecef_m: [f64; 3], near: Option<&Linearisation>) -> Self {
        // The same fixed point either way: started from the previous
        // latitude, or from Bowring's closed form (1-2 iterations instead
        // of 10).
        let lat0_rad = match near {
            Some(l) => l.geodetic.lat_rad,
            None => bowring_latitude_rad(point_ecef_m),
        };
        let geodetic = ecef_to_geodetic_from(point_ecef_m, lat0_rad);
        Linearisation {
            point_ecef_m,
            geodetic,
            rotation: enu_rotation(&geodetic),
        }
    }

    /// The geodetic coordinates of a point `x` within
    /// [`GEODETIC_LINEAR_MAX_M`] of this one, by the first-order update
    /// through the local frame: lat += dN / (M + h), lon += dE / ((N + h)
    /// cos lat), h += dU. The neglected second-order terms are below
    /// d^2 / R = 1.6e-7 m (d <= 1 m), far under the iterative conversion's
    /// own tolerance (`GEODETIC_STEP_TOL_RAD`, 0.6 mm). Further away, or
    /// near a pole, the iterative conversion.
    fn geodetic_of(&self, x: [f64; 3]) -> Geodetic {
        let d = [
            x[0] - self.point_ecef_m[0],
            x[1] - self.point_ecef_m[1],
            x[2] - self.point_ecef_m[2],
        ];
        let dist = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        // Rows E, N, U; sin and cos of the latitude are U_z and N_z.
        let r = &self.rotation;
        let (sl, cl) = (r[(2, 2)], r[(1, 2)]);
        let g = self.geodetic;
        let pi = core::f64::consts::PI;
        if !(dist <= GEODETIC_LINEAR_MAX_M) || !(cl > 1e-6) {
            return ecef_to_geodetic_from(x, g.lat_rad);
        }
        let [de, dn, du] = rotate(r, d);
        let e2 = WGS84_F * (2.0 - WGS84_F);
        let w = libm::sqrt(1.0 - e2 * sl * sl);
        let n_rad = WGS84_A_M / w;
        let m_rad = n_rad * (1.0 - e2) / (w * w);
        let lon_rad = g.lon_rad + de / ((n_rad + g.height_m) * cl);
        if !(lon_rad > -pi && lon_rad <= pi) {
            return ecef_to_geodetic_from(x, g.lat_rad);
        }
        Geodetic {
            lat_rad: g.lat_rad + dn / (m_rad + g.height_m),
            lon_rad,
            height_m: g.height_m + du,
        }
    }

    fn distance_m(&self, x: &[f64; 3]) -> f64 {
        let d = [
            x[0] - self.point_ecef_m[0],
            x[1] - self.point_ecef_m[1],
            x[2] - self.point_ecef_m[2],
        ];
        libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    }
}

/// Weighted Gauss-Newton (SPEC §1) from `start`, filling `out` with the
/// parity quantities of the model at the reported position.
///
/// Work done once (docs/CORE.md, "Do the work once"): the geodetic
/// conversion, the ENU rotation, the elevations and the sigma model are
/// evaluated at a linearisation point and reused on later iterations (and,
/// through [`Start::Sibling`], by the FDE subsets of the same epoch) until
/// the position has moved by more than [`RELINEARISE_M`]. Only the range,
/// the unit line of sight and the residual are formed on every iteration.
/// The iteration stops when the position step is below
/// `cfg.convergence_m`. Once a step is small enough ([`PARITY_STEP_SCALE_M`]), the next
/// iteration builds the full parity model instead of the bare least-squares
/// step, so the converged iteration is also the final model: the reported
/// position is its least-squares estimate (the point plus the last step, <
/// `convergence_m`), and `correction_enu_m` is zero.
#[inline(never)]
fn gauss_newton<const N: usize, T: Real>(
    cfg: &Config,
    sats: &[RangeObservation],
    apriori_m: Option<[f64; 3]>,
    mask: &[bool; N],
    start: Start<'_, N, T>,
    out: &mut Solution<N, T>,
) -> Result<(), RaimError> {
    let converged_m = convergence_bound_m::<T>(cfg.convergence_m);
    // One builder for all iterations: its rows are the selected
    // satellites in order, and its per-row elevations and sigmas are the
    // cache, valid while `cached` (same linearisation, on the surface).
    let mut b = Builder::<N, T>::new(selected(sats, mask).map(|(_, s)| s.id.system));
    let cols = b.cols;
    // The ECEF-to-ENU rotation of `lin` in `T`, for the lines of sight.
    let mut rot = Matrix3::<T>::identity();
    let StartPoint {
        mut x,
        clock_m: start_clock,
        mut lin,
        mut cached,
    } = starting_point(start, apriori_m, &mut b, sats, mask);
    let mut clock = column_clocks(&cols, &start_clock);
    let mut last_step_m = f64::INFINITY;
    let mut last_full = false;
    let mut iterations = 0;
    while iterations < cfg.max_iterations {
        iterations += 1;
        let radius = libm::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        let on_surface = radius > SURFACE_RADIUS_MIN_M;
        if on_surface
            && lin
                .as_ref()
                .is_none_or(|l| !(l.distance_m(&x) <= RELINEARISE_M))
        {
            lin = Some(Linearisation::at(x, lin.as_ref()));
            cached = false;
        }
        let frame = if on_surface { lin } else { None };
        if let Some(l) = &frame {
            rot = l.rotation.map(T::of);
        }
        let reuse = cached && frame.is_some();
        linearise(
            cfg,
            &mut b,
            selected(sats, mask),
            &x,
            &clock,
            frame.as_ref().map(|_| &rot),
            reuse,
        )?;
        cached = frame.is_some();
        let full = frame.is_some() && last_step_m * last_step_m < converged_m * PARITY_STEP_SCALE_M;
        // A step needs only the least-squares solution; the parity
        // quantities come once, with the final model.
        let dx = if full {
            b.parity_into(&mut out.parity)?;
            out.parity.dx().map(T::to_f64)
        } else {
            b.least_squares()?.map(T::to_f64)
        };
        let (step, step_m) = position_step(frame.as_ref(), &dx);
        let stalled = stalled::<T>(full && last_full, step_m, last_step_m);
        if let (Some(l), true) = (frame, step_m < converged_m || stalled) {
            // Converged: this iteration's model, at x, is the solution.
            if !full {
                b.parity_into(&mut out.parity)?;
            }
            let x_ls = [x[0] + step[0], x[1] + step[1], x[2] + step[2]];
            converged(&b, l, x_ls, &clock, iterations, out);
            return Ok(());
        }
        for (xk, dk) in x.iter_mut().zip(step.iter()) {
            *xk += dk;
        }
        for (c, d) in clock.iter_mut().zip(dx.iter().skip(3)) {
            *c += d;
        }
        last_step_m = step_m;
        last_full = full;
        if !last_step_m.is_finite() {
            break;
        }
    }
    Err(RaimError::NoConvergence {
        iterations,
        step_m: last_step_m,
    })
}

/// Where Gauss-Newton starts: the position, the clocks by system, and the
/// linearisation in force with whether the builder's per-row elevations
/// and sigmas are valid for it (`cached`).
struct StartPoint {
    x: [f64; 3],
    clock_m: [Option<f64>; MAX_SYSTEMS],
    lin: Option<Linearisation>,
    cached: bool,
}

/// The [`StartPoint`] of `start`: a cold start at the a-priori position
/// (or the Earth's centre) with no clocks, a fix's position and clocks,
/// or a sibling's, whose linearisation and rows `b` takes over
/// ([`sibling_rows`]).
fn starting_point<const N: usize, T: Real>(
    start: Start<'_, N, T>,
    apriori_m: Option<[f64; 3]>,
    b: &mut Builder<N, T>,
    sats: &[RangeObservation],
    mask: &[bool; N],
) -> StartPoint {
    match start {
        Start::Cold => StartPoint {
            x: apriori_m.unwrap_or([0.0; 3]),
            clock_m: [None; MAX_SYSTEMS],
            lin: None,
            cached: false,
        },
        Start::Fix(f) => StartPoint {
            x: f.position_ecef_m,
            clock_m: f.clock_m,
            lin: None,
            cached: false,
        },
        Start::Sibling(s) => {
            let lin = s.linearisation;
            let cached = lin.is_some() && sibling_rows(b, s, selected(sats, mask));
            StartPoint {
                x: s.position_ecef_m.or(apriori_m).unwrap_or([0.0; 3]),
                clock_m: s.clock_m,
                lin,
                cached,
            }
        }
    }
}

/// The position part of the state step `dx` in ECEF (rotated back from
/// ENU when the iteration runs in a local frame), and its length, m.
fn position_step(frame: Option<&Linearisation>, dx: &[f64; MAX_STATES]) -> ([f64; 3], f64) {
    let [e, n, u, ..] = *dx;
    let step = match frame {
        Some(l) => unrotate(&l.rotation, [e, n, u]),
        None => [e, n, u],
    };
    let step_m = libm::sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]);
    (step, step_m)
}

/// Gauss-Newton has stalled at the rounding floor: in a precision coarser
/// than f64 (on a weak geometry), two consecutive parity iterations
/// (`both_parity`) whose step, below [`STALL_MAX_M`], no longer shrinks by
/// [`STALL_RATIO`]. Counted as converged.
fn stalled<T: Real>(both_parity: bool, step_m: f64, last_step_m: f64) -> bool {
    T::EPS.to_f64() > f64::EPSILON
        && both_parity
        && step_m < STALL_MAX_M
        && !(step_m < STALL_RATIO * last_step_m)
}

/// The satellites `mask` selects, with their index in `sats`, in order (a
/// satellite beyond the mask's N is not selected).
fn selected<'a, const N: usize>(
    sats: &'a [RangeObservation],
    mask: &'a [bool; N],
) -> impl Iterator<Item = (usize, &'a RangeObservation)> + 'a {
    sats.iter()
        .enumerate()
        .filter(|(i, _)| mask.get(*i) == Some(&true))
}

/// A sibling start's cache: each selected satellite's elevation and
/// sigma from the sibling solution's rows (the same linearisation).
/// Returns whether every satellite had one.
fn sibling_rows<'a, const N: usize, T: Real>(
    b: &mut Builder<N, T>,
    sibling: &Solution<N, T>,
    rows: impl Iterator<Item = (usize, &'a RangeObservation)>,
) -> bool {
    let mut cached = true;
    let mut sibling_model = SiblingModel::new(Some(sibling));
    for (k, (i, _)) in rows.enumerate() {
        match (sibling_model.get(i), b.el.get_mut(k), b.sigma.get_mut(k)) {
            (Some((el, sigma)), Some(e), Some(g)) => {
                *e = el;
                *g = sigma;
            }
            _ => cached = false,
        }
    }
    cached
}

/// The clock of each column, from the start's clock of the column's
/// system (0 where it has none).
fn column_clocks(
    cols: &[Option<System>; MAX_SYSTEMS],
    start_clock: &[Option<f64>; MAX_SYSTEMS],
) -> [f64; MAX_SYSTEMS] {
    let mut clock = [0.0; MAX_SYSTEMS];
    for (c, sys) in clock.iter_mut().zip(cols.iter()) {
        if let Some(v) = sys.and_then(|s| start_clock.get(s.index()).copied().flatten()) {
            *c = v;
        }
    }
    clock
}

/// The linear model at x (SPEC §1): per selected satellite the row
/// [-u^T, c^T] (u the unit line of sight, in ENU through `rot` on the
/// surface, else ECEF with unit weight) and z = rho - |s - x| - clock, with
/// its elevation and sigma (from the cache when `reuse`).
fn linearise<'a, const N: usize, T: Real>(
    cfg: &Config,
    b: &mut Builder<N, T>,
    rows: impl Iterator<Item = (usize, &'a RangeObservation)>,
    x: &[f64; 3],
    clock: &[f64; MAX_SYSTEMS],
    rot: Option<&Matrix3<T>>,
    reuse: bool,
) -> Result<(), RaimError> {
    let cols = b.cols;
    b.n = 0;
    for (k, (i, s)) in rows.enumerate() {
        let d = [
            s.position_m[0] - x[0],
            s.position_m[1] - x[1],
            s.position_m[2] - x[2],
        ];
        let range = T::range_sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if !(range > MIN_RANGE_M) {
            return Err(RaimError::OutOfRange {
                field: "range_m",
                value: range,
                min: MIN_RANGE_M,
                max: f64::INFINITY,
            });
        }
        // The unit line of sight in `T` (the policy: only the range and
        // the residual need f64).
        let r_t = T::of(range);
        let u_ecef = [T::of(d[0]) / r_t, T::of(d[1]) / r_t, T::of(d[2]) / r_t];
        // On the surface, use ENU so the model is final; near the centre,
        // ECEF axes are as good as any (position columns are rotated back
        // by the caller) and the weights are unit.
        let (u, el, sigma) = match rot {
            Some(rot) => {
                let u = rotate(rot, u_ecef);
                let (el, sigma) = match (reuse, b.el.get(k), b.sigma.get(k)) {
                    (true, Some(&el), Some(&sigma)) => (el, sigma),
                    _ => {
                        let el = crate::frames::elevation(u);
                        let sigma = match s.sigma_m {
                            Some(v) => v,
                            None => cfg.sigma_model.sigma(el).to_f64(),
                        };
                        (el.to_f64(), sigma)
                    }
                };
                (u, el, sigma)
            }
            None => (
                u_ecef,
                core::f64::consts::FRAC_PI_2,
                s.sigma_m.unwrap_or(1.0),
            ),
        };
        // The builder's columns are those of the selected systems, so the
        // system has one; a system without a column would have no clock
        // term in its row (`push`), and none is subtracted here either.
        let clock_m = cols
            .iter()
            .zip(clock.iter())
            .find(|(c, _)| **c == Some(s.id.system))
            .map(|(_, v)| *v);
        debug_assert!(clock_m.is_some(), "every selected system has a column");
        let z = match clock_m {
            Some(c) => s.pseudorange_m - range - c,
            None => s.pseudorange_m - range,
        };
        b.push(i, s.id, u, z, sigma, el)?;
    }
    Ok(())
}

/// The converged solution (the model of this iteration, at x, with the
/// parity quantities in `out.parity`): the least-squares position x_ls =
/// x + dx, each column's clock plus its correction, the rows.
fn converged<const N: usize, T: Real>(
    b: &Builder<N, T>,
    l: Linearisation,
    x_ls: [f64; 3],
    clock: &[f64; MAX_SYSTEMS],
    iterations: u32,
    out: &mut Solution<N, T>,
) {
    let cols = b.cols;
    let dx = out.parity.dx().map(T::to_f64);
    let mut clock_m = [None; MAX_SYSTEMS];
    for ((sys, &c), &d) in cols.iter().zip(clock.iter()).zip(dx.iter().skip(3)) {
        if let Some(sys) = sys {
            let v = c + d;
            if let Some(c) = clock_m.get_mut(sys.index()) {
                *c = Some(v);
            }
        }
    }
    b.fill(out);
    out.clocks = cols;
    out.position_ecef_m = Some(x_ls);
    out.geodetic = Some(l.geodetic_of(x_ls));
    out.linearisation = Some(l);
    out.correction_enu_m = [0.0; 3];
    out.clock_m = clock_m;
    out.iterations = iterations;
}

/// Accumulates whitened rows [-u, onehot] / sigma and z / sigma, in `T`
/// (the residual z itself is formed in f64 by the caller).
struct Builder<const N: usize, T: Real> {
    n: usize,
    m: usize,
    cols: [Option<System>; MAX_SYSTEMS],
    h: [[T; N]; MAX_STATES],
    z: [T; N],
    source: [usize; N],
    ids: [SatId; N],
    sigma: [f64; N],
    el: [f64; N],
}

impl<const N: usize, T: Real> Builder<N, T> {
    fn new(systems: impl Iterator<Item = System>) -> Self {
        let (cols, k) = clock_columns(systems);
        Builder {
            n: 0,
            m: 3 + k,
            cols,
            h: [[T::zero(); N]; MAX_STATES],
            z: [T::zero(); N],
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
        u: [T; 3],
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
        // Positive and finite (NaN fails both comparisons): two comparisons
        // (`!(sigma > 0.0) || !sigma.is_finite()`
        // compiled to a 28-instruction classification per satellite).
        if !(sigma > 0.0 && sigma < f64::INFINITY) {
            return Err(RaimError::NonPositiveSigma {
                index,
                sigma_m: sigma,
            });
        }
        // The weight in `T`; in f64 the same operations as before.
        let wt = T::one() / T::of(sigma);
        let clock = clock_column(&self.cols, id.system).map(|c| 3 + c);
        let [u0, u1, u2] = u;
        for (j, col) in self.h.iter_mut().enumerate() {
            let v = match j {
                0 => -u0 * wt,
                1 => -u1 * wt,
                2 => -u2 * wt,
                _ if Some(j) == clock => wt,
                _ => T::zero(),
            };
            if let Some(cell) = col.get_mut(k) {
                *cell = v;
            }
        }
        if let Some(c) = self.z.get_mut(k) {
            *c = T::of(z) * wt;
        }
        let set = |a: &mut [f64; N], v: f64| {
            if let Some(c) = a.get_mut(k) {
                *c = v;
            }
        };
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
    fn parity_into(&self, out: &mut Parity<N, T>) -> Result<(), RaimError> {
        out.compute(&self.h, &self.z, self.n, self.m)
    }

    /// Copy the per-row bookkeeping into a solution.
    fn fill(&self, out: &mut Solution<N, T>) {
        out.source = self.source;
        out.ids = self.ids;
        out.sigma_m = self.sigma;
        out.elevation_rad = self.el;
        out.clocks = self.cols;
    }

    /// The least-squares correction alone (a Gauss-Newton step).
    #[inline(never)]
    fn least_squares(&self) -> Result<[T; MAX_STATES], RaimError> {
        if self.n <= self.m {
            return Err(RaimError::TooFewSatellites {
                have: self.n,
                need: self.m + 1,
            });
        }
        let qr = Householder::factor(&self.h, self.n, self.m)?;
        let mut z = self.z;
        qr.apply_ut(&mut z);
        let mut rhs = [T::zero(); MAX_STATES];
        for (r, v) in rhs.iter_mut().zip(z.iter()).take(self.m) {
            *r = *v;
        }
        Ok(qr.solve_t(&rhs))
    }
}

#[cfg(test)]
#[path = "solve_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "solve_cov_tests.rs"]
mod cov_tests;
