//! The `raim` binary end to end: `snapshot --json` on the example vector,
//! typed errors for bad epochs, and `threshold` against the SPEC's values.

use std::io::Write;
use std::process::{Command, Stdio};

fn raim(args: &[&str], stdin: &str) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("spawn raim");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin.as_bytes())
        .expect("write");
    let out = child.wait_with_output().expect("wait");
    assert!(out.status.success(), "raim {args:?} failed");
    String::from_utf8(out.stdout).expect("utf8")
}

fn example() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../host-tests/vectors/snapshot_example.jsonl"
    );
    std::fs::read_to_string(path).expect("example vector")
}

#[test]
fn snapshot_json_reports_the_injected_faults() {
    let out = raim(&["snapshot", "--json"], &example());
    let rows: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    assert_eq!(rows.len(), 8);
    for i in [0, 1, 2, 6] {
        assert_eq!(rows[i]["decision"], "ok", "epoch {i}");
    }
    for i in [3, 4, 7] {
        assert_eq!(rows[i]["decision"], "excluded", "epoch {i}");
        assert_eq!(rows[i]["excluded"][0], "G02");
        assert_eq!(rows[i]["exclusions"][0]["sat"], "G02");
        // The 50 m step is estimated within 5 m (sigma 1 m, S_ii > 0.3).
        let bias = rows[i]["exclusions"][0]["bias_m"].as_f64().unwrap();
        assert!((bias - 50.0).abs() < 5.0, "{bias}");
        assert_eq!(rows[i]["sats"].as_array().unwrap().len(), 8);
    }
    // The pseudorange epochs carry a geodetic position near the 0759 station.
    let lat = rows[6]["lat_deg"].as_f64().unwrap();
    assert!((lat - 35.33).abs() < 0.1, "{lat}");
}

#[test]
fn snapshot_reports_typed_errors_and_goes_on() {
    let mut lines: Vec<String> = example().lines().take(2).map(String::from).collect();
    // A duplicate PRN in the first epoch: replace G03 by a second G02.
    lines[0] = lines[0].replacen("\"prn\": 3,", "\"prn\": 2,", 1);
    let out = raim(&["snapshot", "--json", "--keep-going"], &lines.join("\n"));
    let rows: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 2, "every epoch answered");
    assert_eq!(rows[0]["error"], "DuplicateSatellite");
    assert_eq!(rows[1]["decision"], "ok");
}

/// SPEC §3: sqrt of the chi-square threshold at Pfa 3.3333e-7, dof 1..10
/// (exact values, rounded to 5 decimals), and SPEC §6 pbias at Pmd 1e-3.
#[test]
fn threshold_matches_the_spec_tables() {
    let exact = [
        5.10356, 5.46153, 5.73840, 5.97506, 6.18611, 6.37884, 6.55756, 6.72508, 6.88335, 7.03383,
    ];
    let pbias = [
        8.194, 8.479, 8.687, 8.860, 9.009, 9.142, 9.263, 9.375, 9.479, 9.576,
    ];
    const T_TOL: f64 = 6e-6; // dimensionless, 5-decimal rounding
    const PBIAS_TOL: f64 = 6e-4; // sigma units, 3-decimal rounding
    for dof in 1..=10usize {
        let out = raim(
            &[
                "threshold",
                "--pfa",
                "3.3333e-7",
                "--dof",
                &dof.to_string(),
                "--pmd",
                "1e-3",
                "--json",
            ],
            "",
        );
        let v: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
        let t = v["threshold"].as_f64().unwrap();
        let p = v["pbias"].as_f64().unwrap();
        assert!((t - exact[dof - 1]).abs() < T_TOL, "dof {dof}: {t}");
        assert!((p - pbias[dof - 1]).abs() < PBIAS_TOL, "dof {dof}: {p}");
    }
}

/// With `--mcusum` every result carries the MCUSUM state (SPEC §7): a finite
/// threshold h for the dimension and the statistic D_t >= 0.
#[test]
fn snapshot_reports_the_mcusum_state() {
    let out = raim(&["snapshot", "--json", "--mcusum"], &example());
    let rows: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 8);
    for r in &rows {
        let m = &r["mcusum"];
        assert!(m["threshold"].as_f64().unwrap() > 0.0, "{r}");
        assert!(m["statistic"].as_f64().unwrap() >= 0.0);
        // dof 4 all in view; 3 or 2 while excluded satellites are held out.
        let dim = m["dim"].as_u64().unwrap();
        assert!((2..=4).contains(&dim), "{r}");
    }
    assert!(rows[0]["mcusum"]["alarm"] == false);
}
