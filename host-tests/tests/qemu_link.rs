//! Under QEMU (mps2-an386, and netduinoplus2 for the stream):
//! - no byte lost: the host streams 1,000 frames back to back without
//!   waiting for answers; the firmware receives them by interrupt into its
//!   ring (`firmware/src/link_rx.rs`) and answers every one, in order, bit
//!   for bit as the host core; no UART overrun is counted (QEMU's UART
//!   holds the sender back), and when the ring filled (reception paused,
//!   `rx_ring_overflows`) no byte was lost either;
//! - the integrity-alarm discrete output (`firmware/src/discrete.rs`): its
//!   state in `Status` (and the pin read back) from boot, after a valid
//!   epoch, after an alarm or unavailable epoch, after an errored epoch,
//!   and once the time-to-alert has passed without an epoch.

mod qemu_common;

use std::time::{Duration, Instant};

use qemu_common::{host_result, range_epoch, range_vectors, stream_session_on, wire_bytes, Rng};
use raim_core::{Config, Decision, Epoch, System};
use raim_proto::message::{CommandRef, ResponseBody};
use raim_proto::AlarmOutput;
use raim_qemu::{epoch_command, Machine, Options, QemuSession, ANSWER_TIMEOUT};

/// Frames streamed back to back on mps2-an386, and (to keep CI short) on
/// netduinoplus2.
const STREAM_FRAMES: u32 = 1000;
const STREAM_FRAMES_NETDUINO: u32 = 200;
/// The firmware's default time-to-alert (`RAIM_TIME_TO_ALERT_S`).
const TIME_TO_ALERT_S: f64 = 10.0;
/// The output asserts up to one SysTick wrap (2^24 ticks at 25 MHz) before
/// the time-to-alert (firmware/src/discrete.rs).
const CHECK_PERIOD_S: f64 = 16_777_216.0 / 25.0e6;
/// How long past the time-to-alert the test waits for the output before it
/// calls the unit hung (a deadline only a hang reaches, not a timing check).
const TTA_HANG_DEADLINE: Duration = Duration::from_secs(120);
/// The pace of the status polls while waiting for the time-to-alert.
const POLL_PERIOD: Duration = Duration::from_millis(250);

/// Verifies: SAFE-LINK
#[test]
fn qemu_streamed_frames_are_all_answered_in_order() {
    stream(Machine::Mps2An386, STREAM_FRAMES);
}

/// The real-board build (USART2 by interrupt on stm32f4xx-hal) under
/// QEMU's netduinoplus2. Both machines' streaming builds have a 30 s
/// pause on the link (`raim_qemu::NETDUINOPLUS2_LINK_IDLE_S`): a loaded
/// host that does not run QEMU for 0.25 s between two bytes would
/// otherwise cut a frame (docs/EVIDENCE.md "The suite under load").
#[test]
fn qemu_netduinoplus2_streamed_frames_are_all_answered_in_order() {
    stream(Machine::NetduinoPlus2, STREAM_FRAMES_NETDUINO);
}

/// On the machine's streaming build (`raim_qemu::firmware_elf_stream`).
fn stream(machine: Machine, frames: u32) {
    let mut fw = stream_session_on(machine);
    let before = fw.status().unwrap();
    let seq0 = fw.next_seq();
    let cfg = Config::default();
    let vectors = range_vectors(11);
    let expected: Vec<Result<Vec<u8>, ()>> = vectors
        .iter()
        .map(|(t, s, a)| {
            host_result(&cfg, &Epoch::ranges(*t, s, *a))
                .map(|r| wire_bytes(&r))
                .map_err(|_| ())
        })
        .collect();
    // Every other frame a Status, the others the vectors in turn.
    let mut stream = Vec::new();
    let mut kinds = Vec::new();
    for i in 0..frames as usize {
        let command = if i % 2 == 1 {
            kinds.push(None);
            CommandRef::Status
        } else {
            let v = (i / 2) % vectors.len();
            kinds.push(Some(v));
            let (t, s, a) = &vectors[v];
            epoch_command(&Epoch::ranges(*t, s, *a))
        };
        let (seq, bytes) = fw.frame(command).unwrap();
        assert_eq!(seq, seq0 + i as u32);
        stream.extend(bytes);
    }
    let t0 = Instant::now();
    fw.send_raw(&stream).unwrap();
    for (i, kind) in kinds.iter().enumerate() {
        let r = fw.recv(ANSWER_TIMEOUT).unwrap();
        assert_eq!(r.seq, Some(seq0 + i as u32), "answer {i}: {:?}", r.body);
        match (kind, r.body) {
            (None, ResponseBody::Status(st)) => {
                assert_eq!(st.frames, before.frames + i as u32 + 1);
                assert_eq!(st.uart_overruns, 0);
            }
            (Some(v), ResponseBody::Result(res)) => {
                assert_eq!(Ok(wire_bytes(&res)), expected[*v], "frame {i}")
            }
            (Some(v), ResponseBody::Error(_)) => assert!(expected[*v].is_err(), "frame {i}"),
            (k, body) => panic!("frame {i} ({k:?}) answered {body:?}"),
        }
    }
    let s = t0.elapsed().as_secs_f64();
    let st = fw.status().unwrap();
    assert_eq!(st.frames, before.frames + frames + 1);
    assert_eq!(st.uart_overruns, 0);
    eprintln!(
        "{machine:?}: {frames} frames ({} bytes) streamed and answered in {s:.2} s: {:.0} frames/s, \
         {:.0} bytes/s; ring full {} times",
        stream.len(),
        f64::from(frames) / s,
        stream.len() as f64 / s,
        st.rx_ring_overflows
    );
}

/// Verifies: SAFE-ALARM
#[test]
fn qemu_integrity_alarm_output_follows_the_epochs_and_the_time_to_alert() {
    // No -icount: the guest's SysTick runs on QEMU's virtual clock, which
    // is the host's monotonic clock while the guest runs.
    let elf = raim_qemu::firmware_elf().unwrap();
    let mut fw = QemuSession::start_with(&elf, &Options::default()).unwrap();
    let cfg = Config::default();
    let mut vectors = range_vectors(3);
    // Five satellites, one with a 200 m fault: detected, and no subset is
    // left to exclude it with: Alarm.
    let sky: Vec<(f64, f64)> = (0..5)
        .map(|i| (i as f64 * 31.0, 12.0 + (i as f64 * 23.0) % 70.0))
        .collect();
    let faulty = range_epoch(&sky, &[System::Gps], &mut Rng::new(5), &[(2, 200.0)]);
    vectors.push((vectors[0].0 + 10.0, faulty, None));
    let outcome = |v: &(f64, Vec<_>, Option<[f64; 3]>)| {
        host_result(&cfg, &Epoch::ranges(v.0, &v.1, v.2)).map(|r| r.decision)
    };
    let pick = |want: &dyn Fn(Result<Decision, ()>) -> bool| {
        vectors
            .iter()
            .find(|v| want(outcome(v).map_err(|_| ())))
            .expect("a vector of each kind")
    };
    let valid = pick(&|d| matches!(d, Ok(Decision::Ok | Decision::Excluded)));
    let alarm = pick(&|d| matches!(d, Ok(Decision::Alarm | Decision::Unavailable)));
    let errored = pick(&|d| d.is_err());
    let alarm_state = match outcome(alarm) {
        Ok(Decision::Alarm) => AlarmOutput::Alarm,
        _ => AlarmOutput::Unavailable,
    };
    let state = |fw: &mut QemuSession| {
        let st = fw.status().unwrap();
        assert_eq!(st.alarm_pin_asserted, st.alarm_output.asserted(), "{st:?}");
        st.alarm_output
    };
    let run = |fw: &mut QemuSession, v: &(f64, Vec<_>, Option<[f64; 3]>)| {
        fw.process(&Epoch::ranges(v.0, &v.1, v.2)).unwrap();
    };
    assert_eq!(state(&mut fw), AlarmOutput::NoValidEpoch);
    run(&mut fw, valid);
    assert_eq!(state(&mut fw), AlarmOutput::Clear);
    run(&mut fw, alarm);
    assert_eq!(state(&mut fw), alarm_state);
    run(&mut fw, valid);
    assert_eq!(state(&mut fw), AlarmOutput::Clear);
    run(&mut fw, errored);
    assert_eq!(state(&mut fw), AlarmOutput::EpochError);
    // The last valid epoch: sent at `s0`, answered at `r0` (host clock).
    // Without -icount the guest's clock is QEMU's virtual clock, the
    // host's monotonic clock while the guest runs, so the unit ran this
    // epoch at a guest time in [s0, r0], and it may assert the output
    // from one check period before the time-to-alert after that.
    let s0 = Instant::now();
    run(&mut fw, valid);
    let r0 = Instant::now();
    assert_eq!(state(&mut fw), AlarmOutput::Clear);
    // Poll until the output asserts, with a deadline only a hang reaches.
    // Each answer is read at a guest time in [s, r] of its request, so an
    // assertion answered by r < s0 + TTA - one check period would be early,
    // whatever the machine's load; a late one is measured in the guest's
    // own time by the hung-loop test (qemu_fail_loud).
    let earliest = Duration::from_secs_f64(TIME_TO_ALERT_S - CHECK_PERIOD_S);
    let hang = r0 + Duration::from_secs_f64(TIME_TO_ALERT_S) + TTA_HANG_DEADLINE;
    let mut clear_polls = 0u32;
    loop {
        let st = state(&mut fw);
        let r = Instant::now();
        match st {
            AlarmOutput::Clear => clear_polls += 1,
            AlarmOutput::TimeToAlertExceeded => {
                assert!(
                    r.duration_since(s0) >= earliest,
                    "asserted {:.2} s after the valid epoch was sent, before {:.2} s",
                    r.duration_since(s0).as_secs_f64(),
                    earliest.as_secs_f64()
                );
                break;
            }
            other => panic!("after a valid epoch and no other: {other:?}"),
        }
        assert!(r < hang, "the time-to-alert never asserted the output");
        std::thread::sleep(POLL_PERIOD);
    }
    // The output was seen clear after the epoch before it asserted.
    assert!(clear_polls >= 1);
    assert_eq!(state(&mut fw), AlarmOutput::TimeToAlertExceeded);
    run(&mut fw, valid);
    assert_eq!(state(&mut fw), AlarmOutput::Clear);
}
