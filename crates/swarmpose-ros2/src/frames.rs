//! The engine's side of the intake: waits for the newest pair, checks it against its
//! `camera_info` and the camera the engine runs for, turns it into gray (rectified when
//! the images are raw), and reports every problem as a status ([`Reporter`]) instead of
//! stopping: images with no camera_info yet, a camera_info that disagrees with the
//! images, an unknown encoding, a side that never sends, a camera that changes size or
//! calibration mid-stream.

use std::sync::Arc;
use std::time::{Duration, Instant};

use swarmpose_datasets::RectifiedStereo;
use swarmpose_odometry::OwnedStereoFrame;
use swarmpose_ros::convert::seconds_since;
use swarmpose_ros::image::image_to_gray;
use swarmpose_ros::msg::{CameraInfo, DiagnosticStatus, Image};
use swarmpose_ros::stereo::calib::{Rig, rig_from_camera_info};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::rectify::remap;

use crate::dds::TopicNames;
use crate::intake::{Intake, Pair};
use crate::report::Reporter;
use crate::shared::Shared;

/// How long the engine waits without a pair before it says why.
pub const QUIET: Duration = Duration::from_secs(1);

/// A frame ready for the engine.
#[derive(Debug)]
pub struct Frame {
    /// The gray (rectified) images, the time since the first frame.
    pub frame: OwnedStereoFrame,
    /// The images' header stamp, nanoseconds.
    pub stamp_ns: i64,
    /// When the pair was complete.
    pub complete: Instant,
    /// The rig of the frame.
    pub rig: RectifiedStereo,
    /// The images' `frame_id` (the camera frame).
    pub frame_id: String,
    /// The left camera's `camera_info`.
    pub left_info: CameraInfo,
}

/// The calibration in use: the `camera_info` pair and image sizes it was made from.
struct InUse {
    left: CameraInfo,
    right: CameraInfo,
    sizes: [(usize, usize); 2],
    rig: Rig,
}

/// Whether two `camera_info` give the same calibration (stamps aside).
fn same_calibration(a: &CameraInfo, b: &CameraInfo) -> bool {
    (a.width, a.height, &a.distortion_model, &a.d, a.k, a.r, a.p)
        == (b.width, b.height, &b.distortion_model, &b.d, b.k, b.r, b.p)
}

fn size(img: &Image) -> (usize, usize) {
    (img.width as usize, img.height as usize)
}

/// The engine's source of frames.
pub struct Frames {
    shared: Arc<Shared>,
    names: TopicNames,
    reporter: Reporter,
    in_use: Option<InUse>,
    /// Set once the engine runs: its camera can no longer change.
    fixed: bool,
    first_stamp_ns: Option<i64>,
}

impl Frames {
    /// Frames from `shared`, problems reported through `reporter`.
    #[must_use]
    pub fn new(shared: Arc<Shared>, names: TopicNames, reporter: Reporter) -> Self {
        Self {
            shared,
            names,
            reporter,
            in_use: None,
            fixed: false,
            first_stamp_ns: None,
        }
    }

    /// From now on the camera may not change (the engine was built for it).
    pub fn fix_camera(&mut self) {
        self.fixed = true;
    }

    /// Reports a problem with a frame and counts it refused.
    pub fn refuse(&mut self, message: String) {
        let counts = {
            let mut i = self.shared.intake();
            i.counts.refused += 1;
            i.counts
        };
        self.reporter
            .problem(DiagnosticStatus::ERROR, message, counts);
    }

    /// The next frame: the newest pair once it passes the checks. `None` when the node
    /// is asked to stop (checked at least every [`crate::receive::POLL`]).
    pub fn next_frame(&mut self) -> Option<Frame> {
        let mut quiet_since = Instant::now();
        loop {
            let pair = {
                let mut intake = self.shared.intake();
                loop {
                    if self.shared.stopped_by().is_some() {
                        return None;
                    }
                    if let Some(p) = intake.take() {
                        break Some((p, intake.left_info.clone(), intake.right_info.clone()));
                    }
                    if quiet_since.elapsed() >= QUIET {
                        break None;
                    }
                    intake = self.shared.wait(intake, crate::receive::POLL);
                }
            };
            let Some((pair, li, ri)) = pair else {
                self.say_why_quiet();
                quiet_since = Instant::now();
                continue;
            };
            match self.check(pair, li, ri) {
                Ok(f) => return Some(f),
                Err(message) => self.refuse(message),
            }
        }
    }

    /// Reports why no pair came for [`QUIET`].
    fn say_why_quiet(&mut self) {
        let intake = self.shared.intake();
        let message = why_quiet(&intake, &self.names);
        let counts = intake.counts;
        drop(intake);
        self.reporter
            .problem(DiagnosticStatus::WARN, message, counts);
    }

    /// The rig for a pair of `camera_info` and image sizes: the one in use, or a new one
    /// (refused once the engine runs).
    fn rig(
        &mut self,
        li: CameraInfo,
        ri: CameraInfo,
        sizes: [(usize, usize); 2],
    ) -> Result<&Rig, String> {
        let same = self.in_use.as_ref().is_some_and(|u| {
            u.sizes == sizes && same_calibration(&u.left, &li) && same_calibration(&u.right, &ri)
        });
        if !same {
            if let Some(u) = self.in_use.as_ref().filter(|_| self.fixed) {
                let what = if u.sizes == sizes {
                    "the camera_info changed".to_owned()
                } else {
                    format!(
                        "the images changed size from {}x{} to {}x{}",
                        u.sizes[0].0, u.sizes[0].1, sizes[0].0, sizes[0].1
                    )
                };
                return Err(format!(
                    "{what} mid-stream: the engine runs for the first camera; frame refused \
                     (restart the node for another camera)"
                ));
            }
            let rig = rig_from_camera_info(&li, &ri, sizes[0], sizes[1]).map_err(|m| {
                format!(
                    "{} and {}: {m}",
                    self.names.left_info, self.names.right_info
                )
            })?;
            self.in_use = Some(InUse {
                left: li,
                right: ri,
                sizes,
                rig,
            });
        }
        self.in_use
            .as_ref()
            .map(|u| &u.rig)
            .ok_or_else(|| "no calibration".to_owned())
    }

    /// Checks a pair and turns it into a frame, or says why it is refused.
    fn check(
        &mut self,
        p: Pair,
        li: Option<CameraInfo>,
        ri: Option<CameraInfo>,
    ) -> Result<Frame, String> {
        let (li, ri) = match (li, ri) {
            (Some(l), Some(r)) => (l, r),
            (l, _) => {
                let missing = if l.is_none() {
                    &self.names.left_info
                } else {
                    &self.names.right_info
                };
                return Err(format!(
                    "no camera_info yet on {missing}: the rig is unknown, frame refused"
                ));
            }
        };
        let left_info = li.clone();
        let t = Instant::now();
        let gray = |img: &Image, side: &str, topic: &str| {
            image_to_gray(img).map_err(|e| format!("{side} image on {topic}: {e}"))
        };
        // The encodings first: a size check of an image that cannot be read is moot.
        let (l, r) = (
            gray(&p.left, "left", &self.names.left)?,
            gray(&p.right, "right", &self.names.right)?,
        );
        let rig = self.rig(li, ri, [size(&p.left), size(&p.right)])?;
        let (l, r): (GrayImage, GrayImage) = match rig {
            Rig::Rectified(_) => (l, r),
            Rig::Raw { left, right, .. } => (remap(l.view(), left), remap(r.view(), right)),
        };
        let rectified = rig.rectified();
        let first = *self.first_stamp_ns.get_or_insert(p.stamp_ns);
        Ok(Frame {
            frame: OwnedStereoFrame {
                left: l,
                right: r,
                timestamp_s: seconds_since(first, p.stamp_ns),
                load_ms: t.elapsed().as_secs_f64() * 1e3,
            },
            stamp_ns: p.stamp_ns,
            complete: p.complete,
            rig: rectified,
            frame_id: p.left.header.frame_id,
            left_info,
        })
    }
}

/// Why no pair came: nothing received, one side silent, or stamps that never agree.
fn why_quiet(intake: &Intake, names: &TopicNames) -> String {
    let c = intake.counts;
    if let Some(e) = &intake.decode_error {
        return e.clone();
    }
    match (c.left, c.right) {
        (0, 0) => format!("waiting for images on {} and {}", names.left, names.right),
        (n, 0) => format!(
            "{n} left images on {} but no right image on {}",
            names.left, names.right
        ),
        (0, n) => format!(
            "{n} right images on {} but no left image on {}",
            names.right, names.left
        ),
        _ if intake.waiting() == (0, 0) => format!(
            "no new images on {} and {} ({} pairs so far)",
            names.left, names.right, c.pairs
        ),
        _ => {
            let (l, r) = intake.newest_waiting_ns();
            let ns = |s: Option<i64>| s.map_or("none".to_owned(), |v| format!("{v} ns"));
            format!(
                "no new pair: left and right images with equal header stamps are needed \
                 (exact-stamp pairing; newest waiting left {}, right {})",
                ns(l),
                ns(r)
            )
        }
    }
}
