//! The mode enumeration's refusal when more than MAX_EVENTS simultaneous
//! events would be needed, with P(more than MAX_EVENTS events) against a
//! brute-force sum over every on/off pattern of the events.

extern crate std;

use super::*;

/// P(more than `r` of the independent events with probabilities `p`
/// happen), by summing every one of the 2^n patterns.
fn brute_tail(p: &[f64], r: usize) -> f64 {
    let n = p.len();
    let mut total = 0.0;
    for mask in 0u32..(1 << n) {
        if mask.count_ones() as usize > r {
            let mut pr = 1.0;
            for (i, &pi) in p.iter().enumerate() {
                pr *= if mask & (1 << i) != 0 { pi } else { 1.0 - pi };
            }
            total += pr;
        }
    }
    total
}

#[test]
fn too_many_events_carries_the_exceedance_at_max_events() {
    // Ten satellites of two constellations at P_sat 0.2 and the two
    // constellations at 0.1: P(> 4 events) is about 0.15, far above
    // P_THRES = 1e-9.
    let p_sat = [0.2; 10];
    let sys = [0u8, 1, 0, 1, 0, 1, 0, 1, 0, 1];
    let p_const = [(0u8, 0.1), (1u8, 0.1)];
    let events = Events {
        p_sat: &p_sat,
        sat_system: &sys,
        p_const: &p_const,
    };
    let mut all: std::vec::Vec<f64> = p_sat.to_vec();
    all.extend(p_const.iter().map(|c| c.1));
    let want = brute_tail(&all, MAX_EVENTS);
    let mut out: Vec<ModeEvents, 64> = Vec::new();
    match enumerate(&events, 1e-9, &mut out) {
        Err(EnumerationLimit::TooManyEvents { p_exceed_at_max }) => {
            assert!(
                (p_exceed_at_max - want).abs() < 1e-12 * want,
                "{p_exceed_at_max} {want}"
            );
        }
        other => panic!("{other:?}"),
    }
    // With a threshold above that tail the event count is not the limit.
    assert!(!matches!(
        enumerate(&events, 2.0 * want, &mut out),
        Err(EnumerationLimit::TooManyEvents { .. })
    ));
}
