//! Tests of the correspondence CSV reader and writer.

use super::*;
use swarmpose_testdata::TempDir;

fn read_str(text: &str) -> Result<Correspondences, CsvError> {
    read_from(text.as_bytes(), "test.csv")
}

/// The error of reading `text`, checked to name the input.
fn error_of(text: &str) -> CsvError {
    let e = read_str(text).expect_err("should fail");
    assert_eq!(e.input, "test.csv");
    assert!(e.to_string().starts_with("test.csv: "), "{e}");
    assert!(!e.to_string().contains('\n'), "{e}");
    e
}

const GOOD: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z\n\
                    1,2,3,4,5,6\n\
                    -1.5,0,2e1,0.25,-0.5,7\n";

#[test]
fn reads_good_file() {
    let c = read_str(GOOD).unwrap();
    assert_eq!(c.len(), 2);
    assert_eq!(c.src()[1], Point3::new(-1.5, 0.0, 20.0));
    assert_eq!(c.dst()[0], Point3::new(4.0, 5.0, 6.0));
}

#[test]
fn tolerates_whitespace_crlf_and_trailing_blank_lines() {
    let text = "  src_x , src_y,src_z,dst_x,dst_y,dst_z \r\n 1 , 2,3,4,5,6\r\n\r\n  \n\n";
    let c = read_str(text).unwrap();
    assert_eq!(c.len(), 1);
    assert_eq!(c.src()[0], Point3::new(1.0, 2.0, 3.0));
    // No final newline.
    let c = read_str("src_x,src_y,src_z,dst_x,dst_y,dst_z\n1,2,3,4,5,6").unwrap();
    assert_eq!(c.len(), 1);
}

#[test]
fn empty_file() {
    for text in ["", "\n", "  \r\n\n"] {
        let e = error_of(text);
        assert!(matches!(e.kind, CsvErrorKind::Empty));
        assert_eq!(e.line, None);
        assert!(e.to_string().contains("empty file"), "{e}");
        assert!(e.to_string().contains(HEADER), "{e}");
    }
}

#[test]
fn missing_header() {
    let e = error_of("1,2,3,4,5,6\n7,8,9,10,11,12\n");
    assert!(matches!(e.kind, CsvErrorKind::MissingHeader { .. }));
    assert_eq!(e.line, Some(1));
    let msg = e.to_string();
    assert!(msg.starts_with("test.csv: line 1: missing header"), "{msg}");
    assert!(msg.contains(HEADER) && msg.contains("1,2,3,4,5,6"), "{msg}");
    // A blank first line before the header.
    let e = error_of("\nsrc_x,src_y,src_z,dst_x,dst_y,dst_z\n1,2,3,4,5,6\n");
    assert_eq!(e.line, Some(1));
    assert!(e.to_string().contains("found a blank line"), "{e}");
}

#[test]
fn wrong_header() {
    let e = error_of("x,y,z,u,v,w\n1,2,3,4,5,6\n");
    assert!(matches!(e.kind, CsvErrorKind::WrongHeader { .. }));
    assert_eq!(e.line, Some(1));
    let msg = e.to_string();
    assert_eq!(
        msg,
        format!(
            "test.csv: line 1: wrong header: expected \"{HEADER}\" (optionally followed by the 12 covariance columns src_cxx,...,dst_czz), found \"x,y,z,u,v,w\""
        )
    );
    // Case and order matter.
    for h in [
        "SRC_X,src_y,src_z,dst_x,dst_y,dst_z",
        "dst_x,dst_y,dst_z,src_x,src_y,src_z",
        "src_x,src_y,src_z,dst_x,dst_y",
        "src_x,\u{feff}src_y,src_z,dst_x,dst_y,dst_z",
        "src_x;src_y;src_z;dst_x;dst_y;dst_z",
    ] {
        let e = error_of(&format!("{h}\n1,2,3,4,5,6\n"));
        assert!(matches!(e.kind, CsvErrorKind::WrongHeader { .. }), "{h}");
    }
}

#[test]
fn header_only() {
    let e = error_of("src_x,src_y,src_z,dst_x,dst_y,dst_z\n\n");
    assert!(matches!(e.kind, CsvErrorKind::NoRows));
    assert!(e.to_string().contains("no data rows"), "{e}");
}

#[test]
fn wrong_field_count() {
    let e = error_of(&format!("{GOOD}1,2,3,4,5\n"));
    assert!(matches!(
        e.kind,
        CsvErrorKind::FieldCount {
            expected: 6,
            found: 5
        }
    ));
    assert_eq!(
        e.to_string(),
        "test.csv: line 4: expected 6 fields, found 5"
    );
    let e = error_of(&format!("{GOOD}1,2,3,4,5,6,\n"));
    assert!(matches!(
        e.kind,
        CsvErrorKind::FieldCount {
            expected: 6,
            found: 7
        }
    ));
}

#[test]
fn non_numeric_field() {
    let e = error_of(&format!("{GOOD}1,2,3,4,abc,6\n"));
    assert_eq!(
        e.to_string(),
        "test.csv: line 4: column dst_y: not a number: \"abc\""
    );
    let e = error_of(&format!("{GOOD}1,,3,4,5,6\n"));
    assert!(matches!(
        e.kind,
        CsvErrorKind::NotANumber {
            column: "src_y",
            ..
        }
    ));
    // Quoting is not part of the format.
    let e = error_of(&format!("{GOOD}\"1\",2,3,4,5,6\n"));
    assert!(matches!(
        e.kind,
        CsvErrorKind::NotANumber {
            column: "src_x",
            ..
        }
    ));
}

#[test]
fn nan_and_infinity() {
    let e = error_of(&format!("{GOOD}1,2,NaN,4,5,6\n"));
    assert_eq!(
        e.to_string(),
        "test.csv: line 4: column src_z: not a finite number: \"NaN\""
    );
    for (v, col) in [("inf", "dst_x"), ("-infinity", "dst_x"), ("1e999", "dst_x")] {
        let e = error_of(&format!("{GOOD}1,2,3,{v},5,6\n"));
        match e.kind {
            CsvErrorKind::NonFinite { column, .. } => assert_eq!(column, col),
            other => panic!("{v}: {other:?}"),
        }
        assert_eq!(e.line, Some(4));
    }
}

#[test]
fn blank_line_inside_data() {
    let e = error_of("src_x,src_y,src_z,dst_x,dst_y,dst_z\n1,2,3,4,5,6\n\n1,2,3,4,5,6\n");
    assert!(matches!(e.kind, CsvErrorKind::BlankLine));
    assert_eq!(e.line, Some(3));
}

#[test]
fn invalid_utf8() {
    let bytes = b"src_x,src_y,src_z,dst_x,dst_y,dst_z\n1,2,3,\xff,5,6\n";
    let e = read_from(&bytes[..], "bin.csv").unwrap_err();
    assert!(matches!(e.kind, CsvErrorKind::NotUtf8));
    assert_eq!(e.to_string(), "bin.csv: line 2: not valid UTF-8 text");
}

#[test]
fn long_text_is_shortened() {
    let long = "x".repeat(500);
    let e = error_of(&format!("{long}\n"));
    let msg = e.to_string();
    assert!(msg.len() < 250 && msg.contains("..."), "{msg}");
}

#[test]
fn unreadable_file() {
    let dir = TempDir::new("missing");
    let path = dir.path("does-not-exist.csv");
    let e = read_path(&path).unwrap_err();
    assert!(matches!(e.kind, CsvErrorKind::Read(_)));
    assert_eq!(e.line, None);
    let msg = e.to_string();
    assert!(
        msg.starts_with(&format!("{}: cannot read: ", path.display())),
        "{msg}"
    );
    // A directory is not a readable file either (it opens, reading fails).
    let e = read_path(&dir.0).unwrap_err();
    assert!(matches!(e.kind, CsvErrorKind::Read(_)), "{e}");
    assert_eq!(e.line, None);
}

#[test]
fn io_error_mid_read_names_the_line() {
    struct Failing(usize);
    impl Read for Failing {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.0 == 0 {
                return Err(std::io::Error::other("device gone"));
            }
            let text = b"src_x,src_y,src_z,dst_x,dst_y,dst_z\n";
            buf[..text.len()].copy_from_slice(text);
            self.0 -= 1;
            Ok(text.len())
        }
    }
    let e = read_from(Failing(1), STDIN_NAME).unwrap_err();
    assert_eq!(e.to_string(), "<stdin>: line 2: cannot read: device gone");
}

#[test]
fn write_read_round_trip() {
    let src = vec![
        Point3::new(0.1, -2.0 / 3.0, 12.345_678_901_234),
        Point3::new(1e-9, 5e7, -0.0),
        Point3::new(f64::MIN_POSITIVE, 1.0, 2.0),
        Point3::new(-6.0, 6.0, 25.0),
    ];
    let dst = src
        .iter()
        .map(|p| Point3::new(p.x + 0.3, p.y * 1.1, std::f64::consts::PI))
        .collect();
    let data = Correspondences::new(src, dst).unwrap();
    let dir = TempDir::new("roundtrip");
    let path = dir.path("points.csv");
    write_path(&path, &data).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with(&format!("{HEADER}\n")));
    assert_eq!(read_path(&path).unwrap(), data);
}

#[test]
fn unwritable_file() {
    let dir = TempDir::new("unwritable");
    let path = dir.path("no-such-dir").join("out.csv");
    let data = read_str(GOOD).unwrap();
    let e = write_path(&path, &data).unwrap_err();
    assert!(matches!(e.kind, CsvErrorKind::Write(_)));
    assert!(e.to_string().contains("cannot write"), "{e}");
}

const WITH_COV: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z,src_cxx,src_cxy,src_cxz,src_cyy,src_cyz,src_czz,dst_cxx,dst_cxy,dst_cxz,dst_cyy,dst_cyz,dst_czz\n\
                        1,2,3,4,5,6,1e-4,0,0,1e-4,0,0.04,1e-4,1e-5,0,1e-4,0,0.09\n\
                        -1,0,2,0.5,1,7,1e-4,0,0,1e-4,0,1e-4,2e-4,0,0,2e-4,0,2e-4\n";

#[test]
fn reads_covariances_and_writes_them_back() {
    let c = read_str(WITH_COV).unwrap();
    let (sc, dc) = c.noise_covariance().expect("covariances read");
    assert_eq!(sc[0][(2, 2)], 0.04);
    assert_eq!(dc[0][(1, 0)], 1e-5);
    assert_eq!(dc[0][(0, 1)], 1e-5);
    assert!(c.noise_sigma().is_some());
    let dir = TempDir::new("csv-cov");
    let path = dir.0.join("cov.csv");
    write_path(&path, &c).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with(HEADER_WITH_COVARIANCE), "{text}");
    assert_eq!(read_path(&path).unwrap(), c);
}

#[test]
fn bad_covariance_rows_name_the_line() {
    let bad = WITH_COV.replace("1e-4,0,0.04,", "1e-4,0,-0.04,");
    let e = error_of(&bad);
    assert_eq!(e.line, Some(2));
    assert!(
        e.to_string()
            .ends_with("line 2: source covariance is not positive definite"),
        "{e}"
    );
    let e = error_of(&WITH_COV.replace(",2e-4\n", "\n"));
    assert!(
        matches!(
            e.kind,
            CsvErrorKind::FieldCount {
                expected: 18,
                found: 17
            }
        ),
        "{e}"
    );
    let e = error_of(&WITH_COV.replace("dst_czz", "dst_zz"));
    assert!(e.to_string().contains("wrong header"), "{e}");
    let e = error_of(&WITH_COV.replace("0.09", "nan"));
    assert!(
        e.to_string()
            .contains("column dst_czz: not a finite number"),
        "{e}"
    );
}
