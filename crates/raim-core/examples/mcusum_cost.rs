//! Runs 2000 clean epochs of a slowly turning n-satellite sky through
//! `Raim::process` with the MCUSUM off or on, for instruction counting:
//!
//!     cargo build --release -p raim-core --example mcusum_cost
//!     valgrind --tool=callgrind --callgrind-out-file=/dev/null \
//!         target/release/examples/mcusum_cost 12 on
//!
//! (the difference of the "Collected" counts of `on` and `off`, divided by
//! 2000, is the per-epoch cost the MCUSUM adds; BENCHMARKS.md).
use raim_core::{Config, Epoch, LinearObservation, Raim, SatId, System};

const EPOCHS: usize = 2000;

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(12);
    let on = args.next().is_some_and(|a| a == "on");
    let cfg = if on {
        Config::default().split_false_alarm_budget(0.5)
    } else {
        Config::default()
    };
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut raim = Raim::<32>::new();
    let mut sats = Vec::with_capacity(n);
    let mut alarms = 0;
    for t in 0..EPOCHS {
        sats.clear();
        for i in 0..n {
            let az = (i as f64 * 137.507_764 + 0.01 * t as f64).rem_euclid(360.0);
            let el = 10.0 + 75.0 * ((i * 7) % n) as f64 / n as f64;
            let z = (-2.0 * uniform().ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
            let mut o = LinearObservation::from_az_el(
                SatId::new(
                    if i % 2 == 0 {
                        System::Gps
                    } else {
                        System::Galileo
                    },
                    i as u8 + 1,
                ),
                az.to_radians(),
                el.to_radians(),
                z,
            );
            o.sigma_m = Some(1.0);
            sats.push(o);
        }
        let r = raim
            .process(&cfg, &Epoch::linear(t as f64, &sats))
            .expect("solvable");
        alarms += usize::from(r.mcusum.is_some_and(|m| m.alarm));
    }
    println!("n={n} mcusum={on} epochs={EPOCHS} mcusum_alarms={alarms}");
}
