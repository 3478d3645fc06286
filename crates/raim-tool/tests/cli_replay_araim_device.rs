//! `raim replay --araim` with NMEA, and on the device:
//! - `--araim --nmea`: every ARAIM epoch writes its NMEA sentences (the
//!   device's writer, `WireResult::set_from_araim`, on the host), the
//!   excluded satellite out of GSA once excluded; `--nmea-file` holds the
//!   same stream beside `--json`;
//! - `--araim --target qemu`: the firmware's ARAIM (f32, its ISM with the
//!   ADD elevation curves) on ESBC (G+E, single frequency: the error model
//!   the host uses there too) with a 50 m step on G15: the same decision,
//!   FDE outcome and exclusions as the host's f64 run at every epoch, PLs
//!   and positions within the f32 spread, and its own NMEA sentences with
//!   the host's used-satellite lists (docs/REPLAY.md, "ARAIM on the
//!   device").

use std::process::Command;

use serde_json::Value;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

/// The ADD bracket output's resolution, `AraimConfig::tol_pl_m` (0.01 m by
/// default, docs/ARAIM.md), plus the f32 engine's spread: the host (f64)
/// and the device (f32) may stop on neighbouring brackets.
const PL_TOL_M: f64 = 0.05;
/// The position in force: the f32 Gauss-Newton steps (docs/REPLAY.md
/// measures the spread on this run).
const POSITION_TOL_M: f64 = 0.01;

struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

/// ESBC (2020, G+E single frequency, C1C: the ADD curves on both
/// targets), 00:55-01:05 against the surveyed header position, 50 m on
/// G15 from 01:00.
fn raim(extra: &[&str]) -> Run {
    let obs = format!("{DATA}/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz");
    let nav = format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz");
    let mut args = vec![
        "replay",
        "--obs",
        &obs,
        "--nav",
        &nav,
        "--systems",
        "GE",
        "--reference",
        "header",
        "--start",
        "00:55:00",
        "--end",
        "01:05:00",
        "--araim",
        "--fault",
        "step:G15:50@01:00:00",
    ];
    args.extend_from_slice(extra);
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(&args)
        .output()
        .expect("spawn raim");
    let r = Run {
        code: out.status.code().expect("exited"),
        stdout: String::from_utf8(out.stdout).expect("utf8"),
        stderr: String::from_utf8(out.stderr).expect("utf8"),
    };
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    r
}

fn records(stdout: &str) -> (Vec<Value>, Value) {
    let lines: Vec<Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    let (summary, recs) = lines.split_last().expect("a summary");
    (recs.to_vec(), summary["araim_summary"].clone())
}

/// The sentences of each epoch (split after each ZDA).
fn epochs_of(stream: &str) -> Vec<Vec<&str>> {
    let lines: Vec<&str> = stream.lines().collect();
    lines
        .split_inclusive(|l| l.get(3..6) == Some("ZDA"))
        .map(<[&str]>::to_vec)
        .collect()
}

/// The satellite numbers the GSA sentences of NMEA 4.11 system ID
/// `system_id` (field 18) list as used (fields 3 to 14): numbers are per
/// system (Galileo 1-36, BeiDou 1-63).
fn gsa_used(epoch: &[&str], system_id: &str) -> Vec<String> {
    epoch
        .iter()
        .filter(|l| l.get(3..6) == Some("GSA"))
        .map(|l| l.split('*').next().unwrap_or(""))
        .filter(|body| body.split(',').nth(18) == Some(system_id))
        .flat_map(|body| {
            body.split(',')
                .skip(3)
                .take(12)
                .filter(|f| !f.is_empty())
                .map(String::from)
                .collect::<Vec<_>>()
        })
        .collect()
}

fn fields<'a>(epoch: &[&'a str], kind: &str) -> Vec<&'a str> {
    epoch
        .iter()
        .find(|l| l.get(3..6) == Some(kind))
        .map(|l| l.split('*').next().unwrap_or("").split(',').collect())
        .unwrap_or_default()
}

/// 21 epochs (00:55-01:05), G15 faulted from 01:00.
const EPOCHS: usize = 21;
const FAULTED: usize = 11;

#[test]
fn araim_nmea_on_the_host() {
    let only = raim(&["--nmea", "only"]);
    assert_eq!(only.code, 0, "{}", only.stderr);
    let s = &only.stdout;
    assert!(s.ends_with("\r\n") && !s.replace("\r\n", "").contains('\n'));
    for l in s.lines() {
        let (body, cs) = l
            .strip_prefix('$')
            .and_then(|b| b.split_once('*'))
            .expect("a sentence");
        let x = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(format!("{x:02X}"), cs, "{l}");
    }
    let epochs = epochs_of(s);
    assert_eq!(epochs.len(), EPOCHS);
    let (recs, _) = records(&raim(&["--json"]).stdout);
    assert_eq!(recs.len(), EPOCHS);
    for (e, r) in epochs.iter().zip(&recs) {
        // ESBC is 2020-06-25 (UTC); RMC status A (valid) exactly when the
        // verdict gives service.
        let rmc = fields(e, "RMC");
        assert_eq!(rmc.get(9), Some(&"250620"), "{e:?}");
        let valid = rmc.get(2) == Some(&"A");
        assert_eq!(valid, r["available"] == true, "{r}\n{e:?}");
        let used = gsa_used(e, "1");
        // GPS PRN 15 is "15" in the GSA of system ID 1 (GPS).
        let g15 = used.contains(&"15".to_string());
        assert_eq!(g15, r["fde"] != "excluded", "{used:?}\n{r}");
    }
    // The step is excluded from its first epoch on, and every epoch is
    // available: G15 leaves GSA, RMC stays valid.
    let excluded = recs.iter().filter(|r| r["fde"] == "excluded").count();
    assert_eq!(excluded, FAULTED, "{recs:?}");
    assert!(recs.iter().all(|r| r["available"] == true));
    // with-text: each text line, then its sentences indented.
    let wt = raim(&["--nmea", "with-text"]);
    assert_eq!(wt.code, 0, "{}", wt.stderr);
    let indented = wt.stdout.lines().filter(|l| l.starts_with("    $")).count();
    assert_eq!(indented, s.lines().count());
    assert!(wt.stdout.contains("| epochs |"), "the summary table");
    // --nmea-file beside --json: the same stream.
    let file = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-araim.nmea");
    let j = raim(&["--json", "--nmea-file", file.to_str().expect("utf8")]);
    assert_eq!(j.code, 0, "{}", j.stderr);
    assert_eq!(std::fs::read_to_string(&file).expect("nmea file"), *s);
    assert_eq!(records(&j.stdout).0, recs);
}

fn f(r: &Value, k: &str) -> Option<f64> {
    r[k].as_f64()
}

#[test]
fn qemu_araim_decides_as_the_host_on_esbc_with_a_step() {
    let host = raim(&["--json"]);
    assert_eq!(host.code, 0, "{}", host.stderr);
    let file = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-araim-qemu.nmea");
    let dev = raim(&[
        "--json",
        "--target",
        "qemu",
        "--nmea-file",
        file.to_str().expect("utf8"),
    ]);
    assert_eq!(dev.code, 0, "{}", dev.stderr);
    let (h, hs) = records(&host.stdout);
    let (d, ds) = records(&dev.stdout);
    assert_eq!(h.len(), EPOCHS);
    assert_eq!(d.len(), EPOCHS);
    let (mut pl_diff_m, mut pos_diff_m) = (0.0f64, 0.0f64);
    for (a, b) in h.iter().zip(&d) {
        for k in [
            "time_gps_s",
            "sats",
            "faulted",
            "modes",
            "monitored",
            "max_faults",
            "detection_passed",
            "fde",
            "excluded",
            "available",
            "unavailable",
            "exclusion",
            "error",
        ] {
            assert_eq!(a[k], b[k], "{k}: host {a}\ndevice {b}");
        }
        for k in ["vpl_m", "hpl_m", "vpl_all_m", "hpl_all_m", "emt_m"] {
            match (f(a, k), f(b, k)) {
                (Some(x), Some(y)) => {
                    pl_diff_m = pl_diff_m.max((x - y).abs());
                    assert!((x - y).abs() <= PL_TOL_M, "{k}: {x} vs {y}");
                }
                (x, y) => assert_eq!(x.is_some(), y.is_some(), "{k}"),
            }
        }
        for i in 0..3 {
            let (x, y) = (a["error_enu_m"][i].as_f64(), b["error_enu_m"][i].as_f64());
            let (x, y) = (x.expect("host error"), y.expect("device error"));
            pos_diff_m = pos_diff_m.max((x - y).abs());
            assert!((x - y).abs() <= POSITION_TOL_M, "error[{i}] {x} vs {y}");
        }
    }
    // The spread quoted in docs/REPLAY.md.
    eprintln!(
        "device vs host over {EPOCHS} epochs: max |PL or EMT difference| {pl_diff_m:.4} m, \
         max |position difference per ENU axis| {pos_diff_m:.5} m"
    );
    for k in ["available", "exclusions", "correct_exclusions", "alarms"] {
        assert_eq!(hs[k], ds[k], "{k}");
    }
    assert_eq!(ds["correct_exclusions"], FAULTED, "{ds}");
    // The device's own NMEA: one epoch per answer, the host's
    // used-satellite lists and RMC status.
    let dev_nmea = std::fs::read_to_string(&file).expect("device nmea");
    let host_nmea = raim(&["--nmea", "only"]).stdout;
    let (de, he) = (epochs_of(&dev_nmea), epochs_of(&host_nmea));
    assert_eq!(de.len(), EPOCHS);
    for (a, b) in de.iter().zip(&he) {
        for id in ["1", "3", "4"] {
            assert_eq!(gsa_used(a, id), gsa_used(b, id), "system ID {id}");
        }
        assert_eq!(fields(a, "RMC").get(2), fields(b, "RMC").get(2));
        let kinds = |e: &[&str]| e.iter().map(|l| l[3..6].to_string()).collect::<Vec<_>>();
        assert_eq!(kinds(a), kinds(b));
    }
}

/// What the device cannot do is refused, naming both options.
#[test]
fn araim_on_the_device_refuses_what_it_lacks() {
    let r = raim(&["--target", "qemu", "--araim-iono-m", "0.5"]);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("--araim-iono-m") && r.stderr.contains("--target qemu"));
    assert!(r.stdout.is_empty());
}
