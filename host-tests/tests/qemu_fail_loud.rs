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
