//! EuRoC MAV (ASL) layout: `mav0/cam0` (left) and `mav0/cam1` (right), each with
//! `data.csv` (`timestamp [ns], filename`), `data/*.png` and `sensor.yaml` (pinhole
//! intrinsics, radial-tangential distortion, `T_BS`), and optionally
//! `mav0/state_groundtruth_estimate0/data.csv` (body pose in the world frame).
//!
//! The images are raw: the loader computes the stereo rectification once
//! ([`swarmpose_vision::rectify`]) and remaps every frame with bilinear interpolation.
//! Ground truth, when present, is the pose of the RECTIFIED left camera.

pub mod yaml;

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use swarmpose_vision::rectify::{
    RemapTable, StereoRectification, rectify_map, remap, stereo_rectify,
};

use crate::error::DatasetError;
use crate::frames::check_pairs;
use crate::text::{
    check_baseline, check_plausible, numbers_at_least, parse_error, read_text, strip_bom,
};
use crate::{RectifiedStereo, StereoPair, StereoSequence, load_indexed_pair};

pub use yaml::{SensorYaml, parse_sensor_yaml, read_sensor_yaml};

/// The `mav0` directory of `dir` (`dir` itself when it is one).
fn mav0(dir: &Path) -> PathBuf {
    if dir.file_name().is_some_and(|n| n == "mav0") {
        dir.to_owned()
    } else {
        dir.join("mav0")
    }
}

/// True when `dir` looks like a EuRoC sequence.
#[must_use]
pub fn detect(dir: &Path) -> bool {
    let m = mav0(dir);
    m.join("cam0").is_dir() && m.join("cam1").is_dir()
}

/// `(timestamp ns, image path)` rows of a camera `data.csv`.
fn read_image_list(cam_dir: &Path) -> Result<Vec<(i64, PathBuf)>, DatasetError> {
    let path = cam_dir.join("data.csv");
    let text = read_text(&path, "EuRoC image list data.csv")?;
    parse_image_list(&text, &path, cam_dir)
}

/// The `(timestamp ns, image path)` rows of the text of a camera's `data.csv` at `path`
/// (`timestamp [ns], filename` per line, `#` comments); the images are in
/// `cam_dir/data/`.
///
/// # Errors
/// [`DatasetError::Parse`] naming `path` and the line.
pub fn parse_image_list(
    text: &str,
    path: &Path,
    cam_dir: &Path,
) -> Result<Vec<(i64, PathBuf)>, DatasetError> {
    let path = path.to_owned();
    let mut out = Vec::new();
    for (k, line) in strip_bom(text).lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let Some((ts, name)) = line.split_once(',') else {
            return Err(parse_error(&path, k + 1, "expected 'timestamp,filename'"));
        };
        let ts: i64 = ts.trim().parse().map_err(|_| {
            parse_error(&path, k + 1, format!("'{}' is not a timestamp", ts.trim()))
        })?;
        out.push((ts, cam_dir.join("data").join(name.trim())));
    }
    Ok(out)
}

/// Body poses `(timestamp ns, world_from_body)` of a EuRoC ground-truth `data.csv`.
fn read_groundtruth(path: &Path) -> Result<Vec<(i64, Isometry3<f64>)>, DatasetError> {
    let text = read_text(path, "EuRoC ground truth data.csv")?;
    parse_groundtruth(&text, path)
}

/// The ground-truth poses of the rectified left camera at each frame (`timestamps_ns`),
/// in the first frame's, from the body poses of `path` (the nearest within
/// [`GT_TOLERANCE_NS`] of each frame), `T_WB T_BS0 R_rect⁻¹` with `camera` the last two. When a frame has no pose
/// that near (a ground truth that starts late, ends early or has a gap), none is used,
/// and a note says so (before, the run went on without evaluation and without a word).
///
/// # Errors
/// As [`parse_groundtruth`].
fn camera_ground_truth(
    path: &Path,
    timestamps_ns: &[i64],
    camera: (&Isometry3<f64>, &Isometry3<f64>),
    notes: &mut Vec<String>,
) -> Result<Option<Vec<Isometry3<f64>>>, DatasetError> {
    let gt = read_groundtruth(path)?;
    let nearest = |t: i64| {
        gt.iter()
            .min_by_key(|g| (g.0 - t).abs())
            .filter(|g| (g.0 - t).abs() <= GT_TOLERANCE_NS)
    };
    let found: Vec<Option<&(i64, Isometry3<f64>)>> =
        timestamps_ns.iter().map(|&t| nearest(t)).collect();
    let missing = found.iter().filter(|f| f.is_none()).count();
    if let Some(first) = found.iter().position(Option::is_none) {
        notes.push(format!(
            "{}: no pose within {} ms of {missing} of the {} frames (the first: frame {first}, \
             timestamp {} ns): the ground truth is not used",
            path.display(),
            GT_TOLERANCE_NS / 1_000_000,
            timestamps_ns.len(),
            timestamps_ns[first]
        ));
        return Ok(None);
    }
    let world: Vec<Isometry3<f64>> = found
        .iter()
        .flatten()
        .map(|g| g.1 * camera.0 * camera.1)
        .collect();
    let Some(first_inv) = world.first().map(Isometry3::inverse) else {
        return Ok(None);
    };
    Ok(Some(world.iter().map(|p| first_inv * p).collect()))
}

/// Body poses `(timestamp ns, world_from_body)` of the text of a EuRoC ground-truth
/// `data.csv` (`timestamp, p_x, p_y, p_z [m], q_w, q_x, q_y, q_z, ...` per line).
///
/// # Errors
/// [`DatasetError::Parse`] naming `path` and the line.
pub fn parse_groundtruth(
    text: &str,
    path: &Path,
) -> Result<Vec<(i64, Isometry3<f64>)>, DatasetError> {
    let mut out = Vec::new();
    for (k, line) in strip_bom(text).lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let v = numbers_at_least(line, path, k + 1, 8, |n| {
            format!("expected timestamp, position (3), quaternion wxyz (4); found {n} numbers")
        })?;
        let q = Quaternion::new(v[4], v[5], v[6], v[7]);
        // A quaternion of norm 0 (or far from 1) is no rotation: normalising it gave NaN
        // poses and NaN metrics.
        if !((1.0 - 1e-2)..=(1.0 + 1e-2)).contains(&q.norm()) {
            return Err(parse_error(
                path,
                k + 1,
                format!(
                    "the quaternion (q_w, q_x, q_y, q_z) = ({}, {}, {}, {}) has norm {:.3e}: \
                     a rotation's has norm 1",
                    v[4],
                    v[5],
                    v[6],
                    v[7],
                    q.norm()
                ),
            ));
        }
        let q = UnitQuaternion::from_quaternion(q);
        let ts = line
            .split(',')
            .next()
            .unwrap_or("")
            .trim()
            .parse::<i64>()
            .unwrap_or(v[0] as i64);
        out.push((
            ts,
            Isometry3::from_parts(Translation3::new(v[1], v[2], v[3]), q),
        ));
    }
    Ok(out)
}

/// Checks the timestamps of a camera list: strictly increasing, and no interval longer
/// than 1.5 times the median (a frame missing from the list: the odometry numbers frames
/// by their order, so a gap would shift every later frame in time).
fn check_timestamps(rows: &[(i64, PathBuf)], list: &Path) -> Result<(), DatasetError> {
    let frames_error = |k: usize, message: String| DatasetError::Frames {
        path: list.to_owned(),
        message: format!("row {} ({}): {message}", k + 1, rows[k].1.display()),
    };
    for (k, w) in rows.windows(2).enumerate() {
        if w[1].0 <= w[0].0 {
            return Err(frames_error(
                k + 1,
                format!(
                    "timestamp {} does not follow {}: timestamps must increase",
                    w[1].0, w[0].0
                ),
            ));
        }
    }
    let mut steps: Vec<i64> = rows.windows(2).map(|w| w[1].0 - w[0].0).collect();
    steps.sort_unstable();
    let Some(&median) = steps.get(steps.len() / 2) else {
        return Ok(());
    };
    if let Some(k) = rows
        .windows(2)
        .position(|w| (w[1].0 - w[0].0) as f64 > 1.5 * median as f64)
    {
        return Err(frames_error(
            k + 1,
            format!(
                "{} ns after the previous frame, {:.1} times the usual {median} ns: a \
                 frame is missing before it (frames are taken in order, so a gap would \
                 shift every later frame in time)",
                rows[k + 1].0 - rows[k].0,
                (rows[k + 1].0 - rows[k].0) as f64 / median as f64
            ),
        ));
    }
    Ok(())
}

/// A EuRoC sequence, rectified on load.
#[derive(Debug, Clone)]
pub struct EurocSequence {
    root: PathBuf,
    left: Vec<PathBuf>,
    right: Vec<PathBuf>,
    timestamps_ns: Vec<i64>,
    rectification: StereoRectification,
    raw_size: (usize, usize),
    left_map: RemapTable,
    right_map: RemapTable,
    poses: Option<Vec<Isometry3<f64>>>,
    notes: Vec<String>,
}

/// Largest time gap between a frame and its ground-truth row, nanoseconds.
const GT_TOLERANCE_NS: i64 = 5_000_000;

impl EurocSequence {
    /// Opens a EuRoC sequence (the directory holding `mav0`, or `mav0` itself).
    ///
    /// # Errors
    /// Missing or malformed `data.csv` / `sensor.yaml`, a left/right mismatch (count or
    /// timestamps), a degenerate stereo geometry.
    pub fn open(dir: &Path) -> Result<Self, DatasetError> {
        let m = mav0(dir);
        let (c0, c1) = (m.join("cam0"), m.join("cam1"));
        let l = read_image_list(&c0)?;
        let r = read_image_list(&c1)?;
        let (list0, list1) = (c0.join("data.csv"), c1.join("data.csv"));
        check_pairs(dir, &l, &list0, &r, &list1)?;
        check_timestamps(&l, &list0)?;
        check_timestamps(&r, &list1)?;
        let left: Vec<PathBuf> = l.iter().map(|x| x.1.clone()).collect();
        let right: Vec<PathBuf> = r.iter().map(|x| x.1.clone()).collect();
        let mut notes = match left.first() {
            Some(first) => crate::first_image(first)?.1,
            None => Vec::new(),
        };
        let s0 = read_sensor_yaml(&c0.join("sensor.yaml"))?;
        let s1 = read_sensor_yaml(&c1.join("sensor.yaml"))?;
        if (s0.camera.width, s0.camera.height) != (s1.camera.width, s1.camera.height) {
            return Err(DatasetError::SizeMismatch {
                first: c0.join("sensor.yaml"),
                first_size: (s0.camera.width, s0.camera.height),
                second: c1.join("sensor.yaml"),
                second_size: (s1.camera.width, s1.camera.height),
            });
        }
        // X_cam1 = T_BS1⁻¹ T_BS0 X_cam0.
        let right_from_left = s1.body_from_camera.inverse() * s0.body_from_camera;
        let rectification = stereo_rectify(
            &s0.camera,
            &s1.camera,
            right_from_left.rotation.to_rotation_matrix().matrix(),
            &right_from_left.translation.vector,
        )
        .map_err(|e| parse_error(&c1.join("sensor.yaml"), 0, e.to_string()))?;
        check_baseline(
            &c1.join("sensor.yaml"),
            0,
            rectification.rig.baseline_m,
            "T_BS of cam0 and cam1",
        )?;
        // Each camera's own intrinsics for its raw images, then the common rectified one.
        for (cam, s) in [(&c0, &s0), (&c1, &s1)] {
            let c = &s.camera;
            let raw = RectifiedStereo {
                fx: c.fx,
                fy: c.fy,
                cx: c.cx,
                cy: c.cy,
                ..rectification.rig
            };
            check_plausible(&cam.join("sensor.yaml"), &raw, (c.width, c.height))?;
        }
        check_plausible(
            &c1.join("sensor.yaml"),
            &rectification.rig,
            (rectification.width, rectification.height),
        )?;
        let (w, h) = (rectification.width, rectification.height);
        let left_map = rectify_map(
            &s0.camera,
            &rectification.rect_from_left,
            &rectification.rig,
            w,
            h,
        );
        let right_map = rectify_map(
            &s1.camera,
            &rectification.rect_from_right,
            &rectification.rig,
            w,
            h,
        );
        let gt_path = m.join("state_groundtruth_estimate0").join("data.csv");
        let timestamps_ns: Vec<i64> = l.iter().map(|x| x.0).collect();
        let poses = if gt_path.is_file() {
            // The rectified left camera in the world: T_WB T_BS0 R_rect⁻¹.
            let cam_from_rect = Isometry3::from_parts(
                Translation3::identity(),
                crate::nearest_rotation(&rectification.rect_from_left.transpose()),
            );
            let camera = (&s0.body_from_camera, &cam_from_rect);
            camera_ground_truth(&gt_path, &timestamps_ns, camera, &mut notes)?
        } else {
            None
        };
        Ok(Self {
            root: dir.to_owned(),
            left,
            right,
            timestamps_ns,
            rectification,
            raw_size: (s0.camera.width, s0.camera.height),
            left_map,
            right_map,
            poses,
            notes,
        })
    }

    /// The rectification (rotations and the common camera).
    #[must_use]
    pub fn rectification(&self) -> &StereoRectification {
        &self.rectification
    }

    /// Timestamps of the frames, nanoseconds.
    #[must_use]
    pub fn timestamps_ns(&self) -> &[i64] {
        &self.timestamps_ns
    }

    /// Frame `i` as recorded (raw, distorted, unrectified).
    ///
    /// # Errors
    /// As [`StereoSequence::frame`].
    pub fn raw_frame(&self, i: usize) -> Result<StereoPair, DatasetError> {
        let yaml = self.root.join("mav0/cam0/sensor.yaml");
        load_indexed_pair(
            &self.root,
            &self.left,
            &self.right,
            i,
            (self.raw_size, &yaml),
        )
    }
}

impl StereoSequence for EurocSequence {
    crate::sequence_fields!("euroc");

    fn calibration(&self) -> RectifiedStereo {
        self.rectification.rig
    }

    fn image_size(&self) -> (usize, usize) {
        (self.rectification.width, self.rectification.height)
    }

    fn frame(&self, i: usize) -> Result<StereoPair, DatasetError> {
        let raw = self.raw_frame(i)?;
        Ok(StereoPair {
            left: remap(raw.left.view(), &self.left_map),
            right: remap(raw.right.view(), &self.right_map),
        })
    }

    fn notes(&self) -> &[String] {
        &self.notes
    }

    fn timestamp_s(&self, i: usize) -> Option<f64> {
        let first = *self.timestamps_ns.first()?;
        Some((*self.timestamps_ns.get(i)? - first) as f64 * 1e-9)
    }

    fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        self.poses.as_deref()
    }
}
