//! Run outputs: the trace CSV, the summary JSON and the resolved scenario (their format lives in
//! `isotrack-runs`, re-exported here), and the check that an output is not one of the inputs.

pub use isotrack_runs::files::same_file;
pub use isotrack_runs::summary::{scenario_toml, summary_to_json, write_summary, Summary};
pub use isotrack_runs::trace::{num, run_to_trace, TraceWriter, TELEMETRY_COLUMNS, TRACE_COLUMNS};
use isotrack_scenario::Scenario;
use std::path::{Path, PathBuf};

/// The files a command reads for `scenario`: the scenario file (if any) and the data files its
/// field names (`field.path`, `field.paths`: absolute once the scenario is built). An output
/// that is one of them is refused (64), never written over.
pub fn input_files(scenario_file: Option<&Path>, scenario: &Scenario) -> Vec<PathBuf> {
    let field = &scenario.file().field;
    scenario_file
        .map(Path::to_path_buf)
        .into_iter()
        .chain(field.path.iter().map(PathBuf::from))
        .chain(field.paths.iter().flatten().map(PathBuf::from))
        .collect()
}

/// When `output` is one of `inputs` (the same file, through links): the message that refuses it.
pub fn input_clash(inputs: &[PathBuf], output: &Path) -> Option<String> {
    let input = inputs.iter().find(|i| same_file(i, output))?;
    Some(format!(
        "{} is an input ({}): an output cannot be one of the inputs",
        output.display(),
        input.display()
    ))
}
