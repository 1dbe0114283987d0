//! The figures of a Monte Carlo study (SVG, plotters, as the campaign's):
//!
//! * `cdf.svg`: the empirical CDF of eta_v, flow and torque over the drawn
//!   pumps, one panel per quantity, one line per condition (201 points per
//!   line: the percentiles at every half per cent, so the file stays small
//!   for any number of pumps); flow and torque as the deviation from their
//!   median at each condition, in %, since their levels differ tenfold
//!   between conditions.
//! * `tornado.svg`: at the focus condition, one bar per clearance for its
//!   first-order Sobol index and an outlined bar for its total index, on
//!   eta_v (left) and torque (right), the clearances sorted by their
//!   first-order index on eta_v, largest at the top.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::estimators::percentile_sorted;
use super::{condition_label, MonteCarloError, Outputs, Quantity, Study, Summary, CLEARANCES};

type DrawResult = Result<(), Box<dyn std::error::Error>>;

fn plot_err(path: &Path) -> impl FnOnce(Box<dyn std::error::Error>) -> MonteCarloError + '_ {
    move |e| MonteCarloError::Plot {
        file: path
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .unwrap_or_default(),
        message: e.to_string(),
    }
}

/// Draws into a temporary file renamed into place.
fn write(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend, plotters::coord::Shift>) -> DrawResult,
) -> Result<PathBuf, MonteCarloError> {
    let tmp = path.with_extension("svg.tmp");
    (|| -> DrawResult {
        let root = SVGBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    })()
    .map_err(plot_err(path))?;
    std::fs::rename(&tmp, path).map_err(|source| MonteCarloError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(path.to_path_buf())
}

fn colour(i: usize) -> RGBColor {
    let c = Palette99::pick(i).to_rgba();
    RGBColor(c.0, c.1, c.2)
}

/// `cdf.svg` (module doc).
pub fn cdf(path: &Path, study: &Study, o: &Outputs) -> Result<PathBuf, MonteCarloError> {
    let nc = study.conditions.len();
    let panels = [
        (Quantity::EtaV, "volumetric efficiency eta_v"),
        (
            Quantity::FlowLpm,
            "flow from its median at the condition, %",
        ),
        (
            Quantity::TorqueNm,
            "torque from its median at the condition, %",
        ),
    ];
    write(path, (1560, 520), |root| {
        let areas = root.split_evenly((1, 3));
        for (pi, (area, (q, label))) in areas.iter().zip(panels).enumerate() {
            let lines: Vec<(String, Vec<(f64, f64)>)> = study
                .conditions
                .iter()
                .enumerate()
                .map(|(c, cond)| {
                    let mut v: Vec<f64> = (0..study.pumps)
                        .map(|i| o.get(q)[i * nc + c])
                        .filter(|x| x.is_finite())
                        .collect();
                    v.sort_by(f64::total_cmp);
                    // flow and torque differ 10x between conditions: their
                    // spread shows as the deviation from each one's median
                    if q != Quantity::EtaV && !v.is_empty() {
                        let m = percentile_sorted(&v, 50.0);
                        if m != 0.0 {
                            v.iter_mut().for_each(|x| *x = 100.0 * (*x / m - 1.0));
                        }
                    }
                    let pts = if v.is_empty() {
                        Vec::new()
                    } else {
                        (0..=200)
                            .map(|k| (percentile_sorted(&v, k as f64 / 2.0), k as f64 / 200.0))
                            .collect()
                    };
                    (condition_label(cond), pts)
                })
                .collect();
            let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
            for (_, p) in &lines {
                for &(x, _) in p {
                    x0 = x0.min(x);
                    x1 = x1.max(x);
                }
            }
            if !x0.is_finite() {
                (x0, x1) = (0.0, 1.0);
            }
            let pad = ((x1 - x0).abs() * 0.05).max(1e-9);
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("CDF over {} pumps", study.pumps),
                    ("sans-serif", 18),
                )
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d(x0 - pad..x1 + pad, 0.0..1.0)?;
            chart
                .configure_mesh()
                .x_desc(label)
                .y_desc("share of pumps at or below")
                .draw()?;
            for (i, (name, pts)) in lines.into_iter().enumerate() {
                let c = colour(i);
                let s = chart.draw_series(LineSeries::new(pts, c.stroke_width(2)))?;
                if pi == 0 {
                    s.label(name).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                    });
                }
            }
            if pi == 0 {
                chart
                    .configure_series_labels()
                    .position(SeriesLabelPosition::UpperLeft)
                    .label_font(("sans-serif", 11))
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()?;
            }
        }
        Ok(())
    })
}

/// `tornado.svg` (module doc); a note instead of bars without indices.
pub fn tornado(path: &Path, summary: &Summary) -> Result<PathBuf, MonteCarloError> {
    let focus = summary.conditions.get(summary.focus);
    let sens = focus.and_then(|c| c.sensitivity.as_ref());
    let title = focus
        .map(|c| condition_label(&c.condition))
        .unwrap_or_default();
    let order: Vec<usize> = {
        let mut k: Vec<usize> = (0..4).collect();
        if let Some(idx) = sens.and_then(|s| s.eta_v.as_ref()) {
            // ascending: the chart's y axis grows upwards, largest on top
            k.sort_by(|&a, &b| idx[a].first.total_cmp(&idx[b].first));
        }
        k
    };
    write(path, (1100, 420), |root| {
        let areas = root.split_evenly((1, 2));
        for (area, q) in areas.iter().zip([Quantity::EtaV, Quantity::TorqueNm]) {
            let idx = sens.and_then(|s| s.get(q));
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!("{}: Sobol indices at {title}", q.name()),
                    ("sans-serif", 16),
                )
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(90)
                .build_cartesian_2d(0.0..1.0, -0.5..3.5)?;
            let names = order.clone();
            chart
                .configure_mesh()
                .disable_y_mesh()
                .y_labels(4)
                .y_label_formatter(&move |y: &f64| {
                    let r = y.round();
                    if (y - r).abs() < 1e-6 && (0.0..4.0).contains(&r) {
                        CLEARANCES[names[r as usize]].to_string()
                    } else {
                        String::new()
                    }
                })
                .x_desc("share of the variance (first order filled, total outlined)")
                .draw()?;
            let Some(idx) = idx else {
                chart.draw_series(std::iter::once(Text::new(
                    "no indices (no sensitivity runs, or no variation)",
                    (0.05, 1.5),
                    ("sans-serif", 14),
                )))?;
                continue;
            };
            for (row, &k) in order.iter().enumerate() {
                let y = row as f64;
                let first = idx[k].first.clamp(0.0, 1.0);
                let total = idx[k].total.clamp(0.0, 1.0);
                let c = colour(k);
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(0.0, y - 0.3), (first, y + 0.3)],
                    c.filled(),
                )))?;
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(0.0, y - 0.38), (total, y + 0.38)],
                    c.stroke_width(2),
                )))?;
            }
        }
        Ok(())
    })
}
