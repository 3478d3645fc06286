//! raim-server: the RAIM unit's protocol loop, board-independent: bytes in
//! from the link UART, one answer per frame out on the same UART, NMEA
//! sentences for every solved epoch out on the second UART (SPEC §11,
//! docs/PROTOCOL.md). The frames and messages are the wire crate's
//! (`raim-proto`); this crate holds the engines and answers them.
//!
//! It is sans-IO and lives outside `firmware/` so that the host can
//! unit-test every answer (sequence gaps, errors, counters) without an
//! emulator; the firmware only supplies the UARTs (`embedded_io::Write`)
//! and a [`Platform`] (a tick counter and the stack high-water mark).
#![no_std]
#![forbid(unsafe_code)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]
// `!(a < b)` is deliberate: it is true for NaN, so NaN never wins a
// comparison it should lose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
#![cfg_attr(
    test,
    allow(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod araim;

use embedded_io::Write;
use raim_core::{Config, Epoch, EpochResult, Raim};

use raim_proto::error::WireError;
use raim_proto::link::{LinkEvent, LinkReceiver};
use raim_proto::lock::{ConfigId, ConfigSource};
#[cfg(doc)]
use raim_proto::message::Response;
use raim_proto::message::{
    Command, EpochCycles, EpochKind, Request, ResetCause, ResponseBody, Status, TestFault,
};
use raim_proto::result::WireResult;
use raim_proto::unit::{ProvisionError, UnitConfig, UnitConfigRef};
use raim_proto::{
    DevicePrecision, CAPACITY, MAX_REQUEST_FRAME, MAX_RESPONSE_FRAME, MAX_RESPONSE_PAYLOAD,
    PROTOCOL_VERSION,
};

/// Satellites the snapshot monitor (and the stream receiver, whose
/// epochs it runs) takes: the wire's capacity. An epoch with more is
/// refused with the typed `TooManySatellites { capacity }`, never
/// truncated.
#[cfg(not(all(feature = "ram-192k", feature = "rtcm")))]
pub const SNAPSHOT_SATS: usize = CAPACITY;
/// Satellites the snapshot monitor and the stream receiver take on a part
/// with 192 KiB of RAM (the STM32F405/407, docs/FLASH.md) that carries
/// the stream: 24, as ARAIM there (`araim::ARAIM_SATS`). The engine's
/// O(N^2) storage and the stream's per-satellite buffers at 24 leave room
/// for the stream beside ARAIM and the particle filter; a 25th satellite
/// is `TooManySatellites { capacity: 24 }` (a stream epoch's,
/// `StreamCapacity { capacity: 24 }`). The part's build without the
/// stream keeps the wire's 32.
#[cfg(all(feature = "ram-192k", feature = "rtcm"))]
pub const SNAPSHOT_SATS: usize = 24;
const _: () = assert!(SNAPSHOT_SATS <= CAPACITY);

mod answer;
mod gate;
pub mod model_check;
#[cfg(feature = "rtcm")]
pub mod stream;

use answer::{send_answer, BodyRef, Buffers};
use gate::Applied;
pub use gate::{check_unit, UnitRefusal};
use raim_proto::auth::Change;

// Particle-filter RAIM: a child module, so it reaches the
// server's fields while its code stays out of this file.
mod pf;
pub use pf::{map_error as pf_error, PfEngines, PfUnit};
#[cfg(feature = "pf")]
pub use pf::{EkfEngine, Ga100Engine, Ga300Engine, Pf100Engine, Pf300Engine, PfT};

/// A pause on the link of this long ends an open frame and releases a held
/// RTCM candidate ([`Server::on_line_idle`]), s: 250 ms, 2,880 byte times
/// at 115200 baud, far longer than a USB-serial adapter's gaps inside one
/// write or an emulator's scheduling stalls, and shorter than a 1 Hz
/// receiver's pause between epochs (a faster receiver may never pause that
/// long; its link then resynchronises at a frame ending in 0x00).
pub const LINK_IDLE_S: f64 = 0.25;

/// What the board provides besides the UARTs.
pub trait Platform {
    /// A free-running tick counter (any rate); wraps at `TICK_MASK + 1`.
    fn now(&mut self) -> u32;
    /// Mask of the counter's valid bits (SysTick: 24 bits).
    const TICK_MASK: u32 = u32::MAX;
    /// Deepest stack use so far, bytes (0 if not measured).
    fn stack_high_water_bytes(&mut self) -> u32 {
        0
    }
    /// Resets since power-on and the cause of the last one.
    fn reset_record(&mut self) -> (u32, ResetCause) {
        (0, ResetCause::PowerOn)
    }
    /// Carry out a test-only fault (hang, panic); `false` when the build
    /// has no test hooks (the server then answers `TestHooksDisabled`).
    /// Honoured, it does not return.
    fn test_fault(&mut self, _fault: TestFault) -> bool {
        false
    }
    /// Called after every epoch with its decision, or `None` when it was
    /// answered with a typed error, before the answer goes out (the
    /// integrity-alarm output, `alert`).
    fn on_epoch(&mut self, _decision: Option<raim_core::Decision>) {}
    /// Fills the board's fields of a `Status` (link counters, the alarm
    /// output, the key) before it is sent.
    fn board_status(&mut self, _status: &mut Status) {}
    /// The core's cycle counter (Cortex-M DWT CYCCNT, wrapping at 2^32),
    /// or `None` when the platform has none that runs: `Status` then says
    /// `EpochCycles::NotMeasured`, never a zero count.
    fn cycles(&mut self) -> Option<u32> {
        None
    }
}

/// The tick counter and the cycle counter, read at the start of a timed
/// span (an epoch's monitor run, a stream epoch's forming).
pub(crate) struct Stopwatch {
    ticks: u32,
    cycles: Option<u32>,
}

/// A timed span: ticks (masked to the counter's width) and, when the
/// cycle counter runs, cycles.
pub(crate) struct Lap {
    pub(crate) ticks: u32,
    cycles: Option<u32>,
}

impl Stopwatch {
    pub(crate) fn start<P: Platform>(platform: &mut P) -> Self {
        let cycles = platform.cycles();
        Stopwatch {
            ticks: platform.now(),
            cycles,
        }
    }

    pub(crate) fn stop<P: Platform>(self, platform: &mut P) -> Lap {
        let t1 = platform.now();
        let c1 = platform.cycles();
        Lap {
            ticks: t1.wrapping_sub(self.ticks) & P::TICK_MASK,
            cycles: match (self.cycles, c1) {
                (Some(c0), Some(c1)) => Some(c1.wrapping_sub(c0)),
                _ => None,
            },
        }
    }
}

impl Lap {
    /// Counts the span's cycles as one epoch of `kind` in `status`, when
    /// the cycle counter runs.
    pub(crate) fn record(&self, status: &mut Status, kind: EpochKind) {
        if let Some(c) = self.cycles {
            status.epoch_cycles.record(kind, c);
        }
    }
}

/// A platform without a clock (host tests).
pub struct NoPlatform;
impl Platform for NoPlatform {
    fn now(&mut self) -> u32 {
        0
    }
}

/// The protocol state: receive buffer, engine, configuration, counters, the
/// transmit buffers, and the last request, result and wire result (kept
/// here rather than on the stack). The firmware keeps it in a
/// static (docs/bench-history/firmware.md, the stack work).
pub struct Server {
    /// The link's receiver: the host's frames, and a receiver's RTCM 3
    /// frames beside them.
    rx: LinkReceiver<MAX_REQUEST_FRAME>,
    raim: Raim<SNAPSHOT_SATS, DevicePrecision>,
    /// The snapshot configuration in force; `None` until one is
    /// provisioned or taken (snapshot epochs are then `Unconfigured`).
    config: Option<Config>,
    /// Whether epoch frames' per-satellite sigmas are used.
    host_sigmas: bool,
    expected_seq: Option<u32>,
    /// Fingerprint of the unit configuration in force, its source and the
    /// lock (`lock`).
    config_id: ConfigId,
    /// The authentication key and the last counter accepted (`auth`).
    auth: Option<(raim_proto::auth::AuthKey, Option<u64>)>,
    /// This boot's nonce (`auth::boot_nonce`).
    nonce: raim_proto::auth::Nonce,
    /// Whether hardware entropy went into it (`auth::BootEntropy`).
    hardware_entropy: bool,
    /// This boot's boot counter (`set_boot_counter`): its value is in the
    /// nonce; a failed counter refuses every authenticated change.
    boot_counter: raim_proto::boot_counter::BootCounterStatus,
    /// Why the provisioned configuration was refused at boot, if it was.
    provision_error: Option<ProvisionError>,
    status: Status,
    /// The ISM in force and the ARAIM engines (`server/araim.rs`).
    araim: araim::AraimState,
    /// The last request decoded (`on_byte`): decoded here rather than on
    /// the stack.
    request: Option<Request>,
    /// The answer's buffers, the stream epoch's forming scratch or (on the
    /// STM32F4 stream build) ARAIM's FDE scratch: one at a time
    /// ([`Shared`]).
    shared: Shared,
    /// The PF configuration and the engines lent by the owner
    /// (`attach_pf`; a few pointers, the engines stay where they are).
    pf: PfUnit,
    /// The receiver of an RTCM 3 stream on the link (`stream`).
    #[cfg(feature = "rtcm")]
    stream: stream::StreamState,
    /// The run-time model check of the model in force (`model_check`).
    model: model_check::UnitModelCheck,
}

impl Default for Server {
    fn default() -> Self {
        Self::new()
    }
}

/// The buffers of one epoch's run and answer, written and read only while
/// a frame is answered: the answer's encoding (`scratch`, `out`), and the
/// epoch's result (`Raim::process_into`) and wire form, both written in
/// place.
pub(crate) struct AnswerSlots {
    pub(crate) scratch: [u8; MAX_RESPONSE_PAYLOAD],
    pub(crate) out: [u8; MAX_RESPONSE_FRAME],
    pub(crate) result: EpochResult<SNAPSHOT_SATS>,
    pub(crate) wire: WireResult,
}

/// One room for parts that never run at once (docs/FLASH.md,
/// "STM32F4: the stream", items 2 and 5): the answer's buffers, the forming
/// scratch of a stream epoch, used only inside the receiver's
/// `on_frame_in`, which ends before the epoch is staged, run and
/// answered, and, on the STM32F4 stream build (`ram-192k` and `rtcm`),
/// ARAIM's FDE scratch engine, used only while an ARAIM epoch is run and
/// its wire result and model-check sample are read from it, which ends
/// before its NMEA sentences and answer are written. Each part takes the
/// room in its initial state from a constant when another had it, so no
/// value of one is ever read as another's, and nothing an answer reads
/// was left by an earlier one: every path writes `wire` and `result`
/// before it reads them, and the FDE leaves its subset in the scratch
/// before the monitor's runs read it (`raim_core::araim::MonitorCore`: the
/// runs borrow the scratch they were decided in).
// The variants' sizes differ by design: the room is the larger one's, and
// sharing it is the point (boxing is not an option without a heap).
#[allow(clippy::large_enum_variant)]
enum Shared {
    Answer(AnswerSlots),
    #[cfg(feature = "rtcm")]
    Forming(raim_nav::rtcm::FormScratch<SNAPSHOT_SATS>),
    #[cfg(all(feature = "araim", feature = "ram-192k", feature = "rtcm"))]
    Fde(araim::FdeScratch),
}

impl Shared {
    /// The answer's buffers, zero.
    const ANSWER_SLOTS: AnswerSlots = AnswerSlots {
        scratch: [0; MAX_RESPONSE_PAYLOAD],
        out: [0; MAX_RESPONSE_FRAME],
        result: EpochResult::empty(),
        wire: WireResult::empty(),
    };

    /// The room holding the answer's buffers, zero (the server's initial
    /// state).
    const ANSWER: Shared = Shared::Answer(Self::ANSWER_SLOTS);

    /// The forming scratch, empty.
    #[cfg(feature = "rtcm")]
    const FORMING: raim_nav::rtcm::FormScratch<SNAPSHOT_SATS> = raim_nav::rtcm::FormScratch::new();

    /// ARAIM's FDE scratch engine, empty.
    #[cfg(all(feature = "araim", feature = "ram-192k", feature = "rtcm"))]
    const FDE: araim::FdeScratch = araim::FdeScratch::new();

    /// The answer's buffers, taking the room if another part had it (at
    /// most one pass of the loop does).
    #[cfg(feature = "rtcm")]
    fn answer(&mut self) -> &mut AnswerSlots {
        loop {
            match self {
                Shared::Answer(a) => return a,
                _ => *self = Shared::Answer(Self::ANSWER_SLOTS),
            }
        }
    }

    /// The answer's buffers (without the stream, the room's only use).
    #[cfg(not(feature = "rtcm"))]
    fn answer(&mut self) -> &mut AnswerSlots {
        match self {
            Shared::Answer(a) => a,
        }
    }

    /// The forming scratch, taking the room if another part had it.
    #[cfg(feature = "rtcm")]
    fn forming(&mut self) -> &mut raim_nav::rtcm::FormScratch<SNAPSHOT_SATS> {
        loop {
            match self {
                Shared::Forming(f) => return f,
                _ => *self = Shared::Forming(Self::FORMING),
            }
        }
    }

    /// ARAIM's FDE scratch engine, taking the room if another part had it.
    #[cfg(all(feature = "araim", feature = "ram-192k", feature = "rtcm"))]
    fn fde(&mut self) -> &mut araim::FdeScratch {
        loop {
            match self {
                Shared::Fde(f) => return f,
                _ => *self = Shared::Fde(Self::FDE),
            }
        }
    }
}

/// Either UART failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IoError<L, M> {
    Link(L),
    Nmea(M),
}

/// The fingerprint of the unconfigured unit (no snapshot, ARAIM or PF
/// configuration, host sigmas on, the model check's default settings):
/// `UnitConfigRef::fingerprint` of it, a
/// SHA-256 that `const fn` cannot compute, written out so that
/// [`Server::new`] is `const`; the test `unconfigured_fingerprint_is_computed`
/// recomputes it.
const UNCONFIGURED_FINGERPRINT: raim_proto::unit::Fingerprint = [
    44, 133, 30, 195, 206, 67, 97, 158, 110, 213, 240, 68, 105, 102, 215, 148,
];

impl Server {
    /// An unconfigured, unkeyed server: every epoch is answered
    /// `Unconfigured` until a configuration is taken ([`Server::boot`]
    /// with a provisioned one, or a runtime `Configure`).
    pub const fn new() -> Self {
        // `const`: the firmware's server is a static initialised at
        // compile time (`.bss`/`.data`), never built on the stack.
        Server {
            rx: LinkReceiver::new(),
            raim: Raim::new(),
            config: None,
            host_sigmas: true,
            expected_seq: None,
            config_id: ConfigId {
                fingerprint: UNCONFIGURED_FINGERPRINT,
                locked: false,
                source: ConfigSource::Unconfigured,
            },
            auth: None,
            nonce: [0; 16],
            hardware_entropy: false,
            boot_counter: raim_proto::boot_counter::BootCounterStatus::Absent,
            provision_error: None,
            status: Status {
                protocol_version: PROTOCOL_VERSION,
                capacity: SNAPSHOT_SATS as u16,
                ..Status::ZERO
            },
            araim: araim::AraimState::new(),
            request: None,
            shared: Shared::ANSWER,
            pf: PfUnit::EMPTY,
            #[cfg(feature = "rtcm")]
            stream: stream::StreamState::new(),
            model: model_check::UnitModelCheck::new(),
        }
    }

    /// A server that accepts only authenticated changes under `key`
    /// (`auth`), with the boot nonce of `(resets, entropy)`.
    pub fn with_auth_key(key: raim_proto::auth::AuthKey) -> Self {
        let mut s = Server::new();
        s.set_auth_key(key);
        s
    }

    /// Make this server take only changes authenticated with `key` from
    /// now on, as `with_auth_key` (the firmware sets up its static server
    /// in place at boot, without a second server on the stack). Call
    /// before [`Server::boot`], which derives the nonce from the key.
    pub fn set_auth_key(&mut self, key: raim_proto::auth::AuthKey) {
        self.auth = Some((key, None));
    }

    /// This boot's boot counter, as the platform advanced it
    /// (`raim_proto::boot_counter::advance`; docs/SAFETY.md "Boot
    /// counter"). Call before [`Server::boot`]: its value goes into the
    /// nonce. A `Failed` counter leaves the boot without a count, and
    /// every authenticated change is then refused
    /// (`WireError::BootCounter`): the nonce may have been used in an
    /// earlier power-on. A server never given one (`Absent`, the host's)
    /// derives its nonce as before, from the reset count and the entropy.
    pub fn set_boot_counter(&mut self, counter: raim_proto::boot_counter::BootCounterStatus) {
        self.boot_counter = counter;
    }

    /// The boot sequence: the boot nonce from the key, the reset count,
    /// the boot counter ([`Server::set_boot_counter`]) and
    /// the platform's `entropy` (whose source `Status.hardware_entropy`
    /// then reports), then the provisioned configuration, if
    /// any. A provisioned configuration whose seal verified (`provisioned`
    /// is what `unit::open` gave) and whose every part passes its checks
    /// is put in force, locked. A section that is present and refused
    /// (any [`ProvisionError`]: a bad seal, a sealed section on a unit
    /// whose key was erased, a part that fails its checks) leaves the unit
    /// Unconfigured and locked, the reason kept for the boot notice,
    /// `Status` and every refusal; an erased section leaves it
    /// Unconfigured and open (bench use). No default is ever put in force.
    pub fn boot(
        &mut self,
        provisioned: Result<Option<UnitConfig>, ProvisionError>,
        resets: u32,
        entropy: &raim_proto::auth::BootEntropy,
    ) {
        let boot_count = match self.boot_counter {
            raim_proto::boot_counter::BootCounterStatus::Count(n) => Some(n),
            _ => None,
        };
        self.nonce = raim_proto::auth::boot_nonce(
            self.auth.as_ref().map(|(k, _)| k),
            resets,
            boot_count,
            &entropy.bytes,
        );
        self.hardware_entropy = entropy.hardware;
        match provisioned {
            Ok(Some(unit)) => {
                if let Err(e) = self.provision(unit) {
                    self.provision_error = Some(e);
                }
            }
            Ok(None) => {}
            Err(e) => self.provision_error = Some(e),
        }
        // A section that is present and refused: an installed unit whose
        // installation failed. It stays Unconfigured and locked (the gate
        // refuses every change with the reason, `gate.rs`) until a reset
        // finds a good section; it never becomes an open bench unit.
        if self.provision_error.is_some() {
            self.config_id.locked = true;
        }
        self.config_id.fingerprint = self.fingerprint();
    }

    /// Puts a provisioned unit configuration in force, locked, if every
    /// part passes its checks (all or nothing).
    pub fn provision(&mut self, unit: UnitConfig) -> Result<(), ProvisionError> {
        if let Err(refusal) = gate::check_unit(&unit) {
            return Err(ProvisionError::InvalidPart(refusal.part));
        }
        let UnitConfig {
            snapshot,
            araim,
            pf,
            host_sigmas,
            model_check,
        } = unit;
        if let Some(p) = pf {
            self.pf
                .configure(p)
                .map_err(|_| ProvisionError::InvalidPart(raim_proto::unit::UnitPart::Pf))?;
        }
        self.model
            .configure(model_check)
            .map_err(|_| ProvisionError::InvalidPart(raim_proto::unit::UnitPart::ModelCheck))?;
        self.config = snapshot;
        self.araim.ism = araim;
        self.host_sigmas = host_sigmas;
        self.model.reset();
        self.config_id = ConfigId {
            fingerprint: self.fingerprint(),
            locked: true,
            source: ConfigSource::Provisioned,
        };
        Ok(())
    }

    /// The fingerprint of everything in force (`unit::UnitConfigRef`).
    pub fn fingerprint(&self) -> raim_proto::Fingerprint {
        UnitConfigRef {
            snapshot: self.config.as_ref(),
            araim: self.araim.ism.as_ref(),
            pf: self.pf.config(),
            host_sigmas: self.host_sigmas,
            model_check: self.model.settings(),
        }
        .fingerprint()
    }

    /// Takes `config` at run time, through the gate, as if a host had sent
    /// `Configure(config)` (the bench's set-up, for host tests and tools;
    /// the firmware never calls it).
    pub fn take_runtime_config(&mut self, config: Config) -> Result<(), WireError> {
        self.change_plain(&Change::Configure(config)).map(|_| ())
    }

    /// This boot's nonce.
    pub fn nonce(&self) -> raim_proto::auth::Nonce {
        self.nonce
    }

    /// Sends the boot notice (unasked, `seq: None`): the first frame after
    /// every reset.
    pub fn send_boot_notice<L: Write, M, P: Platform>(
        &mut self,
        link: &mut L,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M>> {
        let (resets, reset_cause) = platform.reset_record();
        let notice = raim_proto::BootNotice {
            protocol_version: PROTOCOL_VERSION,
            resets,
            reset_cause,
            config: self.config_id,
            provision_error: self.provision_error,
            auth_provisioned: self.auth.is_some(),
            boot_nonce: self.nonce,
        };
        self.send(link, None, BodyRef::Boot(&notice))
    }

    pub fn status(&self) -> Status {
        Status {
            config: self.config_id,
            boot_nonce: self.nonce,
            hardware_entropy: self.hardware_entropy,
            boot_counter: self.boot_counter,
            host_sigmas: self.host_sigmas,
            provision_error: self.provision_error,
            auth_provisioned: self.auth.is_some(),
            ..self.status
        }
    }

    /// The fingerprint of the configuration in force and the lock state.
    pub fn config_id(&self) -> ConfigId {
        self.config_id
    }

    /// The snapshot configuration in force, if any.
    pub fn config(&self) -> Option<&Config> {
        self.config.as_ref()
    }

    /// Feed one received byte; writes the answers (and NMEA) when it
    /// completes a frame.
    ///
    /// The request is decoded once, into the server's own `request` slot,
    /// and checked once (`answer::decode`); `Server::dispatch` then
    /// answers it. Epochs are answered from references into that slot with
    /// the wire result written in place, and answers are encoded from
    /// references (`answer::ResponseRef`): no request-, result- or
    /// answer-sized value is on the stack of the epoch path.
    pub fn on_byte<L: Write, M: Write, P: Platform>(
        &mut self,
        byte: u8,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        self.link_events(Some(byte), link, nmea_out, platform)
    }

    /// The link has been quiet for a while (no byte for [`LINK_IDLE_S`]):
    /// a held RTCM candidate is released and an open frame is ended
    /// (`LinkReceiver::line_idle`), and whatever that completes is
    /// answered. The board calls it once per pause.
    pub fn on_line_idle<L: Write, M: Write, P: Platform>(
        &mut self,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        self.link_events(None, link, nmea_out, platform)
    }

    /// The events of one byte (`Some`) or of a pause (`None`), answered
    /// in order: one byte may complete several frames
    /// (`LinkReceiver::poll`).
    fn link_events<L: Write, M: Write, P: Platform>(
        &mut self,
        byte: Option<u8>,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        let mut first = true;
        loop {
            let step = {
                let event = match (first, byte) {
                    (true, Some(b)) => self.rx.push(b),
                    (true, None) => self.rx.line_idle(),
                    (false, _) => self.rx.poll(),
                };
                first = false;
                match event {
                    None => return Ok(()),
                    // A frame the unit cannot read (longer than the
                    // receive buffer, not COBS or not an envelope, a bad
                    // CRC) may have been an epoch: it is answered as a
                    // refused epoch, the alarm output hears it and the
                    // no-fix sentences go out at once (issue 35,
                    // docs/SAFETY.md "Frames the unit cannot read").
                    Some(LinkEvent::Frame(Err(e))) => {
                        Step::Frame(Err(answer::Refusal::unread(None, WireError::from(e))))
                    }
                    // Bytes given up when a host frame ended inside an
                    // RTCM candidate (`link` "Resynchronisation on a host
                    // frame"): unreadable, answered as such; the frame
                    // follows.
                    Some(LinkEvent::TruncatedRtcm { received, declared }) => {
                        Step::Frame(Err(answer::Refusal::unread(
                            None,
                            WireError::TruncatedRtcm { received, declared },
                        )))
                    }
                    Some(LinkEvent::Frame(Ok(payload))) => {
                        Step::Frame(answer::decode(payload, &mut self.request))
                    }
                    #[cfg(feature = "rtcm")]
                    Some(LinkEvent::Rtcm(frame)) => {
                        let watch = Stopwatch::start(platform);
                        // `stream_runs_araim`, on the field (`frame`
                        // borrows the receiver).
                        let araim = self.araim.runs_stream();
                        let formed = self.stream.on_frame(
                            frame,
                            self.config.as_ref(),
                            araim,
                            self.shared.forming(),
                        );
                        let lap = watch.stop(platform);
                        match formed {
                            Some(formed) => {
                                self.status.last_stream_ticks = lap.ticks;
                                lap.record(&mut self.status, EpochKind::StreamForming);
                                Step::Stream(formed)
                            }
                            None => continue,
                        }
                    }
                    // Without a stream receiver, RTCM frames are counted
                    // (`Status::rtcm_frames`) and not used.
                    #[cfg(not(feature = "rtcm"))]
                    Some(LinkEvent::Rtcm(_)) => continue,
                }
            };
            match step {
                Step::Frame(decoded) => self.on_frame(decoded, link, nmea_out, platform)?,
                #[cfg(feature = "rtcm")]
                Step::Stream(formed) => self.on_stream_epoch(formed, link, nmea_out, platform)?,
            }
        }
    }

    /// A frame from the host, decoded (or refused).
    fn on_frame<L: Write, M: Write, P: Platform>(
        &mut self,
        decoded: Result<u32, answer::Refusal>,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        self.status.frames = self.status.frames.wrapping_add(1);
        match decoded {
            Ok(seq) => {
                self.check_sequence(seq, link)?;
                self.dispatch(seq, link, nmea_out, platform)
            }
            Err(refusal) => {
                if let Some(s) = refusal.seq {
                    self.check_sequence(s, link)?;
                }
                if refusal.epoch {
                    platform.on_epoch(None);
                }
                if let Some(time_s) = refusal.nmea_time_s {
                    let wire = &mut self.shared.answer().wire;
                    wire.reset();
                    wire.time_s = time_s;
                    answer::write_nmea(wire, None, &[], None, nmea_out).map_err(IoError::Nmea)?;
                }
                self.send(link, refusal.seq, BodyRef::Error(&refusal.error))
            }
        }
    }

    /// Answers the request in `self.request`: the one place where a
    /// request kind meets its handler. Epochs are answered from references
    /// into the request slot; every other request is taken out of it.
    fn dispatch<L: Write, M: Write, P: Platform>(
        &mut self,
        seq: u32,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        use raim_proto::araim_msg::AraimCommand;
        let Some(command) = self.request.as_ref().map(|r| &r.command) else {
            return Ok(());
        };
        if command.is_epoch() {
            if let Err(e) = self.admit_epoch(command) {
                return self.refuse_epoch(seq, e, link, nmea_out, platform);
            }
        }
        match command {
            Command::Ranges(_) | Command::Linear(_) => {
                self.answer_epoch(Some(seq), link, nmea_out, platform)
            }
            Command::Araim(AraimCommand::Epoch(_) | AraimCommand::Ranges(_)) => {
                self.answer_araim_epoch(Some(seq), link, nmea_out, platform)
            }
            _ => self.answer_other(seq, link, nmea_out, platform),
        }
    }

    /// Every request but an epoch answered from the request slot: taken
    /// out of the slot, in a frame of its own so that the request-sized
    /// value is not on the stack of the epoch path.
    #[inline(never)]
    fn answer_other<L: Write, M: Write, P: Platform>(
        &mut self,
        seq: u32,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        use raim_proto::araim_msg::AraimCommand;
        let Some(request) = self.request.take() else {
            return Ok(());
        };
        let body = match request.command {
            Command::Status => ResponseBody::Status(self.fill_status(platform)),
            Command::TestFault(f) => {
                let _ = platform.test_fault(f);
                ResponseBody::Error(WireError::TestHooksDisabled)
            }
            Command::Lock => Applied::body(self.change_plain(&Change::Lock)),
            Command::Configure(c) => Applied::body(self.change_plain(&Change::Configure(c))),
            Command::Araim(AraimCommand::Ism(frame)) => {
                Applied::body(self.change_plain(&Change::Ism(frame)))
            }
            Command::PfConfigure(c) => Applied::body(self.change_plain(&Change::Pf(c))),
            Command::HostSigmas(on) => Applied::body(self.change_plain(&Change::HostSigmas(on))),
            Command::ModelCheck(c) => Applied::body(self.change_plain(&Change::ModelCheck(c))),
            Command::Authenticated(a) => Applied::body(self.change_authenticated(&a)),
            Command::PfRanges(ref e) => {
                let body = self.pf_epoch(e.time_s, &e.sats.items, platform);
                self.write_pf_nmea(&body, &request.command, nmea_out)
                    .map_err(IoError::Nmea)?;
                body
            }
            // Answered from the request slot above.
            Command::Ranges(_)
            | Command::Linear(_)
            | Command::Araim(AraimCommand::Epoch(_) | AraimCommand::Ranges(_)) => return Ok(()),
        };
        self.send(link, Some(seq), BodyRef::from(&body))
    }

    /// The checks every epoch passes before its engine runs: a
    /// configuration is in force for it, and its satellites carry no sigma
    /// unless the unit configuration takes host sigmas.
    fn admit_epoch(&self, command: &Command) -> Result<(), WireError> {
        use raim_proto::araim_msg::AraimCommand;
        let unconfigured = WireError::Unconfigured {
            provision: self.provision_error,
        };
        let nothing_in_force = self.config_id.source == ConfigSource::Unconfigured;
        let (needs_snapshot, first_sigma) = match command {
            Command::Ranges(e) => (true, e.sats.items.iter().position(|s| s.sigma_m.is_some())),
            Command::Linear(e) => (true, e.sats.items.iter().position(|s| s.sigma_m.is_some())),
            Command::Araim(AraimCommand::Ranges(e)) => {
                (true, e.sats.items.iter().position(|s| s.sigma_m.is_some()))
            }
            Command::Araim(AraimCommand::Epoch(e)) => {
                (true, e.sats.items.iter().position(|s| s.sigma_m.is_some()))
            }
            Command::PfRanges(e) => (false, e.sats.items.iter().position(|s| s.sigma_m.is_some())),
            _ => return Ok(()),
        };
        if nothing_in_force || (needs_snapshot && self.config.is_none()) {
            return Err(unconfigured);
        }
        match first_sigma {
            Some(i) if !self.host_sigmas => Err(WireError::HostSigmaRefused {
                index: u32::try_from(i).unwrap_or(u32::MAX),
            }),
            _ => araim_sigma_bounds(command),
        }
    }

    /// An epoch refused before its engine ran: the alarm output hears it,
    /// the NMEA port gets the epoch's no-fix sentences, and the host the
    /// typed error.
    fn refuse_epoch<L: Write, M: Write, P: Platform>(
        &mut self,
        seq: u32,
        e: WireError,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        platform.on_epoch(None);
        self.write_no_fix(Some(seq), nmea_out)
            .map_err(IoError::Nmea)?;
        self.request = None;
        self.send(link, Some(seq), BodyRef::Error(&e))
    }

    /// What the NMEA writer reads of an answered epoch: its wire result,
    /// the request, the C/N0 of its satellites for GSV and the speed and
    /// course over ground for RMC and VTG: a stream epoch's (answered
    /// unasked, `seq` None: the epoch formed last, `stream::StreamState`;
    /// the velocity from its Doppler at the solved position, with the
    /// satellites the solution used), else none (the protocol's epochs
    /// carry no C/N0 and no Doppler).
    #[allow(clippy::type_complexity)]
    pub(crate) fn nmea_parts(
        &mut self,
        seq: Option<u32>,
    ) -> (
        &WireResult,
        Option<&Request>,
        &[u8],
        Option<raim_proto::nmea::GroundVelocity>,
    ) {
        let Server {
            shared,
            request,
            #[cfg(feature = "rtcm")]
            stream,
            ..
        } = self;
        let wire = &shared.answer().wire;
        #[cfg(feature = "rtcm")]
        let (cn0, velocity): (&[u8], _) = if seq.is_none() {
            (stream.cn0_dbhz(), stream.velocity(wire))
        } else {
            (&[], None)
        };
        #[cfg(not(feature = "rtcm"))]
        let (cn0, velocity): (&[u8], _) = {
            let _ = seq;
            (&[], None)
        };
        (wire, request.as_ref(), cn0, velocity)
    }

    /// The no-fix NMEA sentences of the epoch in the request slot (its
    /// time, no position, status void); `seq` as for [`Self::nmea_parts`].
    pub(crate) fn write_no_fix<M: Write>(
        &mut self,
        seq: Option<u32>,
        nmea_out: &mut M,
    ) -> Result<(), M::Error> {
        let Some(time_s) = self
            .request
            .as_ref()
            .and_then(|r| r.command.nmea_epoch_time_s())
        else {
            return Ok(());
        };
        let wire = &mut self.shared.answer().wire;
        wire.reset();
        wire.time_s = time_s;
        let (wire, request, cn0, velocity) = self.nmea_parts(seq);
        answer::write_nmea(wire, request, cn0, velocity, nmea_out)
    }

    /// The NMEA sentences of a particle-filter epoch (`command`, taken out
    /// of the request slot), as every epoch writes them: the filter's
    /// position under the decision that drives the alarm output
    /// ([`WireResult::set_from_pf`]); a refused epoch's no-fix sentences.
    fn write_pf_nmea<M: Write>(
        &mut self,
        body: &ResponseBody,
        command: &Command,
        nmea_out: &mut M,
    ) -> Result<(), M::Error> {
        let Command::PfRanges(e) = command else {
            return Ok(());
        };
        match body {
            ResponseBody::PfResult(r) => {
                let decision = pf::pf_decision(r);
                self.shared.answer().wire.set_from_pf(
                    r,
                    decision,
                    e.sats.items.iter().map(|s| s.id),
                );
            }
            _ => {
                let wire = &mut self.shared.answer().wire;
                wire.reset();
                wire.time_s = e.time_s;
            }
        }
        answer::write_nmea_for(
            &self.shared.answer().wire,
            Some(command),
            &[],
            None,
            nmea_out,
        )
    }

    /// `Status`, with the platform's fields filled in.
    fn fill_status<P: Platform>(&mut self, platform: &mut P) -> Status {
        self.status.stack_high_water_bytes = platform.stack_high_water_bytes();
        (self.status.resets, self.status.reset_cause) = platform.reset_record();
        self.status.auth_provisioned = self.auth.is_some();
        let link = self.rx.counts();
        (self.status.rtcm_frames, self.status.rtcm_bad_crc) = (link.rtcm_frames, link.rtcm_bad_crc);
        #[cfg(feature = "rtcm")]
        {
            (self.status.stream_epochs, self.status.stream_ephemerides) = self.stream.counters();
            self.status.stream_leap_seconds = self.stream.leap_seconds();
        }
        self.status.model_check = model_check::status(&self.model);
        if self.status.epoch_cycles == EpochCycles::NotMeasured && platform.cycles().is_some() {
            // The counter runs, and no epoch has been timed yet.
            self.status.epoch_cycles = EpochCycles::RUNNING;
        }
        platform.board_status(&mut self.status);
        self.status()
    }

    /// A `Ranges` or `Linear` request (in `self.request`): the epoch, its
    /// NMEA sentences and the answer, the result written into `self.wire`.
    #[inline(never)]
    pub(crate) fn answer_epoch<L: Write, M: Write, P: Platform>(
        &mut self,
        seq: Option<u32>,
        link: &mut L,
        nmea_out: &mut M,
        platform: &mut P,
    ) -> Result<(), IoError<L::Error, M::Error>> {
        let Some(config) = self.config else {
            // `admit_epoch` refused it already.
            return Ok(());
        };
        let outcome = {
            let Server {
                request,
                raim,
                status,
                shared,
                model,
                ..
            } = self;
            let AnswerSlots { result, wire, .. } = shared.answer();
            let slots = (result, wire);
            match request.as_ref().map(|r| &r.command) {
                Some(Command::Ranges(e)) => run_epoch(
                    (raim, model),
                    &config,
                    status,
                    slots,
                    &Epoch::ranges(e.time_s, &e.sats.items, e.apriori_m),
                    platform,
                ),
                Some(Command::Linear(e)) => run_epoch(
                    (raim, model),
                    &config,
                    status,
                    slots,
                    &Epoch::linear(e.time_s, &e.sats.items),
                    platform,
                ),
                // `dispatch` sends only epochs here.
                _ => return Ok(()),
            }
        };
        match outcome {
            Ok(()) => {
                let (wire, request, cn0, velocity) = self.nmea_parts(seq);
                answer::write_nmea(wire, request, cn0, velocity, nmea_out)
                    .map_err(IoError::Nmea)?;
                let Server {
                    shared,
                    status,
                    config_id,
                    ..
                } = self;
                let AnswerSlots {
                    scratch, out, wire, ..
                } = shared.answer();
                send_answer(
                    Buffers {
                        scratch,
                        out,
                        status,
                        config: *config_id,
                    },
                    link,
                    seq,
                    BodyRef::Result(wire),
                )
            }
            Err(e) => {
                self.write_no_fix(seq, nmea_out).map_err(IoError::Nmea)?;
                self.send(link, seq, BodyRef::Error(&e))
            }
        }
    }

    /// A jump in the sequence numbers is reported as a notice before the
    /// answer (which still follows).
    fn check_sequence<L: Write, M>(
        &mut self,
        seq: u32,
        link: &mut L,
    ) -> Result<(), IoError<L::Error, M>> {
        let expected = self.expected_seq.replace(seq.wrapping_add(1));
        match expected {
            Some(e) if e != seq => self.send(
                link,
                Some(seq),
                BodyRef::Error(&WireError::SequenceGap {
                    expected: e,
                    received: seq,
                }),
            ),
            _ => Ok(()),
        }
    }

    fn send<L: Write, M>(
        &mut self,
        link: &mut L,
        seq: Option<u32>,
        body: BodyRef<'_>,
    ) -> Result<(), IoError<L::Error, M>> {
        let Server {
            shared,
            status,
            config_id,
            ..
        } = self;
        let AnswerSlots { scratch, out, .. } = shared.answer();
        send_answer(
            Buffers {
                scratch,
                out,
                status,
                config: *config_id,
            },
            link,
            seq,
            body,
        )
    }
}

/// What one link event asks of the server.
enum Step {
    /// A host frame, decoded into the request slot (or refused).
    Frame(Result<u32, answer::Refusal>),
    /// A stream epoch closed: formed, or why not.
    #[cfg(feature = "rtcm")]
    Stream(Result<(), raim_nav::rtcm::FormError>),
}

/// The per-satellite sigma bound (`raim_core::config_bounds::SIGMA_M`) on
/// an ARAIM epoch's host sigmas, checked at admission as the snapshot and
/// PF engines check theirs.
fn araim_sigma_bounds(command: &Command) -> Result<(), WireError> {
    use raim_proto::araim_msg::AraimCommand;
    // A build without the ARAIM engine answers every ARAIM epoch
    // `Araim(Disabled)` whatever it holds (as a build without the PF
    // answers `PfUnavailable`), and carries no code to check it
    // (docs/FLASH.md).
    if !cfg!(feature = "araim") {
        return Ok(());
    }
    // Statically dispatched (no vtable call on the epoch path: the
    // firmware's call graph, scripts/firmware_callgraph.py, resolves every
    // call).
    match command {
        Command::Araim(AraimCommand::Epoch(e)) => {
            check_sigma_bounds(e.sats.items.iter().map(|s| s.sigma_m))
        }
        Command::Araim(AraimCommand::Ranges(e)) => {
            check_sigma_bounds(e.sats.items.iter().map(|s| s.sigma_m))
        }
        _ => Ok(()),
    }
}

/// [`araim_sigma_bounds`] on one epoch's host sigmas.
fn check_sigma_bounds(sigmas: impl Iterator<Item = Option<f64>>) -> Result<(), WireError> {
    let bound = raim_core::config_bounds::SIGMA_M;
    for (i, s) in sigmas.enumerate() {
        // A non-positive or non-finite sigma is the engine's own typed
        // error (`NonPositiveSigma`, `NonFinite`).
        if let Some(sigma_m) = s.filter(|v| v.is_finite() && *v > 0.0) {
            if bound.check(sigma_m).is_err() {
                return Err(WireError::SigmaOutOfRange {
                    index: u32::try_from(i).unwrap_or(u32::MAX),
                    sigma_m,
                    min_m: bound.min,
                    max_m: bound.max,
                });
            }
        }
    }
    Ok(())
}

/// One epoch through the engine; the result written into `result` and
/// its wire form into `wire`, or the typed error. The model check takes
/// the delivered solution's sample, and a model it has declared broken
/// makes the decision `Unavailable` (`model_check`). The platform hears
/// the verdict.
fn run_epoch<P: Platform>(
    (raim, model): (
        &mut Raim<SNAPSHOT_SATS, DevicePrecision>,
        &mut model_check::UnitModelCheck,
    ),
    config: &Config,
    status: &mut Status,
    (result, wire): (&mut EpochResult<SNAPSHOT_SATS>, &mut WireResult),
    epoch: &Epoch<'_>,
    platform: &mut P,
) -> Result<(), WireError> {
    status.epochs = status.epochs.wrapping_add(1);
    let watch = Stopwatch::start(platform);
    let r = raim.process_into(config, epoch, result);
    let lap = watch.stop(platform);
    status.last_epoch_ticks = lap.ticks;
    lap.record(status, EpochKind::Snapshot);
    if r.is_ok() {
        result.decision =
            model_check::judge(model, epoch.time_s, result.model_sample(), result.decision);
    }
    platform.on_epoch(r.as_ref().ok().map(|()| result.decision));
    match r {
        Ok(()) => {
            wire.set_from_result(result);
            Ok(())
        }
        Err(e) => Err(e.into()),
    }
}

#[cfg(test)]
mod cov_tests;
#[cfg(test)]
mod tests;

#[cfg(test)]
mod cov2_tests;
