//! `fly` against `sitl` in lockstep over UDP loopback, both in this process on threads (each on
//! a port of its own: the vehicle binds port 0), against the in-process mirror.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions, FlyReport};
use isotrack_mavlink::mirror::{mirror, Rounding, Transport};
use isotrack_mavlink::sitl::{run_sitl, Pace, SitlOptions, SitlReport};
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::{NoTrace, TraceRow, TraceSink};
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
