//! `raim pci --plot pci.png`: P_CI against a common bias for each satellite,
//! one panel per rule (Monte Carlo with common random numbers, so the curves
//! are smooth in b and comparable across rules).
//!
//! Text is rendered by plotters' `ab_glyph` backend from a TrueType file read
//! at run time (no fontconfig/freetype): `--font`, or DejaVu Sans where
//! distributions install it.

use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::design;
use super::geometry::Geometry;
use super::montecarlo::{self, McSpec};
use super::rules;
use super::PciArgs;

/// Bias grid points of the plot.
const GRID: usize = 25;
/// Draws per grid point (at most; fewer if --mc asks for fewer).
const PLOT_DRAWS: usize = 40_000;
/// Where distributions install DejaVu Sans.
const FONT_CANDIDATES: [&str; 3] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
];

/// Register the font under "sans-serif" (once per process).
pub fn register_font(path: Option<&Path>) -> Result<()> {
    let path = match path {
        Some(p) => p.to_path_buf(),
        None => FONT_CANDIDATES
            .iter()
            .map(std::path::PathBuf::from)
            .find(|p| p.exists())
            .context("no TrueType font found: pass --font FILE.ttf")?,
    };
    let bytes = std::fs::read(&path).with_context(|| format!("reading font {}", path.display()))?;
    let leaked: &'static [u8] = Box::leak(bytes.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, leaked)
        .map_err(|_| anyhow!("{} is not a usable TrueType font", path.display()))
}

/// Compute the curves and draw them.
pub fn pci_vs_bias(geom: &Geometry, args: &PciArgs, path: &Path) -> Result<()> {
    register_font(args.font.as_deref())?;
    let rules = rules::rules(args.kappa);
    let t2 = design::threshold(args.pfa, geom.d)?;
    let mdb = design::mdb(geom, args.pfa, args.pmd, args.min_s_ii)?;
    let b_max = mdb
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1.0)
        * 1.2;
    let draws = if args.mc > 0 {
        args.mc.min(PLOT_DRAWS)
    } else {
        PLOT_DRAWS
    };
    let grid: Vec<f64> = (0..=GRID).map(|k| b_max * k as f64 / GRID as f64).collect();
    // curves[r][i] = [(b, P_CI)]
    let mut curves = vec![vec![Vec::new(); geom.n()]; rules.len()];
    for &b in &grid {
        let bias = vec![b; geom.n()];
        let spec = McSpec {
            draws,
            seed: args.seed,
            progress: false,
        };
        let res = montecarlo::run(geom, &rules, args.min_s_ii, &bias, t2, spec);
        for (r, per_rule) in curves.iter_mut().enumerate() {
            for (i, c) in per_rule.iter_mut().enumerate() {
                c.push((b, res.cells[i][r].p_ci));
            }
        }
    }
    draw(geom, &rules, &curves, b_max, args, path)
}

fn draw(
    geom: &Geometry,
    rules: &[rules::Rule],
    curves: &[Vec<Vec<(f64, f64)>>],
    b_max: f64,
    args: &PciArgs,
    path: &Path,
) -> Result<()> {
    let width = 520 * rules.len() as u32;
    let root = BitMapBackend::new(path, (width, 520)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
    let panels = root.split_evenly((1, rules.len()));
    for ((panel, rule), per_rule) in panels.iter().zip(rules.iter()).zip(curves.iter()) {
        let caption = format!("P_CI {} (d={}, Pfa={:e})", rule.name, geom.d, args.pfa);
        let mut chart = ChartBuilder::on(panel)
            .caption(caption, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..b_max, 0.0..1.0)
            .map_err(|e| anyhow!("plot: {e}"))?;
        chart
            .configure_mesh()
            .x_desc("bias b (sigma)")
            .y_desc("P_CI")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        for (i, pts) in per_rule.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let label = format!("{} h={:.2}", geom.sats[i].id, geom.h_ii(i));
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
                .map_err(|e| anyhow!("plot: {e}"))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .position(SeriesLabelPosition::LowerRight)
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
    }
    root.present().map_err(|e| anyhow!("plot: {e}"))?;
    if !path.exists() {
        bail!("plot: {} was not written", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::geometry::fixtures::beidou;
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Wrap {
        #[command(flatten)]
        args: super::super::PciArgs,
    }

    /// The plot is written as a PNG with drawn curves and text (if a font is
    /// installed; otherwise the typed "no TrueType font" error).
    #[test]
    fn writes_a_png() {
        let a = Wrap::parse_from(["pci", "--pfa", "1e-2", "--bias", "5", "--mc", "2000"]).args;
        let path = std::env::temp_dir().join(format!("raim_pci_plot_{}.png", std::process::id()));
        match pci_vs_bias(&beidou(), &a, &path) {
            Ok(()) => {
                let bytes = std::fs::read(&path).unwrap();
                assert_eq!(&bytes[1..4], b"PNG");
                // Three panels of curves and text: far more than a blank image.
                assert!(bytes.len() > 20_000, "{} bytes", bytes.len());
                let _ = std::fs::remove_file(&path);
            }
            Err(e) => assert!(e.to_string().contains("no TrueType font"), "{e}"),
        }
    }
}
