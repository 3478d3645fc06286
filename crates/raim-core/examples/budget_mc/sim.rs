//! The combined false-alarm Monte Carlo of docs/BUDGET.md: fault-free
//! epochs through every monitor on the integrity path at once, with the
//! thresholds of one budget (`raim_core::budget`), counting per-epoch
//! alarm events per monitor and their union.
//!
//! Sky: 12 satellites, GPS + Galileo alternating, fixed azimuths and
//! elevations 10-84 deg; every epoch an independent N(0, 1 m^2) error per
//! satellite (sigma 1 m, the model the thresholds assume); 1 s epochs. The
//! snapshot engine runs the snapshot test, the MCUSUM (k = 1, transport)
//! and the multiple-fault FDE (t_max 2); ARAIM runs on the same errors
//! (C_acc = C_int = 1 m^2, b_nom 0, P_sat 1e-5, P_const 1e-4). Several
//! threads each run their own stream (seed, thread) with their own state.

use raim_core::araim::{Araim, AraimConfig, AraimSat, Ism};
use raim_core::budget::{Budget, FalseAlarmShares};
use raim_core::measurement::{LinearObservation, SatId, System};
use raim_core::pf::rng;
use raim_core::result::Decision;
use raim_core::{Config, Epoch, FdeMethod, Phase, Raim};

/// Satellites in the sky.
pub const SATS: usize = 12;
const ARAIM_MODES: usize = 256;
const P_SAT: f64 = 1e-5;
const P_CONST: f64 = 1e-4;
/// Epoch interval, s.
const EPOCH_S: f64 = 1.0;

/// Per-epoch event counts.
#[derive(Debug, Clone, Copy, Default)]
pub struct Tally {
    pub epochs: u64,
    /// The all-in-view chi-square test failed.
    pub snapshot: u64,
    /// The MCUSUM statistic reached h.
    pub mcusum: u64,
    /// The snapshot engine's decision was Alarm (no exclusion restored
    /// consistency, or the multiple-fault search was ambiguous).
    pub engine_alarm: u64,
    /// The snapshot engine excluded a satellite.
    pub engine_excluded: u64,
    /// The multiple-fault search ran (after a detection).
    pub multifault_ran: u64,
    /// ARAIM: some monitored mode failed its separation test.
    pub araim: u64,
    /// Any of the above: a continuity event of the combined monitor.
    pub combined: u64,
    /// Epochs a monitor refused (typed error); not counted as alarms.
    pub refused: u64,
}

impl Tally {
    fn add(&mut self, o: &Tally) {
        self.epochs += o.epochs;
        self.snapshot += o.snapshot;
        self.mcusum += o.mcusum;
        self.engine_alarm += o.engine_alarm;
        self.engine_excluded += o.engine_excluded;
        self.multifault_ran += o.multifault_ran;
        self.araim += o.araim;
        self.combined += o.combined;
        self.refused += o.refused;
    }
}

/// The budget the Monte Carlo runs: total P_FA per epoch split
/// snapshot / MCUSUM / ARAIM as given, PCA and PF 0, the default integrity
/// split.
pub fn budget(p_fa_total: f64, snapshot: f64, mcusum: f64, araim: f64) -> Budget {
    Budget {
        p_fa_total,
        shares: FalseAlarmShares {
            snapshot,
            mcusum,
            araim,
            pca: 0.0,
            pf: 0.0,
        },
        ..Budget::default()
    }
}

fn sky() -> [(System, f64, f64); SATS] {
    core::array::from_fn(|i| {
        let sys = if i % 2 == 0 {
            System::Gps
        } else {
            System::Galileo
        };
        let az = (i as f64) * 360.0 / SATS as f64 + 7.0 * (i % 3) as f64;
        let el = 10.0 + ((i * 37) % 75) as f64;
        (sys, az.to_radians(), el.to_radians())
    })
}

/// One stream of `epochs` epochs.
fn stream(b: &Budget, epochs: u64, seed: u64) -> Result<Tally, String> {
    let mut cfg = b
        .apply(Config::preset(Phase::Npa))
        .map_err(|e| e.to_string())?;
    cfg.fde_method = FdeMethod::Reconstruction {
        t_max: 2,
        group_budget: 1000,
    };
    cfg.max_exclusions = 2;
    cfg.validate().map_err(|e| e.to_string())?;
    let acfg = if b.shares.araim > 0.0 {
        Some(
            b.apply_araim(AraimConfig::default())
                .map_err(|e| e.to_string())?,
        )
    } else {
        None
    };
    let sky = sky();
    let ism = Ism::with(&[System::Gps, System::Galileo], P_CONST);
    let mut raim = Box::new(Raim::<32>::new());
    let mut araim: Box<Araim<f64, 32, ARAIM_MODES>> = Box::new(Araim::new());
    let mut r = rng::seeded(seed);
    let mut t = Tally::default();
    let mut obs = [LinearObservation::from_az_el(SatId::new(System::Gps, 1), 0.0, 1.0, 0.0); SATS];
    let mut asats = [AraimSat::<f64> {
        id: SatId::new(System::Gps, 1),
        g_enu: [0.0; 3],
        c_int_m2: 1.0,
        c_acc_m2: 1.0,
        b_nom_m: 0.0,
        p_sat: P_SAT,
        residual_m: 0.0,
    }; SATS];
    for k in 0..epochs {
        for (i, ((o, a), &(sys, az, el))) in
            obs.iter_mut().zip(asats.iter_mut()).zip(&sky).enumerate()
        {
            let e = rng::normal(&mut r);
            let id = SatId::new(sys, i as u8 + 1);
            *o = LinearObservation::from_az_el(id, az, el, e);
            o.sigma_m = Some(1.0);
            a.id = id;
            a.g_enu = AraimSat::g_from_az_el(az, el);
            a.residual_m = e;
        }
        t.epochs += 1;
        let mut any = false;
        match raim.process(&cfg, &Epoch::linear(k as f64 * EPOCH_S, &obs)) {
            Ok(res) => {
                let snap = res.initial_test.alarm();
                let mc = res.mcusum.is_some_and(|m| m.alarm);
                t.snapshot += u64::from(snap);
                t.mcusum += u64::from(mc);
                t.multifault_ran += u64::from(res.multifault.is_some());
                match res.decision {
                    Decision::Alarm => t.engine_alarm += 1,
                    Decision::Excluded => t.engine_excluded += 1,
                    _ => {}
                }
                any |= snap || mc || matches!(res.decision, Decision::Alarm | Decision::Excluded);
            }
            Err(e) => {
                if t.refused == 0 {
                    eprintln!("refused: {e}");
                }
                t.refused += 1
            }
        }
        if let Some(acfg) = &acfg {
            match araim.process(acfg, &ism, &asats) {
                Ok(out) => {
                    let a = !out.detection_passed;
                    t.araim += u64::from(a);
                    any |= a;
                }
                Err(e) => {
                    if t.refused == 0 {
                        eprintln!("refused: {e}");
                    }
                    t.refused += 1
                }
            }
        }
        t.combined += u64::from(any);
    }
    Ok(t)
}

/// `epochs` epochs over `threads` streams (seeds seed * 1000 + thread).
pub fn run(b: &Budget, epochs: u64, seed: u64, threads: u64) -> Result<Tally, String> {
    let threads = threads.max(1);
    let per = epochs / threads;
    let handles: Vec<_> = (0..threads)
        .map(|j| {
            let b = *b;
            let n = if j + 1 == threads {
                epochs - per * (threads - 1)
            } else {
                per
            };
            std::thread::spawn(move || stream(&b, n, seed * 1000 + j))
        })
        .collect();
    let mut total = Tally::default();
    for h in handles {
        let t = h
            .join()
            .map_err(|_| "a Monte Carlo thread panicked".to_string())??;
        total.add(&t);
    }
    Ok(total)
}

/// Clopper-Pearson 95 % interval of k / n: the p at which
/// P(X >= k | p) = 0.025 and P(X <= k | p) = 0.025, X ~ Binomial(n, p),
/// by bisection on log p with the binomial CDF (statrs' inverse Beta CDF
/// does not converge for n ~ 1e7).
pub fn interval(k: u64, n: u64) -> (f64, f64) {
    use statrs::distribution::{Binomial, DiscreteCDF};
    const ALPHA_HALF: f64 = 0.025;
    const STEPS: usize = 200;
    // Solve g(p) = target for g increasing in p, over log p in [1e-300, 1].
    let solve = |g: &dyn Fn(f64) -> f64, target: f64| {
        let (mut lo, mut hi) = (-690.0_f64, 0.0_f64);
        for _ in 0..STEPS {
            let mid = 0.5 * (lo + hi);
            if g(mid.exp()) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).exp()
    };
    let cdf = |x: u64, p: f64| Binomial::new(p.min(1.0), n).map_or(f64::NAN, |b| b.cdf(x));
    // P(X >= k | p) = 1 - cdf(k - 1) increases with p.
    let lo = if k == 0 {
        0.0
    } else {
        solve(&|p| 1.0 - cdf(k - 1, p), ALPHA_HALF)
    };
    // P(X > k | p) = 1 - cdf(k) increases with p; the upper end has
    // cdf(k) = 0.025.
    let hi = if k == n {
        1.0
    } else {
        solve(&|p| 1.0 - cdf(k, p), 1.0 - ALPHA_HALF)
    };
    (lo, hi)
}
