//! The worst-case guest instructions of one epoch per method, found by a
//! search over inputs rather than only the hand-picked cases of
//! `tests/qemu_watchdog_margin.rs` (issue 37, "A time bound"): a seeded
//! hill climb on the STM32F4 build under QEMU's netduinoplus2 with
//! `-icount shift=0`, where the count of an epoch is a deterministic
//! function of its input. Each method starts from the test's costliest
//! case and from random skies; a candidate is mutated (satellites added or
//! removed, the geometry redrawn, a fault added, moved, resized or
//! removed, the priors changed) and kept when it costs more. The result is
//! turned into seconds at 168 MHz and 16 MHz with the test's CPI bounds
//! and compared with the watchdog budget (docs/SAFETY.md "Watchdog
//! margin"); the table goes to BENCHMARKS.md "Worst-case epoch by search".
//!
//! Build the netduinoplus2 firmware as scripts/test.sh does, then
//!
//!     cargo run --release -p host-tests --example worst_case_search -- [evaluations per method] [seed]
//!
//! (defaults: 120 evaluations, seed 1). The particle filter is not
//! searched: its cost per epoch is particles x satellites x window, fixed
//! by its configuration, and the test already runs it at the build's
//! capacity.

#[path = "../tests/qemu_common/araim.rs"]
mod araim_common;
#[path = "../tests/qemu_common/mod.rs"]
mod qemu_common;
#[path = "../tests/qemu_common/watchdog.rs"]
mod watchdog;

use araim_common::{epoch_command, ranges_command, ranges_of, sky, Scenario};
use qemu_common::{range_epoch, Rng};
use raim_core::{Config, Epoch, FdeMethod, LinearObservation, System};
use raim_qemu::QemuSession;
use watchdog::{
    budget_instructions, epoch_any, netduino, CPI_BOUND_HSI, CPI_BOUND_PLL, IWDG_TIMEOUT_HSI_MS,
    IWDG_TIMEOUT_PLL_MS,
};

/// The snapshot build's satellite capacity (`raim_proto::CAPACITY`) and
/// ARAIM's on the STM32F4 build (the test's 24).
const SNAPSHOT_MAX_SATS: usize = 32;
const ARAIM_MAX_SATS: usize = 24;
/// The fewest satellites an epoch of either method is run with.
const MIN_SATS: usize = 6;
/// Faults per candidate, at most, and their size range, m.
const MAX_FAULTS: usize = 6;
const FAULT_MIN_M: f64 = 3.0;
const FAULT_MAX_M: f64 = 300.0;

/// One input: the sky's size and geometry, the faults, and for ARAIM the
/// priors.
#[derive(Clone, Debug)]
struct Candidate {
    n: usize,
    geometry_seed: u64,
    two_constellations: bool,
    faults: Vec<(usize, f64)>,
    p_sat: f64,
    p_const: f64,
}

impl Candidate {
    /// Azimuth and elevation (deg) of each satellite: random, elevations
    /// from 5 to 89 degrees.
    fn sky_deg(&self) -> Vec<(f64, f64)> {
        let mut rng = Rng::new(self.geometry_seed);
        (0..self.n)
            .map(|_| (360.0 * rng.uniform(), 5.0 + 84.0 * rng.uniform()))
            .collect()
    }

    fn faults_in_range(&self) -> Vec<(usize, f64)> {
        self.faults
            .iter()
            .filter(|(i, _)| *i < self.n)
            .copied()
            .collect()
    }

    fn mutate(&self, rng: &mut Rng, max_sats: usize) -> Candidate {
        let mut c = self.clone();
        let pick = |rng: &mut Rng, k: usize| ((rng.uniform() * k as f64) as usize).min(k - 1);
        match pick(rng, 6) {
            0 => {
                let step = pick(rng, 4) as i64 + 1;
                let n = if rng.uniform() < 0.5 {
                    c.n as i64 - step
                } else {
                    c.n as i64 + step
                };
                c.n = n.clamp(MIN_SATS as i64, max_sats as i64) as usize;
            }
            1 => c.geometry_seed = (rng.uniform() * 1e12) as u64,
            2 if c.faults.len() < MAX_FAULTS => {
                let size = FAULT_MIN_M + (FAULT_MAX_M - FAULT_MIN_M) * rng.uniform();
                let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                c.faults.push((pick(rng, c.n), sign * size));
            }
            3 if !c.faults.is_empty() => {
                let k = pick(rng, c.faults.len());
                c.faults[k].1 *= 0.5 + rng.uniform();
                c.faults[k].0 = pick(rng, c.n);
            }
            4 if !c.faults.is_empty() => {
                let k = pick(rng, c.faults.len());
                c.faults.remove(k);
            }
            _ => {
                c.two_constellations = !c.two_constellations;
                c.p_sat = [1e-5, 1e-4, 1e-3][pick(rng, 3)];
                c.p_const = [1e-8, 1e-4][pick(rng, 2)];
            }
        }
        c
    }
}

/// One epoch's instructions and answer; a refused epoch (too few
/// satellites for the candidate's constellations, a mode capacity) counts
/// as what it cost.
fn cost_of(fw: &mut QemuSession, command: raim_proto::message::CommandRef<'_>) -> (u64, String) {
    let (n, what, _) = epoch_any(fw, command);
    (n, what)
}

/// The snapshot monitor's epoch of a candidate (pseudoranges).
fn snapshot_cost(fw: &mut QemuSession, cfg: &Config, c: &Candidate) -> (u64, String) {
    let systems: &[System] = if c.two_constellations {
        &[System::Gps, System::Galileo]
    } else {
        &[System::Gps]
    };
    let sats = range_epoch(
        &c.sky_deg(),
        systems,
        &mut Rng::new(c.geometry_seed ^ 0x5EED),
        &c.faults_in_range(),
    );
    let e = Epoch::ranges(1.7e9, &sats, None);
    // A fresh configuration before each candidate: the first run pays for
    // any threshold the cache lacks, the second is the steady state.
    fw.configure(cfg).expect("configure");
    let first = cost_of(fw, raim_qemu::epoch_command(&e));
    let second = cost_of(fw, raim_qemu::epoch_command(&e));
    if first.0 >= second.0 {
        first
    } else {
        second
    }
}

/// ARAIM's epoch of a candidate: the ISM with its priors, then the linear
/// and the pseudorange epoch; the costlier counts.
fn araim_cost(fw: &mut QemuSession, c: &Candidate) -> (u64, String) {
    let mut s: Scenario = sky(c.n, usize::MAX, 0.0);
    s.p_const = s.p_const.map(|p| p.map(|_| c.p_const));
    for sat in s.ism.iter_mut() {
        sat.p_sat = c.p_sat;
    }
    for (o, &(az, el)) in s.obs.iter_mut().zip(c.sky_deg().iter()) {
        *o = LinearObservation::from_az_el(o.id, az.to_radians(), el.to_radians(), o.residual_m);
    }
    for (i, f) in c.faults_in_range() {
        s.obs[i].residual_m += f;
    }
    fw.send(s.ism_command()).expect("ISM");
    fw.recv(raim_qemu::ANSWER_TIMEOUT).expect("ISM answer");
    let linear = cost_of(fw, epoch_command(0.0, &s.obs));
    let ranges = ranges_of(&s);
    let pseudo = cost_of(fw, ranges_command(0.0, &ranges));
    if linear.0 >= pseudo.0 {
        linear
    } else {
        (pseudo.0, format!("{}, pseudoranges", pseudo.1))
    }
}

/// The hill climb: `evaluations` candidates from `start`, restarting from
/// a random sky every tenth; returns the costliest found.
fn climb(
    name: &str,
    start: Candidate,
    evaluations: usize,
    rng: &mut Rng,
    max_sats: usize,
    cost: &mut dyn FnMut(&Candidate) -> (u64, String),
) -> (Candidate, u64, String) {
    let (n0, w0) = cost(&start);
    let (mut best, mut best_n, mut best_what) = (start.clone(), n0, w0);
    let mut current = (start, n0);
    for k in 1..evaluations {
        let c = if k % 10 == 0 {
            Candidate {
                n: MIN_SATS + (rng.uniform() * (max_sats - MIN_SATS + 1) as f64) as usize,
                geometry_seed: (rng.uniform() * 1e12) as u64,
                ..best.clone()
            }
        } else {
            current.0.mutate(rng, max_sats)
        };
        let (n, what) = cost(&c);
        if n >= current.1 || k % 10 == 0 {
            current = (c.clone(), n);
        }
        if n > best_n {
            println!("{name:>14} | {k:>4} | {n:>11} | {what} | {c:?}");
            (best, best_n, best_what) = (c, n, what);
        }
    }
    (best, best_n, best_what)
}

fn main() {
    let mut args = std::env::args().skip(1);
    let evaluations: usize = args.next().map_or(120, |a| a.parse().expect("evaluations"));
    let seed: u64 = args.next().map_or(1, |a| a.parse().expect("seed"));
    let mut rng = Rng::new(seed);
    let mut fw = netduino();
    println!("{:>14} | eval | instructions | answer | input", "method");

    let start = Candidate {
        n: SNAPSHOT_MAX_SATS,
        geometry_seed: 32,
        two_constellations: true,
        faults: vec![(2, 60.0), (9, -70.0), (15, 80.0), (21, -90.0), (27, 100.0)],
        p_sat: 1e-5,
        p_const: 1e-8,
    };
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
    let mut results = Vec::new();
    for (name, cfg) in [
        ("snapshot", &sequential),
        ("reconstruction", &reconstruction),
    ] {
        let r = climb(
            name,
            start.clone(),
            evaluations,
            &mut rng,
            SNAPSHOT_MAX_SATS,
            &mut |c| snapshot_cost(&mut fw, cfg, c),
        );
        results.push((name, r));
    }
    let araim_start = Candidate {
        n: 8,
        faults: vec![(0, 6.0), (7, -6.0)],
        p_sat: 1e-3,
        ..start
    };
    let r = climb(
        "ARAIM",
        araim_start,
        evaluations,
        &mut rng,
        ARAIM_MAX_SATS,
        &mut |c| araim_cost(&mut fw, c),
    );
    results.push(("ARAIM", r));

    println!();
    println!(
        "| method | worst found (guest instructions) | at 168 MHz, CPI {CPI_BOUND_PLL}: s | budget ({IWDG_TIMEOUT_PLL_MS} ms IWDG) | at 16 MHz, CPI {CPI_BOUND_HSI}: s | budget ({IWDG_TIMEOUT_HSI_MS} ms IWDG) | answer | input |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: | --- | --- |");
    for (name, (c, n, what)) in &results {
        let (_, _, b_pll) = budget_instructions(IWDG_TIMEOUT_PLL_MS, 168e6, CPI_BOUND_PLL);
        let (_, _, b_hsi) = budget_instructions(IWDG_TIMEOUT_HSI_MS, 16e6, CPI_BOUND_HSI);
        println!(
            "| {name} | {n} | {:.3} | {b_pll:.0} | {:.3} | {b_hsi:.0} | {what} | n {}, geometry {}, {} constellation(s), faults {:?}, P_sat {:e}, P_const {:e} |",
            *n as f64 * CPI_BOUND_PLL / 168e6,
            *n as f64 * CPI_BOUND_HSI / 16e6,
            c.n,
            c.geometry_seed,
            if c.two_constellations { 2 } else { 1 },
            c.faults_in_range(),
            c.p_sat,
            c.p_const,
        );
    }
}
