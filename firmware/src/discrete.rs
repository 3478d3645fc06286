//! The integrity-alarm discrete output: drives the board's
//! `AlarmPin` (embedded-hal `OutputPin`, active low) from
//! `raim_proto::alert::AlertMonitor`: asserted until the first valid
//! epoch, on every `Alarm`, `Unavailable` or errored epoch, and when no
//! valid epoch has arrived within the time-to-alert (docs/SAFETY.md).
//!
//! The time-to-alert is a build setting (`RAIM_TIME_TO_ALERT_S`, default
//! 10 s, bounded to 1-30 s by `build.rs`), not part of the wire
//! configuration: no host can lengthen it.
//!
//! The time-to-alert does not depend on the main loop: every valid epoch
//! arms a deadline ([`DEADLINE_WRAPS`], in SysTick wraps), and SysTick's
//! exception, which runs whatever the main loop does (a hung epoch, a
//! blocked write), asserts the pin itself once the deadline has passed
//! ([`on_wrap`], through `Board::force_alarm`). The handler only asserts;
//! only the main loop, on a valid epoch, clears. So a hung loop shows the
//! alarm within the time-to-alert on every clock, before the watchdog
//! resets the unit (up to 28 s on the STM32F4's HSI; issue 35).

use core::sync::atomic::{AtomicU32, Ordering};

use embedded_hal::digital::{OutputPin, StatefulOutputPin};
use raim_core::Decision;
use raim_proto::alert::{AlarmOutput, AlertMonitor};

use crate::board::Board;

include!(concat!(env!("OUT_DIR"), "/settings.rs"));

/// The main loop checks the time at least once per SysTick wrap (2^24
/// ticks); the output asserts this much before the time-to-alert so that
/// it is asserted by the time-to-alert at the latest.
const CHECK_PERIOD_TICKS: u64 = 1 << 24;

/// The monitor's time-to-alert in ticks of a `core_hz` clock: the setting
/// less one check period.
pub fn time_to_alert_ticks(core_hz: u32) -> u64 {
    (u64::from(TIME_TO_ALERT_S) * u64::from(core_hz)).saturating_sub(CHECK_PERIOD_TICKS)
}

/// The SysTick wrap (2^24 core ticks) at or after which the exception
/// asserts the output: the first wrap after the last valid epoch's tick
/// plus [`time_to_alert_ticks`], so after the monitor's own deadline, and
/// less than one wrap later, which is within the setting. `u32::MAX`
/// until the first valid epoch (the output is asserted until then).
/// Written by the main loop, read by the exception.
static DEADLINE_WRAPS: AtomicU32 = AtomicU32::new(u32::MAX);

/// The last valid epoch's tick, split in two words (no 64-bit atomics on
/// the Cortex-M4), for the test build's record of the timer's assertion.
#[cfg(feature = "tta-record")]
static VALID_AT: [AtomicU32; 2] = [AtomicU32::new(0), AtomicU32::new(0)];

/// Arms the timer for a valid epoch at `now_ticks`; before the pin may be
/// cleared, so that the exception never sees the old deadline with the
/// pin clear for a new epoch's sake.
fn arm(now_ticks: u64, tta_ticks: u64) {
    // The wrap after the one the deadline falls in: at or after the
    // deadline, and less than one wrap after it.
    let wraps = (now_ticks.saturating_add(tta_ticks) >> 24) + 1;
    #[cfg(feature = "tta-record")]
    {
        VALID_AT[0].store(now_ticks as u32, Ordering::Relaxed);
        VALID_AT[1].store((now_ticks >> 32) as u32, Ordering::Relaxed);
    }
    DEADLINE_WRAPS.store(u32::try_from(wraps).unwrap_or(u32::MAX), Ordering::Release);
}

/// SysTick's exception, at wrap `wraps` since boot: asserts the output
/// when the deadline has passed (no valid epoch within the time-to-alert),
/// whatever the main loop is doing. Never clears it.
pub fn on_wrap(wraps: u32) {
    let deadline = DEADLINE_WRAPS.load(Ordering::Acquire);
    if wraps >= deadline {
        crate::board::Active::force_alarm();
        #[cfg(feature = "tta-record")]
        if wraps == deadline {
            record_assertion(wraps);
        }
    }
}

/// The test build's record (feature `tta-record`) of the timer's
/// assertion, on the semihosting
/// output (plain text among the defmt frames): the tick of the last valid
/// epoch and of the assertion, and the time-to-alert in ticks, all in the
/// guest's own time base (SysTick). `host-tests/tests/qemu_fail_loud.rs`
/// reads it while the main loop hangs.
#[cfg(feature = "tta-record")]
fn record_assertion(wraps: u32) {
    fn decimal(out: &mut [u8; 20], mut v: u64) -> &[u8] {
        let mut i = out.len();
        loop {
            i -= 1;
            if let Some(d) = out.get_mut(i) {
                *d = b'0' + (v % 10) as u8;
            }
            v /= 10;
            if v == 0 || i == 0 {
                break;
            }
        }
        out.get(i..).unwrap_or(&[])
    }
    let valid = u64::from(VALID_AT[0].load(Ordering::Relaxed))
        | u64::from(VALID_AT[1].load(Ordering::Relaxed)) << 32;
    let at = u64::from(wraps) * CHECK_PERIOD_TICKS;
    if let Ok(mut out) = cortex_m_semihosting::hio::hstdout() {
        let mut buf = [0u8; 20];
        let _ = out.write_all(b"\nRAIM-TTA-TIMER valid=");
        let _ = out.write_all(decimal(&mut buf, valid));
        let _ = out.write_all(b" asserted=");
        let _ = out.write_all(decimal(&mut buf, at));
        // The pin read back (mps2-an386's LED0, bit 0; low is the alarm).
        // SAFETY: a read of the FPGA I/O block's LED0 register, always
        // mapped on this board.
        let led0 = unsafe { core::ptr::read_volatile(0x4002_8000 as *const u32) };
        let _ = out.write_all(if led0 & 1 == 0 {
            b" pin=alarm"
        } else {
            b" pin=clear"
        });
        let _ = out.write_all(b" tta_s=");
        let _ = out.write_all(decimal(&mut buf, u64::from(TIME_TO_ALERT_S)));
        let _ = out.write_all(b"\n");
    }
}

pub struct Discrete<P> {
    monitor: AlertMonitor,
    pin: P,
    /// The monitor's time-to-alert, ticks.
    tta_ticks: u64,
}

impl<P: OutputPin + StatefulOutputPin> Discrete<P> {
    /// The output on `pin`, with the time-to-alert counted in ticks of a
    /// `core_hz` clock.
    pub fn new(pin: P, core_hz: u32) -> Self {
        let tta_ticks = time_to_alert_ticks(core_hz);
        let mut d = Discrete {
            monitor: AlertMonitor::new(tta_ticks),
            pin,
            tta_ticks,
        };
        d.update(0);
        d
    }

    /// An epoch was processed at `now_ticks`.
    pub fn on_epoch(&mut self, now_ticks: u64, decision: Option<Decision>) {
        if matches!(decision, Some(Decision::Ok | Decision::Excluded)) {
            arm(now_ticks, self.tta_ticks);
        }
        self.monitor.on_epoch(now_ticks, decision);
        self.update(now_ticks);
    }

    /// Drive the pin for `now_ticks`; returns the state.
    pub fn update(&mut self, now_ticks: u64) -> AlarmOutput {
        let out = self.monitor.output(now_ticks);
        // The pin's error type is Infallible on both boards.
        let _ = if out.asserted() {
            self.pin.set_low()
        } else {
            self.pin.set_high()
        };
        out
    }

    /// Whether the pin, read back, is at its alarm (low) level; a pin that
    /// cannot be read counts as asserted.
    pub fn pin_asserted(&mut self) -> bool {
        self.pin.is_set_low().unwrap_or(true)
    }
}
