//! `raim replay --plot out.png`: four panels. (1) the test statistic sqrt(D^2)
//! against its threshold over time, alarms and exclusions marked; (2) the
//! horizontal/vertical position error with HPL/VPL; (3) which satellites
//! were excluded when (injected faults underneath); (4) a Stanford diagram,
//! horizontal error against HPL, with the HAL.

use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use raim_core::Config;

use super::ReplayOutput;

/// A named, coloured quantity of an epoch.
type Series = (&'static str, RGBColor, fn(&super::EpochRecord) -> f64);

const W: u32 = 1600;
const H: u32 = 1200;

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// An output file's folder must exist: say so, naming the option and the
/// folder, before any work (plotters would only report an `ImageError`
/// after the run).
pub(crate) fn check_folder(path: &Path, what: &str) -> Result<()> {
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if path.is_dir() {
        return Err(anyhow!(
            "{what} {}: is a directory; give a file name",
            path.display()
        ));
    }
    if !parent.is_dir() {
        return Err(anyhow!(
            "{what} {}: no such folder {} (create it first)",
            path.display(),
            parent.display()
        ));
    }
    Ok(())
}

/// Where distributions install DejaVu Sans.
const FONT_CANDIDATES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Text is drawn by plotters' ab_glyph backend from a TrueType file read at
/// run time (no fontconfig): `--font`, or DejaVu Sans where installed.
pub(super) fn register_font(path: Option<&Path>) -> Result<()> {
    let path = match path {
        Some(p) => p.to_path_buf(),
        None => FONT_CANDIDATES
            .iter()
            .map(std::path::PathBuf::from)
            .find(|p| p.exists())
            .ok_or_else(|| anyhow!("no TrueType font found: pass --font FILE.ttf"))?,
    };
    let bytes =
        std::fs::read(&path).map_err(|e| anyhow!("reading font {}: {e}", path.display()))?;
    let leaked: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, leaked)
        .map_err(|_| anyhow!("{} is not a usable TrueType font", path.display()))
}

pub fn draw(
    out: &ReplayOutput,
    cfg: &Config,
    path: &Path,
    font: Option<&Path>,
    title: &str,
) -> Result<()> {
    let _ = title;
    register_font(font)?;
    let root = BitMapBackend::new(path, (W, H)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let panels = root.split_evenly((2, 2));
    let recs = &out.records;
    let t0 = recs.first().map_or(0.0, |r| r.time_gps_s);
    let mins = |t: f64| (t - t0) / 60.0;
    let t_max = recs.last().map_or(1.0, |r| mins(r.time_gps_s)).max(1.0);
    let solved: Vec<_> = recs
        .iter()
        .filter(|r| r.initial_statistic.is_finite())
        .collect();

    // (1) statistic vs threshold.
    {
        let y_max = solved
            .iter()
            .map(|r| r.initial_statistic.sqrt().max(r.initial_threshold.sqrt()))
            .fold(1.0f64, f64::max)
            * 1.1;
        let mut c = ChartBuilder::on(&panels[0])
            .caption("test statistic sqrt(D2) vs threshold T", ("sans-serif", 24))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_max, (0.1f64..y_max).log_scale())
            .map_err(err)?;
        c.configure_mesh()
            .x_desc("minutes from start")
            .y_desc("sigma units")
            .draw()
            .map_err(err)?;
        c.draw_series(LineSeries::new(
            solved
                .iter()
                .map(|r| (mins(r.time_gps_s), r.initial_threshold.sqrt())),
            &RED,
        ))
        .map_err(err)?
        .label("threshold T")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        c.draw_series(LineSeries::new(
            solved
                .iter()
                .map(|r| (mins(r.time_gps_s), r.initial_statistic.sqrt().max(0.1))),
            &BLUE,
        ))
        .map_err(err)?
        .label("all-in-view sqrt(D2)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        c.draw_series(solved.iter().filter(|r| r.decision == "excluded").map(|r| {
            Circle::new(
                (mins(r.time_gps_s), r.initial_statistic.sqrt().max(0.1)),
                4,
                GREEN.filled(),
            )
        }))
        .map_err(err)?
        .label("excluded")
        .legend(|(x, y)| Circle::new((x + 10, y), 4, GREEN.filled()));
        c.draw_series(solved.iter().filter(|r| r.decision == "alarm").map(|r| {
            Cross::new(
                (mins(r.time_gps_s), r.initial_statistic.sqrt().max(0.1)),
                6,
                RED.stroke_width(2),
            )
        }))
        .map_err(err)?
        .label("alarm")
        .legend(|(x, y)| Cross::new((x + 10, y), 6, RED.stroke_width(2)));
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }

    // (2) errors and protection levels.
    {
        let usable: Vec<_> = recs
            .iter()
            .filter(|r| r.usable() && r.error_h_m.is_some())
            .collect();
        let y_max = usable
            .iter()
            .flat_map(|r| {
                [
                    r.hpl_m,
                    r.vpl_m,
                    r.error_h_m.unwrap_or(0.0),
                    r.error_v_m.unwrap_or(0.0),
                ]
            })
            .filter(|v| v.is_finite() && *v < 1e6)
            .fold(1.0f64, f64::max)
            * 1.5;
        let mut c = ChartBuilder::on(&panels[1])
            .caption(
                "position error and protection levels (usable epochs)",
                ("sans-serif", 24),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_max, (0.01f64..y_max).log_scale())
            .map_err(err)?;
        c.configure_mesh()
            .x_desc("minutes from start")
            .y_desc("m")
            .draw()
            .map_err(err)?;
        let series: [Series; 4] = [
            ("HPL", RED, |r| r.hpl_m),
            ("VPL", MAGENTA, |r| r.vpl_m),
            ("horizontal error", BLUE, |r| {
                r.error_h_m.unwrap_or(f64::NAN)
            }),
            ("vertical error", CYAN, |r| r.error_v_m.unwrap_or(f64::NAN)),
        ];
        for (name, color, f) in series {
            c.draw_series(usable.iter().map(|r| {
                Circle::new(
                    (mins(r.time_gps_s), f(r).clamp(0.01, y_max)),
                    2,
                    color.filled(),
                )
            }))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }

    // (3) exclusions and injected faults per satellite.
    {
        let mut sats: Vec<String> = recs
            .iter()
            .flat_map(|r| {
                r.excluded
                    .iter()
                    .cloned()
                    .chain(r.faulted.iter().map(|(s, _)| s.clone()))
            })
            .collect();
        sats.sort();
        sats.dedup();
        let n = sats.len().max(1) as f64;
        let idx = |s: &str| sats.iter().position(|x| x == s).unwrap_or(0) as f64;
        let mut c = ChartBuilder::on(&panels[2])
            .caption(
                "exclusions (dots) over injected faults (grey)",
                ("sans-serif", 24),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_max, -0.5..(n - 0.5))
            .map_err(err)?;
        let labels = sats.clone();
        c.configure_mesh()
            .x_desc("minutes from start")
            .y_labels(sats.len().max(1))
            .y_label_formatter(&|y| {
                labels
                    .get(y.round().max(0.0) as usize)
                    .cloned()
                    .unwrap_or_default()
            })
            .draw()
            .map_err(err)?;
        c.draw_series(recs.iter().flat_map(|r| {
            r.faulted.iter().map(move |(s, _)| {
                let t = mins(r.time_gps_s);
                Rectangle::new(
                    [(t - 0.25, idx(s) - 0.3), (t + 0.25, idx(s) + 0.3)],
                    RGBColor(200, 200, 200).filled(),
                )
            })
        }))
        .map_err(err)?;
        c.draw_series(recs.iter().flat_map(|r| {
            let color = match r.decision.as_str() {
                "excluded" => GREEN,
                "alarm" => RED,
                _ => BLUE,
            };
            r.excluded
                .iter()
                .map(move |s| Circle::new((mins(r.time_gps_s), idx(s)), 3, color.filled()))
        }))
        .map_err(err)?;
    }

    // (4) Stanford diagram.
    {
        let usable: Vec<_> = recs
            .iter()
            .filter(|r| r.usable() && r.error_h_m.is_some())
            .collect();
        let hal = cfg.alert.hal_m;
        let top = usable
            .iter()
            .flat_map(|r| [r.hpl_m, r.error_h_m.unwrap_or(0.0)])
            .filter(|v| v.is_finite() && *v < 1e6)
            .fold(hal, f64::max)
            * 2.0;
        let mut c = ChartBuilder::on(&panels[3])
            .caption(
                "Stanford diagram: horizontal error vs HPL",
                ("sans-serif", 24),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((0.01f64..top).log_scale(), (0.01f64..top).log_scale())
            .map_err(err)?;
        c.configure_mesh()
            .x_desc("horizontal error, m")
            .y_desc("HPL, m")
            .draw()
            .map_err(err)?;
        c.draw_series(LineSeries::new([(0.01, 0.01), (top, top)], &BLACK))
            .map_err(err)?;
        c.draw_series(LineSeries::new(
            [(0.01, hal), (top, hal)],
            RED.stroke_width(1),
        ))
        .map_err(err)?
        .label(format!("HAL {hal:.0} m"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        c.draw_series(usable.iter().map(|r| {
            let color = if r.decision == "excluded" {
                GREEN
            } else {
                BLUE
            };
            Circle::new(
                (
                    r.error_h_m.unwrap_or(0.01).clamp(0.01, top),
                    r.hpl_m.clamp(0.01, top),
                ),
                2,
                color.filled(),
            )
        }))
        .map_err(err)?;
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    Ok(())
}
