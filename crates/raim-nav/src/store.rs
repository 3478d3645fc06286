//! The broadcast ephemerides a receiver has decoded so far, in fixed
//! capacity: Keplerian sets (`K` of them) and GLONASS state vectors (`G`),
//! with the selection rule of the host's navigation data (the healthy set
//! whose reference time is nearest the epoch, within
//! [`max_ephemeris_age_s`]).

use heapless::Vec;
use raim_core::{SatId, System};

use crate::ephemeris::Kepler;
use crate::glonass::GlonassEphemeris;
use crate::ranging::Broadcast;

/// Largest |t - toe| at which a broadcast ephemeris is used, s (the
/// classic single-point choices: GPS 2 h, Galileo 4 h, BeiDou 6 h,
/// GLONASS 30 min, the spacing of its t_b).
pub fn max_ephemeris_age_s(system: System) -> f64 {
    match system {
        System::Gps | System::Qzss => 7_200.0,
        System::Galileo => 14_400.0,
        System::Beidou => 21_600.0,
        System::Glonass => 1_800.0,
    }
}

/// |t - toe| of a Keplerian set at GPS time `t_gps_s` (IS-GPS-200's
/// week-free t_k), or None when the set is not of `t_gps_s`'s week: t_k
/// alone cannot tell a set from the same one a week earlier, so the set's
/// absolute toc must also be within twice the system's
/// [`max_ephemeris_age_s`] of t (toc and toe are within minutes of each
/// other for every system).
pub fn kepler_age_s(k: &Kepler, t_gps_s: f64) -> Option<f64> {
    let max_age = max_ephemeris_age_s(k.system);
    let age = k.tk_s(t_gps_s).abs();
    ((t_gps_s - k.toc_gps_s).abs() <= 2.0 * max_age).then_some(age)
}

/// What [`EphemerisStore::insert_kepler`] and
/// [`EphemerisStore::insert_glonass`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stored {
    /// A new set.
    Added,
    /// The same set again (a stream repeats each one): nothing changed.
    Repeat,
    /// A new set, in the place of the oldest one (the store was full).
    Replaced,
}

/// Fixed-capacity ephemeris store.
#[derive(Debug, Clone)]
pub struct EphemerisStore<const K: usize, const G: usize> {
    kepler: Vec<Kepler, K>,
    glonass: Vec<GlonassEphemeris, G>,
}

impl<const K: usize, const G: usize> Default for EphemerisStore<K, G> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const K: usize, const G: usize> EphemerisStore<K, G> {
    /// An empty store.
    pub const fn new() -> Self {
        EphemerisStore {
            kepler: Vec::new(),
            glonass: Vec::new(),
        }
    }

    /// Forget every set.
    pub fn clear(&mut self) {
        self.kepler.clear();
        self.glonass.clear();
    }

    /// Forget every GLONASS set (their t_b were placed with a leap-second
    /// count found wrong).
    pub fn clear_glonass(&mut self) {
        self.glonass.clear();
    }

    /// Number of Keplerian and GLONASS sets held.
    pub fn len(&self) -> (usize, usize) {
        (self.kepler.len(), self.glonass.len())
    }

    /// True when no set is held.
    pub fn is_empty(&self) -> bool {
        self.kepler.is_empty() && self.glonass.is_empty()
    }

    /// Add a Keplerian set; a full store drops its oldest (toc) set.
    pub fn insert_kepler(&mut self, k: Kepler) -> Stored {
        if self.kepler.contains(&k) {
            return Stored::Repeat;
        }
        insert_oldest_out(&mut self.kepler, k, |e| e.toc_gps_s)
    }

    /// Add a GLONASS set; a full store drops its oldest (t_b) set.
    pub fn insert_glonass(&mut self, g: GlonassEphemeris) -> Stored {
        if self.glonass.contains(&g) {
            return Stored::Repeat;
        }
        insert_oldest_out(&mut self.glonass, g, |e| e.tb_gps_s)
    }

    /// The healthy set of `id` whose toe (t_b) is nearest `t_gps_s`, within
    /// [`max_ephemeris_age_s`]; the first such set on a tie.
    pub fn select(&self, id: SatId, t_gps_s: f64) -> Option<Broadcast<'_>> {
        let max_age = max_ephemeris_age_s(id.system);
        let best = |a: (f64, usize), b: (f64, usize)| if b.0 < a.0 { b } else { a };
        if id.system == System::Glonass {
            let (_, i) = self
                .glonass
                .iter()
                .enumerate()
                .filter(|(_, g)| g.slot == id.prn && g.health == 0)
                .map(|(i, g)| (g.age_s(t_gps_s).abs(), i))
                .filter(|(age, _)| *age <= max_age)
                .reduce(best)?;
            self.glonass.get(i).map(Broadcast::Glonass)
        } else {
            let (_, i) = self
                .kepler
                .iter()
                .enumerate()
                .filter(|(_, k)| k.system == id.system && k.prn == id.prn && k.health == 0)
                .filter_map(|(i, k)| Some((kepler_age_s(k, t_gps_s)?, i)))
                .filter(|(age, _)| *age <= max_age)
                .reduce(best)?;
            self.kepler.get(i).map(Broadcast::Kepler)
        }
    }
}

/// Push `x`, or replace the element with the smallest `time` when full
/// (a store of capacity 0 keeps nothing and says `Replaced`).
fn insert_oldest_out<T, const N: usize>(
    v: &mut Vec<T, N>,
    x: T,
    time: impl Fn(&T) -> f64,
) -> Stored {
    match v.push(x) {
        Ok(()) => Stored::Added,
        Err(x) => {
            let oldest = v
                .iter()
                .enumerate()
                .map(|(i, e)| (time(e), i))
                .reduce(|a, b| if b.0 < a.0 { b } else { a });
            if let Some(slot) = oldest.and_then(|(_, i)| v.get_mut(i)) {
                *slot = x;
            }
            Stored::Replaced
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(prn: u8, toe_s: f64, health: u32) -> Kepler {
        Kepler {
            toc_gps_s: 1000.0 * 604_800.0 + toe_s,
            toe_sow_s: toe_s,
            health,
            ..crate::ephemeris::circular(System::Gps, prn)
        }
    }

    /// The nearest healthy set within 2 h is chosen; a repeat is not
    /// stored twice; a full store drops the oldest set.
    #[test]
    fn selection_and_capacity() {
        let mut s = EphemerisStore::<3, 1>::new();
        assert_eq!(s.insert_kepler(k(5, 7_200.0, 0)), Stored::Added);
        assert_eq!(s.insert_kepler(k(5, 7_200.0, 0)), Stored::Repeat);
        assert_eq!(s.insert_kepler(k(5, 14_400.0, 0)), Stored::Added);
        assert_eq!(s.insert_kepler(k(5, 21_600.0, 1)), Stored::Added);
        let t = 1000.0 * 604_800.0 + 12_000.0;
        let pick = |s: &EphemerisStore<3, 1>, t: f64| match s.select(SatId::new(System::Gps, 5), t)
        {
            Some(Broadcast::Kepler(k)) => Some(k.toe_sow_s),
            _ => None,
        };
        assert_eq!(pick(&s, t), Some(14_400.0));
        // The unhealthy set at 21600 is nearer at 20000 but not used.
        assert_eq!(pick(&s, 1000.0 * 604_800.0 + 20_000.0), Some(14_400.0));
        // Beyond 2 h of every healthy set: none.
        assert_eq!(pick(&s, 1000.0 * 604_800.0 + 14_400.0 + 7_201.0), None);
        assert_eq!(s.select(SatId::new(System::Gps, 6), t), None);
        // A week later the sets have the same t_k, but not the week.
        assert_eq!(pick(&s, t + 604_800.0), None);
        // Full: the oldest (toe 7200) goes.
        assert_eq!(s.insert_kepler(k(5, 28_800.0, 0)), Stored::Replaced);
        assert_eq!(pick(&s, 1000.0 * 604_800.0 + 7_200.0), Some(14_400.0));
        assert_eq!(s.len(), (3, 0));
    }

    /// A Galileo set is used up to 4 h from its toe and not beyond (the
    /// age of each system: GPS 2 h above); `clear_glonass` keeps the
    /// Keplerian sets (the receiver re-places only GLONASS after a
    /// leap-second change), `clear` forgets every set, and `is_empty` says
    /// so.
    ///
    /// Verifies: RX-STREAM
    #[test]
    fn galileo_age_and_clearing() {
        let mut s = EphemerisStore::<3, 1>::new();
        assert!(s.is_empty());
        let e11 = Kepler {
            toc_gps_s: 1000.0 * 604_800.0 + 7_200.0,
            toe_sow_s: 7_200.0,
            ..crate::ephemeris::circular(System::Galileo, 11)
        };
        assert_eq!(s.insert_kepler(e11), Stored::Added);
        let id = SatId::new(System::Galileo, 11);
        let at = |dt: f64| 1000.0 * 604_800.0 + 7_200.0 + dt;
        assert!(s.select(id, at(14_400.0)).is_some());
        assert!(s.select(id, at(-14_400.0)).is_some());
        assert!(s.select(id, at(14_401.0)).is_none());
        assert!(!s.is_empty());
        s.clear_glonass();
        assert_eq!(s.len(), (1, 0));
        s.clear();
        assert_eq!(s.len(), (0, 0));
        assert!(s.is_empty());
        assert!(s.select(id, at(0.0)).is_none());
    }
}
