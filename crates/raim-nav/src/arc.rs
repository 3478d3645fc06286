//! Keplerian orbit arcs kept across a stream's epochs: each satellite's
//! exact state (position, velocity, clock, clock drift; [`Orbit::state_motion`])
//! at two nodes at most [`ARC_S`] apart, and the cubic Hermite
//! polynomial through them, which gives the satellite's transmit-time
//! state and motion at an epoch between the nodes for a few dozen
//! operations instead of an orbit evaluation (Kepler's equation, the sum
//! formulas, the node's rotation: soft-float f64 on the M4, BENCHMARKS.md
//! "Orbit arcs").
//!
//! **The error bound.** Between nodes h apart, the cubic Hermite
//! interpolant H of a function f with a continuous fourth derivative
//! errs by at most h^4 / 384 max|f''''| and its derivative by at most
//! sqrt(3) / 216 h^3 max|f''''| (Birkhoff and Priver, "Hermite
//! interpolation errors for derivatives", J. Math. Phys. 46, 1967; the
//! first is the remainder f''''(xi) / 4! (t - t0)^2 (t - t1)^2 at its
//! largest, mid-arc). The fourth derivative of an Earth-fixed broadcast
//! orbit, measured by fourth differences on every Keplerian set of the
//! shared navigation files and GMSD7's 1019s (host-tests `orbit_sums`),
//! is at most 2.9e-8 m/s^4 (Galileo; GPS 1.8e-8, BeiDou 1.4e-8): with h =
//! [`ARC_S`] = 30 s, positions within 6.1e-5 m and velocities within
//! 6.2e-6 m/s, and the same test finds the interpolant within 6.1e-5 m
//! and 6.1e-6 m/s of the exact evaluation on every arc of those sets'
//! fit intervals (its bound: 1 mm and 1 mm/s). The clock is a quadratic,
//! which the cubic reproduces, plus the relativistic term F e sqrt(A)
//! sin E, whose fourth derivative is below 1e-21 s/s^4: clocks within
//! 1.1e-18 s.
//!
//! **Nodes.** A satellite's nodes are at the multiples of ARC_S offset
//! by a phase of its own (0 to 29 s, by its number and system:
//! [`arc_nodes_s`]), so that the arc a signal is interpolated on, and
//! the result, depend on the set, the satellite and the time alone, not
//! on the epochs before (a stream read from its middle forms the same
//! bits), and the satellites of an epoch reach their arcs' ends at
//! different epochs. An epoch past an arc's end evaluates one node (the
//! next arc's end; its start is the last arc's end); a satellite new to
//! the receiver, or on a new set, two: a stream's first epoch, and the
//! epoch at which the satellites of a constellation change sets together
//! (GPS's toe every two hours), evaluate two nodes per satellite, about
//! twice an exact transmit state each (BENCHMARKS.md "Orbit arcs": the
//! worst-case epoch measured).
//!
//! **One model everywhere.** A Keplerian satellite's transmit-time state
//! is this interpolant wherever it is formed: the device's stream
//! receiver keeps the arcs ([`KeplerArcs`]: 32, 12 on the STM32F4's
//! `ram-192k` build); the host's readers of a receiver stream (`raim
//! replay --rtcm3` and `--ubx`: `crate::ranging::transmit_state` with
//! `SatInput::orbit_arc`, which raim-recv's `NavData` sets) and a
//! satellite beyond the kept arcs evaluate the same arc afresh
//! ([`transmit_state_motion_on_arc`]: two node evaluations); so they form
//! the same bits. A RINEX replay keeps the exact orbit.

use core::borrow::Borrow;

use heapless::Vec;
use raim_core::SatId;

use crate::ephemeris::{Kepler, Orbit, SatState};
use crate::velocity::SatMotion;

/// An arc's length between its nodes, s (the error bound, module doc).
pub const ARC_S: f64 = 30.0;
/// The satellites' node phases: 0 to this less one, s (module doc).
const STAGGER: usize = 30;

/// A satellite's exact state and motion at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// GPS time, s.
    pub t_gps_s: f64,
    pub state: SatState,
    pub motion: SatMotion,
}

impl Node {
    /// The exact state and motion of `orbit` at `t_gps_s`.
    pub fn of(orbit: &Orbit, t_gps_s: f64) -> Self {
        let (state, motion) = orbit.state_motion(t_gps_s);
        Node {
            t_gps_s,
            state,
            motion,
        }
    }
}

/// The cubic Hermite polynomial through two nodes, in s = (t - t0) / h:
/// for each of x, y, z and the clock, f(s) = c0 + s (c1 + s (c2 + s c3))
/// with c0 = f0, c1 = h f0', c2 = 3 d - 2 h f0' - h f1', c3 = -2 d + h f0'
/// + h f1', d = f1 - f0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HermiteArc {
    /// The first node's time and the second's, GPS s.
    t0_gps_s: f64,
    t1_gps_s: f64,
    /// 1 / h, 1/s.
    inv_h: f64,
    /// [c0, c1, c2, c3] of x, y, z (m) and the clock (s).
    c: [[f64; 4]; 4],
    /// The second node (the next arc's first).
    end: Node,
}

impl HermiteArc {
    /// The arc from `a` to `b` (b later than a).
    pub fn new(a: &Node, b: &Node) -> Self {
        let h = b.t_gps_s - a.t_gps_s;
        let coefficients = |f0: f64, d0: f64, f1: f64, d1: f64| {
            let (hd0, hd1, d) = (h * d0, h * d1, f1 - f0);
            [f0, hd0, 3.0 * d - 2.0 * hd0 - hd1, -2.0 * d + hd0 + hd1]
        };
        let (pa, va, pb, vb) = (
            a.state.position_m,
            a.motion.velocity_m_s,
            b.state.position_m,
            b.motion.velocity_m_s,
        );
        HermiteArc {
            t0_gps_s: a.t_gps_s,
            t1_gps_s: b.t_gps_s,
            inv_h: 1.0 / h,
            c: [
                coefficients(pa[0], va[0], pb[0], vb[0]),
                coefficients(pa[1], va[1], pb[1], vb[1]),
                coefficients(pa[2], va[2], pb[2], vb[2]),
                coefficients(
                    a.state.clock_s,
                    a.motion.clock_drift_s_s,
                    b.state.clock_s,
                    b.motion.clock_drift_s_s,
                ),
            ],
            end: *b,
        }
    }

    /// True when `t_gps_s` is within the arc, ends included.
    pub fn covers(&self, t_gps_s: f64) -> bool {
        t_gps_s >= self.t0_gps_s && t_gps_s <= self.t1_gps_s
    }

    /// The clock at `t_gps_s`, s.
    pub fn clock_s(&self, t_gps_s: f64) -> f64 {
        let s = (t_gps_s - self.t0_gps_s) * self.inv_h;
        let [c0, c1, c2, c3] = self.c[3];
        c0 + s * (c1 + s * (c2 + s * c3))
    }

    /// The state and motion at `t_gps_s`.
    pub fn at(&self, t_gps_s: f64) -> (SatState, SatMotion) {
        let s = (t_gps_s - self.t0_gps_s) * self.inv_h;
        let value = |[c0, c1, c2, c3]: [f64; 4]| c0 + s * (c1 + s * (c2 + s * c3));
        let rate = |[_, c1, c2, c3]: [f64; 4]| (c1 + s * (2.0 * c2 + 3.0 * s * c3)) * self.inv_h;
        let [x, y, z, clock] = self.c;
        (
            SatState {
                position_m: [value(x), value(y), value(z)],
                clock_s: value(clock),
            },
            SatMotion {
                velocity_m_s: [rate(x), rate(y), rate(z)],
                clock_drift_s_s: rate(clock),
            },
        )
    }
}

/// One satellite's arc, for one Keplerian set.
#[derive(Debug, Clone, PartialEq)]
struct SatArc {
    id: SatId,
    /// The set the nodes are of (compared whole).
    set: Kepler,
    arc: HermiteArc,
    /// The epoch count when an epoch last used it.
    used: u32,
}

/// The arcs of up to `A` satellites (module doc); `A` = 0 keeps none
/// (each transmit state evaluated exactly).
#[derive(Debug, Clone)]
pub struct KeplerArcs<const A: usize> {
    arcs: Vec<SatArc, A>,
    /// Epochs started ([`Self::next_epoch`]), wrapping.
    epoch: u32,
}

impl<const A: usize> Default for KeplerArcs<A> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const A: usize> KeplerArcs<A> {
    /// No arc.
    pub const fn new() -> Self {
        KeplerArcs {
            arcs: Vec::new(),
            epoch: 0,
        }
    }

    /// A new epoch: the arcs the last one used may now give way.
    pub fn next_epoch(&mut self) {
        self.epoch = self.epoch.wrapping_add(1);
    }

    /// Arcs kept.
    pub fn len(&self) -> usize {
        self.arcs.len()
    }

    /// True when no arc is kept.
    pub fn is_empty(&self) -> bool {
        self.arcs.is_empty()
    }

    /// The transmit time, state and motion of satellite `id` on `orbit`
    /// for a signal sent at `t_sv_gps_s` by its clock (as
    /// [`Orbit::transmit_state_motion`], within the module doc's bound):
    /// on the arc of [`arc_nodes_s`]`(id, t_sv)`, the clock at t_sv and
    /// then the state and motion at t = t_sv - clock (which may precede
    /// the arc's start by the clock offset, below 1 ms). The arc is the
    /// kept one, or the next one from its end node and one new node, or
    /// else two new nodes ([`Node::of`]); it is a function of the set,
    /// the satellite and t_sv alone, whatever the epochs before. With `A`
    /// = 0, or a non-finite time, [`Orbit::transmit_state_motion`].
    pub fn transmit_state_motion(
        &mut self,
        id: SatId,
        orbit: &Orbit,
        t_sv_gps_s: f64,
    ) -> (f64, SatState, SatMotion) {
        self.transmit_state_motion_of(id, &orbit.set, t_sv_gps_s, || orbit)
    }

    /// [`Self::transmit_state_motion`] of set `set`, whose orbit's
    /// constants `orbit` makes only when a node is to be evaluated (a set
    /// decoded for the epoch: [`Orbit::new`] takes three library sines
    /// and cosines).
    pub fn transmit_state_motion_of<O: Borrow<Orbit>>(
        &mut self,
        id: SatId,
        set: &Kepler,
        t_sv_gps_s: f64,
        orbit: impl FnOnce() -> O,
    ) -> (f64, SatState, SatMotion) {
        let (t0, t1) = arc_nodes_s(id, t_sv_gps_s);
        if A == 0 || !(t0.is_finite() && t1.is_finite()) {
            return transmit_state_motion_on_arc(id, orbit().borrow(), t_sv_gps_s);
        }
        let epoch = self.epoch;
        let kept = self.arcs.iter_mut().find(|a| a.id == id && a.set == *set);
        let arc = match kept {
            Some(a) => {
                a.used = epoch;
                if a.arc.t0_gps_s != t0 || a.arc.t1_gps_s != t1 {
                    let o = orbit();
                    let o = o.borrow();
                    a.arc = if a.arc.t1_gps_s == t0 {
                        HermiteArc::new(&a.arc.end, &Node::of(o, t1))
                    } else {
                        HermiteArc::new(&Node::of(o, t0), &Node::of(o, t1))
                    };
                }
                a.arc
            }
            None => {
                let o = orbit();
                let o = o.borrow();
                let arc = HermiteArc::new(&Node::of(o, t0), &Node::of(o, t1));
                self.keep(id, o, arc);
                arc
            }
        };
        on(&arc, t_sv_gps_s)
    }

    /// Keep `arc` of satellite `id` on `orbit`: in the place of the
    /// satellite's arc of another set, else in a free place, else in the
    /// place of an arc no satellite of this epoch has used (not kept when
    /// there is none).
    fn keep(&mut self, id: SatId, orbit: &Orbit, arc: HermiteArc) {
        let epoch = self.epoch;
        let new = SatArc {
            id,
            set: orbit.set,
            arc,
            used: epoch,
        };
        let place = match self.arcs.iter().position(|a| a.id == id) {
            Some(i) => Some(i),
            None if self.arcs.len() < A => None,
            None => self.arcs.iter().position(|a| a.used != epoch),
        };
        match place.and_then(|i| self.arcs.get_mut(i)) {
            Some(slot) => *slot = new,
            None => {
                let _ = self.arcs.push(new);
            }
        }
    }
}

/// The transmit time, state and motion of satellite `id` on `orbit` for
/// a signal sent at `t_sv_gps_s` by its clock, on the arc of
/// [`arc_nodes_s`] with both its nodes evaluated here: what
/// [`KeplerArcs::transmit_state_motion`] gives, to the bit, without
/// keeping anything (the host's readers, whose cost does not matter, and
/// a build without room for arcs). With a non-finite time,
/// [`Orbit::transmit_state_motion`].
pub fn transmit_state_motion_on_arc(
    id: SatId,
    orbit: &Orbit,
    t_sv_gps_s: f64,
) -> (f64, SatState, SatMotion) {
    let (t0, t1) = arc_nodes_s(id, t_sv_gps_s);
    if !(t0.is_finite() && t1.is_finite()) {
        return orbit.transmit_state_motion(t_sv_gps_s);
    }
    on(
        &HermiteArc::new(&Node::of(orbit, t0), &Node::of(orbit, t1)),
        t_sv_gps_s,
    )
}

/// The transmit time, state and motion on `arc` of a signal sent at
/// `t_sv_gps_s`: the clock at t_sv, then the state and motion at t, t_sv
/// less the clock (before the arc's start by at most the clock offset,
/// below 1 ms, where the interpolation's remainder f''''(xi) / 4! (t -
/// t0)^2 (t - t1)^2 is below 1e-11 m).
fn on(arc: &HermiteArc, t_sv_gps_s: f64) -> (f64, SatState, SatMotion) {
    let t = t_sv_gps_s - arc.clock_s(t_sv_gps_s);
    let (state, motion) = arc.at(t);
    (t, state, motion)
}

/// The nodes (GPS s) of the arc satellite `id`'s state at GPS time
/// `t_gps_s` is interpolated on: the multiples of [`ARC_S`] offset by
/// the satellite's phase, 0 to 29 s by its number and system (so that the
/// satellites of an epoch reach their arcs' ends at different epochs),
/// the last at or before `t_gps_s` and the next.
pub fn arc_nodes_s(id: SatId, t_gps_s: f64) -> (f64, f64) {
    let system = match id.system {
        raim_core::System::Gps => 0u32,
        raim_core::System::Glonass => 1,
        raim_core::System::Galileo => 2,
        raim_core::System::Beidou => 3,
        raim_core::System::Qzss => 4,
    };
    let phase_s = f64::from((u32::from(id.prn) + 11 * system) % STAGGER as u32);
    let t0 = crate::m::floor((t_gps_s - phase_s) / ARC_S) * ARC_S + phase_s;
    (t0, t0 + ARC_S)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ephemeris::{circular, WEEK_S};
    use raim_core::System;

    fn set(prn: u8) -> Kepler {
        let mut k = circular(System::Gps, prn);
        k.e = 0.02;
        k.i0_rad = 0.96;
        k.m0_rad = 0.3 * f64::from(prn);
        k.omega_rad = 1.1;
        k.omega0_rad = -0.7;
        k.omega_dot_rad_s = -8e-9;
        k.idot_rad_s = 1e-10;
        k.cus_rad = 8e-6;
        k.crs_m = 60.0;
        k.cic_rad = 1e-7;
        k.af0_s = 3e-4;
        k.af1_s_s = 2e-12;
        k.af2_s_s2 = 1e-19;
        k
    }

    /// The arc's state and motion within the module doc's bound of the
    /// exact evaluation at the same time, epoch after epoch at 1 Hz across
    /// two hours (every refresh included), the transmit time the exact
    /// one's within its ulp; each epoch's bits those of a receiver that
    /// sees the satellite first at that epoch (no history) and of the
    /// arc evaluated afresh ([`transmit_state_motion_on_arc`]), across a
    /// gap in the stream and a change of set.
    ///
    /// Verifies: RX-FORM-ARC
    #[test]
    fn arcs_are_the_exact_orbit_within_the_bound() {
        let t0 = 1000.0 * WEEK_S + 0.5;
        let mut arcs = KeplerArcs::<4>::new();
        let (orbit, other) = (Orbit::new(&set(3)), Orbit::new(&set(9)));
        let id = SatId::new(System::Gps, 3);
        let mut worst = [0.0f64; 4];
        for i in 0..7200 {
            arcs.next_epoch();
            // A 40 s gap at 3600 s.
            if (3600..3640).contains(&i) {
                continue;
            }
            // Another set from 5000 s on.
            let o = if i >= 5000 { &other } else { &orbit };
            let t_sv = t0 + f64::from(i);
            let got = arcs.transmit_state_motion(id, o, t_sv);
            let (t, s, m) = got;
            let (te, _, _) = o.transmit_state_motion(t_sv);
            let (se, me) = o.state_motion(t);
            let d = |a: [f64; 3], b: [f64; 3]| {
                (0..3).map(|j| (a[j] - b[j]).powi(2)).sum::<f64>().sqrt()
            };
            worst[0] = worst[0].max((t - te).abs());
            worst[1] = worst[1].max(d(s.position_m, se.position_m));
            worst[2] = worst[2].max(d(m.velocity_m_s, me.velocity_m_s));
            worst[3] = worst[3].max((s.clock_s - se.clock_s).abs());
            assert!((m.clock_drift_s_s - me.clock_drift_s_s).abs() < 1e-18);
            if i % 7 == 0 {
                let mut fresh = KeplerArcs::<1>::new();
                assert_eq!(fresh.transmit_state_motion(id, o, t_sv), got, "{i}");
            }
            assert_eq!(transmit_state_motion_on_arc(id, o, t_sv), got, "{i}");
        }
        // The transmit times: the clock's rounding, 1e-19 s, moves t by
        // at most its own ulp (1.2e-7 s at week 1000).
        assert!(worst[0] <= 1.2e-7, "{worst:?}");
        assert!(worst[1] < 2.1e-4 && worst[2] < 2.1e-5, "{worst:?}");
        assert!(worst[3] < 1e-18, "{worst:?}");
        // The arc was used: mid-arc the result is not the exact one's bits.
        assert!(worst[1] > 0.0);
        assert_eq!(arcs.len(), 1);
        let mut none = KeplerArcs::<0>::new();
        let t = t0 + 7200.0;
        assert_eq!(
            none.transmit_state_motion(id, &orbit, t),
            transmit_state_motion_on_arc(id, &orbit, t)
        );
        assert!(none.is_empty());
    }

    /// A full set of arcs: a satellite beyond them has its arc evaluated
    /// afresh (the same bits) and takes the place of an arc no satellite
    /// of the epoch used at a later epoch; the lazily made orbit is not
    /// made while the kept arc covers the signal; a non-finite time gives
    /// the exact evaluation's (non-finite) result.
    ///
    /// Verifies: RX-FORM-ARC
    #[test]
    fn a_full_set_of_arcs_gives_way_and_keeps_the_bits() {
        let t = 1000.0 * WEEK_S + 100.25;
        let (a, b) = (Orbit::new(&set(3)), Orbit::new(&set(9)));
        let (ia, ib) = (SatId::new(System::Gps, 3), SatId::new(System::Gps, 9));
        let mut arcs = KeplerArcs::<1>::new();
        arcs.next_epoch();
        let ga = arcs.transmit_state_motion(ia, &a, t);
        let gb = arcs.transmit_state_motion(ib, &b, t);
        assert_eq!(ga, transmit_state_motion_on_arc(ia, &a, t));
        assert_eq!(gb, transmit_state_motion_on_arc(ib, &b, t));
        assert_eq!(arcs.len(), 1);
        // The next epoch: G09 alone takes G03's place.
        arcs.next_epoch();
        let gb = arcs.transmit_state_motion(ib, &b, t + 1.0);
        assert_eq!(gb, transmit_state_motion_on_arc(ib, &b, t + 1.0));
        assert_eq!(arcs.len(), 1);
        // Kept and covering: the orbit is not made.
        arcs.next_epoch();
        let mut made = false;
        let got = arcs.transmit_state_motion_of(ib, &b.set, t + 2.0, || {
            made = true;
            b
        });
        assert!(!made);
        assert_eq!(got, transmit_state_motion_on_arc(ib, &b, t + 2.0));
        let (tn, sn, _) = arcs.transmit_state_motion(ib, &b, f64::NAN);
        assert!(tn.is_nan() && sn.position_m.iter().all(|v| v.is_nan()));
    }

    /// Every system has a phase of its own (PRN 1 of each: five different
    /// seconds), an arc covers its own span, ends included, and nothing
    /// beyond it, and a non-finite time on the arc evaluated afresh gives
    /// the exact evaluation's (non-finite) result.
    ///
    /// Verifies: RX-FORM-ARC
    #[test]
    fn each_system_has_its_phase_and_an_arc_covers_its_span() {
        let t = 1000.0 * WEEK_S + 12.25;
        let mut phases = std::collections::BTreeSet::new();
        for system in [
            System::Gps,
            System::Glonass,
            System::Galileo,
            System::Beidou,
            System::Qzss,
        ] {
            let (a, b) = arc_nodes_s(SatId::new(system, 1), t);
            assert!(a <= t && t < b && b - a == ARC_S, "{system:?}");
            phases.insert((a - 1000.0 * WEEK_S).rem_euclid(ARC_S) as u32);
        }
        assert_eq!(phases.len(), 5, "{phases:?}");
        let id = SatId::new(System::Gps, 3);
        let o = Orbit::new(&set(3));
        let (a, b) = arc_nodes_s(id, t);
        let arc = HermiteArc::new(&Node::of(&o, a), &Node::of(&o, b));
        assert!(arc.covers(a) && arc.covers(b) && arc.covers(t));
        assert!(!arc.covers(a - 1e-3) && !arc.covers(b + 1e-3) && !arc.covers(f64::NAN));
        let (tn, sn, _) = transmit_state_motion_on_arc(id, &o, f64::NAN);
        assert!(tn.is_nan() && sn.position_m.iter().all(|v| v.is_nan()));
    }

    /// Nodes are ARC_S apart at the satellite's phase; the phases of GPS
    /// 1-30 are 30 different seconds.
    #[test]
    fn nodes_are_staggered_by_satellite() {
        let t = 1000.0 * WEEK_S + 12.25;
        let mut phases = std::collections::BTreeSet::new();
        for prn in 1..=30 {
            let (a, b) = arc_nodes_s(SatId::new(System::Gps, prn), t);
            assert!(a <= t && t < b && b - a == ARC_S);
            assert_eq!(a, a.floor());
            phases.insert((a - 1000.0 * WEEK_S).rem_euclid(ARC_S) as u32);
        }
        assert_eq!(phases.len(), 30);
    }
}
