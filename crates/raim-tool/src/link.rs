//! `raim link`: talk to a unit over a real serial port (or a pty): send
//! Status, Configure or Lock framed as the firmware's link UART expects
//! (docs/PROTOCOL.md) and print each answer. The frames and the answers'
//! decoding are those of the QEMU runner (`raim_qemu::encode_request`,
//! `raim_proto::FrameReceiver`), over `serialport` instead of a socket.

use std::io::{Read, Write};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use clap::{Args, ValueEnum};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_proto::{FrameReceiver, MAX_RESPONSE_FRAME};

use crate::config_args::ConfigArgs;

/// How long an answer is waited for.
const ANSWER_TIMEOUT: Duration = Duration::from_secs(10);

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LinkCommand {
    // Ask for the unit's status.
    Status,
    // Send the monitor configuration of the options below.
    Configure,
    // Lock the configuration in force until the unit resets.
    Lock,
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
    /// What to send, in order (repeatable): status, configure, lock.
    #[arg(value_enum, required = true)]
    pub commands: Vec<LinkCommand>,
    #[command(flatten, next_help_heading = "Monitor (for configure; docs/CORE.md)")]
    pub config: ConfigArgs,
}

/// The link: frames out, answers in (boot notices printed and skipped).
struct Link {
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
}

pub fn run(args: &LinkArgs) -> Result<()> {
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
            LinkCommand::Lock => link.call(CommandRef::Lock)?,
        };
        let ok = matches!(
            (c, &r.body),
            (LinkCommand::Status, ResponseBody::Status(_))
                | (LinkCommand::Configure, ResponseBody::Configured)
                | (LinkCommand::Lock, ResponseBody::LockEngaged)
        );
        crate::outln!("{c:?}: {:?} (configuration {:?})", r.body, r.config)?;
        if !ok {
            bail!("{c:?} refused: {:?}", r.body);
        }
    }
    Ok(())
}
