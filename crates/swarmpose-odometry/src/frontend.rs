//! The engine's front end: from the images of one frame to its triangulated features
//! ([`StereoFrame`]): features in both images, stereo matching along rows and
//! triangulation; for RGB-D frames, features of the gray image with their depth.

use std::time::Instant;

use nalgebra::{Matrix3, Point3, Vector3};
use swarmpose_vision::features::{FeatureExtractor, GrayView};
use swarmpose_vision::frontend::{Frontend, StereoFrame};
use swarmpose_vision::stereo::RectifiedStereo;

use crate::error::OdometryError;
use crate::intake::DepthView;
use crate::record::StageTimes;
use crate::refine::model::PixelNoise;

/// Milliseconds since `t`.
pub(crate) fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// A frame whose stereo points are fewer than this share of its left features is
/// checked for images given the wrong way round (on the shared sequences every frame
/// has at least 0.40; a pair given the wrong way round, 0.03).
const EXCHANGED_CHECK_SHARE: f64 = 0.25;
/// The images are taken as given the wrong way round when exchanging them gives at
/// least this many times the stereo matches, and at least [`EXCHANGED_MIN_MATCHES`].
const EXCHANGED_RATIO: usize = 4;
/// See [`EXCHANGED_RATIO`].
const EXCHANGED_MIN_MATCHES: usize = 50;

/// The triangulated features of a stereo frame, timing features and stereo matching.
///
/// # Errors
/// [`OdometryError::Frame`] when the left and right images look exchanged: few stereo
/// matches as given, and many with the images the other way round.
pub(crate) fn stereo_frame<E: FeatureExtractor>(
    frontend: &Frontend<E>,
    left: GrayView<'_>,
    right: GrayView<'_>,
    times: &mut StageTimes,
) -> Result<StereoFrame<E::Descriptor>, OdometryError> {
    let t = Instant::now();
    let lf = frontend.extract(left);
    let rf = frontend.extract_right(right);
    times.features_ms = ms(t);
    let t = Instant::now();
    let frame = frontend.stereo_from_features(&lf, &rf, left, right);
    if (frame.len() as f64) < EXCHANGED_CHECK_SHARE * lf.len() as f64 {
        let exchanged = frontend.exchanged_stereo_matches(&lf, &rf, left, right);
        if exchanged >= EXCHANGED_MIN_MATCHES && exchanged >= EXCHANGED_RATIO * frame.len() {
            return Err(OdometryError::Frame {
                message: format!(
                    "the left and right images look exchanged: {} stereo matches as given, \
                     {exchanged} with the two images the other way round",
                    frame.len()
                ),
            });
        }
    }
    if (frame.len() as f64) < EXCHANGED_CHECK_SHARE * lf.len() as f64 {
        crate::rectification::check_rows(frontend, &lf, &rf, left, right, frame.len())?;
    }
    times.stereo_ms = ms(t);
    Ok(frame)
}

/// The noise model of an RGB-D camera: Khoshelham and Elberink's Kinect depth noise
/// `σ_z = k z²` (`k` = [`RgbdNoise::depth_coefficient`], 1/m), and a keypoint position
/// noise. Expressed as a stereo camera with a virtual baseline, the disparity
/// `d = fx b / z` has the constant noise `σ_d = fx b k`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct RgbdNoise {
    /// `k` in `σ_z = k z²`, 1/m (default 1.425e-3, Kinect v1).
    pub depth_coefficient: f64,
    /// Keypoint position noise, pixels (default 0.5).
    pub position_px: f64,
    /// Virtual baseline, metres (default 0.075, the Kinect's).
    pub virtual_baseline_m: f64,
    /// Depths below this are not used, metres (default 0.1).
    pub min_depth_m: f64,
}

impl Default for RgbdNoise {
    fn default() -> Self {
        Self {
            depth_coefficient: 1.425e-3,
            position_px: 0.5,
            virtual_baseline_m: 0.075,
            min_depth_m: 0.1,
        }
    }
}

impl RgbdNoise {
    /// Checks that every value is a finite positive number.
    ///
    /// # Errors
    /// [`crate::OdometryError::Camera`] naming the value.
    pub fn validate(&self) -> Result<(), crate::OdometryError> {
        for (what, v) in [
            ("the depth noise coefficient", self.depth_coefficient),
            ("the keypoint position noise", self.position_px),
            ("the virtual baseline", self.virtual_baseline_m),
            ("the smallest depth", self.min_depth_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(crate::OdometryError::Camera {
                    message: format!("{what} is {v}: it must be a finite positive number"),
                });
            }
        }
        Ok(())
    }

    /// The pixel noise of the virtual stereo measurement for the focal length `fx`.
    #[must_use]
    pub fn pixel_noise(&self, fx: f64) -> PixelNoise {
        PixelNoise {
            position_px: self.position_px,
            disparity_px: fx * self.virtual_baseline_m * self.depth_coefficient,
        }
    }
}

/// The features of a gray image with a valid depth, as a [`StereoFrame`] of the virtual
/// stereo camera `rig` (the right keypoint is the left one; the disparity is
/// `fx b / z`).
pub(crate) fn rgbd_frame<E: FeatureExtractor>(
    frontend: &Frontend<E>,
    rig: &RectifiedStereo,
    noise: &RgbdNoise,
    gray: GrayView<'_>,
    depth: DepthView<'_>,
    times: &mut StageTimes,
) -> StereoFrame<E::Descriptor> {
    let t = Instant::now();
    let f = frontend.extract(gray);
    times.features_ms = ms(t);
    let t = Instant::now();
    let mut out = StereoFrame {
        n_left_features: f.keypoints.len(),
        ..StereoFrame::default()
    };
    let sp = noise.position_px;
    for (kp, d) in f.keypoints.iter().zip(&f.descriptors) {
        let (u, v) = (kp.x.round(), kp.y.round());
        if u < 0.0 || v < 0.0 || u as usize >= depth.width || v as usize >= depth.height {
            continue;
        }
        let z = f64::from(depth.data[v as usize * depth.width + u as usize]);
        if !(z.is_finite() && z >= noise.min_depth_m) {
            continue;
        }
        let (x, y) = (
            (f64::from(kp.x) - rig.cx) * z / rig.fx,
            (f64::from(kp.y) - rig.cy) * z / rig.fy,
        );
        // Covariance: Jacobian of (u, v, z) -> (x, y, z).
        let j = Matrix3::new(
            z / rig.fx,
            0.0,
            x / z,
            0.0,
            z / rig.fy,
            y / z,
            0.0,
            0.0,
            1.0,
        );
        let sz = noise.depth_coefficient * z * z;
        let cov =
            j * Matrix3::from_diagonal(&Vector3::new(sp * sp, sp * sp, sz * sz)) * j.transpose();
        out.left_keypoints.push(*kp);
        out.left_descriptors.push(d.clone());
        out.right_keypoints.push(*kp);
        out.right_descriptors.push(d.clone());
        out.points.push(Point3::new(x, y, z));
        out.disparities_px
            .push((rig.fx * rig.baseline_m / z) as f32);
        out.row_offsets_px.push(f32::NAN);
        out.sigmas_m.push(sz.hypot(sp * z / rig.fx));
        out.covariances.push(cov);
    }
    times.stereo_ms = ms(t);
    out
}
