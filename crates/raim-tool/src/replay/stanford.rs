//! The Stanford diagram (Tsai, Stanford University, for WAAS): a 2-D
//! histogram of the protection level against the position error, both on
//! log axes, with the lines PE = PL and PL = AL, PE = AL cutting it into the
//! regions an integrity engineer counts:
//!
//! - **nominal**: PE < PL <= AL, the bound holds and the service is there;
//! - **MI** (misleading information): PL <= PE <= AL, the bound fails but
//!   the error stays within the alert limit;
//! - **HMI** (hazardously misleading): PL <= AL < PE;
//! - **unavailable**: PL > AL (the service is declared unavailable), of
//!   which those with PE >= PL are counted apart.
//!
//! Without an alert limit (no VAL in NPA) only nominal and MI are counted.

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    Horizontal,
    Vertical,
}

/// Epochs per region.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    pub nominal: usize,
    pub mi: usize,
    pub hmi: usize,
    pub unavailable: usize,
    /// Unavailable epochs whose error also reaches the PL.
    pub unavailable_mi: usize,
}

/// The counts of `(error, PL)` pairs (m; PL may be infinite) against `al`.
pub fn count(points: &[(f64, f64)], al: Option<f64>) -> Counts {
    let mut c = Counts::default();
    for &(pe, pl) in points {
        match al {
            Some(al) if pl > al => {
                c.unavailable += 1;
                if pe >= pl {
                    c.unavailable_mi += 1;
                }
            }
            Some(al) if pe >= pl && pe > al => c.hmi += 1,
            _ if pe >= pl => c.mi += 1,
            _ => c.nominal += 1,
        }
    }
    c
}

/// Bin counts to colours: a ramp from light blue to dark red, by decade
/// classes, with their legend labels.
const CLASSES: [(usize, &str, RGBColor); 5] = [
    (1, "1 epoch", RGBColor(160, 200, 255)),
    (2, "2-4 epochs", RGBColor(60, 130, 230)),
    (5, "5-19 epochs", RGBColor(40, 170, 80)),
    (20, "20-99 epochs", RGBColor(240, 160, 0)),
    (100, ">= 100 epochs", RGBColor(190, 20, 20)),
];

fn class_colour(n: usize) -> RGBColor {
    CLASSES
        .iter()
        .rev()
        .find(|(lo, _, _)| n >= *lo)
        .map_or(CLASSES[0].2, |c| c.2)
}

const BINS: usize = 60;

/// Draw the diagram for `points` (error, PL) into `area`; `alarms` is the
/// count of epochs not plotted (no usable position). Returns the counts.
pub fn draw<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    points: &[(f64, f64)],
    axis: Axis,
    al: Option<f64>,
    alarms: usize,
) -> Result<Counts> {
    let counts = count(points, al);
    let (pe_name, pl_name, al_name) = match axis {
        Axis::Horizontal => ("horizontal position error, m", "HPL, m", "HAL"),
        Axis::Vertical => ("vertical position error, m", "VPL, m", "VAL"),
    };
    let finite: Vec<f64> = points
        .iter()
        .flat_map(|&(e, p)| [e, p])
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let lo_v = finite
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
        .max(1e-3);
    let hi_v = finite
        .iter()
        .copied()
        .fold(al.unwrap_or(1.0), f64::max)
        .max(al.unwrap_or(1.0) * 10.0);
    let lo = 10f64.powf(lo_v.log10().floor()).min(0.1);
    let hi = 10f64.powf((hi_v * 1.5).log10().ceil());
    let unbounded = points.iter().filter(|(_, p)| !p.is_finite()).count();
    let caption = match axis {
        Axis::Horizontal => "horizontal Stanford diagram",
        Axis::Vertical => "vertical Stanford diagram",
    };
    let mut c = ChartBuilder::on(area)
        .caption(
            if alarms > 0 {
                format!(
                    "{caption}: {} epochs ({alarms} alarm or refused epochs not plotted)",
                    points.len()
                )
            } else {
                format!("{caption}: {} epochs", points.len())
            },
            ("sans-serif", 22),
        )
        .margin(12)
        .x_label_area_size(60)
        .y_label_area_size(70)
        .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())
        .map_err(err)?;
    let note = if unbounded > 0 {
        format!("{pe_name} ({unbounded} unbounded PLs drawn at the top edge)")
    } else {
        pe_name.to_string()
    };
    c.configure_mesh()
        .x_desc(note.as_str())
        .y_desc(pl_name)
        .draw()
        .map_err(err)?;
    // The 2-D histogram on log bins.
    let (llo, lhi) = (lo.log10(), hi.log10());
    let step = (lhi - llo) / BINS as f64;
    let bin = |v: f64| -> usize {
        let v = if v.is_finite() { v } else { hi };
        (((v.clamp(lo, hi).log10() - llo) / step).floor() as usize).min(BINS - 1)
    };
    let mut grid = vec![0usize; BINS * BINS];
    for &(pe, pl) in points {
        if let Some(g) = grid.get_mut(bin(pe) * BINS + bin(pl)) {
            *g += 1;
        }
    }
    let edge = |k: usize| 10f64.powf(llo + k as f64 * step);
    for (lo_class, label, colour) in CLASSES {
        let cells: Vec<(usize, usize)> = (0..BINS * BINS)
            .filter(|&k| grid[k] > 0 && class_colour(grid[k]) == colour)
            .map(|k| (k / BINS, k % BINS))
            .collect();
        let _ = lo_class;
        c.draw_series(cells.into_iter().map(|(i, j)| {
            Rectangle::new(
                [(edge(i), edge(j)), (edge(i + 1), edge(j + 1))],
                colour.filled(),
            )
        }))
        .map_err(err)?
        .label(label)
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 14, y + 5)], colour.filled()));
    }
    // The region boundaries.
    c.draw_series(LineSeries::new([(lo, lo), (hi, hi)], BLACK.stroke_width(1)))
        .map_err(err)?
        .label("PL = error")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    if let Some(al) = al {
        c.draw_series(LineSeries::new([(lo, al), (hi, al)], RED.stroke_width(2)))
            .map_err(err)?
            .label(format!("{al_name} {al:.0} m"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        c.draw_series(LineSeries::new([(al, lo), (al, al)], RED.stroke_width(2)))
            .map_err(err)?;
    }
    // Region names and counts.
    let font = ("sans-serif", 20).into_font();
    let mut labels: Vec<(String, (f64, f64))> = Vec::new();
    let top = al.unwrap_or(hi);
    labels.push((
        format!("nominal: {}", counts.nominal),
        (lo * 1.5, (top / 8.0).max(lo * 20.0)),
    ));
    match al {
        Some(al) => {
            labels.push((
                format!("MI: {}", counts.mi),
                ((al / 12.0).max(lo * 5.0), lo * 1.5),
            ));
            labels.push((format!("HMI: {}", counts.hmi), (al * 1.3, lo * 1.5)));
            labels.push((
                format!(
                    "unavailable: {} ({} with error >= PL)",
                    counts.unavailable, counts.unavailable_mi
                ),
                (lo * 1.5, al * 2.5),
            ));
        }
        None => {
            labels.push((format!("MI: {}", counts.mi), (hi / 200.0, lo * 1.5)));
            labels.push((
                format!("no {al_name} given: no unavailable or HMI region"),
                (lo * 1.5, hi / 2.5),
            ));
        }
    }
    for (text, at) in labels {
        c.draw_series(std::iter::once(Text::new(text, at, font.clone())))
            .map_err(err)?;
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One point in each region, and an unbounded PL.
    #[test]
    fn regions_are_counted() {
        let al = Some(40.0);
        let pts = [
            (1.0, 10.0),          // nominal
            (12.0, 10.0),         // MI
            (50.0, 10.0),         // HMI
            (1.0, 60.0),          // unavailable
            (70.0, 60.0),         // unavailable, error >= PL
            (1.0, f64::INFINITY), // unavailable
        ];
        let c = count(&pts, al);
        assert_eq!(
            c,
            Counts {
                nominal: 1,
                mi: 1,
                hmi: 1,
                unavailable: 3,
                unavailable_mi: 1
            }
        );
        let c = count(&pts, None);
        assert_eq!((c.nominal, c.mi, c.hmi, c.unavailable), (3, 3, 0, 0));
    }
}
