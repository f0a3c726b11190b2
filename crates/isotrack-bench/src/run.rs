//! Running a suite: tuning the built-in laws on the tuning seeds, scoring every controller on
//! the scoring seeds, and the pictures of each task.

use crate::registry::{Clipped, Entrant, Registry};
use crate::score::{score, Score, ScoreContext};
use crate::suite::{seed_overrides, Suite, Task};
use crate::tune::tune;
use isotrack_core::{ScalarField, Vec2};
use isotrack_fields::isoline::IsolineSegments;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::{NoTrace, RunResult, TraceRow, TraceSink};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// What went wrong running a benchmark.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// A task's scenario does not load (the message names the file, line and key).
    #[error("task {task}: {message}")]
    Task {
        /// The task id.
        task: String,
        /// Why.
        message: String,
    },
    /// A controller name that is not registered.
    #[error("unknown controller {0:?} (built in: pi_isoline, sliding_mode, sliding_mode_smooth, suboptimal_sosm, pid, pid_crossing, gradient_reference)")]
    UnknownController(String),
    /// Reading or writing results.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// `--resume` on results of another suite or controller set.
    #[error("{0}")]
    Mismatch(String),
    /// Stopped by [`Options::cancel`] before it finished.
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

/// The field behind a task's picture: values on a grid over the paths (at t = 0) and the target
/// isoline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldPicture {
    /// `[x_min, y_min, x_max, y_max]`, m.
    pub bounds_m: [f64; 4],
    /// Samples per row and column.
    pub n: usize,
    /// Values, row 0 at `y_min`, `None` where the field has none.
    pub values: Vec<Option<f64>>,
    /// The isoline `s_d` as segments `[x0, y0, x1, y1]`, m.
    pub isoline: Vec<[f64; 4]>,
    /// The level.
    pub level: f64,
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
}

/// A benchmark's results.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchResult {
    /// Suite name.
    pub suite: String,
    /// Suite version.
    pub version: u32,
    /// Controllers, in order.
    pub controllers: Vec<String>,
    /// Per task.
    pub tasks: Vec<TaskResult>,
    /// Overall score per controller (mean over tasks), best first.
    pub overall: Vec<(String, f64)>,
}

/// How to run.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// The controllers (default: the suite's, then every registered custom one).
    pub controllers: Option<Vec<String>>,
    /// Rerun the tuning on the tuning seeds (else: the suite's recorded gains).
    pub tune: bool,
    /// Reuse task results found here (`DIR/tasks/ID/task.json`) when their digest matches.
    pub resume_from: Option<std::path::PathBuf>,
    /// Set to `true` (from another thread: a front end's Ctrl-C) to stop the benchmark before
    /// its next run; it then returns [`BenchError::Interrupted`]. A tuning under way finishes
    /// its law first.
    pub cancel: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl Options {
    fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed))
    }
}

/// The controllers a run scores.
pub fn controllers_of(
    suite: &Suite,
    reg: &Registry,
    o: &Options,
) -> Result<Vec<String>, BenchError> {
    let names: Vec<String> = match &o.controllers {
        Some(c) => c.clone(),
        None => suite
            .controllers
            .iter()
            .cloned()
            .chain(reg.custom_names().iter().map(|s| s.to_string()))
            .collect(),
    };
    for n in &names {
        if reg.get(n).is_none() {
            return Err(BenchError::UnknownController(n.clone()));
        }
    }
    Ok(names)
}

/// Runs a suite: every task, each controller on each scoring seed (tuned first if `o.tune`).
/// `progress(task_index, task_count, task_id)` is called as each task starts. Results do not
/// depend on the thread count: every run is a pure function of its task, controller, gains and
/// seed, and every mean is taken in a fixed order.
pub fn run_benchmark(
    suite: &Suite,
    reg: &Registry,
    o: &Options,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> Result<BenchResult, BenchError> {
    let controllers = controllers_of(suite, reg, o)?;
    let mut tasks = Vec::with_capacity(suite.tasks.len());
    for (i, task) in suite.tasks.iter().enumerate() {
        if o.cancelled() {
            return Err(BenchError::Interrupted);
        }
        progress(i, suite.tasks.len(), &task.id);
        tasks.push(run_task(suite, task, reg, &controllers, o)?);
    }
    let mut overall: Vec<(String, f64)> = controllers
        .iter()
        .map(|c| {
            let s: f64 = tasks
                .iter()
                .map(|t| t.scores.iter().find(|(n, _)| n == c).map_or(0.0, |x| x.1))
                .sum();
            (c.clone(), s / tasks.len() as f64)
        })
        .collect();
    // Best first; ties keep the controller order (stable sort).
    overall.sort_by(|a, b| b.1.total_cmp(&a.1));
    Ok(BenchResult {
        suite: suite.name.clone(),
        version: suite.version,
        controllers,
        tasks,
        overall,
    })
}

/// The task's base scenario: its file with the task's overrides, recording no trace (the
/// scores need none).
pub fn task_base(suite: &Suite, task: &Task) -> Result<Scenario, BenchError> {
    let mut sets = task.set.clone();
    sets.push("output.record_rate_hz=0.0".into());
    load_scenario(Some(&suite.scenario_path(task)), &sets).map_err(|e| BenchError::Task {
        task: task.id.clone(),
        message: e.to_string(),
    })
}

fn run_task(
    suite: &Suite,
    task: &Task,
    reg: &Registry,
    controllers: &[String],
    o: &Options,
) -> Result<TaskResult, BenchError> {
    let base = task_base(suite, task)?;
    let mut gains: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    for c in controllers {
        if let Some(Entrant::Builtin(kind)) = reg.get(c) {
            if o.cancelled() {
                return Err(BenchError::Interrupted);
            }
            let g = if o.tune {
                tune(&base, task, *kind, &suite.tuning_seeds)
            } else {
                task.tuned.get(c).cloned().unwrap_or_default()
            };
            gains.insert(c.clone(), g);
        }
    }
    let digest = task_digest(suite, task, controllers, &gains);
    if let Some(dir) = &o.resume_from {
        if let Some(prev) = read_task(dir, &task.id) {
            if prev.digest == digest {
                return Ok(prev);
            }
        }
    }
    let jobs: Vec<(&String, u64)> = controllers
        .iter()
        .flat_map(|c| suite.scoring_seeds.iter().map(move |s| (c, *s)))
        .collect();
    let runs: Vec<RunRow> = jobs
        .par_iter()
        .map(|(c, seed)| {
            let entrant = reg.get(c).expect("checked by controllers_of");
            (!o.cancelled()).then(|| scored_run(&base, task, c, entrant, gains.get(*c), *seed))
        })
        .collect::<Option<_>>()
        .ok_or(BenchError::Interrupted)?;
    let scores = controllers
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
        .collect();
    let seed0 = suite.scoring_seeds[0];
    let trajectories: Vec<Trajectory> = controllers
        .par_iter()
        .map(|c| {
            let entrant = reg.get(c).expect("checked by controllers_of");
            (!o.cancelled()).then(|| trajectory(&base, task, c, entrant, gains.get(c), seed0))
        })
        .collect::<Option<_>>()
        .ok_or(BenchError::Interrupted)?;
    let picture = field_picture(&base, &trajectories);
    Ok(TaskResult {
        id: task.id.clone(),
        title: task.title.clone(),
        scores,
        gains,
        runs,
        trajectories,
        picture,
        digest,
    })
}

/// The overrides of one run: the built-in law's gains, then the seed's draws (the law itself is
/// set by [`Scenario::with_controller_kind`]).
pub fn run_overrides(
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
) -> Vec<String> {
    let mut o = vec![];
    if let Entrant::Builtin(_) = entrant {
        for (k, v) in gains.into_iter().flatten() {
            o.push(format!("controller.{k}={v:?}"));
        }
    }
    o.extend(seed_overrides(task, seed));
    o
}

/// Runs one (task, controller, seed) into `sink`: the scenario, and its result (`Err` with the
/// message when the overrides make an invalid scenario).
pub fn run_one<S: TraceSink + ?Sized>(
    base: &Scenario,
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    sink: &mut S,
) -> Result<(Scenario, RunResult), String> {
    let flown = match entrant {
        Entrant::Builtin(kind) => base
            .with_controller_kind(*kind)
            .map_err(|e| e.to_string())?,
        Entrant::Custom(_) => base.clone(),
    };
    let s = flown
        .derive(
            &run_overrides(task, entrant, gains, seed),
            &format!("task {}", task.id),
        )
        .map_err(|e| e.to_string())?;
    let r = match entrant {
        Entrant::Builtin(_) => s.run(sink),
        Entrant::Custom(f) => {
            let mut c = Clipped {
                inner: f.make(&s),
                max_turn_rate_radps: s.max_turn_rate_radps(),
            };
            s.run_with(&mut c, sink)
        }
    };
    Ok((s, r))
}

/// The score context of a run of `s`.
pub fn context(s: &Scenario, task: &Task) -> ScoreContext {
    let plan = s.plan();
    ScoreContext {
        steady_start_s: plan.steady_state_start_step as f64 * plan.dt_s,
        length_m: task.length_m,
        speed_mps: s.start_speed_mps(s.start()),
    }
}

fn scored_run(
    base: &Scenario,
    task: &Task,
    controller: &str,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
) -> RunRow {
    match run_one(base, task, entrant, gains, seed, &mut NoTrace) {
        Ok((s, r)) => {
            let m = &r.metrics;
            RunRow {
                controller: controller.to_string(),
                seed,
                outcome: r.outcome.as_str().to_string(),
                convergence_time_s: m.convergence_time_s,
                time_in_band_fraction: m.time_in_band_fraction,
                steady_state_rms_isoline_distance_m: m.steady_state_rms_isoline_distance_m,
                track_losses: m.track_losses,
                control_effort: m.control_effort,
                steady_state_rms_error: m.steady_state_rms_error,
                score: score(&r, &context(&s, task)),
            }
        }
        Err(_) => RunRow {
            controller: controller.to_string(),
            seed,
            outcome: "invalid_scenario".into(),
            convergence_time_s: None,
            time_in_band_fraction: None,
            steady_state_rms_isoline_distance_m: None,
            track_losses: 0,
            control_effort: 0.0,
            steady_state_rms_error: None,
            score: Score {
                total: 0.0,
                parts: [0.0; 5],
            },
        },
    }
}

/// At most this many points per path in a picture.
const PICTURE_POINTS: usize = 600;

/// Keeps every n-th row.
struct Thinned {
    every: u64,
    k: u64,
    points: Vec<[f64; 2]>,
}

impl TraceSink for Thinned {
    fn record(&mut self, row: &TraceRow) {
        if self.k.is_multiple_of(self.every) && row.x_m.is_finite() && row.y_m.is_finite() {
            self.points.push([row.x_m, row.y_m]);
        }
        self.k += 1;
    }
}

fn trajectory(
    base: &Scenario,
    task: &Task,
    controller: &str,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
) -> Trajectory {
    // Record at 10 Hz, keep at most PICTURE_POINTS of the rows.
    let duration = base.file().sim.duration_s.unwrap_or(600.0);
    let rows = (duration * 10.0).max(1.0) as u64;
    let mut sink = Thinned {
        every: rows.div_ceil(PICTURE_POINTS as u64).max(1),
        k: 0,
        points: vec![],
    };
    let with_rate = base.derive(&["output.record_rate_hz=10.0".into()], "picture");
    let outcome = match with_rate {
        Ok(b) => match run_one(&b, task, entrant, gains, seed, &mut sink) {
            Ok((_, r)) => r.outcome.as_str().to_string(),
            Err(_) => "invalid_scenario".to_string(),
        },
        Err(_) => "invalid_scenario".to_string(),
    };
    Trajectory {
        controller: controller.to_string(),
        points: sink.points,
        outcome,
    }
}

/// Field samples per side of a picture.
const PICTURE_GRID: usize = 64;

fn field_picture(base: &Scenario, trajectories: &[Trajectory]) -> FieldPicture {
    let start = base.start();
    let points = std::iter::once([start.x_m, start.y_m])
        .chain(trajectories.iter().flat_map(|t| t.points.iter().copied()));
    // The start is finite (a resolved scenario's), so there is always a square to draw.
    FieldPicture::around(base, points, PICTURE_GRID).expect("a finite start point")
}

impl FieldPicture {
    /// The field of `scenario` at t = 0 on an `n x n` grid over a square round `points` (their
    /// bounding box, widened by 15 %, at least 2 m across), with its isoline `s_d`; `None` when
    /// no point is finite.
    pub fn around(
        scenario: &Scenario,
        points: impl IntoIterator<Item = [f64; 2]>,
        n: usize,
    ) -> Option<FieldPicture> {
        let (mut x0, mut y0, mut x1, mut y1) =
            (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
        for [x, y] in points
            .into_iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
        {
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
        if !(x0.is_finite() && y0.is_finite()) {
            return None;
        }
        // A square with a margin, so the isoline around the paths shows.
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let half = (0.5 * (x1 - x0).max(y1 - y0)).max(1.0) * 1.15;
        let (x0, y0) = (cx - half, cy - half);
        let h = 2.0 * half / (n - 1) as f64;
        let field = scenario.field();
        let at = |p: Vec2| field.value(0.0, p).filter(|v| v.is_finite());
        let mut values = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                values.push(at(Vec2::new(x0 + i as f64 * h, y0 + j as f64 * h)));
            }
        }
        let level = scenario.level();
        let iso = IsolineSegments::from_samples(Vec2::new(x0, y0), h, n, n, level, at);
        Some(FieldPicture {
            bounds_m: [x0, y0, x0 + 2.0 * half, y0 + 2.0 * half],
            n,
            values,
            isoline: iso
                .segments()
                .iter()
                .map(|(a, b)| [a.x, a.y, b.x, b.y])
                .collect(),
            level,
        })
    }
}

fn task_digest(
    suite: &Suite,
    task: &Task,
    controllers: &[String],
    gains: &BTreeMap<String, BTreeMap<String, f64>>,
) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(env!("CARGO_PKG_VERSION"));
    h.update(toml::to_string(task).unwrap_or_default());
    h.update(format!("{:?}{:?}", suite.scoring_seeds, controllers));
    h.update(serde_json::to_string(gains).unwrap_or_default());
    if let Ok(t) = isotrack_fields::io::read_limited(
        &suite.scenario_path(task),
        isotrack_scenario::MAX_SCENARIO_FILE_BYTES,
    ) {
        h.update(t);
    }
    h.finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<String>()
}

/// The file a task's results are kept in under a benchmark's output directory.
pub fn task_file(dir: &Path, id: &str) -> std::path::PathBuf {
    dir.join("tasks").join(id).join("task.json")
}

fn read_task(dir: &Path, id: &str) -> Option<TaskResult> {
    // A task file is a few KB; anything that is not a regular file is not one of ours.
    let text = isotrack_fields::io::read_text_limited(&task_file(dir, id), 64 << 20).ok()?;
    serde_json::from_str(&text).ok()
}
