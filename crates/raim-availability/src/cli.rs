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
}

/// The examples that end `raim availability --help`.
pub const EXAMPLES: &str = "Examples:
  raim availability --run docs/runs/availability_maast_g24e24.toml --out runs/availability --level 0.99 --maps
  raim availability --run docs/runs/availability_maast_g24e24.toml --shard 2/4 --out shards
  raim availability merge shards/availability_maast_g24e24.shard-*-of-4.json --out runs/availability

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
