//! `summary.json` and the resolved `scenario.toml` of a run directory.

use isotrack_scenario::{Scenario, ScenarioFile};
use isotrack_sim::RunResult;
use serde::Serialize;
use std::path::Path;

/// The content of `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary<'a> {
    /// isotrack's version.
    pub isotrack_version: &'static str,
    /// The scenario file as given, or `null` for the built-in default.
    pub scenario_path: Option<String>,
    /// The run's outcome and metrics (flattened: `outcome`, `steady_state_max_abs_error`, ...).
    #[serde(flatten)]
    pub result: &'a RunResult,
    /// Warnings about the scenario (also printed on stderr): noise through a backward
    /// difference, a sampled loop that `isotrack check` finds unstable.
    pub warnings: &'a [String],
    /// The fully resolved scenario.
    pub scenario: &'a ScenarioFile,
}

/// Writes `summary.json` (pretty-printed; non-finite or undefined metrics are `null`),
/// atomically ([`crate::files::write_atomic`]): a reader sees no summary or a whole one.
pub fn write_summary(
    path: &Path,
    scenario: &Scenario,
    scenario_path: Option<&Path>,
    result: &RunResult,
    warnings: &[String],
) -> std::io::Result<()> {
    let s = Summary {
        isotrack_version: env!("CARGO_PKG_VERSION"),
        scenario_path: scenario_path.map(|p| p.display().to_string()),
        result,
        warnings,
        scenario: scenario.file(),
    };
    let text = summary_to_json(&s).map_err(std::io::Error::other)?;
    crate::files::write_atomic(path, (text + "\n").as_bytes())
}

/// `summary.json`'s text (pretty-printed; non-finite metrics are `null`): one rendering for the
/// file and for the Python package.
pub fn summary_to_json(s: &Summary<'_>) -> serde_json::Result<String> {
    serde_json::to_string_pretty(s)
}

/// The resolved scenario as TOML (reads back as the same scenario).
pub fn scenario_toml(scenario: &Scenario) -> String {
    toml::to_string(scenario.file()).unwrap_or_else(|e| format!("# cannot render: {e}\n"))
}
