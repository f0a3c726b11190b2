//! What `isotrack fly` records of a flight: the trace rows, each paired with the vehicle's
//! position and heading at its measurement's time, flushed at a bounded interval so that a
//! killed companion leaves a readable trace; and the run's tracking metrics, the library's own
//! ([`isotrack_sim::Metrics`]) on the measured error series (positions only for the path
//! length: the law never sees them).
//!
//! Pairing: a MAVLink measurement stamped `t` (`time_boot_ms`) gets the latest position
//! (`LOCAL_POSITION_NED`, else `GLOBAL_POSITION_INT`) and heading (`ATTITUDE`) stamped at or
//! before `t`, in the vehicle's clock. A vehicle may send the position of `t` after the
//! measurement of `t` (as `isotrack sitl` does: the pose of a step follows its sample's
//! answer), so a row waits until a position (and, if the vehicle sends any, an attitude)
//! stamped at or after `t` has come, for at most [`MAX_ROW_WAIT_S`] of wall time, then takes
//! what there is (`NaN` for none). A UDP sensor's line is on the sensor's own clock: its row
//! takes the latest position and heading received when the line arrived.
//!
//! An invalid position (not finite, or a latitude/longitude out of range: the vehicle does not
//! know where it is) is recorded too ([`Recorder::no_position`]): a row stamped at or after it,
//! before the next valid one, gets `NaN` (no position), never the last valid one repeated as if
//! it were current.

use isotrack_scenario::Scenario;
use isotrack_sim::{Metrics, MetricsConfig, RunMetrics, TraceRow, TraceSink};
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The longest a trace row waits for its position, wall s.
pub const MAX_ROW_WAIT_S: f64 = 1.0;
/// The trace is flushed after this many rows (fewer than fill `TraceWriter`'s 8 KiB buffer,
/// which would otherwise write a row's first part alone: a killed companion leaves whole rows)
/// ...
pub const FLUSH_EVERY_ROWS: u64 = 32;
/// ... and at least this often while rows come, wall s.
pub const FLUSH_INTERVAL_S: f64 = 1.0;
/// The positions and attitudes kept for pairing (the newest).
const HISTORY: usize = 4096;
/// The samples answered in control kept to compute the metrics over what was flown of a
/// flight that ended early (24 bytes each: 24 MB; about 28 h at 10 Hz). Past it, an early
/// end's metrics are the planned window's (the summary says so).
pub const MAX_KEPT_SAMPLES: usize = 1_000_000;

/// A vehicle-clock history of one telemetry value, newest last.
#[derive(Default)]
struct History<T: Copy> {
    items: VecDeque<(u32, T)>,
}

impl<T: Copy> History<T> {
    fn push(&mut self, ms: u32, v: T) {
        // The vehicle's clock wrapped (2^32 ms): the history starts again from the wrap.
        if self
            .items
            .back()
            .is_some_and(|&(last, _)| crate::wire::wrapped_forward(last, ms))
        {
            self.items.clear();
        }
        // Out of order: kept in order (a late one is only ever older than what is there).
        if self.items.back().is_some_and(|&(last, _)| ms < last) {
            return;
        }
        self.items.push_back((ms, v));
        if self.items.len() > HISTORY {
            self.items.pop_front();
        }
    }
    fn newest_ms(&self) -> Option<u32> {
        self.items.back().map(|x| x.0)
    }
    fn newest(&self) -> Option<T> {
        self.items.back().map(|x| x.1)
    }
    /// The latest item stamped at or before `ms`.
    fn at(&self, ms: u32) -> Option<T> {
        let i = self.items.partition_point(|&(t, _)| t <= ms);
        i.checked_sub(1).map(|i| self.items[i].1)
    }
    /// Whether an item stamped at or after `ms` has come (or none ever will be waited for).
    fn covers(&self, ms: u32) -> bool {
        self.newest_ms().is_none_or(|n| n >= ms)
    }
}

/// A row waiting for its pose.
struct Pending {
    row: TraceRow,
    /// Its measurement's vehicle time (`None`: a UDP line, paired on arrival).
    ms: Option<u32>,
    at: Instant,
}

/// The measured error series' metrics: [`Metrics`] on the samples the law answered, sample
/// `i` at step `round((t_i - t_0) / T)` of the scenario's sampling period `T`
/// (`1 / sensor.rate_hz`, else `sim.dt_s`), from the first answered sample `t_0`.
struct SeriesMetrics {
    m: Metrics,
    period_s: f64,
    t0_s: Option<f64>,
    /// The command answering the previous sample, held over one period (integrated when the
    /// next sample comes: the last one's never is, as in a simulated run).
    held: Option<f64>,
    /// The last received position in control, for the path length.
    last_pos: Option<(f64, f64)>,
    /// The samples answered in control: time, s, measured error, command (at most
    /// [`MAX_KEPT_SAMPLES`]).
    kept: Vec<(f64, f64, f64)>,
    /// More samples came than were kept.
    kept_all: bool,
    /// The metrics' configuration (the planned window).
    cfg: MetricsConfig,
    /// The planned duration, s, and the steady-state fraction.
    planned_s: f64,
    fraction: f64,
}

/// The trace and the metrics of a flight.
pub(crate) struct Recorder {
    positions: History<(f64, f64)>,
    headings: History<f64>,
    pending: VecDeque<Pending>,
    unflushed: u64,
    last_flush: Instant,
    metrics: SeriesMetrics,
    max_wait: Duration,
}

impl Recorder {
    /// For `scenario`'s metrics (its `[metrics]` keys), the steady-state window being the last
    /// `metrics.steady_state_fraction` of `planned_s` from the first answered sample.
    pub(crate) fn new(scenario: &Scenario, planned_s: f64) -> Self {
        let f = scenario.file();
        let period_s = f.sensor.rate_hz.map_or(scenario.dt_s(), |r| 1.0 / r);
        let plan = scenario.plan();
        let n = (planned_s / period_s).round().max(0.0);
        let frac = f.metrics.steady_state_fraction.unwrap_or(0.2);
        let cfg = MetricsConfig {
            dt_s: period_s,
            steady_state_start_step: ((1.0 - frac) * n).ceil() as u64,
            convergence_tolerance: plan.convergence_tolerance,
            convergence_min_dwell_steps: ((scenario.convergence_min_dwell_s() / period_s)
                .ceil()
                .max(0.0)
                .min(n)) as u64,
            track_loss_band: plan.track_loss_band,
        };
        Self {
            positions: History::default(),
            headings: History::default(),
            pending: VecDeque::new(),
            unflushed: 0,
            last_flush: Instant::now(),
            metrics: SeriesMetrics {
                m: Metrics::new(cfg),
                period_s,
                t0_s: None,
                held: None,
                last_pos: None,
                kept: Vec::new(),
                kept_all: true,
                cfg,
                planned_s,
                fraction: frac,
            },
            max_wait: Duration::from_secs_f64(MAX_ROW_WAIT_S),
        }
    }

    /// A position received, m (x east, y north), stamped `ms`; `in_control`: it counts for the
    /// path length.
    pub(crate) fn position(&mut self, ms: u32, p: (f64, f64), in_control: bool) {
        self.positions.push(ms, p);
        let s = &mut self.metrics;
        if in_control {
            if let Some(q) = s.last_pos {
                s.m.add_path(((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt());
            }
            s.last_pos = Some(p);
        }
    }

    /// An invalid position received, stamped `ms`: rows from `ms` until the next valid position
    /// get `NaN` (the path length goes on from the last valid position to the next).
    pub(crate) fn no_position(&mut self, ms: u32) {
        self.positions.push(ms, (f64::NAN, f64::NAN));
    }

    /// A heading received, rad (counter-clockwise from east), stamped `ms`.
    pub(crate) fn heading(&mut self, ms: u32, h: f64) {
        self.headings.push(ms, h);
    }

    /// A sample the law answered in control: measured error `eps` at `t_s`, command `omega`.
    pub(crate) fn observe(&mut self, t_s: f64, eps: f64, omega: f64) {
        let s = &mut self.metrics;
        let t0 = *s.t0_s.get_or_insert(t_s);
        let k = ((t_s - t0) / s.period_s).round().max(0.0) as u64;
        if let Some(w) = s.held.replace(omega) {
            s.m.integrate_command(w);
        }
        s.m.observe(k, eps, omega);
        if s.kept.len() < MAX_KEPT_SAMPLES {
            s.kept.push((t_s, eps, omega));
        } else {
            s.kept_all = false;
        }
    }

    /// The metrics, and what they were computed over in words; `completed`: the flight reached
    /// its planned end.
    ///
    /// A completed flight's are the planned window's: steady state over the last
    /// `metrics.steady_state_fraction` of the planned duration. A flight that ended early (a
    /// pilot took over, a failsafe) has flown less than that window, often none of it: its
    /// metrics are computed over what was flown instead, the steady state over the last
    /// fraction of the steps from its first sample answered in control to its last, and the
    /// convergence time within them (the same [`Metrics`] on the same samples, only the
    /// window and the end moved).
    pub(crate) fn metrics(&self, completed: bool) -> (RunMetrics, String) {
        let s = &self.metrics;
        let pct = format!("{}%", s.fraction * 100.0);
        let planned = format!(
            "the samples the law answered in control (measured error, sampling period {} s); steady state over the last {pct} of the planned {} s",
            s.period_s, s.planned_s
        );
        let Some(&(t_last, _, _)) = s.kept.last() else {
            return (
                s.m.finish(completed),
                "no sample answered in control: no tracking metrics".into(),
            );
        };
        if completed {
            return (s.m.finish(true), planned);
        }
        if !s.kept_all {
            return (
                s.m.finish(false),
                format!("{planned} (the flight ended early, but was too long to keep its samples: the planned window's)"),
            );
        }
        let t0 = s.kept[0].0;
        let n = ((t_last - t0) / s.period_s).round().max(0.0);
        let mut cfg = s.cfg;
        cfg.steady_state_start_step = ((1.0 - s.fraction) * n).ceil() as u64;
        cfg.convergence_min_dwell_steps = cfg.convergence_min_dwell_steps.min(n as u64);
        let mut m = Metrics::new(cfg);
        let mut held = None;
        for &(t, eps, w) in &s.kept {
            let k = ((t - t0) / s.period_s).round().max(0.0) as u64;
            if let Some(h) = held.replace(w) {
                m.integrate_command(h);
            }
            m.observe(k, eps, w);
        }
        m.add_path(s.m.finish(false).path_length_m);
        (
            m.finish(true),
            format!(
                "the samples the law answered in control (measured error, sampling period {} s); the flight ended early, after {} s of the planned {} s: steady state over the last {pct} of what was flown, convergence within it",
                s.period_s,
                t_last - t0,
                s.planned_s
            ),
        )
    }

    /// Queues `row` for its pose (`ms`: its measurement's vehicle time; `None`: now's pose).
    pub(crate) fn row<S: TraceSink + ?Sized>(
        &mut self,
        sink: &mut S,
        row: TraceRow,
        ms: Option<u32>,
    ) {
        let mut row = row;
        if ms.is_none() {
            (row.x_m, row.y_m) = self.positions.newest().unwrap_or((f64::NAN, f64::NAN));
            row.heading_rad = self.headings.newest().unwrap_or(f64::NAN);
        }
        self.pending.push_back(Pending {
            row,
            ms,
            at: Instant::now(),
        });
        self.write_ready(sink, false);
    }

    /// Writes the rows whose pose is known (all of them if `all`), in order.
    fn write_ready<S: TraceSink + ?Sized>(&mut self, sink: &mut S, all: bool) {
        while let Some(p) = self.pending.front() {
            let ready = match p.ms {
                None => true,
                Some(ms) => {
                    all || p.at.elapsed() >= self.max_wait
                        || (self.positions.covers(ms) && self.headings.covers(ms))
                }
            };
            if !ready {
                break;
            }
            let Some(mut p) = self.pending.pop_front() else {
                break;
            };
            if let Some(ms) = p.ms {
                (p.row.x_m, p.row.y_m) = self.positions.at(ms).unwrap_or((f64::NAN, f64::NAN));
                p.row.heading_rad = self.headings.at(ms).unwrap_or(f64::NAN);
            }
            sink.record(&p.row);
            self.unflushed += 1;
        }
    }

    /// Once a turn of the loop: writes the rows that are ready, and flushes (`flush`) after
    /// [`FLUSH_EVERY_ROWS`] rows or [`FLUSH_INTERVAL_S`] with rows unflushed.
    pub(crate) fn tick<S: TraceSink + ?Sized>(
        &mut self,
        sink: &mut S,
        flush: &mut dyn FnMut(&mut S),
    ) {
        self.write_ready(sink, false);
        if self.unflushed >= FLUSH_EVERY_ROWS
            || (self.unflushed > 0 && self.last_flush.elapsed().as_secs_f64() >= FLUSH_INTERVAL_S)
        {
            flush(sink);
            self.unflushed = 0;
            self.last_flush = Instant::now();
        }
    }

    /// At the end: every row written (with the pose there is), flushed.
    pub(crate) fn finish<S: TraceSink + ?Sized>(
        &mut self,
        sink: &mut S,
        flush: &mut dyn FnMut(&mut S),
    ) {
        self.write_ready(sink, true);
        flush(sink);
        self.unflushed = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The latest stamped at or before: 150 ms takes 100's; 200 takes 200's; 50, none.
    #[test]
    fn history_pairs_at_or_before() {
        let mut h = History::default();
        h.push(100, 1.0);
        h.push(200, 2.0);
        h.push(150, 9.0); // late: dropped
        assert_eq!(h.at(150), Some(1.0));
        assert_eq!(h.at(200), Some(2.0));
        assert_eq!(h.at(50), None);
        assert!(h.covers(200) && !h.covers(201));
        assert!(History::<f64>::default().covers(5));
    }

    struct Rows(Vec<TraceRow>);
    impl TraceSink for Rows {
        fn record(&mut self, row: &TraceRow) {
            self.0.push(*row);
        }
    }

    /// After an invalid position (200 ms), rows get no position (NaN) until the next valid one
    /// (300 ms), not the last valid one (100 ms) repeated; a row before it keeps its own.
    #[test]
    fn rows_after_an_invalid_position_have_none() {
        let s = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let mut r = Recorder::new(&s, 10.0);
        let mut sink = Rows(Vec::new());
        r.position(100, (1.0, 2.0), true);
        r.no_position(200);
        r.position(300, (3.0, 4.0), true);
        let row = TraceRow {
            t_s: 0.0,
            x_m: 0.0,
            y_m: 0.0,
            heading_rad: 0.0,
            s: 0.0,
            error: 0.0,
            omega_radps: 0.0,
            s_measured: None,
            telemetry: None,
        };
        for ms in [150, 200, 250, 300] {
            r.row(&mut sink, row, Some(ms));
        }
        r.finish(&mut sink, &mut |_| {});
        let xy: Vec<(f64, f64)> = sink.0.iter().map(|r| (r.x_m, r.y_m)).collect();
        assert_eq!(xy[0], (1.0, 2.0));
        assert!(xy[1].0.is_nan() && xy[1].1.is_nan(), "{xy:?}");
        assert!(xy[2].0.is_nan() && xy[2].1.is_nan(), "{xy:?}");
        assert_eq!(xy[3], (3.0, 4.0));
    }
}
