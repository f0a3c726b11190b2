//! `fly` with a sensor not wired to the autopilot (`--sensor udp:HOST:PORT`, lines `t_s,value`)
//! and without `--take-control`: against a stand-in vehicle whose pilot has already armed it
//! and switched it to OFFBOARD, every line is answered by a setpoint stamped with its time and
//! carrying the law's command for it (the scenario's tracker fed the same measurements), as the
//! coordinated-turn roll of the Fig. 3 UAV.

use isotrack_core::{IsolineController, Measurement};
use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions, SensorSource};
use isotrack_mavlink::link::Link;
use isotrack_mavlink::wire;
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::net::UdpSocket;
use std::path::PathBuf;
use std::time::{Duration, Instant};

mod support;
use support::stop_after;

#[test]
fn udp_lines_are_answered_with_the_laws_roll() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let mut vehicle = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = vehicle.local_addr().unwrap();
    // The sensor's port: bound here first to find a free one, then handed to fly.
    let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
    let sensor_addr = probe.local_addr().unwrap();
    drop(probe);
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.sensor = SensorSource::parse(&format!("udp:{sensor_addr}")).unwrap();
    o.timeout_s = 2.0;
    o.max_duration_s = Some(4.0);
    let sc = s.clone();
    let companion =
        std::thread::spawn(move || run_fly(&sc, &o, &mut NoTrace, &mut |_| Ok(())).unwrap());
    let values = [12.0, 11.5, 11.2, 10.9, 10.7, 10.6];
    let sensor = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut answers: Vec<(u32, [f32; 4])> = Vec::new();
    let mut next = 0;
    let t0 = Instant::now();
    let mut beats = 0;
    while t0.elapsed() < Duration::from_secs(60) && !companion.is_finished() {
        for r in vehicle.poll(Duration::from_millis(20)).unwrap() {
            if let MavMessage::SET_ATTITUDE_TARGET(a) = &r.msg {
                // Only the answer to the last line sent (not the setpoints repeated meanwhile,
                // stamped NOT_AN_ANSWER_MS before the first).
                if next == 0 || a.time_boot_ms != 1000 * (next as u32 - 1) {
                    continue;
                }
                if answers.last().map(|x| x.0) != Some(a.time_boot_ms) {
                    answers.push((a.time_boot_ms, a.q));
                }
            }
        }
        if vehicle.has_peer() {
            // The pilot's vehicle: armed, in OFFBOARD (PX4 main mode 6), reported ten times
            // before the first line, so the companion knows it has control.
            vehicle
                .send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                    custom_mode: 6 << 16,
                    mavtype: MavType::MAV_TYPE_FIXED_WING,
                    autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
                    base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                        | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                    system_status: MavState::MAV_STATE_ACTIVE,
                    mavlink_version: 3,
                }))
                .unwrap();
            beats += 1;
            // One line a second of sensor time, once the previous one is answered.
            if beats > 10 && answers.len() == next && next < values.len() {
                let line = format!("{}.0,{}\n", next, values[next]);
                sensor.send_to(line.as_bytes(), sensor_addr).unwrap();
                next += 1;
            }
        }
    }
    let report = companion.join().unwrap();
    assert_eq!(report.end, FlyEnd::MaxDuration, "{:?}", report.events);
    assert_eq!(answers.len(), 4, "{answers:?}");
    let mut law = s.tracker();
    for (k, (ms, q)) in answers.iter().enumerate() {
        assert_eq!(*ms, 1000 * k as u32);
        let w = law.update(&Measurement {
            t_s: k as f64,
            value: values[k],
        });
        let roll = wire::roll_of_turn_rate(w, 30.0);
        assert_eq!(*q, wire::quaternion_of_roll(roll), "sample {k}");
    }
}

/// A pilot's vehicle (armed, OFFBOARD) that records the time stamps of the setpoints it gets
/// while `send` feeds the UDP sensor; returns (companion's report, stamps received).
fn udp_flight(
    send: impl FnOnce(&UdpSocket, std::net::SocketAddr) + Send + 'static,
) -> (isotrack_mavlink::fly::FlyReport, Vec<u32>) {
    let s = load_scenario(None, &[]).unwrap();
    let mut vehicle = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = vehicle.local_addr().unwrap();
    let probe = UdpSocket::bind("127.0.0.1:0").unwrap();
    let sensor_addr = probe.local_addr().unwrap();
    drop(probe);
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.sensor = SensorSource::parse(&format!("udp:{sensor_addr}")).unwrap();
    o.timeout_s = 1.0;
    let companion =
        std::thread::spawn(move || run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap());
    let sensor = UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut send = Some(send);
    let (mut stamps, mut beats) = (Vec::new(), 0);
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(60) && !companion.is_finished() {
        for r in vehicle.poll(Duration::from_millis(20)).unwrap() {
            match &r.msg {
                MavMessage::SET_ATTITUDE_TARGET(a) if a.time_boot_ms != u32::MAX => {
                    stamps.push(a.time_boot_ms)
                }
                MavMessage::COMMAND_LONG(c) => {
                    vehicle
                        .send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                            command: c.command,
                            result: MavResult::MAV_RESULT_ACCEPTED,
                        }))
                        .unwrap();
                }
                _ => {}
            }
        }
        if vehicle.has_peer() {
            vehicle
                .send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                    custom_mode: 6 << 16,
                    mavtype: MavType::MAV_TYPE_GROUND_ROVER,
                    autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
                    base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                        | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                    system_status: MavState::MAV_STATE_ACTIVE,
                    mavlink_version: 3,
                }))
                .unwrap();
            beats += 1;
            if beats == 10 {
                if let Some(f) = send.take() {
                    f(&sensor, sensor_addr);
                }
            }
        }
    }
    (companion.join().unwrap(), stamps)
}

/// A line split across two datagrams is one measurement: `5.0,1` + `.5\n` is 1.5 at 5 s (the
/// law's command for 1.5, not for 1).
#[test]
fn a_line_may_span_datagrams() {
    let (r, _) = udp_flight(|s, a| {
        s.send_to(b"5.0,1", a).unwrap();
        s.send_to(b".5\n", a).unwrap();
    });
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    let w = law.update(&Measurement {
        t_s: 5.0,
        value: 1.5,
    });
    assert_eq!(r.commands, vec![(5000, w)], "{:?}", r.events);
}

/// 500 lines of a 1 kHz sensor in one datagram: the law runs on each, but the setpoints keep
/// to --setpoint-rate-hz (here: the burst is answered by a handful, not 500).
#[test]
fn a_fast_sensor_does_not_multiply_setpoints() {
    let (r, stamps) = udp_flight(|s, a| {
        let text: String = (0..500)
            .map(|k| format!("{},{}\n", k as f64 / 1000.0, 1.0))
            .collect();
        s.send_to(text.as_bytes(), a).unwrap();
    });
    assert_eq!(r.commands.len(), 500, "{:?}", r.events);
    let mut distinct = stamps.clone();
    distinct.dedup();
    assert!(distinct.len() < 20, "{distinct:?}");
}

/// 5000 lines with one time stamp: the repeats are answered within --setpoint-rate-hz (10 Hz
/// for the second or so before the sensor is lost), not 5000 times.
#[test]
fn repeated_time_stamps_keep_to_the_setpoint_rate() {
    let (_, stamps) = udp_flight(|s, a| {
        let text: String = (0..5000).map(|_| "1.0,1\n").collect();
        s.send_to(text.as_bytes(), a).unwrap();
    });
    let n = stamps.iter().filter(|&&t| t == 1000).count();
    assert!((1..100).contains(&n), "{n} answers");
}

/// The tail of a dropped over-long line is no measurement: only the next whole line is.
#[test]
fn the_tail_of_an_over_long_line_is_dropped() {
    let (r, _) = udp_flight(|s, a| {
        s.send_to(&[b'9'; 2000], a).unwrap();
        s.send_to(b"7.0,3\n", a).unwrap();
        s.send_to(b"8.0,2\n", a).unwrap();
    });
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    let w = law.update(&Measurement {
        t_s: 8.0,
        value: 2.0,
    });
    assert_eq!(r.commands, vec![(8000, w)], "{:?}", r.events);
}

/// Lines from a second sender (another address) are not the sensor's: dropped and logged
/// once; the law runs on the first sender's lines only.
#[test]
fn a_second_sender_is_not_the_sensor() {
    let (r, _) = udp_flight(|s, a| {
        let intruder = UdpSocket::bind("127.0.0.1:0").unwrap();
        s.send_to(b"7.0,3\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        intruder.send_to(b"7.5,50\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        s.send_to(b"8.0,2\n", a).unwrap();
    });
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    let expected: Vec<(u32, f64)> = [(7.0, 3.0), (8.0, 2.0)]
        .iter()
        .map(|&(t, v)| {
            let w = law.update(&Measurement { t_s: t, value: v });
            ((t * 1000.0) as u32, w)
        })
        .collect();
    assert_eq!(r.commands, expected, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("not the sensor")),
        "{:?}",
        r.events
    );
}

/// Lines that are no measurement (att33b item 3): not two comma-separated numbers, a time
/// out of [0, 4294967.295] s, a value not finite. Dropped, never given to the law, counted
/// (measurements_invalid: 7) and the first logged; the law runs on the one good line.
#[test]
fn malformed_and_non_finite_lines_are_counted_and_logged() {
    let (r, _) = udp_flight(|s, a| {
        s.send_to(
            b"abc,def\n2;9.2\n2,9.2,7\n2,nan\nnan,9\n-1,9\n1e300,9\n\n3.0,1\n",
            a,
        )
        .unwrap();
    });
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    let w = law.update(&Measurement {
        t_s: 3.0,
        value: 1.0,
    });
    assert_eq!(r.commands, vec![(3000, w)], "{:?}", r.events);
    assert_eq!(r.measurements_invalid, 7, "{:?}", r.events);
    let logged: Vec<_> = r
        .events
        .iter()
        .filter(|e| e.contains("measurements_invalid"))
        .collect();
    assert_eq!(logged.len(), 1, "{:?}", r.events);
    assert!(logged[0].contains("abc,def"), "{logged:?}");
}

/// A pilot's PX4 vehicle of type `mavtype` (system 1, component 1; armed, in OFFBOARD) that
/// `fly` (listening, `udpin:`, with `opts`) flies: every 50 ms beat it sends its heartbeat,
/// then `beat(k, vehicle, other)` sends what the test wants (`other`: component 100 of the
/// vehicle's system, a peripheral). Returns the report and the setpoints received.
fn pilots_vehicle(
    mavtype: MavType,
    opts: impl FnOnce(&mut FlyOptions),
    beat: impl FnMut(u32, &mut Link, &mut Link),
) -> (
    isotrack_mavlink::fly::FlyReport,
    Vec<SET_ATTITUDE_TARGET_DATA>,
) {
    pilots_vehicle_in(mavtype, Some(6 << 16), 100, opts, beat)
}

/// [`pilots_vehicle`] armed in PX4 mode `mode` (`None`: `beat` sends the heartbeats), its
/// `other` component `other_component`.
fn pilots_vehicle_in(
    mavtype: MavType,
    mode: Option<u32>,
    other_component: u8,
    opts: impl FnOnce(&mut FlyOptions),
    mut beat: impl FnMut(u32, &mut Link, &mut Link),
) -> (
    isotrack_mavlink::fly::FlyReport,
    Vec<SET_ATTITUDE_TARGET_DATA>,
) {
    let s = if mavtype == MavType::MAV_TYPE_FIXED_WING {
        let p =
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig3-uav.toml");
        load_scenario(Some(&p), &[]).unwrap()
    } else {
        load_scenario(None, &[]).unwrap()
    };
    let mut o = FlyOptions::new("udpin:127.0.0.1:0");
    o.timeout_s = 2.0;
    opts(&mut o);
    let (tx, rx) = std::sync::mpsc::channel();
    let companion = std::thread::spawn(move || {
        run_fly(&s, &o, &mut NoTrace, &mut |l| {
            tx.send(l.local_addr()?).unwrap();
            Ok(())
        })
        .unwrap()
    });
    let url = format!("udpout:{}", rx.recv().unwrap());
    let mut vehicle = Link::open(&url, 1, 1).unwrap();
    let mut other = Link::open(&url, 1, other_component).unwrap();
    let mut setpoints = Vec::new();
    let t0 = Instant::now();
    let mut k = 0;
    while t0.elapsed() < Duration::from_secs(60) && !companion.is_finished() {
        if let Some(mode) = mode {
            vehicle
                .send(&px4_heartbeat(
                    mavtype,
                    MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                        | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                    mode,
                ))
                .unwrap();
        }
        beat(k, &mut vehicle, &mut other);
        k += 1;
        for r in vehicle.poll(Duration::from_millis(50)).unwrap() {
            if let MavMessage::SET_ATTITUDE_TARGET(a) = r.msg {
                setpoints.push(a);
            }
        }
        let _ = other.poll(Duration::ZERO);
    }
    (companion.join().unwrap(), setpoints)
}

/// A PX4 autopilot's heartbeat.
fn px4_heartbeat(mavtype: MavType, base_mode: MavModeFlag, custom_mode: u32) -> MavMessage {
    support::heartbeat(
        mavtype,
        MavAutopilot::MAV_AUTOPILOT_PX4,
        base_mode,
        custom_mode,
    )
}

/// `NAMED_VALUE_FLOAT` `ISO_S` stamped `ms` with `value`.
fn iso_s(ms: u32, value: f32) -> MavMessage {
    let mut name = [0u8; 10];
    name[..5].copy_from_slice(b"ISO_S");
    MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
        time_boot_ms: ms,
        value,
        name: name.into(),
    })
}

/// The law's commands for `values` at `times_ms`, as `fly` reports them.
fn law_commands(times_ms: &[u32], value: impl Fn(u32) -> f64) -> Vec<(u32, f64)> {
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    times_ms
        .iter()
        .map(|&ms| {
            let w = law.update(&Measurement {
                t_s: ms as f64 / 1000.0,
                value: value(ms),
            });
            (ms, w)
        })
        .collect()
}

/// att33c item 1: `ISO_S` from a second component of the vehicle's system (1, 100), interleaved
/// with the autopilot's: the sensor is the first sender of a valid one (the autopilot here);
/// the other's values are never flown (the law runs on the autopilot's only), they are
/// counted in measurements_other_sources and logged once.
#[test]
fn a_second_components_measurements_are_not_flown() {
    let (r, _) = pilots_vehicle(
        MavType::MAV_TYPE_GROUND_ROVER,
        |o| o.max_duration_s = Some(1.0),
        |k, v, other| {
            v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
            if k > 2 {
                other.send(&iso_s(1025 + 50 * k, 50.0)).unwrap();
            }
        },
    );
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    let times: Vec<u32> = r.commands.iter().map(|c| c.0).collect();
    assert!(times.len() > 5, "{:?}", r.events);
    assert!(times.iter().all(|t| t % 50 == 0), "{times:?}");
    assert_eq!(r.commands, law_commands(&times, |_| 9.5));
    assert!(r.measurements_other_sources > 0, "{:?}", r.events);
    let logged: Vec<_> = r
        .events
        .iter()
        .filter(|e| e.contains("measurements_other_sources"))
        .collect();
    assert_eq!(logged.len(), 1, "{:?}", r.events);
    assert!(logged[0].contains("component 100"), "{logged:?}");
}

/// att33c items 2 and 2b: a value beyond +-1e12 (MAX_MEASUREMENT_ABS) is no measurement, on
/// either path: never given to the law (whose integral one such sample would wind for the
/// rest of the flight), counted in measurements_invalid; the law runs on the plausible ones.
#[test]
fn an_implausible_value_is_no_measurement() {
    assert!(isotrack_mavlink::fly::plausible_value(1e12));
    assert!(!isotrack_mavlink::fly::plausible_value(-1.0000001e12));
    let (r, _) = udp_flight(|s, a| {
        s.send_to(b"1.0,1e300\n2.0,-2e12\n3.0,4e-320\n4.0,1\n", a)
            .unwrap();
    });
    assert_eq!(
        r.commands,
        law_commands(&[3000, 4000], |ms| if ms == 3000 { 4e-320 } else { 1.0 }),
        "{:?}",
        r.events
    );
    assert_eq!(r.measurements_invalid, 2, "{:?}", r.events);
    // MAVLink's f32 path: 3e38 is finite, and still no measurement.
    let (r, _) = pilots_vehicle(
        MavType::MAV_TYPE_GROUND_ROVER,
        |o| o.max_duration_s = Some(0.5),
        |k, v, _| {
            let value = if k == 3 || k == 4 { 3e38 } else { 9.5 };
            v.send(&iso_s(1000 + 50 * k, value)).unwrap();
        },
    );
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert_eq!(r.measurements_invalid, 2, "{:?}", r.events);
    let times: Vec<u32> = r.commands.iter().map(|c| c.0).collect();
    assert!(
        !times.contains(&1150) && !times.contains(&1200),
        "{times:?}"
    );
    assert_eq!(r.commands, law_commands(&times, |_| 9.5));
}

/// att33c item 6: a junk datagram (a port scanner's "hello") arriving first does not lock the
/// UDP sensor: the sensor is the first sender of a valid line; the junk is counted in
/// measurements_invalid and the real sensor's lines are flown.
#[test]
fn a_junk_datagram_does_not_lock_the_sensor() {
    let (r, _) = udp_flight(|s, a| {
        let stray = UdpSocket::bind("127.0.0.1:0").unwrap();
        stray.send_to(b"hello\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        s.send_to(b"7.0,3\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        s.send_to(b"8.0,2\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        stray.send_to(b"9.0,50\n", a).unwrap();
    });
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    let expected: Vec<(u32, f64)> = [(7.0, 3.0), (8.0, 2.0)]
        .iter()
        .map(|&(t, v)| {
            (
                (t * 1000.0) as u32,
                law.update(&Measurement { t_s: t, value: v }),
            )
        })
        .collect();
    assert_eq!(r.commands, expected, "{:?}", r.events);
    assert_eq!(r.measurements_invalid, 1, "{:?}", r.events);
    assert_eq!(r.measurements_other_sources, 1, "{:?}", r.events);
}

/// ver33-7: a stray datagram whose tail only looks like a line (`0,9` without its newline)
/// locks nothing: no line was parsed from it (its tail waits for a newline that never comes).
/// The real sensor, sending next, is the sensor and is flown; the stray's datagram is counted
/// invalid, and the stray's later line is another source's.
#[test]
fn an_unterminated_tail_does_not_lock_the_sensor() {
    let (r, _) = udp_flight(|s, a| {
        let stray = UdpSocket::bind("127.0.0.1:0").unwrap();
        stray.send_to(b"0,9", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        s.send_to(b"7.0,3\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        s.send_to(b"8.0,2\n", a).unwrap();
        std::thread::sleep(Duration::from_millis(100));
        stray.send_to(b"\n9.0,50\n", a).unwrap();
    });
    let mut law = load_scenario(None, &[]).unwrap().tracker();
    let expected: Vec<(u32, f64)> = [(7.0, 3.0), (8.0, 2.0)]
        .iter()
        .map(|&(t, v)| {
            (
                (t * 1000.0) as u32,
                law.update(&Measurement { t_s: t, value: v }),
            )
        })
        .collect();
    assert_eq!(r.commands, expected, "{:?}", r.events);
    assert_eq!(r.measurements_invalid, 1, "{:?}", r.events);
    assert_eq!(r.measurements_other_sources, 1, "{:?}", r.events);
}

/// The pitch of a setpoint's attitude quaternion `[w, x, y, z]` (ZYX Euler angles), rad.
fn pitch_of(q: [f32; 4]) -> f64 {
    let [w, x, y, z] = q.map(f64::from);
    (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin()
}

/// att33c item 19: the fixed wing's altitude (LOCAL_POSITION_NED z) steps by 90 m between two
/// samples 50 ms apart (an EKF height reset): 1800 m/s, beyond the 30 m/s the Fig. 3 UAV
/// flies. Not a climb to answer with the full 15 deg of pitch: the hold's target moves with
/// the step, the pitch stays 0 (on target before, on target after), logged once.
#[test]
fn an_altitude_step_is_a_reset_not_a_climb() {
    for step_m in [90.0f32, -90.0] {
        let (r, setpoints) = pilots_vehicle(
            MavType::MAV_TYPE_FIXED_WING,
            |o| o.max_duration_s = Some(1.5),
            |k, v, _| {
                let z = if k < 10 { -100.0 } else { -100.0 - step_m };
                v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
                v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: 1000 + 50 * k,
                    z,
                    ..Default::default()
                }))
                .unwrap();
            },
        );
        assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
        assert!(setpoints.len() > 20, "{}", setpoints.len());
        for a in &setpoints {
            assert!(
                pitch_of(a.q).abs() < 1e-6,
                "{step_m}: pitch {}",
                pitch_of(a.q)
            );
        }
        let logged: Vec<_> = r
            .events
            .iter()
            .filter(|e| e.contains("altitude step of"))
            .collect();
        assert_eq!(logged.len(), 1, "{:?}", r.events);
        assert!(
            logged[0].contains(&format!("altitude step of {step_m} m ignored")),
            "{logged:?}"
        );
    }
}

/// ver33-1: the fixed wing's altitude (100 m for 1 s) stops for 2 s, longer than --timeout-s (1 s: the hold's
/// pitch is 0 meanwhile), and comes back 200 m higher (an EKF height reset after the outage)
/// with the vehicle's clock 10 s on (its stamps follow the wall clock, plus 10 s from then):
/// the bound `V dt + 10 m` on that 12 s gap is 370 m, so compared, the step was flown as a
/// climb with the full -15 deg. The first altitude after the outage re-references the hold's
/// target instead: the pitch stays 0 (on target before, unknown during, on target after),
/// logged.
#[test]
fn an_altitude_after_an_outage_re_references_the_hold() {
    let t0 = Instant::now();
    let mut gap: Option<Instant> = None;
    let (r, setpoints) = pilots_vehicle(
        MavType::MAV_TYPE_FIXED_WING,
        |o| {
            o.timeout_s = 1.0;
            o.max_duration_s = Some(16.0);
        },
        move |_, v, _| {
            let back = gap.is_some_and(|g| g.elapsed() > Duration::from_secs(2));
            let ms = 1000 + t0.elapsed().as_millis() as u32 + if back { 10_000 } else { 0 };
            v.send(&iso_s(ms, 9.5)).unwrap();
            let z = if t0.elapsed() < Duration::from_secs(1) {
                -100.0
            } else if back {
                -300.0
            } else {
                gap.get_or_insert_with(Instant::now);
                return;
            };
            v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                time_boot_ms: ms,
                z,
                ..Default::default()
            }))
            .unwrap();
        },
    );
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(setpoints.len() > 20, "{}", setpoints.len());
    for a in &setpoints {
        assert!(pitch_of(a.q).abs() < 1e-6, "pitch {}", pitch_of(a.q));
    }
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("re-referenced from 100 m to it")),
        "{:?}",
        r.events
    );
    assert!(
        !r.events.iter().any(|e| e.contains("altitude step of")),
        "{:?}",
        r.events
    );
}

/// A second companion with this one's ids (system 1, component 191) beats on the link: with
/// --take-control, fly goes no further (another_controller, nothing commanded: exit 79);
/// without, it is logged once and the flight goes on.
#[test]
fn a_twin_companions_heartbeat_is_noticed() {
    // The twin beats before the sensor and the position are there: --take-control has
    // commanded nothing yet (nor sent a setpoint, which goes with its first command).
    let twin_beats = |k: u32, v: &mut Link, twin: &mut Link| {
        twin.send(&support::heartbeat(
            MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            MavAutopilot::MAV_AUTOPILOT_INVALID,
            MavModeFlag::empty(),
            0,
        ))
        .unwrap();
        std::thread::sleep(Duration::from_millis(5));
        v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
        v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
            time_boot_ms: 1000 + 50 * k,
            ..Default::default()
        }))
        .unwrap();
    };
    let (r, setpoints) = pilots_vehicle_in(
        MavType::MAV_TYPE_GROUND_ROVER,
        Some(3 << 16),
        191,
        |o| o.take_control = true,
        twin_beats,
    );
    assert_eq!(r.end, FlyEnd::AnotherController, "{:?}", r.events);
    assert!(
        !r.way_out_commanded && setpoints.is_empty(),
        "{:?}",
        r.events
    );
    assert!(
        r.events.iter().any(|e| e.contains("second companion")),
        "{:?}",
        r.events
    );
    let (r, _) = pilots_vehicle_in(
        MavType::MAV_TYPE_GROUND_ROVER,
        Some(6 << 16),
        191,
        |o| o.max_duration_s = Some(0.5),
        twin_beats,
    );
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    let logged = r.events.iter().filter(|e| e.contains("second companion"));
    assert_eq!(logged.count(), 1, "{:?}", r.events);
}

/// att33c item 17: a heartbeat armed with `custom_mode` OFFBOARD but without
/// MAV_MODE_FLAG_CUSTOM_MODE_ENABLED says nothing of its mode (MAVLink): no hand-over, the
/// law never runs; the flight waits for the pilot until stopped.
#[test]
fn a_custom_mode_without_its_flag_is_no_mode() {
    let (r, _) = pilots_vehicle_in(
        MavType::MAV_TYPE_GROUND_ROVER,
        None,
        100,
        |o| stop_after(o, 1.5),
        |k, v, _| {
            v.send(&px4_heartbeat(
                MavType::MAV_TYPE_GROUND_ROVER,
                MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                6 << 16,
            ))
            .unwrap();
            v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
        },
    );
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(r.commands.is_empty(), "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("armed in an unknown mode")),
        "{:?}",
        r.events
    );
}

/// att33c item 9: a heartbeat flapping between POSCTL and STABILIZED (20 a beat, 400 a second)
/// while fly waits for the pilot: at most one change of mode logged a second, the ones
/// between counted in it; the events stay few, not one per heartbeat.
#[test]
fn a_flapping_mode_is_logged_at_most_once_a_second() {
    let (r, _) = pilots_vehicle_in(
        MavType::MAV_TYPE_GROUND_ROVER,
        None,
        100,
        |o| stop_after(o, 2.5),
        |k, v, _| {
            for i in 0..20 {
                let mode = if i % 2 == 0 { 3 << 16 } else { 7 << 16 };
                v.send(&px4_heartbeat(
                    MavType::MAV_TYPE_GROUND_ROVER,
                    MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                        | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                    mode,
                ))
                .unwrap();
            }
            v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
        },
    );
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    let modes: Vec<_> = r
        .events
        .iter()
        .filter(|e| e.contains("vehicle armed in"))
        .collect();
    // 2.5 s: the first change and at most one a second after it.
    assert!((1..=4).contains(&modes.len()), "{:?}", r.events);
    assert!(
        modes.iter().any(|e| e.contains("not logged")),
        "{:?}",
        r.events
    );
    assert!(r.events.len() < 20, "{:?}", r.events);
}

/// att33c item 8: a MAV_TYPE_GENERIC autopilot heartbeat from another component of the
/// vehicle's system (1, 100: a MAVSDK-based peripheral) beside the autopilot (1, 1) is no
/// second vehicle (`two_vehicles`, which --target-system cannot resolve): ignored, logged once,
/// whichever beats first; the autopilot is flown.
#[test]
fn a_generic_peripheral_beside_the_autopilot_is_no_second_vehicle() {
    for peripheral_first in [false, true] {
        let (r, _) = pilots_vehicle_in(
            MavType::MAV_TYPE_GROUND_ROVER,
            None,
            100,
            |o| o.max_duration_s = Some(0.5),
            |k, v, other| {
                let generic = px4_heartbeat(
                    MavType::MAV_TYPE_GENERIC,
                    MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                    0,
                );
                let autopilot = px4_heartbeat(
                    MavType::MAV_TYPE_GROUND_ROVER,
                    MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                        | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
                    6 << 16,
                );
                if peripheral_first {
                    other.send(&generic).unwrap();
                    std::thread::sleep(Duration::from_millis(5));
                }
                v.send(&autopilot).unwrap();
                if !peripheral_first {
                    other.send(&generic).unwrap();
                }
                v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
            },
        );
        assert_eq!(
            r.end,
            FlyEnd::MaxDuration,
            "{peripheral_first}: {:?}",
            r.events
        );
        assert!(!r.commands.is_empty(), "{:?}", r.events);
        let logged = r.events.iter().filter(|e| e.contains("peripheral"));
        assert_eq!(logged.count(), 1, "{:?}", r.events);
    }
}

/// att33d-10: two vehicles left at the same ids (1, 1) on one link, from two addresses: their
/// measurements would mix in the law. In control (the pilot's OFFBOARD), the flight ends
/// `vehicle_lost` and commands the way out; the second's values are never flown.
#[test]
fn two_vehicles_with_the_same_ids_are_not_flown_as_one() {
    let (r, _) = pilots_vehicle_in(
        MavType::MAV_TYPE_GROUND_ROVER,
        Some(6 << 16),
        1,
        |o| o.max_duration_s = Some(3.0),
        |k, v, twin| {
            v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
            if k == 10 {
                twin.send(&iso_s(1025 + 50 * k, 50.0)).unwrap();
            }
        },
    );
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("two vehicles with the ids")),
        "{:?}",
        r.events
    );
    assert!(r.commands.iter().all(|c| c.0 % 50 == 0), "{:?}", r.commands);
    assert!(r.way_out_commanded, "{:?}", r.events);
}

/// ver33-3: the once-a-second limit of the mode log never loses the last change when none
/// follows it: the pilot arming in OFFBOARD 0.5 s after the vehicle was heard disarmed in
/// MANUAL (the hand-over: logged at once, it gave the companion control), or switching from
/// POSCTL to STABILIZED 0.5 s after it was heard (logged when its second has passed).
#[test]
fn the_last_change_of_mode_is_logged_when_none_follows() {
    for (first, then, want) in [
        (
            (false, 1u32 << 16),
            (true, 6u32 << 16),
            "vehicle armed in OFFBOARD",
        ),
        (
            (true, 3 << 16),
            (true, 7 << 16),
            "vehicle armed in STABILIZED",
        ),
    ] {
        let (r, _) = pilots_vehicle_in(
            MavType::MAV_TYPE_GROUND_ROVER,
            None,
            100,
            |o| stop_after(o, 2.0),
            |k, v, _| {
                let (armed, mode) = if k < 10 { first } else { then };
                v.send(&px4_heartbeat(
                    MavType::MAV_TYPE_GROUND_ROVER,
                    support::custom_mode_flags(armed),
                    mode,
                ))
                .unwrap();
                v.send(&iso_s(1000 + 50 * k, 9.5)).unwrap();
            },
        );
        assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
        assert!(
            r.events.iter().any(|e| e.contains(want)),
            "{want}: {:?}",
            r.events
        );
    }
}
