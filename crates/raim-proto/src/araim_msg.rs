//! ARAIM on the wire (docs/PROTOCOL.md "ARAIM"): the integrity
//! support message (ISM) with the ARAIM configuration, the ARAIM epoch, its
//! result and its typed errors.
//!
//! Each reaches the shared enums through one appended variant
//! (`Command::Araim`, `ResponseBody::Araim`, `WireError::Araim`), so the
//! ARAIM messages can grow here without touching the other variants'
//! indices.
//!
//! The core's types (`raim_core::araim::{AraimConfig, Ism, AraimOutput}`)
//! carry `usize` and no serde derives; the wire forms below mirror them
//! field by field with fixed-width integers, and convert both ways.

use raim_core::araim::{
    AraimConfig, AraimError, AraimOutput, FdeAlarm, FdeDecision, Limits, PlOutput, Unavailable,
};
use raim_core::measurement::MAX_SYSTEMS;
use raim_core::{Decision, LinearObservation, RangeObservation, Real, SatId, System};
use serde::{Deserialize, Serialize};

use crate::error::{FieldName, WireError};
use crate::message::{LinearEpoch, RangeEpoch, SatList};
use crate::CAPACITY;

/// The ISM entry of one satellite (ADD ISM content; SPEC §9.1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IsmSat {
    /// The satellite.
    pub id: SatId,
    /// sigma_URA: the integrity clock-and-ephemeris sigma (m), >= 0.
    pub sigma_ura_m: f64,
    /// sigma_URE: the accuracy (continuity) sigma (m), >= 0.
    pub sigma_ure_m: f64,
    /// b_nom: the maximum nominal bias (m), >= 0.
    pub b_nom_m: f64,
    /// P_sat: the prior probability of a satellite fault, in (0, 1).
    pub p_sat: f64,
}

/// `raim_core::araim::AraimConfig` on the wire, field for field (units and
/// defaults there: LPV-200).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WireAraimConfig {
    /// Vertical integrity budget PHMI_VERT.
    pub phmi_vert: f64,
    /// Horizontal integrity budget PHMI_HOR.
    pub phmi_hor: f64,
    /// Vertical continuity budget P_FA_VERT.
    pub pfa_vert: f64,
    /// Horizontal continuity budget P_FA_HOR.
    pub pfa_hor: f64,
    /// Threshold on the probability of the unmonitored fault modes.
    pub p_thres: f64,
    /// Prior at or above which a mode enters the EMT.
    pub p_emt: f64,
    /// Vertical alert limit, m.
    pub val_m: f64,
    /// Horizontal alert limit, m.
    pub hal_m: f64,
    /// Bracket width of the ADD's PL bisection, m.
    pub tol_pl_m: f64,
    /// Availability limit on the effective monitor threshold, m.
    pub emt_max_m: f64,
    /// Availability limit on sigma_v,acc, m.
    pub sigma_acc_max_m: f64,
    /// The PL that feeds the availability: false = the ADD's bracket
    /// output (default), true = the exact root.
    pub pl_exact: bool,
}

impl From<AraimConfig> for WireAraimConfig {
    fn from(c: AraimConfig) -> Self {
        WireAraimConfig {
            phmi_vert: c.phmi_vert,
            phmi_hor: c.phmi_hor,
            pfa_vert: c.pfa_vert,
            pfa_hor: c.pfa_hor,
            p_thres: c.p_thres,
            p_emt: c.p_emt,
            val_m: c.val_m,
            hal_m: c.hal_m,
            tol_pl_m: c.tol_pl_m,
            emt_max_m: c.emt_max_m,
            sigma_acc_max_m: c.sigma_acc_max_m,
            pl_exact: c.pl_output == PlOutput::Exact,
        }
    }
}

impl From<WireAraimConfig> for AraimConfig {
    fn from(c: WireAraimConfig) -> Self {
        AraimConfig {
            phmi_vert: c.phmi_vert,
            phmi_hor: c.phmi_hor,
            pfa_vert: c.pfa_vert,
            pfa_hor: c.pfa_hor,
            p_thres: c.p_thres,
            p_emt: c.p_emt,
            val_m: c.val_m,
            hal_m: c.hal_m,
            tol_pl_m: c.tol_pl_m,
            emt_max_m: c.emt_max_m,
            sigma_acc_max_m: c.sigma_acc_max_m,
            pl_output: if c.pl_exact {
                PlOutput::Exact
            } else {
                PlOutput::AddBracket
            },
        }
    }
}

impl Default for WireAraimConfig {
    fn default() -> Self {
        AraimConfig::default().into()
    }
}

/// An ISM frame: the ARAIM configuration, P_const per constellation
/// (indexed by `System::index()`; `None` = constellation not in use) and
/// the per-satellite entries (up to [`CAPACITY`]). It replaces the ISM in
/// force as a whole, or not at all.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IsmFrame {
    /// The ARAIM allocation and alert limits.
    pub config: WireAraimConfig,
    /// P_const per constellation (`System::index()`), `None` when not in use.
    pub p_const: [Option<f64>; MAX_SYSTEMS],
    /// The per-satellite ISM entries.
    pub sats: SatList<IsmSat>,
}

/// The host's borrowed form of [`IsmFrame`] (same bytes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IsmFrameRef<'a> {
    /// The ARAIM allocation and alert limits.
    pub config: WireAraimConfig,
    /// P_const per constellation (`System::index()`), `None` when not in use.
    pub p_const: [Option<f64>; MAX_SYSTEMS],
    /// The per-satellite ISM entries.
    pub sats: &'a [IsmSat],
}

/// The payload of `Command::Araim`. Without a heap the frames cannot be
/// boxed; only one request exists at a time.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum AraimCommand {
    /// Replace the ISM and ARAIM configuration in force. Answered
    /// `AraimAnswer::IsmAccepted` or a typed error (the previous ISM stays).
    Ism(IsmFrame),
    /// One linearised epoch through ARAIM (and its FDE after a detection).
    /// Answered `AraimAnswer::Result` or a typed error.
    Epoch(LinearEpoch),
    /// One pseudorange epoch (the unit's normal input, as `Command::Ranges`)
    /// through ARAIM (protocol 8): the unit linearises it at its
    /// all-in-view Gauss-Newton solution (ranges and residuals in f64),
    /// takes the lines of sight and elevations there, C_int/C_acc from the
    /// ISM and the ADD elevation model, and runs ARAIM and FDE as for
    /// `Epoch`. Answered `AraimAnswer::Result` with `position_ecef_m`, or a
    /// typed error (the snapshot solver's for bad ranges).
    Ranges(RangeEpoch),
}

/// The host's borrowed form of [`AraimCommand`] (same bytes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum AraimCommandRef<'a> {
    /// [`AraimCommand::Ism`].
    Ism(IsmFrameRef<'a>),
    /// [`AraimCommand::Epoch`], its fields inline.
    Epoch {
        /// Epoch time, s.
        time_s: f64,
        /// The linearised rows.
        sats: &'a [LinearObservation],
    },
    /// [`AraimCommand::Ranges`], its fields inline.
    Ranges {
        /// Epoch time, s.
        time_s: f64,
        /// Where Gauss-Newton starts, ECEF m.
        apriori_m: Option<[f64; 3]>,
        /// The pseudoranges and satellite positions.
        sats: &'a [RangeObservation],
    },
}

/// Why an epoch gives no ARAIM service (`raim_core::araim::Unavailable`
/// with fixed-width integers).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum WireUnavailable {
    /// The mode list does not fit.
    ModeCapacity {
        /// Modes the epoch needs.
        needed: u32,
        /// Modes the engine holds.
        capacity: u32,
    },
    /// P(more faults) cannot reach P_THRES within `MAX_EVENTS`.
    TooManyEvents {
        /// P(more than `MAX_EVENTS` events).
        p_exceed_at_max: f64,
    },
    /// The unmonitored probability exceeds P_THRES.
    Unmonitored {
        /// The unmonitored probability.
        p_unmon: f64,
        /// P_THRES.
        p_thres: f64,
    },
    /// The PL equation of an axis could not be bracketed.
    PlNotSolved {
        /// The axis (0 E, 1 N, 2 U).
        axis: u32,
    },
    /// One or more availability limits fails (see `WireLimits`).
    Limits,
}

fn u32_of(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

impl From<Unavailable> for WireUnavailable {
    fn from(u: Unavailable) -> Self {
        match u {
            Unavailable::ModeCapacity { needed, capacity } => WireUnavailable::ModeCapacity {
                needed: u32_of(needed),
                capacity: u32_of(capacity),
            },
            Unavailable::TooManyEvents { p_exceed_at_max } => {
                WireUnavailable::TooManyEvents { p_exceed_at_max }
            }
            Unavailable::Unmonitored { p_unmon, p_thres } => {
                WireUnavailable::Unmonitored { p_unmon, p_thres }
            }
            Unavailable::PlNotSolved { axis } => {
                WireUnavailable::PlNotSolved { axis: u32_of(axis) }
            }
            Unavailable::Limits => WireUnavailable::Limits,
        }
    }
}

/// The availability limits, each true when met (`araim::Limits`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct WireLimits {
    /// VPL <= VAL.
    pub vpl: bool,
    /// HPL <= HAL.
    pub hpl: bool,
    /// EMT <= EMT_max.
    pub emt: bool,
    /// sigma_v,acc <= its maximum.
    pub sigma_acc: bool,
}

impl From<Limits> for WireLimits {
    fn from(l: Limits) -> Self {
        WireLimits {
            vpl: l.vpl,
            hpl: l.hpl,
            emt: l.emt,
            sigma_acc: l.sigma_acc,
        }
    }
}

/// What one ARAIM run (all in view, or the subset left after an
/// exclusion) produced. Lengths in metres; probabilities as numbers.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct AraimSummary {
    /// Fault modes enumerated, and those solved and tested.
    pub modes: u32,
    /// Fault modes solved and tested.
    pub monitored: u32,
    /// N_fault,max.
    pub max_faults: u32,
    /// Unmonitored probability (beyond N_fault,max + unmonitorable modes).
    pub p_unmon: f64,
    /// The PLs that feed the availability (the configured `pl_exact`
    /// choice: ADD bracket output or exact root).
    pub vpl_m: f64,
    /// Horizontal PL feeding the availability, m.
    pub hpl_m: f64,
    /// The exact roots of the PL equations.
    pub vpl_exact_m: f64,
    /// Exact horizontal PL root, m.
    pub hpl_exact_m: f64,
    /// Effective monitor threshold (vertical).
    pub emt_m: f64,
    /// sigma_v,acc.
    pub sigma_v_acc_m: f64,
    /// Every monitored mode passed its solution-separation test.
    pub detection_passed: bool,
    /// Which availability limits are met.
    pub limits: WireLimits,
    /// `None` when ARAIM service is available.
    pub unavailable: Option<WireUnavailable>,
}

impl AraimSummary {
    /// The summary of a core ARAIM output; `pl_exact` picks the exact roots for `vpl_m`/`hpl_m`.
    pub fn from_output<T: Real, const K: usize>(out: &AraimOutput<T, K>, pl_exact: bool) -> Self {
        let pl = if pl_exact { out.pl_exact } else { out.pl_add };
        AraimSummary {
            modes: u32_of(out.modes.len()),
            monitored: u32_of(out.n_monitored),
            max_faults: u32_of(out.max_faults),
            p_unmon: out.p_unmon,
            vpl_m: pl.vpl_m,
            hpl_m: pl.hpl_m,
            vpl_exact_m: out.pl_exact.vpl_m,
            hpl_exact_m: out.pl_exact.hpl_m,
            emt_m: out.emt_m.to_f64(),
            sigma_v_acc_m: out.sigma_v_acc_m.to_f64(),
            detection_passed: out.detection_passed,
            limits: out.limits.into(),
            unavailable: out.unavailable.map(Into::into),
        }
    }

    /// Service available: no structural cause and every limit met.
    pub fn available(&self) -> bool {
        self.unavailable.is_none()
    }
}

/// The FDE outcome (`raim_core::araim::FdeDecision`); mode indices are
/// into the all-in-view mode list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum WireFde {
    /// The all-in-view test passed: nothing to exclude.
    NoFault,
    /// A mode was excluded.
    Excluded {
        /// Index of the excluded mode.
        mode: u32,
        /// Excluded constellations, bit c = constellation index c.
        consts: u8,
    },
    /// No candidate subset (single-event, then multi-event) passes all
    /// its own tests.
    NoCandidate,
    /// Two consistent candidates that do not nest: never a silent pick.
    Ambiguous {
        /// The first candidate's mode index.
        first: u32,
        /// The second candidate's mode index.
        second: u32,
    },
    /// The fault modes could not be enumerated (`ModeCapacity`,
    /// `TooManyEvents`): no test was run, the epoch is `Unavailable`.
    NotTested,
    /// The test failed with more monitored modes than the device attempts
    /// exclusion for (`server::araim::MAX_FDE_MODES`); the epoch is an
    /// `Alarm`. Kept for a build with a limit below the mode capacity: the
    /// firmware's limit equals it (600), so there every failed test with
    /// enumerated modes gets an exclusion attempt.
    NotAttempted {
        /// Fault modes enumerated.
        modes: u32,
    },
    /// The exclusion search would process more candidate subsets than the
    /// device's work budget allows (`server::araim::FDE_WORK_BUDGET`,
    /// kept within the watchdog period): `candidates` through the stage
    /// not started, `budget` the maximum for this epoch's mode count.
    /// Nothing excluded; the epoch is an `Alarm`. (Appended: protocol 8.)
    BudgetExceeded {
        /// Candidates through the stage not started.
        candidates: u32,
        /// The maximum for this epoch's mode count.
        budget: u32,
    },
}

impl From<FdeDecision> for WireFde {
    fn from(d: FdeDecision) -> Self {
        match d {
            FdeDecision::NoFault => WireFde::NoFault,
            FdeDecision::Excluded { mode, consts, .. } => WireFde::Excluded {
                mode: u32_of(mode),
                consts,
            },
            FdeDecision::Alarm(FdeAlarm::NoCandidate) => WireFde::NoCandidate,
            FdeDecision::Alarm(FdeAlarm::Ambiguous { first, second }) => WireFde::Ambiguous {
                first: u32_of(first),
                second: u32_of(second),
            },
            FdeDecision::Alarm(FdeAlarm::BudgetExceeded { candidates, budget }) => {
                WireFde::BudgetExceeded {
                    candidates: u32_of(candidates),
                    budget: u32_of(budget),
                }
            }
        }
    }
}

/// One ARAIM epoch's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WireAraimResult {
    /// Epoch time, s.
    pub time_s: f64,
    /// The verdict for a user of the position: `Ok` (consistent,
    /// available), `Unavailable` (consistent or excluded, service not
    /// available), `Excluded` (a fault excluded and the subset available),
    /// `Alarm` (a test failed and nothing could be excluded).
    pub decision: Decision,
    /// The all-in-view ARAIM run.
    pub all_in_view: AraimSummary,
    /// The FDE outcome.
    pub fde: WireFde,
    /// The satellites excluded (those of an excluded constellation
    /// included), in epoch order; empty unless `fde` is `Excluded`.
    pub excluded: heapless::Vec<SatId, CAPACITY>,
    /// The subset's own ARAIM after an exclusion (its PLs are those in
    /// force); `None` otherwise.
    pub after_exclusion: Option<AraimSummary>,
    /// Seed 003's effective sample quantity N* = P_Sigma / P_max on the
    /// vertical axis of the all-in-view run, at the PL the result reports
    /// (`raim_core::araim::esq::effective_samples`, SPEC §9.2; docs/ESQ.md);
    /// `None` when it is undefined (no PL, modes not enumerated). The host
    /// divides its window by it for dT_e.
    pub n_star_vertical: Option<f64>,
    /// The ECEF position in force (m) for a pseudorange epoch
    /// (`AraimCommand::Ranges`): the linearisation point plus the ARAIM
    /// solution's correction, the subset's after an exclusion, the
    /// all-in-view one otherwise (also when the verdict is `Alarm` or
    /// `Unavailable`: the verdict says whether it may be used). `None` for
    /// a linearised epoch (no ECEF point) (protocol 8).
    pub position_ecef_m: Option<[f64; 3]>,
}

impl WireAraimResult {
    /// The summary in force: the subset's after an exclusion, else the
    /// all-in-view one.
    pub fn in_force(&self) -> &AraimSummary {
        self.after_exclusion.as_ref().unwrap_or(&self.all_in_view)
    }

    /// The wire form of an ARAIM monitor's epoch (`Monitor::epoch`'s
    /// verdict and its runs, `Monitor::runs`, or those `MonitorCore::epoch`
    /// returns with it), in either precision: the device's
    /// server and the host's replay build their answers here, so both
    /// say the same thing of the same run. The PLs reported are the
    /// configured `pl_output`'s; N* is seed 003's vertical effective sample
    /// quantity at that PL (SPEC §9.2), for an epoch whose FDE ran.
    /// `TooManySatellites` when the verdict excludes more satellites than
    /// the wire carries (an engine larger than `CAPACITY`).
    pub fn from_verdict<T: Real, const N: usize, const K: usize>(
        runs: raim_core::araim::Runs<'_, T, N, K>,
        verdict: &raim_core::araim::Verdict<N>,
        cfg: &AraimConfig,
        time_s: f64,
    ) -> Result<Self, WireError> {
        use raim_core::araim::Exclusion;
        let pl_exact = cfg.pl_output == PlOutput::Exact;
        let out = runs.all_in_view();
        let (fde, n_star_vertical) = match verdict.exclusion {
            Exclusion::NotTested => (WireFde::NotTested, None),
            Exclusion::NotAttempted { monitored } => (
                WireFde::NotAttempted {
                    modes: u32::try_from(monitored).unwrap_or(u32::MAX),
                },
                None,
            ),
            Exclusion::Fde(d) => (
                d.into(),
                raim_core::araim::esq::effective_samples(out, 2, cfg.pl_output)
                    .ok()
                    .map(|e| e.n_star),
            ),
        };
        let mut excluded = heapless::Vec::new();
        for id in verdict.excluded.iter() {
            excluded
                .push(*id)
                .map_err(|_| WireError::TooManySatellites {
                    have: u32::try_from(verdict.excluded.len()).unwrap_or(u32::MAX),
                    capacity: CAPACITY as u32,
                })?;
        }
        Ok(WireAraimResult {
            time_s,
            decision: verdict.decision,
            all_in_view: AraimSummary::from_output(out, pl_exact),
            fde,
            excluded,
            after_exclusion: runs
                .after_exclusion()
                .map(|o| AraimSummary::from_output(o, pl_exact)),
            n_star_vertical,
            position_ecef_m: verdict.position_ecef_m,
        })
    }
}

/// The payload of `ResponseBody::Araim` (unboxed, as `ResponseBody`).
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum AraimAnswer {
    /// The ISM frame was taken; `satellites` entries are in force. The
    /// response's `config.crc32` now covers it (docs/PROTOCOL.md).
    IsmAccepted {
        /// ISM entries in force.
        satellites: u32,
    },
    /// The epoch's result.
    Result(WireAraimResult),
}

/// ARAIM's own typed refusals (the payload of `WireError::Araim`). The
/// errors ARAIM shares with the snapshot monitor (NaN, duplicate,
/// capacity, too few, rank) use the existing `WireError` variants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum AraimWireError {
    /// This build has no ARAIM engine (a firmware built without the
    /// `araim` feature).
    Disabled,
    /// An ARAIM epoch before any ISM was accepted since reset.
    NoIsm,
    /// A satellite of the epoch (`index`) has no entry in the ISM in force.
    NotInIsm {
        /// The satellite.
        id: SatId,
        /// Its index in the epoch.
        index: u32,
    },
    /// An ISM field out of its range (`index`: satellite or constellation
    /// index, 0 for configuration fields). Probabilities are in the open
    /// (0, 1).
    OutOfRange {
        /// Name of the offending field.
        field: FieldName,
        /// Satellite (or constellation) index, 0 for configuration fields.
        index: u32,
        /// The value received (in the field's unit).
        value: f64,
        /// Smallest value accepted.
        min: f64,
        /// Largest value accepted.
        max: f64,
    },
    /// The ISM declares P_const for a constellation with no satellite entry.
    EmptyConstellation {
        /// The constellation.
        system: System,
    },
    /// A satellite (`index`) of a constellation without P_const.
    MissingConstellationIsm {
        /// The constellation.
        system: System,
        /// Index of the satellite in the epoch.
        index: u32,
    },
    /// An ISM frame with no satellite entry: it would put in force an ISM
    /// under which every ARAIM epoch is refused, and answer
    /// `IsmAccepted { 0 }` as if a usable one had been taken (issue 35).
    /// Protocol 14.
    EmptyIsm,
}

impl core::fmt::Display for AraimWireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            AraimWireError::Disabled => write!(f, "this build has no ARAIM engine"),
            AraimWireError::NoIsm => write!(f, "ARAIM epoch before any ISM"),
            AraimWireError::NotInIsm { id, index } => {
                write!(f, "satellite {id} at index {index} has no ISM entry")
            }
            AraimWireError::OutOfRange {
                field,
                index,
                value,
                min,
                max,
            } => write!(
                f,
                "ISM {field} at index {index} is {value}, outside [{min}, {max}]"
            ),
            AraimWireError::EmptyConstellation { system } => write!(
                f,
                "the ISM gives P_const for {} but no satellite of it",
                system.letter()
            ),
            AraimWireError::MissingConstellationIsm { system, index } => write!(
                f,
                "satellite at index {index} is of {}, which has no P_const",
                system.letter()
            ),
            AraimWireError::EmptyIsm => write!(f, "the ISM has no satellite entry"),
        }
    }
}

impl core::error::Error for AraimWireError {}

pub(crate) fn field(name: &str) -> FieldName {
    let mut s = FieldName::new();
    for c in name.chars() {
        if s.push(c).is_err() {
            break;
        }
    }
    s
}

impl From<AraimError> for WireError {
    fn from(e: AraimError) -> Self {
        match e {
            AraimError::NotFinite {
                field: f,
                index,
                value,
            } => WireError::NonFinite {
                field: field(f),
                index: u32_of(index),
                value,
            },
            AraimError::OutOfRange {
                field: f,
                index,
                value,
                min,
                max,
            } => WireError::Araim(AraimWireError::OutOfRange {
                field: field(f),
                index: u32_of(index),
                value,
                min,
                max,
            }),
            AraimError::DuplicateSatellite {
                system,
                prn,
                first,
                second,
            } => WireError::DuplicateSatellite {
                id: SatId::new(system, prn),
                first: u32_of(first),
                second: u32_of(second),
            },
            AraimError::CapacityExceeded { have, capacity } => WireError::TooManySatellites {
                have: u32_of(have),
                capacity: u32_of(capacity),
            },
            AraimError::EmptyConstellation { system } => {
                WireError::Araim(AraimWireError::EmptyConstellation { system })
            }
            AraimError::MissingConstellationIsm { system, index } => {
                WireError::Araim(AraimWireError::MissingConstellationIsm {
                    system,
                    index: u32_of(index),
                })
            }
            AraimError::TooFewSatellites { have, need } => WireError::TooFewSatellites {
                have: u32_of(have),
                need: u32_of(need),
            },
            AraimError::RankDeficient { column, pivot } => WireError::DegenerateGeometry {
                column: u32_of(column),
                pivot,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::message::{CommandRef, Request, RequestRef};

    fn ism_sats(n: u8) -> std::vec::Vec<IsmSat> {
        (1..=n)
            .map(|prn| IsmSat {
                id: SatId::new(System::Gps, prn),
                sigma_ura_m: 0.75,
                sigma_ure_m: 0.5,
                b_nom_m: 0.5,
                p_sat: 1e-5,
            })
            .collect()
    }

    /// The borrowed and owned forms encode alike, and the configuration
    /// converts to the core's and back unchanged.
    #[test]
    fn borrowed_and_owned_araim_requests_encode_alike() {
        let sats = ism_sats(4);
        let mut p_const = [None; MAX_SYSTEMS];
        p_const[System::Gps.index()] = Some(1e-4);
        let config = WireAraimConfig {
            pl_exact: true,
            val_m: 50.0,
            ..WireAraimConfig::default()
        };
        assert_eq!(WireAraimConfig::from(AraimConfig::from(config)), config);
        let owned = Request {
            seq: 7,
            command: crate::Command::Araim(AraimCommand::Ism(IsmFrame {
                config,
                p_const,
                sats: SatList {
                    items: sats.iter().copied().collect(),
                    declared: 4,
                },
            })),
        };
        let borrowed = RequestRef {
            seq: 7,
            command: CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
                config,
                p_const,
                sats: &sats,
            })),
        };
        let (mut buf_a, mut buf_b) = ([0u8; 512], [0u8; 512]);
        let a = postcard::to_slice(&owned, &mut buf_a).unwrap();
        let b = postcard::to_slice(&borrowed, &mut buf_b).unwrap();
        assert_eq!(a, b);
        assert_eq!(postcard::from_bytes::<Request>(a).unwrap(), owned);
    }

    /// An (authenticated) ISM frame at the capacity fits the receive buffer.
    #[test]
    fn largest_ism_frame_fits() {
        let sats = ism_sats(CAPACITY as u8);
        let req = RequestRef {
            seq: u32::MAX,
            command: CommandRef::Authenticated(crate::auth::AuthenticatedRef {
                counter: u64::MAX,
                change: crate::auth::ChangeRef::Ism(IsmFrameRef {
                    config: WireAraimConfig {
                        pl_exact: true,
                        ..WireAraimConfig::default()
                    },
                    p_const: [Some(0.5); MAX_SYSTEMS],
                    sats: &sats,
                }),
                tag: [0xFF; 32],
            }),
        };
        let mut scratch = [0u8; 4 * crate::MAX_REQUEST_FRAME];
        let mut out = [0u8; 4 * crate::MAX_REQUEST_FRAME];
        let f = crate::frame::encode(&req, &mut scratch, &mut out).unwrap();
        assert!(f.len() <= crate::MAX_REQUEST_FRAME, "{}", f.len());
    }
}
