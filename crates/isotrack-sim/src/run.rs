//! What a run is given and what it gives back: the step plan, the oracles a reference
//! controller and the metrics may consult, a delivered sample, the outcome and the result.
//! Shared by the loop ([`crate::simulation`]), the step kernel and the batched lanes.

use crate::metrics::RunMetrics;
use crate::sensor::{whole_steps, StepsError};
use isotrack_core::math::Pose2;
use isotrack_core::numtext::Echo;
use isotrack_core::Measurement;
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

/// A delivered sample, at which an [`Episode`](crate::Episode) waits for its command.
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
