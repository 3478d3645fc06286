//! A guard in front of the `rinex` crate for corrupt files.
//!
//! The `rinex` crate (0.24) panics on some corrupt records instead of
//! returning an error: a RINEX 2 observation file whose later epoch has
//! month 13 aborts the host tool (docs/RINEX_GUARD.md has the cause and the
//! upstream note). Two layers keep a corrupt file from crashing the host:
//! - [`check_observation_epochs`] reads every epoch record of an
//!   observation file (RINEX 2 by the record structure, RINEX 3/4 by the
//!   `>` lines) and refuses a date or time field out of its calendar range
//!   with [`GnssError::BadEpoch`] naming the line, before the crate sees it;
//! - [`no_panic`] turns any other panic inside the crate into
//!   [`GnssError::Parse`], so that the tool reports it and goes on.

use std::io::Read;
use std::path::Path;

use crate::error::GnssError;

/// Run `f` (a call into the `rinex` crate) and turn a panic into a typed
/// error for `path`.
pub fn no_panic<T>(path: &Path, f: impl FnOnce() -> Result<T, GnssError>) -> Result<T, GnssError> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(GnssError::Parse {
                path: path.to_path_buf(),
                detail: format!("the RINEX parser panicked: {msg}"),
            })
        }
    }
}

/// The file's text (gunzipped by its `.gz` suffix).
fn read_text(path: &Path) -> Result<String, GnssError> {
    let io = |e: std::io::Error| GnssError::Parse {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let bytes = std::fs::read(path).map_err(io)?;
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    if gz {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(&bytes[..])
            .read_to_end(&mut out)
            .map_err(io)?;
        Ok(String::from_utf8_lossy(&out).into_owned())
    } else {
        Ok(String::from_utf8_lossy(&bytes).into_owned())
    }
}

/// Check every epoch record of an observation file; other files pass.
pub fn check_observation_epochs(path: &Path) -> Result<(), GnssError> {
    let text = read_text(path)?;
    check_observation_text(path, &text)
}

/// [`check_observation_epochs`] on the file's text.
pub fn check_observation_text(path: &Path, text: &str) -> Result<(), GnssError> {
    let mut lines = text.lines().enumerate();
    let Some((_, first)) = lines.next() else {
        return Ok(());
    };
    let version: f64 = first.get(0..9).unwrap_or("").trim().parse().unwrap_or(0.0);
    let is_obs = first.get(20..21) == Some("O");
    if !is_obs {
        return Ok(());
    }
    let mut n_types = 0usize;
    for (_, l) in lines.by_ref() {
        let label = l.get(60..).unwrap_or("").trim();
        if label == "# / TYPES OF OBSERV" && n_types == 0 {
            n_types = l.get(0..6).unwrap_or("").trim().parse().unwrap_or(0);
        }
        if label == "END OF HEADER" {
            break;
        }
    }
    let bad = |line: usize, detail: String| GnssError::BadEpoch {
        path: path.to_path_buf(),
        line: line + 1,
        detail,
    };
    if version >= 3.0 {
        for (i, l) in lines {
            if let Some(rest) = l.strip_prefix('>') {
                check_date(rest, true).map_err(|d| bad(i, d))?;
            }
        }
        return Ok(());
    }
    // RINEX 2: an epoch record, its continuation lines (12 satellites per
    // line), then per satellite ceil(n_types / 5) data lines; an event
    // record (flag 2-5) is followed by `n` header lines.
    let lines_per_sat = n_types.div_ceil(5).max(1);
    let mut it = lines;
    while let Some((i, l)) = it.next() {
        if l.trim().is_empty() {
            continue;
        }
        let flag: u32 = l
            .get(28..29)
            .unwrap_or("0")
            .trim()
            .parse()
            .map_err(|_| bad(i, format!("not an epoch record: {l:?}")))?;
        let n: usize = l
            .get(29..32)
            .unwrap_or("")
            .trim()
            .parse()
            .map_err(|_| bad(i, format!("not an epoch record: {l:?}")))?;
        let date = l.get(0..26).unwrap_or("");
        let skip = if (2..=5).contains(&flag) {
            if !date.trim().is_empty() {
                check_date(date, false).map_err(|d| bad(i, d))?;
            }
            n
        } else {
            check_date(date, false).map_err(|d| bad(i, d))?;
            n.saturating_sub(1) / 12 + n * lines_per_sat
        };
        for _ in 0..skip {
            it.next();
        }
    }
    Ok(())
}

/// Year, month, day, hour, minute (integers) and second of an epoch record.
fn check_date(fields: &str, four_digit_year: bool) -> Result<(), String> {
    let t: Vec<&str> = fields.split_whitespace().take(6).collect();
    let [y, mo, d, h, mi, s] = t[..] else {
        return Err(format!("an epoch needs 6 date/time fields: {fields:?}"));
    };
    let int = |name: &str, v: &str, lo: i64, hi: i64| -> Result<i64, String> {
        let x: i64 = v
            .parse()
            .map_err(|_| format!("{name} {v:?} is not an integer"))?;
        if (lo..=hi).contains(&x) {
            Ok(x)
        } else {
            Err(format!("{name} {x} outside {lo}..={hi}"))
        }
    };
    if four_digit_year {
        int("year", y, 1900, 2200)?;
    } else {
        int("year", y, 0, 99)?;
    }
    int("month", mo, 1, 12)?;
    int("day", d, 1, 31)?;
    int("hour", h, 0, 23)?;
    int("minute", mi, 0, 59)?;
    let sec: f64 = s
        .parse()
        .map_err(|_| format!("second {s:?} is not a number"))?;
    if !(0.0..61.0).contains(&sec) {
        return Err(format!("second {sec} outside [0, 61)"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_in_and_out_of_range() {
        assert_eq!(check_date(" 05  4  2  0  0  0.0000000", false), Ok(()));
        assert_eq!(check_date(" 2020 12 31 23 59 60.5000000", true), Ok(()));
        for (bad, what) in [
            (" 05 13  2  0  0  0.0", "month 13"),
            (" 05  0  2  0  0  0.0", "month 0"),
            (" 05  4 32  0  0  0.0", "day 32"),
            (" 05  4  2 24  0  0.0", "hour 24"),
            (" 05  4  2  0 60  0.0", "minute 60"),
            (" 05  4  2  0  0 61.0", "second 61"),
            (" 05  4  2  0  0  NaN", "second NaN"),
            (" 05 4.5  2  0  0  0.0", "month \"4.5\""),
            (" 05  4", "6 date/time fields"),
        ] {
            let e = check_date(bad, false).unwrap_err();
            assert!(e.contains(what), "{bad}: {e}");
        }
    }

    #[test]
    fn rinex3_epoch_lines_are_checked() {
        let text =
            "     3.04           OBSERVATION DATA    M                   RINEX VERSION / TYPE\n\
                    \x20                                                           END OF HEADER\n\
                    > 2020 06 25 00 00  0.0000000  0  1\n\
                    G01  20000000.000\n\
                    > 2020 13 25 00 00 30.0000000  0  1\n";
        let e = check_observation_text(Path::new("x.rnx"), text).unwrap_err();
        assert!(matches!(e, GnssError::BadEpoch { line: 5, .. }), "{e}");
    }

    #[test]
    fn a_panic_becomes_a_parse_error() {
        let r: Result<(), GnssError> = no_panic(Path::new("f"), || panic!("boom"));
        assert!(matches!(r, Err(GnssError::Parse { ref detail, .. }) if detail.contains("boom")));
    }
}
