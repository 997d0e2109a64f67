//! The estimate stage: matches with the reference frame, the robust estimator's motion
//! on their 3D points, and the stereo measurements the refinement takes.

use nalgebra::{Isometry3, Point3};
use swarmpose_core::{Correspondences, Estimator};
use swarmpose_vision::frontend::{DisparityCorrection, FrameMatches};
use swarmpose_vision::stereo::RectifiedStereo;

use crate::refine::model::StereoObservation;
use crate::window::Link;

/// The measurements of the matches in the reference frame A and the current frame B,
/// and the fold of each (alternate vertical stripes of B's image).
#[derive(Debug, Clone, Default)]
pub(crate) struct Observations {
    /// In A (the matches' destination points).
    pub reference: Vec<StereoObservation>,
    /// In B (the matches' source points).
    pub current: Vec<StereoObservation>,
    /// Fold 0 or 1 of each match.
    pub folds: Vec<u8>,
    /// Index of each into the matches.
    pub source: Vec<usize>,
}

/// The stereo measurements of `m` (matches from the current frame B, `src`, to the
/// reference A, `dst`); `stripe_px` is the width of the fold stripes.
pub(crate) fn observations(m: &FrameMatches, stripe_px: f64) -> Observations {
    let obs = |px: &[(f32, f32)], d: &[f64]| -> Vec<StereoObservation> {
        px.iter()
            .zip(d)
            .map(|(&(u, v), &d)| StereoObservation {
                u: f64::from(u),
                v: f64::from(v),
                d,
            })
            .collect()
    };
    let current = obs(&m.src_pixels, &m.src_disparities_px);
    let folds = current
        .iter()
        .map(|z| ((z.u / stripe_px).floor().max(0.0) as u64 % 2) as u8)
        .collect();
    Observations {
        reference: obs(&m.dst_pixels, &m.dst_disparities_px),
        source: (0..current.len()).collect(),
        current,
        folds,
    }
}

/// Median image motion, pixels, of the measurements `inliers` (indices into `obs`)
/// between the reference and the current frame; 0 for none.
pub(crate) fn median_flow_px(obs: &Observations, inliers: &[usize]) -> f64 {
    let mut flows: Vec<f64> = inliers
        .iter()
        .map(|&k| {
            let (a, b) = (&obs.reference[k], &obs.current[k]);
            (b.u - a.u).hypot(b.v - a.v)
        })
        .collect();
    if flows.is_empty() {
        return 0.0;
    }
    let mid = flows.len() / 2;
    *flows.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The window's links of the inlier matches `inliers` (indices into `obs`) of `m`: the
/// features' indices in both frames, the reference's measurement, the current frame's
/// patch-aligned measurement and its detected keypoint.
pub(crate) fn window_links(m: &FrameMatches, obs: &Observations, inliers: &[usize]) -> Vec<Link> {
    inliers
        .iter()
        .map(|&k| {
            let s = obs.source[k];
            Link {
                reference_feature: m.dst_index[s],
                current_feature: m.src_index[s],
                reference: obs.reference[k],
                current: obs.current[k],
                current_keypoint: StereoObservation {
                    u: f64::from(m.src_pixels[s].0),
                    v: f64::from(m.src_pixels[s].1),
                    d: m.src_disparities_px[s],
                },
            }
        })
        .collect()
}

/// The estimator's motion from the reference A to the current frame B.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Initial {
    /// The pose of B in A.
    pub motion: Isometry3<f64>,
    /// Its inliers.
    pub inliers: usize,
    /// The estimator found a second, distinct motion with comparable support (a moving
    /// object, or a scene that repeats): `motion` is the one of the two nearer the
    /// prediction (the larger one without a prediction).
    pub ambiguous: bool,
}

/// Median distance, pixels in `(u, v, d)` of `rig`, between where `a` and `b` put the
/// points `src` (in B) in A; `f64::INFINITY` when no point lies in front of the camera
/// under both. Unit-free: it compares two motions by what they do to the measurements.
fn median_separation_px(
    rig: &RectifiedStereo,
    src: &[Point3<f64>],
    a: &Isometry3<f64>,
    b: &Isometry3<f64>,
) -> f64 {
    let measure = |p: Point3<f64>| -> Option<[f64; 3]> {
        (p.z > 0.0).then(|| {
            let (u, v) = rig.project_left(&p);
            [u, v, rig.fx * rig.baseline_m / p.z]
        })
    };
    let mut d: Vec<f64> = src
        .iter()
        .filter_map(|p| {
            let (za, zb) = (measure(a * p)?, measure(b * p)?);
            Some(
                za.iter()
                    .zip(&zb)
                    .map(|(x, y)| (x - y) * (x - y))
                    .sum::<f64>()
                    .sqrt(),
            )
        })
        .collect();
    if d.is_empty() {
        return f64::INFINITY;
    }
    let mid = d.len() / 2;
    *d.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The estimator's motion (pose of B in A) on the matches' 3D points with `correction`
/// applied (a rig of baseline `baseline_m`) and depths stretched by `focal_scale` (the
/// ratio of the focal length applied to the calibration's: depth is `f b / d`, the other
/// coordinates `(u − c) b / d` do not depend on `f`); the reason when there is none.
///
/// When the estimator reports a runner-up (a second distinct motion with at least its
/// ambiguity ratio of the winner's support, [`swarmpose_core::RunnerUp`]), the motion
/// taken is the one that moves the points of both consensus sets nearer to where
/// `prediction` (the constant-velocity motion from A to B) puts them, measured on `rig`'s
/// pixels; without a prediction, the winner. Either way the result is flagged ambiguous.
#[allow(clippy::too_many_arguments)]
pub(crate) fn initial_motion(
    m: &FrameMatches,
    correction: &DisparityCorrection,
    focal_scale: f64,
    rig: &RectifiedStereo,
    estimator: &dyn Estimator,
    seed: u64,
    min_inliers: usize,
    prediction: Option<&Isometry3<f64>>,
) -> Result<Initial, String> {
    let baseline_m = rig.baseline_m;
    let corrected;
    let data = if *correction == DisparityCorrection::default() {
        &m.correspondences
    } else {
        corrected = m
            .with_disparity_correction(*correction, baseline_m)
            .map_err(|e| format!("disparity correction {correction}: {e}"))?;
        &corrected.correspondences
    };
    let stretched;
    let data = if focal_scale == 1.0 {
        data
    } else {
        let z = |p: &[Point3<f64>]| -> Vec<Point3<f64>> {
            p.iter()
                .map(|p| Point3::new(p.x, p.y, p.z * focal_scale))
                .collect()
        };
        stretched = Correspondences::new(z(data.src()), z(data.dst()))
            .map_err(|e| format!("focal length x {focal_scale}: {e}"))?;
        &stretched
    };
    let e = estimator
        .estimate_seeded(data, seed)
        .map_err(|e| format!("estimator: {e}"))?;
    let mut initial = Initial {
        motion: e.transform,
        inliers: e.inliers.len(),
        ambiguous: e.diagnostics.runner_up.is_some(),
    };
    if let (Some(second), Some(prediction)) = (e.diagnostics.runner_up.as_ref(), prediction) {
        let src = data.src();
        let both: Vec<Point3<f64>> = e
            .inliers
            .iter()
            .chain(&second.inliers)
            .filter_map(|&i| src.get(i).copied())
            .collect();
        let winner = median_separation_px(rig, &both, &e.transform, prediction);
        let runner_up = median_separation_px(rig, &both, &second.transform, prediction);
        if runner_up < winner {
            initial.motion = second.transform;
            initial.inliers = second.inliers.len();
        }
    }
    if initial.inliers < min_inliers {
        return Err(format!(
            "estimator: {} inliers, fewer than {min_inliers}",
            initial.inliers
        ));
    }
    Ok(initial)
}
