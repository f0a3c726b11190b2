//! What `fly` records and sends, against a stand-in vehicle its pilot has armed and switched to
//! OFFBOARD (PX4), which sends, each beat of 50 ms, its heartbeat, then the measurement
//! (`ISO_S`), then the position, attitude and airspeed stamped with the same time (as
//! `isotrack sitl` does: a step's pose follows its sample): the trace pairs each measurement
//! with the position of its time; the metrics are the library's on the measured error; late and
//! repeated measurements never reach the law; a fixed wing's setpoint carries the altitude
//! hold's pitch and the airspeed hold's thrust.

use isotrack_core::{IsolineController, Measurement};
use isotrack_mavlink::fly::{run_fly, FlyOptions, FlyReport};
use isotrack_mavlink::link::Link;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::TraceRow;
use mavlink::dialects::common::*;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// One beat of the stand-in: the measurement's time and value, the position north and the
/// altitude, m.
#[derive(Clone, Copy)]
struct Beat {
    ms: u32,
    value: f32,
    north_m: f32,
    alt_m: f32,
    /// From this beat on the pilot has the vehicle in MANUAL (PX4 main mode 1).
    manual: bool,
}

/// The yaw the stand-in reports at beat `k`, rad.
fn yaw(k: usize) -> f32 {
    0.1 * k as f32
}

/// Flies `s` (no take-over; `--timeout-s` 1) against the stand-in playing `beats`, then
/// beating on without measurements (the flight ends by sensor loss or `opts`' limits; HOLD is
/// confirmed). Returns the report, the trace rows and the setpoints received.
fn pilots_flight(
    s: &Scenario,
    beats: Vec<Beat>,
    opts: impl FnOnce(&mut FlyOptions),
) -> (FlyReport, Vec<TraceRow>, Vec<SET_ATTITUDE_TARGET_DATA>) {
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let finished = done.clone();
    // The vehicle's type is the scenario's kind (a mismatch is refused).
    let mavtype = if s.is_flying() {
        MavType::MAV_TYPE_FIXED_WING
    } else {
        MavType::MAV_TYPE_GROUND_ROVER
    };
    let vehicle = std::thread::spawn(move || {
        let (mut mode, mut k, mut got) = (6u32 << 16, 0usize, Vec::new());
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(60)
            && !finished.load(std::sync::atomic::Ordering::SeqCst)
        {
            for r in link.poll(Duration::from_millis(50)).unwrap() {
                match &r.msg {
                    MavMessage::SET_ATTITUDE_TARGET(a) => got.push(a.clone()),
                    MavMessage::COMMAND_LONG(c) => {
                        mode = ((c.param2 as u32) << 16) | ((c.param3 as u32) << 24);
                        link.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                            command: c.command,
                            result: MavResult::MAV_RESULT_ACCEPTED,
                        }))
                        .unwrap();
                    }
                    _ => {}
                }
            }
            if !link.has_peer() {
                continue;
            }
            if beats.get(k).is_some_and(|b| b.manual) {
                mode = 1 << 16;
            }
            link.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                custom_mode: mode,
                mavtype,
                autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
                base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                    | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                system_status: MavState::MAV_STATE_ACTIVE,
                mavlink_version: 3,
            }))
            .unwrap();
            let Some(b) = beats.get(k).copied() else {
                continue;
            };
            let mut name = [0u8; 10];
            name[..5].copy_from_slice(b"ISO_S");
            for m in [
                MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                    time_boot_ms: b.ms,
                    value: b.value,
                    name: name.into(),
                }),
                MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: b.ms,
                    x: b.north_m,
                    z: -b.alt_m,
                    ..Default::default()
                }),
                MavMessage::ATTITUDE(ATTITUDE_DATA {
                    time_boot_ms: b.ms,
                    yaw: yaw(k),
                    ..Default::default()
                }),
                MavMessage::VFR_HUD(VFR_HUD_DATA {
                    airspeed: 25.0,
                    ..Default::default()
                }),
            ] {
                link.send(&m).unwrap();
            }
            k += 1;
        }
        got
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 1.0;
    opts(&mut o);
    let mut rows: Vec<TraceRow> = Vec::new();
    let r = run_fly(s, &o, &mut rows, &mut |_| Ok(())).unwrap();
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    (r, rows, vehicle.join().unwrap())
}

fn beats(values: &[f32], ms: impl Fn(usize) -> u32) -> Vec<Beat> {
    values
        .iter()
        .enumerate()
        .map(|(k, &value)| Beat {
            ms: ms(k),
            value,
            north_m: k as f32,
            alt_m: 100.0,
            manual: false,
        })
        .collect()
}

/// Each row has the position and heading stamped with its measurement's time (beat k: k m
/// north, yaw 0.1 k), though they arrived after the measurement: never the previous beat's.
#[test]
fn trace_rows_have_the_position_of_their_time() {
    let s = load_scenario(None, &[]).unwrap();
    let values: Vec<f32> = (0..12).map(|k| 1.0 + 0.01 * k as f32).collect();
    let (r, rows, _) = pilots_flight(&s, beats(&values, |k| 1000 + 50 * k as u32), |_| {});
    assert_eq!(rows.len(), 12, "{:?}", r.events);
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.t_s, (1000 + 50 * k) as f64 / 1000.0);
        assert_eq!((row.x_m, row.y_m), (0.0, k as f64), "row {k}");
        let heading = std::f64::consts::FRAC_PI_2 - yaw(k) as f64;
        assert!((row.heading_rad - heading).abs() < 1e-12, "row {k}");
        assert_eq!(row.s_measured, Some(values[k] as f64));
    }
}

/// The metrics are the library's on the measured error: with `--max-duration-s` 10 and 20
/// measurements 0.5 s apart (the default scenario samples every 10 ms step: the sampling
/// period of the metrics), the steady-state window (the last 20 % of the planned 10 s: from
/// step 800) holds measurements 16 to 19, and the control effort sums each command but the
/// last over one sampling period (0.01 s).
#[test]
fn metrics_are_of_the_measured_error() {
    let s = load_scenario(None, &[]).unwrap();
    let level = s.level();
    let eps: Vec<f64> = (0..30)
        .map(|k| 0.3 * if k % 2 == 0 { 1.0 } else { -1.0 } / (k + 1) as f64)
        .collect();
    let values: Vec<f32> = eps.iter().map(|e| (level + e) as f32).collect();
    let (r, _, _) = pilots_flight(&s, beats(&values, |k| 1000 + 500 * k as u32), |o| {
        o.max_duration_s = Some(10.0)
    });
    assert_eq!(r.commands.len(), 20, "{:?}", r.events);
    // The error as measured (f32 on the wire).
    let e: Vec<f64> = values.iter().map(|&v| v as f64 - level).collect();
    let window = &e[16..20];
    let max = window.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mean = window.iter().sum::<f64>() / 4.0;
    let rms = (window.iter().map(|x| x * x).sum::<f64>() / 4.0).sqrt();
    assert_eq!(r.metrics.steady_state_max_abs_error, Some(max));
    assert!((r.metrics.steady_state_mean_error.unwrap() - mean).abs() < 1e-15);
    assert!((r.metrics.steady_state_rms_error.unwrap() - rms).abs() < 1e-15);
    let mut law = s.tracker();
    let w: Vec<f64> = (0..20)
        .map(|k| {
            law.update(&Measurement {
                t_s: (1000 + 500 * k) as f64 / 1000.0,
                value: values[k] as f64,
            })
        })
        .collect();
    let effort: f64 = w[..19].iter().map(|w| w * w * 0.01).sum();
    assert!((r.metrics.control_effort - effort).abs() <= 1e-12 * effort.max(1e-300));
}

/// A measurement older than one answered is dropped, a repeat answered again: neither reaches
/// the law (whose derivative estimator sees 1000, 1050, 1100, 1150, 1200 ms only), both are
/// counted, the late ones logged once.
#[test]
fn late_and_repeated_measurements_never_reach_the_law() {
    let s = load_scenario(None, &[]).unwrap();
    let times = [1000, 1050, 1020, 1050, 1100, 1010, 1150, 1200];
    let values = [1.0f32, 1.5, 9.0, 7.0, 1.2, 8.0, 1.1, 1.3];
    let b = beats(&values, |k| times[k]);
    let (r, _, _) = pilots_flight(&s, b, |_| {});
    let mut law = s.tracker();
    let expected: Vec<(u32, f64)> = [0, 1, 4, 6, 7]
        .iter()
        .map(|&k| {
            let w = law.update(&Measurement {
                t_s: times[k] as f64 / 1000.0,
                value: values[k] as f64,
            });
            (times[k], w)
        })
        .collect();
    assert_eq!(r.commands, expected, "{:?}", r.events);
    assert_eq!(r.measurements_out_of_order, 2);
    assert_eq!(r.measurements_repeated, 1);
    let logged = r
        .events
        .iter()
        .filter(|e| e.contains("out of order"))
        .count();
    assert_eq!(logged, 1, "{:?}", r.events);
}

/// A fixed wing's setpoint (Fig. 3's UAV, V = 30 m/s) is an attitude with thrust (type mask:
/// the three body rates ignored, nothing else): flying 10 m below the first altitude it
/// reported once the companion had control, the pitch is k_h (10 m - 2 m dead zone) = 0.02 x 8 = 0.16 rad
/// nose up; at 25 m/s the thrust is 0.5 + 0.05 x 5 = 0.75; the roll is the law's
/// `-atan(omega V / g)`. At the starting altitude the pitch is 0.
#[test]
fn a_fixed_wing_setpoint_holds_altitude_and_airspeed() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let values: Vec<f32> = (0..16).map(|k| 10.3 - 0.01 * k as f32).collect();
    let mut b = beats(&values, |k| 1000 * k as u32);
    for x in &mut b[8..] {
        x.alt_m = 90.0;
    }
    let (r, _, got) = pilots_flight(&s, b, |_| {});
    assert_eq!(r.commands.len(), 16, "{:?}", r.events);
    let answer = |ms: u32| {
        got.iter()
            .find(|a| a.time_boot_ms == ms)
            .unwrap_or_else(|| panic!("no answer to {ms}"))
    };
    let euler = |q: [f32; 4]| {
        let [w, x, y, z] = q.map(f64::from);
        (
            (2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y)),
            (2.0 * (w * y - z * x)).asin(),
        )
    };
    let mask = AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE
        | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE
        | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE;
    let mut law = s.tracker();
    for (k, v) in values.iter().enumerate() {
        let w = law.update(&Measurement {
            t_s: k as f64,
            value: *v as f64,
        });
        let a = answer(1000 * k as u32);
        assert_eq!(a.type_mask, mask, "answer {k}");
        let (roll, pitch) = euler(a.q);
        let expected_roll = -(w * 30.0 / 9.8).atan();
        assert!(
            (roll - expected_roll).abs() < 1e-6,
            "answer {k}: {roll} vs {expected_roll}"
        );
        // The answer to beat k is computed with beat k's altitude or beat k - 1's (whichever
        // came first): 100 m up to beat 7, 90 m from beat 8 on.
        if k <= 7 {
            assert_eq!(pitch, 0.0, "answer {k}");
        } else if k >= 9 {
            assert!((pitch - 0.16).abs() < 1e-6, "answer {k}: pitch {pitch}");
        }
        if k >= 1 {
            assert_eq!(a.thrust, 0.75, "answer {k}");
        }
    }
}

/// A pilot who takes the vehicle back early (MANUAL at the 21st of 30 measurements, 0.5 s
/// apart, `--max-duration-s` 100: the planned steady-state window, from 80 s, never flown):
/// the metrics are computed over what was flown, not left null. The 20 answered samples span
/// 9.5 s, 950 steps of 0.01 s; the last 20 % (from step 760, 7.6 s after the first) holds
/// samples 16 to 19; the summary says so.
#[test]
fn an_early_hand_back_has_metrics_over_what_was_flown() {
    let s = load_scenario(None, &[]).unwrap();
    let level = s.level();
    let eps: Vec<f64> = (0..30)
        .map(|k| 0.3 * if k % 2 == 0 { 1.0 } else { -1.0 } / (k + 1) as f64)
        .collect();
    let values: Vec<f32> = eps.iter().map(|e| (level + e) as f32).collect();
    let mut b = beats(&values, |k| 1000 + 500 * k as u32);
    for x in &mut b[20..] {
        x.manual = true;
    }
    let (r, _, _) = pilots_flight(&s, b, |o| o.max_duration_s = Some(100.0));
    assert_eq!(
        r.end,
        isotrack_mavlink::fly::FlyEnd::PilotTookOver,
        "{:?}",
        r.events
    );
    assert_eq!(r.commands.len(), 20, "{:?}", r.events);
    let e: Vec<f64> = values.iter().map(|&v| v as f64 - level).collect();
    let window = &e[16..20];
    let max = window.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rms = (window.iter().map(|x| x * x).sum::<f64>() / 4.0).sqrt();
    assert_eq!(
        r.metrics.steady_state_max_abs_error,
        Some(max),
        "{}",
        r.metrics_over
    );
    assert!((r.metrics.steady_state_rms_error.unwrap() - rms).abs() < 1e-15);
    assert!(r.metrics_over.contains("ended early"), "{}", r.metrics_over);
}
