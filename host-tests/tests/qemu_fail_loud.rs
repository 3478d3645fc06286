//! The firmware fails loud and recovers. Under QEMU (mps2-an386)
//! a hung main loop (the test-only `TestFault::Hang`) is reset by the CMSDK
//! watchdog, a panic (`TestFault::Panic`) resets the unit, and the next
//! `Status` reports the reset count and cause, a stack overflow
//! (`TestFault::StackOverflow`) is stopped by the MPU guard and reported
//! the same way; the reset also unlocks the
//! configuration (only a reset does), and the unit answers epochs again.

mod qemu_common;

use std::time::Duration;

use qemu_common::{host_result, range_vectors, session, wire_bytes};
use raim_core::{Config, Epoch, Phase};
use raim_proto::message::CommandRef;
use raim_proto::{ConfigSource, ResetCause, TestFault};

/// The watchdog fires 2 s after the last feed (mps2-an386's `WATCHDOG_TIMEOUT_MS`, firmware/src/board/mps2.rs).
const WATCHDOG_S: f64 = 2.0;

/// How long a reset may take to bring its boot notice: a deadline only a
/// unit that never comes back reaches (the test waits for the notice, so
/// it does not depend on how fast the loaded machine runs QEMU).
const REBOOT_DEADLINE: Duration = Duration::from_secs(120);

/// Verifies: SAFE-FAULT
#[test]
fn qemu_hang_and_panic_reset_the_unit_and_are_reported() {
    let mut fw = session();
    let st = fw.status().unwrap();
    assert_eq!((st.resets, st.reset_cause), (0, ResetCause::PowerOn));
    // Idle longer than the watchdog timeout: the waiting loop feeds it.
    std::thread::sleep(Duration::from_secs_f64(1.5 * WATCHDOG_S));
    let st = fw.status().unwrap();
    assert_eq!((st.resets, st.reset_cause), (0, ResetCause::PowerOn));

    let terminal = Config::preset(Phase::Terminal);
    fw.configure(&terminal).unwrap();
    fw.lock().unwrap();
    fw.send(CommandRef::TestFault(TestFault::Hang)).unwrap();
    // Hung: no answer before the watchdog fires.
    assert!(fw.recv(Duration::from_secs_f64(0.75 * WATCHDOG_S)).is_err());
    // The watchdog's reset: its boot notice, not a fixed sleep.
    fw.wait_boot(REBOOT_DEADLINE).unwrap();
    let st = fw.status().unwrap();
    assert_eq!(st.resets, 1, "{st:?}");
    assert!(
        matches!(st.reset_cause, ResetCause::Watchdog { .. }),
        "{st:?}"
    );
    // The reset unlocked the unit and dropped the runtime configuration:
    // an unprovisioned unit is Unconfigured again (qemu_authority.rs).
    assert_eq!(st.config.source, ConfigSource::Unconfigured);
    assert!(!st.config.locked);

    fw.send(CommandRef::TestFault(TestFault::Panic)).unwrap();
    fw.wait_boot(REBOOT_DEADLINE).unwrap();
    let st = fw.status().unwrap();
    assert_eq!(st.resets, 2, "{st:?}");
    assert!(
        matches!(st.reset_cause, ResetCause::Panic { line } if line > 0),
        "{st:?}"
    );

    // A stack overflow hits the MPU guard between the statics and the
    // stack instead of overwriting the server state.
    fw.send(CommandRef::TestFault(TestFault::StackOverflow))
        .unwrap();
    fw.wait_boot(REBOOT_DEADLINE).unwrap();
    let st = fw.status().unwrap();
    assert_eq!(st.resets, 3, "{st:?}");
    let ResetCause::StackOverflow { address } = st.reset_cause else {
        panic!("{st:?}")
    };
    // The frame was stacked in the guard, in RAM (mps2-an386: 0x2000_0000..).
    assert!(
        (0x2000_0000..0x2040_0000).contains(&address),
        "{address:#x}"
    );
    // Stack painting still measures (above the guard).
    assert!(st.stack_high_water_bytes > 0, "{st:?}");

    // Back in service once configured: an epoch is answered bit for bit
    // as on the host.
    fw.configure(&Config::default()).unwrap();
    let (time_s, sats, apriori) = &range_vectors(5)[1];
    let epoch = Epoch::ranges(*time_s, sats, *apriori);
    let p = fw.process(&epoch).unwrap();
    let want = host_result(&Config::default(), &epoch).unwrap();
    assert_eq!(wire_bytes(&p.outcome.unwrap()), wire_bytes(&want));
}

/// The firmware built with a time-to-alert of 1 s (`RAIM_TIME_TO_ALERT_S=1`),
/// shorter than mps2-an386's 2 s watchdog, so that a hung loop outlives
/// the time-to-alert, and with the timer's record (feature `tta-record`): `$RAIM_FIRMWARE_ELF_TTA1` (scripts/test.sh copies it
/// to firmware/target/elf/qemu-tta1), else built into
/// `firmware/target/tta1`.
fn tta1_elf() -> std::path::PathBuf {
    if let Some(p) = std::env::var_os("RAIM_FIRMWARE_ELF_TTA1") {
        return p.into();
    }
    let dir = raim_qemu::repo_root().join("firmware");
    let mut cmd =
        std::process::Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.current_dir(&dir)
        .args([
            "build",
            "--release",
            "--quiet",
            "--features",
            "tta-record",
            "--target-dir",
            "target/tta1",
        ])
        .env("RAIM_TIME_TO_ALERT_S", "1");
    for (k, _) in std::env::vars_os() {
        let k = k.to_string_lossy().into_owned();
        if k.starts_with("CARGO_BUILD_") || k == "CARGO_TARGET_DIR" || k.contains("RUSTFLAGS") {
            cmd.env_remove(k);
        }
    }
    assert!(cmd.status().expect("cargo").success(), "firmware build");
    dir.join("target/tta1/thumbv7em-none-eabihf/release/raim-firmware")
}

/// The record the SysTick exception writes when it asserts the output
/// (`firmware/src/discrete.rs`, test build): ticks of the last valid
/// epoch and of the assertion, the pin read back, the setting.
fn tta_record(log: &[u8]) -> Option<(u64, u64, bool, u64)> {
    let marker = b"RAIM-TTA-TIMER ";
    let at = log.windows(marker.len()).position(|w| w == marker)?;
    let line = log.get(at + marker.len()..)?;
    let end = line.iter().position(|&b| b == b'\n')?;
    let text = std::str::from_utf8(line.get(..end)?).ok()?;
    let field = |name: &str| {
        text.split(' ')
            .find_map(|kv| kv.strip_prefix(name)?.strip_prefix('='))
    };
    Some((
        field("valid")?.parse().ok()?,
        field("asserted")?.parse().ok()?,
        field("pin")? == "alarm",
        field("tta_s")?.parse().ok()?,
    ))
}

/// Issue 35: the alarm output is asserted within the time-to-alert with
/// the main loop hung. After a valid epoch clears the output, the loop is
/// hung on purpose (`TestFault::Hang`, interrupts on, watchdog not fed);
/// SysTick's exception, not the loop, asserts the pin once no valid epoch
/// has come within the time-to-alert, before the watchdog resets the unit.
/// Measured in the guest's time base (SysTick at 25 MHz under `-icount`):
/// the assertion comes at the monitor's deadline or after it (the
/// setting less one SysTick wrap) and no later than the setting, and the
/// pin read back is at the alarm level.
///
/// Verifies: SAFE-TTA-TIMER
#[test]
fn qemu_a_hung_loop_asserts_the_alarm_within_the_time_to_alert() {
    const CORE_HZ: u64 = 25_000_000;
    const WRAP_TICKS: u64 = 1 << 24;
    let elf = tta1_elf();
    let mut fw = raim_qemu::QemuSession::start_with(
        &elf,
        &raim_qemu::Options {
            icount: true,
            ..raim_qemu::Options::default()
        },
    )
    .expect("qemu-system-arm with the firmware");
    let (time_s, sats, apriori) = &range_vectors(5)[1];
    let p = fw.process(&Epoch::ranges(*time_s, sats, *apriori)).unwrap();
    assert!(p.outcome.is_ok(), "{:?}", p.outcome);
    let st = fw.status().unwrap();
    assert_eq!(
        (st.alarm_output, st.alarm_pin_asserted),
        (raim_proto::alert::AlarmOutput::Clear, false),
        "a valid epoch clears the output first"
    );
    assert!(
        tta_record(&std::fs::read(fw.log_path()).unwrap()).is_none(),
        "no assertion by the timer yet"
    );
    fw.send(CommandRef::TestFault(TestFault::Hang)).unwrap();
    // The watchdog's reset follows the hang; the record comes before it.
    fw.wait_boot(REBOOT_DEADLINE).unwrap();
    let log = std::fs::read(fw.log_path()).unwrap();
    let (valid, asserted, pin_alarm, tta_s) = tta_record(&log).expect("the timer's record");
    assert_eq!(tta_s, 1);
    let tta_ticks = tta_s * CORE_HZ;
    println!(
        "valid epoch at tick {valid}, asserted by the timer at tick {asserted}: {:.3} s",
        (asserted - valid) as f64 / CORE_HZ as f64
    );
    assert!(pin_alarm, "the pin read back after the timer asserted it");
    assert!(
        asserted >= valid + tta_ticks - WRAP_TICKS && asserted <= valid + tta_ticks,
        "asserted {} s after the last valid epoch; time-to-alert {tta_s} s",
        (asserted - valid) as f64 / CORE_HZ as f64
    );
    let st = fw.status().unwrap();
    assert!(
        matches!(st.reset_cause, ResetCause::Watchdog { .. }),
        "{st:?}"
    );
}
