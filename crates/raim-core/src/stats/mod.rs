//! Distributions in no_std (chi-square, non-central chi-square, normal),
//! shared by every method's thresholds and protection levels (SPEC §3, §6).

pub mod dist;
