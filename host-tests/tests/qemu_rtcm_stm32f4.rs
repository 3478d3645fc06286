//! The STM32F4 build with the stream receiver (docs/FLASH.md "STM32F4:
//! the stream"), under QEMU's netduinoplus2: the real GMSD7 RTCM 3 stream
//! (GPS + GLONASS MSM7 with 1019/1020) written into its link UART, and
//! the unit forming, running and answering its own epochs with the part's
//! capacities (24 satellites, 64 Keplerian sets kept as payloads, the
//! forming scratch sharing the answer's room).
//!
//! Checked against the host's causal RTCM replay (`rtcm_common`), its
//! epochs sent to an mps2-an386 unit as `Ranges` frames: every epoch the
//! STM32F4 answers has the same wire result, to the bit, and its stack
//! stays within the firmware's goal.

mod qemu_common;
mod rtcm_common;

use std::time::Duration;

use qemu_common::{session_on, wire_bytes};
use raim_core::{Decision, Epoch};
use raim_proto::error::WireError;
use raim_proto::message::{Response, ResponseBody};
use raim_qemu::{Machine, Options, QemuSession};
use rtcm_common::{frames, gmsd7_moved_to, host_epochs, in_window_week, GMSD7};

/// GMSD7 within the firmware's dating window (as `qemu_rtcm.rs`).
fn gmsd7_in_window() -> (Vec<u8>, i64) {
    let file = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let week = in_window_week();
    (gmsd7_moved_to(&file, week), week + 1)
}

/// The firmware's stack goal for every path (BENCHMARKS.md "Stack"), B.
const STACK_GOAL_BYTES: u32 = 16 * 1024;

/// The STM32F4 stream build's satellites (raim-server `SNAPSHOT_SATS`
/// with `ram-192k` and `rtcm`).
const F4_SATS: usize = 24;

/// How long the unit may take over the whole stream (257 epochs).
const STREAM_TIMEOUT: Duration = Duration::from_secs(300);

/// The stream up to the end of its last whole frame.
fn whole_frames(bytes: &[u8]) -> &[u8] {
    let end = frames(bytes).last().map_or(0, |f| {
        f.as_ptr() as usize - bytes.as_ptr() as usize + f.len()
    });
    &bytes[..end]
}

/// The stream's ephemeris frames (1019, 1020), in order.
fn ephemeris_frames(bytes: &[u8]) -> Vec<u8> {
    frames(bytes)
        .into_iter()
        .filter(|f| {
            let n = rtcm_rs::MessageFrame::new(f)
                .ok()
                .and_then(|m| m.message_number());
            matches!(n, Some(1019 | 1020))
        })
        .flatten()
        .copied()
        .collect()
}

/// Stream `bytes` into the unit's link and collect `n` unasked answers.
fn stream_answers(fw: &mut QemuSession, bytes: &[u8], n: usize) -> Vec<Response> {
    for chunk in bytes.chunks(4096) {
        fw.send_raw(chunk).unwrap();
    }
    let mut out = Vec::new();
    let deadline = std::time::Instant::now() + STREAM_TIMEOUT;
    while out.len() < n {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        let r = fw
            .recv(left.max(Duration::from_millis(1)))
            .unwrap_or_else(|e| panic!("after {} answers: {e}", out.len()));
        assert_eq!(r.seq, None, "a stream epoch's answer is unasked: {r:?}");
        out.push(r);
    }
    out
}

/// GMSD7 (ephemerides first, as `qemu_rtcm`'s bit-for-bit test) through
/// the STM32F4 stream build's link: every epoch answered as the host
/// replay's epoch through a unit, to the bit; `Status` says 24
/// satellites; the stack high water is within the 16 KiB goal.
///
/// Verifies: RX-STREAM, SAFE-STACK
#[test]
fn qemu_stm32f4_stream_epochs_equal_the_host_replay_bit_for_bit() {
    let (file, now_week) = gmsd7_in_window();
    let once = whole_frames(&file);
    let warm = [ephemeris_frames(once).as_slice(), once].concat();
    let bytes = warm.as_slice();
    let (host, counts) = host_epochs(bytes, now_week);
    let n_epochs = counts.epochs as usize;

    let elf = raim_qemu::firmware_elf_stm32f4_stream().expect("STM32F4 stream build");
    let mut fw = QemuSession::start_with(
        &elf,
        &Options {
            machine: Machine::NetduinoPlus2,
            ..Options::default()
        },
    )
    .expect("qemu-system-arm with the STM32F4 stream build");
    let answers = stream_answers(&mut fw, bytes, n_epochs);
    let status = fw.status().unwrap();
    assert_eq!(status.capacity as usize, F4_SATS);
    assert_eq!(status.rtcm_frames, frames(bytes).len() as u32);
    assert_eq!(status.rtcm_bad_crc, 0);
    assert_eq!(status.stream_epochs as usize, n_epochs);
    assert!(
        status.stack_high_water_bytes <= STACK_GOAL_BYTES,
        "stack high water {} B",
        status.stack_high_water_bytes
    );
    assert!(status.stream_ephemerides[0] > 0 && status.stream_ephemerides[1] > 0);

    let mut reference = session_on(Machine::Mps2An386);
    let (mut same, mut not_dated, mut refused, mut decisions) = (0, 0, 0, [0usize; 4]);
    let mut most_sats = 0;
    assert_eq!(answers.len(), host.len());
    for (a, h) in answers.iter().zip(&host) {
        let time_s = raim_nav::time::unix_utc_s(h.prepared.time_gps_s);
        if let ResponseBody::Error(WireError::StreamNotDated { .. }) = a.body {
            not_dated += 1;
            continue;
        }
        most_sats = most_sats.max(h.obs.len());
        let want = reference
            .process(&Epoch::ranges(time_s, &h.obs, h.prepared.reference_m))
            .unwrap()
            .outcome;
        match (&a.body, want) {
            (ResponseBody::Result(r), Ok(want)) => {
                assert_eq!(wire_bytes(r), wire_bytes(&want), "epoch at {time_s} s");
                let k = match r.decision {
                    Decision::Ok => 0,
                    Decision::Excluded => 1,
                    Decision::Alarm => 2,
                    Decision::Unavailable => 3,
                };
                decisions[k] += 1;
                same += 1;
            }
            (ResponseBody::Error(e), Err(want)) => {
                assert_eq!(*e, want, "epoch at {time_s} s");
                refused += 1;
            }
            (got, want) => panic!("epoch at {time_s} s: unit {got:?}, host {want:?}"),
        }
    }
    println!(
        "GMSD7 through the STM32F4 stream build: {same} epochs answered as the host replay's (ok/excluded/alarm/unavailable {decisions:?}), {refused} refused alike, {not_dated} not dated; at most {most_sats} satellites; stack high water {} B",
        status.stack_high_water_bytes
    );
    assert_eq!(same + refused + not_dated, n_epochs);
    assert!(most_sats <= F4_SATS, "GMSD7 within the part's capacity");
    assert!(same * 10 >= n_epochs * 8, "{same} of {n_epochs}");
    assert_eq!(decisions[2], 0);
}
