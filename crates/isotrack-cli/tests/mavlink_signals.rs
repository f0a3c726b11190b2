//! Ctrl-C (SIGINT) at each phase of `isotrack fly` (issue 33, docs/ROBUSTNESS.md's checklist
//! item 4), against a stand-in PX4 rover over UDP loopback: waiting for a heartbeat (nothing
//! sent, exit 69), waiting for the pilot (nothing commanded, exit 79), in control (HOLD
//! commanded and confirmed, exit 75), and in the failsafe's retries (a second Ctrl-C ends them
//! unconfirmed, exit 69). And two `fly` on one UDP port: the second is refused, never shares it.

#![cfg(unix)]

mod common;
use common::stderr;
use isotrack_mavlink::link::Link;
use mavlink::dialects::common::*;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A UDP port on 127.0.0.1 free a moment ago (bound, then released).
fn free_udp_port() -> u16 {
    let s = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    s.local_addr().unwrap().port()
}

/// PX4's OFFBOARD `custom_mode` (main mode 6 in bits 16..24, `px4_custom_mode.h`).
const PX4_OFFBOARD: u32 = 6 << 16;

/// What the stand-in vehicle received.
#[derive(Default, Debug)]
struct Seen {
    /// `COMMAND_LONG`s: (command, param2).
    commands: Vec<(MavCmd, f32)>,
    /// Setpoints received while armed in OFFBOARD.
    setpoints_in_control: u32,
    /// All setpoints.
    setpoints: u32,
}

/// A PX4 rover that beats every 50 ms with `ISO_S` and a position, accepts the arming and
/// OFFBOARD, and goes to the failsafe's mode when `confirm_way_out` (else acknowledges it and
/// stays in OFFBOARD); until `stop`.
fn vehicle(port: u16, confirm_way_out: bool, seen: Arc<Mutex<Seen>>, stop: Arc<AtomicBool>) {
    let mut v = Link::open(&format!("udpout:127.0.0.1:{port}"), 1, 1).unwrap();
    let (mut armed, mut mode, mut k) = (false, 0u32, 0u32);
    while !stop.load(Ordering::SeqCst) {
        let mut base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        if armed {
            base_mode |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        let _ = v.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: mode,
            mavtype: MavType::MAV_TYPE_GROUND_ROVER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }));
        let mut name = [0u8; 10];
        name[..5].copy_from_slice(b"ISO_S");
        let _ = v.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
            time_boot_ms: 1000 + 50 * k,
            value: 1.0,
            name: name.into(),
        }));
        let _ = v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
            time_boot_ms: 1000 + 50 * k,
            ..Default::default()
        }));
        k += 1;
        let Ok(received) = v.poll(Duration::from_millis(50)) else {
            continue;
        };
        for r in received {
            match &r.msg {
                MavMessage::COMMAND_LONG(c) => {
                    seen.lock().unwrap().commands.push((c.command, c.param2));
                    match c.command {
                        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => armed = c.param1 == 1.0,
                        MavCmd::MAV_CMD_DO_SET_MODE if c.param2 == 6.0 => mode = PX4_OFFBOARD,
                        MavCmd::MAV_CMD_DO_SET_MODE if confirm_way_out => {
                            mode = ((c.param2 as u32) << 16) | ((c.param3 as u32) << 24)
                        }
                        _ => {}
                    }
                    let _ = v.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                        command: c.command,
                        result: MavResult::MAV_RESULT_ACCEPTED,
                    }));
                }
                MavMessage::SET_ATTITUDE_TARGET(_) => {
                    let mut s = seen.lock().unwrap();
                    s.setpoints += 1;
                    if armed && mode == PX4_OFFBOARD {
                        s.setpoints_in_control += 1;
                    }
                }
                _ => {}
            }
        }
    }
}

/// `fly` (default Dubins scenario) listening on `udpin:127.0.0.1:PORT` with `extra` flags.
fn fly(port: u16, extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--timeout-s", "30"])
        .args(extra)
        .arg("--mavlink")
        .arg(format!("udpin:127.0.0.1:{port}"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn sigint(child: &Child) {
    let ok = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

/// Waits (at most 60 s) until `cond` holds of what the vehicle saw.
fn wait_for(seen: &Mutex<Seen>, what: &str, cond: impl Fn(&Seen) -> bool) {
    let t0 = Instant::now();
    while !cond(&seen.lock().unwrap()) {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "{what}: {:?}",
            seen.lock().unwrap()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Runs `fly` with `extra` against the stand-in; `at` says when to send Ctrl-C (a second one
/// when `again` says so); returns fly's output and what the vehicle saw.
fn interrupted_flight(
    extra: &[&str],
    confirm_way_out: bool,
    at: impl Fn(&Seen) -> bool,
    again: Option<fn(&Seen) -> bool>,
) -> (std::process::Output, Seen) {
    let port = free_udp_port();
    let mut child = fly(port, extra);
    // Its first line says it listens.
    let mut line = String::new();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    err.read_line(&mut line).unwrap();
    assert!(line.contains("companion on"), "{line}");
    let (seen, stop) = (
        Arc::new(Mutex::new(Seen::default())),
        Arc::new(AtomicBool::new(false)),
    );
    let v = {
        let (seen, stop) = (seen.clone(), stop.clone());
        std::thread::spawn(move || vehicle(port, confirm_way_out, seen, stop))
    };
    wait_for(&seen, "before the first Ctrl-C", at);
    sigint(&child);
    if let Some(again) = again {
        wait_for(&seen, "before the second Ctrl-C", again);
        sigint(&child);
    }
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    let mut o = child.wait_with_output().unwrap();
    o.stderr = format!("{line}{rest}").into_bytes();
    stop.store(true, Ordering::SeqCst);
    v.join().unwrap();
    let seen = std::mem::take(&mut *seen.lock().unwrap());
    (o, seen)
}

fn way_outs(s: &Seen) -> usize {
    s.commands
        .iter()
        .filter(|(c, p2)| *c == MavCmd::MAV_CMD_DO_SET_MODE && *p2 != 6.0)
        .count()
}

#[test]
fn ctrl_c_while_waiting_for_a_heartbeat_sends_nothing_and_exits_69() {
    let port = free_udp_port();
    let mut child = fly(port, &["--take-control", "--arm"]);
    let mut line = String::new();
    BufReader::new(child.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(line.contains("companion on"), "{line}");
    let t0 = Instant::now();
    sigint(&child);
    let o = child.wait_with_output().unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(69), "{out}");
    assert!(out.contains("end         interrupted"), "{out}");
    // At once, not after the 30 s --timeout-s.
    assert!(t0.elapsed() < Duration::from_secs(20));
}

#[test]
fn ctrl_c_while_waiting_for_the_pilot_commands_nothing_and_exits_79() {
    let (o, seen) = interrupted_flight(&[], true, |s| s.setpoints >= 3, None);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(79), "{err}");
    assert!(err.contains("nothing commanded"), "{err}");
    assert!(seen.commands.is_empty(), "{seen:?}");
}

#[test]
fn ctrl_c_in_control_commands_hold_and_exits_75_once_confirmed() {
    let (o, seen) = interrupted_flight(
        &["--take-control", "--arm"],
        true,
        |s| s.setpoints_in_control >= 5,
        None,
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(75), "{err}");
    assert!(
        err.contains("failsafe (interrupted)") && err.contains("the vehicle is in"),
        "{err}"
    );
    assert_eq!(way_outs(&seen), 1, "{seen:?}");
}

#[test]
fn a_second_ctrl_c_in_the_failsafe_ends_the_retries_unconfirmed_exit_69() {
    let (o, seen) = interrupted_flight(
        &["--take-control", "--arm"],
        false,
        |s| s.setpoints_in_control >= 5,
        Some(|s| way_outs(s) >= 1),
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(69), "{err}");
    assert!(err.contains("stopped by a signal"), "{err}");
    // Fewer than the 20 tries the retries allow: the second Ctrl-C ended them.
    assert!(way_outs(&seen) < 20, "{seen:?}");
}

/// Two `fly` on one `udpin:` port: the second is refused at once, naming the taken port (never
/// two companions silently sharing a vehicle's traffic).
#[test]
fn a_second_fly_on_a_taken_port_is_refused() {
    let port = free_udp_port();
    let mut first = fly(port, &[]);
    let mut line = String::new();
    BufReader::new(first.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(line.contains("companion on"), "{line}");
    let second = fly(port, &[]).wait_with_output().unwrap();
    let err = stderr(&second);
    assert_eq!(second.status.code(), Some(71), "{err}");
    assert!(
        err.contains(&format!("udpin:127.0.0.1:{port}")) && err.contains("the port is taken"),
        "{err}"
    );
    sigint(&first);
    let o = first.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(69));
}
