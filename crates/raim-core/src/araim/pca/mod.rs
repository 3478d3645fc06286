//! Constellation faults by feature extraction: seed 003's second
//! embodiment (SPEC §9.3, steps S201-S205).
//!
//! Over a sliding window of the `W` epochs *before* the current one:
//!
//! 1. S201: the covariance Sigma of the N pseudorange-residual series (per
//!    series mean over the window; the seed's m_x is "the mean of all the
//!    measurement values", read as the mean of each series, which is what
//!    makes Sigma a covariance);
//! 2. S202: its SVD (nalgebra, no_std). Sigma is symmetric positive
//!    semi-definite, so U = V and the singular values are its eigenvalues;
//! 3. S203: k = the smallest count of leading components whose *singular
//!    values* cover at least `variance_share` (0.99) of their sum. The seed
//!    writes the ratio over "the pseudo-range measurement values"; SPEC §9.3
//!    reads it over the singular values, as here;
//! 4. S204: the features of the current epoch x' = z V_k, z = x - mean, and
//!    its reconstruction z_hat = V_k x'^T (the k "new" measurements); the
//!    N - k directions left over are the "redundant observed quantities";
//! 5. S205: solution separation on the transformed set: the position from
//!    the reconstructed set minus the all-in-view position,
//!    dx_q = s_q . (z_hat - z) (s_q: row q of the all-in-view WLS gain S0,
//!    per axis E, N, U), against T_q = K sigma_q, where
//!    sigma_q^2 = s_q^T (I - P) Sigma (I - P) s_q = sum_{j > k} lambda_j (v_j . s_q)^2
//!    is its spread over the window and K = Q^-1(p_fa / 6) (two-sided, three
//!    axes). The seed's "x' - x^(0)" and threshold.
//!
//! The current epoch is tested against the window, then enters it. Fixed
//! size, no heap: the ring holds `W` residual vectors over `N` satellite
//! slots.
//!
//! **Satellites entering and leaving.** A satellite takes a free slot the
//! first epoch it is seen; a slot is freed the first epoch its satellite is
//! absent (its history is dropped: a returning satellite starts again). Only
//! the satellites with a complete history (present in all `W` window epochs
//! and now) enter Sigma and the test; the others still enter the all-in-view
//! gain S0 (they are in the position solution), but their component of
//! z_hat - z is zero. So a rising satellite joins the PCA test `W` epochs
//! after it is first seen, and a setting satellite leaves it at once.

mod svd;
#[cfg(test)]
mod tests;

pub use svd::{principal, Principal};

use crate::measurement::{SatId, MAX_STATES, MAX_SYSTEMS};
use crate::real::Real;
use crate::stats::dist::normal_q_inv;
use nalgebra::{Const, DefaultAllocator, DimDiff, DimMin, DimSub, SMatrix, U1};

use super::AraimSat;

/// Default share of the singular values kept (S203).
pub const DEFAULT_VARIANCE_SHARE: f64 = 0.99;

/// Configuration of the PCA monitor.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PcaConfig {
    /// Share of the sum of singular values the k components cover, (0, 1].
    pub variance_share: f64,
    /// False-alert probability per epoch of the separation test, (0, 1).
    pub p_fa: f64,
}

impl Default for PcaConfig {
    fn default() -> Self {
        Self {
            variance_share: DEFAULT_VARIANCE_SHARE,
            // The ADD's vertical budget, LPV-200.
            p_fa: 3.9e-6,
        }
    }
}

/// Why an epoch could not be processed.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PcaError {
    /// A configuration field out of range (name, value).
    BadConfig {
        /// Name of the field.
        field: &'static str,
        /// The value received.
        value: f64,
    },
    /// A non-finite input (field name, satellite index, value).
    NotFinite {
        /// Name of the field.
        field: &'static str,
        /// Index of the satellite.
        index: usize,
        /// The value received.
        value: f64,
    },
    /// More satellites than the slots `N`.
    CapacityExceeded {
        /// Satellites in the epoch.
        have: usize,
        /// The slots `N`.
        capacity: usize,
    },
    /// The same satellite appears twice in one epoch.
    DuplicateSatellite {
        /// Index of its first appearance.
        first: usize,
        /// Index of its second appearance.
        second: usize,
    },
    /// Fewer satellites than the unknowns (3 + one clock per constellation).
    TooFewSatellites {
        /// Satellites in the epoch.
        have: usize,
        /// Unknowns (3 + one clock per constellation).
        need: usize,
    },
    /// The all-in-view normal matrix is singular.
    RankDeficient,
    /// The SVD did not converge.
    SvdFailed,
    /// The epoch time is outside the GPS era
    /// (`measurement::EPOCH_TIME_S`, issue 35).
    TimeOutOfRange {
        /// The epoch time, s.
        t_s: f64,
        /// The earliest time accepted, s.
        min_s: f64,
        /// The latest time accepted, s.
        max_s: f64,
    },
    /// The epoch time did not advance.
    NonMonotonicTime {
        /// The previous epoch's time, s.
        previous_s: f64,
        /// This epoch's time, s.
        now_s: f64,
    },
}

impl core::fmt::Display for PcaError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PcaError::BadConfig { field, value } => {
                write!(f, "configuration {field} = {value} is out of range")
            }
            PcaError::NotFinite {
                field,
                index,
                value,
            } => write!(f, "non-finite {field} at index {index}: {value}"),
            PcaError::CapacityExceeded { have, capacity } => {
                write!(f, "{have} satellites exceed capacity {capacity}")
            }
            PcaError::DuplicateSatellite { first, second } => {
                write!(f, "duplicate satellite at indices {first} and {second}")
            }
            PcaError::TooFewSatellites { have, need } => {
                write!(f, "too few satellites: have {have}, need {need}")
            }
            PcaError::RankDeficient => write!(f, "the all-in-view normal matrix is singular"),
            PcaError::SvdFailed => write!(f, "the SVD of the residual covariance did not converge"),
            PcaError::TimeOutOfRange { t_s, min_s, max_s } => {
                write!(f, "time {t_s} s outside [{min_s}, {max_s}] s")
            }
            PcaError::NonMonotonicTime { previous_s, now_s } => {
                write!(f, "time {now_s} s does not follow {previous_s} s")
            }
        }
    }
}

impl core::error::Error for PcaError {}

/// The test of one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PcaTest<const N: usize> {
    /// Satellites with a complete history (the PCA dimension n_c).
    pub n_complete: usize,
    /// k: the leading components kept.
    pub k: usize,
    /// The singular values of Sigma, descending (first n_c meaningful), m^2.
    pub singular_values_m2: [f64; N],
    /// Share of the singular-value sum the k components cover.
    pub covered: f64,
    /// dx_q = s_q . (z_hat - z), E, N, U (m).
    pub separation_m: [f64; 3],
    /// sigma_q of dx_q over the window (m).
    pub sigma_m: [f64; 3],
    /// T_q = K sigma_q (m).
    pub threshold_m: [f64; 3],
    /// max_q |dx_q| / T_q (0 when no redundancy is left: k = n_c).
    pub ratio: f64,
    /// Some axis exceeded its threshold.
    pub fault: bool,
}

/// One epoch's outcome: the test, or why there is none yet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PcaOutcome<const N: usize> {
    /// The window is full: the PCA test of this epoch.
    Tested(PcaTest<N>),
    /// Fewer than `W` epochs of history, or fewer than 2 satellites with
    /// a complete history.
    WarmingUp {
        /// Epochs of history held.
        epochs: usize,
        /// Satellites with a complete history.
        complete: usize,
    },
}

/// The PCA monitor: `N` satellite slots, a window of `W` epochs.
pub struct Pca<T, const N: usize, const W: usize> {
    ids: [Option<SatId>; N],
    /// Consecutive epochs each slot's satellite has been seen (capped at W).
    run: [usize; N],
    ring: [[T; N]; W],
    head: usize,
    filled: usize,
    last_s: Option<f64>,
}

impl<T: Real, const N: usize, const W: usize> Default for Pca<T, N, W> {
    fn default() -> Self {
        Self {
            ids: [None; N],
            run: [0; N],
            ring: [[T::of(0.0); N]; W],
            head: 0,
            filled: 0,
            last_s: None,
        }
    }
}

/// Column `j` of a column-array matrix as a vector.
fn col<T: Real, const N: usize>(v: &[[T; N]; N], j: usize) -> nalgebra::OVector<T, Const<N>>
where
    DefaultAllocator: nalgebra::allocator::Allocator<Const<N>>,
{
    let mut out = nalgebra::OVector::<T, Const<N>>::zeros();
    if let Some(c) = v.get(j) {
        for (o, x) in out.iter_mut().zip(c.iter()) {
            *o = *x;
        }
    }
    out
}

/// Row q (E, N, U) of the all-in-view WLS gain S0 = (G^T W G)^-1 G^T W for
/// the ARAIM geometry (one clock column per constellation), per satellite.
///
/// # Errors
/// `TooFewSatellites`, `RankDeficient`.
pub fn gain_rows<T: Real, const N: usize>(
    sats: &[AraimSat<T>],
    out: &mut [[T; N]; 3],
) -> Result<(), PcaError> {
    let zero = T::of(0.0);
    let mut col_of = [usize::MAX; MAX_SYSTEMS];
    let mut m = 3;
    for s in sats {
        if let Some(c) = col_of.get_mut(s.id.system.index()) {
            if *c == usize::MAX {
                *c = m;
                m += 1;
            }
        }
    }
    if sats.len() < m {
        return Err(PcaError::TooFewSatellites {
            have: sats.len(),
            need: m,
        });
    }
    let row = |s: &AraimSat<T>| {
        let mut g = [zero; MAX_STATES];
        for (x, v) in g.iter_mut().zip(s.g_enu.iter()) {
            *x = *v;
        }
        // System::index() < MAX_SYSTEMS (its match over System::ALL).
        #[allow(clippy::indexing_slicing)]
        let c = col_of[s.id.system.index()];
        if let Some(x) = g.get_mut(c) {
            *x = T::of(1.0);
        }
        SMatrix::<T, MAX_STATES, 1>::from_column_slice(&g)
    };
    let mut a = SMatrix::<T, MAX_STATES, MAX_STATES>::zeros();
    for s in sats {
        let g = row(s);
        a += g * g.transpose() / s.c_int_m2;
    }
    // Unused state columns: identity, so the factorisation is of the used block.
    for j in m..MAX_STATES {
        if let Some(x) = a.get_mut((j, j)) {
            *x = T::of(1.0);
        }
    }
    let chol = nalgebra::Cholesky::new(a).ok_or(PcaError::RankDeficient)?;
    *out = [[zero; N]; 3];
    for (i, s) in sats.iter().enumerate() {
        let x = chol.solve(&(row(s) / s.c_int_m2));
        for (q, r) in out.iter_mut().enumerate() {
            if let (Some(dst), Some(v)) = (r.get_mut(i), x.get(q)) {
                *dst = *v;
            }
        }
    }
    Ok(())
}

impl<T: Real, const N: usize, const W: usize> Pca<T, N, W>
where
    Const<N>: DimMin<Const<N>, Output = Const<N>> + DimSub<U1>,
    DefaultAllocator: nalgebra::allocator::Allocator<DimDiff<Const<N>, U1>>
        + nalgebra::allocator::Allocator<Const<N>, Const<N>>
        + nalgebra::allocator::Allocator<Const<N>>
        + nalgebra::allocator::Allocator<U1, Const<N>>,
{
    /// A monitor with an empty history.
    pub fn new() -> Self {
        Self::default()
    }

    /// Epochs of history held (at most `W`).
    pub fn filled(&self) -> usize {
        self.filled
    }

    fn validate(cfg: &PcaConfig, t_s: f64, sats: &[AraimSat<T>]) -> Result<(), PcaError> {
        if !(cfg.variance_share > 0.0 && cfg.variance_share <= 1.0) {
            return Err(PcaError::BadConfig {
                field: "variance_share",
                value: cfg.variance_share,
            });
        }
        if !(cfg.p_fa > 0.0 && cfg.p_fa < 1.0) {
            return Err(PcaError::BadConfig {
                field: "p_fa",
                value: cfg.p_fa,
            });
        }
        if !t_s.is_finite() {
            return Err(PcaError::NotFinite {
                field: "t_s",
                index: 0,
                value: t_s,
            });
        }
        let era = crate::measurement::EPOCH_TIME_S;
        if !era.contains(t_s) {
            return Err(PcaError::TimeOutOfRange {
                t_s,
                min_s: era.min,
                max_s: era.max,
            });
        }
        if sats.len() > N {
            return Err(PcaError::CapacityExceeded {
                have: sats.len(),
                capacity: N,
            });
        }
        for (i, s) in sats.iter().enumerate() {
            for (field, v) in [
                ("g_e", s.g_enu[0]),
                ("g_n", s.g_enu[1]),
                ("g_u", s.g_enu[2]),
                ("residual_m", s.residual_m),
                ("c_int_m2", s.c_int_m2),
            ] {
                let v = v.to_f64();
                if !v.is_finite() {
                    return Err(PcaError::NotFinite {
                        field,
                        index: i,
                        value: v,
                    });
                }
            }
            if !(s.c_int_m2.to_f64() > 0.0) {
                return Err(PcaError::NotFinite {
                    field: "c_int_m2",
                    index: i,
                    value: s.c_int_m2.to_f64(),
                });
            }
            if let Some(j) = sats.iter().take(i).position(|o| o.id == s.id) {
                return Err(PcaError::DuplicateSatellite {
                    first: j,
                    second: i,
                });
            }
        }
        Ok(())
    }

    /// Maps this epoch's satellites to slots: frees the slots of absent
    /// satellites (history dropped), gives new satellites a free slot.
    /// Returns slot -> index in `sats`.
    fn assign(&mut self, sats: &[AraimSat<T>]) -> [Option<usize>; N] {
        for (id, run) in self.ids.iter_mut().zip(self.run.iter_mut()) {
            if let Some(x) = id {
                if !sats.iter().any(|s| s.id == *x) {
                    *id = None;
                    *run = 0;
                }
            }
        }
        let mut map = [None; N];
        for (i, s) in sats.iter().enumerate() {
            let slot = match self.ids.iter().position(|x| *x == Some(s.id)) {
                Some(k) => Some(k),
                None => {
                    let free = self.ids.iter().position(|x| x.is_none());
                    if let Some(k) = free {
                        if let (Some(id), Some(run)) = (self.ids.get_mut(k), self.run.get_mut(k)) {
                            *id = Some(s.id);
                            *run = 0;
                        }
                    }
                    free
                }
            };
            if let Some(m) = slot.and_then(|k| map.get_mut(k)) {
                *m = Some(i);
            }
        }
        map
    }

    /// Processes one epoch (time `t_s`, the ARAIM satellites with their
    /// residuals): tests it against the window, then adds it.
    ///
    /// # Errors
    /// A typed [`PcaError`]; the state is unchanged on error.
    pub fn process(
        &mut self,
        cfg: &PcaConfig,
        t_s: f64,
        sats: &[AraimSat<T>],
    ) -> Result<PcaOutcome<N>, PcaError> {
        Self::validate(cfg, t_s, sats)?;
        if let Some(prev) = self.last_s {
            if !(t_s > prev) {
                return Err(PcaError::NonMonotonicTime {
                    previous_s: prev,
                    now_s: t_s,
                });
            }
        }
        let mut gain = [[T::of(0.0); N]; 3];
        gain_rows(sats, &mut gain)?;
        let map = self.assign(sats);
        self.last_s = Some(t_s);

        // Slots with a complete history (all W window epochs) and present now.
        let mut complete = [false; N];
        let mut n_c = 0;
        for ((c, run), m) in complete.iter_mut().zip(self.run.iter()).zip(map.iter()) {
            *c = *run >= W && m.is_some() && self.filled >= W;
            n_c += usize::from(*c);
        }
        let outcome = if n_c < 2 || W < 2 {
            PcaOutcome::WarmingUp {
                epochs: self.filled,
                complete: n_c,
            }
        } else {
            PcaOutcome::Tested(self.test(cfg, sats, &gain, &map, &complete, n_c)?)
        };

        // The epoch enters the window.
        let zero = T::of(0.0);
        if let Some(row) = self.ring.get_mut(self.head) {
            *row = [zero; N];
            for (k, m) in map.iter().enumerate() {
                if let (Some(i), Some(dst)) = (m, row.get_mut(k)) {
                    *dst = sats.get(*i).map_or(zero, |s| s.residual_m);
                }
            }
        }
        self.head = if self.head + 1 >= W { 0 } else { self.head + 1 };
        self.filled = (self.filled + 1).min(W);
        for (run, m) in self.run.iter_mut().zip(map.iter()) {
            if m.is_some() {
                *run = (*run + 1).min(W);
            }
        }
        Ok(outcome)
    }

    fn test(
        &self,
        cfg: &PcaConfig,
        sats: &[AraimSat<T>],
        gain: &[[T; N]; 3],
        map: &[Option<usize>; N],
        complete: &[bool; N],
        n_c: usize,
    ) -> Result<PcaTest<N>, PcaError> {
        let zero = T::of(0.0);
        let w = T::of(W as f64);
        // S201: means and covariance of the complete series.
        let mut mean = [zero; N];
        for row in self.ring.iter() {
            for ((m, x), c) in mean.iter_mut().zip(row.iter()).zip(complete.iter()) {
                if *c {
                    *m += *x;
                }
            }
        }
        for m in mean.iter_mut() {
            *m /= w;
        }
        let mut sigma = nalgebra::OMatrix::<T, Const<N>, Const<N>>::zeros();
        for row in self.ring.iter() {
            let mut d = nalgebra::OVector::<T, Const<N>>::zeros();
            for (k, ((x, m), c)) in row.iter().zip(mean.iter()).zip(complete.iter()).enumerate() {
                if *c {
                    if let Some(v) = d.get_mut(k) {
                        *v = *x - *m;
                    }
                }
            }
            sigma.ger(T::of(1.0), &d, &d, T::of(1.0));
        }
        sigma /= T::of((W - 1) as f64);

        // S202-S203.
        let p = principal(sigma, cfg.variance_share).ok_or(PcaError::SvdFailed)?;
        let k = p.k.min(n_c);

        // S204: z, its features and reconstruction.
        let mut z = nalgebra::OVector::<T, Const<N>>::zeros();
        for (slot, ((m, c), mu)) in map.iter().zip(complete.iter()).zip(mean.iter()).enumerate() {
            if let (Some(i), true) = (m, *c) {
                if let Some(v) = z.get_mut(slot) {
                    *v = sats.get(*i).map_or(zero, |s| s.residual_m) - *mu;
                }
            }
        }
        let mut z_hat = nalgebra::OVector::<T, Const<N>>::zeros();
        for j in 0..k {
            let v = col(&p.v, j);
            let f = v.dot(&z);
            z_hat += v * f;
        }
        let e = z_hat - z;

        // S205: separation of the reconstructed solution and its spread.
        let k_fa = normal_q_inv(cfg.p_fa / 6.0).unwrap_or(f64::NAN);
        let mut sep = [0.0; 3];
        let mut sd = [0.0; 3];
        let mut thr = [0.0; 3];
        let mut ratio: f64 = 0.0;
        let mut fault = false;
        for q in 0..3 {
            let mut s = nalgebra::OVector::<T, Const<N>>::zeros();
            if let Some(g) = gain.get(q) {
                for (slot, (m, c)) in map.iter().zip(complete.iter()).enumerate() {
                    if let (Some(i), true) = (m, *c) {
                        if let (Some(v), Some(&gi)) = (s.get_mut(slot), g.get(*i)) {
                            *v = gi;
                        }
                    }
                }
            }
            let dx = s.dot(&e).to_f64();
            let mut var = 0.0;
            for (j, &lam) in p.values.iter().enumerate().skip(k) {
                let proj = col(&p.v, j).dot(&s).to_f64();
                var += lam * proj * proj;
            }
            let sig = libm::sqrt(var.max(0.0));
            let t = k_fa * sig;
            if let (Some(a), Some(b), Some(c)) = (sep.get_mut(q), sd.get_mut(q), thr.get_mut(q)) {
                *a = dx;
                *b = sig;
                *c = t;
            }
            if k < n_c {
                let r = libm::fabs(dx) / t;
                if !(r <= 1.0) {
                    fault = true;
                }
                if r.is_nan() || r > ratio {
                    ratio = r;
                }
            }
        }
        Ok(PcaTest {
            n_complete: n_c,
            k,
            singular_values_m2: p.values,
            covered: p.covered,
            separation_m: sep,
            sigma_m: sd,
            threshold_m: thr,
            ratio,
            fault,
        })
    }
}

#[cfg(test)]
mod pca_cov_tests;
