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

/// The team score in one line (for pages).
pub const TEAM_FORMULA: &str = "A team task's run (its scenario has [team]) scores 100 × (0.50 tracking + held × (0.25 spacing + 0.25 revisit)): tracking the mean of its vehicles' scores by the formula above over 100, held the mean of their held, spacing 1 − gap CV/√(N−1), revisit min(r, 1/r) with r the mean revisit time over the ideal L/(N v0); spacing and revisit 0 if a vehicle did not complete. The table's parts are the vehicles' means; the team parts are in the task's results.csv. The picture shows vehicle 0's path.";

/// The weights of a team run's score, in the order tracking, spacing, revisit
/// ([`team_score`]).
pub const TEAM_WEIGHTS: [f64; 3] = [0.50, 0.25, 0.25];

/// The team parts of a team run's score (docs/BENCHMARK.md, "Team score"), each in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TeamParts {
    /// The mean over the vehicles of each vehicle's score (the suite's formula, 0 for a vehicle
    /// that did not complete), over 100.
    pub tracking: f64,
    /// The mean over the vehicles of how much of the isoline each held: 1 for a vehicle that
    /// converged (or, by formula 1, completed), else its share of the steady window in the band
    /// (formula 2); 0 for a vehicle that did not complete.
    pub held: f64,
    /// `held * (1 - gap_cv / sqrt(N - 1))`, clamped to `[0, 1]` (1 for a team of one).
    pub spacing: f64,
    /// `held * min(r, 1/r)`, `r = revisit_time_mean_s / revisit_time_ideal_s`.
    pub revisit: f64,
}

/// Scores a team run: its vehicles' `runs` (in the listed order) and its team metrics `team`
/// (`summary.json`'s `team.metrics`; `None` when none were measured), each vehicle scored in
/// `ctx` by [`score`].
///
/// ```text
/// score    = 100 * (0.50*tracking + 0.25*spacing + 0.25*revisit)
/// tracking = mean_i score_i / 100            score_i vehicle i's score (0 unless completed)
/// held     = mean_i held_i                   held_i as in formula 2 (formula 1: 1), 0 unless
///                                            vehicle i completed
/// spacing  = held * clamp(1 - gap_cv / sqrt(N - 1), 0, 1)    (1 for N = 1)
/// revisit  = held * min(r, 1/r),  r = revisit_time_mean_s / (L / (N v0))
/// ```
///
/// `sqrt(N - 1)` is the largest gap CV of `N` gaps that sum to the isoline's length `L` (all of
/// it in one gap: the whole team in one place), so `spacing` runs from 0 (one cluster) to 1
/// (even gaps). The mean revisit time is off the ideal both ways: a cluster passes a point in
/// bursts (short intervals), a team slower than `v0` or off the isoline less often, so the
/// ratio counts either way. A team with a vehicle that did not complete gets spacing and
/// revisit 0 (its gaps and passes are measured to a vehicle no longer tracking), as does a
/// metric that was not measured (`None`: no closed isoline at any sample of the window). The
/// returned [`Score::parts`] are the vehicles' mean parts (`tracking = sum(WEIGHTS * parts)`).
pub fn team_score(
    runs: &[RunResult],
    team: Option<&isotrack_runs::summary::TeamRecord>,
    ctx: &ScoreContext,
) -> (Score, TeamParts) {
    let n = runs.len().max(1) as f64;
    let mut parts = [0.0; 5];
    let mut tracking = 0.0;
    let mut held = 0.0;
    for r in runs {
        let s = score(r, ctx);
        tracking += s.total / 100.0;
        for (p, q) in parts.iter_mut().zip(s.parts) {
            *p += q;
        }
        held += vehicle_held(r, ctx.scoring);
    }
    let parts = parts.map(|p| p / n);
    let all_completed = !runs.is_empty() && runs.iter().all(|r| r.outcome == Outcome::Completed);
    let (total, team) = team_total(tracking / n, held / n, all_completed, team);
    (Score { total, parts }, team)
}

/// A team run's score from its vehicles' `tracking` and `held` means ([`team_score`]), whether
/// every vehicle completed, and its team metrics: `(score, parts)`, the spacing and revisit
/// parts computed from `team` as [`team_score`] does. The one rule for a team run's score, also
/// what `benchmark --resume` recomputes a stored team run's score with.
pub fn team_total(
    tracking: f64,
    held: f64,
    all_completed: bool,
    team: Option<&isotrack_runs::summary::TeamRecord>,
) -> (f64, TeamParts) {
    let (spacing, revisit) = match team {
        Some(t) if all_completed => (
            spacing_part(t.count, t.gap_cv),
            revisit_part(t.revisit_time_mean_s, t.revisit_time_ideal_s),
        ),
        _ => (0.0, 0.0),
    };
    let team = TeamParts {
        tracking,
        held,
        spacing: held * spacing,
        revisit: held * revisit,
    };
    let total = 100.0
        * (TEAM_WEIGHTS[0] * team.tracking
            + TEAM_WEIGHTS[1] * team.spacing
            + TEAM_WEIGHTS[2] * team.revisit);
    (total, team)
}

/// How much of the isoline a vehicle held: 0 unless it completed; formula 1: 1; formula 2: 1
/// once converged, else its share of the steady window in the band.
fn vehicle_held(r: &RunResult, scoring: Scoring) -> f64 {
    if r.outcome != Outcome::Completed {
        return 0.0;
    }
    match scoring {
        Scoring::V1 => 1.0,
        Scoring::V2 if r.metrics.convergence_time_s.is_some() => 1.0,
        Scoring::V2 => {
            let b = r.metrics.time_in_band_fraction.unwrap_or(0.0);
            if b.is_finite() {
                b.clamp(0.0, 1.0)
            } else {
                0.0
            }
        }
    }
}

/// `clamp(1 - gap_cv / sqrt(N - 1), 0, 1)`; 1 for a team of one; 0 when not measured.
fn spacing_part(count: usize, gap_cv: Option<f64>) -> f64 {
    if count <= 1 {
        return 1.0;
    }
    match gap_cv {
        Some(cv) if cv.is_finite() => (1.0 - cv / ((count - 1) as f64).sqrt()).clamp(0.0, 1.0),
        _ => 0.0,
    }
}

/// `min(r, 1/r)` with `r = mean / ideal`; 0 when either is not measured or not positive.
fn revisit_part(mean_s: Option<f64>, ideal_s: Option<f64>) -> f64 {
    match (mean_s, ideal_s) {
        (Some(m), Some(i)) if m.is_finite() && i.is_finite() && m > 0.0 && i > 0.0 => {
            let r = m / i;
            r.min(1.0 / r).clamp(0.0, 1.0)
        }
        _ => 0.0,
    }
}
