//! The score of a run, in `[0, 100]` (docs/BENCHMARK.md states the same formulas).
//!
//! A run that does not complete (`left_field`, `diverged`) scores 0. A completed run's parts:
//!
//! ```text
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
//! and its score, by the suite's `scoring` ([`Scoring`]):
//!
//! ```text
//! scoring = 1:  100 * (0.20*capture + 0.30*band + 0.30*distance + 0.10*losses + 0.10*effort)
//! scoring = 2:  100 * (0.20*capture + 0.30*band
//!                      + held * (0.30*distance + 0.10*losses + 0.10*effort))
//!               held = 1 if the run converged (t_c defined), else band
//! ```
//!
//! Every part is in `[0, 1]` and 1 is perfect: capture rewards converging early, band holding
//! the isoline, distance being on it (in metres, so that fields in different units compare),
//! losses not losing it again, effort not turning harder than the isoline needs (chattering
//! laws pay here). Formula 1 paid distance, losses and effort whatever the run did: a law that
//! never came near the isoline had no track loss to lose and little turning to pay for, and
//! collected up to half the score. Formula 2 pays them only for the isoline held: in full once
//! the run has converged, else in the share of the steady window spent in the band, so a law
//! that never captures the isoline scores 0, and a run that converged scores exactly what
//! formula 1 gives it. The parts recorded ([`Score::parts`]) are the scaled ones, so the score
//! is always `100 * sum(WEIGHTS[i] * parts[i])`. A task's score is the mean over its scoring
//! seeds; the overall score the mean over tasks.

use isotrack_sim::{Outcome, RunResult};
use serde::{Deserialize, Serialize};

/// The weights of the parts, in the order capture, band, distance, losses, effort.
pub const WEIGHTS: [f64; 5] = [0.20, 0.30, 0.30, 0.10, 0.10];

/// Which score formula a suite uses (its `scoring` key: `1` or `2`; default `2`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "i64", into = "i64")]
pub enum Scoring {
    /// The original formula: every part counts whatever the run did (standard suite v1).
    V1,
    /// Distance, losses and effort count only for the isoline held (standard suite v2).
    #[default]
    V2,
}

impl TryFrom<i64> for Scoring {
    type Error = String;
    fn try_from(v: i64) -> Result<Self, String> {
        match v {
            1 => Ok(Scoring::V1),
            2 => Ok(Scoring::V2),
            _ => Err(format!(
                "scoring = {v}: the score formulas are 1 and 2 (docs/BENCHMARK.md)"
            )),
        }
    }
}

impl From<Scoring> for i64 {
    fn from(s: Scoring) -> i64 {
        match s {
            Scoring::V1 => 1,
            Scoring::V2 => 2,
        }
    }
}

impl Scoring {
    /// The formula in one line (for pages and reports).
    pub fn formula(self) -> &'static str {
        match self {
            Scoring::V1 => {
                "100 × (0.20 capture + 0.30 in band + 0.30 isoline distance + 0.10 track losses + 0.10 effort)"
            }
            Scoring::V2 => {
                "100 × (0.20 capture + 0.30 in band + held × (0.30 isoline distance + 0.10 track losses + 0.10 effort)), held = 1 once converged, else the share of the steady window in the band"
            }
        }
    }
}

/// What a score needs to know of its task.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScoreContext {
    /// Start of the steady-state window, s.
    pub steady_start_s: f64,
    /// The task's length scale, m.
    pub length_m: f64,
    /// The vehicle's speed, m/s.
    pub speed_mps: f64,
    /// The formula.
    pub scoring: Scoring,
}

/// A run's score and its parts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Score {
    /// The score, `[0, 100]`.
    pub total: f64,
    /// `[capture, band, distance, losses, effort]`, each in `[0, 1]`, as scored (with
    /// [`Scoring::V2`], distance, losses and effort are scaled by `held`).
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
    let held = match ctx.scoring {
        Scoring::V1 => 1.0,
        Scoring::V2 if m.convergence_time_s.is_some() => 1.0,
        Scoring::V2 => band,
    };
    let parts = [capture, band, held * distance, held * losses, held * effort];
    let parts = parts.map(|p| if p.is_finite() { p } else { 0.0 });
    let total = 100.0 * parts.iter().zip(WEIGHTS).map(|(p, w)| p * w).sum::<f64>();
    Score { total, parts }
}
