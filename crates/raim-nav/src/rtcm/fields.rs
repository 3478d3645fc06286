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

/// The latest full week congruent to `week_mod` modulo `modulus` and not
/// after `now_week` (a week number ahead of the clock is a past rollover).
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
