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
    /// A team's run (`[team]`): the team metrics; left out for one vehicle. The flattened
    /// top-level metrics are then vehicle 0's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub team: Option<TeamJson<'a>>,
    /// A team's run: every vehicle's outcome and metrics, in the listed order.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vehicles: Option<&'a [RunResult]>,
    /// The fully resolved scenario.
    pub scenario: &'a ScenarioFile,
}

/// The `team` object of `summary.json`.
#[derive(Debug, Serialize)]
pub struct TeamJson<'a> {
    /// Vehicles in the team.
    pub vehicle_count: usize,
    /// `team.spacing`.
    pub spacing: &'static str,
    /// Whether the spacing law uses only ranges and neighbour identities (`arc_reference`
    /// does not: a reference).
    pub coordinate_free: bool,
    /// Each vehicle's `[ahead, behind]` neighbours at the end (`null`: none known).
    pub neighbours: &'a [Option<[u32; 2]>],
    /// The team metrics along the true isoline (`gap_cv`, `time_to_even_s`,
    /// `revisit_time_max_s`, `revisit_time_mean_s`, `revisit_time_ideal_s`, `min_separation_m`,
    /// `order_preserved`, ...); left out where the isoline has no arc-length projection
    /// ([`TeamJson::metrics_note`] says so).
    #[serde(flatten)]
    pub metrics: Option<&'a isotrack_sim::team::metrics::TeamSummary>,
    /// Why the metrics are left out.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub metrics_note: Option<&'static str>,
}

impl<'a> TeamJson<'a> {
    /// The `team` object of a team run of `scenario`.
    pub fn new(scenario: &Scenario, r: &'a isotrack_sim::TeamResult) -> Self {
        let law = scenario
            .spec()
            .team
            .as_ref()
            .map(|t| t.law)
            .unwrap_or(isotrack_sim::team::spacing::SpacingLaw::None);
        Self {
            vehicle_count: r.runs.len(),
            spacing: law.name(),
            coordinate_free: law.is_coordinate_free(),
            neighbours: &r.ring,
            metrics: r.team.as_ref(),
            metrics_note: r.team.is_none().then(|| scenario.team_metrics_note()),
        }
    }
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
    write_summary_team(path, scenario, scenario_path, result, warnings, None)
}

/// [`write_summary`] for any run: with `team`, the top-level metrics are vehicle 0's (`result`),
/// and the `team` object and `vehicles` array are added.
pub fn write_summary_team(
    path: &Path,
    scenario: &Scenario,
    scenario_path: Option<&Path>,
    result: &RunResult,
    warnings: &[String],
    team: Option<&isotrack_sim::TeamResult>,
) -> std::io::Result<()> {
    let s = Summary {
        isotrack_version: env!("CARGO_PKG_VERSION"),
        scenario_path: scenario_path.map(|p| p.display().to_string()),
        result,
        warnings,
        data_files: data_file_digests(scenario),
        team: team.map(|t| TeamJson::new(scenario, t)),
        vehicles: team.map(|t| t.runs.as_slice()),
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
