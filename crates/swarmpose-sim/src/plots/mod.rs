//! The figures: `position_error` (the paper's figure 6), `processing_time` (figure 7),
//! `rotation_error` and `success_rate`, each as PNG and SVG with one panel per noise
//! level, outlier fraction on the x axis and, per estimator, the median as a line with
//! the interquartile range as a band.

mod draw;

use std::path::{Path, PathBuf};

use crate::error::SimError;
use crate::stats::{Cell, Quartiles, Summary};

pub mod font;

pub use draw::{Figure, Panel, Series, render_png, render_svg};

/// Figure size in pixels.
pub const SIZE: (u32, u32) = (1400, 1000);

/// The file stems of the four figures.
pub const FIGURES: [&str; 4] = [
    "position_error",
    "processing_time",
    "rotation_error",
    "success_rate",
];

fn panels(s: &Summary, value: &dyn Fn(&Cell) -> Quartiles) -> Vec<Panel> {
    s.noise_levels
        .iter()
        .enumerate()
        .map(|(i, noise)| Panel {
            caption: format!("noise σ = {noise} m"),
            series: s
                .estimators
                .iter()
                .enumerate()
                .map(|(e, name)| Series {
                    name: name.clone(),
                    points: s
                        .fractions
                        .iter()
                        .zip(&s.cells[e][i])
                        .map(|(f, c)| (100.0 * f, value(c)))
                        .collect(),
                })
                .collect(),
        })
        .collect()
}

/// The four figures of a summary.
#[must_use]
pub fn figures(s: &Summary) -> Vec<Figure> {
    let band = "line: median of the runs, band: interquartile range";
    let inf = "runs without a pose count as infinite error (drawn at the top edge)";
    let rate = |c: &Cell| {
        let p = c.success_pct();
        Quartiles {
            q1: p,
            median: p,
            q3: p,
        }
    };
    vec![
        Figure {
            name: "position_error".into(),
            title: "Position error against outliers (cf. paper fig. 6)".into(),
            y_label: "position error |t_est - t_true| (m)".into(),
            log_y: true,
            y_floor: 1e-6,
            bands: true,
            no_pose_edge: true,
            note: format!("{band}; {inf}; log scale, values below 1e-6 m drawn at 1e-6"),
            panels: panels(s, &|c| c.position_m),
        },
        Figure {
            name: "processing_time".into(),
            title: "Processing time against outliers (cf. paper fig. 7)".into(),
            y_label: "time per estimation (ms)".into(),
            log_y: true,
            y_floor: 1e-3,
            bands: true,
            no_pose_edge: false,
            note: format!("{band}; log scale; wall time of one call on one worker thread"),
            panels: panels(s, &|c| c.time_ms),
        },
        Figure {
            name: "rotation_error".into(),
            title: "Rotation error against outliers".into(),
            y_label: "rotation error (deg)".into(),
            log_y: true,
            y_floor: 1e-6,
            bands: true,
            no_pose_edge: true,
            note: format!("{band}; {inf}; log scale, values below 1e-6 deg drawn at 1e-6"),
            panels: panels(s, &|c| c.rotation_deg),
        },
        Figure {
            name: "success_rate".into(),
            title: "Success rate against outliers".into(),
            y_label: "success rate (%)".into(),
            log_y: false,
            y_floor: 0.0,
            bands: false,
            no_pose_edge: false,
            note: "success: rotation error < 2 deg and position error < 0.2 m; no pose = failure"
                .into(),
            panels: panels(s, &rate),
        },
    ]
}

/// Draws the four figures into `dir` as `NAME.png` and `NAME.svg`; returns the paths.
///
/// # Errors
/// [`SimError::Plot`] when drawing or saving fails.
pub fn write_figures(s: &Summary, dir: &Path) -> Result<Vec<PathBuf>, SimError> {
    let mut paths = Vec::new();
    for fig in figures(s) {
        let png = dir.join(format!("{}.png", fig.name));
        let svg = dir.join(format!("{}.svg", fig.name));
        render_png(&fig, &png, SIZE)?;
        render_svg(&fig, &svg, SIZE)?;
        paths.push(png);
        paths.push(svg);
    }
    Ok(paths)
}
