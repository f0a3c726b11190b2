//! Issue 30 (fix30b), item 4: the Dubins robot's heading under a huge turn rate.

use isotrack_core::math::Vec2;
use isotrack_core::Vehicle;
use isotrack_vehicles::dubins::HEADING_WRAP_RAD;
use isotrack_vehicles::{Dubins, DubinsState};
use std::f64::consts::PI;

/// The heading was never wrapped, so a law with huge gains and no turn-rate limit drove it
/// past 1e16 rad, where `sin`/`cos` of it are noise. A turn of 1e13 rad/s (1e11 rad a step of
/// 0.01 s) now leaves it in `(-pi, pi]` after every step (it passes `HEADING_WRAP_RAD` at
/// once), equal to the exact remainder of the unwrapped step's heading modulo `2 pi`; the path
/// stays finite and within `v t` of the start; the lanes give the same bits; and a heading
/// within the bound is left as it is (its turn count kept).
#[test]
fn a_huge_turn_rate_keeps_the_heading_within_pi_and_the_path_within_v_t() {
    let d = Dubins { speed_mps: 0.5 };
    let dt = 0.01;
    let start = Vec2::new(1.0, -2.0);
    let mut s = DubinsState {
        position_m: start,
        heading_rad: 0.3,
    };
    let mut lanes = [s; 2];
    for k in 1..=5000u32 {
        let omega = if k % 3 == 0 { -1.3e13 } else { 1.0e13 };
        let before = s.heading_rad;
        d.step(&mut s, omega, dt);
        d.step_lanes(&mut lanes, &[omega, omega], dt);
        assert_eq!(lanes[0], s, "step {k}");
        assert!(s.heading_rad.abs() <= PI, "step {k}: {}", s.heading_rad);
        // The exact remainder (fmod) of the unwrapped heading, into (-pi, pi].
        let r = (before + omega * dt) % (2.0 * PI);
        let want = if r > PI {
            r - 2.0 * PI
        } else if r <= -PI {
            r + 2.0 * PI
        } else {
            r
        };
        assert_eq!(s.heading_rad, want, "step {k}");
        let t = f64::from(k) * dt;
        let from_start = (s.position_m - start).norm();
        assert!(s.position_m.x.is_finite() && s.position_m.y.is_finite());
        assert!(
            from_start <= 0.5 * t * (1.0 + 1e-12),
            "step {k}: {from_start} m"
        );
    }
    // A heading from before this bound: the first step wraps it.
    let mut far = DubinsState {
        position_m: Vec2::new(0.0, 0.0),
        heading_rad: 1.0e17,
    };
    assert!(far.heading_rad > HEADING_WRAP_RAD);
    d.step(&mut far, 0.0, dt);
    assert!(far.heading_rad.abs() <= PI, "{}", far.heading_rad);
    // Within the bound the heading is continuous: 9000 rad and a turn stay 9000 + 0.01 rad.
    let mut near = DubinsState {
        position_m: Vec2::new(0.0, 0.0),
        heading_rad: 9000.0,
    };
    assert!(near.heading_rad < HEADING_WRAP_RAD);
    d.step(&mut near, 1.0, dt);
    assert_eq!(near.heading_rad, 9000.0 + dt);
}
