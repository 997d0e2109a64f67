//! One front door for every stereo input: a ROS 2 bag (an `.mcap` or `.db3` file, or a
//! folder with `metadata.yaml`) or a dataset folder ([`swarmpose_datasets::open`]).

use std::path::Path;

use swarmpose_datasets::{DatasetError, StereoSequence};

use crate::msg::CameraInfo;
use crate::stereo::pairing::UnpairedImage;
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

/// What a bag adds to a sequence for the ROS 2 outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct BagInfo {
    /// The left images' `frame_id`.
    pub frame_id: String,
    /// The left camera's `camera_info`.
    pub camera_info: CameraInfo,
    /// The header stamp of each frame, nanoseconds.
    pub stamps_ns: Vec<i64>,
    /// The left and right image topics.
    pub topics: (String, String),
    /// The images left without a partner (in no frame), in stamp order.
    pub unpaired: Vec<UnpairedImage>,
    /// Where reading stopped early (a cut bag), if it did.
    pub stopped: Option<String>,
}

/// An opened stereo input.
pub struct Opened {
    /// The frames.
    pub sequence: Box<dyn StereoSequence>,
    /// For a bag, what it adds.
    pub bag: Option<BagInfo>,
}

impl std::fmt::Debug for Opened {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Opened")
            .field("layout", &self.sequence.layout())
            .field("frames", &self.sequence.len())
            .field("bag", &self.bag)
            .finish()
    }
}

/// Opens `path`: a ROS 2 bag with `opts`, or else a dataset folder (`opts` unused).
///
/// # Errors
/// The bag's error (one line naming the bag), or the folder loader's.
pub fn open_stereo(path: &Path, opts: &StereoOptions) -> Result<Opened, DatasetError> {
    if !is_bag(path) {
        if opts.left.is_some() || opts.right.is_some() {
            return Err(DatasetError::Parse {
                path: path.to_owned(),
                line: 0,
                message: "topics are named for a ROS 2 bag, and this is not one".to_owned(),
            });
        }
        return Ok(Opened {
            sequence: swarmpose_datasets::open(path)?,
            bag: None,
        });
    }
    let seq = BagSequence::open(path, opts).map_err(|e| to_dataset(&e))?;
    let (l, r) = seq.topics();
    let bag = BagInfo {
        frame_id: seq.frame_id().to_owned(),
        camera_info: seq.camera_info().clone(),
        stamps_ns: seq.stamps_ns(),
        topics: (l.to_owned(), r.to_owned()),
        unpaired: seq.unpaired().to_vec(),
        stopped: seq.bag().stopped().map(str::to_owned),
    };
    Ok(Opened {
        sequence: Box::new(seq),
        bag: Some(bag),
    })
}
