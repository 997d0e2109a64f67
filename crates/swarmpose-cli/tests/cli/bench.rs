//! `swarmpose bench` on a small suite written here in the generator's format.

use crate::common::{TempDir, check_error, swarmpose};
use swarmpose_core::geometry::quaternion_wxyz;
use swarmpose_core::synthetic::SyntheticSpec;
use swarmpose_data::truth::{ScenarioTruth, write};

/// Writes `runs` scenarios per outlier fraction, noise 0.02 m, in `gen_scenarios.py`'s
/// file format.
fn suite(dir: &TempDir, fractions: &[f64], runs: u64) {
    for &f in fractions {
        for run in 0..runs {
            let spec = SyntheticSpec {
                outlier_fraction: f,
                n: 120,
                ..Default::default()
            };
            let s = spec.generate(run).expect("valid spec");
            let name = format!("random_n0.020_o{f:.2}_r{run:03}");
            swarmpose_data::correspondence_csv::write_path(
                dir.0.join(format!("{name}.csv")),
                &s.data,
            )
            .expect("write csv");
            let t = s.truth.translation.vector;
            let truth = ScenarioTruth {
                rotation_wxyz: quaternion_wxyz(&s.truth.rotation),
                translation: [t.x, t.y, t.z],
                n_outliers: s.inlier.iter().filter(|b| !**b).count(),
                n: s.inlier.len(),
                inlier: s.inlier.clone(),
                noise_sigma: 0.02,
                outlier_fraction: f,
                seed: run,
                mode: "random".into(),
                n_scene_points_drawn: None,
                rotation_angle_deg: None,
                outlier_rotation_wxyz: None,
                outlier_translation: None,
            };
            write(dir.0.join(format!("{name}.json")), &truth).expect("write truth");
        }
    }
}

#[test]
fn prints_tables_per_cell() {
    let dir = TempDir::new("bench");
    suite(&dir, &[0.0, 0.5], 4);
    let path = dir.0.to_string_lossy().to_string();
    let out = swarmpose(&["bench", &path, "--methods", "pso,msac,svd"], None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("## Success rate (%) vs outlier fraction - random outliers, noise 0.02 m")
    );
    assert!(text.contains("| method | 0 | 0.5 |"), "{text}");
    // pso and msac solve every scenario; svd fails with half the matches wrong.
    assert!(text.contains("| pso | 100 (n=4) | 100 (n=4) |"), "{text}");
    assert!(text.contains("| msac | 100 (n=4) | 100 (n=4) |"), "{text}");
    assert!(text.contains("| svd | 100 (n=4) | 0 (n=4) |"), "{text}");
    assert!(text.contains("8 scenarios"));
}

#[test]
fn writes_one_row_per_run_and_the_oracle_reference() {
    let dir = TempDir::new("bench-runs");
    suite(&dir, &[0.5], 3);
    let path = dir.0.to_string_lossy().to_string();
    let runs = dir.0.join("runs.csv");
    let runs_arg = runs.to_string_lossy().to_string();
    let args = [
        "bench",
        &path,
        "--methods",
        "pso,oracle-inliers",
        "--runs-csv",
        &runs_arg,
    ];
    let out = swarmpose(&args, None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&runs).expect("runs CSV written");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "scenario,method,success,rotation_deg,translation_m,time_ms,inliers"
    );
    assert_eq!(lines.len(), 1 + 3 * 2, "{text}");
    // The oracle fits exactly the 60 true inliers of 120 correspondences.
    let oracle: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.contains(",oracle-inliers,"))
        .collect();
    assert_eq!(oracle.len(), 3);
    assert!(
        oracle
            .iter()
            .all(|l| l.ends_with(",60") && l.contains(",1,")),
        "{text}"
    );
    // Seeds follow the scenario, not its position: a filtered run repeats the same row.
    let only = [
        "bench",
        &path,
        "--methods",
        "pso",
        "--filter",
        "r002",
        "--runs-csv",
        &runs_arg,
    ];
    let pso_row = |t: &str| {
        t.lines()
            .find(|l| l.starts_with("random_n0.020_o0.50_r002,pso,"))
            .map(|l| l.rsplitn(3, ',').nth(2).unwrap_or_default().to_owned())
    };
    let first = pso_row(&text);
    assert!(swarmpose(&only, None).status.success());
    let again = std::fs::read_to_string(&runs).expect("runs CSV written");
    assert!(first.is_some());
    assert_eq!(first, pso_row(&again), "{text}\n{again}");
}

#[test]
fn bad_arguments_are_one_line_errors() {
    let dir = TempDir::new("bench-bad");
    let path = dir.0.to_string_lossy().to_string();
    check_error(
        &swarmpose(&["bench", &path], None),
        &["no scenario .csv files"],
    );
    suite(&dir, &[0.0], 1);
    check_error(
        &swarmpose(&["bench", &path, "--methods", "ransac"], None),
        &["unknown method"],
    );
    std::fs::remove_file(dir.0.join("random_n0.020_o0.00_r000.json")).expect("remove truth");
    check_error(
        &swarmpose(&["bench", &path], None),
        &["random_n0.020_o0.00_r000.json"],
    );
    check_error(
        &swarmpose(&["bench", "/nonexistent/suite"], None),
        &["/nonexistent/suite"],
    );
}

/// Issue 29, cause 11: `bench --stereo 0` (or a filter that matches no generated
/// scenario) printed empty tables with exit 0.
#[test]
fn no_scenario_is_an_error() {
    let out = swarmpose(&["bench", "--stereo", "0"], None);
    check_error(
        &out,
        &["--stereo 0: give 1 to 100000 scenarios per outlier fraction"],
    );
    let out = swarmpose(&["bench", "--stereo", "1", "--filter", "nothing"], None);
    check_error(
        &out,
        &["--filter \"nothing\" matches none of the 3 generated scenarios"],
    );
}
