//! The output-directory lock: one writer per directory (`sweep`, `merge`, `benchmark`).

use crate::failure::{exit, fail, Failure};
use std::io::{Read, Seek, Write};
use std::path::Path;

/// The file in an output directory whose operating-system lock marks the directory as being
/// written (README, "Sweeps"). The lock, not the file, is what counts: it is released when its
/// holder exits in any way (SIGKILL and a crashed node included), so a file left behind is
/// never a stale lock. While held, the file names its holder (`sweep pid 1234 on node7`); the
/// holder empties it when it lets go normally.
pub const LOCK_FILE: &str = ".isotrack.lock";

/// The largest holder record read back from [`LOCK_FILE`], bytes.
const MAX_HOLDER_BYTES: u64 = 256;

/// The lock of an output directory, held while this lives ([`lock_output_dir`]). Dropped, it
/// empties the holder record (an empty [`LOCK_FILE`] is what a finished command leaves) and the
/// operating system releases the lock with the file.
#[derive(Debug)]
pub struct DirLock {
    file: std::fs::File,
}

impl Drop for DirLock {
    fn drop(&mut self) {
        let _ = self.file.set_len(0);
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
            format!("cannot lock {}: {e}", path.display()),
        )
    };
    // Never through a link nor into a FIFO: a `.isotrack.lock` that is a link to a user's file
    // would have that file emptied (the holder record replaces its content).
    let mut f = crate::files::open_regular(&path, true, false).map_err(cant)?;
    match f.try_lock() {
        Ok(()) => {
            // The record is a courtesy for the message of the next one refused: failing to
            // write it does not fail the command.
            let _ = f
                .set_len(0)
                .and_then(|()| f.rewind())
                .and_then(|()| f.write_all(holder_record(command).as_bytes()));
            Ok(DirLock { file: f })
        }
        Err(std::fs::TryLockError::WouldBlock) => {
            let holder = read_holder(&mut f).map_or_else(
                || {
                    "another isotrack command (sweep, merge, benchmark, check --map, fly or sitl)"
                        .to_string()
                },
                |h| format!("another isotrack {h}"),
            );
            Err(fail(
                exit::CANTCREAT,
                format!(
                    "{}: {holder} is writing this directory (it holds the lock on {LOCK_FILE}); wait for it to end, or use another --out",
                    dir.display()
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
                    dir.display()
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
                    dir.display()
                ),
            ))
        }
        _ => Ok(()),
    }
}
