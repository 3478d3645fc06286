//! `raim availability`: the command line of the engine (docs/AVAILABILITY.md).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, Result};

use crate::output::{self, Meta, Partial, PartialUser, Piece, SweepHead, PARTIAL_FORMAT};
use crate::{engine, run, sweep};

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
    /// Run shard i of n and write its partial result
    /// `<name>.shard-i-of-n.json` for `merge`: the run's (scenario, epoch)
    /// units, scenario by scenario, split into n contiguous blocks (n equal
    /// to the scenarios: one scenario per shard; more: scenarios split in
    /// time).
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
    /// `<name>.outages.csv` and `.md` (a run file without `[[scenario]]`).
    #[arg(long, value_name = "SYS")]
    pub outages: Option<String>,
}

/// The examples that end `raim availability --help`.
pub const EXAMPLES: &str = "Examples:
  raim availability --run docs/runs/availability_maast_g24e24.toml --out runs/availability --level 0.99 --maps
  raim availability --run docs/runs/availability_maast_g24e24.toml --shard 2/4 --out shards
  raim availability merge shards/availability_maast_g24e24.shard-*-of-4.json --out runs/availability
  raim availability --run docs/runs/availability_maast_g24e24.toml --outages G --out runs/outages --level 0.99
  raim availability --run docs/runs/availability_sweep_europe.toml --out runs/sweep --level 0.99

Outputs: <name>.summary.json (coverage, users, user-epochs), <name>.users.csv (per user: availability,
99.5th-percentile VPL/HPL/EMT, fault modes), with --maps three PNG maps; a sweep ([[scenario]] in the run
file, or --outages) writes them per scenario and the coverage table <name>.sweep.csv/.md. Run file:
docs/AVAILABILITY.md.";

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
        let (head, results) = output::merge(parts)?;
        let target = results.first().map_or(0.995, |(m, _)| m.target);
        return write_sweep(out, &head, &results, &levels(target, *level)?, *maps);
    }
    let path = args
        .run
        .as_ref()
        .ok_or_else(|| anyhow!("raim availability: give --run FILE, or `merge PARTIAL...`"))?;
    let sweep = match &args.outages {
        Some(sys) => sweep::load_outages(path, sys)?,
        None => sweep::load(path)?,
    };
    if args.maps && args.shard.is_some() {
        return Err(anyhow!(
            "--maps draws a whole run: give it to `raim availability merge`, not with --shard"
        ));
    }
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(engine::STACK_BYTES);
    if let Some(t) = args.threads {
        pool = pool.num_threads(t);
    }
    let pool = pool.build()?;
    let head = SweepHead::of(&sweep);
    let t0 = Instant::now();
    let e = |e: raim_core::araim::MonitorError| anyhow!("{}: {e}", path.display());
    let mut user_epochs = 0;
    match &args.shard {
        Some(s) => {
            let (i, n) = output::parse_shard(s)?;
            let mut pieces = Vec::new();
            for (k, range) in output::shard_pieces(head.scenarios.len(), head.epochs, i, n) {
                let study = &sweep.scenarios[k].study;
                report(study, range.len(), &pool);
                user_epochs += study.users.len() * range.len();
                let users = pool
                    .install(|| engine::run_users(study, range.clone(), |p| PartialUser::from(&p)))
                    .map_err(e)?;
                pieces.push(Piece {
                    meta: Meta::of(study),
                    epoch_range: [range.start, range.end],
                    users,
                });
            }
            let part = Partial {
                format: PARTIAL_FORMAT.into(),
                head,
                shard: i,
                shards: n,
                pieces,
            };
            std::fs::create_dir_all(&args.out)?;
            let f = args
                .out
                .join(format!("{}.shard-{i}-of-{n}.json", part.head.name));
            std::fs::write(&f, serde_json::to_string(&part)?)?;
            eprintln!("wrote {}", f.display());
        }
        None => {
            let mut results = Vec::new();
            for sc in &sweep.scenarios {
                let study = &sc.study;
                let n_epochs = study.epochs_gps_s.len();
                report(study, n_epochs, &pool);
                user_epochs += study.users.len() * n_epochs;
                let users = pool
                    .install(|| engine::run_users(study, 0..n_epochs, engine::UserPartial::summary))
                    .map_err(e)?;
                results.push((Meta::of(study), users));
            }
            let target = sweep.scenarios[0].study.target;
            write_sweep(
                &args.out,
                &head,
                &results,
                &levels(target, args.level)?,
                args.maps,
            )?;
        }
    }
    let s = t0.elapsed().as_secs_f64();
    eprintln!(
        "{user_epochs} user-epochs in {s:.2} s: {:.0} user-epochs/s",
        user_epochs as f64 / s
    );
    Ok(())
}

fn report(study: &run::Study, epochs: usize, pool: &rayon::ThreadPool) {
    eprintln!(
        "{}: {} users x {} epochs ({} satellites) on {} threads",
        study.name,
        study.users.len(),
        epochs,
        study.sats.len(),
        pool.current_num_threads()
    );
}

/// Writes every scenario's summary and CSV (and maps), and a sweep's
/// coverage table `<name>.<tag>.csv` and `.md`: the same function for a
/// whole run and for `merge`, so that both give the same bytes.
fn write_sweep(
    dir: &std::path::Path,
    head: &SweepHead,
    results: &[(Meta, Vec<engine::UserSummary>)],
    lv: &[f64],
    maps: bool,
) -> Result<()> {
    for (meta, users) in results {
        let files = output::write_outputs(dir, meta, users, lv)?;
        let prefix = if results.len() > 1 {
            format!("{}: ", meta.name)
        } else {
            String::new()
        };
        for l in lv {
            eprintln!(
                "{prefix}coverage at {l}: {:.4}",
                output::coverage(meta, users, *l)
            );
        }
        for f in files {
            eprintln!("wrote {}", f.display());
        }
        if maps {
            draw_maps(dir, meta, users)?;
        }
    }
    if let Some(tag) = &head.table {
        let (csv, md) = output::sweep_tables(head, results, lv);
        for (ext, text) in [("csv", csv), ("md", md)] {
            let f = dir.join(format!("{}.{tag}.{ext}", head.name));
            std::fs::write(&f, text)?;
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}

fn draw_maps(dir: &std::path::Path, meta: &Meta, users: &[engine::UserSummary]) -> Result<()> {
    let cov = output::coverage(meta, users, meta.target);
    for f in crate::map::write_maps(dir, meta, users, cov)? {
        eprintln!("wrote {}", f.display());
    }
    Ok(())
}
