//! Average run lengths of Crosier's MCUSUM (SPEC §7.2) and the device
//! threshold table.
//!
//! In control the parity vector is N(0, I_d), isotropic, so R_t = ||S_t|| is
//! a Markov chain on [0, inf): C_t = ||R_(t-1) e + y_t|| is non-central chi
//! with d degrees of freedom and non-centrality R_(t-1), and
//! R_t = max(0, C_t - k) (||S_t|| = C_t (1 - k / C_t)). The zero-state ARL
//! L(0) solves the Fredholm equation of the second kind with an atom at 0,
//!
//! ```text
//! L(r) = 1 + P(C <= k | r) L(0) + integral_0^h f_C(x + k | r) L(x) dx,
//! ```
//!
//! discretised by Nystrom's method on composite Gauss-Legendre nodes (panels
//! of width <= 1, where the kernel is a smooth bump of width ~1). The
//! inverse h(ARL0) is found by bracketing and bisection (Illinois-accelerated)
//! on ln ARL0, which is monotone in h. Out of control (mean offset delta) the
//! chain is no longer one-dimensional; ARL1 comes from seeded simulation of
//! the core's own recursion ([`raim_core::sequential::mcusum::crosier_step`]).
//!
//! The "aligned" model is the integral equation with non-centrality
//! R + delta: the CUSUM vector assumed always to point along the shift. It
//! reproduces seed 001's published ARL1 row (22, 8.6, 5.2) and is what that
//! row computes; the simulation gives the true values (SPEC §7.2).

// `!(a < b)` is deliberate: it is true for NaN, so a NaN fails safe.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod scenario;

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use nalgebra::{DMatrix, DVector};
use raim_core::sequential::mcusum;
use raim_core::stats::dist;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Gauss-Legendre nodes per panel.
const NODES_PER_PANEL: usize = 8;
/// Largest panel width (the kernel's scale is 1 in sigma units).
const PANEL_WIDTH: f64 = 1.0;
/// Bisection stops when the bracket on h is this narrow (sigma units).
const H_TOL: f64 = 1e-8;
/// Longest simulated run (a guard against h so large the run never ends).
const MAX_RUN: u64 = 1_000_000_000;

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n from the
/// Chebyshev-like start; |x| and weights symmetric).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for j in 2..=n {
                let p2 = ((2 * j - 1) as f64 * z * p1 - (j - 1) as f64 * p0) / j as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 0 {
                1.0
            } else if n == 1 {
                z
            } else {
                p1
            };
            let pn1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pn1) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    (x, w)
}

/// e^-z I_nu(z), the exponentially scaled modified Bessel function, for
/// nu >= -1/2 and z > 0: power series below z = 30 (all terms positive),
/// Hankel's asymptotic series above (it terminates for half-integer nu and
/// is summed to its smallest term otherwise, error ~ e^-2z).
pub fn bessel_i_scaled(nu: f64, z: f64) -> f64 {
    if z < BESSEL_SWITCH {
        bessel_i_scaled_series(nu, z)
    } else {
        bessel_i_scaled_hankel(nu, z)
    }
}

/// Where [`bessel_i_scaled`] switches from the power series to Hankel's.
const BESSEL_SWITCH: f64 = 30.0;

/// e^-z sum_m (z/2)^(2m+nu) / (m! Gamma(m+nu+1)).
fn bessel_i_scaled_series(nu: f64, z: f64) -> f64 {
    let ln_first = nu * (0.5 * z).ln() - libm::lgamma(nu + 1.0) - z;
    let mut term = 1.0;
    let mut sum = 1.0;
    let q = 0.25 * z * z;
    for m in 1..2000 {
        term *= q / (m as f64 * (m as f64 + nu));
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    sum * ln_first.exp()
}

/// (2 pi z)^-1/2 sum_m (-1)^m prod_j (4 nu^2 - (2j-1)^2) / (m! (8z)^m),
/// summed until the terms, once past their growth (2m - 1 > 2 nu), stop
/// shrinking or fall below 1e-17 of the sum.
fn bessel_i_scaled_hankel(nu: f64, z: f64) -> f64 {
    let mu = 4.0 * nu * nu;
    let mut term = 1.0f64;
    let mut sum = 1.0f64;
    for m in 1..400 {
        let odd = (2 * m - 1) as f64;
        let next = -term * (mu - odd * odd) / (m as f64 * 8.0 * z);
        if next == 0.0 || (odd > 2.0 * nu.abs() && next.abs() >= term.abs()) {
            break;
        }
        term = next;
        sum += term;
        if term.abs() < 1e-17 * sum.abs() {
            break;
        }
    }
    sum / (2.0 * std::f64::consts::PI * z).sqrt()
}

/// Density of C = ||mu + y||, y ~ N(0, I_d), ||mu|| = r (non-central chi):
/// f(c) = c (c/r)^nu e^(-(c-r)^2/2) e^(-rc) I_nu(rc), nu = d/2 - 1; the
/// central chi density when r = 0.
pub fn ncchi_pdf(c: f64, r: f64, d: usize) -> f64 {
    if c <= 0.0 {
        return 0.0;
    }
    let half = 0.5 * d as f64;
    if r <= 0.0 {
        let ln = (d as f64 - 1.0) * c.ln()
            - 0.5 * c * c
            - (half - 1.0) * std::f64::consts::LN_2
            - libm::lgamma(half);
        return ln.exp();
    }
    let nu = half - 1.0;
    let z = r * c;
    let ln_pre = c.ln() + nu * (c / r).ln() - 0.5 * (c - r) * (c - r);
    ln_pre.exp() * bessel_i_scaled(nu, z)
}

/// P(C <= k | r) = P(ncx2(d, r^2) <= k^2), from the core's distribution code.
fn atom(k: f64, r: f64, d: usize) -> Result<f64> {
    dist::ncx2_cdf(k * k, d as u32, r * r).map_err(|e| anyhow::anyhow!("ncx2_cdf: {e}"))
}

/// Zero-state ARL of the norm chain with threshold h, reference k, dimension
/// d. `shift` adds to the non-centrality (0: in control; delta: the aligned
/// model of the out-of-control ARL). `refine` multiplies the node count
/// (1 normally; 2 to check convergence).
pub fn arl(h: f64, k: f64, d: usize, shift: f64, refine: usize) -> Result<f64> {
    if !(h > 0.0 && k > 0.0 && d >= 1) {
        bail!("arl needs h > 0, k > 0, d >= 1 (h = {h}, k = {k}, d = {d})");
    }
    let panels = (h / PANEL_WIDTH).ceil().max(1.0) as usize;
    let (gx, gw) = gauss_legendre(NODES_PER_PANEL * refine);
    let width = h / panels as f64;
    let mut x = Vec::with_capacity(panels * gx.len());
    let mut w = Vec::with_capacity(panels * gx.len());
    for p in 0..panels {
        let a = p as f64 * width;
        for (xi, wi) in gx.iter().zip(gw.iter()) {
            x.push(a + 0.5 * width * (xi + 1.0));
            w.push(0.5 * width * wi);
        }
    }
    let n = x.len() + 1;
    let mut a = DMatrix::<f64>::identity(n, n);
    let points = std::iter::once(0.0).chain(x.iter().copied());
    for (i, r) in points.enumerate() {
        let rr = r + shift;
        a[(i, 0)] -= atom(k, rr, d)?;
        for (j, (xj, wj)) in x.iter().zip(w.iter()).enumerate() {
            a[(i, j + 1)] -= wj * ncchi_pdf(xj + k, rr, d);
        }
    }
    let l = a
        .lu()
        .solve(&DVector::from_element(n, 1.0))
        .context("singular Nystrom system")?;
    Ok(l[0])
}

/// h with ARL0(h, k, d) = target: bracket, then Illinois (modified regula
/// falsi) on ln ARL0(h) - ln target, which is nearly linear in h, stopping
/// when the bracket is narrower than `H_TOL`.
pub fn h_for_arl0(target: f64, k: f64, d: usize) -> Result<f64> {
    h_for_arl0_from(target, k, d, None)
}

/// As [`h_for_arl0`], with a known lower point (h, ARL0(h)) with
/// ARL0(h) < target to start the bracket from (the table solves increasing
/// targets in turn).
pub fn h_for_arl0_from(target: f64, k: f64, d: usize, below: Option<(f64, f64)>) -> Result<f64> {
    if !(target > 1.0) {
        bail!("ARL0 must exceed 1 (got {target})");
    }
    let g = |h: f64| -> Result<f64> { Ok(arl(h, k, d, 0.0, 1)?.ln() - target.ln()) };
    let (mut lo, mut glo) = match below {
        Some((h, a)) if a < target => (h, a.ln() - target.ln()),
        _ => {
            let lo = 0.5 * k.min(1.0);
            (lo, g(lo)?)
        }
    };
    if glo > 0.0 {
        bail!("ARL0 {target} is below the ARL at h = {lo}");
    }
    // ln ARL0 grows at least ~k per unit of h once h is past the in-control
    // level of the chain; step up by the linear estimate, then by 1.5x.
    let mut step = (-glo / k).clamp(0.5, 20.0);
    let mut hi = lo + step;
    let mut ghi = g(hi)?;
    while ghi < 0.0 {
        lo = hi;
        glo = ghi;
        step *= 1.5;
        hi += step;
        ghi = g(hi)?;
        if hi > 1e4 {
            bail!("no h found for ARL0 {target}");
        }
    }
    let mut side = 0i8;
    for _ in 0..200 {
        if hi - lo < H_TOL {
            break;
        }
        let mut m = hi - ghi * (hi - lo) / (ghi - glo);
        if !(m > lo && m < hi) {
            m = 0.5 * (lo + hi);
        }
        let gm = g(m)?;
        if gm == 0.0 {
            return Ok(m);
        }
        if gm < 0.0 {
            lo = m;
            glo = gm;
            if side == -1 {
                ghi *= 0.5;
            }
            side = -1;
        } else {
            hi = m;
            ghi = gm;
            if side == 1 {
                glo *= 0.5;
            }
            side = 1;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// ARL by seeded simulation of the core's Crosier recursion: `runs` runs
/// from S_0 = 0 with y ~ N(mu, I_d), ||mu|| = delta along the first axis,
/// each to its first D_t >= h. Run i draws from ChaCha8 stream i of `seed`,
/// so the result does not depend on the thread split. Returns (mean,
/// standard error of the mean).
pub fn simulate_arl(h: f64, k: f64, d: usize, delta: f64, runs: usize, seed: u64) -> (f64, f64) {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(8);
    let lengths: Vec<u64> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    (t..runs)
                        .step_by(threads)
                        .map(|i| {
                            let mut rng = ChaCha8Rng::seed_from_u64(seed);
                            rng.set_stream(i as u64);
                            run_length(h, k, d, delta, &mut rng)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let n = lengths.len() as f64;
    let mean = lengths.iter().map(|&l| l as f64).sum::<f64>() / n;
    let var = lengths
        .iter()
        .map(|&l| (l as f64 - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

fn run_length(h: f64, k: f64, d: usize, delta: f64, rng: &mut ChaCha8Rng) -> u64 {
    let mut s = vec![0.0; d];
    let mut y = vec![0.0; d];
    for t in 1..=MAX_RUN {
        for (j, yj) in y.iter_mut().enumerate() {
            let z: f64 = StandardNormal.sample(rng);
            *yj = z + if j == 0 { delta } else { 0.0 };
        }
        let (_, dt) = mcusum::crosier_step(&mut s, &y, k);
        if !(dt < h) {
            return t;
        }
    }
    MAX_RUN
}

/// The snapshot test's ARL (seed 001 Table 2, second row): a geometric run
/// with success probability P(ncx2(d, delta^2) >= T^2).
pub fn snapshot_arl(t: f64, d: usize, delta: f64) -> Result<f64> {
    let p =
        1.0 - dist::ncx2_cdf(t * t, d as u32, delta * delta).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(1.0 / p)
}

/// The documented k values of the device table (sigma units).
pub const TABLE_K: [f64; 3] = [0.5, 1.0, 1.5];
/// log10 ARL0 nodes of the device table: 2, 2.5, ..., 9.
pub const TABLE_LOG10_ARL0_STEPS: usize = 15;
/// Dimensions 1..=TABLE_MAX_DIM (capacity 32 minus the 4 unknowns of one
/// constellation).
pub const TABLE_MAX_DIM: usize = raim_core::DEFAULT_CAPACITY - 4;

fn table_log10() -> Vec<f64> {
    (0..TABLE_LOG10_ARL0_STEPS)
        .map(|i| 2.0 + 0.5 * i as f64)
        .collect()
}

/// One row of the device table: h for each log10 ARL0 node, solved in
/// increasing order, each bracket starting from the previous solution.
pub fn table_row(k: f64, d: usize, logs: &[f64]) -> Result<Vec<f64>> {
    let mut below = None;
    let mut row = Vec::with_capacity(logs.len());
    for l in logs {
        let target = 10f64.powf(*l);
        let h = h_for_arl0_from(target, k, d, below)?;
        row.push(h);
        below = Some((h, target * (1.0 - 1e-6)));
    }
    Ok(row)
}

/// One computed row of the table, keyed by (k index, d).
type TableRow = ((usize, usize), Result<Vec<f64>>);

/// The device table's Rust source: h(k, d, ARL0) rounded to 1e-4.
pub fn table_source() -> Result<String> {
    let logs = table_log10();
    let jobs: Vec<(usize, usize)> = (0..TABLE_K.len())
        .flat_map(|ki| (1..=TABLE_MAX_DIM).map(move |d| (ki, d)))
        .collect();
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(8);
    let rows: Vec<TableRow> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let jobs = &jobs;
                let logs = &logs;
                scope.spawn(move || {
                    jobs.iter()
                        .skip(t)
                        .step_by(threads)
                        .map(|&(ki, d)| ((ki, d), table_row(TABLE_K[ki], d, logs)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let mut grid = vec![vec![Vec::new(); TABLE_MAX_DIM]; TABLE_K.len()];
    for ((ki, d), row) in rows {
        grid[ki][d - 1] = row?;
    }
    let mut s = String::new();
    writeln!(
        s,
        "//! MCUSUM alarm thresholds h(k, d, ARL0) for the device (SPEC §7.2)."
    )?;
    writeln!(s, "//! GENERATED by `cargo run --release -p raim-tool -- arl --table --out crates/raim-core/src/sequential/mcusum_table.rs`;")?;
    writeln!(
        s,
        "//! do not edit. The raim-tool test `device_table_regenerates_identically`"
    )?;
    writeln!(
        s,
        "//! checks that the tool still produces this file byte for byte."
    )?;
    writeln!(
        s,
        "//! Each h solves ARL0(h, k, d) = 10^`LOG10_ARL0[j]` by the Fredholm integral"
    )?;
    writeln!(s, "//! equation (Gauss-Legendre Nystrom, {NODES_PER_PANEL} nodes per panel of width <= {PANEL_WIDTH}), rounded to 1e-4.")?;
    writeln!(s)?;
    writeln!(s, "/// Reference values k (sigma units) the table covers.")?;
    writeln!(
        s,
        "pub const K_VALUES: [f64; {}] = {:?};",
        TABLE_K.len(),
        TABLE_K
    )?;
    writeln!(
        s,
        "/// Largest parity dimension d covered (d = 1..=MAX_DIM)."
    )?;
    writeln!(s, "pub const MAX_DIM: usize = {TABLE_MAX_DIM};")?;
    writeln!(s, "/// log10 of the in-control ARL0 nodes, epochs.")?;
    writeln!(
        s,
        "pub const LOG10_ARL0: [f64; {}] = {:?};",
        logs.len(),
        logs
    )?;
    writeln!(s, "/// H[k index][d - 1][ARL0 index].")?;
    writeln!(s, "#[rustfmt::skip]")?;
    writeln!(
        s,
        "pub const H: [[[f64; {}]; {}]; {}] = [",
        logs.len(),
        TABLE_MAX_DIM,
        TABLE_K.len()
    )?;
    for (ki, k) in TABLE_K.iter().enumerate() {
        writeln!(s, "    // k = {k}")?;
        writeln!(s, "    [")?;
        for (di, row) in grid[ki].iter().enumerate() {
            let cells: Vec<String> = row.iter().map(|h| format!("{h:.4}")).collect();
            writeln!(s, "        [{}], // d = {}", cells.join(", "), di + 1)?;
        }
        writeln!(s, "    ],")?;
    }
    writeln!(s, "];")?;
    Ok(s)
}

/// `raim arl`: ARL0 by the integral equation, its inverse h(ARL0), ARL1 by
/// simulation, seed 001 Table 2, the device table.
#[derive(Debug, Clone, clap::Args)]
pub struct ArlArgs {
    /// Parity dimension d.
    #[arg(long)]
    pub dim: Option<usize>,
    /// Reference value k, sigma units.
    #[arg(long)]
    pub k: Option<f64>,
    /// Alarm threshold h: print ARL0(h).
    #[arg(long, conflicts_with = "arl0")]
    pub h: Option<f64>,
    /// Target in-control ARL0: print h(ARL0).
    #[arg(long)]
    pub arl0: Option<f64>,
    /// Mean offset delta = ||mu|| (sigma units): ARL1 by seeded simulation
    /// (and by the aligned-shift integral equation, for comparison).
    #[arg(long)]
    pub offset: Option<f64>,
    /// Simulated runs for --offset.
    #[arg(long, default_value_t = 10_000)]
    pub runs: usize,
    /// Seed of the simulation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Print the published ARL table of the MCUSUM RAIM paper (docs/MCRAIM.md, its Table 2) beside our values (dim 2, k = 1).
    #[arg(long)]
    pub seed001: bool,
    /// Write the device threshold table (Rust source) to --out or stdout.
    #[arg(long)]
    pub table: bool,
    /// Output file for --table.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run the step/ramp comparison of snapshot, MCUSUM reset, MCUSUM
    /// transport and the combination on a moving 8-12 satellite sky at ARL0
    /// --arl0 (default 3e6) with --runs runs (docs/MCRAIM.md).
    #[arg(long)]
    pub scenario: bool,
    /// In-control ARL0 for the scenario's false-alarm count.
    #[arg(long, default_value_t = 500.0)]
    pub fa_arl0: f64,
    /// Length of each fault-free run of the scenario's false-alarm count, epochs.
    #[arg(long, default_value_t = 5000)]
    pub fa_epochs: u64,
}

pub fn run(a: &ArlArgs) -> Result<()> {
    if a.table {
        let src = table_source()?;
        match &a.out {
            Some(p) => {
                std::fs::write(p, src).with_context(|| format!("writing {}", p.display()))?
            }
            None => crate::out!("{src}")?,
        }
        return Ok(());
    }
    if a.seed001 {
        return seed001(a.runs, a.seed, a.json);
    }
    if a.scenario {
        let p = scenario::Params {
            arl0: a.arl0.unwrap_or(3.0e6),
            share: raim_core::config::DEFAULT_SNAPSHOT_SHARE,
            k: a.k.unwrap_or(raim_core::config::DEFAULT_MCUSUM_K),
            warmup_s: 300,
            cap_s: 1000,
        };
        let rows = scenario::compare(&p, a.runs, a.seed, a.fa_arl0, a.runs, a.fa_epochs)?;
        if a.json {
            crate::outln!("{}", serde_json::to_string(&rows)?)?;
        } else {
            crate::outln!(
                "ARL0 {} epochs (1 s), k = {}, snapshot share {}; {} runs, seed {}; false alarms: ARL0 {}, {} runs x {} epochs",
                p.arl0, p.k, p.share, a.runs, a.seed, a.fa_arl0, a.runs, a.fa_epochs
            )?;
            scenario::print_table(&rows)?;
        }
        return Ok(());
    }
    let (Some(d), Some(k)) = (a.dim, a.k) else {
        bail!("give --dim and --k (or --table, or --seed001)");
    };
    let h = match (a.h, a.arl0) {
        (Some(h), _) => h,
        (None, Some(t)) => h_for_arl0(t, k, d)?,
        (None, None) => bail!("give --h or --arl0"),
    };
    let arl0 = arl(h, k, d, 0.0, 1)?;
    let mut v = serde_json::json!({ "dim": d, "k": k, "h": h, "arl0": arl0 });
    if let Some(delta) = a.offset {
        let (mean, se) = simulate_arl(h, k, d, delta, a.runs, a.seed);
        let aligned = arl(h, k, d, delta, 1)?;
        v["offset"] = delta.into();
        v["arl1"] = mean.into();
        v["arl1_se"] = se.into();
        v["runs"] = a.runs.into();
        v["seed"] = a.seed.into();
        v["arl1_aligned_model"] = aligned.into();
    }
    if a.json {
        crate::outln!("{v}")?;
    } else {
        crate::outln!("dim={d} k={k} h={h:.6} ARL0={arl0:.3}")?;
        if let Some(delta) = a.offset {
            crate::outln!(
                "offset={delta} ARL1={:.4} +- {:.4} (simulation, {} runs, seed {}); aligned-shift model {:.4}",
                v["arl1"].as_f64().unwrap_or(f64::NAN),
                v["arl1_se"].as_f64().unwrap_or(f64::NAN),
                a.runs,
                a.seed,
                v["arl1_aligned_model"].as_f64().unwrap_or(f64::NAN)
            )?;
        }
    }
    Ok(())
}

/// Seed 001 Table 2 (dim 2, k = 1, ARL0 = 1e4) printed beside ours.
pub const SEED001_OFFSETS: [f64; 6] = [1.0, 1.5, 2.0, 3.0, 4.0, 5.0];
/// The published MCUSUM row (h = 5.21).
pub const SEED001_MCUSUM: [f64; 6] = [22.0, 8.6, 5.2, 3.0, 2.2, 1.88];
/// The published snapshot row (T = 4.3).
pub const SEED001_SNAPSHOT: [f64; 6] = [938.0, 219.0, 60.0, 8.5, 2.32, 1.26];

fn seed001(runs: usize, seed: u64, json: bool) -> Result<()> {
    let (d, k, h, t) = (2usize, 1.0, 5.21, 4.3);
    let h_exact = h_for_arl0(1e4, k, d)?;
    let arl0 = arl(h, k, d, 0.0, 1)?;
    let snap0 = snapshot_arl(t, d, 0.0)?;
    let mut rows = Vec::new();
    for (i, &delta) in SEED001_OFFSETS.iter().enumerate() {
        let (sim, se) = simulate_arl(h, k, d, delta, runs, seed);
        rows.push(serde_json::json!({
            "offset": delta,
            "mcusum_published": SEED001_MCUSUM[i],
            "mcusum_simulated": sim, "mcusum_simulated_se": se,
            "mcusum_aligned_model": arl(h, k, d, delta, 1)?,
            "snapshot_published": SEED001_SNAPSHOT[i],
            "snapshot_exact": snapshot_arl(t, d, delta)?,
        }));
    }
    let v = serde_json::json!({
        "dim": d, "k": k, "h_for_arl0_1e4": h_exact, "arl0_at_h_5_21": arl0,
        "snapshot_t": t, "snapshot_arl0": snap0, "runs": runs, "seed": seed, "rows": rows,
    });
    if json {
        crate::outln!("{v}")?;
        return Ok(());
    }
    crate::outln!("seed 001 Table 2, dim {d}, k = {k}: h(ARL0 = 1e4) = {h_exact:.4}; ARL0(h = 5.21) = {arl0:.1}; snapshot ARL0(T = 4.3) = {snap0:.1}")?;
    crate::outln!(
        "{:>6} | {:>9} {:>16} {:>9} | {:>9} {:>9}",
        "delta",
        "MC publ.",
        "MC simulated",
        "aligned",
        "snap publ.",
        "snap exact"
    )?;
    for r in rows {
        let f = |key: &str| r[key].as_f64().unwrap_or(f64::NAN);
        crate::outln!(
            "{:>6} | {:>9} {:>9.3} ±{:<5.3} {:>9.3} | {:>9} {:>9.3}",
            f("offset"),
            f("mcusum_published"),
            f("mcusum_simulated"),
            f("mcusum_simulated_se"),
            f("mcusum_aligned_model"),
            f("snapshot_published"),
            f("snapshot_exact")
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two branches of the scaled Bessel function agree where they meet
    /// and beyond, for the orders the table uses (nu = d/2 - 1, d <= 28).
    #[test]
    fn bessel_branches_agree() {
        const BRANCH_REL_TOL: f64 = 1e-12;
        for nu in [-0.5, 0.0, 0.5, 1.0, 4.5, 9.0, 13.0] {
            for z in [30.0, 34.0, 45.0, 80.0] {
                let a = bessel_i_scaled_series(nu, z);
                let b = bessel_i_scaled_hankel(nu, z);
                assert!(
                    ((a - b) / a).abs() < BRANCH_REL_TOL,
                    "nu {nu} z {z}: {a} vs {b}"
                );
            }
        }
    }

    /// Gauss-Legendre integrates polynomials of degree 2n-1 exactly.
    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        for n in [1usize, 2, 5, 8, 16] {
            let (x, w) = gauss_legendre(n);
            for deg in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!((q - exact).abs() < 1e-13, "n {n} deg {deg}: {q} vs {exact}");
            }
        }
    }

    /// The non-central chi density against closed forms: d = 1 is
    /// phi(c - r) + phi(c + r); d = 3 is (c/r) (phi(c - r) - phi(c + r)).
    /// d = 2 (Rice) against I0 by quadrature of (1/pi) int_0^pi e^(z cos t) dt.
    /// And every density integrates to 1.
    #[test]
    fn ncchi_density_matches_closed_forms() {
        let phi = |x: f64| (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
        const DENSITY_REL_TOL: f64 = 1e-11;
        for &r in &[0.0, 0.3, 2.0, 7.0, 25.0, 60.0] {
            for &c in &[0.05, 0.5, 1.0, 3.0, 6.5, 24.0, 61.0] {
                let d1 = phi(c - r) + phi(c + r);
                let got = ncchi_pdf(c, r, 1);
                assert!(
                    (got - d1).abs() <= DENSITY_REL_TOL * d1 + 1e-300,
                    "d1 r {r} c {c}: {got} vs {d1}"
                );
                if r > 0.0 {
                    let d3 = c / r * (phi(c - r) - phi(c + r));
                    let got = ncchi_pdf(c, r, 3);
                    assert!(
                        (got - d3).abs() <= 1e-9 * d3 + 1e-300,
                        "d3 r {r} c {c}: {got} vs {d3}"
                    );
                }
                if r * c < 40.0 {
                    let m = 20_000;
                    let i0: f64 = (0..m)
                        .map(|j| {
                            let t = (j as f64 + 0.5) * std::f64::consts::PI / m as f64;
                            (r * c * t.cos() - r * c).exp()
                        })
                        .sum::<f64>()
                        / m as f64;
                    let rice = c * (-0.5 * (c - r) * (c - r)).exp() * i0;
                    let got = ncchi_pdf(c, r, 2);
                    assert!(
                        (got - rice).abs() <= 1e-9 * rice + 1e-300,
                        "d2 r {r} c {c}: {got} vs {rice}"
                    );
                }
            }
        }
        for d in [1usize, 2, 5, 12, 28] {
            for r in [0.0, 1.0, 9.0, 40.0] {
                let (x, w) = gauss_legendre(64);
                let hi = r + 12.0 + (d as f64).sqrt() * 2.0;
                let mass: f64 = (0..40)
                    .flat_map(|p| {
                        let a = p as f64 * hi / 40.0;
                        let b = a + hi / 40.0;
                        x.iter().zip(&w).map(move |(x, w)| (a, b, *x, *w))
                    })
                    .map(|(a, b, x, w)| {
                        0.5 * (b - a) * w * ncchi_pdf(a + 0.5 * (b - a) * (x + 1.0), r, d)
                    })
                    .sum();
                assert!((mass - 1.0).abs() < 1e-9, "d {d} r {r}: {mass}");
            }
        }
    }

    /// Seed 001 Table 2 / SPEC §7.1-7.2: dim 2, k = 1. The exact ARL0 at
    /// h = 5.21 is 10071 and h for ARL0 = 1e4 is 5.206, which rounds to the
    /// published 5.21. Also the discretisation has converged: doubling the
    /// nodes changes ARL0 by less than 1e-8 relative.
    ///
    /// Verifies: SPEC-7.2
    #[test]
    fn seed_001_threshold() {
        let a = arl(5.21, 1.0, 2, 0.0, 1).unwrap();
        let fine = arl(5.21, 1.0, 2, 0.0, 2).unwrap();
        const CONVERGENCE_REL: f64 = 1e-8;
        assert!(((a - fine) / fine).abs() < CONVERGENCE_REL, "{a} vs {fine}");
        const SPEC_ARL0_ABS_TOL: f64 = 0.5; // epochs: SPEC quotes 10071
        assert!((a - 10071.0).abs() < SPEC_ARL0_ABS_TOL, "{a}");
        let h = h_for_arl0(1e4, 1.0, 2).unwrap();
        const SPEC_H_TOL: f64 = 5e-4; // SPEC quotes 5.206
        assert!((h - 5.206).abs() < SPEC_H_TOL, "{h}");
        assert!(
            ((h * 100.0).round() - 521.0).abs() < 0.5,
            "{h} does not round to 5.21"
        );
        let back = arl(h, 1.0, 2, 0.0, 1).unwrap();
        assert!((back - 1e4).abs() < 1e-4, "{back}");
    }

    /// Seed 001 Table 2, snapshot row (T = 4.3, dim 2): ARL = 1 /
    /// P(ncx2(2, delta^2) >= 4.3^2) within 1 % of the published 938, 219,
    /// 60, 2.32, 1.26; at delta = 3 the exact value is 8.13 against the
    /// printed 8.5 (SPEC §7.2).
    #[test]
    fn seed_001_snapshot_row() {
        const PUBLISHED_REL_TOL: f64 = 0.01;
        for (i, &delta) in SEED001_OFFSETS.iter().enumerate() {
            let ours = snapshot_arl(4.3, 2, delta).unwrap();
            let theirs = SEED001_SNAPSHOT[i];
            if delta == 3.0 {
                assert!((ours - 8.13).abs() < 0.005, "{ours}");
                assert!(
                    (ours - theirs).abs() / theirs > 0.04,
                    "the misprint should show: {ours}"
                );
            } else {
                assert!(
                    (ours - theirs).abs() / theirs < PUBLISHED_REL_TOL,
                    "delta {delta}: {ours} vs {theirs}"
                );
            }
        }
        // In control, exp(4.3^2 / 2) = 10353 (closed form for dim 2).
        let a0 = snapshot_arl(4.3, 2, 0.0).unwrap();
        assert!((a0 - (4.3f64 * 4.3 / 2.0).exp()).abs() < 1e-6 * a0);
    }

    /// Seed 001 Table 2, MCUSUM row (h = 5.21). By simulation of the core's
    /// recursion: 27.7, 9.35, 5.51, 3.10, 2.25, 1.887 for delta 1, 1.5, 2,
    /// 3, 4, 5 (200 000 runs; an independent numpy simulation gives the
    /// same to within its standard error; SPEC §7.2 quotes "about 27.4, 9.4,
    /// 5.5" and 3.0, 2.2, 1.88). The published row (22, 8.6, 5.2, 3.0, 2.2,
    /// 1.88) is, digit for digit, the aligned-shift model (integral equation
    /// with non-centrality R + delta: 22.44, 8.614, 5.281, 3.057, 2.230,
    /// 1.886) truncated to the printed digits.
    ///
    /// Verifies: SPEC-7.2
    #[test]
    fn seed_001_mcusum_row() {
        const RUNS: usize = 4000;
        // Our simulation against SPEC's approximate figures: 4 standard
        // errors plus 2 % for SPEC's "about" (27.4 vs our 27.7).
        const SE_FACTOR: f64 = 4.0;
        const SPEC_SIM_REL_TOL: f64 = 0.02;
        let spec_sim = [27.4, 9.4, 5.5, 3.1, 2.25, 1.887];
        let printed_decimals = [0, 1, 1, 1, 1, 2];
        for (i, &delta) in SEED001_OFFSETS.iter().enumerate() {
            let (sim, se) = simulate_arl(5.21, 1.0, 2, delta, RUNS, 17);
            let tol = SE_FACTOR * se + SPEC_SIM_REL_TOL * spec_sim[i];
            assert!(
                (sim - spec_sim[i]).abs() < tol,
                "delta {delta}: {sim} ± {se}"
            );
            let aligned = arl(5.21, 1.0, 2, delta, 1).unwrap();
            let published = SEED001_MCUSUM[i];
            let scale = 10f64.powi(printed_decimals[i]);
            let truncated = (aligned * scale).floor() / scale;
            assert!(
                (truncated - published).abs() < 1e-9,
                "delta {delta}: aligned {aligned} -> {truncated}"
            );
            if delta < 3.0 {
                // Here the aligned model is wrong by 4-25 %: the true ARL1 is longer.
                assert!(
                    sim > published * 1.04,
                    "delta {delta}: simulation {sim} vs {published}"
                );
            } else {
                // For large shifts published and simulated agree within 4 %.
                const LARGE_SHIFT_REL_TOL: f64 = 0.04;
                assert!(
                    (sim - published).abs() / published < LARGE_SHIFT_REL_TOL,
                    "delta {delta}: {sim}"
                );
            }
        }
    }

    /// The integral-equation ARL0 against a seeded simulation of the core's
    /// recursion, within 4 standard errors, across dimensions and k.
    #[test]
    fn integral_equation_matches_simulation() {
        const SE_FACTOR: f64 = 4.0;
        for &(d, k, h, runs) in &[
            (1usize, 0.5, 3.0, 20_000usize),
            (2, 1.0, 3.5, 20_000),
            (5, 0.5, 6.0, 10_000),
            (12, 1.0, 5.0, 10_000),
            (2, 1.0, 5.21, 1500),
        ] {
            let exact = arl(h, k, d, 0.0, 1).unwrap();
            let (sim, se) = simulate_arl(h, k, d, 0.0, runs, 99);
            assert!(
                (sim - exact).abs() < SE_FACTOR * se,
                "d {d} k {k} h {h}: {exact} vs {sim} ± {se}"
            );
        }
    }

    /// A sample of rows of the committed device table (cheap and expensive
    /// ones, every k) regenerates to the same printed digits. The full
    /// byte-for-byte check is the ignored test below (~40 s CPU in release).
    #[test]
    fn device_table_sample_rows_regenerate() {
        let logs = table_log10();
        assert_eq!(
            logs.as_slice(),
            raim_core::sequential::mcusum::LOG10_ARL0.as_slice()
        );
        assert_eq!(
            TABLE_K.as_slice(),
            raim_core::sequential::mcusum::K_VALUES.as_slice()
        );
        for &(ki, d) in &[(0usize, 1usize), (1, 2), (2, 5), (1, 13)] {
            let fresh = table_row(TABLE_K[ki], d, &logs).unwrap();
            let committed = &raim_core::sequential::mcusum_table::H[ki][d - 1];
            for (a, b) in fresh.iter().zip(committed.iter()) {
                assert_eq!(
                    format!("{a:.4}"),
                    format!("{b:.4}"),
                    "k {} d {d}",
                    TABLE_K[ki]
                );
            }
        }
    }

    /// The committed device table is what the tool generates, byte for byte
    /// (regenerate with the command in its header). Run with
    /// `cargo test --release -p raim-tool -- --ignored device_table`.
    #[test]
    #[ignore = "about 40 s CPU in release; run before committing a new table"]
    fn device_table_regenerates_identically() {
        let committed = include_str!("../../raim-core/src/sequential/mcusum_table.rs");
        let fresh = table_source().unwrap();
        assert!(
            committed == fresh,
            "crates/raim-core/src/sequential/mcusum_table.rs is stale: rerun the command in its header"
        );
    }

    /// The core's interpolated threshold against the tool's exact inverse,
    /// between table nodes (half-way in log10 ARL0).
    #[test]
    fn core_interpolation_matches_exact_inverse() {
        const H_INTERP_TOL: f64 = 2e-3;
        for &(d, k, arl0) in &[
            (2usize, 1.0, 3.0e4),
            (6, 0.5, 6.0e6),
            (12, 1.5, 2.0e3),
            (28, 1.0, 4.0e7),
            (1, 0.5, 1.5e2),
        ] {
            let exact = h_for_arl0(arl0, k, d).unwrap();
            let core = mcusum::threshold(d, k, arl0).unwrap();
            assert!(
                (core - exact).abs() < H_INTERP_TOL,
                "d {d} k {k} ARL0 {arl0}: {core} vs {exact}"
            );
        }
    }
}
