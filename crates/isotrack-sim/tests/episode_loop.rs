//! The loop (`Episode`, `simulate`) on toy parts whose every number is known by hand: a ramp
//! field `F(x, y) = x` (no value beyond `x_max`), a unicycle stepped by Euler
//! (`x += v cos(h) dt`, `y += v sin(h) dt`, `h += omega dt`; NaN beyond a turn-rate limit), and
//! scripted controllers. Step order, sample timing, held commands, the trace and its last row,
//! every outcome with its step and detail, the metrics the loop feeds, and the batched loop
//! (`simulate_batch`) against each run alone.

use isotrack_core::vehicle::Telemetry;
use isotrack_core::{IsolineController, Measurement, Pose2, ScalarField, Vec2, Vehicle};
use isotrack_sim::{
    simulate, Episode, Metrics, MetricsConfig, NoTrace, Oracles, Outcome, RunResult, Sensor,
    SensorConfig, StepPlan, TraceRow,
};

struct Ramp {
    x_max: f64,
}
impl ScalarField for Ramp {
    fn value(&self, _t: f64, p: Vec2) -> Option<f64> {
        (p.x < self.x_max).then_some(p.x)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Unicycle {
    x: f64,
    y: f64,
    h: f64,
}
struct Euler {
    v: f64,
}
impl Vehicle for Euler {
    type State = Unicycle;
    fn step(&self, s: &mut Unicycle, w: f64, dt: f64) {
        if w.abs() > 1e6 {
            s.x = f64::NAN;
            return;
        }
        s.x += self.v * s.h.cos() * dt;
        s.y += self.v * s.h.sin() * dt;
        s.h += w * dt;
    }
    fn pose(&self, s: &Unicycle) -> Pose2 {
        Pose2 {
            position: Vec2::new(s.x, s.y),
            heading_rad: s.h,
        }
    }
    fn speed_mps(&self, _s: &Unicycle) -> f64 {
        self.v
    }
    fn telemetry(&self, s: &Unicycle) -> Option<Telemetry> {
        Some(Telemetry {
            altitude_m: s.y,
            airspeed_mps: self.v,
            roll_rad: 0.0,
        })
    }
}

/// Answers each sample with `f(t, value)` and remembers what it saw.
struct Scripted<F: FnMut(f64, f64) -> f64> {
    f: F,
    seen: Vec<(f64, f64)>,
}
impl<F: FnMut(f64, f64) -> f64> IsolineController for Scripted<F> {
    fn update(&mut self, m: &Measurement) -> f64 {
        self.seen.push((m.t_s, m.value));
        (self.f)(m.t_s, m.value)
    }
    fn reset(&mut self) {}
}

const DT: f64 = 0.1;

fn plan(duration_s: f64, record_rate_hz: f64) -> StepPlan {
    // Window: the last 20 % (steps 16..=20 of 20); tolerance 0.1; no dwell; level 0.5.
    StepPlan::new(DT, duration_s, record_rate_hz, 0.2, 0.1, 0.0, 0.5).unwrap()
}

fn sensor(rate_hz: f64) -> Sensor {
    Sensor::new(
        SensorConfig {
            rate_hz,
            ..SensorConfig::default()
        },
        DT,
        0,
    )
    .unwrap()
}

fn start(x: f64) -> Unicycle {
    Unicycle { x, y: 0.0, h: 0.0 }
}

fn run(
    x_max: f64,
    x0: f64,
    rate_hz: f64,
    record_hz: f64,
    law: impl FnMut(f64, f64) -> f64,
) -> (RunResult, Vec<TraceRow>, Vec<(f64, f64)>) {
    let mut c = Scripted {
        f: law,
        seen: vec![],
    };
    let mut rows = vec![];
    let dist = |_t: f64, p: Vec2| Some((p.x - 0.5).abs());
    let oracles = Oracles {
        isoline_distance: Some(&dist),
        gradient: None,
    };
    let r = simulate(
        &Ramp { x_max },
        &Euler { v: 1.0 },
        start(x0),
        &mut c,
        sensor(rate_hz),
        &plan(2.0, record_hz),
        &oracles,
        &mut rows,
    );
    (r, rows, c.seen)
}

/// Straight along x at 1 m/s from x = 0: x_k = 0.1 k exactly enough, s = x, eps = x - 0.5.
#[test]
fn a_straight_run_by_hand() {
    let (r, rows, seen) = run(f64::INFINITY, 0.0, 10.0, 10.0, |_, _| 0.0);
    assert_eq!(r.outcome, Outcome::Completed);
    assert_eq!(r.outcome_detail, None);
    assert_eq!((r.steps, r.samples, r.samples_dropped), (20, 21, 0));
    assert!((r.t_end_s - 2.0).abs() < 1e-12);
    assert!((r.end_position_m[0] - 2.0).abs() < 1e-12 && r.end_position_m[1] == 0.0);
    // One row per step, t = k dt, the error against the level, the measurement the same.
    assert_eq!(rows.len(), 21);
    for (k, row) in rows.iter().enumerate() {
        let x = 0.1 * k as f64;
        assert!((row.t_s - x).abs() < 1e-12, "row {k}");
        assert!((row.x_m - x).abs() < 1e-12 && (row.s - x).abs() < 1e-12);
        assert!((row.error - (x - 0.5)).abs() < 1e-12);
        assert_eq!(row.s_measured, Some(row.s));
        assert_eq!(row.telemetry.unwrap().airspeed_mps, 1.0);
    }
    assert_eq!(seen.len(), 21);
    // Steady window: steps 16..=20, eps = 1.1 .. 1.5.
    let m = &r.metrics;
    let eps: Vec<f64> = (16..=20).map(|k| 0.1 * k as f64 - 0.5).collect();
    assert!((m.steady_state_max_abs_error.unwrap() - 1.5).abs() < 1e-12);
    let mean = eps.iter().sum::<f64>() / 5.0;
    let rms = (eps.iter().map(|e| e * e).sum::<f64>() / 5.0).sqrt();
    assert!((m.steady_state_mean_error.unwrap() - mean).abs() < 1e-12);
    assert!((m.steady_state_rms_error.unwrap() - rms).abs() < 1e-12);
    // The isoline distance |x - 0.5| is taken on the window's steps only.
    assert!((m.steady_state_max_isoline_distance_m.unwrap() - 1.5).abs() < 1e-12);
    assert!((m.steady_state_rms_isoline_distance_m.unwrap() - rms).abs() < 1e-12);
    assert_eq!(m.time_in_band_fraction, Some(0.0));
    assert_eq!(m.convergence_time_s, None);
    assert!((m.path_length_m - 2.0).abs() < 1e-12);
    assert_eq!(m.control_effort, 0.0);
}

/// A held turn command: effort = sum of omega^2 dt over the 20 integrated steps (the final
/// sample's command is never integrated), and the heading turns by omega * t.
#[test]
fn commands_are_held_and_integrated() {
    let (r, rows, _) = run(f64::INFINITY, 0.0, 10.0, 10.0, |_, _| 0.5);
    assert!((r.metrics.control_effort - 0.25 * DT * 20.0).abs() < 1e-12);
    assert!((rows[20].heading_rad - 0.5 * 2.0).abs() < 1e-12);
    assert!(rows.iter().all(|row| row.omega_radps == 0.5));
}

/// A 5 Hz sensor on a 0.1 s step samples every other step: 11 samples over 20 steps, each
/// command held for two steps, and the trace keeps the last measurement between samples.
#[test]
fn the_sensor_period_spaces_samples_and_holds_commands() {
    let mut n = 0.0;
    let (r, rows, seen) = run(f64::INFINITY, 0.0, 5.0, 10.0, move |_, _| {
        n += 1.0;
        n
    });
    assert_eq!(r.samples, 11);
    let times: Vec<f64> = seen.iter().map(|s| s.0).collect();
    for (i, t) in times.iter().enumerate() {
        assert!((t - 0.2 * i as f64).abs() < 1e-12);
    }
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.omega_radps, (k / 2 + 1) as f64, "row {k}");
        // The measurement of the last sample step (an ideal sensor: the true value there).
        assert_eq!(row.s_measured, Some(rows[2 * (k / 2)].s), "row {k}");
    }
}

/// Recording every third step: rows 0, 3, ..., 18, and the last valid step (20) always.
#[test]
fn the_trace_keeps_every_nth_row_and_the_last() {
    let (_, rows, _) = run(f64::INFINITY, 0.0, 10.0, 10.0 / 3.0, |_, _| 0.0);
    let ks: Vec<i64> = rows.iter().map(|r| (r.t_s / DT).round() as i64).collect();
    assert_eq!(ks, [0, 3, 6, 9, 12, 15, 18, 20]);
    // With a trace rate that lands on the last step, no duplicate row.
    let (_, rows, _) = run(f64::INFINITY, 0.0, 10.0, 5.0, |_, _| 0.0);
    let ks: Vec<i64> = rows.iter().map(|r| (r.t_s / DT).round() as i64).collect();
    assert_eq!(ks, [0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20]);
    // No trace at all with rate 0.
    let (_, rows, _) = run(f64::INFINITY, 0.0, 10.0, 0.0, |_, _| 0.0);
    assert!(rows.is_empty());
}

/// Past x = 1.05 the field has no value: the run ends at step 11 as `left_field`, its last
/// valid step 10 (t = 1 s), which is the trace's last row.
#[test]
fn leaving_the_field_ends_the_run_at_the_last_valid_step() {
    let (r, rows, _) = run(1.05, 0.0, 10.0, 10.0 / 3.0, |_, _| 0.0);
    assert_eq!(r.outcome, Outcome::LeftField);
    assert_eq!(r.steps, 10);
    assert!((r.t_end_s - 1.0).abs() < 1e-12);
    assert!(r
        .outcome_detail
        .unwrap()
        .contains("no value at (1.100000, 0.000000) m"));
    assert!((rows.last().unwrap().t_s - 1.0).abs() < 1e-12);
    assert!(
        rows.iter().all(|row| row.s.is_finite()),
        "no row for the step off the field"
    );
    assert!((r.metrics.path_length_m - 1.0).abs() < 1e-12);
    assert_eq!(r.metrics.convergence_time_s, None);
    // Starting off the field: one row with the start and NaN value and error.
    let (r, rows, seen) = run(1.0, 2.0, 10.0, 10.0, |_, _| 0.0);
    assert_eq!((r.outcome, r.steps, r.samples), (Outcome::LeftField, 0, 0));
    assert!(seen.is_empty());
    assert_eq!(rows.len(), 1);
    assert!(rows[0].s.is_nan() && rows[0].error.is_nan() && rows[0].x_m == 2.0);
    // Without a trace, not even that row.
    let (_, rows, _) = run(1.0, 2.0, 10.0, 0.0, |_, _| 0.0);
    assert!(rows.is_empty());
}

/// A non-finite first command (t = 0) ends the run before any step, but the trace still holds
/// the start: the vehicle at x0, the field's value there, the error from the level (0.5), the
/// command held before any sample (0), the measured value; without a trace, no row.
#[test]
fn a_run_diverging_at_its_first_sample_keeps_its_start_row() {
    let (r, rows, seen) = run(f64::INFINITY, 0.25, 10.0, 10.0, |_, _| f64::NAN);
    assert_eq!((r.outcome, r.steps), (Outcome::Diverged, 0));
    assert_eq!(seen.len(), 1);
    assert_eq!(rows.len(), 1);
    let row = &rows[0];
    assert_eq!((row.t_s, row.x_m, row.omega_radps), (0.0, 0.25, 0.0));
    assert_eq!(row.error, row.s - 0.5);
    assert_eq!(row.s_measured, Some(seen[0].1));
    let (_, rows, _) = run(f64::INFINITY, 0.25, 10.0, 0.0, |_, _| f64::NAN);
    assert!(rows.is_empty());
}

/// A non-finite command ends the run at its sample (`diverged`, the step before is the last
/// valid one); so does a non-finite vehicle state, one step later.
#[test]
fn non_finite_commands_and_states_diverge() {
    let (r, _, _) = run(f64::INFINITY, 0.0, 10.0, 10.0, |t, _| {
        if t > 0.45 {
            f64::NAN
        } else {
            0.0
        }
    });
    assert_eq!(r.outcome, Outcome::Diverged);
    assert_eq!(r.steps, 4);
    assert!(r
        .outcome_detail
        .unwrap()
        .contains("non-finite turn-rate command at t = 0.5 s"));
    let (r, _, _) = run(f64::INFINITY, 0.0, 10.0, 10.0, |t, _| {
        if t > 0.45 {
            1e7
        } else {
            0.0
        }
    });
    assert_eq!(r.outcome, Outcome::Diverged);
    assert_eq!(r.steps, 5);
    assert!(r
        .outcome_detail
        .unwrap()
        .contains("non-finite vehicle state at t = 0.6"));
    assert_eq!(Outcome::Completed.as_str(), "completed");
    assert_eq!(Outcome::LeftField.as_str(), "left_field");
    assert_eq!(Outcome::Diverged.as_str(), "diverged");
}

/// Driven one command at a time, the episode is the same run; while a sample waits, asking again
/// returns it; its clock and held command are readable; a command without a waiting sample does
/// nothing.
#[test]
fn an_episode_driven_from_outside_is_the_same_run() {
    let law = |t: f64, v: f64| 0.3 * (v - 0.5) + t;
    let (want, _, _) = run(f64::INFINITY, 0.0, 5.0, 0.0, law);
    let (field, vehicle) = (
        Ramp {
            x_max: f64::INFINITY,
        },
        Euler { v: 1.0 },
    );
    let dist = |_t: f64, p: Vec2| Some((p.x - 0.5).abs());
    let oracles = Oracles {
        isoline_distance: Some(&dist),
        gradient: None,
    };
    let mut e = Episode::new(&vehicle, start(0.0), sensor(5.0), &plan(2.0, 0.0));
    assert_eq!(e.outcome(), None);
    let mut n = 0;
    while let Some(s) = e.run_to_sample(&field, &vehicle, &oracles, &mut NoTrace) {
        let again = e
            .run_to_sample(&field, &vehicle, &oracles, &mut NoTrace)
            .unwrap();
        assert_eq!(again, s);
        assert!((e.t_s() - 0.2 * n as f64).abs() < 1e-12);
        assert!((s.true_value - s.pose.position.x).abs() < 1e-15 && s.speed_mps == 1.0);
        let w = law(s.measurement.t_s, s.measurement.value);
        e.command(w, &vehicle, &oracles, &mut NoTrace);
        assert_eq!(e.omega_radps(), w);
        assert!(e.state().x >= 0.0);
        n += 1;
    }
    assert_eq!(n, 11);
    assert_eq!(e.outcome(), Some(Outcome::Completed));
    e.command(5.0, &vehicle, &oracles, &mut NoTrace); // nothing waits: ignored
    assert_eq!(e.finish(&mut NoTrace), want);
}

/// `Vec<TraceRow>` records what it is given.
#[test]
fn a_vec_records_rows() {
    use isotrack_sim::TraceSink;
    let mut v: Vec<TraceRow> = vec![];
    let row = TraceRow {
        t_s: 1.0,
        x_m: 2.0,
        y_m: 3.0,
        heading_rad: 0.0,
        s: 4.0,
        error: 5.0,
        omega_radps: 6.0,
        s_measured: None,
        telemetry: None,
    };
    v.record(&row);
    assert_eq!(v, [row]);
}

fn metrics(start: u64, dwell: u64) -> Metrics {
    Metrics::new(MetricsConfig {
        dt_s: 0.5,
        steady_state_start_step: start,
        convergence_tolerance: 0.1,
        convergence_min_dwell_steps: dwell,
        track_loss_band: 0.5,
    })
}

/// Boundaries: |eps| equal to the tolerance is in the band (<=) but not converged (<); the
/// track-loss band is left only beyond it (>); a NaN error is a loss.
#[test]
fn metrics_boundaries_and_track_losses() {
    let mut m = metrics(0, 0);
    for (k, e) in [0.1, 0.1].iter().enumerate() {
        m.observe(k as u64, *e, 0.0);
    }
    let r = m.finish(true);
    assert_eq!(r.time_in_band_fraction, Some(1.0));
    assert_eq!(r.convergence_time_s, None);
    // Tracked at 0.05; 0.5 is on the band's edge (kept); 0.6 is a loss; 0.3 is no re-acquisition;
    // 0.05 re-acquires; NaN is a second loss.
    let mut m = metrics(100, 0);
    for (k, e) in [0.05, 0.5, 0.05, 0.6, 0.05, 0.3, 0.05, f64::NAN]
        .iter()
        .enumerate()
    {
        m.observe(k as u64, *e, 0.0);
    }
    assert_eq!(m.finish(true).track_losses, 2);
    // Never within the tolerance: leaving the band is not a loss.
    let mut m = metrics(100, 0);
    for (k, e) in [0.2, 0.9, 0.2].iter().enumerate() {
        m.observe(k as u64, *e, 0.0);
    }
    assert_eq!(m.finish(true).track_losses, 0);
    assert!(!m.in_window(99) && m.in_window(100));
}

/// Sign changes of omega skip zeros (1, 0, -1, 0, 1: two changes); total variation and both
/// rates are per second of the window, (n - 1) dt = 2 s.
#[test]
fn metrics_chattering_and_sign_changes() {
    let mut m = metrics(0, 0);
    for (k, w) in [1.0, 0.0, -1.0, 0.0, 1.0].iter().enumerate() {
        m.observe(k as u64, 0.0, *w);
    }
    let r = m.finish(true);
    assert_eq!(r.sign_changes_per_s, Some(2.0 / 2.0));
    assert_eq!(r.chattering_radps2, Some(4.0 / 2.0));
    // A zero command has no sign: -1, 0, -1 and 1, 0, 1 change sign nowhere.
    for ws in [[-1.0, 0.0, -1.0], [1.0, 0.0, 1.0]] {
        let mut m = metrics(0, 0);
        for (k, w) in ws.iter().enumerate() {
            m.observe(k as u64, 0.0, *w);
        }
        assert_eq!(m.finish(true).sign_changes_per_s, Some(0.0), "{ws:?}");
    }
    // A one-step window has no duration: no rates.
    let mut m = metrics(0, 0);
    m.observe(0, 0.0, 1.0);
    let r = m.finish(true);
    assert_eq!((r.chattering_radps2, r.sign_changes_per_s), (None, None));
}

/// Isoline distances, effort and path accumulate as stated; convergence needs the dwell.
#[test]
fn metrics_accumulators_and_dwell() {
    let mut m = metrics(0, 0);
    m.observe_isoline_distance(3.0);
    m.observe_isoline_distance(4.0);
    m.integrate_command(2.0);
    m.integrate_command(-1.0);
    m.add_path(1.5);
    m.add_path(2.5);
    m.observe(0, 0.0, 0.0);
    let r = m.finish(true);
    assert_eq!(r.steady_state_max_isoline_distance_m, Some(4.0));
    assert_eq!(r.steady_state_rms_isoline_distance_m, Some(12.5f64.sqrt()));
    assert_eq!(r.control_effort, (4.0 + 1.0) * 0.5);
    assert_eq!(r.path_length_m, 4.0);
    // No isoline distance observed: none reported.
    let mut m = metrics(0, 0);
    m.observe(0, 0.0, 0.0);
    let r = m.finish(true);
    assert_eq!(r.steady_state_max_isoline_distance_m, None);
    assert_eq!(r.steady_state_rms_isoline_distance_m, None);
    // Never outside the tolerance: converged at 0 once the run lasted the dwell, not before.
    let run = |dwell: u64, steps: u64, violation_at: Option<u64>| {
        let mut m = metrics(0, dwell);
        for k in 0..=steps {
            let e = if Some(k) == violation_at { 1.0 } else { 0.0 };
            m.observe(k, e, 0.0);
        }
        m.finish(true).convergence_time_s
    };
    assert_eq!(run(4, 4, None), Some(0.0));
    assert_eq!(run(5, 4, None), None);
    // Outside at step 2, inside from step 3 to 8: 5 steps after the violation, converged at
    // (2 + 1) * 0.5 s when the dwell is below 6 steps.
    assert_eq!(run(5, 8, Some(2)), Some(1.5));
    assert_eq!(run(6, 8, Some(2)), None);
    assert_eq!(run(0, 8, Some(8)), None);
    // An incomplete run reports no convergence.
    let mut m = metrics(0, 0);
    m.observe(0, 0.0, 0.0);
    assert_eq!(m.finish(false).convergence_time_s, None);
}

/// `whole_steps`: whole to 1e-9 relative, at most MAX_STEPS (exactly MAX_STEPS is allowed).
#[test]
fn whole_steps_edges() {
    use isotrack_sim::{whole_steps, StepsError, MAX_STEPS};
    assert_eq!(whole_steps(600.0, 0.01), Ok(60_000));
    assert_eq!(whole_steps(1.0 + 5e-10, 1.0), Ok(1));
    assert_eq!(whole_steps(1.0 + 5e-9, 1.0), Err(StepsError::NotWhole));
    assert_eq!(whole_steps(1e6 * (1.0 + 5e-10), 1.0), Ok(1_000_000));
    assert_eq!(whole_steps(-1.0, 1.0), Err(StepsError::NotWhole));
    assert_eq!(whole_steps(MAX_STEPS as f64, 1.0), Ok(MAX_STEPS));
    assert_eq!(
        whole_steps(2.0 * MAX_STEPS as f64, 1.0),
        Err(StepsError::TooMany)
    );
    assert_eq!(whole_steps(1e300, 1.0), Err(StepsError::TooMany));
    // An infinite count is too many, not "not whole".
    assert_eq!(whole_steps(1e300, 1e-300), Err(StepsError::TooMany));
    assert_eq!(whole_steps(f64::NAN, 1.0), Err(StepsError::NotWhole));
}

/// A robot standing on the isoline (speed 0, x = s_d): converged from t = 0 when the run
/// completes; a run that ends early reports no convergence time.
#[test]
fn convergence_is_reported_for_completed_runs_only() {
    let go = |x_max: f64| {
        let mut c = Scripted {
            f: |t: f64, _| if t > 1.05 { f64::NAN } else { 0.0 },
            seen: vec![],
        };
        simulate(
            &Ramp { x_max },
            &Euler { v: 0.0 },
            start(0.5),
            &mut c,
            sensor(10.0),
            &plan(1.0, 0.0),
            &Oracles::default(),
            &mut NoTrace,
        )
    };
    let r = go(f64::INFINITY);
    assert_eq!(r.outcome, Outcome::Completed);
    assert_eq!(r.metrics.convergence_time_s, Some(0.0));
    assert_eq!(r.metrics.time_in_band_fraction, Some(1.0));
    // The same, cut short by a NaN command at t = 1.1 s in a 2 s run.
    let mut c = Scripted {
        f: |t: f64, _| if t > 1.05 { f64::NAN } else { 0.0 },
        seen: vec![],
    };
    let r = simulate(
        &Ramp {
            x_max: f64::INFINITY,
        },
        &Euler { v: 0.0 },
        start(0.5),
        &mut c,
        sensor(10.0),
        &plan(2.0, 0.0),
        &Oracles::default(),
        &mut NoTrace,
    );
    assert_eq!(r.outcome, Outcome::Diverged);
    assert_eq!(r.metrics.convergence_time_s, None);
}

/// A law by hand: `-kp (s - 1/2)` from a sample; from ground truth (when it asks for it) a
/// different mix of the true value, gradient, heading, speed and time, so a lane that took the
/// wrong path shows; from `blow_up_at_s` on, `blow_up` (NaN: a non-finite command; 2e6: the
/// unicycle's state goes NaN at the next step).
#[derive(Clone, Copy)]
struct Law {
    kp: f64,
    truth: bool,
    blow_up_at_s: f64,
    blow_up: f64,
}
impl IsolineController for Law {
    fn update(&mut self, m: &Measurement) -> f64 {
        if m.t_s >= self.blow_up_at_s {
            return self.blow_up;
        }
        -self.kp * (m.value - 0.5)
    }
    fn needs_ground_truth(&self) -> bool {
        self.truth
    }
    fn update_with_truth(
        &mut self,
        m: &Measurement,
        truth: &isotrack_core::control::GroundTruth,
    ) -> f64 {
        let gx = truth.derivatives.map_or(0.0, |(g, _)| g.x);
        -self.kp * (truth.value - 0.5) * gx - 0.3 * truth.pose.heading_rad
            + 0.01 * truth.speed_mps
            + 0.001 * m.t_s
    }
    fn reset(&mut self) {}
}

/// `simulate_batch` promises each run the result `simulate` gives it alone, bit for bit: 12
/// runs (a full group of 8 and a group of 4) with their own starts, gains, sensor rates,
/// dropouts and noise, three asking for ground truth, on a ramp that ends at x = 1.2 m, ending
/// every way a run can (completed, one on the isoline from the start and so converged at
/// t = 0, left the field at different steps, a non-finite command, a
/// non-finite state), each compared with its run alone.
#[test]
fn a_batch_gives_each_run_its_result_alone() {
    let field = Ramp { x_max: 1.2 };
    let vehicle = Euler { v: 1.0 };
    let plan = plan(2.0, 0.0);
    let dist = |_t: f64, p: Vec2| Some((p.x - 0.5).abs());
    let gradient = |_t: f64, _p: Vec2| Some((Vec2::new(1.0, 0.0), [[0.0; 2]; 2]));
    let oracles = || Oracles {
        isoline_distance: Some(&dist),
        gradient: Some(&gradient),
    };
    let case = |i: usize| {
        let x0 = if i == 11 {
            // North along the isoline x = 1/2 from the start: converged at once.
            Unicycle {
                x: 0.5,
                y: 0.0,
                h: std::f64::consts::FRAC_PI_2,
            }
        } else {
            Unicycle {
                x: -1.0 + 0.2 * i as f64,
                y: 0.1 * i as f64,
                h: 0.4 * (i % 3) as f64 - 0.4,
            }
        };
        let (blow_up_at_s, blow_up) = match i {
            3 => (0.7, f64::NAN),
            2 => (1.2, 2e6),
            _ => (f64::INFINITY, 0.0),
        };
        let law = Law {
            kp: if i == 11 { 0.0 } else { 0.5 + 0.1 * i as f64 },
            truth: i % 3 == 1,
            blow_up_at_s,
            blow_up,
        };
        let config = SensorConfig {
            rate_hz: [10.0, 5.0, 2.5][i % 3],
            dropout_probability: if i.is_multiple_of(4) { 0.2 } else { 0.0 },
            noise_std: if i.is_multiple_of(5) { 0.01 } else { 0.0 },
            ..SensorConfig::default()
        };
        (x0, law, Sensor::new(config, DT, 7 + i as u64).unwrap())
    };
    let runs = (0..12)
        .map(|i| {
            let (x0, controller, sensor) = case(i);
            isotrack_sim::BatchRun {
                x0,
                controller,
                sensor,
                oracles: oracles(),
            }
        })
        .collect();
    let batch = isotrack_sim::simulate_batch(&field, &vehicle, &plan, runs);
    assert_eq!(batch.len(), 12);
    for (i, got) in batch.iter().enumerate() {
        let (x0, mut law, sensor) = case(i);
        let alone = simulate(
            &field,
            &vehicle,
            x0,
            &mut law,
            sensor,
            &plan,
            &oracles(),
            &mut NoTrace,
        );
        assert_eq!(*got, alone, "run {i}");
    }
    // Every way to end is among them, and the ends differ in time.
    let ended = |o: Outcome, detail: &str| {
        batch
            .iter()
            .any(|r| r.outcome == o && r.outcome_detail.as_deref().unwrap_or("").contains(detail))
    };
    assert!(ended(Outcome::Completed, ""));
    assert_eq!(batch[11].outcome, Outcome::Completed);
    assert_eq!(batch[11].metrics.convergence_time_s, Some(0.0));
    assert!(ended(Outcome::LeftField, "no value at"));
    assert!(ended(
        Outcome::Diverged,
        "non-finite turn-rate command at t = 0.7"
    ));
    assert!(ended(Outcome::Diverged, "non-finite vehicle state"));
    let left: std::collections::BTreeSet<u64> = batch
        .iter()
        .filter(|r| r.outcome == Outcome::LeftField)
        .map(|r| r.steps)
        .collect();
    assert!(left.len() >= 2, "{left:?}");
    assert!(batch.iter().any(|r| r.samples_dropped > 0));
    // The empty batch is empty.
    let none: Vec<isotrack_sim::BatchRun<'_, Unicycle, Law>> = vec![];
    assert!(isotrack_sim::simulate_batch(&field, &vehicle, &plan, none).is_empty());
}

/// `F(x, y) = x` before `x_max`, and `poison` (NaN or infinite: a broken field's value, not
/// `None`) from there on.
struct Poisoned {
    x_max: f64,
    poison: f64,
}
impl ScalarField for Poisoned {
    fn value(&self, _t: f64, p: Vec2) -> Option<f64> {
        Some(if p.x < self.x_max { p.x } else { self.poison })
    }
}

/// One rule for a field's value alone and in lanes: a value that is not finite is no value.
/// Straight along x at 1 m/s from x0 = 0, 0.3, 0.6 (and one from 5 m, already in the poison):
/// the field turns NaN (or +-inf) past x = 1.05, so the runs end as `left_field` at x = 1.1 m,
/// steps 11, 8 and 5 (the last valid ones 10, 7 and 4), and the fourth at its start; exactly as
/// on a field with no value there (`None`), run alone or batched.
#[test]
fn a_non_finite_field_value_ends_the_run_alone_and_in_a_batch() {
    let vehicle = Euler { v: 1.0 };
    let plan = plan(2.0, 0.0);
    let starts = [0.0, 0.3, 0.6, 5.0];
    let law = || Law {
        kp: 0.0,
        truth: false,
        blow_up_at_s: f64::INFINITY,
        blow_up: 0.0,
    };
    let alone = |field: &dyn ScalarField, x0: f64| {
        simulate(
            field,
            &vehicle,
            start(x0),
            &mut law(),
            sensor(10.0),
            &plan,
            &Oracles::default(),
            &mut NoTrace,
        )
    };
    let reference: Vec<RunResult> = starts
        .iter()
        .map(|&x0| alone(&Ramp { x_max: 1.05 }, x0))
        .collect();
    let steps: Vec<u64> = reference.iter().map(|r| r.steps).collect();
    assert_eq!(steps, [10, 7, 4, 0]);
    for (r, x) in reference
        .iter()
        .zip(["1.100000", "1.100000", "1.100000", "5.000000"])
    {
        assert_eq!(r.outcome, Outcome::LeftField);
        let detail = r.outcome_detail.as_deref().unwrap();
        assert!(
            detail.contains(&format!("no value at ({x}, 0.000000) m")),
            "{detail}"
        );
    }
    for poison in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let field = Poisoned {
            x_max: 1.05,
            poison,
        };
        let runs = starts
            .iter()
            .map(|&x0| isotrack_sim::BatchRun {
                x0: start(x0),
                controller: law(),
                sensor: sensor(10.0),
                oracles: Oracles::default(),
            })
            .collect();
        let batch = isotrack_sim::simulate_batch(&field, &vehicle, &plan, runs);
        for (i, &x0) in starts.iter().enumerate() {
            assert_eq!(
                alone(&field, x0),
                reference[i],
                "alone, {poison}, x0 = {x0}"
            );
            assert_eq!(batch[i], reference[i], "batched, {poison}, x0 = {x0}");
        }
    }
}
