//! `raim replay` end to end on a window of the 0759 file: the summary JSON
//! line, a scenario file giving the same run as the --fault flags, the
//! NMEA checksums, the plot, and a typed error for a missing file.

use std::process::Command;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

fn raim(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .output()
        .expect("spawn raim");
    (
        out.status.success(),
        String::from_utf8(out.stdout).expect("utf8"),
        String::from_utf8(out.stderr).expect("utf8"),
    )
}

fn base() -> Vec<String> {
    [
        "replay",
        "--obs",
        &format!("{DATA}/07590920.05o"),
        "--nav",
        &format!("{DATA}/07590920.05n"),
        "--systems",
        "G",
        "--mask-deg",
        "15",
        "--ura-m",
        "0.3",
        "--iono-vertical-m",
        "0.5",
        "--noise-m",
        "0.2",
        "--start",
        "00:19:00",
        "--end",
        "00:25:00",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

fn summary(stdout: &str) -> serde_json::Value {
    let last = stdout.lines().last().expect("a summary line");
    serde_json::from_str::<serde_json::Value>(last).expect("json")["summary"].clone()
}

/// 13 epochs; the 50 m G24 step from 00:20:00 is excluded at all 11
/// faulted epochs, at once, with no wrong exclusion; the first two are ok.
///
/// Verifies: TOOL-REPLAY
#[test]
fn json_lines_and_summary() {
    let mut a = base();
    a.extend(["--fault", "step:G24:50@00:20:00", "--json"].map(String::from));
    let args: Vec<&str> = a.iter().map(String::as_str).collect();
    let (ok, out, err) = raim(&args);
    assert!(ok, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 14);
    let first: serde_json::Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(first["tod"], "00:19:00");
    assert_eq!(first["decision"], "ok");
    let s = summary(&out);
    assert_eq!(s["epochs"], 13);
    assert_eq!(s["faulted_epochs"], 11);
    assert_eq!(s["correct_exclusions"], 11);
    assert_eq!(s["wrong_exclusions"], 0);
    assert_eq!(s["missed_detections"], 0);
    assert!(s["detection_delay_s"].as_f64().unwrap() < 1.0);
}

/// The same faults from a TOML scenario give the same output.
#[test]
fn scenario_file_equals_flags() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-replay");
    std::fs::create_dir_all(&dir).unwrap();
    let scen = dir.join("s.toml");
    std::fs::write(
        &scen,
        "seed = 3\n[[fault]]\nkind = \"ramp\"\ntarget = \"G24\"\nvalue = 0.1\nstart = \"00:20:00\"\n\
         [[fault]]\nkind = \"noise\"\ntarget = \"all\"\nvalue = 0.3\nnoise = \"laplace\"\n",
    )
    .unwrap();
    let mut a = base();
    a.extend(["--json", "--scenario", scen.to_str().unwrap()].map(String::from));
    let mut b = base();
    b.extend(
        [
            "--json",
            "--fault",
            "ramp:G24:0.1@00:20:00",
            "--fault",
            "noise:all:laplace:0.3",
            "--seed",
            "3",
        ]
        .map(String::from),
    );
    let run = |v: &Vec<String>| raim(&v.iter().map(String::as_str).collect::<Vec<_>>());
    let (ok_a, out_a, _) = run(&a);
    let (ok_b, out_b, _) = run(&b);
    assert!(ok_a && ok_b);
    assert_eq!(out_a, out_b);
    // Another seed changes the noise, hence the statistics.
    let mut c = b.clone();
    let n = c.len();
    c[n - 1] = "4".into();
    assert_ne!(run(&c).1, out_b);
    let _ = std::fs::remove_dir_all(&dir);
}

/// NMEA (`--nmea only`): the monitor's NMEA 0183 4.11 sentences per epoch
/// (RMC, VTG, GGA, GSA per constellation, GSV per constellation, GST, GBS,
/// ZDA), each ended by CR LF, nothing else; every checksum is the XOR of
/// its body.
#[test]
fn nmea_checksums() {
    let mut a = base();
    a.extend(["--nmea", "only"].map(String::from));
    let (ok, out, _) = raim(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok);
    assert!(out.ends_with("\r\n") && !out.replace("\r\n", "").contains('\n'));
    let lines: Vec<&str> = out.lines().collect();
    let epochs: Vec<&[&str]> = lines.split_inclusive(|l| &l[3..6] == "ZDA").collect();
    assert_eq!(epochs.len(), 13);
    for e in &epochs {
        let kinds: Vec<&str> = e.iter().map(|l| &l[3..6]).collect();
        let gsv = kinds.iter().filter(|k| **k == "GSV").count();
        let mut want = vec!["RMC", "VTG", "GGA", "GSA"];
        want.extend(std::iter::repeat_n("GSV", gsv));
        want.extend(["GST", "GBS", "ZDA"]);
        assert!(gsv >= 1);
        assert_eq!(kinds, want, "{e:?}");
    }
    for l in lines {
        let (body, cs) = l.trim_start_matches('$').split_once('*').unwrap();
        let x = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(format!("{x:02X}"), cs, "{l}");
    }
}

#[test]
fn missing_file_is_an_error_not_a_panic() {
    let (ok, _, err) = raim(&[
        "replay",
        "--obs",
        "/nonexistent.05o",
        "--nav",
        "/nonexistent.05n",
    ]);
    assert!(!ok);
    assert!(err.contains("/nonexistent.05o: no such file"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// `--plot` writes a PNG of the configured size (1800 x 1900).
#[test]
fn plot_is_a_png() {
    let png = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-replay-plot.png");
    let mut a = base();
    a.extend(
        [
            "--quiet",
            "--fault",
            "step:G24:50@00:20:00",
            "--plot",
            png.to_str().unwrap(),
        ]
        .map(String::from),
    );
    let (ok, _, err) = raim(&a.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(ok, "{err}");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    // IHDR width and height, big-endian, at bytes 16..24.
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 1800);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 1900);
    let _ = std::fs::remove_file(&png);
}
