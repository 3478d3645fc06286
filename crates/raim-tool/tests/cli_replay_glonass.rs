//! `raim replay` with GLONASS on ESBC (3 h, 360 epochs, Septentrio
//! PolaRx5): G+R+E+C against G+E+C, the GLONASS-only cut, a step on a
//! GLONASS satellite, and a bad GLONASS URA. Errors are against the
//! surveyed header position (`--reference header`), so the runs share one
//! reference. Sigma model: the geodetic fit of docs/REPLAY.md (URA 0.3 m,
//! vertical iono 0.5 m, noise 0.2 m), GLONASS URA 0.3 x 1.9 / 0.7 m.

use std::process::Command;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
const OBS: &str = "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz";
const NAV: &str = "ESBC00DNK_R_20201770000_01D_MN.rnx.gz";
const EPOCHS: u64 = 360;

fn raim(args: &[String]) -> (bool, String, String) {
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

fn args(systems: &str, extra: &[&str]) -> Vec<String> {
    let mut a: Vec<String> = [
        "replay",
        "--obs",
        &format!("{DATA}/{OBS}"),
        "--nav",
        &format!("{DATA}/{NAV}"),
        "--systems",
        systems,
        "--ura-m",
        "0.3",
        "--iono-vertical-m",
        "0.5",
        "--noise-m",
        "0.2",
        "--reference",
        "header",
        "--json",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    a.extend(extra.iter().map(|s| s.to_string()));
    a
}

fn summary(systems: &str, extra: &[&str]) -> serde_json::Value {
    let (ok, out, err) = raim(&args(systems, extra));
    assert!(ok, "{systems}: {err}");
    let last = out.lines().last().expect("a summary line");
    serde_json::from_str::<serde_json::Value>(last).expect("json")["summary"].clone()
}

fn num(s: &serde_json::Value, key: &str) -> f64 {
    s[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {s}"))
}

/// G+R+E+C over the whole file: every epoch solved and ok, no alarm, no
/// exclusion, no error above its protection level; the largest horizontal
/// and vertical errors no larger than G+E+C's (measured: H 1.59 vs 1.71 m,
/// V 2.02 vs 2.09 m), and the median horizontal error lower.
#[test]
fn grec_has_no_false_alarm_and_errors_no_worse_than_gec() {
    let gec = summary("GEC", &[]);
    let grec = summary("GREC", &[]);
    for (name, s) in [("GEC", &gec), ("GREC", &grec)] {
        assert_eq!(s["epochs"], EPOCHS, "{name} {s}");
        assert_eq!(s["solved"], EPOCHS, "{name} {s}");
        assert_eq!(s["ok"], EPOCHS, "{name} {s}");
        assert_eq!(s["alarms"], 0, "{name} {s}");
        assert_eq!(s["false_alarms"], 0, "{name} {s}");
        assert_eq!(s["false_exclusions"], 0, "{name} {s}");
        assert_eq!(s["misleading"], 0, "{name} {s}");
    }
    for key in ["error_h_max_m", "error_v_max_m", "error_h_median_m"] {
        assert!(
            num(&grec, key) <= num(&gec, key),
            "{key}: GREC {} > GEC {}",
            num(&grec, key),
            num(&gec, key)
        );
    }
    // The GLONASS satellites were used: more degrees of freedom means the
    // fault-free statistic is still consistent with its sigma model.
    assert!(num(&grec, "clean_d2_per_dof_mean") < 1.5, "{grec}");
}

/// The GLONASS-only cut: a solution at every epoch (6-9 satellites), no
/// alarm; errors within 5 m H and 6 m V of the header position (measured
/// 3.8 m and 4.8 m: GLONASS alone has the weakest broadcast orbits and
/// clocks and the fewest satellites).
#[test]
fn glonass_only_gives_solutions() {
    const MAX_H_M: f64 = 5.0;
    const MAX_V_M: f64 = 6.0;
    let s = summary("R", &[]);
    assert_eq!(s["solved"], EPOCHS, "{s}");
    assert_eq!(s["alarms"], 0, "{s}");
    assert_eq!(s["misleading"], 0, "{s}");
    assert!(num(&s, "error_h_max_m") < MAX_H_M, "{s}");
    assert!(num(&s, "error_v_max_m") < MAX_V_M, "{s}");
}

/// A 30 m step on R02 from 01:00:00 (10 min window, 21 epochs) in G+R+E+C
/// is excluded, and only R02, at every faulted epoch.
#[test]
fn glonass_step_is_excluded() {
    let s = summary(
        "GREC",
        &[
            "--start",
            "01:00:00",
            "--end",
            "01:10:00",
            "--fault",
            "step:R02:30@01:00:00",
        ],
    );
    assert_eq!(s["faulted_epochs"], 21, "{s}");
    assert_eq!(s["correct_exclusions"], 21, "{s}");
    assert_eq!(s["wrong_exclusions"], 0, "{s}");
    assert_eq!(s["missed_detections"], 0, "{s}");
}

/// A non-positive GLONASS URA is refused, naming the option.
#[test]
fn bad_glonass_ura_is_refused() {
    let (ok, _, err) = raim(&args("GR", &["--glonass-ura-m", "-1"]));
    assert!(!ok);
    assert!(err.contains("--glonass-ura-m"), "{err}");
}
