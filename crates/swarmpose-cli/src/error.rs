//! Errors of the command-line tool: a message and an exit status, printed as one line.

use std::fmt;

use swarmpose_data::{CsvError, CsvErrorKind};

/// Exit status of an estimation that ran and failed (no pose with enough support), or
/// of output that could not be written.
pub const EXIT_FAILURE: u8 = 1;
/// Exit status of bad usage or bad input: options, files, CSV content, too few or
/// degenerate points.
pub const EXIT_USAGE: u8 = 2;
/// Exit status of a run that finished but whose result is not usable (for example an
/// odometry run in which fewer than half of the motions were tracked); its outputs are
/// written.
pub const EXIT_NOT_USABLE: u8 = 3;

/// A failure of a subcommand: what to tell the user and the exit status.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CliError {
    /// Exit status, [`EXIT_USAGE`] or [`EXIT_FAILURE`].
    pub code: u8,
    /// The message, without the `swarmpose: error: ` prefix.
    pub message: String,
}

impl CliError {
    /// Bad usage or bad input (exit status 2).
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            code: EXIT_USAGE,
            message: message.into(),
        }
    }

    /// A run that failed on valid input, or output that could not be written (exit
    /// status 1).
    pub fn failure(message: impl Into<String>) -> Self {
        Self {
            code: EXIT_FAILURE,
            message: message.into(),
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl From<CsvError> for CliError {
    fn from(e: CsvError) -> Self {
        match e.kind {
            CsvErrorKind::Write(_) => Self::failure(e.to_string()),
            _ => Self::usage(e.to_string()),
        }
    }
}

impl From<swarmpose_runs::RunError> for CliError {
    fn from(e: swarmpose_runs::RunError) -> Self {
        if e.is_input() {
            Self::usage(e.to_string())
        } else {
            Self::failure(e.to_string())
        }
    }
}

/// `text` on one line: line breaks become `"; "`, blank lines are dropped.
pub fn one_line(text: &str) -> String {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

/// One line from a clap error: its first paragraph without the `error: ` prefix, any
/// tip, and where to find help.
pub fn from_clap(e: &clap::Error) -> CliError {
    let text = e.render().to_string();
    let mut paragraphs = text.split("\n\n").map(str::trim).filter(|p| !p.is_empty());
    let first = paragraphs.next().unwrap_or("invalid arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    // "the following required arguments were not provided:\n  <FILE>" -> one line.
    let mut message = first.lines().map(str::trim).collect::<Vec<_>>().join(" ");
    for p in paragraphs {
        if let Some(tip) = p.strip_prefix("tip: ") {
            message.push_str(&format!("; {}", one_line(tip)));
        } else if let Some(rest) = p.strip_prefix("For more information, try ") {
            message.push_str(&format!(" (try {})", rest.trim_end_matches('.')));
        }
    }
    CliError::usage(message)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_line_joins_lines() {
        assert_eq!(one_line("a\n\n  b  \r\nc"), "a; b; c");
        assert_eq!(one_line("plain"), "plain");
    }
}
