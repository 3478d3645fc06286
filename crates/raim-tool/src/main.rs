//! `raim`: host tools for the raim-core integrity monitor.

mod araim_cmd;
mod arl;
mod campaign;
mod config_args;
mod epoch_json;
mod outcome;
mod pci;
mod pf_table;
mod qemu;
mod replay;
mod result_json;
mod snapshot;

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use raim_core::stats::dist;

use config_args::ConfigArgs;
use outcome::Tally;

/// `println!` that returns the write error (a closed pipe: `raim ... | head`)
/// instead of panicking, so the caller can end quietly.
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout(), $($t)*)
    }};
}

/// `print!` that returns the write error; see [`outln!`].
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout(), $($t)*)
    }};
}

#[derive(Parser)]
#[command(
    name = "raim",
    version,
    about = "GNSS integrity monitor (RAIM) host tools",
    after_help = outcome::HELP,
    next_line_help = true
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
        /// Exit 0 even when some epochs were refused (they are still
        /// reported in the output and counted on stderr).
        #[arg(long)]
        keep_going: bool,
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
    /// The particle-filter RAIM's threshold table from an allocated false-alarm probability (docs/PF.md "Thresholds").
    PfTable(pf_table::PfTableArgs),
    /// Replay RINEX data through the monitor with seeded faults (docs/REPLAY.md).
    Replay(Box<replay::ReplayArgs>),
    /// Replay a JSON-lines epoch file through the firmware under QEMU; print decisions and NMEA (docs/PROTOCOL.md).
    Qemu(qemu::QemuArgs),
    /// The chi-square detection threshold; with --pmd, lambda and pbias too.
    Threshold {
        /// Probability of false alarm per sample, e.g. 3.3333e-7.
        #[arg(long)]
        pfa: f64,
        /// Degrees of freedom of the chi-square test (satellites - unknowns).
        #[arg(long)]
        dof: u32,
        /// Probability of missed detection: also print the non-centrality
        /// lambda and pbias = sqrt(lambda) (SPEC §6).
        #[arg(long)]
        pmd: Option<f64>,
        /// Print one JSON object instead of text (docs/FORMATS.md).
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // --help and --version print to stdout and succeed; usage
            // errors print to stderr and give 2.
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() {
                outcome::EXIT_USAGE
            } else {
                outcome::EXIT_OK
            });
        }
    };
    let keep_going = match &cli.command {
        Command::Snapshot { keep_going, .. } => *keep_going,
        Command::Replay(a) => a.keep_going,
        Command::Qemu(a) => a.keep_going,
        _ => false,
    };
    match run(cli.command) {
        Ok(tally) => tally.finish(keep_going),
        Err(e) if outcome::is_broken_pipe(&e) => ExitCode::from(outcome::EXIT_OK),
        Err(e) => outcome::fail(&e),
    }
}

fn run(command: Command) -> Result<Tally> {
    let none = |r: Result<()>| r.map(|()| Tally::default());
    match command {
        Command::Snapshot {
            config,
            json,
            input,
            keep_going: _,
        } => snapshot::run(&config, json, input.as_deref()),
        Command::Threshold {
            pfa,
            dof,
            pmd,
            json,
        } => none(threshold(pfa, dof, pmd, json)),
        Command::Araim(args) => none(araim_cmd::run(&args)),
        Command::Qemu(args) => qemu::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Pci(args) => none(pci::run(&args)),
        Command::Arl(args) => none(arl::run(&args)),
        Command::PfTable(args) => none(pf_table::run(&args)),
        Command::Campaign { which } => none(campaign::run(&which)),
    }
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
        crate::outln!("{v}")?;
    } else {
        crate::outln!("pfa={pfa:e} dof={dof} T^2={t2:.6} T={:.6}", t2.sqrt())?;
        if let (Some(pmd), Some(l)) = (pmd, lambda) {
            crate::outln!("pmd={pmd:e} lambda={l:.6} pbias={:.6}", l.sqrt())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Every subcommand, depth first, with its path ("raim campaign false-alarm").
    fn all_commands() -> Vec<(String, clap::Command)> {
        fn walk(path: String, c: &clap::Command, out: &mut Vec<(String, clap::Command)>) {
            out.push((path.clone(), c.clone()));
            for s in c.get_subcommands() {
                if s.get_name() != "help" {
                    walk(format!("{path} {}", s.get_name()), s, out);
                }
            }
        }
        let mut out = Vec::new();
        walk("raim".into(), &Cli::command(), &mut out);
        out
    }

    #[test]
    fn clap_definition_is_consistent() {
        Cli::command().debug_assert();
    }

    /// Issue 16: every option of every subcommand has a description, and
    /// the descriptions are one paragraph (so `-h` and `--help` give the
    /// same one layout everywhere).
    #[test]
    fn every_option_is_described_in_one_layout() {
        let mut missing = Vec::new();
        for (path, c) in all_commands() {
            assert!(c.get_about().is_some() || path == "raim", "{path}");
            for a in c.get_arguments() {
                let id = a.get_id().as_str();
                if id == "help" || id == "version" {
                    continue;
                }
                match a.get_help() {
                    Some(h) if !h.to_string().trim().is_empty() => {}
                    _ => missing.push(format!("{path} --{id}")),
                }
                assert!(
                    a.get_long_help().is_none(),
                    "{path} --{id}: multi-paragraph help"
                );
                for v in a.get_possible_values() {
                    assert!(
                        v.get_help().is_none(),
                        "{path} --{id}: value docs switch to the long layout"
                    );
                }
            }
        }
        assert!(missing.is_empty(), "options without help: {missing:?}");
    }

    /// Defaults print as users write them: no long runs of zeros
    /// (3.3333e-7, not 0.00000033333); and the string defaults equal the
    /// core's constants they stand for.
    #[test]
    fn defaults_print_as_users_write_them() {
        for (path, c) in all_commands() {
            for a in c.get_arguments() {
                for d in a.get_default_values() {
                    let d = d.to_string_lossy();
                    assert!(!d.contains("0.000"), "{path} --{}: {d}", a.get_id());
                    assert!(!d.contains(' '), "{path} --{}: {d}", a.get_id());
                }
            }
        }
        let min_s_ii: f64 = "1e-4".parse().unwrap();
        assert_eq!(min_s_ii, raim_core::config::DEFAULT_MIN_S_II);
        let cli = Cli::try_parse_from(["raim", "snapshot"]).unwrap();
        let Command::Snapshot { config, .. } = cli.command else {
            panic!()
        };
        assert_eq!(config.pfa, 3.3333e-7);
        assert_eq!(config.pmd, 1e-3);
        let cli = Cli::try_parse_from(["raim", "campaign", "false-alarm"]).unwrap();
        let Command::Campaign {
            which: campaign::CampaignCmd::FalseAlarm(fa),
        } = cli.command
        else {
            panic!()
        };
        assert_eq!(fa.pfa, vec![1e-3, 1e-5]);
    }
}
