//! Every method on the real-board build (`board-stm32f4`: 128 KiB SRAM +
//! 64 KiB CCM, ARAIM at the `ram-192k` capacities, the GA-PF at 100
//! particles in CCM; the snapshot monitor and its reconstruction FDE are
//! `qemu_boards.rs`') under QEMU's `netduinoplus2` (an STM32F405), through
//! the same runner as the QEMU board. Each answer is compared byte for byte
//! with the host's `Server` at the device precision (f32) wherever the
//! build's capacities admit the epoch; beyond them the device's own typed
//! answer is checked (capacity error, `ModeCapacity` unavailability).
//!
//! `(cd firmware && cargo stm32f4 --target-dir target/stm32f4)`, then
//! `cargo test --release -p host-tests --test qemu_stm32f4`; on the stream
//! build (`board-stm32f4,qemu-netduinoplus2,rtcm`, scripts/test.sh's
//! `stm32f4-stream-netduinoplus2`) with `RAIM_FIRMWARE_ELF_STM32F4` set to
//! its ELF (docs/FLASH.md "STM32F4: the stream").

#[path = "qemu_common/araim.rs"]
mod araim_common;
mod qemu_common;

use araim_common::{appendix_d, epoch_command, sky, Twin};
use qemu_common::{range_epoch, session_on, wire_bytes, Rng};
use raim_core::pf::PfConfig;
use raim_core::{Config, Decision, Epoch, FdeMethod, Raim, RangeObservation, SatId, System};
use raim_proto::araim_msg::{AraimAnswer, WireAraimResult, WireFde, WireUnavailable};
use raim_proto::message::{CommandRef, Response, ResponseBody};
use raim_proto::{PfKind, WireError, WirePfConfig, WireResult, CAPACITY};
use raim_qemu::Machine;

/// The build's ARAIM capacities (raim-server `ram-192k`: `ARAIM_SATS`,
/// `MAX_MODES`).
const ARAIM_SATS: usize = 24;
const MAX_MODES: u32 = 48;

/// The snapshot monitor's satellites on the STM32F4 stream build
/// (raim-server `SNAPSHOT_SATS` with `ram-192k` and `rtcm`).
const STREAM_BUILD_SATS: u16 = 24;

/// Stack headroom the build must keep above the measured high water
/// (docs/FLASH.md), bytes.
const STACK_HEADROOM_BYTES: u32 = 8 * 1024;

fn result(r: &Response) -> &WireAraimResult {
    match &r.body {
        ResponseBody::Araim(AraimAnswer::Result(w)) => w,
        other => panic!("{other:?}"),
    }
}

/// ARAIM on the STM32F4 build: App. D, then 24 satellites (G12 + E12) at
/// P_const 1e-8 (26 modes): clean, and 100 m on G01, excluded, both as
/// the host answers; then the device's own answers beyond its capacities.
#[test]
fn netduinoplus2_araim_appendix_d_and_24_satellites_with_exclusion() {
    let mut t = Twin::new(session_on(Machine::NetduinoPlus2));
    let (d, want) = appendix_d();
    t.ask(d.ism_command(), "App. D ISM");
    let r = t.ask(epoch_command(0.0, &d.obs), "App. D epoch");
    let w = result(&r);
    assert_eq!(
        u64::from(w.all_in_view.modes),
        want["modes"].as_u64().unwrap()
    );
    assert_eq!((w.decision, w.fde), (Decision::Ok, WireFde::NoFault));

    let mut clean = sky(ARAIM_SATS, usize::MAX, 0.0);
    clean.p_const = clean.p_const.map(|p| p.map(|_| 1e-8));
    t.ask(clean.ism_command(), "24 satellites, ISM at P_const 1e-8");
    let r = t.ask(epoch_command(1.0, &clean.obs), "24 satellites, clean");
    let w = result(&r);
    assert_eq!(w.all_in_view.modes, ARAIM_SATS as u32 + 2);
    assert_eq!(w.decision, Decision::Ok, "{w:?}");
    let faulted = sky(ARAIM_SATS, 0, 100.0);
    let r = t.ask(
        epoch_command(2.0, &faulted.obs),
        "24 satellites, 100 m on G01",
    );
    let w = result(&r);
    assert!(matches!(w.fde, WireFde::Excluded { .. }), "{:?}", w.fde);
    assert_eq!(w.excluded.as_slice(), &[SatId::new(System::Gps, 1)]);

    // 24 satellites at P_const 1e-4 need 327 modes: unavailable, untested,
    // with the typed reason (the host's 600-mode engine holds them).
    let pairs = sky(ARAIM_SATS, usize::MAX, 0.0);
    t.fw.send(pairs.ism_command()).unwrap();
    t.fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    t.fw.send(epoch_command(3.0, &pairs.obs)).unwrap();
    let r = t.fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    let w = result(&r);
    assert_eq!(w.decision, Decision::Unavailable, "{w:?}");
    assert_eq!(
        w.all_in_view.unavailable,
        Some(WireUnavailable::ModeCapacity {
            needed: 327,
            capacity: MAX_MODES
        }),
        "{w:?}"
    );
    // 25 satellites: the engine's satellite capacity, a typed error.
    let mut more = sky(ARAIM_SATS + 1, usize::MAX, 0.0);
    more.p_const = more.p_const.map(|p| p.map(|_| 1e-8));
    t.fw.send(more.ism_command()).unwrap();
    t.fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    t.fw.send(epoch_command(4.0, &more.obs)).unwrap();
    let r = t.fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(
        r.body,
        ResponseBody::Error(WireError::TooManySatellites {
            have: ARAIM_SATS as u32 + 1,
            capacity: ARAIM_SATS as u32
        }),
    );
    let st = t.fw.status().unwrap();
    println!(
        "netduinoplus2 ARAIM: stack high water {} B",
        st.stack_high_water_bytes
    );
    assert_stack_headroom(st.stack_high_water_bytes);
}

/// The stack the STM32F4 build leaves (from its ELF: the top of SRAM less
/// the end of the statics and the 1 KiB MPU guard) keeps
/// `STACK_HEADROOM_BYTES` above `high_water`.
fn assert_stack_headroom(high_water: u32) {
    let elf = raim_qemu::firmware_elf_for(Machine::NetduinoPlus2).unwrap();
    let data = std::fs::read(elf).unwrap();
    let file = object::File::parse(&*data).unwrap();
    use object::{Object, ObjectSymbol};
    let sym = |name: &str| {
        file.symbols()
            .find(|s| s.name() == Ok(name))
            .unwrap_or_else(|| panic!("{name}"))
            .address()
    };
    let guard_bytes = 1024;
    let statics_end = sym("__sheap").div_ceil(guard_bytes) * guard_bytes;
    let stack_bytes = (sym("_stack_start") - statics_end - guard_bytes) as u32;
    println!("STM32F4 stack {stack_bytes} B, high water {high_water} B");
    assert!(
        high_water + STACK_HEADROOM_BYTES <= stack_bytes,
        "stack {stack_bytes} B, high water {high_water} B"
    );
}

/// The GA-PF at 100 particles (the build's one PF engine, in CCM): a 60 m
/// step on G04 raises the alarm, isolates and excludes G04, as the host
/// answers byte for byte; the engines the build leaves out (the EKF here)
/// are answered `PfUnavailable`.
#[test]
fn netduinoplus2_pf_60_m_step_alarm_isolation_exclusion() {
    let mut fw = session_on(Machine::NetduinoPlus2);
    // The runner waited for the boot notice: one, of a power-on boot.
    assert_eq!(fw.boots().len(), 1, "{:?}", fw.boots());
    assert_eq!(fw.boots()[0].reset_cause, raim_proto::ResetCause::PowerOn);
    let mut host = Box::new(raim_server::Server::new());
    host.attach_pf(raim_server::PfEngines {
        ga100: Some(Box::leak(Box::new(raim_core::pf::PfRaim::new(0)))),
        ..raim_server::PfEngines::NONE
    });
    host.take_runtime_config(raim_core::Config::default())
        .unwrap();
    let cfg = WirePfConfig {
        kind: PfKind::Gapf,
        particles: 100,
        seed: 7,
        config: PfConfig {
            sigma_m: 3.0,
            mutation_m: 0.5,
            window: 8,
            pfa: 1e-3,
            ..PfConfig::default()
        },
    };
    let ekf = WirePfConfig {
        kind: PfKind::Ekf,
        particles: 0,
        ..cfg
    };
    let sky: Vec<(f64, f64)> = (0..8)
        .map(|i| (i as f64 * 41.0, 15.0 + (i as f64 * 23.0) % 70.0))
        .collect();
    let mut rng = Rng::new(14);
    let epochs: Vec<Vec<RangeObservation>> = (0..12)
        .map(|k| {
            let faults: Vec<(usize, f64)> = (k >= 6).then_some((3, 60.0)).into_iter().collect();
            let mut e = range_epoch(&sky, &[System::Gps], &mut rng, &faults);
            for o in e.iter_mut() {
                o.sigma_m = None;
            }
            e
        })
        .collect();
    let t0 = 1_709_208_000.0;
    let mut script = vec![CommandRef::PfConfigure(&ekf), CommandRef::PfConfigure(&cfg)];
    for (k, e) in epochs.iter().enumerate() {
        script.push(CommandRef::PfRanges {
            time_s: t0 + k as f64,
            apriori_m: None,
            sats: e,
        });
    }
    let g4 = SatId::new(System::Gps, 4);
    let mut alarms_excluding_g4 = 0;
    for (i, &command) in script.iter().enumerate() {
        let seq = fw.send(command).unwrap();
        let got = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
        let want = pf_host_answer(&mut host, seq, command);
        assert_eq!(
            araim_common::response_bytes(&got),
            araim_common::response_bytes(&want),
            "step {i}: firmware {got:?}\nhost {want:?}"
        );
        if i == 0 {
            assert_eq!(got.body, ResponseBody::Error(WireError::PfUnavailable));
        }
        if let ResponseBody::PfResult(r) = &got.body {
            if r.alarm && r.excluded == Some(g4) {
                alarms_excluding_g4 += 1;
            }
        }
    }
    assert!(alarms_excluding_g4 >= 1, "no alarm isolating G04");
    let st = fw.status().unwrap();
    println!(
        "netduinoplus2 PF: stack high water {} B",
        st.stack_high_water_bytes
    );
    assert_stack_headroom(st.stack_high_water_bytes);
}

/// The host server's answer to one frame.
fn pf_host_answer(server: &mut raim_server::Server, seq: u32, command: CommandRef<'_>) -> Response {
    use qemu_common::Sink;
    use raim_proto::frame::{encode, FrameReceiver};
    use raim_proto::message::RequestRef;
    let mut scratch = vec![0u8; 8192];
    let mut out = vec![0u8; 8192];
    let frame = encode(&RequestRef { seq, command }, &mut scratch, &mut out)
        .unwrap()
        .to_vec();
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    for b in frame {
        server
            .on_byte(b, &mut link, &mut nmea, &mut raim_server::NoPlatform)
            .unwrap();
    }
    let mut rx = Box::new(FrameReceiver::<{ raim_proto::MAX_RESPONSE_FRAME }>::new());
    let mut answers: Vec<Response> = link
        .0
        .iter()
        .filter_map(|&b| {
            rx.push(b)
                .map(|p| postcard::from_bytes(p.unwrap()).unwrap())
        })
        .collect();
    assert_eq!(answers.len(), 1, "{answers:?}");
    answers.pop().unwrap()
}

/// The reconstruction FDE (multi-fault, t_max 3) on the STM32F4 build: 32
/// satellites (G+E) with 60 m on index 2 and -70 m on index 9, both
/// excluded, bit for bit as the host core at the device precision. The
/// STM32F4 stream build (`board-stm32f4,rtcm`, docs/FLASH.md "STM32F4: the
/// stream", step 3) takes 24 satellites, as its `Status.capacity` says:
/// there the epoch is refused whole, `TooManySatellites { have: 32,
/// capacity: 24 }`, never truncated.
///
/// Verifies: SAFE-STACK
#[test]
fn netduinoplus2_multifault_excludes_two_faults_as_the_host() {
    let sky: Vec<(f64, f64)> = (0..32)
        .map(|i| ((i as f64 * 137.5) % 360.0, 10.0 + (i as f64 * 29.0) % 75.0))
        .collect();
    let sats = range_epoch(
        &sky,
        &[System::Gps, System::Galileo],
        &mut Rng::new(32),
        &[(2, 60.0), (9, -70.0)],
    );
    let cfg = Config {
        fde_method: FdeMethod::Reconstruction {
            t_max: 3,
            group_budget: 1000,
        },
        max_exclusions: 3,
        ..Config::default()
    };
    let mut fw = session_on(Machine::NetduinoPlus2);
    fw.configure(&cfg).unwrap();
    let epoch = Epoch::ranges(1.7e9, &sats, None);
    let capacity = fw.status().unwrap().capacity;
    let processed = fw.process(&epoch).unwrap();
    if capacity == STREAM_BUILD_SATS {
        assert_eq!(
            processed.outcome.unwrap_err(),
            WireError::TooManySatellites {
                have: 32,
                capacity: u32::from(STREAM_BUILD_SATS)
            }
        );
        let st = fw.status().unwrap();
        println!(
            "netduinoplus2 multi-fault (stream build, refused): stack high water {} B",
            st.stack_high_water_bytes
        );
        assert_stack_headroom(st.stack_high_water_bytes);
        return;
    }
    assert_eq!(
        usize::from(capacity),
        CAPACITY,
        "the product build's capacity"
    );
    let r = processed.outcome.unwrap();
    let mut host = Box::new(Raim::<CAPACITY, raim_proto::DevicePrecision>::new());
    let want = WireResult::from_result(&host.process(&cfg, &epoch).unwrap());
    assert_eq!(wire_bytes(&r), wire_bytes(&want), "firmware vs host");
    assert_eq!(r.decision, Decision::Excluded);
    assert_eq!(r.exclusions.len(), 2);
    let st = fw.status().unwrap();
    println!(
        "netduinoplus2 multi-fault: stack high water {} B",
        st.stack_high_water_bytes
    );
    assert_stack_headroom(st.stack_high_water_bytes);
}
