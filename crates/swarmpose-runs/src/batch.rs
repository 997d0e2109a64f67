//! Runs over recorded sequences: loops that feed the engine one frame at a time, so
//! that a directory is processed exactly as a live camera would be.

use std::ops::ControlFlow;
use std::time::Instant;

use swarmpose_datasets::{DepthSequence, StereoSequence};

use swarmpose_odometry::{
    DepthView, FrameResult, Odometry, OwnedStereoFrame, RgbdInput, RunEnd, RunFailure,
    StereoCamera, StereoInput,
};

use crate::error::RunError;

/// Milliseconds since `t`.
fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The camera of a stereo sequence.
#[must_use]
pub fn camera_of(seq: &dyn StereoSequence) -> StereoCamera {
    let (width, height) = seq.image_size();
    StereoCamera {
        rig: seq.calibration(),
        width,
        height,
    }
}

/// The time of frame `i` of `seq`, seconds: the sequence's own, or `i × frame_period_s`.
#[must_use]
pub fn time_of(seq: &dyn StereoSequence, i: usize, frame_period_s: f64) -> f64 {
    seq.timestamp_s(i).unwrap_or(i as f64 * frame_period_s)
}

/// Feeds the frames of `seq` to `odometry` in order, frame `i` at the time the sequence
/// records for it ([`StereoSequence::timestamp_s`]) or else `i × frame_period_s`, and
/// calls `on_frame` with each result as soon as it exists; it
/// may stop the run by returning [`ControlFlow::Break`].
///
/// # Errors
/// [`RunError::AtFrame`] with the index of the first frame that cannot be loaded or
/// taken; the frames before it were given to `on_frame`.
pub fn run_sequence(
    seq: &dyn StereoSequence,
    odometry: &mut Odometry,
    frame_period_s: f64,
    on_frame: &mut dyn FnMut(&FrameResult) -> ControlFlow<()>,
) -> Result<RunEnd, RunError> {
    for i in 0..seq.len() {
        let at = |e: RunError| e.at_frame(i);
        let t = Instant::now();
        let pair = seq.frame(i).map_err(|e| at(e.into()))?;
        let load_ms = ms(t);
        let input = StereoInput {
            left: pair.left.view(),
            right: pair.right.view(),
            timestamp_s: time_of(seq, i, frame_period_s),
        };
        let r = odometry
            .track_timed(input, load_ms)
            .map_err(|e| at(e.into()))?;
        if on_frame(&r).is_break() {
            return Ok(RunEnd::Stopped(i + 1));
        }
    }
    Ok(RunEnd::Finished)
}

/// [`run_sequence`] on two threads ([`Odometry::run_two_threads`]): frame `i + 1` is
/// loaded and goes through the front end while the back end works on frame `i`. The
/// same results as [`run_sequence`].
///
/// # Errors
/// As [`run_sequence`].
pub fn run_sequence_two_threads(
    seq: &dyn StereoSequence,
    odometry: &mut Odometry,
    frame_period_s: f64,
    on_frame: &mut dyn FnMut(&FrameResult) -> ControlFlow<()>,
) -> Result<RunEnd, RunError> {
    let frames = (0..seq.len()).map(|i| {
        let t = Instant::now();
        let pair = seq.frame(i).map_err(RunError::from)?;
        Ok(OwnedStereoFrame {
            load_ms: ms(t),
            left: pair.left,
            right: pair.right,
            timestamp_s: time_of(seq, i, frame_period_s),
        })
    });
    odometry.run_two_threads(frames, on_frame)
}

/// The camera of an RGB-D sequence: its intrinsics and image size, with the RGB-D
/// engine's virtual baseline.
///
/// # Errors
/// [`RunError::Dataset`]: the sequence's camera cannot be read or is not plausible.
pub fn rgbd_camera(seq: &dyn DepthSequence) -> Result<StereoCamera, RunError> {
    let (k, (width, height)) = seq.camera()?;
    // Checked by the sequence; the virtual baseline is the engine's own.
    Ok(StereoCamera {
        rig: swarmpose_vision::stereo::RectifiedStereo {
            fx: k.fx,
            fy: k.fy,
            cx: k.cx,
            cy: k.cy,
            baseline_m: swarmpose_odometry::frontend::RgbdNoise::default().virtual_baseline_m,
        },
        width,
        height,
    })
}

/// [`run_sequence`] for an RGB-D sequence (a TUM RGB-D folder, an RGB-D bag), frame `i`
/// at its own time ([`DepthSequence::timestamp_s`]).
///
/// # Errors
/// As [`run_sequence`].
pub fn run_rgbd_sequence(
    seq: &dyn DepthSequence,
    odometry: &mut Odometry,
    on_frame: &mut dyn FnMut(&FrameResult) -> ControlFlow<()>,
) -> Result<RunEnd, RunError> {
    for i in 0..seq.len() {
        let at = |e: RunError| e.at_frame(i);
        let t = Instant::now();
        let frame = seq.frame(i).map_err(|e| at(e.into()))?;
        let load_ms = ms(t);
        let input = RgbdInput {
            gray: frame.gray.view(),
            depth: DepthView {
                width: frame.gray.width,
                height: frame.gray.height,
                data: &frame.depth_m,
            },
            timestamp_s: seq.timestamp_s(i).unwrap_or(0.0),
        };
        let r = odometry
            .track_rgbd_timed(input, load_ms)
            .map_err(|e| at(e.into()))?;
        if on_frame(&r).is_break() {
            return Ok(RunEnd::Stopped(i + 1));
        }
    }
    Ok(RunEnd::Finished)
}

/// Every result of a whole run, for tests and tools (a run's results grow with its
/// length; the engine's state does not).
///
/// # Errors
/// As [`run_sequence`].
pub fn collect(
    seq: &dyn StereoSequence,
    odometry: &mut Odometry,
    frame_period_s: f64,
) -> Result<Vec<FrameResult>, RunError> {
    let mut out = Vec::with_capacity(seq.len());
    run_sequence(seq, odometry, frame_period_s, &mut |r| {
        out.push(r.clone());
        ControlFlow::Continue(())
    })?;
    Ok(out)
}
