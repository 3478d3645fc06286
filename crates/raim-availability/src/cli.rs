//! `raim availability`: the command line of the engine (docs/AVAILABILITY.md).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, Result};

use crate::output::{self, Meta, Partial, PartialUser, PARTIAL_FORMAT};
use crate::{engine, run};

/// `raim availability --run FILE [--shard i/n] [--out DIR] [--level L]`, or
/// `raim availability merge PARTIAL... [--out DIR] [--level L]`.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true, after_help = EXAMPLES)]
pub struct AvailabilityArgs {
    /// Combine shard results.
    #[command(subcommand)]
    pub merge: Option<MergeCmd>,
    /// The TOML run file (docs/runs/*.toml).
    #[arg(long)]
    pub run: Option<PathBuf>,
    /// Run shard i of n (epochs split into n contiguous blocks) and write
    /// its partial result `<name>.shard-i-of-n.json` for `merge`.
    #[arg(long)]
    pub shard: Option<String>,
    /// Output directory.
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// A second coverage level beside the run file's target, e.g. 0.99.
    #[arg(long)]
    pub level: Option<f64>,
    /// Also draw the PNG maps (availability, 99.5th-percentile VPL, fault
    /// modes) beside the outputs (not with --shard).
    #[arg(long)]
    pub maps: bool,
    /// Worker threads (default: rayon's, one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// A sweep of every single-satellite outage of constellation SYS (G or
    /// E): the run as given, then once per satellite of SYS with that
    /// satellite removed (`<name>.outage-G03.*`), and the table
    /// `<name>.outages.csv` (not with --shard).
    #[arg(long, value_name = "SYS")]
    pub outages: Option<String>,
}

/// The examples that end `raim availability --help`.
pub const EXAMPLES: &str = "Examples:
  raim availability --run docs/runs/availability_maast_g24e24.toml --out runs/availability --level 0.99 --maps
  raim availability --run docs/runs/availability_maast_g24e24.toml --shard 2/4 --out shards
  raim availability merge shards/availability_maast_g24e24.shard-*-of-4.json --out runs/availability
  raim availability --run docs/runs/availability_maast_g24e24.toml --outages G --out runs/outages --level 0.99

Outputs: <name>.summary.json (coverage, users, user-epochs), <name>.users.csv (per user: availability,
99.5th-percentile VPL/HPL/EMT, fault modes), with --maps three PNG maps. Run file: docs/AVAILABILITY.md.";

/// `merge`.
#[derive(clap::Subcommand, Debug)]
pub enum MergeCmd {
    /// Combine the partial results of every shard of one run into the
    /// summary and CSV of the whole run (bit for bit the unsharded run's).
    Merge {
        /// The partial files (`*.shard-i-of-n.json`), in any order.
        #[arg(required = true)]
        parts: Vec<PathBuf>,
        /// Output directory.
        #[arg(long, default_value = ".")]
        out: PathBuf,
        /// A second coverage level beside the run's target.
        #[arg(long)]
        level: Option<f64>,
        /// Also draw the PNG maps.
        #[arg(long)]
        maps: bool,
    },
}

fn levels(target: f64, level: Option<f64>) -> Result<Vec<f64>> {
    let mut v = vec![target];
    if let Some(l) = level {
        if !(l > 0.0 && l <= 1.0) {
            return Err(anyhow!("--level {l}: outside (0, 1]"));
        }
        v.push(l);
    }
    Ok(v)
}

/// Runs the subcommand; reports on stderr.
///
/// # Errors
/// Bad input (file and line named) or an output that cannot be written.
pub fn run(args: &AvailabilityArgs) -> Result<()> {
    if let Some(MergeCmd::Merge {
        parts,
        out,
        level,
        maps,
    }) = &args.merge
    {
        let (meta, users) = output::merge(parts)?;
        let files = output::write_outputs(out, &meta, &users, &levels(meta.target, *level)?)?;
        for f in files {
            eprintln!("wrote {}", f.display());
        }
        if *maps {
            draw_maps(out, &meta, &users)?;
        }
        return Ok(());
    }
    let path = args
        .run
        .as_ref()
        .ok_or_else(|| anyhow!("raim availability: give --run FILE, or `merge PARTIAL...`"))?;
    let study = run::load(path)?;
    if let Some(sys) = &args.outages {
        if args.shard.is_some() {
            return Err(anyhow!("--outages runs whole scenarios: not with --shard"));
        }
        return outage_sweep(args, &study, sys);
    }
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(engine::STACK_BYTES);
    if let Some(t) = args.threads {
        pool = pool.num_threads(t);
    }
    let pool = pool.build()?;
    let meta = Meta::of(&study);
    let lv = levels(study.target, args.level)?;
    let t0 = Instant::now();
    let n_epochs = study.epochs_gps_s.len();
    if args.maps && args.shard.is_some() {
        return Err(anyhow!(
            "--maps draws a whole run: give it to `raim availability merge`, not with --shard"
        ));
    }
    let (range, shard) = match &args.shard {
        Some(s) => {
            let (i, n) = output::parse_shard(s)?;
            (output::shard_range(n_epochs, i, n), Some((i, n)))
        }
        None => (0..n_epochs, None),
    };
    let user_epochs = study.users.len() * range.len();
    eprintln!(
        "{}: {} users x {} epochs ({} satellites) on {} threads",
        study.name,
        study.users.len(),
        range.len(),
        study.sats.len(),
        pool.current_num_threads()
    );
    let e = |e: raim_core::araim::MonitorError| anyhow!("{}: {e}", path.display());
    match shard {
        Some((i, n)) => {
            let users = pool
                .install(|| engine::run_users(&study, range.clone(), |p| PartialUser::from(&p)))
                .map_err(e)?;
            let part = Partial {
                format: PARTIAL_FORMAT.into(),
                meta,
                shard: i,
                shards: n,
                epoch_range: [range.start, range.end],
                users,
            };
            std::fs::create_dir_all(&args.out)?;
            let f = args
                .out
                .join(format!("{}.shard-{i}-of-{n}.json", part.meta.name));
            std::fs::write(&f, serde_json::to_string(&part)?)?;
            eprintln!("wrote {}", f.display());
        }
        None => {
            let users = pool
                .install(|| engine::run_users(&study, range, engine::UserPartial::summary))
                .map_err(e)?;
            let files = output::write_outputs(&args.out, &meta, &users, &lv)?;
            for l in &lv {
                eprintln!(
                    "coverage at {l}: {:.4}",
                    output::coverage(&meta, &users, *l)
                );
            }
            for f in files {
                eprintln!("wrote {}", f.display());
            }
            if args.maps {
                draw_maps(&args.out, &meta, &users)?;
            }
        }
    }
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "{user_epochs} user-epochs in {s:.2} s: {:.0} user-epochs/s",
        user_epochs as f64 / s
    );
    Ok(())
}

fn draw_maps(dir: &std::path::Path, meta: &Meta, users: &[engine::UserSummary]) -> Result<()> {
    let cov = output::coverage(meta, users, meta.target);
    for f in crate::map::write_maps(dir, meta, users, cov)? {
        eprintln!("wrote {}", f.display());
    }
    Ok(())
}

/// `--outages SYS` (docs/AVAILABILITY.md "Outages"): the run as given and
/// each single-satellite outage of SYS, each written as a run of its own
/// (`<name>.outage-<sat>.summary.json`, `.users.csv`), and the table
/// `<name>.outages.csv`: scenario, removed satellite, coverage at the
/// target and at `--level`, the area-weighted mean availability, and the
/// users less and more available than with every satellite.
fn outage_sweep(args: &AvailabilityArgs, study: &run::Study, sys: &str) -> Result<()> {
    let system = match sys {
        "G" => raim_core::System::Gps,
        "E" => raim_core::System::Galileo,
        s => return Err(anyhow!("--outages {s}: G or E")),
    };
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(engine::STACK_BYTES);
    if let Some(t) = args.threads {
        pool = pool.num_threads(t);
    }
    let pool = pool.build()?;
    let lv = levels(study.target, args.level)?;
    let mut scenarios = vec![(String::new(), study.clone())];
    for s in study.sats.iter().filter(|s| s.id.system == system) {
        let label = format!("{}{:02}", system.letter(), s.id.prn);
        let mut o = study.clone();
        let keep: Vec<bool> = o.sats.iter().map(|x| x.id != s.id).collect();
        let mut k = keep.iter();
        o.sats.retain(|_| *k.next().unwrap_or(&true));
        let mut k = keep.iter();
        o.ism_entries.retain(|_| *k.next().unwrap_or(&true));
        o.name = format!("{}.outage-{label}", study.name);
        scenarios.push((label, o));
    }
    if scenarios.len() == 1 {
        return Err(anyhow!(
            "--outages {sys}: the run has no satellite of {sys}"
        ));
    }
    let mut table = format!(
        "scenario,removed,{},mean_availability,users_less_available,users_more_available\n",
        lv.iter()
            .map(|l| format!("coverage_{l}"))
            .collect::<Vec<_>>()
            .join(",")
    );
    let mut base: Vec<f64> = Vec::new();
    for (label, sc) in &scenarios {
        let meta = Meta::of(sc);
        let e = |e: raim_core::araim::MonitorError| anyhow!("{}: {e}", sc.name);
        let users = pool
            .install(|| {
                engine::run_users(sc, 0..sc.epochs_gps_s.len(), engine::UserPartial::summary)
            })
            .map_err(e)?;
        output::write_outputs(&args.out, &meta, &users, &lv)?;
        let avail: Vec<f64> = users.iter().map(|u| u.availability).collect();
        if label.is_empty() {
            base.clone_from(&avail);
        }
        let less = avail.iter().zip(&base).filter(|(a, b)| a < b).count();
        let more = avail.iter().zip(&base).filter(|(a, b)| a > b).count();
        let w: f64 = sc.users.iter().map(|u| u.weight).sum();
        let mean = sc
            .users
            .iter()
            .zip(&avail)
            .map(|(u, a)| u.weight * a)
            .sum::<f64>()
            / w;
        let cov: Vec<String> = lv
            .iter()
            .map(|l| format!("{:.6}", output::coverage(&meta, &users, *l)))
            .collect();
        table.push_str(&format!(
            "{},{},{},{mean:.6},{less},{more}\n",
            sc.name,
            if label.is_empty() { "none" } else { label },
            cov.join(",")
        ));
        eprintln!("{}: coverage at {}: {}", sc.name, lv[0], cov[0]);
    }
    std::fs::create_dir_all(&args.out)?;
    let f = args.out.join(format!("{}.outages.csv", study.name));
    std::fs::write(&f, table)?;
    eprintln!("wrote {}", f.display());
    Ok(())
}
