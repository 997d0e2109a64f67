//! Synthetic sequences with known motion. This module: a built-in synthetic stereo
//! sequence, so that odometry runs with no data: a street of textured planes (ground,
//! two house fronts, a far wall) rendered by the vision crate's ray caster from a stereo
//! rig driving along a known, gently turning path. [`features`]: a stream of triangulated
//! features without images, of any length, optionally with a [`vehicle`] ahead.

pub mod features;
pub mod vehicle;

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use swarmpose_datasets::{DatasetError, StereoPair, StereoSequence};

use crate::error::RunError;
use swarmpose_vision::render::{TexturedPlane, depth_at, render};
use swarmpose_vision::stereo::RectifiedStereo;

/// The rig of the synthetic sequence (KITTI-like baseline, a small image).
pub const RIG: RectifiedStereo = RectifiedStereo {
    fx: 450.0,
    fy: 450.0,
    cx: 239.5,
    cy: 143.5,
    baseline_m: 0.54,
};
/// Image size, pixels.
pub const SIZE: (usize, usize) = (480, 288);

/// The synthetic sequence: `n` frames, `step_m` forward and `yaw_rad` to the right per
/// frame.
#[derive(Debug, Clone)]
pub struct SyntheticSequence {
    root: PathBuf,
    planes: Vec<TexturedPlane>,
    poses: Vec<Isometry3<f64>>,
    samples: usize,
    right_error: RightCameraError,
    focal_scale: f64,
}

/// How the rendered right camera differs from the calibration the sequence reports
/// (which stays [`RIG`]): to test self-calibration.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RightCameraError {
    /// Principal point column of the right camera minus the calibration's, pixels: every
    /// measured disparity is short by this much.
    pub principal_point_px: f64,
    /// Yaw of the right camera about its y axis (down), radians: positive turns it to the
    /// right, so measured disparities are short by about `−fx ψ (1 + x²)`.
    pub yaw_rad: f64,
    /// Pitch of the right camera about its x axis (right), radians.
    pub pitch_rad: f64,
    /// Roll of the right camera about its z axis (forward), radians.
    pub roll_rad: f64,
    /// Focal length of the right camera (`fx` and `fy`) minus the calibration's, pixels:
    /// measured disparities are short by about `focal_px · x` (`x` the right camera's
    /// normalised column), and its rows are off by `focal_px · y`.
    pub focal_px: f64,
}

impl SyntheticSequence {
    /// `n` frames moving `step_m` metres forward and turning `yaw_rad` (about the camera
    /// `y` axis, down: positive turns right) per frame.
    #[must_use]
    pub fn new(n: usize, step_m: f64, yaw_rad: f64) -> Self {
        let plane =
            |origin: [f64; 3], u: Vector3<f64>, v: Vector3<f64>, cell: f64, seed| TexturedPlane {
                origin: Point3::new(origin[0], origin[1], origin[2]),
                u,
                v,
                cell_m: cell,
                seed,
            };
        let planes = vec![
            // Ground 1.6 m below the camera (y is down).
            plane([0.0, 1.6, 0.0], Vector3::x(), Vector3::z(), 0.12, 11),
            // House fronts 5 m to the left and 6 m to the right.
            plane([-5.0, 0.0, 0.0], Vector3::z(), Vector3::y(), 0.15, 12),
            plane([6.0, 0.0, 0.0], Vector3::z(), Vector3::y(), 0.15, 13),
            // A far wall.
            plane([0.0, 0.0, 45.0], Vector3::x(), Vector3::y(), 0.3, 14),
        ];
        let mut poses = Vec::with_capacity(n);
        let mut pose = Isometry3::identity();
        for _ in 0..n {
            poses.push(pose);
            let step = Isometry3::from_parts(
                Translation3::new(0.0, 0.0, step_m),
                UnitQuaternion::from_axis_angle(&Vector3::y_axis(), yaw_rad),
            );
            pose *= step;
        }
        Self {
            root: PathBuf::from("<built-in synthetic sequence>"),
            planes,
            poses,
            samples: 2,
            right_error: RightCameraError::default(),
            focal_scale: 1.0,
        }
    }

    /// `n` frames of a rig facing one flat textured wall `distance_m` metres ahead (normal
    /// along the first camera's `z`, texture cells of `cell_m` metres), moving by `step_m`
    /// (metres, the first camera's `x`, `y`, `z`: `[0, 0, 0.3]` approaches the wall along
    /// the optical axis) per frame without turning. Every point of the scene is at the same
    /// depth in a frame, so a disparity offset and a scale of the scene are nearly
    /// indistinguishable: the self-calibration must not correct anything here.
    #[must_use]
    pub fn facing_wall(n: usize, distance_m: f64, step_m: [f64; 3], cell_m: f64) -> Self {
        let step = Vector3::from(step_m);
        Self {
            root: PathBuf::from("<built-in synthetic wall>"),
            planes: vec![TexturedPlane::fronto_parallel(distance_m, cell_m, 21)],
            poses: (0..n)
                .map(|i| Isometry3::from(Translation3::from(step * i as f64)))
                .collect(),
            samples: 2,
            right_error: RightCameraError::default(),
            focal_scale: 1.0,
        }
    }

    /// The same scene and path with other textures: every plane's texture seed offset by
    /// `seed` (0 leaves the sequence as it is). Each seed renders an independent draw of
    /// the texture (and of its rendering error), to tell a figure of one sequence from the
    /// sampling noise of a short one.
    #[must_use]
    pub fn with_texture_seed(mut self, seed: u64) -> Self {
        for (k, plane) in self.planes.iter_mut().enumerate() {
            plane.seed = plane.seed.wrapping_add(seed.wrapping_mul(1_000 + k as u64));
        }
        self
    }

    /// The same sequence rendered with a right camera that is not the calibrated one.
    #[must_use]
    pub fn with_right_camera_error(mut self, error: RightCameraError) -> Self {
        self.right_error = error;
        self
    }

    /// The same sequence rendered by cameras whose focal length (both cameras, `fx` and
    /// `fy`) is `scale` times the calibration's, which stays [`RIG`]: to test the
    /// self-calibration of the focal length.
    #[must_use]
    pub fn with_focal_error(mut self, scale: f64) -> Self {
        self.focal_scale = scale;
        self
    }
}

impl SyntheticSequence {
    /// Writes the sequence's left camera as a TUM RGB-D directory: `rgb/` (gray PNGs),
    /// `depth/` (16-bit PNGs, 5000 per metre, 0 beyond 13 m), `rgb.txt`, `depth.txt`
    /// (depth stamped 5 ms after colour), `groundtruth.txt` (the path in a world frame
    /// that is not the first camera's) and `intrinsics.txt`; frames at 30 Hz.
    ///
    /// # Errors
    /// [`RunError::Write`] naming the file.
    pub fn write_tum_rgbd(&self, dir: &Path) -> Result<(), RunError> {
        let werr = |path: &Path, e: &dyn std::fmt::Display| RunError::Write {
            path: path.to_owned(),
            message: e.to_string(),
        };
        for sub in ["rgb", "depth"] {
            let d = dir.join(sub);
            std::fs::create_dir_all(&d).map_err(|e| werr(&d, &e))?;
        }
        let world = Isometry3::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.1, 0.4, -0.2));
        let (mut rgb, mut depth) = (
            String::from("# color images\n# timestamp filename\n"),
            String::from("# depth maps\n# timestamp filename\n"),
        );
        let mut gt_poses = Vec::new();
        let mut stamps = Vec::new();
        for (i, pose) in self.poses.iter().enumerate() {
            let t = 1_305_031_102.0 + i as f64 / 30.0;
            let img = render(&RIG, pose, SIZE.0, SIZE.1, &self.planes, self.samples);
            let name = format!("rgb/{t:.6}.png");
            let path = dir.join(&name);
            img.save_png(&path).map_err(|e| werr(&path, &e))?;
            rgb.push_str(&format!("{t:.6} {name}\n"));
            let mut d = Vec::with_capacity(SIZE.0 * SIZE.1);
            for v in 0..SIZE.1 {
                for u in 0..SIZE.0 {
                    let z = depth_at(&RIG, pose, &self.planes, u as f64, v as f64).unwrap_or(0.0);
                    let units = (z * crate::rgbd::DEPTH_SCALE).round();
                    d.push(if (1.0..65535.0).contains(&units) {
                        units as u16
                    } else {
                        0
                    });
                }
            }
            let td = t + 0.005;
            let name = format!("depth/{td:.6}.png");
            let path = dir.join(&name);
            image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(
                SIZE.0 as u32,
                SIZE.1 as u32,
                d,
            )
            .ok_or_else(|| werr(&path, &"bad buffer"))?
            .save(&path)
            .map_err(|e| werr(&path, &e))?;
            depth.push_str(&format!("{td:.6} {name}\n"));
            gt_poses.push(world * pose);
            stamps.push(t);
        }
        let files = [
            ("rgb.txt", rgb),
            ("depth.txt", depth),
            (
                "groundtruth.txt",
                swarmpose_eval::trajectory::tum_text(&stamps, &gt_poses),
            ),
            (
                "intrinsics.txt",
                format!("{} {} {} {}\n", RIG.fx, RIG.fy, RIG.cx, RIG.cy),
            ),
        ];
        for (name, text) in files {
            let path = dir.join(name);
            std::fs::write(&path, text).map_err(|e| werr(&path, &e))?;
        }
        Ok(())
    }
}

impl Default for SyntheticSequence {
    /// 20 frames, 0.6 m and 1 degree to the right per frame.
    fn default() -> Self {
        Self::new(20, 0.6, 1f64.to_radians())
    }
}

impl StereoSequence for SyntheticSequence {
    fn layout(&self) -> &'static str {
        "synthetic"
    }

    fn root(&self) -> &Path {
        &self.root
    }

    fn len(&self) -> usize {
        self.poses.len()
    }

    fn calibration(&self) -> RectifiedStereo {
        RIG
    }

    fn image_size(&self) -> (usize, usize) {
        SIZE
    }

    fn frame(&self, i: usize) -> Result<StereoPair, DatasetError> {
        let Some(pose) = self.poses.get(i) else {
            return Err(DatasetError::Missing {
                path: self.root.join(format!("frame {i}")),
                what: "synthetic frame",
            });
        };
        let e = self.right_error;
        let right = pose
            * Isometry3::translation(RIG.baseline_m, 0.0, 0.0)
            * Isometry3::rotation(Vector3::new(e.pitch_rad, e.yaw_rad, e.roll_rad));
        let left_rig = RectifiedStereo {
            fx: RIG.fx * self.focal_scale,
            fy: RIG.fy * self.focal_scale,
            ..RIG
        };
        let right_rig = RectifiedStereo {
            fx: left_rig.fx + e.focal_px,
            fy: left_rig.fy + e.focal_px,
            cx: RIG.cx + e.principal_point_px,
            ..left_rig
        };
        Ok(StereoPair {
            left: render(&left_rig, pose, SIZE.0, SIZE.1, &self.planes, self.samples),
            right: render(
                &right_rig,
                &right,
                SIZE.0,
                SIZE.1,
                &self.planes,
                self.samples,
            ),
        })
    }

    fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        Some(&self.poses)
    }
}
