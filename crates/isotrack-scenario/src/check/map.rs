//! The stability chart of `isotrack check --map` (docs/SAMPLED.md, "The stability chart"): the
//! sampled loop's spectral radius over a grid of `kp` x sensor rate, each cell computed exactly
//! as `isotrack check` computes `sampled.spectral_radius` for the scenario with that `kp` and
//! that rate ([`LoopFamily::cell`] goes through the check's own loop set-up and
//! [`sampled::worst_radius`](super::sampled::worst_radius)), and `--verify`: closed-loop
//! simulations at points spread over the chart, each classified from its own run.
//!
//! * Slopes: the isoline's own (as the verdict), never the tube's. With `ki = 0` on a circular
//!   field each `kp` is checked on the orbit the P law settles on *at that `kp`* (as `check` of
//!   the scenario with that `kp` does).
//! * A cell whose delay spans more than [`MAX_DELAY_STATES`](super::sampled::MAX_DELAY_STATES)
//!   sensor periods is not computed ([`CellStatus::NotComputed`]), never guessed.
//! * Bounded: at most [`MAX_AXIS_POINTS`] points an axis and [`MAX_CELLS`] cells; at most
//!   [`MAX_VERIFY_RUNS`] verification runs and [`MAX_VERIFY_STEPS`] simulation steps in all.

use super::regions::{regions, CHECK_LATTICE};
use super::sampled;
use super::setup::{
    circular_p_law, growing_mode_period_samples, law, not_computed, p_law_orbit, Law, LoopSetup,
};
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_sim::{Outcome, TraceRow, TraceSink};
use serde::Serialize;

/// The most points on either axis of the chart.
pub const MAX_AXIS_POINTS: usize = 400;
/// The most cells (`kp` points x rate points) of one chart: each is one eigenproblem per
/// isoline slope, up to `MAX_DELAY_STATES` states larger than the loop without delay.
pub const MAX_CELLS: usize = 40_000;
/// The most `--verify` runs.
pub const MAX_VERIFY_RUNS: usize = 1000;
/// The most simulation steps of all `--verify` runs together (runs x steps per run).
pub const MAX_VERIFY_STEPS: f64 = 2e9;

/// A cell's state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CellStatus {
    /// Spectral radius below 1.
    Stable,
    /// Spectral radius 1 or more.
    Unstable,
    /// With `ki = 0` the P law has no orbit to settle on (radius infinite; `check` reports
    /// `spectral_radius` null and `stable` false).
    NoEquilibrium,
    /// Not computed: the delay spans more than `MAX_DELAY_STATES` sensor periods, or the
    /// loop gain is beyond [`MAX_LOOP_GAIN`] (the cell's `note` says which).
    NotComputed,
}

impl CellStatus {
    /// The snake_case name (CSV `status`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Stable => "stable",
            Self::Unstable => "unstable",
            Self::NoEquilibrium => "no_equilibrium",
            Self::NotComputed => "not_computed",
        }
    }

    /// `Some(stable)`, `None` when not computed.
    pub fn stable(self) -> Option<bool> {
        match self {
            Self::Stable => Some(true),
            Self::Unstable | Self::NoEquilibrium => Some(false),
            Self::NotComputed => None,
        }
    }
}

/// One cell of the chart.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Cell {
    /// The largest spectral radius over the slopes (finite; `None` when not computed or
    /// infinite).
    pub spectral_radius: Option<f64>,
    /// Stable, unstable, no equilibrium, not computed.
    pub status: CellStatus,
    /// The slopes the cell was checked at, `[min, max]` (the P law's orbit's at this `kp`).
    pub slope_range: [f64; 2],
    /// Why a cell is not computed (CSV `note`; `None` otherwise).
    pub note: Option<&'static str>,
}

pub use super::setup::MAX_LOOP_GAIN;

/// The scenario's sampled loop with `kp` and the sensor rate free: what `check` computes, for
/// any `(kp, rate)`.
pub struct LoopFamily {
    scenario: Scenario,
    law: Law,
    setup: LoopSetup,
    on_orbit: bool,
}

impl LoopFamily {
    /// The scenario's loop; `tube_halfwidth` as for [`super::check`] (the isoline's slopes are
    /// read off the lattice within that tube on fields other than circular ones). `Err` with
    /// the check's note when the sampled check does not apply.
    pub fn new(s: &Scenario, tube_halfwidth: Option<f64>) -> Result<Self, String> {
        let l = law(s);
        let tube = tube_halfwidth.unwrap_or(l.c2);
        let r = regions(s, tube, CHECK_LATTICE, false);
        let setup = LoopSetup::new(s, &l, &r)?;
        let on_orbit = p_law_orbit(s, &l).is_some();
        Ok(Self {
            scenario: s.clone(),
            law: l,
            setup,
            on_orbit,
        })
    }

    /// The cell at `(kp, rate_hz)`: the same computation as `check`'s
    /// `sampled.spectral_radius` for the scenario with `controller.kp = kp` and
    /// `sensor.rate_hz = rate_hz`.
    pub fn cell(&self, kp: f64, rate_hz: f64) -> Cell {
        let l = Law { kp, ..self.law };
        let period_s = 1.0 / rate_hz;
        let (lp, slopes, orbit) = self.setup.at(&self.scenario, &l, period_s);
        let lo = slopes.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = slopes.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        // What `check` does not compute, the chart does not either (one test for both).
        if let Some(why) = not_computed(&lp, orbit.as_ref()) {
            return Cell {
                spectral_radius: None,
                status: CellStatus::NotComputed,
                slope_range: [lo, hi],
                note: Some(why.short()),
            };
        }
        let r = sampled::worst_spectral_radius(&lp, &slopes);
        let (spectral_radius, status, note) = match r {
            r if r.is_finite() => (
                Some(r),
                if r < 1.0 {
                    CellStatus::Stable
                } else {
                    CellStatus::Unstable
                },
                None,
            ),
            _ if circular_p_law(&self.scenario, &l) => (None, CellStatus::NoEquilibrium, None),
            _ => (
                None,
                CellStatus::NotComputed,
                Some("the spectral radius is not finite"),
            ),
        };
        Cell {
            spectral_radius,
            status,
            slope_range: [lo, hi],
            note,
        }
    }

    /// The dominant mode of the loop at `(kp, rate_hz)` at the slope that decides the cell
    /// (the largest radius): its time constant `T/|ln rho|` (decay or growth, s; infinite at
    /// `rho = 1`) and its oscillation period `T 2 pi/|arg z|` (s; `None` for a real positive
    /// eigenvalue). `None` when the cell is not computed or has no equilibrium.
    pub fn dominant_mode(&self, kp: f64, rate_hz: f64) -> Option<(f64, Option<f64>)> {
        let l = Law { kp, ..self.law };
        let period_s = 1.0 / rate_hz;
        let (lp, slopes, orbit) = self.setup.at(&self.scenario, &l, period_s);
        if not_computed(&lp, orbit.as_ref()).is_some() {
            return None;
        }
        let radius = |alpha: f64| sampled::SampledLoop { slope: alpha, ..lp }.spectral_radius();
        let worst = slopes
            .iter()
            .copied()
            .max_by(|a, b| radius(*a).total_cmp(&radius(*b)))?;
        let rho = radius(worst);
        if !rho.is_finite() {
            return None;
        }
        let tau = period_s / rho.ln().abs();
        let period = growing_mode_period_samples(&lp, worst).map(|p| p * period_s);
        Some((tau, period))
    }

    /// The scenario's own `kp`.
    pub fn kp(&self) -> f64 {
        self.law.kp
    }

    /// The scenario's own sensor rate, Hz.
    pub fn rate_hz(&self) -> f64 {
        1.0 / self.setup.base.period_s
    }

    /// The simulation step `sim.dt_s`, s: the fastest sensor rate is `1/dt`.
    pub fn dt_s(&self) -> f64 {
        self.scenario.dt_s()
    }

    /// The sensor delay, s.
    pub fn delay_s(&self) -> f64 {
        self.setup.base.delay_s
    }

    /// `ki`, `c1`, `c2` (held fixed over the chart).
    pub fn other_gains(&self) -> [f64; 3] {
        [self.law.ki, self.law.c1, self.law.c2]
    }

    /// Which slopes the chart uses, in words (figure caption, JSON, docs).
    pub fn slope_basis(&self) -> &'static str {
        if self.on_orbit {
            "the P law's orbit at each kp (ki = 0 on a circular field: the isoline is no equilibrium)"
        } else {
            "the isoline's own slopes (as the verdict; not the tube's)"
        }
    }

    /// The scenario.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }
}

/// The chart's grid: `kp` and sensor rate, each spaced logarithmically from the first end to
/// the second (both included).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MapGrid {
    /// `[lo, hi]` of `kp`.
    pub kp_range: [f64; 2],
    /// `[lo, hi]` of the sensor rate, Hz.
    pub rate_range_hz: [f64; 2],
    /// Points along `kp`.
    pub kp_points: usize,
    /// Points along the rate.
    pub rate_points: usize,
}

impl MapGrid {
    /// The default grid round the scenario's point: `kp` from 1/100 to 100 times the
    /// scenario's (61 points, 15 a decade), the rate from 1/10 to 10 times the scenario's but
    /// at most `1/dt` (41 points).
    pub fn default_for(f: &LoopFamily) -> Self {
        let (kp, rate) = (f.kp(), f.rate_hz());
        Self {
            kp_range: [kp / 100.0, kp * 100.0],
            rate_range_hz: [
                (rate / 10.0).max(1.0 / (isotrack_sim::MAX_STEPS as f64 * f.dt_s())),
                (rate * 10.0).min(1.0 / f.dt_s()).max(rate),
            ],
            kp_points: 61,
            rate_points: 41,
        }
    }

    /// Checks the grid: ranges of positive finite numbers with `lo < hi` and `hi/lo` finite,
    /// rates at most `1/dt` (the sensor cannot sample faster than the simulation steps) and at
    /// least `1/(MAX_STEPS dt)` (as `sensor.rate_hz`), 2 to
    /// [`MAX_AXIS_POINTS`] points an axis and at most [`MAX_CELLS`] cells.
    pub fn validate(&self, dt_s: f64) -> Result<(), String> {
        let range = |name: &str, [lo, hi]: [f64; 2]| -> Result<(), String> {
            // HI/LO finite too: log spacing of a range wider than f64 overflows (a hostile
            // review's hang in the figure's axis).
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi && (hi / lo).is_finite()) {
                return Err(format!(
                    "{name} must be LO:HI with 0 < LO < HI and HI/LO finite, got {}:{}",
                    Echo(lo),
                    Echo(hi)
                ));
            }
            Ok(())
        };
        range("--kp-range", self.kp_range)?;
        range("--rate-range", self.rate_range_hz)?;
        // The slowest rate's period spans at most MAX_STEPS steps, as `sensor.rate_hz` (a
        // hostile review's hang at 1e-50 Hz).
        let bottom = 1.0 / (isotrack_sim::MAX_STEPS as f64 * dt_s);
        if self.rate_range_hz[0] < bottom {
            return Err(format!(
                "--rate-range: {} Hz is slower than a sensor period may be (at most {} steps of sim.dt_s = {} s: at least {} Hz)",
                Echo(self.rate_range_hz[0]),
                isotrack_sim::MAX_STEPS,
                Num(dt_s),
                Num(bottom)
            ));
        }
        let top = 1.0 / dt_s;
        if self.rate_range_hz[1] > top * (1.0 + 1e-9) {
            return Err(format!(
                "--rate-range: {} Hz is faster than the simulation step allows (sim.dt_s = {} s: at most {} Hz)",
                Echo(self.rate_range_hz[1]),
                Num(dt_s),
                Num(top)
            ));
        }
        for (name, n) in [("kp", self.kp_points), ("rate", self.rate_points)] {
            if !(2..=MAX_AXIS_POINTS).contains(&n) {
                return Err(format!(
                    "--map-size: {n} {name} points; each axis needs 2 to {MAX_AXIS_POINTS}"
                ));
            }
        }
        let cells = self.kp_points * self.rate_points;
        if cells > MAX_CELLS {
            return Err(format!(
                "--map-size {}x{} is {cells} cells; at most {MAX_CELLS} (each is an eigenproblem per slope)",
                self.kp_points, self.rate_points
            ));
        }
        Ok(())
    }

    /// The `kp` points.
    pub fn kps(&self) -> Vec<f64> {
        log_points(self.kp_range, self.kp_points)
    }

    /// The rate points, Hz.
    pub fn rates_hz(&self) -> Vec<f64> {
        log_points(self.rate_range_hz, self.rate_points)
    }
}

/// `n >= 2` points from `lo` to `hi` (both exact), evenly spaced in `ln`.
fn log_points([lo, hi]: [f64; 2], n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| match i {
            0 => lo,
            _ if i == n - 1 => hi,
            _ => lo * (hi / lo).powf(i as f64 / (n - 1) as f64),
        })
        .collect()
}

/// The chart: the grid and its cells (`cells[j * kp_points + i]` at `kps[i]`, `rates_hz[j]`).
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityMap {
    /// The grid.
    pub grid: MapGrid,
    /// The `kp` points.
    pub kps: Vec<f64>,
    /// The rate points, Hz.
    pub rates_hz: Vec<f64>,
    /// The cells, row by row of rate.
    pub cells: Vec<Cell>,
    /// The scenario's own `(kp, rate_hz)`.
    pub scenario_point: (f64, f64),
    /// Which slopes ([`LoopFamily::slope_basis`]).
    pub slope_basis: &'static str,
    /// `ki`, `c1`, `c2`, held fixed.
    pub other_gains: [f64; 3],
    /// The sensor delay, s.
    pub delay_s: f64,
}

impl StabilityMap {
    /// The chart from cells computed elsewhere (in parallel: each is
    /// [`LoopFamily::cell`] at its point, in the order of `cells`).
    pub fn from_cells(f: &LoopFamily, grid: MapGrid, cells: Vec<Cell>) -> Self {
        Self {
            kps: grid.kps(),
            rates_hz: grid.rates_hz(),
            grid,
            cells,
            scenario_point: (f.kp(), f.rate_hz()),
            slope_basis: f.slope_basis(),
            other_gains: f.other_gains(),
            delay_s: f.delay_s(),
        }
    }

    /// The points of the grid in the order of `cells`.
    pub fn points(grid: &MapGrid) -> Vec<(f64, f64)> {
        let (kps, rates) = (grid.kps(), grid.rates_hz());
        rates
            .iter()
            .flat_map(|&r| kps.iter().map(move |&k| (k, r)))
            .collect()
    }

    /// The chart computed here, one cell after another.
    pub fn compute(f: &LoopFamily, grid: MapGrid) -> Self {
        let cells = Self::points(&grid)
            .into_iter()
            .map(|(k, r)| f.cell(k, r))
            .collect();
        Self::from_cells(f, grid, cells)
    }

    /// The cell at `kps[i]`, `rates_hz[j]`.
    pub fn at(&self, i: usize, j: usize) -> &Cell {
        &self.cells[j * self.kps.len() + i]
    }

    /// Where stability changes along `kp` at rate row `j`: the pairs of neighbouring `kp`
    /// points `(kps[i], kps[i + 1])` whose cells are computed and differ.
    pub fn kp_crossings(&self, j: usize) -> Vec<(f64, f64)> {
        (0..self.kps.len() - 1)
            .filter_map(|i| {
                let (a, b) = (
                    self.at(i, j).status.stable(),
                    self.at(i + 1, j).status.stable(),
                );
                match (a, b) {
                    (Some(x), Some(y)) if x != y => Some((self.kps[i], self.kps[i + 1])),
                    _ => None,
                }
            })
            .collect()
    }
}

/// What a `--verify` run did, judged from its own trace over the steady-state window
/// (docs/SAMPLED.md, "`--verify N`": the rule, on the law's and the scenario's own scales).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Behaviour {
    /// Completed; over the window's second half the error's range is within the floor that
    /// the sensor's own error (noise, quantisation, bias, lag) and a moving or bending
    /// isoline give, or
    /// it shrank by at least [`DECAY_RATIO`] from the first half; and the vehicle is neither
    /// spinning nor dithering (mean `|omega|` below [`spin_turn_rate_radps`], or below the turn
    /// rate the reading's own error drives through the law, `kp (c1 R/T + R/c2)` with `R` the
    /// reading error's range from the sensor's settings, when that is larger).
    Converged,
    /// Completed but not converged: a sustained or growing oscillation, a spin or a dither.
    LimitCycle,
    /// Completed and calm (not spinning or dithering) but off the level: the mean `|eps|` over
    /// the window's second half exceeds the scenario's convergence tolerance (or the floor,
    /// when larger). Not converged: disagrees with a stable cell (issue 29: a run 9.99 from the
    /// level, moving 0.6 m in 120 s, was "converged").
    Stalled,
    /// The run did not complete: its state diverged (`outcome = diverged`).
    Diverged,
    /// The vehicle left the field's domain (`outcome = left_field`): not compared with the
    /// chart (a loop can leave a bounded map while still converging, and an unstable one can
    /// leave it before it oscillates); counted apart ([`Agreement::left_field`]).
    LeftField,
    /// Completed, but in the window's second half the turn-rate command sat at the turn-rate
    /// limit for at least [`SATURATION_FRACTION`] of the samples: the limit is a saturation
    /// the linear chart leaves out, so the run is not compared with it (an unstable loop
    /// typically grows until it bangs between the limits; a stable one that still saturates
    /// late is in a regime the linearisation does not describe). Counted apart
    /// ([`Agreement::saturated`]).
    Saturated,
    /// Completed, but too short to judge: each half of the steady-state window must span the
    /// time constant of the mode that decides the cell (`T/|ln rho|`: it decays or grows by a
    /// factor e per half, distinct from a sustained oscillation), two periods of its
    /// oscillation and [`MIN_HALF_SAMPLES`] samples ([`LoopFamily::dominant_mode`]). Not
    /// compared; counted apart ([`Agreement::undetermined`]).
    Undetermined,
    /// The point makes no valid scenario (the reason in `detail`).
    Invalid,
}

impl Behaviour {
    /// The snake_case name (CSV `outcome`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Converged => "converged",
            Self::LimitCycle => "limit_cycle",
            Self::Stalled => "stalled",
            Self::Diverged => "diverged",
            Self::LeftField => "left_field",
            Self::Saturated => "saturated",
            Self::Undetermined => "undetermined",
            Self::Invalid => "invalid",
        }
    }
}

/// A run whose turn-rate command sits at the turn-rate limit for at least this fraction of the
/// samples of its window's second half is [`Behaviour::Saturated`].
pub const SATURATION_FRACTION: f64 = 0.1;

/// The fewest sensor samples each half of a run's steady-state window must hold for the run to
/// be judged ([`Behaviour::Undetermined`] otherwise).
pub const MIN_HALF_SAMPLES: f64 = 10.0;

/// A run whose error range over the second half of the steady-state window is at most this
/// fraction of the first half's is still converging (a loop at spectral radius 0.999 at 2.7 Hz
/// shrinks by 0.86 over a 60 s half; a sustained oscillation keeps its range, ratio ~1).
pub const DECAY_RATIO: f64 = 0.9;

/// The sensor's own error (noise, quantisation, bias drift) widens the settled error's range by
/// up to about as much as its own range: a settled run's error range may be this many times
/// the reading error's range (`8 noise_std + resolution + 4 bias_drift sqrt(window)`).
pub const SENSOR_FLOOR_FACTOR: f64 = 2.0;

/// A cell is "near the boundary" (`near_boundary`) when its deciding mode grows or decays by
/// less than `e^NEAR_BOUNDARY_E_FOLDS` (about 22 000) over the run's duration `D`:
/// `|ln rho| * D / T <= NEAR_BOUNDARY_E_FOLDS` (`T` the sensor period). A rate per second, not
/// per sample (issue 29: the old `|rho - 1| <= 0.02` a sample put almost every cell at 100 Hz
/// "near", a decay of 2 % a sample being a factor e^1200 over a 600 s run). There a run of
/// finite length, or the linearisation, may disagree with the chart. Defined on the radius,
/// not the grid: independent of `--map-size`.
pub const NEAR_BOUNDARY_E_FOLDS: f64 = 10.0;

/// The mean `|omega|` from which a run counts as spinning, dithering or oscillating rather than
/// following an isoline, rad/s: the least of `pi/(8T)` (an eighth of a half turn per sensor
/// period: the sampled loop's dither is at `pi/T`, and a loop that follows an isoline turns by
/// `v kappa T`, a small angle, per sample), half the turn-rate limit (an unstable loop bangs
/// between the limits, its mean `|omega|` near the limit) and, where the loop model knows the
/// curvature `kappa` it is checked at (the circle, the P law's orbit), `4 v kappa`; never below
/// `2 v kappa`, twice the turn the curve itself needs.
pub fn spin_turn_rate_radps(limit_radps: Option<f64>, period_s: f64, v_kappa_radps: f64) -> f64 {
    let mut w = std::f64::consts::PI / (8.0 * period_s);
    if let Some(l) = limit_radps {
        w = w.min(0.5 * l);
    }
    if v_kappa_radps > 0.0 {
        w = w.min(4.0 * v_kappa_radps).max(2.0 * v_kappa_radps);
    }
    w
}

/// The steady-state window's two halves: error ranges, turn rate, mean `|eps|`.
struct Window {
    from_s: f64,
    mid_s: f64,
    /// `[lo, hi]` of the error in the first and the second half.
    halves: [[f64; 2]; 2],
    turn_sum: f64,
    /// Sum of `omega^2` over the second half (its RMS).
    turn_sq_sum: f64,
    /// Sum of `|eps - eps_ref|` over the second half (its mean).
    abs_error_sum: f64,
    /// The turn-rate limit in force (`None`: none).
    limit_radps: Option<f64>,
    /// Samples of the second half at the turn-rate limit.
    saturated_rows: u64,
    /// The error the loop the chart checks settles at: 0 on the isoline, the P law's orbit
    /// error `eps*` on a circular field with `ki = 0`.
    error_ref: f64,
    rows: u64,
}

impl TraceSink for Window {
    fn record(&mut self, row: &TraceRow) {
        if row.t_s < self.from_s {
            return;
        }
        let h = usize::from(row.t_s >= self.mid_s);
        let r = &mut self.halves[h];
        r[0] = r[0].min(row.error);
        r[1] = r[1].max(row.error);
        if h == 1 {
            self.turn_sum += row.omega_radps.abs();
            self.turn_sq_sum += row.omega_radps * row.omega_radps;
            self.abs_error_sum += (row.error - self.error_ref).abs();
            if self
                .limit_radps
                .is_some_and(|l| row.omega_radps.abs() >= l * (1.0 - 1e-6))
            {
                self.saturated_rows += 1;
            }
            self.rows += 1;
        }
    }
}

/// One `--verify` point: where, what the chart predicts there, what the simulation did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VerifyPoint {
    /// `kp`.
    pub kp: f64,
    /// Sensor rate, Hz (a whole number of simulation steps per period).
    pub rate_hz: f64,
    /// The chart's computation at this very point.
    pub cell: Cell,
    /// What the simulation did.
    pub behaviour: Behaviour,
    /// `max - min` of the error over the second half of the steady-state window.
    pub error_range: Option<f64>,
    /// Mean `|omega|` over the second half of the steady-state window, rad/s.
    pub mean_abs_turn_radps: Option<f64>,
    /// The run's `outcome` (`completed`, `diverged`, `left_field`) and the numbers the
    /// classification used, or why the point is invalid.
    pub detail: String,
    /// Whether prediction (stable) and behaviour (converged) agree; `None` when not computed,
    /// invalid or left the field.
    pub agrees: Option<bool>,
    /// The cell's mode changes by less than `e^NEAR_BOUNDARY_E_FOLDS` over the run
    /// ([`near_boundary`]).
    pub near_boundary: bool,
}

/// Whether a cell sampled at period `period_s` lies near the boundary for a run of
/// `duration_s`: `|ln rho| * duration_s / period_s <= NEAR_BOUNDARY_E_FOLDS` (a cell not
/// computed or without equilibrium is not).
pub fn near_boundary(cell: &Cell, period_s: f64, duration_s: f64) -> bool {
    cell.spectral_radius
        .is_some_and(|r| r > 0.0 && r.ln().abs() * duration_s / period_s <= NEAR_BOUNDARY_E_FOLDS)
}

/// The sensor periods, in whole simulation steps `[lo, hi]`, whose rates `1/(k dt)` lie in the
/// grid's rate range; `lo > hi` when none does (then no simulation can sample inside the chart).
pub fn whole_step_periods(grid: &MapGrid, dt_s: f64) -> [f64; 2] {
    let [r0, r1] = grid.rate_range_hz;
    [
        (1.0 / (r1 * dt_s) - 1e-9).ceil().max(1.0),
        (1.0 / (r0 * dt_s) + 1e-9).floor(),
    ]
}

/// `count` verification points spread over the grid's rectangle (in `ln kp`, `ln rate`): the
/// Halton sequence in bases 2 and 3 (points 1..=count), shifted modulo 1 by two numbers drawn
/// from `seed` (a Cranley-Patterson rotation, SplitMix64 of the seed). Each rate is moved to
/// the nearest rate the simulation can sample at, `1/(k dt)`, kept in the grid's rate range
/// when one lies there.
pub fn verify_points(grid: &MapGrid, dt_s: f64, count: usize, seed: u64) -> Vec<(f64, f64)> {
    let halton = |mut i: u64, base: u64| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= base as f64;
            r += f * (i % base) as f64;
            i /= base;
        }
        r
    };
    let shift = |k: u64| crate::sweep::derived_seed(seed, k) as f64 / 2f64.powi(63);
    let (s1, s2) = (shift(0), shift(1));
    let [k0, k1] = grid.kp_range;
    let [r0, r1] = grid.rate_range_hz;
    let [steps_lo, steps_hi] = whole_step_periods(grid, dt_s);
    (1..=count as u64)
        .map(|i| {
            let u = (halton(i, 2) + s1).fract();
            let v = (halton(i, 3) + s2).fract();
            let kp = k0 * (k1 / k0).powf(u);
            let rate = r0 * (r1 / r0).powf(v);
            let mut steps = (1.0 / (rate * dt_s)).round().max(1.0);
            if steps_lo <= steps_hi {
                steps = steps.clamp(steps_lo, steps_hi);
            }
            (kp, 1.0 / (steps * dt_s))
        })
        .collect()
}

/// Runs the scenario at `(kp, rate_hz)` (recording at the sensor's rate) and classifies it
/// ([`Behaviour`]): the run (`verify_run`), the floors a settled run is held to
/// (`SettleFloors`), its behaviour in the window (`classify_run`), then the runs the chart is
/// not compared with (saturated, too short to judge).
pub fn verify_point(f: &LoopFamily, kp: f64, rate_hz: f64) -> VerifyPoint {
    let cell = f.cell(kp, rate_hz);
    let mut p = VerifyPoint {
        kp,
        rate_hz,
        cell,
        behaviour: Behaviour::Invalid,
        error_range: None,
        mean_abs_turn_radps: None,
        detail: String::new(),
        agrees: None,
        near_boundary: near_boundary(&cell, 1.0 / rate_hz, f.scenario.spec().sim.duration_s),
    };
    let Some((s, w)) = verify_run(f, &mut p, kp, rate_hz) else {
        return p;
    };
    let range = |[lo, hi]: [f64; 2]| (hi >= lo).then_some(hi - lo);
    let (first, second) = (range(w.halves[0]), range(w.halves[1]));
    p.error_range = second;
    if w.rows > 0 {
        p.mean_abs_turn_radps = Some(w.turn_sum / w.rows as f64);
    }
    let floors = SettleFloors::of(f, &s, kp, rate_hz, w.from_s);
    classify_run(&mut p, &w, (first, second), &floors, &s);
    if saturated(&mut p, &w) || too_short_to_judge(&mut p, f, kp, rate_hz, floors.window_s) {
        return p;
    }
    p.agrees = p
        .cell
        .status
        .stable()
        .map(|st| st == (p.behaviour == Behaviour::Converged));
    p
}

/// The run at `(kp, rate_hz)` with its steady-state window recorded: `None` (and `p` final)
/// when the scenario cannot be derived, the run left the field or diverged.
fn verify_run(
    f: &LoopFamily,
    p: &mut VerifyPoint,
    kp: f64,
    rate_hz: f64,
) -> Option<(Scenario, Window)> {
    let sets = [
        format!("controller.kp={kp:?}"),
        format!("sensor.rate_hz={rate_hz:?}"),
        format!("output.record_rate_hz={rate_hz:?}"),
    ];
    let s = match f.scenario.derive(&sets, "--verify") {
        Ok(s) => s,
        Err(e) => {
            p.detail = e.to_string();
            return None;
        }
    };
    let spec = s.spec();
    let duration = spec.sim.duration_s;
    let frac = spec.metrics.steady_state_fraction;
    let from_s = (1.0 - frac) * duration;
    let mut w = Window {
        from_s,
        mid_s: 0.5 * (from_s + duration),
        halves: [[f64::INFINITY, f64::NEG_INFINITY]; 2],
        turn_sum: 0.0,
        turn_sq_sum: 0.0,
        abs_error_sum: 0.0,
        limit_radps: s.max_turn_rate_radps(),
        saturated_rows: 0,
        error_ref: f
            .setup
            .at(&f.scenario, &Law { kp, ..f.law }, 1.0 / rate_hz)
            .2
            .map_or(0.0, |o| o.orbit.error),
        rows: 0,
    };
    let r = s.run(&mut w);
    p.detail = r.outcome.as_str().to_string();
    match r.outcome {
        Outcome::Completed => {}
        Outcome::LeftField => {
            p.behaviour = Behaviour::LeftField;
            return None;
        }
        _ => {
            p.behaviour = Behaviour::Diverged;
            p.agrees = p.cell.status.stable().map(|st| !st);
            return None;
        }
    }
    Some((s, w))
}

/// What a settled run is held to: the floor its error range may reach, the turn rate a calm
/// one stays below, and the steady-state window's length.
#[derive(Clone, Copy)]
struct SettleFloors {
    /// The floor, field units.
    floor: f64,
    /// The spin turn rate (or the reading error's own, when larger), rad/s.
    spin: f64,
    /// The steady-state window, s.
    window_s: f64,
}

impl SettleFloors {
    fn of(f: &LoopFamily, s: &Scenario, kp: f64, rate_hz: f64, from_s: f64) -> Self {
        let spec = s.spec();
        let duration = spec.sim.duration_s;
        // The floor a settled run's error range may reach: the reading error's own range (times
        // SENSOR_FLOOR_FACTOR), on a moving isoline the scenario's convergence tolerance (the
        // error tracking the motion leaves, by the scenario's own measure), and rounding.
        let c2 = f.law.c2;
        let level = s.level();
        // The reading error's range from the sensor's own settings (not from the trace: the held
        // reading lags the true value by the motion over a period, which on an oscillating run is
        // the oscillation itself): about 8 std of Gaussian noise over the window's samples, the
        // resolution, and 4 sqrt(window) times the bias drift.
        let sn = &spec.sensor;
        let window_s = duration - from_s;
        let rr = 8.0 * sn.noise_std
            + sn.resolution
            + 4.0 * sn.bias_drift_per_sqrt_s * window_s.max(0.0).sqrt();
        let sensor_floor = SENSOR_FLOOR_FACTOR * rr;
        let (lp, _, _) = f.setup.at(&f.scenario, &Law { kp, ..f.law }, 1.0 / rate_hz);
        // A moving isoline, or one whose bends the loop model leaves out (taken as straight:
        // curvature 0 on a grid), keeps forcing the error of a settled run: there the floor is the
        // scenario's own convergence tolerance (the band it counts as on the isoline).
        let motion_floor = if s.is_time_varying() || lp.curvature_per_m == 0.0 {
            spec.metrics.convergence_tolerance
        } else {
            0.0
        };
        let floor = sensor_floor
            .max(motion_floor)
            .max(1e-9 * level.abs().max(c2));
        // The turn rate the reading's own error drives through the law (a noisy sensor makes a
        // settled vehicle jitter): `kp (c1 R/T + R/c2)`, `R` the reading error's range.
        let c1 = f.law.c1;
        let noise_turn = kp * (c1.abs() * rr * rate_hz + rr / c2.abs());
        let spin = spin_turn_rate_radps(
            s.max_turn_rate_radps(),
            1.0 / rate_hz,
            lp.speed_mps * lp.curvature_per_m.abs(),
        )
        .max(noise_turn);
        Self {
            floor,
            spin,
            window_s,
        }
    }
}

/// A completed run's behaviour in the window (converged, limit cycle, stalled) and the
/// numbers it was judged by, in `p.detail`.
fn classify_run(
    p: &mut VerifyPoint,
    w: &Window,
    (first, second): (Option<f64>, Option<f64>),
    floors: &SettleFloors,
    s: &Scenario,
) {
    let spec = s.spec();
    let SettleFloors { floor, spin, .. } = *floors;
    let settled = match (first, second) {
        (_, Some(b)) if b <= floor => true,
        (Some(a), Some(b)) => b <= DECAY_RATIO * a,
        _ => false,
    };
    // Calm: the RMS turn rate below the spin rate. The RMS, not the mean: a loop that bangs
    // between large turn rates part of the time has a mean below the spin rate while it spins
    // (issue 29: volcano at kp 48.8, 33.3 Hz, mean |omega| 12.1 < 13.09 with |omega| > 1 rad/s
    // 35 % of the time); a vehicle following the isoline turns at about v*kappa throughout, so
    // its RMS is about its mean.
    let rms_turn = (w.rows > 0).then(|| (w.turn_sq_sum / w.rows as f64).sqrt());
    let calm = rms_turn.is_some_and(|t| t < spin);
    // On the level: the mean |eps| over the second half (from the P law's orbit error on a
    // circular field with ki = 0: the equilibrium the chart checks) within the scenario's
    // convergence tolerance (or the floor, when larger).
    let mean_abs_error = (w.rows > 0).then(|| w.abs_error_sum / w.rows as f64);
    let tolerance = spec.metrics.convergence_tolerance.max(floor);
    let near = mean_abs_error.is_some_and(|e| e <= tolerance);
    p.behaviour = if !calm {
        Behaviour::LimitCycle
    } else if !near {
        Behaviour::Stalled
    } else if settled {
        Behaviour::Converged
    } else {
        Behaviour::LimitCycle
    };
    let g = |x: Option<f64>| x.map_or_else(|| "-".to_string(), |v| format!("{v:.3e}"));
    p.detail = format!(
        "completed; error range {} then {} (floor {}), mean |eps| {} (tolerance {}), mean |omega| {} rad/s, RMS {} (spin from {})",
        g(first),
        g(second),
        g(Some(floor)),
        g(mean_abs_error),
        g(Some(tolerance)),
        g(p.mean_abs_turn_radps),
        g(rms_turn),
        g(Some(spin))
    );
}

/// The turn-rate limit saturating late: outside what the linear chart describes (`true`: `p`
/// is final, not compared).
fn saturated(p: &mut VerifyPoint, w: &Window) -> bool {
    // The turn-rate limit saturating late: outside what the linear chart describes.
    let saturated_share = (w.rows > 0).then(|| w.saturated_rows as f64 / w.rows as f64);
    if let (Some(share), Some(limit)) = (saturated_share, w.limit_radps) {
        if share >= SATURATION_FRACTION {
            p.behaviour = Behaviour::Saturated;
            p.detail = format!(
                "saturated: the turn-rate command sat at the limit {} rad/s in {:.0} % of the window's second half (the chart's linear loop leaves the limit out: not compared); {}",
                Num(limit),
                100.0 * share,
                p.detail
            );
            return true;
        }
    }
    false
}

/// Too short to judge (`true`: `p` is final, undetermined).
fn too_short_to_judge(
    p: &mut VerifyPoint,
    f: &LoopFamily,
    kp: f64,
    rate_hz: f64,
    window_s: f64,
) -> bool {
    // Too short to judge: each half of the window must cover the time scale of the mode that
    // decides the cell (issue 29: a slowly decaying run was called a limit cycle, and a 2 s
    // run "agreed" from no data).
    let half_s = 0.5 * window_s.max(0.0);
    let period_s = 1.0 / rate_hz;
    let (tau, osc) = f
        .dominant_mode(kp, rate_hz)
        .unwrap_or((f64::INFINITY, None));
    let need_s = tau
        .max(2.0 * osc.unwrap_or(0.0))
        .max(MIN_HALF_SAMPLES * period_s);
    // A NaN need (no time scale) counts as too short: judged only when the half covers it.
    let covered = half_s.partial_cmp(&need_s).is_some_and(|o| o.is_ge());
    if p.cell.status.stable().is_some() && !covered {
        let judged = p.behaviour.as_str();
        p.behaviour = Behaviour::Undetermined;
        p.detail = format!(
            "undetermined: each half of the steady-state window is {} s, shorter than the {} s it needs (the deciding mode's time constant T/|ln rho| = {} s{}, at least {} samples); it looked {judged}: {}",
            Num(half_s),
            Num(need_s),
            Num(tau),
            osc.map_or_else(String::new, |o| format!(", twice its period {} s", Num(o))),
            MIN_HALF_SAMPLES,
            p.detail
        );
        return true;
    }
    false
}

/// The simulation steps of one run of `s` (`duration / dt`).
pub fn steps_per_run(s: &Scenario) -> f64 {
    s.spec().sim.duration_s / s.dt_s()
}

/// Agreement over verified points.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Agreement {
    /// Points whose prediction was computed and whose run was valid and stayed on the field.
    pub compared: usize,
    /// Of those, where prediction and behaviour agree.
    pub agree: usize,
    /// `100 agree / compared` (null when nothing was compared).
    pub percent: Option<f64>,
    /// Agreement over the compared points the chart predicts stable.
    pub predicted_stable: SideAgreement,
    /// Agreement over the compared points the chart predicts unstable (or without
    /// equilibrium).
    pub predicted_unstable: SideAgreement,
    /// Disagreements near the boundary ([`near_boundary`]).
    pub disagreements_near_boundary: usize,
    /// Disagreements further from radius 1 (each listed in `verify.csv`, `near_boundary`
    /// false).
    pub disagreements_far: usize,
    /// Runs that left the field (not compared: [`Behaviour::LeftField`]).
    pub left_field: usize,
    /// Runs that saturated the turn-rate limit late (not compared: [`Behaviour::Saturated`]).
    pub saturated: usize,
    /// Runs too short to judge (not compared: [`Behaviour::Undetermined`]).
    pub undetermined: usize,
    /// Points whose cell was not computed (not compared: no prediction).
    pub not_computed: usize,
    /// Points that make no valid scenario (not compared: [`Behaviour::Invalid`]).
    pub invalid: usize,
    /// Points not compared (not computed, invalid, left the field, saturated, too short).
    pub not_compared: usize,
}

/// Agreement over the compared points of one prediction (stable or unstable).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SideAgreement {
    /// Compared points with this prediction.
    pub compared: usize,
    /// Of those, where the run agrees.
    pub agree: usize,
    /// `100 agree / compared` (null when none).
    pub percent: Option<f64>,
}

fn side(points: &[&VerifyPoint], stable: bool) -> SideAgreement {
    let of: Vec<&&VerifyPoint> = points
        .iter()
        .filter(|p| p.cell.status.stable() == Some(stable))
        .collect();
    let agree = of.iter().filter(|p| p.agrees == Some(true)).count();
    SideAgreement {
        compared: of.len(),
        agree,
        percent: (!of.is_empty()).then(|| 100.0 * agree as f64 / of.len() as f64),
    }
}

/// Counts [`Agreement`].
pub fn agreement(points: &[VerifyPoint]) -> Agreement {
    let compared: Vec<&VerifyPoint> = points.iter().filter(|p| p.agrees.is_some()).collect();
    let agree = compared.iter().filter(|p| p.agrees == Some(true)).count();
    let count = |b: Behaviour| points.iter().filter(|p| p.behaviour == b).count();
    let near = compared
        .iter()
        .filter(|p| p.agrees == Some(false) && p.near_boundary)
        .count();
    Agreement {
        compared: compared.len(),
        agree,
        percent: (!compared.is_empty()).then(|| 100.0 * agree as f64 / compared.len() as f64),
        predicted_stable: side(&compared, true),
        predicted_unstable: side(&compared, false),
        disagreements_near_boundary: near,
        disagreements_far: compared.len() - agree - near,
        left_field: count(Behaviour::LeftField),
        saturated: count(Behaviour::Saturated),
        undetermined: count(Behaviour::Undetermined),
        not_computed: points
            .iter()
            .filter(|p| p.agrees.is_none() && p.cell.status == CellStatus::NotComputed)
            .count(),
        invalid: count(Behaviour::Invalid),
        not_compared: points.len() - compared.len(),
    }
}
