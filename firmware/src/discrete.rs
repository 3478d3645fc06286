//! The integrity-alarm discrete output: drives the board's
//! `AlarmPin` (embedded-hal `OutputPin`, active low) from
//! `raim_proto::alert::AlertMonitor`: asserted until the first valid
//! epoch, on every `Alarm`, `Unavailable` or errored epoch, and when no
//! valid epoch has arrived within the time-to-alert (docs/SAFETY.md).
//!
//! The time-to-alert is a build setting (`RAIM_TIME_TO_ALERT_S`, default
//! 10 s, bounded to 1-30 s by `build.rs`), not part of the wire
//! configuration: no host can lengthen it.

use embedded_hal::digital::{OutputPin, StatefulOutputPin};
use raim_core::Decision;
use raim_proto::alert::{AlarmOutput, AlertMonitor};

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

pub struct Discrete<P> {
    monitor: AlertMonitor,
    pin: P,
}

impl<P: OutputPin + StatefulOutputPin> Discrete<P> {
    /// The output on `pin`, with the time-to-alert counted in ticks of a
    /// `core_hz` clock.
    pub fn new(pin: P, core_hz: u32) -> Self {
        let mut d = Discrete {
            monitor: AlertMonitor::new(time_to_alert_ticks(core_hz)),
            pin,
        };
        d.update(0);
        d
    }

    /// An epoch was processed at `now_ticks`.
    pub fn on_epoch(&mut self, now_ticks: u64, decision: Option<Decision>) {
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
