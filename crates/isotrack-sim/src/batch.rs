//! Batched runs: up to [`LANES`] runs that share the field, the vehicle model and the plan are
//! stepped together, structure of arrays, so that the field's formula and the vehicle's step
//! run in SIMD lanes (the `*_lanes` methods of [`ScalarField`] and [`Vehicle`]) while each run
//! keeps its own start, sensor, controller and metrics. A run that ends early is masked: its
//! lane is still computed (that costs nothing in a vector) but never read again.
//!
//! Every run's result is the one [`simulate`](crate::simulate) gives it alone, bit for bit:
//! the step order is the same, the per-run bookkeeping is the same code (the step kernel,
//! `kernel::VehicleRun`, which [`Episode`](crate::Episode) runs for one vehicle) and the
//! arithmetic is the same (the lane functions are the scalar ones, see `isotrack_core::lanes`),
//! which the tests check run by run. So a sweep's results do not depend on how its runs are
//! grouped, on the thread count or on the shard split. Traces are not recorded (a batch serves
//! sweeps, which keep summaries).
//!
//! The loop is compiled for AVX-512 and AVX2 besides the baseline, and picks one at run time
//! (`multiversion`); all give the same numbers (no fused multiply-add is used).

use crate::kernel::{ask, Sensed, VehicleRun};
use crate::run::{Oracles, RunResult, StepPlan};
use crate::sensor::Sensor;
use crate::trace::NoTrace;
use isotrack_core::{IsolineController, Measurement, ScalarField, Vehicle};

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

/// One lane: its run's state in the step kernel, and the controller that answers its samples.
struct Lane<'a, C> {
    run: VehicleRun<false>,
    controller: C,
    wants_truth: bool,
    oracles: Oracles<'a>,
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
    let Some(first) = runs.first() else {
        return vec![];
    };
    let mut states: [V::State; LANES] = core::array::from_fn(|_| first.x0.clone());
    let mut lanes: Vec<Lane<'_, C>> = Vec::with_capacity(runs.len());
    for (i, r) in runs.into_iter().enumerate() {
        lanes.push(Lane {
            run: VehicleRun::new(plan, r.sensor, vehicle.pose(&r.x0)),
            wants_truth: r.controller.needs_ground_truth(),
            controller: r.controller,
            oracles: r.oracles,
        });
        states[i] = r.x0;
    }
    let mut omega = [0.0; LANES];
    let mut px = [0.0; LANES];
    let mut py = [0.0; LANES];
    let mut k: u64 = 0;
    while lanes.iter().any(|l| l.run.is_running()) {
        let t = k as f64 * plan.dt_s;
        for (i, s) in states.iter().enumerate() {
            let p = vehicle.position(s);
            (px[i], py[i]) = (p.x, p.y);
        }
        let values = field.value_lanes(t, &px, &py);
        // Steps 1-3 up to the controller, lane by lane; then every sampled law at once; then
        // the rest of step 3 and step 4, lane by lane; then step 5 for all lanes.
        let mut step = sense_lanes(&mut lanes, vehicle, &states, k, t, &values);
        if step.sampled.iter().any(|&s| s) {
            update_sampled_lanes(&mut lanes, &mut step);
        }
        for (i, lane) in lanes.iter_mut().enumerate() {
            if step.going[i] {
                let (run, oracles) = (&mut lane.run, &lane.oracles);
                run.complete(
                    step.command[i],
                    k,
                    t,
                    vehicle,
                    &states[i],
                    oracles,
                    &mut NoTrace,
                );
                omega[i] = run.omega_radps();
            }
        }
        vehicle.step_lanes(&mut states, &omega, plan.dt_s);
        k += 1;
    }
    lanes
        .into_iter()
        .map(|l| l.run.finish(&mut NoTrace))
        .collect()
}

/// One step of the lanes between sensing and completing it.
struct LaneStep {
    /// The lanes still running after sensing (the others ended or were never live).
    going: [bool; LANES],
    /// The lanes whose sampled law answers at once ([`IsolineController::update_lanes`]).
    sampled: [bool; LANES],
    /// Each going lane's command, once its law answered (`None`: held).
    command: [Option<f64>; LANES],
    /// The samples of the `sampled` lanes.
    ms: [Measurement; LANES],
}

/// Steps 1-3 of step `k` (time `t`, the field's `values` at the lanes' positions) up to the
/// controller, lane by lane ([`VehicleRun::sense`]): a law that needs ground truth is asked
/// at once ([`ask`], with its oracles' gradient), a sample for any other law is kept for
/// [`update_sampled_lanes`].
#[inline(always)]
fn sense_lanes<V, C>(
    lanes: &mut [Lane<'_, C>],
    vehicle: &V,
    states: &[V::State; LANES],
    k: u64,
    t: f64,
    values: &[f64; LANES],
) -> LaneStep
where
    V: Vehicle,
    C: IsolineController,
{
    let mut step = LaneStep {
        going: [false; LANES],
        sampled: [false; LANES],
        command: [None; LANES],
        ms: [Measurement {
            t_s: 0.0,
            value: 0.0,
        }; LANES],
    };
    for (i, lane) in lanes.iter_mut().enumerate() {
        if !lane.run.is_running() {
            continue;
        }
        let value_at = |_| values[i];
        match lane
            .run
            .sense(vehicle, &states[i], k, t, value_at, &mut NoTrace)
        {
            Sensed::Ended => continue,
            Sensed::Held => {}
            Sensed::Sampled(m) if lane.wants_truth => {
                let sample = lane.run.sample(m, vehicle.speed_mps(&states[i]));
                let gradient = lane.oracles.gradient;
                step.command[i] = Some(ask(&mut lane.controller, true, &sample, gradient));
            }
            Sensed::Sampled(m) => {
                step.ms[i] = m;
                step.sampled[i] = true;
            }
        }
        step.going[i] = true;
    }
    step
}

/// Every sampled law of the step answers at once ([`IsolineController::update_lanes`] over
/// the `sampled` lanes' controllers and samples): their commands.
#[inline(always)]
fn update_sampled_lanes<C: IsolineController>(lanes: &mut [Lane<'_, C>], step: &mut LaneStep) {
    let mut ctrls: [Option<&mut C>; LANES] = [const { None }; LANES];
    for (i, lane) in lanes.iter_mut().enumerate() {
        if step.sampled[i] {
            ctrls[i] = Some(&mut lane.controller);
        }
    }
    let w = C::update_lanes(&mut ctrls, &step.ms);
    for (i, w) in w.iter().enumerate() {
        if step.sampled[i] {
            step.command[i] = Some(*w);
        }
    }
}
