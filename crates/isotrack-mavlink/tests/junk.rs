//! `sitl` under a flood of junk (issue 33, "hostile traffic"; docs/ROBUSTNESS.md item 8): while
//! a lockstep flight runs, another socket floods the vehicle's port with frames whose checksum
//! is wrong (setpoints that would turn it hard, arming and mode commands), truncated frames and
//! random bytes. The vehicle stays responsive (the flight completes), the junk is dropped and
//! counted (and logged at the end), and it moves nothing: the flight is the in-process mirror's,
//! bit for bit, as without the flood.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions};
use isotrack_mavlink::mirror::{mirror, Rounding, Transport};
use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions};
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use mavlink::MavHeader;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

/// A MAVLink 2 frame of `msg` from system 1, component 191 (the companion's ids).
fn frame(msg: &MavMessage) -> Vec<u8> {
    let mut buf = Vec::new();
    let header = MavHeader {
        system_id: 1,
        component_id: 191,
        sequence: 0,
    };
    mavlink::write_v2_msg(&mut buf, header, msg).unwrap();
    buf
}

/// The junk: frames that would move the vehicle, each with its checksum broken; the same
/// frames cut short; bytes that are no frame.
fn junk() -> Vec<Vec<u8>> {
    let turn = MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
        time_boot_ms: 0,
        q: [1.0, 0.0, 0.0, 0.0],
        body_yaw_rate: 5.0,
        target_system: 1,
        target_component: 1,
        type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
        ..Default::default()
    });
    let disarm = MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        param1: 0.0,
        param2: 21196.0,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    });
    let mut out = Vec::new();
    for m in [turn, disarm] {
        let f = frame(&m);
        for stamp in [1u32, 1000, u32::MAX - 1] {
            let mut bad = f.clone();
            // time_boot_ms / param1 bytes changed, the checksum left as it was.
            bad[10..14].copy_from_slice(&stamp.to_le_bytes());
            out.push(bad);
        }
        let mut crc = f.clone();
        let n = crc.len();
        crc[n - 1] ^= 0xff;
        out.push(crc);
        out.push(f[..f.len() / 2].to_vec());
        out.push(f[..3].to_vec());
    }
    out.push((0..255u8).collect());
    out.push(vec![0xfd; 300]);
    out
}

#[test]
fn a_flood_of_junk_neither_stalls_nor_moves_the_vehicle() {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig2b-circular.toml");
    let s = load_scenario(Some(&p), &["sim.duration_s=20".to_string()]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    opts.companion_timeout_s = 30.0;
    let (tx, rx) = mpsc::channel();
    let sv = s.clone();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&sv, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).expect("sitl")
    });
    let addr = rx.recv().unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let flood = {
        let done = done.clone();
        std::thread::spawn(move || {
            let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
            let junk = junk();
            let mut sent = 0u64;
            while !done.load(Ordering::SeqCst) {
                for j in &junk {
                    if sock.send_to(j, addr).is_ok() {
                        sent += 1;
                    }
                }
                std::thread::sleep(Duration::from_millis(2));
            }
            sent
        })
    };
    let mut c = FlyOptions::new(&format!("udpout:{addr}"));
    c.take_control = true;
    c.arm = true;
    c.timeout_s = 30.0;
    let f = run_fly(&s, &c, &mut NoTrace, &mut |_| Ok(())).expect("fly");
    done.store(true, Ordering::SeqCst);
    let sent = flood.join().unwrap();
    let v = vehicle.join().unwrap();
    // Responsive: the flight reached its end; unmoved: it is the mirror's, bit for bit.
    assert_eq!(f.end, FlyEnd::VehicleEnded, "{:?}", f.events);
    let m = mirror(&s, Rounding::Wire, &mut NoTrace);
    assert_eq!(f.commands, m.commands, "the law's commands");
    let t = Transport::of(&s);
    let flown: Vec<(u32, f64)> = m.commands.iter().map(|&(ms, w)| (ms, t.flown(w))).collect();
    assert_eq!(v.flown, flown, "the turn rates flown");
    assert_eq!(format!("{:?}", v.result), format!("{:?}", m.result));
    // Dropped and counted (the kernel may drop some of the flood before the vehicle reads it).
    assert!(sent > 0);
    assert!(
        v.link.junk_datagrams > 0 && v.link.junk_datagrams <= sent,
        "{} of {sent}",
        v.link.junk_datagrams
    );
    assert_eq!(v.setpoints_refused, 0, "{:?}", v.events);
    let logged = format!(
        "{} datagrams without a valid MAVLink 2 frame dropped",
        v.link.junk_datagrams
    );
    assert!(
        v.events.iter().any(|e| e.contains(&logged)),
        "{:?}",
        v.events
    );
}
