//! A fixed wing's altitude hold never flies on a stale altitude (issue 33, hostile pass): a
//! pilot's vehicle in OFFBOARD reports 100 m, then 90 m (10 m low: the hold's pitch
//! `0.02 rad/m x (10 - 2) m = 0.16 rad` nose up), then its positions stop while its
//! measurements go on. Once the last altitude is older than `--timeout-s` it is unknown: the
//! setpoints' pitch is 0 (logged once), not the frozen error's 0.16 rad for ever.

use isotrack_mavlink::fly::{run_fly, FlyEnd, FlyOptions};
use isotrack_mavlink::link::Link;
use isotrack_scenario::load_scenario;
use isotrack_sim::NoTrace;
use mavlink::dialects::common::*;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The pitch of an attitude quaternion `[w, x, y, z]` (ZYX Euler angles).
fn pitch_of(q: [f32; 4]) -> f64 {
    let [w, x, y, z] = q.map(f64::from);
    (2.0 * (w * y - z * x)).clamp(-1.0, 1.0).asin()
}

#[test]
fn a_stale_altitude_is_unknown_not_flown_on() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let mut o = FlyOptions::new("udpin:127.0.0.1:0");
    o.timeout_s = 1.0;
    o.max_duration_s = Some(5.0);
    let (tx, rx) = std::sync::mpsc::channel();
    let companion = std::thread::spawn(move || {
        run_fly(&s, &o, &mut NoTrace, &mut |l| {
            tx.send(l.local_addr()?).unwrap();
            Ok(())
        })
        .unwrap()
    });
    let addr = rx.recv().unwrap();
    let mut v = Link::open(&format!("udpout:{addr}"), 1, 1).unwrap();
    // (wall time since the positions stopped, pitch) of each setpoint.
    let mut pitches: Vec<(Option<Duration>, f64)> = Vec::new();
    let (mut beat, mut stopped_at) = (0u32, None);
    let t0 = Instant::now();
    while !companion.is_finished() && t0.elapsed() < Duration::from_secs(60) {
        v.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 6 << 16,
            mavtype: MavType::MAV_TYPE_FIXED_WING,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                | MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }))
        .unwrap();
        let mut name = [0u8; 10];
        name[..5].copy_from_slice(b"ISO_S");
        v.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
            time_boot_ms: 1000 + 50 * beat,
            value: 10.0,
            name: name.into(),
        }))
        .unwrap();
        if beat < 40 {
            v.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                time_boot_ms: 1000 + 50 * beat,
                z: if beat < 20 { -100.0 } else { -90.0 },
                ..Default::default()
            }))
            .unwrap();
        } else if stopped_at.is_none() {
            stopped_at = Some(Instant::now());
        }
        beat += 1;
        // One beat per 50 ms of wall time: the vehicle's clock keeps to the wall's.
        let next = t0 + Duration::from_millis(50 * beat as u64);
        while Instant::now() < next {
            for r in v
                .poll(next.saturating_duration_since(Instant::now()))
                .unwrap()
            {
                if let MavMessage::SET_ATTITUDE_TARGET(a) = &r.msg {
                    pitches.push((stopped_at.map(|t| t.elapsed()), pitch_of(a.q)));
                }
            }
        }
    }
    let r = companion.join().unwrap();
    assert_eq!(r.end, FlyEnd::MaxDuration, "{:?}", r.events);
    // 10 m low: 0.02 rad/m x (10 m - the 2 m dead zone), nose up, while the altitude is fresh.
    let held = pitches.iter().filter(|(t, _)| t.is_none()).map(|p| p.1);
    assert!(
        held.clone().any(|p| (p - 0.16).abs() < 1e-6),
        "{:?}",
        pitches
    );
    // Well past the 1 s timeout after the positions stopped: pitch 0.
    let late: Vec<f64> = pitches
        .iter()
        .filter(|(t, _)| t.is_some_and(|t| t > Duration::from_millis(1500)))
        .map(|p| p.1)
        .collect();
    assert!(!late.is_empty(), "{pitches:?}");
    assert!(late.iter().all(|&p| p == 0.0), "{late:?}");
    assert!(
        r.events
            .iter()
            .any(|e| e.contains("no altitude from the vehicle")),
        "{:?}",
        r.events
    );
}
