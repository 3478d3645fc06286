//! The typed errors a response can carry: framing errors, protocol errors
//! (sequence gap, too many satellites) and every `raim_core::RaimError`,
//! each with the offending values.

use raim_core::{RaimError, SatId};
use serde::{Deserialize, Serialize};

use crate::frame::FrameError;

/// A field name on the wire (the core's `&'static str` names, truncated to
/// 24 bytes; the longest the core uses is 19).
pub type FieldName = heapless::String<24>;

fn field(name: &str) -> FieldName {
    let mut s = FieldName::new();
    for c in name.chars() {
        if s.push(c).is_err() {
            break;
        }
    }
    s
}

/// Why a frame got no result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum WireError {
    /// The envelope's CRC does not match its payload.
    BadCrc {
        /// CRC-32 computed over the payload received.
        computed: u32,
        /// CRC-32 the envelope carried.
        received: u32,
    },
    /// A chunk that is not valid COBS or not an envelope (`len` bytes), or
    /// whose payload is not a request (then the response carries the
    /// sequence number if it could be read).
    Undecodable {
        /// Length of the chunk, bytes (delimiter included).
        len: u32,
    },
    /// A chunk longer than the receive buffer; skipped to the next delimiter.
    Overflow {
        /// The receive buffer's size, bytes.
        capacity: u32,
    },
    /// The request's sequence number is not the one after the previous
    /// request's. Sent as a notice before the answer to `received`.
    SequenceGap {
        /// The sequence number that was due.
        expected: u32,
        /// The sequence number received.
        received: u32,
    },
    /// More satellites than the firmware's capacity.
    TooManySatellites {
        /// Satellites in the epoch.
        have: u32,
        /// The firmware's capacity.
        capacity: u32,
    },
    /// A NaN or infinite input (`field`, satellite `index`).
    NonFinite {
        /// Name of the offending field.
        field: FieldName,
        /// Index of the satellite (0 for a per-epoch field).
        index: u32,
        /// The value received.
        value: f64,
    },
    /// The geometry lost rank (Householder pivot relative to its column).
    DegenerateGeometry {
        /// Index of the geometry column that lost rank.
        column: u32,
        /// Its pivot relative to the column norm (dimensionless).
        pivot: f64,
    },
    /// Fewer satellites than the unknowns plus the redundancy needed.
    TooFewSatellites {
        /// Satellites in the epoch.
        have: u32,
        /// Satellites needed.
        need: u32,
    },
    /// The same satellite appears twice in one epoch.
    DuplicateSatellite {
        /// The satellite.
        id: SatId,
        /// Index of its first appearance.
        first: u32,
        /// Index of its second appearance.
        second: u32,
    },
    /// A sigma that is zero or negative.
    NonPositiveSigma {
        /// Index of the satellite.
        index: u32,
        /// The sigma received, m.
        sigma_m: f64,
    },
    /// A configuration or input value outside its documented range.
    OutOfRange {
        /// Name of the offending field.
        field: FieldName,
        /// The value received (in the field's unit).
        value: f64,
        /// Smallest value accepted.
        min: f64,
        /// Largest value accepted.
        max: f64,
    },
    /// Gauss-Newton did not converge.
    NoConvergence {
        /// Iterations run.
        iterations: u32,
        /// Length of the last position step, m.
        step_m: f64,
    },
    /// A chi-square degree of freedom outside 1..=max.
    InvalidDof {
        /// The degree of freedom asked for.
        dof: u32,
        /// The largest supported.
        max: u32,
    },
    /// A change of configuration after `Lock`, or on a unit running its
    /// provisioned configuration (locked from boot): refused until reset.
    /// `fingerprint` is that of the configuration that stays in force.
    Locked {
        /// Fingerprint of the configuration in force.
        fingerprint: crate::unit::Fingerprint,
    },
    /// A `TestFault` request to a build without test hooks.
    TestHooksDisabled,
    /// A plain state-changing request (`Configure`, `Ism`, `PfConfigure`,
    /// `Lock`, `HostSigmas`, `ModelCheck`) to a unit with an authentication
    /// key.
    AuthRequired,
    /// An `Authenticated` request to a unit without a key.
    AuthNotProvisioned,
    /// An `Authenticated` request whose tag does not verify under the
    /// unit's key and this boot's nonce (a forged frame, or one recorded
    /// before a reset).
    BadAuthTag {
        /// The counter of the refused frame.
        counter: u64,
    },
    /// An `Authenticated` request whose counter is not above the last one
    /// accepted since boot (a replayed or reordered frame).
    Replayed {
        /// The counter of the refused frame.
        counter: u64,
        /// The last counter accepted.
        last: u64,
    },
    /// ARAIM's own refusals (`araim_msg::AraimWireError`).
    Araim(crate::araim_msg::AraimWireError),
    /// A `PfRanges` epoch before any `PfConfigure` was taken.
    PfNotConfigured,
    /// A PF request to a build without the particle-filter engine (or
    /// without its static storage attached).
    PfUnavailable,
    /// A `PfConfigure` whose particle count is not compiled in: above the
    /// capacity `max`, or not one of `raim_proto::pf_msg::PF_PARTICLE_COUNTS`
    /// (non-zero for the EKF). The previous PF configuration stays.
    PfParticles {
        /// Particles asked for.
        requested: u32,
        /// The largest count the build holds.
        max: u32,
    },
    /// A `PfConfigure` value outside its domain (`PfConfig::validate`), or
    /// a non-positive per-satellite sigma in a PF epoch.
    PfInvalidConfig {
        /// Name of the offending field.
        field: FieldName,
        /// The value received (in the field's unit).
        value: f64,
    },
    /// A PF epoch whose time does not follow the previous one's.
    TimeNotIncreasing {
        /// The previous PF epoch's time, s.
        previous_s: f64,
        /// This epoch's time, s.
        now_s: f64,
    },
    /// A per-satellite sigma outside its operational bound
    /// (`raim_core::config_bounds::SIGMA_M`), in any epoch form.
    SigmaOutOfRange {
        /// The satellite's index in the epoch.
        index: u32,
        /// The sigma given, m.
        sigma_m: f64,
        /// The bound's floor, m.
        min_m: f64,
        /// The bound's ceiling, m.
        max_m: f64,
    },
    /// An epoch to a unit with no configuration in force: none provisioned
    /// (or a corrupt one, `provision`), and none taken at run time. The
    /// epoch is unavailable; the alarm output is asserted.
    Unconfigured {
        /// Why the provisioned configuration was refused, if one was.
        provision: Option<crate::unit::ProvisionError>,
    },
    /// An `Authenticated` request with the counter at the top of its range
    /// (`u64::MAX`): refused, so that a later change stays possible.
    CounterExhausted {
        /// The counter refused.
        counter: u64,
    },
    /// An epoch carrying a per-satellite sigma (satellite `index`) to a
    /// unit configured to use only its own sigma model (`host_sigmas`
    /// off in the unit configuration).
    HostSigmaRefused {
        /// The satellite's index in the epoch.
        index: u32,
    },
    /// An epoch of the receiver's RTCM 3 stream (on the link UART) that
    /// cannot be dated: no GPS ephemeris (1019) has arrived yet, so its
    /// GPS week is unknown. Answered unasked (`seq: None`).
    StreamNotDated {
        /// The epoch's GPS time of week, ms.
        tow_ms: u32,
    },
    /// An epoch of the receiver's RTCM 3 stream with more signals than
    /// the unit's receiver holds (`capacity`); refused whole.
    StreamCapacity {
        /// Signals (or satellites) the receiver holds per epoch.
        capacity: u32,
    },
    /// A satellite number outside its system's range 1..=`max`
    /// (`raim_core::System::max_prn`), in an epoch or an ISM (satellite
    /// `index`). Protocol 14.
    PrnOutOfRange {
        /// The satellite's index in the epoch (or the ISM's entries).
        index: u32,
        /// The satellite as given.
        id: SatId,
        /// The system's largest number.
        max: u8,
    },
    /// An epoch of the receiver's RTCM 3 stream with GLONASS data, dated
    /// past the unit's leap-second table's expiry, while the stream has
    /// sent no GPS - UTC count (RTCM 1013): GLONASS time is UTC-based, so
    /// the epoch is refused rather than joined at a guessed second
    /// (`Status.stream_leap_seconds` says `TableExpired`). Protocol 15.
    StreamLeapSecondsUnknown {
        /// The epoch's GPS time of week, ms.
        tow_ms: u32,
    },
    /// Bytes dropped from the link: they began like an RTCM 3 frame whose
    /// header declared `declared` bytes, and a host frame ended `received`
    /// bytes after its 0xD3 (`link::LinkEvent::TruncatedRtcm`); that frame
    /// is answered next. Unasked (`seq: None`). Protocol 15.
    TruncatedRtcm {
        /// Bytes dropped, the 0xD3 included.
        received: u32,
        /// The frame length its header declared (N + 6), bytes.
        declared: u32,
    },
    /// An `Authenticated` request to a unit whose boot counter could not
    /// be advanced at this boot (`boot_counter::advance`): its boot nonce
    /// may have been used in an earlier power-on, so no authenticated
    /// change is taken until a boot whose counter works. Protocol 16.
    BootCounter {
        /// Why the counter failed.
        error: crate::boot_counter::BootCounterError,
    },
}

/// A field name for the wire (truncated to 24 bytes).
pub fn field_name(name: &str) -> FieldName {
    field(name)
}

fn u32_of(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

impl From<FrameError> for WireError {
    fn from(e: FrameError) -> Self {
        match e {
            FrameError::Overflow { capacity } => WireError::Overflow { capacity },
            FrameError::Undecodable { len } => WireError::Undecodable { len },
            FrameError::BadCrc { computed, received } => WireError::BadCrc { computed, received },
        }
    }
}

impl From<RaimError> for WireError {
    fn from(e: RaimError) -> Self {
        match e {
            RaimError::NotFinite {
                field: f,
                index,
                value,
            } => WireError::NonFinite {
                field: field(f),
                index: u32_of(index),
                value,
            },
            RaimError::DuplicateSatellite {
                system,
                prn,
                first,
                second,
            } => WireError::DuplicateSatellite {
                id: SatId::new(system, prn),
                first: u32_of(first),
                second: u32_of(second),
            },
            RaimError::TooFewSatellites { have, need } => WireError::TooFewSatellites {
                have: u32_of(have),
                need: u32_of(need),
            },
            RaimError::RankDeficient { column, pivot } => WireError::DegenerateGeometry {
                column: u32_of(column),
                pivot,
            },
            RaimError::NonPositiveSigma { index, sigma_m } => WireError::NonPositiveSigma {
                index: u32_of(index),
                sigma_m,
            },
            RaimError::CapacityExceeded { have, capacity } => WireError::TooManySatellites {
                have: u32_of(have),
                capacity: u32_of(capacity),
            },
            RaimError::OutOfRange {
                field: f,
                value,
                min,
                max,
            } => WireError::OutOfRange {
                field: field(f),
                value,
                min,
                max,
            },
            RaimError::NoConvergence { iterations, step_m } => {
                WireError::NoConvergence { iterations, step_m }
            }
            RaimError::InvalidDof { dof, max } => WireError::InvalidDof { dof, max },
            RaimError::SigmaOutOfRange {
                index,
                sigma_m,
                min_m,
                max_m,
            } => WireError::SigmaOutOfRange {
                index: u32_of(index),
                sigma_m,
                min_m,
                max_m,
            },
            RaimError::PrnOutOfRange {
                index,
                system,
                prn,
                max,
            } => WireError::PrnOutOfRange {
                index: u32_of(index),
                id: SatId::new(system, prn),
                max,
            },
            RaimError::TimeNotIncreasing { previous_s, now_s } => {
                WireError::TimeNotIncreasing { previous_s, now_s }
            }
        }
    }
}

impl core::fmt::Display for WireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            WireError::BadCrc { computed, received } => {
                write!(
                    f,
                    "bad CRC: computed {computed:#010x}, frame says {received:#010x}"
                )
            }
            WireError::Undecodable { len } => write!(f, "undecodable frame ({len} bytes)"),
            WireError::Overflow { capacity } => {
                write!(f, "frame longer than the {capacity}-byte receive buffer")
            }
            WireError::SequenceGap { expected, received } => {
                write!(f, "sequence gap: expected {expected}, received {received}")
            }
            WireError::TooManySatellites { have, capacity } => {
                write!(f, "{have} satellites exceed capacity {capacity}")
            }
            WireError::NonFinite {
                field,
                index,
                value,
            } => {
                write!(f, "non-finite {field} at index {index}: {value}")
            }
            WireError::DegenerateGeometry { column, pivot } => {
                write!(
                    f,
                    "degenerate geometry at column {column} (pivot {pivot:e})"
                )
            }
            WireError::TooFewSatellites { have, need } => {
                write!(f, "too few satellites: have {have}, need {need}")
            }
            WireError::DuplicateSatellite { id, first, second } => {
                write!(
                    f,
                    "duplicate satellite {id} at indices {first} and {second}"
                )
            }
            WireError::NonPositiveSigma { index, sigma_m } => {
                write!(f, "sigma at index {index} is not positive: {sigma_m} m")
            }
            WireError::OutOfRange {
                field,
                value,
                min,
                max,
            } => write!(f, "{field} = {value} outside [{min}, {max}]"),
            WireError::NoConvergence { iterations, step_m } => {
                write!(
                    f,
                    "no convergence after {iterations} iterations (last step {step_m} m)"
                )
            }
            WireError::InvalidDof { dof, max } => {
                write!(f, "degrees of freedom {dof} outside 1..={max}")
            }
            WireError::Locked { fingerprint } => write!(
                f,
                "configuration locked until reset (in force: {})",
                crate::unit::Hex(fingerprint)
            ),
            WireError::TestHooksDisabled => write!(f, "test hooks are disabled in this build"),
            WireError::AuthRequired => {
                write!(f, "state-changing frames must be authenticated on this unit")
            }
            WireError::AuthNotProvisioned => write!(f, "no authentication key provisioned"),
            WireError::BadAuthTag { counter } => {
                write!(f, "authentication tag does not verify (counter {counter})")
            }
            WireError::Replayed { counter, last } => {
                write!(
                    f,
                    "replayed request: counter {counter} <= last {last}"
                )
            }
            WireError::Araim(e) => write!(f, "ARAIM: {e}"),
            WireError::PfNotConfigured => write!(f, "no particle-filter configuration taken yet"),
            WireError::PfUnavailable => write!(f, "this build has no particle-filter engine"),
            WireError::PfParticles { requested, max } => write!(
                f,
                "{requested} particles not compiled in (counts {:?}, at most {max})",
                crate::pf_msg::PF_PARTICLE_COUNTS
            ),
            WireError::PfInvalidConfig { field, value } => {
                write!(f, "particle-filter {field} = {value} is out of range")
            }
            WireError::TimeNotIncreasing { previous_s, now_s } => {
                write!(f, "time {now_s} s does not follow {previous_s} s")
            }
            WireError::SigmaOutOfRange {
                index,
                sigma_m,
                min_m,
                max_m,
            } => write!(
                f,
                "sigma at index {index} is {sigma_m} m, outside [{min_m}, {max_m}] m"
            ),
            WireError::Unconfigured { provision: None } => {
                write!(f, "unconfigured: no configuration provisioned or taken")
            }
            WireError::Unconfigured { provision: Some(e) } => {
                write!(f, "unconfigured: the provisioned configuration is refused ({e:?})")
            }
            WireError::CounterExhausted { counter } => {
                write!(f, "counter {counter} is at the top of its range")
            }
            WireError::StreamNotDated { tow_ms } => write!(
                f,
                "stream epoch at GPS time of week {tow_ms} ms not dated: no GPS ephemeris (1019) yet"
            ),
            WireError::StreamCapacity { capacity } => {
                write!(f, "stream epoch with more than {capacity} signals")
            }
            WireError::HostSigmaRefused { index } => write!(
                f,
                "satellite at index {index} carries a sigma; this unit uses only its own sigma model"
            ),
            WireError::PrnOutOfRange { index, id, max } => write!(
                f,
                "satellite number {} of {} at index {index} is outside 1..={max}",
                id.prn,
                id.system.letter()
            ),
            WireError::StreamLeapSecondsUnknown { tow_ms } => write!(
                f,
                "stream epoch at GPS time of week {tow_ms} ms has GLONASS data, but GPS - UTC is unknown: the unit's leap-second table has expired and the stream sent no RTCM 1013"
            ),
            WireError::TruncatedRtcm { received, declared } => write!(
                f,
                "{received} bytes dropped: an RTCM 3 header declaring {declared} bytes, cut by a host frame"
            ),
            WireError::BootCounter { error } => write!(
                f,
                "no authenticated change: the boot counter failed at this boot ({error:?})"
            ),
        }
    }
}

impl core::error::Error for WireError {}

#[cfg(test)]
mod tests {
    use super::*;
    use raim_core::System;

    /// Verifies: WIRE-TooManySatellites, WIRE-NonFinite, WIRE-DegenerateGeometry, WIRE-DuplicateSatellite
    #[test]
    fn core_errors_keep_their_values() {
        let e: WireError = RaimError::NotFinite {
            field: "pseudorange_m",
            index: 3,
            value: f64::INFINITY,
        }
        .into();
        assert_eq!(
            e,
            WireError::NonFinite {
                field: field("pseudorange_m"),
                index: 3,
                value: f64::INFINITY
            }
        );
        let e: WireError = RaimError::CapacityExceeded {
            have: 40,
            capacity: 32,
        }
        .into();
        assert_eq!(
            e,
            WireError::TooManySatellites {
                have: 40,
                capacity: 32
            }
        );
        let e: WireError = RaimError::RankDeficient {
            column: 2,
            pivot: 1e-12,
        }
        .into();
        assert_eq!(
            e,
            WireError::DegenerateGeometry {
                column: 2,
                pivot: 1e-12
            }
        );
        let e: WireError = RaimError::DuplicateSatellite {
            system: System::Glonass,
            prn: 7,
            first: 1,
            second: 4,
        }
        .into();
        assert_eq!(
            e,
            WireError::DuplicateSatellite {
                id: SatId::new(System::Glonass, 7),
                first: 1,
                second: 4
            }
        );
    }

    #[test]
    fn long_field_names_are_truncated_not_dropped() {
        let f = field("a_field_name_much_longer_than_twenty_four");
        assert_eq!(f.as_str(), "a_field_name_much_longer");
    }
}

#[cfg(test)]
mod display_tests;
