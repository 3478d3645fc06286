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
//!   `Lock`, and every answer carries its fingerprint and the lock state;
//! - no `Ok` without a valid configuration in force, and the alarm output
//!   (what the platform hears, `Platform::on_epoch`) asserted for every
//!   epoch frame not answered `Ok` or `Excluded`: oversized frames, absurd
//!   and backward times, out-of-range PRNs included (issue 35);
//! - an empty ISM is never taken;
//! - the model check's settings (`ModelCheck`, in and out of bounds; a
//!   provisioned section with them in or out of bounds) are taken only
//!   within their bounds, on an open unkeyed unit, refused otherwise with
//!   the check's own typed error, and the fingerprint covers them;
//! - on a keyed unit, power cycles and resets advance the boot counter in
//!   a simulated flash (torn by power cuts, failing, or taking a write
//!   that reports success and stores other bits or leaves a marginal
//!   cell), each completed
//!   boot's count above every earlier one; a frame sent before, replayed
//!   in a later power-on or the same one, is never taken again, and a
//!   boot whose counter failed takes no authenticated change.
//!
//! Run by `fuzz_targets/server_structured.rs` (cargo-fuzz, nightly) or by
//! `src/bin/structured_loop.rs` (stable: seeded bytes, no coverage).

use arbitrary::{Arbitrary, Unstructured};
use raim_core::{AlertLimits, Config, FiRule, LinearObservation, Phase, SatId, System};
use raim_proto::araim_msg::{AraimCommandRef, AraimWireError, IsmFrameRef, WireAraimConfig};
use raim_proto::auth::{AuthKey, AuthenticatedRef, ChangeRef};
use raim_proto::boot_counter::{BootCounterStatus, CounterFlash, FlashFault};
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_proto::result::WireResult;
use raim_proto::unit::{UnitConfig, UnitConfigRef, PROVISION_BYTES};
use raim_proto::{ConfigId, ConfigSource, WireError, MAX_RESPONSE_FRAME};
use raim_server::Server;

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
        /// The MCUSUM on (the false-alarm budget split with it): a
        /// stateful monitor, for which time must go forward.
        mcusum: bool,
    },
    Lock,
    Status,
    /// Non-zero bytes and a delimiter: one frame that is not a request.
    Garbage(Vec<u8>),
    /// A reset (watchdog, panic, power glitch): the unit boots again from
    /// its flash, and says so first (the boot notice).
    Reset,
    /// An epoch frame with more satellites than the unit holds
    /// (`CAPACITY + 1` to 64): refused, the alarm asserted.
    Oversized {
        sats: u8,
        sky_seed: u32,
    },
    /// An epoch at an absurd time (+-1e300 s, NaN, +-inf, -1 s, 1e12 s) or
    /// 50 s before the last one answered: refused when absurd, and when
    /// backward under the MCUSUM.
    BadTime {
        kind: u8,
        sky_seed: u32,
    },
    /// An epoch with one GPS PRN out of range (0, or 33-255).
    BadPrn {
        index: u8,
        prn: u8,
        sky_seed: u32,
    },
    /// An ARAIM ISM with no entries: never taken.
    EmptyIsm,
    /// An authenticated `Configure` (keyed units), tagged under the boot
    /// nonce the unit announced and the host's next counter; recorded.
    AuthConfigure {
        phase: u8,
        mcusum: bool,
    },
    /// An authenticated `Lock`; recorded.
    AuthLock,
    /// A power cycle: the unit loses power (the reset count is gone) and
    /// boots again; the first `cuts % 3` boots are cut during the boot
    /// counter's advance, after `cut_at % 48` flash operations (a torn
    /// write); the last boot's flash takes no write when `flash_fails`,
    /// and with `bad_write` = (k, weak) its (k % 4)-th program that clears
    /// a bit reports success and stores other bits, or (`weak`) leaves a
    /// marginal cell that reads right once or twice and then with a bit
    /// flipped.
    PowerCycle {
        cuts: u8,
        cut_at: u8,
        flash_fails: bool,
        bad_write: Option<(u8, bool)>,
    },
    /// One of the recorded authenticated frames sent again (re-framed with
    /// the next sequence number, as an attacker on the link would).
    Replay {
        index: u8,
    },
    /// The model check's settings (`Command::ModelCheck`): the spacing
    /// from a list that reaches past both bounds (or `wild_spacing_s`),
    /// the window 0-19 (bounds 1-16), P_h 10^-(0..=13) (bounds 1e-12,
    /// 0.5) or `wild_p_h`: taken only within the bounds, refused with the
    /// check's own typed error otherwise.
    ModelCheck {
        spacing: u8,
        window: u8,
        p_h_exp: u8,
        wild_spacing_s: Option<f64>,
        wild_p_h: Option<f64>,
    },
}

/// The settings of a `Step::ModelCheck`.
fn model_check_settings(step: &Step) -> Option<raim_proto::WireModelCheckConfig> {
    let Step::ModelCheck {
        spacing,
        window,
        p_h_exp,
        wild_spacing_s,
        wild_p_h,
    } = *step
    else {
        return None;
    };
    const SPACINGS_S: [f64; 8] = [1e-4, 1e-3, 1.0, 30.0, 900.0, 1800.0, 86_400.0, 1e6];
    Some(raim_proto::WireModelCheckConfig {
        spacing_s: wild_spacing_s.unwrap_or(SPACINGS_S[usize::from(spacing) % SPACINGS_S.len()]),
        window: u32::from(window % 20),
        p_fa_per_hour: wild_p_h.unwrap_or(10f64.powi(-i32::from(p_h_exp % 14))),
    })
}

/// What the unit's flash holds in its provisioned-configuration section.
#[derive(Debug, Clone, Copy, Arbitrary)]
pub enum Provision {
    /// Erased: the unit boots Unconfigured.
    None,
    /// A sealed configuration (a preset phase, host sigmas on or off, a
    /// model-check window of 1-16).
    Valid {
        phase: u8,
        host_sigmas: bool,
        window: u8,
    },
    /// A sealed configuration with one byte of the section flipped.
    Corrupt { phase: u8, byte: u16, flip: u8 },
    /// A sealed configuration whose model-check window (0, or 17-255) is
    /// out of its bounds: refused at boot (`InvalidPart(ModelCheck)`).
    BadModelCheck { phase: u8, window: u8 },
}

/// A provisioning state, whether the unit is keyed, and a sequence of
/// requests.
#[derive(Debug)]
pub struct Scenario {
    pub provision: Provision,
    pub keyed: bool,
    pub steps: Vec<Step>,
}

impl<'a> Arbitrary<'a> for Scenario {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        let provision = Provision::arbitrary(u)?;
        // One scenario in four keyed: the others keep the bench unit's
        // plain changes, and with them the epochs answered under them.
        let keyed = u8::arbitrary(u)? < 64;
        let mut steps = Vec::new();
        while steps.len() < MAX_STEPS && !u.is_empty() {
            steps.push(Step::arbitrary(u)?);
        }
        Ok(Scenario {
            provision,
            keyed,
            steps,
        })
    }
}

/// The key of keyed scenarios.
const KEY: AuthKey = [0x35; 32];

/// The boot counter's flash, simulated: NOR semantics (a program clears
/// bits, an erase sets a page to all ones), 4 entries a page (a page
/// switch every 4 boots). A power cut after `budget` operations tears the
/// operation it interrupts (a program clears only some of its bits, an
/// erase sets only some) and fails every later one; `read_only` is a
/// flash that takes no write (QEMU's netduinoplus2). `bad_program`:
/// the n-th program of a boot that clears a bit reports success and
/// stores other bits, or (`true`) leaves a marginal cell (`weak`: page,
/// word, good reads left, the bit that flips after them).
struct SimFlash {
    pages: [Vec<u32>; 2],
    budget: Option<u32>,
    read_only: bool,
    tear: u32,
    bad_program: Option<(u32, bool)>,
    programs: u32,
    weak: Vec<(usize, usize, u32, u32)>,
}

impl SimFlash {
    fn spend(&mut self) -> Result<bool, FlashFault> {
        match self.budget {
            Some(0) => Err(FlashFault),
            Some(n) => {
                self.budget = Some(n - 1);
                Ok(n == 1)
            }
            None => Ok(false),
        }
    }
}

impl CounterFlash for SimFlash {
    fn page_words(&self) -> usize {
        8
    }
    fn read(&mut self, page: usize, word: usize) -> Result<u32, FlashFault> {
        if self.spend()? {
            return Err(FlashFault);
        }
        let v = self
            .pages
            .get(page)
            .and_then(|p| p.get(word))
            .copied()
            .ok_or(FlashFault)?;
        match self
            .weak
            .iter_mut()
            .find(|(p, w, _, _)| *p == page && *w == word)
        {
            Some((_, _, 0, bit)) => Ok(v ^ (1 << *bit)),
            Some((_, _, left, _)) => {
                *left -= 1;
                Ok(v)
            }
            None => Ok(v),
        }
    }
    fn erase(&mut self, page: usize) -> Result<(), FlashFault> {
        let cut = self.spend()?;
        if self.read_only {
            return Ok(());
        }
        let tear = self.tear;
        if !cut {
            self.weak.retain(|(p, _, _, _)| *p != page);
        }
        let p = self.pages.get_mut(page).ok_or(FlashFault)?;
        for (k, w) in p.iter_mut().enumerate() {
            *w = if cut {
                *w | tear.rotate_left(k as u32)
            } else {
                u32::MAX
            };
        }
        if cut {
            Err(FlashFault)
        } else {
            Ok(())
        }
    }
    fn program(&mut self, page: usize, word: usize, value: u32) -> Result<(), FlashFault> {
        let cut = self.spend()?;
        if self.read_only {
            return Ok(());
        }
        let tear = self.tear;
        let w = self
            .pages
            .get_mut(page)
            .and_then(|p| p.get_mut(word))
            .ok_or(FlashFault)?;
        if cut {
            *w &= value | tear;
            return Err(FlashFault);
        }
        let old = *w;
        // A program pulses only the bits it clears: one that clears none
        // changes nothing, and cannot go wrong.
        if old & !value != 0 {
            let n = self.programs;
            self.programs += 1;
            match self.bad_program {
                Some((k, false)) if k == n => {
                    // Some bits to clear left set, some to keep cleared.
                    let stored = old & ((value | tear) & !tear.rotate_left(7));
                    *w = if stored == old & value {
                        stored ^ 1
                    } else {
                        stored
                    };
                    return Ok(());
                }
                Some((k, true)) if k == n => {
                    self.weak.push((page, word, 1 + n % 2, tear % 32));
                }
                _ => {}
            }
        }
        *w &= value;
        Ok(())
    }
}

/// One boot's counter: advanced on `flash` as the firmware does.
fn count_boot(flash: &mut SimFlash) -> BootCounterStatus {
    match raim_proto::boot_counter::advance(flash) {
        Ok(n) => BootCounterStatus::Count(n),
        Err(e) => BootCounterStatus::Failed(e),
    }
}

/// What the platform heard of each frame's epoch verdict.
struct Heard(Vec<Option<raim_core::Decision>>);
impl raim_server::Platform for Heard {
    fn now(&mut self) -> u32 {
        0
    }
    fn on_epoch(&mut self, decision: Option<raim_core::Decision>) {
        self.0.push(decision);
    }
}

/// A recorded authenticated change: its counter, change and tag.
#[derive(Clone, Copy)]
struct Recorded {
    change: RecordedChange,
    counter: u64,
    tag: raim_proto::auth::Tag,
}

#[derive(Clone, Copy)]
enum RecordedChange {
    Configure(Config),
    Lock,
}

/// The provisioned configuration of a scenario, and its sealed section.
fn provisioned(
    p: Provision,
    key: Option<&AuthKey>,
) -> (Option<UnitConfig>, bool, Box<[u8; PROVISION_BYTES]>) {
    let mut blob = Box::new([0xFFu8; PROVISION_BYTES]);
    let unit = |phase: u8, host_sigmas, window| UnitConfig {
        snapshot: Some(Config::preset(
            [Phase::EnRoute, Phase::Terminal, Phase::Npa][usize::from(phase % 3)],
        )),
        araim: None,
        pf: None,
        host_sigmas,
        model_check: raim_proto::WireModelCheckConfig {
            window,
            ..raim_proto::WireModelCheckConfig::DEFAULT
        },
    };
    match p {
        Provision::None => (None, false, blob),
        Provision::Valid {
            phase,
            host_sigmas,
            window,
        } => {
            let u = unit(phase, host_sigmas, 1 + u32::from(window % 16));
            let _ = raim_proto::unit::seal(&u, key, &mut blob);
            (Some(u), false, blob)
        }
        Provision::BadModelCheck { phase, window } => {
            let w = if window <= 16 { 0 } else { u32::from(window) };
            let u = unit(phase, false, w);
            let _ = raim_proto::unit::seal(&u, key, &mut blob);
            // Sealed right, refused by boot's check of the part.
            (None, true, blob)
        }
        Provision::Corrupt { phase, byte, flip } => {
            let u = unit(phase, false, 8);
            let _ = raim_proto::unit::seal(&u, key, &mut blob);
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

/// A unit booting from `section`, as the firmware does, with the boot
/// counter's status of this boot. The entropy is the same at every boot
/// (QEMU's: zeroed SRAM, no RNG), so only the reset count and the boot
/// counter tell boots apart.
fn boot(
    section: &[u8; PROVISION_BYTES],
    resets: u32,
    key: Option<&AuthKey>,
    counter: BootCounterStatus,
) -> Box<Server> {
    let mut server = Box::new(Server::new());
    if let Some(k) = key {
        server.set_auth_key(*k);
    }
    server.set_boot_counter(counter);
    let entropy = raim_proto::auth::BootEntropy {
        bytes: [7; 32],
        hardware: false,
    };
    server.boot(raim_proto::unit::open(section, key), resets, &entropy);
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
    pub oversized: u64,
    pub bad_times: u64,
    pub bad_prns: u64,
    pub empty_isms: u64,
    pub power_cycles: u64,
    pub torn_boots: u64,
    pub failed_counters: u64,
    pub auth_taken: u64,
    pub replays_refused: u64,
    pub model_checks_taken: u64,
    pub model_checks_refused: u64,
    pub bad_writes: u64,
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
    match step {
        Step::Oversized { sats, sky_seed } => {
            let n = raim_proto::CAPACITY + 1 + usize::from(*sats) % (64 - raim_proto::CAPACITY);
            return plain_sky(n, *sky_seed);
        }
        Step::BadTime { sky_seed, .. } => return plain_sky(8, *sky_seed),
        Step::BadPrn {
            index,
            prn,
            sky_seed,
        } => {
            let mut v = plain_sky(8, *sky_seed);
            let k = usize::from(*index) % v.len();
            v[k].id.prn = if prn % 2 == 0 { 0 } else { 33 + prn % 223 };
            return v;
        }
        _ => {}
    }
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

/// `n` GPS satellites, PRN 1 up, on a sky from `seed`, with unit-sigma
/// noise and sigmas of 1 m (PRNs above 32 wrap into range).
fn plain_sky(n: usize, seed: u32) -> Vec<LinearObservation> {
    let mut rng = Lcg(u64::from(seed) ^ 0x5851_F42D_4C95_7F2D);
    (0..n)
        .map(|i| {
            let az = rng.next() * 2.0 * std::f64::consts::PI;
            let el = (5.0 + 85.0 * rng.next()).to_radians();
            let mut o = LinearObservation::from_az_el(
                SatId::new(System::Gps, (i % 32) as u8 + 1),
                az,
                el,
                rng.normal(),
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

/// The time of a `BadTime` epoch: absurd, or 50 s before `last_s`.
fn bad_time(kind: u8, last_s: Option<f64>) -> (f64, bool) {
    match (kind % 8, last_s) {
        (0, _) => (1e300, true),
        (1, _) => (-1e300, true),
        (2, _) => (f64::NAN, true),
        (3, _) => (f64::INFINITY, true),
        (4, _) => (f64::NEG_INFINITY, true),
        (5, _) => (-1.0, true),
        (6, _) => (1e12, true),
        (_, Some(t)) => (t - 50.0, false),
        (_, None) => (1e300, true),
    }
}

fn config(step: &Step) -> Option<Config> {
    if let Step::AuthConfigure { phase, mcusum } = step {
        let c =
            Config::preset([Phase::EnRoute, Phase::Terminal, Phase::Npa][usize::from(phase % 3)]);
        return Some(if *mcusum {
            c.split_false_alarm_budget(raim_core::config::DEFAULT_SNAPSHOT_SHARE)
        } else {
            c
        });
    }
    let Step::Configure {
        phase,
        pfa_exp,
        rule,
        kappa,
        hal_m,
        val_m,
        max_exclusions,
        wild_pfa,
        mcusum,
    } = step
    else {
        return None;
    };
    let phase = [Phase::EnRoute, Phase::Terminal, Phase::Npa][usize::from(*phase % 3)];
    let base = Config::preset(phase);
    let base = if *mcusum {
        base.split_false_alarm_budget(raim_core::config::DEFAULT_SNAPSHOT_SHARE)
    } else {
        base
    };
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
/// frame after the boot notice is answered; every epoch frame not answered
/// `Ok` or `Excluded` is heard by the platform as an alarm (oversized,
/// absurd or backward in time, out-of-range PRNs: never a result); an
/// empty ISM is never taken; each completed boot's counter is above every
/// earlier one, a frame sent before is never taken again, and a boot
/// whose counter failed takes no authenticated change.
pub fn run(scenario: &Scenario, tally: &mut Tally) -> Result<(), String> {
    let key = scenario.keyed.then_some(KEY);
    let key = key.as_ref();
    let keyed = key.is_some();
    let (provision, corrupt, section) = provisioned(scenario.provision, key);
    let mut flash = SimFlash {
        pages: [vec![u32::MAX; 8], vec![u32::MAX; 8]],
        budget: None,
        read_only: false,
        tear: 0,
        bad_program: None,
        programs: 0,
        weak: Vec::new(),
    };
    // The largest count a completed boot has had.
    let mut last_count: Option<u32> = None;
    let mut check_count = |c: BootCounterStatus| -> Result<(), String> {
        if let BootCounterStatus::Count(n) = c {
            if last_count.is_some_and(|l| n <= l) {
                return Err(format!("boot count {n} after {last_count:?}"));
            }
            last_count = Some(n);
        }
        Ok(())
    };
    let mut resets = 0u32;
    let mut counter = count_boot(&mut flash);
    check_count(counter)?;
    let mut server = boot(&section, resets, key, counter);
    let after_boot =
        |server: &Server,
         provision: &Option<UnitConfig>|
         -> Result<(Option<Config>, bool, bool, raim_proto::WireModelCheckConfig), String> {
            let id = server.config_id();
            match provision {
                Some(u) => {
                    if id.source != ConfigSource::Provisioned
                        || !id.locked
                        || id.fingerprint != u.fingerprint()
                    {
                        return Err(format!("booted with {id:?}, provisioned {u:?}"));
                    }
                    Ok((u.snapshot, true, u.host_sigmas, u.model_check))
                }
                None => {
                    if id.source != ConfigSource::Unconfigured || id.locked != corrupt {
                        return Err(format!(
                            "booted with {id:?}, nothing provisioned (corrupt section: {corrupt})"
                        ));
                    }
                    Ok((
                        None,
                        corrupt,
                        true,
                        raim_proto::WireModelCheckConfig::DEFAULT,
                    ))
                }
            }
        };
    let (mut in_force, mut locked, mut host_sigmas, mut model_check) =
        after_boot(&server, &provision)?;
    let mut source = server.config_id().source;
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    let mut rx = Box::new(FrameReceiver::<MAX_RESPONSE_FRAME>::new());
    let mut scratch = vec![0u8; 8192];
    let mut out = vec![0u8; 8192];
    let mut next_seq = 0u32;
    // The host's authentication counter since the boot, the changes it
    // sent, and the time of the last epoch answered with a result.
    let mut host_counter = 0u64;
    let mut recorded: Vec<Recorded> = Vec::new();
    let mut last_time: Option<f64> = None;
    for step in &scenario.steps {
        if let Step::Reset | Step::PowerCycle { .. } = step {
            match *step {
                Step::PowerCycle {
                    cuts,
                    cut_at,
                    flash_fails,
                    bad_write,
                } => {
                    tally.power_cycles += 1;
                    resets = 0;
                    for k in 0..cuts % 3 {
                        flash.budget = Some(u32::from(cut_at % 48) + u32::from(k));
                        flash.tear = 0x9E37_79B9u32.rotate_left(u32::from(cut_at));
                        let c = count_boot(&mut flash);
                        flash.budget = None;
                        if matches!(c, BootCounterStatus::Failed(_)) {
                            tally.torn_boots += 1;
                        }
                        check_count(c)?;
                    }
                    flash.read_only = flash_fails;
                    flash.programs = 0;
                    flash.bad_program = bad_write.map(|(k, weak)| (u32::from(k % 4), weak));
                    flash.tear = 0x85EB_CA6Bu32.rotate_left(u32::from(cut_at));
                    counter = count_boot(&mut flash);
                    // The bad program happened (the boot reached it).
                    if flash.bad_program.is_some_and(|(k, _)| flash.programs > k) {
                        tally.bad_writes += 1;
                    }
                    flash.read_only = false;
                    flash.bad_program = None;
                }
                _ => {
                    resets += 1;
                    counter = count_boot(&mut flash);
                }
            }
            if matches!(counter, BootCounterStatus::Failed(_)) {
                tally.failed_counters += 1;
            }
            check_count(counter)?;
            server = boot(&section, resets, key, counter);
            (in_force, locked, host_sigmas, model_check) = after_boot(&server, &provision)?;
            source = server.config_id().source;
            host_counter = 0;
            last_time = None;
            if server.status().boot_counter != counter {
                return Err(format!(
                    "status says {:?}, the boot had {counter:?}",
                    server.status().boot_counter
                ));
            }
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
        if matches!(step, Step::Replay { .. }) && recorded.is_empty() {
            continue;
        }
        let seq = next_seq;
        if !matches!(step, Step::Garbage(_)) {
            next_seq += 1;
        }
        let sats = sky(step);
        let cfg = config(step);
        let settings = model_check_settings(step);
        let (epoch_time, absurd) = match step {
            Step::Epoch { time_s, .. } => (f64::from(*time_s), false),
            Step::BadTime { kind, .. } => bad_time(*kind, last_time),
            _ => (last_time.map_or(1_000.0, |t| t + 1.0), false),
        };
        // The authenticated change of this step, if any: a new one
        // (recorded) or one recorded before (replayed).
        let signed: Option<Recorded> = match step {
            Step::AuthConfigure { .. } | Step::AuthLock => {
                host_counter += 1;
                let change = match (step, cfg) {
                    (Step::AuthConfigure { .. }, Some(c)) => RecordedChange::Configure(c),
                    _ => RecordedChange::Lock,
                };
                let tag = match &change {
                    RecordedChange::Configure(c) => raim_proto::auth::tag(
                        &KEY,
                        &server.nonce(),
                        host_counter,
                        &ChangeRef::Configure(c),
                    ),
                    RecordedChange::Lock => {
                        raim_proto::auth::tag(&KEY, &server.nonce(), host_counter, &ChangeRef::Lock)
                    }
                };
                let r = Recorded {
                    change,
                    counter: host_counter,
                    tag,
                };
                recorded.push(r);
                Some(r)
            }
            Step::Replay { index } => recorded.get(usize::from(*index) % recorded.len()).copied(),
            _ => None,
        };
        let frame: Vec<u8> = match step {
            Step::Garbage(bytes) => bytes
                .iter()
                .filter(|&&b| b != 0)
                .copied()
                .chain([0u8])
                .collect(),
            _ => {
                let ism = IsmFrameRef {
                    config: WireAraimConfig::default(),
                    p_const: [None; raim_core::measurement::MAX_SYSTEMS],
                    sats: &[],
                };
                let command = match (step, &signed) {
                    (_, Some(r)) => CommandRef::Authenticated(AuthenticatedRef {
                        counter: r.counter,
                        change: match &r.change {
                            RecordedChange::Configure(c) => ChangeRef::Configure(c),
                            RecordedChange::Lock => ChangeRef::Lock,
                        },
                        tag: r.tag,
                    }),
                    (
                        Step::Epoch { .. }
                        | Step::Oversized { .. }
                        | Step::BadTime { .. }
                        | Step::BadPrn { .. },
                        None,
                    ) => CommandRef::Linear {
                        time_s: epoch_time,
                        sats: &sats,
                    },
                    (Step::Configure { .. }, None) => {
                        CommandRef::Configure(cfg.as_ref().ok_or("no configuration")?)
                    }
                    (Step::Lock, None) => CommandRef::Lock,
                    (Step::ModelCheck { .. }, None) => {
                        CommandRef::ModelCheck(settings.ok_or("no settings")?)
                    }
                    (Step::EmptyIsm, None) => CommandRef::Araim(AraimCommandRef::Ism(ism)),
                    _ => CommandRef::Status,
                };
                encode(&RequestRef { seq, command }, &mut scratch, &mut out)
                    .map_err(|e| format!("encoding: {e:?}"))?
                    .to_vec()
            }
        };
        link.0.clear();
        let mut heard = Heard(Vec::new());
        for &b in &frame {
            let _ = server.on_byte(b, &mut link, &mut nmea, &mut heard);
        }
        // The host waits for the answer: a pause on the line, which ends
        // an RTCM candidate that garbage starting 0xD3 opened (as the
        // firmware's loop does after `LINK_IDLE_S`).
        let _ = server.on_line_idle(&mut link, &mut nmea, &mut heard);
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
        let oversized = matches!(step, Step::Oversized { .. });
        let want_seq = (!matches!(step, Step::Garbage(_))).then_some(seq);
        if oversized && answer.seq.is_none() {
            // Refused before its sequence number was read: the next
            // request carries the same one.
            next_seq = seq;
        } else if answer.seq != want_seq {
            return Err(format!("step {seq}: answer for {:?}", answer.seq));
        }
        let epoch_frame = matches!(
            step,
            Step::Epoch { .. }
                | Step::Oversized { .. }
                | Step::BadTime { .. }
                | Step::BadPrn { .. }
        );
        if epoch_frame {
            // The alarm output: cleared only by an `Ok` or `Excluded`
            // answer, asserted by every other answer to an epoch frame.
            let clearing = match &answer.body {
                ResponseBody::Result(r) => matches!(
                    r.decision,
                    raim_core::Decision::Ok | raim_core::Decision::Excluded
                )
                .then_some(r.decision),
                _ => None,
            };
            let last = heard.0.last().copied();
            let ok = match clearing {
                Some(d) => last == Some(Some(d)),
                None => matches!(
                    last,
                    Some(
                        None | Some(raim_core::Decision::Alarm | raim_core::Decision::Unavailable)
                    )
                ),
            };
            if !ok {
                return Err(format!(
                    "step {seq} {step:?}: answered {:?}, the platform heard {:?}",
                    answer.body, heard.0
                ));
            }
            if !matches!(step, Step::Epoch { .. }) {
                let refused_kind = match step {
                    Step::Oversized { .. } => {
                        tally.oversized += 1;
                        true
                    }
                    Step::BadPrn { .. } => {
                        tally.bad_prns += 1;
                        true
                    }
                    Step::BadTime { .. } => {
                        tally.bad_times += 1;
                        absurd || in_force.is_some_and(|c| c.mcusum.enabled)
                    }
                    _ => false,
                };
                if refused_kind && matches!(answer.body, ResponseBody::Result(_)) {
                    return Err(format!(
                        "step {seq} {step:?} (time {epoch_time}): answered {:?}",
                        answer.body
                    ));
                }
            }
            if matches!(answer.body, ResponseBody::Result(_)) && epoch_time.is_finite() {
                last_time = Some(epoch_time);
            }
        }
        match (step, &answer.body) {
            (
                Step::Epoch { .. }
                | Step::Oversized { .. }
                | Step::BadTime { .. }
                | Step::BadPrn { .. },
                ResponseBody::Result(r),
            ) => {
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
            (
                Step::Epoch { .. }
                | Step::Oversized { .. }
                | Step::BadTime { .. }
                | Step::BadPrn { .. },
                ResponseBody::Error(e),
            ) => {
                if in_force.is_none()
                    && !oversized
                    && !matches!(
                        e,
                        WireError::Unconfigured { .. }
                            | WireError::OutOfRange { .. }
                            | WireError::NonFinite { .. }
                            | WireError::PrnOutOfRange { .. }
                    )
                {
                    return Err(format!("step {seq}: unconfigured, answered {e:?}"));
                }
                tally.epochs += 1;
                tally.epoch_errors += 1;
            }
            (Step::Configure { .. }, ResponseBody::Configured) => {
                if locked {
                    return Err(format!("step {seq}: configured while locked"));
                }
                if keyed {
                    return Err(format!("step {seq}: a plain change taken by a keyed unit"));
                }
                let c = cfg.ok_or("no configuration")?;
                if c.validate().is_err() {
                    return Err(format!("step {seq}: an invalid configuration taken: {c:?}"));
                }
                in_force = Some(c);
                source = ConfigSource::Runtime;
                // A new configuration restarts the stateful monitors:
                // time is held to go forward from its first epoch.
                last_time = None;
                tally.configured += 1;
            }
            (
                Step::Configure { .. }
                | Step::Lock
                | Step::EmptyIsm
                | Step::AuthConfigure { .. }
                | Step::AuthLock
                | Step::Replay { .. }
                | Step::ModelCheck { .. },
                ResponseBody::Error(WireError::Unconfigured { provision: Some(_) }),
            ) if corrupt => {
                tally.locked_refusals += 1;
            }
            (
                Step::Configure { .. }
                | Step::EmptyIsm
                | Step::AuthConfigure { .. }
                | Step::AuthLock
                | Step::Replay { .. }
                | Step::ModelCheck { .. },
                ResponseBody::Error(WireError::Locked { .. }),
            ) if locked && !corrupt => {
                tally.locked_refusals += 1;
            }
            (Step::Configure { .. }, ResponseBody::Error(_)) if !locked => {
                tally.refused_configs += 1;
            }
            // The model check's settings: taken only within their bounds,
            // on an open, unkeyed unit; refused with the check's own
            // typed error otherwise, and nothing changes.
            (Step::ModelCheck { .. }, ResponseBody::Configured) => {
                let c = settings.ok_or("no settings")?;
                if locked || keyed {
                    return Err(format!(
                        "step {seq}: settings taken (locked {locked}, keyed {keyed})"
                    ));
                }
                if let Err(e) = c.check() {
                    return Err(format!(
                        "step {seq}: out-of-bounds settings taken: {c:?} ({e})"
                    ));
                }
                model_check = c;
                source = ConfigSource::Runtime;
                tally.model_checks_taken += 1;
            }
            (Step::ModelCheck { .. }, ResponseBody::Error(WireError::AuthRequired))
                if keyed && !locked => {}
            (Step::ModelCheck { .. }, ResponseBody::Error(e)) if !locked && !keyed => {
                let c = settings.ok_or("no settings")?;
                // NaN is not equal to itself: compare the printed forms.
                match c.check() {
                    Err(want) if format!("{want:?}") == format!("{e:?}") => {}
                    other => {
                        return Err(format!(
                            "step {seq}: {c:?} refused with {e:?}, the check gives {other:?}"
                        ))
                    }
                }
                tally.model_checks_refused += 1;
            }
            // `Lock` only with a configuration in force (issue 35).
            (Step::Lock, ResponseBody::LockEngaged)
                if !locked && !keyed && source != ConfigSource::Unconfigured =>
            {
                locked = true
            }
            (Step::Lock, ResponseBody::Error(WireError::Unconfigured { provision: None }))
                if !locked && !keyed && source == ConfigSource::Unconfigured => {}
            (Step::Lock, ResponseBody::Error(WireError::AuthRequired)) if !locked && keyed => {}
            (Step::Lock, ResponseBody::Error(WireError::Locked { .. })) if locked && !corrupt => {}
            (Step::Status, ResponseBody::Status(_)) => {}
            (Step::Garbage(_), ResponseBody::Error(_)) => {}
            (
                Step::EmptyIsm,
                ResponseBody::Error(
                    WireError::Araim(AraimWireError::EmptyIsm | AraimWireError::Disabled)
                    | WireError::AuthRequired,
                ),
            ) if !locked => {
                tally.empty_isms += 1;
            }
            // A frame sent before: never taken again, in this power-on or
            // a later one.
            (Step::Replay { .. }, ResponseBody::Error(_)) => {
                tally.replays_refused += 1;
            }
            (Step::AuthConfigure { .. } | Step::AuthLock, ResponseBody::Error(e)) => {
                if !keyed && *e != WireError::AuthNotProvisioned {
                    return Err(format!("step {seq}: unkeyed, answered {e:?}"));
                }
                if let (true, BootCounterStatus::Failed(error)) = (keyed, counter) {
                    if *e != (WireError::BootCounter { error }) {
                        return Err(format!(
                            "step {seq}: the boot counter failed, answered {e:?}"
                        ));
                    }
                }
                if matches!(e, WireError::BadAuthTag { .. } | WireError::Replayed { .. }) {
                    return Err(format!("step {seq}: a fresh change refused {e:?}"));
                }
            }
            (
                Step::AuthConfigure { .. } | Step::AuthLock,
                ResponseBody::Configured | ResponseBody::LockEngaged,
            ) => {
                if !keyed || locked || corrupt || !matches!(counter, BootCounterStatus::Count(_)) {
                    return Err(format!(
                        "step {seq}: taken {:?} (keyed {keyed}, locked {locked}, counter {counter:?})",
                        answer.body
                    ));
                }
                match (step, &answer.body) {
                    (Step::AuthConfigure { .. }, ResponseBody::Configured) => {
                        let c = cfg.ok_or("no configuration")?;
                        if c.validate().is_err() {
                            return Err(format!("step {seq}: an invalid configuration taken"));
                        }
                        in_force = Some(c);
                        source = ConfigSource::Runtime;
                        last_time = None;
                    }
                    (Step::AuthLock, ResponseBody::LockEngaged)
                        if source != ConfigSource::Unconfigured =>
                    {
                        locked = true;
                    }
                    (s, b) => return Err(format!("step {seq}: {s:?} answered {b:?}")),
                }
                tally.auth_taken += 1;
            }
            (s, b) => return Err(format!("step {seq}: {s:?} answered {b:?}")),
        }
        let id = ConfigId {
            fingerprint: UnitConfigRef {
                snapshot: in_force.as_ref(),
                araim: None,
                pf: None,
                host_sigmas,
                model_check: &model_check,
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
