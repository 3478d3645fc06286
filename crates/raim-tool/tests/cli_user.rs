//! The `raim` binary as a user scripting it relies on it. One
//! test per point of the issue: the exit code, the message, and that no
//! Rust panic or backtrace reaches the user (every run has RUST_BACKTRACE=1
//! set, so a backtrace would show if an error or panic path printed one).
//! Exit codes: 0 every epoch answered, 1 error, 2 usage, 3 epochs refused.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

/// Run `raim` with `stdin`; checks that stderr carries no panic and no
/// backtrace whatever the outcome.
fn raim(args: &[&str], stdin: &str) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
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
    writer.join().unwrap();
    let r = Run {
        code: out.status.code().expect("exited, not killed"),
        stdout: String::from_utf8(out.stdout).expect("utf8"),
        stderr: String::from_utf8(out.stderr).expect("utf8"),
    };
    no_panic(&r.stderr);
    r
}

fn no_panic(stderr: &str) {
    for bad in ["panicked", "backtrace", "Backtrace", "RUST_BACKTRACE"] {
        assert!(!stderr.contains(bad), "{bad} in stderr:\n{stderr}");
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-cli-user");
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn example() -> Vec<String> {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../host-tests/vectors/snapshot_example.jsonl"
    );
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .map(String::from)
        .collect()
}

/// The first example epoch (linearised form, 8 satellites) with satellite
/// G02's elevation set to `el`.
fn with_elevation(el: &str) -> String {
    let l = example()[0].clone();
    assert!(l.contains("\"el_deg\": 30,"));
    l.replacen("\"el_deg\": 30,", &format!("\"el_deg\": {el},"), 1)
}

fn json_rows(stdout: &str) -> Vec<serde_json::Value> {
    stdout
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect()
}

// ---- Per-epoch errors: exit 3 at the end, the count on stderr, --keep-going.

#[test]
fn refused_epochs_give_exit_3_and_a_count_on_stderr() {
    let mut lines = example();
    lines.truncate(3);
    // A duplicate PRN in the second epoch.
    lines[1] = lines[1].replacen("\"prn\": 3,", "\"prn\": 2,", 1);
    let r = raim(&["snapshot", "--json"], &lines.join("\n"));
    assert_eq!(r.code, 3, "{}", r.stderr);
    let rows = json_rows(&r.stdout);
    assert_eq!(rows.len(), 3, "processing goes on after the bad epoch");
    assert_eq!(rows[0]["decision"], "ok");
    assert_eq!(rows[1]["error"], "DuplicateSatellite");
    assert_eq!(rows[1]["line"], 2);
    assert!(rows[2]["decision"].is_string());
    assert!(
        r.stderr
            .contains("raim: 1 of 3 epochs refused (first: line 2: duplicate satellite G02"),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("exit code 3 (--keep-going for 0)"));
    // --keep-going: same output, exit 0, the count still on stderr.
    let k = raim(&["snapshot", "--json", "--keep-going"], &lines.join("\n"));
    assert_eq!(k.code, 0);
    assert_eq!(k.stdout, r.stdout);
    assert!(k.stderr.contains("1 of 3 epochs refused"), "{}", k.stderr);
    // Text mode too.
    let t = raim(&["snapshot"], &lines.join("\n"));
    assert_eq!(t.code, 3);
    assert!(t
        .stdout
        .contains("ERROR       line 2: duplicate satellite G02"));
}

#[test]
fn too_few_satellites_is_refused_with_exit_3() {
    let l = example()[0].clone();
    let v: serde_json::Value = serde_json::from_str(&l).unwrap();
    let mut e = v.clone();
    e["sats"] = serde_json::Value::Array(v["sats"].as_array().unwrap()[..3].to_vec());
    let r = raim(&["snapshot", "--json"], &e.to_string());
    assert_eq!(r.code, 3);
    assert_eq!(json_rows(&r.stdout)[0]["error"], "TooFewSatellites");
    assert!(r.stderr.contains("1 of 1 epochs refused"), "{}", r.stderr);
}

#[test]
fn all_answered_exits_0_with_nothing_on_stderr() {
    let r = raim(&["snapshot", "--json"], &example().join("\n"));
    assert_eq!(r.code, 0);
    assert_eq!(json_rows(&r.stdout).len(), 8);
    assert_eq!(r.stderr, "");
}

// ---- Elevation range checks (the core's try_from_az_el).

#[test]
fn elevation_out_of_range_is_refused_by_the_core_check() {
    for el in ["200", "-30.5e1", "90.001"] {
        let r = raim(&["snapshot", "--json"], &with_elevation(el));
        assert_eq!(r.code, 3, "el {el}: {}", r.stderr);
        let row = &json_rows(&r.stdout)[0];
        assert_eq!(row["error"], "OutOfRange", "el {el}");
        let d = row["detail"].as_str().unwrap();
        assert!(
            d.contains("G02") && d.contains("el_rad") && d.contains("el_deg"),
            "{d}"
        );
        assert_eq!(row["time_s"], 0.0);
    }
    // Negative elevations are real (an aircraft above the horizon plane)
    // and the bounds are valid: these epochs are answered.
    for el in ["-30", "90", "-90"] {
        let r = raim(&["snapshot", "--json"], &with_elevation(el));
        assert_eq!(r.code, 0, "el {el}: {}", r.stderr);
        assert!(json_rows(&r.stdout)[0]["decision"].is_string(), "el {el}");
    }
}

/// `raim pci --az/--el` goes through the same core check: exit 1 (an
/// argument error of a one-shot computation, not a refused epoch).
#[test]
fn pci_elevation_out_of_range_is_an_error() {
    let r = raim(
        &[
            "pci",
            "--az",
            "0,90,180,270,45,135",
            "--el",
            "85,30,200,20,60,25",
            "--mc",
            "0",
        ],
        "",
    );
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains("--az/--el satellite 3: el_rad = ") && r.stderr.contains("(el_deg 200)"),
        "{}",
        r.stderr
    );
}

/// JSON cannot carry NaN or infinity: an azimuth beyond f64 is an
/// unreadable line (exit 3), while any finite azimuth is valid (it wraps;
/// the core's NotFinite check on az_rad is tested in raim-core).
#[test]
fn azimuth_beyond_f64_is_refused_and_finite_azimuths_wrap() {
    let l = example()[0].replacen("\"az_deg\": 45,", "\"az_deg\": 1e309,", 1);
    let r = raim(&["snapshot", "--json"], &l);
    assert_eq!(r.code, 3, "{}", r.stderr);
    let row = &json_rows(&r.stdout)[0];
    assert_eq!(row["error"], "Unreadable");
    assert!(
        row["detail"].as_str().unwrap().contains("out of range"),
        "{row}"
    );
    let a = raim(&["snapshot", "--json"], &example()[0]);
    let l = example()[0].replacen("\"az_deg\": 45,", "\"az_deg\": 405,", 1);
    let b = raim(&["snapshot", "--json"], &l);
    assert_eq!(b.code, 0);
    let (ra, rb) = (&json_rows(&a.stdout)[0], &json_rows(&b.stdout)[0]);
    const TOL: f64 = 1e-9; // dimensionless statistic, one rounding of sin/cos
    let (da, db) = (
        ra["final_statistic"].as_f64().unwrap(),
        rb["final_statistic"].as_f64().unwrap(),
    );
    assert!((da - db).abs() < TOL, "{da} {db}");
}

// ---- Unreadable input lines, truncated input, empty input.

#[test]
fn an_unreadable_line_is_refused_and_the_rest_processed() {
    let ex = example();
    let mut lines = vec![
        ex[0].clone(),
        "{\"time_s\": 1, \"sats\": [".into(),
        ex[1].clone(),
    ];
    // The last line is cut short, as in a truncated file.
    lines.push(ex[2][..40].to_string());
    let input = lines.join("\n");
    let r = raim(&["snapshot", "--json"], &input);
    assert_eq!(r.code, 3);
    let rows = json_rows(&r.stdout);
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[1]["error"], "Unreadable");
    assert_eq!(rows[1]["line"], 2);
    assert_eq!(rows[2]["decision"], "ok");
    assert_eq!(rows[3]["line"], 4);
    let d = rows[3]["detail"].as_str().unwrap();
    assert!(
        d.contains("the input ends inside this line: truncated?"),
        "{d}"
    );
    assert!(r.stderr.contains("2 of 4 epochs refused"), "{}", r.stderr);
}

#[test]
fn empty_stdin_prints_a_notice() {
    for input in ["", "\n\n# only a comment\n"] {
        let r = raim(&["snapshot"], input);
        assert_eq!(r.code, 0);
        assert_eq!(r.stdout, "");
        assert_eq!(
            r.stderr.trim(),
            "raim snapshot: no epochs in stdin (empty input; format: docs/FORMATS.md)"
        );
    }
}

// ---- A closed pipe.

#[test]
fn a_closed_pipe_ends_quietly() {
    // Enough output to fill the pipe: 8 epochs x 400, ~1.5 MB of JSON.
    let input = tmp("many.jsonl");
    let ex = example().join("\n");
    std::fs::write(&input, vec![ex.as_str(); 400].join("\n")).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(["snapshot", "--json", "--input", input.to_str().unwrap()])
        .env("RUST_BACKTRACE", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 100];
    stdout.read_exact(&mut first).unwrap();
    drop(stdout); // `| head -c 100`
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0), "{err}");
    assert_eq!(err, "", "quiet");
}

// ---- Help.

fn help(args: &[&str]) -> String {
    let r = raim(args, "");
    assert_eq!(r.code, 0, "{args:?}");
    r.stdout
}

#[test]
fn help_documents_exit_codes_options_and_defaults() {
    let top = help(&["--help"]);
    assert!(top.contains("Exit codes:"), "{top}");
    for code in [
        "0  every epoch answered",
        "1  error",
        "2  usage",
        "3  finished",
    ] {
        assert!(top.contains(code), "{code}");
    }
    let t = help(&["threshold", "--help"]);
    for opt in ["--pfa", "--dof", "--pmd", "--json"] {
        // next_line_help: the description follows on the next line.
        let line = t
            .lines()
            .position(|l| l.trim_start().starts_with(opt))
            .unwrap();
        let desc = t.lines().nth(line + 1).unwrap().trim();
        assert!(!desc.is_empty() && !desc.starts_with("--"), "{opt}: {t}");
    }
    let s = help(&["snapshot", "--help"]);
    assert!(s.contains("[default: 3.3333e-7]"), "{s}");
    assert!(!s.contains("0.00000033333"));
    assert!(s.contains("--keep-going"));
    let fa = help(&["campaign", "false-alarm", "--help"]);
    assert!(
        fa.contains("(comma separated)") && fa.contains("[default: 1e-3,1e-5]"),
        "{fa}"
    );
    let r = help(&["replay", "--help"]);
    assert!(
        r.contains("docs/REPLAY.md, section \"Scenario files\""),
        "{r}"
    );
    assert!(!r.contains("raim_gnss::faults"));
    assert!(
        r.contains("--nmea <MODE>") && !r.contains("--with-nmea"),
        "{r}"
    );
    // One layout: no subcommand switches to clap's long-help layout.
    for sub in [
        "snapshot",
        "threshold",
        "replay",
        "qemu",
        "pci",
        "arl",
        "campaign",
    ] {
        let h = help(&[sub, "--help"]);
        assert!(!h.contains("see a summary with '-h'"), "{sub}");
    }
}

#[test]
fn usage_errors_exit_2() {
    let r = raim(&["threshold", "--pfa", "x", "--dof", "4"], "");
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("invalid value 'x'"), "{}", r.stderr);
    let r = raim(&["replay", "--obs", "a", "--nav", "b", "--nmea"], "");
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("[possible values: only, with-text]"),
        "{}",
        r.stderr
    );
}

#[test]
fn a_fatal_error_is_one_line_exit_1() {
    let r = raim(&["snapshot", "--input", "/nonexistent/x.jsonl"], "");
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .starts_with("raim: error: opening /nonexistent/x.jsonl"),
        "{}",
        r.stderr
    );
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr);
    let r = raim(&["threshold", "--pfa", "2", "--dof", "4"], "");
    assert_eq!(r.code, 1);
    assert!(r.stderr.starts_with("raim: error:"), "{}", r.stderr);
}

// ---- Replay: fault specifications and windows that match nothing.

fn replay_0759(extra: &[&str]) -> Run {
    let obs = format!("{DATA}/07590920.05o");
    let nav = format!("{DATA}/07590920.05n");
    let mut a = vec![
        "replay",
        "--obs",
        &obs,
        "--nav",
        &nav,
        "--systems",
        "G",
        "--quiet",
    ];
    a.extend_from_slice(extra);
    raim(&a, "")
}

#[test]
fn a_fault_on_a_satellite_never_in_view_is_an_error() {
    let r = replay_0759(&["--fault", "step:G99:50@00:20:00"]);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .contains("fault 'step:G99:50@00:20:00' touches no epoch: none of its satellites"),
        "{}",
        r.stderr
    );
    // Part of the target in view: a warning with the count, and the run.
    let r = replay_0759(&["--fault", "step:G24+G99:50@00:20:00"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.contains(
            "warning: fault 'step:G24+G99:50@00:20:00': G99 never used while it is active; applied in 80 of 120 epochs"
        ),
        "{}",
        r.stderr
    );
}

#[test]
fn a_fault_outside_the_run_or_reversed_is_an_error() {
    let r = replay_0759(&["--fault", "step:G24:50@05:00:00"]);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains(
            "fault 'step:G24:50@05:00:00' touches no epoch: it is active from 05:00:00, the run covers 00:00:00..00:59:30"
        ),
        "{}",
        r.stderr
    );
    let r = replay_0759(&["--fault", "ramp:G24:0.1@00:30:00..00:20:00"]);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains(
            "fault 'ramp:G24:0.1@00:30:00..00:20:00' ends (00:20:00) before it starts (00:30:00)"
        ),
        "{}",
        r.stderr
    );
    // The same checks for a scenario file's faults, named by file and entry.
    let scen = tmp("late.toml");
    std::fs::write(
        &scen,
        "[[fault]]\nkind = \"step\"\ntarget = \"G24\"\nvalue = 50.0\nstart = \"03:00:00\"\n",
    )
    .unwrap();
    let r = replay_0759(&["--scenario", scen.to_str().unwrap()]);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .contains("late.toml [[fault]] #1' touches no epoch"),
        "{}",
        r.stderr
    );
}

#[test]
fn start_after_end_is_an_error_not_a_nan_summary() {
    let r = replay_0759(&["--start", "00:30:00", "--end", "00:20:00"]);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .contains("--start 00:30:00 (00:30:00) is after --end 00:20:00 (00:20:00)"),
        "{}",
        r.stderr
    );
    assert!(!r.stdout.contains("NaN"));
    let r = replay_0759(&["--start", "02:00:00"]);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .contains("no epochs between --start and --end: the file covers 00:00:00..00:59:30"),
        "{}",
        r.stderr
    );
}

#[test]
fn replay_refused_epochs_exit_3_unless_keep_going() {
    // The last epochs of 0759 above a 30 degree mask have too few satellites.
    let r = replay_0759(&["--mask-deg", "40", "--start", "00:50:00"]);
    assert_eq!(r.code, 3, "{}", r.stderr);
    assert!(
        r.stderr.contains("epochs refused (first: 00:"),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("too few satellites"), "{}", r.stderr);
    let k = replay_0759(&["--mask-deg", "40", "--start", "00:50:00", "--keep-going"]);
    assert_eq!(k.code, 0);
    assert_eq!(k.stdout, r.stdout);
}

// ---- Truncated and corrupt files.

fn cut(src: &Path, bytes: usize, name: &str) -> PathBuf {
    let p = tmp(name);
    let all = std::fs::read(src).unwrap();
    std::fs::write(&p, &all[..bytes]).unwrap();
    p
}

#[test]
fn a_truncated_gzip_says_so_and_where() {
    let obs = cut(
        &Path::new(DATA).join("ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz"),
        300_000,
        "cut.rnx.gz",
    );
    let nav = format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz");
    let r = raim(
        &[
            "replay",
            "--obs",
            obs.to_str().unwrap(),
            "--nav",
            &nav,
            "--quiet",
        ],
        "",
    );
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains("cut.rnx.gz: file is truncated"),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("300000 compressed bytes"), "{}", r.stderr);
    assert!(r.stderr.contains("(line "), "{}", r.stderr);
    assert!(!r.stderr.contains("i/o: input error"));
    // A corrupt one (bytes flipped in the middle of the deflate data).
    let mut bytes =
        std::fs::read(Path::new(DATA).join("ESBC00DNK_R_20201770000_01D_MN.rnx.gz")).unwrap();
    for b in &mut bytes[5000..5100] {
        *b ^= 0x5a;
    }
    let bad = tmp("bad_nav.rnx.gz");
    std::fs::write(&bad, bytes).unwrap();
    let obs = format!("{DATA}/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz");
    let r = raim(
        &[
            "replay",
            "--obs",
            &obs,
            "--nav",
            bad.to_str().unwrap(),
            "--quiet",
        ],
        "",
    );
    assert_eq!(r.code, 1);
    assert!(r.stderr.contains("bad_nav.rnx.gz: file is"), "{}", r.stderr);
}

#[test]
fn a_plain_file_cut_inside_an_epoch_is_warned_about() {
    let obs = cut(&Path::new(DATA).join("07590920.05o"), 40_000, "cut.05o");
    let nav = format!("{DATA}/07590920.05n");
    let r = raim(
        &[
            "replay",
            "--obs",
            obs.to_str().unwrap(),
            "--nav",
            &nav,
            "--systems",
            "G",
            "--quiet",
            "--keep-going",
        ],
        "",
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr
            .contains("cut.05o: the file ends inside its last epoch"),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("record lines present (file cut short?)"));
}

// ---- Install footprint: one quiet helper shared by both scripts.

#[test]
fn both_scripts_share_one_quiet_install_helper() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let read = |p: &str| std::fs::read_to_string(format!("{root}/{p}")).unwrap();
    let helper = read("scripts/install-deps.sh");
    assert!(helper.contains("apt-get install -y -qq --no-install-recommends"));
    assert!(
        helper.contains(">\"$log\" 2>&1"),
        "apt output goes to a log"
    );
    for (script, mode) in [("scripts/main-job.sh", "main"), ("scripts/test.sh", "test")] {
        let s = read(script);
        assert!(
            s.contains(&format!("bash scripts/install-deps.sh {mode}")),
            "{script}"
        );
        assert!(!s.contains("apt-get"), "{script} has its own apt call");
        assert!(!s.contains("with-nmea"), "{script}");
    }
    // A wrong mode is a usage error that installs nothing.
    let out = Command::new("bash")
        .arg(format!("{root}/scripts/install-deps.sh"))
        .arg("everything")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("usage:"));
}

// ---- docs/REPLAY.md "Scenario files": the example is a working file,
// equal to the flags the text gives for it.

#[test]
fn the_documented_scenario_example_equals_its_flags() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/REPLAY.md"))
        .unwrap();
    let section = &doc[doc.find("## Scenario files").unwrap()..];
    let body = section.split("```toml\n").nth(1).unwrap();
    let toml = &body[..body.find("```").unwrap()];
    let scen = tmp("doc_example.toml");
    std::fs::write(&scen, toml).unwrap();
    let obs = format!("{DATA}/ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz");
    let nav = format!("{DATA}/ESBC00DNK_R_20201770000_01D_MN.rnx.gz");
    let base = [
        "replay",
        "--obs",
        &obs,
        "--nav",
        &nav,
        "--ura-m",
        "0.3",
        "--iono-vertical-m",
        "0.5",
        "--noise-m",
        "0.2",
        "--start",
        "00:55:00",
        "--end",
        "01:05:00",
        "--json",
    ];
    let mut a = base.to_vec();
    a.extend(["--scenario", scen.to_str().unwrap()]);
    let mut b = base.to_vec();
    b.extend([
        "--fault",
        "step:G15+G28:50@01:00:00..02:00:00",
        "--fault",
        "ramp:G13:0.1@+3480",
        "--fault",
        "noise:all:t3:1.0",
        "--seed",
        "7",
    ]);
    let (ra, rb) = (raim(&a, ""), raim(&b, ""));
    assert_eq!(ra.code, 0, "{}", ra.stderr);
    assert_eq!(rb.code, 0, "{}", rb.stderr);
    assert_eq!(ra.stdout, rb.stdout);
    let last = ra.stdout.lines().last().unwrap();
    let s: serde_json::Value = serde_json::from_str(last).unwrap();
    assert_eq!(s["summary"]["epochs"], 21);
    assert!(s["summary"]["faulted_epochs"].as_u64().unwrap() >= 10);
}

// ---- `raim qemu`: the same exit codes through the firmware (QEMU, ~1 s).

#[test]
fn qemu_refused_epochs_exit_3_unless_keep_going() {
    let ex = example();
    let lines = [
        ex[0].clone(),
        ex[1].replacen("\"prn\": 3,", "\"prn\": 2,", 1), // refused by the firmware's core
        ex[2].replacen("\"el_deg\": 30,", "\"el_deg\": 200,", 1), // refused before it
        "not json".to_string(),
    ];
    let input = tmp("qemu.jsonl");
    std::fs::write(&input, lines.join("\n")).unwrap();
    let r = raim(&["qemu", "--input", input.to_str().unwrap(), "--json"], "");
    assert_eq!(r.code, 3, "{}", r.stderr);
    let rows = json_rows(&r.stdout);
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[0]["decision"], "ok");
    assert!(
        rows[1]["error"].as_str().unwrap().contains("duplicate"),
        "{}",
        rows[1]
    );
    assert_eq!(rows[2]["error"], "OutOfRange");
    assert_eq!(rows[3]["error"], "Unreadable");
    assert!(
        r.stderr.contains("raim: 3 of 4 epochs refused"),
        "{}",
        r.stderr
    );
    let k = raim(
        &[
            "qemu",
            "--input",
            input.to_str().unwrap(),
            "--json",
            "--keep-going",
        ],
        "",
    );
    assert_eq!(k.code, 0, "{}", k.stderr);
    let empty = tmp("empty.jsonl");
    std::fs::write(&empty, "").unwrap();
    let e = raim(&["qemu", "--input", empty.to_str().unwrap()], "");
    assert_eq!(e.code, 0);
    assert!(e.stderr.contains("raim qemu: no epochs in"), "{}", e.stderr);
}
