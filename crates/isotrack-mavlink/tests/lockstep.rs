//! `fly` against `sitl` in lockstep over UDP loopback, both in this process on threads (each on
//! a port of its own: the vehicle binds port 0), against the in-process mirror.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions, FlyReport};
use isotrack_mavlink::link::Link;
use isotrack_mavlink::mirror::{mirror, Rounding, Transport};
use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions, SitlReport};
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::{NoTrace, TraceRow, TraceSink};
use mavlink::dialects::common::*;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::mpsc;

fn scenario(name: &str, set: &[&str]) -> Scenario {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name);
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    load_scenario(Some(&p), &set).expect("scenario")
}

/// A trace sink that tells a channel about its first row (the companion's first answer).
struct Notify(Option<mpsc::Sender<()>>);
impl TraceSink for Notify {
    fn record(&mut self, _row: &TraceRow) {
        if let Some(tx) = self.0.take() {
            let _ = tx.send(());
        }
    }
}

/// Runs a lockstep sitl on a thread and `fly` here; `during` runs on another thread once the
/// companion has answered its first measurement, with the vehicle's address. Stops the vehicle
/// once the companion has ended (a failsafe leaves the lockstep vehicle waiting).
fn flight(
    s: &Scenario,
    fly_opts: impl FnOnce(&mut FlyOptions),
    during: impl FnOnce(std::net::SocketAddr) + Send + 'static,
) -> (SitlReport, FlyReport) {
    let mut opts = SitlOptions::new("udpin:127.0.0.1:0");
    opts.pace = Pace::Lockstep;
    let stop = opts.stop.clone();
    let (addr_tx, addr_rx) = mpsc::channel();
    let sim = s.clone();
    let vehicle = std::thread::spawn(move || {
        run_sitl(&sim, &opts, &mut NoTrace, &mut |a| addr_tx.send(a).unwrap()).expect("sitl")
    });
    let addr = addr_rx.recv().unwrap();
    let mut fo = FlyOptions::new(&format!("udpout:{addr}"));
    fo.take_control = true;
    fo.arm = true;
    fo.timeout_s = 30.0;
    fly_opts(&mut fo);
    let (first_tx, first_rx) = mpsc::channel();
    let side = std::thread::spawn(move || {
        if first_rx.recv().is_ok() {
            during(addr);
        }
    });
    let report = run_fly(s, &fo, &mut Notify(Some(first_tx)), &mut |_| Ok(())).expect("fly");
    stop.store(true, Ordering::SeqCst);
    let v = vehicle.join().unwrap();
    side.join().unwrap();
    (v, report)
}

/// The lockstep flight's commands are the mirror's, bit for bit, and so is the run; the
/// mirror without rounding is `isotrack run` itself, bit for bit.
fn reproduces(name: &str, set: &[&str]) {
    let s = scenario(name, set);
    let m = mirror(&s, Rounding::Wire, &mut NoTrace);
    let (v, f) = flight(&s, |_| {}, |_| {});
    assert_eq!(f.end, FlyEnd::VehicleEnded, "{:?}", f.events);
    assert!(!m.commands.is_empty());
    assert_eq!(f.commands.len(), m.commands.len());
    assert_eq!(f.commands, m.commands, "the law's commands");
    let t = Transport::of(&s);
    let flown: Vec<(u32, f64)> = m.commands.iter().map(|&(ms, w)| (ms, t.flown(w))).collect();
    assert_eq!(v.flown, flown, "the turn rates flown");
    assert_eq!(format!("{:?}", v.result), format!("{:?}", m.result));
    assert_eq!(v.setpoints_refused, 0);
    // The mirror without rounding is the scenario's own run.
    let exact = mirror(&s, Rounding::None, &mut NoTrace);
    assert_eq!(
        format!("{:?}", exact.result),
        format!("{:?}", s.run(&mut NoTrace))
    );
}

#[test]
fn lockstep_fig3_uav_reproduces_the_in_process_run() {
    reproduces("paper-fig3-uav.toml", &[]);
}

#[test]
fn lockstep_fig2b_dubins_reproduces_the_in_process_run() {
    reproduces("paper-fig2b-circular.toml", &["sim.duration_s=120"]);
}

/// The measurement rounded to f32 moves the fig. 3 flight by little: the same outcome and a
/// steady-state error within 10 % of the unrounded run's.
#[test]
fn wire_rounding_changes_the_fig3_flight_little() {
    let s = scenario("paper-fig3-uav.toml", &[]);
    let a = mirror(&s, Rounding::Wire, &mut NoTrace).result;
    let b = s.run(&mut NoTrace);
    assert_eq!(a.outcome, b.outcome);
    let (ea, eb) = (
        a.metrics.steady_state_max_abs_error.unwrap(),
        b.metrics.steady_state_max_abs_error.unwrap(),
    );
    assert!((ea - eb).abs() <= 0.1 * eb, "{ea} vs {eb}");
}

/// `--max-duration-s`: the companion stops after that much vehicle time (10 samples at 1 Hz),
/// and commands HOLD, which the vehicle acknowledges.
#[test]
fn max_duration_fails_safe_to_hold() {
    let s = scenario("paper-fig3-uav.toml", &[]);
    let (v, f) = flight(&s, |o| o.max_duration_s = Some(10.0), |_| {});
    assert_eq!(f.end, FlyEnd::MaxDuration);
    assert_eq!(f.commands.len(), 10);
    assert!(f.failsafe_acknowledged, "{:?}", f.events);
    assert!(
        v.events.iter().any(|e| e.contains("mode HOLD")),
        "{:?}",
        v.events
    );
}

/// `--fence-m`: the Dubins robot at 0.5 m/s leaves a 2 m fence within seconds; RETURN is
/// commanded.
#[test]
fn fence_fails_safe_to_return() {
    let s = scenario("paper-fig2b-circular.toml", &["sim.duration_s=60"]);
    let (v, f) = flight(
        &s,
        |o| {
            o.fence_m = Some(2.0);
            o.failsafe = isotrack_mavlink::fly::FailsafeAction::Return;
        },
        |_| {},
    );
    assert_eq!(f.end, FlyEnd::Fence);
    assert!(f.failsafe_acknowledged, "{:?}", f.events);
    assert!(
        v.events.iter().any(|e| e.contains("mode RETURN")),
        "{:?}",
        v.events
    );
}

/// Ctrl-C (the stop flag, set once the companion flies): setpoints stop, HOLD is commanded
/// and acknowledged.
#[test]
fn interrupt_fails_safe_to_hold() {
    let s = scenario("paper-fig3-uav.toml", &[]);
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let set = stop.clone();
    let (v, f) = flight(
        &s,
        |o| o.stop = stop.clone(),
        move |_| set.store(true, Ordering::SeqCst),
    );
    assert_eq!(f.end, FlyEnd::Interrupted);
    assert!(!f.commands.is_empty());
    assert!(f.failsafe_acknowledged, "{:?}", f.events);
    assert!(
        v.events.iter().any(|e| e.contains("mode HOLD")),
        "{:?}",
        v.events
    );
}

/// Sends one command as a ground station (system 255) to the vehicle at `addr`, from a link
/// of its own.
fn pilot_command(addr: std::net::SocketAddr, command: MavCmd, p: [f32; 3]) {
    let mut gcs = Link::open(&format!("udpout:{addr}"), 255, 190).unwrap();
    gcs.send(&MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p[0],
        param2: p[1],
        param3: p[2],
        command,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    }))
    .unwrap();
    // Keep the socket until the vehicle has read the command (its acknowledgement arrives).
    let t0 = std::time::Instant::now();
    while t0.elapsed() < std::time::Duration::from_secs(10) {
        if gcs
            .poll(std::time::Duration::from_millis(50))
            .unwrap()
            .iter()
            .any(|r| matches!(&r.msg, MavMessage::COMMAND_ACK(a) if a.command == command))
        {
            return;
        }
    }
}

/// Whether the companion took the vehicle back after the pilot's `event`: an arming or an
/// OFFBOARD switch by another system than the ground station, after it.
fn taken_back(v: &SitlReport, event: &str) -> bool {
    let i = v
        .events
        .iter()
        .position(|e| e.contains(event))
        .unwrap_or_else(|| panic!("no `{event}` in {:?}", v.events));
    v.events[i + 1..]
        .iter()
        .any(|e| e.contains("armed by") || e.contains("mode OFFBOARD"))
}

/// A pilot (ground station, system 255) switches the flying vehicle to HOLD: the companion
/// ends at once (`pilot_took_over`), never switches back to OFFBOARD and commands nothing.
#[test]
fn pilot_switch_to_hold_ends_the_flight() {
    let s = scenario("paper-fig3-uav.toml", &[]);
    let (v, f) = flight(
        &s,
        |_| {},
        |addr| pilot_command(addr, MavCmd::MAV_CMD_DO_SET_MODE, [1.0, 4.0, 3.0]),
    );
    assert_eq!(f.end, FlyEnd::PilotTookOver, "{:?}", f.events);
    assert!(!f.end.is_failsafe());
    assert!(!taken_back(&v, "mode HOLD by system 255"), "{:?}", v.events);
    assert!(
        f.events.iter().any(|e| e.contains("pilot_took_over")),
        "{:?}",
        f.events
    );
}

/// A pilot disarms the flying vehicle (with PX4's force code): the companion ends at once and
/// does not arm it again.
#[test]
fn pilot_disarm_ends_the_flight() {
    let s = scenario("paper-fig3-uav.toml", &[]);
    let (v, f) = flight(
        &s,
        |_| {},
        |addr| {
            pilot_command(
                addr,
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                [0.0, 21196.0, 0.0],
            )
        },
    );
    assert_eq!(f.end, FlyEnd::PilotTookOver, "{:?}", f.events);
    assert!(!taken_back(&v, "disarmed by system 255"), "{:?}", v.events);
}
