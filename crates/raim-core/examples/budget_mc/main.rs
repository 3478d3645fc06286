//! The combined false-alarm Monte Carlo of docs/BUDGET.md.
//!
//! ```text
//! cargo run --release -p raim-core --example budget_mc -- EPOCHS P_FA_TOTAL SNAPSHOT MCUSUM ARAIM [SEED] [THREADS]
//! cargo run --release -p raim-core --example budget_mc -- 1000000 1e-4 0.5 0.25 0.25 1 2
//! ```
//! The long benchmark is 10^7 epochs (`-- 10000000 1e-5 0.5 0.25 0.25 1 2`).
//! Prints, per monitor, its events per epoch against its allocation, and
//! the combined rate against the total, with Clopper-Pearson 95 % intervals,
//! as the markdown rows of the table in docs/BUDGET.md.
mod sim;

fn main() -> Result<(), String> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, d: f64| -> Result<f64, String> {
        a.get(i).map_or(Ok(d), |s| {
            s.parse().map_err(|e| format!("argument {}: {e}", i + 1))
        })
    };
    let epochs = num(0, 1e6)? as u64;
    let total = num(1, 1e-4)?;
    let (snap, mc, ar) = (num(2, 0.5)?, num(3, 0.25)?, num(4, 0.25)?);
    let seed = num(5, 1.0)? as u64;
    let threads = num(6, 2.0)? as u64;
    let b = sim::budget(total, snap, mc, ar);
    b.validate().map_err(|e| e.to_string())?;
    let t0 = std::time::Instant::now();
    let t = sim::run(&b, epochs, seed, threads)?;
    let n = t.epochs;
    println!(
        "budget_mc: {n} epochs, P_FA total {total:e} per epoch (snapshot {snap}, MCUSUM {mc}, ARAIM {ar}), pmd {:e}, pwe {:e}, seed {seed}, {threads} threads, {:.0} s",
        b.pmd(),
        b.pwe(),
        t0.elapsed().as_secs_f64()
    );
    println!();
    println!(
        "| monitor | allocated per epoch | events | rate per epoch | 95 % interval | within |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    let row = |name: &str, alloc: Option<f64>, k: u64| {
        let (lo, hi) = sim::interval(k, n);
        let within = alloc.map_or("-".to_string(), |p| {
            if lo <= p {
                "yes".into()
            } else {
                "NO".into()
            }
        });
        println!(
            "| {name} | {} | {k} | {:.3e} | [{lo:.2e}, {hi:.2e}] | {within} |",
            alloc.map_or("-".into(), |p| format!("{p:.3e}")),
            k as f64 / n as f64
        );
    };
    row("snapshot test", Some(b.pfa_of(snap)), t.snapshot);
    row("MCUSUM (1 / ARL0)", Some(b.pfa_of(mc)), t.mcusum);
    row("ARAIM (P_FA,vert + P_FA,hor)", Some(b.pfa_of(ar)), t.araim);
    println!("| PCA | 0 (not on the integrity path) | not run | - | - | - |");
    println!(
        "| particle filters | 0 in this run (their own epochs; calibrated thresholds, docs/PF.md) | not run | - | - | - |"
    );
    row("**combined** (any event)", Some(total), t.combined);
    println!();
    println!("Continuity cost (snapshot engine decisions on fault-free epochs):");
    println!();
    println!("| outcome | epochs | rate per epoch |");
    println!("| --- | --- | --- |");
    for (name, k) in [
        (
            "multiple-fault search ran (after a detection)",
            t.multifault_ran,
        ),
        ("exclusion (a satellite lost)", t.engine_excluded),
        ("alarm (the solution lost)", t.engine_alarm),
        ("refused epochs (typed error)", t.refused),
    ] {
        println!("| {name} | {k} | {:.3e} |", k as f64 / n as f64);
    }
    Ok(())
}
