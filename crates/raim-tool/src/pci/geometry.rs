//! The parity-space picture of one geometry (SPEC §2, §4.3): for each
//! satellite its S_ii and its parity direction a_i = U2^T e_i (|a_i|^2 = S_ii),
//! computed by the core's Householder parity (`raim_core::linalg::parity::Parity`), so
//! the tool analyses the product's own projection.
//!
//! With unit noise (sigma = 1, biases in sigma units) and a fault b on
//! satellite i, the parity vector is y ~ N(b a_i, I_d), d = n - m, and the
//! whitened residuals are r_j = a_j^T y. Every statistic the rules use is a
//! function of y, so P_CI is an integral over R^d (exact.rs) or an average
//! over draws of y (montecarlo.rs).

// Index loops over the column-major core buffers read like the formulas.
#![allow(clippy::needless_range_loop)]

use anyhow::{bail, Result};
use raim_core::linalg::parity::Parity;
use raim_core::measurement::MAX_STATES;
use raim_core::{SatId, System};

/// Capacity of the core buffers used here: the documented default.
pub const N: usize = raim_core::DEFAULT_CAPACITY;

/// One satellite of the analysed geometry.
#[derive(Debug, Clone, Copy)]
pub struct Sat {
    pub id: SatId,
    pub az_deg: f64,
    pub el_deg: f64,
    /// Unit line of sight receiver -> satellite, East/North/Up.
    pub los_enu: [f64; 3],
}

impl Sat {
    pub fn from_az_el_deg(id: SatId, az_deg: f64, el_deg: f64) -> Self {
        let (az, el) = (az_deg.to_radians(), el_deg.to_radians());
        Sat {
            id,
            az_deg,
            el_deg,
            los_enu: [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()],
        }
    }
}

/// Parity-space geometry: S_ii and the parity directions of every satellite.
#[derive(Debug, Clone)]
pub struct Geometry {
    pub sats: Vec<Sat>,
    /// Number of states m = 3 + number of constellations (one clock each).
    pub m: usize,
    /// Parity dimension d = n - m.
    pub d: usize,
    /// Diagonal of S (the core's value).
    pub s_ii: Vec<f64>,
    /// a_i = U2^T e_i, length d each.
    pub a: Vec<Vec<f64>>,
}

impl Geometry {
    /// Build H = [-LOS(ENU), one-hot clock per constellation] (sigma = 1)
    /// and factor it with the core.
    pub fn new(sats: Vec<Sat>) -> Result<Self> {
        let n = sats.len();
        if n > N {
            bail!("{n} satellites: more than the capacity {N}");
        }
        let mut systems: Vec<System> = Vec::new();
        for s in &sats {
            if !systems.contains(&s.id.system) {
                systems.push(s.id.system);
            }
            if !(s.az_deg.is_finite() && s.el_deg.is_finite()) {
                bail!(
                    "satellite {}: azimuth {} / elevation {} not finite",
                    s.id,
                    s.az_deg,
                    s.el_deg
                );
            }
            if !(-90.0..=90.0).contains(&s.el_deg) {
                bail!(
                    "satellite {}: elevation {} deg outside [-90, 90]",
                    s.id,
                    s.el_deg
                );
            }
        }
        let m = 3 + systems.len();
        if n <= m {
            bail!(
                "{n} satellites with {m} states: need at least {} for a parity space",
                m + 1
            );
        }
        if m > MAX_STATES {
            bail!("{m} states: more than the core's {MAX_STATES}");
        }
        let mut h = [[0.0; N]; MAX_STATES];
        for (i, s) in sats.iter().enumerate() {
            for k in 0..3 {
                h[k][i] = -s.los_enu[k];
            }
            let c = systems.iter().position(|x| *x == s.id.system).unwrap_or(0);
            h[3 + c][i] = 1.0;
        }
        let z = [0.0; N];
        let parity =
            Parity::<N>::new(&h, &z, n, m).map_err(|e| anyhow::anyhow!("geometry: {e}"))?;
        let d = n - m;
        // Column k of U2 is U2 e_k; a_i[k] = (U2)_{ik}.
        let mut a = vec![vec![0.0; d]; n];
        for k in 0..d {
            let mut e = vec![0.0; d];
            e[k] = 1.0;
            let col = parity.lift(&e);
            for (i, ai) in a.iter_mut().enumerate() {
                ai[k] = col[i];
            }
        }
        Ok(Geometry {
            sats,
            m,
            d,
            s_ii: parity.s_ii().to_vec(),
            a,
        })
    }

    pub fn n(&self) -> usize {
        self.sats.len()
    }

    /// Leverage h_ii = 1 - S_ii.
    pub fn h_ii(&self, i: usize) -> f64 {
        1.0 - self.s_ii[i]
    }

    /// Whitened residuals r_j = a_j^T y for a parity vector y.
    pub fn residuals_into(&self, y: &[f64], out: &mut [f64]) {
        for (o, a) in out.iter_mut().zip(self.a.iter()) {
            *o = a.iter().zip(y.iter()).map(|(p, q)| p * q).sum();
        }
    }
}

/// Satellites from comma-separated azimuth and elevation lists (degrees),
/// one constellation (labelled G01, G02, ... in input order).
pub fn sats_from_lists(az_deg: &[f64], el_deg: &[f64]) -> Result<Vec<Sat>> {
    if az_deg.len() != el_deg.len() {
        bail!("{} azimuths but {} elevations", az_deg.len(), el_deg.len());
    }
    az_deg
        .iter()
        .zip(el_deg.iter())
        .enumerate()
        .map(|(i, (&az, &el))| {
            // The core's range check: elevation in [-90, 90] deg, both finite.
            raim_core::measurement::check_az_el(i, az.to_radians(), el.to_radians())
                .map_err(|e| anyhow::anyhow!("--az/--el satellite {}: {e} (el_deg {el})", i + 1))?;
            Ok(Sat::from_az_el_deg(
                SatId::new(System::Gps, (i + 1) as u8),
                az,
                el,
            ))
        })
        .collect()
}

/// Geometries shared by the tests of the pci modules.
#[cfg(test)]
pub mod fixtures {
    use super::*;

    /// Seed 001 Table 1 (BeiDou, 6 satellites): PRN, azimuth, elevation (deg).
    pub const BEIDOU_TABLE1: [(u8, f64, f64); 6] = [
        (5, 119.8, 20.9),
        (8, 45.0, 25.0),
        (9, 184.7, 54.4),
        (18, 302.7, 19.4),
        (21, 210.3, 40.3),
        (22, 302.1, 15.4),
    ];

    /// Seed 001's BeiDou geometry: n = 6, d = 2.
    pub fn beidou() -> Geometry {
        let sats = BEIDOU_TABLE1
            .iter()
            .map(|&(prn, az, el)| Sat::from_az_el_deg(SatId::new(System::Beidou, prn), az, el))
            .collect();
        Geometry::new(sats).unwrap()
    }

    /// A 7-satellite sky (d = 3) with one low satellite of high leverage.
    pub fn seven() -> Geometry {
        let az = [10.0, 75.0, 140.0, 200.0, 255.0, 320.0, 110.0];
        let el = [75.0, 35.0, 28.0, 40.0, 22.0, 45.0, 8.0];
        Geometry::new(sats_from_lists(&az, &el).unwrap()).unwrap()
    }

    /// A 5-satellite sky (d = 1).
    pub fn five() -> Geometry {
        let az = [0.0, 90.0, 180.0, 270.0, 45.0];
        let el = [70.0, 30.0, 20.0, 40.0, 15.0];
        Geometry::new(sats_from_lists(&az, &el).unwrap()).unwrap()
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::beidou;
    use super::*;

    /// |a_i|^2 = S_ii, a_i^T a_j = S_ij and sum_i S_ii = d: the parity
    /// directions reproduce the projector S = U2 U2^T, checked against
    /// I - H (H^T H)^-1 H^T computed independently with nalgebra-free
    /// normal equations (Gauss-Jordan on 4x4).
    #[test]
    fn parity_directions_reproduce_projector() {
        let g = beidou();
        assert_eq!((g.n(), g.m, g.d), (6, 4, 2));
        const PROJ_TOL: f64 = 1e-12; // dimensionless
        let trace: f64 = g.s_ii.iter().sum();
        assert!((trace - g.d as f64).abs() < PROJ_TOL);
        // Dense H and (H^T H)^-1 by Gauss-Jordan.
        let h: Vec<[f64; 4]> = g
            .sats
            .iter()
            .map(|s| [-s.los_enu[0], -s.los_enu[1], -s.los_enu[2], 1.0])
            .collect();
        let mut a = [[0.0; 8]; 4];
        for r in 0..4 {
            for c in 0..4 {
                a[r][c] = h.iter().map(|row| row[r] * row[c]).sum();
            }
            a[r][4 + r] = 1.0;
        }
        for p in 0..4 {
            let piv = a[p][p];
            for c in 0..8 {
                a[p][c] /= piv;
            }
            for r in 0..4 {
                if r != p {
                    let f = a[r][p];
                    for c in 0..8 {
                        a[r][c] -= f * a[p][c];
                    }
                }
            }
        }
        for i in 0..6 {
            for j in 0..6 {
                let mut hp = 0.0;
                for r in 0..4 {
                    for c in 0..4 {
                        hp += h[i][r] * a[r][4 + c] * h[j][c];
                    }
                }
                let s_ij = if i == j { 1.0 } else { 0.0 } - hp;
                let dot: f64 = g.a[i].iter().zip(g.a[j].iter()).map(|(p, q)| p * q).sum();
                assert!((dot - s_ij).abs() < PROJ_TOL, "S_{i}{j}: {dot} vs {s_ij}");
                if i == j {
                    assert!((g.s_ii[i] - s_ij).abs() < PROJ_TOL);
                }
            }
        }
    }

    #[test]
    fn too_few_satellites_is_an_error() {
        let sats = sats_from_lists(&[0.0, 90.0, 180.0, 270.0], &[30.0, 30.0, 30.0, 80.0]).unwrap();
        assert!(Geometry::new(sats).is_err());
        assert!(sats_from_lists(&[0.0], &[1.0, 2.0]).is_err());
    }
}
