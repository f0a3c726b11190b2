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

/// Process exit codes (BSD `sysexits.h`, the convention for command-line tools).
pub mod exit {
    /// Success: the run executed, whatever its outcome.
    pub const OK: u8 = 0;
    /// Command-line usage error: a malformed command line (clap's errors are mapped here) or an
    /// option value out of its range (`--shard 4/3`, `--spacing-m 0`, `--airspeed-mps 80`).
    pub const USAGE: u8 = 64;
    /// Invalid input data: a malformed or invalid scenario or override.
    pub const DATAERR: u8 = 65;
    /// An input file does not exist or cannot be read.
    pub const NOINPUT: u8 = 66;
    /// `fly`: a failsafe the vehicle did not confirm (no acknowledgement nor the mode in its
    /// heartbeat), or no vehicle to command.
    pub const UNAVAILABLE: u8 = 69;
    /// `fly`: the flight was ended by a failsafe (or a refused take-over) and the vehicle
    /// confirmed the way out (HOLD/RETURN, or the disarm): the vehicle is safe, the flight did
    /// not complete (`EX_TEMPFAIL`).
    pub const FAILSAFE: u8 = 75;
    /// An operating-system error: threads or other resources could not be had.
    pub const OSERR: u8 = 71;
    /// An output file or directory cannot be created or written (standard output included,
    /// unless its reader closed it: that exits [`OK`]), or is locked by another command.
    pub const CANTCREAT: u8 = 73;
}
