//! Team metrics along the true isoline (ground truth, for the summary only): the spread of the
//! arc-length gaps, the time the team takes to spread evenly, how long points of the isoline go
//! unvisited, the closest approach and whether the order along the isoline held.
//!
//! Sampled every `every_steps` steps (the cost is a sort of the `N` arc coordinates, `O(N log N)`
//! per sample, plus the revisit bins each vehicle crossed).

use super::arc::{wrap_arc, ArcProjection};
use isotrack_core::Vec2;
use serde::Serialize;

/// Team metrics settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TeamMetricsConfig {
    /// Sample the team every this many steps (>= 1).
    pub every_steps: u64,
    /// First step of the steady-state window (the runs' plan's).
    pub steady_state_start_step: u64,
    /// `gap_cv` at or below which the team counts as evenly spread, for `time_to_even_s`.
    pub even_gap_cv: f64,
    /// Number of equal arcs the isoline is cut into for the revisit times (>= 1).
    pub revisit_bins: usize,
}

impl Default for TeamMetricsConfig {
    /// Every step, the window from step 0, evenly spread at `gap_cv <= 0.05`, 720 bins.
    fn default() -> Self {
        Self {
            every_steps: 1,
            steady_state_start_step: 0,
            even_gap_cv: 0.05,
            revisit_bins: 720,
        }
    }
}

/// The team's summary (the `team` object of `summary.json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TeamSummary {
    /// Vehicles in the team.
    pub count: usize,
    /// Length of the isoline, m.
    pub isoline_length_m: f64,
    /// Mean over the steady window's samples of the coefficient of variation (population
    /// standard deviation over mean) of the arc-length gaps between consecutive vehicles along
    /// the isoline (0: evenly spread). `None` without a sample in the window.
    pub gap_cv: Option<f64>,
    /// The gap CV at the last sample.
    pub gap_cv_final: Option<f64>,
    /// First sample time from which the gap CV stays at or below `even_gap_cv` to the end
    /// (`None`: not evenly spread at the end).
    pub time_to_even_s: Option<f64>,
    /// Longest age of a point of the isoline over the steady window, s: the age is the time
    /// since a vehicle last passed the point, that pass counted wherever it was (before the
    /// window too), and a point not passed yet counts from the run's start. So an interval
    /// between passes that ends in the window counts whole, as does the open one at the run's
    /// end; a window shorter than the interval between passes does not censor it.
    pub revisit_time_max_s: Option<f64>,
    /// Mean time between consecutive passes over a point of the isoline, over the passes in the
    /// steady window, each measured back to the pass before it wherever that was (before the
    /// window too), s. `None` when no pass in the window had one before it.
    pub revisit_time_mean_s: Option<f64>,
    /// The ideal revisit time of an evenly spread team at the nominal speed, `L/(N v0)`, s.
    pub revisit_time_ideal_s: f64,
    /// Smallest distance between vehicles consecutive along the isoline over the samples, m
    /// (consecutive pairs only: `O(N)` per sample; on a simple isoline the closest pair is
    /// consecutive unless vehicles are far off it).
    pub min_separation_m: Option<f64>,
    /// Whether the cyclic order of the vehicles along the isoline at every steady-window sample
    /// was the order at the window's first sample (no overtaking once settled).
    pub order_preserved: bool,
    /// Slowest and fastest speed any vehicle held at a sample, m/s.
    pub speed_range_mps: Option<[f64; 2]>,
    /// For an isoline that moves (left out otherwise): how it was followed. `isoline_length_m`
    /// is then the mean of its length over the samples, and `revisit_time_ideal_s` uses it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moving_isoline: Option<MovingIsolineStats>,
}

/// How the team metrics followed an isoline that moves (`summary.json`'s
/// `team.moving_isoline`).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct MovingIsolineStats {
    /// Times the isoline was extracted (once per frame or period, not per sample).
    pub extractions: u64,
    /// Shortest and longest length of the isoline over the samples, m (`null`: none).
    pub length_range_m: Option<[f64; 2]>,
    /// Samples without an isoline to measure along (none closed, or the field ended): left
    /// out of every metric.
    pub samples_without_isoline: u64,
}

/// The streaming team metrics.
#[derive(Clone, Debug)]
pub struct TeamMetrics {
    cfg: TeamMetricsConfig,
    n: usize,
    length_m: f64,
    nominal_speed_mps: f64,
    countdown: u64,
    dt_s: f64,
    // Scratch: (s, id) of the vehicles projected at a sample.
    scratch: Vec<(f64, u32)>,
    cv_sum: f64,
    cv_count: u64,
    cv_last: Option<f64>,
    /// Time of the first sample of the current run of samples at or below `even_gap_cv`.
    even_since: Option<f64>,
    last_s: Vec<f64>,
    /// Per bin: time of the last pass, over the whole run (NaN: none yet).
    bin_last: Vec<f64>,
    revisit_max: f64,
    revisit_sum: f64,
    revisit_count: u64,
    min_sep: f64,
    order_ref: Option<Vec<u32>>,
    order_ok: bool,
    speed_min: f64,
    speed_max: f64,
    t_last: f64,
    t_window: Option<f64>,
    /// The isoline's length at the last sample (the arc coordinates in `last_s` are on it).
    last_l: f64,
    /// Whether the isoline moves (its length per sample, [`MovingIsolineStats`]).
    moving: bool,
    len_sum: f64,
    len_count: u64,
    len_min: f64,
    len_max: f64,
    extractions: u64,
    skipped: u64,
    /// The isoline was extracted again since the last sample: the last sample's positions are
    /// projected onto the new one (a new loop's arc coordinates differ by more than a rescale).
    reproject: bool,
    last_p: Vec<Vec2>,
}

impl TeamMetrics {
    /// The speed of the ideal revisit time `L/(N v)`: for vehicles of unequal nominal speeds
    /// `v0_i`, their mean (an evenly spread team at the common speed `mean v0_i` passes a point
    /// every `L/sum v0_i`; so does, on average, a team at its own speeds, each vehicle passing
    /// a point every `L/v0_i`).
    pub fn set_nominal_speed(&mut self, speed_mps: f64) {
        self.nominal_speed_mps = speed_mps;
    }

    /// Metrics for `n` vehicles on an isoline of `length_m`, steps of `dt_s`, nominal speed
    /// `nominal_speed_mps` (for the ideal revisit time).
    pub fn new(
        cfg: TeamMetricsConfig,
        n: usize,
        length_m: f64,
        dt_s: f64,
        nominal_speed_mps: f64,
    ) -> Self {
        let cfg = TeamMetricsConfig {
            every_steps: cfg.every_steps.max(1),
            revisit_bins: cfg.revisit_bins.max(1),
            ..cfg
        };
        Self {
            n,
            length_m,
            nominal_speed_mps,
            countdown: 0,
            dt_s,
            scratch: Vec::with_capacity(n),
            cv_sum: 0.0,
            cv_count: 0,
            cv_last: None,
            even_since: None,
            last_s: vec![f64::NAN; n],
            bin_last: vec![f64::NAN; cfg.revisit_bins],
            revisit_max: 0.0,
            revisit_sum: 0.0,
            revisit_count: 0,
            min_sep: f64::INFINITY,
            order_ref: None,
            order_ok: true,
            speed_min: f64::INFINITY,
            speed_max: f64::NEG_INFINITY,
            t_last: 0.0,
            t_window: None,
            last_l: length_m,
            moving: false,
            len_sum: 0.0,
            len_count: 0,
            len_min: f64::INFINITY,
            len_max: f64::NEG_INFINITY,
            extractions: 0,
            skipped: 0,
            reproject: false,
            last_p: vec![Vec2::new(f64::NAN, f64::NAN); n],
            cfg,
        }
    }

    /// Metrics along an isoline that moves: the isoline passed to each
    /// [`observe`](Self::observe) may differ (its length, its arc coordinates); the arc
    /// coordinates of the last sample are rescaled to the new length, the bins of the revisit
    /// times are fractions of the length, `isoline_length_m` is the mean length.
    pub fn moving(mut self) -> Self {
        self.moving = true;
        self
    }

    /// Counts one extraction of a moving isoline: at the next sample, the passes since the last
    /// one are measured from the last sample's positions projected onto the new isoline (not
    /// from their arc coordinates on the old one, which a new extraction shifts: each shift
    /// would count as passes).
    pub fn extracted(&mut self) {
        self.extractions += 1;
        self.reproject = true;
    }

    /// A sample at step `k` without an isoline to measure along: it counts for nothing, and
    /// no vehicle's passes are followed across it.
    pub fn skip(&mut self, k: u64) {
        self.t_last = k as f64 * self.dt_s;
        self.skipped += 1;
        self.last_s.iter_mut().for_each(|s| *s = f64::NAN);
    }

    /// Whether step `k` is a metrics sample (call [`observe`](Self::observe) then).
    #[inline(always)]
    pub fn due(&mut self) -> bool {
        if self.countdown == 0 {
            self.countdown = self.cfg.every_steps - 1;
            true
        } else {
            self.countdown -= 1;
            false
        }
    }

    /// One sample at step `k`: `positions[i]` and `speeds[i]` of vehicle `i`, `alive[i]` whether
    /// its run goes on.
    pub fn observe(
        &mut self,
        k: u64,
        arc: &dyn ArcProjection,
        positions: &[Vec2],
        speeds: &[f64],
        alive: &[bool],
    ) {
        let t = k as f64 * self.dt_s;
        self.t_last = t;
        let in_window = k >= self.cfg.steady_state_start_step;
        if in_window && self.t_window.is_none() {
            self.t_window = Some(t);
        }
        let l = if self.moving {
            arc.length_m()
        } else {
            self.length_m
        };
        if self.moving {
            self.len_sum += l;
            self.len_count += 1;
            self.len_min = self.len_min.min(l);
            self.len_max = self.len_max.max(l);
        }
        // The last sample's arc coordinates on this sample's isoline (the same when it does
        // not move).
        let rescale = (self.last_l != l).then(|| l / self.last_l);
        self.last_l = l;
        let reproject = core::mem::take(&mut self.reproject);
        let m = self.cfg.revisit_bins;
        let bin = |s: f64| ((s / l * m as f64) as usize).min(m - 1);
        self.scratch.clear();
        for i in 0..self.n {
            if !alive[i] {
                self.last_s[i] = f64::NAN;
                continue;
            }
            self.speed_min = self.speed_min.min(speeds[i]);
            self.speed_max = self.speed_max.max(speeds[i]);
            let Some(a) = arc.project(positions[i]) else {
                self.last_s[i] = f64::NAN;
                continue;
            };
            let s = a.s_m;
            self.scratch.push((s, i as u32));
            let prev = if reproject && !self.last_s[i].is_nan() {
                arc.project(self.last_p[i]).map_or(f64::NAN, |a| a.s_m)
            } else {
                match rescale {
                    Some(r) => (self.last_s[i] * r).min(l.next_down()),
                    None => self.last_s[i],
                }
            };
            self.last_s[i] = s;
            if self.moving {
                self.last_p[i] = positions[i];
            }
            if prev.is_nan() {
                continue;
            }
            // The bins entered between the last sample and this one (the shorter way round).
            let d = wrap_arc(s - prev + 0.5 * l, l) - 0.5 * l;
            let (b0, b1) = (bin(prev), bin(s));
            if b0 == b1 {
                continue;
            }
            let forward = d > 0.0;
            let mut b = b0;
            loop {
                b = if forward {
                    (b + 1) % m
                } else {
                    (b + m - 1) % m
                };
                // Before the window a pass only dates the bin's last visit; in it, the
                // interval it ends counts whole (its start may be before the window), and a
                // bin not passed before counts from the run's start (t = 0).
                let last = self.bin_last[b];
                if in_window {
                    if last.is_nan() {
                        self.revisit_max = self.revisit_max.max(t);
                    } else {
                        let gap = t - last;
                        self.revisit_max = self.revisit_max.max(gap);
                        self.revisit_sum += gap;
                        self.revisit_count += 1;
                    }
                }
                self.bin_last[b] = t;
                if b == b1 {
                    break;
                }
            }
        }
        let count = self.scratch.len();
        if count < 2 {
            return;
        }
        self.scratch
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mean = l / count as f64;
        let mut var = 0.0;
        for j in 0..count {
            let (s0, i0) = self.scratch[j];
            let (s1, i1) = self.scratch[(j + 1) % count];
            let g = if j + 1 == count { s1 + l - s0 } else { s1 - s0 };
            var += (g - mean) * (g - mean);
            let sep = (positions[i1 as usize] - positions[i0 as usize]).norm();
            self.min_sep = self.min_sep.min(sep);
        }
        let cv = (var / count as f64).sqrt() / mean;
        self.cv_last = Some(cv);
        if cv <= self.cfg.even_gap_cv {
            self.even_since.get_or_insert(t);
        } else {
            self.even_since = None;
        }
        if in_window {
            self.cv_sum += cv;
            self.cv_count += 1;
            self.check_order();
        }
    }

    /// Compares the cyclic order of the vehicles along the isoline with the window's first.
    fn check_order(&mut self) {
        let now: Vec<u32> = self.scratch.iter().map(|&(_, i)| i).collect();
        let Some(reference) = &self.order_ref else {
            self.order_ref = Some(now);
            return;
        };
        // The reference restricted to the vehicles present now, compared cyclically.
        let present: Vec<u32> = reference
            .iter()
            .copied()
            .filter(|i| now.contains(i))
            .collect();
        if present.len() != now.len() || present.is_empty() {
            self.order_ok = false;
            return;
        }
        let Some(shift) = now.iter().position(|&i| i == present[0]) else {
            self.order_ok = false;
            return;
        };
        let n = now.len();
        if (0..n).any(|j| now[(shift + j) % n] != present[j]) {
            self.order_ok = false;
        }
    }

    /// The summary.
    pub fn finish(&self) -> TeamSummary {
        let l = if self.moving {
            if self.len_count > 0 {
                self.len_sum / self.len_count as f64
            } else {
                f64::NAN
            }
        } else {
            self.length_m
        };
        let (revisit_max, revisit_mean) = match self.t_window {
            Some(_) => {
                // The open interval at the run's end: the age of each bin then (from the run's
                // start for a bin never passed).
                let mut mx = self.revisit_max;
                for &last in &self.bin_last {
                    let open = if last.is_nan() {
                        self.t_last
                    } else {
                        self.t_last - last
                    };
                    mx = mx.max(open);
                }
                let mean =
                    (self.revisit_count > 0).then(|| self.revisit_sum / self.revisit_count as f64);
                (Some(mx), mean)
            }
            None => (None, None),
        };
        TeamSummary {
            count: self.n,
            isoline_length_m: l,
            gap_cv: (self.cv_count > 0).then(|| self.cv_sum / self.cv_count as f64),
            gap_cv_final: self.cv_last,
            time_to_even_s: self.even_since,
            revisit_time_max_s: revisit_max,
            revisit_time_mean_s: revisit_mean,
            revisit_time_ideal_s: l / (self.n as f64 * self.nominal_speed_mps),
            min_separation_m: self.min_sep.is_finite().then_some(self.min_sep),
            order_preserved: self.order_ok,
            speed_range_mps: (self.speed_min <= self.speed_max)
                .then_some([self.speed_min, self.speed_max]),
            moving_isoline: self.moving.then(|| MovingIsolineStats {
                extractions: self.extractions,
                length_range_m: (self.len_min <= self.len_max)
                    .then_some([self.len_min, self.len_max]),
                samples_without_isoline: self.skipped,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::team::arc::CircleArc;
    use std::f64::consts::PI;

    /// Four points moving rigidly round a circle of radius 10 at 1 m/s, at arc positions 0, 10,
    /// 20, 40 (gaps 10, 10, 20, L - 40): the CV is the gaps' by hand; the revisit time of a point
    /// is the time between consecutive points passing it, its maximum the largest gap / v.
    #[test]
    fn rigid_rotation_by_hand() {
        let r = 10.0;
        let arc = CircleArc {
            center_m: Vec2::new(0.0, 0.0),
            radius_m: r,
        };
        let l = 2.0 * PI * r;
        let offs = [0.0, 10.0, 20.0, 40.0];
        let dt = 0.01;
        let cfg = TeamMetricsConfig {
            every_steps: 1,
            steady_state_start_step: 0,
            even_gap_cv: 0.05,
            revisit_bins: 360,
        };
        let mut m = TeamMetrics::new(cfg, 4, l, dt, 1.0);
        let steps = 50_000u64; // 500 s: eight laps.
        for k in 0..=steps {
            let t = k as f64 * dt;
            let pos: Vec<Vec2> = offs
                .iter()
                .map(|o| {
                    let th = (o + t) / r;
                    Vec2::new(r * th.cos(), r * th.sin())
                })
                .collect();
            if m.due() {
                m.observe(k, &arc, &pos, &[1.0; 4], &[true; 4]);
            }
        }
        let s = m.finish();
        let gaps = [10.0, 10.0, 20.0, l - 40.0];
        let mean = l / 4.0;
        let cv = (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / 4.0).sqrt() / mean;
        assert!(
            (s.gap_cv.unwrap() - cv).abs() < 1e-9,
            "{:?} vs {cv}",
            s.gap_cv
        );
        // Max revisit: the largest gap over v (a bin's passes are one bin-crossing apart at most).
        let bin_t = l / 360.0;
        let mx = s.revisit_time_max_s.unwrap();
        assert!((mx - (l - 40.0)).abs() < bin_t + 0.02, "{mx}");
        // Mean over passes: every point sees each gap once per lap, so the mean is L/4 / v.
        let mean_t = s.revisit_time_mean_s.unwrap();
        assert!((mean_t - l / 4.0).abs() < 0.5, "{mean_t}");
        assert!((s.revisit_time_ideal_s - l / 4.0).abs() < 1e-12);
        // Closest: the chord of the 10 m gaps.
        let chord = 2.0 * r * (10.0 / (2.0 * r)).sin();
        assert!((s.min_separation_m.unwrap() - chord).abs() < 1e-9);
        assert!(s.order_preserved);
        assert_eq!(s.time_to_even_s, None);
        assert_eq!(s.speed_range_mps, Some([1.0, 1.0]));
    }

    /// Four points evenly spread, rotating rigidly at `w` on a circle whose radius grows
    /// linearly from 10 to 20 m (a moving isoline): the gaps stay even (CV 0), a point of the
    /// isoline is passed every `2 pi/(4 w)` s whatever the radius (its bins are fractions of
    /// the length), the length is the mean over the samples. A sample without an isoline (the
    /// last) counts for nothing.
    #[test]
    fn a_growing_circle() {
        let w = 0.05;
        let dt = 0.1;
        let steps = 4000u64; // 400 s: 3.2 laps.
        let radius = |t: f64| 10.0 + 10.0 * t / 400.0;
        let mut m = TeamMetrics::new(TeamMetricsConfig::default(), 4, f64::NAN, dt, 1.0).moving();
        for k in 0..=steps {
            let t = k as f64 * dt;
            let r = radius(t);
            let arc = CircleArc {
                center_m: Vec2::new(0.0, 0.0),
                radius_m: r,
            };
            let pos: Vec<Vec2> = (0..4)
                .map(|i| {
                    let th = w * t + 0.5 * PI * i as f64;
                    Vec2::new(r * th.cos(), r * th.sin())
                })
                .collect();
            if k == steps {
                m.skip(k);
                continue;
            }
            if k % 10 == 0 {
                m.extracted();
            }
            m.observe(k, &arc, &pos, &[1.0; 4], &[true; 4]);
        }
        let s = m.finish();
        assert!(s.gap_cv.unwrap() < 1e-9, "{:?}", s.gap_cv);
        let period = 2.0 * PI / (4.0 * w);
        // Not asserted: the mean revisit time (29.87 s measured against 31.42 s, 5 % short:
        // an open question, see the issue-32 report).
        // The longest: a lap's quarter, or the open interval at the window's start (a bin
        // first passed a quarter lap in), one sample either way.
        let mx = s.revisit_time_max_s.unwrap();
        assert!((mx - period).abs() < 2.0 * dt + 1e-9, "{mx} vs {period}");
        // The mean of 2 pi r over the samples observed (the last one skipped).
        let mean_l = (0..steps)
            .map(|k| 2.0 * PI * radius(k as f64 * dt))
            .sum::<f64>()
            / steps as f64;
        assert!(
            (s.isoline_length_m - mean_l).abs() < 1e-9,
            "{}",
            s.isoline_length_m
        );
        let st = s.moving_isoline.unwrap();
        assert_eq!(st.samples_without_isoline, 1);
        assert_eq!(st.extractions, 400);
        let [lo, hi] = st.length_range_m.unwrap();
        let last = 2.0 * PI * radius((steps - 1) as f64 * dt);
        assert!((lo - 20.0 * PI).abs() < 1e-9 && (hi - last).abs() < 1e-9);
        assert!((s.revisit_time_ideal_s - mean_l / 4.0).abs() < 1e-9);
    }

    /// Issue 32, att32 F2: a perfectly even team of `N` at `v` on a circle of length `L`, its
    /// steady window (10 s) far shorter than the interval between passes `L/(N v)` (31.4 s):
    /// every point's age since its last pass (that pass before the window or in it) peaks at
    /// `L/(N v)` just before the next, so the longest revisit time is `L/(N v)` and every pass
    /// in the window ends an interval of `L/(N v)` (the mean), to a bin's crossing time `L/(M v)`
    /// plus a sample. A window measuring only passes inside it saw no point passed twice.
    #[test]
    fn a_window_shorter_than_the_revisit_interval_is_not_censored() {
        let r = 20.0;
        let arc = CircleArc {
            center_m: Vec2::new(0.0, 0.0),
            radius_m: r,
        };
        let (n, v, dt) = (4usize, 1.0, 0.05);
        let l = 2.0 * PI * r;
        let ideal = l / (n as f64 * v);
        let cfg = TeamMetricsConfig {
            every_steps: 2,
            steady_state_start_step: 1800, // 90 s into a 100 s run
            even_gap_cv: 0.05,
            revisit_bins: 720,
        };
        let mut m = TeamMetrics::new(cfg, n, l, dt, v);
        for k in 0..=2000u64 {
            let t = k as f64 * dt;
            let pos: Vec<Vec2> = (0..n)
                .map(|i| {
                    let th = v * t / r + 2.0 * PI * i as f64 / n as f64;
                    Vec2::new(r * th.cos(), r * th.sin())
                })
                .collect();
            if m.due() {
                m.observe(k, &arc, &pos, &[v; 4], &[true; 4]);
            }
        }
        let s = m.finish();
        let tol = l / (720.0 * v) + 2.0 * dt + 1e-9;
        let mx = s.revisit_time_max_s.unwrap();
        assert!((mx - ideal).abs() <= tol, "max {mx} vs L/(N v) = {ideal}");
        let mean = s
            .revisit_time_mean_s
            .expect("passes in the window measured back");
        assert!(
            (mean - ideal).abs() <= tol,
            "mean {mean} vs L/(N v) = {ideal}"
        );
        assert!((s.revisit_time_ideal_s - ideal).abs() < 1e-12);
    }

    /// Two points swapping order mid-window: not preserved; evenly spread from t = 0: 0.
    #[test]
    fn order_and_even() {
        let arc = CircleArc {
            center_m: Vec2::new(0.0, 0.0),
            radius_m: 1.0,
        };
        let mut m = TeamMetrics::new(TeamMetricsConfig::default(), 3, 2.0 * PI, 1.0, 1.0);
        let at = |th: f64| Vec2::new(th.cos(), th.sin());
        let third = 2.0 * PI / 3.0;
        for k in 0..3u64 {
            let p = [at(0.0), at(third), at(2.0 * third)];
            m.observe(k, &arc, &p, &[1.0; 3], &[true; 3]);
        }
        assert_eq!(m.finish().time_to_even_s, Some(0.0));
        assert!(m.finish().order_preserved);
        let p = [at(0.0), at(2.0 * third + 0.1), at(third)];
        m.observe(3, &arc, &p, &[1.0; 3], &[true; 3]);
        assert!(!m.finish().order_preserved);
        assert!(m.finish().gap_cv.unwrap() > 0.0);
    }
}
