//! The multiple-fault Monte Carlo (SPEC §8.4): seeded random
//! geometries (n = 8..20, 1-3 constellations), 1, 2 or 3 simultaneous
//! faults of random size and sign, each draw run through today's FDE
//! (`FdeMethod::Sequential`: single exclusion + closed-form pair search)
//! and through the reconstruction (`FdeMethod::Reconstruction`), on the
//! same observations. Shared by `examples/multifault_mc.rs` (the long run)
//! and `tests/multifault_mc.rs` (the short CI run).
#![allow(dead_code)]

use raim_core::config::{FdeMethod, Phase};
use raim_core::snapshot::fde::AlarmCause;
use raim_core::{Config, Decision, Epoch, LinearObservation, Raim, SatId, System};
use std::time::Instant;

/// xorshift64* (deterministic, seedable).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((v >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n - 1)
    }
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

/// Largest fault size drawn, m (unit sigma: also sigma units).
pub const MAX_FAULT_M: f64 = 60.0;
/// Width of a fault-size bin for the tables, m.
pub const BIN_M: f64 = 10.0;
pub const BINS: usize = (MAX_FAULT_M / BIN_M) as usize;

/// What one method did with one draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// The all-in-view test passed.
    Missed,
    /// Exactly the faulty set was excluded.
    Correct,
    /// A satellite that was not faulty was excluded (the subset passed).
    WrongExclusion,
    /// Only part of the faulty set was excluded (the subset passed).
    Partial,
    /// An alarm naming an ambiguity.
    Ambiguous,
    /// Any other alarm (no consistent subset, budget, geometry).
    OtherAlarm,
    /// Consistent but protection levels above the alert limit (no exclusion).
    Unavailable,
}

pub const OUTCOMES: [Outcome; 7] = [
    Outcome::Missed,
    Outcome::Correct,
    Outcome::WrongExclusion,
    Outcome::Partial,
    Outcome::Ambiguous,
    Outcome::OtherAlarm,
    Outcome::Unavailable,
];

/// One draw: the observations and the faulty rows.
pub struct Draw {
    pub sats: Vec<LinearObservation>,
    pub faulty: Vec<usize>,
    pub size_m: f64,
    pub t: usize,
}

/// A random sky: n in 8..=20, 1-3 constellations (each with >= 2
/// satellites when present), az uniform, el 5-90 deg, unit sigma; t faults
/// (1, 2, 3 in turn) on distinct random satellites, each of size uniform
/// in [0, MAX_FAULT_M] with a random sign (the bin uses the smallest).
pub fn draw(rng: &mut Rng, index: u64) -> Draw {
    let t = 1 + (index % 3) as usize;
    let n = 8 + rng.below(13);
    let systems_n = 1 + rng.below(3);
    let systems = [System::Gps, System::Galileo, System::Beidou];
    let mut sats = Vec::with_capacity(n);
    let mut sizes = Vec::new();
    let mut faulty = Vec::new();
    while faulty.len() < t {
        let k = rng.below(n);
        if !faulty.contains(&k) {
            faulty.push(k);
        }
    }
    for i in 0..n {
        // The first 2 * systems_n satellites make every system present
        // with at least two; the rest are random.
        let sys = if i < 2 * systems_n {
            systems[i % systems_n]
        } else {
            systems[rng.below(systems_n)]
        };
        let az = rng.uniform() * 360.0;
        let el = 5.0 + 85.0 * rng.uniform();
        let mut z = rng.normal();
        if faulty.contains(&i) {
            let size = MAX_FAULT_M * rng.uniform();
            sizes.push(size);
            z += if rng.uniform() < 0.5 { -size } else { size };
        }
        let mut o = LinearObservation::from_az_el(
            SatId::new(sys, i as u8 + 1),
            az.to_radians(),
            el.to_radians(),
            z,
        );
        o.sigma_m = Some(1.0);
        sats.push(o);
    }
    let size_m = sizes.iter().copied().fold(f64::INFINITY, f64::min);
    faulty.sort_unstable();
    Draw {
        sats,
        faulty,
        size_m,
        t,
    }
}

/// The two configurations compared: today's FDE and the reconstruction,
/// both allowed 3 exclusions, en-route alert limits (so availability
/// rarely masks the FDE outcome).
pub fn configs(group_budget: u16) -> [(&'static str, Config); 2] {
    let base = Config {
        max_exclusions: 3,
        ..Config::preset(Phase::EnRoute)
    };
    [
        ("sequential", base),
        (
            "reconstruction",
            Config {
                fde_method: FdeMethod::Reconstruction {
                    t_max: 3,
                    group_budget,
                },
                ..base
            },
        ),
    ]
}

/// Classifies one result against the truth.
pub fn classify(r: &raim_core::EpochResult<32>, faulty: &[usize]) -> Outcome {
    if !r.initial_test.alarm() {
        return Outcome::Missed;
    }
    match r.decision {
        Decision::Excluded => {
            let mut got: Vec<usize> = r.exclusions.iter().map(|e| e.index).collect();
            got.sort_unstable();
            if got.iter().any(|i| !faulty.contains(i)) {
                Outcome::WrongExclusion
            } else if got.len() == faulty.len() {
                Outcome::Correct
            } else {
                Outcome::Partial
            }
        }
        Decision::Alarm => match r.alarm_cause {
            Some(AlarmCause::Ambiguous { .. }) => Outcome::Ambiguous,
            _ => Outcome::OtherAlarm,
        },
        Decision::Unavailable => {
            if r.exclusions.iter().any(|e| !faulty.contains(&e.index)) {
                Outcome::WrongExclusion
            } else {
                Outcome::Unavailable
            }
        }
        // The initial test failed but the final one passes without
        // exclusions: cannot happen; count it as missed.
        Decision::Ok => Outcome::Missed,
    }
}

/// Counts per method, fault count t (1..3), fault-size bin and outcome,
/// and the reconstruction's cost per number of groups processed.
pub struct Tally {
    pub counts: [[[[u64; 7]; BINS]; 3]; 2],
    /// (groups processed, total ns, epochs) per method 1's epochs that ran
    /// the search.
    pub cost: Vec<(u32, u128, u64)>,
    pub draws: u64,
    pub skipped: u64,
}

impl Tally {
    pub fn total(&self, method: usize, t: usize, outcome: Outcome) -> u64 {
        let k = OUTCOMES.iter().position(|o| *o == outcome).unwrap_or(0);
        self.counts[method][t].iter().map(|bin| bin[k]).sum()
    }
    pub fn draws_of(&self, method: usize, t: usize) -> u64 {
        self.counts[method][t].iter().flat_map(|b| b.iter()).sum()
    }
    pub fn bin(&self, method: usize, t: usize, bin: usize, outcome: Outcome) -> (u64, u64) {
        let k = OUTCOMES.iter().position(|o| *o == outcome).unwrap_or(0);
        let row = &self.counts[method][t][bin];
        (row[k], row.iter().sum())
    }
}

/// Runs `draws` draws from `seed`.
pub fn run(draws: u64, seed: u64, group_budget: u16) -> Tally {
    let mut rng = Rng::new(seed);
    let configs = configs(group_budget);
    let mut raim = Raim::<32>::new();
    let mut tally = Tally {
        counts: [[[[0; 7]; BINS]; 3]; 2],
        cost: Vec::new(),
        draws: 0,
        skipped: 0,
    };
    for index in 0..draws {
        let d = draw(&mut rng, index);
        let epoch = Epoch::linear(index as f64, &d.sats);
        let bin = ((d.size_m / BIN_M) as usize).min(BINS - 1);
        let mut results = Vec::new();
        for (_, cfg) in &configs {
            let start = Instant::now();
            let r = raim.process(cfg, &epoch);
            results.push((r, start.elapsed().as_nanos()));
        }
        // Geometries without the redundancy for t faults (n - m - 1 < t)
        // or degenerate ones are skipped for both methods alike.
        let redundancy = match &results[0].0 {
            Ok(r) => r.initial_test.dof as usize,
            Err(_) => 0,
        };
        if redundancy < d.t + 1 || results.iter().any(|(r, _)| r.is_err()) {
            tally.skipped += 1;
            continue;
        }
        tally.draws += 1;
        for (method, (r, ns)) in results.iter().enumerate() {
            let Ok(r) = r else { continue };
            let o = classify(r, &d.faulty);
            let k = OUTCOMES.iter().position(|x| *x == o).unwrap_or(0);
            tally.counts[method][d.t - 1][bin][k] += 1;
            if method == 1 {
                if let Some(rep) = &r.multifault {
                    let g = rep.groups_processed;
                    match tally.cost.iter_mut().find(|c| c.0 == g) {
                        Some(c) => {
                            c.1 += ns;
                            c.2 += 1;
                        }
                        None => tally.cost.push((g, *ns, 1)),
                    }
                }
            }
        }
    }
    tally.cost.sort_unstable();
    tally
}
