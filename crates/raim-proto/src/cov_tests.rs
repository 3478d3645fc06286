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

/// Eight GPS satellites of a linear epoch (unit sigmas, small residuals),
/// G08 at `el8_deg`, processed by the core and in wire form.
fn linear_result(
    el8_deg: f64,
) -> (
    crate::result::WireResult,
    std::vec::Vec<raim_core::LinearObservation>,
) {
    use raim_core::{Config, Epoch, LinearObservation, Raim, SatId, System};
    let sky = [
        (0.0, 85.0),
        (45.0, 30.0),
        (100.0, 50.0),
        (150.0, 20.0),
        (200.0, 60.0),
        (250.0, 25.0),
        (300.0, 40.0),
        (340.0, el8_deg),
    ];
    let sats: std::vec::Vec<LinearObservation> = sky
        .iter()
        .enumerate()
        .map(|(i, &(az, el)): (usize, &(f64, f64))| {
            let mut o = LinearObservation::from_az_el(
                SatId::new(System::Gps, i as u8 + 1),
                f64::to_radians(az),
                f64::to_radians(el),
                0.1 * i as f64 - 0.3,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect();
    let r = Raim::<32>::new()
        .process(&Config::default(), &Epoch::linear(1_709_164_800.0, &sats))
        .unwrap();
    (crate::result::WireResult::from_result(&r), sats)
}

/// GSV: a satellite below the horizon has an empty elevation field (NMEA
/// 0183 elevation is 0-90 degrees), its azimuth still given; the C/N0
/// field is the epoch's value in whole dB-Hz, empty for 0 (unknown).
#[test]
fn gsv_leaves_a_negative_elevation_and_an_unknown_cn0_empty() {
    use crate::nmea::{epoch_sentences, Options, Sky};
    let (w, sats) = linear_result(-5.0);
    let e = raim_core::Epoch::linear(w.time_s, &sats);
    let cn0 = [40u8, 0, 42, 43, 44, 45, 46, 47];
    let sky = Sky {
        epoch: &e,
        cn0_dbhz: &cn0,
        velocity: None,
    };
    let all = epoch_sentences(
        &w,
        &sky,
        Options {
            geoid: false,
            sky: true,
        },
    )
    .unwrap();
    let gsv: std::vec::Vec<&str> = all
        .iter()
        .map(|s| s.as_str())
        .filter(|s| s.get(3..6) == Some("GSV"))
        .collect();
    assert_eq!(gsv.len(), 2, "{gsv:?}");
    // Fields: talker+GSV, total, part, count, then (SVID, el, az, C/N0)
    // per satellite, then the signal ID and checksum.
    let fields = |s: &str| -> std::vec::Vec<std::string::String> {
        let body = &s[1..s.find('*').unwrap()];
        body.split(',').map(std::string::String::from).collect()
    };
    let first = fields(gsv[0]);
    assert_eq!(&first[4..8], ["01", "85", "000", "40"]);
    assert_eq!(&first[8..12], ["02", "30", "045", ""]);
    let second = fields(gsv[1]);
    assert_eq!(&second[16..20], ["08", "", "340", "47"]);
}

/// ZDA before year 1: the proleptic Gregorian year with its sign.
/// 0000-01-01 is Unix time -62,167,219,200 s; year -1 (not a leap year)
/// starts 365 days before it, at -62,198,755,200 s.
#[test]
fn zda_writes_a_negative_year_with_its_sign() {
    let (mut w, _) = linear_result(15.0);
    w.time_s = -62_198_755_200.0;
    let s = crate::nmea::zda(&w).unwrap();
    assert!(
        s.as_str().contains(",000000.00,01,01,-0001,00,00*"),
        "{}",
        s.as_str()
    );
}

/// DOPs of a sky whose satellites all lie on one line of sight: the
/// geometry matrix has rank 2 (one direction and the clock), so no DOP
/// exists and none is written.
#[test]
fn a_sky_on_one_line_of_sight_has_no_dops() {
    use raim_core::{Epoch, LinearObservation};
    let (w, sats) = linear_result(15.0);
    let same: std::vec::Vec<LinearObservation> = sats
        .iter()
        .map(|s| LinearObservation::from_az_el(s.id, 0.3, 0.7, 0.0))
        .collect();
    let e = Epoch::linear(w.time_s, &same);
    assert_eq!(crate::nmea::dops(&w, &crate::nmea::Sky::new(&e)), None);
    let good = Epoch::linear(w.time_s, &sats);
    assert!(crate::nmea::dops(&w, &crate::nmea::Sky::new(&good)).is_some());
}

/// Without the sky sentences (`Options::sky` false): no GSV, and the GSA
/// carries no DOP.
#[test]
fn without_the_sky_no_gsv_and_no_dops() {
    use crate::nmea::{epoch_sentences, Options, Sky};
    let (w, sats) = linear_result(15.0);
    let e = raim_core::Epoch::linear(w.time_s, &sats);
    let all = epoch_sentences(
        &w,
        &Sky::new(&e),
        Options {
            geoid: false,
            sky: false,
        },
    )
    .unwrap();
    assert!(all.iter().all(|s| s.as_str().get(3..6) != Some("GSV")));
    // GSA fields: talker+GSA, mode, fix, 12 satellite slots, PDOP, HDOP,
    // VDOP, system ID.
    let dop_fields = |all: &crate::nmea::Sentences| -> std::vec::Vec<std::string::String> {
        let gsa = all
            .iter()
            .map(|s| s.as_str())
            .find(|s| s.get(3..6) == Some("GSA"))
            .unwrap();
        let body = &gsa[1..gsa.find('*').unwrap()];
        body.split(',')
            .skip(15)
            .take(3)
            .map(std::string::String::from)
            .collect()
    };
    assert_eq!(dop_fields(&all), ["", "", ""]);
    let with_sky = epoch_sentences(
        &w,
        &Sky::new(&e),
        Options {
            geoid: false,
            sky: true,
        },
    )
    .unwrap();
    assert!(
        dop_fields(&with_sky).iter().all(|f| !f.is_empty()),
        "{:?}",
        dop_fields(&with_sky)
    );
}

/// An authenticated ISM whose list overflowed is refused on its declared
/// count, as a plain ISM is.
#[test]
fn an_authenticated_ism_that_overflowed_is_caught() {
    use crate::araim_msg::{IsmFrame, WireAraimConfig};
    use crate::auth::{Authenticated, Change};
    use crate::message::{Command, SatList};
    let ism = IsmFrame {
        config: WireAraimConfig::default(),
        p_const: [None; raim_core::measurement::MAX_SYSTEMS],
        sats: SatList {
            items: heapless::Vec::new(),
            declared: 77,
        },
    };
    let c = Command::Authenticated(Authenticated {
        counter: 1,
        change: Change::Ism(ism),
        tag: [0; 32],
    });
    assert_eq!(c.overflowed_list(), Some(77));
}
