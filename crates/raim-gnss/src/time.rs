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

/// UTC seconds since 1970-01-01 of a GPS time: the epoch time of the wire
/// protocol (docs/PROTOCOL.md), from which the firmware writes the NMEA
/// time and date. raim-nav's leap-second table, the one the firmware
/// dates its own epochs with (checked against hifitime below).
pub fn unix_utc_s(t_gps_s: f64) -> f64 {
    raim_nav::time::unix_utc_s(t_gps_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// raim-nav's leap-second table against hifitime's (an independent
    /// implementation, through the `rinex` crate), every 5 days from the
    /// GPS epoch to 2030 and a minute either side of every leap. Within a
    /// minute of a leap hifitime steps at a slightly different instant
    /// (by up to the offset itself): the
    /// table steps at the leap itself (UTC midnight, GPS = UTC + the new
    /// offset), as IS-GPS-200 20.3.3.5.2.4 defines it.
    #[test]
    fn leap_seconds_match_hifitime() {
        /// hifitime's rounding of a fractional second, s.
        const FRACTION_TOL_S: f64 = 1e-6;
        use rinex::prelude::{Epoch, TimeScale};
        let hifi = |t: f64| {
            Epoch::from_gpst_seconds(t)
                .to_time_scale(TimeScale::UTC)
                .to_unix_seconds()
        };
        let leaps: Vec<f64> = (1..=18)
            .map(|leap| {
                (0..60 * 366 * 86_400_i64)
                    .step_by(86_400)
                    .map(|s| s as f64)
                    .find(|&s| raim_nav::time::gps_minus_utc_s(s + 86_399.0) >= f64::from(leap))
                    .unwrap()
            })
            .collect();
        let near_leap = |t: f64| leaps.iter().any(|&l| (t - l).abs() < 60.0);
        let mut t = 0.0;
        let mut n = 0;
        while t < 50.0 * 365.25 * DAY_S {
            if !near_leap(t) {
                assert_eq!(unix_utc_s(t), hifi(t), "GPS {t} s");
                // hifitime rounds a fraction through its own f64 steps.
                let d = unix_utc_s(t + 0.25) - hifi(t + 0.25);
                assert!(d.abs() < FRACTION_TOL_S, "GPS {t} s + 0.25: {d}");
                n += 1;
            }
            t += 5.0 * DAY_S;
        }
        assert!(n > 3000, "{n}");
        for (i, &day) in leaps.iter().enumerate() {
            // The leap is at the day's start (UTC) + the new offset.
            let at = day + (i + 1) as f64;
            for dt in [-2.0 * DAY_S, -60.0, 60.0, 2.0 * DAY_S] {
                let t = at + dt;
                assert_eq!(unix_utc_s(t), hifi(t), "leap {}, GPS {t} s", i + 1);
            }
            // Either side of the leap, the table's offsets differ by one.
            assert_eq!(
                raim_nav::time::gps_minus_utc_s(at) - raim_nav::time::gps_minus_utc_s(at - 1.0),
                1.0
            );
        }
    }

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
