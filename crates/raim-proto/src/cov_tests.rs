//! Wire paths the message tests leave out (issue 37, structural
//! coverage): FDE alarms on the wire, long field names, the cycle
//! counters of every epoch kind, a sealed section whose payload is no
//! unit configuration (built here from docs/PROTOCOL.md "Boot", not with
//! the crate's sealing code), and error messages.
extern crate std;

use raim_core::araim::{FdeAlarm, FdeDecision};
use sha2::{Digest, Sha256};

use crate::araim_msg::{field, WireFde};
use crate::boot_counter::BootCounterError;
use crate::error::WireError;
use crate::message::{CycleSpan, EpochCycles, EpochKind};
use crate::unit::{open, ProvisionError, PROVISION_BYTES};

/// The FDE alarms keep their mode indices on the wire.
#[test]
fn fde_alarms_on_the_wire() {
    assert_eq!(
        WireFde::from(FdeDecision::Alarm(FdeAlarm::NoCandidate)),
        WireFde::NoCandidate
    );
    assert_eq!(
        WireFde::from(FdeDecision::Alarm(FdeAlarm::Ambiguous {
            first: 2,
            second: 7
        })),
        WireFde::Ambiguous {
            first: 2,
            second: 7
        }
    );
}

/// A field name longer than the wire's 24 characters is cut to its
/// first 24.
#[test]
fn long_field_names_are_cut_to_the_wire_capacity() {
    let long = "abcdefghijklmnopqrstuvwxyz0123";
    let f = field(long);
    assert_eq!(f.as_str(), &long[..24]);
    assert_eq!(field("p_thres").as_str(), "p_thres");
}

/// Each epoch kind keeps its own last and largest count; the first
/// record starts the counter (`NotMeasured` before).
#[test]
fn cycle_counts_per_epoch_kind() {
    let mut c = EpochCycles::NotMeasured;
    assert_eq!(c.get(EpochKind::Pf), None);
    let kinds = [
        EpochKind::Snapshot,
        EpochKind::Araim,
        EpochKind::Pf,
        EpochKind::StreamForming,
    ];
    for (i, k) in kinds.iter().enumerate() {
        let base = 1000 * (i as u32 + 1);
        c.record(*k, base + 50);
        c.record(*k, base);
    }
    for (i, k) in kinds.iter().enumerate() {
        let base = 1000 * (i as u32 + 1);
        assert_eq!(
            c.get(*k),
            Some(CycleSpan {
                last_cycles: base,
                max_cycles: base + 50
            }),
            "{k:?}"
        );
    }
}

/// A section with the magic, a length and a seal that verifies (SHA-256
/// of `"raim-provision-v1" || payload`, docs/PROTOCOL.md "Boot") over a
/// payload that is no `UnitConfig` (an `Option` tag of 7) is refused
/// `Undecodable`; the same section with one payload byte changed is
/// refused `BadSeal`.
///
/// Verifies: SAFE-PROVISION
#[test]
fn a_sealed_payload_that_is_no_unit_configuration_is_undecodable() {
    let payload = [7u8, 1, 2];
    let mut section = [0xFFu8; PROVISION_BYTES];
    section[..8].copy_from_slice(b"RAIMUC01");
    section[8..12].copy_from_slice(&(payload.len() as u32).to_le_bytes());
    section[12..15].copy_from_slice(&payload);
    let mut h = Sha256::new();
    h.update(b"raim-provision-v1");
    h.update(payload);
    let seal: [u8; 32] = h.finalize().into();
    section[15..47].copy_from_slice(&seal);
    assert_eq!(open(&section, None), Err(ProvisionError::Undecodable));
    section[13] ^= 1;
    assert_eq!(open(&section, None), Err(ProvisionError::BadSeal));
}

/// The refusal of an authenticated change after a failed boot counter
/// names the counter's error.
#[test]
fn the_boot_counter_refusal_names_its_error() {
    let e = WireError::BootCounter {
        error: BootCounterError::EraseFailed { page: 1 },
    };
    let s = std::format!("{e}");
    assert!(s.contains("boot counter failed"), "{s}");
    assert!(s.contains("EraseFailed { page: 1 }"), "{s}");
}

/// A formatting error is a sentence that does not fit.
#[test]
fn a_format_error_is_too_long() {
    assert_eq!(
        crate::nmea::TooLong::from(core::fmt::Error),
        crate::nmea::TooLong
    );
}
