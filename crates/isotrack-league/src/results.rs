//! What a benchmark produces: its results (per task, per run) and its errors, and where a task's
//! results are kept.

use crate::score::{Score, Scoring, TeamParts};
use crate::suite::SuiteError;
use isotrack_plot::FieldPicture;
use isotrack_runs::results::{RunRecord, INVALID_SCENARIO};
use isotrack_runs::summary::TeamRecord;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// What went wrong running a benchmark.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A task's scenario file, or a file it names (`field.path`), cannot be read: missing, a
    /// FIFO, a directory, a device (the message names the suite file and line that names it).
    #[error("task {task}: {message}")]
    Task {
        /// The task id.
        task: String,
        /// Why.
        message: String,
    },
    /// The suite cannot run as written: a task's scenario or overrides are invalid, or a run it
    /// defines (a law with its recorded gains, a seed's `vary` draws) makes an invalid
    /// scenario. Found before any run starts; located at the suite file's line.
    #[error("{0}")]
    Suite(SuiteError),
    /// A controller name that is not registered.
    #[error("unknown controller `{}` (built in: pi_isoline, sliding_mode, sliding_mode_smooth, suboptimal_sosm, pid, pid_crossing, gradient_reference)", isotrack_core::numtext::Clipped(.0))]
    UnknownController(String),
    /// A controller named twice in [`Options::controllers`](crate::run::Options::controllers).
    #[error("controller `{}` is named twice", isotrack_core::numtext::Clipped(.0))]
    DuplicateController(String),
    /// Reading or writing results.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// A controller registered from Rust or Python on a team task: it flies one vehicle, and
    /// a team's vehicles each run the scenario's built-in tracking law (a team of your own
    /// controllers is not wired yet).
    #[error("task {task}: {controller} is a registered controller, and a team task's vehicles fly the built-in laws only (a team of registered controllers is not wired yet): leave it out of this suite (--controllers)")]
    TeamController {
        /// The task id.
        task: String,
        /// The controller.
        controller: String,
    },
    /// `--resume` found a task's stored results (`tasks/ID/task.json`, its digest matching)
    /// that the suite contradicts: runs other than the suite's seeds x controllers, a value no
    /// run can have. Edited or damaged: never reused, never silently rerun (exit 65).
    #[error("{path}: {message}")]
    Damaged {
        /// The file.
        path: String,
        /// The field and why.
        message: String,
    },
    /// `--resume` on results of another suite or controller set.
    #[error("{0}")]
    Mismatch(String),
    /// Stopped by [`Options::cancel`](crate::run::Options::cancel) before it finished.
    #[error("interrupted")]
    Interrupted,
}

/// One scored run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRow {
    /// Controller name.
    pub controller: String,
    /// Scoring seed.
    pub seed: u64,
    /// `completed`, `left_field`, `diverged`, or `invalid_scenario`.
    pub outcome: String,
    /// Convergence time, s.
    pub convergence_time_s: Option<f64>,
    /// Share of the steady window within the tolerance.
    pub time_in_band_fraction: Option<f64>,
    /// Steady RMS distance to the true isoline, m.
    pub steady_state_rms_isoline_distance_m: Option<f64>,
    /// Track losses.
    pub track_losses: u64,
    /// `integral(omega^2 dt)`, rad^2/s.
    pub control_effort: f64,
    /// Steady RMS error (field units).
    pub steady_state_rms_error: Option<f64>,
    /// The score and its parts.
    pub score: Score,
    /// A team run's team columns (a task whose scenario has `[team]`; absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub team: Option<TeamRow>,
}

/// What a team run's row adds: how many of its vehicles completed, the team parts of its
/// score and its team metrics (`summary.json`'s `team.metrics`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TeamRow {
    /// Vehicles in the team.
    pub vehicles: usize,
    /// Vehicles whose run completed.
    pub vehicles_completed: usize,
    /// The team parts of the score.
    pub parts: TeamParts,
    /// The team metrics (`None`: none measured).
    pub metrics: Option<TeamRecord>,
}

impl RunRow {
    /// The row of `controller`'s run on `seed`: its [`RunRecord`] (the record every results
    /// file is built from, `isotrack-runs`), or `None` for a run whose scenario is invalid
    /// (outcome `invalid_scenario`, no metrics, effort 0), and its score.
    pub fn of(controller: &str, seed: u64, record: Option<&RunRecord>, score: Score) -> RunRow {
        match record {
            Some(r) => RunRow {
                controller: controller.to_string(),
                seed,
                outcome: r.outcome.clone(),
                convergence_time_s: r.metrics.convergence_time_s,
                time_in_band_fraction: r.metrics.time_in_band_fraction,
                steady_state_rms_isoline_distance_m: r.metrics.steady_state_rms_isoline_distance_m,
                track_losses: r.metrics.track_losses,
                // Not finite: NaN (`null` in task.json, as before; an empty cell in results.csv).
                control_effort: r.metrics.control_effort.unwrap_or(f64::NAN),
                steady_state_rms_error: r.metrics.steady_state_rms_error,
                score,
                team: None,
            },
            None => RunRow {
                controller: controller.to_string(),
                seed,
                outcome: INVALID_SCENARIO.into(),
                convergence_time_s: None,
                time_in_band_fraction: None,
                steady_state_rms_isoline_distance_m: None,
                track_losses: 0,
                control_effort: 0.0,
                steady_state_rms_error: None,
                score,
                team: None,
            },
        }
    }
}

/// One controller's path for a task's picture (the first scoring seed), m.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    /// Controller name.
    pub controller: String,
    /// `[x, y]` points, m.
    pub points: Vec<[f64; 2]>,
    /// How the run ended.
    pub outcome: String,
}

/// A task's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskResult {
    /// Task id.
    pub id: String,
    /// Task title.
    pub title: String,
    /// Mean score per controller, in the run's controller order.
    pub scores: Vec<(String, f64)>,
    /// The gains each built-in law ran with (`controller.KEY`).
    pub gains: BTreeMap<String, BTreeMap<String, f64>>,
    /// Every scored run, controller by controller, seed by seed.
    pub runs: Vec<RunRow>,
    /// Paths for the picture.
    pub trajectories: Vec<Trajectory>,
    /// The field for the picture.
    pub picture: FieldPicture,
    /// The digest of what produced it (suite, controllers, gains, version): `--resume` reuses
    /// a task's results only when it matches.
    pub digest: String,
    /// Whether the task's scenario has `[team]` (its runs are teams, scored by
    /// [`crate::score::team_score`], and its `results.csv` has the team columns).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub team: bool,
}

/// A task's mean score per controller ([`TaskResult::scores`]), in `controllers`' order: the
/// mean of the totals of its `runs` (0 for a controller without a run).
pub(crate) fn controller_means(controllers: &[String], runs: &[RunRow]) -> Vec<(String, f64)> {
    controllers
        .iter()
        .map(|c| {
            let mine: Vec<f64> = runs
                .iter()
                .filter(|r| &r.controller == c)
                .map(|r| r.score.total)
                .collect();
            (
                c.clone(),
                mine.iter().sum::<f64>() / mine.len().max(1) as f64,
            )
        })
        .collect()
}

/// A benchmark's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchResult {
    /// Suite name.
    pub suite: String,
    /// Suite version.
    pub version: u32,
    /// The score formula.
    #[serde(default)]
    pub scoring: Scoring,
    /// Controllers, in order.
    pub controllers: Vec<String>,
    /// Per task.
    pub tasks: Vec<TaskResult>,
    /// Overall score per controller (mean over tasks), best first.
    pub overall: Vec<(String, f64)>,
}

/// The file a task's results are kept in under a benchmark's output directory.
pub fn task_file(dir: &Path, id: &str) -> std::path::PathBuf {
    dir.join("tasks").join(id).join("task.json")
}
