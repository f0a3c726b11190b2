//! The `isotrack` binary: the command line of [`isotrack_cli::entry::main_with`] over the
//! process's arguments.
use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(isotrack_cli::entry::main_with(std::env::args_os()))
}
