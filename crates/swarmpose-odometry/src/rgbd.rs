//! RGB-D input, as the paper also allows: the TUM RGB-D layout. A directory with
//! `rgb.txt` and `depth.txt` (`timestamp filename` per line, `#` comments), the images
//! they name (colour or gray PNGs; 16-bit depth PNGs, 5000 per metre, 0 = no depth),
//! optionally `groundtruth.txt` (TUM trajectory of the colour camera) and
//! `intrinsics.txt` (`fx fy cx cy`; default 525, 525, 319.5, 239.5, TUM's
//! recommendation for its sequences as published).
//!
//! Each colour image is paired with the depth image nearest in time within 20 ms (as
//! TUM's `associate.py`), and the ground truth with the nearest pose within 20 ms. The
//! features of the gray image with a valid depth become the frame's 3D points, with a
//! Kinect-like noise model (depth σ = 1.425e-3 z² m, 0.5 px in the image).

use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{Isometry3, Matrix3, Point3};
use swarmpose_core::Estimator;
use swarmpose_eval::{Format, Trajectory};
use swarmpose_vision::features::FeatureExtractor;
use swarmpose_vision::frontend::{Frontend, StereoFrame};
use swarmpose_vision::image::GrayImage;

use crate::error::OdometryError;
use crate::pipeline::{DisparityOffset, OdometryConfig, OdometryRun, StageTimes, run_frames};

/// Depth PNG units per metre.
pub const DEPTH_SCALE: f64 = 5000.0;
/// Largest time between paired colour, depth and ground truth, seconds.
pub const MAX_DIFF_S: f64 = 0.02;

/// Pinhole intrinsics, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal length along x.
    pub fx: f64,
    /// Focal length along y.
    pub fy: f64,
    /// Principal point column.
    pub cx: f64,
    /// Principal point row.
    pub cy: f64,
}

impl Default for Intrinsics {
    fn default() -> Self {
        Self {
            fx: 525.0,
            fy: 525.0,
            cx: 319.5,
            cy: 239.5,
        }
    }
}

/// A TUM RGB-D sequence.
#[derive(Debug, Clone)]
pub struct RgbdSequence {
    root: PathBuf,
    /// Timestamp, colour image, depth image of each frame.
    frames: Vec<(f64, PathBuf, PathBuf)>,
    intrinsics: Intrinsics,
    ground_truth: Option<Vec<Isometry3<f64>>>,
}

/// True when `dir` has `rgb.txt` and `depth.txt`.
#[must_use]
pub fn detect(dir: &Path) -> bool {
    dir.join("rgb.txt").is_file() && dir.join("depth.txt").is_file()
}

fn rgbd_err(path: &Path, line: usize, message: impl Into<String>) -> OdometryError {
    OdometryError::Rgbd {
        path: path.to_owned(),
        line,
        message: message.into(),
    }
}

fn read_list(dir: &Path, name: &str) -> Result<Vec<(f64, PathBuf)>, OdometryError> {
    let path = dir.join(name);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| rgbd_err(&path, 0, format!("cannot read: {e}")))?;
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let mut parts = t.split_whitespace();
        let (Some(ts), Some(file)) = (parts.next(), parts.next()) else {
            return Err(rgbd_err(&path, k + 1, "expected 'timestamp filename'"));
        };
        let ts: f64 = ts
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| rgbd_err(&path, k + 1, format!("'{ts}' is not a timestamp")))?;
        out.push((ts, dir.join(file)));
    }
    if out.is_empty() {
        return Err(rgbd_err(&path, 0, "no image listed"));
    }
    Ok(out)
}

fn nearest(stamps: &[f64], t: f64) -> Option<(usize, f64)> {
    stamps
        .iter()
        .map(|s| (s - t).abs())
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

impl RgbdSequence {
    /// Opens a TUM RGB-D directory.
    ///
    /// # Errors
    /// [`OdometryError::Rgbd`] naming the file (and line) that is missing or malformed,
    /// or a colour image without a depth image within 20 ms, or a frame without a
    /// ground-truth pose within 20 ms when `groundtruth.txt` exists.
    pub fn open(dir: &Path) -> Result<Self, OdometryError> {
        let rgb = read_list(dir, "rgb.txt")?;
        let depth = read_list(dir, "depth.txt")?;
        let depth_stamps: Vec<f64> = depth.iter().map(|d| d.0).collect();
        let mut frames = Vec::with_capacity(rgb.len());
        for (t, file) in &rgb {
            match nearest(&depth_stamps, *t) {
                Some((j, d)) if d <= MAX_DIFF_S => {
                    frames.push((*t, file.clone(), depth[j].1.clone()));
                }
                _ => {
                    return Err(rgbd_err(
                        &dir.join("depth.txt"),
                        0,
                        format!("no depth image within {MAX_DIFF_S} s of colour image {t}"),
                    ));
                }
            }
        }
        let intrinsics = read_intrinsics(&dir.join("intrinsics.txt"))?;
        let gt_path = dir.join("groundtruth.txt");
        let ground_truth = if gt_path.is_file() {
            let gt = Trajectory::read(&gt_path, Format::Tum)
                .map_err(|e| rgbd_err(&gt_path, 0, e.to_string()))?;
            let mut poses = Vec::with_capacity(frames.len());
            for (t, _, _) in &frames {
                match nearest(&gt.stamps, *t) {
                    Some((j, d)) if d <= MAX_DIFF_S => poses.push(gt.poses[j]),
                    _ => {
                        return Err(rgbd_err(
                            &gt_path,
                            0,
                            format!("no ground-truth pose within {MAX_DIFF_S} s of frame {t}"),
                        ));
                    }
                }
            }
            // In the colour camera frame of frame 0.
            let first_inv = poses[0].inverse();
            Some(poses.iter().map(|p| first_inv * p).collect())
        } else {
            None
        };
        Ok(Self {
            root: dir.to_owned(),
            frames,
            intrinsics,
            ground_truth,
        })
    }

    /// Number of frames.
    #[must_use]
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True when there is no frame.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The directory.
    #[must_use]
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// Timestamps of the frames (colour images), seconds.
    #[must_use]
    pub fn stamps(&self) -> Vec<f64> {
        self.frames.iter().map(|f| f.0).collect()
    }

    /// Camera poses in the colour camera frame of frame 0, when `groundtruth.txt` exists.
    #[must_use]
    pub fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        self.ground_truth.as_deref()
    }

    /// The intrinsics.
    #[must_use]
    pub fn intrinsics(&self) -> Intrinsics {
        self.intrinsics
    }

    /// Loads frame `i`: the gray image and the depth in metres (0 = none).
    ///
    /// # Errors
    /// [`OdometryError::Rgbd`] naming an unreadable image or sizes that differ.
    pub fn frame(&self, i: usize) -> Result<(GrayImage, Vec<f32>), OdometryError> {
        let Some((_, rgb, depth)) = self.frames.get(i) else {
            return Err(rgbd_err(&self.root, 0, format!("frame {i} out of range")));
        };
        let gray = GrayImage::load_png(rgb).map_err(|e| rgbd_err(rgb, 0, e.to_string()))?;
        let d = image::ImageReader::open(depth)
            .map_err(|e| rgbd_err(depth, 0, format!("cannot read: {e}")))?
            .decode()
            .map_err(|e| rgbd_err(depth, 0, format!("cannot decode: {e}")))?
            .into_luma16();
        if (d.width() as usize, d.height() as usize) != (gray.width, gray.height) {
            return Err(rgbd_err(
                depth,
                0,
                format!(
                    "depth image {}x{} but colour image {}x{}",
                    d.width(),
                    d.height(),
                    gray.width,
                    gray.height
                ),
            ));
        }
        let metres = d
            .into_raw()
            .into_iter()
            .map(|v| (f64::from(v) / DEPTH_SCALE) as f32)
            .collect();
        Ok((gray, metres))
    }
}

fn read_intrinsics(path: &Path) -> Result<Intrinsics, OdometryError> {
    if !path.is_file() {
        return Ok(Intrinsics::default());
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| rgbd_err(path, 0, format!("cannot read: {e}")))?;
    let v: Vec<f64> = text
        .split_whitespace()
        .filter_map(|s| s.parse().ok())
        .collect();
    match v.as_slice() {
        [fx, fy, cx, cy] if *fx > 0.0 && *fy > 0.0 => Ok(Intrinsics {
            fx: *fx,
            fy: *fy,
            cx: *cx,
            cy: *cy,
        }),
        _ => Err(rgbd_err(path, 1, "expected four numbers: fx fy cx cy")),
    }
}

/// Depth noise (σ, metres) at depth `z`: Khoshelham and Elberink's Kinect model.
fn depth_sigma(z: f64) -> f64 {
    1.425e-3 * z * z
}

/// The frame's features with a valid depth, as a [`StereoFrame`] (no right image).
fn rgbd_frame<E: FeatureExtractor>(
    frontend: &Frontend<E>,
    k: &Intrinsics,
    gray: &GrayImage,
    depth: &[f32],
) -> StereoFrame<E::Descriptor> {
    let f = frontend.extract(gray.view());
    let mut out = StereoFrame {
        n_left_features: f.keypoints.len(),
        ..StereoFrame::default()
    };
    let px_sigma = 0.5;
    for (kp, d) in f.keypoints.iter().zip(&f.descriptors) {
        let (u, v) = (kp.x.round() as isize, kp.y.round() as isize);
        if u < 0 || v < 0 || u as usize >= gray.width || v as usize >= gray.height {
            continue;
        }
        let z = f64::from(depth[v as usize * gray.width + u as usize]);
        if z.is_nan() || z <= 0.1 {
            continue;
        }
        let (x, y) = (
            (f64::from(kp.x) - k.cx) * z / k.fx,
            (f64::from(kp.y) - k.cy) * z / k.fy,
        );
        // Covariance: Jacobian of (u, v, z) -> (x, y, z).
        let j = Matrix3::new(z / k.fx, 0.0, x / z, 0.0, z / k.fy, y / z, 0.0, 0.0, 1.0);
        let sz = depth_sigma(z);
        let cov =
            j * Matrix3::from_diagonal(&nalgebra::Vector3::new(
                px_sigma * px_sigma,
                px_sigma * px_sigma,
                sz * sz,
            )) * j.transpose();
        out.left_keypoints.push(*kp);
        out.left_descriptors.push(d.clone());
        out.right_keypoints.push(*kp);
        out.right_descriptors.push(d.clone());
        out.points.push(Point3::new(x, y, z));
        // A virtual disparity (Kinect-like 7.5 cm baseline); only used by a disparity
        // offset, which RGB-D runs never apply.
        out.disparities_px.push((k.fx * 0.075 / z) as f32);
        out.sigmas_m.push(sz.hypot(px_sigma * z / k.fx));
        out.covariances.push(cov);
    }
    out
}

/// Runs the odometry on a TUM RGB-D sequence with `frontend`'s left-image extractor and
/// temporal matching. The disparity offset is never applied.
///
/// # Errors
/// [`OdometryError::TooFewFrames`], or an unreadable frame.
pub fn run_rgbd<E: FeatureExtractor>(
    seq: &RgbdSequence,
    frontend: &Frontend<E>,
    estimator: &dyn Estimator,
    config: &OdometryConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<OdometryRun, OdometryError> {
    let n = seq.len();
    if n < 2 {
        return Err(OdometryError::TooFewFrames {
            dir: seq.root().to_owned(),
            n,
        });
    }
    let k = seq.intrinsics();
    let mut make_frame = |i: usize| {
        let mut times = StageTimes::default();
        let t = Instant::now();
        let (gray, depth) = seq.frame(i)?;
        times.load_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let frame = rgbd_frame(frontend, &k, &gray, &depth);
        times.features_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok((frame, times))
    };
    let config = OdometryConfig {
        disparity_offset: DisparityOffset::Fixed(0.0),
        ..config.clone()
    };
    run_frames(
        n,
        &mut make_frame,
        &frontend.temporal,
        estimator,
        &config,
        progress,
        seq.stamps(),
        frontend.extractor.name(),
    )
}
