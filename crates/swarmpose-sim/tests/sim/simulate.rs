//! The whole job on a tiny grid: every file written; bad arguments rejected before work.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;

use swarmpose_sim::{Experiment, SimError, SimOptions, default_estimators, simulate};

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("swarmpose-sim-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn tiny(out: PathBuf) -> SimOptions {
    SimOptions {
        experiment: Experiment {
            noise_levels: vec![0.0, 0.05],
            fractions: vec![0.0, 0.3],
            runs: 2,
            ..Experiment::default()
        },
        out_dir: out,
        export_dir: None,
        threads: Some(2),
        progress: false,
    }
}

#[test]
fn writes_every_file_and_exports_readable_scenarios() {
    let out = temp_dir("out");
    let export = temp_dir("export");
    let mut opts = tiny(out.clone());
    opts.export_dir = Some(export.clone());
    let outcome = simulate(&opts, &default_estimators()).unwrap();
    for name in [
        "runs.csv",
        "summary.md",
        "position_error.png",
        "position_error.svg",
        "processing_time.png",
        "processing_time.svg",
        "rotation_error.png",
        "rotation_error.svg",
        "success_rate.png",
        "success_rate.svg",
    ] {
        let path = out.join(name);
        assert!(std::fs::metadata(&path).unwrap().len() > 100, "{name}");
    }
    let csv = std::fs::read_to_string(out.join("runs.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 2 * 2 * 4);
    let md = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(md.contains("## Noise σ = 0.05 m") && md.contains("| msac |"));
    assert!(outcome.console.contains("svd"));
    // Exported scenarios read back with the data crate, truth consistent with the rows.
    let name = "random_n0.050_o0.30_r001";
    let data =
        swarmpose_data::correspondence_csv::read_path(export.join(format!("{name}.csv"))).unwrap();
    let truth = swarmpose_data::truth::read(export.join(format!("{name}.json"))).unwrap();
    assert_eq!(truth.n, data.len());
    assert_eq!(truth.seed, 1001);
    assert_eq!(truth.n_outliers, (0.3 * data.len() as f64).round() as usize);
    assert_eq!(std::fs::read_dir(&export).unwrap().count(), 2 * 2 * 2 * 2);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&export);
}

#[test]
fn bad_arguments_fail_before_any_work() {
    // An output "folder" that is a file.
    let file = temp_dir("file");
    std::fs::write(&file, b"x").unwrap();
    let err = simulate(&tiny(file.join("sub")), &default_estimators()).unwrap_err();
    assert!(matches!(err, SimError::Io { .. }), "{err}");
    let err = simulate(&tiny(file.clone()), &default_estimators()).unwrap_err();
    assert!(err.to_string().contains("not a folder"), "{err}");
    let _ = std::fs::remove_file(&file);

    let out = temp_dir("bad");
    let mut cases = Vec::new();
    let mut o = tiny(out.clone());
    o.experiment.noise_levels = vec![-0.02];
    cases.push(o);
    let mut o = tiny(out.clone());
    o.experiment.fractions = vec![1.0];
    cases.push(o);
    let mut o = tiny(out.clone());
    o.experiment.runs = 0;
    cases.push(o);
    let mut o = tiny(out.clone());
    o.threads = Some(0);
    cases.push(o);
    for o in cases {
        let err = simulate(&o, &default_estimators()).unwrap_err();
        assert!(matches!(err, SimError::InvalidConfig(_)), "{err}");
        assert!(
            !out.exists(),
            "output folder created before the settings were checked"
        );
    }
}
