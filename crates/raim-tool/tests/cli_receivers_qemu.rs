//! `raim replay --rtcm3` / `--ubx` with `--target qemu`: the firmware under
//! QEMU (mps2-an386) gives the host's decisions and exclusions, epoch by
//! epoch, on a window of each real log around a 50 m step (QEMU takes a
//! fraction of a second per epoch, so the windows are 40 s).

use std::process::Command;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

fn run(args: &[&str], target: &str) -> Vec<serde_json::Value> {
    let out = Command::new(env!("CARGO_BIN_EXE_raim"))
        .args(args)
        .args(["--target", target, "--json", "--keep-going"])
        .output()
        .expect("spawn raim");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{target}: {stderr}");
    let text = String::from_utf8(out.stdout).expect("utf8");
    let mut v: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("json"))
        .collect();
    v.pop();
    v
}

fn same_decisions(args: &[&str], expect_epochs: usize) {
    let host = run(args, "host");
    let qemu = run(args, "qemu");
    assert_eq!(host.len(), expect_epochs);
    assert_eq!(host.len(), qemu.len());
    let mut excluded = 0;
    for (h, q) in host.iter().zip(&qemu) {
        assert_eq!(h["tod"], q["tod"]);
        for k in ["decision", "excluded", "alarm_cause", "n_sats"] {
            assert_eq!(h[k], q[k], "{} {k}", h["tod"]);
        }
        excluded += usize::from(h["decision"] == "excluded");
    }
    assert!(excluded > 0, "the window has exclusions to compare");
}

#[test]
fn gmsd7_on_the_firmware() {
    let src = format!("{DATA}/GMSD7_20121014.rtcm3");
    same_decisions(
        &[
            "replay",
            "--rtcm3",
            &src,
            "--systems",
            "G",
            "--mask-deg",
            "0",
            "--fault",
            "step:G06:50@+60",
            "--start",
            "+40",
            "--end",
            "+79",
        ],
        40,
    );
}

/// GPS + GLONASS (RTCM 1087 with the 1020 ephemerides): a 50 m step on the
/// GLONASS satellite R14, the same decisions on the firmware.
#[test]
fn gmsd7_gps_glonass_on_the_firmware() {
    let src = format!("{DATA}/GMSD7_20121014.rtcm3");
    same_decisions(
        &[
            "replay",
            "--rtcm3",
            &src,
            "--systems",
            "GR",
            "--mask-deg",
            "0",
            "--fault",
            "step:R14:50@+60",
            "--start",
            "+40",
            "--end",
            "+79",
        ],
        40,
    );
}

#[test]
fn lea4t_on_the_firmware() {
    let src = format!("{DATA}/ubx_20080526.ubx");
    same_decisions(
        &[
            "replay",
            "--ubx",
            &src,
            "--fault",
            "step:G05:50@+60",
            "--start",
            "+40",
            "--end",
            "+79",
        ],
        40,
    );
}
