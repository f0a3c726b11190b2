//! The step kernel: one vehicle's run state ([`VehicleRun`]) and the one implementation of the
//! bookkeeping of a step (steps 1-4 of the crate's order, around the controller's answer),
//! the end-of-run rules and the result.
//!
//! The vehicle's state, the clock `k` and the field are not in it: whoever drives the runs owns
//! them and lends them to each call, and moves the vehicles (step 5) when
//! [`complete`](VehicleRun::complete) says so. [`Episode`](crate::Episode) drives one
//! (`simulate`, a traced run, an agent from outside); the batched loop drives
//! [`LANES`](crate::LANES) at once, the field and the vehicle step in SIMD lanes; a team of
//! vehicles sharing one clock and one field ([`Group`](crate::team::Group)) drives one per
//! vehicle the same way, the spacing law answering between sense and complete. So every
//! way to run gives each vehicle the same numbers, bit for bit, and ends it by the same rules.
//!
//! The controller is not in it either: between [`sense`](VehicleRun::sense) and
//! [`complete`](VehicleRun::complete) the driver asks it ([`ask`]: a controller in the loop, one
//! at a time or in lanes) or hands the sample out (an agent outside the loop).

use crate::metrics::{Metrics, MetricsConfig};
use crate::run::{GradientFn, Oracles, Outcome, RunResult, Sample, StepPlan};
use crate::sensor::Sensor;
use crate::trace::{TraceRow, TraceSink};
use isotrack_core::control::GroundTruth;
use isotrack_core::math::Pose2;
use isotrack_core::numtext::Num;
use isotrack_core::{IsolineController, Measurement, Vec2, Vehicle};

/// What [`VehicleRun::sense`] found: the run ended, or it goes on, the command held or to be
/// answered to a sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Sensed {
    /// The run has ended (see [`VehicleRun::outcome`]).
    Ended,
    /// No sample this step: the command is held.
    Held,
    /// The sensor delivered this measurement: the command is the answer to it.
    Sampled(Measurement),
}

/// One vehicle's run, all but its vehicle state: the plan (a copy), the sensor, the metrics, the
/// command held, the sample count, the end and, if `TRACE`, the trace's bookkeeping (a run
/// without it records nothing whatever its plan's `record_every`, and its steps carry no trace
/// code: the batched loop's lanes).
#[derive(Clone, Debug)]
pub(crate) struct VehicleRun<const TRACE: bool> {
    plan: StepPlan,
    sensor: Sensor,
    metrics: Metrics,
    /// The command held since the last sample, rad/s.
    omega: f64,
    /// The last measured value, for the trace (kept only if `TRACE`).
    s_measured: Option<f64>,
    samples: u64,
    /// How it ended, once it has.
    ended: Option<(Outcome, Option<String>)>,
    /// The pose at the last step sensed (finite; the start before any).
    pose: Pose2,
    /// The true field value there (finite).
    value: f64,
    last_valid_step: u64,
    /// Where the vehicle started.
    start: Vec2,
    end_pos: Vec2,
    last_row: Option<TraceRow>,
    last_recorded_step: Option<u64>,
    /// Countdown to the next recorded step (not `k % record_every`: see `Sensor`).
    record_countdown: u64,
}

impl<const TRACE: bool> VehicleRun<TRACE> {
    /// A run of `plan` behind `sensor` for a vehicle starting at `start`, at step 0.
    pub(crate) fn new(plan: &StepPlan, sensor: Sensor, start: Pose2) -> Self {
        let metrics = Metrics::new(MetricsConfig {
            dt_s: plan.dt_s,
            steady_state_start_step: plan.steady_state_start_step,
            convergence_tolerance: plan.convergence_tolerance,
            convergence_min_dwell_steps: plan.convergence_min_dwell_steps,
            track_loss_band: plan.track_loss_band,
        });
        Self {
            plan: *plan,
            sensor,
            metrics,
            omega: 0.0,
            s_measured: None,
            samples: 0,
            ended: None,
            pose: start,
            value: f64::NAN,
            last_valid_step: 0,
            start: start.position,
            end_pos: start.position,
            last_row: None,
            last_recorded_step: None,
            record_countdown: 0,
        }
    }

    /// Whether rows are recorded: a traced run whose plan has a recording period.
    #[inline(always)]
    fn records(&self) -> bool {
        TRACE && self.plan.record_every > 0
    }

    /// Steps 1-2 of step `k` (time `t_s`) and the sensor's part of step 3, for a vehicle in
    /// `state`: the pose (non-finite: the run ends as `diverged`), the true field value
    /// `value_at(position)` (not finite: the run ends as `left_field`), the path, the sample
    /// if the sensor delivers one. The pose and value stay the run's until its next step (for
    /// [`sample`](Self::sample) and [`complete`](Self::complete)).
    ///
    /// The one rule for the field's value: `None` from [`ScalarField::value`] is passed as NaN
    /// (as [`ScalarField::value_lanes`] gives it), and any value that is not finite (NaN, or
    /// infinite) is no value: the run ends there as `left_field`, alone or in lanes alike.
    ///
    /// [`ScalarField::value`]: isotrack_core::ScalarField::value
    /// [`ScalarField::value_lanes`]: isotrack_core::ScalarField::value_lanes
    #[inline(always)]
    pub(crate) fn sense<V, S>(
        &mut self,
        vehicle: &V,
        state: &V::State,
        k: u64,
        t_s: f64,
        value_at: impl FnOnce(Vec2) -> f64,
        sink: &mut S,
    ) -> Sensed
    where
        V: Vehicle,
        S: TraceSink + ?Sized,
    {
        let pose = vehicle.pose(state);
        if !pose.is_finite() {
            self.end(
                Outcome::Diverged,
                format!("non-finite vehicle state at t = {} s", Num(t_s)),
            );
            self.record_last(sink);
            return Sensed::Ended;
        }
        let value = value_at(pose.position);
        if !value.is_finite() {
            self.end(
                Outcome::LeftField,
                format!(
                    "the field has no value at ({:.6}, {:.6}) m, t = {} s",
                    pose.position.x,
                    pose.position.y,
                    Num(t_s)
                ),
            );
            if k == 0 && self.records() {
                // The start itself is off the field: the trace still shows where the vehicle
                // was (the field value and error unknown, NaN), so a plot can say why.
                sink.record(&TraceRow {
                    t_s,
                    x_m: pose.position.x,
                    y_m: pose.position.y,
                    heading_rad: pose.heading_rad,
                    s: f64::NAN,
                    error: f64::NAN,
                    omega_radps: self.omega,
                    s_measured: None,
                    telemetry: vehicle.telemetry(state),
                });
                self.last_recorded_step = Some(0);
            }
            self.record_last(sink);
            return Sensed::Ended;
        }
        if k > 0 {
            self.metrics
                .add_path((pose.position - self.pose.position).norm());
            let d = pose.position - self.start;
            self.metrics.observe_offset_sq(d.dot(d));
        }
        (self.pose, self.value) = (pose, value);
        match self.sensor.observe(t_s, value) {
            Some(m) => {
                self.samples += 1;
                if TRACE {
                    self.s_measured = Some(m.value);
                }
                Sensed::Sampled(m)
            }
            None => Sensed::Held,
        }
    }

    /// The sample a controller or an agent answers: `measurement` (from [`sense`](Self::sense))
    /// with the ground truth of the step sensed, the vehicle's speed `speed_mps` (m/s) included.
    #[inline(always)]
    pub(crate) fn sample(&self, measurement: Measurement, speed_mps: f64) -> Sample {
        Sample {
            measurement,
            pose: self.pose,
            speed_mps,
            true_value: self.value,
        }
    }

    /// The rest of step 3 and step 4 of step `k` (time `t_s`), after [`sense`](Self::sense) found
    /// the run going on: `command` is the answer to the step's sample (`None`: no sample, the
    /// command is held; a non-finite one ends the run as `diverged` and is never flown); then
    /// the metrics, the isoline distance (`oracles`), the trace (into `sink`), and the end as
    /// `completed` at the planned last step. Returns whether the vehicle moves on: step 5,
    /// `x_{k+1} = vehicle.step(x_k, omega, dt)` with [`omega_radps`](Self::omega_radps), is the
    /// caller's (one vehicle, or lanes at once).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn complete<V, S>(
        &mut self,
        command: Option<f64>,
        k: u64,
        t_s: f64,
        vehicle: &V,
        state: &V::State,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) -> bool
    where
        V: Vehicle,
        S: TraceSink + ?Sized,
    {
        let (pose, value) = (self.pose, self.value);
        if let Some(w) = command {
            if !w.is_finite() {
                self.end(
                    Outcome::Diverged,
                    format!("non-finite turn-rate command at t = {} s", Num(t_s)),
                );
                self.record_start(k, t_s, vehicle, state, sink);
                self.record_last(sink);
                return false;
            }
            self.omega = w;
        }
        let eps = value - self.plan.level;
        self.metrics.observe(k, eps, self.omega);
        if let Some(dist) = oracles.isoline_distance {
            if self.metrics.in_window(k) {
                if let Some(d) = dist(t_s, pose.position) {
                    self.metrics.observe_isoline_distance(d);
                }
            }
        }
        self.last_valid_step = k;
        self.end_pos = pose.position;
        if self.records() && !sink.keeps_rows() {
            // The recording schedule as below, into a sink that keeps nothing: no row built.
            if self.record_countdown == 0 {
                self.last_recorded_step = Some(k);
                self.record_countdown = self.plan.record_every;
            }
            self.record_countdown -= 1;
        } else if self.records() {
            // Only a recording run keeps its rows (the last valid one goes into the trace at the
            // end): without a trace, no row is built.
            let row = TraceRow {
                t_s,
                x_m: pose.position.x,
                y_m: pose.position.y,
                heading_rad: pose.heading_rad,
                s: value,
                error: eps,
                omega_radps: self.omega,
                s_measured: self.s_measured,
                telemetry: vehicle.telemetry(state),
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
            return false;
        }
        self.metrics.integrate_command(self.omega);
        true
    }

    /// A run that ends at its very first sample (a non-finite first command) still has its
    /// start in the trace: the vehicle where it was, the field value, the error, the command
    /// held before the sample (the non-finite one never flew), so that a trace is never empty.
    fn record_start<V, S>(&mut self, k: u64, t_s: f64, vehicle: &V, state: &V::State, sink: &mut S)
    where
        V: Vehicle,
        S: TraceSink + ?Sized,
    {
        if k != 0 || !self.records() || self.last_recorded_step.is_some() {
            return;
        }
        let (pose, value) = (self.pose, self.value);
        sink.record(&TraceRow {
            t_s,
            x_m: pose.position.x,
            y_m: pose.position.y,
            heading_rad: pose.heading_rad,
            s: value,
            error: value - self.plan.level,
            omega_radps: self.omega,
            s_measured: self.s_measured,
            telemetry: vehicle.telemetry(state),
        });
        self.last_recorded_step = Some(0);
    }

    /// The last valid state into the trace, if the recording schedule left it out: at the
    /// step a run ends early (`left_field`, `diverged`), so that a team's trace, whose vehicles
    /// share one file, stays in time order (issue 32, att32d-14: the row once went in at the
    /// team's end, after every later row), and at [`finish`](Self::finish).
    fn record_last<S: TraceSink + ?Sized>(&mut self, sink: &mut S) {
        if self.records() && self.last_recorded_step != Some(self.last_valid_step) {
            if let Some(row) = &self.last_row {
                sink.record(row);
                self.last_recorded_step = Some(self.last_valid_step);
            }
        }
    }

    fn end(&mut self, outcome: Outcome, detail: String) {
        self.ended = Some((outcome, Some(detail)));
    }

    /// Whether the run goes on (it has not ended).
    #[inline(always)]
    pub(crate) fn is_running(&self) -> bool {
        self.ended.is_none()
    }

    /// How the run ended, once it has (`None` while it runs).
    pub(crate) fn outcome(&self) -> Option<Outcome> {
        self.ended.as_ref().map(|(o, _)| *o)
    }

    /// The command being held, rad/s.
    #[inline(always)]
    pub(crate) fn omega_radps(&self) -> f64 {
        self.omega
    }

    /// The plan.
    #[inline(always)]
    pub(crate) fn plan(&self) -> &StepPlan {
        &self.plan
    }

    /// Ends the run (a run still going ends as it stands, as `completed` would at its end) and
    /// returns its result; the last valid state is always in the trace.
    pub(crate) fn finish<S: TraceSink + ?Sized>(mut self, sink: &mut S) -> RunResult {
        self.record_last(sink);
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

/// The command `controller` answers `sample` with: its `update` of the measurement, or, for a
/// reference law that asks for it (`wants_truth`, its `needs_ground_truth()`),
/// `update_with_truth` with the true pose, speed and value and, from `gradient`, the field's
/// derivatives there.
#[inline(always)]
pub(crate) fn ask<C: IsolineController + ?Sized>(
    controller: &mut C,
    wants_truth: bool,
    sample: &Sample,
    gradient: Option<GradientFn<'_>>,
) -> f64 {
    if wants_truth {
        let truth = GroundTruth {
            pose: sample.pose,
            speed_mps: sample.speed_mps,
            value: sample.true_value,
            derivatives: gradient.and_then(|g| g(sample.measurement.t_s, sample.pose.position)),
        };
        controller.update_with_truth(&sample.measurement, &truth)
    } else {
        controller.update(&sample.measurement)
    }
}
