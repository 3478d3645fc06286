//! The replay's Doppler from RINEX D observables (issue 34, "NMEA";
//! docs/REPLAY.md "Speed and course"): each signal's Doppler turned into
//! a range rate on its own carrier (GLONASS FDMA on the satellite's
//! channel from the navigation file), checked against two independent
//! numbers on ESBC (a static geodetic station, G+R+E+C, every signal with
//! its D observable):
//! - the pseudoranges' own change over the 30 s between epochs: each
//!   signal's mean rate over the interval against (P(t + 30) - P(t)) / 30,
//!   the receiver clock (common to all) removed, for every band and
//!   every GLONASS channel;
//! - a known motion added to the Doppler (as the Doppler shift a receiver
//!   moving at that velocity sees, on each signal's carrier) comes back
//!   from the velocity solution, and the station at rest solves near 0.
//!
//!     cargo test --release -p host-tests --test replay_velocity -- --nocapture

mod replay_common;

use std::collections::BTreeMap;

use raim_core::frames::{ecef_to_geodetic, enu_rotation, rotate, unrotate};
use raim_core::{Config, Decision, Epoch, Raim, SatId, System};
use raim_gnss::ephemeris::C_M_S;
use raim_gnss::ranging::{prepare_epoch, signal_carrier_hz, solve_velocity, RangingOptions};
use raim_gnss::rinex_io::SignalRate;
use raim_gnss::{NavData, ObsData, ObsEpoch};
use replay_common::data;

const OBS: &str = "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz";
const NAV: &str = "ESBC00DNK_R_20201770000_01D_MN.rnx.gz";

/// A signal's mean range rate over 30 s against its pseudorange change,
/// m/s: the pseudorange's noise and multipath over 30 s (a few dm, so
/// ~0.02 m/s), the ionosphere's rate taken twice (code and phase move
/// apart: mm/s to cm/s), and the rate's curvature over the interval
/// (below 1 mm/s for the trapezoid of a satellite's range) stay well
/// below it; a GLONASS Doppler on a carrier one channel off is misplaced
/// by 3.5e-4 of its rate (up to 0.3 m/s), one on another band's carrier by
/// 5 % to 34 % (tens of m/s), a wrong sign by twice the rate.
const RANGE_DIFFERENCE_TOL_M_S: f64 = 0.5;
/// The rms of [`RANGE_DIFFERENCE_TOL_M_S`]'s differences over a signal,
/// m/s (code noise over 30 s: ESBC's noisiest, R1C, 0.033 m/s).
const RANGE_DIFFERENCE_RMS_TOL_M_S: f64 = 0.05;
/// A known velocity added to the Doppler comes back within this, m/s:
/// the solution's light-time factor 1 + u . w_sat / c (up to 3e-6) on the
/// shift (0.8 mm/s at 250 m/s) and the shift's own line of sight, taken
/// at the solved position.
const KNOWN_MOTION_TOL_M_S: f64 = 1.5e-3;
/// The largest speed over ground and vertical speed at rest, m/s
/// (docs/REPLAY.md: a geodetic receiver's D observables are good to a few
/// mm/s; see `cli_replay_velocity`'s bound).
const STATIC_TOL_M_S: f64 = 0.1;

/// The largest relative scale error of a carrier: the fitted factor e in
/// r = e x rate over a signal or a GLONASS band and channel (a carrier
/// one GLONASS channel off gives 3.5e-4 on L1 and L2; noise of 0.03 m/s
/// over a few hundred rates of hundreds of m/s gives ~1e-5).
const CARRIER_SCALE_TOL: f64 = 5e-5;

/// Sums over a signal's differences r (rate less pseudorange change) and
/// mean rates.
#[derive(Debug, Default)]
struct Sums {
    r2: f64,
    r_rate: f64,
    rate2: f64,
    n: usize,
    largest: f64,
}

impl Sums {
    fn add(&mut self, r: f64, rate: f64) {
        self.r2 += r * r;
        self.r_rate += r * rate;
        self.rate2 += rate * rate;
        self.n += 1;
        self.largest = self.largest.max(r.abs());
    }

    fn rms(&self) -> f64 {
        (self.r2 / self.n as f64).sqrt()
    }

    /// The least-squares factor e of r = e x rate: a carrier's relative
    /// error.
    fn scale(&self) -> f64 {
        self.r_rate / self.rate2
    }
}

fn load() -> (ObsData, NavData) {
    (
        ObsData::load(&data(OBS)).expect("ESBC observations"),
        NavData::load(&data(NAV)).expect("ESBC navigation"),
    )
}

/// The carrier of `code` of satellite `id` at `t`: its channel from the
/// navigation file for GLONASS.
fn carrier(nav: &NavData, id: SatId, code: &str, t: f64) -> Option<f64> {
    let k = nav
        .select_broadcast(id, t)
        .and_then(|b| b.frequency_channel());
    signal_carrier_hz(id.system, code, k)
}

/// Every signal with a Doppler of a satellite above 15 degrees (where
/// code multipath is small), at two epochs 30 s apart: its mean rate (the
/// two Dopplers' as -D c / f) less its pseudorange change over the
/// interval, less the median of these over every signal of the pair (the
/// receiver clock's jumps and drift, common to all): every one within
/// [`RANGE_DIFFERENCE_TOL_M_S`], the rms of each signal (system and code)
/// within [`RANGE_DIFFERENCE_RMS_TOL_M_S`], and no part proportional to
/// the rate (a carrier's error, [`CARRIER_SCALE_TOL`]) in any signal or
/// any GLONASS band and channel, for every band of every system.
///
/// Verifies: RX-DOPPLER-RINEX
#[test]
fn rinex_doppler_rates_match_the_pseudorange_change() {
    let (obs, nav) = load();
    let opts = RangingOptions {
        systems: vec![
            System::Gps,
            System::Glonass,
            System::Galileo,
            System::Beidou,
        ],
        ..Default::default()
    };
    // Per signal, and per GLONASS band and channel: the sums of r^2, of
    // r x rate and of rate^2, the count, the largest |r|.
    let mut by_signal: BTreeMap<String, Sums> = BTreeMap::new();
    let mut by_channel: BTreeMap<(char, i8), Sums> = BTreeMap::new();
    for pair in obs.epochs.windows(2).take(120) {
        let (a, b) = (&pair[0], &pair[1]);
        let dt = b.time_gps_s - a.time_gps_s;
        assert!((dt - 30.0).abs() < 1e-6, "{dt}");
        let p = prepare_epoch(&nav, a, &opts, obs.approx_position_m);
        let high = |id: SatId| {
            p.sats
                .iter()
                .any(|s| s.obs.id == id && s.elevation_rad > 15f64.to_radians())
        };
        let mut diffs = Vec::new();
        for (id, codes) in a.sats.iter().filter(|(id, _)| high(**id)) {
            let Some(later) = b.sats.get(id) else {
                continue;
            };
            for c in codes {
                let Some(c2) = later.iter().find(|o| o.code == c.code) else {
                    continue;
                };
                let (Some(SignalRate::Doppler { hz: d1 }), Some(SignalRate::Doppler { hz: d2 })) =
                    (c.rate, c2.rate)
                else {
                    continue;
                };
                let Some(f) = carrier(&nav, *id, &c.code, a.time_gps_s) else {
                    continue;
                };
                let mean_rate = -(d1 + d2) / 2.0 * C_M_S / f;
                let change = (c2.value_m - c.value_m) / dt;
                diffs.push((*id, c.code.clone(), mean_rate - change, mean_rate));
            }
        }
        let mut sorted: Vec<f64> = diffs.iter().map(|d| d.2).collect();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[sorted.len() / 2];
        for (id, code, d, rate) in diffs {
            let r = d - median;
            assert!(
                r.abs() < RANGE_DIFFERENCE_TOL_M_S,
                "{id} {code} at {}: {r} m/s",
                a.time_gps_s
            );
            by_signal
                .entry(format!("{}{}", id.system.letter(), &code[1..]))
                .or_default()
                .add(r, rate);
            if id.system == System::Glonass {
                let k = nav
                    .select_broadcast(id, a.time_gps_s)
                    .and_then(|b| b.frequency_channel())
                    .expect("a GLONASS channel");
                let band = code.chars().nth(1).unwrap_or('?');
                by_channel.entry((band, k)).or_default().add(r, rate);
            }
        }
    }
    for (name, m) in &by_signal {
        println!(
            "{name}: {} intervals, rms {:.4} m/s, largest {:.4} m/s, scale {:+.1e}",
            m.n,
            m.rms(),
            m.largest,
            m.scale()
        );
        assert!(m.rms() < RANGE_DIFFERENCE_RMS_TOL_M_S, "{name}");
        assert!(m.scale().abs() < CARRIER_SCALE_TOL, "{name}");
    }
    for ((band, k), m) in &by_channel {
        println!(
            "GLONASS L{band} channel {k:+}: {} intervals, rms {:.4} m/s, scale {:+.1e}",
            m.n,
            m.rms(),
            m.scale()
        );
        assert!(m.scale().abs() < CARRIER_SCALE_TOL, "L{band} channel {k}");
    }
    for sig in [
        "G1C", "G2W", "G5Q", "R1C", "R2P", "E1C", "E5Q", "E7Q", "C2I", "C6I",
    ] {
        assert!(
            by_signal.get(sig).is_some_and(|m| m.n > 100),
            "{sig}: {by_signal:?}"
        );
    }
    assert!(by_channel.len() >= 5, "{by_channel:?}");
}

/// ESBC's first 60 epochs, G+R+E+C: the snapshot monitor's position
/// (`Raim` on the host, as the replay runs it) and the velocity from the
/// Doppler of the satellites it used (`solve_velocity`, the replay's)
/// are near 0 at rest; the same epochs with the Doppler a receiver moving
/// at a known velocity would see added to each signal's D observable
/// ((u . v) f / c on its own carrier, u the line of sight from the solved
/// position) give that velocity back within [`KNOWN_MOTION_TOL_M_S`].
///
/// Verifies: RX-DOPPLER-RINEX, RX-VELOCITY
#[test]
fn rinex_doppler_known_motion_is_recovered() {
    let (obs, nav) = load();
    let opts = RangingOptions {
        systems: vec![
            System::Gps,
            System::Glonass,
            System::Galileo,
            System::Beidou,
        ],
        ..Default::default()
    };
    let cfg = Config::default();
    let model = cfg.sigma_model;
    let sigma = |el: f64| model.sigma_m(el);
    let mut raim = Box::new(Raim::<48>::new());
    let (mut solved, mut glonass) = (0, 0);
    let (mut worst_static, mut worst_moved) = (0.0f64, 0.0f64);
    for e in obs.epochs.iter().take(60) {
        let p = prepare_epoch(&nav, e, &opts, obs.approx_position_m);
        let sats = p.observations();
        let r = raim
            .process(&cfg, &Epoch::ranges(e.time_gps_s, &sats, p.reference_m))
            .expect("ESBC epoch");
        assert!(matches!(r.decision, Decision::Ok | Decision::Excluded));
        let rx = r.position_ecef_m.expect("a position");
        let used: Vec<SatId> = r
            .satellites
            .iter()
            .filter(|s| s.used)
            .map(|s| s.id)
            .collect();
        let is_used = |id: SatId| used.contains(&id);
        let v0 = solve_velocity(&p.sats, &sats, is_used, rx, sigma).expect("velocity");
        let rot = enu_rotation(&ecef_to_geodetic(rx));
        let [ve, vn, vu] = rotate(&rot, v0.ecef_m_s);
        worst_static = worst_static.max(ve.hypot(vn)).max(vu.abs());
        glonass += p
            .sats
            .iter()
            .filter(|s| s.rate.is_some() && s.obs.id.system == System::Glonass)
            .count();

        // A receiver moving at 250 m/s (east, north, up: 150, -199, 10).
        let known = unrotate(&rot, [150.0, -199.0, 10.0]);
        let mut moved: ObsEpoch = e.clone();
        for s in &p.sats {
            let d = [
                s.obs.position_m[0] - rx[0],
                s.obs.position_m[1] - rx[1],
                s.obs.position_m[2] - rx[2],
            ];
            let range = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let u_v = (d[0] * known[0] + d[1] * known[1] + d[2] * known[2]) / range;
            for c in moved.sats.get_mut(&s.obs.id).into_iter().flatten() {
                let (Some(SignalRate::Doppler { hz }), Some(f)) =
                    (c.rate, carrier(&nav, s.obs.id, &c.code, e.time_gps_s))
                else {
                    continue;
                };
                // The range rate falls by u . v: the Doppler rises by
                // (u . v) f / c.
                c.rate = Some(SignalRate::Doppler {
                    hz: hz + u_v * f / C_M_S,
                });
            }
        }
        let q = prepare_epoch(&nav, &moved, &opts, obs.approx_position_m);
        assert_eq!(q.observations(), sats, "the ranges do not move");
        let v1 = solve_velocity(&q.sats, &sats, is_used, rx, sigma).expect("velocity");
        for ((a, b), want) in v1.ecef_m_s.iter().zip(&v0.ecef_m_s).zip(&known) {
            worst_moved = worst_moved.max((a - b - want).abs());
        }
        solved += 1;
    }
    println!(
        "ESBC G+R+E+C, {solved} epochs ({glonass} GLONASS rates): at rest largest horizontal or vertical speed {worst_static:.4} m/s; a known 250 m/s motion recovered within {:.3} mm/s",
        worst_moved * 1e3
    );
    assert_eq!(solved, 60);
    assert!(glonass > 200, "{glonass}");
    assert!(worst_static < STATIC_TOL_M_S, "{worst_static}");
    assert!(worst_moved < KNOWN_MOTION_TOL_M_S, "{worst_moved}");
}
