//! The texts of the wire's typed errors: what the host tool prints for a
//! refusal (`raim` shows a response's error with `Display`). Each must
//! name the values the error carries, so that the user sees which field,
//! satellite or count was refused and why, not only the variant's name.

extern crate std;

use std::format;
use std::string::String;

use raim_core::{RaimError, SatId, System};

use super::{field, WireError};
use crate::araim_msg::AraimWireError;
use crate::unit::ProvisionError;

fn text(e: &WireError) -> String {
    format!("{e}")
}

/// Every `WireError` variant's text, against the text written out by hand
/// with the values the variant carries (hexadecimal CRCs, the field's
/// name, the satellite as RINEX letter and number, the fingerprint in
/// hexadecimal, ARAIM's own refusals behind "ARAIM: ", the compiled PF
/// particle counts).
///
/// Verifies: WIRE-TEXT
#[test]
fn every_wire_error_names_its_values() {
    let g07 = SatId::new(System::Gps, 7);
    let cases: &[(WireError, &str)] = &[
        (
            WireError::BadCrc {
                computed: 0xdead_beef,
                received: 0x12,
            },
            "bad CRC: computed 0xdeadbeef, frame says 0x00000012",
        ),
        (WireError::Undecodable { len: 9 }, "undecodable frame (9 bytes)"),
        (
            WireError::Overflow { capacity: 2048 },
            "frame longer than the 2048-byte receive buffer",
        ),
        (
            WireError::SequenceGap {
                expected: 4,
                received: 6,
            },
            "sequence gap: expected 4, received 6",
        ),
        (
            WireError::TooManySatellites {
                have: 40,
                capacity: 32,
            },
            "40 satellites exceed capacity 32",
        ),
        (
            WireError::NonFinite {
                field: field("pseudorange_m"),
                index: 3,
                value: f64::INFINITY,
            },
            "non-finite pseudorange_m at index 3: inf",
        ),
        (
            WireError::DegenerateGeometry {
                column: 2,
                pivot: 1.5e-12,
            },
            "degenerate geometry at column 2 (pivot 1.5e-12)",
        ),
        (
            WireError::TooFewSatellites { have: 4, need: 5 },
            "too few satellites: have 4, need 5",
        ),
        (
            WireError::DuplicateSatellite {
                id: g07,
                first: 1,
                second: 4,
            },
            "duplicate satellite G07 at indices 1 and 4",
        ),
        (
            WireError::NonPositiveSigma {
                index: 2,
                sigma_m: -1.5,
            },
            "sigma at index 2 is not positive: -1.5 m",
        ),
        (
            WireError::OutOfRange {
                field: field("pfa"),
                value: 0.5,
                min: 1e-9,
                max: 0.01,
            },
            "pfa = 0.5 outside [0.000000001, 0.01]",
        ),
        (
            WireError::NoConvergence {
                iterations: 20,
                step_m: 3.25,
            },
            "no convergence after 20 iterations (last step 3.25 m)",
        ),
        (
            WireError::InvalidDof { dof: 0, max: 60 },
            "degrees of freedom 0 outside 1..=60",
        ),
        (
            WireError::Locked {
                fingerprint: [0xab; 16],
            },
            "configuration locked until reset (in force: abababababababababababababababab)",
        ),
        (
            WireError::TestHooksDisabled,
            "test hooks are disabled in this build",
        ),
        (
            WireError::AuthRequired,
            "state-changing frames must be authenticated on this unit",
        ),
        (
            WireError::AuthNotProvisioned,
            "no authentication key provisioned",
        ),
        (
            WireError::BadAuthTag { counter: 77 },
            "authentication tag does not verify (counter 77)",
        ),
        (
            WireError::Replayed {
                counter: 5,
                last: 9,
            },
            "replayed request: counter 5 <= last 9",
        ),
        (
            WireError::Araim(AraimWireError::NotInIsm { id: g07, index: 3 }),
            "ARAIM: satellite G07 at index 3 has no ISM entry",
        ),
        (
            WireError::PfNotConfigured,
            "no particle-filter configuration taken yet",
        ),
        (
            WireError::PfUnavailable,
            "this build has no particle-filter engine",
        ),
        (
            WireError::PfInvalidConfig {
                field: field("q_m"),
                value: -2.0,
            },
            "particle-filter q_m = -2 is out of range",
        ),
        (
            WireError::TimeNotIncreasing {
                previous_s: 10.0,
                now_s: 9.5,
            },
            "time 9.5 s does not follow 10 s",
        ),
        (
            WireError::SigmaOutOfRange {
                index: 1,
                sigma_m: 500.0,
                min_m: 0.1,
                max_m: 100.0,
            },
            "sigma at index 1 is 500 m, outside [0.1, 100] m",
        ),
        (
            WireError::Unconfigured { provision: None },
            "unconfigured: no configuration provisioned or taken",
        ),
        (
            WireError::Unconfigured {
                provision: Some(ProvisionError::BadMagic),
            },
            "unconfigured: the provisioned configuration is refused (BadMagic)",
        ),
        (
            WireError::CounterExhausted { counter: u64::MAX },
            "counter 18446744073709551615 is at the top of its range",
        ),
        (
            WireError::StreamNotDated { tow_ms: 1000 },
            "stream epoch at GPS time of week 1000 ms not dated: no GPS ephemeris (1019) yet",
        ),
        (
            WireError::StreamCapacity { capacity: 256 },
            "stream epoch with more than 256 signals",
        ),
        (
            WireError::HostSigmaRefused { index: 5 },
            "satellite at index 5 carries a sigma; this unit uses only its own sigma model",
        ),
        (
            WireError::PrnOutOfRange {
                index: 2,
                id: SatId::new(System::Glonass, 40),
                max: 32,
            },
            "satellite number 40 of R at index 2 is outside 1..=32",
        ),
        (
            WireError::StreamLeapSecondsUnknown { tow_ms: 2000 },
            "stream epoch at GPS time of week 2000 ms has GLONASS data, but GPS - UTC is unknown: the unit's leap-second table has expired and the stream sent no RTCM 1013",
        ),
        (
            WireError::TruncatedRtcm {
                received: 12,
                declared: 30,
            },
            "12 bytes dropped: an RTCM 3 header declaring 30 bytes, cut by a host frame",
        ),
    ];
    for (e, want) in cases {
        assert_eq!(text(e), *want, "{e:?}");
    }
    let pf = text(&WireError::PfParticles {
        requested: 7,
        max: 300,
    });
    assert!(
        pf.starts_with("7 particles not compiled in (counts [") && pf.ends_with("], at most 300)"),
        "{pf}"
    );
    for n in crate::pf_msg::PF_PARTICLE_COUNTS {
        assert!(pf.contains(&format!("{n}")), "{pf}");
    }
}

/// The core's refusals the earlier tests do not convert keep their values
/// on the wire: too few satellites, no convergence, an invalid degree of
/// freedom.
///
/// Verifies: WIRE-TooFewSatellites, WIRE-NoConvergence, WIRE-InvalidDof
#[test]
fn core_refusals_keep_their_values_on_the_wire() {
    let e: WireError = RaimError::TooFewSatellites { have: 4, need: 6 }.into();
    assert_eq!(e, WireError::TooFewSatellites { have: 4, need: 6 });
    let e: WireError = RaimError::NoConvergence {
        iterations: 20,
        step_m: 12.5,
    }
    .into();
    assert_eq!(
        e,
        WireError::NoConvergence {
            iterations: 20,
            step_m: 12.5
        }
    );
    let e: WireError = RaimError::InvalidDof { dof: 0, max: 60 }.into();
    assert_eq!(e, WireError::InvalidDof { dof: 0, max: 60 });
}

/// ARAIM's own refusals' texts name their values: the satellite and its
/// index, the ISM field with its index and bounds, the constellation by
/// its RINEX letter.
///
/// Verifies: WIRE-TEXT, WIRE-Araim
#[test]
fn every_araim_refusal_names_its_values() {
    let cases: &[(AraimWireError, &str)] = &[
        (AraimWireError::Disabled, "this build has no ARAIM engine"),
        (AraimWireError::NoIsm, "ARAIM epoch before any ISM"),
        (
            AraimWireError::NotInIsm {
                id: SatId::new(System::Galileo, 11),
                index: 6,
            },
            "satellite E11 at index 6 has no ISM entry",
        ),
        (
            AraimWireError::OutOfRange {
                field: field("p_sat"),
                index: 2,
                value: 1.5,
                min: 0.0,
                max: 1.0,
            },
            "ISM p_sat at index 2 is 1.5, outside [0, 1]",
        ),
        (
            AraimWireError::EmptyConstellation {
                system: System::Beidou,
            },
            "the ISM gives P_const for C but no satellite of it",
        ),
        (
            AraimWireError::MissingConstellationIsm {
                system: System::Qzss,
                index: 4,
            },
            "satellite at index 4 is of J, which has no P_const",
        ),
        (AraimWireError::EmptyIsm, "the ISM has no satellite entry"),
    ];
    for (e, want) in cases {
        assert_eq!(format!("{e}"), *want, "{e:?}");
    }
}

/// Every reason the core gives for an unavailable ARAIM epoch reaches the
/// wire with its values (the counts as u32, the probabilities unchanged).
///
/// Verifies: WIRE-Araim
#[test]
fn araim_unavailability_keeps_its_values_on_the_wire() {
    use crate::araim_msg::WireUnavailable;
    use raim_core::araim::Unavailable;
    let cases = [
        (
            Unavailable::ModeCapacity {
                needed: 601,
                capacity: 600,
            },
            WireUnavailable::ModeCapacity {
                needed: 601,
                capacity: 600,
            },
        ),
        (
            Unavailable::TooManyEvents {
                p_exceed_at_max: 2e-7,
            },
            WireUnavailable::TooManyEvents {
                p_exceed_at_max: 2e-7,
            },
        ),
        (
            Unavailable::Unmonitored {
                p_unmon: 1e-7,
                p_thres: 9e-8,
            },
            WireUnavailable::Unmonitored {
                p_unmon: 1e-7,
                p_thres: 9e-8,
            },
        ),
        (
            Unavailable::PlNotSolved { axis: 2 },
            WireUnavailable::PlNotSolved { axis: 2 },
        ),
        (Unavailable::Limits, WireUnavailable::Limits),
    ];
    for (core, wire) in cases {
        assert_eq!(WireUnavailable::from(core), wire);
    }
}

/// The provisioning tool's GA-PF configuration is seed 004's filter with
/// the particles and seed asked for and the core's default PF
/// configuration.
///
/// Verifies: SPEC-10
#[test]
fn the_gapf_configuration_is_the_default_pf_config() {
    use crate::pf_msg::{PfKind, WirePfConfig};
    let c = WirePfConfig::gapf(300, 42);
    assert_eq!(c.kind, PfKind::Gapf);
    assert_eq!((c.particles, c.seed), (300, 42));
    assert_eq!(c.config, raim_core::pf::PfConfig::default());
}

/// ARAIM's refusals that it shares with the snapshot monitor reach the
/// wire as the snapshot's typed errors with their values: over capacity
/// (`TooManySatellites`), too few satellites, a singular geometry
/// (`DegenerateGeometry`), a satellite given twice; its own constellation
/// refusals as `WireError::Araim`.
///
/// Verifies: WIRE-Araim, WIRE-TooManySatellites, WIRE-TooFewSatellites, WIRE-DegenerateGeometry
#[test]
fn araim_refusals_reach_the_wire_with_their_values() {
    use raim_core::araim::AraimError;
    let cases = [
        (
            AraimError::CapacityExceeded {
                have: 40,
                capacity: 32,
            },
            WireError::TooManySatellites {
                have: 40,
                capacity: 32,
            },
        ),
        (
            AraimError::TooFewSatellites { have: 4, need: 5 },
            WireError::TooFewSatellites { have: 4, need: 5 },
        ),
        (
            AraimError::RankDeficient {
                column: 3,
                pivot: 2e-13,
            },
            WireError::DegenerateGeometry {
                column: 3,
                pivot: 2e-13,
            },
        ),
        (
            AraimError::DuplicateSatellite {
                system: System::Galileo,
                prn: 9,
                first: 0,
                second: 6,
            },
            WireError::DuplicateSatellite {
                id: SatId::new(System::Galileo, 9),
                first: 0,
                second: 6,
            },
        ),
        (
            AraimError::EmptyConstellation {
                system: System::Beidou,
            },
            WireError::Araim(AraimWireError::EmptyConstellation {
                system: System::Beidou,
            }),
        ),
        (
            AraimError::MissingConstellationIsm {
                system: System::Qzss,
                index: 2,
            },
            WireError::Araim(AraimWireError::MissingConstellationIsm {
                system: System::Qzss,
                index: 2,
            }),
        ),
    ];
    for (core, wire) in cases {
        assert_eq!(WireError::from(core), wire, "{core:?}");
    }
}

/// The frame decoder's refusals' texts name the buffer's size, the
/// chunk's length and both CRCs (the host tool prints them for a frame it
/// could not read).
///
/// Verifies: WIRE-TEXT, WIRE-BadCrc, WIRE-Undecodable, WIRE-Overflow
#[test]
fn frame_refusals_name_their_values() {
    use crate::frame::FrameError;
    let cases = [
        (
            FrameError::Overflow { capacity: 4096 },
            "frame longer than the 4096-byte receive buffer (skipped to the next delimiter)",
        ),
        (
            FrameError::Undecodable { len: 17 },
            "a 17-byte chunk is not a valid COBS envelope",
        ),
        (
            FrameError::BadCrc {
                computed: 0xcafe,
                received: 0xbeef_0001,
            },
            "CRC mismatch: computed 0x0000cafe, received 0xbeef0001",
        ),
    ];
    for (e, want) in cases {
        assert_eq!(format!("{e}"), want, "{e:?}");
    }
}
