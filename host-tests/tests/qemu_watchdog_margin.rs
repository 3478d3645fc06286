//! The STM32F4 build's watchdog margin: the costliest epoch a host can send
//! to each method, within the build's capacities, counted in guest
//! instructions under QEMU's netduinoplus2 (`-icount shift=0`), bounded in
//! cycles by a stated cycles-per-instruction bound, and compared with half
//! the IWDG's shortest timeout (the LSI at its datasheet maximum) at each
//! clock the board can run at: 168 MHz from the PLL, 16 MHz on the HSI
//! fallback. The test fails when an epoch's count grows past the budget
//! that leaves. The derivation and the table: docs/SAFETY.md "Watchdog
//! margin"; the counts: BENCHMARKS.md "Watchdog margin (STM32F4)".
//!
//! `(cd firmware && cargo stm32f4 --features qemu-netduinoplus2 --target-dir target/stm32f4)`, then
//! `cargo test --release -p host-tests --test qemu_watchdog_margin -- --nocapture`

#[path = "qemu_common/araim.rs"]
mod araim_common;
mod qemu_common;
#[path = "qemu_common/watchdog.rs"]
mod watchdog;

use araim_common::{epoch_command, ranges_command, ranges_of, sky, Scenario};
use qemu_common::{range_epoch, Rng};
use raim_core::pf::PfConfig;
use raim_core::{Config, Epoch, FdeMethod, RangeObservation, System};
use raim_proto::message::CommandRef;
use raim_proto::{PfKind, WirePfConfig};
use raim_qemu::{Options, QemuSession};
use watchdog::{
    budget_instructions, epoch, instructions, netduino, CPI_BOUND_HSI, CPI_BOUND_PLL,
    CROSS_CHECK_TOLERANCE, IWDG_TIMEOUT_HSI_MS, IWDG_TIMEOUT_PLL_MS, LSI_MAX_HZ,
    MPS2_INSTRUCTIONS_PER_TICK,
};

/// A 32-satellite G+E pseudorange sky with `faults` (index, m).
fn sky32(faults: &[(usize, f64)]) -> Vec<RangeObservation> {
    let sky: Vec<(f64, f64)> = (0..32)
        .map(|i| ((i as f64 * 137.5) % 360.0, 10.0 + (i as f64 * 29.0) % 75.0))
        .collect();
    range_epoch(
        &sky,
        &[System::Gps, System::Galileo],
        &mut Rng::new(32),
        faults,
    )
}

/// The worst case per method: (method, case, instructions).
type Worst = (&'static str, String, u64);

fn keep(worst: &mut Option<Worst>, method: &'static str, case: String, n: u64) {
    println!("{method:>14} | {case} | {n}");
    if worst.as_ref().is_none_or(|w| n > w.2) {
        *worst = Some((method, case, n));
    }
}

/// The snapshot monitor at its capacity (32 satellites, pseudoranges) with
/// the sequential FDE at its most exclusions, and the reconstruction FDE
/// at t_max 3 with the largest group budget (the whole covering design is
/// searched), each with more faults than it can remove.
fn snapshot_and_reconstruction(fw: &mut QemuSession) -> Vec<Worst> {
    let faults = [(2, 60.0), (9, -70.0), (15, 80.0), (21, -90.0), (27, 100.0)];
    let mut seq_worst = None;
    let mut rec_worst = None;
    let sequential = Config {
        max_exclusions: raim_core::snapshot::fde::MAX_EXCLUSIONS as u8,
        ..Config::default()
    };
    let reconstruction = Config {
        fde_method: FdeMethod::Reconstruction {
            t_max: 3,
            group_budget: u16::MAX,
        },
        max_exclusions: 3,
        ..Config::default()
    };
    for (name, cfg, slot) in [
        ("snapshot", &sequential, &mut seq_worst),
        ("reconstruction", &reconstruction, &mut rec_worst),
    ] {
        fw.configure(cfg).unwrap();
        for k in 0..=faults.len() {
            let sats = sky32(&faults[..k]);
            let e = Epoch::ranges(1.7e9, &sats, None);
            // The second run: the thresholds cached (the steady state);
            // the first is counted too.
            for run in 0..2 {
                let (n, what) = epoch(fw, raim_qemu::epoch_command(&e));
                keep(
                    slot,
                    name,
                    format!("32 sats, {k} faults, run {run}: {what}"),
                    n,
                );
            }
        }
    }
    vec![seq_worst.unwrap(), rec_worst.unwrap()]
}

/// ARAIM at the build's 24 satellites (G12 + E12) and P_const 1e-8 (26
/// modes): clean, one fault, a pair of faults (the multi-event stage),
/// and the small faults where more candidates pass their own tests (no
/// early exit). A sky of 24 needing pair modes needs 327, beyond the
/// build's 48 (the typed `ModeCapacity` answer, which costs little), so
/// the pair modes are reached with fewer satellites: 8 at P_sat 1e-3, 47
/// modes (9 need 157). Linear and pseudorange epochs.
fn araim(fw: &mut QemuSession) -> Worst {
    let mut worst = None;
    let scenario = |n: usize, p_sat: f64, faults: &[(usize, f64)]| {
        let mut s = sky(n, usize::MAX, 0.0);
        s.p_const = s.p_const.map(|p| p.map(|_| 1e-8));
        for &(i, f) in faults {
            s.obs[i].residual_m += f;
        }
        for sat in s.ism.iter_mut() {
            sat.p_sat = p_sat;
        }
        s
    };
    let mut cases: Vec<(String, Scenario)> = Vec::new();
    for (n, p_sat) in [(24, 1e-5), (8, 1e-3)] {
        let tag = format!("{n} sats at P_sat {p_sat:e}");
        cases.push((format!("{tag}, clean"), scenario(n, p_sat, &[])));
        for f in [4.0, 6.0, 8.0, 10.0, 15.0, 20.0, 30.0, 100.0] {
            if n < 24 && ![6.0, 10.0, 100.0].contains(&f) {
                continue;
            }
            cases.push((format!("{tag}, {f} m on 0"), scenario(n, p_sat, &[(0, f)])));
            cases.push((
                format!("{tag}, {f} m on 0, -{f} m on {}", n - 1),
                scenario(n, p_sat, &[(0, f), (n - 1, -f)]),
            ));
        }
    }
    for (name, s) in &cases {
        fw.send(s.ism_command()).unwrap();
        fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
        let (n, what) = epoch(fw, epoch_command(0.0, &s.obs));
        keep(&mut worst, "ARAIM", format!("{name}: {what}"), n);
        let ranges = ranges_of(s);
        let (n, what) = epoch(fw, ranges_command(0.0, &ranges));
        keep(
            &mut worst,
            "ARAIM",
            format!("{name}, pseudoranges: {what}"),
            n,
        );
    }
    worst.unwrap()
}

/// The GA-PF at 100 particles and 12 satellites (the build's PF engine):
/// twelve epochs, a 60 m step on G04 from the seventh (alarm, isolation,
/// exclusion).
fn pf(fw: &mut QemuSession) -> Worst {
    let mut worst = None;
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
    fw.send(CommandRef::PfConfigure(&cfg)).unwrap();
    fw.recv(raim_qemu::ANSWER_TIMEOUT).unwrap();
    let sky: Vec<(f64, f64)> = (0..12)
        .map(|i| (i as f64 * 29.0, 15.0 + (i as f64 * 23.0) % 70.0))
        .collect();
    let mut rng = Rng::new(14);
    for k in 0..12 {
        let faults: Vec<(usize, f64)> = (k >= 6).then_some((3, 60.0)).into_iter().collect();
        let mut e = range_epoch(&sky, &[System::Gps], &mut rng, &faults);
        for o in e.iter_mut() {
            o.sigma_m = None;
        }
        let (n, what) = epoch(
            fw,
            CommandRef::PfRanges {
                time_s: 1_709_208_000.0 + k as f64,
                apriori_m: None,
                sats: &e,
            },
        );
        keep(
            &mut worst,
            "GA-PF 100",
            format!("12 sats, epoch {k}: {what}"),
            n,
        );
    }
    worst.unwrap()
}

/// The tick conversion: the same snapshot epoch counted on both boards.
fn cross_check(netduino_instructions: u64) {
    let sats = sky32(&[(2, 60.0)]);
    let e = Epoch::ranges(1.7e9, &sats, None);
    let elf = raim_qemu::firmware_elf().unwrap();
    let mut mps2 = QemuSession::start_with(
        &elf,
        &Options {
            icount: true,
            ..Options::default()
        },
    )
    .unwrap();
    mps2.configure(&Config::default()).unwrap();
    mps2.process(&e).unwrap();
    mps2.process(&e).unwrap();
    let ticks = mps2.status().unwrap().last_epoch_ticks;
    let mps2_instructions = f64::from(ticks) * MPS2_INSTRUCTIONS_PER_TICK;
    let rel = (netduino_instructions as f64 - mps2_instructions).abs() / mps2_instructions;
    println!(
        "cross-check: 32 sats, 1 fault: netduinoplus2 {netduino_instructions}, mps2-an386 {mps2_instructions} instructions"
    );
    assert!(
        rel < CROSS_CHECK_TOLERANCE,
        "netduinoplus2 {netduino_instructions} vs mps2-an386 {mps2_instructions}"
    );
}

/// Verifies: SAFE-WDOG
#[test]
fn qemu_netduinoplus2_worst_epochs_fit_half_the_shortest_watchdog_timeout() {
    let mut fw = netduino();
    // The cross-check's epoch, on this board.
    fw.configure(&Config::default()).unwrap();
    let e1 = sky32(&[(2, 60.0)]);
    let e = Epoch::ranges(1.7e9, &e1, None);
    fw.process(&e).unwrap();
    fw.process(&e).unwrap();
    let one_fault = instructions(fw.status().unwrap().last_epoch_ticks);

    let mut worst = snapshot_and_reconstruction(&mut fw);
    worst.push(araim(&mut fw));
    worst.push(pf(&mut fw));
    drop(fw);
    cross_check(one_fault);

    println!(
        "| method | worst case | guest instructions | {} MHz, {} ms IWDG: s | budget | {} MHz, {} ms IWDG: s | budget |",
        168, IWDG_TIMEOUT_PLL_MS, 16, IWDG_TIMEOUT_HSI_MS
    );
    let clocks = [
        (168e6, CPI_BOUND_PLL, IWDG_TIMEOUT_PLL_MS),
        (16e6, CPI_BOUND_HSI, IWDG_TIMEOUT_HSI_MS),
    ];
    let mut over = Vec::new();
    for (method, case, n) in &worst {
        let mut row = format!("| {method} | {case} | {n} |");
        for &(hz, cpi, timeout_ms) in &clocks {
            let (t_min_s, uart_s, budget) = budget_instructions(timeout_ms, hz, cpi);
            let epoch_s = *n as f64 * cpi / hz;
            row += &format!(" {epoch_s:.3} | {:.0} |", budget);
            if *n as f64 > budget {
                over.push(format!(
                    "{method} at {} MHz: {n} instructions, budget {budget:.0} (IWDG {t_min_s:.3} s min, UART {uart_s:.3} s)",
                    hz / 1e6
                ));
            }
        }
        println!("{row}");
    }
    for &(hz, cpi, timeout_ms) in &clocks {
        let (t_min_s, uart_s, budget) = budget_instructions(timeout_ms, hz, cpi);
        println!(
            "{} MHz: IWDG {timeout_ms} ms nominal, {t_min_s:.3} s at {LSI_MAX_HZ} Hz; UART {uart_s:.3} s; CPI {cpi}; budget {budget:.0} instructions",
            hz / 1e6
        );
    }
    assert!(over.is_empty(), "{over:#?}");
}
