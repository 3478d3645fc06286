//! Reading the replay's RINEX files with checks the reader does not make:
//! a gzip file that is truncated or corrupt is an error that says so and
//! where (the `rinex` crate only says "i/o: input error"), and an
//! observation file that ends inside an epoch gets a warning on stderr
//! (the reader takes the partial epoch as if it were complete).

use std::io::{Read, Write};
use std::path::Path;

use anyhow::{bail, Context, Result};
use raim_gnss::{NavData, ObsData};

/// What a replay input file should be, for the messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// RINEX observations (`--obs`).
    Observation,
    /// RINEX broadcast navigation (`--nav`).
    Navigation,
}

impl Kind {
    fn what(self) -> &'static str {
        match self {
            Kind::Observation => "a RINEX observation file (--obs)",
            Kind::Navigation => "a RINEX navigation file (--nav)",
        }
    }
}

/// The file's bytes, decompressed when it ends in `.gz` (the stream
/// checked to its end), after the checks that name the file and say what
/// is wrong with it: no such file, a directory, empty, not RINEX, or the
/// other kind of RINEX file.
fn text(path: &Path, kind: Kind) -> Result<Vec<u8>> {
    let shown = path.display();
    let want = kind.what();
    match std::fs::metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            bail!("{shown}: no such file (expected {want})")
        }
        Err(e) => bail!("{shown}: cannot read it: {e}"),
        Ok(m) if m.is_dir() => bail!("{shown} is a directory, not {want}"),
        Ok(_) => {}
    }
    let raw = std::fs::read(path).map_err(|e| anyhow::anyhow!("{shown}: cannot read it: {e}"))?;
    if raw.is_empty() {
        bail!("{shown} is empty (0 bytes): expected {want}");
    }
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    let out = if gz {
        let mut out = Vec::new();
        let mut dec = flate2::read::MultiGzDecoder::new(raw.as_slice());
        if let Err(e) = dec.read_to_end(&mut out) {
            let lines = out.iter().filter(|&&b| b == b'\n').count();
            let what = if e.kind() == std::io::ErrorKind::UnexpectedEof {
                "truncated (the gzip stream ends early)"
            } else {
                "corrupt"
            };
            bail!(
                "{}: file is {what}: {e}; {} compressed bytes, decompression stopped after {} bytes (line {})",
                path.display(),
                raw.len(),
                out.len(),
                lines + 1
            );
        }
        if out.is_empty() {
            bail!("{shown} decompresses to nothing: expected {want}");
        }
        out
    } else {
        raw
    };
    check_header(&out, kind).map_err(|why| anyhow::anyhow!("{shown} is not {want}: {why}"))?;
    Ok(out)
}

/// The first line of a RINEX file is labelled `RINEX VERSION / TYPE` in
/// columns 61-80, with the file type in column 21 (`O` observations; `N`,
/// `G`, `H`, `L`, ... navigation).
fn check_header(bytes: &[u8], kind: Kind) -> std::result::Result<(), String> {
    let first = bytes.split(|&b| b == b'\n').next().unwrap_or(&[]);
    let first = String::from_utf8_lossy(first);
    let label = first.get(60..).unwrap_or("").trim_end();
    if label != "RINEX VERSION / TYPE" {
        let shown: String = first.trim_end().chars().take(60).collect();
        return Err(format!(
            "its first line does not end in the label 'RINEX VERSION / TYPE' (it reads \"{shown}\")"
        ));
    }
    let t = first.get(20..21).unwrap_or(" ");
    match (kind, t) {
        (Kind::Observation, "O") => Ok(()),
        (Kind::Observation, t) => Err(format!(
            "its header says file type '{t}' (navigation or other data); observations are type 'O'"
        )),
        (Kind::Navigation, "O") => Err(
            "its header says file type 'O': an observation file, given where the navigation file goes"
                .into(),
        ),
        (Kind::Navigation, _) => Ok(()),
    }
}

/// Load an observation file; warn on stderr about a partial last epoch.
pub fn load_obs(path: &Path) -> Result<ObsData> {
    let text = text(path, Kind::Observation)?;
    let obs = ObsData::load(path).with_context(|| format!("reading {}", path.display()))?;
    if let Some(w) = partial_last_epoch(&text) {
        let _ = writeln!(
            std::io::stderr(),
            "raim: warning: {}: {w}; its data may be partial",
            path.display()
        );
    }
    Ok(obs)
}

/// Load a navigation file (gzip checked to its end first).
pub fn load_nav(path: &Path) -> Result<NavData> {
    text(path, Kind::Navigation)?;
    NavData::load(path).with_context(|| format!("reading {}", path.display()))
}

/// Lines an epoch header announces after itself, or None when the line is
/// not an epoch header of this version (then the file is not checked
/// further: no warning rather than a wrong one).
fn following_lines(line: &str, version: u8, n_obs_types: usize) -> Option<usize> {
    let field = |a: usize, b: usize| line.get(a..b).map(str::trim);
    let (flag, n) = if version >= 3 {
        if !line.starts_with('>') {
            return None;
        }
        (field(31, 32)?, field(32, 35)?)
    } else {
        (field(28, 29)?, field(29, 32)?)
    };
    let flag: u8 = flag.parse().ok()?;
    let n: usize = n.parse().ok()?;
    Some(match flag {
        // Observations: one record per satellite; RINEX 2 lists the
        // satellites 12 per line and wraps each record at 5 values.
        0 | 1 | 6 if version >= 3 => n,
        0 | 1 | 6 => n.saturating_sub(1) / 12 + n * n_obs_types.div_ceil(5).max(1),
        // Events: n header records follow.
        _ => n,
    })
}

/// A description of the incomplete last epoch, if the file ends inside one.
fn partial_last_epoch(bytes: &[u8]) -> Option<String> {
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines();
    let mut version = 0u8;
    let mut n_obs_types = 0usize;
    for l in lines.by_ref() {
        let label = l.get(60..).unwrap_or("").trim_end();
        match label {
            "RINEX VERSION / TYPE" => {
                version = l.get(..9)?.trim().parse::<f64>().ok()? as u8;
            }
            "# / TYPES OF OBSERV" if n_obs_types == 0 => {
                n_obs_types = l.get(..6)?.trim().parse().ok()?;
            }
            "END OF HEADER" => break,
            _ => {}
        }
    }
    if version == 0 {
        return None;
    }
    let body: Vec<&str> = lines.collect();
    let mut i = 0;
    while let Some(header) = body.get(i) {
        if header.trim().is_empty() {
            i += 1;
            continue;
        }
        let need = following_lines(header, version, n_obs_types)?;
        let have = body.len() - i - 1;
        if have < need {
            return Some(format!(
                "the file ends inside its last epoch '{}': {have} of {need} record lines present (file cut short?)",
                header.trim()
            ));
        }
        i += need + 1;
    }
    if !bytes.is_empty() && bytes.last() != Some(&b'\n') {
        return Some("the last line has no end of line (file cut short?)".into());
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data");

    /// The complete real files have no partial epoch (RINEX 2 with event
    /// records, RINEX 3 gzip), so the check gives no false warning.
    #[test]
    fn complete_files_pass() {
        for f in [
            "07590920.05o",
            "ESBC00DNK_R_20201770000_03H_30S_MO.rnx.gz",
            "GEOP092I.24o.gz",
        ] {
            let p = Path::new(DATA).join(f);
            let t = text(&p, Kind::Observation).unwrap();
            assert_eq!(partial_last_epoch(&t), None, "{f}");
        }
    }

    /// Cut after every line of the last complete epoch of 0759 (8
    /// satellites, 4 types: one line each, plus the header): each cut inside
    /// the epoch is found, with the count of lines present.
    #[test]
    fn cuts_inside_an_epoch_are_found() {
        let full = std::fs::read(Path::new(DATA).join("07590920.05o")).unwrap();
        let text = String::from_utf8(full).unwrap();
        let start = text.find(" 05  4  2  0  0  0.0000000  0  8").unwrap();
        let body = &text[start..];
        let ends: Vec<usize> = body
            .match_indices('\n')
            .map(|(k, _)| start + k + 1)
            .collect();
        // Header line + 8 record lines.
        for have in 0..8 {
            let cut = &text[..ends[have]];
            let w = partial_last_epoch(cut.as_bytes()).unwrap();
            assert!(w.contains(&format!("{have} of 8 record lines")), "{w}");
        }
        assert_eq!(partial_last_epoch(&text.as_bytes()[..ends[8]]), None);
        // Cut in the middle of the last record line: all lines are there,
        // the last one without its end of line.
        let w = partial_last_epoch(&text.as_bytes()[..ends[8] - 10]).unwrap();
        assert!(w.contains("no end of line"), "{w}");
    }
}
