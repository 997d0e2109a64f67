//! Small text-parsing helpers shared by the loaders.

use std::path::{Path, PathBuf};

use crate::error::DatasetError;

/// Reads a whole text file.
pub(crate) fn read_text(path: &Path, what: &'static str) -> Result<String, DatasetError> {
    if !path.exists() {
        return Err(DatasetError::Missing {
            path: path.to_owned(),
            what,
        });
    }
    std::fs::read_to_string(path).map_err(|source| DatasetError::Io {
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

/// The entries of `dir`, sorted by name, whose file names satisfy `keep`.
pub(crate) fn list_sorted(
    dir: &Path,
    keep: impl Fn(&str) -> bool,
) -> Result<Vec<PathBuf>, DatasetError> {
    let rd = std::fs::read_dir(dir).map_err(|source| DatasetError::Io {
        path: dir.to_owned(),
        source,
    })?;
    let mut out = Vec::new();
    for e in rd {
        let e = e.map_err(|source| DatasetError::Io {
            path: dir.to_owned(),
            source,
        })?;
        let name = e.file_name();
        if name.to_str().is_some_and(&keep) {
            out.push(e.path());
        }
    }
    out.sort();
    Ok(out)
}

/// True for a `.png` file name (any case).
pub(crate) fn is_png(name: &str) -> bool {
    name.to_ascii_lowercase().ends_with(".png")
}
