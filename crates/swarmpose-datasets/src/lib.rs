//! # swarmpose-datasets
//!
//! Stereo image sequences behind one [`StereoSequence`] abstraction: frames in order as
//! rectified grayscale pairs, the rectified stereo calibration, and optional ground
//! truth. Three real layouts are read:
//!
//! | layout | module | notes |
//! |---|---|---|
//! | KITTI odometry | [`kitti`] | `image_0/`, `image_1/`, `calib.txt` (`P0:`, `P1:`), `poses.txt` or `../../poses/NN.txt` |
//! | Karlsruhe sequences | [`karlsruhe`] | `I1_*.png`, `I2_*.png`, `calib.txt` (`P1_roi`, `P2_roi`); INS data is not camera ground truth |
//! | EuRoC MAV (ASL) | [`euroc`] | raw images, undistorted and rectified on load from `sensor.yaml` |
//!
//! [`open`] detects the layout of a directory. RGB-D sequences (a gray image and a depth
//! image a frame) are behind [`DepthSequence`] ([`rgbd`]).
//!
//! Frames: ground-truth poses are those of the (rectified) LEFT camera at each frame,
//! expressed in the left camera frame of frame 0 (x right, y down, z forward, metres).
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

/// The [`StereoSequence`] methods that read a field: `layout` (the layout's name),
/// `root` and `len` of the `root` and `left` fields (of the field `$pairs` when given).
macro_rules! sequence_fields {
    ($layout:literal $(, $pairs:ident)?) => {
        fn layout(&self) -> &'static str {
            $layout
        }

        fn root(&self) -> &std::path::Path {
            &self$(.$pairs)?.root
        }

        fn len(&self) -> usize {
            self$(.$pairs)?.left.len()
        }
    };
}
pub(crate) use sequence_fields;

/// The [`StereoSequence`] methods of a layout whose frames are listed image files, kept in
/// the field `pairs` (`frames::ListedPairs`).
macro_rules! listed_sequence {
    ($layout:literal) => {
        $crate::sequence_fields!($layout, pairs);

        fn calibration(&self) -> RectifiedStereo {
            self.pairs.rig
        }

        fn image_size(&self) -> (usize, usize) {
            self.pairs.size
        }

        fn frame(&self, i: usize) -> Result<StereoPair, DatasetError> {
            let p = &self.pairs;
            $crate::load_listed_pair(&p.root, &p.left, &p.right, i, p.size)
        }

        fn notes(&self) -> &[String] {
            &self.pairs.notes
        }
    };
}
pub(crate) use listed_sequence;

pub mod error;
pub mod euroc;
mod frames;
pub mod karlsruhe;
pub mod kitti;
pub mod projection;
pub mod rgbd;
mod text;

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

pub use error::DatasetError;
pub use rgbd::{DepthSequence, Intrinsics, RgbdFrame};
pub use swarmpose_vision::image::GrayImage;
pub use swarmpose_vision::stereo::RectifiedStereo;

/// The stereo baselines accepted from a calibration, metres (the vision crate's, one
/// list for the loaders and the engine).
pub use swarmpose_vision::stereo::BASELINE_RANGE_M;

/// One rectified stereo frame, 8-bit grayscale, both images the same size.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StereoPair {
    /// Left image.
    pub left: GrayImage,
    /// Right image.
    pub right: GrayImage,
}

/// A stereo sequence: frames in order, calibration, optional ground truth.
pub trait StereoSequence: Send + Sync {
    /// The layout (`kitti`, `karlsruhe`, `euroc`).
    fn layout(&self) -> &'static str;

    /// The sequence directory.
    fn root(&self) -> &Path;

    /// Number of frames.
    fn len(&self) -> usize;

    /// True when there are no frames.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The rectified stereo model of every frame (pixels, baseline metres).
    fn calibration(&self) -> RectifiedStereo;

    /// Width and height of the rectified images, pixels.
    fn image_size(&self) -> (usize, usize);

    /// Loads frame `i` (0-based), rectified.
    ///
    /// # Errors
    /// A missing or unreadable image, images of different sizes, or `i` out of range;
    /// the message names the file.
    fn frame(&self, i: usize) -> Result<StereoPair, DatasetError>;

    /// Warnings found when the sequence was opened (for example 16-bit images read as
    /// 12-bit data without an `sBIT` chunk saying so), one line each, naming the file.
    fn notes(&self) -> &[String] {
        &[]
    }

    /// Ground-truth pose of the left camera at each frame in the left camera frame of
    /// frame 0, when the sequence has camera ground truth.
    fn ground_truth(&self) -> Option<&[Isometry3<f64>]>;

    /// Time of frame `i`, seconds since the first frame, when the layout records it
    /// (EuRoC); `None` otherwise, and the caller assumes a frame period.
    fn timestamp_s(&self, i: usize) -> Option<f64> {
        let _ = i;
        None
    }

    /// Ground-truth motion mapping frame-`j` camera coordinates into frame `i`:
    /// `pose_i⁻¹ · pose_j`, i.e. `dst = R src + t` with src in frame `j`, dst in frame `i`.
    fn relative_ground_truth(&self, i: usize, j: usize) -> Option<Isometry3<f64>> {
        let gt = self.ground_truth()?;
        Some(gt.get(i)?.inverse() * gt.get(j)?)
    }
}

/// Opens `dir`, detecting its layout.
///
/// # Errors
/// [`DatasetError::Missing`] when `dir` does not exist, [`DatasetError::UnknownLayout`]
/// when it matches no layout, or the loader's error.
pub fn open(dir: &Path) -> Result<Box<dyn StereoSequence>, DatasetError> {
    if !dir.is_dir() {
        return Err(DatasetError::Missing {
            path: dir.to_owned(),
            what: "sequence directory",
        });
    }
    if kitti::detect(dir) {
        return Ok(Box::new(kitti::KittiSequence::open(dir)?));
    }
    if euroc::detect(dir) {
        return Ok(Box::new(euroc::EurocSequence::open(dir)?));
    }
    if karlsruhe::detect(dir) {
        return Ok(Box::new(karlsruhe::KarlsruheSequence::open(dir)?));
    }
    Err(DatasetError::UnknownLayout {
        dir: dir.to_owned(),
    })
}

/// Loads a left/right pair of PNGs and checks that both have `expected` size (when
/// given) and the same size.
///
/// # Errors
/// Image errors naming the file; [`DatasetError::SizeMismatch`] naming both files.
pub fn load_pair(
    left: &Path,
    right: &Path,
    expected: Option<((usize, usize), &Path)>,
) -> Result<StereoPair, DatasetError> {
    let l = GrayImage::load_png(left)?;
    let r = GrayImage::load_png(right)?;
    let (ls, rs) = ((l.width, l.height), (r.width, r.height));
    if ls != rs {
        return Err(DatasetError::SizeMismatch {
            first: left.to_owned(),
            first_size: ls,
            second: right.to_owned(),
            second_size: rs,
        });
    }
    if let Some((size, reference)) = expected
        && ls != size
    {
        return Err(DatasetError::SizeMismatch {
            first: reference.to_owned(),
            first_size: size,
            second: left.to_owned(),
            second_size: ls,
        });
    }
    Ok(StereoPair { left: l, right: r })
}

/// Size of the first image of a sequence (read by decoding it), and a warning when it is
/// a 16-bit PNG read as 12-bit data without an `sBIT` chunk saying so.
pub(crate) fn first_image(path: &Path) -> Result<((usize, usize), Vec<String>), DatasetError> {
    let bytes = std::fs::read(path).map_err(|source| DatasetError::Io {
        path: path.to_owned(),
        source,
    })?;
    let (img, depth) = GrayImage::decode_png_with_depth(&bytes, path)?;
    let notes = (depth.source == swarmpose_vision::image::DepthSource::Guessed12)
        .then(|| {
            format!(
                "{}: a 16-bit PNG whose values all fit in 12 bits and no sBIT chunk gives \
                 the depth: read as 12-bit data (scaled by 4095, not 65535)",
                path.display()
            )
        })
        .into_iter()
        .collect();
    Ok(((img.width, img.height), notes))
}

/// The rotation nearest a 3x3 matrix read from a file, with a capped iteration count
/// (nalgebra's uncapped `Rotation3::from_matrix` can spin on a matrix far from any
/// rotation, such as a corrupted file's). Callers check first that `m` is within 1e-2 of
/// a rotation: even capped, nalgebra's perturbation loop never ends on a matrix with an
/// entry of 1e58 (found by the `euroc_sensor_yaml` fuzz target).
pub(crate) fn nearest_rotation(m: &nalgebra::Matrix3<f64>) -> nalgebra::UnitQuaternion<f64> {
    use nalgebra::{Rotation3, UnitQuaternion};
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_eps(
        m,
        1e-12,
        100,
        Rotation3::identity(),
    ))
}

/// Frame `i` of index-aligned left/right image lists of the sequence at `root`, checked
/// against the expected size (`expected`: the size and the file it was read from).
///
/// # Errors
/// [`DatasetError::FrameOutOfRange`], or as [`load_pair`].
pub(crate) fn load_indexed_pair(
    root: &Path,
    left: &[PathBuf],
    right: &[PathBuf],
    i: usize,
    expected: ((usize, usize), &Path),
) -> Result<StereoPair, DatasetError> {
    let (Some(l), Some(r)) = (left.get(i), right.get(i)) else {
        return Err(DatasetError::FrameOutOfRange {
            dir: root.to_owned(),
            index: i,
            len: left.len(),
        });
    };
    load_pair(l, r, Some(expected))
}

/// [`load_indexed_pair`] with the first left image as the reference of the expected size
/// (the KITTI and Karlsruhe layouts, whose sizes are read from that image).
///
/// # Errors
/// As [`load_indexed_pair`].
pub(crate) fn load_listed_pair(
    root: &Path,
    left: &[PathBuf],
    right: &[PathBuf],
    i: usize,
    size: (usize, usize),
) -> Result<StereoPair, DatasetError> {
    let first = left.first().map_or(root, PathBuf::as_path);
    load_indexed_pair(root, left, right, i, (size, first))
}

/// Rows of 12 numbers as row-major 3x4 `[R | t]` poses.
pub(crate) fn pose_from_3x4(m: &[f64]) -> Isometry3<f64> {
    use nalgebra::{Matrix3, Translation3};
    let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
    Isometry3::from_parts(Translation3::new(m[3], m[7], m[11]), nearest_rotation(&r))
}
