//! The correspondence CSV format.
//!
//! ```text
//! src_x,src_y,src_z,dst_x,dst_y,dst_z
//! 1.0,2.0,10.0,1.1,2.0,10.3
//! ...
//! ```
//!
//! - The first line is the header [`HEADER`], exactly; whitespace around it and around
//!   each of its names is allowed.
//! - Then one correspondence per line: six decimal numbers in metres, source point
//!   then destination point, with `dst = R src + t`. Whitespace around a field and CRLF
//!   line ends are allowed; quoting, comments and other separators are not.
//! - Blank lines are allowed at the end of the file only.
//! - Every value must be finite (no NaN, no infinity).
//!
//! The reader does not check the number of rows beyond "at least one": estimators report
//! too few correspondences themselves.

use std::fmt;
use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Read, Write};
use std::path::Path;

use nalgebra::Point3;
use swarmpose_core::{Correspondences, PoseError};
use thiserror::Error;

/// The header line, exactly as written and as expected (around whitespace aside).
pub const HEADER: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z";

/// The column names, in file order.
pub const COLUMNS: [&str; 6] = ["src_x", "src_y", "src_z", "dst_x", "dst_y", "dst_z"];

/// The name used in messages for data read from standard input.
pub const STDIN_NAME: &str = "<stdin>";

/// Longest excerpt of offending text quoted in a message, in characters.
const EXCERPT_CHARS: usize = 80;

/// What is wrong with a correspondence CSV (see [`CsvError`] for where).
#[derive(Debug, Error)]
pub enum CsvErrorKind {
    /// The input could not be opened or read.
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    /// The output could not be created or written.
    #[error("cannot write: {0}")]
    Write(std::io::Error),
    /// No header at all: the input is empty or blank.
    #[error("empty file: expected the header \"{}\"", HEADER)]
    Empty,
    /// The first line is not the header but a data row or a blank line.
    #[error("missing header: expected \"{}\", found {found}", HEADER)]
    MissingHeader {
        /// What was found instead: `a data row "..."` or `a blank line`.
        found: String,
    },
    /// The first line is a header with the wrong column names.
    #[error("wrong header: expected \"{}\", found {found:?}", HEADER)]
    WrongHeader {
        /// The first line as found (trimmed, possibly shortened).
        found: String,
    },
    /// A data row without exactly six fields.
    #[error("expected 6 fields, found {found}")]
    FieldCount {
        /// Number of comma-separated fields on the row.
        found: usize,
    },
    /// A field that does not parse as a decimal number.
    #[error("column {column}: not a number: {value:?}")]
    NotANumber {
        /// The column name, e.g. `dst_y`.
        column: &'static str,
        /// The field as found (trimmed, possibly shortened).
        value: String,
    },
    /// A field that parses, but to NaN or an infinity.
    #[error("column {column}: not a finite number: {value:?}")]
    NonFinite {
        /// The column name, e.g. `dst_y`.
        column: &'static str,
        /// The field as found (trimmed).
        value: String,
    },
    /// A blank line followed by more data.
    #[error("blank line inside the data (blank lines are allowed only at the end)")]
    BlankLine,
    /// A header and no data row.
    #[error("no correspondences: the file has a header but no data rows")]
    NoRows,
    /// A line that is not valid UTF-8 text.
    #[error("not valid UTF-8 text")]
    NotUtf8,
    /// The rows were read but do not form valid correspondences (not expected after
    /// the checks above; kept so that no case is silently dropped).
    #[error("{0}")]
    Pose(PoseError),
}

/// A failure to read or write a correspondence CSV: which input, which line, and what.
///
/// Displays as one line, `NAME: line N: PROBLEM` or `NAME: PROBLEM`, for example
/// `data.csv: line 7: column dst_y: not a number: "abc"`.
#[derive(Debug)]
pub struct CsvError {
    /// The file path as given, or [`STDIN_NAME`].
    pub input: String,
    /// 1-based line number the problem is on, when it is on one line.
    pub line: Option<usize>,
    /// What is wrong.
    pub kind: CsvErrorKind,
}

impl CsvError {
    fn new(input: &str, line: Option<usize>, kind: CsvErrorKind) -> Self {
        Self {
            input: input.to_owned(),
            line,
            kind,
        }
    }
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}: line {line}: {}", self.input, self.kind),
            None => write!(f, "{}: {}", self.input, self.kind),
        }
    }
}

impl std::error::Error for CsvError {}

/// `text` cut to [`EXCERPT_CHARS`] characters, with an ellipsis when cut.
fn excerpt(text: &str) -> String {
    match text.char_indices().nth(EXCERPT_CHARS) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text.to_owned(),
    }
}

/// Reads a correspondence CSV file; messages name it by `path` as given.
///
/// # Errors
/// [`CsvError`] naming the file, the line and the problem.
pub fn read_path(path: impl AsRef<Path>) -> Result<Correspondences, CsvError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let file = File::open(path).map_err(|e| CsvError::new(&name, None, CsvErrorKind::Read(e)))?;
    read_from(file, &name)
}

/// Reads a correspondence CSV from any reader (for example standard input, with
/// `name` = [`STDIN_NAME`]); messages name it by `name`.
///
/// # Errors
/// [`CsvError`] naming the input, the line and the problem.
pub fn read_from<R: Read>(reader: R, name: &str) -> Result<Correspondences, CsvError> {
    let mut reader = BufReader::new(reader);
    let err = |line: Option<usize>, kind| CsvError::new(name, line, kind);
    let mut buf = Vec::new();
    let mut line_no = 0usize;
    // Line 1 when it is blank: an error if anything but blank lines follows.
    let mut blank_first = false;
    let mut header_seen = false;
    // First blank line after the header: an error if a data row follows.
    let mut blank_at: Option<usize> = None;
    let (mut src, mut dst) = (Vec::new(), Vec::new());
    loop {
        buf.clear();
        let read = reader
            .read_until(b'\n', &mut buf)
            // Failing before the first line is a failure of the input, not of a line.
            .map_err(|e| err((line_no > 0).then_some(line_no + 1), CsvErrorKind::Read(e)))?;
        if read == 0 {
            break;
        }
        line_no += 1;
        let text =
            std::str::from_utf8(&buf).map_err(|_| err(Some(line_no), CsvErrorKind::NotUtf8))?;
        let text = text.trim();
        if !header_seen {
            if text.is_empty() {
                blank_first |= line_no == 1;
                continue;
            }
            if blank_first {
                let found = "a blank line".to_owned();
                return Err(err(Some(1), CsvErrorKind::MissingHeader { found }));
            }
            check_header(text).map_err(|kind| err(Some(line_no), kind))?;
            header_seen = true;
            continue;
        }
        if text.is_empty() {
            blank_at.get_or_insert(line_no);
            continue;
        }
        if let Some(blank) = blank_at {
            return Err(err(Some(blank), CsvErrorKind::BlankLine));
        }
        let [sx, sy, sz, dx, dy, dz] = parse_row(text).map_err(|kind| err(Some(line_no), kind))?;
        src.push(Point3::new(sx, sy, sz));
        dst.push(Point3::new(dx, dy, dz));
    }
    if !header_seen {
        return Err(err(None, CsvErrorKind::Empty));
    }
    if src.is_empty() {
        return Err(err(None, CsvErrorKind::NoRows));
    }
    Correspondences::new(src, dst).map_err(|e| err(None, CsvErrorKind::Pose(e)))
}

/// Checks a trimmed, non-empty first line against [`HEADER`].
fn check_header(text: &str) -> Result<(), CsvErrorKind> {
    let names: Vec<&str> = text.split(',').map(str::trim).collect();
    if names == COLUMNS {
        return Ok(());
    }
    if names.iter().all(|f| f.parse::<f64>().is_ok()) {
        Err(CsvErrorKind::MissingHeader {
            found: format!("a data row {:?}", excerpt(text)),
        })
    } else {
        Err(CsvErrorKind::WrongHeader {
            found: excerpt(text),
        })
    }
}

/// Parses a trimmed, non-empty data row into six finite numbers.
fn parse_row(text: &str) -> Result<[f64; 6], CsvErrorKind> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    if fields.len() != COLUMNS.len() {
        return Err(CsvErrorKind::FieldCount {
            found: fields.len(),
        });
    }
    let mut row = [0.0; 6];
    for ((value, field), column) in row.iter_mut().zip(&fields).zip(COLUMNS) {
        let v: f64 = field.parse().map_err(|_| CsvErrorKind::NotANumber {
            column,
            value: excerpt(field),
        })?;
        if !v.is_finite() {
            return Err(CsvErrorKind::NonFinite {
                column,
                value: excerpt(field),
            });
        }
        *value = v;
    }
    Ok(row)
}

/// Writes `data` as a correspondence CSV file (created or truncated at `path`).
///
/// Values are written in the shortest form that reads back to the same `f64`, so a
/// write followed by a read gives the same correspondences bit for bit.
///
/// # Errors
/// [`CsvError`] with [`CsvErrorKind::Write`] naming the file.
pub fn write_path(path: impl AsRef<Path>, data: &Correspondences) -> Result<(), CsvError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let file =
        File::create(path).map_err(|e| CsvError::new(&name, None, CsvErrorKind::Write(e)))?;
    write_to(BufWriter::new(file), data, &name)
}

/// Writes `data` as a correspondence CSV to any writer (flushed at the end); messages
/// name it by `name`.
///
/// # Errors
/// [`CsvError`] with [`CsvErrorKind::Write`].
pub fn write_to<W: Write>(
    mut writer: W,
    data: &Correspondences,
    name: &str,
) -> Result<(), CsvError> {
    let mut write = || -> std::io::Result<()> {
        writeln!(writer, "{HEADER}")?;
        for (s, d) in data.src().iter().zip(data.dst()) {
            writeln!(writer, "{},{},{},{},{},{}", s.x, s.y, s.z, d.x, d.y, d.z)?;
        }
        writer.flush()
    };
    write().map_err(|e| CsvError::new(name, None, CsvErrorKind::Write(e)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::test_util::TempDir;

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
            format!("test.csv: line 1: wrong header: expected \"{HEADER}\", found \"x,y,z,u,v,w\"")
        );
        // Case and order matter; a BOM is not tolerated either.
        for h in [
            "SRC_X,src_y,src_z,dst_x,dst_y,dst_z",
            "dst_x,dst_y,dst_z,src_x,src_y,src_z",
            "src_x,src_y,src_z,dst_x,dst_y",
            "\u{feff}src_x,src_y,src_z,dst_x,dst_y,dst_z",
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
        assert!(matches!(e.kind, CsvErrorKind::FieldCount { found: 5 }));
        assert_eq!(
            e.to_string(),
            "test.csv: line 4: expected 6 fields, found 5"
        );
        let e = error_of(&format!("{GOOD}1,2,3,4,5,6,\n"));
        assert!(matches!(e.kind, CsvErrorKind::FieldCount { found: 7 }));
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
}
