//! The process's signal handling, in one place, on `signal-hook` (its handler only writes the
//! signal into a pipe, async-signal-safe; a thread of this module reads it and answers). A
//! command answers SIGINT (Ctrl-C), SIGTERM and SIGHUP (the terminal or ssh session closed) one
//! of two ways:
//!
//! * [`remove_on_interrupt`] (the command-line program, once, before anything else): remove
//!   every file [`crate::cleanup::register`]ed (an output directory's lock file, a trace being
//!   streamed into its temporary file) and exit 128 + the signal (130, 143, 129), as the
//!   default action would, but without the litter (README: "the holder removes the file when
//!   done (an error and Ctrl-C included)").
//! * [`interrupt_flag`] (`fly`, `sitl`, `check --map --verify`: commands that stop cleanly, `fly`
//!   commanding its failsafe first): from then on a signal sets the returned flag instead, again
//!   at each signal (a second Ctrl-C ends the failsafe's retries), and the command ends itself;
//!   [`interrupted_exit_code`] is 128 + the signal it heard.
//!
//! A signal the process inherited as ignored (`trap '' INT`, a non-interactive shell's
//! `cmd &`, `nohup`) stays ignored, as shells expect. A library user (the Python package) keeps
//! its own handling: nothing is installed unless one of these is called.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::{Arc, Mutex};

/// The last signal received (0: none yet).
static LAST: AtomicI32 = AtomicI32::new(0);

/// The flags a signal sets ([`interrupt_flag`]); none: a signal removes the registered files
/// and exits.
static FLAGS: Mutex<Vec<Arc<AtomicBool>>> = Mutex::new(Vec::new());

/// What a signal `sig` does: set the flags, or remove the registered files and exit.
fn received(sig: i32) {
    LAST.store(sig, Ordering::SeqCst);
    let flags = FLAGS.lock().unwrap_or_else(|e| e.into_inner());
    if flags.is_empty() {
        crate::cleanup::remove_pending_for_exit();
        std::process::exit(128 + sig);
    }
    for f in flags.iter() {
        f.store(true, Ordering::SeqCst);
    }
}

#[cfg(unix)]
mod unix {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    use signal_hook::iterator::Signals;
    use std::sync::OnceLock;

    /// Set once the handlers are installed (or their installation failed: not retried).
    static INSTALLED: OnceLock<()> = OnceLock::new();

    /// Whether the process was started with `sig` ignored (read before anything is installed).
    fn inherited_ignored(sig: libc::c_int) -> bool {
        // SAFETY: a zeroed `sigaction` is a valid value to be overwritten; sigaction(2) with a
        // null new action only reads the current one into `old`.
        let mut old: libc::sigaction = unsafe { std::mem::zeroed() };
        let read = unsafe { libc::sigaction(sig, std::ptr::null(), &mut old) };
        read == 0 && old.sa_sigaction == libc::SIG_IGN
    }

    /// Installs the handlers of SIGINT, SIGTERM and SIGHUP (each not inherited as ignored) and
    /// the thread that answers them; once per process.
    pub(super) fn install() {
        INSTALLED.get_or_init(|| {
            let wanted: Vec<libc::c_int> = [SIGINT, SIGTERM, SIGHUP]
                .into_iter()
                .filter(|&s| !inherited_ignored(s))
                .collect();
            let Ok(mut signals) = Signals::new(&wanted) else {
                return;
            };
            // If the thread cannot start, `signals` is dropped with the closure, which
            // unregisters the handlers: the default actions stay.
            let _ = std::thread::Builder::new()
                .name("isotrack-signals".into())
                .spawn(move || {
                    for sig in signals.forever() {
                        super::received(sig);
                    }
                });
        });
    }
}

fn install() {
    #[cfg(unix)]
    unix::install();
}

/// Makes SIGINT, SIGTERM and SIGHUP remove every [`crate::cleanup::register`]ed file and exit
/// 130, 143 or 129 (for the command-line program; once per process). Commands that stop
/// cleanly on a signal take it over with [`interrupt_flag`].
pub fn remove_on_interrupt() {
    install();
}

/// A flag that SIGINT (Ctrl-C), SIGTERM and SIGHUP set instead of ending the process, so that
/// the command stops cleanly (`fly` commands its failsafe mode first); every signal sets it
/// again (whoever clears the flag hears the next one). From this call on, no signal ends the
/// process nor removes the registered files: the command does both.
pub fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    FLAGS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(flag.clone());
    install();
    flag
}

/// The exit code of a command stopped by a signal through [`interrupt_flag`]: 128 + the last
/// signal received (130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP; 130 if none was).
pub fn interrupted_exit_code() -> u8 {
    match LAST.load(Ordering::SeqCst) {
        sig @ 1..=127 => 128 + sig as u8,
        _ => 130,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A signal after [`interrupt_flag`] sets every flag and is remembered for the exit code
    /// (128 + the signal); nothing exits.
    #[test]
    fn a_signal_sets_the_flags_and_names_the_exit_code() {
        let (a, b) = (interrupt_flag(), interrupt_flag());
        received(15);
        assert!(a.load(Ordering::SeqCst) && b.load(Ordering::SeqCst));
        assert_eq!(interrupted_exit_code(), 143);
        a.store(false, Ordering::SeqCst);
        received(1);
        assert!(
            a.load(Ordering::SeqCst),
            "a cleared flag hears the next signal"
        );
        assert_eq!(interrupted_exit_code(), 129);
    }
}
