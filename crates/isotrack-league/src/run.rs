//! Running a suite: tuning the built-in laws on the tuning seeds, scoring every controller on
//! the scoring seeds, and the pictures of each task.

use crate::one_run::run_assignments;
pub use crate::one_run::{
    context, prepare, run_one, run_overrides, run_scored, run_scored_into, Scored,
};
use crate::registry::{Entrant, Registry};
pub use crate::results::{task_file, BenchError, BenchResult, RunRow, TaskResult, Trajectory};
use crate::score::{Score, Scoring};
use crate::suite::{task_path, Seg, Suite, SuiteError, Task};
use crate::tune::tune;
use isotrack_plot::FieldPicture;
use isotrack_scenario::{load_scenario, ErrorLocation, Scenario, ScenarioError};
use isotrack_sim::{TraceRow, TraceSink};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

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
    /// Write each task's results here (`DIR/tasks/ID/`) as soon as it finishes, so an
    /// interrupted benchmark (Ctrl-C) keeps its finished tasks for `resume_from`.
    pub save_to: Option<std::path::PathBuf>,
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
    for (i, n) in names.iter().enumerate() {
        if reg.get(n).is_none() {
            return Err(BenchError::UnknownController(n.clone()));
        }
        if names[..i].contains(n) {
            return Err(BenchError::DuplicateController(n.clone()));
        }
    }
    Ok(names)
}

/// Runs a suite: every task, each controller on each scoring seed (tuned first if `o.tune`).
/// `progress(task_index, task_count, task_id)` is called as each task starts (tasks run in
/// parallel, so not necessarily in the suite's order). Results do not depend on the thread
/// count: every run is a pure function of its task, controller, gains and seed, and every mean
/// is taken in a fixed order.
///
/// Before any run starts, every task's scenario is loaded and every run it defines is built
/// ([`check_runs`]): a suite with an invalid run fails as a whole with
/// [`BenchError::Suite`], never as runs scored 0.
pub fn run_benchmark(
    suite: &Suite,
    reg: &Registry,
    o: &Options,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> Result<BenchResult, BenchError> {
    let controllers = controllers_of(suite, reg, o)?;
    let bases = suite
        .tasks
        .iter()
        .map(|t| task_base(suite, t))
        .collect::<Result<Vec<_>, _>>()?;
    check_runs(suite, reg, &controllers, &bases, o.tune)?;
    // The tasks run at once (and each task's runs): a task's result is a pure function of the
    // task, so the results are taken in the suite's order, and of several errors the first in
    // that order is returned.
    let n = suite.tasks.len();
    let tasks = suite
        .tasks
        .par_iter()
        .zip(bases.into_par_iter())
        .enumerate()
        .map(|(i, (task, base))| {
            if o.cancelled() {
                return Err(BenchError::Interrupted);
            }
            progress(i, n, &task.id);
            let t = run_task(suite, task, base, reg, &controllers, o)?;
            if let Some(dir) = &o.save_to {
                crate::leaderboard::write_task(&t, dir)?;
            }
            Ok(t)
        })
        .collect::<Vec<Result<TaskResult, BenchError>>>()
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
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
        scoring: suite.scoring,
        controllers,
        tasks,
        overall,
    })
}

/// The task's base scenario: its file with the task's overrides, recording no trace (the
/// scores need none). Errors name the suite file's line of the task's `scenario` (or of the
/// `set` entry at fault) and the scenario file's own line.
pub fn task_base(suite: &Suite, task: &Task) -> Result<Scenario, BenchError> {
    let mut sets = task.set.clone();
    sets.push("output.record_rate_hz=0.0".into());
    let ti = suite
        .tasks
        .iter()
        .position(|t| t.id == task.id)
        .unwrap_or(0);
    load_scenario(Some(&suite.scenario_path(task)), &sets).map_err(|e| {
        let scenario_line = suite.error_at(&task_path(ti, &["scenario"]), String::new());
        let unreadable = e.is_unreadable_input();
        match &e {
            ScenarioError::Invalid(issues) if !unreadable => {
                // An issue at a `set` entry is located there, anything else at `scenario`.
                let set_at = issues.iter().find_map(|i| match &i.location {
                    ErrorLocation::Override { arg } => task.set.iter().position(|s| s == arg),
                    _ => None,
                });
                let path = match set_at {
                    Some(j) => {
                        let mut p = task_path(ti, &["set"]);
                        p.push(Seg::Index(j));
                        p
                    }
                    None => task_path(ti, &["scenario"]),
                };
                BenchError::Suite(suite.error_at(&path, format!("task {}: {e}", task.id)))
            }
            // The scenario file, or a file it names, cannot be read: exit 66 in the CLI.
            _ => BenchError::Task {
                task: task.id.clone(),
                message: format!("{scenario_line}{e}"),
            },
        }
    })
}

/// Builds every run the suite defines for `controllers` before any runs (the recorded gains of
/// each built-in law, each scoring seed's draws, and each tuning seed's when `tuning`): the
/// first that makes an invalid scenario is a [`BenchError::Suite`] located at the suite key
/// it comes from (the `[task.tuned.LAW]` gain, the `vary` key, the task's `scenario`).
/// `bases` are the tasks' [`task_base`]s, in order.
pub fn check_runs(
    suite: &Suite,
    reg: &Registry,
    controllers: &[String],
    bases: &[Scenario],
    tuning: bool,
) -> Result<(), BenchError> {
    let seeds: Vec<u64> = suite
        .scoring_seeds
        .iter()
        .chain(suite.tuning_seeds.iter().filter(|_| tuning))
        .copied()
        .collect();
    for (ti, (task, base)) in suite.tasks.iter().zip(bases).enumerate() {
        check_team_task(suite, ti, base, reg, controllers)?;
        for c in controllers {
            let Some(entrant) = reg.get(c) else {
                return Err(BenchError::UnknownController(c.clone()));
            };
            let gains = task.tuned.get(c);
            for &seed in &seeds {
                if let Err(e) = prepare(base, task, entrant, gains, seed) {
                    return Err(BenchError::Suite(locate_run_error(
                        suite, ti, c, entrant, gains, seed, &e,
                    )));
                }
            }
        }
    }
    Ok(())
}

/// A team task (its scenario has `[team]`) runs only built-in laws (a registered controller:
/// [`BenchError::TeamController`]) and needs a closed isoline to measure its spacing and revisit
/// times on (none, e.g. an isoline that leaves the grid: [`BenchError::Suite`] at the task's
/// `scenario`, since the team score would be the tracking half only).
fn check_team_task(
    suite: &Suite,
    ti: usize,
    base: &Scenario,
    reg: &Registry,
    controllers: &[String],
) -> Result<(), BenchError> {
    let task = &suite.tasks[ti];
    if base.spec().team.is_none() {
        return Ok(());
    }
    if let Some(c) = controllers
        .iter()
        .find(|c| matches!(reg.get(c), Some(Entrant::Custom(_))))
    {
        return Err(BenchError::TeamController {
            task: task.id.clone(),
            controller: c.clone(),
        });
    }
    let model = base.team_isoline();
    if model.as_team_isoline().is_none() || model.is_open() {
        let why = if model.is_open() {
            "the isoline leaves the field: an open isoline's team metrics measure the stretch the team covers, not a loop's"
        } else {
            base.team_metrics_note()
        };
        return Err(BenchError::Suite(suite.error_at(
            &task_path(ti, &["scenario"]),
            format!(
                "task {}: a team task needs a closed isoline to measure its spacing and revisit times on, and this one has none ({why})",
                task.id
            ),
        )));
    }
    Ok(())
}

/// Where in the suite file a run's problem comes from, and what it is.
fn locate_run_error(
    suite: &Suite,
    ti: usize,
    controller: &str,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    e: &ScenarioError,
) -> SuiteError {
    let task = &suite.tasks[ti];
    let assignments = run_assignments(task, entrant, gains, seed);
    let n_gains = match entrant {
        Entrant::Builtin(_) => gains.map_or(0, |g| g.len()),
        Entrant::Custom(_) => 0,
    };
    let issue = e.issues().first();
    let at = issue.and_then(|i| match &i.location {
        ErrorLocation::Assigned { label } => assignments.iter().position(|a| &a.label == label),
        _ => None,
    });
    let (path, what) = match at {
        Some(j) if j < n_gains => {
            let (k, v) = gains
                .and_then(|g| g.iter().nth(j))
                .map_or((String::new(), f64::NAN), |(k, v)| (k.clone(), *v));
            (
                task_path(ti, &["tuned", controller, &k]),
                format!("tuned {controller}.{k} = {v:?}"),
            )
        }
        Some(j) if j < n_gains + task.vary.len() => {
            let k = task
                .vary
                .keys()
                .nth(j - n_gains)
                .cloned()
                .unwrap_or_default();
            (
                task_path(ti, &["vary", &k]),
                format!("{controller}, seed {seed}: vary {}", assignments[j].arg),
            )
        }
        Some(_) => (
            vec![Seg::Key("scoring_seeds".into())],
            format!("{controller}, seed {seed}"),
        ),
        None => (
            task_path(ti, &["scenario"]),
            format!("{controller}, seed {seed}"),
        ),
    };
    let why = match issue {
        Some(i) => {
            let more = e.issues().len() - 1;
            let key = i
                .key
                .as_deref()
                .map(|k| format!("`{k}`: "))
                .unwrap_or_default();
            let more = if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            };
            format!("{key}{}{more}", i.message)
        }
        None => e.to_string(),
    };
    suite.error_at(&path, format!("task {}, {what}: {why}", task.id))
}

/// Task `task` of `suite` on `base` for `controllers`: the built-in laws' gains, then either
/// the stored results reused (`--resume`, digest matching) or every scoring run, with each
/// controller's mean score and the picture.
fn run_task(
    suite: &Suite,
    task: &Task,
    base: Scenario,
    reg: &Registry,
    controllers: &[String],
    o: &Options,
) -> Result<TaskResult, BenchError> {
    let gains = task_gains(suite, task, &base, reg, controllers, o)?;
    let digest = task_digest(suite, task, controllers, &gains, &base);
    if let Some(dir) = &o.resume_from {
        if let Some(prev) = read_task(dir, &task.id) {
            if prev.digest == digest {
                // Reused only once checked: its runs are the suite's and possible, its scores
                // and picture recomputed (`resume`).
                let expected = crate::resume::Expected {
                    task,
                    base: &base,
                    reg,
                    controllers,
                    seeds: &suite.scoring_seeds,
                    gains: &gains,
                    scoring: suite.scoring,
                    max_points: picture_points(&base),
                };
                return crate::resume::reuse(prev, &task_file(dir, &task.id), &expected, |t| {
                    field_picture(&base, t)
                });
            }
        }
    }
    let jobs = scoring_jobs(controllers, &suite.scoring_seeds);
    let seeded = seeded_scenarios(&base, &suite.scoring_seeds);
    let done = run_jobs(
        &Jobs {
            jobs: &jobs,
            seeded: &seeded,
            base: &base,
            task,
            reg,
            gains: &gains,
            scoring: suite.scoring,
        },
        o,
        true,
    )?;
    let (runs, paths): (Vec<RunRow>, Vec<Option<Trajectory>>) = done.into_iter().unzip();
    let scores = crate::results::controller_means(controllers, &runs);
    // Each controller's path: drawn by its run of the first scoring seed, in controller order.
    let trajectories: Vec<Trajectory> = paths.into_iter().flatten().collect();
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
        team: base.spec().team.is_some(),
    })
}

/// The gains each built-in law among `controllers` runs task `task` with: tuned on the suite's
/// tuning seeds under `--tune` ([`tune`]), else the suite's recorded ones (none recorded: the
/// law's resolved defaults). Stops at a cancel between laws.
fn task_gains(
    suite: &Suite,
    task: &Task,
    base: &Scenario,
    reg: &Registry,
    controllers: &[String],
    o: &Options,
) -> Result<BTreeMap<String, BTreeMap<String, f64>>, BenchError> {
    let mut gains: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    for c in controllers {
        if let Some(Entrant::Builtin(kind)) = reg.get(c) {
            if o.cancelled() {
                return Err(BenchError::Interrupted);
            }
            let g = if o.tune {
                tune(base, task, *kind, &suite.tuning_seeds, suite.scoring)
            } else {
                task.tuned.get(c).cloned().unwrap_or_default()
            };
            gains.insert(c.clone(), g);
        }
    }
    Ok(gains)
}

/// A task's scoring runs, controller by controller, seed by seed: (controller, seed, whether
/// this run also draws the controller's path in the picture: the first scoring seed's).
fn scoring_jobs<'c>(controllers: &'c [String], seeds: &[u64]) -> Vec<(&'c String, u64, bool)> {
    controllers
        .iter()
        .flat_map(|c| seeds.iter().enumerate().map(move |(k, s)| (c, *s, k == 0)))
        .collect()
}

/// The scenario with each seed's `sim.seed`, shared by the controllers' runs of that seed: a
/// field that follows the seed (a puff plume's meander) and its true isoline are then built
/// once per seed, not once per run. A seed whose scenario does not derive is left out.
fn seeded_scenarios(base: &Scenario, seeds: &[u64]) -> BTreeMap<u64, Scenario> {
    seeds
        .iter()
        .filter_map(|&seed| {
            let b = base.derive(&[format!("sim.seed={seed}")], "seed").ok()?;
            Some((seed, b))
        })
        .collect()
}

/// A task's scored runs: (controller, seed, whether the run draws the controller's path),
/// with what they are run from.
struct Jobs<'a> {
    jobs: &'a [(&'a String, u64, bool)],
    /// The task's base scenario with each seed's `sim.seed`.
    seeded: &'a BTreeMap<u64, Scenario>,
    base: &'a Scenario,
    task: &'a Task,
    reg: &'a Registry,
    gains: &'a BTreeMap<String, BTreeMap<String, f64>>,
    scoring: Scoring,
}

/// A scored run's row, and its path when it draws one.
type Done = (RunRow, Option<Trajectory>);

/// The rows (and the paths) of `j`'s runs, in their order. With `lanes` (issue 34), the runs
/// that draw no path, of one vehicle, by a built-in law, are stepped [`isotrack_sim::LANES`]
/// at a time in SIMD lanes ([`crate::one_run::run_scored_lanes`]; the runs of a seed
/// together, since a field that follows the seed differs between seeds), every other run
/// alone ([`scored_job`]); each row is the same either way, on any thread count.
fn run_jobs(j: &Jobs<'_>, o: &Options, lanes: bool) -> Result<Vec<Done>, BenchError> {
    let laned = |&(c, _, picture): &(&String, u64, bool)| {
        lanes
            && !picture
            && j.base.spec().team.is_none()
            && matches!(j.reg.get(c), Some(Entrant::Builtin(_)))
    };
    // The units of work: up to LANES laned runs (seed by seed, the runs' order within a
    // seed), then each other run alone.
    let mut together: Vec<usize> = (0..j.jobs.len()).filter(|&i| laned(&j.jobs[i])).collect();
    together.sort_by_key(|&i| j.jobs[i].1);
    let units: Vec<(bool, Vec<usize>)> = together
        .chunks(isotrack_sim::LANES)
        .map(|c| (true, c.to_vec()))
        .chain(
            (0..j.jobs.len())
                .filter(|&i| !laned(&j.jobs[i]))
                .map(|i| (false, vec![i])),
        )
        .collect();
    let base_of = |seed: u64| j.seeded.get(&seed).unwrap_or(j.base);
    let entrant_of = |c: &str| j.reg.get(c).expect("checked by controllers_of");
    let done: Vec<Vec<(usize, Done)>> = units
        .par_iter()
        .map(|(in_lanes, unit)| {
            if o.cancelled() {
                return None;
            }
            if *in_lanes {
                let runs: Vec<crate::one_run::LaneJob<'_>> = unit
                    .iter()
                    .map(|&i| {
                        let (c, seed, _) = j.jobs[i];
                        crate::one_run::LaneJob {
                            base: base_of(seed),
                            entrant: entrant_of(c),
                            gains: j.gains.get(c),
                            seed,
                        }
                    })
                    .collect();
                let scored = crate::one_run::run_scored_lanes(&runs, j.task, j.scoring);
                return Some(
                    unit.iter()
                        .zip(scored)
                        .map(|(&i, r)| {
                            let (c, seed, _) = j.jobs[i];
                            (i, (scored_row(c, seed, r), None))
                        })
                        .collect(),
                );
            }
            Some(
                unit.iter()
                    .map(|&i| {
                        let (c, seed, picture) = j.jobs[i];
                        let job = scored_job(
                            base_of(seed),
                            j.task,
                            c,
                            entrant_of(c),
                            j.gains.get(c),
                            seed,
                            j.scoring,
                            picture,
                        );
                        (i, job)
                    })
                    .collect(),
            )
        })
        .collect::<Option<_>>()
        .ok_or(BenchError::Interrupted)?;
    let mut done: Vec<(usize, Done)> = done.into_iter().flatten().collect();
    done.sort_by_key(|(i, _)| *i);
    Ok(done.into_iter().map(|(_, d)| d).collect())
}

/// The scored run of (controller, seed) and, with `picture`, the controller's path for the
/// task's picture ([`trajectory`]): one vehicle's path recorded by the scored run itself (the
/// trace does not change the run), a team's flown again with vehicle 0 recording.
#[allow(clippy::too_many_arguments)]
fn scored_job(
    base: &Scenario,
    task: &Task,
    controller: &str,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    scoring: Scoring,
    picture: bool,
) -> (RunRow, Option<Trajectory>) {
    if picture && base.spec().team.is_none() {
        if let Ok(b) = base.derive(&["output.record_rate_hz=10.0".into()], "picture") {
            let mut sink = Thinned::of(&b);
            if let Ok(r) = run_scored_into(&b, task, entrant, gains, seed, scoring, &mut sink) {
                let path = Trajectory {
                    controller: controller.to_string(),
                    points: sink.points,
                    outcome: r.outcome.clone(),
                };
                return (scored_row(controller, seed, Ok(r)), Some(path));
            }
        }
    }
    let row = scored_run(base, task, controller, entrant, gains, seed, scoring);
    let path = picture.then(|| trajectory(base, task, controller, entrant, gains, seed));
    (row, path)
}

fn scored_run(
    base: &Scenario,
    task: &Task,
    controller: &str,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    scoring: Scoring,
) -> RunRow {
    scored_row(
        controller,
        seed,
        run_scored(base, task, entrant, gains, seed, scoring),
    )
}

/// The results row of a scored run (scored 0 when its scenario was invalid or refused).
fn scored_row(controller: &str, seed: u64, run: Result<Scored, String>) -> RunRow {
    match run {
        Ok(r) => {
            let mut row = RunRow::of(controller, seed, Some(&r.record), r.score);
            row.outcome = r.outcome;
            row.team = r.team;
            row
        }
        Err(_) => RunRow::of(
            controller,
            seed,
            None,
            Score {
                total: 0.0,
                parts: [0.0; 5],
            },
        ),
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

impl Thinned {
    /// For a run of `base` recorded at 10 Hz: keeps at most [`PICTURE_POINTS`] of the rows.
    fn of(base: &Scenario) -> Self {
        let duration = base.spec().sim.duration_s;
        let rows = (duration * 10.0).max(1.0) as u64;
        Self {
            every: rows.div_ceil(PICTURE_POINTS as u64).max(1),
            k: 0,
            points: vec![],
        }
    }
}

impl TraceSink for Thinned {
    fn record(&mut self, row: &TraceRow) {
        if self.k.is_multiple_of(self.every) && row.x_m.is_finite() && row.y_m.is_finite() {
            self.points.push([row.x_m, row.y_m]);
        }
        self.k += 1;
    }
}

/// The most points [`trajectory`] keeps of a run of `base`: every `ceil(rows / PICTURE_POINTS)`-th
/// of its `rows` 10 Hz rows (the rows `0, e, 2e, ...` below `rows + 1`).
fn picture_points(base: &Scenario) -> usize {
    let rows = (base.spec().sim.duration_s * 10.0).max(1.0) as u64;
    let every = rows.div_ceil(PICTURE_POINTS as u64).max(1);
    // A run records at most `rows + 1` rows (its start and each step's), one kept every `every`.
    ((rows + 1) / every + 1) as usize
}

fn trajectory(
    base: &Scenario,
    task: &Task,
    controller: &str,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
) -> Trajectory {
    let mut sink = Thinned::of(base);
    let with_rate = base.derive(&["output.record_rate_hz=10.0".into()], "picture");
    let outcome = match with_rate {
        // A team: vehicle 0's path (every vehicle records; the others' rows are dropped).
        Ok(b) if b.spec().team.is_some() => {
            match team_path(&b, task, entrant, gains, seed, &mut sink) {
                Ok(o) => o,
                Err(_) => "invalid_scenario".to_string(),
            }
        }
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

/// Flies a team run of (task, controller, seed) with vehicle 0 recording into `sink`: the
/// team's outcome (`completed` when every vehicle completed).
fn team_path(
    base: &Scenario,
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    sink: &mut Thinned,
) -> Result<String, String> {
    let s = prepare(base, task, entrant, gains, seed).map_err(|e| e.to_string())?;
    let n = s.spec().team.as_ref().map_or(0, |t| t.starts.len());
    let mut sinks: Vec<Thinned> = (0..n)
        .map(|_| Thinned {
            every: sink.every,
            k: 0,
            points: vec![],
        })
        .collect();
    let t = match s.run_team(&mut sinks) {
        Some(Ok(t)) => t,
        Some(Err(e)) => return Err(e.to_string()),
        None => return Err("no team".into()),
    };
    if let Some(first) = sinks.into_iter().next() {
        *sink = first;
    }
    Ok(t.runs
        .iter()
        .find(|r| r.outcome != isotrack_sim::Outcome::Completed)
        .map_or("completed", |r| r.outcome.as_str())
        .to_string())
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

/// The digest of what produces a task's results (`task.json`'s `digest`; `--resume` reuses
/// the stored task only when it is this one): the version, the task's keys, the suite's seeds,
/// controllers and scoring, the gains, the scenario file's bytes, and the SHA-256 of each
/// data file its field reads (`field.path`, `field.paths` of `base`, the task's scenario with
/// its `set`): a grid file rewritten since was otherwise reused as scored on the old one
/// (ver30b-3, att30d-10's benchmark half). A task without data files has the digest it had
/// before they were counted.
fn task_digest(
    suite: &Suite,
    task: &Task,
    controllers: &[String],
    gains: &BTreeMap<String, BTreeMap<String, f64>>,
    base: &Scenario,
) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update(env!("CARGO_PKG_VERSION"));
    h.update(toml::to_string(task).unwrap_or_default());
    h.update(format!(
        "{:?}{:?}{:?}",
        suite.scoring_seeds, controllers, suite.scoring
    ));
    h.update(serde_json::to_string(gains).unwrap_or_default());
    if let Ok(t) = isotrack_fields::io::read_limited(
        &suite.scenario_path(task),
        isotrack_scenario::MAX_SCENARIO_FILE_BYTES,
    ) {
        h.update(t);
    }
    // Each data file by path and content (a file that cannot be read now is left out, as in
    // summary.json; the task then fails to build anyway).
    for (path, sha) in isotrack_runs::summary::data_file_digests(base) {
        h.update(b"data_file\0");
        h.update(path.as_bytes());
        h.update(b"\0");
        h.update(sha.as_bytes());
    }
    h.finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<String>()
}

/// Each task of `suite` with the digest its results get in this run (`task.json`'s `digest`:
/// `--resume` reuses a stored task only when it is this one, [`run_task`]), known before any
/// run: what a front end tells the user `--resume` would reuse and replace (att53o-3, -7:
/// `--resume` was advised where it reused nothing). `None` under `o.tune` (the digest holds the
/// gains the tuning finds) or when a task cannot be built (the run then says why).
pub fn task_digests(suite: &Suite, reg: &Registry, o: &Options) -> Option<Vec<(String, String)>> {
    if o.tune {
        return None;
    }
    let controllers = controllers_of(suite, reg, o).ok()?;
    suite
        .tasks
        .iter()
        .map(|t| {
            let base = task_base(suite, t).ok()?;
            let gains = task_gains(suite, t, &base, reg, &controllers, o).ok()?;
            Some((
                t.id.clone(),
                task_digest(suite, t, &controllers, &gains, &base),
            ))
        })
        .collect()
}

/// The digest of the task results stored in `dir/tasks/ID/task.json`, when the file reads as a
/// task's results (as `--resume` reads it).
pub fn stored_digest(dir: &Path, id: &str) -> Option<String> {
    read_task(dir, id).map(|t| t.digest)
}

fn read_task(dir: &Path, id: &str) -> Option<TaskResult> {
    // A task file is a few KB; anything that is not a regular file is not one of ours.
    let text = isotrack_fields::io::read_text_limited(&task_file(dir, id), 64 << 20).ok()?;
    serde_json::from_str(&text).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 34: a task's runs stepped in lanes ([`run_jobs`] with `lanes`) give every row and
    /// path that each run flown alone gives, on 1 and 2 threads: the 6-DOF UAV in gusts (each
    /// lane its own gust seed and heading), the Dubins robot on the circular field, and a puff
    /// plume (a field per seed), each flown by three laws on four seeds.
    #[test]
    fn lanes_score_as_runs_one_at_a_time() {
        let text = r#"
name = "lanes"
version = 1
controllers = ["pi_isoline", "pid", "sliding_mode"]
tuning_seeds = [11]
scoring_seeds = [1, 2, 3, 4]

[[task]]
id = "uav"
title = "UAV in gusts"
scenario = "paper-fig3-uav.toml"
set = ["sim.duration_s=40.0", "vehicle.wind_mps=[6.0, 2.0]", "vehicle.gusts=true"]
length_m = 2131.0
vary = { "initial.heading_rad" = { uniform = [-3.0, 3.0] } }

[task.tuned.pi_isoline]
ki = 0.2
kp = 8.0

[[task]]
id = "circular"
title = "circular field"
scenario = "paper-fig2b-circular.toml"
set = ["sim.duration_s=30.0"]
length_m = 6.93
vary = { "initial.x_m" = { uniform = [8.0, 12.0] }, "initial.heading_rad" = { uniform = [-3.0, 3.0] } }

[[task]]
id = "puff"
title = "puff plume"
scenario = "puff-plume-edge.toml"
set = ["sim.duration_s=20.0"]
length_m = 50.0
"#;
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let suite = Suite::parse(text, "lanes.toml", &dir).unwrap();
        let reg = Registry::builtin();
        let o = Options::default();
        for task in &suite.tasks {
            let base = task_base(&suite, task).unwrap();
            let controllers = suite.controllers.clone();
            let jobs: Vec<(&String, u64, bool)> = controllers
                .iter()
                .flat_map(|c| {
                    suite
                        .scoring_seeds
                        .iter()
                        .enumerate()
                        .map(move |(k, s)| (c, *s, k == 0))
                })
                .collect();
            let seeded: BTreeMap<u64, Scenario> = suite
                .scoring_seeds
                .iter()
                .map(|&seed| {
                    (
                        seed,
                        base.derive(&[format!("sim.seed={seed}")], "seed").unwrap(),
                    )
                })
                .collect();
            let gains: BTreeMap<String, BTreeMap<String, f64>> = controllers
                .iter()
                .map(|c| (c.clone(), task.tuned.get(c).cloned().unwrap_or_default()))
                .collect();
            let j = Jobs {
                jobs: &jobs,
                seeded: &seeded,
                base: &base,
                task,
                reg: &reg,
                gains: &gains,
                scoring: suite.scoring,
            };
            let on = |threads: usize, lanes: bool| {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let done = pool.install(|| run_jobs(&j, &o, lanes)).unwrap();
                // `{:?}` writes each number's shortest round trip: equal text, equal bits.
                format!("{done:?}")
            };
            let alone = on(1, false);
            assert_eq!(on(1, true), alone, "task {}", task.id);
            assert_eq!(on(2, true), alone, "task {}", task.id);
            // Each row where its run is, and a path for each law's first seed.
            let rows = run_jobs(&j, &o, true).unwrap();
            assert_eq!(rows.len(), 12);
            for (k, (row, path)) in rows.iter().enumerate() {
                assert_eq!((&row.controller, row.seed), (jobs[k].0, jobs[k].1));
                assert_eq!(path.is_some(), jobs[k].2, "task {} run {k}", task.id);
            }
        }
    }
}
