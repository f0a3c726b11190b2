//! A command's failure (its message and exit code) and the exit codes.

/// A command's failure: the message and the exit code.
#[derive(Debug)]
pub struct Failure {
    /// Exit code (see [`exit`]).
    pub code: u8,
    /// What to print on stderr.
    pub message: String,
}

/// A failure with exit code `code`.
pub fn fail(code: u8, message: String) -> Failure {
    Failure { code, message }
}

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
    /// `fly`: a failsafe (Ctrl-C, `--max-duration-s`, a lost sensor or link, ...) before the
    /// companion had control of the vehicle: it stops and commands nothing (a pilot's or a
    /// disarmed vehicle keeps its mode), so no way out is claimed either way (outside
    /// sysexits' range, which has no such meaning).
    pub const NOTHING_COMMANDED: u8 = 79;
    /// An operating-system error: threads or other resources could not be had.
    pub const OSERR: u8 = 71;
    /// An output file or directory cannot be created or written (standard output included,
    /// unless its reader closed it: that exits [`OK`]), or is locked by another command.
    pub const CANTCREAT: u8 = 73;
}

/// A scenario error as a failure: [`exit::NOINPUT`] when the file, or a file it names
/// (`field.path`), cannot be read (missing, a FIFO, a directory, a device, too big),
/// [`exit::DATAERR`] when what it holds is invalid.
pub fn scenario_failure(e: isotrack_scenario::ScenarioError) -> Failure {
    Failure {
        code: if e.is_unreadable_input() {
            exit::NOINPUT
        } else {
            exit::DATAERR
        },
        message: e.to_string(),
    }
}
