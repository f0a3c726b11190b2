//! `summary.json` and the resolved `scenario.toml` of a run directory.
//!
//! [`Summary`] is the one type of `summary.json`: every command that writes a run directory
//! (`run`, `compare`, `figures`, `sitl`, `fly`, the Python package's `Run.save`) writes it
//! through [`Summary::to_json`] ([`crate::rundir::RunDir`] writes it, atomically and last), and
//! every reader (`isotrack-plot`, the HTML report) reads it through [`Summary::read`] /
//! [`Summary::from_json`], whose errors name the file and the key.

use crate::results::{MetricsRecord, RunRecord};
use isotrack_scenario::Scenario;
use isotrack_sim::RunResult;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The largest `summary.json` read, bytes (a summary is a few kB; the scenario in it is capped at
/// 1 MiB as a file).
pub const MAX_SUMMARY_BYTES: u64 = 16 << 20;

/// The content of `summary.json`: who wrote it, from which scenario file, how the run ended
/// ([`Ended`], flattened: a simulated run's [`RunRecord`] or a flight's [`FlightRecord`]), and
/// the resolved scenario. `S` is the scenario's type: the resolved scenario itself when written
/// ([`Summary::of_run`]), its JSON when read back ([`Summary::read`]).
///
/// Non-finite or undefined numbers are `null` in the file and `None` here.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary<S = serde_json::Value> {
    /// isotrack's version.
    pub isotrack_version: String,
    /// The scenario file as given, or `null` for the built-in default.
    pub scenario_path: Option<String>,
    /// How the run ended, flattened into the top level (`outcome`, `t_end_s`, the metrics ...).
    #[serde(flatten)]
    pub ended: Ended,
    /// The fully resolved scenario.
    pub scenario: S,
    /// The controller that flew when it is not the scenario's own law (the Python package's
    /// `{"kind": "python", "class": ...}`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub controller: Option<serde_json::Value>,
}

/// How a run ended: a simulated run's record, or a flight's (`isotrack fly`: no metrics, the
/// link's counters instead). Told apart by `end_reason`, which only a flight has.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Ended {
    /// A flight flown by `isotrack fly`.
    Flight(FlightRecord),
    /// A run simulated by isotrack (also `sitl`'s, whose vehicle isotrack simulates).
    Run(RunEnd),
}

/// A simulated run's end: its record (outcome and metrics) and the warnings about its scenario.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunEnd {
    /// Outcome and metrics.
    #[serde(flatten)]
    pub record: RunRecord,
    /// Warnings about the scenario (also printed on stderr): noise through a backward
    /// difference, a sampled loop that `isotrack check` finds unstable; for `sitl`, its events.
    /// Empty when read from an older isotrack's summary, which has none (att41-14: `plot` and
    /// `report` refused it with serde's "missing field `warnings`", where `run --out` takes it
    /// for an earlier isotrack run, [`not_isotracks`]).
    #[serde(default)]
    pub warnings: Vec<String>,
    /// The SHA-256 of each data file the field was read from (`field.path`, `field.paths`), by
    /// its absolute path ([`data_file_digests`]); left out when there are none. `plot` and
    /// `report` refuse runs whose files differ (one overwritten in place between them).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub data_files: BTreeMap<String, String>,
    /// A team's run (`[team]`): the team metrics; left out for one vehicle. The flattened
    /// top-level record is then vehicle 0's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub team: Option<Box<TeamJson>>,
    /// A team's run: every vehicle's outcome and metrics, in the listed order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vehicles: Option<Vec<RunRecord>>,
}

/// The `team` object of `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TeamJson {
    /// Vehicles in the team.
    pub vehicle_count: usize,
    /// `team.spacing`.
    pub spacing: String,
    /// Whether the spacing law uses only ranges and neighbour identities (`arc_reference`
    /// does not: a reference).
    pub coordinate_free: bool,
    /// Each vehicle's `[ahead, behind]` neighbours at the end (`null`: none known).
    pub neighbours: Vec<Option<[u32; 2]>>,
    /// The team metrics along the true isoline ([`TeamRecord`]); left out where the isoline
    /// has no arc-length projection ([`TeamJson::metrics_note`] says so).
    #[serde(flatten)]
    pub metrics: Option<TeamRecord>,
    /// Why the metrics are left out.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics_note: Option<String>,
}

/// The team metrics of `summary.json`'s `team` object, with the names and in the order of
/// [`isotrack_sim::team::metrics::TeamSummary`]; a number that is not finite is `None`
/// (`null`, as serde writes a non-finite `f64`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TeamRecord {
    /// Vehicles in the team.
    pub count: usize,
    /// Length of the isoline, m.
    pub isoline_length_m: Option<f64>,
    /// Mean over the steady window of the coefficient of variation of the arc-length gaps.
    pub gap_cv: Option<f64>,
    /// The gap CV at the last sample.
    pub gap_cv_final: Option<f64>,
    /// First sample time from which the gap CV stays at or below `even_gap_cv`, s.
    pub time_to_even_s: Option<f64>,
    /// Longest time a point of the isoline went without a vehicle passing, s.
    pub revisit_time_max_s: Option<f64>,
    /// Mean time between consecutive passes over a point of the isoline, s.
    pub revisit_time_mean_s: Option<f64>,
    /// The ideal revisit time of an evenly spread team, `L/(N v0)`, s.
    pub revisit_time_ideal_s: Option<f64>,
    /// The ideal revisit time of the vehicles whose runs went on, over the steady window,
    /// `L / mean_k(sum of the live vehicles' v0_i)`, s: present only when a vehicle had gone
    /// at a steady-window sample (docs/TEAMS.md "Vehicles that end early").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub revisit_time_ideal_active_s: Option<f64>,
    /// Smallest distance between vehicles consecutive along the isoline, m.
    pub min_separation_m: Option<f64>,
    /// Whether the cyclic order of the vehicles held over the steady window.
    pub order_preserved: bool,
    /// Slowest and fastest speed any vehicle held at a sample, m/s.
    pub speed_range_mps: Option<[Option<f64>; 2]>,
    /// For an isoline that moves: how it was followed (left out otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub moving_isoline: Option<isotrack_sim::team::metrics::MovingIsolineStats>,
    /// For an open isoline (one that leaves the field): the stretch the team covers (left out
    /// for a closed one; docs/TEAMS.md "Open isolines").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_isoline: Option<isotrack_sim::team::metrics::OpenIsolineStats>,
}

/// `Some(x)` when `x` is finite (serde writes a non-finite `f64` as `null`).
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

impl TeamRecord {
    /// The record of the team metrics `m`.
    pub fn of(m: &isotrack_sim::team::metrics::TeamSummary) -> Self {
        let o = |x: Option<f64>| x.and_then(finite);
        TeamRecord {
            count: m.count,
            isoline_length_m: finite(m.isoline_length_m),
            gap_cv: o(m.gap_cv),
            gap_cv_final: o(m.gap_cv_final),
            time_to_even_s: o(m.time_to_even_s),
            revisit_time_max_s: o(m.revisit_time_max_s),
            revisit_time_mean_s: o(m.revisit_time_mean_s),
            revisit_time_ideal_s: finite(m.revisit_time_ideal_s),
            revisit_time_ideal_active_s: o(m.revisit_time_ideal_active_s),
            min_separation_m: o(m.min_separation_m),
            order_preserved: m.order_preserved,
            speed_range_mps: m.speed_range_mps.map(|r| r.map(finite)),
            moving_isoline: m.moving_isoline.clone(),
            open_isoline: m.open_isoline.clone(),
        }
    }
}

impl TeamJson {
    /// The `team` object of a team run `r` of `scenario`.
    pub fn new(scenario: &Scenario, r: &isotrack_sim::TeamResult) -> Self {
        let law = scenario
            .spec()
            .team
            .as_ref()
            .map(|t| t.law)
            .unwrap_or(isotrack_sim::team::spacing::SpacingLaw::None);
        Self {
            vehicle_count: r.runs.len(),
            spacing: law.name().to_string(),
            coordinate_free: law.is_coordinate_free(),
            neighbours: r.ring.clone(),
            metrics: r.team.as_ref().map(TeamRecord::of),
            metrics_note: r
                .team
                .is_none()
                .then(|| scenario.team_metrics_note().to_string()),
        }
    }
}

/// A flight's end (`isotrack fly --out`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FlightRecord {
    /// `completed` when the vehicle ended its run, `failsafe` after a failsafe, else the end
    /// reason.
    pub outcome: String,
    /// The last event.
    pub outcome_detail: String,
    /// Why the flight ended.
    pub end_reason: String,
    /// Whether a failsafe ended it.
    pub failsafe: bool,
    /// Whether the vehicle confirmed the failsafe mode.
    pub failsafe_acknowledged: bool,
    /// Time of the last measurement, s.
    pub t_end_s: Option<f64>,
    /// Measurements received.
    pub samples: u64,
    /// Law commands sent.
    pub commands: u64,
    /// What happened, in order.
    pub events: Vec<String>,
    /// MAVLink frames received.
    pub frames_in: u64,
    /// MAVLink frames sent.
    pub frames_out: u64,
    /// Datagrams that were not MAVLink.
    pub junk_datagrams: u64,
    /// Measurements stamped before one already received (dropped, never given to the law).
    #[serde(default)]
    pub measurements_out_of_order: u64,
    /// Measurements repeating the last one's stamp (dropped).
    #[serde(default)]
    pub measurements_repeated: u64,
    /// Measurements that were none (a non-finite value, a malformed UDP sensor line): dropped.
    #[serde(default)]
    pub measurements_invalid: u64,
    /// Measurements from another sender than the sensor's (another component's
    /// `NAMED_VALUE_FLOAT`, another address's UDP datagram): dropped.
    #[serde(default)]
    pub measurements_other_sources: u64,
    /// Why the flight's trace is incomplete (its recording stopped: a disk that filled
    /// mid-flight), absent when it is whole.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recording_incomplete: Option<String>,
    /// The SHA-256 of each data file of the scenario flown, by path, as a run records them
    /// ([`data_file_digests`]; left out when there are none): `plot` compares a flight with the
    /// runs it is drawn with.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub data_files: BTreeMap<String, String>,
    /// What the metrics were computed over (the planned window, or what was flown).
    #[serde(default)]
    pub metrics_over: String,
    /// The tracking metrics of the measured error series, as a simulated run's record has them.
    #[serde(flatten)]
    pub metrics: MetricsRecord,
}

/// Why a `summary.json` cannot be read: the file and what is wrong, on one line.
#[derive(Clone, Debug, PartialEq)]
pub struct SummaryError {
    /// Whether the file could not be read at all (missing, not a regular file, too big), as
    /// opposed to read and found invalid.
    pub unreadable: bool,
    /// The message, naming the file (and the line and column or the key where known).
    pub message: String,
}

impl std::fmt::Display for SummaryError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for SummaryError {}

impl<'a> Summary<&'a isotrack_scenario::ScenarioFile> {
    /// The summary of a simulated run of `scenario` (`scenario_path`: the file it was read
    /// from, `None` for the built-in default).
    pub fn of_run(
        scenario: &'a Scenario,
        scenario_path: Option<&Path>,
        result: &RunResult,
        warnings: &[String],
    ) -> Self {
        Summary {
            isotrack_version: env!("CARGO_PKG_VERSION").to_string(),
            scenario_path: scenario_path.map(|p| p.display().to_string()),
            ended: Ended::Run(RunEnd {
                record: RunRecord::of(result),
                warnings: warnings.to_vec(),
                data_files: data_file_digests(scenario),
                team: None,
                vehicles: None,
            }),
            scenario: scenario.file(),
            controller: None,
        }
    }

    /// The summary of a team's run `team` of `scenario` (`[team]`): the top-level record is
    /// vehicle 0's, followed by the `team` object ([`TeamJson`]) and the `vehicles` array
    /// (every vehicle's record, in the listed order).
    pub fn of_team(
        scenario: &'a Scenario,
        scenario_path: Option<&Path>,
        team: &isotrack_sim::TeamResult,
        warnings: &[String],
    ) -> Self {
        let mut s = Summary::of_run(scenario, scenario_path, &team.runs[0], warnings);
        if let Ended::Run(r) = &mut s.ended {
            r.warnings.extend(team_warnings(scenario, team));
            r.team = Some(Box::new(TeamJson::new(scenario, team)));
            r.vehicles = Some(team.runs.iter().map(RunRecord::of).collect());
        }
        s
    }
}

impl<S: Serialize> Summary<S> {
    /// `summary.json`'s text: pretty-printed, non-finite numbers `null`, a final newline.
    pub fn to_json(&self) -> String {
        // Serialising plain data into a String cannot fail (no map with non-string keys).
        serde_json::to_string_pretty(self).unwrap_or_else(|_| "null".into()) + "\n"
    }

    /// Writes the summary to `path` atomically ([`crate::files::write_atomic`]): a reader sees
    /// no summary or a whole one.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        crate::files::write_atomic(path, self.to_json().as_bytes())
    }
}

/// Whether `text` (a summary an isotrack wrote: [`not_isotracks`] is `None`) is a flight's,
/// `fly`'s: a JSON object with an `end_reason` string, the key every flight's summary has had
/// since `fly` came (2219288) and no other summary has (a simulated run's, `sitl`'s, a team's,
/// `Run.save`'s). Only beside a flight's summary is a `mavlink.tlog` that flight's log
/// (att41-1: `fly --out` replaced a user's log sitting beside a simulated run's summary).
pub fn is_flights(text: &str) -> bool {
    serde_json::from_str::<serde_json::Value>(text).is_ok_and(|v| {
        v.get("end_reason")
            .is_some_and(serde_json::Value::is_string)
    })
}

/// Why `text` is not a `summary.json` that an isotrack of any version wrote (`None` when it
/// is one): what tells an earlier isotrack run's directory, which a new run may replace, from
/// a folder holding a user's own `summary.json` (att39-1), which it never replaces.
///
/// Every summary isotrack has written, from its first version on (`run`, `sitl`, `compare`'s
/// and `figures`' runs, a team's, `fly`'s flight, the Python package's `Run.save`), is a JSON
/// object with `isotrack_version` (a string), `outcome` (a string) and `scenario` (the
/// resolved scenario, an object); those three and nothing more are required. Every other key
/// may be missing or unknown: an older isotrack's summary has no `warnings` (before the
/// Python package), no `data_files`, no `metrics_over`, and a newer one may add keys; so this
/// is looser than [`Summary::from_json`], which reads the present format.
pub fn not_isotracks(text: &str) -> Option<String> {
    let v: serde_json::Value = match serde_json::from_str(text) {
        Ok(v) => v,
        Err(e) => return Some(format!("not JSON: {e}")),
    };
    let serde_json::Value::Object(map) = &v else {
        return Some("not a JSON object".into());
    };
    for (key, what, ok) in [
        (
            "isotrack_version",
            "a string",
            map.get("isotrack_version").is_some_and(|v| v.is_string()),
        ),
        (
            "outcome",
            "a string",
            map.get("outcome").is_some_and(|v| v.is_string()),
        ),
        (
            "scenario",
            "an object",
            map.get("scenario").is_some_and(|v| v.is_object()),
        ),
    ] {
        if !ok {
            return Some(match map.get(key) {
                None => format!("no `{key}` key"),
                Some(_) => format!("its `{key}` is not {what}"),
            });
        }
    }
    None
}

impl Summary {
    /// Reads `path` (a regular file of at most [`MAX_SUMMARY_BYTES`]).
    pub fn read(path: &Path) -> Result<Summary, SummaryError> {
        let text =
            isotrack_fields::io::read_text_limited(path, MAX_SUMMARY_BYTES).map_err(|e| {
                SummaryError {
                    unreadable: true,
                    message: format!("{}: {e}", path.display()),
                }
            })?;
        Summary::from_json(&text).map_err(|e| SummaryError {
            message: format!("{}: {}", path.display(), e.message),
            ..e
        })
    }

    /// Parses a summary's text. A flight's summary is told by its `end_reason` key; the error
    /// names the line and column of bad JSON, or the key missing or of the wrong type.
    pub fn from_json(text: &str) -> Result<Summary, SummaryError> {
        let bad = |message: String| SummaryError {
            unreadable: false,
            message,
        };
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
        let serde_json::Value::Object(map) = &v else {
            return Err(bad("not a JSON object".into()));
        };
        let ended = if map.contains_key("end_reason") {
            serde_json::from_value::<FlightRecord>(v.clone()).map(Ended::Flight)
        } else {
            serde_json::from_value::<RunEnd>(v.clone()).map(Ended::Run)
        }
        .map_err(|e| bad(e.to_string()))?;
        let field = |k: &str| map.get(k).cloned().unwrap_or(serde_json::Value::Null);
        let string = |k: &str| -> Result<Option<String>, SummaryError> {
            match field(k) {
                serde_json::Value::Null => Ok(None),
                serde_json::Value::String(s) => Ok(Some(s)),
                other => Err(bad(format!("`{k}`: expected a string, got {other}"))),
            }
        };
        Ok(Summary {
            isotrack_version: string("isotrack_version")?
                .ok_or_else(|| bad("missing field `isotrack_version`".into()))?,
            scenario_path: string("scenario_path")?,
            ended,
            scenario: match map.get("scenario") {
                Some(s @ serde_json::Value::Object(_)) => s.clone(),
                Some(other) => {
                    return Err(bad(format!(
                        "`scenario`: expected an object, got {}",
                        isotrack_scenario::load::clip(&other.to_string())
                    )))
                }
                None => return Err(bad("missing field `scenario`".into())),
            },
            controller: map.get("controller").cloned(),
        })
    }
}

impl<S> Summary<S> {
    /// nu40-4: names the data files as the run read them, `read` ([`data_file_digests`] of the
    /// scenario flown: the bytes its field was parsed from), not as they are when the summary
    /// is written: a file replaced while the run flew (on the field read before) was named by
    /// its new SHA-256. When a file's digest now differs from `read`'s (or it is gone), returns
    /// the warning saying so, also added to a run's `warnings` or a flight's `events`
    /// (att41-17: `sitl` and `fly` record theirs so too); `None` when every file is as read.
    pub fn data_files_as_read(&mut self, read: BTreeMap<String, String>) -> Option<String> {
        let changed: Vec<String> = read
            .iter()
            .filter(|(p, d)| {
                crate::files::sha256_file(Path::new(p.as_str()))
                    .ok()
                    .as_ref()
                    != Some(*d)
            })
            .map(|(p, d)| format!("{p} (SHA-256 {} as read)", &d[..d.len().min(16)]))
            .collect();
        let w = (!changed.is_empty()).then(|| {
            format!(
                "a data file changed (or went) while the run flew: {}; the run flew the field as read before it, and data_files names that one",
                changed.join(", ")
            )
        });
        match &mut self.ended {
            Ended::Run(r) => {
                r.data_files = read;
                r.warnings.extend(w.clone());
            }
            Ended::Flight(f) => {
                f.data_files = read;
                f.events.extend(w.clone());
            }
        }
        w
    }

    /// The outcome (`completed`, `left_field`, `diverged`; `interrupted` or `companion_lost`
    /// for a cut `sitl` run; a flight's).
    pub fn outcome(&self) -> &str {
        match &self.ended {
            Ended::Run(r) => &r.record.outcome,
            Ended::Flight(f) => &f.outcome,
        }
    }

    /// Why the run ended so, when said.
    pub fn outcome_detail(&self) -> Option<&str> {
        match &self.ended {
            Ended::Run(r) => r.record.outcome_detail.as_deref(),
            Ended::Flight(f) => Some(&f.outcome_detail),
        }
    }

    /// The time of the last valid step (a flight's last measurement), s.
    pub fn t_end_s(&self) -> Option<f64> {
        match &self.ended {
            Ended::Run(r) => r.record.t_end_s,
            Ended::Flight(f) => f.t_end_s,
        }
    }

    /// The simulated run's record (`None` for a flight).
    pub fn record(&self) -> Option<&RunRecord> {
        match &self.ended {
            Ended::Run(r) => Some(&r.record),
            Ended::Flight(_) => None,
        }
    }

    /// A team's `team` object (`None` for one vehicle's run and for a flight).
    pub fn team(&self) -> Option<&TeamJson> {
        match &self.ended {
            Ended::Run(r) => r.team.as_deref(),
            Ended::Flight(_) => None,
        }
    }

    /// The data files' digests the run or flight recorded.
    pub fn data_files(&self) -> Option<&BTreeMap<String, String>> {
        match &self.ended {
            Ended::Run(r) => Some(&r.data_files),
            Ended::Flight(f) => Some(&f.data_files),
        }
    }
}

/// The resolved scenario as TOML (reads back as the same scenario, bit for bit; floats in
/// their shortest form, [`isotrack_scenario::tomltext::to_toml`]).
pub fn scenario_toml(scenario: &Scenario) -> String {
    isotrack_scenario::tomltext::to_toml(scenario.file())
        .unwrap_or_else(|e| format!("# cannot render: {e}\n"))
}

/// The SHA-256 of each data file of `scenario`'s field (`field.path`, `field.paths`, absolute
/// in a resolved scenario), by path, of the bytes the field was parsed from
/// ([`Scenario::data_file_digests`]: taken as the load read them). att41-22: they were taken
/// by reading each file again after the load, so a file replaced while the scenario loaded
/// was named by its new digest (and then agreed with itself at the end: no warning) for a
/// field parsed from the old one.
pub fn data_file_digests(scenario: &Scenario) -> BTreeMap<String, String> {
    scenario.data_file_digests().clone()
}

/// The most vehicles [`unfinished_vehicles`] names one by one (a team of 10 000 whose every
/// vehicle left the field gives one line, not 10 000).
const UNFINISHED_NAMED: usize = 5;

/// The warnings of a team run `team` of `scenario`: the engine's
/// ([`isotrack_sim::TeamResult::warnings`]: a discovered ring that was not one ring), then
/// [`close_approach`]'s and [`unfinished_vehicles`]'. `isotrack run` prints them and
/// `summary.json` lists them in `warnings`.
pub fn team_warnings(scenario: &Scenario, team: &isotrack_sim::TeamResult) -> Vec<String> {
    let mut w = team.warnings.clone();
    w.extend(close_approach(team, scenario.spec().team.as_ref()));
    w.extend(unfinished_vehicles(team));
    w
}

/// The warning of a team run whose vehicles came closer than
/// [`CLOSE_APPROACH_M`](isotrack_sim::team::metrics::CLOSE_APPROACH_M) to each other
/// (nu39-3: on the puff plume with a listed ring whose arrival order differed, two robots
/// passed through each other, 0.02 m apart, with no word): which, when and how close, and the
/// reason the team's settings (`spec`, its `[team]`) give ([`approach_reason`]); `None`
/// otherwise. `order_preserved` looks at the steady window only, so a crossing before it is
/// named here and nowhere else.
pub fn close_approach(
    team: &isotrack_sim::TeamResult,
    spec: Option<&isotrack_scenario::spec::team::TeamSpec>,
) -> Option<String> {
    use isotrack_core::numtext::Num;
    use isotrack_sim::team::metrics::CLOSE_APPROACH_M;
    let summary = team.team.as_ref()?;
    let c = summary.closest_approach?;
    (c.distance_m < CLOSE_APPROACH_M).then(|| {
        format!(
            "vehicles {} and {} came within {} m of each other at t = {} s (closer than {} m: a collision for real vehicles, which the model's points pass through): {}",
            c.pair[0],
            c.pair[1],
            Num(c.distance_m),
            Num(c.t_s),
            Num(CLOSE_APPROACH_M),
            if c.t_s == 0.0 {
                // att43-9: at the first sample no law has acted: the deployment put them there.
                "they were deployed that close (team.starts, team.spread): no law had acted yet"
                    .into()
            } else {
                approach_reason(c.pair, summary.isoline_length_m, spec)
            }
        )
    })
}

/// Why vehicles `pair` of a team (`spec`: its `[team]`; `None` when unknown) came close, as the
/// team's settings tell it (att41-3: a team with no spacing law, lapped by a slower vehicle,
/// was told that "the spacing law drove them together" and to try `team.ring =
/// "discovered"`, which refuses per-vehicle speeds):
///
/// * their nominal speeds differ and nothing holds the faster back (`team.spacing = "none"`,
///   or envelopes with no speed in common): the faster laps the slower every
///   `L/|v0_i - v0_j|` (`l_m`: the isoline's length);
/// * no spacing law (equal speeds): nothing keeps them apart;
/// * a spacing law on a listed ring, every vehicle at one speed: the law drove them together,
///   as a listed ring whose arrival order differs from the listed one does (try
///   `team.ring = "discovered"`, which such a team may use), or they started too close;
/// * any other team: the spacing law drove them together, or they started too close (per-vehicle
///   speeds named when the pair's differ).
pub fn approach_reason(
    pair: [u32; 2],
    l_m: f64,
    spec: Option<&isotrack_scenario::spec::team::TeamSpec>,
) -> String {
    use isotrack_core::numtext::Num;
    use isotrack_sim::team::spacing::{RingMode, SpacingLaw};
    let Some(t) = spec else {
        return "the spacing law drove them together, a faster vehicle lapped a slower one, or they started too close".into();
    };
    let (i, j) = (pair[0] as usize, pair[1] as usize);
    let (a, b) = (t.speeds(i), t.speeds(j));
    let no_law = t.law == SpacingLaw::None;
    let apart = a.min_mps > b.max_mps || b.min_mps > a.max_mps;
    if a.nominal_mps != b.nominal_mps && (no_law || apart) {
        let (fast, slow, vf, vs) = if a.nominal_mps > b.nominal_mps {
            (i, j, a.nominal_mps, b.nominal_mps)
        } else {
            (j, i, b.nominal_mps, a.nominal_mps)
        };
        let why = if no_law {
            "with no spacing law (team.spacing = \"none\") each keeps its speed"
        } else {
            "their speed envelopes have no speed in common, so the spacing law cannot hold them"
        };
        let every = if l_m.is_finite() && l_m > 0.0 {
            format!(" = {} s", Num(l_m / (vf - vs)))
        } else {
            String::new()
        };
        return format!(
            "vehicle {fast} flies at {} m/s and vehicle {slow} at {} m/s (team.vehicles) and {why}: the faster laps the slower every L/|v0_{fast} - v0_{slow}|{every} (robots pass through each other)",
            Num(vf),
            Num(vs)
        );
    }
    if no_law {
        return "no spacing law holds them apart (team.spacing = \"none\"): they started too close, or met on the isoline".into();
    }
    let one_speed = (0..t.count()).all(|k| t.speeds(k).nominal_mps == t.nominal_speed_mps);
    if matches!(t.ring, RingMode::Listed) && one_speed {
        return "the spacing law drove them together (a listed team.ring whose arrival order on the isoline differs from the listed one does: try team.ring = \"discovered\"), or they started too close".into();
    }
    if a.nominal_mps != b.nominal_mps {
        return format!(
            "the spacing law drove them together (vehicle {i} at {} m/s, vehicle {j} at {} m/s: team.vehicles), or they started too close",
            Num(a.nominal_mps),
            Num(b.nominal_mps)
        );
    }
    "the spacing law drove them together, or they started too close".into()
}

/// The warning of a team run `team` in which vehicles other than vehicle 0 (whose outcome is
/// the top level's) did not complete: each named with its outcome, the time it ended and why
/// (`vehicle 3: left_field at t = 0.68 s (the field has no value at ...)`), the first
/// [`UNFINISHED_NAMED`] of them; `None` when they all completed. `isotrack run` prints it and
/// `summary.json` lists it in `warnings` (issue 32, att32d-14: a run whose vehicle 3 left the
/// field at 0.68 s said `completed`, `warnings: []`).
pub fn unfinished_vehicles(team: &isotrack_sim::TeamResult) -> Option<String> {
    use isotrack_core::numtext::Num;
    let ended: Vec<(usize, &RunResult)> = team
        .runs
        .iter()
        .enumerate()
        .skip(1)
        .filter(|(_, r)| r.outcome != isotrack_sim::Outcome::Completed)
        .collect();
    if ended.is_empty() {
        return None;
    }
    let mut named: Vec<String> = ended
        .iter()
        .take(UNFINISHED_NAMED)
        .map(|(i, r)| {
            let why = r
                .outcome_detail
                .as_deref()
                .map_or_else(String::new, |d| format!(" ({d})"));
            format!(
                "vehicle {i}: {} at t = {} s{why}",
                r.outcome.as_str(),
                Num(r.t_end_s)
            )
        })
        .collect();
    if ended.len() > UNFINISHED_NAMED {
        named.push(format!("and {} more", ended.len() - UNFINISHED_NAMED));
    }
    Some(format!(
        "{} of the {} vehicles besides vehicle 0 did not complete the run ({}); the top-level outcome and metrics are vehicle 0's, each vehicle's outcome is in `vehicles`",
        ended.len(),
        team.runs.len() - 1,
        named.join("; ")
    ))
}

#[cfg(test)]
mod tests {
    /// Numbers read back from the run files' JSON (`summary.json`, a benchmark's `task.json` that
    /// `--resume` reads) are the numbers written: serde_json parses floats correctly rounded only
    /// with its `float_roundtrip` feature (without it `0.9065168750000001`, a score a benchmark
    /// wrote, read back one unit in the last place off as `0.906516875`, and `--resume` rewrote
    /// results.csv with it). Checked against the standard library's correctly rounded parser.
    #[test]
    fn json_floats_read_back_exactly() {
        for text in [
            "0.9065168750000001",
            "0.1",
            "2.2250738585072014e-308",
            "5e-324",
            "1.7976931348623157e308",
            "0.30000000000000004",
            "6.3500000000000005",
            "2571.4285714285716",
        ] {
            let json: f64 = serde_json::from_str(text).unwrap();
            let exact: f64 = text.parse().unwrap();
            assert_eq!(json.to_bits(), exact.to_bits(), "{text}");
            let again: f64 = serde_json::from_str(&serde_json::to_string(&json).unwrap()).unwrap();
            assert_eq!(again.to_bits(), exact.to_bits(), "{text} round trip");
        }
    }
}
