//! Figures of a simulation (SVG, plotters): gear centre loci over a mesh
//! period and pocket pressure round the gears. Writes go to a temporary file
//! renamed into place.

use plotters::prelude::*;
use std::path::Path;

/// A named series of (x, y) points.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// The series colours of the project's figures, in order.
pub const COLOURS: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(174, 199, 232),
];

fn bounds(series: &[&Series]) -> ((f64, f64), (f64, f64)) {
    let mut x = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y = (f64::INFINITY, f64::NEG_INFINITY);
    for s in series {
        for &(a, b) in &s.points {
            if a.is_finite() && b.is_finite() {
                x = (x.0.min(a), x.1.max(a));
                y = (y.0.min(b), y.1.max(b));
            }
        }
    }
    let pad = |r: (f64, f64)| {
        if !r.0.is_finite() {
            return (0.0, 1.0);
        }
        let d = (r.1 - r.0).abs().max(1e-9) * 0.08;
        (r.0 - d, r.1 + d)
    };
    (pad(x), pad(y))
}

/// Line plots in side-by-side panels, one per (title, series list), to `path`.
pub fn panels(
    path: &Path,
    panels: &[(&str, Vec<Series>)],
    x_label: &str,
    y_label: &str,
    equal_axes: bool,
) -> Result<(), String> {
    let tmp = path.with_extension("svg.tmp");
    {
        let width = 520 * panels.len() as u32;
        let root = SVGBackend::new(&tmp, (width, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let areas = root.split_evenly((1, panels.len()));
        for (area, (title, series)) in areas.iter().zip(panels) {
            let refs: Vec<&Series> = series.iter().collect();
            let ((mut x0, mut x1), (mut y0, mut y1)) = bounds(&refs);
            if equal_axes {
                let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
                let h = (x1 - x0).max(y1 - y0) / 2.0;
                (x0, x1, y0, y1) = (cx - h, cx + h, cy - h, cy + h);
            }
            let mut chart = ChartBuilder::on(area)
                .caption(*title, ("sans-serif", 18))
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(55)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(y_label)
                .draw()
                .map_err(|e| e.to_string())?;
            for (i, s) in series.iter().enumerate() {
                let c = COLOURS[i % COLOURS.len()];
                chart
                    .draw_series(LineSeries::new(s.points.iter().copied(), c.stroke_width(2)))
                    .map_err(|e| e.to_string())?
                    .label(s.label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], c.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    std::fs::rename(&tmp, path).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_an_svg_with_the_series_labels() {
        let dir = std::env::temp_dir().join(format!("gearpump-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.svg");
        let s = vec![Series {
            label: "10 bar".into(),
            points: (0..20).map(|i| (i as f64, (i as f64).sin())).collect(),
        }];
        panels(&path, &[("panel", s)], "x", "y", false).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<svg") && text.contains("10 bar"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
