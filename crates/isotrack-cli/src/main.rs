//! The `isotrack` binary: the command line of [`isotrack_commands::entry::main_with`] over the
//! process's arguments (the parser and the commands live in the `isotrack-commands` library, which
//! the Python package's `isotrack` command calls too).
use std::process::ExitCode;

fn main() -> ExitCode {
    // Ctrl-C, SIGTERM and SIGHUP remove the lock and temporary files a command holds, then
    // exit 130 / 143 / 129 (issue 30, att30b item 10; att30c-7).
    isotrack_commands::entry::remove_on_interrupt();
    let code = isotrack_commands::entry::main_with(std::env::args_os());
    // A command that ended while an interrupt is ending the process (its files being removed,
    // its exit 130 / 143 / 129 due within 50 ms) leaves the exit to the interrupt.
    isotrack_commands::entry::wait_if_interrupted();
    ExitCode::from(code)
}
