//! `swarmpose simulate`: a small grid end to end, and bad arguments refused before work.

mod common;

use common::{TempDir, check_error, swarmpose};

#[test]
fn writes_the_tables_and_figures() {
    let dir = TempDir::new("simulate");
    let out = dir.0.join("out");
    let out_s = out.to_string_lossy().to_string();
    let run = swarmpose(
        &[
            "simulate",
            "--out",
            &out_s,
            "--runs",
            "3",
            "--noise",
            "0,0.02",
            "--fractions",
            "0,0.5",
        ],
        None,
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("pso-paper") && stdout.contains("msac"),
        "{stdout}"
    );
    for f in [
        "runs.csv",
        "summary.md",
        "position_error.png",
        "position_error.svg",
        "processing_time.png",
        "rotation_error.svg",
        "success_rate.png",
    ] {
        let meta = std::fs::metadata(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(meta.len() > 100, "{f} is nearly empty");
    }
    // 2 noise levels x 2 fractions x 3 runs x 4 estimators, plus the header.
    let rows = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv");
    assert_eq!(rows.lines().count(), 1 + 2 * 2 * 3 * 4);
}

#[test]
fn bad_arguments_fail_before_any_work() {
    let dir = TempDir::new("simulate-bad");
    let out = dir.0.join("never");
    let out_s = out.to_string_lossy().to_string();
    check_error(
        &swarmpose(&["simulate", "--out", &out_s, "--noise", "-0.1"], None),
        &["noise"],
    );
    check_error(
        &swarmpose(&["simulate", "--out", &out_s, "--fractions", "1.0"], None),
        &["fraction"],
    );
    check_error(
        &swarmpose(&["simulate", "--out", &out_s, "--runs", "0"], None),
        &["runs"],
    );
    assert!(!out.exists(), "nothing is written for bad settings");
    let file = dir.file("a-file", "x");
    let inside = file.join("sub").to_string_lossy().to_string();
    check_error(
        &swarmpose(&["simulate", "--out", &inside], None),
        &["a-file"],
    );
}

#[test]
fn demo_help_names_both_jobs() {
    // The demo itself is the README's first command (run by hand: it writes out/); here
    // only its wiring is checked, cheaply.
    let out = swarmpose(&["demo", "--help"], None);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("simulate") && text.contains("odometry"),
        "{text}"
    );
}

#[test]
fn quick_keeps_explicit_runs_and_fractions() {
    let dir = TempDir::new("simulate-quick");
    let out = dir.0.join("out");
    let out_s = out.to_string_lossy().to_string();
    let run = swarmpose(
        &[
            "simulate",
            "--quick",
            "--out",
            &out_s,
            "--runs",
            "2",
            "--noise",
            "0.05",
            "--fractions",
            "0,0.4",
            "--threads",
            "1",
        ],
        None,
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // 1 noise level x 2 fractions x 2 runs x 4 estimators, plus the header.
    let rows = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv");
    assert_eq!(rows.lines().count(), 1 + 2 * 2 * 4);
    assert!(
        rows.lines()
            .skip(1)
            .all(|l| l.starts_with("0.05,0,") || l.starts_with("0.05,0.4,"))
    );
}

#[test]
fn help_shows_the_defaults() {
    let run = swarmpose(&["simulate", "--help"], None);
    assert_eq!(run.status.code(), Some(0));
    let help = String::from_utf8_lossy(&run.stdout);
    for needle in [
        "[default: out/simulate]",
        "[default: 50, or 10 with --quick]",
        "with --quick]",
        "[default: random]",
        "[default: 1000]",
        "[default: one per core]",
    ] {
        assert!(help.contains(needle), "{needle} not in help: {help}");
    }
}
