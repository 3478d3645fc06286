//! The EGM96 geoid separation N (geoid above the WGS-84 ellipsoid, m) for
//! the GGA sentence's mean-sea-level altitude, `h - N`.
//!
//! Source: EGM96 (Lemoine et al. 1998, NASA/TP-1998-206861), synthesised
//! to degree and order 360 with its height-anomaly-to-undulation
//! correction term by the `egm96` crate (a port of NGA's F477 program), on
//! a 1-degree grid, the resolution RTKLIB embeds (its `geoid.c`, EGM96
//! 1x1 degree). Stored as little-endian i16 centimetres, rows of latitude
//! 90 to -90 degrees, columns of longitude 0 to 359 degrees (181 x 360
//! nodes, 130,320 B): `egm96_1deg.bin`, written by the ignored test
//! `nmea::geoid::tests::regenerate_grid` and checked node by node against
//! the synthesis by `grid_nodes_are_the_synthesis`. Between nodes,
//! bilinear interpolation (within 1.25 m of the synthesis at 95 % of
//! points, 0.25 m at half; test `interpolation_error`).

/// The grid (module doc).
static GRID: &[u8] = include_bytes!("egm96_1deg.bin");

/// Rows (latitudes 90..=-90) and columns (longitudes 0..=359) of `GRID`.
pub const ROWS: usize = 181;
/// Columns of the grid (one per degree of longitude).
pub const COLS: usize = 360;

/// Grid step, degrees.
const STEP_DEG: f64 = 1.0;

/// Metres per stored unit.
const UNIT_M: f64 = 0.01;

/// The node of row `r` (latitude 90 - r degrees) and column `c`
/// (longitude c degrees, wrapped), m.
pub fn node_m(r: usize, c: usize) -> Option<f64> {
    let k = 2 * (r * COLS + c % COLS);
    let b: [u8; 2] = GRID.get(k..k + 2)?.try_into().ok()?;
    Some(f64::from(i16::from_le_bytes(b)) * UNIT_M)
}

/// N (m) at a geodetic latitude and longitude (rad), by bilinear
/// interpolation of the grid; `None` for a non-finite input.
pub fn separation_m(lat_rad: f64, lon_rad: f64) -> Option<f64> {
    if !(lat_rad.is_finite() && lon_rad.is_finite()) {
        return None;
    }
    let lat_deg = lat_rad.to_degrees().clamp(-90.0, 90.0);
    let lon = lon_rad.to_degrees();
    let lon_deg = lon - 360.0 * libm::floor(lon / 360.0);
    // Row coordinate from the north pole, column from Greenwich.
    let y = (90.0 - lat_deg) / STEP_DEG;
    let x = lon_deg / STEP_DEG;
    let r0 = (libm::floor(y) as usize).min(ROWS - 2);
    let c0 = (libm::floor(x) as usize).min(COLS - 1);
    let (ty, tx) = (y - r0 as f64, x - c0 as f64);
    let (n00, n01) = (node_m(r0, c0)?, node_m(r0, c0 + 1)?);
    let (n10, n11) = (node_m(r0 + 1, c0)?, node_m(r0 + 1, c0 + 1)?);
    let north = n00 + (n01 - n00) * tx;
    let south = n10 + (n11 - n10) * tx;
    Some(north + (south - north) * ty)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    fn synthesis_m(lat_deg: f64, lon_deg: f64) -> f64 {
        egm96::egm96_compute_altitude_offset(lat_deg, lon_deg)
    }

    /// Rewrites the grid from the synthesis (about 3 minutes):
    /// `cargo test -p raim-proto --release --lib regenerate_grid -- --ignored`.
    #[test]
    #[ignore]
    fn regenerate_grid() {
        let mut out = Vec::with_capacity(ROWS * COLS * 2);
        for r in 0..ROWS {
            for c in 0..COLS {
                let n = synthesis_m(90.0 - r as f64, c as f64);
                out.extend_from_slice(&((n / UNIT_M).round() as i16).to_le_bytes());
            }
        }
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/nmea/egm96_1deg.bin");
        std::fs::write(path, out).unwrap();
    }

    /// A deterministic sample of nodes (every 37th) equals the synthesis
    /// rounded to the stored centimetre.
    #[test]
    fn grid_nodes_are_the_synthesis() {
        assert_eq!(GRID.len(), ROWS * COLS * 2);
        let mut checked = 0;
        for k in (0..ROWS * COLS).step_by(37) {
            let (r, c) = (k / COLS, k % COLS);
            let want = (synthesis_m(90.0 - r as f64, c as f64) / UNIT_M).round() * UNIT_M;
            let got = node_m(r, c).unwrap();
            assert!((got - want).abs() < 1e-9, "node {r},{c}: {got} != {want}");
            checked += 1;
        }
        assert!(checked > 1700);
    }

    /// Bilinear interpolation between 1-degree nodes against the synthesis
    /// at 400 scattered points: within 0.25 m at half of them, 1.25 m at
    /// 95 %, and 6 m everywhere (5.2 m measured) (the largest errors are over trenches and
    /// mountain ranges, where the geoid bends within a degree).
    #[test]
    fn interpolation_error() {
        const MEDIAN_M: f64 = 0.25;
        const TYPICAL_M: f64 = 1.25;
        const WORST_M: f64 = 6.0;
        let mut errs: Vec<f64> = (0..400)
            .map(|i| {
                // A low-discrepancy scatter over the sphere.
                let lat = (2.0 * ((i as f64 * 0.618_034) % 1.0) - 1.0)
                    .asin()
                    .to_degrees();
                let lon = (i as f64 * 0.754_877_666) % 1.0 * 360.0 - 180.0;
                let got = separation_m(lat.to_radians(), lon.to_radians()).unwrap();
                (got - synthesis_m(lat, lon)).abs()
            })
            .collect();
        errs.sort_by(f64::total_cmp);
        std::eprintln!("median {} p95 {} max {}", errs[199], errs[379], errs[399]);
        assert!(errs[199] < MEDIAN_M, "median {}", errs[199]);
        assert!(errs[379] < TYPICAL_M, "95th percentile {}", errs[379]);
        assert!(errs[399] < WORST_M, "worst {}", errs[399]);
    }

    /// GSI station 0759 (RINEX header position): RTKLIB's 1-degree EGM96
    /// gives N = 36.478 m there; the synthesis 36.104 m.
    #[test]
    fn station_0759() {
        let g = raim_core::frames::ecef_to_geodetic([-3976219.5082, 3382372.5671, 3652512.9849]);
        let n = separation_m(g.lat_rad, g.lon_rad).unwrap();
        assert!((n - 36.478).abs() < 0.5, "{n}");
        assert!((n - synthesis_m(g.lat_rad.to_degrees(), g.lon_rad.to_degrees())).abs() < 0.5);
        assert_eq!(separation_m(f64::NAN, 0.0), None);
        // The poles and the antimeridian wrap.
        assert!(separation_m(core::f64::consts::FRAC_PI_2, 3.0).is_some());
        assert!(separation_m(-core::f64::consts::FRAC_PI_2, -3.0).is_some());
        assert!(separation_m(0.1, core::f64::consts::PI).is_some());
    }
}
