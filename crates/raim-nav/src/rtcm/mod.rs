//! RTCM 3 (RTCM 10403.3): the message fields the host and the firmware
//! share ([`fields`]), and the receiver that turns a station's or a
//! receiver's stream into the monitor's epochs on its own, in fixed
//! capacity ([`receiver`]).

pub mod bits;
pub mod decode;
pub mod fields;
pub mod receiver;

#[cfg(feature = "rtcm-rs")]
pub use fields::glonass_fields;
pub use fields::{fx, kepler, latest_week, KeplerFields, LIGHT_MS_M};
pub use receiver::{FormError, FormedEpoch, RtcmCounts, StreamReceiver};
