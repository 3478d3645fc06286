//! The reconstruction FDE (docs/MULTIFAULT.md) in the firmware under QEMU:
//! guest instructions per epoch for n = 12, 20, 32 linearised satellites
//! (GPS + Galileo) with t = 1, 2, 3 simultaneous 60 m faults and t_max = t
//! (`-icount shift=0`: one SysTick tick is 40 instructions), and the stack
//! high water after the deepest of them, on a fresh firmware.
//!
//! `cargo run --release -p host-tests --example qemu_multifault`

use raim_core::{Config, Epoch, FdeMethod, LinearObservation, SatId, System};
use raim_qemu::{Options, QemuSession};

const INSTRUCTIONS_PER_TICK: u64 = 40;

/// As benches/multifault.rs: golden-angle spiral, 60 m on rows 2, 5, 9.
fn sky(n: usize, t: usize) -> Vec<LinearObservation> {
    let faulty = [2usize, 5, 9];
    (0..n)
        .map(|i| {
            let az = (i as f64 * 137.507_764_f64).rem_euclid(360.0);
            let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
            let noise = ((i as f64 * 12.9898).sin() * 43758.5453).fract() - 0.5;
            let fault = if faulty[..t].contains(&i) { 60.0 } else { 0.0 };
            let sys = if i % 2 == 0 {
                System::Gps
            } else {
                System::Galileo
            };
            let mut o = LinearObservation::from_az_el(
                SatId::new(sys, i as u8 + 1),
                az.to_radians(),
                el.to_radians(),
                noise + fault,
            );
            o.sigma_m = Some(1.0);
            o
        })
        .collect()
}

fn config(t_max: u8) -> Config {
    Config {
        fde_method: FdeMethod::Reconstruction {
            t_max,
            group_budget: 1000,
        },
        max_exclusions: 3,
        ..Config::default()
    }
}

fn main() -> anyhow::Result<()> {
    let elf = raim_qemu::firmware_elf()?;
    let mut fw = QemuSession::start_with(
        &elf,
        &Options {
            icount: true,
            ..Options::default()
        },
    )?;
    println!("| n | t | decision, exclusions | reconstruction (instructions) | today's FDE (instructions) |");
    println!("| --- | --- | --- | --- | --- |");
    for n in [12usize, 20, 32] {
        for t in 1..=3u8 {
            let sats = sky(n, usize::from(t));
            let epoch = Epoch::linear(0.0, &sats);
            let mut row = Vec::new();
            let mut outcome = String::new();
            for cfg in [
                config(t),
                Config {
                    max_exclusions: 3,
                    ..Config::default()
                },
            ] {
                fw.configure(&cfg)?;
                // The second epoch: thresholds cached (steady state).
                let mut ticks = 0;
                for _ in 0..2 {
                    let p = fw.process(&epoch)?;
                    if outcome.is_empty() {
                        outcome =
                            format!("{:?}", p.outcome.map(|r| (r.decision, r.exclusions.len())));
                    }
                    ticks = fw.status()?.last_epoch_ticks as u64;
                }
                row.push(ticks * INSTRUCTIONS_PER_TICK);
            }
            println!("| {n} | {t} | {outcome} | {} | {} |", row[0], row[1]);
        }
    }
    drop(fw);
    let mut fw = QemuSession::start(&elf)?;
    let idle = fw.status()?.stack_high_water_bytes;
    fw.configure(&config(3))?;
    let p = fw.process(&Epoch::linear(0.0, &sky(32, 3)))?;
    let st = fw.status()?;
    println!(
        "stack high water: {idle} B after boot + a status request; {} B after one 32-satellite epoch with 3 faults, t_max 3 ({:?})",
        st.stack_high_water_bytes,
        p.outcome.map(|r| (r.decision, r.exclusions.len()))
    );
    Ok(())
}
