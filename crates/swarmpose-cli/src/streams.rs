//! Standard output and error that never panic: a closed pipe ends the command quietly
//! (as other Unix tools do, with status 141), a full or failing standard output is an
//! error (status 1), and a message that cannot be written to standard error is dropped.

use std::cell::RefCell;
use std::io::{ErrorKind, Write};

use crate::error::{CliError, EXIT_FAILURE, one_line};

/// Exit status when standard output was closed by its reader (128 + SIGPIPE).
pub const EXIT_PIPE_CLOSED: u8 = 141;

thread_local! {
    /// The console output of this thread while [`capture`] runs.
    static CAPTURED: RefCell<Option<String>> = const { RefCell::new(None) };
}

/// Runs `f` with what it writes to standard output and error on this thread (through
/// [`out`], [`out_text`], [`err`]) kept instead, in order: a batch runs its items side by
/// side and keeps each one's console output in its folder.
pub fn capture<T>(f: impl FnOnce() -> T) -> (T, String) {
    let outer = CAPTURED.with(|c| c.borrow_mut().replace(String::new()));
    let value = f();
    let text = CAPTURED.with(|c| std::mem::replace(&mut *c.borrow_mut(), outer));
    (value, text.unwrap_or_default())
}

/// Appends `text` to this thread's capture, if one runs; false otherwise.
fn captured(text: &str) -> bool {
    CAPTURED.with(|c| match c.borrow_mut().as_mut() {
        Some(buf) => {
            buf.push_str(text);
            true
        }
        None => false,
    })
}

/// Writes `text` and a line end to standard output.
///
/// # Errors
/// A quiet [`CliError`] with [`EXIT_PIPE_CLOSED`] when the reader closed the pipe; exit
/// status 1 for any other write error (a full disk, `> /dev/full`).
pub fn out(text: &str) -> Result<(), CliError> {
    let mut line = String::with_capacity(text.len() + 1);
    line.push_str(text);
    line.push('\n');
    out_text(&line)
}

/// Writes `text` as it is (several lines, each with its line end) to standard output.
///
/// # Errors
/// As [`out`].
pub fn out_text(text: &str) -> Result<(), CliError> {
    if captured(text) {
        return Ok(());
    }
    let mut stdout = std::io::stdout().lock();
    match stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
    {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == ErrorKind::BrokenPipe => Err(CliError {
            code: EXIT_PIPE_CLOSED,
            message: String::new(),
        }),
        Err(e) => Err(CliError {
            code: EXIT_FAILURE,
            message: format!("cannot write to standard output: {e}"),
        }),
    }
}

/// Writes `text` and a line end to standard error; an error is ignored (there is no
/// better place to report it).
pub fn err(text: &str) {
    if captured(&format!("{text}\n")) {
        return;
    }
    let mut stderr = std::io::stderr().lock();
    let _ = writeln!(stderr, "{text}").and_then(|()| stderr.flush());
}

/// Writes `swarmpose: warning: TEXT` to standard error (see [`err`]).
pub fn warn(text: &str) {
    err(&format!("swarmpose: warning: {}", one_line(text)));
}

/// Prints `swarmpose: error: MESSAGE` of `e` as exactly one line on standard error
/// (nothing for an empty message: a quiet stop); never panics.
pub fn print_error(e: &CliError) {
    if !e.message.is_empty() {
        err(&format!("swarmpose: error: {}", one_line(&e.message)));
    }
}
