//! The command line as a function: parse arguments, dispatch, map failures to exit codes. The
//! `isotrack` binary is this over the process's arguments; the Python package's `isotrack`
//! command calls the same function through its native module (one build for both).

use crate::cli::{Cli, Command};
use clap::Parser;
use std::ffi::OsString;

/// Makes Ctrl-C, SIGTERM and SIGHUP remove the lock and temporary files the command holds and
/// exit 130 / 143 / 129 ([`isotrack_runs::signals::remove_on_interrupt`]); the binary calls it
/// first.
pub fn remove_on_interrupt() {
    isotrack_runs::signals::remove_on_interrupt();
}

/// Waits for the interrupt's exit when one is ending the process
/// ([`isotrack_runs::cleanup::exiting`]): the binary calls it after [`main_with`], so that a
/// command ending meanwhile does not exit first with its own code.
pub fn wait_if_interrupted() {
    if isotrack_runs::cleanup::exiting() {
        isotrack_runs::cleanup::wait_for_exit();
    }
}

/// Runs the command line `args` (the program name first) and returns its exit code (README,
/// "Exit codes"); errors are printed on stderr as `error: ...`.
pub fn main_with<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    // clap's own errors exit 2 by default; every usage error of isotrack exits 64 (one table,
    // README "Exit codes"), so they are mapped here. Help and version exit 0.
    let cli = match Cli::try_parse_from(args) {
        Ok(c) => c,
        Err(e) => {
            // Through the console like every other line: the user's arguments echoed in a
            // usage error are escaped, and help or version text that cannot be written
            // (`isotrack --help > /dev/full`) is an I/O error, not a success.
            let text = e.render().to_string();
            if e.use_stderr() {
                crate::console::write_err(format_args!("{text}"));
                return crate::exit::USAGE;
            }
            crate::console::write_out(format_args!("{text}"));
            return stdout_exit_code();
        }
    };
    let result = match &cli.command {
        Command::Run(args) => crate::run::run(args),
        Command::Show(args) => crate::run::show(args),
        Command::Check(args) => crate::run::check(args),
        Command::Compare(args) => crate::compare::compare(args),
        Command::Plot(args) => crate::figures::plot(args),
        Command::Figures(args) => crate::figures::figures(args),
        Command::Sweep(args) => crate::sweep::sweep(args),
        Command::Merge(args) => crate::sweep::merge(args),
        Command::Trim(args) => crate::aircraft::trim(args),
        Command::Replay(args) => crate::aircraft::replay(args),
        Command::Interpolate(args) => crate::interpolate::interpolate(args),
        Command::Benchmark(args) => crate::league::benchmark(args),
        Command::Report(args) => crate::league::report(args),
        Command::Sitl(args) => crate::mavlink::sitl(args),
        Command::Fly(args) => crate::mavlink::fly(args),
    };
    // A reader that closed standard output is not an error (exit 0); another failure to write
    // it is exit 73 unless the command failed first (see `crate::console`).
    match result {
        Ok(()) => stdout_exit_code(),
        Err(f) => {
            // A failure while an interrupt is removing the command's files and ending the
            // process is the cleanup's doing (a directory it created and removed, a temporary
            // gone), not the command's: never printed (att51-3: "cannot write a/b/c: No such
            // file or directory" for a directory the interrupt removed); the interrupt's own
            // lines say what was left.
            wait_if_interrupted();
            crate::errln!("error: {}", f.message);
            f.code
        }
    }
}

/// The exit code of a command that did its work: 0, or 73 when standard output could not be
/// written for another reason than a reader that closed it (see `crate::console`).
fn stdout_exit_code() -> u8 {
    match crate::console::stdout_failure() {
        None => crate::exit::OK,
        Some(why) => {
            crate::errln!("error: cannot write standard output: {why}");
            crate::exit::CANTCREAT
        }
    }
}
