//! # isotrack-cli
//!
//! The thin command-line layer: argument parsing ([`cli`]), the commands, and the run outputs
//! ([`output`]: `trace.csv`, `summary.json`, the resolved `scenario.toml`).
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
