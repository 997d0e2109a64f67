//! The options of `swarmpose odometry` ([`OdometryArgs`]) and the run configuration they
//! give ([`run_config`]): the defaults, or a `--config` file, with the options applied over
//! them.

use std::path::PathBuf;

use clap::Args;
use swarmpose_core::EstimatorConfig;
use swarmpose_odometry::OdometryConfig;
use swarmpose_odometry::window::Marginalisation;
use swarmpose_runs::config::{InputConfig, RunConfig};

use crate::commands::stereo_options::StereoOptions;
use crate::error::CliError;
use crate::methods::{EstimatorOptions, Method, MethodParser, configure};

/// Arguments of `swarmpose odometry`.
#[derive(Debug, Args)]
#[command(after_help = "\
SEQUENCE_DIR is a KITTI odometry sequence, a Karlsruhe sequence, a EuRoC MAV sequence, \
a TUM RGB-D directory (see `swarmpose correspondences --help`) or a ROS 2 bag (an .mcap or \
.db3 file, or a rosbag2 folder with metadata.yaml: two Image or CompressedImage topics with \
their camera_info, found or named with --left/--right, paired by header stamp). Outputs in \
--out, written frame by frame as the run goes: trajectory.kitti.txt (KITTI poses), \
odometry.mcap (ROS 2 messages: nav_msgs/Odometry with covariance, PoseWithCovarianceStamped, \
/tf, DiagnosticArray status, the paths; see README \"ROS 2\"), trajectory.tum.txt \
(timestamp tx ty tz qx qy qz qw), frames.csv (per frame: status, reference frame, counts, \
time per stage in ms, the motion from the previous frame, the position, the disparity \
correction, 1 for a keyframe of the sliding window, and 1 for an ambiguous motion: two distinct \
motions with comparable support, such as a truck ahead keeping pace, of which the one nearer the \
constant-velocity prediction was taken; a bag's images without a partner have a row with no frame number and the status unpaired (TOPIC message I, stamp NS ns)), motion_covariance.csv (each tracked frame's measured motion from its \
reference frame and the motion's 6x6 covariance, see its header). At the end: calibration.json (the self-calibration's decision and evidence), \
trajectory.smoothed.kitti.txt/.tum.txt (each frame's last estimate by the sliding window: a fixed-lag smoother), \
trajectory.png/.svg (top view against the ground truth: figure 17) and, with ground truth, \
errors.png, groundtruth.kitti.txt, groundtruth.tum.txt and evaluation.json.

A frame the engine cannot track is predicted at constant velocity (at most 1 s), then \
marked lost; frames.csv says which and why. A bag cut short (its recorder killed) is run \
up to its last whole frame, then exits with status 2 saying where it stopped.

Exit status: 0 on success; 2 for bad options or an unreadable, malformed or too short \
sequence (a frame that cannot be read stops the run: the frames before it are kept and the \
message names the frame); 1 when an output cannot be written; 3 when the run finished but \
fewer than half of the motions were tracked (the result is not usable; the outputs are \
still written); 130/143 when stopped by SIGINT/SIGTERM between two frames (the frames done \
and the summary are kept); 141 when standard output was closed by its reader. The last \
line on standard output says how many frames were tracked, held at constant velocity or \
lost. --out is created and checked writable before the first frame; files an earlier run \
wrote there (listed in its .swarmpose-manifest) are removed; files written at the end \
are written under a temporary name and renamed when complete.")]
pub struct OdometryArgs {
    /// Sequence directory; without it, the built-in synthetic stereo sequence.
    #[arg(value_name = "SEQUENCE_DIR")]
    pub sequence: Option<PathBuf>,

    /// Estimator [default: pso].
    #[arg(long, value_parser = MethodParser)]
    pub method: Option<Method>,

    /// A run configuration (the config.json every run writes): its settings replace the
    /// defaults, and the options given beside it replace its settings. The same file and
    /// input rerun a run byte for byte.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,

    /// Output directory (created if needed).
    #[arg(long, value_name = "DIR", default_value = "out/odometry")]
    pub out: PathBuf,

    /// Seed of the estimator (frame k uses seed + k) [default: 0].
    #[arg(long, value_name = "N")]
    pub seed: Option<u64>,

    /// Keep the estimator's motion: no reprojection refinement (and no covariance).
    #[arg(long)]
    pub no_refine: bool,

    /// Refine the last K keyframes and the feature tracks they share together (a sliding
    /// window bundle adjustment; 0: frame to frame only; 2 is frame to frame again). A
    /// frame becomes a keyframe when its features moved beyond their noise since the last
    /// one or it lost most of that one's tracks.
    #[arg(long, value_name = "K", help = with_default(
        "Refine the last K keyframes and the feature tracks they share together (a sliding \
         window bundle adjustment; 0: frame to frame only; 2 is frame to frame again)",
        OdometryConfig::default().window.keyframes))]
    pub window: Option<usize>,

    /// What happens to the oldest keyframe's information when it leaves the window: `off`
    /// (discarded: the next keyframe is held fixed at its estimate), `finished` (its pose
    /// and the tracks it sees that have ended are marginalised into a Gaussian prior on
    /// the other keyframes) or `all` (with every track it sees; those that go on begin a
    /// new point). See docs/window.md.
    #[arg(long, value_name = "MODE", value_parser = |s: &str| s.parse::<Marginalisation>(),
          help = with_default(
              "What happens to the oldest keyframe's information when it leaves the window: \
               off, finished or all (docs/window.md)",
              OdometryConfig::default().window.marginalise.name()))]
    pub marginalise: Option<Marginalisation>,

    /// Each measurement of the sliding window keeps the disparity correction of the frame
    /// where it was made: a change of the self-calibration enters through new measurements
    /// only and does not jump the online pose, at a cost in drift (docs/self-calibration.md).
    #[arg(long)]
    pub correction_per_frame: bool,

    /// Search each feature's partner in the next frame within PX pixels of where the
    /// constant-velocity prediction puts it, instead of within 150 px of where it was (the
    /// pair is searched again without the prediction when the share of features matched
    /// drops below 0.75 times the last pair's). A third of the matching time; not the
    /// default, since it raises Karlsruhe's ATE (docs/history.md, issue 34).
    #[arg(long, value_name = "PX", value_parser = positive_px, allow_negative_numbers = true)]
    pub guided_radius: Option<f32>,

    /// Fewest inliers for a motion to be accepted (at least 3).
    #[arg(long, value_name = "N", value_parser = min_inliers, allow_negative_numbers = true,
          help = with_default("Fewest inliers for a motion to be accepted (at least 3)",
                              OdometryConfig::default().min_inliers))]
    pub min_inliers: Option<usize>,

    /// Most pixels of a stereo image the engine works on: larger images are halved (2x2
    /// means) until they have at most this many (1920x1080 is halved once; the front end
    /// is made for cameras of about half a megapixel to a megapixel).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(usize), help = with_default(
        "Most pixels of a stereo image the engine works on: larger images are halved (2x2 \
         means) until they have at most this many (1920x1080 is halved once)",
        OdometryConfig::default().max_working_pixels))]
    pub max_working_pixels: Option<usize>,

    /// Fewest pixels of a stereo image the engine works on: smaller images are doubled
    /// (bicubic) until they have at least this many (default 0: never; at most a quarter
    /// of --max-working-pixels, and at most 16777216). 250000 doubles 620x188 and 480x288: it helps some
    /// sequences and hurts others (RESULTS.md, "Other image sizes").
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(usize), help = with_default(
        "Fewest pixels of a stereo image the engine works on: smaller images are doubled \
         (bicubic) until they have at least this many (0: never; at most a quarter of \
         --max-working-pixels, and at most 16777216). 250000 doubles 620x188 and 480x288: \
         it helps some sequences and hurts others (RESULTS.md, \"Other image sizes\")",
        OdometryConfig::default().min_working_pixels))]
    pub min_working_pixels: Option<usize>,

    /// Seconds between frames of a sequence without timestamps [default: 0.1].
    #[arg(long, value_name = "S", help = with_default(
        "Seconds between frames of a sequence without timestamps",
        InputConfig::default().frame_period_s))]
    pub frame_period: Option<f64>,

    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,

    /// Threads: 1, or 2 to load the next frame, run its front end and match it to this
    /// one while the back end works on this one (the same trajectory; stereo sequences
    /// only).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=2),
          help = with_default(
              "Threads: 1, or 2 to load the next frame, run its front end and match it to \
               this one while the back end works on this one (the same trajectory; stereo \
               sequences only)",
              RunConfig::default().threads))]
    pub threads: Option<u8>,

    /// Check each pair's covariance on two spatially disjoint halves of its matches
    /// (split_check.csv; two more refinements a frame).
    #[arg(long)]
    pub split_check: bool,

    /// The left camera's true poses, in place of the sequence's own: KITTI poses (one a
    /// frame, in order) or, for a bag, TUM poses matched by time (`*.tum.txt`, `*.tum`,
    /// `groundtruth.txt`); the evaluation and plots use them.
    #[arg(long, value_name = "FILE")]
    pub ground_truth: Option<PathBuf>,

    /// ROS 2 bag: the left image topic (found when not given; give both or neither).
    #[arg(long, value_name = "TOPIC")]
    pub left: Option<String>,

    /// ROS 2 bag: the right image topic.
    #[arg(long, value_name = "TOPIC")]
    pub right: Option<String>,

    /// ROS 2 bag: the depth image topic of an RGB-D input (16UC1 millimetres or 32FC1
    /// metres; found when the bag has one colour and one depth camera); --left then
    /// names the colour topic.
    #[arg(long, value_name = "TOPIC")]
    pub depth: Option<String>,

    /// ROS 2 bag: largest difference of the header stamps of a left and a right image
    /// paired into a frame, milliseconds (0: equal stamps).
    #[arg(long, value_name = "MS", help = with_default(
        "ROS 2 bag: largest difference of the header stamps of a left and a right image \
         paired into a frame, milliseconds (0: equal stamps)",
        InputConfig::default().stamp_tolerance_ms))]
    pub stamp_tolerance: Option<f64>,

    /// odometry.mcap: the fixed frame of the poses [default: odom].
    #[arg(long, value_name = "NAME")]
    pub odom_frame: Option<String>,

    /// odometry.mcap: the camera frame (default: the images' frame_id from a bag, else
    /// camera_optical).
    #[arg(long, value_name = "NAME")]
    pub camera_frame: Option<String>,

    /// odometry.mcap: every N-th frame (0, N, 2N, ...) also as its left image with the
    /// inliers drawn (CompressedImage, PNG) and the inliers' points (PointCloud2) [default:
    /// 0: none].
    #[arg(long, value_name = "N")]
    pub mcap_images: Option<usize>,

    #[command(flatten)]
    pub stereo: StereoOptions,

    #[command(flatten)]
    pub options: EstimatorOptions,
}

/// `--min-inliers`: at least [`swarmpose_odometry::MIN_INLIERS`] (fewer used to be raised
/// to 3 without a word; the engine and Python's `min_inliers=` refuse them too).
fn min_inliers(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= swarmpose_odometry::MIN_INLIERS => Ok(n),
        _ => Err(format!(
            "at least {} are needed for a motion",
            swarmpose_odometry::MIN_INLIERS
        )),
    }
}

/// `--guided-radius`: a finite number of pixels above 0.
fn positive_px(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err("a radius is a finite number of pixels above 0".into()),
    }
}

/// `text` with its default value noted, as clap notes it.
fn with_default(text: &str, default: impl std::fmt::Display) -> String {
    format!("{text} [default: {default}]")
}

/// The run's configuration: the defaults, or the `--config` file, with the options given
/// applied over them.
///
/// # Errors
/// An unreadable or invalid configuration file, or options that do not apply.
pub fn run_config(args: &OdometryArgs) -> Result<RunConfig, CliError> {
    let mut rc = match &args.config {
        Some(path) => RunConfig::read(path).map_err(|e| CliError::usage(e.to_string()))?,
        None => RunConfig::default(),
    };
    let o = &mut rc.odometry;
    args.stereo.apply(o)?;
    let base = match args.method {
        Some(m) if m != o.estimator.method() => EstimatorConfig::of(m),
        _ => o.estimator.clone(),
    };
    o.estimator = configure(base, &args.options)?;
    o.refine &= !args.no_refine;
    o.split_check |= args.split_check;
    let set = |field: &mut usize, v: Option<usize>| *field = v.unwrap_or(*field);
    set(&mut o.min_inliers, args.min_inliers);
    set(&mut o.window.keyframes, args.window);
    set(&mut o.max_working_pixels, args.max_working_pixels);
    set(&mut o.min_working_pixels, args.min_working_pixels);
    o.seed = args.seed.unwrap_or(o.seed);
    o.window.marginalise = args.marginalise.unwrap_or(o.window.marginalise);
    o.window.correction_per_frame |= args.correction_per_frame;
    if let Some(r) = args.guided_radius {
        o.orb.temporal.guided_radius_px = Some(r);
        o.surf.temporal.guided_radius_px = Some(r);
    }
    let input = &mut rc.input;
    input.frame_period_s = args.frame_period.unwrap_or(input.frame_period_s);
    input.stamp_tolerance_ms = args.stamp_tolerance.unwrap_or(input.stamp_tolerance_ms);
    if args.left.is_some() || args.right.is_some() {
        input.left_topic.clone_from(&args.left);
        input.right_topic.clone_from(&args.right);
    }
    if args.depth.is_some() {
        input.depth_topic.clone_from(&args.depth);
    }
    if let Some(f) = &args.odom_frame {
        rc.output.odom_frame.clone_from(f);
    }
    if args.camera_frame.is_some() {
        rc.output.camera_frame.clone_from(&args.camera_frame);
    }
    rc.output.mcap_images = args.mcap_images.unwrap_or(rc.output.mcap_images);
    rc.threads = args.threads.unwrap_or(rc.threads);
    rc.check().map_err(|m| {
        CliError::usage(match m.strip_prefix("input.frame_period_s") {
            Some(rest) => format!("--frame-period{rest}"),
            None => match m.strip_prefix("input.stamp_tolerance_ms") {
                Some(rest) => format!("--stamp-tolerance{rest}"),
                None => m,
            },
        })
    })?;
    Ok(rc)
}
