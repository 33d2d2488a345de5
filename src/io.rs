//! Output files are never left half-written, and a killed write leaves nothing behind.
//!
//! On Linux the bytes go to an unnamed file in the destination's directory (`O_TMPFILE`), which
//! the kernel removes if the process dies; only when it is complete and synced is it given a
//! name (`linkat` through `/proc/self/fd`) and renamed over the destination. Elsewhere, or on a
//! file system without unnamed files, it is a named temporary file `.<name>.<pid>.tmp` renamed
//! when complete. A process killed between naming and renaming (or during a fallback write)
//! leaves such a file; the next write of the same output removes those of processes that no
//! longer run.
//!
//! Every error is a [`WriteError`] inside the `std::io::Error` (so callers keep their
//! `io::Result`s), which says in the user's words what is wrong with the path and whether the
//! user's input caused it ([`WriteError::is_bad_input`], exit code 2 on the command line).
//!
//! Text read from files goes to the terminal through [`printable`], so that a scene's name or a
//! PNG's text chunk cannot move the cursor, recolour the terminal or hide what follows it.

use std::io::{ErrorKind, Write};
use std::path::{Path, PathBuf};

/// Why an output could not be written.
#[derive(Debug)]
pub struct WriteError {
    pub path: PathBuf,
    pub cause: std::io::Error,
}

impl std::fmt::Display for WriteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let reason = match self.cause.kind() {
            ErrorKind::IsADirectory => "it is a folder; give a file name",
            ErrorKind::NotADirectory => "a part of its path is a file, not a folder",
            ErrorKind::PermissionDenied => "permission denied (the folder is read-only or not yours)",
            ErrorKind::ReadOnlyFilesystem => "the file system is read-only",
            ErrorKind::NotFound => "no file can be created there (the folder is missing or takes no new files)",
            ErrorKind::StorageFull => "the disk is full",
            // The cause says it best (the closure's own messages, e.g. a format's size limit).
            _ => return write!(f, "{}", self.cause),
        };
        f.write_str(reason)
    }
}

impl std::error::Error for WriteError {}

impl WriteError {
    /// Whether the path or the request is at fault (a folder, a read-only place, an output
    /// past its format's limits) rather than the machine (a full disk, an I/O failure).
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self.cause.kind(),
            ErrorKind::IsADirectory
                | ErrorKind::NotADirectory
                | ErrorKind::PermissionDenied
                | ErrorKind::ReadOnlyFilesystem
                | ErrorKind::NotFound
                | ErrorKind::AlreadyExists
                | ErrorKind::DirectoryNotEmpty
                | ErrorKind::InvalidFilename
                | ErrorKind::InvalidInput
                | ErrorKind::FileTooLarge
                | ErrorKind::CrossesDevices
                | ErrorKind::Unsupported
        )
    }

    /// The `WriteError` inside an error returned by this module, if it is one.
    pub fn of(e: &std::io::Error) -> Option<&WriteError> {
        e.get_ref().and_then(|inner| inner.downcast_ref::<WriteError>())
    }

    fn wrap(path: &Path, cause: std::io::Error) -> std::io::Error {
        if WriteError::of(&cause).is_some() {
            return cause;
        }
        std::io::Error::new(cause.kind(), WriteError { path: path.to_path_buf(), cause })
    }
}

/// The temporary name used while `path` is being written.
pub fn temp_path(path: &Path) -> PathBuf {
    temp_path_of(path, std::process::id())
}

fn temp_path_of(path: &Path, pid: u32) -> PathBuf {
    path.with_file_name(format!(".{}.{pid}.tmp", file_name(path)))
}

fn file_name(path: &Path) -> String {
    path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

/// Writes `path` atomically: `write` fills a buffered temporary file, which is flushed, synced
/// and renamed onto `path`. On any error nothing is left behind; the error is a [`WriteError`].
///
/// In the browser, where there are no files, the bytes are offered as a download named as
/// `path`'s file name (`platform::web::download`): every save is one there.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> std::io::Result<()> {
    #[cfg(target_arch = "wasm32")]
    return crate::platform::web::download(&file_name(path), write).map_err(|e| WriteError::wrap(path, e));
    #[cfg(not(target_arch = "wasm32"))]
    write_atomic_inner(path, write).map_err(|e| WriteError::wrap(path, e))
}

#[cfg_attr(
    target_arch = "wasm32",
    expect(dead_code, reason = "the browser offers downloads instead (its callees too)")
)]
fn write_atomic_inner(path: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> std::io::Result<()> {
    if path.is_dir() || path.as_os_str().is_empty() || path.file_name().is_none() {
        return Err(ErrorKind::IsADirectory.into());
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // create_dir_all says "File exists" when a part of the path is a file; the user's words
    // for that are "not a folder".
    std::fs::create_dir_all(&dir).map_err(|e| match e.kind() {
        ErrorKind::AlreadyExists => std::io::Error::from(ErrorKind::NotADirectory),
        _ => e,
    })?;
    remove_stale_temp_files(&dir, path);
    #[cfg(target_os = "linux")]
    let write = match unnamed::write(&dir, path, write) {
        unnamed::Outcome::Done(result) => return result,
        unnamed::Outcome::Unsupported(write) => write,
    };
    let tmp = temp_path(path);
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(file);
        write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Checks before any work that `path` can be written as [`write_atomic`] writes it: creates the
/// missing folders above it, then creates its temporary file in its folder and removes it
/// again, so that a read-only or missing place fails at once instead of after a long render.
/// Returns the folders this call created, outermost first (the caller may say so, or take
/// them back with [`remove_created`]); on an error it leaves nothing behind. The error is a
/// [`WriteError`], as [`write_atomic`]'s.
pub fn probe(path: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut created = Vec::new();
    probe_inner(path, &mut created).map(|()| created.clone()).map_err(|e| {
        remove_created(&created);
        WriteError::wrap(path, e)
    })
}

fn probe_inner(path: &Path, created: &mut Vec<PathBuf>) -> std::io::Result<()> {
    if path.is_dir() || path.as_os_str().is_empty() || path.file_name().is_none() {
        return Err(ErrorKind::IsADirectory.into());
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // The folders missing now, outermost first: the ones create_dir_all is about to make.
    let missing: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && std::fs::symlink_metadata(a).is_err())
        .map(Path::to_path_buf)
        .collect();
    std::fs::create_dir_all(&dir).map_err(|e| match e.kind() {
        ErrorKind::AlreadyExists => std::io::Error::from(ErrorKind::NotADirectory),
        _ => e,
    })?;
    created.extend(missing.into_iter().rev());
    let tmp = temp_path(path);
    // This process writes nothing yet, so a file of this name is a dead one's, as good to replace.
    // The file closes at the end of the statement.
    std::fs::File::create(&tmp)?;
    std::fs::remove_file(&tmp)
}

/// Removes the folders [`probe`] created (outermost first, as it returns them) where they are
/// still empty, innermost first.
pub fn remove_created(folders: &[PathBuf]) {
    for dir in folders.iter().rev() {
        let _ = std::fs::remove_dir(dir);
    }
}

/// Removes `.<name>.<pid>.tmp` files of `path` left by processes that no longer run (a write
/// killed before its rename). Files of running processes, this one included, are kept: another
/// process may be writing the same output right now.
fn remove_stale_temp_files(dir: &Path, path: &Path) {
    let name = file_name(path);
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.filter_map(|e| e.ok()) {
        let entry_name = entry.file_name().to_string_lossy().into_owned();
        let pid = entry_name
            .strip_prefix('.')
            .and_then(|r| r.strip_prefix(name.as_str()))
            .and_then(|r| r.strip_prefix('.'))
            .and_then(|r| r.strip_suffix(".tmp"))
            .and_then(|r| r.parse::<u32>().ok());
        if let Some(pid) = pid
            && pid != std::process::id()
            && !process_runs(pid)
        {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether process `pid` exists. Where that cannot be told, it is assumed to run, so that no
/// file that may still be written is removed.
fn process_runs(pid: u32) -> bool {
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

#[cfg(target_os = "linux")]
mod unnamed {
    //! The `O_TMPFILE` path: an unnamed file that cannot outlive the process until linked.

    use std::io::Write;
    use std::os::fd::AsRawFd;
    use std::path::Path;

    use rustix::fs::{AtFlags, CWD, Mode, OFlags};

    pub(super) enum Outcome<W> {
        Done(std::io::Result<()>),
        /// The file system has no unnamed files (or `/proc` is missing): the caller falls back.
        Unsupported(W),
    }

    pub(super) fn write<W: FnOnce(&mut dyn Write) -> std::io::Result<()>>(
        dir: &Path,
        path: &Path,
        write: W,
    ) -> Outcome<W> {
        // Linking an unnamed file without privileges goes through its /proc/self/fd entry.
        if !Path::new("/proc/self/fd").is_dir() {
            return Outcome::Unsupported(write);
        }
        let fd = match rustix::fs::open(dir, OFlags::TMPFILE | OFlags::WRONLY | OFlags::CLOEXEC, Mode::from(0o666)) {
            Ok(fd) => fd,
            Err(_) => return Outcome::Unsupported(write),
        };
        let file = std::fs::File::from(fd);
        Outcome::Done((|| {
            let mut w = std::io::BufWriter::new(file);
            write(&mut w)?;
            let file = w.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()?;
            // linkat cannot replace a file, so the name is the temporary one, renamed over the
            // destination at once; only a kill between the two leaves it (removed next time).
            let tmp = super::temp_path(path);
            let _ = std::fs::remove_file(&tmp);
            let proc_path = format!("/proc/self/fd/{}", file.as_raw_fd());
            rustix::fs::linkat(CWD, proc_path.as_str(), CWD, &tmp, AtFlags::SYMLINK_FOLLOW)?;
            std::fs::rename(&tmp, path).inspect_err(|_| {
                let _ = std::fs::remove_file(&tmp);
            })
        })())
    }
}

/// Encodes `img` as PNG and writes it atomically.
pub fn save_png(path: &Path, img: &image::RgbImage) -> std::io::Result<()> {
    let mut bytes = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).map_err(std::io::Error::other)?;
    write_atomic(path, |w| w.write_all(&bytes))
}

/// `text` with its control characters escaped as Rust writes them (`\u{1b}`, `\0`, `\r`;
/// line feeds too unless `keep_lines`), and the bidirectional overrides and isolates escaped
/// likewise, which would reorder what a terminal shows: for names and descriptions read from
/// files that are printed.
pub fn printable(text: &str, keep_lines: bool) -> std::borrow::Cow<'_, str> {
    let escaped = |c: char| {
        (c.is_control() && !(keep_lines && c == '\n')) || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
    };
    if !text.chars().any(escaped) {
        return text.into();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if escaped(c) {
            out.extend(c.escape_debug());
        } else {
            out.push(c);
        }
    }
    out.into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stale_temp_files_of_dead_processes_go() {
        let dir = std::env::temp_dir().join(format!("nlifs-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("out.glb");
        // u32::MAX - 1 is past any pid limit (at most 2^22 on Linux), so no process runs there.
        let dead = temp_path_of(&out, u32::MAX - 1);
        let other = dir.join(".other.glb.4294967294.tmp");
        std::fs::write(&dead, b"debris").unwrap();
        std::fs::write(&other, b"not ours").unwrap();
        write_atomic(&out, |w| w.write_all(b"data")).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"data");
        assert!(!dead.exists(), "the dead process's temporary file stays");
        assert!(other.exists(), "another output's temporary file was removed");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_probe_creates_the_folder_and_leaves_no_file() {
        let top = std::env::temp_dir().join(format!("nlifs-probe-{}", std::process::id()));
        let out = top.join("a/b/out.png");
        std::fs::create_dir_all(&top).unwrap();
        assert_eq!(probe(&out).unwrap(), [top.join("a"), top.join("a/b")]);
        assert_eq!(std::fs::read_dir(top.join("a/b")).unwrap().count(), 0, "the probe left a file");
        assert_eq!(probe(&out).unwrap(), Vec::<PathBuf>::new(), "an existing folder is not created again");
        remove_created(&[top.join("a"), top.join("a/b")]);
        assert!(!top.join("a").exists(), "the created folders stay");
        // A folder that is a file: the probe fails as the write would, and creates nothing.
        std::fs::write(top.join("file.txt"), b"x").unwrap();
        let e = probe(&top.join("file.txt/out.png")).unwrap_err();
        assert!(WriteError::of(&e).is_some_and(WriteError::is_bad_input), "{e}");
        assert_eq!(e.to_string(), "a part of its path is a file, not a folder");
        let mut names: Vec<_> = std::fs::read_dir(&top).unwrap().map(|e| e.unwrap().file_name()).collect();
        names.sort();
        assert_eq!(names, ["file.txt"]);
        std::fs::remove_dir_all(&top).unwrap();
    }

    #[test]
    fn a_folder_is_bad_input() {
        let e = write_atomic(&std::env::temp_dir(), |w| w.write_all(b"x")).unwrap_err();
        let w = WriteError::of(&e).expect("a WriteError");
        assert!(w.is_bad_input());
        assert_eq!(e.to_string(), "it is a folder; give a file name");
    }
}
