//! The JSON-lines epoch format of `raim snapshot` (docs/FORMATS.md): one
//! object per line, with satellites in either the pseudorange form or the
//! linearised (az/el + residual) form.

use anyhow::{bail, Context, Result};
use raim_core::{LinearObservation, RangeObservation, SatId, System};
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

impl EpochJson {
    pub fn to_sats(&self) -> Result<Sats> {
        let ranged = self
            .sats
            .iter()
            .all(|s| s.pseudorange_m.is_some() && s.position_m.is_some());
        let linear = self
            .sats
            .iter()
            .all(|s| s.az_deg.is_some() && s.el_deg.is_some() && s.residual_m.is_some());
        if ranged && !self.sats.is_empty() {
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
                .map(|s| {
                    let mut o = LinearObservation::from_az_el(
                        sat_id(s)?,
                        s.az_deg.unwrap_or(f64::NAN).to_radians(),
                        s.el_deg.unwrap_or(f64::NAN).to_radians(),
                        s.residual_m.unwrap_or(f64::NAN),
                    );
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
