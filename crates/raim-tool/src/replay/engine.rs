//! Where the epochs run: the core on the host, the firmware under QEMU
//! (`crates/raim-qemu`, the same core built for Cortex-M4F, reached over
//! its framed UART protocol), or a unit on a serial port (`raim link`).
//! All answer in the wire form of a result, so the records, summary and
//! plots are identical for the targets.

use std::cell::RefCell;
use std::rc::Rc;

use anyhow::Result;
use raim_core::{Config, Epoch, Raim};
use raim_proto::nmea::GroundVelocity;
use raim_proto::result::WireResult;
use raim_qemu::QemuSession;

use super::{Target, REPLAY_CAPACITY};

pub enum Engine {
    Host(Box<Raim<REPLAY_CAPACITY>>),
    Qemu(Box<QemuSession>),
    /// A unit over its link UART, shared with the `raim link` run that
    /// configured it; its NMEA goes to the unit's other UART, not here.
    Link(Rc<RefCell<crate::link::Link>>),
}

impl Engine {
    /// A fresh engine configured with `cfg` (the firmware is built if
    /// needed, or taken from `$RAIM_FIRMWARE_ELF`).
    pub fn start(target: Target, cfg: &Config) -> Result<Self> {
        Ok(match target {
            Target::Host => Engine::Host(Box::new(Raim::new())),
            Target::Qemu => {
                let elf = raim_qemu::firmware_elf()?;
                let mut s = QemuSession::start(&elf)?;
                s.configure(cfg)?;
                Engine::Qemu(Box::new(s))
            }
        })
    }

    /// Put `cfg` in force for the epochs that follow: a live run learns its
    /// residual-ionosphere sigma from its first epoch with satellites
    /// (`receiver::adjust_config`), after the engine started. The host
    /// takes the configuration with every epoch; the firmware under QEMU
    /// and a unit on a link are sent `Configure` (a locked unit keeps its
    /// configuration, with a notice, as at the start).
    pub fn reconfigure(&mut self, cfg: &Config) -> Result<()> {
        match self {
            Engine::Host(_) => Ok(()),
            Engine::Qemu(s) => s.configure(cfg),
            Engine::Link(l) => l.borrow_mut().configure_for_epochs(cfg),
        }
    }

    /// One epoch: the result, or the monitor's typed error as text, and
    /// the epoch's NMEA sentences (RMC to ZDA, without their CRLF): the firmware's
    /// own second-UART output under QEMU, the same writer on the host. A
    /// transport failure (QEMU gone, timeout) is an `Err` of the outer result.
    /// `cn0_dbhz`: the satellites' C/N0 for the host's GSV (the source's,
    /// e.g. RINEX S observables); `velocity`: the speed and course of the
    /// answer for the host's RMC and VTG (`super::velocity`, from the
    /// source's Doppler). The protocol carries neither, so the firmware's
    /// GSV has no C/N0 and its RMC and VTG no speed or course.
    pub fn process(
        &mut self,
        cfg: &Config,
        epoch: &Epoch<'_>,
        cn0_dbhz: &[u8],
        velocity: &dyn Fn(&WireResult) -> Option<GroundVelocity>,
    ) -> Result<(Result<WireResult, String>, Vec<String>)> {
        Ok(match self {
            Engine::Host(raim) => match raim.process(cfg, epoch) {
                Ok(r) => {
                    let w = WireResult::from_result(&r);
                    let sky = raim_proto::nmea::Sky {
                        epoch,
                        cn0_dbhz,
                        velocity: velocity(&w),
                    };
                    let nmea = raim_proto::nmea::epoch_sentences(&w, &sky, raim_proto::nmea::BUILT)
                        .map(|v| v.iter().map(|s| s.trim_end().to_string()).collect())
                        .unwrap_or_default();
                    (Ok(w), nmea)
                }
                Err(e) => (Err(e.to_string()), Vec::new()),
            },
            Engine::Qemu(s) => {
                let p = s.process(epoch)?;
                (p.outcome.map_err(|e| e.to_string()), p.nmea)
            }
            Engine::Link(l) => (l.borrow_mut().process(epoch)?, Vec::new()),
        })
    }
}
