//! Structured fuzzing of the protocol server: `arbitrary`
//! builds a sequence of well-formed requests with valid CRCs (linearised
//! epochs with faults and NaNs, configurations in and out of bounds,
//! locks, status requests, garbage frames), feeds them to
//! `raim_server::Server` as the firmware does, and checks after
//! every answer:
//! - every frame gets exactly one answer, in order, with its sequence
//!   number (garbage: one answer without one);
//! - an `Ok` or `Excluded` result has a finite test statistic below its
//!   finite threshold and finite protection levels within the alert limits
//!   of the configuration in force (Decision's definition, raim-core
//!   `result.rs`);
//! - the configuration in force changes only on `Configured`, never after
//!   `Lock`, and every answer carries its fingerprint and the lock state.
//!
//! Run by `fuzz_targets/server_structured.rs` (cargo-fuzz, nightly) or by
//! `src/bin/structured_loop.rs` (stable: seeded bytes, no coverage).

use arbitrary::{Arbitrary, Unstructured};
use raim_core::{AlertLimits, Config, FiRule, LinearObservation, Phase, SatId, System};
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_proto::result::WireResult;
use raim_proto::unit::{UnitConfig, UnitConfigRef, PROVISION_BYTES};
use raim_proto::{ConfigId, ConfigSource, WireError, MAX_RESPONSE_FRAME};
use raim_server::{NoPlatform, Server};

/// At most this many steps per scenario.
pub const MAX_STEPS: usize = 8;

/// One request of a scenario.
#[derive(Debug, Arbitrary)]
pub enum Step {
    /// A linearised epoch: `sats` satellites (4-14) on a sky drawn from
    /// `sky_seed`, unit-sigma noise scaled by `noise_tenths` / 10, up to two
    /// faults (satellite index, fiftieths of a metre) and a NaN residual.
    Epoch {
        sats: u8,
        sky_seed: u32,
        noise_tenths: u8,
        fault: Option<(u8, i16)>,
        second_fault: Option<(u8, i16)>,
        nan_at: Option<u8>,
        time_s: u32,
    },
    /// A configuration: a preset, then fields from the fuzzer (some out of
    /// bounds, which must be refused).
    Configure {
        phase: u8,
        pfa_exp: u8,
        rule: u8,
        kappa: u16,
        hal_m: u16,
        val_m: Option<u16>,
        max_exclusions: u8,
        wild_pfa: Option<f64>,
    },
    Lock,
    Status,
    /// Non-zero bytes and a delimiter: one frame that is not a request.
    Garbage(Vec<u8>),
    /// A reset (watchdog, panic, power glitch): the unit boots again from
    /// its flash, and says so first (the boot notice).
    Reset,
}

/// What the unit's flash holds in its provisioned-configuration section.
#[derive(Debug, Clone, Copy, Arbitrary)]
pub enum Provision {
    /// Erased: the unit boots Unconfigured.
    None,
    /// A sealed configuration (a preset phase, host sigmas on or off).
    Valid { phase: u8, host_sigmas: bool },
    /// A sealed configuration with one byte of the section flipped.
    Corrupt { phase: u8, byte: u16, flip: u8 },
}

/// A provisioning state and a sequence of requests.
#[derive(Debug)]
pub struct Scenario {
    pub provision: Provision,
    pub steps: Vec<Step>,
}

impl<'a> Arbitrary<'a> for Scenario {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        let provision = Provision::arbitrary(u)?;
        let mut steps = Vec::new();
        while steps.len() < MAX_STEPS && !u.is_empty() {
            steps.push(Step::arbitrary(u)?);
        }
        Ok(Scenario { provision, steps })
    }
}

/// The provisioned configuration of a scenario, and its sealed section.
fn provisioned(p: Provision) -> (Option<UnitConfig>, bool, Box<[u8; PROVISION_BYTES]>) {
    let mut blob = Box::new([0xFFu8; PROVISION_BYTES]);
    let unit = |phase: u8, host_sigmas| UnitConfig {
        snapshot: Some(Config::preset(
            [Phase::EnRoute, Phase::Terminal, Phase::Npa][usize::from(phase % 3)],
        )),
        araim: None,
        pf: None,
        host_sigmas,
    };
    match p {
        Provision::None => (None, false, blob),
        Provision::Valid { phase, host_sigmas } => {
            let u = unit(phase, host_sigmas);
            let _ = raim_proto::unit::seal(&u, None, &mut blob);
            (Some(u), false, blob)
        }
        Provision::Corrupt { phase, byte, flip } => {
            let u = unit(phase, false);
            let _ = raim_proto::unit::seal(&u, None, &mut blob);
            // Within the sealed bytes (header 12, payload, seal 32).
            let len = u32::from_le_bytes([blob[8], blob[9], blob[10], blob[11]]) as usize;
            let i = usize::from(byte) % (12 + len + 32);
            blob[i] ^= flip.max(1);
            // A flip that still opened would be a broken seal: the run
            // checks that it never does.
            (None, true, blob)
        }
    }
}

/// A platform that has been reset `0` times (a watchdog reset).
struct Rebooted(u32);
impl raim_server::Platform for Rebooted {
    fn now(&mut self) -> u32 {
        0
    }
    fn reset_record(&mut self) -> (u32, raim_proto::ResetCause) {
        (self.0, raim_proto::ResetCause::Watchdog { pc: 0 })
    }
}

/// A unit booting from `section`, as the firmware does.
fn boot(section: &[u8; PROVISION_BYTES], resets: u32) -> Box<Server> {
    let mut server = Box::new(Server::new());
    let entropy = raim_proto::auth::BootEntropy {
        bytes: [7; 32],
        hardware: false,
    };
    server.boot(raim_proto::unit::open(section, None), resets, &entropy);
    server
}

/// What the scenarios covered (for the run's record).
#[derive(Debug, Default, Clone, Copy)]
pub struct Tally {
    pub frames: u64,
    pub epochs: u64,
    pub ok: u64,
    pub excluded: u64,
    pub alarm: u64,
    pub unavailable: u64,
    pub epoch_errors: u64,
    pub configured: u64,
    pub refused_configs: u64,
    pub locked_refusals: u64,
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

/// A small deterministic generator for the sky and the noise.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.next().max(1e-300), self.next());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

fn sky(step: &Step) -> Vec<LinearObservation> {
    let Step::Epoch {
        sats,
        sky_seed,
        noise_tenths,
        fault,
        second_fault,
        nan_at,
        ..
    } = step
    else {
        return Vec::new();
    };
    let n = 4 + usize::from(*sats % 11);
    let mut rng = Lcg(u64::from(*sky_seed) ^ 0x9E37_79B9_7F4A_7C15);
    (0..n)
        .map(|i| {
            let az = rng.next() * 2.0 * std::f64::consts::PI;
            let el = (5.0 + 85.0 * rng.next()).to_radians();
            let mut r = rng.normal() * f64::from(*noise_tenths) / 10.0;
            // Faults up to +-655 m in 2 cm steps: the region around the
            // threshold and the PLs, where a wrong "Ok" would hide.
            for (k, m) in [fault, second_fault].into_iter().flatten() {
                if usize::from(*k) % n == i {
                    r += f64::from(*m) / 50.0;
                }
            }
            // One epoch in 16 of those that ask has a NaN residual.
            if nan_at.is_some_and(|k| k < 16 && usize::from(k) % n == i) {
                r = f64::NAN;
            }
            let mut o =
                LinearObservation::from_az_el(SatId::new(System::Gps, i as u8 + 1), az, el, r);
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn config(step: &Step) -> Option<Config> {
    let Step::Configure {
        phase,
        pfa_exp,
        rule,
        kappa,
        hal_m,
        val_m,
        max_exclusions,
        wild_pfa,
    } = step
    else {
        return None;
    };
    let phase = [Phase::EnRoute, Phase::Terminal, Phase::Npa][usize::from(*phase % 3)];
    let base = Config::preset(phase);
    Some(Config {
        pfa: wild_pfa.unwrap_or(10f64.powi(-i32::from(2 + *pfa_exp % 12))),
        rule: match rule % 3 {
            0 => FiRule::Mle,
            1 => FiRule::LraimFlat,
            _ => FiRule::LraimGaussian {
                kappa: f64::from(*kappa),
            },
        },
        alert: AlertLimits {
            hal_m: f64::from(*hal_m),
            val_m: val_m.map(f64::from),
        },
        max_exclusions: *max_exclusions % 4,
        ..base
    })
}

/// The first invariant a result breaks, if any.
fn check_result(r: &WireResult, cfg: &Config) -> Result<(), String> {
    use raim_core::Decision;
    if !matches!(r.decision, Decision::Ok | Decision::Excluded) {
        return Ok(());
    }
    let t = &r.test;
    if !(t.statistic.is_finite() && t.threshold.is_finite() && t.statistic < t.threshold) {
        return Err(format!("{:?} with test {t:?}", r.decision));
    }
    if !(r.hpl_m.is_finite() && r.hpl_m <= cfg.alert.hal_m) {
        return Err(format!(
            "{:?} with HPL {} > HAL {}",
            r.decision, r.hpl_m, cfg.alert.hal_m
        ));
    }
    if let Some(val) = cfg.alert.val_m {
        if !(r.vpl_m.is_finite() && r.vpl_m <= val) {
            return Err(format!("{:?} with VPL {} > VAL {val}", r.decision, r.vpl_m));
        }
    }
    Ok(())
}

/// Run a scenario through a unit booted from the scenario's provisioned
/// section; `Err` names the broken invariant. The invariants, besides the
/// answers' own: `Ok` only under the provisioned configuration or one
/// taken at run time since the last reset, whose fingerprint the answer
/// carries; after every reset the configuration in force is the
/// provisioned one or none; a unit whose section is corrupt boots
/// Unconfigured and locked and refuses every change with the reason
/// (issue 35); `Lock` is taken only with a configuration in force; every
/// frame after the boot notice is answered.
pub fn run(scenario: &Scenario, tally: &mut Tally) -> Result<(), String> {
    let (provision, corrupt, section) = provisioned(scenario.provision);
    let mut resets = 0u32;
    let mut server = boot(&section, resets);
    let after_boot = |server: &Server,
                      provision: &Option<UnitConfig>|
     -> Result<(Option<Config>, bool, bool), String> {
        let id = server.config_id();
        match provision {
            Some(u) => {
                if id.source != ConfigSource::Provisioned
                    || !id.locked
                    || id.fingerprint != u.fingerprint()
                {
                    return Err(format!("booted with {id:?}, provisioned {u:?}"));
                }
                Ok((u.snapshot, true, u.host_sigmas))
            }
            None => {
                if id.source != ConfigSource::Unconfigured || id.locked != corrupt {
                    return Err(format!(
                        "booted with {id:?}, nothing provisioned (corrupt section: {corrupt})"
                    ));
                }
                Ok((None, corrupt, true))
            }
        }
    };
    let (mut in_force, mut locked, mut host_sigmas) = after_boot(&server, &provision)?;
    let mut source = server.config_id().source;
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    let mut rx = Box::new(FrameReceiver::<MAX_RESPONSE_FRAME>::new());
    let mut scratch = vec![0u8; 8192];
    let mut out = vec![0u8; 8192];
    let mut next_seq = 0u32;
    for step in &scenario.steps {
        if matches!(step, Step::Reset) {
            resets += 1;
            server = boot(&section, resets);
            (in_force, locked, host_sigmas) = after_boot(&server, &provision)?;
            source = server.config_id().source;
            // The boot notice comes first, unasked.
            link.0.clear();
            server
                .send_boot_notice::<_, core::convert::Infallible, _>(
                    &mut link,
                    &mut Rebooted(resets),
                )
                .map_err(|e| format!("boot notice: {e:?}"))?;
            let mut notices: Vec<Response> = Vec::new();
            for &b in &link.0 {
                if let Some(Ok(p)) = rx.push(b) {
                    notices.push(postcard::from_bytes(p).map_err(|e| format!("{e}"))?);
                }
            }
            match notices.as_slice() {
                [Response {
                    seq: None,
                    body: ResponseBody::Boot(b),
                    ..
                }] if b.resets == resets && b.config == server.config_id() => {}
                other => return Err(format!("after reset {resets}: {other:?}")),
            }
            continue;
        }
        let seq = next_seq;
        if !matches!(step, Step::Garbage(_)) {
            next_seq += 1;
        }
        let sats = sky(step);
        let cfg = config(step);
        let frame: Vec<u8> = match step {
            Step::Garbage(bytes) => bytes
                .iter()
                .filter(|&&b| b != 0)
                .copied()
                .chain([0u8])
                .collect(),
            _ => {
                let command = match step {
                    Step::Epoch { time_s, .. } => CommandRef::Linear {
                        time_s: f64::from(*time_s),
                        sats: &sats,
                    },
                    Step::Configure { .. } => {
                        CommandRef::Configure(cfg.as_ref().ok_or("no configuration")?)
                    }
                    Step::Lock => CommandRef::Lock,
                    _ => CommandRef::Status,
                };
                encode(&RequestRef { seq, command }, &mut scratch, &mut out)
                    .map_err(|e| format!("encoding: {e:?}"))?
                    .to_vec()
            }
        };
        link.0.clear();
        for &b in &frame {
            let _ = server.on_byte(b, &mut link, &mut nmea, &mut NoPlatform);
        }
        // The host waits for the answer: a pause on the line, which ends
        // an RTCM candidate that garbage starting 0xD3 opened (as the
        // firmware's loop does after `LINK_IDLE_S`).
        let _ = server.on_line_idle(&mut link, &mut nmea, &mut NoPlatform);
        tally.frames += 1;
        let mut answers: Vec<Response> = Vec::new();
        for &b in &link.0 {
            match rx.push(b) {
                None => {}
                Some(Ok(p)) => answers.push(postcard::from_bytes(p).map_err(|e| format!("{e}"))?),
                Some(Err(e)) => return Err(format!("the server's own frame: {e:?}")),
            }
        }
        // A garbage chunk that is only a delimiter is not a frame.
        let empty = matches!(step, Step::Garbage(_)) && frame.len() == 1;
        if empty {
            if !answers.is_empty() {
                return Err(format!("an empty chunk answered: {answers:?}"));
            }
            continue;
        }
        // Garbage that starts like an RTCM header may be cut in two
        // chunks (module raim_proto::link): one error answer or more,
        // unasked; it changes nothing.
        if matches!(step, Step::Garbage(_)) && !answers.is_empty() {
            let id = server.config_id();
            for a in &answers {
                if a.seq.is_some() || !matches!(a.body, ResponseBody::Error(_)) || a.config != id {
                    return Err(format!("step {seq}: garbage answered {a:?}"));
                }
            }
            if id.locked != locked || id.source != source {
                return Err(format!("step {seq}: garbage changed {id:?}"));
            }
            continue;
        }
        let [answer] = answers.as_slice() else {
            return Err(format!(
                "step {seq} {step:?}: {} answers {answers:?}",
                answers.len()
            ));
        };
        let want_seq = (!matches!(step, Step::Garbage(_))).then_some(seq);
        if answer.seq != want_seq {
            return Err(format!("step {seq}: answer for {:?}", answer.seq));
        }
        match (step, &answer.body) {
            (Step::Epoch { .. }, ResponseBody::Result(r)) => {
                tally.epochs += 1;
                match r.decision {
                    raim_core::Decision::Ok => tally.ok += 1,
                    raim_core::Decision::Excluded => tally.excluded += 1,
                    raim_core::Decision::Alarm => tally.alarm += 1,
                    raim_core::Decision::Unavailable => tally.unavailable += 1,
                }
                let Some(cfg) = in_force.as_ref() else {
                    return Err(format!(
                        "step {seq}: a result with no configuration in force"
                    ));
                };
                check_result(r, cfg).map_err(|e| format!("step {seq}: {e}"))?;
            }
            (Step::Epoch { .. }, ResponseBody::Error(e)) => {
                if in_force.is_none() && !matches!(e, WireError::Unconfigured { .. }) {
                    return Err(format!("step {seq}: unconfigured, answered {e:?}"));
                }
                tally.epochs += 1;
                tally.epoch_errors += 1;
            }
            (Step::Configure { .. }, ResponseBody::Configured) => {
                if locked {
                    return Err(format!("step {seq}: configured while locked"));
                }
                let c = cfg.ok_or("no configuration")?;
                if c.validate().is_err() {
                    return Err(format!("step {seq}: an invalid configuration taken: {c:?}"));
                }
                in_force = Some(c);
                source = ConfigSource::Runtime;
                tally.configured += 1;
            }
            (
                Step::Configure { .. } | Step::Lock,
                ResponseBody::Error(WireError::Unconfigured { provision: Some(_) }),
            ) if corrupt => {
                tally.locked_refusals += 1;
            }
            (Step::Configure { .. }, ResponseBody::Error(WireError::Locked { .. }))
                if locked && !corrupt =>
            {
                tally.locked_refusals += 1;
            }
            (Step::Configure { .. }, ResponseBody::Error(_)) if !locked => {
                tally.refused_configs += 1;
            }
            // `Lock` only with a configuration in force (issue 35).
            (Step::Lock, ResponseBody::LockEngaged)
                if !locked && source != ConfigSource::Unconfigured =>
            {
                locked = true
            }
            (Step::Lock, ResponseBody::Error(WireError::Unconfigured { provision: None }))
                if !locked && source == ConfigSource::Unconfigured => {}
            (Step::Lock, ResponseBody::Error(WireError::Locked { .. })) if locked && !corrupt => {}
            (Step::Status, ResponseBody::Status(_)) => {}
            (Step::Garbage(_), ResponseBody::Error(_)) => {}
            (s, b) => return Err(format!("step {seq}: {s:?} answered {b:?}")),
        }
        let id = ConfigId {
            fingerprint: UnitConfigRef {
                snapshot: in_force.as_ref(),
                araim: None,
                pf: None,
                host_sigmas,
            }
            .fingerprint(),
            locked,
            source,
        };
        if answer.config != id {
            return Err(format!(
                "step {seq}: answer carries {:?}, in force {id:?}",
                answer.config
            ));
        }
    }
    if std::str::from_utf8(&nmea.0).is_err() {
        return Err("NMEA output is not text".into());
    }
    Ok(())
}
