//! The output-directory lock: one writer per directory (`sweep`, `merge`, `benchmark`).

use crate::failure::{exit, fail, Failure};
use std::io::{Read, Seek, Write};
use std::path::Path;

/// The file in an output directory whose operating-system lock marks the directory as being
/// written (README, "Sweeps"). The lock, not the file, is what counts: it is released when its
/// holder exits in any way (SIGKILL and a crashed node included), so a file left behind is
/// never a stale lock. While held, the file names its holder (`sweep pid 1234 on node7`); the
/// holder removes it when it lets go normally (only a killed holder leaves the file behind).
pub const LOCK_FILE: &str = ".isotrack.lock";

/// The largest holder record read back from [`LOCK_FILE`], bytes.
const MAX_HOLDER_BYTES: u64 = 256;

/// The lock of an output directory, held while this lives ([`lock_output_dir`]). Dropped, it
/// removes [`LOCK_FILE`] while still holding its lock (a finished command leaves no lock file)
/// and the operating system then releases the lock with the file. A command that opened the
/// file before it was removed and takes its lock after finds the path gone or another file
/// there, and opens the path again ([`lock_output_dir`]): two commands never both hold "the"
/// lock of one directory.
#[derive(Debug)]
pub struct DirLock {
    file: std::fs::File,
    path: std::path::PathBuf,
    /// The file removed if the process is interrupted ([`crate::cleanup`]).
    _pending: crate::cleanup::Pending,
}

impl Drop for DirLock {
    fn drop(&mut self) {
        // Only the file this holds (a link or another file put there is not removed); when it
        // cannot be removed (a read-only directory), its holder record is emptied as before.
        if !(is_this_file(&self.file, &self.path) && std::fs::remove_file(&self.path).is_ok()) {
            let _ = self.file.set_len(0);
        }
    }
}

/// Whether `path` (not followed if a link) is the file `file` is open on.
fn is_this_file(file: &std::fs::File, path: &Path) -> bool {
    match (file.metadata(), std::fs::symlink_metadata(path)) {
        #[cfg(unix)]
        (Ok(a), Ok(b)) => {
            use std::os::unix::fs::MetadataExt;
            a.dev() == b.dev() && a.ino() == b.ino()
        }
        #[cfg(not(unix))]
        (Ok(_), Ok(b)) => b.is_file(),
        _ => false,
    }
}

/// This process as a holder record: `COMMAND pid PID` and, where the host name can be read
/// (`/proc/sys/kernel/hostname`), ` on HOST`.
fn holder_record(command: &str) -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty() && h.len() < 128 && !h.chars().any(char::is_control));
    match host {
        Some(h) => format!("{command} pid {} on {h}", std::process::id()),
        None => format!("{command} pid {}", std::process::id()),
    }
}

/// The holder a locked [`LOCK_FILE`] names (`sweep pid 1234 on node7`), if it names one: a
/// record of printable text only (the file is in a directory others may write), clipped.
fn read_holder(f: &mut std::fs::File) -> Option<String> {
    let mut text = String::new();
    f.rewind().ok()?;
    f.take(MAX_HOLDER_BYTES).read_to_string(&mut text).ok()?;
    let text = text.trim();
    (!text.is_empty() && !text.chars().any(char::is_control)).then(|| text.to_string())
}

/// Whether locked [`LOCK_FILE`] `f` is isotrack's to reuse (att41-13): empty (the first
/// isotrack's lock files, one a holder could not remove) or a holder record
/// ([`holder_record`]: `COMMAND pid PID`, ` on HOST`) that a killed holder left. Anything else
/// is a file of the user's of that name, never overwritten. Reads at most
/// [`MAX_HOLDER_BYTES`] and one more.
fn holds_a_record_or_nothing(f: &mut std::fs::File) -> bool {
    let mut bytes = Vec::new();
    if f.rewind().is_err()
        || f.take(MAX_HOLDER_BYTES + 1)
            .read_to_end(&mut bytes)
            .is_err()
    {
        return false;
    }
    if bytes.len() as u64 > MAX_HOLDER_BYTES {
        return false;
    }
    let Ok(text) = std::str::from_utf8(&bytes) else {
        return false;
    };
    let text = text.trim();
    if text.is_empty() {
        return true;
    }
    let Some((command, rest)) = text.split_once(" pid ") else {
        return false;
    };
    let (pid, host) = rest.split_once(" on ").unwrap_or((rest, "x"));
    !command.is_empty()
        && !host.is_empty()
        && !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && !text.chars().any(char::is_control)
}

/// Takes the exclusive lock of output directory `dir` for `command` (`sweep`, `merge`,
/// `benchmark`): an advisory `flock`-style lock on [`LOCK_FILE`], std's `File::try_lock`, held
/// until the returned [`DirLock`] is dropped or the process ends, with the holder (command,
/// pid, host) recorded in the file. A second sweep, merge or benchmark writing the same
/// directory (a requeued Slurm task while the old one still runs) exits 73, naming the holder,
/// instead of running everything again beside it.
pub fn lock_output_dir(dir: &Path, command: &str) -> Result<DirLock, Failure> {
    let path = dir.join(LOCK_FILE);
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot lock {}: {e}", crate::owned::shell_quoted(&path)),
        )
    };
    // A holder removes the file as it lets go (DirLock's drop): a lock taken on a file no
    // longer at the path is no lock, so the path is opened again (a few times: each retry
    // means another command finished meanwhile).
    for _ in 0..16 {
        match lock_once(dir, &path, command)? {
            Some(lock) => return Ok(lock),
            None => continue,
        }
    }
    Err(cant(std::io::Error::other(
        "the lock file was replaced again and again while being locked",
    )))
}

/// The holder named when its record is not yet written (it has locked, not yet recorded
/// itself): every command that locks an output directory (README, exit 73; att48-4: `run --out`,
/// `compare --out` and `plot` were missing, the very holder at times).
const UNNAMED_HOLDER: &str = "another isotrack command (sweep, merge, benchmark, run --out, compare --out, check --map, fly --out, sitl --out or plot)";

/// One attempt of [`lock_output_dir`]: `None` when the file locked is no longer at the path.
fn lock_once(dir: &Path, path: &Path, command: &str) -> Result<Option<DirLock>, Failure> {
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot lock {}: {e}", crate::owned::shell_quoted(path)),
        )
    };
    // Never through a link nor into a FIFO: a `.isotrack.lock` that is a link to a user's file
    // would have that file emptied (the holder record replaces its content).
    // A file this creates is registered before it is created: an interrupt right after the
    // creation removes it, and with it the directory the command created (att51-3).
    let created = std::fs::symlink_metadata(path)
        .is_err()
        .then(|| crate::cleanup::register(path));
    let mut f = crate::files::open_regular(path, true, false).map_err(cant)?;
    match f.try_lock() {
        Ok(()) if !is_this_file(&f, path) => Ok(None),
        Ok(()) if !holds_a_record_or_nothing(&mut f) => Err(fail(
            exit::CANTCREAT,
            format!(
                "{} is not an isotrack lock file (it holds text that is not isotrack's holder record `COMMAND pid N on HOST`: a file of your own), and isotrack never replaces a file it did not write: move it away, or use another --out",
                crate::owned::shell_quoted(path)
            ),
        )),
        Ok(()) => {
            // The record is a courtesy for the message of the next one refused: failing to
            // write it does not fail the command.
            let _ = f
                .set_len(0)
                .and_then(|()| f.rewind())
                .and_then(|()| f.write_all(holder_record(command).as_bytes()));
            Ok(Some(DirLock {
                file: f,
                path: path.to_path_buf(),
                _pending: created.unwrap_or_else(|| crate::cleanup::register(path)),
            }))
        }
        Err(std::fs::TryLockError::WouldBlock) => {
            let holder = read_holder(&mut f).map_or_else(
                || UNNAMED_HOLDER.to_string(),
                |h| format!("another isotrack {h}"),
            );
            Err(fail(
                exit::CANTCREAT,
                format!(
                    "{}: {holder} is writing this directory (it holds the lock on {LOCK_FILE}); wait for it to end, or use another --out",
                    crate::owned::shell_quoted(dir)
                ),
            ))
        }
        Err(std::fs::TryLockError::Error(e)) => Err(cant(e)),
    }
}

/// Refuses to read shard directory `dir` while a command still writes it (it holds the lock of
/// [`lock_output_dir`]; the message names it): its rows are not all there yet. A directory
/// without a lock file was never locked (nothing to wait for).
pub fn check_not_being_written(dir: &Path) -> Result<(), Failure> {
    let path = dir.join(LOCK_FILE);
    // Only a regular file is opened: a FIFO there would block the open.
    match std::fs::symlink_metadata(&path) {
        Ok(m) if m.file_type().is_file() => {}
        Ok(_) => {
            return Err(fail(
                exit::CANTCREAT,
                format!(
                    "{}: {LOCK_FILE} is not a regular file (a link, FIFO, directory or device); remove it",
                    crate::owned::shell_quoted(dir)
                ),
            ))
        }
        Err(_) => return Ok(()),
    }
    let Ok(mut f) = std::fs::File::open(&path) else {
        return Ok(());
    };
    match f.try_lock_shared() {
        Err(std::fs::TryLockError::WouldBlock) => {
            let holder = read_holder(&mut f)
                .map_or_else(|| "a sweep".to_string(), |h| format!("an isotrack {h}"));
            Err(fail(
                exit::CANTCREAT,
                format!(
                    "{}: {holder} is still writing this directory (it holds the lock on {LOCK_FILE}); merge once it has ended",
                    crate::owned::shell_quoted(dir)
                ),
            ))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// att48-4: a lock held by a command that has not yet written its holder record is refused
    /// (73) naming every command that locks, `run --out`, `compare --out` and `plot` included.
    #[test]
    fn an_unrecorded_holder_is_named_as_any_locking_command() {
        let dir = tempfile::tempdir().unwrap();
        let held = std::fs::File::create(dir.path().join(LOCK_FILE)).unwrap();
        held.lock().unwrap();
        let e = lock_output_dir(dir.path(), "run").unwrap_err();
        assert_eq!(e.code, exit::CANTCREAT);
        for c in [
            "sweep",
            "merge",
            "benchmark",
            "run --out",
            "compare --out",
            "check --map",
            "fly --out",
            "sitl --out",
            "plot",
        ] {
            assert!(e.message.contains(c), "{c} not named: {}", e.message);
        }
    }
}
