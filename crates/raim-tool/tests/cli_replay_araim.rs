//! `raim replay --araim`: the short CI version of docs/ARAIM.md's ESBC
//! runs (one hour, 00:30-01:30, faults from 01:00), against the surveyed
//! header position:
//! - clean G+E+C: every epoch available, no detection, error never above
//!   the protection levels;
//! - 30 m on G15 (G+E): every faulted epoch detected and G15 alone excluded;
//! - a Galileo-wide fault (a 20 m N / -20 m U shift of the Galileo
//!   solution): G+E alarms (excluding GPS or Galileo are both consistent),
//!   G+E+C excludes exactly the Galileo satellites;
//! - a uniform 30 m Galileo step is the Galileo clock: no detection and the
//!   same positions as the clean run;
//! - the plot is written.

use std::process::Command;

use serde_json::Value;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
/// Positions of two runs that must coincide: the relinearisation stops at
/// a 1e-4 m correction.
const SAME_POSITION_M: f64 = 1e-3;

fn run(extra: &[&str]) -> (Vec<Value>, Value) {
    let obs = format!("{DATA}/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz");
    let nav = format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz");
    let mut args = vec![
        "replay",
        "--obs",
        &obs,
        "--nav",
        &nav,
        "--reference",
        "header",
        "--start",
        "00:30:00",
        "--end",
        "01:30:00",
        "--araim",
        "--json",
    ];
    args.extend_from_slice(extra);
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(&args)
        .output()
        .expect("spawn raim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines: Vec<Value> = String::from_utf8(out.stdout)
        .expect("utf8")
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    let (summary, recs) = lines.split_last().expect("a summary");
    (recs.to_vec(), summary["araim_summary"].clone())
}

fn faulted(r: &Value) -> bool {
    !r["faulted"].as_array().unwrap().is_empty()
}

fn excluded(r: &Value) -> Vec<String> {
    r["excluded"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

/// Every epoch with a position output: error within its PLs.
fn errors_within_pls(recs: &[Value]) {
    for r in recs {
        if let (Some(v), Some(h)) = (r["vpl_m"].as_f64(), r["hpl_m"].as_f64()) {
            let ev = r["error_v_m"].as_f64().unwrap();
            let eh = r["error_h_m"].as_f64().unwrap();
            assert!(ev <= v && eh <= h, "{r}");
        }
    }
}

#[test]
fn esbc_clean_available_and_bounded() {
    let (recs, s) = run(&["--systems", "GEC"]);
    assert_eq!(recs.len(), 121);
    assert_eq!(s["available"], 121, "{s}");
    assert_eq!(s["false_detections"], 0);
    assert_eq!(s["error_above_pl"], 0);
    errors_within_pls(&recs);
    // G+E+C with pairs: hundreds of modes, every one monitored.
    assert!(recs
        .iter()
        .all(|r| r["modes"].as_u64().unwrap() > 100 && r["monitored"] == r["modes"]));
}

#[test]
fn esbc_step_on_g15_excluded() {
    let (recs, s) = run(&["--systems", "GE", "--fault", "step:G15:30@01:00:00"]);
    let hit: Vec<&Value> = recs.iter().filter(|r| faulted(r)).collect();
    assert_eq!(hit.len(), 61);
    for r in &hit {
        assert_eq!(r["fde"], "excluded", "{r}");
        assert_eq!(excluded(r), vec!["G15".to_string()]);
    }
    assert!(recs
        .iter()
        .filter(|r| !faulted(r))
        .all(|r| r["fde"] == "no_fault"));
    assert_eq!(s["wrong_exclusions"], 0);
    assert_eq!(s["error_above_pl"], 0);
    errors_within_pls(&recs);
}

#[test]
fn esbc_galileo_wide_fault_alarms_with_two_and_is_excluded_with_three() {
    let fault = ["--araim-const-fault", "E:0:0,20,-20@01:00:00"];
    let (recs, s) = run(&[&["--systems", "GE"][..], &fault[..]].concat());
    for r in recs.iter().filter(|r| faulted(r)) {
        assert_eq!(r["fde"], "alarm_ambiguous", "{r}");
        assert_eq!(r["available"], false);
        assert!(r["vpl_m"].is_null());
    }
    assert_eq!(s["alarms"], 61);

    let (recs, s) = run(&[&["--systems", "GEC"][..], &fault[..]].concat());
    for r in recs.iter().filter(|r| faulted(r)) {
        assert_eq!(r["fde"], "excluded", "{r}");
        let gal = r["faulted"].as_array().unwrap().len();
        let ex = excluded(r);
        assert_eq!(ex.len(), gal);
        assert!(ex.iter().all(|n| n.starts_with('E')));
    }
    assert_eq!(s["correct_exclusions"], 61);
    assert_eq!(s["error_above_pl"], 0);
    errors_within_pls(&recs);
}

#[test]
fn uniform_galileo_step_is_the_galileo_clock() {
    let plot = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim_araim_replay_test.png");
    let _ = std::fs::remove_file(&plot);
    let (clean, _) = run(&["--systems", "GEC"]);
    let (stepped, s) = run(&[
        "--systems",
        "GEC",
        "--fault",
        "step:E:30@01:00:00",
        "--araim-plot",
        plot.to_str().unwrap(),
    ]);
    assert_eq!(s["faulted_detected"], 0);
    for (a, b) in clean.iter().zip(stepped.iter()) {
        assert_eq!(b["fde"], "no_fault");
        for k in 0..3 {
            let d = a["error_enu_m"][k].as_f64().unwrap() - b["error_enu_m"][k].as_f64().unwrap();
            assert!(d.abs() < SAME_POSITION_M, "{d}");
        }
    }
    assert!(std::fs::metadata(&plot).unwrap().len() > 10_000);
}

/// The iono-free replay (docs/ARAIM.md "Iono-free replay"): GPS L1/L2
/// P(Y) and Galileo E1/E5a pairs, no Klobuchar, the ADD model with each
/// pair's noise factor. Every epoch available, no detection, error within
/// the PLs; and the pairs are in use: the positions differ from the
/// single-frequency run's (the ionosphere is removed by the data, not the
/// model) by more than 1 cm at every epoch, but by less than 10 m (the
/// same receiver; Klobuchar's residual is metres).
#[test]
fn esbc_iono_free_available_bounded_and_in_use() {
    let pairs = ["--code", "G=C1W+C2W", "--code", "E=C1C+C5Q"];
    let (recs, s) = run(&[&["--systems", "GE"][..], &pairs[..]].concat());
    assert_eq!(recs.len(), 121);
    assert_eq!(s["available"], 121, "{s}");
    assert_eq!(s["false_detections"], 0);
    assert_eq!(s["error_above_pl"], 0);
    errors_within_pls(&recs);
    let (sf, _) = run(&["--systems", "GE"]);
    for (a, b) in recs.iter().zip(sf.iter()) {
        let d: f64 = (0..3)
            .map(|k| {
                let x =
                    a["error_enu_m"][k].as_f64().unwrap() - b["error_enu_m"][k].as_f64().unwrap();
                x * x
            })
            .sum::<f64>()
            .sqrt();
        assert!(d > 0.01 && d < 10.0, "{d} m at {}", a["time_gps_s"]);
    }
}
