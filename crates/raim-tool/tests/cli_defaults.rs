//! Every subcommand of `raim --help` runs with its defaults (issue 37,
//! "defaults that are refused": `raim replay --pf pf` with the then
//! default `--particles 100` was refused as above the detectability
//! ceiling). Each run gives only what the subcommand requires (an input,
//! a mode it cannot guess) and, where the default run takes minutes, only
//! an option that limits its length (epochs, trials, Monte Carlo draws);
//! every other option keeps its default. Each must exit 0 with output.
//!
//! The inputs: the 0759 RINEX pair and the LEA-4T UBX log of
//! ../shared/data for `replay` (each monitor `replay` selects, with its
//! own defaults); the committed epoch vectors for `snapshot` and `araim`
//! (those subcommands read epochs in JSON, not receiver data); the unit
//! configuration of docs/unit.toml and the firmware image for `provision`.
//!
//! Not run here: `qemu` and `replay --target qemu` (they need QEMU; their
//! defaults are run by cli_receivers_qemu.rs and host-tests' qemu_*
//! tests) and `link` (it needs a unit on a serial port; cli_link.rs runs
//! it against QEMU through a pty). GMSD7 (RTCM 3) is not a default run:
//! with the default `--systems GEC` it holds at most 4 GPS satellites
//! above the default 10 degree mask, so every epoch is refused for want of
//! satellites (exit 3) with a configuration the tool accepts; it needs
//! `--systems GR` (docs/RECEIVERS.md).

use std::io::Write;
use std::process::{Command, Stdio};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
const REPO: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// `raim args` with `stdin` (none: empty): exit code, stdout, stderr.
fn raim(args: &[&str], stdin: Option<&[u8]>) -> (Option<i32>, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn raim");
    let mut pipe = child.stdin.take().expect("stdin");
    pipe.write_all(stdin.unwrap_or_default()).expect("stdin");
    drop(pipe);
    let out = child.wait_with_output().expect("raim");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Runs `args`, asserting exit 0 and a non-empty stdout.
fn accepted(args: &[&str]) {
    let (code, out, err) = raim(args, None);
    assert_eq!(code, Some(0), "raim {}: {err}", args.join(" "));
    assert!(
        !out.trim().is_empty(),
        "raim {}: no output; {err}",
        args.join(" ")
    );
}

/// The subcommands `raim --help` lists, so that a new one fails this
/// file until it is run (or excluded with a reason) here.
///
/// Verifies: TOOL-DEFAULTS
#[test]
fn every_subcommand_is_covered() {
    let (code, out, _) = raim(&["--help"], None);
    assert_eq!(code, Some(0));
    let listed: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.is_empty())
        .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
        .map(str::trim)
        .collect();
    let covered = [
        "snapshot",
        "araim",
        "campaign",
        "pci",
        "arl",
        "pf-table",
        "replay",
        "threshold",
        "completions",
        "man",
        "provision",
        "availability",
        "rtcm-fault",
        // Excluded, see the module docs.
        "qemu",
        "link",
        "help",
    ];
    assert!(!listed.is_empty(), "{out}");
    for c in &listed {
        assert!(
            covered.contains(c),
            "`raim {c}` is not run with its defaults"
        );
    }
}

/// `raim replay` on the 0759 RINEX pair (GPS, 30 s, 2005) with nothing
/// but the files: the snapshot monitor and each other monitor it selects
/// (`--pf` ekf, pf and gapf with the default particle count, `--araim`,
/// `--esq`, `--pca`, `--mcusum`, `--model-check` beside the snapshot
/// monitor and ARAIM) with their defaults.
///
/// Verifies: TOOL-DEFAULTS
#[test]
fn replay_defaults_on_the_0759_pair() {
    let obs = format!("{DATA}/07590920.05o");
    let nav = format!("{DATA}/07590920.05n");
    for monitor in [
        &[][..],
        &["--pf", "ekf"],
        &["--pf", "pf"],
        &["--pf", "gapf"],
        &["--araim"],
        &["--esq"],
        &["--pca"],
        &["--mcusum"],
        &["--model-check"],
        &["--model-check", "--araim"],
    ] {
        let mut a = vec!["replay", "--obs", &obs, "--nav", &nav];
        a.extend_from_slice(monitor);
        accepted(&a);
    }
}

/// `raim replay --ubx` on the LEA-4T log, defaults otherwise.
#[test]
fn replay_defaults_on_a_ubx_log() {
    accepted(&["replay", "--ubx", &format!("{DATA}/ubx_20080526.ubx")]);
}

/// `snapshot` and `araim` on the committed epoch vectors (their required
/// input).
///
/// Verifies: TOOL-DEFAULTS
#[test]
fn snapshot_and_araim_defaults() {
    accepted(&[
        "snapshot",
        "--input",
        &format!("{REPO}/host-tests/vectors/snapshot_example.jsonl"),
    ]);
    accepted(&[
        "araim",
        "--input",
        &format!("{REPO}/host-tests/vectors/add_v3_appendix_d.json"),
    ]);
}

/// The analysis subcommands: what each requires (a sky for `pci` and the
/// `--pd` target it needs one of; `--dim`, `--k` and `--arl0` for `arl`;
/// `--pfa` and `--dof` for `threshold`), and the runs shortened (campaign
/// epochs and trials, `pci --mc`, `pf-table --only ekf --epochs`).
#[test]
fn analysis_defaults() {
    accepted(&["campaign", "false-alarm", "--epochs", "2000"]);
    accepted(&["campaign", "single-fault", "--trials", "10"]);
    accepted(&[
        "pci",
        "--az",
        "0,45,100,160,220,280,330",
        "--el",
        "85,30,50,20,60,15,40",
        "--pd",
        "0.5",
        "--mc",
        "2000",
    ]);
    accepted(&["arl", "--dim", "4", "--k", "1", "--arl0", "500"]);
    accepted(&["threshold", "--pfa", "3.3333e-7", "--dof", "4"]);
    accepted(&["pf-table", "--only", "ekf", "--epochs", "100"]);
    accepted(&["completions", "bash"]);
    accepted(&["man"]);
}

/// `rtcm-fault` on GMSD7 with what it requires (the stream, an output
/// and a fault: a 50 m step on G06 a minute after the first MSM), and the
/// faulted stream replayed (`raim replay --rtcm3 --systems G --mask-deg
/// 0`, as docs/RECEIVERS.md runs GMSD7): G06 is excluded at every solved
/// epoch from the onset on and at none before, where the original stream
/// has no exclusion at all.
///
/// Verifies: TOOL-DEFAULTS, RX-STREAM-FAULT
#[test]
fn rtcm_fault_defaults() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-cli-defaults-rtcm");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = dir.join("gmsd7_g06.rtcm3");
    let out = out.to_str().expect("utf-8 path");
    accepted(&[
        "rtcm-fault",
        "--in",
        &format!("{DATA}/GMSD7_20121014.rtcm3"),
        "--out",
        out,
        "--fault",
        "step:G06:50@+60",
    ]);
    let (code, text, err) = raim(
        &[
            "replay",
            "--rtcm3",
            out,
            "--systems",
            "G",
            "--mask-deg",
            "0",
            "--json",
            "--keep-going",
        ],
        None,
    );
    assert_eq!(code, Some(0), "{err}");
    let (mut first, mut excluded, mut before, mut solved_after) = (None, 0, 0, 0);
    for line in text.lines() {
        let v: serde_json::Value = match serde_json::from_str(line) {
            Ok(v) => v,
            Err(_) => continue,
        };
        let Some(t) = v.get("time_gps_s").and_then(|t| t.as_f64()) else {
            continue;
        };
        let t0 = *first.get_or_insert(t);
        let ex = v.get("excluded").map(|e| e.to_string()).unwrap_or_default();
        let decision = v.get("decision").and_then(|d| d.as_str()).unwrap_or("");
        if t < t0 + 60.0 {
            before += usize::from(!ex.contains("G06") && decision != "excluded");
        } else if matches!(decision, "ok" | "excluded") {
            solved_after += 1;
            excluded += usize::from(ex.contains("G06"));
        }
    }
    assert!(solved_after > 150, "{solved_after}: {err}");
    assert_eq!(excluded, solved_after, "{err}");
    assert!(before >= 60, "{before}");
    // A constellation fault needs the station's lines of sight: GMSD7
    // sends no 1005/1006 (GLONASS's as GPS's); a fault on a satellite the
    // stream does not carry (or after its end) writes nothing.
    for (option, spec, why) in [
        (
            "--araim-const-fault",
            "G:0:0,0,30@+60",
            "no station position",
        ),
        (
            "--araim-const-fault",
            "R:0:0,0,30@+60",
            "no station position",
        ),
        ("--fault", "step:G02:50@+60", "move no pseudorange"),
        ("--fault", "step:G06:50@+100000", "move no pseudorange"),
    ] {
        let (code, _, err) = raim(
            &[
                "rtcm-fault",
                "--in",
                &format!("{DATA}/GMSD7_20121014.rtcm3"),
                "--out",
                out,
                option,
                spec,
            ],
            None,
        );
        assert_eq!(code, Some(1), "{spec}: {err}");
        assert!(err.contains(why), "{spec}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `availability` on the committed MAAST scenario (its required input, the
/// run file), defaults otherwise, its outputs into a temporary directory
/// instead of the default `.`. It reports on stderr and writes its
/// results as files: the summary must be there, with the coverage.
///
/// Verifies: TOOL-DEFAULTS, SPEC-14
#[test]
fn availability_defaults() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-cli-defaults-avail");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let run = format!("{REPO}/docs/runs/availability_maast_g24e24.toml");
    let out = dir.to_str().expect("utf-8 path");
    let (code, _, err) = raim(&["availability", "--run", &run, "--out", out], None);
    assert_eq!(code, Some(0), "{err}");
    let summary = std::fs::read_to_string(dir.join("availability_maast_g24e24.summary.json"))
        .unwrap_or_else(|e| panic!("no summary ({e}); {err}"));
    assert!(summary.contains("coverage"), "{summary}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `provision` seals docs/unit.toml into the firmware image (its required
/// inputs), defaults otherwise, and writes the sealed image.
///
/// Verifies: TOOL-DEFAULTS
#[test]
fn provision_defaults() {
    let elf = raim_qemu::firmware_elf().expect("firmware build");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-cli-defaults");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let out = dir.join("sealed.elf");
    let (code, stdout, err) = raim(
        &[
            "provision",
            "--config",
            &format!("{REPO}/docs/unit.toml"),
            "--out",
            out.to_str().expect("utf-8 path"),
            elf.to_str().expect("utf-8 path"),
        ],
        None,
    );
    assert_eq!(code, Some(0), "{err}");
    assert!(
        stdout.contains("fingerprint") || err.contains("fingerprint"),
        "{stdout}{err}"
    );
    let sealed = std::fs::metadata(&out).expect("sealed image").len();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(sealed > 0);
}
