//! The per-epoch entry point: validate the configuration and the epoch,
//! then dispatch to the engine the configuration selects: the snapshot
//! monitor (`snapshot`, SPEC §3-6), or the snapshot test with the MCUSUM
//! beside it (`sequential`, SPEC §7). Allocates nothing; the state is the
//! engines' (a per-dof threshold cache, and the MCUSUM's accumulated vector
//! and holds). The caller owns time, bytes and configuration.

use crate::config::Config;
use crate::error::RaimError;
use crate::measurement::{validate, Epoch};
use crate::real::{Real, Stat};
use crate::result::EpochResult;
use crate::sequential::mcusum::Mcusum;
use crate::sequential::Sequential;
use crate::snapshot::fde::FdeOutcome;
use crate::snapshot::Snapshot;

/// The integrity monitor. `N` is the satellite capacity (default 32); all
/// buffers are N-sized, on the stack or, for the epoch's FDE outcome (the
/// solution in force), in the monitor itself (scratch, reset at every
/// epoch: the firmware keeps the monitor in a static). `T` is the precision of the
/// statistics path (docs/CORE.md, "Precision"): [`Stat`] (f64) by default;
/// the device runs `Raim::<N, f32>`, and `Raim::<N, f32>` and
/// `Raim::<N, f64>` can run side by side.
#[derive(Debug, Clone)]
pub struct Raim<const N: usize = 32, T: Real = Stat> {
    snapshot: Snapshot<N, T>,
    sequential: Sequential<N, T>,
    /// Scratch, not state: the epoch's FDE outcome (the solution in force),
    /// kept here rather than on the stack and reset at every
    /// epoch, so no result depends on an earlier epoch through it.
    outcome: FdeOutcome<N, T>,
}

impl<const N: usize, T: Real> Default for Raim<N, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, T: Real> Raim<N, T> {
    /// An engine with no history (MCUSUM and PF state empty).
    pub const fn new() -> Self {
        Raim {
            snapshot: Snapshot::new(),
            sequential: Sequential::new(),
            outcome: FdeOutcome::empty(),
        }
    }

    /// The MCUSUM state (accumulated vector and holds).
    pub fn mcusum(&self) -> &Mcusum<N, T> {
        &self.sequential.mcusum
    }

    /// Restart the MCUSUM and release its holds (e.g. a new run).
    pub fn reset_mcusum(&mut self) {
        self.sequential.mcusum.clear();
    }

    /// Gauss-Newton warm start from the last epoch's solution (off by
    /// default; see [`Snapshot::set_warm_start`]).
    pub fn set_warm_start(&mut self, on: bool) {
        self.snapshot.set_warm_start(on);
    }

    /// The chi-square threshold T^2 and lambda_md for a dof (cached).
    pub fn thresholds(&mut self, cfg: &Config, dof: usize) -> Result<(f64, f64), RaimError> {
        self.snapshot.thresholds(cfg, dof)
    }

    /// Process one epoch: the snapshot test, identification, FDE and PLs;
    /// with `cfg.mcusum.enabled`, the MCUSUM beside it (SPEC §7.4).
    ///
    /// An 8-satellite GPS sky in the linearised form (azimuth, elevation and
    /// the pseudorange residual of each satellite; sigmas from the default
    /// elevation model), first clean, then with a 60 m step on G07:
    ///
    /// ```
    /// use raim_core::{Config, Decision, Epoch, LinearObservation, Phase, Raim, SatId, System};
    ///
    /// // (PRN, azimuth deg, elevation deg, residual m): a spread sky, metre-level noise.
    /// const SKY: [(u8, f64, f64, f64); 8] = [
    ///     (2, 40.0, 72.0, 0.6),
    ///     (5, 95.0, 35.0, -1.1),
    ///     (7, 150.0, 55.0, 0.3),
    ///     (12, 210.0, 20.0, 1.4),
    ///     (15, 260.0, 48.0, -0.4),
    ///     (19, 310.0, 15.0, -1.6),
    ///     (24, 350.0, 30.0, 0.9),
    ///     (29, 120.0, 10.0, -0.2),
    /// ];
    /// let sky = |step_on: u8, step_m: f64| {
    ///     SKY.map(|(prn, az_deg, el_deg, residual_m)| {
    ///         let bias_m = if prn == step_on { step_m } else { 0.0 };
    ///         LinearObservation::from_az_el(
    ///             SatId::new(System::Gps, prn),
    ///             az_deg.to_radians(),
    ///             el_deg.to_radians(),
    ///             residual_m + bias_m,
    ///         )
    ///     })
    /// };
    ///
    /// // Non-precision approach: HAL 556 m, Pfa 3.3e-7, Pmd 1e-3.
    /// let cfg = Config::preset(Phase::Npa);
    /// let mut raim: Raim = Raim::new();
    ///
    /// let clean = sky(0, 0.0);
    /// let r = raim.process(&cfg, &Epoch::linear(0.0, &clean))?;
    /// assert_eq!(r.decision, Decision::Ok);
    /// assert!(r.test.statistic < r.test.threshold); // D^2 < T^2, dof n - m = 4
    /// assert!(r.protection.hpl_m < cfg.alert.hal_m); // HPL within HAL
    /// assert!(r.protection.vpl_m.is_finite());
    ///
    /// let faulty = sky(7, 60.0);
    /// let r = raim.process(&cfg, &Epoch::linear(1.0, &faulty))?;
    /// assert_eq!(r.decision, Decision::Excluded);
    /// assert!(r.initial_test.statistic > r.initial_test.threshold);
    /// assert_eq!(r.exclusions[0].id, SatId::new(System::Gps, 7));
    /// assert!(r.test.statistic < r.test.threshold); // the subset passes
    /// assert!(r.protection.hpl_m < cfg.alert.hal_m); // its HPL, 7 satellites
    /// # Ok::<(), raim_core::RaimError>(())
    /// ```
    pub fn process(
        &mut self,
        cfg: &Config,
        epoch: &Epoch<'_>,
    ) -> Result<EpochResult<N>, RaimError> {
        let mut result = EpochResult::empty();
        self.process_into(cfg, epoch, &mut result)?;
        Ok(result)
    }

    /// [`Raim::process`] with the result written into `out` (every field;
    /// on an error `out` is unspecified and the error is returned). For a
    /// caller that keeps the result in its own storage (the firmware's
    /// static server): no result-sized value on the stack.
    pub fn process_into(
        &mut self,
        cfg: &Config,
        epoch: &Epoch<'_>,
        out: &mut EpochResult<N>,
    ) -> Result<(), RaimError> {
        cfg.validate()?;
        validate::<N>(epoch)?;
        if cfg.mcusum.enabled {
            return self.sequential.process_into(
                &mut self.snapshot,
                cfg,
                epoch,
                &mut self.outcome,
                out,
            );
        }
        self.sequential.mcusum.clear();
        self.outcome.reset();
        self.snapshot.run(cfg, epoch, &mut self.outcome, out)
    }
}
