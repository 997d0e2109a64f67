//! The files of a run: `trajectory.kitti.txt`, `trajectory.tum.txt`, `frames.csv`, and
//! with ground truth `groundtruth.kitti.txt` and `evaluation.json`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::Isometry3;
use swarmpose_core::geometry::quaternion_wxyz;
use swarmpose_eval::trajectory::{kitti_text, tum_text, write_text};
use swarmpose_eval::{Evaluation, Trajectory, associate, evaluate};

use crate::error::OdometryError;
use crate::pipeline::OdometryRun;

/// The header of `frames.csv`.
pub const FRAMES_HEADER: &str = "frame,status,left_features,right_features,stereo_points,\
matches,inliers,load_ms,features_ms,stereo_ms,match_ms,estimate_ms,refine_ms,total_ms,\
tx,ty,tz,qw,qx,qy,qz,x,y,z";

/// `frames.csv`: one row per frame: status (`first`, `ok`, `constant-velocity (why)`),
/// counts, time per stage (ms), the motion from the previous frame (`dst = R src + t`,
/// translation metres and quaternion) and the position of the camera.
#[must_use]
pub fn frames_csv(run: &OdometryRun) -> String {
    let mut s = String::from(FRAMES_HEADER);
    s.push('\n');
    for (f, pose) in run.frames.iter().zip(&run.poses) {
        let t = f.motion.translation.vector;
        let [qw, qx, qy, qz] = quaternion_wxyz(&f.motion.rotation);
        let p = pose.translation.vector;
        let tm = &f.times;
        let status = f.status.text().replace('"', "'");
        let _ = writeln!(
            s,
            "{},\"{status}\",{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.6},{:.6},{:.6},{:.9},{:.9},{:.9},{:.9},{:.6},{:.6},{:.6}",
            f.frame,
            f.n_left_features,
            f.n_right_features,
            f.n_stereo,
            f.n_matches,
            f.n_inliers,
            tm.load_ms,
            tm.features_ms,
            tm.stereo_ms,
            tm.match_ms,
            tm.estimate_ms,
            tm.refine_ms,
            tm.total_ms(),
            t.x,
            t.y,
            t.z,
            qw,
            qx,
            qy,
            qz,
            p.x,
            p.y,
            p.z
        );
    }
    s
}

/// The evaluation of a run against ground truth of the same frames.
///
/// # Errors
/// [`OdometryError::Eval`] when the lengths differ or there are too few poses.
pub fn evaluate_run(
    run: &OdometryRun,
    ground_truth: &[Isometry3<f64>],
) -> Result<Evaluation, OdometryError> {
    let pairs = associate::by_index(
        &Trajectory::indexed("the estimated trajectory", run.poses.clone()),
        &Trajectory::indexed("the ground truth", ground_truth.to_vec()),
    )?;
    Ok(evaluate(&pairs)?)
}

fn write(path: PathBuf, text: &str, written: &mut Vec<PathBuf>) -> Result<(), OdometryError> {
    write_text(&path, text).map_err(|e| OdometryError::Write {
        path: path.clone(),
        message: e.to_string(),
    })?;
    written.push(path);
    Ok(())
}

/// Writes the text outputs of `run` into `dir` (created if needed); returns the paths.
///
/// # Errors
/// [`OdometryError::Write`] naming the file.
pub fn write_text_outputs(
    run: &OdometryRun,
    dir: &Path,
    ground_truth: Option<&[Isometry3<f64>]>,
    evaluation: Option<&Evaluation>,
) -> Result<Vec<PathBuf>, OdometryError> {
    std::fs::create_dir_all(dir).map_err(|e| OdometryError::Write {
        path: dir.to_owned(),
        message: e.to_string(),
    })?;
    let mut written = Vec::new();
    write(
        dir.join("trajectory.kitti.txt"),
        &kitti_text(&run.poses),
        &mut written,
    )?;
    write(
        dir.join("trajectory.tum.txt"),
        &tum_text(&run.stamps, &run.poses),
        &mut written,
    )?;
    write(dir.join("frames.csv"), &frames_csv(run), &mut written)?;
    if let Some(gt) = ground_truth {
        write(
            dir.join("groundtruth.kitti.txt"),
            &kitti_text(gt),
            &mut written,
        )?;
        write(
            dir.join("groundtruth.tum.txt"),
            &tum_text(&run.stamps, gt),
            &mut written,
        )?;
    }
    if let Some(e) = evaluation {
        let text = serde_json_like(e);
        write(dir.join("evaluation.json"), &text, &mut written)?;
    }
    Ok(written)
}

/// The evaluation as JSON.
fn serde_json_like(e: &Evaluation) -> String {
    serde_json::to_string_pretty(e).unwrap_or_else(|err| format!("{{\"error\": \"{err}\"}}"))
}
