//! Authenticated configuration frames (issue 15), an option: with a key
//! provisioned (`Server::with_auth_key`), a configuration is accepted only
//! as `AuthConfigure { counter, config, tag }` where
//! `tag = HMAC-SHA256(key, "raim-configure-v1" || counter (u64 LE) ||
//! postcard(config))` and `counter` is above every counter accepted since
//! boot, so that a recorded frame cannot be replayed. Plain `Configure` is
//! then refused. The `hmac` and `sha2` crates (RustCrypto, no_std).

use hmac::{Hmac, Mac};
use raim_core::Config;
use serde::{Deserialize, Serialize};
use sha2::Sha256;

/// A provisioned key.
pub type AuthKey = [u8; 32];
/// An HMAC-SHA256 tag.
pub type Tag = [u8; 32];

const DOMAIN: &[u8] = b"raim-configure-v1";
const CONFIG_BYTES: usize = 256;

/// An authenticated configuration (the payload of `Command::AuthConfigure`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AuthConfigure {
    /// Replay counter, above every one accepted since boot.
    pub counter: u64,
    /// The configuration.
    pub config: Config,
    /// HMAC-SHA256 tag over the counter and the configuration.
    pub tag: Tag,
}

fn mac(key: &AuthKey, counter: u64, cfg: &Config) -> Option<Hmac<Sha256>> {
    let mut buf = [0u8; CONFIG_BYTES];
    let bytes = postcard::to_slice(cfg, &mut buf).ok()?;
    let mut m = <Hmac<Sha256> as Mac>::new_from_slice(key).ok()?;
    m.update(DOMAIN);
    m.update(&counter.to_le_bytes());
    m.update(bytes);
    Some(m)
}

/// The tag of `(counter, cfg)` under `key` (the host side).
pub fn tag(key: &AuthKey, counter: u64, cfg: &Config) -> Tag {
    mac(key, counter, cfg)
        .map(|m| m.finalize().into_bytes().into())
        .unwrap_or([0; 32])
}

/// Constant-time check of `tag` (the unit side).
pub fn verify(key: &AuthKey, counter: u64, cfg: &Config, tag: &Tag) -> bool {
    mac(key, counter, cfg).is_some_and(|m| m.verify_slice(tag).is_ok())
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

    #[test]
    fn tag_binds_key_counter_and_config() {
        let key = [7u8; 32];
        let c = Config::default();
        let t = tag(&key, 5, &c);
        assert!(verify(&key, 5, &c, &t));
        assert!(!verify(&key, 6, &c, &t));
        assert!(!verify(&[8u8; 32], 5, &c, &t));
        assert!(!verify(&key, 5, &Config { pfa: 1e-6, ..c }, &t));
    }
}
