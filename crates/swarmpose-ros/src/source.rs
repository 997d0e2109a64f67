//! One front door for every input but a TUM RGB-D folder (whose reader is
//! swarmpose-runs', put before this door by the command line's `odometry::input`, which
//! Python uses too): a ROS 2 bag (an `.mcap` or `.db3` file, or a folder with
//! `metadata.yaml`; stereo or RGB-D) or a stereo dataset folder
//! ([`swarmpose_datasets::open`]).

use std::path::Path;

use nalgebra::Isometry3;
use swarmpose_datasets::{DatasetError, DepthSequence, StereoSequence};

use crate::bag::Bag;
use crate::rgbd::{BagRgbdSequence, rgbd_cameras};
use crate::stereo::frames::BagInfo;
use crate::stereo::{BagSequence, StereoOptions, to_dataset};

/// True when `path` is a ROS 2 bag: an `.mcap` or `.db3` file, or a folder with
/// `metadata.yaml`.
#[must_use]
pub fn is_bag(path: &Path) -> bool {
    if path.is_dir() {
        return path.join("metadata.yaml").is_file();
    }
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mcap") || e.eq_ignore_ascii_case("db3"))
}

/// The frames of an input.
pub enum Input {
    /// Stereo pairs.
    Stereo(Box<dyn StereoSequence>),
    /// RGB-D frames.
    Rgbd(Box<dyn DepthSequence>),
}

impl Input {
    /// Number of frames.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::Stereo(s) => s.len(),
            Self::Rgbd(s) => s.len(),
        }
    }

    /// True when there are no frames.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The layout (`kitti`, `ros2 bag`, `ros2 bag, rgb-d`, ...).
    #[must_use]
    pub fn layout(&self) -> &'static str {
        match self {
            Self::Stereo(s) => s.layout(),
            Self::Rgbd(s) => s.layout(),
        }
    }

    /// The folder or bag read.
    #[must_use]
    pub fn root(&self) -> &Path {
        match self {
            Self::Stereo(s) => s.root(),
            Self::Rgbd(s) => s.root(),
        }
    }

    /// The ground-truth poses of the (left, colour) camera in the first frame's, when
    /// the input has them.
    #[must_use]
    pub fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        match self {
            Self::Stereo(s) => s.ground_truth(),
            Self::Rgbd(s) => s.ground_truth(),
        }
    }
}

/// An opened input: its frames, and what a bag adds.
pub struct OpenedInput {
    /// The frames.
    pub input: Input,
    /// For a bag, what it adds.
    pub bag: Option<BagInfo>,
}

impl std::fmt::Debug for OpenedInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenedInput")
            .field("layout", &self.input.layout())
            .field("frames", &self.input.len())
            .field("bag", &self.bag)
            .finish()
    }
}

/// Opens `path`: a ROS 2 bag with `opts` (RGB-D when a depth topic is named or it has
/// one colour and one depth camera, else stereo), or else a stereo dataset folder (`opts`
/// unused).
///
/// # Errors
/// The bag's error (one line naming the bag), or the folder loader's.
pub fn open_input(path: &Path, opts: &StereoOptions) -> Result<OpenedInput, DatasetError> {
    if !is_bag(path) {
        if opts.left.is_some() || opts.right.is_some() || opts.depth.is_some() {
            return Err(DatasetError::Parse {
                path: path.to_owned(),
                line: 0,
                message: "topics are named for a ROS 2 bag, and this is not one".to_owned(),
            });
        }
        return Ok(OpenedInput {
            input: Input::Stereo(swarmpose_datasets::open(path)?),
            bag: None,
        });
    }
    let ros = |e: crate::RosError| to_dataset(&e);
    let bag = Bag::open(path).map_err(ros)?;
    if let Some((colour, depth)) = rgbd_cameras(&bag, opts).map_err(ros)? {
        let seq = BagRgbdSequence::from_bag(bag, &colour, &depth, opts).map_err(ros)?;
        let info = seq.frames().info();
        return Ok(OpenedInput {
            input: Input::Rgbd(Box::new(seq)),
            bag: Some(info),
        });
    }
    let seq = BagSequence::from_bag(bag, opts).map_err(ros)?;
    let info = seq.frames().info();
    Ok(OpenedInput {
        input: Input::Stereo(Box::new(seq)),
        bag: Some(info),
    })
}
