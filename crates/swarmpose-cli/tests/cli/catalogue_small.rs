//! The smaller cases of the second audit (issue 29, item 11): a mirrored point set, a
//! UTF-8 byte-order mark in every reader `register` and `evaluate` use, coordinates so
//! large their spread overflows.

use crate::common::{TempDir, assert_success, check_error, swarmpose};

const HEADER: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z";

/// 10 points in general position, `dst = f(src)`.
fn csv(f: impl Fn([f64; 3]) -> [f64; 3]) -> String {
    let mut text = format!("{HEADER}\n");
    for i in 0..10 {
        let k = f64::from(i);
        let s = [k * 0.7 - 2.0, (k * 1.3).sin() * 3.0, 4.0 + (k * 0.9).cos()];
        let d = f(s);
        text.push_str(&format!(
            "{},{},{},{},{},{}\n",
            s[0], s[1], s[2], d[0], d[1], d[2]
        ));
    }
    text
}

#[test]
fn a_mirror_image_is_refused_by_every_method() {
    let dir = TempDir::new("mirror");
    let mirrored = dir.file("mirror.csv", &csv(|s| [-s[0], -s[1], -s[2]]));
    let flipped = dir.file("flip.csv", &csv(|s| [s[0] + 1.0, s[1], -s[2]]));
    for path in [&mirrored, &flipped] {
        for method in ["pso", "pso-paper", "svd", "msac"] {
            let out = swarmpose(
                &[
                    "register",
                    "--method",
                    method,
                    path.to_str().expect("utf-8"),
                ],
                None,
            );
            check_error(&out, &["mirror image of the source", "not a rigid motion"]);
        }
    }
    // A rotated and shifted set still registers.
    let moved = dir.file("moved.csv", &csv(|s| [-s[1] + 0.5, s[0], s[2] + 1.0]));
    assert_success(&swarmpose(
        &[
            "register",
            "--method",
            "svd",
            moved.to_str().expect("utf-8"),
        ],
        None,
    ));
}

#[test]
fn a_byte_order_mark_is_accepted_by_the_csv_and_trajectory_readers() {
    let dir = TempDir::new("bom");
    let text = csv(|s| [s[0] + 0.5, s[1], s[2]]);
    let with_bom = dir.file("bom.csv", &format!("\u{feff}{text}"));
    assert_success(&swarmpose(
        &[
            "register",
            "--method",
            "svd",
            with_bom.to_str().expect("utf-8"),
        ],
        None,
    ));
    assert_success(&swarmpose(
        &["register", "--method", "svd", "-"],
        Some(&format!("\u{feff}{text}")),
    ));
    let lines: String = (0..6)
        .map(|i| format!("{}.0 {} 0 0 0 0 0 1\n", i, f64::from(i) * 0.5))
        .collect();
    let estimate = dir.file("est.tum", &format!("\u{feff}{lines}"));
    let truth = dir.file("gt.tum", &lines);
    for (e, g) in [(&estimate, &truth), (&truth, &estimate)] {
        let out = swarmpose(
            &[
                "evaluate",
                e.to_str().expect("utf-8"),
                g.to_str().expect("utf-8"),
                "--format",
                "tum",
            ],
            None,
        );
        assert_success(&out);
    }
}

#[test]
fn coordinates_too_large_are_not_called_coincident() {
    let dir = TempDir::new("huge");
    let huge = dir.file(
        "huge.csv",
        &csv(|s| [s[0] * 1e300, s[1] * 1e300, s[2] * 1e300]),
    );
    let out = swarmpose(
        &["register", "--method", "svd", huge.to_str().expect("utf-8")],
        None,
    );
    let line = check_error(&out, &["coordinates are too large"]);
    assert!(!line.contains("coincide"), "{line}");
}
