//! Scenarios as files in `gen_scenarios.py`'s format, so any other tool can run them:
//! `NAME.csv` (`src_x,src_y,src_z,dst_x,dst_y,dst_z`) and `NAME.json` (the truth).

use std::path::{Path, PathBuf};

use swarmpose_core::geometry::quaternion_wxyz;
use swarmpose_data::ScenarioTruth;

use crate::error::SimError;
use crate::outliers::{OutlierMode, Scenario};
use crate::stereo::StereoScenario;

/// The generator's file name (without extension) of a scenario:
/// `{mode}_n{noise:.3}_o{fraction:.2}_r{run:03}`.
#[must_use]
pub fn scenario_name(mode: OutlierMode, noise: f64, fraction: f64, run: usize) -> String {
    format!("{mode}_n{noise:.3}_o{fraction:.2}_r{run:03}")
}

/// The truth record of a scenario, as the generator writes it.
#[must_use]
pub fn truth_of(s: &Scenario) -> ScenarioTruth {
    let wxyz = quaternion_wxyz(&s.truth.rotation);
    let t = s.truth.translation.vector;
    let (outlier_rotation_wxyz, outlier_translation) = match &s.outlier_motion {
        Some(m) => {
            let mt = m.translation.vector;
            (Some(quaternion_wxyz(&m.rotation)), Some([mt.x, mt.y, mt.z]))
        }
        None => (None, None),
    };
    ScenarioTruth {
        rotation_wxyz: wxyz,
        translation: [t.x, t.y, t.z],
        inlier: s.inlier.clone(),
        noise_sigma: s.noise_sigma,
        outlier_fraction: s.outlier_fraction,
        seed: s.seed,
        mode: s.mode.name().to_owned(),
        n: s.data.len(),
        n_outliers: s.n_outliers(),
        n_scene_points_drawn: Some(s.n_drawn),
        rotation_angle_deg: Some(2.0 * wxyz[0].abs().min(1.0).acos().to_degrees()),
        outlier_rotation_wxyz,
        outlier_translation,
    }
}

/// Writes `dir/NAME.csv` and `dir/NAME.json`; returns the CSV path.
///
/// # Errors
/// [`SimError::Export`] naming the file that could not be written.
pub fn write_scenario(dir: &Path, name: &str, s: &Scenario) -> Result<PathBuf, SimError> {
    let csv = dir.join(format!("{name}.csv"));
    swarmpose_data::correspondence_csv::write_path(&csv, &s.data)
        .map_err(|e| SimError::Export(e.to_string()))?;
    swarmpose_data::truth::write(dir.join(format!("{name}.json")), &truth_of(s))
        .map_err(|e| SimError::Export(e.to_string()))?;
    Ok(csv)
}

/// The truth record of a stereo-noise scenario (`mode` "stereo"; `noise_sigma` 0: its
/// noise has no single σ, it grows with depth).
#[must_use]
pub fn stereo_truth_of(s: &StereoScenario, outlier_fraction: f64, seed: u64) -> ScenarioTruth {
    let wxyz = quaternion_wxyz(&s.truth.rotation);
    let t = s.truth.translation.vector;
    let n_outliers = s.inlier.iter().filter(|&&b| !b).count();
    ScenarioTruth {
        rotation_wxyz: wxyz,
        translation: [t.x, t.y, t.z],
        inlier: s.inlier.clone(),
        noise_sigma: 0.0,
        outlier_fraction,
        seed,
        mode: "stereo".to_owned(),
        n: s.data.len(),
        n_outliers,
        n_scene_points_drawn: None,
        rotation_angle_deg: Some(2.0 * wxyz[0].abs().min(1.0).acos().to_degrees()),
        outlier_rotation_wxyz: None,
        outlier_translation: None,
    }
}

/// Writes a stereo-noise scenario as `dir/NAME.csv` and `dir/NAME.json`, with its
/// covariance columns when `covariances`, else plain coordinates (the peers' format);
/// returns the CSV path.
///
/// # Errors
/// [`SimError::Export`] naming the file that could not be written.
pub fn write_stereo_scenario(
    dir: &Path,
    name: &str,
    s: &StereoScenario,
    outlier_fraction: f64,
    seed: u64,
    covariances: bool,
) -> Result<PathBuf, SimError> {
    let csv = dir.join(format!("{name}.csv"));
    let plain;
    let data = if covariances {
        &s.data
    } else {
        plain = s.plain()?;
        &plain
    };
    swarmpose_data::correspondence_csv::write_path(&csv, data)
        .map_err(|e| SimError::Export(e.to_string()))?;
    swarmpose_data::truth::write(
        dir.join(format!("{name}.json")),
        &stereo_truth_of(s, outlier_fraction, seed),
    )
    .map_err(|e| SimError::Export(e.to_string()))?;
    Ok(csv)
}
