//! `raim qemu`: replay a JSON-lines epoch file (docs/FORMATS.md) through the
//! firmware running under QEMU (mps2-an386) and print each epoch's decision
//! and the NMEA sentences the firmware wrote on its second UART.
//! The wire protocol is docs/PROTOCOL.md; the QEMU plumbing is `raim-qemu`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use raim_core::Epoch;
use raim_proto::WireResult;
use raim_qemu::{Processed, QemuSession};

use crate::config_args::ConfigArgs;
use crate::epoch_json::{self, Sats};
use crate::outcome::Tally;

#[derive(Debug, Clone, Args)]
pub struct QemuArgs {
    #[command(flatten)]
    pub config: ConfigArgs,
    /// JSON-lines epochs (docs/FORMATS.md).
    #[arg(long)]
    pub input: PathBuf,
    /// One JSON object per epoch: {seq, time_s, result | error, nmea}.
    #[arg(long)]
    pub json: bool,
    /// Firmware ELF to run (default: build firmware/ and use its release ELF).
    #[arg(long)]
    pub elf: Option<PathBuf>,
    /// Do not print the NMEA sentences (text mode).
    #[arg(long)]
    pub no_nmea: bool,
    /// Exit 0 even when some epochs were refused (they are still reported
    /// in the output and counted on stderr).
    #[arg(long)]
    pub keep_going: bool,
}

pub fn run(args: &QemuArgs) -> Result<Tally> {
    let cfg = args.config.config();
    cfg.validate()
        .map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    let elf = match &args.elf {
        Some(p) => p.clone(),
        None => raim_qemu::firmware_elf()?,
    };
    let mut fw = QemuSession::start(&elf)?;
    fw.configure(&cfg)?;
    let file = std::fs::File::open(&args.input)
        .with_context(|| format!("opening {}", args.input.display()))?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut tally = Tally::default();
    for line in epoch_json::lines(std::io::BufReader::new(file)) {
        let line = line.with_context(|| format!("reading {}", args.input.display()))?;
        let number = line.number;
        let (e, sats) = match line.parsed {
            Ok(p) => p,
            Err(r) => {
                // Refused before the firmware: answered here, counted.
                let detail = r.to_string();
                tally.refuse(|| format!("line {number}: {detail}"));
                if args.json {
                    let v = serde_json::json!({
                        "line": number, "time_s": line.time_s, "error": r.name(), "detail": detail,
                    });
                    writeln!(out, "{v}")?;
                } else {
                    let t = line.time_s.map_or("-".into(), |t| format!("{t:.1}"));
                    writeln!(
                        out,
                        "t={t:>10}s seq=-     ERROR       line {number}: {detail}"
                    )?;
                }
                continue;
            }
        };
        let epoch = match &sats {
            Sats::Ranges(v) => Epoch::ranges(e.time_s, v, e.apriori_m),
            Sats::Linear(v) => Epoch::linear(e.time_s, v),
        };
        let p = fw.process(&epoch)?;
        match &p.outcome {
            Ok(_) => tally.answered(),
            Err(err) => tally.refuse(|| format!("line {number}: {err}")),
        }
        if args.json {
            writeln!(out, "{}", json_line(e.time_s, &p)?)?;
        } else {
            writeln!(out, "{}", text_line(e.time_s, &p))?;
            if !args.no_nmea {
                for s in &p.nmea {
                    writeln!(out, "    {s}")?;
                }
            }
        }
    }
    if tally.epochs == 0 {
        let _ = writeln!(
            std::io::stderr(),
            "raim qemu: no epochs in {} (empty input; format: docs/FORMATS.md)",
            args.input.display()
        );
    }
    let st = fw.status()?;
    if !args.json {
        writeln!(
            out,
            "firmware: {} frames, {} epochs, {} errors, protocol {}, capacity {}",
            st.frames, st.epochs, st.errors, st.protocol_version, st.capacity
        )?;
    }
    Ok(tally)
}

fn json_line(time_s: f64, p: &Processed) -> Result<String> {
    let v = match &p.outcome {
        Ok(r) => serde_json::json!({
            "seq": p.seq, "time_s": time_s, "decision": decision(r),
            "result": r, "nmea": p.nmea,
        }),
        Err(e) => serde_json::json!({
            "seq": p.seq, "time_s": time_s, "error": e.to_string(), "detail": e,
        }),
    };
    Ok(serde_json::to_string(&v)?)
}

fn decision(r: &WireResult) -> &'static str {
    match r.decision {
        raim_core::Decision::Ok => "ok",
        raim_core::Decision::Alarm => "alarm",
        raim_core::Decision::Excluded => "excluded",
        raim_core::Decision::Unavailable => "unavailable",
    }
}

fn text_line(time_s: f64, p: &Processed) -> String {
    match &p.outcome {
        Ok(r) => {
            let excluded: Vec<String> = r.exclusions.iter().map(|x| x.id.to_string()).collect();
            let mut s = format!(
                "t={time_s:>10.1}s seq={:<5} {:<11} D2={:>9.3} T2={:>7.3} dof={} HPL={:>8.1} m VPL={:>8.1} m",
                p.seq,
                decision(r).to_uppercase(),
                r.initial_test.statistic,
                r.initial_test.threshold,
                r.initial_test.dof,
                r.hpl_m,
                r.vpl_m
            );
            if !excluded.is_empty() {
                s.push_str(&format!(" excluded={}", excluded.join(",")));
            }
            if let Some(c) = &r.alarm_cause {
                s.push_str(&format!(" cause={}", crate::replay::record::cause_name(*c)));
            }
            s
        }
        Err(e) => format!("t={time_s:>10.1}s seq={:<5} ERROR       {e}", p.seq),
    }
}
