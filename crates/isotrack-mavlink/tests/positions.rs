//! `fly`'s trace after an invalid position: a vehicle whose `LOCAL_POSITION_NED` turns `NaN`
//! for a while (it lost its position estimate) gives rows with no position (`NaN`) for those
//! measurements, never the last valid position repeated as if it were current.

use isotrack_mavlink::fly::{run_fly, FlyOptions};
use isotrack_mavlink::link::Link;
use isotrack_scenario::load_scenario;
use isotrack_sim::{TraceRow, TraceSink};
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

struct Rows(Vec<TraceRow>);

impl TraceSink for Rows {
    fn record(&mut self, row: &TraceRow) {
        self.0.push(*row);
    }
}

/// Measurement `k` at `1000 + 100 k` ms, after the position of the same time: `k` m east,
/// except `k` in 10..15, where the position is `NaN`. Rows 10 to 14 have no position; the
/// others have their own (`x = k`).
#[test]
fn rows_after_an_invalid_position_have_none() {
    let s = load_scenario(None, &[]).unwrap();
    let mut link = Link::open("udpin:127.0.0.1:0", 1, 1).unwrap();
    let addr = link.local_addr().unwrap();
    let done = Arc::new(AtomicBool::new(false));
    let finished = done.clone();
    let n = 25u32;
    let vehicle = std::thread::spawn(move || {
        let t0 = Instant::now();
        let mut k = 0u32;
        while t0.elapsed() < Duration::from_secs(20) && !finished.load(Ordering::SeqCst) {
            link.poll(Duration::from_millis(50)).unwrap();
            if !link.has_peer() {
                continue;
            }
            link.send(&heartbeat()).unwrap();
            let kk = k.min(n - 1);
            let ms = 1000 + 100 * kk;
            let x = if (10..15).contains(&kk) {
                f32::NAN
            } else {
                kk as f32
            };
            // NED: north x, east y.
            link.send(&MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
                time_boot_ms: ms,
                x: if x.is_nan() { f32::NAN } else { 0.0 },
                y: x,
                ..Default::default()
            }))
            .unwrap();
            let mut name = [0u8; 10];
            name[..5].copy_from_slice(b"ISO_S");
            link.send(&MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                time_boot_ms: ms,
                value: 1.0,
                name: name.into(),
            }))
            .unwrap();
            k += 1;
        }
    });
    let mut o = FlyOptions::new(&format!("udpout:{addr}"));
    o.timeout_s = 1.0;
    let mut rows = Rows(Vec::new());
    let r = run_fly(&s, &o, &mut rows, &mut |_| Ok(())).unwrap();
    done.store(true, Ordering::SeqCst);
    vehicle.join().unwrap();
    assert_eq!(rows.0.len(), n as usize, "{:?}", r.events);
    for (k, row) in rows.0.iter().enumerate() {
        assert_eq!(row.t_s, (1000 + 100 * k) as f64 / 1000.0);
        if (10..15).contains(&k) {
            assert!(row.x_m.is_nan() && row.y_m.is_nan(), "row {k}: {row:?}");
        } else {
            assert_eq!((row.x_m, row.y_m), (k as f64, 0.0), "row {k}");
        }
    }
}
