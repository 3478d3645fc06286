//! The particle-filter side of the protocol loop (a child module
//! of `server`, so that `Server`'s own file only dispatches to it).
//!
//! The PF state (main filter + one auxiliary filter per satellite, each of
//! up to [`PF_MAX_PARTICLES`] particles of `f32` state) is up to ~160 KiB
//! per engine: far too large for the stack or for the `Server` itself (the
//! firmware builds the `Server` by value). Each engine lives in storage the
//! owner provides for good ([`PfEngines`], [`Server::attach_pf`]): the
//! firmware's zero-initialised statics, leaked boxes on the host. The
//! server never moves or builds an engine: a `PfConfigure` selects the
//! engine of the requested filter and particle count and restarts it in
//! place (`PfRaim::restart`), so no engine ever passes through the stack.
//! (An enum of engines sharing one storage needs a new value, built on the
//! stack, at every change of filter: measured 318 KiB of stack for a
//! 300-particle engine, so it was dropped.)

use raim_core::pf::PfError;
use raim_core::RangeObservation;

use raim_proto::error::{field_name, WireError};
use raim_proto::message::ResponseBody;
#[cfg(feature = "pf")]
use raim_proto::pf_msg::{PfKind, PF_MAX_PARTICLES};
use raim_proto::pf_msg::{WirePfConfig, WirePfResult};

use super::Server;

#[cfg(feature = "pf")]
mod engine {
    use raim_core::pf::{Ekf, GaPf, PfRaim, SirPf};

    use raim_proto::pf_msg::{PF_PARTICLE_COUNTS, PF_SATS};

    /// The particle state's precision on host and device: the device's
    /// (docs/PF.md "Memory": 300 particles x 12 satellites fit 192 KiB only
    /// in f32).
    pub type PfT = raim_proto::DevicePrecision;

    const _: () = assert!(PF_PARTICLE_COUNTS[0] == 100 && PF_PARTICLE_COUNTS[1] == 300);

    /// The EKF baseline in seed 004's structure.
    pub type EkfEngine = PfRaim<PfT, Ekf<PfT>, PF_SATS>;
    /// The SIR particle filter, 100 particles.
    pub type Pf100Engine = PfRaim<PfT, SirPf<PfT, 100>, PF_SATS>;
    /// The SIR particle filter, 300 particles.
    pub type Pf300Engine = PfRaim<PfT, SirPf<PfT, 300>, PF_SATS>;
    /// The GA-PF, 100 particles.
    pub type Ga100Engine = PfRaim<PfT, GaPf<PfT, 100>, PF_SATS>;
    /// The GA-PF, 300 particles.
    pub type Ga300Engine = PfRaim<PfT, GaPf<PfT, 300>, PF_SATS>;

    /// The engines a build provides, each in its owner's static storage;
    /// `None` for an engine the build leaves out (its `PfConfigure` is
    /// answered `PfParticles` or `PfUnavailable`).
    #[derive(Default)]
    pub struct PfEngines {
        /// The EKF engine, if the build has one.
        pub ekf: Option<&'static mut EkfEngine>,
        /// The SIR PF at 100 particles, if the build has one.
        pub pf100: Option<&'static mut Pf100Engine>,
        /// The SIR PF at 300 particles, if the build has one.
        pub pf300: Option<&'static mut Pf300Engine>,
        /// The GA-PF at 100 particles, if the build has one.
        pub ga100: Option<&'static mut Ga100Engine>,
        /// The GA-PF at 300 particles, if the build has one.
        pub ga300: Option<&'static mut Ga300Engine>,
    }

    impl PfEngines {
        /// No engine attached.
        pub const NONE: PfEngines = PfEngines {
            ekf: None,
            pf100: None,
            pf300: None,
            ga100: None,
            ga300: None,
        };
    }
}

#[cfg(not(feature = "pf"))]
mod engine {
    /// Without the `pf` feature a build has no engine.
    #[derive(Default)]
    pub struct PfEngines {}

    impl PfEngines {
        /// No engine (the only value without the `pf` feature).
        pub const NONE: PfEngines = PfEngines {};
    }
}

pub use engine::*;

/// The PF configuration in force and the engines.
pub struct PfUnit {
    config: Option<WirePfConfig>,
    engines: PfEngines,
}

impl PfUnit {
    /// No configuration, no engine.
    pub const EMPTY: PfUnit = PfUnit {
        config: None,
        engines: PfEngines::NONE,
    };

    /// The PF configuration in force.
    pub fn config(&self) -> Option<&WirePfConfig> {
        self.config.as_ref()
    }

    /// Checks `c` and makes it the configuration in force, restarting the
    /// selected engine in place; on error nothing changes.
    #[cfg(feature = "pf")]
    pub(crate) fn configure(&mut self, c: WirePfConfig) -> Result<(), WireError> {
        check(&c)?;
        self.restart(&c)?;
        self.config = Some(c);
        Ok(())
    }

    /// Without the `pf` feature no engine exists to configure: every
    /// `PfConfigure` is answered `PfUnavailable`, valid or not (the
    /// configuration checks are not linked, to keep the snapshot build's
    /// flash small), and nothing changes.
    #[cfg(not(feature = "pf"))]
    pub(crate) fn configure(&mut self, _c: WirePfConfig) -> Result<(), WireError> {
        Err(WireError::PfUnavailable)
    }

    #[cfg(feature = "pf")]
    fn restart(&mut self, c: &WirePfConfig) -> Result<(), WireError> {
        let e = &mut self.engines;
        let seed = c.seed;
        let done = match (c.kind, c.particles) {
            (PfKind::Ekf, _) => e.ekf.as_mut().map(|m| m.restart(seed)),
            (PfKind::Pf, 100) => e.pf100.as_mut().map(|m| m.restart(seed)),
            (PfKind::Pf, 300) => e.pf300.as_mut().map(|m| m.restart(seed)),
            (PfKind::Gapf, 100) => e.ga100.as_mut().map(|m| m.restart(seed)),
            (PfKind::Gapf, 300) => e.ga300.as_mut().map(|m| m.restart(seed)),
            _ => None,
        };
        done.ok_or(WireError::PfUnavailable)
    }

    /// One epoch through the configured filter.
    fn process(
        &mut self,
        time_s: f64,
        sats: &[RangeObservation],
    ) -> Result<WirePfResult, WireError> {
        let Some(c) = self.config else {
            return Err(WireError::PfNotConfigured);
        };
        #[cfg(feature = "pf")]
        {
            let cfg = &c.config;
            let e = &mut self.engines;
            let out = match (c.kind, c.particles) {
                (PfKind::Ekf, _) => e.ekf.as_mut().map(|m| m.process(cfg, time_s, sats)),
                (PfKind::Pf, 100) => e.pf100.as_mut().map(|m| m.process(cfg, time_s, sats)),
                (PfKind::Pf, 300) => e.pf300.as_mut().map(|m| m.process(cfg, time_s, sats)),
                (PfKind::Gapf, 100) => e.ga100.as_mut().map(|m| m.process(cfg, time_s, sats)),
                (PfKind::Gapf, 300) => e.ga300.as_mut().map(|m| m.process(cfg, time_s, sats)),
                _ => None,
            };
            match out {
                None => Err(WireError::PfUnavailable),
                Some(r) => r
                    .map(|o| WirePfResult::from_output(&o))
                    .map_err(|e| map_error(e, sats)),
            }
        }
        #[cfg(not(feature = "pf"))]
        {
            let _ = (c, time_s, sats, &self.engines);
            Err(WireError::PfUnavailable)
        }
    }
}

/// Every check of a PF configuration: the engine exists in this build, the
/// particle count is compiled in, and `PfConfig::validate`.
pub(crate) fn check(c: &WirePfConfig) -> Result<(), WireError> {
    #[cfg(feature = "pf")]
    {
        check_particles(c)?;
        c.config.validate().map_err(|e| map_error(e, &[]))?;
        // The threshold comes from the calibrated table at the configured
        // Pfa, inside the detectability ceiling: a configuration the table
        // does not cover is refused here.
        let kind = match c.kind {
            PfKind::Ekf => "ekf",
            PfKind::Pf => "pf",
            PfKind::Gapf => "gapf",
        };
        let threshold = raim_core::pf::threshold::lookup(kind, c.particles as usize, &c.config)
            .map_err(|e| map_error(e, &[]))?;
        raim_core::config_bounds::pf::threshold_bound(&c.config.likelihood, c.config.window)
            .check_pf(threshold)
            .map_err(|e| map_error(e, &[]))
    }
    #[cfg(not(feature = "pf"))]
    {
        let _ = c;
        Err(WireError::PfUnavailable)
    }
}

/// The particle count must be compiled in (0 for the EKF).
#[cfg(feature = "pf")]
fn check_particles(c: &WirePfConfig) -> Result<(), WireError> {
    let ok = match c.kind {
        PfKind::Ekf => c.particles == 0,
        PfKind::Pf | PfKind::Gapf => raim_proto::pf_msg::PF_PARTICLE_COUNTS.contains(&c.particles),
    };
    if ok {
        Ok(())
    } else {
        Err(WireError::PfParticles {
            requested: c.particles,
            max: PF_MAX_PARTICLES,
        })
    }
}

fn u32_of(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

/// A `PfError` on the wire, with the offending values; a duplicate
/// satellite gets the indices of its two occurrences in `sats`.
pub fn map_error(e: PfError, sats: &[RangeObservation]) -> WireError {
    match e {
        PfError::NotFinite {
            field,
            index,
            value,
        } => WireError::NonFinite {
            field: field_name(field),
            index: u32_of(index),
            value,
        },
        PfError::DuplicateSatellite { id } => {
            let mut at = sats.iter().enumerate().filter(|(_, o)| o.id == id);
            let first = at.next().map_or(0, |(i, _)| i);
            let second = at.next().map_or(0, |(i, _)| i);
            WireError::DuplicateSatellite {
                id,
                first: u32_of(first),
                second: u32_of(second),
            }
        }
        PfError::TooFewSatellites { have, need } => WireError::TooFewSatellites {
            have: u32_of(have),
            need: u32_of(need),
        },
        PfError::Capacity { have, max, .. } => WireError::TooManySatellites {
            have: u32_of(have),
            capacity: u32_of(max),
        },
        PfError::InvalidConfig { field, value } => WireError::PfInvalidConfig {
            field: field_name(field),
            value,
        },
        PfError::NotCalibrated { field, value } => WireError::PfInvalidConfig {
            field: field_name(field),
            value,
        },
        PfError::TimeNotIncreasing { previous_s, now_s } => {
            WireError::TimeNotIncreasing { previous_s, now_s }
        }
        PfError::NoInitialFix { iterations, step_m } => {
            WireError::NoConvergence { iterations, step_m }
        }
        PfError::OutOfRange {
            field,
            value,
            min,
            max,
        } => WireError::OutOfRange {
            field: field_name(field),
            value,
            min,
            max,
        },
        PfError::SigmaOutOfRange {
            index,
            sigma_m,
            min_m,
            max_m,
        } => WireError::SigmaOutOfRange {
            index: u32_of(index),
            sigma_m,
            min_m,
            max_m,
        },
        PfError::PrnOutOfRange { index, id, max } => WireError::PrnOutOfRange {
            index: u32_of(index),
            id,
            max,
        },
    }
}

/// The integrity-alarm output's reading of a PF epoch (the discrete
/// output and the NMEA status; docs/SAFETY.md "Integrity-alarm discrete
/// output", docs/PF.md "No protection level"). The particle filter gives
/// a position and a fault test, but no protection level: nothing bounds
/// its position error at an integrity risk, so a PF epoch never claims
/// integrity on its own (issue 35). An alarm this epoch is `Alarm` (also
/// when the isolated satellite was excluded in the same epoch); every
/// other epoch is `Unavailable`, its position kept on the wire and in the
/// NMEA sentences as information, not as a valid fix. A PF epoch therefore
/// never clears the alarm output: integrity comes from the monitors that
/// bound their error (snapshot, ARAIM).
pub(crate) fn pf_decision(r: &WirePfResult) -> raim_core::Decision {
    use raim_core::Decision;
    if r.position_ecef_m.is_some() && r.alarm {
        Decision::Alarm
    } else {
        Decision::Unavailable
    }
}

impl Server {
    /// Lends the server the PF engines for good: from then on
    /// it answers `PfConfigure` and `PfRanges` for them; without them they
    /// are answered `PfUnavailable`. Any PF configuration is dropped.
    pub fn attach_pf(&mut self, engines: PfEngines) {
        self.pf = PfUnit {
            config: None,
            engines,
        };
        self.config_id.fingerprint = self.fingerprint();
    }

    /// The PF configuration in force, if any.
    pub fn pf_config(&self) -> Option<&WirePfConfig> {
        self.pf.config()
    }

    /// `PfRanges`: one epoch, timed like a snapshot epoch.
    pub(super) fn pf_epoch<P: super::Platform>(
        &mut self,
        time_s: f64,
        sats: &[RangeObservation],
        platform: &mut P,
    ) -> ResponseBody {
        self.status.epochs = self.status.epochs.wrapping_add(1);
        let watch = super::Stopwatch::start(platform);
        let r = self.pf.process(time_s, sats);
        let lap = watch.stop(platform);
        self.status.last_epoch_ticks = lap.ticks;
        lap.record(&mut self.status, raim_proto::EpochKind::Pf);
        platform.on_epoch(r.as_ref().ok().map(pf_decision));
        match r {
            Ok(r) => ResponseBody::PfResult(r),
            Err(e) => ResponseBody::Error(e),
        }
    }
}

#[cfg(all(test, feature = "pf"))]
mod tests {
    extern crate std;
    use super::*;
    use crate::NoPlatform;
    use raim_core::pf::{rng, GaPf, PfConfig, PfRaim};
    use raim_core::{Config, SatId, System};
    use raim_proto::frame::{encode, FrameReceiver};
    use raim_proto::message::{CommandRef, RequestRef, Response};
    use raim_proto::MAX_RESPONSE_FRAME;
    use std::boxed::Box;
    use std::vec::Vec;

    const RECEIVER_M: [f64; 3] = [-3_962_108.673, 3_381_309.574, 3_668_678.638];
    const SIGMA_M: f64 = 3.0;

    /// `n` satellites at GPS orbit radius spread over the receiver's sky;
    /// pseudorange = range + 100 m clock + 0.5 m/s drift + N(0, 3 m) +
    /// `fault` (index, m).
    fn epoch(
        n: usize,
        k: usize,
        noise: &mut rng::PfRng,
        fault: Option<(usize, f64)>,
    ) -> Vec<RangeObservation> {
        let r = libm::sqrt(RECEIVER_M.iter().map(|v| v * v).sum::<f64>());
        let up = RECEIVER_M.map(|v| v / r);
        let east = {
            let e = [-up[1], up[0], 0.0];
            let ne = libm::sqrt(e[0] * e[0] + e[1] * e[1]);
            e.map(|v| v / ne)
        };
        let north = [
            up[1] * east[2] - up[2] * east[1],
            up[2] * east[0] - up[0] * east[2],
            up[0] * east[1] - up[1] * east[0],
        ];
        (0..n)
            .map(|i| {
                let az = (i as f64 * 137.5).to_radians();
                let el = (15.0 + (i as f64 * 23.0) % 70.0).to_radians();
                let los: [f64; 3] = core::array::from_fn(|j| {
                    libm::cos(el) * (libm::sin(az) * east[j] + libm::cos(az) * north[j])
                        + libm::sin(el) * up[j]
                });
                // Range to a sphere of radius 26,560 km along the line of sight.
                let b: f64 = (0..3).map(|j| RECEIVER_M[j] * los[j]).sum();
                let c = r * r - 26_560_000.0f64 * 26_560_000.0;
                let range = -b + libm::sqrt(b * b - c);
                let sat = core::array::from_fn(|j| RECEIVER_M[j] + range * los[j]);
                let bias = fault.filter(|f| f.0 == i).map_or(0.0, |f| f.1);
                RangeObservation {
                    id: SatId::new(System::Gps, i as u8 + 1),
                    pseudorange_m: range
                        + 100.0
                        + 0.5 * k as f64
                        + SIGMA_M * rng::normal(noise)
                        + bias,
                    position_m: sat,
                    sigma_m: Some(SIGMA_M),
                }
            })
            .collect()
    }

    fn pf_config(particles: u32) -> WirePfConfig {
        WirePfConfig {
            kind: PfKind::Gapf,
            particles,
            seed: 11,
            config: PfConfig {
                sigma_m: SIGMA_M,
                mutation_m: 0.5,
                window: 8,
                pfa: 1e-3,
                ..PfConfig::default()
            },
        }
    }

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

    /// Sends each command as a frame (sequence numbers from `seq0`) and
    /// returns the answers.
    fn exchange(server: &mut Server, seq0: u32, commands: &[CommandRef<'_>]) -> Vec<Response> {
        let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
        for (i, c) in commands.iter().enumerate() {
            let req = RequestRef {
                seq: seq0 + i as u32,
                command: *c,
            };
            let mut scratch = [0u8; 4096];
            let mut out = [0u8; 4096];
            for &mut b in encode(&req, &mut scratch, &mut out).unwrap() {
                server
                    .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
                    .unwrap();
            }
        }
        // Every PF epoch, answered or refused, writes its sentences (one
        // RMC each); no other request writes any.
        let epochs = commands
            .iter()
            .filter(|c| matches!(c, CommandRef::PfRanges { .. }))
            .count();
        let nmea = std::string::String::from_utf8(nmea.0).unwrap();
        let rmc = nmea.lines().filter(|l| l.get(3..6) == Some("RMC")).count();
        assert_eq!(rmc, epochs, "{nmea}");
        let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
        link.0
            .iter()
            .filter_map(|&b| {
                rx.push(b)
                    .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
            })
            .collect()
    }

    fn pf_server() -> Server {
        fn leak<T>(t: T) -> Option<&'static mut T> {
            Some(Box::leak(Box::new(t)))
        }
        let mut s = Server::new();
        s.take_runtime_config(Config::default()).unwrap();
        s.attach_pf(PfEngines {
            ekf: leak(PfRaim::new(0)),
            pf100: leak(PfRaim::new(0)),
            pf300: leak(PfRaim::new(0)),
            ga100: leak(PfRaim::new(0)),
            ga300: leak(PfRaim::new(0)),
        });
        s
    }

    fn ranges<'a>(time_s: f64, sats: &'a [RangeObservation]) -> CommandRef<'a> {
        CommandRef::PfRanges {
            time_s,
            apriori_m: None,
            sats,
        }
    }

    /// The GA-PF through the wire answers exactly what the core's
    /// `PfRaim<DevicePrecision, GaPf<DevicePrecision, 100>, 12>` answers for the same seed and
    /// epochs, and on a 60 m step on G04 from epoch 6 it alarms, isolates
    /// and excludes G04 with no alarm before.
    #[test]
    fn gapf_over_the_wire_equals_the_core_and_isolates_a_step() {
        crate::tests::on_big_stack(gapf_over_the_wire_equals_the_core_and_isolates_a_step_body)
    }

    fn gapf_over_the_wire_equals_the_core_and_isolates_a_step_body() {
        let mut server = pf_server();
        let cfg = pf_config(100);
        let mut noise = rng::seeded(3);
        let epochs: Vec<Vec<RangeObservation>> = (0..10)
            .map(|k| epoch(8, k, &mut noise, (k >= 6).then_some((3, 60.0))))
            .collect();
        let mut cmds = std::vec![CommandRef::PfConfigure(&cfg)];
        cmds.extend(epochs.iter().enumerate().map(|(k, e)| ranges(k as f64, e)));
        let resp = exchange(&mut server, 0, &cmds);
        assert_eq!(resp[0].body, ResponseBody::Configured);
        let mut core = Box::new(PfRaim::<
            raim_proto::DevicePrecision,
            GaPf<raim_proto::DevicePrecision, 100>,
            12,
        >::new(cfg.seed));
        let mut first_alarm = None;
        for (k, (r, e)) in resp[1..].iter().zip(&epochs).enumerate() {
            let want = core.process(&cfg.config, k as f64, e).unwrap();
            let ResponseBody::PfResult(got) = &r.body else {
                panic!("epoch {k}: {r:?}")
            };
            assert_eq!(*got, WirePfResult::from_output(&want), "epoch {k}");
            if got.alarm && first_alarm.is_none() {
                first_alarm = Some((k, got.isolated, got.excluded));
            }
        }
        let g4 = Some(SatId::new(System::Gps, 4));
        let (k, isolated, excluded) = first_alarm.unwrap();
        assert!((6..=8).contains(&k), "alarm at {k}");
        assert_eq!((isolated, excluded), (g4, g4));
    }

    /// Bad input over the wire: typed errors, never a position; the filter
    /// is untouched by a refused epoch; a satellite leaving view mid-window
    /// drops its auxiliary filter; a collapsed filter is reinitialised and
    /// reported without a position.
    ///
    /// Verifies: WIRE-PfNotConfigured, WIRE-PfParticles, WIRE-PfInvalidConfig, WIRE-TimeNotIncreasing
    #[test]
    fn bad_pf_input_gets_typed_errors() {
        crate::tests::on_big_stack(bad_pf_input_gets_typed_errors_body)
    }

    fn bad_pf_input_gets_typed_errors_body() {
        let mut server = pf_server();
        let mut noise = rng::seeded(5);
        let good: Vec<Vec<RangeObservation>> =
            (0..8).map(|k| epoch(8, k, &mut noise, None)).collect();
        let four = epoch(4, 1, &mut noise, None);
        let mut nan = good[1].clone();
        nan[2].pseudorange_m = f64::NAN;
        let mut dup = good[1].clone();
        dup[5].id = dup[1].id;
        let many = epoch(13, 1, &mut noise, None);
        let mut zero_sigma = good[1].clone();
        zero_sigma[0].sigma_m = Some(0.0);
        let leaving = good[2][1..].to_vec(); // G01 leaves view
        let mut jump = good[4].clone();
        for (i, o) in jump.iter_mut().enumerate() {
            o.pseudorange_m += if i % 2 == 0 { 1e5 } else { -1e5 };
        }
        let c100 = pf_config(100);
        let c400 = pf_config(400);
        let c200 = pf_config(200);
        let ekf_with_particles = WirePfConfig {
            kind: PfKind::Ekf,
            ..c100
        };
        let bad_window = WirePfConfig {
            config: PfConfig {
                window: 0,
                ..c100.config
            },
            ..c100
        };
        let cmds = [
            ranges(0.0, &good[0]),                        // 0 not configured
            CommandRef::PfConfigure(&c400),               // 1 above capacity
            CommandRef::PfConfigure(&c200),               // 2 not compiled
            CommandRef::PfConfigure(&ekf_with_particles), // 3
            CommandRef::PfConfigure(&bad_window),         // 4
            ranges(0.0, &good[0]),                        // 5 still not configured
            CommandRef::PfConfigure(&c100),               // 6
            ranges(0.0, &good[0]),                        // 7 ok
            ranges(1.0, &four),                           // 8 too few
            ranges(1.0, &nan),                            // 9
            ranges(1.0, &dup),                            // 10
            ranges(1.0, &many),                           // 11 above the PF's 12
            ranges(1.0, &zero_sigma),                     // 12
            ranges(0.0, &good[1]),                        // 13 time not increasing
            ranges(1.0, &good[1]),                        // 14 ok
            ranges(2.0, &leaving),                        // 15 ok, 7 satellites
            ranges(3.0, &good[3]),                        // 16 ok, G01 back
            ranges(4.0, &jump),                           // 17 collapse
            ranges(5.0, &good[5]),                        // 18 ok again
        ];
        let resp = exchange(&mut server, 0, &cmds);
        assert_eq!(resp.len(), cmds.len());
        let err = |i: usize| match &resp[i].body {
            ResponseBody::Error(e) => e.clone(),
            other => panic!("{i}: {other:?}"),
        };
        let res = |i: usize| match &resp[i].body {
            ResponseBody::PfResult(r) => r.clone(),
            other => panic!("{i}: {other:?}"),
        };
        assert_eq!(err(0), WireError::PfNotConfigured);
        assert_eq!(
            err(1),
            WireError::PfParticles {
                requested: 400,
                max: 300
            }
        );
        assert_eq!(
            err(2),
            WireError::PfParticles {
                requested: 200,
                max: 300
            }
        );
        assert_eq!(
            err(3),
            WireError::PfParticles {
                requested: 100,
                max: 300
            }
        );
        assert!(
            matches!(err(4), WireError::OutOfRange { ref field, value, .. } if field.as_str() == "window" && value == 0.0)
        );
        assert_eq!(err(5), WireError::PfNotConfigured);
        assert_eq!(resp[6].body, ResponseBody::Configured);
        assert!(res(7).position_ecef_m.is_some());
        assert_eq!(err(8), WireError::TooFewSatellites { have: 4, need: 5 });
        assert!(
            matches!(err(9), WireError::NonFinite { ref field, index: 2, .. } if field.as_str() == "pseudorange_m")
        );
        assert_eq!(
            err(10),
            WireError::DuplicateSatellite {
                id: SatId::new(System::Gps, 2),
                first: 1,
                second: 5
            }
        );
        assert_eq!(
            err(11),
            WireError::TooManySatellites {
                have: 13,
                capacity: 12
            }
        );
        assert!(
            matches!(err(12), WireError::PfInvalidConfig { ref field, value } if field.as_str() == "sigma_m" && value == 0.0)
        );
        assert_eq!(
            err(13),
            WireError::TimeNotIncreasing {
                previous_s: 0.0,
                now_s: 0.0
            }
        );
        // The refused epochs left the filter as it was: epoch 14 equals a
        // core monitor fed only the accepted epochs.
        let mut core = Box::new(PfRaim::<
            raim_proto::DevicePrecision,
            GaPf<raim_proto::DevicePrecision, 100>,
            12,
        >::new(c100.seed));
        core.process(&c100.config, 0.0, &good[0]).unwrap();
        let want = core.process(&c100.config, 1.0, &good[1]).unwrap();
        assert_eq!(res(14), WirePfResult::from_output(&want));
        assert_eq!(res(14).llr.len(), 8);
        let r15 = res(15);
        assert_eq!((r15.used, r15.llr.len()), (7, 7));
        assert!(r15.llr.iter().all(|l| l.id != SatId::new(System::Gps, 1)));
        // G01 back: a fresh auxiliary filter with an empty window.
        let r16 = res(16);
        assert_eq!(r16.llr.len(), 8);
        let g1 = r16
            .llr
            .iter()
            .find(|l| l.id == SatId::new(System::Gps, 1))
            .unwrap();
        assert_eq!(g1.windowed, g1.llr);
        let r17 = res(17);
        assert!(r17.main_collapsed && r17.position_ecef_m.is_none() && !r17.alarm);
        let r18 = res(18);
        assert!(!r18.main_collapsed);
        let p = r18.position_ecef_m.unwrap();
        let d: f64 = (0..3)
            .map(|j| (p[j] - RECEIVER_M[j]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(d < 50.0, "{d}");
        // No answer carried a position it should not have.
        for (i, r) in resp.iter().enumerate() {
            if let ResponseBody::PfResult(r) = &r.body {
                assert_eq!(r.position_ecef_m.is_none(), r.main_collapsed, "{i}");
            }
        }
    }

    /// Every engine a PF configuration can select is the one answering:
    /// the EKF, the SIR PF at 100 and 300 particles and the GA-PF at 300
    /// (the GA-PF at 100: the test above), each configured over the wire
    /// and sent the same 6 epochs, answer what the core's engine of that
    /// kind and size answers for the same seed, bit for bit; a second
    /// `PfConfigure` of the same kind restarts its filter from the seed
    /// (the first epoch's answer again).
    ///
    /// Verifies: SPEC-10
    #[test]
    fn each_configured_engine_answers_as_the_cores() {
        crate::tests::on_big_stack(each_configured_engine_answers_as_the_cores_body)
    }

    fn each_configured_engine_answers_as_the_cores_body() {
        use raim_core::pf::{Ekf, SirPf};
        type T = raim_proto::DevicePrecision;
        let mut noise = rng::seeded(5);
        let epochs: Vec<Vec<RangeObservation>> =
            (0..6).map(|k| epoch(8, k, &mut noise, None)).collect();
        macro_rules! against {
            ($kind:expr, $particles:expr, $engine:ty) => {{
                let mut server = pf_server();
                let cfg = WirePfConfig {
                    kind: $kind,
                    particles: $particles,
                    ..pf_config(100)
                };
                let mut cmds = std::vec![CommandRef::PfConfigure(&cfg)];
                cmds.extend(epochs.iter().enumerate().map(|(k, e)| ranges(k as f64, e)));
                cmds.push(CommandRef::PfConfigure(&cfg));
                cmds.push(ranges(0.0, &epochs[0]));
                let resp = exchange(&mut server, 0, &cmds);
                assert_eq!(resp[0].body, ResponseBody::Configured, "{:?}", $kind);
                let mut core = Box::new(<$engine>::new(cfg.seed));
                for (k, e) in epochs.iter().enumerate() {
                    let want = core.process(&cfg.config, k as f64, e).unwrap();
                    assert_eq!(
                        resp[1 + k].body,
                        ResponseBody::PfResult(WirePfResult::from_output(&want)),
                        "{:?} {} epoch {k}",
                        $kind,
                        $particles
                    );
                }
                assert_eq!(resp[7].body, ResponseBody::Configured);
                assert_eq!(resp[8].body, resp[1].body, "{:?} restarted", $kind);
            }};
        }
        against!(PfKind::Ekf, 0, PfRaim<T, Ekf<T>, 12>);
        against!(PfKind::Pf, 100, PfRaim<T, SirPf<T, 100>, 12>);
        against!(PfKind::Pf, 300, PfRaim<T, SirPf<T, 300>, 12>);
        against!(PfKind::Gapf, 300, PfRaim<T, GaPf<T, 300>, 12>);
    }
}

/// The alarm output's reading of a PF epoch (`pf_decision`), on every
/// combination of the three flags it reads.
#[cfg(test)]
mod decision_tests {
    use super::pf_decision;
    use raim_core::{Decision, SatId, System};
    use raim_proto::pf_msg::WirePfResult;

    fn result(position: bool, alarm: bool, excluded: bool) -> WirePfResult {
        let g = SatId::new(System::Gps, 4);
        WirePfResult {
            time_s: 0.0,
            position_ecef_m: position.then_some([1.0, 2.0, 3.0]),
            clock_m: Default::default(),
            drift_m_s: 0.0,
            decision: if alarm { 10.0 } else { 0.0 },
            threshold: 5.0,
            alarm,
            isolated: alarm.then_some(g),
            excluded: excluded.then_some(g),
            n_eff: 0.0,
            n_eff_before_ga: 0.0,
            used: 8,
            main_collapsed: !position,
            aux_collapsed: 0,
            clock_jump: false,
            llr: heapless::Vec::new(),
        }
    }

    /// A PF epoch never reads as `Ok` or `Excluded`: with no protection
    /// level it claims no integrity, whatever its flags; an alarm with a
    /// position is an alarm.
    ///
    /// Verifies: SAFE-PF-NO-BOUND, SAFE-ALARM
    #[test]
    fn a_pf_epoch_never_clears_the_alarm() {
        for position in [false, true] {
            for alarm in [false, true] {
                for excluded in [false, true] {
                    let d = pf_decision(&result(position, alarm, excluded));
                    let want = if position && alarm {
                        Decision::Alarm
                    } else {
                        Decision::Unavailable
                    };
                    assert_eq!(d, want, "{position} {alarm} {excluded}");
                    assert!(!matches!(d, Decision::Ok | Decision::Excluded));
                }
            }
        }
    }
}
