//! A team's run read back for its figures (issue 32, docs/TEAMS.md): the vehicles' arc
//! coordinates along the true isoline from the trace (never by re-simulating), the gap ahead of
//! each vehicle over time and the revisit time along the isoline. The isoline is the one the
//! team metrics measure along (`Scenario::team_isoline`): a radial field's circle, a static
//! field's marching-squares polyline (closed, or open where it leaves the field), or for a
//! field that moves the isoline at the last row's time (the last frame), labelled so.

use crate::run_data::RunData;
use isotrack_core::Vec2;
use isotrack_scenario::{Scenario, TeamIsolineModel};
use isotrack_sim::team::arc::{pick_loop, ArcProjection, CircleArc, PolylineArc};

/// The isoline a team's figure measures along ([`TeamTracks::arc`]).
#[derive(Clone, Debug, PartialEq)]
pub enum FigureArc {
    /// A radial field's circle (exact).
    Circle(CircleArc),
    /// A polyline from marching squares (closed or open).
    Polyline(PolylineArc),
}

impl ArcProjection for FigureArc {
    fn length_m(&self) -> f64 {
        match self {
            FigureArc::Circle(c) => c.length_m(),
            FigureArc::Polyline(p) => p.length_m(),
        }
    }
    fn project(&self, p: Vec2) -> Option<isotrack_sim::team::arc::ArcPoint> {
        match self {
            FigureArc::Circle(c) => c.project(p),
            FigureArc::Polyline(l) => l.project(p),
        }
    }
    fn is_closed(&self) -> bool {
        match self {
            FigureArc::Circle(_) => true,
            FigureArc::Polyline(p) => p.is_closed(),
        }
    }
}

/// Points of a circle drawn as a polyline.
const CIRCLE_POINTS: usize = 360;

impl FigureArc {
    /// The isoline as the polyline drawn: a circle's [`CIRCLE_POINTS`] points, a polyline's
    /// vertices; a closed one ends with its first point again.
    pub fn points(&self) -> Vec<Vec2> {
        match self {
            FigureArc::Circle(c) => (0..=CIRCLE_POINTS)
                .map(|i| {
                    let th = std::f64::consts::TAU * i as f64 / CIRCLE_POINTS as f64;
                    c.center_m + Vec2::new(th.cos(), th.sin()) * c.radius_m
                })
                .collect(),
            FigureArc::Polyline(p) => {
                let mut v = p.vertices().to_vec();
                if p.is_closed() {
                    v.extend(p.vertices().first().copied());
                }
                v
            }
        }
    }
}

/// A linear ramp without `field.domain_m`: a field without an edge, whose isoline the team
/// metrics cut at the box the team can reach.
fn ramp_without_edge(scenario: &Scenario) -> bool {
    matches!(
        scenario.field(),
        isotrack_scenario::field::FieldModel::Analytic(f)
            if f.domain_m.is_none()
                && matches!(f.kind, isotrack_fields::AnalyticKind::LinearRamp(_))
    )
}

/// The isoline a team figure of `scenario` measures along and its legend label: as
/// `Scenario::team_isoline` (the metrics' own), and for a field that moves its isoline at
/// `t_last_s` (the loop most of `last_positions` are nearest to), labelled with that time.
/// `None` where there is none.
pub fn figure_isoline(
    scenario: &Scenario,
    t_last_s: f64,
    last_positions: &[Vec2],
) -> Option<(FigureArc, String)> {
    let level = crate::style::value_label(scenario.level());
    match scenario.team_isoline() {
        TeamIsolineModel::Circle(c) => Some((
            FigureArc::Circle(c),
            format!("true isoline s_d = {level} (circle)"),
        )),
        TeamIsolineModel::Polyline(p) => {
            let kind = if p.is_closed() {
                "closed"
            } else if ramp_without_edge(scenario) {
                // nu36-12: a linear ramp without a domain has no edge to leave: its line is
                // cut at the box the team can reach (docs/TEAMS.md "Open isolines").
                "open: cut at the box the team can reach"
            } else {
                "open: it leaves the field"
            };
            Some((
                FigureArc::Polyline(p),
                format!("true isoline s_d = {level} ({kind})"),
            ))
        }
        TeamIsolineModel::Moving(m) => {
            let v = m.version(t_last_s)?;
            let loops = m.loops(v);
            let j = pick_loop(&loops, last_positions)?;
            let p = PolylineArc::aligned(loops[j].clone(), None).ok()?;
            Some((
                FigureArc::Polyline(p),
                format!(
                    "isoline s_d = {level} at t = {} s (the last frame)",
                    crate::style::tick_label(t_last_s, 1.0)
                ),
            ))
        }
        TeamIsolineModel::None(_) => None,
    }
}

/// The steady window of a team's figure as the team metrics take it (att32g-1, -2): the time
/// of the metrics' first sample at or after the run's steady-state start step (its step plan's,
/// `metrics.steady_state_fraction` of `sim.duration_s`), the metrics sampling every step along
/// a circle and every `POLYLINE_METRICS_PERIOD_S` along an extracted isoline (`arc`), from step
/// 0. `None` when the run has no metrics sample in the window (a window shorter than the
/// sampling period): `summary.json`'s window quantities are then `null`. The window start
/// once was `(1 - f) T` in floating point, a hair after a vehicle's end at the metrics' first
/// window step, and the figure and `summary.json` disagreed on whether a vehicle was live in it.
pub fn metrics_window_start_s(scenario: &Scenario, arc: &FigureArc) -> Option<f64> {
    let plan = scenario.plan();
    let every = scenario
        .team_metrics_every_steps(matches!(arc, FigureArc::Circle(_)))
        .max(1);
    let k = plan
        .steady_state_start_step
        .div_ceil(every)
        .checked_mul(every)?;
    (k <= plan.n_steps).then_some(k as f64 * plan.dt_s)
}

/// Bins the isoline is cut into for the revisit-time figure.
pub const REVISIT_BINS: usize = 360;

/// A team's vehicles (one [`RunData`] each, in the listed order, rows at the same times) with
/// the isoline's arc-length projection.
pub struct TeamTracks<'a> {
    /// The vehicles.
    pub vehicles: &'a [RunData],
    /// The isoline ([`figure_isoline`]).
    pub arc: FigureArc,
    /// Its legend label (which isoline: for a field that moves, the last frame's).
    pub isoline_label: String,
    /// `+1` when the team travels towards increasing arc coordinate, `-1` otherwise (the sign
    /// of the summed arc motion).
    pub direction: f64,
    /// The recorded times: the rows of the vehicle with the most rows at the recorded times
    /// (every vehicle that completed the run has them all).
    pub rows: usize,
    /// Each vehicle's rows at the recorded times (`rows` for a vehicle that completed; fewer
    /// for one that ended early, whose rows stop at its own end: att32e-2/-6, the figure once
    /// stopped at the first vehicle's end).
    pub vehicle_rows: Vec<usize>,
    /// The vehicle whose rows give the recorded times.
    clock: usize,
}

impl<'a> TeamTracks<'a> {
    /// `None` when the scenario has no isoline to measure along ([`figure_isoline`]) or
    /// there is no vehicle or row.
    pub fn new(vehicles: &'a [RunData]) -> Option<Self> {
        let first = vehicles.first()?;
        // A vehicle that ended early may end on a row off the recorded times (its last valid
        // state, at the step it ended: att32d-14); the rows paired across vehicles are those
        // at the recorded times, the longest trace's. Each vehicle counts to its own end.
        let clock =
            (0..vehicles.len()).max_by_key(|&i| (vehicles[i].trace.len(), usize::MAX - i))?;
        let longest = &vehicles[clock];
        let vehicle_rows: Vec<usize> = vehicles
            .iter()
            .map(|v| {
                let c = v.trace.len();
                let on_schedule =
                    c == 0 || longest.trace.get(c - 1).map(|r| r.t_s) == Some(v.trace[c - 1].t_s);
                if on_schedule {
                    c
                } else {
                    c - 1
                }
            })
            .collect();
        let rows = vehicle_rows.iter().copied().max()?;
        let last = rows.checked_sub(1)?;
        let t_last = longest.trace[last].t_s;
        // Each vehicle's last position (its own end).
        let ends: Vec<Vec2> = vehicles
            .iter()
            .filter_map(|v| v.trace.last().map(|r| Vec2::new(r.x_m, r.y_m)))
            .collect();
        let (arc, isoline_label) = figure_isoline(&first.scenario, t_last, &ends)?;
        let l = arc.length_m();
        let closed = arc.is_closed();
        let mut sum = 0.0;
        for (v, &own) in vehicles.iter().zip(&vehicle_rows) {
            for w in v.trace[..own].windows(2) {
                if let (Some(a), Some(b)) = (s_of(&arc, &w[0]), s_of(&arc, &w[1])) {
                    sum += if closed { wrap_half(b - a, l) } else { b - a };
                }
            }
        }
        Some(Self {
            vehicles,
            arc,
            isoline_label,
            direction: if sum < 0.0 { -1.0 } else { 1.0 },
            rows,
            vehicle_rows,
            clock,
        })
    }

    /// The recorded time of row `k`, s.
    pub fn time_s(&self, k: usize) -> f64 {
        self.vehicles[self.clock].trace[k].t_s
    }

    /// The last vehicle's end, s: the latest of the vehicles' last rows (each at its own end,
    /// on the recorded times or off them), where the team figure's time axis ends (att32f-3:
    /// it ended at the gaps' last time, which stops once fewer than two vehicles are left).
    pub fn end_s(&self) -> f64 {
        self.vehicles
            .iter()
            .filter_map(|v| v.trace.last().map(|r| r.t_s))
            .fold(self.time_s(self.rows - 1), f64::max)
    }

    /// Whether the isoline is closed (else open: gaps and revisit times over the stretch the
    /// team covers, as `summary.json`'s `team.open_isoline`).
    pub fn is_closed(&self) -> bool {
        self.arc.is_closed()
    }

    /// The isoline's length `L`, m.
    pub fn length_m(&self) -> f64 {
        self.arc.length_m()
    }

    /// The arc coordinate of vehicle `i` at row `k`, measured along the travel, in `[0, L)`
    /// (on an open isoline in `[0, L]`, from the end the team travels away from).
    /// `None` also past the vehicle's own end.
    fn along(&self, i: usize, k: usize) -> Option<f64> {
        if k >= self.vehicle_rows[i] {
            return None;
        }
        let s = s_of(&self.arc, &self.vehicles[i].trace[k])?;
        Some(if self.is_closed() {
            (self.direction * s).rem_euclid(self.length_m())
        } else if self.direction < 0.0 {
            self.length_m() - s
        } else {
            s
        })
    }

    /// The gap ahead of each vehicle along the travel at every `stride`-th row, m:
    /// `(t, [gap of vehicle 0, 1, ...])` (the next vehicle ahead in the order along the
    /// isoline at that time; `O(N log N)` per row). On an open isoline the vehicle in front
    /// has none (NaN): no gap wraps around. A vehicle past its own end has none (NaN), and the
    /// others' gaps close around it, as the team's ring does.
    pub fn gaps(&self, stride: usize) -> Vec<(f64, Vec<f64>)> {
        let n = self.vehicles.len();
        let l = self.length_m();
        let mut out = Vec::new();
        let mut order: Vec<(f64, usize)> = Vec::with_capacity(n);
        for k in (0..self.rows).step_by(stride.max(1)) {
            order.clear();
            order.extend((0..n).filter_map(|i| self.along(i, k).map(|s| (s, i))));
            let live = self.vehicle_rows.iter().filter(|&&r| k < r).count();
            if order.len() != live || live < 2 {
                continue;
            }
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut g = vec![f64::NAN; n];
            let n = live;
            for p in 0..n {
                let (s, i) = order[p];
                let next = order[(p + 1) % n].0;
                g[i] = if p + 1 < n {
                    next - s
                } else if self.is_closed() {
                    next + l - s
                } else {
                    f64::NAN
                };
            }
            out.push((self.time_s(k), g));
        }
        out
    }

    /// The revisit time along the isoline over the steady window (from `t0_s`): for each of
    /// [`REVISIT_BINS`] equal arcs (centres in `[0, L)`, along the travel), its longest age over
    /// the window, the age being the time since a vehicle last entered it, that visit counted
    /// wherever it was (before the window too; a bin not entered yet counts from the first
    /// row), the open interval at the last row included (every bin crossed between two rows
    /// counts as visited at the later row), s: `summary.json`'s `revisit_time_max_s` is the
    /// largest of them (docs/TEAMS.md). On an open isoline, as its metrics: a bin counts while
    /// in the team's stretch (from the vehicle at the back to the one in front), so a bin's
    /// first visit ends an interval only if the first row's stretch held it, and the open
    /// interval at the last row counts for the last row's stretch; a bin the team never covered
    /// is NaN. Every bin is NaN when the team ended before the window (no vehicle's row in it:
    /// `summary.json`'s `revisit_time_max_s` is then `null`; att32f-3: the open interval at the
    /// last row was drawn as the bins' revisit time, a loop nobody flew "revisited within
    /// 0.3 s").
    pub fn revisit_max(&self, t0_s: f64) -> Vec<(f64, f64)> {
        let l = self.length_m();
        let bins = REVISIT_BINS;
        let width = l / bins as f64;
        let Some(last_row) = self.rows.checked_sub(1) else {
            return vec![];
        };
        if self.end_s() < t0_s {
            return (0..bins)
                .map(|j| ((j as f64 + 0.5) * width, f64::NAN))
                .collect();
        }
        let t_end = self.time_s(last_row);
        let t_start = self.time_s(0);
        let closed = self.is_closed();
        let bin_of = |s: f64| ((s / width).floor().max(0.0) as usize).min(bins - 1);
        // The bins between the vehicles at the back and in front at row `k` (open isoline).
        let stretch = |k: usize| -> Option<(usize, usize)> {
            let s: Vec<f64> = (0..self.vehicles.len())
                .filter_map(|i| self.along(i, k))
                .collect();
            let lo = s.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo <= hi).then(|| (bin_of(lo), bin_of(hi)))
        };
        let mut last = vec![if closed { t_start } else { f64::NAN }; bins];
        let mut worst = vec![if closed { 0.0f64 } else { f64::NAN }; bins];
        if !closed {
            if let Some((lo, hi)) = stretch(0) {
                last[lo..=hi].fill(t_start);
            }
        }
        for k in 1..self.rows {
            let t = self.time_s(k);
            let in_window = t >= t0_s;
            for i in 0..self.vehicles.len() {
                let (Some(a), Some(b)) = (self.along(i, k - 1), self.along(i, k)) else {
                    continue;
                };
                let d = if closed { wrap_half(b - a, l) } else { b - a };
                // Bins entered moving forward from a to a + d (a backward step enters none).
                if d <= 0.0 {
                    continue;
                }
                let first = (a / width).floor() as i64 + 1;
                let lastb = ((a + d) / width).floor() as i64;
                let lastb = if closed {
                    lastb
                } else {
                    lastb.min(bins as i64 - 1)
                };
                for j in first..=lastb.min(first + bins as i64 - 1) {
                    let j = j.rem_euclid(bins as i64) as usize;
                    // (`f64::max` keeps the number over a NaN: a bin's first interval.)
                    if in_window && !last[j].is_nan() {
                        worst[j] = worst[j].max(t - last[j]);
                    }
                    last[j] = t;
                }
            }
        }
        let open_end = if closed {
            Some((0, bins - 1))
        } else {
            stretch(self.rows - 1)
        };
        (0..bins)
            .map(|j| {
                let w = match open_end {
                    Some((lo, hi)) if (lo..=hi).contains(&j) && !last[j].is_nan() => {
                        worst[j].max(t_end - last[j])
                    }
                    _ => worst[j],
                };
                ((j as f64 + 0.5) * width, w)
            })
            .collect()
    }
}

/// The arc coordinate of a trace row (`None`: no finite position, or the circle's centre).
fn s_of(arc: &dyn ArcProjection, t: &isotrack_sim::TraceRow) -> Option<f64> {
    if !(t.x_m.is_finite() && t.y_m.is_finite()) {
        return None;
    }
    arc.project(Vec2::new(t.x_m, t.y_m)).map(|p| p.s_m)
}

/// `d` wrapped into `(-L/2, L/2]`.
fn wrap_half(d: f64, l: f64) -> f64 {
    let r = d.rem_euclid(l);
    if r > 0.5 * l {
        r - l
    } else {
        r
    }
}
