//! `raim snapshot`: JSON-lines epochs (docs/FORMATS.md) through the core,
//! one answer per epoch: a result, or the typed reason it was refused.
//! A refused epoch does not stop the run; it is counted for the exit code
//! (crate::outcome).

use std::io::{BufRead, Write};
use std::path::Path;

use anyhow::{Context, Result};
use raim_core::{Epoch, Raim};

use crate::config_args::ConfigArgs;
use crate::epoch_json::{self, Sats};
use crate::outcome::Tally;
use crate::result_json::{self, ErrorOut};

/// Capacity of the host engine: the documented default.
const N: usize = raim_core::DEFAULT_CAPACITY;

pub fn run(args: &ConfigArgs, json: bool, input: Option<&Path>) -> Result<Tally> {
    let cfg = args.config();
    cfg.validate()
        .map_err(|e| anyhow::anyhow!("configuration: {e}"))?;
    let (reader, source): (Box<dyn BufRead>, String) = match input {
        Some(p) => (
            Box::new(std::io::BufReader::new(
                std::fs::File::open(p).with_context(|| format!("opening {}", p.display()))?,
            )),
            p.display().to_string(),
        ),
        None => (Box::new(std::io::stdin().lock()), "stdin".into()),
    };
    let mut raim = Raim::<N>::new();
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut tally = Tally::default();
    for line in epoch_json::lines(reader) {
        let line = line.with_context(|| format!("reading {source}"))?;
        let number = line.number;
        let refused = |out: &mut dyn Write, e: ErrorOut| -> Result<()> {
            if json {
                writeln!(out, "{}", serde_json::to_string(&e)?)?;
            } else {
                let t = e.time_s.map_or("-".into(), |t| format!("{t:.1}"));
                writeln!(out, "t={t:>10}s ERROR       line {number}: {}", e.detail)?;
            }
            Ok(())
        };
        let (epoch, sats) = match line.parsed {
            Ok(p) => p,
            Err(r) => {
                let detail = r.to_string();
                tally.refuse(|| format!("line {number}: {detail}"));
                refused(
                    &mut out,
                    ErrorOut {
                        line: Some(number),
                        time_s: line.time_s,
                        error: r.name(),
                        detail,
                    },
                )?;
                continue;
            }
        };
        let e = match &sats {
            Sats::Ranges(v) => Epoch::ranges(epoch.time_s, v, epoch.apriori_m),
            Sats::Linear(v) => Epoch::linear(epoch.time_s, v),
        };
        match raim.process(&cfg, &e) {
            Ok(r) => {
                tally.answered();
                if json {
                    let v = serde_json::to_string(&result_json::result_out(&r))?;
                    writeln!(out, "{v}")?;
                } else {
                    writeln!(out, "{}", result_json::text_line(&r))?;
                }
            }
            Err(err) => {
                tally.refuse(|| format!("line {number}: {err}"));
                refused(
                    &mut out,
                    result_json::error_out(Some(number), epoch.time_s, &err),
                )?;
            }
        }
    }
    out.flush()?;
    if tally.epochs == 0 {
        let _ = writeln!(
            std::io::stderr(),
            "raim snapshot: no epochs in {source} (empty input; format: docs/FORMATS.md)"
        );
    }
    Ok(tally)
}
