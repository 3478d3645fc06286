//! ARAIM in the protocol server (docs/PROTOCOL.md "ARAIM"): the
//! ISM in force, its validation, the ARAIM engine and its FDE scratch,
//! all in the (static) server, so that the main loop's stack carries no
//! ARAIM buffer. The FDE scratch is the ARAIM state's own, except on the
//! STM32F4 stream build (`ram-192k` and `rtcm`), where it is a part of the
//! server's shared per-epoch room (`Shared`, docs/FLASH.md "STM32F4: the
//! stream", item 5).
//!
//! Lifecycle: no ISM at reset; an `Ism` frame replaces the ISM and ARAIM
//! configuration as a whole after every check passes (else the previous one
//! stays); `Configure` leaves it alone; `Lock` locks it with the snapshot
//! configuration (an `Ism` frame is then `Locked`); the configuration
//! fingerprint covers it. A unit with an authentication key takes the ISM
//! only as `AuthIsm` (HMAC-SHA256, counter shared with `AuthConfigure`). An epoch satellite without an ISM entry is a typed
//! error (`NotInIsm`), never a default: P_sat and sigma_URA are integrity
//! parameters the unit must not invent.

use raim_core::araim::{AraimConfig, AraimError, Ism};
use raim_core::Config;

use super::Server;
use raim_proto::araim_msg::{
    AraimAnswer, AraimCommand, AraimWireError, IsmFrame, IsmSat, WireAraimResult,
};
use raim_proto::error::WireError;
use raim_proto::message::{LinearEpoch, RangeEpoch};

/// An ARAIM epoch as it arrived: linearised, or pseudoranges. (Without the
/// `araim` feature it is only refused, `Disabled`.)
#[cfg_attr(not(feature = "araim"), allow(dead_code))]
enum Input<'a> {
    Linear(&'a LinearEpoch),
    Ranges(&'a RangeEpoch),
}
use raim_proto::CAPACITY;

/// Fault modes the device engine holds (per engine; the FDE scratch has as
/// many). A mode list that needs more makes the epoch unavailable with
/// `ModeCapacity`, never truncated. At P_sat 1e-5 and P_const 1e-4: 20
/// satellites need 22 modes (single faults), 24 need 327 (pairs), 32 need
/// 563 (BENCHMARKS.md). The engines take ~280 KB of static RAM (f32,
/// 32 satellites: 160 B per mode per engine).
#[cfg(not(feature = "ram-192k"))]
pub const MAX_MODES: usize = 600;
/// Fault modes the device engine holds, sized for a part with 192 KiB of
/// RAM (the STM32F405/407, docs/FLASH.md): at P_sat 1e-5 and P_const 1e-8
/// n satellites need n + 2 modes (24 satellites: 26), at P_const 1e-4 up
/// to 22 satellites need 24; a sky that needs more (24 satellites at
/// P_const 1e-4: 327) is unavailable with `ModeCapacity`, never truncated.
#[cfg(feature = "ram-192k")]
pub const MAX_MODES: usize = 48;

/// Satellites the device's ARAIM engine takes: the wire's capacity, or 24
/// on a part with 192 KiB of RAM (each satellite costs ~1.6 KB across the
/// two engines). An epoch with more is refused with the typed capacity
/// error (`AraimError::CapacityExceeded`), never truncated.
#[cfg(not(feature = "ram-192k"))]
pub const ARAIM_SATS: usize = CAPACITY;
/// Satellites the device's ARAIM engine takes on a part with 192 KiB of
/// RAM.
#[cfg(feature = "ram-192k")]
pub const ARAIM_SATS: usize = 24;
const _: () = assert!(ARAIM_SATS <= CAPACITY);

/// Exclusion is attempted when the failed all-in-view run has at most
/// this many monitored modes; above it the epoch would be an alarm
/// (`WireFde::NotAttempted`). It equals the engine's mode capacity: the
/// core's FDE checks each candidate by its tests with an early exit at a
/// certain failure, so stage 1 costs about one more all-in-view run plus
/// the failing candidates' exits, and the multi-event stage 2 is bounded by
/// [`FDE_WORK_BUDGET`]. The measured costs are in BENCHMARKS.md and
/// docs/ARAIM.md, "FDE work budget".
pub const MAX_FDE_MODES: u32 = MAX_MODES as u32;

/// The FDE's work budget, in candidate-modes: the search may process at
/// most `FDE_WORK_BUDGET / m` candidate subsets when the all-in-view run
/// has `m` monitored modes (`raim_core::araim::fde::FdeBudget`); beyond
/// it the epoch is an `Alarm`, `WireFde::BudgetExceeded`, decided before
/// the stage that would overrun is started. Per mode, because a candidate
/// is a subset processed as an epoch of its own with about `m` modes, so a
/// search costs about (candidates x m) x c. The value keeps the costliest
/// admitted epoch within the watchdog margin that docs/SAFETY.md derives
/// (measured instruction counts: docs/ARAIM.md, "FDE work budget"). The
/// budget counts candidates, not tests: an epoch where far more candidates
/// pass all their own tests than in the measured sweep would cost more per
/// candidate.
pub const FDE_WORK_BUDGET: u32 = 110_000;

/// ARAIM's FDE scratch engine at the device's capacities.
#[cfg(feature = "araim")]
pub(super) type FdeScratch = raim_core::araim::FdeScratch<engine::AraimT, ARAIM_SATS, MAX_MODES>;

/// The ARAIM part of the server: the ISM in force and, with the `araim`
/// feature, the engine, the epoch's satellites and (except on the STM32F4
/// stream build, where it is in the shared room) the FDE scratch.
pub(super) struct AraimState {
    /// The ISM and ARAIM configuration in force; `None` since reset until
    /// an `Ism` frame is accepted.
    pub(super) ism: Option<IsmFrame>,
    #[cfg(feature = "araim")]
    engine: engine::Engines,
    #[cfg(all(feature = "araim", not(all(feature = "ram-192k", feature = "rtcm"))))]
    fde: FdeScratch,
}

impl AraimState {
    pub(super) const fn new() -> Self {
        AraimState {
            ism: None,
            #[cfg(feature = "araim")]
            engine: engine::Engines::new(),
            #[cfg(all(feature = "araim", not(all(feature = "ram-192k", feature = "rtcm"))))]
            fde: FdeScratch::new(),
        }
    }

    /// The ISM in force, the engine and the FDE scratch: the state's own,
    /// or on the STM32F4 stream build the shared room's (taking it).
    #[cfg(feature = "araim")]
    fn parts<'a>(
        &'a mut self,
        shared: &'a mut super::Shared,
    ) -> (
        Option<&'a IsmFrame>,
        &'a mut engine::Engines,
        &'a mut FdeScratch,
    ) {
        #[cfg(all(feature = "ram-192k", feature = "rtcm"))]
        let fde = shared.fde();
        #[cfg(not(all(feature = "ram-192k", feature = "rtcm")))]
        let fde = {
            let _ = shared;
            &mut self.fde
        };
        (self.ism.as_ref(), &mut self.engine, fde)
    }

    /// Whether ARAIM is the configured monitor of the unit's own stream
    /// epochs: an ISM is in force (`stream.rs`, "Which monitor").
    #[cfg_attr(not(feature = "rtcm"), allow(dead_code))]
    pub(super) fn runs_stream(&self) -> bool {
        self.ism.is_some()
    }
}

/// Range checks of an ISM frame: everything the core checks at an epoch
/// that the ISM alone determines, so that a bad ISM is refused when it
/// arrives rather than at every epoch.
pub fn check_ism(frame: &IsmFrame) -> Result<(), WireError> {
    if frame.sats.overflowed() {
        return Err(WireError::TooManySatellites {
            have: frame.sats.declared,
            capacity: CAPACITY as u32,
        });
    }
    if frame.sats.items.is_empty() {
        return Err(WireError::Araim(AraimWireError::EmptyIsm));
    }
    AraimConfig::from(frame.config).validate()?;
    let ism = Ism {
        p_const: frame.p_const,
    };
    ism.validate()?;
    for (i, s) in frame.sats.items.iter().enumerate() {
        raim_core::measurement::check_prn(i, s.id)?;
        check_sat(i, s)?;
        if frame
            .p_const
            .get(s.id.system.index())
            .copied()
            .flatten()
            .is_none()
        {
            return Err(AraimError::MissingConstellationIsm {
                system: s.id.system,
                index: i,
            }
            .into());
        }
        if let Some(j) = frame.sats.items.iter().take(i).position(|o| o.id == s.id) {
            return Err(AraimError::DuplicateSatellite {
                system: s.id.system,
                prn: s.id.prn,
                first: j,
                second: i,
            }
            .into());
        }
    }
    for (j, p) in frame.p_const.iter().enumerate() {
        let system = raim_core::System::ALL.get(j).copied().unwrap_or_default();
        if p.is_some() && !frame.sats.items.iter().any(|s| s.id.system == system) {
            return Err(AraimError::EmptyConstellation { system }.into());
        }
    }
    Ok(())
}

fn check_sat(index: usize, s: &IsmSat) -> Result<(), AraimError> {
    raim_core::config_bounds::araim::check_ism_entry(
        index,
        s.sigma_ura_m,
        s.sigma_ure_m,
        s.b_nom_m,
        s.p_sat,
    )
}

impl Server {
    /// Checks an ISM frame and, if it passes, puts it in force (the gate,
    /// `gate.rs`, has passed it and updates the fingerprint).
    pub(crate) fn take_ism(&mut self, frame: &IsmFrame) -> Result<u32, WireError> {
        check_ism(frame)?;
        let satellites = u32::try_from(frame.sats.items.len()).unwrap_or(u32::MAX);
        self.araim.ism = Some(frame.clone());
        Ok(satellites)
    }

    /// An ARAIM epoch request (`Araim(Epoch)` or `Araim(Ranges)`, in
    /// `self.request`; `seq` None for a stream epoch the unit formed
    /// itself, `stream.rs`), answered from a reference into the request
    /// (the firmware's stack: the epoch is not moved out of the
    /// server's request slot onto this frame, as `answer_other` moves the
    /// other requests).
    #[inline(never)]
    pub(super) fn answer_araim_epoch<
        L: embedded_io::Write,
        M: embedded_io::Write,
        P: super::Platform,
    >(
        &mut self,
        seq: Option<u32>,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), super::IoError<L::Error, M::Error>> {
        let answer = {
            let Server {
                request,
                araim,
                status,
                config,
                model,
                shared,
                ..
            } = self;
            let input = match request.as_ref().map(|r| &r.command) {
                Some(raim_proto::message::Command::Araim(AraimCommand::Epoch(e))) => {
                    Input::Linear(e)
                }
                Some(raim_proto::message::Command::Araim(AraimCommand::Ranges(e))) => {
                    Input::Ranges(e)
                }
                // `dispatch` sends only ARAIM epochs here.
                _ => return Ok(()),
            };
            epoch_answer(
                (araim, shared, model),
                status,
                config.as_ref(),
                &input,
                platform,
            )
        };
        self.write_araim_nmea(seq, &answer, nmea_out)
            .map_err(super::IoError::Nmea)?;
        match &answer {
            Ok(a) => self.send(link, seq, super::BodyRef::Araim(a)),
            Err(e) => self.send(link, seq, super::BodyRef::Error(e)),
        }
    }

    /// The NMEA sentences of an ARAIM epoch, as every epoch writes them:
    /// its verdict, position and PLs in force, with the excluded
    /// satellites not used ([`WireResult::set_from_araim`]); a refused
    /// epoch's no-fix sentences.
    ///
    /// [`WireResult::set_from_araim`]: raim_proto::result::WireResult::set_from_araim
    fn write_araim_nmea<M: embedded_io::Write>(
        &mut self,
        seq: Option<u32>,
        answer: &Result<AraimAnswer, WireError>,
        nmea_out: &mut M,
    ) -> Result<(), M::Error> {
        let Ok(AraimAnswer::Result(r)) = answer else {
            return self.write_no_fix(seq, nmea_out);
        };
        let Server {
            request, shared, ..
        } = self;
        let wire = &mut shared.answer().wire;
        match request.as_ref().map(|q| &q.command) {
            Some(raim_proto::message::Command::Araim(AraimCommand::Epoch(e))) => {
                wire.set_from_araim(r, e.sats.items.iter().map(|s| s.id));
            }
            Some(raim_proto::message::Command::Araim(AraimCommand::Ranges(e))) => {
                wire.set_from_araim(r, e.sats.items.iter().map(|s| s.id));
            }
            _ => return Ok(()),
        }
        let (wire, request, cn0, velocity) = self.nmea_parts(seq);
        super::answer::write_nmea(wire, request, cn0, velocity, nmea_out)
    }
}

/// An ARAIM epoch on the server's ARAIM state, shared room, status and
/// configuration (disjoint fields, so the epoch may be borrowed from the
/// request slot); the model check takes the delivered solution's C_acc
/// sample, and a model it has declared broken makes the decision
/// `Unavailable` (`model_check`); the decision (or the refusal, as `None`)
/// drives the integrity-alarm output like a snapshot epoch's
/// (`Platform::on_epoch`).
fn epoch_answer<P: super::Platform>(
    (araim, shared, model): (
        &mut AraimState,
        &mut super::Shared,
        &mut super::model_check::UnitModelCheck,
    ),
    status: &mut raim_proto::message::Status,
    config: Option<&Config>,
    epoch: &Input<'_>,
    platform: &mut P,
) -> Result<AraimAnswer, WireError> {
    let r = epoch_answer_inner(araim, shared, status, config, epoch, platform).map(
        |(mut res, sample)| {
            res.decision = super::model_check::judge(model, res.time_s, sample, res.decision);
            AraimAnswer::Result(res)
        },
    );
    platform.on_epoch(match &r {
        Ok(AraimAnswer::Result(res)) => Some(res.decision),
        _ => None,
    });
    r
}

/// An epoch's wire result and, unless it is an `Alarm`, the delivered
/// solution's (q, dof) against C_acc for the model check
/// (`raim_core::araim::Runs::accuracy_sample`; `None` when it has none).
type Evaluated = (WireAraimResult, Option<(f64, u32)>);

fn epoch_answer_inner<P: super::Platform>(
    araim: &mut AraimState,
    shared: &mut super::Shared,
    status: &mut raim_proto::message::Status,
    config: Option<&Config>,
    epoch: &Input<'_>,
    platform: &mut P,
) -> Result<Evaluated, WireError> {
    #[cfg(feature = "araim")]
    {
        let (Some(ism), engine, fde) = araim.parts(shared) else {
            return Err(WireError::Araim(AraimWireError::NoIsm));
        };
        status.epochs = status.epochs.wrapping_add(1);
        let watch = crate::Stopwatch::start(platform);
        // Both forms run with the snapshot configuration in force (the
        // solver's settings and sigma model); none in force: Unconfigured.
        let r = match (epoch, config) {
            (_, None) => Err(WireError::Unconfigured { provision: None }),
            (Input::Linear(e), Some(c)) => engine.run(fde, c, ism, e),
            (Input::Ranges(e), Some(c)) => engine.run_ranges(fde, c, ism, e),
        };
        let lap = watch.stop(platform);
        status.last_epoch_ticks = lap.ticks;
        lap.record(status, raim_proto::EpochKind::Araim);
        r
    }
    #[cfg(not(feature = "araim"))]
    {
        let _ = (araim, shared, status, config, epoch, platform);
        Err(WireError::Araim(AraimWireError::Disabled))
    }
}

#[cfg(feature = "araim")]
mod engine {
    use raim_core::araim::{
        AraimConfig, FdeLimits, Ism, MonitorCore, MonitorError, SatIsm, SatelliteModels,
    };
    use raim_core::SatId;

    use super::{
        AraimWireError, Evaluated, FdeScratch, IsmFrame, WireAraimResult, ARAIM_SATS,
        FDE_WORK_BUDGET, MAX_FDE_MODES, MAX_MODES,
    };
    use raim_core::{Config, Epoch};
    use raim_proto::araim_msg::IsmSat;
    use raim_proto::error::WireError;
    use raim_proto::message::{LinearEpoch, RangeEpoch};

    /// The unit's ARAIM precision: the device's.
    pub type AraimT = raim_proto::DevicePrecision;

    /// The core's ARAIM monitor: the engine, the epoch's satellites and,
    /// for a pseudorange epoch, its Gauss-Newton solution and linearised
    /// form (static, so the main loop's stack carries none of them); the
    /// FDE's scratch engine is lent at each epoch (`AraimState::parts`).
    pub(super) struct Engines(MonitorCore<AraimT, ARAIM_SATS, MAX_MODES>);

    /// The ISM frame's satellite entries, as the monitor joins them.
    struct Entries<'a>(&'a [IsmSat]);

    impl SatelliteModels for Entries<'_> {
        fn ism(&self, id: SatId) -> Option<SatIsm> {
            self.0.iter().find(|s| s.id == id).map(|s| SatIsm {
                id: s.id,
                sigma_ura_m: s.sigma_ura_m,
                sigma_ure_m: s.sigma_ure_m,
                b_nom_m: s.b_nom_m,
                p_sat: s.p_sat,
            })
        }
    }

    /// The device's exclusion limits: `MAX_FDE_MODES` and the work budget
    /// `FDE_WORK_BUDGET` (the watchdog).
    fn limits() -> FdeLimits {
        FdeLimits {
            max_modes: usize::try_from(MAX_FDE_MODES).unwrap_or(usize::MAX),
            work_candidate_modes: usize::try_from(FDE_WORK_BUDGET).unwrap_or(usize::MAX),
        }
    }

    impl Engines {
        pub(super) const fn new() -> Self {
            Engines(MonitorCore::new())
        }

        /// One linearised epoch: the core monitor with the ISM in force.
        pub(super) fn run(
            &mut self,
            fde: &mut FdeScratch,
            cfg: &Config,
            ism: &IsmFrame,
            epoch: &LinearEpoch,
        ) -> Result<Evaluated, WireError> {
            let e = Epoch::linear(epoch.time_s, &epoch.sats.items);
            self.evaluate(fde, cfg, ism, &e)
        }

        /// One pseudorange epoch (`AraimCommand::Ranges`): the core monitor
        /// linearises it at its Gauss-Newton solution with the snapshot
        /// configuration in force (`cfg`: its iteration limit, convergence
        /// and, as weights, its sigma model; ranges and residuals in f64,
        /// the steps in `AraimT`); the position in force is reported.
        pub(super) fn run_ranges(
            &mut self,
            fde: &mut FdeScratch,
            cfg: &Config,
            ism: &IsmFrame,
            epoch: &RangeEpoch,
        ) -> Result<Evaluated, WireError> {
            let e = Epoch::ranges(epoch.time_s, &epoch.sats.items, epoch.apriori_m);
            self.evaluate(fde, cfg, ism, &e)
        }

        /// The epoch, its wire result and, unless it is an `Alarm`, the
        /// delivered solution's q = r^T C_acc^-1 r and its dof for the
        /// model check (`None` when it has none), all read from the runs
        /// the epoch returns, which borrow `fde` until they are read.
        fn evaluate(
            &mut self,
            fde: &mut FdeScratch,
            cfg: &Config,
            ism: &IsmFrame,
            epoch: &Epoch<'_>,
        ) -> Result<Evaluated, WireError> {
            let araim_cfg = AraimConfig::from(ism.config);
            let p_const = Ism {
                p_const: ism.p_const,
            };
            let models = Entries(&ism.sats.items);
            let (verdict, runs) = self
                .0
                .epoch(fde, cfg, &araim_cfg, &p_const, &models, epoch, limits())
                .map_err(wire_error)?;
            let wire = WireAraimResult::from_verdict(runs, &verdict, &araim_cfg, epoch.time_s)?;
            let sample = if verdict.decision == raim_core::Decision::Alarm {
                None
            } else {
                runs.accuracy_sample().ok().map(|f| (f.q, f.dof))
            };
            Ok((wire, sample))
        }
    }

    fn wire_error(e: MonitorError) -> WireError {
        match e {
            MonitorError::Araim(e) => e.into(),
            MonitorError::Raim(e) => e.into(),
            MonitorError::NotInIsm { id, index } => WireError::Araim(AraimWireError::NotInIsm {
                id,
                index: u32::try_from(index).unwrap_or(u32::MAX),
            }),
        }
    }
}

#[cfg(all(test, feature = "araim"))]
mod tests {
    extern crate std;
    use super::*;
    use raim_core::measurement::MAX_SYSTEMS;
    use raim_core::{Decision, LinearObservation, SatId, System};
    use raim_proto::araim_msg::{AraimCommandRef, IsmFrameRef, WireAraimConfig, WireFde};
    use raim_proto::frame::{encode, FrameReceiver};
    use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
    use raim_proto::MAX_RESPONSE_FRAME;
    use std::vec::Vec;

    #[derive(Default)]
    struct Sink(Vec<u8>);
    impl embedded_io::ErrorType for Sink {
        type Error = core::convert::Infallible;
    }
    impl embedded_io::Write for Sink {
        fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
            self.0.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
    }

    /// Sends each command with consecutive sequence numbers; one response
    /// per command.
    struct Link {
        server: std::boxed::Box<Server>,
        seq: u32,
        /// What the platform heard (`Platform::on_epoch`), per request.
        heard: Heard,
        /// What the NMEA port carried for the last request.
        nmea: std::string::String,
    }

    /// A platform that records each verdict the server reports to it (the
    /// integrity-alarm output's input).
    #[derive(Default)]
    struct Heard(Vec<Option<Decision>>);
    impl crate::Platform for Heard {
        fn now(&mut self) -> u32 {
            0
        }
        fn on_epoch(&mut self, decision: Option<Decision>) {
            self.0.push(decision);
        }
    }

    impl Link {
        fn new() -> Self {
            let mut server = std::boxed::Box::new(Server::new());
            server.take_runtime_config(Config::default()).unwrap();
            Link {
                server,
                seq: 0,
                heard: Heard::default(),
                nmea: std::string::String::new(),
            }
        }
        fn ask(&mut self, command: CommandRef<'_>) -> Response {
            let mut scratch = std::vec![0u8; 8192];
            let mut out = std::vec![0u8; 8192];
            let bytes = encode(
                &RequestRef {
                    seq: self.seq,
                    command,
                },
                &mut scratch,
                &mut out,
            )
            .unwrap()
            .to_vec();
            self.seq += 1;
            let (mut link, mut nmea) = (Sink::default(), Sink::default());
            for &b in &bytes {
                self.server
                    .on_byte(b, &mut link, &mut nmea, &mut self.heard)
                    .unwrap();
            }
            self.nmea = std::string::String::from_utf8(nmea.0).unwrap();
            let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
            let resp: Vec<Response> = link
                .0
                .iter()
                .filter_map(|&b| {
                    rx.push(b)
                        .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
                })
                .collect();
            assert_eq!(resp.len(), 1, "{resp:?}");
            resp.into_iter().next().unwrap()
        }
        fn ism(&mut self, sats: &[IsmSat], p_const: [Option<f64>; MAX_SYSTEMS]) -> Response {
            self.ask(CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
                config: WireAraimConfig::default(),
                p_const,
                sats,
            })))
        }
        fn epoch(&mut self, sats: &[LinearObservation]) -> Response {
            self.ask(CommandRef::Araim(AraimCommandRef::Epoch {
                time_s: 1.0,
                sats,
            }))
        }
    }

    fn gal() -> [Option<f64>; MAX_SYSTEMS] {
        let mut p = [None; MAX_SYSTEMS];
        p[System::Gps.index()] = Some(1e-4);
        p[System::Galileo.index()] = Some(1e-4);
        p
    }

    /// G10 + E10 (the bench's sky spread): ISM entries (sigma_URA 0.75 m,
    /// sigma_URE 0.5 m, b_nom 0.5 m, P_sat 1e-5) and a linearised epoch
    /// with small residuals plus `fault_m` on satellite `faulty`.
    fn sky20(faulty: usize, fault_m: f64) -> (Vec<IsmSat>, Vec<LinearObservation>) {
        sky(20, faulty, fault_m)
    }

    /// [`sky20`] with `n` satellites.
    fn sky(n: usize, faulty: usize, fault_m: f64) -> (Vec<IsmSat>, Vec<LinearObservation>) {
        let mut ism = Vec::new();
        let mut obs = Vec::new();
        for i in 0..n {
            let system = if i % 2 == 0 {
                System::Gps
            } else {
                System::Galileo
            };
            let id = SatId::new(system, (i / 2) as u8 + 1);
            let az = (i as f64 * 137.5) % 360.0;
            let el = 10.0 + (i as f64 * 29.0) % 75.0;
            let r = 0.3 * (((i * 7919) % 11) as f64 / 11.0 - 0.5);
            let f = if i == faulty { fault_m } else { 0.0 };
            obs.push(LinearObservation::from_az_el(
                id,
                az.to_radians(),
                el.to_radians(),
                r + f,
            ));
            ism.push(IsmSat {
                id,
                sigma_ura_m: 0.75,
                sigma_ure_m: 0.5,
                b_nom_m: 0.5,
                p_sat: 1e-5,
            });
        }
        (ism, obs)
    }

    fn result(r: &Response) -> &raim_proto::araim_msg::WireAraimResult {
        match &r.body {
            ResponseBody::Araim(AraimAnswer::Result(w)) => w,
            other => panic!("{other:?}"),
        }
    }

    fn error(r: &Response) -> &WireError {
        match &r.body {
            ResponseBody::Error(e) => e,
            other => panic!("{other:?}"),
        }
    }

    /// The bad inputs, over the wire: each is a typed error with
    /// its values, the ISM in force stays, and every frame is answered and
    /// counted.
    ///
    /// Verifies: WIRE-TooManySatellites, WIRE-NonFinite, WIRE-NonPositiveSigma, WIRE-DuplicateSatellite, WIRE-Araim, WIRE-SigmaOutOfRange
    #[test]
    fn bad_input_is_typed_and_nothing_is_lost() {
        let (ism, obs) = sky20(usize::MAX, 0.0);
        let mut l = Link::new();
        assert!(matches!(
            l.ism(&ism, gal()).body,
            ResponseBody::Araim(AraimAnswer::IsmAccepted { satellites: 20 })
        ));
        let good = result(&l.epoch(&obs)).clone();
        let with = |f: &dyn Fn(&mut Vec<IsmSat>)| {
            let mut v = ism.clone();
            f(&mut v);
            v
        };
        let oor = |field: &str, index: u32, value: f64, min: f64, max: f64| {
            WireError::Araim(AraimWireError::OutOfRange {
                field: raim_proto::error::field_name(field),
                index,
                value,
                min,
                max,
            })
        };
        let mut gps_only = [None; MAX_SYSTEMS];
        gps_only[System::Gps.index()] = Some(1e-4);
        let mut nan_const = gal();
        nan_const[System::Galileo.index()] = Some(f64::NAN);
        let mut with_beidou = gal();
        with_beidou[System::Beidou.index()] = Some(1e-4);
        let forty: Vec<IsmSat> = (0..40u8)
            .map(|k| IsmSat {
                id: SatId::new(System::Gps, k + 1),
                ..ism[0]
            })
            .collect();
        use raim_core::config_bounds::araim::{B_NOM_M, P_SAT};
        let cases: Vec<(Vec<IsmSat>, [Option<f64>; MAX_SYSTEMS], WireError)> = std::vec![
            (
                with(&|v| v[3].sigma_ura_m = f64::NAN),
                gal(),
                WireError::NonFinite {
                    field: raim_proto::error::field_name("sigma_ura_m"),
                    index: 3,
                    value: f64::NAN
                }
            ),
            (
                with(&|v| v[4].p_sat = 0.0),
                gal(),
                oor("p_sat", 4, 0.0, P_SAT.min, P_SAT.max)
            ),
            (
                with(&|v| v[5].p_sat = 1.0),
                gal(),
                oor("p_sat", 5, 1.0, P_SAT.min, P_SAT.max)
            ),
            (
                with(&|v| v[6].p_sat = 1.5),
                gal(),
                oor("p_sat", 6, 1.5, P_SAT.min, P_SAT.max)
            ),
            (
                with(&|v| v[7].b_nom_m = -0.1),
                gal(),
                oor("b_nom_m", 7, -0.1, B_NOM_M.min, B_NOM_M.max)
            ),
            (
                ism.clone(),
                nan_const,
                WireError::NonFinite {
                    field: raim_proto::error::field_name("p_const"),
                    index: 1,
                    value: f64::NAN
                }
            ),
            (
                ism.clone(),
                with_beidou,
                WireError::Araim(AraimWireError::EmptyConstellation {
                    system: System::Beidou
                })
            ),
            (
                ism.clone(),
                gps_only,
                WireError::Araim(AraimWireError::MissingConstellationIsm {
                    system: System::Galileo,
                    index: 1
                })
            ),
            (
                forty,
                gal(),
                WireError::TooManySatellites {
                    have: 40,
                    capacity: 32
                }
            ),
            (
                with(&|v| v[9].id = v[2].id),
                gal(),
                WireError::DuplicateSatellite {
                    id: ism[2].id,
                    first: 2,
                    second: 9
                }
            ),
            // Issue 35: an ISM with no entry (it was `IsmAccepted { 0 }`),
            // with or without P_const; entries for PRN 0, 255, E37.
            (
                Vec::new(),
                gal(),
                WireError::Araim(AraimWireError::EmptyIsm)
            ),
            (
                Vec::new(),
                [None; MAX_SYSTEMS],
                WireError::Araim(AraimWireError::EmptyIsm)
            ),
            (
                with(&|v| v[4].id.prn = 0),
                gal(),
                WireError::PrnOutOfRange {
                    index: 4,
                    id: SatId::new(System::Gps, 0),
                    max: 32
                }
            ),
            (
                with(&|v| v[6].id.prn = 255),
                gal(),
                WireError::PrnOutOfRange {
                    index: 6,
                    id: SatId::new(System::Gps, 255),
                    max: 32
                }
            ),
            (
                with(&|v| v[7].id.prn = 37),
                gal(),
                WireError::PrnOutOfRange {
                    index: 7,
                    id: SatId::new(System::Galileo, 37),
                    max: 36
                }
            ),
        ];
        let mut errors = 0;
        for (k, (sats, p_const, want)) in cases.iter().enumerate() {
            let r = l.ism(sats, *p_const);
            // NaN != NaN: compare the encoded bytes.
            let (mut a, mut b) = ([0u8; 256], [0u8; 256]);
            assert_eq!(
                postcard::to_slice(error(&r), &mut a).unwrap(),
                postcard::to_slice(want, &mut b).unwrap(),
                "case {k}: {r:?}"
            );
            errors += 1;
        }
        // The configuration: NaN and out of range.
        let bad_cfg = WireAraimConfig {
            p_thres: 1e-6,
            ..WireAraimConfig::default()
        };
        let r = l.ask(CommandRef::Araim(AraimCommandRef::Ism(IsmFrameRef {
            config: bad_cfg,
            p_const: gal(),
            sats: &ism,
        })));
        assert!(
            matches!(error(&r), WireError::Araim(AraimWireError::OutOfRange { field, .. }) if field.as_str() == "p_thres"),
            "{r:?}"
        );
        errors += 1;
        // Epoch errors.
        let mut dup = obs.clone();
        dup[9].id = dup[2].id;
        let mut nan = obs.clone();
        nan[4].residual_m = f64::NAN;
        let mut zero_sigma = obs.clone();
        zero_sigma[1].sigma_m = Some(0.0);
        let mut stranger = obs.clone();
        stranger[8].id = SatId::new(System::Gps, 30);
        let forty_obs: Vec<LinearObservation> = (0..40).map(|k| obs[k % 20]).collect();
        let r = l.epoch(&dup);
        assert!(
            matches!(
                error(&r),
                WireError::DuplicateSatellite {
                    first: 2,
                    second: 9,
                    ..
                }
            ),
            "{r:?}"
        );
        let r = l.epoch(&nan);
        assert!(
            matches!(error(&r), WireError::NonFinite { field, index: 4, .. } if field.as_str() == "residual_m"),
            "{r:?}"
        );
        let mut nan_los = obs.clone();
        nan_los[5].los_enu[1] = f64::NAN;
        let r = l.epoch(&nan_los);
        assert!(
            matches!(error(&r), WireError::NonFinite { field, index: 5, .. } if field.as_str() == "g_n"),
            "{r:?}"
        );
        let r = l.epoch(&zero_sigma);
        assert_eq!(
            *error(&r),
            WireError::NonPositiveSigma {
                index: 1,
                sigma_m: 0.0
            }
        );
        // A host sigma outside the bound (1e30 m used to remove the
        // satellite silently).
        for v in [1e30, 1e-9] {
            let mut huge_sigma = obs.clone();
            huge_sigma[2].sigma_m = Some(v);
            let r = l.epoch(&huge_sigma);
            assert_eq!(
                *error(&r),
                WireError::SigmaOutOfRange {
                    index: 2,
                    sigma_m: v,
                    min_m: raim_core::config_bounds::SIGMA_M.min,
                    max_m: raim_core::config_bounds::SIGMA_M.max
                }
            );
        }
        let r = l.epoch(&stranger);
        assert_eq!(
            *error(&r),
            WireError::Araim(AraimWireError::NotInIsm {
                id: SatId::new(System::Gps, 30),
                index: 8
            })
        );
        let r = l.epoch(&forty_obs);
        assert_eq!(
            *error(&r),
            WireError::TooManySatellites {
                have: 40,
                capacity: 32
            }
        );
        // Issue 35: an epoch time outside the GPS era, and satellite
        // numbers outside their system's range (before the ISM lookup).
        let era = raim_core::measurement::EPOCH_TIME_S;
        for t in [1e300, -1e300, -1.0] {
            let r = l.ask(CommandRef::Araim(AraimCommandRef::Epoch {
                time_s: t,
                sats: &obs,
            }));
            assert_eq!(
                *error(&r),
                WireError::OutOfRange {
                    field: raim_proto::error::field_name("time_s"),
                    value: t,
                    min: era.min,
                    max: era.max
                }
            );
        }
        for prn in [0u8, 255] {
            let mut odd = obs.clone();
            odd[3].id.prn = prn;
            let r = l.epoch(&odd);
            assert_eq!(
                *error(&r),
                WireError::PrnOutOfRange {
                    index: 3,
                    id: odd[3].id,
                    max: odd[3].id.system.max_prn()
                }
            );
        }
        // The six refused epochs above, the two out-of-bound sigmas, and
        // the three times and two numbers of issue 35.
        errors += 6 + 2 + 3 + 2;
        // The good ISM stayed in force: the same answer as before.
        assert_eq!(*result(&l.epoch(&obs)), good);
        let ResponseBody::Status(st) = l.ask(CommandRef::Status).body else {
            panic!()
        };
        // ISM + good epoch + cases + config + 7 epochs + epoch + status.
        assert_eq!(st.frames, l.seq);
        assert_eq!(st.errors, errors);
    }

    /// A 100 m fault on one satellite of the 20-satellite sky is detected
    /// and that satellite (only) is excluded; the clean sky is Ok; the
    /// results match the core engine run directly on the same inputs.
    #[test]
    fn a_faulted_satellite_is_excluded() {
        let (ism, clean) = sky20(usize::MAX, 0.0);
        let mut l = Link::new();
        l.ism(&ism, gal());
        let ok = result(&l.epoch(&clean)).clone();
        assert_eq!(ok.decision, Decision::Ok);
        assert_eq!(ok.fde, WireFde::NoFault);
        assert_eq!(ok.all_in_view.modes, 22);
        let mut excluded = 0;
        for faulty in 0..20 {
            let (_, obs) = sky20(faulty, 100.0);
            let r = result(&l.epoch(&obs)).clone();
            assert!(!r.all_in_view.detection_passed, "sat {faulty}");
            match r.decision {
                Decision::Excluded | Decision::Unavailable
                    if matches!(r.fde, WireFde::Excluded { .. }) =>
                {
                    assert_eq!(r.excluded.as_slice(), &[obs[faulty].id], "sat {faulty}");
                    assert!(r.after_exclusion.is_some());
                    excluded += 1;
                }
                Decision::Alarm => assert!(r.excluded.is_empty()),
                other => panic!("sat {faulty}: {other:?} {r:?}"),
            }
        }
        assert!(excluded >= 10, "{excluded} of 20 excluded");
    }

    /// Every ARAIM epoch's verdict reaches the
    /// integrity-alarm output (`Platform::on_epoch`) exactly as it goes on
    /// the wire (an ARAIM alarm asserts the discrete), a refused epoch as
    /// `None` (an epoch error), and an ISM frame is no epoch.
    ///
    /// Verifies: SAFE-ALARM
    #[test]
    fn araim_verdicts_drive_the_alarm_output() {
        let (ism, clean) = sky20(usize::MAX, 0.0);
        let mut l = Link::new();
        assert!(matches!(
            error(&l.epoch(&clean)),
            WireError::Araim(AraimWireError::NoIsm)
        ));
        assert_eq!(l.heard.0, [None]);
        l.ism(&ism, gal());
        assert_eq!(l.heard.0.len(), 1, "an ISM frame is no epoch");
        let mut want = std::vec![None];
        for fault_m in [0.0, 100.0, 0.0] {
            let (_, obs) = sky20(3, fault_m);
            want.push(Some(result(&l.epoch(&obs)).decision));
        }
        let mut nan = clean.clone();
        nan[0].residual_m = f64::NAN;
        assert!(matches!(l.epoch(&nan).body, ResponseBody::Error(_)));
        want.push(None);
        assert_eq!(l.heard.0, want);
        // Not vacuous: a clean and a faulted verdict were both heard.
        assert_eq!(want.get(1), Some(&Some(Decision::Ok)));
        assert!(matches!(
            want.get(2),
            Some(Some(Decision::Excluded | Decision::Alarm))
        ));
    }

    /// Larger skies: 24 satellites need satellite pairs (327 modes), and
    /// a 100 m fault there is still excluded (FDE is attempted whenever the
    /// modes fit, `MAX_FDE_MODES`); 32 satellites at P_sat 1e-3 need more
    /// modes than the engine holds: unavailable, untested, never an alarm
    /// over zero modes.
    #[test]
    #[cfg_attr(
        feature = "ram-192k",
        ignore = "the wire's 600 fault modes; the ram-192k engine holds 48, and a larger sky is its typed ModeCapacity (qemu_stm32f4, qemu_watchdog_margin)"
    )]
    fn larger_skies_exclude_or_are_unavailable() {
        let mut l = Link::new();
        let (ism, obs) = sky(24, 0, 100.0);
        l.ism(&ism, gal());
        let r = result(&l.epoch(&obs)).clone();
        assert_eq!(r.all_in_view.modes, 327);
        assert!(r.all_in_view.monitored <= MAX_FDE_MODES);
        assert!(!r.all_in_view.detection_passed);
        assert!(matches!(r.fde, WireFde::Excluded { .. }), "{:?}", r.fde);
        assert_eq!(r.excluded.as_slice(), &[obs[0].id]);
        assert!(matches!(
            r.decision,
            Decision::Excluded | Decision::Unavailable
        ));
        let (mut ism, obs) = sky(32, usize::MAX, 0.0);
        for s in ism.iter_mut() {
            s.p_sat = 1e-3;
        }
        l.ism(&ism, gal());
        let r = result(&l.epoch(&obs)).clone();
        assert_eq!(r.decision, Decision::Unavailable);
        assert_eq!(r.fde, WireFde::NotTested);
        assert!(matches!(
            r.all_in_view.unavailable,
            Some(raim_proto::araim_msg::WireUnavailable::ModeCapacity { needed, capacity: 600 }) if needed > 600
        ));
    }

    /// The FDE work budget (`FDE_WORK_BUDGET`): a pair fault on 24
    /// satellites (327 modes, 326 monitored: 106 k candidate-modes) is
    /// searched through stage 2 and the pair excluded; the same on 32
    /// satellites (563 modes, 562 monitored: stage 2 would take 562
    /// candidates, the budget is 195) is an `Alarm`
    /// with `BudgetExceeded` on the wire and at the alarm output, never a
    /// pass; a single fault there is still excluded in stage 1 (34
    /// candidates). The core's unlimited FDE on the same 32-satellite
    /// epoch does find the pair: the budget, not the data, is the cause.
    #[test]
    #[cfg_attr(
        feature = "ram-192k",
        ignore = "the wire's 600 fault modes; the ram-192k engine holds 48, and a larger sky is its typed ModeCapacity (qemu_stm32f4, qemu_watchdog_margin)"
    )]
    fn fde_work_budget_bounds_the_search() {
        let mut l = Link::new();
        let pair = |n: usize| {
            let (ism, mut obs) = sky(n, 0, 100.0);
            obs[n - 1].residual_m -= 100.0;
            (ism, obs)
        };
        let (ism, obs) = pair(24);
        l.ism(&ism, gal());
        let r = result(&l.epoch(&obs)).clone();
        assert_eq!(r.all_in_view.modes, 327);
        let m = r.all_in_view.monitored;
        assert!(m * m <= FDE_WORK_BUDGET, "{m}");
        assert_eq!(r.excluded.as_slice(), &[obs[0].id, obs[23].id]);

        let (ism, obs) = pair(32);
        l.ism(&ism, gal());
        let r = result(&l.epoch(&obs)).clone();
        assert_eq!(r.all_in_view.modes, 563);
        // Every monitored mode is a candidate (stage 1's and stage 2's).
        let m = r.all_in_view.monitored;
        assert_eq!(
            r.fde,
            WireFde::BudgetExceeded {
                candidates: m,
                budget: FDE_WORK_BUDGET / m,
            }
        );
        assert_eq!(r.decision, Decision::Alarm);
        assert!(r.excluded.is_empty() && r.after_exclusion.is_none());
        assert_eq!(l.heard.0.last(), Some(&Some(Decision::Alarm)));
        let mut monitor = raim_proto::alert::AlertMonitor::new(10);
        monitor.on_epoch(0, Some(r.decision));
        assert_eq!(monitor.output(0), raim_proto::alert::AlarmOutput::Alarm);

        // The unlimited core FDE on the same epoch: the pair.
        let mut sats = Vec::new();
        for o in &obs {
            let g = o.los_enu.map(|v| -v);
            use raim_core::araim::error_model::{elevation_from_g, nominal_variance_m2};
            let nom = nominal_variance_m2::<f64>(elevation_from_g(&o.los_enu));
            sats.push(raim_core::araim::AraimSat::<f64> {
                id: o.id,
                g_enu: g,
                c_int_m2: 0.75 * 0.75 + nom,
                c_acc_m2: 0.5 * 0.5 + nom,
                b_nom_m: 0.5,
                p_sat: 1e-5,
                residual_m: o.residual_m,
            });
        }
        let core_ism = raim_core::araim::Ism { p_const: gal() };
        let cfg = AraimConfig::from(WireAraimConfig::default());
        let mut main = std::boxed::Box::new(raim_core::araim::Araim::<f64, 32, 600>::new());
        let mut scratch = std::boxed::Box::new(raim_core::araim::Araim::<f64, 32, 600>::new());
        main.process(&cfg, &core_ism, &sats).unwrap();
        let d = main.fde(&cfg, &core_ism, &sats, &mut scratch).unwrap();
        assert!(
            matches!(d, raim_core::araim::FdeDecision::Excluded { sats, .. } if sats == (1 | 1 << 31)),
            "{d:?}"
        );

        let (ism, obs) = sky(32, 0, 100.0);
        l.ism(&ism, gal());
        let r = result(&l.epoch(&obs)).clone();
        assert!(matches!(r.fde, WireFde::Excluded { .. }), "{:?}", r.fde);
        assert_eq!(r.excluded.as_slice(), &[obs[0].id]);
    }

    /// The pseudorange form of a linearised sky seen from `x` (ECEF, m):
    /// each satellite 2e7 m + 1e5 m x index away along its line of sight,
    /// with a clock of 1234.5 m (GPS) or 1240.25 m (others) and the
    /// residual added to the range.
    fn as_ranges(obs: &[LinearObservation], x: [f64; 3]) -> Vec<raim_core::RangeObservation> {
        let rot = raim_core::frames::enu_rotation(&raim_core::frames::ecef_to_geodetic(x));
        obs.iter()
            .enumerate()
            .map(|(i, o)| {
                let rho = 2.0e7 + 1.0e5 * i as f64;
                let u = raim_core::frames::unrotate(&rot, o.los_enu);
                let clock = if o.id.system == System::Gps {
                    1234.5
                } else {
                    1240.25
                };
                raim_core::RangeObservation {
                    id: o.id,
                    pseudorange_m: rho + clock + o.residual_m,
                    position_m: [x[0] + rho * u[0], x[1] + rho * u[1], x[2] + rho * u[2]],
                    sigma_m: None,
                }
            })
            .collect()
    }

    /// Every ARAIM epoch writes its NMEA sentences (an earlier epoch's fix
    /// never stays the last word on the port): a clean pseudorange epoch
    /// a valid fix; a faulted one its verdict, with the excluded satellite
    /// out of GSA and named in GBS; a refused epoch its no-fix sentences;
    /// an ISM frame none. Every sentence within 82 characters, CRLF.
    ///
    /// Verifies: SAFE-T9
    #[test]
    fn every_araim_epoch_writes_its_nmea() {
        let x = [3_582_105.0, 532_589.0, 5_232_755.0];
        let field = |nmea: &str, kind: &str, i: usize| -> std::string::String {
            let line = nmea.lines().find(|l| l.get(3..6) == Some(kind)).unwrap();
            line.split(['*', ',']).nth(i).unwrap().into()
        };
        let mut l = Link::new();
        let (ism, clean) = sky(20, usize::MAX, 0.0);
        l.ism(&ism, gal());
        assert!(l.nmea.is_empty(), "an ISM frame is no epoch");
        for (faulty, fault_m) in [(usize::MAX, 0.0), (5, 100.0)] {
            let (_, obs) = sky(20, faulty, fault_m);
            let ranges = as_ranges(&obs, x);
            let r = result(&l.ask(CommandRef::Araim(AraimCommandRef::Ranges {
                time_s: 1.7e9,
                apriori_m: None,
                sats: &ranges,
            })))
            .clone();
            let nmea = l.nmea.clone();
            for line in nmea.split_inclusive('\n') {
                assert!(line.ends_with("\r\n") && line.len() <= 82, "{line:?}");
            }
            let usable = matches!(r.decision, Decision::Ok | Decision::Excluded);
            assert_eq!(
                field(&nmea, "RMC", 2),
                if usable { "A" } else { "V" },
                "{nmea}"
            );
            assert!(!field(&nmea, "RMC", 3).is_empty(), "a position: {nmea}");
            let gsa_ids: Vec<std::string::String> = nmea
                .lines()
                .filter(|l| l.get(3..6) == Some("GSA"))
                .flat_map(|l| l.split(',').skip(3).take(12).map(Into::into))
                .filter(|f: &std::string::String| !f.is_empty())
                .collect();
            if faulty == usize::MAX {
                assert_eq!(r.decision, Decision::Ok);
                assert_eq!(gsa_ids.len(), 20, "{nmea}");
            } else {
                assert_eq!(r.excluded.as_slice(), &[obs[faulty].id]);
                assert_eq!(gsa_ids.len(), 19, "{nmea}");
                let svid = std::format!("{:02}", raim_proto::nmea::nmea_svid(obs[faulty].id));
                assert_eq!(field(&nmea, "GBS", 5), svid, "{nmea}");
            }
        }
        let mut nan = as_ranges(&clean, x);
        nan[2].position_m[1] = f64::NAN;
        l.ask(CommandRef::Araim(AraimCommandRef::Ranges {
            time_s: 1.7e9 + 1.0,
            apriori_m: None,
            sats: &nan,
        }));
        assert_eq!(field(&l.nmea, "RMC", 2), "V", "{}", l.nmea);
        assert!(field(&l.nmea, "RMC", 3).is_empty(), "{}", l.nmea);
    }

    /// A pseudorange epoch (protocol 8) against the same sky sent
    /// linearised at the truth: the device-side Gauss-Newton and
    /// linearisation change nothing that matters (same decision, FDE and
    /// excluded set; PLs within 1 mm: the lines of sight move by |x0 - x|
    /// / 2e7 rad), and the position is the truth within the residuals'
    /// effect (< 1 m; a linearised epoch has none). Bad input is typed.
    #[test]
    fn pseudorange_epoch_matches_the_linearised_one() {
        /// The PL agreement of the two forms (m).
        const PL_TOL_M: f64 = 1e-3;
        let x = [3_582_105.0, 532_589.0, 5_232_755.0];
        let to_ranges = |obs: &[LinearObservation]| as_ranges(obs, x);
        for (faulty, fault_m) in [(usize::MAX, 0.0), (5, 100.0)] {
            let (ism, obs) = sky(20, faulty, fault_m);
            let mut l = Link::new();
            l.ism(&ism, gal());
            let lin = l.epoch(&obs);
            let ranges = to_ranges(&obs);
            let rng = l.ask(CommandRef::Araim(AraimCommandRef::Ranges {
                time_s: 1.0,
                apriori_m: None,
                sats: &ranges,
            }));
            let (a, b) = (result(&lin), result(&rng));
            assert_eq!((a.decision, a.fde), (b.decision, b.fde), "{faulty}");
            assert_eq!(a.excluded, b.excluded);
            for (p, q) in [
                (a.in_force().vpl_exact_m, b.in_force().vpl_exact_m),
                (a.in_force().hpl_exact_m, b.in_force().hpl_exact_m),
            ] {
                assert!((p - q).abs() <= PL_TOL_M, "{p} {q}");
            }
            assert!(a.position_ecef_m.is_none());
            let p = b.position_ecef_m.unwrap();
            let d = ((p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2) + (p[2] - x[2]).powi(2)).sqrt();
            assert!(d < 1.0, "{d}");
            if faulty == 5 {
                assert_eq!(b.excluded.as_slice(), &[obs[5].id]);
            }
            let mut nan = ranges.clone();
            nan[2].position_m[1] = f64::NAN;
            let r = l.ask(CommandRef::Araim(AraimCommandRef::Ranges {
                time_s: 2.0,
                apriori_m: None,
                sats: &nan,
            }));
            assert!(
                matches!(
                    &r.body,
                    ResponseBody::Error(WireError::NonFinite { index: 2, .. })
                ),
                "{r:?}"
            );
        }
    }

    /// Issue 35 "Bounds that agree with the device's arithmetic": every
    /// accepted combination of the ISM's and the host sigma's floors (and
    /// a nominal value beside each floor: sigma_URA 0.3 / 0.75 m,
    /// sigma_URE 0.2 / 0.3 / 0.5 m within sigma_URA, host sigma none /
    /// 0.3 / 1 m, b_nom 0 / 0.5 m, P_sat 1e-6 / 1e-5, P_const 1e-8 / 1e-4),
    /// through the unit's engine in its precision (`AraimT`, f32): each
    /// ISM is accepted and its clean epoch gives service (`Ok`). At
    /// sigma_URE 0.2 m and a host sigma of 0.3 m, C_acc is 0.13 m² in f64
    /// and 0.1299999952 m² in f32, and was refused `c_acc_m2 OutOfRange`
    /// at every epoch.
    ///
    /// Verifies: SAFE-BOUNDS-PRECISION
    #[test]
    fn every_accepted_combination_of_the_floors_gives_service() {
        use raim_core::config_bounds::araim::{B_NOM_M, P_CONST, P_SAT, SIGMA_URA_M, SIGMA_URE_M};
        use raim_core::config_bounds::SIGMA_M;
        let (base, clean) = sky20(usize::MAX, 0.0);
        let mut runs = 0;
        for ura in [SIGMA_URA_M.min, 0.75] {
            for ure in [SIGMA_URE_M.min, 0.3, 0.5]
                .into_iter()
                .filter(|u| *u <= ura)
            {
                for sigma in [None, Some(SIGMA_M.min), Some(1.0)] {
                    for b_nom in [B_NOM_M.min, 0.5] {
                        for p_sat in [P_SAT.min, 1e-5] {
                            for p_c in [P_CONST.min, 1e-4] {
                                let ism: Vec<IsmSat> = base
                                    .iter()
                                    .map(|e| IsmSat {
                                        sigma_ura_m: ura,
                                        sigma_ure_m: ure,
                                        b_nom_m: b_nom,
                                        p_sat,
                                        ..*e
                                    })
                                    .collect();
                                let obs: Vec<LinearObservation> = clean
                                    .iter()
                                    .map(|o| LinearObservation {
                                        sigma_m: sigma,
                                        ..*o
                                    })
                                    .collect();
                                let mut p = [None; MAX_SYSTEMS];
                                p[System::Gps.index()] = Some(p_c);
                                p[System::Galileo.index()] = Some(p_c);
                                let mut l = Link::new();
                                let what = (ura, ure, sigma, b_nom, p_sat, p_c);
                                assert!(
                                    matches!(
                                        l.ism(&ism, p).body,
                                        ResponseBody::Araim(AraimAnswer::IsmAccepted {
                                            satellites: 20
                                        })
                                    ),
                                    "{what:?}"
                                );
                                let r = l.epoch(&obs);
                                let ResponseBody::Araim(AraimAnswer::Result(w)) = &r.body else {
                                    panic!("{what:?}: {r:?}")
                                };
                                assert_eq!(w.decision, Decision::Ok, "{what:?}: {w:?}");
                                runs += 1;
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(runs, 5 * 3 * 2 * 2 * 2);
    }

    /// A stream epoch (the unit's own, formed from a receiver's RTCM) with
    /// an ISM in force runs ARAIM through the same path as the host's
    /// `Araim(Ranges)` epoch of the same satellites: the same answer body,
    /// sent unasked (`seq: None`), the same NMEA sentences and the same
    /// verdict at the alarm output, clean and with a 100 m fault (the
    /// satellite excluded); a satellite without an ISM entry is that
    /// path's typed refusal (`NotInIsm`), sent unasked, heard as a refused
    /// epoch. With no ISM in force the stream epoch is a snapshot epoch
    /// (a `Result`, not an ARAIM answer).
    ///
    /// Verifies: RX-ARAIM
    #[cfg(feature = "rtcm")]
    #[test]
    fn a_stream_epoch_with_an_ism_runs_the_araim_path() {
        let x = [3_582_105.0, 532_589.0, 5_232_755.0];
        let time_gps_s = 1.3e9;
        let time_s = raim_nav::time::unix_utc_s(time_gps_s);
        /// The unit's answer and NMEA for a stream epoch of `sats`.
        fn stream_epoch(
            l: &mut Link,
            time_gps_s: f64,
            sats: &[raim_core::RangeObservation],
        ) -> (Response, std::string::String) {
            let f = l.server.stream.formed_mut();
            f.time_gps_s = time_gps_s;
            f.reference_m = None;
            f.sats.clear();
            for s in sats {
                f.sats.push(*s).unwrap();
            }
            let (mut link, mut nmea) = (Sink::default(), Sink::default());
            l.server
                .on_stream_epoch(Ok(()), &mut link, &mut nmea, &mut l.heard)
                .unwrap();
            let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
            let resp: Vec<Response> = link
                .0
                .iter()
                .filter_map(|&b| {
                    rx.push(b)
                        .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
                })
                .collect();
            assert_eq!(resp.len(), 1, "{resp:?}");
            let nmea = std::string::String::from_utf8(nmea.0).unwrap();
            (resp.into_iter().next().unwrap(), nmea)
        }

        let mut l = Link::new();
        let (ism, _) = sky(20, usize::MAX, 0.0);
        l.ism(&ism, gal());
        for (faulty, fault_m) in [(usize::MAX, 0.0), (5, 100.0)] {
            let (_, obs) = sky(20, faulty, fault_m);
            let ranges = as_ranges(&obs, x);
            let asked = l.ask(CommandRef::Araim(AraimCommandRef::Ranges {
                time_s,
                apriori_m: None,
                sats: &ranges,
            }));
            let (asked_nmea, asked_heard) = (l.nmea.clone(), *l.heard.0.last().unwrap());
            let (unasked, nmea) = stream_epoch(&mut l, time_gps_s, &ranges);
            assert_eq!(unasked.seq, None);
            assert_eq!(unasked.body, asked.body, "{faulty}");
            assert_eq!(nmea, asked_nmea);
            assert!(nmea.contains("RMC"), "{nmea}");
            assert_eq!(l.heard.0.last(), Some(&asked_heard));
            let r = result(&unasked);
            if faulty == usize::MAX {
                assert_eq!(r.decision, Decision::Ok);
            } else {
                assert_eq!(r.decision, Decision::Excluded);
                assert_eq!(r.excluded.as_slice(), &[obs[faulty].id]);
            }
        }

        // A satellite the ISM does not hold: the ARAIM path's refusal.
        let (_, obs) = sky(21, usize::MAX, 0.0);
        let ranges = as_ranges(&obs, x);
        let asked = l.ask(CommandRef::Araim(AraimCommandRef::Ranges {
            time_s,
            apriori_m: None,
            sats: &ranges,
        }));
        let (unasked, nmea) = stream_epoch(&mut l, time_gps_s, &ranges);
        assert_eq!(unasked.seq, None);
        assert_eq!(unasked.body, asked.body);
        assert!(
            matches!(
                error(&unasked),
                WireError::Araim(AraimWireError::NotInIsm { id, index: 20 }) if *id == obs[20].id
            ),
            "{unasked:?}"
        );
        assert_eq!(l.heard.0.last(), Some(&None));
        assert!(nmea.contains("RMC"), "the no-fix sentences: {nmea}");

        // No ISM in force: the snapshot monitor.
        let mut l = Link::new();
        let (_, obs) = sky(20, usize::MAX, 0.0);
        let (unasked, _) = stream_epoch(&mut l, time_gps_s, &as_ranges(&obs, x));
        assert_eq!(unasked.seq, None);
        assert!(
            matches!(unasked.body, ResponseBody::Result(_)),
            "{unasked:?}"
        );
    }

    /// The server's ARAIM answers are the core monitor's own epochs in wire
    /// form (`raim_core::araim::Monitor`, which keeps its FDE scratch
    /// across epochs), every bit, whether the server's FDE scratch is the
    /// ARAIM state's own or, on the STM32F4 stream build (`ram-192k` and
    /// `rtcm`: `cargo test -p raim-server --features ram-192k,rtcm`), a
    /// part of the shared per-epoch room, taken new from a constant after
    /// the answer's buffers and the forming scratch had the room: a clean
    /// sky, single faults excluded, and the epochs in between.
    ///
    /// Verifies: ARAIM-FDE-SCRATCH
    #[test]
    fn araim_answers_are_the_core_monitors_wherever_the_fde_scratch_is() {
        use raim_core::araim::{FdeLimits, Monitor, SatIsm};
        let (ism, _) = sky20(usize::MAX, 0.0);
        let mut l = Link::new();
        l.ism(&ism, gal());
        let cfg = AraimConfig::from(WireAraimConfig::default());
        let p_const = Ism { p_const: gal() };
        let entries: Vec<SatIsm> = ism
            .iter()
            .map(|s| SatIsm {
                id: s.id,
                sigma_ura_m: s.sigma_ura_m,
                sigma_ure_m: s.sigma_ure_m,
                b_nom_m: s.b_nom_m,
                p_sat: s.p_sat,
            })
            .collect();
        let limits = FdeLimits {
            max_modes: MAX_FDE_MODES as usize,
            work_candidate_modes: FDE_WORK_BUDGET as usize,
        };
        let mut core =
            std::boxed::Box::new(Monitor::<engine::AraimT, ARAIM_SATS, MAX_MODES>::new());
        let mut excluded = 0;
        for faulty in [usize::MAX, 0, 3, usize::MAX, 7, 12, 12] {
            // The forming scratch takes the room between epochs, as a
            // stream's frames do.
            #[cfg(feature = "rtcm")]
            let _ = l.server.shared.forming();
            let (_, obs) = sky20(faulty, 100.0);
            let verdict = core
                .linear(&cfg, &p_const, &entries[..], &obs, limits)
                .unwrap();
            let want = WireAraimResult::from_verdict(core.runs(), &verdict, &cfg, 1.0).unwrap();
            let got = result(&l.epoch(&obs)).clone();
            assert_eq!(got, want, "faulty {faulty}");
            excluded += usize::from(matches!(got.fde, WireFde::Excluded { .. }));
        }
        assert!(excluded >= 3, "{excluded}");
    }
}
