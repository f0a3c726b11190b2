//! att33d-10: two vehicles with the SAME ids (system 1, component 1: two PX4s left at the
//! default `MAV_SYS_ID`) reaching `fly` from ONE address (a router), each with its own MAVLink
//! frame counter, are never flown as one: their interleaved sequence numbers end the flight
//! (`vehicle_lost`: before control nothing commanded, in control the way out). One vehicle over a
//! link that loses and reorders frames is flown as ever.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions, FlyReport};
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use mavlink::MavHeader;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

mod support;

/// A PX4 ground rover's heartbeat, armed, in PX4 main mode `main` (6: OFFBOARD, 2: POSCTL).
fn heartbeat(main: u32) -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: main << 16,
        mavtype: MavType::MAV_TYPE_GROUND_ROVER,
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// `NAMED_VALUE_FLOAT` `ISO_S` stamped `ms` with `value`.
fn iso_s(ms: u32, value: f32) -> MavMessage {
    let mut name = [0u8; 10];
    name[..5].copy_from_slice(b"ISO_S");
    MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
        time_boot_ms: ms,
        value,
        name: name.into(),
    })
}

/// A position `x` m north, stamped `ms`.
fn position(ms: u32, x: f32) -> MavMessage {
    MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
        time_boot_ms: ms,
        x,
        ..Default::default()
    })
}

/// One sender with ids (1, 1) (or `ids`) on a raw socket: its own frame counter.
struct Sender {
    seq: u8,
    ids: (u8, u8),
}

impl Sender {
    /// The frames of `msgs`, numbered on from this sender's counter.
    fn frames(&mut self, msgs: &[MavMessage]) -> Vec<(u8, Vec<u8>)> {
        msgs.iter()
            .map(|m| {
                let mut f = Vec::new();
                let header = MavHeader {
                    system_id: self.ids.0.into(),
                    component_id: self.ids.1,
                    sequence: self.seq,
                };
                mavlink::write_v2_msg(&mut f, header, m).unwrap();
                let s = self.seq;
                self.seq = self.seq.wrapping_add(1);
                (s, f)
            })
            .collect()
    }
}

/// Runs `fly` (the default scenario's rover, `udpin`, timeout 2 s, `max_duration_s`) against
/// frames from ONE socket: `turn(k)` gives the datagrams of turn `k` (every 50 ms).
fn fly_against(max_duration_s: f64, turn: impl FnMut(u32) -> Vec<Vec<u8>>) -> FlyReport {
    fly_against_with(max_duration_s, |_| {}, false, turn)
}

/// [`fly_against`], its options tweaked (`--take-control`, a Ctrl-C), the socket sending every datagram of fly's
/// back to it (`echo`: a loop in the link) or not.
fn fly_against_with(
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    echo: bool,
    turn: impl FnMut(u32) -> Vec<Vec<u8>>,
) -> FlyReport {
    fly_against_seen(max_duration_s, tweak, echo, turn).0
}

/// A command fly sent: `MAV_CMD` number and its first three parameters.
type Sent = (u16, [f32; 3]);

/// The `COMMAND_LONG`s (message 76) in a datagram of MAVLink 2 frames, read by hand: the
/// payload's seven f32 parameters, then the u16 command (MAVLink 2 drops the payload's
/// trailing zero bytes: what is missing is 0).
fn command_longs(d: &[u8]) -> Vec<Sent> {
    let mut out = Vec::new();
    let mut i = 0;
    while i + 12 <= d.len() && d[i] == 0xFD {
        let len = d[i + 1] as usize;
        let signed = d[i + 2] & 1 == 1;
        let id = u32::from_le_bytes([d[i + 7], d[i + 8], d[i + 9], 0]);
        let end = (i + 10 + len).min(d.len());
        if id == 76 {
            let mut p = [0u8; 33];
            let n = (end - i - 10).min(33);
            p[..n].copy_from_slice(&d[i + 10..i + 10 + n]);
            let f =
                |k: usize| f32::from_le_bytes([p[4 * k], p[4 * k + 1], p[4 * k + 2], p[4 * k + 3]]);
            out.push((u16::from_le_bytes([p[28], p[29]]), [f(0), f(1), f(2)]));
        }
        i = end + 2 + if signed { 13 } else { 0 };
    }
    out
}

/// `MAV_CMD_COMPONENT_ARM_DISARM`'s number.
const ARM_DISARM: u16 = 400;
/// `MAV_CMD_DO_SET_MODE`'s number.
const SET_MODE: u16 = 176;

/// Whether fly ever sent a disarm (`ARM_DISARM` with param1 0, forced or not).
fn disarm_sent(c: &[Sent]) -> bool {
    c.iter().any(|&(cmd, p)| cmd == ARM_DISARM && p[0] == 0.0)
}

/// [`fly_against_with`], also returning the commands fly sent (`COMMAND_LONG`), in order.
fn fly_against_seen(
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    echo: bool,
    turn: impl FnMut(u32) -> Vec<Vec<u8>>,
) -> (FlyReport, Vec<Sent>) {
    let (r, c) = fly_against_turns(max_duration_s, tweak, echo, turn);
    (r, c.into_iter().map(|x| x.1).collect())
}

/// [`fly_against_seen`], each command with the turn after whose datagrams it was read (fly
/// sent it after it had the frames of the turns before).
fn fly_against_turns(
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    echo: bool,
    mut turn: impl FnMut(u32) -> Vec<Vec<u8>>,
) -> (FlyReport, Vec<(u32, Sent)>) {
    let (r, c) = fly_against_sockets(max_duration_s, tweak, echo, move |k| {
        turn(k).into_iter().map(|d| (0, d)).collect()
    });
    (r, c.into_iter().map(|(k, _, x)| (k, x)).collect())
}

/// [`fly_against_turns`] from TWO sockets (two source addresses): `turn(k)` gives each
/// datagram of turn `k` with the socket it leaves from (0 or 1); each command comes with the
/// socket it was read at (fly sends every command to each peer).
fn fly_against_sockets(
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    echo: bool,
    mut turn: impl FnMut(u32) -> Vec<(usize, Vec<u8>)>,
) -> (FlyReport, Vec<(u32, usize, Sent)>) {
    let s = load_scenario(None, &[]).unwrap();
    let mut o = FlyOptions::new("udpin:127.0.0.1:0");
    o.timeout_s = 2.0;
    o.max_duration_s = Some(max_duration_s);
    tweak(&mut o);
    let (tx, rx) = std::sync::mpsc::channel();
    let companion = std::thread::spawn(move || {
        run_fly(&s, &o, &mut NoTrace, &mut |l| {
            tx.send(l.local_addr()?).unwrap();
            Ok(())
        })
        .unwrap()
    });
    let fly: SocketAddr = rx.recv().unwrap();
    let socks = [
        UdpSocket::bind("127.0.0.1:0").unwrap(),
        UdpSocket::bind("127.0.0.1:0").unwrap(),
    ];
    let mut buf = [0u8; 2048];
    let mut commands = Vec::new();
    let t0 = Instant::now();
    let mut k = 0;
    while t0.elapsed() < Duration::from_secs(60) && !companion.is_finished() {
        for (i, d) in turn(k) {
            socks[i].send_to(&d, fly).unwrap();
        }
        k += 1;
        // Whatever fly sends (setpoints, commands) is read and left (no acknowledgement), or
        // sent back to it; 50 ms a turn.
        for (i, sock) in socks.iter().enumerate() {
            let wait_ms = if i == 0 { 50 } else { 1 };
            sock.set_read_timeout(Some(Duration::from_millis(wait_ms)))
                .unwrap();
            while let Ok((n, _)) = sock.recv_from(&mut buf) {
                if echo {
                    sock.send_to(&buf[..n], fly).unwrap();
                }
                commands.extend(command_longs(&buf[..n]).into_iter().map(|c| (k - 1, i, c)));
                sock.set_read_timeout(Some(Duration::from_millis(1)))
                    .unwrap();
            }
        }
    }
    (companion.join().unwrap(), commands)
}

/// Vehicle A (armed, in PX4 mode `main`) alone for 20 turns (1 s), then vehicle B with the same
/// ids through the same socket, its counter 100 ahead, 2 m from A (no jump in the positions:
/// only the frame numbers tell the two apart), its measurement 50 where A's is 9.5.
fn two_senders(main: u32) -> FlyReport {
    let mut a = vehicle_sender();
    let mut b = Sender {
        seq: 100,
        ids: (1, 1),
    };
    fly_against(6.0, move |k| {
        let ms = 1000 + 50 * k;
        let x = 0.05 * k as f32;
        let mut out: Vec<Vec<u8>> = a
            .frames(&[heartbeat(main), iso_s(ms, 9.5), position(ms, x)])
            .into_iter()
            .map(|f| f.1)
            .collect();
        if k >= 20 {
            out.extend(
                b.frames(&[
                    heartbeat(main),
                    iso_s(ms + 20, 50.0),
                    position(ms + 20, x + 2.0),
                ])
                .into_iter()
                .map(|f| f.1),
            );
        }
        out
    })
}

/// Whether event `e` names a proof of two senders by their frame numbers: two different frames
/// with one number in a doubt's window, or a counter going on beside the one that came back
/// behind it (att37-1: one conflict is a doubt, not yet a proof).
fn frame_numbers_proof(e: &str) -> bool {
    e.contains("two different frames numbered") || e.contains("goes on from the counter's")
}

/// In control (the pilot's OFFBOARD): the flight ends `vehicle_lost`, naming the ids and the
/// frame numbers, and the way out is commanded.
#[test]
fn two_senders_with_the_same_ids_on_one_address_end_the_flight_in_control() {
    let r = two_senders(6);
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| frame_numbers_proof(e)
            && e.contains("two vehicles with the ids (system 1, component 1): ")),
        "{:?}",
        r.events
    );
    assert!(r.way_out_commanded, "{:?}", r.events);
}

/// Before control (the pilot's POSCTL: no hand-over yet): the flight ends `vehicle_lost` with
/// nothing commanded (the CLI's exit 79), no law command.
#[test]
fn two_senders_with_the_same_ids_before_control_command_nothing() {
    let r = two_senders(2);
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| frame_numbers_proof(e)),
        "{:?}",
        r.events
    );
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(r.commands.is_empty(), "{:?}", r.commands);
}

/// One vehicle (six frames a turn) over a link that loses every third frame, loses the 150
/// of 25 turns in a row once (a fade, silent for 25 turns where 64 frames take 16: its
/// counter seems to step back 106), and swaps two neighbours every 100 frames: flown to its
/// `max_duration_s`, never taken for two.
#[test]
fn one_sender_over_a_lossy_reordering_link_is_flown() {
    let mut a = vehicle_sender();
    let mut n = 0u32;
    let mut held: Option<Vec<u8>> = None;
    let r = fly_against(3.0, move |k| {
        let ms = 1000 + 50 * k;
        let p = position(ms, 0.05 * k as f32);
        let frames = a.frames(&[
            heartbeat(6),
            iso_s(ms, 9.5),
            p.clone(),
            p.clone(),
            p.clone(),
            p,
        ]);
        if (30..55).contains(&k) {
            // A fade: the turn's frames lost.
            return Vec::new();
        }
        let mut out = Vec::new();
        for (_, f) in frames {
            n += 1;
            if n.is_multiple_of(3) {
                continue;
            }
            if n % 100 == 1 {
                held = Some(f);
                continue;
            }
            out.push(f);
            if let Some(h) = held.take() {
                out.push(h);
            }
        }
        out
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(!r.commands.is_empty(), "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("two vehicles")),
        "{:?}",
        r.events
    );
}

/// Two vehicles with the same ids far apart (300 m) and their counters in step (two PX4s booted
/// together): their positions jump farther than any airframe moves, which ends the flight.
#[test]
fn two_vehicles_far_apart_with_the_same_ids_jump() {
    let mut a = vehicle_sender();
    let r = fly_against(6.0, move |k| {
        let ms = 1000 + 50 * k;
        // One counter for both (the numbers alone cannot tell them apart), the positions
        // alternate between the two vehicles from turn 20.
        let x = if k >= 20 && k % 2 == 1 { 300.0 } else { 0.0 };
        a.frames(&[heartbeat(6), iso_s(ms, 9.5), position(ms, x)])
            .into_iter()
            .map(|f| f.1)
            .collect()
    });
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("positions jumped farther than 100 m/s covers (the last 300 m")),
        "{:?}",
        r.events
    );
    assert!(r.way_out_commanded, "{:?}", r.events);
}

/// A heartbeat of another type with the vehicle's ids (a rover's ids beating as a quadrotor:
/// a second vehicle left at them, or its autopilot changed) ends the flight.
#[test]
fn a_heartbeat_of_another_type_with_the_vehicles_ids_ends_the_flight() {
    let mut a = vehicle_sender();
    let r = fly_against(6.0, move |k| {
        let ms = 1000 + 50 * k;
        let mut hb = heartbeat(6);
        if k == 20 {
            if let MavMessage::HEARTBEAT(h) = &mut hb {
                h.mavtype = MavType::MAV_TYPE_QUADROTOR;
            }
        }
        turn_frames(&mut a, Some(hb), ms)
    });
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "a heartbeat of MAV_TYPE_QUADROTOR (MAV_AUTOPILOT_PX4) after the vehicle's MAV_TYPE_GROUND_ROVER"
        )),
        "{:?}",
        r.events
    );
    assert!(r.way_out_commanded, "{:?}", r.events);
}

/// ver33-4 (a): a twin companion's heartbeat (this one's ids, 1, 191) heard before any
/// vehicle, with `--take-control`: `another_controller`, nothing sent or commanded (the CLI's
/// exit 79, not "no vehicle was ever heard").
#[test]
fn a_twin_heard_before_the_vehicle_ends_as_another_controller() {
    let mut twin = Sender {
        seq: 0,
        ids: (1, 191),
    };
    let r = fly_against_with(
        6.0,
        |o| o.take_control = true,
        false,
        move |_| {
            let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
                autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
                mavlink_version: 3,
                ..Default::default()
            });
            twin.frames(&[beat]).into_iter().map(|f| f.1).collect()
        },
    );
    assert_eq!(r.end, FlyEnd::AnotherController, "{:?}", r.events);
    assert!(!r.vehicle_heard && !r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("a second companion with this one's ids")),
        "{:?}",
        r.events
    );
}

/// ver33-4 (b): a link that hands fly its own frames back (a routing loop): its own heartbeats
/// and setpoints are recognised (the ids, numbers and contents it sent) and ignored, logged
/// once; the pilot's vehicle is flown to its `max_duration_s`, not ended as a twin's.
#[test]
fn a_link_echoing_fly_s_own_frames_is_no_twin() {
    let mut a = vehicle_sender();
    let r = fly_against_with(
        2.0,
        |_| {},
        true,
        move |k| {
            let ms = 1000 + 50 * k;
            turn_frames(&mut a, Some(heartbeat(6)), ms)
        },
    );
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(!r.commands.is_empty(), "{:?}", r.events);
    let echoes = support::logged(&r, &["own frames came back"]);
    assert_eq!(echoes, 1, "{:?}", r.events);
}

/// att33d-9a: in control, the vehicle falls silent for 1.5 s and comes back disarmed in MANUAL,
/// its clock not gone back (a reboot that does not look like one, or a pilot's disarm): it
/// ends `pilot_took_over`, nothing commanded, and the log says it may be a reboot.
#[test]
fn a_disarm_after_a_silence_may_be_a_reboot() {
    let mut a = vehicle_sender();
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        if (20..50).contains(&k) {
            return Vec::new();
        }
        let mut hb = heartbeat(if k < 20 { 6 } else { 1 });
        if k >= 50 {
            if let MavMessage::HEARTBEAT(h) = &mut hb {
                h.base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
            }
        }
        turn_frames(&mut a, Some(hb), ms)
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("or its autopilot rebooted")),
        "{:?}",
        r.events
    );
}

/// att49f's CB (att45f-10): in control the vehicle falls silent for 1.5 s and comes back
/// disarmed in MANUAL, its measurement stamped 100 s back (its autopilot rebooted; no position
/// to show its clock): `sensor_clock_jump` fires while the disarm awaits confirmation as the
/// pilot's word (nothing commanded), and the log says it may be a reboot, as
/// `pilot_took_over` does ([`a_disarm_after_a_silence_may_be_a_reboot`]). Before: "rebooted"
/// only in the measurement's "(a rebooted or spoofed clock)", the failsafe's line silent.
#[test]
fn a_failsafe_on_a_disarm_after_a_silence_says_it_may_be_a_reboot() {
    let mut a = vehicle_sender();
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        match k {
            0..=19 => datagrams(a.frames(&[heartbeat(6), iso_s(ms + 100_000, 9.5)])),
            20..=49 => Vec::new(),
            _ => datagrams(a.frames(&[heartbeat_disarmed(1), iso_s(ms, 9.5)])),
        }
    });
    assert_eq!(r.end, FlyEnd::SensorClockJump, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    support::assert_logged(
        &r,
        &[
            "not yet confirmed as its pilot's",
            "(or its autopilot rebooted: it was silent for more than 1 s",
        ],
    );
}

/// ver33b-1: a second autopilot (system 4) heard 0.5 s after the vehicle, once the companion has
/// control (the pilot's OFFBOARD): `two_vehicles`, and the way out (HOLD) is commanded to the
/// vehicle flown, not "nothing commanded" with the vehicle left in OFFBOARD.
#[test]
fn a_second_autopilot_in_control_gets_the_way_out() {
    let mut a = vehicle_sender();
    let mut b = Sender {
        seq: 0,
        ids: (4, 1),
    };
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        let mut out: Vec<Vec<u8>> = a
            .frames(&[heartbeat(6), iso_s(ms, 9.5), position(ms, 0.0)])
            .into_iter()
            .map(|f| f.1)
            .collect();
        if k >= 10 {
            out.extend(b.frames(&[heartbeat(2)]).into_iter().map(|f| f.1));
        }
        out
    });
    assert_eq!(r.end, FlyEnd::TwoVehicles, "{:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("in control): which to fly is ambiguous, the way out is commanded")),
        "{:?}",
        r.events
    );
}

/// ver33b-5: in control, the pilot disarms (the heartbeat disarmed, time-stamped frames pause)
/// and Ctrl-C comes 0.5 s after the disarm is confirmed, inside the reboot watch: the disarm is the pilot's, nothing is
/// commanded (no HOLD on the pilot's disarmed vehicle).
#[test]
fn a_failsafe_in_the_reboot_watch_commands_nothing() {
    let mut a = vehicle_sender();
    // The pilot's disarm at 1.0 s of this clock, confirmed once its heartbeats have shown it
    // for the span (1.1 x the 1 s floor of the heartbeat period: at ~2.1 s), the Ctrl-C at
    // 2.6 s: inside the 1 s watch that follows (and before the sensor's 2 s timeout, 3.0 s).
    let t0 = Instant::now();
    let r = fly_against_with(
        20.0,
        |o| {
            let stop = o.stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(2600));
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            });
        },
        false,
        move |k| {
            let ms = 1000 + 50 * k;
            if t0.elapsed() < Duration::from_millis(1000) {
                return a
                    .frames(&[heartbeat(6), iso_s(ms, 9.5), position(ms, 0.0)])
                    .into_iter()
                    .map(|f| f.1)
                    .collect();
            }
            let mut hb = heartbeat(6);
            if let MavMessage::HEARTBEAT(h) = &mut hb {
                h.base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
            }
            a.frames(&[hb]).into_iter().map(|f| f.1).collect()
        },
    );
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("a pilot's disarm, watched for a reboot")),
        "{:?}",
        r.events
    );
}

/// ver33b-10: in control, heartbeats that drop the custom-mode flag for 0.5 s (a relay
/// rewriting `base_mode`; the mode unknown, still armed) are no pilot's word: the flight goes
/// on to its `max_duration_s`, not `pilot_took_over` with the vehicle left in OFFBOARD.
#[test]
fn an_unknown_mode_in_control_is_no_pilots_word() {
    let mut a = vehicle_sender();
    let r = fly_against(2.5, move |k| {
        let ms = 1000 + 50 * k;
        let mut hb = heartbeat(6);
        if (15..25).contains(&k) {
            if let MavMessage::HEARTBEAT(h) = &mut hb {
                h.base_mode = MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
            }
        }
        turn_frames(&mut a, Some(hb), ms)
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
}

/// A PX4 ground rover's heartbeat in PX4 main mode `main` (1: MANUAL, 3: POSCTL, 6:
/// OFFBOARD), disarmed.
fn heartbeat_disarmed(main: u32) -> MavMessage {
    let mut hb = heartbeat(main);
    if let MavMessage::HEARTBEAT(h) = &mut hb {
        h.base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    }
    hb
}

/// The datagrams of `frames`.
fn datagrams(frames: Vec<(u8, Vec<u8>)>) -> Vec<Vec<u8>> {
    frames.into_iter().map(|f| f.1).collect()
}

/// ver33c-1: in control (the pilot's OFFBOARD), a second vehicle with the same ids behind the
/// same address (its own frame counter, behind or ahead of the vehicle's) beats once a second,
/// in POSCTL or disarmed in MANUAL, and sends nothing else. Its first heartbeat is no pilot's
/// word: the vehicle's next heartbeat (armed in OFFBOARD) contradicts it with a frame out of
/// sequence between, so the flight ends `vehicle_lost` with the way out commanded (before:
/// `pilot_took_over` at the twin's first heartbeat, nothing commanded, the vehicle left in
/// OFFBOARD with nobody sending setpoints).
#[test]
fn a_same_id_twins_heartbeat_in_control_is_no_pilots_word() {
    for (twin_seq, twin) in [
        (0u8, heartbeat(3)),
        (100, heartbeat(3)),
        (0, heartbeat_disarmed(1)),
        (100, heartbeat_disarmed(1)),
    ] {
        let mut a = Sender {
            seq: 0,
            ids: (1, 1),
        };
        let mut b = Sender {
            seq: twin_seq,
            ids: (1, 1),
        };
        let twin_hb = twin.clone();
        let r = fly_against(20.0, move |k| {
            let ms = 1000 + 50 * k;
            let mut out = turn_frames(&mut a, Some(heartbeat(6)), ms);
            if k >= 20 && k % 20 == 0 {
                out.extend(datagrams(b.frames(std::slice::from_ref(&twin_hb))));
            }
            out
        });
        assert_eq!(r.end, FlyEnd::VehicleLost, "{twin:?} {:?}", r.events);
        // The way out, or nothing where the twin's heartbeat was applied as a word before the
        // proof (att39f-1).
        if !r.way_out_commanded {
            assert_word_before_the_proof_commands_nothing(&r);
        }
        assert!(
            r.events
                .iter()
                .any(|e| e.contains("vehicle_lost: two vehicles with the ids")),
            "{:?}",
            r.events
        );
        assert!(
            !r.events.iter().any(|e| e.contains("pilot_took_over")),
            "{:?}",
            r.events
        );
    }
}

/// att33e-2: one vehicle whose pilot switches to POSCTL, the last OFFBOARD heartbeat before the
/// switch delivered late (after the first POSCTL one: its frame number behind): older news, not
/// a second vehicle's contradiction: `pilot_took_over`, nothing commanded (before: `vehicle_lost`
/// with HOLD commanded against the pilot).
#[test]
fn a_late_heartbeat_after_a_pilots_switch_is_older_news() {
    let mut a = vehicle_sender();
    let mut held: Vec<Vec<u8>> = Vec::new();
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        let mut out = turn_frames(&mut a, Some(heartbeat(if k < 20 { 6 } else { 3 })), ms);
        if k == 19 {
            // Turn 19's OFFBOARD heartbeat is held back and delivered after turn 20's POSCTL one.
            held.push(out.remove(0));
        }
        if k == 20 {
            out.insert(1, held.remove(0));
        }
        out
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
}

/// ver33c-1's other side: one vehicle whose pilot switches to POSCTL in flight over a link
/// that delivers that heartbeat late (after the measurement sent after it: a frame out of
/// sequence) is not taken for two: the next heartbeats, in sequence, confirm the pilot's word:
/// `pilot_took_over`, nothing commanded.
#[test]
fn a_pilots_switch_on_a_reordering_link_stands() {
    let mut a = vehicle_sender();
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        let mut out = turn_frames(&mut a, Some(heartbeat(if k < 20 { 6 } else { 3 })), ms);
        if k == 20 {
            out.swap(0, 1);
        }
        out
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
}

/// One sender's change and back within a heartbeat (POSCTL, then OFFBOARD again at the next
/// one, frames in sequence): the pilot's word, as before ver33c-1: `pilot_took_over`, nothing
/// commanded.
#[test]
fn one_senders_switch_and_back_is_the_pilots_word() {
    let mut a = vehicle_sender();
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        turn_frames(&mut a, Some(heartbeat(if k == 20 { 3 } else { 6 })), ms)
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains(", then armed in OFFBOARD")),
        "{:?}",
        r.events
    );
}

/// att33e-1: in control, Ctrl-C starts the failsafe (HOLD, never acknowledged here); from then
/// on a second vehicle with the same ids behind the same address beats disarmed in MANUAL at
/// 5 Hz. Its heartbeats are no pilot's word during the retries either: they never end them
/// "pilot_took_over during the failsafe" (before: at the twin's first heartbeat, the vehicle
/// flown left in OFFBOARD with no setpoints); the HOLD goes on being commanded.
#[test]
fn a_twins_heartbeat_during_the_failsafe_is_no_pilots_word() {
    let mut a = vehicle_sender();
    let mut b = Sender {
        seq: 100,
        ids: (1, 1),
    };
    let t0 = Instant::now();
    let r = fly_against_with(
        20.0,
        |o| {
            let stop = o.stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(1500));
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            });
        },
        false,
        move |k| {
            let ms = 1000 + 50 * k;
            let mut out = turn_frames(&mut a, Some(heartbeat(6)), ms);
            if t0.elapsed() > Duration::from_millis(1600) && k % 4 == 0 {
                out.extend(datagrams(b.frames(&[heartbeat_disarmed(1)])));
            }
            out
        },
    );
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        r.events
    );
}

/// att33e-6: one vehicle (1 Hz heartbeat, measurements every 40 ms) over a link that delivers
/// a frame late once a second (at phase 0.5 s two consecutive frames swapped: att33e's
/// `--swap-every 1`), its pilot switching to POSCTL at 2.5 s: the late frames are no second
/// sender's, the pilot's word stands once the heartbeats have shown it for longer than their
/// period (at the 5 s heartbeat): `pilot_took_over`, nothing commanded (before att33e-6's fix:
/// never confirmed, the flight flown on to its end and HOLD commanded against the pilot). (A
/// swap at every 50 ms turn, as this test once sent with a 20 Hz heartbeat, is 12 late frames
/// in 512 within 0.6 s: two senders' interleaving by the rule, before the span of a 1 s
/// heartbeat period.)
#[test]
fn a_pilots_switch_over_a_link_that_reorders_once_a_second_stands() {
    let mut a = vehicle_sender();
    let mut own = Beats::new(0.0, &[1.0]);
    let mut swaps = Beats::new(0.5, &[1.0]);
    let mut last_ms = 0u32;
    let t0 = Instant::now();
    let r = fly_against(30.0, move |_| {
        let t = t0.elapsed().as_secs_f64();
        let ms = 1000 + (t * 1000.0) as u32;
        let beat = own.due(t).then(|| heartbeat(if t < 2.5 { 6 } else { 3 }));
        if ms < last_ms + 40 && beat.is_none() {
            return Vec::new();
        }
        last_ms = ms;
        let mut out = turn_frames(&mut a, beat, ms);
        if swaps.due(t) {
            let n = out.len();
            out.swap(n - 2, n - 1);
        }
        out
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
}

/// att33f-2 (N7's order): the vehicle (the pilot's OFFBOARD, 1 Hz heartbeat) is switched to
/// MANUAL by its pilot at 2.5 s (heartbeats in MANUAL from 3 s); at 3.05 s one pair of frames
/// is swapped (a frame out of sequence), at 3.1 s the 2 s OFFBOARD heartbeat is delivered
/// again, byte-identical (a retransmitting radio). A copy of a frame already handled is no
/// news, never applied: the pilot's word stands (`pilot_took_over` at the 5 s heartbeat),
/// nothing commanded. Before (92cda41): the copy was applied as the vehicle's state, read as a
/// second vehicle's contradiction with the swapped frame between: `vehicle_lost`, HOLD
/// commanded against the pilot.
#[test]
fn a_late_copy_of_a_heartbeat_is_no_news() {
    let mut a = vehicle_sender();
    let mut own = Beats::new(0.0, &[1.0]);
    let mut kept: Option<Vec<u8>> = None;
    let (mut swapped, mut copied) = (false, false);
    let mut last_ms = 0u32;
    let t0 = Instant::now();
    let r = fly_against(30.0, move |_| {
        let t = t0.elapsed().as_secs_f64();
        let ms = 1000 + (t * 1000.0) as u32;
        let beat = own
            .due(t)
            .then(|| if t < 2.5 { heartbeat(6) } else { heartbeat(1) });
        if ms < last_ms + 40 && beat.is_none() {
            return Vec::new();
        }
        last_ms = ms;
        let mut out = turn_frames(&mut a, beat.clone(), ms);
        if beat.is_some() && (2.0..2.5).contains(&t) {
            kept = out.first().cloned();
        }
        if t >= 3.05 && !swapped {
            swapped = true;
            out.swap(0, 1);
        }
        if t >= 3.1 && !copied {
            copied = true;
            out.extend(kept.take());
        }
        out
    });
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
}

/// att33f-7: the pilot's switch to POSCTL shown by a heartbeat, then no heartbeat any more
/// (its positions and measurements go on): the link is lost before the span confirms the
/// pilot's word, and nothing is commanded against it (before: HOLD commanded at link_lost).
#[test]
fn a_failsafe_while_a_pilots_word_awaits_confirmation_commands_nothing() {
    let mut a = vehicle_sender();
    let r = fly_against(20.0, move |k| {
        let ms = 1000 + 50 * k;
        let msgs = match k {
            0..=19 => vec![heartbeat(6), iso_s(ms, 9.5), position(ms, 0.0)],
            20 => vec![heartbeat(3), iso_s(ms, 9.5), position(ms, 0.0)],
            _ => vec![iso_s(ms, 9.5), position(ms, 0.0)],
        };
        datagrams(a.frames(&msgs))
    });
    assert_eq!(r.end, FlyEnd::LinkLost, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("not yet confirmed as its pilot's")),
        "{:?}",
        r.events
    );
}

/// A schedule of heartbeats on the companion's wall clock: the first at `first_s`, then one
/// after each of `gaps_s` in turn (cycled), s.
struct Beats {
    next_s: f64,
    gaps_s: Vec<f64>,
    i: usize,
}

impl Beats {
    fn new(first_s: f64, gaps_s: &[f64]) -> Self {
        Self {
            next_s: first_s,
            gaps_s: gaps_s.to_vec(),
            i: 0,
        }
    }

    /// Whether a beat is due at `t_s` (then the next one is scheduled).
    fn due(&mut self, t_s: f64) -> bool {
        if t_s < self.next_s {
            return false;
        }
        self.next_s += self.gaps_s[self.i % self.gaps_s.len()];
        self.i += 1;
        true
    }
}

/// `fly` (tweaked as [`fly_against_with`]) against a vehicle (ids 1, 1) on wall time: its
/// measurement and position every 40 ms (stamped with that time), then its heartbeat whenever
/// `vehicle(t_s)` gives one (`t_s` since the start, on that 40 ms grid); and a second vehicle
/// with the same ids behind the same socket beating whenever `twin(t_s)` gives a heartbeat, its
/// frame counter 100 ahead of the vehicle's (each sender's frames in sequence: only their
/// interleaving steps back). The turns due are caught up after a slow one (the harness's turns
/// last as long as fly's datagrams make them, longer under load): the vehicle's 50 frames a
/// second, which the frame counter's watch reads, never depend on the machine's load.
fn vehicle_and_twin(
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    mut vehicle: impl FnMut(f64) -> Option<MavMessage> + Send + 'static,
    mut twin: impl FnMut(f64) -> Option<MavMessage> + Send + 'static,
) -> FlyReport {
    let mut a = vehicle_sender();
    let mut b = Sender {
        seq: 100,
        ids: (1, 1),
    };
    let mut next_s = 0.0f64;
    let t0 = Instant::now();
    fly_against_with(max_duration_s, tweak, false, move |_| {
        let now_s = t0.elapsed().as_secs_f64();
        let mut out = Vec::new();
        while next_s <= now_s {
            let t_s = next_s;
            let ms = 1000 + (t_s * 1000.0) as u32;
            // A heartbeat after the turn's measurement: never the vehicle's first frame after
            // the second vehicle's (which steps back, and is dropped as late if a heartbeat).
            let mut msgs = vec![iso_s(ms, 9.5), position(ms, 0.0)];
            msgs.extend(vehicle(t_s));
            out.extend(datagrams(a.frames(&msgs)));
            if let Some(hb) = twin(t_s) {
                // Its counter kept 100 ahead of the vehicle's (a sender of more frames): each
                // of its frames steps forward, the vehicle's next one back (out of sequence).
                b.seq = a.seq.wrapping_add(100);
                out.extend(datagrams(b.frames(&[hb])));
            }
            next_s += 0.04;
        }
        out
    })
}

/// The number of tries in the way out's last word ("... (N tries, ...)").
fn way_out_tries(r: &FlyReport) -> Option<u32> {
    r.events.iter().rev().find_map(|e| {
        let (_, rest) = e.split_once(" (")?;
        rest.split_once(" tries")?.0.parse().ok()
    })
}

/// Asserts that a flight ended `vehicle_lost` on a second sender with nothing commanded because
/// a heartbeat applied before the proof showed a word (a pilot's, or the second sender's:
/// att39f-1), and that the log says so.
fn assert_word_before_the_proof_commands_nothing(r: &FlyReport) {
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "(a pilot's word, or the second sender's): setpoints stopped, nothing commanded, the pilot's mode stands"
        )),
        "{:?}",
        r.events
    );
}

/// Asserts that a flight with a second vehicle's heartbeats ended `vehicle_lost` with HOLD
/// commanded more than once and never unconfirmed-confirmed: no `pilot_took_over` (at the
/// flight's end or during the failsafe's retries), the vehicle flown (which never leaves
/// OFFBOARD here) not reported in HOLD.
///
/// att39f-1: where a heartbeat applied before the second sender was proven showed a word (the
/// twin's, which fly cannot tell from a pilot's), nothing is commanded instead
/// ([`assert_word_before_the_proof_commands_nothing`]).
fn assert_twin_never_the_pilot(r: &FlyReport) {
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        r.events
    );
    if !r.way_out_commanded {
        assert_word_before_the_proof_commands_nothing(r);
        return;
    }
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("the vehicle did not confirm the HOLD")),
        "{:?}",
        r.events
    );
    assert!(way_out_tries(r).is_some_and(|n| n >= 2), "{:?}", r.events);
}

/// att33f-1 (N3): the vehicle flown (the pilot's OFFBOARD) beats at 1 Hz; from 2.05 s a second
/// vehicle with its ids beats at 5 Hz, armed in OFFBOARD (in agreement: its beats in sequence
/// count as the vehicle's), then from 3.1 s disarmed in MANUAL. The span is the vehicle's own
/// period (1.1 x 1 s), not a fifth of it: the vehicle's 4.0 s heartbeat contradicts the
/// second vehicle's word (`vehicle_lost`, HOLD commanded), and during the retries its 5 Hz
/// beats never stand either (B1, att33f-4): the HOLD is retried, never "a pilot took over".
/// Before: the twin's beats made the span 0.22 s: `pilot_took_over` at ~3.5 s, nothing
/// commanded, the vehicle left armed in OFFBOARD.
#[test]
fn a_fast_twin_in_agreement_then_disarmed_is_no_pilots_word() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(2.05, &[0.2]);
    let r = vehicle_and_twin(
        30.0,
        |_| {},
        move |t| own.due(t).then(|| heartbeat(6)),
        move |t| {
            other.due(t).then(|| {
                if t < 3.1 {
                    heartbeat(6)
                } else {
                    heartbeat_disarmed(1)
                }
            })
        },
    );
    assert_twin_never_the_pilot(&r);
}

/// att33f-1 (N8): the vehicle beats at 5 Hz, then at 1 Hz from 2.6 s (a stream-rate change,
/// at 2.45 s); from 2.65 s a second vehicle with its ids beats disarmed in MANUAL at 5 Hz. The
/// span is at least 1.1 s (a 1 Hz heartbeat's), never the 5 Hz gaps': the vehicle's 3.6 s
/// heartbeat contradicts (`vehicle_lost`, HOLD retried). Before: span 0.22 s,
/// `pilot_took_over` at ~3.05 s.
#[test]
fn a_heartbeat_rate_drop_does_not_shorten_the_span() {
    let mut own = Beats::new(0.0, &[0.2]);
    let mut slow = false;
    let mut other = Beats::new(2.65, &[0.2]);
    let r = vehicle_and_twin(
        30.0,
        |_| {},
        move |t| {
            if t >= 2.45 && !slow {
                slow = true;
                own = Beats::new(own.next_s.max(2.45), &[1.0]);
            }
            own.due(t).then(|| heartbeat(6))
        },
        move |t| other.due(t).then(|| heartbeat_disarmed(1)),
    );
    assert_twin_never_the_pilot(&r);
}

/// att33f-1 (N1): the vehicle's heartbeat jitters, gaps of 0.5 s four times then 1.5 s (beats
/// at 0, 0.5, 1, 1.5, 2, 3.5, ..., 5.5, 7); a second vehicle with its ids beats disarmed in
/// MANUAL at 5 Hz from 5.55 s, the start of a 1.5 s gap after four of 0.5 s. The span is the
/// longest gap seen (1.1 x 1.5 s), not the last four's (0.55 s): the vehicle's 7 s heartbeat
/// contradicts (`vehicle_lost`, HOLD retried). Before: `pilot_took_over` at ~6.15 s.
#[test]
fn heartbeat_jitter_does_not_shorten_the_span() {
    let mut own = Beats::new(0.0, &[0.5, 0.5, 0.5, 0.5, 1.5]);
    let mut other = Beats::new(5.55, &[0.2]);
    let r = vehicle_and_twin(
        30.0,
        |_| {},
        move |t| own.due(t).then(|| heartbeat(6)),
        move |t| other.due(t).then(|| heartbeat_disarmed(1)),
    );
    assert_twin_never_the_pilot(&r);
}

/// The vehicle's sender: ids (1, 1), its frame counter from 0.
fn vehicle_sender() -> Sender {
    Sender {
        seq: 0,
        ids: (1, 1),
    }
}

/// One turn of the vehicle's frames: its heartbeat `hb` (if any), then its measurement (9.5)
/// and position (at the origin), both stamped `ms`.
fn turn_frames(a: &mut Sender, hb: Option<MavMessage>, ms: u32) -> Vec<Vec<u8>> {
    let mut msgs: Vec<MavMessage> = hb.into_iter().collect();
    msgs.extend([iso_s(ms, 9.5), position(ms, 0.0)]);
    datagrams(a.frames(&msgs))
}

/// A PX4 ground rover's heartbeat, armed, in PX4 main mode `main` and sub mode `sub` (4, 3:
/// AUTO.LOITER, the failsafe's HOLD).
fn heartbeat_sub(main: u32, sub: u32) -> MavMessage {
    let mut hb = heartbeat(main);
    if let MavMessage::HEARTBEAT(h) = &mut hb {
        h.custom_mode = (main << 16) | (sub << 24);
    }
    hb
}

/// att33f-3 (N10c): in control (the pilot's OFFBOARD, 1 Hz heartbeat), Ctrl-C at 2.5 s starts
/// the failsafe: HOLD, never acknowledged nor carried out (the vehicle stays armed in OFFBOARD).
/// From 2.65 s a second vehicle with its ids beats armed in AUTO.LOITER (the HOLD commanded) at
/// 1 Hz. Its heartbeat confirms nothing before it has stood for the span with none
/// contradicting, and the vehicle's OFFBOARD heartbeats contradict it every second: the HOLD
/// is retried to the bound and reported not confirmed (exit 69). Before: "the vehicle is in
/// HOLD (1 tries)" at the second vehicle's first heartbeat (exit 75), the vehicle flown left in
/// OFFBOARD with nobody sending setpoints.
#[test]
fn a_twins_heartbeat_in_the_mode_commanded_confirms_no_failsafe() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(2.65, &[1.0]);
    let r = vehicle_and_twin(
        30.0,
        |o| {
            let stop = o.stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(2500));
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            });
        },
        move |t| own.due(t).then(|| heartbeat(6)),
        move |t| other.due(t).then(|| heartbeat_sub(4, 3)),
    );
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("the vehicle is in")),
        "{:?}",
        r.events
    );
    assert!(way_out_tries(&r).is_some_and(|n| n >= 2), "{:?}", r.events);
}

/// The way out shown by the vehicle's own heartbeats (one sender, 1 Hz: it goes to AUTO.LOITER
/// at 3.2 s, after Ctrl-C at 2.5 s) is confirmed once they have shown it for the span (1.1 s:
/// at the third heartbeat in HOLD, 6 s), as before only later: exit 75, "the vehicle is in
/// HOLD".
#[test]
fn the_vehicles_own_hold_is_confirmed_after_the_span() {
    let mut own = Beats::new(0.0, &[1.0]);
    let r = vehicle_and_twin(
        30.0,
        |o| {
            let stop = o.stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(2500));
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            });
        },
        move |t| {
            own.due(t).then(|| {
                if t < 3.2 {
                    heartbeat(6)
                } else {
                    heartbeat_sub(4, 3)
                }
            })
        },
        |_| None,
    );
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("the vehicle is in HOLD")),
        "{:?}",
        r.events
    );
}

/// A vehicle whose unchanging heartbeat (armed in OFFBOARD, 1 Hz) always falls on one frame
/// number (7: its frames between span the other 255 numbers, 100 of them lost in a fade every
/// second): each heartbeat is identical to the last frame with its number, but ahead of the
/// newest, a new frame, never dropped as a copy delivered again: the flight is flown to its
/// `max_duration_s` (found while testing att33f-1's rate drop: a heartbeat 256 frames after an
/// identical one was dropped as a copy since 2535521, and the failsafe's retries then took a
/// second vehicle's word for the pilot's; here, no heartbeat after the first was heard:
/// `link_lost` at 3 s).
#[test]
fn a_heartbeat_on_the_number_of_the_last_one_is_no_copy() {
    let mut a = vehicle_sender();
    let mut own = Beats::new(0.0, &[1.0]);
    let mut fades = Beats::new(0.5, &[1.0]);
    let mut next_s = 0.0f64;
    let t0 = Instant::now();
    let r = fly_against(5.0, move |_| {
        // A turn every 40 ms of wall time, caught up after a slow one (as `vehicle_and_twin`):
        // the numbers the vehicle's frames span in a second are its own, never the load's.
        let now_s = t0.elapsed().as_secs_f64();
        let mut out = Vec::new();
        while next_s <= now_s {
            let t = next_s;
            let ms = 1000 + (t * 1000.0) as u32;
            let beat = own.due(t).then(|| heartbeat(6));
            if beat.is_some() {
                a.seq = 7;
            }
            if fades.due(t) {
                a.seq = a.seq.wrapping_add(100);
            }
            out.extend(turn_frames(&mut a, beat, ms));
            next_s += 0.04;
        }
        out
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("two vehicles")),
        "{:?}",
        r.events
    );
}

/// `fly` (tweaked as [`fly_against_with`]) against a vehicle as [`vehicle_and_twin`]'s, and
/// a second vehicle with its ids from `twin_from_s` on: its own frame counter, starting
/// `ahead` numbers ahead of the vehicle's and stepping by one per frame (no reset), a
/// position 0.5 m from the vehicle's every 40 ms and a heartbeat whenever `twin(t_s)` gives
/// one. Returns the report and the commands fly sent.
fn vehicle_and_twin_with_positions(
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    mut vehicle: impl FnMut(f64) -> Option<MavMessage> + Send + 'static,
    twin_from_s: f64,
    ahead: u8,
    mut twin: impl FnMut(f64) -> Option<MavMessage> + Send + 'static,
) -> (FlyReport, Vec<Sent>) {
    let mut a = vehicle_sender();
    let mut b: Option<Sender> = None;
    let mut last_ms = 0u32;
    let t0 = Instant::now();
    fly_against_seen(max_duration_s, tweak, false, move |_| {
        let t_s = t0.elapsed().as_secs_f64();
        let ms = 1000 + (t_s * 1000.0) as u32;
        let beat = vehicle(t_s);
        let due = ms >= last_ms + 40;
        let mut msgs = Vec::new();
        if due || beat.is_some() {
            last_ms = ms;
            msgs.extend([iso_s(ms, 9.5), position(ms, 0.0)]);
        }
        msgs.extend(beat);
        let mut out = datagrams(a.frames(&msgs));
        if t_s >= twin_from_s {
            let b = b.get_or_insert_with(|| Sender {
                seq: a.seq.wrapping_add(ahead),
                ids: (1, 1),
            });
            let mut m: Vec<MavMessage> = twin(t_s).into_iter().collect();
            if due {
                m.push(position(ms + 10, 0.5));
            }
            out.extend(datagrams(b.frames(&m)));
        }
        out
    })
}

/// Asserts the end after a second sender was seen: `vehicle_lost`, the HOLD commanded more
/// than once and never confirmed, no disarm ever sent, no pilot's word taken, and the log
/// saying so.
///
/// att39f-1: where a heartbeat applied before the second sender was proven showed a word (the
/// twin's, which fly cannot tell from a pilot's), nothing is commanded instead: no disarm, no
/// HOLD ([`assert_word_before_the_proof_commands_nothing`]).
fn assert_hold_never_a_disarm(r: &FlyReport, c: &[Sent]) {
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(!disarm_sent(c), "{c:?} {:?}", r.events);
    if !r.way_out_commanded {
        assert_word_before_the_proof_commands_nothing(r);
        assert!(
            !c.iter().any(|x| x.0 == SET_MODE && x.1[1] == 4.0),
            "{c:?} {:?}",
            r.events
        );
        assert!(
            !r.events.iter().any(|e| e.contains("pilot_took_over")),
            "{:?}",
            r.events
        );
        return;
    }
    assert!(
        c.iter().filter(|x| x.0 == SET_MODE).count() >= 2,
        "{c:?} {:?}",
        r.events
    );
    assert!(
        !r.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        r.events
    );
    assert!(
        r.events.iter().any(|e| e.contains(
            "a second sender with the vehicle's ids (system 1, component 1) was seen, and nothing tells the two apart"
        ) && e.contains("no disarm is sent")
            && e.contains("must be disarmed by its operator")),
        "{:?}",
        r.events
    );
}

/// att33f-6 / att33h-2 (C4, N9a): `--take-control --arm` of a disarmed vehicle (1 Hz
/// heartbeat; it shows itself armed from 3 s, after the companion's arming, and never goes to
/// OFFBOARD). From 3.5 s a second vehicle with its ids beats disarmed in MANUAL at 4 Hz, its
/// counter 100 ahead. Once its frames and the vehicle's meet on one number (a conflict), the
/// flight ends `vehicle_lost`; either may be the vehicle (the companion cannot tell which is on
/// the ground), so no disarm is sent: HOLD, to the retries' bound, never confirmed. Before
/// (main): the forced disarm, to whichever of the two heard it.
#[test]
fn a_twin_during_take_control_arm_gets_hold_never_a_disarm() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(3.5, &[0.25]);
    let (r, c) = vehicle_and_twin_with_positions(
        30.0,
        |o| {
            o.take_control = true;
            o.arm = true;
        },
        move |t| {
            own.due(t).then(|| {
                if t < 2.9 {
                    heartbeat_disarmed(1)
                } else {
                    heartbeat(1)
                }
            })
        },
        3.5,
        100,
        move |t| other.due(t).then(|| heartbeat_disarmed(1)),
    );
    assert_hold_never_a_disarm(&r, &c);
}

/// att33g-1 / att33h-5 (N9a, W3b): `--take-control --arm`, the vehicle armed on the
/// companion's arming (from 2.9 s) but staying in MANUAL; a second vehicle with its ids,
/// counter 120 ahead, beats armed in OFFBOARD at 5 Hz from 3.2 s (after the companion's switch
/// to OFFBOARD): control is taken on its beat. The conflict of the two counters ends the flight `vehicle_lost`: HOLD to the bound,
/// never a disarm, never "a pilot's change and back".
#[test]
fn a_twins_offboard_beat_during_take_control_arm_gets_hold_never_a_disarm() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(3.2, &[0.2]);
    let (r, c) = vehicle_and_twin_with_positions(
        30.0,
        |o| {
            o.take_control = true;
            o.arm = true;
        },
        move |t| {
            own.due(t).then(|| {
                if t < 2.9 {
                    heartbeat_disarmed(1)
                } else {
                    heartbeat(1)
                }
            })
        },
        3.2,
        120,
        move |t| other.due(t).then(|| heartbeat(6)),
    );
    assert_hold_never_a_disarm(&r, &c);
}

/// att33h-3 (X1): in control of a vehicle its pilot armed (OFFBOARD, 1 Hz heartbeat), a
/// second vehicle with its ids from 2.05 s: disarmed heartbeats at 5 Hz and a position every
/// 40 ms, its counter 60 ahead (as many frames as the vehicle's: the vehicle's heartbeats are
/// all older than its last one). Its disarm is no pilot's word: the vehicle's own heartbeats,
/// older, keep it from standing; the two counters' conflict ends the flight `vehicle_lost`,
/// HOLD to the bound. Before (main): the twin's word ended the retries ("pilot_took_over during
/// the failsafe"), the vehicle left in OFFBOARD with nobody sending setpoints.
#[test]
fn a_twin_with_positions_ahead_in_control_is_no_pilots_word() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(2.05, &[0.2]);
    let (r, c) = vehicle_and_twin_with_positions(
        30.0,
        |_| {},
        move |t| own.due(t).then(|| heartbeat(6)),
        2.05,
        60,
        move |t| other.due(t).then(|| heartbeat_disarmed(1)),
    );
    assert_hold_never_a_disarm(&r, &c);
}

/// att33h-8 (F1): in control, Ctrl-C at 2.5 s starts the failsafe (HOLD never acknowledged
/// nor carried out: the vehicle stays armed in OFFBOARD); from 2.6 s a second vehicle with its
/// ids beats disarmed at 5 Hz and sends positions every 40 ms, its counter 40 ahead. Its
/// disarm never ends the retries as a pilot's: HOLD commanded, never confirmed, never "a pilot
/// took over". Before (main): "pilot_took_over during the failsafe" after 2 tries. att41f-2:
/// its disarm, heard before the second sender was proven, awaits confirmation as a pilot's
/// word would (no retry meanwhile); the proof then stops the retries with nothing more
/// commanded (a pilot's word, or the second sender's: the vehicle flown has the HOLD already
/// commanded, or falls to its own offboard-loss failsafe), where before it retried the HOLD
/// to the bound.
#[test]
fn a_twin_with_positions_during_the_failsafe_is_no_pilots_word() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(2.6, &[0.2]);
    let (r, c) = vehicle_and_twin_with_positions(
        30.0,
        |o| {
            let stop = o.stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(2500));
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            });
        },
        move |t| own.due(t).then(|| heartbeat(6)),
        2.6,
        40,
        move |t| other.due(t).then(|| heartbeat_disarmed(1)),
    );
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(!disarm_sent(&c), "{c:?}");
    assert!(
        !r.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        r.events
    );
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("during the failsafe's retries: a second sender")),
        "{:?}",
        r.events
    );
    assert!(c.iter().any(|x| x.0 == SET_MODE), "{c:?}");
    assert!(
        r.events.iter().any(|e| e.contains(
            "showed it disarmed (a pilot's word, or the second sender's, awaiting confirmation): the retries stop, nothing more commanded"
        )),
        "{:?}",
        r.events
    );
}

/// att33g-2 / att33h-1 (P5a): the pilot (the vehicle in OFFBOARD, 1 Hz heartbeat, frames
/// every 40 ms) switches to MANUAL at 2.5 s, and from then for 1 s the link swaps the first
/// two frames of every turn (a frame late every 50 ms, the MANUAL heartbeats among them): late
/// frames of one sender, however many, are never a second sender: `pilot_took_over`, nothing
/// commanded. Before (main): 12 late frames in 512 were two senders: `vehicle_lost`, HOLD
/// commanded against the pilot.
#[test]
fn a_burst_of_reordering_after_a_pilots_switch_is_no_second_sender() {
    let mut a = vehicle_sender();
    let mut own = Beats::new(0.0, &[1.0]);
    let mut last_ms = 0u32;
    let t0 = Instant::now();
    let (r, c) = fly_against_seen(
        30.0,
        |_| {},
        false,
        move |_| {
            let t = t0.elapsed().as_secs_f64();
            let ms = 1000 + (t * 1000.0) as u32;
            let beat = own.due(t).then(|| heartbeat(if t < 2.5 { 6 } else { 1 }));
            if ms < last_ms + 40 && beat.is_none() {
                return Vec::new();
            }
            last_ms = ms;
            let mut out = turn_frames(&mut a, beat, ms);
            if (2.5..3.5).contains(&t) {
                out.swap(0, 1);
            }
            out
        },
    );
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(c.is_empty(), "{c:?}");
    assert!(
        !r.events.iter().any(|e| e.contains("two vehicles")),
        "{:?}",
        r.events
    );
}

/// S11: every heartbeat (1 Hz) delivered one frame late (swapped with the frame after it): a
/// heartbeat of the ids keeps the link alive, and one newer than the last applied is applied
/// however it came: in control the flight goes on to its `max_duration_s` (8 s); a pilot's
/// MANUAL at 3.5 s is confirmed (`pilot_took_over`, nothing commanded). Before (main): every heartbeat
/// after the first was dropped as late: `link_lost` 3 s on, HOLD commanded.
#[test]
fn heartbeats_each_one_frame_late_keep_the_link() {
    for pilot in [false, true] {
        let mut a = vehicle_sender();
        let mut own = Beats::new(0.0, &[1.0]);
        let mut last_ms = 0u32;
        let t0 = Instant::now();
        let (r, c) = fly_against_seen(
            8.0,
            |_| {},
            false,
            move |_| {
                let t = t0.elapsed().as_secs_f64();
                let ms = 1000 + (t * 1000.0) as u32;
                let manual = pilot && t >= 3.5;
                let beat = own.due(t).then(|| heartbeat(if manual { 1 } else { 6 }));
                if ms < last_ms + 40 && beat.is_none() {
                    return Vec::new();
                }
                last_ms = ms;
                let late = beat.is_some();
                let mut out = turn_frames(&mut a, beat, ms);
                if late {
                    out.swap(0, 1);
                }
                out
            },
        );
        if pilot {
            assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
            assert!(!r.way_out_commanded, "{:?}", r.events);
            assert!(c.is_empty(), "{c:?}");
        } else {
            // Flown to the end (the HOLD of max_duration), never link_lost.
            assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
        }
    }
}

/// The names of the events that say the frame watch resynchronised after a burst loss.
fn resyncs(r: &FlyReport) -> usize {
    r.events
        .iter()
        .filter(|e| e.contains("resynchronised as one sender"))
        .count()
}

/// att37-1 (A1): in control (the pilot's OFFBOARD; a heartbeat, a measurement and a position
/// every 50 ms turn of the vehicle's clock), the link loses a burst of `lost` frames sent at once
/// (a parameter list at the link's full speed: the vehicle's counter steps `lost + 1` with no
/// silence, its next number 254 - lost behind the newest, on a number seen). One sender: flown
/// to its `max_duration_s`, the watch resynchronised once (logged), never "two vehicles".
/// Before (046ada6): `vehicle_lost` at the first frame after the burst, HOLD commanded.
#[test]
fn a_burst_loss_without_silence_is_one_sender_in_control() {
    for lost in [127u8, 200, 254] {
        let mut a = vehicle_sender();
        // The burst at turn 100 (300 frames in: the window full).
        let r = fly_against(8.0, move |k| {
            if k == 100 {
                a.seq = a.seq.wrapping_add(lost);
            }
            turn_frames(&mut a, Some(heartbeat(6)), 1000 + 50 * k)
        });
        assert_eq!(r.end, FlyEnd::MaxDuration, "{lost}: {:?}", r.events);
        assert!(
            !r.events.iter().any(|e| e.contains("two vehicles")),
            "{lost}: {:?}",
            r.events
        );
        assert_eq!(resyncs(&r), 1, "{lost}: {:?}", r.events);
        // The first frame after the burst opens the doubt, or, if it is a heartbeat identical
        // to the one seen with its number (a copy by its content: ignored), the next one.
        assert!(
            r.events.iter().any(|e| [lost as u32, lost as u32 + 1]
                .iter()
                .any(|n| e.contains(&format!("({n} frames lost in a burst?)")))),
            "{lost}: {:?}",
            r.events
        );
    }
}

/// att37-1 (A3): in control (the pilot's OFFBOARD, a heartbeat every turn), the pilot switches
/// to POSCTL at turn 100 and the link loses a burst of 200 frames at turn 104, before the word
/// is confirmed. The frames after the burst are a doubt (nothing applied), then one sender
/// resynchronised: the pilot's POSCTL, heard again, is confirmed: `pilot_took_over`, nothing
/// commanded (no mode, no disarm). Before (046ada6): `vehicle_lost`, HOLD commanded against
/// the pilot.
#[test]
fn a_burst_loss_after_a_pilots_switch_leaves_the_pilot_the_vehicle() {
    let mut a = vehicle_sender();
    let (r, c) = fly_against_seen(
        8.0,
        |_| {},
        false,
        move |k| {
            if k == 104 {
                a.seq = a.seq.wrapping_add(200);
            }
            let hb = heartbeat(if k < 100 { 6 } else { 2 });
            turn_frames(&mut a, Some(hb), 1000 + 50 * k)
        },
    );
    assert_eq!(r.end, FlyEnd::PilotTookOver, "{:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    assert!(c.iter().all(|x| x.0 != SET_MODE), "{c:?}");
    assert!(!disarm_sent(&c), "{c:?}");
    assert_eq!(resyncs(&r), 1, "{:?}", r.events);
}

/// `fly --take-control --arm` (tweaked by `tweak`) against one vehicle: disarmed in MANUAL,
/// armed from 2.9 s (after the companion's arming; it never goes to OFFBOARD and acknowledges
/// nothing), a 1 Hz heartbeat, a measurement and a position every 40 ms; at `burst_at_s` its
/// counter steps by `lost` (a burst lost with no silence; 0: none). The report and the commands
/// fly sent.
fn armed_on_the_ground_with_a_burst(burst_at_s: f64, lost: u8) -> (FlyReport, Vec<Sent>) {
    let mut a = vehicle_sender();
    let mut own = Beats::new(0.0, &[1.0]);
    let mut burst = Some(burst_at_s);
    let mut last_ms = 0u32;
    let t0 = Instant::now();
    fly_against_seen(
        30.0,
        |o| {
            o.take_control = true;
            o.arm = true;
        },
        false,
        move |_| {
            let t_s = t0.elapsed().as_secs_f64();
            let ms = 1000 + (t_s * 1000.0) as u32;
            if burst.is_some_and(|b| t_s >= b) {
                burst = None;
                a.seq = a.seq.wrapping_add(lost);
            }
            let mut msgs: Vec<MavMessage> = own
                .due(t_s)
                .then(|| {
                    if t_s < 2.9 {
                        heartbeat_disarmed(1)
                    } else {
                        heartbeat(1)
                    }
                })
                .into_iter()
                .collect();
            if ms >= last_ms + 40 {
                last_ms = ms;
                msgs.extend([iso_s(ms, 9.5), position(ms, 0.0)]);
            }
            datagrams(a.frames(&msgs))
        },
    )
}

/// att37-1 addendum (X1): `--take-control --arm` of a vehicle on the ground; it arms, and its
/// link loses a burst of 200 frames at 3.5 s (no silence). One sender: the take-over ends as
/// it does without the burst (the vehicle never switches to OFFBOARD), and the disarm the
/// companion owes to the vehicle it armed on the ground is sent (forced) as without the burst.
/// Before (046ada6): `vehicle_lost`, HOLD, the vehicle left armed on the ground.
#[test]
fn a_burst_loss_on_the_ground_leaves_the_owed_disarm() {
    let (r0, c0) = armed_on_the_ground_with_a_burst(1e9, 0);
    assert!(disarm_sent(&c0), "{c0:?} {:?}", r0.events);
    let (r, c) = armed_on_the_ground_with_a_burst(3.5, 200);
    assert_eq!(r.end, r0.end, "{:?}", r.events);
    assert!(disarm_sent(&c), "{c:?} {:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("two vehicles")),
        "{:?}",
        r.events
    );
    assert_eq!(resyncs(&r), 1, "{:?}", r.events);
}

/// att37-2 (B4): in control (the pilot's OFFBOARD; five frames a 50 ms turn, four of them
/// time-stamped), the link holds the 125 frames of turns 30 to 54 (1.2 s of the vehicle's
/// clock) and delivers them newest first at turn 55: one sender, no frame lost. The frames
/// after the newest are late (unseen numbers behind it), and the last ones go back 1.2 s on
/// the vehicle's clock, two and more in a row: no reboot (the reboot test reads new frames
/// only). Flown to its `max_duration_s`. Before: `vehicle_lost` "its autopilot rebooted".
#[test]
fn a_reversed_burst_of_one_sender_is_no_reboot() {
    let mut a = vehicle_sender();
    let mut held: Vec<Vec<u8>> = Vec::new();
    let r = fly_against(5.0, move |k| {
        let ms = 1000 + 50 * k;
        let p = position(ms, 0.0);
        let f = datagrams(a.frames(&[heartbeat(6), iso_s(ms, 9.5), p.clone(), p.clone(), p]));
        if (30..55).contains(&k) {
            held.extend(f);
            return Vec::new();
        }
        let mut out: Vec<Vec<u8>> = held.drain(..).rev().collect();
        out.extend(f);
        out
    });
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("rebooted")),
        "{:?}",
        r.events
    );
}

/// One sender on a frame-level link (att39f's stand-in PX4): in control (the pilot's
/// OFFBOARD), three frames a 50 ms turn (paced on the wall clock; a heartbeat every fourth turn, else a second
/// position; a measurement and a position each), the pilot's MANUAL from turn 60 (heartbeats
/// of it from then: a pilot's word awaiting confirmation). `link(k, frames)` is the link: it
/// gets turn `k`'s frames (number, bytes) and the vehicle's sender (to step its counter: a
/// burst of frames sent and lost) and gives the datagrams delivered. The report and every
/// command fly sent.
fn pilot_manual_over_a_link(
    link: impl FnMut(u32, Vec<(u8, Vec<u8>)>, &mut Sender) -> Vec<Vec<u8>> + Send + 'static,
) -> (FlyReport, Vec<Sent>) {
    let (r, c) = manual_over_a_link(60, 8.0, |_| {}, link);
    (r, c.into_iter().map(|x| x.1).collect())
}

/// [`pilot_manual_over_a_link`], the pilot's MANUAL from turn `manual_from`, `fly` tweaked by
/// `tweak` with `max_duration_s`; each command with its turn ([`fly_against_turns`]).
fn manual_over_a_link(
    manual_from: u32,
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    link: impl FnMut(u32, Vec<(u8, Vec<u8>)>, &mut Sender) -> Vec<Vec<u8>> + Send + 'static,
) -> (FlyReport, Vec<(u32, Sent)>) {
    let beat = move |k| heartbeat(if k < manual_from { 6 } else { 1 });
    beats_over_a_link(4, beat, max_duration_s, tweak, link)
}

/// [`manual_over_a_link`], the vehicle's heartbeat every `every` turns (4: 5 Hz, 20: PX4's
/// 1 Hz) being `beat(k)` at turn `k`.
fn beats_over_a_link(
    every: u32,
    beat: impl Fn(u32) -> MavMessage + Send + 'static,
    max_duration_s: f64,
    tweak: impl FnOnce(&mut FlyOptions),
    mut link: impl FnMut(u32, Vec<(u8, Vec<u8>)>, &mut Sender) -> Vec<Vec<u8>> + Send + 'static,
) -> (FlyReport, Vec<(u32, Sent)>) {
    let mut a = vehicle_sender();
    let t0 = Instant::now();
    fly_against_turns(max_duration_s, tweak, false, move |k| {
        // Turns paced at 50 ms (the link's silences as long as the frames' rate says).
        let due = Duration::from_millis(50 * k as u64);
        if let Some(wait) = due.checked_sub(t0.elapsed()) {
            std::thread::sleep(wait);
        }
        let ms = 1000 + 50 * k;
        let msgs = if k % every == 0 {
            vec![beat(k), iso_s(ms, 9.5), position(ms, 0.0)]
        } else {
            vec![iso_s(ms, 9.5), position(ms, 0.0), position(ms + 1, 0.0)]
        };
        let frames = a.frames(&msgs);
        link(k, frames, &mut a)
    })
}

/// Asserts that nothing was commanded against the pilot's MANUAL heard (no COMMAND_LONG at all:
/// the pilot put the vehicle in OFFBOARD, fly commanded nothing before either): the flight ends
/// as the pilot's (`pilot_took_over`), or `vehicle_lost` if the link still reads as two
/// senders, then with nothing commanded and the log saying why.
fn assert_nothing_against_the_pilot(r: &FlyReport, c: &[Sent]) {
    assert!(c.is_empty(), "{c:?} {:?}", r.events);
    assert!(!r.way_out_commanded, "{:?}", r.events);
    match r.end {
        FlyEnd::PilotTookOver => {}
        FlyEnd::VehicleLost => assert!(
            r.events.iter().any(|e| e.contains(
                "showed it armed in MANUAL (a pilot's word, or the second sender's): setpoints stopped, nothing commanded, the pilot's mode stands"
            )),
            "{:?}",
            r.events
        ),
        e => panic!("{e:?}: {:?}", r.events),
    }
}

/// att39f-1 (F9b): one sender; the pilot's MANUAL heard (turn 60); at turn 66 the link holds
/// the last two frames before a burst of 200 frames sent at once and lost, and delivers the
/// first frame after the burst, then the two held ones newest first (numbers N_A + 201, N_A,
/// N_A - 1), then on. No command may go out after the MANUAL heartbeat, whatever the verdict
/// on the senders. Before (fly39): `vehicle_lost` "goes on from the counter's ...", HOLD
/// commanded against the pilot (7 DO_SET_MODE).
#[test]
fn a_swap_across_a_burst_after_a_pilots_manual_commands_nothing() {
    let mut held: Vec<Vec<u8>> = Vec::new();
    let (r, c) = pilot_manual_over_a_link(move |k, frames, a| {
        let mut out: Vec<Vec<u8>> = frames.into_iter().map(|f| f.1).collect();
        if k == 66 {
            held = out.split_off(1);
            a.seq = a.seq.wrapping_add(200);
        } else if k == 67 {
            let rest = out.split_off(1);
            out.extend(held.drain(..).rev());
            out.extend(rest);
        }
        out
    });
    assert_nothing_against_the_pilot(&r, &c);
}

/// att39f-2 (F3c): one sender; the pilot's MANUAL heard (turn 60); at turn 66 a burst of 200
/// frames sent at once is lost, six frames come, then the next 52 frames (a fade at the usual
/// rate, shorter than the last 64 frames took: no restart of the watch) are lost, then on. No
/// command may go out after the MANUAL heartbeat. Before (fly39): `vehicle_lost`, HOLD
/// commanded against the pilot.
#[test]
fn a_burst_then_a_fade_after_a_pilots_manual_commands_nothing() {
    let mut seen_after = 0u32;
    let mut lose = 0u32;
    let (r, c) = pilot_manual_over_a_link(move |k, frames, a| {
        if k == 66 {
            a.seq = a.seq.wrapping_add(200);
        }
        // (The frames of turn 66 were numbered before the burst: the burst comes after them.)
        let mut out = Vec::new();
        for (_, f) in frames {
            if k > 66 && seen_after < 6 {
                seen_after += 1;
                if seen_after == 6 {
                    lose = 52;
                }
            } else if lose > 0 {
                lose -= 1;
                continue;
            }
            out.push(f);
        }
        out
    });
    assert_nothing_against_the_pilot(&r, &c);
}

/// How a slow twin numbers its frames ([`vehicle_with_a_slow_twin`]).
#[derive(Clone, Copy, Debug)]
enum TwinCounter {
    /// Each frame numbered the vehicle's last number + this (a spoofer reading the link).
    Near(i32),
    /// Its own counter, starting this many numbers ahead of the vehicle's.
    Free(u8),
}

/// att39f-3's stand-in: in control (the pilot's OFFBOARD; three frames a 50 ms turn, paced on
/// the wall clock, a heartbeat every fourth turn), a second sender with the vehicle's ids
/// beats armed in MANUAL once a second (every 20 turns) from turn 40, numbered by `counter`.
/// The report and the commands fly sent.
fn vehicle_with_a_slow_twin(counter: TwinCounter) -> (FlyReport, Vec<Sent>) {
    vehicle_with_a_slow_beat(counter, heartbeat(1))
}

/// [`vehicle_with_a_slow_twin`], the second sender's heartbeat being `twin_beat`.
fn vehicle_with_a_slow_beat(counter: TwinCounter, twin_beat: MavMessage) -> (FlyReport, Vec<Sent>) {
    let mut a = vehicle_sender();
    let mut free: Option<Sender> = None;
    let t0 = Instant::now();
    fly_against_seen(
        12.0,
        |_| {},
        false,
        move |k| {
            let due = Duration::from_millis(50 * k as u64);
            if let Some(wait) = due.checked_sub(t0.elapsed()) {
                std::thread::sleep(wait);
            }
            let ms = 1000 + 50 * k;
            let msgs = if k % 4 == 0 {
                vec![heartbeat(6), iso_s(ms, 9.5), position(ms, 0.0)]
            } else {
                vec![iso_s(ms, 9.5), position(ms, 0.0), position(ms + 1, 0.0)]
            };
            let mut out = datagrams(a.frames(&msgs));
            if k >= 40 && k % 20 == 0 {
                let last = a.seq.wrapping_sub(1);
                let b = match counter {
                    TwinCounter::Near(off) => free.insert(Sender {
                        seq: (last as i32 + off).rem_euclid(256) as u8,
                        ids: (1, 1),
                    }),
                    TwinCounter::Free(ahead) => free.get_or_insert_with(|| Sender {
                        seq: last.wrapping_add(ahead),
                        ids: (1, 1),
                    }),
                };
                out.extend(datagrams(b.frames(std::slice::from_ref(&twin_beat))));
            }
            out
        },
    )
}

/// The wall time of the first event starting `what` ("wall T s: what...").
fn event_time_s(r: &FlyReport, what: &str) -> Option<f64> {
    r.events.iter().find_map(|e| {
        let (t, rest) = e.strip_prefix("wall ")?.split_once(" s: ")?;
        rest.starts_with(what).then(|| t.parse().ok()).flatten()
    })
}

/// att39f-3 (N22, N23, N18): a second sender beating armed in MANUAL once a second beside the
/// vehicle's 60 frames a second, numbered 3 behind or 3 ahead of the vehicle's last number, or
/// with its own counter 60 ahead, ends the flight `vehicle_lost` within a few seconds of its
/// first frame (2 s in: turn 40), never `pilot_took_over` and never flown to the end. Where its
/// MANUAL heartbeat was applied as the vehicle's before the proof, nothing is commanded
/// (att39f-1); else the HOLD. Before (fly39): N22 never proven (a resync each second, flown to
/// max_duration), N23 and N18 `pilot_took_over` "no second sender ... seen".
#[test]
fn a_slow_twin_near_the_vehicles_counter_is_proven() {
    for counter in [
        TwinCounter::Near(-3),
        TwinCounter::Near(3),
        TwinCounter::Free(60),
    ] {
        let (r, c) = vehicle_with_a_slow_twin(counter);
        assert_eq!(r.end, FlyEnd::VehicleLost, "{counter:?}: {:?}", r.events);
        assert!(
            !r.events.iter().any(|e| e.contains("pilot_took_over")),
            "{counter:?}: {:?}",
            r.events
        );
        let at = event_time_s(&r, "vehicle_lost");
        assert!(
            at.is_some_and(|t| t < 7.0),
            "{counter:?}: {at:?} {:?}",
            r.events
        );
        if !r.way_out_commanded {
            assert_word_before_the_proof_commands_nothing(&r);
            assert!(c.is_empty(), "{counter:?}: {c:?}");
        }
    }
}

/// The turns of the mode commands (`DO_SET_MODE`) fly sent.
fn mode_command_turns(c: &[(u32, Sent)]) -> Vec<u32> {
    c.iter()
        .filter(|x| x.1 .0 == SET_MODE)
        .map(|x| x.0)
        .collect()
}

/// att41f-2 (Q1): in control (the pilot's OFFBOARD), Ctrl-C at 1.5 s: HOLD commanded, never
/// shown by the vehicle (it stays in OFFBOARD), retried every 0.3 s. One sender whose link
/// loses a burst of 200 frames sent at once at turn 50 (a doubt, resynchronised as one sender
/// after 48 frames); the pilot switches to MANUAL at turn 80 (a word awaiting confirmation: no
/// retry meanwhile); a second burst of 200 at turn 86, within 5 s of the resync: a second
/// sender by rule (c). The pilot's word was heard before the proof: the retries stop with
/// nothing more commanded, as for a word heard before a proof that ends the flight
/// (att39f-1). Before: the retries resumed at the proof, HOLD every 0.3 s against the pilot's
/// MANUAL to the retries' bound.
#[test]
fn a_second_sender_proven_after_a_pilots_word_in_the_retries_stops_them() {
    let (r, c) = manual_over_a_link(
        80,
        30.0,
        |o| {
            o.timeout_s = 3.0;
            let stop = o.stop.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(1500));
                stop.store(true, std::sync::atomic::Ordering::SeqCst);
            });
        },
        |k, frames, a| {
            if k == 50 || k == 86 {
                a.seq = a.seq.wrapping_add(200);
            }
            frames.into_iter().map(|f| f.1).collect()
        },
    );
    let modes = mode_command_turns(&c);
    // The Ctrl-C's HOLD went out, and none once fly had the MANUAL heartbeat (turn 80; a
    // command read at turn 81 may have left before it).
    assert!(
        modes.first().is_some_and(|&k| k < 80),
        "{c:?} {:?}",
        r.events
    );
    assert!(modes.iter().all(|&k| k <= 81), "{c:?} {:?}", r.events);
    assert!(!disarm_sent(&c.iter().map(|x| x.1).collect::<Vec<_>>()));
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "showed it in MANUAL (a pilot's word, or the second sender's, awaiting confirmation): the retries stop, nothing more commanded"
        )),
        "{:?}",
        r.events
    );
}

/// att41f-3 (E9): in control (the pilot's OFFBOARD), one sender whose link loses a burst of 200
/// frames sent at once at turn 40 and another at turn 70, within 5 s of the first's resync: a
/// second sender by rule (c) (one sender read as two, FLYING.md), no word heard before:
/// `vehicle_lost`, HOLD commanded (never shown: the vehicle stays in OFFBOARD). The pilot then
/// switches to MANUAL (turn 100): a heartbeat of the ids showing a mode the companion did not
/// command, the pilot's or the second sender's: the retries stop, nothing more commanded.
/// Before: HOLD retried against the pilot's MANUAL to the retries' bound (3 x --timeout-s).
#[test]
fn a_mode_nobody_commanded_after_a_proof_stops_the_retries() {
    let (r, c) = manual_over_a_link(
        100,
        30.0,
        |o| o.timeout_s = 3.0,
        |k, frames, a| {
            if k == 40 || k == 70 {
                a.seq = a.seq.wrapping_add(200);
            }
            frames.into_iter().map(|f| f.1).collect()
        },
    );
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    let modes = mode_command_turns(&c);
    // HOLD went out after the proof, and none once fly had the MANUAL heartbeat (turn 100; a
    // command read at turn 101 may have left before it).
    assert!(
        modes.first().is_some_and(|&k| (70..100).contains(&k)),
        "{c:?} {:?}",
        r.events
    );
    assert!(modes.iter().all(|&k| k <= 101), "{c:?} {:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "a heartbeat of the ids shows in MANUAL, which the companion did not command: a pilot's or the second sender's; nothing more commanded"
        )),
        "{:?}",
        r.events
    );
}

/// The vehicle's heartbeat in PX4's HOLD (AUTO.LOITER), armed or not.
fn heartbeat_hold(armed: bool) -> MavMessage {
    let mut hb = heartbeat_sub(4, 3);
    if let (false, MavMessage::HEARTBEAT(h)) = (armed, &mut hb) {
        h.base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
    }
    hb
}

/// A turn's frames as sent: each one's number and bytes.
type Frames = Vec<(u8, Vec<u8>)>;

/// The links of att42f's tests: one sender that loses a burst of 200 frames sent at once
/// after the frames of turn `first` and another after those of turn `second` (the turns'
/// frames otherwise delivered as sent).
fn two_bursts(
    first: u32,
    second: u32,
) -> impl FnMut(u32, Frames, &mut Sender) -> Vec<Vec<u8>> + Send + 'static {
    move |k, frames, a| {
        if k == first || k == second {
            a.seq = a.seq.wrapping_add(200);
        }
        frames.into_iter().map(|f| f.1).collect()
    }
}

/// att42f-5 (in flight): in control (the pilot's OFFBOARD, PX4's 1 Hz heartbeat: every 20
/// turns, three frames a turn), one sender whose link loses a burst of 200 frames at turn 50
/// (a doubt from turn 51, resynchronised after 48 frames, about turn 67) and another at turn
/// 70, within 5 s of the resync: a second sender by rule (c) at turn 71. The pilot switches
/// to MANUAL at turn 60: its only heartbeat before the proof (turn 60) came inside the doubt.
/// A word heard in a doubt counts as a pilot's word awaiting confirmation: nothing is
/// commanded against it. Before: nothing in a doubt counted, so `vehicle_lost` commanded HOLD
/// against the pilot's MANUAL.
#[test]
fn a_pilots_word_heard_in_a_doubt_then_a_proof_commands_nothing() {
    let beat = |k: u32| heartbeat(if k < 60 { 6 } else { 1 });
    let (r, c) = beats_over_a_link(20, beat, 12.0, |o| o.timeout_s = 3.0, two_bursts(50, 70));
    let c: Vec<Sent> = c.into_iter().map(|x| x.1).collect();
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert_nothing_against_the_pilot(&r, &c);
}

/// att42f-5 (in the retries): as [`a_pilots_word_heard_in_a_doubt_then_a_proof_commands_nothing`],
/// but Ctrl-C at 1.5 s (turn 30) started the failsafe first: HOLD commanded every 0.3 s, never
/// shown (the vehicle stays in OFFBOARD). The pilot's MANUAL heartbeat at turn 60, inside the
/// doubt, holds the retries as a word awaiting confirmation; the proof at turn 71 stops them
/// with nothing more commanded (as att41f-2 for a word applied before the proof). Before: the
/// retries went on through the doubt and after the proof, HOLD against the pilot's MANUAL every
/// 0.3 s until the heartbeat at turn 80 showed it.
#[test]
fn a_pilots_word_heard_in_a_doubt_in_the_retries_stops_them_at_the_proof() {
    let beat = |k: u32| heartbeat(if k < 60 { 6 } else { 1 });
    let (r, c) = beats_over_a_link(
        20,
        beat,
        30.0,
        |o| {
            o.timeout_s = 3.0;
            support_stop_after(o, 1.5);
        },
        two_bursts(50, 70),
    );
    let modes = mode_command_turns(&c);
    // The Ctrl-C's HOLD went out, and none once fly had the MANUAL heartbeat (turn 60; a
    // command read at turn 61 may have left before it).
    assert!(
        modes.first().is_some_and(|&k| k < 60),
        "{c:?} {:?}",
        r.events
    );
    assert!(modes.iter().all(|&k| k <= 61), "{c:?} {:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "showed it in MANUAL (a pilot's word, or the second sender's, awaiting confirmation): the retries stop, nothing more commanded"
        )),
        "{:?}",
        r.events
    );
}

/// Sets `o.stop` (Ctrl-C) after `s` seconds.
fn support_stop_after(o: &FlyOptions, s: f64) {
    let stop = o.stop.clone();
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs_f64(s));
        stop.store(true, std::sync::atomic::Ordering::SeqCst);
    });
}

/// Whether every mode command after the first was read in the turn of a heartbeat at a
/// multiple of 20 in `beats`, or the next (a retry sent on that heartbeat).
fn retries_follow_beats(modes: &[u32], beats: std::ops::Range<u32>) -> bool {
    modes.iter().skip(1).all(|&k| {
        [k, k.saturating_sub(1)]
            .iter()
            .any(|b| b % 20 == 0 && beats.contains(b))
    })
}

/// att42f-2: in control (the pilot's OFFBOARD, PX4's 1 Hz heartbeat), one sender whose link
/// loses two bursts of 200 frames within 5 s (turns 40 and 70): a second sender by rule (c)
/// at turn 71, `vehicle_lost`, HOLD commanded. The vehicle stays in OFFBOARD (heartbeats at
/// turns 80, 100, 120), then shows HOLD from turn 140. After the proof a retry goes out only
/// on a heartbeat showing the vehicle still in OFFBOARD, at once (in that heartbeat's turn or
/// the next), never on one showing HOLD: 1 + 3 HOLDs. Before: a retry every 0.3 s (6 turns)
/// whatever the heartbeats showed, HOLD too, to the retries' bound (a pilot's switch between
/// a heartbeat and the next retry overridden at each).
#[test]
fn after_a_proof_a_retry_only_follows_a_heartbeat_in_offboard() {
    let beat = |k: u32| {
        if k < 130 {
            heartbeat(6)
        } else {
            heartbeat_hold(true)
        }
    };
    let (r, c) = beats_over_a_link(20, beat, 30.0, |o| o.timeout_s = 3.0, two_bursts(40, 70));
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    let modes = mode_command_turns(&c);
    assert!(
        modes.first().is_some_and(|&k| (70..80).contains(&k)),
        "{modes:?} {:?}",
        r.events
    );
    assert!(
        retries_follow_beats(&modes, 80..121),
        "{modes:?} {:?}",
        r.events
    );
    assert_eq!(modes.len(), 4, "{modes:?} {:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(!r.way_out_overridden, "{:?}", r.events);
}

/// att42f-1: as [`after_a_proof_a_retry_only_follows_a_heartbeat_in_offboard`], the vehicle
/// in HOLD from turn 100 (armed), then disarmed in HOLD from turn 140: a disarm of a vehicle
/// armed as the failsafe began, which the companion did not command (it sends no disarm after
/// a second sender): a pilot's or the second sender's word, the retries stop, nothing more
/// commanded. Before: a disarmed heartbeat in the failsafe mode was no answer, and HOLD went on
/// every 0.3 s to the retries' bound.
#[test]
fn after_a_proof_a_disarm_nobody_commanded_in_hold_stops_the_retries() {
    let beat = |k: u32| match k {
        0..100 => heartbeat(6),
        100..140 => heartbeat_hold(true),
        _ => heartbeat_hold(false),
    };
    let (r, c) = beats_over_a_link(20, beat, 30.0, |o| o.timeout_s = 3.0, two_bursts(40, 70));
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    let modes = mode_command_turns(&c);
    assert!(modes.iter().all(|&k| k <= 141), "{modes:?} {:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    assert!(!disarm_sent(&c.iter().map(|x| x.1).collect::<Vec<_>>()));
    assert!(
        r.events.iter().any(|e| e.contains(
            "a heartbeat of the ids shows disarmed, which the companion did not command: a pilot's or the second sender's; nothing more commanded"
        )),
        "{:?}",
        r.events
    );
}

/// In control (the pilot's OFFBOARD, a heartbeat every 4 turns, one sender over `link`), Ctrl-C
/// at 2.5 s starts the failsafe (HOLD, never shown); the pilot switches to MANUAL at turn 80,
/// which the heartbeats show for the span: the retries stop, nothing more commanded. Asserts
/// that the log says "a pilot's or the second sender's" for `why`, never asserting a pilot
/// (`pilot_took_over`), and returns the report.
fn change_in_the_retries_hedged(
    link: impl FnMut(u32, Frames, &mut Sender) -> Vec<Vec<u8>> + Send + 'static,
    why: &str,
) -> FlyReport {
    let (r, _) = manual_over_a_link(
        80,
        30.0,
        |o| {
            o.timeout_s = 3.0;
            support_stop_after(o, 2.5);
        },
        link,
    );
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    assert!(
        !r.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        r.events
    );
    let said = format!("the heartbeats of the vehicle's ids show it in MANUAL, which the companion did not command: a pilot's or the second sender's ({why}");
    assert!(r.events.iter().any(|e| e.contains(&said)), "{:?}", r.events);
    r
}

/// att42f-3: [`change_in_the_retries_hedged`], one sender whose link loses a burst of 200
/// frames at turn 30 (a doubt, resynchronised as one sender before the failsafe): the frame
/// counter was in doubt before. Before: "pilot_took_over during the failsafe".
#[test]
fn a_change_in_the_retries_after_a_doubt_is_not_asserted_a_pilots() {
    let r = change_in_the_retries_hedged(
        move |k, frames, a| {
            if k == 30 {
                a.seq = a.seq.wrapping_add(200);
            }
            frames.into_iter().map(|f| f.1).collect()
        },
        "their frame counter was in doubt before",
    );
    assert_eq!(resyncs(&r), 1, "{:?}", r.events);
}

/// att42f-3: [`change_in_the_retries_hedged`], the link holding the last OFFBOARD heartbeat
/// (turn 76) and delivering it after the first MANUAL one (turn 80): a heartbeat older than
/// the last applied came during the retries (a second counter ahead would make the vehicle's
/// own so; here one sender's late one, which nothing tells apart). Before: "pilot_took_over
/// during the failsafe".
#[test]
fn a_change_in_the_retries_after_an_older_heartbeat_is_not_asserted_a_pilots() {
    let mut held = Vec::new();
    let r = change_in_the_retries_hedged(
        move |k, frames, _| {
            let mut out: Vec<Vec<u8>> = frames.into_iter().map(|f| f.1).collect();
            if k == 76 {
                held = out.remove(0);
            } else if k == 80 {
                out.insert(1, std::mem::take(&mut held));
            }
            out
        },
        "a heartbeat of the ids older than the last applied came during the retries",
    );
    assert_eq!(resyncs(&r), 0, "{:?}", r.events);
}

/// att42f-4: in control (the pilot's OFFBOARD), a ground station misconfigured with the
/// vehicle's ids (its own counter, 60 ahead) beats once a second from turn 40
/// (`MAV_TYPE_GCS`, `MAV_AUTOPILOT_INVALID`, `base_mode` 0). Its heartbeat is never the
/// vehicle's state: never read as "disarmed", nor as another vehicle's type; its frames count
/// in the frame counter as any of the ids' (a second sender there, then `vehicle_lost` with
/// HOLD retried, or flown to the end). Before: at its first heartbeat "a heartbeat of
/// MAV_TYPE_GCS ... after the vehicle's", HOLD, and its next one read as the vehicle
/// "disarmed", which stopped the retries.
#[test]
fn a_ground_stations_heartbeat_with_the_vehicles_ids_is_no_state() {
    let gcs = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    });
    let (r, c) = vehicle_with_a_slow_beat(TwinCounter::Free(60), gcs);
    assert!(
        matches!(r.end, FlyEnd::VehicleLost | FlyEnd::MaxDuration),
        "{:?}",
        r.events
    );
    assert!(
        !r.events
            .iter()
            .any(|e| ["MAV_TYPE_GCS", "shows disarmed", "vehicle disarmed"]
                .iter()
                .any(|w| e.contains(w))),
        "{:?}",
        r.events
    );
    assert!(!r.way_out_overridden, "{:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(
        c.iter().filter(|x| x.0 == SET_MODE).count() >= 3,
        "{c:?} {:?}",
        r.events
    );
}

/// A Ctrl-C (the stop flag set) `ms` after the flight starts.
fn ctrl_c_at(ms: u64) -> impl FnOnce(&mut FlyOptions) {
    move |o| {
        let stop = o.stop.clone();
        std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(ms));
            stop.store(true, std::sync::atomic::Ordering::SeqCst);
        });
    }
}

/// `fly` against a vehicle (ids 1, 1) on wall time, a Ctrl-C at 1.5 s (in control: the
/// pilot's OFFBOARD), so that the failsafe's HOLD (never acknowledged) is retried from then:
/// each turn (every 50 ms) `turn(t_s, ms, a)` gives the datagrams, each with the socket (0 or
/// 1: two source addresses) it leaves from, `a` the vehicle's frame counter, `ms` 1000 + the
/// wall time since the start, ms.
fn in_the_retries(
    mut turn: impl FnMut(f64, u32, &mut Sender) -> Vec<(usize, Vec<u8>)>,
) -> (FlyReport, Vec<(u32, usize, Sent)>) {
    let mut a = vehicle_sender();
    let t0 = Instant::now();
    fly_against_sockets(30.0, ctrl_c_at(1500), false, move |_| {
        let t_s = t0.elapsed().as_secs_f64();
        turn(t_s, 1000 + (t_s * 1000.0) as u32, &mut a)
    })
}

/// `datagrams` all leaving from socket `sock`.
fn from_socket(sock: usize, datagrams: Vec<Vec<u8>>) -> Vec<(usize, Vec<u8>)> {
    datagrams.into_iter().map(|d| (sock, d)).collect()
}

/// The way out's last word ("the vehicle did not confirm the HOLD (N tries, WHY)"), if any.
fn way_out_end(r: &FlyReport) -> &str {
    r.events
        .iter()
        .rev()
        .find(|e| e.contains("did not confirm the") || e.contains("the vehicle is in"))
        .map_or("", |e| e.as_str())
}

/// Asserts that the failsafe's way out ended with a line holding `text` ([`way_out_end`]; the
/// events shown when it did not).
#[track_caller]
fn assert_way_out_end(r: &FlyReport, text: &str) {
    assert!(way_out_end(r).contains(text), "{:?}", r.events);
}

/// att45f-1: during the failsafe's retries (HOLD, never carried out: the vehicle stays
/// armed in OFFBOARD, then falls silent at 2 s), a second vehicle with the ids beats armed in
/// AUTO.LOITER (the HOLD commanded) at 1 Hz from ANOTHER source address, on the very numbers
/// the vehicle's counter would go on with (only the address tells the two apart). As in
/// control, the second address is a second sender: no heartbeat confirms the HOLD, and none of
/// its heartbeats in the `--failsafe` mode is a reason to retry (no command ever reaches its
/// address). Before: its heartbeats "confirmed" the HOLD ("the vehicle is in HOLD", exit 75)
/// and the retries went to its address, nothing logged of a second sender.
#[test]
fn a_twin_at_another_address_in_the_retries_confirms_nothing() {
    let mut own = Beats::new(0.0, &[1.0]);
    let (r, c) = in_the_retries(move |t, ms, a| {
        let beat = own.due(t);
        if t < 2.0 {
            from_socket(0, turn_frames(a, beat.then(|| heartbeat(6)), ms))
        } else {
            let hb: Vec<MavMessage> = beat.then(|| heartbeat_sub(4, 3)).into_iter().collect();
            from_socket(1, datagrams(a.frames(&hb)))
        }
    });
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e
            .contains("during the failsafe's retries, two vehicles with the ids")
            && e.contains("frames from")),
        "{:?}",
        r.events
    );
    assert_way_out_end(&r, "did not confirm the HOLD");
    assert!(!c.iter().any(|x| x.1 == 1), "{c:?}");
}

/// att45f-2: during the failsafe's retries the vehicle's positions alternate between the
/// origin and 11 km north from 1.8 s (two vehicles' positions interleaving, 11 km in 50 ms),
/// and from 2.2 s its heartbeats show AUTO.LOITER (the HOLD). As in control, the jumps are a
/// second sender: no heartbeat confirms the HOLD. Before: the jumps were never checked in the
/// retries, "the vehicle is in HOLD" at the third heartbeat in it, exit 75.
#[test]
fn positions_jumping_in_the_retries_confirm_nothing() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut far = false;
    let (r, _) = in_the_retries(move |t, ms, a| {
        let hb = own.due(t).then(|| {
            if t < 2.2 {
                heartbeat(6)
            } else {
                heartbeat_sub(4, 3)
            }
        });
        far = t >= 1.8 && !far;
        let mut msgs: Vec<MavMessage> = hb.into_iter().collect();
        msgs.extend([
            iso_s(ms, 9.5),
            position(ms, if far { 11_000.0 } else { 0.0 }),
        ]);
        from_socket(0, datagrams(a.frames(&msgs)))
    });
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e
            .contains("during the failsafe's retries, two vehicles with the ids")
            && e.contains("positions jumped farther")),
        "{:?}",
        r.events
    );
    assert_way_out_end(&r, "did not confirm the HOLD");
}

/// att45f-5: during the failsafe's retries the vehicle's heartbeats show it DISARMED in
/// AUTO.LOITER (the HOLD commanded) from 2.2 s: the companion commanded no disarm, so it is a
/// pilot's word whatever mode it shows (`pilot_took_over during the failsafe`, the HOLD not
/// confirmed). Before: "the vehicle is in HOLD", exit 75, the disarm never logged.
#[test]
fn a_disarm_shown_in_hold_during_the_retries_is_the_pilots() {
    let mut own = Beats::new(0.0, &[1.0]);
    let (r, _) = in_the_retries(move |t, ms, a| {
        let hb = own.due(t).then(|| {
            if t < 2.2 {
                heartbeat(6)
            } else {
                let mut hb = heartbeat_sub(4, 3);
                if let MavMessage::HEARTBEAT(h) = &mut hb {
                    h.base_mode = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
                }
                hb
            }
        });
        from_socket(0, turn_frames(a, hb, ms))
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("pilot_took_over during the failsafe: the vehicle is disarmed")),
        "{:?}",
        r.events
    );
}

/// att45f-3: the vehicle falls silent at 2 s, during the failsafe's retries; a ground
/// station misconfigured with its ids (`MAV_TYPE_GCS`, on the vehicle's counter) beats on at
/// 1 Hz. Its heartbeat says nothing of the vehicle's link, as in control: the retries end
/// "link lost" once no autopilot's heartbeat came for 3 s (at 4 s: the last one at 1 s),
/// before their bound (7.5 s). Before: "retries' bound reached".
#[test]
fn a_ground_stations_heartbeat_keeps_no_link_in_the_retries() {
    let gcs = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    });
    let mut own = Beats::new(0.0, &[1.0]);
    let (r, _) = in_the_retries(move |t, ms, a| {
        let beat = own.due(t);
        if t < 2.0 {
            from_socket(0, turn_frames(a, beat.then(|| heartbeat(6)), ms))
        } else {
            let hb: Vec<MavMessage> = beat.then(|| gcs.clone()).into_iter().collect();
            from_socket(0, datagrams(a.frames(&hb)))
        }
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert_way_out_end(&r, "link lost)");
}

/// att45f-10: during the failsafe's retries every time the vehicle stamps (its position's
/// `time_boot_ms`) drops by 50 s at 2 s, and goes on from there: its clock began again, as in
/// control its autopilot rebooted: logged, the retries stop with nothing more commanded.
/// Before: the reboot check was off in the retries, nothing logged, HOLD retried to the bound.
#[test]
fn a_reboot_during_the_retries_is_told() {
    let mut own = Beats::new(0.0, &[1.0]);
    let (r, _) = in_the_retries(move |t, ms, a| {
        let clock = if t < 2.0 { ms + 60_000 } else { ms + 10_000 };
        let mut msgs: Vec<MavMessage> = own.due(t).then(|| heartbeat(6)).into_iter().collect();
        msgs.extend([iso_s(ms, 9.5), position(clock, 0.0)]);
        from_socket(0, datagrams(a.frames(&msgs)))
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    support::assert_logged(
        &r,
        &[
            "during the failsafe's retries, vehicle_lost: the vehicle's clock (time_boot_ms) went back",
            "its autopilot rebooted",
        ],
    );
    assert_way_out_end(&r, "its autopilot rebooted)");
}

/// `fly` in control (the pilot's OFFBOARD) against a vehicle (1 Hz heartbeat; its measurement
/// and position each 50 ms turn, the measurement on its own steady clock) whose clock (the
/// position's `time_boot_ms`) goes back 50 s at 2 s (its autopilot rebooted) and, if
/// `again_s`, 50 s more then (a second reboot); from 2.5 s its heartbeats show AUTO.LOITER, the
/// HOLD the failsafe commands (it obeyed).
fn rebooted_in_control(again_s: Option<f64>) -> FlyReport {
    clock_back_in_control(again_s, 50_000, false, heartbeat_sub(4, 3))
}

/// [`rebooted_in_control`], the clock going back `back_ms` (twice that from `again_s`), the
/// measurement stamped by the vehicle's clock too if `shared` (as the autopilot's own `ISO_S`),
/// the heartbeats from 2.5 s `after`.
fn clock_back_in_control(
    again_s: Option<f64>,
    back_ms: u32,
    shared: bool,
    after: MavMessage,
) -> FlyReport {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut a = vehicle_sender();
    let t0 = Instant::now();
    fly_against(30.0, move |_| {
        let t = t0.elapsed().as_secs_f64();
        let ms = 1000 + (t * 1000.0) as u32;
        let back = match (t >= 2.0, again_s.is_some_and(|s| t >= s)) {
            (_, true) => 2 * back_ms,
            (true, false) => back_ms,
            (false, false) => 0,
        };
        let hb = own
            .due(t)
            .then(|| if t < 2.5 { heartbeat(6) } else { after.clone() });
        let mut msgs: Vec<MavMessage> = hb.into_iter().collect();
        let clock = ms + 200_000 - back;
        msgs.extend([
            iso_s(if shared { clock } else { ms }, 9.5),
            position(clock, 0.0),
        ]);
        datagrams(a.frames(&msgs))
    })
}

/// att49f-2 (M3): in control the vehicle's clock goes back 50 s at 2 s: its autopilot
/// rebooted, `vehicle_lost`, HOLD commanded; it obeys (AUTO.LOITER from 2.5 s). The reboot
/// that caused the failsafe is no new one for the retries' reboot watch, which goes on from
/// the rebooted clock: the HOLD is confirmed once its heartbeats have shown it for the span
/// ("the vehicle is in HOLD", exit 75), the reboot logged once. Before (fly45 to fly50): the
/// retries' watch caught the same clock step ("went back from 203.0 s", the same reference)
/// a frame later and stopped them: "did not confirm the HOLD (1 tries, its autopilot
/// rebooted)", exit 69.
#[test]
fn a_reboot_in_control_is_no_new_one_in_the_retries() {
    let r = rebooted_in_control(None);
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(r.failsafe_acknowledged, "{:?}", r.events);
    assert_way_out_end(&r, "the vehicle is in HOLD (");
    let reboots = support::logged(&r, &["its autopilot rebooted"]);
    assert_eq!(reboots, 1, "{:?}", r.events);
}

/// att49f-2, the other side (att45f-10's RB2): in control the vehicle's clock goes back 50 s at
/// 2 s (`vehicle_lost`, HOLD commanded), and 50 s more at 2.3 s, before any heartbeat shows
/// the HOLD: a second reboot, after the one that caused the failsafe, found by the retries'
/// watch from the rebooted clock: the retries stop, nothing more commanded, the HOLD not
/// confirmed.
#[test]
fn a_second_reboot_in_the_retries_is_told() {
    let r = rebooted_in_control(Some(2.3));
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    support::assert_logged(
        &r,
        &["during the failsafe's retries, vehicle_lost: the vehicle's clock (time_boot_ms) went back from 153."],
    );
    assert_way_out_end(&r, "its autopilot rebooted)");
}

/// att53f-1 (A11): in control the vehicle's clock, which stamps its measurement too (an
/// autopilot's own `ISO_S`), goes back 65 s at 2 s: the measurement's step (more than 60 s)
/// fires `sensor_clock_jump`, HOLD commanded; the vehicle obeys (AUTO.LOITER from 2.5 s). The
/// vehicle's own frames went back with it: one step, seen once, no reboot found again by the
/// retries' watch: the HOLD is confirmed once its heartbeats have shown it for the span ("the
/// vehicle is in HOLD", exit 75), "its autopilot rebooted" never logged. Before: the retries'
/// watch found the same step a frame later ("went back from 203.0 s"): "did not confirm the
/// HOLD (1 tries, its autopilot rebooted)", exit 69.
#[test]
fn a_clock_step_that_fired_sensor_clock_jump_is_no_reboot_in_the_retries() {
    let r = clock_back_in_control(None, 65_000, true, heartbeat_sub(4, 3));
    assert_eq!(r.end, FlyEnd::SensorClockJump, "{:?}", r.events);
    assert!(r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        way_out_end(&r).contains("the vehicle is in HOLD ("),
        "{:?}",
        r.events
    );
    assert_eq!(
        support::logged(&r, &["its autopilot rebooted"]),
        0,
        "{:?}",
        r.events
    );
}

/// att53f-4 (A15): in control (the pilot's OFFBOARD; its clock stamps its positions) two
/// positions at the vehicle's address and on its counter (a second sender with its ids, in step)
/// come at 2 s stamped 50 s behind the vehicle's clock: read as its autopilot's reboot,
/// `vehicle_lost`, HOLD commanded (its heartbeats show AUTO.LOITER from 2.5 s). Then the
/// vehicle's own clock comes back 50 s ahead of the rebooted one: no rebooted autopilot does
/// that, two clocks are two senders, so the retries go on as for two senders (no heartbeat
/// confirms, to the bound), and a second such pair at 3.5 s is no second reboot. Before: the
/// clock back ahead was taken silently, and the second pair stopped the retries ("(1 tries,
/// its autopilot rebooted)").
#[test]
fn a_clock_back_then_ahead_again_is_two_senders() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut a = vehicle_sender();
    let mut pairs = [(2.0, false), (3.5, false)];
    let t0 = Instant::now();
    let r = fly_against(30.0, move |_| {
        let t = t0.elapsed().as_secs_f64();
        let ms = 1000 + (t * 1000.0) as u32;
        let hb = own.due(t).then(|| {
            if t < 2.5 {
                heartbeat(6)
            } else {
                heartbeat_sub(4, 3)
            }
        });
        let mut msgs: Vec<MavMessage> = hb.into_iter().collect();
        msgs.extend([iso_s(ms, 9.5), position(ms + 60_000, 0.0)]);
        for (at_s, done) in pairs.iter_mut() {
            if t >= *at_s && !*done {
                *done = true;
                msgs.extend([position(ms + 10_000, 0.0), position(ms + 10_020, 0.0)]);
            }
        }
        datagrams(a.frames(&msgs))
    });
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "two vehicles with the ids (system 1, component 1): the vehicle's clock (time_boot_ms) went back from"
        ) && e.contains("no rebooted autopilot's clock runs ahead so")),
        "{:?}",
        r.events
    );
    let reboots = r
        .events
        .iter()
        .filter(|e| e.contains("its autopilot rebooted"))
        .count();
    assert!(reboots <= 1, "{:?}", r.events);
    assert!(
        way_out_end(&r).contains("retries' bound reached; a second sender"),
        "{:?}",
        r.events
    );
}

/// att53f-3 (A8b, A18): in control the vehicle's clock goes back 50 s at 2 s (its autopilot
/// rebooted: `vehicle_lost`, HOLD commanded), and from 2.5 s its heartbeats show it as a
/// rebooted autopilot comes up, disarmed in MANUAL. What it shows after the reboot is the
/// reboot's, no pilot's word: once it has stood, the retries stop "its autopilot rebooted",
/// nothing more commanded, no pilot's take-over logged or reported. Before: "pilot_took_over
/// during the failsafe: the vehicle is disarmed ...: the pilot's mode stands", "a pilot took
/// over during the retries" (exit 69 as now).
#[test]
fn a_rebooted_autopilots_disarm_in_the_retries_is_no_pilots() {
    let r = clock_back_in_control(None, 50_000, false, heartbeat_disarmed(1));
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(!r.way_out_overridden, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "during the failsafe's retries, the heartbeats of the vehicle's ids show it disarmed, which the companion did not command: its autopilot rebooted (its clock went back from "
        )),
        "{:?}",
        r.events
    );
    assert!(
        !r.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        r.events
    );
    assert!(
        way_out_end(&r).contains("its autopilot rebooted)"),
        "{:?}",
        r.events
    );
}

/// att53f-2 (C9): during the failsafe's retries (Ctrl-C at 1.5 s; the HOLD never carried out,
/// the vehicle armed in OFFBOARD) the vehicle falls silent from 2.1 s to 3.6 s (1.5 s: less
/// than `--timeout-s`) and comes back disarmed, its clock not stepped: a pilot's disarm, or
/// its autopilot rebooted with a clock that did not go back far enough to show. As in control,
/// the line that ends the retries says so: "pilot_took_over during the failsafe: the vehicle
/// is disarmed, not commanded by the companion (or its autopilot rebooted: it was silent for
/// more than 1 s before the disarm)". Before: no word of a reboot.
#[test]
fn a_disarm_after_a_silence_in_the_retries_may_be_a_reboot() {
    let mut own = Beats::new(0.0, &[1.0]);
    let (r, _) = in_the_retries(move |t, ms, a| {
        if (2.1..3.6).contains(&t) {
            return Vec::new();
        }
        let hb = own.due(t).then(|| {
            if t < 2.1 {
                heartbeat(6)
            } else {
                heartbeat_disarmed(6)
            }
        });
        from_socket(0, turn_frames(a, hb, ms))
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "pilot_took_over during the failsafe: the vehicle is disarmed, not commanded by the companion (or its autopilot rebooted: it was silent for more than 1 s before the disarm)"
        )),
        "{:?}",
        r.events
    );
}

/// att53f-8 (tk12): `--take-control` of a vehicle its pilot armed in POSCTL (one frame each
/// 20 ms of its clock, its measurement and position in turn, its heartbeat each second; the
/// switch to OFFBOARD goes out at 2 s, unanswered). At 3.0 s its counter comes back 100 (a
/// doubt: nothing of the ids applied), and from then its heartbeats show OFFBOARD; it sends no
/// measurement from 3.0 s to 5.2 s. The doubt resynchronises (48 frames and 0.5 s, or 64: by
/// 4.3 s), and the first heartbeat applied after it gives control (at 4.0 or 5.0 s), before any
/// measurement came since. The measurement held from before the doubt (stamped 3.96 s) is
/// dropped at the resync: the law starts from the first one after it (stamped 6.2 s, the
/// vehicle's clock 1 s ahead of the frames' 20 ms grid), and `--max-duration-s` counts from
/// there. Before: the law's first answer was to the one held from before the doubt.
#[test]
fn control_after_a_resync_starts_on_a_measurement_after_it() {
    let mut a = vehicle_sender();
    let (mut next_s, mut k) = (0.0f64, 0u32);
    let t0 = Instant::now();
    let tweak = |o: &mut FlyOptions| {
        o.take_control = true;
        o.timeout_s = 3.0;
    };
    let r = fly_against_with(2.0, tweak, false, move |_| {
        let t = t0.elapsed().as_secs_f64();
        let mut out = Vec::new();
        // One frame every 20 ms of wall time, however the turns go (caught up).
        while next_s <= t {
            let ms = 1000 + 20 * k;
            if k == 150 {
                a.seq = a.seq.wrapping_sub(100);
            }
            let measured = k.is_multiple_of(2) && !(150..260).contains(&k);
            let mut msgs = vec![if measured {
                iso_s(ms, 9.5)
            } else {
                position(ms, 0.0)
            }];
            if k.is_multiple_of(50) {
                msgs.push(match k {
                    ..150 => heartbeat(3),
                    150..400 => heartbeat(6),
                    _ => heartbeat_sub(4, 3),
                });
            }
            out.extend(datagrams(a.frames(&msgs)));
            k += 1;
            next_s += 0.02;
        }
        out
    });
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("resynchronised as one sender")),
        "{:?}",
        r.events
    );
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    let first = r.commands.first().map(|c| c.0);
    assert!(
        first.is_some_and(|ms| ms >= 1000 + 20 * 260),
        "{first:?} {:?}",
        r.events
    );
}

/// The vehicle's frames of one turn from socket 0 (its 1 Hz heartbeat in OFFBOARD from `own`,
/// its measurement and its position stamped with its clock, `ms` + 60 s), and, once at `twin_s`
/// and later, a second sender's two positions from socket 1 on the numbers the vehicle's counter
/// goes on with, stamped with ITS clock, 50 s behind the vehicle's.
fn vehicle_and_twins_clock(
    own: &mut Beats,
    twin_s: f64,
    paired: &mut bool,
    t: f64,
    ms: u32,
    a: &mut Sender,
) -> Vec<(usize, Vec<u8>)> {
    let mut msgs: Vec<MavMessage> = own.due(t).then(|| heartbeat(6)).into_iter().collect();
    msgs.extend([iso_s(ms, 9.5), position(ms + 60_000, 0.0)]);
    let mut out = from_socket(0, datagrams(a.frames(&msgs)));
    if t >= twin_s && !*paired {
        *paired = true;
        let twin = [position(ms + 10_000, 0.0), position(ms + 10_020, 0.0)];
        out.extend(from_socket(1, datagrams(a.frames(&twin))));
    }
    out
}

/// att53f-6: during the failsafe's retries (Ctrl-C at 1.5 s; the HOLD never carried out, the
/// vehicle armed in OFFBOARD, beating at 1 Hz) a second vehicle with the ids beats once from
/// ANOTHER address at 1.8 s (two senders proven), then at 2.5 s sends two positions stamped
/// with its own clock, 50 s behind the vehicle's. Two senders' clocks interleaved are no reboot
/// of the vehicle flown: the two-sender retries go on, a HOLD on each OFFBOARD heartbeat to the
/// bound (3 x 2 s from 1.5 s: the vehicle's beats at 2 to 7 s, one HOLD each, and the first at
/// 1.5 s), never "its autopilot rebooted". Before: the pair read as the vehicle's reboot stopped
/// them ("(2 tries, its autopilot rebooted)"), the vehicle left in OFFBOARD.
#[test]
fn a_second_senders_clock_after_the_proof_is_no_reboot() {
    let mut own = Beats::new(0.0, &[1.0]);
    let (mut told, mut paired) = (false, false);
    let (r, c) = in_the_retries(move |t, ms, a| {
        let mut out = vehicle_and_twins_clock(&mut own, 2.5, &mut paired, t, ms, a);
        if t >= 1.8 && !told {
            told = true;
            out.extend(from_socket(1, datagrams(a.frames(&[heartbeat(6)]))));
        }
        out
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert_eq!(
        support::logged(&r, &["its autopilot rebooted"]),
        0,
        "{:?}",
        r.events
    );
    assert!(
        way_out_end(&r).contains("retries' bound reached; a second sender"),
        "{:?}",
        r.events
    );
    let holds = c
        .iter()
        .filter(|x| x.1 == 0 && x.2 .0 == SET_MODE && x.2 .1[1] == 4.0)
        .count();
    assert!(holds >= 5, "{holds} {c:?} {:?}", r.events);
}

/// att53f-7: in control (the pilot's OFFBOARD) a second vehicle with the ids sends from ANOTHER
/// address at 2 s its first frames, two positions stamped with its own clock, 50 s behind the
/// vehicle's. The second address proves two senders at the first of them, and the second is
/// no reboot: the flight ends `vehicle_lost` naming the two addresses, the HOLD commanded as
/// for two senders, never "its autopilot rebooted". Before: the pair read as the vehicle's
/// reboot was logged first ("its autopilot rebooted"), the two addresses never named.
#[test]
fn a_second_address_with_its_own_clock_is_no_reboot() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut a = vehicle_sender();
    let mut paired = false;
    let t0 = Instant::now();
    let (r, _) = fly_against_sockets(
        30.0,
        |_| {},
        false,
        move |_| {
            let t = t0.elapsed().as_secs_f64();
            let ms = 1000 + (t * 1000.0) as u32;
            vehicle_and_twins_clock(&mut own, 2.0, &mut paired, t, ms, &mut a)
        },
    );
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    assert!(r.way_out_commanded, "{:?}", r.events);
    assert!(
        r.events.iter().any(|e| e.contains(
            "vehicle_lost: two vehicles with the ids (system 1, component 1): frames from"
        )),
        "{:?}",
        r.events
    );
    assert_eq!(
        support::logged(&r, &["its autopilot rebooted"]),
        0,
        "{:?}",
        r.events
    );
}

/// att45f-4: during the failsafe's retries the vehicle's frame counter jumps back 100 at
/// 2.05 s (a doubt opens) and a heartbeat in the doubt shows it armed in MANUAL (a pilot's
/// word awaiting confirmation: no retry meanwhile); the counter goes on from there (the
/// doubt resynchronises as one sender) and the heartbeats applied after it show OFFBOARD again.
/// As in control, a word contradicted with a doubt between is two senders', no change and back
/// of one: the retries stop with nothing more commanded. Before: the word was forgotten, the
/// HOLD retried to the bound, not a word of it logged.
#[test]
fn a_word_in_a_doubt_contradicted_in_the_retries_is_two_senders() {
    let mut own = Beats::new(0.0, &[1.0]);
    let (mut jumped, mut manual) = (false, false);
    let (r, c) = in_the_retries(move |t, ms, a| {
        if t >= 2.05 && !jumped {
            jumped = true;
            a.seq = a.seq.wrapping_sub(100);
        }
        let mut hb = own.due(t).then(|| heartbeat(6));
        if t >= 2.15 && !manual {
            manual = true;
            hb = Some(heartbeat(1));
        }
        from_socket(0, turn_frames(a, hb, ms))
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    support::assert_logged(
        &r,
        &[
            "during the failsafe's retries, two vehicles with the ids",
            "the heartbeats showed it in MANUAL, then armed in OFFBOARD, with 1 doubt",
        ],
    );
    assert_way_out_end(&r, "a pilot's word before a second sender)");
    assert!(c.len() <= 4 + 2, "{c:?}");
}

/// att49f-3 (R8b): during the failsafe's retries (Ctrl-C at 1.5 s; the HOLD never carried
/// out, the vehicle armed in OFFBOARD) the vehicle's counter jumps back 100 at 2.0 s, onto
/// numbers seen (a doubt), and its heartbeat in the doubt (2.1 s) shows it armed in MANUAL (a
/// pilot's word awaiting confirmation: no retry meanwhile). Its frames (one every 20 ms, on its
/// own schedule) resynchronise the doubt as one sender within 64 frames (by 3.3 s); its next
/// heartbeat, applied (3.5 s), shows MANUAL again, and those from 4.5 s OFFBOARD. The word was
/// FIRST heard in the doubt: a heartbeat applied that contradicts it has a doubt between, two
/// senders, however many applied ones repeated it after the resync; as in control (C8b), the
/// retries stop, nothing more commanded, the MANUAL logged. Before: the applied MANUAL took
/// the word as new (no doubt since), the OFFBOARD heartbeat forgot it, and the HOLD was
/// retried from 4.5 s to the bound, the MANUAL never logged.
#[test]
fn a_word_in_a_doubt_repeated_after_the_resync_then_contradicted_is_two_senders() {
    let (mut next_s, mut k) = (0.0f64, 0u32);
    let (r, c) = in_the_retries(move |t, _, a| {
        let mut out = Vec::new();
        // One step every 20 ms of wall time, however the turns go (caught up).
        while next_s <= t {
            let ms = 1000 + 20 * k;
            if k == 100 {
                a.seq = a.seq.wrapping_sub(100);
            }
            let mut msgs = vec![if k.is_multiple_of(2) {
                iso_s(ms, 9.5)
            } else {
                position(ms, 0.0)
            }];
            if k == 105 || k == 175 {
                msgs.push(heartbeat(1));
            } else if (k < 100 && k.is_multiple_of(50)) || (k >= 225 && (k + 25).is_multiple_of(50))
            {
                msgs.push(heartbeat(6));
            }
            out.extend(datagrams(a.frames(&msgs)));
            k += 1;
            next_s += 0.02;
        }
        from_socket(0, out)
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert!(r.way_out_overridden, "{:?}", r.events);
    support::assert_logged(
        &r,
        &[
            "during the failsafe's retries, two vehicles with the ids",
            "the heartbeats showed it in MANUAL, then armed in OFFBOARD, with 1 doubt",
        ],
    );
    assert_way_out_end(&r, "a pilot's word before a second sender)");
    // The tries before the word (1.5 s to 2.1 s, one each 0.3 s), none after it.
    assert!(c.len() <= 4, "{c:?} {:?}", r.events);
}

/// att45f-9: during the failsafe's retries a second autopilot (system 1, component 2, a PX4
/// rover armed in MANUAL, its own address and counter) beats at 1 Hz from 2.3 s: never flown,
/// logged once as in control. Before: never logged in the retries.
#[test]
fn another_autopilot_first_heard_in_the_retries_is_logged() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(2.3, &[1.0]);
    let mut b = Sender {
        seq: 0,
        ids: (1, 2),
    };
    let (r, _) = in_the_retries(move |t, ms, a| {
        let mut out = from_socket(0, turn_frames(a, own.due(t).then(|| heartbeat(6)), ms));
        if other.due(t) {
            out.extend(from_socket(1, datagrams(b.frames(&[heartbeat(1)]))));
        }
        out
    });
    assert!(
        r.events
            .iter()
            .any(|e| e
                .contains("another autopilot (system 1, component 2) heard in flight: not flown")),
        "{:?}",
        r.events
    );
}

/// An unaddressed `COMMAND_ACK`: `DO_SET_MODE` accepted.
fn set_mode_accepted() -> MavMessage {
    MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
        command: MavCmd::MAV_CMD_DO_SET_MODE,
        result: MavResult::MAV_RESULT_ACCEPTED,
    })
}

/// att45f-7: `--take-control` of a vehicle its pilot armed in POSCTL (1 Hz heartbeat): it
/// accepts every `DO_SET_MODE` (an acknowledgement each turn: the switch goes out at 2 s) and
/// never leaves POSCTL. From 3.5 s a second vehicle with its ids beats armed in POSCTL from
/// another address: a second sender, `vehicle_lost`, HOLD commanded once (an OFFBOARD was
/// accepted). The POSCTL its heartbeats show is the pilot's mode (the companion armed nothing),
/// no reason for a retry: one HOLD in all. Before: a HOLD on every POSCTL heartbeat of either, to the bound.
#[test]
fn after_a_proof_a_pilots_mode_is_no_reason_to_retry() {
    let mut own = Beats::new(0.0, &[1.0]);
    let mut other = Beats::new(3.5, &[1.0]);
    let mut a = vehicle_sender();
    let t0 = Instant::now();
    let (r, c) = fly_against_sockets(
        30.0,
        |o| o.take_control = true,
        false,
        move |_| {
            let t = t0.elapsed().as_secs_f64();
            let ms = 1000 + (t * 1000.0) as u32;
            let hb = own.due(t).then(|| heartbeat(3));
            let mut msgs: Vec<MavMessage> = hb.into_iter().collect();
            msgs.extend([iso_s(ms, 9.5), position(ms, 0.0), set_mode_accepted()]);
            let mut out = from_socket(0, datagrams(a.frames(&msgs)));
            if t >= 3.5 && other.due(t) {
                out.extend(from_socket(1, datagrams(a.frames(&[heartbeat(3)]))));
            }
            out
        },
    );
    assert_eq!(r.end, FlyEnd::VehicleLost, "{:?}", r.events);
    let holds: Vec<_> = c
        .iter()
        .filter(|x| x.2 .0 == SET_MODE && x.2 .1[1] == 4.0 && x.1 == 0)
        .collect();
    assert_eq!(holds.len(), 1, "{c:?} {:?}", r.events);
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
}

/// fly47: in the failsafe's retries (Ctrl-C at 1.5 s; HOLD never acknowledged, the vehicle
/// stays armed in OFFBOARD), the vehicle's counter comes back 12 numbers behind at 2 s onto
/// numbers seen (a burst lost: a doubt), and its unchanging 1 Hz heartbeat always carries the
/// number of its last one before the doubt: identical to it, a copy in the old window. Its
/// other frames (10 a second, on its own schedule) keep the doubt open 4.8 s (48 frames). A
/// heartbeat heard while a doubt is open is the link speaking: the retries go to their bound
/// (6 s). Before: "no heartbeat from the vehicle for 3 s" at 4 s, the retries ended "link
/// lost".
#[test]
fn heartbeats_heard_as_copies_in_a_doubt_keep_the_link() {
    let mut next_s = 0.0f64;
    let mut k = 0u32;
    let mut beat_seq: Option<u8> = None;
    let (r, _) = in_the_retries(move |t, _, a| {
        let mut out = Vec::new();
        // One frame every 100 ms of wall time, however the turns go (caught up).
        while next_s <= t {
            let ms = 1000 + (next_s * 1000.0) as u32;
            let mut msgs = Vec::new();
            if k == 20 {
                // The counter comes back onto numbers seen: a first conflict, a doubt.
                a.seq = a.seq.wrapping_sub(12);
            }
            msgs.push(if k.is_multiple_of(2) {
                iso_s(ms, 9.5)
            } else {
                position(ms, 0.0)
            });
            out.extend(datagrams(a.frames(&msgs)));
            if k.is_multiple_of(10) {
                let hb = heartbeat(6);
                match beat_seq {
                    // From the doubt on, on the number of the last one before it.
                    Some(s) if k >= 20 => {
                        let mut copy = Sender { seq: s, ids: a.ids };
                        out.extend(datagrams(copy.frames(&[hb])));
                    }
                    _ => {
                        beat_seq = Some(a.seq);
                        out.extend(datagrams(a.frames(&[hb])));
                    }
                }
            }
            k += 1;
            next_s += 0.1;
        }
        from_socket(0, out)
    });
    assert_eq!(r.end, FlyEnd::Interrupted, "{:?}", r.events);
    assert_way_out_end(&r, "retries' bound reached");
    assert!(
        !r.events.iter().any(|e| e.contains("no heartbeat")),
        "{:?}",
        r.events
    );
}

/// att49f-1: the vehicle (armed, OFFBOARD: in control) sends its position at 20 Hz and its
/// heartbeat at 1 Hz, its measurement coming from another component of its system (1, 2) at
/// 20 Hz throughout (a sensor that never stops). At 2.0 s its counter comes back 20 numbers,
/// onto numbers seen (a doubt), at 2.1 s one more heartbeat, after 2.15 s nothing new: from 2.2 s a repeater
/// re-sends the exact bytes of that last heartbeat every second (a copy in the doubt, which
/// counts frames and so never settles). Copies keep the link only as of the vehicle's last
/// frame that was none: `link_lost` within the heartbeat timeout (max(`--timeout-s` 2 s, 3 s))
/// of that frame, plus a poll's slack, never before `--timeout-s` after it; the doubt logged
/// as it opened. Before: the copies kept the link to `max_duration` (12 s), no line of the doubt.
#[test]
fn copies_of_a_dead_vehicles_heartbeat_in_a_doubt_keep_no_link() {
    const LAST_NEW_S: f64 = 2.15;
    let mut a = vehicle_sender();
    let mut sensor = Sender {
        seq: 0,
        ids: (1, 2),
    };
    let mut k = 0u32;
    let mut last_beat: Vec<Vec<u8>> = Vec::new();
    let t0 = Instant::now();
    let r = fly_against(12.0, move |_| {
        // One step every 50 ms of wall time, caught up after a slow turn.
        let now_s = t0.elapsed().as_secs_f64();
        let mut out = Vec::new();
        while 0.05 * k as f64 <= now_s {
            let ms = 1000 + 50 * k;
            out.extend(datagrams(sensor.frames(&[iso_s(ms, 9.5)])));
            if k == 40 {
                a.seq = a.seq.wrapping_sub(20);
            }
            if k <= 43 {
                out.extend(datagrams(a.frames(&[position(ms, 0.0)])));
            }
            if (k < 40 && k.is_multiple_of(20)) || k == 42 {
                last_beat = datagrams(a.frames(&[heartbeat(6)]));
                out.extend(last_beat.clone());
            } else if k >= 44 && (k - 44).is_multiple_of(20) {
                out.extend(last_beat.clone());
            }
            k += 1;
        }
        out
    });
    assert_eq!(r.end, FlyEnd::LinkLost, "{:?}", r.events);
    let lost_s = event_time_s(&r, "no message from the vehicle")
        .or_else(|| event_time_s(&r, "no heartbeat from the vehicle"))
        .expect("the link lost logged");
    assert!(
        lost_s > LAST_NEW_S + 2.0 - 0.2 && lost_s < LAST_NEW_S + 3.0 + 1.0,
        "{lost_s} {:?}",
        r.events
    );
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("the vehicle's frame counter in doubt: a frame numbered")),
        "{:?}",
        r.events
    );
}

/// att49f-1 in the failsafe's retries (01/D1R): the vehicle (its measurement and position
/// every 100 ms, its heartbeat in OFFBOARD each second: the HOLD never confirmed) comes back
/// 12 numbers on its counter at 2.0 s, onto numbers seen (a doubt), beats once more at 2.1 s, then sends nothing new; a
/// repeater re-sends that last heartbeat's bytes every second. The copies keep the link only
/// as of its last frame that was none: the retries end "link lost" (by about 5.1 s) before
/// their bound (7.5 s). Before: "retries' bound reached", the copies keeping the link.
#[test]
fn copies_of_a_dead_vehicles_heartbeat_in_a_doubt_keep_no_link_in_the_retries() {
    let mut next_s = 0.0f64;
    let mut k = 0u32;
    let mut last_beat: Vec<Vec<u8>> = Vec::new();
    let (r, _) = in_the_retries(move |t, _, a| {
        let mut out = Vec::new();
        // One step every 100 ms of wall time, however the turns go (caught up).
        while next_s <= t {
            let ms = 1000 + 100 * k;
            if k == 20 {
                a.seq = a.seq.wrapping_sub(12);
            }
            if k <= 21 {
                out.extend(datagrams(a.frames(&[iso_s(ms, 9.5), position(ms, 0.0)])));
            }
            if (k < 20 && k.is_multiple_of(10)) || k == 21 {
                last_beat = datagrams(a.frames(&[heartbeat(6)]));
                out.extend(last_beat.clone());
            } else if k >= 22 && (k - 22).is_multiple_of(10) {
                out.extend(last_beat.clone());
            }
            k += 1;
            next_s += 0.1;
        }
        from_socket(0, out)
    });
    assert!(!r.failsafe_acknowledged, "{:?}", r.events);
    assert_way_out_end(&r, "link lost)");
}
