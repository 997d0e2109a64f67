//! The plots of a run, rendered in memory (the caller writes them): `trajectory.png`/
//! `.svg`, the top view (x right, z forward) of the estimated trajectory against the
//! ground truth as in the paper's figure 17, and `errors.png`, the per-frame rotation
//! error (eq. 20 of the relative rotations) and translation error (RPE, 1 frame).

use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use nalgebra::Isometry3;
use plotters::coord::Shift;
use plotters::prelude::*;
use swarmpose_eval::Evaluation;

use crate::error::RunError;

/// DejaVu Sans, the copy `swarmpose-sim` ships (Bitstream Vera license, see
/// `crates/swarmpose-sim/assets/DejaVuSans-LICENSE.txt`).
use swarmpose_sim::plots::font::{FAMILY, register_font};
const EST: RGBColor = RGBColor(214, 39, 40);
const GT: RGBColor = RGBColor(31, 119, 180);

/// The estimated trajectory to draw.
#[derive(Debug, Clone, Copy)]
pub struct PlotTrack<'a> {
    /// Camera poses.
    pub poses: &'a [Isometry3<f64>],
    /// For each pose, true when its motion was not tracked (drawn as a cross).
    pub predicted: &'a [bool],
    /// Legend label (method and detector).
    pub label: &'a str,
}

fn err(path: &Path, e: impl std::fmt::Display) -> RunError {
    RunError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

fn top_view(poses: &[Isometry3<f64>]) -> Vec<(f64, f64)> {
    poses
        .iter()
        .map(|p| (p.translation.vector.x, p.translation.vector.z))
        .collect()
}

/// Square ranges holding every point, so the top view keeps its aspect.
fn square_ranges(points: &[(f64, f64)], w: u32, h: u32) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        return ((-1.0, 1.0), (-1.0, 1.0));
    }
    let aspect = f64::from(w) / f64::from(h);
    let span = ((x1 - x0) / aspect).max(y1 - y0).max(0.05) * 1.1;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    (
        (cx - span * aspect / 2.0, cx + span * aspect / 2.0),
        (cy - span / 2.0, cy + span / 2.0),
    )
}

fn draw_trajectory<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    run: &PlotTrack<'_>,
    gt: Option<&[Isometry3<f64>]>,
    title: &str,
    path: &Path,
) -> Result<(), RunError> {
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let est = top_view(run.poses);
    let truth = gt.map(top_view).unwrap_or_default();
    let all: Vec<(f64, f64)> = est.iter().chain(&truth).copied().collect();
    let (w, h) = root.dim_in_pixel();
    let ((x0, x1), (y0, y1)) = square_ranges(&all, w.saturating_sub(110), h.saturating_sub(120));
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 24))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("x (m, right)")
        .y_desc("z (m, forward)")
        .label_style((FAMILY, 15))
        .axis_desc_style((FAMILY, 17))
        .light_line_style(BLACK.mix(0.04))
        .draw()
        .map_err(|e| err(path, e))?;
    if !truth.is_empty() {
        chart
            .draw_series(LineSeries::new(truth.clone(), GT.stroke_width(3)))
            .map_err(|e| err(path, e))?
            .label("ground truth")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], GT.stroke_width(3)));
        chart
            .draw_series(truth.iter().map(|&p| Circle::new(p, 3, GT.filled())))
            .map_err(|e| err(path, e))?;
    }
    chart
        .draw_series(LineSeries::new(est.clone(), EST.stroke_width(2)))
        .map_err(|e| err(path, e))?
        .label(run.label)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], EST.stroke_width(2)));
    chart
        .draw_series(est.iter().zip(run.predicted).map(|(&p, &predicted)| {
            if predicted {
                Cross::new(p, 7, BLACK.stroke_width(2)).into_dyn()
            } else {
                Circle::new(p, 3, EST.filled()).into_dyn()
            }
        }))
        .map_err(|e| err(path, e))?;
    chart
        .configure_series_labels()
        .label_font((FAMILY, 16))
        .border_style(BLACK.mix(0.3))
        .background_style(WHITE.mix(0.9))
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(|e| err(path, e))?;
    root.present().map_err(|e| err(path, e))
}

fn draw_errors<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    e: &Evaluation,
    path: &Path,
) -> Result<(), RunError> {
    root.fill(&WHITE).map_err(|x| err(path, x))?;
    let (top, bottom) = root.split_vertically(root.dim_in_pixel().1 / 2);
    let panels = [
        (
            &top,
            format!(
                "rotation error per frame, eq. (20) of the relative rotation (RMS {:.5})",
                e.eq20_rms
            ),
            "||I - R_gt R^T||_F",
            &e.eq20_per_frame,
        ),
        (
            &bottom,
            format!(
                "translation error per frame, RPE 1 frame (RMSE {:.4} m)",
                e.rpe_translation.rmse
            ),
            "m",
            &e.rpe_translation_per_frame,
        ),
    ];
    for (area, caption, unit, values) in panels {
        let n = values.len().max(1) as f64;
        let hi = values.iter().copied().fold(0.0f64, f64::max).max(1e-6) * 1.15;
        let mut chart = ChartBuilder::on(area)
            .caption(caption, (FAMILY, 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(0.5..n + 0.5, 0.0..hi)
            .map_err(|x| err(path, x))?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc(unit)
            .label_style((FAMILY, 14))
            .axis_desc_style((FAMILY, 16))
            .light_line_style(BLACK.mix(0.04))
            .draw()
            .map_err(|x| err(path, x))?;
        let pts: Vec<(f64, f64)> = values
            .iter()
            .enumerate()
            .map(|(k, &v)| ((k + 1) as f64, v))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), EST.stroke_width(2)))
            .map_err(|x| err(path, x))?;
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, EST.filled())))
            .map_err(|x| err(path, x))?;
    }
    root.present().map_err(|x| err(path, x))
}

fn encode_png(path: &Path, buf: &[u8], size: (u32, u32)) -> Result<Vec<u8>, RunError> {
    let mut out = Vec::new();
    PngEncoder::new_with_quality(&mut out, CompressionType::Default, FilterType::Adaptive)
        .write_image(buf, size.0, size.1, ExtendedColorType::Rgb8)
        .map_err(|e| err(path, e))?;
    Ok(out)
}

/// The plots of a run: `(file name, bytes)` of `trajectory.png`, `trajectory.svg` and,
/// with an evaluation, `errors.png`.
///
/// # Errors
/// [`RunError::Write`] naming the plot that could not be drawn.
pub fn render_plots(
    run: &PlotTrack<'_>,
    title: &str,
    gt: Option<&[Isometry3<f64>]>,
    evaluation: Option<&Evaluation>,
) -> Result<Vec<(&'static str, Vec<u8>)>, RunError> {
    // Without the font the labels are missing; the figure is still drawn.
    let _ = register_font();
    let mut out = Vec::new();
    let size = (1000u32, 1000u32);
    let png = Path::new("trajectory.png");
    let mut buf = vec![0u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw_trajectory(&root, run, gt, title, png)?;
    }
    out.push(("trajectory.png", encode_png(png, &buf, size)?));
    let svg = Path::new("trajectory.svg");
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        draw_trajectory(&root, run, gt, title, svg)?;
    }
    out.push(("trajectory.svg", text.into_bytes()));
    if let Some(e) = evaluation {
        let size = (1200u32, 800u32);
        let path = Path::new("errors.png");
        let mut buf = vec![0u8; size.0 as usize * size.1 as usize * 3];
        {
            let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
            draw_errors(&root, e, path)?;
        }
        out.push(("errors.png", encode_png(path, &buf, size)?));
    }
    Ok(out)
}
