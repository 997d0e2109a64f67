//! The bad-input catalogue of `register`: every case is built here (a valid CSV with one
//! thing broken), run through the binary, and must give exit status 2 and one line that
//! starts with the expected words. Classes: a bad token in every column of plain and
//! covariance CSVs (not a number, not finite), wrong field counts, wrong headers, bad
//! covariances, structural faults, degenerate point sets for every method, bad options.
//! More than 448 cases; the count is asserted.

use std::path::Path;

use crate::common::{TempDir, swarmpose};

const HEADER: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z";
const COV_HEADER: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z,src_cxx,src_cxy,src_cxz,src_cyy,\
src_cyz,src_czz,dst_cxx,dst_cxy,dst_cxz,dst_cyy,dst_cyz,dst_czz";
const METHODS: [&str; 4] = ["pso", "pso-paper", "svd", "msac"];
const NOT_NUMBERS: [&str; 8] = ["abc", "", "1.2.3", "0x1F", "--1", "1e", "one", "1;2"];
const NOT_FINITE: [&str; 7] = ["nan", "NaN", "inf", "-inf", "1e309", "-1e400", "infinity"];

/// A point set in general position, 8 rows: `(src, dst)` per row.
fn rows() -> Vec<[f64; 6]> {
    (0..8)
        .map(|i| {
            let f = f64::from(i);
            let s = [f * 0.7 - 2.0, (f * 1.3).sin() * 3.0, 4.0 + (f * 0.9).cos()];
            [s[0], s[1], s[2], s[0] + 0.5, s[1] - 0.2, s[2] + 1.0]
        })
        .collect()
}

fn fields(row: &[f64; 6], covariance: bool) -> Vec<String> {
    let mut f: Vec<String> = row.iter().map(|v| v.to_string()).collect();
    if covariance {
        for _ in 0..2 {
            f.extend(["0.01", "0", "0", "0.01", "0", "0.04"].map(str::to_owned));
        }
    }
    f
}

/// A CSV of `rows()`, with `edit(row index, fields)` applied to each row's fields.
fn csv_with(covariance: bool, edit: impl Fn(usize, &mut Vec<String>)) -> String {
    let mut text = format!("{}\n", if covariance { COV_HEADER } else { HEADER });
    for (i, r) in rows().iter().enumerate() {
        let mut f = fields(r, covariance);
        edit(i, &mut f);
        text.push_str(&f.join(","));
        text.push('\n');
    }
    text
}

fn column_name(k: usize) -> &'static str {
    const NAMES: [&str; 18] = [
        "src_x", "src_y", "src_z", "dst_x", "dst_y", "dst_z", "src_cxx", "src_cxy", "src_cxz",
        "src_cyy", "src_cyz", "src_czz", "dst_cxx", "dst_cxy", "dst_cxz", "dst_cyy", "dst_cyz",
        "dst_czz",
    ];
    NAMES[k]
}

/// One case: a file's text, extra arguments, and the words the message starts with
/// after `swarmpose: error: PATH: ` (or after `swarmpose: error: ` when `path_first` is
/// false).
struct Case {
    text: String,
    args: Vec<String>,
    start: String,
    path_first: bool,
}

fn case(text: String, start: impl Into<String>) -> Case {
    Case {
        text,
        args: Vec::new(),
        start: start.into(),
        path_first: true,
    }
}

fn all_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    // A bad token in every column of rows 1, 4 and 8 (file lines 2, 5, 9).
    for covariance in [false, true] {
        let columns = if covariance { 18 } else { 6 };
        let rows_hit: &[usize] = if covariance { &[0] } else { &[0, 3, 7] };
        for &r in rows_hit {
            for k in 0..columns {
                for (tokens, what) in [
                    (&NOT_NUMBERS[..], "not a number"),
                    (&NOT_FINITE[..], "not a finite number"),
                ] {
                    for &t in tokens {
                        if t.contains(';') && covariance {
                            continue;
                        }
                        let text = csv_with(covariance, |i, f| {
                            if i == r {
                                f[k] = t.to_owned();
                            }
                        });
                        cases.push(case(
                            text,
                            format!("line {}: column {}: {what}", r + 2, column_name(k)),
                        ));
                    }
                }
            }
        }
    }
    // Wrong field counts.
    for covariance in [false, true] {
        let expected = if covariance { 18 } else { 6 };
        for n in 1..=expected + 6 {
            if n == expected {
                continue;
            }
            let text = csv_with(covariance, |i, f| {
                if i == 2 {
                    f.resize(n, "1".to_owned());
                }
            });
            cases.push(case(
                text,
                format!("line 4: expected {expected} fields, found {n}"),
            ));
        }
    }
    // Wrong headers.
    let body = csv_with(false, |_, _| {});
    let data = body.split_once('\n').map_or("", |x| x.1).to_owned();
    for header in [
        "x1,y1,z1,x2,y2,z2",
        "src_x,src_y,src_z,dst_x,dst_y",
        "src_x,src_y,src_z,dst_x,dst_y,dst_z,extra",
        "dst_x,dst_y,dst_z,src_x,src_y,src_z",
        "SRC_X,SRC_Y,SRC_Z,DST_X,DST_Y,DST_Z",
        "src_x;src_y;src_z;dst_x;dst_y;dst_z",
        "src_x,src_y,src_z,dst_x,dst_y,dst_z,src_cxx",
        "x,y,z",
        "id,src_x,src_y,src_z,dst_x,dst_y,dst_z",
        "src x,src y,src z,dst x,dst y,dst z",
    ] {
        cases.push(case(format!("{header}\n{data}"), "line 1: wrong header"));
    }
    for skip in 0..3 {
        let rows: Vec<&str> = data.lines().skip(skip).collect();
        cases.push(case(rows.join("\n"), "line 1: missing header"));
    }
    // Bad covariances (row 2 = file line 3): negative or zero variance, indefinite.
    for (point, at) in [("source", 6), ("destination", 12)] {
        for upper in [
            ["-0.01", "0", "0", "0.01", "0", "0.04"],
            ["0", "0", "0", "0.01", "0", "0.04"],
            ["0.01", "0.5", "0", "0.01", "0", "0.04"],
            ["0.01", "0", "0", "-1", "0", "0.04"],
            ["0.01", "0", "0", "0.01", "0", "0"],
            ["0.01", "0", "0.9", "0.01", "0", "0.04"],
            ["0.01", "0", "0", "0.01", "0.9", "0.04"],
            ["0", "0", "0", "0", "0", "0"],
        ] {
            let text = csv_with(true, |i, f| {
                if i == 1 {
                    for (j, v) in upper.iter().enumerate() {
                        f[at + j] = (*v).to_owned();
                    }
                }
            });
            cases.push(case(
                text,
                format!("line 3: {point} covariance is not positive definite"),
            ));
        }
    }
    // Structure.
    cases.push(case(String::new(), "empty file"));
    cases.push(case(format!("{HEADER}\n"), "no correspondences"));
    cases.push(case(format!("{HEADER}\n\n\n"), "no correspondences"));
    let mut gap = csv_with(false, |_, _| {});
    gap.insert(HEADER.len() + 1, '\n');
    cases.push(case(gap, "line 2: blank line inside the data"));
    cases.push(case(
        format!("\n{}", csv_with(false, |_, _| {})),
        "line 1: missing header",
    ));
    // Degenerate point sets, for every method.
    let few = |n: usize| {
        let t = csv_with(false, |_, _| {});
        t.lines().take(n + 1).collect::<Vec<_>>().join("\n") + "\n"
    };
    let same = format!("{HEADER}\n{}", "1,2,3,1.5,1.8,4\n".repeat(8));
    let line: String = (0..8)
        .map(|i| {
            let f = f64::from(i);
            format!(
                "{},{},{},{},{},{}\n",
                f,
                2.0 * f,
                3.0 * f,
                f + 0.5,
                2.0 * f,
                3.0 * f + 1.0
            )
        })
        .collect();
    let collinear = format!("{HEADER}\n{line}");
    for method in METHODS {
        for n in 1..=3 {
            let mut c = case(few(n), format!("{method}: too few correspondences: {n}"));
            c.args = vec!["--method".into(), method.into()];
            cases.push(c);
        }
        for (text, what) in [
            (&same, "all points coincide"),
            (&collinear, "all points are collinear"),
        ] {
            let mut c = case(
                text.clone(),
                format!("{method}: degenerate source point set: {what}"),
            );
            c.args = vec!["--method".into(), method.into()];
            cases.push(c);
        }
    }
    // Bad option values (checked before the file is read).
    let good = csv_with(false, |_, _| {});
    for (opt, values) in [
        ("--threshold", &["-0.1", "0", "NaN", "inf", "-inf", "x"][..]),
        // 10^12 particles were allocated at once: the process aborted.
        (
            "--particles",
            &["0", "-1", "x", "1.5", "1000001", "1000000000000"][..],
        ),
        (
            "--seeded-particles",
            &["-1", "1000001", "1000000000000"][..],
        ),
        // 10^18 iterations with --stall none ran for ever (a signal stops between frames).
        (
            "--iterations",
            &["-3", "x", "1e3", "100001", "1000000000000000000"][..],
        ),
        ("--inertia", &["NaN", "inf", "x"][..]),
        ("--stall", &["0", "x", "-2"][..]),
        ("--seed", &["-1", "x", "1.5"][..]),
    ] {
        for v in values {
            let mut c = case(good.clone(), opt);
            c.args = vec![format!("{opt}={v}")];
            c.path_first = false;
            c.start = String::new();
            cases.push(c);
        }
    }
    cases
}

fn run_case(dir: &Path, k: usize, c: &Case) -> Result<(), String> {
    let path = dir.join(format!("case{k}.csv"));
    std::fs::write(&path, &c.text).map_err(|e| e.to_string())?;
    let shown = path.to_str().ok_or("utf-8 path")?;
    let mut args = vec!["register", shown];
    args.extend(c.args.iter().map(String::as_str));
    let out = swarmpose(&args, None);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let expected = if c.path_first {
        format!("swarmpose: error: {shown}: {}", c.start)
    } else {
        format!("swarmpose: error: {}", c.start)
    };
    let ok = out.status.code() == Some(2)
        && out.stdout.is_empty()
        && stderr.lines().count() == 1
        && stderr.starts_with(&expected)
        && !stderr.contains("panicked")
        && !stderr.contains("internal error");
    if ok {
        Ok(())
    } else {
        Err(format!(
            "case {k} (args {:?}): status {:?}, expected a line starting {expected:?}, got {stderr:?}",
            c.args,
            out.status.code()
        ))
    }
}

#[test]
fn every_bad_register_input_gives_exit_2_and_its_message() {
    let cases = all_cases();
    assert!(cases.len() >= 448, "{} cases", cases.len());
    let dir = TempDir::new("catalogue-register");
    let failures: Vec<String> = cases
        .iter()
        .enumerate()
        .filter_map(|(k, c)| run_case(&dir.0, k, c).err())
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
