//! Closed-loop tests of the UAV: trimmed flight, loop step responses, steady turns, wind.

use super::autopilot::Commands;
use super::*;

fn uav(cfg: FixedWingConfig) -> FixedWing {
    FixedWing::new(cfg).unwrap()
}

fn fly(
    v: &FixedWing,
    s: &mut FixedWingState,
    cmd: &Commands,
    seconds: f64,
    mut each: impl FnMut(f64, &FixedWingState),
) {
    let n = (seconds / 0.01).round() as usize;
    for k in 0..n {
        v.step_with_commands(s, cmd, 0.01);
        each((k + 1) as f64 * 0.01, s);
    }
}

fn hold(v: &FixedWing, s: &FixedWingState) -> Commands {
    Commands {
        course_rad: s.course_rad,
        altitude_m: v.cfg.altitude_m,
        airspeed_mps: v.cfg.airspeed_mps,
    }
}

/// Straight trimmed flight holds altitude and airspeed in tight bands (with trim feed-forward).
#[test]
fn straight_trimmed_flight_holds_altitude_and_airspeed() {
    let v = uav(FixedWingConfig::default());
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    let cmd = hold(&v, &s);
    let (mut dh, mut dva, mut dchi): (f64, f64, f64) = (0.0, 0.0, 0.0);
    fly(&v, &mut s, &cmd, 60.0, |_, s| {
        dh = dh.max((-s.x[2] - 100.0).abs());
        dva = dva.max((v.air_data(s).va_mps - 30.0).abs());
        dchi = dchi.max((s.course_rad - cmd.course_rad).abs());
    });
    assert!(dh < 0.01, "altitude deviation {dh} m");
    assert!(dva < 0.01, "airspeed deviation {dva} m/s");
    assert!(dchi < 1e-3, "course deviation {dchi} rad");
    // Flying north at 30 m/s for 60 s.
    assert!((s.x[0] - 1800.0).abs() < 1.0, "pn {}", s.x[0]);
}

/// Without trim feed-forward (the original), the start from trim dips in airspeed (about
/// 1.6 m/s per the reference) and recovers.
#[test]
fn without_feedforward_the_original_dip_appears_and_recovers() {
    let v = uav(FixedWingConfig {
        trim_feedforward: false,
        ..FixedWingConfig::default()
    });
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    let cmd = hold(&v, &s);
    let mut dip: f64 = 0.0;
    let mut late: f64 = 0.0;
    fly(&v, &mut s, &cmd, 30.0, |t, s| {
        let e = 30.0 - v.air_data(s).va_mps;
        dip = dip.max(e);
        if t > 20.0 {
            late = late.max(e.abs());
        }
    });
    assert!((0.8..2.5).contains(&dip), "airspeed dip {dip}");
    assert!(late < 0.1, "not recovered: {late}");
}

/// Each loop's step response settles: course (+30 deg), altitude (+8 m, inside the hold band),
/// airspeed (+3 m/s).
#[test]
fn loop_step_responses_settle() {
    let v = uav(FixedWingConfig::default());
    // Course.
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    let mut cmd = hold(&v, &s);
    cmd.course_rad += 30f64.to_radians();
    let mut max_bank: f64 = 0.0;
    fly(&v, &mut s, &cmd, 20.0, |_, s| {
        max_bank = max_bank.max(s.x[6].abs())
    });
    assert!(
        (s.course_rad - cmd.course_rad).abs() < 0.01,
        "course error {}",
        s.course_rad - cmd.course_rad
    );
    assert!(max_bank <= 40f64.to_radians() + 0.02, "bank {max_bank}");
    assert!(max_bank > 5f64.to_radians(), "it banked to turn");
    // Altitude.
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    let mut cmd = hold(&v, &s);
    cmd.altitude_m = 108.0;
    fly(&v, &mut s, &cmd, 60.0, |_, _| {});
    assert!((-s.x[2] - 108.0).abs() < 0.2, "altitude {}", -s.x[2]);
    // Airspeed.
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    let mut cmd = hold(&v, &s);
    cmd.airspeed_mps = 33.0;
    fly(&v, &mut s, &cmd, 30.0, |_, _| {});
    assert!(
        (v.air_data(&s).va_mps - 33.0).abs() < 0.1,
        "airspeed {}",
        v.air_data(&s).va_mps
    );
    assert!((-s.x[2] - 100.0).abs() < 1.0);
}

/// A steady coordinated-rate turn at omega = 0.1 rad/s: bank = atan(V omega/g) = 17.0 deg,
/// within the small sideslip of the uncoordinated (no rudder) turn.
#[test]
fn steady_turn_bank_matches_atan_v_omega_over_g() {
    let v = uav(FixedWingConfig::default());
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    for _ in 0..6000 {
        v.step(&mut s, 0.1, 0.01);
    }
    let expected = (30.0f64 * 0.1 / 9.8).atan();
    let air = v.air_data(&s);
    assert!(
        (s.x[6] - -expected).abs() < 0.5f64.to_radians() + air.beta_rad.abs(),
        "bank {} vs {} (beta {})",
        s.x[6],
        -expected,
        air.beta_rad
    );
    // A left turn (omega > 0) banks left: roll negative.
    assert!(s.x[6] < 0.0);
    assert!(air.beta_rad.abs() < 0.02, "sideslip {}", air.beta_rad);
}

/// With a steady cross wind the ground course and the heading differ by the crab angle
/// asin(w/Va); the course loop holds the ground course.
#[test]
fn wind_separates_course_from_heading() {
    let v = uav(FixedWingConfig {
        wind_mps: [5.0, 0.0], // blowing towards the east
        ..FixedWingConfig::default()
    });
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2); // north over the ground
    let cmd = hold(&v, &s);
    fly(&v, &mut s, &cmd, 60.0, |_, _| {});
    let crab = (5.0f64 / 30.0).asin();
    assert!(s.course_rad.abs() < 1e-3, "course {}", s.course_rad);
    assert!(
        (s.x[8] + crab).abs() < 2e-3,
        "heading {} vs {}",
        s.x[8],
        -crab
    );
    // Ground track: still due north.
    assert!(s.x[1].abs() < 2.0, "drifted east {}", s.x[1]);
    // Gusts: seeded, reproducible, bounded.
    let g = FixedWingConfig {
        gusts: true,
        seed: 3,
        ..FixedWingConfig::default()
    };
    let run = || {
        let v = uav(g);
        let mut s = v.initial_state(0.0, 0.0, 0.0);
        let cmd = hold(&v, &s);
        fly(&v, &mut s, &cmd, 30.0, |_, _| {});
        s.x
    };
    let (a, b) = (run(), run());
    assert_eq!(a, b);
    assert!((-a[2] - 100.0).abs() < 5.0, "gusty altitude {}", -a[2]);
}

/// The roll loop's step response: a 120 deg course step saturates the course loop, so the roll
/// loop sees a step to the 40 deg bank limit; it reaches it within 1 deg in under 2 s and
/// overshoots by less than 3 deg (the design has zeta = 1.2: no overshoot expected).
#[test]
fn roll_loop_step_to_the_bank_limit() {
    let v = uav(FixedWingConfig::default());
    let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
    let mut cmd = hold(&v, &s);
    cmd.course_rad += 120f64.to_radians();
    let limit = 40f64.to_radians();
    let mut reached: Option<f64> = None;
    let mut peak: f64 = 0.0;
    fly(&v, &mut s, &cmd, 4.0, |t, s| {
        peak = peak.max(s.x[6]);
        if reached.is_none() && (s.x[6] - limit).abs() < 1f64.to_radians() {
            reached = Some(t);
        }
    });
    let t = reached.expect("the bank reached the limit");
    assert!(t < 2.0, "took {t} s");
    assert!(
        peak < limit + 3f64.to_radians(),
        "overshoot to {} deg",
        peak.to_degrees()
    );
}

/// A +50 m altitude step goes through the altitude state machine's climb zone (h below
/// h_c - 10 m: airspeed held by pitch, fixed throttle), then the hold zone: the UAV climbs the 40 m
/// to 140 m no faster than `Va sin(theta_max)` allows, its airspeed within 15 % of the command
/// throughout (the pitch loop holds it), and settles within 0.5 m of 150 m. A -40 m step (to
/// 60 m: lower would be the take-off zone below 50 m) goes through the descend zone and settles
/// likewise, its airspeed within the model's range [15, 45] m/s but not within 15 %: with the
/// throttle at 0 the descent first sags to 21 m/s, then overspeeds by about 9 m/s before the pitch
/// loop catches it (found by this test; an open question for the
/// autopilot, not yet changed).
#[test]
fn altitude_steps_run_through_the_climb_and_descend_zones() {
    let v = uav(FixedWingConfig::default());
    for (target, boundary) in [(150.0, 140.0), (60.0, 70.0)] {
        let mut s = v.initial_state(0.0, 0.0, FRAC_PI_2);
        let mut cmd = hold(&v, &s);
        cmd.altitude_m = target;
        let mut crossed_at: Option<f64> = None;
        let mut worst_va: f64 = 0.0;
        let mut slowest_va = f64::INFINITY;
        fly(&v, &mut s, &cmd, 150.0, |t, s| {
            let h = -s.x[2];
            let in_zone = if target > 100.0 {
                h <= boundary
            } else {
                h >= boundary
            };
            if in_zone {
                let va = v.air_data(s).va_mps;
                worst_va = worst_va.max((va - 30.0).abs());
                slowest_va = slowest_va.min(va);
            } else if crossed_at.is_none() {
                crossed_at = Some(t);
            }
        });
        let t = crossed_at.unwrap_or_else(|| panic!("never left the zone towards {target} m"));
        // 30 m through the zone (100 -> 140 m, or 100 -> 70 m) at no more than Va sin(theta_max).
        let fastest = 30.0 / (30.0 * v.ap.theta_max_rad.sin());
        assert!(
            (fastest..100.0).contains(&t),
            "{target} m: left the zone after {t} s"
        );
        if target > 100.0 {
            assert!(
                worst_va < 0.15 * 30.0,
                "{target} m: airspeed off by {worst_va} in the zone"
            );
        }
        // Climbing or descending, the pitch loop keeps the airspeed inside the model's valid
        // range (the descent pitches the nose down to hold it: a pitch command held nose-up
        // sags to 13 m/s).
        let (lo, hi) = super::trim::AIRSPEED_RANGE_MPS;
        assert!(
            slowest_va > lo && 30.0 + worst_va < hi,
            "{target} m: airspeed in [{slowest_va}, {}] in the zone",
            30.0 + worst_va
        );
        assert!(
            (-s.x[2] - target).abs() < 0.5,
            "settled at {} m, not {target}",
            -s.x[2]
        );
    }
}

/// Dryden gusts move the aircraft: a gusty flight differs from the calm one (same start and
/// commands), its altitude wanders by more than a centimetre, and stays within 5 m.
#[test]
fn gusts_differ_from_calm_flight() {
    let fly_with = |gusts: bool| {
        let v = uav(FixedWingConfig {
            gusts,
            seed: 5,
            ..FixedWingConfig::default()
        });
        let mut s = v.initial_state(0.0, 0.0, 0.0);
        let cmd = hold(&v, &s);
        let mut wander: f64 = 0.0;
        fly(&v, &mut s, &cmd, 60.0, |t, s| {
            if t > 10.0 {
                wander = wander.max((-s.x[2] - 100.0).abs());
            }
        });
        (s.x, wander)
    };
    let (calm, calm_wander) = fly_with(false);
    let (gusty, gusty_wander) = fly_with(true);
    assert_ne!(calm, gusty);
    assert!(calm_wander < 0.05, "calm altitude wanders {calm_wander} m");
    assert!(
        (0.01..5.0).contains(&gusty_wander),
        "gusty altitude wanders {gusty_wander} m"
    );
    let drift = ((calm[0] - gusty[0]).powi(2) + (calm[1] - gusty[1]).powi(2)).sqrt();
    assert!(
        drift > 0.1,
        "gusts moved the track by only {drift} m in 60 s"
    );
}

/// The `Vehicle` interface of the UAV by closed forms: the airframe's turn-rate limit
/// `g tan(40 deg)/V`, the start (trimmed, crabbed so the ground course is the heading given,
/// the trim deflections), the NED ground velocity against nalgebra's rotation, the pose
/// (x east, y north, heading counter-clockwise from east), the horizontal ground speed and the
/// telemetry (altitude = -p_d).
#[test]
fn the_vehicle_interface_by_closed_forms() {
    use isotrack_core::vehicle::Vehicle;
    use nalgebra::{Rotation3, Vector3};
    let v = uav(FixedWingConfig::default());
    let limit = 9.81 * 40f64.to_radians().tan() / 30.0;
    assert!((v.airframe_turn_rate_limit_radps() - limit).abs() < 2e-3 * limit);
    let v45 = uav(FixedWingConfig {
        airspeed_mps: 45.0,
        ..FixedWingConfig::default()
    });
    let ratio = v.airframe_turn_rate_limit_radps() / v45.airframe_turn_rate_limit_radps();
    assert!(
        (ratio - 1.5).abs() < 1e-12,
        "inverse in the airspeed: {ratio}"
    );

    // A start in a 6 m/s wind from the west (blowing east), flying north over the ground.
    let windy = uav(FixedWingConfig {
        wind_mps: [6.0, 0.0],
        ..FixedWingConfig::default()
    });
    let s = windy.initial_state(120.0, -40.0, FRAC_PI_2);
    let pose = windy.pose(&s);
    assert_eq!((pose.position.x, pose.position.y), (120.0, -40.0));
    assert!(
        (pose.heading_rad - FRAC_PI_2).abs() < 1e-12,
        "{}",
        pose.heading_rad
    );
    assert!((-s.x[2] - 100.0).abs() < 1e-12);
    let g = FixedWing::ground_velocity(&s.x);
    // Crabbed west of north: ground speed sqrt(30^2 - 6^2) due north, none east or down.
    let along = (30.0f64 * 30.0 - 36.0).sqrt();
    assert!(
        (g[0] - along).abs() < 1e-9 && g[1].abs() < 1e-9 && g[2].abs() < 1e-6,
        "{g:?}"
    );
    assert!((windy.speed_mps(&s) - along).abs() < 1e-9);
    assert!(
        (s.x[8] + (6.0f64 / 30.0).asin()).abs() < 1e-12,
        "yaw {}",
        s.x[8]
    );
    assert_eq!(s.deltas.elevator_rad, windy.trim.delta_e_rad);
    assert_eq!(s.deltas.throttle, windy.trim.delta_t);
    let t = windy.telemetry(&s).unwrap();
    assert!((t.altitude_m - 100.0).abs() < 1e-12);
    assert!((t.airspeed_mps - 30.0).abs() < 1e-9, "{}", t.airspeed_mps);
    assert_eq!(t.roll_rad, s.x[6]);

    // Ground velocity of an arbitrary attitude: R(phi, theta, psi) (u, v, w).
    let mut x = s.x;
    x[3..12].copy_from_slice(&[25.0, -3.0, 4.0, 0.3, -0.2, 2.5, 0.0, 0.0, 0.0]);
    let want = Rotation3::from_euler_angles(x[6], x[7], x[8]) * Vector3::new(x[3], x[4], x[5]);
    let got = FixedWing::ground_velocity(&x);
    for i in 0..3 {
        assert!((got[i] - want[i]).abs() < 1e-12, "{got:?} vs {want:?}");
    }
    let mut st = s.clone();
    st.x = x;
    assert!((windy.speed_mps(&st) - want[0].hypot(want[1])).abs() < 1e-12);
    // The ground course follows the velocity, continuous with the previous value (one turn
    // up), and holds it when there is no horizontal motion.
    let course = want[1].atan2(want[0]);
    let tau = 2.0 * std::f64::consts::PI;
    assert!((FixedWing::ground_course(&x, 0.1) - course).abs() < 1e-12);
    assert!((FixedWing::ground_course(&x, tau + 0.1) - (course + tau)).abs() < 1e-12);
    let mut still = x;
    still[3..6].copy_from_slice(&[0.0, 0.0, 0.0]);
    assert_eq!(FixedWing::ground_course(&still, 0.7), 0.7);
    // Below 1e-6 m/s of horizontal speed the course is held; above, it follows the velocity.
    let mut level = x;
    level[6..9].copy_from_slice(&[0.0, 0.0, 0.0]);
    level[3..6].copy_from_slice(&[1e-7, 0.0, 0.0]);
    assert_eq!(FixedWing::ground_course(&level, 0.7), 0.7);
    level[3..6].copy_from_slice(&[1e-3, 1e-5, 0.0]);
    let c = FixedWing::ground_course(&level, 0.7);
    assert!((c - 1e-5f64.atan2(1e-3)).abs() < 1e-12, "{c}");
    // A start in an oblique wind: crabbed so that the ground velocity lies along the heading
    // given, at the wind triangle's speed sqrt(Va^2 - w_cross^2) + w_along.
    let oblique = uav(FixedWingConfig {
        wind_mps: [3.0, -4.0],
        ..FixedWingConfig::default()
    });
    let heading = 0.5f64;
    let s = oblique.initial_state(0.0, 0.0, heading);
    let gv = FixedWing::ground_velocity(&s.x);
    let (east, north) = (gv[1], gv[0]);
    assert!(
        (north.atan2(east) - heading).abs() < 1e-12,
        "course {}",
        north.atan2(east)
    );
    let (c, sn) = (heading.cos(), heading.sin());
    let along = 3.0 * c - 4.0 * sn;
    let cross = -3.0 * sn - 4.0 * c;
    let speed = (30.0f64 * 30.0 - cross * cross).sqrt() + along;
    assert!(
        (east.hypot(north) - speed).abs() < 1e-9,
        "{} vs {speed}",
        east.hypot(north)
    );
    st.course_rad = course;
    let pose = windy.pose(&st);
    assert!((pose.heading_rad - isotrack_core::math::wrap_angle(FRAC_PI_2 - course)).abs() < 1e-12);
    assert_eq!((pose.position.x, pose.position.y), (st.x[1], st.x[0]));
}

/// The bare airframe at its trim deflections flies on, trimmed: 1 s open loop moves it 30 m
/// along its course and changes altitude and airspeed by almost nothing.
#[test]
fn open_loop_flight_at_trim_stays_trimmed() {
    let v = uav(FixedWingConfig::default());
    let s = v.initial_state(0.0, 0.0, FRAC_PI_2); // flying north
    let mut x = s.x;
    for _ in 0..100 {
        v.step_open_loop(&mut x, &s.deltas, 0.01);
    }
    assert!(
        (x[0] - 30.0).abs() < 1e-3 && x[1].abs() < 1e-6,
        "{} m north, {} m east",
        x[0],
        x[1]
    );
    assert!((-x[2] - 100.0).abs() < 1e-3, "altitude {}", -x[2]);
    let u = (x[3] * x[3] + x[4] * x[4] + x[5] * x[5]).sqrt();
    assert!((u - 30.0).abs() < 1e-4, "airspeed {u}");
}

/// The airspeed command of a team's spacing law goes through the autopilot's airspeed loop:
/// from trim at 30 m/s, commands at the ends of the team's range (20 and 45 m/s) and between,
/// flown in a steady turn at the controller's default limit (0.274 rad/s at 30 m/s), settle
/// within 0.5 m/s of the command in 60 s, the altitude within 2 m of its command, the angle of
/// attack below the stall blending's alpha0 = 0.47 rad throughout; in still air the ground
/// speed of the settled straight flight is the airspeed (within 0.5 m/s). Commands outside the
/// envelope are held at its ends (a NaN at the slowest); an envelope outside [20, 45] m/s is
/// refused. (A 15 m/s command in that turn stalls: the angle of attack reached 1.47 rad, the
/// airspeed ran away to 32.7 m/s; at 20 m/s its peak was 0.428 rad, below alpha0 = 0.471.)
#[test]
fn airspeed_commands_through_the_airspeed_loop() {
    use isotrack_core::SpeedCommand;
    let cfg = FixedWingConfig::default();
    let w = FixedWingVariableSpeed::new(uav(cfg), 20.0, 45.0).unwrap();
    for (cmd, turn) in [
        (20.0, 0.274),
        (40.0, 0.274),
        (45.0, 0.274),
        (20.0, 0.0),
        (40.0, 0.0),
    ] {
        let mut s = w.uav.initial_state(0.0, 0.0, 0.0);
        assert_eq!(w.command_speed(&mut s, cmd), cmd);
        let mut worst_alpha: f64 = 0.0;
        for _ in 0..6000 {
            w.step(&mut s, turn, 0.01);
            worst_alpha = worst_alpha.max(w.uav.air_data(&s).alpha_rad);
        }
        let va = w.uav.air_data(&s).va_mps;
        assert!(
            (va - cmd).abs() < 0.5,
            "{cmd} m/s, turn {turn}: airspeed {va}"
        );
        assert!(
            (-s.x[2] - cfg.altitude_m).abs() < 2.0,
            "{cmd} m/s: altitude {}",
            -s.x[2]
        );
        assert!(
            worst_alpha < w.uav.params().alpha0,
            "{cmd} m/s: alpha {worst_alpha}"
        );
        if turn == 0.0 {
            let g = w.speed_mps(&s);
            assert!((g - cmd).abs() < 0.5, "{cmd} m/s: ground speed {g}");
        }
    }
    let mut s = w.uav.initial_state(0.0, 0.0, 0.0);
    assert_eq!(w.command_speed(&mut s, 100.0), 45.0);
    assert_eq!(w.command_speed(&mut s, f64::NAN), 20.0);
    assert_eq!(s.airspeed_cmd_mps, 20.0);
    assert!(FixedWingVariableSpeed::new(uav(cfg), 15.0, 40.0).is_err());
    assert!(FixedWingVariableSpeed::new(uav(cfg), 10.0, 40.0).is_err());
    assert!(FixedWingVariableSpeed::new(uav(cfg), 20.0, 50.0).is_err());
    assert!(FixedWingVariableSpeed::new(uav(cfg), 40.0, 20.0).is_err());
}

/// At the configured airspeed the commanded UAV flies as the UAV does, bit for bit.
#[test]
fn commanded_at_trim_is_the_uav() {
    use isotrack_core::SpeedCommand;
    let cfg = FixedWingConfig {
        gusts: true,
        seed: 3,
        ..FixedWingConfig::default()
    };
    let plain = uav(cfg);
    let w = FixedWingVariableSpeed::new(uav(cfg), 20.0, 40.0).unwrap();
    let mut a = plain.initial_state(1.0, 2.0, 0.3);
    let mut b = w.uav.initial_state(1.0, 2.0, 0.3);
    for k in 0..3000 {
        w.command_speed(&mut b, 30.0);
        let om = 0.1 * ((k / 500) % 2) as f64;
        plain.step(&mut a, om, 0.01);
        w.step(&mut b, om, 0.01);
    }
    assert_eq!(a.x, b.x);
}

/// `N` aircraft stepped together (`step_lanes`: the airframe in SIMD lanes) against each
/// stepped alone (`step`), state for state and bit for bit after every step of a long closed-loop
/// flight: each lane with its own start, gust seed, airspeed command and turn-rate command
/// sequence; one lane starts motionless in the air (airspeed exactly 0: the branch-free body's
/// other side) and one diverges (a non-finite state) beside the others.
fn lanes_equal_one_at_a_time<const N: usize>(v: &FixedWing, seconds: f64) {
    let dt = 0.01;
    let mut lanes: [FixedWingState; N] = core::array::from_fn(|i| {
        let mut s = v.initial_state_seeded(
            100.0 * i as f64,
            -50.0 * i as f64,
            0.7 * i as f64 - 2.0,
            1000 + i as u64,
        );
        s.airspeed_cmd_mps = 26.0 + i as f64;
        s
    });
    // Lane 1 at rest relative to the air, level and heading north: body velocity = wind.
    let wned = v.steady_ned();
    lanes[1].x[3..9].copy_from_slice(&[wned[0], wned[1], wned[2], 0.0, 0.0, 0.0]);
    lanes[1].x[9..12].copy_from_slice(&[0.0; 3]);
    // Lane N - 1 diverges: a non-finite roll rate.
    lanes[N - 1].x[9] = f64::NAN;
    let mut alone = lanes.clone();
    let n = (seconds / dt).round() as usize;
    let bits = |s: &FixedWingState| {
        let mut b: Vec<u64> = s.x.iter().map(|v| v.to_bits()).collect();
        b.extend([s.course_rad, s.course_cmd_rad].map(f64::to_bits));
        b.extend(s.wind.gust_body_mps.map(f64::to_bits));
        (b, format!("{s:?}"))
    };
    let mut airspeed_zero_met = false;
    for k in 0..n {
        let omega: [f64; N] =
            core::array::from_fn(|i| 0.2 * ((k as f64) * 0.003 * (i + 1) as f64).sin());
        if k == 0 {
            airspeed_zero_met = v.air_data(&lanes[1]).va_mps == 0.0;
        }
        v.step_lanes(&mut lanes, &omega, dt);
        for (s, &w) in alone.iter_mut().zip(&omega) {
            v.step(s, w, dt);
        }
        for i in 0..N {
            assert_eq!(
                bits(&lanes[i]),
                bits(&alone[i]),
                "N = {N}, lane {i}, step {k}"
            );
        }
    }
    assert!(airspeed_zero_met, "lane 1 did not start at airspeed 0");
    // The lanes flew different, finite flights; the diverged one stayed apart.
    assert!(lanes[0].x.iter().all(|v| v.is_finite()));
    assert!(lanes[N - 1].x.iter().any(|v| v.is_nan()));
    assert_ne!(lanes[0].x[0].to_bits(), lanes[2].x[0].to_bits());
}

#[test]
fn lanes_of_4_and_8_equal_one_at_a_time_in_calm_air_and_in_gusts() {
    let calm = uav(FixedWingConfig {
        wind_mps: [3.0, -2.0],
        ..FixedWingConfig::default()
    });
    let gusty = uav(FixedWingConfig {
        wind_mps: [-4.0, 1.5],
        gusts: true,
        ..FixedWingConfig::default()
    });
    for v in [&calm, &gusty] {
        lanes_equal_one_at_a_time::<4>(v, 120.0);
        lanes_equal_one_at_a_time::<8>(v, 120.0);
    }
    // The commanded-airspeed UAV steps its lanes as the UAV does.
    let commanded = FixedWingVariableSpeed::new(gusty.clone(), 20.0, 40.0).unwrap();
    let mut a = [
        gusty.initial_state(0.0, 0.0, 1.0),
        gusty.initial_state(0.0, 0.0, -1.0),
    ];
    let mut b = a.clone();
    for _ in 0..500 {
        commanded.step_lanes(&mut a, &[0.1, -0.05], 0.01);
        gusty.step_lanes(&mut b, &[0.1, -0.05], 0.01);
    }
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
}
