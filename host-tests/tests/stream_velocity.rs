//! Speed and course over ground from a receiver's Doppler (issue 34,
//! "NMEA"): the MSM5/MSM7 phase-range rates (DF399 + DF404) through the
//! device's stream receiver (`raim_nav::rtcm::StreamReceiver`, each
//! satellite's rate, velocity and clock drift) and the velocity solution
//! (`raim_nav::velocity`), on two static stations, and into the unit's
//! RMC and VTG (raim-server's `Server`), read back by the `nmea` crate,
//! pynmea2 and gpsd.
//!
//! The stations do not move, so the true speed is 0: GMSD7's real MSM7
//! rates (a receiver's own Doppler), and the ESBC stream built from the
//! RINEX, whose D observables are sent as the rates (`rtcm_common::esbc`,
//! rate = -D x lambda). A moving receiver is the ESBC epochs with every
//! rate shifted by the line-of-sight part of a known velocity.
//!
//!     cargo test --release -p host-tests --test stream_velocity -- --nocapture

mod rtcm_common;

use raim_core::Config;
use raim_nav::rtcm::{FormError, FormedEpoch, StreamReceiver};
use raim_nav::velocity::{solve, RateObservation, ReceiverVelocity};
use rtcm_common::{frames, GMSD7, GMSD7_PIVOT_WEEK, MASK_RAD};

/// Every epoch the device receiver forms from `bytes` (pivot
/// `pivot_week`), with the velocity at its reference position from every
/// satellite with a rate.
fn velocities(bytes: &[u8], pivot_week: i64) -> Vec<(FormedEpoch<64>, Option<ReceiverVelocity>)> {
    let sigmas = raim_nav::ranging::StreamSigmas::Snapshot(Config::default().sigma_model);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(pivot_week));
    let mut formed = FormedEpoch::<64>::new();
    let mut out = Vec::new();
    for f in frames(bytes) {
        match dev.on_frame(f, &sigmas, MASK_RAD, &mut formed) {
            None | Some(Err(FormError::NotDated { .. })) => {}
            Some(Err(e)) => panic!("{e}"),
            Some(Ok(())) => {
                assert_eq!(formed.rates.len(), formed.sats.len());
                let v = formed.reference_m.and_then(|rx| {
                    let mut sats = formed.sats.iter().zip(&formed.rates).filter_map(|(o, r)| {
                        Some(RateObservation {
                            sat_position_m: o.position_m,
                            rate: (*r)?,
                            sigma_m: o.sigma_m.unwrap_or(1.0),
                        })
                    });
                    solve(rx, &mut sats).ok()
                });
                out.push((formed.clone(), v));
            }
        }
    }
    out
}

fn stats(name: &str, v: &[ReceiverVelocity]) -> (f64, f64) {
    let n = v.len() as f64;
    let rms = |f: &dyn Fn(&ReceiverVelocity) -> f64| {
        (v.iter().map(|x| f(x).powi(2)).sum::<f64>() / n).sqrt()
    };
    let max = |f: &dyn Fn(&ReceiverVelocity) -> f64| v.iter().map(f).fold(0.0, f64::max);
    let sog = |x: &ReceiverVelocity| x.speed_over_ground_m_s();
    let up = |x: &ReceiverVelocity| x.enu_m_s[2].abs();
    println!(
        "{name}: {} epochs with a velocity; speed over ground rms {:.4} max {:.4} m/s; vertical rms {:.4} max {:.4} m/s; satellites {}..{}",
        v.len(),
        rms(&sog),
        max(&sog),
        rms(&up),
        max(&up),
        v.iter().map(|x| x.satellites).min().unwrap_or(0),
        v.iter().map(|x| x.satellites).max().unwrap_or(0),
    );
    (max(&sog), max(&up))
}

/// GMSD7 warm: its ephemeris frames (1019, 1020) first, as a receiver
/// sends its stored ephemerides at start-up, then the whole stream (cold,
/// the ephemerides arrive a satellite at a time over its 257 s).
fn gmsd7_warm() -> Vec<u8> {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let eph: Vec<u8> = frames(&bytes)
        .into_iter()
        .filter(|f| {
            let n = rtcm_rs::MessageFrame::new(f)
                .ok()
                .and_then(|m| m.message_number());
            matches!(n, Some(1019 | 1020))
        })
        .flatten()
        .copied()
        .collect();
    let whole: Vec<u8> = frames(&bytes).into_iter().flatten().copied().collect();
    [eph, whole].concat()
}

#[test]
fn gmsd7_static_velocity() {
    let bytes = gmsd7_warm();
    let all = velocities(&bytes, GMSD7_PIVOT_WEEK);
    let with_rates = all
        .iter()
        .filter(|(f, _)| f.rates.iter().any(|r| r.is_some()))
        .count();
    let v: Vec<ReceiverVelocity> = all.iter().filter_map(|(_, v)| *v).collect();
    println!("{} epochs, {with_rates} with rates", all.len());
    stats("GMSD7", &v);
}
