//! raim-nav: broadcast navigation for the integrity monitor, `no_std` and
//! heap-free, shared by the host tools and the firmware so that both turn
//! the same broadcast data into the same bits.
//!
//! - [`ephemeris`]: Keplerian broadcast orbits and clocks (GPS, Galileo,
//!   BeiDou, QZSS);
//! - [`glonass`]: GLONASS FDMA state vectors integrated by RK4, GLONASS
//!   time, PZ-90.11 to WGS-84;
//! - [`time`]: GPS time, UTC and the leap seconds;
//! - [`geometry`], [`tropo`], [`iono`]: the Earth-rotation correction,
//!   azimuth/elevation, Saastamoinen and Klobuchar;
//! - [`ranging`]: a satellite's raw pseudorange(s) and ephemeris to the
//!   core's corrected observation (the host's replays and the firmware's
//!   own epochs both call it);
//! - [`store`]: the ephemerides a receiver holds, in fixed capacity;
//! - [`velocity`]: satellite velocities and clock drifts, and the
//!   receiver velocity from Doppler (speed and course over ground);
//! - `rtcm` (feature `rtcm`): the RTCM 3 fields, a compact decoder and the
//!   stream receiver that forms epochs on the device.
//!
//! Every elementary function goes through `libm` (`m`), on the host too.
#![cfg_attr(not(test), no_std)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod arc;
pub mod bootstrap;
pub mod ephemeris;
pub mod error;
pub mod geometry;
pub mod glonass;
pub mod iono;
pub mod ranging;
#[cfg(feature = "rtcm")]
pub mod rtcm;
pub mod store;
pub mod time;
pub mod tropo;
pub mod velocity;

mod m;

pub use error::NavError;

#[cfg(all(test, feature = "rtcm"))]
mod cov2_tests;
