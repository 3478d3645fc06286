//! The unit configuration: every part the unit runs, in one value, with one
//! canonical encoding and one cryptographic fingerprint; and the sealed
//! form in which it is provisioned into the unit's flash (docs/PROTOCOL.md
//! "Configuration authority", docs/SAFETY.md).
//!
//! The parts are the snapshot configuration (`raim_core::Config`: Pfa and
//! Pmd, the FDE method and the multi-fault reconstruction, the MCUSUM, the
//! alert limits and the sigma model), the ISM with the ARAIM configuration,
//! the particle-filter configuration, whether the unit uses the
//! per-satellite sigmas a host puts in an epoch frame, and the run-time
//! model check's allocation, spacing and window. Each part is
//! validated by its own `validate` in the core; the device server checks
//! all of them before any is put in force.
//!
//! Canonical encoding: `postcard(UnitConfig)` (postcard is deterministic:
//! fixed field order, varints, IEEE-754 little-endian floats). The
//! fingerprint is the first 16 bytes of SHA-256 over a domain string and
//! that encoding, so that no change of any byte of any part keeps it (a
//! CRC-32 can be forged by changing four bytes).

use hmac::{Hmac, Mac};
use raim_core::Config;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::araim_msg::IsmFrame;
use crate::auth::{AuthKey, Tag};
use crate::model_check_msg::WireModelCheckConfig;
use crate::pf_msg::WirePfConfig;

/// The fingerprint of a unit configuration: SHA-256, truncated to 128 bits.
pub type Fingerprint = [u8; 16];

/// Bytes shown as lowercase hexadecimal.
pub struct Hex<'a>(pub &'a [u8]);

impl core::fmt::Display for Hex<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for b in self.0 {
            write!(f, "{b:02x}")?;
        }
        Ok(())
    }
}

/// Domain string of the fingerprint.
const FINGERPRINT_DOMAIN: &[u8] = b"raim-unit-config-v1";
/// Domain string of the provisioning seal.
const SEAL_DOMAIN: &[u8] = b"raim-provision-v1";

/// Everything the unit runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnitConfig {
    /// The snapshot monitor, its FDE, the MCUSUM and the alert limits; if
    /// absent, snapshot epochs (and ARAIM pseudorange epochs, which are
    /// solved with it) are answered `Unconfigured`.
    pub snapshot: Option<Config>,
    /// The ISM and ARAIM configuration, if ARAIM is to run.
    pub araim: Option<IsmFrame>,
    /// The particle-filter configuration, if the PF is to run.
    pub pf: Option<WirePfConfig>,
    /// Whether a per-satellite `sigma_m` in an epoch frame is used. When
    /// false, an epoch carrying one is refused (`HostSigmaRefused`): the
    /// unit's own sigma model is then the only one.
    pub host_sigmas: bool,
    /// The run-time model check's allocation, spacing and window
    /// (docs/MODEL_CHECK.md); a TOML file that omits it, or any of its
    /// fields, gets the defaults (`WireModelCheckConfig::DEFAULT`).
    #[serde(default)]
    pub model_check: WireModelCheckConfig,
}

/// A [`UnitConfig`] by reference: the same encoding, field for field
/// (`Option<&T>` and `&T` serialize as `Option<T>` and `T`).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct UnitConfigRef<'a> {
    /// [`UnitConfig::snapshot`].
    pub snapshot: Option<&'a Config>,
    /// [`UnitConfig::araim`].
    pub araim: Option<&'a IsmFrame>,
    /// [`UnitConfig::pf`].
    pub pf: Option<&'a WirePfConfig>,
    /// [`UnitConfig::host_sigmas`].
    pub host_sigmas: bool,
    /// [`UnitConfig::model_check`].
    pub model_check: &'a WireModelCheckConfig,
}

impl UnitConfig {
    /// This configuration by reference.
    pub fn as_ref(&self) -> UnitConfigRef<'_> {
        UnitConfigRef {
            snapshot: self.snapshot.as_ref(),
            araim: self.araim.as_ref(),
            pf: self.pf.as_ref(),
            host_sigmas: self.host_sigmas,
            model_check: &self.model_check,
        }
    }

    /// The fingerprint of this configuration.
    pub fn fingerprint(&self) -> Fingerprint {
        self.as_ref().fingerprint()
    }
}

/// A postcard flavor that feeds a SHA-256 hasher (no buffer).
struct ShaFlavor(Sha256);

impl postcard::ser_flavors::Flavor for ShaFlavor {
    type Output = Sha256;
    fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
        self.0.update(data);
        Ok(())
    }
    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        self.0.update([data]);
        Ok(())
    }
    fn finalize(self) -> postcard::Result<Self::Output> {
        Ok(self.0)
    }
}

/// SHA-256 of `domain || postcard(value)`.
pub(crate) fn sha256_of<T: Serialize>(domain: &[u8], value: &T) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(domain);
    match postcard::serialize_with_flavor(value, ShaFlavor(h)) {
        Ok(h) => h.finalize().into(),
        // The flavor never fails; should the serializer ever, the
        // fingerprint is all ones, which no configuration has.
        Err(_) => [0xFF; 32],
    }
}

impl UnitConfigRef<'_> {
    /// The fingerprint: SHA-256 of the canonical encoding, first 16 bytes.
    pub fn fingerprint(&self) -> Fingerprint {
        let d = sha256_of(FINGERPRINT_DOMAIN, self);
        let mut f = [0u8; 16];
        f.copy_from_slice(d.get(..16).unwrap_or(&[0xFF; 16]));
        f
    }
}

/// Size of the provisioned-configuration section (`.raim_config`).
pub const PROVISION_BYTES: usize = 4096;
/// The sealed form's magic word.
const MAGIC: &[u8; 8] = b"RAIMUC01";
/// Magic, then the payload length (u32 little-endian).
const HEADER: usize = 12;

/// Why a provisioned configuration was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ProvisionError {
    /// The section does not start with the magic word.
    BadMagic,
    /// The length does not fit the section.
    BadLength {
        /// The length the section gives, bytes.
        len: u32,
        /// The largest that fits, bytes.
        max: u32,
    },
    /// The seal (HMAC on a keyed unit, SHA-256 otherwise) does not match.
    BadSeal,
    /// The payload is not a unit configuration.
    Undecodable,
    /// The configuration does not fit the section.
    TooLarge,
    /// The seal verified but a part fails its own checks (the core's
    /// `validate`, the ISM and PF checks); nothing of it is put in force.
    InvalidPart(UnitPart),
}

/// A part of the unit configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UnitPart {
    /// The snapshot configuration.
    Snapshot,
    /// The ISM and ARAIM configuration.
    Araim,
    /// The particle-filter configuration.
    Pf,
    /// The run-time model check's settings (protocol 17).
    ModelCheck,
}

fn seal_of(key: Option<&AuthKey>, payload: &[u8]) -> Tag {
    match key {
        Some(k) => match <Hmac<Sha256> as Mac>::new_from_slice(k) {
            Ok(mut m) => {
                m.update(SEAL_DOMAIN);
                m.update(payload);
                m.finalize().into_bytes().into()
            }
            Err(_) => [0; 32],
        },
        None => {
            let mut h = Sha256::new();
            h.update(SEAL_DOMAIN);
            h.update(payload);
            h.finalize().into()
        }
    }
}

/// Writes `unit` sealed into `out` (the host's provisioning step): magic,
/// length, `postcard(unit)`, then the seal: HMAC-SHA256 under the unit's
/// key when it has one, SHA-256 otherwise. The rest stays erased (0xFF).
pub fn seal(
    unit: &UnitConfig,
    key: Option<&AuthKey>,
    out: &mut [u8; PROVISION_BYTES],
) -> Result<(), ProvisionError> {
    out.fill(0xFF);
    let (head, rest) = out.split_at_mut(HEADER);
    let max = rest.len().saturating_sub(32);
    let body = rest.get_mut(..max).ok_or(ProvisionError::TooLarge)?;
    let len = postcard::to_slice(unit, body)
        .map_err(|_| ProvisionError::TooLarge)?
        .len();
    let tag = seal_of(key, rest.get(..len).ok_or(ProvisionError::TooLarge)?);
    rest.get_mut(len..len + 32)
        .ok_or(ProvisionError::TooLarge)?
        .copy_from_slice(&tag);
    head.get_mut(..8)
        .ok_or(ProvisionError::TooLarge)?
        .copy_from_slice(MAGIC);
    head.get_mut(8..12)
        .ok_or(ProvisionError::TooLarge)?
        .copy_from_slice(&(len as u32).to_le_bytes());
    Ok(())
}

/// Reads a provisioned section: `Ok(None)` when it is erased (all 0xFF),
/// the unit configuration when its seal verifies, otherwise the error. The
/// configuration is not yet validated (the server does that).
pub fn open(section: &[u8], key: Option<&AuthKey>) -> Result<Option<UnitConfig>, ProvisionError> {
    if section.iter().all(|&b| b == 0xFF) {
        return Ok(None);
    }
    if section.get(..8) != Some(MAGIC.as_slice()) {
        return Err(ProvisionError::BadMagic);
    }
    let mut len_bytes = [0u8; 4];
    len_bytes.copy_from_slice(section.get(8..12).ok_or(ProvisionError::BadMagic)?);
    let len = u32::from_le_bytes(len_bytes);
    let max = section.len().saturating_sub(HEADER + 32);
    let bad_length = ProvisionError::BadLength {
        len,
        max: max as u32,
    };
    let n = usize::try_from(len).map_err(|_| bad_length)?;
    if n > max {
        return Err(bad_length);
    }
    let payload = section.get(HEADER..HEADER + n).ok_or(bad_length)?;
    let tag = section.get(HEADER + n..HEADER + n + 32).ok_or(bad_length)?;
    let want = seal_of(key, payload);
    // Constant time is not needed for a seal read from the unit's own
    // flash, but costs nothing.
    let diff = want.iter().zip(tag).fold(0u8, |a, (x, y)| a | (x ^ y));
    if diff != 0 {
        return Err(ProvisionError::BadSeal);
    }
    match postcard::from_bytes::<UnitConfig>(payload) {
        Ok(u) => Ok(Some(u)),
        Err(_) => Err(ProvisionError::Undecodable),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> UnitConfig {
        UnitConfig {
            snapshot: Some(Config::default()),
            araim: None,
            pf: None,
            host_sigmas: false,
            model_check: WireModelCheckConfig::DEFAULT,
        }
    }

    /// SHA-256 through the same crate: FIPS 180-2's "abc" vector.
    #[test]
    fn sha256_matches_fips_180_2() {
        let d: [u8; 32] = Sha256::digest(b"abc").into();
        assert_eq!(d[..4], [0xba, 0x78, 0x16, 0xbf]);
        assert_eq!(d[28..], [0xf2, 0x00, 0x15, 0xad]);
    }

    /// The fingerprint is SHA-256 of the domain and the postcard bytes,
    /// by reference or by value; every single-bit change of the encoding
    /// that still decodes changes it.
    ///
    /// Verifies: SAFE-T3
    #[test]
    fn fingerprint_is_sha256_of_the_encoding_and_every_bit_counts() {
        let u = unit();
        let mut buf = [0u8; 512];
        let bytes = postcard::to_slice(&u, &mut buf).unwrap().to_vec();
        let mut h = Sha256::new();
        h.update(FINGERPRINT_DOMAIN);
        h.update(&bytes);
        let d: [u8; 32] = h.finalize().into();
        assert_eq!(u.fingerprint()[..], d[..16]);
        assert_eq!(u.as_ref().fingerprint(), u.fingerprint());
        let mut changed = 0;
        for i in 0..bytes.len() {
            for bit in 0..8 {
                let mut b = bytes.clone();
                b[i] ^= 1 << bit;
                if let Ok(v) = postcard::from_bytes::<UnitConfig>(&b) {
                    if v != u {
                        assert_ne!(v.fingerprint(), u.fingerprint(), "byte {i} bit {bit}");
                        changed += 1;
                    }
                }
            }
        }
        assert!(changed > 100, "{changed}");
    }

    /// Verifies: SAFE-T3
    #[test]
    fn sealed_round_trips_and_any_corruption_is_refused() {
        let key = [3u8; 32];
        let u = UnitConfig {
            host_sigmas: true,
            ..unit()
        };
        for k in [None, Some(&key)] {
            let mut s = [0u8; PROVISION_BYTES];
            seal(&u, k, &mut s).unwrap();
            assert_eq!(open(&s, k).unwrap(), Some(u.clone()));
            // Sealed without the key, opened with it, and the reverse.
            let other = if k.is_some() { None } else { Some(&key) };
            assert_eq!(open(&s, other), Err(ProvisionError::BadSeal));
            let len = u32::from_le_bytes(s[8..12].try_into().unwrap()) as usize;
            for i in 0..HEADER + len + 32 {
                let mut c = s;
                c[i] ^= 0x40;
                assert!(open(&c, k).is_err(), "byte {i}");
            }
        }
        assert_eq!(open(&[0xFF; PROVISION_BYTES], None), Ok(None));
        assert_eq!(
            open(&[0; PROVISION_BYTES], None),
            Err(ProvisionError::BadMagic)
        );
    }
}
