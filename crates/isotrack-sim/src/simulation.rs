//! The simulation loop.

use crate::metrics::{Metrics, MetricsConfig, RunMetrics};
use crate::sensor::{whole_steps, Sensor, StepsError};
use crate::trace::{TraceRow, TraceSink};
use isotrack_core::control::GroundTruth;
use isotrack_core::{IsolineController, ScalarField, Vehicle};
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
    #[error("the duration {duration_s} s {reason} of {dt_s} s")]
    DurationNotMultiple {
        /// Duration, s.
        duration_s: f64,
        /// Step, s.
        dt_s: f64,
        /// What is wrong with it.
        reason: StepsError,
    },
    /// Recording period not a whole number (>= 1) of steps, or too many.
    #[error("the recording period 1/{rate_hz} s {reason} of {dt_s} s")]
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
/// [`GroundTruth`]: isotrack_core::control::GroundTruth
///
/// Generic over every part so the loop is monomorphised: no dynamic dispatch in the hot path.
#[allow(clippy::too_many_arguments)]
pub fn simulate<F, V, C, S>(
    field: &F,
    vehicle: &V,
    x0: V::State,
    controller: &mut C,
    sensor: &mut Sensor,
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
    let mut x = x0;
    let wants_truth = controller.needs_ground_truth();
    let mut metrics = Metrics::new(MetricsConfig {
        dt_s: plan.dt_s,
        steady_state_start_step: plan.steady_state_start_step,
        convergence_tolerance: plan.convergence_tolerance,
        convergence_min_dwell_steps: plan.convergence_min_dwell_steps,
        track_loss_band: plan.track_loss_band,
    });
    let mut omega = 0.0_f64;
    let mut s_measured: Option<f64> = None;
    let mut samples = 0u64;
    let mut outcome = Outcome::Completed;
    let mut detail = None;
    let mut last_row: Option<TraceRow> = None;
    let mut last_recorded_step: Option<u64> = None;
    let mut last_valid_step = 0u64;
    let mut prev_pos = vehicle.pose(&x).position;
    // Countdown to the next recorded step (not `k % record_every`: see `Sensor`).
    let mut record_countdown = 0u64;
    let mut end_pos = prev_pos;

    for k in 0..=plan.n_steps {
        let t = k as f64 * plan.dt_s;
        let pose = vehicle.pose(&x);
        if !pose.is_finite() {
            outcome = Outcome::Diverged;
            detail = Some(format!("non-finite vehicle state at t = {t} s"));
            break;
        }
        let Some(s) = field.value(t, pose.position) else {
            outcome = Outcome::LeftField;
            detail = Some(format!(
                "the field has no value at ({:.6}, {:.6}) m, t = {t} s",
                pose.position.x, pose.position.y
            ));
            if k == 0 && plan.record_every > 0 {
                // The start itself is off the field: the trace still shows where the vehicle
                // was (the field value and error unknown, NaN), so a plot can say why.
                let row = TraceRow {
                    t_s: t,
                    x_m: pose.position.x,
                    y_m: pose.position.y,
                    heading_rad: pose.heading_rad,
                    s: f64::NAN,
                    error: f64::NAN,
                    omega_radps: omega,
                    s_measured: None,
                    telemetry: vehicle.telemetry(&x),
                };
                sink.record(&row);
                last_recorded_step = Some(0);
            }
            break;
        };
        if k > 0 {
            metrics.add_path((pose.position - prev_pos).norm());
        }
        prev_pos = pose.position;
        if let Some(m) = sensor.observe(t, s) {
            samples += 1;
            s_measured = Some(m.value);
            let w = if wants_truth {
                let truth = GroundTruth {
                    pose,
                    speed_mps: vehicle.speed_mps(&x),
                    value: s,
                    derivatives: oracles.gradient.and_then(|g| g(t, pose.position)),
                };
                controller.update_with_truth(&m, &truth)
            } else {
                controller.update(&m)
            };
            if !w.is_finite() {
                outcome = Outcome::Diverged;
                detail = Some(format!("non-finite turn-rate command at t = {t} s"));
                break;
            }
            omega = w;
        }
        let eps = s - plan.level;
        metrics.observe(k, eps, omega);
        if let Some(dist) = oracles.isoline_distance {
            if metrics.in_window(k) {
                if let Some(d) = dist(t, pose.position) {
                    metrics.observe_isoline_distance(d);
                }
            }
        }
        last_valid_step = k;
        end_pos = pose.position;
        let row = TraceRow {
            t_s: t,
            x_m: pose.position.x,
            y_m: pose.position.y,
            heading_rad: pose.heading_rad,
            s,
            error: eps,
            omega_radps: omega,
            s_measured,
            telemetry: vehicle.telemetry(&x),
        };
        if plan.record_every > 0 {
            if record_countdown == 0 {
                sink.record(&row);
                last_recorded_step = Some(k);
                record_countdown = plan.record_every;
            }
            record_countdown -= 1;
        }
        last_row = Some(row);
        if k == plan.n_steps {
            break;
        }
        metrics.integrate_command(omega);
        vehicle.step(&mut x, omega, plan.dt_s);
    }
    // Always keep the last valid state in the trace.
    if plan.record_every > 0 && last_recorded_step != Some(last_valid_step) {
        if let Some(row) = last_row {
            sink.record(&row);
        }
    }
    RunResult {
        outcome,
        outcome_detail: detail,
        t_end_s: last_valid_step as f64 * plan.dt_s,
        steps: last_valid_step,
        samples_dropped: sensor.dropped(),
        samples,
        end_position_m: [end_pos.x, end_pos.y],
        metrics: metrics.finish(outcome == Outcome::Completed),
    }
}
