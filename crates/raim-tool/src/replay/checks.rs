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

/// A GPS time as a calendar date and time (GPS scale), for messages.
pub fn gps_date_time(t_gps_s: f64) -> String {
    // Days since 1970-01-01 to civil (H. Hinnant's days_from_civil inverse).
    let unix = t_gps_s + 315_964_800.0;
    let days = (unix / 86_400.0).floor() as i64;
    let sod = unix - days as f64 * 86_400.0;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    let s = sod.round() as i64;
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02}",
        s / 3600,
        s / 60 % 60,
        s % 60
    )
}

/// Why no epoch has a usable satellite, from what each satellite was
/// rejected for: no supported system at all, only systems not selected (or
/// not modelled), ephemerides of another date, no ephemeris for these
/// satellites, none of the codes, or all below the mask.
pub fn why_nothing(
    obs: &[&raim_gnss::ObsEpoch],
    nav: &raim_gnss::NavData,
    epochs: &[PreparedEpoch],
    opts: &raim_gnss::RangingOptions,
) -> String {
    use raim_core::System;
    use raim_gnss::ranging::Rejection;
    let letters = |v: &mut Vec<System>| {
        v.sort();
        v.dedup();
        v.iter()
            .map(|s| s.letter().to_string())
            .collect::<Vec<_>>()
            .join("")
    };
    let mut present: Vec<System> = obs
        .iter()
        .flat_map(|e| e.sats.keys().map(|id| id.system))
        .collect();
    if present.is_empty() {
        return "the observations hold no satellite of a supported system (GPS, Galileo, BeiDou, QZSS; \
                GLONASS is read but not modelled; SBAS, NavIC and others are not read)"
            .into();
    }
    let mut selected = opts.systems.clone();
    let (p, s) = (letters(&mut present), letters(&mut selected));
    let rej: Vec<Rejection> = epochs
        .iter()
        .flat_map(|e| e.rejected.iter().map(|r| r.1))
        .collect();
    let all = |f: fn(&Rejection) -> bool| !rej.is_empty() && rej.iter().all(f);
    if all(|r| matches!(r, Rejection::SystemNotSelected)) {
        let glo = if present.contains(&System::Glonass) {
            " (GLONASS orbits are not modelled)"
        } else {
            ""
        };
        return format!(
            "only systems that are not used are present: the observations hold {p}{glo}, --systems selects {s}"
        );
    }
    if rej.iter().any(|r| matches!(r, Rejection::NoEphemeris)) {
        let tocs: Vec<f64> = nav
            .ephemerides
            .iter()
            .filter(|(id, _)| selected.contains(&id.system))
            .flat_map(|(_, v)| v.iter().map(|k| k.toc_gps_s))
            .collect();
        let (t0, t1) = (
            obs.first().map_or(0.0, |e| e.time_gps_s),
            obs.last().map_or(0.0, |e| e.time_gps_s),
        );
        if tocs.is_empty() {
            return format!("the navigation data has no ephemeris of the selected systems ({s})");
        }
        let lo = tocs.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = tocs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // The longest validity of any system (BeiDou, 6 h) bounds "same date".
        let slack = 21_600.0;
        if t1 < lo - slack || t0 > hi + slack {
            return format!(
                "the ephemerides are from another date: the navigation data's clock times span {} .. {} (GPS), \
                 the observations {} .. {}",
                gps_date_time(lo),
                gps_date_time(hi),
                gps_date_time(t0),
                gps_date_time(t1)
            );
        }
        if all(|r| matches!(r, Rejection::NoEphemeris | Rejection::SystemNotSelected)) {
            return "no healthy ephemeris within its validity for any observed satellite of the selected systems"
                .into();
        }
    }
    if all(|r| matches!(r, Rejection::NoCode | Rejection::SystemNotSelected)) {
        let mut codes: Vec<String> = obs
            .iter()
            .flat_map(|e| {
                e.sats
                    .values()
                    .flat_map(|v| v.iter().map(|c| c.code.clone()))
            })
            .collect();
        codes.sort();
        codes.dedup();
        return format!(
            "none of the pseudorange codes asked for is present (the observations have {})",
            codes.join(" ")
        );
    }
    if all(|r| {
        matches!(
            r,
            Rejection::BelowMask { .. } | Rejection::SystemNotSelected
        )
    }) {
        return "every satellite is below the elevation mask (--mask-deg)".into();
    }
    format!(
        "satellites were rejected for mixed reasons ({} rejections)",
        rej.len()
    )
}
