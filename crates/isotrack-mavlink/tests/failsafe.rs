//! The companion's failsafes on a lost link or sensor, against a stand-in vehicle that goes
//! quiet: the setpoints stop and HOLD is commanded (PX4 AUTO.LOITER: main mode 4, sub mode 3).
//! Real time is needed here (a silence is a duration); the timeouts are short, the waits long,
//! and nothing asserts how long anything took.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions};
use isotrack_mavlink::link::Link;
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::time::{Duration, Instant};

mod support;
use support::ack_of;

/// A ground rover (the default scenario's Dubins vehicle) a pilot armed and switched to
/// OFFBOARD (PX4 main mode 6): the companion has control from its first heartbeat, so a
/// failsafe commands HOLD.
fn heartbeat() -> MavMessage {
    support::heartbeat(
        MavType::MAV_TYPE_GROUND_ROVER,
        MavAutopilot::MAV_AUTOPILOT_PX4,
        support::custom_mode_flags(true),
        6 << 16,
    )
}

/// A vehicle that answers the companion's first message with a heartbeat, then sends
/// heartbeats every 50 ms if `keep_beating`, and reports the first DO_SET_MODE it receives
/// (parameters 2 and 3); gives up after 60 s.
fn quiet_vehicle(
    keep_beating: bool,
) -> (
    std::net::SocketAddr,
    std::thread::JoinHandle<Option<(f32, f32)>>,
) {
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let h = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut sent = false;
        while t0.elapsed() < Duration::from_secs(60) {
            for r in link.poll(Duration::from_millis(50)).unwrap() {
                if let MavMessage::COMMAND_LONG(c) = &r.msg {
                    if c.command == MavCmd::MAV_CMD_DO_SET_MODE {
                        return Some((c.param2, c.param3));
                    }
                }
            }
            if link.has_peer() && (!sent || keep_beating) {
                link.send(&heartbeat()).unwrap();
                sent = true;
            }
        }
        None
    });
    (addr, h)
}

fn fly_against(keep_beating: bool) -> (FlyEnd, Option<(f32, f32)>) {
    let s = load_scenario(None, &[]).unwrap();
    let (addr, vehicle) = quiet_vehicle(keep_beating);
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 0.5;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    (r.end, vehicle.join().unwrap())
}

#[test]
fn link_loss_fails_safe_to_hold() {
    let (end, mode) = fly_against(false);
    assert_eq!(end, FlyEnd::LinkLost);
    assert_eq!(mode, Some((4.0, 3.0)));
}

#[test]
fn sensor_loss_fails_safe_to_hold() {
    let (end, mode) = fly_against(true);
    assert_eq!(end, FlyEnd::SensorLost);
    assert_eq!(mode, Some((4.0, 3.0)));
}

/// att37-5: in control (the pilot's OFFBOARD, a heartbeat every 50 ms, no measurement), the
/// sensor is lost after `timeout_s` (1 s) and HOLD is commanded; the vehicle acknowledges it
/// as ACCEPTED, then falls silent (before any heartbeat shows HOLD). The accepted command is
/// not sent again before a heartbeat says what the vehicle did, so only 1 try goes out; the
/// retries end once nothing has come for `timeout_s`, "link lost" (FLYING.md: "the link is
/// lost ...; at least 5 tries even then, unless the vehicle acknowledged the command as
/// accepted"), not at the retries' bound (3 s). Before: "(1 tries, retries' bound reached)".
#[test]
fn a_hold_accepted_then_silence_ends_link_lost() {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(60) {
            for r in link.poll(Duration::from_millis(50)).unwrap() {
                if let MavMessage::COMMAND_LONG(c) = &r.msg {
                    if c.command == MavCmd::MAV_CMD_DO_SET_MODE {
                        link.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                            command: c.command,
                            result: MavResult::MAV_RESULT_ACCEPTED,
                        }))
                        .unwrap();
                        return true;
                    }
                }
            }
            if link.has_peer() {
                link.send(&heartbeat()).unwrap();
            }
        }
        false
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 1.0;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    assert!(vehicle.join().unwrap());
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("the vehicle did not confirm the HOLD (1 tries, link lost)")),
        "{:?}",
        r.events
    );
}

/// The vehicle's own offboard failsafe: a companion that arms it, switches it to OFFBOARD, sends
/// one setpoint and falls silent leaves it in HOLD (real time at 20x; the run is 20 simulated
/// seconds, the timeout 1).
#[test]
fn sitl_holds_when_offboard_setpoints_stop() {
    use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
    let s = load_scenario(None, &["sim.duration_s=20".to_string()]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::RealTime { speedup: 20.0 };
    let (tx, rx) = std::sync::mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let addr = rx.recv().unwrap();
    let mut c = Link::open(&format!("udpout:{addr}"), 1, 191).unwrap();
    let command = |cmd, p1, p2| {
        MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: p1,
            param2: p2,
            command: cmd,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        })
    };
    c.send(&command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0))
        .unwrap();
    c.send(&yaw_rate_setpoint(-0.1)).unwrap();
    c.send(&command(MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0))
        .unwrap();
    let report = vehicle.join().unwrap();
    let i = report
        .events
        .iter()
        .position(|e| e.contains("mode OFFBOARD"));
    let j = report.events.iter().position(|e| e.contains("failsafe"));
    assert!(i.is_some() && j > i, "{:?}", report.events);
    // Its last turn rates are HOLD's: half the 0.2 rad/s default loiter limit, to the left.
    assert_eq!(report.flown.last().unwrap().1, 0.1);
}

/// A yaw-rate setpoint (attitude ignored) for system 1, component 1, rad/s.
fn yaw_rate_setpoint(body_yaw_rate: f32) -> MavMessage {
    MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
        time_boot_ms: 0,
        q: [1.0, 0.0, 0.0, 0.0],
        body_yaw_rate,
        target_system: 1,
        target_component: 1,
        type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
        ..Default::default()
    })
}

/// Once companion A (system 1, component 191) has armed the flying vehicle, a stranger B
/// (system 7) can neither arm it (take it over), switch its mode, fly it by setpoints, nor
/// disarm it without PX4's force code 21196; with the code, B's disarm is accepted.
#[test]
fn sitl_refuses_a_stranger_once_armed() {
    use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let addr = rx.recv().unwrap();
    let url = format!("udpout:{addr}");
    let mut a = Link::open(&url, 1, 191).unwrap();
    let mut b = Link::open(&url, 7, 191).unwrap();
    let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
    let mode = MavCmd::MAV_CMD_DO_SET_MODE;
    let (accepted, denied) = (
        Some(MavResult::MAV_RESULT_ACCEPTED),
        Some(MavResult::MAV_RESULT_DENIED),
    );
    // A's arming as MAVSDK sends it: the unused param2 is NaN (an ordinary, unforced request).
    assert_eq!(ack_of(&mut a, arm, 1.0, f32::NAN), accepted);
    assert_eq!(ack_of(&mut b, arm, 1.0, 0.0), denied, "B's arming");
    assert_eq!(ack_of(&mut b, mode, 1.0, 6.0), denied, "B's OFFBOARD");
    b.send(&yaw_rate_setpoint(-0.1)).unwrap();
    assert_eq!(
        ack_of(&mut b, arm, 0.0, 0.0),
        denied,
        "B's disarm, unforced"
    );
    assert_eq!(
        ack_of(&mut b, arm, 0.0, 21196.0),
        accepted,
        "B's forced disarm"
    );
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    let report = vehicle.join().unwrap();
    assert_eq!(report.setpoints_refused, 1, "{:?}", report.events);
    let owner_kept = !report
        .events
        .iter()
        .any(|e| e.contains(": armed by system 7"));
    assert!(owner_kept, "{:?}", report.events);
}

/// Two companions with the same ids (system 1, component 191: two `fly` with the defaults) on
/// one vehicle, from two source addresses (att33b item 9): once A has armed it, B's setpoints
/// are a twin's, refused and logged (naming both addresses); A's are flown.
#[test]
fn sitl_refuses_a_twin_companions_setpoints() {
    use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
    let s = load_scenario(None, &[]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let addr = rx.recv().unwrap();
    let url = format!("udpout:{addr}");
    let mut a = Link::open(&url, 1, 191).unwrap();
    let mut b = Link::open(&url, 1, 191).unwrap();
    let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
    let accepted = Some(MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!(ack_of(&mut a, arm, 1.0, 0.0), accepted);
    for _ in 0..3 {
        b.send(&yaw_rate_setpoint(-0.1)).unwrap();
    }
    a.send(&yaw_rate_setpoint(0.1)).unwrap();
    // A round trip: what B and A sent before has been handled.
    assert_eq!(ack_of(&mut a, arm, 1.0, 0.0), accepted);
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    let report = vehicle.join().unwrap();
    assert_eq!(report.setpoints_refused, 3, "{:?}", report.events);
    let (a_addr, b_addr) = (a.local_addr().unwrap(), b.local_addr().unwrap());
    let logged: Vec<_> = report
        .events
        .iter()
        .filter(|e| e.contains("same ids"))
        .collect();
    assert_eq!(logged.len(), 1, "{:?}", report.events);
    assert!(
        logged[0].contains(&b_addr.port().to_string())
            && logged[0].contains(&a_addr.port().to_string()),
        "{logged:?}"
    );
}

/// A vehicle that beats every 50 ms and sends `ISO_S` with the given `time_boot_ms`, one per
/// beat, the last one again and again; stops after 10 s (or once told the companion ended).
fn clocked_vehicle(times: Vec<u32>) -> FlyEnd {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let finished = done.clone();
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut i = 0;
        while t0.elapsed() < Duration::from_secs(10)
            && !finished.load(std::sync::atomic::Ordering::SeqCst)
        {
            link.poll(Duration::from_millis(50)).unwrap();
            if link.has_peer() {
                link.send(&heartbeat()).unwrap();
                let mut name = [0u8; 10];
                name[..5].copy_from_slice(b"ISO_S");
                link.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                    time_boot_ms: times[i.min(times.len() - 1)],
                    value: 1.0,
                    name: name.into(),
                }))
                .unwrap();
                i += 1;
            }
        }
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 0.5;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    vehicle.join().unwrap();
    r.end
}

/// One measurement stamped 46 days ahead (a spoofed clock) is a sensor fault: failsafe at
/// once, not a frozen clock whose later (older) measurements keep the sensor timer alive.
#[test]
fn a_clock_jump_ahead_fails_safe() {
    let mut times = vec![1000, 2000, 4_000_000_000];
    times.extend((3..400).map(|k| k * 1000));
    assert_eq!(clocked_vehicle(times), FlyEnd::SensorClockJump);
}

/// The same time stamp again and again is no news from the sensor: sensor loss after the
/// timeout, though the vehicle keeps talking.
#[test]
fn a_repeated_time_stamp_is_sensor_loss() {
    assert_eq!(clocked_vehicle(vec![1000]), FlyEnd::SensorLost);
}

/// A fixed wing given yaw-rate setpoints (1e4 rad/s clockwise) turns as the roll path does:
/// at the coordinated-turn rate of the 40 deg bank limit, to the right (isotrack's omega
/// negative): -g tan(40 deg) / V.
#[test]
fn sitl_fixed_wing_yaw_rate_is_bank_limited() {
    use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let v_mps = s.spec().vehicle.speed_mps();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let addr = rx.recv().unwrap();
    let mut a = Link::open(&format!("udpout:{addr}"), 1, 191).unwrap();
    let setpoint = |ms| {
        MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            time_boot_ms: ms,
            q: [1.0, 0.0, 0.0, 0.0],
            body_yaw_rate: 1e4,
            target_system: 1,
            target_component: 1,
            type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
            ..Default::default()
        })
    };
    let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
    assert_eq!(
        ack_of(&mut a, arm, 1.0, 0.0),
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    a.send(&setpoint(u32::MAX)).unwrap();
    let offboard = ack_of(&mut a, MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0);
    assert_eq!(offboard, Some(MavResult::MAV_RESULT_ACCEPTED));
    let (mut answered, t0) = (0, Instant::now());
    while answered < 5 && t0.elapsed() < Duration::from_secs(30) {
        for r in a.poll(Duration::from_millis(50)).unwrap() {
            if let MavMessage::NAMED_VALUE_FLOAT(n) = &r.msg {
                a.send(&setpoint(n.time_boot_ms)).unwrap();
                answered += 1;
            }
        }
    }
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    let report = vehicle.join().unwrap();
    let expected = -9.8 * 40f64.to_radians().tan() / v_mps;
    let flown = report.flown.last().expect("a sample flown").1;
    assert!((flown - expected).abs() < 1e-12, "{flown} vs {expected}");
}

/// A vehicle that beats every 50 ms with a new `ISO_S` and a position `k` metres north at
/// beat `k` (beat 0: not finite if `nan_first`), as `LOCAL_POSITION_NED`, or only as
/// `GLOBAL_POSITION_INT` if `global`; the companion's fence is 5 m.
fn fenced_flight(nan_first: bool, global: bool) -> FlyEnd {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut k = 0u32;
        while t0.elapsed() < Duration::from_secs(20) {
            let got = link.poll(Duration::from_millis(50)).unwrap();
            let over = got
                .iter()
                .any(|r| matches!(&r.msg, MavMessage::COMMAND_LONG(_)));
            if over {
                return;
            }
            if !link.has_peer() {
                continue;
            }
            link.send(&heartbeat()).unwrap();
            let mut name = [0u8; 10];
            name[..5].copy_from_slice(b"ISO_S");
            link.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                time_boot_ms: 1000 + 50 * k,
                value: 1.0,
                name: name.into(),
            }))
            .unwrap();
            let north_m = if nan_first && k == 0 {
                f32::NAN
            } else {
                k as f32
            };
            if global {
                // 1 m north is 1 / (6371008.8 m) rad of latitude: 0.0899 microdegrees.
                let lat_deg = 47.0 + (north_m as f64 / 6_371_008.8).to_degrees();
                link.send(&MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
                    lat: (lat_deg * 1e7).round() as i32,
                    lon: 85_000_000,
                    ..Default::default()
                }))
                .unwrap();
            } else {
                link.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    x: north_m,
                    ..Default::default()
                }))
                .unwrap();
            }
            k += 1;
        }
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 5.0;
    o.fence_m = Some(5.0);
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    vehicle.join().unwrap();
    r.end
}

/// A non-finite first position does not switch the fence off.
#[test]
fn fence_survives_a_nan_first_position() {
    assert_eq!(fenced_flight(true, false), FlyEnd::Fence);
}

/// With only `GLOBAL_POSITION_INT`, the fence works on it (projected about the first fix).
#[test]
fn fence_works_on_global_positions() {
    assert_eq!(fenced_flight(false, true), FlyEnd::Fence);
}

/// A vehicle that powers off (`MAV_STATE_POWEROFF`) without announcing the end of its run is
/// lost: failsafe, HOLD commanded (PX4 main mode 4, sub mode 3).
#[test]
fn a_vehicle_powering_off_is_lost() {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut beats = 0;
        while t0.elapsed() < Duration::from_secs(20) {
            for r in link.poll(Duration::from_millis(50)).unwrap() {
                if let MavMessage::COMMAND_LONG(c) = &r.msg {
                    if c.command == MavCmd::MAV_CMD_DO_SET_MODE {
                        return Some((c.param2, c.param3));
                    }
                }
            }
            if link.has_peer() {
                let mut h = heartbeat();
                if let (MavMessage::HEARTBEAT(d), true) = (&mut h, beats >= 3) {
                    d.system_status = MavState::MAV_STATE_POWEROFF;
                }
                link.send(&h).unwrap();
                beats += 1;
            }
        }
        None
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 10.0;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert_eq!(vehicle.join().unwrap(), Some((4.0, 3.0)));
}

/// A vehicle that announces the end of its run (`STATUSTEXT` "isotrack sitl: run ended
/// (HOW)", as `sitl` does) at its 3rd beat and then powers off: the flight's end, and the
/// commands it received (DO_SET_MODE's param2 and param3).
fn run_ended_as(how: &str) -> (isotrack_mavlink::fly::FlyReport, Option<(f32, f32)>) {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let text = format!("isotrack sitl: run ended ({how})");
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut beats = 0;
        while t0.elapsed() < Duration::from_secs(8) {
            for r in link.poll(Duration::from_millis(50)).unwrap() {
                if let MavMessage::COMMAND_LONG(c) = &r.msg {
                    if c.command == MavCmd::MAV_CMD_DO_SET_MODE {
                        return Some((c.param2, c.param3));
                    }
                }
            }
            if link.has_peer() && beats < 6 {
                if beats == 3 {
                    let mut bytes = [0u8; 50];
                    bytes[..text.len()].copy_from_slice(text.as_bytes());
                    link.send(&MavMessage::STATUSTEXT(STATUSTEXT_DATA {
                        severity: MavSeverity::MAV_SEVERITY_NOTICE,
                        text: bytes.into(),
                    }))
                    .unwrap();
                }
                let mut h = heartbeat();
                if let (MavMessage::HEARTBEAT(d), true) = (&mut h, beats >= 3) {
                    d.system_status = MavState::MAV_STATE_POWEROFF;
                }
                link.send(&h).unwrap();
                beats += 1;
            }
        }
        None
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 1.0;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    (r, vehicle.join().unwrap())
}

/// Ctrl-C on `sitl` ("run ended (interrupted)", then powered off) is the vehicle going away,
/// not the end of the flight: `link_lost`, a failsafe (HOLD commanded, unconfirmed), never
/// `vehicle_ended`; a run that reached its end ("run ended (completed)") is `vehicle_ended`.
#[test]
fn an_interrupted_vehicle_is_a_lost_link_not_a_completed_flight() {
    for how in ["interrupted", "companion_lost"] {
        let (r, mode) = run_ended_as(how);
        assert_eq!(r.end, FlyEnd::LinkLost, "{how}: {:?}", r.events);
        assert!(r.end.is_failsafe());
        assert!(!r.failsafe_acknowledged, "{:?}", r.events);
        assert_eq!(mode, Some((4.0, 3.0)), "{:?}", r.events);
    }
    let (r, mode) = run_ended_as("completed");
    assert_eq!(r.end, FlyEnd::VehicleEnded, "{:?}", r.events);
    assert_eq!(mode, None);
}

/// No vehicle ever heard (nobody at the address): the failsafe says so, and nothing is said
/// to have been commanded ("no failsafe mode was sent" read as if one had been due).
#[test]
fn no_vehicle_heard_is_said_plainly() {
    let s = load_scenario(None, &[]).unwrap();
    let silent = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut o = FlyOptions::new(&format!("udpout:{}", silent.local_addr().unwrap()));
    o.timeout_s = 0.5;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    assert_eq!(r.end, FlyEnd::LinkLost, "{:?}", r.events);
    assert!(!r.vehicle_heard && !r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("no vehicle was ever heard: nothing sent")),
        "{:?}",
        r.events
    );
    assert!(
        !r.events
            .iter()
            .any(|e| e.contains("failsafe mode was sent")),
        "{:?}",
        r.events
    );
}

/// A lockstep vehicle whose companion falls silent (it ended, or failed safe) ends its run
/// after `companion_timeout_s` instead of waiting for an answer for ever. The companion arms
/// it and switches it to OFFBOARD first: a lockstep run advances only while the vehicle
/// follows setpoints (before, its answers to a disarmed vehicle advanced the run).
#[test]
fn a_lockstep_vehicle_ends_when_the_companion_is_gone() {
    use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
    let s = load_scenario(None, &[]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    opts.companion_timeout_s = 0.5;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let r = run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap();
        done_tx.send(r).unwrap();
    });
    let addr = rx.recv().unwrap();
    let mut c = Link::open(&format!("udpout:{addr}"), 1, 191).unwrap();
    let mut answered = 0;
    let t0 = Instant::now();
    c.send(&heartbeat()).unwrap();
    let ok = Some(MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!(
        ack_of(&mut c, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0),
        ok
    );
    // Setpoints first (answering no sample), as PX4 needs them before OFFBOARD.
    let mut first = yaw_rate_setpoint(0.0);
    if let MavMessage::SET_ATTITUDE_TARGET(d) = &mut first {
        d.time_boot_ms = u32::MAX;
    }
    c.send(&first).unwrap();
    assert_eq!(ack_of(&mut c, MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0), ok);
    // The first sample (t = 0) came while the commands were acknowledged: answered now,
    // within the 0.5 s the vehicle waits for a message.
    let mut sp = yaw_rate_setpoint(0.0);
    if let MavMessage::SET_ATTITUDE_TARGET(d) = &mut sp {
        d.time_boot_ms = 0;
    }
    c.send(&sp).unwrap();
    answered += 1;
    while answered < 3 && t0.elapsed() < Duration::from_secs(30) {
        for r in c.poll(Duration::from_millis(50)).unwrap() {
            if let MavMessage::NAMED_VALUE_FLOAT(n) = &r.msg {
                let mut sp = yaw_rate_setpoint(0.0);
                if let MavMessage::SET_ATTITUDE_TARGET(d) = &mut sp {
                    d.time_boot_ms = n.time_boot_ms;
                }
                c.send(&sp).unwrap();
                answered += 1;
            }
        }
    }
    // Silent from here on; a watchdog stops the vehicle if it never ends by itself.
    let report = match done_rx.recv_timeout(Duration::from_secs(30)) {
        Ok(r) => r,
        Err(_) => {
            stop.store(true, std::sync::atomic::Ordering::SeqCst);
            done_rx.recv().unwrap()
        }
    };
    assert!(report.companion_lost, "{:?}", report.events);
    assert!(!report.interrupted);
    assert_eq!(report.flown.len(), 3, "{:?}", report.events);
}

/// Whether a datagram is one MAVLink 2 `COMMAND_LONG` (message 76) carrying
/// `MAV_CMD_DO_SET_MODE` (176): its command is the payload's bytes 28 and 29.
fn is_set_mode(d: &[u8]) -> bool {
    d.len() >= 10 + 30
        && d[0] == 0xFD
        && u32::from_le_bytes([d[7], d[8], d[9], 0]) == 76
        && u16::from_le_bytes([d[10 + 28], d[10 + 29]]) == 176
}

/// att37-3, against `isotrack sitl` itself (not a stand-in): `fly --take-control --arm` arms
/// sitl's fixed wing, which then reports itself in the air (`EXTENDED_SYS_STATE`
/// `MAV_LANDED_STATE_IN_AIR`: a fixed wing armed flies), its switches to OFFBOARD are lost on
/// the way (a relay drops the first two), and it is interrupted before it ever had control:
/// the vehicle it armed is in the air, so it is never disarmed (forced or not): HOLD is
/// commanded (the relay passes it) and confirmed. Before: the forced disarm (param2 21196) of
/// a flying fixed wing, which sitl accepted.
#[test]
fn an_interrupt_before_offboard_holds_sitls_fixed_wing_in_the_air() {
    use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let sitl_stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let sc = s.clone();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&sc, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let sitl_addr = rx.recv().unwrap();
    // The relay between fly and sitl: everything passes but the switches to OFFBOARD; at the
    // second one dropped (fly armed and retrying), fly is interrupted.
    let relay = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    relay
        .set_read_timeout(Some(Duration::from_millis(50)))
        .unwrap();
    let relay_addr = relay.local_addr().unwrap();
    let mut o = FlyOptions::new(&format!("udpout:{relay_addr}"));
    o.take_control = true;
    o.arm = true;
    o.timeout_s = 2.0;
    let fly_stop = o.stop.clone();
    let companion =
        std::thread::spawn(move || run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap());
    let (mut fly_addr, mut dropped) = (None, 0);
    let mut buf = [0u8; 65_536];
    let t0 = Instant::now();
    while !companion.is_finished() && t0.elapsed() < Duration::from_secs(60) {
        let Ok((n, from)) = relay.recv_from(&mut buf) else {
            continue;
        };
        if from == sitl_addr {
            if let Some(f) = fly_addr {
                relay.send_to(&buf[..n], f).unwrap();
            }
            continue;
        }
        fly_addr = Some(from);
        if is_set_mode(&buf[..n]) && dropped < 2 {
            dropped += 1;
            if dropped == 2 {
                fly_stop.store(true, std::sync::atomic::Ordering::SeqCst);
            }
            continue;
        }
        relay.send_to(&buf[..n], sitl_addr).unwrap();
    }
    let r = companion.join().unwrap();
    sitl_stop.store(true, std::sync::atomic::Ordering::SeqCst);
    let report = vehicle.join().unwrap();
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(
        r.way_out_commanded && r.failsafe_acknowledged,
        "{:?}",
        r.events
    );
    assert!(
        !report.events.iter().any(|e| e.contains("disarmed by")),
        "{:?}",
        report.events
    );
    support::assert_logged(
        &r,
        &["HOLD commanded (armed by the companion, but the vehicle reports itself in the air"],
    );
    support::assert_logged(&r, &["the vehicle is in HOLD"]);
}

/// att39f-4: PX4's rover land detector reports `MAV_LANDED_STATE_IN_AIR` whenever the rover is
/// armed (RoverLandDetector: "if we are armed we are not landed"). A rover `fly --take-control
/// --arm` armed on the ground and interrupted before it had control is owed the disarm, in
/// the air or not by its report: a ground scenario's vehicle is on the ground. The stand-in:
/// disarmed when first heard, armed by the companion's ARM, EXTENDED_SYS_STATE IN_AIR while
/// armed, the switch to OFFBOARD acknowledged but never shown; the companion is interrupted at
/// that switch. It must send the disarm, never HOLD (before: HOLD, the rover left armed).
#[test]
fn a_rover_reporting_in_air_when_armed_is_still_disarmed() {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.take_control = true;
    o.arm = true;
    o.timeout_s = 2.0;
    let fly_stop = o.stop.clone();
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut armed = false;
        while t0.elapsed() < Duration::from_secs(60) {
            for r in link.poll(Duration::from_millis(20)).unwrap() {
                let MavMessage::COMMAND_LONG(c) = &r.msg else {
                    continue;
                };
                let ack = |link: &mut Link| {
                    link.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                        command: c.command,
                        result: MavResult::MAV_RESULT_ACCEPTED,
                    }))
                    .unwrap()
                };
                match c.command {
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM if c.param1 == 1.0 => {
                        armed = true;
                        ack(&mut link);
                    }
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => return Some("disarm"),
                    MavCmd::MAV_CMD_DO_SET_MODE if c.param2 == 6.0 => {
                        ack(&mut link);
                        fly_stop.store(true, std::sync::atomic::Ordering::SeqCst);
                    }
                    MavCmd::MAV_CMD_DO_SET_MODE => return Some("set mode"),
                    _ => {}
                }
            }
            if link.has_peer() {
                // PX4 POSCTL (main mode 3) as a pilot left it, armed only by the companion.
                link.send(&support::heartbeat(
                    MavType::MAV_TYPE_GROUND_ROVER,
                    MavAutopilot::MAV_AUTOPILOT_PX4,
                    support::custom_mode_flags(armed),
                    3 << 16,
                ))
                .unwrap();
                // The measurement, so that the companion goes on to arm and take control.
                let mut name = [0u8; 10];
                name[..5].copy_from_slice(b"ISO_S");
                link.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                    time_boot_ms: t0.elapsed().as_millis() as u32,
                    value: 12.0,
                    name: name.into(),
                }))
                .unwrap();
                link.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: t0.elapsed().as_millis() as u32,
                    ..Default::default()
                }))
                .unwrap();
                link.send(&MavMessage::EXTENDED_SYS_STATE(EXTENDED_SYS_STATE_DATA {
                    vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
                    landed_state: if armed {
                        MavLandedState::MAV_LANDED_STATE_IN_AIR
                    } else {
                        MavLandedState::MAV_LANDED_STATE_ON_GROUND
                    },
                }))
                .unwrap();
            }
        }
        None
    });
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    assert_eq!(vehicle.join().unwrap(), Some("disarm"), "{:?}", r.events);
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
}
