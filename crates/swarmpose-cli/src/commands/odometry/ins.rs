//! The Karlsruhe sequences' evaluation: their rough INS positions against the estimate.

use std::path::Path;

use nalgebra::{Isometry3, Point3};

/// Karlsruhe has no camera ground truth, only rough INS positions of the vehicle in
/// another frame: the ATE of our positions after their SE(3) Umeyama alignment, as a line
/// to print (`None` without INS data).
pub(crate) fn ins_summary(dir: &Path, poses: &[Isometry3<f64>]) -> Option<String> {
    let ins =
        swarmpose_datasets::karlsruhe::KarlsruheSequence::open(dir).and_then(|k| k.ins_positions());
    let Ok(Some(ins)) = ins else {
        return None;
    };
    if ins.len() != poses.len() {
        return None;
    }
    let x: Vec<Point3<f64>> = poses
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let y: Vec<Point3<f64>> = ins.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
    let t = swarmpose_eval::metrics::umeyama(&x, &y).ok()?;
    let ate: Vec<f64> = x.iter().zip(&y).map(|(a, b)| (b - t * a).norm()).collect();
    let stats = swarmpose_eval::Stats::of(&ate);
    let length: f64 = y.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let last = ate.last().copied().unwrap_or(0.0);
    Some(format!(
        "vs INS positions (insdata.txt, after SE(3) alignment): path {length:.2} m, ATE {:.3} m ({:.2} % of the path), final position error {last:.3} m ({:.2} %)",
        stats.rmse,
        100.0 * stats.rmse / length.max(1e-9),
        100.0 * last / length.max(1e-9)
    ))
}
