//! The epoch result on the wire: every field of `raim_core::EpochResult`
//! (SPEC §11: position, decision, statistics and thresholds, identified and
//! excluded satellites, protection levels), plus room for the MCUSUM state.

use raim_core::frames::Geodetic;
use raim_core::measurement::MAX_SYSTEMS;
use raim_core::snapshot::fde::{AlarmCause, Exclusion, MAX_EXCLUSIONS};
use raim_core::{snapshot::detection::TestStatistic, SatId};
use raim_core::{Decision, EpochResult, SatelliteResult};
use serde::{Deserialize, Serialize};

use crate::CAPACITY;

/// The sequential (MCUSUM, SPEC §7) detector's state after the epoch: the
/// core's own report (D_t, h, k, C_t, dimension, alarm and its source, the
/// satellite identified and those held out). `None` when the MCUSUM is
/// disabled in the configuration.
pub type WireMcusum = raim_core::McusumReport;

/// One epoch's result. Field meanings are those of `raim_core::EpochResult`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WireResult {
    /// Epoch time, s.
    pub time_s: f64,
    /// Ok, alarm, excluded or unavailable.
    pub decision: Decision,
    /// Why an alarm stands (`None` unless the decision is `Alarm`).
    pub alarm_cause: Option<AlarmCause>,
    /// ECEF position of the solution in force (pseudorange input), m.
    pub position_ecef_m: Option<[f64; 3]>,
    /// Geodetic position of the solution in force (pseudorange input).
    pub geodetic: Option<Geodetic>,
    /// ENU correction to the linearisation point (linear input), m.
    pub correction_enu_m: [f64; 3],
    /// Receiver clock per system in `System::ALL` order, m.
    pub clock_m: [Option<f64>; MAX_SYSTEMS],
    /// The all-in-view test.
    pub initial_test: TestStatistic,
    /// The test of the solution in force.
    pub test: TestStatistic,
    /// The satellite identified on the all-in-view solution when the test failed.
    pub identified: Option<SatId>,
    /// Exclusion steps (in force when the decision is `Excluded`).
    pub exclusions: heapless::Vec<Exclusion, MAX_EXCLUSIONS>,
    /// Horizontal protection level of the solution in force, m.
    pub hpl_m: f64,
    /// Vertical protection level of the solution in force, m.
    pub vpl_m: f64,
    /// Satellite with the largest horizontal slope.
    pub worst_h: Option<SatId>,
    /// Satellite with the largest vertical slope.
    pub worst_v: Option<SatId>,
    /// 1-sigma ENU position error of the solution in force, m.
    pub sigma_enu_m: [f64; 3],
    /// Non-centrality lambda_md used for the PLs.
    pub lambda_md: f64,
    /// n - m >= 1 in the solution in force.
    pub detection_available: bool,
    /// n - m >= 2 in the solution in force.
    pub exclusion_available: bool,
    /// PLs within the alert limits.
    pub pl_available: bool,
    /// Gauss-Newton iterations of the all-in-view solve (0 for linear input).
    pub iterations: u32,
    /// Per satellite, in input order.
    pub satellites: heapless::Vec<SatelliteResult, CAPACITY>,
    /// The MCUSUM state, when the sequential monitor is on.
    pub mcusum: Option<WireMcusum>,
}

impl WireResult {
    /// The wire form of a result of an engine of capacity `N <= CAPACITY`
    /// (satellites beyond `CAPACITY` cannot occur then; were `N` larger they
    /// would be cut, which `from_result` documents rather than hides:
    /// `satellites.len()` would be shorter than the epoch).
    pub fn from_result<const N: usize>(r: &EpochResult<N>) -> Self {
        let mut w = Self::empty();
        w.set_from_result(r);
        w
    }

    /// The initial value of the server's result storage: an unavailable
    /// epoch with no satellites (a conservative verdict, never a fix),
    /// overwritten in full by [`WireResult::set_from_result`]: the server
    /// keeps one `WireResult` in its own (static) storage and fills it in
    /// place.
    pub const fn empty() -> Self {
        WireResult {
            time_s: 0.0,
            decision: Decision::Unavailable,
            alarm_cause: None,
            position_ecef_m: None,
            geodetic: None,
            correction_enu_m: [0.0; 3],
            clock_m: [None; MAX_SYSTEMS],
            initial_test: TestStatistic::ZERO,
            test: TestStatistic::ZERO,
            identified: None,
            exclusions: heapless::Vec::new(),
            hpl_m: f64::INFINITY,
            vpl_m: f64::INFINITY,
            worst_h: None,
            worst_v: None,
            sigma_enu_m: [0.0; 3],
            lambda_md: 0.0,
            detection_available: false,
            exclusion_available: false,
            pl_available: false,
            iterations: 0,
            satellites: heapless::Vec::new(),
            mcusum: None,
        }
    }

    /// Overwrite every field with the wire form of `r` (as
    /// [`WireResult::from_result`], without a result-sized value on the
    /// stack, for the firmware's stack budget).
    pub fn set_from_result<const N: usize>(&mut self, r: &EpochResult<N>) {
        self.satellites.clear();
        for s in r.satellites.iter() {
            let _ = self.satellites.push(*s);
        }
        self.time_s = r.time_s;
        self.decision = r.decision;
        self.alarm_cause = r.alarm_cause;
        self.position_ecef_m = r.position_ecef_m;
        self.geodetic = r.geodetic;
        self.correction_enu_m = r.correction_enu_m;
        self.clock_m = r.clock_m;
        self.initial_test = r.initial_test;
        self.test = r.test;
        self.identified = r.identified;
        self.exclusions.clear();
        for e in r.exclusions.iter() {
            let _ = self.exclusions.push(*e);
        }
        self.hpl_m = r.protection.hpl_m;
        self.vpl_m = r.protection.vpl_m;
        self.worst_h = r.worst_h;
        self.worst_v = r.worst_v;
        self.sigma_enu_m = r.sigma_enu_m;
        self.lambda_md = r.lambda_md;
        self.detection_available = r.detection_available;
        self.exclusion_available = r.exclusion_available;
        self.pl_available = r.pl_available;
        self.iterations = r.iterations;
        self.mcusum = r.mcusum;
    }

    /// Every field back to [`WireResult::empty`]'s value, in place (no
    /// result-sized value on the stack).
    pub fn reset(&mut self) {
        self.time_s = 0.0;
        self.decision = Decision::Unavailable;
        self.alarm_cause = None;
        self.position_ecef_m = None;
        self.geodetic = None;
        self.correction_enu_m = [0.0; 3];
        self.clock_m = [None; MAX_SYSTEMS];
        self.initial_test = TestStatistic::default();
        self.test = TestStatistic::default();
        self.identified = None;
        self.exclusions.clear();
        self.hpl_m = f64::INFINITY;
        self.vpl_m = f64::INFINITY;
        self.worst_h = None;
        self.worst_v = None;
        self.sigma_enu_m = [0.0; 3];
        self.lambda_md = 0.0;
        self.detection_available = false;
        self.exclusion_available = false;
        self.pl_available = false;
        self.iterations = 0;
        self.satellites.clear();
        self.mcusum = None;
    }

    /// Overwrite every field with what an ARAIM epoch's answer says, for
    /// the NMEA writer: the verdict, the position in force (a pseudorange
    /// epoch's; none for a linearised one), the PLs in force, and the
    /// epoch's satellites `ids` (in input order), each used unless ARAIM
    /// excluded it. What ARAIM does not compute (per-satellite statistics,
    /// the ENU sigmas, the snapshot tests) is NaN or absent, so the
    /// sentences leave those fields empty rather than show a number ARAIM
    /// never produced. An excluded satellite is named in GBS with empty
    /// statistics.
    pub fn set_from_araim(
        &mut self,
        r: &crate::araim_msg::WireAraimResult,
        ids: impl IntoIterator<Item = SatId>,
    ) {
        let in_force = r.in_force();
        self.reset();
        self.time_s = r.time_s;
        self.decision = r.decision;
        self.position_ecef_m = r.position_ecef_m;
        self.geodetic = r.position_ecef_m.map(raim_core::frames::ecef_to_geodetic);
        self.hpl_m = in_force.hpl_m;
        self.vpl_m = in_force.vpl_m;
        self.sigma_enu_m = [f64::NAN; 3];
        self.pl_available = in_force.unavailable.is_none();
        for (index, id) in ids.into_iter().enumerate() {
            let excluded = r.excluded.contains(&id);
            // Both lists hold at most CAPACITY entries: the epoch was
            // decoded into a list of that capacity.
            if self
                .satellites
                .push(unknown_satellite(id, !excluded))
                .is_err()
            {
                break;
            }
            if excluded && self.exclusions.len() < MAX_EXCLUSIONS {
                let _ = self.exclusions.push(unknown_exclusion(id, index));
            }
        }
    }

    /// Overwrite every field with what a particle-filter epoch's answer
    /// says, for the NMEA writer: `decision` (the server's reading of the
    /// epoch, the one that drives the alarm output), the filter's position,
    /// and the epoch's satellites `ids`, each used unless the filter
    /// excluded it this epoch. The filters compute no protection level, so
    /// both are +infinity; their per-satellite statistics are NaN, and the
    /// sentences leave those fields empty.
    pub fn set_from_pf(
        &mut self,
        r: &crate::pf_msg::WirePfResult,
        decision: Decision,
        ids: impl IntoIterator<Item = SatId>,
    ) {
        self.reset();
        self.time_s = r.time_s;
        self.decision = decision;
        self.position_ecef_m = r.position_ecef_m;
        self.geodetic = r.position_ecef_m.map(raim_core::frames::ecef_to_geodetic);
        self.sigma_enu_m = [f64::NAN; 3];
        for (index, id) in ids.into_iter().enumerate() {
            let excluded = r.excluded == Some(id);
            if self
                .satellites
                .push(unknown_satellite(id, !excluded))
                .is_err()
            {
                break;
            }
            if excluded {
                let _ = self.exclusions.push(unknown_exclusion(id, index));
            }
        }
    }

    /// The satellite most likely to be faulty: the identified one if the
    /// test failed, else the best-scoring identifiable satellite under the
    /// configured rule (SPEC §4). Used for NMEA GBS field 5.
    pub fn most_likely_failed(&self) -> Option<&SatelliteResult> {
        if let Some(id) = self.identified {
            if let Some(s) = self.satellites.iter().find(|s| s.id == id) {
                return Some(s);
            }
        }
        self.satellites
            .iter()
            .filter(|s| s.identifiable && s.score.is_finite())
            .fold(None, |best: Option<&SatelliteResult>, s| match best {
                Some(b) if !(s.score > b.score) => Some(b),
                _ => Some(s),
            })
    }
}

/// A satellite of an ARAIM or particle-filter epoch: its identity and
/// whether the solution in force uses it; the snapshot statistics, which
/// those methods do not compute, NaN (empty in NMEA).
fn unknown_satellite(id: SatId, used: bool) -> SatelliteResult {
    let nan = f64::NAN;
    SatelliteResult {
        id,
        used,
        sigma_m: nan,
        elevation_rad: nan,
        s_ii: nan,
        h_ii: nan,
        w: nan,
        bias_m: nan,
        score: nan,
        identifiable: false,
    }
}

/// An exclusion by ARAIM or a particle filter: the satellite and its index
/// in the epoch, without the snapshot test's statistics.
fn unknown_exclusion(id: SatId, index: usize) -> Exclusion {
    Exclusion {
        id,
        index,
        before: TestStatistic::default(),
        after: TestStatistic::default(),
        score: f64::NAN,
        bias_m: f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::message::{Response, ResponseBody};
    use crate::{frame, MAX_RESPONSE_FRAME, MAX_RESPONSE_PAYLOAD};
    use raim_core::snapshot::fde::AlarmCause;
    use raim_core::{Config, Epoch, LinearObservation, Raim, System};

    /// `reset` restores every field of a filled result to `empty`'s value
    /// (a field added later and forgotten there fails here).
    #[test]
    fn reset_is_empty() {
        let sats: std::vec::Vec<LinearObservation> = (1..=8u8)
            .map(|prn| {
                let az = f64::from(prn) * 0.7;
                LinearObservation::from_az_el(
                    SatId::new(System::Gps, prn),
                    az,
                    0.2 + 0.1 * f64::from(prn),
                    if prn == 3 { 80.0 } else { 0.5 },
                )
            })
            .collect();
        let r = Raim::<8>::new()
            .process(&Config::default(), &Epoch::linear(5.0, &sats))
            .unwrap();
        let mut w = WireResult::from_result(&r);
        assert_ne!(w, WireResult::empty());
        w.reset();
        assert_eq!(w, WireResult::empty());
    }

    /// An unbounded protection level is +infinity in the initial storage
    /// and on the wire: postcard carries the f64 bit pattern, so +inf
    /// decodes as +inf (never 0, never f64::MAX); so do the ARAIM summary's
    /// levels and the sigma bound's error.
    ///
    /// Verifies: SAFE-T8
    #[test]
    fn unbounded_levels_travel_as_infinity() {
        let w = WireResult::empty();
        assert_eq!((w.hpl_m, w.vpl_m), (f64::INFINITY, f64::INFINITY));
        let mut buf = [0u8; MAX_RESPONSE_PAYLOAD];
        let bytes = postcard::to_slice(&w, &mut buf).unwrap().to_vec();
        let back: WireResult = postcard::from_bytes(&bytes).unwrap();
        assert_eq!((back.hpl_m, back.vpl_m), (f64::INFINITY, f64::INFINITY));
        let e: crate::error::WireError = raim_core::RaimError::SigmaOutOfRange {
            index: 3,
            sigma_m: 1e30,
            min_m: 0.3,
            max_m: 150.0,
        }
        .into();
        let bytes = postcard::to_slice(&e, &mut buf).unwrap().to_vec();
        let back: crate::error::WireError = postcard::from_bytes(&bytes).unwrap();
        assert_eq!(
            back,
            crate::error::WireError::SigmaOutOfRange {
                index: 3,
                sigma_m: 1e30,
                min_m: 0.3,
                max_m: 150.0
            }
        );
    }

    /// The seeds' 8-satellite sky with a 50 m step on G02 (docs/CORE.md
    /// example): decodes back to the same bytes, and carries the exclusion.
    #[test]
    fn a_core_result_round_trips() {
        let sky = [
            (0.0, 85.0),
            (45.0, 30.0),
            (100.0, 50.0),
            (150.0, 20.0),
            (200.0, 60.0),
            (250.0, 25.0),
            (300.0, 40.0),
            (340.0, 15.0),
        ];
        let res = [0.57, 50.0 - 0.23, -0.80, 1.12, -0.05, 0.08, 0.40, 0.86];
        let sats: std::vec::Vec<LinearObservation> = sky
            .iter()
            .zip(res)
            .enumerate()
            .map(|(i, (&(az, el), r)): (usize, (&(f64, f64), f64))| {
                let mut o = LinearObservation::from_az_el(
                    SatId::new(System::Gps, i as u8 + 1),
                    az.to_radians(),
                    el.to_radians(),
                    r,
                );
                o.sigma_m = Some(1.0);
                o
            })
            .collect();
        let r = Raim::<CAPACITY>::new()
            .process(&Config::default(), &Epoch::linear(3.0, &sats))
            .unwrap();
        let w = WireResult::from_result(&r);
        assert_eq!(w.decision, Decision::Excluded);
        assert_eq!(w.exclusions.len(), 1);
        assert_eq!(w.exclusions[0].id, SatId::new(System::Gps, 2));
        assert_eq!(
            w.most_likely_failed().map(|s| s.id),
            Some(SatId::new(System::Gps, 2))
        );
        let mut buf = [0u8; MAX_RESPONSE_PAYLOAD];
        let bytes = postcard::to_slice(&w, &mut buf).unwrap().to_vec();
        let back: WireResult = postcard::from_bytes(&bytes).unwrap();
        let mut buf2 = [0u8; MAX_RESPONSE_PAYLOAD];
        assert_eq!(postcard::to_slice(&back, &mut buf2).unwrap(), &bytes[..]);
    }

    #[test]
    fn largest_response_fits() {
        let sat = SatelliteResult {
            id: SatId::new(System::Qzss, 255),
            used: true,
            sigma_m: 1.0,
            elevation_rad: 1.0,
            s_ii: 0.5,
            h_ii: 0.5,
            w: 1.0,
            bias_m: 1.0,
            score: 1.0,
            identifiable: true,
        };
        let test = TestStatistic {
            statistic: 1.0,
            threshold: 2.0,
            dof: u32::MAX,
        };
        let excl = Exclusion {
            id: sat.id,
            index: usize::MAX,
            before: test,
            after: test,
            score: 1.0,
            bias_m: 1.0,
        };
        let w = WireResult {
            time_s: 1.0,
            decision: Decision::Alarm,
            alarm_cause: Some(AlarmCause::Ambiguous {
                best: sat.id,
                runner_up: sat.id,
            }),
            position_ecef_m: Some([1.0; 3]),
            geodetic: Some(Geodetic::default()),
            correction_enu_m: [1.0; 3],
            clock_m: [Some(1.0); MAX_SYSTEMS],
            initial_test: test,
            test,
            identified: Some(sat.id),
            exclusions: core::iter::repeat_n(excl, MAX_EXCLUSIONS).collect(),
            hpl_m: 1.0,
            vpl_m: 1.0,
            worst_h: Some(sat.id),
            worst_v: Some(sat.id),
            sigma_enu_m: [1.0; 3],
            lambda_md: 1.0,
            detection_available: true,
            exclusion_available: true,
            pl_available: true,
            iterations: u32::MAX,
            satellites: core::iter::repeat_n(sat, CAPACITY).collect(),
            mcusum: Some(WireMcusum {
                statistic: 1.0,
                threshold: 1.0,
                k: 1.0,
                c: 1.0,
                dim: u32::MAX,
                prior_norm: 1.0,
                identified: Some(sat.id),
                after_exclusion: Some(1.0),
                held: [Some(sat.id); raim_core::sequential::mcusum::MAX_HELD],
                ..WireMcusum::default()
            }),
        };
        let resp = Response {
            seq: Some(u32::MAX),
            body: ResponseBody::Result(w),
            config: crate::ConfigId {
                fingerprint: [0xFF; 16],
                locked: true,
                source: crate::ConfigSource::Runtime,
            },
        };
        let mut scratch = [0u8; MAX_RESPONSE_PAYLOAD];
        let mut out = [0u8; MAX_RESPONSE_FRAME];
        let f = frame::encode(&resp, &mut scratch, &mut out).unwrap();
        assert!(f.len() <= MAX_RESPONSE_FRAME);
    }
}
