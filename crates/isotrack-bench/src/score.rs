//! The score of a run, in `[0, 100]` (docs/BENCHMARK.md states the same formula).
//!
//! A run that does not complete (`left_field`, `diverged`) scores 0. A completed run scores
//!
//! ```text
//! score = 100 * (0.20*capture + 0.30*band + 0.30*distance + 0.10*losses + 0.10*effort)
//!
//! capture  = max(0, 1 - t_c / t_w)      t_c the convergence time, t_w the start of the steady
//!                                       window (0 if it never converged)
//! band     = share of the steady window with |eps| within the tolerance
//! distance = 1 / (1 + d_rms / L)        d_rms the steady RMS distance to the true isoline, m;
//!                                       L the task's length_m
//! losses   = 1 / (1 + n)                n track losses
//! effort   = min(1, w_ref^2 / mean(omega^2))   w_ref = v / L, the turn rate of a circle of
//!                                       radius L at the vehicle's speed; mean over the run
//! ```
//!
//! Every part is in `[0, 1]` and 1 is perfect: capture rewards converging early, band holding
//! the isoline, distance being on it (in metres, so that fields in different units compare),
//! losses not losing it again, effort not turning harder than the isoline needs (chattering
//! laws pay here). A task's score is the mean over its scoring seeds; the overall score the mean
//! over tasks.

use isotrack_sim::{Outcome, RunResult};
use serde::{Deserialize, Serialize};

/// The weights of the parts, in the order capture, band, distance, losses, effort.
pub const WEIGHTS: [f64; 5] = [0.20, 0.30, 0.30, 0.10, 0.10];

/// What a score needs to know of its task.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScoreContext {
    /// Start of the steady-state window, s.
    pub steady_start_s: f64,
    /// The task's length scale, m.
    pub length_m: f64,
    /// The vehicle's speed, m/s.
    pub speed_mps: f64,
}

/// A run's score and its parts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Score {
    /// The score, `[0, 100]`.
    pub total: f64,
    /// `[capture, band, distance, losses, effort]`, each in `[0, 1]`.
    pub parts: [f64; 5],
}

/// Scores one run.
pub fn score(r: &RunResult, ctx: &ScoreContext) -> Score {
    if r.outcome != Outcome::Completed {
        return Score {
            total: 0.0,
            parts: [0.0; 5],
        };
    }
    let m = &r.metrics;
    let capture = match m.convergence_time_s {
        Some(t) if ctx.steady_start_s > 0.0 => (1.0 - t / ctx.steady_start_s).clamp(0.0, 1.0),
        Some(_) => 1.0,
        None => 0.0,
    };
    let band = m.time_in_band_fraction.unwrap_or(0.0).clamp(0.0, 1.0);
    let distance = m
        .steady_state_rms_isoline_distance_m
        .map_or(0.0, |d| 1.0 / (1.0 + d.max(0.0) / ctx.length_m));
    let losses = 1.0 / (1.0 + m.track_losses as f64);
    let w_ref = ctx.speed_mps / ctx.length_m;
    let mean_w2 = if r.t_end_s > 0.0 {
        m.control_effort / r.t_end_s
    } else {
        0.0
    };
    let effort = if mean_w2 <= w_ref * w_ref {
        1.0
    } else {
        w_ref * w_ref / mean_w2
    };
    let parts = [capture, band, distance, losses, effort];
    let parts = parts.map(|p| if p.is_finite() { p } else { 0.0 });
    let total = 100.0 * parts.iter().zip(WEIGHTS).map(|(p, w)| p * w).sum::<f64>();
    Score { total, parts }
}
