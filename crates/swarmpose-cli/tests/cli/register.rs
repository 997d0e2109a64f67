//! `swarmpose register` end to end: the built binary on small CSVs in a temp dir.

use std::path::Path;
use std::process::Output;

use crate::common::{HEADER, TempDir, check_error, csv, json_of, swarmpose};
use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use serde_json::Value;

const METHODS: [&str; 4] = ["pso", "pso-paper", "svd", "msac"];

fn register(path: &Path, extra: &[&str]) -> Output {
    let path = path.to_str().expect("utf-8 temp path");
    let mut args = vec!["register", path];
    args.extend_from_slice(extra);
    swarmpose(&args, None)
}

/// The true motion of the synthetic data.
fn truth() -> Isometry3<f64> {
    let rotation = UnitQuaternion::from_scaled_axis(Vector3::new(0.12, -0.25, 0.3));
    Isometry3::from_parts(Vector3::new(0.4, -1.1, 0.75).into(), rotation)
}

/// `n` well spread source points (metres, in front of a camera), deterministic.
fn source_points(n: usize) -> Vec<Point3<f64>> {
    (0..n)
        .map(|i| {
            let f = i as f64;
            Point3::new(
                -4.0 + (i % 7) as f64 * 1.3 + 0.01 * f,
                -3.0 + ((i / 7) % 5) as f64 * 1.4,
                4.0 + ((i * 3) % 11) as f64 * 1.7,
            )
        })
        .collect()
}

/// Noise-free data: `dst = truth * src` for every row.
fn clean_csv(n: usize) -> String {
    let src = source_points(n);
    let dst: Vec<_> = src.iter().map(|p| truth() * p).collect();
    csv(&src, &dst)
}

fn f64s(v: &Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("{key} is an array"))
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// Checks the keys, the threshold reported and the pose against [`truth`] to 1e-6.
/// `threshold_m`: the δ given on the command line, or `None` for the default (pso then
/// estimates its own from the scene's scale, here below 0.3 m; the others use 0.1 m).
fn check_pose(v: &Value, method: &str, n: usize, threshold_m: Option<f64>) {
    for key in [
        "method",
        "input",
        "seed",
        "n_correspondences",
        "rotation_wxyz",
        "translation",
        "inliers",
        "inlier_ratio",
        "threshold_m",
        "final_cost",
        "residual_rms_m",
        "iterations",
        "cost_evaluations",
        "elapsed_ms",
    ] {
        assert!(v.get(key).is_some(), "{method}: key {key} missing in {v}");
    }
    assert_eq!(v["method"], method);
    assert_eq!(v["n_correspondences"].as_u64(), Some(n as u64));
    let q = f64s(v, "rotation_wxyz");
    let t = f64s(v, "translation");
    let tq = swarmpose_core::geometry::quaternion_wxyz(&truth().rotation);
    let tt = truth().translation.vector;
    assert!(q[0] >= 0.0, "{method}: w >= 0");
    for k in 0..4 {
        assert!(
            (q[k] - tq[k]).abs() < 1e-6,
            "{method}: rotation {q:?} vs {tq:?}"
        );
    }
    for k in 0..3 {
        assert!(
            (t[k] - tt[k]).abs() < 1e-6,
            "{method}: translation {t:?} vs {tt}"
        );
    }
    assert!(v["elapsed_ms"].as_f64().expect("elapsed_ms") >= 0.0);
    assert!(
        v["residual_rms_m"].as_f64().expect("rms") < 1e-6,
        "{method}"
    );
    if method == "svd" {
        assert!(v["threshold_m"].is_null());
    } else {
        let got = v["threshold_m"].as_f64().expect("threshold_m");
        match (threshold_m, method) {
            (Some(d), _) => assert_eq!(got, d, "{method}"),
            (None, "pso") => assert!(got > 0.0 && got <= 0.3, "{method}: {got}"),
            (None, _) => assert_eq!(got, 0.1, "{method}"),
        }
    }
}

fn inliers(v: &Value) -> Vec<u64> {
    v["inliers"]
        .as_array()
        .expect("inliers is an array")
        .iter()
        .map(|x| x.as_u64().expect("index"))
        .collect()
}

#[test]
fn every_method_recovers_a_noise_free_pose() {
    let dir = TempDir::new("clean");
    let n = 30;
    let path = dir.file("clean.csv", &clean_csv(n));
    for method in METHODS {
        let v = json_of(&register(&path, &["--method", method, "--seed", "7"]));
        check_pose(&v, method, n, None);
        assert_eq!(inliers(&v), (0..n as u64).collect::<Vec<_>>(), "{method}");
        assert_eq!(v["inlier_ratio"].as_f64(), Some(1.0));
        assert_eq!(v["seed"].as_u64(), Some(7));
        assert_eq!(v["input"].as_str(), path.to_str());
    }
}

#[test]
fn default_method_is_pso_and_one_seed_gives_one_answer() {
    let dir = TempDir::new("default");
    let path = dir.file("clean.csv", &clean_csv(12));
    let a = json_of(&register(&path, &[]));
    check_pose(&a, "pso", 12, None);
    assert_eq!(a["seed"].as_u64(), Some(0));
    let b = json_of(&register(&path, &[]));
    assert_eq!(a["rotation_wxyz"], b["rotation_wxyz"]);
    assert_eq!(a["translation"], b["translation"]);
}

#[test]
fn robust_methods_reject_outliers() {
    let dir = TempDir::new("outliers");
    let (n, bad) = (40, 10);
    let src = source_points(n + bad);
    let dst: Vec<_> = src
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let shift = if i < n {
                Vector3::zeros()
            } else {
                Vector3::new(2.0 + (i % 3) as f64, -1.5, 1.0 + (i % 4) as f64)
            };
            truth() * p + shift
        })
        .collect();
    let path = dir.file("outliers.csv", &csv(&src, &dst));
    for method in ["pso", "msac"] {
        let v = json_of(&register(&path, &["--method", method]));
        check_pose(&v, method, n + bad, None);
        assert_eq!(inliers(&v), (0..n as u64).collect::<Vec<_>>(), "{method}");
    }
}

#[test]
fn knobs_are_applied() {
    let dir = TempDir::new("knobs");
    let path = dir.file("clean.csv", &clean_csv(20));
    let swarm = |method: &str, particles: u64, iterations: u64, threshold: &str| {
        let (p, i) = (particles.to_string(), iterations.to_string());
        let args = [
            "--method",
            method,
            "--particles",
            &p,
            "--iterations",
            &i,
            "--stall",
            "none",
            "--inertia",
            "0.5",
            "--acceleration",
            "1.2",
            "--threshold",
            threshold,
        ];
        let v = json_of(&register(&path, &args));
        check_pose(&v, method, 20, Some(threshold.parse().expect("number")));
        assert_eq!(v["iterations"].as_u64(), Some(iterations), "{method}");
        let evaluations = particles * (1 + iterations);
        assert_eq!(
            v["cost_evaluations"].as_u64(),
            Some(evaluations),
            "{method}"
        );
    };
    swarm("pso", 6, 3, "0.05");
    swarm("pso-paper", 40, 120, "0.2");
    let msac = [
        "--method",
        "msac",
        "--max-samples",
        "1",
        "--confidence",
        "0.5",
    ];
    let v = json_of(&register(&path, &msac));
    assert_eq!(v["iterations"].as_u64(), Some(1));
    let seeded = ["--seeded-particles", "3", "--particles", "8"];
    check_pose(&json_of(&register(&path, &seeded)), "pso", 20, None);
}

#[test]
fn reads_standard_input() {
    let v = json_of(&swarmpose(
        &["register", "-", "--method", "svd"],
        Some(&clean_csv(10).replace('\n', "\r\n")),
    ));
    check_pose(&v, "svd", 10, None);
    assert_eq!(v["input"], "<stdin>");
}

/// Writes `text` as `name` and checks the error of registering it.
fn bad_file(name: &str, text: &str, needles: &[&str]) -> String {
    let dir = TempDir::new("bad");
    let path = dir.file(name, text);
    let shown = path.to_str().expect("utf-8 path").to_owned();
    let mut all = vec![shown.as_str()];
    all.extend_from_slice(needles);
    check_error(&register(&path, &[]), &all)
}

/// A good file with `row` appended as line 12.
fn with_row(row: &str) -> String {
    format!("{}{row}\n", clean_csv(10))
}

#[test]
fn empty_file() {
    bad_file("empty.csv", "", &["empty file", HEADER]);
}

#[test]
fn missing_header() {
    let body = clean_csv(6);
    let headless = body.split_once('\n').expect("header").1;
    bad_file(
        "noheader.csv",
        headless,
        &["line 1", "missing header", HEADER],
    );
}

#[test]
fn wrong_header() {
    let text = clean_csv(6).replace(HEADER, "x1,y1,z1,x2,y2,z2");
    bad_file(
        "header.csv",
        &text,
        &["line 1", "wrong header", HEADER, "x1,y1,z1,x2,y2,z2"],
    );
}

#[test]
fn non_numeric_field() {
    let line = bad_file(
        "text.csv",
        &with_row("1,2,3,4,abc,6"),
        &["line 12", "column dst_y", "not a number", "\"abc\""],
    );
    assert!(
        line.ends_with("line 12: column dst_y: not a number: \"abc\""),
        "{line}"
    );
}

#[test]
fn nan_field() {
    bad_file(
        "nan.csv",
        &with_row("1,NaN,3,4,5,6"),
        &["line 12", "column src_y", "not a finite number"],
    );
}

#[test]
fn infinite_field() {
    bad_file(
        "inf.csv",
        &with_row("1,2,3,inf,5,6"),
        &["line 12", "column dst_x", "not a finite number"],
    );
}

#[test]
fn row_with_five_fields() {
    bad_file(
        "short.csv",
        &with_row("1,2,3,4,5"),
        &["line 12", "expected 6 fields, found 5"],
    );
}

#[test]
fn header_only() {
    bad_file("headeronly.csv", &format!("{HEADER}\n"), &["no data rows"]);
}

/// Registers `text` with every method; each must fail naming the file and `what`.
fn bad_points_for_every_method(name: &str, text: &str, what: &str) {
    let dir = TempDir::new("points");
    let path = dir.file(name, text);
    let shown = path.to_str().expect("utf-8 path");
    for method in METHODS {
        check_error(
            &register(&path, &["--method", method]),
            &[shown, method, what],
        );
    }
}

#[test]
fn fewer_than_four_rows() {
    bad_points_for_every_method("three.csv", &clean_csv(3), "too few correspondences: 3");
}

#[test]
fn all_points_identical() {
    let p = Point3::new(1.0, 2.0, 3.0);
    let text = csv(&[p; 8], &[truth() * p; 8]);
    bad_points_for_every_method("same.csv", &text, "all points coincide");
}

#[test]
fn all_points_collinear() {
    let src: Vec<_> = (0..8)
        .map(|i| Point3::new(1.0, 2.0, 3.0) + Vector3::new(0.5, -0.2, 1.0) * i as f64)
        .collect();
    let dst: Vec<_> = src.iter().map(|p| truth() * p).collect();
    bad_points_for_every_method("line.csv", &csv(&src, &dst), "collinear");
}

#[test]
fn nonexistent_file() {
    let dir = TempDir::new("missing");
    let path = dir.0.join("no-such-file.csv");
    let shown = path.to_str().expect("utf-8 path");
    check_error(&register(&path, &[]), &[shown, "cannot read"]);
}

#[test]
fn bad_standard_input_is_named() {
    let out = swarmpose(&["register", "-"], Some(&with_row("1,2,3,4,5,x")));
    check_error(&out, &["<stdin>: line 12: column dst_z"]);
}

#[test]
fn negative_threshold() {
    let dir = TempDir::new("threshold");
    let path = dir.file("clean.csv", &clean_csv(10));
    for value in ["-0.1", "0", "NaN", "inf"] {
        check_error(
            &register(&path, &["--threshold", value]),
            &["--threshold", value, "positive"],
        );
    }
    let joined = register(&path, &["--threshold=-1"]);
    check_error(&joined, &["--threshold", "-1"]);
}

#[test]
fn invalid_option_values() {
    let dir = TempDir::new("options");
    let path = dir.file("clean.csv", &clean_csv(10));
    let cases: [(&[&str], &str); 7] = [
        (&["--particles", "0"], "--particles"),
        (&["--iterations", "-3"], "--iterations"),
        (&["--inertia", "NaN"], "--inertia"),
        (&["--stall", "0"], "--stall"),
        (&["--method", "msac", "--confidence", "1"], "--confidence"),
        (&["--method", "ransac"], "--method"),
        (&["--method", "svd", "--particles", "10"], "does not apply"),
    ];
    for (args, needle) in cases {
        check_error(&register(&path, args), &[needle]);
    }
    check_error(&swarmpose(&["register"], None), &["<FILE.csv|->"]);
    check_error(&swarmpose(&[], None), &["register"]);
}

#[test]
fn help_lists_every_default() {
    let out = swarmpose(&["register", "--help"], None);
    assert_eq!(out.status.code(), Some(0));
    let help = String::from_utf8(out.stdout).expect("utf-8 help");
    let options = [
        "--method",
        "--seed",
        "--threshold",
        "--particles",
        "--iterations",
        "--inertia",
        "--acceleration",
        "--stall",
        "--seeded-particles",
        "--confidence",
        "--max-samples",
    ];
    for option in options {
        // The option's entry runs from its name to the next blank line.
        let start = help
            .find(&format!("      {option} <"))
            .unwrap_or_else(|| panic!("{option} not in help:\n{help}"));
        let entry = help[start..].split("\n\n").next().unwrap_or_default();
        let entry = if option == "--method" {
            // Possible values come first, then the default after a blank line.
            &help[start..start + help[start..].find("[default").unwrap_or(0) + 9]
        } else {
            entry
        };
        assert!(
            entry.contains("[default"),
            "{option}: no default in {entry:?}"
        );
    }
    assert!(help.contains("[default: pso]"), "{help}");
}

/// Stereo-noise scenes in millimetres and at tabletop size (90 % wrong matches onto other
/// scene points, no covariances in the file): the automatic threshold follows the unit,
/// and an answer is right or an error, never a wrong pose with exit 0.
#[test]
fn millimetres_and_tabletops_are_registered_or_refused() {
    use swarmpose_core::geometry::rotation_angle_between;
    use swarmpose_sim::StereoSpec;
    let dir = TempDir::new("register-units");
    for (name, spec) in [
        ("street_mm", StereoSpec::street().with_unit(1000.0)),
        ("tabletop_m", StereoSpec::tabletop()),
    ] {
        let (mut right, mut refused) = (0, 0);
        for seed in 0..5u64 {
            let s = spec
                .clone()
                .with_outliers(0.9)
                .scenario(seed)
                .expect("scenario");
            let path = dir.file(
                &format!("{name}_{seed}.csv"),
                &csv(s.data.src(), s.data.dst()),
            );
            let out = register(&path, &[]);
            if !out.status.success() {
                assert_eq!(
                    out.status.code(),
                    Some(1),
                    "{name} {seed}: not a failed run"
                );
                refused += 1;
                continue;
            }
            let v = json_of(&out);
            let q = f64s(&v, "rotation_wxyz");
            let t = f64s(&v, "translation");
            let rotation =
                UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
            let pose = Isometry3::from_parts(Vector3::new(t[0], t[1], t[2]).into(), rotation);
            let r = rotation_angle_between(&pose.rotation, &s.truth.rotation).to_degrees();
            let e = (pose.translation.vector - s.truth.translation.vector).norm();
            // A right consensus fitted without the noise model may miss the 0.2 m bar
            // slightly; a wrong motion is degrees and metres off.
            assert!(
                r < 5.0 && e < 5.0 * s.success_translation,
                "{name} {seed}: {r} deg, {e}"
            );
            right += 1;
        }
        assert!(
            right >= 4,
            "{name}: {right}/5 registered, {refused} refused"
        );
    }
}
