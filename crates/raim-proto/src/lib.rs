//! raim-proto: the wire protocol between a host and the RAIM firmware, and
//! the NMEA 0183 writer of the firmware's second UART (SPEC §11,
//! `docs/PROTOCOL.md`).
//!
//! `#![no_std]`, no allocation: every buffer is sized from [`CAPACITY`], the
//! same satellite capacity the firmware gives `raim_core::Raim`.
//!
//! - [`frame`]: `COBS(postcard(Envelope { payload, crc32 }))`, a receiver
//!   that turns a byte stream into verified payloads or typed framing errors.
//! - [`link`]: COBS frames and RTCM 3 frames from a GNSS receiver on one
//!   link, told apart byte by byte.
//! - [`message`]: what the payloads carry (requests, responses).
//! - [`result`]: the epoch result on the wire, converted from
//!   `raim_core::EpochResult`.
//! - [`error`]: the typed errors of a response.
//! - [`alert`]: the integrity-alarm discrete output's state machine.
//! - [`lock`]: the configuration lock and its CRC-32 fingerprint.
//! - [`boot_counter`]: the monotonic boot counter in flash, in the boot
//!   nonce.
//! - [`araim_msg`]: the ISM, the ARAIM epoch and result.
//! - [`model_check_msg`]: the run-time model check's settings.
//! - [`nmea`]: RMC, GGA, GSA, GST and GBS sentences for a solved epoch.
//!
//! The device's protocol loop, which answers these frames, is the
//! `raim-server` crate.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// `!(a < b)` is deliberate: it is true for NaN, so NaN never wins a
// comparison it should lose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod alert;
pub mod araim_msg;
pub mod auth;
pub mod boot_counter;
pub mod error;
pub mod frame;
pub mod link;
pub mod lock;
pub mod message;
pub mod model_check_msg;
pub mod nmea;
pub mod pf_msg;
pub mod result;
pub mod unit;

pub use alert::{AlarmOutput, AlertMonitor};
pub use auth::{AuthKey, Authenticated, AuthenticatedRef, Change, ChangeRef, Nonce};
pub use error::WireError;
pub use frame::{encode, FrameError, FrameReceiver};
pub use link::{LinkCounts, LinkEvent, LinkReceiver};
pub use lock::{ConfigId, ConfigSource};
pub use message::{
    BootNotice, Command, CycleSpan, EpochCycles, EpochKind, LinearEpoch, RangeEpoch, Request,
    RequestRef, ResetCause, Response, ResponseBody, SatList, Status, TestFault,
};
pub use model_check_msg::WireModelCheckConfig;
pub use pf_msg::{PfKind, WirePfConfig, WirePfResult};
pub use result::{WireMcusum, WireResult};
pub use unit::{Fingerprint, ProvisionError, UnitConfig, UnitConfigRef};

/// Satellites per epoch: the firmware's `Raim::<CAPACITY>` and every list on
/// the wire. The core's documented default.
pub const CAPACITY: usize = raim_core::DEFAULT_CAPACITY;

/// The device's precision: the statistics path of every engine the
/// device server (`raim-server`) runs (the snapshot monitor `Raim<CAPACITY, DevicePrecision>`,
/// ARAIM and the particle filters), on the firmware and on the host alike,
/// so that the host's `Server` reproduces the firmware bit for bit. `f32`:
/// the Cortex-M4F's FPU is single precision, and every f64 operation there
/// is a software call (docs/CORE.md, "Precision").
pub type DevicePrecision = f32;

/// Version of the frame layout and message types; reported by `Status`.
/// Bump on any change of a serialized type (postcard is not self-describing);
/// new enum variants are appended so that the earlier ones keep their
/// indices. The history of the versions is in CHANGELOG.md, "Wire protocol
/// versions"; 15 is the stream's leap seconds (`Status::stream_leap_seconds`,
/// `WireError::StreamLeapSecondsUnknown`) and `WireError::TruncatedRtcm`,
/// the answer to bytes dropped when a host frame ends inside an RTCM
/// candidate; 16 is the epochs' core clock cycles (`Status::epoch_cycles`,
/// the DWT cycle counter of a real board, `NotMeasured` elsewhere) and the
/// boot counter (`Status::boot_counter`, `WireError::BootCounter`); 17 is
/// the model check's settings as a part of the unit configuration
/// (`Command::ModelCheck`, `Change::ModelCheck`, `UnitConfig::model_check`,
/// `UnitPart::ModelCheck`).
pub const PROTOCOL_VERSION: u16 = 17;

/// Largest encoded request frame (delimiter included) the firmware accepts.
/// A range epoch at [`CAPACITY`] satellites encodes to at most 1,425 bytes
/// (test `frame::tests::largest_request_fits`); the margin lets frames of up
/// to 47 satellites decode, so that they are answered `TooManySatellites`
/// with their count rather than `Overflow`.
pub const MAX_REQUEST_FRAME: usize = 2048;

/// Upper bound of the encoded size of an epoch request with `n` satellites:
/// request header (seq varint 5, command 1, time 8, a-priori 1 + 24, list
/// length varint 2), 43 bytes per satellite (system 1, PRN 1, four f64 32,
/// optional sigma 1 + 8), envelope (payload length varint 2, CRC varint 5),
/// COBS overhead (one byte per 254 started) and the delimiter.
pub const fn max_request_frame(n: usize) -> usize {
    let payload = 5 + 1 + 8 + 25 + 2 + 43 * n;
    let envelope = payload + 2 + 5;
    envelope + envelope / 254 + 1 + 1
}

// The receive buffer holds any epoch at the capacity.
const _: () = assert!(max_request_frame(CAPACITY) <= MAX_REQUEST_FRAME);

/// Largest postcard payload of a response (before CRC and COBS).
/// A result at [`CAPACITY`] satellites with every field present serializes
/// to less than this (test `result::tests::largest_response_fits`).
pub const MAX_RESPONSE_PAYLOAD: usize = 3072;

/// Largest encoded response frame: payload + envelope (length varint and
/// CRC varint, at most 8 bytes) + COBS overhead (one byte per 254) + the
/// delimiter.
pub const MAX_RESPONSE_FRAME: usize = MAX_RESPONSE_PAYLOAD + 8 + MAX_RESPONSE_PAYLOAD / 254 + 2;

#[cfg(test)]
mod cov_tests;

#[cfg(test)]
mod cov2_tests;
