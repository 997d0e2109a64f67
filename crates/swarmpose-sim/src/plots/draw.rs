//! Drawing one figure with plotters, on a bitmap (saved as PNG with `image`) or SVG.

use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::prelude::*;

use crate::error::SimError;
use crate::stats::Quartiles;

use super::font::FAMILY;

/// One estimator's curve: `(x, quartiles)` per outlier fraction (x in percent).
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend name.
    pub name: String,
    /// Points in x order.
    pub points: Vec<(f64, Quartiles)>,
}

/// One panel (one noise level).
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Caption above the panel.
    pub caption: String,
    /// One curve per estimator.
    pub series: Vec<Series>,
}

/// A figure: panels on a grid of two columns, a title and a footnote.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// File stem.
    pub name: String,
    /// Title on top.
    pub title: String,
    /// Y axis label with its unit.
    pub y_label: String,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Smallest value drawn on a log axis (smaller ones are drawn there).
    pub y_floor: f64,
    /// Draw interquartile bands.
    pub bands: bool,
    /// Label the top edge "no pose" (where runs without a pose are drawn).
    pub no_pose_edge: bool,
    /// Footnote.
    pub note: String,
    /// The panels.
    pub panels: Vec<Panel>,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn register_font() -> Result<(), SimError> {
    if super::font::register_font() {
        Ok(())
    } else {
        Err(SimError::Plot {
            name: "font".into(),
            message: "the embedded font is not a valid TTF".into(),
        })
    }
}

fn plot_err(fig: &Figure, e: impl std::fmt::Display) -> SimError {
    SimError::Plot {
        name: fig.name.clone(),
        message: e.to_string(),
    }
}

/// Y range of the figure: `(lo, hi)` over finite values, clamped at the floor on a log axis.
fn y_range(fig: &Figure) -> (f64, f64) {
    if !fig.log_y {
        return (0.0, 105.0);
    }
    let values = fig
        .panels
        .iter()
        .flat_map(|p| &p.series)
        .flat_map(|s| &s.points)
        .flat_map(|(_, q)| [q.q1, q.median, q.q3])
        .filter(|v| v.is_finite());
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values {
        lo = lo.min(v.max(fig.y_floor));
        hi = hi.max(v.max(fig.y_floor));
    }
    if !(lo.is_finite() && hi > 0.0) {
        return (fig.y_floor, 1.0);
    }
    (lo / 2.0, hi * 3.0)
}

/// Draws `fig` on any backend area.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> Result<(), SimError> {
    root.fill(&WHITE).map_err(|e| plot_err(fig, e))?;
    let (w, h) = root.dim_in_pixel();
    let (body, footer) = root.split_vertically(h.saturating_sub(34));
    footer
        .draw(&Text::new(
            fig.note.clone(),
            (20, 8),
            (FAMILY, 17).into_font().color(&BLACK.mix(0.8)),
        ))
        .map_err(|e| plot_err(fig, e))?;
    let body = body
        .margin(8, 0, 0, 0)
        .titled(&fig.title, (FAMILY, 30).into_font().style(FontStyle::Bold))
        .map_err(|e| plot_err(fig, e))?;
    let cols = if fig.panels.len() > 1 { 2 } else { 1 };
    let rows = fig.panels.len().div_ceil(cols).max(1);
    let (strip, body) = body.split_vertically(36);
    draw_legend(&strip, fig)?;
    let areas = body.split_evenly((rows, cols));
    let (lo, hi) = y_range(fig);
    let xs = fig
        .panels
        .iter()
        .flat_map(|p| &p.series)
        .flat_map(|s| s.points.iter().map(|(x, _)| *x));
    let (xmin, xmax) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let (xmin, xmax) = if xmin.is_finite() {
        (xmin - 3.0, xmax + 3.0)
    } else {
        (0.0, 100.0)
    };
    let _ = w;
    for (panel, area) in fig.panels.iter().zip(&areas) {
        if fig.log_y {
            let fmt = |v: &f64| format!("{v:.0e}");
            draw_panel(
                area,
                fig,
                panel,
                (xmin..xmax, (lo..hi).log_scale()),
                hi,
                &fmt,
            )?;
        } else {
            let fmt = |v: &f64| format!("{v:.0}");
            draw_panel(area, fig, panel, (xmin..xmax, lo..hi), hi, &fmt)?;
        }
    }
    root.present().map_err(|e| plot_err(fig, e))
}

fn draw_panel<DB, Y>(
    area: &DrawingArea<DB, Shift>,
    fig: &Figure,
    panel: &Panel,
    (x, y): (std::ops::Range<f64>, Y),
    top: f64,
    y_fmt: &dyn Fn(&f64) -> String,
) -> Result<(), SimError>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.caption, (FAMILY, 22))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(78)
        .build_cartesian_2d(x, y)
        .map_err(|e| plot_err(fig, e))?;
    chart
        .configure_mesh()
        .x_desc("outliers (% of correspondences)")
        .y_desc(&fig.y_label)
        .y_label_formatter(y_fmt)
        .x_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FAMILY, 15))
        .axis_desc_style((FAMILY, 17))
        .light_line_style(BLACK.mix(0.04))
        .bold_line_style(BLACK.mix(0.12))
        .draw()
        .map_err(|e| plot_err(fig, e))?;
    if fig.no_pose_edge {
        let x0 = chart.x_range().start;
        chart
            .draw_series(std::iter::once(Text::new(
                "no pose (top edge)",
                (x0, top),
                (FAMILY, 14).into_font().color(&BLACK.mix(0.6)),
            )))
            .map_err(|e| plot_err(fig, e))?;
    }
    let floor = fig.y_floor;
    let clamp = |v: f64| {
        if v.is_infinite() {
            top
        } else if fig.log_y {
            v.max(floor)
        } else {
            v
        }
    };
    for (k, s) in panel.series.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let pts: Vec<(f64, Quartiles)> = s
            .points
            .iter()
            .filter(|(_, q)| !q.median.is_nan())
            .copied()
            .collect();
        if fig.bands && pts.len() > 1 {
            let mut poly: Vec<(f64, f64)> = pts.iter().map(|(x, q)| (*x, clamp(q.q3))).collect();
            poly.extend(pts.iter().rev().map(|(x, q)| (*x, clamp(q.q1))));
            chart
                .draw_series(std::iter::once(Polygon::new(
                    poly,
                    color.mix(0.15).filled(),
                )))
                .map_err(|e| plot_err(fig, e))?;
        }
        let line: Vec<(f64, f64)> = pts.iter().map(|(x, q)| (*x, clamp(q.median))).collect();
        // Wider lines first, so a curve hidden under a later one still shows at its edges.
        let width = line_width(k);
        chart
            .draw_series(LineSeries::new(line.clone(), color.stroke_width(width)))
            .map_err(|e| plot_err(fig, e))?;
        chart
            .draw_series(line.iter().map(|&p| EmptyElement::at(p) + marker(k, color)))
            .map_err(|e| plot_err(fig, e))?;
    }
    Ok(())
}

/// Line width of series `k`: 6, 4.5, 3, 2 px...
fn line_width(k: usize) -> u32 {
    [6, 4, 3, 2].get(k).copied().unwrap_or(2)
}

/// The marker of series `k` (pixel offsets around the point).
fn marker<DB: DrawingBackend>(k: usize, color: RGBColor) -> DynElement<'static, DB, (i32, i32)> {
    let style = color.filled();
    match k % 4 {
        0 => Circle::new((0, 0), 6, style).into_dyn(),
        1 => Polygon::new(vec![(0, -7), (6, 5), (-6, 5)], style).into_dyn(),
        2 => Rectangle::new([(-4, -4), (4, 4)], style).into_dyn(),
        _ => Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], style).into_dyn(),
    }
}

/// One legend for the whole figure, in a strip under the title.
fn draw_legend<DB: DrawingBackend>(
    strip: &DrawingArea<DB, Shift>,
    fig: &Figure,
) -> Result<(), SimError> {
    let names: Vec<&str> = fig
        .panels
        .first()
        .map(|p| p.series.iter().map(|s| s.name.as_str()).collect())
        .unwrap_or_default();
    let mut x = 90;
    for (k, name) in names.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let y = 16;
        strip
            .draw(&PathElement::new(
                vec![(x, y), (x + 44, y)],
                color.stroke_width(line_width(k)),
            ))
            .map_err(|e| plot_err(fig, e))?;
        strip
            .draw(&(EmptyElement::at((x + 22, y)) + marker(k, color)))
            .map_err(|e| plot_err(fig, e))?;
        strip
            .draw(&Text::new(name.to_string(), (x + 52, y - 10), (FAMILY, 20)))
            .map_err(|e| plot_err(fig, e))?;
        x += 60 + 12 * name.chars().count() as i32 + 30;
    }
    Ok(())
}
/// Renders `fig` as a PNG file.
///
/// # Errors
/// [`SimError::Plot`] when drawing fails, [`SimError::Io`] when saving fails.
pub fn render_png(fig: &Figure, path: &Path, size: (u32, u32)) -> Result<(), SimError> {
    register_font()?;
    let mut buf = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw(&root, fig)?;
    }
    let mut png = Vec::new();
    let encoder =
        PngEncoder::new_with_quality(&mut png, CompressionType::Best, FilterType::Adaptive);
    encoder
        .write_image(&buf, size.0, size.1, ExtendedColorType::Rgb8)
        .map_err(|e| plot_err(fig, e))?;
    crate::output::write_file(path, png)
}

/// Renders `fig` as an SVG file.
///
/// # Errors
/// [`SimError::Plot`] when drawing or writing fails.
pub fn render_svg(fig: &Figure, path: &Path, size: (u32, u32)) -> Result<(), SimError> {
    register_font()?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw(&root, fig)?;
    }
    crate::output::write_file(path, text)
}
