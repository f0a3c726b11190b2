//! `fly`'s one-second windows against `isotrack sitl` beating as PX4 does (`heartbeat_hz` 1:
//! a switch shows only in the next beat, up to a second after its acknowledgement), not only
//! against stand-ins: the take-over (an accepted arming or OFFBOARD never sent again before a
//! heartbeat shows it), the failsafe's HOLD (sent once, confirmed by the next beat), a pilot's
//! switch in control (`pilot_took_over`, nothing commanded), two vehicles (`two_vehicles`).

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions, FlyReport};
use isotrack_mavlink::link::Link;
use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions, SitlReport};
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

/// The frame of a datagram (sitl and fly send one a datagram), if it is one.
fn decode(d: &[u8]) -> Option<(mavlink::MavHeader, MavMessage)> {
    mavlink::MavlinkReader::new(d)
        .read_any_message::<MavMessage>()
        .ok()
}

/// A real-time sitl (the default rover scenario, 60 s) on `url`, beating at 1 Hz only
/// (`heartbeat_hz`) or not, system `id`.
fn sitl(
    url: &str,
    id: u8,
    one_hz: bool,
) -> (
    std::thread::JoinHandle<SitlReport>,
    SocketAddr,
    std::sync::Arc<std::sync::atomic::AtomicBool>,
) {
    let s = load_scenario(None, &["sim.duration_s=60".to_string()]).unwrap();
    let mut opts = SitlOptions::new(url);
    opts.pace = Pace::RealTime { speedup: 1.0 };
    opts.system_id = id;
    opts.heartbeat_hz = one_hz.then_some(1.0);
    let stop = opts.stop.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    let v = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).unwrap()
    });
    (v, rx.recv().unwrap(), stop)
}

/// sitl with `heartbeat_hz` answers an arming without a heartbeat after it (PX4 reports it in
/// its next beat); without, the heartbeat follows the acknowledgement at once.
#[test]
fn sitl_at_1hz_beats_on_its_clock_only() {
    for one_hz in [false, true] {
        let (v, addr, stop) = sitl("udpin:127.0.0.1:0", 1, one_hz);
        let u = UdpSocket::bind("127.0.0.1:0").unwrap();
        u.set_read_timeout(Some(Duration::from_millis(50))).unwrap();
        let arm = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: 1.0,
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        });
        let mut f = Vec::new();
        let header = mavlink::MavHeader {
            system_id: 1,
            component_id: 191,
            sequence: 0,
        };
        mavlink::write_v2_msg(&mut f, header, &arm).unwrap();
        u.send_to(&f, addr).unwrap();
        let mut after_ack = None;
        let mut acked = false;
        let mut buf = [0u8; 2048];
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(10) && after_ack.is_none() {
            let Ok((n, _)) = u.recv_from(&mut buf) else {
                continue;
            };
            match decode(&buf[..n]).map(|m| m.1) {
                Some(MavMessage::COMMAND_ACK(_)) => acked = true,
                // The first frame after the acknowledgement that is no telemetry.
                Some(MavMessage::HEARTBEAT(h)) if acked => after_ack = Some(Some(h)),
                Some(MavMessage::EXTENDED_SYS_STATE(_)) if acked => after_ack = Some(None),
                _ => {}
            }
        }
        stop.store(true, std::sync::atomic::Ordering::SeqCst);
        v.join().unwrap();
        assert!(acked, "{one_hz}");
        match after_ack {
            // Default: the heartbeat, armed, at once (before EXTENDED_SYS_STATE).
            Some(Some(h)) => {
                assert!(!one_hz);
                assert!(h
                    .base_mode
                    .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED));
            }
            other => assert!(one_hz, "{other:?}"),
        }
    }
}

/// What the relay between fly and sitl saw: per command fly sent (the arming, a mode by its
/// PX4 main mode), how many went after sitl had ACCEPTED one like it and before sitl's
/// heartbeat showed the result.
#[derive(Debug, Default)]
struct Relayed {
    arms: u32,
    offboards: u32,
    holds: u32,
    /// Commands sent again after an ACCEPTED one, before a heartbeat showed it.
    resent_after_accepted: Vec<String>,
}

/// fly (`--take-control --arm`, the default rover scenario, `max_duration_s`) against a 1 Hz
/// sitl through a relay; `pilot` runs once fly has control (its first law command's
/// setpoint), with sitl's address.
fn take_over(
    max_duration_s: f64,
    pilot: impl FnOnce(SocketAddr) + Send + 'static,
) -> (FlyReport, SitlReport, Relayed) {
    let (v, sitl_addr, stop) = sitl("udpin:127.0.0.1:0", 1, true);
    let relay = UdpSocket::bind("127.0.0.1:0").unwrap();
    relay
        .set_read_timeout(Some(Duration::from_millis(20)))
        .unwrap();
    let relay_addr = relay.local_addr().unwrap();
    let s = load_scenario(None, &[]).unwrap();
    let mut o = FlyOptions::new(&format!("udpout:{relay_addr}"));
    o.take_control = true;
    o.arm = true;
    o.timeout_s = 3.0;
    o.max_duration_s = Some(max_duration_s);
    let companion =
        std::thread::spawn(move || run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap());
    let mut seen = Relayed::default();
    // The command ACCEPTED and not yet shown by a heartbeat: (command, main mode).
    let mut accepted: Option<(MavCmd, u32)> = None;
    let mut pending: Option<(MavCmd, u32)> = None;
    let mut pilot = Some(pilot);
    let mut fly_addr = None;
    let mut buf = [0u8; 65_536];
    let t0 = Instant::now();
    while !companion.is_finished() && t0.elapsed() < Duration::from_secs(60) {
        let Ok((n, from)) = relay.recv_from(&mut buf) else {
            continue;
        };
        let frame = decode(&buf[..n]);
        if from == sitl_addr {
            match frame.as_ref().map(|f| &f.1) {
                Some(MavMessage::COMMAND_ACK(a)) if a.result == MavResult::MAV_RESULT_ACCEPTED => {
                    accepted = pending.filter(|p| p.0 == a.command);
                }
                Some(MavMessage::HEARTBEAT(_)) => accepted = None,
                _ => {}
            }
            if let Some(f) = fly_addr {
                relay.send_to(&buf[..n], f).unwrap();
            }
            continue;
        }
        fly_addr = Some(from);
        match frame.as_ref().map(|f| &f.1) {
            Some(MavMessage::COMMAND_LONG(c)) => {
                let main = c.param2 as u32;
                let what = (c.command, main);
                match c.command {
                    MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => seen.arms += 1,
                    MavCmd::MAV_CMD_DO_SET_MODE if main == 6 => seen.offboards += 1,
                    MavCmd::MAV_CMD_DO_SET_MODE => seen.holds += 1,
                    _ => {}
                }
                if accepted == Some(what) {
                    seen.resent_after_accepted.push(format!("{what:?}"));
                }
                pending = Some(what);
            }
            Some(MavMessage::SET_ATTITUDE_TARGET(a)) if a.time_boot_ms != u32::MAX => {
                if let Some(p) = pilot.take() {
                    std::thread::spawn(move || p(sitl_addr));
                }
            }
            _ => {}
        }
        relay.send_to(&buf[..n], sitl_addr).unwrap();
    }
    let r = companion.join().unwrap();
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
    (r, v.join().unwrap(), seen)
}

/// The take-over and the way out of a 1 Hz vehicle: fly arms sitl, switches it to OFFBOARD,
/// flies it to its `max_duration_s` and commands HOLD; no accepted arming, OFFBOARD or HOLD is
/// sent again before sitl's next heartbeat (up to a second later) shows it, and the HOLD is
/// confirmed by it.
#[test]
fn fly_takes_over_and_lets_go_of_a_1hz_sitl_without_resending_accepted_commands() {
    let (r, v, seen) = take_over(3.0, |_| {});
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(!r.commands.is_empty(), "{:?}", r.events);
    assert!(
        r.way_out_commanded && r.failsafe_acknowledged,
        "{:?}",
        r.events
    );
    assert!(
        seen.resent_after_accepted.is_empty(),
        "{seen:?} {:?}",
        r.events
    );
    assert!(
        seen.arms >= 1 && seen.offboards >= 1 && seen.holds >= 1,
        "{seen:?}"
    );
    assert!(
        v.events
            .iter()
            .any(|e| e.contains("mode OFFBOARD by system 1")),
        "{:?}",
        v.events
    );
    assert!(
        v.events.iter().any(|e| e.contains("mode HOLD by system 1")),
        "{:?}",
        v.events
    );
}

/// In control of a 1 Hz sitl, a pilot (a ground station, system 255) switches it to MANUAL:
/// fly learns it from the next heartbeat, ends `pilot_took_over` and commands nothing; the
/// pilot's mode stands.
#[test]
fn a_pilots_switch_on_a_1hz_sitl_ends_pilot_took_over() {
    let (r, v, seen) = take_over(20.0, |sitl_addr| {
        std::thread::sleep(Duration::from_millis(300));
        let mut gcs = Link::open(&format!("udpout:{sitl_addr}"), 255, 190).unwrap();
        let manual = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: 1.0,
            param2: 1.0,
            command: MavCmd::MAV_CMD_DO_SET_MODE,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        });
        gcs.send(&manual).unwrap();
        let _ = gcs.poll(Duration::from_millis(200));
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert_eq!(seen.holds, 0, "{seen:?}");
    let modes: Vec<&String> = v.events.iter().filter(|e| e.contains("mode ")).collect();
    assert!(
        modes
            .last()
            .is_some_and(|e| e.contains("mode MANUAL by system 255")),
        "{:?}",
        v.events
    );
}

/// Two 1 Hz sitls (systems 1 and 2) on one link to fly `--take-control`: the second's first
/// heartbeat comes within a second of the first's, inside fly's 2 s window: `two_vehicles`,
/// nothing commanded (neither armed).
#[test]
fn two_1hz_sitls_are_two_vehicles() {
    let fly_sock = UdpSocket::bind("127.0.0.1:0").unwrap();
    let fly_addr = fly_sock.local_addr().unwrap();
    drop(fly_sock);
    let s = load_scenario(None, &[]).unwrap();
    let mut o = FlyOptions::new(&format!("udpin:{fly_addr}"));
    o.take_control = true;
    o.arm = true;
    o.timeout_s = 3.0;
    let companion =
        std::thread::spawn(move || run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap());
    std::thread::sleep(Duration::from_millis(200));
    let (a, _, stop_a) = sitl(&format!("udpout:{fly_addr}"), 1, true);
    std::thread::sleep(Duration::from_millis(400));
    let (b, _, stop_b) = sitl(&format!("udpout:{fly_addr}"), 2, true);
    let r = companion.join().unwrap();
    stop_a.store(true, std::sync::atomic::Ordering::SeqCst);
    stop_b.store(true, std::sync::atomic::Ordering::SeqCst);
    let (a, b) = (a.join().unwrap(), b.join().unwrap());
    assert_eq!(r.end, FlyEnd::TwoVehicles, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    for v in [&a, &b] {
        assert!(
            !v.events.iter().any(|e| e.contains("armed by")),
            "{:?}",
            v.events
        );
    }
}
