//! Navigation paths the other tests leave out (issue 37, structural
//! coverage, second pass), through the public API: GLONASS time and a
//! GLONASS set without a t_b, and the ephemeris store's repeats,
//! replacements, choice among sets and decoded sets of an older store.
extern crate std;

use std::vec::Vec;

use raim_core::{SatId, System};

use crate::ephemeris::{Kepler, WEEK_S};
use crate::glonass::{
    glonass_from_gps_s, glonass_time_of_day_to_gps_with_s, GlonassEphemeris, GlonassIcdFields,
};
use crate::ranging::Broadcast;
use crate::rtcm::decode::kepler_message;
use crate::rtcm::fields::kepler;
use crate::store::{DecodedSets, EphemerisStore, Stored};
use crate::NavError;

/// GLONASS time is UTC(SU) + 3 h: GPS time less GPS - UTC (15 s in 2012
/// before 1 July, 16 s after; IERS Bulletin C 43) plus 10,800 s. GPS week
/// 1669 starts on 2012-01-01, week 1710 on 2012-10-14.
#[test]
fn glonass_time_follows_the_leap_second_table() {
    let jan = 1669.0 * WEEK_S;
    let oct = 1710.0 * WEEK_S;
    assert_eq!(glonass_from_gps_s(jan), jan - 15.0 + 10_800.0);
    assert_eq!(glonass_from_gps_s(oct), oct - 16.0 + 10_800.0);
}

/// A t_b of 23:45 Moscow time carried by a message received at 00:30
/// Moscow time is the previous day's (within 12 h of the reception), and
/// a t_b of 00:15 received at 23:30 is the next day's.
#[test]
fn a_time_of_day_is_placed_on_the_day_nearest_its_reception() {
    let leap_s = 16.0;
    // GPS time of Moscow midnight starting GLONASS day `d`.
    let midnight = |d: f64| d * 86_400.0 + leap_s - 10_800.0;
    let d = 15_000.0;
    let got = glonass_time_of_day_to_gps_with_s(85_500.0, midnight(d) + 1_800.0, leap_s);
    assert_eq!(got, midnight(d) - 900.0);
    let got = glonass_time_of_day_to_gps_with_s(900.0, midnight(d) - 1_800.0, leap_s);
    assert_eq!(got, midnight(d) + 900.0);
}

/// A GLONASS set's ICD fields: slot `slot`, channel 1, t_b at `tb_gps_s`,
/// a plausible orbit (about 19,100 km from the centre, 3.9 km/s).
fn icd(slot: u8, tb_gps_s: f64) -> GlonassIcdFields {
    GlonassIcdFields {
        slot,
        frequency_channel: 1,
        tb_gps_s,
        x_km: 10_000.0,
        y_km: -15_000.0,
        z_km: 6_000.0,
        vx_km_s: 1.5,
        vy_km_s: 0.8,
        vz_km_s: -3.4,
        ax_km_s2: 0.0,
        ay_km_s2: 0.0,
        az_km_s2: 0.0,
        tau_n_s: 1e-5,
        gamma_n: 0.0,
        unhealthy: false,
    }
}

/// A set whose t_b is not a finite time (not yet placed) is refused with
/// the field and value; a placed one is a GLONASS set.
#[test]
fn a_glonass_set_needs_a_finite_tb() {
    let e = GlonassEphemeris::from_icd(&icd(3, f64::NAN)).unwrap_err();
    assert!(
        matches!(e, NavError::OutOfRange { field: "tb_gps_s", value, .. } if value.is_nan()),
        "{e:?}"
    );
    let e = GlonassEphemeris::from_icd(&icd(3, f64::INFINITY)).unwrap_err();
    assert!(
        matches!(
            e,
            NavError::OutOfRange {
                field: "tb_gps_s",
                ..
            }
        ),
        "{e:?}"
    );
    let g = GlonassEphemeris::from_icd(&icd(3, 1e9)).unwrap();
    assert_eq!(g.system(), System::Glonass);
    assert_eq!(g.position_m, [10_000e3, -15_000e3, 6_000e3]);
}

/// The GLONASS sets of a store of two: a repeat changes nothing, a third
/// set replaces the one with the oldest t_b (wherever it is), and a
/// satellite's set is the one whose t_b is nearest the time asked, up to
/// 30 min (`max_ephemeris_age_s`).
#[test]
fn glonass_sets_repeat_replace_the_oldest_and_the_nearest_is_chosen() {
    let t0 = 1e9;
    let g = |slot, dt: f64| GlonassEphemeris::from_icd(&icd(slot, t0 + dt)).unwrap();
    let mut s = EphemerisStore::<4, 2>::new();
    assert_eq!(s.insert_glonass(g(5, 1_800.0)), Stored::Added);
    assert_eq!(s.insert_glonass(g(5, 0.0)), Stored::Added);
    assert_eq!(s.insert_glonass(g(5, 0.0)), Stored::Repeat);
    assert_eq!(s.len(), (0, 2));
    let id = SatId::new(System::Glonass, 5);
    let d = DecodedSets::<4>::new();
    let tb_of = |s: &EphemerisStore<4, 2>, t: f64| match s.select(id, t, &d) {
        Some(Broadcast::Glonass(x)) => Some(x.tb_gps_s - t0),
        Some(other) => panic!("{other:?}"),
        None => None,
    };
    let tb = |t: f64| tb_of(&s, t);
    assert_eq!(tb(t0 + 300.0), Some(0.0));
    assert_eq!(tb(t0 + 1_500.0), Some(1_800.0));
    assert_eq!(tb(t0 - 1_800.0), Some(0.0));
    assert_eq!(tb(t0 - 1_801.0), None);
    // Full: the set of t_b + 0 (the second) is the oldest.
    assert_eq!(s.insert_glonass(g(6, 900.0)), Stored::Replaced);
    assert_eq!(tb_of(&s, t0 + 300.0), Some(1_800.0));
    assert_eq!(s.len(), (0, 2));
    let six = SatId::new(System::Glonass, 6);
    assert!(matches!(s.select(six, t0 + 900.0, &d), Some(Broadcast::Glonass(x)) if x.slot == 6));
}

/// GMSD7's first 1019 payload (RTCM 10403.3 §3.5.11).
fn gmsd7_1019() -> Vec<u8> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/GMSD7_20121014.rtcm3"
    );
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut i = 0;
    while i + 6 <= bytes.len() {
        if bytes[i] != 0xD3 {
            i += 1;
            continue;
        }
        let len = (usize::from(bytes[i + 1] & 0x03) << 8) | usize::from(bytes[i + 2]);
        let p = &bytes[i + 3..i + 3 + len];
        if len >= 2 && (u16::from(p[0]) << 4 | u16::from(p[1]) >> 4) == 1019 {
            return p.to_vec();
        }
        i += 6 + len;
    }
    panic!("no 1019 in {path}")
}

/// The set of a payload as the receiver takes it: decoded, toc in GPS
/// seconds of GMSD7's week 1709.
fn set_of(payload: &[u8]) -> Kepler {
    let m = kepler_message(payload).unwrap();
    let mut k = kepler(m.system, m.prn, &m.fields);
    k.toc_gps_s = 1709.0 * WEEK_S + m.fields.toc_s;
    k
}

/// A set that its payload does not decode to (here the GPS set relabelled
/// Galileo: the keys of the GPS set held differ by system) is not kept,
/// and says how long the payload was.
#[test]
fn a_set_its_payload_does_not_give_is_not_kept() {
    let p = gmsd7_1019();
    let k = set_of(&p);
    let mut s = EphemerisStore::<4, 2>::new();
    assert_eq!(s.insert_kepler(k, &p), Stored::Added);
    let galileo = Kepler {
        system: System::Galileo,
        ..k
    };
    assert_eq!(
        s.insert_kepler(galileo, &p),
        Stored::NotKept {
            payload_len: p.len() as u16
        }
    );
    assert_eq!(s.len(), (1, 0));
}

/// Decoded sets of an older store (another generation) are started again
/// by `load`, which then decodes the set `select` gives: the one inserted.
#[test]
fn load_restarts_decoded_sets_of_an_older_store() {
    let p = gmsd7_1019();
    let k = set_of(&p);
    let id = SatId::new(k.system, k.prn);
    let mut s = EphemerisStore::<4, 2>::new();
    assert_eq!(s.insert_kepler(k, &p), Stored::Added);
    let mut d = DecodedSets::<4>::new();
    assert_eq!(s.select(id, k.toc_gps_s, &d), None);
    s.load(id, k.toc_gps_s, &mut d).unwrap();
    assert_eq!(s.select(id, k.toc_gps_s, &d), Some(Broadcast::Kepler(&k)));
}

/// Seven GPS satellites 2e7 m above a receiver on the equator at the
/// prime meridian (ECEF x up, y east, z north), pushed sideways, with
/// exact ranges plus a 3e4 m clock; the receiver's position.
fn equator_sky() -> (Vec<raim_core::RangeObservation>, [f64; 3]) {
    let rx = [raim_core::frames::WGS84_A_M, 0.0, 0.0];
    let sats = [
        (0.0, 0.0),
        (1.2e7, 0.3e7),
        (-1.0e7, 0.8e7),
        (0.2e7, -1.1e7),
        (0.9e7, 0.9e7),
        (-0.7e7, -0.6e7),
        (0.4e7, 1.3e7),
    ]
    .iter()
    .enumerate()
    .map(|(k, &(e, n))| {
        let p = [rx[0] + 2.0e7, e, n];
        let d = ((p[0] - rx[0]).powi(2) + p[1].powi(2) + p[2].powi(2)).sqrt();
        raim_core::RangeObservation {
            id: SatId::new(System::Gps, k as u8 + 1),
            pseudorange_m: d + 3.0e4,
            position_m: p,
            sigma_m: None,
        }
    })
    .collect();
    (sats, rx)
}

fn distance_m(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Host sigmas weigh the bootstrap's fit in place of the elevation
/// model: exact ranges still give the point back (to 1 mm), whatever
/// the (equal) weights.
#[test]
fn the_bootstrap_takes_host_sigmas() {
    use crate::bootstrap::bootstrap_position;
    let (mut sats, rx) = equator_sky();
    for s in &mut sats {
        s.sigma_m = Some(2.5);
    }
    let got = bootstrap_position::<32>(&sats, None).unwrap();
    assert!(distance_m(got, rx) < 1e-3, "{}", distance_m(got, rx));
}

/// The bootstrap gives no position (its documented refusals) for: a
/// satellite at the starting point (no line of sight), a satellite
/// position that is not a number, a sigma that is not positive, a
/// pseudorange that is not a number (no finite step), satellites all at
/// one point (singular normal equations), and ranges that put the
/// receiver at the Earth's centre (it converges there, where no weights
/// apply, and gives up after its iterations).
#[test]
fn the_bootstrap_refuses_what_gives_no_position() {
    use crate::bootstrap::bootstrap_position;
    let (sats, _) = equator_sky();
    let at_sat = Some(sats[2].position_m);
    assert_eq!(bootstrap_position::<32>(&sats, at_sat), None);

    let mut nan_pos = sats.clone();
    nan_pos[1].position_m[2] = f64::NAN;
    assert_eq!(bootstrap_position::<32>(&nan_pos, None), None);

    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut s = sats.clone();
        s[4].sigma_m = Some(bad);
        assert_eq!(bootstrap_position::<32>(&s, None), None, "sigma {bad}");
    }

    let mut nan_range = sats.clone();
    nan_range[3].pseudorange_m = f64::NAN;
    assert_eq!(bootstrap_position::<32>(&nan_range, None), None);

    let mut one_point = sats.clone();
    for s in &mut one_point {
        s.position_m = sats[0].position_m;
    }
    assert_eq!(bootstrap_position::<32>(&one_point, None), None);

    let mut centre = sats.clone();
    for s in &mut centre {
        s.pseudorange_m = distance_m(s.position_m, [0.0; 3]) + 3.0e4;
    }
    assert_eq!(bootstrap_position::<32>(&centre, None), None);
    // The same ranges solved from the receiver's side of the Earth.
    let (_, rx) = equator_sky();
    let got = bootstrap_position::<32>(&sats, Some(rx)).unwrap();
    assert!(distance_m(got, rx) < 1e-3);
}

/// `payload` with the `width`-bit field at bit `at` raised by `add`.
fn with_field_added(payload: &[u8], at: usize, width: usize, add: u64) -> Vec<u8> {
    let mut p = payload.to_vec();
    let mut v = 0u64;
    for k in at..at + width {
        v = (v << 1) | u64::from((p[k / 8] >> (7 - k % 8)) & 1);
    }
    v += add;
    for (i, k) in (at..at + width).enumerate() {
        let bit = (v >> (width - 1 - i)) & 1;
        p[k / 8] = (p[k / 8] & !(0x80 >> (k % 8))) | ((bit as u8) << (7 - k % 8));
    }
    p
}

/// Of two sets of one satellite an hour apart (GMSD7's first 1019, and
/// the same with toc, DF081 at bit 56, and toe, DF093 at bit 288, each
/// 16 bits of 16 s, raised by 225 = 3,600 s), the store gives the one
/// whose toe is nearer the time asked, whichever was inserted first.
#[test]
fn the_store_gives_the_set_nearest_in_time() {
    let p1 = gmsd7_1019();
    let p2 = with_field_added(&with_field_added(&p1, 56, 16, 225), 288, 16, 225);
    let (k1, k2) = (set_of(&p1), set_of(&p2));
    assert_eq!(k2.toe_sow_s - k1.toe_sow_s, 3_600.0);
    let id = SatId::new(k1.system, k1.prn);
    for order in [[(k1, &p1), (k2, &p2)], [(k2, &p2), (k1, &p1)]] {
        let mut s = EphemerisStore::<4, 2>::new();
        for (k, p) in order {
            assert_eq!(s.insert_kepler(k, p), Stored::Added);
        }
        for (t, want) in [(k1.toc_gps_s - 600.0, k1), (k2.toc_gps_s + 600.0, k2)] {
            let mut d = DecodedSets::<4>::new();
            s.start_epoch(&mut d);
            s.load(id, t, &mut d).unwrap();
            assert_eq!(s.select(id, t, &d), Some(Broadcast::Kepler(&want)));
        }
    }
}

/// A store of no GLONASS capacity keeps nothing: each set is `Replaced`
/// (its documented answer) and the store stays empty.
#[test]
fn a_store_of_no_capacity_keeps_nothing() {
    let mut s = EphemerisStore::<4, 0>::new();
    let g = GlonassEphemeris::from_icd(&icd(2, 1e9)).unwrap();
    assert_eq!(s.insert_glonass(g), Stored::Replaced);
    assert_eq!(s.len(), (0, 0));
    assert!(s.is_empty());
}

/// A Keplerian broadcast's clock alone is its state's clock to the bit
/// (`Broadcast::clock_s`, the receiver's transmit-time iteration).
#[test]
fn a_kepler_broadcast_clock_is_its_states() {
    let k = set_of(&gmsd7_1019());
    let b = Broadcast::Kepler(&k);
    for dt in [-3_000.0, 0.0, 1_234.5] {
        let t = k.toc_gps_s + dt;
        assert_eq!(b.clock_s(t).to_bits(), b.state(t).clock_s.to_bits());
    }
}

/// The state at the transmit time (IS-GPS-200 20.3.3.3.3.1: t = t_sv -
/// dt_sv(t_sv)): with a clock offset of 0.5 s, beyond the one Newton
/// step's reach (the orbit moves 7e-5 rad in it, the step is taken up to
/// 2e-5 rad), the state is solved at t again; with GMSD7's own offset it
/// is the step. Either way it is the state at t (to 1 um).
#[test]
fn the_transmit_state_is_the_state_at_the_transmit_time() {
    let k0 = set_of(&gmsd7_1019());
    for af0_s in [k0.af0_s, 0.5] {
        let k = Kepler { af0_s, ..k0 };
        let t_sv = k.toc_gps_s + 1_000.0;
        let (t, s) = k.transmit_state(t_sv);
        assert_eq!(t, t_sv - k.clock_s(t_sv));
        let want = k.state(t);
        let d = distance_m(s.position_m, want.position_m);
        assert!(d < 1e-6, "af0 {af0_s}: {d} m");
        assert_eq!(s.clock_s, want.clock_s);
    }
}

/// A set whose eccentricity is not a number gives a state and clock that
/// are not numbers (the checks downstream refuse them) rather than loop or
/// panic: the Kepler solution stops at its first step.
#[test]
fn an_eccentricity_that_is_not_a_number_gives_no_number() {
    let k = Kepler {
        e: f64::NAN,
        ..set_of(&gmsd7_1019())
    };
    let t = k.toc_gps_s + 100.0;
    assert!(k.state(t).position_m.iter().all(|v| v.is_nan()));
    assert!(k.clock_s(t).is_nan());
    let (tt, s) = k.transmit_state(t);
    assert!(tt.is_nan() && s.position_m.iter().all(|v| v.is_nan()));
}
