//! `swarmpose evaluate --kitti-segments`: the KITTI devkit's segment errors as a table
//! (per length and over all segments) and, with `--segment-plot FILE.svg`, the devkit's
//! two plots (translation error in percent and rotation error in degrees per 100 m,
//! against the segment length).

use std::fmt::Write as _;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use swarmpose_eval::KittiSegments;

use crate::error::CliError;
use crate::output_file::write_bytes;

/// DejaVu Sans, the copy `swarmpose-sim` ships (Bitstream Vera license, see
/// `crates/swarmpose-sim/assets/DejaVuSans-LICENSE.txt`).
use swarmpose_sim::plots::font::{FAMILY, register_font};
const LINE: RGBColor = RGBColor(214, 39, 40);

/// The segment table printed on standard output.
#[must_use]
pub fn segment_table(k: &KittiSegments, estimate: &Path) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}: {}", estimate.display(), k.note);
    if k.scale != 1.0 {
        let _ = writeln!(
            s,
            "NOTE: segment lengths scaled by {} (--segment-scale): these are not the KITTI \
             benchmark's figures",
            k.scale
        );
    }
    let _ = writeln!(
        s,
        "{:>10} {:>9} {:>18} {:>22}",
        "length m", "segments", "translation %", "rotation deg/100 m"
    );
    for l in &k.per_length {
        let _ = writeln!(
            s,
            "{:>10.1} {:>9} {:>18.6} {:>22.6}",
            l.length_m, l.n, l.translation_percent, l.rotation_deg_per_100m
        );
    }
    if let (Some(t), Some(r)) = (k.translation_percent, k.rotation_deg_per_100m) {
        let _ = writeln!(
            s,
            "{:>10} {:>9} {t:>18.6} {r:>22.6}",
            "all",
            k.segments.len()
        );
    }
    s
}

/// One panel: `(length, value)` points with a line, as the devkit's gnuplot figures.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    points: &[(f64, f64)],
    (caption, y_desc): (&str, &str),
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let x_max = points.iter().map(|p| p.0).fold(0.0, f64::max) * 1.1;
    let y_max = points.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-9) * 1.15;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FAMILY, 20))
        .margin(14)
        .x_label_area_size(46)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..x_max.max(1e-9), 0.0..y_max)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("path length (m)")
        .y_desc(y_desc)
        .x_label_formatter(&|v| format!("{v:.0}"))
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(BLACK.mix(0.04))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(LineSeries::new(points.to_vec(), LINE.stroke_width(2)))
        .map_err(e)?;
    chart
        .draw_series(points.iter().map(|&p| Circle::new(p, 4, LINE.filled())))
        .map_err(e)?;
    Ok(())
}

/// Renders the two plots of `k` as SVG text.
///
/// # Errors
/// What plotters reports.
pub fn segment_svg(k: &KittiSegments, title: &str) -> Result<String, String> {
    // Without the font the labels are missing; the figure is still drawn.
    let _ = register_font();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1100, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, (FAMILY, 18))
            .map_err(|e| e.to_string())?;
        let (left, right) = root.split_horizontally(550);
        let t: Vec<_> = k
            .per_length
            .iter()
            .map(|l| (l.length_m, l.translation_percent))
            .collect();
        let r: Vec<_> = k
            .per_length
            .iter()
            .map(|l| (l.length_m, l.rotation_deg_per_100m))
            .collect();
        panel(&left, &t, ("Translation error", "translation error (%)"))?;
        panel(&right, &r, ("Rotation error", "rotation error (deg/100 m)"))?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Writes the plots of `k` to `path` (SVG).
///
/// # Errors
/// Exit status 2 unless `path` ends in `.svg` and is not an existing non-regular file; 1 when it cannot be written.
pub fn write_segment_plot(k: &KittiSegments, estimate: &Path, path: &Path) -> Result<(), CliError> {
    if path.extension().and_then(|e| e.to_str()) != Some("svg") {
        return Err(CliError::usage(format!(
            "{}: --segment-plot writes SVG, the file name must end in .svg",
            path.display()
        )));
    }
    if std::fs::symlink_metadata(path).is_ok_and(|m| !m.is_file()) {
        return Err(CliError::usage(format!(
            "{}: exists and is not a regular file; not replaced",
            path.display()
        )));
    }
    let scaled = if k.scale == 1.0 {
        String::new()
    } else {
        format!(" (lengths x {}: not the KITTI figures)", k.scale)
    };
    let title = format!("KITTI segment errors of {}{scaled}", estimate.display());
    let svg = segment_svg(k, &title).map_err(|e| CliError::failure(format!("plot: {e}")))?;
    write_bytes(path, svg.as_bytes())
}
