//! `raim replay --pca`: seed 003's constellation-fault monitor
//! (raim_core::araim::pca) beside the ARAIM separation test (any mode, and
//! the constellation modes alone) and the snapshot monitor, on the same
//! faulted epochs. Per epoch: the PCA dimension n_c, k, the statistic
//! max_q |dx_q| / T_q and the three verdicts; then one summary row per
//! method (false alarms before the onset, first detection after it), the
//! rows of the table in docs/ESQ.md.

use std::io::Write;
use std::path::Path;

use anyhow::{anyhow, Result};
use plotters::prelude::*;

use super::esq::{false_alarms, first_after, Row, Setup, PCA_SLOTS};
use super::ReplayArgs;
use raim_core::araim::pca::PcaTest;

/// Q^-1(0.005): the 99th percentile of |u| for u ~ N(0, 1).
const Z_0_005: f64 = 2.575_829_303_549;

/// The PCA alarm at threshold `scale` x T_q: the ratio above it, or NaN
/// (as in the core's test, a NaN alarms).
fn exceeds(ratio: f64, scale: f64) -> bool {
    ratio.is_nan() || ratio > scale
}

/// Whether a method alarmed on an epoch.
type Hit = dyn Fn(&Row) -> bool;

fn verdict(alarm: bool) -> &'static str {
    if alarm {
        "ALARM"
    } else {
        "ok"
    }
}

pub fn run(args: &ReplayArgs, s: &Setup, rows: &[Row], w: &mut impl Write) -> Result<()> {
    if !args.quiet {
        for r in rows {
            let pca = match &r.pca {
                Some(t) => format!(
                    "n_c {:2} k {:2} ratio {:7.3} {:5}",
                    t.n_complete,
                    t.k,
                    t.ratio,
                    verdict(exceeds(t.ratio, args.esq.pca_null_scale))
                ),
                None => "warming up                    ".into(),
            };
            writeln!(
                w,
                "{} n {:2} PCA {} | ARAIM ratio {:7.3} {:5}{} | snapshot {}{}",
                raim_gnss::time::time_of_day(r.t_gps_s),
                r.n_sats,
                pca,
                r.araim_ratio,
                verdict(r.araim_alarm),
                if r.araim_const_alarm {
                    " (constellation mode)"
                } else {
                    ""
                },
                verdict(r.snapshot_alarm),
                if r.errors.is_empty() {
                    String::new()
                } else {
                    format!(" [{}]", r.errors.join("; "))
                },
            )?;
        }
    }
    let scale = args.esq.pca_null_scale;
    if !(scale.is_finite() && scale > 0.0) {
        anyhow::bail!("--pca-null-scale {scale}: must be finite and positive");
    }
    // The alarm at threshold c T_q: the statistic max_q |dx_q| / T_q above c
    // (NaN alarms, as in the core's test).
    let pca_hit = move |r: &Row| r.pca.is_some_and(|t| exceeds(t.ratio, scale));
    let tested = rows.iter().filter(|r| r.pca.is_some()).count();
    let ks: Vec<usize> = rows.iter().filter_map(|r| r.pca.map(|t| t.k)).collect();
    let k_min = ks.iter().copied().min().unwrap_or(0);
    let k_max = ks.iter().copied().max().unwrap_or(0);
    writeln!(
        w,
        "PCA summary: {} epochs, {tested} tested (window {} epochs), k {k_min}..{k_max}",
        rows.len(),
        super::esq::PCA_WINDOW
    )?;
    let methods: [(&str, &Hit); 4] = [
        ("PCA", &pca_hit),
        ("ARAIM (any mode)", &|r: &Row| r.araim_alarm),
        ("ARAIM constellation mode", &|r: &Row| r.araim_const_alarm),
        ("snapshot", &|r: &Row| r.snapshot_alarm),
    ];
    for (name, hit) in methods {
        let faulted = rows.iter().filter(|r| r.faulted).count();
        let detected = rows.iter().filter(|r| r.faulted && hit(r)).count();
        let d = first_after(rows, s.onset_gps_s, hit);
        writeln!(
            w,
            "  {name:26} false alarms {:3} | detected {} delay {} | faulted epochs alarmed {detected}/{faulted}",
            false_alarms(rows, hit),
            if d.is_some() { "yes" } else { "no " },
            d.map_or("-".into(), |d| format!("{d:.0} s")),
        )?;
    }
    // The statistic's scale: its largest value before the onset (the
    // threshold that would have given no false alarm) against its largest
    // in the first five faulted epochs.
    let max_ratio = |it: &mut dyn Iterator<Item = &Row>| {
        it.filter_map(|r| r.pca.map(|t| t.ratio))
            .fold(f64::NAN, f64::max)
    };
    let clean_max = max_ratio(&mut rows.iter().filter(|r| !r.faulted));
    let onset_max = max_ratio(&mut rows.iter().filter(|r| r.faulted).take(5));
    writeln!(
        w,
        "  PCA ratio: max before onset {clean_max:.2}, max in the first 5 faulted epochs {onset_max:.2}"
    )?;
    // The false-alarm count against the allocation: clean tested epochs,
    // the binomial 99 % bound at p_fa; and the empirical null: the
    // standardized separations u = dx_q / sigma_q on the clean tested
    // epochs (N(0, 1) per axis under the nominal null), their 99th
    // percentile of |u| over Q^-1(0.005) as a Gaussian scale fitted on
    // this file.
    let clean: Vec<&PcaTest<PCA_SLOTS>> = rows
        .iter()
        .filter(|r| !r.faulted)
        .filter_map(|r| r.pca.as_ref())
        .collect();
    let fa = rows.iter().filter(|r| !r.faulted && pca_hit(r)).count();
    let bound = super::stats::binomial_bound_99(clean.len(), args.esq.pca_pfa);
    writeln!(
        w,
        "  PCA false alarms against the allocation: {fa} in {} clean tested epochs at p_fa {:e}, threshold {scale} x nominal; binomial 99 % bound {bound}: {}",
        clean.len(),
        args.esq.pca_pfa,
        if fa as u64 <= bound { "within" } else { "OUTSIDE" }
    )?;
    let mut u: Vec<f64> = clean
        .iter()
        .filter(|t| t.k < t.n_complete)
        .flat_map(|t| {
            t.separation_m
                .iter()
                .zip(t.sigma_m.iter())
                .filter(|(_, s)| **s > 0.0)
                .map(|(d, s)| (d / s).abs())
                .collect::<Vec<_>>()
        })
        .collect();
    u.sort_by(f64::total_cmp);
    if let (Some(q99), Some(max)) = (super::stats::quantile_ci(&u, 0.99, 0.95).0, u.last()) {
        writeln!(
            w,
            "  PCA standardized separations |dx_q / sigma_q| on clean epochs: {} values, 99th percentile {q99:.3}, max {max:.3}; fitted Gaussian scale {:.3}",
            u.len(),
            q99 / Z_0_005
        )?;
    }
    let refused = rows.iter().filter(|r| !r.errors.is_empty()).count();
    if refused > 0 {
        writeln!(w, "  epochs with a refusal (listed per epoch): {refused}")?;
    }
    if let Some(p) = &args.esq.esq_plot {
        plot(rows, p, args.font.as_deref(), &super::run_title(args))?;
    }
    Ok(())
}

fn err<E: std::fmt::Display>(e: E) -> anyhow::Error {
    anyhow!("plot: {e}")
}

/// A title naming the file, the faults and the window; two panels on GPS
/// time: the PCA statistic (log scale) against its threshold, alarms
/// marked, and the number of components k of the satellites with a
/// complete window, each with its legend.
fn plot(rows: &[Row], path: &Path, font: Option<&Path>, title: &str) -> Result<()> {
    super::plot::register_font(font)?;
    let root = BitMapBackend::new(path, (1400, 950)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let root = root
        .titled(&format!("raim replay --pca: {title}"), ("sans-serif", 26))
        .map_err(err)?;
    let panels = root.split_evenly((2, 1));
    let ax = super::plot::TimeAxis::new(
        rows.first().map_or(0.0, |r| r.t_gps_s),
        rows.last().map_or(0.0, |r| r.t_gps_s),
    );
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| r.pca.map(|t| (ax.x(r.t_gps_s), t.ratio)))
        .filter(|p| p.1.is_finite())
        .collect();
    let y_max = pts.iter().map(|p| p.1).fold(1.5, f64::max) * 3.0;
    let floor = 0.011;
    let mut c = ChartBuilder::on(&panels[0])
        .caption(
            "PCA constellation statistic max_q |dx_q| / T_q (values below 0.011 drawn at 0.011)",
            ("sans-serif", 22),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), (0.01f64..y_max).log_scale())
        .map_err(err)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("ratio (log)")
        .draw()
        .map_err(err)?;
    c.draw_series(LineSeries::new(
        pts.iter().map(|&(x, y)| (x, y.max(floor))),
        &BLUE,
    ))
    .map_err(err)?
    .label("statistic / threshold")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    c.draw_series(
        pts.iter()
            .filter(|p| p.1 > 1.0)
            .map(|&(x, y)| Circle::new((x, y), 3, RED.filled())),
    )
    .map_err(err)?
    .label("alarm (ratio > 1)")
    .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
    c.draw_series(LineSeries::new(
        [(ax.first_h, 1.0), (ax.range().end, 1.0)],
        RED.stroke_width(2),
    ))
    .map_err(err)?
    .label("threshold (ratio 1)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    let ks: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| r.pca.map(|t| (ax.x(r.t_gps_s), t.k as f64)))
        .collect();
    let nc: Vec<(f64, f64)> = rows
        .iter()
        .filter_map(|r| r.pca.map(|t| (ax.x(r.t_gps_s), t.n_complete as f64)))
        .collect();
    let n_max = nc.iter().map(|p| p.1).fold(2.0, f64::max) * 1.4 + 1.0;
    let mut c = ChartBuilder::on(&panels[1])
        .caption(
            "principal components kept and satellites with a complete window",
            ("sans-serif", 22),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(ax.range(), 0.0..n_max)
        .map_err(err)?;
    c.configure_mesh()
        .x_desc(ax.desc.as_str())
        .x_label_formatter(&super::plot::hhmm)
        .y_desc("count")
        .draw()
        .map_err(err)?;
    c.draw_series(LineSeries::new(ks, &BLUE))
        .map_err(err)?
        .label("k (components)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    c.draw_series(LineSeries::new(nc, &BLACK))
        .map_err(err)?
        .label("n_c (satellites, complete window)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}
