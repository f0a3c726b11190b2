//! `time_boot_ms` wraps at 2^32 ms (49.7 days after boot): a vehicle whose measurements step
//! 100 ms at a time across the wrap is flown on as any other (the law's time unwrapped, the
//! setpoints stamped with the wire's times), not failed safe as a clock jump.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions};
use isotrack_mavlink::link::Link;
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A ground rover (the default scenario's Dubins vehicle) a pilot armed and switched to
/// OFFBOARD (PX4 main mode 6): the companion has control from its first heartbeat.
fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 6 << 16,
        mavtype: MavType::MAV_TYPE_GROUND_ROVER,
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// 40 measurements 100 ms apart from 2^32 - 2000 ms on (20 before the wrap, 20 after), one per
/// 50 ms of wall time, then the last one again and again: the companion answers each one once,
/// in order, stamped with its wire time, and ends on sensor loss (the clock standing still),
/// never on a clock jump.
#[test]
fn a_measurement_clock_that_wraps_is_flown_on() {
    let s = load_scenario(None, &[]).unwrap();
    let times: Vec<u32> = (0..40u32)
        .map(|k| (u32::MAX - 1999).wrapping_add(100 * k))
        .collect();
    assert!(times[19] > u32::MAX - 200 && times[20] < 200);
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let finished = done.clone();
    let sent = times.clone();
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut i = 0;
        while t0.elapsed() < Duration::from_secs(20) && !finished.load(Ordering::SeqCst) {
            link.poll(Duration::from_millis(50)).unwrap();
            if link.has_peer() {
                link.send(&heartbeat()).unwrap();
                let mut name = [0u8; 10];
                name[..5].copy_from_slice(b"ISO_S");
                link.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                    time_boot_ms: sent[i.min(sent.len() - 1)],
                    value: 1.0,
                    name: name.into(),
                }))
                .unwrap();
                i += 1;
            }
        }
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 1.0;
    let r = run_fly(&s, &o, &mut NoTrace, &mut |_| Ok(())).unwrap();
    done.store(true, Ordering::SeqCst);
    vehicle.join().unwrap();
    assert_eq!(r.end, FlyEnd::SensorLost, "{:?}", r.events);
    let answered: Vec<u32> = r.commands.iter().map(|c| c.0).collect();
    assert_eq!(answered, times, "{:?}", r.events);
}
