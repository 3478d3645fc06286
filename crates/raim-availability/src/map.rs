//! PNG maps of a grid's results (issue 36): per-user availability, the
//! 99.5th-percentile VPL and the most monitored fault modes, each cell
//! filled with its bin's colour, coastlines over the cells, a colour bar
//! and a title naming the scenario.
//!
//! The coastlines are Natural Earth's 1:110m coastline (public domain),
//! as packaged in the crate `plotine` 0.5.2 (MIT), converted by
//! `scripts/coastline.py` into `data/coastline_ne110m.bin` (134 lines,
//! 5,127 points at 0.01 degree; compiled in, nothing read at run time).
//!
//! Availability bins are the ones MAAST's coverage maps use (0, 50, 75,
//! 85, 90, 95, 98, 99, 99.5, 99.9 %); VPL bins step 5 m up to the LPV
//! alert limits (10, 15, ..., 35, 40, 50 m).

use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use crate::engine::UserSummary;
use crate::output::Meta;

/// The canvas (pixels) and the map area's width: the colour bar is to
/// its right.
pub const WIDTH_PX: u32 = 1400;
/// Canvas height (pixels).
pub const HEIGHT_PX: u32 = 760;
/// The map area's width (pixels).
pub const MAP_WIDTH_PX: u32 = 1180;

/// Colour bins: value v is in bin i when `edges[i] <= v < edges[i + 1]`
/// (the last bin is open above; NaN falls in no bin and is drawn grey).
#[derive(Debug, Clone)]
pub struct Bins {
    /// Lower edges, increasing.
    pub edges: Vec<f64>,
    /// One colour per bin.
    pub colours: Vec<RGBColor>,
    /// One label per bin.
    pub labels: Vec<String>,
}

impl Bins {
    /// The bin of `v`.
    pub fn of(&self, v: f64) -> Option<usize> {
        if v.is_nan() {
            return None;
        }
        self.edges.iter().rposition(|e| v >= *e)
    }
}

/// A red-to-blue ramp of `n` colours (low values red).
fn ramp(n: usize, reverse: bool) -> Vec<RGBColor> {
    const STOPS: [(u8, u8, u8); 10] = [
        (128, 0, 0),
        (200, 0, 0),
        (255, 64, 0),
        (255, 150, 0),
        (255, 220, 0),
        (200, 230, 60),
        (100, 200, 80),
        (0, 160, 120),
        (0, 110, 200),
        (0, 40, 140),
    ];
    let mut v: Vec<RGBColor> = (0..n)
        .map(|i| {
            let k = if n == 1 {
                0
            } else {
                i * (STOPS.len() - 1) / (n - 1)
            };
            let (r, g, b) = STOPS[k];
            RGBColor(r, g, b)
        })
        .collect();
    if reverse {
        v.reverse();
    }
    v
}

/// MAAST's availability bins.
pub fn availability_bins() -> Bins {
    let edges = vec![0.0, 0.5, 0.75, 0.85, 0.9, 0.95, 0.98, 0.99, 0.995, 0.999];
    let labels = edges
        .iter()
        .enumerate()
        .map(|(i, e)| match edges.get(i + 1) {
            Some(n) => format!("{}-{} %", e * 100.0, n * 100.0),
            None => format!(">= {} %", e * 100.0),
        })
        .collect();
    Bins {
        colours: ramp(edges.len(), false),
        edges,
        labels,
    }
}

/// VPL bins (m), good (small) in blue.
pub fn vpl_bins() -> Bins {
    let edges = vec![0.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0, 50.0];
    let labels = edges
        .iter()
        .enumerate()
        .map(|(i, e)| match edges.get(i + 1) {
            Some(n) => format!("{e}-{n} m"),
            None => format!(">= {e} m"),
        })
        .collect();
    Bins {
        colours: ramp(edges.len(), true),
        edges,
        labels,
    }
}

/// Fault-mode bins: one per count from the smallest to the largest seen.
pub fn mode_bins(users: &[UserSummary]) -> Bins {
    let lo = users.iter().map(|u| u.max_modes).min().unwrap_or(0);
    let hi = users.iter().map(|u| u.max_modes).max().unwrap_or(0).max(lo);
    let edges: Vec<f64> = (lo..=hi).map(f64::from).collect();
    Bins {
        colours: ramp(edges.len(), false),
        labels: (lo..=hi).map(|m| format!("{m} modes")).collect(),
        edges,
    }
}

/// The smallest positive step between the sorted distinct values (1 when
/// there is one value).
fn step(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.dedup();
    let d = v
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    if d.is_finite() && d > 0.0 {
        d
    } else {
        1.0
    }
}

const FONT_CANDIDATES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Registers DejaVu Sans (where distributions install it) as plotters'
/// sans-serif, once.
fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    DONE.get_or_init(|| {
        let path = FONT_CANDIDATES
            .iter()
            .find(|p| Path::new(p).exists())
            .ok_or("no TrueType font found (DejaVu Sans) for the maps' text")?;
        let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
        let leaked: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", FontStyle::Normal, leaked)
            .map_err(|_| format!("{path} is not a usable TrueType font"))
    })
    .clone()
    .map_err(|e| anyhow!(e))
}

/// Natural Earth's 1:110m coastlines (module doc): little-endian i16
/// pairs, longitude then latitude in hundredths of a degree, with
/// (-32768, -32768) between two lines.
const COASTLINE: &[u8] = include_bytes!("../data/coastline_ne110m.bin");

/// The coastlines, each a run of (longitude, latitude) points in degrees.
pub fn coastlines() -> Vec<Vec<(f64, f64)>> {
    let mut lines = Vec::new();
    let mut line = Vec::new();
    for c in COASTLINE.chunks_exact(4) {
        let x = i16::from_le_bytes([c[0], c[1]]);
        let y = i16::from_le_bytes([c[2], c[3]]);
        if x == i16::MIN && y == i16::MIN {
            lines.push(std::mem::take(&mut line));
        } else {
            line.push((f64::from(x) / 100.0, f64::from(y) / 100.0));
        }
    }
    lines.push(line);
    lines.retain(|l| l.len() >= 2);
    lines
}

/// The part of segment a-b inside the box [x0, x1] x [y0, y1]
/// (Liang-Barsky), if any.
fn clip(
    a: (f64, f64),
    b: (f64, f64),
    (x0, x1, y0, y1): (f64, f64, f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// Where a map's axes fell on the canvas: the plotting area's pixels and
/// the longitudes and latitudes at its edges.
#[derive(Debug, Clone, PartialEq)]
pub struct MapFrame {
    /// Pixel columns of the plotting area.
    pub x_px: std::ops::Range<i32>,
    /// Pixel rows of the plotting area (top to bottom).
    pub y_px: std::ops::Range<i32>,
    /// Longitudes at the left and right edges (degrees).
    pub lon_deg: (f64, f64),
    /// Latitudes at the bottom and top edges (degrees).
    pub lat_deg: (f64, f64),
}

impl MapFrame {
    /// The pixel of (longitude, latitude).
    pub fn pixel(&self, lon_deg: f64, lat_deg: f64) -> (i32, i32) {
        let fx = (lon_deg - self.lon_deg.0) / (self.lon_deg.1 - self.lon_deg.0);
        let fy = (self.lat_deg.1 - lat_deg) / (self.lat_deg.1 - self.lat_deg.0);
        let w = f64::from(self.x_px.end - self.x_px.start);
        let h = f64::from(self.y_px.end - self.y_px.start);
        (
            self.x_px.start + (fx * w).round() as i32,
            self.y_px.start + (fy * h).round() as i32,
        )
    }
}

/// Draws one map of `values` (one per user of `meta`) into `path`, with
/// the coastlines over the cells; returns where its axes fell.
///
/// # Errors
/// No font, or the PNG cannot be written.
pub fn draw(
    path: &Path,
    title: &str,
    meta: &Meta,
    values: &[f64],
    bins: &Bins,
) -> Result<MapFrame> {
    register_font()?;
    let e = |e: &dyn std::fmt::Display| anyhow!("{}: {e}", path.display());
    let root = BitMapBackend::new(path, (WIDTH_PX, HEIGHT_PX)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let (map, bar) = root.split_horizontally(MAP_WIDTH_PX);
    let lats: Vec<f64> = meta.users.iter().map(|u| u.1).collect();
    let lons: Vec<f64> = meta.users.iter().map(|u| u.2).collect();
    let (dlat, dlon) = (step(lats.clone()), step(lons.clone()));
    let lo = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (lat0, lat1) = (
        (lo(&lats) - dlat / 2.0).max(-90.0),
        (hi(&lats) + dlat / 2.0).min(90.0),
    );
    let (lon0, lon1) = (lo(&lons) - dlon / 2.0, hi(&lons) + dlon / 2.0);
    let mut chart = ChartBuilder::on(&map)
        .caption(title, ("sans-serif", 24))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(lon0..lon1, lat0..lat1)
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("longitude (deg)")
        .y_desc("latitude (deg)")
        .draw()
        .map_err(|x| e(&x))?;
    let grey = RGBColor(160, 160, 160);
    chart
        .draw_series(meta.users.iter().zip(values).map(|(u, v)| {
            let c = bins.of(*v).map_or(grey, |b| bins.colours[b]);
            Rectangle::new(
                [
                    (u.2 - dlon / 2.0, (u.1 - dlat / 2.0).max(lat0)),
                    (u.2 + dlon / 2.0, (u.1 + dlat / 2.0).min(lat1)),
                ],
                c.filled(),
            )
        }))
        .map_err(|x| e(&x))?;
    let area = (lon0, lon1, lat0, lat1);
    chart
        .draw_series(
            coastlines()
                .iter()
                .flat_map(|l| l.windows(2))
                .filter_map(|w| clip(w[0], w[1], area))
                .map(|(a, b)| PathElement::new(vec![a, b], BLACK.stroke_width(1))),
        )
        .map_err(|x| e(&x))?;
    let (x_px, y_px) = chart.plotting_area().get_pixel_range();
    let frame = MapFrame {
        x_px,
        y_px,
        lon_deg: (lon0, lon1),
        lat_deg: (lat0, lat1),
    };
    // The colour bar: one box per bin, lowest at the bottom.
    let n = bins.edges.len() as i32;
    let h = (HEIGHT_PX as i32 - 120) / n.max(1);
    for (i, (c, label)) in bins.colours.iter().zip(&bins.labels).enumerate() {
        let y = 60 + (n - 1 - i as i32) * h;
        bar.draw(&Rectangle::new([(10, y), (40, y + h - 2)], c.filled()))
            .map_err(|x| e(&x))?;
        bar.draw(&Text::new(
            label.clone(),
            (48, y + h / 2 - 8),
            ("sans-serif", 16),
        ))
        .map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(frame)
}

/// The three maps beside the outputs: `<name>.availability.png`,
/// `<name>.vpl.png`, `<name>.modes.png`; returns their paths.
///
/// # Errors
/// As [`draw`].
pub fn write_maps(
    dir: &Path,
    meta: &Meta,
    users: &[UserSummary],
    coverage: f64,
) -> Result<Vec<std::path::PathBuf>> {
    let avail: Vec<f64> = users.iter().map(|u| u.availability).collect();
    let vpl: Vec<f64> = users.iter().map(|u| u.vpl_pct_m).collect();
    let modes: Vec<f64> = users.iter().map(|u| f64::from(u.max_modes)).collect();
    let target = meta.target * 100.0;
    let maps = [
        (
            "availability",
            format!(
                "{}: availability (coverage at {target} %: {:.2} %)",
                meta.name,
                coverage * 100.0
            ),
            avail,
            availability_bins(),
        ),
        (
            "vpl",
            format!("{}: VPL, 99.5th percentile (m)", meta.name),
            vpl,
            vpl_bins(),
        ),
        (
            "modes",
            format!("{}: most monitored fault modes", meta.name),
            modes,
            mode_bins(users),
        ),
    ];
    let mut out = Vec::new();
    for (tag, title, values, bins) in maps {
        let p = dir.join(format!("{}.{tag}.png", meta.name));
        draw(&p, &title, meta, &values, &bins)?;
        out.push(p);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_place_values() {
        let a = availability_bins();
        assert_eq!(a.of(1.0), Some(9));
        assert_eq!(a.of(0.995), Some(8));
        assert_eq!(a.of(0.9949), Some(7));
        assert_eq!(a.of(0.0), Some(0));
        assert_eq!(a.of(f64::NAN), None);
        let v = vpl_bins();
        assert_eq!(v.of(f64::INFINITY), Some(8));
        assert_eq!(v.of(34.99), Some(5));
        assert_eq!(step(vec![10.0, -10.0, 0.0, 0.0]), 10.0);
        assert_eq!(step(vec![5.0]), 1.0);
    }

    /// A 3 x 4 grid whose availabilities fall in 3 of the 10 bins: in the
    /// map area those 3 bin colours fill the cells (and grey the NaN
    /// user's), any other only at a coastline's blended edge; the colour
    /// bar shows all 10.
    ///
    /// Verifies: TOOL-AVAIL-MAPS
    #[test]
    fn map_cells_take_their_bin_colour() {
        let mut users = Vec::new();
        let mut values = Vec::new();
        for (i, lat) in [-10.0, 0.0, 10.0].into_iter().enumerate() {
            for (j, lon) in [0.0, 10.0, 20.0, 30.0].into_iter().enumerate() {
                users.push((String::new(), lat, lon, 1.0));
                values.push(match (i + j) % 3 {
                    0 => 1.0,
                    1 => 0.97,
                    _ => 0.6,
                });
            }
        }
        values[5] = f64::NAN;
        let meta = Meta {
            name: "t".into(),
            run_digest: String::new(),
            satellites: vec![],
            unhealthy: vec![],
            epochs: 1,
            mask_rad: 0.0,
            limits_m: [35.0, 40.0, 15.0, 1.87],
            target: 0.995,
            users,
            ephemeris_gaps: None,
            adjusted_sigma_acc_max_m: None,
            horizontal_only: false,
            budgets: None,
        };
        let bins = availability_bins();
        let dir = std::env::temp_dir().join(format!("raim-avail-map-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        draw(&path, "test", &meta, &values, &bins).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (WIDTH_PX, HEIGHT_PX));
        let count = |c: RGBColor, map_area: bool| {
            img.enumerate_pixels()
                .filter(|(x, _, p)| (*x < MAP_WIDTH_PX) == map_area && p.0 == [c.0, c.1, c.2])
                .count()
        };
        let used = [
            bins.of(1.0).unwrap(),
            bins.of(0.97).unwrap(),
            bins.of(0.6).unwrap(),
        ];
        for (b, c) in bins.colours.iter().enumerate() {
            let n = count(*c, true);
            if used.contains(&b) {
                assert!(n > 1000, "bin {b}: {n} pixels");
            } else {
                // A few pixels where the coastline's edge blends into a
                // cell's colour.
                assert!(n < 20, "bin {b} drawn but unused: {n} pixels");
            }
            assert!(
                count(*c, false) > 100,
                "bin {b} missing from the colour bar"
            );
        }
        assert!(count(RGBColor(160, 160, 160), true) > 1000, "the NaN cell");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The packaged coastlines: Natural Earth's 1:110m coastline has 134
    /// lines (rnaturalearthdata's `coastline110`: 134 rows); the southern
    /// tip of Africa lies at Cape Agulhas, 34.83 S 20.00 E (within 0.3
    /// deg), and South America's near Cape Horn, 55.98 S 67.27 W (within
    /// 0.5 deg: the 1:110m generalisation of Tierra del Fuego ends at
    /// 55.61 S).
    ///
    /// Verifies: TOOL-AVAIL-MAPS
    #[test]
    fn coastlines_are_natural_earths() {
        let lines = coastlines();
        assert_eq!(lines.len(), 134);
        let points: Vec<(f64, f64)> = lines.iter().flatten().copied().collect();
        assert!(points
            .iter()
            .all(|(x, y)| (-180.0..=180.0).contains(x) && (-90.0..=90.0).contains(y)));
        let southmost = |lon: std::ops::Range<f64>, lat: std::ops::Range<f64>| {
            points
                .iter()
                .filter(|(x, y)| lon.contains(x) && lat.contains(y))
                .map(|p| p.1)
                .fold(f64::INFINITY, f64::min)
        };
        assert!((southmost(15.0..30.0, -40.0..-30.0) + 34.83).abs() < 0.3);
        assert!((southmost(-75.0..-60.0, -60.0..-50.0) + 55.98).abs() < 0.5);
    }

    /// On a map of the Gulf of Guinea (one colour), the coastline is drawn
    /// in black through each of its vertices in the map's frame, and
    /// nowhere near a point 5 deg from any coast (Central Africa, 20 E 5 N;
    /// the South Atlantic, 10 W 10 S).
    ///
    /// Verifies: TOOL-AVAIL-MAPS
    #[test]
    fn coastlines_are_drawn_where_they_lie() {
        let mut users = Vec::new();
        for lat in [-10.0, 0.0, 10.0] {
            for lon in [-10.0, 0.0, 10.0, 20.0, 30.0] {
                users.push((String::new(), lat, lon, 1.0));
            }
        }
        let values = vec![1.0; users.len()];
        let meta = Meta {
            name: "t".into(),
            run_digest: String::new(),
            satellites: vec![],
            unhealthy: vec![],
            epochs: 1,
            mask_rad: 0.0,
            limits_m: [35.0, 40.0, 15.0, 1.87],
            target: 0.995,
            users,
            ephemeris_gaps: None,
            adjusted_sigma_acc_max_m: None,
            horizontal_only: false,
            budgets: None,
        };
        let dir = std::env::temp_dir().join(format!("raim-avail-coast-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        let frame = draw(&path, "test", &meta, &values, &availability_bins()).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        let black_near = |(px, py): (i32, i32), r: i32| {
            (-r..=r).any(|dx| {
                (-r..=r).any(|dy| {
                    let (x, y) = (px + dx, py + dy);
                    x >= 0
                        && y >= 0
                        && img
                            .get_pixel_checked(x as u32, y as u32)
                            .is_some_and(|p| p.0 == [0, 0, 0])
                })
            })
        };
        let inside = |(x, y): &(f64, f64)| {
            (frame.lon_deg.0 + 0.5..frame.lon_deg.1 - 0.5).contains(x)
                && (frame.lat_deg.0 + 0.5..frame.lat_deg.1 - 0.5).contains(y)
        };
        let vertices: Vec<(f64, f64)> = coastlines().into_iter().flatten().filter(inside).collect();
        assert!(vertices.len() > 20, "{}", vertices.len());
        for (x, y) in &vertices {
            assert!(black_near(frame.pixel(*x, *y), 1), "no coast at {x} {y}");
        }
        assert!(!black_near(frame.pixel(20.0, 5.0), 10));
        assert!(!black_near(frame.pixel(-10.0, -10.0), 10));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
