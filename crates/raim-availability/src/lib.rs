//! ARAIM availability over a service volume (issue 36; SPEC §14,
//! docs/AVAILABILITY.md): almanacs into orbits, a user grid, and per user
//! and epoch one call of raim-core's ARAIM monitor (the device's decision
//! path, not a copy), summarised as per-user availability and PL
//! percentiles and an area-weighted coverage, in shards that merge exactly.

pub mod airborne;
pub mod almanac;
pub mod cli;
pub mod engine;
pub mod map;
pub mod output;
pub mod run;
pub mod sweep;
