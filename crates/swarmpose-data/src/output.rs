//! Output files that harm nothing: the one place that decides how a path given as an
//! output is written.
//!
//! * A regular file, or a path where nothing is yet: written whole under a temporary
//!   name beside it (`.NAME.partial-PID.EXT`) and renamed when complete, so that a full
//!   disk, an error or a kill never leaves a truncated file under the final name.
//! * A symbolic link: followed. The link stays; the regular file it leads to (or the
//!   missing file it names) is replaced as above.
//! * A FIFO (a named pipe, `/dev/stdout` of a pipeline) or a character device (a
//!   terminal, `/dev/null`): written through, in place, never renamed over. A FIFO
//!   with no reader is waited for [`FIFO_READER_WAIT`] at most, then refused (`open`
//!   itself would wait forever: `--out` on a FIFO nobody reads hung the command).
//! * A folder, a block device or a socket: refused, nothing written ([`ErrorKind`]
//!   `InvalidInput`, the message says what the path is).

use std::fs::{File, OpenOptions};
use std::io::{self, ErrorKind, Write};
use std::path::{Path, PathBuf};

/// How an output path is written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// A regular file, or nothing yet, at this path (symbolic links resolved): replaced
    /// whole through a temporary file and a rename.
    Replace(PathBuf),
    /// A FIFO or a character device: written through in place.
    Through,
}

/// The marker in the temporary names of files being written (`.NAME.partial-PID.EXT`).
pub const TEMPORARY_MARKER: &str = ".partial-";

/// How long an output that is a FIFO may wait for its reader before it is refused.
pub const FIFO_READER_WAIT: std::time::Duration = std::time::Duration::from_secs(5);

/// At most this many symbolic links are followed (Linux's own limit).
const MAX_LINKS: usize = 40;

fn refused(what: &str) -> io::Error {
    io::Error::new(
        ErrorKind::InvalidInput,
        format!("{what}, not a file: refused (nothing written)"),
    )
}

/// What `meta` (of the path itself or where its links lead) is, when it is not a regular
/// file: `Some(Target::Through)` for a FIFO or a character device, an error for what is
/// refused, `None` for a regular file.
fn special(meta: &std::fs::Metadata) -> Result<Option<Target>, io::Error> {
    let kind = meta.file_type();
    if kind.is_file() {
        return Ok(None);
    }
    if kind.is_dir() {
        return Err(refused("a folder"));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() || kind.is_char_device() {
            return Ok(Some(Target::Through));
        }
        if kind.is_block_device() {
            return Err(refused("a block device (writing would overwrite it)"));
        }
        if kind.is_socket() {
            return Err(refused("a socket"));
        }
    }
    Err(refused("not a regular file"))
}

/// Follows the symbolic links of a path that leads nowhere yet (a dangling link) to the
/// path of the file they name.
fn dangling_target(path: &Path) -> io::Result<PathBuf> {
    let mut p = path.to_owned();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) if to.is_relative() => dir.join(to),
                    _ => to,
                };
            }
            _ => return Ok(p),
        }
    }
    Err(io::Error::new(
        ErrorKind::InvalidInput,
        "too many levels of symbolic links",
    ))
}

/// How `path` is written (see the module documentation).
///
/// # Errors
/// `InvalidInput` for a folder, a block device or a socket (or where links lead to
/// one); the error of the file system when the path cannot be examined.
pub fn target(path: &Path) -> io::Result<Target> {
    match std::fs::metadata(path) {
        Ok(meta) => match special(&meta)? {
            Some(t) => Ok(t),
            None if std::fs::symlink_metadata(path)?.file_type().is_symlink() => {
                Ok(Target::Replace(std::fs::canonicalize(path)?))
            }
            None => Ok(Target::Replace(path.to_owned())),
        },
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(Target::Replace(dangling_target(path)?)),
        Err(e) => Err(e),
    }
}

/// The temporary name of `path` while it is written: `.NAME.partial-PID.EXT` in the same
/// folder (the same extension, for writers that choose a format by it).
#[must_use]
pub fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!(
        ".{name}{TEMPORARY_MARKER}{}{ext}",
        std::process::id()
    ))
}

/// The final name of which `name` (a file name) is a temporary ([`temporary`], of any
/// process: what a killed writer may have left), or `None`.
#[must_use]
pub fn temporary_of(name: &str) -> Option<&str> {
    let at = name.rfind(TEMPORARY_MARKER)?;
    let final_name = name.get(1..at).filter(|_| name.starts_with('.'))?;
    let rest = &name[at + TEMPORARY_MARKER.len()..];
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let ext = Path::new(final_name)
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    (!final_name.is_empty() && digits > 0 && rest[digits..] == ext).then_some(final_name)
}

/// A new temporary file at `tmp` (one a killed run of the same process id left is
/// replaced; a link planted there is not followed).
fn create_temporary(tmp: &Path) -> io::Result<File> {
    let new = || OpenOptions::new().write(true).create_new(true).open(tmp);
    match new() {
        Err(e) if e.kind() == ErrorKind::AlreadyExists => {
            std::fs::remove_file(tmp)?;
            new()
        }
        other => other,
    }
}

/// Writes `bytes` to `path` whole (see the module documentation). The folder that holds
/// the file must exist.
///
/// # Errors
/// The error of the file system, or `InvalidInput` for a path that is refused; no
/// temporary file is left.
pub fn write_file(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let dest = match target(path)? {
        Target::Through => {
            let mut f = open_through(path)?;
            return f.write_all(bytes).and_then(|()| f.flush());
        }
        Target::Replace(dest) => dest,
    };
    let tmp = temporary(&dest);
    let result = create_temporary(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        // Data on disk before the name points at it.
        f.sync_all()?;
        std::fs::rename(&tmp, &dest)
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Opens `path` to be written bit by bit (a file streamed line by line): a regular file
/// (or where a link leads) is created or truncated, a FIFO or a character device written
/// through; what is refused is refused as by [`write_file`].
///
/// # Errors
/// As [`target`], or the error of opening.
pub fn create_stream(path: &Path) -> io::Result<File> {
    match target(path)? {
        Target::Through => open_through(path),
        Target::Replace(dest) => File::create(dest),
    }
}

/// Opens a FIFO or a character device to be written through. A FIFO's reader is waited
/// for at most [`FIFO_READER_WAIT`] (polled with non-blocking opens, which fail while
/// there is none); then the file is opened for blocking writes.
///
/// # Errors
/// `TimedOut` for a FIFO nobody opened for reading in time; the error of opening.
fn open_through(path: &Path) -> io::Result<File> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        let start = std::time::Instant::now();
        loop {
            match OpenOptions::new()
                .write(true)
                .custom_flags(libc::O_NONBLOCK)
                .open(path)
            {
                // A reader is there: the writes must wait for it, not fail, so open again
                // without O_NONBLOCK (this open does not wait: the reader is there).
                Ok(_probe) => return OpenOptions::new().write(true).open(path),
                Err(e) if e.raw_os_error() == Some(libc::ENXIO) => {
                    if start.elapsed() >= FIFO_READER_WAIT {
                        return Err(io::Error::new(
                            ErrorKind::TimedOut,
                            format!(
                                "a FIFO that nobody reads (no reader within {} s): refused \
                                 (nothing written)",
                                FIFO_READER_WAIT.as_secs()
                            ),
                        ));
                    }
                    std::thread::sleep(std::time::Duration::from_millis(20));
                }
                Err(e) => return Err(e),
            }
        }
    }
    #[cfg(not(unix))]
    OpenOptions::new().write(true).open(path)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use swarmpose_testdata::TempDir;

    #[test]
    fn a_file_is_replaced_and_a_link_keeps_pointing_at_it() {
        let dir = TempDir::new("output");
        let path = dir.0.join("a.csv");
        write_file(&path, b"one\n").unwrap();
        write_file(&path, b"two\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two\n");
        #[cfg(unix)]
        {
            let link = dir.0.join("link.csv");
            std::os::unix::fs::symlink("a.csv", &link).unwrap();
            write_file(&link, b"three\n").unwrap();
            assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
            assert_eq!(std::fs::read(&path).unwrap(), b"three\n");
            // A link to nothing yet: the file it names is made, the link stays.
            let dangling = dir.0.join("dangling.csv");
            std::os::unix::fs::symlink("made.csv", &dangling).unwrap();
            write_file(&dangling, b"four\n").unwrap();
            assert!(std::fs::symlink_metadata(&dangling).unwrap().is_symlink());
            assert_eq!(std::fs::read(dir.0.join("made.csv")).unwrap(), b"four\n");
        }
        let names: Vec<String> = std::fs::read_dir(&dir.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(
            names.iter().all(|n| !n.contains(TEMPORARY_MARKER)),
            "{names:?}"
        );
    }

    #[test]
    fn a_folder_is_refused() {
        let dir = TempDir::new("output-dir");
        let e = write_file(&dir.0, b"x").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::InvalidInput);
        assert!(e.to_string().starts_with("a folder, not a file"), "{e}");
        assert!(dir.0.is_dir());
        assert!(create_stream(&dir.0).is_err());
    }

    #[test]
    fn temporary_names_are_recognised() {
        let tmp = temporary(Path::new("/x/runs.csv"));
        let name = tmp.file_name().unwrap().to_string_lossy().into_owned();
        assert_eq!(temporary_of(&name), Some("runs.csv"), "{name}");
        assert_eq!(temporary_of(".runs.csv.partial-12.csv"), Some("runs.csv"));
        assert_eq!(temporary_of(".LICENSE.partial-7"), Some("LICENSE"));
        assert_eq!(
            temporary_of(".a.partial-1.png.partial-2.png"),
            Some("a.partial-1.png")
        );
        for other in [
            "runs.csv",
            ".runs.csv.partial-.csv",
            ".runs.csv.partial-12.png",
            ".runs.csv.partial-12x.csv",
            "x.runs.csv.partial-12.csv",
            "..partial-12",
        ] {
            assert_eq!(temporary_of(other), None, "{other}");
        }
    }

    /// A node made by `mknod`/`mkfifo` in `dir`, or `None` (with the reason printed) where
    /// this user may not make one.
    #[cfg(unix)]
    fn node(dir: &Path, name: &str, args: &[&str]) -> Option<PathBuf> {
        let path = dir.join(name);
        let (tool, rest) = args.split_first()?;
        let made = std::process::Command::new(tool)
            .arg(&path)
            .args(rest)
            .status()
            .is_ok_and(|s| s.success());
        if !made {
            eprintln!("SKIPPED: {tool} {name} not permitted here");
        }
        made.then_some(path)
    }

    #[cfg(unix)]
    fn is_char_device(path: &Path) -> bool {
        use std::os::unix::fs::FileTypeExt;
        std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_char_device())
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_nobody_reads_is_refused_in_bounded_time() {
        use std::os::unix::fs::FileTypeExt;
        let dir = TempDir::new("output-lonely-fifo");
        let Some(fifo) = node(&dir.0, "pipe", &["mkfifo"]) else {
            return;
        };
        let start = std::time::Instant::now();
        // Both ways of writing wait at once (each up to FIFO_READER_WAIT): the test takes
        // one wait, not two.
        let stream = {
            let fifo = fifo.clone();
            std::thread::spawn(move || create_stream(&fifo).map(drop))
        };
        let e = write_file(&fifo, b"nobody\n").unwrap_err();
        assert_eq!(e.kind(), ErrorKind::TimedOut, "{e}");
        assert!(e.to_string().starts_with("a FIFO that nobody reads"), "{e}");
        let e = stream.join().unwrap().unwrap_err();
        assert_eq!(e.kind(), ErrorKind::TimedOut, "{e}");
        assert!(start.elapsed() >= FIFO_READER_WAIT);
        assert!(start.elapsed() < 4 * FIFO_READER_WAIT);
        assert!(
            std::fs::symlink_metadata(&fifo)
                .unwrap()
                .file_type()
                .is_fifo()
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_and_a_device_are_written_through_never_replaced() {
        use std::os::unix::fs::FileTypeExt;
        let dir = TempDir::new("output-nodes");
        if let Some(fifo) = node(&dir.0, "pipe", &["mkfifo"]) {
            let reader = {
                let fifo = fifo.clone();
                std::thread::spawn(move || std::fs::read(fifo).unwrap())
            };
            write_file(&fifo, b"through the pipe\n").unwrap();
            assert_eq!(reader.join().unwrap(), b"through the pipe\n");
            assert!(
                std::fs::symlink_metadata(&fifo)
                    .unwrap()
                    .file_type()
                    .is_fifo()
            );
        }
        // Copies of /dev/null (1, 3) and /dev/full (1, 7), made here, and a link to one.
        if let Some(null) = node(&dir.0, "null", &["mknod", "c", "1", "3"]) {
            write_file(&null, b"gone\n").unwrap();
            create_stream(&null).unwrap().write_all(b"gone\n").unwrap();
            assert!(is_char_device(&null));
        }
        if let Some(full) = node(&dir.0, "full", &["mknod", "c", "1", "7"]) {
            let link = dir.0.join("to-full");
            std::os::unix::fs::symlink(&full, &link).unwrap();
            for path in [&full, &link] {
                let e = write_file(path, b"x\n").unwrap_err();
                assert_eq!(e.kind(), ErrorKind::StorageFull, "{e}");
            }
            assert!(is_char_device(&full));
            assert!(std::fs::symlink_metadata(&link).unwrap().is_symlink());
            assert_eq!(
                std::fs::read_dir(&dir.0).unwrap().count(),
                4,
                "no temporary"
            );
        }
        if let Some(block) = node(&dir.0, "block", &["mknod", "b", "7", "200"]) {
            let e = write_file(&block, b"x").unwrap_err();
            assert!(e.to_string().starts_with("a block device"), "{e}");
        }
    }
}
