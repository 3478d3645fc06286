//! Fault-mode enumeration (SPEC §9.1 step 1).
//!
//! Events are each satellite fault (P_sat,i) and each constellation fault
//! (P_const,j), independent. N_fault,max = r is the smallest count with
//! P(more than r events) <= P_THRES; that probability is the unmonitored
//! part. The modes are all combinations of 1..=r events, with the prior
//! p_k = the product of their probabilities, and none is skipped: in
//! particular the satellite + constellation combinations are modes.
//!
//! One merge, exact: a combination holding a constellation event and a
//! satellite event of the same constellation removes the same satellites
//! and clock as the combination without that satellite event, so its
//! probability is added to that mode instead of making a duplicate one
//! (the PL sum is identical, and the false-alert budget is not split over
//! identical tests). `enumerate` applies it in closed form through the
//! elementary symmetric sums of each constellation's P_sat.

use crate::measurement::MAX_SYSTEMS;
use heapless::Vec;

/// Largest number of simultaneous fault events a mode may hold.
pub const MAX_EVENTS: usize = 4;

/// The events of one fault mode and its prior.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ModeEvents {
    /// Satellite events: bit i is the epoch's satellite i.
    pub sats: u64,
    /// Constellation events: bit j is `System::ALL[j]`.
    pub consts: u8,
    /// p_k: the product of the events' probabilities, plus the merged
    /// redundant combinations (module doc).
    pub prior: f64,
}

/// What the enumeration found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Enumeration {
    /// N_fault,max: the largest number of simultaneous events monitored.
    pub max_faults: usize,
    /// P(more than `max_faults` events): unmonitored by construction.
    pub p_exceed: f64,
    /// The number of modes the enumeration needs (may exceed the capacity).
    pub needed: usize,
}

/// Why the enumeration could not produce the mode list.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EnumerationLimit {
    /// More than `MAX_EVENTS` simultaneous events would be needed to bring
    /// the unmonitored probability to P_THRES.
    TooManyEvents {
        /// P(more than `MAX_EVENTS` events) at `MAX_EVENTS`.
        p_exceed_at_max: f64,
    },
    /// The mode list does not fit the capacity `K`.
    Capacity {
        /// Modes the epoch needs.
        needed: usize,
        /// Modes the list holds (`K`).
        capacity: usize,
    },
}

/// The events of one epoch: per satellite its P_sat and constellation
/// index, and per constellation in use its index and P_const.
pub struct Events<'a> {
    /// P_sat per satellite.
    pub p_sat: &'a [f64],
    /// Constellation index per satellite.
    pub sat_system: &'a [u8],
    /// (constellation index, P_const) per constellation in use.
    pub p_const: &'a [(u8, f64)],
}

/// P(more than r events) for r = 0..=MAX_EVENTS, by the Poisson-binomial
/// recursion on the tail (no 1 - sum cancellation).
pub fn exceedance(events: &Events<'_>) -> [f64; MAX_EVENTS + 1] {
    let mut q = [0.0f64; MAX_EVENTS + 1];
    let mut tail = [0.0f64; MAX_EVENTS + 1];
    if let Some(q0) = q.first_mut() {
        *q0 = 1.0;
    }
    let ps = events
        .p_sat
        .iter()
        .copied()
        .chain(events.p_const.iter().map(|c| c.1));
    for p in ps {
        for (t, qr) in tail.iter_mut().zip(q.iter()) {
            *t += qr * p;
        }
        // q_j <- q_j (1 - p) + q_{j-1} p (q_{-1} = 0), from the old q.
        let old = q;
        for (qj, prev) in q.iter_mut().zip(core::iter::once(0.0).chain(old)) {
            *qj = *qj * (1.0 - p) + prev * p;
        }
    }
    tail
}

/// Elementary symmetric sums e_0..e_MAX_EVENTS of the P_sat of each
/// constellation's satellites.
fn symmetric_sums(events: &Events<'_>) -> [[f64; MAX_EVENTS + 1]; MAX_SYSTEMS] {
    let mut e = [[0.0f64; MAX_EVENTS + 1]; MAX_SYSTEMS];
    for row in e.iter_mut() {
        if let Some(e0) = row.first_mut() {
            *e0 = 1.0;
        }
    }
    for (&p, &s) in events.p_sat.iter().zip(events.sat_system.iter()) {
        if let Some(row) = e.get_mut(usize::from(s)) {
            // e_j <- e_j + e_{j-1} p (j >= 1), from the old row.
            let old = *row;
            for (x, prev) in row.iter_mut().skip(1).zip(old) {
                *x += prev * p;
            }
        }
    }
    e
}

/// The factor (>= 1) by which the merged redundant combinations raise the
/// prior of a mode with constellation events `consts` and `budget` events
/// to spare: sum over total degree 0..=budget of the product of the
/// constellations' symmetric sums.
fn merge_factor(consts: u8, budget: usize, e: &[[f64; MAX_EVENTS + 1]; MAX_SYSTEMS]) -> f64 {
    let mut poly = [0.0f64; MAX_EVENTS + 1];
    if let Some(p0) = poly.first_mut() {
        *p0 = 1.0;
    }
    for (j, ej) in e.iter().enumerate() {
        if consts & (1 << j) == 0 {
            continue;
        }
        let mut next = [0.0f64; MAX_EVENTS + 1];
        for (a, pa) in poly.iter().enumerate().take(budget + 1) {
            for (b, eb) in ej.iter().enumerate().take(budget + 1 - a) {
                if let Some(x) = next.get_mut(a + b) {
                    *x += pa * eb;
                }
            }
        }
        poly = next;
    }
    poly.iter().take(budget + 1).sum()
}

/// Enumerates the fault modes into `out` (cleared first).
///
/// # Errors
/// `TooManyEvents` if P(more than MAX_EVENTS) > P_THRES; `Capacity` if the
/// modes do not fit in `K` (the list is then incomplete and must not be
/// used: the epoch is unavailable, never silently truncated).
pub fn enumerate<const K: usize>(
    events: &Events<'_>,
    p_thres: f64,
    out: &mut Vec<ModeEvents, K>,
) -> Result<Enumeration, EnumerationLimit> {
    out.clear();
    let tail = exceedance(events);
    let Some((r, p_exceed)) = tail
        .iter()
        .copied()
        .enumerate()
        .find(|&(_, t)| t <= p_thres)
    else {
        return Err(EnumerationLimit::TooManyEvents {
            p_exceed_at_max: tail.last().copied().unwrap_or(1.0),
        });
    };
    let n = events.p_sat.len();
    let c = events.p_const.len();
    let total = n + c;
    let sums = symmetric_sums(events);
    let mut needed = 0usize;
    for size in 1..=r.min(total) {
        let mut idx = [0usize; MAX_EVENTS];
        for (k, x) in idx.iter_mut().enumerate().take(size) {
            *x = k;
        }
        loop {
            let mut sats = 0u64;
            let mut consts = 0u8;
            let mut prior = 1.0f64;
            for &e in idx.iter().take(size) {
                if let Some(&p) = events.p_sat.get(e) {
                    sats |= 1u64 << e;
                    prior *= p;
                } else if let Some(&(sys, p)) = events.p_const.get(e - n) {
                    consts |= 1u8 << sys;
                    prior *= p;
                }
            }
            let redundant = idx.iter().take(size).any(|&e| {
                e < n
                    && events
                        .sat_system
                        .get(e)
                        .is_some_and(|&s| consts & (1u8 << s) != 0)
            });
            if !redundant {
                if consts != 0 {
                    prior *= merge_factor(consts, r - size, &sums);
                }
                needed += 1;
                // A full list refuses the mode and `needed` keeps counting,
                // so the `needed > K` check below returns the Capacity error
                // with how many were needed.
                let refused = out
                    .push(ModeEvents {
                        sats,
                        consts,
                        prior,
                    })
                    .is_err();
                debug_assert!(!refused || needed > K);
            }
            if !next_combination(&mut idx, size, total) {
                break;
            }
        }
    }
    if needed > K {
        out.clear();
        return Err(EnumerationLimit::Capacity {
            needed,
            capacity: K,
        });
    }
    Ok(Enumeration {
        max_faults: r,
        p_exceed,
        needed,
    })
}

/// Advances `idx[..size]` to the next size-subset of 0..total in
/// lexicographic order; false when it was the last.
fn next_combination(idx: &mut [usize; MAX_EVENTS], size: usize, total: usize) -> bool {
    let mut k = size;
    while k > 0 {
        k -= 1;
        let limit = total - size + k;
        let Some(v) = idx.get_mut(k) else {
            return false;
        };
        if *v < limit {
            *v += 1;
            let base = *v;
            for (off, x) in idx.iter_mut().enumerate().take(size).skip(k + 1) {
                *x = base + (off - k);
            }
            return true;
        }
    }
    false
}

#[cfg(test)]
#[path = "modes_cov_tests.rs"]
mod cov_tests;
