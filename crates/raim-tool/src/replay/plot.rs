//! `raim replay --plot out.png`: a title naming the file, the faults and
//! the window, then five panels on a GPS-time axis: (1) the test statistic
//! sqrt(D^2) against its threshold, alarms and exclusions marked; (2) the
//! horizontal/vertical position error with HPL/VPL; (3) which satellites
//! were excluded when, over the injected faults; (4, 5) the horizontal and
//! vertical Stanford diagrams (module `stanford`).

use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use raim_core::Config;

use super::stanford::{self, Axis};
use super::ReplayOutput;

/// A named, coloured quantity of an epoch.
type Series = (&'static str, RGBColor, fn(&super::EpochRecord) -> f64);

const W: u32 = 1800;
const H: u32 = 1900;

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// GPS time of day (hours) on the x axis of every time panel.
pub(crate) struct TimeAxis {
    /// GPS seconds of 00:00:00 GPST of the first epoch's day.
    day0_gps_s: f64,
    pub first_h: f64,
    pub last_h: f64,
    /// The axis name, with the date: "GPS time of day (GPST) on 2005/04/02".
    pub desc: String,
}

impl TimeAxis {
    pub fn new(first_gps_s: f64, last_gps_s: f64) -> Self {
        let day0_gps_s = (first_gps_s / 86_400.0).floor() * 86_400.0;
        let first_h = (first_gps_s - day0_gps_s) / 3600.0;
        let last_h = ((last_gps_s - day0_gps_s) / 3600.0).max(first_h + 1.0 / 60.0);
        let date = super::export::gpst_text(first_gps_s);
        TimeAxis {
            day0_gps_s,
            first_h,
            last_h,
            desc: format!(
                "GPS time of day (GPST, HH:MM) from {}",
                date.get(..10).unwrap_or(&date)
            ),
        }
    }
    pub fn x(&self, t_gps_s: f64) -> f64 {
        (t_gps_s - self.day0_gps_s) / 3600.0
    }
    pub fn range(&self) -> std::ops::Range<f64> {
        self.first_h..self.last_h
    }
}

/// "HH:MM" of hours since the GPS day's start.
pub(crate) fn hhmm(h: &f64) -> String {
    let m = (h * 60.0).round() as i64;
    format!(
        "{:02}:{:02}",
        m.div_euclid(60).rem_euclid(24),
        m.rem_euclid(60)
    )
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
    register_font(font)?;
    let root = BitMapBackend::new(path, (W, H)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(&format!("raim replay: {title}"), ("sans-serif", 30))
        .map_err(err)?;
    let (upper, lower) = root.split_vertically(1100);
    let rows = upper.split_evenly((2, 1));
    let mid = rows[1].split_evenly((1, 2));
    let bottom = lower.split_evenly((1, 2));
    let recs = &out.records;
    let ax = TimeAxis::new(
        recs.first().map_or(0.0, |r| r.time_gps_s),
        recs.last().map_or(0.0, |r| r.time_gps_s),
    );
    let solved: Vec<_> = recs
        .iter()
        .filter(|r| r.initial_statistic.is_finite())
        .collect();

    // (1) statistic vs threshold: the lines drawn over small hollow markers.
    {
        let y_max = solved
            .iter()
            .map(|r| r.initial_statistic.sqrt().max(r.initial_threshold.sqrt()))
            .fold(1.0f64, f64::max)
            * 3.0;
        let mut c = ChartBuilder::on(&rows[0])
            .caption(
                "all-in-view test statistic sqrt(D2) against its threshold T",
                ("sans-serif", 24),
            )
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(ax.range(), (0.1f64..y_max).log_scale())
            .map_err(err)?;
        c.configure_mesh()
            .x_desc(ax.desc.as_str())
            .x_label_formatter(&hhmm)
            .y_desc("sqrt(D2), T (sigma units)")
            .draw()
            .map_err(err)?;
        let y = |r: &super::EpochRecord| r.initial_statistic.sqrt().max(0.1);
        let orange = RGBColor(255, 140, 0);
        c.draw_series(
            solved
                .iter()
                .filter(|r| r.decision == "excluded")
                .map(|r| TriangleMarker::new((ax.x(r.time_gps_s), y(r) * 1.6), 5, orange.filled())),
        )
        .map_err(err)?
        .label("epoch with an exclusion (triangle above the line)")
        .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 5, orange.filled()));
        c.draw_series(
            solved
                .iter()
                .filter(|r| r.decision == "alarm")
                .map(|r| Cross::new((ax.x(r.time_gps_s), y(r) * 1.6), 5, RED.stroke_width(2))),
        )
        .map_err(err)?
        .label("alarm (cross above the line)")
        .legend(|(x, y)| Cross::new((x + 10, y), 5, RED.stroke_width(2)));
        c.draw_series(LineSeries::new(
            solved
                .iter()
                .map(|r| (ax.x(r.time_gps_s), r.initial_threshold.sqrt())),
            RED.stroke_width(2),
        ))
        .map_err(err)?
        .label("threshold T (from the false-alarm probability)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        c.draw_series(LineSeries::new(
            solved.iter().map(|r| (ax.x(r.time_gps_s), y(r))),
            BLUE.stroke_width(1),
        ))
        .map_err(err)?
        .label("all-in-view sqrt(D2)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
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
            * 4.0;
        let mut c = ChartBuilder::on(&mid[0])
            .caption(
                "position error and protection levels (usable epochs)",
                ("sans-serif", 22),
            )
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(ax.range(), (0.01f64..y_max).log_scale())
            .map_err(err)?;
        c.configure_mesh()
            .x_desc(ax.desc.as_str())
            .x_label_formatter(&hhmm)
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
            c.draw_series(usable.iter().filter(|r| f(r).is_finite()).map(|r| {
                Circle::new(
                    (ax.x(r.time_gps_s), f(r).clamp(0.01, y_max)),
                    2,
                    color.filled(),
                )
            }))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
        }
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }

    // (3) exclusions and injected faults per satellite.
    {
        let ax = &ax;
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
        let mut c = ChartBuilder::on(&mid[1])
            .caption("exclusions over the injected faults", ("sans-serif", 22))
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(ax.range(), -0.5..(n + 0.5))
            .map_err(err)?;
        let labels = sats.clone();
        c.configure_mesh()
            .x_desc(ax.desc.as_str())
            .x_label_formatter(&hhmm)
            .y_desc("satellite")
            .y_labels(sats.len().max(1) + 1)
            .y_label_formatter(&|y| {
                let k = y.round();
                if (y - k).abs() > 0.01 || k < 0.0 {
                    return String::new();
                }
                labels.get(k as usize).cloned().unwrap_or_default()
            })
            .draw()
            .map_err(err)?;
        let half_h = 0.5 / 60.0 * 0.5;
        let grey = RGBColor(190, 190, 190);
        c.draw_series(recs.iter().flat_map(|r| {
            r.faulted.iter().map(move |(s, _)| {
                let t = ax.x(r.time_gps_s);
                Rectangle::new(
                    [(t - half_h, idx(s) - 0.3), (t + half_h, idx(s) + 0.3)],
                    grey.filled(),
                )
            })
        }))
        .map_err(err)?
        .label("fault injected")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], grey.filled()));
        let kinds = [
            ("excluded", RGBColor(255, 140, 0), "excluded (in force)"),
            ("unavailable", BLUE, "excluded, PL above the alert limit"),
            ("alarm", RED, "exclusion tried, alarm"),
        ];
        for (decision, color, label) in kinds {
            c.draw_series(
                recs.iter()
                    .filter(|r| r.decision == decision)
                    .flat_map(|r| {
                        r.excluded.iter().map(move |s| {
                            Circle::new((ax.x(r.time_gps_s), idx(s)), 3, color.filled())
                        })
                    }),
            )
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
        }
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(err)?;
    }

    // (4, 5) Stanford diagrams.
    let pts = |pe: fn(&super::EpochRecord) -> Option<f64>, pl: fn(&super::EpochRecord) -> f64| {
        recs.iter()
            .filter(|r| r.usable())
            .filter_map(|r| pe(r).map(|e| (e, pl(r))))
            .collect::<Vec<_>>()
    };
    let alarms = recs.iter().filter(|r| !r.usable()).count();
    stanford::draw(
        &bottom[0],
        &pts(|r| r.error_h_m, |r| r.hpl_m),
        Axis::Horizontal,
        Some(cfg.alert.hal_m),
        alarms,
    )?;
    stanford::draw(
        &bottom[1],
        &pts(|r| r.error_v_m, |r| r.vpl_m),
        Axis::Vertical,
        cfg.alert.val_m,
        alarms,
    )?;
    root.present().map_err(err)?;
    Ok(())
}
