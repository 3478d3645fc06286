//! Authenticated state-changing requests. On a unit with a provisioned key
//! every request that changes what the unit runs, or locks it, must come as
//! [`Authenticated`] `{ counter, change, tag }` where
//!
//! `tag = HMAC-SHA256(key, "raim-change-v2" || nonce || counter (u64 LE) ||
//! postcard(change))`.
//!
//! - `nonce` is the unit's boot nonce (16 bytes), announced in its boot
//!   notice and in every `Status`, new at every reset: a frame recorded
//!   before a reset does not verify after it.
//! - `counter` must be above every counter accepted since boot (no replay
//!   within a boot), and below `u64::MAX` (a counter at the top of its range
//!   would leave no room for the next change, so it is refused).
//!
//! The `hmac` and `sha2` crates (RustCrypto, no_std).

use hmac::{Hmac, Mac};
use raim_core::Config;
use serde::{Deserialize, Serialize};
use sha2::Sha256;

use crate::araim_msg::{IsmFrame, IsmFrameRef};
use crate::model_check_msg::WireModelCheckConfig;
use crate::pf_msg::WirePfConfig;

/// A provisioned key.
pub type AuthKey = [u8; 32];
/// An HMAC-SHA256 tag.
pub type Tag = [u8; 32];
/// The unit's boot nonce.
pub type Nonce = [u8; 16];

const DOMAIN: &[u8] = b"raim-change-v2";

/// What an authenticated request changes.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Change {
    /// Replace the snapshot configuration (as `Command::Configure`).
    Configure(Config),
    /// Replace the ISM and ARAIM configuration (as `AraimCommand::Ism`).
    Ism(IsmFrame),
    /// Replace the particle-filter configuration (as `PfConfigure`).
    Pf(WirePfConfig),
    /// Lock what is in force until reset (as `Command::Lock`).
    Lock,
    /// Whether epoch frames' per-satellite sigmas are used (as
    /// `Command::HostSigmas`).
    HostSigmas(bool),
    /// Replace the model check's settings (as `Command::ModelCheck`).
    ModelCheck(WireModelCheckConfig),
}

/// The host's borrowed form of [`Change`] (same bytes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum ChangeRef<'a> {
    /// [`Change::Configure`].
    Configure(&'a Config),
    /// [`Change::Ism`].
    Ism(IsmFrameRef<'a>),
    /// [`Change::Pf`].
    Pf(&'a WirePfConfig),
    /// [`Change::Lock`].
    Lock,
    /// [`Change::HostSigmas`].
    HostSigmas(bool),
    /// [`Change::ModelCheck`].
    ModelCheck(WireModelCheckConfig),
}

/// An authenticated change (the payload of `Command::Authenticated`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Authenticated {
    /// Above every counter accepted since boot, below `u64::MAX`.
    pub counter: u64,
    /// What the request changes.
    pub change: Change,
    /// HMAC-SHA256 over the nonce, the counter and the change ([`tag`]).
    pub tag: Tag,
}

/// The host's borrowed form of [`Authenticated`] (same bytes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AuthenticatedRef<'a> {
    /// [`Authenticated::counter`].
    pub counter: u64,
    /// [`Authenticated::change`].
    pub change: ChangeRef<'a>,
    /// [`Authenticated::tag`].
    pub tag: Tag,
}

/// A postcard flavor that feeds an HMAC (no buffer).
struct MacFlavor(Hmac<Sha256>);

impl postcard::ser_flavors::Flavor for MacFlavor {
    type Output = Hmac<Sha256>;
    fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
        self.0.update(data);
        Ok(())
    }
    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        self.0.update(&[data]);
        Ok(())
    }
    fn finalize(self) -> postcard::Result<Self::Output> {
        Ok(self.0)
    }
}

fn mac<T: Serialize>(
    key: &AuthKey,
    nonce: &Nonce,
    counter: u64,
    change: &T,
) -> Option<Hmac<Sha256>> {
    let mut m = <Hmac<Sha256> as Mac>::new_from_slice(key).ok()?;
    m.update(DOMAIN);
    m.update(nonce);
    m.update(&counter.to_le_bytes());
    postcard::serialize_with_flavor(change, MacFlavor(m)).ok()
}

/// The tag of `(nonce, counter, change)` under `key` (the host side;
/// `change` is a [`Change`] or a [`ChangeRef`], which encode alike).
pub fn tag<T: Serialize>(key: &AuthKey, nonce: &Nonce, counter: u64, change: &T) -> Tag {
    mac(key, nonce, counter, change)
        .map(|m| m.finalize().into_bytes().into())
        .unwrap_or([0; 32])
}

/// Constant-time check of `tag` (the unit side).
pub fn verify(key: &AuthKey, nonce: &Nonce, counter: u64, change: &Change, tag: &Tag) -> bool {
    mac(key, nonce, counter, change).is_some_and(|m| m.verify_slice(tag).is_ok())
}

/// What a platform gives its boot nonce: 32 bytes that should differ from
/// boot to boot, and whether a hardware random source (the STM32F4's RNG)
/// went into them. Without one, the bytes may repeat across power cycles
/// (QEMU's zeroed SRAM), and so may the nonce (docs/SAFETY.md "Boot nonce").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BootEntropy {
    /// The bytes, hashed into the nonce ([`boot_nonce`]).
    pub bytes: [u8; 32],
    /// True when a hardware random source's output is in `bytes`.
    pub hardware: bool,
}

/// The unit's boot nonce from its key (or none) and what differs between
/// boots: the reset count, the boot counter in flash (when the platform
/// keeps one: `boot_counter`, a new value at every boot, power cycles
/// included) and the platform's entropy. SHA-256 of them, first 16 bytes;
/// a new value at every reset whenever the reset count, the boot count or
/// the entropy changes.
pub fn boot_nonce(
    key: Option<&AuthKey>,
    resets: u32,
    boot_count: Option<u32>,
    entropy: &[u8; 32],
) -> Nonce {
    use sha2::Digest;
    let mut h = Sha256::new();
    h.update(b"raim-boot-nonce-v1");
    if let Some(k) = key {
        h.update(k);
    }
    h.update(resets.to_le_bytes());
    if let Some(n) = boot_count {
        h.update(b"boot-count");
        h.update(n.to_le_bytes());
    }
    h.update(entropy);
    let d: [u8; 32] = h.finalize().into();
    let mut n = [0u8; 16];
    n.copy_from_slice(d.get(..16).unwrap_or(&[0; 16]));
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RFC 4231 test case 2 through the same crates: HMAC-SHA256 with key
    /// "Jefe" of "what do ya want for nothing?".
    #[test]
    fn hmac_sha256_matches_rfc_4231() {
        let mut m = <Hmac<Sha256> as Mac>::new_from_slice(b"Jefe").unwrap();
        m.update(b"what do ya want for nothing?");
        let got: [u8; 32] = m.finalize().into_bytes().into();
        let want: [u8; 32] = [
            0x5b, 0xdc, 0xc1, 0x46, 0xbf, 0x60, 0x75, 0x4e, 0x6a, 0x04, 0x24, 0x26, 0x08, 0x95,
            0x75, 0xc7, 0x5a, 0x00, 0x3f, 0x08, 0x9d, 0x27, 0x39, 0x83, 0x9d, 0xec, 0x58, 0xb9,
            0x64, 0xec, 0x38, 0x43,
        ];
        assert_eq!(got, want);
    }

    /// Verifies: SAFE-T4
    #[test]
    fn tag_binds_key_nonce_counter_and_change() {
        let key = [7u8; 32];
        let nonce = [1u8; 16];
        let c = Config::default();
        let change = Change::Configure(c);
        let t = tag(&key, &nonce, 5, &ChangeRef::Configure(&c));
        assert!(verify(&key, &nonce, 5, &change, &t));
        assert!(!verify(&key, &[2u8; 16], 5, &change, &t));
        assert!(!verify(&key, &nonce, 6, &change, &t));
        assert!(!verify(&[8u8; 32], &nonce, 5, &change, &t));
        let other = Change::Configure(Config { pfa: 1e-6, ..c });
        assert!(!verify(&key, &nonce, 5, &other, &t));
        assert!(!verify(&key, &nonce, 5, &Change::Lock, &t));
        let lock = tag(&key, &nonce, 5, &ChangeRef::Lock);
        assert!(verify(&key, &nonce, 5, &Change::Lock, &lock));
    }

    #[test]
    fn boot_nonce_changes_with_resets_entropy_and_key() {
        let e = [9u8; 32];
        let n0 = boot_nonce(None, 0, None, &e);
        assert_ne!(n0, boot_nonce(None, 1, None, &e));
        assert_ne!(n0, boot_nonce(None, 0, None, &[8u8; 32]));
        assert_ne!(n0, boot_nonce(Some(&[1; 32]), 0, None, &e));
        assert_eq!(n0, boot_nonce(None, 0, None, &e));
        // The boot counter: every value its own nonce, none equal to the
        // nonce without one.
        let n1 = boot_nonce(None, 0, Some(1), &e);
        assert_ne!(n0, n1);
        assert_ne!(n1, boot_nonce(None, 0, Some(2), &e));
        assert_eq!(n1, boot_nonce(None, 0, Some(1), &e));
    }
}
