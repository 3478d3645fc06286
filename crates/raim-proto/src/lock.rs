//! What the unit runs, as every answer reports it (docs/PROTOCOL.md
//! "Configuration authority").
//!
//! Every response carries a [`ConfigId`]: the fingerprint of the unit
//! configuration in force (`unit::UnitConfig::fingerprint`, SHA-256), where
//! it came from, and whether it is locked. A unit running its provisioned
//! configuration is locked from boot; after `Lock` a runtime configuration
//! is locked too. Only a reset unlocks, and a reset returns the unit to its
//! provisioned configuration, or to none.

use serde::{Deserialize, Serialize};

use crate::unit::Fingerprint;

/// Where the configuration in force came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigSource {
    /// None is in force: every epoch is answered `Unconfigured`.
    #[default]
    Unconfigured,
    /// The configuration provisioned into the unit's flash, verified at
    /// boot.
    Provisioned,
    /// Taken at run time since the last reset (bench use); lost at reset.
    Runtime,
}

/// The configuration in force, by fingerprint, where it came from, and
/// whether it can change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConfigId {
    /// SHA-256 (first 16 bytes) of the canonical encoding of the unit
    /// configuration in force (`unit::UnitConfigRef::fingerprint`).
    pub fingerprint: Fingerprint,
    /// Changes are refused until reset.
    pub locked: bool,
    /// Where the configuration in force came from.
    pub source: ConfigSource,
}
