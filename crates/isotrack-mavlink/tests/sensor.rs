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
