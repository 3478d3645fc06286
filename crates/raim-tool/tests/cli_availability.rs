//! `raim availability` (issue 36, docs/AVAILABILITY.md) on a small study of
//! the real almanacs (G24 + E24, 9 users, 12 epochs): the same inputs give
//! the same bytes; 4 time shards merged give the single run's files bit
//! for bit; at single user-epochs the engine's VPL, HPL, EMT and
//! sigma_v,acc equal `raim araim`'s on the same sky, with the sky and the
//! ADD error model formed independently of the engine.

use std::path::{Path, PathBuf};
use std::process::Command;

use raim_availability::{engine, run};
use serde_json::{json, Value};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn data(name: &str) -> String {
    format!("{ROOT}/../shared/data/{name}")
}

/// A fresh directory under the target's scratch directory.
fn tmp_dir(tag: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("raim-avail-{tag}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

/// The MAAST scenario's ISM and service on a 3 x 3 region and one hour.
fn small_run() -> String {
    small_run_with("none")
}

/// [`small_run`] with `exclusion` = `none`, `satellites` or `single_events`.
fn small_run_with(exclusion: &str) -> String {
    format!(
        r#"name = "small"
mask_deg = 5.0
exclusion = "{exclusion}"
[time]
start_s = 345600.0
span_s = 3600.0
step_s = 300.0
[grid]
kind = "region"
step_deg = 10.0
lat_min_deg = 50.0
lat_max_deg = 70.0
lon_min_deg = 0.0
lon_max_deg = 20.0
[service]
level = "LPV-200"
[[constellation]]
system = "G"
almanac = "{}"
week_rollovers = 0
sigma_ura_m = 1.0
sigma_ure_m = 0.6666666666666666
b_nom_m = 0.75
p_sat = 1e-5
p_const = 1e-8
[[constellation]]
system = "E"
almanac = "{}"
week_rollovers = 0
id_offset = 74
sigma_ura_m = 1.0
sigma_ure_m = 0.6666666666666666
b_nom_m = 0.75
p_sat = 1e-5
p_const = 1e-4
"#,
        data("almanac_gps24_mops.yuma"),
        data("almanac_galileo24.yuma")
    )
}

/// The CSV's rows as (availability, VPL percentile).
fn rows(csv: &[u8]) -> Vec<(f64, f64)> {
    String::from_utf8_lossy(csv)
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[6].parse().expect("availability"),
                f[7].parse().expect("vpl"),
            )
        })
        .collect()
}

fn raim(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .current_dir(ROOT)
        .output()
        .expect("run raim");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn read(dir: &Path) -> (Vec<u8>, Vec<u8>) {
    (
        std::fs::read(dir.join("small.summary.json")).expect("summary"),
        std::fs::read(dir.join("small.users.csv")).expect("csv"),
    )
}

/// Verifies: SPEC-14
#[test]
fn same_inputs_same_bytes_and_shards_merge_bit_for_bit() {
    let none = shards_merge_bit_for_bit("none");
    // With exclusion (every single-satellite exclusion must leave the
    // service available) no user is more available, and no level lower.
    let fde = shards_merge_bit_for_bit("satellites");
    let (none, fde) = (rows(&none), rows(&fde));
    assert_eq!(none.len(), fde.len());
    for ((a0, v0), (a1, v1)) in none.iter().zip(&fde) {
        assert!(a1 <= a0 && v1 >= v0, "{a0} {v0} -> {a1} {v1}");
    }
    assert!(fde.iter().zip(&none).any(|(f, n)| f.1 > n.1));
}

/// Runs the small study twice and in 4 shards; returns the CSV.
fn shards_merge_bit_for_bit(exclusion: &str) -> Vec<u8> {
    let d = tmp_dir(&format!("shards-{exclusion}"));
    let runf = d.join("small.toml");
    std::fs::write(&runf, small_run_with(exclusion)).expect("write run");
    let r = runf.to_str().expect("utf8");
    let (a, b, s, m) = (d.join("a"), d.join("b"), d.join("s"), d.join("m"));
    for out in [&a, &b] {
        let (code, _, err) = raim(&[
            "availability",
            "--run",
            r,
            "--out",
            out.to_str().expect("utf8"),
            "--level",
            "0.99",
        ]);
        assert_eq!(code, 0, "{err}");
    }
    let single = read(&a);
    assert_eq!(single, read(&b), "two runs of the same inputs differ");
    let csv = String::from_utf8(single.1.clone()).expect("utf8");
    assert_eq!(csv.lines().count(), 10, "{csv}");
    // Shards 1..4 (by time: 12 epochs as 3 + 3 + 3 + 3), one thread each,
    // merged in reverse order.
    let mut parts = Vec::new();
    for i in 1..=4 {
        let sh = format!("{i}/4");
        let (code, _, err) = raim(&[
            "availability",
            "--run",
            r,
            "--shard",
            &sh,
            "--threads",
            "1",
            "--out",
            s.to_str().expect("utf8"),
        ]);
        assert_eq!(code, 0, "{err}");
        parts.push(
            s.join(format!("small.shard-{i}-of-4.json"))
                .to_str()
                .expect("utf8")
                .to_string(),
        );
    }
    let mut args = vec!["availability", "merge"];
    args.extend(parts.iter().rev().map(String::as_str));
    let mo = m.to_str().expect("utf8").to_string();
    args.extend(["--out", &mo, "--level", "0.99"]);
    let (code, _, err) = raim(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        read(&m),
        single,
        "4 shards merged differ from the single run"
    );
    // A missing shard is refused by name.
    let (code, _, err) = raim(&["availability", "merge", &parts[0], &parts[1], &parts[3]]);
    assert_ne!(code, 0);
    assert!(err.contains("shard 3/4 is missing"), "{err}");
    let _ = std::fs::remove_dir_all(&d);
    single.1
}

/// SPEC §9.1's nominal variance written out (DO-229 troposphere, the
/// ADD's multipath and noise through the L1/L5 iono-free factor), in std
/// arithmetic: independent of raim-core's `error_model`.
fn nominal_m2(el_rad: f64) -> f64 {
    let s = el_rad.sin();
    let tropo = 0.12 * 1.001 / (0.002_001 + s * s).sqrt();
    let el_deg = el_rad.to_degrees();
    let mp = 0.13 + 0.53 * (-el_deg / 10.0).exp();
    let noise = 0.15 + 0.43 * (-el_deg / 6.9).exp();
    let (f1, f5) = (1575.42f64.powi(2), 1176.45f64.powi(2));
    let k2 = (f1 * f1 + f5 * f5) / ((f1 - f5) * (f1 - f5));
    tropo * tropo + k2 * (mp * mp + noise * noise)
}

/// Verifies: SPEC-14, SPEC-9.1
#[test]
fn one_user_epoch_equals_raim_araim_on_the_same_sky() {
    on_engine_stack(one_user_epoch_body);
}

fn one_user_epoch_body() {
    let d = tmp_dir("epoch");
    let runf = d.join("small.toml");
    std::fs::write(&runf, small_run()).expect("write run");
    let study = run::load(&runf).expect("study");
    let mut monitor = engine::new_engine();
    let mut lines = String::new();
    let mut expected = Vec::new();
    // Three users (one unavailable at 99.5 % in the 24 h run) at three epochs.
    for (ui, k) in [(0usize, 0usize), (4, 5), (8, 11)] {
        let u = &study.users[ui];
        let sky = engine::sky_table(&study, k..k + 1);
        let (x, rot) = engine::user_frame(&study, u);
        let mut obs = Vec::new();
        engine::visible(&study, &sky, x, &rot, &mut obs);
        let o = engine::evaluate(&study, &mut monitor, &obs).expect("epoch");
        assert!(o.vpl_m.is_finite() && o.hpl_m.is_finite() && o.modes > obs.len() as u32);
        // The same sky by raim-nav's az/el from ECEF (its own geodetic
        // conversion and trigonometry), the G rows and variances by hand.
        let mut sats = Vec::new();
        for (s, p) in study.sats.iter().zip(&sky) {
            let (az, el, _) = raim_nav::geometry::az_el(x, *p);
            if el < 5f64.to_radians() {
                continue;
            }
            let v = nominal_m2(el);
            let (c_int, c_acc) = (1.0 + v, (2.0f64 / 3.0).powi(2) + v);
            sats.push(json!({
                "sys": s.id.system.letter().to_string(), "prn": s.id.prn,
                "g_enu": [-el.cos() * az.sin(), -el.cos() * az.cos(), -el.sin()],
                "c_int_m2": c_int, "c_acc_m2": c_acc, "b_nom_m": 0.75, "p_sat": 1e-5,
            }));
        }
        assert_eq!(
            sats.len(),
            obs.len(),
            "user {ui} epoch {k}: visible sets differ"
        );
        let line = json!({
            "time_s": study.epochs_gps_s[k],
            "ism": {"p_const": {"G": 1e-8, "E": 1e-4}},
            "sats": sats,
        });
        lines.push_str(&format!("{line}\n"));
        expected.push((ui, k, o));
    }
    let input = d.join("sky.jsonl");
    std::fs::write(&input, &lines).expect("write");
    let (code, out, err) = raim(&["araim", "--json", "--input", input.to_str().expect("utf8")]);
    assert_eq!(code, 0, "{err}");
    let got: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    assert_eq!(got.len(), expected.len());
    for ((ui, k, o), g) in expected.iter().zip(&got) {
        let f = |key: &str| g[key].as_f64().unwrap_or(f64::INFINITY);
        for (name, ours, theirs) in [
            ("VPL", o.vpl_m, f("vpl_m")),
            ("HPL", o.hpl_m, f("hpl_m")),
            ("EMT", o.emt_m, f("emt_m")),
            ("sigma_v,acc", o.sigma_v_acc_m, f("sigma_v_acc_m")),
        ] {
            assert!(
                (ours - theirs).abs() <= 1e-6,
                "user {ui} epoch {k}: {name} engine {ours} vs raim araim {theirs}"
            );
        }
        assert_eq!(
            Some(o.available),
            g["available"].as_bool(),
            "user {ui} epoch {k}"
        );
        assert_eq!(u64::from(o.modes), g["monitored"].as_u64().unwrap_or(0));
    }
    // App. D's vector still holds through the same subcommand.
    let (code, out, err) = raim(&[
        "araim",
        "--json",
        "--input",
        "host-tests/vectors/add_v3_appendix_d.json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(out.lines().next().unwrap_or("")).expect("json");
    assert!(
        (v["vpl_m"].as_f64().unwrap_or(0.0) - 19.2).abs() < 0.05,
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Bad run files are refused with the file and line.
///
/// Verifies: SPEC-14
#[test]
fn bad_run_files_name_file_and_line() {
    let d = tmp_dir("bad");
    let cases = [
        (
            small_run().replace("level = \"LPV-200\"", "level = \"custom\"\nval_m = 35.0\nhal_m = 40.0\nemt_max_m = 40.0\nsigma_acc_max_m = 1.87"),
            "bad.toml:16: the service level is refused by raim-core",
        ),
        (
            small_run().replace("step_deg = 10.0\nlat_min_deg = 50.0", "step_deg = 10.0\nlat_min_deg = 80.0"),
            "bad.toml:9: bad grid axis [80, 70]",
        ),
        (
            small_run().replacen("week_rollovers = 0\n", "", 1),
            "almanac_gps24_mops.yuma:14: week 703 is a 10-bit broadcast week",
        ),
        (
            small_run().replace("start_s = 345600.0", "start_s = 0.0"),
            "almanac_gps24_mops.yuma:2: the run's epochs",
        ),
        (
            small_run().replacen("p_sat = 1e-5", "p_sat = 2.0", 1),
            "the ISM is refused by raim-core",
        ),
        (
            small_run().replacen("almanac = ", "navigation = \"x.rnx\"\nalmanac = ", 1),
            "[[constellation]] 1 (system \"G\"): give the constellation's `almanac` or `navigation` (one of them)",
        ),
        (
            small_run_with("continuity"),
            "bad.toml:3: exclusion = \"continuity\" needs a [continuity] table",
        ),
        (
            continuity_run("1e-5", "{ name = \"A\", lat_deg = 0.0, lon_deg = 0.0 }")
                .replacen("mfd_const_s = 7200.0\n", "", 1),
            "[[constellation]] 2 (system \"E\"): exclusion = \"continuity\" needs mfd_sat_s and mfd_const_s",
        ),
        (
            continuity_run("3e-6", "{ name = \"A\", lat_deg = 0.0, lon_deg = 0.0 }"),
            "bad.toml:5: p_alert 0.000003 must exceed the false-alert budget",
        ),
        (
            continuity_run("1e-5", "{ name = \"A\", lat_deg = 0.0, lon_deg = 0.0 }")
                .replace("exclusion = \"continuity\"", "exclusion = \"none\""),
            "bad.toml:4: [continuity] is read only with exclusion = \"continuity\"",
        ),
    ];
    for (text, want) in cases {
        let f = d.join("bad.toml");
        std::fs::write(&f, text).expect("write");
        let (code, _, err) = raim(&["availability", "--run", f.to_str().expect("utf8")]);
        assert_ne!(code, 0, "{want}");
        assert!(err.contains(want), "want `{want}` in: {err}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// [`small_run`] as `exclusion = "continuity"` with ADD v4.2's LPV-200
/// continuity parameters (docs/runs/availability_maast_g24e24_fde.toml),
/// `p_alert` given, on `sites` over 24 h.
fn continuity_run(p_alert: &str, sites: &str) -> String {
    small_run_with("continuity")
        .replace(
            "[time]",
            &format!("[continuity]\np_alert = {p_alert}\nt_exp_s = 150.0\n[time]"),
        )
        .replace("span_s = 3600.0", "span_s = 86400.0")
        .replace(
            "kind = \"region\"\nstep_deg = 10.0\nlat_min_deg = 50.0\nlat_max_deg = 70.0\nlon_min_deg = 0.0\nlon_max_deg = 20.0",
            &format!("kind = \"sites\"\nsites = [{sites}]"),
        )
        .replacen("p_const = 1e-8\n", "p_const = 1e-8\nmfd_sat_s = 3600.0\nmfd_const_s = 3600.0\n", 1)
        .replacen("p_const = 1e-4\n", "p_const = 1e-4\nmfd_sat_s = 5400.0\nmfd_const_s = 7200.0\n", 1)
}

/// `exclusion = "continuity"`: at every epoch of two users over 24 h the
/// engine's decision equals the rule evaluated by brute force in the
/// test: detection-only available, and the fault modes whose exclusion
/// leaves the service unavailable (every monitored mode's subset through
/// `Monitor::after_excluding`, no early exit) have a summed onset
/// probability P T_exp / MFD, written out here from the run file's
/// numbers (GPS satellite 1e-5 x 150 / 3600, Galileo satellite 1e-5 x 150
/// / 5400, Galileo constellation 1e-4 x 150 / 7200, GPS constellation
/// 1e-8 x 150 / 3600), within P_ALERT - P_FA,V - P_FA,H = 1e-5 - 3.99e-6.
/// Both outcomes occur: epochs whose failed exclusions the allocation
/// absorbs, and epochs it makes unavailable. With P_ALERT 0.5 the result
/// is detection only.
///
/// Verifies: TOOL-AVAIL-FDE
#[test]
fn continuity_rule_equals_brute_force_over_every_candidate() {
    on_engine_stack(continuity_rule_body);
}

/// Runs `f` on a thread with the engine workers' stack
/// (`engine::STACK_BYTES`: the monitor's outputs are formed on the stack,
/// more than a test thread's default in a debug build).
fn on_engine_stack(f: fn()) {
    std::thread::Builder::new()
        .stack_size(engine::STACK_BYTES)
        .spawn(f)
        .expect("spawn")
        .join()
        .expect("the test body panicked");
}

fn continuity_rule_body() {
    use raim_core::araim::ModeStatus;
    let d = tmp_dir("continuity");
    let sites = r#"{ name = "A", lat_deg = 80.0, lon_deg = 150.0 }, { name = "B", lat_deg = 0.0, lon_deg = 70.0 }"#;
    let runf = d.join("c.toml");
    std::fs::write(&runf, continuity_run("1e-5", sites)).expect("write run");
    let study = run::load(&runf).expect("study");
    let mut detection = study.clone();
    detection.exclusion = run::ExclusionSpec::None;
    let mut lax = study.clone();
    std::fs::write(&runf, continuity_run("0.5", sites)).expect("write run");
    lax.continuity = run::load(&runf).expect("study").continuity;
    let p_alloc = 1e-5 - 3.9e-6 - 9e-8;
    let sky = engine::sky_table(&study, 0..study.epochs_gps_s.len());
    let n = study.sats.len();
    let mut monitor = engine::new_engine();
    let (mut absorbed, mut lost, mut epochs) = (0, 0, 0);
    for u in &study.users {
        let (x, rot) = engine::user_frame(&study, u);
        for row in sky.chunks_exact(n) {
            let mut obs = Vec::new();
            engine::visible(&study, row, x, &rot, &mut obs);
            let got = engine::evaluate(&study, &mut monitor, &obs).expect("epoch");
            let lax_got = engine::evaluate(&lax, &mut monitor, &obs).expect("epoch");
            let det = engine::evaluate(&detection, &mut monitor, &obs).expect("epoch");
            assert_eq!(lax_got, det, "P_ALERT 0.5 is detection only");
            epochs += 1;
            if !det.available {
                assert!(!got.available);
                continue;
            }
            let modes: Vec<(usize, raim_core::araim::ModeEvents)> = monitor
                .all_in_view()
                .modes
                .iter()
                .enumerate()
                .filter(|(_, m)| m.status == ModeStatus::Monitored)
                .map(|(k, m)| (k, m.events))
                .collect();
            let systems: Vec<raim_core::System> =
                monitor.satellites().iter().map(|s| s.id.system).collect();
            let mut failed = 0.0;
            for (k, events) in modes {
                let ok = monitor
                    .after_excluding(&study.cfg, &study.ism, k)
                    .expect("subset")
                    .is_some_and(|s| s.available());
                if ok {
                    continue;
                }
                let sats_in: Vec<_> = (0..systems.len())
                    .filter(|i| events.sats >> i & 1 == 1)
                    .collect();
                let onset = match (sats_in.as_slice(), events.consts) {
                    ([i], 0) if systems[*i] == raim_core::System::Gps => 1e-5 * 150.0 / 3600.0,
                    ([_], 0) => 1e-5 * 150.0 / 5400.0,
                    ([], c) if c == 1 << raim_core::System::Galileo.index() => {
                        1e-4 * 150.0 / 7200.0
                    }
                    ([], c) if c == 1 << raim_core::System::Gps.index() => 1e-8 * 150.0 / 3600.0,
                    other => panic!("a multi-event mode at P_sat 1e-5: {other:?}"),
                };
                failed += onset;
            }
            let want = failed <= p_alloc;
            assert_eq!(got.available, want, "user {} failed {failed:e}", u.name);
            // The levels reported are the detection-only ones.
            assert_eq!(
                (got.vpl_m, got.hpl_m, got.emt_m),
                (det.vpl_m, det.hpl_m, det.emt_m)
            );
            absorbed += usize::from(want && failed > 0.0);
            lost += usize::from(!want);
        }
    }
    assert_eq!(epochs, 2 * 288);
    assert!(absorbed > 0 && lost > 0, "absorbed {absorbed}, lost {lost}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `airborne = "galileo_e1e5a"`: the Galileo satellites' C_int and C_acc
/// are sigma_URA^2 (sigma_URE^2) + the DO-229 troposphere + the square of
/// the E1/E5a table (MAAST's `af_cnmp_galileo` values, written out here
/// and interpolated by hand), the GPS satellites keep the L1/L5 curves;
/// a mask below the table's 5 degrees is refused.
///
/// Verifies: SPEC-14, SPEC-9.1
#[test]
fn galileo_e1e5a_curve_feeds_the_core() {
    on_engine_stack(galileo_body);
}

fn galileo_body() {
    const TABLE: [f64; 18] = [
        0.4529, 0.3553, 0.3063, 0.2638, 0.2593, 0.2555, 0.2504, 0.2438, 0.2396, 0.2359, 0.2339,
        0.2302, 0.2295, 0.2278, 0.2297, 0.2310, 0.2274, 0.2277,
    ];
    let d = tmp_dir("galileo");
    let runf = d.join("g.toml");
    let text = small_run().replace(
        "id_offset = 74\n",
        "id_offset = 74\nairborne = \"galileo_e1e5a\"\n",
    );
    std::fs::write(&runf, &text).expect("write run");
    let study = run::load(&runf).expect("study");
    let mut monitor = engine::new_engine();
    let (mut n_gal, mut n_gps) = (0, 0);
    for (ui, k) in [(0usize, 0usize), (4, 7)] {
        let sky = engine::sky_table(&study, k..k + 1);
        let (x, rot) = engine::user_frame(&study, &study.users[ui]);
        let mut obs = Vec::new();
        engine::visible(&study, &sky, x, &rot, &mut obs);
        engine::evaluate(&study, &mut monitor, &obs).expect("epoch");
        for s in monitor.satellites() {
            let el_rad = (-s.g_enu[2]).asin();
            let el = el_rad.to_degrees();
            let v = if s.id.system == raim_core::System::Galileo {
                n_gal += 1;
                let lo = ((el / 5.0).floor() as usize).clamp(1, 17);
                let (a, b) = (TABLE[lo - 1], TABLE[lo.min(17)]);
                let air = a + (el - 5.0 * lo as f64) / 5.0 * (b - a);
                let tropo = 0.12 * 1.001 / (0.002_001 + el_rad.sin().powi(2)).sqrt();
                tropo * tropo + air * air
            } else {
                n_gps += 1;
                nominal_m2(el_rad)
            };
            assert!((s.c_int_m2 - (1.0 + v)).abs() < 1e-9, "{:?} el {el}", s.id);
            assert!(
                (s.c_acc_m2 - (4.0 / 9.0 + v)).abs() < 1e-9,
                "{:?} el {el}",
                s.id
            );
        }
    }
    assert!(n_gal > 10 && n_gps > 10, "{n_gal} {n_gps}");
    std::fs::write(&runf, text.replace("mask_deg = 5.0", "mask_deg = 2.0")).expect("write");
    let e = run::load(&runf).expect_err("mask below 5");
    assert!(e.to_string().contains("needs mask_deg >= 5"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `airborne = "ed259a_maast"` on both constellations: every satellite's
/// C_int and C_acc are sigma_URA^2 (sigma_URE^2) plus the DO-229
/// troposphere, MAAST for ARAIM 2's ED-259A curve 0.4^2 + (0.34 + 0.40
/// exp(-el / 14 deg))^2 and its ionospheric residual (40 / (261 + el^2)
/// plus 0.018)^2, written out here from `af_cnmp_259a.m` and
/// `usrprocess_araim.m`; at a 2 deg mask too (the curve has no table
/// bound). At the zenith that sum is 0.29096 m^2 (worked by hand: tropo
/// 0.12^2, airborne 0.27604, residual 0.022784^2).
///
/// Verifies: SPEC-14, SPEC-9.1
#[test]
fn ed259a_maast_curve_feeds_the_core() {
    on_engine_stack(ed259a_body);
}

fn ed259a_maast_m2(el_rad: f64) -> f64 {
    let el = el_rad.to_degrees();
    let tropo = 0.12 * 1.001 / (0.002_001 + el_rad.sin().powi(2)).sqrt();
    let mp = 0.34 + 0.40 * (-el / 14.0).exp();
    let iono = 40.0 / (261.0 + el * el) + 0.018;
    tropo * tropo + 0.16 + mp * mp + iono * iono
}

fn ed259a_body() {
    assert!((ed259a_maast_m2(std::f64::consts::FRAC_PI_2) - 0.290_96).abs() < 1e-5);
    let d = tmp_dir("ed259a");
    let runf = d.join("e.toml");
    let text = small_run()
        .replace(
            "week_rollovers = 0\n",
            "week_rollovers = 0\nairborne = \"ed259a_maast\"\n",
        )
        .replace("mask_deg = 5.0", "mask_deg = 2.0");
    assert_eq!(text.matches("ed259a_maast").count(), 2, "{text}");
    std::fs::write(&runf, &text).expect("write run");
    let study = run::load(&runf).expect("study");
    let mut monitor = engine::new_engine();
    let (mut n_gal, mut n_gps, mut low) = (0, 0, 0);
    for (ui, k) in
        (0..study.users.len()).flat_map(|u| (0..study.epochs_gps_s.len()).map(move |k| (u, k)))
    {
        let sky = engine::sky_table(&study, k..k + 1);
        let (x, rot) = engine::user_frame(&study, &study.users[ui]);
        let mut obs = Vec::new();
        engine::visible(&study, &sky, x, &rot, &mut obs);
        engine::evaluate(&study, &mut monitor, &obs).expect("epoch");
        for s in monitor.satellites() {
            let el_rad = (-s.g_enu[2]).asin();
            if s.id.system == raim_core::System::Galileo {
                n_gal += 1;
            } else {
                n_gps += 1;
            }
            low += usize::from(el_rad.to_degrees() < 5.0);
            let v = ed259a_maast_m2(el_rad);
            assert!((s.c_int_m2 - (1.0 + v)).abs() < 1e-9, "{:?}", s.id);
            assert!((s.c_acc_m2 - (4.0 / 9.0 + v)).abs() < 1e-9, "{:?}", s.id);
        }
    }
    assert!(n_gal > 100 && n_gps > 100, "{n_gal} {n_gps}");
    assert!(low > 0, "no satellite between the 2 and 5 deg masks");
    let _ = std::fs::remove_dir_all(&d);
}

/// `--outages G`: the run as given and each of the 24 GPS outages, each
/// written as a run of its own; the outage of G05 gives the per-user CSV
/// of a separate run with `remove = [5]` byte for byte, and its row of
/// `small.outages.csv` that run's coverage; the base row the plain run's.
///
/// Verifies: SPEC-14
#[test]
fn outage_sweep_equals_separate_runs() {
    let d = tmp_dir("outages");
    let runf = d.join("small.toml");
    std::fs::write(&runf, small_run()).expect("write");
    let (sweep, single, plain) = (d.join("sweep"), d.join("single"), d.join("plain"));
    let r = runf.to_str().expect("utf8");
    let (code, _, err) = raim(&[
        "availability",
        "--run",
        r,
        "--outages",
        "G",
        "--out",
        sweep.to_str().expect("utf8"),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = raim(&[
        "availability",
        "--run",
        r,
        "--out",
        plain.to_str().expect("utf8"),
    ]);
    assert_eq!(code, 0, "{err}");
    let runf5 = d.join("small5.toml");
    std::fs::write(
        &runf5,
        small_run().replacen("p_const = 1e-8\n", "p_const = 1e-8\nremove = [5]\n", 1),
    )
    .expect("write");
    let (code, _, err) = raim(&[
        "availability",
        "--run",
        runf5.to_str().expect("utf8"),
        "--out",
        single.to_str().expect("utf8"),
    ]);
    assert_eq!(code, 0, "{err}");
    let table = std::fs::read_to_string(sweep.join("small.outages.csv")).expect("table");
    let rows: Vec<Vec<&str>> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 25, "{table}");
    assert_eq!(rows[0][1], "none");
    let cov = |dir: &Path| -> f64 {
        let v: Value = serde_json::from_slice(
            &std::fs::read(dir.join("small.summary.json")).expect("summary"),
        )
        .expect("json");
        v["coverage"][0]["coverage"].as_f64().expect("coverage")
    };
    let row5 = rows.iter().find(|r| r[1] == "G05").expect("G05 row");
    assert!(
        (row5[2].parse::<f64>().expect("num") - cov(&single)).abs() < 1e-6,
        "{row5:?}"
    );
    assert!((rows[0][2].parse::<f64>().expect("num") - cov(&plain)).abs() < 1e-6);
    assert_eq!(
        std::fs::read(sweep.join("small.outage-G05.users.csv")).expect("csv"),
        std::fs::read(single.join("small.users.csv")).expect("csv")
    );
    assert_eq!(
        std::fs::read(sweep.join("small.users.csv")).expect("csv"),
        std::fs::read(plain.join("small.users.csv")).expect("csv")
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The sweep of [`small_run`]: the run as written, Galileo's P_const at
/// 1e-5, LPV-250 with the strict exclusion rule, and every single GPS
/// outage with E03 removed (24 scenarios from one generator).
fn sweep_run() -> String {
    format!(
        r#"{}
[[scenario]]
name = "gal-pconst-1e-5"
[[scenario.constellation]]
system = "E"
p_const = 1e-5

[[scenario]]
name = "lpv250-fde"
exclusion = "satellites"
[scenario.service]
level = "LPV-250"

[[scenario]]
name = "gps-out"
outages = "G"
[[scenario.constellation]]
system = "E"
remove = [3]
"#,
        small_run()
    )
}

/// Every file of `dir`, by name.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .expect("dir")
        .map(|e| {
            let p = e.expect("entry").path();
            (
                p.file_name().expect("name").to_string_lossy().into_owned(),
                std::fs::read(&p).expect("read"),
            )
        })
        .collect();
    v.sort();
    v
}

/// A sweep in one run file (`[[scenario]]`): each scenario's CSV equals a
/// separate run file with its change written in, byte for byte (the
/// P_const override; a generated outage, G05 with E03 removed); the
/// coverage table has a row per scenario with the scenario's coverage; 4
/// shards over scenario x epoch (27 scenarios x 12 epochs: whole scenarios
/// and a scenario cut in time in one shard) merged in reverse order give
/// every file of the whole run byte for byte.
///
/// Verifies: TOOL-AVAIL-SWEEP
#[test]
fn sweep_scenarios_equal_separate_runs_and_shards_merge_bit_for_bit() {
    let d = tmp_dir("sweep");
    let runf = d.join("small.toml");
    std::fs::write(&runf, sweep_run()).expect("write");
    let r = runf.to_str().expect("utf8");
    let (whole, shards, merged) = (d.join("whole"), d.join("shards"), d.join("merged"));
    let (code, _, err) = raim(&[
        "availability",
        "--run",
        r,
        "--out",
        whole.to_str().expect("utf8"),
        "--level",
        "0.99",
    ]);
    assert_eq!(code, 0, "{err}");
    // Separate runs of two scenarios.
    let separate = |tag: &str, text: String| -> Vec<u8> {
        let f = d.join(format!("{tag}.toml"));
        std::fs::write(&f, text).expect("write");
        let o = d.join(tag);
        let (code, _, err) = raim(&[
            "availability",
            "--run",
            f.to_str().expect("utf8"),
            "--out",
            o.to_str().expect("utf8"),
        ]);
        assert_eq!(code, 0, "{err}");
        std::fs::read(o.join("small.users.csv")).expect("csv")
    };
    let pconst = separate(
        "pconst",
        small_run().replacen("p_const = 1e-4", "p_const = 1e-5", 1),
    );
    let out5 = separate(
        "out5",
        small_run()
            .replacen("p_const = 1e-8\n", "p_const = 1e-8\nremove = [5]\n", 1)
            .replacen("p_const = 1e-4\n", "p_const = 1e-4\nremove = [3]\n", 1),
    );
    let plain = separate("plain", small_run());
    let csv = |stem: &str| std::fs::read(whole.join(format!("{stem}.users.csv"))).expect(stem);
    assert_eq!(csv("small"), plain);
    assert_eq!(csv("small.gal-pconst-1e-5"), pconst);
    assert_eq!(csv("small.gps-out.outage-G05"), out5);
    assert_ne!(pconst, plain, "the override changed nothing");
    // The table: 1 + 2 + 24 rows, each row the scenario's own coverage.
    let table = std::fs::read_to_string(whole.join("small.sweep.csv")).expect("table");
    let rows: Vec<Vec<&str>> = table
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 27, "{table}");
    assert_eq!(rows[0][..2], ["small", "none"]);
    assert_eq!(rows[26][..2], ["small.gps-out.outage-G24", "G24"]);
    for row in &rows {
        let v: Value = serde_json::from_slice(
            &std::fs::read(whole.join(format!("{}.summary.json", row[0]))).expect("summary"),
        )
        .expect("json");
        let cov = v["coverage"][1]["coverage"].as_f64().expect("coverage");
        assert!(
            (row[3].parse::<f64>().expect("num") - cov).abs() < 1e-6,
            "{row:?}"
        );
    }
    let lpv250: Value = serde_json::from_slice(
        &std::fs::read(whole.join("small.lpv250-fde.summary.json")).expect("summary"),
    )
    .expect("json");
    assert_eq!(lpv250["val_m"], 50.0);
    assert!(std::fs::read_to_string(whole.join("small.sweep.md"))
        .expect("md")
        .starts_with("| scenario | removed | coverage at 99.5 % | coverage at 99 % |"));
    // 4 shards, one thread each, merged in reverse order.
    let mut parts = Vec::new();
    for i in 1..=4 {
        let sh = format!("{i}/4");
        let (code, _, err) = raim(&[
            "availability",
            "--run",
            r,
            "--shard",
            &sh,
            "--threads",
            "1",
            "--out",
            shards.to_str().expect("utf8"),
        ]);
        assert_eq!(code, 0, "{err}");
        parts.push(
            shards
                .join(format!("small.shard-{i}-of-4.json"))
                .to_str()
                .expect("utf8")
                .to_string(),
        );
    }
    // Shard 1 holds whole scenarios and the start of one cut in time.
    let p1: Value = serde_json::from_slice(&std::fs::read(&parts[0]).expect("part")).expect("json");
    let ranges: Vec<(u64, u64)> = p1["pieces"]
        .as_array()
        .expect("pieces")
        .iter()
        .map(|p| {
            (
                p["epoch_range"][0].as_u64().expect("a"),
                p["epoch_range"][1].as_u64().expect("b"),
            )
        })
        .collect();
    assert!(
        ranges.contains(&(0, 12)) && ranges.last() == Some(&(0, 9)),
        "{ranges:?}"
    );
    let mut args = vec!["availability", "merge"];
    args.extend(parts.iter().rev().map(String::as_str));
    let mo = merged.to_str().expect("utf8").to_string();
    args.extend(["--out", &mo, "--level", "0.99"]);
    let (code, _, err) = raim(&args);
    assert_eq!(code, 0, "{err}");
    let (w, m) = (files(&whole), files(&merged));
    assert_eq!(w.len(), 27 * 2 + 2);
    assert_eq!(
        w.iter().map(|x| &x.0).collect::<Vec<_>>(),
        m.iter().map(|x| &x.0).collect::<Vec<_>>()
    );
    for (a, b) in w.iter().zip(&m) {
        assert!(a.1 == b.1, "{}: merged differs from the whole run", a.0);
    }
    // Scenario errors name the scenario and its line.
    for (text, want) in [
        (
            format!("{}\n[[scenario]]\nname = \"g\"\n[scenario.grid]\nkind = \"world\"\nstep_deg = 5.0\n", small_run()),
            ":39: scenario `g`: `grid` cannot be set in a scenario",
        ),
        (
            format!("{}\n[[scenario]]\nname = \"p\"\n[[scenario.constellation]]\nsystem = \"G\"\np_sat = 2.0\n", small_run()),
            "bad.toml: [[constellation]] 1 (system \"G\"): the ISM is refused by raim-core",
        ),
        (
            format!("{}\n[[scenario]]\nname = \"m\"\nmask_deg = 95.0\n", small_run()),
            "bad.toml:39: mask_deg 95 outside [0, 90)",
        ),
        (
            format!("{}\n[[scenario]]\nmask_deg = 9.0\n", small_run()),
            "a [[scenario]] needs `name`",
        ),
    ] {
        let f = d.join("bad.toml");
        std::fs::write(&f, text).expect("write");
        let (code, _, err) = raim(&["availability", "--run", f.to_str().expect("utf8")]);
        assert_ne!(code, 0, "{want}");
        assert!(err.contains(want), "want `{want}` in: {err}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A constellation from a RINEX navigation file (docs/runs/
/// availability_esbc_nav.toml, GPS and Galileo from ESBC's mixed file):
/// at the first epoch of ESBC's observation file, every GPS and Galileo
/// satellite the replay's receiver path forms (raim-gnss `prepare_epoch`:
/// the transmit time from the pseudorange, the position there rotated by
/// the Earth's rotation during transit) is in the study, and the study's
/// position at that transmit time, rotated here by hand, equals the
/// replay's within 1 mm. A short run over a region gives a result, and a
/// span past the file's end reports the epochs without a valid ephemeris,
/// each satellite's count equal to the count of epochs at which no
/// healthy record of it lies within the validity window (counted here
/// from the records).
///
/// Verifies: TOOL-AVAIL-RINEX
#[test]
fn rinex_navigation_positions_equal_the_replays() {
    let runf = Path::new(ROOT).join("docs/runs/availability_esbc_nav.toml");
    let study = run::load(&runf).expect("study");
    let nav = raim_gnss::NavData::load(Path::new(&data("ESBC00DNK_R_20201770000_01D_MN.rnx.gz")))
        .expect("nav");
    let obs = raim_gnss::ObsData::load(Path::new(&data(
        "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz",
    )))
    .expect("obs");
    let opts = raim_gnss::RangingOptions {
        systems: vec![raim_core::System::Gps, raim_core::System::Galileo],
        ..Default::default()
    };
    let prep = raim_gnss::prepare_epoch(&nav, &obs.epochs[0], &opts, None);
    let rx = prep.reference_m.expect("the replay's position");
    const C: f64 = 299_792_458.0;
    const OMEGA_E: f64 = 7.292_115_146_7e-5;
    let dist = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let rot = |p: [f64; 3], tau: f64| {
        let (s, c) = (OMEGA_E * tau).sin_cos();
        [c * p[0] + s * p[1], -s * p[0] + c * p[1], p[2]]
    };
    assert!(prep.sats.len() >= 15, "{} satellites", prep.sats.len());
    for ps in &prep.sats {
        let id = ps.obs.id;
        let sat = study
            .sats
            .iter()
            .find(|s| s.id == id)
            .unwrap_or_else(|| panic!("{id:?} not in the study"));
        let t_tx = prep.time_gps_s - ps.raw_pseudorange_m / C - ps.sat_clock_m / C;
        let p = sat.position_m(t_tx).expect("a valid ephemeris");
        let t0 = dist(p, rx) / C;
        let q = rot(p, dist(rot(p, t0), rx) / C);
        let d = dist(q, ps.obs.position_m);
        assert!(d < 1e-3, "{id:?}: {d} m from the replay's position");
    }
    // A short run over a region (2 h, 9 users over the North Sea) gives a result.
    let d = tmp_dir("nav");
    let base = Path::new(ROOT).join("../shared/data");
    let text = std::fs::read_to_string(&runf)
        .expect("run file")
        .replace("../../../shared/data", base.to_str().expect("utf8"))
        .replace("span_s = 86400.0", "span_s = 7200.0")
        .replace("lat_min_deg = 45.0", "lat_min_deg = 55.0")
        .replace("lon_max_deg = 25.0", "lon_max_deg = 5.0");
    let f = d.join("nav.toml");
    std::fs::write(&f, &text).expect("write");
    let (code, _, err) = raim(&[
        "availability",
        "--run",
        f.to_str().expect("utf8"),
        "--out",
        d.to_str().expect("utf8"),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_slice(
        &std::fs::read(d.join("availability_esbc_nav.summary.json")).expect("summary"),
    )
    .expect("json");
    assert_eq!(v["users"], 3 * 3);
    assert_eq!(v["user_epochs"], 9 * 24);
    let cov = v["coverage"][0]["coverage"].as_f64().expect("coverage");
    assert!((0.0..=1.0).contains(&cov), "{v}");
    // From 22:00 for 6 h: past the file's last records, gaps are reported.
    let late = text
        .replace("span_s = 7200.0", "span_s = 21600.0")
        .replace("start_s = 345600.0", "start_s = 424800.0");
    std::fs::write(&f, &late).expect("write");
    let study = run::load(&f).expect("late study");
    let (code, _, err) = raim(&[
        "availability",
        "--run",
        f.to_str().expect("utf8"),
        "--out",
        d.to_str().expect("utf8"),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_slice(
        &std::fs::read(d.join("availability_esbc_nav.summary.json")).expect("summary"),
    )
    .expect("json");
    let gaps = v["ephemeris_gaps_epochs"].as_object().expect("gaps");
    assert!(!gaps.is_empty());
    let mut listed = 0;
    for s in &study.sats {
        let name = format!("{}{:02}", s.id.system.letter(), s.id.prn);
        let window = if s.id.system == raim_core::System::Gps {
            7200.0
        } else {
            14400.0
        };
        let recs = &nav.ephemerides[&s.id];
        let n = study
            .epochs_gps_s
            .iter()
            .filter(|t| {
                !recs.iter().any(|k| {
                    let toe = (k.toc_gps_s / 604_800.0).floor() * 604_800.0 + k.toe_sow_s;
                    k.health == 0 && (*t - toe).abs() <= window
                })
            })
            .count();
        assert_eq!(
            gaps.get(&name).and_then(Value::as_u64).unwrap_or(0),
            n as u64,
            "{name}"
        );
        listed += usize::from(n > 0);
    }
    assert_eq!(listed, gaps.len());
    // At the last epoch, the satellites without a valid set are not in any
    // user's sky, and the others above the mask are.
    let k = study.epochs_gps_s.len() - 1;
    let t = study.epochs_gps_s[k];
    let sky = engine::sky_table(&study, k..k + 1);
    let mut seen_gap = false;
    for u in &study.users {
        let (x, r) = engine::user_frame(&study, u);
        let mut obs = Vec::new();
        engine::visible(&study, &sky, x, &r, &mut obs);
        for s in &study.sats {
            let used = obs.iter().any(|o| o.id == s.id);
            match s.position_m(t) {
                None => {
                    seen_gap = true;
                    assert!(!used, "{:?} used without an ephemeris", s.id);
                }
                Some(p) => {
                    let (_, el, _) = raim_nav::geometry::az_el(x, p);
                    assert_eq!(used, el >= 5f64.to_radians(), "{:?}", s.id);
                }
            }
        }
    }
    assert!(seen_gap);
    assert_eq!(
        v["satellite_epochs_without_ephemeris"].as_u64(),
        Some(gaps.values().filter_map(Value::as_u64).sum())
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// A horizontal-only service level (`custom-horizontal`, HAL 40 m, its
/// own budgets PHMI 1e-7, P_FA 3.99e-6 per epoch): at every user-epoch of
/// the small study it is available exactly when its HPL is within 40 m,
/// and it is available at user-epochs that a level with the tightest
/// vertical limits (VAL 10 m, EMT 10 m, same HAL) refuses; the preset
/// `H-ARAIM-NPA` has the HAL 555.6 m; vertical limits with a horizontal
/// level are refused. (That the budgets reach the core: raim-availability's
/// `horizontal_level_budgets_flow_into_the_core`.)
///
/// Verifies: TOOL-AVAIL-HARAIM
#[test]
fn horizontal_only_level_judges_the_hpl_alone() {
    on_engine_stack(horizontal_only_body);
}

fn horizontal_only_body() {
    let d = tmp_dir("haraim");
    let load = |tag: &str, service: &str| {
        let f = d.join(format!("{tag}.toml"));
        std::fs::write(&f, small_run().replace("level = \"LPV-200\"", service)).expect("write");
        run::load(&f)
    };
    let vert = load(
        "v",
        "level = \"custom\"\nval_m = 10.0\nhal_m = 40.0\nemt_max_m = 10.0\nsigma_acc_max_m = 1.87",
    )
    .expect("vertical");
    let hor = load(
        "h",
        "level = \"custom-horizontal\"\nhal_m = 40.0\nphmi = 1e-7\np_fa = 3.99e-6",
    )
    .expect("horizontal");
    assert_eq!(hor.criteria, raim_core::araim::Criteria::HorizontalOnly);
    let mut m = engine::new_engine();
    let mut only_h = 0;
    for u in &hor.users {
        let (x, r) = engine::user_frame(&hor, u);
        for k in 0..hor.epochs_gps_s.len() {
            let sky = engine::sky_table(&hor, k..k + 1);
            let mut obs = Vec::new();
            engine::visible(&hor, &sky, x, &r, &mut obs);
            let v = engine::evaluate(&vert, &mut m, &obs).expect("v");
            let h = engine::evaluate(&hor, &mut m, &obs).expect("h");
            assert_eq!(h.available, h.hpl_m <= 40.0, "HPL {}", h.hpl_m);
            assert!(!v.available || h.available);
            only_h += usize::from(h.available && !v.available);
        }
    }
    assert!(only_h > 0, "no user-epoch available only horizontally");
    let npa = load("n", "level = \"H-ARAIM-NPA\"\nphmi = 1e-7\np_fa = 3.99e-6").expect("npa");
    assert_eq!(npa.cfg.hal_m, 555.6);
    let e = load(
        "e",
        "level = \"H-ARAIM-terminal\"\nphmi = 1e-7\np_fa = 3.99e-6\nval_m = 35.0",
    )
    .expect_err("val");
    assert!(e.to_string().contains("judges the HAL alone"), "{e}");
    let e = load("e", "level = \"custom-horizontal\"").expect_err("hal");
    assert!(e.to_string().contains("needs `hal_m`"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}
