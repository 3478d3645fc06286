//! RTCM 3 (RTCM 10403.3): the message fields the host and the firmware
//! share ([`fields`]), the device's compact decoder ([`decode`] over the
//! bit reader [`bits`]), and the receiver that turns a station's or a
//! receiver's stream into the monitor's epochs on its own, in fixed
//! capacity ([`receiver`]).
//!
//! Feature `rtcm` (the firmware's) does not link `rtcm-rs`: its message
//! decoding took about 20 KB of stack for any frame and 45 KB for an MSM7
//! under QEMU, over the firmware's 16 KiB goal, where [`decode`] stays
//! within the boot's high water. Feature `rtcm-rs` adds the host's
//! conversions from `rtcm-rs`'s message types (`glonass_fields`), which
//! the host's stream reader (`raim-recv`) decodes with.

pub mod bits;
pub mod decode;
pub mod fields;
pub mod receiver;

pub use fields::{
    fx, gps_week_of, kepler, latest_week, week_from_pivot, KeplerFields, BDT_WEEK0_GPS,
    GST_WEEK0_GPS, LIGHT_MS_M,
};
#[cfg(feature = "rtcm-rs")]
pub use fields::{
    glonass_fields, msg1019_fields, msg1042_fields, msg1044_fields, msg1045_fields, msg1046_fields,
};
pub use receiver::{FormError, FormScratch, FormedEpoch, LeapSeconds, RtcmCounts, StreamReceiver};

#[cfg(test)]
mod receiver_cov2_tests;
#[cfg(test)]
mod receiver_cov_tests;
#[cfg(test)]
mod stream_tests;
