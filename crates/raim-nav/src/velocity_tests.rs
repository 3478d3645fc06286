//! The velocity module against independent numbers: satellite velocities
//! and clock drifts against the numerical derivative of the broadcast
//! positions and clocks ([`Kepler::state`], the GLONASS integration), and
//! the receiver velocity against a synthetic moving receiver whose range
//! rates are the numerical derivative of its pseudoranges, each formed by
//! the light-time iteration in the inertial frame.

use super::*;
use crate::ephemeris::{circular, SatState, WEEK_S};
use crate::glonass::{GlonassEphemeris, GlonassIcdFields};
use raim_core::frames::{geodetic_to_ecef, Geodetic};
use raim_core::System;

/// Tolerance of a satellite velocity against the central difference of
/// its positions, mm/s: the difference's truncation (the jerk of a GNSS
/// orbit, 1e-4 m/s^3, times h^2 / 6 with h = 0.5 s, 4e-6 m/s) and the
/// positions' rounding (1e-7 m over 1 s) are far below it.
const SAT_VELOCITY_TOL_MM_S: f64 = 0.01;
/// Tolerance of a GLONASS velocity against the central difference of its
/// integrated positions, mm/s: the two positions end on shortened RK4
/// steps of different lengths, whose truncation errors (60 s steps, about
/// 1e-5 m) differ smoothly over the 1 s span. Observed: 0.006 mm/s.
const GLONASS_VELOCITY_TOL_MM_S: f64 = 0.02;
/// Tolerance of a clock drift against the central difference of the
/// clock, s/s (the clock's rounding, 1e-19 s, over 1 s).
const CLOCK_DRIFT_TOL_S_S: f64 = 1e-16;
/// Tolerance of the recovered receiver velocity, mm/s: the synthetic
/// rates are central differences of pseudoranges of 2e7 m (rounding 4e-9
/// m over 1 s) from the light-time iteration (converged to 1e-9 m); the
/// model's left-out terms (module doc) are below 1e-5 m/s here (no
/// atmosphere, satellite clock drifts of 1e-11). Observed: 2.6e-3 mm/s.
/// The sets and times are near GPS week 0: at week 1000 a GPS time (6e8
/// s) is rounded to 1.2e-7 s, which moves each synthetic range by up to
/// 5e-5 m and the recovered velocity by 0.07 mm/s.
const RX_VELOCITY_TOL_MM_S: f64 = 0.01;

/// Half the central difference's span, s.
const H_S: f64 = 0.5;

fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A broadcast-like Keplerian set of `system`: random elements and
/// harmonic corrections of the broadcast sizes.
fn random_kepler(system: System, prn: u8, next: &mut impl FnMut() -> f64) -> Kepler {
    let mut k = circular(system, prn);
    k.sqrt_a_m05 = match system {
        System::Galileo => 5440.6,
        System::Beidou if prn <= 5 => 6493.4,
        _ => 5153.6,
    };
    k.e = 0.02 * next();
    k.m0_rad = 6.0 * next() - 3.0;
    k.omega_rad = 6.0 * next() - 3.0;
    k.omega0_rad = 6.0 * next() - 3.0;
    k.i0_rad = 0.95 + 0.05 * next();
    k.delta_n_rad_s = 5e-9 * next();
    k.omega_dot_rad_s = -8e-9 * next();
    k.idot_rad_s = 4e-10 * (next() - 0.5);
    k.cuc_rad = 1e-5 * (next() - 0.5);
    k.cus_rad = 1e-5 * (next() - 0.5);
    k.crc_m = 300.0 * (next() - 0.5);
    k.crs_m = 200.0 * (next() - 0.5);
    k.cic_rad = 2e-7 * (next() - 0.5);
    k.cis_rad = 2e-7 * (next() - 0.5);
    k.toe_sow_s = 7200.0;
    k.toc_gps_s = 7200.0;
    k.af0_s = 2e-4 * (next() - 0.5);
    k.af1_s_s = 2e-11 * (next() - 0.5);
    k.af2_s_s2 = 1e-18 * next();
    k
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// The velocity of every Keplerian system (GPS, Galileo, QZSS, a BeiDou
/// MEO and a BeiDou GEO with its extra rotations) is the central
/// difference of [`Kepler::state`]'s positions, and the clock drift that
/// of its clock, from two hours before toe to six hours after.
///
/// Verifies: RX-VELOCITY
#[test]
fn kepler_velocity_is_the_derivative_of_the_broadcast_position() {
    let mut next = xorshift(0x5eed_7e10_c0de_0001);
    let mut worst = (0.0f64, 0.0f64);
    for (system, prn) in [
        (System::Gps, 5),
        (System::Galileo, 11),
        (System::Qzss, 193),
        (System::Beidou, 30),
        (System::Beidou, 3),
    ] {
        for _ in 0..100 {
            let k = random_kepler(system, prn, &mut next);
            let t = 14_400.0 + 28_800.0 * (next() - 0.5);
            let got = kepler_motion(&k, t);
            let (a, b): (SatState, SatState) = (k.state(t + H_S), k.state(t - H_S));
            let fd = sub(a.position_m, b.position_m).map(|v| v / (2.0 * H_S));
            let err = norm(sub(got.velocity_m_s, fd));
            assert!(
                err * 1e3 < SAT_VELOCITY_TOL_MM_S,
                "{system:?} {prn}: {err} m/s at speed {}",
                norm(fd)
            );
            // A satellite moves: ~3-4 km/s Earth-fixed (a GEO's is near 0).
            if prn != 3 {
                assert!(norm(fd) > 1000.0, "{system:?} {}", norm(fd));
            }
            let drift_fd = (a.clock_s - b.clock_s) / (2.0 * H_S);
            let derr = (got.clock_drift_s_s - drift_fd).abs();
            assert!(derr < CLOCK_DRIFT_TOL_S_S, "{system:?} drift {derr:e}");
            worst = (worst.0.max(err), worst.1.max(derr));
        }
    }
    println!("worst velocity {:.3e} m/s, drift {:.3e}", worst.0, worst.1);
}

/// The motion the receiver takes with the transmit state
/// ([`Orbit::transmit_state_motion`], one evaluation for both): its
/// transmit time and state are [`Orbit::transmit_state`]'s to the bit,
/// its velocity the central difference of [`Kepler::state`]'s positions
/// about that transmit time and its clock drift that of the clock, for
/// every Keplerian system (a BeiDou GEO with its extra rotations), clock
/// offsets to 1 ms, eccentricities to 0.2 (the Newton step's fallback
/// to a fresh solution included: no shortcut of the transmit state
/// changes the derivative; [`Orbit::motion`] at the transmit time, from a
/// fresh eccentric anomaly, within 1e-9 m/s).
///
/// Verifies: RX-VELOCITY
#[test]
fn the_transmit_states_motion_is_the_derivative_at_the_transmit_time() {
    let mut next = xorshift(0x7a11_5eed_0bad_cafe);
    let mut worst = (0.0f64, 0.0f64);
    for (system, prn) in [
        (System::Gps, 7),
        (System::Galileo, 14),
        (System::Qzss, 194),
        (System::Beidou, 25),
        (System::Beidou, 2),
    ] {
        for case in 0..100 {
            let mut k = random_kepler(system, prn, &mut next);
            k.af0_s = 2e-3 * next() - 1e-3;
            if case % 10 == 0 {
                k.e = 0.2 * next();
            }
            let orbit = Orbit::new(&k);
            let t_sv = 14_400.0 + 28_800.0 * (next() - 0.5);
            let (t, state, got) = orbit.transmit_state_motion(t_sv);
            let (want_t, want_state) = orbit.transmit_state(t_sv);
            assert_eq!(t.to_bits(), want_t.to_bits());
            assert_eq!(state, want_state);
            let (a, b) = (k.state(t + H_S), k.state(t - H_S));
            let fd = sub(a.position_m, b.position_m).map(|v| v / (2.0 * H_S));
            let err = norm(sub(got.velocity_m_s, fd));
            assert!(
                err * 1e3 < SAT_VELOCITY_TOL_MM_S,
                "{system:?} {prn}: {err} m/s"
            );
            let drift_fd = (a.clock_s - b.clock_s) / (2.0 * H_S);
            let derr = (got.clock_drift_s_s - drift_fd).abs();
            assert!(derr < CLOCK_DRIFT_TOL_S_S, "{system:?} drift {derr:e}");
            // A fresh eccentric anomaly at t moves only the last bits.
            let fresh = orbit.motion(t);
            assert!(norm(sub(got.velocity_m_s, fresh.velocity_m_s)) < 1e-9);
            worst = (worst.0.max(err), worst.1.max(derr));
        }
    }
    println!("worst velocity {:.3e} m/s, drift {:.3e}", worst.0, worst.1);
}

fn glonass_set() -> GlonassEphemeris {
    // R01-like state at t_b (GLONASS ICD units: km, km/s, km/s^2).
    let f = GlonassIcdFields {
        slot: 1,
        frequency_channel: 1,
        tb_gps_s: 1000.0 * WEEK_S + 3600.0,
        x_km: 10_697.116_211,
        y_km: 21_058.792_969,
        z_km: 2_729.740_723,
        vx_km_s: -0.299_617_767,
        vy_km_s: -0.211_649_895,
        vz_km_s: 3.560_036_659,
        ax_km_s2: -1.862_645e-9,
        ay_km_s2: 0.0,
        az_km_s2: -1.862_645e-9,
        tau_n_s: 1.2e-5,
        gamma_n: 1.8e-12,
        unhealthy: false,
    };
    GlonassEphemeris::from_icd(&f).unwrap()
}

/// A GLONASS velocity (the integration's, through the PZ-90.11 to WGS-84
/// rotation) is the central difference of the WGS-84 positions the
/// receiver uses ([`GlonassEphemeris::state`]), and its clock drift that
/// of its clock, across the 30 minutes either side of t_b.
///
/// Verifies: RX-VELOCITY
#[test]
fn glonass_velocity_is_the_derivative_of_the_integrated_position() {
    let g = glonass_set();
    let mut worst = 0.0f64;
    for step in -30..=30 {
        let t = g.tb_gps_s + 60.0 * f64::from(step) + 17.3;
        let (_, v) = g.propagate_pz90(t);
        let got = glonass_motion(v, g.gamma_n);
        let (a, b) = (g.state(t + H_S), g.state(t - H_S));
        let fd = sub(a.position_m, b.position_m).map(|v| v / (2.0 * H_S));
        let err = norm(sub(got.velocity_m_s, fd));
        assert!(
            err * 1e3 < GLONASS_VELOCITY_TOL_MM_S,
            "t_b {step} min: {err}"
        );
        assert!(norm(fd) > 1000.0);
        let drift_fd = (a.clock_s - b.clock_s) / (2.0 * H_S);
        assert!((got.clock_drift_s_s - drift_fd).abs() < CLOCK_DRIFT_TOL_S_S);
        worst = worst.max(err);
    }
    println!("worst GLONASS velocity {worst:.3e} m/s");
}

/// The pseudorange a receiver at `rx(t)` with clock offset `clock_m(t)`
/// measures at `t` from `k`: the light-time iteration (the satellite's
/// position at t - tau turned by the Earth's rotation over tau), plus
/// the receiver's clock, less the satellite's at its transmit time.
/// Also the satellite's turned position and its transmit time.
fn pseudorange_m(k: &Kepler, t: f64, rx: [f64; 3], clock_m: f64) -> (f64, [f64; 3], f64) {
    let mut tau = 0.07;
    let mut pos = [0.0; 3];
    let mut tx = t;
    for _ in 0..10 {
        tx = t - tau;
        pos = rotate_earth(k.state(tx).position_m, tau);
        tau = norm(sub(pos, rx)) / C_M_S;
    }
    (C_M_S * tau + clock_m - C_M_S * k.state(tx).clock_s, pos, tx)
}

/// A receiver moving at a known velocity, with a known clock drift: its
/// pseudoranges formed by the light-time iteration at t - h and t + h,
/// their difference over 2 h taken as the measured rate, and the
/// velocity solution at its position recovers the velocity and drift,
/// whatever the speed (static to an aircraft's 250 m/s, climbing and
/// descending).
///
/// Verifies: RX-VELOCITY
#[test]
fn a_synthetic_moving_receiver_is_recovered() {
    let mut next = xorshift(0x0ddb_a11c_afe5_f00d);
    let rx0 = geodetic_to_ecef(Geodetic {
        lat_rad: 0.98,
        lon_rad: 0.15,
        height_m: 3000.0,
    });
    let r = enu_rotation(&ecef_to_geodetic(rx0));
    let mut worst = 0.0f64;
    for case in 0..40 {
        // ENU velocity, m/s, and the clock drift (c x drift), m/s.
        let speed = [0.0, 0.3, 70.0, 250.0][case % 4];
        let heading = std::f64::consts::TAU * next();
        let enu = [
            speed * heading.sin(),
            speed * heading.cos(),
            10.0 * (next() - 0.5),
        ];
        let v_ecef = raim_core::frames::unrotate(&r, enu);
        let drift_m_s = 200.0 * (next() - 0.5);
        let t = 7200.0 + 3600.0 * next();
        let rx_at = |dt: f64| [0, 1, 2].map(|i| rx0[i] + v_ecef[i] * dt);
        let clock_at = |dt: f64| 3e4 + drift_m_s * dt;
        let mut sats = std::vec::Vec::new();
        let mut prn = 1;
        while sats.len() < 9 && prn < 200 {
            let system = if prn % 3 == 0 {
                System::Galileo
            } else {
                System::Gps
            };
            let k = random_kepler(system, (prn % 36 + 1) as u8, &mut next);
            prn += 1;
            let (_, pos, tx) = pseudorange_m(&k, t, rx_at(0.0), clock_at(0.0));
            let up = raim_core::frames::rotate(&r, sub(pos, rx0))[2];
            if up < 0.2 * norm(sub(pos, rx0)) {
                continue;
            }
            let (pa, _, _) = pseudorange_m(&k, t + H_S, rx_at(H_S), clock_at(H_S));
            let (pb, _, _) = pseudorange_m(&k, t - H_S, rx_at(-H_S), clock_at(-H_S));
            let rate = (pa - pb) / (2.0 * H_S);
            let motion = kepler_motion(&k, tx);
            sats.push(RateObservation {
                sat_position_m: pos,
                rate: range_rate(rate, &motion, pos, rx0),
                sigma_m: 1.0 + next(),
            });
        }
        assert_eq!(sats.len(), 9, "case {case}");
        let v = solve(rx0, &mut sats.iter().copied()).unwrap();
        let err = norm(sub(v.enu_m_s, enu));
        assert!(
            err * 1e3 < RX_VELOCITY_TOL_MM_S,
            "case {case}: {:?} against {enu:?}: {err} m/s",
            v.enu_m_s
        );
        assert!((v.clock_drift_m_s - drift_m_s).abs() * 1e3 < RX_VELOCITY_TOL_MM_S);
        assert_eq!(v.satellites, 9);
        // Speed and course over ground: the horizontal part.
        let sog = (enu[0] * enu[0] + enu[1] * enu[1]).sqrt();
        assert!((v.speed_over_ground_m_s() - sog).abs() * 1e3 < RX_VELOCITY_TOL_MM_S);
        if speed >= 70.0 {
            let want = heading.rem_euclid(std::f64::consts::TAU);
            let mut d = (v.course_over_ground_rad() - want).abs();
            d = d.min(std::f64::consts::TAU - d);
            assert!(
                d < 1e-5,
                "course {} against {want}",
                v.course_over_ground_rad()
            );
        }
        worst = worst.max(err);
    }
    println!("worst receiver velocity error {worst:.3e} m/s");
}

/// The course is clockwise from north in [0, 2 pi): east 90 degrees,
/// south 180, west 270, north 0.
#[test]
fn course_over_ground_is_clockwise_from_north() {
    let at = |e: f64, n: f64| ReceiverVelocity {
        ecef_m_s: [0.0; 3],
        enu_m_s: [e, n, 5.0],
        clock_drift_m_s: 0.0,
        satellites: 5,
    };
    for (e, n, deg) in [
        (0.0, 1.0, 0.0),
        (1.0, 0.0, 90.0),
        (0.0, -1.0, 180.0),
        (-1.0, 0.0, 270.0),
        (-1.0, 1.0, 315.0),
    ] {
        let v = at(e, n);
        assert!((v.course_over_ground_rad().to_degrees() - deg).abs() < 1e-9);
        assert!((v.speed_over_ground_m_s() - (e * e + n * n).sqrt()).abs() < 1e-12);
    }
}

/// Bad input gets a typed error: too few rates, a singular geometry (every
/// satellite in one direction), a non-finite rate or position.
///
/// Verifies: RX-VELOCITY
#[test]
fn velocity_errors_are_typed() {
    let rx = [4e6, 1e6, 4.8e6];
    let obs = |p: [f64; 3], rate: f64| RateObservation {
        sat_position_m: p,
        rate: RangeRate {
            rate_m_s: rate,
            sat_velocity_m_s: [0.0; 3],
            sat_clock_drift_s_s: 0.0,
        },
        sigma_m: 1.0,
    };
    let three = [
        obs([2e7, 0.0, 0.0], 1.0),
        obs([0.0, 2e7, 0.0], 1.0),
        obs([0.0, 0.0, 2e7], 1.0),
    ];
    assert_eq!(
        solve(rx, &mut three.iter().copied()),
        Err(VelocityError::TooFewRates { have: 3, need: 4 })
    );
    let same = [obs([2e7, 2e7, 2e7], 1.0); 6];
    assert_eq!(
        solve(rx, &mut same.iter().copied()),
        Err(VelocityError::Singular)
    );
    let mut nan = three.to_vec();
    nan.push(obs([1e7, 1e7, 2e7], f64::NAN));
    assert_eq!(
        solve(rx, &mut nan.iter().copied()),
        Err(VelocityError::NotFinite {
            field: "range rate"
        })
    );
    assert_eq!(
        solve([f64::NAN; 3], &mut three.iter().copied()),
        Err(VelocityError::NotFinite { field: "position" })
    );
    // A sigma of zero (an infinite weight), of infinity (a zero weight)
    // and not a number.
    for sigma_m in [0.0, f64::INFINITY, f64::NAN] {
        let mut bad = three.to_vec();
        bad.push(RateObservation {
            sigma_m,
            ..obs([1e7, 1e7, 2e7], 1.0)
        });
        assert_eq!(
            solve(rx, &mut bad.iter().copied()),
            Err(VelocityError::NotFinite {
                field: "range rate"
            }),
            "sigma {sigma_m}"
        );
    }
    // Each error says what is wrong.
    let said = [
        (
            VelocityError::TooFewRates { have: 3, need: 4 },
            "3 range rates, 4 needed for a velocity",
        ),
        (VelocityError::Singular, "velocity geometry singular"),
        (
            VelocityError::NotFinite { field: "position" },
            "velocity: position not finite",
        ),
    ];
    for (e, text) in said {
        assert_eq!(std::format!("{e}"), text);
    }
}
