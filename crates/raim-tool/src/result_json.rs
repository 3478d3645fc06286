//! One JSON object per epoch result (docs/FORMATS.md), and a one-line text
//! summary for terminals.

use raim_core::snapshot::fde::AlarmCause;
use raim_core::AlarmSource;
use raim_core::{Decision, EpochResult, RaimError};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct SatOut {
    pub sat: String,
    pub used: bool,
    pub el_deg: f64,
    pub sigma_m: f64,
    pub s_ii: f64,
    pub h_ii: f64,
    pub w: f64,
    pub bias_m: f64,
    pub score: Option<f64>,
}

#[derive(Debug, Serialize)]
pub struct ExclusionOut {
    pub sat: String,
    pub statistic_before: f64,
    pub threshold_before: f64,
    pub statistic_after: f64,
    pub threshold_after: f64,
    pub dof_after: u32,
    pub bias_m: f64,
}

/// The MCUSUM state of an epoch (SPEC §7), when the sequential test runs.
#[derive(Debug, Serialize)]
pub struct McusumOut {
    /// D_t = ||S_t||, sigma units.
    pub statistic: f64,
    /// The alarm threshold h for this dimension.
    pub threshold: f64,
    pub k: f64,
    pub dim: u32,
    pub alarm: bool,
    /// Which test alarmed: none | snapshot | cusum | both.
    pub source: &'static str,
    /// The satellite the MCUSUM's identification picked (then held out).
    pub candidate: Option<String>,
    pub held: Vec<String>,
    pub available: bool,
}

#[derive(Debug, Serialize)]
pub struct ResultOut {
    pub time_s: f64,
    pub decision: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alarm_cause: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position_ecef_m: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lat_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lon_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_m: Option<f64>,
    pub correction_enu_m: [f64; 3],
    /// All-in-view test: D^2, T^2 and dof.
    pub initial_statistic: f64,
    pub initial_threshold: f64,
    pub initial_dof: u32,
    /// Test of the solution in force (after exclusions; equal to the
    /// all-in-view test when nothing was excluded).
    pub final_statistic: f64,
    pub final_threshold: f64,
    pub final_dof: u32,
    /// The satellite the identification rule ranks first on the
    /// all-in-view solution (null when that test passes). Not necessarily
    /// excluded: a pair search can explain the residuals better.
    pub candidate: Option<String>,
    /// Satellites removed by FDE, in order.
    pub excluded: Vec<String>,
    /// Each exclusion's test before and after it.
    pub exclusions: Vec<ExclusionOut>,
    /// Protection levels, m; unbounded prints as null.
    pub hpl_m: f64,
    pub vpl_m: f64,
    pub sigma_enu_m: [f64; 3],
    pub pl_available: bool,
    pub detection_available: bool,
    pub exclusion_available: bool,
    pub sats: Vec<SatOut>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mcusum: Option<McusumOut>,
}

/// A refused epoch: the input line, the epoch time when it was read, the
/// error's name (a `RaimError` variant, or `Unreadable`) and its message.
#[derive(Debug, Serialize)]
pub struct ErrorOut {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub line: Option<usize>,
    pub time_s: Option<f64>,
    pub error: String,
    pub detail: String,
}

pub fn decision_name(d: Decision) -> &'static str {
    match d {
        Decision::Ok => "ok",
        Decision::Alarm => "alarm",
        Decision::Excluded => "excluded",
        Decision::Unavailable => "unavailable",
    }
}

fn cause_name(c: AlarmCause) -> String {
    match c {
        AlarmCause::NoRedundancy => "no_redundancy".into(),
        AlarmCause::Unidentifiable => "unidentifiable".into(),
        AlarmCause::Ambiguous { best, runner_up } => format!("ambiguous:{best}/{runner_up}"),
        AlarmCause::MaxExclusions => "max_exclusions".into(),
        AlarmCause::SubsetGeometry { excluded } => format!("subset_geometry:{excluded}"),
        AlarmCause::NoConsistentSet => "no_consistent_set".into(),
        AlarmCause::SearchIncomplete { groups, budget } => {
            format!("search_incomplete:{budget}/{groups}")
        }
    }
}

pub fn result_out<const N: usize>(r: &EpochResult<N>) -> ResultOut {
    ResultOut {
        time_s: r.time_s,
        decision: decision_name(r.decision),
        alarm_cause: r.alarm_cause.map(cause_name),
        position_ecef_m: r.position_ecef_m,
        lat_deg: r.geodetic.map(|g| g.lat_rad.to_degrees()),
        lon_deg: r.geodetic.map(|g| g.lon_rad.to_degrees()),
        height_m: r.geodetic.map(|g| g.height_m),
        correction_enu_m: r.correction_enu_m,
        initial_statistic: r.initial_test.statistic,
        initial_threshold: r.initial_test.threshold,
        initial_dof: r.initial_test.dof,
        final_statistic: r.test.statistic,
        final_threshold: r.test.threshold,
        final_dof: r.test.dof,
        candidate: r.identified.map(|s| s.to_string()),
        excluded: r.exclusions.iter().map(|e| e.id.to_string()).collect(),
        exclusions: r
            .exclusions
            .iter()
            .map(|e| ExclusionOut {
                sat: e.id.to_string(),
                statistic_before: e.before.statistic,
                threshold_before: e.before.threshold,
                statistic_after: e.after.statistic,
                threshold_after: e.after.threshold,
                dof_after: e.after.dof,
                bias_m: e.bias_m,
            })
            .collect(),
        hpl_m: r.protection.hpl_m,
        vpl_m: r.protection.vpl_m,
        sigma_enu_m: r.sigma_enu_m,
        pl_available: r.pl_available,
        detection_available: r.detection_available,
        exclusion_available: r.exclusion_available,
        sats: r
            .satellites
            .iter()
            .map(|s| SatOut {
                sat: s.id.to_string(),
                used: s.used,
                el_deg: s.elevation_rad.to_degrees(),
                sigma_m: s.sigma_m,
                s_ii: s.s_ii,
                h_ii: s.h_ii,
                w: s.w,
                bias_m: s.bias_m,
                score: s.identifiable.then_some(s.score),
            })
            .collect(),
        mcusum: r.mcusum.map(|m| McusumOut {
            statistic: m.statistic,
            threshold: m.threshold,
            k: m.k,
            dim: m.dim,
            alarm: m.alarm,
            source: match m.source {
                AlarmSource::None => "none",
                AlarmSource::Snapshot => "snapshot",
                AlarmSource::Cusum => "cusum",
                AlarmSource::Both => "both",
            },
            candidate: m.identified.map(|s| s.to_string()),
            held: m.held.iter().flatten().map(|s| s.to_string()).collect(),
            available: m.available,
        }),
    }
}

/// The variant name of a core error (`DuplicateSatellite`, ...).
pub fn error_name(e: &RaimError) -> String {
    let name = format!("{e:?}");
    name.split([' ', '{', '(']).next().unwrap_or("").to_string()
}

pub fn error_out(line: Option<usize>, time_s: f64, e: &RaimError) -> ErrorOut {
    ErrorOut {
        line,
        time_s: Some(time_s),
        error: error_name(e),
        detail: e.to_string(),
    }
}

/// A protection level for the text line: metres, or `inf` when unbounded.
fn pl_text(v: f64) -> String {
    if v.is_finite() {
        format!("{v:>8.1}m")
    } else {
        format!("{:>8}", "inf")
    }
}

/// One readable line per epoch.
pub fn text_line<const N: usize>(r: &EpochResult<N>) -> String {
    let excl: Vec<String> = r.exclusions.iter().map(|e| e.id.to_string()).collect();
    let cusum = r
        .mcusum
        .map(|m| format!(" Dt={:.2} h={:.2}", m.statistic, m.threshold))
        .unwrap_or_default();
    format!(
        "t={:>10.1}s {:<11} D2={:>9.2} T2={:>6.2} dof={} {}{} HPL={} VPL={}{}",
        r.time_s,
        decision_name(r.decision).to_uppercase(),
        r.initial_test.statistic,
        r.initial_test.threshold,
        r.initial_test.dof,
        if excl.is_empty() {
            String::new()
        } else {
            format!("excluded={} ", excl.join(","))
        },
        r.alarm_cause
            .map(|c| format!("cause={} ", cause_name(c)))
            .unwrap_or_default(),
        pl_text(r.protection.hpl_m),
        pl_text(r.protection.vpl_m),
        cusum,
    )
}
