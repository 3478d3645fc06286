//! ARAIM in the protocol server (issue 12; docs/PROTOCOL.md "ARAIM"): the
//! ISM in force, its validation, the ARAIM engine and its FDE scratch,
//! all in the (static) server, so that the main loop's stack carries no
//! ARAIM buffer.
//!
//! Lifecycle: no ISM at reset; an `Ism` frame replaces the ISM and ARAIM
//! configuration as a whole after every check passes (else the previous one
//! stays); `Configure` leaves it alone; `Lock` locks it with the snapshot
//! configuration (an `Ism` frame is then `Locked`); the configuration
//! fingerprint covers it. An epoch satellite without an ISM entry is a typed
//! error (`NotInIsm`), never a default: P_sat and sigma_URA are integrity
//! parameters the unit must not invent.

use raim_core::araim::{AraimConfig, AraimError, Ism};
use raim_core::measurement::MAX_SYSTEMS;
use raim_core::Config;

use super::Server;
use crate::araim_msg::{AraimAnswer, AraimCommand, AraimWireError, IsmFrame, IsmSat};
use crate::error::WireError;
use crate::message::{LinearEpoch, ResponseBody};
use crate::CAPACITY;

/// Fault modes the device engine holds (per engine; the FDE scratch has as
/// many). A mode list that needs more makes the epoch unavailable with
/// `ModeCapacity`, never truncated. 32 satellites at P_sat 1e-5 and
/// P_const 1e-4 need 34 modes; G15+E15 at P_sat 1e-4, 498.
pub const MAX_MODES: usize = 512;

/// CRC-32/ISO-HDLC, as `frame::CRC32`; a static so that a digest can
/// borrow it.
static CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// A postcard output that feeds a CRC digest (no buffer).
struct CrcFlavor(crc::Digest<'static, u32>);

impl postcard::ser_flavors::Flavor for CrcFlavor {
    type Output = crc::Digest<'static, u32>;
    fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
        self.0.update(data);
        Ok(())
    }
    fn try_push(&mut self, data: u8) -> postcard::Result<()> {
        self.0.update(&[data]);
        Ok(())
    }
    fn finalize(self) -> postcard::Result<Self::Output> {
        Ok(self.0)
    }
}

/// The digest after `postcard(v)`. The flavor never fails, so neither
/// does serializing plain data.
fn feed<T: serde::Serialize>(
    v: &T,
    digest: crc::Digest<'static, u32>,
) -> crc::Digest<'static, u32> {
    let mut ser = postcard::Serializer {
        output: CrcFlavor(digest),
    };
    let _ = v.serialize(&mut ser);
    ser.output.0
}

/// The fingerprint of what is in force: CRC-32/ISO-HDLC of
/// `postcard(config)`, followed by `postcard(ism)` when an ISM is in
/// force. Without an ISM it equals `config_fingerprint(config)`.
pub fn fingerprint(config: &Config, ism: Option<&IsmFrame>) -> u32 {
    let mut digest = feed(config, CRC32.digest());
    if let Some(i) = ism {
        digest = feed(i, digest);
    }
    digest.finalize()
}

/// The ARAIM part of the server: the ISM in force and, with the `araim`
/// feature, the engine, its FDE scratch and the epoch's satellites.
pub(super) struct AraimState {
    /// The ISM and ARAIM configuration in force; `None` since reset until
    /// an `Ism` frame is accepted.
    pub(super) ism: Option<IsmFrame>,
    #[cfg(feature = "araim")]
    engine: engine::Engines,
}

impl AraimState {
    pub(super) fn new() -> Self {
        AraimState {
            ism: None,
            #[cfg(feature = "araim")]
            engine: engine::Engines::new(),
        }
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
    AraimConfig::from(frame.config).validate()?;
    let ism = Ism {
        p_const: frame.p_const,
    };
    ism.validate()?;
    for (i, s) in frame.sats.items.iter().enumerate() {
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
    for (field, v) in [
        ("sigma_ura_m", s.sigma_ura_m),
        ("sigma_ure_m", s.sigma_ure_m),
        ("b_nom_m", s.b_nom_m),
        ("p_sat", s.p_sat),
    ] {
        if !v.is_finite() {
            return Err(AraimError::NotFinite {
                field,
                index,
                value: v,
            });
        }
    }
    for (field, v) in [
        ("sigma_ura_m", s.sigma_ura_m),
        ("sigma_ure_m", s.sigma_ure_m),
        ("b_nom_m", s.b_nom_m),
    ] {
        if v < 0.0 {
            return Err(AraimError::OutOfRange {
                field,
                index,
                value: v,
                min: 0.0,
                max: f64::INFINITY,
            });
        }
    }
    if !(s.p_sat > 0.0 && s.p_sat < 1.0) {
        return Err(AraimError::OutOfRange {
            field: "p_sat",
            index,
            value: s.p_sat,
            min: 0.0,
            max: 1.0,
        });
    }
    Ok(())
}

impl Server {
    /// Answers `Command::Araim`.
    pub(super) fn araim<P: super::Platform>(
        &mut self,
        command: AraimCommand,
        platform: &mut P,
    ) -> ResponseBody {
        let answer = match command {
            AraimCommand::Ism(_) if !cfg!(feature = "araim") => {
                Err(WireError::Araim(AraimWireError::Disabled))
            }
            AraimCommand::Ism(_) if self.config_id.locked => Err(WireError::Locked {
                config_crc32: self.config_id.crc32,
            }),
            // ISM frames are not authenticated yet: a unit with a key
            // refuses them rather than take unauthenticated integrity data.
            AraimCommand::Ism(_) if self.auth.is_some() => Err(WireError::AuthRequired),
            AraimCommand::Ism(frame) => check_ism(&frame).map(|()| {
                let satellites = u32::try_from(frame.sats.items.len()).unwrap_or(u32::MAX);
                self.araim.ism = Some(frame);
                self.config_id.crc32 = fingerprint(&self.config, self.araim.ism.as_ref());
                AraimAnswer::IsmAccepted { satellites }
            }),
            AraimCommand::Epoch(e) => self.araim_epoch(&e, platform),
        };
        match answer {
            Ok(a) => ResponseBody::Araim(a),
            Err(e) => ResponseBody::Error(e),
        }
    }

    fn araim_epoch<P: super::Platform>(
        &mut self,
        epoch: &LinearEpoch,
        platform: &mut P,
    ) -> Result<AraimAnswer, WireError> {
        #[cfg(feature = "araim")]
        {
            let Some(ism) = self.araim.ism.as_ref() else {
                return Err(WireError::Araim(AraimWireError::NoIsm));
            };
            if epoch.sats.overflowed() {
                return Err(WireError::TooManySatellites {
                    have: epoch.sats.declared,
                    capacity: CAPACITY as u32,
                });
            }
            self.status.epochs = self.status.epochs.wrapping_add(1);
            let t0 = platform.now();
            let r = self.araim.engine.run(ism, epoch);
            let t1 = platform.now();
            self.status.last_epoch_ticks = t1.wrapping_sub(t0) & P::TICK_MASK;
            r.map(AraimAnswer::Result)
        }
        #[cfg(not(feature = "araim"))]
        {
            let _ = (epoch, platform);
            Err(WireError::Araim(AraimWireError::Disabled))
        }
    }
}

#[cfg(feature = "araim")]
mod engine {
    use raim_core::araim::error_model::{elevation_from_g, variances_m2};
    use raim_core::araim::{Araim, AraimConfig, AraimSat, FdeDecision, Ism};
    use raim_core::{Decision, Real, Stat};

    use super::{AraimWireError, IsmFrame, MAX_MODES, MAX_SYSTEMS};
    use crate::araim_msg::{AraimSummary, WireAraimResult};
    use crate::error::WireError;
    use crate::message::LinearEpoch;
    use crate::CAPACITY;

    type Engine = Araim<Stat, CAPACITY, MAX_MODES>;

    /// The engine, the FDE's scratch engine and the epoch's satellites.
    pub(super) struct Engines {
        main: Engine,
        scratch: Engine,
        sats: [AraimSat<Stat>; CAPACITY],
    }

    impl Engines {
        pub(super) fn new() -> Self {
            Engines {
                main: Engine::new(),
                scratch: Engine::new(),
                sats: [AraimSat::default(); CAPACITY],
            }
        }

        /// One epoch: the satellites from the epoch and the ISM, ARAIM all
        /// in view, FDE after a detection.
        pub(super) fn run(
            &mut self,
            ism: &IsmFrame,
            epoch: &LinearEpoch,
        ) -> Result<WireAraimResult, WireError> {
            let mut p_const = [None; MAX_SYSTEMS];
            let mut n = 0;
            for (i, o) in epoch.sats.items.iter().enumerate() {
                let Some(entry) = ism.sats.items.iter().find(|s| s.id == o.id) else {
                    return Err(WireError::Araim(AraimWireError::NotInIsm {
                        id: o.id,
                        index: u32::try_from(i).unwrap_or(u32::MAX),
                    }));
                };
                let j = o.id.system.index();
                if let (Some(dst), Some(src)) = (p_const.get_mut(j), ism.p_const.get(j)) {
                    *dst = *src;
                }
                if let Some(s) = o.sigma_m {
                    if !(s > 0.0) || !s.is_finite() {
                        return Err(WireError::NonPositiveSigma {
                            index: u32::try_from(i).unwrap_or(u32::MAX),
                            sigma_m: s,
                        });
                    }
                }
                // The ADD's G row is minus the line of sight.
                let g = o.los_enu.map(|v| Stat::of(-v));
                let (ura, ure) = (Stat::of(entry.sigma_ura_m), Stat::of(entry.sigma_ure_m));
                let (c_int_m2, c_acc_m2) = match o.sigma_m {
                    // The host's own sigma of the tropo + airborne terms.
                    Some(s) => {
                        let v = Stat::of(s * s);
                        (ura * ura + v, ure * ure + v)
                    }
                    None => variances_m2(elevation_from_g(&g), ura, ure),
                };
                if let Some(slot) = self.sats.get_mut(i) {
                    *slot = AraimSat {
                        id: o.id,
                        g_enu: g,
                        c_int_m2,
                        c_acc_m2,
                        b_nom_m: Stat::of(entry.b_nom_m),
                        p_sat: entry.p_sat,
                        residual_m: Stat::of(o.residual_m),
                    };
                    n += 1;
                }
            }
            let sats = self.sats.get(..n).unwrap_or(&[]);
            let cfg = AraimConfig::from(ism.config);
            let ism = Ism { p_const };
            let pl_exact = ism_pl_exact(&cfg);
            let out = self.main.process(&cfg, &ism, sats)?;
            let all_in_view = AraimSummary::from_output(out, pl_exact);
            let (fde, after_exclusion) = if out.detection_passed {
                (FdeDecision::NoFault, None)
            } else {
                let d = self.main.fde(&cfg, &ism, sats, &mut self.scratch)?;
                let after = match d {
                    FdeDecision::Excluded { .. } => {
                        Some(AraimSummary::from_output(self.scratch.output(), pl_exact))
                    }
                    _ => None,
                };
                (d, after)
            };
            let mut excluded = heapless::Vec::new();
            if let FdeDecision::Excluded { sats: mask, .. } = fde {
                for (i, s) in sats.iter().enumerate() {
                    if i < 64 && mask & (1u64 << i) != 0 {
                        // At most CAPACITY satellites: never full.
                        let _ = excluded.push(s.id);
                    }
                }
            }
            let decision = match (&fde, &after_exclusion) {
                (FdeDecision::NoFault, _) if all_in_view.available() => Decision::Ok,
                (FdeDecision::NoFault, _) => Decision::Unavailable,
                (FdeDecision::Excluded { .. }, Some(a)) if a.available() => Decision::Excluded,
                (FdeDecision::Excluded { .. }, _) => Decision::Unavailable,
                (FdeDecision::Alarm(_), _) => Decision::Alarm,
            };
            Ok(WireAraimResult {
                time_s: epoch.time_s,
                decision,
                all_in_view,
                fde: fde.into(),
                excluded,
                after_exclusion,
            })
        }
    }

    fn ism_pl_exact(cfg: &AraimConfig) -> bool {
        cfg.pl_output == raim_core::araim::PlOutput::Exact
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    #[test]
    fn sizes() {
        std::println!("server {}", core::mem::size_of::<super::Server>());
    }
}
