//! Times at the I/O edge: a time of day `HH:MM[:SS]` relative to the day of
//! the first epoch, or seconds from the first epoch ("+600"), to GPS seconds.

use crate::error::GnssError;

/// Seconds in a day.
pub const DAY_S: f64 = 86_400.0;

/// Resolve `spec` against the first epoch's GPS time `first_gps_s`:
/// "HH:MM:SS" or "HH:MM" is that time of day (GPS time) on the first
/// epoch's day; "+S" is S seconds after the first epoch.
pub fn resolve(spec: &str, first_gps_s: f64) -> Result<f64, GnssError> {
    let bad = || GnssError::BadTime(spec.to_string());
    let s = spec.trim();
    if let Some(rel) = s.strip_prefix('+') {
        let v: f64 = rel.parse().map_err(|_| bad())?;
        return if v.is_finite() {
            Ok(first_gps_s + v)
        } else {
            Err(bad())
        };
    }
    let parts: Vec<&str> = s.split(':').collect();
    if !(2..=3).contains(&parts.len()) {
        return Err(bad());
    }
    let mut secs = 0.0;
    for (p, scale) in parts.iter().zip([3600.0, 60.0, 1.0]) {
        let v: f64 = p.parse().map_err(|_| bad())?;
        if !(0.0..=60.0 * 24.0).contains(&v) {
            return Err(bad());
        }
        secs += v * scale;
    }
    let day_start = (first_gps_s / DAY_S).floor() * DAY_S;
    Ok(day_start + secs)
}

/// "HH:MM:SS" of a GPS time (time of day in GPS time).
pub fn time_of_day(t_gps_s: f64) -> String {
    let s = t_gps_s.rem_euclid(DAY_S).round() as u64;
    format!("{:02}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60)
}

/// UTC time of day "hhmmss.ss" of a GPS time (leap seconds from hifitime),
/// for NMEA sentences.
pub fn utc_hhmmss(t_gps_s: f64) -> String {
    use rinex::prelude::{Epoch, TimeScale};
    let e = Epoch::from_gpst_seconds(t_gps_s).to_time_scale(TimeScale::UTC);
    let (_, _, _, h, m, s, ns) = e.to_gregorian_utc();
    format!("{h:02}{m:02}{:05.2}", s as f64 + ns as f64 * 1e-9)
}

/// UTC seconds since 1970-01-01 of a GPS time (leap seconds from hifitime):
/// the epoch time of the wire protocol (docs/PROTOCOL.md), from which the
/// firmware writes the NMEA time and date.
pub fn unix_utc_s(t_gps_s: f64) -> f64 {
    use rinex::prelude::{Epoch, TimeScale};
    Epoch::from_gpst_seconds(t_gps_s)
        .to_time_scale(TimeScale::UTC)
        .to_unix_seconds()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2020-06-25 00:00:00 GPST (ESBC's first epoch) is 2020-06-24
    /// 23:59:42 UTC (18 leap seconds), Unix 1593043182.
    #[test]
    fn unix_utc_of_a_gps_time() {
        // GPS week 2111, day 4 (Thursday) 00:00:00: 2111*604800 + 4*86400.
        let t_gps = 2111.0 * 604_800.0 + 4.0 * DAY_S;
        assert!(
            (unix_utc_s(t_gps) - 1_593_043_182.0).abs() < 1e-6,
            "{}",
            unix_utc_s(t_gps)
        );
    }

    #[test]
    fn resolves_time_of_day_and_offsets() {
        let first = 1_000.0 * DAY_S + 30.0;
        assert_eq!(
            resolve("00:20:00", first).unwrap(),
            1_000.0 * DAY_S + 1200.0
        );
        assert_eq!(resolve("01:00", first).unwrap(), 1_000.0 * DAY_S + 3600.0);
        assert_eq!(resolve("+60", first).unwrap(), first + 60.0);
        assert_eq!(time_of_day(1_000.0 * DAY_S + 2370.0), "00:39:30");
        assert!(matches!(
            resolve("1:2:3:4", first),
            Err(GnssError::BadTime(_))
        ));
        assert!(matches!(resolve("ab", first), Err(GnssError::BadTime(_))));
        // 2005-04-02 00:00:00 GPST is 2005-04-01 23:59:47 UTC (13 leap seconds).
        assert_eq!(utc_hhmmss(796_435_200.0), "235947.00");
    }
}
