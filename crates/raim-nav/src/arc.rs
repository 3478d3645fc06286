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
//! largest, mid-arc). An Earth-fixed broadcast orbit's position has
//! |f''''| <= (n_max + omega_e)^4 r_max, with n_max the largest angular
//! rate of the true anomaly, n (1 + e)^2 / (1 - e^2)^(3/2), and r_max =
//! A (1 + e) (the harmonic corrections, below 1e-5 of r, move it by as
//! little): for GPS (A = 26,560 km, e < 0.03) 6.4e-8 m/s^4, for Galileo's
//! E14 and E18 (A = 27,980 km, e = 0.16) 1.9e-7 m/s^4, for a BeiDou GEO or
//! IGSO (A = 42,160 km) 3e-8 m/s^4. With h = [`ARC_S`] = 30 s: positions
//! within 2.1e-4 m (Galileo's eccentric pair 4.0e-4 m), velocities within
//! 2.1e-5 m/s (4.3e-5 m/s). The clock is a quadratic, which the cubic
//! reproduces, plus the relativistic term F e sqrt(A) sin E, whose fourth
//! derivative is below 1e-21 s/s^4. Checked on every Keplerian set of
//! the shared navigation files and GMSD7's 1019s across each fit
//! interval against the exact evaluation, with the fourth derivative
//! measured by differences (host-tests `orbit_sums`): within 1 mm and 1
//! mm/s, as the bound says.
//!
//! **Refresh.** A satellite first seen with a set (or seen with a new
//! one, or after a gap longer than its arc) is evaluated exactly at its
//! transmit time, which becomes its first node; the epoch after it
//! evaluates the second node, and an epoch past an arc's end (within the
//! next arc) the next node ARC_S on: an epoch evaluates at most one
//! orbit per satellite, as without arcs, and a satellite in steady
//! tracking one every ARC_S. The first arc of a satellite is `1 + slot %
//! 30` seconds long, its slot being its place among the arcs, so that
//! satellites first seen in the same epoch (a stream's start, a
//! constellation whose sets change at the same toe, GPS's every two
//! hours) reach their arcs' ends at different epochs. A stream whose
//! epochs are ARC_S or more apart is evaluated exactly at every epoch.
//!
//! An epoch's bits depend on where its satellites' arcs started, i.e. on
//! the epochs before it in the stream (within the bound above of the
//! exact evaluation). The host's stream reader and the device's form their epochs
//! through the same receiver and arcs, so they form the same bits from
//! the same stream. A build
//! without room for the arcs (`ram-192k`, the STM32F4's) evaluates each
//! transmit state exactly: its epochs are within the bound above of the
//! others', not their bits.

use heapless::Vec;
use raim_core::SatId;

use crate::ephemeris::{Kepler, Orbit, SatState};
use crate::velocity::SatMotion;

/// An arc's length between its nodes, s (the error bound, module doc).
pub const ARC_S: f64 = 30.0;
/// First arcs are 1 to this many seconds long, by slot (module doc).
const STAGGER: usize = 30;
/// An arc is used this far beyond its ends, s: a node is a transmit time,
/// and the next epoch's signal time t_sv differs from its transmit time
/// by the satellite's clock offset, below 1 ms. The interpolation's
/// remainder f''''(xi) / 4! (t - t0)^2 (t - t1)^2 there is below h^2
/// (1 ms)^2 / 24 max|f''''|, 1e-11 m, far within the bound.
pub const CLOCK_MARGIN_S: f64 = 1e-3;

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

    /// True when `t_gps_s` is within the arc, or beyond an end by at most
    /// [`CLOCK_MARGIN_S`].
    pub fn covers(&self, t_gps_s: f64) -> bool {
        t_gps_s >= self.t0_gps_s - CLOCK_MARGIN_S && t_gps_s <= self.t1_gps_s + CLOCK_MARGIN_S
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

/// What a satellite's arc has.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Nodes {
    /// One node, and the second's distance from it, s.
    First(Node, f64),
    /// An arc.
    Arc(HermiteArc),
}

/// One satellite's arc, for one Keplerian set.
#[derive(Debug, Clone, PartialEq)]
struct SatArc {
    id: SatId,
    /// The set the nodes are of (compared whole).
    set: Kepler,
    nodes: Nodes,
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
    /// from the satellite's arc when it covers the signal (the clock at
    /// t_sv, then the state and motion at t = t_sv - clock), after
    /// evaluating the arc's next node ([`Node::of`]) when the signal is
    /// past its end but within the next arc; else exactly, and the result
    /// the first node of a new arc. At most one evaluation of the orbit.
    pub fn transmit_state_motion(
        &mut self,
        id: SatId,
        orbit: &Orbit,
        t_sv_gps_s: f64,
    ) -> (f64, SatState, SatMotion) {
        let epoch = self.epoch;
        let kept = self
            .arcs
            .iter()
            .position(|a| a.id == id && a.set == orbit.set);
        let Some((slot, a)) = kept.and_then(|i| Some((i, self.arcs.get_mut(i)?))) else {
            return self.start(id, orbit, t_sv_gps_s);
        };
        a.used = epoch;
        let arc = match a.nodes {
            Nodes::First(n, len)
                if t_sv_gps_s > n.t_gps_s && t_sv_gps_s <= n.t_gps_s + len + CLOCK_MARGIN_S =>
            {
                Some(HermiteArc::new(&n, &Node::of(orbit, n.t_gps_s + len)))
            }
            Nodes::Arc(arc) if arc.covers(t_sv_gps_s) => Some(arc),
            Nodes::Arc(arc)
                if t_sv_gps_s > arc.t1_gps_s
                    && t_sv_gps_s <= arc.t1_gps_s + ARC_S + CLOCK_MARGIN_S =>
            {
                Some(HermiteArc::new(
                    &arc.end,
                    &Node::of(orbit, arc.t1_gps_s + ARC_S),
                ))
            }
            _ => None,
        };
        if let Some(arc) = arc {
            a.nodes = Nodes::Arc(arc);
            let t = t_sv_gps_s - arc.clock_s(t_sv_gps_s);
            let (state, motion) = arc.at(t);
            return (t, state, motion);
        }
        // Outside the arc and the next: exactly, and a new arc from here.
        let (t, state, motion) = orbit.transmit_state_motion(t_sv_gps_s);
        a.nodes = Nodes::First(
            Node {
                t_gps_s: t,
                state,
                motion,
            },
            first_length_s(slot),
        );
        (t, state, motion)
    }

    /// A satellite without an arc for `orbit`: exactly, and its arc's
    /// first node kept in the place of its arc of another set, else in a
    /// free place, else in the place of an arc no satellite of this
    /// epoch has used (not kept when there is none).
    fn start(&mut self, id: SatId, orbit: &Orbit, t_sv_gps_s: f64) -> (f64, SatState, SatMotion) {
        let (t, state, motion) = orbit.transmit_state_motion(t_sv_gps_s);
        let epoch = self.epoch;
        let place = match self.arcs.iter().position(|a| a.id == id) {
            Some(i) => Some(i),
            None if self.arcs.len() < A => Some(self.arcs.len()),
            None => self.arcs.iter().position(|a| a.used != epoch),
        };
        if let Some(slot) = place {
            let new = SatArc {
                id,
                set: orbit.set,
                nodes: Nodes::First(
                    Node {
                        t_gps_s: t,
                        state,
                        motion,
                    },
                    first_length_s(slot),
                ),
                used: epoch,
            };
            match self.arcs.get_mut(slot) {
                Some(s) => *s = new,
                None => {
                    let _ = self.arcs.push(new);
                }
            }
        }
        (t, state, motion)
    }
}

/// The first arc's length of the arc in `slot`, s: 1 to [`STAGGER`]
/// seconds by slot, at most [`ARC_S`] (module doc).
fn first_length_s(slot: usize) -> f64 {
    let k = slot % STAGGER + 1;
    ARC_S * k as f64 / STAGGER as f64
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
    /// two hours (every refresh included), across a 40 s gap in the
    /// stream and a change of set, the transmit time the exact one's
    /// within its ulp; the first epoch of an arc the exact bits; with
    /// capacity 0, the exact bits at every epoch.
    ///
    /// Verifies: RX-FORM-ARC
    #[test]
    fn arcs_are_the_exact_orbit_within_the_bound() {
        let t0 = 1000.0 * WEEK_S + 0.5;
        let mut arcs = KeplerArcs::<4>::new();
        let mut none = KeplerArcs::<0>::new();
        let (orbit, other) = (Orbit::new(&set(3)), Orbit::new(&set(9)));
        let id = SatId::new(System::Gps, 3);
        let mut worst = [0.0f64; 4];
        let mut exact = 0;
        for i in 0..7200 {
            arcs.next_epoch();
            // A 40 s gap at 3600 s.
            if (3600..3640).contains(&i) {
                continue;
            }
            // Another set from 5000 s on.
            let o = if i >= 5000 { &other } else { &orbit };
            let t_sv = t0 + f64::from(i);
            let (t, s, m) = arcs.transmit_state_motion(id, o, t_sv);
            let want = o.transmit_state_motion(t_sv);
            assert_eq!(none.transmit_state_motion(id, o, t_sv), want);
            if (t, s, m) == want {
                exact += 1;
            }
            let (se, me) = o.state_motion(t);
            let d = |a: [f64; 3], b: [f64; 3]| {
                (0..3).map(|j| (a[j] - b[j]).powi(2)).sum::<f64>().sqrt()
            };
            worst[0] = worst[0].max((t - want.0).abs());
            worst[1] = worst[1].max(d(s.position_m, se.position_m));
            worst[2] = worst[2].max(d(m.velocity_m_s, me.velocity_m_s));
            worst[3] = worst[3].max((s.clock_s - se.clock_s).abs());
            assert!((m.clock_drift_s_s - me.clock_drift_s_s).abs() < 1e-18);
        }
        // The transmit times: the clock's rounding, 1e-19 s, moves t by
        // at most its own ulp (1.2e-7 s at week 1000).
        assert!(worst[0] <= 1.2e-7, "{worst:?}");
        assert!(worst[1] < 2.1e-4 && worst[2] < 2.1e-5, "{worst:?}");
        assert!(worst[3] < 1e-18, "{worst:?}");
        // Exact at the three starts (first epoch, after the gap, the new
        // set) and where a node falls on an epoch; interpolated between.
        println!("{exact} exact epochs; worst {worst:?}");
        assert!((3..300).contains(&exact), "{exact}");
        assert_eq!(arcs.len(), 1);
        assert!(none.is_empty());
    }

    /// First arcs are staggered by slot: 1 to 30 s, never longer than
    /// [`ARC_S`].
    #[test]
    fn first_arcs_are_staggered() {
        assert_eq!(first_length_s(0), 1.0);
        assert_eq!(first_length_s(29), ARC_S);
        assert_eq!(first_length_s(30), 1.0);
        assert!((0..64).all(|s| first_length_s(s) <= ARC_S));
    }
}
