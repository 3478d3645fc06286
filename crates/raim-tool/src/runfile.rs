//! Run files: one TOML file describing a replay (docs/REPLAY.md, "Run
//! files"). Its sections are the headings of `raim replay --help`
//! (`[sources]`, `[models]`, `[faults]`, `[monitors]`, `[outputs]`,
//! `[plots]`) and its keys the options' long names, so the file and the
//! command line share one definition: the run file becomes options placed
//! before the command line's, and a later option overrides an earlier one
//! (repeatable options, such as `fault`, add up).

use std::ffi::OsString;
use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use clap::CommandFactory;

/// The section of a `--help` heading: its first word, lower case
/// ("Monitors: ARAIM (docs/ARAIM.md)" -> "monitors").
pub fn section_of(heading: &str) -> String {
    heading
        .split(|c: char| !c.is_alphanumeric())
        .next()
        .unwrap_or("")
        .to_lowercase()
}

/// The run file named by `--config FILE` or `--config=FILE` after the
/// `replay` subcommand, if any.
fn run_file(argv: &[OsString]) -> Option<(usize, OsString)> {
    if argv.get(1).and_then(|a| a.to_str()) != Some("replay") {
        return None;
    }
    for (k, a) in argv.iter().enumerate().skip(2) {
        let s = a.to_string_lossy();
        if s == "--" {
            break;
        }
        if s == "--config" {
            return argv.get(k + 1).map(|v| (k, v.clone()));
        }
        if let Some(v) = s.strip_prefix("--config=") {
            return Some((k, OsString::from(v)));
        }
    }
    None
}

/// `argv` with the run file's options inserted after `replay`; `argv`
/// unchanged when there is no run file (a `--config` without a value is
/// left to clap's usage error).
pub fn expand(argv: Vec<OsString>) -> Result<Vec<OsString>> {
    let Some((_, file)) = run_file(&argv) else {
        return Ok(argv);
    };
    let extra = options(Path::new(&file))?;
    let mut out = Vec::with_capacity(argv.len() + extra.len());
    out.extend(argv.iter().take(2).cloned());
    out.extend(extra.into_iter().map(OsString::from));
    out.extend(argv.iter().skip(2).cloned());
    Ok(out)
}

/// A run file's options, in file order, as command-line words.
pub fn options(path: &Path) -> Result<Vec<String>> {
    let shown = path.display();
    if path.is_dir() {
        bail!("run file {shown} is a directory, not a TOML file");
    }
    let text = std::fs::read_to_string(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => anyhow!("run file {shown}: no such file"),
        _ => anyhow!("run file {shown}: cannot read it: {e}"),
    })?;
    let table: toml::Table =
        toml::from_str(&text).with_context(|| format!("run file {shown} is not valid TOML"))?;
    let mut cli = crate::Cli::command();
    cli.build();
    let replay = cli
        .find_subcommand("replay")
        .ok_or_else(|| anyhow!("no replay subcommand"))?;
    let mut out = Vec::new();
    for (section, body) in &table {
        let toml::Value::Table(body) = body else {
            bail!(
                "run file {shown}: `{section}` must be a section ([sources], [models], [faults], \
                 [monitors], [outputs] or [plots]), not a value"
            );
        };
        for (key, value) in body {
            let long = key.replace('_', "-");
            let arg = replay
                .get_arguments()
                .find(|a| a.get_long() == Some(long.as_str()))
                .filter(|a| a.get_id() != "run_config")
                .ok_or_else(|| {
                    anyhow!(
                        "run file {shown}: [{section}] {key}: not an option of raim replay \
                         (see raim replay --help)"
                    )
                })?;
            let want = section_of(arg.get_help_heading().unwrap_or(""));
            if want != *section {
                bail!("run file {shown}: [{section}] {key}: this option belongs in [{want}]");
            }
            let flag = format!("--{long}");
            let takes_value = arg.get_num_args().is_none_or(|n| n.takes_values());
            let mut push = |v: &toml::Value| -> Result<()> {
                match v {
                    toml::Value::Boolean(b) if !takes_value => {
                        if *b {
                            out.push(flag.clone());
                        }
                    }
                    toml::Value::String(s) if takes_value => {
                        out.push(flag.clone());
                        out.push(s.clone());
                    }
                    toml::Value::Integer(i) if takes_value => {
                        out.push(flag.clone());
                        out.push(i.to_string());
                    }
                    toml::Value::Float(x) if takes_value => {
                        out.push(flag.clone());
                        out.push(x.to_string());
                    }
                    other => bail!(
                        "run file {shown}: [{section}] {key} = {other}: expected {}",
                        if takes_value {
                            "a string or a number"
                        } else {
                            "true or false"
                        }
                    ),
                }
                Ok(())
            };
            match value {
                toml::Value::Array(items) => {
                    for v in items {
                        push(v)?;
                    }
                }
                v => push(v)?,
            }
        }
    }
    Ok(out)
}
