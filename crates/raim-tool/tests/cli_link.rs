//! `raim link` against the firmware under QEMU through a pty (QEMU's
//! `-serial pty` on the link UART, as a serial port on a bench would be):
//! Status, Configure, Lock and Status answered in order; a second
//! `raim link` process's Configure is refused because the lock holds, and
//! exits non-zero. `epochs` of a receiver stream over the pty answered
//! with the decisions of `raim replay --target qemu` on the same epochs.

mod common;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// How long QEMU may take to name its pty.
const PTY_TIMEOUT: Duration = Duration::from_secs(30);

/// QEMU, killed when the test ends however it ends.
struct Qemu(Child);

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn raim(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("spawn raim");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// The firmware under QEMU with its link UART on a pty: QEMU (killed on
/// drop) and the pty's path.
fn qemu_on_a_pty() -> (Qemu, String) {
    // The streaming build: a loaded host's stall of QEMU is not a pause
    // on the link to it (docs/EVIDENCE.md "The suite under load").
    let elf =
        raim_qemu::firmware_elf_stream(raim_qemu::Machine::Mps2An386).expect("firmware build");
    let mut child = Command::new("qemu-system-arm")
        .args(["-machine", "mps2-an386", "-cpu", "cortex-m4"])
        .args(["-nographic", "-monitor", "none"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-serial", "pty", "-serial", "null", "-kernel"])
        .arg(&elf)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("qemu-system-arm");
    let stdout = child.stdout.take().expect("QEMU's stdout");
    let _qemu = Qemu(child);
    // "char device redirected to /dev/pts/N (label serial0)" on QEMU's
    // stdout (with the semihosting bytes), read on a thread so that a
    // silent QEMU fails the test instead of hanging it; the thread drains
    // the rest so that QEMU never blocks on a full pipe.
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut r = BufReader::new(stdout);
        let mut line = Vec::new();
        while r.read_until(b'\n', &mut line).is_ok_and(|n| n > 0) {
            let l = String::from_utf8_lossy(&line);
            if let Some(p) = l.split_whitespace().find(|w| w.starts_with("/dev/pts/")) {
                let _ = tx.send(p.to_string());
            }
            line.clear();
        }
    });
    let pty = rx.recv_timeout(PTY_TIMEOUT).expect("QEMU names its pty");
    (_qemu, pty)
}

#[test]
fn link_over_a_pty_to_qemu() {
    let (_qemu, pty) = qemu_on_a_pty();
    let (code, out, err) = raim(&[
        "link",
        "--port",
        &pty,
        "status",
        "configure",
        "lock",
        "status",
    ]);
    assert_eq!(code, Some(0), "{out}{err}");
    let answers: Vec<&str> = out
        .lines()
        .filter(|l| !l.starts_with("notice") && !l.starts_with("boot"))
        .collect();
    // Each Status is followed by its epoch cycles, which QEMU does not
    // measure (no DWT): said, not printed as zeros.
    assert_eq!(
        out.lines()
            .filter(|l| *l == "epoch cycles: not measured (the unit's cycle counter does not run)")
            .count(),
        2,
        "{out}"
    );
    let answers: Vec<&str> = answers
        .into_iter()
        .filter(|l| !l.starts_with("epoch cycles"))
        .collect();
    assert_eq!(answers.len(), 4, "{out}");
    assert!(
        answers[0].starts_with("Status: Status(") && answers[0].contains("locked: false"),
        "{out}"
    );
    assert!(answers[1].starts_with("Configure: Configured"), "{out}");
    assert!(answers[2].starts_with("Lock: LockEngaged"), "{out}");
    assert!(
        answers[3].starts_with("Status: Status(") && answers[3].contains("locked: true"),
        "{out}"
    );

    let (code, out, err) = raim(&["link", "--port", &pty, "configure"]);
    assert_eq!(code, Some(1), "{out}{err}");
    assert!(
        err.contains("Configure refused") && err.contains("Locked"),
        "{out}{err}"
    );
}

/// 15 epochs of GMSD7 with GPS + GLONASS and a 50 m step on R14 from the
/// 5th (`raim replay`'s options after `--`), sent over the pty: every
/// epoch answered with the decision, exclusions, alarm cause, satellite
/// count and protection levels of `raim replay --target qemu` on the
/// same epochs (the same firmware, so the same f32 results, bit for bit).
#[test]
fn link_epochs_answer_as_the_qemu_replay() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
    let src = format!("{data}/GMSD7_20121014.rtcm3");
    let opts = [
        "--rtcm3",
        &src,
        "--systems",
        "GR",
        "--mask-deg",
        "0",
        "--fault",
        "step:R14:50@+60",
        "--start",
        "+56",
        "--end",
        "+70",
        "--json",
        "--keep-going",
    ];
    let lines = |out: &str| -> Vec<serde_json::Value> {
        let mut v: Vec<serde_json::Value> = out
            .lines()
            .filter(|l| l.starts_with('{'))
            .map(|l| serde_json::from_str(l).expect("json"))
            .collect();
        v.pop();
        v
    };
    let mut replay = vec!["replay"];
    replay.extend(opts);
    replay.extend(["--target", "qemu"]);
    let (code, out, err) = raim(&replay);
    assert_eq!(code, Some(0), "{err}");
    let want = lines(&out);
    assert_eq!(want.len(), 15, "{out}");

    let (_qemu, pty) = qemu_on_a_pty();
    let mut link = vec!["link", "--port", &pty, "status", "epochs", "--"];
    link.extend(opts);
    let (code, out, err) = raim(&link);
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(
        out.lines().any(|l| l.starts_with("Status: Status(")),
        "{out}"
    );
    let got = lines(&out);
    assert_eq!(got.len(), want.len(), "{out}");
    let mut excluded = 0;
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g["tod"], w["tod"]);
        for k in [
            "decision",
            "excluded",
            "alarm_cause",
            "n_sats",
            "hpl_m",
            "vpl_m",
        ] {
            assert_eq!(g[k], w[k], "{} {k}", w["tod"]);
        }
        excluded += usize::from(w["excluded"] == serde_json::json!(["R14"]));
    }
    assert_eq!(excluded, 11, "R14 excluded from the step's onset on");
}

/// A live source through the unit: GMSD7 served over TCP, `raim link
/// epochs -- --rtcm3 tcp://...` sends each epoch to the unit over the pty
/// as it arrives; every epoch gets the decision, satellite count and
/// protection levels of `raim replay --target qemu` on the same live
/// source, and the run ends cleanly at the end of the stream.
///
/// Verifies: TOOL-LIVE
#[test]
fn link_epochs_from_a_live_source() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");
    let bytes = std::fs::read(format!("{data}/GMSD7_20121014.rtcm3")).unwrap();
    let opts = |addr: &str| {
        vec![
            "--rtcm3".to_string(),
            format!("tcp://{addr}"),
            "--systems".into(),
            "GR".into(),
            "--mask-deg".into(),
            "0".into(),
            "--json".into(),
            "--keep-going".into(),
        ]
    };
    let records = |out: &str| -> Vec<serde_json::Value> {
        out.lines()
            .filter(|l| l.starts_with('{'))
            .map(|l| serde_json::from_str::<serde_json::Value>(l).expect("json"))
            .filter(|v| v.get("summary").is_none())
            .collect()
    };
    let addr = common::serve(
        bytes.clone(),
        8192,
        Duration::from_millis(1),
        Duration::ZERO,
    );
    let mut replay = vec!["replay".to_string()];
    replay.extend(opts(&addr));
    replay.extend(["--target".into(), "qemu".into()]);
    let replay: Vec<&str> = replay.iter().map(String::as_str).collect();
    let (code, out, err) = raim(&replay);
    assert_eq!(code, Some(0), "{err}");
    let want = records(&out);
    assert_eq!(want.len(), 257, "{err}");

    let (_qemu, pty) = qemu_on_a_pty();
    let addr = common::serve(bytes, 8192, Duration::from_millis(1), Duration::ZERO);
    let mut link = vec![
        "link".to_string(),
        "--port".into(),
        pty.clone(),
        "epochs".into(),
        "--".into(),
    ];
    link.extend(opts(&addr));
    let link: Vec<&str> = link.iter().map(String::as_str).collect();
    let (code, out, err) = raim(&link);
    assert_eq!(code, Some(0), "{out}{err}");
    assert!(err.contains("stopped (end of stream)"), "{err}");
    let got = records(&out);
    assert_eq!(got.len(), want.len(), "{err}");
    let mut solved = 0;
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g["tod"], w["tod"]);
        for k in ["decision", "excluded", "n_sats", "hpl_m", "vpl_m"] {
            assert_eq!(g[k], w[k], "{} {k}", w["tod"]);
        }
        solved += usize::from(w["hpl_m"].is_number());
    }
    assert!(solved > 0);
}

/// `epochs` options are checked before the port is opened: none given,
/// given without `epochs`, a replay-only monitor, a run file.
#[test]
fn link_epoch_options_are_checked_first() {
    let port = "/nonexistent/tty";
    for (args, want) in [
        (vec!["epochs"], "after `--`"),
        (
            vec!["status", "--", "--rtcm3", "x.rtcm3"],
            "options after `--` are for `epochs`",
        ),
        (
            vec!["epochs", "--", "--rtcm3", "x.rtcm3", "--araim"],
            "snapshot monitor",
        ),
        (
            vec!["epochs", "--", "--rtcm3", "x.rtcm3", "--config", "run.toml"],
            "--config",
        ),
    ] {
        let mut a = vec!["link", "--port", port];
        a.extend(args.iter().copied());
        let (code, out, err) = raim(&a);
        assert_eq!(code, Some(1), "{args:?}: {out}{err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("opening"), "{args:?}: {err}");
    }
}
