//! The `raim` host tool as a GNSS engineer uses it beside RTKLIB and gpsd:
//! no option silently ignored (exit 2, both options named), negative
//! numbers as values, unbounded protection levels as `inf`/`null`, one
//! JSON vocabulary checked against the JSON Schemas in docs/schema,
//! messages that name the file and what is wrong with it, grouped help
//! with examples, completions and a man page, run files, and the standard
//! solution files (.pos read by RTKLIB's pos2kml, KML/GPX well-formed).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

fn raim_in(dir: &Path, args: &[&str], stdin: &str) -> Run {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "1")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn raim");
    let mut input = child.stdin.take().expect("stdin");
    let text = stdin.to_string();
    let writer = std::thread::spawn(move || {
        let _ = input.write_all(text.as_bytes());
    });
    let out = child.wait_with_output().expect("wait");
    writer.join().expect("stdin writer");
    let r = Run {
        code: out.status.code().expect("exited, not killed"),
        stdout: String::from_utf8(out.stdout).expect("utf8"),
        stderr: String::from_utf8(out.stderr).expect("utf8"),
    };
    for bad in ["panicked", "backtrace", "Backtrace"] {
        assert!(!r.stderr.contains(bad), "{bad} in stderr:\n{}", r.stderr);
    }
    r
}

fn raim(args: &[&str], stdin: &str) -> Run {
    raim_in(Path::new(ROOT), args, stdin)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-cli-tool");
    std::fs::create_dir_all(&d).expect("temp dir");
    d.join(name)
}

fn obs() -> String {
    format!("{DATA}/07590920.05o")
}
fn nav() -> String {
    format!("{DATA}/07590920.05n")
}

/// A short 0759 GPS-only replay (the first hour: 120 epochs) with `extra`.
fn replay(extra: &[&str]) -> Run {
    let (o, n) = (obs(), nav());
    let mut a = vec![
        "replay",
        "--obs",
        &o,
        "--nav",
        &n,
        "--systems",
        "G",
        "--end",
        "00:59:30",
    ];
    a.extend_from_slice(extra);
    raim(&a, "")
}

fn example_lines() -> Vec<String> {
    std::fs::read_to_string(format!("{ROOT}/host-tests/vectors/snapshot_example.jsonl"))
        .expect("example")
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(String::from)
        .collect()
}

fn json_rows(stdout: &str) -> Vec<serde_json::Value> {
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect()
}

// ---- Options that cannot be ignored.

/// Each combination that used to do nothing is a usage error naming both
/// options; a plot refused is not written.
#[test]
fn ignored_combinations_are_refused_naming_both_options() {
    let png = tmp("never.png");
    let png = png.to_str().expect("utf8 path");
    let cases: &[(&[&str], [&str; 2])] = &[
        (&["--nmea", "only", "--json"], ["--nmea", "--json"]),
        (&["--nmea", "only", "--quiet"], ["--nmea", "--quiet"]),
        (&["--nmea", "with-text", "--json"], ["--nmea", "--json"]),
        (
            &["--pf", "ekf", "--target", "qemu"],
            ["--pf", "--target qemu"],
        ),
        (&["--esq", "--target", "qemu"], ["--esq", "--target qemu"]),
        (&["--pf", "ekf", "--nmea", "only"], ["--nmea", "--pf"]),
        (&["--esq", "--pf", "gapf"], ["--esq", "--pf"]),
        (&["--araim", "--pf", "ekf"], ["--araim", "--pf"]),
        (&["--pf-plot", png], ["--pf-plot", "--pf"]),
        (&["--araim-plot", png], ["--araim-plot", "--araim"]),
        (&["--esq-plot", png], ["--esq-plot", "--esq"]),
        (&["--araim", "--plot", png], ["--plot", "--araim"]),
        (&["--araim", "--pos", png], ["--pos", "--araim"]),
        (&["--particles", "300"], ["--particles", "--pf"]),
        (&["--mcusum-k", "1.5"], ["--mcusum-k", "--mcusum"]),
        (
            &["--group-budget", "10"],
            ["--group-budget", "--multifault-t-max"],
        ),
        (&["--rule", "mle", "--kappa", "10"], ["--kappa", "--rule"]),
        (&["--araim", "--particles", "50"], ["--particles", "--pf"]),
    ];
    for (extra, names) in cases {
        let r = replay(extra);
        assert_eq!(r.code, 2, "{extra:?}: {}", r.stderr);
        for n in names {
            assert!(
                r.stderr.contains(n),
                "{extra:?}: {n} not named in {}",
                r.stderr
            );
        }
        assert!(r.stdout.is_empty(), "{extra:?}: {}", r.stdout);
    }
    assert!(!Path::new(png).exists(), "a refused plot was written");
    // The snapshot subcommand shares the monitor options and their checks.
    let r = raim(&["snapshot", "--mcusum-share", "0.3"], "");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("--mcusum-share") && r.stderr.contains("--mcusum"));
}

/// Negative values parse without `=`; a value the model refuses is a
/// configuration error naming it, not clap's "unexpected argument".
#[test]
fn negative_numbers_are_values() {
    let r = replay(&["--mask-deg", "-5", "--quiet"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let r = replay(&["--fault", "step:G24:-50@00:20:00", "--json"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let rows = json_rows(&r.stdout);
    assert_eq!(rows[40]["faulted"], serde_json::json!([["G24", -50.0]]));
    let r = replay(&["--ura-m", "-1", "--quiet"]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(!r.stderr.contains("unexpected argument"), "{}", r.stderr);
    assert!(r.stderr.contains("ura_m = -1"), "{}", r.stderr);
}

/// A satellite whose removal leaves a rank-deficient geometry (four on one
/// elevation cone and one at the zenith, plus a sixth) has S_ii = 0: the
/// PLs are unbounded, `inf` in the text line and `null` in JSON (never
/// 1.8e308).
///
/// Verifies: SAFE-T8
#[test]
fn unbounded_protection_levels_print_inf_and_null() {
    let sat = |prn: u32, az: f64, el: f64| {
        serde_json::json!({"sys": "G", "prn": prn, "az_deg": az, "el_deg": el,
                           "residual_m": 0.1, "sigma_m": 1.0})
    };
    let epoch = serde_json::json!({"time_s": 0.0, "sats": [
        sat(1, 0.0, 30.0), sat(2, 90.0, 30.0), sat(3, 180.0, 30.0),
        sat(4, 270.0, 30.0), sat(5, 0.0, 90.0), sat(6, 45.0, 30.0)]})
    .to_string();
    let r = raim(&["snapshot", "--json"], &epoch);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let row = &json_rows(&r.stdout)[0];
    assert!(row["hpl_m"].is_null() && row["vpl_m"].is_null(), "{row}");
    assert!(!r.stdout.contains("e308"), "{}", r.stdout);
    let r = raim(&["snapshot"], &epoch);
    assert!(r.stdout.contains("HPL=     inf"), "{}", r.stdout);
    assert!(r.stdout.contains("VPL=     inf"), "{}", r.stdout);
}

// ---- One vocabulary.

const SHARED_KEYS: [&str; 8] = [
    "initial_statistic",
    "initial_threshold",
    "initial_dof",
    "final_statistic",
    "final_threshold",
    "final_dof",
    "candidate",
    "excluded",
];

/// The same keys in `snapshot --json` and `replay --json`, with the same
/// meaning: all in view, then the solution in force, and the satellites
/// excluded as a list of names. The example's epoch 5 (a 50 m step on G02
/// and 30 m on G06): the rule's first candidate is G03, the pair search
/// excludes G02 and G06, and the final test passes.
#[test]
fn snapshot_and_replay_share_one_vocabulary() {
    let r = raim(&["snapshot", "--json"], &example_lines().join("\n"));
    let snap = json_rows(&r.stdout);
    let e5 = &snap[5];
    assert_eq!(e5["decision"], "excluded", "{e5}");
    assert_eq!(e5["excluded"], serde_json::json!(["G02", "G06"]), "{e5}");
    assert_eq!(e5["candidate"], "G03", "{e5}");
    assert!(e5["final_statistic"].as_f64() < e5["final_threshold"].as_f64());
    assert!(e5["initial_statistic"].as_f64() > e5["initial_threshold"].as_f64());
    assert!(e5.get("identified").is_none() && e5.get("statistic").is_none());
    let r = replay(&["--fault", "step:G24:50@00:20:00", "--json"]);
    let rows = json_rows(&r.stdout);
    let excluded = rows
        .iter()
        .find(|r| r["decision"] == "excluded")
        .expect("an exclusion");
    assert_eq!(excluded["excluded"], serde_json::json!(["G24"]));
    for row in [&snap[3], excluded] {
        for k in SHARED_KEYS {
            assert!(row.get(k).is_some(), "{k} missing in {row}");
        }
        assert!(row["final_statistic"].as_f64() < row["final_threshold"].as_f64());
        assert!(row["initial_statistic"].as_f64() > row["initial_threshold"].as_f64());
    }
}

fn schema(name: &str) -> jsonschema::Validator {
    let text = std::fs::read_to_string(format!("{ROOT}/docs/schema/{name}.schema.json"))
        .expect("schema file");
    let v: serde_json::Value = serde_json::from_str(&text).expect("schema json");
    jsonschema::validator_for(&v).expect("valid schema")
}

fn assert_valid(v: &jsonschema::Validator, doc: &serde_json::Value, what: &str) {
    let errors: Vec<String> = v.iter_errors(doc).map(|e| e.to_string()).collect();
    assert!(errors.is_empty(), "{what}: {errors:?}\n{doc}");
}

/// The examples and the outputs against docs/schema: the input epochs,
/// `snapshot --json` (results, MCUSUM, a refused epoch) and
/// `replay --json` (every epoch of a faulted hour). The schemas forbid
/// undeclared keys, so a new key must be added there (and in FORMATS.md,
/// next test) to pass.
#[test]
fn outputs_match_the_json_schemas() {
    let epoch = schema("epoch");
    let lines = example_lines();
    for (k, l) in lines.iter().enumerate() {
        let v: serde_json::Value = serde_json::from_str(l).expect("json");
        assert_valid(&epoch, &v, &format!("example epoch {k}"));
    }
    let result = schema("result");
    let mut input = lines.clone();
    input.push(lines[1].replacen("\"prn\": 3,", "\"prn\": 2,", 1));
    for args in [
        &["snapshot", "--json"][..],
        &["snapshot", "--json", "--mcusum"],
    ] {
        let r = raim(args, &input.join("\n"));
        let rows = json_rows(&r.stdout);
        assert_eq!(rows.len(), input.len());
        assert!(rows.last().is_some_and(|r| r.get("error").is_some()));
        for (k, row) in rows.iter().enumerate() {
            assert_valid(&result, row, &format!("{args:?} line {k}"));
        }
    }
    let rec = schema("replay-epoch");
    let r = replay(&["--fault", "step:G24:50@00:20:00", "--json"]);
    let rows = json_rows(&r.stdout);
    let (summary, epochs) = rows.split_last().expect("rows");
    assert!(summary.get("summary").is_some());
    assert_eq!(epochs.len(), 120);
    for (k, row) in epochs.iter().enumerate() {
        assert_valid(&rec, row, &format!("replay epoch {k}"));
    }
}

/// Every key of the schemas is documented in docs/FORMATS.md (as `key`),
/// and FORMATS.md says what `time_s` is and where the NMEA date comes from.
#[test]
fn formats_md_documents_every_key() {
    let doc = std::fs::read_to_string(format!("{ROOT}/docs/FORMATS.md")).expect("FORMATS.md");
    fn keys(v: &serde_json::Value, out: &mut Vec<String>) {
        match v {
            serde_json::Value::Object(m) => {
                if let Some(serde_json::Value::Object(p)) = m.get("properties") {
                    out.extend(p.keys().cloned());
                }
                for x in m.values() {
                    keys(x, out);
                }
            }
            serde_json::Value::Array(a) => a.iter().for_each(|x| keys(x, out)),
            _ => {}
        }
    }
    for name in ["epoch", "result", "replay-epoch"] {
        let text = std::fs::read_to_string(format!("{ROOT}/docs/schema/{name}.schema.json"))
            .expect("schema");
        let v: serde_json::Value = serde_json::from_str(&text).expect("json");
        let mut ks = Vec::new();
        keys(&v, &mut ks);
        for k in ks {
            assert!(
                doc.contains(&format!("`{k}`")),
                "{name}: `{k}` not in FORMATS.md"
            );
        }
    }
    assert!(doc.contains("Unix time"), "time_s's origin");
    assert!(doc.contains("NMEA date"), "the NMEA date's calendar");
    // The text columns of `snapshot` and `replay`.
    for col in [
        "`D2=`",
        "`T2=`",
        "`dof=`",
        "`errH=`/`errV=`",
        "`HPL=`/`VPL=`",
    ] {
        assert!(doc.contains(col), "text column {col} not in FORMATS.md");
    }
}

/// `time_s` is Unix time for the NMEA date (FORMATS.md, "Time"): an epoch
/// at `time_s: 100` is dated 1 January 1970 by the firmware's RMC, one at
/// Unix 1112400000 (2005-04-02 00:00:00 UTC) 2 April 2005.
#[test]
fn qemu_nmea_date_is_the_unix_date_of_time_s() {
    let first = example_lines().remove(0);
    for (t, date) in [("100", "010170"), ("1112400000", "020405")] {
        let line = first.replacen("\"time_s\": 0", &format!("\"time_s\": {t}"), 1);
        let f = tmp(&format!("date-{t}.jsonl"));
        std::fs::write(&f, &line).expect("write");
        let r = raim(
            &["qemu", "--input", f.to_str().expect("utf8"), "--json"],
            "",
        );
        assert_eq!(r.code, 0, "{}", r.stderr);
        let row = &json_rows(&r.stdout)[0];
        let nmea: Vec<&str> = row["nmea"]
            .as_array()
            .expect("nmea")
            .iter()
            .filter_map(|s| s.as_str())
            .collect();
        let rmc = nmea
            .iter()
            .find(|s| s.get(3..6) == Some("RMC"))
            .expect("RMC");
        assert_eq!(rmc.split(',').nth(9), Some(date), "{rmc}");
    }
}

/// `raim araim` prints the FDE outcome and the unavailability in words,
/// never a Rust Debug form (`NoFault`, `Limits`, `{ axis: 2 }`).
#[test]
fn araim_prints_words_not_debug_text() {
    for json in [false, true] {
        let mut a = vec![
            "araim",
            "--input",
            "host-tests/vectors/add_v3_appendix_d.json",
        ];
        if json {
            a.push("--json");
        }
        let r = raim(&a, "");
        assert_eq!(r.code, 0, "{}", r.stderr);
        assert!(r.stdout.contains("no_fault"), "{}", r.stdout);
        for debug in ["NoFault", "Some(", " { ", "Limits"] {
            assert!(!r.stdout.contains(debug), "{debug}: {}", r.stdout);
        }
    }
}

// ---- Messages for people.

/// Each bad input names the file (or folder) and says what is wrong.
#[test]
fn bad_inputs_are_named_and_explained() {
    let empty = tmp("empty.nav");
    std::fs::write(&empty, "").expect("write");
    let readme = format!("{ROOT}/README.md");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let (o, n) = (obs(), nav());
    let e = empty.to_str().expect("utf8");
    let d = dir.to_str().expect("utf8");
    let cases: &[(&[&str], &[&str])] = &[
        (&["--obs", &o, "--nav", e], &[e, "is empty", "navigation"]),
        (
            &["--obs", d, "--nav", &n],
            &[d, "is a directory", "observation"],
        ),
        (
            &["--obs", &readme, "--nav", &n],
            &[
                "README.md",
                "is not a RINEX observation file",
                "RINEX VERSION / TYPE",
            ],
        ),
        (&["--obs", &n, "--nav", &n], &["07590920.05n", "type 'N'"]),
        (
            &["--obs", &o, "--nav", &o],
            &["07590920.05o", "observation file"],
        ),
        (
            &["--obs", "/no/such.05o", "--nav", &n],
            &["/no/such.05o", "no such file"],
        ),
        (
            &["--obs", &o, "--nav", &n, "--plot", "/no/such/folder/x.png"],
            &["--plot", "/no/such/folder", "no such folder"],
        ),
        (
            &["--obs", &o, "--nav", &n, "--kml", "/no/such/folder/x.kml"],
            &["--kml", "no such folder"],
        ),
    ];
    for (args, want) in cases {
        let mut a = vec!["replay", "--systems", "G", "--quiet"];
        a.extend_from_slice(args);
        let r = raim(&a, "");
        assert_eq!(r.code, 1, "{args:?}: {}", r.stderr);
        assert!(r.stderr.starts_with("raim: error:"), "{}", r.stderr);
        assert_eq!(r.stderr.lines().count(), 1, "one line: {}", r.stderr);
        for w in *want {
            assert!(r.stderr.contains(w), "{args:?}: {w:?} not in {}", r.stderr);
        }
        for leak in ["Os {", "ImageError", "IoError", "code: 2"] {
            assert!(
                !r.stderr.contains(leak),
                "{args:?}: Debug text {}",
                r.stderr
            );
        }
    }
}

// ---- Help that fits.

fn help(args: &[&str]) -> String {
    let mut a = args.to_vec();
    a.push("--help");
    let r = raim(&a, "");
    assert_eq!(r.code, 0, "{}", r.stderr);
    r.stdout
}

/// Replay options come under the six headings; every subcommand's help
/// ends with examples; no internal label (seed numbers, issue numbers,
/// SPEC sections) is left; the text columns are explained.
#[test]
fn help_is_grouped_with_examples_and_plain_names() {
    let h = help(&["replay"]);
    for heading in [
        "Sources:",
        "Models:",
        "Faults:",
        "Monitors: snapshot RAIM",
        "Monitors: ARAIM",
        "Monitors: particle filter",
        "Outputs:",
        "Plots:",
    ] {
        assert!(h.contains(heading), "{heading} missing");
    }
    for col in ["D2 =", "T2 =", "dof =", "errH/errV", "HPL/VPL"] {
        assert!(h.contains(col), "column {col} not explained");
    }
    for sub in [
        "snapshot",
        "araim",
        "availability",
        "campaign",
        "pci",
        "arl",
        "pf-table",
        "replay",
        "qemu",
        "threshold",
        "completions",
        "man",
    ] {
        let h = help(&[sub]);
        assert!(h.contains("Examples:\n  raim "), "{sub}: no examples");
        for label in ["seed 00", "Seed 00", "issue 1", "issue 2", "SPEC §"] {
            assert!(!h.contains(label), "{sub}: internal label {label:?}");
        }
    }
}

/// The examples in the help run (the ones that need no other file).
#[test]
fn help_examples_run() {
    for a in [
        &["threshold", "--pfa", "3.3333e-7", "--dof", "4"][..],
        &[
            "threshold",
            "--pfa",
            "1e-5",
            "--dof",
            "3",
            "--pmd",
            "1e-3",
            "--json",
        ],
        &[
            "snapshot",
            "--input",
            "host-tests/vectors/snapshot_example.jsonl",
        ],
        &[
            "araim",
            "--input",
            "host-tests/vectors/add_v3_appendix_d.json",
        ],
        &["arl", "--dim", "2", "--k", "1", "--h", "8.5"],
    ] {
        let r = raim(a, "");
        assert_eq!(r.code, 0, "{a:?}: {}", r.stderr);
    }
}

/// Completions and the man page come from the same definitions.
#[test]
fn completions_and_man_page() {
    for shell in ["bash", "zsh", "fish"] {
        let r = raim(&["completions", shell], "");
        assert_eq!(r.code, 0, "{}", r.stderr);
        for w in ["replay", "mask-deg", "araim-plot"] {
            assert!(r.stdout.contains(w), "{shell}: {w}");
        }
    }
    let r = raim(&["man"], "");
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout.starts_with(".ie") || r.stdout.contains(".TH raim"),
        "roff"
    );
    for w in ["RAIM REPLAY", "mask\\-deg", "Examples:"] {
        assert!(r.stdout.contains(w), "man: {w}");
    }
}

// ---- Run files.

/// A run file gives the same run as its options on the command line;
/// options after it override it; a key in the wrong section or unknown is
/// an error naming the file and the key.
#[test]
fn run_files_reproduce_and_are_overridden() {
    let run = tmp("run.toml");
    std::fs::write(
        &run,
        format!(
            "[sources]\nobs = \"{}\"\nnav = \"{}\"\nsystems = \"G\"\nend = \"00:59:30\"\n\
             [models]\nmask_deg = -5.0\nura-m = 0.3\n[faults]\nfault = [\"step:G24:50@00:20:00\"]\n\
             [outputs]\njson = true\n",
            obs(),
            nav()
        ),
    )
    .expect("write");
    let r = run.to_str().expect("utf8");
    let from_file = raim(&["replay", "--config", r], "");
    assert_eq!(from_file.code, 0, "{}", from_file.stderr);
    let flags = replay(&[
        "--mask-deg",
        "-5",
        "--ura-m",
        "0.3",
        "--fault",
        "step:G24:50@00:20:00",
        "--json",
    ]);
    assert_eq!(from_file.stdout, flags.stdout);
    // The command line overrides: a shorter window.
    let shorter = raim(&["replay", "--config", r, "--end", "00:29:30"], "");
    assert_eq!(shorter.code, 0, "{}", shorter.stderr);
    assert_eq!(json_rows(&shorter.stdout).len(), 60 + 1);
    for (body, want) in [
        ("[models]\nfault = \"x\"\n", "belongs in [faults]"),
        (
            "[sources]\nobservations = \"x\"\n",
            "not an option of raim replay",
        ),
        ("obs = \"x\"\n", "must be a section"),
        ("[outputs]\njson = 1\n", "true or false"),
        ("[sources\n", "not valid TOML"),
    ] {
        let bad = tmp("bad.toml");
        std::fs::write(&bad, body).expect("write");
        let b = bad.to_str().expect("utf8");
        let r = raim(&["replay", "--config", b], "");
        assert_eq!(r.code, 1, "{body}: {}", r.stderr);
        assert!(
            r.stderr.contains(b) && r.stderr.contains(want),
            "{body}: {}",
            r.stderr
        );
    }
}

/// The run files in docs/runs parse into options `raim replay` accepts;
/// the availability run files (`availability_*.toml`, docs/AVAILABILITY.md)
/// are read by `raim availability`, run here on the first of 288 time
/// shards (one epoch of the grid) so that the whole file is checked.
#[test]
fn documented_run_files_are_valid() {
    let dir = format!("{ROOT}/docs/runs");
    let (mut n, mut n_availability) = (0, 0);
    for e in std::fs::read_dir(&dir).expect("docs/runs") {
        let p = e.expect("entry").path();
        if p.extension().is_some_and(|x| x == "toml") {
            let s = p.to_str().expect("utf8");
            let availability = p
                .file_name()
                .and_then(|f| f.to_str())
                .is_some_and(|f| f.starts_with("availability_"));
            if availability {
                let out = tmp("availability-run-file");
                std::fs::create_dir_all(&out).expect("temp dir");
                let o = out.to_str().expect("utf8");
                let r = raim(
                    &["availability", "--run", s, "--shard", "1/288", "--out", o],
                    "",
                );
                assert_eq!(r.code, 0, "{s}: {}", r.stderr);
                n_availability += 1;
                continue;
            }
            // --help after the run file: parsed and checked, nothing run.
            let r = raim(&["replay", "--config", s, "--help"], "");
            assert_eq!(r.code, 0, "{s}: {}", r.stderr);
            n += 1;
        }
    }
    assert!(n >= 2, "{n} run files");
    assert!(
        n_availability >= 1,
        "{n_availability} availability run files"
    );
}

// ---- Standard outputs.

fn tool(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join(name))
            .find(|p| p.is_file())
    })
}

/// The .pos has RTKLIB's header and one line per epoch with a position,
/// the integrity columns after RTKLIB's 15; RTKLIB's pos2kml reads it; the
/// KML and GPX are well-formed XML with one point per epoch, and the
/// excluded satellite is named in the placemarks of the faulted epochs; the
/// NMEA file equals the `--nmea only` stream.
#[test]
fn solution_files_are_standard() {
    let (pos, csv, kml, gpx, nmea) = (
        tmp("run.pos"),
        tmp("run.csv"),
        tmp("run.kml"),
        tmp("run.gpx"),
        tmp("run.nmea"),
    );
    let s = |p: &PathBuf| p.to_str().expect("utf8").to_string();
    let r = replay(&[
        "--fault",
        "step:G24:50@00:20:00",
        "--quiet",
        "--pos",
        &s(&pos),
        "--csv",
        &s(&csv),
        "--kml",
        &s(&kml),
        "--gpx",
        &s(&gpx),
        "--nmea-file",
        &s(&nmea),
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let pos_text = std::fs::read_to_string(&pos).expect("pos");
    assert!(pos_text
        .contains("%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns"));
    let lines: Vec<&str> = pos_text.lines().filter(|l| !l.starts_with('%')).collect();
    assert_eq!(lines.len(), 120);
    assert!(
        lines[0].starts_with("2005/04/02 00:00:00.000"),
        "{}",
        lines[0]
    );
    let excluded: Vec<&&str> = lines.iter().filter(|l| l.contains(" excluded ")).collect();
    assert!(!excluded.is_empty());
    for l in &excluded {
        let f: Vec<&str> = l.split_whitespace().collect();
        // date, time, 13 RTKLIB values, then decision, HPL, VPL, excluded.
        assert_eq!(f.len(), 19, "{l}");
        assert_eq!((f[15], f[18]), ("excluded", "G24"), "{l}");
    }
    let csv_text = std::fs::read_to_string(&csv).expect("csv");
    let header = csv_text.lines().next().expect("header");
    assert!(header.starts_with("time_gps_s,gpst,decision,"), "{header}");
    let cols = header.split(',').count();
    assert_eq!(csv_text.lines().count(), 121);
    assert!(csv_text.lines().all(|l| l.split(',').count() == cols));
    let kml_text = std::fs::read_to_string(&kml).expect("kml");
    assert_eq!(kml_text.matches("<Point>").count(), 120);
    // The `kml` crate's parser (the OGC KML 2.2 element model) reads it,
    // and finds the 120 points.
    let parsed: kml::Kml = kml_text.parse().expect("the kml crate parses the KML");
    assert_eq!(count_points(&parsed), 120);
    assert!(kml_text.contains("excluded: G24"));
    assert!(kml_text.contains("<styleUrl>#excluded</styleUrl>"));
    let gpx_text = std::fs::read_to_string(&gpx).expect("gpx");
    assert_eq!(gpx_text.matches("<trkpt ").count(), 120);
    let stream = replay(&["--fault", "step:G24:50@00:20:00", "--nmea", "only"]);
    assert_eq!(std::fs::read_to_string(&nmea).expect("nmea"), stream.stdout);

    // Both tools are required (scripts/install-deps.sh installs them), as
    // gpsd is for the NMEA tests: a missing tool fails, never skips.
    match tool("xmllint") {
        Some(x) => {
            let out = Command::new(x)
                .args(["--noout", &s(&kml), &s(&gpx)])
                .output()
                .expect("xmllint");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        None => panic!(
            "xmllint not installed (apt package libxml2-utils; scripts/install-deps.sh test)"
        ),
    }
    match tool("pos2kml") {
        Some(p) => {
            let out_kml = tmp("pos2kml.kml");
            let out = Command::new(p)
                .args(["-o", &s(&out_kml), &s(&pos)])
                .output()
                .expect("pos2kml");
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let k = std::fs::read_to_string(&out_kml).expect("pos2kml output");
            // RTKLIB writes one placemark per solution (plus the track).
            assert!(
                k.matches("<Placemark>").count() >= 120,
                "pos2kml read too few"
            );
        }
        None => {
            panic!("pos2kml not installed (Debian package rtklib; scripts/install-deps.sh test)")
        }
    }
}

/// The `Point` geometries anywhere in a parsed KML tree.
fn count_points(k: &kml::Kml) -> usize {
    match k {
        kml::Kml::KmlDocument(d) => d.elements.iter().map(count_points).sum(),
        kml::Kml::Document { elements, .. } => elements.iter().map(count_points).sum(),
        kml::Kml::Folder(f) => f.elements.iter().map(count_points).sum(),
        kml::Kml::Placemark(p) => p.geometry.as_ref().map_or(0, |g| match g {
            kml::types::Geometry::Point(_) => 1,
            _ => 0,
        }),
        kml::Kml::Point(_) => 1,
        _ => 0,
    }
}
