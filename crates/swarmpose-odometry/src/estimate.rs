//! The estimate stage: matches with the reference frame, the robust estimator's motion
//! on their 3D points, and the stereo measurements the refinement takes.

use nalgebra::{Isometry3, Point3};
use swarmpose_core::{Correspondences, Estimator};
use swarmpose_vision::frontend::{DisparityCorrection, FrameMatches};

use crate::record::{Inlier, Reason};
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

/// The inliers `matches` (indices into `m`'s correspondences) as the engine reports
/// them: each feature's pixel in the current frame B and the reference A, and its point
/// in B (metres).
pub(crate) fn inlier_features(
    m: &FrameMatches,
    matches: impl Iterator<Item = usize>,
) -> Vec<Inlier> {
    let points = m.correspondences.src();
    matches
        .filter_map(|s| {
            let p = points.get(s)?;
            Some(Inlier {
                pixel: *m.src_pixels.get(s)?,
                reference_pixel: *m.dst_pixels.get(s)?,
                point_m: [p.x as f32, p.y as f32, p.z as f32],
            })
        })
        .collect()
}

/// The estimator's motion from the reference A to the current frame B.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Initial {
    /// The pose of B in A.
    pub motion: Isometry3<f64>,
    /// Its inliers.
    pub inliers: usize,
    /// Their indices into the matches.
    pub inlier_matches: Vec<usize>,
    /// The estimator found a second, distinct motion with comparable support (a moving
    /// object, or a scene that repeats); `motion` is the one with more support.
    pub ambiguous: bool,
}

/// The estimator's motion (pose of B in A) on the matches' 3D points with `correction`
/// applied (a rig of baseline `baseline_m`) and depths stretched by `focal_scale` (the
/// ratio of the focal length applied to the calibration's: depth is `f b / d`, the other
/// coordinates `(u − c) b / d` do not depend on `f`); the reason when there is none.
///
/// A runner-up reported by the estimator (a second distinct motion with at least its
/// ambiguity ratio of the winner's support, [`swarmpose_core::RunnerUp`]) flags the result
/// ambiguous; which of the two motions is the camera's is decided after the refinement
/// ([`crate::tracker`]'s check for a second motion near the prediction).
pub(crate) fn initial_motion(
    m: &FrameMatches,
    correction: &DisparityCorrection,
    focal_scale: f64,
    baseline_m: f64,
    estimator: &dyn Estimator,
    seed: u64,
    min_inliers: usize,
) -> Result<Initial, Reason> {
    let corrected;
    let data = if *correction == DisparityCorrection::default() {
        &m.correspondences
    } else {
        corrected = m
            .with_disparity_correction(*correction, baseline_m)
            .map_err(|error| Reason::Correction {
                correction: *correction,
                error,
            })?;
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
        stretched = Correspondences::new(z(data.src()), z(data.dst())).map_err(|error| {
            Reason::FocalLength {
                scale: focal_scale,
                error,
            }
        })?;
        &stretched
    };
    let e = estimator
        .estimate_seeded(data, seed)
        .map_err(Reason::Estimator)?;
    let initial = Initial {
        motion: e.transform,
        inliers: e.inliers.len(),
        inlier_matches: e.inliers,
        ambiguous: e.diagnostics.runner_up.is_some(),
    };
    if initial.inliers < min_inliers {
        return Err(Reason::TooFewInliers {
            inliers: initial.inliers,
            min: min_inliers,
        });
    }
    Ok(initial)
}
