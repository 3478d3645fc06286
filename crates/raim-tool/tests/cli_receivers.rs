//! `raim replay --rtcm3` / `--ubx` end to end on the two real receiver logs
//! (../shared/data: GMSD7, an RTCM 3 MSM7 station stream; a u-blox LEA-4T
//! RXM-RAW/SFRB log), their faults, damaged streams, live TCP sources, and
//! the distinct messages when nothing can be solved.

mod common;
use common::serve;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

/// How long a test's TCP source stays open after its last byte when the
/// run must end by something else (a timeout, Ctrl-C): a deadline only a
/// hung run reaches (the serving thread ends with the test binary).
const HOLD_OPEN: Duration = Duration::from_secs(600);

/// How long a test waits for an event of a live run (its first epoch): a
/// deadline only a hang reaches, not a measure of speed.
const EVENT_DEADLINE: Duration = Duration::from_secs(300);

fn gmsd7() -> String {
    format!("{DATA}/GMSD7_20121014.rtcm3")
}

fn lea4t() -> String {
    format!("{DATA}/ubx_20080526.ubx")
}

fn raim(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .output()
        .expect("spawn raim");
    (
        out.status.code(),
        String::from_utf8(out.stdout).expect("utf8"),
        String::from_utf8(out.stderr).expect("utf8"),
    )
}

fn summary(stdout: &str) -> serde_json::Value {
    let last = stdout.lines().last().expect("a summary line");
    serde_json::from_str::<serde_json::Value>(last).expect("json")["summary"].clone()
}

fn n(v: &serde_json::Value, k: &str) -> u64 {
    v[k].as_u64().unwrap_or_else(|| panic!("{k} in {v}"))
}

/// A scratch directory for this test binary.
fn scratch(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-cli-receivers");
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// RTCM 3 frames of a byte stream, split by their length field (the
/// stream is clean, so no CRC check is needed to cut it).
fn rtcm_frames(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 6 <= bytes.len() && bytes[i] == 0xD3 {
        let len = (usize::from(bytes[i + 1] & 3) << 8 | usize::from(bytes[i + 2])) + 6;
        if i + len > bytes.len() {
            break;
        }
        out.push(&bytes[i..i + len]);
        i += len;
    }
    out
}

fn message_number(frame: &[u8]) -> u16 {
    (u16::from(frame[3]) << 4) | (u16::from(frame[4]) >> 4)
}

/// GMSD7, GPS only, no elevation mask (the stream's ephemerides cover 6
/// of the 12 GPS satellites in view, 2 of them below 10 degrees; see
/// docs/RECEIVERS.md): 257 epochs; the 16 before 00:00:00 have 2 GPS
/// satellites with an ephemeris within 2 h of its toe and cannot be
/// solved; the other 241 are solved with no alarm and no exclusion.
#[test]
fn gmsd7_clean() {
    let (code, out, err) = raim(&[
        "replay",
        "--rtcm3",
        &gmsd7(),
        "--systems",
        "G",
        "--mask-deg",
        "0",
        "--json",
        "--keep-going",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "epochs"), 257);
    assert_eq!(n(&s, "solved"), 241, "{s}");
    assert_eq!(n(&s, "errors"), 16);
    assert_eq!(n(&s, "alarms"), 0);
    assert_eq!(n(&s, "false_alarms"), 0);
    assert_eq!(n(&s, "false_exclusions"), 0);
    // Against the allocation: the 241 tested clean epochs, none with a
    // false event, and Bin(241, 3.3333e-7) puts 0 within its 99 % bound.
    assert_eq!(n(&s, "clean_tested"), 241, "{s}");
    assert_eq!(n(&s, "clean_false_events"), 0, "{s}");
    assert_eq!(n(&s, "false_event_bound_99"), 0, "{s}");
    // The counts of the reader, and the cut last frame.
    assert!(err.contains("257 epochs, 31 ephemerides"), "{err}");
    assert!(err.contains("ends inside a frame (302 bytes cut)"), "{err}");
    // The dual-frequency stream is combined iono-free: every used
    // satellite's code is a pair.
    let first_ok = out
        .lines()
        .find(|l| l.contains("\"decision\":\"ok\""))
        .expect("an ok epoch");
    assert!(first_ok.contains("\"n_sats\":6"), "{first_ok}");
}

/// A 50 m step on G06 from 60 s after the start: excluded at every one
/// of the 197 faulted epochs, nothing else excluded, no false alarm.
#[test]
fn gmsd7_step_excluded_every_epoch() {
    let (code, out, err) = raim(&[
        "replay",
        "--rtcm3",
        &gmsd7(),
        "--systems",
        "G",
        "--mask-deg",
        "0",
        "--fault",
        "step:G06:50@+60",
        "--json",
        "--keep-going",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "faulted_epochs"), 197, "{s}");
    assert_eq!(n(&s, "correct_exclusions"), 197, "{s}");
    assert_eq!(n(&s, "wrong_exclusions"), 0);
    assert_eq!(n(&s, "missed_detections"), 0);
    assert_eq!(n(&s, "false_alarms"), 0);
}

/// The LEA-4T log: 242 epochs, all solved with 8 GPS satellites, no
/// alarm; its ephemerides come from its own subframes.
#[test]
fn lea4t_clean() {
    let (code, out, err) = raim(&["replay", "--ubx", &lea4t(), "--json"]);
    assert_eq!(code, Some(0), "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "epochs"), 242);
    assert_eq!(n(&s, "solved"), 242);
    assert_eq!(n(&s, "alarms"), 0);
    assert_eq!(n(&s, "false_exclusions"), 0);
    assert!(err.contains("242 epochs"), "{err}");
    assert!(
        err.contains("NMEA sentence x"),
        "NMEA between frames is counted: {err}"
    );
    // Position error against the clean mean: metres, not kilometres.
    assert!(s["error_h_max_m"].as_f64().unwrap() < 5.0, "{s}");
    // The first solution against the receiver's own fix of that second
    // (its first $GPRMC in the log, 35 52.37449 N 138 23.38721 E): within
    // ABS_TOL_M, so the decoded ephemerides place it absolutely too.
    const ABS_TOL_M: f64 = 10.0;
    let first: serde_json::Value = serde_json::from_str(out.lines().next().unwrap()).unwrap();
    let p: Vec<f64> = first["position_ecef_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let g = raim_core::frames::ecef_to_geodetic([p[0], p[1], p[2]]);
    let (lat, lon) = (
        (35.0 + 52.37449 / 60.0f64).to_radians(),
        (138.0 + 23.38721 / 60.0f64).to_radians(),
    );
    let north_m = (g.lat_rad - lat) * 6.371e6;
    let east_m = (g.lon_rad - lon) * 6.371e6 * lat.cos();
    assert!(north_m.hypot(east_m) < ABS_TOL_M, "{north_m} {east_m}");
}

/// A 50 m step on G05 from 60 s after the start: excluded at all 182
/// faulted epochs.
#[test]
fn lea4t_step_excluded_every_epoch() {
    let (code, out, err) = raim(&[
        "replay",
        "--ubx",
        &lea4t(),
        "--fault",
        "step:G05:50@+60",
        "--json",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "faulted_epochs"), 182, "{s}");
    assert_eq!(n(&s, "correct_exclusions"), 182, "{s}");
    assert_eq!(n(&s, "wrong_exclusions"), 0);
    assert_eq!(n(&s, "missed_detections"), 0);
    assert_eq!(n(&s, "false_alarms"), 0);
}

/// Damage: garbage bytes between frames, one frame with a flipped CRC
/// byte and an RTCM message type no reader knows (4095, proprietary) are
/// skipped and counted; the rest of the stream runs.
#[test]
fn damaged_rtcm_is_skipped_and_counted() {
    let bytes = std::fs::read(gmsd7()).unwrap();
    let frames = rtcm_frames(&bytes);
    let mut out = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        if k == 10 {
            out.extend_from_slice(b"garbage!"); // 8 bytes, no 0xD3
        }
        if k == 20 {
            let mut bad = f.to_vec();
            let last = bad.len() - 1;
            bad[last] ^= 0x55;
            out.extend_from_slice(&bad);
            continue;
        }
        out.extend_from_slice(f);
    }
    let p = scratch("damaged.rtcm3");
    std::fs::write(&p, &out).unwrap();
    let (code, _, err) = raim(&[
        "replay",
        "--rtcm3",
        p.to_str().unwrap(),
        "--systems",
        "G",
        "--mask-deg",
        "0",
        "--quiet",
        "--keep-going",
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("1 bad checksums"), "{err}");
    assert!(err.contains("bytes between frames"), "{err}");
    assert!(!err.contains(" 0 bytes between frames"), "{err}");
    assert!(err.contains("not used: 1007 x28"), "{err}");
}

/// A stream with its ephemeris messages removed says so, naming them
/// and the GLONASS ephemerides it does have.
#[test]
fn stream_without_ephemerides_says_so() {
    let bytes = std::fs::read(gmsd7()).unwrap();
    let kept: Vec<u8> = rtcm_frames(&bytes)
        .into_iter()
        .filter(|f| message_number(f) != 1019)
        .flatten()
        .copied()
        .collect();
    let p = scratch("no-eph.rtcm3");
    std::fs::write(&p, &kept).unwrap();
    let (code, _, err) = raim(&["replay", "--rtcm3", p.to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(
        err.contains("no ephemeris to date them")
            || err.contains("no ephemeris of a modelled system"),
        "{err}"
    );
    assert!(err.contains("1019"), "{err}");
}

/// Only GLONASS (MSM 1087 and its 1020 ephemerides): a GLONASS MSM has a
/// time of day and a day of the week, the 1020s of GMSD7 no date (N4 and
/// N_T are 0), so the epochs cannot be dated; the message says so.
#[test]
fn glonass_only_stream_says_so() {
    let bytes = std::fs::read(gmsd7()).unwrap();
    let kept: Vec<u8> = rtcm_frames(&bytes)
        .into_iter()
        .filter(|f| matches!(message_number(f), 1087 | 1020))
        .flatten()
        .copied()
        .collect();
    let p = scratch("glonass-only.rtcm3");
    std::fs::write(&p, &kept).unwrap();
    let (code, _, err) = raim(&["replay", "--rtcm3", p.to_str().unwrap()]);
    assert_eq!(code, Some(1));
    assert!(err.contains("only GLONASS observations"), "{err}");
    assert!(err.contains("GLONASS time of day"), "{err}");
}

/// GMSD7 with GPS and GLONASS (`--systems GR --mask-deg 0`): the 1020s
/// give R13, R14 and R15 (the stream's other observed GLONASS satellites,
/// R17, R18 and R24, have no 1020 before it is cut), so 9 satellites from
/// 00:00:00. The first 16 epochs have 2 GPS + 3 GLONASS satellites for 5
/// unknowns (position, two clocks): no redundancy, refused as with GPS
/// alone, so 241 of 257 are solved (93.8 %): the stream holds no more.
/// No alarm, no exclusion, and the errors no worse than GPS alone.
#[test]
fn gmsd7_gps_glonass_clean() {
    /// Horizontal error bound (against the clean mean), m: GPS alone has
    /// a 3.85 m maximum on this stream (docs/RECEIVERS.md).
    const MAX_H_M: f64 = 3.85;
    let (code, out, err) = raim(&[
        "replay",
        "--rtcm3",
        &gmsd7(),
        "--systems",
        "GR",
        "--mask-deg",
        "0",
        "--json",
        "--keep-going",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "epochs"), 257);
    assert_eq!(n(&s, "solved"), 241, "{s}");
    assert_eq!(n(&s, "alarms"), 0);
    assert_eq!(n(&s, "false_alarms"), 0);
    assert_eq!(n(&s, "false_exclusions"), 0);
    assert_eq!(n(&s, "excluded"), 0);
    assert_eq!(n(&s, "clean_false_events"), 0, "{s}");
    assert!(s["error_h_max_m"].as_f64().unwrap() < MAX_H_M, "{s}");
    assert!(err.contains("too few satellites: have 5"), "{err}");
    let first_ok = out
        .lines()
        .find(|l| l.contains("\"decision\":\"ok\""))
        .expect("an ok epoch");
    assert!(first_ok.contains("\"n_sats\":9"), "{first_ok}");
}

/// A 50 m step from 60 s after the start on each satellite of the GPS +
/// GLONASS run, one run each: excluded at every one of the 197 faulted
/// epochs, nothing else excluded, no alarm. (GPS alone, G01 and G07 are
/// mostly alarmed: 6 satellites leave 2 degrees of freedom; G+R has 9.)
#[test]
fn gmsd7_gps_glonass_step_excluded_every_epoch() {
    for sat in ["R14", "R13", "R15", "G01", "G07"] {
        let fault = format!("step:{sat}:50@+60");
        let (code, out, err) = raim(&[
            "replay",
            "--rtcm3",
            &gmsd7(),
            "--systems",
            "GR",
            "--mask-deg",
            "0",
            "--fault",
            &fault,
            "--json",
            "--keep-going",
        ]);
        assert_eq!(code, Some(0), "{err}");
        let s = summary(&out);
        assert_eq!(n(&s, "faulted_epochs"), 197, "{sat} {s}");
        assert_eq!(n(&s, "correct_exclusions"), 197, "{sat} {s}");
        assert_eq!(n(&s, "wrong_exclusions"), 0, "{sat}");
        assert_eq!(n(&s, "missed_detections"), 0, "{sat}");
        assert_eq!(n(&s, "alarms"), 0, "{sat}");
        assert_eq!(n(&s, "false_alarms"), 0, "{sat}");
    }
}

/// Empty file, a directory, a RINEX file and a UBX file given to --rtcm3,
/// an RTCM file given to --ubx: each its own message, exit 1.
#[test]
fn wrong_inputs_each_say_what_they_are() {
    let empty = scratch("empty.rtcm3");
    std::fs::write(&empty, b"").unwrap();
    let dir = scratch("a-directory");
    std::fs::create_dir_all(&dir).unwrap();
    let cases: [(&str, String, &str); 5] = [
        ("--rtcm3", empty.display().to_string(), "is empty (0 bytes)"),
        ("--rtcm3", dir.display().to_string(), "is a directory"),
        (
            "--rtcm3",
            format!("{DATA}/07590920.05o"),
            "looks like a RINEX file (use --obs and --nav)",
        ),
        (
            "--rtcm3",
            lea4t(),
            "looks like a u-blox UBX stream (use --ubx)",
        ),
        (
            "--ubx",
            gmsd7(),
            "looks like an RTCM 3 stream (use --rtcm3)",
        ),
    ];
    for (flag, path, want) in cases {
        let (code, _, err) = raim(&["replay", flag, &path]);
        assert_eq!(code, Some(1), "{flag} {path}: {err}");
        assert!(err.contains(want), "{flag} {path}: {err}");
    }
}

/// `--reference header` with no position to refer to is an error that
/// says so (it used to print NaN errors and exit 0): RTCM without
/// 1005/1006, and a RINEX header without APPROX POSITION XYZ.
#[test]
fn reference_header_without_a_position() {
    let (code, _, err) = raim(&[
        "replay",
        "--rtcm3",
        &gmsd7(),
        "--systems",
        "G",
        "--mask-deg",
        "0",
        "--reference",
        "header",
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("no station position (RTCM 1005/1006)"),
        "{err}"
    );
    let text = std::fs::read_to_string(format!("{DATA}/07590920.05o")).unwrap();
    let cut: String = text
        .lines()
        .filter(|l| !l.contains("APPROX POSITION XYZ"))
        .map(|l| format!("{l}\n"))
        .collect();
    let p = scratch("no-approx.05o");
    std::fs::write(&p, cut).unwrap();
    let (code, _, err) = raim(&[
        "replay",
        "--obs",
        p.to_str().unwrap(),
        "--nav",
        &format!("{DATA}/07590920.05n"),
        "--systems",
        "G",
        "--end",
        "00:02:00",
        "--reference",
        "header",
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("no APPROX POSITION XYZ"), "{err}");
}

/// Ephemerides of another date (0759 of 2005 with ESBC's 2020 navigation
/// file), and only systems not selected (0759 is GPS only, --systems E):
/// each its own message instead of "too few satellites: have 0".
#[test]
fn nothing_solves_says_why() {
    let (code, _, err) = raim(&[
        "replay",
        "--obs",
        &format!("{DATA}/07590920.05o"),
        "--nav",
        &format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"),
        "--systems",
        "G",
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("ephemerides are from another date"), "{err}");
    assert!(
        err.contains("2020-06-2") && err.contains("2005-04-02"),
        "{err}"
    );
    let (code, _, err) = raim(&[
        "replay",
        "--obs",
        &format!("{DATA}/07590920.05o"),
        "--nav",
        &format!("{DATA}/07590920.05n"),
        "--systems",
        "E",
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("only systems that are not used are present"),
        "{err}"
    );
    assert!(err.contains("hold G") && err.contains("selects E"), "{err}");
}

/// A live TCP source: each epoch printed as decoded (ephemerides as they
/// arrive, so the epochs before four GPS ephemerides are refused), then
/// the summary, and a clean stop at the end of the stream.
#[test]
fn live_tcp_rtcm_runs_to_the_end_of_stream() {
    let bytes = std::fs::read(gmsd7()).unwrap();
    let addr = serve(bytes, 8192, Duration::from_millis(1), Duration::ZERO);
    let (code, out, err) = raim(&[
        "replay",
        "--rtcm3",
        &format!("tcp://{addr}"),
        "--systems",
        "G",
        "--mask-deg",
        "0",
        "--json",
        "--keep-going",
    ]);
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("stopped (end of stream)"), "{err}");
    let lines: Vec<&str> = out.lines().collect();
    // 257 epochs and the summary.
    assert_eq!(lines.len(), 258, "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "epochs"), 257);
    assert_eq!(n(&s, "false_alarms"), 0);
    assert!(n(&s, "solved") > 0, "{s}");
}

/// The UBX log over TCP: its subframes complete the ephemerides within
/// the first 30 s, then the epochs are solved.
#[test]
fn live_tcp_ubx() {
    let bytes = std::fs::read(lea4t()).unwrap();
    let addr = serve(bytes, 4096, Duration::from_millis(1), Duration::ZERO);
    let (code, out, err) = raim(&[
        "replay",
        "--ubx",
        &format!("tcp://{addr}"),
        "--json",
        "--keep-going",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let s = summary(&out);
    assert_eq!(n(&s, "epochs"), 242);
    assert!(n(&s, "solved") >= 200, "{s}");
    assert_eq!(n(&s, "false_alarms"), 0);
}

/// A live stream that sends epochs but no ephemeris is given up after
/// --ephemeris-timeout-s with a message that says so. The source stays
/// open far longer than the timeout (it is wall-clock supervision of a
/// silent source), so however slowly the machine runs `raim` the timeout
/// is what ends the run, never the end of the stream.
#[test]
fn live_stream_without_ephemerides_times_out() {
    let bytes = std::fs::read(gmsd7()).unwrap();
    let kept: Vec<u8> = rtcm_frames(&bytes)
        .into_iter()
        .filter(|f| message_number(f) != 1019)
        .take(200)
        .flatten()
        .copied()
        .collect();
    let addr = serve(kept, 512, Duration::from_millis(20), HOLD_OPEN);
    let (code, _, err) = raim(&[
        "replay",
        "--rtcm3",
        &format!("tcp://{addr}"),
        "--ephemeris-timeout-s",
        "1",
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("no ephemeris after 1 s"), "{err}");
    assert!(err.contains("1019"), "{err}");
}

/// Ctrl-C (SIGINT) on a live source that stays open: the run stops
/// cleanly, prints the reader's counts and the summary, exit 0. SIGINT is
/// sent once the first epoch has been printed (so the handler is in place
/// and an epoch was run, however loaded the machine), and the source stays
/// open until long after that ([`HOLD_OPEN`]).
#[test]
fn live_source_stops_on_ctrl_c() {
    use std::io::{BufRead, BufReader, Read};
    let bytes = std::fs::read(lea4t()).unwrap();
    let head = bytes[..60_000].to_vec();
    let addr = serve(head, 4096, Duration::from_millis(1), HOLD_OPEN);
    let mut child = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args([
            "replay",
            "--ubx",
            &format!("tcp://{addr}"),
            "--json",
            "--keep-going",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn raim");
    // The stdout lines, read on a thread so that a silent run fails the
    // test at the deadline instead of hanging it.
    let stdout = child.stdout.take().expect("stdout");
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut lines = Vec::new();
        for l in BufReader::new(stdout).lines() {
            let Ok(l) = l else { break };
            let _ = tx.send(());
            lines.push(l);
        }
        lines
    });
    rx.recv_timeout(EVENT_DEADLINE)
        .expect("the first epoch printed");
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let status = child.wait().expect("wait");
    let mut err = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut err)
        .expect("stderr");
    let lines = reader.join().expect("stdout reader");
    assert_eq!(status.code(), Some(0), "{err}");
    assert!(err.contains("stopped (Ctrl-C)"), "{err}");
    let s = summary(&lines.join("\n"));
    assert!(n(&s, "epochs") > 0, "{s}");
}

#[test]
fn bad_source_specs_are_refused() {
    for (spec, want) in [
        ("tcp://nohost", "expected tcp://HOST:PORT"),
        ("serial:/dev/ttyUSB0", "expected serial:PATH:BAUD"),
    ] {
        let (code, _, err) = raim(&["replay", "--rtcm3", spec]);
        assert_eq!(code, Some(1), "{spec}: {err}");
        assert!(err.contains(want), "{spec}: {err}");
    }
    let _ = Path::new(DATA);
}
