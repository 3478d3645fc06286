//! The RTCM 3 message fields in the units of the navigation layer: the
//! broadcast ephemerides (1019, 1020, 1042, 1044, 1045, 1046) and the week
//! numbers, as the host's stream reader and the firmware's receiver both
//! read them. On the host `rtcm-rs` applies each data field's resolution
//! and sign (feature `rtcm-rs`: `glonass_fields`); on the device the
//! compact decoder ([`super::decode`]) does, with the same operations.

use raim_core::System;

use crate::ephemeris::{Kepler, WEEK_S};
#[cfg(feature = "rtcm-rs")]
use crate::glonass::GlonassIcdFields;

/// One light-millisecond, m (RTCM DF011/DF014 unit and the MSM range unit).
pub const LIGHT_MS_M: f64 = 299_792.458;

/// toc in GPS seconds from a broadcast's week (`week`, full GPS week),
/// toe and toc (seconds of that week): the toc placed within half a week
/// of the toe (the two may sit on either side of a week's end).
pub fn toc_near_toe(week: i64, toe_sow_s: f64, toc_sow_s: f64) -> f64 {
    let toe = week as f64 * WEEK_S + toe_sow_s;
    let mut toc = week as f64 * WEEK_S + toc_sow_s;
    if toc - toe > WEEK_S / 2.0 {
        toc -= WEEK_S;
    } else if toe - toc > WEEK_S / 2.0 {
        toc += WEEK_S;
    }
    toc
}

/// The full week congruent to `week_mod` modulo `modulus` in the window
/// `[pivot_week, pivot_week + modulus - 1]`: a receiver's week-rollover
/// pivot is the earliest week it can be operating in (its build date,
/// less a stated lookback), so a truncated week is never placed before it
/// (IS-GPS-200 20.3.3.3.1.1: the transmitted week is the full week modulo
/// 1024; RTCM 10403.3 DF076, DF289, DF489 carry 10, 12 and 13 bits).
/// `modulus` must be positive; a non-positive one places nothing and
/// returns `pivot_week` with `week_mod` added, which no caller passes.
pub fn week_from_pivot(week_mod: i64, modulus: i64, pivot_week: i64) -> i64 {
    if modulus <= 0 {
        return pivot_week.saturating_add(week_mod);
    }
    pivot_week + (week_mod - pivot_week).rem_euclid(modulus)
}

/// GPS week of the Galileo week 0 (GST starts 1999-08-22 00:00 GPS time,
/// Galileo OS SIS ICD 5.1.2).
pub const GST_WEEK0_GPS: i64 = 1024;
/// GPS week of the BeiDou week 0 (BDT starts 2006-01-01 00:00 UTC, GPS
/// time 14 s later; BDS-SIS-ICD-B1I 5.1.2).
pub const BDT_WEEK0_GPS: i64 = 1356;

/// The full GPS week of a Keplerian ephemeris' week as sent, placed from
/// the receiver's pivot (a GPS week) in the system's own week count:
/// GPS and QZSS send the GPS week modulo 1024 (DF076, DF452), Galileo the
/// GST week modulo 4096 (DF289), BeiDou the BDT week modulo 8192 (DF489),
/// each placed in `[pivot_week, ...]` by [`week_from_pivot`] and returned
/// as the GPS week of that system week's start. GLONASS sends no week:
/// its value is placed as a 10-bit GPS week, which no caller asks for.
pub fn gps_week_of(system: System, week_sent: u16, pivot_week: i64) -> i64 {
    let w = i64::from(week_sent);
    match system {
        System::Galileo => week_from_pivot(w, 4096, pivot_week - GST_WEEK0_GPS) + GST_WEEK0_GPS,
        System::Beidou => week_from_pivot(w, 8192, pivot_week - BDT_WEEK0_GPS) + BDT_WEEK0_GPS,
        System::Gps | System::Qzss | System::Glonass => week_from_pivot(w, 1024, pivot_week),
    }
}

/// The latest full week congruent to `week_mod` modulo `modulus` and not
/// after `now_week`: for a reader that knows the current week from a
/// clock (the host's replay of a live source), where a week number ahead
/// of the clock is a past rollover. The device has no clock and places
/// weeks from its pivot instead ([`week_from_pivot`]).
pub fn latest_week(week_mod: i64, modulus: i64, now_week: i64) -> i64 {
    let mut w = now_week - (now_week - week_mod).rem_euclid(modulus);
    if w < 0 {
        w = week_mod;
    }
    w
}

/// The ICD fields of a 1020 (RTCM 10403.3 Table 3.5-21) and its t_b as
/// seconds of the Moscow day. `rtcm-rs` applies each data field's
/// resolution, sign-magnitude coding and offset, as checked against the
/// standard: DF040 channel number minus 7 (k = -7..=13), DF110 t_b in
/// minutes (15-minute units), DF111/114/117 velocity km/s (2^-20),
/// DF112/115/118 position km (2^-11), DF113/116/119 luni-solar
/// acceleration km/s^2 (2^-30), DF121 gamma_n (2^-40), DF124 tau_n s
/// (2^-30). Unhealthy: the MSB of B_n (DF108) or the GLONASS-M l_n of
/// the third string (DF123). t_b (`tb_gps_s` here 0) is placed in GPS
/// time once the stream's week is known.
#[cfg(feature = "rtcm-rs")]
pub fn glonass_fields(m: &rtcm_rs::msg::Msg1020T) -> (GlonassIcdFields, f64) {
    let f = GlonassIcdFields {
        slot: m.glo_satellite_id,
        frequency_channel: m.glo_satellite_freq_chan_number,
        tb_gps_s: 0.0,
        x_km: m.xn_km,
        y_km: m.yn_km,
        z_km: m.zn_km,
        vx_km_s: m.xn_first_deriv_km_s,
        vy_km_s: m.yn_first_deriv_km_s,
        vz_km_s: m.zn_first_deriv_km_s,
        ax_km_s2: fx(m.xn_second_deriv_km_s2),
        ay_km_s2: fx(m.yn_second_deriv_km_s2),
        az_km_s2: fx(m.zn_second_deriv_km_s2),
        tau_n_s: m.tau_n_s,
        gamma_n: fx(m.gamma_n),
        unhealthy: m.glo_eph_health_flag != 0 || m.glo_m_3str_ln_flag != 0,
    };
    (f, f64::from(m.tb_min) * 60.0)
}

/// The [`KeplerFields`] of a 1019 from `rtcm-rs` (the host's reader).
#[cfg(feature = "rtcm-rs")]
pub fn msg1019_fields(m: &rtcm_rs::msg::Msg1019T) -> KeplerFields {
    KeplerFields {
        toc_s: fx(m.toc_s),
        toe_s: fx(m.toe_s),
        af0: fx(m.af0_s),
        af1: fx(m.af1_s_s),
        af2: fx(m.af2_s_s2),
        sqrt_a: fx(m.sqrt_a_sqrt_m),
        e: fx(m.eccentricity),
        i0_sc: fx(m.i0_sc),
        omega0_sc: fx(m.omega0_sc),
        omega_sc: fx(m.omega_sc),
        m0_sc: fx(m.m0_sc),
        delta_n_sc: fx(m.delta_n_sc_s),
        omega_dot_sc: fx(m.omegadot_sc_s),
        idot_sc: fx(m.idot_sc_s),
        cuc: fx(m.cuc_rad),
        cus: fx(m.cus_rad),
        crc: fx(m.crc_m),
        crs: fx(m.crs_m),
        cic: fx(m.cic_rad),
        cis: fx(m.cis_rad),
        tgd: fx(m.tgd_s),
        tgd2: 0.0,
        health: u32::from(m.sv_health_ind),
        iod: u32::from(m.iode),
    }
}

/// The [`KeplerFields`] of a 1044 (QZSS) from `rtcm-rs`: TGD (DF455) the
/// L1 C/A group delay, health DF454, IODE DF434.
#[cfg(feature = "rtcm-rs")]
pub fn msg1044_fields(m: &rtcm_rs::msg::Msg1044T) -> KeplerFields {
    KeplerFields {
        toc_s: fx(m.toc_s),
        toe_s: fx(m.toe_s),
        af0: fx(m.af0_s),
        af1: fx(m.af1_s_s),
        af2: fx(m.af2_s_s2),
        sqrt_a: fx(m.sqrt_a_sqrt_m),
        e: fx(m.eccentricity),
        i0_sc: fx(m.i0_sc),
        omega0_sc: fx(m.omega0_sc),
        omega_sc: fx(m.omega_sc),
        m0_sc: fx(m.m0_sc),
        delta_n_sc: fx(m.delta_n_sc_s),
        omega_dot_sc: fx(m.omegadot_sc_s),
        idot_sc: fx(m.idot_sc_s),
        cuc: fx(m.cuc_rad),
        cus: fx(m.cus_rad),
        crc: fx(m.crc_m),
        crs: fx(m.crs_m),
        cic: fx(m.cic_rad),
        cis: fx(m.cis_rad),
        tgd: fx(m.tgd_s),
        tgd2: 0.0,
        health: u32::from(m.sv_health_ind),
        iod: u32::from(m.iode),
    }
}

/// The [`KeplerFields`] of a 1045 (Galileo F/NAV) from `rtcm-rs`: F/NAV's
/// clock is the E1/E5a combination's, so BGD(E1,E5a) (DF312) serves E1
/// alone and the pair; health: E5a signal health (DF314) and data
/// validity (DF315) << 2; IODnav DF290.
#[cfg(feature = "rtcm-rs")]
pub fn msg1045_fields(m: &rtcm_rs::msg::Msg1045T) -> KeplerFields {
    let bgd = fx(m.bgd_e1_e5a_s);
    KeplerFields {
        toc_s: fx(m.toc_s),
        toe_s: fx(m.toe_s),
        af0: fx(m.af0_s),
        af1: fx(m.af1_s_s),
        af2: fx(m.af2_s_s2),
        sqrt_a: fx(m.sqrt_a_sqrt_m),
        e: fx(m.eccentricity),
        i0_sc: fx(m.i0_sc),
        omega0_sc: fx(m.omega0_sc),
        omega_sc: fx(m.omega_sc),
        m0_sc: fx(m.m0_sc),
        delta_n_sc: fx(m.delta_n_sc_s),
        omega_dot_sc: fx(m.omegadot_sc_s),
        idot_sc: fx(m.idot_sc_s),
        cuc: fx(m.cuc_rad),
        cus: fx(m.cus_rad),
        crc: fx(m.crc_m),
        crs: fx(m.crs_m),
        cic: fx(m.cic_rad),
        cis: fx(m.cis_rad),
        tgd: bgd,
        tgd2: bgd,
        health: u32::from(m.e5a_sig_health_ind) | (u32::from(m.e5a_data_validity_flag) << 2),
        iod: u32::from(m.iodnav),
    }
}

/// The [`KeplerFields`] of a 1046 (Galileo I/NAV) from `rtcm-rs`:
/// BGD(E1,E5b) (DF313) for E1 alone, BGD(E1,E5a) (DF312) for the E1/E5a
/// pair; health: E1-B health (DF287), validity (DF288) << 2, E5b health
/// (DF316) << 3, validity (DF317) << 5; IODnav DF290.
#[cfg(feature = "rtcm-rs")]
pub fn msg1046_fields(m: &rtcm_rs::msg::Msg1046T) -> KeplerFields {
    KeplerFields {
        toc_s: fx(m.toc_s),
        toe_s: fx(m.toe_s),
        af0: fx(m.af0_s),
        af1: fx(m.af1_s_s),
        af2: fx(m.af2_s_s2),
        sqrt_a: fx(m.sqrt_a_sqrt_m),
        e: fx(m.eccentricity),
        i0_sc: fx(m.i0_sc),
        omega0_sc: fx(m.omega0_sc),
        omega_sc: fx(m.omega_sc),
        m0_sc: fx(m.m0_sc),
        delta_n_sc: fx(m.delta_n_sc_s),
        omega_dot_sc: fx(m.omegadot_sc_s),
        idot_sc: fx(m.idot_sc_s),
        cuc: fx(m.cuc_rad),
        cus: fx(m.cus_rad),
        crc: fx(m.crc_m),
        crs: fx(m.crs_m),
        cic: fx(m.cic_rad),
        cis: fx(m.cis_rad),
        tgd: fx(m.bgd_e1_e5b_s),
        tgd2: fx(m.bgd_e1_e5a_s),
        health: u32::from(m.e1_b_sig_health_ind)
            | (u32::from(m.e1_b_data_validity_flag) << 2)
            | (u32::from(m.e5b_sig_health_ind) << 3)
            | (u32::from(m.e5b_data_validity_flag) << 5),
        iod: u32::from(m.iodnav),
    }
}

/// The [`KeplerFields`] of a 1042 (BeiDou) from `rtcm-rs`: a0-a2 the clock
/// terms, TGD1 (DF513) the B1I group delay, health DF515, AODE DF492.
#[cfg(feature = "rtcm-rs")]
pub fn msg1042_fields(m: &rtcm_rs::msg::Msg1042T) -> KeplerFields {
    KeplerFields {
        toc_s: fx(m.toc_s),
        toe_s: fx(m.toe_s),
        af0: fx(m.a0_s),
        af1: fx(m.a1_s_s),
        af2: fx(m.a2_s_s2),
        sqrt_a: fx(m.sqrt_a_sqrt_m),
        e: fx(m.eccentricity),
        i0_sc: fx(m.i0_sc),
        omega0_sc: fx(m.omega0_sc),
        omega_sc: fx(m.omega_sc),
        m0_sc: fx(m.m0_sc),
        delta_n_sc: fx(m.delta_n_sc_s),
        omega_dot_sc: fx(m.omegadot_sc_s),
        idot_sc: fx(m.idot_sc_s),
        cuc: fx(m.cuc_rad),
        cus: fx(m.cus_rad),
        crc: fx(m.crc_m),
        crs: fx(m.crs_m),
        cic: fx(m.cic_rad),
        cis: fx(m.cis_rad),
        tgd: fx(m.tgd1_s),
        tgd2: 0.0,
        health: u32::from(m.sv_health_flag),
        iod: u32::from(m.aode),
    }
}

/// A field of any numeric width as f64 (the crate's fields are f32 or f64
/// by their resolution).
pub fn fx<T: Into<f64>>(x: T) -> f64 {
    x.into()
}

/// The broadcast fields common to the Keplerian messages (angles in
/// semicircles as sent).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeplerFields {
    pub toc_s: f64,
    pub toe_s: f64,
    pub af0: f64,
    pub af1: f64,
    pub af2: f64,
    pub sqrt_a: f64,
    pub e: f64,
    pub i0_sc: f64,
    pub omega0_sc: f64,
    pub omega_sc: f64,
    pub m0_sc: f64,
    pub delta_n_sc: f64,
    pub omega_dot_sc: f64,
    pub idot_sc: f64,
    pub cuc: f64,
    pub cus: f64,
    pub crc: f64,
    pub crs: f64,
    pub cic: f64,
    pub cis: f64,
    pub tgd: f64,
    pub tgd2: f64,
    pub health: u32,
    pub iod: u32,
}

pub fn kepler(system: System, prn: u8, f: &KeplerFields) -> Kepler {
    let pi = core::f64::consts::PI;
    let _ = f.toc_s;
    Kepler {
        system,
        prn,
        toc_gps_s: 0.0,
        toe_sow_s: f.toe_s,
        af0_s: f.af0,
        af1_s_s: f.af1,
        af2_s_s2: f.af2,
        sqrt_a_m05: f.sqrt_a,
        e: f.e,
        i0_rad: f.i0_sc * pi,
        omega0_rad: f.omega0_sc * pi,
        omega_rad: f.omega_sc * pi,
        m0_rad: f.m0_sc * pi,
        delta_n_rad_s: f.delta_n_sc * pi,
        omega_dot_rad_s: f.omega_dot_sc * pi,
        idot_rad_s: f.idot_sc * pi,
        cuc_rad: f.cuc,
        cus_rad: f.cus,
        crc_m: f.crc,
        crs_m: f.crs,
        cic_rad: f.cic,
        cis_rad: f.cis,
        group_delay_s: f.tgd,
        group_delay_e5a_s: f.tgd2,
        health: f.health,
        iod: f.iod,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// GPS weeks at which the 10-bit week rolls over (1999-08-22,
    /// 2019-04-07, 2038-11-21), and 2447, the week of 2026-11-29.
    const GPS_ROLLOVERS: [i64; 3] = [1024, 2048, 3072];
    const TODAY_GPS_WEEK: i64 = 2447;

    /// Every week in `[pivot, pivot + modulus - 1]` is placed exactly,
    /// for truth weeks just before, at and just after each rollover, and
    /// at today's week, with the pivot at the truth week, a year before
    /// it, and as early as the window allows.
    fn placed_exactly(modulus: i64, truths: &[i64]) {
        for &truth in truths {
            for back in [0, 1, 52, modulus - 1] {
                let pivot = truth - back;
                let sent = truth.rem_euclid(modulus);
                assert_eq!(
                    week_from_pivot(sent, modulus, pivot),
                    truth,
                    "week {truth} sent as {sent} (mod {modulus}), pivot {pivot}"
                );
            }
        }
    }

    /// Verifies: RX-DATING
    #[test]
    fn gps_10_bit_weeks_around_each_rollover_and_today() {
        placed_exactly(1024, &[TODAY_GPS_WEEK]);
        for r in GPS_ROLLOVERS {
            placed_exactly(1024, &[r - 1, r, r + 1]);
        }
        // The case: week 2447 (2026-11-29) sent as 399 with the
        // old pivot 2400 read as the latest week not after it: 1423
        // (2007). Read from the pivot, it is 2447.
        assert_eq!(latest_week(2447 % 1024, 1024, 2400), 1423);
        assert_eq!(week_from_pivot(2447 % 1024, 1024, 2400), 2447);
    }

    /// Galileo's 12-bit week (DF289, GST weeks from 1999-08-22, rolling
    /// over in 2078) and BeiDou's 13-bit week (DF489, BDT weeks from
    /// 2006-01-01) are placed the same way, in their own week counts.
    ///
    /// Verifies: RX-DATING
    #[test]
    fn galileo_12_bit_and_beidou_13_bit_weeks() {
        // GST week of 2026-11-29 is GPS week 2447 - 1024.
        placed_exactly(4096, &[1423, 4095, 4096, 4097]);
        // BDT week of 2026-11-29 is GPS week 2447 - 1356.
        placed_exactly(8192, &[1091, 8191, 8192, 8193]);
    }

    /// A Keplerian message's week as sent, to the GPS week of its
    /// system week's start: GPS/QZSS 10 bits, Galileo 12-bit GST weeks
    /// (GPS week 1024 = GST 0), BeiDou 13-bit BDT weeks (GPS week 1356 =
    /// BDT 0), at today's week and around GPS's 2038 rollover, from a
    /// pivot a year before.
    ///
    /// Verifies: RX-DATING, RX-MULTI
    #[test]
    fn message_weeks_in_each_system_count() {
        for truth in [TODAY_GPS_WEEK, 3071, 3072, 3073] {
            let pivot = truth - 52;
            let sent = |w: i64, m: i64| u16::try_from(w.rem_euclid(m)).unwrap_or(u16::MAX);
            for s in [System::Gps, System::Qzss] {
                assert_eq!(gps_week_of(s, sent(truth, 1024), pivot), truth);
            }
            let gst = sent(truth - GST_WEEK0_GPS, 4096);
            assert_eq!(gps_week_of(System::Galileo, gst, pivot), truth);
            let bdt = sent(truth - BDT_WEEK0_GPS, 8192);
            assert_eq!(gps_week_of(System::Beidou, bdt, pivot), truth);
        }
        // 2026-11-29: GST week 1423, BDT week 1091.
        assert_eq!(gps_week_of(System::Galileo, 1423, 2395), 2447);
        assert_eq!(gps_week_of(System::Beidou, 1091, 2395), 2447);
    }

    /// A week before the pivot is never placed before it: it is read as
    /// the next rollover's, the receiver's own convention.
    #[test]
    fn a_week_before_the_pivot_is_placed_after_it() {
        let pivot = 2395;
        for truth in [1709, 2000, 2394] {
            let w = week_from_pivot(truth % 1024, 1024, pivot);
            assert!((pivot..pivot + 1024).contains(&w), "{truth} -> {w}");
            assert_eq!(w.rem_euclid(1024), truth.rem_euclid(1024));
        }
    }

    /// The degenerate modulus the function refuses to place with.
    #[test]
    fn non_positive_modulus_places_nothing() {
        assert_eq!(week_from_pivot(5, 0, 2400), 2405);
        assert_eq!(week_from_pivot(5, -1024, 2400), 2405);
    }
}
