//! Files a command removes when it is interrupted (Ctrl-C, SIGTERM): an output directory's
//! lock file ([`crate::sweep::lock::LOCK_FILE`]) and a trace being streamed into its
//! temporary file (`.trace.csv.PID.tmp`). Each is registered while it exists ([`register`]);
//! so is a directory a command created for a run ([`register_dir`]: removed when still
//! empty). The signals are [`crate::signals`]': once the command-line program has called
//! [`crate::signals::remove_on_interrupt`], SIGINT, SIGTERM and SIGHUP remove every registered
//! file ([`remove_pending`]) and end the process with 128 + the signal.
//!
//! A replacement that must not be cut in two (a run directory's old summary removed, its new
//! trace, scenario and summary put in place; a table and its record) runs as one [`whole`]
//! step: the interrupt waits for a step under way to end before it removes anything, and a
//! step not yet begun never begins (att46-10: the cleanup removed a law's temporary trace
//! while its run directory was being replaced, so the old summary was gone and the new one
//! never written).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// The registered paths, each with its registration's number and whether it is a directory
/// (removed only when empty, after the files).
static PENDING: Mutex<Vec<(u64, PathBuf, bool)>> = Mutex::new(Vec::new());
/// The next registration's number.
static NEXT: AtomicU64 = AtomicU64::new(0);

/// A file removed if the process is interrupted while this lives ([`register`]); dropped, the
/// file is no longer the interruption's to remove (it was renamed into place or removed).
#[derive(Debug)]
pub struct Pending {
    id: u64,
}

impl Drop for Pending {
    fn drop(&mut self) {
        let mut list = PENDING.lock().unwrap_or_else(|e| e.into_inner());
        list.retain(|(id, _, _)| *id != self.id);
    }
}

/// Registers `path` to be removed if the process is interrupted before the returned
/// [`Pending`] is dropped.
pub fn register(path: &Path) -> Pending {
    register_path(path, false)
}

/// Registers directory `path` (one the command created) to be removed if the process is
/// interrupted before the returned [`Pending`] is dropped, and only if it is empty then (its
/// registered files removed first): an interrupted command leaves no empty directory of its
/// own behind, and never one holding a file.
pub fn register_dir(path: &Path) -> Pending {
    register_path(path, true)
}

/// Creates directory `dir` and each missing parent (as [`std::fs::create_dir_all`]), each level
/// it creates registered with [`register_dir`], the outermost first (so removed last): an
/// interrupted command removes every empty directory it made, `a/b/c` and its parents `a/b`
/// and `a` alike (att48-5: only `c` was removed). Hold the returned registrations to the end.
pub fn create_dir_all(dir: &Path) -> std::io::Result<Vec<Pending>> {
    let missing: Vec<&Path> = dir
        .ancestors()
        .filter(|p| !p.as_os_str().is_empty())
        .take_while(|p| std::fs::symlink_metadata(p).is_err())
        .collect();
    let mut created = Vec::with_capacity(missing.len());
    for level in missing.into_iter().rev() {
        // Registered before it is made: an interrupt right after the creation finds it listed.
        let pending = register_dir(level);
        match std::fs::create_dir(level) {
            Ok(()) => created.push(pending),
            // Made by another process meanwhile: not this command's to remove.
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && level.is_dir() => {}
            Err(e) => return Err(e),
        }
    }
    // Whatever exists at `dir` must be a directory (as create_dir_all checks).
    std::fs::create_dir_all(dir)?;
    Ok(created)
}

/// Output directory `dir` as a command creates, cleans up and names it, settled once before
/// anything is created: a `..` right after a level not there yet (`u/b/../c` with no `u/b`,
/// `x/../u/b` with no `x`) is resolved in the text, so that [`create_dir_all`] never makes a
/// level only to pass through it (att53o-2: it made `u/b`, the interrupt removed it as empty,
/// and the note then read `u/b/../c` through the missing `u/b` and said "nothing written" of
/// a directory holding the rows). The levels are walked in order, as the system walks them
/// once the missing ones are made: a `..` after a level that is there (a link is followed) is
/// kept for the system to resolve, never taken off in the text (att55o-1: `x/../L/../c`, `L`
/// a link to `elsewhere/deep`, was settled to `c` and replaced a run there, where the system
/// and the earlier build wrote `elsewhere/c`). `dir` is returned as it is without a `..`.
pub fn settled_dir(dir: &Path) -> PathBuf {
    use std::path::Component;
    if !dir.components().any(|c| c == Component::ParentDir) {
        return dir.to_path_buf();
    }
    let mut settled = PathBuf::new();
    // The trailing levels of `settled` not there yet (made later by create_dir_all).
    let mut missing = 0_usize;
    for c in dir.components() {
        match c {
            // A level not there yet: `NAME/..` is where NAME would be made.
            Component::ParentDir if missing > 0 => {
                settled.pop();
                missing -= 1;
            }
            // After a level that is there: the system resolves it (through a link too).
            Component::ParentDir => settled.push(".."),
            Component::Normal(name) => {
                settled.push(name);
                if missing > 0 || std::fs::symlink_metadata(&settled).is_err() {
                    missing += 1;
                }
            }
            Component::CurDir => {}
            Component::RootDir | Component::Prefix(_) => settled.push(c.as_os_str()),
        }
    }
    if settled.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        settled
    }
}

fn register_path(path: &Path, dir: bool) -> Pending {
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    PENDING
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push((id, path.to_path_buf(), dir));
    Pending { id }
}

/// What an interrupt says before the process ends ([`on_interrupt`]), each with its
/// registration's number.
type Say = Box<dyn Fn() + Send>;
static NOTES: Mutex<Vec<(u64, Say)>> = Mutex::new(Vec::new());

/// A note said if the process is interrupted while this lives ([`on_interrupt`]).
pub struct OnInterrupt {
    id: u64,
}

impl std::fmt::Debug for OnInterrupt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OnInterrupt").field("id", &self.id).finish()
    }
}

impl Drop for OnInterrupt {
    fn drop(&mut self) {
        // Kept once an interrupt is ending the process: a command that fails meanwhile (the
        // cleanup removed a temporary or a directory under it) returns through its note's
        // scope before the interrupt says the notes, which must still say what was left.
        if exiting() {
            return;
        }
        let mut list = NOTES.lock().unwrap_or_else(|e| e.into_inner());
        list.retain(|(id, _)| *id != self.id);
    }
}

/// Registers `say` (it prints a line on stderr: what the interrupted command left, and how to
/// go on) to be called if the process is interrupted before the returned [`OnInterrupt`] is
/// dropped: after a [`whole`] step under way has ended and the registered files are removed, so
/// it sees the directory as the command leaves it (att48-2, -6: exit 130 without a word on
/// what was left). One place for every command's interrupted line.
pub fn on_interrupt(say: impl Fn() + Send + 'static) -> OnInterrupt {
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    NOTES
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push((id, Box::new(say)));
    OnInterrupt { id }
}

/// Calls every registered [`on_interrupt`] note, in the order they were registered.
fn say_notes() {
    let list = NOTES.lock().unwrap_or_else(|e| e.into_inner());
    for (_, say) in list.iter() {
        say();
    }
}

/// Held by a [`whole`] step while it runs, and by the interrupt before it removes anything.
static WHOLE: Mutex<()> = Mutex::new(());

thread_local! {
    /// Whether this thread is inside a [`whole`] step.
    static IN_WHOLE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether this thread is inside a [`whole`] step (its files are created even while an
/// interrupt waits for it: [`crate::files::create_output`]).
pub fn in_whole() -> bool {
    IN_WHOLE.with(std::cell::Cell::get)
}

/// Runs `step` as one step an interrupt never cuts: an interrupt that comes while it runs
/// waits for it to end before it removes the registered files and exits
/// ([`remove_pending_for_exit`]), and once an interrupt is ending the process, no step begins
/// (this thread waits for the exit instead). For a replacement that must leave the old files
/// or the new ones, never a mix: [`crate::rundir::RunDir::finish`], a table with its record
/// ([`crate::owned::write_table`]). A step inside a step is part of it. Keep steps short
/// (renames and small writes): the interrupt waits for them.
pub fn whole<T>(step: impl FnOnce() -> T) -> T {
    if in_whole() {
        return step();
    }
    let guard = WHOLE.lock().unwrap_or_else(|e| e.into_inner());
    if exiting() {
        drop(guard);
        wait_for_exit();
    }
    /// Clears [`IN_WHOLE`] however the step ends (a panic included).
    struct Leave;
    impl Drop for Leave {
        fn drop(&mut self) {
            IN_WHOLE.with(|c| c.set(false));
        }
    }
    IN_WHOLE.with(|c| c.set(true));
    let leave = Leave;
    let out = step();
    drop(leave);
    drop(guard);
    out
}

/// Set once an interrupt is ending the process ([`remove_pending_for_exit`]): from then on no
/// output file is created ([`crate::files::create_output`] refuses), so none appears after the
/// registered ones are removed.
static EXITING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether an interrupt is ending the process ([`remove_pending_for_exit`]).
pub fn exiting() -> bool {
    EXITING.load(Ordering::SeqCst)
}

/// For a thread that finds the process ending ([`exiting`]): waits for the interrupt's exit
/// (at most [`EXIT_GRACE`] away), so that the thread neither creates a file the cleanup would
/// miss nor ends the process first with another exit code (a command refused its output, exit
/// 73, where the interrupt's is 130: review's a_failed_or_interrupted_command_leaves_no_lock).
pub fn wait_for_exit() -> ! {
    loop {
        std::thread::park();
    }
}

/// How long [`remove_pending_for_exit`] lets a write already under way finish before it removes
/// the registered files again.
const EXIT_GRACE: std::time::Duration = std::time::Duration::from_millis(50);

/// For an interrupt that ends the process (`crate::signals`): no output file is created from now
/// on ([`exiting`]) and no [`whole`] step begins; a step under way is waited for; then every
/// registered file is removed, and removed again after [`EXIT_GRACE`]; then the registered
/// notes are said ([`on_interrupt`]).
/// The second pass is for a write that was already opening a registered file by its path when
/// the first pass removed it (a figure's encoder, the mark rewriting it: both create the file
/// anew): the signal is answered on its own thread while the command's thread runs on, so a
/// single pass left `.trajectory.png.PID.tmp.png` behind now and then (runs_guard's
/// ctrl_c_during_plot_leaves_no_temporary_figure, under load).
pub fn remove_pending_for_exit() {
    EXITING.store(true, Ordering::SeqCst);
    // A step under way ends first (held to the exit: none begins after it).
    let _whole = WHOLE.lock().unwrap_or_else(|e| e.into_inner());
    remove_pending();
    std::thread::sleep(EXIT_GRACE);
    remove_pending();
    say_notes();
}

/// Removes every registered file, then every registered directory that is empty (best effort:
/// a file already gone, or a directory holding a file, is no error).
pub fn remove_pending() {
    let list = PENDING.lock().unwrap_or_else(|e| e.into_inner());
    for (_, p, _) in list.iter().filter(|(_, _, dir)| !dir) {
        let _ = std::fs::remove_file(p);
    }
    // The innermost first (registered last): `CMP/LAW` before `CMP`.
    for (_, p, _) in list.iter().rev().filter(|(_, _, dir)| *dir) {
        let _ = std::fs::remove_dir(p);
    }
}

/// Whether a process with id `pid` exists (`kill(pid, 0)` does not fail with ESRCH); `true`
/// where that cannot be told.
#[cfg(unix)]
fn process_exists(pid: u32) -> bool {
    let Ok(p) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: signal 0 sends nothing; it only checks the process.
    let r = unsafe { libc::kill(p, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

#[cfg(not(unix))]
fn process_exists(_pid: u32) -> bool {
    true
}

/// Removes the temporary files (`.NAME.PID.tmp`, [`crate::files::temp_beside`]) of `names` in
/// `dir` that a process no longer running left (killed with SIGKILL, or before this cleanup
/// existed): for a command holding `dir`'s lock, so no other command writes there. Files of
/// this process or of a running one are kept.
pub fn remove_stale_temporaries(dir: &Path, names: &[&str]) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let file_name = e.file_name();
        let Some(n) = file_name.to_str() else {
            continue;
        };
        let stale = names.iter().any(|name| {
            n.strip_prefix('.')
                .and_then(|r| r.strip_prefix(name))
                .and_then(|r| r.strip_prefix('.'))
                .and_then(|r| r.strip_suffix(".tmp"))
                .filter(|pid| !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|pid| pid.parse::<u32>().ok())
                .is_some_and(|pid| pid != std::process::id() && !process_exists(pid))
        });
        if stale && e.file_type().is_ok_and(|t| t.is_file()) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file is listed for removal while its [`Pending`] lives, and no longer once dropped
    /// (the removal itself, which touches every registered file of the process, is tested
    /// through the binary: `tests/review.rs`).
    #[test]
    fn files_are_listed_while_registered() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        let listed = |p: &Path| {
            PENDING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .iter()
                .any(|(_, q, _)| q == p)
        };
        let pa = register(&a);
        drop(register(&b));
        assert!(listed(&a));
        assert!(!listed(&b));
        drop(pa);
        assert!(!listed(&a));
    }

    /// A directory is listed for removal as a directory (removed only when empty, after the
    /// files: exercised through the binary, `runs_guard.rs`
    /// `an_interrupted_compare_leaves_every_law_whole_and_no_stale_table`) while its
    /// [`Pending`] lives.
    #[test]
    fn a_directory_is_listed_as_one() {
        let dir = tempfile::tempdir().unwrap();
        let law = dir.path().join("pid");
        let kind = || {
            PENDING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .iter()
                .find(|(_, q, _)| *q == law)
                .map(|(_, _, d)| *d)
        };
        let p = register_dir(&law);
        assert_eq!(kind(), Some(true));
        drop(p);
        assert_eq!(kind(), None);
    }

    /// att48-5: each level [`create_dir_all`] creates is listed as a directory, the innermost
    /// last (removed first); an existing level is not listed.
    #[test]
    fn each_created_level_is_listed_innermost_last() {
        let dir = tempfile::tempdir().unwrap();
        let c = dir.path().join("a").join("b").join("c");
        let listed = || -> Vec<PathBuf> {
            PENDING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .iter()
                .filter(|(_, q, d)| *d && q.starts_with(dir.path()))
                .map(|(_, q, _)| q.clone())
                .collect()
        };
        let held = create_dir_all(&c).unwrap();
        assert!(c.is_dir());
        let a = dir.path().join("a");
        assert_eq!(listed(), vec![a.clone(), a.join("b"), c.clone()]);
        drop(held);
        assert_eq!(listed(), Vec::<PathBuf>::new());
        let again = create_dir_all(&c.join("d")).unwrap();
        assert_eq!(listed(), vec![c.join("d")]);
        drop(again);
    }

    /// att53o-2: a `..` through a level not there yet is resolved in the text (the directory
    /// the system would reach once the level were made), one above the missing part is kept
    /// for the system; a path whose missing part has no `..` is returned as written, and so
    /// is the existing part (`u/./b/..` kept: the system resolves it).
    #[test]
    fn a_parent_step_through_a_missing_level_is_settled() {
        let dir = tempfile::tempdir().unwrap();
        let u = dir.path().join("u");
        std::fs::create_dir(&u).unwrap();
        std::fs::create_dir(u.join("e")).unwrap();
        let s = |rel: &str| settled_dir(&dir.path().join(rel));
        let at = |rel: &str| dir.path().join(rel);
        assert_eq!(s("u/b/../c"), at("u/c"));
        assert_eq!(s("x/../u/b"), at("u/b"));
        assert_eq!(s("u/b/c/../../d"), at("u/d"));
        assert_eq!(s("u/b/../../z"), at("u/../z"));
        assert_eq!(s("u/b/.."), at("u"));
        // Nothing to settle: as written, byte for byte.
        assert_eq!(s("u/b/c"), at("u/b/c"));
        assert_eq!(s("u/./b//c"), at("u/./b//c"));
        assert_eq!(s("u/e/../c"), at("u/e/../c"));
        assert_eq!(settled_dir(Path::new("n0ne/..")), PathBuf::from("."));
    }

    /// A [`whole`] step marks its thread for its length (a step inside it is part of it), and
    /// the mark goes however the step ends, a panic included; no interrupt is under way here,
    /// so every step runs.
    #[test]
    fn a_whole_step_marks_its_thread_while_it_runs() {
        assert!(!in_whole());
        let v = whole(|| {
            assert!(in_whole());
            whole(|| assert!(in_whole()));
            assert!(in_whole());
            7
        });
        assert_eq!(v, 7);
        assert!(!in_whole());
        let r = std::panic::catch_unwind(|| whole(|| panic!("step failed")));
        assert!(r.is_err());
        assert!(!in_whole());
        assert_eq!(whole(|| 1), 1, "the lock is free again after a panic");
    }

    /// att43-14: the temporary file of [`crate::files::write_atomic`] (`report`'s page, a
    /// summary, a sweep's files) is listed for removal on an interrupt while it is written, and
    /// no longer once renamed into place (or removed after a failed write). Before, only
    /// `run`'s trace and the lock were: Ctrl-C during `report`'s write left `.NAME.PID.tmp`.
    #[test]
    fn an_atomic_write_lists_its_temporary_while_writing() {
        use std::io::Write;
        let dir = tempfile::tempdir().unwrap();
        let page = dir.path().join("x.html");
        let tmp = crate::files::temp_beside(&page);
        let listed = || {
            PENDING
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .iter()
                .any(|(_, q, _)| *q == tmp)
        };
        crate::files::write_atomic_with(&page, |f| {
            f.write_all(b"<html>")?;
            assert!(listed(), "{} not listed while written", tmp.display());
            Ok(())
        })
        .unwrap();
        assert!(!listed());
        assert!(!tmp.exists());
        assert_eq!(std::fs::read(&page).unwrap(), b"<html>");
        let e = crate::files::write_atomic_with(&page, |f| {
            f.write_all(b"half")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(e.is_err());
        assert!(!listed() && !tmp.exists());
        assert_eq!(std::fs::read(&page).unwrap(), b"<html>");
    }

    /// A `.trace.csv.PID.tmp` of a process that no longer exists is removed; this process's,
    /// another name's and a non-number's are kept.
    #[cfg(unix)]
    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        // A child that has exited and been waited for: its pid names no process (until the
        // system reuses it, which does not happen within this test on any usual pid range).
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let me = std::process::id();
        let names = [
            format!(".trace.csv.{dead}.tmp"),
            format!(".trace.csv.{me}.tmp"),
            format!(".notes.txt.{dead}.tmp"),
            ".trace.csv.x1.tmp".to_string(),
        ];
        for n in &names {
            std::fs::write(dir.path().join(n), "x").unwrap();
        }
        remove_stale_temporaries(dir.path(), &["trace.csv", "summary.json"]);
        let left: Vec<bool> = names.iter().map(|n| dir.path().join(n).exists()).collect();
        assert_eq!(left, [false, true, true, true]);
    }

    /// att55o-1: a `..` after a link that is there is the system's to resolve (the link's
    /// target's parent), a `..` after a level not there yet is taken off in the text: with
    /// `L -> elsewhere/deep`, `x/../L/../c` (no `x`) is `L/../c`, made as `elsewhere/c`;
    /// `u/b/../c` (no `u/b`) is `u/c`; a path without `..` is returned as it is.
    #[cfg(unix)]
    #[test]
    fn a_dot_dot_after_a_link_is_not_taken_off_in_the_text() {
        let base = tempfile::tempdir().unwrap();
        let b = base.path();
        std::fs::create_dir_all(b.join("elsewhere/deep")).unwrap();
        std::fs::create_dir(b.join("u")).unwrap();
        std::os::unix::fs::symlink(b.join("elsewhere/deep"), b.join("L")).unwrap();
        let settled = settled_dir(&b.join("x/../L/../c"));
        assert_eq!(settled, b.join("L/../c"));
        create_dir_all(&settled).unwrap();
        assert!(b.join("elsewhere/c").is_dir());
        assert!(!b.join("c").exists() && !b.join("x").exists());
        assert_eq!(settled_dir(&b.join("u/b/../c")), b.join("u/c"));
        assert_eq!(settled_dir(&b.join("x/../u/b")), b.join("u/b"));
        assert_eq!(settled_dir(&b.join("L/../../u")), b.join("L/../../u"));
        assert_eq!(settled_dir(&b.join("p/q")), b.join("p/q"));
    }
}
