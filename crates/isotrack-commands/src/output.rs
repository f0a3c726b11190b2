//! Run outputs: the trace CSV, the summary JSON and the resolved scenario, and the check that an
//! output is not one of the inputs (their format and the one run-directory writer live in
//! `isotrack-runs`, re-exported here).

pub use isotrack_runs::files::same_file;
pub use isotrack_runs::rundir::{input_clash, input_files, RunDir, RUN_FILES};
pub use isotrack_runs::summary::{scenario_toml, Summary};
pub use isotrack_runs::trace::{num, run_to_trace, TraceWriter, TELEMETRY_COLUMNS, TRACE_COLUMNS};
