//! RGB-D input, as the paper also allows: the TUM RGB-D layout. A directory with
//! `rgb.txt` and `depth.txt` (`timestamp filename` per line, `#` comments), the images
//! they name (colour or gray PNGs; 16-bit depth PNGs, 5000 per metre, 0 and 65535 = no
//! depth; other images named as depth are refused),
//! optionally `groundtruth.txt` (TUM trajectory of the colour camera) and
//! `intrinsics.txt` (the four numbers `fx fy cx cy` and nothing else; default 525, 525, 319.5, 239.5, TUM's
//! recommendation for its sequences as published).
//!
//! Each colour image is paired with the depth image nearest in time within 20 ms (as
//! TUM's `associate.py`), and the ground truth with the nearest pose within 20 ms. The
//! features of the gray image with a valid depth become the frame's 3D points, with a
//! Kinect-like noise model (depth σ = 1.425e-3 z² m, 0.5 px in the image).

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use swarmpose_eval::{Format, Trajectory};
use swarmpose_vision::image::GrayImage;

use crate::error::RunError;
use swarmpose_datasets::{DatasetError, DepthSequence, RgbdFrame};
use swarmpose_odometry::StereoCamera;

/// Depth PNG units per metre.
pub const DEPTH_SCALE: f64 = 5000.0;
/// Largest time between paired colour, depth and ground truth, seconds.
pub const MAX_DIFF_S: f64 = 0.02;

/// Pinhole intrinsics, pixels (default: TUM's recommendation, 525, 525, 319.5, 239.5).
pub use swarmpose_datasets::Intrinsics;

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

fn rgbd_err(path: &Path, line: usize, message: impl Into<String>) -> RunError {
    RunError::Rgbd {
        path: path.to_owned(),
        line,
        message: message.into(),
    }
}

/// A text file of the sequence, without a leading UTF-8 byte-order mark (accepted, as by
/// every reader).
fn read_text(path: &Path) -> Result<String, RunError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| rgbd_err(path, 0, format!("cannot read: {e}")))?;
    Ok(text.strip_prefix('\u{feff}').unwrap_or(&text).to_owned())
}

fn read_list(dir: &Path, name: &str) -> Result<Vec<(f64, PathBuf)>, RunError> {
    let path = dir.join(name);
    let text = read_text(&path)?;
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
    /// [`RunError::Rgbd`] naming the file (and line) that is missing or malformed,
    /// or a colour image without a depth image within 20 ms, or a frame without a
    /// ground-truth pose within 20 ms when `groundtruth.txt` exists.
    pub fn open(dir: &Path) -> Result<Self, RunError> {
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

    /// The camera of the sequence (its intrinsics, the size of its first image; the
    /// baseline is the RGB-D engine's virtual one).
    ///
    /// # Errors
    /// [`RunError::Dataset`] when the first image cannot be read, or naming
    /// `intrinsics.txt` when its numbers are not a plausible camera for the images.
    pub fn camera(&self) -> Result<StereoCamera, RunError> {
        crate::batch::rgbd_camera(self)
    }

    /// Loads frame `i`: the gray image and the depth in metres (0 = none).
    ///
    /// # Errors
    /// [`RunError::Rgbd`] naming an unreadable image or sizes that differ.
    pub fn frame(&self, i: usize) -> Result<(GrayImage, Vec<f32>), RunError> {
        let Some((_, rgb, depth)) = self.frames.get(i) else {
            return Err(rgbd_err(&self.root, 0, format!("frame {i} out of range")));
        };
        let gray = GrayImage::load_png(rgb).map_err(|e| rgbd_err(rgb, 0, e.to_string()))?;
        let d = image::ImageReader::open(depth)
            .map_err(|e| rgbd_err(depth, 0, format!("cannot read: {e}")))?
            .decode()
            .map_err(|e| rgbd_err(depth, 0, format!("cannot decode: {e}")))?;
        // Only 16-bit one-channel images are depth: an 8-bit image (scaled by 257 it
        // read as depths up to 13 m) or a colour one (a depth list naming colour images)
        // is refused.
        let image::DynamicImage::ImageLuma16(d) = d else {
            return Err(rgbd_err(
                depth,
                0,
                format!(
                    "a {:?} image is not a depth image: TUM depth images are 16-bit gray \
                     ({DEPTH_SCALE} per metre)",
                    d.color()
                ),
            ));
        };
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
            .map(|v| {
                // 65535 is a sensor's saturated or "too far" value, not 13.107 m: no
                // depth (a band of it skewed the motion 68 %).
                if v == u16::MAX {
                    0.0
                } else {
                    (f64::from(v) / DEPTH_SCALE) as f32
                }
            })
            .collect();
        Ok((gray, metres))
    }
}

fn read_intrinsics(path: &Path) -> Result<Intrinsics, RunError> {
    if !path.is_file() {
        return Ok(Intrinsics::default());
    }
    let text = read_text(path)?;
    // Numbers only, in the order fx fy cx cy: a labelled file ("cx 319.5 ...") had its
    // labels dropped and its numbers taken in the order written.
    let v: Vec<f64> = text
        .split_whitespace()
        .map(|s| {
            s.parse().map_err(|_| {
                rgbd_err(
                    path,
                    1,
                    format!("'{s}' is not a number: expected four numbers: fx fy cx cy"),
                )
            })
        })
        .collect::<Result<_, _>>()?;
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

/// A [`RunError`] of the reader as the sequences' error (the same line).
fn dataset_error(e: RunError) -> DatasetError {
    match e {
        RunError::Rgbd {
            path,
            line,
            message,
        } => DatasetError::Parse {
            path,
            line,
            message,
        },
        RunError::Dataset(d) => d,
        other => DatasetError::Parse {
            path: std::path::PathBuf::new(),
            line: 0,
            message: other.to_string(),
        },
    }
}

impl DepthSequence for RgbdSequence {
    fn layout(&self) -> &'static str {
        "tum rgb-d"
    }

    fn root(&self) -> &Path {
        &self.root
    }

    fn len(&self) -> usize {
        self.frames.len()
    }

    fn camera(&self) -> Result<(Intrinsics, (usize, usize)), DatasetError> {
        let Some((_, rgb, _)) = self.frames.first() else {
            return Err(dataset_error(rgbd_err(&self.root, 0, "no frame")));
        };
        let (w, h) = image::image_dimensions(rgb)
            .map_err(|e| dataset_error(rgbd_err(rgb, 0, format!("cannot read: {e}"))))?;
        let size = (w as usize, h as usize);
        match self.intrinsics.implausibility(size.0, size.1) {
            Some(why) => Err(dataset_error(rgbd_err(
                &self.root.join("intrinsics.txt"),
                0,
                why,
            ))),
            None => Ok((self.intrinsics, size)),
        }
    }

    fn frame(&self, i: usize) -> Result<RgbdFrame, DatasetError> {
        let (gray, depth_m) = RgbdSequence::frame(self, i).map_err(dataset_error)?;
        Ok(RgbdFrame { gray, depth_m })
    }

    fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        self.ground_truth.as_deref()
    }

    fn timestamp_s(&self, i: usize) -> Option<f64> {
        self.frames.get(i).map(|f| f.0)
    }
}
