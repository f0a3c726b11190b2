//! `sitl --lockstep` with a ground station or SDK flying offboard itself (MAVSDK's workflow:
//! system 245, its own clock on its setpoints), driven by a raw peer: what advances the run
//! and what does not, out-of-order setpoints, and a flood of refused commands.

use isotrack_mavlink::link::Link;
use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions, SitlReport, MAX_EVENTS};
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use mavlink::MavHeader;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A lockstep vehicle (the default scenario: a Dubins robot, a sample every 10 ms) on a port of
/// its own, a raw peer (system `system`, component 190: a ground station's heartbeat, or a
/// companion's for the vehicle's own system 1) talking to it, and its stop flag.
fn vehicle(
    system: u8,
) -> (
    Link,
    JoinHandle<SitlReport>,
    Arc<AtomicBool>,
    std::net::SocketAddr,
) {
    let s = load_scenario(None, &["sim.duration_s=60".to_string()]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    opts.companion_timeout_s = 30.0;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let v = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).expect("sitl")
    });
    let addr = rx.recv().unwrap();
    let mut g = Link::open(&format!("udpout:{addr}"), system, 190).unwrap();
    let mut beat = heartbeat();
    if let (MavMessage::HEARTBEAT(h), 1) = (&mut beat, system) {
        h.mavtype = MavType::MAV_TYPE_ONBOARD_CONTROLLER;
    }
    g.send(&beat).unwrap();
    (g, v, stop, addr)
}

fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        mavlink_version: 3,
        ..Default::default()
    })
}

fn command(cmd: MavCmd, p: [f32; 3]) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p[0],
        param2: p[1],
        param3: p[2],
        command: cmd,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    })
}

/// A yaw-rate setpoint stamped `ms`.
fn setpoint(ms: u32, yaw_rate: f32) -> MavMessage {
    MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
        time_boot_ms: ms,
        q: [1.0, 0.0, 0.0, 0.0],
        body_yaw_rate: yaw_rate,
        target_system: 1,
        target_component: 1,
        type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
        ..Default::default()
    })
}

/// What the peer hears for `wall`: the newest sample time (`ISO_S`) and the
/// acknowledgements' results.
fn listen(g: &mut Link, wall: Duration, newest: &mut Option<u32>, acks: &mut Vec<MavResult>) {
    let t0 = Instant::now();
    while t0.elapsed() < wall {
        for r in g.poll(Duration::from_millis(20)).unwrap() {
            match &r.msg {
                MavMessage::NAMED_VALUE_FLOAT(n) => {
                    *newest = Some(newest.map_or(n.time_boot_ms, |m| m.max(n.time_boot_ms)))
                }
                MavMessage::COMMAND_ACK(a) => acks.push(a.result),
                _ => {}
            }
        }
    }
}

/// Arms the vehicle and switches it to OFFBOARD as a ground station; both accepted. A setpoint
/// that answers no sample (stamped `u32::MAX`) goes first: as PX4, the vehicle refuses
/// OFFBOARD before setpoints stream.
fn arm_offboard(g: &mut Link, newest: &mut Option<u32>) {
    for (cmd, p) in [
        (MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, [1.0, f32::NAN, 0.0]),
        (MavCmd::MAV_CMD_DO_SET_MODE, [1.0, 6.0, 0.0]),
    ] {
        if cmd == MavCmd::MAV_CMD_DO_SET_MODE {
            g.send(&setpoint(u32::MAX, 0.0)).unwrap();
        }
        g.send(&command(cmd, p)).unwrap();
        let mut acks = Vec::new();
        let t0 = Instant::now();
        while acks.is_empty() && t0.elapsed() < Duration::from_secs(10) {
            listen(g, Duration::from_millis(50), newest, &mut acks);
        }
        assert_eq!(acks, [MavResult::MAV_RESULT_ACCEPTED], "{cmd:?}");
    }
}

/// A ground station's neutral traffic (heartbeats, requests for telemetry, parameters and
/// messages, a setpoint that sets nothing, arming and the mode switch) never advances a
/// lockstep run: the vehicle keeps offering its first sample. Its setpoints, stamped with its
/// own clock (as MAVSDK's Offboard plugin stamps them), advance it one sample each; a repeat
/// of the same stamp does not.
#[test]
fn only_a_new_setpoint_advances_a_lockstep_run() {
    let (mut g, v, stop, _) = vehicle(245);
    let mut newest = None;
    let mut acks = Vec::new();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_millis(1500) {
        g.send(&heartbeat()).unwrap();
        // Deprecated, still sent by ground stations for ArduPilot.
        #[allow(deprecated)]
        let streams = MavMessage::REQUEST_DATA_STREAM(REQUEST_DATA_STREAM_DATA {
            req_message_rate: 10,
            target_system: 1,
            target_component: 1,
            req_stream_id: MavDataStream::MAV_DATA_STREAM_ALL,
            start_stop: 1,
        });
        g.send(&streams).unwrap();
        g.send(&command(
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
            [33.0, 1e5, 0.0],
        ))
        .unwrap();
        g.send(&command(MavCmd::MAV_CMD_REQUEST_MESSAGE, [148.0, 0.0, 0.0]))
            .unwrap();
        g.send(&MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
        }))
        .unwrap();
        // Attitude and yaw rate both ignored: a setpoint that sets nothing.
        let mut nothing = setpoint(999_999, 0.0);
        if let MavMessage::SET_ATTITUDE_TARGET(d) = &mut nothing {
            d.type_mask |= AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE;
        }
        g.send(&nothing).unwrap();
        listen(&mut g, Duration::from_millis(50), &mut newest, &mut acks);
    }
    assert_eq!(newest, Some(0), "neutral traffic advanced the run");
    assert!(
        !acks.is_empty(),
        "the requests were read (and acknowledged)"
    );
    arm_offboard(&mut g, &mut newest);
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(newest, Some(0), "arming and OFFBOARD advanced the run");
    // MAVSDK's own clock: 777 s since it started.
    g.send(&setpoint(777_000, 0.2)).unwrap();
    listen(&mut g, Duration::from_millis(500), &mut newest, &mut acks);
    assert_eq!(newest, Some(10), "one setpoint, one sample");
    g.send(&setpoint(777_000, 0.2)).unwrap();
    listen(&mut g, Duration::from_millis(500), &mut newest, &mut acks);
    assert_eq!(newest, Some(10), "a repeat advanced the run");
    g.send(&setpoint(777_050, 0.2)).unwrap();
    listen(&mut g, Duration::from_millis(500), &mut newest, &mut acks);
    assert_eq!(newest, Some(20));
    stop.store(true, Ordering::SeqCst);
    let r = v.join().unwrap();
    // The turn rate flown is the setpoint's: -(yaw rate), through f32.
    let w = -(0.2f32 as f64);
    assert_eq!(r.flown, vec![(0, w), (10, w)], "{:?}", r.events);
    assert_eq!(r.setpoints_out_of_order, 0);
}

/// Simulated time stands still while nobody flies the vehicle by setpoints: a companion's
/// answers (stamped with the sample's time, or newer) to a disarmed vehicle, to an armed one in
/// MANUAL, or in HOLD, advance nothing; armed in OFFBOARD, one new setpoint advances one
/// sample (10 ms). Only that sample is flown: the disarmed vehicle did not move on.
#[test]
fn a_lockstep_run_stands_still_until_the_vehicle_follows_setpoints() {
    let (mut g, v, stop, _) = vehicle(245);
    let mut newest = None;
    let mut acks = Vec::new();
    listen(&mut g, Duration::from_millis(200), &mut newest, &mut acks);
    assert_eq!(newest, Some(0));
    // Disarmed: the sample's own stamp, then newer ones.
    for ms in [0, 1_000, 2_000] {
        g.send(&setpoint(ms, 0.1)).unwrap();
        listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    }
    assert_eq!(
        newest,
        Some(0),
        "answers to a disarmed vehicle advanced the run"
    );
    fn ack(g: &mut Link, cmd: MavCmd, p: [f32; 3], newest: &mut Option<u32>) {
        g.send(&command(cmd, p)).unwrap();
        let mut acks = Vec::new();
        let t0 = Instant::now();
        while acks.is_empty() && t0.elapsed() < Duration::from_secs(10) {
            listen(g, Duration::from_millis(50), newest, &mut acks);
        }
        assert_eq!(acks, [MavResult::MAV_RESULT_ACCEPTED], "{cmd:?}");
    }
    ack(
        &mut g,
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [1.0, 0.0, 0.0],
        &mut newest,
    );
    g.send(&setpoint(3_000, 0.1)).unwrap();
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(newest, Some(0), "an answer in MANUAL advanced the run");
    ack(
        &mut g,
        MavCmd::MAV_CMD_DO_SET_MODE,
        [1.0, 6.0, 0.0],
        &mut newest,
    );
    g.send(&setpoint(4_000, 0.2)).unwrap();
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(
        newest,
        Some(10),
        "armed in OFFBOARD: one setpoint, one sample"
    );
    // HOLD (PX4's AUTO, LOITER): the setpoints no longer fly it.
    ack(
        &mut g,
        MavCmd::MAV_CMD_DO_SET_MODE,
        [1.0, 4.0, 3.0],
        &mut newest,
    );
    g.send(&setpoint(5_000, 0.2)).unwrap();
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(newest, Some(10), "an answer in HOLD advanced the run");
    stop.store(true, Ordering::SeqCst);
    let r = v.join().unwrap();
    assert_eq!(r.flown, vec![(0, -(0.2f32 as f64))], "{:?}", r.events);
    assert!(!r.companion_lost);
}

/// Setpoints stamped older than the last one applied from their sender (UDP delivered them
/// late) move nothing and are counted; one stamped a minute back is the sender's clock
/// restarting: applied, and logged.
#[test]
fn an_older_setpoint_is_ignored_and_counted() {
    let (mut g, v, stop, addr) = vehicle(245);
    let mut newest = None;
    let mut acks = Vec::new();
    listen(&mut g, Duration::from_millis(200), &mut newest, &mut acks);
    arm_offboard(&mut g, &mut newest);
    g.send(&setpoint(50_000, 0.1)).unwrap();
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(newest, Some(10));
    // A newer setpoint and, in the same datagram, a late one (stamped between the two): the
    // late one is read last, and ignored.
    let raw = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let mut datagram = Vec::new();
    for (seq, m) in [(1u8, setpoint(60_000, 0.2)), (2, setpoint(55_000, 0.3))] {
        let h = MavHeader {
            system_id: 245,
            component_id: 190,
            sequence: seq,
        };
        mavlink::write_v2_msg(&mut datagram, h, &m).unwrap();
    }
    raw.send_to(&datagram, addr).unwrap();
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(newest, Some(20));
    // A minute back: a restarted clock.
    g.send(&setpoint(1_000, 0.4)).unwrap();
    listen(&mut g, Duration::from_millis(300), &mut newest, &mut acks);
    assert_eq!(newest, Some(30));
    stop.store(true, Ordering::SeqCst);
    let r = v.join().unwrap();
    let w = |y: f32| -(y as f64);
    assert_eq!(
        r.flown,
        vec![(0, w(0.1)), (10, w(0.2)), (20, w(0.4))],
        "{:?}",
        r.events
    );
    assert_eq!(r.setpoints_out_of_order, 1, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("went back from 60000 to 1000 ms: taken as restarted")),
        "{:?}",
        r.events
    );
}

/// A stranger's flood of commands, each refused (and acknowledged DENIED), does not grow the
/// vehicle's log past [`MAX_EVENTS`]: the rest are counted.
#[test]
fn a_flood_of_refused_commands_keeps_the_log_bounded() {
    let (mut owner, v, stop, addr) = vehicle(1);
    let mut newest = None;
    let mut acks = Vec::new();
    listen(
        &mut owner,
        Duration::from_millis(200),
        &mut newest,
        &mut acks,
    );
    // The companion (system 1, component 190) arms it: it owns it.
    owner
        .send(&command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0],
        ))
        .unwrap();
    listen(
        &mut owner,
        Duration::from_millis(300),
        &mut newest,
        &mut acks,
    );
    assert_eq!(acks, [MavResult::MAV_RESULT_ACCEPTED]);
    let mut stranger = Link::open(&format!("udpout:{addr}"), 7, 1).unwrap();
    let mut denied = 0;
    for _ in 0..15 {
        for _ in 0..100 {
            stranger
                .send(&command(MavCmd::MAV_CMD_DO_SET_MODE, [1.0, 4.0, 3.0]))
                .unwrap();
        }
        let mut got = Vec::new();
        let t0 = Instant::now();
        while got.len() < 100 && t0.elapsed() < Duration::from_secs(3) {
            listen(
                &mut stranger,
                Duration::from_millis(20),
                &mut None,
                &mut got,
            );
        }
        denied += got
            .iter()
            .filter(|a| **a == MavResult::MAV_RESULT_DENIED)
            .count();
    }
    stop.store(true, Ordering::SeqCst);
    let r = v.join().unwrap();
    assert!(
        denied > MAX_EVENTS,
        "only {denied} refusals came back: {:?}",
        &r.events[..r.events.len().min(5)]
    );
    assert!(
        r.events.len() <= MAX_EVENTS + 3,
        "{} events",
        r.events.len()
    );
    let more = r
        .events
        .iter()
        .find(|e| e.contains("more events not logged"))
        .unwrap_or_else(|| panic!("{:?}", &r.events[r.events.len() - 3..]));
    let n: usize = more.split(' ').next().unwrap().parse().unwrap();
    // Each refusal is one event: logged or counted.
    assert!(n + MAX_EVENTS >= denied, "{more}, {denied} refusals");
}

/// A lon/lat field (the ERA5 NetCDF: a 0.25 deg grid from 10 W, 50 N, 33 rows) is its own
/// georeference: the first `GLOBAL_POSITION_INT` is the field file's coordinate of the start
/// (305253 m east, 750566 m north of the south-west node), computed here from the grid the
/// data's README gives (equirectangular about the grid's middle latitude, 54 N, mean Earth
/// radius), and `HOME_POSITION` is the south-west node. `sitl.home_*` at that node agrees; at
/// PX4's default home it is refused.
#[test]
fn a_lonlat_field_places_the_vehicle_at_its_own_coordinates() {
    use isotrack_mavlink::geo::Frame;
    use isotrack_mavlink::sitl::run_sitl;
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/era5-isotherm-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let sv = s.clone();
    let v = std::thread::spawn(move || {
        run_sitl(&sv, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).expect("sitl")
    });
    let addr = rx.recv().unwrap();
    let mut g = Link::open(&format!("udpout:{addr}"), 245, 190).unwrap();
    g.send(&heartbeat()).unwrap();
    let (mut position, mut home) = (None, None);
    let t0 = Instant::now();
    while (position.is_none() || home.is_none()) && t0.elapsed() < Duration::from_secs(20) {
        for r in g.poll(Duration::from_millis(50)).unwrap() {
            match r.msg {
                MavMessage::GLOBAL_POSITION_INT(p) if p.time_boot_ms == 0 => {
                    position.get_or_insert((p.lat, p.lon));
                }
                MavMessage::HOME_POSITION(h) => {
                    home.get_or_insert((h.latitude, h.longitude));
                }
                _ => {}
            }
        }
    }
    stop.store(true, Ordering::SeqCst);
    v.join().unwrap();
    let k = 6_371_008.8 * std::f64::consts::PI / 180.0;
    let ref_lat = 50.0 + 0.5 * 0.25 * 32.0;
    let lat = 50.0 + 750_566.0 / k;
    let lon = -10.0 + 305_253.0 / (k * f64::to_radians(ref_lat).cos());
    let e7 = |d: f64| (d * 1e7).round() as i32;
    assert_eq!(position, Some((e7(lat), e7(lon))), "{lat} N, {lon} E");
    assert_eq!(home, Some((500_000_000, -100_000_000)));
    // sitl.home_* at the field's origin agree with it; elsewhere they are refused.
    let agree = load_scenario(
        Some(&p),
        &[
            "sitl.home_lat_deg=50".to_string(),
            "sitl.home_lon_deg=-10".to_string(),
        ],
    )
    .unwrap();
    assert_eq!(Frame::of(&agree).unwrap(), Frame::of(&s).unwrap());
    let px4 = load_scenario(Some(&p), &["sitl.home_lon_deg=8.545594".to_string()]).unwrap();
    let e = Frame::of(&px4).unwrap_err();
    assert!(
        e.contains("sitl.home_lon_deg = 8.545594") && e.contains("longitude -10 deg"),
        "{e}"
    );
}
