//! Small text-parsing helpers shared by the loaders.

use std::path::Path;

use crate::error::DatasetError;

/// Reads a whole text file, without a leading UTF-8 byte-order mark ([`strip_bom`]).
pub(crate) fn read_text(path: &Path, what: &'static str) -> Result<String, DatasetError> {
    if !path.exists() {
        return Err(DatasetError::Missing {
            path: path.to_owned(),
            what,
        });
    }
    std::fs::read_to_string(path)
        .map(|text| strip_bom(&text).to_owned())
        .map_err(|source| DatasetError::Io {
            path: path.to_owned(),
            source,
        })
}

/// A parse error at `line` (1-based) of `path`.
pub(crate) fn parse_error(path: &Path, line: usize, message: impl Into<String>) -> DatasetError {
    DatasetError::Parse {
        path: path.to_owned(),
        line,
        message: message.into(),
    }
}

/// The rows `read` from the optional file `path` (`None` when it is absent), one per
/// frame: `frames` of them, else an error saying how many `rows` (a plural noun) there are.
pub(crate) fn rows_per_frame<T>(
    path: &Path,
    frames: usize,
    rows: &str,
    read: impl FnOnce(&Path) -> Result<Vec<T>, DatasetError>,
) -> Result<Option<Vec<T>>, DatasetError> {
    if !path.is_file() {
        return Ok(None);
    }
    let v = read(path)?;
    if v.len() != frames {
        let message = format!("{} {rows} for {frames} frames", v.len());
        return Err(parse_error(path, 0, message));
    }
    Ok(Some(v))
}

/// Whitespace- or comma-separated numbers of one line.
pub(crate) fn numbers(text: &str, path: &Path, line: usize) -> Result<Vec<f64>, DatasetError> {
    text.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| parse_error(path, line, format!("'{s}' is not a finite number")))
        })
        .collect()
}

/// [`numbers`], at least `min` of them; fewer is the error `expected(count)`.
pub(crate) fn numbers_at_least(
    text: &str,
    path: &Path,
    line: usize,
    min: usize,
    expected: impl FnOnce(usize) -> String,
) -> Result<Vec<f64>, DatasetError> {
    let v = numbers(text, path, line)?;
    if v.len() < min {
        return Err(parse_error(path, line, expected(v.len())));
    }
    Ok(v)
}

/// True for a `.png` file name (any case).
pub(crate) fn is_png(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".png")
}

/// `text` without a leading UTF-8 byte-order mark (some editors write one).
pub(crate) fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// The first line of each key of a `key: values` file: a key given twice is an error
/// naming both lines (the reader would otherwise keep one of them silently).
#[derive(Debug, Default)]
pub(crate) struct KeyLines(std::collections::BTreeMap<String, usize>);

impl KeyLines {
    /// Records `key` at `line` (1-based).
    pub(crate) fn first(
        &mut self,
        key: &str,
        line: usize,
        path: &Path,
    ) -> Result<(), DatasetError> {
        if let Some(&before) = self.0.get(key) {
            return Err(parse_error(
                path,
                line,
                format!("'{key}' is given twice (lines {before} and {line}): keep one"),
            ));
        }
        self.0.insert(key.to_owned(), line);
        Ok(())
    }
}

/// Checks that two row-major 3x4 projection matrices of a rectified pair have the same
/// focal lengths and principal point (entries 0, 5, 2, 6), to a relative 1e-6.
pub(crate) fn check_same_intrinsics(
    path: &Path,
    (name0, p0): (&str, &[f64]),
    (name1, line1, p1): (&str, usize, &[f64]),
) -> Result<(), DatasetError> {
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs()).max(1.0);
    let labels = [(0, "fx"), (5, "fy"), (2, "cx"), (6, "cy")];
    if let Some((k, label)) = labels.iter().find(|(k, _)| !same(p0[*k], p1[*k])) {
        return Err(parse_error(
            path,
            line1,
            format!(
                "{name1} {label} = {} differs from {name0} {label} = {}: the images of a \
                 rectified pair share one camera matrix (fx, fy, cx, cy), only the \
                 baseline term differs",
                p1[*k], p0[*k]
            ),
        ));
    }
    Ok(())
}

/// Checks that a stereo baseline (metres) lies in [`crate::BASELINE_RANGE_M`].
pub(crate) fn check_baseline(
    path: &Path,
    line: usize,
    baseline_m: f64,
    what: &str,
) -> Result<(), DatasetError> {
    let (lo, hi) = crate::BASELINE_RANGE_M;
    if baseline_m.is_finite() && (lo..=hi).contains(&baseline_m) {
        return Ok(());
    }
    Err(parse_error(
        path,
        line,
        format!(
            "{what} gives a baseline of {baseline_m:.3e} m, outside the {lo} to {hi} m of a \
             stereo rig"
        ),
    ))
}

/// Checks that `rig` is a plausible camera for images of `size` (width, height)
/// ([`RectifiedStereo::implausibility`]); the error names the calibration file `path`.
pub(crate) fn check_plausible(
    path: &Path,
    rig: &crate::RectifiedStereo,
    size: (usize, usize),
) -> Result<(), DatasetError> {
    match rig.implausibility(size.0, size.1) {
        Some(why) => Err(parse_error(path, 0, why)),
        None => Ok(()),
    }
}
