//! `raim link`: talk to a unit over a real serial port (or a pty): send
//! Status, Configure, the model check's settings (ModelCheck) or Lock framed as the firmware's link UART expects
//! (docs/PROTOCOL.md) and print each answer. The frames and the answers'
//! decoding are those of the QEMU runner (`raim_qemu::encode_request`,
//! `raim_proto::FrameReceiver`), over `serialport` instead of a socket.
//!
//! `epochs` sends the epochs of a RINEX pair, an RTCM 3 or a UBX file,
//! built by the replay itself (`raim replay`'s options after `--`, the
//! same epoch builder, faults and window), and prints each answer as
//! `raim replay` prints its epochs (decision, protection levels,
//! exclusions), then the summary.

use std::cell::RefCell;
use std::io::{Read, Write};
use std::rc::Rc;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, Parser, ValueEnum};
use raim_core::{Config, Epoch};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_proto::result::WireResult;
use raim_proto::{EpochCycles, EpochKind, FrameReceiver, WireError, MAX_RESPONSE_FRAME};

use crate::config_args::ConfigArgs;
use crate::replay::engine::Engine;
use crate::replay::ReplayArgs;

/// How long an answer is waited for.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(10);

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LinkCommand {
    // Ask for the unit's status.
    Status,
    // Send the monitor configuration of the options below.
    Configure,
    // Send the model check's settings (--model-check-*; docs/MODEL_CHECK.md).
    ModelCheck,
    // Lock the configuration in force until the unit resets.
    Lock,
    // Send the epochs of the source given after `--` (raim replay's
    // options), configured as raim replay would run them.
    Epochs,
}

#[derive(Debug, Clone, Args)]
pub struct LinkArgs {
    /// The serial port of the unit's link UART (e.g. /dev/ttyUSB0, or a
    /// QEMU `-serial pty` device).
    #[arg(long, value_name = "PATH")]
    pub port: String,
    /// Baud rate (8N1).
    #[arg(long, default_value_t = 115_200)]
    pub baud: u32,
    /// What to send, in order (repeatable): status, configure,
    /// model-check, lock, epochs.
    #[arg(value_enum, required = true)]
    pub commands: Vec<LinkCommand>,
    #[command(flatten, next_help_heading = "Monitor (for configure; docs/CORE.md)")]
    pub config: ConfigArgs,
    #[command(
        flatten,
        next_help_heading = "Model check (for model-check; docs/MODEL_CHECK.md)"
    )]
    pub model_check: ModelCheckSettings,
    /// For `epochs`: `raim replay`'s options after `--` (the source:
    /// --obs/--nav, --rtcm3 FILE or --ubx FILE; --systems, --fault,
    /// --start/--end, --json, ... and the monitor options the epochs are
    /// configured with).
    #[arg(last = true, value_name = "REPLAY_OPTIONS")]
    pub replay: Vec<String>,
}

/// The settings `model-check` sends (`raim_proto::WireModelCheckConfig`;
/// the defaults are the unit's). The unit checks them: a value out of its
/// bounds is refused with the field and the value, and the settings in
/// force stay.
#[derive(Debug, Clone, Args)]
pub struct ModelCheckSettings {
    /// Least time between two samples, s ([1e-3, 86400]).
    #[arg(long, default_value_t = raim_proto::WireModelCheckConfig::DEFAULT.spacing_s)]
    pub model_check_spacing_s: f64,
    /// Samples in the window (1 to 16, the unit's capacity).
    #[arg(long, default_value_t = raim_proto::WireModelCheckConfig::DEFAULT.window)]
    pub model_check_window: u32,
    /// Allocated false-declaration probability per hour ([1e-12, 0.5]).
    #[arg(long, default_value = "1e-6")]
    pub model_check_pfa_hour: f64,
}

impl ModelCheckSettings {
    /// The settings on the wire.
    pub fn wire(&self) -> raim_proto::WireModelCheckConfig {
        raim_proto::WireModelCheckConfig {
            spacing_s: self.model_check_spacing_s,
            window: self.model_check_window,
            p_fa_per_hour: self.model_check_pfa_hour,
        }
    }
}

/// `raim replay`'s options, parsed on their own for `epochs`.
#[derive(Debug, Parser)]
#[command(name = "raim link ... epochs --", no_binary_name = true)]
struct ReplayOptions {
    #[command(flatten)]
    args: ReplayArgs,
}

/// `Status.epoch_cycles` for a reader: per kind of epoch, the last and
/// the largest core clock cycles since the unit's reset and, with the
/// unit's clock, the time they take; or that the unit has no running
/// cycle counter (QEMU), which is not a zero count.
pub fn epoch_cycles_line(cycles: &EpochCycles, core_clock_hz: u32) -> String {
    if *cycles == EpochCycles::NotMeasured {
        return "epoch cycles: not measured (the unit's cycle counter does not run)".into();
    }
    let ms = |c: u32| {
        if core_clock_hz == 0 {
            String::new()
        } else {
            format!(" ({:.2} ms)", f64::from(c) / f64::from(core_clock_hz) * 1e3)
        }
    };
    let parts: Vec<String> = [
        ("snapshot", EpochKind::Snapshot),
        ("araim", EpochKind::Araim),
        ("pf", EpochKind::Pf),
        ("stream forming", EpochKind::StreamForming),
    ]
    .into_iter()
    .map(|(name, kind)| match cycles.get(kind) {
        Some(s) => format!(
            "{name} last {}{} max {}{}",
            s.last_cycles,
            ms(s.last_cycles),
            s.max_cycles,
            ms(s.max_cycles)
        ),
        None => format!("{name} none yet"),
    })
    .collect();
    format!("epoch cycles at {} Hz: {}", core_clock_hz, parts.join(", "))
}

/// The link: frames out, answers in (boot notices printed and skipped).
pub struct Link {
    port: Box<dyn serialport::SerialPort>,
    frames: Box<FrameReceiver<MAX_RESPONSE_FRAME>>,
    seq: u32,
}

impl Link {
    fn answer(&mut self, seq: u32) -> Result<Response> {
        let deadline = Instant::now() + ANSWER_TIMEOUT;
        let mut buf = [0u8; 512];
        while Instant::now() < deadline {
            let n = match self.port.read(&mut buf) {
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => 0,
                Err(e) => return Err(e).context("reading the link"),
            };
            for &b in buf.get(..n).unwrap_or(&[]) {
                let Some(item) = self.frames.push(b) else {
                    continue;
                };
                let r: Response = match item {
                    Ok(p) => postcard::from_bytes(p).map_err(|e| anyhow!("bad answer: {e}"))?,
                    Err(e) => {
                        crate::outln!("frame error: {e}")?;
                        continue;
                    }
                };
                if let ResponseBody::Boot(b) = &r.body {
                    crate::outln!("boot notice: {b:?}")?;
                    continue;
                }
                // A sequence-gap notice comes before the answer it concerns
                // (the unit saw a new host's first number).
                let gap = matches!(
                    r.body,
                    ResponseBody::Error(raim_proto::WireError::SequenceGap { .. })
                );
                if gap {
                    crate::outln!("notice: {:?}", r.body)?;
                    continue;
                }
                if r.seq == Some(seq) {
                    return Ok(r);
                }
                crate::outln!("answer to another request ({:?}): {:?}", r.seq, r.body)?;
            }
        }
        bail!("no answer to request {seq} within {ANSWER_TIMEOUT:?}")
    }

    fn call(&mut self, command: CommandRef<'_>) -> Result<Response> {
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        let f = raim_qemu::encode_request(&RequestRef { seq, command })?;
        self.port.write_all(&f).context("writing the link")?;
        self.port.flush()?;
        self.answer(seq)
    }

    /// One epoch on the unit: its result, or its typed refusal as text (as
    /// `Engine::process` gives it); an answer of another kind is an error.
    pub fn process(
        &mut self,
        epoch: &Epoch<'_>,
    ) -> Result<std::result::Result<WireResult, String>> {
        let r = self.call(raim_qemu::epoch_command(epoch))?;
        match r.body {
            ResponseBody::Result(w) => Ok(Ok(w)),
            ResponseBody::Error(e) => Ok(Err(e.to_string())),
            other => bail!("epoch answered with {other:?}"),
        }
    }

    /// Configure the unit for a run of epochs. A unit locked on another
    /// configuration refuses; the epochs then run with the locked one,
    /// and a notice says so (its decisions may differ from `raim replay`'s).
    pub(crate) fn configure_for_epochs(&mut self, cfg: &Config) -> Result<()> {
        let r = self.call(CommandRef::Configure(cfg))?;
        match r.body {
            ResponseBody::Configured => Ok(()),
            ResponseBody::Error(e @ WireError::Locked { .. }) => {
                eprintln!(
                    "raim: link: {e}: the epochs run with the unit's locked configuration, not the replay's"
                );
                Ok(())
            }
            other => bail!("Configure for the epochs refused: {other:?}"),
        }
    }
}

/// `epochs`: the replay's epochs (its builder, faults and window) run on
/// the unit, one fresh configuration per run as `raim replay` starts a
/// fresh engine, and printed as `raim replay` prints them.
fn epochs(link: Link, args: &ReplayArgs) -> Result<Link> {
    let shared = Rc::new(RefCell::new(link));
    let mut start = |cfg: &Config| {
        shared.borrow_mut().configure_for_epochs(cfg)?;
        Ok(Engine::Link(shared.clone()))
    };
    match crate::replay::receiver::source(args)? {
        // A live source (TCP, serial): each epoch sent to the unit as it
        // arrives, printed as `raim replay` prints a live source's.
        Some((format, spec)) if spec.is_live() => {
            let _tally = crate::replay::receiver::run_live_on(args, format, &spec, &mut start)?;
        }
        _ => {
            let out = crate::replay::replay_on(args, &mut start)?;
            crate::replay::write_outputs(args, &out)?;
        }
    }
    Rc::try_unwrap(shared)
        .map(RefCell::into_inner)
        .map_err(|_| anyhow!("the link is still in use"))
}

/// `raim replay`'s options for `epochs`, checked before the port is opened.
fn epoch_options(replay: &[String]) -> Result<ReplayArgs> {
    if replay.is_empty() {
        bail!("epochs: give raim replay's options after `--`, e.g. `raim link --port P epochs -- --rtcm3 FILE --systems GR`");
    }
    let opts = ReplayOptions::try_parse_from(replay).map_err(|e| anyhow!("epochs: {e}"))?;
    let args = opts.args;
    if args.run_config.is_some() {
        bail!("epochs: a run file (--config) is read by raim replay only; give its options after `--`");
    }
    if args.araim.araim || args.pf.pf.is_some() || args.esq.any() {
        bail!(
            "epochs: the unit runs the snapshot monitor; --araim, --pf and --esq are replay-only"
        );
    }
    Ok(args)
}

pub fn run(args: &LinkArgs) -> Result<()> {
    if !args.replay.is_empty() && !args.commands.contains(&LinkCommand::Epochs) {
        bail!("options after `--` are for `epochs`, which is not among the commands");
    }
    let replay = if args.commands.contains(&LinkCommand::Epochs) {
        Some(epoch_options(&args.replay)?)
    } else {
        None
    };
    let port = serialport::new(&args.port, args.baud)
        .timeout(Duration::from_millis(100))
        .open()
        .with_context(|| format!("opening {}", args.port))?;
    let mut link = Link {
        port,
        frames: Box::new(FrameReceiver::new()),
        seq: 1,
    };
    let cfg = args.config.config();
    for c in &args.commands {
        let r = match c {
            LinkCommand::Status => link.call(CommandRef::Status)?,
            LinkCommand::Configure => link.call(CommandRef::Configure(&cfg))?,
            LinkCommand::ModelCheck => {
                link.call(CommandRef::ModelCheck(args.model_check.wire()))?
            }
            LinkCommand::Lock => link.call(CommandRef::Lock)?,
            LinkCommand::Epochs => {
                if let Some(r) = &replay {
                    link = epochs(link, r)?;
                }
                continue;
            }
        };
        let ok = matches!(
            (c, &r.body),
            (LinkCommand::Status, ResponseBody::Status(_))
                | (LinkCommand::Configure, ResponseBody::Configured)
                | (LinkCommand::ModelCheck, ResponseBody::Configured)
                | (LinkCommand::Lock, ResponseBody::LockEngaged)
        );
        crate::outln!("{c:?}: {:?} (configuration {:?})", r.body, r.config)?;
        if let ResponseBody::Status(st) = &r.body {
            crate::outln!("{}", epoch_cycles_line(&st.epoch_cycles, st.core_clock_hz))?;
        }
        if !ok {
            bail!("{c:?} refused: {:?}", r.body);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `raim link model-check` sends the settings its options give, the
    /// unit's defaults for the ones not given.
    ///
    /// Verifies: MODEL-CONFIG
    #[test]
    fn model_check_settings_come_from_the_options_with_the_units_defaults() {
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            link: LinkArgs,
        }
        let parse = |extra: &[&str]| {
            let mut argv = vec!["raim", "--port", "/dev/null", "model-check"];
            argv.extend_from_slice(extra);
            Cli::try_parse_from(argv).unwrap().link
        };
        let d = parse(&[]);
        assert_eq!(d.commands, [LinkCommand::ModelCheck]);
        assert_eq!(
            d.model_check.wire(),
            raim_proto::WireModelCheckConfig::DEFAULT
        );
        let w = parse(&[
            "--model-check-window",
            "4",
            "--model-check-pfa-hour",
            "1e-3",
        ]);
        assert_eq!(
            w.model_check.wire(),
            raim_proto::WireModelCheckConfig {
                window: 4,
                p_fa_per_hour: 1e-3,
                ..raim_proto::WireModelCheckConfig::DEFAULT
            }
        );
    }

    /// `raim link status` prints the unit's epoch cycles per kind, with
    /// their time at the unit's clock, and says when they are not
    /// measured rather than printing zeros.
    ///
    /// Verifies: FW-CYCLES
    #[test]
    fn epoch_cycles_are_printed_per_kind_and_not_measured_is_said() {
        assert_eq!(
            epoch_cycles_line(&EpochCycles::NotMeasured, 16_000_000),
            "epoch cycles: not measured (the unit's cycle counter does not run)"
        );
        let mut c = EpochCycles::NotMeasured;
        c.record(EpochKind::Snapshot, 1_680_000);
        c.record(EpochKind::Snapshot, 840_000);
        c.record(EpochKind::StreamForming, 16_800);
        assert_eq!(
            epoch_cycles_line(&c, 168_000_000),
            "epoch cycles at 168000000 Hz: snapshot last 840000 (5.00 ms) max 1680000 (10.00 ms), \
             araim none yet, pf none yet, stream forming last 16800 (0.10 ms) max 16800 (0.10 ms)"
        );
        assert_eq!(
            epoch_cycles_line(&EpochCycles::RUNNING, 0),
            "epoch cycles at 0 Hz: snapshot none yet, araim none yet, pf none yet, stream forming none yet"
        );
    }
}
