//! Campaign plots (SVG): measured vs simulated characteristic curves per
//! sample (the analogue of the seed paper's Figs. 11-14) and residuals
//! against every feature.
//!
//! * `curves_pressure.svg`: `eta_v` against delivery pressure at the speed
//!   with the most distinct pressures (1000 rpm in the seed's Table 2), one
//!   panel per sample; measured solid with dots, simulated dashed; one colour
//!   per oil temperature (black = lowest, grey = next, as in the seed).
//! * `curves_speed.svg`: `eta_v` against speed at the pressure with the most
//!   distinct speeds (30 bar in Table 2), same layout.
//! * `residuals.svg`: `d = eta_v,meas - eta_v,sim` against pressure, speed,
//!   temperature and each of the four measured clearances, coloured by
//!   temperature, with the zero line.
//! * `losses.svg`: where the flow goes: the simulated loss budget
//!   (`gearpump_core::losses`), mean over the samples of each working condition, as
//!   stacked bars in % of `Vm n` (losses up, gains down), with `1 - eta_v,sim`
//!   marked.
//!
//! A sweep figure is skipped when no speed (pressure) has at least two
//! distinct pressures (speeds). Output is deterministic text (no dates), so
//! a resumed run writes the same bytes. Text is laid out with plotters'
//! built-in size estimate (no font files needed).

use std::collections::BTreeMap;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::data::TestRow;
use super::io::{atomic_write_text, TestOutcome};
use super::run::{sample_ids, RunError};
use gearpump_core::units::m_to_um;

/// A figure written into the output folder.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// File name (in the output folder).
    pub file: String,
    /// One-line caption for the report.
    pub caption: String,
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// The files [`write_plots`] may write (a sweep figure is skipped when the
/// data have no sweep).
pub const FIGURE_FILES: [&str; 3] = ["curves_pressure.svg", "curves_speed.svg", "residuals.svg"];

const FONT: &str = "sans-serif";
const PANEL: (u32, u32) = (250, 200);
const HEADER: u32 = 56;
const COLUMNS: usize = 5;

fn temp_colour(i: usize) -> RGBColor {
    const P: [RGBColor; 6] = [
        RGBColor(0, 0, 0),
        RGBColor(150, 150, 150),
        RGBColor(200, 60, 40),
        RGBColor(40, 90, 200),
        RGBColor(30, 150, 60),
        RGBColor(150, 60, 170),
    ];
    P[i % P.len()]
}

/// Quantised key of an edge value (1e-6 resolution, as the data grouping).
fn key(x: f64) -> i64 {
    (x / 1.0e-6).round() as i64
}

/// Sorted distinct temperatures of the given rows (degC).
fn temperatures(rows: &[TestRow], idx: &[usize]) -> Vec<f64> {
    let mut m: BTreeMap<i64, f64> = BTreeMap::new();
    for &i in idx {
        m.entry(key(rows[i].condition.temp_c))
            .or_insert(rows[i].condition.temp_c);
    }
    m.into_values().collect()
}

fn temp_index(temps: &[f64], t: f64) -> usize {
    temps.iter().position(|x| key(*x) == key(t)).unwrap_or(0)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sweep {
    Pressure,
    Speed,
}

impl Sweep {
    fn x(self, r: &TestRow) -> f64 {
        match self {
            Sweep::Pressure => r.condition.pressure_bar,
            Sweep::Speed => r.condition.speed_rpm,
        }
    }
    fn fixed(self, r: &TestRow) -> f64 {
        match self {
            Sweep::Pressure => r.condition.speed_rpm,
            Sweep::Speed => r.condition.pressure_bar,
        }
    }
}

/// The rows of the sweep and the fixed value: the fixed speed (pressure)
/// with the most distinct pressures (speeds), ties to more rows, then to
/// first appearance. None when no fixed value has two distinct x values.
fn find_sweep(rows: &[TestRow], sweep: Sweep) -> Option<(f64, Vec<usize>)> {
    // fixed key -> (first appearance, fixed value, distinct x, rows)
    let mut groups: Vec<(i64, f64, Vec<i64>, Vec<usize>)> = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let k = key(sweep.fixed(r));
        let g = match groups.iter().position(|g| g.0 == k) {
            Some(g) => g,
            None => {
                groups.push((k, sweep.fixed(r), Vec::new(), Vec::new()));
                groups.len() - 1
            }
        };
        let xk = key(sweep.x(r));
        if !groups[g].2.contains(&xk) {
            groups[g].2.push(xk);
        }
        groups[g].3.push(i);
    }
    let mut best: Option<&(i64, f64, Vec<i64>, Vec<usize>)> = None;
    for g in &groups {
        if g.2.len() < 2 {
            continue;
        }
        let better = match best {
            None => true,
            Some(b) => (g.2.len(), g.3.len()) > (b.2.len(), b.3.len()),
        };
        if better {
            best = Some(g);
        }
    }
    best.map(|g| (g.1, g.3.clone()))
}

/// A padded axis range of the finite values: 8 % of the span each side, or
/// `floor` each side when the span is below `floor`.
fn range(values: impl Iterator<Item = f64>, floor: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-floor, floor);
    }
    let span = hi - lo;
    let pad = if span < floor { floor } else { 0.08 * span };
    (lo - pad, hi + pad)
}

fn grid(n: usize) -> (usize, usize) {
    let cols = n.clamp(1, COLUMNS);
    (n.div_ceil(cols).max(1), cols)
}

fn legend(area: &DrawingArea<SVGBackend, Shift>, title: &str, temps: &[f64]) -> DrawResult {
    area.draw(&Text::new(
        title.to_string(),
        (10, 6),
        (FONT, 16).into_font(),
    ))?;
    let y = 40;
    area.draw(&Text::new(
        "solid + dots: measured, dashed: simulated;".to_string(),
        (10, y - 8),
        (FONT, 12).into_font(),
    ))?;
    let mut x = 300;
    for (i, t) in temps.iter().enumerate() {
        let c = temp_colour(i);
        area.draw(&PathElement::new(
            vec![(x, y - 2), (x + 24, y - 2)],
            c.stroke_width(2),
        ))?;
        area.draw(&Text::new(
            format!("{t} degC"),
            (x + 30, y - 8),
            (FONT, 12).into_font(),
        ))?;
        x += 110;
    }
    Ok(())
}

/// The per-sample curves figure of one sweep.
fn curves_svg(
    rows: &[TestRow],
    outcomes: &[TestOutcome],
    sweep: Sweep,
    fixed: f64,
    idx: &[usize],
) -> Result<String, Box<dyn std::error::Error>> {
    let samples = sample_ids(&idx.iter().map(|&i| rows[i].clone()).collect::<Vec<_>>());
    let temps = temperatures(rows, idx);
    let (nr, nc) = grid(samples.len());
    let size = (PANEL.0 * nc as u32 + 20, PANEL.1 * nr as u32 + HEADER + 10);
    let (xlo, xhi) = range(idx.iter().map(|&i| sweep.x(&rows[i])), 1.0);
    let (ylo, yhi) = range(
        idx.iter()
            .flat_map(|&i| [outcomes[i].eta_v_meas, outcomes[i].eta_v_sim]),
        0.005,
    );
    let (title, xdesc) = match sweep {
        Sweep::Pressure => (
            format!("Volumetric efficiency vs delivery pressure at {fixed} rpm"),
            "p (bar)",
        ),
        Sweep::Speed => (
            format!("Volumetric efficiency vs speed at {fixed} bar"),
            "n (rpm)",
        ),
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(HEADER);
        legend(&top, &title, &temps)?;
        let body = body.margin(0, 10, 10, 10);
        let panels = body.split_evenly((nr, nc));
        for (panel, sample) in panels.iter().zip(&samples) {
            let mut chart = ChartBuilder::on(panel)
                .caption(sample, (FONT, 13))
                .margin(4)
                .x_label_area_size(30)
                .y_label_area_size(42)
                .build_cartesian_2d(xlo..xhi, ylo..yhi)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(5)
                .y_labels(5)
                .x_desc(xdesc)
                .y_desc("eta_v")
                .y_label_formatter(&|v| format!("{v:.3}"))
                .x_label_formatter(&|v| format!("{v}"))
                .label_style((FONT, 10))
                .draw()?;
            for (ti, t) in temps.iter().enumerate() {
                let c = temp_colour(ti);
                let mut pts: Vec<(f64, f64, f64)> = idx
                    .iter()
                    .filter(|&&i| {
                        rows[i].sample == *sample && key(rows[i].condition.temp_c) == key(*t)
                    })
                    .map(|&i| {
                        (
                            sweep.x(&rows[i]),
                            outcomes[i].eta_v_meas,
                            outcomes[i].eta_v_sim,
                        )
                    })
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                let meas: Vec<(f64, f64)> = pts
                    .iter()
                    .filter(|p| p.1.is_finite())
                    .map(|p| (p.0, p.1))
                    .collect();
                let sim: Vec<(f64, f64)> = pts
                    .iter()
                    .filter(|p| p.2.is_finite())
                    .map(|p| (p.0, p.2))
                    .collect();
                chart.draw_series(LineSeries::new(meas.clone(), c.stroke_width(1)))?;
                chart.draw_series(meas.iter().map(|&p| Circle::new(p, 2, c.filled())))?;
                chart.draw_series(DashedLineSeries::new(sim, 5, 3, c.stroke_width(1)))?;
            }
        }
        root.present()?;
    }
    Ok(svg)
}

/// The residual figure: d against each feature.
fn residuals_svg(
    rows: &[TestRow],
    outcomes: &[TestOutcome],
) -> Result<String, Box<dyn std::error::Error>> {
    type Feature = (&'static str, fn(&TestRow) -> f64);
    let features: [Feature; 7] = [
        ("pressure (bar)", |r| r.condition.pressure_bar),
        ("speed (rpm)", |r| r.condition.speed_rpm),
        ("temperature (degC)", |r| r.condition.temp_c),
        ("tip clearance, driving (um)", |r| {
            m_to_um(r.tip_clearance[0])
        }),
        ("tip clearance, driven (um)", |r| {
            m_to_um(r.tip_clearance[1])
        }),
        ("bearing clearance, driving (um)", |r| {
            m_to_um(r.bearing_clearance[0])
        }),
        ("bearing clearance, driven (um)", |r| {
            m_to_um(r.bearing_clearance[1])
        }),
    ];
    let all: Vec<usize> = (0..rows.len()).collect();
    let temps = temperatures(rows, &all);
    let dmax = outcomes
        .iter()
        .map(|o| o.d.abs())
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    let yh = (1.15 * dmax).max(1.0e-3);
    let (nr, nc) = (2usize, 4usize);
    let size = (PANEL.0 * nc as u32 + 20, PANEL.1 * nr as u32 + HEADER + 10);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(HEADER);
        top.draw(&Text::new(
            "Residual d = eta_v,meas - eta_v,sim against each feature".to_string(),
            (10, 6),
            (FONT, 16).into_font(),
        ))?;
        let mut x = 10;
        for (i, t) in temps.iter().enumerate() {
            top.draw(&Circle::new((x + 4, 36), 3, temp_colour(i).filled()))?;
            top.draw(&Text::new(
                format!("{t} degC"),
                (x + 12, 30),
                (FONT, 12).into_font(),
            ))?;
            x += 100;
        }
        let body = body.margin(0, 10, 10, 10);
        let panels = body.split_evenly((nr, nc));
        for (panel, (name, f)) in panels.iter().zip(features.iter()) {
            let (xlo, xhi) = range(rows.iter().map(f), 1.0);
            let mut chart = ChartBuilder::on(panel)
                .margin(4)
                .x_label_area_size(30)
                .y_label_area_size(48)
                .build_cartesian_2d(xlo..xhi, -yh..yh)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(5)
                .y_labels(5)
                .x_desc(*name)
                .y_desc("d")
                .y_label_formatter(&|v| format!("{v:.3}"))
                .x_label_formatter(&|v| format!("{v}"))
                .label_style((FONT, 10))
                .draw()?;
            chart.draw_series(LineSeries::new(
                vec![(xlo, 0.0), (xhi, 0.0)],
                RGBColor(120, 120, 120).stroke_width(1),
            ))?;
            chart.draw_series(
                rows.iter()
                    .zip(outcomes)
                    .filter(|(_, o)| o.d.is_finite())
                    .map(|(r, o)| {
                        let c = temp_colour(temp_index(&temps, r.condition.temp_c));
                        Circle::new((f(r), o.d), 2, c.filled())
                    }),
            )?;
        }
        root.present()?;
    }
    Ok(svg)
}

fn save(
    out: &Path,
    file: &str,
    svg: Result<String, Box<dyn std::error::Error>>,
) -> Result<(), RunError> {
    let text = svg.map_err(|e| RunError::Plot {
        file: file.to_string(),
        message: e.to_string(),
    })?;
    atomic_write_text(&out.join(file), &text)?;
    Ok(())
}

/// The loss budget per working condition as stacked bars.
fn losses_svg(
    rows: &[TestRow],
    outcomes: &[TestOutcome],
) -> Result<String, Box<dyn std::error::Error>> {
    const NAMES: [&str; 6] = [
        "tip, pressure-driven",
        "tip, drag",
        "lateral faces",
        "bearings",
        "meshing zone, grooves",
        "compressibility, ports",
    ];
    let groups = crate::group_by_condition(rows);
    // mean budget (%) and mean 1 - eta_v,sim (%) per condition
    let mut bars: Vec<(String, [f64; 6], f64)> = Vec::new();
    for g in &groups {
        let ok: Vec<&TestOutcome> = g
            .rows
            .iter()
            .map(|&i| &outcomes[i])
            .filter(|o| o.losses.iter().all(|v| v.is_finite()))
            .collect();
        if ok.is_empty() {
            continue;
        }
        let n = ok.len() as f64;
        let mut mean = [0.0; 6];
        for o in &ok {
            for (m, v) in mean.iter_mut().zip(o.losses) {
                *m += 100.0 * v / n;
            }
        }
        let deficit = ok.iter().map(|o| 100.0 * (1.0 - o.eta_v_sim)).sum::<f64>() / n;
        let c = g.condition;
        let label = format!("{}/{}/{}", c.pressure_bar, c.speed_rpm, c.temp_c);
        bars.push((label, mean, deficit));
    }
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for (_, m, d) in &bars {
        let up: f64 = m.iter().filter(|v| **v > 0.0).sum();
        let down: f64 = m.iter().filter(|v| **v < 0.0).sum();
        hi = hi.max(up).max(*d);
        lo = lo.min(down);
    }
    let (lo, hi) = (1.1 * lo - 0.5, 1.1 * hi + 0.5);
    let nb = bars.len().max(1);
    let size = (90 * nb as u32 + 260, 520);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        let (plot, legend) = root.split_horizontally(90 * nb as u32 + 70);
        let mut chart = ChartBuilder::on(&plot)
            .caption(
                "Where the flow goes (bar / rpm / degC)",
                (FONT, 16).into_font(),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(0.0..nb as f64, lo..hi)?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .y_desc("% of Vm n")
            .label_style((FONT, 10))
            .draw()?;
        // each bar's condition under it
        chart.draw_series(bars.iter().enumerate().map(|(i, b)| {
            Text::new(
                b.0.clone(),
                (i as f64 + 0.1, lo + 0.03 * (hi - lo)),
                (FONT, 10).into_font(),
            )
        }))?;
        for (i, (_, m, d)) in bars.iter().enumerate() {
            let x0 = i as f64 + 0.15;
            let x1 = i as f64 + 0.85;
            let (mut up, mut down) = (0.0, 0.0);
            for (j, v) in m.iter().enumerate() {
                let c = crate::figures::COLOURS[j % crate::figures::COLOURS.len()];
                let (a, b) = if *v >= 0.0 {
                    let r = (up, up + v);
                    up += v;
                    r
                } else {
                    let r = (down + v, down);
                    down += v;
                    r
                };
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(x0, a), (x1, b)],
                    c.filled(),
                )))?;
            }
            chart.draw_series(LineSeries::new(
                vec![(x0 - 0.05, *d), (x1 + 0.05, *d)],
                BLACK.stroke_width(2),
            ))?;
        }
        for (j, name) in NAMES.iter().enumerate() {
            let y = 40 + 22 * j as i32;
            let c = crate::figures::COLOURS[j % crate::figures::COLOURS.len()];
            legend.draw(&Rectangle::new([(5, y), (19, y + 12)], c.filled()))?;
            legend.draw(&Text::new(
                name.to_string(),
                (25, y),
                (FONT, 12).into_font(),
            ))?;
        }
        let y = 40 + 22 * NAMES.len() as i32;
        legend.draw(&PathElement::new(
            vec![(5, y + 6), (19, y + 6)],
            BLACK.stroke_width(2),
        ))?;
        legend.draw(&Text::new(
            "1 - eta_v,sim".to_string(),
            (25, y),
            (FONT, 12).into_font(),
        ))?;
        root.present()?;
    }
    Ok(svg)
}

/// Writes every figure into `out` (atomically) and returns them in order.
pub fn write_plots(
    out: &Path,
    rows: &[TestRow],
    outcomes: &[TestOutcome],
) -> Result<Vec<Figure>, RunError> {
    let mut figures = Vec::new();
    for (sweep, file) in [
        (Sweep::Pressure, "curves_pressure.svg"),
        (Sweep::Speed, "curves_speed.svg"),
    ] {
        if let Some((fixed, idx)) = find_sweep(rows, sweep) {
            save(out, file, curves_svg(rows, outcomes, sweep, fixed, &idx))?;
            let caption = match sweep {
                Sweep::Pressure => format!(
                    "Measured (solid) and simulated (dashed) eta_v against delivery pressure at {fixed} rpm, per sample (cf. seed Figs. 11-12)"
                ),
                Sweep::Speed => format!(
                    "Measured (solid) and simulated (dashed) eta_v against speed at {fixed} bar, per sample (cf. seed Figs. 13-14)"
                ),
            };
            figures.push(Figure {
                file: file.to_string(),
                caption,
            });
        }
    }
    save(out, "residuals.svg", residuals_svg(rows, outcomes))?;
    if outcomes
        .iter()
        .any(|o| o.losses.iter().all(|v| v.is_finite()))
    {
        save(out, "losses.svg", losses_svg(rows, outcomes))?;
        figures.push(Figure {
            file: "losses.svg".to_string(),
            caption: "Where the flow goes: simulated loss budget per working condition (mean over the samples), % of Vm n; losses up, gains (drag) down; the bar marks 1 - eta_v,sim".to_string(),
        });
    }
    figures.push(Figure {
        file: "residuals.svg".to_string(),
        caption: "Residual d against pressure, speed, temperature and each measured clearance"
            .to_string(),
    });
    Ok(figures)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::parse_campaign_str;

    #[test]
    fn campaign_plots_sweep_detection() {
        let mut text = String::from("sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\n");
        for (p, n) in [(10, 1000), (20, 1000), (30, 1000), (30, 500), (30, 2000)] {
            text.push_str(&format!("N1,30,30,12,12,{p},{n},60,10,\n"));
        }
        let c = parse_campaign_str("c.csv", &text).unwrap();
        let (fixed, idx) = find_sweep(&c.rows, Sweep::Pressure).unwrap();
        assert_eq!((fixed, idx), (1000.0, vec![0, 1, 2]));
        let (fixed, idx) = find_sweep(&c.rows, Sweep::Speed).unwrap();
        assert_eq!((fixed, idx), (30.0, vec![2, 3, 4]));
        assert_eq!(range([1.0, 1.0].into_iter(), 0.5), (0.5, 1.5));
        assert_eq!(grid(20), (4, 5));
        assert_eq!(grid(3), (1, 3));
    }
}
