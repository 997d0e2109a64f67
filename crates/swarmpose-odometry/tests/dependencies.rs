//! The engine reads and writes no file: its dependency tree holds no dataset reader,
//! evaluation, plotting, image codec, serialisation or run crate (issue 31). Embedding the
//! engine (a bag reader, a ROS 2 node, a batch runner) pulls in only the maths and the
//! vision front end.

use std::process::Command;

/// Crates that belong around the engine, never in it.
const FORBIDDEN: &[&str] = &[
    "swarmpose-datasets",
    "swarmpose-eval",
    "swarmpose-runs",
    "swarmpose-data",
    "swarmpose-sim",
    "plotters",
    "image",
    "png",
    "serde",
    "serde_json",
    "csv",
    "clap",
];

#[test]
fn the_engine_depends_on_no_io_crate() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "--locked",
            "-p",
            "swarmpose-odometry",
            "-e",
            "normal",
            "--prefix",
            "none",
            "--format",
            "{p}",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tree = String::from_utf8_lossy(&out.stdout);
    let names: Vec<&str> = tree
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(names.contains(&"nalgebra"), "unexpected tree:\n{tree}");
    let found: Vec<&&str> = FORBIDDEN.iter().filter(|f| names.contains(f)).collect();
    assert!(found.is_empty(), "the engine depends on {found:?}:\n{tree}");
}
