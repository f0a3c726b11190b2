//! # isotrack-commands
//!
//! The isotrack commands as a library: argument parsing ([`cli`]), the commands, and the run
//! outputs ([`output`], re-exported from `isotrack-runs`). [`entry::main_with`] is the whole
//! command line: the `isotrack` binary (crate `isotrack-cli`, its `main` only) and the Python
//! package's `isotrack` command both call it, so there is one implementation of the commands
//! and the Python package builds without the binary's crate.
#![deny(missing_docs)]
// Every line printed goes through `console` (a closed pipe never panics): issue 30, item 13.
#![deny(clippy::print_stdout, clippy::print_stderr)]

#[macro_use]
pub mod console;
pub mod aircraft;
pub mod check_text;
pub mod checkmap;
pub mod cli;
pub mod compare;
pub mod entry;
pub mod figures;
pub mod interpolate;
pub mod league;
pub mod mavlink;
pub mod output;
pub mod run;
pub mod sweep;

/// Process exit codes (BSD `sysexits.h`, the convention for command-line tools), defined in
/// `isotrack-runs` with the failures that carry them.
pub use isotrack_runs::exit;
