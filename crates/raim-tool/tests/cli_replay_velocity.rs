//! Speed and course over ground in the replay's RMC and VTG (issue 34,
//! "NMEA"; docs/REPLAY.md "Speed and course"), from the source's Doppler:
//! - `raim replay --rtcm3` on GMSD7 (MSM7 phase-range rates) writes the
//!   RMC and VTG the unit writes under QEMU for the same stream, byte for
//!   byte;
//! - `raim replay` on RINEX with D observables (ESBC, a static geodetic
//!   station, G+R+E+C; GEOP, a smartphone at rest, G+E) writes a speed and
//!   course at every valid epoch, a static station's speed; 0759 (RINEX
//!   2 with no D observable) leaves them empty; the `nmea` crate and
//!   pynmea2 read the numbers written.
//!
//!     cargo test --release -p raim-tool --test cli_replay_velocity -- --nocapture

#[path = "../../../host-tests/tests/rtcm_common/mod.rs"]
mod rtcm_common;

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use raim_qemu::{Machine, Options, QemuSession};
use rtcm_common::{frames, gmsd7_moved_to, host_epochs, in_window_week};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
/// Metres per second in a knot and in a km/h.
const KNOT_M_S: f64 = 1852.0 / 3600.0;
const KM_H_M_S: f64 = 1000.0 / 3600.0;
/// How long the unit may take over the whole stream (257 epochs): a
/// deadline only a hang reaches.
const STREAM_TIMEOUT: Duration = Duration::from_secs(300);

/// `raim replay ARGS --nmea only`: the sentences, without their CRLF.
fn replay_nmea(args: &[&str]) -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .arg("replay")
        .args(args)
        .args(["--nmea", "only", "--keep-going"])
        .output()
        .expect("spawn raim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .expect("utf8")
        .lines()
        .map(|l| l.trim_end().to_string())
        .collect()
}

/// GMSD7 as a receiver would send it within this firmware's dating window
/// (`rtcm_common::gmsd7_moved_to`), warm: its ephemeris frames first (a
/// receiver's stored ephemerides at start-up), then the whole frames.
fn gmsd7_warm_in_window() -> Vec<u8> {
    let file = std::fs::read(format!("{DATA}/GMSD7_20121014.rtcm3"))
        .expect("GMSD7 stream (../shared/data)");
    let moved = gmsd7_moved_to(&file, in_window_week());
    let eph: Vec<u8> = frames(&moved)
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
    let whole: Vec<u8> = frames(&moved).into_iter().flatten().copied().collect();
    [eph, whole].concat()
}

/// The RMC and VTG sentences of `lines`, each RMC with the VTG after it.
fn rmc_vtg(lines: &[String]) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rmc: Option<&String> = None;
    for l in lines {
        match l.get(3..6) {
            Some("RMC") => rmc = Some(l),
            Some("VTG") => out.push((rmc.take().expect("RMC before VTG").clone(), l.clone())),
            _ => {}
        }
    }
    out
}

/// The host's stream replay and the unit under QEMU (its streaming build,
/// configured with `Config::default()` as the replay's defaults are) on
/// the same bytes: every epoch the unit solves with a speed, the replay
/// writes the same RMC and VTG, byte for byte (the replay's velocity is
/// the unit's: the same rates, kept to the mm/s; the same satellite
/// motion at the same transmit times; the same solution at the same
/// position, from the satellites the answer used).
///
/// Verifies: NMEA-VELOCITY-REPLAY
#[test]
fn replay_rtcm3_rmc_and_vtg_equal_the_unit_under_qemu() {
    let bytes = gmsd7_warm_in_window();
    let file = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-gmsd7-vel.rtcm3");
    std::fs::write(&file, &bytes).unwrap();
    let host = rmc_vtg(&replay_nmea(&[
        "--rtcm3",
        file.to_str().unwrap(),
        "--systems",
        "GRECJ",
    ]));
    let _ = std::fs::remove_file(&file);

    let elf = raim_qemu::firmware_elf_stream(Machine::Mps2An386).expect("firmware build");
    let mut fw = QemuSession::start_with(&elf, &Options::default()).expect("qemu-system-arm");
    fw.drain_nmea();
    // The epochs the stream closes (the host reader's count, as
    // host-tests' qemu_rtcm pairs the unit's answers with it).
    let epochs = host_epochs(&bytes, in_window_week() + 1).1.epochs as usize;
    for chunk in bytes.chunks(4096) {
        fw.send_raw(chunk).unwrap();
    }
    let mut answers = 0;
    let deadline = Instant::now() + STREAM_TIMEOUT;
    while answers < epochs {
        let left = deadline.saturating_duration_since(Instant::now());
        let r = fw
            .recv(left.max(Duration::from_millis(1)))
            .unwrap_or_else(|e| panic!("after {answers} answers: {e}"));
        assert_eq!(r.seq, None, "a stream epoch's answer is unasked");
        answers += 1;
    }
    // The NMEA UART is read by its own thread: wait, with a deadline only
    // a hang reaches, for the last epoch's VTG.
    let mut lines = fw.drain_nmea();
    let deadline = Instant::now() + Duration::from_secs(30);
    while rmc_vtg(&lines).len() < epochs && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        lines.extend(fw.drain_nmea());
    }
    let lines: Vec<String> = lines.iter().map(|s| s.trim_end().to_string()).collect();
    let unit = rmc_vtg(&lines);
    assert_eq!(unit.len(), epochs);

    let time = |rmc: &str| rmc.split(',').nth(1).unwrap_or("").to_string();
    let with_speed = |rmc: &str| rmc.split(',').nth(7).is_some_and(|f| !f.is_empty());
    let mut same = 0;
    for (u_rmc, u_vtg) in unit.iter().filter(|(r, _)| with_speed(r)) {
        let (h_rmc, h_vtg) = host
            .iter()
            .find(|(r, _)| time(r) == time(u_rmc))
            .unwrap_or_else(|| panic!("no replay epoch for the unit's {u_rmc}"));
        assert_eq!(h_rmc, u_rmc);
        assert_eq!(h_vtg, u_vtg);
        same += 1;
    }
    // And the replay writes no speed where the unit writes none.
    for (h_rmc, _) in host.iter().filter(|(r, _)| with_speed(r)) {
        assert!(
            unit.iter().any(|(r, _)| r == h_rmc),
            "the replay's {h_rmc} is not the unit's"
        );
    }
    println!(
        "GMSD7 (warm, in the dating window): {} unit epochs, {same} with speed and course, their RMC and VTG the replay's byte for byte ({} replay epochs)",
        unit.len(),
        host.len()
    );
    assert!(same >= 230, "{same}");
}

/// One epoch's RMC/VTG fields: RMC status, speed (knots), course; VTG
/// course, knots, km/h.
#[derive(Debug, Clone, PartialEq)]
struct Written {
    valid: bool,
    rmc: (Option<f64>, Option<f64>),
    vtg: (Option<f64>, Option<f64>, Option<f64>),
}

fn field(s: &str, i: usize) -> Option<f64> {
    let body = s.trim_start_matches('$').split('*').next()?;
    body.split(',').nth(i)?.parse().ok()
}

fn written(pairs: &[(String, String)]) -> Vec<Written> {
    pairs
        .iter()
        .map(|(r, v)| Written {
            valid: r.split(',').nth(2) == Some("A"),
            rmc: (field(r, 7), field(r, 8)),
            vtg: (field(v, 1), field(v, 5), field(v, 7)),
        })
        .collect()
}

/// Each valid epoch's speed over ground (m/s), after checking that it
/// has one, that RMC and VTG agree and that VTG's km/h is its knots; an
/// invalid epoch has none.
fn speeds(name: &str, w: &[Written]) -> Vec<f64> {
    let mut out = Vec::new();
    for e in w {
        if !e.valid {
            assert_eq!(
                (e.rmc, e.vtg),
                ((None, None), (None, None, None)),
                "{name} {e:?}"
            );
            continue;
        }
        let (Some(knots), Some(course)) = e.rmc else {
            panic!("{name}: a valid epoch without speed and course: {e:?}");
        };
        assert_eq!(e.vtg.0, Some(course), "{name} {e:?}");
        assert_eq!(e.vtg.1, Some(knots), "{name} {e:?}");
        let kmh = e.vtg.2.unwrap();
        // Each field rounded to 3 decimals.
        assert!(
            (kmh * KM_H_M_S - knots * KNOT_M_S).abs() < 0.001,
            "{name} {e:?}"
        );
        assert!((0.0..360.0).contains(&course), "{name} {e:?}");
        out.push(knots * KNOT_M_S);
    }
    out
}

/// The `nmea` crate and pynmea2 read the numbers the sentences were
/// written with.
fn readers_agree(pairs: &[(String, String)], w: &[Written]) {
    let mut by_crate = Vec::new();
    for (r, v) in pairs {
        for l in [r, v] {
            match nmea::parse_str(l).unwrap_or_else(|e| panic!("{l}: {e:?}")) {
                nmea::ParseResult::RMC(r) => by_crate.push((r.speed_over_ground, r.true_course)),
                nmea::ParseResult::VTG(v) => by_crate.push((v.speed_over_ground, v.true_course)),
                other => panic!("{other:?}"),
            }
        }
    }
    let from_text: Vec<(Option<f32>, Option<f32>)> = w
        .iter()
        .flat_map(|e| {
            [
                (e.rmc.0.map(|v| v as f32), e.rmc.1.map(|v| v as f32)),
                (e.vtg.1.map(|v| v as f32), e.vtg.0.map(|v| v as f32)),
            ]
        })
        .collect();
    assert_eq!(by_crate, from_text);

    let script = "import sys, pynmea2\n\
for line in sys.stdin:\n    m = pynmea2.parse(line.strip(), check=True)\n    \
if m.sentence_type == 'RMC':\n        print('RMC', m.spd_over_grnd, m.true_course)\n    \
else:\n        print('VTG', m.true_track, m.spd_over_grnd_kts, m.spd_over_grnd_kmph)\n";
    let mut py = Command::new("python3")
        .args(["-c", script])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3");
    let input: String = pairs
        .iter()
        .map(|(r, v)| format!("{r}\r\n{v}\r\n"))
        .collect();
    py.stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = py.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "pynmea2: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let num = |s: &str| s.parse::<f64>().ok();
    let py_read: Vec<Vec<Option<f64>>> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| l.split(' ').skip(1).map(num).collect())
        .collect();
    let want: Vec<Vec<Option<f64>>> = w
        .iter()
        .flat_map(|e| [vec![e.rmc.0, e.rmc.1], vec![e.vtg.0, e.vtg.1, e.vtg.2]])
        .collect();
    assert_eq!(py_read, want);
}

/// The root mean square and the largest of `v`.
fn rms_max(v: &[f64]) -> (f64, f64) {
    let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    (rms, v.iter().copied().fold(0.0, f64::max))
}

/// The largest speed over ground a geodetic station at rest may show from
/// its RINEX Doppler, m/s: its D observables are good to a few mm/s
/// (ESBC through the stream path: rms 0.007 m/s, docs/RECEIVERS.md), and
/// 0.1 m/s at rest would be an error of the model (a GLONASS satellite's
/// carrier taken on the wrong frequency channel misplaces its rate by
/// 3.5e-4 of it per channel, up to 0.3 m/s; a wrong sign by twice the
/// rate, hundreds of m/s).
const GEODETIC_SPEED_TOL_M_S: f64 = 0.1;
/// The same for a smartphone at rest (GEOP) or a 2008 single-frequency
/// u-blox (LEA-4T): their Doppler is good to a few cm/s; the bound is
/// host-tests' `stream_velocity` one for a geodetic receiver's MSM
/// (0.2 m/s), with their noisier, multipath-prone tracking allowed twice
/// it.
const PHONE_SPEED_TOL_M_S: f64 = 0.4;

/// ESBC (RINEX 3.05, D observables on every signal, G+R+E+C; GLONASS
/// Dopplers on each satellite's channel from the navigation file) and
/// GEOP (RINEX 3.03, a smartphone at rest, G+E): every valid epoch has a
/// speed and course, a station at rest's speed; 0759 (RINEX 2.10, no D
/// observable) has none at any epoch. The `nmea` crate and pynmea2 read
/// them.
///
/// Verifies: NMEA-VELOCITY-REPLAY
#[test]
fn rinex_replay_speed_and_course_from_the_d_observables() {
    let esbc = rmc_vtg(&replay_nmea(&[
        "--obs",
        &format!("{DATA}/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz"),
        "--nav",
        &format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz"),
        "--systems",
        "GREC",
    ]));
    let w = written(&esbc);
    let s = speeds("ESBC", &w);
    let (rms, max) = rms_max(&s);
    println!(
        "ESBC G+R+E+C: {} epochs, {} with speed and course; speed over ground rms {rms:.4} m/s, largest {max:.4} m/s",
        w.len(),
        s.len()
    );
    assert_eq!(s.len(), w.len());
    assert!(max < GEODETIC_SPEED_TOL_M_S, "{max}");
    readers_agree(&esbc, &w);

    let geop = rmc_vtg(&replay_nmea(&[
        "--obs",
        &format!("{DATA}/GEOP092I.24o.gz"),
        "--nav",
        &format!("{DATA}/CORD00ARG_R_20240920000_01D_MN.rnx.gz"),
        "--systems",
        "GE",
    ]));
    let w = written(&geop);
    let s = speeds("GEOP", &w);
    let (rms, max) = rms_max(&s);
    println!(
        "GEOP G+E: {} epochs, {} with speed and course; speed over ground rms {rms:.4} m/s, largest {max:.4} m/s",
        w.len(),
        s.len()
    );
    assert!(s.len() * 10 >= w.len() * 9, "{} of {}", s.len(), w.len());
    assert!(max < PHONE_SPEED_TOL_M_S, "{max}");
    readers_agree(&geop, &w);

    let l0759 = rmc_vtg(&replay_nmea(&[
        "--obs",
        &format!("{DATA}/07590920.05o"),
        "--nav",
        &format!("{DATA}/07590920.05n"),
        "--systems",
        "G",
    ]));
    let w = written(&l0759);
    assert!(w.iter().filter(|e| e.valid).count() > 100);
    for e in &w {
        assert_eq!(
            (e.rmc, e.vtg),
            ((None, None), (None, None, None)),
            "0759 {e:?}"
        );
    }
    println!(
        "0759 (no D observable): {} epochs, speed and course empty in each",
        w.len()
    );
}

/// The u-blox LEA-4T log (RXM-RAW, a receiver at rest, GPS L1): its
/// doMes (Hz, positive approaching) gives every valid epoch a speed and
/// course near 0 (a wrong sign or carrier would give hundreds of m/s).
///
/// Verifies: NMEA-VELOCITY-REPLAY
#[test]
fn ubx_replay_speed_and_course_from_do_mes() {
    let ubx = rmc_vtg(&replay_nmea(&[
        "--ubx",
        &format!("{DATA}/ubx_20080526.ubx"),
        "--systems",
        "G",
    ]));
    let w = written(&ubx);
    let s = speeds("LEA-4T", &w);
    let (rms, max) = rms_max(&s);
    println!(
        "LEA-4T (UBX RXM-RAW): {} epochs, {} with speed and course; speed over ground rms {rms:.4} m/s, largest {max:.4} m/s",
        w.len(),
        s.len()
    );
    assert!(s.len() * 10 >= w.len() * 9, "{} of {}", s.len(), w.len());
    assert!(max < PHONE_SPEED_TOL_M_S, "{max}");
    readers_agree(&ubx, &w);
}
