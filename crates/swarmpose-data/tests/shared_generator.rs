//! The core estimators on scenarios written by the shared generator
//! (`$SWARMPOSE_DATA/../peers/gen_scenarios.py`, default `../shared/peers/` beside the
//! repository), read back through this crate's CSV and truth readers.
//!
//! Skipped with a printed reason when the generator, python3 or numpy is missing, except
//! under `CI=true`, where that is a failure.

use std::path::{Path, PathBuf};
use std::process::Command;

use nalgebra::Isometry3;
use swarmpose_core::geometry::rotation_angle_between;
use swarmpose_core::{
    Estimator, MsacConfig, MsacEstimator, PsoEstimator, PsoEstimatorConfig, SvdEstimator,
};
use swarmpose_data::{correspondence_csv, truth};

/// `$SWARMPOSE_DATA`, or `../shared/data` beside the repository.
fn shared_data_dir() -> PathBuf {
    std::env::var_os("SWARMPOSE_DATA").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        PathBuf::from,
    )
}

/// The generator script, or `None` (after printing why) when the test must be skipped.
fn generator() -> Option<PathBuf> {
    let script = shared_data_dir().join("../peers/gen_scenarios.py");
    let numpy = Command::new("python3")
        .args(["-c", "import numpy"])
        .status()
        .is_ok_and(|s| s.success());
    let reason = if !script.is_file() {
        format!("{} not found", script.display())
    } else if !numpy {
        "python3 with numpy is not available".to_string()
    } else {
        return Some(script);
    };
    assert!(
        std::env::var("CI").as_deref() != Ok("true"),
        "under CI the shared generator must be usable: {reason}"
    );
    eprintln!("SKIPPED: {reason} (set SWARMPOSE_DATA to the shared data folder)");
    None
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("swarmpose-gen-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn errors(est: &Isometry3<f64>, truth: &Isometry3<f64>) -> (f64, f64) {
    (
        rotation_angle_between(&est.rotation, &truth.rotation).to_degrees(),
        (est.translation.vector - truth.translation.vector).norm(),
    )
}

/// Issue 2, "Done when": noise 0.02 m, random outliers 0 to 50 %, 50 runs each: `pso` and
/// `msac` within 0.5 degrees and 0.1 m in at least 98 % of the runs.
#[test]
fn pso_and_msac_recover_shared_scenarios() {
    let Some(script) = generator() else { return };
    let dir = temp_dir("suite");
    let status = Command::new("python3")
        .arg(&script)
        .args(["--out"])
        .arg(&dir)
        .args([
            "--runs",
            "50",
            "--noise",
            "0.02",
            "--fractions",
            "0",
            "0.1",
            "0.3",
            "0.5",
        ])
        .args(["--modes", "random"])
        .status()
        .expect("run the generator");
    assert!(status.success());
    let threshold = 3.368 * 0.02; // the peers' threshold: sqrt(chi2_3(0.99)) sigma
    let estimators: Vec<Box<dyn Estimator>> = vec![
        Box::new(PsoEstimator::new(
            PsoEstimatorConfig::default().with_threshold(threshold),
        )),
        Box::new(MsacEstimator::new(
            MsacConfig::default().with_threshold(threshold),
        )),
    ];
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("read suite")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 200);
    for e in &estimators {
        for frac in ["o0.00", "o0.10", "o0.30", "o0.50"] {
            let (mut ok, mut total, mut worst_rot) = (0, 0, 0.0_f64);
            for (run, csv) in files
                .iter()
                .filter(|p| p.to_string_lossy().contains(frac))
                .enumerate()
            {
                let data = correspondence_csv::read_path(csv).expect("readable scenario");
                let t = truth::read(truth::path_for_csv(csv)).expect("readable truth");
                total += 1;
                if let Ok(out) = e.estimate_seeded(&data, run as u64) {
                    let (rot_deg, trans_m) =
                        errors(&out.transform, &t.isometry().expect("valid truth"));
                    worst_rot = worst_rot.max(rot_deg);
                    ok += usize::from(rot_deg < 0.5 && trans_m < 0.1);
                }
            }
            eprintln!(
                "{} {frac}: {ok}/{total} within 0.5 deg and 0.1 m (worst rotation {worst_rot:.3} deg)",
                e.name()
            );
            assert_eq!(total, 50);
            assert!(
                ok * 100 >= total * 98,
                "{} at {frac}: {ok}/{total}",
                e.name()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `svd` is exact on the generator's noise-free, outlier-free scenarios. The generator's
/// CSV keeps 6 decimals, so the scenario is written here at full precision by the
/// generator's own `make_scenario`.
#[test]
fn svd_exact_on_shared_noise_free_scenarios() {
    let Some(script) = generator() else { return };
    let dir = temp_dir("exact");
    let program = r#"
import sys, json, importlib.util
import numpy as np
spec = importlib.util.spec_from_file_location("gen", sys.argv[1])
gen = importlib.util.module_from_spec(spec); spec.loader.exec_module(gen)
for seed in range(1000, 1020):
    src, dst, truth = gen.make_scenario(seed, 0.0, 0.0, "random")
    base = f"{sys.argv[2]}/exact_{seed}"
    np.savetxt(base + ".csv", np.hstack([src, dst]), delimiter=",", fmt="%.17g",
               header="src_x,src_y,src_z,dst_x,dst_y,dst_z", comments="")
    json.dump(truth, open(base + ".json", "w"))
"#;
    let status = Command::new("python3")
        .args(["-c", program])
        .arg(&script)
        .arg(&dir)
        .status()
        .expect("run python");
    assert!(status.success());
    for seed in 1000..1020 {
        let csv = dir.join(format!("exact_{seed}.csv"));
        let data = correspondence_csv::read_path(&csv).expect("readable");
        let t = truth::read(truth::path_for_csv(&csv))
            .expect("truth")
            .isometry()
            .expect("valid");
        let out = SvdEstimator.estimate_seeded(&data, 0).expect("solvable");
        let dr = (out.transform.rotation.to_rotation_matrix().into_inner()
            - t.rotation.to_rotation_matrix().into_inner())
        .norm();
        let dt = (out.transform.translation.vector - t.translation.vector).norm();
        assert!(
            dr < 1e-9 && dt < 1e-9,
            "seed {seed}: rotation {dr:e}, translation {dt:e} m"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
