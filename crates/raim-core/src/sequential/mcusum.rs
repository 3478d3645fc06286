//! Sequential detection: Crosier's multivariate CUSUM (MCUSUM) on the
//! whitened parity vector (SPEC §7, seed 001 eqs. 8-12), carried from epoch
//! to epoch across changing geometry (SPEC §7.3), with identification from
//! the accumulated vector (SPEC §7.4).
//!
//! The recursion (SPEC §7.1; seed 001 eq. 9 prints C_t without the square
//! root, a misprint: the norm is used, as in Crosier 1988):
//!
//! ```text
//! C_t = || S_(t-1) + y_t ||
//! S_t = 0                              if C_t <= k
//!     = (S_(t-1) + y_t) (1 - k / C_t)  otherwise
//! D_t = || S_t ||,   alarm when D_t >= h
//! ```
//!
//! y_t is the parity vector p_t = U2^T z (whitened, so the seed's Sigma^-1
//! drops out). The parity basis U2 changes every epoch and its dimension
//! changes when satellites rise, set or are excluded, so the state is kept in
//! measurement space, v = U2 S_t, one entry per satellite ([`SatId`]). At the
//! next epoch v is mapped to the new satellite list (rows of satellites that
//! left are dropped, newcomers get 0) and S_(t-1) = U2_new^T v. This is an
//! orthogonal projection: it never increases ||S||, so the in-control false
//! alarm rate stays at or below the nominal one of the threshold table.
//!
//! Fixed capacity `N`, no heap, no panics.

use crate::config::{Carry, FiRule};
use crate::error::RaimError;
use crate::linalg::parity::Parity;
use crate::measurement::SatId;
use crate::real::{Real, Stat};
use crate::sequential::mcusum_table as table;
use crate::snapshot::lraim::{self, Candidate};

pub use crate::sequential::mcusum_table::{K_VALUES, LOG10_ARL0, MAX_DIM};

/// Scale of [`H_E4`]: the generated table is rounded to 1e-4.
const H_UNITS_PER_ONE: f64 = 1e4;

/// The device table's h in units of 1e-4, the rounding of the generated
/// table (`mcusum_table::H`): half the flash of the f64 table (5,040 B
/// instead of 10,080 B on the firmware), and read back exactly:
/// `n / 1e4` is the f64 nearest to the decimal `n * 1e-4`, which is what the
/// table's literal parses to (the test `integer_table_reads_back_bit_for_bit`).
/// Converted at compile time; `H` itself is not linked.
static H_E4: [[[u32; LOG10_ARL0.len()]; MAX_DIM]; K_VALUES.len()] = {
    let mut out = [[[0u32; LOG10_ARL0.len()]; MAX_DIM]; K_VALUES.len()];
    let mut k = 0;
    while k < K_VALUES.len() {
        let mut d = 0;
        while d < MAX_DIM {
            let mut j = 0;
            while j < LOG10_ARL0.len() {
                // Compile-time indexing: out of range is a build error.
                #[allow(clippy::indexing_slicing)]
                {
                    out[k][d][j] = (table::H[k][d][j] * H_UNITS_PER_ONE + 0.5) as u32;
                }
                j += 1;
            }
            d += 1;
        }
        k += 1;
    }
    out
};

/// Most satellites held excluded after MCUSUM alarms at one time.
pub const MAX_HELD: usize = 4;

/// After an MCUSUM alarm the identification is refused as ambiguous when the
/// runner-up explains at least this fraction of what the best candidate
/// explains: (v_2^2 / S_22) / (v_1^2 / S_11) = cos^2 of its angle to S_t over
/// the best's. With S_t along a_1 the ratio is the squared correlation
/// rho_12^2 of the two fault directions, so 0.8 refuses pairs whose parity
/// directions are within ~27 deg of each other (the G24/G11 pair of the 0759
/// data, docs/MCRAIM.md). A heuristic guard, not a calibrated test.
pub const AMBIGUITY_RATIO: f64 = 0.8;

/// Largest distance of a configured k from a table value (sigma units).
const K_MATCH_TOL: f64 = 1e-9;

/// One Crosier step in place on the parity-space state `s` (length d) with
/// the observation `y` (length d). Returns (C_t, D_t). A NaN observation
/// gives a NaN state and statistic, which alarms (`!(D < h)`).
pub fn crosier_step<T: Real>(s: &mut [T], y: &[T], k: T) -> (T, T) {
    let mut c2 = T::zero();
    for (si, yi) in s.iter_mut().zip(y.iter()) {
        *si += *yi;
        c2 += *si * *si;
    }
    let c = c2.sqrt();
    if c <= k {
        for si in s.iter_mut() {
            *si = T::zero();
        }
        (c, T::zero())
    } else {
        let shrink = T::one() - k / c;
        for si in s.iter_mut() {
            *si *= shrink;
        }
        (c, c - k)
    }
}

/// [`crosier_step`] with the observation weighted: S_(t-1) + w y_t in place
/// of S_(t-1) + y_t (w = 1 / sqrt(I) of [`variance_inflation`]). A NaN
/// weight or observation gives a NaN statistic, which alarms.
pub fn crosier_step_weighted<T: Real>(s: &mut [T], y: &[T], k: T, w: T) -> (T, T) {
    let mut c2 = T::zero();
    for (si, yi) in s.iter_mut().zip(y.iter()) {
        *si += w * *yi;
        c2 += *si * *si;
    }
    let c = c2.sqrt();
    if c <= k {
        for si in s.iter_mut() {
            *si = T::zero();
        }
        (c, T::zero())
    } else {
        let shrink = T::one() - k / c;
        for si in s.iter_mut() {
            *si *= shrink;
        }
        (c, c - k)
    }
}

/// Variance inflation of a sum of samples of a first-order Gauss-Markov
/// error (unit variance, correlation time `tau_s`) taken every `dt_s`:
/// I = (1 + rho) / (1 - rho) = coth(dt / (2 tau)), rho = exp(-dt / tau).
/// The variance of the sum of n samples is
/// n I - 2 rho (1 - rho^n) / (1 - rho)^2 <= n I, so samples weighted by
/// 1 / sqrt(I) have partial sums no more variable than white unit-variance
/// samples, the process the ARL0 table was computed for. I ~ 2 tau / dt
/// for dt << tau. `tau_s` <= 0 (white noise) gives 1; so does NaN.
pub fn variance_inflation(dt_s: f64, tau_s: f64) -> f64 {
    if !(tau_s > 0.0) {
        return 1.0;
    }
    1.0 / libm::tanh(dt_s / (2.0 * tau_s))
}

/// The inverse of [`variance_inflation`] in tau: the correlation time whose
/// inflation at the interval `dt_s` is `inflation` (> 1),
/// tau = dt / (2 artanh(1 / I)). An integrated autocorrelation time
/// 1 + 2 sum_L rho(L), measured in samples, is such an I. 0 for I <= 1
/// (white or anti-correlated); NaN in, NaN out.
pub fn correlation_time_for_inflation_s(dt_s: f64, inflation: f64) -> f64 {
    if inflation.is_nan() {
        return f64::NAN;
    }
    if inflation <= 1.0 {
        return 0.0;
    }
    dt_s / (2.0 * libm::atanh(1.0 / inflation))
}

/// The Euclidean norm, in `T`.
fn norm<'a, T: Real>(v: impl Iterator<Item = &'a T>) -> T {
    v.fold(T::zero(), |acc, x| acc + *x * *x).sqrt()
}

/// Check the MCUSUM settings against the device table: k must be one of
/// [`K_VALUES`] and log10(ARL0) inside [`LOG10_ARL0`]'s range.
pub fn check_settings(k: f64, arl0: f64) -> Result<(), RaimError> {
    k_index(k)?;
    let [lo, .., hi] = LOG10_ARL0;
    let l = libm::log10(arl0);
    if !(l >= lo && l <= hi) {
        return Err(RaimError::OutOfRange {
            field: "mcusum_arl0",
            value: arl0,
            min: libm::pow(10.0, lo),
            max: libm::pow(10.0, hi),
        });
    }
    Ok(())
}

fn k_index(k: f64) -> Result<usize, RaimError> {
    let [k_min, .., k_max] = K_VALUES;
    K_VALUES
        .iter()
        .position(|&kv| libm::fabs(kv - k) <= K_MATCH_TOL)
        .ok_or(RaimError::OutOfRange {
            field: "mcusum_k",
            value: k,
            min: k_min,
            max: k_max,
        })
}

/// The alarm threshold h for dimension `dim`, reference value `k` and
/// in-control ARL0 `arl0` (epochs), from the device table generated by
/// `raim arl --table` (SPEC §7.2). Between the table's ARL0 nodes (every
/// half decade) h is interpolated by the quadratic through the three nearest
/// nodes in log10(ARL0), where h is nearly linear.
pub fn threshold(dim: usize, k: f64, arl0: f64) -> Result<f64, RaimError> {
    check_settings(k, arl0)?;
    let ki = k_index(k)?;
    let row = H_E4
        .get(ki)
        .and_then(|rows| rows.get(dim.wrapping_sub(1)))
        .filter(|_| dim >= 1)
        .ok_or(RaimError::InvalidDof {
            dof: u32::try_from(dim).unwrap_or(u32::MAX),
            max: MAX_DIM as u32,
        })?;
    let l = libm::log10(arl0);
    let n = LOG10_ARL0.len();
    // Index of the middle node of the three nearest.
    let mut mid = 1;
    let mut best = f64::INFINITY;
    for (i, x) in LOG10_ARL0
        .iter()
        .enumerate()
        .take(n.saturating_sub(1))
        .skip(1)
    {
        let dist = libm::fabs(x - l);
        if dist < best {
            best = dist;
            mid = i;
        }
    }
    let (Some(&x0), Some(&x1), Some(&x2)) = (
        LOG10_ARL0.get(mid - 1),
        LOG10_ARL0.get(mid),
        LOG10_ARL0.get(mid + 1),
    ) else {
        return Err(RaimError::InvalidDof {
            dof: dim as u32,
            max: MAX_DIM as u32,
        });
    };
    let y = |i: usize| row.get(i).map(|&n| f64::from(n) / H_UNITS_PER_ONE);
    let (Some(y0), Some(y1), Some(y2)) = (y(mid - 1), y(mid), y(mid + 1)) else {
        return Err(RaimError::InvalidDof {
            dof: dim as u32,
            max: MAX_DIM as u32,
        });
    };
    let l0 = (l - x1) * (l - x2) / ((x0 - x1) * (x0 - x2));
    let l1 = (l - x0) * (l - x2) / ((x1 - x0) * (x1 - x2));
    let l2 = (l - x0) * (l - x1) / ((x2 - x0) * (x2 - x1));
    Ok(y0 * l0 + y1 * l1 + y2 * l2)
}

/// What one MCUSUM update did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Step {
    /// C_t = ||S_(t-1) + y_t||.
    pub c: f64,
    /// D_t = ||S_t||.
    pub statistic: f64,
    /// ||S_(t-1)|| after the transport into this epoch's parity space.
    pub prior_norm: f64,
    /// Parity dimension d = n - m of this epoch.
    pub dim: usize,
    /// False when the state was restarted at 0 this epoch (`Carry::Reset`
    /// on a change of the satellite set).
    pub carried: bool,
}

/// A satellite excluded after an MCUSUM alarm, and since when.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Held {
    /// The satellite held out.
    pub id: SatId,
    /// Epoch time of the exclusion, s.
    pub since_s: f64,
}

/// The MCUSUM state that lives across epochs: v = U2 S_t in measurement
/// space (whitened, sigma units), indexed by satellite, and the satellites
/// held excluded after MCUSUM alarms. The vector is in the precision `T`
/// of the statistics path.
#[derive(Debug, Clone)]
pub struct Mcusum<const N: usize, T: Real = Stat> {
    v: [T; N],
    ids: [SatId; N],
    n: usize,
    /// Dimension and threshold of the last update (0 / NaN before the first).
    last_dim: usize,
    last_h: f64,
    /// Time of the last epoch seen by [`Self::observation_weight`] and the
    /// last positive interval, s (NaN before them).
    last_time_s: f64,
    last_dt_s: f64,
    held: heapless::Vec<Held, MAX_HELD>,
    /// Time of the last epoch the sequential monitor took ([`Self::take_time`]),
    /// s; `None` before any and after [`Self::clear`].
    last_epoch_s: Option<f64>,
}

impl<const N: usize, T: Real> Default for Mcusum<N, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, T: Real> Mcusum<N, T> {
    /// A detector with a zero state and nothing held.
    pub const fn new() -> Self {
        Mcusum {
            v: [T::ZERO; N],
            ids: [SatId::DEFAULT; N],
            n: 0,
            last_dim: 0,
            last_h: f64::NAN,
            last_time_s: f64::NAN,
            last_dt_s: f64::NAN,
            held: heapless::Vec::new(),
            last_epoch_s: None,
        }
    }
}

impl<const N: usize, T: Real> Mcusum<N, T> {
    /// Restart the CUSUM at S = 0 (the holds are kept).
    pub fn reset(&mut self) {
        self.n = 0;
        self.v = [T::zero(); N];
        self.last_dim = 0;
        self.last_h = f64::NAN;
    }

    /// Forget everything, holds included (and the last epoch's time: with
    /// no state left, nothing is carried to an earlier time).
    pub fn clear(&mut self) {
        self.reset();
        self.held.clear();
        self.last_epoch_s = None;
    }

    /// Whether an epoch at `time_s` may be taken: its time must follow the
    /// last epoch's strictly (as the PF's, the ESQ's and the PCA's), else
    /// `TimeNotIncreasing`. A state accumulated at t carried to an earlier
    /// time (or counted twice at the same time) would weigh the same
    /// errors again and release holds by a negative age (issue 35). The
    /// caller checks before it changes any state, so a refused epoch
    /// leaves the monitor exactly as it was.
    pub fn check_time(&self, time_s: f64) -> Result<(), RaimError> {
        match self.last_epoch_s {
            Some(previous_s) if !(time_s > previous_s) => Err(RaimError::TimeNotIncreasing {
                previous_s,
                now_s: time_s,
            }),
            _ => Ok(()),
        }
    }

    /// Record `time_s` as the last epoch's ([`Self::check_time`] passed).
    pub fn take_time(&mut self, time_s: f64) {
        self.last_epoch_s = Some(time_s);
    }

    /// The accumulated vector v = U2 S_t in measurement space, with the
    /// satellite of each entry.
    // n <= N: `store` sets it to at most N.
    #[allow(clippy::indexing_slicing)]
    pub fn state(&self) -> (&[SatId], &[T]) {
        (&self.ids[..self.n.min(N)], &self.v[..self.n.min(N)])
    }

    /// D = ||S|| = ||v|| (U2 has orthonormal columns).
    pub fn norm(&self) -> f64 {
        norm(self.v.iter().take(self.n)).to_f64()
    }

    fn same_set(&self, ids: &[SatId]) -> bool {
        ids.len() == self.n
            && ids
                .iter()
                .all(|id| self.ids.iter().take(self.n).any(|o| o == id))
    }

    /// The previous state in this epoch's parity coordinates: v mapped onto
    /// `ids` (0 for satellites it does not hold), then U2^T. Written into
    /// `out` (first d entries). Returns false if the state was reset.
    fn prior(&self, ids: &[SatId], parity: &Parity<N, T>, carry: Carry, out: &mut [T; N]) -> bool {
        *out = [T::zero(); N];
        if self.n == 0 {
            return true;
        }
        if carry == Carry::Reset && !self.same_set(ids) {
            return false;
        }
        let mut x = [T::zero(); N];
        for (xi, id) in x.iter_mut().zip(ids.iter()) {
            if let Some((_, &v)) = self
                .ids
                .iter()
                .zip(self.v.iter())
                .take(self.n)
                .find(|(o, _)| *o == id)
            {
                *xi = v;
            }
        }
        parity.project(&x, out);
        true
    }

    /// The weight w = 1 / sqrt(I(dt, tau)) of the observation of the epoch at
    /// `time_s` ([`variance_inflation`], SPEC §7.1 on whitened samples),
    /// with dt the interval since the previous call. 1 when `tau_s` is 0
    /// (white noise). When this epoch's interval is unknown (the first
    /// epoch, or time not advancing) the last positive interval is used;
    /// before any, the weight is 0: the epoch only starts the clock. The
    /// clock survives [`Self::reset`] and [`Self::clear`].
    pub fn observation_weight(&mut self, time_s: f64, tau_s: f64) -> f64 {
        let dt = time_s - self.last_time_s;
        if dt > 0.0 && dt.is_finite() {
            self.last_dt_s = dt;
        }
        self.last_time_s = time_s;
        if !(tau_s > 0.0) {
            return 1.0;
        }
        if !(self.last_dt_s > 0.0) {
            return 0.0;
        }
        1.0 / libm::sqrt(variance_inflation(self.last_dt_s, tau_s))
    }

    /// One epoch: transport (or reset), then the Crosier step on this
    /// epoch's parity vector. `ids` names the rows of `parity`; `h` is this
    /// epoch's threshold. When the dimension dropped since the last epoch
    /// the transported state is also scaled by h / h_last: a d-dimensional
    /// CUSUM sits higher in control than a (d-1)-dimensional one, and the
    /// projection alone removes only ~1/d of it, so without the scaling a
    /// setting satellite raises the false-alarm rate above the table's
    /// (docs/MCRAIM.md measures it). When the dimension grows the state is
    /// left as is (conservative).
    pub fn update(
        &mut self,
        ids: &[SatId],
        parity: &Parity<N, T>,
        k: f64,
        carry: Carry,
        h: f64,
    ) -> Step {
        self.update_weighted(ids, parity, k, carry, h, 1.0)
    }

    /// [`Self::update`] with the observation weighted by `weight`
    /// ([`Self::observation_weight`]); a weight of exactly 1 is the plain
    /// recursion, bit for bit.
    pub fn update_weighted(
        &mut self,
        ids: &[SatId],
        parity: &Parity<N, T>,
        k: f64,
        carry: Carry,
        h: f64,
        weight: f64,
    ) -> Step {
        let d = parity.dof();
        let mut s = [T::zero(); N];
        let carried = self.prior(ids, parity, carry, &mut s);
        // d = n - m < n <= N (a computed parity space).
        #[allow(clippy::indexing_slicing)]
        let sd = &mut s[..d.min(N)];
        if d < self.last_dim && self.last_h > 0.0 && h < self.last_h {
            let scale = T::of(h / self.last_h);
            for x in sd.iter_mut() {
                *x *= scale;
            }
        }
        let prior_norm = norm(sd.iter()).to_f64();
        let (c, statistic) = if weight == 1.0 {
            crosier_step(sd, parity.p(), T::of(k))
        } else {
            crosier_step_weighted(sd, parity.p(), T::of(k), T::of(weight))
        };
        self.store(ids, parity, sd);
        self.last_dim = d;
        self.last_h = h;
        Step {
            c: c.to_f64(),
            statistic: statistic.to_f64(),
            prior_norm,
            dim: d,
            carried,
        }
    }

    fn store(&mut self, ids: &[SatId], parity: &Parity<N, T>, s: &[T]) {
        self.v = parity.lift(s);
        let n = ids.len().min(N).min(parity.rows());
        for (dst, src) in self.ids.iter_mut().zip(ids.iter()).take(n) {
            *dst = *src;
        }
        self.n = n;
    }

    /// Carry the state into another parity space (e.g. the subset left after
    /// an exclusion) without a new observation. Dropping an excluded
    /// satellite's row and projecting removes exactly the component of v
    /// along that satellite's fault signature S e_j (the subset's parity space
    /// is the full one minus that direction), so the evidence for the
    /// identified fault is cleared and the rest is kept. Returns the new D.
    pub fn carry_to(&mut self, ids: &[SatId], parity: &Parity<N, T>, carry: Carry) -> f64 {
        let d = parity.dof();
        let mut s = [T::zero(); N];
        self.prior(ids, parity, carry, &mut s);
        // d = n - m < n <= N (a computed parity space).
        #[allow(clippy::indexing_slicing)]
        let sd = &s[..d.min(N)];
        self.store(ids, parity, sd);
        self.last_dim = d;
        self.norm()
    }

    /// Identify the faulty satellite from the accumulated vector (SPEC §7.4):
    /// the MLE rule of SPEC §4.1 applied to v, argmax_i v_i^2 / S_ii. Since
    /// v = U2 S_t lies in the parity space, v_i / sqrt(S_ii) = a_i^T S_t with
    /// a_i = U2^T e_i / sqrt(S_ii), so this picks the satellite whose fault
    /// direction is closest in angle to S_t. The L-RAIM rules are not used
    /// here: their leverage term is calibrated for a unit-variance residual,
    /// and v's scale is the CUSUM's, not N(0, 1). `parity` must be the one of
    /// the last [`Self::update`]. Returns the best and the runner-up.
    pub fn identify(
        &self,
        parity: &Parity<N, T>,
        min_s_ii: f64,
    ) -> (Option<Candidate<T>>, Option<Candidate<T>>) {
        // n <= N: `store` sets it to at most N.
        #[allow(clippy::indexing_slicing)]
        let v = &self.v[..self.n.min(N)];
        lraim::rank_rows(FiRule::Mle, v, parity.s_ii(), T::of(min_s_ii))
    }

    /// Satellites held excluded.
    pub fn held(&self) -> &[Held] {
        &self.held
    }

    /// True when `id` is held out after an MCUSUM alarm.
    pub fn is_held(&self, id: SatId) -> bool {
        self.held.iter().any(|h| h.id == id)
    }

    /// Hold `id` excluded from `time_s`. When the list is full the oldest
    /// hold is released.
    pub fn hold(&mut self, id: SatId, time_s: f64) {
        if self.is_held(id) {
            return;
        }
        if self.held.is_full() {
            // The oldest hold (the first) released, the others kept in order.
            let mut first = true;
            self.held.retain(|_| !core::mem::take(&mut first));
        }
        let pushed = self.held.push(Held {
            id,
            since_s: time_s,
        });
        // Cannot fill: a full list released its oldest hold above.
        debug_assert!(pushed.is_ok());
    }

    /// Release holds whose satellite is not in the epoch (`present` says
    /// which are), that are older than `hold_s`, or that lie in the future
    /// (time went backwards: a new run).
    pub fn release(&mut self, time_s: f64, hold_s: f64, present: impl Fn(SatId) -> bool) {
        self.held
            .retain(|h| present(h.id) && h.since_s <= time_s && time_s - h.since_s <= hold_s);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::config::Config;
    use crate::measurement::{Epoch, LinearObservation, System};
    use crate::solve::{solve, Solution};
    use crate::testutil::{at_stat, linear_epoch, Rng, SKY8};
    use nalgebra::{DMatrix, DVector};
    use std::vec::Vec;

    const N: usize = 16;
    /// Rounding tolerance of the Crosier step on O(10) f64 values (the
    /// hand-computed tests call it at f64 whatever the test build's precision).
    const ROUND_TOL: f64 = 1e-10;
    /// The transported prior norm against the dense f64 projector, relative
    /// to 1 + norm: 1e-9 in f64; in f32 the state is rotated and projected
    /// through the f32 QR of each epoch (eps x cond(H) per carry over 60
    /// epochs), 1e-4.
    /// The transported state against the plain recursion over 50 epochs
    /// (values up to ~20): 1e-10 in f64; in f32 the transport's rotation
    /// and the recursion round differently at every step, and the
    /// differences accumulate in the state (1.05e-5 measured at t = 30 on
    /// D = 13.5): 1e-4.
    const RECURSION_TOL: f64 = at_stat(1e-10, 1e-4);
    const PRIOR_REL_TOL: f64 = at_stat(1e-9, 1e-4);
    /// |H^T v| of the stored state, relative to 1 + |v|_max: 1e-9 in f64,
    /// 1e-5 in f32 (the state lies in the f32 parity space, orthogonal to
    /// H to a few eps x |H| |v|).
    const ORTHO_REL_TOL: f64 = at_stat(1e-9, 1e-5);

    fn solution(sats: &[LinearObservation]) -> Solution<N> {
        let mut mask = [false; N];
        mask[..sats.len()].iter_mut().for_each(|m| *m = true);
        solve::<N>(&Config::default(), &Epoch::linear(0.0, sats), &mask).unwrap()
    }

    fn ids(sol: &Solution<N>) -> Vec<SatId> {
        sol.ids[..sol.rows()].to_vec()
    }

    /// Dense whitened H of a linear epoch (unit sigma, one GPS clock plus
    /// one per other system present), for the independent projector.
    fn dense_h(sats: &[LinearObservation]) -> DMatrix<f64> {
        let systems: Vec<System> = System::ALL
            .iter()
            .copied()
            .filter(|s| sats.iter().any(|o| o.id.system == *s))
            .collect();
        let m = 3 + systems.len();
        let mut h = DMatrix::zeros(sats.len(), m);
        for (i, o) in sats.iter().enumerate() {
            let w = 1.0 / o.sigma_m.unwrap();
            for k in 0..3 {
                h[(i, k)] = -o.los_enu[k] * w;
            }
            h[(
                i,
                3 + systems.iter().position(|s| *s == o.id.system).unwrap(),
            )] = w;
        }
        h
    }

    /// The Crosier step against hand-computed values: S = 0, y = (3, 4),
    /// k = 1: C = 5, S = (3, 4) 4/5 = (2.4, 3.2), D = 4. Then y = (-2.4, -2.7):
    /// C = 0.5 <= k so S = 0.
    ///
    /// Verifies: SPEC-7.1
    #[test]
    fn crosier_step_by_hand() {
        let mut s = [0.0f64, 0.0];
        let (c, d) = crosier_step(&mut s, &[3.0, 4.0], 1.0);
        assert!((c - 5.0).abs() < ROUND_TOL && (d - 4.0).abs() < ROUND_TOL);
        assert!((s[0] - 2.4).abs() < ROUND_TOL && (s[1] - 3.2).abs() < ROUND_TOL);
        let (c, d) = crosier_step(&mut s, &[-2.4, -2.7], 1.0);
        assert!((c - 0.5).abs() < ROUND_TOL && d == 0.0 && s == [0.0, 0.0]);
        // NaN in, NaN out: the alarm comparison !(D < h) then alarms.
        let (_, d) = crosier_step(&mut s, &[f64::NAN, 0.0], 1.0);
        assert!(d.is_nan());
    }

    /// The squared form printed as seed 001 eq. 9 (C_t without the root) is
    /// not Crosier's: on the same input it shrinks by k / C^2 instead of
    /// k / C, so the two disagree (SPEC §7.1 explains why the norm is right).
    ///
    /// Verifies: SPEC-7.1
    #[test]
    fn misprinted_squared_form_differs() {
        let mut s = [0.0f64, 0.0];
        let (_, d) = crosier_step(&mut s, &[3.0, 4.0], 1.0);
        let c2 = 25.0f64;
        let d_squared_form = 5.0 * (1.0 - 1.0 / c2);
        assert!((d - 4.0).abs() < ROUND_TOL && (d_squared_form - 4.8).abs() < ROUND_TOL);
    }

    /// With an unchanged geometry and satellite list, the transport is the
    /// identity: the state after t steps equals the plain recursion on the
    /// same parity vectors.
    #[test]
    fn same_geometry_transport_is_identity() {
        let mut rng = Rng::new(11);
        let mut mc = Mcusum::<N>::new();
        let mut s_ref = [0.0; 4];
        for t in 0..50 {
            let sats = linear_epoch(&SKY8, 1.0, &mut rng, &[(3, 0.8)]);
            let sol = solution(&sats);
            let step = mc.update(&ids(&sol), &sol.parity, 0.5, Carry::Transport, f64::NAN);
            let (_, d_ref) = crosier_step(&mut s_ref, sol.parity.p(), Stat::of(0.5));
            let d_ref = d_ref.to_f64();
            assert!(
                (step.statistic - d_ref).abs() < RECURSION_TOL,
                "t {t}: {} vs {d_ref}",
                step.statistic
            );
            assert!((mc.norm() - d_ref).abs() < RECURSION_TOL);
        }
    }

    /// Moving geometry, satellites setting and rising, reordered input and a
    /// constellation change: S_(t-1) = U2_new^T v_mapped is checked through
    /// its norm against an independent dense projector,
    /// ||U2^T x||^2 = x^T (I - H (H^T H)^-1 H^T) x, for both carry modes.
    ///
    /// Verifies: SPEC-7.3
    #[test]
    fn transport_matches_dense_projector_across_set_changes() {
        let mut rng = Rng::new(5);
        let sky10: Vec<(f64, f64)> = SKY8
            .iter()
            .copied()
            .chain([(120.0, 70.0), (280.0, 65.0)])
            .collect();
        for carry in [Carry::Transport, Carry::Reset] {
            let mut mc = Mcusum::<N>::new();
            let mut prev_ids: Vec<SatId> = Vec::new();
            for t in 0..60usize {
                // Azimuths rotate 1 deg per epoch; satellite 9 sets at t=20,
                // comes back at t=40; from t=30 one Galileo satellite joins
                // (adds a clock); the input order is reversed on odd epochs.
                let mut sats: Vec<LinearObservation> = sky10
                    .iter()
                    .map(|&(az, el)| (az + t as f64, el))
                    .enumerate()
                    .filter(|(i, _)| !(*i == 8 && (20..40).contains(&t)))
                    .map(|(i, (az, el))| {
                        let mut o = LinearObservation::from_az_el(
                            SatId::new(System::Gps, i as u8 + 1),
                            az.to_radians(),
                            el.to_radians(),
                            rng.normal() + if i == 2 { 1.5 } else { 0.0 },
                        );
                        o.sigma_m = Some(1.0);
                        o
                    })
                    .collect();
                if t >= 30 {
                    let mut o = LinearObservation::from_az_el(
                        SatId::new(System::Galileo, 7),
                        1.0,
                        0.6,
                        rng.normal(),
                    );
                    o.sigma_m = Some(1.0);
                    sats.push(o);
                }
                if t % 2 == 1 {
                    sats.reverse();
                }
                let sol = solution(&sats);
                let now_ids = ids(&sol);
                // Expected prior norm from the dense projector on v mapped.
                let (old_ids, old_v) = mc.state();
                let x = DVector::from_iterator(
                    now_ids.len(),
                    now_ids.iter().map(|id| {
                        old_ids
                            .iter()
                            .position(|o| o == id)
                            .map_or(0.0, |p| old_v[p].to_f64())
                    }),
                );
                let h = dense_h(&sats);
                let proj = DMatrix::identity(h.nrows(), h.nrows())
                    - &h * (h.transpose() * &h).try_inverse().unwrap() * h.transpose();
                let same = {
                    let mut a = prev_ids.clone();
                    let mut b = now_ids.clone();
                    a.sort();
                    b.sort();
                    a == b
                };
                let expected = if carry == Carry::Reset && !same && !prev_ids.is_empty() {
                    0.0
                } else {
                    (x.transpose() * &proj * &x)[(0, 0)].max(0.0).sqrt()
                };
                let step = mc.update(&now_ids, &sol.parity, 0.5, carry, f64::NAN);
                assert!(
                    (step.prior_norm - expected).abs() < PRIOR_REL_TOL * (1.0 + expected),
                    "{carry:?} t {t}: {} vs {expected}",
                    step.prior_norm
                );
                assert_eq!(step.dim, sats.len() - if t >= 30 { 5 } else { 4 });
                assert_eq!(
                    step.carried,
                    !(carry == Carry::Reset && !same && !prev_ids.is_empty())
                );
                // The stored v lies in the parity space: H^T v = 0.
                let (_, v) = mc.state();
                let v = DVector::from_iterator(v.len(), v.iter().map(|x| x.to_f64()));
                assert!((h.transpose() * &v).amax() < ORTHO_REL_TOL * (1.0 + v.amax()));
                prev_ids = now_ids;
            }
        }
    }

    /// A persistent 1.5 sigma bias on one satellite, too small for the
    /// snapshot test, accumulates until the MCUSUM alarms; identification
    /// from v names the satellite; removing its row and carrying the state
    /// into the subset's parity space clears the accumulated evidence.
    ///
    /// Verifies: SPEC-7.4
    #[test]
    fn accumulated_vector_identifies_and_exclusion_clears_it() {
        let sky10: Vec<(f64, f64)> = SKY8
            .iter()
            .copied()
            .chain([(120.0, 70.0), (280.0, 65.0)])
            .collect();
        let h = threshold(6, 1.0, 1e4).unwrap();
        let mut correct = 0;
        const TRIALS: u64 = 40;
        for seed in 0..TRIALS {
            let mut rng = Rng::new(1000 + seed);
            let mut mc = Mcusum::<N>::new();
            for t in 0..400 {
                let sats = linear_epoch(&sky10, 1.0, &mut rng, &[(4, 4.0)]);
                let sol = solution(&sats);
                let step = mc.update(&ids(&sol), &sol.parity, 1.0, Carry::Transport, h);
                if step.statistic >= h {
                    let (best, _) = mc.identify(&sol.parity, 1e-4);
                    let row = best.unwrap().row;
                    if sol.ids[row] == SatId::new(System::Gps, 5) {
                        correct += 1;
                        // Exclude it: the subset's parity space.
                        let rest: Vec<LinearObservation> = sats
                            .iter()
                            .copied()
                            .filter(|o| o.id != sol.ids[row])
                            .collect();
                        let sub = solution(&rest);
                        let before = mc.norm();
                        let after = mc.carry_to(&ids(&sub), &sub.parity, Carry::Transport);
                        assert!(
                            after < 0.5 * before,
                            "seed {seed} t {t}: {before} -> {after}"
                        );
                    }
                    break;
                }
            }
        }
        // A 4 sigma bias (about 3 sigma in parity space) on a 10-satellite
        // geometry is identified nearly always; allow a few misses.
        const MIN_CORRECT: u64 = TRIALS - 4;
        assert!(correct >= MIN_CORRECT, "{correct} of {TRIALS}");
    }

    #[test]
    fn holds_are_released_when_absent_or_expired() {
        let mut mc = Mcusum::<N>::new();
        let a = SatId::new(System::Gps, 1);
        let b = SatId::new(System::Gps, 2);
        mc.hold(a, 0.0);
        mc.hold(b, 10.0);
        mc.hold(b, 11.0);
        assert_eq!(mc.held().len(), 2);
        mc.release(100.0, 600.0, |id| id == a);
        assert!(mc.is_held(a) && !mc.is_held(b));
        mc.release(700.0, 600.0, |_| true);
        assert!(!mc.is_held(a));
        for prn in 1..=6 {
            mc.hold(SatId::new(System::Gps, prn), prn as f64);
        }
        assert_eq!(mc.held().len(), MAX_HELD);
        assert!(!mc.is_held(SatId::new(System::Gps, 1)) && mc.is_held(SatId::new(System::Gps, 6)));
    }

    /// Settings outside the table are typed errors carrying the value.
    ///
    /// Verifies: WIRE-InvalidDof
    #[test]
    fn threshold_rejects_values_outside_the_table() {
        assert!(matches!(
            threshold(2, 0.3, 1e4),
            Err(RaimError::OutOfRange {
                field: "mcusum_k",
                ..
            })
        ));
        assert!(matches!(
            threshold(2, 1.0, 10.0),
            Err(RaimError::OutOfRange {
                field: "mcusum_arl0",
                ..
            })
        ));
        assert!(matches!(
            threshold(2, 1.0, f64::NAN),
            Err(RaimError::OutOfRange {
                field: "mcusum_arl0",
                ..
            })
        ));
        assert!(matches!(
            threshold(0, 1.0, 1e4),
            Err(RaimError::InvalidDof { dof: 0, .. })
        ));
        assert!(matches!(
            threshold(MAX_DIM + 1, 1.0, 1e4),
            Err(RaimError::InvalidDof { .. })
        ));
    }

    /// An ARL0 above the table's last node (1e9 epochs) is refused with
    /// the value and the table's range, 1e2 to 1e9.
    #[test]
    fn arl0_above_the_table_is_refused_with_its_range() {
        assert_eq!(
            threshold(2, 1.0, 1e10),
            Err(RaimError::OutOfRange {
                field: "mcusum_arl0",
                value: 1e10,
                min: 1e2,
                max: 1e9
            })
        );
    }

    /// Seed 001 Table 2: dim 2, k = 1, ARL0 = 1e4 gives h = 5.21 (exact
    /// 5.206, SPEC §7.1) from the device table.
    #[test]
    fn integer_table_reads_back_bit_for_bit() {
        for (k, rows) in table::H.iter().enumerate() {
            for (d, row) in rows.iter().enumerate() {
                for (j, h) in row.iter().enumerate() {
                    let back = f64::from(H_E4[k][d][j]) / H_UNITS_PER_ONE;
                    assert_eq!(back.to_bits(), h.to_bits(), "k {k} d {} j {j}: {h}", d + 1);
                }
            }
        }
    }

    /// Verifies: SPEC-7.2
    #[test]
    fn table_gives_seed_001_threshold() {
        let h = threshold(2, 1.0, 1e4).unwrap();
        // The table holds h to 1e-4; 1e4 is a node, so no interpolation.
        const H_TABLE_TOL: f64 = 1e-3;
        assert!((h - 5.206).abs() < H_TABLE_TOL, "{h}");
        assert!(((h * 100.0).round() - 521.0).abs() < 0.5);
    }

    /// I(dt = 30 s, tau = 1560 s) against the hand computation
    /// rho = exp(-30 / 1560) = 0.9809529623602027,
    /// (1 + rho) / (1 - rho) = 104.00320510844975 (Python, f64), and
    /// I(1 s, 10 s) = 20.016663889550088; white noise (tau 0, NaN) gives 1;
    /// the inverse returns tau; I -> 2 tau / dt for dt << tau.
    #[test]
    fn variance_inflation_by_hand() {
        /// Relative difference between coth(dt / 2 tau) and the hand's
        /// (1 + rho) / (1 - rho): a few f64 roundings of a quotient of 1e2.
        const INFLATION_REL_TOL: f64 = 1e-12;
        /// Round trip of tau through I, s (artanh of 1/I near 0.01).
        const TAU_TOL_S: f64 = 1e-9;
        for (dt, tau, hand) in [
            (30.0, 1560.0, 104.00320510844975),
            (1.0, 10.0, 20.016663889550088),
        ] {
            let i = variance_inflation(dt, tau);
            assert!((i / hand - 1.0).abs() < INFLATION_REL_TOL, "{i} {hand}");
            let back = correlation_time_for_inflation_s(dt, i);
            assert!((back - tau).abs() < TAU_TOL_S, "{back} {tau}");
        }
        assert_eq!(variance_inflation(30.0, 0.0), 1.0);
        assert_eq!(variance_inflation(30.0, f64::NAN), 1.0);
        assert_eq!(correlation_time_for_inflation_s(30.0, 1.0), 0.0);
        assert!(correlation_time_for_inflation_s(30.0, f64::NAN).is_nan());
        // dt / tau = 1e-3: I = 2 tau / dt + dt / (6 tau) + ...
        let i = variance_inflation(1.0, 1000.0);
        assert!((i - 2000.0 - 1.0 / 6000.0).abs() < 1e-6, "{i}");
    }

    /// The overbound the weight rests on: for a unit-variance AR(1) with
    /// correlation rho, Var(sum of n samples) = sum_ij rho^|i-j| (computed
    /// here by the double sum) equals n I - 2 rho (1 - rho^n) / (1 - rho)^2
    /// and never exceeds n I, for n = 1..300 and rho from tau / dt = 0.5..300.
    #[test]
    fn weighted_partial_sums_are_no_more_variable_than_white() {
        /// Relative rounding of a double sum of up to 9e4 terms.
        const SUM_REL_TOL: f64 = 1e-9;
        for tau_over_dt in [0.5, 3.0, 52.0, 300.0] {
            let rho = libm::exp(-1.0 / tau_over_dt);
            let i = variance_inflation(1.0, tau_over_dt);
            let mut var = 0.0;
            for n in 1..=300usize {
                // Adding sample n adds 1 + 2 sum_{L=1}^{n-1} rho^L.
                let mut row = 1.0;
                let mut r = 1.0;
                for _ in 1..n {
                    r *= rho;
                    row += 2.0 * r;
                }
                var += row;
                let nf = n as f64;
                let closed =
                    nf * i - 2.0 * rho * (1.0 - libm::pow(rho, nf)) / ((1.0 - rho) * (1.0 - rho));
                assert!(
                    (var / closed - 1.0).abs() < SUM_REL_TOL,
                    "{n} {var} {closed}"
                );
                assert!(var <= nf * i * (1.0 + SUM_REL_TOL), "{n} {var} {}", nf * i);
            }
        }
    }

    /// The clock of the weight: 0 at the first epoch (no interval yet),
    /// then 1 / sqrt(I) of the measured interval; a repeated time keeps the
    /// last interval; tau = 0 is exactly 1 at every epoch.
    #[test]
    fn observation_weight_follows_the_epoch_interval() {
        const W_TOL: f64 = 1e-12;
        let mut m = Mcusum::<4>::new();
        assert_eq!(m.observation_weight(100.0, 1560.0), 0.0);
        let w30 = 1.0 / libm::sqrt(104.00320510844975);
        assert!((m.observation_weight(130.0, 1560.0) - w30).abs() < W_TOL);
        assert!((m.observation_weight(130.0, 1560.0) - w30).abs() < W_TOL);
        m.reset();
        let w60 = 1.0 / libm::sqrt(variance_inflation(60.0, 1560.0));
        assert!((m.observation_weight(190.0, 1560.0) - w60).abs() < W_TOL);
        let mut white = Mcusum::<4>::new();
        for t in [0.0, 0.0, 1.0, 31.0, f64::NAN] {
            assert_eq!(white.observation_weight(t, 0.0), 1.0);
        }
    }

    /// In-control alarms of a d = 4 MCUSUM (k = 1, ARL0 = 500, restarted
    /// after each alarm) over 2e5 epochs of AR(1) errors with tau / dt = 10
    /// (seed 5): unweighted, the correlated errors alarm far above the
    /// nominal 400; weighted by 1 / sqrt(I) the count is at most nominal
    /// + 4 standard errors (sqrt(400) = 20).
    #[test]
    fn weight_restores_the_false_alarm_rate_on_gauss_markov_errors() {
        const D: usize = 4;
        const EPOCHS: usize = 200_000;
        const ARL0: f64 = 500.0;
        let h = threshold(D, 1.0, ARL0).unwrap();
        let (dt, tau) = (1.0, 10.0);
        let rho = libm::exp(-dt / tau);
        let w = 1.0 / libm::sqrt(variance_inflation(dt, tau));
        let mut rng = Rng::new(5);
        let mut x = [0.0f64; D];
        for xi in x.iter_mut() {
            *xi = rng.normal();
        }
        let (mut s_plain, mut s_weighted) = ([0.0f64; D], [0.0f64; D]);
        let (mut plain, mut weighted) = (0usize, 0usize);
        for _ in 0..EPOCHS {
            for xi in x.iter_mut() {
                *xi = rho * *xi + libm::sqrt(1.0 - rho * rho) * rng.normal();
            }
            if crosier_step(&mut s_plain, &x, 1.0).1 >= h {
                plain += 1;
                s_plain = [0.0; D];
            }
            if crosier_step_weighted(&mut s_weighted, &x, 1.0, w).1 >= h {
                weighted += 1;
                s_weighted = [0.0; D];
            }
        }
        let nominal = EPOCHS as f64 / ARL0;
        std::println!(
            "AR(1) tau/dt 10: alarms unweighted {plain}, weighted {weighted}, nominal {nominal}"
        );
        assert!(plain as f64 > 10.0 * nominal, "{plain}");
        assert!(
            (weighted as f64) <= nominal + 4.0 * libm::sqrt(nominal),
            "{weighted}"
        );
    }

    /// A weight of exactly 1 is the plain recursion, bit for bit.
    #[test]
    fn unit_weight_is_the_plain_step() {
        let mut rng = Rng::new(9);
        let (mut a, mut b) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..1000 {
            let y = [rng.normal(), rng.normal(), rng.normal()];
            let ra = crosier_step(&mut a, &y, 0.5);
            let rb = crosier_step_weighted(&mut b, &y, 0.5, 1.0);
            assert_eq!(ra, rb);
            assert_eq!(a, b);
        }
    }
}

#[cfg(test)]
#[path = "mcusum_cov_tests.rs"]
mod cov_tests;
