//! A receiver wired straight to the unit, under QEMU (mps2-an386): the
//! real GMSD7 RTCM 3 stream (GPS + GLONASS MSM7 with 1019/1020) written
//! into the link UART, and the unit forming, running and answering its own
//! epochs (raim-server's `stream`, raim-nav's receiver).
//!
//! Checked against two references:
//! - the host's causal RTCM replay (`rtcm_common`: raim-recv's reader,
//!   raim-gnss's preparation), its epochs sent to a second unit as
//!   `Ranges` frames: every epoch the stream unit answers has the same
//!   wire result, to the bit (the device's precision, f32);
//! - the same bytes through raim-server's `Server` on the host: the same
//!   answer frames, byte for byte.

mod qemu_common;
mod rtcm_common;

use std::time::Duration;

use qemu_common::{session_on, stream_session_on, wire_bytes, Sink};
use raim_core::{Config, Decision, Epoch};
use raim_proto::error::WireError;
use raim_proto::message::{CommandRef, Response, ResponseBody};
use raim_qemu::{Machine, Options, QemuSession, ANSWER_TIMEOUT};
use rtcm_common::{frames, gmsd7_moved_to, host_epochs, in_window_week, GMSD7};

/// GMSD7 as a receiver would send it within this firmware's dating window
/// (`rtcm_common::gmsd7_moved_to`: the same orbits and observables, dated
/// half a year after the firmware's pivot): the unit dates a stream from
/// its build date on, so the 2012 recording as sent would be read 1024
/// weeks on. Returns the bytes and the host reader's clock week for them.
fn gmsd7_in_window() -> (Vec<u8>, i64) {
    let file = std::fs::read(GMSD7).expect("GMSD7 stream (../shared/data)");
    let week = in_window_week();
    (gmsd7_moved_to(&file, week), week + 1)
}

/// The firmware's stack goal for every path (BENCHMARKS.md "Stack"), B.
const STACK_GOAL_BYTES: u32 = 16 * 1024;

/// How long the unit may take over the whole stream (257 epochs).
const STREAM_TIMEOUT: Duration = Duration::from_secs(300);

/// The stream up to the end of its last whole frame (the shared file is
/// cut at 256 KiB inside a frame).
fn whole_frames(bytes: &[u8]) -> &[u8] {
    let end = frames(bytes).last().map_or(0, |f| {
        f.as_ptr() as usize - bytes.as_ptr() as usize + f.len()
    });
    &bytes[..end]
}

/// The stream's ephemeris frames (1019, 1020), in order: what a receiver
/// sends of its stored ephemerides at start-up.
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

/// Verifies: RX-STREAM, RX-DATING, RX-LINK, SAFE-STACK
#[test]
fn qemu_rtcm_stream_epochs_equal_the_host_replay_bit_for_bit() {
    let (file, now_week) = gmsd7_in_window();
    let once = whole_frames(&file);
    assert_eq!(file.len() - once.len(), 302, "the cut last frame");
    // Cold, the ephemerides arrive over the stream's 257 s, a satellite at
    // a time, and few epochs have enough of them. So the stream is sent
    // warm: its ephemeris frames first, then the whole stream.
    let warm = [ephemeris_frames(once).as_slice(), once].concat();
    let bytes = warm.as_slice();
    let (host, counts) = host_epochs(bytes, now_week);
    let n_epochs = counts.epochs as usize;

    // The unit fed the stream (its streaming build: a loaded host's stall
    // of QEMU is not a pause to it; the pause itself:
    // `qemu_rtcm_a_cut_frame_is_ended_by_the_pause`).
    let mut fw = stream_session_on(Machine::Mps2An386);
    let answers = stream_answers(&mut fw, bytes, n_epochs);
    let status = fw.status().unwrap();
    let nframes = frames(bytes).len() as u32;
    assert_eq!(status.rtcm_frames, nframes);
    assert_eq!(status.rtcm_bad_crc, 0);
    assert_eq!(status.stream_epochs as usize, n_epochs);
    // The whole stream (frames decoded, epochs formed with their bootstrap
    // solve, answered) within the firmware's stack goal.
    assert!(
        status.stack_high_water_bytes <= STACK_GOAL_BYTES,
        "stack high water {} B",
        status.stack_high_water_bytes
    );
    assert!(status.stream_ephemerides[0] > 0 && status.stream_ephemerides[1] > 0);

    // The host's epochs through a second unit.
    let mut reference = session_on(Machine::Mps2An386);
    let (mut same, mut not_dated, mut refused, mut decisions) = (0, 0, 0, [0usize; 4]);
    // Epochs solved (Ok or Excluded), epochs.
    let mut solved = [0usize; 2];
    // Answers and host epochs pair up in order.
    assert_eq!(answers.len(), host.len());
    for (a, h) in answers.iter().zip(&host) {
        solved[1] += 1;
        let time_s = raim_nav::time::unix_utc_s(h.prepared.time_gps_s);
        if let ResponseBody::Error(WireError::StreamNotDated { .. }) = a.body {
            // Before the first GPS ephemeris; the host held this epoch
            // back until then.
            not_dated += 1;
            continue;
        }
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
                if k < 2 {
                    solved[0] += 1;
                }
            }
            // An epoch with too few satellites (the first ephemerides):
            // the same typed error.
            (ResponseBody::Error(e), Err(want)) => {
                assert_eq!(*e, want, "epoch at {time_s} s");
                if refused < 5 || refused % 50 == 0 {
                    println!("refused at {time_s}: {e} ({} sats)", h.obs.len());
                }
                refused += 1;
            }
            (got, want) => panic!("epoch at {time_s} s: unit {got:?}, host {want:?}"),
        }
    }
    println!(
        "GMSD7 (ephemerides first) through the link: {same} epochs answered as the host replay's (ok/excluded/alarm/unavailable {decisions:?}), {refused} refused alike, {not_dated} not dated; {} of {} solved; {status:?}",
        solved[0], solved[1]
    );
    assert_eq!(same + refused + not_dated, n_epochs);
    assert!(solved[0] * 10 >= solved[1] * 8, "{solved:?}");
    // A clean station stream: no alarm.
    assert_eq!(decisions[2], 0);
}

/// The file's cut last frame (302 bytes of a longer one), as a receiver
/// losing power mid-frame, on the default build (the unit's 0.25 s pause,
/// `raim_server::LINK_IDLE_S`): it holds the link until the pause
/// (checked at SysTick wraps), which ends it as a bad chunk; the next
/// request is answered.
///
/// Verifies: RX-LINK
#[test]
fn qemu_rtcm_a_cut_frame_is_ended_by_the_pause() {
    let (file, _) = gmsd7_in_window();
    let once = whole_frames(&file);
    assert_eq!(file.len() - once.len(), 302, "the cut last frame");
    let mut fw = session_on(Machine::Mps2An386);
    fw.send_raw(&file[once.len()..]).unwrap();
    // The event, not a wait: only the pause decides a candidate that never
    // reaches its declared length (no host frame follows to resynchronise
    // on), and the bytes it gives up come back as the unit's unasked
    // refusals. The deadline is one only a hang reaches.
    let first = fw.recv(STREAM_TIMEOUT).unwrap();
    assert!(
        first.seq.is_none() && matches!(first.body, ResponseBody::Error(_)),
        "the cut frame at the pause: {first:?}"
    );
    // Then the link takes a host frame again; any further refusals of the
    // same bytes come before its answer.
    let seq = fw.send(CommandRef::Status).unwrap();
    let status = loop {
        let r = fw.recv(STREAM_TIMEOUT).unwrap();
        match (r.seq, r.body) {
            (None, ResponseBody::Error(_)) => {}
            (Some(s), ResponseBody::Status(status)) if s == seq => break status,
            other => panic!("after the cut frame: {other:?}"),
        }
    };
    assert_eq!(status.rtcm_frames, 0);
    assert_eq!(status.rtcm_bad_crc, 0);
}

/// The same bytes through the host's `Server` (the firmware's protocol
/// loop, compiled for x86): the unit's answer frames byte for byte.
///
/// Verifies: RX-STREAM
#[test]
fn qemu_rtcm_answers_equal_the_host_server_byte_for_byte() {
    let (bytes, _) = gmsd7_in_window();
    let part = whole_frames(&bytes[..40_000.min(bytes.len())]);
    let mut fw = stream_session_on(Machine::Mps2An386);
    let mut server = raim_server::Server::new();
    server.take_runtime_config(Config::default()).unwrap();
    let mut link = Sink(Vec::new());
    let mut nmea = Sink(Vec::new());
    for &b in part {
        server
            .on_byte(b, &mut link, &mut nmea, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let mut rx = raim_proto::frame::FrameReceiver::<{ raim_proto::MAX_RESPONSE_FRAME }>::new();
    let host: Vec<Response> = link
        .0
        .iter()
        .filter_map(|&b| match rx.push(b) {
            Some(Ok(p)) => Some(postcard::from_bytes::<Response>(p).expect("host answer")),
            Some(Err(e)) => panic!("host answer frame: {e}"),
            None => None,
        })
        .collect();
    assert!(host.len() >= 30, "{}", host.len());
    let unit = stream_answers(&mut fw, part, host.len());
    for (h, u) in host.iter().zip(&unit) {
        assert_eq!(h.seq, u.seq);
        match (&h.body, &u.body) {
            (ResponseBody::Result(a), ResponseBody::Result(b)) => {
                assert_eq!(wire_bytes(a), wire_bytes(b), "epoch at {} s", a.time_s)
            }
            (a, b) => assert_eq!(a, b),
        }
    }
    // Nothing more from the unit: the next answer is the one to a status
    // request sent now (the unit answers in order, so an unasked answer
    // still to come would arrive before it), whatever the machine's load.
    let seq = fw.send(CommandRef::Status).unwrap();
    let r = fw.recv(ANSWER_TIMEOUT).unwrap();
    assert_eq!(r.seq, Some(seq), "an answer after the stream's: {r:?}");
    let ResponseBody::Status(status) = r.body else {
        panic!("{r:?}");
    };
    // And every epoch the unit formed was one of those answered.
    assert_eq!(status.stream_epochs as usize, host.len());
}

/// The unit's NMEA on a warm stream (GMSD7's ephemerides, then its first
/// 60 kB) equals the host `Server`'s on the same bytes, byte for byte:
/// RMC and VTG with the speed and course of the Doppler velocity (f64
/// soft-float on the M4, libm everywhere) among them.
///
/// Verifies: RX-STREAM, NMEA-VELOCITY
#[test]
fn qemu_rtcm_nmea_with_speed_and_course_equals_the_host_server() {
    let (file, now_week) = gmsd7_in_window();
    let once = whole_frames(&file);
    let part = whole_frames(&once[..60_000]);
    let warm = [ephemeris_frames(once).as_slice(), part].concat();
    let (_, counts) = host_epochs(&warm, now_week);
    let mut server = raim_server::Server::new();
    server.take_runtime_config(Config::default()).unwrap();
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    for &b in &warm {
        server
            .on_byte(b, &mut link, &mut nmea, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let host: Vec<String> = String::from_utf8(nmea.0)
        .unwrap()
        .lines()
        .map(|l| l.trim_end().to_string())
        .collect();
    let with_speed = host
        .iter()
        .filter(|l| &l[3..6] == "RMC" && l.split(',').nth(7).is_some_and(|f| !f.is_empty()))
        .count();
    assert!(with_speed >= 40, "{with_speed} RMC with a speed");
    let mut fw = stream_session_on(Machine::Mps2An386);
    fw.drain_nmea();
    let answers = stream_answers(&mut fw, &warm, counts.epochs as usize);
    assert_eq!(answers.len(), counts.epochs as usize);
    // The NMEA UART is read by its own thread: wait, with a deadline only
    // a hang reaches, for the sentences the host wrote.
    let mut unit = fw.drain_nmea();
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    while unit.len() < host.len() && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        unit.extend(fw.drain_nmea());
    }
    let unit: Vec<String> = unit.iter().map(|s| s.trim_end().to_string()).collect();
    assert_eq!(unit, host);
    println!(
        "{} NMEA sentences alike, {with_speed} RMC with speed and course",
        host.len()
    );
}

/// An unconfigured unit keeps the stream's ephemerides but puts nothing in
/// force: every stream epoch is answered `Unconfigured` (or not dated).
///
/// Verifies: WIRE-Unconfigured, WIRE-StreamNotDated, RX-STREAM
#[test]
fn qemu_rtcm_stream_on_an_unconfigured_unit_is_refused() {
    let (bytes, now_week) = gmsd7_in_window();
    let part = whole_frames(&bytes[..20_000.min(bytes.len())]);
    let elf = raim_qemu::firmware_elf_stream(Machine::Mps2An386).unwrap();
    let mut fw = QemuSession::start_with(
        &elf,
        &Options {
            raw: true,
            ..Options::default()
        },
    )
    .unwrap();
    let (_, counts) = host_epochs(part, now_week);
    let answers = stream_answers(&mut fw, part, counts.epochs as usize);
    let mut unconfigured = 0;
    for a in &answers {
        match &a.body {
            ResponseBody::Error(WireError::Unconfigured { .. }) => unconfigured += 1,
            ResponseBody::Error(WireError::StreamNotDated { .. }) => {}
            other => panic!("unconfigured unit answered {other:?}"),
        }
    }
    assert!(
        unconfigured >= answers.len() - 1,
        "{unconfigured} of {}",
        answers.len()
    );
    let s = fw.status().unwrap();
    assert!(s.stream_ephemerides[0] > 0, "ephemerides are kept: {s:?}");
}

/// The cost of a stream epoch on the unit (BENCHMARKS.md), under
/// `-icount shift=0` (a SysTick tick is 40 guest instructions): the
/// forming of the last epoch (`Status.last_stream_ticks`: its closing
/// frame's decoding, the orbits and clocks, the corrections, the bootstrap
/// solution) and its monitor run (`last_epoch_ticks`). Printed, not
/// asserted (a benchmark).
#[test]
fn qemu_rtcm_stream_epoch_cost() {
    let (file, now_week) = gmsd7_in_window();
    let once = whole_frames(&file);
    let part = whole_frames(&once[..60_000]);
    let warm = [ephemeris_frames(once).as_slice(), part].concat();
    let (host, counts) = host_epochs(&warm, now_week);
    let elf = raim_qemu::firmware_elf_stream(Machine::Mps2An386).unwrap();
    let mut fw = QemuSession::start_with(
        &elf,
        &Options {
            icount: true,
            ..Options::default()
        },
    )
    .unwrap();
    let answers = stream_answers(&mut fw, &warm, counts.epochs as usize);
    let s = fw.status().unwrap();
    let last = answers.last().unwrap();
    let sats = host.last().map_or(0, |h| h.obs.len());
    println!(
        "stream epoch, {sats} satellites (G+R iono-free), answer {}: forming {} ticks = {} instructions; monitor {} ticks = {} instructions; stack high water {} B",
        match &last.body {
            ResponseBody::Result(r) => format!("{:?}", r.decision),
            other => format!("{other:?}"),
        },
        s.last_stream_ticks,
        40 * u64::from(s.last_stream_ticks),
        s.last_epoch_ticks,
        40 * u64::from(s.last_epoch_ticks),
        s.stack_high_water_bytes
    );
    assert!(s.last_stream_ticks > 0);
}

/// The G+E+C stream generated from ESBC's RINEX (`rtcm_common::esbc`:
/// 1005, 1019/1046/1042, MSM7 1077/1097/1127), sent in this build's dating
/// window into the unit's link: every epoch is formed and answered as a
/// second unit answers the host replay's epoch (the same wire bytes), with
/// Galileo and BeiDou in the solution, within the stack goal.
///
/// Verifies: RX-MULTI, RX-STREAM
#[test]
fn qemu_rtcm_esbc_gec_stream_answers_equal_the_host_replay() {
    use rtcm_common::esbc::{esbc_stream, EPOCHS, ESBC_WEEK};
    let week = in_window_week();
    let (bytes, _) = esbc_stream(week - ESBC_WEEK);
    let (host, counts) = host_epochs(&bytes, week + 1);
    assert_eq!(counts.epochs as usize, EPOCHS);
    assert_eq!(host.len(), EPOCHS);
    let mut fw = stream_session_on(Machine::Mps2An386);
    let answers = stream_answers(&mut fw, &bytes, EPOCHS);
    let status = fw.status().unwrap();
    assert_eq!(status.rtcm_frames, frames(&bytes).len() as u32);
    assert_eq!(status.stream_epochs as usize, EPOCHS);
    assert!(
        status.stack_high_water_bytes <= STACK_GOAL_BYTES,
        "stack high water {} B",
        status.stack_high_water_bytes
    );
    let mut reference = session_on(Machine::Mps2An386);
    let (mut ok, mut systems) = (0, std::collections::BTreeSet::new());
    for (a, h) in answers.iter().zip(&host) {
        let time_s = raim_nav::time::unix_utc_s(h.prepared.time_gps_s);
        let want = reference
            .process(&Epoch::ranges(time_s, &h.obs, h.prepared.reference_m))
            .unwrap()
            .outcome;
        match (&a.body, want) {
            (ResponseBody::Result(r), Ok(want)) => {
                assert_eq!(wire_bytes(r), wire_bytes(&want), "epoch at {time_s} s");
                assert_eq!(r.decision, Decision::Ok, "a clean stream: {r:?}");
                systems.extend(h.obs.iter().map(|s| s.id.system));
                ok += 1;
            }
            (got, want) => panic!("epoch at {time_s} s: unit {got:?}, host {want:?}"),
        }
    }
    println!(
        "ESBC G+E+C stream in week {week}: {ok} of {EPOCHS} epochs answered Ok as the host replay's, systems {systems:?}; stack high water {} B, last stream epoch {} ticks",
        status.stack_high_water_bytes, status.last_stream_ticks
    );
    assert_eq!(ok, EPOCHS);
    assert_eq!(systems.len(), 3, "{systems:?}");
}

/// The forming's instructions (`Status.last_stream_ticks` x 40, under
/// `-icount shift=0`) of every epoch of `bytes`, read after each epoch's
/// answer: the stream is sent an epoch at a time, each up to its closing
/// 1127 (the last MSM of every epoch of GMSD7's and of the ESBC stream,
/// DF393 = 0), and the unit's answer awaited (a deadline only a hang
/// reaches).
fn forming_per_epoch(bytes: &[u8]) -> Vec<u64> {
    let elf = raim_qemu::firmware_elf_stream(Machine::Mps2An386).unwrap();
    let mut fw = QemuSession::start_with(
        &elf,
        &Options {
            icount: true,
            ..Options::default()
        },
    )
    .unwrap();
    let mut out = Vec::new();
    let mut chunk = Vec::new();
    for f in frames(bytes) {
        chunk.extend_from_slice(f);
        let number = (u16::from(f[3]) << 4) | (u16::from(f[4]) >> 4);
        if number == 1127 {
            fw.send_raw(&chunk).unwrap();
            chunk.clear();
            let r = fw.recv(STREAM_TIMEOUT).unwrap();
            assert_eq!(r.seq, None, "a stream epoch's answer is unasked: {r:?}");
            out.push(40 * u64::from(fw.status().unwrap().last_stream_ticks));
        }
    }
    out
}

/// The forming's cost at every epoch, with the Keplerian satellites'
/// orbit arcs (raim-nav `arc`): GMSD7 (1 Hz, ephemerides first, the whole
/// stream) and the ESBC G+E+C stream (30 s apart). Printed: the first
/// dated epoch (every satellite's arc evaluated at two nodes), the
/// largest, the median and the last (BENCHMARKS.md "Orbit arcs").
#[test]
fn qemu_rtcm_stream_epoch_cost_every_epoch() {
    let (file, _) = gmsd7_in_window();
    let once = whole_frames(&file);
    let warm = [ephemeris_frames(once).as_slice(), once].concat();
    let week = in_window_week();
    let (esbc, _) = rtcm_common::esbc::esbc_stream(week - rtcm_common::esbc::ESBC_WEEK);
    for (name, bytes) in [("GMSD7", warm.as_slice()), ("ESBC", esbc.as_slice())] {
        let cost = forming_per_epoch(bytes);
        let dated: Vec<(usize, u64)> = cost
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, c)| *c > 0)
            .collect();
        assert!(dated.len() > 50, "{name}: {} epochs formed", dated.len());
        let mut sorted: Vec<u64> = dated.iter().map(|d| d.1).collect();
        sorted.sort_unstable();
        let (max_at, max) = dated.iter().copied().max_by_key(|d| d.1).unwrap();
        println!(
            "{name}: {} epochs; forming instructions: first {:?}, largest {max} (epoch {max_at}), median {}, last {}",
            cost.len(),
            &dated[..3],
            sorted[sorted.len() / 2],
            dated.last().unwrap().1
        );
    }
}
