//! Shared helpers for the cross-crate vectors: reading the JSON-lines
//! epochs of `vectors/` into raim-core inputs (the same format as
//! `raim snapshot`, docs/FORMATS.md).

use raim_core::{LinearObservation, RangeObservation, SatId, System};
use serde::Deserialize;

#[derive(Debug, Clone, Deserialize)]
pub struct EpochJson {
    pub time_s: f64,
    #[serde(default)]
    pub apriori_m: Option<[f64; 3]>,
    pub sats: Vec<SatJson>,
}

#[derive(Debug, Clone, Deserialize)]
pub struct SatJson {
    pub sys: String,
    pub prn: u8,
    #[serde(default)]
    pub sigma_m: Option<f64>,
    #[serde(default)]
    pub pseudorange_m: Option<f64>,
    #[serde(default)]
    pub position_m: Option<[f64; 3]>,
    #[serde(default)]
    pub az_deg: Option<f64>,
    #[serde(default)]
    pub el_deg: Option<f64>,
    #[serde(default)]
    pub residual_m: Option<f64>,
}

/// An epoch's satellites in one of the core's input forms.
pub enum Sats {
    Ranges(Vec<RangeObservation>),
    Linear(Vec<LinearObservation>),
}

fn id(s: &SatJson) -> SatId {
    let c = s.sys.chars().next().unwrap_or('?');
    SatId::new(System::from_letter(c).unwrap_or(System::Gps), s.prn)
}

impl EpochJson {
    pub fn sats(&self) -> Sats {
        if self.sats.iter().all(|s| s.pseudorange_m.is_some()) {
            Sats::Ranges(
                self.sats
                    .iter()
                    .map(|s| RangeObservation {
                        id: id(s),
                        pseudorange_m: s.pseudorange_m.unwrap_or(f64::NAN),
                        position_m: s.position_m.unwrap_or([f64::NAN; 3]),
                        sigma_m: s.sigma_m,
                    })
                    .collect(),
            )
        } else {
            Sats::Linear(
                self.sats
                    .iter()
                    .map(|s| {
                        let mut o = LinearObservation::from_az_el(
                            id(s),
                            s.az_deg.unwrap_or(f64::NAN).to_radians(),
                            s.el_deg.unwrap_or(f64::NAN).to_radians(),
                            s.residual_m.unwrap_or(f64::NAN),
                        );
                        o.sigma_m = s.sigma_m;
                        o
                    })
                    .collect(),
            )
        }
    }
}

/// Path of a file under `host-tests/vectors/`.
pub fn vector_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("vectors")
        .join(name)
}

/// Read a JSON-lines vector file.
pub fn read_vector(name: &str) -> Vec<EpochJson> {
    let text = std::fs::read_to_string(vector_path(name)).unwrap_or_default();
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}
