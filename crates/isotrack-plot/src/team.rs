//! A team's run read back for its figures (issue 32, docs/TEAMS.md): the vehicles' arc
//! coordinates along the true isoline from the trace (never by re-simulating), the gap ahead of
//! each vehicle over time and the revisit time along the isoline.

use crate::run_data::RunData;
use isotrack_core::Vec2;
use isotrack_sim::team::arc::{ArcProjection, CircleArc};

/// Bins the isoline is cut into for the revisit-time figure.
pub const REVISIT_BINS: usize = 360;

/// A team's vehicles (one [`RunData`] each, in the listed order, rows at the same times) with
/// the isoline's arc-length projection.
pub struct TeamTracks<'a> {
    /// The vehicles.
    pub vehicles: &'a [RunData],
    /// The isoline: a circle (`Scenario::team_arc`).
    pub arc: CircleArc,
    /// `+1` when the team travels towards increasing arc coordinate, `-1` otherwise (the sign
    /// of the summed arc motion).
    pub direction: f64,
    /// The common number of rows.
    pub rows: usize,
}

impl<'a> TeamTracks<'a> {
    /// `None` when the isoline is not a known circle or there is no vehicle.
    pub fn new(vehicles: &'a [RunData]) -> Option<Self> {
        let first = vehicles.first()?;
        let arc = first.scenario.team_arc()?;
        let rows = vehicles.iter().map(|v| v.trace.len()).min()?;
        let l = arc.length_m();
        let mut sum = 0.0;
        for v in vehicles {
            for w in v.trace[..rows].windows(2) {
                if let (Some(a), Some(b)) = (s_of(&arc, &w[0]), s_of(&arc, &w[1])) {
                    sum += wrap_half(b - a, l);
                }
            }
        }
        Some(Self {
            vehicles,
            arc,
            direction: if sum < 0.0 { -1.0 } else { 1.0 },
            rows,
        })
    }

    /// The isoline's length `L`, m.
    pub fn length_m(&self) -> f64 {
        self.arc.length_m()
    }

    /// The arc coordinate of vehicle `i` at row `k`, measured along the travel, in `[0, L)`.
    fn along(&self, i: usize, k: usize) -> Option<f64> {
        let s = s_of(&self.arc, &self.vehicles[i].trace[k])?;
        Some((self.direction * s).rem_euclid(self.length_m()))
    }

    /// The gap ahead of each vehicle along the travel at every `stride`-th row, m:
    /// `(t, [gap of vehicle 0, 1, ...])` (the next vehicle ahead in the order along the
    /// isoline at that time; `O(N log N)` per row).
    pub fn gaps(&self, stride: usize) -> Vec<(f64, Vec<f64>)> {
        let n = self.vehicles.len();
        let l = self.length_m();
        let mut out = Vec::new();
        let mut order: Vec<(f64, usize)> = Vec::with_capacity(n);
        for k in (0..self.rows).step_by(stride.max(1)) {
            order.clear();
            order.extend((0..n).filter_map(|i| self.along(i, k).map(|s| (s, i))));
            if order.len() != n || n < 2 {
                continue;
            }
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut g = vec![0.0; n];
            for p in 0..n {
                let (s, i) = order[p];
                let next = order[(p + 1) % n].0;
                g[i] = if p + 1 == n { next + l - s } else { next - s };
            }
            out.push((self.vehicles[0].trace[k].t_s, g));
        }
        out
    }

    /// The revisit time along the isoline over the steady window (from `t0_s`): for each of
    /// [`REVISIT_BINS`] equal arcs (centres in `[0, L)`, along the travel), its longest age over
    /// the window, the age being the time since a vehicle last entered it, that visit counted
    /// wherever it was (before the window too; a bin not entered yet counts from the first
    /// row), the open interval at the last row included (every bin crossed between two rows
    /// counts as visited at the later row), s: `summary.json`'s `revisit_time_max_s` is the
    /// largest of them (docs/TEAMS.md).
    pub fn revisit_max(&self, t0_s: f64) -> Vec<(f64, f64)> {
        let l = self.length_m();
        let bins = REVISIT_BINS;
        let width = l / bins as f64;
        let Some(t_end) = self.vehicles[0]
            .trace
            .get(self.rows.wrapping_sub(1))
            .map(|t| t.t_s)
        else {
            return vec![];
        };
        let t_start = self.vehicles[0].trace[0].t_s;
        let mut last = vec![t_start; bins];
        let mut worst = vec![0.0f64; bins];
        for k in 1..self.rows {
            let t = self.vehicles[0].trace[k].t_s;
            let in_window = t >= t0_s;
            for i in 0..self.vehicles.len() {
                let (Some(a), Some(b)) = (self.along(i, k - 1), self.along(i, k)) else {
                    continue;
                };
                let d = wrap_half(b - a, l);
                // Bins entered moving forward from a to a + d (a backward step enters none).
                if d <= 0.0 {
                    continue;
                }
                let first = (a / width).floor() as i64 + 1;
                let lastb = ((a + d) / width).floor() as i64;
                for j in first..=lastb.min(first + bins as i64 - 1) {
                    let j = j.rem_euclid(bins as i64) as usize;
                    if in_window {
                        worst[j] = worst[j].max(t - last[j]);
                    }
                    last[j] = t;
                }
            }
        }
        (0..bins)
            .map(|j| ((j as f64 + 0.5) * width, worst[j].max(t_end - last[j])))
            .collect()
    }
}

/// The arc coordinate of a trace row (`None`: no finite position, or the circle's centre).
fn s_of(arc: &CircleArc, t: &isotrack_sim::TraceRow) -> Option<f64> {
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
