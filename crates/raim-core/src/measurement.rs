//! The measurement model's inputs (SPEC §1): satellites, their identities and
//! the two input forms of an epoch (ranges + ECEF positions, or the
//! linearised form the seeds print: line of sight + residual).

use crate::config_bounds::{Bound, SIGMA_M};
use crate::error::RaimError;

/// A GNSS constellation. Each constellation present adds one receiver clock
/// unknown to the state (SPEC §1: m = 3 + number of constellations).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum System {
    #[default]
    /// GPS (G).
    Gps,
    /// Galileo (E).
    Galileo,
    /// BeiDou (C).
    Beidou,
    /// GLONASS (R).
    Glonass,
    /// QZSS (J).
    Qzss,
}

/// Number of constellations the model knows.
pub const MAX_SYSTEMS: usize = 5;
/// Largest number of unknowns: 3 position + one clock per constellation.
pub const MAX_STATES: usize = 3 + MAX_SYSTEMS;

impl System {
    /// All systems, in clock-column order.
    pub const ALL: [System; MAX_SYSTEMS] = [
        System::Gps,
        System::Galileo,
        System::Beidou,
        System::Glonass,
        System::Qzss,
    ];

    /// RINEX system letter.
    pub const fn letter(self) -> char {
        match self {
            System::Gps => 'G',
            System::Galileo => 'E',
            System::Beidou => 'C',
            System::Glonass => 'R',
            System::Qzss => 'J',
        }
    }

    /// Parse a RINEX system letter.
    pub const fn from_letter(c: char) -> Option<System> {
        match c {
            'G' => Some(System::Gps),
            'E' => Some(System::Galileo),
            'C' => Some(System::Beidou),
            'R' => Some(System::Glonass),
            'J' => Some(System::Qzss),
            _ => None,
        }
    }

    /// Position of this system in [`System::ALL`].
    pub const fn index(self) -> usize {
        match self {
            System::Gps => 0,
            System::Galileo => 1,
            System::Beidou => 2,
            System::Glonass => 3,
            System::Qzss => 4,
        }
    }

    /// The largest satellite number of this system (the smallest is 1 for
    /// every system): GPS PRN 1-32 (IS-GPS-200), Galileo 1-36 (Galileo OS
    /// SIS ICD, RINEX 3 E01-E36), BeiDou 1-63 (BDS ICD, RINEX 3 C01-C63),
    /// GLONASS slots 1-24 and up to 27 for spares (as `raim_nav::glonass`
    /// reads them), QZSS 1-10 (IS-QZSS PRN 193-202, RINEX 3 J01-J10, as
    /// the receivers' readers number them). A number outside is no
    /// satellite the error models, ISMs or NMEA numbering know: an epoch
    /// carrying one is refused ([`check_prn`]).
    pub const fn max_prn(self) -> u8 {
        match self {
            System::Gps => 32,
            System::Galileo => 36,
            System::Beidou => 63,
            System::Glonass => 27,
            System::Qzss => 10,
        }
    }

    /// This system's entry of a per-system table (in [`System::ALL`]
    /// order): the table has one entry per system, so there is no index
    /// to check.
    pub fn entry<T>(self, table: &[T; MAX_SYSTEMS]) -> &T {
        let [gps, galileo, beidou, glonass, qzss] = table;
        match self {
            System::Gps => gps,
            System::Galileo => galileo,
            System::Beidou => beidou,
            System::Glonass => glonass,
            System::Qzss => qzss,
        }
    }

    /// [`System::entry`], mutable.
    pub fn entry_mut<T>(self, table: &mut [T; MAX_SYSTEMS]) -> &mut T {
        let [gps, galileo, beidou, glonass, qzss] = table;
        match self {
            System::Gps => gps,
            System::Galileo => galileo,
            System::Beidou => beidou,
            System::Glonass => glonass,
            System::Qzss => qzss,
        }
    }
}

/// A satellite's identity: constellation and PRN (slot number for GLONASS).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SatId {
    /// The constellation.
    pub system: System,
    /// The satellite number within it (PRN; slot for GLONASS).
    pub prn: u8,
}

impl SatId {
    /// The derived `Default` (GPS, PRN 0), for `const fn` constructors.
    pub const DEFAULT: Self = SatId {
        system: System::Gps,
        prn: 0,
    };
    /// The satellite `prn` of `system`.
    pub const fn new(system: System, prn: u8) -> Self {
        SatId { system, prn }
    }
}

impl core::fmt::Display for SatId {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}{:02}", self.system.letter(), self.prn)
    }
}

/// One satellite's corrected pseudorange with its ECEF position.
///
/// `pseudorange_m` is corrected for the satellite clock, ionosphere and
/// troposphere (and group delays); `position_m` is the satellite's ECEF
/// position at transmit time, already rotated into the ECEF frame at the
/// reception time (Earth-rotation / Sagnac correction applied by the caller).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RangeObservation {
    /// The satellite.
    pub id: SatId,
    /// Corrected pseudorange, m.
    pub pseudorange_m: f64,
    /// Satellite ECEF position at transmission, in the frame of reception, m.
    pub position_m: [f64; 3],
    /// One-sigma ranging error. `None` selects the configured elevation model.
    pub sigma_m: Option<f64>,
}

impl RangeObservation {
    /// The derived `Default`, for `const fn` constructors.
    pub const DEFAULT: Self = RangeObservation {
        id: SatId::DEFAULT,
        pseudorange_m: 0.0,
        position_m: [0.0; 3],
        sigma_m: None,
    };
}

/// The linearised form used by the seeds' tables: the unit line of sight from
/// receiver to satellite in local ENU, and the measurement residual
/// z_i = rho_i - rho_hat_i(x0) (SPEC §1).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LinearObservation {
    /// The satellite.
    pub id: SatId,
    /// Unit line-of-sight vector receiver -> satellite, East/North/Up.
    pub los_enu: [f64; 3],
    /// Pseudorange residual (measured - predicted), m.
    pub residual_m: f64,
    /// One-sigma ranging error. `None` selects the configured elevation model.
    pub sigma_m: Option<f64>,
}

impl LinearObservation {
    /// The derived `Default`, for `const fn` constructors.
    pub const DEFAULT: Self = LinearObservation {
        id: SatId::DEFAULT,
        los_enu: [0.0; 3],
        residual_m: 0.0,
        sigma_m: None,
    };
    /// Build from azimuth (clockwise from north) and elevation, in radians.
    pub fn from_az_el(id: SatId, az_rad: f64, el_rad: f64, residual_m: f64) -> Self {
        let (sa, ca) = (libm::sin(az_rad), libm::cos(az_rad));
        let (se, ce) = (libm::sin(el_rad), libm::cos(el_rad));
        LinearObservation {
            id,
            los_enu: [ce * sa, ce * ca, se],
            residual_m,
            sigma_m: None,
        }
    }

    /// [`LinearObservation::from_az_el`] with its inputs range-checked first
    /// (see [`check_az_el`]): the constructor for az/el that come from
    /// outside (a file, a wire message). The line of sight alone cannot show
    /// an elevation of 200° (it is the same unit vector as azimuth + 180°,
    /// elevation -20°), so `validate` cannot catch it later.
    pub fn try_from_az_el(
        id: SatId,
        index: usize,
        az_rad: f64,
        el_rad: f64,
        residual_m: f64,
    ) -> Result<Self, RaimError> {
        check_az_el(index, az_rad, el_rad)?;
        finite("residual_m", index, residual_m)?;
        Ok(Self::from_az_el(id, az_rad, el_rad, residual_m))
    }

    /// Elevation of the line of sight, radians.
    pub fn elevation_rad(&self) -> f64 {
        let [e, n, u] = self.los_enu;
        libm::atan2(u, libm::sqrt(e * e + n * n))
    }
}

/// The observations of one epoch, borrowed from the caller (no copy, no heap).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Observations<'a> {
    /// Pseudoranges with ECEF satellite positions; the core solves the
    /// position by Gauss-Newton from `apriori_m` (or the Earth's centre).
    Ranges {
        /// The observations.
        sats: &'a [RangeObservation],
        /// Where Gauss-Newton starts, ECEF m (`None`: the Earth's centre).
        apriori_m: Option<[f64; 3]>,
    },
    /// Already-linearised rows (the seeds' form).
    Linear {
        /// The rows.
        sats: &'a [LinearObservation],
    },
}

/// One epoch of input: the time comes in as an argument (sans-IO).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Epoch<'a> {
    /// Receiver time of the epoch, seconds (any consistent time scale).
    pub time_s: f64,
    /// What was measured: pseudoranges or linearised rows.
    pub observations: Observations<'a>,
}

impl<'a> Epoch<'a> {
    /// An epoch of pseudoranges at `time_s`, solved from `apriori_m` (ECEF, m).
    pub fn ranges(time_s: f64, sats: &'a [RangeObservation], apriori_m: Option<[f64; 3]>) -> Self {
        Epoch {
            time_s,
            observations: Observations::Ranges { sats, apriori_m },
        }
    }

    /// An epoch of linearised rows at `time_s`.
    pub fn linear(time_s: f64, sats: &'a [LinearObservation]) -> Self {
        Epoch {
            time_s,
            observations: Observations::Linear { sats },
        }
    }

    /// Number of satellites in the epoch.
    pub fn len(&self) -> usize {
        match self.observations {
            Observations::Ranges { sats, .. } => sats.len(),
            Observations::Linear { sats } => sats.len(),
        }
    }

    /// True when the epoch has no satellite.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The satellite identities, in input order.
    pub fn id(&self, index: usize) -> Option<SatId> {
        match self.observations {
            Observations::Ranges { sats, .. } => sats.get(index).map(|s| s.id),
            Observations::Linear { sats } => sats.get(index).map(|s| s.id),
        }
    }
}

/// Unix time of the GPS epoch, 1980-01-06 00:00:00 UTC, s.
pub const GPS_EPOCH_UNIX_S: f64 = 315_964_800.0;
/// One GPS week, s.
pub const GPS_WEEK_S: f64 = 604_800.0;
/// Weeks the GPS era counts: the 13-bit week number of the modernised
/// navigation messages (IS-GPS-200 CNAV, the widest GPS week count), 8192
/// weeks from the GPS epoch, to 2137-01-06.
pub const GPS_ERA_WEEKS: f64 = 8192.0;

/// The epoch times every engine accepts, s (`time_s`: Unix UTC seconds,
/// docs/FORMATS.md "Time"; the host tools' GPS seconds are inside it too).
/// From 0 (the Unix epoch: the seeds' tables and the bench vectors count
/// their epochs from 0, and the monitors use only differences of the
/// time) to the end of the GPS era, [`GPS_EPOCH_UNIX_S`] +
/// [`GPS_ERA_WEEKS`] weeks = 5,270,486,400 s. Within it an f64 time
/// resolves 2^-20 s (< 1 µs), so the intervals the stateful monitors take
/// (MCUSUM weight and holds, PF prediction, windows) are exact to the
/// microsecond; outside it a time is no receiver's (a time of 1e300 s
/// resolves 1e284 s and every interval is 0 or absurd). docs/SAFETY.md
/// "Inputs refused".
pub const EPOCH_TIME_S: Bound = Bound {
    field: "time_s",
    min: 0.0,
    max: GPS_EPOCH_UNIX_S + GPS_ERA_WEEKS * GPS_WEEK_S,
};

/// An epoch time against [`EPOCH_TIME_S`]: `NotFinite` for NaN and
/// infinities (as before), `OutOfRange { field: "time_s" }` outside the
/// bound. Every engine's epoch check calls it (snapshot, MCUSUM, ARAIM,
/// PF), so the host tools and the firmware refuse alike.
pub fn check_time_s(time_s: f64) -> Result<(), RaimError> {
    finite("time_s", 0, time_s)?;
    EPOCH_TIME_S.check(time_s)
}

/// A satellite number against its system's range, 1..=[`System::max_prn`]:
/// `PrnOutOfRange` with the satellite's `index` in the epoch.
pub fn check_prn(index: usize, id: SatId) -> Result<(), RaimError> {
    if prn_in_range(id) {
        Ok(())
    } else {
        Err(RaimError::PrnOutOfRange {
            index,
            system: id.system,
            prn: id.prn,
            max: id.system.max_prn(),
        })
    }
}

/// Whether `id`'s number is within its system's range (branch-free, for
/// the one-pass checks).
pub const fn prn_in_range(id: SatId) -> bool {
    (id.prn >= 1) & (id.prn <= id.system.max_prn())
}

/// [`check_prn`] over a list of identities: the first one out of range.
pub fn check_prns(ids: impl Iterator<Item = SatId>) -> Result<(), RaimError> {
    ids.enumerate().try_for_each(|(i, id)| check_prn(i, id))
}

/// Reject a non-finite value with its field name and index.
pub(crate) fn finite(field: &'static str, index: usize, value: f64) -> Result<f64, RaimError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(RaimError::NotFinite {
            field,
            index,
            value,
        })
    }
}

/// Range check of a linearised input's direction (SPEC §1, the rows of H
/// come from azimuth and elevation): the azimuth must be finite (any value,
/// it wraps), the elevation finite and within [-π/2, π/2] (negative
/// elevations are real for an aircraft above the local horizon plane).
/// `index` is the satellite's position in the epoch, for the error.
pub fn check_az_el(index: usize, az_rad: f64, el_rad: f64) -> Result<(), RaimError> {
    finite("az_rad", index, az_rad)?;
    finite("el_rad", index, el_rad)?;
    let half_pi = core::f64::consts::FRAC_PI_2;
    if !(-half_pi..=half_pi).contains(&el_rad) {
        return Err(RaimError::OutOfRange {
            field: "el_rad",
            value: el_rad,
            min: -half_pi,
            max: half_pi,
        });
    }
    Ok(())
}

/// A host-given per-satellite sigma against its operational bound
/// (`config_bounds::SIGMA_M`, docs/PROTOCOL.md "Configuration bounds"):
/// `SigmaOutOfRange` with the satellite's index. Callers check finiteness
/// and sign first (their own typed errors).
pub fn check_sigma_bound(index: usize, sigma_m: f64) -> Result<(), RaimError> {
    if SIGMA_M.contains(sigma_m) {
        Ok(())
    } else {
        Err(RaimError::SigmaOutOfRange {
            index,
            sigma_m,
            min_m: SIGMA_M.min,
            max_m: SIGMA_M.max,
        })
    }
}

/// Check an epoch's inputs: the time ([`check_time_s`]), capacity,
/// finiteness, sigma sign and bound, satellite numbers ([`check_prn`]),
/// duplicates.
/// O(n^2) duplicate check; n <= N is small.
pub(crate) fn validate<const N: usize>(epoch: &Epoch<'_>) -> Result<(), RaimError> {
    check_time_s(epoch.time_s)?;
    let n = epoch.len();
    if n > N {
        return Err(RaimError::CapacityExceeded {
            have: n,
            capacity: N,
        });
    }
    let check_sigma = |index: usize, sigma: Option<f64>| -> Result<(), RaimError> {
        if let Some(s) = sigma {
            finite("sigma_m", index, s)?;
            if s <= 0.0 {
                return Err(RaimError::NonPositiveSigma { index, sigma_m: s });
            }
            check_sigma_bound(index, s)?;
        }
        Ok(())
    };
    // One branch-free pass first for the linearised form (fourth
    // pass: the checks below, with an early return per value, were 6 % of a
    // clean linearised epoch); only when it finds a bad value does the
    // detailed pass run, which names the first offender exactly as before.
    // Pseudorange epochs take the detailed pass directly (their cost is the
    // f64 geometry; the device's flash has no room for a second copy).
    let sigma_ok = |sigma: Option<f64>| sigma.is_none_or(|s| SIGMA_M.contains(s));
    let all_ok = match epoch.observations {
        Observations::Ranges { .. } => false,
        Observations::Linear { sats } => sats.iter().fold(true, |ok, s| {
            // A squared norm in range implies finite components.
            let norm2 = s.los_enu.iter().map(|v| v * v).sum::<f64>();
            ok & s.residual_m.is_finite() & (0.5..=1.5).contains(&norm2) & sigma_ok(s.sigma_m)
        }),
    };
    match epoch.observations {
        _ if all_ok => {}
        Observations::Ranges { sats, apriori_m } => {
            if let Some(a) = apriori_m {
                for v in a {
                    finite("apriori_m", 0, v)?;
                }
            }
            for (i, s) in sats.iter().enumerate() {
                finite("pseudorange_m", i, s.pseudorange_m)?;
                for v in s.position_m {
                    finite("position_m", i, v)?;
                }
                check_sigma(i, s.sigma_m)?;
            }
        }
        Observations::Linear { sats } => {
            for (i, s) in sats.iter().enumerate() {
                finite("residual_m", i, s.residual_m)?;
                for v in s.los_enu {
                    finite("los_enu", i, v)?;
                }
                let norm2 = s.los_enu.iter().map(|v| v * v).sum::<f64>();
                if !(0.5..=1.5).contains(&norm2) {
                    return Err(RaimError::OutOfRange {
                        field: "los_enu_norm",
                        value: libm::sqrt(norm2),
                        min: libm::sqrt(0.5),
                        max: libm::sqrt(1.5),
                    });
                }
                check_sigma(i, s.sigma_m)?;
            }
        }
    }
    // One pass over a bitmap of the (system, PRN) pairs seen (
    // the pairwise comparison cost O(n^2) on every epoch); only when it
    // finds a repeat does the pairwise search below run, so the error names
    // the same first pair as before.
    let mut seen = [[0u64; 4]; MAX_SYSTEMS];
    let mut repeated = false;
    let mut numbered = true;
    let mut mark = |id: SatId| {
        numbered &= prn_in_range(id);
        let (word, bit) = (usize::from(id.prn >> 6), id.prn & 63);
        if let Some(w) = seen
            .get_mut(id.system.index())
            .and_then(|s| s.get_mut(word))
        {
            repeated |= *w & (1u64 << bit) != 0;
            *w |= 1u64 << bit;
        }
    };
    // Over the input form's own slice (not
    // `epoch.id(i)`, which matched the form again for every satellite).
    match epoch.observations {
        Observations::Ranges { sats, .. } => sats.iter().for_each(|s| mark(s.id)),
        Observations::Linear { sats } => sats.iter().for_each(|s| mark(s.id)),
    }
    if numbered && !repeated {
        return Ok(());
    }
    // The first offender by index: a number out of range, or the first
    // appearance of a satellite that appears again (the pair named by its
    // first index, then its second).
    for i in 0..n {
        let Some(a) = epoch.id(i) else { continue };
        check_prn(i, a)?;
        for j in (i + 1)..n {
            if epoch.id(j) == Some(a) {
                return Err(RaimError::DuplicateSatellite {
                    system: a.system,
                    prn: a.prn,
                    first: i,
                    second: j,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const G1: SatId = SatId::new(System::Gps, 1);

    /// RINEX 3's system letters (G, E, C, R, J) name the five systems in
    /// `System::ALL` order; any other character (lower case too) none.
    /// Per-system tables give each system its own entry, mutable too.
    #[test]
    fn system_letters_and_table_entries() {
        for (sys, c) in System::ALL.into_iter().zip(['G', 'E', 'C', 'R', 'J']) {
            assert_eq!(System::from_letter(c), Some(sys));
        }
        for c in ['g', 'S', 'I', ' '] {
            assert_eq!(System::from_letter(c), None, "{c}");
        }
        let mut table = [10, 20, 30, 40, 50];
        for (sys, want) in System::ALL.into_iter().zip([10, 20, 30, 40, 50]) {
            assert_eq!(*sys.entry(&table), want);
            *sys.entry_mut(&mut table) += 1;
        }
        assert_eq!(table, [11, 21, 31, 41, 51]);
    }

    /// A linear observation's elevation is the one it was built from, and
    /// an epoch without satellites is empty.
    #[test]
    fn linear_elevation_and_empty_epochs() {
        for el_deg in [-5.0f64, 0.0, 12.5, 45.0, 89.0] {
            let o = LinearObservation::from_az_el(G1, 1.1, el_deg.to_radians(), 0.0);
            assert!(
                (o.elevation_rad() - el_deg.to_radians()).abs() < 1e-12,
                "{el_deg}"
            );
        }
        assert!(Epoch::linear(0.0, &[]).is_empty());
        let one = [LinearObservation::from_az_el(G1, 0.0, 0.5, 0.0)];
        assert!(!Epoch::linear(0.0, &one).is_empty());
    }

    /// The duplicate check (a bitmap pass, then the pairwise search only on
    /// a repeat) names the lexicographically first pair (i, j), like the
    /// pairwise search alone: checked against a brute force on 3,000
    /// random id lists (n = 0..20, few distinct ids so repeats are common),
    /// e.g. A B B A gives (0, 3), not (1, 2).
    ///
    /// Verifies: WIRE-DuplicateSatellite
    #[test]
    fn duplicates_are_named_by_the_first_pair() {
        extern crate std;
        use std::vec::Vec;
        let mut rng = crate::testutil::Rng::new(7);
        // Numbers valid in both systems drawn (GPS and Galileo): an
        // out-of-range one is refused before the duplicate search.
        let prns = [1u8, 2, 17, 31, 32, 9];
        let mut errors = 0;
        for trial in 0..3000 {
            let n = trial % 21;
            let sats: Vec<LinearObservation> = (0..n)
                .map(|_| {
                    let sys = System::ALL[(rng.uniform() * 2.0) as usize];
                    let prn = prns[(rng.uniform() * (2.0 + (trial % 5) as f64)) as usize];
                    LinearObservation::from_az_el(SatId::new(sys, prn), 0.3, 0.7, 0.0)
                })
                .collect();
            let mut expected = Ok(());
            'outer: for i in 0..n {
                for j in i + 1..n {
                    if sats[i].id == sats[j].id {
                        expected = Err(RaimError::DuplicateSatellite {
                            system: sats[i].id.system,
                            prn: sats[i].id.prn,
                            first: i,
                            second: j,
                        });
                        break 'outer;
                    }
                }
            }
            errors += usize::from(expected.is_err());
            assert_eq!(
                validate::<32>(&Epoch::linear(0.0, &sats)),
                expected,
                "{trial}"
            );
        }
        assert!(errors > 1000, "{errors}");
        let id = |prn| SatId::new(System::Gps, prn);
        let abba: Vec<LinearObservation> = [1, 2, 2, 1]
            .map(|p| LinearObservation::from_az_el(id(p), 0.3, 0.7, 0.0))
            .to_vec();
        assert!(matches!(
            validate::<32>(&Epoch::linear(0.0, &abba)),
            Err(RaimError::DuplicateSatellite {
                first: 0,
                second: 3,
                ..
            })
        ));
    }

    /// Verifies: WIRE-OutOfRange
    #[test]
    fn elevation_outside_plus_minus_90_deg_is_out_of_range() {
        for el_deg in [200.0f64, -90.5, 90.000_001, -200.0] {
            let e = LinearObservation::try_from_az_el(G1, 3, 0.5, el_deg.to_radians(), 0.0)
                .unwrap_err();
            match e {
                RaimError::OutOfRange {
                    field,
                    value,
                    min,
                    max,
                } => {
                    assert_eq!(field, "el_rad");
                    assert_eq!(value, el_deg.to_radians());
                    assert_eq!(min, -core::f64::consts::FRAC_PI_2);
                    assert_eq!(max, core::f64::consts::FRAC_PI_2);
                }
                other => panic!("{other:?}"),
            }
        }
    }

    /// The bounds themselves (as the degree conversion gives them) and
    /// negative elevations are valid; the result equals the unchecked
    /// constructor's.
    #[test]
    fn elevation_bounds_and_negative_elevations_are_accepted() {
        for el_deg in [90.0f64, -90.0, -30.0, 0.0, 45.0] {
            let (az, el) = (1.0, el_deg.to_radians());
            let o = LinearObservation::try_from_az_el(G1, 0, az, el, 2.0).unwrap();
            assert_eq!(o, LinearObservation::from_az_el(G1, az, el, 2.0));
        }
        // Azimuth wraps: any finite value is valid.
        assert!(LinearObservation::try_from_az_el(G1, 0, 7.0, 0.3, 0.0).is_ok());
        assert!(LinearObservation::try_from_az_el(G1, 0, -7.0, 0.3, 0.0).is_ok());
    }

    #[test]
    fn non_finite_azimuth_elevation_or_residual_names_the_field_and_index() {
        let cases = [
            (f64::NAN, 0.3, 0.0, "az_rad"),
            (f64::INFINITY, 0.3, 0.0, "az_rad"),
            (0.1, f64::NAN, 0.0, "el_rad"),
            (0.1, 0.3, f64::NEG_INFINITY, "residual_m"),
        ];
        for (az, el, r, name) in cases {
            match LinearObservation::try_from_az_el(G1, 5, az, el, r).unwrap_err() {
                RaimError::NotFinite { field, index, .. } => {
                    assert_eq!((field, index), (name, 5));
                }
                other => panic!("{other:?}"),
            }
        }
    }
}

/// Issue 35 "Inputs": epoch times outside the GPS era and satellite
/// numbers outside their system's range are refused by every entry of the
/// snapshot monitor (the firmware's too: the server calls it).
#[cfg(test)]
mod input_tests {
    extern crate std;
    use super::*;
    use crate::config::Phase;
    use crate::testutil::{linear_epoch, Rng, SKY8};
    use crate::{Config, Raim};

    /// Verifies: SAFE-INPUTS
    #[test]
    fn times_outside_the_gps_era_are_refused() {
        let sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(1), &[]);
        let cfg = Config::preset(Phase::Npa);
        let end_s = 315_964_800.0 + 8192.0 * 604_800.0;
        assert_eq!(EPOCH_TIME_S.max, end_s);
        assert_eq!(end_s, 5_270_486_400.0);
        for t in [1e300, -1e300, -1.0, -1e-9, end_s + 1.0, f64::MAX] {
            let e = Raim::<16>::new()
                .process(&cfg, &Epoch::linear(t, &sats))
                .unwrap_err();
            assert_eq!(
                e,
                RaimError::OutOfRange {
                    field: "time_s",
                    value: t,
                    min: 0.0,
                    max: end_s
                },
                "{t}"
            );
        }
        for t in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = Raim::<16>::new()
                .process(&cfg, &Epoch::linear(t, &sats))
                .unwrap_err();
            assert!(
                matches!(
                    e,
                    RaimError::NotFinite {
                        field: "time_s",
                        ..
                    }
                ),
                "{e:?}"
            );
        }
        // The bounds themselves and a time of today are taken; an f64
        // time resolves better than 1 µs everywhere inside.
        for t in [0.0, 1.0, 1_764_000_000.0, end_s] {
            assert!(Raim::<16>::new()
                .process(&cfg, &Epoch::linear(t, &sats))
                .is_ok());
        }
        assert!(end_s + 1e-6 > end_s);
    }

    /// Verifies: SAFE-INPUTS, WIRE-PrnOutOfRange
    #[test]
    fn satellite_numbers_outside_each_systems_range_are_refused() {
        let cfg = Config::preset(Phase::Npa);
        for system in System::ALL {
            let max = system.max_prn();
            for (prn, ok) in [
                (0u8, false),
                (1, true),
                (max, true),
                (max + 1, false),
                (255, false),
            ] {
                let mut sats = linear_epoch(&SKY8, 1.0, &mut Rng::new(2), &[]);
                // Satellite 3 gets the number under test, in its own system
                // (the rest are GPS 1..8, distinct from it unless `ok`
                // repeats one: then give the others high GPS numbers).
                for (i, o) in sats.iter_mut().enumerate() {
                    o.id = SatId::new(System::Gps, 20 + i as u8);
                }
                sats[3].id = SatId::new(system, prn);
                let r = Raim::<16>::new().process(&cfg, &Epoch::linear(10.0, &sats));
                if ok {
                    assert!(r.is_ok(), "{system:?} {prn}: {r:?}");
                } else {
                    assert_eq!(
                        r.unwrap_err(),
                        RaimError::PrnOutOfRange {
                            index: 3,
                            system,
                            prn,
                            max
                        }
                    );
                }
            }
        }
        assert_eq!(
            System::ALL.map(System::max_prn),
            [32, 36, 63, 27, 10],
            "GPS, Galileo, BeiDou, GLONASS, QZSS"
        );
    }
}
