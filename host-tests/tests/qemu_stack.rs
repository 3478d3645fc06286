//! The firmware's stack high water for the deepest epochs we know (the
//! default FDE, the MCUSUM's alarm and hold path, the reconstruction FDE,
//! all at N = 32 with two faults), measured by stack painting under QEMU
//! (deterministic: same ELF, same input, same bytes), as a regression guard.
//! The goal is 16 KiB (docs/bench-history/firmware.md has the history), and
//! the budgets below are the measured values rounded up to the next KiB: a change that deepens the stack fails here and has to
//! update them (and BENCHMARKS.md "Firmware: flash, RAM, stack") deliberately.
//!
//! Selected by `cargo test -p host-tests qemu`.

#[path = "qemu_common/araim.rs"]
mod araim_common;
mod qemu_common;

use qemu_common::{range_epoch, session, wire_bytes, Rng};
use raim_core::{
    AlarmSource, Config, Decision, Epoch, FdeMethod, Raim, RangeObservation, SatId, System,
};
use raim_proto::araim_msg::AraimAnswer;
use raim_proto::message::ResponseBody;
use raim_proto::{WireResult, CAPACITY};

/// The 32-satellite sky of every scenario here (azimuth, elevation, deg).
fn sky32() -> Vec<(f64, f64)> {
    (0..32)
        .map(|i| ((i as f64 * 137.5) % 360.0, 10.0 + (i as f64 * 29.0) % 75.0))
        .collect()
}

/// 32 satellites, GPS + Galileo, two faults (60 m and -70 m): solve, FDE
/// with two exclusions and the runner-up checks, PLs, wire result, NMEA.
fn two_fault_epoch() -> Vec<RangeObservation> {
    range_epoch(
        &sky32(),
        &[System::Gps, System::Galileo],
        &mut Rng::new(32),
        &[(2, 60.0), (9, -70.0)],
    )
}

/// Snapshot monitor (MCUSUM off), with the request, the results and the
/// FDE outcome in the server's and the monitor's static storage: measured
/// 13,476 B (BENCHMARKS.md; the history is in docs/bench-history/).
const STACK_BUDGET_SNAPSHOT_B: u32 = 14 * 1024;
/// MCUSUM on (the sequential path's frames on top), an epoch in which the
/// CUSUM itself does not alarm: measured 13,908 B. An epoch whose CUSUM
/// alarms is bounded by [`STACK_BUDGET_MCUSUM_ALARM_B`].
const STACK_BUDGET_MCUSUM_B: u32 = 14 * 1024;

/// Verifies: SAFE-STACK
#[test]
fn qemu_stack_high_water_of_a_32_satellite_two_fault_epoch() {
    let sats = two_fault_epoch();
    for (label, mcusum, budget) in [
        ("snapshot", false, STACK_BUDGET_SNAPSHOT_B),
        ("mcusum on", true, STACK_BUDGET_MCUSUM_B),
    ] {
        let mut fw = session();
        let mut cfg = Config::default();
        cfg.mcusum.enabled = mcusum;
        fw.configure(&cfg).unwrap();
        let p = fw.process(&Epoch::ranges(1.7e9, &sats, None)).unwrap();
        let r = p.outcome.unwrap();
        assert_eq!(r.decision, Decision::Excluded, "{label}");
        assert_eq!(r.exclusions.len(), 2, "{label}");
        let high_water = fw.status().unwrap().stack_high_water_bytes;
        println!("{label}: stack high water {high_water} B (budget {budget} B)");
        assert!(high_water <= budget, "{label}: {high_water} B > {budget} B");
    }
}

/// The MCUSUM's alarm path: an epoch whose CUSUM
/// alarms (identification from the accumulated vector, the subset solve and
/// test, the hold) and the epochs after it (the held satellite filtered out
/// of the input first, `without_held_ranges`, into the sequential engine's
/// storage). Measured 13,604 B up to and including the alarm epoch, and
/// 13,764 B after the held epochs.
const STACK_BUDGET_MCUSUM_ALARM_B: u32 = 14 * 1024;
/// The reconstruction FDE (`FdeMethod::Reconstruction`, t_max 3) with two
/// faults, MCUSUM off and on, with the reconstruction's scratch in the
/// snapshot engine's storage: measured 13,436 B with the MCUSUM on
/// (BENCHMARKS.md), of which the link's demultiplexer of host and RTCM
/// frames takes 224 B on every path (13,220 B before it). The guard is the
/// snapshot path's.
const STACK_BUDGET_RECONSTRUCTION_B: u32 = 14 * 1024;

/// The persistent bias of the CUSUM scenario (m, sigma 1 m): too small for
/// the snapshot test (its non-centrality, ~bias^2 S_ii, stays far below
/// T^2 - dof at dof 26), large enough for the CUSUM (k = 1) to reach h
/// within a few tens of epochs.
const CUSUM_BIAS_M: f64 = 3.0;
/// Epochs of the CUSUM scenario at most before its alarm, and after it
/// (the held satellite's epochs).
const MAX_EPOCHS_TO_ALARM: u32 = 60;
const EPOCHS_AFTER_ALARM: u32 = 3;

/// Fault 1: 60 m on satellite index 2 every epoch (the snapshot excludes
/// it); fault 2: `CUSUM_BIAS_M` on index 9 (G10), which only the MCUSUM
/// sees. 1 s epochs, fresh noise each.
fn cusum_epoch(t: u32) -> Vec<RangeObservation> {
    range_epoch(
        &sky32(),
        &[System::Gps, System::Galileo],
        &mut Rng::new(1000 + u64::from(t)),
        &[(2, 60.0), (9, CUSUM_BIAS_M)],
    )
}

/// N = 32, MCUSUM on, two faults, run until the CUSUM alarms and excludes
/// the biased satellite, then a few epochs with it held. Every epoch is
/// also run through the host core in the device's precision and must agree
/// with the firmware bit for bit (the alarm path's first QEMU check). The
/// stack high water is read after every epoch.
#[test]
fn qemu_stack_high_water_of_an_mcusum_alarm_with_two_faults() {
    let mut cfg = Config::default();
    cfg.mcusum.enabled = true;
    let mut fw = session();
    fw.configure(&cfg).unwrap();
    let mut host = Raim::<CAPACITY, raim_proto::DevicePrecision>::new();
    let biased = SatId::new(System::Galileo, 10);
    let (mut alarm_at, mut worst_before, mut worst_alarm, mut worst_after) = (None, 0, 0, 0);
    for t in 0..MAX_EPOCHS_TO_ALARM + EPOCHS_AFTER_ALARM {
        let sats = cusum_epoch(t);
        let epoch = Epoch::ranges(1.7e9 + f64::from(t), &sats, None);
        let r = fw.process(&epoch).unwrap().outcome.unwrap();
        let want = WireResult::from_result(&host.process(&cfg, &epoch).unwrap());
        assert_eq!(wire_bytes(&r), wire_bytes(&want), "t {t}: firmware vs host");
        let high_water = fw.status().unwrap().stack_high_water_bytes;
        let m = r.mcusum.unwrap();
        match alarm_at {
            None if m.alarm => {
                assert_eq!(m.source, AlarmSource::Both, "t {t}");
                assert_eq!(m.identified, Some(biased), "t {t}");
                assert_eq!(r.decision, Decision::Excluded, "t {t}");
                let ids: Vec<SatId> = r.exclusions.iter().map(|e| e.id).collect();
                assert_eq!(ids, [SatId::new(System::Gps, 3), biased], "t {t}");
                alarm_at = Some(t);
                worst_alarm = high_water;
            }
            None => {
                assert!(t + 1 < MAX_EPOCHS_TO_ALARM, "no CUSUM alarm in {t} epochs");
                worst_before = high_water;
            }
            Some(a) => {
                assert!(m.held.contains(&Some(biased)), "t {t}");
                let held = r.satellites.iter().find(|s| s.id == biased).unwrap();
                assert!(!held.used, "t {t}");
                assert_eq!(r.decision, Decision::Excluded, "t {t}");
                if t == a + EPOCHS_AFTER_ALARM {
                    worst_after = high_water;
                    break;
                }
            }
        }
    }
    let a = alarm_at.unwrap();
    println!(
        "mcusum alarm at epoch {a} (bias {CUSUM_BIAS_M} m): stack high water {worst_before} B before, \
         {worst_alarm} B after the alarm epoch, {worst_after} B after {EPOCHS_AFTER_ALARM} held epochs \
         (budget {STACK_BUDGET_MCUSUM_ALARM_B} B)"
    );
    assert!(
        worst_after <= STACK_BUDGET_MCUSUM_ALARM_B,
        "{worst_after} B > {STACK_BUDGET_MCUSUM_ALARM_B} B"
    );
}

/// N = 32, the reconstruction FDE (t_max 3), the two faults of the
/// snapshot scenario, MCUSUM off and on, each on a fresh firmware.
#[test]
fn qemu_stack_high_water_of_the_reconstruction_fde_with_two_faults() {
    let sats = two_fault_epoch();
    for (label, mcusum) in [("reconstruction", false), ("reconstruction + mcusum", true)] {
        let mut cfg = Config {
            fde_method: FdeMethod::Reconstruction {
                t_max: 3,
                group_budget: 1000,
            },
            max_exclusions: 3,
            ..Config::default()
        };
        cfg.mcusum.enabled = mcusum;
        let mut fw = session();
        fw.configure(&cfg).unwrap();
        let epoch = Epoch::ranges(1.7e9, &sats, None);
        let r = fw.process(&epoch).unwrap().outcome.unwrap();
        let want = WireResult::from_result(
            &Raim::<CAPACITY, raim_proto::DevicePrecision>::new()
                .process(&cfg, &epoch)
                .unwrap(),
        );
        assert_eq!(
            wire_bytes(&r),
            wire_bytes(&want),
            "{label}: firmware vs host"
        );
        assert_eq!(r.decision, Decision::Excluded, "{label}");
        let mut ids: Vec<SatId> = r.exclusions.iter().map(|e| e.id).collect();
        ids.sort();
        assert_eq!(
            ids,
            [SatId::new(System::Gps, 3), SatId::new(System::Galileo, 10)],
            "{label}"
        );
        let high_water = fw.status().unwrap().stack_high_water_bytes;
        let budget = STACK_BUDGET_RECONSTRUCTION_B;
        println!("{label}: stack high water {high_water} B (budget {budget} B)");
        assert!(high_water <= budget, "{label}: {high_water} B > {budget} B");
    }
}

/// An ARAIM session (the 16 KiB goal applies to it too): the ISM, then the 20-satellite sky with 100 m on
/// satellite 0 (all-in-view ARAIM, detection, FDE with the exclusion's
/// subset), the deepest of `qemu_araim_bench`'s sessions (15,620 B, no
/// deeper with 24 or 32 satellites). Measured 15,620 B.
const STACK_BUDGET_ARAIM_B: u32 = 16 * 1024;

/// Verifies: SAFE-STACK
#[test]
fn qemu_stack_high_water_of_an_araim_session() {
    let s = araim_common::sky20(0, 100.0);
    let mut fw = session();
    let seq = fw.send(s.ism_command()).unwrap();
    let r = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(r.seq, Some(seq), "{r:?}");
    let seq = fw.send(araim_common::epoch_command(0.0, &s.obs)).unwrap();
    let r = fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    assert_eq!(r.seq, Some(seq), "{r:?}");
    let ResponseBody::Araim(AraimAnswer::Result(w)) = r.body else {
        panic!("{:?}", r.body)
    };
    assert_eq!(w.decision, Decision::Excluded);
    assert_eq!(
        w.excluded.iter().copied().collect::<Vec<_>>(),
        [SatId::new(System::Gps, 1)]
    );
    let high_water = fw.status().unwrap().stack_high_water_bytes;
    let budget = STACK_BUDGET_ARAIM_B;
    println!("araim session: stack high water {high_water} B (budget {budget} B)");
    assert!(high_water <= budget, "araim: {high_water} B > {budget} B");
}
