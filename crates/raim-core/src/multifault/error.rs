//! Typed errors of the multiple-fault reconstruction (SPEC §8). Each carries
//! the offending values; none is a panic.

/// Why a covering or a reconstruction could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum MultifaultError {
    /// `t` simultaneous faults cannot be searched with `n` satellites and
    /// `m` states: a candidate set needs t <= n - m - 1 (its subset
    /// statistic RSS_T has n - m - t >= 1 degrees of freedom, SPEC §8.4).
    TooManyFaults {
        /// Faults asked for.
        t: usize,
        /// Satellites in the epoch.
        n: usize,
        /// States of the solution (3 + clocks).
        m: usize,
        /// The largest fault count the geometry allows, n - m - 1.
        max: usize,
    },
    /// `t` is 0 or above the largest supported number of faults.
    FaultCountOutOfRange {
        /// Name of the offending field.
        field: &'static str,
        /// The fault count received.
        t: usize,
        /// The largest supported fault count.
        max: usize,
    },
    /// The group budget per epoch is 0: nothing could be searched.
    ZeroGroupBudget {
        /// Name of the zero budget field.
        field: &'static str,
    },
    /// More satellites than the engine's capacity (or the 64-bit set masks).
    CapacityExceeded {
        /// Satellites in the epoch.
        have: usize,
        /// The capacity exceeded (`N`, or 64).
        capacity: usize,
    },
    /// No group's constrained set has rank m in H: nothing is identifiable
    /// (every identifiable set lost all its satellites to rank swaps).
    NoIdentifiableGroup {
        /// Satellites in the epoch.
        n: usize,
        /// Constraint groups tried.
        groups: usize,
    },
    /// A group given by the caller names a satellite outside 0..n.
    GroupOutOfRange {
        /// Index of the group.
        group: usize,
        /// Its satellite bit mask.
        mask: u64,
        /// Satellites in the epoch.
        n: usize,
    },
}

impl core::fmt::Display for MultifaultError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            MultifaultError::TooManyFaults { t, n, m, max } => write!(
                f,
                "{t} faults cannot be searched with n = {n}, m = {m} (at most {max})"
            ),
            MultifaultError::FaultCountOutOfRange { field, t, max } => {
                write!(f, "{field} = {t} outside 1..={max}")
            }
            MultifaultError::ZeroGroupBudget { field } => write!(f, "{field} is 0"),
            MultifaultError::CapacityExceeded { have, capacity } => {
                write!(f, "{have} satellites exceed capacity {capacity}")
            }
            MultifaultError::NoIdentifiableGroup { n, groups } => write!(
                f,
                "no constrained set of rank m among {groups} groups of {n} satellites"
            ),
            MultifaultError::GroupOutOfRange { group, mask, n } => {
                write!(f, "group {group} (mask {mask:#x}) names a satellite >= {n}")
            }
        }
    }
}

impl core::error::Error for MultifaultError {}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;

    /// Every reconstruction rejection's message shows its offending values.
    #[test]
    fn every_error_names_its_values() {
        let cases: [(MultifaultError, &[&str]); 6] = [
            (
                MultifaultError::TooManyFaults {
                    t: 4,
                    n: 9,
                    m: 5,
                    max: 2,
                },
                &["4 faults", "n = 9", "m = 5", "at most 2"],
            ),
            (
                MultifaultError::FaultCountOutOfRange {
                    field: "t_max",
                    t: 0,
                    max: 3,
                },
                &["t_max = 0", "1..=3"],
            ),
            (
                MultifaultError::ZeroGroupBudget {
                    field: "group_budget",
                },
                &["group_budget is 0"],
            ),
            (
                MultifaultError::CapacityExceeded {
                    have: 70,
                    capacity: 64,
                },
                &["70", "64"],
            ),
            (
                MultifaultError::NoIdentifiableGroup { n: 7, groups: 21 },
                &["21 groups", "7 satellites"],
            ),
            (
                MultifaultError::GroupOutOfRange {
                    group: 3,
                    mask: 0x100,
                    n: 8,
                },
                &["group 3", "0x100", ">= 8"],
            ),
        ];
        for (e, parts) in cases {
            let msg = format!("{e}");
            for p in parts {
                assert!(msg.contains(p), "{e:?}: {msg:?} lacks {p:?}");
            }
        }
    }
}
