//! The ARAIM epoch, written once: from an epoch and the ISM to the
//! verdict and the satellites excluded (SPEC §9.1, the ADD's steps).
//!
//! [`Monitor`] owns the all-in-view engine, the FDE's scratch engine, the
//! epoch's joined satellites and, for pseudoranges, the Gauss-Newton
//! solution and its linearised form: nothing N- or K-sized is built on the
//! caller's stack, so a device keeps one `Monitor` in a static.
//! [`MonitorCore`] is the same monitor without the FDE's scratch engine
//! ([`FdeScratch`]), which its caller lends at each epoch: a device may
//! then keep the scratch in a room it shares with other per-epoch users
//! (docs/FLASH.md, "STM32F4: the stream"). Per epoch:
//!
//! 1. The ISM join: each satellite of the epoch gets its ISM entry
//!    (sigma_URA, sigma_URE, b_nom, P_sat; [`SatelliteModels::ism`]), a
//!    satellite without one is refused ([`MonitorError::NotInIsm`]), and
//!    P_const is kept for the constellations in the epoch only.
//! 2. C_int = sigma_URA^2 + v and C_acc = sigma_URE^2 + v, v the nominal
//!    variance: the square of the observation's own sigma when it gives
//!    one, else the curves of [`error_model`](super::error_model) at the
//!    elevation of its line of sight ([`Curves`], in f64 through `libm`).
//! 3. Pseudoranges ([`Monitor::epoch`]) are linearised at the all-in-view
//!    Gauss-Newton solution of [`crate::solve`] (the snapshot
//!    configuration's iteration limit, convergence and weights): per
//!    satellite the unit line of sight in ENU there and the residual
//!    pseudorange - |sat - x0| - clock(system), in f64.
//! 4. The all-in-view run ([`Araim::process`]: the fault modes, the subset
//!    solutions and tests, the PLs, EMT, sigma_v,acc, the availability).
//! 5. After a failed test, FDE ([`Araim::fde_within`]) within the work
//!    budget of [`FdeLimits`]; not attempted above its mode limit.
//! 6. The verdict ([`Verdict`]): the [`Decision`], the exclusion outcome,
//!    the excluded satellites (those of an excluded constellation
//!    included) and, for pseudoranges, the position in force: x0 plus the
//!    ENU correction of the solution in force (the excluded subset's after
//!    an exclusion, else the all-in-view one).

use heapless::Vec;

use super::error_model::{elevation_from_g, Curves};
use super::fde::{FdeBudget, FdeDecision};
use super::{Araim, AraimConfig, AraimError, AraimOutput, AraimSat, Ism, Unavailable};
use crate::config::Config;
use crate::error::RaimError;
use crate::frames::{enu_rotation, rotate, unrotate};
use crate::measurement::{
    check_prns, check_time_s, Epoch, LinearObservation, Observations, RangeObservation, SatId,
    MAX_SYSTEMS,
};
use crate::real::Real;
use crate::result::Decision;
use crate::solve::{solve_into, Solution};

/// One satellite's entry of the integrity support message.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SatIsm {
    /// The satellite.
    pub id: SatId,
    /// sigma_URA (m), for C_int.
    pub sigma_ura_m: f64,
    /// sigma_URE (m), for C_acc.
    pub sigma_ure_m: f64,
    /// The maximum nominal bias b_nom (m).
    pub b_nom_m: f64,
    /// The prior probability of a satellite fault, P_sat, in (0, 1).
    pub p_sat: f64,
}

/// What the monitor joins to each satellite of an epoch: its ISM entry
/// and its nominal curves.
pub trait SatelliteModels {
    /// The ISM entry of `id`; `None` refuses the epoch
    /// ([`MonitorError::NotInIsm`]): P_sat and sigma_URA are integrity
    /// parameters the monitor must not invent.
    fn ism(&self, id: SatId) -> Option<SatIsm>;

    /// The nominal curves of `id` (used when its observation gives no
    /// sigma): the ADD's L1/L5 model by default.
    fn curves(&self, id: SatId) -> Curves {
        let _ = id;
        Curves::default()
    }
}

/// A list of ISM entries, searched by satellite, with the ADD's curves.
impl SatelliteModels for [SatIsm] {
    fn ism(&self, id: SatId) -> Option<SatIsm> {
        self.iter().find(|s| s.id == id).copied()
    }
}

/// The limits of the exclusion search (`fde.rs`, "Work budget").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FdeLimits {
    /// Exclusion is attempted only when the failed all-in-view run has at
    /// most this many monitored modes; above it the epoch is an alarm
    /// ([`Exclusion::NotAttempted`]).
    pub max_modes: usize,
    /// The work allowed, in candidate-modes: with `m` monitored modes the
    /// search may process `work_candidate_modes / m` candidate subsets
    /// (each is an epoch of about `m` modes of its own).
    pub work_candidate_modes: usize,
}

impl FdeLimits {
    /// No limit. (`usize::MAX / m` candidates exceed any mode list that
    /// fits in memory, so the outcome is the unlimited search's.)
    pub const UNLIMITED: Self = FdeLimits {
        max_modes: usize::MAX,
        work_candidate_modes: usize::MAX,
    };

    /// The candidate budget for an all-in-view run with `monitored` modes.
    pub fn budget(&self, monitored: usize) -> FdeBudget {
        FdeBudget {
            max_candidates: self.work_candidate_modes / monitored.max(1),
        }
    }
}

/// What became of the exclusion step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Exclusion {
    /// The fault modes could not be enumerated (`ModeCapacity`,
    /// `TooManyEvents`): no test ran, the epoch is `Unavailable`.
    NotTested,
    /// The test failed with more monitored modes than
    /// [`FdeLimits::max_modes`]: no exclusion attempted, an `Alarm`.
    NotAttempted {
        /// The monitored modes of the failed test.
        monitored: usize,
    },
    /// The FDE's outcome (`NoFault` when the test passed).
    Fde(FdeDecision),
}

/// One epoch's verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict<const N: usize> {
    /// `Ok` (consistent, available), `Unavailable` (consistent or
    /// excluded, or untested, without service), `Excluded` (a fault
    /// excluded and the subset available), `Alarm` (a test failed and
    /// nothing was excluded).
    pub decision: Decision,
    /// What the fault detection and exclusion did.
    pub exclusion: Exclusion,
    /// The satellites excluded, in epoch order (empty unless excluded).
    pub excluded: Vec<SatId, N>,
    /// For pseudoranges, the ECEF position in force (m).
    pub position_ecef_m: Option<[f64; 3]>,
}

/// Why an epoch was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MonitorError {
    /// The ARAIM engine's refusal (input ranges, duplicates, capacity,
    /// constellations, too few satellites, a singular geometry).
    Araim(AraimError),
    /// A refusal shared with the snapshot monitor: a non-finite or
    /// non-positive input, or the Gauss-Newton solution of pseudoranges.
    Raim(RaimError),
    /// The satellite at `index` has no ISM entry.
    NotInIsm {
        /// The satellite.
        id: SatId,
        /// Its index in the epoch.
        index: usize,
    },
}

impl From<AraimError> for MonitorError {
    fn from(e: AraimError) -> Self {
        MonitorError::Araim(e)
    }
}

impl From<RaimError> for MonitorError {
    fn from(e: RaimError) -> Self {
        MonitorError::Raim(e)
    }
}

impl core::fmt::Display for MonitorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MonitorError::Araim(e) => write!(f, "{e}"),
            MonitorError::Raim(e) => write!(f, "{e}"),
            MonitorError::NotInIsm { id, index } => {
                write!(f, "satellite {id} at index {index} has no ISM entry")
            }
        }
    }
}

/// The ARAIM monitor: `N` satellites, `K` fault modes per engine,
/// precision `T`. Module doc for the steps of one epoch.
///
/// # Example
///
/// The sky of ADD v3.0 Appendix D (GPS 1-5 and Galileo 1-5, each line of
/// sight minus the published G row) with the ISM of the appendix
/// (sigma_URA 0.75 m, sigma_URE 0.5 m, b_nom 0.5 m, P_sat 1e-5, P_const
/// 1e-4; the curves give the published C_int and C_acc) and LPV-200:
/// consistent and available, VPL 19.2 m as published. With 30 m on G3 the
/// test fails, and both G3 and the whole Galileo constellation explain
/// the data: the monitor does not pick one, it raises the alarm.
///
/// ```
/// use raim_core::araim::{
///     AraimConfig, Exclusion, FdeAlarm, FdeDecision, FdeLimits, Ism, Monitor, SatIsm,
/// };
/// use raim_core::{Decision, LinearObservation, SatId, System};
///
/// const G_ROWS: [[f64; 3]; 10] = [
///     [0.0225, 0.9951, -0.0966],
///     [0.6750, -0.6900, -0.2612],
///     [0.0723, -0.6601, -0.7477],
///     [-0.9398, 0.2553, -0.2269],
///     [-0.5907, -0.7539, -0.2877],
///     [-0.3236, -0.0354, -0.9455],
///     [-0.6748, 0.4356, -0.5957],
///     [0.0938, -0.7004, -0.7075],
///     [0.5571, 0.3088, -0.7709],
///     [0.6622, 0.6958, -0.2780],
/// ];
/// let mut obs = [LinearObservation::default(); 10];
/// let mut entries = [SatIsm::default(); 10];
/// for (i, g) in G_ROWS.iter().enumerate() {
///     let system = if i < 5 { System::Gps } else { System::Galileo };
///     let id = SatId::new(system, (i % 5 + 1) as u8);
///     obs[i] = LinearObservation {
///         id,
///         los_enu: g.map(|v| -v),
///         residual_m: 0.0,
///         sigma_m: None,
///     };
///     entries[i] = SatIsm {
///         id,
///         sigma_ura_m: 0.75,
///         sigma_ure_m: 0.5,
///         b_nom_m: 0.5,
///         p_sat: 1e-5,
///     };
/// }
/// let cfg = AraimConfig::default();
/// let ism = Ism::with(&[System::Gps, System::Galileo], 1e-4);
/// // Two engines of 600 modes: on the heap here, in a static on a device.
/// let mut monitor = Box::new(Monitor::<f64, 16, 600>::new());
///
/// let v = monitor.linear(&cfg, &ism, &entries[..], &obs, FdeLimits::UNLIMITED)?;
/// assert_eq!(v.decision, Decision::Ok);
/// assert_eq!(v.exclusion, Exclusion::Fde(FdeDecision::NoFault));
/// let out = monitor.all_in_view();
/// assert_eq!(out.modes.len(), 12);
/// assert!((out.pl_add.vpl_m - 19.2).abs() < 0.05);
///
/// obs[2].residual_m = 30.0;
/// let v = monitor.linear(&cfg, &ism, &entries[..], &obs, FdeLimits::UNLIMITED)?;
/// assert_eq!(v.decision, Decision::Alarm);
/// assert!(matches!(
///     v.exclusion,
///     Exclusion::Fde(FdeDecision::Alarm(FdeAlarm::Ambiguous { .. }))
/// ));
/// assert!(v.excluded.is_empty());
/// # Ok::<(), raim_core::araim::MonitorError>(())
/// ```
pub struct Monitor<T: Real, const N: usize, const K: usize> {
    core: MonitorCore<T, N, K>,
    scratch: FdeScratch<T, N, K>,
}

impl<T: Real, const N: usize, const K: usize> Default for Monitor<T, N, K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const N: usize, const K: usize> Monitor<T, N, K> {
    /// A monitor with empty engines (the first epoch fills them).
    pub const fn new() -> Self {
        Monitor {
            core: MonitorCore::new(),
            scratch: FdeScratch::new(),
        }
    }

    /// A linearised epoch: steps 1, 2, 4-6 of the module doc. `ism` gives
    /// P_const, `models` the satellites' ISM entries and curves.
    ///
    /// # Errors
    /// [`MonitorError`]: a satellite not in the ISM, a non-positive or
    /// non-finite sigma, or the engine's refusal of the epoch.
    pub fn linear<M: SatelliteModels + ?Sized>(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        models: &M,
        obs: &[LinearObservation],
        limits: FdeLimits,
    ) -> Result<Verdict<N>, MonitorError> {
        let (verdict, _) = self
            .core
            .linear(&mut self.scratch, cfg, ism, models, obs, limits)?;
        Ok(verdict)
    }

    /// An epoch of either form: [`Self::linear`] for linearised rows; for
    /// pseudoranges, steps 1-6 of the module doc, linearised at the
    /// Gauss-Newton solution of `solver` (the snapshot configuration: its
    /// iteration limit, convergence and, as weights, its sigma model).
    ///
    /// # Errors
    /// As [`Self::linear`], and for pseudoranges the solver's refusal
    /// (non-finite input, too few satellites, no convergence) or a
    /// solution off the Earth's surface (no local frame for the curves).
    pub fn epoch<M: SatelliteModels + ?Sized>(
        &mut self,
        solver: &Config,
        cfg: &AraimConfig,
        ism: &Ism,
        models: &M,
        epoch: &Epoch<'_>,
        limits: FdeLimits,
    ) -> Result<Verdict<N>, MonitorError> {
        let (verdict, _) =
            self.core
                .epoch(&mut self.scratch, solver, cfg, ism, models, epoch, limits)?;
        Ok(verdict)
    }

    /// Satellites whose C_int and C_acc are already known (no join, no
    /// curves): steps 4-6 of the module doc on `sats` and `ism` as given.
    ///
    /// # Errors
    /// The engine's refusal of the epoch.
    pub fn given(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        limits: FdeLimits,
    ) -> Result<Verdict<N>, MonitorError> {
        let (verdict, _) = self.core.given(&mut self.scratch, cfg, ism, sats, limits)?;
        Ok(verdict)
    }

    /// Availability with exclusion (issue 36): after the last epoch, the
    /// output after excluding the events of the all-in-view run's mode `k`
    /// ([`Araim::after_excluding`], in the FDE's scratch engine, which
    /// then holds no excluded subset: [`Self::in_force`] is the
    /// all-in-view output afterwards). `ism` is the epoch's.
    ///
    /// # Errors
    /// The engine's refusal of the subset (not its geometry: `Ok(None)`).
    pub fn after_excluding(
        &mut self,
        cfg: &AraimConfig,
        ism: &Ism,
        k: usize,
    ) -> Result<Option<&AraimOutput<T, K>>, MonitorError> {
        self.core.after_excluding(&mut self.scratch, cfg, ism, k)
    }

    /// Sets the all-in-view estimator of every later epoch
    /// ([`Araim::set_estimator`]; the FDE's subsets take it too).
    ///
    /// # Errors
    /// As [`Araim::set_estimator`].
    pub fn set_estimator(&mut self, estimator: super::Estimator) -> Result<(), AraimError> {
        self.core.set_estimator(estimator)
    }

    /// The last epoch's runs (all in view, and the excluded subset's).
    pub fn runs(&self) -> Runs<'_, T, N, K> {
        self.core.runs_with(&self.scratch)
    }

    /// The last epoch's all-in-view output.
    pub fn all_in_view(&self) -> &AraimOutput<T, K> {
        self.core.all_in_view()
    }

    /// After an exclusion, the remaining subset's output (its PLs with the
    /// exclusion risk); `None` otherwise.
    pub fn after_exclusion(&self) -> Option<&AraimOutput<T, K>> {
        self.runs().after_exclusion()
    }

    /// The output in force: the subset's after an exclusion, else the
    /// all-in-view one.
    pub fn in_force(&self) -> &AraimOutput<T, K> {
        self.runs().in_force()
    }

    /// The model check's sample of the last epoch (issue 35,
    /// docs/MODEL_CHECK.md): q and dof of the C_acc-weighted fit of the
    /// solution in force (the excluded subset's after an exclusion, else
    /// all in view). Offer it to a [`crate::consistency::ModelCheck`] for
    /// an answered epoch (not an `Alarm`, not a refused epoch).
    ///
    /// # Errors
    /// As [`crate::consistency::fit::accuracy_fit`].
    pub fn accuracy_sample(
        &self,
    ) -> Result<crate::consistency::fit::Fit, crate::consistency::ModelCheckError> {
        self.runs().accuracy_sample()
    }

    /// The last epoch's satellites as the engine saw them (joined).
    pub fn satellites(&self) -> &[AraimSat<T>] {
        self.core.satellites()
    }
}

/// The FDE's scratch engine (`N` satellites, `K` fault modes, precision
/// `T`): the candidate subsets are processed in it, and after an exclusion
/// it holds the excluded subset's output. [`Monitor`] owns one;
/// [`MonitorCore`] takes it from its caller at each epoch, so that a
/// device may keep it in a room it shares with other per-epoch users
/// (docs/FLASH.md, "STM32F4: the stream"). It carries nothing from one
/// epoch to the next that changes a result (the engine's memos answer only
/// for their own keys): a scratch new at every epoch gives the same bits
/// (test `monitor::lent::a_scratch_new_at_every_epoch_gives_the_same_bits`).
pub struct FdeScratch<T, const N: usize, const K: usize>(Araim<T, N, K>);

impl<T: Real, const N: usize, const K: usize> Default for FdeScratch<T, N, K> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real, const N: usize, const K: usize> FdeScratch<T, N, K> {
    /// An empty scratch engine (`const`: a device builds it in place).
    pub const fn new() -> Self {
        FdeScratch(Araim::new())
    }
}

/// The runs of one epoch, as [`MonitorCore`]'s epoch returns them with its
/// verdict (borrowing the scratch lent for it, so that nothing else can
/// have used the scratch before they are read), or as [`Monitor::runs`]
/// gives them.
#[derive(Clone, Copy)]
pub struct Runs<'a, T, const N: usize, const K: usize> {
    main: &'a Araim<T, N, K>,
    /// The scratch engine, holding the excluded subset: `Some` after an
    /// exclusion only.
    after: Option<&'a Araim<T, N, K>>,
    sats: &'a [AraimSat<T>],
}

impl<'a, T: Real, const N: usize, const K: usize> Runs<'a, T, N, K> {
    /// The all-in-view output.
    pub fn all_in_view(&self) -> &'a AraimOutput<T, K> {
        self.main.output()
    }

    /// After an exclusion, the remaining subset's output (its PLs with the
    /// exclusion risk); `None` otherwise.
    pub fn after_exclusion(&self) -> Option<&'a AraimOutput<T, K>> {
        self.after.map(|a| a.output())
    }

    /// The output in force: the subset's after an exclusion, else the
    /// all-in-view one.
    pub fn in_force(&self) -> &'a AraimOutput<T, K> {
        self.after.unwrap_or(self.main).output()
    }

    /// The model check's sample ([`Monitor::accuracy_sample`]): the fit of
    /// the solution in force.
    ///
    /// # Errors
    /// As [`crate::consistency::fit::accuracy_fit`].
    pub fn accuracy_sample(
        &self,
    ) -> Result<crate::consistency::fit::Fit, crate::consistency::ModelCheckError> {
        crate::consistency::fit::accuracy_fit(self.after.unwrap_or(self.main).geometry())
    }

    /// The epoch's satellites as the engine saw them (joined).
    pub fn satellites(&self) -> &'a [AraimSat<T>] {
        self.sats
    }
}

/// The ARAIM monitor without its FDE scratch engine: each epoch borrows
/// one from the caller ([`FdeScratch`]) and returns, with its verdict, its
/// [`Runs`] borrowing it. The one decision path: [`Monitor`] is this with
/// a scratch of its own.
pub struct MonitorCore<T: Real, const N: usize, const K: usize> {
    main: Araim<T, N, K>,
    sats: [AraimSat<T>; N],
    n_sats: usize,
    /// The last epoch ended in an exclusion: the scratch lent for it holds
    /// its subset.
    excluded: bool,
    solution: Solution<N, T>,
    lin: [LinearObservation; N],
}

impl<T: Real, const N: usize, const K: usize> Default for MonitorCore<T, N, K> {
    fn default() -> Self {
        Self::new()
    }
}

/// An epoch's verdict and its runs.
pub type Decided<'a, T, const N: usize, const K: usize> = (Verdict<N>, Runs<'a, T, N, K>);

impl<T: Real, const N: usize, const K: usize> MonitorCore<T, N, K> {
    /// A monitor with an empty engine (the first epoch fills it).
    pub const fn new() -> Self {
        MonitorCore {
            main: Araim::new(),
            sats: [AraimSat::ZERO; N],
            n_sats: 0,
            excluded: false,
            solution: Solution::empty(),
            lin: [LinearObservation::DEFAULT; N],
        }
    }

    /// [`Monitor::linear`], the FDE in `scratch`.
    ///
    /// # Errors
    /// As [`Monitor::linear`].
    pub fn linear<'a, M: SatelliteModels + ?Sized>(
        &'a mut self,
        scratch: &'a mut FdeScratch<T, N, K>,
        cfg: &AraimConfig,
        ism: &Ism,
        models: &M,
        obs: &[LinearObservation],
        limits: FdeLimits,
    ) -> Result<Decided<'a, T, N, K>, MonitorError> {
        self.n_sats = 0;
        self.excluded = false;
        let ism = join(&mut self.sats, ism, models, obs)?;
        self.n_sats = obs.len();
        let verdict = self.decide(&mut scratch.0, cfg, &ism, limits)?;
        Ok((verdict, self.runs_with(scratch)))
    }

    /// [`Monitor::epoch`], the FDE in `scratch`.
    ///
    /// # Errors
    /// As [`Monitor::epoch`].
    #[allow(clippy::too_many_arguments)]
    pub fn epoch<'a, M: SatelliteModels + ?Sized>(
        &'a mut self,
        scratch: &'a mut FdeScratch<T, N, K>,
        solver: &Config,
        cfg: &AraimConfig,
        ism: &Ism,
        models: &M,
        epoch: &Epoch<'_>,
        limits: FdeLimits,
    ) -> Result<Decided<'a, T, N, K>, MonitorError> {
        check_time_s(epoch.time_s)?;
        let sats = match epoch.observations {
            Observations::Linear { sats } => {
                return self.linear(scratch, cfg, ism, models, sats, limits)
            }
            Observations::Ranges { sats, .. } => sats,
        };
        self.n_sats = 0;
        self.excluded = false;
        let (x0, rot) = self.linearise(solver, epoch, sats)?;
        let lin = self
            .lin
            .get(..sats.len())
            .ok_or(capacity::<N>(sats.len()))?;
        let ism = join(&mut self.sats, ism, models, lin)?;
        self.n_sats = lin.len();
        let mut verdict = self.decide(&mut scratch.0, cfg, &ism, limits)?;
        let runs = self.runs_with(scratch);
        let correction = runs.in_force().correction_enu_m.map(|c| c.to_f64());
        let shift = unrotate(&rot, correction);
        verdict.position_ecef_m = Some([x0[0] + shift[0], x0[1] + shift[1], x0[2] + shift[2]]);
        Ok((verdict, runs))
    }

    /// [`Monitor::given`], the FDE in `scratch`.
    ///
    /// # Errors
    /// As [`Monitor::given`].
    pub fn given<'a>(
        &'a mut self,
        scratch: &'a mut FdeScratch<T, N, K>,
        cfg: &AraimConfig,
        ism: &Ism,
        sats: &[AraimSat<T>],
        limits: FdeLimits,
    ) -> Result<Decided<'a, T, N, K>, MonitorError> {
        self.n_sats = 0;
        self.excluded = false;
        if sats.len() > N {
            return Err(capacity::<N>(sats.len()));
        }
        for (slot, s) in self.sats.iter_mut().zip(sats) {
            *slot = *s;
        }
        self.n_sats = sats.len();
        let verdict = self.decide(&mut scratch.0, cfg, ism, limits)?;
        Ok((verdict, self.runs_with(scratch)))
    }

    /// [`Monitor::after_excluding`], in `scratch`.
    ///
    /// # Errors
    /// As [`Monitor::after_excluding`].
    pub fn after_excluding<'s>(
        &mut self,
        scratch: &'s mut FdeScratch<T, N, K>,
        cfg: &AraimConfig,
        ism: &Ism,
        k: usize,
    ) -> Result<Option<&'s AraimOutput<T, K>>, MonitorError> {
        self.excluded = false;
        let sats = self
            .sats
            .get(..self.n_sats)
            .ok_or(capacity::<N>(self.n_sats))?;
        Ok(self
            .main
            .after_excluding(cfg, ism, sats, k, &mut scratch.0)?)
    }

    /// The last epoch's all-in-view output.
    pub fn all_in_view(&self) -> &AraimOutput<T, K> {
        self.main.output()
    }

    /// [`Monitor::set_estimator`].
    ///
    /// # Errors
    /// As [`Araim::set_estimator`].
    pub fn set_estimator(&mut self, estimator: super::Estimator) -> Result<(), AraimError> {
        self.main.set_estimator(estimator)
    }

    /// The last epoch's satellites as the engine saw them (joined).
    pub fn satellites(&self) -> &[AraimSat<T>] {
        // n_sats <= N: it is set only after `join` or `given` checked the
        // count against N (and reset to 0 before either runs), so the
        // empty fallback is never taken; it keeps a panic path off the
        // device's epoch path.
        self.sats.get(..self.n_sats).unwrap_or_default()
    }

    /// The runs of the last epoch with `scratch`, the one lent for it
    /// (private: the epochs return them, borrowing the scratch).
    fn runs_with<'a>(&'a self, scratch: &'a FdeScratch<T, N, K>) -> Runs<'a, T, N, K> {
        Runs {
            main: &self.main,
            after: self.excluded.then_some(&scratch.0),
            sats: self.satellites(),
        }
    }

    /// Step 3: Gauss-Newton all in view, then the linearised epoch at its
    /// solution x0 in `self.lin`; x0 and its ENU rotation.
    fn linearise(
        &mut self,
        solver: &Config,
        epoch: &Epoch<'_>,
        sats: &[RangeObservation],
    ) -> Result<([f64; 3], nalgebra::Matrix3<f64>), MonitorError> {
        let apriori_m = match epoch.observations {
            Observations::Ranges { apriori_m, .. } => apriori_m,
            Observations::Linear { .. } => None,
        };
        check_ranges(epoch.time_s, sats, apriori_m)?;
        if sats.len() > N {
            return Err(RaimError::CapacityExceeded {
                have: sats.len(),
                capacity: N,
            }
            .into());
        }
        let mut mask = [false; N];
        for m in mask.iter_mut().take(sats.len()) {
            *m = true;
        }
        solve_into(solver, epoch, &mask, &mut self.solution)?;
        let solution = &self.solution;
        let (Some(x0), Some(geo)) = (solution.position_ecef_m, solution.geodetic) else {
            return Err(RaimError::OutOfRange {
                field: "position_radius_m",
                value: libm::sqrt(
                    solution
                        .position_ecef_m
                        .map(|p| p[0] * p[0] + p[1] * p[1] + p[2] * p[2])
                        .unwrap_or(0.0),
                ),
                min: 5.0e6,
                max: f64::INFINITY,
            }
            .into());
        };
        let rot = enu_rotation(&geo);
        for (o, slot) in sats.iter().zip(self.lin.iter_mut()) {
            let d = [
                o.position_m[0] - x0[0],
                o.position_m[1] - x0[1],
                o.position_m[2] - x0[2],
            ];
            let range_m = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            let u = rotate(&rot, [d[0] / range_m, d[1] / range_m, d[2] / range_m]);
            // Every satellite was in the solution, so its system has a
            // clock; a system without one would have no clock term.
            let clock_m = *o.id.system.entry(&solution.clock_m);
            debug_assert!(
                clock_m.is_some(),
                "every system in the solution has a clock"
            );
            let residual_m = match clock_m {
                Some(c) => o.pseudorange_m - range_m - c,
                None => o.pseudorange_m - range_m,
            };
            *slot = LinearObservation {
                id: o.id,
                los_enu: u,
                residual_m,
                sigma_m: o.sigma_m,
            };
        }
        Ok((x0, rot))
    }

    /// Steps 4-6 on the joined satellites.
    fn decide(
        &mut self,
        scratch: &mut Araim<T, N, K>,
        cfg: &AraimConfig,
        ism: &Ism,
        limits: FdeLimits,
    ) -> Result<Verdict<N>, MonitorError> {
        let sats = self
            .sats
            .get(..self.n_sats)
            .ok_or(capacity::<N>(self.n_sats))?;
        let out = self.main.process(cfg, ism, sats)?;
        let mut verdict = Verdict {
            decision: Decision::Unavailable,
            exclusion: Exclusion::NotTested,
            excluded: Vec::new(),
            position_ecef_m: None,
        };
        if matches!(
            out.unavailable,
            Some(Unavailable::ModeCapacity { .. } | Unavailable::TooManyEvents { .. })
        ) {
            return Ok(verdict);
        }
        let monitored = out.n_monitored;
        let available = out.available();
        if out.detection_passed {
            verdict.exclusion = Exclusion::Fde(FdeDecision::NoFault);
            if available {
                verdict.decision = Decision::Ok;
            }
            return Ok(verdict);
        }
        verdict.decision = Decision::Alarm;
        if monitored > limits.max_modes {
            verdict.exclusion = Exclusion::NotAttempted { monitored };
            return Ok(verdict);
        }
        let budget = limits.budget(monitored);
        let fde = self.main.fde_within(cfg, ism, sats, scratch, budget)?;
        verdict.exclusion = Exclusion::Fde(fde);
        if let FdeDecision::Excluded { sats: mask, .. } = fde {
            self.excluded = true;
            verdict.decision = if scratch.output().available() {
                Decision::Excluded
            } else {
                Decision::Unavailable
            };
            for (i, s) in sats.iter().enumerate() {
                if i < 64 && mask & (1u64 << i) != 0 {
                    let pushed = verdict.excluded.push(s.id);
                    debug_assert!(pushed.is_ok(), "at most N satellites: never full");
                }
            }
        }
        Ok(verdict)
    }
}

/// The pseudorange inputs' checks before the solver, typed with field and
/// index (the solver's own are for its snapshot epochs).
fn check_ranges(
    time_s: f64,
    sats: &[RangeObservation],
    apriori_m: Option<[f64; 3]>,
) -> Result<(), RaimError> {
    let finite = |field: &'static str, index: usize, value: f64| {
        if value.is_finite() {
            Ok(())
        } else {
            Err(RaimError::NotFinite {
                field,
                index,
                value,
            })
        }
    };
    check_time_s(time_s)?;
    for v in apriori_m.iter().flatten() {
        finite("apriori_m", 0, *v)?;
    }
    for (i, o) in sats.iter().enumerate() {
        finite("pseudorange_m", i, o.pseudorange_m)?;
        for v in o.position_m {
            finite("position_m", i, v)?;
        }
    }
    Ok(())
}

/// Steps 1 and 2: the satellites of `obs` with their ISM entries and
/// C_int/C_acc into `out`, and the ISM's P_const restricted to the
/// constellations present.
/// The refusal of `have` satellites by an `N`-satellite monitor.
fn capacity<const N: usize>(have: usize) -> MonitorError {
    AraimError::CapacityExceeded {
        have,
        capacity: N.min(super::MAX_SATS),
    }
    .into()
}

fn join<T: Real, M: SatelliteModels + ?Sized, const N: usize>(
    out: &mut [AraimSat<T>; N],
    ism: &Ism,
    models: &M,
    obs: &[LinearObservation],
) -> Result<Ism, MonitorError> {
    if obs.len() > N {
        return Err(capacity::<N>(obs.len()));
    }
    check_prns(obs.iter().map(|o| o.id))?;
    let mut p_const = [None; MAX_SYSTEMS];
    for (i, (o, slot)) in obs.iter().zip(out.iter_mut()).enumerate() {
        let Some(entry) = models.ism(o.id) else {
            return Err(MonitorError::NotInIsm { id: o.id, index: i });
        };
        let j = o.id.system.index();
        if let (Some(dst), Some(src)) = (p_const.get_mut(j), ism.p_const.get(j)) {
            *dst = *src;
        }
        if let Some(s) = o.sigma_m {
            if !(s > 0.0) || !s.is_finite() {
                return Err(RaimError::NonPositiveSigma {
                    index: i,
                    sigma_m: s,
                }
                .into());
            }
        }
        let nominal_m2 = match o.sigma_m {
            Some(s) => s * s,
            None => models
                .curves(o.id)
                .variance_m2(elevation_from_g(&o.los_enu)),
        };
        let (ura, ure) = (entry.sigma_ura_m, entry.sigma_ure_m);
        // The ADD's G row is minus the line of sight.
        *slot = AraimSat {
            id: o.id,
            g_enu: o.los_enu.map(|v| T::of(-v)),
            c_int_m2: T::of(ura * ura + nominal_m2),
            c_acc_m2: T::of(ure * ure + nominal_m2),
            b_nom_m: T::of(entry.b_nom_m),
            p_sat: entry.p_sat,
            residual_m: T::of(o.residual_m),
        };
    }
    Ok(Ism { p_const })
}

#[cfg(test)]
mod lent {
    extern crate std;
    use super::*;
    use crate::measurement::System;
    use std::format;
    use std::string::String;

    /// `n` satellites, G and E alternating, spread in azimuth and elevation,
    /// small residuals plus `fault_m` on each satellite of `faulty`, with
    /// the ISM of ADD v3.0 Appendix D (sigma_URA 0.75 m, sigma_URE 0.5 m,
    /// b_nom 0.5 m, P_sat 1e-5).
    fn sky(
        n: usize,
        faults: &[(usize, f64)],
    ) -> (std::vec::Vec<SatIsm>, std::vec::Vec<LinearObservation>) {
        let (mut ism, mut obs) = (std::vec::Vec::new(), std::vec::Vec::new());
        for i in 0..n {
            let system = if i % 2 == 0 {
                System::Gps
            } else {
                System::Galileo
            };
            let id = SatId::new(system, (i / 2) as u8 + 1);
            let az_deg = (i as f64 * 137.5) % 360.0;
            let el_deg = 10.0 + (i as f64 * 29.0) % 75.0;
            let noise_m = 0.3 * (((i * 7919) % 11) as f64 / 11.0 - 0.5);
            let fault_m: f64 = faults.iter().filter(|f| f.0 == i).map(|f| f.1).sum();
            obs.push(LinearObservation::from_az_el(
                id,
                az_deg.to_radians(),
                el_deg.to_radians(),
                noise_m + fault_m,
            ));
            ism.push(SatIsm {
                id,
                sigma_ura_m: 0.75,
                sigma_ure_m: 0.5,
                b_nom_m: 0.5,
                p_sat: 1e-5,
            });
        }
        (ism, obs)
    }

    /// What an epoch's runs say, every bit (`Debug` of f32/f64 is the
    /// shortest text that reads back to the same bits).
    fn said<T: Real, const N: usize, const K: usize>(
        verdict: &Verdict<N>,
        runs: Runs<'_, T, N, K>,
    ) -> String {
        format!(
            "{verdict:?}\n{:?}\n{:?}\n{:?}\n{:?}",
            runs.all_in_view(),
            runs.after_exclusion(),
            runs.accuracy_sample(),
            runs.satellites()
        )
    }

    /// The epochs of [`a_scratch_new_at_every_epoch_gives_the_same_bits`]
    /// through a `Monitor` (its own scratch, kept across epochs) and a
    /// `MonitorCore` lent a new scratch at every epoch; returns the
    /// decisions seen.
    fn compare<T: Real, const N: usize, const K: usize>() -> std::vec::Vec<Decision> {
        let cfg = AraimConfig::default();
        let p_const = Ism::with(&[System::Gps, System::Galileo], 1e-4);
        let mut owned = std::boxed::Box::new(Monitor::<T, N, K>::new());
        let mut core = std::boxed::Box::<MonitorCore<T, N, K>>::default();
        let mut decisions = std::vec::Vec::new();
        let epochs: [&[(usize, f64)]; 6] = [
            &[],
            &[(0, 100.0)],
            &[(7, -60.0)],
            &[],
            &[(3, 80.0), (12, -90.0)],
            &[(5, 100.0)],
        ];
        for (e, faults) in epochs.iter().enumerate() {
            let (ism, obs) = sky(20, faults);
            let want_verdict = owned
                .linear(&cfg, &p_const, &ism[..], &obs, FdeLimits::UNLIMITED)
                .unwrap();
            let want = said(&want_verdict, owned.runs());
            // The room's part: new whenever another part had the room.
            let mut scratch = std::boxed::Box::<FdeScratch<T, N, K>>::default();
            let (verdict, runs) = core
                .linear(
                    &mut scratch,
                    &cfg,
                    &p_const,
                    &ism[..],
                    &obs,
                    FdeLimits::UNLIMITED,
                )
                .unwrap();
            assert_eq!(said(&verdict, runs), want, "epoch {e}");
            assert_eq!(runs.in_force().pl_add, owned.in_force().pl_add);
            if let Exclusion::Fde(FdeDecision::Excluded { mode, .. }) = verdict.exclusion {
                // Independently: the engine's own run of the subset without
                // the excluded mode, at the exclusion-risk share.
                let (all, sats) = (runs.all_in_view(), runs.satellites());
                let mut engine = std::boxed::Box::new(Araim::<T, N, K>::new());
                let mut other = std::boxed::Box::new(Araim::<T, N, K>::new());
                engine.process(&cfg, &p_const, sats).unwrap();
                assert_eq!(format!("{:?}", engine.output()), format!("{all:?}"));
                let subset = engine
                    .after_excluding(&cfg, &p_const, sats, mode, &mut other)
                    .unwrap()
                    .unwrap();
                assert_eq!(
                    format!("{subset:?}"),
                    format!("{:?}", runs.after_exclusion().unwrap()),
                    "epoch {e}"
                );
            }
            decisions.push(verdict.decision);
        }
        decisions
    }

    /// The FDE's scratch lent by the caller (`MonitorCore`, the STM32F4
    /// stream build's shared room, docs/FLASH.md "STM32F4: the stream"
    /// item 5) and new at every epoch gives every bit of the verdicts and
    /// runs of the monitor that keeps its own across epochs, at the
    /// device's precision and capacities (f32, 24 satellites, 48 modes)
    /// and the host's (f64, 600 modes); an excluded subset's output is the
    /// engine's own run of the subset at the exclusion-risk share.
    ///
    /// Verifies: ARAIM-FDE-SCRATCH
    #[test]
    fn a_scratch_new_at_every_epoch_gives_the_same_bits() {
        for decisions in [compare::<f32, 24, 48>(), compare::<f64, 24, 600>()] {
            assert!(decisions.contains(&Decision::Excluded), "{decisions:?}");
            assert!(decisions.contains(&Decision::Ok), "{decisions:?}");
            assert!(
                decisions
                    .iter()
                    .any(|d| !matches!(d, Decision::Ok | Decision::Excluded)),
                "{decisions:?}"
            );
        }
    }
}
