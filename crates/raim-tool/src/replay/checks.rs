//! Checks of a replay's request against the data, before anything runs:
//! a `--start`/`--end` window that selects no epoch, and faults that would
//! be applied to nothing (a satellite never in view, a time outside the
//! run, an end before the start). A fault that touches no epoch is an
//! error naming its spec; one that misses part of its target is a warning
//! on stderr with the count of epochs it did touch.

use anyhow::{bail, Result};
use raim_core::SatId;
use raim_gnss::faults::{Fault, Target};
use raim_gnss::ranging::PreparedEpoch;
use raim_gnss::time::time_of_day;

/// A fault with the text the user wrote (a `--fault` spec, or the
/// scenario file's entry).
pub struct LabelledFault<'a> {
    pub label: String,
    pub fault: &'a Fault,
}

/// `--start` must not be after `--end`.
pub fn window(start_gps_s: Option<f64>, end_gps_s: Option<f64>, args: (&str, &str)) -> Result<()> {
    if let (Some(s), Some(e)) = (start_gps_s, end_gps_s) {
        if s > e {
            bail!(
                "--start {} ({}) is after --end {} ({}): no epoch between them",
                args.0,
                time_of_day(s),
                args.1,
                time_of_day(e)
            );
        }
    }
    Ok(())
}

fn active(f: &Fault, t: f64) -> bool {
    t >= f.start_gps_s && f.end_gps_s.is_none_or(|e| t < e)
}

fn hits(target: &Target, id: SatId) -> bool {
    match target {
        Target::Sats(v) => v.contains(&id),
        Target::System(s) => id.system == *s,
        Target::All => true,
    }
}

fn span(epochs: &[PreparedEpoch]) -> String {
    match (epochs.first(), epochs.last()) {
        (Some(a), Some(b)) => format!(
            "{}..{}",
            time_of_day(a.time_gps_s),
            time_of_day(b.time_gps_s)
        ),
        _ => "no epochs".into(),
    }
}

/// Each fault's effect on the selected epochs: an error for a fault that
/// touches no epoch; warnings (returned, for stderr) for one whose target
/// is partly never in view.
pub fn faults(list: &[LabelledFault<'_>], epochs: &[PreparedEpoch]) -> Result<Vec<String>> {
    let mut warnings = Vec::new();
    for LabelledFault { label, fault } in list {
        if let Some(end) = fault.end_gps_s {
            if end <= fault.start_gps_s {
                bail!(
                    "fault '{label}' ends ({}) before it starts ({})",
                    time_of_day(end),
                    time_of_day(fault.start_gps_s)
                );
            }
        }
        let in_time: Vec<&PreparedEpoch> = epochs
            .iter()
            .filter(|e| active(fault, e.time_gps_s))
            .collect();
        if in_time.is_empty() {
            let when = match fault.end_gps_s {
                Some(e) => format!("{}..{}", time_of_day(fault.start_gps_s), time_of_day(e)),
                None => format!("from {}", time_of_day(fault.start_gps_s)),
            };
            bail!(
                "fault '{label}' touches no epoch: it is active {when}, the run covers {}",
                span(epochs)
            );
        }
        let touched = in_time
            .iter()
            .filter(|e| e.sats.iter().any(|s| hits(&fault.target, s.obs.id)))
            .count();
        let seen = |id: SatId| {
            in_time
                .iter()
                .any(|e| e.sats.iter().any(|s| s.obs.id == id))
        };
        if touched == 0 {
            let why = match &fault.target {
                Target::Sats(_) => "none of its satellites is used in any epoch while it is active",
                Target::System(_) => "no satellite of that system is used while it is active",
                Target::All => "no satellite is used while it is active",
            };
            bail!(
                "fault '{label}' touches no epoch: {why} (check the PRN, --systems and --mask-deg)"
            );
        }
        if let Target::Sats(ids) = &fault.target {
            let missing: Vec<String> = ids
                .iter()
                .filter(|&&id| !seen(id))
                .map(|id| id.to_string())
                .collect();
            if !missing.is_empty() {
                warnings.push(format!(
                    "raim: warning: fault '{label}': {} never used while it is active; applied in {touched} of {} epochs",
                    missing.join(", "),
                    epochs.len()
                ));
            }
        }
    }
    Ok(warnings)
}
