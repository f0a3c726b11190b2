//! One run of a benchmark: the scenario of a (task, controller, seed), flying it, and the context
//! it is scored in. Shared by the scoring ([`crate::run`]) and the tuning ([`crate::tune`]).

use crate::registry::{Clipped, Entrant};
use crate::score::{ScoreContext, Scoring};
use crate::suite::{seed_overrides, Task};
use isotrack_scenario::{Assignment, Scenario, ScenarioError};
use isotrack_sim::{RunResult, TraceSink};
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
