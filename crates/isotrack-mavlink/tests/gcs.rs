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

mod support;
use support::ack_of;

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
    // As PX4, the vehicle refuses OFFBOARD (temporarily) until the companion's setpoints
    // stream: the pilot tries again.
    let t0 = Instant::now();
    let mut offboard = ack_of(&mut gcs, MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0);
    while offboard == Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED)
        && t0.elapsed() < Duration::from_secs(10)
    {
        std::thread::sleep(Duration::from_millis(200));
        offboard = ack_of(&mut gcs, MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0);
    }
    assert_eq!(offboard, ok);
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

/// A raw peer's frame: `msg` from `system`, `component`.
fn frame_of(system: u8, component: u8, msg: &MavMessage) -> Vec<u8> {
    let mut f = Vec::new();
    let header = mavlink::MavHeader {
        system_id: system.into(),
        component_id: component,
        sequence: 0,
    };
    mavlink::write_v2_msg(&mut f, header, msg).unwrap();
    f
}

/// What a ground station reads of `sitl` (read here from the raw datagrams, not through
/// isotrack's own link): each `COMMAND_ACK` is addressed to the command's sender, system and
/// component, in MAVLink 2's extension fields (payload bytes 8 and 9: after `command` u16,
/// `result`, `progress`, `result_param2` i32), with a checksum the `mavlink` crate accepts;
/// `SYS_STATUS` reports the sensors and the pre-arm check present, enabled and healthy (what
/// MAVSDK's health and `is_armable` read); `EXTENDED_SYS_STATE` says a disarmed fixed wing is
/// on the ground and an armed one in the air (MAVSDK's `in_air`).
#[test]
fn sitl_addresses_its_acks_and_reports_health_and_landed_state() {
    use std::net::UdpSocket;
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:17100");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    let addr = rx.recv().unwrap();
    let gcs = UdpSocket::bind("127.0.0.1:17101").unwrap();
    let companion = UdpSocket::bind("127.0.0.1:17102").unwrap();
    for u in [&gcs, &companion] {
        u.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
    }
    let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        mavlink_version: 3,
        ..Default::default()
    });
    gcs.send_to(&frame_of(245, 190, &beat), addr).unwrap();
    let arm = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: 1.0,
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    });
    // Every frame `u` receives for `wall`, raw and decoded.
    let hear = |u: &UdpSocket, wall: Duration| {
        let mut got = Vec::new();
        let t0 = Instant::now();
        let mut buf = [0u8; 2048];
        while t0.elapsed() < wall {
            if let Ok((n, _)) = u.recv_from(&mut buf) {
                let raw = buf[..n].to_vec();
                if let Ok((_, m)) =
                    mavlink::MavlinkReader::new(&raw[..]).read_any_message::<MavMessage>()
                {
                    got.push((raw, m));
                }
            }
        }
        got
    };
    // Before arming: the health, and on the ground.
    let before = hear(&gcs, Duration::from_millis(1500));
    let status = before.iter().find_map(|(_, m)| match m {
        MavMessage::SYS_STATUS(d) => Some(d.clone()),
        _ => None,
    });
    let status = status.expect("a SYS_STATUS");
    let want = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_MAG
        | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS
        | MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK;
    for bits in [
        status.onboard_control_sensors_present,
        status.onboard_control_sensors_enabled,
        status.onboard_control_sensors_health,
    ] {
        assert!(bits.contains(want), "{status:?}");
    }
    let landed = |got: &[(Vec<u8>, MavMessage)]| {
        got.iter()
            .filter_map(|(_, m)| match m {
                MavMessage::EXTENDED_SYS_STATE(d) => Some(d.landed_state),
                _ => None,
            })
            .collect::<Vec<_>>()
    };
    let on_ground = landed(&before);
    assert!(
        !on_ground.is_empty()
            && on_ground
                .iter()
                .all(|l| *l == MavLandedState::MAV_LANDED_STATE_ON_GROUND),
        "{on_ground:?}"
    );
    // The ground station arms it; then the companion asks again: each ACK is its own.
    let ack_to = |u: &UdpSocket, system: u8, component: u8| {
        u.send_to(&frame_of(system, component, &arm), addr).unwrap();
        let got = hear(u, Duration::from_millis(1500));
        let ack = got
            .iter()
            .find(|(_, m)| matches!(m, MavMessage::COMMAND_ACK(_)))
            .map(|(raw, _)| raw.clone())
            .expect("a COMMAND_ACK");
        (ack, landed(&got))
    };
    let (ack, in_air) = ack_to(&gcs, 245, 190);
    assert_eq!(ack[1], 10, "payload length: {ack:?}");
    assert_eq!(&ack[10..20], &[0x90, 0x01, 0, 0, 0, 0, 0, 0, 245, 190]);
    assert!(
        in_air.contains(&MavLandedState::MAV_LANDED_STATE_IN_AIR),
        "{in_air:?}"
    );
    let (ack, _) = ack_to(&companion, 1, 191);
    assert_eq!(&ack[10..20], &[0x90, 0x01, 0, 0, 0, 0, 0, 0, 1, 191]);
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    vehicle.join().unwrap();
}
