//! The firmware's RTCM 3 receiver (`raim_nav::rtcm::StreamReceiver`, no_std,
//! fixed capacity) against the host's stream reader (`raim_recv::rtcm`, a
//! separate decoder, dating and ephemeris store) on the real GMSD7 stream
//! (GPS + GLONASS MSM7, 1019 and 1020; ../shared/data/README.md).
//!
//! The host is run causally, as its live mode runs (`rtcm_common`). Both
//! sides use raim-nav's ranging kernel, so an epoch both form must be the
//! same to the bit: time, reference, satellites, pseudoranges, positions
//! and sigmas.

mod rtcm_common;

use raim_core::Config;
use raim_nav::rtcm::{FormError, FormedEpoch, StreamReceiver};
use rtcm_common::{frames, host_epochs, GMSD7, MASK_RAD, PIVOT_WEEK};

#[test]
fn device_receiver_forms_the_host_epochs_bit_for_bit() {
    let bytes = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let model = Config::default().sigma_model;
    let (host, host_counts) = host_epochs(&bytes);
    let mut dev = Box::new(StreamReceiver::<64, 256>::new(PIVOT_WEEK));
    let mut formed = FormedEpoch::<64> {
        time_gps_s: 0.0,
        reference_m: None,
        sats: heapless::Vec::new(),
        rejected: 0,
    };
    let (mut same, mut not_dated) = (0, 0);
    for (n, f) in frames(&bytes).into_iter().enumerate() {
        match dev.on_frame(f, &model, MASK_RAD, &mut formed) {
            None => {}
            Some(Err(FormError::NotDated { .. })) => not_dated += 1,
            Some(Err(e)) => panic!("{e}"),
            Some(Ok(())) => {
                let h = host
                    .iter()
                    .find(|h| h.prepared.time_gps_s == formed.time_gps_s)
                    .unwrap_or_else(|| {
                        panic!("device epoch at {} s, none on the host", formed.time_gps_s)
                    });
                // The host releases an epoch at the frame that closes it,
                // as the device does.
                assert_eq!(h.frame, n, "epoch {} s", formed.time_gps_s);
                assert_eq!(h.prepared.reference_m, formed.reference_m);
                assert_eq!(
                    h.obs.len(),
                    formed.sats.len(),
                    "epoch {} s",
                    formed.time_gps_s
                );
                for (h, d) in h.obs.iter().zip(formed.sats.iter()) {
                    assert_eq!(h.id, d.id);
                    assert_eq!(
                        h.pseudorange_m.to_bits(),
                        d.pseudorange_m.to_bits(),
                        "{:?}",
                        h.id
                    );
                    assert_eq!(h.position_m, d.position_m, "{:?}", h.id);
                    assert_eq!(h.sigma_m, d.sigma_m, "{:?}", h.id);
                }
                same += 1;
            }
        }
    }
    let c = dev.counts();
    println!(
        "GMSD7: {same} epochs formed alike, {not_dated} before the first 1019; host {} epochs; device counts {c:?}, ephemerides {:?}",
        host.len(),
        dev.ephemerides()
    );
    // 257 epochs in the stream; the one before the first GPS ephemeris
    // cannot be dated on the device (the host holds it back until then).
    assert_eq!(same + not_dated, c.epochs as usize);
    assert_eq!(c.epochs as u64, host_counts.epochs);
    assert!(same >= 250, "{same}");
    // rtcm-rs does not decode this stream's QZSS MSM7 (1117): the host
    // counts it undecodable. The device's decoder reads GPS and GLONASS
    // only: every other message (1117 among them) is counted ignored.
    let other = frames(&bytes)
        .iter()
        .filter(|f| {
            let n = rtcm_rs::MessageFrame::new(f)
                .ok()
                .and_then(|x| x.message_number());
            !matches!(n, Some(1077 | 1087 | 1019 | 1020))
        })
        .count();
    assert_eq!(c.undecodable, 0);
    assert!(host_counts.undecodable > 0);
    assert_eq!(c.ignored as usize, other);
    assert_eq!(c.glonass_dropped, 0);
}
