//! The one gate every state-changing request passes, in this order: the
//! part exists in this build, the lock, the authentication (the tag under
//! the key and this boot's nonce, the counter's range, then the counter
//! against replay), then the part's own checks. Only then is the part put
//! in force, and the fingerprint follows what is in force.
//!
//! The rule (docs/SAFETY.md "Configuration authority"): a provisioned unit
//! runs its provisioned configuration, locked, from boot, and takes no
//! change until reset; an unprovisioned unit takes runtime changes (bench
//! use), authenticated when it holds a key, until it is locked; runtime
//! changes are volatile, so a reset returns the unit to its provisioned
//! configuration or to none.

use raim_proto::auth::{Authenticated, Change};
use raim_proto::error::WireError;
use raim_proto::lock::ConfigSource;
use raim_proto::message::ResponseBody;
use raim_proto::unit::{UnitConfig, UnitPart};

use crate::Server;

/// Every part of a unit configuration checked, as the gate checks a
/// runtime change of that part; the first part that fails.
pub(crate) fn check_unit(unit: &UnitConfig) -> Result<(), UnitPart> {
    if let Some(c) = &unit.snapshot {
        c.validate().map_err(|_| UnitPart::Snapshot)?;
    }
    if let Some(i) = &unit.araim {
        if !cfg!(feature = "araim") {
            return Err(UnitPart::Araim);
        }
        crate::araim::check_ism(i).map_err(|_| UnitPart::Araim)?;
    }
    if let Some(p) = &unit.pf {
        crate::pf::check(p).map_err(|_| UnitPart::Pf)?;
    }
    Ok(())
}

impl Server {
    /// A plain state-changing request.
    pub(crate) fn change_plain(&mut self, change: Change) -> ResponseBody {
        self.change(None, change)
    }

    /// An authenticated state-changing request.
    pub(crate) fn change_authenticated(&mut self, a: Authenticated) -> ResponseBody {
        let Authenticated {
            counter,
            change,
            tag,
        } = a;
        self.change(Some((counter, tag)), change)
    }

    /// Passes `change` through the gate and, if every check holds, puts it
    /// in force; the answer, or the first check that failed, typed. On a
    /// refusal nothing changes.
    fn change(
        &mut self,
        signed: Option<(u64, raim_proto::auth::Tag)>,
        change: Change,
    ) -> ResponseBody {
        let r = self.gate(signed, &change).and_then(|counter| {
            let body = self.apply(change)?;
            if let (Some(c), Some((key, _))) = (counter, self.auth) {
                self.auth = Some((key, Some(c)));
            }
            Ok(body)
        });
        r.unwrap_or_else(ResponseBody::Error)
    }

    /// The build, the lock and the authentication; the counter to record
    /// once the change is in force.
    fn gate(
        &self,
        signed: Option<(u64, raim_proto::auth::Tag)>,
        change: &Change,
    ) -> Result<Option<u64>, WireError> {
        if !cfg!(feature = "araim") && matches!(change, Change::Ism(_)) {
            return Err(WireError::Araim(
                raim_proto::araim_msg::AraimWireError::Disabled,
            ));
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
                if !raim_proto::auth::verify(&key, &self.nonce, counter, change, &tag) {
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
    fn apply(&mut self, change: Change) -> Result<ResponseBody, WireError> {
        let body = match change {
            Change::Configure(c) => {
                c.validate()?;
                self.config = Some(c);
                ResponseBody::Configured
            }
            Change::Ism(frame) => ResponseBody::Araim(self.take_ism(frame)?),
            Change::Pf(c) => {
                self.pf.configure(c)?;
                ResponseBody::Configured
            }
            Change::HostSigmas(on) => {
                self.host_sigmas = on;
                ResponseBody::Configured
            }
            Change::Lock => {
                self.config_id.locked = true;
                return Ok(ResponseBody::LockEngaged);
            }
        };
        self.config_id.source = ConfigSource::Runtime;
        self.config_id.fingerprint = self.fingerprint();
        Ok(body)
    }
}
