//! The broadcast ephemerides a receiver has decoded so far, in fixed
//! capacity (`EphemerisStore`, feature `rtcm`): Keplerian sets (`K` of
//! them, each kept as its RTCM message's payload and decoded when an
//! epoch uses it) and GLONASS state vectors (`G`), with the selection
//! rule of the host's navigation data (the healthy set whose reference
//! time is nearest the epoch, within [`max_ephemeris_age_s`]).

#[cfg(feature = "rtcm")]
use heapless::Vec;
#[cfg(feature = "rtcm")]
use raim_core::SatId;
use raim_core::System;

use crate::ephemeris::Kepler;
#[cfg(feature = "rtcm")]
use crate::ephemeris::Orbit;
#[cfg(feature = "rtcm")]
use crate::glonass::GlonassEphemeris;
#[cfg(feature = "rtcm")]
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
    /// A Keplerian set not kept: its message's payload is longer than
    /// [`KEPLER_PAYLOAD_BYTES`] (the longest of RTCM 10403.3's Keplerian
    /// messages, 1042's 511 bits, fills 64) or does not decode to the set.
    NotKept {
        /// The payload's length, bytes.
        payload_len: u16,
    },
}

/// Bytes of a Keplerian message's payload the store keeps: 1019 is 488
/// bits, 1044 485, 1045 496, 1046 504 and 1042 511 (RTCM 10403.3
/// §3.5.11-3.5.14), 64 bytes at most.
#[cfg(feature = "rtcm")]
pub const KEPLER_PAYLOAD_BYTES: usize = 64;

/// A Keplerian set as the payload of the message it came in (88 B,
/// against the decoded set's 192 B of f64): decoded again by the one
/// decoder ([`crate::rtcm::decode::kepler_message`] and
/// [`crate::rtcm::fields::kepler`]) when an epoch uses it, so the set an
/// epoch uses is the set the message carried, to the bit. The toc is the
/// one placed when the message arrived (its week from the receiver's
/// pivot, `rtcm::fields::gps_week_of`); toe and health are kept decoded
/// for the choice of the set ([`EphemerisStore::select`]).
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone, PartialEq)]
struct KeplerBits {
    toc_gps_s: f64,
    toe_sow_s: f64,
    health: u32,
    system: System,
    prn: u8,
    /// Bytes of `payload` in use.
    len: u8,
    payload: [u8; KEPLER_PAYLOAD_BYTES],
}

#[cfg(feature = "rtcm")]
impl KeplerBits {
    /// `k` as `payload`, when the payload fits and decodes to `k`.
    fn new(k: &Kepler, payload: &[u8]) -> Option<Self> {
        let mut b = KeplerBits {
            toc_gps_s: k.toc_gps_s,
            toe_sow_s: k.toe_sow_s,
            health: k.health,
            system: k.system,
            prn: k.prn,
            len: u8::try_from(payload.len()).ok()?,
            payload: [0; KEPLER_PAYLOAD_BYTES],
        };
        b.payload.get_mut(..payload.len())?.copy_from_slice(payload);
        (b.decode().as_ref() == Some(k)).then_some(b)
    }

    /// Whether `other` is the same message, placed alike: the same
    /// payload, toc and key (cheap fields first).
    fn same(&self, other: &KeplerBits) -> bool {
        self.prn == other.prn
            && self.system == other.system
            && self.len == other.len
            && self.payload == other.payload
            && self.toc_gps_s.to_bits() == other.toc_gps_s.to_bits()
            && self.toe_sow_s.to_bits() == other.toe_sow_s.to_bits()
            && self.health == other.health
    }

    /// Whether this may be `k` (the decoded set must then be compared).
    fn keys_match(&self, k: &Kepler) -> bool {
        self.system == k.system
            && self.prn == k.prn
            && self.health == k.health
            && self.toe_sow_s == k.toe_sow_s
            && self.toc_gps_s == k.toc_gps_s
    }

    /// The set, decoded as the receiver decoded it on arrival.
    fn decode(&self) -> Option<Kepler> {
        let payload = self.payload.get(..usize::from(self.len))?;
        let m = crate::rtcm::decode::kepler_message(payload).ok()?;
        let mut k = crate::rtcm::fields::kepler(m.system, m.prn, &m.fields);
        k.toc_gps_s = self.toc_gps_s;
        Some(k)
    }

    /// [`kepler_age_s`] of the set at GPS time `t_gps_s`, whose seconds of
    /// the set's system's week are `sow_s` (`ephemeris::system_sow_s`,
    /// computed once for every set of the system): the same operations
    /// on the set's toe and toc, without decoding the set.
    fn age_s(&self, t_gps_s: f64, sow_s: f64) -> Option<f64> {
        let max_age = max_ephemeris_age_s(self.system);
        let age = crate::ephemeris::tk_from_sow_s(sow_s, self.toe_sow_s).abs();
        ((t_gps_s - self.toc_gps_s).abs() <= 2.0 * max_age).then_some(age)
    }
}

/// No decoded set left for the satellite: the epoch's satellites outnumber
/// the decoded sets ([`EphemerisStore::load`]).
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecodedFull {
    /// Sets one epoch may decode.
    pub capacity: u32,
}

/// The Keplerian sets one epoch uses, decoded from the store's payloads
/// ([`EphemerisStore::load`], then [`EphemerisStore::select`]): `D` of
/// them, each with the index of the set it was decoded from. Held apart
/// from the store, so that the room serves other work between epochs
/// (raim-server lends it while forming only); stamped with the store's
/// generation, so that a set replaced since is never given.
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone)]
pub struct DecodedSets<const D: usize> {
    sets: Vec<(usize, Kepler), D>,
    /// The store's generation the sets were decoded at.
    generation: u64,
}

#[cfg(feature = "rtcm")]
impl<const D: usize> DecodedSets<D> {
    /// None decoded.
    pub const fn new() -> Self {
        DecodedSets {
            sets: Vec::new(),
            generation: 0,
        }
    }
}

#[cfg(feature = "rtcm")]
impl<const D: usize> Default for DecodedSets<D> {
    fn default() -> Self {
        Self::new()
    }
}

/// One decoded set of an [`OrbitCache`]: the payload it was decoded
/// from (its key, compared whole) and the set with its orbit's
/// constants.
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone)]
struct CachedOrbit {
    bits: KeplerBits,
    orbit: Orbit,
    /// The cache's epoch count when an epoch last used it.
    used: u32,
}

/// Where the set [`EphemerisStore::load_cached`] chose for a satellite
/// is, for the same epoch's [`EphemerisStore::select_chosen`].
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Chosen {
    /// No set in force (or one whose payload does not decode).
    None,
    /// A GLONASS satellite: its sets are kept decoded, chosen at select.
    Glonass,
    /// Kept in the cache, at this place.
    Kept(u16),
    /// Decoded for the epoch: the store's set of this index.
    Decoded(u16),
}

#[cfg(feature = "rtcm")]
impl Chosen {
    /// `make` of `i`, None when `i` does not fit a u16 (no store or cache
    /// holds 65,536 sets).
    fn at(i: usize, make: fn(u16) -> Chosen) -> Chosen {
        u16::try_from(i).map_or(Chosen::None, make)
    }
}

/// Decoded Keplerian sets kept across epochs, `C` of them, so that a set
/// is decoded and its orbit's constants computed ([`Orbit::new`]) once,
/// not at every epoch ([`EphemerisStore::load_cached`],
/// [`EphemerisStore::select_cached`]; BENCHMARKS.md "Forming by sum
/// formulas"). Each is keyed by the whole payload it came from: a set
/// the store replaced, or one another message of the satellite changed,
/// has another payload and is never matched, so a kept set is the set
/// its payload decodes to, to the bit, however the store has changed.
/// Sets used by the current epoch are kept; when the cache is full, one
/// an earlier epoch used last gives way, and with none such the set is
/// decoded into the epoch's [`DecodedSets`] as without a cache. A cache of
/// capacity 0 (a part without the RAM, feature `ram-192k`) keeps nothing.
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone)]
pub struct OrbitCache<const C: usize> {
    sets: Vec<CachedOrbit, C>,
    /// Epochs started ([`Self::next_epoch`]), wrapping.
    epoch: u32,
}

#[cfg(feature = "rtcm")]
impl<const C: usize> OrbitCache<C> {
    /// Nothing kept.
    pub const fn new() -> Self {
        OrbitCache {
            sets: Vec::new(),
            epoch: 0,
        }
    }

    /// A new epoch: the sets the last one used may now give way.
    pub fn next_epoch(&mut self) {
        self.epoch = self.epoch.wrapping_add(1);
    }

    /// Sets kept.
    pub fn len(&self) -> usize {
        self.sets.len()
    }

    /// True when no set is kept.
    pub fn is_empty(&self) -> bool {
        self.sets.is_empty()
    }

    /// The place of the kept set decoded from `bits`, marked used by this
    /// epoch.
    fn find_and_mark(&mut self, bits: &KeplerBits) -> Option<usize> {
        let epoch = self.epoch;
        let i = self.sets.iter().position(|c| c.bits.same(bits))?;
        if let Some(c) = self.sets.get_mut(i) {
            c.used = epoch;
        }
        Some(i)
    }

    /// Keep `orbit`, decoded from `bits`, in a free place or in the place
    /// of a set no set of this epoch is: its place, None when there is
    /// none. (A place this epoch uses is not given to another set before
    /// the next epoch, so a place [`EphemerisStore::load_cached`] gives
    /// stays the set's for the epoch.)
    fn keep(&mut self, bits: &KeplerBits, orbit: Orbit) -> Option<usize> {
        let c = CachedOrbit {
            bits: bits.clone(),
            orbit,
            used: self.epoch,
        };
        let epoch = self.epoch;
        match self.sets.push(c) {
            Ok(()) => Some(self.sets.len() - 1),
            Err(c) => {
                let i = self.sets.iter().position(|x| x.used != epoch)?;
                if let Some(slot) = self.sets.get_mut(i) {
                    *slot = c;
                }
                Some(i)
            }
        }
    }
}

#[cfg(feature = "rtcm")]
impl<const C: usize> Default for OrbitCache<C> {
    fn default() -> Self {
        Self::new()
    }
}

/// Fixed-capacity ephemeris store: `K` Keplerian sets, kept as their
/// messages' payloads and decoded for an epoch into [`DecodedSets`]
/// ([`Self::load`], then [`Self::select`]), and `G` GLONASS sets.
#[cfg(feature = "rtcm")]
#[derive(Debug, Clone)]
pub struct EphemerisStore<const K: usize, const G: usize> {
    kepler: Vec<KeplerBits, K>,
    glonass: Vec<GlonassEphemeris, G>,
    /// Counts the changes of `kepler`: decoded sets of another generation
    /// are not given ([`DecodedSets`]).
    generation: u64,
}

#[cfg(feature = "rtcm")]
impl<const K: usize, const G: usize> Default for EphemerisStore<K, G> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(feature = "rtcm")]
impl<const K: usize, const G: usize> EphemerisStore<K, G> {
    /// An empty store.
    pub const fn new() -> Self {
        EphemerisStore {
            kepler: Vec::new(),
            glonass: Vec::new(),
            // Above the decoded sets' initial 0: nothing is given before a
            // `start_epoch` or `load`.
            generation: 1,
        }
    }

    /// Forget every set.
    pub fn clear(&mut self) {
        self.kepler.clear();
        self.glonass.clear();
        self.generation = self.generation.wrapping_add(1);
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

    /// Add a Keplerian set `k`, decoded by the receiver from `payload`
    /// (its message from DF002 on, [`crate::rtcm::decode::Frame::payload`]):
    /// the payload is kept, and must decode to `k` again
    /// ([`Stored::NotKept`] otherwise). A full store drops its oldest
    /// (toc) set. Sets decoded before ([`DecodedSets`]) are no longer
    /// given.
    pub fn insert_kepler(&mut self, k: Kepler, payload: &[u8]) -> Stored {
        if self
            .kepler
            .iter()
            .any(|b| b.keys_match(&k) && b.decode().as_ref() == Some(&k))
        {
            return Stored::Repeat;
        }
        let Some(bits) = KeplerBits::new(&k, payload) else {
            return Stored::NotKept {
                payload_len: u16::try_from(payload.len()).unwrap_or(u16::MAX),
            };
        };
        self.generation = self.generation.wrapping_add(1);
        insert_oldest_out(&mut self.kepler, bits, |e| e.toc_gps_s)
    }

    /// Add a GLONASS set; a full store drops its oldest (t_b) set.
    pub fn insert_glonass(&mut self, g: GlonassEphemeris) -> Stored {
        if self.glonass.contains(&g) {
            return Stored::Repeat;
        }
        insert_oldest_out(&mut self.glonass, g, |e| e.tb_gps_s)
    }

    /// Empty `decoded` for a new epoch's [`Self::load`]s.
    pub fn start_epoch<const D: usize>(&self, decoded: &mut DecodedSets<D>) {
        decoded.sets.clear();
        decoded.generation = self.generation;
    }

    /// Decode into `decoded` the Keplerian set [`Self::select`] will
    /// choose for `id` at `t_gps_s`, if any (nothing to do for GLONASS,
    /// whose sets are kept decoded); `Err` when `D` sets are already
    /// decoded.
    pub fn load<const D: usize>(
        &self,
        id: SatId,
        t_gps_s: f64,
        decoded: &mut DecodedSets<D>,
    ) -> Result<(), DecodedFull> {
        self.load_cached(id, t_gps_s, decoded, &mut OrbitCache::<0>::new())
            .map(|_| ())
    }

    /// [`Self::load`] with the sets kept across epochs in `cache`: a set
    /// kept there is not decoded again; a set decoded is kept there when
    /// there is room ([`OrbitCache`]), else decoded into `decoded`. The
    /// cache's [`OrbitCache::next_epoch`] is the caller's, once an epoch
    /// before its loads. Returns where the chosen set is, which
    /// [`Self::select_chosen`] takes for the same epoch instead of
    /// choosing again.
    pub fn load_cached<const D: usize, const C: usize>(
        &self,
        id: SatId,
        t_gps_s: f64,
        decoded: &mut DecodedSets<D>,
        cache: &mut OrbitCache<C>,
    ) -> Result<Chosen, DecodedFull> {
        if decoded.generation != self.generation {
            self.start_epoch(decoded);
        }
        if id.system == System::Glonass {
            return Ok(Chosen::Glonass);
        }
        let Some(i) = self.choose_kepler(id, t_gps_s) else {
            return Ok(Chosen::None);
        };
        let Some(bits) = self.kepler.get(i) else {
            return Ok(Chosen::None);
        };
        if let Some(slot) = cache.find_and_mark(bits) {
            return Ok(Chosen::at(slot, Chosen::Kept));
        }
        if decoded.sets.iter().any(|(j, _)| *j == i) {
            return Ok(Chosen::at(i, Chosen::Decoded));
        }
        let Some(k) = bits.decode() else {
            return Ok(Chosen::None);
        };
        if C > 0 {
            if let Some(slot) = cache.keep(bits, Orbit::new(&k)) {
                return Ok(Chosen::at(slot, Chosen::Kept));
            }
        }
        decoded
            .sets
            .push((i, k))
            .map(|()| Chosen::at(i, Chosen::Decoded))
            .map_err(|_| DecodedFull {
                capacity: u32::try_from(D).unwrap_or(u32::MAX),
            })
    }

    /// [`Self::select_cached`] for a satellite whose set `chosen` this
    /// epoch's [`Self::load_cached`] gave (the store, `decoded` and
    /// `cache` unchanged since): the same set without choosing it again
    /// (the choice scans the store's sets and reduces the time to each
    /// set's week: BENCHMARKS.md "Orbit arcs").
    pub fn select_chosen<'a, const D: usize, const C: usize>(
        &'a self,
        id: SatId,
        t_gps_s: f64,
        chosen: Chosen,
        decoded: &'a DecodedSets<D>,
        cache: &'a OrbitCache<C>,
    ) -> Option<Broadcast<'a>> {
        match chosen {
            Chosen::None => None,
            Chosen::Glonass => self.select_in(id, t_gps_s, decoded, &[]),
            Chosen::Kept(slot) => cache
                .sets
                .get(usize::from(slot))
                .map(|c| Broadcast::Orbit(&c.orbit)),
            Chosen::Decoded(i) => {
                let i = usize::from(i);
                if decoded.generation != self.generation {
                    return None;
                }
                decoded
                    .sets
                    .iter()
                    .find(|(j, _)| *j == i)
                    .map(|(_, k)| Broadcast::Kepler(k))
            }
        }
    }

    /// The healthy set of `id` whose toe (t_b) is nearest `t_gps_s`, within
    /// [`max_ephemeris_age_s`]; the first such set on a tie. A Keplerian
    /// set is given from `decoded` once [`Self::load`] has decoded it there
    /// since the store last changed (None otherwise).
    pub fn select<'a, const D: usize>(
        &'a self,
        id: SatId,
        t_gps_s: f64,
        decoded: &'a DecodedSets<D>,
    ) -> Option<Broadcast<'a>> {
        self.select_in(id, t_gps_s, decoded, &[])
    }

    /// [`Self::select`] with the sets kept in `cache` ([`Self::load_cached`]):
    /// a kept set is given with its orbit's constants
    /// ([`Broadcast::Orbit`]).
    pub fn select_cached<'a, const D: usize, const C: usize>(
        &'a self,
        id: SatId,
        t_gps_s: f64,
        decoded: &'a DecodedSets<D>,
        cache: &'a OrbitCache<C>,
    ) -> Option<Broadcast<'a>> {
        self.select_in(id, t_gps_s, decoded, &cache.sets)
    }

    /// [`Self::select_cached`] with the cache's sets `kept`.
    fn select_in<'a, const D: usize>(
        &'a self,
        id: SatId,
        t_gps_s: f64,
        decoded: &'a DecodedSets<D>,
        kept: &'a [CachedOrbit],
    ) -> Option<Broadcast<'a>> {
        if id.system == System::Glonass {
            let max_age = max_ephemeris_age_s(id.system);
            let best = |a: (f64, usize), b: (f64, usize)| if b.0 < a.0 { b } else { a };
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
            let i = self.choose_kepler(id, t_gps_s)?;
            if let Some(c) = self
                .kepler
                .get(i)
                .and_then(|bits| kept.iter().find(|c| c.bits.same(bits)))
            {
                return Some(Broadcast::Orbit(&c.orbit));
            }
            if decoded.generation != self.generation {
                return None;
            }
            decoded
                .sets
                .iter()
                .find(|(j, _)| *j == i)
                .map(|(_, k)| Broadcast::Kepler(k))
        }
    }

    /// The index of the Keplerian set [`Self::select`] chooses.
    fn choose_kepler(&self, id: SatId, t_gps_s: f64) -> Option<usize> {
        let max_age = max_ephemeris_age_s(id.system);
        let sow_s = crate::ephemeris::system_sow_s(id.system, t_gps_s);
        let best = |a: (f64, usize), b: (f64, usize)| if b.0 < a.0 { b } else { a };
        let (_, i) = self
            .kepler
            .iter()
            .enumerate()
            .filter(|(_, k)| k.system == id.system && k.prn == id.prn && k.health == 0)
            .filter_map(|(i, k)| Some((k.age_s(t_gps_s, sow_s)?, i)))
            .filter(|(age, _)| *age <= max_age)
            .reduce(best)?;
        Some(i)
    }
}

/// Push `x`, or replace the element with the smallest `time` when full
/// (a store of capacity 0 keeps nothing and says `Replaced`).
#[cfg(feature = "rtcm")]
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

#[cfg(all(test, feature = "rtcm"))]
mod tests {
    use super::*;
    use crate::ephemeris::WEEK_S;
    use crate::rtcm::decode::kepler_message;
    use crate::rtcm::fields::kepler;
    extern crate std;
    use std::vec::Vec as StdVec;

    /// Big-endian bit packing of (value, width) fields, zero-padded to
    /// whole bytes, as RTCM 3 lays a payload out.
    fn pack(fields: &[(u64, u32)]) -> StdVec<u8> {
        let mut bits: StdVec<bool> = StdVec::new();
        for &(v, w) in fields {
            for i in (0..w).rev() {
                bits.push((v >> i) & 1 == 1);
            }
        }
        bits.chunks(8)
            .map(|c| {
                c.iter()
                    .enumerate()
                    .fold(0u8, |b, (i, &x)| b | (u8::from(x) << (7 - i)))
            })
            .collect()
    }

    /// A 1019 payload (RTCM 10403.3 §3.5.11, 488 bits): G`prn`, week 1000
    /// mod 1024, toe = toc = `toe_s` (a multiple of 16 s), `health`, and
    /// `x` in every other field (each masked to its width).
    fn msg1019(prn: u8, toe_s: f64, health: u32, x: u64) -> StdVec<u8> {
        let t = (toe_s / 16.0) as u64;
        let f = |w: u32| (x & ((1u64 << w) - 1), w);
        pack(&[
            (1019, 12),
            (u64::from(prn), 6),
            (1000, 10),
            f(4),
            f(2),
            f(14),
            f(8),
            (t, 16),
            f(8),
            f(16),
            f(22),
            f(10),
            f(16),
            f(16),
            f(32),
            f(16),
            f(32),
            f(16),
            (2_702_000_000, 32),
            (t, 16),
            f(16),
            f(32),
            f(16),
            f(32),
            f(16),
            f(32),
            f(24),
            f(8),
            (u64::from(health), 6),
            (0, 2),
        ])
    }

    /// A 1046 payload (Galileo I/NAV, 504 bits): E`prn`, the GST week of
    /// GPS week 1000 (mod 4096), toe = toc = `toe_s` (a multiple of 60 s),
    /// healthy, `x` in every other field.
    fn msg1046(prn: u8, toe_s: f64, x: u64) -> StdVec<u8> {
        let t = (toe_s / 60.0) as u64;
        let f = |w: u32| (x & ((1u64 << w) - 1), w);
        pack(&[
            (1046, 12),
            (u64::from(prn), 6),
            ((1000 - 1024i64).rem_euclid(4096) as u64, 12),
            f(10),
            f(8),
            f(14),
            (t, 14),
            f(6),
            f(21),
            f(31),
            f(16),
            f(16),
            f(32),
            f(16),
            f(32),
            f(16),
            (2_702_000_000, 32),
            (t, 14),
            f(16),
            f(32),
            f(16),
            f(32),
            f(16),
            f(32),
            f(24),
            f(10),
            f(10),
            (0, 3),
            (0, 3),
            (0, 2),
        ])
    }

    /// The set of a payload as the receiver takes it: decoded, toc in GPS
    /// seconds of week 1000 (the pivot's placing is `rtcm::fields`').
    fn set_of(payload: &[u8]) -> Kepler {
        let m = kepler_message(payload).unwrap();
        let mut k = kepler(m.system, m.prn, &m.fields);
        k.toc_gps_s = 1000.0 * WEEK_S + m.fields.toc_s;
        k
    }

    fn insert(s: &mut EphemerisStore<3, 1>, payload: &[u8]) -> Stored {
        s.insert_kepler(set_of(payload), payload)
    }

    /// The toe of the set chosen for `id` at `t`, after an epoch's load.
    fn pick(s: &EphemerisStore<3, 1>, id: SatId, t: f64) -> Option<f64> {
        let mut d = DecodedSets::<4>::new();
        s.start_epoch(&mut d);
        s.load(id, t, &mut d).unwrap();
        match s.select(id, t, &d) {
            Some(Broadcast::Kepler(k)) => Some(k.toe_sow_s),
            _ => None,
        }
    }

    /// The nearest healthy set within 2 h is chosen; a repeat is not
    /// stored twice; a full store drops the oldest set.
    #[test]
    fn selection_and_capacity() {
        let mut s = EphemerisStore::<3, 1>::new();
        let g05 = SatId::new(System::Gps, 5);
        assert_eq!(insert(&mut s, &msg1019(5, 7_200.0, 0, 3)), Stored::Added);
        assert_eq!(insert(&mut s, &msg1019(5, 7_200.0, 0, 3)), Stored::Repeat);
        assert_eq!(insert(&mut s, &msg1019(5, 14_400.0, 0, 3)), Stored::Added);
        assert_eq!(insert(&mut s, &msg1019(5, 21_600.0, 1, 3)), Stored::Added);
        let t = 1000.0 * WEEK_S + 12_000.0;
        assert_eq!(pick(&s, g05, t), Some(14_400.0));
        // The unhealthy set at 21600 is nearer at 20000 but not used.
        assert_eq!(pick(&s, g05, 1000.0 * WEEK_S + 20_000.0), Some(14_400.0));
        // Beyond 2 h of every healthy set: none.
        assert_eq!(pick(&s, g05, 1000.0 * WEEK_S + 14_400.0 + 7_201.0), None);
        assert_eq!(pick(&s, SatId::new(System::Gps, 6), t), None);
        // A week later the sets have the same t_k, but not the week.
        assert_eq!(pick(&s, g05, t + WEEK_S), None);
        // Full: the oldest (toe 7200) goes.
        assert_eq!(
            insert(&mut s, &msg1019(5, 28_800.0, 0, 3)),
            Stored::Replaced
        );
        assert_eq!(pick(&s, g05, 1000.0 * WEEK_S + 7_200.0), Some(14_400.0));
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
        assert_eq!(insert(&mut s, &msg1046(11, 7_200.0, 5)), Stored::Added);
        let id = SatId::new(System::Galileo, 11);
        let at = |dt: f64| 1000.0 * WEEK_S + 7_200.0 + dt;
        assert!(pick(&s, id, at(14_400.0)).is_some());
        assert!(pick(&s, id, at(-14_400.0)).is_some());
        assert!(pick(&s, id, at(14_401.0)).is_none());
        assert!(!s.is_empty());
        s.clear_glonass();
        assert_eq!(s.len(), (1, 0));
        s.clear();
        assert_eq!(s.len(), (0, 0));
        assert!(s.is_empty());
        assert!(pick(&s, id, at(0.0)).is_none());
    }

    /// A set kept as its message's payload is given back, once loaded for
    /// an epoch, equal field for field and bit for bit to the set decoded
    /// on arrival, for 1019 and 1046 payloads with pseudo-random fields
    /// (the store's sets are the receiver's, so its epochs are the host's:
    /// host-tests rtcm_receiver, rtcm_esbc, qemu_rtcm). A payload longer
    /// than 64 B, or one that is not the set's message, is `NotKept` with
    /// its length; a set is not given before its epoch's load, nor after
    /// the store changed (an insert); more satellites than
    /// the decoded capacity is the typed `DecodedFull`.
    ///
    /// Verifies: RX-STREAM
    #[test]
    fn sets_kept_as_payloads_decode_to_the_same_bits() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for n in 0..200u32 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let (payload, id) = if n % 2 == 0 {
                (msg1019(7, 3_600.0, 0, x), SatId::new(System::Gps, 7))
            } else {
                (msg1046(19, 3_600.0, x), SatId::new(System::Galileo, 19))
            };
            assert!(payload.len() <= KEPLER_PAYLOAD_BYTES);
            let want = set_of(&payload);
            let mut s = EphemerisStore::<3, 1>::new();
            assert_eq!(s.insert_kepler(want, &payload), Stored::Added);
            let t = 1000.0 * WEEK_S + 3_600.0;
            let mut d = DecodedSets::<4>::new();
            assert!(s.select(id, t, &d).is_none(), "not loaded yet");
            s.start_epoch(&mut d);
            s.load(id, t, &mut d).unwrap();
            let Some(Broadcast::Kepler(got)) = s.select(id, t, &d) else {
                panic!("set {n} not given back");
            };
            assert_eq!(*got, want);
            assert_eq!(std::format!("{got:?}"), std::format!("{want:?}"));
        }
        let payload = msg1019(7, 3_600.0, 0, 1);
        let k = set_of(&payload);
        let mut s = EphemerisStore::<3, 1>::new();
        let mut long = payload.clone();
        long.resize(65, 0);
        assert_eq!(
            s.insert_kepler(k, &long),
            Stored::NotKept { payload_len: 65 }
        );
        let other = Kepler {
            iod: k.iod ^ 1,
            ..k
        };
        assert_eq!(
            s.insert_kepler(other, &payload),
            Stored::NotKept { payload_len: 61 }
        );
        assert_eq!(s.len(), (0, 0));
        assert_eq!(s.insert_kepler(k, &payload), Stored::Added);
        let g07 = SatId::new(System::Gps, 7);
        let g08 = SatId::new(System::Gps, 8);
        let t = 1000.0 * WEEK_S + 3_600.0;
        let mut d = DecodedSets::<1>::new();
        s.start_epoch(&mut d);
        s.load(g07, t, &mut d).unwrap();
        assert!(s.select(g07, t, &d).is_some());
        let p8 = msg1019(8, 3_600.0, 0, 1);
        assert_eq!(s.insert_kepler(set_of(&p8), &p8), Stored::Added);
        assert!(
            s.select(g07, t, &d).is_none(),
            "a set decoded before the store changed is not given"
        );
        s.start_epoch(&mut d);
        s.load(g07, t, &mut d).unwrap();
        assert_eq!(s.load(g08, t, &mut d), Err(DecodedFull { capacity: 1 }));
        // Loading again, or a satellite with no set, needs no room.
        assert_eq!(s.load(g07, t, &mut d), Ok(()));
        assert_eq!(s.load(SatId::new(System::Gps, 9), t, &mut d), Ok(()));
    }

    /// The decoded sets kept across epochs ([`OrbitCache`]): a kept set is
    /// given with its orbit's constants, the very set a fresh decode gives
    /// and the same states to the bit, epoch after epoch without a decode;
    /// a set replaced in the store (a new toe, or another set of the same
    /// satellite in the same place) is never given from the cache, the new
    /// one is; a full cache whose sets this epoch uses leaves a further
    /// set to the epoch's decoded sets, and gives way to it at the next
    /// epoch; a cache of capacity 0 is the store without one.
    ///
    /// Verifies: RX-FORM-ORBIT
    #[test]
    fn orbit_cache_gives_the_decoded_set_and_never_a_stale_one() {
        let t = 1000.0 * WEEK_S + 3_600.0;
        let g = |prn| SatId::new(System::Gps, prn);
        let mut s = EphemerisStore::<3, 1>::new();
        let p5 = msg1019(5, 3_600.0, 0, 0x5555);
        let p6 = msg1019(6, 3_600.0, 0, 0x6666);
        insert(&mut s, &p5);
        insert(&mut s, &p6);
        let mut cache = OrbitCache::<1>::new();
        let mut d = DecodedSets::<4>::new();
        // Each epoch's loads; every satellite's set as chosen at its load
        // is the set `select_cached` chooses again.
        let epoch = |s: &EphemerisStore<3, 1>,
                     d: &mut DecodedSets<4>,
                     cache: &mut OrbitCache<1>,
                     ids: &[SatId]| {
            s.start_epoch(d);
            cache.next_epoch();
            let chosen: std::vec::Vec<Chosen> = ids
                .iter()
                .map(|id| s.load_cached(*id, t, d, cache).unwrap())
                .collect();
            for (id, c) in ids.iter().zip(chosen) {
                assert_eq!(
                    s.select_chosen(*id, t, c, d, cache),
                    s.select_cached(*id, t, d, cache)
                );
                assert!(c != Chosen::None);
            }
            let none = SatId::new(System::Gps, 30);
            let c = s.load_cached(none, t, d, cache).unwrap();
            assert_eq!(c, Chosen::None);
            assert_eq!(s.select_chosen(none, t, c, d, cache), None);
        };
        // G05 alone: kept, given as an orbit equal to the fresh decode.
        epoch(&s, &mut d, &mut cache, &[g(5)]);
        assert_eq!(cache.len(), 1);
        let want5 = set_of(&p5);
        match s.select_cached(g(5), t, &d, &cache) {
            Some(Broadcast::Orbit(o)) => {
                assert_eq!(o.set, want5);
                assert_eq!(o.transmit_state(t), want5.transmit_state(t));
            }
            other => panic!("{other:?}"),
        }
        // G05 and G06: the cache's one place is G05's (this epoch's), so
        // G06 is decoded for the epoch alone.
        epoch(&s, &mut d, &mut cache, &[g(5), g(6)]);
        assert!(matches!(
            s.select_cached(g(5), t, &d, &cache),
            Some(Broadcast::Orbit(_))
        ));
        match s.select_cached(g(6), t, &d, &cache) {
            Some(Broadcast::Kepler(k)) => assert_eq!(*k, set_of(&p6)),
            other => panic!("{other:?}"),
        }
        // G06 alone at the next epoch: G05's place, last used before, gives way.
        epoch(&s, &mut d, &mut cache, &[g(6)]);
        match s.select_cached(g(6), t, &d, &cache) {
            Some(Broadcast::Orbit(o)) => assert_eq!(o.set, set_of(&p6)),
            other => panic!("{other:?}"),
        }
        // Another set of G06 with the same toe and other elements takes
        // the place of the oldest set in the full store (G05's, before
        // G06's), so it is the first of the tie and the one chosen: the
        // kept G06 set, of the same satellite and toe, is not given; the
        // new one is.
        let p5b = msg1019(5, 7_200.0, 0, 0x7777);
        insert(&mut s, &p5b);
        let p6b = msg1019(6, 3_600.0, 0, 0x8888);
        assert_eq!(insert(&mut s, &p6b), Stored::Replaced);
        epoch(&s, &mut d, &mut cache, &[g(6)]);
        match s.select_cached(g(6), t, &d, &cache) {
            Some(Broadcast::Orbit(o)) => assert_eq!(o.set, set_of(&p6b)),
            other => panic!("{other:?}"),
        }
        // Capacity 0: the store's own load and select.
        let mut none = OrbitCache::<0>::new();
        s.start_epoch(&mut d);
        none.next_epoch();
        s.load_cached(g(6), t, &mut d, &mut none).unwrap();
        assert!(none.is_empty());
        assert_eq!(s.select_cached(g(6), t, &d, &none), s.select(g(6), t, &d));
        assert!(matches!(s.select(g(6), t, &d), Some(Broadcast::Kepler(k)) if *k == set_of(&p6b)));
    }

    /// The age of a set kept as its payload, from its toe and toc with t
    /// reduced to the week once (`KeplerBits::age_s`), is the decoded
    /// set's `kepler_age_s` to the bit, for GPS, Galileo and BeiDou sets
    /// at times across three weeks (the week crossover, a week off, BDT).
    ///
    /// Verifies: RX-FORM-COST
    #[test]
    fn the_payloads_age_is_the_decoded_sets() {
        let mut n = 0;
        for (prn, toe) in [(3u8, 0.0), (9, 302_400.0), (12, 597_600.0)] {
            for payload in [msg1019(prn, toe, 0, 0x1234), msg1046(prn, toe, 0x4321)] {
                let k = set_of(&payload);
                let bits = KeplerBits::new(&k, &payload).unwrap();
                for beidou in [false, true] {
                    let (k, bits) = if beidou {
                        let k = Kepler {
                            system: System::Beidou,
                            ..k
                        };
                        let b = KeplerBits {
                            system: System::Beidou,
                            ..bits.clone()
                        };
                        (k, b)
                    } else {
                        (k, bits.clone())
                    };
                    for j in -300..300 {
                        let t = 1000.0 * WEEK_S + toe + f64::from(j) * 3_607.0;
                        let sow = crate::ephemeris::system_sow_s(k.system, t);
                        let got = bits.age_s(t, sow).map(f64::to_bits);
                        assert_eq!(got, kepler_age_s(&k, t).map(f64::to_bits), "{t}");
                        n += usize::from(got.is_some());
                    }
                }
            }
        }
        assert!(n > 100, "{n}");
    }
}
