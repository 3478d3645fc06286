//! The one gate every state-changing request passes, in this order: the
//! part exists in this build, the lock, the authentication (the tag under
//! the key and this boot's nonce, the counter's range, then the counter
//! against replay), then the part's own checks. Only then is the part put
//! in force, and the fingerprint follows what is in force.
//!
//! The rule (docs/SAFETY.md "Configuration authority"): a provisioned unit
//! runs its provisioned configuration, locked, from boot, and takes no
//! change until reset; a unit whose provisioned section is present but
//! refused at boot (a bad seal, an erased key under a sealed section, a
//! part that fails its checks) takes no change either and stays
//! Unconfigured (it is an installed unit whose installation failed, never
//! a bench unit); an unprovisioned unit takes runtime changes (bench
//! use), authenticated when it holds a key, until it is locked, and
//! `Lock` only once a configuration is in force; runtime changes are
//! volatile, so a reset returns the unit to its provisioned configuration
//! or to none.

use raim_proto::araim_msg::AraimAnswer;
use raim_proto::auth::{Authenticated, Change};
use raim_proto::error::WireError;
use raim_proto::lock::ConfigSource;
use raim_proto::message::ResponseBody;
use raim_proto::unit::{UnitConfig, UnitPart};

use crate::Server;

/// Why a unit configuration is refused: the first part that fails its
/// checks, and that part's own typed error (the one a runtime change of
/// the part gets).
#[derive(Debug, Clone, PartialEq)]
pub struct UnitRefusal {
    /// The part refused (the boot notice's `InvalidPart`).
    pub part: UnitPart,
    /// Its own check's typed error.
    pub error: WireError,
}

/// Every part of a unit configuration checked, as the gate checks a
/// runtime change of that part; the first part that fails. The one
/// validation of a unit configuration: boot ([`Server::provision`]) puts
/// nothing in force that fails it, and `raim provision` refuses to seal
/// what fails it (issue 35), with the same part and error. The checks
/// that depend on the build are this build's: without the `araim`
/// feature an ARAIM part is refused `Araim(Disabled)`, without `pf` a PF
/// part `PfUnavailable`.
pub fn check_unit(unit: &UnitConfig) -> Result<(), UnitRefusal> {
    let refuse = |part: UnitPart| move |error: WireError| UnitRefusal { part, error };
    if let Some(c) = &unit.snapshot {
        c.validate()
            .map_err(|e| refuse(UnitPart::Snapshot)(e.into()))?;
    }
    if let Some(i) = &unit.araim {
        if !cfg!(feature = "araim") {
            return Err(refuse(UnitPart::Araim)(WireError::Araim(
                raim_proto::araim_msg::AraimWireError::Disabled,
            )));
        }
        crate::araim::check_ism(i).map_err(refuse(UnitPart::Araim))?;
    }
    if let Some(p) = &unit.pf {
        crate::pf::check(p).map_err(refuse(UnitPart::Pf))?;
    }
    unit.model_check
        .check()
        .map_err(refuse(UnitPart::ModelCheck))?;
    Ok(())
}

/// What a change that passed the gate answers (small: the answer's
/// `ResponseBody` is built by the caller, whose frame holds one anyway).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Applied {
    Configured,
    IsmAccepted { satellites: u32 },
    LockEngaged,
}

impl Applied {
    /// The answer on the wire.
    pub(crate) fn body(r: Result<Applied, WireError>) -> ResponseBody {
        match r {
            Ok(Applied::Configured) => ResponseBody::Configured,
            Ok(Applied::IsmAccepted { satellites }) => {
                ResponseBody::Araim(AraimAnswer::IsmAccepted { satellites })
            }
            Ok(Applied::LockEngaged) => ResponseBody::LockEngaged,
            Err(e) => ResponseBody::Error(e),
        }
    }
}

impl Server {
    /// A plain state-changing request.
    pub(crate) fn change_plain(&mut self, change: &Change) -> Result<Applied, WireError> {
        self.change(None, change)
    }

    /// An authenticated state-changing request.
    pub(crate) fn change_authenticated(&mut self, a: &Authenticated) -> Result<Applied, WireError> {
        self.change(Some((a.counter, &a.tag)), &a.change)
    }

    /// Passes `change` through the gate and, if every check holds, puts it
    /// in force; what it answers, or the first check that failed, typed.
    /// On a refusal nothing changes.
    #[inline(never)]
    fn change(
        &mut self,
        signed: Option<(u64, &raim_proto::auth::Tag)>,
        change: &Change,
    ) -> Result<Applied, WireError> {
        let counter = self.gate(signed, change)?;
        let applied = self.apply(change)?;
        if let (Some(c), Some((key, _))) = (counter, self.auth) {
            self.auth = Some((key, Some(c)));
        }
        Ok(applied)
    }

    /// The build, the lock and the authentication; the counter to record
    /// once the change is in force.
    fn gate(
        &self,
        signed: Option<(u64, &raim_proto::auth::Tag)>,
        change: &Change,
    ) -> Result<Option<u64>, WireError> {
        if !cfg!(feature = "araim") && matches!(change, Change::Ism(_)) {
            return Err(WireError::Araim(
                raim_proto::araim_msg::AraimWireError::Disabled,
            ));
        }
        // A provisioned section refused at boot: fail safe until reset,
        // whatever the change and whoever sends it (issue 35: erasing the
        // key must not make a sealed unit an open bench unit).
        if let Some(e) = self.provision_error {
            return Err(WireError::Unconfigured { provision: Some(e) });
        }
        if self.config_id.locked {
            return Err(WireError::Locked {
                fingerprint: self.config_id.fingerprint,
            });
        }
        match (self.auth, signed) {
            (None, None) => Ok(None),
            (Some(_), None) => Err(WireError::AuthRequired),
            (None, Some(_)) => Err(WireError::AuthNotProvisioned),
            (Some((key, last)), Some((counter, tag))) => {
                // No boot count this boot: the nonce may repeat an
                // earlier power-on's, so a recorded frame could verify.
                if let raim_proto::boot_counter::BootCounterStatus::Failed(error) =
                    self.boot_counter
                {
                    return Err(WireError::BootCounter { error });
                }
                if !raim_proto::auth::verify(&key, &self.nonce, counter, change, tag) {
                    return Err(WireError::BadAuthTag { counter });
                }
                if counter == u64::MAX {
                    return Err(WireError::CounterExhausted { counter });
                }
                match last {
                    Some(l) if counter <= l => Err(WireError::Replayed { counter, last: l }),
                    _ => Ok(Some(counter)),
                }
            }
        }
    }

    /// The part's own checks, then the part in force and the fingerprint
    /// updated (it covers every part in force).
    fn apply(&mut self, change: &Change) -> Result<Applied, WireError> {
        let applied = match change {
            Change::Configure(c) => {
                c.validate()?;
                self.config = Some(*c);
                Applied::Configured
            }
            Change::Ism(frame) => Applied::IsmAccepted {
                satellites: self.take_ism(frame)?,
            },
            Change::Pf(c) => {
                self.pf.configure(*c)?;
                Applied::Configured
            }
            Change::HostSigmas(on) => {
                self.host_sigmas = *on;
                Applied::Configured
            }
            Change::ModelCheck(c) => {
                self.model.configure(*c)?;
                Applied::Configured
            }
            // Locking a unit with nothing in force would leave it
            // Unconfigured and deaf to every change until a reset (issue
            // 35): refused, typed, until a configuration is in force.
            Change::Lock if self.config_id.source == ConfigSource::Unconfigured => {
                return Err(WireError::Unconfigured { provision: None });
            }
            Change::Lock => {
                self.config_id.locked = true;
                return Ok(Applied::LockEngaged);
            }
        };
        self.config_id.source = ConfigSource::Runtime;
        self.config_id.fingerprint = self.fingerprint();
        // A new model is in force: the model check starts again.
        self.model.reset();
        Ok(applied)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use raim_core::Config;
    use raim_proto::auth::{tag, Authenticated, Change};

    const KEY: raim_proto::auth::AuthKey = [7; 32];

    fn signed(s: &Server, key: &raim_proto::auth::AuthKey, counter: u64) -> Authenticated {
        let change = Change::Configure(Config::default());
        Authenticated {
            counter,
            tag: tag(key, &s.nonce(), counter, &change),
            change,
        }
    }

    /// The authentication's typed refusals, in the gate's order: a signed
    /// change to an unkeyed unit, an unsigned one to a keyed unit, a tag
    /// that does not verify, a counter not above the last accepted one;
    /// and nothing changes on any of them (docs/SAFETY.md threat model #4).
    ///
    /// Verifies: WIRE-AuthNotProvisioned, WIRE-AuthRequired, WIRE-BadAuthTag, WIRE-Replayed, SAFE-T4
    #[test]
    fn authentication_refusals_are_typed_and_change_nothing() {
        crate::tests::on_big_stack(authentication_refusals);
    }

    fn authentication_refusals() {
        let mut open = std::boxed::Box::new(Server::new());
        let a = signed(&open, &KEY, 1);
        assert_eq!(
            open.change_authenticated(&a),
            Err(WireError::AuthNotProvisioned)
        );
        assert_eq!(open.config, None);

        let mut keyed = std::boxed::Box::new(Server::with_auth_key(KEY));
        assert_eq!(
            keyed.change_plain(&Change::Configure(Config::default())),
            Err(WireError::AuthRequired)
        );
        let forged = signed(&keyed, &[8; 32], 1);
        assert_eq!(
            keyed.change_authenticated(&forged),
            Err(WireError::BadAuthTag { counter: 1 })
        );
        assert_eq!(keyed.config, None);
        let first = signed(&keyed, &KEY, 5);
        assert_eq!(keyed.change_authenticated(&first), Ok(Applied::Configured));
        let fingerprint = keyed.config_id.fingerprint;
        for counter in [5, 4] {
            let again = signed(&keyed, &KEY, counter);
            assert_eq!(
                keyed.change_authenticated(&again),
                Err(WireError::Replayed { counter, last: 5 })
            );
        }
        assert_eq!(keyed.config_id.fingerprint, fingerprint);
        let next = signed(&keyed, &KEY, 6);
        assert_eq!(keyed.change_authenticated(&next), Ok(Applied::Configured));
    }
    /// Issue 35: an unkeyed, Unconfigured unit refuses `Lock` (typed,
    /// `Unconfigured`, nothing changes) until a configuration is in force;
    /// then `Lock` is taken. A host could otherwise lock a unit that can
    /// only answer `Unconfigured`, deaf to every change until a reset.
    ///
    /// Verifies: SAFE-LOCK-UNCONFIGURED
    #[test]
    fn lock_is_refused_until_a_configuration_is_in_force() {
        crate::tests::on_big_stack(lock_refused_until_configured);
    }

    fn lock_refused_until_configured() {
        let mut open = std::boxed::Box::new(Server::new());
        let before = open.config_id;
        assert_eq!(
            open.change_plain(&Change::Lock),
            Err(WireError::Unconfigured { provision: None })
        );
        assert_eq!(open.config_id, before);
        assert!(!open.config_id.locked);
        assert_eq!(
            open.change_plain(&Change::Configure(Config::default())),
            Ok(Applied::Configured)
        );
        assert_eq!(open.change_plain(&Change::Lock), Ok(Applied::LockEngaged));
        assert!(open.config_id.locked);
    }

    /// Issue 35: a unit whose provisioned section is present but refused
    /// (a sealed section read without its key: `BadSeal`; any corrupt
    /// section) never becomes an open bench unit: it boots Unconfigured
    /// and locked, refuses every change, plain or authenticated, with the
    /// reason (`Unconfigured { provision }`), and `Status` says why.
    ///
    /// Verifies: SAFE-SEALED-NO-KEY
    #[test]
    fn a_refused_provisioned_section_takes_no_change() {
        crate::tests::on_big_stack(refused_section_takes_no_change);
    }

    fn refused_section_takes_no_change() {
        let entropy = raim_proto::auth::BootEntropy {
            bytes: [3; 32],
            hardware: false,
        };
        for e in [
            raim_proto::unit::ProvisionError::BadSeal,
            raim_proto::unit::ProvisionError::BadMagic,
            raim_proto::unit::ProvisionError::InvalidPart(raim_proto::unit::UnitPart::Snapshot),
        ] {
            let refused = WireError::Unconfigured { provision: Some(e) };
            let mut unit = std::boxed::Box::new(Server::new());
            unit.boot(Err(e), 0, &entropy);
            assert_eq!(unit.config_id.source, ConfigSource::Unconfigured);
            assert!(unit.config_id.locked);
            let st = unit.status();
            assert_eq!(st.provision_error, Some(e));
            assert!(st.config.locked);
            for change in [
                Change::Configure(Config::default()),
                Change::Lock,
                Change::HostSigmas(true),
            ] {
                assert_eq!(unit.change_plain(&change), Err(refused.clone()));
            }
            assert_eq!(unit.config, None);
            // The same with a key: an authenticated change is refused too.
            let mut keyed = std::boxed::Box::new(Server::with_auth_key(KEY));
            keyed.boot(Err(e), 0, &entropy);
            let a = signed(&keyed, &KEY, 1);
            assert_eq!(keyed.change_authenticated(&a), Err(refused));
            assert_eq!(keyed.config, None);
        }
        // An erased section is a bench unit: open, and it takes changes.
        let mut bench = std::boxed::Box::new(Server::new());
        bench.boot(Ok(None), 0, &entropy);
        assert!(!bench.config_id.locked);
        assert_eq!(
            bench.change_plain(&Change::Configure(Config::default())),
            Ok(Applied::Configured)
        );
    }
}
