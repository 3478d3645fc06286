//! `raim`: host tools for the raim-core integrity monitor.

mod araim_cmd;
mod arl;
mod campaign;
mod config_args;
mod epoch_json;
mod pci;
mod qemu;
mod replay;
mod result_json;

use std::io::{BufRead, Write};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use raim_core::stats::dist;
use raim_core::{Epoch, Raim};

use config_args::ConfigArgs;
use epoch_json::{EpochJson, Sats};

/// Capacity of the host engine: the documented default.
const N: usize = raim_core::DEFAULT_CAPACITY;

#[derive(Parser)]
#[command(
    name = "raim",
    version,
    about = "GNSS integrity monitor (RAIM) host tools"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Read epochs as JSON lines on stdin (docs/FORMATS.md); print one result per epoch.
    Snapshot {
        #[command(flatten)]
        config: ConfigArgs,
        /// Print one JSON object per line instead of text.
        #[arg(long)]
        json: bool,
        /// Read from this file instead of stdin.
        #[arg(long)]
        input: Option<std::path::PathBuf>,
    },
    /// ARAIM (docs/ARAIM.md) on ARAIM epochs as JSON lines (docs/FORMATS.md).
    Araim(araim_cmd::AraimArgs),
    /// Seeded Monte Carlo validation campaigns (false-alarm rate; single-fault identification).
    Campaign {
        #[command(subcommand)]
        which: campaign::CampaignCmd,
    },
    /// Probability of correct identification per satellite, MLE vs L-RAIM (exact and Monte Carlo), P_D, MDB.
    Pci(pci::PciArgs),
    /// MCUSUM average run lengths (SPEC §7.2): ARL0(h) / h(ARL0) by the integral equation, ARL1 by simulation, the device table.
    Arl(arl::ArlArgs),
    /// Replay RINEX data through the monitor with seeded faults (docs/REPLAY.md).
    Replay(Box<replay::ReplayArgs>),
    /// Replay a JSON-lines epoch file through the firmware under QEMU; print decisions and NMEA (docs/PROTOCOL.md).
    Qemu(qemu::QemuArgs),
    /// The chi-square detection threshold; with --pmd, lambda and pbias too.
    Threshold {
        #[arg(long)]
        pfa: f64,
        #[arg(long)]
        dof: u32,
        #[arg(long)]
        pmd: Option<f64>,
        #[arg(long)]
        json: bool,
    },
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Snapshot {
            config,
            json,
            input,
        } => snapshot(&config, json, input),
        Command::Threshold {
            pfa,
            dof,
            pmd,
            json,
        } => threshold(pfa, dof, pmd, json),
        Command::Araim(args) => araim_cmd::run(&args),
        Command::Qemu(args) => qemu::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Pci(args) => pci::run(&args),
        Command::Arl(args) => arl::run(&args),
        Command::Campaign { which } => campaign::run(&which),
    }
}

fn snapshot(args: &ConfigArgs, json: bool, input: Option<std::path::PathBuf>) -> Result<()> {
    let cfg = args.config();
    cfg.validate()
        .map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    let reader: Box<dyn BufRead> = match &input {
        Some(p) => Box::new(std::io::BufReader::new(
            std::fs::File::open(p).with_context(|| format!("opening {}", p.display()))?,
        )),
        None => Box::new(std::io::stdin().lock()),
    };
    let mut raim = Raim::<N>::new();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    for (lineno, line) in reader.lines().enumerate() {
        let line = line?;
        if line.trim().is_empty() || line.trim_start().starts_with('#') {
            continue;
        }
        let epoch: EpochJson = serde_json::from_str(&line)
            .with_context(|| format!("line {}: not an epoch", lineno + 1))?;
        let sats = epoch
            .to_sats()
            .with_context(|| format!("line {}", lineno + 1))?;
        let e = match &sats {
            Sats::Ranges(v) => Epoch::ranges(epoch.time_s, v, epoch.apriori_m),
            Sats::Linear(v) => Epoch::linear(epoch.time_s, v),
        };
        match raim.process(&cfg, &e) {
            Ok(r) if json => writeln!(
                out,
                "{}",
                serde_json::to_string(&result_json::result_out(&r))?
            )?,
            Ok(r) => writeln!(out, "{}", result_json::text_line(&r))?,
            Err(err) if json => writeln!(
                out,
                "{}",
                serde_json::to_string(&result_json::error_out(epoch.time_s, &err))?
            )?,
            Err(err) => writeln!(out, "t={:>10.1}s ERROR       {err}", epoch.time_s)?,
        }
    }
    Ok(())
}

fn threshold(pfa: f64, dof: u32, pmd: Option<f64>, json: bool) -> Result<()> {
    let t2 = dist::chi2_quantile_upper(pfa, dof).map_err(|e| anyhow::anyhow!("{e}"))?;
    let lambda = match pmd {
        Some(pmd) => Some(dist::ncx2_lambda(pfa, pmd, dof).map_err(|e| anyhow::anyhow!("{e}"))?),
        None => None,
    };
    if json {
        let v = serde_json::json!({
            "pfa": pfa, "dof": dof, "threshold_chi2": t2, "threshold": t2.sqrt(),
            "pmd": pmd, "lambda": lambda, "pbias": lambda.map(f64::sqrt),
        });
        println!("{v}");
    } else {
        println!("pfa={pfa:e} dof={dof} T^2={t2:.6} T={:.6}", t2.sqrt());
        if let (Some(pmd), Some(l)) = (pmd, lambda) {
            println!("pmd={pmd:e} lambda={l:.6} pbias={:.6}", l.sqrt());
        }
    }
    Ok(())
}
