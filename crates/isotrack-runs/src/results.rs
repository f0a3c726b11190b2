//! A run's result as every results file records it: [`RunRecord`] (the outcome and metrics of
//! one run, numbers `None` where undefined or not finite) and the one row builder,
//! [`result_cells`], over named [`Column`]s. `summary.json` flattens the record ([`crate::summary`]),
//! a sweep's `results.csv` ([`crate::sweep::rows`]), `isotrack compare`'s `comparison.csv` and the
//! benchmark's per-task `results.csv` (`isotrack-league`) take their cells from it.

use crate::trace::num;
use isotrack_sim::{RunMetrics, RunResult};
use serde::{Deserialize, Serialize};

/// The outcome a results row records for a run whose scenario is invalid (the reason in
/// `outcome_detail`).
pub const INVALID_SCENARIO: &str = "invalid_scenario";

/// One run's outcome and metrics, in `summary.json`'s order and with its names (those of
/// [`RunResult`] and [`isotrack_sim::RunMetrics`]). A number that is undefined or not finite is
/// `None` (`null` in JSON, an empty CSV cell).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// `completed`, `left_field`, `diverged` (`interrupted`, `companion_lost`: a cut `sitl`
    /// run).
    pub outcome: String,
    /// A sentence on why, for non-`completed` outcomes.
    pub outcome_detail: Option<String>,
    /// Time of the last valid step, s.
    pub t_end_s: Option<f64>,
    /// Steps integrated.
    pub steps: u64,
    /// Measurements delivered to the controller.
    pub samples: u64,
    /// Samples lost to dropouts (0 when read from an older isotrack's summary, written before
    /// the sensor had dropouts, att41-14).
    #[serde(default)]
    pub samples_dropped: u64,
    /// Last valid position `[x, y]`, m.
    pub end_position_m: [Option<f64>; 2],
    /// The metrics ([`MetricsRecord`], flattened).
    #[serde(flatten)]
    pub metrics: MetricsRecord,
}

/// A run's tracking metrics as every results file records them, in `summary.json`'s order and
/// with the names of [`isotrack_sim::RunMetrics`]; a number that is undefined or not finite is
/// `None`. A simulated run's [`RunRecord`] and a flight's record
/// ([`crate::summary::FlightRecord`]: the metrics of the measured error series) both hold one.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MetricsRecord {
    /// `max |eps|` over the steady-state window (field units).
    pub steady_state_max_abs_error: Option<f64>,
    /// `sqrt(mean(eps^2))` over the steady-state window.
    pub steady_state_rms_error: Option<f64>,
    /// `mean(eps)` over the steady-state window.
    pub steady_state_mean_error: Option<f64>,
    /// Convergence time, s.
    pub convergence_time_s: Option<f64>,
    /// Distance travelled, m.
    pub path_length_m: Option<f64>,
    /// `integral(omega^2 dt)`, rad^2/s.
    pub control_effort: Option<f64>,
    /// Total variation of `omega` over the steady window per second, rad/s^2.
    pub chattering_radps2: Option<f64>,
    /// Sign changes of `omega` per second over the steady window.
    pub sign_changes_per_s: Option<f64>,
    /// Largest distance to the true isoline over the steady window, m.
    pub steady_state_max_isoline_distance_m: Option<f64>,
    /// RMS distance to the true isoline over the steady window, m.
    pub steady_state_rms_isoline_distance_m: Option<f64>,
    /// Share of the steady window within the tolerance, `[0, 1]`.
    pub time_in_band_fraction: Option<f64>,
    /// Times the error left the track-loss band after being tracked.
    #[serde(default)]
    pub track_losses: u64,
}

/// `Some(x)` when `x` is finite.
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

impl MetricsRecord {
    /// The record of metrics `m`.
    pub fn of(m: &RunMetrics) -> Self {
        let o = |x: Option<f64>| x.and_then(finite);
        MetricsRecord {
            steady_state_max_abs_error: o(m.steady_state_max_abs_error),
            steady_state_rms_error: o(m.steady_state_rms_error),
            steady_state_mean_error: o(m.steady_state_mean_error),
            convergence_time_s: o(m.convergence_time_s),
            path_length_m: finite(m.path_length_m),
            control_effort: finite(m.control_effort),
            chattering_radps2: o(m.chattering_radps2),
            sign_changes_per_s: o(m.sign_changes_per_s),
            steady_state_max_isoline_distance_m: o(m.steady_state_max_isoline_distance_m),
            steady_state_rms_isoline_distance_m: o(m.steady_state_rms_isoline_distance_m),
            time_in_band_fraction: o(m.time_in_band_fraction),
            track_losses: m.track_losses,
        }
    }
}

impl RunRecord {
    /// The record of `r`.
    pub fn of(r: &RunResult) -> Self {
        RunRecord {
            outcome: r.outcome.as_str().to_string(),
            outcome_detail: r.outcome_detail.clone(),
            t_end_s: finite(r.t_end_s),
            steps: r.steps,
            samples: r.samples,
            samples_dropped: r.samples_dropped,
            end_position_m: r.end_position_m.map(finite),
            metrics: MetricsRecord::of(&r.metrics),
        }
    }

    /// The value of a numeric column (`None` for [`Column::Outcome`] and
    /// [`Column::OutcomeDetail`], which are text).
    pub fn value(&self, c: Column) -> Option<f64> {
        match c {
            Column::Outcome | Column::OutcomeDetail => None,
            Column::ConvergenceTimeS => self.metrics.convergence_time_s,
            Column::SteadyStateMaxAbsError => self.metrics.steady_state_max_abs_error,
            Column::SteadyStateRmsError => self.metrics.steady_state_rms_error,
            Column::SteadyStateMeanError => self.metrics.steady_state_mean_error,
            Column::SteadyStateMaxIsolineDistanceM => {
                self.metrics.steady_state_max_isoline_distance_m
            }
            Column::SteadyStateRmsIsolineDistanceM => {
                self.metrics.steady_state_rms_isoline_distance_m
            }
            Column::PathLengthM => self.metrics.path_length_m,
            Column::ControlEffort => self.metrics.control_effort,
            Column::ChatteringRadps2 => self.metrics.chattering_radps2,
            Column::SignChangesPerS => self.metrics.sign_changes_per_s,
            Column::TEndS => self.t_end_s,
            Column::Samples => Some(self.samples as f64),
            Column::TimeInBandFraction => self.metrics.time_in_band_fraction,
            Column::TrackLosses => Some(self.metrics.track_losses as f64),
        }
    }

    /// The cell of column `c`: text as is, a count in decimal, a number in the shortest
    /// round-trip form ([`num`]) or empty when undefined ([`real_cell`]).
    pub fn cell(&self, c: Column) -> String {
        match c {
            Column::Outcome => self.outcome.clone(),
            Column::OutcomeDetail => self.outcome_detail.clone().unwrap_or_default(),
            Column::Samples => self.samples.to_string(),
            Column::TrackLosses => self.metrics.track_losses.to_string(),
            c => real_cell(self.value(c)),
        }
    }
}

/// A result column: its name is the key of `summary.json` and the header of every results file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// `outcome`.
    Outcome,
    /// `convergence_time_s`.
    ConvergenceTimeS,
    /// `steady_state_max_abs_error`.
    SteadyStateMaxAbsError,
    /// `steady_state_rms_error`.
    SteadyStateRmsError,
    /// `steady_state_mean_error`.
    SteadyStateMeanError,
    /// `steady_state_max_isoline_distance_m`.
    SteadyStateMaxIsolineDistanceM,
    /// `steady_state_rms_isoline_distance_m`.
    SteadyStateRmsIsolineDistanceM,
    /// `path_length_m`.
    PathLengthM,
    /// `control_effort`.
    ControlEffort,
    /// `chattering_radps2`.
    ChatteringRadps2,
    /// `sign_changes_per_s`.
    SignChangesPerS,
    /// `t_end_s`.
    TEndS,
    /// `samples`.
    Samples,
    /// `outcome_detail`.
    OutcomeDetail,
    /// `time_in_band_fraction`.
    TimeInBandFraction,
    /// `track_losses`.
    TrackLosses,
}

impl Column {
    /// The column's name.
    pub fn name(self) -> &'static str {
        match self {
            Column::Outcome => "outcome",
            Column::ConvergenceTimeS => "convergence_time_s",
            Column::SteadyStateMaxAbsError => "steady_state_max_abs_error",
            Column::SteadyStateRmsError => "steady_state_rms_error",
            Column::SteadyStateMeanError => "steady_state_mean_error",
            Column::SteadyStateMaxIsolineDistanceM => "steady_state_max_isoline_distance_m",
            Column::SteadyStateRmsIsolineDistanceM => "steady_state_rms_isoline_distance_m",
            Column::PathLengthM => "path_length_m",
            Column::ControlEffort => "control_effort",
            Column::ChatteringRadps2 => "chattering_radps2",
            Column::SignChangesPerS => "sign_changes_per_s",
            Column::TEndS => "t_end_s",
            Column::Samples => "samples",
            Column::OutcomeDetail => "outcome_detail",
            Column::TimeInBandFraction => "time_in_band_fraction",
            Column::TrackLosses => "track_losses",
        }
    }
}

/// A number's cell: the shortest round-trip form ([`num`]), empty when undefined or not
/// finite (a results file never holds `NaN` or `inf`, as `summary.json` writes `null`).
pub fn real_cell(x: Option<f64>) -> String {
    x.and_then(finite).map(num).unwrap_or_default()
}

/// The one row builder: the cells of `columns` for a run's `record`, or for a run whose
/// scenario is invalid (`Err(reason)`: outcome [`INVALID_SCENARIO`], the reason in
/// `outcome_detail`, every other cell empty).
pub fn result_cells(columns: &[Column], record: Result<&RunRecord, &str>) -> Vec<String> {
    columns
        .iter()
        .map(|&c| match (&record, c) {
            (Ok(r), c) => r.cell(c),
            (Err(_), Column::Outcome) => INVALID_SCENARIO.to_string(),
            (Err(why), Column::OutcomeDetail) => why.to_string(),
            (Err(_), _) => String::new(),
        })
        .collect()
}
