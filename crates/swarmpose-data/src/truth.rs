//! The ground truth of a simulated scenario: the JSON file the scenario generator
//! (`gen_scenarios.py`) writes beside each correspondence CSV, `NAME.json` beside
//! `NAME.csv`.
//!
//! ```json
//! {"rotation_wxyz":[0.99,0.01,-0.1,0.02],"translation":[0.3,-1.0,0.2],
//!  "inlier":[true,false,...],"noise_sigma":0.02,"outlier_fraction":0.1,"seed":1000,
//!  "mode":"random","n":143,"n_outliers":14,"n_scene_points_drawn":400,
//!  "rotation_angle_deg":11.3}
//! ```
//!
//! The motion is the one of the CSV, `dst = R src + t`, from the source (camera 2) frame
//! to the destination (camera 1) frame, metres. `structured` scenarios add the motion
//! obeyed by the outlier cluster (`outlier_rotation_wxyz`, `outlier_translation`).
//! Unknown keys are ignored on reading.

use std::fmt;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Largest accepted deviation of a truth quaternion's norm from 1.
const UNIT_TOLERANCE: f64 = 1e-6;

/// The true motion and inlier labels of one scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScenarioTruth {
    /// Rotation of `dst = R src + t` as a unit quaternion `[w, x, y, z]`, `w >= 0`.
    pub rotation_wxyz: [f64; 4],
    /// Translation `t` of `dst = R src + t`, metres, destination frame.
    pub translation: [f64; 3],
    /// Per correspondence (CSV row order): true for an inlier, false for an outlier.
    pub inlier: Vec<bool>,
    /// Standard deviation of the Gaussian noise added to each `dst` coordinate, metres.
    pub noise_sigma: f64,
    /// Requested fraction of outliers, in `[0, 1]`.
    pub outlier_fraction: f64,
    /// Seed of the scene and camera pose.
    pub seed: u64,
    /// How outliers were made: `random` (wrong matches) or `structured` (a moving object).
    pub mode: String,
    /// Number of correspondences.
    pub n: usize,
    /// Number of outliers.
    pub n_outliers: usize,
    /// Scene points drawn before visibility culling (generator bookkeeping).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_scene_points_drawn: Option<usize>,
    /// Angle of the true rotation, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_angle_deg: Option<f64>,
    /// `structured` mode: rotation `[w, x, y, z]` obeyed by the outlier cluster.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outlier_rotation_wxyz: Option<[f64; 4]>,
    /// `structured` mode: translation obeyed by the outlier cluster, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outlier_translation: Option<[f64; 3]>,
}

/// Truth values that contradict each other or are out of range.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{0}")]
pub struct InvalidTruth(pub String);

/// What went wrong with a truth file.
#[derive(Debug, Error)]
pub enum TruthErrorKind {
    /// The file could not be opened or read.
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    /// The file could not be created or written.
    #[error("cannot write: {0}")]
    Write(std::io::Error),
    /// Not JSON, or JSON without the expected keys and types (the message has the line
    /// and column).
    #[error("invalid truth JSON: {0}")]
    Json(serde_json::Error),
    /// Well-formed JSON whose values contradict each other or are out of range.
    #[error("inconsistent truth: {0}")]
    Inconsistent(InvalidTruth),
}

/// A failure to read or write a truth file, naming it.
///
/// Displays as one line, `PATH: PROBLEM`.
#[derive(Debug)]
pub struct TruthError {
    /// The file path as given.
    pub path: String,
    /// What is wrong.
    pub kind: TruthErrorKind,
}

impl fmt::Display for TruthError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path, self.kind)
    }
}

impl std::error::Error for TruthError {}

/// The truth file beside a scenario CSV: `NAME.csv` -> `NAME.json`.
#[must_use]
pub fn path_for_csv(csv_path: &Path) -> PathBuf {
    csv_path.with_extension("json")
}

/// A unit quaternion from `[w, x, y, z]`, if its norm is within tolerance of 1.
fn unit_quaternion(wxyz: &[f64; 4], what: &str) -> Result<UnitQuaternion<f64>, InvalidTruth> {
    let [w, x, y, z] = *wxyz;
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    if !norm.is_finite() || (norm - 1.0).abs() > UNIT_TOLERANCE {
        return Err(InvalidTruth(format!(
            "{what} {wxyz:?} is not a unit quaternion (norm {norm})"
        )));
    }
    Ok(UnitQuaternion::from_quaternion(q))
}

/// A finite translation vector, metres.
fn translation(xyz: &[f64; 3], what: &str) -> Result<Vector3<f64>, InvalidTruth> {
    if xyz.iter().all(|v| v.is_finite()) {
        Ok(Vector3::from(*xyz))
    } else {
        Err(InvalidTruth(format!("{what} {xyz:?} is not finite")))
    }
}

impl ScenarioTruth {
    /// The true motion `dst = R src + t` (source frame to destination frame, metres).
    ///
    /// # Errors
    /// [`InvalidTruth`] when the rotation is not a unit quaternion (within 1e-6) or the
    /// translation is not finite.
    pub fn isometry(&self) -> Result<Isometry3<f64>, InvalidTruth> {
        let r = unit_quaternion(&self.rotation_wxyz, "rotation_wxyz")?;
        let t = translation(&self.translation, "translation")?;
        Ok(Isometry3::from_parts(Translation3::from(t), r))
    }

    /// The motion obeyed by the outlier cluster of a `structured` scenario, if given.
    ///
    /// # Errors
    /// As [`ScenarioTruth::isometry`], or when only one of the two parts is given.
    pub fn outlier_isometry(&self) -> Result<Option<Isometry3<f64>>, InvalidTruth> {
        match (&self.outlier_rotation_wxyz, &self.outlier_translation) {
            (None, None) => Ok(None),
            (Some(r), Some(t)) => {
                let r = unit_quaternion(r, "outlier_rotation_wxyz")?;
                let t = translation(t, "outlier_translation")?;
                Ok(Some(Isometry3::from_parts(Translation3::from(t), r)))
            }
            _ => Err(InvalidTruth(
                "outlier_rotation_wxyz and outlier_translation must be given together".into(),
            )),
        }
    }

    /// 0-based indices of the true inliers, ascending.
    #[must_use]
    pub fn inlier_indices(&self) -> Vec<usize> {
        (0..self.inlier.len()).filter(|&i| self.inlier[i]).collect()
    }

    /// Checks that the values agree with each other: a unit rotation, finite
    /// translation, `inlier.len() == n`, `n_outliers` false labels, a non-negative
    /// finite noise level and an outlier fraction in `[0, 1]`.
    ///
    /// # Errors
    /// [`InvalidTruth`] naming the first disagreement.
    pub fn validate(&self) -> Result<(), InvalidTruth> {
        self.isometry()?;
        self.outlier_isometry()?;
        if self.inlier.len() != self.n {
            return Err(InvalidTruth(format!(
                "inlier has {} labels but n is {}",
                self.inlier.len(),
                self.n
            )));
        }
        let outliers = self.inlier.iter().filter(|&&b| !b).count();
        if outliers != self.n_outliers {
            return Err(InvalidTruth(format!(
                "inlier has {outliers} false labels but n_outliers is {}",
                self.n_outliers
            )));
        }
        if !(self.noise_sigma.is_finite() && self.noise_sigma >= 0.0) {
            return Err(InvalidTruth(format!(
                "noise_sigma {} is not a non-negative number",
                self.noise_sigma
            )));
        }
        if !(0.0..=1.0).contains(&self.outlier_fraction) {
            return Err(InvalidTruth(format!(
                "outlier_fraction {} is not in [0, 1]",
                self.outlier_fraction
            )));
        }
        Ok(())
    }
}

/// Reads and validates a truth file.
///
/// # Errors
/// [`TruthError`] naming the file: unreadable, not the expected JSON, or inconsistent
/// (see [`ScenarioTruth::validate`]).
pub fn read(path: impl AsRef<Path>) -> Result<ScenarioTruth, TruthError> {
    let path = path.as_ref();
    let err = |kind| TruthError {
        path: path.display().to_string(),
        kind,
    };
    let bytes = std::fs::read(path).map_err(|e| err(TruthErrorKind::Read(e)))?;
    // A UTF-8 byte-order mark is accepted, as by every reader.
    let json = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
    let truth: ScenarioTruth =
        serde_json::from_slice(json).map_err(|e| err(TruthErrorKind::Json(e)))?;
    truth
        .validate()
        .map_err(|e| err(TruthErrorKind::Inconsistent(e)))?;
    Ok(truth)
}

/// Writes a truth file as compact JSON (the generator's layout), after validating it
/// ([`crate::output::write_file`]: whole, never over a device, a FIFO or a folder).
///
/// # Errors
/// [`TruthError`] naming the file: inconsistent values, or the file cannot be written.
pub fn write(path: impl AsRef<Path>, truth: &ScenarioTruth) -> Result<(), TruthError> {
    let path = path.as_ref();
    let err = |kind| TruthError {
        path: path.display().to_string(),
        kind,
    };
    truth
        .validate()
        .map_err(|e| err(TruthErrorKind::Inconsistent(e)))?;
    let bytes = serde_json::to_vec(truth).map_err(|e| err(TruthErrorKind::Json(e)))?;
    crate::output::write_file(path, &bytes).map_err(|e| err(TruthErrorKind::Write(e)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use swarmpose_testdata::TempDir;

    /// Written by gen_scenarios.py (`make_scenario(1000, 0.02, 0.3, "structured", n_target=5)`).
    const GENERATED: &str = r#"{"rotation_wxyz":[0.9958624493740758,-0.01675119826227682,0.05794774356936882,0.06796644980181756],"translation":[0.13673865983756053,-1.108268486648121,0.1764206200104044],"inlier":[true,true,false,false,true],"noise_sigma":0.02,"outlier_fraction":0.3,"seed":1000,"mode":"structured","n":5,"n_outliers":2,"n_scene_points_drawn":400,"rotation_angle_deg":10.427714759501251,"outlier_rotation_wxyz":[0.9701978607333821,0.0059216544039218996,0.11453942944809434,0.21345201835352767],"outlier_translation":[-3.2844914262257414,-1.2572112506197608,-0.5931856117635804]}"#;

    fn write_text(dir: &TempDir, name: &str, text: &str) -> PathBuf {
        let path = dir.path(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn sample() -> ScenarioTruth {
        serde_json::from_str(GENERATED).unwrap()
    }

    #[test]
    fn reads_generator_output() {
        let dir = TempDir::new("truth-read");
        let t = read(write_text(&dir, "s.json", GENERATED)).unwrap();
        assert_eq!(t.mode, "structured");
        assert_eq!(t.seed, 1000);
        assert_eq!(t.inlier_indices(), vec![0, 1, 4]);
        let iso = t.isometry().unwrap();
        let q = swarmpose_core::geometry::quaternion_wxyz(&iso.rotation);
        for (a, b) in q.iter().zip(t.rotation_wxyz) {
            assert!((a - b).abs() < 1e-12);
        }
        assert_eq!(iso.translation.vector, Vector3::from(t.translation));
        assert!(t.outlier_isometry().unwrap().is_some());
    }

    #[test]
    fn extras_are_optional_and_unknown_keys_ignored() {
        let text = r#"{"rotation_wxyz":[1,0,0,0],"translation":[0,0,0],"inlier":[true],
            "noise_sigma":0,"outlier_fraction":0,"seed":1,"mode":"random","n":1,
            "n_outliers":0,"something_new":[1,2]}"#;
        let dir = TempDir::new("truth-min");
        let t = read(write_text(&dir, "m.json", text)).unwrap();
        assert_eq!(t.outlier_rotation_wxyz, None);
        assert_eq!(t.outlier_isometry().unwrap(), None);
        assert_eq!(t.isometry().unwrap(), Isometry3::identity());
    }

    #[test]
    fn write_read_round_trip() {
        let dir = TempDir::new("truth-rt");
        let path = dir.path("rt.json");
        let t = sample();
        write(&path, &t).unwrap();
        assert_eq!(read(&path).unwrap(), t);
        // Optional fields left out stay out.
        let mut bare = t.clone();
        bare.outlier_rotation_wxyz = None;
        bare.outlier_translation = None;
        bare.rotation_angle_deg = None;
        write(&path, &bare).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(!text.contains("outlier_translation") && !text.contains("null"));
        assert_eq!(read(&path).unwrap(), bare);
    }

    #[test]
    fn missing_file() {
        let dir = TempDir::new("truth-missing");
        let path = dir.path("nope.json");
        let e = read(&path).unwrap_err();
        assert!(matches!(e.kind, TruthErrorKind::Read(_)));
        assert!(
            e.to_string()
                .starts_with(&format!("{}: cannot read: ", path.display()))
        );
    }

    #[test]
    fn bad_json() {
        let dir = TempDir::new("truth-bad");
        for text in ["", "{", "[1,2]", r#"{"rotation_wxyz":[1,0,0,0]}"#] {
            let e = read(write_text(&dir, "b.json", text)).unwrap_err();
            assert!(matches!(e.kind, TruthErrorKind::Json(_)), "{text}: {e}");
            assert!(e.to_string().contains("b.json: invalid truth JSON"), "{e}");
        }
        let e = read(write_text(
            &dir,
            "b.json",
            &GENERATED.replace("\"seed\":1000", "\"seed\":\"x\""),
        ))
        .unwrap_err();
        assert!(e.to_string().contains("line 1 column"), "{e}");
    }

    #[test]
    fn inconsistent_values() {
        let dir = TempDir::new("truth-inconsistent");
        let cases = [
            ("\"n\":5", "\"n\":6", "n is 6"),
            ("\"n_outliers\":2", "\"n_outliers\":1", "n_outliers is 1"),
            ("[0.9958624493740758", "[1.5", "not a unit quaternion"),
            ("\"noise_sigma\":0.02", "\"noise_sigma\":-1", "noise_sigma"),
            (
                "\"outlier_fraction\":0.3",
                "\"outlier_fraction\":1.5",
                "outlier_fraction",
            ),
            (
                ",\"outlier_translation\":[-3.2844914262257414,-1.2572112506197608,-0.5931856117635804]",
                "",
                "given together",
            ),
        ];
        for (from, to, expect) in cases {
            let text = GENERATED.replace(from, to);
            assert_ne!(text, GENERATED, "{from}");
            let e = read(write_text(&dir, "i.json", &text)).unwrap_err();
            assert!(matches!(e.kind, TruthErrorKind::Inconsistent(_)), "{e}");
            assert!(e.to_string().contains(expect), "{expect}: {e}");
        }
        // Writing refuses it too.
        let mut t = sample();
        t.n = 99;
        let e = write(dir.path("w.json"), &t).unwrap_err();
        assert!(matches!(e.kind, TruthErrorKind::Inconsistent(_)));
    }

    #[test]
    fn unwritable_file() {
        let dir = TempDir::new("truth-unwritable");
        let e = write(dir.path("missing-dir").join("t.json"), &sample()).unwrap_err();
        assert!(matches!(e.kind, TruthErrorKind::Write(_)), "{e}");
    }

    #[test]
    fn csv_and_json_paths() {
        assert_eq!(
            path_for_csv(Path::new("suite/random_n0.020_o0.10_r001.csv")),
            PathBuf::from("suite/random_n0.020_o0.10_r001.json")
        );
    }
}
