//! `swarmpose simulate`: a small grid end to end, and bad arguments refused before work.

use crate::common::{TempDir, check_error, swarmpose};

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
    // An --out that cannot be a folder: an output that cannot be written, status 1 as
    // docs/testing.md says for every command (issue 29, cause 11: it was 2).
    let file = dir.file("a-file", "x");
    let inside = file.join("sub").to_string_lossy().to_string();
    let run = swarmpose(&["simulate", "--out", &inside], None);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with("swarmpose: error: cannot write ") && stderr.contains("a-file"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
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

/// Issue 29, cause 10: a grid too large to hold is refused before any work (a huge
/// `--runs` aborted on an allocation, or overflowed the scenario count).
#[test]
fn grids_too_large_are_refused() {
    for runs in ["100000000", "18446744073709551615"] {
        let out = swarmpose(
            &["simulate", "--runs", runs, "--out", "/nonexistent/x"],
            None,
        );
        check_error(
            &out,
            &[&format!(
                "invalid setting: {runs} runs x 4 noise levels x 10 fractions is over the 1000000 scenarios"
            )],
        );
    }
    let out = swarmpose(&["simulate", "--threads", "100000", "--quick"], None);
    check_error(&out, &["threads must be 1 to 1024, got 100000"]);
}

/// Issue 29, cause 10: SIGTERM stops `simulate` after the scenarios being run, keeping
/// the rows done (before, the process ended and wrote nothing).
#[test]
fn sigterm_keeps_the_rows_done() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let dir = TempDir::new("simulate-term");
    let out = dir.0.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args([
            "simulate",
            "--runs",
            "20000",
            "--noise",
            "0.02",
            "--fractions",
            "0.5",
        ])
        .args(["--out", &out.to_string_lossy()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run swarmpose");
    // 20 000 scenarios take minutes: stop it a few seconds in.
    std::thread::sleep(Duration::from_secs(3));
    let asked = Instant::now();
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let run = child.wait_with_output().expect("wait");
    assert!(
        asked.elapsed() < Duration::from_secs(20),
        "{:?}",
        asked.elapsed()
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(143), "{stderr}");
    let done: usize = stderr
        .split("stopped by SIGTERM after ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next()?.parse().ok())
        .unwrap_or_else(|| panic!("{stderr}"));
    assert!(
        stderr.contains(&format!("{done} of 20000 scenarios")),
        "{stderr}"
    );
    assert!(done < 20_000);
    let rows = std::fs::read_to_string(out.join("runs.csv")).expect("runs.csv");
    assert_eq!(rows.lines().count(), 1 + 4 * done);
    let summary = std::fs::read_to_string(out.join("summary.md")).expect("summary.md");
    assert!(summary.starts_with("# Stopped"), "{summary}");
}
