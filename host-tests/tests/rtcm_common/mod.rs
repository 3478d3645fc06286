//! The host's causal replay of an RTCM 3 stream, as `raim replay --rtcm3`
//! runs a live source: frame by frame through the host's reader
//! (`raim_recv::rtcm`), each epoch prepared (`raim_gnss::ranging`) with the
//! ephemerides received before it, and given the stream sigmas.

#![allow(dead_code)]

use raim_core::sigma::SigmaModel;
use raim_core::{Config, RangeObservation, System};
use raim_gnss::ranging::{prepare_epoch, PreparedEpoch, RangingOptions};
use raim_gnss::{NavData, ObsData};
use raim_recv::{Decoder, Item};

pub const GMSD7: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/data/GMSD7_20121014.rtcm3"
);
/// The firmware's week-rollover pivot (raim-server's `stream::PIVOT_WEEK`).
pub const PIVOT_WEEK: i64 = 2400;
/// The firmware's stream elevation mask, rad.
pub const MASK_RAD: f64 = 10.0 * core::f64::consts::PI / 180.0;

/// The whole RTCM frames of a byte stream, in order (rtcm-rs checks each).
pub fn frames(bytes: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut i = 0;
    while let Some(rest) = bytes.get(i..).filter(|r| !r.is_empty()) {
        match (rest.first(), rtcm_rs::MessageFrame::new(rest)) {
            (Some(0xD3), Ok(f)) => {
                out.push(&rest[..f.frame_len()]);
                i += f.frame_len();
            }
            _ => i += 1,
        }
    }
    out
}

/// The GLONASS sigma model of `model` (its own URA).
pub fn glonass_model(model: &SigmaModel) -> SigmaModel {
    SigmaModel {
        ura_m: raim_gnss::glonass::glonass_ura_m(model.ura_m),
        ..*model
    }
}

/// The ranging options of a G+R stream replay at the firmware's mask.
pub fn options(model: &SigmaModel) -> RangingOptions {
    RangingOptions {
        systems: vec![System::Gps, System::Glonass],
        codes: raim_nav::ranging::STREAM_CODES
            .iter()
            .map(|(s, c)| (*s, c.iter().map(|c| c.to_string()).collect()))
            .collect(),
        elevation_mask_rad: MASK_RAD,
        iono: true,
        tropo: true,
        group_delay: true,
        glonass_sigma: Some(glonass_model(model)),
    }
}

/// The stream sigma of one prepared satellite: raim-nav's rule, and a
/// single-frequency range of another system with the configuration's
/// model, ionosphere doubled (what `raim replay` does through its
/// configuration, `adjust_config`).
pub fn sigma_m(model: &SigmaModel, system: System, code: &str, el_rad: f64) -> f64 {
    raim_nav::ranging::stream_sigma_m(
        system,
        code,
        el_rad,
        model,
        Some(&glonass_model(model)),
        2.0,
    )
    .unwrap_or_else(|| {
        let mut m = *model;
        m.iono_vertical_m *= 2.0;
        m.sigma_m(el_rad)
    })
}

/// One epoch as the host forms it: its prepared form and the observations
/// with their stream sigmas.
pub struct HostEpoch {
    /// Index of the frame that closed it.
    pub frame: usize,
    pub prepared: PreparedEpoch,
    pub obs: Vec<RangeObservation>,
}

/// The host's causal replay of `bytes`, and its reader's counts.
pub fn host_epochs(bytes: &[u8]) -> (Vec<HostEpoch>, raim_recv::Counts) {
    let model = Config::default().sigma_model;
    let opts = options(&model);
    let mut host = raim_recv::rtcm::Rtcm3::new(PIVOT_WEEK);
    let mut obs = ObsData {
        path: GMSD7.into(),
        approx_position_m: None,
        epochs: Vec::new(),
    };
    let mut nav = NavData::default();
    let mut out = Vec::new();
    let mut items = Vec::new();
    for (n, f) in frames(bytes).into_iter().enumerate() {
        host.push(f, &mut items);
        let mut epochs = Vec::new();
        for it in items.drain(..) {
            match it {
                Item::Epoch(e) => epochs.push(e),
                other => raim_recv::apply(other, &mut obs, &mut nav),
            }
        }
        for e in epochs {
            let prepared = prepare_epoch(&nav, &e, &opts, obs.approx_position_m);
            let sats = prepared
                .sats
                .iter()
                .map(|s| RangeObservation {
                    sigma_m: Some(sigma_m(&model, s.obs.id.system, &s.code, s.elevation_rad)),
                    ..s.obs
                })
                .collect();
            out.push(HostEpoch {
                frame: n,
                prepared,
                obs: sats,
            });
        }
    }
    (out, host.counts().clone())
}
