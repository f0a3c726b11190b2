//! The `isotrack` binary: the command line of [`isotrack_commands::entry::main_with`] over the
//! process's arguments (the parser and the commands live in the `isotrack-commands` library, which
//! the Python package's `isotrack` command calls too).
use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(isotrack_commands::entry::main_with(std::env::args_os()))
}
