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

/// Most revisit bins along an open isoline ([`open_revisit_bins`]): 2^20 (16 MiB of bin
/// state), whatever the isoline's length.
pub const MAX_OPEN_REVISIT_BINS: usize = 1 << 20;

/// The revisit bins along an open isoline of `length_m`: each at most `step_m` long (what a
/// vehicle at its nominal speed moves in one metrics sample, so a bin's crossing time is at
/// most a sample), at least `min_bins`, at most [`MAX_OPEN_REVISIT_BINS`]. An open isoline
/// runs to the field's edge (or the box the team can reach), mostly ground the team never
/// covers, so a fixed count of bins over its length would blur the revisit times of the
/// stretch it does cover as the field (or the run) grows. `min_bins` for a step that is not
/// positive and finite.
pub fn open_revisit_bins(length_m: f64, step_m: f64, min_bins: usize) -> usize {
    let want = length_m / step_m;
    if !(want.is_finite() && want > 0.0) {
        return min_bins.max(1);
    }
    (want.ceil() as usize).clamp(min_bins.max(1), MAX_OPEN_REVISIT_BINS.max(min_bins))
}

/// A distance between two vehicles below which a team run warns (nu39-3): closer than this,
/// real robots or aircraft collide (the model's vehicles are points and pass through each
/// other), m. A team whose vehicles are larger reads `min_separation_m` against its own.
pub const CLOSE_APPROACH_M: f64 = 0.5;

/// The closest approach of two vehicles consecutive along the isoline
/// ([`TeamSummary::min_separation_m`]): when and which.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestApproach {
    /// Distance between them, m.
    pub distance_m: f64,
    /// Time of the approach, s (between two samples when it was reached between them).
    pub t_s: f64,
    /// The two vehicles' indices in the listed order, the smaller first.
    pub pair: [u32; 2],
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
    /// The gap CV at the last sample (`None` when that sample has none: fewer than two
    /// vehicles live on a closed isoline, fewer than three on an open one).
    pub gap_cv_final: Option<f64>,
    /// First sample time from which the gap CV stays at or below `even_gap_cv` to the end
    /// (`None`: not evenly spread at the end, which a sample without a gap CV is not: the
    /// team then has no gaps to be even).
    pub time_to_even_s: Option<f64>,
    /// Longest age of a point of the isoline over the steady window, s: the age is the time
    /// since a vehicle last passed the point, that pass counted wherever it was (before the
    /// window too), and a point not passed yet counts from the run's start. So an interval
    /// between passes that ends in the window counts whole, as does the open one at the run's
    /// end; a window shorter than the interval between passes does not censor it. `None`
    /// without a steady-window sample at which a vehicle was live.
    pub revisit_time_max_s: Option<f64>,
    /// Mean time between consecutive passes over a point of the isoline, over the passes in the
    /// steady window, each measured back to the pass before it wherever that was (before the
    /// window too), s. `None` when no pass in the window had one before it.
    pub revisit_time_mean_s: Option<f64>,
    /// The ideal revisit time of an evenly spread team at the nominal speed, `L/(N v0)`, s
    /// (every vehicle of the team, gone or not: the team as deployed).
    pub revisit_time_ideal_s: f64,
    /// The ideal revisit time of the vehicles whose runs went on, over the steady window:
    /// `L / mean_k(sum of v0_i over the vehicles live at sample k)`, s (`L/(N_active v0)` with
    /// one nominal speed and the same vehicles live throughout the window). Present only when a
    /// vehicle's run had ended at a steady-window sample (a closed isoline); then
    /// `revisit_time_mean_s` is to be compared with it, not with `revisit_time_ideal_s`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub revisit_time_ideal_active_s: Option<f64>,
    /// Smallest distance between vehicles consecutive along the isoline, m, at the samples and
    /// between them (each vehicle along the straight segment between its two samples: a pass
    /// between samples counts, att41-4), consecutive pairs only: `O(N)` per sample; on a
    /// simple isoline the closest pair is consecutive unless vehicles are far off it.
    pub min_separation_m: Option<f64>,
    /// Where `min_separation_m` was reached: the first time it was (not in
    /// `summary.json`: the run's warning names it, [`CLOSE_APPROACH_M`]).
    #[serde(skip)]
    pub closest_approach: Option<ClosestApproach>,
    /// Whether the cyclic order of the vehicles along the isoline at every steady-window sample
    /// was the order at the window's first sample (no overtaking once settled).
    pub order_preserved: bool,
    /// Slowest and fastest speed any vehicle held at a sample, m/s.
    pub speed_range_mps: Option<[f64; 2]>,
    /// For an isoline that moves (left out otherwise): how it was followed. `isoline_length_m`
    /// is then the mean of its length over the samples, and `revisit_time_ideal_s` uses it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub moving_isoline: Option<MovingIsolineStats>,
    /// For an open isoline (one that leaves the field; left out for a closed one): the stretch
    /// the team covers. The gaps are then those between consecutive vehicles along the curve
    /// only (no wrap-around gap), the revisit times are over the points inside the stretch,
    /// and `revisit_time_ideal_s` is the stretch's ([`OpenIsolineStats`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub open_isoline: Option<OpenIsolineStats>,
}

/// How the team metrics measured along an open isoline (`summary.json`'s
/// `team.open_isoline`): one that leaves the field (a front or a plume edge crossing a grid,
/// a planar field's line), with two ends and no wrap-around.
///
/// Definitions (docs/TEAMS.md "Open isolines"): at a sample the live vehicles' arc
/// coordinates sorted along the curve, `s_(1) <= ... <= s_(n)`; the team's **stretch** is
/// `[s_(1), s_(n)]`, of length `S = s_(n) - s_(1)`; the **gaps** are
/// `g_j = s_(j+1) - s_(j)`, `j = 1..n-1` (no gap from the last vehicle back to the first);
/// `gap_cv` is their population standard deviation over their mean `S/(n-1)` (at least two
/// gaps: three vehicles). A point of the curve counts for the revisit times while it lies in
/// the stretch: an interval between two passes over it counts whole, as on a closed isoline;
/// the first pass over a point the team has not covered yet (the vehicle in front entering new
/// ground) ends no interval; a point inside the first sample's stretch not passed yet counts
/// from the run's start; at the run's end the points in the final stretch count their age.
/// The ideal revisit time is the mean gap over the steady window's samples over the nominal
/// speed, `mean_k(S_k/(n_k - 1))/v0`: the interval between passes of the same stretch covered
/// evenly.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct OpenIsolineStats {
    /// Mean over the steady window's samples of the stretch's length `S`, m (`null`: no
    /// sample with two vehicles on the curve).
    pub stretch_length_m: Option<f64>,
    /// Mean over the steady window's samples of the mean gap `S/(n - 1)`, m.
    pub mean_gap_m: Option<f64>,
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

/// One sample as every live vehicle's passes are measured in it ([`TeamMetrics::observe`]).
struct SampleAt {
    /// The sample's time, s.
    t: f64,
    /// Whether it is in the steady window.
    in_window: bool,
    /// The length of its isoline, m.
    l: f64,
    /// The factor of the last sample's arc coordinates onto this isoline (its length changed).
    rescale: Option<f64>,
    /// Whether the last sample's positions are projected onto this isoline (an extraction).
    reproject: bool,
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
    closest: Option<ClosestApproach>,
    /// Each vehicle's position at the last sample (NaN: not live or off the isoline there) and
    /// that sample's time: the separations between samples are taken along the straight
    /// segments from there (att41-4).
    sep_prev_p: Vec<Vec2>,
    sep_prev_t: f64,
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
    /// Moving isoline: the points of the current isoline's bin boundaries (bin `b` starts at
    /// `b L/M`), kept to carry each bin's last pass to the next extraction's isoline (empty
    /// while the isoline gives no points: the bins are then only fractions of its length).
    bound_p: Vec<Vec2>,
    /// Scratch at an extraction: the old boundaries' arc coordinates on the new isoline with
    /// their last passes, sorted; the vehicles' last positions' arc coordinates there.
    carried: Vec<(f64, f64)>,
    vehicles_new: Vec<f64>,
    /// The isoline is open ([`OpenIsolineStats`]).
    open: bool,
    /// Open isoline: per bin, whether it lay in the team's stretch at the first sample (its
    /// first pass then ends an interval from the run's start, as every bin's on a loop).
    from_start: Vec<bool>,
    /// Open isoline: whether the first sample with a vehicle on the curve was taken.
    started: bool,
    /// Open isoline: the bins of the stretch at the last sample.
    stretch_bins: Option<(usize, usize)>,
    /// Open isoline: sums over the steady window's samples of `S` and `S/(n - 1)`, and their
    /// count.
    stretch_sum: f64,
    mean_gap_sum: f64,
    stretch_count: u64,
    /// Each vehicle's nominal speed `v0_i` (for the live vehicles' ideal revisit time).
    member_speeds_mps: Vec<f64>,
    /// Over the steady window's samples: the sum of the live vehicles' nominal speeds, the
    /// samples, and whether a vehicle's run had ended at one of them.
    active_speed_sum: f64,
    active_samples: u64,
    lost_in_window: bool,
    /// Whether a vehicle was live at a steady-window sample (without one, no revisit time:
    /// att32g-1, a sample after every vehicle had ended gave every bin an age).
    live_in_window: bool,
}

impl TeamMetrics {
    /// The speed of the ideal revisit time `L/(N v)`: for vehicles of unequal nominal speeds
    /// `v0_i`, their mean (an evenly spread team at the common speed `mean v0_i` passes a point
    /// every `L/sum v0_i`; so does, on average, a team at its own speeds, each vehicle passing
    /// a point every `L/v0_i`).
    pub fn set_nominal_speed(&mut self, speed_mps: f64) {
        self.nominal_speed_mps = speed_mps;
    }

    /// Each vehicle's own nominal speed `v0_i` (one per vehicle; ignored otherwise), for
    /// `revisit_time_ideal_active_s` (by default every vehicle's is the nominal speed given to
    /// [`new`](Self::new)).
    pub fn set_member_speeds(&mut self, speeds_mps: &[f64]) {
        if speeds_mps.len() == self.n {
            self.member_speeds_mps = speeds_mps.to_vec();
        }
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
            closest: None,
            sep_prev_p: vec![Vec2::new(f64::NAN, f64::NAN); n],
            sep_prev_t: f64::NAN,
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
            bound_p: Vec::new(),
            carried: Vec::new(),
            vehicles_new: Vec::new(),
            open: false,
            from_start: Vec::new(),
            started: false,
            stretch_bins: None,
            stretch_sum: 0.0,
            mean_gap_sum: 0.0,
            stretch_count: 0,
            member_speeds_mps: vec![nominal_speed_mps; n],
            active_speed_sum: 0.0,
            active_samples: 0,
            lost_in_window: false,
            live_in_window: false,
            cfg,
        }
    }

    /// Metrics along an open isoline (its arc coordinates in `[0, length_m]` from one end,
    /// no wrap-around): the gaps between consecutive vehicles along it only, the revisit times
    /// over the stretch the team covers ([`OpenIsolineStats`]). Not for a moving isoline.
    pub fn open(mut self) -> Self {
        self.open = true;
        self.from_start = vec![false; self.cfg.revisit_bins];
        self
    }

    /// Metrics along an isoline that moves: the isoline passed to each
    /// [`observe`](Self::observe) may differ (its length, its arc coordinates); the arc
    /// coordinates of the last sample are rescaled to the new length, the bins of the revisit
    /// times are `revisit_bins` equal arcs of the isoline of the time, `isoline_length_m` is the
    /// mean length. At an extraction ([`extracted`](Self::extracted)) each bin's last pass is
    /// carried from the old isoline to the new one by place, not by its fraction of the length
    /// (issue 32, nu36-6): the old bins' boundaries are projected onto the new isoline, and a new
    /// boundary takes the last pass interpolated between the two old ones about it (the time a
    /// vehicle passed is linear in the arc between two vehicles), or, where a vehicle lies
    /// between them, the one on its side. A new loop starts at the vertex nearest to the last
    /// one's start, which slides along the loop as it deforms; taken by fraction, the bins slid
    /// with it, and a bin sliding along with the vehicles went unpassed.
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
        self.observe_sample(k, arc, positions, speeds, alive);
        for (i, q) in self.sep_prev_p.iter_mut().enumerate() {
            *q = if alive[i] && !self.last_s[i].is_nan() {
                positions[i]
            } else {
                Vec2::new(f64::NAN, f64::NAN)
            };
        }
        self.sep_prev_t = self.t_last;
    }

    /// [`observe`](Self::observe)'s sample before the last positions are kept for the next:
    /// the time and window, the isoline's length (a moving one's bins carried), each live
    /// vehicle's passes, then the gaps along a closed or an open isoline.
    fn observe_sample(
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
        let l = self.sample_length(arc);
        // The last sample's arc coordinates on this sample's isoline (the same when it does
        // not move).
        let rescale = (self.last_l != l).then(|| l / self.last_l);
        self.last_l = l;
        let reproject = core::mem::take(&mut self.reproject);
        if self.moving {
            self.carry_bins(arc, l, reproject, rescale.is_some());
        }
        if in_window {
            self.note_active(alive);
        }
        let at = SampleAt {
            t,
            in_window,
            l,
            rescale,
            reproject,
        };
        self.scratch.clear();
        for i in 0..self.n {
            if alive[i] {
                self.observe_vehicle(i, arc, positions[i], speeds[i], &at);
            } else {
                self.last_s[i] = f64::NAN;
            }
        }
        if self.open {
            self.observe_open(t, in_window, l);
            return;
        }
        self.observe_closed(t, in_window, l, positions);
    }

    /// The length of this sample's isoline `arc` (of a moving isoline, counted in its length
    /// statistics).
    fn sample_length(&mut self, arc: &dyn ArcProjection) -> f64 {
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
        l
    }

    /// A sample in the steady window: the live vehicles' nominal speeds (the ideal revisit
    /// time of those still flying), whether a vehicle was lost, whether one is live.
    fn note_active(&mut self, alive: &[bool]) {
        let mut sum = 0.0;
        for (v, _) in self
            .member_speeds_mps
            .iter()
            .zip(alive)
            .filter(|(_, a)| **a)
        {
            sum += v;
        }
        self.active_speed_sum += sum;
        self.active_samples += 1;
        self.lost_in_window |= alive.iter().take(self.n).any(|a| !a);
        self.live_in_window |= alive.iter().take(self.n).any(|a| *a);
    }

    /// Live vehicle `i` at `position` and `speed` in the sample `at`: its speed in the range,
    /// its arc coordinate in `scratch` (none off the isoline), the bins it passed since the
    /// last sample.
    #[inline]
    fn observe_vehicle(
        &mut self,
        i: usize,
        arc: &dyn ArcProjection,
        position: Vec2,
        speed: f64,
        at: &SampleAt,
    ) {
        self.speed_min = self.speed_min.min(speed);
        self.speed_max = self.speed_max.max(speed);
        let Some(a) = arc.project(position) else {
            self.last_s[i] = f64::NAN;
            return;
        };
        let s = a.s_m;
        self.scratch.push((s, i as u32));
        let prev = if at.reproject && !self.last_s[i].is_nan() {
            arc.project(self.last_p[i]).map_or(f64::NAN, |a| a.s_m)
        } else {
            match at.rescale {
                // (A vehicle without a last arc coordinate keeps none: `NaN.min(x)` is `x`,
                // which had it pass from the loop's end at the first sample and after a
                // sample without an isoline.)
                Some(r) if !self.last_s[i].is_nan() => (self.last_s[i] * r).min(at.l.next_down()),
                _ => self.last_s[i],
            }
        };
        self.last_s[i] = s;
        if self.moving || self.open {
            self.last_p[i] = position;
        }
        if prev.is_nan() {
            return;
        }
        self.count_passes(prev, s, at);
    }

    /// The bins a vehicle entered between its arc coordinate `prev` at the last sample and `s`
    /// at this one (the shorter way round; on an open isoline, the only way), each dated.
    #[inline]
    fn count_passes(&mut self, prev: f64, s: f64, at: &SampleAt) {
        let (l, m, t) = (at.l, self.cfg.revisit_bins, at.t);
        let bin = |s: f64| ((s / l * m as f64) as usize).min(m - 1);
        let d = if self.open {
            s - prev
        } else {
            wrap_arc(s - prev + 0.5 * l, l) - 0.5 * l
        };
        let (b0, b1) = (bin(prev), bin(s));
        if b0 == b1 {
            return;
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
            if at.in_window {
                if last.is_nan() {
                    // On an open isoline only a point the team covered from the start
                    // (the first pass over new ground ends no interval).
                    if !self.open || self.from_start[b] {
                        self.revisit_max = self.revisit_max.max(t);
                    }
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

    /// The rest of a sample at time `t` on a closed isoline of length `l`, the vehicles' arc
    /// coordinates in `scratch`: the gaps between consecutive vehicles round the loop (their
    /// CV), the closest consecutive pair, the order.
    fn observe_closed(&mut self, t: f64, in_window: bool, l: f64, positions: &[Vec2]) {
        let count = self.scratch.len();
        if count < 2 {
            self.no_gap_cv();
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
            self.note_separation(positions[i0 as usize], positions[i1 as usize], t, i0, i1);
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

    /// Moving isoline, before a sample's passes on the isoline `arc` of length `l`: at an
    /// extraction (`reproject`), each bin of the new isoline takes its last pass from the old
    /// bins' boundaries projected onto it ([`moving`](Self::moving)); then, when the isoline is
    /// new or `changed` (its length), the points of its bin boundaries for the next extraction.
    /// `O(M x vertices)` per extraction (the projections), `O(M (log M + N))` for the rest.
    fn carry_bins(&mut self, arc: &dyn ArcProjection, l: f64, reproject: bool, changed: bool) {
        let m = self.cfg.revisit_bins;
        if reproject && self.bound_p.len() == m && l > 0.0 && l.is_finite() {
            self.carried.clear();
            for (p, t) in self.bound_p.iter().zip(&self.bin_last) {
                if let Some(a) = arc.project(*p) {
                    self.carried.push((a.s_m, *t));
                }
            }
            self.carried.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            self.vehicles_new.clear();
            for i in 0..self.n {
                if self.last_s[i].is_nan() {
                    continue;
                }
                if let Some(a) = arc.project(self.last_p[i]) {
                    self.vehicles_new.push(a.s_m);
                }
            }
            let k = self.carried.len();
            for b in 0..m * usize::from(k > 0) {
                let x = b as f64 * l / m as f64;
                // The old boundaries about `x` (cyclically): `u0 <= x < u1`.
                let hi = self.carried.partition_point(|c| c.0 <= x);
                let (i0, i1) = if hi == 0 {
                    (k - 1, 0)
                } else {
                    (hi - 1, hi % k)
                };
                let ((u0, t0), (u1, t1)) = (self.carried[i0], self.carried[i1]);
                let g = wrap_arc(u1 - u0, l);
                let at = wrap_arc(x - u0, l);
                // The more recent pass is the side a vehicle between them came from (a pass
                // never made is the oldest).
                let recent0 = !t0.is_nan() && (t1.is_nan() || t0 >= t1);
                let vehicle = self
                    .vehicles_new
                    .iter()
                    .map(|q| wrap_arc(q - u0, l))
                    .find(|e| *e < g);
                self.bin_last[b] = match vehicle {
                    Some(e) if recent0 => {
                        if at <= e {
                            t0
                        } else {
                            t1
                        }
                    }
                    Some(e) => {
                        if at >= e {
                            t1
                        } else {
                            t0
                        }
                    }
                    None if t0.is_nan() || t1.is_nan() || g <= 0.0 => {
                        if at <= 0.5 * g {
                            t0
                        } else {
                            t1
                        }
                    }
                    None => t0 + (t1 - t0) * (at / g),
                };
            }
        }
        if self.bound_p.len() != m || reproject || changed {
            self.bound_p.clear();
            for b in 0..m {
                match arc.point_at(b as f64 * l / m as f64) {
                    Some(p) => self.bound_p.push(p),
                    None => {
                        self.bound_p.clear();
                        return;
                    }
                }
            }
        }
    }

    /// The rest of a sample at time `t` on an open isoline of length `l`, the vehicles' arc
    /// coordinates in `scratch`: the stretch, the gaps between consecutive vehicles (no
    /// wrap-around), the closest consecutive pair, the order ([`OpenIsolineStats`]).
    fn observe_open(&mut self, t: f64, in_window: bool, l: f64) {
        let count = self.scratch.len();
        if count == 0 {
            self.stretch_bins = None;
            self.no_gap_cv();
            return;
        }
        self.scratch
            .sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let m = self.cfg.revisit_bins;
        let bin = |s: f64| ((s / l * m as f64) as usize).min(m - 1);
        let (lo, hi) = (self.scratch[0].0, self.scratch[count - 1].0);
        let (b_lo, b_hi) = (bin(lo), bin(hi));
        self.stretch_bins = Some((b_lo, b_hi));
        if !self.started {
            // The points the team covers at its first sample: unvisited since the start.
            self.started = true;
            for b in b_lo..=b_hi {
                self.from_start[b] = self.bin_last[b].is_nan();
            }
        }
        if count < 2 {
            self.no_gap_cv();
            return;
        }
        let stretch = hi - lo;
        let mean = stretch / (count - 1) as f64;
        let mut var = 0.0;
        for j in 0..count - 1 {
            let (s0, i0) = self.scratch[j];
            let (s1, i1) = self.scratch[j + 1];
            let g = s1 - s0;
            var += (g - mean) * (g - mean);
            self.note_separation(self.last_p_or(i0), self.last_p_or(i1), t, i0, i1);
        }
        if in_window {
            self.stretch_sum += stretch;
            self.mean_gap_sum += mean;
            self.stretch_count += 1;
            self.check_order();
        }
        // A gap CV needs two gaps (one has no spread) and a stretch of positive length.
        if count < 3 || mean.is_nan() || mean <= 0.0 {
            self.no_gap_cv();
            return;
        }
        let cv = (var / (count - 1) as f64).sqrt() / mean;
        self.cv_last = Some(cv);
        if cv <= self.cfg.even_gap_cv {
            self.even_since.get_or_insert(t);
        } else {
            self.even_since = None;
        }
        if in_window {
            self.cv_sum += cv;
            self.cv_count += 1;
        }
    }

    /// A sample without a gap CV (too few vehicles live on the isoline: att32f-4/-6): the
    /// final gap CV is none, and the team is not evenly spread from it on (`time_to_even_s`
    /// restarts at the next sample that is). Before, such a sample left both as the last
    /// sample with a CV had them: `gap_cv_final` a number (even from `t = 0`) with one or no
    /// vehicle live at the end, and `time_to_even_s` 0 on an open isoline whose evenly
    /// deployed team had all gone.
    fn no_gap_cv(&mut self) {
        self.cv_last = None;
        self.even_since = None;
    }

    /// Vehicle `i`'s position at the current sample (kept in `last_p` for an open isoline).
    /// The closest approach of consecutive vehicles `i0` and `i1` (now at `p0`, `p1`, time `t`)
    /// since the last sample: the smallest so far kept, with its time. Between samples each
    /// vehicle is taken to move along the straight segment from its last sample's position
    /// when their relative position reversed (a pass: `d0.d1 < 0`; exact for constant
    /// velocities: `d(u) = d0 + u (d1 - d0)`, nearest the origin at
    /// `u* = -d0.(d1 - d0)/|d1 - d0|^2` in `(0, 1)`): a pass between samples (att41-4: 20 m/s
    /// apart, samples 0.1 s apart, 2 m of relative travel) is caught, not only the samples'
    /// distances. Without a last position for either (its first
    /// sample, or one off the isoline), the distance now.
    fn note_separation(&mut self, p0: Vec2, p1: Vec2, t: f64, i0: u32, i1: u32) {
        let d1 = p1 - p0;
        let mut sep = d1.norm();
        let mut at = t;
        let (q0, q1) = (self.sep_prev_p[i0 as usize], self.sep_prev_p[i1 as usize]);
        let d0 = q1 - q0;
        // Only a pass (the pair's relative position reversed, `d0.d1 < 0`): between samples of
        // vehicles that keep their order the straight segments would cut the curve's chord
        // short (by `1 - cos(dtheta/2)` of it), a bias, not an approach.
        if q0.is_finite() && q1.is_finite() && self.sep_prev_t < t && d0.dot(d1) < 0.0 {
            let dd = d1 - d0;
            let den = dd.dot(dd);
            if den > 0.0 {
                let u = -d0.dot(dd) / den;
                if u > 0.0 && u < 1.0 {
                    let between = (d0 + dd * u).norm();
                    if between < sep {
                        sep = between;
                        at = self.sep_prev_t + u * (t - self.sep_prev_t);
                    }
                }
            }
        }
        if sep < self.min_sep {
            self.closest = Some(ClosestApproach {
                distance_m: sep,
                t_s: at,
                pair: [i0.min(i1), i0.max(i1)],
            });
        }
        self.min_sep = self.min_sep.min(sep);
    }

    fn last_p_or(&self, i: u32) -> Vec2 {
        self.last_p[i as usize]
    }

    /// Compares the cyclic order of the vehicles along the isoline with the window's first
    /// (on an open isoline, the order from one end to the other).
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
        if self.open && shift != 0 {
            self.order_ok = false;
            return;
        }
        if (0..n).any(|j| now[(shift + j) % n] != present[j]) {
            self.order_ok = false;
        }
    }

    /// The summary.
    pub fn finish(&self) -> TeamSummary {
        let l = self.mean_length_m();
        let (revisit_max, revisit_mean) = self.revisit_times_s();
        TeamSummary {
            count: self.n,
            isoline_length_m: l,
            gap_cv: (self.cv_count > 0).then(|| self.cv_sum / self.cv_count as f64),
            gap_cv_final: self.cv_last,
            time_to_even_s: self.even_since,
            revisit_time_max_s: revisit_max,
            revisit_time_mean_s: revisit_mean,
            revisit_time_ideal_s: if self.open {
                match self.stretch_count {
                    0 => f64::NAN,
                    c => self.mean_gap_sum / c as f64 / self.nominal_speed_mps,
                }
            } else {
                l / (self.n as f64 * self.nominal_speed_mps)
            },
            revisit_time_ideal_active_s: (self.lost_in_window && !self.open)
                .then(|| l / (self.active_speed_sum / self.active_samples as f64)),
            min_separation_m: self.min_sep.is_finite().then_some(self.min_sep),
            closest_approach: self.closest.filter(|_| self.min_sep.is_finite()),
            order_preserved: self.order_ok,
            speed_range_mps: (self.speed_min <= self.speed_max)
                .then_some([self.speed_min, self.speed_max]),
            moving_isoline: self.moving.then(|| MovingIsolineStats {
                extractions: self.extractions,
                length_range_m: (self.len_min <= self.len_max)
                    .then_some([self.len_min, self.len_max]),
                samples_without_isoline: self.skipped,
            }),
            open_isoline: self.open.then(|| {
                let c = self.stretch_count;
                OpenIsolineStats {
                    stretch_length_m: (c > 0).then(|| self.stretch_sum / c as f64),
                    mean_gap_m: (c > 0).then(|| self.mean_gap_sum / c as f64),
                }
            }),
        }
    }

    /// The isoline's length, m: a moving isoline's mean over the samples (NaN without one).
    fn mean_length_m(&self) -> f64 {
        if self.moving {
            if self.len_count > 0 {
                self.len_sum / self.len_count as f64
            } else {
                f64::NAN
            }
        } else {
            self.length_m
        }
    }

    /// The longest and the mean revisit time, s, the longest counting the intervals still open
    /// at the run's end; none without a steady window with a live vehicle (the mean none
    /// without a closed interval).
    fn revisit_times_s(&self) -> (Option<f64>, Option<f64>) {
        match self.t_window {
            Some(_) if self.live_in_window => {
                // The open interval at the run's end: the age of each bin then (from the run's
                // start for a bin never passed).
                let mut mx = self.revisit_max;
                if self.open {
                    // The points of the final stretch only (the ground behind the team is
                    // left, the ground ahead not covered yet).
                    if let Some((b_lo, b_hi)) = self.stretch_bins {
                        for b in b_lo..=b_hi {
                            let last = self.bin_last[b];
                            if !last.is_nan() {
                                mx = mx.max(self.t_last - last);
                            } else if self.from_start[b] {
                                mx = mx.max(self.t_last);
                            }
                        }
                    }
                } else {
                    for &last in &self.bin_last {
                        let open = if last.is_nan() {
                            self.t_last
                        } else {
                            self.t_last - last
                        };
                        mx = mx.max(open);
                    }
                }
                let mean =
                    (self.revisit_count > 0).then(|| self.revisit_sum / self.revisit_count as f64);
                (Some(mx), mean)
            }
            _ => (None, None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::team::arc::{CircleArc, PolylineArc};
    use std::f64::consts::PI;

    /// att41-4: two vehicles 20 m/s apart on a straight stretch (a circle of radius 10 km),
    /// sampled every 0.1 s: vehicle 0 at 30 m/s starts 1.1 m behind vehicle 1 at 10 m/s, so it
    /// passes through it at t = 1.1/20 = 0.055 s, between the samples at 0 (1.1 m apart) and
    /// 0.1 s (0.9 m apart, the order swapped). The closest approach is 0 (to the circle's
    /// sagitta over 3 m, 3^2/(8 10^4) = 1e-4 m), at 0.055 s, not the samples' 0.9 m.
    #[test]
    fn a_pass_between_samples_is_the_closest_approach() {
        let r = 10_000.0;
        let arc = CircleArc {
            center_m: Vec2::new(0.0, -r),
            radius_m: r,
        };
        let l = 2.0 * PI * r;
        let dt = 0.01;
        let cfg = TeamMetricsConfig {
            every_steps: 10,
            steady_state_start_step: 0,
            even_gap_cv: 0.05,
            revisit_bins: 360,
        };
        let mut m = TeamMetrics::new(cfg, 2, l, dt, 20.0);
        let at = |s: f64| {
            let th = PI / 2.0 - s / r;
            Vec2::new(r * th.cos(), -r + r * th.sin())
        };
        for k in 0..=20u64 {
            let t = k as f64 * dt;
            let pos = [at(30.0 * t), at(1.1 + 10.0 * t)];
            if m.due() {
                m.observe(k, &arc, &pos, &[30.0, 10.0], &[true; 2]);
            }
        }
        let s = m.finish();
        let d = s.min_separation_m.unwrap();
        assert!(d < 2e-4, "{d}");
        let c = s.closest_approach.unwrap();
        assert!((c.t_s - 0.055).abs() < 1e-6, "{c:?}");
        assert_eq!(c.pair, [0, 1]);
    }

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

    /// Issue 32 (nu36-6): a loop re-extracted with its start vertex sliding along it. The
    /// isoline is a circle of radius 20 m that does not move, given at every second as a
    /// 720-gon whose first vertex is at the angle `phi(t) = c v t/R` (a moving isoline's start
    /// slides as the loop deforms); four points evenly spread go round at `v = 1` m/s. Every
    /// point of the circle is passed every `L/(N v) = 2 pi 20/4 = 31.42` s whatever the start,
    /// so the longest and the mean revisit time over the window (the last 200 of 400 s) are
    /// `L/(N v)`, to a bin's crossing `L/(M v) = 0.17` s, a sample (0.1 s) and the start's
    /// slide in a second (`|c| v x 1 s`). Before the fix the bins were fractions of the length
    /// from the start and slid with it: passed at the relative speed `(1 - c) v`, every
    /// `L/(N (1 - c) v)`: 62.8 s for `c = 1/2`, 20.9 s for `c = -1/2`.
    #[test]
    fn a_loop_whose_start_slides_is_revisited_every_l_over_n_v() {
        let (r, v, dt, n) = (20.0, 1.0, 0.1, 4usize);
        let l = 2.0 * PI * r;
        let ideal = l / (n as f64 * v);
        let polygon = |phi: f64| {
            PolylineArc::new(
                (0..720)
                    .map(|i| {
                        let th = phi + 2.0 * PI * i as f64 / 720.0;
                        Vec2::new(r * th.cos(), r * th.sin())
                    })
                    .collect(),
            )
            .unwrap()
        };
        for c in [0.5, -0.5, 0.0] {
            let cfg = TeamMetricsConfig {
                steady_state_start_step: 2000,
                ..TeamMetricsConfig::default()
            };
            let mut m = TeamMetrics::new(cfg, n, f64::NAN, dt, v).moving();
            let mut arc = polygon(0.0);
            for k in 0..=4000u64 {
                let t = k as f64 * dt;
                if k % 10 == 0 {
                    arc = polygon(c * v * t / r);
                    m.extracted();
                }
                let pos: Vec<Vec2> = (0..n)
                    .map(|i| {
                        let th = v * t / r + 2.0 * PI * i as f64 / n as f64;
                        Vec2::new(r * th.cos(), r * th.sin())
                    })
                    .collect();
                m.observe(k, &arc, &pos, &[v; 4], &[true; 4]);
            }
            let s = m.finish();
            let tol = l / (720.0 * v) + dt + c.abs() * v + 1e-9;
            let mx = s.revisit_time_max_s.unwrap();
            assert!((mx - ideal).abs() <= tol, "c {c}: max {mx} vs {ideal}");
            let mean = s.revisit_time_mean_s.unwrap();
            assert!((mean - ideal).abs() <= tol, "c {c}: mean {mean} vs {ideal}");
            assert_eq!(s.moving_isoline.unwrap().extractions, 401);
        }
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

    /// att32e (item 2): the live vehicles' ideal revisit time. Four points on a circle of
    /// radius 10, nominal speeds 1, 2, 1, 1 m/s; the window is the last 10 of 20 samples.
    /// Vehicle 3 is gone from the window's sixth sample on: the live speeds sum to 5 m/s at 5
    /// samples and 4 m/s at 5, so the ideal is `L/4.5` by hand; `revisit_time_ideal_s` stays
    /// the team's `L/(4 x 1.25)`. With every vehicle live in the window it is absent.
    #[test]
    fn the_ideal_of_the_live_vehicles() {
        let r = 10.0;
        let arc = CircleArc {
            center_m: Vec2::new(0.0, 0.0),
            radius_m: r,
        };
        let l = 2.0 * PI * r;
        let cfg = TeamMetricsConfig {
            every_steps: 1,
            steady_state_start_step: 10,
            even_gap_cv: 0.05,
            revisit_bins: 36,
        };
        let run = |gone_from: u64| {
            let mut m = TeamMetrics::new(cfg, 4, l, 0.1, 1.25);
            m.set_member_speeds(&[1.0, 2.0, 1.0, 1.0]);
            for k in 0..20u64 {
                let pos: Vec<Vec2> = (0..4)
                    .map(|i| {
                        let th = 0.01 * k as f64 + PI / 2.0 * i as f64;
                        Vec2::new(r * th.cos(), r * th.sin())
                    })
                    .collect();
                let alive = [true, true, true, k < gone_from];
                if m.due() {
                    m.observe(k, &arc, &pos, &[1.0; 4], &alive);
                }
            }
            m.finish()
        };
        let s = run(15);
        let want = l / 4.5;
        let got = s.revisit_time_ideal_active_s.unwrap();
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
        assert!((s.revisit_time_ideal_s - l / 5.0).abs() < 1e-12 * l);
        // Gone before the window: L/4 throughout.
        let got = run(3).revisit_time_ideal_active_s.unwrap();
        assert!((got - l / 4.0).abs() < 1e-12 * l, "{got}");
        assert_eq!(run(20).revisit_time_ideal_active_s, None);
    }

    /// att32g-1: no revisit time without a vehicle live at a steady-window sample. Four points
    /// at rest on a circle, samples at steps 0..=11 of 0.1 s, the window from step 10; every
    /// vehicle's run ends at step `end` (live at it, as a run that ends at a step writes it).
    /// Ending at step 9, nobody is live in the window: `None` (it was the open age at the last
    /// sample, 1.1 s, of a loop nobody flew). Ending at step 10, the window's first sample has
    /// them: no point is ever passed, so each one's age at the last sample is 1.1 s.
    #[test]
    fn no_revisit_time_without_a_live_vehicle_in_the_window() {
        let r = 10.0;
        let arc = CircleArc {
            center_m: Vec2::new(0.0, 0.0),
            radius_m: r,
        };
        let l = 2.0 * PI * r;
        let cfg = TeamMetricsConfig {
            every_steps: 1,
            steady_state_start_step: 10,
            even_gap_cv: 0.05,
            revisit_bins: 36,
        };
        let run = |end: u64| {
            let mut m = TeamMetrics::new(cfg, 4, l, 0.1, 1.0);
            let pos: Vec<Vec2> = (0..4)
                .map(|i| {
                    let th = PI / 2.0 * i as f64;
                    Vec2::new(r * th.cos(), r * th.sin())
                })
                .collect();
            for k in 0..=11u64 {
                let alive = [k <= end; 4];
                if m.due() {
                    m.observe(k, &arc, &pos, &[1.0; 4], &alive);
                }
            }
            m.finish()
        };
        let s = run(9);
        assert_eq!(s.revisit_time_max_s, None);
        assert_eq!(s.revisit_time_mean_s, None);
        let s = run(10);
        let got = s.revisit_time_max_s.unwrap();
        assert!((got - 1.1).abs() < 1e-12, "{got}");
    }

    /// Four points at arc offsets `offs` behind one another along `arc` (an open isoline),
    /// moving rigidly at `v` from `s0` for `steps` steps of `dt`, the window from `window`.
    #[allow(clippy::too_many_arguments)]
    fn rigid_open(
        arc: &dyn ArcProjection,
        at: &dyn Fn(f64) -> Vec2,
        offs: &[f64],
        v: f64,
        dt: f64,
        steps: u64,
        window: u64,
        bins: usize,
    ) -> TeamSummary {
        let n = offs.len();
        let cfg = TeamMetricsConfig {
            every_steps: 1,
            steady_state_start_step: window,
            even_gap_cv: 0.05,
            revisit_bins: bins,
        };
        let mut m = TeamMetrics::new(cfg, n, arc.length_m(), dt, v).open();
        for k in 0..=steps {
            let t = k as f64 * dt;
            let pos: Vec<Vec2> = offs.iter().map(|o| at(o + v * t)).collect();
            if m.due() {
                m.observe(k, arc, &pos, &vec![v; n], &vec![true; n]);
            }
        }
        m.finish()
    }

    /// The population CV of `gaps`.
    fn cv_of(gaps: &[f64]) -> f64 {
        let k = gaps.len() as f64;
        let mean = gaps.iter().sum::<f64>() / k;
        (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / k).sqrt() / mean
    }

    /// An open isoline: the straight line `y = 5` from `x = -100` to `x = 400` (the isoline
    /// of the planar field `F = y` at level 5, cut by a domain), arc coordinate `x + 100`.
    /// Four points at `x = 0, 10, 20, 40` moving rigidly along it at 2 m/s: the gaps are
    /// 10, 10, 20 (no wrap-around gap of `L - 40 = 460`), so the gap CV is theirs by hand; a
    /// point inside the stretch waits a gap over `v` between passes: at most 20/2 = 10 s, on
    /// average (each point sees the three gaps once) 40/3/2 s, which is also the ideal
    /// (the mean gap `S/(N - 1)` over `v`); the stretch is 40 m; the closest pair 10 m apart.
    /// Measured as a closed isoline instead, the wrap-around gap gives a CV of 1.4 and a
    /// longest revisit time of the run.
    #[test]
    fn open_straight_line_by_hand() {
        let arc = PolylineArc::open(vec![Vec2::new(-100.0, 5.0), Vec2::new(400.0, 5.0)]).unwrap();
        assert!(!arc.is_closed());
        assert_eq!(arc.length_m(), 500.0);
        let p = arc.project(Vec2::new(37.5, 9.0)).unwrap();
        assert_eq!(p.s_m, 137.5);
        assert_eq!(arc.project(Vec2::new(-300.0, 5.0)).unwrap().s_m, 0.0);
        assert_eq!(arc.project(Vec2::new(900.0, 0.0)).unwrap().s_m, 500.0);
        let (v, dt) = (2.0, 0.05);
        let at = |x: f64| Vec2::new(x, 5.0);
        // 100 s: the lead from x = 40 to 240; the window from 30 s.
        let s = rigid_open(&arc, &at, &[0.0, 10.0, 20.0, 40.0], v, dt, 2000, 600, 500);
        let cv = cv_of(&[10.0, 10.0, 20.0]);
        assert!(
            (s.gap_cv.unwrap() - cv).abs() < 1e-9,
            "{:?} vs {cv}",
            s.gap_cv
        );
        assert!((s.gap_cv_final.unwrap() - cv).abs() < 1e-9);
        // A bin is 1 m, crossed in 0.5 s; a sample 0.05 s.
        let tol = 1.0 / v + dt + 1e-9;
        let mx = s.revisit_time_max_s.unwrap();
        assert!((mx - 20.0 / v).abs() <= tol, "max {mx}");
        let mean = s.revisit_time_mean_s.unwrap();
        assert!((mean - 40.0 / 3.0 / v).abs() <= tol, "mean {mean}");
        assert!((s.revisit_time_ideal_s - 40.0 / 3.0 / v).abs() < 1e-9);
        let o = s.open_isoline.clone().unwrap();
        assert!((o.stretch_length_m.unwrap() - 40.0).abs() < 1e-9);
        assert!((o.mean_gap_m.unwrap() - 40.0 / 3.0).abs() < 1e-9);
        assert!((s.min_separation_m.unwrap() - 10.0).abs() < 1e-9);
        assert!(s.order_preserved);
        assert_eq!(s.isoline_length_m, 500.0);
        assert_eq!(s.time_to_even_s, None);
        assert!(s.moving_isoline.is_none());
        // The same team measured as on a loop of the same length (wrapping): the gap
        // `L - 40` counts, and the ground behind the team ages to the run's end.
        let mut closed = TeamMetrics::new(
            TeamMetricsConfig {
                steady_state_start_step: 600,
                revisit_bins: 500,
                ..TeamMetricsConfig::default()
            },
            4,
            500.0,
            dt,
            v,
        );
        for k in 0..=2000u64 {
            let t = k as f64 * dt;
            let pos: Vec<Vec2> = [0.0, 10.0, 20.0, 40.0]
                .iter()
                .map(|o| at(o + v * t))
                .collect();
            closed.observe(k, &arc, &pos, &[v; 4], &[true; 4]);
        }
        let c = closed.finish();
        assert!(c.gap_cv.unwrap() > 1.0 && c.revisit_time_max_s.unwrap() > 90.0);
    }

    /// An open isoline that curves: three quarters of a circle of radius 20 m (a polyline of
    /// 2700 chords from angle 0 to `3 pi/2`, the circle cut open), four points at arc offsets
    /// 0, 8, 16, 30 going round at 1 m/s for 40 s (the lead ends at 70 m of the 94.2 m): the
    /// gaps along the curve are 8, 8, 14 (to the chords' sagitta), the closest pair the chord
    /// of an 8 m arc, `2 R sin(8/(2 R))`, the longest revisit 14 s, the ideal `(30/3)/1` s.
    #[test]
    fn open_circle_cut_by_hand() {
        let r = 20.0;
        let m = 2700;
        let pts: Vec<Vec2> = (0..=m)
            .map(|i| {
                let th = 1.5 * PI * i as f64 / m as f64;
                Vec2::new(r * th.cos(), r * th.sin())
            })
            .collect();
        let arc = PolylineArc::open(pts).unwrap();
        let per = 2.0 * m as f64 * r * (0.75 * PI / m as f64).sin();
        assert!((arc.length_m() - per).abs() < 1e-9);
        let at = |s: f64| Vec2::new(r * (s / r).cos(), r * (s / r).sin());
        // The window from 15 s: every pass in it ends an interval whose start the window's
        // passes share (the lead passed s = 30 m at 0 s).
        let s = rigid_open(&arc, &at, &[0.0, 8.0, 16.0, 30.0], 1.0, 0.05, 800, 300, 360);
        let cv = cv_of(&[8.0, 8.0, 14.0]);
        assert!(
            (s.gap_cv.unwrap() - cv).abs() < 1e-4,
            "{:?} vs {cv}",
            s.gap_cv
        );
        let chord = 2.0 * r * (8.0 / (2.0 * r)).sin();
        assert!((s.min_separation_m.unwrap() - chord).abs() < 1e-9);
        let tol = per / 360.0 + 0.05 + 1e-9;
        let mx = s.revisit_time_max_s.unwrap();
        assert!((mx - 14.0).abs() <= tol, "max {mx}");
        let mean = s.revisit_time_mean_s.unwrap();
        assert!((mean - 10.0).abs() <= tol, "mean {mean}");
        assert!((s.revisit_time_ideal_s - 10.0).abs() < 1e-4);
        assert!(s.order_preserved);
    }

    /// An open isoline's revisit bins: a sample's travel each (314 m at 0.05 m per sample:
    /// 6280), never fewer than the loop's count nor more than the cap.
    #[test]
    fn open_bins_follow_the_travel_per_sample() {
        assert_eq!(open_revisit_bins(314.0, 0.05, 720), 6280);
        assert_eq!(open_revisit_bins(10.0, 1.0, 720), 720);
        assert_eq!(open_revisit_bins(1e12, 1.0, 720), MAX_OPEN_REVISIT_BINS);
        assert_eq!(open_revisit_bins(100.0, 0.0, 720), 720);
        assert_eq!(open_revisit_bins(100.0, f64::NAN, 720), 720);
    }

    /// On an open isoline two points swapping places break the order (a linear order: a
    /// rotation of it, which a loop allows, is a change too); two vehicles give no gap CV.
    #[test]
    fn open_order_and_two_vehicles() {
        let arc = PolylineArc::open(vec![Vec2::new(0.0, 0.0), Vec2::new(100.0, 0.0)]).unwrap();
        let mut m = TeamMetrics::new(TeamMetricsConfig::default(), 3, 100.0, 1.0, 1.0).open();
        let x = |a: f64| Vec2::new(a, 0.0);
        m.observe(0, &arc, &[x(10.0), x(20.0), x(30.0)], &[1.0; 3], &[true; 3]);
        m.observe(1, &arc, &[x(11.0), x(21.0), x(31.0)], &[1.0; 3], &[true; 3]);
        assert!(m.finish().order_preserved);
        // (1, 2, 0): a cyclic rotation of (0, 1, 2), fine on a loop, not on an open curve.
        m.observe(2, &arc, &[x(40.0), x(22.0), x(32.0)], &[1.0; 3], &[true; 3]);
        assert!(!m.finish().order_preserved);
        let mut two = TeamMetrics::new(TeamMetricsConfig::default(), 2, 100.0, 1.0, 1.0).open();
        two.observe(0, &arc, &[x(10.0), x(30.0)], &[1.0; 2], &[true; 2]);
        let s = two.finish();
        assert_eq!(s.gap_cv, None);
        assert!((s.min_separation_m.unwrap() - 20.0).abs() < 1e-12);
        assert!((s.revisit_time_ideal_s - 20.0).abs() < 1e-12);
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

    /// att32f-6/-4: `gap_cv_final` is the gap CV at the last sample and `time_to_even_s` the
    /// start of the last run of even samples up to it; a sample without a gap CV (one vehicle
    /// live on a loop, fewer than three on an open isoline) has neither. On the unit circle,
    /// three points a third apart (CV 0, even from t = 0); vehicle 2 gone: the gaps of the
    /// two left are `2 pi/3` and `4 pi/3`, mean `pi`, CV `(pi/3)/pi = 1/3` by hand; vehicle 1
    /// gone too: no gap CV (before the fix: 1/3 and even from 0 whatever came after). On an
    /// open line, three points 10 m apart (CV 0, even from 0), then all gone: none of either
    /// (before: `time_to_even_s` 0, `gap_cv_final` 0, where a loop's team gone gave none).
    #[test]
    fn the_final_gap_cv_is_the_last_samples() {
        let arc = CircleArc {
            center_m: Vec2::new(0.0, 0.0),
            radius_m: 1.0,
        };
        let mut m = TeamMetrics::new(TeamMetricsConfig::default(), 3, 2.0 * PI, 1.0, 1.0);
        let at = |th: f64| Vec2::new(th.cos(), th.sin());
        let third = 2.0 * PI / 3.0;
        let p = [at(0.0), at(third), at(2.0 * third)];
        m.observe(0, &arc, &p, &[1.0; 3], &[true; 3]);
        let s = m.finish();
        assert!(s.gap_cv_final.unwrap() < 1e-12);
        assert_eq!(s.time_to_even_s, Some(0.0));
        m.observe(1, &arc, &p, &[1.0; 3], &[true, true, false]);
        let s = m.finish();
        assert!((s.gap_cv_final.unwrap() - 1.0 / 3.0).abs() < 1e-12, "{s:?}");
        assert_eq!(s.time_to_even_s, None);
        m.observe(2, &arc, &p, &[1.0; 3], &[true, false, false]);
        let s = m.finish();
        assert_eq!(s.gap_cv_final, None, "one vehicle live: no gaps");
        assert_eq!(s.time_to_even_s, None);
        assert!(
            (s.gap_cv.unwrap() - 1.0 / 6.0).abs() < 1e-12,
            "mean of 0, 1/3"
        );
        m.observe(3, &arc, &p, &[1.0; 3], &[false; 3]);
        assert_eq!(m.finish().gap_cv_final, None);

        let line = PolylineArc::open(vec![Vec2::new(0.0, 0.0), Vec2::new(100.0, 0.0)]).unwrap();
        let mut o = TeamMetrics::new(TeamMetricsConfig::default(), 3, 100.0, 1.0, 1.0).open();
        let x = |a: f64| Vec2::new(a, 0.0);
        let q = [x(10.0), x(20.0), x(30.0)];
        o.observe(0, &line, &q, &[1.0; 3], &[true; 3]);
        let s = o.finish();
        assert_eq!((s.gap_cv_final, s.time_to_even_s), (Some(0.0), Some(0.0)));
        o.observe(1, &line, &q, &[1.0; 3], &[true, true, false]);
        let s = o.finish();
        assert_eq!((s.gap_cv_final, s.time_to_even_s), (None, None), "one gap");
        o.observe(2, &line, &q, &[1.0; 3], &[false; 3]);
        let s = o.finish();
        assert_eq!((s.gap_cv_final, s.time_to_even_s), (None, None), "all gone");
    }
}
