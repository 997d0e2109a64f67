//! `swarmpose correspondences SEQUENCE_DIR --frames I J --out FILE.csv`: the stereo front
//! end on two frames of a sequence, written as a correspondence CSV for `register`
//! (src = frame J, dst = frame I, both in their left camera frames, metres), so that
//! `dst = R src + t` is the pose of camera J in camera I. `--draw` draws the matches
//! (the paper's figure 9); with `--inliers` (the JSON printed by `register`) inliers and
//! outliers get different colours.

use std::path::{Path, PathBuf};

use clap::Args;
use swarmpose_core::Correspondences;
use swarmpose_data::{correspondence_csv, register_report};
use swarmpose_datasets::{DatasetError, StereoPair, StereoSequence, open};
use swarmpose_odometry::config::Calibration;
use swarmpose_odometry::{Odometry, OdometryConfig};
use swarmpose_runs::batch::{camera_of, run_sequence};
use swarmpose_vision::draw::draw_matches;
use swarmpose_vision::features::FeatureExtractor;
use swarmpose_vision::frontend::{Detector, DisparityCorrection, FrameMatches, Frontend};

use super::stereo_options::StereoOptions;
use crate::error::{CliError, EXIT_NOT_USABLE};
use crate::output_file::{check_target, create_parent, write_bytes};
use crate::streams::{err, warn};

/// Arguments of `swarmpose correspondences`.
#[derive(Debug, Args)]
#[command(after_help = "\
SEQUENCE_DIR is a KITTI odometry sequence (image_0/, image_1/, calib.txt), a Karlsruhe \
sequence (I1_*.png, I2_*.png, calib.txt) or a EuRoC MAV sequence (mav0/cam0, mav0/cam1; \
rectified on load). Frames are 0-based indices. The CSV has the columns \
src_x,src_y,src_z,dst_x,dst_y,dst_z: src in the left camera frame of frame J, dst in that \
of frame I (x right, y down, z forward, metres), then the 12 columns \
src_cxx,src_cxy,src_cxz,src_cyy,src_cyz,src_czz,dst_cxx,...,dst_czz: the upper triangles \
of both points' stereo noise covariances (m^2, from the pixel noise; elongated along the \
viewing ray), which `register` uses for a Mahalanobis inlier test and fit (omit them with \
--no-covariance). A one-line summary goes to standard error.

Exit status: 0 on success; 2 for bad options, an unreadable or malformed sequence, or an \
--inliers report made from another CSV (checked by its row count and points_checksum \
before anything is written); 1 when an output cannot be written; 3 when no \
correspondence was found (the CSV is written with its header only: not usable). Outputs \
are written under a temporary name and renamed when complete (a FIFO or a device such \
as /dev/stdout is written through, never replaced; a folder is refused); missing folders \
are created.")]
pub struct CorrespondencesArgs {
    /// Sequence directory.
    #[arg(value_name = "SEQUENCE_DIR")]
    pub sequence: PathBuf,

    /// The two frames: I (destination) and J (source).
    #[arg(long, num_args = 2, value_names = ["I", "J"], required = true)]
    pub frames: Vec<usize>,

    /// Output correspondence CSV.
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,

    /// Also draw the matches: frame I left, frame J right, a line per match.
    #[arg(long, value_name = "FILE.png")]
    pub draw: Option<PathBuf>,

    /// The JSON report of `swarmpose register` on the CSV: its inliers are drawn in
    /// green, the outliers in red (otherwise every match is yellow).
    #[arg(long, value_name = "REPORT.json", requires = "draw")]
    pub inliers: Option<PathBuf>,

    /// Keep only the matches confirmed by the right images (left t -> right t -> right
    /// t-1 -> left t-1 -> left t closes).
    #[arg(long)]
    pub circular_check: bool,

    #[command(flatten)]
    pub stereo: StereoOptions,

    /// Write only the six coordinate columns, without the stereo noise covariances.
    #[arg(long)]
    pub no_covariance: bool,

    /// Self-calibrate the disparity correction on the first N consecutive pairs of the
    /// sequence, as `odometry` does online (image data only: the causes of --calibrate
    /// that the rows and the rigidity of the pairs support), print it and use it.
    #[arg(long, value_name = "N", conflicts_with_all = ["disparity_offset", "disparity_quadratic", "disparity_linear"])]
    pub self_calibrate: Option<usize>,
}

fn dataset_error(e: DatasetError) -> CliError {
    CliError::usage(e.to_string())
}

/// The disparity correction self-calibrated on the first `pairs` consecutive pairs: the
/// odometry engine's decision after those frames.
fn self_calibrate(
    seq: &dyn StereoSequence,
    args: &CorrespondencesArgs,
    pairs: usize,
) -> Result<DisparityCorrection, CliError> {
    if pairs == 0 || pairs >= seq.len() {
        return Err(CliError::usage(format!(
            "--self-calibrate needs 1 to {} pairs, got {pairs}",
            seq.len().saturating_sub(1)
        )));
    }
    let (_, selfcal) = args.stereo.calibration()?;
    let config = OdometryConfig {
        detector: args.stereo.detector(),
        calibration: Calibration::Auto,
        selfcal,
        ..OdometryConfig::default()
    };
    let mut odometry =
        Odometry::new(camera_of(seq), config).map_err(|e| CliError::usage(e.to_string()))?;
    let mut done = 0;
    run_sequence(seq, &mut odometry, 0.1, &mut |_| {
        done += 1;
        if done > pairs {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    })
    .map_err(|e| CliError::usage(e.to_string()))?;
    let d = odometry.calibration();
    let c = d.correction;
    let reuse = if c.linear_y_px == 0.0 && c.cross_xy_px == 0.0 {
        format!(
            "--disparity-offset {} --disparity-quadratic {} --disparity-linear {}",
            c.offset_px, c.quadratic_px, c.linear_x_px
        )
    } else {
        "terms beyond --disparity-offset, --disparity-quadratic and --disparity-linear: \
         use --self-calibrate again"
            .to_owned()
    };
    err(&format!(
        "swarmpose: self-calibrated disparity correction {c} ({}) over {pairs} pairs ({reuse})",
        d.model
    ));
    Ok(c)
}

/// Runs the front end on frames `i` and `j`.
fn matches<E: FeatureExtractor>(
    frontend: &mut Frontend<E>,
    correction: DisparityCorrection,
    args: &CorrespondencesArgs,
    a: &StereoPair,
    b: &StereoPair,
) -> Result<FrameMatches, CliError> {
    frontend.temporal.circular_check = args.circular_check;
    let fa = frontend.stereo_frame(a.left.view(), a.right.view());
    let fb = frontend.stereo_frame(b.left.view(), b.right.view());
    let m = frontend
        .match_frames(&fa, &fb)
        .map_err(|e| CliError::failure(format!("matching failed: {e}")))?;
    if correction == DisparityCorrection::default() {
        return Ok(m);
    }
    m.with_disparity_correction(correction, frontend.rig.baseline_m)
        .map_err(|e| {
            CliError::usage(format!(
                "the disparity correction {correction} makes a disparity non-positive ({e})"
            ))
        })
}

/// Inlier flags from a `register` JSON report, checked to be of `data` (its row count
/// and points checksum).
fn read_inliers(path: &Path, data: &Correspondences) -> Result<Vec<bool>, CliError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::usage(format!("{name}: cannot read: {e}")))?;
    register_report::parse_inliers(
        &text,
        &name,
        data.len(),
        &register_report::points_checksum(data),
    )
    .map_err(|e| CliError::usage(e.to_string()))
}

/// Runs `correspondences`.
///
/// # Errors
/// A bad sequence or frame index (exit 2), an unwritable output (exit 1).
pub fn run(args: &CorrespondencesArgs) -> Result<(), CliError> {
    let fixed = match args.stereo.calibration()?.0 {
        Calibration::Fixed(c) => Some(c),
        Calibration::Auto | Calibration::Off => None,
    };
    let (i, j) = match args.frames.as_slice() {
        [i, j] => (*i, *j),
        _ => return Err(CliError::usage("--frames takes two frame indices, I and J")),
    };
    let seq: Box<dyn StereoSequence> = open(&args.sequence).map_err(dataset_error)?;
    for note in seq.notes() {
        warn(note);
    }
    // The output folders exist (or are made) before any work.
    for path in std::iter::once(&args.out).chain(&args.draw) {
        create_parent(path)?;
        check_target(path)?;
    }
    for f in [i, j] {
        if f >= seq.len() {
            return Err(CliError::usage(format!(
                "{}: frame {f} out of range (the sequence has {} frames, 0-{})",
                args.sequence.display(),
                seq.len(),
                seq.len().saturating_sub(1)
            )));
        }
    }
    let correction = match args.self_calibrate {
        Some(n) => self_calibrate(seq.as_ref(), args, n)?,
        None => fixed.unwrap_or_default(),
    };
    let a = seq.frame(i).map_err(dataset_error)?;
    let b = seq.frame(j).map_err(dataset_error)?;
    let rig = seq.calibration();
    let m = match args.stereo.detector() {
        Detector::Orb => matches(&mut Frontend::orb(rig), correction, args, &a, &b)?,
        Detector::Surf => matches(&mut Frontend::surf(rig), correction, args, &a, &b)?,
    };
    let data = if args.no_covariance || m.correspondences.is_empty() {
        m.correspondences.clone()
    } else {
        m.correspondences_with_covariance().map_err(|e| {
            CliError::failure(format!(
                "the stereo covariances are not usable ({e}); --no-covariance writes the points only"
            ))
        })?
    };
    // The report is checked before anything is written.
    let flags = match &args.inliers {
        Some(p) => Some(read_inliers(p, &data)?),
        None => None,
    };
    let csv = if data.is_empty() {
        let header = if args.no_covariance {
            swarmpose_data::HEADER
        } else {
            swarmpose_data::HEADER_WITH_COVARIANCE
        };
        format!("{header}\n").into_bytes()
    } else {
        let mut bytes = Vec::new();
        correspondence_csv::write_to(&mut bytes, &data, &args.out.display().to_string())?;
        bytes
    };
    write_bytes(&args.out, &csv)?;
    if let Some(png) = &args.draw {
        let canvas = draw_matches(
            a.left.view(),
            b.left.view(),
            &m.dst_pixels,
            &m.src_pixels,
            flags.as_deref(),
        );
        let bytes = canvas
            .png()
            .map_err(|e| crate::output_file::write_error(png, &e))?;
        write_bytes(png, &bytes)?;
    }
    err(&format!(
        "swarmpose: {} ({}), frames {i} -> {j}: {} correspondences written to {}",
        args.sequence.display(),
        seq.layout(),
        m.correspondences.len(),
        args.out.display()
    ));
    if data.is_empty() {
        return Err(CliError {
            code: EXIT_NOT_USABLE,
            message: format!(
                "not usable: no correspondence between frames {i} and {j} ({} has the header \
                 only)",
                args.out.display()
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inliers_of_a_register_report() {
        use nalgebra::Point3;
        let dir = std::env::temp_dir().join(format!("swarmpose-corr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("tmp");
        let points = |n: usize| -> Correspondences {
            let p: Vec<Point3<f64>> = (0..n).map(|i| Point3::new(i as f64, 1.0, 2.0)).collect();
            Correspondences::new(p.clone(), p).expect("points")
        };
        let (three, two) = (points(3), points(2));
        let p = dir.join("r.json");
        std::fs::write(
            &p,
            format!(
                r#"{{"method":"pso","n_correspondences":3,"points_checksum":"{}","inliers":[0,2]}}"#,
                register_report::points_checksum(&three)
            ),
        )
        .expect("write");
        assert_eq!(
            read_inliers(&p, &three).expect("ok"),
            vec![true, false, true]
        );
        let e = read_inliers(&p, &two).expect_err("another CSV");
        assert!(
            e.message.contains("r.json") && e.message.contains("another CSV"),
            "{e}"
        );
        std::fs::write(&p, "{}").expect("write");
        assert!(read_inliers(&p, &three).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn args(sequence: PathBuf, frames: [usize; 2], out: PathBuf) -> CorrespondencesArgs {
        CorrespondencesArgs {
            sequence,
            frames: frames.to_vec(),
            out,
            draw: None,
            inliers: None,
            circular_check: false,
            stereo: StereoOptions {
                detector: Some(Detector::Orb),
                disparity_offset: None,
                disparity_quadratic: None,
                disparity_linear: None,
                calibrate: None,
                calibration_memory: None,
            },
            no_covariance: false,
            self_calibrate: None,
        }
    }

    #[test]
    fn kitti_frames_to_csv_and_drawing() {
        let root = swarmpose_testdata::data_root().join("kitti_vo_seq2");
        if !root.is_dir() {
            assert!(
                std::env::var("CI").map_or(true, |v| v != "true"),
                "CI=true: {} missing",
                root.display()
            );
            eprintln!("SKIPPED: {} not found", root.display());
            return;
        }
        let dir = std::env::temp_dir().join(format!("swarmpose-corr-k-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("tmp");
        let mut a = args(root.clone(), [3, 4], dir.join("c.csv"));
        a.draw = Some(dir.join("m.png"));
        run(&a).expect("run");
        let data = correspondence_csv::read_path(dir.join("c.csv")).expect("csv");
        assert!(data.len() >= 300, "{}", data.len());
        assert!(data.noise_covariance().is_some(), "covariances written");
        assert!(dir.join("m.png").is_file());
        let mut plain = args(root.clone(), [3, 4], dir.join("p.csv"));
        plain.no_covariance = true;
        run(&plain).expect("run");
        let points = correspondence_csv::read_path(dir.join("p.csv")).expect("csv");
        assert!(points.noise_covariance().is_none());
        assert_eq!(points.src(), data.src());
        // Errors: a frame out of range, a missing directory, a bad offset.
        let e = run(&args(root.clone(), [0, 51], dir.join("x.csv"))).expect_err("range");
        assert!(
            e.code == 2 && e.message.contains("frame 51 out of range"),
            "{e}"
        );
        let e = run(&args(dir.join("nope"), [0, 1], dir.join("x.csv"))).expect_err("missing");
        assert!(e.code == 2 && e.message.contains("nope"), "{e}");
        let mut b = args(root.clone(), [0, 1], dir.join("x.csv"));
        b.stereo.disparity_offset = Some(f64::NAN);
        assert_eq!(run(&b).expect_err("nan").code, 2);
        let mut c = args(root, [0, 1], dir.join("y.csv"));
        c.self_calibrate = Some(4);
        run(&c).expect("self-calibrated run");
        c.self_calibrate = Some(51);
        assert_eq!(run(&c).expect_err("too many pairs").code, 2);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
