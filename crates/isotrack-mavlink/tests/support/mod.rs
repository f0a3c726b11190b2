//! Helpers the bridge's test binaries share (each `mod support;`): the stand-in vehicles'
//! heartbeat, a command and its acknowledgement, a Ctrl-C after a delay, what a flight logged.
//! Not every binary uses every helper.
#![allow(dead_code)]

use isotrack_mavlink::fly::{FlyOptions, FlyReport};
use isotrack_mavlink::link::Link;
use mavlink::dialects::common::*;
use std::time::{Duration, Instant};

/// A vehicle's heartbeat: its type, autopilot, `base_mode` flags and `custom_mode`.
pub fn heartbeat(
    mavtype: MavType,
    autopilot: MavAutopilot,
    base_mode: MavModeFlag,
    custom_mode: u32,
) -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode,
        mavtype,
        autopilot,
        base_mode,
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// `base_mode` with the custom mode enabled (as PX4 and ArduPilot send it), armed or not.
pub fn custom_mode_flags(armed: bool) -> MavModeFlag {
    let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    if armed {
        base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
    }
    base
}

/// Sends `cmd` (param1, param2) from `link` to vehicle (1, 1) and returns the result of its
/// acknowledgement (`None` after 10 s without one).
pub fn ack_of(link: &mut Link, cmd: MavCmd, p1: f32, p2: f32) -> Option<MavResult> {
    link.send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p1,
        param2: p2,
        command: cmd,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    }))
    .unwrap();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(10) {
        for r in link.poll(Duration::from_millis(50)).unwrap() {
            if let MavMessage::COMMAND_ACK(a) = &r.msg {
                if a.command == cmd {
                    return Some(a.result);
                }
            }
        }
    }
    None
}

/// Sets `o.stop` (Ctrl-C) after `s` seconds.
pub fn stop_after(o: &FlyOptions, s: f64) {
    let stop = o.stop.clone();
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs_f64(s));
        stop.store(true, std::sync::atomic::Ordering::SeqCst);
    });
}

/// How many of `r`'s events hold every one of `needles`.
pub fn logged(r: &FlyReport, needles: &[&str]) -> usize {
    r.events
        .iter()
        .filter(|e| needles.iter().all(|n| e.contains(n)))
        .count()
}

/// Asserts that one of `r`'s events holds every one of `needles` (the events shown when none
/// does).
#[track_caller]
pub fn assert_logged(r: &FlyReport, needles: &[&str]) {
    assert!(logged(r, needles) > 0, "{:?}", r.events);
}
