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
//! - Optionally, the noise covariance of both points (m², each in its own frame): the
//!   header [`HEADER_WITH_COVARIANCE`] adds the upper triangles of both 3 × 3 matrices,
//!   `src_cxx,src_cxy,src_cxz,src_cyy,src_cyz,src_czz` then the same for `dst`, so every
//!   row has 18 numbers. Each matrix must be symmetric positive definite; estimators then
//!   test and fit Mahalanobis residuals
//!   ([`swarmpose_core::Correspondences::with_noise_covariance`]). Stereo front ends
//!   write them (`swarmpose correspondences`).
//! - Blank lines are allowed at the end of the file only.
//! - Every value must be finite (no NaN, no infinity).
//! - A UTF-8 byte-order mark at the start is allowed (as by every reader of swarmpose).
//!
//! The reader does not check the number of rows beyond "at least one": estimators report
//! too few correspondences themselves.

use std::fmt;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;

use nalgebra::{Matrix3, Point3};
use swarmpose_core::geometry::check_covariance;
use swarmpose_core::{Correspondences, PoseError};
use thiserror::Error;

/// The header line, exactly as written and as expected (around whitespace aside).
pub const HEADER: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z";

/// The header with the covariance columns ([`COVARIANCE_COLUMNS`] after [`COLUMNS`]).
pub const HEADER_WITH_COVARIANCE: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z,\
src_cxx,src_cxy,src_cxz,src_cyy,src_cyz,src_czz,dst_cxx,dst_cxy,dst_cxz,dst_cyy,dst_cyz,dst_czz";

/// The column names, in file order.
pub const COLUMNS: [&str; 6] = ["src_x", "src_y", "src_z", "dst_x", "dst_y", "dst_z"];

/// The optional covariance columns (m²), upper triangles of the source then destination
/// point's covariance.
pub const COVARIANCE_COLUMNS: [&str; 12] = [
    "src_cxx", "src_cxy", "src_cxz", "src_cyy", "src_cyz", "src_czz", "dst_cxx", "dst_cxy",
    "dst_cxz", "dst_cyy", "dst_cyz", "dst_czz",
];

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
    #[error(
        "wrong header: expected \"{}\" (optionally followed by the 12 covariance columns \
         src_cxx,...,dst_czz), found {found:?}",
        HEADER
    )]
    WrongHeader {
        /// The first line as found (trimmed, possibly shortened).
        found: String,
    },
    /// A data row without as many fields as the header has columns.
    #[error("expected {expected} fields, found {found}")]
    FieldCount {
        /// Number of columns of the header (6, or 18 with covariances).
        expected: usize,
        /// Number of comma-separated fields on the row.
        found: usize,
    },
    /// A covariance that is not symmetric positive definite.
    #[error("{point} covariance {why}")]
    BadCovariance {
        /// `source` or `destination`.
        point: &'static str,
        /// What is wrong, e.g. `is not positive definite`.
        why: &'static str,
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
    let (mut src_cov, mut dst_cov) = (Vec::new(), Vec::new());
    let mut with_covariance = false;
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
        // A UTF-8 byte-order mark before the header is accepted, as by every reader.
        let text = if line_no == 1 {
            text.strip_prefix('\u{feff}').unwrap_or(text)
        } else {
            text
        };
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
            with_covariance = check_header(text).map_err(|kind| err(Some(line_no), kind))?;
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
        let row = parse_row(text, with_covariance).map_err(|kind| err(Some(line_no), kind))?;
        src.push(Point3::new(row[0], row[1], row[2]));
        dst.push(Point3::new(row[3], row[4], row[5]));
        if with_covariance {
            for (point, at, out) in [
                ("source", 6, &mut src_cov),
                ("destination", 12, &mut dst_cov),
            ] {
                let c = symmetric(&row[at..at + 6]);
                check_covariance(&c).map_err(|why| {
                    err(Some(line_no), CsvErrorKind::BadCovariance { point, why })
                })?;
                out.push(c);
            }
        }
    }
    if !header_seen {
        return Err(err(None, CsvErrorKind::Empty));
    }
    if src.is_empty() {
        return Err(err(None, CsvErrorKind::NoRows));
    }
    let data = Correspondences::new(src, dst).map_err(|e| err(None, CsvErrorKind::Pose(e)))?;
    if with_covariance {
        data.with_noise_covariance(src_cov, dst_cov)
            .map_err(|e| err(None, CsvErrorKind::Pose(e)))
    } else {
        Ok(data)
    }
}

/// The symmetric matrix of an upper triangle `xx, xy, xz, yy, yz, zz`.
fn symmetric(u: &[f64]) -> Matrix3<f64> {
    Matrix3::new(u[0], u[1], u[2], u[1], u[3], u[4], u[2], u[4], u[5])
}

/// Checks a trimmed, non-empty first line against [`HEADER`] (`Ok(false)`) and
/// [`HEADER_WITH_COVARIANCE`] (`Ok(true)`).
fn check_header(text: &str) -> Result<bool, CsvErrorKind> {
    let names: Vec<&str> = text.split(',').map(str::trim).collect();
    if names == COLUMNS {
        return Ok(false);
    }
    if names.len() == COLUMNS.len() + COVARIANCE_COLUMNS.len()
        && names[..6] == COLUMNS
        && names[6..] == COVARIANCE_COLUMNS
    {
        return Ok(true);
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

/// Parses a trimmed, non-empty data row into 6 finite numbers, or 18 with covariances
/// (the rest of the array is zero).
fn parse_row(text: &str, with_covariance: bool) -> Result<[f64; 18], CsvErrorKind> {
    let fields: Vec<&str> = text.split(',').map(str::trim).collect();
    let expected = if with_covariance { 18 } else { 6 };
    if fields.len() != expected {
        return Err(CsvErrorKind::FieldCount {
            expected,
            found: fields.len(),
        });
    }
    let mut row = [0.0; 18];
    let columns = COLUMNS.iter().chain(COVARIANCE_COLUMNS.iter()).copied();
    for ((value, field), column) in row.iter_mut().zip(&fields).zip(columns) {
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

/// Writes `data` as a correspondence CSV file at `path` ([`crate::output::write_file`]:
/// whole, never over a device, a FIFO or a folder), with the covariance columns when
/// `data` carries covariances.
///
/// Values are written in the shortest form that reads back to the same `f64`, so a
/// write followed by a read gives the same correspondences bit for bit.
///
/// # Errors
/// [`CsvError`] with [`CsvErrorKind::Write`] naming the file.
pub fn write_path(path: impl AsRef<Path>, data: &Correspondences) -> Result<(), CsvError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let mut bytes = Vec::new();
    write_to(&mut bytes, data, &name)?;
    crate::output::write_file(path, &bytes)
        .map_err(|e| CsvError::new(&name, None, CsvErrorKind::Write(e)))
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
    let covariance = data.noise_covariance();
    let mut write = || -> std::io::Result<()> {
        let header = if covariance.is_some() {
            HEADER_WITH_COVARIANCE
        } else {
            HEADER
        };
        writeln!(writer, "{header}")?;
        for (i, (s, d)) in data.src().iter().zip(data.dst()).enumerate() {
            write!(writer, "{},{},{},{},{},{}", s.x, s.y, s.z, d.x, d.y, d.z)?;
            if let Some((sc, dc)) = covariance {
                for c in [&sc[i], &dc[i]] {
                    let (xx, xy, xz) = (c[(0, 0)], c[(0, 1)], c[(0, 2)]);
                    let (yy, yz, zz) = (c[(1, 1)], c[(1, 2)], c[(2, 2)]);
                    write!(writer, ",{xx},{xy},{xz},{yy},{yz},{zz}")?;
                }
            }
            writeln!(writer)?;
        }
        writer.flush()
    };
    write().map_err(|e| CsvError::new(name, None, CsvErrorKind::Write(e)))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;
