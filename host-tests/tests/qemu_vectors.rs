//! The host's vectors through the firmware under QEMU (mps2-an386): every
//! answer must equal the host core's result for the same epoch, bit for bit
//! (compared as postcard bytes of `WireResult`, so NaN scores compare too).
//!
//! Why bit-exact is expected: both sides run the same Rust code in IEEE-754
//! f64 (the M4F's FPU is single precision, so f64 is software there, with
//! correctly rounded + - * / and sqrt, as on x86-64 SSE2), the transcendental
//! functions come from the same `libm` crate source on both, and rustc does
//! not contract a*b+c into FMA on either target.
//!
//! Selected by `cargo test -p host-tests qemu`. Needs `qemu-system-arm`
//! (scripts/test.sh installs it) and builds `firmware/` if needed.

mod qemu_common;

use host_tests::Sats;
use qemu_common::{host_result, range_vectors, session, wire_bytes};
use raim_core::{Config, Decision, Epoch, FiRule, Phase};
use raim_proto::WireError;

/// Verifies: FW-EQUIV
#[test]
fn qemu_vectors_match_the_host_core_bit_for_bit() {
    let mut fw = session();
    let cfg = Config::default();
    fw.configure(&cfg).unwrap();
    let mut files = 0;
    let mut compared = 0;
    let mut dir: Vec<_> = std::fs::read_dir(host_tests::vector_path(""))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    dir.sort();
    for path in dir
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
    {
        files += 1;
        let name = path.file_name().unwrap().to_str().unwrap();
        for (i, e) in host_tests::read_vector(name).iter().enumerate() {
            let sats = e.sats();
            let epoch = match &sats {
                Sats::Ranges(v) => Epoch::ranges(e.time_s, v, e.apriori_m),
                Sats::Linear(v) => Epoch::linear(e.time_s, v),
            };
            if epoch.len() > raim_proto::CAPACITY {
                continue;
            }
            compare(&mut fw, &cfg, &epoch, &format!("{name} epoch {i}"));
            compared += 1;
        }
    }
    assert!(
        files >= 1 && compared >= 8,
        "{files} files, {compared} epochs"
    );
}

#[test]
fn qemu_pseudorange_epochs_and_every_rule_match_the_host_core() {
    let mut fw = session();
    let rules = [
        FiRule::Mle,
        FiRule::LraimFlat,
        FiRule::LraimGaussian { kappa: 30.0 },
    ];
    for (k, rule) in rules.into_iter().enumerate() {
        let cfg = Config {
            rule,
            ..Config::preset(Phase::Terminal)
        };
        fw.configure(&cfg).unwrap();
        for (i, (time_s, sats, apriori)) in range_vectors(k as u64).iter().enumerate() {
            let epoch = Epoch::ranges(*time_s, sats, *apriori);
            let p = compare(
                &mut fw,
                &cfg,
                &epoch,
                &format!("rule {rule:?} range epoch {i}"),
            );
            // The decisions follow the injected faults (range_vectors).
            let got = p.outcome.clone().map(|r| {
                let mut x: Vec<String> = r.exclusions.iter().map(|e| e.id.to_string()).collect();
                x.sort();
                (r.decision, x)
            });
            let want: Result<(Decision, Vec<String>), WireError> = match i {
                0 | 4 => Ok((Decision::Ok, vec![])),
                1 => Ok((Decision::Excluded, vec!["G05".into()])),
                2 => Ok((Decision::Excluded, vec!["G03".into(), "G08".into()])),
                3 => Ok((Decision::Excluded, vec!["E06".into()])),
                _ => Err(WireError::TooFewSatellites { have: 4, need: 5 }),
            };
            assert_eq!(got, want, "rule {rule:?} range epoch {i}");
            // A solved pseudorange epoch has a position: GGA carries it.
            if let Ok(r) = &p.outcome {
                assert!(r.geodetic.is_some());
                assert!(
                    p.nmea[2].contains(",N,") || p.nmea[2].contains(",S,"),
                    "{:?}",
                    p.nmea
                );
            }
        }
    }
}

/// One epoch on both sides; the answers must be identical.
fn compare(
    fw: &mut raim_qemu::QemuSession,
    cfg: &Config,
    epoch: &Epoch<'_>,
    what: &str,
) -> raim_qemu::Processed {
    let p = fw
        .process(epoch)
        .unwrap_or_else(|e| panic!("{what}: {e:#}"));
    assert!(p.notices.is_empty(), "{what}: {:?}", p.notices);
    match (&p.outcome, host_result(cfg, epoch)) {
        (Ok(fw_r), Ok(host_r)) => {
            assert_eq!(
                wire_bytes(fw_r),
                wire_bytes(&host_r),
                "{what}: firmware {fw_r:?}\nhost {host_r:?}"
            );
            let host_nmea: Vec<String> = raim_proto::nmea::epoch_sentences(
                &host_r,
                &raim_proto::nmea::Sky::new(epoch),
                raim_proto::nmea::BUILT,
            )
            .unwrap()
            .iter()
            .map(|s| s.trim_end().to_string())
            .collect();
            assert_eq!(p.nmea, host_nmea, "{what}");
        }
        (Err(fw_e), Err(host_e)) => assert_eq!(*fw_e, WireError::from(host_e), "{what}"),
        (a, b) => panic!("{what}: firmware {a:?}, host {b:?}"),
    }
    p
}

/// With the MCUSUM on, the firmware's engine carries state from epoch to
/// epoch: its answers must equal those of one persistent host engine fed the
/// same sequence (the MCUSUM report included), epoch by epoch.
#[test]
fn qemu_mcusum_state_matches_a_persistent_host_engine() {
    let mut fw = session();
    let mut cfg = Config::default();
    cfg.mcusum.enabled = true;
    fw.configure(&cfg).unwrap();
    let mut host = raim_core::Raim::<{ raim_proto::CAPACITY }, raim_proto::DevicePrecision>::new();
    let mut with_report = 0;
    for e in host_tests::read_vector("snapshot_example.jsonl") {
        let sats = e.sats();
        let epoch = match &sats {
            Sats::Ranges(v) => Epoch::ranges(e.time_s, v, e.apriori_m),
            Sats::Linear(v) => Epoch::linear(e.time_s, v),
        };
        let want = host
            .process(&cfg, &epoch)
            .map(|r| raim_proto::WireResult::from_result(&r));
        let got = fw.process(&epoch).unwrap().outcome;
        match (got, want) {
            (Ok(g), Ok(w)) => {
                assert_eq!(
                    wire_bytes(&g),
                    wire_bytes(&w),
                    "t={}: {g:?}\n{w:?}",
                    e.time_s
                );
                with_report += usize::from(g.mcusum.is_some());
            }
            (g, w) => panic!("t={}: firmware {g:?}, host {w:?}", e.time_s),
        }
    }
    assert_eq!(with_report, 8, "every epoch carries the MCUSUM report");
}

/// The reconstruction FDE (`FdeMethod::Reconstruction`, docs/MULTIFAULT.md)
/// in the firmware: the pseudorange vectors (clean, one, two faults, a
/// Galileo fault) and a 20-satellite pseudorange epoch with three faults
/// give the host core's answers bit for bit.
#[test]
fn qemu_reconstruction_fde_matches_the_host_core() {
    let mut fw = session();
    let cfg = Config {
        fde_method: raim_core::FdeMethod::Reconstruction {
            t_max: 3,
            group_budget: 1000,
        },
        max_exclusions: 3,
        ..Config::preset(Phase::Terminal)
    };
    fw.configure(&cfg).unwrap();
    for (i, (time_s, sats, apriori)) in range_vectors(7).iter().enumerate() {
        let epoch = Epoch::ranges(*time_s, sats, *apriori);
        compare(
            &mut fw,
            &cfg,
            &epoch,
            &format!("reconstruction range epoch {i}"),
        );
    }
    let sky: Vec<(f64, f64)> = (0..20)
        .map(|i| (i as f64 * 137.5 % 360.0, 12.0 + (i as f64 * 29.0) % 70.0))
        .collect();
    let sats = qemu_common::range_epoch(
        &sky,
        &[raim_core::System::Gps, raim_core::System::Galileo],
        &mut qemu_common::Rng::new(3),
        &[(2, 60.0), (7, -70.0), (11, 80.0)],
    );
    let epoch = Epoch::ranges(1.7e9, &sats, None);
    let p = compare(&mut fw, &cfg, &epoch, "three faults");
    let got = p.outcome.map(|r| {
        let mut x: Vec<usize> = r.exclusions.iter().map(|e| e.index).collect();
        x.sort();
        (r.decision, x)
    });
    assert_eq!(got, Ok((Decision::Excluded, vec![2, 7, 11])));
}
