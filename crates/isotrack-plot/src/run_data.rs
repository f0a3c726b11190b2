//! Reading a run directory.

use crate::PlotError;
use isotrack_core::numtext::Echo;
use isotrack_runs::summary::{Ended, Summary, MAX_SUMMARY_BYTES};
use isotrack_runs::trace::TRACE_COLUMNS;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::TraceRow;
use std::path::{Path, PathBuf};

/// A finished run, as written by `isotrack run --out DIR` (or one directory of `compare`).
#[derive(Clone, Debug)]
pub struct RunData {
    /// Label for legends (the directory name).
    pub name: String,
    /// The directory.
    pub dir: PathBuf,
    /// The trace.
    pub trace: Vec<TraceRow>,
    /// `summary.json` (read by its one reader, [`Summary::from_json`]). A team's vehicle
    /// ([`RunData::load_team`]) has its own record, without the lists of every vehicle
    /// (`vehicles`, `team.neighbours`), and after vehicle 0 without the recorded `scenario`
    /// (`null`: [`RunData::scenario`] is the team's).
    pub summary: Summary,
    /// The resolved scenario (its field rebuilt for the map).
    pub scenario: Scenario,
}

/// The outcomes a team's vehicle ends with (`summary.json`'s `vehicles[i].outcome`).
const TEAM_OUTCOMES: [&str; 3] = ["completed", "left_field", "diverged"];

/// The outcomes of a simulated run's `summary.json` (a cut `sitl` run's too).
const RUN_OUTCOMES: [&str; 5] = [
    "completed",
    "left_field",
    "diverged",
    "interrupted",
    "companion_lost",
];

/// A team's `summary.json` against itself and its scenario (att32f-1): `team.count` (the
/// metrics') and the scenario's `[team]` count are `team.vehicle_count` (`n`), and `vehicles`
/// lists `n` vehicles. A list one short or one long drew a vehicle with no end known (or one
/// with no rows), and `count` differing passed unread; each refused naming the key.
fn check_team_lists(run: &RunData, n: usize) -> Result<(), String> {
    let Ended::Run(end) = &run.summary.ended else {
        return Ok(());
    };
    if let Some(c) = end
        .team
        .as_ref()
        .and_then(|t| t.metrics.as_ref())
        .map(|m| m.count)
    {
        if c != n {
            return Err(format!(
                "summary.json: team.count = {c}, but team.vehicle_count = {n}: not one team"
            ));
        }
    }
    if let Some(t) = run.scenario.spec().team.as_ref() {
        if t.count() != n {
            return Err(format!(
                "scenario.toml's team has {} vehicles, but summary.json's team.vehicle_count = {n}",
                t.count()
            ));
        }
    }
    // att36-15: each vehicle's outcome one a team's run writes, and the top-level record
    // (documented to be vehicle 0's) vehicle 0's.
    if let Some(v) = &end.vehicles {
        if let Some((i, bad)) = v
            .iter()
            .enumerate()
            .find(|(_, v)| !TEAM_OUTCOMES.contains(&v.outcome.as_str()))
        {
            return Err(format!(
                "summary.json: vehicles[{i}].outcome = \"{}\" is no outcome of a team's vehicle ({})",
                isotrack_scenario::load::clip(&bad.outcome),
                TEAM_OUTCOMES.join(", ")
            ));
        }
        if let Some(v0) = v.first() {
            let same_end = match (end.record.t_end_s, v0.t_end_s) {
                (Some(a), Some(b)) => a == b,
                (a, b) => a.is_none() && b.is_none(),
            };
            if end.record.outcome != v0.outcome || !same_end {
                return Err(format!(
                    "summary.json: the top-level outcome {} at t_end_s = {} is not vehicles[0]'s ({} at {}), whose record the top level repeats",
                    isotrack_scenario::load::clip(&end.record.outcome),
                    end.record.t_end_s.map_or("null".to_string(), |t| Echo(t).to_string()),
                    isotrack_scenario::load::clip(&v0.outcome),
                    v0.t_end_s.map_or("null".to_string(), |t| Echo(t).to_string()),
                ));
            }
        }
    }
    match &end.vehicles {
        None => Err(format!(
            "summary.json has no `vehicles` list (each vehicle's outcome and end), but its team has {n} vehicles"
        )),
        Some(v) if v.len() != n => Err(format!(
            "summary.json's `vehicles` lists {} vehicles, but team.vehicle_count = {n}",
            v.len()
        )),
        // A team's run writes every vehicle's end; one with none was drawn ending at its last
        // row, a trace cut short read as its end (att32g-5).
        Some(v) => match v.iter().position(|v| v.t_end_s.is_none()) {
            Some(i) => Err(format!(
                "summary.json: vehicles[{i}].t_end_s is null, but a team's run writes every vehicle's end ({} of vehicle {i}): its rows cannot be checked against it",
                v[i].outcome
            )),
            None => check_duration(run, v),
        },
    }
}

/// A team's vehicles against `scenario.toml`'s `sim.duration_s` (att32g-7): a vehicle that
/// `completed` ends at the duration, none after it. A scenario edited after the run (another
/// duration) was drawn, its steady window (and the revisit panel's) taken from the edited
/// duration; refused naming the key and the first vehicle that disagrees.
fn check_duration(
    run: &RunData,
    vehicles: &[isotrack_runs::results::RunRecord],
) -> Result<(), String> {
    let d = run.scenario.spec().sim.duration_s;
    let tol = 1e-9 * d.abs().max(1.0);
    for (i, v) in vehicles.iter().enumerate() {
        let Some(t) = v.t_end_s else { continue };
        let wrong = if v.outcome == "completed" {
            (t - d).abs() > tol
        } else {
            t > d + tol
        };
        if wrong {
            return Err(format!(
                "scenario.toml: sim.duration_s = {} s, but summary.json's vehicles[{i}] {}: the scenario is not this run's",
                Echo(d),
                vehicle_end(&run.summary, i)
            ));
        }
    }
    Ok(())
}

/// `summary.json`'s numbers as a sweep's row is held to
/// ([`isotrack_runs::sweep::check::check_run_summary`], att43-15): `report` shows them as the
/// run's, so an impossible one (a negative maximum, a convergence time past the run's end) is
/// a data error naming its key, not a number on the page. After [`check_scenario_is_runs`]:
/// the team's bounds are its scenario's.
fn check_summary_numbers(run: &RunData) -> Result<(), String> {
    isotrack_runs::sweep::check::check_run_summary(&run.summary, &run.scenario)
        .map_err(|m| format!("summary.json: {m} (edited after the run?); re-run it"))
}

/// The summary's scenario to compare with `scenario.toml`: as recorded, but a run flown by a
/// Python controller (`Run.save`, README "From Python": `controller = {kind = "python", class =
/// "module.Class", level ...}`) has its `controller` read as `scenario.toml`'s built-in law with
/// the summary's other controller keys (the level) set on it: the law in `scenario.toml` is not
/// the one that flew (its note says so), so it cannot differ from it (att46-3: every saved
/// Python-controller run was refused "not a scenario (unknown field `class`)").
fn python_law_as_toml_law(run: &RunData) -> serde_json::Value {
    let mut recorded = run.summary.scenario.clone();
    let Some(law) = recorded
        .get_mut("controller")
        .and_then(|c| c.as_object_mut())
    else {
        return recorded;
    };
    if law.get("kind").and_then(|k| k.as_str()) != Some("python") {
        return recorded;
    }
    let Some(mut toml_law) = serde_json::to_value(run.scenario.file())
        .ok()
        .and_then(|f| f.get("controller").and_then(|c| c.as_object()).cloned())
    else {
        return recorded;
    };
    for (k, v) in law
        .iter()
        .filter(|(k, _)| !matches!(k.as_str(), "kind" | "class"))
    {
        toml_law.insert(k.clone(), v.clone());
    }
    *law = toml_law;
    recorded
}

/// `scenario.toml` against the resolved scenario `summary.json` records (att36-5): the run
/// flew the summary's; a `scenario.toml` edited after the run (another level, field, speed,
/// steady fraction ...) drew the run against a scenario it never flew, and an edited
/// summary's scenario likewise. Both sides are compared after resolving (att40-3): the
/// summary's scenario is read as a scenario file and resolved as `scenario.toml` is, and every
/// key of the two resolved forms is compared, so that a key one side has and the other leaves
/// to its default (`field.drift_mps`, `field.domain_m`, `team.ranging.max_range_m`, which a
/// resolved file leaves out when unset) is a difference unless both resolve to the same value
/// (an older isotrack's summary without a newer key resolves it to its default, as
/// `scenario.toml` does). Refused naming the first key (in key order) whose values differ. A
/// summary's scenario that is empty or is no scenario (not one key of a run's resolved
/// scenario) is not this run's: refused too (att40-3: `"scenario": {}` turned the check off).
fn check_scenario_is_runs(run: &RunData) -> Result<(), String> {
    let not_runs = |why: String| {
        format!(
            "summary.json's scenario {why}: it is not this run's (a run records its whole resolved scenario there); re-run it"
        )
    };
    if run
        .summary
        .scenario
        .as_object()
        .is_none_or(serde_json::Map::is_empty)
    {
        return Err(not_runs("is empty".into()));
    }
    let file: isotrack_scenario::ScenarioFile = serde_json::from_value(python_law_as_toml_law(run))
        .map_err(|e| {
            not_runs(format!(
                "is not a scenario ({})",
                isotrack_scenario::load::clip(&e.to_string())
            ))
        })?;
    let resolved = isotrack_scenario::resolve::resolve(file).map_err(|issues| {
        let first = issues.first().map_or_else(String::new, |i| {
            format!(
                " ({}: {})",
                i.key,
                isotrack_scenario::load::clip(&i.message)
            )
        });
        not_runs(format!("does not resolve{first}"))
    })?;
    let (Ok(mut in_toml), Ok(mut in_summary)) = (
        serde_json::to_value(run.scenario.file()),
        serde_json::to_value(&resolved),
    ) else {
        return Err(not_runs("cannot be compared".into()));
    };
    // Each key one side leaves out that resolves, set on that side, to the settings it has
    // without it (a derived default written out, a zero drift) is the same run: set there,
    // and the comparison goes on. Each pass settles one key, so the passes are bounded.
    loop {
        let Some(d) = first_difference(&in_toml, &in_summary, &mut Vec::new()) else {
            return Ok(());
        };
        let side = match (&d.in_toml, &d.in_summary) {
            (Some(v), None) => Some((&mut in_summary, v.clone())),
            (None, Some(v)) => Some((&mut in_toml, v.clone())),
            _ => None,
        };
        // A section's key only: `name` and `description` are text, not settings.
        let settled = side.filter(|_| d.path.len() >= 2).is_some_and(|(lacking, v)| {
            let mut set = lacking.clone();
            set_at(&mut set, &d.path, v)
                && matches!((settings_of(lacking), settings_of(&set)), (Some(a), Some(b)) if a == b)
                && {
                    *lacking = set;
                    true
                }
        });
        if !settled {
            let shown = |v: &Option<serde_json::Value>| {
                v.as_ref().map_or_else(
                    || UNSET.to_string(),
                    |v| isotrack_scenario::load::clip(&v.to_string()),
                )
            };
            return Err(format!(
                "scenario.toml: {key} = {}, but summary.json's scenario (the one the run flew) has {key} = {}: the scenario is not this run's (edited after the run?); restore it or re-run it",
                shown(&d.in_toml),
                shown(&d.in_summary),
                key = d.key,
            ));
        }
    }
}

/// Every setting in force ([`isotrack_scenario::spec::ScenarioSpec`], the derived ones
/// computed) of a scenario given as the JSON of a scenario file, resolved; `None` when it is
/// not one. No file is read: a field's files only fill keys a resolved file already holds.
fn settings_of(json: &serde_json::Value) -> Option<isotrack_scenario::spec::ScenarioSpec> {
    let file: isotrack_scenario::ScenarioFile = serde_json::from_value(json.clone()).ok()?;
    let file = isotrack_scenario::resolve::resolve(file).ok()?;
    let vehicle = isotrack_scenario::vehicle::build_vehicle(&file).ok()?;
    isotrack_scenario::spec::ScenarioSpec::new(&file, vehicle.airframe_turn_rate_limit_radps()).ok()
}

/// Sets the key at `path` (as [`first_difference`] gives it: object keys and `[i]` indices)
/// in `json` to `value`; `false` when the path does not lead to an object there.
fn set_at(json: &mut serde_json::Value, path: &[String], value: serde_json::Value) -> bool {
    let Some((last, parents)) = path.split_last() else {
        return false;
    };
    let mut at = json;
    for p in parents {
        let next = match p.strip_prefix('[').and_then(|i| i.strip_suffix(']')) {
            Some(i) => i.parse::<usize>().ok().and_then(|i| at.get_mut(i)),
            None => at.get_mut(p.as_str()),
        };
        match next {
            Some(n) => at = n,
            None => return false,
        }
    }
    match at.as_object_mut() {
        Some(m) => {
            m.insert(last.clone(), value);
            true
        }
        None => false,
    }
}

/// A JSON number that is an integer, exactly (`None` for a fraction or exponent form).
fn integer(n: &serde_json::Number) -> Option<i128> {
    n.as_i64()
        .map(i128::from)
        .or_else(|| n.as_u64().map(i128::from))
}

/// How a key one side leaves out is shown (a resolved file leaves out a key whose default is
/// "none": no drift, no domain, no range limit, or a derived value).
const UNSET: &str = "(unset: the default)";

/// Where two scenarios' JSON first differ ([`first_difference`]).
struct Difference {
    /// The key, dotted (`a.b[2].c`).
    key: String,
    /// The key as its parts (object keys, `[i]` indices).
    path: Vec<String>,
    /// `scenario.toml`'s value (`None`: it has no such key).
    in_toml: Option<serde_json::Value>,
    /// `summary.json`'s value (`None`: it has no such key).
    in_summary: Option<serde_json::Value>,
}

/// The first key (in key order) where `a` (`scenario.toml`'s) and `b` (`summary.json`'s)
/// differ; a key only one side has is a difference (att40-3: such keys were skipped, so a key
/// added to `scenario.toml` that the resolved file leaves out was never compared).
fn first_difference(
    a: &serde_json::Value,
    b: &serde_json::Value,
    path: &mut Vec<String>,
) -> Option<Difference> {
    use serde_json::Value;
    let here = |path: &[String], x: Option<&Value>, y: Option<&Value>| {
        let mut key = String::new();
        for p in path {
            if !p.starts_with('[') && !key.is_empty() {
                key.push('.');
            }
            key.push_str(p);
        }
        Some(Difference {
            key,
            path: path.to_vec(),
            in_toml: x.cloned(),
            in_summary: y.cloned(),
        })
    };
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            // Every key of either side, in key order.
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort();
            keys.dedup();
            for k in keys {
                path.push(k.clone());
                let d = match (x.get(k), y.get(k)) {
                    (Some(va), Some(vb)) => first_difference(va, vb, path),
                    (va, vb) => here(path, va, vb),
                };
                path.pop();
                if d.is_some() {
                    return d;
                }
            }
            None
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (va, vb)) in x.iter().zip(y).enumerate() {
                path.push(format!("[{i}]"));
                let d = first_difference(va, vb, path);
                path.pop();
                if d.is_some() {
                    return d;
                }
            }
            None
        }
        // Integers (a seed up to 2^64 - 1) compare exactly: as f64, 2^60 and 2^60 + 1 are one
        // number, and an edited seed passed (att40-4).
        (Value::Number(x), Value::Number(y)) if integer(x).is_some() && integer(y).is_some() => {
            if integer(x) != integer(y) {
                here(path, Some(a), Some(b))
            } else {
                None
            }
        }
        (Value::Number(x), Value::Number(y))
            if x.as_f64().is_some() && x.as_f64() == y.as_f64() =>
        {
            None
        }
        _ if a == b => None,
        _ => here(path, Some(a), Some(b)),
    }
}

/// How `summary.json`'s `vehicles[i]` ends vehicle `i`, for a message: "ends it at t = T s
/// (OUTCOME)".
fn vehicle_end(summary: &Summary, i: usize) -> String {
    let Ended::Run(end) = &summary.ended else {
        return "is not there".into();
    };
    match end.vehicles.as_ref().and_then(|v| v.get(i)) {
        Some(v) => format!(
            "ends it at t = {} ({})",
            v.t_end_s
                .map_or_else(|| "?".to_string(), |t| format!("{} s", Echo(t))),
            v.outcome
        ),
        None => "is not there".into(),
    }
}

/// A run whose `summary.json` has no `team` object (att32f-2): its trace must not be a team's (a
/// `vehicle` column: the single-run figures would join every vehicle's rows into one path), nor
/// its summary have a `vehicles` list, nor its scenario a `[team]` (a run of it has a `team`).
fn check_not_a_team(
    summary: &Summary,
    scenario: &Scenario,
    vehicle_col: bool,
) -> Result<(), String> {
    let Ended::Run(end) = &summary.ended else {
        return if vehicle_col {
            Err("trace.csv has a `vehicle` column (a team's trace), but summary.json is a flight's, with no `team`".into())
        } else {
            Ok(())
        };
    };
    let why = if vehicle_col {
        Some("trace.csv has a `vehicle` column (a team's trace)")
    } else if end.vehicles.is_some() {
        Some("summary.json has a `vehicles` list (a team's run)")
    } else if scenario.spec().team.is_some() {
        Some("scenario.toml has a `[team]` (a run of it is a team's)")
    } else {
        None
    };
    match why {
        Some(w) => Err(format!(
            "{w}, but summary.json's `team` is null or missing: the team's run cannot be read as one vehicle's"
        )),
        None => Ok(()),
    }
}

/// Reads and checks `DIR/summary.json` of a run directory ([`RunData`]): an outcome isotrack
/// writes; a team's run refused unless `team_ok`.
fn read_summary(dir: &Path, team_ok: bool) -> Result<Summary, PlotError> {
    let err = |m: String| PlotError::Data(format!("{}: {m}", dir.display()));
    let cannot = |m: String| PlotError::Input(format!("{}: {m}", dir.display()));
    let text = isotrack_fields::io::read_text_limited(&dir.join("summary.json"), MAX_SUMMARY_BYTES)
        .map_err(|e| cannot(format!("summary.json: {e} (is this a run directory?)")))?;
    let summary = Summary::from_json(&text).map_err(|e| err(format!("summary.json: {e}")))?;
    // att36-15: an outcome isotrack never writes ("exploded") was drawn and reported as
    // given.
    if let Ended::Run(end) = &summary.ended {
        if !RUN_OUTCOMES.contains(&end.record.outcome.as_str()) {
            return Err(err(format!(
                "summary.json: outcome = \"{}\" is no outcome of a run ({})",
                isotrack_scenario::load::clip(&end.record.outcome),
                RUN_OUTCOMES.join(", ")
            )));
        }
    }
    // A team's run (issue 32): one trace of every vehicle, which the single-vehicle figures
    // would join into one path; refused until the team's figures are drawn.
    if !team_ok && summary.team().is_some() {
        return Err(err(
            "a team's run (summary.json has a `team` object): `isotrack plot` draws teams; this command does not yet (docs/TEAMS.md)".into(),
        ));
    }
    Ok(summary)
}

/// Reads `DIR/trace.csv` of the run of `summary` and `scenario`: its rows, each row's
/// `vehicle` cell and each row's line ([`RunData::read`]); every row checked ([`check_row`]).
#[allow(clippy::type_complexity)]
fn read_trace(
    dir: &Path,
    summary: &Summary,
    scenario: &Scenario,
    team_ok: bool,
) -> Result<(Vec<TraceRow>, Vec<Option<usize>>, Vec<u64>), PlotError> {
    let err = |m: String| PlotError::Data(format!("{}: {m}", dir.display()));
    // Each `\r\n` read as `\n`: the csv reader counts a CRLF file's lines one short (its
    // record starts before the `\n` of the line ending before it), so every trace.csv:LINE
    // named was one too early (att32g-9).
    let mut rdr =
        csv::Reader::from_reader(CrlfAsLf::new(crate::open_input(&dir.join("trace.csv"))?));
    let headers = rdr
        .headers()
        .map_err(|e| err(format!("trace.csv: {e}")))?
        .clone();
    let col = |n: &str| {
        headers
            .iter()
            .position(|h| h == n)
            .ok_or_else(|| err(format!("trace.csv has no column `{n}`")))
    };
    // The numeric columns every trace has (TRACE_COLUMNS: `t_s` ... `omega_radps`), then the
    // optional `s_measured` (empty before the first measurement).
    let [t_s, x_m, y_m, heading_rad, s, error, omega_radps, s_measured] = TRACE_COLUMNS;
    let idx = [
        col(t_s)?,
        col(x_m)?,
        col(y_m)?,
        col(heading_rad)?,
        col(s)?,
        col(error)?,
        col(omega_radps)?,
    ];
    let meas = headers.iter().position(|h| h == s_measured);
    let vehicle_col = headers.iter().position(|h| h == "vehicle");
    if summary.team().is_none() {
        check_not_a_team(summary, scenario, vehicle_col.is_some()).map_err(err)?;
    }
    let mut vehicles = Vec::new();
    let mut lines = Vec::new();
    let mut trace = Vec::new();
    let end_s = run_end_s(summary, team_ok);
    for rec in rdr.records() {
        let rec = rec.map_err(|e| err(format!("trace.csv: {e}")))?;
        let line = rec.position().map_or(0, |p| p.line());
        lines.push(line);
        let mut v = [0.0; 7];
        for (k, &i) in idx.iter().enumerate() {
            v[k] = rec.get(i).and_then(|t| t.parse().ok()).ok_or_else(|| {
                err(format!(
                    "trace.csv:{line}: column {} is not a number",
                    headers.get(i).unwrap_or("?")
                ))
            })?;
        }
        check_row(&v, trace.last().map(|r: &TraceRow| r.t_s), end_s)
            .map_err(|m| err(format!("trace.csv:{line}: {m}")))?;
        let m = meas.and_then(|i| rec.get(i)).and_then(|t| t.parse().ok());
        vehicles.push(
            vehicle_col
                .and_then(|i| rec.get(i))
                .and_then(|t| t.parse().ok()),
        );
        trace.push(TraceRow {
            t_s: v[0],
            x_m: v[1],
            y_m: v[2],
            heading_rad: v[3],
            s: v[4],
            error: v[5],
            omega_radps: v[6],
            s_measured: m,
            telemetry: None,
        });
    }
    Ok((trace, vehicles, lines))
}

/// The end of the run of `summary`, which bounds every row's time: a team's is its last
/// vehicle's (the top-level `t_end_s` is vehicle 0's, which may end first: its end once
/// refused the others' later rows, att32e-2) when its team is read (`team_ok`); each vehicle's
/// own end bounds its own rows ([`RunData::load_team`]).
fn run_end_s(summary: &Summary, team_ok: bool) -> Option<f64> {
    match (&summary.ended, team_ok && summary.team().is_some()) {
        (Ended::Run(end), true) => end
            .vehicles
            .iter()
            .flatten()
            .filter_map(|v| v.t_end_s)
            .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))))
            .filter(|m| m.is_finite())
            .or(summary.t_end_s()),
        _ => summary.t_end_s(),
    }
}

/// Why a run's trace.csv has no rows: its trace turned off, or the run's end.
fn why_no_rows(summary: &Summary, scenario: &Scenario) -> String {
    if scenario.file().output.record_rate_hz == Some(0.0) {
        "the trace was turned off (output.record_rate_hz = 0)".to_string()
    } else {
        // A flight that answered no measurement has no end time (`t_end_s` null).
        let when = match summary.t_end_s() {
            Some(t) => format!("the run ended at t = {} s", serde_json::Value::from(t)),
            None => "the run ended before its first measurement (no end time)".to_string(),
        };
        format!(
            "{when}: {} ({})",
            summary.outcome(),
            summary.outcome_detail().unwrap_or("no detail")
        )
    }
}

/// A team's trace split into its vehicles' rows as it is read ([`RunData::load_team`]), each
/// row checked against the recorded times. The rows come a recorded time at a time, every
/// running vehicle's row at each: a vehicle's k-th row is at the k-th time (a vehicle that ends
/// leaves for good). A row missing (or one too many) would pair one vehicle's positions with
/// the others' at another time in every figure: refused, naming the line. The messages are
/// the run directory's to prefix.
struct TeamRows<'a> {
    /// The team's `summary.json`.
    summary: &'a Summary,
    /// The team's vehicle count.
    n: usize,
    /// Each vehicle's rows so far.
    traces: Vec<Vec<TraceRow>>,
    /// The recorded times so far.
    times: Vec<f64>,
    /// Each vehicle's last row's line in trace.csv so far.
    last_line: Vec<u64>,
    /// A vehicle that ended early (`left_field`, `diverged`: summary.json) writes its last
    /// valid state at the step it ended, which may fall between two recorded times: that
    /// one row, at its `t_end_s`, is its last, off the schedule (att32d-14).
    ended_at: Vec<Option<f64>>,
    /// Every vehicle's own end (`vehicles[i].t_end_s`): a row after it is refused (att32e-4).
    end_of: Vec<Option<f64>>,
    /// Whether a vehicle's last row (off the schedule, at its end) was read.
    done: Vec<bool>,
    /// Each vehicle's last row (its index in the file), and for each recorded time the row
    /// that set it and how many rows are at it: a time set by a vehicle's last row alone is
    /// that vehicle's end off the recorded times (att32f-8).
    last_row: Vec<usize>,
    /// For each recorded time, its first row's vehicle, index and line.
    time_set_by: Vec<(usize, usize, u64)>,
    /// For each recorded time, whether every row at it is its vehicle's last: a time off the
    /// schedule where one or more vehicles ended together (att32g-4: two vehicles ending at
    /// the same step blamed a right row).
    all_last: Vec<bool>,
}

impl<'a> TeamRows<'a> {
    /// Nothing read yet of the trace of a team of `n` vehicles with `summary`, whose rows'
    /// `vehicle` cells are `ids`.
    fn new(summary: &'a Summary, ids: &[Option<usize>], n: usize) -> Self {
        let mut ended_at: Vec<Option<f64>> = vec![None; n];
        if let Ended::Run(end) = &summary.ended {
            for (i, v) in end.vehicles.iter().flatten().enumerate().take(n) {
                if v.outcome != "completed" {
                    ended_at[i] = v.t_end_s;
                }
            }
        }
        let mut end_of: Vec<Option<f64>> = vec![None; n];
        if let Ended::Run(end) = &summary.ended {
            for (i, v) in end.vehicles.iter().flatten().enumerate().take(n) {
                end_of[i] = v.t_end_s;
            }
        }
        let mut last_row = vec![usize::MAX; n];
        for (row, id) in ids.iter().enumerate() {
            if let Some(i) = id.filter(|&i| i < n) {
                last_row[i] = row;
            }
        }
        Self {
            summary,
            n,
            traces: vec![Vec::new(); n],
            times: Vec::new(),
            last_line: vec![0u64; n],
            ended_at,
            end_of,
            done: vec![false; n],
            last_row,
            time_set_by: Vec::new(),
            all_last: Vec::new(),
        }
    }

    /// The next row `t` (the `row`-th, at trace.csv's `line`, of vehicle `id`) given to its
    /// vehicle, or why it cannot be that vehicle's next.
    fn take(
        &mut self,
        row: usize,
        t: &TraceRow,
        id: Option<usize>,
        line: u64,
    ) -> Result<(), String> {
        let n = self.n;
        let Some(i) = id.filter(|&i| i < n) else {
            return Err(format!(
                "trace.csv:{line}: the vehicle column is not one of the team's {n} vehicles",
            ));
        };
        if let Some(e) = self.end_of[i].filter(|e| t.t_s > e + 1e-9 * e.abs().max(1.0)) {
            return Err(format!(
                "trace.csv:{line}: vehicle {i} has a row at t = {} s, after its end (t_end_s = {} s in summary.json's vehicles[{i}])",
                Echo(t.t_s),
                Echo(e)
            ));
        }
        if self.done[i] {
            return Err(format!(
                "trace.csv:{line}: vehicle {i} has a row after its last (at its end, t_end_s = {} s in summary.json)",
                self.ended_at[i].map_or("?".to_string(), |e| Echo(e).to_string())
            ));
        }
        let k = self.traces[i].len();
        if self.ended_at[i] == Some(t.t_s)
            && self.times.get(k) != Some(&t.t_s)
            && self.times.last().is_none_or(|l| *l < t.t_s)
        {
            self.traces[i].push(*t);
            self.last_line[i] = line;
            self.done[i] = true;
            return Ok(());
        }
        if self.times.last() != Some(&t.t_s) {
            self.times.push(t.t_s);
            self.time_set_by.push((i, row, line));
            self.all_last.push(true);
        }
        if let Some(c) = self.all_last.last_mut() {
            *c &= row == self.last_row[i];
        }
        if self.times.get(k) != Some(&t.t_s) {
            return Err(self.off_schedule(i, k, t.t_s, line));
        }
        self.traces[i].push(*t);
        self.last_line[i] = line;
        Ok(())
    }

    /// Why vehicle `i`'s row `k` (0-based) at `t_s`, trace.csv's `line`, is not at the k-th
    /// recorded time.
    fn off_schedule(&self, i: usize, k: usize, t_s: f64, line: u64) -> String {
        let (n, times) = (self.n, &self.times);
        // The time this vehicle skipped is held by other vehicles' last rows only: a
        // time off the recorded ones, which only a vehicle's end is, but the summary
        // of one of them ends it elsewhere (a later end, or `completed`). That vehicle
        // is named, not this one (att32f-8: "vehicle 0's row 5" was blamed at a line
        // that was right; att32g-4: so it was when two vehicles ended there).
        if let Some(&(j0, _, _)) = self.time_set_by.get(k) {
            let ends_there = |j: usize| {
                self.traces[j].last().map(|r| r.t_s) == Some(times[k])
                    && self.ended_at[j] != Some(times[k])
            };
            let j = (0..n).find(|&j| j != i && ends_there(j)).unwrap_or(j0);
            let jline = self.last_line[j];
            if j != i && self.all_last[k] && times[k] < t_s {
                return format!(
                    "trace.csv:{jline}: vehicle {j}'s last row is at t = {} s, between the recorded times{} and t = {} s (trace.csv:{line}), off them, as a vehicle's row is only at its end, but summary.json's vehicles[{j}] {}: the summary is not this trace's, or a row of vehicle {j} is missing",
                    Echo(times[k]),
                    k.checked_sub(1)
                        .map_or(String::new(), |p| format!(" t = {} s", Echo(times[p]))),
                    Echo(t_s),
                    vehicle_end(self.summary, j),
                );
            }
        }
        format!(
            "trace.csv:{line}: vehicle {i}'s row {} is at t = {} s, but recorded time {} is {}: a row of the team's trace is missing or out of order (each vehicle has a row at every recorded time until it ends)",
            k + 1,
            Echo(t_s),
            k + 1,
            times.get(k).map_or("not there".to_string(), |x| format!("t = {} s", Echo(*x)))
        )
    }

    /// After the last row: every vehicle has rows, each ends where its summary ends it.
    fn check_ends(&self) -> Result<(), String> {
        let (n, traces, times) = (self.n, &self.traces, &self.times);
        // Every vehicle of the team has rows (att32f-1: one without any was drawn nowhere).
        if let Some(i) = traces.iter().position(Vec::is_empty) {
            return Err(format!(
                "trace.csv has no row of vehicle {i}, one of the team's {n} (summary.json's team.vehicle_count)",
            ));
        }
        let Ended::Run(end) = &self.summary.ended else {
            return Ok(());
        };
        // A vehicle that completed the run has a row at the last recorded time.
        for (i, v) in end.vehicles.iter().flatten().enumerate().take(n) {
            let rows = traces[i].len();
            if v.outcome == "completed" && rows < times.len() {
                return Err(format!(
                    "trace.csv:{}: vehicle {i}'s rows end at t = {} s, but it completed the run (summary.json) and the trace goes on to t = {} s: a row of the team's trace is missing",
                    self.last_line[i],
                    traces[i].last().map_or("?".to_string(), |r| Echo(r.t_s).to_string()),
                    Echo(times[times.len() - 1])
                ));
            }
        }
        // Every vehicle's rows end at its end (its last valid state is always written, at the
        // step it ended): a vehicle whose summary ends it later than its last row (a row cut,
        // or another run's summary) is refused naming its last row (att32f-8).
        for (i, v) in end.vehicles.iter().flatten().enumerate().take(n) {
            let Some((e, last)) = v.t_end_s.zip(traces[i].last()) else {
                continue;
            };
            if last.t_s < e - 1e-9 * e.abs().max(1.0) {
                return Err(format!(
                    "trace.csv:{}: vehicle {i}'s rows end at t = {} s, but summary.json's vehicles[{i}] {}: a row of the team's trace is missing, or the summary is not this trace's",
                    self.last_line[i],
                    Echo(last.t_s),
                    vehicle_end(self.summary, i),
                ));
            }
        }
        Ok(())
    }
}

impl RunData {
    /// Loads `DIR/trace.csv`, `DIR/summary.json` and `DIR/scenario.toml` of a single-vehicle
    /// run (a team's run is refused: [`RunData::load_team`]).
    pub fn load(dir: &Path) -> Result<Self, PlotError> {
        let run = Self::read(dir, false)?.0;
        check_scenario_is_runs(&run)
            .and_then(|()| check_summary_numbers(&run))
            .map_err(|m| PlotError::Data(format!("{}: {m}", dir.display())))?;
        Ok(run)
    }

    /// Whether `DIR/summary.json` is a team's run (it has a `team` object); `false` when it
    /// cannot be read (the loading then says why).
    pub fn is_team(dir: &Path) -> bool {
        Summary::read(&dir.join("summary.json")).is_ok_and(|s| s.team().is_some())
    }

    /// Loads a run directory as its vehicles: a single-vehicle run as one, a team's run (a
    /// `team` object in `summary.json`, a `vehicle` column in `trace.csv`) as one [`RunData`]
    /// per vehicle in the listed order, named `vehicle I`, each with its rows (the team's
    /// `summary.json` and scenario shared). A `vehicle` cell that is not a vehicle of the team
    /// (`0..team.vehicle_count`) is a data error naming its line.
    pub fn load_team(dir: &Path) -> Result<Vec<Self>, PlotError> {
        Self::load_team_named(dir, false)
    }

    /// [`load_team`](Self::load_team), a team's vehicles named `DIR vehicle I` when
    /// `with_run` (several runs drawn together: their vehicles, and the messages that compare
    /// them, tell the runs apart; issue 32, att32d-7), else `vehicle I`.
    pub fn load_team_named(dir: &Path, with_run: bool) -> Result<Vec<Self>, PlotError> {
        let (all, ids, lines) = Self::read(dir, true)?;
        let in_dir = |m: String| PlotError::Data(format!("{}: {m}", dir.display()));
        let Some(n) = all.summary.team().map(|t| t.vehicle_count) else {
            check_scenario_is_runs(&all)
                .and_then(|()| check_summary_numbers(&all))
                .map_err(in_dir)?;
            return Ok(vec![all]);
        };
        if !(1..=1_000_000).contains(&n) {
            return Err(in_dir(
                "summary.json: team.vehicle_count is not a vehicle count".into(),
            ));
        }
        check_team_lists(&all, n)
            .and_then(|()| check_scenario_is_runs(&all))
            .map_err(in_dir)?;
        let mut rows = TeamRows::new(&all.summary, &ids, n);
        for (row, ((t, id), line)) in all.trace.iter().zip(&ids).zip(&lines).enumerate() {
            rows.take(row, t, *id, *line).map_err(in_dir)?;
        }
        rows.check_ends().map_err(in_dir)?;
        // Last: an edit the trace contradicts is named by its row first.
        check_summary_numbers(&all).map_err(in_dir)?;
        let traces = rows.traces;
        Ok(Self::into_vehicles(all, traces, with_run))
    }

    /// A team's run `all` (its rows already split into `traces`, one per vehicle) as one
    /// [`RunData`] per vehicle ([`load_team_named`](Self::load_team_named)).
    fn into_vehicles(all: Self, traces: Vec<Vec<TraceRow>>, with_run: bool) -> Vec<Self> {
        // The rows are in `traces` now: each vehicle clones the rest only, without the lists
        // of every vehicle (`vehicles`, `team.neighbours`: N of them in each of N copies), and
        // shares the scenario (a clone of it shares its keys and settings: a `team.starts` of
        // N starts once was copied into each of the N vehicles, O(N^2) memory, mem45).
        let mut all = Self {
            trace: Vec::new(),
            ..all
        };
        let mut vehicles = Vec::new();
        if let Ended::Run(end) = &mut all.summary.ended {
            vehicles = end.vehicles.take().unwrap_or_default();
            if let Some(team) = end.team.as_mut() {
                team.neighbours = Vec::new();
            }
        }
        // The resolved scenario summary.json records (checked against `scenario.toml` already,
        // [`check_scenario_is_runs`]) is vehicle 0's only: the others' is `null` (it lists
        // `team.starts`, N of them, in each of N copies, mem45).
        let recorded = std::mem::take(&mut all.summary.scenario);
        traces
            .into_iter()
            .enumerate()
            .map(|(i, trace)| {
                // The vehicle's own outcome and metrics (`vehicles[i]`) over the team's
                // top-level ones (vehicle 0's); the rest (`team`, `data_files`) shared.
                let mut summary = all.summary.clone();
                if i == 0 {
                    summary.scenario = recorded.clone();
                }
                if let (Some(own), Ended::Run(end)) = (vehicles.get(i), &mut summary.ended) {
                    end.record = own.clone();
                }
                Self {
                    name: if with_run {
                        format!("{} vehicle {i}", all.name)
                    } else {
                        format!("vehicle {i}")
                    },
                    trace,
                    summary,
                    ..all.clone()
                }
            })
            .collect()
    }

    /// The run and each row's `vehicle` cell (`None` when there is no such column or it does
    /// not parse); a team's run is refused unless `team_ok`.
    /// Each row's line in trace.csv comes third.
    #[allow(clippy::type_complexity)]
    fn read(dir: &Path, team_ok: bool) -> Result<(Self, Vec<Option<usize>>, Vec<u64>), PlotError> {
        let err = |m: String| PlotError::Data(format!("{}: {m}", dir.display()));
        let cannot = |m: String| PlotError::Input(format!("{}: {m}", dir.display()));
        let summary = read_summary(dir, team_ok)?;
        let scenario = load_scenario(Some(&dir.join("scenario.toml")), &[]).map_err(|e| {
            let m = format!("scenario.toml: {e}");
            if e.is_unreadable_input() {
                cannot(m)
            } else {
                err(m)
            }
        })?;
        let (trace, vehicles, lines) = read_trace(dir, &summary, &scenario, team_ok)?;
        if trace.is_empty() {
            return Err(err(format!(
                "trace.csv has no rows: {}",
                why_no_rows(&summary, &scenario)
            )));
        }
        // The name as every figure, page and message shows it: each character the plain-text
        // rule refuses as its escape (`\u{202e}`, `\x1b`), as `--title` is drawn; a legend
        // once drew U+202E and ESC as U+FFFD and kept U+2028 raw (att30c-10).
        let name = dir.file_name().map_or_else(
            || dir.display().to_string(),
            |n| isotrack_core::numtext::Escaped(&n.to_string_lossy()).to_string(),
        );
        Ok((
            Self {
                name,
                dir: dir.to_path_buf(),
                trace,
                summary,
                scenario,
            },
            vehicles,
            lines,
        ))
    }

    /// Start of the steady-state window, s.
    pub fn steady_state_start_s(&self) -> f64 {
        let spec = self.scenario.spec();
        (1.0 - spec.metrics.steady_state_fraction) * spec.sim.duration_s
    }
}

/// A reader that reads each `\r\n` of `R` as `\n` (a `\r` not followed by `\n` is kept), so
/// that the csv reader's line of a record is the file's line whatever the line ending
/// (att32g-9: with `\r\n` it was one line too early).
struct CrlfAsLf<R> {
    inner: R,
    /// Bytes read from `inner`, `buf[at..]` not yet given out.
    buf: Vec<u8>,
    at: usize,
    /// A `\r` ended the last chunk read: whether it is kept depends on the next byte.
    pending_cr: bool,
}

impl<R: std::io::Read> CrlfAsLf<R> {
    fn new(inner: R) -> Self {
        Self {
            inner,
            buf: Vec::new(),
            at: 0,
            pending_cr: false,
        }
    }
}

impl<R: std::io::Read> std::io::Read for CrlfAsLf<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        while self.at >= self.buf.len() {
            let mut chunk = [0u8; 64 * 1024];
            let n = self.inner.read(&mut chunk)?;
            self.buf.clear();
            self.at = 0;
            if n == 0 {
                if std::mem::take(&mut self.pending_cr) {
                    self.buf.push(b'\r');
                    continue;
                }
                return Ok(0);
            }
            for &b in &chunk[..n] {
                if std::mem::take(&mut self.pending_cr) && b != b'\n' {
                    self.buf.push(b'\r');
                }
                if b == b'\r' {
                    self.pending_cr = true;
                } else {
                    self.buf.push(b);
                }
            }
        }
        let k = out.len().min(self.buf.len() - self.at);
        out[..k].copy_from_slice(&self.buf[self.at..self.at + k]);
        self.at += k;
        Ok(k)
    }
}

/// The one check of a trace row shared by `plot` and `report` (and the Python package's, which
/// read runs here), issue 30 (att30c-18): its time `v[0]` finite, not before the row before
/// (`before`, a team's rows share a time) and not past the run's end (`t_end_s` of
/// `summary.json`, to a rounding of 1e-9 of it); its position `v[1]`, `v[2]` finite and within
/// the +-[`MAX_AXIS_ABS`](crate::limits::MAX_AXIS_ABS) m a figure can show, or both NaN (no
/// position: `fly`'s rows while the vehicle reports none). A doctored row (a
/// time going back, a last row at 1e9 s in a 5 s run, `x_m = 1e300` or NaN) once gave a page
/// whose map spanned 1e300 m or whose time series were squashed to the left edge.
fn check_row(v: &[f64; 7], before: Option<f64>, t_end_s: Option<f64>) -> Result<(), String> {
    use isotrack_core::numtext::Num;
    let t = v[0];
    if !(t.is_finite() && t >= 0.0) {
        return Err(format!("t_s = {} is not a time >= 0", Num(t)));
    }
    if let Some(b) = before.filter(|b| t < *b) {
        return Err(format!(
            "t_s = {} goes back in time (the row before is at {} s)",
            Num(t),
            Num(b)
        ));
    }
    if let Some(end) = t_end_s.filter(|e| e.is_finite() && t > e + 1e-9 * e.abs().max(1.0)) {
        return Err(format!(
            "t_s = {} is past the run's end (summary.json: t_end_s = {} s)",
            Num(t),
            Num(end)
        ));
    }
    // `fly` writes a row whose position the vehicle did not report valid as NaN, NaN
    // (unknown, not drawn); one coordinate NaN alone is no position isotrack writes.
    if v[1].is_nan() && v[2].is_nan() {
        return Ok(());
    }
    for (name, x) in [("x_m", v[1]), ("y_m", v[2])] {
        if !(x.is_finite() && x.abs() <= crate::limits::MAX_AXIS_ABS) {
            return Err(format!(
                "{name} = {} is not a position within +-{:e} m (what a figure can show)",
                Num(x),
                crate::limits::MAX_AXIS_ABS
            ));
        }
    }
    Ok(())
}

/// What decides the field a run's map shows: its `[field]` section (every key, file paths
/// absolute as written in `scenario.toml`), `controller.level` (the isoline drawn), and for a
/// puff plume with a meander `sim.seed` (the meander's random modes), each as `(key, value as
/// JSON text)`. A puff plume without meander (`field.meander_std_mps = 0`) is the same field
/// whatever its seed and its `meander_correlation_s`: its meander's amplitude is 0, so every
/// puff is at `source + U t` (`isotrack_fields::puff`, `displacement`), the seed and the
/// correlation time shaping only modes that are multiplied by 0.
fn field_identity(s: &isotrack_scenario::Scenario) -> Vec<(String, String)> {
    let f = s.file();
    let meander = match s.field() {
        isotrack_scenario::field::FieldModel::Puff(p) => Some(p.params().meander_std_mps != 0.0),
        _ => None,
    };
    let mut keys: Vec<(String, String)> = match serde_json::to_value(&f.field) {
        Ok(serde_json::Value::Object(m)) => m
            .into_iter()
            .filter(|(k, _)| !(meander == Some(false) && k == "meander_correlation_s"))
            .map(|(k, v)| (format!("field.{k}"), v.to_string()))
            .collect(),
        other => vec![("field".into(), format!("{other:?}"))],
    };
    keys.push(("controller.level".into(), format!("{:?}", s.level())));
    if meander == Some(true) {
        keys.push(("sim.seed".into(), f.sim.seed.unwrap_or(0).to_string()));
    }
    keys
}

/// The SHA-256 of each data file a run's field was read from, by path, as its `summary.json`
/// records them (`data_files`; none in a run written before they were recorded).
fn data_digests(r: &RunData) -> Vec<(String, String)> {
    r.summary
        .data_files()
        .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
        .unwrap_or_default()
}

/// Checks each run's data files, as its scenario reads them now (the field drawn), against
/// the digests its `summary.json` recorded (`data_files`): the field is drawn from the files as
/// they are now, so a file changed after the run would draw another field under its path.
/// att43-4: the scenario's own files are checked, not only the files the summary lists: a
/// summary naming a file the scenario does not read, or lacking one it reads, is not this
/// run's summary. Each a [`PlotError::Data`] (65) naming the run, the file and `data_files`.
/// A summary with no digests at all (an older isotrack's) is drawn, with
/// [`unrecorded_data_files_note`]'s note.
pub fn data_files_unchanged(runs: &[RunData]) -> Result<(), PlotError> {
    let clip = isotrack_scenario::load::clip;
    let short = |d: &str| clip(&d.chars().take(16).collect::<String>());
    for r in runs {
        let Some(recorded) = r.summary.data_files().filter(|d| !d.is_empty()) else {
            continue;
        };
        let now = r.scenario.data_file_digests();
        if let Some(path) = recorded.keys().find(|p| !now.contains_key(*p)) {
            return Err(PlotError::Data(format!(
                "{}: summary.json data_files names {}, a file its scenario's field does not read ({}): the summary is not this run's",
                r.dir.display(),
                clip(path),
                field_files_text(now)
            )));
        }
        for (path, current) in now {
            let Some(was) = recorded.get(path) else {
                return Err(PlotError::Data(format!(
                    "{}: summary.json data_files has no digest of {}, a data file its scenario's field reads (it names {}): the summary is not this run's",
                    r.dir.display(),
                    clip(path),
                    clip(&recorded.keys().cloned().collect::<Vec<_>>().join(", "))
                )));
            };
            if was != current {
                return Err(PlotError::Data(format!(
                    "{}: data file {} changed after the run (SHA-256 {} recorded in its summary.json, {} now): the field drawn would not be the one it ran over; re-run it",
                    r.dir.display(),
                    clip(path),
                    short(was),
                    short(current),
                )));
            }
        }
    }
    Ok(())
}

/// The data files a field reads, for a message (`none` for a field without files).
fn field_files_text(files: &std::collections::BTreeMap<String, String>) -> String {
    if files.is_empty() {
        return "none".into();
    }
    isotrack_scenario::load::clip(&files.keys().cloned().collect::<Vec<_>>().join(", "))
}

/// A note naming the runs whose field reads data files but whose `summary.json` recorded no
/// digest of them (`data_files` missing or empty: a run written before they were recorded):
/// the field drawn for them is the files as they are now, unchecked against what they ran over
/// (att43-4: drawn without a word), nor against the other runs' files. `None` when every run
/// with data files recorded them.
pub fn unrecorded_data_files_note(runs: &[RunData]) -> Option<String> {
    let has_files = |r: &RunData| !r.scenario.data_file_digests().is_empty();
    // `data_files` is left out of a summary when empty, so recorded means non-empty.
    let recorded = |r: &RunData| r.summary.data_files().is_some_and(|d| !d.is_empty());
    // Each run by its directory: a team's vehicles share one summary, named once.
    let mut missing: Vec<String> = runs
        .iter()
        .filter(|r| has_files(r) && !recorded(r))
        .map(|r| r.dir.display().to_string())
        .collect();
    missing.dedup();
    if missing.is_empty() {
        return None;
    }
    let others = runs.iter().any(|r| has_files(r) && recorded(r));
    Some(format!(
        "{} recorded no data_files digests in summary.json (an older run): the field drawn is its data file as it is now, not checked against the one it ran over{}",
        isotrack_scenario::load::clip(&missing.join(", ")),
        if others {
            ", nor against the other runs' data files"
        } else {
            ""
        }
    ))
}

/// [`field_identity`] with each data file's path (`field.path`, `field.paths`) replaced by the
/// SHA-256 the run's `summary.json` recorded for it: the field by its bytes, wherever the
/// file was (att43-12: the same bytes copied to a second folder were "runs over different
/// fields"). `None` when a file has no recorded digest.
fn field_identity_by_content(r: &RunData) -> Option<Vec<(String, String)>> {
    let recorded = r.summary.data_files().filter(|d| !d.is_empty())?;
    let digest_of = |v: &serde_json::Value| -> Option<serde_json::Value> {
        match v {
            serde_json::Value::String(p) => recorded.get(p).cloned().map(serde_json::Value::String),
            _ => None,
        }
    };
    let mut keys = field_identity(&r.scenario);
    for (k, v) in &mut keys {
        if k.as_str() != "field.path" && k.as_str() != "field.paths" {
            continue;
        }
        let value: serde_json::Value = serde_json::from_str(v).ok()?;
        let by_content = match &value {
            serde_json::Value::Null => continue,
            serde_json::Value::Array(list) => {
                serde_json::Value::Array(list.iter().map(digest_of).collect::<Option<_>>()?)
            }
            one => digest_of(one)?,
        };
        *v = by_content.to_string();
    }
    Some(keys)
}

/// Checks that every run shows the same field and isoline (see `field_identity`: the
/// `[field]` section, the level, a meandering puff plume's seed; and the content of its data
/// files where both runs recorded their digests), since a figure or page of several runs
/// draws one field under every path. Otherwise a [`PlotError::Data`] naming the first run and
/// the first that differs from it, and the first key that differs with both values. Then each
/// run's recorded data files against the files as they are now ([`data_files_unchanged`]).
pub fn same_field(runs: &[RunData]) -> Result<(), PlotError> {
    let Some(first) = runs.first() else {
        return Ok(());
    };
    let a = field_identity(&first.scenario);
    let a_files = data_digests(first);
    for r in &runs[1..] {
        let b = field_identity(&r.scenario);
        if a == b {
            // One path, other content: a data file overwritten in place between the runs
            // (compared where both runs recorded the file's digest).
            let b_files = data_digests(r);
            if let Some((path, da, db)) = a_files.iter().find_map(|(p, da)| {
                b_files
                    .iter()
                    .find(|(q, db)| q == p && db != da)
                    .map(|(_, db)| (p, da, db))
            }) {
                let clip = isotrack_scenario::load::clip;
                return Err(PlotError::Data(format!(
                    "{} and {} are runs over different fields: their data file {} held other content (SHA-256 {} in {}, {} in {}: overwritten in place between the runs), so these are not drawn together; plot or report each run on its own",
                    first.dir.display(),
                    r.dir.display(),
                    clip(path),
                    clip(&da.chars().take(16).collect::<String>()),
                    first.name,
                    clip(&db.chars().take(16).collect::<String>()),
                    r.name,
                )));
            }
            continue;
        }
        // Other paths, the same bytes (both runs recorded their files' digests): one field.
        if let (Some(ca), Some(cb)) = (
            field_identity_by_content(first),
            field_identity_by_content(r),
        ) {
            if ca == cb {
                continue;
            }
        }
        let lookup = |set: &[(String, String)], k: &str| {
            set.iter()
                .find(|(key, _)| key == k)
                .map_or_else(|| "unset".to_string(), |(_, v)| v.clone())
        };
        let key = a
            .iter()
            .chain(&b)
            .map(|(k, _)| k.as_str())
            .find(|k| lookup(&a, k) != lookup(&b, k))
            .unwrap_or("field");
        let clip = isotrack_scenario::load::clip;
        return Err(PlotError::Data(format!(
            "{} and {} are runs over different fields ({}: {} in {}, {} in {}): a figure of several runs draws one field and isoline under every path, so these are not drawn together; plot or report each run on its own",
            first.dir.display(),
            r.dir.display(),
            key,
            clip(&lookup(&a, key)),
            first.name,
            clip(&lookup(&b, key)),
            r.name,
        )));
    }
    // The runs agree with each other; each also with its data files as they are now.
    data_files_unchanged(runs)
}
