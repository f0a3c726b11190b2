//! `summary.json` and the resolved `scenario.toml` of a run directory.

use isotrack_scenario::{Scenario, ScenarioFile};
use isotrack_sim::RunResult;
use serde::Serialize;
use std::collections::BTreeMap;
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
    /// The SHA-256 of each data file the field was read from (`field.path`, `field.paths`), by
    /// its absolute path ([`data_file_digests`]); left out when there are none. `plot` and
    /// `report` refuse runs whose files differ (one overwritten in place between them).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub data_files: BTreeMap<String, String>,
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
        data_files: data_file_digests(scenario),
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

/// The resolved scenario as TOML (reads back as the same scenario, bit for bit; floats in
/// their shortest form, [`isotrack_scenario::tomltext::to_toml`]).
pub fn scenario_toml(scenario: &Scenario) -> String {
    isotrack_scenario::tomltext::to_toml(scenario.file())
        .unwrap_or_else(|e| format!("# cannot render: {e}\n"))
}

/// The SHA-256 of each data file of `scenario`'s field (`field.path`, `field.paths`, absolute
/// in a resolved scenario), by path ([`crate::files::sha256_file`]); a file that cannot be read
/// now (gone since the field was built) is left out.
pub fn data_file_digests(scenario: &Scenario) -> BTreeMap<String, String> {
    let f = &scenario.file().field;
    f.path
        .iter()
        .chain(f.paths.iter().flatten())
        .filter_map(|p| {
            crate::files::sha256_file(Path::new(p))
                .ok()
                .map(|d| (p.clone(), d))
        })
        .collect()
}
