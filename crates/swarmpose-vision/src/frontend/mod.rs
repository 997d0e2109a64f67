//! The front end: from two rectified stereo frames to the 3D-3D correspondences the
//! core estimators take, plus the pixel positions needed to draw them.
//!
//! Per frame: extract features in both images, match them along rows and triangulate
//! ([`StereoFrame`]). Per pair of frames: match the left features of the triangulated
//! points ([`Frontend::match_frames`]), optionally confirmed by the right images.

mod check;
mod correction;
mod detector;
mod guided;
mod refine;
mod settings;

pub use correction::{CORRECTION_TERMS, DisparityCorrection};
pub use detector::{Detector, UnknownDetector};
pub use guided::{MotionGuide, Search, match_frames_guided, match_share};
pub use refine::{CHI2_3_99, refine_stereo, refine_weighted};
pub use settings::{OrbFrontendConfig, SurfFrontendConfig};

use nalgebra::{Matrix3, Point3};
use swarmpose_core::{Correspondences, PoseError};

use crate::bucketing::{BucketConfig, bucket_indices};
use crate::features::{Descriptor, FeatureExtractor, Features, GrayView, Keypoint};
use crate::stereo::{RectifiedStereo, StereoConfig, match_stereo};
use crate::temporal::{TemporalConfig, circular_check, mutual_matches};

/// The triangulated features of one stereo frame, index-aligned: feature `k` is seen at
/// `left_keypoints[k]` and `right_keypoints[k]` and lies at `points[k]`.
#[derive(Debug, Clone)]
pub struct StereoFrame<D> {
    /// Left-image keypoints, pixels.
    pub left_keypoints: Vec<Keypoint>,
    /// Their descriptors.
    pub left_descriptors: Vec<D>,
    /// Right-image keypoints, pixels.
    pub right_keypoints: Vec<Keypoint>,
    /// Their descriptors.
    pub right_descriptors: Vec<D>,
    /// The points, metres, in this frame's LEFT camera frame.
    pub points: Vec<Point3<f64>>,
    /// Sub-pixel disparities, pixels.
    pub disparities_px: Vec<f32>,
    /// Row of each right feature minus that of its left feature, pixels (NaN when not
    /// measured): the evidence of a rectification error.
    pub row_offsets_px: Vec<f32>,
    /// Noise level of each point, metres.
    pub sigmas_m: Vec<f64>,
    /// Covariance of each point, m².
    pub covariances: Vec<Matrix3<f64>>,
    /// Features detected in the left image before stereo matching.
    pub n_left_features: usize,
    /// Features detected in the right image.
    pub n_right_features: usize,
}

impl<D> Default for StereoFrame<D> {
    fn default() -> Self {
        Self {
            left_keypoints: Vec::new(),
            left_descriptors: Vec::new(),
            right_keypoints: Vec::new(),
            right_descriptors: Vec::new(),
            points: Vec::new(),
            disparities_px: Vec::new(),
            row_offsets_px: Vec::new(),
            sigmas_m: Vec::new(),
            covariances: Vec::new(),
            n_left_features: 0,
            n_right_features: 0,
        }
    }
}

impl<D> StereoFrame<D> {
    /// Number of triangulated features.
    #[must_use]
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when no feature was triangulated.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// The matches between frame I (destination) and frame J (source).
#[derive(Debug, Clone)]
pub struct FrameMatches {
    /// `src[k]`: the point in frame J's left camera frame; `dst[k]`: the same feature in
    /// frame I's left camera frame (metres). The motion `dst = R src + t` is the pose of
    /// camera J in camera I. No per-point noise is attached: see
    /// [`FrameMatches::noise_sigma_m`].
    pub correspondences: Correspondences,
    /// Isotropic noise level of each correspondence, metres: the root sum of squares of
    /// both points' ([`crate::stereo::RectifiedStereo::point_sigma`]). Not attached to
    /// [`FrameMatches::correspondences`] because the core's per-point mode refits without
    /// weights, which far stereo points (σ of metres) ruin; see
    /// [`FrameMatches::correspondences_with_noise`].
    pub noise_sigma_m: Vec<f64>,
    /// Left-image pixel `(u, v)` of each correspondence in frame J.
    pub src_pixels: Vec<(f32, f32)>,
    /// Left-image pixel `(u, v)` of each correspondence in frame I.
    pub dst_pixels: Vec<(f32, f32)>,
    /// Index of each correspondence in frame J's [`StereoFrame`].
    pub src_index: Vec<usize>,
    /// Index of each correspondence in frame I's [`StereoFrame`].
    pub dst_index: Vec<usize>,
    /// Covariance of each source point (frame J), m².
    pub src_covariances: Vec<Matrix3<f64>>,
    /// Covariance of each destination point (frame I), m².
    pub dst_covariances: Vec<Matrix3<f64>>,
    /// Disparity of each source point (frame J), pixels.
    pub src_disparities_px: Vec<f64>,
    /// Disparity of each destination point (frame I), pixels.
    pub dst_disparities_px: Vec<f64>,
}

impl FrameMatches {
    /// The correspondences with [`FrameMatches::noise_sigma_m`] attached, for estimators
    /// that scale their inlier test per point.
    ///
    /// # Errors
    /// As [`Correspondences::with_noise_sigma`].
    pub fn correspondences_with_noise(&self) -> Result<Correspondences, PoseError> {
        self.correspondences
            .clone()
            .with_noise_sigma(self.noise_sigma_m.clone())
    }

    /// The correspondences with both points' stereo covariances attached
    /// ([`Correspondences::with_noise_covariance`]): the estimators then test and fit
    /// Mahalanobis residuals, which respects that stereo noise lies along the viewing ray.
    ///
    /// # Errors
    /// As [`Correspondences::with_noise_covariance`].
    pub fn correspondences_with_covariance(&self) -> Result<Correspondences, PoseError> {
        self.correspondences
            .clone()
            .with_noise_covariance(self.src_covariances.clone(), self.dst_covariances.clone())
    }
}

/// Detector, calibration and matching settings of the front end.
#[derive(Debug, Clone)]
pub struct Frontend<E> {
    /// The detector/descriptor.
    pub extractor: E,
    /// A different detector for the right image (e.g. more, unbucketed corners, so
    /// every left feature finds its partner); `None` uses [`Frontend::extractor`].
    pub right_extractor: Option<E>,
    /// The rectified stereo camera.
    pub rig: RectifiedStereo,
    /// Stereo matching.
    pub stereo: StereoConfig,
    /// Matching between frames.
    pub temporal: TemporalConfig,
    /// Bucketing applied to each image's features after extraction (for extractors
    /// that do not bucket themselves); `None` keeps them all.
    pub bucketing: Option<BucketConfig>,
}

impl<E: FeatureExtractor> Frontend<E> {
    /// Extracts (and buckets) the features of one left image.
    #[must_use]
    pub fn extract(&self, image: GrayView<'_>) -> Features<E::Descriptor> {
        self.extract_with(&self.extractor, image)
    }

    /// Extracts the features of one right image: all of them, not bucketed, so that
    /// every left feature can find its partner.
    #[must_use]
    pub fn extract_right(&self, image: GrayView<'_>) -> Features<E::Descriptor> {
        self.right_extractor
            .as_ref()
            .unwrap_or(&self.extractor)
            .extract(image)
    }

    fn extract_with(&self, extractor: &E, image: GrayView<'_>) -> Features<E::Descriptor> {
        match &self.bucketing {
            // Bucketing before describing: the same features as bucketing afterwards,
            // without describing those dropped.
            Some(b) => extractor.extract_selected(image, &|keypoints| {
                bucket_indices(keypoints, image.width, image.height, b)
            }),
            None => extractor.extract(image),
        }
    }

    /// Stereo-matches already extracted features and triangulates them.
    #[must_use]
    pub fn stereo_from_features(
        &self,
        left: &Features<E::Descriptor>,
        right: &Features<E::Descriptor>,
        left_img: GrayView<'_>,
        right_img: GrayView<'_>,
    ) -> StereoFrame<E::Descriptor> {
        let matches = match_stereo(left, right, left_img, right_img, &self.rig, &self.stereo);
        let n = matches.len();
        let mut f = StereoFrame {
            left_keypoints: Vec::with_capacity(n),
            left_descriptors: Vec::with_capacity(n),
            right_keypoints: Vec::with_capacity(n),
            right_descriptors: Vec::with_capacity(n),
            points: Vec::with_capacity(n),
            disparities_px: Vec::with_capacity(n),
            row_offsets_px: Vec::with_capacity(n),
            sigmas_m: Vec::with_capacity(n),
            covariances: Vec::with_capacity(n),
            n_left_features: left.len(),
            n_right_features: right.len(),
        };
        for m in matches {
            f.left_keypoints.push(left.keypoints[m.left]);
            f.left_descriptors.push(left.descriptors[m.left].clone());
            f.right_keypoints.push(right.keypoints[m.right]);
            f.right_descriptors.push(right.descriptors[m.right].clone());
            f.points.push(m.point);
            f.disparities_px.push(m.disparity_px);
            f.row_offsets_px.push(m.row_offset_px);
            f.sigmas_m.push(m.sigma_m);
            f.covariances.push(m.covariance);
        }
        f
    }

    /// The number of stereo matches with the roles of the images exchanged (the right
    /// image's features matched as the left ones, and the other way round): on a pair
    /// whose images were given the wrong way round it is the number the pair would have,
    /// and far more than [`Frontend::stereo_from_features`] finds.
    #[must_use]
    pub fn exchanged_stereo_matches(
        &self,
        left: &Features<E::Descriptor>,
        right: &Features<E::Descriptor>,
        left_img: GrayView<'_>,
        right_img: GrayView<'_>,
    ) -> usize {
        match_stereo(right, left, right_img, left_img, &self.rig, &self.stereo).len()
    }

    /// Stereo matches found when rows may differ by up to `row_tolerance_px` (wider than
    /// [`StereoConfig::row_tolerance_px`]): their number and the median row of the right
    /// keypoint minus the left one, pixels (`None` without a match). On a rig that is not
    /// rectified (a right camera pitched or shifted vertically by a few pixels) the
    /// matches within the normal tolerance collapse while these do not.
    #[must_use]
    pub fn wide_row_matches(
        &self,
        left: &Features<E::Descriptor>,
        right: &Features<E::Descriptor>,
        left_img: GrayView<'_>,
        right_img: GrayView<'_>,
        row_tolerance_px: f32,
    ) -> (usize, Option<f32>) {
        let config = StereoConfig {
            row_tolerance_px,
            subpixel_radius: 0,
            row_offset_stride: 0,
            ..self.stereo
        };
        let matches = match_stereo(left, right, left_img, right_img, &self.rig, &config);
        let mut rows: Vec<f32> = matches
            .iter()
            .map(|m| right.keypoints[m.right].y - left.keypoints[m.left].y)
            .collect();
        rows.sort_by(f32::total_cmp);
        (matches.len(), rows.get(rows.len() / 2).copied())
    }

    /// One stereo frame: extract in both images, match, triangulate.
    #[must_use]
    pub fn stereo_frame(
        &self,
        left: GrayView<'_>,
        right: GrayView<'_>,
    ) -> StereoFrame<E::Descriptor> {
        let lf = self.extract(left);
        let rf = self.extract_right(right);
        self.stereo_from_features(&lf, &rf, left, right)
    }

    /// Matches frame J (`src`) to frame I (`dst`): mutual nearest neighbours of the left
    /// descriptors (and the circular check when configured).
    ///
    /// # Errors
    /// Never in practice (the points are finite); kept for the core's checked
    /// constructor.
    pub fn match_frames(
        &self,
        dst: &StereoFrame<E::Descriptor>,
        src: &StereoFrame<E::Descriptor>,
    ) -> Result<FrameMatches, PoseError> {
        match_frames(dst, src, &self.temporal)
    }
}

/// [`Frontend::match_frames`] without a front end.
///
/// # Errors
/// As [`Frontend::match_frames`].
pub fn match_frames<D: Descriptor>(
    dst: &StereoFrame<D>,
    src: &StereoFrame<D>,
    config: &TemporalConfig,
) -> Result<FrameMatches, PoseError> {
    let pairs = frame_pairs(
        (&dst.left_keypoints, &dst.right_keypoints),
        dst,
        src,
        config,
    );
    frame_matches(dst, src, &pairs)
}

/// The pairs `(index in dst, index in src)` of the left descriptors' mutual nearest
/// neighbours, with `dst`'s features at the keypoints `(dst_left, dst_right)` (their own,
/// or where a prediction puts them in `src`'s images), confirmed by the right images when
/// configured.
fn frame_pairs<D: Descriptor>(
    (dst_left, dst_right): (&[Keypoint], &[Keypoint]),
    dst: &StereoFrame<D>,
    src: &StereoFrame<D>,
    config: &TemporalConfig,
) -> Vec<(usize, usize)> {
    let pairs = mutual_matches(
        dst_left,
        &dst.left_descriptors,
        &src.left_keypoints,
        &src.left_descriptors,
        config,
    );
    if !config.circular_check {
        return pairs;
    }
    let right = mutual_matches(
        dst_right,
        &dst.right_descriptors,
        &src.right_keypoints,
        &src.right_descriptors,
        config,
    );
    circular_check(&pairs, &right)
}

/// The matches of the `pairs` `(index in dst, index in src)`.
fn frame_matches<D>(
    dst: &StereoFrame<D>,
    src: &StereoFrame<D>,
    pairs: &[(usize, usize)],
) -> Result<FrameMatches, PoseError> {
    let src_pts = pairs.iter().map(|&(_, j)| src.points[j]).collect();
    let dst_pts = pairs.iter().map(|&(i, _)| dst.points[i]).collect();
    let px = |k: &Keypoint| (k.x, k.y);
    let sigma: Vec<f64> = pairs
        .iter()
        .map(|&(i, j)| dst.sigmas_m[i].hypot(src.sigmas_m[j]))
        .collect();
    Ok(FrameMatches {
        correspondences: Correspondences::new(src_pts, dst_pts)?,
        noise_sigma_m: sigma,
        src_pixels: pairs
            .iter()
            .map(|&(_, j)| px(&src.left_keypoints[j]))
            .collect(),
        dst_pixels: pairs
            .iter()
            .map(|&(i, _)| px(&dst.left_keypoints[i]))
            .collect(),
        src_index: pairs.iter().map(|&(_, j)| j).collect(),
        dst_index: pairs.iter().map(|&(i, _)| i).collect(),
        src_covariances: pairs.iter().map(|&(_, j)| src.covariances[j]).collect(),
        dst_covariances: pairs.iter().map(|&(i, _)| dst.covariances[i]).collect(),
        src_disparities_px: pairs
            .iter()
            .map(|&(_, j)| f64::from(src.disparities_px[j]))
            .collect(),
        dst_disparities_px: pairs
            .iter()
            .map(|&(i, _)| f64::from(dst.disparities_px[i]))
            .collect(),
    })
}

/// The map `T` with `Σ' = T Σ Tᵀ` from the covariance of a stereo point `p = (X, Y, Z)` of
/// disparity `d` to that of the same measurement with disparity `d + δ`, where
/// `k = d / (d + δ)`. The point is `b (u - cx, v - cy, f) / d`, so with `J` its Jacobian in
/// `(u, v, d)` the new Jacobian is `J diag(k, k, k²)`, and
/// `T = J diag(k, k, k²) J⁻¹ = [[k, 0, (X/Z)(k² - k)], [0, k, (Y/Z)(k² - k)], [0, 0, k²]]`,
/// which needs neither the calibration nor the pixel (only the ratios `X/Z`, `Y/Z`).
fn offset_jacobian(p: &Point3<f64>, k: f64) -> Matrix3<f64> {
    let bend = k * k - k;
    let (rx, ry) = if p.z.abs() > f64::EPSILON {
        (p.x / p.z, p.y / p.z)
    } else {
        (0.0, 0.0)
    };
    Matrix3::new(k, 0.0, rx * bend, 0.0, k, ry * bend, 0.0, 0.0, k * k)
}

#[cfg(test)]
mod offset_tests {
    use super::*;

    #[test]
    fn offset_jacobian_moves_a_stereo_covariance_exactly() {
        let rig = RectifiedStereo {
            fx: 718.856,
            fy: 718.856,
            cx: 607.19,
            cy: 185.22,
            baseline_m: 0.537,
        };
        for &(u, v, d, delta) in &[
            (100.0, 50.0, 8.0, 1.4),
            (1200.0, 300.0, 30.0, -0.7),
            (607.0, 185.0, 3.0, 2.0),
        ] {
            let p = Point3::new(
                (u - rig.cx) * rig.baseline_m / d,
                (v - rig.cy) * rig.baseline_m / d,
                rig.fx * rig.baseline_m / d,
            );
            let before = rig.point_covariance(u, v, d, 0.3, 0.2);
            let after = rig.point_covariance(u, v, d + delta, 0.3, 0.2);
            let t = offset_jacobian(&p, d / (d + delta));
            let moved = t * before * t.transpose();
            let err = (moved - after).abs().max() / after.abs().max();
            assert!(
                err < 1e-12,
                "relative error {err} at u={u}, d={d}, δ={delta}"
            );
        }
    }
}
