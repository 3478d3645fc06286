//! GPS time and UTC: the leap seconds (GPS - UTC) as a table, so that the
//! device and the host date epochs alike without a calendar library.
//!
//! The table is the IERS Bulletin C list of leap seconds since the GPS
//! epoch (1980-01-06, when GPS - UTC was 0); each entry is the GPS time at
//! which the new offset takes effect (UTC midnight of the date plus the new
//! offset). No leap second has been announced after 2017-01-01 (Bulletin C
//! 72, July 2026); a later one needs a new row here. The host's tests check
//! the table against hifitime's (raim-gnss).
//!
//! **Expiry.** The table is known to hold only up to the date the last
//! Bulletin C reaches: Bulletin C 72 (July 2026) announced no leap second
//! at the end of December 2026, and the leap-second list issued with it
//! expires 2027-06-28 (NTP 4023129600; the next possible leap second is at
//! the end of June 2027). Source as read here: the IANA tz database's
//! `leapseconds` file, release 2026.6 (as packaged by the Python `tzdata`
//! 2026.6: "Updated through IERS Bulletin C", `#expires 1814140800
//! (2027-06-28 00:00:00 UTC)`, last leap second 2016-12-31). Past [`LEAP_TABLE_EXPIRES_GPS_S`] the table
//! is not used ([`table_gps_minus_utc_s`] says None): the count must then
//! come from the data (RTCM 1013 DF054, the GPS LNAV UTC parameters), or
//! whatever needs it (GLONASS, whose time is UTC-based) is refused.
//! Renewing the table with a later Bulletin C moves the expiry on.

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

/// GPS time (s since 1980-01-06) up to which the leap-second table is known to
/// hold: 2027-06-28 00:00:00 UTC (day 17,340 of GPS time, + 18 s), the
/// expiry of the leap-second list issued with IERS Bulletin C 72.
pub const LEAP_TABLE_EXPIRES_GPS_S: f64 = 17_340.0 * DAY_S + 18.0;

/// GPS - UTC from the table at GPS time `t_gps_s`, s, or None from
/// [`LEAP_TABLE_EXPIRES_GPS_S`] on (a leap second may have been
/// announced since the table was made).
pub fn table_gps_minus_utc_s(t_gps_s: f64) -> Option<f64> {
    (t_gps_s < LEAP_TABLE_EXPIRES_GPS_S).then(|| gps_minus_utc_s(t_gps_s))
}

/// GPS time minus UTC at GPS time `t_gps_s`, s (0 before 1981-07-01): the
/// table's latest count, also past its expiry (host tools that date by the
/// computer's clock; the device uses [`table_gps_minus_utc_s`]).
pub fn gps_minus_utc_s(t_gps_s: f64) -> f64 {
    let n = LEAP_GPS_S.iter().take_while(|&&t| t_gps_s >= t).count();
    n as f64
}

/// UTC seconds since 1970-01-01 of GPS time `t_gps_s` (the wire protocol's
/// epoch time, from which the NMEA time and date are written).
pub fn unix_utc_s(t_gps_s: f64) -> f64 {
    unix_utc_with_s(t_gps_s, gps_minus_utc_s(t_gps_s))
}

/// UTC seconds since 1970-01-01 of GPS time `t_gps_s` with GPS - UTC =
/// `gps_minus_utc_s` (the count in force, from the stream or the table).
pub fn unix_utc_with_s(t_gps_s: f64, gps_minus_utc_s: f64) -> f64 {
    t_gps_s + GPS_EPOCH_UNIX_S - gps_minus_utc_s
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

    /// The table's expiry is 2027-06-28 00:00:00 UTC (Unix 1814140800):
    /// the table answers up to the second before, not from it on.
    ///
    /// Verifies: RX-LEAP
    #[test]
    fn the_table_expires() {
        assert_eq!(
            unix_utc_s(LEAP_TABLE_EXPIRES_GPS_S),
            1_814_140_800.0,
            "2027-06-28 00:00:00 UTC"
        );
        assert_eq!(
            table_gps_minus_utc_s(LEAP_TABLE_EXPIRES_GPS_S - 1.0),
            Some(18.0)
        );
        assert_eq!(table_gps_minus_utc_s(LEAP_TABLE_EXPIRES_GPS_S), None);
        assert_eq!(table_gps_minus_utc_s(f64::NAN), None);
        assert_eq!(table_gps_minus_utc_s(1711.0 * 7.0 * DAY_S), Some(16.0));
        assert_eq!(unix_utc_with_s(0.0, 0.0), GPS_EPOCH_UNIX_S);
    }
}
