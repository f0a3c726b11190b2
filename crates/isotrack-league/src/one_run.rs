//! One run of a benchmark: the scenario of a (task, controller, seed), flying it, and the context
//! it is scored in. Shared by the scoring ([`crate::run`]) and the tuning ([`crate::tune`]).

use crate::registry::{Clipped, Entrant};
use crate::results::TeamRow;
use crate::score::{score, team_score, Score, ScoreContext, Scoring};
use crate::suite::{seed_overrides, Task};
use isotrack_runs::results::RunRecord;
use isotrack_runs::summary::TeamRecord;
use isotrack_scenario::{Assignment, Scenario, ScenarioError};
use isotrack_sim::{NoTrace, Outcome, RunResult, TraceSink};
use std::collections::BTreeMap;

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

/// [`run_overrides`] as assignments labelled `task ID: KEY=VALUE`, in the same order.
pub(crate) fn run_assignments(
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
) -> Vec<Assignment> {
    let origin = format!("task {}", task.id);
    run_overrides(task, entrant, gains, seed)
        .into_iter()
        .map(|a| Assignment::new(a, &origin))
        .collect()
}

/// The scenario of one (task, controller, seed): the task's base flown by the controller (a
/// built-in law switched in with its gains), with the seed's draws and `sim.seed`.
pub fn prepare(
    base: &Scenario,
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
) -> Result<Scenario, ScenarioError> {
    let flown = match entrant {
        Entrant::Builtin(kind) => base.with_controller_kind(*kind)?,
        Entrant::Custom(_) => base.clone(),
    };
    flown.derive_with(
        &run_assignments(task, entrant, gains, seed),
        &format!("task {}", task.id),
    )
}

/// Runs one (task, controller, seed) into `sink`: the scenario ([`prepare`]), and its result
/// (`Err` with the message when the overrides make an invalid scenario).
pub fn run_one<S: TraceSink + ?Sized>(
    base: &Scenario,
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    sink: &mut S,
) -> Result<(Scenario, RunResult), String> {
    let s = prepare(base, task, entrant, gains, seed).map_err(|e| e.to_string())?;
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

/// The score context of a run of `s`, scored by `scoring`.
pub fn context(s: &Scenario, task: &Task, scoring: Scoring) -> ScoreContext {
    let plan = s.plan();
    ScoreContext {
        steady_start_s: plan.steady_state_start_step as f64 * plan.dt_s,
        length_m: task.length_m,
        speed_mps: s.start_speed_mps(s.start()),
        scoring,
    }
}

/// A scored run of one (task, controller, seed).
#[derive(Clone, Debug)]
pub struct Scored {
    /// `completed` when every vehicle completed; else the first vehicle's that did not
    /// (a single run: its outcome).
    pub outcome: String,
    /// The run's record (a team: vehicle 0's, as `summary.json`'s top level).
    pub record: RunRecord,
    /// Its score.
    pub score: Score,
    /// A team run's team columns.
    pub team: Option<TeamRow>,
}

/// The scored single-vehicle run `r` of scenario `s`.
fn scored_single(s: &Scenario, r: &RunResult, task: &Task, scoring: Scoring) -> Scored {
    Scored {
        outcome: r.outcome.as_str().to_string(),
        record: RunRecord::of(r),
        score: score(r, &context(s, task, scoring)),
        team: None,
    }
}

/// One run of [`run_scored_lanes`]: its task's base scenario (of its seed), the built-in law
/// that flies it with its gains, and its seed.
pub(crate) struct LaneJob<'a> {
    /// The base scenario (one vehicle).
    pub base: &'a Scenario,
    /// The built-in law's entrant ([`Entrant::Builtin`]).
    pub entrant: &'a Entrant,
    /// Its gains.
    pub gains: Option<&'a BTreeMap<String, f64>>,
    /// The scoring seed.
    pub seed: u64,
}

/// [`run_scored`] of each of `jobs` (single-vehicle runs of built-in laws), the runs stepped
/// together ([`Scenario::run_batch`]: those that share their field, vehicle and step plan,
/// [`isotrack_sim::LANES`] at a time in SIMD lanes, whatever their law, gains or seed), each
/// result the one `run_scored` gives (`run_batch`'s results are `run(&mut NoTrace)`'s bit for
/// bit; test `run::tests::lanes_score_as_runs_one_at_a_time`).
pub(crate) fn run_scored_lanes(
    jobs: &[LaneJob<'_>],
    task: &Task,
    scoring: Scoring,
) -> Vec<Result<Scored, String>> {
    // Each job's place among the scenarios flown, or why its scenario is invalid.
    let mut flown = Vec::with_capacity(jobs.len());
    let slots: Vec<Result<usize, String>> = jobs
        .iter()
        .map(|j| {
            let s = prepare(j.base, task, j.entrant, j.gains, j.seed).map_err(|e| e.to_string())?;
            flown.push(s);
            Ok(flown.len() - 1)
        })
        .collect();
    let results = Scenario::run_batch(&flown);
    slots
        .into_iter()
        .map(|slot| slot.map(|i| scored_single(&flown[i], &results[i], task, scoring)))
        .collect()
}

/// Runs and scores one (task, controller, seed) by `scoring`: a scenario with `[team]` as a
/// team (through [`Scenario::run_team`], the engine `isotrack run` flies it with; scored by
/// [`team_score`]), any other as one vehicle ([`run_one`], [`score`]). `Err` with the message
/// when the run's scenario is invalid, the team engine refuses it, or a registered controller
/// is asked to fly a team.
pub fn run_scored(
    base: &Scenario,
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    scoring: Scoring,
) -> Result<Scored, String> {
    run_scored_into(base, task, entrant, gains, seed, scoring, &mut NoTrace)
}

/// As [`run_scored`], a single vehicle's trace rows going into `sink` as well (at `base`'s
/// `output.record_rate_hz`; the trace does not change the run). A team records none.
pub fn run_scored_into<S: TraceSink + ?Sized>(
    base: &Scenario,
    task: &Task,
    entrant: &Entrant,
    gains: Option<&BTreeMap<String, f64>>,
    seed: u64,
    scoring: Scoring,
    sink: &mut S,
) -> Result<Scored, String> {
    if base.spec().team.is_none() {
        let (s, r) = run_one(base, task, entrant, gains, seed, sink)?;
        return Ok(scored_single(&s, &r, task, scoring));
    }
    if let Entrant::Custom(_) = entrant {
        return Err(format!(
            "task {}: a team task's vehicles fly the built-in laws only",
            task.id
        ));
    }
    let s = prepare(base, task, entrant, gains, seed).map_err(|e| e.to_string())?;
    let t = match s.run_team(&mut [] as &mut [NoTrace]) {
        Some(Ok(t)) => t,
        Some(Err(e)) => return Err(format!("[team]: {e}")),
        None => {
            return Err("[team]: this run has no team while its task's scenario has one".into())
        }
    };
    let metrics = t.team.as_ref().map(TeamRecord::of);
    let (sc, parts) = team_score(&t.runs, metrics.as_ref(), &context(&s, task, scoring));
    let r0 = t.runs.first().ok_or("[team]: no vehicle")?;
    let outcome = t
        .runs
        .iter()
        .find(|r| r.outcome != Outcome::Completed)
        .unwrap_or(r0)
        .outcome
        .as_str()
        .to_string();
    Ok(Scored {
        outcome,
        record: RunRecord::of(r0),
        score: sc,
        team: Some(TeamRow {
            vehicles: t.runs.len(),
            vehicles_completed: t
                .runs
                .iter()
                .filter(|r| r.outcome == Outcome::Completed)
                .count(),
            parts,
            metrics,
        }),
    })
}
