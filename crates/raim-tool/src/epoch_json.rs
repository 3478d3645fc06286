//! The JSON-lines epoch format of `raim snapshot` (docs/FORMATS.md): one
//! object per line, with satellites in either the pseudorange form or the
//! linearised (az/el + residual) form.

use std::io::BufRead;

use anyhow::{bail, Context, Result};
use raim_core::{LinearObservation, RaimError, RangeObservation, SatId, System};
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EpochJson {
    pub time_s: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub apriori_m: Option<[f64; 3]>,
    pub sats: Vec<SatJson>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SatJson {
    /// RINEX system letter: G, E, C, R, J.
    pub sys: String,
    pub prn: u8,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma_m: Option<f64>,
    // Pseudorange form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pseudorange_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_m: Option<[f64; 3]>,
    // Linearised form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub az_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub el_deg: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residual_m: Option<f64>,
}

/// The epoch's satellites, converted to one of the core's input forms.
pub enum Sats {
    Ranges(Vec<RangeObservation>),
    Linear(Vec<LinearObservation>),
}

fn sat_id(s: &SatJson) -> Result<SatId> {
    let mut chars = s.sys.chars();
    let (Some(c), None) = (chars.next(), chars.next()) else {
        bail!("sys must be one letter, got {:?}", s.sys);
    };
    let system = System::from_letter(c).with_context(|| format!("unknown system letter {c:?}"))?;
    Ok(SatId::new(system, s.prn))
}

/// Why a line of the input did not reach the engine: every refused line is
/// still answered (one output per epoch) and counted for the exit code.
#[derive(Debug, Clone)]
pub enum Refusal {
    /// The line is not an epoch of docs/FORMATS.md (bad JSON, missing
    /// fields, unknown system, cut short by the end of the input).
    Unreadable(String),
    /// A value the core's input checks reject (`raim_core::measurement::
    /// check_az_el`): the satellite, then the typed error.
    Input { sat: String, error: RaimError },
}

impl Refusal {
    /// Short name for the JSON `error` field.
    pub fn name(&self) -> String {
        match self {
            Refusal::Unreadable(_) => "Unreadable".into(),
            Refusal::Input { error, .. } => crate::result_json::error_name(error),
        }
    }
}

impl std::fmt::Display for Refusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Refusal::Unreadable(m) => write!(f, "not an epoch: {m}"),
            Refusal::Input { sat, error } => write!(f, "satellite {sat}: {error}"),
        }
    }
}

impl std::error::Error for Refusal {}

/// One non-blank, non-comment input line, read and converted.
pub struct Line {
    /// 1-based line number in the input.
    pub number: usize,
    /// The epoch's time when the line got that far.
    pub time_s: Option<f64>,
    pub parsed: std::result::Result<(EpochJson, Sats), Refusal>,
}

/// The epochs of a JSON-lines input (docs/FORMATS.md), one [`Line`] per
/// non-blank, non-comment line. A line that is not UTF-8 or not an epoch is
/// refused, not fatal, so the lines after it are still processed; a last
/// line without its newline that does not parse is reported as cut short.
/// Only a read error of the input itself ends the iteration with `Err`.
pub fn lines<R: BufRead>(mut reader: R) -> impl Iterator<Item = std::io::Result<Line>> {
    let mut number = 0usize;
    let mut buf = Vec::new();
    std::iter::from_fn(move || loop {
        buf.clear();
        match reader.read_until(b'\n', &mut buf) {
            Err(e) => return Some(Err(e)),
            Ok(0) => return None,
            Ok(_) => {}
        }
        number += 1;
        let complete = buf.last() == Some(&b'\n');
        let text = match std::str::from_utf8(&buf) {
            Ok(t) => t.trim(),
            Err(e) => {
                return Some(Ok(Line {
                    number,
                    time_s: None,
                    parsed: Err(Refusal::Unreadable(format!("not UTF-8 text ({e})"))),
                }))
            }
        };
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let epoch = match serde_json::from_str::<EpochJson>(text) {
            Ok(e) => e,
            Err(e) => {
                let cut = if complete {
                    String::new()
                } else {
                    " (the input ends inside this line: truncated?)".into()
                };
                return Some(Ok(Line {
                    number,
                    time_s: None,
                    parsed: Err(Refusal::Unreadable(format!("{e}{cut}"))),
                }));
            }
        };
        let time_s = Some(epoch.time_s);
        let parsed = epoch.to_sats().map(|s| (epoch, s));
        return Some(Ok(Line {
            number,
            time_s,
            parsed,
        }));
    })
}

impl EpochJson {
    /// The satellites in the core's input form; az/el go through the core's
    /// range checks (`LinearObservation::try_from_az_el`: elevation in
    /// [-90°, 90°], azimuth and residual finite).
    pub fn to_sats(&self) -> std::result::Result<Sats, Refusal> {
        self.convert().map_err(|e| match e.downcast::<Refusal>() {
            Ok(r) => r,
            Err(e) => Refusal::Unreadable(format!("{e:#}")),
        })
    }

    fn convert(&self) -> Result<Sats> {
        let ranged = self
            .sats
            .iter()
            .all(|s| s.pseudorange_m.is_some() && s.position_m.is_some());
        let linear = self
            .sats
            .iter()
            .all(|s| s.az_deg.is_some() && s.el_deg.is_some() && s.residual_m.is_some());
        if self.sats.is_empty() {
            bail!("no satellites (\"sats\" is empty)")
        }
        if ranged {
            let v = self
                .sats
                .iter()
                .map(|s| {
                    Ok(RangeObservation {
                        id: sat_id(s)?,
                        pseudorange_m: s.pseudorange_m.unwrap_or(f64::NAN),
                        position_m: s.position_m.unwrap_or([f64::NAN; 3]),
                        sigma_m: s.sigma_m,
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(Sats::Ranges(v))
        } else if linear {
            let v = self
                .sats
                .iter()
                .enumerate()
                .map(|(index, s)| {
                    let id = sat_id(s)?;
                    let (az_deg, el_deg) =
                        (s.az_deg.unwrap_or(f64::NAN), s.el_deg.unwrap_or(f64::NAN));
                    let mut o = LinearObservation::try_from_az_el(
                        id,
                        index,
                        az_deg.to_radians(),
                        el_deg.to_radians(),
                        s.residual_m.unwrap_or(f64::NAN),
                    )
                    .map_err(|error| Refusal::Input {
                        sat: format!("{id} (index {index}, az_deg {az_deg}, el_deg {el_deg})"),
                        error,
                    })?;
                    o.sigma_m = s.sigma_m;
                    Ok(o)
                })
                .collect::<Result<Vec<_>>>()?;
            Ok(Sats::Linear(v))
        } else {
            bail!("every satellite needs either pseudorange_m + position_m, or az_deg + el_deg + residual_m")
        }
    }
}
