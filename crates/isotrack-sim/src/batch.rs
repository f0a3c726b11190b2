//! Batched runs: up to [`LANES`] runs that share the field, the vehicle model and the plan are
//! stepped together, structure of arrays, so that the field's formula and the vehicle's step
//! run in SIMD lanes (the `*_lanes` methods of [`ScalarField`] and [`Vehicle`]) while each run
//! keeps its own start, sensor, controller and metrics. A run that ends early is masked: its
//! lane is still computed (that costs nothing in a vector) but never read again.
//!
//! Every run's result is the one [`simulate`](crate::simulate) gives it alone, bit for bit:
//! the step order, the per-run bookkeeping and the arithmetic are the same (the lane
//! functions are the scalar ones, see `isotrack_core::lanes`), which the tests check run by
//! run. So a sweep's results do not depend on how its runs are grouped, on the thread count or
//! on the shard split. Traces are not recorded (a batch serves sweeps, which keep summaries).
//!
//! The loop is compiled for AVX-512 and AVX2 besides the baseline, and picks one at run time
//! (`multiversion`); all give the same numbers (no fused multiply-add is used).

use crate::metrics::{Metrics, MetricsConfig};
use crate::sensor::Sensor;
use crate::simulation::{Oracles, Outcome, RunResult, StepPlan};
use isotrack_core::control::GroundTruth;
use isotrack_core::math::Pose2;
use isotrack_core::{IsolineController, Measurement, ScalarField, Vec2, Vehicle};

/// Runs stepped together: 8 doubles fill an AVX-512 register (two AVX2 ones).
pub const LANES: usize = 8;

/// One run of a batch: where it starts, what steers it, what it senses, and the oracles its
/// metrics (and a reference controller) may consult.
pub struct BatchRun<'a, X, C> {
    /// Initial vehicle state.
    pub x0: X,
    /// The run's controller.
    pub controller: C,
    /// The run's sensor (its own seeded streams).
    pub sensor: Sensor,
    /// The run's oracles (see [`Oracles`]).
    pub oracles: Oracles<'a>,
}

/// Runs every run of `runs` on `field` with `vehicle` and `plan`, [`LANES`] at a time, and
/// returns their results in order: each the result [`simulate`](crate::simulate) gives that
/// run alone (with no trace).
pub fn simulate_batch<F, V, C>(
    field: &F,
    vehicle: &V,
    plan: &StepPlan,
    runs: Vec<BatchRun<'_, V::State, C>>,
) -> Vec<RunResult>
where
    F: ScalarField,
    V: Vehicle,
    C: IsolineController,
{
    let mut out = Vec::with_capacity(runs.len());
    let mut runs = runs.into_iter().peekable();
    while runs.peek().is_some() {
        let group: Vec<_> = runs.by_ref().take(LANES).collect();
        out.extend(run_group(field, vehicle, plan, group));
    }
    out
}

/// The bookkeeping of one lane: what [`Episode`](crate::Episode) keeps for a run without a trace.
struct Lane<'a, C> {
    controller: C,
    sensor: Sensor,
    oracles: Oracles<'a>,
    wants_truth: bool,
    metrics: Metrics,
    samples: u64,
    ended: Option<(Outcome, Option<String>)>,
    prev_pos: Vec2,
    last_valid_step: u64,
    end_pos: Vec2,
}

/// Up to [`LANES`] runs, stepped together (the lanes past `runs.len()` are padding, never live).
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "aarch64+neon"
))]
fn run_group<F, V, C>(
    field: &F,
    vehicle: &V,
    plan: &StepPlan,
    runs: Vec<BatchRun<'_, V::State, C>>,
) -> Vec<RunResult>
where
    F: ScalarField,
    V: Vehicle,
    C: IsolineController,
{
    let live = runs.len();
    let Some(first) = runs.first() else {
        return vec![];
    };
    let mut states: [V::State; LANES] = core::array::from_fn(|_| first.x0.clone());
    let mut lanes: Vec<Lane<'_, C>> = Vec::with_capacity(live);
    for (i, r) in runs.into_iter().enumerate() {
        let p0 = vehicle.pose(&r.x0).position;
        states[i] = r.x0;
        lanes.push(Lane {
            wants_truth: r.controller.needs_ground_truth(),
            controller: r.controller,
            sensor: r.sensor,
            oracles: r.oracles,
            metrics: Metrics::new(MetricsConfig {
                dt_s: plan.dt_s,
                steady_state_start_step: plan.steady_state_start_step,
                convergence_tolerance: plan.convergence_tolerance,
                convergence_min_dwell_steps: plan.convergence_min_dwell_steps,
                track_loss_band: plan.track_loss_band,
            }),
            samples: 0,
            ended: None,
            prev_pos: p0,
            last_valid_step: 0,
            end_pos: p0,
        });
    }
    let mut omega = [0.0; LANES];
    let mut px = [0.0; LANES];
    let mut py = [0.0; LANES];
    let mut k: u64 = 0;
    while lanes.iter().any(|l| l.ended.is_none()) {
        let t = k as f64 * plan.dt_s;
        for (i, s) in states.iter().enumerate() {
            let p = vehicle.position(s);
            (px[i], py[i]) = (p.x, p.y);
        }
        let values = field.value_lanes(t, &px, &py);
        // Steps 1-3 up to the controller, lane by lane; then every sampled law at once; then
        // the rest of step 3 and step 4, lane by lane; then step 5 for all lanes.
        let mut going = [None; LANES];
        let mut sampled = [false; LANES];
        let mut command = [None; LANES];
        let mut ms = [Measurement {
            t_s: 0.0,
            value: 0.0,
        }; LANES];
        for (i, lane) in lanes.iter_mut().enumerate() {
            if lane.ended.is_none() {
                going[i] = sense(lane, vehicle, &states[i], values[i], k, t).map(|(pose, m)| {
                    match m {
                        Some(m) if lane.wants_truth => {
                            command[i] = Some(ask_with_truth(
                                lane, vehicle, &states[i], pose, &m, values[i],
                            ));
                        }
                        Some(m) => {
                            ms[i] = m;
                            sampled[i] = true;
                        }
                        None => {}
                    }
                    pose
                });
            }
        }
        if sampled.iter().any(|&s| s) {
            let mut ctrls: [Option<&mut C>; LANES] = [const { None }; LANES];
            for (i, lane) in lanes.iter_mut().enumerate() {
                if sampled[i] {
                    ctrls[i] = Some(&mut lane.controller);
                }
            }
            let w = C::update_lanes(&mut ctrls, &ms);
            for i in 0..LANES {
                if sampled[i] {
                    command[i] = Some(w[i]);
                }
            }
        }
        for (i, lane) in lanes.iter_mut().enumerate() {
            if let Some(pose) = going[i] {
                complete(lane, pose, values[i], command[i], &mut omega[i], k, t, plan);
            }
        }
        vehicle.step_lanes(&mut states, &omega, plan.dt_s);
        k += 1;
    }
    lanes.into_iter().map(|l| finish(l, plan)).collect()
}

/// Steps 1-2 of step `k` for one live lane and the sensor's part of step 3, exactly as
/// [`Episode`](crate::Episode) does them: the pose and the sample, if any (`None`: the lane
/// has ended).
#[inline(always)]
fn sense<V: Vehicle, C>(
    lane: &mut Lane<'_, C>,
    vehicle: &V,
    state: &V::State,
    value: f64,
    k: u64,
    t: f64,
) -> Option<(Pose2, Option<Measurement>)> {
    let pose = vehicle.pose(state);
    if !pose.is_finite() {
        lane.ended = Some((
            Outcome::Diverged,
            Some(format!("non-finite vehicle state at t = {t} s")),
        ));
        return None;
    }
    if value.is_nan() {
        lane.ended = Some((
            Outcome::LeftField,
            Some(format!(
                "the field has no value at ({:.6}, {:.6}) m, t = {t} s",
                pose.position.x, pose.position.y
            )),
        ));
        return None;
    }
    if k > 0 {
        lane.metrics
            .add_path((pose.position - lane.prev_pos).norm());
    }
    lane.prev_pos = pose.position;
    let m = lane.sensor.observe(t, value);
    if m.is_some() {
        lane.samples += 1;
    }
    Some((pose, m))
}

/// A reference law's command, with the ground truth it asks for (as [`simulate`](crate::simulate)
/// gives it).
fn ask_with_truth<V: Vehicle, C: IsolineController>(
    lane: &mut Lane<'_, C>,
    vehicle: &V,
    state: &V::State,
    pose: Pose2,
    m: &Measurement,
    value: f64,
) -> f64 {
    let truth = GroundTruth {
        pose,
        speed_mps: vehicle.speed_mps(state),
        value,
        derivatives: lane.oracles.gradient.and_then(|g| g(m.t_s, pose.position)),
    };
    lane.controller.update_with_truth(m, &truth)
}

/// The rest of step 3 (a non-finite command ends the lane as `diverged`) and step 4, exactly
/// as [`Episode`](crate::Episode) does them.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn complete<C>(
    lane: &mut Lane<'_, C>,
    pose: Pose2,
    value: f64,
    command: Option<f64>,
    omega: &mut f64,
    k: u64,
    t: f64,
    plan: &StepPlan,
) {
    if let Some(w) = command {
        if !w.is_finite() {
            lane.ended = Some((
                Outcome::Diverged,
                Some(format!("non-finite turn-rate command at t = {t} s")),
            ));
            return;
        }
        *omega = w;
    }
    let eps = value - plan.level;
    lane.metrics.observe(k, eps, *omega);
    if let Some(dist) = lane.oracles.isoline_distance {
        if lane.metrics.in_window(k) {
            if let Some(d) = dist(t, pose.position) {
                lane.metrics.observe_isoline_distance(d);
            }
        }
    }
    lane.last_valid_step = k;
    lane.end_pos = pose.position;
    if k == plan.n_steps {
        lane.ended = Some((Outcome::Completed, None));
        return;
    }
    lane.metrics.integrate_command(*omega);
}

/// A lane's result: [`Episode::finish`](crate::Episode::finish) without a trace.
fn finish<C>(lane: Lane<'_, C>, plan: &StepPlan) -> RunResult {
    let (outcome, detail) = lane.ended.unwrap_or((Outcome::Completed, None));
    RunResult {
        outcome,
        outcome_detail: detail,
        t_end_s: lane.last_valid_step as f64 * plan.dt_s,
        steps: lane.last_valid_step,
        samples_dropped: lane.sensor.dropped(),
        samples: lane.samples,
        end_position_m: [lane.end_pos.x, lane.end_pos.y],
        metrics: lane.metrics.finish(outcome == Outcome::Completed),
    }
}
