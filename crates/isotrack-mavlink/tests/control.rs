//! Taking and letting go of control, against a scripted stand-in vehicle (system 1, component 1,
//! PX4 modes; a ground rover flying the default Dubins scenario, a fixed wing flying Fig. 3's)
//! that records every command it receives: the companion locks onto the autopilot
//! only, takes control only once the sensor and a position are there, and on a refused take-over
//! or a failsafe commands its way out (disarm on the ground, else HOLD) until the vehicle
//! confirms it. Real time is needed (a silence is a duration); nothing asserts how long
//! anything took.

use isotrack_mavlink::fly::{run_fly, FailsafeAction, FlyEnd, FlyOptions, FlyReport};
use isotrack_mavlink::link::Link;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::time::{Duration, Instant};

mod support;
use support::stop_after;

/// PX4's custom_mode of OFFBOARD (main mode 6).
const OFFBOARD: u32 = 6 << 16;

/// How the stand-in behaves.
#[derive(Clone)]
struct Script {
    /// Armed (by a pilot) from the start.
    armed: bool,
    /// The answer to an arm command.
    arm: MavResult,
    /// The answer to a switch to OFFBOARD.
    offboard: MavResult,
    /// The first failsafe mode commands (HOLD/RETURN) go unanswered: acknowledged from this
    /// one on (1: the first).
    hold_acked_at: u32,
    /// Beats (50 ms) before the first measurement and position; `u32::MAX`: never.
    quiet_beats: u32,
    /// A gimbal (component 154, `MAV_AUTOPILOT_GENERIC`) beats on the vehicle's system, first.
    gimbal: bool,
    /// The vehicle also sends each heartbeat as a MAVLink 1 frame.
    mavlink1: bool,
    /// The mode (PX4 custom_mode) from the start.
    start_mode: u32,
    /// A pilot arms it and switches it to OFFBOARD at this beat.
    offboard_at_beat: Option<u32>,
    /// Positions turn to NaN from this beat on.
    nan_positions_from: u32,
    /// It acknowledges HOLD/RETURN but stays in its mode (a liar).
    hold_lies: bool,
    /// Its autopilot and type (PX4 ground rover by default; ArduPilot's mode numbers differ).
    firmware: (MavAutopilot, MavType),
    /// The scenario flown: `None`, the one of the vehicle's type (Fig. 3's fixed wing for
    /// `MAV_TYPE_FIXED_WING`, else the default Dubins robot).
    scenario: Option<&'static str>,
    /// Asked for a failsafe mode, it goes to this PX4 mode instead (another safe mode).
    hold_goes_to: Option<u32>,
    /// At this beat another companion (component 192) sends the vehicle a setpoint.
    foreign_setpoint_at: Option<u32>,
    /// That companion's component (192; 191: a twin with the companion's own ids).
    foreign_component: u8,
    /// At this beat the vehicle acknowledges an arming nobody here asked for (a ground
    /// station's), denied.
    stray_ack_at: Option<u32>,
    /// Until it is in OFFBOARD it sends its first measurement again and again (as `sitl` in
    /// lockstep does while nobody answers).
    resend_until_offboard: bool,
    /// After this many failsafe mode commands a pilot switches it to MANUAL (PX4 main mode 1).
    pilot_manual_after_holds: Option<u32>,
    /// From this beat on it sends no heartbeat (its measurements and positions go on).
    heartbeats_stop_at: Option<u32>,
    /// At this beat it disarms (in MANUAL), nobody having commanded it.
    disarm_at_beat: Option<u32>,
    /// With `disarm_at_beat`: its clock begins again at 0 there (the autopilot rebooted).
    clock_restarts: bool,
    /// Until it is in OFFBOARD it moves this far north each beat (a pilot flying it to the
    /// area), m; then it stays.
    pilot_flies_m_per_beat: f32,
    /// Switches to OFFBOARD go unanswered before this beat (a slow take-over).
    offboard_from_beat: u32,
    /// At this beat it also sends a measurement whose value is NaN.
    nan_measurement_at: Option<u32>,
    /// At this beat (a pilot) it switches to this PX4 mode.
    mode_at_beat: Option<(u32, u32)>,
    /// Each command is first answered DENIED addressed to a ground station (system 255,
    /// component 190: its own request's answer), then answered to the companion.
    gcs_denial_first: bool,
    /// The failsafe mode commands before this one (1: the first) are answered DENIED
    /// unaddressed and not carried out (a ground station's same command answered, say).
    hold_denied_before: u32,
    /// Each command is first answered DENIED unaddressed (no target: as an autopilot answers
    /// any sender's same command, a ground station's), then answered as the script says.
    unaddressed_denial_first: bool,
    /// After it accepts a mode switch, no heartbeat for this many beats (PX4's 1 Hz heartbeat:
    /// the switch shows only at the next one).
    quiet_after_ack_beats: u32,
    /// After it accepts a mode switch, no heartbeat for this long, s (wall time: a 1 Hz
    /// heartbeat however fast the turns go).
    quiet_after_ack_s: f64,
    /// It accepts the switch to OFFBOARD but stays in its mode (never shown).
    offboard_unshown: bool,
    /// Right after it accepts the first mode switch, a pilot switches to this PX4 mode.
    pilot_after_ack: Option<u32>,
    /// With `disarm_at_beat`: this many beats later it is armed again in OFFBOARD, and it
    /// sends no position meanwhile (no time-stamped message).
    rearm_after: Option<u32>,
    /// At this beat it also sends one position stamped 2 s back (a late frame).
    late_frame_at: Option<u32>,
}

impl Script {
    /// Its custom mode for `MAV_CMD_DO_SET_MODE`'s param2 and param3: PX4's `main << 16 |
    /// sub << 24`, ArduPilot's number in param2.
    fn custom_mode(&self, p2: f32, p3: f32) -> u32 {
        if self.firmware.0 == MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA {
            p2 as u32
        } else {
            ((p2 as u32) << 16) | ((p3 as u32) << 24)
        }
    }
    /// Its mode that follows setpoints: PX4 OFFBOARD (main mode 6), ArduPilot GUIDED
    /// (ArduCopter 4, ArduPlane and Rover 15).
    fn guided(&self) -> u32 {
        use MavType::*;
        match self.firmware {
            (MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA, MAV_TYPE_QUADROTOR) => 4,
            (MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA, _) => 15,
            _ => OFFBOARD,
        }
    }
}

impl Default for Script {
    fn default() -> Self {
        Self {
            armed: false,
            arm: MavResult::MAV_RESULT_ACCEPTED,
            offboard: MavResult::MAV_RESULT_ACCEPTED,
            hold_acked_at: 1,
            quiet_beats: 0,
            gimbal: false,
            mavlink1: false,
            start_mode: 0,
            offboard_at_beat: None,
            nan_positions_from: u32::MAX,
            hold_lies: false,
            firmware: (
                MavAutopilot::MAV_AUTOPILOT_PX4,
                MavType::MAV_TYPE_GROUND_ROVER,
            ),
            scenario: None,
            hold_goes_to: None,
            foreign_setpoint_at: None,
            foreign_component: 192,
            stray_ack_at: None,
            resend_until_offboard: false,
            pilot_manual_after_holds: None,
            heartbeats_stop_at: None,
            disarm_at_beat: None,
            clock_restarts: false,
            pilot_flies_m_per_beat: 0.0,
            offboard_from_beat: 0,
            nan_measurement_at: None,
            mode_at_beat: None,
            gcs_denial_first: false,
            unaddressed_denial_first: false,
            hold_denied_before: 1,
            quiet_after_ack_beats: 0,
            quiet_after_ack_s: 0.0,
            offboard_unshown: false,
            pilot_after_ack: None,
            rearm_after: None,
            late_frame_at: None,
        }
    }
}

/// A command the stand-in received: command, param1..3, target component, and how many
/// measurements it had sent before it.
#[derive(Clone, Debug)]
struct Got {
    cmd: MavCmd,
    p: [f32; 3],
    target_component: u8,
    measurements_before: u32,
}

fn heartbeat(mavtype: MavType, autopilot: MavAutopilot, armed: bool, mode: u32) -> MavMessage {
    support::heartbeat(mavtype, autopilot, support::custom_mode_flags(armed), mode)
}

/// The scenario a stand-in of `script` flies: its own, else the one of the vehicle's type.
fn scenario_of(script: &Script) -> Scenario {
    let name = script.scenario.or_else(|| {
        (script.firmware.1 == MavType::MAV_TYPE_FIXED_WING).then_some("paper-fig3-uav.toml")
    });
    match name {
        Some(n) => {
            let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../scenarios")
                .join(n);
            load_scenario(Some(&p), &[]).unwrap()
        }
        None => load_scenario(None, &[]).unwrap(),
    }
}

/// Flies the scenario's law against the stand-in (the companion listens, `udpin:`), until the
/// companion ends; returns its report and the commands the stand-in received.
fn against(script: Script, opts: impl FnOnce(&mut FlyOptions)) -> (FlyReport, Vec<Got>) {
    let (r, got, _) = against_counting(script, opts);
    (r, got)
}

/// [`against`], also counting the setpoints the stand-in received.
fn against_counting(
    script: Script,
    opts: impl FnOnce(&mut FlyOptions),
) -> (FlyReport, Vec<Got>, u32) {
    let s = scenario_of(&script);
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
    let addr = rx.recv().unwrap();
    let url = format!("udpout:{addr}");
    let mut v = Link::open(&url, 1, 1).unwrap();
    let mut gimbal = Link::open(&url, 1, 154).unwrap();
    let mut other = Link::open(&url, 1, script.foreign_component).unwrap();
    let mut setpoints = 0u32;
    let raw = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let (mut armed, mut mode, mut holds) = (script.armed, script.start_mode, 0u32);
    let (mut beats, mut sent) = (0u32, 0u32);
    // The vehicle's clock at `sent` 0, ms.
    let mut clock0 = 1000u32;
    let mut north_m = 0.0f32;
    let (mut quiet_until, mut pilot_after_ack) = (0u32, script.pilot_after_ack);
    let mut quiet_until_t = Instant::now();
    let mut got = Vec::new();
    let t0 = Instant::now();
    while !companion.is_finished() && t0.elapsed() < Duration::from_secs(60) {
        if script.offboard_at_beat == Some(beats) {
            armed = true;
            mode = script.guided();
        }
        if let Some((b, m)) = script.mode_at_beat {
            if b == beats {
                mode = m;
            }
        }
        if let (Some(d), Some(n)) = (script.disarm_at_beat, script.rearm_after) {
            if beats == d + n {
                armed = true;
                mode = script.guided();
            }
        }
        if script.disarm_at_beat == Some(beats) {
            armed = false;
            mode = 1 << 16;
            if script.clock_restarts {
                (clock0, sent) = (0, 0);
            }
        }
        if script.gimbal {
            gimbal
                .send(&heartbeat(
                    MavType::MAV_TYPE_GIMBAL,
                    MavAutopilot::MAV_AUTOPILOT_GENERIC,
                    false,
                    0,
                ))
                .unwrap();
        }
        if (!script.gimbal || beats > 0)
            && script.heartbeats_stop_at.is_none_or(|b| beats < b)
            && beats >= quiet_until
            && Instant::now() >= quiet_until_t
        {
            v.send(&heartbeat(
                script.firmware.1,
                script.firmware.0,
                armed,
                mode,
            ))
            .unwrap();
        }
        if script.mavlink1 {
            let mut frame = Vec::new();
            mavlink::write_v1_msg(
                &mut frame,
                mavlink::MavHeader {
                    system_id: 1,
                    component_id: 1,
                    sequence: 0,
                },
                &heartbeat(script.firmware.1, script.firmware.0, armed, mode),
            )
            .unwrap();
            raw.send_to(&frame, addr).unwrap();
        }
        if script.foreign_setpoint_at == Some(beats) {
            other
                .send(&MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
                    time_boot_ms: 1,
                    q: [1.0, 0.0, 0.0, 0.0],
                    target_system: 1,
                    target_component: 1,
                    type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
                    ..Default::default()
                }))
                .unwrap();
        }
        if script.stray_ack_at == Some(beats) {
            v.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                result: MavResult::MAV_RESULT_DENIED,
            }))
            .unwrap();
        }
        if beats >= script.quiet_beats {
            let mut name = [0u8; 10];
            name[..5].copy_from_slice(b"ISO_S");
            if script.resend_until_offboard && !(armed && mode == script.guided()) {
                sent = 0;
            }
            v.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                time_boot_ms: clock0 + 50 * sent,
                value: 1.0,
                name: name.into(),
            }))
            .unwrap();
            if !(armed && mode == script.guided()) {
                north_m += script.pilot_flies_m_per_beat;
            }
            if script.nan_measurement_at == Some(beats) {
                v.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                    time_boot_ms: clock0 + 50 * sent + 1,
                    value: f32::NAN,
                    name: name.into(),
                }))
                .unwrap();
            }
            let p = if beats >= script.nan_positions_from {
                f32::NAN
            } else {
                0.0
            };
            let paused = match (script.disarm_at_beat, script.rearm_after) {
                (Some(d), Some(n)) => (d..d + n).contains(&beats),
                _ => false,
            };
            if !paused {
                v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: clock0 + 50 * sent,
                    x: p + north_m,
                    y: p,
                    ..Default::default()
                }))
                .unwrap();
            }
            if script.late_frame_at == Some(beats) {
                v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                    time_boot_ms: (clock0 + 50 * sent).saturating_sub(2000),
                    x: north_m,
                    ..Default::default()
                }))
                .unwrap();
            }
            sent += 1;
        }
        beats += 1;
        for r in v.poll(Duration::from_millis(50)).unwrap() {
            if let MavMessage::SET_ATTITUDE_TARGET(_) = &r.msg {
                setpoints += 1;
            }
            let MavMessage::COMMAND_LONG(c) = &r.msg else {
                continue;
            };
            got.push(Got {
                cmd: c.command,
                p: [c.param1, c.param2, c.param3],
                target_component: c.target_component,
                measurements_before: sent,
            });
            // An autopilot answers commands to its own component (or to all, 0) only.
            if c.target_system != 1 || !matches!(c.target_component, 0 | 1) {
                continue;
            }
            if script.gcs_denial_first {
                // The extensions after command and result: progress, result_param2 (4 bytes),
                // target_system, target_component.
                v.send_extended(
                    &MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                        command: c.command,
                        result: MavResult::MAV_RESULT_DENIED,
                    }),
                    <COMMAND_ACK_DATA as mavlink::MessageData>::EXTRA_CRC,
                    3,
                    &[0, 0, 0, 0, 0, 255, 190],
                )
                .unwrap();
            }
            if script.unaddressed_denial_first {
                v.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                    command: c.command,
                    result: MavResult::MAV_RESULT_DENIED,
                }))
                .unwrap();
            }
            let result = match c.command {
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM if c.param1 == 1.0 => {
                    if script.arm == MavResult::MAV_RESULT_ACCEPTED {
                        armed = true;
                    }
                    script.arm
                }
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => {
                    armed = false;
                    MavResult::MAV_RESULT_ACCEPTED
                }
                MavCmd::MAV_CMD_DO_SET_MODE
                    if script.custom_mode(c.param2, c.param3) == script.guided()
                        && beats < script.offboard_from_beat =>
                {
                    continue;
                }
                MavCmd::MAV_CMD_DO_SET_MODE
                    if script.custom_mode(c.param2, c.param3) == script.guided() =>
                {
                    if script.offboard == MavResult::MAV_RESULT_ACCEPTED && !script.offboard_unshown
                    {
                        mode = script.guided();
                    }
                    script.offboard
                }
                MavCmd::MAV_CMD_DO_SET_MODE => {
                    holds += 1;
                    if script.pilot_manual_after_holds.is_some_and(|n| holds >= n) {
                        mode = 1 << 16;
                        continue;
                    }
                    if holds < script.hold_acked_at {
                        continue;
                    }
                    if holds < script.hold_denied_before {
                        v.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                            command: c.command,
                            result: MavResult::MAV_RESULT_DENIED,
                        }))
                        .unwrap();
                        continue;
                    }
                    if let Some(m) = script.hold_goes_to {
                        mode = m;
                    } else if !script.hold_lies {
                        mode = script.custom_mode(c.param2, c.param3);
                    }
                    MavResult::MAV_RESULT_ACCEPTED
                }
                _ => MavResult::MAV_RESULT_UNSUPPORTED,
            };
            v.send(&MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
                command: c.command,
                result,
            }))
            .unwrap();
            if c.command == MavCmd::MAV_CMD_DO_SET_MODE && result == MavResult::MAV_RESULT_ACCEPTED
            {
                quiet_until = beats + script.quiet_after_ack_beats;
                quiet_until_t = Instant::now() + Duration::from_secs_f64(script.quiet_after_ack_s);
                if let Some(m) = pilot_after_ack.take() {
                    mode = m;
                }
            }
        }
    }
    (companion.join().unwrap(), got, setpoints)
}

fn is_hold(g: &Got) -> bool {
    g.cmd == MavCmd::MAV_CMD_DO_SET_MODE && g.p[1] == 4.0 && g.p[2] == 3.0
}

fn is_disarm(g: &Got) -> bool {
    g.cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && g.p[0] == 0.0
}

/// The companion armed the vehicle on the ground, then OFFBOARD was refused: it disarms it
/// (no HOLD, no more setpoints), and the vehicle confirms.
#[test]
fn a_refused_offboard_disarms_what_the_companion_armed() {
    let script = Script {
        offboard: MavResult::MAV_RESULT_DENIED,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(got.iter().any(is_disarm), "{got:?}");
    assert!(!got.iter().any(is_hold), "{got:?}");
    assert!(
        r.way_out_commanded && r.failsafe_acknowledged,
        "{:?}",
        r.events
    );
    assert!(r.commands.is_empty());
}

/// A vehicle a pilot armed (in MANUAL, in flight) refuses OFFBOARD: the companion never
/// controlled it nor armed it, so it commands nothing (no HOLD yanking the pilot out of MANUAL,
/// no disarm): the pilot's mode stands.
#[test]
fn a_refused_offboard_of_a_pilots_vehicle_commands_nothing() {
    let script = Script {
        armed: true,
        start_mode: 1 << 16,
        offboard: MavResult::MAV_RESULT_DENIED,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(!got.iter().any(is_hold), "{got:?}");
    assert!(!got.iter().any(is_disarm), "{got:?}");
    assert!(!r.way_out_commanded, "{:?}", r.events);
}

/// A failsafe in control whose HOLD the vehicle acknowledges but does not take (still in
/// OFFBOARD), then a pilot switches it to MANUAL: the retries stop at once (the pilot's word
/// is final in the failsafe too), logged, no more HOLD after the pilot's MANUAL.
#[test]
fn a_pilot_taking_over_during_the_failsafe_stops_the_retries() {
    let script = Script {
        hold_lies: true,
        pilot_manual_after_holds: Some(2),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("pilot_took_over during the failsafe") && e.contains("MANUAL")),
        "{:?}",
        r.events
    );
    // The second HOLD met the pilot's MANUAL; at most one more was on its way.
    let holds = got.iter().filter(|g| is_hold(g)).count();
    assert!((2..=3).contains(&holds), "{holds} HOLDs: {got:?}");
}

/// Heartbeats that stop while measurements and positions still come: the vehicle's mode and
/// arming are unknown, the flight ends `link_lost` (after the heartbeat timeout, at least 3 s).
#[test]
fn a_vehicle_whose_heartbeats_stop_is_lost() {
    let script = Script {
        heartbeats_stop_at: Some(20),
        ..Script::default()
    };
    let (r, _) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::LinkLost, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("no heartbeat from the vehicle")),
        "{:?}",
        r.events
    );
}

/// A vehicle that refuses to arm stays disarmed: nothing more to command, the flight ends
/// `control_refused`.
#[test]
fn a_refused_arming_commands_nothing_more() {
    let script = Script {
        arm: MavResult::MAV_RESULT_DENIED,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(!r.way_out_commanded);
    assert!(!got.iter().any(|g| is_hold(g) || is_disarm(g)), "{got:?}");
}

/// A gimbal beating first on the vehicle's system (component 154) is not the vehicle: every
/// command goes to the autopilot, component 1.
#[test]
fn a_gimbal_is_not_the_vehicle() {
    let script = Script {
        gimbal: true,
        quiet_beats: u32::MAX,
        armed: true,
        start_mode: OFFBOARD,
        ..Script::default()
    };
    let (r, got) = against(script, |_| {});
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(!got.is_empty());
    assert!(got.iter().all(|g| g.target_component == 1), "{got:?}");
    assert!(
        r.events.iter().any(|e| e.contains("system 1, component 1")),
        "{:?}",
        r.events
    );
}

/// `--take-control` arms only once a measurement and a position have arrived (here after 20
/// beats of silence).
#[test]
fn take_control_waits_for_the_sensor() {
    let script = Script {
        quiet_beats: 20,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(0.5);
    });
    let arm = got
        .iter()
        .find(|g| g.cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && g.p[0] == 1.0)
        .unwrap_or_else(|| panic!("no arm: {:?} {got:?}", r.events));
    assert!(arm.measurements_before > 0, "{got:?}");
}

/// Without any measurement, `--take-control` never arms: sensor loss after the timeout.
#[test]
fn take_control_without_a_sensor_never_arms() {
    let script = Script {
        quiet_beats: u32::MAX,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(
        !got.iter()
            .any(|g| g.cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && g.p[0] == 1.0),
        "{got:?}"
    );
}

/// HOLD is commanded until the vehicle acknowledges it, not 5 times: a vehicle that answers the
/// 8th is confirmed in HOLD.
#[test]
fn hold_is_retried_until_acknowledged() {
    let script = Script {
        quiet_beats: u32::MAX,
        hold_acked_at: 8,
        armed: true,
        start_mode: OFFBOARD,
        ..Script::default()
    };
    let (r, got) = against(script, |_| {});
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(r.failsafe_acknowledged, "{:?}", r.events);
    assert_eq!(got.iter().filter(|g| is_hold(g)).count(), 8, "{got:?}");
}

/// MAVLink 1 frames are not silently dropped: the companion logs once that it saw them.
#[test]
fn mavlink1_is_logged_once() {
    let script = Script {
        quiet_beats: u32::MAX,
        mavlink1: true,
        ..Script::default()
    };
    let (r, _) = against(script, |_| {});
    let n = r.events.iter().filter(|e| e.contains("MAVLink 1")).count();
    assert_eq!(n, 1, "{:?}", r.events);
    assert!(r.link.mavlink1_frames > 1);
}

/// Ctrl-C after the companion armed the vehicle on the ground but before OFFBOARD (the
/// vehicle keeps answering "in progress"): it disarms it, never a HOLD.
#[test]
fn an_interrupt_before_offboard_disarms_what_the_companion_armed() {
    let script = Script {
        offboard: MavResult::MAV_RESULT_IN_PROGRESS,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        // After the arming (sent once TWO_VEHICLES_WINDOW_S, 2 s, has passed).
        stop_after(o, 3.0);
    });
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(got.iter().any(is_disarm), "{got:?}");
    assert!(!got.iter().any(is_hold), "{got:?}");
    assert!(r.failsafe_acknowledged, "{:?}", r.events);
}

/// A pilot-flown vehicle (armed, not in OFFBOARD) that the companion never controlled: a lost
/// sensor stops the companion and commands nothing.
#[test]
fn a_pilots_vehicle_gets_no_hold_on_sensor_loss() {
    let script = Script {
        armed: true,
        quiet_beats: u32::MAX,
        ..Script::default()
    };
    let (r, got) = against(script, |_| {});
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(!got.iter().any(|g| is_hold(g) || is_disarm(g)), "{got:?}");
}

/// A disarmed vehicle: --max-duration-s does not count before control, and Ctrl-C commands
/// nothing.
#[test]
fn a_disarmed_vehicle_gets_nothing_on_interrupt() {
    let (r, got) = against(Script::default(), |o| {
        o.max_duration_s = Some(0.3);
        stop_after(o, 2.0);
    });
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(got.is_empty(), "{got:?}");
}

/// --max-duration-s counts from when the companion has control: a pilot switches to OFFBOARD
/// at beat 40 (2 s of measurements at 20 Hz later), and the law answers about 0.5 s / 50 ms =
/// 10 measurements in control before the end (none, if it counted from the first one).
#[test]
fn max_duration_counts_from_control() {
    let script = Script {
        offboard_at_beat: Some(40),
        ..Script::default()
    };
    let (r, got) = against(script, |o| o.max_duration_s = Some(0.5));
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(r.commands.len() >= 5, "{:?} {:?}", r.commands, r.events);
    assert!(got.iter().any(is_hold), "{got:?}");
}

/// Positions turning NaN in flight do not switch the fence off: position_lost after
/// --timeout-s.
#[test]
fn the_fence_fails_safe_when_positions_stop() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        nan_positions_from: 10,
        ..Script::default()
    };
    let (r, got) = against(script, |o| o.fence_m = Some(1000.0));
    assert_eq!(r.end, FlyEnd::Fence, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("position_lost")),
        "{:?}",
        r.events
    );
    assert!(got.iter().any(is_hold), "{got:?}");
}

/// A vehicle that acknowledges HOLD but stays in OFFBOARD has not confirmed it; the retries
/// end at their bound (3 x 2 s, i.e. at most 6 s / 0.3 s = 20 tries, not the minute the
/// stand-in lasts).
#[test]
fn an_acknowledged_hold_without_the_mode_is_not_confirmed() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        quiet_beats: u32::MAX,
        hold_lies: true,
        ..Script::default()
    };
    let (r, got) = against(script, |_| {});
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(got.iter().filter(|g| is_hold(g)).count() <= 21, "{got:?}");
}

/// A signal during the HOLD retries ends them (unconfirmed).
#[test]
fn a_signal_ends_the_hold_retries() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        quiet_beats: u32::MAX,
        hold_acked_at: u32::MAX,
        ..Script::default()
    };
    let (r, _) = against(script, |o| stop_after(o, 3.5));
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("stopped by a signal")),
        "{:?}",
        r.events
    );
}

/// Two autopilots (systems 1 and 2) beating from the start: the companion refuses to pick
/// (`two_vehicles`, naming both, nothing commanded); with `target_system` 2 it takes system 2.
#[test]
fn two_autopilots_are_refused_unless_one_is_picked() {
    for pick in [None, Some(2u8)] {
        let s = load_scenario(None, &[]).unwrap();
        let mut o = FlyOptions::new("udpin:127.0.0.1:0");
        o.timeout_s = 1.0;
        o.target_system = pick;
        let (tx, rx) = std::sync::mpsc::channel();
        let companion = std::thread::spawn(move || {
            run_fly(&s, &o, &mut NoTrace, &mut |l| {
                tx.send(l.local_addr()?).unwrap();
                Ok(())
            })
            .unwrap()
        });
        let url = format!("udpout:{}", rx.recv().unwrap());
        let mut a = Link::open(&url, 1, 1).unwrap();
        let mut b = Link::open(&url, 2, 1).unwrap();
        let t0 = Instant::now();
        while !companion.is_finished() && t0.elapsed() < Duration::from_secs(60) {
            for l in [&mut a, &mut b] {
                l.send(&heartbeat(
                    MavType::MAV_TYPE_GROUND_ROVER,
                    MavAutopilot::MAV_AUTOPILOT_PX4,
                    false,
                    0,
                ))
                .unwrap();
                l.poll(Duration::from_millis(25)).unwrap();
            }
        }
        let r = companion.join().unwrap();
        match pick {
            None => {
                assert_eq!(r.end, FlyEnd::TwoVehicles, "{:?}", r.events);
                let e = r.events.iter().find(|e| e.contains("two autopilots"));
                assert!(
                    e.is_some_and(|e| e.contains("system 1") && e.contains("system 2")),
                    "{:?}",
                    r.events
                );
                assert!(!r.way_out_commanded);
            }
            Some(_) => {
                assert_ne!(r.end, FlyEnd::TwoVehicles, "{:?}", r.events);
                assert!(
                    r.events.iter().any(|e| e.contains("vehicle: system 2")),
                    "{:?}",
                    r.events
                );
            }
        }
    }
}

/// The modes a flight with `--take-control` asked for (DO_SET_MODE's param2 and param3, in
/// order), and its report, against a stand-in of `firmware`; the flight ends at
/// `--max-duration-s` 0.5 (a failsafe: `failsafe` commanded).
fn modes_of(
    firmware: (MavAutopilot, MavType),
    failsafe: FailsafeAction,
) -> (FlyReport, Vec<(f32, f32)>) {
    let script = Script {
        firmware,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.failsafe = failsafe;
        o.max_duration_s = Some(0.5);
    });
    let modes = got
        .iter()
        .filter(|g| g.cmd == MavCmd::MAV_CMD_DO_SET_MODE)
        .map(|g| {
            assert_eq!(g.p[0], 1.0, "MAV_MODE_FLAG_CUSTOM_MODE_ENABLED");
            (g.p[1], g.p[2])
        })
        .collect();
    (r, modes)
}

/// ArduPilot's mode numbers by vehicle type (ArduPlane: GUIDED 15, RTL 11, LOITER 12; Rover:
/// GUIDED 15, HOLD 4, LOITER 5, RTL 11), never PX4's (whose 4 and 6 are ArduPlane's ACRO and
/// FBWB); each failsafe mode confirmed by the vehicle's heartbeat. (ArduCopter's table, GUIDED
/// 4, LOITER 5, RTL 6, is the unit test's in `modes`: no scenario kind flies a multirotor.)
#[test]
fn ardupilot_modes_by_vehicle_type() {
    let ap = MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA;
    for (mavtype, failsafe, guided, way_out, name) in [
        (
            MavType::MAV_TYPE_FIXED_WING,
            FailsafeAction::Return,
            15.0,
            11.0,
            "RTL",
        ),
        (
            MavType::MAV_TYPE_FIXED_WING,
            FailsafeAction::Hold,
            15.0,
            12.0,
            "LOITER",
        ),
        (
            MavType::MAV_TYPE_GROUND_ROVER,
            FailsafeAction::Hold,
            15.0,
            4.0,
            "HOLD",
        ),
        (
            MavType::MAV_TYPE_GROUND_ROVER,
            FailsafeAction::Loiter,
            15.0,
            5.0,
            "LOITER",
        ),
        (
            MavType::MAV_TYPE_GROUND_ROVER,
            FailsafeAction::Return,
            15.0,
            11.0,
            "RTL",
        ),
    ] {
        let (r, modes) = modes_of((ap, mavtype), failsafe);
        let case = format!("{mavtype:?} {failsafe:?}: {modes:?} {:?}", r.events);
        assert_eq!(r.end, FlyEnd::MaxDuration, "{case}");
        assert_eq!(modes.first(), Some(&(guided, 0.0)), "{case}");
        assert_eq!(modes.last(), Some(&(way_out, 0.0)), "{case}");
        assert!(r.failsafe_acknowledged, "{case}");
        let confirmed = format!("the vehicle is in {name}");
        assert!(r.events.iter().any(|e| e.contains(&confirmed)), "{case}");
    }
}

/// PX4: OFFBOARD is main mode 6; RETURN is AUTO.RTL (main 4, sub 5), not a loiter; LOITER and
/// HOLD are AUTO.LOITER (4, 3); each confirmed by the heartbeat.
#[test]
fn px4_return_and_loiter_modes() {
    let px4 = (
        MavAutopilot::MAV_AUTOPILOT_PX4,
        MavType::MAV_TYPE_FIXED_WING,
    );
    for (failsafe, way_out, name) in [
        (FailsafeAction::Return, (4.0, 5.0), "RETURN"),
        (FailsafeAction::Loiter, (4.0, 3.0), "LOITER"),
    ] {
        let (r, modes) = modes_of(px4, failsafe);
        assert_eq!(modes.first(), Some(&(6.0, 0.0)), "{modes:?}");
        assert_eq!(modes.last(), Some(&way_out), "{modes:?}");
        assert!(r.failsafe_acknowledged, "{:?}", r.events);
        let confirmed = format!("the vehicle is in {name}");
        assert!(
            r.events.iter().any(|e| e.contains(&confirmed)),
            "{:?}",
            r.events
        );
    }
}

/// An ArduPilot vehicle of a type without a mode table here (`MAV_TYPE_GENERIC`, which the
/// kind check lets through with a warning; a submarine is refused before, as of another
/// kind): `--take-control` commands nothing at all, not even the arming (it used to arm, find
/// no table, then disarm), and the take-over ends refused.
#[test]
fn a_vehicle_without_a_mode_table_is_never_armed() {
    let script = Script {
        firmware: (
            MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            MavType::MAV_TYPE_GENERIC,
        ),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.allow_generic = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("says nothing of its airframe")),
        "{:?}",
        r.events
    );
    assert!(
        got.iter()
            .all(|g| g.cmd != MavCmd::MAV_CMD_COMPONENT_ARM_DISARM
                && g.cmd != MavCmd::MAV_CMD_DO_SET_MODE),
        "commanded: {:?}",
        got.iter().map(|g| g.cmd).collect::<Vec<_>>()
    );
}

/// The scenario's vehicle kind against the vehicle's type, both ways: a Dubins (ground)
/// scenario and a fixed wing, a fixed-wing scenario and a ground rover, either and a
/// quadrotor: refused (`vehicle_mismatch`, naming both) before any setpoint or command, even
/// with `--take-control`.
#[test]
fn a_vehicle_of_another_kind_is_refused_before_anything_is_sent() {
    let px4 = MavAutopilot::MAV_AUTOPILOT_PX4;
    for (scenario, mavtype, kind) in [
        (None, MavType::MAV_TYPE_FIXED_WING, "dubins"),
        (
            Some("paper-fig3-uav.toml"),
            MavType::MAV_TYPE_GROUND_ROVER,
            "fixed_wing",
        ),
        (None, MavType::MAV_TYPE_QUADROTOR, "dubins"),
        (
            Some("paper-fig3-uav.toml"),
            MavType::MAV_TYPE_QUADROTOR,
            "fixed_wing",
        ),
    ] {
        let script = Script {
            firmware: (px4, mavtype),
            scenario: Some(scenario.unwrap_or("paper-fig2b-circular.toml")),
            ..Script::default()
        };
        let (r, got, setpoints) = against_counting(script, |o| {
            o.take_control = true;
            o.arm = true;
            o.arm = true;
        });
        let case = format!("{kind} vs {mavtype:?}: {:?}", r.events);
        assert_eq!(r.end, FlyEnd::VehicleMismatch, "{case}");
        assert!(got.is_empty(), "{case}: {got:?}");
        assert_eq!(setpoints, 0, "{case}");
        assert!(r.commands.is_empty() && !r.way_out_commanded, "{case}");
        let e = r.events.iter().find(|e| e.contains("vehicle_mismatch"));
        assert!(
            e.is_some_and(|e| e.contains(&format!("{mavtype:?}")) && e.contains(kind)),
            "{case}"
        );
    }
}

/// `--take-control` and a vehicle announcing `MAV_TYPE_GENERIC` (PX4 and ArduPilot, for a
/// fixed-wing and a ground scenario) without `--allow-generic`: refused (`vehicle_mismatch`)
/// before any setpoint or command, as a vehicle of another kind is.
#[test]
fn take_control_refuses_a_generic_vehicle_unless_allowed() {
    for (autopilot, scenario) in [
        (MavAutopilot::MAV_AUTOPILOT_PX4, "paper-fig3-uav.toml"),
        (MavAutopilot::MAV_AUTOPILOT_PX4, "paper-fig2b-circular.toml"),
        (
            MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            "paper-fig2b-circular.toml",
        ),
    ] {
        let script = Script {
            firmware: (autopilot, MavType::MAV_TYPE_GENERIC),
            scenario: Some(scenario),
            ..Script::default()
        };
        let (r, got, setpoints) = against_counting(script, |o| {
            o.take_control = true;
            o.arm = true;
            o.arm = true;
        });
        let case = format!("{autopilot:?} {scenario}: {:?}", r.events);
        assert_eq!(r.end, FlyEnd::VehicleMismatch, "{case}");
        assert!(got.is_empty(), "{case}: {got:?}");
        assert_eq!(setpoints, 0, "{case}");
        assert!(r.commands.is_empty() && !r.way_out_commanded, "{case}");
        assert!(
            r.events
                .iter()
                .any(|e| e.contains("vehicle_mismatch") && e.contains("--allow-generic")),
            "{case}"
        );
    }
}

/// A vehicle already armed and in OFFBOARD when a `--take-control` companion starts, which it
/// commanded neither: another controller holds it. Refused: nothing commanded, no setpoint,
/// nothing recorded as flown.
#[test]
fn take_control_does_not_join_a_vehicle_someone_else_holds() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        ..Script::default()
    };
    let (r, got, setpoints) = against_counting(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::AnotherController, "{:?}", r.events);
    assert!(got.is_empty(), "{got:?}");
    assert_eq!(setpoints, 0);
    assert!(
        r.commands.is_empty() && !r.way_out_commanded,
        "{:?}",
        r.events
    );
}

/// In control (a pilot's OFFBOARD), setpoints for the vehicle from another component (192):
/// another controller is flying it: the setpoints stop and HOLD is commanded.
#[test]
fn setpoints_from_another_controller_stop_the_flight() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        foreign_setpoint_at: Some(20),
        ..Script::default()
    };
    let (r, got) = against(script, |_| {});
    assert_eq!(r.end, FlyEnd::AnotherController, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("from system 1, component 192")),
        "{:?}",
        r.events
    );
    assert!(got.iter().any(is_hold), "{got:?}");
}

/// A setpoint with the companion's own system and component id (1, 191) is a twin's (the
/// link never hands the companion its own frames back): another controller, said so.
#[test]
fn a_twin_companions_setpoint_is_another_controller() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        foreign_setpoint_at: Some(20),
        foreign_component: 191,
        ..Script::default()
    };
    let (r, _) = against(script, |_| {});
    assert_eq!(r.end, FlyEnd::AnotherController, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("its own ids")),
        "{:?}",
        r.events
    );
}

/// Asked for RETURN (AUTO.RTL), the vehicle goes to AUTO.LOITER, another safe mode: the
/// failsafe ends there, after one command, logged; not retried until the bound.
#[test]
fn another_safe_mode_ends_the_failsafe() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        quiet_beats: u32::MAX,
        hold_goes_to: Some((4 << 16) | (3 << 24)),
        ..Script::default()
    };
    let (r, got) = against(script, |o| o.failsafe = FailsafeAction::Return);
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    assert!(r.failsafe_acknowledged, "{:?}", r.events);
    let modes = got
        .iter()
        .filter(|g| g.cmd == MavCmd::MAV_CMD_DO_SET_MODE)
        .count();
    assert_eq!(modes, 1, "{got:?}");
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("went to HOLD, not the RETURN commanded")),
        "{:?}",
        r.events
    );
    // The mode it is in is named, in the last event too (the summary's outcome_detail).
    assert!(
        r.events.last().is_some_and(|e| e.contains("is in HOLD")),
        "{:?}",
        r.events
    );
    assert!(
        !r.events.iter().any(|e| e.contains("is in RETURN")),
        "{:?}",
        r.events
    );
}

/// A failsafe mode the vehicle never confirms is commanded at most `MAX_WAY_OUT_TRIES` times,
/// however long `--timeout-s` makes the time bound (10 s: 30 s, 100 tries).
#[test]
fn the_way_out_is_tried_a_bounded_number_of_times() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        quiet_beats: u32::MAX,
        hold_acked_at: u32::MAX,
        ..Script::default()
    };
    let (r, got) = against(script, |o| o.timeout_s = 10.0);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    let n = got.iter().filter(|g| is_hold(g)).count() as u32;
    let max = isotrack_mavlink::fly::MAX_WAY_OUT_TRIES;
    assert!((max - 2..=max).contains(&n), "{n} tries: {:?}", r.events);
}

/// An acknowledgement of a command the companion did not send (a ground station's arming,
/// denied) is neither logged as the companion's nor a refusal of its take-over: it arms once
/// the sensor is there and flies to `--max-duration-s`.
#[test]
fn someone_elses_acknowledgement_is_not_the_companions() {
    let script = Script {
        quiet_beats: 10,
        stray_ack_at: Some(3),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("MAV_RESULT_DENIED")),
        "{:?}",
        r.events
    );
    assert!(
        got.iter()
            .any(|g| g.cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && g.p[0] == 1.0),
        "{got:?}"
    );
}

/// A clean take-over of a vehicle that sends its first measurement again while nobody answers
/// (as `sitl` in lockstep does): the copies held before control are one measurement, not
/// repeats: none counted, none logged.
#[test]
fn a_clean_take_over_logs_no_repeat() {
    let script = Script {
        resend_until_offboard: true,
        ..Script::default()
    };
    let (r, _) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert_eq!(r.measurements_repeated, 0, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("came again")),
        "{:?}",
        r.events
    );
    assert!(r.commands.len() >= 5, "{:?}", r.commands);
}

/// In control, the autopilot reboots (att33b item 2: `sitl` killed and restarted): its
/// heartbeat says disarmed in MANUAL, nobody having commanded it, and its clock begins again
/// at 0 (4 s back). Not a pilot's take-over: `vehicle_lost`, a failsafe (HOLD commanded).
#[test]
fn an_autopilot_that_reboots_in_flight_is_lost_not_taken_over() {
    let script = Script {
        disarm_at_beat: Some(60),
        clock_restarts: true,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("rebooted")),
        "{:?}",
        r.events
    );
    assert!(got.iter().any(is_hold), "{got:?}");
    assert!(r.way_out_commanded);
}

/// The same disarm with the vehicle's clock going on (a pilot's kill switch): the pilot's word
/// is final, `pilot_took_over`, nothing commanded.
#[test]
fn a_disarm_in_flight_without_a_reboot_is_the_pilots() {
    let script = Script {
        disarm_at_beat: Some(60),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!got.iter().any(is_hold), "{got:?}");
    assert!(!r.way_out_commanded);
}

/// FLYING.md's recipe (att33b item 19): the pilot flies the vehicle (armed, MANUAL) 400 m to
/// the area, then hands over (OFFBOARD). The 100 m fence is centred where the companion got
/// control and not enforced before: the flight is flown to its --max-duration-s, not ended by
/// the fence on the way.
#[test]
fn the_fence_is_centred_where_control_begins() {
    let script = Script {
        armed: true,
        start_mode: 1 << 16,
        offboard_at_beat: Some(40),
        pilot_flies_m_per_beat: 10.0,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.fence_m = Some(100.0);
        o.max_duration_s = Some(1.0);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(!r.commands.is_empty(), "{:?}", r.events);
    assert!(got.iter().any(is_hold), "{got:?}");
}

/// A slow take-over (att33b item 15): OFFBOARD is answered only from beat 40 (2 s of 50 ms
/// measurements held meanwhile). Once in control the law starts from the newest one held, not
/// from a burst of stale ones: its first command answers a measurement of beat 30 or later
/// (stamped 1000 + 50 k ms), and the older ones dropped are logged.
#[test]
fn a_slow_take_over_starts_from_the_newest_measurement() {
    let script = Script {
        offboard_from_beat: 40,
        ..Script::default()
    };
    let (r, _) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    let first_ms = r.commands.first().expect("a command").0;
    assert!(first_ms >= 1000 + 50 * 30, "{first_ms} {:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("older ones dropped")),
        "{:?}",
        r.events
    );
}

/// A measurement whose value is NaN (att33b item 3) is no measurement: dropped, counted in
/// measurements_invalid, logged once; the flight goes on.
#[test]
fn a_non_finite_measurement_is_counted_and_logged() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        nan_measurement_at: Some(5),
        ..Script::default()
    };
    let (r, _) = against(script, |o| o.max_duration_s = Some(1.0));
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert_eq!(r.measurements_invalid, 1, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("NaN") && e.contains("measurements_invalid")),
        "{:?}",
        r.events
    );
}

fn is_arm(g: &Got) -> bool {
    g.cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && g.p[0] == 1.0
}

/// att33c item 5: during a take-over (the vehicle armed by the companion, its OFFBOARD switch
/// unanswered), the pilot disarms it: the take-over ends at once, `pilot_took_over`; it is
/// never armed again, nothing more is commanded (no disarm, no HOLD).
#[test]
fn a_pilots_disarm_during_the_take_over_is_final() {
    let script = Script {
        offboard_from_beat: u32::MAX,
        disarm_at_beat: Some(60),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert_eq!(got.iter().filter(|g| is_arm(g)).count(), 1, "{got:?}");
    assert!(
        !got.iter().any(is_hold) && !got.iter().any(is_disarm),
        "{got:?}"
    );
    assert!(!r.way_out_commanded && r.commands.is_empty());
}

/// att33c item 5: a pilot's vehicle (armed in POSCTL) whose OFFBOARD switch goes unanswered;
/// the pilot switches to STABILIZED: the take-over ends at once, no more OFFBOARD requests
/// after the pilot's switch is heard, nothing commanded on the way out.
#[test]
fn a_pilots_mode_change_during_the_take_over_is_final() {
    let script = Script {
        armed: true,
        start_mode: 3 << 16,
        offboard_from_beat: u32::MAX,
        mode_at_beat: Some((60, 7 << 16)),
        ..Script::default()
    };
    let (r, got) = against(script, |o| o.take_control = true);
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains("STABILIZED")),
        "{:?}",
        r.events
    );
    assert!(
        !got.iter().any(is_hold) && !got.iter().any(is_disarm),
        "{got:?}"
    );
    // OFFBOARD is asked every 0.5 s (10 beats), from 2 s (TWO_VEHICLES_WINDOW_S): at most one
    // more after beat 60's switch.
    let late = got
        .iter()
        .filter(|g| g.cmd == MavCmd::MAV_CMD_DO_SET_MODE && g.measurements_before > 61)
        .count();
    assert!(late <= 1, "{got:?}");
}

/// att33c item 14: a vehicle armed in PX4 AUTO.RTL (its own failsafe bringing it home) is never
/// pulled out of it: nothing commanded, `control_refused`.
#[test]
fn take_control_never_pulls_a_vehicle_out_of_its_return() {
    let script = Script {
        armed: true,
        start_mode: (4 << 16) | (5 << 24),
        ..Script::default()
    };
    let (r, got, setpoints) = against_counting(script, |o| o.take_control = true);
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(got.is_empty(), "{got:?}");
    assert_eq!(setpoints, 0);
    assert!(
        r.events.iter().any(|e| e.contains("AUTO.RTL")),
        "{:?}",
        r.events
    );
}

/// att33c item 4: an acknowledgement addressed to a ground station (system 255, component 190),
/// DENIED, before the vehicle's answer to the companion: not the companion's; the take-over
/// goes on and the flight is flown.
#[test]
fn an_acknowledgement_addressed_to_another_system_is_not_ours() {
    let script = Script {
        gcs_denial_first: true,
        ..Script::default()
    };
    let (r, _) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(!r.commands.is_empty());
    assert!(
        !r.events.iter().any(|e| e.contains("DENIED")),
        "{:?}",
        r.events
    );
}

/// ver33b-11: every command is first answered DENIED unaddressed (an autopilot's answer to a
/// ground station's same command), then ACCEPTED; the switch to OFFBOARD shows only at the
/// heartbeat 0.5 s later (PX4's slow heartbeat). The refusal is not the vehicle's last word:
/// the companion waits for the heartbeat, takes control and flies (before: `control_refused`
/// at once, nothing commanded, the vehicle left in OFFBOARD with nobody sending setpoints), and
/// its way out at the end is confirmed. Both a pilot's vehicle (armed in POSCTL) and one the
/// companion arms.
#[test]
fn an_unaddressed_refusal_before_the_acceptance_is_not_the_last_word() {
    for armed in [true, false] {
        let script = Script {
            armed,
            start_mode: 3 << 16,
            unaddressed_denial_first: true,
            quiet_after_ack_beats: 10,
            ..Script::default()
        };
        let (r, got) = against(script, |o| {
            o.take_control = true;
            o.arm = true;
            o.max_duration_s = Some(1.0);
        });
        assert_eq!(r.end, FlyEnd::MaxDuration, "armed {armed}: {:?}", r.events);
        assert!(!r.commands.is_empty(), "{:?}", r.events);
        assert!(
            r.events
                .iter()
                .any(|e| e.contains("not the vehicle's last word")),
            "{:?}",
            r.events
        );
        assert!(got.iter().any(is_hold), "{got:?}");
        assert!(
            r.way_out_commanded && r.failsafe_acknowledged,
            "{:?}",
            r.events
        );
    }
}

/// att33e-5: the first failsafe HOLD is answered only by an unaddressed DENIED (not carried
/// out), the second ACCEPTED: the refusal does not end the retries (an unaddressed refusal may
/// answer someone else's same command), and the vehicle is confirmed in HOLD (before: "refused"
/// after one try, the vehicle left in OFFBOARD with nobody sending setpoints).
#[test]
fn a_refused_failsafe_mode_is_retried() {
    let script = Script {
        armed: true,
        start_mode: 3 << 16,
        hold_denied_before: 2,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.max_duration_s = Some(0.5);
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(got.iter().filter(|g| is_hold(g)).count() >= 2, "{got:?}");
    assert!(
        r.way_out_commanded && r.failsafe_acknowledged,
        "{:?}",
        r.events
    );
}

/// ver33b-11: the vehicle refuses OFFBOARD for real (DENIED, and its next heartbeat still shows
/// POSCTL): the take-over ends `control_refused` at that heartbeat, nothing commanded (the
/// pilot's mode stands), however long the heartbeat takes.
#[test]
fn a_refusal_the_next_heartbeat_confirms_ends_the_take_over() {
    let script = Script {
        armed: true,
        start_mode: 3 << 16,
        offboard: MavResult::MAV_RESULT_DENIED,
        unaddressed_denial_first: true,
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.max_duration_s = Some(5.0);
    });
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(!got.iter().any(is_hold), "{got:?}");
    assert!(!r.way_out_commanded, "{:?}", r.events);
}

/// att33c item 15: without `arm`, `--take-control` does not arm a disarmed vehicle (a real
/// aircraft is armed and flown to the area by its pilot): refused, nothing commanded.
#[test]
fn take_control_arms_only_when_asked() {
    let (r, got, setpoints) = against_counting(Script::default(), |o| o.take_control = true);
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    assert!(got.is_empty(), "{got:?}");
    assert_eq!(setpoints, 0);
    assert!(
        r.events.iter().any(|e| e.contains("--arm")),
        "{:?}",
        r.events
    );
}

fn is_offboard_switch(g: &Got) -> bool {
    g.cmd == MavCmd::MAV_CMD_DO_SET_MODE && g.p[1] == 6.0
}

/// att33d-7: a pilot's vehicle (armed in POSCTL) with a PX4-like heartbeat (none for 1 s after
/// an acknowledgement) accepts fly's OFFBOARD, and its pilot switches to STABILIZED at once:
/// the accepted switch is never sent again (a retry would take the vehicle back from the
/// pilot); the next heartbeat shows STABILIZED, the pilot's word: `pilot_took_over`.
#[test]
fn an_accepted_offboard_switch_is_never_sent_again() {
    let script = Script {
        armed: true,
        start_mode: 3 << 16,
        quiet_after_ack_beats: 20,
        pilot_after_ack: Some(7 << 16),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.max_duration_s = Some(1.0);
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert_eq!(
        got.iter().filter(|g| is_offboard_switch(g)).count(),
        1,
        "{got:?}"
    );
    assert!(r.commands.is_empty() && !r.way_out_commanded);
}

/// att45f-8: a pilot's vehicle (armed in POSCTL, a 1 Hz heartbeat: none for 1 s after an
/// acknowledgement) accepts every switch to OFFBOARD and never makes it. Each switch waits for
/// the heartbeat newer than the last acceptance, so in the 10 s of retries at most 1 + 10 go
/// out (before: 20, over 19 s, the log saying 10 s); at the bound the last accepted switch's
/// heartbeat is awaited, and it shows the pilot's POSCTL: `control_refused`, nothing
/// commanded (before: HOLD sent to the vehicle that showed POSCTL in every heartbeat).
#[test]
fn an_offboard_accepted_and_never_shown_is_retried_for_10_s_and_commands_nothing() {
    let script = Script {
        armed: true,
        start_mode: 3 << 16,
        quiet_after_ack_s: 1.0,
        offboard_unshown: true,
        ..Script::default()
    };
    let (r, got) = against(script, |o| o.take_control = true);
    assert_eq!(r.end, FlyEnd::ControlRefused, "{:?}", r.events);
    let switches = got.iter().filter(|g| is_offboard_switch(g)).count();
    assert!((2..=11).contains(&switches), "{switches} {got:?}");
    assert!(!got.iter().any(is_hold), "{got:?}");
    assert!(!got.iter().any(is_disarm), "{got:?}");
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("did not arm or switch to OFFBOARD in 10 s")),
        "{:?}",
        r.events
    );
}

/// att33d-6: in control, a failsafe's HOLD is accepted, then the pilot switches to POSCTL
/// before the next (1 Hz) heartbeat: HOLD is not sent again (it would yank the vehicle back);
/// the heartbeat shows POSCTL, a pilot's take-over during the failsafe.
#[test]
fn an_accepted_hold_is_not_sent_again_over_the_pilot() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        quiet_after_ack_beats: 20,
        pilot_after_ack: Some(3 << 16),
        ..Script::default()
    };
    let (r, got) = against(script, |o| stop_after(o, 0.5));
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert_eq!(got.iter().filter(|g| is_hold(g)).count(), 1, "{got:?}");
    assert!(r.way_out_overridden, "{:?}", r.events);
}

/// att33d-5: Ctrl-C after the vehicle accepted fly's OFFBOARD but before its next (1 Hz)
/// heartbeat shows it: the vehicle may be in OFFBOARD with nobody sending setpoints, so the
/// way out is commanded (HOLD) and confirmed, not "nothing commanded".
#[test]
fn a_failsafe_after_an_accepted_offboard_commands_the_way_out() {
    let script = Script {
        armed: true,
        start_mode: 3 << 16,
        quiet_after_ack_beats: 40,
        ..Script::default()
    };
    // OFFBOARD goes out at 2 s (TWO_VEHICLES_WINDOW_S); Ctrl-C 0.6 s after, in the quiet.
    let (r, got) = against(script, |o| {
        o.take_control = true;
        stop_after(o, 2.6);
    });
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(got.iter().any(is_hold), "{got:?}");
    assert!(
        r.way_out_commanded && r.failsafe_acknowledged,
        "{:?}",
        r.events
    );
}

/// att33d-3: in control the vehicle is disarmed (nobody here commanded it; no time-stamped
/// message while the disarm is watched for a reboot) and armed again in OFFBOARD 0.4 s later:
/// the disarm was a pilot's, `pilot_took_over`, never flown on (no setpoint left unsent while
/// the law runs).
#[test]
fn a_disarm_and_rearm_in_the_reboot_watch_is_the_pilots() {
    let script = Script {
        disarm_at_beat: Some(60),
        rearm_after: Some(8),
        ..Script::default()
    };
    let (r, got) = against(script, |o| {
        o.take_control = true;
        o.arm = true;
        o.max_duration_s = Some(6.0);
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!got.iter().any(is_hold) && !r.way_out_commanded, "{got:?}");
}

/// att33d-4: one position frame stamped 2 s before the newest (a late frame on a link that
/// reorders) is no reboot: dropped, the flight goes on to --max-duration-s.
#[test]
fn one_late_frame_is_not_a_reboot() {
    let script = Script {
        armed: true,
        start_mode: OFFBOARD,
        late_frame_at: Some(40),
        ..Script::default()
    };
    let (r, _) = against(script, |o| o.max_duration_s = Some(3.0));
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("rebooted")),
        "{:?}",
        r.events
    );
}
