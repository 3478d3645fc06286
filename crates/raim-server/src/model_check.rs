//! The unit's run-time model check (issue 35, docs/MODEL_CHECK.md): the
//! core's windowed chi-square goodness of fit
//! (`raim_core::consistency::ModelCheck`) driven by every answered epoch of
//! the snapshot monitor and of ARAIM, with the allocation, spacing and
//! window of the unit configuration's `model_check` part
//! (`raim_proto::model_check_msg`; the defaults 1e-6 false declarations
//! per hour, 1,800 s and 8 samples when the configuration does not set
//! them).
//!
//! - **Sample:** the delivered solution's q = r^T W r and its dof (the
//!   snapshot monitor's sigma model; ARAIM's C_acc), not of an `Alarm`
//!   epoch, which delivers no solution. An offer the check refuses (a time
//!   not after the last offer: the snapshot monitor is stateless and takes
//!   one) is no sample; the latch stays.
//! - **Broken:** once a window has rejected, the error model in force
//!   understates the errors, so no protection level computed with it is a
//!   bound: every epoch from then on is answered `Unavailable` (the alarm
//!   output asserted, the NMEA sentences without a fix), an `Alarm` stays
//!   an `Alarm`, until a new configuration, ISM, model-check setting or
//!   provisioned section is put in force (`reset`). `Status.model_check`
//!   says so.
//! - The particle filter is not checked: its epochs never clear the alarm
//!   output (docs/PF.md "No protection level").

use raim_core::consistency::{ModelCheck, ModelCheckConfig};
use raim_core::Decision;
use raim_proto::message::ModelCheckStatus;
use raim_proto::model_check_msg::{WireModelCheckConfig, MAX_WINDOW};

/// The check at the unit's capacity ([`MAX_WINDOW`] samples) and the
/// settings it runs with: the wire form (what the fingerprint covers) and
/// the core's, checked, form of the same values.
#[derive(Debug, Clone)]
pub struct UnitModelCheck {
    check: ModelCheck<MAX_WINDOW>,
    wire: WireModelCheckConfig,
    config: ModelCheckConfig,
}

impl Default for UnitModelCheck {
    fn default() -> Self {
        Self::new()
    }
}

impl UnitModelCheck {
    /// The check at the defaults (`ModelCheckConfig::DEFAULT`), nothing
    /// sampled.
    pub const fn new() -> Self {
        UnitModelCheck {
            check: ModelCheck::new(),
            wire: WireModelCheckConfig::DEFAULT,
            config: ModelCheckConfig::DEFAULT,
        }
    }

    /// Puts `wire` in force if every field is within its bounds
    /// (`WireModelCheckConfig::check`) and restarts the check; otherwise
    /// the typed error, and nothing changes.
    ///
    /// # Errors
    /// The first field out of its bounds, with its value.
    pub fn configure(
        &mut self,
        wire: WireModelCheckConfig,
    ) -> Result<(), raim_proto::error::WireError> {
        self.config = wire.check()?;
        self.wire = wire;
        self.check.reset();
        Ok(())
    }

    /// Restarts the check (a new model in force); the settings stay.
    pub fn reset(&mut self) {
        self.check.reset();
    }

    /// The settings in force, as on the wire.
    pub fn settings(&self) -> &WireModelCheckConfig {
        &self.wire
    }

    /// The settings in force, as the core runs them.
    pub fn config(&self) -> &ModelCheckConfig {
        &self.config
    }

    /// Whether the model has been declared broken since the last reset.
    pub fn broken(&self) -> bool {
        self.check.broken()
    }
}

/// Offers an answered epoch's `sample` (q, dof) at `time_s`, and returns
/// the decision to answer with: `decision`, or `Unavailable` once the
/// model is declared broken (an `Alarm` stays an `Alarm`).
pub fn judge(
    unit: &mut UnitModelCheck,
    time_s: f64,
    sample: Option<(f64, u32)>,
    decision: Decision,
) -> Decision {
    if let Some((q, dof)) = sample {
        // A refused offer (time not increasing, a NaN) is no sample.
        let _ = unit.check.offer(&unit.config, time_s, q, dof);
    }
    if unit.check.broken() && decision != Decision::Alarm {
        Decision::Unavailable
    } else {
        decision
    }
}

/// The check's state for `Status`.
pub fn status(unit: &UnitModelCheck) -> ModelCheckStatus {
    let check = &unit.check;
    let n = |x: u64| u32::try_from(x).unwrap_or(u32::MAX);
    ModelCheckStatus {
        evaluations: n(check.evaluations()),
        rejections: n(check.rejections()),
        // An epoch time is in [0, 5.27e9] s (`EPOCH_TIME_S`); the cast
        // saturates.
        broken_at_ms: check.broken_at_s().map(|t| libm::round(t * 1000.0) as u64),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples at the model's own scale (q = dof) never break it; samples
    /// far above it (q = 25 dof: errors 5 sigma) do, within the window,
    /// and then every decision but `Alarm` becomes `Unavailable` until a
    /// reset.
    ///
    /// Verifies: SAFE-MODEL
    #[test]
    fn a_broken_model_makes_every_epoch_unavailable_until_a_reset() {
        let mut check = UnitModelCheck::new();
        let spacing_s = check.config().spacing_s;
        let mut t = 0.0;
        for _ in 0..20 {
            t += spacing_s;
            assert_eq!(
                judge(&mut check, t, Some((4.0, 4)), Decision::Ok),
                Decision::Ok
            );
        }
        assert!(!check.broken());
        // Between samples (closer than the spacing): skipped, no change.
        assert_eq!(
            judge(&mut check, t + 1.0, Some((1e9, 4)), Decision::Ok),
            Decision::Ok
        );
        check.reset();
        let mut t = 0.0;
        let mut broken_after = None;
        for k in 1..=raim_core::consistency::DEFAULT_WINDOW {
            t += spacing_s;
            if judge(&mut check, t, Some((100.0, 4)), Decision::Ok) == Decision::Unavailable {
                broken_after = Some(k);
                break;
            }
        }
        assert!(broken_after.is_some(), "not declared within the window");
        assert_eq!(status(&check).broken_at_ms, Some((t * 1000.0) as u64));
        // Latched: a good sample, no sample, an exclusion: Unavailable.
        t += spacing_s;
        assert_eq!(
            judge(&mut check, t, Some((4.0, 4)), Decision::Ok),
            Decision::Unavailable
        );
        assert_eq!(
            judge(&mut check, t + 1.0, None, Decision::Excluded),
            Decision::Unavailable
        );
        assert_eq!(
            judge(&mut check, t + 2.0, None, Decision::Alarm),
            Decision::Alarm
        );
        // A time going back is no sample and changes nothing.
        assert_eq!(
            judge(&mut check, 0.0, Some((4.0, 4)), Decision::Ok),
            Decision::Unavailable
        );
        check.reset();
        assert_eq!(
            judge(&mut check, t + 3.0, Some((4.0, 4)), Decision::Ok),
            Decision::Ok
        );
        assert_eq!(
            status(&check),
            ModelCheckStatus {
                evaluations: 1,
                rejections: 0,
                broken_at_ms: None,
            }
        );
    }
}
