//! GPS time and UTC: the leap seconds (GPS - UTC) as a table, so that the
//! device and the host date epochs alike without a calendar library.
//!
//! The table is the IERS Bulletin C list of leap seconds since the GPS
//! epoch (1980-01-06, when GPS - UTC was 0); each entry is the GPS time at
//! which the new offset takes effect (UTC midnight of the date plus the new
//! offset). No leap second has been announced after 2017-01-01 (Bulletin C
//! 70, July 2025); a later one needs a new row here. The host's tests check
//! the table against hifitime's (raim-gnss).

/// Seconds in a day.
pub const DAY_S: f64 = 86_400.0;
/// Unix time (UTC seconds since 1970-01-01) of the GPS epoch 1980-01-06.
pub const GPS_EPOCH_UNIX_S: f64 = 315_964_800.0;

/// GPS time (s since 1980-01-06) at which GPS - UTC becomes its index + 1.
const LEAP_GPS_S: [f64; 18] = [
    542.0 * DAY_S + 1.0,    // 1981-07-01
    907.0 * DAY_S + 2.0,    // 1982-07-01
    1272.0 * DAY_S + 3.0,   // 1983-07-01
    2003.0 * DAY_S + 4.0,   // 1985-07-01
    2917.0 * DAY_S + 5.0,   // 1988-01-01
    3648.0 * DAY_S + 6.0,   // 1990-01-01
    4013.0 * DAY_S + 7.0,   // 1991-01-01
    4560.0 * DAY_S + 8.0,   // 1992-07-01
    4925.0 * DAY_S + 9.0,   // 1993-07-01
    5290.0 * DAY_S + 10.0,  // 1994-07-01
    5839.0 * DAY_S + 11.0,  // 1996-01-01
    6386.0 * DAY_S + 12.0,  // 1997-07-01
    6935.0 * DAY_S + 13.0,  // 1999-01-01
    9492.0 * DAY_S + 14.0,  // 2006-01-01
    10588.0 * DAY_S + 15.0, // 2009-01-01
    11865.0 * DAY_S + 16.0, // 2012-07-01
    12960.0 * DAY_S + 17.0, // 2015-07-01
    13510.0 * DAY_S + 18.0, // 2017-01-01
];

/// GPS time minus UTC at GPS time `t_gps_s`, s (0 before 1981-07-01).
pub fn gps_minus_utc_s(t_gps_s: f64) -> f64 {
    let n = LEAP_GPS_S.iter().take_while(|&&t| t_gps_s >= t).count();
    n as f64
}

/// UTC seconds since 1970-01-01 of GPS time `t_gps_s` (the wire protocol's
/// epoch time, from which the NMEA time and date are written).
pub fn unix_utc_s(t_gps_s: f64) -> f64 {
    t_gps_s + GPS_EPOCH_UNIX_S - gps_minus_utc_s(t_gps_s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The offsets the GPS ICD and RINEX headers quote: 0 at the GPS
    /// epoch, 13 in 2005, 16 in October 2012, 18 since 2017.
    #[test]
    fn known_offsets() {
        assert_eq!(gps_minus_utc_s(0.0), 0.0);
        assert_eq!(gps_minus_utc_s(25.0 * 365.25 * DAY_S), 13.0);
        assert_eq!(gps_minus_utc_s(1711.0 * 7.0 * DAY_S), 16.0);
        assert_eq!(gps_minus_utc_s(2400.0 * 7.0 * DAY_S), 18.0);
        // The leap itself: one second before the 2017 entry, still 17.
        assert_eq!(gps_minus_utc_s(13510.0 * DAY_S + 17.0), 17.0);
        assert_eq!(gps_minus_utc_s(13510.0 * DAY_S + 18.0), 18.0);
    }
}
