//! The node's refusals that come before any DDS traffic: a bad domain, a missing or
//! corrupt run configuration, a bad option. Each: one line naming the problem, exit
//! status 2, and no participant created (the process ends at once).
//!
//! Being an integration test, this also makes `cargo test --workspace` build the node's
//! binary with the workspace's features, which the Cyclone DDS pytest
//! (`tests/py`, `SWARMPOSE_BIN_DIR`) then uses without a build of its own (issue 32).

use std::process::{Command, Output};

fn node(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_swarmpose-ros2"));
    cmd.args(args)
        .env_remove("ROS_DOMAIN_ID")
        .env_remove("ROS_LOCALHOST_ONLY")
        .env_remove("ROS_AUTOMATIC_DISCOVERY_RANGE");
    for (k, v) in env {
        cmd.env(k, v);
    }
    match cmd.output() {
        Ok(out) => out,
        Err(e) => panic!("cannot start swarmpose-ros2: {e}"),
    }
}

/// Exit status 2 and exactly one line on standard error, which contains `words`.
fn refused(out: &Output, words: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "status of: {err}");
    assert_eq!(err.lines().count(), 1, "one line expected: {err}");
    assert!(err.contains(words), "{words:?} not in: {err}");
    assert!(out.stdout.is_empty(), "nothing on standard output");
}

/// A temporary folder, removed when dropped (also when a test fails).
fn scratch() -> tempfile::TempDir {
    match tempfile::tempdir() {
        Ok(dir) => dir,
        Err(e) => panic!("cannot create a temporary folder: {e}"),
    }
}

#[test]
fn a_domain_outside_dds_range_is_refused() {
    for bad in ["233", "-1", "abc", "1.5"] {
        let out = node(&[], &[("ROS_DOMAIN_ID", bad)]);
        refused(&out, &format!("ROS_DOMAIN_ID={bad}"));
    }
}

#[test]
fn a_missing_configuration_file_is_refused() {
    let dir = scratch();
    let path = dir.path().join("no-such-config.json");
    let out = node(&["--config", &path.to_string_lossy()], &[]);
    refused(&out, "no-such-config.json");
}

#[test]
fn a_corrupt_configuration_file_is_refused() {
    let dir = scratch();
    let path = dir.path().join("config.json");
    if let Err(e) = std::fs::write(&path, "{\"odometry\": {\"window\": ") {
        panic!("cannot write {}: {e}", path.display());
    }
    let out = node(&["--config", &path.to_string_lossy()], &[]);
    refused(&out, "config.json");
}

#[test]
fn a_thread_count_other_than_one_or_two_is_refused() {
    let out = node(&["--threads", "3"], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "status of: {err}");
    assert!(err.contains("--threads"), "{err}");
}
