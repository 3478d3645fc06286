//! A receiver wired straight to the unit: its RTCM 3 frames arrive on the
//! link UART beside the host's frames ([`raim_proto::link`] separates
//! them), and the unit forms its own epochs from them
//! ([`raim_nav::rtcm::StreamReceiver`]: ephemerides, satellite positions
//! and clocks, the corrections, in f64), runs the monitor on each as it
//! runs a `Ranges` epoch, and writes the NMEA sentences and the alarm
//! output. No host is in the loop.
//!
//! Each stream epoch is answered on the link unasked (`seq: None`): its
//! result, or why it could not be run (`StreamNotDated` before the first
//! GPS ephemeris, `StreamCapacity`, `Unconfigured` with no configuration
//! in force: a stream never puts a default in force). Sigmas are the
//! unit's own (`raim_nav::ranging::stream_sigma_for_m`, [`stream_sigmas`]),
//! whatever `host_sigmas` says: the
//! host supplies nothing here. docs/RECEIVERS.md "Straight into the unit".
//!
//! **Which monitor.** ARAIM is the configured monitor when an ISM is in
//! force (provisioned, or taken from an `Ism`/`AuthIsm` frame, as for the
//! host's `Araim` epochs): each stream epoch is then staged as an
//! `Araim(Ranges)` epoch and answered by `answer_araim_epoch`, the one
//! ARAIM decision path (its answer, NMEA and alarm output); otherwise as a
//! `Ranges` epoch through `answer_epoch`. A satellite the ISM has no entry
//! for is that path's typed refusal of the epoch (`NotInIsm`), never a
//! default entry. The stream sigma of an ARAIM epoch has no
//! signal-in-space term: the ISM's sigma_URA and sigma_URE carry it, and
//! the stream sigma is the satellite's nominal that the ARAIM join adds
//! to them, `raim replay --araim`'s own rule
//! (`raim_nav::ranging::araim_curves`: the DO-229 troposphere and the
//! ADD's airborne multipath and noise curves through the noise factor of
//! the signal pair the epoch formed; for a single-frequency range the
//! doubled residual ionosphere the ADD's dual-frequency model lacks)
//! (docs/RECEIVERS.md "ARAIM from the stream").

use crate::{IoError, Platform, Server, SNAPSHOT_SATS};
use embedded_io::Write;
use raim_nav::ranging::StreamSigmas;
use raim_nav::rtcm::{FormError, FormScratch, FormedEpoch, StreamReceiver};
use raim_proto::araim_msg::AraimCommand;
use raim_proto::error::WireError;
use raim_proto::lock::ConfigSource;
use raim_proto::message::{Command, RangeEpoch, Request, SatList};

/// Signals one stream epoch may carry (GPS, GLONASS, Galileo, BeiDou and
/// QZSS, every band: e.g. 60 satellites on 3 signals and more; an epoch
/// with more is refused, `StreamCapacity`).
#[cfg(not(feature = "ram-192k"))]
pub const STREAM_SIGNALS: usize = 256;
/// Signals one stream epoch may carry on a part with 192 KiB of RAM: five
/// for each of the 24 satellites its epochs take (`SNAPSHOT_SATS`; five
/// is the most bands an MSM7 of one system carries for a satellite,
/// e.g. Galileo E1, E5a, E5b, E5 AltBOC and E6). An epoch with more is
/// refused whole, `StreamCapacity { capacity: 120 }`.
#[cfg(feature = "ram-192k")]
pub const STREAM_SIGNALS: usize = 120;
/// The elevation mask of stream epochs, rad (10 degrees, the replay's
/// default `--mask-deg`).
pub const STREAM_MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;
// `BUILD_GPS_WEEK`: the GPS week of this build's date
// (`SOURCE_DATE_EPOCH`, else the build machine's clock), written by
// build.rs.
include!(concat!(env!("OUT_DIR"), "/build_week.rs"));
/// Weeks before the build date a stream may still be dated in: a year,
/// for recordings made before the build and replayed into the unit.
pub const PIVOT_LOOKBACK_WEEKS: i64 = 52;
/// The stream's week-rollover pivot, the earliest week the unit places a
/// truncated week in (`raim_nav::rtcm::week_from_pivot`): a 10-bit GPS
/// week is read in `[PIVOT_WEEK, PIVOT_WEEK + 1023]`, so a unit built on
/// date D dates a stream correctly from D less a year to D plus 18.6
/// years (docs/RECEIVERS.md "Dating the stream").
pub const PIVOT_WEEK: i64 = BUILD_GPS_WEEK - PIVOT_LOOKBACK_WEEKS;

/// The stream receiver and the epoch it formed last.
pub struct StreamState {
    receiver: StreamReceiver<SNAPSHOT_SATS, STREAM_SIGNALS>,
    formed: FormedEpoch<SNAPSHOT_SATS>,
    epochs: u32,
}

impl StreamState {
    pub const fn new() -> Self {
        StreamState {
            receiver: StreamReceiver::new(PIVOT_WEEK),
            formed: FormedEpoch {
                time_gps_s: 0.0,
                reference_m: None,
                sats: heapless::Vec::new(),
                cn0_dbhz: heapless::Vec::new(),
                rates: heapless::Vec::new(),
                rejected: 0,
            },
            epochs: 0,
        }
    }

    /// Decode one RTCM frame; `Some` when it closed an epoch. `araim`:
    /// the epoch will run ARAIM, so its sigmas leave out the
    /// signal-in-space term ([`stream_sigmas`]). Not inlined: its
    /// stack stays off the link's other paths.
    #[inline(never)]
    pub(crate) fn on_frame(
        &mut self,
        frame: &[u8],
        config: Option<&raim_core::Config>,
        araim: bool,
        scratch: &mut FormScratch<SNAPSHOT_SATS>,
    ) -> Option<Result<(), FormError>> {
        let sigmas = stream_sigmas(config, araim);
        let r =
            self.receiver
                .on_frame_in(frame, &sigmas, STREAM_MASK_RAD, &mut self.formed, scratch);
        if r.is_some() {
            self.epochs = self.epochs.wrapping_add(1);
        }
        r
    }

    /// The epoch formed last, to be written by the tests as the receiver
    /// writes it.
    #[cfg(test)]
    pub(crate) fn formed_mut(&mut self) -> &mut FormedEpoch<SNAPSHOT_SATS> {
        &mut self.formed
    }

    /// The C/N0 of the satellites of the epoch formed last (GSV).
    pub(crate) fn cn0_dbhz(&self) -> &[u8] {
        &self.formed.cn0_dbhz
    }

    /// The speed and course over ground of the epoch formed last, for RMC
    /// and VTG ([`ground_velocity`]).
    pub(crate) fn velocity(
        &self,
        wire: &raim_proto::result::WireResult,
    ) -> Option<raim_proto::nmea::GroundVelocity> {
        ground_velocity(&self.formed, wire)
    }

    /// Epochs formed (answered or refused) and ephemerides held.
    pub(crate) fn counters(&self) -> (u32, [u16; 2]) {
        let (k, g) = self.receiver.ephemerides();
        let n = |x: usize| u16::try_from(x).unwrap_or(u16::MAX);
        (self.epochs, [n(k), n(g)])
    }
}

impl StreamState {
    /// The leap seconds the receiver dates GLONASS with, for `Status`.
    pub(crate) fn leap_seconds(&self) -> raim_proto::message::StreamLeapSeconds {
        use raim_nav::rtcm::LeapSeconds as L;
        use raim_proto::message::StreamLeapSeconds as S;
        match self.receiver.leap_seconds() {
            L::NotDated => S::NotDated,
            L::Stream(n) => S::Stream { gps_minus_utc_s: n },
            L::Table(n) => S::Table { gps_minus_utc_s: n },
            L::TableExpired => S::TableExpired,
        }
    }
}

impl Default for StreamState {
    fn default() -> Self {
        Self::new()
    }
}

/// The sigmas of a stream epoch's satellites
/// ([`raim_nav::ranging::stream_sigma_for_m`]): for the snapshot monitor
/// the configuration's model (the default before one is in force: such
/// epochs are refused `Unconfigured`); for ARAIM the nominal curves of
/// each satellite's signal pair, `raim replay --araim`'s
/// ([`raim_nav::ranging::araim_curves`]), with no signal-in-space term
/// (the ISM's sigma_URA/sigma_URE, which the ARAIM join adds,
/// `raim_core::araim::monitor`) and, for a single-frequency range, the
/// configuration's residual ionosphere doubled.
pub fn stream_sigmas(config: Option<&raim_core::Config>, araim: bool) -> StreamSigmas {
    let model = config.map_or_else(raim_core::sigma::SigmaModel::default, |c| c.sigma_model);
    if araim {
        StreamSigmas::Araim {
            iono_vertical_m: model.iono_vertical_m,
        }
    } else {
        StreamSigmas::Snapshot(model)
    }
}

/// The speed and course over ground of a formed stream epoch whose
/// answer is `wire` (docs/RECEIVERS.md "Speed and course"): none unless
/// the decision is `Ok` or `Excluded` with a position; else the velocity
/// solution ([`raim_nav::velocity::solve`]) at that position from the
/// Doppler of the satellites the answer used (an excluded satellite is
/// left out), each weighted by its range sigma; none when fewer than four
/// have a rate or the geometry is singular.
pub fn ground_velocity<const N: usize>(
    formed: &FormedEpoch<N>,
    wire: &raim_proto::result::WireResult,
) -> Option<raim_proto::nmea::GroundVelocity> {
    use raim_core::Decision;
    use raim_nav::velocity::{solve, RateObservation};
    if !matches!(wire.decision, Decision::Ok | Decision::Excluded) {
        return None;
    }
    let rx_m = wire.position_ecef_m?;
    let used = |id: raim_core::SatId| wire.satellites.iter().any(|s| s.id == id && s.used);
    let mut sats = formed
        .sats
        .iter()
        .zip(formed.rates.iter())
        .filter_map(|(obs, rate)| {
            let rate = (*rate)?;
            used(obs.id).then_some(RateObservation {
                sat_position_m: obs.position_m,
                rate,
                sigma_m: obs.sigma_m.unwrap_or(1.0),
            })
        });
    let v = solve(rx_m, &mut sats).ok()?;
    Some(raim_proto::nmea::GroundVelocity {
        speed_m_s: v.speed_over_ground_m_s(),
        course_rad: v.course_over_ground_rad(),
    })
}

/// The monitor a staged stream epoch runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StreamMonitor {
    /// The snapshot monitor (`answer_epoch`).
    Snapshot,
    /// ARAIM with the ISM in force (`answer_araim_epoch`).
    Araim,
}

/// The wire form of a stream epoch that could not be formed.
fn wire_error(e: FormError) -> WireError {
    match e {
        FormError::NotDated { tow_ms } => WireError::StreamNotDated {
            tow_ms: u32::try_from(tow_ms).unwrap_or(u32::MAX),
        },
        FormError::TooManySignals { capacity } => WireError::StreamCapacity { capacity },
        FormError::LeapSecondsUnknown { tow_ms } => WireError::StreamLeapSecondsUnknown {
            tow_ms: u32::try_from(tow_ms).unwrap_or(u32::MAX),
        },
    }
}

impl Server {
    /// Whether stream epochs run ARAIM: an ISM is in force (module docs,
    /// "Which monitor").
    pub(crate) fn stream_runs_araim(&self) -> bool {
        self.araim.runs_stream()
    }

    /// A stream epoch closed (`formed`: whether it could be formed, its
    /// satellites in `self.stream`): staged in the request slot and run by
    /// the monitor in force, or refused; answered unasked (`seq: None`).
    pub(crate) fn on_stream_epoch<L: Write, M: Write, P: Platform>(
        &mut self,
        formed: Result<(), FormError>,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        match self.stage_stream_epoch(formed, link, nmea_out, platform)? {
            Some(StreamMonitor::Snapshot) => self.answer_epoch(None, link, nmea_out, platform),
            Some(StreamMonitor::Araim) => self.answer_araim_epoch(None, link, nmea_out, platform),
            None => Ok(()),
        }
    }

    /// A stream epoch closed (`formed`: whether it could be formed): put it
    /// in the request slot as a `Ranges` epoch, or as an `Araim(Ranges)`
    /// epoch when an ISM is in force, and say which monitor runs it (the
    /// caller runs it), or refuse it, answered unasked (`None`). Not
    /// inlined, and the epoch is run by the caller: the slot's value is
    /// built in this frame, which is gone when the engine runs.
    #[inline(never)]
    pub(crate) fn stage_stream_epoch<L: Write, M: Write, P: Platform>(
        &mut self,
        formed: Result<(), FormError>,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<Option<StreamMonitor>, IoError<L::Error, M::Error>> {
        let monitor = if self.stream_runs_araim() {
            StreamMonitor::Araim
        } else {
            StreamMonitor::Snapshot
        };
        let f = &self.stream.formed;
        let time_s = raim_nav::time::unix_utc_with_s(
            f.time_gps_s,
            self.stream.receiver.utc_offset_s(f.time_gps_s),
        );
        let mut sats = SatList::default();
        for s in f.sats.iter() {
            // `formed` holds at most SNAPSHOT_SATS <= CAPACITY satellites.
            let _ = sats.items.push(*s);
        }
        sats.declared = u32::try_from(sats.items.len()).unwrap_or(u32::MAX);
        let epoch = RangeEpoch {
            time_s,
            apriori_m: f.reference_m,
            sats,
        };
        self.request = Some(Request {
            seq: 0,
            command: match monitor {
                StreamMonitor::Snapshot => Command::Ranges(epoch),
                StreamMonitor::Araim => Command::Araim(AraimCommand::Ranges(epoch)),
            },
        });
        let unconfigured =
            self.config_id.source == ConfigSource::Unconfigured || self.config.is_none();
        let refusal = match formed {
            Err(e) => Some(wire_error(e)),
            Ok(()) if unconfigured => Some(WireError::Unconfigured {
                provision: self.provision_error,
            }),
            Ok(()) => None,
        };
        match refusal {
            Some(e) => {
                platform.on_epoch(None);
                self.write_no_fix(None, nmea_out).map_err(IoError::Nmea)?;
                self.request = None;
                self.send(link, None, crate::answer::BodyRef::Error(&e))?;
                Ok(None)
            }
            None => Ok(Some(monitor)),
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    /// An epoch the receiver could not form is refused with its typed
    /// wire error, the values carried over.
    ///
    /// Verifies: WIRE-StreamCapacity, WIRE-StreamNotDated
    #[test]
    fn unformed_epochs_map_to_their_wire_errors() {
        assert_eq!(
            wire_error(FormError::TooManySignals { capacity: 128 }),
            WireError::StreamCapacity { capacity: 128 }
        );
        assert_eq!(
            wire_error(FormError::NotDated {
                tow_ms: 345_600_000
            }),
            WireError::StreamNotDated {
                tow_ms: 345_600_000
            }
        );
        assert_eq!(
            wire_error(FormError::NotDated { tow_ms: -1 }),
            WireError::StreamNotDated { tow_ms: u32::MAX }
        );
    }

    /// The stream sigmas: the configuration's model for the snapshot
    /// monitor (the default model before a configuration is in force),
    /// and for ARAIM the pair curves with the configuration's residual
    /// ionosphere for single-frequency ranges.
    #[test]
    fn araim_stream_sigmas_leave_the_signal_in_space_to_the_ism() {
        let mut c = raim_core::Config::default();
        c.sigma_model.ura_m = 1.5;
        c.sigma_model.iono_vertical_m = 0.7;
        assert_eq!(
            stream_sigmas(Some(&c), false),
            StreamSigmas::Snapshot(c.sigma_model)
        );
        assert_eq!(
            stream_sigmas(Some(&c), true),
            StreamSigmas::Araim {
                iono_vertical_m: 0.7
            }
        );
        assert_eq!(
            stream_sigmas(None, false),
            StreamSigmas::Snapshot(raim_core::sigma::SigmaModel::default())
        );
    }

    /// A GLONASS epoch past the leap-second table's expiry, with no count
    /// from the stream, is refused `StreamLeapSecondsUnknown`.
    ///
    /// Verifies: WIRE-StreamLeapSecondsUnknown
    #[test]
    fn leap_seconds_unknown_maps_to_its_wire_error() {
        assert_eq!(
            wire_error(FormError::LeapSecondsUnknown { tow_ms: 7_000 }),
            WireError::StreamLeapSecondsUnknown { tow_ms: 7_000 }
        );
    }

    /// The velocity of a formed epoch is solved only for an `Ok` or
    /// `Excluded` answer with a position, from the satellites the answer
    /// used: a satellite not used (excluded) with a rate 50 m/s off moves
    /// nothing; used, it moves the speed. A receiver at rest in the
    /// satellites' rates (their rates exactly the satellites' line-of-sight
    /// motion) reads 0 speed; a missing rate on one satellite of five
    /// leaves four, still solved; three are not.
    ///
    /// Verifies: RX-VELOCITY
    #[test]
    fn ground_velocity_takes_the_answers_used_satellites_only() {
        use raim_core::{Decision, SatId, System};
        use raim_nav::velocity::RangeRate;
        use raim_proto::result::WireResult;
        let rx = [3_582_105.0, 532_590.0, 5_232_755.0];
        // Five satellites around the sky, 20,000 km up-ish.
        let dirs: [[f64; 3]; 5] = [
            [0.3, 0.1, 0.95],
            [0.9, -0.3, 0.3],
            [-0.5, 0.8, 0.3],
            [0.1, -0.9, 0.4],
            [0.6, 0.6, 0.5],
        ];
        let mut formed = FormedEpoch::<SNAPSHOT_SATS>::new();
        let mut wire = WireResult::empty();
        for (k, d) in dirs.iter().enumerate() {
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let u = [d[0] / n, d[1] / n, d[2] / n];
            let p = [0, 1, 2].map(|i| rx[i] + 2.0e7 * u[i]);
            let id = SatId::new(System::Gps, k as u8 + 1);
            let v_sat = [1000.0 * u[1], -1000.0 * u[0], 500.0];
            let range_rate = u[0] * v_sat[0] + u[1] * v_sat[1] + u[2] * v_sat[2];
            let _ = formed.sats.push(raim_core::RangeObservation {
                id,
                pseudorange_m: 2.0e7,
                position_m: p,
                sigma_m: Some(1.0),
            });
            let _ = formed.rates.push(Some(RangeRate {
                rate_m_s: range_rate,
                sat_velocity_m_s: v_sat,
                sat_clock_drift_s_s: 0.0,
            }));
            let _ = wire.satellites.push(raim_core::SatelliteResult {
                id,
                used: true,
                sigma_m: 1.0,
                elevation_rad: 0.5,
                s_ii: 0.5,
                h_ii: 0.5,
                w: 0.0,
                bias_m: 0.0,
                score: 0.0,
                identifiable: true,
            });
        }
        wire.position_ecef_m = Some(rx);
        wire.decision = Decision::Ok;
        // At rest (to the light-time factor, 3e-6 of the rates).
        let v = ground_velocity(&formed, &wire).unwrap();
        assert!(v.speed_m_s < 0.01, "{v:?}");
        // Satellite 3's rate 50 m/s off, and the answer excluded it.
        if let Some(Some(r)) = formed.rates.get_mut(2) {
            r.rate_m_s += 50.0;
        }
        wire.satellites[2].used = false;
        wire.decision = Decision::Excluded;
        let v = ground_velocity(&formed, &wire).unwrap();
        assert!(v.speed_m_s < 0.01, "{v:?}");
        // Used, it moves the solution.
        wire.satellites[2].used = true;
        wire.decision = Decision::Ok;
        let v = ground_velocity(&formed, &wire).unwrap();
        assert!(v.speed_m_s > 1.0, "{v:?}");
        // No velocity for an epoch that is not a valid fix.
        for d in [Decision::Alarm, Decision::Unavailable] {
            wire.decision = d;
            assert_eq!(ground_velocity(&formed, &wire), None, "{d:?}");
        }
        wire.decision = Decision::Ok;
        wire.position_ecef_m = None;
        assert_eq!(ground_velocity(&formed, &wire), None);
        // Four rates still solve; three do not.
        wire.position_ecef_m = Some(rx);
        wire.satellites[2].used = false;
        assert!(ground_velocity(&formed, &wire).is_some());
        formed.rates[0] = None;
        assert_eq!(ground_velocity(&formed, &wire), None);
    }

    /// The pivot is the build week less the lookback, and the build week
    /// is not after the week this test runs in (a build is not dated in
    /// the future).
    #[test]
    fn the_pivot_is_the_build_week_less_a_year() {
        assert_eq!(PIVOT_WEEK, BUILD_GPS_WEEK - 52);
        let unix_s = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_secs() as i64);
        let now_week = (unix_s - 315_964_800).div_euclid(604_800);
        assert!(BUILD_GPS_WEEK <= now_week, "{BUILD_GPS_WEEK} > {now_week}");
    }
}
