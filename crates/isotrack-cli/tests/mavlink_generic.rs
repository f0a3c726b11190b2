//! `isotrack fly --take-control` against a stand-in vehicle announcing `MAV_TYPE_GENERIC`
//! (issue 33): refused before anything is sent (exit 65) unless `--allow-generic`; with it, an
//! ArduPilot vehicle of that type (no mode table here) gets nothing commanded: exit 79, not 75,
//! and not one setpoint (armed or not). No setpoint goes to a vehicle before it is accepted and
//! armed: a PX4 rover that refuses the arming has received none.

mod common;
use common::stderr;
use isotrack_mavlink::link::Link;
use mavlink::dialects::common::*;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// A UDP port on 127.0.0.1 free a moment ago (bound, then released).
fn free_udp_port() -> u16 {
    let s = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    s.local_addr().unwrap().port()
}

/// The stand-in vehicle.
#[derive(Clone, Copy)]
struct Vehicle {
    autopilot: MavAutopilot,
    mavtype: MavType,
    /// Beats armed (by its pilot) from the start.
    armed: bool,
    /// Answers an arming with `MAV_RESULT_DENIED`.
    deny_arming: bool,
}

/// An ArduPilot `MAV_TYPE_GENERIC` vehicle, disarmed.
const GENERIC_ARDUPILOT: Vehicle = Vehicle {
    autopilot: MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
    mavtype: MavType::MAV_TYPE_GENERIC,
    armed: false,
    deny_arming: false,
};

/// Runs `fly` (default Dubins scenario, listening on `udpin:`) with `extra` flags against an
/// ArduPilot `MAV_TYPE_GENERIC` stand-in that beats disarmed and sends `ISO_S` and a position
/// every 50 ms; returns its output and how many commands and setpoints the stand-in received.
fn fly_against_generic(extra: &[&str]) -> (std::process::Output, Vec<String>, u32) {
    fly_against(GENERIC_ARDUPILOT, extra)
}

/// Runs `fly --take-control` (default Dubins scenario, listening on `udpin:`) with `extra`
/// flags against `vehicle`, which beats and sends `ISO_S` and a position every 50 ms; returns
/// its output, the commands it received and how many setpoints.
fn fly_against(vehicle: Vehicle, extra: &[&str]) -> (std::process::Output, Vec<String>, u32) {
    let port = free_udp_port();
    let child = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "5"])
        .args(extra)
        .arg("--mavlink")
        .arg(format!("udpin:127.0.0.1:{port}"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Give `fly` a moment to bind before the first datagram.
    std::thread::sleep(Duration::from_millis(300));
    let mut v = Link::open(&format!("udpout:127.0.0.1:{port}"), 1, 1).unwrap();
    let mut child = child;
    let (mut commands, mut setpoints, mut sent) = (Vec::new(), 0u32, 0u32);
    let t0 = Instant::now();
    let mut base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    if vehicle.armed {
        base_mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    while child.try_wait().unwrap().is_none() && t0.elapsed() < Duration::from_secs(30) {
        v.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: vehicle.mavtype,
            autopilot: vehicle.autopilot,
            base_mode,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }))
        .unwrap();
        let mut name = [0u8; 10];
        name[..5].copy_from_slice(b"ISO_S");
        v.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
            time_boot_ms: 1000 + 50 * sent,
            value: 1.0,
            name: name.into(),
        }))
        .unwrap();
        v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
            time_boot_ms: 1000 + 50 * sent,
            ..Default::default()
        }))
        .unwrap();
        sent += 1;
        for r in v.poll(Duration::from_millis(50)).unwrap() {
            match &r.msg {
                MavMessage::COMMAND_LONG(c) => {
                    commands.push(format!("{:?}", c.command));
                    if vehicle.deny_arming && c.command == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM {
                        v.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                            command: c.command,
                            result: MavResult::MAV_RESULT_DENIED,
                        }))
                        .unwrap();
                    }
                }
                MavMessage::SET_ATTITUDE_TARGET(_) => setpoints += 1,
                _ => {}
            }
        }
    }
    if child.try_wait().unwrap().is_none() {
        child.kill().unwrap();
    }
    (child.wait_with_output().unwrap(), commands, setpoints)
}

#[cfg(unix)]
#[test]
fn take_control_refuses_a_generic_vehicle_unless_allowed() {
    let (o, commands, setpoints) = fly_against_generic(&[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(65), "{err}");
    assert!(
        err.contains("vehicle_mismatch")
            && err.contains("MAV_TYPE_GENERIC")
            && err.contains("--allow-generic"),
        "{err}"
    );
    assert!(
        commands.is_empty() && setpoints == 0,
        "{commands:?} {setpoints} {err}"
    );
}

#[cfg(unix)]
#[test]
fn a_generic_ardupilot_vehicle_without_a_mode_table_exits_79() {
    let (o, commands, setpoints) = fly_against_generic(&["--allow-generic"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(79), "{err}");
    assert!(
        err.contains("no mode table") && err.contains("control_refused"),
        "{err}"
    );
    assert!(!err.contains("ended by a failsafe"), "{err}");
    // No command (arming, mode), and not one setpoint: the vehicle was never accepted for
    // control (no mode table here), and it is disarmed.
    assert!(
        commands.is_empty() && setpoints == 0,
        "{commands:?} {setpoints} {err}"
    );
}

/// The same vehicle armed by its pilot: still not one setpoint (control can never be taken).
#[cfg(unix)]
#[test]
fn an_armed_generic_ardupilot_vehicle_without_a_mode_table_gets_no_setpoint() {
    let vehicle = Vehicle {
        armed: true,
        ..GENERIC_ARDUPILOT
    };
    let (o, commands, setpoints) = fly_against(vehicle, &["--allow-generic"]);
    let err = stderr(&o);
    assert!(err.contains("no mode table"), "{err}");
    assert_eq!(setpoints, 0, "{commands:?} {err}");
}

/// A disarmed PX4 rover that refuses the arming: the arming is the only thing sent, never a
/// setpoint (none goes to a disarmed vehicle under --take-control); exit 79, nothing else
/// commanded.
#[cfg(unix)]
#[test]
fn no_setpoint_reaches_a_vehicle_that_refuses_the_arming() {
    let vehicle = Vehicle {
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        mavtype: MavType::MAV_TYPE_GROUND_ROVER,
        armed: false,
        deny_arming: true,
    };
    let (o, commands, setpoints) = fly_against(vehicle, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(79), "{err}");
    assert!(err.contains("control_refused"), "{err}");
    assert!(
        !commands.is_empty() && commands.iter().all(|c| c == "MAV_CMD_COMPONENT_ARM_DISARM"),
        "{commands:?} {err}"
    );
    assert_eq!(setpoints, 0, "{err}");
}
