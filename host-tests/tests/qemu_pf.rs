//! Particle-filter RAIM on the device: the same seed and the
//! same frames through the host's `raim_server::Server` and through
//! the firmware under QEMU (mps2-an386) give byte-identical answers
//! (compared as the postcard bytes of the whole `Response`: sequence
//! number, body, configuration fingerprint and lock state).
//!
//! Why bit-exact is expected: the PF engine is the same code on both sides
//! (`raim_server`'s `pf`, f32 particle state, `PfRaim`); its random stream is
//! integer xoshiro256++ with f64 ziggurat normals; f32 + - * / and sqrt
//! are correctly rounded on the M4F's FPU and on x86-64 SSE; the f64 paths
//! are correctly rounded soft-float on the M4F; the transcendental
//! functions come from the `libm` crate on the device and, on the host,
//! from whichever of `libm` or the platform `std` nalgebra/num-traits pick
//! in this build. The test checks that this holds.
//!
//! Short (CI): GA-PF 100 and GA-PF 300, 8 satellites, 14 epochs, including
//! a 60 m step, a satellite leaving view, a collapse and the typed errors.
//! Selected by `cargo test -p host-tests --release --test qemu_pf`.

mod qemu_common;

use std::time::Duration;

use qemu_common::{range_epoch, session, Rng};
use raim_core::pf::PfConfig;
use raim_core::{RangeObservation, SatId, System};
use raim_proto::frame::{encode, FrameReceiver};
use raim_proto::message::{CommandRef, RequestRef, Response, ResponseBody};
use raim_proto::{PfKind, WireError, WirePfConfig, MAX_RESPONSE_FRAME};
use raim_server::{Ga100Engine, NoPlatform, PfEngines, Server};

const ANSWER: Duration = Duration::from_secs(60);
/// Stack budget of a firmware session that ran only PF requests: measured
/// 16,732 B (BENCHMARKS.md "Particle-filter RAIM"), with room.
const PF_STACK_BUDGET_BYTES: u32 = 24 * 1024;

fn pf_config(kind: PfKind, particles: u32, seed: u64) -> WirePfConfig {
    WirePfConfig {
        kind,
        particles,
        seed,
        config: PfConfig {
            sigma_m: 3.0,
            mutation_m: 0.5,
            window: 8,
            pfa: 1e-3,
            ..PfConfig::default()
        },
    }
}

fn sky(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| (i as f64 * 41.0, 15.0 + (i as f64 * 23.0) % 70.0))
        .collect()
}

/// Epoch k of 8 GPS satellites; from `fault_from` a 60 m step on G04.
fn epoch(k: usize, rng: &mut Rng, fault_from: usize) -> Vec<RangeObservation> {
    let faults: Vec<(usize, f64)> = (k >= fault_from).then_some((3, 60.0)).into_iter().collect();
    let mut e = range_epoch(&sky(8), &[System::Gps], rng, &faults);
    // The noise is 1 m; the filters weight with a conservative 3 m
    // (`PfConfig::sigma_m`), as a receiver's sigma model would.
    for o in e.iter_mut() {
        o.sigma_m = None;
    }
    e
}

use qemu_common::Sink;

/// The host's answer to one frame.
fn host_answer(server: &mut Server, req: &RequestRef<'_>) -> Response {
    let mut scratch = vec![0u8; 4096];
    let mut out = vec![0u8; 4096];
    let frame = encode(req, &mut scratch, &mut out).unwrap().to_vec();
    let (mut link, mut nmea) = (Sink(Vec::new()), Sink(Vec::new()));
    for b in frame {
        server
            .on_byte(b, &mut link, &mut nmea, &mut NoPlatform)
            .unwrap();
    }
    let mut rx = FrameReceiver::<MAX_RESPONSE_FRAME>::new();
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

fn bytes(r: &Response) -> Vec<u8> {
    let mut buf = vec![0u8; raim_proto::MAX_RESPONSE_PAYLOAD + 64];
    postcard::to_slice(r, &mut buf).unwrap().to_vec()
}

/// A host server with every engine the firmware has, in leaked boxes.
fn host_server() -> Server {
    fn leak<T>(t: T) -> Option<&'static mut T> {
        Some(Box::leak(Box::new(t)))
    }
    use raim_core::pf::PfRaim;
    let mut s = Server::new();
    s.attach_pf(PfEngines {
        ekf: leak(PfRaim::new(0)),
        pf100: leak(PfRaim::new(0)),
        pf300: leak(PfRaim::new(0)),
        ga100: leak(PfRaim::new(0)),
        ga300: leak(PfRaim::new(0)),
    });
    // As the session set the firmware up: a bench host's runtime
    // `Configure(Config::default())`.
    s.take_runtime_config(raim_core::Config::default())
        .expect("the default configuration");
    s
}

/// The firmware's engines are statics initialised with `PfRaim::EMPTY`
/// (`firmware/src/main.rs` `pf_engines`) that the server restarts before
/// use: the empty engine, restarted, answers bit for bit like a new one.
#[test]
fn the_empty_engine_restarted_equals_a_new_one() {
    let cfg = pf_config(PfKind::Gapf, 100, 3).config;
    let mut empty = Box::new(Ga100Engine::EMPTY);
    empty.restart(3);
    let mut new = Box::new(Ga100Engine::new(3));
    let mut rng = Rng::new(5);
    for k in 0..6 {
        let e = epoch(k, &mut rng, 3);
        let a = empty.process(&cfg, k as f64, &e);
        let b = new.process(&cfg, k as f64, &e);
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "epoch {k}");
    }
}

/// `PfRaim::EMPTY` is all zero bytes: the QEMU board's five engine statics
/// are in `.bss` (no flash image, zeroed by the runtime). The STM32F4's
/// engine in `.ccmram` relies on the same fact: `main` zero-fills that
/// section, which is then the engine's `EMPTY` value.
#[test]
fn the_firmware_engines_are_all_zero_statics_in_bss() {
    use object::{Object, ObjectSection, ObjectSymbol};
    let elf = raim_qemu::firmware_elf().expect("firmware build");
    let data = std::fs::read(&elf).expect("the firmware ELF");
    let file = object::File::parse(&*data).expect("an ELF file");
    let mut found = Vec::new();
    for sym in file.symbols() {
        let name = sym.name().unwrap_or("");
        if !name.contains("pf_engines") {
            continue;
        }
        for engine in ["EKF", "PF100", "PF300", "GA100", "GA300"] {
            if name.contains(&format!("{}{engine}", engine.len())) {
                let section = sym
                    .section_index()
                    .and_then(|i| file.section_by_index(i).ok())
                    .and_then(|s| s.name().ok().map(str::to_string))
                    .unwrap_or_default();
                found.push((engine, section));
            }
        }
    }
    found.sort();
    assert_eq!(
        found,
        ["EKF", "GA100", "GA300", "PF100", "PF300"]
            .iter()
            .map(|e| (*e, ".bss".to_string()))
            .collect::<Vec<_>>(),
        "the engine statics and their sections"
    );
}

/// Stack of the thread that runs the host twin: a debug build constructs
/// the server and each PF engine (up to 159 KiB, docs/PF.md) on the stack,
/// with temporaries, before moving it to the heap, which overflowed a test
/// thread's 2 MiB.
const TWIN_STACK_BYTES: usize = 64 << 20;

#[test]
fn qemu_pf_answers_equal_the_host_server_byte_for_byte() {
    let t = std::thread::Builder::new()
        .stack_size(TWIN_STACK_BYTES)
        .spawn(answers_equal_the_host_server)
        .expect("a thread for the twin");
    assert!(t.join().is_ok(), "the twin comparison failed (above)");
}

fn answers_equal_the_host_server() {
    let mut fw = session();
    let mut host = host_server();

    let mut rng = Rng::new(14);
    let clean: Vec<Vec<RangeObservation>> = (0..10).map(|k| epoch(k, &mut rng, 6)).collect();
    let leaving = clean[3][1..].to_vec();
    let mut nan = clean[2].clone();
    nan[4].pseudorange_m = f64::NAN;
    let mut dup = clean[2].clone();
    dup[6].id = dup[0].id;
    let mut jump = clean[8].clone();
    for (i, o) in jump.iter_mut().enumerate() {
        o.pseudorange_m += if i % 2 == 0 { 1e5 } else { -1e5 };
    }
    let ga100 = pf_config(PfKind::Gapf, 100, 7);
    let ga300 = pf_config(PfKind::Gapf, 300, 7);
    let too_many = pf_config(PfKind::Gapf, 301, 7);
    let t0 = 1_709_208_000.0;
    fn at(t0: f64, k: f64, sats: &[RangeObservation]) -> CommandRef<'_> {
        CommandRef::PfRanges {
            time_s: t0 + k,
            apriori_m: None,
            sats,
        }
    }
    let ranges = |k, sats| at(t0, k, sats);
    let mut script: Vec<CommandRef<'_>> = vec![
        ranges(0.0, &clean[0]),
        CommandRef::PfConfigure(&too_many),
        CommandRef::PfConfigure(&ga100),
    ];
    for (k, e) in clean.iter().enumerate().take(3) {
        script.push(ranges(k as f64, e));
    }
    script.push(ranges(3.0, &clean[0][..4]));
    script.push(ranges(3.0, &nan));
    script.push(ranges(3.0, &dup));
    script.push(ranges(3.0, &leaving));
    for (k, e) in clean.iter().enumerate().skip(4).take(4) {
        script.push(ranges(k as f64, e));
    }
    script.push(ranges(8.0, &jump));
    script.push(ranges(9.0, &clean[9]));
    script.push(CommandRef::PfConfigure(&ga300));
    for (k, e) in clean.iter().enumerate().take(3) {
        script.push(ranges(10.0 + k as f64, e));
    }
    script.push(CommandRef::Lock);
    script.push(CommandRef::PfConfigure(&ga100));

    let mut kinds = Vec::new();
    for (i, &command) in script.iter().enumerate() {
        let seq = fw.send(command).unwrap();
        let got = fw
            .recv(ANSWER)
            .unwrap_or_else(|e| panic!("step {i}: {e:#}"));
        let want = host_answer(&mut host, &RequestRef { seq, command });
        assert_eq!(
            bytes(&got),
            bytes(&want),
            "step {i}: firmware {got:?}\nhost {want:?}"
        );
        kinds.push(match &got.body {
            ResponseBody::PfResult(r) if r.main_collapsed => "collapsed".to_string(),
            ResponseBody::PfResult(r) if r.alarm => {
                format!("alarm {}", r.excluded.map_or("-".into(), |s| s.to_string()))
            }
            ResponseBody::PfResult(r) => format!("ok {}", r.used),
            ResponseBody::Configured => "configured".into(),
            ResponseBody::LockEngaged => "locked".into(),
            ResponseBody::Error(WireError::PfNotConfigured) => "not configured".into(),
            ResponseBody::Error(WireError::PfParticles { .. }) => "particles".into(),
            ResponseBody::Error(WireError::TooFewSatellites { .. }) => "too few".into(),
            ResponseBody::Error(WireError::NonFinite { .. }) => "nan".into(),
            ResponseBody::Error(WireError::DuplicateSatellite { .. }) => "duplicate".into(),
            ResponseBody::Error(WireError::Locked { .. }) => "refused: locked".into(),
            other => panic!("step {i}: {other:?}"),
        });
    }
    // What the script exercised (the same on both sides, checked above).
    let g4 = SatId::new(System::Gps, 4).to_string();
    assert_eq!(&kinds[..3], ["not configured", "particles", "configured"]);
    assert_eq!(&kinds[3..6], ["ok 8", "ok 8", "ok 8"]);
    assert_eq!(&kinds[6..10], ["too few", "nan", "duplicate", "ok 7"]);
    assert!(kinds[10..14].contains(&format!("alarm {g4}")), "{kinds:?}");
    assert_eq!(kinds[14], "collapsed");
    assert_eq!(kinds[16], "configured");
    assert_eq!(kinds[20..], ["locked", "refused: locked"]);
    let st = fw.status().unwrap();
    println!(
        "PF under QEMU: {kinds:?}; stack high water {} B",
        st.stack_high_water_bytes
    );
    // The engines live in statics: the PF adds no large stack (the guard
    // of qemu_stack.rs holds the snapshot/MCUSUM budgets; this one the PF's).
    assert!(
        st.stack_high_water_bytes < PF_STACK_BUDGET_BYTES,
        "{} B",
        st.stack_high_water_bytes
    );
}
