//! What `benchmark --resume` keeps of a task's stored results (`tasks/ID/task.json`): the runs'
//! measurements, checked as a sweep's stored rows are ([`isotrack_runs::sweep::check`]), and
//! vehicle 0's picture path; everything else (scores, title, gains, picture) is recomputed.
//!
//! A stored task is reused when it reads as a task's results and its digest (suite, task,
//! controllers, gains, version, scenario file) matches: a changed suite reruns it, as does a file
//! that does not parse. A file whose digest matches but whose content the suite contradicts
//! (runs other than the suite's seeds x controllers, a value no run can have) was edited or
//! damaged: [`BenchError::Damaged`], naming the file and the field (docs/BENCHMARK.md).

use crate::one_run::{context, prepare};
use crate::registry::Registry;
use crate::results::{controller_means, BenchError, RunRow, TaskResult, TeamRow, Trajectory};
use crate::score::{score, team_total, Score, Scoring, WEIGHTS};
use crate::suite::Task;
use isotrack_runs::results::{real_cell, INVALID_SCENARIO};
use isotrack_runs::sweep::check::{check_metrics, check_span, check_team_record, TeamBounds};
use isotrack_scenario::Scenario;
use isotrack_sim::{Outcome, RunMetrics, RunResult};
use std::collections::BTreeMap;
use std::path::Path;

/// The outcomes a picture's path may have.
const PATH_OUTCOMES: [&str; 4] = ["completed", "diverged", "left_field", INVALID_SCENARIO];

/// Everything a stored task is checked against.
pub(crate) struct Expected<'a> {
    /// The task.
    pub task: &'a Task,
    /// Its base scenario.
    pub base: &'a Scenario,
    /// The registry.
    pub reg: &'a Registry,
    /// The controllers, in order.
    pub controllers: &'a [String],
    /// The suite's scoring seeds, in order.
    pub seeds: &'a [u64],
    /// The gains each built-in law runs with.
    pub gains: &'a BTreeMap<String, BTreeMap<String, f64>>,
    /// The score formula.
    pub scoring: Scoring,
    /// At most this many points per picture path.
    pub max_points: usize,
}

/// The task of `prev` (read from `file`, its digest `digest` matching) rebuilt from its checked
/// runs and paths: scores recomputed from the runs, the picture from the paths, the title and
/// gains the suite's.
pub(crate) fn reuse(
    prev: TaskResult,
    file: &Path,
    e: &Expected<'_>,
    picture: impl FnOnce(&[Trajectory]) -> isotrack_plot::FieldPicture,
) -> Result<TaskResult, BenchError> {
    let damaged = |field: String, why: String| BenchError::Damaged {
        path: file.display().to_string(),
        message: format!("{field}: {why} (remove the file to rerun the task)"),
    };
    let runs = check_runs(prev.runs, e, &damaged)?;
    let scores = controller_means(e.controllers, &runs);
    check_paths(&prev.trajectories, e, &damaged)?;
    let picture = picture(&prev.trajectories);
    Ok(TaskResult {
        id: e.task.id.clone(),
        title: e.task.title.clone(),
        scores,
        gains: e.gains.clone(),
        runs,
        trajectories: prev.trajectories,
        picture,
        digest: prev.digest,
        team: e.base.spec().team.is_some(),
    })
}

/// The stored runs are the suite's, in its order (each controller's runs over the scoring
/// seeds), and each possible ([`check_run`]): the runs with their scores recomputed.
fn check_runs(
    stored: Vec<RunRow>,
    e: &Expected<'_>,
    damaged: &dyn Fn(String, String) -> BenchError,
) -> Result<Vec<RunRow>, BenchError> {
    let jobs: Vec<(&String, u64)> = e
        .controllers
        .iter()
        .flat_map(|c| e.seeds.iter().map(move |s| (c, *s)))
        .collect();
    if stored.len() != jobs.len() {
        return Err(damaged(
            "runs".into(),
            format!(
                "{} runs where the suite scores {} ({} controllers x {} seeds)",
                stored.len(),
                jobs.len(),
                e.controllers.len(),
                e.seeds.len()
            ),
        ));
    }
    let mut runs = Vec::with_capacity(jobs.len());
    for (i, (row, (c, seed))) in stored.into_iter().zip(&jobs).enumerate() {
        let at = |f: &str| format!("runs[{i}].{f}");
        if &row.controller != *c {
            return Err(damaged(
                at("controller"),
                format!(
                    "`{}` where the suite's run {i} is {c}'s",
                    isotrack_scenario::load::clip(&row.controller)
                ),
            ));
        }
        if row.seed != *seed {
            return Err(damaged(
                at("seed"),
                format!("{} where the suite's run {i} has seed {seed}", row.seed),
            ));
        }
        let checked = check_run(row, e, c, *seed).map_err(|(f, why)| damaged(at(&f), why))?;
        runs.push(checked);
    }
    Ok(runs)
}

/// The stored picture paths: one per controller, in the suite's order, each with an outcome a
/// path may have ([`PATH_OUTCOMES`]), at most `max_points` points, every one finite and within
/// [`isotrack_scenario::ranges::MAX_COORDINATE_M`] of the origin.
fn check_paths(
    paths: &[Trajectory],
    e: &Expected<'_>,
    damaged: &dyn Fn(String, String) -> BenchError,
) -> Result<(), BenchError> {
    if paths.len() != e.controllers.len() {
        return Err(damaged(
            "trajectories".into(),
            format!(
                "{} paths where the suite has {} controllers",
                paths.len(),
                e.controllers.len()
            ),
        ));
    }
    for (i, (t, c)) in paths.iter().zip(e.controllers).enumerate() {
        let at = |f: &str| format!("trajectories[{i}].{f}");
        if &t.controller != c {
            return Err(damaged(
                at("controller"),
                format!(
                    "`{}` where the suite's controller {i} is {c}",
                    isotrack_scenario::load::clip(&t.controller)
                ),
            ));
        }
        if !PATH_OUTCOMES.contains(&t.outcome.as_str()) {
            return Err(damaged(
                at("outcome"),
                format!(
                    "`{}` is not one of {PATH_OUTCOMES:?}",
                    isotrack_scenario::load::clip(&t.outcome)
                ),
            ));
        }
        if t.points.len() > e.max_points {
            return Err(damaged(
                at("points"),
                format!(
                    "{} points where a picture path has at most {}",
                    t.points.len(),
                    e.max_points
                ),
            ));
        }
        let lim = isotrack_scenario::ranges::MAX_COORDINATE_M;
        if let Some(j) = t
            .points
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite() && v.abs() <= lim))
        {
            return Err(damaged(
                format!("trajectories[{i}].points[{j}]"),
                format!("not a finite position within {lim} m of the origin"),
            ));
        }
    }
    Ok(())
}

/// One stored run checked against its scenario, with its score recomputed; `Err((field, why))`.
fn check_run(
    row: RunRow,
    e: &Expected<'_>,
    controller: &str,
    seed: u64,
) -> Result<RunRow, (String, String)> {
    let entrant = e
        .reg
        .get(controller)
        .ok_or_else(|| ("controller".to_string(), "not registered".to_string()))?;
    let is_team = e.base.spec().team.is_some();
    // Every run of the suite resolves (checked before any task runs), so a run is
    // `invalid_scenario` only when a team's engine refused it: never in a single-vehicle task.
    let s = prepare(e.base, e.task, entrant, e.gains.get(controller), seed).ok();
    if row.outcome == INVALID_SCENARIO {
        return check_invalid_run(row, s.is_some() && !is_team, controller, seed);
    }
    let Some(s) = s else {
        return Err((
            "outcome".into(),
            format!(
                "{} for a run whose scenario is invalid: it was never run",
                isotrack_scenario::load::clip(&row.outcome)
            ),
        ));
    };
    let duration = check_measurements(&row, &s)?;
    let completed = row.outcome == "completed";
    let t_end_s = if completed { duration } else { 0.0 };
    let ctx = context(&s, e.task, e.scoring);
    let mut r = row;
    if !is_team {
        if r.team.is_some() {
            return Err((
                "team".into(),
                "team columns in a task whose scenario has no [team]".into(),
            ));
        }
        r.score = score(&result_of(&r, t_end_s), &ctx);
        return Ok(r);
    }
    let Some(team) = r.team.take() else {
        return Err(("team".into(), "no team columns in a team task's run".into()));
    };
    let n = s.spec().team.as_ref().map_or(0, |t| t.starts.len());
    let (total, parts, team) = check_team(team, &r, n, &s).map_err(|(f, m)| {
        let f = if f.is_empty() {
            "team".to_string()
        } else {
            format!("team.{f}")
        };
        (f, m)
    })?;
    r.score = Score { total, parts };
    r.team = Some(team);
    Ok(r)
}

/// A stored `invalid_scenario` run: refused when its scenario is valid and would have been run
/// (`ran`: a single-vehicle task whose run prepares), or when it holds any measurement (it is
/// then [`RunRow::of`] with no result and a zero score).
fn check_invalid_run(
    row: RunRow,
    ran: bool,
    controller: &str,
    seed: u64,
) -> Result<RunRow, (String, String)> {
    let zero = Score {
        total: 0.0,
        parts: [0.0; 5],
    };
    let want = RunRow::of(controller, seed, None, zero);
    if ran {
        return Err((
            "outcome".into(),
            "invalid_scenario for a run whose scenario is valid: it was run".into(),
        ));
    }
    let mut r = row;
    r.score = zero;
    if r != want {
        return Err((
            "outcome".into(),
            "an invalid_scenario run holds measurements".into(),
        ));
    }
    Ok(r)
}

/// A stored run's measurements checked as a sweep's row is ([`check_metrics`] of a task's
/// record, [`check_span`] against the steps of its scenario `s` under the limit it flew) and its
/// track losses at most one per step: the run's planned duration `N dt`, in s.
fn check_measurements(row: &RunRow, s: &Scenario) -> Result<f64, (String, String)> {
    let Some(mut span) = isotrack_scenario::build::run_span(s.file()) else {
        return Err(("outcome".into(), "the run's steps cannot be counted".into()));
    };
    // The limit the run flew (a fixed wing's airframe limit included).
    span.turn_rate_limit_radps = s.max_turn_rate_radps();
    let duration = span.n_steps as f64 * span.dt_s;
    let cells = record_cells(row, duration);
    let cell = |n: &str| cells.get(n).map_or("", |c| c.as_str());
    check_metrics(&row.outcome, &cell, false).map_err(located)?;
    check_span(&span, &row.outcome, &cell, &|n| n.to_string()).map_err(located)?;
    if row.track_losses > span.n_steps {
        return Err((
            "track_losses".into(),
            format!(
                "{} track losses in a run of {} steps",
                row.track_losses, span.n_steps
            ),
        ));
    }
    Ok(duration)
}

/// A stored run's measurements as the cells of a sweep's row, written as a sweep writes them
/// ([`real_cell`]). A completed run ended at its last planned step (`t_end_s = N dt`, with
/// `duration` as the run computes it); any other within the run, its `t_end_s` not recorded.
fn record_cells(row: &RunRow, duration: f64) -> BTreeMap<&'static str, String> {
    let mut cells: BTreeMap<&str, String> = BTreeMap::new();
    cells.insert("outcome", row.outcome.clone());
    cells.insert("convergence_time_s", real_cell(row.convergence_time_s));
    cells.insert(
        "time_in_band_fraction",
        real_cell(row.time_in_band_fraction),
    );
    cells.insert(
        "steady_state_rms_isoline_distance_m",
        real_cell(row.steady_state_rms_isoline_distance_m),
    );
    cells.insert(
        "steady_state_rms_error",
        real_cell(row.steady_state_rms_error),
    );
    cells.insert("control_effort", real_cell(Some(row.control_effort)));
    if row.outcome == "completed" {
        cells.insert("t_end_s", real_cell(Some(duration)));
    }
    cells
}

/// A row check's message located in a task's record: the field it names (the first of the
/// record's fields it starts with or names in parentheses, else `outcome`) and the message
/// without it when it leads.
fn located(m: String) -> (String, String) {
    let f = [
        "outcome",
        "control_effort",
        "convergence_time_s",
        "time_in_band_fraction",
    ]
    .into_iter()
    .chain([
        "steady_state_rms_isoline_distance_m",
        "steady_state_rms_error",
        "samples",
    ])
    .find(|n| m.starts_with(n) || m.contains(&format!(" ({n})")))
    .unwrap_or("outcome")
    .to_string();
    let m = m
        .strip_prefix(&format!("{f}: "))
        .map_or(m.clone(), str::to_string);
    (f, m)
}

/// A team run's team row checked (its counts, its parts in `[0, 1]`, its metrics as a sweep's
/// team cells are) and its score recomputed ([`team_total`]): `(total, parts, row)`.
fn check_team(
    mut team: TeamRow,
    row: &RunRow,
    n: usize,
    s: &Scenario,
) -> Result<(f64, [f64; 5], TeamRow), (String, String)> {
    if team.vehicles != n {
        return Err((
            "vehicles".into(),
            format!("{} where the task's team has {n}", team.vehicles),
        ));
    }
    let all = team.vehicles_completed == n;
    if team.vehicles_completed > n || all != (row.outcome == "completed") {
        return Err((
            "vehicles_completed".into(),
            format!(
                "{} of {n} vehicles completed in a `{}` run",
                team.vehicles_completed,
                isotrack_scenario::load::clip(&row.outcome)
            ),
        ));
    }
    let unit = |v: f64| v.is_finite() && (0.0..=1.0).contains(&v);
    for (k, v) in [("tracking", team.parts.tracking), ("held", team.parts.held)] {
        if !unit(v) {
            return Err((format!("parts.{k}"), format!("{v:?} is not in [0, 1]")));
        }
    }
    if let Some(j) = row.score.parts.iter().position(|p| !unit(*p)) {
        return Err((
            String::new(),
            format!(
                "score.parts[{j}] = {:?} is not in [0, 1]",
                row.score.parts[j]
            ),
        ));
    }
    // The tracking part is the vehicles' mean score over 100: the weighted sum of their mean
    // parts (to rounding).
    let weighted: f64 = row
        .score
        .parts
        .iter()
        .zip(WEIGHTS)
        .map(|(p, w)| p * w)
        .sum();
    if (weighted - team.parts.tracking).abs() > 1e-9 {
        return Err((
            "parts.tracking".into(),
            format!(
                "{:?} is not the weighted sum of the score's parts, {weighted:?}",
                team.parts.tracking
            ),
        ));
    }
    if let Some(m) = &team.metrics {
        if m.count != n {
            return Err((
                "metrics.count".into(),
                format!("{} where the task's team has {n}", m.count),
            ));
        }
        check_team_record(m, TeamBounds::of(s).as_ref())
            .map_err(|why| ("metrics".to_string(), why))?;
    }
    let (total, parts) = team_total(
        team.parts.tracking,
        team.parts.held,
        all,
        team.metrics.as_ref(),
    );
    team.parts = parts;
    Ok((total, row.score.parts, team))
}

/// The [`RunResult`] a stored run's score is computed from (only what [`score`] reads).
fn result_of(r: &RunRow, t_end_s: f64) -> RunResult {
    RunResult {
        outcome: match r.outcome.as_str() {
            "completed" => Outcome::Completed,
            "diverged" => Outcome::Diverged,
            _ => Outcome::LeftField,
        },
        outcome_detail: None,
        t_end_s,
        steps: 0,
        samples: 0,
        samples_dropped: 0,
        end_position_m: [0.0; 2],
        metrics: RunMetrics {
            steady_state_max_abs_error: None,
            steady_state_rms_error: r.steady_state_rms_error,
            steady_state_mean_error: None,
            convergence_time_s: r.convergence_time_s,
            path_length_m: 0.0,
            control_effort: r.control_effort,
            chattering_radps2: None,
            sign_changes_per_s: None,
            steady_state_max_isoline_distance_m: None,
            steady_state_rms_isoline_distance_m: r.steady_state_rms_isoline_distance_m,
            time_in_band_fraction: r.time_in_band_fraction,
            track_losses: r.track_losses,
            reached_level: false,
            farthest_from_start_m: 0.0,
        },
    }
}
