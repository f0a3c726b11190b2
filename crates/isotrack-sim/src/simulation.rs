//! The simulation loop.

use crate::kernel::{ask, Sensed, VehicleRun};
use crate::metrics::RunMetrics;
use crate::sensor::{whole_steps, Sensor, StepsError};
use crate::trace::TraceSink;
use isotrack_core::math::Pose2;
use isotrack_core::numtext::Echo;
use isotrack_core::{IsolineController, Measurement, ScalarField, Vehicle};
use serde::Serialize;

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The run reached its planned duration.
    Completed,
    /// The state or the command became non-finite.
    Diverged,
    /// The vehicle reached a point where the field has no value (domain edge, no-data cell).
    LeftField,
}

impl Outcome {
    /// The snake_case name used in `summary.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            Outcome::Completed => "completed",
            Outcome::Diverged => "diverged",
            Outcome::LeftField => "left_field",
        }
    }
}

/// Step counts of a run, from its durations in seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepPlan {
    /// Step, s.
    pub dt_s: f64,
    /// Number of steps (the run covers `[0, n_steps*dt]`).
    pub n_steps: u64,
    /// Record a trace row every this many steps (0: no trace).
    pub record_every: u64,
    /// First step of the steady-state window.
    pub steady_state_start_step: u64,
    /// Convergence tolerance on `|eps|`.
    pub convergence_tolerance: f64,
    /// Steps the error must stay within the tolerance, to the end, to count as converged.
    pub convergence_min_dwell_steps: u64,
    /// The level `s_d` the error is measured from.
    pub level: f64,
    /// The track-loss band on `|eps|` (default 5 x the tolerance; see
    /// [`StepPlan::with_track_loss_band`]).
    pub track_loss_band: f64,
}

/// Why durations do not make a [`StepPlan`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepPlanError {
    /// Duration not a whole number of steps, or too many.
    #[error("the duration {} s {reason} of {} s", Echo(*.duration_s), Echo(*.dt_s))]
    DurationNotMultiple {
        /// Duration, s.
        duration_s: f64,
        /// Step, s.
        dt_s: f64,
        /// What is wrong with it.
        reason: StepsError,
    },
    /// Recording period not a whole number (>= 1) of steps, or too many.
    #[error("the recording period 1/{} s {reason} of {} s", Echo(*.rate_hz), Echo(*.dt_s))]
    RecordRateNotMultiple {
        /// Rate, Hz.
        rate_hz: f64,
        /// Step, s.
        dt_s: f64,
        /// What is wrong with it.
        reason: StepsError,
    },
}

impl StepPlan {
    /// Builds the plan: `record_rate_hz = 0` turns the trace off; the steady-state window is the
    /// last `steady_state_fraction` of the planned duration; a convergence time needs the error
    /// to stay within `convergence_tolerance` for `convergence_min_dwell_s` (rounded up to whole
    /// steps) up to the end.
    pub fn new(
        dt_s: f64,
        duration_s: f64,
        record_rate_hz: f64,
        steady_state_fraction: f64,
        convergence_tolerance: f64,
        convergence_min_dwell_s: f64,
        level: f64,
    ) -> Result<Self, StepPlanError> {
        let n_steps =
            whole_steps(duration_s, dt_s).map_err(|reason| StepPlanError::DurationNotMultiple {
                duration_s,
                dt_s,
                reason,
            })?;
        let record_every = if record_rate_hz == 0.0 {
            0
        } else {
            whole_steps(1.0 / record_rate_hz, dt_s)
                .and_then(|n| {
                    if n >= 1 {
                        Ok(n)
                    } else {
                        Err(StepsError::NotWhole)
                    }
                })
                .map_err(|reason| StepPlanError::RecordRateNotMultiple {
                    rate_hz: record_rate_hz,
                    dt_s,
                    reason,
                })?
        };
        let ss = ((1.0 - steady_state_fraction) * n_steps as f64).ceil() as u64;
        Ok(Self {
            dt_s,
            n_steps,
            record_every,
            steady_state_start_step: ss.min(n_steps),
            convergence_tolerance,
            convergence_min_dwell_steps: ((convergence_min_dwell_s / dt_s).ceil().max(0.0) as u64)
                .min(n_steps),
            level,
            track_loss_band: 5.0 * convergence_tolerance,
        })
    }

    /// The plan with another track-loss band (>= the tolerance).
    pub fn with_track_loss_band(mut self, band: f64) -> Self {
        self.track_loss_band = band.max(self.convergence_tolerance);
        self
    }
}

/// What a run produced.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunResult {
    /// How it ended.
    pub outcome: Outcome,
    /// A sentence on why, for non-`completed` outcomes.
    pub outcome_detail: Option<String>,
    /// Time of the last valid step, s.
    pub t_end_s: f64,
    /// Steps integrated.
    pub steps: u64,
    /// Measurements delivered to the controller.
    pub samples: u64,
    /// Samples the sensor lost to dropouts (`sensor.dropout_probability`); the controller held
    /// its last command through each.
    pub samples_dropped: u64,
    /// Last valid position `[x, y]`, m.
    pub end_position_m: [f64; 2],
    /// The metrics.
    #[serde(flatten)]
    pub metrics: RunMetrics,
}

/// Distance from a point to the true isoline at time `t_s` (s), m (`None` where unknown). Used
/// for metrics only.
pub type IsolineDistanceFn<'a> = &'a (dyn Fn(f64, isotrack_core::Vec2) -> Option<f64> + Sync);

/// The true field gradient and Hessian at `(t, p)`, for reference controllers only.
pub type GradientFn<'a> = &'a (dyn Fn(f64, isotrack_core::Vec2) -> Option<(isotrack_core::Vec2, isotrack_core::math::Mat2)>
         + Sync);

/// Ground-truth oracles the loop may consult: never for a coordinate-free controller.
#[derive(Clone, Copy, Default)]
pub struct Oracles<'a> {
    /// For the isoline-distance metrics (evaluated in the steady-state window).
    pub isoline_distance: Option<IsolineDistanceFn<'a>>,
    /// For controllers whose `needs_ground_truth()` is true.
    pub gradient: Option<GradientFn<'a>>,
}

/// Runs one simulation: `field`, `vehicle` from `x0`, `controller` behind `sensor`, for
/// `plan.n_steps` steps, recording into `sink`. See the crate documentation for the order of a step.
/// `oracles.isoline_distance`, if given, is evaluated at every step of the steady-state window for
/// the isoline-distance metrics; `oracles.gradient` feeds [`GroundTruth`] to a reference
/// controller that asks for it (`needs_ground_truth`), and no other.
///
/// This is [`Episode`] driven by `controller`: the loop pauses at each delivered sample and the
/// controller's answer is the command held until the next one.
///
/// Generic over every part so the loop is monomorphised: no dynamic dispatch in the hot path.
///
/// [`GroundTruth`]: isotrack_core::control::GroundTruth
#[allow(clippy::too_many_arguments)]
pub fn simulate<F, V, C, S>(
    field: &F,
    vehicle: &V,
    x0: V::State,
    controller: &mut C,
    sensor: Sensor,
    plan: &StepPlan,
    oracles: &Oracles<'_>,
    sink: &mut S,
) -> RunResult
where
    F: ScalarField + ?Sized,
    V: Vehicle,
    C: IsolineController + ?Sized,
    S: TraceSink + ?Sized,
{
    let wants_truth = controller.needs_ground_truth();
    let mut episode = Episode::new(vehicle, x0, sensor, plan);
    episode.drive(field, vehicle, oracles, sink, |sample| {
        ask(controller, wants_truth, sample, oracles.gradient)
    });
    episode.finish(sink)
}

/// A delivered sample, at which an [`Episode`] waits for its command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// What the controller sees: the sample time and measured value.
    pub measurement: Measurement,
    /// The true pose at the sample step (ground truth: never for a coordinate-free law).
    pub pose: Pose2,
    /// The true ground speed, m/s (ground truth).
    pub speed_mps: f64,
    /// The true, noise-free field value at the pose (ground truth).
    pub true_value: f64,
}

/// One run of the loop, paused at each delivered sample for the command to hold until the next
/// one: the form [`simulate`] drives with a controller, and an external agent (a reinforcement
/// learning environment, say) drives one command at a time. The step order is the crate's:
/// [`run_to_sample`](Self::run_to_sample) performs steps 1-2 (and 3-5 of the steps without a
/// sample) up to the next sample; [`command`](Self::command) completes that step (3-5).
///
/// The episode owns the vehicle's state and the clock; the bookkeeping of each step is the
/// step kernel's (`kernel::VehicleRun`, the same the batched loop runs in lanes). The field,
/// vehicle and oracles are lent to each call, so that one shared field serves many episodes.
#[derive(Clone, Debug)]
pub struct Episode<X> {
    x: X,
    /// The current step.
    k: u64,
    run: VehicleRun<true>,
    /// The sample waiting for its command.
    pending: Option<Sample>,
}

impl<X: Clone> Episode<X> {
    /// An episode of `plan` for `vehicle` from `x0`, behind `sensor`, at step 0 (nothing run).
    pub fn new<V: Vehicle<State = X>>(vehicle: &V, x0: X, sensor: Sensor, plan: &StepPlan) -> Self {
        let run = VehicleRun::new(plan, sensor, vehicle.pose(&x0));
        Self {
            x: x0,
            k: 0,
            run,
            pending: None,
        }
    }

    /// Steps until the sensor delivers a sample (returned; the episode then waits for
    /// [`command`](Self::command)) or the run ends (`None`; see [`outcome`](Self::outcome)).
    /// Called while a sample waits, it returns that sample again.
    pub fn run_to_sample<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) -> Option<Sample>
    where
        F: ScalarField + ?Sized,
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if let Some(sample) = self.pending {
            return Some(sample);
        }
        self.advance(field, vehicle, oracles, sink, |_| None)
    }

    /// Runs the episode to its end, answering every sample with `controller(sample)`: what
    /// [`simulate`] does. (One loop with the answer inlined, not `run_to_sample` and `command`
    /// in turn: pausing at every sample costs the 100 Hz loop about a tenth of its speed.)
    #[inline]
    pub fn drive<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
        mut controller: impl FnMut(&Sample) -> f64,
    ) where
        F: ScalarField + ?Sized,
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if let Some(sample) = self.run_to_sample(field, vehicle, oracles, sink) {
            let w = controller(&sample);
            self.command(w, vehicle, oracles, sink);
        }
        self.advance(field, vehicle, oracles, sink, |s| Some(controller(s)));
    }

    /// The loop: steps until `answer` returns `None` for a delivered sample (which then waits,
    /// and is returned) or the run ends (`None`). `answer` returning `Some(omega)` commands the
    /// sample and goes on.
    #[inline(always)]
    fn advance<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
        mut answer: impl FnMut(&Sample) -> Option<f64>,
    ) -> Option<Sample>
    where
        F: ScalarField + ?Sized,
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        while self.run.is_running() {
            let k = self.k;
            let t = k as f64 * self.run.plan().dt_s;
            let value_at = |p| field.value(t, p).unwrap_or(f64::NAN);
            let command = match self.run.sense(vehicle, &self.x, k, t, value_at, sink) {
                Sensed::Ended => break,
                Sensed::Held => None,
                Sensed::Sampled(m) => {
                    let sample = self.run.sample(m, vehicle.speed_mps(&self.x));
                    let command = answer(&sample);
                    if command.is_none() {
                        self.pending = Some(sample);
                        return Some(sample);
                    }
                    command
                }
            };
            self.complete(command, t, vehicle, oracles, sink);
        }
        None
    }

    /// Answers the waiting sample with the turn-rate command `omega_radps` (held until the next
    /// sample) and completes its step. A non-finite command ends the run as `diverged`. Without a
    /// waiting sample it does nothing.
    #[inline]
    pub fn command<V, S>(
        &mut self,
        omega_radps: f64,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) where
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if self.pending.take().is_some() {
            let t = self.t_s();
            self.complete(Some(omega_radps), t, vehicle, oracles, sink);
        }
    }

    /// The kernel's rest of the current step (time `t_s`), then step 5: the vehicle's move (none
    /// once the run ends).
    #[inline(always)]
    fn complete<V, S>(
        &mut self,
        command: Option<f64>,
        t_s: f64,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) where
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        let k = self.k;
        if self
            .run
            .complete(command, k, t_s, vehicle, &self.x, oracles, sink)
        {
            vehicle.step(&mut self.x, self.run.omega_radps(), self.run.plan().dt_s);
            self.k += 1;
        }
    }

    /// How the run ended, once it has (`None` while it runs).
    pub fn outcome(&self) -> Option<Outcome> {
        self.run.outcome()
    }

    /// Time of the current step, s.
    pub fn t_s(&self) -> f64 {
        self.k as f64 * self.run.plan().dt_s
    }

    /// The vehicle's state.
    pub fn state(&self) -> &X {
        &self.x
    }

    /// The command being held, rad/s.
    pub fn omega_radps(&self) -> f64 {
        self.run.omega_radps()
    }

    /// Ends the episode (a run still going ends as it stands, as `completed` would at its end)
    /// and returns its result; the last valid state is always in the trace.
    pub fn finish<S: TraceSink + ?Sized>(self, sink: &mut S) -> RunResult {
        self.run.finish(sink)
    }
}
