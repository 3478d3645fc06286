//! The messages inside the frames (docs/PROTOCOL.md).
//!
//! Host to firmware: a [`Request`] = sequence number + [`Command`]
//! (status, configure, a pseudorange epoch or a linearised epoch).
//! Firmware to host: a [`Response`] = the sequence number it answers (none
//! when the frame was unreadable) + a [`ResponseBody`].
//!
//! The observation and configuration types are raim-core's own (with its
//! `serde` feature), so the wire carries exactly what the core consumes.
//! postcard encodes fields in declaration order, enums as a varint variant
//! index, integers as varints and f64 as 8 little-endian bytes.

use core::marker::PhantomData;

use raim_core::{Config, LinearObservation, RangeObservation};
use serde::de::{Deserializer, SeqAccess, Visitor};
use serde::ser::Serializer;
use serde::{Deserialize, Serialize};

use crate::error::WireError;
use crate::lock::{ConfigId, ConfigSource};
use crate::result::WireResult;
use crate::CAPACITY;

/// Up to [`CAPACITY`] satellites, and how many the frame declared. A frame
/// with more satellites than the capacity still decodes (the extra ones are
/// read and dropped), so the firmware can answer `TooManySatellites` with
/// the count instead of "undecodable".
#[derive(Debug, Clone, PartialEq)]
pub struct SatList<T> {
    /// The elements, at most [`CAPACITY`].
    pub items: heapless::Vec<T, CAPACITY>,
    /// Satellites in the frame; more than `items.len()` when it overflowed.
    pub declared: u32,
}

impl<T> Default for SatList<T> {
    fn default() -> Self {
        SatList {
            items: heapless::Vec::new(),
            declared: 0,
        }
    }
}

impl<T> SatList<T> {
    /// True when the frame carried more satellites than [`CAPACITY`].
    pub fn overflowed(&self) -> bool {
        self.declared as usize > self.items.len()
    }
}

impl<T: Serialize> Serialize for SatList<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.items.iter())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for SatList<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = SatList<T>;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("a sequence of satellites")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut out = SatList::default();
                while let Some(item) = seq.next_element::<T>()? {
                    out.declared = out.declared.saturating_add(1);
                    // Beyond the capacity the satellite is read and dropped.
                    let _ = out.items.push(item);
                }
                Ok(out)
            }
        }
        d.deserialize_seq(V(PhantomData))
    }
}

/// One epoch of corrected pseudoranges with ECEF satellite positions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RangeEpoch {
    /// Epoch time, s. The NMEA writer reads it as UTC seconds since
    /// 1970-01-01 (docs/PROTOCOL.md).
    pub time_s: f64,
    /// Where Gauss-Newton starts, ECEF m (`None`: the Earth's centre).
    pub apriori_m: Option<[f64; 3]>,
    /// The satellites' pseudoranges and positions.
    pub sats: SatList<RangeObservation>,
}

/// One epoch in the seeds' linearised form (line of sight + residual).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinearEpoch {
    /// Epoch time, s.
    pub time_s: f64,
    /// The satellites' lines of sight and residuals.
    pub sats: SatList<LinearObservation>,
}

/// What the host asks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// Answered with [`ResponseBody::Status`].
    Status,
    /// Replace the configuration (Pfa, Pmd, alert limits, FI rule and
    /// kappa, sigma model, ...). Answered with `Configured` or an error
    /// (`OutOfRange`), in which case the previous configuration stays.
    Configure(Config),
    /// One pseudorange epoch through the snapshot monitor. Answered `Result` or an error.
    Ranges(RangeEpoch),
    /// One linearised epoch through the snapshot monitor. Answered `Result` or an error.
    Linear(LinearEpoch),
    /// Lock the configuration in force until reset: every later `Configure`
    /// is refused with `WireError::Locked`. Answered with `LockEngaged`
    /// (also when already locked).
    Lock,
    /// Test-only: make the unit hang or panic, to test the
    /// watchdog and the fault record under QEMU. Honoured only by a build
    /// whose platform enables it (the QEMU board); elsewhere answered
    /// `WireError::TestHooksDisabled`.
    TestFault(TestFault),
    /// An authenticated change (`auth`): `Configure`, `Ism`, `PfConfigure`,
    /// `Lock`, `HostSigmas` or `ModelCheck`, with a counter and an HMAC
    /// tag under the unit's key and boot nonce. The only form a keyed unit
    /// takes.
    Authenticated(crate::auth::Authenticated),
    /// ARAIM: an ISM frame or an ARAIM epoch (`araim_msg`).
    Araim(crate::araim_msg::AraimCommand),
    /// Particle-filter RAIM (`pf_msg`): take a PF configuration
    /// (filter, particle count, seed, `PfConfig`) and restart the filter.
    /// Answered `Configured`, or an error (`PfParticles`,
    /// `PfInvalidConfig`, `Locked`, `PfUnavailable`) with the previous PF
    /// configuration kept.
    PfConfigure(crate::pf_msg::WirePfConfig),
    /// One pseudorange epoch for the particle-filter monitor (`apriori_m`
    /// is not used: the PF initialises from its own first fix). Answered
    /// `PfResult` or an error.
    PfRanges(RangeEpoch),
    /// Whether the per-satellite sigmas of epoch frames are used (the unit
    /// configuration's `host_sigmas`). Answered `Configured`.
    HostSigmas(bool),
    /// The run-time model check's allocation, spacing and window (the
    /// unit configuration's `model_check`; docs/MODEL_CHECK.md). Answered
    /// `Configured`, or the typed error of the first field out of its
    /// bounds (`OutOfRange`, `NonFinite`) with the settings in force kept.
    /// Protocol 17.
    ModelCheck(crate::model_check_msg::WireModelCheckConfig),
}

impl Command {
    /// The satellite count of a list in this request that held more than
    /// [`CAPACITY`] satellites, if one did. The device server refuses such
    /// a request as soon as it is decoded (`TooManySatellites`), so that no
    /// consumer of a request sees a truncated list.
    pub fn overflowed_list(&self) -> Option<u32> {
        use crate::araim_msg::AraimCommand;
        let (overflowed, declared) = match self {
            Command::Ranges(e) | Command::PfRanges(e) => (e.sats.overflowed(), e.sats.declared),
            Command::Linear(e) => (e.sats.overflowed(), e.sats.declared),
            Command::Araim(AraimCommand::Epoch(e)) => (e.sats.overflowed(), e.sats.declared),
            Command::Araim(AraimCommand::Ranges(e)) => (e.sats.overflowed(), e.sats.declared),
            Command::Araim(AraimCommand::Ism(i))
            | Command::Authenticated(crate::auth::Authenticated {
                change: crate::auth::Change::Ism(i),
                ..
            }) => (i.sats.overflowed(), i.sats.declared),
            Command::Status
            | Command::Configure(_)
            | Command::Lock
            | Command::TestFault(_)
            | Command::Authenticated(_)
            | Command::PfConfigure(_)
            | Command::HostSigmas(_)
            | Command::ModelCheck(_) => (false, 0),
        };
        overflowed.then_some(declared)
    }

    /// The time of an epoch (snapshot, ARAIM or particle filter: every
    /// epoch writes its NMEA sentences, a refused one its no-fix
    /// sentences, so that the port never keeps an earlier epoch's fix),
    /// `None` for every other request.
    pub fn nmea_epoch_time_s(&self) -> Option<f64> {
        use crate::araim_msg::AraimCommand;
        match self {
            Command::Ranges(e) | Command::PfRanges(e) => Some(e.time_s),
            Command::Linear(e) => Some(e.time_s),
            Command::Araim(AraimCommand::Ranges(e)) => Some(e.time_s),
            Command::Araim(AraimCommand::Epoch(e)) => Some(e.time_s),
            _ => None,
        }
    }

    /// True for an epoch (snapshot, ARAIM or particle filter): its verdict,
    /// or its refusal, drives the integrity-alarm output.
    pub fn is_epoch(&self) -> bool {
        use crate::araim_msg::AraimCommand;
        matches!(
            self,
            Command::Ranges(_)
                | Command::Linear(_)
                | Command::PfRanges(_)
                | Command::Araim(AraimCommand::Epoch(_) | AraimCommand::Ranges(_))
        )
    }
}

/// What a `TestFault` request does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TestFault {
    /// Spin without feeding the watchdog (a hung epoch).
    Hang,
    /// Panic.
    Panic,
    /// Recurse until the stack reaches its guard.
    StackOverflow,
}

/// Why the unit last reset, from a record in RAM that a reset
/// does not clear.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// Power-on, or no valid record (the platform keeps none).
    #[default]
    PowerOn,
    /// A reset the firmware did not record (external, debugger).
    Unrecorded,
    /// A panic; `line` is the source line of the panic location.
    Panic {
        /// Source line of the panic.
        line: u32,
    },
    /// A hard fault at `pc`.
    HardFault {
        /// Program counter of the fault.
        pc: u32,
    },
    /// The watchdog expired (a hung main loop); `pc` where it was.
    Watchdog {
        /// Program counter when it expired.
        pc: u32,
    },
    /// The stack reached its guard region (MPU) at `address`.
    StackOverflow {
        /// The address the stack reached.
        address: u32,
    },
}

/// A request frame's payload.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Request {
    /// Increments by one per request; the firmware reports a jump as
    /// `SequenceGap`. It is the first field so that the firmware can read it
    /// even when the rest of the payload does not decode.
    pub seq: u32,
    /// What the firmware is asked to do.
    pub command: Command,
}

/// The host's borrowed form of [`Command`]: identical bytes on the wire
/// (test `borrowed_and_owned_requests_encode_alike`), without copying the
/// satellites, and able to carry more than [`CAPACITY`] of them (to test the
/// firmware's answer).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum CommandRef<'a> {
    /// [`Command::Status`].
    Status,
    /// [`Command::Configure`].
    Configure(&'a Config),
    /// [`Command::Ranges`], its fields inline.
    Ranges {
        /// Epoch time, s.
        time_s: f64,
        /// Where Gauss-Newton starts, ECEF m.
        apriori_m: Option<[f64; 3]>,
        /// The satellites (any number, to test the refusal above capacity).
        sats: &'a [RangeObservation],
    },
    /// [`Command::Linear`], its fields inline.
    Linear {
        /// Epoch time, s.
        time_s: f64,
        /// The satellites (any number).
        sats: &'a [LinearObservation],
    },
    /// [`Command::Lock`].
    Lock,
    /// [`Command::TestFault`].
    TestFault(TestFault),
    /// [`Command::Authenticated`].
    Authenticated(crate::auth::AuthenticatedRef<'a>),
    /// [`Command::Araim`].
    Araim(crate::araim_msg::AraimCommandRef<'a>),
    /// [`Command::PfConfigure`].
    PfConfigure(&'a crate::pf_msg::WirePfConfig),
    /// [`Command::PfRanges`], its fields inline.
    PfRanges {
        /// Epoch time, s.
        time_s: f64,
        /// Not used by the PF (it starts from its own fix), ECEF m.
        apriori_m: Option<[f64; 3]>,
        /// The satellites (any number).
        sats: &'a [RangeObservation],
    },
    /// [`Command::HostSigmas`].
    HostSigmas(bool),
    /// [`Command::ModelCheck`].
    ModelCheck(crate::model_check_msg::WireModelCheckConfig),
}

/// The host's borrowed form of [`Request`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RequestRef<'a> {
    /// Sequence number (see [`Request::seq`]).
    pub seq: u32,
    /// What the firmware is asked to do.
    pub command: CommandRef<'a>,
}

impl<'a> RequestRef<'a> {
    /// A pseudorange epoch request, borrowing its satellites.
    pub fn ranges(
        seq: u32,
        time_s: f64,
        apriori_m: Option<[f64; 3]>,
        sats: &'a [RangeObservation],
    ) -> Self {
        RequestRef {
            seq,
            command: CommandRef::Ranges {
                time_s,
                apriori_m,
                sats,
            },
        }
    }

    /// A linearised epoch request, borrowing its satellites.
    pub fn linear(seq: u32, time_s: f64, sats: &'a [LinearObservation]) -> Self {
        RequestRef {
            seq,
            command: CommandRef::Linear { time_s, sats },
        }
    }
}

/// The firmware's counters, for the host's accounting and the benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// [`crate::PROTOCOL_VERSION`] of the firmware.
    pub protocol_version: u16,
    /// Satellite capacity of the engine.
    pub capacity: u16,
    /// Frames (delimited chunks) received since reset, good or bad.
    pub frames: u32,
    /// Responses that carried an error.
    pub errors: u32,
    /// Epochs processed (results and core errors).
    pub epochs: u32,
    /// Deepest stack use since reset, bytes, by stack painting; 0 when the
    /// build does not paint the stack.
    pub stack_high_water_bytes: u32,
    /// Timer ticks of the last epoch's `Raim::process` (SysTick at the core
    /// clock; under `qemu -icount shift=0` one tick is 40 guest instructions
    /// on mps2-an386).
    pub last_epoch_ticks: u32,
    /// The configuration in force and the lock state (as in every
    /// response's `config`).
    pub config: ConfigId,
    /// Resets since power-on, and the cause of the last one.
    pub resets: u32,
    /// The cause of the last reset.
    pub reset_cause: ResetCause,
    /// Link bytes lost in the UART since reset: times its receive register
    /// overran (a byte arrived before the previous one was read). 0 where
    /// the UART model has no overrun (QEMU applies back-pressure).
    pub uart_overruns: u32,
    /// Times a received byte found the firmware's receive ring full since
    /// reset. Reception then pauses until the main loop makes room: the
    /// UART holds that byte, and a further byte overruns the UART (counted
    /// in `uart_overruns`); under QEMU nothing is lost (docs/SAFETY.md).
    pub rx_ring_overflows: u32,
    /// The integrity-alarm discrete output's state and why (`alert`).
    pub alarm_output: crate::alert::AlarmOutput,
    /// The output pin as read back from the hardware: true when it is at
    /// its alarm level. Must agree with `alarm_output.asserted()`.
    pub alarm_pin_asserted: bool,
    /// True when the unit holds an authentication key: every
    /// state-changing request must then be `Authenticated`.
    pub auth_provisioned: bool,
    /// This boot's nonce, which an `Authenticated` tag covers.
    pub boot_nonce: crate::auth::Nonce,
    /// Whether epoch frames' per-satellite sigmas are used.
    pub host_sigmas: bool,
    /// Why the provisioned configuration was refused at boot, if it was.
    pub provision_error: Option<crate::unit::ProvisionError>,
    /// The core clock the unit runs at, Hz (SysTick and the time-to-alert
    /// count at it); 0 from a server with no board (the host's).
    pub core_clock_hz: u32,
    /// True when that clock is the board's fallback: the STM32F4 on its
    /// 16 MHz HSI because the HSE or the PLL did not become ready within
    /// its bounded wait (docs/SAFETY.md "Clocks").
    pub clock_fallback: bool,
    /// True when this boot's nonce had hardware entropy in it (the
    /// STM32F4's RNG, read without error). False means the nonce comes
    /// from the key, the reset count and whatever else the platform had
    /// (power-on SRAM, SysTick), which under QEMU repeats across power
    /// cycles: frames recorded in an earlier power-on could then verify
    /// again (docs/SAFETY.md "Boot nonce").
    pub hardware_entropy: bool,
    /// RTCM 3 frames taken from the link (CRC verified), since reset.
    pub rtcm_frames: u32,
    /// Candidate RTCM 3 frames whose CRC failed (their bytes went to the
    /// frame receiver instead), since reset.
    pub rtcm_bad_crc: u32,
    /// Epochs the unit formed from the RTCM 3 stream, answered or refused.
    pub stream_epochs: u32,
    /// Broadcast ephemerides the stream receiver holds (GPS, GLONASS).
    pub stream_ephemerides: [u16; 2],
    /// Ticks (as `last_epoch_ticks`) of the last stream epoch's forming:
    /// the decoding of the frame that closed it, the satellites' orbits
    /// and clocks, the corrections and the bootstrap solution.
    pub last_stream_ticks: u32,
    /// The GPS - UTC leap seconds the stream receiver dates GLONASS with,
    /// and where they come from (protocol 15).
    pub stream_leap_seconds: StreamLeapSeconds,
    /// The run-time model check of the configuration and ISM in force
    /// (docs/MODEL_CHECK.md; protocol 15).
    pub model_check: ModelCheckStatus,
    /// Core clock cycles of the epochs since reset, per kind, from the
    /// Cortex-M DWT cycle counter: a real board's own cost, beside the
    /// QEMU-derived bounds (issue 37 "A time bound"; protocol 16).
    /// `NotMeasured` where no cycle counter runs (QEMU, the host).
    pub epoch_cycles: EpochCycles,
    /// This boot's value of the monotonic boot counter in flash (part of
    /// the boot nonce), or why it failed (docs/SAFETY.md "Boot counter";
    /// protocol 16).
    pub boot_counter: crate::boot_counter::BootCounterStatus,
}

/// Core clock cycles of the epochs since reset (DWT CYCCNT, 32 bits: it
/// wraps after 25.6 s at 168 MHz, five times the STM32F4's watchdog
/// timeout, so one epoch's count never wraps twice). Each span covers
/// what the `*_ticks` fields of [`Status`] cover: the monitor's run
/// (`Raim::process`, the ARAIM engine, the particle filter) or the stream
/// epoch's forming.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EpochCycles {
    /// No cycle counter runs: QEMU does not model the DWT (its CYCCNT
    /// reads 0 and does not advance, which the firmware checks at boot),
    /// and the host's server has none. Never reported as a zero count.
    #[default]
    NotMeasured,
    /// The counter runs; per kind, the last and the largest count since
    /// reset, `None` before the first epoch of that kind.
    Measured {
        /// Snapshot epochs (`Ranges`, `Linear`, and stream epochs the
        /// snapshot monitor answers): `Raim::process`.
        snapshot: Option<CycleSpan>,
        /// ARAIM epochs (host frames and stream epochs): the engine's run.
        araim: Option<CycleSpan>,
        /// Particle-filter epochs (`PfRanges`): the filter's run.
        pf: Option<CycleSpan>,
        /// Stream epochs' forming: the closing frame's decoding, orbits,
        /// clocks, corrections and the bootstrap solution.
        stream_forming: Option<CycleSpan>,
    },
}

/// The last and the largest cycle count of one kind of epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CycleSpan {
    /// The last epoch's cycles.
    pub last_cycles: u32,
    /// The largest since reset.
    pub max_cycles: u32,
}

/// The kinds of epoch [`EpochCycles`] counts apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EpochKind {
    /// The snapshot monitor.
    Snapshot,
    /// ARAIM.
    Araim,
    /// The particle filter.
    Pf,
    /// A stream epoch's forming.
    StreamForming,
}

impl EpochCycles {
    /// All kinds measured, none run yet: what a platform whose counter
    /// runs reports before its first epoch.
    pub const RUNNING: EpochCycles = EpochCycles::Measured {
        snapshot: None,
        araim: None,
        pf: None,
        stream_forming: None,
    };

    /// One epoch of `kind` took `cycles`: the counter runs from now on.
    pub fn record(&mut self, kind: EpochKind, cycles: u32) {
        if *self == EpochCycles::NotMeasured {
            *self = EpochCycles::RUNNING;
        }
        if let EpochCycles::Measured {
            snapshot,
            araim,
            pf,
            stream_forming,
        } = self
        {
            let span = match kind {
                EpochKind::Snapshot => snapshot,
                EpochKind::Araim => araim,
                EpochKind::Pf => pf,
                EpochKind::StreamForming => stream_forming,
            };
            let max_cycles = span.map_or(cycles, |s| s.max_cycles.max(cycles));
            *span = Some(CycleSpan {
                last_cycles: cycles,
                max_cycles,
            });
        }
    }

    /// The span of `kind`, `None` when not measured or not run yet.
    pub fn get(&self, kind: EpochKind) -> Option<CycleSpan> {
        match *self {
            EpochCycles::NotMeasured => None,
            EpochCycles::Measured {
                snapshot,
                araim,
                pf,
                stream_forming,
            } => match kind {
                EpochKind::Snapshot => snapshot,
                EpochKind::Araim => araim,
                EpochKind::Pf => pf,
                EpochKind::StreamForming => stream_forming,
            },
        }
    }
}

/// The run-time model check's state: its windowed chi-square goodness of
/// fit of the delivered solutions' normalised residuals against the error
/// model in force (`raim_core::consistency`), since that model was put in
/// force. Once it has rejected, every epoch is answered `Unavailable`
/// (alarm output asserted) until a new configuration or ISM.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ModelCheckStatus {
    /// Windows tested (one per sample taken).
    pub evaluations: u32,
    /// Windows that rejected the model.
    pub rejections: u32,
    /// The epoch time of the first rejection, ms (the epoch's `time_s`
    /// x 1000, rounded): the model is declared broken from then on.
    pub broken_at_ms: Option<u64>,
}

/// Where the stream receiver's GPS - UTC leap seconds come from, at its
/// latest dated epoch (GLONASS time is UTC-based: docs/RECEIVERS.md
/// "Leap seconds").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StreamLeapSeconds {
    /// No stream epoch dated yet and no RTCM 1013 (or no stream receiver).
    #[default]
    NotDated,
    /// From the stream's latest RTCM 1013 (DF054), s.
    Stream {
        /// GPS - UTC, s.
        gps_minus_utc_s: u8,
    },
    /// From the unit's table, s: the latest stream epoch is before the
    /// table's expiry.
    Table {
        /// GPS - UTC, s.
        gps_minus_utc_s: u8,
    },
    /// The latest stream epoch is past the table's expiry and the stream
    /// has sent no count: stream epochs with GLONASS data are refused
    /// (`WireError::StreamLeapSecondsUnknown`); GPS, Galileo, BeiDou and
    /// QZSS epochs are formed.
    TableExpired,
}

impl Status {
    /// The derived `Default` (every counter 0, power-on, unconfigured and
    /// unlocked, the alarm output asserted for want of a valid epoch), for
    /// `const fn` constructors (the device server is built in place in a
    /// static).
    pub const ZERO: Status = Status {
        protocol_version: 0,
        capacity: 0,
        frames: 0,
        errors: 0,
        epochs: 0,
        stack_high_water_bytes: 0,
        last_epoch_ticks: 0,
        config: ConfigId {
            fingerprint: [0; 16],
            locked: false,
            source: ConfigSource::Unconfigured,
        },
        resets: 0,
        reset_cause: ResetCause::PowerOn,
        uart_overruns: 0,
        rx_ring_overflows: 0,
        alarm_output: crate::alert::AlarmOutput::NoValidEpoch,
        alarm_pin_asserted: false,
        auth_provisioned: false,
        boot_nonce: [0; 16],
        host_sigmas: false,
        provision_error: None,
        core_clock_hz: 0,
        clock_fallback: false,
        hardware_entropy: false,
        rtcm_frames: 0,
        rtcm_bad_crc: 0,
        stream_epochs: 0,
        stream_ephemerides: [0, 0],
        last_stream_ticks: 0,
        stream_leap_seconds: StreamLeapSeconds::NotDated,
        model_check: ModelCheckStatus {
            evaluations: 0,
            rejections: 0,
            broken_at_ms: None,
        },
        epoch_cycles: EpochCycles::NotMeasured,
        boot_counter: crate::boot_counter::BootCounterStatus::Absent,
    };
}

/// The first frame a unit sends after any reset, unasked (`seq: None`):
/// the host learns that answers to frames sent before it may be missing,
/// what the unit now runs, and the nonce its authenticated requests must
/// carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BootNotice {
    /// [`crate::PROTOCOL_VERSION`] of the unit.
    pub protocol_version: u16,
    /// Resets since power-on, and the cause of this one.
    pub resets: u32,
    /// The cause of this boot's reset.
    pub reset_cause: ResetCause,
    /// The configuration now in force (provisioned, or none).
    pub config: ConfigId,
    /// Why the provisioned configuration was refused, if it was.
    pub provision_error: Option<crate::unit::ProvisionError>,
    /// True when the unit holds an authentication key.
    pub auth_provisioned: bool,
    /// This boot's nonce.
    pub boot_nonce: crate::auth::Nonce,
}

/// A response frame's payload.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Response {
    /// The request answered; `None` when the frame could not be read.
    pub seq: Option<u32>,
    /// The answer.
    pub body: ResponseBody,
    /// The configuration in force when the answer was made (after a
    /// `Configure` it answers, the new one) and the lock state.
    pub config: ConfigId,
}

/// What the firmware answers. The result is by far the largest variant;
/// without a heap it cannot be boxed, and only one response exists at a time.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ResponseBody {
    /// The answer to a `Ranges` or `Linear` epoch.
    Result(WireResult),
    /// The answer to `Configure` or `PfConfigure`: the configuration is in force.
    Configured,
    /// The answer to `Status`.
    Status(Status),
    /// The request was refused, or a notice (`SequenceGap`).
    Error(WireError),
    /// The answer to `Lock`: the configuration is now locked until reset.
    LockEngaged,
    /// The answer to `Command::Araim` (`araim_msg`).
    Araim(crate::araim_msg::AraimAnswer),
    /// The answer to a `PfRanges` epoch.
    PfResult(crate::pf_msg::WirePfResult),
    /// Unasked, after every reset.
    Boot(BootNotice),
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use raim_core::{FiRule, Phase, SatId, System};

    fn obs(n: usize) -> std::vec::Vec<RangeObservation> {
        (0..n)
            .map(|i| RangeObservation {
                id: SatId::new(System::Gps, i as u8 + 1),
                pseudorange_m: 2.0e7 + i as f64 * 0.5,
                position_m: [1.0, 2.0, f64::NAN],
                sigma_m: if i % 2 == 0 { Some(2.0) } else { None },
            })
            .collect()
    }

    #[test]
    fn borrowed_and_owned_requests_encode_alike() {
        let s = obs(5);
        let cfg = Config {
            rule: FiRule::LraimGaussian { kappa: 42.0 },
            ..Config::preset(Phase::Terminal)
        };
        let lin = [raim_core::LinearObservation::from_az_el(
            SatId::new(System::Beidou, 9),
            0.3,
            0.7,
            -1.5,
        )];
        let pairs = [
            (
                RequestRef {
                    seq: 1,
                    command: CommandRef::Status,
                },
                Request {
                    seq: 1,
                    command: Command::Status,
                },
            ),
            (
                RequestRef {
                    seq: 2,
                    command: CommandRef::Configure(&cfg),
                },
                Request {
                    seq: 2,
                    command: Command::Configure(cfg),
                },
            ),
            (
                RequestRef::ranges(300, 4.5, Some([7.0, 8.0, 9.0]), &s),
                Request {
                    seq: 300,
                    command: Command::Ranges(RangeEpoch {
                        time_s: 4.5,
                        apriori_m: Some([7.0, 8.0, 9.0]),
                        sats: SatList {
                            items: s.iter().copied().collect(),
                            declared: 5,
                        },
                    }),
                },
            ),
            (
                RequestRef::linear(u32::MAX, -1.0, &lin),
                Request {
                    seq: u32::MAX,
                    command: Command::Linear(LinearEpoch {
                        time_s: -1.0,
                        sats: SatList {
                            items: lin.iter().copied().collect(),
                            declared: 1,
                        },
                    }),
                },
            ),
        ];
        for (borrowed, owned) in pairs {
            let a = postcard::to_allocvec_shim(&borrowed);
            let b = postcard::to_allocvec_shim(&owned);
            assert_eq!(a, b, "{owned:?}");
            let back: Request = postcard::from_bytes(&a).unwrap();
            // NaN != NaN: compare the re-encoded bytes instead.
            assert_eq!(postcard::to_allocvec_shim(&back), a);
        }
    }

    #[test]
    fn oversized_satellite_list_decodes_with_its_count() {
        let s = obs(CAPACITY + 3);
        let bytes = postcard::to_allocvec_shim(&RequestRef::ranges(9, 0.0, None, &s));
        let req: Request = postcard::from_bytes(&bytes).unwrap();
        let Command::Ranges(e) = req.command else {
            panic!()
        };
        assert_eq!(e.sats.declared as usize, CAPACITY + 3);
        assert_eq!(e.sats.items.len(), CAPACITY);
        assert!(e.sats.overflowed());
    }

    #[test]
    fn the_sequence_number_is_readable_from_a_damaged_payload() {
        let bytes = postcard::to_allocvec_shim(&RequestRef {
            seq: 123_456,
            command: CommandRef::Status,
        });
        let mut damaged = bytes.clone();
        damaged.truncate(bytes.len() - 1);
        damaged.push(0x7F); // no such command
        assert!(postcard::from_bytes::<Request>(&damaged).is_err());
        let (seq, _) = postcard::take_from_bytes::<u32>(&damaged).unwrap();
        assert_eq!(seq, 123_456);
    }

    /// postcard without `alloc`: serialize into a big stack buffer.
    mod postcard {
        extern crate std;
        pub use ::postcard::*;
        pub fn to_allocvec_shim<T: serde::Serialize>(t: &T) -> std::vec::Vec<u8> {
            let mut buf = [0u8; 8192];
            to_slice(t, &mut buf).unwrap().to_vec()
        }
    }
}

#[cfg(test)]
mod status_zero {
    extern crate std;
    use super::{CycleSpan, EpochCycles, EpochKind, Status};

    /// The `const` initial status is the derived `Default`, field for field.
    #[test]
    fn status_zero_is_the_default() {
        assert_eq!(Status::ZERO, Status::default());
    }

    /// A `Status` with measured epoch cycles and one saying "not measured"
    /// survive the wire (postcard) unchanged, and differ on it: no zero
    /// count stands for a counter that does not run.
    ///
    /// Verifies: FW-CYCLES
    #[test]
    fn epoch_cycles_round_trip_and_not_measured_is_no_zero() {
        let mut measured = EpochCycles::NotMeasured;
        for (kind, cycles) in [
            (EpochKind::Snapshot, 1_200_000),
            (EpochKind::Snapshot, 900_000),
            (EpochKind::Araim, u32::MAX),
            (EpochKind::StreamForming, 0),
        ] {
            measured.record(kind, cycles);
        }
        assert_eq!(
            measured.get(EpochKind::Snapshot),
            Some(CycleSpan {
                last_cycles: 900_000,
                max_cycles: 1_200_000
            })
        );
        assert_eq!(measured.get(EpochKind::Pf), None);
        let zero = EpochCycles::Measured {
            snapshot: Some(CycleSpan {
                last_cycles: 0,
                max_cycles: 0,
            }),
            araim: None,
            pf: None,
            stream_forming: None,
        };
        let mut buf = [0u8; 512];
        let mut bytes = std::vec::Vec::new();
        for cycles in [
            EpochCycles::NotMeasured,
            EpochCycles::RUNNING,
            zero,
            measured,
        ] {
            let status = Status {
                epoch_cycles: cycles,
                ..Status::ZERO
            };
            let b = postcard::to_slice(&status, &mut buf).unwrap().to_vec();
            let back: Status = postcard::from_bytes(&b).unwrap();
            assert_eq!(back, status);
            bytes.push(b);
        }
        // Four different encodings: not measured, running with no epoch
        // yet, a zero count, and the counts.
        for i in 0..bytes.len() {
            for j in 0..i {
                assert_ne!(bytes[i], bytes[j], "{i} and {j}");
            }
        }
    }
}
