//! A stereo rig from the two cameras' `sensor_msgs/CameraInfo`.
//!
//! - Rectified images (no distortion, `R` the identity on both sides): the pinhole of
//!   `P` (`fx = P[0]`, `fy = P[5]`, `cx = P[2]`, `cy = P[6]`, the same on both sides) and
//!   the baseline from both `P` rows: `b = P_left[3] / fx_left - P_right[3] / fx_right`
//!   (metres; ROS writes `P[3] = -fx * Tx`).
//! - Raw images: `K` and the `plumb_bob` (radial-tangential) `D` give each raw camera,
//!   `R` rotates it into the rectified frame and `P` is the rectified pinhole; each
//!   frame is remapped through [`swarmpose_vision::rectify`] as the EuRoC loader does.
//!
//! Refused: sizes that disagree with the images, a baseline that is not horizontal
//! (`P[7] != 0`, or `b <= 0`), a baseline outside
//! [`swarmpose_datasets::BASELINE_RANGE_M`], unequal rectified pinholes, binning or a
//! region of interest, and distortion models other than `plumb_bob` with `k3 = 0`.

use nalgebra::Matrix3;
use swarmpose_datasets::{BASELINE_RANGE_M, RectifiedStereo};
use swarmpose_vision::rectify::{RadTanCamera, RemapTable, rectify_map};

use crate::msg::CameraInfo;

/// How frames of a bag become rectified pairs.
#[derive(Debug, Clone, PartialEq)]
pub enum Rig {
    /// The images are rectified: use them as they are.
    Rectified(RectifiedStereo),
    /// The images are raw: remap each through its table.
    Raw {
        /// The rectified rig.
        rig: RectifiedStereo,
        /// Remap table of the left camera.
        left: Box<RemapTable>,
        /// Remap table of the right camera.
        right: Box<RemapTable>,
    },
}

impl Rig {
    /// The rectified rig.
    #[must_use]
    pub fn rectified(&self) -> RectifiedStereo {
        match self {
            Self::Rectified(r) | Self::Raw { rig: r, .. } => *r,
        }
    }
}

/// True when `info` describes a camera whose images are already rectified.
fn is_rectified(info: &CameraInfo) -> bool {
    let identity = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    info.d.iter().all(|&x| x == 0.0) && (info.r == identity || info.r == [0.0; 9])
}

/// The raw camera of `info` (`K`, `plumb_bob` `D`).
fn radtan(info: &CameraInfo, side: &str) -> Result<RadTanCamera, String> {
    let model = info.distortion_model.as_str();
    if !matches!(model, "plumb_bob" | "radtan" | "") {
        return Err(format!(
            "{side} camera_info: distortion model '{model}' is not plumb_bob (radial-tangential)"
        ));
    }
    let d = |i: usize| info.d.get(i).copied().unwrap_or(0.0);
    if info.d.iter().skip(4).any(|&k| k != 0.0) {
        return Err(format!(
            "{side} camera_info: D = {:?} has terms beyond k1 k2 p1 p2 (k3 and higher are not modelled)",
            info.d
        ));
    }
    Ok(RadTanCamera {
        fx: info.k[0],
        fy: info.k[4],
        cx: info.k[2],
        cy: info.k[5],
        k1: d(0),
        k2: d(1),
        p1: d(2),
        p2: d(3),
        width: info.width as usize,
        height: info.height as usize,
    })
}

/// The rig of the left and right `camera_info`, checked against the image size
/// `(width, height)` of each side.
///
/// # Errors
/// A one-line message saying what is refused and why.
pub fn rig_from_camera_info(
    left: &CameraInfo,
    right: &CameraInfo,
    left_size: (usize, usize),
    right_size: (usize, usize),
) -> Result<Rig, String> {
    for (info, size, side) in [(left, left_size, "left"), (right, right_size, "right")] {
        if (info.width as usize, info.height as usize) != size {
            return Err(format!(
                "{side} camera_info is for {}x{} images but the images are {}x{}",
                info.width, info.height, size.0, size.1
            ));
        }
        if info.binning_x > 1 || info.binning_y > 1 {
            return Err(format!("{side} camera_info: binning is not supported"));
        }
        let roi = info.roi;
        if roi.width != 0 && (roi.width, roi.height) != (info.width, info.height) {
            return Err(format!(
                "{side} camera_info: a region of interest is not supported"
            ));
        }
        let p = &info.p;
        if !(p[0] > 0.0 && p[5] > 0.0 && p.iter().all(|x| x.is_finite())) {
            return Err(format!(
                "{side} camera_info: P has no positive focal lengths (fx = {}, fy = {}): uncalibrated",
                p[0], p[5]
            ));
        }
    }
    let (pl, pr) = (&left.p, &right.p);
    if pl[7] != 0.0 || pr[7] != 0.0 {
        return Err(format!(
            "the rig has no horizontal baseline: P[1][3] = {} (left), {} (right) (a vertical stereo rig)",
            pl[7], pr[7]
        ));
    }
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(1.0);
    if !(same(pl[0], pr[0]) && same(pl[5], pr[5]) && same(pl[2], pr[2]) && same(pl[6], pr[6])) {
        return Err(format!(
            "the rectified projections differ (left fx fy cx cy = {} {} {} {}, right {} {} {} {}): \
             not a rectified pair",
            pl[0], pl[5], pl[2], pl[6], pr[0], pr[5], pr[2], pr[6]
        ));
    }
    let baseline_m = pl[3] / pl[0] - pr[3] / pr[0];
    let (lo, hi) = BASELINE_RANGE_M;
    if baseline_m.is_nan() || baseline_m <= 0.0 {
        return Err(format!(
            "the rig has no horizontal baseline: P[0][3] = {} (left), {} (right) give {baseline_m} m \
             (the right camera must be to the right: P[0][3] = -fx * baseline)",
            pl[3], pr[3]
        ));
    }
    if !(lo..=hi).contains(&baseline_m) {
        return Err(format!(
            "baseline {baseline_m} m from P is outside {lo}..{hi} m (a unit error?)"
        ));
    }
    let rig = RectifiedStereo {
        fx: pl[0],
        fy: pl[5],
        cx: pl[2],
        cy: pl[6],
        baseline_m,
    };
    if is_rectified(left) && is_rectified(right) {
        return Ok(Rig::Rectified(rig));
    }
    let (w, h) = left_size;
    let table = |info: &CameraInfo, side: &str| -> Result<Box<RemapTable>, String> {
        let cam = radtan(info, side)?;
        let r = Matrix3::from_row_slice(&info.r);
        let off = (r * r.transpose() - Matrix3::identity()).norm();
        if off > 1e-3 || r.determinant() <= 0.0 {
            return Err(format!(
                "{side} camera_info: R is not a rotation (|R Rᵀ - I| = {off:.2e})"
            ));
        }
        Ok(Box::new(rectify_map(&cam, &r, &rig, w, h)))
    };
    Ok(Rig::Raw {
        rig,
        left: table(left, "left")?,
        right: table(right, "right")?,
    })
}
