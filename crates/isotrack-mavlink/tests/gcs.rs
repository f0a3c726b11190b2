//! The ground-station workflow of docs/FLYING.md, end to end against `sitl`: `fly` runs without
//! `--take-control` (answering with neutral setpoints), a ground station (system 255, as
//! QGroundControl and pymavlink default to) arms the vehicle and switches it to OFFBOARD, and
//! the companion's law then flies it: its setpoints are accepted and the vehicle turns as the
//! law commands.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions};
use isotrack_mavlink::link::Link;
use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::time::{Duration, Instant};

fn ack_of(link: &mut Link, cmd: MavCmd, p1: f32, p2: f32) -> Option<MavResult> {
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

fn gcs_workflow(gcs_system: u8) {
    let s = load_scenario(None, &["sim.duration_s=30".to_string()]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let sv = s.clone();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&sv, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let addr = rx.recv().unwrap();
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 20.0;
    o.max_duration_s = Some(3.0);
    let companion =
        std::thread::spawn(move || run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap());
    let mut gcs = Link::open(&format!("udpout:{addr}"), gcs_system, 190).unwrap();
    // The ground station waits for the vehicle (its heartbeat comes once the companion runs).
    gcs.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        mavlink_version: 3,
        ..Default::default()
    }))
    .unwrap();
    let t0 = Instant::now();
    let mut heard = false;
    while !heard && t0.elapsed() < Duration::from_secs(20) {
        heard = gcs
            .poll(Duration::from_millis(50))
            .unwrap()
            .iter()
            .any(|r| matches!(r.msg, MavMessage::HEARTBEAT(_)) && r.header.component_id == 1);
    }
    assert!(heard);
    let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
    let ok = Some(MavResult::MAV_RESULT_ACCEPTED);
    assert_eq!(ack_of(&mut gcs, arm, 1.0, 0.0), ok);
    assert_eq!(ack_of(&mut gcs, MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0), ok);
    let r = companion.join().unwrap();
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    let report = vehicle.join().unwrap();
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(!r.commands.is_empty(), "{:?}", r.events);
    // The ground station's acknowledgements (its arming, its mode switch) are not logged as
    // the companion's, which commanded nothing.
    assert!(
        !r.events.iter().any(|e| e.contains("MAV_RESULT")),
        "{:?}",
        r.events
    );
    // The vehicle flew the law's commands: each command the companion sent for a sample is
    // the turn rate the vehicle flew from it (the default scenario's Dubins robot: the yaw
    // rate is the turn rate, through f32).
    let mut flown_law = 0;
    for (ms, w) in &r.commands {
        if let Some((_, f)) = report.flown.iter().find(|(m, _)| m == ms) {
            assert_eq!(
                *f,
                isotrack_mavlink::wire::ground_round_trip(*w),
                "at {ms} ms"
            );
            flown_law += 1;
        }
    }
    assert!(flown_law > 0, "{:?} {:?}", r.events, report.events);
    assert_eq!(report.setpoints_refused, 0, "{:?}", report.events);
}

/// QGroundControl's and pymavlink's system id.
#[test]
fn a_ground_station_hands_over_to_fly() {
    gcs_workflow(255);
}

/// MAVSDK's default ground-station system id, 245: a ground station all the same.
#[test]
fn a_mavsdk_ground_station_hands_over_to_fly() {
    gcs_workflow(245);
}
