//! The reinforcement-learning environment's engine: a batch of scenario episodes stepped in
//! one call (numpy in, numpy out), for `isotrack.gym.IsolineEnv` (a batch of one) and
//! `isotrack.gym.IsolineVectorEnv`. The Python side draws the random starts and seeds (from
//! Gymnasium's generators) and does the autoreset bookkeeping; everything per step is here.
//!
//! Per environment and step (one sensor sample, see `Episode`):
//! - action: the turn-rate command `omega`, rad/s, clipped to `[-omega_max, omega_max]` and held
//!   until the next delivered sample;
//! - observation: `[eps_m, deps_m]`, the measured error `eps_m = s_measured - s_d` and its
//!   sampled difference `(eps_m,k - eps_m,k-1) / (t_k - t_k-1)` (1/s; 0 at the first sample),
//!   exactly what a coordinate-free controller can compute;
//! - reward: `-min(|eps_k| / error_scale, MAX_SCALED_ERROR) - effort_weight * (omega /
//!   omega_max)^2`, with `eps_k` the true (noise-free) error at the new sample; on a terminating step (`left_field`,
//!   `diverged`) also `-termination_penalty` (default: the worst reward a step can have under
//!   the error cap `MAX_SCALED_ERROR`, times the steps left, so that ending a run early never
//!   scores better than flying it out).
//!
//! The run's last sample (at the last multiple of the sensor period within `sim.duration_s`)
//! ends the episode as truncated; the run then flies to its end with the last command held, so
//! an episode of `D` s at `R` Hz is `floor(D * R)` steps after the reset's first sample.

use crate::errors::ScenarioErrorPy;
use crate::scenario::PyScenario;
use isotrack_scenario::{Scenario, ScenarioEpisode, Start};
use isotrack_sim::{Outcome, RunResult, Sample};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;

/// The scaled error counted by the default termination penalty per step left: a run that ends
/// early pays as if every remaining step had `|eps| = MAX_SCALED_ERROR * error_scale` at full
/// effort.
pub(crate) const MAX_SCALED_ERROR: f64 = 10.0;

/// The tracking term of a reward, `min(|eps| / error_scale, MAX_SCALED_ERROR)`: capped, so that
/// the default termination penalty (`MAX_SCALED_ERROR` per step left) bounds what flying on could
/// cost and leaving the field never pays (att39-10: uncapped, an agent that could not hold its
/// error under 10 error scales scored better by leaving).
pub(crate) fn capped_error(error: f64, error_scale: f64) -> f64 {
    (error.abs() / error_scale).min(MAX_SCALED_ERROR)
}

/// The largest |reward| an episode sums to: `error_scale`, `effort_weight` and
/// `termination_penalty` are bounded so that every reward and their sum stay below it (finite).
const MAX_EPISODE_REWARD: f64 = 1e300;

/// The turn-rate bound of the action space when the scenario has no limit, rad/s (the same
/// default the search phase uses).
const DEFAULT_MAX_TURN_RATE_RADPS: f64 = 1.0;

/// One environment of the batch.
struct Slot {
    /// Boxed: a slot without a run is a few words, so that building a million is cheap.
    episode: Option<Box<ScenarioEpisode>>,
    /// The last observation, returned again once the episode has ended.
    obs: [f64; 2],
    /// Time of the last sample, s.
    t_s: f64,
    /// The true error at the last sample (field units).
    true_error: f64,
    /// Samples delivered so far.
    samples: u64,
    /// The vehicle's true pose at the last sample `(x_m, y_m, heading_rad)` (ground truth, for
    /// rendering; never part of the observation).
    pose: [f64; 3],
}

impl Slot {
    const EMPTY: Slot = Slot {
        episode: None,
        obs: [0.0; 2],
        t_s: 0.0,
        true_error: 0.0,
        samples: 0,
        pose: [0.0; 3],
    };
}

/// The heap one reset environment holds beyond its slot and episode, bytes: the boxed loop state
/// (vehicle, sensor with its generators, metrics) and the heap of the episode's copy of the
/// scenario's settings, rounded up (resident memory per environment measured over 10^5 reset
/// environments, Python's share included: 4.5 KiB for the default scenario, 5.4 KiB for the
/// 6-DOF UAV, of which the slot and episode are about 1.7 KiB; python/tests/test_gym.py checks
/// that the estimate is not below the measure).
const EPISODE_HEAP_BYTES: usize = 4096;

/// Most environments one batch holds (whatever the memory): 2^24. The Python side also sizes
/// `num_envs` by the memory available (`bytes_per_env`).
pub const MAX_NUM_ENVS: usize = 1 << 24;

/// A batch of `num_envs` episodes of one scenario.
#[pyclass(name = "EnvBatch", module = "isotrack._native")]
pub struct PyEnvBatch {
    scenario: Scenario,
    slots: Vec<Slot>,
    level: f64,
    max_turn_rate_radps: f64,
    error_scale: f64,
    effort_weight: f64,
    termination_penalty: Option<f64>,
    /// Samples a full run delivers at most (for the default termination penalty).
    samples_per_run: f64,
    /// Time of the run's last sample step, s: the last multiple of the sensor period within
    /// `sim.duration_s` (`k * dt_s`, the arithmetic of the loop's own sample times). A sample
    /// there is the run's last, and ends the episode.
    last_sample_t_s: f64,
}

pub(crate) fn invalid(name: &str, v: f64, why: &str) -> PyErr {
    PyValueError::new_err(format!(
        "{name} must be {why}, got {}",
        isotrack_core::numtext::Echo(v)
    ))
}

/// The reward settings' bounds, one rule for the Gymnasium environments and the PettingZoo
/// team environment: an episode's rewards stay finite (issue 30, att30b item 7: error_scale =
/// 2.3e-308 gave -inf; att30c-15 for the team). `|eps|` is at most twice the fields' value bound
/// and every weighted term of a reward at most its weight, so with `terms` rewards summed (an
/// episode's samples, times the agents for a team) each term's sum stays below
/// [`MAX_EPISODE_REWARD`]: `error_scale >= 2 MAX_FIELD_VALUE terms / MAX_EPISODE_REWARD`, each
/// weight at most `MAX_EPISODE_REWARD / terms`. `what` names the terms in the message.
pub(crate) fn check_reward_bounds(
    scale: f64,
    weights: &[(&str, f64)],
    terms: f64,
    what: &str,
) -> PyResult<()> {
    let min_scale =
        2.0 * isotrack_scenario::resolve::ranges::MAX_FIELD_VALUE * terms / MAX_EPISODE_REWARD;
    if scale < min_scale {
        return Err(PyValueError::new_err(format!(
            "error_scale must be at least {} field units (|eps| / error_scale over the {} {what} stays below {}), got {}",
            isotrack_core::numtext::Num(min_scale),
            isotrack_core::numtext::Num(terms),
            isotrack_core::numtext::Num(MAX_EPISODE_REWARD),
            isotrack_core::numtext::Echo(scale)
        )));
    }
    let max_weight = MAX_EPISODE_REWARD / terms;
    for (name, w) in weights {
        if *w > max_weight {
            return Err(PyValueError::new_err(format!(
                "{name} must be at most {} (over the {} {what} the reward stays below {}), got {}",
                isotrack_core::numtext::Num(max_weight),
                isotrack_core::numtext::Num(terms),
                isotrack_core::numtext::Num(MAX_EPISODE_REWARD),
                isotrack_core::numtext::Echo(*w)
            )));
        }
    }
    Ok(())
}

/// Each a finite number > 0, not subnormal (the reward's `error_scale`, a turn-rate bound).
pub(crate) const POSITIVE: &str =
    "finite and > 0, not subnormal (at least 2.2250738585072014e-308)";
/// Each a finite number >= 0, 0 or not subnormal (a reward's weight).
pub(crate) const NON_NEGATIVE: &str =
    "finite and >= 0, 0 or not subnormal (at least 2.2250738585072014e-308)";

/// Whether `x` is 0 or a normal number: a subnormal (below 2.2e-308, `1e-310`) is no setting
/// anyone means, and dividing by one overflows (a reward of `-inf` from `error_scale = 1e-310`).
pub(crate) fn zero_or_normal(x: f64) -> bool {
    x == 0.0 || x.is_normal()
}

/// A reward's weight (or penalty) `v`, named `name` in the refusal: a finite number >= 0, 0 or
/// not subnormal ([`NON_NEGATIVE`]).
pub(crate) fn check_weight(name: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() && v >= 0.0 && zero_or_normal(v) {
        Ok(v)
    } else {
        Err(invalid(name, v, NON_NEGATIVE))
    }
}

/// The turn-rate bound of an environment's action, rad/s: `given`, else the scenario's limit,
/// else [`DEFAULT_MAX_TURN_RATE_RADPS`] (unchecked).
pub(crate) fn turn_rate_bound(s: &Scenario, given: Option<f64>) -> f64 {
    given
        .or(s.max_turn_rate_radps())
        .unwrap_or(DEFAULT_MAX_TURN_RATE_RADPS)
}

/// The reward's error scale, field units: `given`, else the scenario's PI law's `c2`, else 1;
/// checked to be [`POSITIVE`].
pub(crate) fn error_scale_of(s: &Scenario, given: Option<f64>) -> PyResult<f64> {
    let scale = given
        .or(s.spec().controller.pi_isoline().map(|p| p.c2))
        .unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0 && scale.is_normal()) {
        return Err(invalid("error_scale", scale, POSITIVE));
    }
    Ok(scale)
}

/// A batch's size, at least 1 and at most [`MAX_NUM_ENVS`].
fn check_num_envs(num_envs: usize) -> PyResult<()> {
    if num_envs == 0 {
        return Err(PyValueError::new_err("num_envs must be at least 1"));
    }
    if num_envs > MAX_NUM_ENVS {
        return Err(PyValueError::new_err(format!(
            "num_envs = {num_envs} is more than the {MAX_NUM_ENVS} environments one batch holds"
        )));
    }
    Ok(())
}

/// The action's turn-rate bound ([`turn_rate_bound`]), rad/s: [`POSITIVE`], and within what
/// the float32 action space holds.
fn action_bound(s: &Scenario, given: Option<f64>) -> PyResult<f64> {
    let omax = turn_rate_bound(s, given);
    // Each a finite number, and not subnormal (a step of 1e-310 divides into infinity).
    if !(omax.is_finite() && omax > 0.0 && omax.is_normal()) {
        return Err(invalid("max_turn_rate_radps", omax, POSITIVE));
    }
    // The action space is float32 (Gymnasium's Box): a bound it cannot hold (1e300, or
    // 1e-300 which rounds to 0) is refused here, in isotrack's words (issue 30, att30b
    // item 7).
    let (f32_max, f32_min) = (f64::from(f32::MAX), f64::from(f32::MIN_POSITIVE));
    if !(f32_min..=f32_max).contains(&omax) {
        return Err(PyValueError::new_err(format!(
            "max_turn_rate_radps must be within [{}, {}] rad/s (the action space is float32), got {}",
            isotrack_core::numtext::Num(f32_min),
            isotrack_core::numtext::Num(f32_max),
            isotrack_core::numtext::Echo(omax)
        )));
    }
    Ok(omax)
}

/// Time of the run's last sample step, s ([`PyEnvBatch`]'s `last_sample_t_s`); refused when
/// the run holds no sample after the first (an episode of no step).
fn last_sample_t_s(s: &Scenario) -> PyResult<f64> {
    let plan = s.plan();
    // The sensor samples the steps 0, every, 2 every, ... (a delay only holds back the first
    // values): the last sample step is the last multiple of `every` within the run.
    let every = s.sensor().steps_per_sample();
    if plan.n_steps < every {
        return Err(PyValueError::new_err(format!(
            "an episode needs at least one step: sim.duration_s = {} s holds no sensor \
             sample after the first at {} Hz",
            s.spec().sim.duration_s,
            s.spec().sensor.rate_hz
        )));
    }
    Ok((plan.n_steps / every * every) as f64 * plan.dt_s)
}

/// `num_envs` slots without a run, or `MemoryError` when they do not fit.
fn empty_slots(num_envs: usize) -> PyResult<Vec<Slot>> {
    let mut slots = Vec::new();
    slots
        .try_reserve_exact(num_envs)
        .map_err(|_| PyMemoryError::new_err(format!("no memory for {num_envs} environments")))?;
    slots.extend((0..num_envs).map(|_| Slot::EMPTY));
    Ok(slots)
}

#[pymethods]
impl PyEnvBatch {
    #[new]
    #[pyo3(signature = (scenario, num_envs, max_turn_rate_radps=None, error_scale=None, effort_weight=0.01, termination_penalty=None))]
    fn new(
        scenario: &PyScenario,
        num_envs: usize,
        max_turn_rate_radps: Option<f64>,
        error_scale: Option<f64>,
        effort_weight: f64,
        termination_penalty: Option<f64>,
    ) -> PyResult<Self> {
        let s = scenario.inner.clone();
        check_num_envs(num_envs)?;
        let omax = action_bound(&s, max_turn_rate_radps)?;
        let scale = error_scale_of(&s, error_scale)?;
        check_weight("effort_weight", effort_weight)?;
        let termination_penalty = termination_penalty
            .map(|p| check_weight("termination_penalty", p))
            .transpose()?;
        let duration = s.spec().sim.duration_s;
        let rate = s.spec().sensor.rate_hz;
        let samples = ((duration * rate).floor() + 1.0).max(1.0);
        check_reward_bounds(
            scale,
            &[
                ("effort_weight", effort_weight),
                ("termination_penalty", termination_penalty.unwrap_or(0.0)),
            ],
            samples,
            "samples of an episode",
        )?;
        let last_sample_t_s = last_sample_t_s(&s)?;
        Ok(Self {
            level: s.level(),
            scenario: s,
            slots: empty_slots(num_envs)?,
            max_turn_rate_radps: omax,
            error_scale: scale,
            effort_weight,
            termination_penalty,
            samples_per_run: (duration * rate).floor() + 1.0,
            last_sample_t_s,
        })
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.slots.len()
    }

    /// The action bound, rad/s.
    #[getter]
    fn max_turn_rate_radps(&self) -> f64 {
        self.max_turn_rate_radps
    }

    /// The largest start radius, m: the scenario's coordinate range
    /// (`isotrack_scenario::resolve::ranges::MAX_COORDINATE_M`).
    #[getter]
    fn max_start_radius_m(&self) -> f64 {
        isotrack_scenario::resolve::ranges::MAX_COORDINATE_M
    }

    /// The reward's error scale (field units).
    #[getter]
    fn error_scale(&self) -> f64 {
        self.error_scale
    }

    /// The scenario's own start `(x_m, y_m, heading_rad)`.
    #[getter]
    fn start(&self) -> (f64, f64, f64) {
        let s = self.scenario.start();
        (s.x_m, s.y_m, s.heading_rad)
    }

    /// The default radius of the random start disc: 1 % of the distance the vehicle flies in the
    /// scenario's duration, m.
    #[getter]
    fn default_start_radius_m(&self) -> f64 {
        let d = self.scenario.spec().sim.duration_s;
        0.01 * d * self.scenario.start_speed_mps(self.scenario.start())
    }

    /// The vehicle's speed at the scenario's start, m/s (for the rendered frame's scale).
    #[getter]
    fn speed_mps(&self) -> f64 {
        self.scenario.start_speed_mps(self.scenario.start())
    }

    /// The sensor period, s.
    #[getter]
    fn sensor_period_s(&self) -> f64 {
        1.0 / self
            .scenario
            .file()
            .sensor
            .rate_hz
            .unwrap_or(1.0 / self.scenario.dt_s())
    }

    /// Whether the field has a value at `(x, y)` (m) at t = 0.
    fn has_value(&self, x_m: f64, y_m: f64) -> bool {
        use isotrack_core::ScalarField;
        self.scenario
            .field()
            .value(0.0, isotrack_core::Vec2::new(x_m, y_m))
            .is_some()
    }

    /// Starts environment `i` from `(x_m, y_m, heading_rad)` with the sensor seeded by
    /// `sensor_seed` (`sim.seed` if `None`), and steps it to its first sample: returns the first
    /// observation. Raises `ValueError` if the run ends before any sample (a start off the field).
    #[pyo3(signature = (i, x_m, y_m, heading_rad, sensor_seed=None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        i: usize,
        x_m: f64,
        y_m: f64,
        heading_rad: f64,
        sensor_seed: Option<u64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let n = self.slots.len();
        let level = self.level;
        let slot = self
            .slots
            .get_mut(i)
            .ok_or_else(|| PyValueError::new_err(format!("environment {i} of {n}")))?;
        // The scenario's own ranges for `initial.*` (issue 30, fix30c: a heading of 1e300 rad
        // was flown): finite coordinates within MAX_COORDINATE_M, a heading within
        // MAX_ANGLE_RAD.
        use isotrack_scenario::resolve::ranges::{MAX_ANGLE_RAD, MAX_COORDINATE_M};
        for (name, v, most, unit) in [
            ("x_m", x_m, MAX_COORDINATE_M, "m"),
            ("y_m", y_m, MAX_COORDINATE_M, "m"),
            ("heading_rad", heading_rad, MAX_ANGLE_RAD, "rad"),
        ] {
            if !(v.is_finite() && v.abs() <= most) {
                return Err(PyValueError::new_err(format!(
                    "start {name} = {} must be a finite number within [-{}, {}] {unit} (as initial.{name} in a scenario)",
                    isotrack_core::numtext::Echo(v),
                    isotrack_core::numtext::Echo(most),
                    isotrack_core::numtext::Echo(most)
                )));
            }
        }
        let start = Start {
            x_m,
            y_m,
            heading_rad,
        };
        let mut e = self.scenario.episode(Some(start), sensor_seed);
        let Some(sample) = e.run_to_sample() else {
            let r = e.result();
            return Err(PyValueError::new_err(format!(
                "the run from ({}, {}) m ended before its first sample: {} ({})",
                isotrack_core::numtext::Echo(x_m),
                isotrack_core::numtext::Echo(y_m),
                r.outcome.as_str(),
                r.outcome_detail.unwrap_or_default()
            )));
        };
        slot.obs = [sample.measurement.value - level, 0.0];
        slot.t_s = sample.measurement.t_s;
        slot.true_error = sample.true_value - level;
        slot.samples = 1;
        slot.pose = pose_of(&sample);
        slot.episode = Some(Box::new(e));
        Ok(PyArray1::from_slice(py, &slot.obs))
    }

    /// Steps every environment where `active` is true by one sample with its action (rad/s):
    /// `(obs[n, 2], reward[n], terminated[n], truncated[n], t_s[n])`. Inactive or ended
    /// environments keep their last observation, with reward 0 and both flags false.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray1<'py, f64>,
        active: PyReadonlyArray1<'py, bool>,
    ) -> PyResult<(
        Bound<'py, PyAny>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let (a, act) = (actions.as_slice()?, active.as_slice()?);
        let n = self.slots.len();
        if a.len() != n || act.len() != n {
            return Err(PyValueError::new_err(format!(
                "expected {n} actions and {n} active flags, got {} and {}",
                a.len(),
                act.len()
            )));
        }
        let mut obs = vec![0.0; 2 * n];
        let mut reward = vec![0.0; n];
        let mut terminated = vec![false; n];
        let mut truncated = vec![false; n];
        let mut t = vec![0.0; n];
        let this = &mut *self;
        py.detach(|| {
            for i in 0..n {
                if act[i] {
                    let (r, term, trunc) = this.step_one(i, a[i]);
                    reward[i] = r;
                    terminated[i] = term;
                    truncated[i] = trunc;
                }
                obs[2 * i..2 * i + 2].copy_from_slice(&this.slots[i].obs);
                t[i] = this.slots[i].t_s;
            }
        });
        let obs = PyArray1::from_vec(py, obs).reshape([n, 2])?.into_any();
        Ok((
            obs,
            PyArray1::from_vec(py, reward),
            PyArray1::from_vec(py, terminated),
            PyArray1::from_vec(py, truncated),
            PyArray1::from_vec(py, t),
        ))
    }

    /// Environment `i`'s true state at its last sample `(x_m, y_m, heading_rad, t_s)` (ground
    /// truth for rendering and logs; never part of the observation). Raises `ValueError` before
    /// its first reset.
    fn pose(&self, i: usize) -> PyResult<(f64, f64, f64, f64)> {
        let s = self
            .slots
            .get(i)
            .filter(|s| s.episode.is_some())
            .ok_or_else(|| PyValueError::new_err(format!("environment {i} was never reset")))?;
        Ok((s.pose[0], s.pose[1], s.pose[2], s.t_s))
    }

    /// Every environment's true state at its last sample, `float64[num_envs, 4]` of rows
    /// `(x_m, y_m, heading_rad, t_s)`, NaN for one never reset (for rendering a vector
    /// environment in one call; never part of the observation).
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f64> = self
            .slots
            .iter()
            .flat_map(|s| match s.episode {
                Some(_) => [s.pose[0], s.pose[1], s.pose[2], s.t_s],
                None => [f64::NAN; 4],
            })
            .collect();
        Ok(PyArray1::from_vec(py, v)
            .reshape([self.slots.len(), 4])?
            .into_any())
    }

    /// Bounds of the observation `[eps_m, deps_m]` where the sensor has a `range = [lo, hi]`
    /// (the measurement is clamped to it): `eps_m` in `[lo - s_d, hi - s_d]` and `|deps_m| <=
    /// (hi - lo) / period` (samples are at least a sensor period apart), widened by a relative
    /// 1e-9 for the rounding of the difference; `None` without a range (no finite bound).
    #[getter]
    fn observation_bounds(&self) -> Option<([f64; 2], [f64; 2])> {
        let [lo, hi] = self.scenario.file().sensor.range?;
        let slope = (hi - lo) / self.sensor_period_s() * (1.0 + 1e-9);
        Some(([lo - self.level, -slope], [hi - self.level, slope]))
    }

    /// The memory one environment of this batch holds once reset, bytes (the slot with its
    /// episode, the boxed loop state and the sensor's delay line), an upper estimate.
    #[getter]
    fn bytes_per_env(&self) -> usize {
        let delay_line = self
            .scenario
            .file()
            .sensor
            .delay_s
            .map_or(0, |d| (d / self.sensor_period_s()).ceil() as usize + 1);
        std::mem::size_of::<Slot>()
            + std::mem::size_of::<ScenarioEpisode>()
            + EPISODE_HEAP_BYTES
            + delay_line * std::mem::size_of::<f64>()
    }

    /// The `summary.json`-style result of environment `i`'s episode so far (JSON text): outcome,
    /// times, and every metric. Raises `ValueError` before its first reset.
    fn result_json(&self, i: usize) -> PyResult<String> {
        let e = self
            .slots
            .get(i)
            .and_then(|s| s.episode.as_ref())
            .ok_or_else(|| PyValueError::new_err(format!("environment {i} was never reset")))?;
        let r: RunResult = e.result();
        serde_json::to_string(&r).map_err(|e| ScenarioErrorPy::new_err(e.to_string()))
    }
}

/// The true pose at a sample, `(x_m, y_m, heading_rad)`.
fn pose_of(sample: &Sample) -> [f64; 3] {
    let p = sample.pose;
    [p.position.x, p.position.y, p.heading_rad]
}

impl PyEnvBatch {
    /// One step of environment `i`: `(reward, terminated, truncated)`.
    fn step_one(&mut self, i: usize, action: f64) -> (f64, bool, bool) {
        let omax = self.max_turn_rate_radps;
        let (level, scale, last_sample_t_s) = (self.level, self.error_scale, self.last_sample_t_s);
        let penalty = |samples: u64| {
            let left = (self.samples_per_run - samples as f64).max(0.0);
            self.termination_penalty
                .unwrap_or((MAX_SCALED_ERROR + self.effort_weight) * left)
        };
        let slot = &mut self.slots[i];
        let Some(e) = slot.episode.as_mut() else {
            return (0.0, false, false);
        };
        if e.outcome().is_some() {
            return (0.0, false, false);
        }
        // NaN stays NaN (and ends the run as `diverged`); infinities clip to the bound.
        let omega = action.clamp(-omax, omax);
        // A NaN command (which ends the run) costs the full effort, not a NaN reward.
        let effort = self.effort_weight * (omega / omax).powi(2).min(1.0);
        let effort = if effort.is_nan() {
            self.effort_weight
        } else {
            effort
        };
        e.command(omega);
        let Some(sample) = e.run_to_sample() else {
            // Ended without a new sample: off the field, diverged, or (the sensor dropping the
            // last samples) at the end of the run.
            let r = -capped_error(slot.true_error, scale) - effort;
            return match e.outcome() {
                Some(Outcome::Completed) | None => (r, false, true),
                Some(_) => (r - penalty(slot.samples), true, false),
            };
        };
        let eps_m = sample.measurement.value - level;
        let dt = sample.measurement.t_s - slot.t_s;
        slot.obs = [eps_m, (eps_m - slot.obs[0]) / dt];
        slot.t_s = sample.measurement.t_s;
        slot.true_error = sample.true_value - level;
        slot.samples += 1;
        slot.pose = pose_of(&sample);
        let r = -capped_error(slot.true_error, scale) - effort;
        if sample.measurement.t_s < last_sample_t_s {
            return (r, false, false);
        }
        // The run's last sample: no later command would reach the vehicle, so the episode ends
        // here, the command held to the end of the run (to `sim.duration_s`).
        e.command(omega);
        while e.run_to_sample().is_some() {
            e.command(omega);
        }
        match e.outcome() {
            Some(Outcome::Completed) | None => (r, false, true),
            Some(_) => (r - penalty(slot.samples), true, false),
        }
    }
}
