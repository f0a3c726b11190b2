//! The simulation loop.

use crate::metrics::{Metrics, MetricsConfig, RunMetrics};
use crate::sensor::{whole_steps, Sensor, StepsError};
use crate::trace::{TraceRow, TraceSink};
use isotrack_core::control::GroundTruth;
use isotrack_core::math::Pose2;
use isotrack_core::numtext::Echo;
use isotrack_core::{IsolineController, Measurement, ScalarField, Vec2, Vehicle};
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
        if wants_truth {
            let truth = GroundTruth {
                pose: sample.pose,
                speed_mps: sample.speed_mps,
                value: sample.true_value,
                derivatives: oracles
                    .gradient
                    .and_then(|g| g(sample.measurement.t_s, sample.pose.position)),
            };
            controller.update_with_truth(&sample.measurement, &truth)
        } else {
            controller.update(&sample.measurement)
        }
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
/// The episode owns its state; the field, vehicle and oracles are lent to each call, so that one
/// shared field serves many episodes.
#[derive(Clone, Debug)]
pub struct Episode<X> {
    x: X,
    sensor: Sensor,
    plan: StepPlan,
    metrics: Metrics,
    /// The current step.
    k: u64,
    omega: f64,
    s_measured: Option<f64>,
    samples: u64,
    /// How it ended, once it has.
    ended: Option<(Outcome, Option<String>)>,
    /// The sample step waiting for its command: `(t, pose, s)`.
    pending: Option<(f64, Pose2, f64)>,
    last_row: Option<TraceRow>,
    last_recorded_step: Option<u64>,
    last_valid_step: u64,
    prev_pos: Vec2,
    /// Countdown to the next recorded step (not `k % record_every`: see `Sensor`).
    record_countdown: u64,
    end_pos: Vec2,
}

impl<X: Clone> Episode<X> {
    /// An episode of `plan` for `vehicle` from `x0`, behind `sensor`, at step 0 (nothing run).
    pub fn new<V: Vehicle<State = X>>(vehicle: &V, x0: X, sensor: Sensor, plan: &StepPlan) -> Self {
        let metrics = Metrics::new(MetricsConfig {
            dt_s: plan.dt_s,
            steady_state_start_step: plan.steady_state_start_step,
            convergence_tolerance: plan.convergence_tolerance,
            convergence_min_dwell_steps: plan.convergence_min_dwell_steps,
            track_loss_band: plan.track_loss_band,
        });
        let p0 = vehicle.pose(&x0).position;
        Self {
            x: x0,
            sensor,
            plan: *plan,
            metrics,
            k: 0,
            omega: 0.0,
            s_measured: None,
            samples: 0,
            ended: None,
            pending: None,
            last_row: None,
            last_recorded_step: None,
            last_valid_step: 0,
            prev_pos: p0,
            record_countdown: 0,
            end_pos: p0,
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
        if let Some((t, pose, s)) = self.pending {
            return Some(Sample {
                measurement: Measurement {
                    t_s: t,
                    value: self.s_measured.unwrap_or(f64::NAN),
                },
                pose,
                speed_mps: vehicle.speed_mps(&self.x),
                true_value: s,
            });
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
        while self.ended.is_none() {
            let k = self.k;
            let t = k as f64 * self.plan.dt_s;
            let pose = vehicle.pose(&self.x);
            if !pose.is_finite() {
                self.end(
                    Outcome::Diverged,
                    format!("non-finite vehicle state at t = {t} s"),
                );
                break;
            }
            let Some(s) = field.value(t, pose.position) else {
                self.end(
                    Outcome::LeftField,
                    format!(
                        "the field has no value at ({:.6}, {:.6}) m, t = {t} s",
                        pose.position.x, pose.position.y
                    ),
                );
                if k == 0 && self.plan.record_every > 0 {
                    // The start itself is off the field: the trace still shows where the vehicle
                    // was (the field value and error unknown, NaN), so a plot can say why.
                    sink.record(&TraceRow {
                        t_s: t,
                        x_m: pose.position.x,
                        y_m: pose.position.y,
                        heading_rad: pose.heading_rad,
                        s: f64::NAN,
                        error: f64::NAN,
                        omega_radps: self.omega,
                        s_measured: None,
                        telemetry: vehicle.telemetry(&self.x),
                    });
                    self.last_recorded_step = Some(0);
                }
                break;
            };
            if k > 0 {
                self.metrics
                    .add_path((pose.position - self.prev_pos).norm());
            }
            self.prev_pos = pose.position;
            if let Some(m) = self.sensor.observe(t, s) {
                self.samples += 1;
                self.s_measured = Some(m.value);
                let sample = Sample {
                    measurement: m,
                    pose,
                    speed_mps: vehicle.speed_mps(&self.x),
                    true_value: s,
                };
                match answer(&sample) {
                    None => {
                        self.pending = Some((t, pose, s));
                        return Some(sample);
                    }
                    Some(w) if !w.is_finite() => {
                        self.end(
                            Outcome::Diverged,
                            format!("non-finite turn-rate command at t = {t} s"),
                        );
                        self.record_start(t, pose, s, vehicle, sink);
                        break;
                    }
                    Some(w) => self.omega = w,
                }
            }
            self.complete_step(t, pose, s, vehicle, oracles, sink);
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
        let Some((t, pose, s)) = self.pending.take() else {
            return;
        };
        if !omega_radps.is_finite() {
            self.end(
                Outcome::Diverged,
                format!("non-finite turn-rate command at t = {t} s"),
            );
            self.record_start(t, pose, s, vehicle, sink);
            return;
        }
        self.omega = omega_radps;
        self.complete_step(t, pose, s, vehicle, oracles, sink);
    }

    /// Steps 4-5 of step `k`: metrics, trace, and the vehicle's move (none past the last step).
    #[inline(always)]
    fn complete_step<V, S>(
        &mut self,
        t: f64,
        pose: Pose2,
        s: f64,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) where
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        let k = self.k;
        let eps = s - self.plan.level;
        self.metrics.observe(k, eps, self.omega);
        if let Some(dist) = oracles.isoline_distance {
            if self.metrics.in_window(k) {
                if let Some(d) = dist(t, pose.position) {
                    self.metrics.observe_isoline_distance(d);
                }
            }
        }
        self.last_valid_step = k;
        self.end_pos = pose.position;
        if self.plan.record_every > 0 {
            // Only a recording run keeps its rows (the last valid one goes into the trace at the
            // end): without a trace, no row is built.
            let row = TraceRow {
                t_s: t,
                x_m: pose.position.x,
                y_m: pose.position.y,
                heading_rad: pose.heading_rad,
                s,
                error: eps,
                omega_radps: self.omega,
                s_measured: self.s_measured,
                telemetry: vehicle.telemetry(&self.x),
            };
            if self.record_countdown == 0 {
                sink.record(&row);
                self.last_recorded_step = Some(k);
                self.record_countdown = self.plan.record_every;
            }
            self.record_countdown -= 1;
            self.last_row = Some(row);
        }
        if k == self.plan.n_steps {
            self.ended = Some((Outcome::Completed, None));
            return;
        }
        self.metrics.integrate_command(self.omega);
        vehicle.step(&mut self.x, self.omega, self.plan.dt_s);
        self.k += 1;
    }

    /// A run that ends at its very first sample (a non-finite first command) still has its
    /// start in the trace: the vehicle where it was, the field value, the error, the command
    /// held before the sample (the non-finite one never flew), so that a trace is never empty.
    fn record_start<V, S>(&mut self, t: f64, pose: Pose2, s: f64, vehicle: &V, sink: &mut S)
    where
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if self.k != 0 || self.plan.record_every == 0 || self.last_recorded_step.is_some() {
            return;
        }
        sink.record(&TraceRow {
            t_s: t,
            x_m: pose.position.x,
            y_m: pose.position.y,
            heading_rad: pose.heading_rad,
            s,
            error: s - self.plan.level,
            omega_radps: self.omega,
            s_measured: self.s_measured,
            telemetry: vehicle.telemetry(&self.x),
        });
        self.last_recorded_step = Some(0);
    }

    fn end(&mut self, outcome: Outcome, detail: String) {
        self.ended = Some((outcome, Some(detail)));
        self.pending = None;
    }

    /// How the run ended, once it has (`None` while it runs).
    pub fn outcome(&self) -> Option<Outcome> {
        self.ended.as_ref().map(|(o, _)| *o)
    }

    /// Time of the current step, s.
    pub fn t_s(&self) -> f64 {
        self.k as f64 * self.plan.dt_s
    }

    /// The vehicle's state.
    pub fn state(&self) -> &X {
        &self.x
    }

    /// The command being held, rad/s.
    pub fn omega_radps(&self) -> f64 {
        self.omega
    }

    /// Ends the episode (a run still going ends as it stands, as `completed` would at its end)
    /// and returns its result; the last valid state is always in the trace.
    pub fn finish<S: TraceSink + ?Sized>(self, sink: &mut S) -> RunResult {
        if self.plan.record_every > 0 && self.last_recorded_step != Some(self.last_valid_step) {
            if let Some(row) = &self.last_row {
                sink.record(row);
            }
        }
        let (outcome, detail) = self.ended.unwrap_or((Outcome::Completed, None));
        RunResult {
            outcome,
            outcome_detail: detail,
            t_end_s: self.last_valid_step as f64 * self.plan.dt_s,
            steps: self.last_valid_step,
            samples_dropped: self.sensor.dropped(),
            samples: self.samples,
            end_position_m: [self.end_pos.x, self.end_pos.y],
            metrics: self.metrics.finish(outcome == Outcome::Completed),
        }
    }
}
