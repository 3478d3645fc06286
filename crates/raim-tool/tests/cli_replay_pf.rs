//! `raim replay --pf`: the short CI version of docs/PF.md's experiment.
//! GA-PF (300 particles) on the first 260 GEOP epochs and on the whole
//! 0759 file, at the thresholds the full runs calibrated (docs/pf/*.md,
//! P_FA = 1e-3 per epoch): the 50 m step is detected within 5 epochs and
//! isolated, with no false alarm before it; the same seed gives the same
//! output byte for byte; the plot is written.

use std::process::Command;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

fn raim(args: &[String]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .output()
        .expect("spawn raim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf8")
}

fn summary(stdout: &str) -> serde_json::Value {
    let last = stdout.lines().last().expect("a summary line");
    serde_json::from_str::<serde_json::Value>(last).expect("json")["pf_summary"].clone()
}

fn args(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

/// The delay budget, epochs.
const MAX_DELAY_EPOCHS: u64 = 5;

#[test]
fn geop_step_detected_isolated_and_deterministic() {
    let plot = std::env::temp_dir().join("raim_pf_geop_test.png");
    let mut a = args(&[
        "replay",
        "--obs",
        &format!("{DATA}/GEOP092I.24o.gz"),
        "--nav",
        &format!("{DATA}/CORD00ARG_R_20240920000_01D_MN.rnx.gz"),
        "--systems",
        "GE",
        "--end",
        "+259",
        "--fault",
        "step:G25:50@+200",
        "--pf",
        "gapf",
        "--particles",
        "300",
        "--pf-threshold",
        "28.69",
        "--json",
    ]);
    let first = raim(&a);
    let s = summary(&first);
    assert_eq!(s["fault_epoch"], 200);
    assert_eq!(s["false_alarms_before_fault"], 0);
    let alarm = s["first_alarm_epoch"].as_u64().expect("an alarm");
    assert!((200..=200 + MAX_DELAY_EPOCHS).contains(&alarm), "{alarm}");
    assert_eq!(s["isolated"], "G25");
    assert_eq!(s["collapses"], 0);
    // Determinism: the per-epoch records (everything but the timing) agree.
    a.extend(args(&["--pf-plot", plot.to_str().unwrap()]));
    let second = raim(&a);
    let strip = |s: &str| -> Vec<String> {
        s.lines()
            .filter(|l| !l.contains("pf_summary"))
            .map(String::from)
            .collect()
    };
    assert_eq!(strip(&first), strip(&second));
    assert!(std::fs::metadata(&plot)
        .map(|m| m.len() > 10_000)
        .unwrap_or(false));
}

#[test]
fn station_0759_step_detected_and_isolated() {
    let a = args(&[
        "replay",
        "--obs",
        &format!("{DATA}/07590920.05o"),
        "--nav",
        &format!("{DATA}/07590920.05n"),
        "--systems",
        "G",
        "--mask-deg",
        "15",
        "--pf-sigma-m",
        "3",
        "--pf-q-pos",
        "0.1",
        "--pf-q-clock",
        "5",
        "--pf-q-drift",
        "0.5",
        "--pf-window",
        "5",
        "--fault",
        "step:G24:50@+1800",
        "--pf",
        "gapf",
        "--particles",
        "300",
        "--pf-threshold",
        "71.97",
        "--json",
    ]);
    let s = summary(&raim(&a));
    assert_eq!(s["fault_epoch"], 60);
    assert_eq!(s["false_alarms_before_fault"], 0);
    let alarm = s["first_alarm_epoch"].as_u64().expect("an alarm");
    assert!((60..=60 + MAX_DELAY_EPOCHS).contains(&alarm), "{alarm}");
    assert_eq!(s["isolated"], "G24");
}

/// `--pf` refuses a fault that matches no epoch, as the snapshot replay
/// does: G99 is never in view, so the run is an error naming
/// the spec, with no panic, instead of a silent fault-free run.
#[test]
fn fault_matching_nothing_is_refused_under_pf_too() {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args(&[
            "replay",
            "--obs",
            &format!("{DATA}/07590920.05o"),
            "--nav",
            &format!("{DATA}/07590920.05n"),
            "--systems",
            "G",
            "--fault",
            "step:G99:50@+1800",
            "--pf",
            "ekf",
        ]))
        .output()
        .expect("spawn raim");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("step:G99:50@+1800"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
