//! The unit's configuration authority under QEMU (docs/SAFETY.md
//! "Configuration authority", docs/PROTOCOL.md): each attack of the
//! threat-model table tried as a hostile host or a power glitch would, and
//! the unit shown refusing it or staying safe.
//!
//! - An unprovisioned unit boots Unconfigured: every epoch is refused
//!   (`Unconfigured`), the alarm output is asserted, the NMEA says no fix,
//!   and a reset returns it there whatever was taken at run time.
//! - A provisioned unit runs its configuration locked from boot, refuses
//!   every change, and boots into the same configuration (same
//!   fingerprint, still locked) after a watchdog reset and a panic.
//! - A corrupt or forged provisioned section leaves the unit Unconfigured.
//! - On a keyed unit every change, `Lock` included, must be authenticated
//!   under this boot's nonce: a frame recorded before a reset is refused
//!   after it, and a counter at the top of its range is refused.
//! - Out-of-bounds settings (ISM, Pfa, PF threshold, per-satellite sigmas,
//!   disabled parts) are refused over the wire.
//!
//! mps2-an386 runs them all (it has the test hooks that hang and panic
//! the unit); netduinoplus2, the real board's build, runs the boot-time
//! ones (it has no test hooks: a reset cannot be commanded there).

mod qemu_common;

use std::time::Duration;

use qemu_common::{host_result, range_vectors, wire_bytes};
use raim_core::{Config, Epoch, Phase};
use raim_proto::alert::AlarmOutput;
use raim_proto::auth::{tag, AuthenticatedRef, ChangeRef};
use raim_proto::message::{CommandRef, ResponseBody};
use raim_proto::unit::{UnitConfig, PROVISION_BYTES};
use raim_proto::{ConfigSource, ProvisionError, ResetCause, TestFault, WireError};
use raim_qemu::{Machine, Options, QemuSession};

const KEY: [u8; 32] = *b"unit 0042 key, never on the link";

/// The watchdog fires 2 s after the last feed (mps2-an386's `WATCHDOG_TIMEOUT_MS`, firmware/src/board/mps2.rs).
const WATCHDOG_S: f64 = 2.0;

fn elf(machine: Machine) -> std::path::PathBuf {
    raim_qemu::firmware_elf_for(machine).expect("firmware build")
}

fn start(elf: &std::path::Path, machine: Machine) -> QemuSession {
    QemuSession::start_with(
        elf,
        &Options {
            machine,
            raw: true,
            ..Options::default()
        },
    )
    .expect("qemu-system-arm with the firmware")
}

/// The installation's configuration: terminal-area alert limits (HAL 40 m,
/// VAL 50 m), the unit's own sigma model only, and model-check settings
/// other than the defaults (900 s, 4 samples, 1e-5 per hour), so that the
/// boot notice's fingerprint says the unit took them.
fn installed() -> UnitConfig {
    UnitConfig {
        snapshot: Some(Config {
            alert: raim_core::AlertLimits {
                hal_m: 40.0,
                val_m: Some(50.0),
            },
            ..Config::preset(Phase::Terminal)
        }),
        araim: None,
        pf: None,
        host_sigmas: false,
        model_check: raim_proto::WireModelCheckConfig {
            spacing_s: 900.0,
            window: 4,
            p_fa_per_hour: 1e-5,
        },
    }
}

/// Hang the unit (test hook) and wait for the watchdog reset's boot notice.
fn hang_and_reboot(fw: &mut QemuSession) -> raim_proto::BootNotice {
    fw.send(CommandRef::TestFault(TestFault::Hang)).unwrap();
    fw.wait_boot(Duration::from_secs_f64(10.0 * WATCHDOG_S))
        .unwrap()
}

fn epochs() -> Vec<(f64, Vec<raim_core::RangeObservation>, Option<[f64; 3]>)> {
    range_vectors(23).into_iter().take(3).collect()
}

/// Finding 2 (unprovisioned): no default ever claims integrity, before or
/// after a reset, and what a bench host took at run time is gone after it.
///
/// Verifies: SAFE-T2, WIRE-Unconfigured
#[test]
fn qemu_unprovisioned_unit_is_unconfigured_and_a_reset_returns_it_there() {
    let elf = elf(Machine::Mps2An386);
    let mut fw = start(&elf, Machine::Mps2An386);
    let boot = fw.boots()[0];
    assert_eq!(boot.config.source, ConfigSource::Unconfigured);
    assert!(!boot.config.locked);
    assert_eq!(boot.provision_error, None);
    assert_eq!((boot.resets, boot.reset_cause), (0, ResetCause::PowerOn));
    let unconfigured = |fw: &mut QemuSession| {
        for (t, sats, apriori) in epochs() {
            let p = fw.process(&Epoch::ranges(t, &sats, apriori)).unwrap();
            assert_eq!(
                p.outcome.unwrap_err(),
                WireError::Unconfigured { provision: None }
            );
            let rmc = p.nmea.iter().find(|s| s.contains("RMC,")).expect("RMC");
            assert_eq!(rmc.split(',').nth(2), Some("V"), "{rmc}");
        }
        let st = fw.status().unwrap();
        assert!(
            st.alarm_output.asserted() && st.alarm_pin_asserted,
            "{st:?}"
        );
        assert_eq!(st.config.source, ConfigSource::Unconfigured);
    };
    unconfigured(&mut fw);
    // A bench host configures and locks; the unit answers under it.
    fw.configure(&Config::preset(Phase::EnRoute)).unwrap();
    fw.lock().unwrap();
    let (t, sats, apriori) = &epochs()[0];
    assert!(fw
        .process(&Epoch::ranges(*t, sats, *apriori))
        .unwrap()
        .outcome
        .is_ok());
    // The reset: the notice first, then Unconfigured again, unlocked.
    let boot = hang_and_reboot(&mut fw);
    assert_eq!(boot.resets, 1);
    assert!(matches!(boot.reset_cause, ResetCause::Watchdog { .. }));
    assert_eq!(boot.config.source, ConfigSource::Unconfigured);
    assert!(!boot.config.locked);
    unconfigured(&mut fw);
}

/// Findings 2 and 3 (provisioned): the installed configuration runs locked
/// from boot, the same after a watchdog reset and a panic, and a corrupt
/// section leaves the unit Unconfigured.
///
/// Verifies: SAFE-T2, SAFE-T3, SAFE-T6, WIRE-Locked, WIRE-HostSigmaRefused
#[test]
fn qemu_provisioned_unit_keeps_its_locked_configuration_across_resets() {
    let unit = installed();
    let base = elf(Machine::Mps2An386);
    let img = raim_qemu::provision_config(&base, &unit, None, "provisioned").unwrap();
    let mut fw = start(&img, Machine::Mps2An386);
    let check_boot = |b: raim_proto::BootNotice| {
        assert_eq!(b.config.source, ConfigSource::Provisioned, "{b:?}");
        assert!(b.config.locked);
        assert_eq!(b.config.fingerprint, unit.fingerprint());
        assert_eq!(b.provision_error, None);
    };
    check_boot(fw.boots()[0]);
    let snapshot = unit.snapshot.unwrap();
    let in_service = |fw: &mut QemuSession| {
        for (t, sats, apriori) in epochs() {
            // Host sigmas are off in this installation: the unit's model.
            let sats: Vec<_> = sats
                .into_iter()
                .map(|s| raim_core::RangeObservation { sigma_m: None, ..s })
                .collect();
            let epoch = Epoch::ranges(t, &sats, apriori);
            let p = fw.process(&epoch).unwrap();
            let want = host_result(&snapshot, &epoch).map(|r| wire_bytes(&r));
            assert_eq!(
                p.outcome.map(|r| wire_bytes(&r)).map_err(|_| ()),
                want.map_err(|_| ())
            );
            assert_eq!(fw.last_config().unwrap().fingerprint, unit.fingerprint());
        }
        // Every change is refused: configure, lock, host sigmas, the
        // model check's settings.
        let locked = WireError::Locked {
            fingerprint: unit.fingerprint(),
        };
        assert_eq!(
            fw.call(CommandRef::ModelCheck(
                raim_proto::WireModelCheckConfig::DEFAULT
            ))
            .unwrap(),
            ResponseBody::Error(locked.clone())
        );
        assert_eq!(
            fw.try_configure(&Config::default()).unwrap(),
            Err(locked.clone())
        );
        assert_eq!(
            fw.call(CommandRef::HostSigmas(true)).unwrap(),
            ResponseBody::Error(locked.clone())
        );
        assert_eq!(
            fw.call(CommandRef::Lock).unwrap(),
            ResponseBody::Error(locked)
        );
    };
    in_service(&mut fw);
    // A host sigma is refused, typed, with the satellite's index.
    let (t, sats, apriori) = &epochs()[0];
    let p = fw.process(&Epoch::ranges(*t, sats, *apriori)).unwrap();
    assert!(matches!(p.outcome, Err(WireError::HostSigmaRefused { .. })));
    let boot = hang_and_reboot(&mut fw);
    check_boot(boot);
    in_service(&mut fw);
    fw.send(CommandRef::TestFault(TestFault::Panic)).unwrap();
    let boot = fw.wait_boot(Duration::from_secs(10)).unwrap();
    assert!(matches!(boot.reset_cause, ResetCause::Panic { .. }));
    check_boot(boot);
    in_service(&mut fw);
    drop(fw);

    // One corrupt byte anywhere in the sealed form: Unconfigured.
    let mut blob = [0u8; PROVISION_BYTES];
    raim_proto::unit::seal(&unit, None, &mut blob).unwrap();
    blob[40] ^= 0x01;
    let bad = raim_qemu::write_section(&base, ".raim_config", &blob, "corrupt").unwrap();
    let mut fw = start(&bad, Machine::Mps2An386);
    let b = fw.boots()[0];
    assert_eq!(b.config.source, ConfigSource::Unconfigured);
    assert_eq!(b.provision_error, Some(ProvisionError::BadSeal));
    let p = fw.process(&Epoch::ranges(*t, sats, *apriori)).unwrap();
    assert_eq!(
        p.outcome.unwrap_err(),
        WireError::Unconfigured {
            provision: Some(ProvisionError::BadSeal)
        }
    );
    // A corrupt unkeyed unit is no bench unit either (issue 35).
    assert_eq!(
        fw.try_configure(&Config::preset(Phase::EnRoute)).unwrap(),
        Err(WireError::Unconfigured {
            provision: Some(ProvisionError::BadSeal)
        })
    );
    for f in [img, bad] {
        let _ = std::fs::remove_file(f);
    }
}

/// Finding 4: on a keyed unit every change, `Lock` included, is
/// authenticated under the boot nonce; a recorded frame does not survive a
/// reset; the top counter is refused; a forged provisioning seal (SHA-256
/// where the key's HMAC is due) is refused.
///
/// Verifies: SAFE-T4, WIRE-AuthRequired, WIRE-BadAuthTag, WIRE-CounterExhausted
#[test]
fn qemu_keyed_unit_authenticates_every_change_and_no_frame_survives_a_reset() {
    let base = elf(Machine::Mps2An386);
    let keyed = raim_qemu::provision_key(&base, &KEY).unwrap();
    let mut fw = start(&keyed, Machine::Mps2An386);
    let boot = fw.boots()[0];
    assert!(boot.auth_provisioned);
    assert_eq!(boot.config.source, ConfigSource::Unconfigured);
    let nonce = boot.boot_nonce;
    assert_eq!(fw.status().unwrap().boot_nonce, nonce);
    let terminal = Config::preset(Phase::Terminal);
    fn signed(
        nonce: [u8; 16],
        counter: u64,
        change: ChangeRef<'_>,
    ) -> (u64, ChangeRef<'_>, [u8; 32]) {
        let t = tag(&KEY, &nonce, counter, &change);
        (counter, change, t)
    }
    fn send(
        fw: &mut QemuSession,
        (counter, change, tag): (u64, ChangeRef<'_>, [u8; 32]),
    ) -> ResponseBody {
        fw.call(CommandRef::Authenticated(AuthenticatedRef {
            counter,
            change,
            tag,
        }))
        .unwrap()
    }
    // Plain changes, Lock included, are refused.
    assert_eq!(
        fw.try_configure(&terminal).unwrap(),
        Err(WireError::AuthRequired)
    );
    assert_eq!(
        fw.call(CommandRef::Lock).unwrap(),
        ResponseBody::Error(WireError::AuthRequired)
    );
    // Authenticated under this boot's nonce: taken.
    let a1 = signed(nonce, 1, ChangeRef::Configure(&terminal));
    let (_, recorded) = fw
        .frame(CommandRef::Authenticated(AuthenticatedRef {
            counter: a1.0,
            change: a1.1,
            tag: a1.2,
        }))
        .unwrap();
    fw.send_raw(&recorded).unwrap();
    let r = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(r.body, ResponseBody::Configured);
    assert_eq!(r.config.source, ConfigSource::Runtime);
    // A tag under another nonce (a frame made for an earlier boot).
    let mut old = nonce;
    old[0] ^= 1;
    assert_eq!(
        send(&mut fw, signed(old, 2, ChangeRef::Configure(&terminal))),
        ResponseBody::Error(WireError::BadAuthTag { counter: 2 })
    );
    // The model check's settings: plain refused, authenticated taken.
    let window_4 = raim_proto::WireModelCheckConfig {
        window: 4,
        ..raim_proto::WireModelCheckConfig::DEFAULT
    };
    assert_eq!(
        fw.call(CommandRef::ModelCheck(window_4)).unwrap(),
        ResponseBody::Error(WireError::AuthRequired)
    );
    assert_eq!(
        send(&mut fw, signed(nonce, 3, ChangeRef::ModelCheck(window_4))),
        ResponseBody::Configured
    );
    // The top of the counter's range.
    assert_eq!(
        send(
            &mut fw,
            signed(nonce, u64::MAX, ChangeRef::Configure(&terminal))
        ),
        ResponseBody::Error(WireError::CounterExhausted { counter: u64::MAX })
    );
    // After the reset: a new nonce, the recorded frame refused, the unit
    // Unconfigured (runtime changes are volatile).
    let boot = hang_and_reboot(&mut fw);
    assert_ne!(boot.boot_nonce, nonce);
    assert_eq!(boot.config.source, ConfigSource::Unconfigured);
    fw.send_raw(&recorded).unwrap();
    // The new boot expects no sequence number yet: one answer, no gap.
    let bodies: Vec<ResponseBody> = (0..1)
        .map(|_| fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap().body)
        .collect();
    assert!(
        bodies.contains(&ResponseBody::Error(WireError::BadAuthTag { counter: 1 })),
        "{bodies:?}"
    );
    // Authenticated under the new nonce: configure, then lock.
    let n2 = boot.boot_nonce;
    assert_eq!(
        send(&mut fw, signed(n2, 1, ChangeRef::Configure(&terminal))),
        ResponseBody::Configured
    );
    assert_eq!(
        send(&mut fw, signed(n2, 2, ChangeRef::Lock)),
        ResponseBody::LockEngaged
    );
    assert!(matches!(
        send(
            &mut fw,
            signed(n2, 3, ChangeRef::Configure(&Config::default()))
        ),
        ResponseBody::Error(WireError::Locked { .. })
    ));
    drop(fw);
    // A configuration sealed with SHA-256 on a keyed unit: its seal must
    // be the key's HMAC, so it is refused and the unit stays Unconfigured.
    let forged = raim_qemu::provision_config(&keyed, &installed(), None, "forged").unwrap();
    let fw = start(&forged, Machine::Mps2An386);
    let b = fw.boots()[0];
    assert_eq!(b.config.source, ConfigSource::Unconfigured);
    assert_eq!(b.provision_error, Some(ProvisionError::BadSeal));
    drop(fw);
    // Sealed with the key: runs locked.
    let good = raim_qemu::provision_config(&keyed, &installed(), Some(&KEY), "sealed").unwrap();
    let fw = start(&good, Machine::Mps2An386);
    let b = fw.boots()[0];
    assert_eq!(b.config.source, ConfigSource::Provisioned);
    assert_eq!(b.config.fingerprint, installed().fingerprint());
    for f in [keyed, forged, good] {
        let _ = std::fs::remove_file(f);
    }
}

/// Findings 1, 5, 6 and 7: settings outside their operational bounds are
/// refused over the wire, typed, and nothing changes.
///
/// Verifies: SAFE-T1, SAFE-T5, SAFE-T6, SAFE-T7, WIRE-OutOfRange, MODEL-CONFIG
#[test]
fn qemu_out_of_bounds_settings_are_refused() {
    let mut fw = start(&elf(Machine::Mps2An386), Machine::Mps2An386);
    let refused = |b: &ResponseBody| matches!(b, ResponseBody::Error(_));
    // Pfa 1e-300 and a disabled MCUSUM with NaN k.
    let mut nan_k = Config::default();
    nan_k.mcusum.enabled = false;
    nan_k.mcusum.k = f64::NAN;
    for cfg in [
        Config {
            pfa: 1e-300,
            ..Config::default()
        },
        nan_k,
    ] {
        let r = fw.call(CommandRef::Configure(&cfg)).unwrap();
        assert!(refused(&r), "{cfg:?}: {r:?}");
    }
    assert_eq!(
        fw.status().unwrap().config.source,
        ConfigSource::Unconfigured
    );
    // A per-satellite sigma of 1e30 m.
    fw.configure(&Config::default()).unwrap();
    let (t, sats, apriori) = &epochs()[0];
    let mut huge = sats.clone();
    huge[0].sigma_m = Some(1e30);
    let p = fw.process(&Epoch::ranges(*t, &huge, *apriori)).unwrap();
    assert!(p.outcome.is_err(), "{:?}", p.outcome);
    // The particle filter's threshold is no wire field: it comes from the
    // calibrated table at the configured false-alarm probability, which is
    // bounded. A Pfa of 1e-300 (the old threshold of 1e300's counterpart:
    // a filter that never alarms) and one of 0.5 are refused.
    for pfa in [1e-300, 0.5] {
        let mut pf = raim_proto::pf_msg::WirePfConfig::gapf(100, 1);
        pf.config.pfa = pfa;
        let r = fw.call(CommandRef::PfConfigure(&pf)).unwrap();
        assert!(refused(&r), "pfa {pfa}: {r:?}");
    }
    // The model check's settings (issue 35): each field out of its bounds
    // is refused with the error the host's check gives (the field and the
    // value), and the settings in force stay (the fingerprint); settings
    // within the bounds are taken, and the fingerprint follows.
    let fingerprint = fw.status().unwrap().config.fingerprint;
    let d = raim_proto::WireModelCheckConfig::DEFAULT;
    for bad in [
        raim_proto::WireModelCheckConfig { window: 0, ..d },
        raim_proto::WireModelCheckConfig { window: 17, ..d },
        raim_proto::WireModelCheckConfig {
            spacing_s: f64::NAN,
            ..d
        },
        raim_proto::WireModelCheckConfig {
            spacing_s: 1e-4,
            ..d
        },
        raim_proto::WireModelCheckConfig {
            p_fa_per_hour: 0.9,
            ..d
        },
    ] {
        let want = bad.check().unwrap_err();
        match fw.call(CommandRef::ModelCheck(bad)).unwrap() {
            // NaN != NaN: compare the encodings.
            ResponseBody::Error(e) => assert_eq!(format!("{e:?}"), format!("{want:?}")),
            other => panic!("{bad:?}: {other:?}"),
        }
        assert_eq!(fw.status().unwrap().config.fingerprint, fingerprint);
    }
    let good = raim_proto::WireModelCheckConfig { window: 4, ..d };
    assert_eq!(
        fw.call(CommandRef::ModelCheck(good)).unwrap(),
        ResponseBody::Configured
    );
    let expected = raim_proto::UnitConfig {
        snapshot: Some(Config::default()),
        araim: None,
        pf: None,
        host_sigmas: true,
        model_check: good,
    };
    assert_eq!(
        fw.status().unwrap().config.fingerprint,
        expected.fingerprint()
    );
    drop(fw);
    // Provisioned out of its bounds: boot refuses it as the model check's
    // part, the unit stays Unconfigured and locked.
    let mut unit = installed();
    unit.model_check.window = 0;
    let img = raim_qemu::provision_config(
        &elf(Machine::Mps2An386),
        &unit,
        None,
        "model-check-window-0",
    )
    .unwrap();
    let fw = start(&img, Machine::Mps2An386);
    let b = fw.boots()[0];
    assert_eq!(b.config.source, ConfigSource::Unconfigured);
    assert!(b.config.locked);
    assert_eq!(
        b.provision_error,
        Some(ProvisionError::InvalidPart(
            raim_proto::unit::UnitPart::ModelCheck
        ))
    );
    drop(fw);
    let _ = std::fs::remove_file(img);
}

/// The boot-time authority on the real board's build (netduinoplus2, no
/// test hooks): unprovisioned it is Unconfigured with the alarm asserted;
/// provisioned it runs its configuration locked.
#[test]
fn qemu_netduinoplus2_boots_unconfigured_or_provisioned_and_locked() {
    let base = elf(Machine::NetduinoPlus2);
    let mut fw = start(&base, Machine::NetduinoPlus2);
    // The boot notice is the first frame, on this machine too.
    let notice = fw.boots().first().copied().unwrap();
    assert_eq!(notice.config.source, ConfigSource::Unconfigured);
    assert_eq!(notice.resets, 0);
    assert_eq!(
        fw.status().unwrap().config.source,
        ConfigSource::Unconfigured
    );
    let (t, sats, apriori) = &epochs()[0];
    let p = fw.process(&Epoch::ranges(*t, sats, *apriori)).unwrap();
    assert_eq!(
        p.outcome.unwrap_err(),
        WireError::Unconfigured { provision: None }
    );
    let st = fw.status().unwrap();
    assert_ne!(st.alarm_output, AlarmOutput::Clear);
    drop(fw);
    let unit = installed();
    let img = raim_qemu::provision_config(&base, &unit, None, "provisioned").unwrap();
    let mut fw = start(&img, Machine::NetduinoPlus2);
    let notice = fw.boots().first().copied().unwrap();
    assert_eq!(notice.config.source, ConfigSource::Provisioned);
    assert!(notice.config.locked);
    assert_eq!(notice.config.fingerprint, unit.fingerprint());
    let b = fw.status().unwrap();
    assert_eq!(b.config.source, ConfigSource::Provisioned);
    assert!(b.config.locked);
    assert_eq!(b.config.fingerprint, unit.fingerprint());
    assert!(matches!(
        fw.try_configure(&Config::default()).unwrap(),
        Err(WireError::Locked { .. })
    ));
    let _ = std::fs::remove_file(img);
}

/// Issue 35: a frame the unit cannot read may have been an epoch. On the
/// unit (mps2-an386), after a valid epoch has cleared the alarm output, a
/// 64-satellite epoch frame (longer than the receive buffer: `Overflow`)
/// asserts it at once (`EpochError`, the pin read back asserted, not
/// after the time-to-alert) and writes the no-fix sentences (a void RMC
/// without a time), as a refused epoch does; the next valid epoch clears
/// it again.
///
/// Verifies: SAFE-UNREADABLE, WIRE-Overflow
#[test]
fn qemu_oversized_frame_asserts_the_alarm_at_once_and_writes_no_fix() {
    let elf = elf(Machine::Mps2An386);
    let mut fw = start(&elf, Machine::Mps2An386);
    fw.configure(&Config::preset(Phase::EnRoute)).unwrap();
    let vectors = epochs();
    let valid = |fw: &mut QemuSession, k: usize| {
        let (t, sats, apriori) = &vectors[k];
        let p = fw.process(&Epoch::ranges(*t, sats, *apriori)).unwrap();
        assert!(p.outcome.is_ok(), "{:?}", p.outcome);
        let st = fw.status().unwrap();
        assert_eq!(
            (st.alarm_output, st.alarm_pin_asserted),
            (AlarmOutput::Clear, false)
        );
    };
    valid(&mut fw, 0);
    let _ = fw.drain_nmea();
    let (t, sats, _) = &vectors[1];
    let big: Vec<raim_core::LinearObservation> = (0..64u8)
        .map(|i| {
            raim_core::LinearObservation::from_az_el(
                raim_core::SatId::new(raim_core::System::Beidou, i % 63 + 1),
                f64::from(i) * 0.3,
                0.2 + f64::from(i % 7) * 0.2,
                0.1,
            )
        })
        .collect();
    assert!(!sats.is_empty());
    // Outside the session's sequence: the unit never reads it.
    let frame =
        raim_qemu::encode_request(&raim_proto::message::RequestRef::linear(9_999, *t, &big))
            .unwrap();
    assert!(
        frame.len() > raim_proto::MAX_REQUEST_FRAME,
        "{}",
        frame.len()
    );
    fw.send_raw(&frame).unwrap();
    let r = fw.recv(Duration::from_secs(30)).unwrap();
    assert!(
        matches!(r.body, ResponseBody::Error(WireError::Overflow { .. })) && r.seq.is_none(),
        "{r:?}"
    );
    let rmc = loop {
        let s = fw
            .take_nmea(1, Duration::from_secs(30))
            .expect("the no-fix sentences")
            .remove(0);
        if s.contains("RMC,") {
            break s;
        }
    };
    let f: Vec<&str> = rmc.split(',').collect();
    assert_eq!((f[1], f[2]), ("", "V"), "{rmc}");
    let st = fw.status().unwrap();
    assert_eq!(
        (st.alarm_output, st.alarm_pin_asserted),
        (AlarmOutput::EpochError, true)
    );
    valid(&mut fw, 1);
}

/// Issue 35: erasing `.raim_key` must not turn a sealed unit into an open
/// bench unit. The installation's configuration sealed under the key, in
/// an image whose key section is erased: the unit opens the section with
/// no key (`BadSeal`) and fails safe. It boots Unconfigured and locked;
/// every epoch is refused `Unconfigured { provision: BadSeal }` with the
/// alarm asserted (pin read back) and the no-fix sentences; a plain
/// `Configure`, `Lock` and `HostSigmas` are refused with the same reason;
/// `Status` says why; and a reset brings it back to the same state.
///
/// Verifies: SAFE-SEALED-NO-KEY, SAFE-LOCK-UNCONFIGURED
#[test]
fn qemu_sealed_unit_without_its_key_refuses_to_run() {
    let base = elf(Machine::Mps2An386);
    // Sealed with the key's HMAC, written into the unkeyed image.
    let img = raim_qemu::provision_config(&base, &installed(), Some(&KEY), "key-erased").unwrap();
    let mut fw = start(&img, Machine::Mps2An386);
    let refused = WireError::Unconfigured {
        provision: Some(ProvisionError::BadSeal),
    };
    let check = |fw: &mut QemuSession, b: raim_proto::BootNotice| {
        assert!(!b.auth_provisioned);
        assert_eq!(b.config.source, ConfigSource::Unconfigured);
        assert!(b.config.locked, "{b:?}");
        assert_eq!(b.provision_error, Some(ProvisionError::BadSeal));
        for (t, sats, apriori) in epochs() {
            let p = fw.process(&Epoch::ranges(t, &sats, apriori)).unwrap();
            assert_eq!(p.outcome.unwrap_err(), refused);
            let rmc = p.nmea.iter().find(|s| s.contains("RMC,")).expect("RMC");
            assert_eq!(rmc.split(',').nth(2), Some("V"), "{rmc}");
        }
        assert_eq!(
            fw.try_configure(&Config::preset(Phase::EnRoute)).unwrap(),
            Err(refused.clone())
        );
        for c in [CommandRef::Lock, CommandRef::HostSigmas(true)] {
            assert_eq!(fw.call(c).unwrap(), ResponseBody::Error(refused.clone()));
        }
        let st = fw.status().unwrap();
        assert_eq!(st.provision_error, Some(ProvisionError::BadSeal));
        assert_eq!(st.config.source, ConfigSource::Unconfigured);
        assert!(st.config.locked);
        assert!(
            st.alarm_output.asserted() && st.alarm_pin_asserted,
            "{st:?}"
        );
    };
    let b = fw.boots()[0];
    check(&mut fw, b);
    let b = hang_and_reboot(&mut fw);
    check(&mut fw, b);
    drop(fw);
    let _ = std::fs::remove_file(img);
}

/// Issue 35: on the unit, an unkeyed, Unconfigured unit refuses `Lock`
/// (`Unconfigured`, still unlocked) until a configuration is in force.
///
/// Verifies: SAFE-LOCK-UNCONFIGURED
#[test]
fn qemu_unconfigured_unit_refuses_lock() {
    let mut fw = start(&elf(Machine::Mps2An386), Machine::Mps2An386);
    assert_eq!(
        fw.call(CommandRef::Lock).unwrap(),
        ResponseBody::Error(WireError::Unconfigured { provision: None })
    );
    let st = fw.status().unwrap();
    assert!(!st.config.locked);
    assert_eq!(st.config.source, ConfigSource::Unconfigured);
    fw.configure(&Config::preset(Phase::EnRoute)).unwrap();
    fw.lock().unwrap();
    assert!(fw.status().unwrap().config.locked);
}

/// Issue 35, the link that lost a frame: the 3 bytes `D3 03 FF` (an RTCM 3
/// header declaring a 1029-byte frame) and 10 bytes, with no delimiter,
/// then a `Status` request in the same write. The request is not lost: the
/// dropped bytes are answered first, unasked, with what is known of them
/// (`TruncatedRtcm { received: 13, declared: 1029 }`), then the request
/// with its own sequence number, without waiting for a pause on the line.
/// The dropped bytes count as an unreadable frame: after a valid epoch
/// had cleared it, the alarm output is asserted (`EpochError`).
///
/// Verifies: SAFE-LINK-RESYNC, WIRE-TruncatedRtcm
#[test]
fn qemu_a_request_after_a_cut_rtcm_header_is_answered() {
    let mut fw = start(&elf(Machine::Mps2An386), Machine::Mps2An386);
    // A valid epoch first: the output is clear.
    fw.configure(&Config::preset(Phase::EnRoute)).unwrap();
    let (t, sats, apriori) = &epochs()[0];
    let p = fw.process(&Epoch::ranges(*t, sats, *apriori)).unwrap();
    assert!(p.outcome.is_ok(), "{:?}", p.outcome);
    assert_eq!(fw.status().unwrap().alarm_output, AlarmOutput::Clear);
    let (seq, status) = fw.frame(CommandRef::Status).unwrap();
    let mut bytes = vec![0xD3, 0x03, 0xFF];
    bytes.extend([0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x99, 0xAA]);
    bytes.extend(&status);
    fw.send_raw(&bytes).unwrap();
    let first = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(first.seq, None, "{first:?}");
    assert_eq!(
        first.body,
        ResponseBody::Error(WireError::TruncatedRtcm {
            received: 13,
            declared: 1029
        })
    );
    let second = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(second.seq, Some(seq), "{second:?}");
    let ResponseBody::Status(st) = second.body else {
        panic!("{second:?}")
    };
    assert_eq!(st.protocol_version, raim_proto::PROTOCOL_VERSION);
    // The dropped bytes may have been an epoch: the output was asserted
    // at once, as for any frame the unit cannot read.
    assert_eq!(
        (st.alarm_output, st.alarm_pin_asserted),
        (AlarmOutput::EpochError, true)
    );
}

/// Issue 35, a fleet key: two units that share a key but have different
/// provisioned unit IDs (`.raim_unit`, firmware/src/unit_id.rs) boot with
/// different nonces, and unit 2 refuses an authenticated frame made for
/// unit 1, which unit 1 takes. Under `-icount shift=0` everything else in
/// the nonce is the same for both (the key, the reset count, QEMU's zeroed
/// SRAM, the SysTick count at boot): the same unit booted twice gets the
/// same nonce, so the unit ID is what tells them apart.
///
/// Verifies: SAFE-UNIT-ID, WIRE-BadAuthTag
#[test]
fn qemu_units_sharing_a_key_do_not_share_a_nonce() {
    let base = elf(Machine::Mps2An386);
    let keyed = raim_qemu::provision_key(&base, &KEY).unwrap();
    let unit = |n: u8| {
        raim_qemu::write_section(&keyed, ".raim_unit", &[n; 16], &format!("unit{n}")).unwrap()
    };
    let (img1, img2) = (unit(1), unit(2));
    let boot = |img: &std::path::Path| {
        QemuSession::start_with(
            img,
            &Options {
                machine: Machine::Mps2An386,
                raw: true,
                icount: true,
                ..Options::default()
            },
        )
        .expect("qemu-system-arm with the firmware")
    };
    let nonce_of = |fw: &QemuSession| fw.boots()[0].boot_nonce;
    let n1 = nonce_of(&boot(&img1));
    let mut u1 = boot(&img1);
    let mut u2 = boot(&img2);
    assert_eq!(nonce_of(&u1), n1, "the same unit boots with the same nonce");
    assert_ne!(nonce_of(&u2), n1, "two units of one key");
    let terminal = Config::preset(Phase::Terminal);
    let change = ChangeRef::Configure(&terminal);
    let for_unit_1 = AuthenticatedRef {
        counter: 1,
        change,
        tag: tag(&KEY, &n1, 1, &change),
    };
    assert_eq!(
        u2.call(CommandRef::Authenticated(for_unit_1)).unwrap(),
        ResponseBody::Error(WireError::BadAuthTag { counter: 1 })
    );
    assert_eq!(
        u2.status().unwrap().config.source,
        ConfigSource::Unconfigured
    );
    assert_eq!(
        u1.call(CommandRef::Authenticated(for_unit_1)).unwrap(),
        ResponseBody::Configured
    );
    drop((u1, u2));
    for f in [keyed, img1, img2] {
        let _ = std::fs::remove_file(f);
    }
}

/// A keyed copy of `machine`'s firmware under a name of its own (the
/// other tests' `provision_key` copies share one name, and each removes
/// it when done).
fn own_keyed_copy(machine: Machine, tag: &str) -> std::path::PathBuf {
    let own = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("raim-{tag}.elf"));
    std::fs::copy(elf(machine), &own).unwrap();
    let keyed = raim_qemu::provision_key(&own, &KEY).unwrap();
    let _ = std::fs::remove_file(own);
    keyed
}

/// Issue 35 "Replay across a power cycle": power-on 1 of a keyed unit
/// takes an authenticated `Configure` and `Lock` and answers `Ok` under
/// them; the boot counter's flash is saved as the power-on leaves it
/// (QMP `pmemsave`) and QEMU ends. Power-on 2 is the same image under
/// `-icount` (the same SRAM, SysTick count and reset count: without a
/// counter its nonce was power-on 1's), given that flash (`-device
/// loader`): its counter is 2, its nonce new, and the recorded frames are
/// refused `BadAuthTag`; it stays Unconfigured and unlocked and answers no
/// epoch `Ok`. Power-on 3, the same image without the saved flash (a unit
/// whose counter was lost), boots with power-on 1's counter and nonce:
/// what tells power-ons apart under QEMU is the persisted counter.
///
/// Verifies: SAFE-BOOT-COUNTER, WIRE-BadAuthTag
#[test]
fn qemu_a_recorded_change_is_refused_after_a_power_cycle() {
    use raim_proto::boot_counter::BootCounterStatus;
    let keyed = own_keyed_copy(Machine::Mps2An386, "power-cycle");
    let power_on = |region: Option<(std::path::PathBuf, u32)>| {
        QemuSession::start_with(
            &keyed,
            &Options {
                machine: Machine::Mps2An386,
                raw: true,
                icount: true,
                qmp: true,
                boot_region: region,
                ..Options::default()
            },
        )
        .expect("qemu-system-arm with the firmware")
    };
    let saved = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-boot-region");

    // Power-on 1.
    let mut fw = power_on(None);
    let n1 = fw.boots()[0].boot_nonce;
    assert_eq!(
        fw.status().unwrap().boot_counter,
        BootCounterStatus::Count(1)
    );
    let terminal = Config::preset(Phase::Terminal);
    let mut recorded = Vec::new();
    for (counter, change) in [(1, ChangeRef::Configure(&terminal)), (2, ChangeRef::Lock)] {
        let a = AuthenticatedRef {
            counter,
            change,
            tag: tag(&KEY, &n1, counter, &change),
        };
        recorded.push(fw.frame(CommandRef::Authenticated(a)).unwrap().1);
    }
    for (f, want) in recorded
        .iter()
        .zip([ResponseBody::Configured, ResponseBody::LockEngaged])
    {
        fw.send_raw(f).unwrap();
        assert_eq!(fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap().body, want);
    }
    let (t, sats, apriori) = &epochs()[0];
    assert!(fw
        .process(&Epoch::ranges(*t, sats, *apriori))
        .unwrap()
        .outcome
        .is_ok());
    let addr = fw.save_boot_region(&keyed, &saved).unwrap();
    drop(fw);

    // Power-on 2: the same unit, its flash kept.
    let mut fw = power_on(Some((saved.clone(), addr)));
    let n2 = fw.boots()[0].boot_nonce;
    assert_ne!(n2, n1);
    assert_eq!(
        fw.status().unwrap().boot_counter,
        BootCounterStatus::Count(2)
    );
    for (f, counter) in recorded.iter().zip([1, 2]) {
        fw.send_raw(f).unwrap();
        assert_eq!(
            fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap().body,
            ResponseBody::Error(WireError::BadAuthTag { counter })
        );
    }
    let st = fw.status().unwrap();
    assert_eq!(st.config.source, ConfigSource::Unconfigured);
    assert!(!st.config.locked);
    for (t, sats, apriori) in epochs() {
        let p = fw.process(&Epoch::ranges(t, &sats, apriori)).unwrap();
        assert_eq!(
            p.outcome.unwrap_err(),
            WireError::Unconfigured { provision: None }
        );
    }
    drop(fw);

    // Power-on 3: the same image, the counter's flash not kept.
    let fw = power_on(None);
    assert_eq!(fw.boots()[0].boot_nonce, n1);
    drop(fw);
    for f in [saved, keyed] {
        let _ = std::fs::remove_file(f);
    }
}

/// QEMU's netduinoplus2 maps the STM32F405's flash read-only and leaves
/// its flash controller unimplemented (its registers read 0 and ignore
/// writes): the boot counter's erase of sector 10 does not erase, so the
/// counter fails, typed (`EraseVerify`: the region reads 0 where QEMU
/// loaded nothing), and `Status` says so. A keyed unit of that build
/// then refuses every authenticated change (`BootCounter`) and stays
/// Unconfigured: it never takes a change under a nonce that may repeat.
///
/// Verifies: SAFE-BOOT-COUNTER, WIRE-BootCounter
#[test]
fn qemu_netduinoplus2_cannot_count_boots_and_takes_no_authenticated_change() {
    use raim_proto::boot_counter::{BootCounterError, BootCounterStatus};
    let keyed = own_keyed_copy(Machine::NetduinoPlus2, "no-counter");
    let mut fw = start(&keyed, Machine::NetduinoPlus2);
    let st = fw.status().unwrap();
    let error = BootCounterError::EraseVerify {
        page: 0,
        word: 0,
        value: 0,
    };
    assert_eq!(st.boot_counter, BootCounterStatus::Failed(error));
    let nonce = st.boot_nonce;
    let terminal = Config::preset(Phase::Terminal);
    let change = ChangeRef::Configure(&terminal);
    let a = AuthenticatedRef {
        counter: 1,
        change,
        tag: tag(&KEY, &nonce, 1, &change),
    };
    assert_eq!(
        fw.call(CommandRef::Authenticated(a)).unwrap(),
        ResponseBody::Error(WireError::BootCounter { error })
    );
    assert_eq!(
        fw.status().unwrap().config.source,
        ConfigSource::Unconfigured
    );
    drop(fw);
    let _ = std::fs::remove_file(keyed);
}

/// The boot counter across resets within one QEMU session (mps2-an386).
/// With nothing loaded into its region the region is plain memory to
/// QEMU: a watchdog reset keeps it, and the count goes on (1, then 2).
/// A region given by `-device loader` (a simulated power cycle) is copied
/// back by QEMU at every system reset, so the count repeats after a reset
/// in that session (3, then 3): a QEMU artefact, not the flash's. The
/// nonce changes anyway, with the reset count.
///
/// Verifies: SAFE-BOOT-COUNTER
#[test]
fn qemu_boot_counter_across_resets_within_a_session() {
    use raim_proto::boot_counter::BootCounterStatus;
    let keyed = own_keyed_copy(Machine::Mps2An386, "resets");
    let saved = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("raim-resets-region");
    let options = |boot_region| Options {
        machine: Machine::Mps2An386,
        raw: true,
        qmp: true,
        boot_region,
        ..Options::default()
    };
    let mut fw = QemuSession::start_with(&keyed, &options(None)).unwrap();
    assert_eq!(
        fw.status().unwrap().boot_counter,
        BootCounterStatus::Count(1)
    );
    let boot = hang_and_reboot(&mut fw);
    assert_eq!(boot.resets, 1);
    assert_eq!(
        fw.status().unwrap().boot_counter,
        BootCounterStatus::Count(2)
    );
    let addr = fw.save_boot_region(&keyed, &saved).unwrap();
    drop(fw);
    let mut fw = QemuSession::start_with(&keyed, &options(Some((saved.clone(), addr)))).unwrap();
    let before = fw.boots()[0].boot_nonce;
    assert_eq!(
        fw.status().unwrap().boot_counter,
        BootCounterStatus::Count(3)
    );
    let boot = hang_and_reboot(&mut fw);
    assert_eq!(boot.resets, 1);
    assert_eq!(
        fw.status().unwrap().boot_counter,
        BootCounterStatus::Count(3)
    );
    assert_ne!(boot.boot_nonce, before);
    drop(fw);
    for f in [saved, keyed] {
        let _ = std::fs::remove_file(f);
    }
}
