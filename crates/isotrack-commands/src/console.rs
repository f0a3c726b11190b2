//! Standard output and standard error, written so that a reader that goes away never crashes a
//! command (issue 30, item 13).
//!
//! `println!` panics when its write fails: `isotrack check | head -c1` closes the pipe after one
//! byte, the next `println!` meets `EPIPE` (Rust ignores `SIGPIPE`, so the write returns the
//! error) and the process dies with exit 101 and a backtrace. Every line the commands print goes
//! through [`out!`](crate::out), [`outln!`](crate::outln) and [`errln!`](crate::errln) instead,
//! which write through [`write_out`] / [`write_err`]:
//!
//! * a closed pipe (`BrokenPipe`) on either stream: the reader is gone, so nothing more is
//!   written to that stream and the command finishes its work (files it writes are written
//!   whole); the process then exits 0 (README, "Exit codes": output nobody reads is not an
//!   error, as for `yes | head`);
//! * any other write error on standard output (`isotrack show > /full/disk`): nothing more is
//!   written there and the process exits 73 (an output cannot be written), saying why on
//!   standard error.
//!
//! `main` asks [`stdout_failure`] once the command has returned. The crate denies
//! `clippy::print_stdout` and `clippy::print_stderr`, so this module is the only way out.
//!
//! Text written by [`out!`](crate::out), [`outln!`](crate::outln) and [`errln!`](crate::errln)
//! is escaped on the way ([`isotrack_core::numtext::Escaped`]): a control character a terminal
//! would obey (ESC, BEL, CR, other C0 and C1 controls, bidi overrides) in a file name, key,
//! value or task name the user gave is shown as `\x1b`, `\u{202e}`, never acted on, and a line
//! longer than [`MAX_LINE_CHARS`] is cut there with `... (N more characters)`. Data
//! printed for programs (`show`'s TOML, `--json`) goes through [`out_data!`](crate::out_data)
//! unchanged: its own format escapes what it must.

use std::fmt;
use std::io::{ErrorKind, Write};
use std::sync::Mutex;

/// What went wrong on a stream: nothing yet, its reader closed it, or another error.
#[derive(Clone, Debug, Default, PartialEq)]
enum StreamState {
    #[default]
    Open,
    Closed,
    Failed(String),
}

/// The state of standard output and standard error (one lock each: lines from the sweep's
/// threads stay whole).
static STDOUT: Mutex<StreamState> = Mutex::new(StreamState::Open);
static STDERR: Mutex<StreamState> = Mutex::new(StreamState::Open);

std::thread_local! {
    /// Set while [`quietly`] runs a command's function on this thread: nothing is printed.
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` with everything it would print on this thread dropped: the library callers' way
/// (the Python package's `plot`, `report`, `sweep`), which return what they wrote instead of
/// printing "wrote ..." or notes into a user's program.
pub fn quietly<R>(f: impl FnOnce() -> R) -> R {
    let before = QUIET.with(|q| q.replace(true));
    struct Restore(bool);
    impl Drop for Restore {
        fn drop(&mut self) {
            QUIET.with(|q| q.set(self.0));
        }
    }
    let _restore = Restore(before);
    f()
}

fn write_to(state: &Mutex<StreamState>, w: &mut dyn Write, args: fmt::Arguments<'_>, escape: bool) {
    if QUIET.with(|q| q.get()) {
        return;
    }
    let mut st = state.lock().unwrap_or_else(|p| p.into_inner());
    if *st != StreamState::Open {
        return;
    }
    let written = if escape {
        w.write_all(clip_lines(&args.to_string(), MAX_LINE_CHARS).as_bytes())
    } else {
        w.write_fmt(args)
    };
    if let Err(e) = written.and_then(|()| w.flush()) {
        *st = if e.kind() == ErrorKind::BrokenPipe {
            StreamState::Closed
        } else {
            StreamState::Failed(e.to_string())
        };
    }
}

/// The longest line a message prints, in characters: the last bound on a message that echoes
/// something long the user wrote (a 900 000-character path, a 40 000-character `--set` value),
/// after the per-echo clip ([`isotrack_core::numtext::Clipped`]).
pub const MAX_LINE_CHARS: usize = 1000;

/// `text` line by line, each line's terminal controls and other non-plain characters (U+2028,
/// U+200B: [`isotrack_core::numtext::is_escaped`]) escaped and a line longer than `max`
/// characters (as shown) cut there with `... (N more characters)`
/// ([`isotrack_core::numtext::Clipped`]). The line feeds between the lines are the message's
/// own; one inside user text was escaped where the text was put in the message.
pub fn clip_lines(text: &str, max: usize) -> std::borrow::Cow<'_, str> {
    if text
        .split('\n')
        .all(|l| l.len() <= max && !l.chars().any(isotrack_core::numtext::is_escaped))
    {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len().min(16 * max));
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(&isotrack_core::numtext::Clipped::with_limit(line, max).to_string());
    }
    std::borrow::Cow::Owned(out)
}

/// Writes text to standard output, terminal controls escaped (see the module docs for what a
/// failed write does).
pub fn write_out(args: fmt::Arguments<'_>) {
    write_to(&STDOUT, &mut std::io::stdout().lock(), args, true);
}

/// Writes data (TOML, JSON) to standard output as it is: its format escapes what it must.
pub fn write_out_data(args: fmt::Arguments<'_>) {
    write_to(&STDOUT, &mut std::io::stdout().lock(), args, false);
}

/// Writes to standard error (a closed or failing standard error silences it: there is nowhere
/// left to say anything).
pub fn write_err(args: fmt::Arguments<'_>) {
    write_to(&STDERR, &mut std::io::stderr().lock(), args, true);
}

/// Why standard output could not be written, when the reason is not a reader that went away:
/// `main` turns it into exit 73. `None` when everything printed was written, or when the reader
/// closed the pipe (not an error).
pub fn stdout_failure() -> Option<String> {
    match &*STDOUT.lock().unwrap_or_else(|p| p.into_inner()) {
        StreamState::Failed(why) => Some(why.clone()),
        StreamState::Open | StreamState::Closed => None,
    }
}

/// `print!` that never panics (see [`crate::console`]).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::console::write_out(format_args!($($arg)*))
    };
}

/// `print!` of data for programs (TOML, JSON), written unescaped, that never panics (see
/// [`crate::console`]).
#[macro_export]
macro_rules! out_data {
    ($($arg:tt)*) => {
        $crate::console::write_out_data(format_args!($($arg)*))
    };
}

/// `println!` that never panics (see [`crate::console`]).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::console::write_out(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::console::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `eprintln!` that never panics (see [`crate::console`]).
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::console::write_err(format_args!("{}\n", format_args!($($arg)*)))
    };
}
