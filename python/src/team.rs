//! Teams from Python (docs/TEAMS.md): a `[team]` scenario's run with every vehicle's trace in
//! one table with a `vehicle` column and its `summary.json` (the `team` object and the
//! `vehicles` array), as `isotrack run` writes them; the run directory written byte for byte as
//! the CLI writes it; and the engine of the multi-agent environment (`isotrack.pettingzoo`),
//! which steps the team through the one team engine (`isotrack_sim::team::Group`), paused
//! between each step's samples and its move so that agents outside the loop can answer.

use crate::columns::{save_run, TraceColumns};
use crate::errors::ScenarioErrorPy;
use crate::scenario::PyScenario;
use isotrack_core::math::Vec2;
use isotrack_core::FieldDerivatives;
use isotrack_runs::trace::TeamTraceSink;
use isotrack_scenario::field::FieldModel;
use isotrack_scenario::spec::TeamSpec;
use isotrack_scenario::{Scenario, TeamIsolineModel, Tracker};
use isotrack_sim::team::spacing::RingMode;
use isotrack_sim::team::{Group, OwnedTeamIsoline};
use isotrack_sim::{Oracles, TeamMember, TeamResult, TraceRow, TraceSink};
use isotrack_vehicles::{DubinsSpeedState, DubinsState, DubinsVariableSpeed};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::cell::RefCell;

/// A team's trace rows, each with its vehicle's index, in the order the team records them.
type Rows = Vec<(u32, TraceRow)>;

/// One vehicle's trace sink into a team's shared row log.
struct RowSink<'a> {
    log: &'a RefCell<Rows>,
    vehicle: u32,
}

impl TraceSink for RowSink<'_> {
    fn record(&mut self, r: &TraceRow) {
        self.log.borrow_mut().push((self.vehicle, *r));
    }
}

fn sinks(log: &RefCell<Rows>, n: usize) -> Vec<RowSink<'_>> {
    (0..n)
        .map(|i| RowSink {
            log,
            vehicle: i as u32,
        })
        .collect()
}

/// `scenario` with `output.record_rate_hz` set to `rate` (as `Scenario.run` sets it).
fn with_record_rate(scenario: &PyScenario, rate: Option<f64>) -> PyResult<Scenario> {
    match rate {
        None => Ok(scenario.inner.clone()),
        Some(r) if !r.is_finite() => Err(ScenarioErrorPy::new_err(format!(
            "`output.record_rate_hz`: {r:?} is not a finite number"
        ))),
        // `{:?}` of a finite f64 is a TOML float that reads back exactly.
        Some(r) => scenario
            .inner
            .derive(&[format!("output.record_rate_hz={r:?}")], &scenario.origin)
            .map_err(|e| ScenarioErrorPy::new_err(e.to_string())),
    }
}

/// `summary.json`'s text for a team run, as `isotrack run` writes it: the top-level metrics
/// vehicle 0's, the `team` object and the `vehicles` array.
fn team_summary_json(s: &Scenario, origin: &str, r: &TeamResult) -> PyResult<String> {
    let warnings = isotrack_scenario::check::warnings(s);
    let path = (!origin.starts_with('<')).then(|| std::path::Path::new(origin));
    // Without its final newline: the writer adds it (`write_team_run`).
    let json = isotrack_runs::summary::Summary::of_team(s, path, r, &warnings).to_json();
    Ok(json.trim_end_matches('\n').to_string())
}

/// The trace's columns as numpy arrays, named as `trace.csv`'s (`s_measured` NaN where no
/// sample was delivered yet), `vehicle` an int64 column.
fn team_columns<'py>(py: Python<'py>, rows: &Rows, flying: bool) -> PyResult<Bound<'py, PyDict>> {
    let d = crate::scenario::trace_columns_by(py, rows, |(_, r)| r, flying)?;
    let v: Vec<i64> = rows.iter().map(|(i, _)| i64::from(*i)).collect();
    d.set_item(
        isotrack_runs::trace::VEHICLE_COLUMN,
        PyArray1::from_vec(py, v),
    )?;
    Ok(d)
}

/// Runs a `[team]` scenario: `(summary_json, trace_columns, scenario_flown)`, the trace with a
/// `vehicle` column (`isotrack run`'s `trace.csv`, rows in its order), the summary with the
/// `team` object and the `vehicles` array. `record_rate_hz` overrides
/// `output.record_rate_hz`. Ctrl-C raises `KeyboardInterrupt` at once (the run, which cannot be
/// cancelled, finishes on its own thread, its answer dropped).
///
/// `controllers`: one Python controller per vehicle (`update(t_s, value) -> omega`, the listed
/// order), each steering its vehicle in place of the scenario's tracking law and seeing only
/// its own vehicle's samples; each is `reset()` first if it has the method. The run then goes
/// on this thread (the controllers call into Python); the first exception of any of them stops
/// every vehicle (their commands NaN: `diverged`) and is raised, as is Ctrl-C.
#[pyfunction]
#[pyo3(signature = (scenario, record_rate_hz=None, controllers=None))]
pub fn team_run<'py>(
    py: Python<'py>,
    scenario: &PyScenario,
    record_rate_hz: Option<f64>,
    controllers: Option<Vec<Py<PyAny>>>,
) -> PyResult<(String, Bound<'py, PyDict>, PyScenario)> {
    crate::guard::no_panic(|| {
        let s = with_record_rate(scenario, record_rate_hz)?;
        let Some(count) = s.spec().team.as_ref().map(|t| t.count()) else {
            return Err(PyValueError::new_err(
                "not a team scenario (no [team] section): run it with Scenario.run()",
            ));
        };
        let flown = s.clone();
        let (result, rows) = match controllers {
            None => crate::guard::detached(py, move || {
                let log = RefCell::new(Rows::new());
                let mut sinks = sinks(&log, count);
                let r = flown.run_team(&mut sinks);
                drop(sinks);
                (r, log.into_inner())
            })?,
            Some(objs) => {
                let (r, rows) = run_team_python(py, &flown, objs, true)?;
                (Some(r), rows)
            }
        };
        let result = result
            .expect("the scenario has a team")
            .map_err(|e| ScenarioErrorPy::new_err(format!("[team]: {e}")))?;
        let summary = team_summary_json(&s, &scenario.origin, &result)?;
        let trace = team_columns(py, &rows, s.is_flying())?;
        Ok((
            summary,
            trace,
            PyScenario {
                inner: s,
                origin: scenario.origin.clone(),
                folder: scenario.folder.clone(),
            },
        ))
    })
}

/// What the Python controllers of a team share while it runs: the watch for Ctrl-C and the
/// first exception any of them raised (after which every one answers NaN).
struct TeamStop {
    watch: crate::guard::SignalWatch,
    error: Option<PyErr>,
}

/// One vehicle's Python controller in a team ([`run_team_python`]).
struct TeamPyController<'a> {
    inner: crate::controller::PyController,
    stop: &'a std::sync::Mutex<TeamStop>,
}

impl isotrack_core::IsolineController for TeamPyController<'_> {
    fn update(&mut self, m: &isotrack_core::Measurement) -> f64 {
        {
            let mut st = self.stop.lock().unwrap_or_else(|e| e.into_inner());
            if st.error.is_some() || !st.watch.keep_going() {
                return f64::NAN;
            }
        }
        let w = self.inner.update(m);
        if let Some(e) = self.inner.error.take() {
            let mut st = self.stop.lock().unwrap_or_else(|e| e.into_inner());
            st.error.get_or_insert(e);
            return f64::NAN;
        }
        w
    }
    fn reset(&mut self) {}
}

/// A team flown by Python controllers, one per vehicle (`objs`, each `reset()` first when it
/// has the method), on this thread with the GIL released between their calls, its trace
/// recorded when `record`. The first exception (a controller's, or Ctrl-C's
/// `KeyboardInterrupt`) is raised after the run.
pub(crate) fn run_team_python(
    py: Python<'_>,
    s: &Scenario,
    objs: Vec<Py<PyAny>>,
    record: bool,
) -> PyResult<(Result<TeamResult, isotrack_sim::TeamError>, Rows)> {
    let count = s.spec().team.as_ref().map_or(0, |t| t.count());
    if objs.len() != count {
        return Err(PyValueError::new_err(format!(
            "{} controllers for a team of {count}: give one per vehicle",
            objs.len()
        )));
    }
    for o in &objs {
        crate::controller::reset_if_any(py, o)?;
    }
    let stop = std::sync::Mutex::new(TeamStop {
        watch: crate::guard::SignalWatch::new(),
        error: None,
    });
    let limit = s.max_turn_rate_radps();
    let ctrls: Vec<TeamPyController<'_>> = objs
        .into_iter()
        .map(|obj| TeamPyController {
            inner: crate::controller::PyController {
                obj,
                error: None,
                max_turn_rate_radps: limit,
            },
            stop: &stop,
        })
        .collect();
    let (r, rows) = py.detach(|| {
        let log = RefCell::new(Rows::new());
        let mut sinks = sinks(&log, if record { count } else { 0 });
        let r = s.run_team_with(ctrls, &mut sinks);
        drop(sinks);
        (r, log.into_inner())
    });
    let st = stop.into_inner().unwrap_or_else(|e| e.into_inner());
    if let Some(e) = st.error.or(st.watch.error) {
        return Err(e);
    }
    py.check_signals()?;
    let r = r.ok_or_else(|| PyValueError::new_err("not a team scenario"))?;
    Ok((r, rows))
}

/// Whether the scenario has a `[team]` section.
#[pyfunction]
pub fn is_team(scenario: &PyScenario) -> bool {
    scenario.inner.spec().team.is_some()
}

/// The team's size (`None` without `[team]`).
#[pyfunction]
pub fn team_count(scenario: &PyScenario) -> Option<usize> {
    scenario.inner.spec().team.as_ref().map(|t| t.count())
}

/// Writes a team's run directory as `isotrack run --out` does: `trace.csv` with the `vehicle`
/// column (numbers in the same shortest round-trip form), `summary.json` (its text) and the
/// resolved `scenario.toml` (after `note`, comment lines, when given), holding the directory's
/// lock as a single run's save does (`crate::tools::write_run`).
#[pyfunction]
#[pyo3(signature = (dir, summary_json, scenario, trace, note="", done=None))]
pub fn write_team_run(
    py: Python<'_>,
    dir: &str,
    summary_json: &str,
    scenario: &PyScenario,
    trace: &Bound<'_, PyDict>,
    note: &str,
    done: Option<&Bound<'_, PyList>>,
) -> PyResult<()> {
    let cols = TraceColumns::read(trace, scenario.inner.is_flying())?;
    let vehicles: PyReadonlyArray1<'_, i64> = trace
        .get_item(isotrack_runs::trace::VEHICLE_COLUMN)?
        .ok_or_else(|| PyValueError::new_err("the trace has no column `vehicle`"))?
        .extract()?;
    let vehicles = crate::columns::copy_interruptible(py, &vehicles)?;
    if vehicles.len() != cols.rows() {
        return Err(PyValueError::new_err(format!(
            "the trace's column `vehicle` has {} rows, `t_s` has {}",
            vehicles.len(),
            cols.rows()
        )));
    }
    let count = vehicles.iter().copied().max().unwrap_or(-1) + 1;
    if vehicles.iter().any(|&v| v < 0) || count > 1_000_000 {
        return Err(PyValueError::new_err(
            "the trace's column `vehicle` holds an index that is no vehicle's",
        ));
    }
    save_run(
        py,
        dir,
        summary_json,
        &scenario.inner,
        note,
        done,
        true,
        |w| {
            let w = RefCell::new(w);
            let mut sinks = TeamTraceSink::for_team(&w, count as usize);
            cols.stream(py, |i, row| sinks[vehicles[i] as usize].record(row))
        },
    )
}

/// Runs `$body` with `$f` bound to the scenario's field as its concrete type.
macro_rules! with_field {
    ($scenario:expr, $f:ident => $body:expr) => {
        match $scenario.field() {
            FieldModel::Analytic($f) => $body,
            FieldModel::Grid($f) => $body,
            FieldModel::Puff(p) => {
                let $f = &**p;
                $body
            }
            FieldModel::Series(s) => {
                let $f = &**s;
                $body
            }
        }
    };
}

/// Observation entries per agent: `[eps_m, deps_m, r_ahead_m, ahead_valid, r_behind_m,
/// behind_valid]`.
pub const OBS_LEN: usize = 6;

/// Per agent, what it has been told so far.
#[derive(Clone, Copy, Debug, Default)]
struct Agent {
    obs: [f64; OBS_LEN],
    /// Time of its last sample, s (`None` before the first).
    t_s: Option<f64>,
    /// The built-in law's last answer (rad/s) and whether this pause has a sample.
    builtin_omega: f64,
    sampled: bool,
    /// The turn rate it flies, rad/s (for the effort term).
    omega: f64,
    /// Whether it has been reported done.
    done: bool,
    /// Its tracking term `|eps| / error_scale` at the last pause with a true value (the term
    /// of a step that ends it off the field, where the field has none: nu36-5).
    last_tracking: f64,
}

/// The engine of `isotrack.pettingzoo`: a team stepped by agents outside the loop. Each env
/// step is `period` engine steps (the greatest common divisor of the sensor period, the
/// ranging period and the ranging delay, in steps): every sample and every range delivery
/// falls on a pause, so an agent that answers as the built-in laws answer flies the run
/// `Scenario.run()` flies, bit for bit.
#[pyclass(name = "TeamEnv", module = "isotrack._native", unsendable)]
pub struct PyTeamEnv {
    /// The scenario as given: its `sim.seed` is the first unseeded episode's.
    base: Scenario,
    /// The current episode's scenario: `base` with `sim.seed` the episode's seed (what its
    /// `summary.json` records, and what `Scenario.run()` and `isotrack run` replay).
    scenario: Scenario,
    vehicle: DubinsVariableSpeed,
    group: Option<Group<'static, DubinsSpeedState, Tracker>>,
    result: Option<TeamResult>,
    log: Rows,
    agents: Vec<Agent>,
    period: u64,
    level: f64,
    max_turn_rate_radps: f64,
    error_scale: f64,
    spacing_weight: f64,
    effort_weight: f64,
    /// What an agent's early end (`left_field`, `diverged`) costs, beside its step's reward
    /// (`None`: the default, as the single-vehicle environment's).
    termination_penalty: Option<f64>,
    /// The scenario's file (`summary.json`'s `scenario_path`), or `<...>` without one.
    origin: String,
    record: bool,
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The team of a scenario the environment can step: refused without `[team]`, with a ring
/// discovered in flight, or with per-vehicle overrides.
fn steppable_team(s: &Scenario) -> PyResult<&TeamSpec> {
    let Some(team) = s.spec().team.as_ref() else {
        return Err(PyValueError::new_err(
            "not a team scenario (no [team] section): the single-vehicle environment is isotrack.gym",
        ));
    };
    if matches!(team.ring, RingMode::Discover(_)) {
        return Err(PyValueError::new_err(
            "team.ring = \"discovered\": the environment's agents need a ring fixed at deployment \
             (team.ring = \"listed\"); the discovery's probes command the speeds themselves",
        ));
    }
    if !team.vehicles.is_empty() {
        return Err(PyValueError::new_err(
            "[[team.vehicles]]: per-vehicle overrides are flown by Scenario.run() and `isotrack run`; \
             the environment's agents share one speed envelope and sensor for now (docs/TEAMS.md)",
        ));
    }
    Ok(team)
}

#[pymethods]
impl PyTeamEnv {
    #[new]
    #[pyo3(signature = (scenario, max_turn_rate_radps=None, error_scale=None, spacing_weight=1.0, effort_weight=0.01, record=true, termination_penalty=None))]
    fn new(
        scenario: &PyScenario,
        max_turn_rate_radps: Option<f64>,
        error_scale: Option<f64>,
        spacing_weight: f64,
        effort_weight: f64,
        record: bool,
        termination_penalty: Option<f64>,
    ) -> PyResult<Self> {
        use crate::env::check_weight;
        let s = scenario.inner.clone();
        let team = steppable_team(&s)?;
        // The single-vehicle environment's bound, checked here without its float32 range.
        let omax = crate::env::turn_rate_bound(&s, max_turn_rate_radps);
        if !(omax.is_finite() && omax > 0.0 && omax.is_normal()) {
            return Err(PyValueError::new_err(format!(
                "max_turn_rate_radps must be finite and > 0, got {omax:?}"
            )));
        }
        let scale = crate::env::error_scale_of(&s, error_scale)?;
        let spacing_weight = check_weight("spacing_weight", spacing_weight)?;
        let effort_weight = check_weight("effort_weight", effort_weight)?;
        let termination_penalty = termination_penalty
            .map(|p| check_weight("termination_penalty", p))
            .transpose()?;
        // The Gymnasium environments' rule (one function): every agent's reward of every step
        // of the episode, at most one step per engine step, summed, stays finite.
        let steps = s.plan().n_steps as f64 + 1.0;
        crate::env::check_reward_bounds(
            scale,
            &[
                ("spacing_weight", spacing_weight),
                ("effort_weight", effort_weight),
                ("termination_penalty", termination_penalty.unwrap_or(0.0)),
            ],
            steps * team.count() as f64,
            "steps x agents of an episode",
        )?;
        let vehicle = DubinsVariableSpeed {
            min_speed_mps: team.v_min_mps,
            max_speed_mps: team.v_max_mps,
        };
        let n = team.count();
        let mut env = Self {
            level: s.level(),
            base: s.clone(),
            scenario: s,
            vehicle,
            group: None,
            result: None,
            log: Rows::new(),
            agents: vec![Agent::default(); n],
            period: 1,
            max_turn_rate_radps: omax,
            error_scale: scale,
            spacing_weight,
            effort_weight,
            termination_penalty,
            origin: scenario.origin.clone(),
            record,
        };
        env.period = env.pause_period()?;
        Ok(env)
    }

    /// Number of agents (vehicles).
    #[getter]
    fn num_agents(&self) -> usize {
        self.agents.len()
    }

    /// The turn-rate bound of the action, rad/s.
    #[getter]
    fn max_turn_rate_radps(&self) -> f64 {
        self.max_turn_rate_radps
    }

    /// The speed envelope `(v_min, v_max)`, m/s.
    #[getter]
    fn speed_range_mps(&self) -> (f64, f64) {
        (self.vehicle.min_speed_mps, self.vehicle.max_speed_mps)
    }

    /// Engine steps per environment step.
    #[getter]
    fn period_steps(&self) -> u64 {
        self.period
    }

    /// The engine's step, s.
    #[getter]
    fn dt_s(&self) -> f64 {
        self.scenario.plan().dt_s
    }

    /// The reward's error scale (field units).
    #[getter]
    fn error_scale(&self) -> f64 {
        self.error_scale
    }

    /// The scenario's own `sim.seed` (the first unseeded episode's).
    #[getter]
    fn base_seed(&self) -> u64 {
        self.base.spec().sim.seed
    }

    /// The current (or last) episode's `sim.seed`.
    #[getter]
    fn episode_seed(&self) -> u64 {
        self.scenario.spec().sim.seed
    }

    /// Starts a new episode, the scenario with `sim.seed = seed` (`None`: the scenario's own
    /// `sim.seed`; a seed is in `0 ..= 2**63-1`, `sim.seed`'s range, else `ValueError`), and
    /// runs to the first pause: `(obs[n, 6], builtin[n, 2], sampled[n], t_s)`.
    #[pyo3(signature = (seed=None))]
    #[allow(clippy::type_complexity)]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<u64>,
    ) -> PyResult<(
        Bound<'py, PyAny>,
        Bound<'py, PyAny>,
        Bound<'py, PyArray1<bool>>,
        f64,
    )> {
        crate::guard::no_panic(|| {
            let base_seed = self.base.spec().sim.seed;
            let seed = seed.unwrap_or(base_seed);
            if i64::try_from(seed).is_err() {
                return Err(PyValueError::new_err(format!(
                    "seed must be in 0 ..= 2**63-1 (9223372036854775807, sim.seed's range), got {seed}"
                )));
            }
            // The episode is the scenario with this `sim.seed`, as `Scenario.set("sim.seed", S)`
            // makes it (a puff plume's meander follows the seed too), so that its summary
            // records the seed it flew and `Scenario.run()` replays it.
            self.scenario = if seed == base_seed {
                self.base.clone()
            } else {
                self.base
                    .derive(&[format!("sim.seed={seed}")], "reset(seed)")
                    .map_err(|e| ScenarioErrorPy::new_err(e.to_string()))?
            };
            self.group = Some(self.build()?);
            self.result = None;
            self.log.clear();
            self.agents.iter_mut().for_each(|a| *a = Agent::default());
            self.run_to_pause();
            self.observe();
            let (b, s) = self.builtin(py)?;
            Ok((self.obs(py)?, b, s, self.t_s()))
        })
    }

    /// Steps with every agent's `(turn rate, speed)` (`turn[n]`, rad/s, `speed[n]`, m/s;
    /// `given[n]`: which agents act, the others' held): `(obs[n, 6], reward[n],
    /// terminated[n], truncated[n], builtin[n, 2], sampled[n], t_s)`. A turn rate takes effect
    /// at the agent's sample (none this step: its command is held, as a built-in law's is); a
    /// speed from this step on.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        turn: PyReadonlyArray1<'py, f64>,
        speed: PyReadonlyArray1<'py, f64>,
        given: PyReadonlyArray1<'py, bool>,
    ) -> PyResult<(
        Bound<'py, PyAny>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyAny>,
        Bound<'py, PyArray1<bool>>,
        f64,
    )> {
        self.act(turn.as_slice()?, speed.as_slice()?, given.as_slice()?)?;
        crate::guard::no_panic(|| {
            let mut rewards = vec![0.0; self.agents.len()];
            self.advance();
            self.run_to_pause();
            self.observe();
            // The time of this pause, before the run is completed below.
            let paused_t_s = self.t_s();
            let pauses_left = self.pauses_left();
            let last_pause = self.complete_run_end(&mut rewards);
            let (terminated, truncated) = self.end_agents(&mut rewards, last_pause, pauses_left);
            // The episode's last step says the time of its last pause (its last sample, as
            // `IsolineEnv` says), the run's end otherwise.
            let t_s = if last_pause { paused_t_s } else { self.t_s() };
            let (b, s) = self.builtin(py)?;
            Ok((
                self.obs(py)?,
                PyArray1::from_vec(py, rewards),
                PyArray1::from_vec(py, terminated),
                PyArray1::from_vec(py, truncated),
                b,
                s,
                t_s,
            ))
        })
    }

    /// Vehicle `i`'s true position `(x_m, y_m)` at the last pause (ground truth for rendering
    /// and logs; never part of an observation).
    fn position(&self, i: usize) -> PyResult<(f64, f64)> {
        let g = self
            .group
            .as_ref()
            .ok_or_else(|| PyValueError::new_err("no episode running"))?;
        if i >= g.len() {
            return Err(PyValueError::new_err(format!("no vehicle {i}")));
        }
        let (p, _) = g.sensed_truth(i);
        Ok((p.x, p.y))
    }

    /// The trace recorded so far (the columns of `Scenario.run()`'s team trace; after the
    /// episode's end its last rows too).
    fn trace<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        team_columns(py, &self.log, self.scenario.is_flying())
    }

    /// Once the episode has ended: its `summary.json` text (as `Scenario.run()`'s; `None`
    /// before the end).
    fn summary_json(&self) -> PyResult<Option<String>> {
        self.result
            .as_ref()
            .map(|r| team_summary_json(&self.scenario, &self.origin, r))
            .transpose()
    }
}

impl PyTeamEnv {
    /// The engine steps per env step, from a first team (which checks the settings): the
    /// greatest common divisor of the sensor period, the ranging period and the ranging delay.
    fn pause_period(&self) -> PyResult<u64> {
        let g = self.build()?;
        let (r_every, r_delay) = g.ranging_steps();
        let s_every = self.scenario.sensor().steps_per_sample();
        Ok(gcd(gcd(s_every, r_every), r_delay).max(1))
    }

    /// A team at step 0, as `Scenario::run_team` builds it (sensor and ranging seeds from
    /// the episode's `sim.seed`).
    fn build(&self) -> PyResult<Group<'static, DubinsSpeedState, Tracker>> {
        let s = &self.scenario;
        let team = s.spec().team.as_ref().expect("checked: a team scenario");
        let seed = s.spec().sim.seed;
        let vehicle = self.vehicle;
        let members = team
            .starts
            .iter()
            .enumerate()
            .map(|(i, st)| TeamMember {
                x0: vehicle.state(
                    DubinsState {
                        position_m: Vec2::new(st.x_m, st.y_m),
                        heading_rad: st.heading_rad,
                    },
                    team.nominal_speed_mps,
                ),
                controller: s.tracker(),
                sensor: s.sensor_seeded(TeamSpec::sensor_seed(seed, i)),
                ranging_seed: TeamSpec::ranging_seed(seed, i),
            })
            .collect();
        // The run's own true isoline and metrics configuration (att36-3: with the circle of a
        // radial field only, an isoline cut by field.domain_m, a grid's or a moving one had
        // no team metrics here, and the summary said the field had none).
        let model = s.team_isoline();
        let cfg = s.team_config(team, &model);
        let isoline = match model {
            TeamIsolineModel::Circle(c) => Some(OwnedTeamIsoline::Fixed(Box::new(c))),
            TeamIsolineModel::Polyline(p) => Some(OwnedTeamIsoline::Fixed(Box::new(p))),
            TeamIsolineModel::Moving(m) => Some(OwnedTeamIsoline::Moving(m)),
            TeamIsolineModel::None(_) => None,
        };
        Group::new_owning_isoline(&vehicle, &s.plan(), cfg, members, isoline)
            .map_err(|e| ScenarioErrorPy::new_err(format!("[team]: {e}")))
    }

    /// Hands the agents' actions to the paused team ([`PyTeamEnv::step`]'s `turn`, `speed` and
    /// `given`): each acting agent's turn rate (taking effect at its sample) and speed, clipped
    /// to the bounds; refused when the lengths are not the team's or no episode runs.
    fn act(&mut self, turn: &[f64], speed: &[f64], given: &[bool]) -> PyResult<()> {
        let n = self.agents.len();
        if turn.len() != n || speed.len() != n || given.len() != n {
            return Err(PyValueError::new_err(format!(
                "expected {n} turn rates, speeds and flags, got {}, {} and {}",
                turn.len(),
                speed.len(),
                given.len()
            )));
        }
        let Some(g) = self.group.as_mut() else {
            return Err(PyValueError::new_err(
                "the episode has ended (or was never reset): call reset()",
            ));
        };
        let (omax, (vlo, vhi)) = (
            self.max_turn_rate_radps,
            (self.vehicle.min_speed_mps, self.vehicle.max_speed_mps),
        );
        for i in 0..n {
            if !given[i] || !g.is_vehicle_running(i) {
                continue;
            }
            // The Python side has checked finiteness and the (float32) bounds; the last
            // rounding of a float32 bound is clipped here.
            let (w, v) = (turn[i].clamp(-omax, omax), speed[i].clamp(vlo, vhi));
            if g.replace_answer(i, w) {
                self.agents[i].omega = w;
            }
            g.hold_speed(i, v);
        }
        Ok(())
    }

    /// The environment steps an agent ending in this one would not fly (the default penalty's
    /// count): the episode's `floor(last / period)` less the steps taken, this one included (a
    /// team whose every vehicle has ended pauses at the step that ended the last one, within
    /// this env step: hence the rounding up).
    fn pauses_left(&self) -> u64 {
        let (last, period) = (self.scenario.plan().n_steps, self.period);
        self.group.as_ref().map_or(0, |g| {
            (last / period).saturating_sub(g.step_index().div_ceil(period))
        })
    }

    /// After a step's pause, completes the run where no later action would move a vehicle, as
    /// `Scenario.run()` completes it: `true` when this was the episode's last pause, whose
    /// rewards (of the agents not done) are then set in `rewards` before the run's last steps
    /// are flown.
    fn complete_run_end(&mut self, rewards: &mut [f64]) -> bool {
        // The run's last step reached and sensed (t = sim.duration_s): no later action would
        // move a vehicle, so the episode ends here, as `IsolineEnv` ends at the last sample
        // (nu-17: one more step repeated the last observation), the last step completed with
        // the laws' answers there (the trace's last row, as `Scenario.run()` writes it).
        let last = self.scenario.plan().n_steps;
        let (period, n) = (self.period, self.agents.len());
        if self
            .group
            .as_ref()
            .is_some_and(|g| g.is_running() && g.step_index() >= last)
        {
            self.advance();
        } else if self.group.as_ref().is_some_and(|g| {
            g.is_running() && g.step_index() < last && g.step_index() + period > last
        }) {
            // The last pause of a run whose sim.duration_s is no multiple of the period: no
            // later pause, so no later action or sample, as `IsolineEnv` ends at its last
            // sample (att30n-6: one more step, t = sim.duration_s, repeated this observation
            // as `sampled`). The run's last steps are flown here with the laws' answers to this
            // pause, held, as `Scenario.run()` holds them.
            // No action answers this pause: its speeds are the spacing laws' answers, as its
            // turn rates are the tracking laws' (nu36-19: the agents' speeds of the pause
            // before were held, and the tail flew another run than Scenario.run()).
            if let Some(g) = self.group.as_mut() {
                g.release_speeds();
            }
            for (i, r) in rewards.iter_mut().enumerate() {
                if !self.agents[i].done {
                    *r = self.reward(i);
                }
            }
            while self.group.as_ref().is_some_and(|g| g.is_running()) {
                self.advance();
                self.run_to_pause();
            }
            return true;
        } else if self
            .group
            .as_ref()
            .is_some_and(|g| g.is_running() && (0..n).all(|i| !g.is_vehicle_running(i)))
        {
            // Every vehicle's run has ended before sim.duration_s (each left the field, say):
            // the step that ended the last one is completed, as the engine's loop completes
            // it, so that the team stops and the summary comes (att30n-5: it stayed `None`
            // although every agent was done).
            self.advance();
        }
        false
    }

    /// Each agent not yet done: its reward in `rewards` (unless set at the `last_pause`), less
    /// the penalty of an early end with `pauses_left`, and whether its episode is terminated
    /// (an early end) or truncated (the run completed, or the team stopped); the team's run
    /// finished once no vehicle runs. `(terminated, truncated)`.
    fn end_agents(
        &mut self,
        rewards: &mut [f64],
        last_pause: bool,
        pauses_left: u64,
    ) -> (Vec<bool>, Vec<bool>) {
        let n = self.agents.len();
        let mut terminated = vec![false; n];
        let mut truncated = vec![false; n];
        let running = self
            .group
            .as_ref()
            .is_some_and(|g| g.is_running() && (0..n).any(|i| g.is_vehicle_running(i)));
        for i in 0..n {
            if self.agents[i].done {
                continue;
            }
            if !last_pause {
                rewards[i] = self.reward(i);
            }
            match self.outcome(i) {
                Some(isotrack_sim::Outcome::Completed) => truncated[i] = true,
                Some(_) => {
                    terminated[i] = true;
                    rewards[i] -= self.penalty(pauses_left);
                }
                None if !running => truncated[i] = true,
                None => {}
            }
            self.agents[i].done = terminated[i] || truncated[i];
        }
        if !running {
            self.finish();
        }
        (terminated, truncated)
    }

    /// Senses steps (each completed and moved, the commands held) until one that is a pause
    /// (a multiple of the period), which is left sensed, or until the team has stopped.
    fn run_to_pause(&mut self) {
        self.fly(true);
    }

    /// Completes the paused step and moves.
    fn advance(&mut self) {
        self.fly(false);
    }

    /// Flies the team through the scenario's field with its oracles, the trace recorded when
    /// `record`: to the next pause when `to_pause` ([`PyTeamEnv::run_to_pause`]), else the
    /// paused step completed and moved ([`PyTeamEnv::advance`]).
    fn fly(&mut self, to_pause: bool) {
        let s = self.scenario.clone();
        let vehicle = self.vehicle;
        let period = self.period;
        let n = if self.record { self.agents.len() } else { 0 };
        let log = RefCell::new(std::mem::take(&mut self.log));
        if let Some(g) = self.group.as_mut() {
            let mut sinks = sinks(&log, n);
            with_field!(s, field => {
                let iso = s.isoline();
                let dist = |t: f64, p: Vec2| iso.distance(t, p);
                let grad = |t: f64, p: Vec2| Some((field.gradient(t, p)?, field.hessian(t, p)?));
                let oracles = Oracles {
                    isoline_distance: Some(&dist),
                    gradient: Some(&grad),
                };
                if to_pause {
                    while g.is_running() {
                        g.sense(field, &vehicle, &oracles, &mut sinks);
                        if g.step_index() % period == 0 {
                            break;
                        }
                        g.advance(&vehicle, &oracles, &mut sinks);
                    }
                } else if g.is_running() {
                    g.advance(&vehicle, &oracles, &mut sinks);
                }
            });
        }
        self.log = log.into_inner();
    }

    /// Ends the team run: its result, the trace's last rows.
    fn finish(&mut self) {
        let Some(g) = self.group.take() else { return };
        let n = if self.record { self.agents.len() } else { 0 };
        let log = RefCell::new(std::mem::take(&mut self.log));
        let mut sinks = sinks(&log, n);
        let r = g.finish(&mut sinks);
        drop(sinks);
        self.log = log.into_inner();
        self.result = Some(TeamResult {
            runs: r
                .runs
                .into_iter()
                .map(|x| self.scenario.explain_end(x))
                .collect(),
            ..r
        });
    }

    /// Updates each agent's observation from the paused step's samples and range deliveries.
    fn observe(&mut self) {
        let Some(g) = self.group.as_ref().filter(|g| g.is_running()) else {
            return;
        };
        let level = self.level;
        for (i, a) in self.agents.iter_mut().enumerate() {
            a.sampled = false;
            if let Some((m, w)) = g.sampled(i) {
                let eps = m.value - level;
                let deps = match a.t_s {
                    Some(t0) if m.t_s > t0 => (eps - a.obs[0]) / (m.t_s - t0),
                    _ => 0.0,
                };
                a.obs[0] = eps;
                a.obs[1] = deps;
                a.t_s = Some(m.t_s);
                a.builtin_omega = w;
                a.sampled = true;
            }
            if let Some(r) = g.delivered_ranges(i) {
                let f = |x: isotrack_sim::team::ranging::Range| {
                    if x.valid {
                        (x.range_m, 1.0)
                    } else {
                        (0.0, 0.0)
                    }
                };
                (a.obs[2], a.obs[3]) = f(r.ahead);
                (a.obs[4], a.obs[5]) = f(r.behind);
            }
        }
    }

    /// Agent `i`'s reward at the pause: `-|eps_i| / error_scale - spacing_weight *
    /// ((d_ahead - d_behind) / (d_ahead + d_behind))^2 - effort_weight * (omega_i /
    /// omega_max)^2`, with the true error and true distances to its ring neighbours.
    fn reward(&mut self, i: usize) -> f64 {
        let effort = self.effort_weight
            * (self.agents[i].omega / self.max_turn_rate_radps)
                .powi(2)
                .min(1.0);
        let Some(g) = self.group.as_ref() else {
            return -effort;
        };
        let (p, value) = g.sensed_truth(i);
        // Off the field (no true value) the last term stands, as the single-vehicle
        // environment's reward keeps the last sample's error (nu36-5: it read 0, so that
        // leaving the field paid).
        let tracking = if value.is_finite() {
            let x = crate::env::capped_error(value - self.level, self.error_scale);
            self.agents[i].last_tracking = x;
            x
        } else {
            self.agents[i].last_tracking
        };
        let spacing = match g.neighbours(i) {
            Some([ahead, behind]) => {
                let da = (g.sensed_truth(ahead as usize).0 - p).norm();
                let db = (g.sensed_truth(behind as usize).0 - p).norm();
                let sum = da + db;
                if sum > 0.0 && sum.is_finite() {
                    ((da - db) / sum).powi(2)
                } else {
                    0.0
                }
            }
            None => 0.0,
        };
        -tracking - self.spacing_weight * spacing - effort
    }

    /// What an agent ending early with `pauses_left` pauses of the run unflown pays beside its
    /// step's reward: `termination_penalty`, by default the worst reward a step can have
    /// under the error cap, `MAX_SCALED_ERROR + spacing_weight + effort_weight`, times the
    /// pauses left, so that ending early never scores better than flying the run out (the
    /// single-vehicle environment's rule, `crate::env`).
    fn penalty(&self, pauses_left: u64) -> f64 {
        self.termination_penalty.unwrap_or(
            (crate::env::MAX_SCALED_ERROR + self.spacing_weight + self.effort_weight)
                * pauses_left as f64,
        )
    }

    fn outcome(&self, i: usize) -> Option<isotrack_sim::Outcome> {
        match (&self.group, &self.result) {
            (Some(g), _) => g.outcome(i),
            (None, Some(r)) => Some(r.runs[i].outcome),
            _ => None,
        }
    }

    fn t_s(&self) -> f64 {
        match &self.group {
            Some(g) => g.step_index() as f64 * g.plan().dt_s,
            None => self.scenario.spec().sim.duration_s,
        }
    }

    fn obs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self.agents.iter().flat_map(|a| a.obs).collect();
        Ok(PyArray1::from_vec(py, v)
            .reshape([self.agents.len(), OBS_LEN])?
            .into_any())
    }

    /// The built-in laws' actions at the pause, `[n, 2]` of `(turn rate, speed)` (the tracking
    /// law's answer to the sample, or its held command without one; the spacing law's speed
    /// saturated to the envelope), and which agents have a sample.
    fn builtin<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyArray1<bool>>)> {
        let (lo, hi) = (self.vehicle.min_speed_mps, self.vehicle.max_speed_mps);
        let mut v = Vec::with_capacity(2 * self.agents.len());
        for (i, a) in self.agents.iter().enumerate() {
            let speed = match &self.group {
                Some(g) => {
                    let s = g.law_speed_mps(i);
                    if s.is_nan() {
                        lo
                    } else {
                        s.clamp(lo, hi)
                    }
                }
                None => lo,
            };
            v.extend([a.builtin_omega, speed]);
        }
        let sampled: Vec<bool> = self.agents.iter().map(|a| a.sampled).collect();
        Ok((
            PyArray1::from_vec(py, v)
                .reshape([self.agents.len(), 2])?
                .into_any(),
            PyArray1::from_vec(py, sampled),
        ))
    }
}
