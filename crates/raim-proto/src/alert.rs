//! The integrity-alarm discrete output, sans-IO: what the
//! output should show, from the decisions of the epochs and the time since
//! the last valid one. The firmware drives a pin from it (`Platform`
//! hooks, `firmware/src/discrete.rs`) and reports it in `Status`.
//!
//! The output is asserted (alarm) unless the last epoch was valid (its
//! decision `Ok` or `Excluded`: a fix whose integrity is assured) and it
//! arrived less than the time-to-alert ago. So it is asserted from boot
//! until the first valid epoch, at once on an `Alarm` or `Unavailable`
//! epoch or on an epoch answered with a typed error (no integrity can be
//! claimed for it), and when the epochs stop (docs/SAFETY.md).

use raim_core::Decision;
use serde::{Deserialize, Serialize};

/// The state of the integrity-alarm output and why. Only `Clear` is the
/// de-asserted state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AlarmOutput {
    /// Asserted: no valid epoch since boot.
    #[default]
    NoValidEpoch,
    /// De-asserted: the last epoch was valid and arrived within the
    /// time-to-alert.
    Clear,
    /// Asserted: the last epoch's decision was `Alarm`.
    Alarm,
    /// Asserted: the last epoch's decision was `Unavailable`.
    Unavailable,
    /// Asserted: the last epoch was answered with a typed error.
    EpochError,
    /// Asserted: the last epoch was valid, but no epoch has arrived within
    /// the time-to-alert since.
    TimeToAlertExceeded,
}

impl AlarmOutput {
    /// True for every state but `Clear`.
    pub fn asserted(self) -> bool {
        self != AlarmOutput::Clear
    }
}

/// The output's state machine. Time is a free-running tick count (any
/// rate, 64 bits so that it does not wrap); the time-to-alert is given in
/// the same ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AlertMonitor {
    time_to_alert_ticks: u64,
    /// The last epoch's verdict and, for a valid one, when it arrived.
    last: AlarmOutput,
    valid_at_ticks: u64,
}

impl AlertMonitor {
    /// An output asserted (no valid epoch yet), with the time-to-alert in ticks.
    pub const fn new(time_to_alert_ticks: u64) -> Self {
        AlertMonitor {
            time_to_alert_ticks,
            last: AlarmOutput::NoValidEpoch,
            valid_at_ticks: 0,
        }
    }

    /// An epoch was processed at `now_ticks`: its decision, or `None` when
    /// it was answered with a typed error.
    pub fn on_epoch(&mut self, now_ticks: u64, decision: Option<Decision>) {
        self.last = match decision {
            Some(Decision::Ok | Decision::Excluded) => {
                self.valid_at_ticks = now_ticks;
                AlarmOutput::Clear
            }
            Some(Decision::Alarm) => AlarmOutput::Alarm,
            Some(Decision::Unavailable) => AlarmOutput::Unavailable,
            None => AlarmOutput::EpochError,
        };
    }

    /// The output at `now_ticks`. A clock that reads earlier than the last
    /// valid epoch (it cannot, unless it is broken) counts as expired.
    pub fn output(&self, now_ticks: u64) -> AlarmOutput {
        if self.last != AlarmOutput::Clear {
            return self.last;
        }
        match now_ticks.checked_sub(self.valid_at_ticks) {
            Some(age) if age < self.time_to_alert_ticks => AlarmOutput::Clear,
            _ => AlarmOutput::TimeToAlertExceeded,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TTA: u64 = 1000;

    /// Verifies: SAFE-ALARM
    #[test]
    fn asserted_from_boot_until_a_valid_epoch_and_again_after_the_time_to_alert() {
        let mut m = AlertMonitor::new(TTA);
        assert_eq!(m.output(0), AlarmOutput::NoValidEpoch);
        assert_eq!(m.output(10 * TTA), AlarmOutput::NoValidEpoch);
        m.on_epoch(5000, Some(Decision::Ok));
        assert_eq!(m.output(5000), AlarmOutput::Clear);
        assert_eq!(m.output(5000 + TTA - 1), AlarmOutput::Clear);
        assert_eq!(m.output(5000 + TTA), AlarmOutput::TimeToAlertExceeded);
        assert!(m.output(5000 + TTA).asserted());
        // A clock that runs backwards is not trusted.
        assert_eq!(m.output(4999), AlarmOutput::TimeToAlertExceeded);
        m.on_epoch(7000, Some(Decision::Excluded));
        assert_eq!(m.output(7001), AlarmOutput::Clear);
        assert!(!m.output(7001).asserted());
    }

    /// Verifies: SAFE-ALARM
    #[test]
    fn alarm_unavailable_and_errors_assert_at_once_whatever_the_time() {
        let mut m = AlertMonitor::new(TTA);
        for (d, want) in [
            (Some(Decision::Alarm), AlarmOutput::Alarm),
            (Some(Decision::Unavailable), AlarmOutput::Unavailable),
            (None, AlarmOutput::EpochError),
        ] {
            m.on_epoch(100, Some(Decision::Ok));
            assert_eq!(m.output(100), AlarmOutput::Clear);
            m.on_epoch(101, d);
            assert_eq!(m.output(101), want);
            assert!(want.asserted());
            // A later valid epoch clears it.
            m.on_epoch(102, Some(Decision::Ok));
            assert_eq!(m.output(102), AlarmOutput::Clear);
        }
    }
}
