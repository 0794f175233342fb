//! Drawing figures with plotters (the `plots` feature): PNG and SVG from the same
//! description, with an embedded DejaVu Sans font so that no system font (and no fontconfig)
//! is needed.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::plot::{Figure, Panel, PlotError, Style};

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(100, 100, 100),
    RGBColor(23, 190, 207),
    RGBColor(188, 189, 34),
];

fn register_fonts() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TTF shipped by the `dejavu` crate; failure would be a build bug.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
        let _ = plotters::style::register_font("sans-serif", FontStyle::Bold, dejavu::sans::bold());
    });
}

fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (1.0, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        return (lo / 1.1, hi * 1.1);
    }
    let span = (hi - lo).max(1e-12 * hi.abs().max(1.0));
    (lo - 0.05 * span, hi + 0.05 * span)
}

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel) -> Result<(), String> {
    let xr = panel
        .x_range
        .unwrap_or_else(|| range(panel.series.iter().flat_map(|s| s.points.iter().map(|p| p.0)), panel.x_log));
    let yr = panel
        .y_range
        .unwrap_or_else(|| range(panel.series.iter().flat_map(|s| s.points.iter().map(|p| p.1)), panel.y_log));
    let mut builder = ChartBuilder::on(area);
    builder.caption(&panel.title, ("sans-serif", 20)).margin(12).x_label_area_size(44).y_label_area_size(70);
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    macro_rules! body {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(&panel.x_label)
                .y_desc(&panel.y_label)
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 15))
                .draw()
                .map_err(e)?;
            for (i, s) in panel.series.iter().enumerate() {
                let color = PALETTE[i % PALETTE.len()];
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|(x, y)| {
                        x.is_finite() && y.is_finite() && (!panel.x_log || *x > 0.0) && (!panel.y_log || *y > 0.0)
                    })
                    .collect();
                match s.style {
                    Style::Line => chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                        .map_err(e)?
                        .label(s.name.clone())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))),
                    Style::Points => chart
                        .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                        .map_err(e)?
                        .label(s.name.clone())
                        .legend(move |(x, y)| Circle::new((x + 9, y), 3, color.filled())),
                };
            }
            if panel.series.len() > 1 {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 13))
                    .position(SeriesLabelPosition::UpperLeft)
                    .draw()
                    .map_err(e)?;
            }
        }};
    }
    match (panel.x_log, panel.y_log) {
        (true, true) => {
            body!(builder.build_cartesian_2d((xr.0..xr.1).log_scale(), (yr.0..yr.1).log_scale()).map_err(e)?)
        }
        (true, false) => body!(builder.build_cartesian_2d((xr.0..xr.1).log_scale(), yr.0..yr.1).map_err(e)?),
        (false, true) => body!(builder.build_cartesian_2d(xr.0..xr.1, (yr.0..yr.1).log_scale()).map_err(e)?),
        (false, false) => body!(builder.build_cartesian_2d(xr.0..xr.1, yr.0..yr.1).map_err(e)?),
    }
    Ok(())
}

fn draw_figure<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let n = fig.panels.len().max(1);
    let areas = root.split_evenly((1, n));
    for (area, panel) in areas.iter().zip(&fig.panels) {
        draw_panel(area, panel)?;
    }
    root.present().map_err(|e| e.to_string())
}

/// Draws `dir/stem.png` and `dir/stem.svg`; returns their paths.
pub(super) fn draw(fig: &Figure, dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    register_fonts();
    let w = 560 * fig.panels.len().max(1) as u32;
    let h = 480;
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    draw_figure(BitMapBackend::new(&png, (w, h)).into_drawing_area(), fig)
        .map_err(|message| PlotError { path: png.clone(), message })?;
    draw_figure(SVGBackend::new(&svg, (w, h)).into_drawing_area(), fig)
        .map_err(|message| PlotError { path: svg.clone(), message })?;
    Ok(vec![png, svg])
}
