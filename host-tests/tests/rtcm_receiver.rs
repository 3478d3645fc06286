//! The firmware's RTCM 3 receiver (`raim_nav::rtcm::StreamReceiver`, no_std,
//! fixed capacity) against the host's stream reader (`raim_recv::rtcm`, a
//! separate decoder, dating and ephemeris store) on the real GMSD7 stream
//! (GPS + GLONASS MSM7, 1019 and 1020; ../shared/data/README.md).
//!
//! The host is run causally, as its live mode runs: frame by frame, each
//! epoch prepared with the ephemerides received before it. Both sides use
//! raim-nav's ranging kernel, so an epoch both form must be the same to
//! the bit: time, satellites, pseudoranges, positions and sigmas.

use raim_core::sigma::SigmaModel;
use raim_core::{Config, System};
use raim_gnss::ranging::{prepare_epoch, RangingOptions};
use raim_gnss::{NavData, ObsData};
use raim_nav::rtcm::{FormError, FormedEpoch, StreamReceiver};
use raim_recv::{Decoder, Item};

const GMSD7: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/GMSD7_20121014.rtcm3"
);
/// The GPS week of 2012-10-14 is 1711; a pivot after it resolves the
/// stream's 10-bit week 687 to it.
const PIVOT_WEEK: i64 = 2400;
/// Elevation mask of both sides, rad.
const MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;

/// The whole RTCM frames of a byte stream, in order (rtcm-rs checks each).
fn frames(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(rest) = bytes.get(i..).filter(|r| !r.is_empty()) {
        match (rest.first(), rtcm_rs::MessageFrame::new(rest)) {
            (Some(0xD3), Ok(f)) => {
                out.push(&rest[..f.frame_len()]);
                i += f.frame_len();
            }
            _ => i += 1,
        }
    }
    out
}

#[test]
fn device_receiver_forms_the_host_epochs_bit_for_bit() {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let model = Config::default().sigma_model;
    let glonass_model = SigmaModel {
        ura_m: raim_gnss::glonass::glonass_ura_m(model.ura_m),
        ..model
    };
    let opts = RangingOptions {
        systems: vec![System::Gps, System::Glonass],
        codes: raim_nav::ranging::STREAM_CODES
            .iter()
            .map(|(s, c)| (*s, c.iter().map(|c| c.to_string()).collect()))
            .collect(),
        elevation_mask_rad: MASK_RAD,
        iono: true,
        tropo: true,
        group_delay: true,
        glonass_sigma: Some(glonass_model),
    };
    let mut host = raim_recv::rtcm::Rtcm3::new(PIVOT_WEEK);
    let mut obs = ObsData {
        path: GMSD7.into(),
        approx_position_m: None,
        epochs: Vec::new(),
    };
    let mut nav = NavData::default();
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(PIVOT_WEEK));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut same, mut not_dated, mut host_only) = (0, 0, 0);
    let mut items = Vec::new();
    for (n, f) in frames(&bytes).into_iter().enumerate() {
        host.push(f, &mut items);

        let mut host_epochs = Vec::new();
        for it in items.drain(..) {
            match it {
                Item::Epoch(e) => host_epochs.push(e),
                other => raim_recv::apply(other, &mut obs, &mut nav),
            }
        }
        let dev_result = dev.on_frame(f, &model, MASK_RAD, &mut formed);
        match dev_result {
            None => {}
            Some(Err(FormError::NotDated { .. })) => not_dated += 1,
            Some(Err(e)) => panic!("{e}"),
            Some(Ok(())) => {
                let e = host_epochs.pop().unwrap_or_else(|| {
                    panic!(
                        "device epoch at {} s, none on the host (frame {}, message {:?}, host counts {})",
                        formed.time_gps_s,
                        n,
                        rtcm_rs::MessageFrame::new(f).ok().and_then(|m| m.message_number()),
                        host.counts()
                    )
                });
                assert_eq!(e.time_gps_s, formed.time_gps_s);
                let p = prepare_epoch(&nav, &e, &opts, obs.approx_position_m);
                assert_eq!(
                    p.reference_m, formed.reference_m,
                    "epoch {} s",
                    e.time_gps_s
                );
                let host_obs: Vec<_> = p.observations();
                assert_eq!(
                    host_obs.len(),
                    formed.sats.len(),
                    "epoch {} s",
                    e.time_gps_s
                );
                for (h, (d, s)) in host_obs.iter().zip(formed.sats.iter().zip(&p.sats)) {
                    assert_eq!(h.id, d.id);
                    assert_eq!(
                        h.pseudorange_m.to_bits(),
                        d.pseudorange_m.to_bits(),
                        "{:?}",
                        h.id
                    );
                    assert_eq!(h.position_m, d.position_m, "{:?}", h.id);
                    // The host sets stream sigmas after preparing (raim
                    // replay's `set_sigmas`); a GPS single-frequency range
                    // keeps the core's model there, with the ionosphere
                    // doubled through the configuration.
                    let want = raim_nav::ranging::stream_sigma_m(
                        h.id.system,
                        &s.code,
                        s.elevation_rad,
                        &model,
                        Some(&glonass_model),
                        2.0,
                    )
                    .unwrap_or_else(|| {
                        let mut m = model;
                        m.iono_vertical_m *= 2.0;
                        m.sigma_m(s.elevation_rad)
                    });
                    assert_eq!(d.sigma_m, Some(want), "{:?}", h.id);
                }
                same += 1;
            }
        }
        host_only += host_epochs.len();
    }
    let c = dev.counts();
    println!(
        "GMSD7: {same} epochs formed alike, {not_dated} before the first 1019, {host_only} host-only (released late); device counts {c:?}, ephemerides {:?}",
        dev.ephemerides()
    );
    // 257 epochs in the stream; the ones before the first GPS ephemeris
    // cannot be dated on the device.
    assert_eq!(same + not_dated, c.epochs as usize);
    assert!(same >= 250, "{same}");
    // rtcm-rs does not decode this stream's QZSS MSM7 (1117) on either
    // side; both count it.
    assert_eq!(u64::from(c.undecodable), host.counts().undecodable);
    assert_eq!(c.glonass_dropped, 0);
}
