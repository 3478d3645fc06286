//! The configuration lock and fingerprint (issue 15, docs/PROTOCOL.md
//! "Lock and fingerprint").
//!
//! After a `Lock` request, or from boot in a build whose configuration is
//! compiled in (`Server::new_locked`), every `Configure` is refused with
//! `WireError::Locked`; only a reset unlocks. Every response carries a
//! [`ConfigId`]: the CRC-32 of the configuration in force and the lock
//! state, so the host can check what the unit runs.

use raim_core::Config;
use serde::{Deserialize, Serialize};

use crate::frame::CRC32;

/// Larger than the postcard encoding of any `Config` (~140 bytes: 14 f64,
/// the rule, flags and varints).
const CONFIG_BYTES: usize = 256;

/// The configuration in force, by fingerprint, and whether it can change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConfigId {
    /// CRC-32/ISO-HDLC of the configuration's postcard encoding (the bytes
    /// a `Configure` frame carries): [`config_fingerprint`].
    pub crc32: u32,
    /// `Configure` is refused until reset.
    pub locked: bool,
}

/// CRC-32/ISO-HDLC (the frames' CRC) of `postcard(cfg)`. The host computes
/// the same from the configuration it sent. 0 if the configuration did not
/// fit the buffer (it always does: test `every_config_fits`).
pub fn config_fingerprint(cfg: &Config) -> u32 {
    let mut buf = [0u8; CONFIG_BYTES];
    match postcard::to_slice(cfg, &mut buf) {
        Ok(bytes) => CRC32.checksum(bytes),
        Err(_) => 0,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use raim_core::{FiRule, Phase};

    /// Bitwise CRC-32 (reflected, polynomial 0xEDB88320, init and xorout
    /// all ones): an independent implementation of CRC-32/ISO-HDLC.
    fn crc32_bitwise(data: &[u8]) -> u32 {
        let mut crc = 0xFFFF_FFFFu32;
        for &b in data {
            crc ^= u32::from(b);
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xEDB8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }

    #[test]
    fn every_config_fits() {
        let big = Config {
            rule: FiRule::LraimGaussian { kappa: 1e12 },
            max_iterations: u32::MAX,
            alert: raim_core::AlertLimits {
                hal_m: 1.0,
                val_m: Some(1.0),
            },
            ..Config::default().split_false_alarm_budget(0.5)
        };
        let mut buf = [0u8; CONFIG_BYTES];
        let n = postcard::to_slice(&big, &mut buf).unwrap().len();
        // 131 bytes: every field at its widest encoding, with room to grow.
        assert!(n + 64 <= CONFIG_BYTES, "{n}");
    }

    /// The fingerprint is the catalogue CRC-32 of the postcard bytes
    /// (check value 0xCBF43926 of "123456789"), and any change of a field
    /// changes it.
    #[test]
    fn fingerprint_is_the_crc_of_the_encoded_config() {
        assert_eq!(crc32_bitwise(b"123456789"), 0xCBF4_3926);
        let c = Config::default();
        let mut buf = [0u8; CONFIG_BYTES];
        let bytes = postcard::to_slice(&c, &mut buf).unwrap();
        assert_eq!(config_fingerprint(&c), crc32_bitwise(bytes));
        let variants = [
            Config::preset(Phase::EnRoute),
            Config::preset(Phase::Terminal),
            Config { pfa: 1e-7, ..c },
            Config { pmd: 1e-4, ..c },
            Config {
                rule: FiRule::Mle,
                ..c
            },
            Config {
                max_exclusions: 1,
                ..c
            },
            Config {
                require_unique_exclusion: false,
                ..c
            },
        ];
        let fp = config_fingerprint(&c);
        for (i, v) in variants.iter().enumerate() {
            assert_ne!(config_fingerprint(v), fp, "variant {i}");
        }
    }
}
