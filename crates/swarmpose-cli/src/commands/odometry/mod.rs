//! `swarmpose odometry [SEQUENCE_DIR] [--out DIR] ...`: stereo (or RGB-D) visual odometry
//! over a recorded sequence, a thin loop over the streaming engine
//! ([`swarmpose_odometry::Odometry`]): each frame is given to the engine as it is read and
//! its pose is written at once (trajectory, per-frame log, covariance), so a run that
//! stops early keeps every finished frame. At the end: the summary, the self-calibration's
//! decision, the plots and, with ground truth, the evaluation.

use std::ops::ControlFlow;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nalgebra::Isometry3;
use swarmpose_datasets::{DepthSequence, StereoSequence};
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::{CorrectionModel, Decision, FrameResult, Odometry, RunEnd};
use swarmpose_ros::convert::FrameNames;
use swarmpose_ros::{BagInfo, Input, StereoOptions as BagOptions};
use swarmpose_runs::RunError;
use swarmpose_runs::batch::{
    camera_of, rgbd_camera, run_rgbd_sequence, run_sequence, run_sequence_two_threads,
};
use swarmpose_runs::output::{Smoothed, Summary, calibration_json};
use swarmpose_runs::output_dir::FrameFiles;
use swarmpose_runs::plots::{PlotTrack, render_plots};
use swarmpose_runs::synthetic::SyntheticSequence;
use swarmpose_vision::image::GrayImage;

mod args;
mod calibration;
pub mod input;
mod ins;
mod mcap;
mod output;
mod split;
mod truth;
mod unpaired;

pub use self::args::{OdometryArgs, run_config};
use self::calibration::calibration_lines;
use self::input::open_input;
use self::mcap::McapOutput;
use self::output::OutputDir;
use self::split::SplitLog;
use self::unpaired::Unpaired;
use crate::error::{CliError, EXIT_NOT_USABLE};
use crate::signals::StopRequest;
use crate::streams::{err, out, warn};

fn odometry_error(e: impl Into<RunError>) -> CliError {
    let e: RunError = e.into();
    if e.is_input() {
        CliError::usage(e.to_string())
    } else {
        CliError::failure(e.to_string())
    }
}

fn progress_bar(quiet: bool, total: usize) -> ProgressBar {
    let pb = ProgressBar::new(total as u64);
    if quiet {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) =
        ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} frames {per_sec} eta {eta}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}

/// The input of a run.
enum Source {
    Stereo(Box<dyn StereoSequence>, String, Option<Vec<Isometry3<f64>>>),
    Rgbd(Box<dyn DepthSequence>, String),
}

/// The left image of frame `i` of `source` as the engine took it (read again, for
/// `odometry.mcap`'s images).
fn left_image(source: &Source, i: usize) -> Result<GrayImage, String> {
    match source {
        Source::Stereo(seq, ..) => seq.frame(i).map(|p| p.left).map_err(|e| e.to_string()),
        Source::Rgbd(seq, _) => seq.frame(i).map(|f| f.gray).map_err(|e| e.to_string()),
    }
}

/// What a run keeps in memory for the end: the poses and whether each was tracked (a
/// few bytes a frame; everything else is on disk).
struct Track {
    poses: Vec<Isometry3<f64>>,
    /// Each frame's last estimate by the sliding window (its online pose without one).
    smoothed: Smoothed,
    stamps: Vec<f64>,
    predicted: Vec<bool>,
    summary: Summary,
    times: swarmpose_odometry::StageTimes,
}

/// Runs `odometry`.
///
/// # Errors
/// Bad options or sequence (exit 2), unwritable outputs (exit 1), a result that is not
/// usable (exit 3).
pub fn run_command(args: &OdometryArgs) -> Result<(), CliError> {
    let rc = run_config(args)?;
    let config = rc.odometry.clone();
    let mut bag_options = BagOptions::with_tolerance_ms(
        rc.input.left_topic.clone(),
        rc.input.right_topic.clone(),
        rc.input.stamp_tolerance_ms,
    )
    .map_err(|e| CliError::usage(format!("--stamp-tolerance: {e}")))?;
    bag_options.depth.clone_from(&rc.input.depth_topic);
    let mut bag: Option<BagInfo> = None;
    let source = match &args.sequence {
        None => {
            let seq = SyntheticSequence::default();
            err(&format!(
                "swarmpose: no SEQUENCE_DIR: running on the built-in synthetic stereo sequence \
                 ({} frames rendered from a textured street along a known path)",
                seq.len()
            ));
            let gt = seq.ground_truth().map(<[_]>::to_vec);
            Source::Stereo(Box::new(seq), "built-in synthetic sequence".into(), gt)
        }
        Some(dir) => {
            let opened = open_input(dir, &bag_options).map_err(odometry_error)?;
            bag = opened.bag;
            let layout = match opened.input.layout() {
                "tum rgb-d" => "TUM RGB-D",
                other => other,
            };
            let title = format!("{} ({layout})", dir.display());
            match opened.input {
                Input::Stereo(seq) => {
                    for note in seq.notes() {
                        warn(note);
                    }
                    let gt = seq.ground_truth().map(<[_]>::to_vec);
                    Source::Stereo(seq, title, gt)
                }
                Input::Rgbd(seq) => {
                    for note in seq.notes() {
                        warn(note);
                    }
                    Source::Rgbd(seq, title)
                }
            }
        }
    };
    if matches!(source, Source::Rgbd(..)) && rc.threads != 1 {
        return Err(CliError::usage(
            "--threads 2 is for stereo sequences; an RGB-D input runs on one thread",
        ));
    }
    let (n, root) = match &source {
        Source::Stereo(s, ..) => (s.len(), s.root().to_owned()),
        Source::Rgbd(s, _) => (s.len(), s.root().to_owned()),
    };
    if n < 2 {
        return Err(CliError::usage(format!(
            "{}: {n} frame(s): odometry needs at least 2",
            root.display()
        )));
    }
    let truth_file = match &args.ground_truth {
        Some(path) => {
            let stamps = bag.as_ref().map_or(&[][..], |b| &b.stamps_ns[..]);
            Some(truth::read(path, n, stamps)?)
        }
        None => None,
    };
    let mut odometry = match &source {
        Source::Stereo(seq, ..) => Odometry::builder(camera_of(seq.as_ref()))
            .config(config.clone())
            .build(),
        Source::Rgbd(seq, _) => {
            Odometry::builder(rgbd_camera(seq.as_ref()).map_err(odometry_error)?)
                .config(config)
                .rgbd(RgbdNoise::default())
                .build()
        }
    }
    .map_err(odometry_error)?;
    let dir = output::prepare(&args.out)?;
    // The settings first: a run that stops early still says how it was made.
    let settings = rc.to_json().map_err(|e| CliError::usage(e.to_string()))?;
    dir.write(swarmpose_runs::config::FILE_NAME, settings.as_bytes())?;
    if !args.quiet {
        err(&format!(
            "swarmpose: settings in {} (rerun with --config)",
            dir.path().join(swarmpose_runs::config::FILE_NAME).display()
        ));
    }
    let mut files = FrameFiles::create(&dir)?;
    let mut split = args
        .split_check
        .then(|| SplitLog::create(&dir))
        .transpose()?;
    let names = FrameNames {
        odom: rc.output.odom_frame.clone(),
        camera: rc.output.camera_frame.clone().unwrap_or_else(|| {
            bag.as_ref()
                .map(|b| b.frame_id.clone())
                .filter(|f| !f.is_empty())
                .unwrap_or_else(|| FrameNames::default().camera)
        }),
    };
    let mut mcap = McapOutput::create(
        &dir,
        (names, rc.output.mcap_images),
        bag.as_ref().map(|b| &b.camera_info),
        bag.as_ref().map(|b| b.stamps_ns.clone()),
        truth_file.as_deref().or(match &source {
            Source::Stereo(_, _, gt) => gt.as_deref(),
            Source::Rgbd(s, _) => s.ground_truth(),
        }),
    )?;
    let frame_stamps = bag
        .as_ref()
        .map(|b| b.stamps_ns.clone())
        .unwrap_or_default();
    let mut unpaired = bag.as_ref().map_or_else(
        || Unpaired::new(&[], 0),
        |b| Unpaired::new(&b.unpaired, frame_stamps.first().copied().unwrap_or(0)),
    );
    let stop = StopRequest::install();
    let mut track = Track {
        poses: Vec::with_capacity(n),
        smoothed: Smoothed::default(),
        stamps: Vec::with_capacity(n),
        predicted: Vec::with_capacity(n),
        summary: Summary::default(),
        times: swarmpose_odometry::StageTimes::default(),
    };
    let pb = progress_bar(args.quiet, n);
    pb.set_prefix("odometry");
    let mut write_error: Option<CliError> = None;
    let mut on_frame = |r: &FrameResult| -> ControlFlow<()> {
        let stamp = frame_stamps.get(r.index).copied().unwrap_or(i64::MIN);
        let written = unpaired
            .write_before(stamp, files.frames_csv())
            .and_then(|()| files.frame(r).map_err(CliError::from))
            .and_then(|()| split.as_mut().map_or(Ok(()), |s| s.add(r)))
            .and_then(|()| mcap.frame(r, &|i| left_image(&source, i)));
        if let Err(e) = written {
            write_error = Some(e);
            return ControlFlow::Break(());
        }
        track.poses.push(r.pose);
        track.smoothed.add(r);
        track.stamps.push(r.timestamp_s);
        track.predicted.push(!matches!(
            r.status,
            swarmpose_odometry::Status::First | swarmpose_odometry::Status::Tracked
        ));
        track.summary.add(r);
        track.times += &r.times;
        pb.inc(1);
        if stop.exit_status().is_some() {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    };
    let ended = match &source {
        Source::Stereo(seq, ..) if rc.threads == 2 => run_sequence_two_threads(
            seq.as_ref(),
            &mut odometry,
            rc.input.frame_period_s,
            &mut on_frame,
        ),
        Source::Stereo(seq, ..) => run_sequence(
            seq.as_ref(),
            &mut odometry,
            rc.input.frame_period_s,
            &mut on_frame,
        ),
        Source::Rgbd(seq, _) => run_rgbd_sequence(seq.as_ref(), &mut odometry, &mut on_frame),
    };
    pb.finish_and_clear();
    if let Some(e) = write_error {
        return Err(e);
    }
    unpaired.write_before(i64::MAX, files.frames_csv())?;
    let (title, gt) = match &source {
        Source::Stereo(_, t, gt) => (t.clone(), gt.clone()),
        Source::Rgbd(s, t) => (t.clone(), s.ground_truth().map(<[_]>::to_vec)),
    };
    let gt = truth_file.or(gt);
    let done = track.summary.frames;
    mcap.finish(gt.as_deref().map(|g| &g[..done.min(g.len())]))?;
    let ended = ended.map_err(|e| {
        // The smoothed poses so far too; a failure to write them leaves the error as it is.
        let _ = write_smoothed(&dir, &track);
        let mut err = odometry_error(e);
        err.message = format!(
            "{}; stopped after {done} frame(s): their poses are in {}",
            err.message,
            dir.path().display()
        );
        err
    })?;
    if let RunEnd::Stopped(done) = ended {
        // Stopped by a signal between two frames: the summary of what was done.
        let gt = gt.map(|g| g[..done.min(g.len())].to_vec());
        finish(&dir, &track, &odometry, &title, gt.as_deref())?;
        return Err(CliError {
            code: stop.exit_status().unwrap_or(crate::error::EXIT_FAILURE),
            message: format!(
                "stopped by {} after {done} frame(s): their poses and the summary are in {}",
                stop.name().unwrap_or("a request"),
                dir.path().display()
            ),
        });
    }
    finish(&dir, &track, &odometry, &title, gt.as_deref())?;
    if let (Source::Stereo(seq, ..), Some(seq_dir)) = (&source, &args.sequence)
        && seq.layout() == "karlsruhe"
        && let Some(line) = ins::ins_summary(seq_dir, &track.poses)
    {
        out(&line)?;
        if let Some(line) = ins::ins_summary(seq_dir, track.smoothed.poses()) {
            out(&format!("smoothed: {line}"))?;
        }
    }
    if let Some(s) = &split {
        out(&s.summary())?;
    }
    if let Some(line) = unpaired.summary() {
        out(&line)?;
    }
    out(&format!(
        "written: {} ({})",
        dir.path().display(),
        track.summary.text()
    ))?;
    if let Some(stopped) = bag.as_ref().and_then(|b| b.stopped.as_deref()) {
        return Err(CliError::usage(format!(
            "{stopped}: the bag is cut; its {} whole frames were run and the outputs are written",
            track.summary.frames
        )));
    }
    match track.summary.not_usable() {
        Some(why) => Err(CliError {
            code: EXIT_NOT_USABLE,
            message: format!("{why}; the outputs are written"),
        }),
        None => Ok(()),
    }
}

/// `trajectory.smoothed.kitti.txt` and `.tum.txt`: each frame's last estimate by the
/// sliding window (a fixed-lag smoother; the frame's online pose without the window).
fn write_smoothed(dir: &OutputDir, track: &Track) -> Result<(), CliError> {
    dir.write(
        "trajectory.smoothed.kitti.txt",
        swarmpose_eval::trajectory::kitti_text(track.smoothed.poses()).as_bytes(),
    )?;
    dir.write(
        "trajectory.smoothed.tum.txt",
        swarmpose_eval::trajectory::tum_text(&track.stamps, track.smoothed.poses()).as_bytes(),
    )?;
    Ok(())
}

/// The end of a run: evaluation, plots, calibration, summary.
fn finish(
    dir: &OutputDir,
    track: &Track,
    odometry: &Odometry,
    title: &str,
    gt: Option<&[Isometry3<f64>]>,
) -> Result<(), CliError> {
    let evaluation = match gt {
        Some(g) if g.len() == track.poses.len() => {
            let pairs = swarmpose_eval::associate::by_index(
                &swarmpose_eval::Trajectory::indexed(
                    "the estimated trajectory",
                    track.poses.clone(),
                ),
                &swarmpose_eval::Trajectory::indexed("the ground truth", g.to_vec()),
            )
            .map_err(|e| CliError::failure(e.to_string()))?;
            Some(swarmpose_eval::evaluate(&pairs).map_err(|e| CliError::failure(e.to_string()))?)
        }
        Some(g) => {
            err(&format!(
                "swarmpose: warning: {} ground-truth poses for {} frames: not evaluated",
                g.len(),
                track.poses.len()
            ));
            None
        }
        None => None,
    };
    // A fixed correction (--disparity-offset) is reported as given, not as the unused
    // self-calibration's "none".
    let (applied, source) = odometry.correction();
    let given = Decision {
        model: source,
        correction: applied,
        ..Decision::default()
    };
    let decision = if source == CorrectionModel::GIVEN {
        given
    } else {
        odometry.calibration()
    };
    let calibration = serde_json::to_string_pretty(&calibration_json(&decision))
        .map_err(|e| CliError::failure(format!("calibration.json: {e}")))?;
    dir.write("calibration.json", calibration.as_bytes())?;
    write_smoothed(dir, track)?;
    if let Some(g) = gt {
        dir.write(
            "groundtruth.kitti.txt",
            swarmpose_eval::trajectory::kitti_text(g).as_bytes(),
        )?;
        dir.write(
            "groundtruth.tum.txt",
            swarmpose_eval::trajectory::tum_text(&track.stamps, g).as_bytes(),
        )?;
    }
    if let Some(e) = &evaluation {
        let text = serde_json::to_string_pretty(e)
            .map_err(|err| CliError::failure(format!("evaluation.json: {err}")))?;
        dir.write("evaluation.json", text.as_bytes())?;
    }
    let label = format!("{} + {}", odometry.estimator(), odometry.detector());
    let plot = PlotTrack {
        poses: &track.poses,
        predicted: &track.predicted,
        label: &label,
    };
    for (name, bytes) in render_plots(&plot, title, gt, evaluation.as_ref())
        .map_err(|e| CliError::failure(e.to_string()))?
    {
        dir.write(name, &bytes)?;
    }
    let s = &track.summary;
    let n = s.frames.max(1) as f64;
    let t = &track.times;
    let total = t.total_ms() / n;
    out(&format!(
        "{title}: {}; method {}, detector {}",
        s.text(),
        odometry.estimator(),
        odometry.detector()
    ))?;
    let levels = odometry.working_levels();
    if levels != 0 {
        let (c, w) = (odometry.camera(), odometry.working_camera());
        out(&format!(
            "working images: {}x{}, the {}x{} images {} {} time(s) (--min-working-pixels, \
             --max-working-pixels)",
            w.width,
            w.height,
            c.width,
            c.height,
            if levels > 0 { "halved" } else { "doubled" },
            levels.unsigned_abs()
        ))?;
    }
    for line in calibration_lines(&decision, source == CorrectionModel::GIVEN) {
        out(&line)?;
    }
    out(&format!(
        "time per frame: {total:.1} ms ({:.1} frames/s): load {:.1}, features {:.1}, stereo {:.1}, \
         match {:.1}, estimate {:.1}, refine {:.1}, calibrate {:.1}, window {:.1} ms",
        1000.0 / total.max(1e-9),
        t.load_ms / n,
        t.features_ms / n,
        t.stereo_ms / n,
        t.match_ms / n,
        t.estimate_ms / n,
        t.refine_ms / n,
        t.calibrate_ms / n,
        t.window_ms / n,
    ))?;
    if let Some(e) = &evaluation {
        let drift = e
            .final_drift_percent
            .map_or_else(|| "n/a".to_owned(), |p| format!("{p:.3} %"));
        out(&format!(
            "vs ground truth: path {:.2} m, final drift {:.3} m ({drift}), RMS eq. (20) {:.5}, \
             ATE {:.3} m raw / {:.3} m aligned, RPE {:.4} m / {:.4} deg",
            e.path_length_m,
            e.final_drift_m,
            e.eq20_rms,
            e.ate_raw.rmse,
            e.ate_aligned.rmse,
            e.rpe_translation.rmse,
            e.rpe_rotation_deg.rmse
        ))?;
        if let Some(g) = gt
            && let Ok(pairs) = swarmpose_eval::associate::by_index(
                &swarmpose_eval::Trajectory::indexed(
                    "the smoothed trajectory",
                    track.smoothed.poses().to_vec(),
                ),
                &swarmpose_eval::Trajectory::indexed("the ground truth", g.to_vec()),
            )
            && let Ok(sm) = swarmpose_eval::evaluate(&pairs)
        {
            out(&format!(
                "smoothed (each frame's last window estimate): RMS eq. (20) {:.5}, ATE {:.3} m \
                 raw / {:.3} m aligned",
                sm.eq20_rms, sm.ate_raw.rmse, sm.ate_aligned.rmse
            ))?;
        }
    }
    Ok(())
}
