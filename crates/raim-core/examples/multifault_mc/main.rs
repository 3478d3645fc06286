//! The multiple-fault Monte Carlo (docs/MULTIFAULT.md): today's
//! FDE against the reconstruction on the same seeded draws.
//!
//!     cargo run --release -p raim-core --example multifault_mc -- 30000 11 1000
//!
//! (draws, seed, group budget). Prints the outcome rates per method and
//! fault count, correct identification per fault-size bin (the plot's
//! data, also written as CSV to `target/multifault_mc.csv`), and the
//! reconstruction's host cost per epoch against the number of groups.
mod campaign;

use campaign::{Outcome, BINS, BIN_M, OUTCOMES};

fn main() {
    let mut args = std::env::args().skip(1);
    let draws: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(3000);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(11);
    let budget: u16 = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000);
    let tally = campaign::run(draws, seed, budget);
    let names = ["sequential", "reconstruction"];
    println!(
        "{} draws kept ({} skipped: n - m - 1 < t), seed {seed}, group budget {budget}",
        tally.draws, tally.skipped
    );
    println!();
    println!("| method | t | draws | missed | correct | wrong excl. | partial | ambiguous | other alarm | unavailable |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (m, name) in names.iter().enumerate() {
        for t in 0..3 {
            let total = tally.draws_of(m, t).max(1) as f64;
            let cells: Vec<String> = OUTCOMES
                .iter()
                .map(|o| format!("{:.4}", tally.total(m, t, *o) as f64 / total))
                .collect();
            println!(
                "| {name} | {} | {} | {} |",
                t + 1,
                tally.draws_of(m, t),
                cells.join(" | ")
            );
        }
    }
    println!();
    println!("Correct identification against the smallest fault size (m = sigma):");
    println!();
    let mut header = String::from("| method | t |");
    let mut rule = String::from("| --- | --- |");
    for b in 0..BINS {
        header += &format!(" {:.0}-{:.0} |", b as f64 * BIN_M, (b + 1) as f64 * BIN_M);
        rule += " --- |";
    }
    println!("{header}\n{rule}");
    let mut csv =
        String::from("method,t,bin_lo_m,bin_hi_m,draws,correct,wrong_exclusion,ambiguous\n");
    for (m, name) in names.iter().enumerate() {
        for t in 0..3 {
            let mut line = format!("| {name} | {} |", t + 1);
            for b in 0..BINS {
                let (c, n) = tally.bin(m, t, b, Outcome::Correct);
                let (w, _) = tally.bin(m, t, b, Outcome::WrongExclusion);
                let (a, _) = tally.bin(m, t, b, Outcome::Ambiguous);
                line += &format!(" {:.3} |", c as f64 / n.max(1) as f64);
                csv += &format!(
                    "{name},{},{},{},{n},{c},{w},{a}\n",
                    t + 1,
                    b as f64 * BIN_M,
                    (b + 1) as f64 * BIN_M
                );
            }
            println!("{line}");
        }
    }
    let _ = std::fs::create_dir_all("target");
    let _ = std::fs::write("target/multifault_mc.csv", csv);
    println!();
    println!("Reconstruction host cost per epoch (whole Raim::process, alarmed epochs):");
    println!();
    println!("| groups processed | epochs | mean µs |");
    println!("| --- | --- | --- |");
    for (g, ns, k) in &tally.cost {
        println!("| {g} | {k} | {:.1} |", *ns as f64 / *k as f64 / 1e3);
    }
}
