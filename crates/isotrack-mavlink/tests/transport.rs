//! The links other than UDP (issue 33: "URL"): `fly` and `sitl` in lockstep over TCP, each way
//! round (`sitl` on `tcpin:` with `fly` on `tcpout:`, and `fly` on `tcpin:` with `sitl` on
//! `tcpout:`), and over serial ports (two pseudo-terminal pairs joined by a relay, as a
//! telemetry radio would): each flight reproduces the in-process mirror bit for bit, as the UDP
//! flights of `lockstep.rs` do. And the peers of a `udpin:` link: bounded, silent ones dropped.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions, FlyReport};
use isotrack_mavlink::link::{Link, HANDSHAKE_TIMEOUT, MAX_PEERS};
use isotrack_mavlink::mirror::{mirror, Rounding, Transport};
use isotrack_mavlink::sitl::{run_sitl, run_sitl_on, Pace, SitlOptions, SitlReport};
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::io::{Read, Write};
use std::os::fd::FromRawFd;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc;
use std::time::{Duration, Instant};

fn scenario() -> Scenario {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig2b-circular.toml");
    load_scenario(Some(&p), &["sim.duration_s=30".to_string()]).expect("scenario")
}

/// The flight's commands and run are the mirror's (the wire's rounding), bit for bit.
fn assert_reproduces(s: &Scenario, v: &SitlReport, f: &FlyReport) {
    let m = mirror(s, Rounding::Wire, &mut NoTrace);
    assert_eq!(f.end, FlyEnd::VehicleEnded, "{:?}", f.events);
    assert!(!m.commands.is_empty());
    assert_eq!(f.commands, m.commands, "the law's commands");
    let t = Transport::of(s);
    let flown: Vec<(u32, f64)> = m.commands.iter().map(|&(ms, w)| (ms, t.flown(w))).collect();
    assert_eq!(v.flown, flown, "the turn rates flown");
    assert_eq!(format!("{:?}", v.result), format!("{:?}", m.result));
    assert_eq!(v.setpoints_refused, 0, "{:?}", v.events);
}

fn lockstep(url: &str) -> SitlOptions {
    let mut o = SitlOptions::new(url);
    o.pace = Pace::Lockstep;
    o.companion_timeout_s = 30.0;
    o
}

fn companion(url: &str) -> FlyOptions {
    let mut o = FlyOptions::new(url);
    o.take_control = true;
    o.arm = true;
    o.timeout_s = 30.0;
    o
}

/// `sitl --mavlink tcpin:127.0.0.1:0 --lockstep` and `fly --mavlink tcpout:...`.
#[test]
fn lockstep_over_tcp_sitl_listening_reproduces_the_mirror() {
    let s = scenario();
    let opts = lockstep("tcpin:127.0.0.1:0");
    let stop = opts.stop.clone();
    let (tx, rx) = mpsc::channel();
    let sv = s.clone();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&sv, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).expect("sitl")
    });
    let addr = rx.recv().unwrap();
    let f = run_fly(
        &s,
        &companion(&format!("tcpout:{addr}")),
        &mut NoTrace,
        &mut |_| Ok(()),
    )
    .expect("fly");
    stop.store(true, Ordering::SeqCst);
    let v = vehicle.join().unwrap();
    assert_reproduces(&s, &v, &f);
}

/// `fly --mavlink tcpin:...` listening, `sitl --mavlink tcpout:...` connecting to it (tried
/// until the companion listens).
#[test]
fn lockstep_over_tcp_fly_listening_reproduces_the_mirror() {
    let s = scenario();
    let (tx, rx) = mpsc::channel();
    let sf = s.clone();
    // The companion listens on a port of its own and says which.
    let companion_thread = std::thread::spawn(move || {
        run_fly(
            &sf,
            &companion("tcpin:127.0.0.1:0"),
            &mut NoTrace,
            &mut |l| {
                tx.send(l.local_addr()?).unwrap();
                Ok(())
            },
        )
        .expect("fly")
    });
    let addr = rx.recv().unwrap();
    let opts = lockstep(&format!("tcpout:{addr}"));
    let v = run_sitl(&s, &opts, &mut NoTrace, &mut |_| {}).expect("sitl");
    let f = companion_thread.join().unwrap();
    assert_reproduces(&s, &v, &f);
}

/// A pseudo-terminal pair: the master's descriptor (as a blocking file) and the slave's path.
fn pty() -> (std::fs::File, String) {
    // SAFETY: plain libc calls on a descriptor this function owns; ptsname_r writes at most
    // `buf.len()` bytes.
    unsafe {
        let m = libc::posix_openpt(libc::O_RDWR | libc::O_NOCTTY);
        assert!(m >= 0, "posix_openpt: {}", std::io::Error::last_os_error());
        assert_eq!(libc::grantpt(m), 0);
        assert_eq!(libc::unlockpt(m), 0);
        let mut buf = [0 as libc::c_char; 128];
        assert_eq!(libc::ptsname_r(m, buf.as_mut_ptr(), buf.len()), 0);
        let name = std::ffi::CStr::from_ptr(buf.as_ptr())
            .to_string_lossy()
            .into_owned();
        (std::fs::File::from_raw_fd(m), name)
    }
}

/// Copies bytes from `from` to `to` until either end closes (a radio link's two modems).
fn relay(mut from: std::fs::File, mut to: std::fs::File) {
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = from.read(&mut buf) {
            if n == 0 || to.write_all(&buf[..n]).is_err() {
                break;
            }
        }
    });
}

/// `sitl --mavlink serial:/dev/pts/A:57600` and `fly --mavlink serial:/dev/pts/B:57600`, the
/// two masters joined by a relay: a lockstep flight over serial ports reproduces the mirror.
#[test]
fn lockstep_over_serial_ports_reproduces_the_mirror() {
    let s = scenario();
    let (ma, a) = pty();
    let (mb, b) = pty();
    let opts = lockstep(&format!("serial:{a}:57600"));
    let stop = opts.stop.clone();
    let (tx, rx) = mpsc::channel();
    let sv = s.clone();
    let vehicle = std::thread::spawn(move || {
        run_sitl_on(&sv, &opts, &mut NoTrace, &mut |l| {
            tx.send(l.describe()).unwrap()
        })
        .expect("sitl")
    });
    // The vehicle's port is open (raw mode) before the companion writes anything.
    assert_eq!(rx.recv().unwrap(), format!("{a} at 57600 baud"));
    // The relays start once both ports are open (in raw mode: no echo, no line editing).
    let mut masters = Some((ma, mb));
    let f = run_fly(
        &s,
        &companion(&format!("serial:{b}:57600")),
        &mut NoTrace,
        &mut |_| {
            if let Some((ma, mb)) = masters.take() {
                relay(ma.try_clone()?, mb.try_clone()?);
                relay(mb, ma);
            }
            Ok(())
        },
    )
    .expect("fly");
    stop.store(true, Ordering::SeqCst);
    let v = vehicle.join().unwrap();
    assert_reproduces(&s, &v, &f);
}

fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        mavlink_version: 3,
        ..Default::default()
    })
}

/// Reads until `link` has nothing more for `quiet`; how many frames came.
/// A setpoint that answers the sample stamped `time_boot_ms` without steering (attitude ignored).
fn neutral_setpoint(time_boot_ms: u32) -> MavMessage {
    MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
        time_boot_ms,
        q: [1.0, 0.0, 0.0, 0.0],
        target_system: 1,
        target_component: 1,
        type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
        ..Default::default()
    })
}

/// For `wall` of wall time, the companion `c` beats and answers every sample it receives with
/// [`neutral_setpoint`].
fn answer_every_sample(c: &mut Link, wall: Duration) {
    let t0 = Instant::now();
    while t0.elapsed() < wall {
        c.send(&heartbeat()).unwrap();
        for r in c.poll(Duration::from_millis(20)).unwrap() {
            if let MavMessage::NAMED_VALUE_FLOAT(n) = &r.msg {
                c.send(&neutral_setpoint(n.time_boot_ms)).unwrap();
            }
        }
    }
}

fn frames_within(link: &mut Link, quiet: Duration) -> usize {
    let mut n = 0;
    loop {
        let got = link.poll(quiet).unwrap().len();
        if got == 0 {
            return n;
        }
        n += got;
    }
}

/// A flood of valid frames from 200 source addresses (what spoofing gives) neither grows the
/// set of peers past [`MAX_PEERS`] nor pushes out the peer that is talking: it still gets what
/// the link sends; the others are refused (counted).
#[test]
fn a_flood_of_addresses_neither_grows_the_peers_nor_pushes_out_a_live_one() {
    let mut vehicle = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = vehicle.local_addr().unwrap();
    let mut gcs = Link::open(&format!("udpout:{addr}"), 245, 190).unwrap();
    gcs.send(&heartbeat()).unwrap();
    assert_eq!(frames_within(&mut vehicle, Duration::from_millis(200)), 1);
    assert_eq!(vehicle.peer_count(), 1);
    let mut flood: Vec<Link> = (0..200)
        .map(|k| Link::open(&format!("udpout:{addr}"), 100, k as u8).unwrap())
        .collect();
    for f in &mut flood {
        f.send(&heartbeat()).unwrap();
    }
    assert_eq!(frames_within(&mut vehicle, Duration::from_millis(300)), 200);
    assert_eq!(vehicle.peer_count(), MAX_PEERS);
    assert_eq!(vehicle.stats.peers_refused, 200 - (MAX_PEERS as u64 - 1));
    // The live peer still hears the vehicle.
    vehicle.send(&heartbeat()).unwrap();
    assert_eq!(frames_within(&mut gcs, Duration::from_millis(300)), 1);
}

/// A peer silent for the peer timeout is dropped: the link stops writing to it, and its
/// place is free for another; a peer that keeps talking stays.
#[test]
fn a_silent_peer_is_dropped_after_the_timeout() {
    let mut vehicle = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    vehicle.set_peer_timeout(Duration::from_millis(300));
    let addr = vehicle.local_addr().unwrap();
    let mut talker = Link::open(&format!("udpout:{addr}"), 245, 190).unwrap();
    let mut silent = Link::open(&format!("udpout:{addr}"), 246, 190).unwrap();
    talker.send(&heartbeat()).unwrap();
    silent.send(&heartbeat()).unwrap();
    assert_eq!(frames_within(&mut vehicle, Duration::from_millis(100)), 2);
    assert_eq!(vehicle.peer_count(), 2);
    // The talker beats every 50 ms for 1 s; the other says nothing.
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(1) {
        talker.send(&heartbeat()).unwrap();
        vehicle.poll(Duration::from_millis(50)).unwrap();
    }
    assert_eq!(vehicle.peer_count(), 1);
    assert_eq!(vehicle.stats.peers_evicted, 1);
    vehicle.send(&heartbeat()).unwrap();
    assert_eq!(frames_within(&mut talker, Duration::from_millis(300)), 1);
    assert_eq!(frames_within(&mut silent, Duration::from_millis(300)), 0);
}

/// `sitl` sets its link's peer timeout to `--timeout-s`: a ground station that fell silent is
/// dropped while the run goes on (it hears nothing more), a companion that keeps answering
/// stays. The companion arms the vehicle and switches it to OFFBOARD first: a lockstep run
/// advances only while the vehicle follows setpoints (before, its answers to the disarmed
/// vehicle flew it).
#[test]
fn sitl_drops_a_silent_ground_station() {
    let s = load_scenario(None, &["sim.duration_s=600".to_string()]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    opts.companion_timeout_s = 0.5;
    let stop = opts.stop.clone();
    let (tx, rx) = mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).expect("sitl")
    });
    let addr = rx.recv().unwrap();
    let mut gcs = Link::open(&format!("udpout:{addr}"), 245, 190).unwrap();
    gcs.send(&heartbeat()).unwrap();
    let mut c = Link::open(&format!("udpout:{addr}"), 1, 191).unwrap();
    c.send(&heartbeat()).unwrap();
    for (cmd, p2) in [
        (MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 0.0),
        (MavCmd::MAV_CMD_DO_SET_MODE, 6.0),
    ] {
        if cmd == MavCmd::MAV_CMD_DO_SET_MODE {
            // Setpoints before OFFBOARD, as PX4 needs them (this one answers no sample).
            c.send(&neutral_setpoint(u32::MAX)).unwrap();
        }
        c.send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: 1.0,
            param2: p2,
            command: cmd,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        }))
        .unwrap();
        let t0 = Instant::now();
        let mut ack = None;
        while ack.is_none() && t0.elapsed() < Duration::from_secs(10) {
            for r in c.poll(Duration::from_millis(20)).unwrap() {
                if let MavMessage::COMMAND_ACK(a) = &r.msg {
                    ack = (a.command == cmd).then_some(a.result);
                }
            }
        }
        assert_eq!(ack, Some(MavResult::MAV_RESULT_ACCEPTED), "{cmd:?}");
    }
    // The first sample (t = 0) may have come with the acknowledgements: answered now.
    c.send(&neutral_setpoint(0)).unwrap();
    // The companion beats and answers every sample for 2 s of wall time.
    answer_every_sample(&mut c, Duration::from_secs(2));
    // The ground station, silent for 2 s (4 timeouts), was dropped: nothing more reaches it.
    frames_within(&mut gcs, Duration::from_millis(50));
    answer_every_sample(&mut c, Duration::from_millis(500));
    let late = frames_within(&mut gcs, Duration::from_millis(100));
    stop.store(true, Ordering::SeqCst);
    let v = vehicle.join().unwrap();
    assert_eq!(late, 0, "the silent ground station still hears the vehicle");
    assert!(v.link.peers_evicted >= 1, "{:?}", v.link);
    assert!(
        v.flown.len() > 10,
        "the companion flew on: {}",
        v.flown.len()
    );
}

/// Twelve idle TCP connections (never a frame: a port scanner, a client of another protocol,
/// sockets held open on purpose) do not lock a MAVLink client out of a `tcpin:` link: the
/// client that connects after them takes the place of the oldest one never heard, is heard,
/// and hears the vehicle; and every idle connection is closed once [`HANDSHAKE_TIMEOUT`] has
/// passed without a frame. (Before: the idle ones held all [`MAX_PEERS`] places for the peer
/// timeout, and the client was turned away.)
#[test]
fn idle_tcp_connections_never_lock_a_client_out() {
    let mut vehicle = Link::open("tcpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = vehicle.local_addr().unwrap();
    let mut idle: Vec<std::net::TcpStream> = (0..12)
        .map(|_| std::net::TcpStream::connect(addr).unwrap())
        .collect();
    for _ in 0..5 {
        vehicle.poll(Duration::from_millis(20)).unwrap();
    }
    assert_eq!(vehicle.peer_count(), MAX_PEERS);
    let mut gcs = Link::open(&format!("tcpout:{addr}"), 245, 190).unwrap();
    gcs.send(&heartbeat()).unwrap();
    let mut heard = 0;
    let t0 = Instant::now();
    while heard == 0 && t0.elapsed() < Duration::from_secs(2) {
        heard += vehicle.poll(Duration::from_millis(20)).unwrap().len();
    }
    assert_eq!(heard, 1, "the client's heartbeat reached the vehicle");
    vehicle.send(&heartbeat()).unwrap();
    assert_eq!(frames_within(&mut gcs, Duration::from_millis(300)), 1);
    // Past the handshake time, the idle connections are closed; the client stays.
    let t0 = Instant::now();
    while t0.elapsed() < HANDSHAKE_TIMEOUT + Duration::from_millis(300) {
        gcs.send(&heartbeat()).unwrap();
        vehicle.poll(Duration::from_millis(50)).unwrap();
        frames_within(&mut gcs, Duration::from_millis(1));
    }
    assert_eq!(vehicle.peer_count(), 1);
    for s in &mut idle {
        s.set_read_timeout(Some(Duration::from_secs(1))).unwrap();
        let mut b = [0u8; 4096];
        // What the vehicle wrote before it closed it (its heartbeats), then the end: end of
        // file or reset (never a timeout: still held open).
        loop {
            match s.read(&mut b) {
                Ok(0) => break,
                Ok(_) => continue,
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => break,
                other => panic!("an idle connection is still open: {other:?}"),
            }
        }
    }
}

/// A stray frame does not start `sitl`'s clock: another vehicle's heartbeat and a command for
/// another system, then a second of silence, and the run has not started (nothing but
/// heartbeats reaches the stray sender, which is a peer of the `udpin:` link); a ground station's
/// heartbeat then starts it, at 0 (its first `SYSTEM_TIME` says `time_boot_ms` < 1 s, where a
/// clock started by the stray frame would say 10 s and more at `--speedup 10`).
#[test]
fn a_stray_frame_does_not_start_the_clock() {
    let s = load_scenario(None, &["sim.duration_s=600".to_string()]).unwrap();
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::RealTime { speedup: 10.0 };
    let stop = opts.stop.clone();
    let (tx, rx) = mpsc::channel();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&s, &opts, &mut NoTrace, &mut |a| tx.send(a).unwrap()).expect("sitl")
    });
    let addr = rx.recv().unwrap();
    let mut stray = Link::open(&format!("udpout:{addr}"), 7, 1).unwrap();
    stray
        .send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            mavlink_version: 3,
            ..Default::default()
        }))
        .unwrap();
    stray
        .send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            param1: 1.0,
            target_system: 9,
            target_component: 1,
            ..Default::default()
        }))
        .unwrap();
    let mut before = Vec::new();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(1) {
        for r in stray.poll(Duration::from_millis(20)).unwrap() {
            if !matches!(r.msg, MavMessage::HEARTBEAT(_)) {
                before.push(r.msg);
            }
        }
    }
    let mut gcs = Link::open(&format!("udpout:{addr}"), 245, 190).unwrap();
    gcs.send(&heartbeat()).unwrap();
    let mut first_ms = None;
    let t0 = Instant::now();
    while first_ms.is_none() && t0.elapsed() < Duration::from_secs(5) {
        for r in gcs.poll(Duration::from_millis(20)).unwrap() {
            if let MavMessage::SYSTEM_TIME(t) = &r.msg {
                first_ms.get_or_insert(t.time_boot_ms);
            }
        }
    }
    stop.store(true, Ordering::SeqCst);
    let v = vehicle.join().unwrap();
    assert!(
        before.is_empty(),
        "the stray frames started the run: {before:?}"
    );
    let first_ms = first_ms.expect("a SYSTEM_TIME");
    assert!(first_ms < 1000, "the clock started early: {first_ms} ms");
    assert!(v.interrupted);
}
