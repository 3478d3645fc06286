//! Runs the RAIM firmware under `qemu-system-arm` and talks to it: the
//! link UART and the NMEA UART are Unix sockets QEMU serves; semihosting
//! output (the firmware's defmt log, binary) goes to a log file. Two
//! machines ([`Machine`], `Options::machine`): `mps2-an386` (default; UART0
//! and UART1) and `netduinoplus2`, an STM32F405 running the real-board
//! build (USART2 and USART3).
//!
//! ```no_run
//! # fn main() -> anyhow::Result<()> {
//! use raim_qemu::{firmware_elf, QemuSession};
//! let elf = firmware_elf()?; // builds firmware/ if needed
//! let mut fw = QemuSession::start(&elf)?;
//! fw.configure(&raim_core::Config::default())?;
//! # let sats: Vec<raim_core::LinearObservation> = vec![];
//! let answer = fw.process(&raim_core::Epoch::linear(0.0, &sats))?;
//! println!("{:?} {:?}", answer.outcome, answer.nmea);
//! # Ok(()) }
//! ```

use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use raim_core::{Config, Epoch, Observations};
use raim_proto::frame::{encode, FrameError, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody, Status};
use raim_proto::unit::{UnitConfig, PROVISION_BYTES};
use raim_proto::{
    BootNotice, ConfigId, ConfigSource, WireError, WireResult, MAX_REQUEST_FRAME,
    MAX_RESPONSE_FRAME,
};

pub mod tied;

/// How long an answer may take (QEMU on a loaded 2-core machine; an epoch
/// takes milliseconds).
pub const ANSWER_TIMEOUT: Duration = Duration::from_secs(30);

/// The repository root (this crate is `crates/raim-qemu`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Path of the release firmware ELF (built by `build_firmware`).
pub fn firmware_elf_path() -> PathBuf {
    repo_root().join("firmware/target/thumbv7em-none-eabihf/release/raim-firmware")
}

/// `cd firmware && cargo build --release` (a no-op when up to date).
pub fn build_firmware() -> Result<PathBuf> {
    cargo_in_firmware(&["build", "--release", "--quiet"])?;
    Ok(firmware_elf_path())
}

/// Run cargo in `firmware/` (its own workspace).
fn cargo_in_firmware(args: &[&str]) -> Result<()> {
    cargo_in_firmware_with(args, &[])
}

/// `cargo_in_firmware` with build settings in the environment.
fn cargo_in_firmware_with(args: &[&str], envs: &[(&str, &str)]) -> Result<()> {
    let dir = repo_root().join("firmware");
    let mut cmd = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()));
    cmd.current_dir(&dir).args(args).envs(envs.iter().copied());
    // Settings of an outer cargo (e.g. under `cargo test`) must not leak
    // into the firmware's own workspace.
    for (k, _) in std::env::vars_os() {
        let k = k.to_string_lossy().into_owned();
        if k.starts_with("CARGO_BUILD_")
            || k == "CARGO_TARGET_DIR"
            || k == "RUSTFLAGS"
            || k == "CARGO_ENCODED_RUSTFLAGS"
        {
            cmd.env_remove(k);
        }
    }
    let st = cmd
        .status()
        .with_context(|| format!("running cargo in {}", dir.display()))?;
    if !st.success() {
        bail!("firmware build failed ({st})");
    }
    Ok(())
}

/// The firmware ELF: `$RAIM_FIRMWARE_ELF` if set, else built from `firmware/`.
pub fn firmware_elf() -> Result<PathBuf> {
    match std::env::var_os("RAIM_FIRMWARE_ELF") {
        Some(p) => Ok(PathBuf::from(p)),
        None => build_firmware(),
    }
}

/// A copy of the firmware ELF `elf` with `key` written into its `.raim_key`
/// section (firmware/src/key.rs), as production provisions a unit: the
/// unit then takes only authenticated configurations. Written next to the
/// original as `<name>.key-<first bytes in hex>`.
pub fn provision_key(elf: &Path, key: &raim_proto::AuthKey) -> Result<PathBuf> {
    let mut bytes = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let (offset, size) = elf32_section(&bytes, ".raim_key")
        .with_context(|| format!("no .raim_key section in {}", elf.display()))?;
    if size != key.len() {
        bail!(".raim_key is {size} bytes, the key {}", key.len());
    }
    bytes
        .get_mut(offset..offset + size)
        .context(".raim_key outside the file")?
        .copy_from_slice(key);
    let hex: String = key.iter().take(4).map(|b| format!("{b:02x}")).collect();
    let out = elf.with_extension(format!("key-{hex}"));
    std::fs::write(&out, bytes)?;
    Ok(out)
}

/// A copy of the firmware ELF `elf` with `unit` sealed into its
/// `.raim_config` section (firmware/src/provision.rs): the installation
/// step. The seal is an HMAC under `key` when the unit has one (it must be
/// the key of its `.raim_key`), SHA-256 otherwise. Written next to `elf` as
/// `<name>.<tag>`.
pub fn provision_config(
    elf: &Path,
    unit: &UnitConfig,
    key: Option<&raim_proto::AuthKey>,
    tag: &str,
) -> Result<PathBuf> {
    let mut blob = [0u8; PROVISION_BYTES];
    raim_proto::unit::seal(unit, key, &mut blob)
        .map_err(|e| anyhow!("sealing the unit configuration: {e:?}"))?;
    write_section(elf, ".raim_config", &blob, tag)
}

/// A copy of `elf` with the bytes of section `name` replaced by `bytes`
/// (same size), written as `<elf>.<tag>`.
pub fn write_section(elf: &Path, name: &str, bytes: &[u8], tag: &str) -> Result<PathBuf> {
    let mut image = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let (offset, size) = elf32_section(&image, name)
        .with_context(|| format!("no {name} section in {}", elf.display()))?;
    if size != bytes.len() {
        bail!("{name} is {size} bytes, the data {}", bytes.len());
    }
    image
        .get_mut(offset..offset + size)
        .with_context(|| format!("{name} outside the file"))?
        .copy_from_slice(bytes);
    let out = elf.with_extension(tag);
    std::fs::write(&out, image)?;
    Ok(out)
}

/// File offset and size of a section of a little-endian ELF32 file.
fn elf32_section(elf: &[u8], name: &str) -> Option<(usize, usize)> {
    let u16_at = |o: usize| Some(u16::from_le_bytes(elf.get(o..o + 2)?.try_into().ok()?) as usize);
    let u32_at = |o: usize| Some(u32::from_le_bytes(elf.get(o..o + 4)?.try_into().ok()?) as usize);
    if elf.get(..6)? != b"\x7fELF\x01\x01" {
        return None;
    }
    let (shoff, shentsize, shnum, shstrndx) =
        (u32_at(0x20)?, u16_at(0x2E)?, u16_at(0x30)?, u16_at(0x32)?);
    let header = |i: usize| shoff + i * shentsize;
    let strtab = u32_at(header(shstrndx) + 16)?;
    (0..shnum).find_map(|i| {
        let h = header(i);
        let start = strtab + u32_at(h)?;
        let end = start + elf.get(start..)?.iter().position(|&b| b == 0)?;
        (elf.get(start..end)? == name.as_bytes()).then_some((u32_at(h + 16)?, u32_at(h + 20)?))
    })
}

/// The value of symbol `name` in a little-endian ELF32 file's symbol
/// table (the linker script's absolute symbols included).
pub fn elf32_symbol(elf: &[u8], name: &str) -> Option<u32> {
    let u16_at = |o: usize| Some(u16::from_le_bytes(elf.get(o..o + 2)?.try_into().ok()?) as usize);
    let u32_at = |o: usize| Some(u32::from_le_bytes(elf.get(o..o + 4)?.try_into().ok()?));
    let at = |o: usize| u32_at(o).map(|v| v as usize);
    if elf.get(..6)? != b"\x7fELF\x01\x01" {
        return None;
    }
    let (shoff, shentsize, shnum) = (at(0x20)?, u16_at(0x2E)?, u16_at(0x30)?);
    let header = |i: usize| shoff + i * shentsize;
    // SHT_SYMTAB = 2; its sh_link is the string table's index.
    let symtab = (0..shnum).find(|&i| at(header(i) + 4) == Some(2))?;
    let (off, size, link) = (
        at(header(symtab) + 16)?,
        at(header(symtab) + 20)?,
        at(header(symtab) + 24)?,
    );
    let strtab = at(header(link) + 16)?;
    (0..size / 16).find_map(|k| {
        let sym = off + 16 * k;
        let start = strtab + at(sym)?;
        let end = start + elf.get(start..)?.iter().position(|&b| b == 0)?;
        (elf.get(start..end)? == name.as_bytes())
            .then(|| u32_at(sym + 4))
            .flatten()
    })
}

/// The boot counter's flash region of a firmware ELF (`RAIM_BOOT` in
/// memory.x: `__raim_boot_start`, `__raim_boot_end`): its address and
/// length, bytes.
pub fn boot_region(elf: &Path) -> Result<(u32, u32)> {
    let bytes = std::fs::read(elf).with_context(|| format!("reading {}", elf.display()))?;
    let start = elf32_symbol(&bytes, "__raim_boot_start").context("no __raim_boot_start")?;
    let end = elf32_symbol(&bytes, "__raim_boot_end").context("no __raim_boot_end")?;
    Ok((
        start,
        end.checked_sub(start)
            .context("__raim_boot_end below its start")?,
    ))
}

/// The machine QEMU emulates, and the firmware build that runs on it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Machine {
    /// `mps2-an386` (Cortex-M4, CMSDK UARTs): the default build
    /// (`board-qemu`), with test hooks, semihosting and the FPGA LED as the
    /// alarm output.
    #[default]
    Mps2An386,
    /// `netduinoplus2` (an STM32F405): the real-board build
    /// (`board-stm32f4`). QEMU models its USARTs (USART2 is the second
    /// `-serial`, USART3 the third) but not its RCC, GPIO or IWDG.
    NetduinoPlus2,
}

impl Machine {
    /// Both machines, for tests that run on each.
    pub const ALL: [Machine; 2] = [Machine::Mps2An386, Machine::NetduinoPlus2];

    /// QEMU's `-machine` name.
    pub fn qemu_name(self) -> &'static str {
        match self {
            Machine::Mps2An386 => "mps2-an386",
            Machine::NetduinoPlus2 => "netduinoplus2",
        }
    }

    /// `-serial` ports before the link UART (netduinoplus2: USART1).
    fn serials_before_link(self) -> usize {
        match self {
            Machine::Mps2An386 => 0,
            Machine::NetduinoPlus2 => 1,
        }
    }

    /// Where `firmware_elf_for` builds this machine's firmware.
    pub fn elf_path(self) -> PathBuf {
        match self {
            Machine::Mps2An386 => firmware_elf_path(),
            Machine::NetduinoPlus2 => repo_root()
                .join("firmware/target/stm32f4/thumbv7em-none-eabihf/release/raim-firmware"),
        }
    }
}

/// The pause on the link of the netduinoplus2 build and of the
/// mps2-an386 streaming build ([`firmware_elf_stream`]), s (the firmware's
/// test-only build setting `RAIM_TEST_LINK_IDLE_S`): QEMU's guest clock is
/// the host's, so with the unit's 0.25 s a host that does not run QEMU for
/// that long between two bytes of one frame cuts it (docs/EVIDENCE.md
/// "The suite under load"); these builds' tests cut no frame on purpose.
pub const NETDUINOPLUS2_LINK_IDLE_S: &str = "30";

/// The firmware ELF for `machine`: for mps2-an386 as `firmware_elf`; for
/// netduinoplus2 `$RAIM_FIRMWARE_ELF_STM32F4` if set, else the STM32F4
/// build for QEMU's model (`--features board-stm32f4,qemu-netduinoplus2`:
/// its CCM region where QEMU maps RAM; with a link pause of
/// [`NETDUINOPLUS2_LINK_IDLE_S`]; into `firmware/target/stm32f4`, as
/// scripts/test.sh builds it).
pub fn firmware_elf_for(machine: Machine) -> Result<PathBuf> {
    match machine {
        Machine::Mps2An386 => firmware_elf(),
        Machine::NetduinoPlus2 => match std::env::var_os("RAIM_FIRMWARE_ELF_STM32F4") {
            Some(p) => Ok(PathBuf::from(p)),
            None => {
                cargo_in_firmware_with(
                    &[
                        "build",
                        "--release",
                        "--quiet",
                        "--no-default-features",
                        "--features",
                        "board-stm32f4,qemu-netduinoplus2",
                        "--target-dir",
                        "target/stm32f4",
                    ],
                    &[("RAIM_TEST_LINK_IDLE_S", NETDUINOPLUS2_LINK_IDLE_S)],
                )?;
                Ok(machine.elf_path())
            }
        },
    }
}

/// The STM32F4 build with the RTCM 3 stream receiver, for QEMU's
/// netduinoplus2 (`--features board-stm32f4,qemu-netduinoplus2,rtcm`: the
/// part's 24-satellite capacities and shared scratch, docs/FLASH.md
/// "STM32F4: the stream"; with a link pause of
/// [`NETDUINOPLUS2_LINK_IDLE_S`], into `firmware/target/stm32f4-stream`):
/// `$RAIM_FIRMWARE_ELF_STM32F4_STREAM` if set (scripts/test.sh builds it
/// into the shared target and sets it).
pub fn firmware_elf_stm32f4_stream() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("RAIM_FIRMWARE_ELF_STM32F4_STREAM") {
        return Ok(PathBuf::from(p));
    }
    cargo_in_firmware_with(
        &[
            "build",
            "--release",
            "--quiet",
            "--no-default-features",
            "--features",
            "board-stm32f4,qemu-netduinoplus2,rtcm",
            "--target-dir",
            "target/stm32f4-stream",
        ],
        &[("RAIM_TEST_LINK_IDLE_S", NETDUINOPLUS2_LINK_IDLE_S)],
    )?;
    Ok(repo_root()
        .join("firmware/target/stm32f4-stream/thumbv7em-none-eabihf/release/raim-firmware"))
}

/// The firmware ELF for the streaming tests on `machine`: the tests that
/// write a long stream into the link and check every answer. On
/// mps2-an386 the default build with a pause on the link of
/// [`NETDUINOPLUS2_LINK_IDLE_S`] (`RAIM_TEST_LINK_IDLE_S`, into
/// `firmware/target/stream`, as scripts/test.sh builds it):
/// `$RAIM_FIRMWARE_ELF_STREAM` if set. On netduinoplus2 its build of
/// [`firmware_elf_for`], which has that pause already. The unit's own
/// 0.25 s pause is checked on the default build (docs/EVIDENCE.md "The
/// suite under load").
pub fn firmware_elf_stream(machine: Machine) -> Result<PathBuf> {
    match machine {
        Machine::NetduinoPlus2 => firmware_elf_for(machine),
        Machine::Mps2An386 => {
            if let Some(p) = std::env::var_os("RAIM_FIRMWARE_ELF_STREAM") {
                return Ok(PathBuf::from(p));
            }
            cargo_in_firmware_with(
                &[
                    "build",
                    "--release",
                    "--quiet",
                    "--target-dir",
                    "target/stream",
                ],
                &[("RAIM_TEST_LINK_IDLE_S", NETDUINOPLUS2_LINK_IDLE_S)],
            )?;
            Ok(repo_root()
                .join("firmware/target/stream/thumbv7em-none-eabihf/release/raim-firmware"))
        }
    }
}

/// The QEMU board's build without the default `araim`, `pf` and
/// `multifault` features (`--no-default-features --features board-qemu`,
/// into `firmware/target/snapshot`, as scripts/test.sh builds it): the
/// configuration whose flash docs/FLASH.md bounds
/// (host-tests/tests/qemu_flash.rs). `$RAIM_FIRMWARE_ELF_SNAPSHOT` if set.
pub fn firmware_elf_snapshot() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("RAIM_FIRMWARE_ELF_SNAPSHOT") {
        return Ok(PathBuf::from(p));
    }
    cargo_in_firmware(&[
        "build",
        "--release",
        "--quiet",
        "--no-default-features",
        "--features",
        "board-qemu",
        "--target-dir",
        "target/snapshot",
    ])?;
    Ok(repo_root().join("firmware/target/snapshot/thumbv7em-none-eabihf/release/raim-firmware"))
}

/// Options of the emulator.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// `-icount shift=0`: one guest instruction per virtual nanosecond, so
    /// the firmware's SysTick (25 MHz) ticks once per 40 instructions.
    pub icount: bool,
    /// Where QEMU's semihosting output (the defmt log) goes; default: a file
    /// in the session's temporary directory.
    pub log: Option<PathBuf>,
    /// The machine (default mps2-an386); the ELF must be its build
    /// (`firmware_elf_for`).
    pub machine: Machine,
    /// Leave an unconfigured, unkeyed unit as it booted. By default the
    /// session sets such a unit up as a bench host would, with a runtime
    /// `Configure(Config::default())` right after its boot notice.
    pub raw: bool,
    /// The boot counter's flash as an earlier session left it
    /// ([`QemuSession::save_boot_region`]), loaded into its region before
    /// the unit starts (`-device loader`): with it, a new session is the
    /// same unit after a power cycle. QEMU keeps no memory across runs
    /// itself, so this models the flash's persistence (docs/SAFETY.md
    /// "Boot counter").
    pub boot_region: Option<(PathBuf, u32)>,
    /// Serve QEMU's QMP on a socket (for `save_boot_region`).
    pub qmp: bool,
}

/// One epoch's answer.
#[derive(Debug, Clone)]
pub struct Processed {
    pub seq: u32,
    pub outcome: Result<WireResult, WireError>,
    /// Sequence-gap notices that came before the answer.
    pub notices: Vec<WireError>,
    /// The NMEA sentences of the epoch (`$...*hh`, without CRLF); empty
    /// when the epoch was rejected.
    pub nmea: Vec<String>,
}

/// A running firmware under QEMU.
pub struct QemuSession {
    child: Child,
    link: UnixStream,
    responses: Receiver<Result<Response, String>>,
    nmea: Receiver<String>,
    next_seq: u32,
    dir: PathBuf,
    log: PathBuf,
    /// The configuration fingerprint and lock state of the last answer.
    last_config: Option<ConfigId>,
    /// Every boot notice received, in order (one per boot of the unit).
    boots: Vec<BootNotice>,
    /// QEMU's QMP socket, when `Options::qmp`.
    qmp: Option<PathBuf>,
    /// Keep the session's directory (its semihosting log and QEMU's
    /// stderr) when dropped: set once an error has named the log.
    keep_dir: bool,
}

static SESSION_COUNTER: AtomicU32 = AtomicU32::new(0);

fn connect(path: &Path, child: &mut Child, deadline: Instant) -> Result<UnixStream> {
    loop {
        match UnixStream::connect(path) {
            Ok(s) => return Ok(s),
            Err(e) => {
                if let Some(st) = child.try_wait()? {
                    bail!("qemu exited ({st}) before serving {}", path.display());
                }
                if Instant::now() > deadline {
                    bail!("cannot connect to {}: {e}", path.display());
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
}

impl QemuSession {
    pub fn start(elf: &Path) -> Result<Self> {
        Self::start_with(elf, &Options::default())
    }

    pub fn start_with(elf: &Path, opts: &Options) -> Result<Self> {
        if !elf.exists() {
            bail!("no firmware ELF at {}", elf.display());
        }
        let n = SESSION_COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("raim-qemu-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let (s0, s1) = (dir.join("uart0.sock"), dir.join("uart1.sock"));
        for s in [&s0, &s1] {
            let _ = std::fs::remove_file(s);
        }
        let log = opts
            .log
            .clone()
            .unwrap_or_else(|| dir.join("semihosting.log"));
        let mut cmd = Command::new("qemu-system-arm");
        cmd.args(["-machine", opts.machine.qemu_name()]);
        if opts.machine == Machine::Mps2An386 {
            cmd.args(["-cpu", "cortex-m4"]);
        }
        cmd.args(["-nographic", "-monitor", "none"])
            .args(["-semihosting-config", "enable=on,target=native"]);
        for _ in 0..opts.machine.serials_before_link() {
            cmd.args(["-serial", "null"]);
        }
        cmd.args([
            "-chardev",
            &format!("socket,id=u0,path={},server=on,wait=on", s0.display()),
        ])
        .args([
            "-chardev",
            &format!("socket,id=u1,path={},server=on,wait=on", s1.display()),
        ])
        .args(["-serial", "chardev:u0", "-serial", "chardev:u1"]);
        if opts.icount {
            cmd.args(["-icount", "shift=0"]);
        }
        let qmp = opts.qmp.then(|| dir.join("qmp.sock"));
        if let Some(q) = &qmp {
            let _ = std::fs::remove_file(q);
            cmd.args(["-qmp", &format!("unix:{},server=on,wait=off", q.display())]);
        }
        if let Some((file, addr)) = &opts.boot_region {
            cmd.args([
                "-device",
                &format!("loader,file={},addr={addr:#x},force-raw=on", file.display()),
            ]);
        }
        cmd.arg("-kernel").arg(elf);
        cmd.stdin(Stdio::null())
            .stdout(std::fs::File::create(&log)?)
            .stderr(std::fs::File::create(dir.join("qemu.stderr"))?);
        let mut child = tied::spawn(cmd)
            .context("starting qemu-system-arm (apt-get install qemu-system-arm)")?;
        let deadline = Instant::now() + Duration::from_secs(20);
        let link = match connect(&s0, &mut child, deadline)
            .and_then(|l| Ok((l, connect(&s1, &mut child, deadline)?)))
        {
            Ok(v) => v,
            Err(e) => {
                let _ = child.kill();
                let _ = child.wait();
                let stderr = std::fs::read_to_string(dir.join("qemu.stderr")).unwrap_or_default();
                return Err(e.context(stderr));
            }
        };
        let (link, nmea_sock) = link;
        let responses = spawn_link_reader(link.try_clone()?);
        let nmea = spawn_nmea_reader(nmea_sock);
        let mut session = QemuSession {
            child,
            link,
            responses,
            nmea,
            next_seq: 0,
            dir,
            log,
            last_config: None,
            boots: Vec::new(),
            keep_dir: false,
            qmp,
        };
        // The boot notice, on both machines. On netduinoplus2 the runner
        // then also sends `Status` until one is answered: QEMU's STM32
        // USART model drops bytes that arrive before the firmware enables
        // its receiver (docs/SAFETY.md).
        session.wait_boot(ANSWER_TIMEOUT)?;
        if opts.machine == Machine::NetduinoPlus2 {
            session.sync()?;
        }
        let bench = if opts.raw {
            false
        } else if let Some(b) = session.boots.last().copied() {
            !b.auth_provisioned && b.config.source == ConfigSource::Unconfigured
        } else {
            let s = session.status()?;
            !s.auth_provisioned && s.config.source == ConfigSource::Unconfigured
        };
        if bench {
            session.configure(&Config::default())?;
        }
        Ok(session)
    }

    /// Wait for the unit's next boot notice (the first frame after every
    /// reset) and return as soon as it arrives; frames before it, and
    /// frames that do not decode (a reset may cut one), are dropped.
    /// `timeout` is a deadline only a hung or silent unit reaches.
    pub fn wait_boot(&mut self, timeout: Duration) -> Result<BootNotice> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                bail!("no boot notice within {timeout:?}");
            }
            match self.responses.recv_timeout(left) {
                Ok(Ok(r)) => {
                    if let ResponseBody::Boot(b) = r.body {
                        self.last_config = Some(r.config);
                        self.boots.push(b);
                        return Ok(b);
                    }
                }
                Ok(Err(_)) => {}
                Err(RecvTimeoutError::Timeout) => bail!("no boot notice within {timeout:?}"),
                Err(RecvTimeoutError::Disconnected) => {
                    let st = self.child.try_wait().ok().flatten();
                    self.keep_dir = true;
                    bail!(
                        "the firmware's link closed before its boot notice (qemu status {st:?}); log {}",
                        self.log.display()
                    )
                }
            }
        }
    }

    /// The boot notices received so far, oldest first.
    pub fn boots(&self) -> &[BootNotice] {
        &self.boots
    }

    /// Wait until the firmware answers. QEMU's STM32 USART model drops the
    /// bytes that arrive before the firmware has enabled the receiver (the
    /// CMSDK UART of mps2-an386 holds them back instead), so a frame sent
    /// at once may be lost: send `Status` until one is answered, then let
    /// late answers to earlier attempts drain.
    fn sync(&mut self) -> Result<()> {
        for _ in 0..40 {
            // A delimiter first ends whatever part of an earlier attempt
            // the firmware did receive.
            self.send_raw(&[0])?;
            let seq = self.send(CommandRef::Status)?;
            let deadline = Instant::now() + Duration::from_millis(500);
            while let Some(left) = deadline.checked_duration_since(Instant::now()) {
                match self.responses.recv_timeout(left) {
                    Ok(Ok(r)) if r.seq == Some(seq) => {
                        while self
                            .responses
                            .recv_timeout(Duration::from_millis(200))
                            .is_ok()
                        {}
                        return Ok(());
                    }
                    Ok(_) => {}
                    Err(RecvTimeoutError::Timeout) => break,
                    Err(RecvTimeoutError::Disconnected) => bail!("the firmware's link closed"),
                }
            }
        }
        bail!("the firmware never answered a Status frame")
    }

    /// The semihosting log file (binary defmt frames; decode with
    /// `defmt-print -e <elf>`).
    pub fn log_path(&self) -> &Path {
        &self.log
    }

    /// The next sequence number `send` will use.
    pub fn next_seq(&self) -> u32 {
        self.next_seq
    }

    /// Send raw bytes on the link (tests of corrupted streams).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<()> {
        self.link
            .write_all(bytes)
            .context("writing to the firmware's link UART")
    }

    /// Encode a request with the next sequence number; returns its frame.
    pub fn frame(&mut self, command: CommandRef<'_>) -> Result<(u32, Vec<u8>)> {
        let seq = self.next_seq;
        self.next_seq = self.next_seq.wrapping_add(1);
        Ok((seq, encode_request(&RequestRef { seq, command })?))
    }

    /// Send a request; returns its sequence number.
    pub fn send(&mut self, command: CommandRef<'_>) -> Result<u32> {
        let (seq, f) = self.frame(command)?;
        self.send_raw(&f)?;
        Ok(seq)
    }

    /// The next response frame (boot notices are kept, `boots`, and
    /// skipped).
    pub fn recv(&mut self, timeout: Duration) -> Result<Response> {
        let deadline = Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let r = self.recv_any(left)?;
            match r.body {
                ResponseBody::Boot(b) => {
                    self.last_config = Some(r.config);
                    self.boots.push(b);
                    if left.is_zero() {
                        bail!("no answer from the firmware within {timeout:?}");
                    }
                }
                _ => return Ok(r),
            }
        }
    }

    /// The next response frame, boot notices included.
    fn recv_any(&mut self, timeout: Duration) -> Result<Response> {
        match self.responses.recv_timeout(timeout) {
            Ok(Ok(r)) => Ok(r),
            Ok(Err(e)) => Err(anyhow!("bad response frame from the firmware: {e}")),
            Err(RecvTimeoutError::Timeout) => {
                Err(anyhow!("no answer from the firmware within {timeout:?}"))
            }
            Err(RecvTimeoutError::Disconnected) => {
                let st = self.child.try_wait().ok().flatten();
                self.keep_dir = true;
                Err(anyhow!(
                    "the firmware's link closed (qemu status {st:?}); log {}",
                    self.log.display()
                ))
            }
        }
    }

    /// Wait for the answer to `seq`, collecting gap notices before it.
    fn answer(&mut self, seq: u32) -> Result<(ResponseBody, Vec<WireError>)> {
        let mut notices = Vec::new();
        loop {
            let r = self.recv(ANSWER_TIMEOUT)?;
            self.last_config = Some(r.config);
            match (r.seq, r.body) {
                (Some(s), ResponseBody::Error(e @ WireError::SequenceGap { .. })) if s == seq => {
                    notices.push(e)
                }
                (Some(s), body) if s == seq => return Ok((body, notices)),
                (s, body) => bail!("expected the answer to {seq}, got {s:?}: {body:?}"),
            }
        }
    }

    /// Send any command and wait for its answer (sequence-gap notices
    /// before it are skipped).
    pub fn call(&mut self, command: CommandRef<'_>) -> Result<ResponseBody> {
        let seq = self.send(command)?;
        Ok(self.answer(seq)?.0)
    }

    pub fn status(&mut self) -> Result<Status> {
        let seq = self.send(CommandRef::Status)?;
        match self.answer(seq)?.0 {
            ResponseBody::Status(s) => Ok(s),
            other => bail!("status request answered with {other:?}"),
        }
    }

    /// The configuration fingerprint and lock state the last answer
    /// carried (every response has them; docs/PROTOCOL.md).
    pub fn last_config(&self) -> Option<ConfigId> {
        self.last_config
    }

    /// Send `Configure`; the firmware's typed refusal (`OutOfRange`,
    /// `Locked`) is the inner error.
    pub fn try_configure(&mut self, cfg: &Config) -> Result<Result<(), WireError>> {
        let seq = self.send(CommandRef::Configure(cfg))?;
        match self.answer(seq)?.0 {
            ResponseBody::Configured => Ok(Ok(())),
            ResponseBody::Error(e) => Ok(Err(e)),
            other => bail!("configure answered with {other:?}"),
        }
    }

    /// Lock the configuration in force until the firmware resets.
    pub fn lock(&mut self) -> Result<()> {
        let seq = self.send(CommandRef::Lock)?;
        match self.answer(seq)?.0 {
            ResponseBody::LockEngaged => Ok(()),
            other => bail!("lock answered with {other:?}"),
        }
    }

    /// Set the firmware's configuration.
    pub fn configure(&mut self, cfg: &Config) -> Result<()> {
        let seq = self.send(CommandRef::Configure(cfg))?;
        match self.answer(seq)?.0 {
            ResponseBody::Configured => Ok(()),
            ResponseBody::Error(e) => bail!("configuration rejected: {e}"),
            other => bail!("configure answered with {other:?}"),
        }
    }

    /// Process one epoch on the firmware: its result or typed error, and
    /// the NMEA sentences it wrote.
    pub fn process(&mut self, epoch: &Epoch<'_>) -> Result<Processed> {
        let seq = self.send(epoch_command(epoch))?;
        let (body, notices) = self.answer(seq)?;
        let outcome = match body {
            ResponseBody::Result(r) => Ok(r),
            ResponseBody::Error(e) => Err(e),
            other => bail!("epoch answered with {other:?}"),
        };
        // Every epoch writes its sentences, a refused one its no-fix
        // sentences.
        let nmea = if outcome.is_ok() {
            self.take_epoch_nmea(ANSWER_TIMEOUT)?
        } else {
            self.take_epoch_nmea(Duration::from_secs(5))
                .unwrap_or_default()
        };
        Ok(Processed {
            seq,
            outcome,
            notices,
            nmea,
        })
    }

    /// The next `count` NMEA sentences.
    pub fn take_nmea(&mut self, count: usize, timeout: Duration) -> Result<Vec<String>> {
        let deadline = Instant::now() + timeout;
        let mut out = Vec::with_capacity(count);
        while out.len() < count {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.nmea.recv_timeout(left) {
                Ok(s) => out.push(s),
                Err(_) => bail!("only {} of {count} NMEA sentences arrived", out.len()),
            }
        }
        Ok(out)
    }

    /// The sentences of one epoch: up to and including its ZDA, the last
    /// sentence the firmware writes for every solved epoch (their number
    /// depends on the satellites seen).
    pub fn take_epoch_nmea(&mut self, timeout: Duration) -> Result<Vec<String>> {
        let deadline = Instant::now() + timeout;
        let mut out = Vec::new();
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.nmea.recv_timeout(left) {
                Ok(s) => {
                    let last = s.get(3..6) == Some("ZDA");
                    out.push(s);
                    if last {
                        return Ok(out);
                    }
                }
                Err(_) => bail!("no ZDA after {} NMEA sentences: {out:?}", out.len()),
            }
        }
    }

    /// Up to `count` NMEA sentences, waiting at most `timeout`.
    pub fn take_nmea_upto(&mut self, count: usize, timeout: Duration) -> Vec<String> {
        let deadline = Instant::now() + timeout;
        let mut out = Vec::with_capacity(count);
        while out.len() < count {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.nmea.recv_timeout(left) {
                Ok(s) => out.push(s),
                Err(_) => break,
            }
        }
        out
    }

    /// NMEA sentences already received and not yet taken.
    pub fn drain_nmea(&mut self) -> Vec<String> {
        self.nmea.try_iter().collect()
    }

    /// Saves `len` bytes of guest memory from `addr` to `file` (QMP
    /// `pmemsave`; the session needs `Options::qmp`): the boot counter's
    /// flash as this power-on leaves it, for the next session's
    /// `Options::boot_region`. Returns when QEMU has written the file.
    pub fn save_memory(&mut self, addr: u32, len: u32, file: &Path) -> Result<()> {
        let path = self
            .qmp
            .clone()
            .context("the session has no QMP socket (Options::qmp)")?;
        let deadline = Instant::now() + Duration::from_secs(20);
        let sock = connect(&path, &mut self.child, deadline)?;
        sock.set_read_timeout(Some(ANSWER_TIMEOUT))?;
        let mut reader = BufReader::new(sock.try_clone()?);
        let mut w = sock;
        // The greeting, then each command's `return` (events are skipped).
        let mut answer = |w: &mut UnixStream, command: Option<String>| -> Result<String> {
            if let Some(c) = command {
                w.write_all(c.as_bytes())?;
                w.write_all(b"\n")?;
            }
            loop {
                let mut line = String::new();
                if reader.read_line(&mut line)? == 0 {
                    bail!("QMP closed");
                }
                if line.contains("\"QMP\"") || line.contains("\"return\"") {
                    return Ok(line);
                }
                if line.contains("\"error\"") {
                    bail!("QMP: {line}");
                }
            }
        };
        answer(&mut w, None)?;
        answer(&mut w, Some(r#"{"execute":"qmp_capabilities"}"#.into()))?;
        let file = std::path::absolute(file)?;
        let filename = file.to_str().context("a file name QMP can carry")?;
        answer(
            &mut w,
            Some(format!(
                r#"{{"execute":"pmemsave","arguments":{{"val":{addr},"size":{len},"filename":{filename:?}}}}}"#
            )),
        )?;
        Ok(())
    }

    /// Saves the boot counter's region of firmware `elf` ([`boot_region`])
    /// to `file`; returns its address, for the next session's
    /// `Options::boot_region`.
    pub fn save_boot_region(&mut self, elf: &Path, file: &Path) -> Result<u32> {
        let (addr, len) = boot_region(elf)?;
        self.save_memory(addr, len, file)?;
        Ok(addr)
    }

    /// True while QEMU runs.
    pub fn is_running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }
}

impl Drop for QemuSession {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(self.dir.join("uart0.sock"));
        let _ = std::fs::remove_file(self.dir.join("uart1.sock"));
        // The directory is the session's own: removed unless something
        // failed (an error named its log, or a test is panicking) or the
        // caller asked to keep it (`RAIM_QEMU_KEEP`), so that a test run
        // leaves no files behind while a failure keeps its evidence.
        if self.keep_dir || std::thread::panicking() || std::env::var_os("RAIM_QEMU_KEEP").is_some()
        {
            eprintln!("raim-qemu: session files kept in {}", self.dir.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

/// The request command of an epoch.
pub fn epoch_command<'a>(epoch: &Epoch<'a>) -> CommandRef<'a> {
    match epoch.observations {
        Observations::Ranges { sats, apriori_m } => CommandRef::Ranges {
            time_s: epoch.time_s,
            apriori_m,
            sats,
        },
        Observations::Linear { sats } => CommandRef::Linear {
            time_s: epoch.time_s,
            sats,
        },
    }
}

/// A complete request frame.
pub fn encode_request(req: &RequestRef<'_>) -> Result<Vec<u8>> {
    // Oversized requests (to test the firmware's answers) may exceed the
    // firmware's buffer; the host's buffers are larger.
    let mut scratch = vec![0u8; 16 * MAX_REQUEST_FRAME];
    let mut out = vec![0u8; 17 * MAX_REQUEST_FRAME];
    let f = encode(req, &mut scratch, &mut out).map_err(|e| anyhow!("encoding a request: {e}"))?;
    Ok(f.to_vec())
}

fn spawn_link_reader(mut link: UnixStream) -> Receiver<Result<Response, String>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut frames = Box::new(FrameReceiver::<MAX_RESPONSE_FRAME>::new());
        let mut buf = [0u8; 4096];
        loop {
            let n = match link.read(&mut buf) {
                Ok(0) | Err(_) => return,
                Ok(n) => n,
            };
            for &b in &buf[..n] {
                let item = match frames.push(b) {
                    None => continue,
                    Some(Ok(p)) => postcard::from_bytes::<Response>(p).map_err(|e| format!("{e}")),
                    Some(Err(e)) => Err(frame_error_text(e)),
                };
                if tx.send(item).is_err() {
                    return;
                }
            }
        }
    });
    rx
}

fn frame_error_text(e: FrameError) -> String {
    e.to_string()
}

fn spawn_nmea_reader(sock: UnixStream) -> Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(sock).lines() {
            let Ok(line) = line else { return };
            if tx.send(line.trim_end().to_string()).is_err() {
                return;
            }
        }
    });
    rx
}
