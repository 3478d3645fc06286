//! The one gate every state-changing request passes, in this order: the
//! part exists in this build, the lock, the authentication (the tag, then
//! the counter against replay), then the part's own checks. Only then is
//! the part put in force, and the fingerprint follows what is in force.

use raim_core::Config;
#[cfg(not(feature = "araim"))]
use raim_proto::araim_msg::AraimWireError;
use raim_proto::araim_msg::IsmFrame;
use raim_proto::auth::Tag;
use raim_proto::error::WireError;
use raim_proto::message::ResponseBody;
use raim_proto::pf_msg::WirePfConfig;

use crate::Server;

/// A part of the unit's configuration that a request replaces.
pub(crate) enum Change {
    /// The snapshot configuration (`Configure`, `AuthConfigure`).
    Configure(Config),
    /// The ISM and ARAIM configuration (`Ism`, `AuthIsm`).
    Ism(IsmFrame),
    /// The particle-filter configuration (`PfConfigure`).
    Pf(WirePfConfig),
}

/// The authentication a request carries: its counter and HMAC tag.
pub(crate) struct Signed {
    counter: u64,
    tag: Tag,
}

impl Signed {
    pub(crate) fn configure(a: &raim_proto::auth::AuthConfigure) -> Self {
        Signed {
            counter: a.counter,
            tag: a.tag,
        }
    }
    pub(crate) fn ism(counter: u64, _ism: &IsmFrame, tag: Tag) -> Self {
        Signed { counter, tag }
    }
}

impl Server {
    /// Passes `change` through the gate and, if every check holds, puts it
    /// in force; the answer, or the first check that failed, typed. On a
    /// refusal nothing changes.
    pub(crate) fn change(&mut self, signed: Option<Signed>, change: Change) -> ResponseBody {
        let r = self.gate(signed.as_ref(), &change).and_then(|counter| {
            let body = self.apply(change)?;
            if let (Some(c), Some((key, _))) = (counter, self.auth) {
                self.auth = Some((key, Some(c)));
            }
            Ok(body)
        });
        r.unwrap_or_else(ResponseBody::Error)
    }

    /// The lock and the authentication; the counter to record once the
    /// change is in force.
    fn gate(&self, signed: Option<&Signed>, change: &Change) -> Result<Option<u64>, WireError> {
        #[cfg(not(feature = "araim"))]
        if matches!(change, Change::Ism(_)) {
            return Err(WireError::Araim(AraimWireError::Disabled));
        }
        if self.config_id.locked {
            return Err(WireError::Locked {
                config_crc32: self.config_id.crc32,
            });
        }
        match (self.auth, signed) {
            (None, None) => Ok(None),
            (Some(_), None) => Err(WireError::AuthRequired),
            (None, Some(_)) => Err(WireError::AuthNotProvisioned),
            (Some((key, last)), Some(s)) => {
                let genuine = match change {
                    Change::Configure(c) => raim_proto::auth::verify(&key, s.counter, c, &s.tag),
                    Change::Ism(i) => crate::araim::verify_ism(&key, s.counter, i, &s.tag),
                    // No authenticated form of `PfConfigure` exists.
                    Change::Pf(_) => false,
                };
                if !genuine {
                    return Err(WireError::BadAuthTag { counter: s.counter });
                }
                match last {
                    Some(l) if s.counter <= l => Err(WireError::Replayed {
                        counter: s.counter,
                        last: l,
                    }),
                    _ => Ok(Some(s.counter)),
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
                self.config = c;
                ResponseBody::Configured
            }
            Change::Ism(frame) => ResponseBody::Araim(self.take_ism(frame)?),
            Change::Pf(c) => {
                self.pf.configure(c)?;
                ResponseBody::Configured
            }
        };
        self.config_id.crc32 = self.fingerprint();
        Ok(body)
    }
}
