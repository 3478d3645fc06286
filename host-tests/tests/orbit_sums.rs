//! The Keplerian orbit by sum formulas (raim-nav `ephemeris::Orbit`: the
//! true anomaly, argument of latitude, second harmonics and inclination
//! from the set's sines and cosines of omega and i0, without atan2 or
//! their own library sines) against IS-GPS-200 Table 20-IV evaluated
//! angle by angle with the library (atan2 for the true anomaly, a sine
//! and cosine of 2 phi, u, i and Omega; Kepler's equation by the
//! fixed-point iteration), over every Keplerian set of the shared
//! navigation files: ESBC's and CORD's RINEX 3 navigation files (GPS,
//! Galileo I/NAV and F/NAV, BeiDou MEO, IGSO and GEO, QZSS), 0759's RINEX
//! 2 GPS file (2005) and GMSD7's 1019 messages
//! (decoded by the device's own decoder), at times across each set's fit
//! interval (toe +- the system's `max_ephemeris_age_s`); and the
//! satellite's motion (velocity and clock drift, the derivative of the
//! same expressions) against the central difference of the
//! angle-by-angle positions and clocks.

mod rtcm_common;

use raim_core::System;
use raim_gnss::NavData;
use raim_nav::ephemeris::{
    Kepler, Orbit, SatState, BDT_MINUS_GPST_S, C_M_S, MU_GAL_BDS_M3_S2, MU_GPS_M3_S2,
    OMEGA_E_BDS_RAD_S, OMEGA_E_GPS_RAD_S, WEEK_S,
};
use raim_nav::rtcm::decode::{kepler_message, Frame};
use raim_nav::rtcm::fields::{kepler, toc_near_toe};
use raim_nav::store::max_ephemeris_age_s;
use raim_nav::velocity::SatMotion;
use rtcm_common::esbc::{data, NAV};
use rtcm_common::{frames, GMSD7, GMSD7_WEEK};

/// The sum formulas' satellite positions agree with the angle-by-angle
/// evaluation within this, m (a range error far below any sigma of the
/// monitor, whose smallest, the ARAIM URA, is 0.5 m and up).
const POSITION_TOL_M: f64 = 1e-4;
/// The clocks agree within this, s (1e-4 m of range over c).
const CLOCK_TOL_S: f64 = POSITION_TOL_M / C_M_S;
/// Times evaluated across each set's fit interval.
const TIMES: usize = 49;
/// The motion (`Orbit::motion`, `Orbit::transmit_state_motion`) agrees
/// with the central difference of the angle-by-angle positions within
/// this, m/s: the difference's truncation (a GNSS orbit's jerk, 1e-4
/// m/s^3, times h^2 / 6 with h = 0.5 s, 4e-6 m/s) and the positions'
/// rounding (1e-8 m over 1 s) are below it; 0.01 mm/s, the velocity
/// tests' tolerance (raim-nav `velocity`).
const VELOCITY_TOL_M_S: f64 = 1e-5;
/// The clock drift agrees with the central difference of the clocks
/// within this, s/s (their rounding, 1e-19 s, over 1 s).
const DRIFT_TOL_S_S: f64 = 1e-16;
/// Half the central difference's span, s.
const H_S: f64 = 0.5;

/// IS-GPS-200 Table 20-IV and 20.3.3.3.3.1 (BeiDou ICD §5.2.4.12 for the
/// GEO rotation), angle by angle: position and clock at GPS time `t`.
fn reference(k: &Kepler, t: f64) -> ([f64; 3], f64) {
    let (mu, omega_e) = match k.system {
        System::Galileo => (MU_GAL_BDS_M3_S2, OMEGA_E_GPS_RAD_S),
        System::Beidou => (MU_GAL_BDS_M3_S2, OMEGA_E_BDS_RAD_S),
        _ => (MU_GPS_M3_S2, OMEGA_E_GPS_RAD_S),
    };
    let sys_t = if k.system == System::Beidou {
        t + BDT_MINUS_GPST_S
    } else {
        t
    };
    let mut tk = sys_t.rem_euclid(WEEK_S) - k.toe_sow_s;
    if tk > WEEK_S / 2.0 {
        tk -= WEEK_S;
    } else if tk < -WEEK_S / 2.0 {
        tk += WEEK_S;
    }
    let a = k.sqrt_a_m05 * k.sqrt_a_m05;
    let n = (mu / (a * a * a)).sqrt() + k.delta_n_rad_s;
    let mk = k.m0_rad + n * tk;
    let mut ek = mk;
    for _ in 0..100 {
        let next = mk + k.e * ek.sin();
        let done = (next - ek).abs() < 1e-15;
        ek = next;
        if done {
            break;
        }
    }
    let nu = ((1.0 - k.e * k.e).sqrt() * ek.sin()).atan2(ek.cos() - k.e);
    let phi = nu + k.omega_rad;
    let (s2, c2) = (2.0 * phi).sin_cos();
    let u = phi + k.cus_rad * s2 + k.cuc_rad * c2;
    let r = a * (1.0 - k.e * ek.cos()) + k.crs_m * s2 + k.crc_m * c2;
    let i = k.i0_rad + k.idot_rad_s * tk + k.cis_rad * s2 + k.cic_rad * c2;
    let (x, y) = (r * u.cos(), r * u.sin());
    let geo = k.system == System::Beidou && (k.prn <= 5 || (59..=63).contains(&k.prn));
    let p = if geo {
        let om = k.omega0_rad + k.omega_dot_rad_s * tk - omega_e * k.toe_sow_s;
        let g = [
            x * om.cos() - y * i.cos() * om.sin(),
            x * om.sin() + y * i.cos() * om.cos(),
            y * i.sin(),
        ];
        let f = (-5.0f64).to_radians();
        let (x1, y1, z1) = (
            g[0],
            f.cos() * g[1] + f.sin() * g[2],
            -f.sin() * g[1] + f.cos() * g[2],
        );
        let z = omega_e * tk;
        [
            z.cos() * x1 + z.sin() * y1,
            -z.sin() * x1 + z.cos() * y1,
            z1,
        ]
    } else {
        let om = k.omega0_rad + (k.omega_dot_rad_s - omega_e) * tk - omega_e * k.toe_sow_s;
        [
            x * om.cos() - y * i.cos() * om.sin(),
            x * om.sin() + y * i.cos() * om.cos(),
            y * i.sin(),
        ]
    };
    let dt = t - k.toc_gps_s;
    let f = -2.0 * mu.sqrt() / (C_M_S * C_M_S);
    let clock = k.af0_s + k.af1_s_s * dt + k.af2_s_s2 * dt * dt + f * k.e * k.sqrt_a_m05 * ek.sin();
    (p, clock)
}

/// The largest differences of the set `k` over its fit interval, as
/// [position m, clock s, velocity m/s, clock drift s/s]:
/// `Orbit::state` at each time, and `Orbit::transmit_state` (the
/// device's path) at each time as t_sv, against [`reference`] at the
/// same time; `Orbit::motion` at each time and
/// `Orbit::transmit_state_motion` (the device's path with a Doppler)
/// against the central difference of [`reference`] about the same time.
/// `Kepler::state` is `Orbit::state` to the bit, and
/// `transmit_state_motion`'s state `transmit_state`'s.
fn worst_of(k: &Kepler, toe_gps_s: f64) -> [f64; 4] {
    let orbit = Orbit::new(k);
    let age = max_ephemeris_age_s(k.system);
    let mut worst = [0.0f64; 4];
    let norm = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    let mut check = |t: f64, got: SatState, motion: Option<SatMotion>| {
        let (p, clock) = reference(k, t);
        worst[0] = worst[0].max(norm(got.position_m, p));
        worst[1] = worst[1].max((got.clock_s - clock).abs());
        if let Some(mo) = motion {
            let ((pa, ca), (pb, cb)) = (reference(k, t + H_S), reference(k, t - H_S));
            let fd = [0, 1, 2].map(|i| (pa[i] - pb[i]) / (2.0 * H_S));
            worst[2] = worst[2].max(norm(mo.velocity_m_s, fd));
            worst[3] = worst[3].max((mo.clock_drift_s_s - (ca - cb) / (2.0 * H_S)).abs());
        }
    };
    for j in 0..TIMES {
        let t = toe_gps_s - age + 2.0 * age * j as f64 / (TIMES - 1) as f64;
        let s = orbit.state(t);
        assert_eq!(s, k.state(t));
        check(t, s, Some(orbit.motion(t)));
        let (t_tx, s) = orbit.transmit_state(t);
        check(t_tx, s, None);
        let (t_m, s_m, motion) = orbit.transmit_state_motion(t);
        assert_eq!((t_m.to_bits(), s_m), (t_tx.to_bits(), s));
        check(t_m, s_m, Some(motion));
    }
    worst
}

/// Every Keplerian set of the shared navigation files and GMSD7's stream,
/// across its fit interval: the sum formulas' positions within
/// [`POSITION_TOL_M`] and clocks within [`CLOCK_TOL_S`] of the
/// angle-by-angle evaluation; the motion from the same evaluation
/// within [`VELOCITY_TOL_M_S`] and [`DRIFT_TOL_S_S`] of its central
/// difference.
///
/// Verifies: RX-VELOCITY
///
/// Verifies: RX-FORM-ORBIT
#[test]
fn sum_formulas_are_the_angles_on_every_real_set() {
    let mut per_system = std::collections::BTreeMap::<System, (usize, [f64; 4])>::new();
    let mut note = |system: System, w: [f64; 4], count: usize| {
        let e = per_system.entry(system).or_default();
        e.0 += count;
        for (m, x) in e.1.iter_mut().zip(w) {
            *m = m.max(x);
        }
    };
    let navs = [NAV, "07590920.05n", "CORD00ARG_R_20240920000_01D_MN.rnx.gz"]
        .map(|name| NavData::load(&data(name)).unwrap());
    for sets in navs.iter().flat_map(|nav| nav.ephemerides.values()) {
        for k in sets {
            // The GPS time of toe: toe is of the week of toc (BeiDou's in
            // BDT, 14 s behind).
            let bdt = if k.system == System::Beidou {
                BDT_MINUS_GPST_S
            } else {
                0.0
            };
            let week_start = ((k.toc_gps_s - bdt) / WEEK_S).floor() * WEEK_S;
            let mut toe_gps = week_start + k.toe_sow_s - bdt;
            if toe_gps - k.toc_gps_s > WEEK_S / 2.0 {
                toe_gps -= WEEK_S;
            } else if k.toc_gps_s - toe_gps > WEEK_S / 2.0 {
                toe_gps += WEEK_S;
            }
            note(k.system, worst_of(k, toe_gps), 1);
        }
    }
    let bytes = std::fs::read(GMSD7).unwrap();
    let mut gmsd7 = 0;
    for f in frames(&bytes) {
        let Ok(frame) = Frame::new(f) else { continue };
        let Ok(m) = kepler_message(frame.payload()) else {
            continue;
        };
        let mut k = kepler(m.system, m.prn, &m.fields);
        k.toc_gps_s = toc_near_toe(GMSD7_WEEK, k.toe_sow_s, m.fields.toc_s);
        let w = worst_of(&k, GMSD7_WEEK as f64 * WEEK_S + k.toe_sow_s);
        gmsd7 += 1;
        note(System::Gps, w, 0);
    }
    for (system, (n, [d, c, v, r])) in &per_system {
        println!(
            "{system:?}: {n} RINEX sets, positions within {d:.2e} m, clocks within {c:.2e} s, \
             velocities within {v:.2e} m/s, clock drifts within {r:.2e} s/s"
        );
    }
    println!("GMSD7: {gmsd7} 1019 messages (in the GPS line above)");
    assert!(gmsd7 > 10, "{gmsd7}");
    for system in [System::Gps, System::Galileo, System::Beidou, System::Qzss] {
        let (n, [d, c, v, r]) = per_system.get(&system).copied().unwrap_or_default();
        assert!(n > 0, "{system:?}: no set");
        assert!(d < POSITION_TOL_M, "{system:?}: {d:e} m");
        assert!(c < CLOCK_TOL_S, "{system:?}: {c:e} s");
        assert!(v < VELOCITY_TOL_M_S, "{system:?}: {v:e} m/s");
        assert!(r < DRIFT_TOL_S_S, "{system:?}: {r:e} s/s");
    }
}

/// Every Keplerian set of the shared navigation files (ESBC's, 0759's,
/// CORD's) with its toe as GPS time, then GMSD7's 1019s: (set, toe,
/// from GMSD7).
fn every_real_set() -> Vec<(Kepler, f64, bool)> {
    let mut out = Vec::new();
    let navs = [NAV, "07590920.05n", "CORD00ARG_R_20240920000_01D_MN.rnx.gz"]
        .map(|name| NavData::load(&data(name)).unwrap());
    for sets in navs.iter().flat_map(|nav| nav.ephemerides.values()) {
        for k in sets {
            let bdt = if k.system == System::Beidou {
                BDT_MINUS_GPST_S
            } else {
                0.0
            };
            let week_start = ((k.toc_gps_s - bdt) / WEEK_S).floor() * WEEK_S;
            let mut toe_gps = week_start + k.toe_sow_s - bdt;
            if toe_gps - k.toc_gps_s > WEEK_S / 2.0 {
                toe_gps -= WEEK_S;
            } else if k.toc_gps_s - toe_gps > WEEK_S / 2.0 {
                toe_gps += WEEK_S;
            }
            out.push((*k, toe_gps, false));
        }
    }
    let bytes = std::fs::read(GMSD7).unwrap();
    for f in frames(&bytes) {
        let Ok(frame) = Frame::new(f) else { continue };
        let Ok(m) = kepler_message(frame.payload()) else {
            continue;
        };
        let mut k = kepler(m.system, m.prn, &m.fields);
        k.toc_gps_s = toc_near_toe(GMSD7_WEEK, k.toe_sow_s, m.fields.toc_s);
        out.push((k, GMSD7_WEEK as f64 * WEEK_S + k.toe_sow_s, true));
    }
    out
}

/// The orbit arcs (raim-nav `arc`: the cubic Hermite interpolant
/// between exact states ARC_S = 30 s apart on the satellite's grid)
/// against the exact evaluation (`Orbit::state_motion`) on every
/// Keplerian set of the shared navigation files and GMSD7's 1019s, every
/// arc across each fit interval, at a quarter, half and three quarters
/// of it, and at the transmit time of a signal sent mid-arc
/// (`transmit_state_motion_on_arc` against `Orbit::transmit_state_motion`):
/// positions within 1 mm, velocities within 1 mm/s, clocks within
/// 1e-15 s (0.3 mm), clock drifts within 1e-16 s/s. And the Hermite
/// remainder's bound with the fourth derivative measured on the same
/// sets (fourth differences, 10 s apart, at every tenth node; the largest
/// per system, times 1.5 for what the sampling misses): h^4 / 384
/// max|f''''| for positions, sqrt(3) / 216 h^3 max|f''''| for velocities
/// (Birkhoff and Priver 1967), which the errors stay within.
///
/// Verifies: RX-FORM-ARC
#[test]
fn arcs_are_the_exact_orbit_on_every_real_set() {
    use raim_core::SatId;
    use raim_nav::arc::{arc_nodes_s, transmit_state_motion_on_arc, ARC_S};
    // Per system: sets, [position, velocity, clock, drift] errors, max|f''''|.
    let mut per_system = std::collections::BTreeMap::<System, (usize, [f64; 4], f64)>::new();
    let norm = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    let sets = every_real_set();
    assert!(sets.iter().filter(|s| s.2).count() > 10);
    for (k, toe_gps, _) in &sets {
        let orbit = Orbit::new(k);
        let id = SatId::new(k.system, k.prn);
        let age = max_ephemeris_age_s(k.system);
        let e = per_system.entry(k.system).or_default();
        e.0 += 1;
        let (mut t0, _) = arc_nodes_s(id, toe_gps - age);
        let mut n = 0;
        while t0 < toe_gps + age {
            for q in [0.25, 0.5, 0.75] {
                let t = t0 + q * ARC_S;
                let (_, got, motion) = transmit_state_motion_on_arc(id, &orbit, t);
                let (t_tx, want_s, _) = orbit.transmit_state_motion(t);
                // The arc's state at its own transmit time against the
                // exact one there (the transmit times agree within the
                // clocks' 1e-19 s, below the time's own ulp).
                let (at_s, at_m) = orbit.state_motion(t_tx);
                assert!((at_s.clock_s - want_s.clock_s).abs() < 1e-18);
                e.1[0] = e.1[0].max(norm(got.position_m, at_s.position_m));
                e.1[1] = e.1[1].max(norm(motion.velocity_m_s, at_m.velocity_m_s));
                e.1[2] = e.1[2].max((got.clock_s - at_s.clock_s).abs());
                e.1[3] = e.1[3].max((motion.clock_drift_s_s - at_m.clock_drift_s_s).abs());
            }
            if n % 10 == 0 {
                const D_S: f64 = 10.0;
                let p = [-2.0, -1.0, 0.0, 1.0, 2.0].map(|j| orbit.state(t0 + j * D_S).position_m);
                let d4 = (0..3)
                    .map(|i| {
                        (p[0][i] - 4.0 * p[1][i] + 6.0 * p[2][i] - 4.0 * p[3][i] + p[4][i])
                            / D_S.powi(4)
                    })
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt();
                e.2 = e.2.max(d4);
            }
            t0 += ARC_S;
            n += 1;
        }
    }
    let mut worst = [0.0f64; 4];
    for (system, (n, [p, v, c, d], f4)) in &per_system {
        let m = 1.5 * f4;
        let (bound_p, bound_v) = (
            ARC_S.powi(4) / 384.0 * m,
            3f64.sqrt() / 216.0 * ARC_S.powi(3) * m,
        );
        println!(
            "{system:?}: {n} sets, positions within {p:.2e} m (bound {bound_p:.2e}), \
             velocities within {v:.2e} m/s (bound {bound_v:.2e}), clocks within {c:.2e} s, \
             drifts within {d:.2e} s/s; max|f''''| {f4:.2e} m/s^4"
        );
        assert!(*p <= bound_p && *v <= bound_v, "{system:?}");
        for (w, x) in worst.iter_mut().zip([*p, *v, *c, *d]) {
            *w = w.max(x);
        }
    }
    assert!(per_system.len() >= 4);
    assert!(worst[0] < 1e-3 && worst[1] < 1e-3, "{worst:?}");
    assert!(worst[2] < 1e-15 && worst[3] < 1e-16, "{worst:?}");
}
