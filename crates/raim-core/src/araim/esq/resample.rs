//! The effective-sample resampler (seed 003 claim 1, step S103): inside
//! each window of length T, the epochs that form the effective measurement
//! set {x_e} are the first at or after t_0 + j dT_e, j = 0, 1, ..., where
//! t_0 is the window's first epoch and dT_e = T / N* is fixed from the N*
//! of that epoch. Fixed-size, sans-IO: the time comes in as an argument,
//! N* is computed by the caller (an ARAIM solve of the opening epoch, which
//! is itself the first sample, so it costs no extra solve).

use super::EsqError;

/// Two epoch times closer than this are the same instant (s); it absorbs
/// the receivers' sub-millisecond time-tag jitter.
pub const TIME_TOL_S: f64 = 1e-3;

/// What to do with one epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sample {
    /// Evaluate the integrity test on this epoch: it is sample `index`
    /// (0-based) of the window opened at `window_start_s`.
    Emit {
        /// Start of the window this sample belongs to, s.
        window_start_s: f64,
        /// Sample index within the window (0-based).
        index: u32,
        /// The sampling interval in force, s.
        interval_s: f64,
    },
    /// Skip the epoch (no solve).
    Skip,
}

/// The resampler's state: the current window and the next emission time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Resampler {
    window_s: f64,
    window_start_s: Option<f64>,
    interval_s: f64,
    next_s: f64,
    index: u32,
    last_s: Option<f64>,
}

impl Resampler {
    /// A resampler for windows of `window_s` seconds.
    ///
    /// # Errors
    /// `OutOfRange` when `window_s` is not positive and finite.
    pub fn new(window_s: f64) -> Result<Self, EsqError> {
        if !(window_s > 0.0 && window_s.is_finite()) {
            return Err(EsqError::OutOfRange {
                field: "window_s",
                value: window_s,
            });
        }
        Ok(Self {
            window_s,
            window_start_s: None,
            interval_s: window_s,
            next_s: 0.0,
            index: 0,
            last_s: None,
        })
    }

    /// The window length dT_e, s.
    pub fn window_s(&self) -> f64 {
        self.window_s
    }

    /// The current dT_e (s); T before the first window.
    pub fn interval_s(&self) -> f64 {
        self.interval_s
    }

    /// Whether the epoch at `t_s` opens a new window, i.e. whether the
    /// caller must supply N* (and so solve this epoch) to [`Self::offer`].
    pub fn opens_window(&self, t_s: f64) -> bool {
        match self.window_start_s {
            None => true,
            Some(w) => t_s >= w + self.window_s - TIME_TOL_S,
        }
    }

    /// Offer the epoch at `t_s`. When it opens a window, `n_star` must be
    /// that epoch's N* (else the call is refused and the state unchanged);
    /// otherwise `n_star` is ignored.
    ///
    /// # Errors
    /// `NotFinite` for a non-finite time, `NonMonotonicTime` when `t_s` is
    /// not after the previous epoch, `OutOfRange` for a time outside the
    /// GPS era (`measurement::EPOCH_TIME_S`) or when a window opens
    /// without a finite N* >= 1.
    pub fn offer(&mut self, t_s: f64, n_star: Option<f64>) -> Result<Sample, EsqError> {
        if !t_s.is_finite() {
            return Err(EsqError::NotFinite {
                field: "t_s",
                value: t_s,
            });
        }
        // The GPS era (`measurement::EPOCH_TIME_S`, issue 35).
        if !crate::measurement::EPOCH_TIME_S.contains(t_s) {
            return Err(EsqError::OutOfRange {
                field: "t_s",
                value: t_s,
            });
        }
        if let Some(prev) = self.last_s {
            if !(t_s > prev) {
                return Err(EsqError::NonMonotonicTime {
                    previous_s: prev,
                    now_s: t_s,
                });
            }
        }
        if self.opens_window(t_s) {
            let n = n_star.unwrap_or(f64::NAN);
            if !(n >= 1.0 && n.is_finite()) {
                return Err(EsqError::OutOfRange {
                    field: "n_star",
                    value: n,
                });
            }
            self.last_s = Some(t_s);
            self.window_start_s = Some(t_s);
            self.interval_s = self.window_s / n;
            self.index = 0;
            self.next_s = t_s + self.interval_s;
            return Ok(Sample::Emit {
                window_start_s: t_s,
                index: 0,
                interval_s: self.interval_s,
            });
        }
        self.last_s = Some(t_s);
        let start = self.window_start_s.unwrap_or(t_s);
        if t_s >= self.next_s - TIME_TOL_S {
            // Skip the emission times that fell into a data gap: one sample
            // per epoch at most, never a burst.
            let k = libm::floor((t_s + TIME_TOL_S - start) / self.interval_s);
            self.next_s = start + (k + 1.0) * self.interval_s;
            self.index = self.index.saturating_add(1);
            return Ok(Sample::Emit {
                window_start_s: start,
                index: self.index,
                interval_s: self.interval_s,
            });
        }
        Ok(Sample::Skip)
    }
}
