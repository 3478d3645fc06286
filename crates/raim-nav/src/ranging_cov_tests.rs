//! The ranging corrections' branches that the stream tests leave out
//! (issue 37, structural coverage), each against a number from outside
//! the code: the signal plan's carriers (IS-GPS-200, Galileo OS SIS ICD,
//! BDS ICD), the Klobuchar model's night-time term (IS-GPS-200
//! 20.3.3.5.2.5: 5 ns times the obliquity factor F = 1 + 16 (0.53 - E)^3,
//! E the elevation in semicircles, whatever the coefficients when they
//! are all zero), the broadcast group delay times c.

use super::*;
use crate::ephemeris::circular;

/// Galileo E5 AltBOC and E6, and a band no system here has.
#[test]
fn galileo_e5_and_e6_carriers_and_unknown_bands() {
    assert_eq!(band_hz(System::Galileo, "C8Q"), Some(1_191.795e6));
    assert_eq!(band_hz(System::Galileo, "C6C"), Some(1_278.75e6));
    assert_eq!(band_hz(System::Galileo, "C2C"), None);
    assert_eq!(band_hz(System::Gps, "C"), None);
}

/// A pair whose first code is not the higher frequency (or the same
/// band twice) has no combination.
#[test]
fn a_pair_in_the_wrong_order_has_no_combination() {
    assert_eq!(iono_free(System::Gps, "C2W+C1C", 2.0e7, 2.0e7, None), None);
    assert_eq!(iono_free(System::Gps, "C1C+C1W", 2.0e7, 2.0e7, None), None);
    assert_eq!(iono_free(System::Gps, "C1C+C9X", 2.0e7, 2.0e7, None), None);
    assert!(iono_free(System::Gps, "C1C+C2W", 2.0e7, 2.0e7, None).is_some());
}

/// The carrier of the iono scaling: BeiDou B1I (1561.098 MHz) for the
/// band-1/2 I codes, L1 for B1C and for the other systems.
#[test]
fn beidou_b1i_codes_scale_with_their_carrier() {
    assert_eq!(carrier_hz(System::Beidou, "C2I", None), 1_561.098e6);
    assert_eq!(carrier_hz(System::Beidou, "C1I", None), 1_561.098e6);
    assert_eq!(carrier_hz(System::Beidou, "C1P", None), 1_575.42e6);
    assert_eq!(carrier_hz(System::Gps, "C5Q", None), 1_575.42e6);
}

/// The broadcast group delay is defined for GPS/QZSS L1 C/A (TGD),
/// Galileo E1 (BGD E1/E5b) and BeiDou B1I (TGD1) only.
#[test]
fn group_delay_applies_to_the_codes_it_is_broadcast_for() {
    for (system, code, want) in [
        (System::Gps, "C1C", true),
        (System::Gps, "C1", true),
        (System::Gps, "C2W", false),
        (System::Qzss, "C1C", true),
        (System::Galileo, "C1X", true),
        (System::Galileo, "C5Q", false),
        (System::Beidou, "C2I", true),
        (System::Beidou, "C1I", true),
        (System::Beidou, "C7I", false),
        (System::Glonass, "C1C", false),
    ] {
        assert_eq!(group_delay_applies(system, code), want, "{system:?} {code}");
    }
}

/// A receiver on the equator under a satellite of [`circular`] (GPS
/// week 1000, its toe), at the Earth's surface below it.
fn overhead(k: &Kepler) -> (f64, [f64; 3]) {
    let t = 1000.0 * WEEK_S;
    let p = k.state(t).position_m;
    let r = distance_m(p, [0.0; 3]);
    let rx = [
        p[0] / r * raim_core::frames::WGS84_A_M,
        p[1] / r * raim_core::frames::WGS84_A_M,
        p[2] / r * raim_core::frames::WGS84_A_M,
    ];
    (t, rx)
}

fn corrections(group_delay: bool, iono: bool) -> Corrections {
    Corrections {
        elevation_mask_rad: 0.0,
        iono,
        tropo: false,
        group_delay,
        glonass_sigma: None,
    }
}

/// Klobuchar's night-time delay with all coefficients zero (5 ns times
/// the obliquity factor at the elevation), on L1.
fn night_l1_m(el_rad: f64) -> f64 {
    let e = el_rad / core::f64::consts::PI;
    C_M_S * 5e-9 * (1.0 + 16.0 * (0.53 - e).powi(3))
}

/// Single-frequency ranges: the group delay is c TGD on GPS C1C and
/// nothing on GPS C5Q; the Klobuchar delay is the night-time term on L1,
/// scaled by (f_L1 / f_B1I)^2 on BeiDou B1I.
#[test]
fn single_frequency_ranges_take_the_group_delay_and_the_klobuchar_delay() {
    let tgd_s = 5e-9;
    let gps = Kepler {
        group_delay_s: tgd_s,
        ..circular(System::Gps, 3)
    };
    let (t, rx) = overhead(&gps);
    let kb = Klobuchar {
        alpha: [0.0; 4],
        beta: [0.0; 4],
    };
    let input = |code, k: &'static Kepler| SatInput {
        id: SatId::new(k.system, k.prn),
        code,
        p1_m: 2.0e7,
        p2_m: None,
        eph: Broadcast::Kepler(k),
        orbit_arc: false,
    };
    let gps: &'static Kepler = std::boxed::Box::leak(std::boxed::Box::new(gps));
    let c = correct(
        &input("C1C", gps),
        t,
        Some(rx),
        true,
        &corrections(true, true),
        Some(&kb),
    )
    .unwrap();
    assert!((c.group_delay_m - C_M_S * tgd_s).abs() < 1e-9, "{c:?}");
    // Overhead but for the Earth's rotation during the transit (~260 m).
    assert!(
        (c.elevation_rad - core::f64::consts::FRAC_PI_2).abs() < 1e-4,
        "{c:?}"
    );
    assert!(
        (c.iono_m - night_l1_m(c.elevation_rad)).abs() < 1e-9,
        "{c:?}"
    );
    assert_eq!(c.tropo_m, 0.0);
    // No Klobuchar: no iono term.
    let c = correct(
        &input("C1C", gps),
        t,
        Some(rx),
        true,
        &corrections(true, true),
        None,
    )
    .unwrap();
    assert_eq!(c.iono_m, 0.0);
    let c = correct(
        &input("C5Q", gps),
        t,
        Some(rx),
        true,
        &corrections(true, false),
        None,
    )
    .unwrap();
    assert_eq!(c.group_delay_m, 0.0);

    let bds: &'static Kepler = std::boxed::Box::leak(std::boxed::Box::new(Kepler {
        group_delay_s: tgd_s,
        ..circular(System::Beidou, 20)
    }));
    let (t, rx) = overhead(bds);
    let c = correct(
        &input("C2I", bds),
        t,
        Some(rx),
        true,
        &corrections(true, true),
        Some(&kb),
    )
    .unwrap();
    let r = 1_575.42e6 / 1_561.098e6;
    assert!(
        (c.iono_m - night_l1_m(c.elevation_rad) * r * r).abs() < 1e-9,
        "{c:?}"
    );
    assert!((c.group_delay_m - C_M_S * tgd_s).abs() < 1e-9, "{c:?}");
}

/// The broadcast's accessors: a Keplerian ephemeris has no FDMA channel,
/// and its state is the ephemeris' own.
#[test]
fn a_kepler_broadcast_has_no_channel() {
    let k = circular(System::Gps, 1);
    let b = Broadcast::Kepler(&k);
    assert_eq!(b.frequency_channel(), None);
    let t = 1000.0 * WEEK_S + 60.0;
    assert_eq!(b.state(t), k.state(t));
}

/// The bootstrap solution needs 4 satellites and at most its capacity.
#[test]
fn the_bootstrap_refuses_too_few_or_too_many_satellites() {
    let o = RangeObservation {
        id: SatId::new(System::Gps, 1),
        pseudorange_m: 2.0e7,
        position_m: [2.6e7, 0.0, 0.0],
        sigma_m: None,
    };
    assert_eq!(
        crate::bootstrap::bootstrap_position::<4>(&[o; 3], None),
        None
    );
    assert_eq!(
        crate::bootstrap::bootstrap_position::<4>(&[o; 5], None),
        None
    );
}

/// C/N0 in whole dB-Hz for GSV: rounded half away from zero, 255 at most,
/// 0 for unknown, not finite or under 0.5 dB-Hz.
#[test]
fn cn0_rounds_and_saturates() {
    assert_eq!(cn0_dbhz_u8(Some(42.5)), 43);
    assert_eq!(cn0_dbhz_u8(Some(254.4)), 254);
    assert_eq!(cn0_dbhz_u8(Some(254.5)), 255);
    assert_eq!(cn0_dbhz_u8(Some(1e6)), 255);
    assert_eq!(cn0_dbhz_u8(Some(0.4)), 0);
    assert_eq!(cn0_dbhz_u8(Some(f64::NAN)), 0);
    assert_eq!(cn0_dbhz_u8(Some(f64::INFINITY)), 0);
    assert_eq!(cn0_dbhz_u8(None), 0);
}

/// A single-frequency GLONASS range with a GLONASS model: that model
/// with its residual ionosphere times the stream's factor (the variance
/// grows by (f^2 - 1) times the iono term's at the same elevation); the
/// snapshot stream sigma of a single-frequency GPS range the same on the
/// configuration's model.
#[test]
fn single_frequency_stream_sigmas_scale_the_residual_ionosphere() {
    let model = SigmaModel::default();
    let el = 0.6;
    let one = stream_sigma_m(System::Glonass, "C1C", el, &model, Some(&model), 1.0).unwrap();
    let two = stream_sigma_m(System::Glonass, "C1C", el, &model, Some(&model), 2.0).unwrap();
    let zero = SigmaModel {
        iono_vertical_m: 0.0,
        ..model
    }
    .sigma_m(el);
    let iono2 = one * one - zero * zero;
    assert!(iono2 > 0.0);
    assert!(
        // f32 sigmas (1e-6 relative, `stream_sigmas_in_f32_are_the_f64_ones`)
        // on variances of tens of m^2.
        (two * two - one * one - 3.0 * iono2).abs() < 1e-4,
        "{one} {two} {zero}"
    );
    assert_eq!(
        stream_sigma_m(System::Gps, "C1C", el, &model, None, 2.0),
        None
    );
    let gps = stream_sigma_for_m(&StreamSigmas::Snapshot(model), System::Gps, "C1C", el, 2.0);
    assert!((gps - two).abs() < 1e-12, "{gps} {two}");
}

/// An iono-free pair takes its combination's group delay only when group
/// delays are on (Galileo E1 + E5a: c (BGD(E1,E5b) - BGD(E1,E5a))), and
/// no Klobuchar term (the combination removes the first-order
/// ionosphere); a single code with group delays off takes none.
#[test]
fn pairs_take_their_group_delay_and_no_klobuchar() {
    let (bgd_s, bgd5a_s) = (4e-9, 1.5e-9);
    let gal: &'static Kepler = std::boxed::Box::leak(std::boxed::Box::new(Kepler {
        group_delay_s: bgd_s,
        group_delay_e5a_s: bgd5a_s,
        ..circular(System::Galileo, 11)
    }));
    let (t, rx) = overhead(gal);
    let kb = Klobuchar {
        alpha: [0.0; 4],
        beta: [0.0; 4],
    };
    let pair = SatInput {
        id: SatId::new(System::Galileo, 11),
        code: "C1C+C5Q",
        p1_m: 2.0e7,
        p2_m: Some(2.0e7 + 3.0),
        eph: Broadcast::Kepler(gal),
        orbit_arc: false,
    };
    let on = correct(
        &pair,
        t,
        Some(rx),
        true,
        &corrections(true, true),
        Some(&kb),
    )
    .unwrap();
    assert!(
        (on.group_delay_m - C_M_S * (bgd_s - bgd5a_s)).abs() < 1e-9,
        "{on:?}"
    );
    assert_eq!(on.iono_m, 0.0);
    let off = correct(
        &pair,
        t,
        Some(rx),
        true,
        &corrections(false, true),
        Some(&kb),
    )
    .unwrap();
    assert_eq!(off.group_delay_m, 0.0);
    let single = SatInput {
        code: "C1C",
        p2_m: None,
        ..pair
    };
    let off = correct(&single, t, Some(rx), true, &corrections(false, false), None).unwrap();
    assert_eq!(off.group_delay_m, 0.0);
}

/// A stream's satellite (`orbit_arc`: the host's readers of a receiver
/// stream) takes its transmit state and motion on its arc, the bits of
/// [`crate::arc::transmit_state_motion_on_arc`] (which the arc tests
/// check against the exact orbit), whether its set comes as the set or as
/// its orbit's constants; without `orbit_arc` it takes the exact orbit's;
/// an orbit's clock is its set's.
///
/// Verifies: RX-FORM-ARC
#[test]
fn a_streams_satellite_takes_its_arc_from_a_set_or_its_orbit() {
    let k: &'static Kepler = std::boxed::Box::leak(std::boxed::Box::new(circular(System::Gps, 7)));
    let o: &'static Orbit = std::boxed::Box::leak(std::boxed::Box::new(Orbit::new(k)));
    let (t, _) = overhead(k);
    let id = SatId::new(System::Gps, 7);
    let p1_m = 2.0e7;
    let input = |eph, orbit_arc| SatInput {
        id,
        code: "C1C",
        p1_m,
        p2_m: None,
        eph,
        orbit_arc,
    };
    let t_sv = t - p1_m / C_M_S;
    let (_, arc_state, arc_motion) = crate::arc::transmit_state_motion_on_arc(id, o, t_sv);
    let (_, exact_state, exact_motion) = o.transmit_state_motion(t_sv);
    for eph in [Broadcast::Kepler(k), Broadcast::Orbit(o)] {
        assert_eq!(eph.clock_s(t_sv), k.clock_s(t_sv));
        let on_arc = transmit_state_motion(&input(eph, true), t, true).unwrap();
        assert_eq!(on_arc, (arc_state, Some(arc_motion)));
        let exact = transmit_state_motion(&input(eph, false), t, true).unwrap();
        assert_eq!(exact, (exact_state, Some(exact_motion)));
        let state_only = transmit_state_motion(&input(eph, true), t, false).unwrap();
        assert_eq!(state_only, (arc_state, None));
    }
    // The arc's and the exact orbit's positions agree within the arc's
    // bound (crate::arc: 1e-3 m).
    let d = (0..3)
        .map(|j| (arc_state.position_m[j] - exact_state.position_m[j]).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(d < 1e-3, "{d}");
}
