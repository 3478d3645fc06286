//! `raim replay --araim`: ARAIM (docs/ARAIM.md) on the replay's
//! corrected pseudoranges, with the same fault injection plus the
//! constellation-wide fault of `raim_gnss::faults::constellation_bias`.
//!
//! Per epoch, the core's ARAIM monitor (`raim_core::araim::Monitor`) on
//! the pseudoranges: linearised at the all-in-view Gauss-Newton solution,
//! the ADD elevation curves for C_int/C_acc (each satellite's iono-free
//! pair and the residual ionosphere, `ReplayModels`), the command's ISM,
//! the ARAIM output, FDE after a detection; then the protection levels of
//! the position actually output (all in view, or the excluded subset's
//! with the exclusion's added risk), and the position error against the
//! reference.
//! Text or JSON lines, a summary, and a plot (PLs and EMT over time against
//! VAL/HAL, the vertical and horizontal Stanford diagrams).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use plotters::prelude::*;
use raim_core::araim::{
    AraimConfig, Curves, FdeLimits, Ism, Monitor, MonitorError, SatIsm, SatelliteModels,
};
use raim_core::frames::{ecef_to_geodetic, enu_rotation, unrotate};
use raim_core::{Config, Decision, Epoch, RangeObservation, SatId, System};
use raim_gnss::faults::{constellation_bias, FaultPlan};
use raim_gnss::ranging::PreparedEpoch;
use raim_proto::araim_msg::{
    AraimAnswer, AraimCommandRef, IsmFrameRef, IsmSat, WireAraimConfig, WireAraimResult, WireFde,
    WireUnavailable,
};
use raim_proto::message::{CommandRef, ResponseBody};
use raim_proto::result::WireResult;
use raim_qemu::QemuSession;
use serde::Serialize;

use super::{checked_fault_plan, prepare, record::error_enu, NmeaMode, ReplayArgs, Target};

/// Satellites per epoch (ESBC G+E+C at a 10 degree mask has up to ~30).
pub const ARAIM_SATS: usize = super::REPLAY_CAPACITY;
/// Fault modes per epoch (G+E+C with pairs: about 700).
pub const ARAIM_MODES: usize = 4096;

pub(super) type Engine = Monitor<f64, ARAIM_SATS, ARAIM_MODES>;

#[derive(Debug, Clone, Args)]
pub struct AraimReplayArgs {
    /// Run ARAIM (Advanced RAIM, docs/ARAIM.md) instead of the snapshot monitor, with the ADD elevation model for C_int and C_acc.
    #[arg(long)]
    pub araim: bool,
    /// ARAIM: sigma_URA for every satellite, m.
    #[arg(long, default_value_t = 0.75)]
    pub araim_ura_m: f64,
    /// ARAIM: sigma_URE for every satellite, m.
    #[arg(long, default_value_t = 0.5)]
    pub araim_ure_m: f64,
    /// ARAIM: b_nom for every satellite, m.
    #[arg(long, default_value_t = 0.5)]
    pub araim_b_nom_m: f64,
    /// ARAIM: P_sat for every satellite.
    #[arg(long, default_value = "1e-5")]
    pub araim_p_sat: f64,
    /// ARAIM: P_const, for every constellation (P) or one (SYS=P, e.g. G=1e-8); repeatable; default 1e-4.
    #[arg(long = "araim-p-const", value_name = "[SYS=]P")]
    pub araim_p_const: Vec<String>,
    /// ARAIM: residual ionosphere of single-frequency data, vertical sigma in m, times the obliquity, added to C_int and C_acc (0: the ADD's dual-frequency model alone).
    #[arg(long, default_value_t = 0.0)]
    pub araim_iono_m: f64,
    /// ARAIM: a constellation-wide fault, SYS:COMMON_M:E_M,N_M,U_M@START[..END]: a common range error plus the range change of a shift (E, N, U) of that constellation's solution (docs/ARAIM.md); repeatable.
    #[arg(long = "araim-const-fault", value_name = "SPEC", allow_hyphen_values = true, help_heading = super::heading::FAULTS)]
    pub araim_const_faults: Vec<String>,
    /// ARAIM: VPL, HPL and EMT over time against VAL/HAL, and the vertical and horizontal Stanford diagrams, into this PNG.
    #[arg(long, value_name = "FILE", help_heading = super::heading::PLOTS)]
    pub araim_plot: Option<PathBuf>,
}

/// A parsed `--araim-const-fault`.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstFault {
    pub system: System,
    pub common_m: f64,
    pub shift_enu_m: [f64; 3],
    pub start_gps_s: f64,
    pub end_gps_s: Option<f64>,
}

impl ConstFault {
    pub fn parse(spec: &str, first_gps_s: f64) -> Result<Self> {
        let bad = || {
            anyhow!("--araim-const-fault {spec}: expected SYS:COMMON_M:E_M,N_M,U_M@START[..END]")
        };
        let (body, when) = spec.split_once('@').ok_or_else(bad)?;
        let (s, e) = match when.split_once("..") {
            Some((s, e)) => (s, Some(e)),
            None => (when, None),
        };
        let start_gps_s = raim_gnss::time::resolve(s, first_gps_s)?;
        let end_gps_s = e
            .map(|e| raim_gnss::time::resolve(e, first_gps_s))
            .transpose()?;
        let parts: Vec<&str> = body.split(':').collect();
        let [sys, common, shift] = parts.as_slice() else {
            return Err(bad());
        };
        let system = raim_gnss::parse_system(sys.chars().next().ok_or_else(bad)?)?;
        let num = |t: &str| -> Result<f64> {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(bad)
        };
        let common_m = num(common)?;
        let v: Vec<f64> = shift.split(',').map(num).collect::<Result<_>>()?;
        let [e_m, n_m, u_m] = v.as_slice() else {
            return Err(bad());
        };
        Ok(Self {
            system,
            common_m,
            shift_enu_m: [*e_m, *n_m, *u_m],
            start_gps_s,
            end_gps_s,
        })
    }

    fn active(&self, t: f64) -> bool {
        t >= self.start_gps_s && self.end_gps_s.is_none_or(|e| t < e)
    }
}

impl AraimReplayArgs {
    /// The ISM for the systems of the run.
    pub fn ism(&self, systems: &[System]) -> Result<Ism> {
        let mut all = 1e-4;
        let mut per: Vec<(System, f64)> = Vec::new();
        for s in &self.araim_p_const {
            match s.split_once('=') {
                Some((sys, p)) => {
                    let sys = raim_gnss::parse_system(sys.chars().next().unwrap_or(' '))?;
                    per.push((
                        sys,
                        p.parse().with_context(|| format!("--araim-p-const {s}"))?,
                    ));
                }
                None => all = s.parse().with_context(|| format!("--araim-p-const {s}"))?,
            }
        }
        let mut ism = Ism::with(systems, all);
        for (sys, p) in per {
            if let Some(slot) = ism.p_const.get_mut(sys.index()) {
                *slot = Some(p);
            }
        }
        ism.validate().map_err(|e| anyhow!("ISM: {e}"))?;
        Ok(ism)
    }
}

/// One epoch of an ARAIM replay.
#[derive(Debug, Clone, Serialize, Default)]
pub struct AraimRecord {
    pub time_gps_s: f64,
    pub sats: usize,
    /// Injected faults, `SAT:BIAS_M`.
    pub faulted: Vec<String>,
    pub modes: usize,
    pub monitored: usize,
    pub max_faults: usize,
    pub p_unmon: f64,
    /// All in view: ADD bracket outputs and exact roots, EMT, sigma_v,acc.
    pub vpl_all_m: f64,
    pub hpl_all_m: f64,
    pub vpl_all_exact_m: f64,
    pub hpl_all_exact_m: f64,
    pub emt_m: f64,
    pub sigma_v_acc_m: f64,
    pub detection_passed: bool,
    /// `no_fault`, `excluded`, `alarm_ambiguous`, `alarm_no_candidate`,
    /// `alarm_budget_exceeded`, `alarm_not_attempted`, or `not_tested`
    /// (the fault modes did not fit: no test, unavailable).
    pub fde: String,
    pub excluded: Vec<String>,
    /// The protection levels of the position output (all in view, or the
    /// excluded subset's, with the exclusion risk); None on an alarm.
    pub vpl_m: Option<f64>,
    pub hpl_m: Option<f64>,
    /// ARAIM service for the position output (false on an alarm).
    pub available: bool,
    pub unavailable: Option<String>,
    /// The position output's error against the reference (ENU, m); on an
    /// alarm, the all-in-view position's.
    pub error_enu_m: Option<[f64; 3]>,
    pub error_h_m: Option<f64>,
    pub error_v_m: Option<f64>,
    /// `correct` (every faulted satellite excluded) or `wrong`.
    pub exclusion: Option<String>,
    pub error: Option<String>,
    #[serde(skip)]
    pub position_ecef_m: Option<[f64; 3]>,
    /// The epoch's NMEA sentences (without CRLF): the firmware's own under
    /// QEMU, the same writer on the host.
    #[serde(skip)]
    pub nmea: Vec<String>,
}

impl AraimRecord {
    fn output_pls(&self) -> Option<(f64, f64)> {
        Some((self.vpl_m?, self.hpl_m?))
    }

    pub fn text_line(&self) -> String {
        let t = raim_gnss::time::time_of_day(self.time_gps_s);
        if let Some(e) = &self.error {
            return format!("{t} error {e}");
        }
        let pl = match self.output_pls() {
            Some((v, h)) => format!("VPL {v:7.2} HPL {h:7.2}"),
            None => "VPL     --- HPL     ---".to_string(),
        };
        let err = match (self.error_v_m, self.error_h_m) {
            (Some(v), Some(h)) => format!("err V {v:5.2} H {h:5.2}"),
            _ => "err ---".to_string(),
        };
        format!(
            "{t} n {:2} modes {:4} {pl} EMT {:6.2} {err} {} {}{}",
            self.sats,
            self.modes,
            self.emt_m,
            if self.available { "avail" } else { "unavail" },
            self.fde,
            if self.excluded.is_empty() {
                String::new()
            } else {
                format!(" {}", self.excluded.join("+"))
            },
        )
    }
}

/// The run's numbers (docs/ARAIM.md tables).
#[derive(Debug, Clone, Serialize, Default)]
pub struct AraimSummary {
    pub epochs: usize,
    pub errors: usize,
    pub available: usize,
    pub availability_pct: f64,
    pub alarms: usize,
    pub exclusions: usize,
    pub correct_exclusions: usize,
    pub wrong_exclusions: usize,
    pub faulted_epochs: usize,
    /// Faulted epochs with a failed all-in-view test.
    pub faulted_detected: usize,
    /// Fault-free epochs with a failed all-in-view test.
    pub false_detections: usize,
    pub max_modes: usize,
    pub mean_vpl_m: f64,
    pub max_vpl_m: f64,
    pub mean_hpl_m: f64,
    pub max_hpl_m: f64,
    pub max_emt_m: f64,
    pub max_error_v_m: f64,
    pub max_error_h_m: f64,
    /// max over epochs with a position output of error / PL.
    pub max_ratio_v: f64,
    pub max_ratio_h: f64,
    /// Epochs with a position output whose error exceeds its PL.
    pub error_above_pl: usize,
    /// ... of which declared available (misleading information).
    pub misleading: usize,
}

impl AraimSummary {
    pub fn table(&self) -> String {
        format!(
            "| epochs | available | alarms | exclusions (correct/wrong) | faulted (detected) | false detections | max modes | VPL mean/max | HPL mean/max | EMT max | error V/H max | error/PL V/H max | error > PL | MI |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n\
             | {} | {} ({:.1} %) | {} | {} ({}/{}) | {} ({}) | {} | {} | {:.2}/{:.2} m | {:.2}/{:.2} m | {:.2} m | {:.2}/{:.2} m | {:.3}/{:.3} | {} | {} |",
            self.epochs,
            self.available,
            self.availability_pct,
            self.alarms,
            self.exclusions,
            self.correct_exclusions,
            self.wrong_exclusions,
            self.faulted_epochs,
            self.faulted_detected,
            self.false_detections,
            self.max_modes,
            self.mean_vpl_m,
            self.max_vpl_m,
            self.mean_hpl_m,
            self.max_hpl_m,
            self.max_emt_m,
            self.max_error_v_m,
            self.max_error_h_m,
            self.max_ratio_v,
            self.max_ratio_h,
            self.error_above_pl,
            self.misleading,
        )
    }
}

pub fn summarise(recs: &[AraimRecord]) -> AraimSummary {
    let mut s = AraimSummary {
        epochs: recs.len(),
        ..AraimSummary::default()
    };
    let (mut sum_v, mut sum_h, mut n_pl) = (0.0, 0.0, 0usize);
    for r in recs {
        if r.error.is_some() {
            s.errors += 1;
            continue;
        }
        s.available += r.available as usize;
        s.max_modes = s.max_modes.max(r.modes);
        s.max_emt_m = s.max_emt_m.max(r.emt_m);
        match r.fde.as_str() {
            "excluded" => s.exclusions += 1,
            // No test ran (the modes did not fit): unavailable, no alarm.
            "no_fault" | "not_tested" => {}
            _ => s.alarms += 1,
        }
        match r.exclusion.as_deref() {
            Some("correct") => s.correct_exclusions += 1,
            Some("wrong") => s.wrong_exclusions += 1,
            _ => {}
        }
        if r.faulted.is_empty() {
            s.false_detections += !r.detection_passed as usize;
        } else {
            s.faulted_epochs += 1;
            s.faulted_detected += !r.detection_passed as usize;
        }
        let (Some(ev), Some(eh)) = (r.error_v_m, r.error_h_m) else {
            continue;
        };
        let Some((vpl, hpl)) = r.output_pls() else {
            continue;
        };
        if !(vpl.is_finite() && hpl.is_finite()) {
            continue;
        }
        sum_v += vpl;
        sum_h += hpl;
        n_pl += 1;
        s.max_vpl_m = s.max_vpl_m.max(vpl);
        s.max_hpl_m = s.max_hpl_m.max(hpl);
        s.max_error_v_m = s.max_error_v_m.max(ev);
        s.max_error_h_m = s.max_error_h_m.max(eh);
        s.max_ratio_v = s.max_ratio_v.max(ev / vpl);
        s.max_ratio_h = s.max_ratio_h.max(eh / hpl);
        if ev > vpl || eh > hpl {
            s.error_above_pl += 1;
            s.misleading += r.available as usize;
        }
    }
    if n_pl > 0 {
        s.mean_vpl_m = sum_v / n_pl as f64;
        s.mean_hpl_m = sum_h / n_pl as f64;
    }
    if s.epochs > 0 {
        s.availability_pct = 100.0 * s.available as f64 / s.epochs as f64;
    }
    s
}

/// The replay's satellite models: the command's ISM entries, the same for
/// every satellite, and each satellite's curves: the ADD's, with the
/// airborne term through its iono-free pair's noise factor when it is
/// ranged with one (L1/L2: 2.98, B1I/B3I: 3.53; a single code or an
/// L1/L5-type pair: the ADD's 2.59, docs/ARAIM.md "Iono-free replay"),
/// plus the residual ionosphere of `--araim-iono-m`
/// (`raim_nav::ranging::araim_curves`, the rule the unit's ARAIM stream
/// epochs take their sigmas from).
struct ReplayModels<'a> {
    args: &'a AraimReplayArgs,
    epoch: &'a PreparedEpoch,
}

impl SatelliteModels for ReplayModels<'_> {
    fn ism(&self, id: SatId) -> Option<SatIsm> {
        let a = self.args;
        Some(SatIsm {
            id,
            sigma_ura_m: a.araim_ura_m,
            sigma_ure_m: a.araim_ure_m,
            b_nom_m: a.araim_b_nom_m,
            p_sat: a.araim_p_sat,
        })
    }

    fn curves(&self, id: SatId) -> Curves {
        let code = self
            .epoch
            .sats
            .iter()
            .find(|p| p.obs.id == id)
            .map_or("", |p| p.code.as_str());
        raim_nav::ranging::araim_curves(id.system, code, self.args.araim_iono_m)
    }
}

fn name(id: SatId) -> String {
    format!("{}{:02}", id.system.letter(), id.prn)
}

/// Where the ARAIM epochs run: the core's monitor on the host (f64, the
/// replay's own satellite models, no FDE limit), or the firmware under
/// QEMU (the device's precision, its ISM entries with the ADD elevation
/// curves, its FDE limits), given the same pseudoranges as
/// `AraimCommand::Ranges` after one `Ism` frame. Both answer in the wire
/// form, from which the records are built, so the two targets' records,
/// summaries, plots and NMEA come from the same code (docs/REPLAY.md,
/// "ARAIM on the device").
pub enum AraimEngine {
    Host(Box<Engine>),
    Qemu(Box<QemuSession>),
}

/// The device's ISM entries: one per satellite of the run, with the
/// command's sigma_URA, sigma_URE, b_nom and P_sat, and P_const for the
/// constellations that have entries (a constellation without one is a
/// typed refusal of the frame).
fn device_ism(
    a: &AraimReplayArgs,
    ism: &Ism,
    epochs: &[PreparedEpoch],
) -> Result<(
    Vec<IsmSat>,
    [Option<f64>; raim_core::measurement::MAX_SYSTEMS],
)> {
    let mut ids: Vec<SatId> = epochs
        .iter()
        .flat_map(|e| e.sats.iter().map(|s| s.obs.id))
        .collect();
    ids.sort_by_key(|id| (id.system.index(), id.prn));
    ids.dedup();
    if ids.len() > raim_proto::CAPACITY {
        bail!(
            "--araim --target qemu: the run has {} satellites, more than the {} ISM entries the device holds (narrow --systems or the --start/--end window)",
            ids.len(),
            raim_proto::CAPACITY
        );
    }
    let mut p_const = [None; raim_core::measurement::MAX_SYSTEMS];
    for id in &ids {
        if let (Some(slot), Some(p)) = (
            p_const.get_mut(id.system.index()),
            ism.p_const.get(id.system.index()).copied().flatten(),
        ) {
            *slot = Some(p);
        }
    }
    let sats = ids
        .into_iter()
        .map(|id| IsmSat {
            id,
            sigma_ura_m: a.araim_ura_m,
            sigma_ure_m: a.araim_ure_m,
            b_nom_m: a.araim_b_nom_m,
            p_sat: a.araim_p_sat,
        })
        .collect();
    Ok((sats, p_const))
}

impl AraimEngine {
    /// A fresh engine: on QEMU, the firmware configured with the solver's
    /// configuration and sent the run's ISM frame.
    fn start(
        target: Target,
        a: &AraimReplayArgs,
        solver: &Config,
        cfg: &AraimConfig,
        ism: &Ism,
        epochs: &[PreparedEpoch],
    ) -> Result<Self> {
        Ok(match target {
            Target::Host => AraimEngine::Host(Box::default()),
            Target::Qemu => {
                let (sats, p_const) = device_ism(a, ism, epochs)?;
                let elf = raim_qemu::firmware_elf()?;
                let mut s = QemuSession::start(&elf)?;
                s.configure(solver)?;
                let frame = IsmFrameRef {
                    config: WireAraimConfig::from(*cfg),
                    p_const,
                    sats: &sats,
                };
                match s.call(CommandRef::Araim(AraimCommandRef::Ism(frame)))? {
                    ResponseBody::Araim(AraimAnswer::IsmAccepted { .. }) => {}
                    ResponseBody::Error(e) => bail!("the firmware refused the ISM frame: {e}"),
                    _ => bail!(
                        "the firmware answered the ISM frame with something else than IsmAccepted"
                    ),
                }
                AraimEngine::Qemu(Box::new(s))
            }
        })
    }

    /// One epoch: the wire result or the refusal as text, and the NMEA
    /// sentences (`nmea`: wanted on the host; the firmware writes them
    /// anyway). A transport failure is the outer error.
    #[allow(clippy::too_many_arguments)]
    fn epoch(
        &mut self,
        a: &AraimReplayArgs,
        solver: &Config,
        cfg: &AraimConfig,
        ism: &Ism,
        e: &PreparedEpoch,
        sats: &[RangeObservation],
        nmea: bool,
    ) -> Result<(Result<WireAraimResult, String>, Vec<String>)> {
        // The protocol's epoch time is UTC Unix seconds (the NMEA date).
        let unix_s = raim_gnss::time::unix_utc_s(e.time_gps_s);
        match self {
            AraimEngine::Host(monitor) => {
                let r = host_epoch(a, solver, cfg, ism, e, sats, monitor, unix_s);
                let sentences = if nmea {
                    let cn0: Vec<u8> = e.sats.iter().map(|s| s.cn0_dbhz).collect();
                    host_nmea(r.as_ref().ok(), unix_s, e, sats, &cn0, &solver.sigma_model)
                } else {
                    Vec::new()
                };
                Ok((r, sentences))
            }
            AraimEngine::Qemu(s) => {
                let body = s.call(CommandRef::Araim(AraimCommandRef::Ranges {
                    time_s: unix_s,
                    apriori_m: e.reference_m,
                    sats,
                }))?;
                let r = match body {
                    ResponseBody::Araim(AraimAnswer::Result(w)) => Ok(w),
                    ResponseBody::Error(err) => Err(format!("ARAIM: {err}")),
                    _ => bail!(
                        "the firmware answered an ARAIM epoch with something else than a result"
                    ),
                };
                // Every epoch writes its sentences (a refused one its
                // no-fix sentences), ending with ZDA.
                let sentences = s.take_epoch_nmea(raim_qemu::ANSWER_TIMEOUT)?;
                Ok((r, sentences))
            }
        }
    }
}

/// One epoch through the host's core monitor, in the wire form the
/// firmware answers with (`raim-server`'s ARAIM answer, field for field).
#[allow(clippy::too_many_arguments)]
fn host_epoch(
    a: &AraimReplayArgs,
    solver: &Config,
    cfg: &AraimConfig,
    ism: &Ism,
    e: &PreparedEpoch,
    sats: &[RangeObservation],
    monitor: &mut Engine,
    unix_s: f64,
) -> Result<WireAraimResult, String> {
    let models = ReplayModels { args: a, epoch: e };
    let ranges = Epoch::ranges(e.time_gps_s, sats, e.reference_m);
    let verdict = monitor
        .epoch(solver, cfg, ism, &models, &ranges, FdeLimits::UNLIMITED)
        .map_err(|e| match e {
            MonitorError::Araim(a) => format!("ARAIM: {a}"),
            other => format!("ARAIM: {other}"),
        })?;
    WireAraimResult::from_verdict(monitor.runs(), &verdict, cfg, unix_s)
        .map_err(|e| format!("ARAIM: {e}"))
}

/// One epoch through the host's core monitor with the replay's satellite
/// models: the verdict itself (the model check reads the monitor after
/// it, `super::model_check`).
pub(super) fn host_verdict(
    a: &AraimReplayArgs,
    solver: &Config,
    cfg: &AraimConfig,
    ism: &Ism,
    e: &PreparedEpoch,
    sats: &[RangeObservation],
    monitor: &mut Engine,
) -> Result<raim_core::araim::Verdict<ARAIM_SATS>, MonitorError> {
    let models = ReplayModels { args: a, epoch: e };
    let ranges = Epoch::ranges(e.time_gps_s, sats, e.reference_m);
    monitor.epoch(solver, cfg, ism, &models, &ranges, FdeLimits::UNLIMITED)
}

/// The NMEA sentences of an ARAIM epoch as the firmware writes them
/// (`raim-server`: `WireResult::set_from_araim`, then the epoch writer,
/// with the speed and course of the source's Doppler, `super::velocity`),
/// or a refused epoch's no-fix sentences.
fn host_nmea(
    r: Option<&WireAraimResult>,
    unix_s: f64,
    e: &PreparedEpoch,
    sats: &[RangeObservation],
    cn0_dbhz: &[u8],
    model: &raim_core::sigma::SigmaModel,
) -> Vec<String> {
    let mut wire = WireResult::empty();
    match r {
        Some(r) => wire.set_from_araim(r, sats.iter().map(|s| s.id)),
        None => wire.time_s = unix_s,
    }
    let epoch = Epoch::ranges(unix_s, sats, e.reference_m);
    let sky = raim_proto::nmea::Sky {
        epoch: &epoch,
        cn0_dbhz,
        velocity: super::velocity::ground_velocity(&wire, e, sats, model),
    };
    raim_proto::nmea::epoch_sentences(&wire, &sky, raim_proto::nmea::BUILT)
        .map(|v| v.iter().map(|s| s.trim_end().to_string()).collect())
        .unwrap_or_default()
}

/// A structural cause of unavailability in words (`WireUnavailable`).
pub fn unavailable_name(u: &WireUnavailable) -> String {
    match u {
        WireUnavailable::ModeCapacity { needed, capacity } => {
            format!("mode_capacity: {needed} modes needed, {capacity} held")
        }
        WireUnavailable::TooManyEvents { p_exceed_at_max } => {
            format!("too_many_events: P(more events) {p_exceed_at_max:.3e}")
        }
        WireUnavailable::Unmonitored { p_unmon, p_thres } => {
            format!("unmonitored: p_unmon {p_unmon:.3e} > P_THRES {p_thres:.3e}")
        }
        WireUnavailable::PlNotSolved { axis } => {
            let name = ["east", "north", "up"]
                .get(*axis as usize)
                .copied()
                .unwrap_or("?");
            format!("pl_not_solved: the {name} protection level has no root")
        }
        WireUnavailable::Limits => "limits".into(),
    }
}

/// The record's monitor fields from the wire result (either target).
fn fill(rec: &mut AraimRecord, w: &WireAraimResult) {
    let a = &w.all_in_view;
    rec.modes = a.modes as usize;
    rec.monitored = a.monitored as usize;
    rec.max_faults = a.max_faults as usize;
    rec.p_unmon = a.p_unmon;
    rec.vpl_all_m = a.vpl_m;
    rec.hpl_all_m = a.hpl_m;
    rec.vpl_all_exact_m = a.vpl_exact_m;
    rec.hpl_all_exact_m = a.hpl_exact_m;
    rec.emt_m = a.emt_m;
    rec.sigma_v_acc_m = a.sigma_v_acc_m;
    rec.detection_passed = a.detection_passed;
    rec.available = matches!(w.decision, Decision::Ok | Decision::Excluded);
    let in_force = w.in_force();
    rec.unavailable = in_force.unavailable.as_ref().map(unavailable_name);
    // The PLs in force when they were solved: available, or unavailable
    // for the limits only. A structural cause leaves no PL (the fields
    // are 0 then, which is not a bound).
    let pls = match in_force.unavailable {
        None | Some(WireUnavailable::Limits) => Some((in_force.vpl_m, in_force.hpl_m)),
        Some(_) => None,
    };
    let alarm = |rec: &mut AraimRecord, fde: &str| {
        rec.fde = fde.into();
        rec.unavailable = Some("alarm".into());
    };
    match w.fde {
        WireFde::NoFault => rec.fde = "no_fault".into(),
        WireFde::Excluded { .. } => {
            rec.fde = "excluded".into();
            rec.excluded = w.excluded.iter().map(|id| name(*id)).collect();
        }
        WireFde::Ambiguous { .. } => alarm(rec, "alarm_ambiguous"),
        WireFde::NoCandidate => alarm(rec, "alarm_no_candidate"),
        WireFde::BudgetExceeded { .. } => alarm(rec, "alarm_budget_exceeded"),
        // No test ran (the modes did not fit): no PL, unavailable.
        WireFde::NotTested => rec.fde = "not_tested".into(),
        WireFde::NotAttempted { .. } => alarm(rec, "alarm_not_attempted"),
    }
    if matches!(rec.fde.as_str(), "no_fault" | "excluded") {
        rec.vpl_m = pls.map(|p| p.0);
        rec.hpl_m = pls.map(|p| p.1);
    }
}

#[allow(clippy::too_many_arguments)]
fn run_epochs(
    engine: &mut AraimEngine,
    a: &AraimReplayArgs,
    solver: &Config,
    cfg: &AraimConfig,
    ism: &Ism,
    epochs: &[PreparedEpoch],
    plan: &FaultPlan,
    const_faults: &[ConstFault],
    reference: Option<[f64; 3]>,
    nmea: bool,
) -> Result<Vec<AraimRecord>> {
    let mut out = Vec::with_capacity(epochs.len());
    for e in epochs {
        let mut sats = e.observations();
        let injected = plan.apply(e.time_gps_s, &mut sats);
        let mut faulted = injected.faulted.clone();
        if let Some(rx) = e.reference_m {
            let rot = enu_rotation(&ecef_to_geodetic(rx));
            for f in const_faults.iter().filter(|f| f.active(e.time_gps_s)) {
                let shift = unrotate(&rot, f.shift_enu_m);
                faulted.extend(constellation_bias(
                    &mut sats, f.system, rx, f.common_m, shift,
                ));
            }
        }
        let mut rec = AraimRecord {
            time_gps_s: e.time_gps_s,
            sats: sats.len(),
            faulted: faulted
                .iter()
                .map(|(id, b)| format!("{}:{b:.1}", name(*id)))
                .collect(),
            ..AraimRecord::default()
        };
        let (result, sentences) = engine.epoch(a, solver, cfg, ism, e, &sats, nmea)?;
        rec.nmea = sentences;
        match result {
            Ok(w) => {
                fill(&mut rec, &w);
                let p = w.position_ecef_m;
                rec.position_ecef_m = p;
                if let (Some(p), Some(rf)) = (p, reference) {
                    let err = error_enu(p, rf);
                    rec.error_enu_m = Some(err);
                    rec.error_h_m = Some(err[0].hypot(err[1]));
                    rec.error_v_m = Some(err[2].abs());
                }
                if rec.fde == "excluded" {
                    let all = faulted
                        .iter()
                        .filter(|(_, b)| b.abs() > 0.0)
                        .all(|(id, _)| rec.excluded.contains(&name(*id)));
                    rec.exclusion = Some(if all { "correct" } else { "wrong" }.into());
                }
            }
            Err(err) => rec.error = Some(err),
        }
        out.push(rec);
    }
    Ok(out)
}

/// The whole ARAIM replay, without printing (used by the tests too).
pub fn replay(args: &ReplayArgs) -> Result<(Vec<AraimRecord>, AraimSummary, Option<[f64; 3]>)> {
    let a = &args.araim;
    if args.pf.pf.is_some() {
        bail!("--araim and --pf are two different monitors: choose one");
    }
    let cfg = AraimConfig::default();
    let solver = args.core_config();
    let systems = args.ranging()?.systems;
    let ism = a.ism(&systems)?;
    let (epochs, header, first) = prepare(args)?;
    let plan = checked_fault_plan(args, first, &epochs)?;
    let const_faults = a
        .araim_const_faults
        .iter()
        .map(|s| ConstFault::parse(s, first))
        .collect::<Result<Vec<_>>>()?;
    let nmea = args.nmea.is_some() || args.nmea_file.is_some();
    if args.target == Target::Qemu {
        for c in args.codes.iter().filter(|c| c.contains('+')) {
            let _ = writeln!(
                std::io::stderr(),
                "raim: warning: --code {c}: the device's error model takes the ADD's \
                 dual-frequency factor for every satellite, not this pair's own \
                 (docs/REPLAY.md, \"ARAIM on the device\")"
            );
        }
    }
    let mut engine = AraimEngine::start(args.target, a, &solver, &cfg, &ism, &epochs)?;
    let reference = match args.reference {
        super::Reference::Header => header,
        super::Reference::CleanMean => {
            let clean = run_epochs(
                &mut engine,
                a,
                &solver,
                &cfg,
                &ism,
                &epochs,
                &FaultPlan::default(),
                &[],
                None,
                false,
            )?;
            let ps: Vec<[f64; 3]> = clean
                .iter()
                .filter(|r| r.available)
                .filter_map(|r| r.position_ecef_m)
                .collect();
            let n = ps.len() as f64;
            (!ps.is_empty()).then(|| [0, 1, 2].map(|k| ps.iter().map(|p| p[k]).sum::<f64>() / n))
        }
    };
    let recs = run_epochs(
        &mut engine,
        a,
        &solver,
        &cfg,
        &ism,
        &epochs,
        &plan,
        &const_faults,
        reference,
        nmea,
    )?;
    let summary = summarise(&recs);
    Ok((recs, summary, reference))
}

pub fn run(args: &ReplayArgs) -> Result<()> {
    let (recs, summary, reference) = replay(args)?;
    let stdout = std::io::stdout();
    let mut w = stdout.lock();
    if !args.quiet {
        for r in &recs {
            match args.nmea {
                _ if args.json => writeln!(w, "{}", serde_json::to_string(r)?)?,
                Some(NmeaMode::Only) => {
                    // NMEA 0183 ends every sentence with CR LF.
                    for s in &r.nmea {
                        write!(w, "{s}\r\n")?;
                    }
                }
                Some(NmeaMode::WithText) => {
                    writeln!(w, "{}", r.text_line())?;
                    for s in &r.nmea {
                        writeln!(w, "    {s}")?;
                    }
                }
                None => writeln!(w, "{}", r.text_line())?,
            }
        }
    }
    if args.json {
        writeln!(
            w,
            "{}",
            serde_json::json!({ "araim_summary": summary, "reference_ecef_m": reference })
        )?;
    } else if args.nmea != Some(NmeaMode::Only) {
        writeln!(w, "{}", summary.table())?;
    }
    w.flush()?;
    if let Some(p) = &args.nmea_file {
        super::export::write_nmea(p, recs.iter().flat_map(|r| &r.nmea))?;
    }
    if let Some(p) = &args.araim.araim_plot {
        draw(
            &recs,
            &AraimConfig::default(),
            p,
            args.font.as_deref(),
            &super::run_title(args),
        )?;
    }
    Ok(())
}

fn perr<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// A title naming the file, the faults and the window, then three panels:
/// PLs and the effective monitor threshold over GPS time against VAL/HAL
/// with the errors, exclusions named by satellite; the vertical and
/// horizontal Stanford diagrams (`super::stanford`).
pub fn draw(
    recs: &[AraimRecord],
    cfg: &AraimConfig,
    path: &Path,
    font: Option<&Path>,
    title: &str,
) -> Result<()> {
    super::plot::register_font(font)?;
    let root = BitMapBackend::new(path, (1800, 1400)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let root = root
        .titled(&format!("raim replay --araim: {title}"), ("sans-serif", 28))
        .map_err(perr)?;
    let (top, bottom) = root.split_vertically(650);
    let lower = bottom.split_evenly((1, 2));
    let ax = super::plot::TimeAxis::new(
        recs.first().map_or(0.0, |r| r.time_gps_s),
        recs.last().map_or(0.0, |r| r.time_gps_s),
    );
    let solved: Vec<&AraimRecord> = recs.iter().filter(|r| r.error.is_none()).collect();
    let with_pl: Vec<(&AraimRecord, f64, f64)> = solved
        .iter()
        .filter_map(|r| r.output_pls().map(|(v, h)| (*r, v, h)))
        .collect();
    // Room above the alert limits for the legend and the exclusion labels.
    let y_max = with_pl
        .iter()
        .map(|(_, v, h)| v.max(*h))
        .filter(|v| v.is_finite())
        .fold(cfg.hal_m.max(cfg.val_m), f64::max)
        * 2.4;
    {
        let mut c = ChartBuilder::on(&top)
            .caption(
                "protection levels, effective monitor threshold and errors against VAL/HAL",
                ("sans-serif", 24),
            )
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(ax.range(), 0.0..y_max)
            .map_err(perr)?;
        c.configure_mesh()
            .x_desc(ax.desc.as_str())
            .x_label_formatter(&super::plot::hhmm)
            .y_desc("m")
            .draw()
            .map_err(perr)?;
        type Get = fn(&(&AraimRecord, f64, f64)) -> f64;
        let series: [(&str, RGBColor, Get); 2] = [("VPL", BLUE, |x| x.1), ("HPL", GREEN, |x| x.2)];
        for (label, color, get) in series {
            c.draw_series(LineSeries::new(
                with_pl
                    .iter()
                    .filter(|x| get(x).is_finite())
                    .map(|x| (ax.x(x.0.time_gps_s), get(x))),
                &color,
            ))
            .map_err(perr)?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        }
        let emt = RGBColor(200, 120, 0);
        c.draw_series(LineSeries::new(
            solved.iter().map(|r| (ax.x(r.time_gps_s), r.emt_m)),
            &emt,
        ))
        .map_err(perr)?
        .label("effective monitor threshold")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], emt));
        for (label, v, color) in [("VAL", cfg.val_m, RED), ("HAL", cfg.hal_m, MAGENTA)] {
            c.draw_series(LineSeries::new(
                [(ax.first_h, v), (ax.last_h, v)],
                color.stroke_width(2),
            ))
            .map_err(perr)?
            .label(format!("{label} {v:.0} m"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        }
        let ev = RGBColor(0, 0, 120);
        c.draw_series(
            solved
                .iter()
                .filter_map(|r| Some((ax.x(r.time_gps_s), r.error_v_m?)))
                .map(|p| Circle::new(p, 2, ev.filled())),
        )
        .map_err(perr)?
        .label("vertical error (absolute)")
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, ev.filled()));
        let eh = RGBColor(0, 120, 0);
        c.draw_series(
            solved
                .iter()
                .filter_map(|r| Some((ax.x(r.time_gps_s), r.error_h_m?)))
                .map(|p| TriangleMarker::new(p, 3, eh.filled())),
        )
        .map_err(perr)?
        .label("horizontal error")
        .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 3, eh.filled()));
        let excl = RGBColor(255, 140, 0);
        c.draw_series(
            solved
                .iter()
                .filter(|r| r.fde == "excluded")
                .map(|r| Circle::new((ax.x(r.time_gps_s), y_max * 0.62), 4, excl.filled())),
        )
        .map_err(perr)?
        .label("exclusion (satellites named where the set changes)")
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, excl.filled()));
        // The excluded satellites, written where the excluded set changes.
        let mut last: Vec<String> = Vec::new();
        let mut names = Vec::new();
        for r in solved.iter().filter(|r| r.fde == "excluded") {
            if r.excluded != last {
                names.push((ax.x(r.time_gps_s), r.excluded.join("+")));
                last.clone_from(&r.excluded);
            }
        }
        let font = ("sans-serif", 18).into_font();
        c.draw_series(
            names
                .into_iter()
                .map(|(x, n)| Text::new(n, (x, y_max * 0.60), font.clone())),
        )
        .map_err(perr)?;
        c.draw_series(
            solved
                .iter()
                .filter(|r| r.fde.starts_with("alarm"))
                .map(|r| Cross::new((ax.x(r.time_gps_s), y_max * 0.55), 6, RED.stroke_width(2))),
        )
        .map_err(perr)?
        .label("alarm")
        .legend(|(x, y)| Cross::new((x + 10, y), 6, RED.stroke_width(2)));
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(perr)?;
    }
    let refused = recs.len() - with_pl.len();
    for (panel, (limit, axis)) in lower.iter().zip([
        (cfg.val_m, super::stanford::Axis::Vertical),
        (cfg.hal_m, super::stanford::Axis::Horizontal),
    ]) {
        let pts: Vec<(f64, f64)> = with_pl
            .iter()
            .filter_map(|(r, v, h)| match axis {
                super::stanford::Axis::Vertical => Some((r.error_v_m?, *v)),
                super::stanford::Axis::Horizontal => Some((r.error_h_m?, *h)),
            })
            .collect();
        super::stanford::draw(panel, &pts, axis, Some(limit), refused)?;
    }
    root.present().map_err(perr)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn const_fault_spec_parses_and_rejects() {
        let f = ConstFault::parse("E:0:0,20,-5@+60..+120", 1000.0).unwrap();
        assert_eq!(f.system, System::Galileo);
        assert_eq!(f.shift_enu_m, [0.0, 20.0, -5.0]);
        assert_eq!((f.start_gps_s, f.end_gps_s), (1060.0, Some(1120.0)));
        assert!(f.active(1060.0) && !f.active(1120.0));
        for bad in [
            "E:0:0,20@+60",
            "E:0:0,20,1",
            "E:x:0,0,0@+1",
            "E:0:0,0,inf@+1",
        ] {
            assert!(ConstFault::parse(bad, 0.0).is_err(), "{bad}");
        }
    }
}
