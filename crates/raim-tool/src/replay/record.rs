//! One replayed epoch, reduced to what the outputs need: the decision, the
//! statistics, the exclusions, the injected truth, the position error
//! against the reference and the protection levels.

use raim_core::frames::{ecef_to_geodetic, enu_rotation, rotate};
use raim_core::snapshot::fde::AlarmCause;
use raim_core::{Decision, SatId};
use raim_proto::result::WireResult;
use serde::Serialize;

/// The epoch as the JSON lines print it.
#[derive(Debug, Clone, Serialize)]
pub struct EpochRecord {
    /// The epoch's NMEA sentences from the monitor (not in the JSON line).
    #[serde(skip)]
    pub nmea: Vec<String>,
    /// GPS seconds since 1980-01-06.
    pub time_gps_s: f64,
    /// Time of day (GPS time), HH:MM:SS.
    pub tod: String,
    /// ok | excluded | alarm | unavailable | error
    pub decision: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alarm_cause: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    pub n_sats: usize,
    /// All-in-view D^2, T^2 and dof.
    pub initial_statistic: f64,
    pub initial_threshold: f64,
    pub initial_dof: u32,
    /// D^2, T^2 and dof of the solution in force.
    pub final_statistic: f64,
    pub final_threshold: f64,
    pub final_dof: u32,
    /// The satellite the identification rule ranks first on the
    /// all-in-view solution (null when that test passes); not necessarily
    /// excluded.
    pub candidate: Option<String>,
    /// Satellites excluded (in force for `excluded`; attempted otherwise).
    pub excluded: Vec<String>,
    pub excluded_bias_m: Vec<f64>,
    /// Satellites carrying an injected step/ramp, with the bias, m.
    pub faulted: Vec<(String, f64)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position_ecef_m: Option<[f64; 3]>,
    /// Position error of the solution in force against the reference, ENU, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_enu_m: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_h_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_v_m: Option<f64>,
    /// Protection levels, m: infinite when unbounded (null in JSON, `inf`
    /// in text).
    pub hpl_m: f64,
    pub vpl_m: f64,
    pub sigma_enu_m: [f64; 3],
    /// For an ambiguous alarm: each candidate's exclusion tried alone, as
    /// (satellite, D^2, T^2, dof) of the subset without it. Both pass.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ambiguity: Vec<(String, f64, f64, u32)>,
    #[serde(skip)]
    pub excluded_ids: Vec<SatId>,
    #[serde(skip)]
    pub faulted_ids: Vec<SatId>,
}

pub fn cause_name(c: AlarmCause) -> String {
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

fn decision_name(d: Decision) -> &'static str {
    match d {
        Decision::Ok => "ok",
        Decision::Alarm => "alarm",
        Decision::Excluded => "excluded",
        Decision::Unavailable => "unavailable",
    }
}

/// ENU error of `p` against `reference`.
pub fn error_enu(p: [f64; 3], reference: [f64; 3]) -> [f64; 3] {
    let d = [
        p[0] - reference[0],
        p[1] - reference[1],
        p[2] - reference[2],
    ];
    rotate(&enu_rotation(&ecef_to_geodetic(reference)), d)
}

impl EpochRecord {
    /// From the wire form of a result (the host engine converts its
    /// `EpochResult` with `WireResult::from_result`; the firmware sends it).
    pub fn from_result(
        r: &WireResult,
        time_gps_s: f64,
        n_sats: usize,
        faulted: &[(SatId, f64)],
        reference: Option<[f64; 3]>,
    ) -> Self {
        let err = match (r.position_ecef_m, reference) {
            (Some(p), Some(rf)) => Some(error_enu(p, rf)),
            _ => None,
        };
        EpochRecord {
            nmea: Vec::new(),
            time_gps_s,
            tod: raim_gnss::time::time_of_day(time_gps_s),
            decision: decision_name(r.decision).into(),
            alarm_cause: r.alarm_cause.map(cause_name),
            error: None,
            n_sats,
            initial_statistic: r.initial_test.statistic,
            initial_threshold: r.initial_test.threshold,
            initial_dof: r.initial_test.dof,
            final_statistic: r.test.statistic,
            final_threshold: r.test.threshold,
            final_dof: r.test.dof,
            candidate: r.identified.map(|s| s.to_string()),
            excluded: r.exclusions.iter().map(|e| e.id.to_string()).collect(),
            excluded_bias_m: r.exclusions.iter().map(|e| e.bias_m).collect(),
            faulted: faulted.iter().map(|(id, b)| (id.to_string(), *b)).collect(),
            position_ecef_m: r.position_ecef_m,
            error_enu_m: err,
            error_h_m: err.map(|e| e[0].hypot(e[1])),
            error_v_m: err.map(|e| e[2].abs()),
            hpl_m: r.hpl_m,
            vpl_m: r.vpl_m,
            sigma_enu_m: r.sigma_enu_m,
            ambiguity: Vec::new(),
            excluded_ids: if r.decision == Decision::Excluded
                || (r.decision == Decision::Unavailable && !r.exclusions.is_empty())
            {
                r.exclusions.iter().map(|e| e.id).collect()
            } else {
                Vec::new()
            },
            faulted_ids: faulted.iter().map(|(id, _)| *id).collect(),
        }
    }

    /// An epoch the core refused (too few satellites, bad geometry, ...).
    pub fn from_error(
        time_gps_s: f64,
        n_sats: usize,
        faulted: &[(SatId, f64)],
        e: &dyn std::fmt::Display,
    ) -> Self {
        EpochRecord {
            nmea: Vec::new(),
            time_gps_s,
            tod: raim_gnss::time::time_of_day(time_gps_s),
            decision: "error".into(),
            alarm_cause: None,
            error: Some(e.to_string()),
            n_sats,
            initial_statistic: f64::NAN,
            initial_threshold: f64::NAN,
            initial_dof: 0,
            final_statistic: f64::NAN,
            final_threshold: f64::NAN,
            final_dof: 0,
            candidate: None,
            excluded: Vec::new(),
            excluded_bias_m: Vec::new(),
            faulted: faulted.iter().map(|(id, b)| (id.to_string(), *b)).collect(),
            position_ecef_m: None,
            error_enu_m: None,
            error_h_m: None,
            error_v_m: None,
            hpl_m: f64::INFINITY,
            vpl_m: f64::INFINITY,
            sigma_enu_m: [f64::NAN; 3],
            ambiguity: Vec::new(),
            excluded_ids: Vec::new(),
            faulted_ids: faulted.iter().map(|(id, _)| *id).collect(),
        }
    }

    /// The position is usable (the monitor did not alarm and solved).
    pub fn usable(&self) -> bool {
        matches!(self.decision.as_str(), "ok" | "excluded" | "unavailable")
    }

    /// One readable line.
    pub fn text_line(&self) -> String {
        let excl = if self.excluded.is_empty() {
            String::new()
        } else {
            format!(" excl={}", self.excluded.join(","))
        };
        let mut cause = self
            .alarm_cause
            .as_ref()
            .map(|c| format!(" cause={c}"))
            .unwrap_or_default();
        for (sat, d2, t2, dof) in &self.ambiguity {
            cause.push_str(&format!(" [w/o {sat}: D2={d2:.2} T2={t2:.2} dof={dof}]"));
        }
        let fault = if self.faulted.is_empty() {
            String::new()
        } else {
            let v: Vec<String> = self
                .faulted
                .iter()
                .map(|(s, b)| format!("{s}{b:+.1}"))
                .collect();
            format!(" fault={}", v.join(","))
        };
        match &self.error {
            Some(e) => format!("{} ERROR n={} {e}{fault}", self.tod, self.n_sats),
            None => format!(
                "{} {:<11} n={:>2} D2={:>9.2} T2={:>6.2} dof={:>2}{excl}{cause} errH={:>7.2} errV={:>7.2} HPL={:>8.1} VPL={:>8.1}{fault}",
                self.tod,
                self.decision.to_uppercase(),
                self.n_sats,
                self.initial_statistic,
                self.initial_threshold,
                self.initial_dof,
                self.error_h_m.unwrap_or(f64::NAN),
                self.error_v_m.unwrap_or(f64::NAN),
                self.hpl_m,
                self.vpl_m,
            ),
        }
    }
}
