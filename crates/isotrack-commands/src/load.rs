//! Loading the scenario a command names, and a scenario error as a command's failure (used by
//! every command; apart from `run.rs` so that the commands `run` calls, `figures` and
//! `checkmap`, do not import it back).

use crate::cli::ScenarioArgs;
use crate::exit;
use isotrack_runs::Failure;
use isotrack_scenario::{load_scenario, Scenario, ScenarioError};

/// A scenario error as a failure: 66 when the file, or a file it names (`field.path`), cannot
/// be read (missing, a FIFO, a directory, a device, too big), 65 when what it holds is invalid.
pub fn invalid(e: ScenarioError) -> Failure {
    Failure {
        code: if e.is_unreadable_input() {
            exit::NOINPUT
        } else {
            exit::DATAERR
        },
        message: e.to_string(),
    }
}

/// Loads the scenario named by the arguments.
pub fn load(args: &ScenarioArgs) -> Result<Scenario, Failure> {
    load_scenario(args.scenario.as_deref(), &args.set).map_err(invalid)
}
