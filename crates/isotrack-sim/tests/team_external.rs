//! A team stepped from outside the loop (`Group::sense`, `replace_answer`, `hold_speed`,
//! `advance`: the hooks the Python PettingZoo environment drives): answering as the built-in
//! laws answer flies `simulate_team`'s run bit for bit, and held speeds fly as commanded, within
//! the envelope. The circular field of Fig. 2(b), as tests/team.rs.
use isotrack_core::control::{PiIsoline, PiIsolineParams};
use isotrack_core::math::Vec2;
use isotrack_fields::{AnalyticField, AnalyticKind, RadialExp};
use isotrack_sim::team::arc::{ArcProjection, CircleArc};
use isotrack_sim::team::metrics::TeamMetricsConfig;
use isotrack_sim::team::ranging::RangingConfig;
use isotrack_sim::team::spacing::{RingMode, SpacingConfig, SpacingLaw};
use isotrack_sim::{
    simulate_team, Group, NoTrace, Oracles, Sensor, SensorConfig, StepPlan, TeamConfig, TeamMember,
    TeamResult,
};
use isotrack_vehicles::{DubinsSpeedState, DubinsState, DubinsVariableSpeed};
use std::f64::consts::FRAC_PI_2;

const V0: f64 = 0.5;
const DT: f64 = 0.01;

fn radius() -> f64 {
    10.0 * std::f64::consts::LN_2
}

fn field() -> AnalyticField {
    AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()))
}

fn arc() -> CircleArc {
    CircleArc {
        center_m: Vec2::new(0.0, 0.0),
        radius_m: radius(),
    }
}

const VEHICLE: DubinsVariableSpeed = DubinsVariableSpeed {
    min_speed_mps: 0.25,
    max_speed_mps: 0.75,
};

/// Four robots in a cluster 0.3 rad apart on the isoline, clockwise, noisy sensors at 10 Hz.
fn members() -> Vec<TeamMember<DubinsSpeedState, PiIsoline>> {
    (0..4)
        .map(|i| {
            let th = -0.3 * i as f64;
            let r = radius();
            TeamMember {
                x0: VEHICLE.state(
                    DubinsState {
                        position_m: Vec2::new(r * th.cos(), r * th.sin()),
                        heading_rad: th - FRAC_PI_2,
                    },
                    V0,
                ),
                controller: PiIsoline::new(PiIsolineParams::paper_fig2b(10.0)),
                sensor: Sensor::new(
                    SensorConfig {
                        rate_hz: 10.0,
                        noise_std: 0.01,
                        ..SensorConfig::default()
                    },
                    DT,
                    100 + i as u64,
                )
                .unwrap(),
                ranging_seed: 1000 + i as u64,
            }
        })
        .collect()
}

fn plan(duration_s: f64) -> StepPlan {
    StepPlan::new(DT, duration_s, 0.0, 0.2, 0.1, 10.0, 10.0).unwrap()
}

/// range_balance on noisy, lossy ranges delivered 0.15 s late.
fn cfg() -> TeamConfig {
    TeamConfig {
        ranging: RangingConfig {
            rate_hz: 10.0,
            noise_std_m: 0.05,
            dropout_probability: 0.2,
            delay_s: 0.15,
            ..RangingConfig::default()
        },
        spacing: SpacingConfig {
            law: SpacingLaw::RangeBalance { gain_per_s: 0.1 },
            nominal_speed_mps: V0,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig::default(),
    }
}

/// Drives a team from outside: at every step `answer(group, i)` may replace vehicle `i`'s
/// answer and hold its speed.
fn drive(
    duration_s: f64,
    mut answer: impl FnMut(&mut Group<'static, DubinsSpeedState, PiIsoline>, usize),
) -> TeamResult {
    let f = field();
    let arc: Box<dyn ArcProjection + Send> = Box::new(arc());
    let mut g =
        Group::new_owning_arc(&VEHICLE, &plan(duration_s), cfg(), members(), Some(arc)).unwrap();
    let oracles = Oracles::default();
    let mut sinks: [NoTrace; 0] = [];
    while g.is_running() {
        g.sense(&f, &VEHICLE, &oracles, &mut sinks);
        for i in 0..g.len() {
            if g.is_vehicle_running(i) {
                answer(&mut g, i);
            }
        }
        g.advance(&VEHICLE, &oracles, &mut sinks);
    }
    g.finish(&mut sinks)
}

/// Replacing every answer by the built-in law's and holding every speed at the spacing law's
/// command (saturated, as the vehicle saturates it) is the built-in run, bit for bit.
#[test]
fn answering_as_the_built_in_laws_is_simulate_team() {
    let a = arc();
    let builtin = simulate_team(
        &field(),
        &VEHICLE,
        &plan(60.0),
        cfg(),
        members(),
        Some(&a),
        &Oracles::default(),
        &mut [] as &mut [NoTrace],
    )
    .unwrap();
    let mut sampled = 0;
    let outside = drive(60.0, |g, i| {
        if let Some((_, w)) = g.sampled(i) {
            assert!(g.replace_answer(i, w));
            sampled += 1;
        } else {
            assert!(!g.replace_answer(i, 0.0));
        }
        let v = g.law_speed_mps(i).clamp(0.25, 0.75);
        g.hold_speed(i, v);
    });
    // 10 Hz for 60 s: 601 samples per robot.
    assert_eq!(sampled, 4 * 601);
    assert_eq!(format!("{builtin:?}"), format!("{outside:?}"));
    // The spacing law did act (the cluster spread), so the held speeds were not all v0.
    let [lo, hi] = builtin.team.unwrap().speed_range_mps.unwrap();
    assert!(lo < V0 && hi > V0, "{lo} {hi}");
}

/// Held speeds are flown as commanded, saturated to the envelope: the path of 30 s at a held
/// 0.6 m/s is 18 m, and a command of 10 m/s flies v_max = 0.75 m/s (22.5 m, not 300 m),
/// whatever the spacing law would command. The path sums each step's chord, shorter than the
/// arc flown by a relative (omega dt)^2 / 24: within 1e-4 below `v T` for turn rates under
/// 4.9 rad/s, never above it.
#[test]
fn held_speeds_fly_within_the_envelope() {
    let r = drive(30.0, |g, i| {
        g.hold_speed(i, if i == 0 { 10.0 } else { 0.6 })
    });
    let path = |i: usize| r.runs[i].metrics.path_length_m;
    let flew = |p: f64, v: f64| p <= v * 30.0 * (1.0 + 1e-12) && p >= v * 30.0 * (1.0 - 1e-4);
    assert!(flew(path(0), 0.75), "{}", path(0));
    for i in 1..4 {
        assert!(flew(path(i), 0.6), "{}", path(i));
    }
}

/// The ranges delivered to an agent: the first at step 15 (0.15 s late), measured at t = 0,
/// the chords of the cluster, 2 R sin(0.15) to each neighbour in it.
#[test]
fn delivered_ranges_are_the_measured_chords_late() {
    let f = field();
    let mut g = Group::new(&VEHICLE, &plan(5.0), cfg(), members(), None).unwrap();
    let oracles = Oracles::default();
    let mut sinks: [NoTrace; 0] = [];
    let mut first = None;
    while g.is_running() && first.is_none() {
        g.sense(&f, &VEHICLE, &oracles, &mut sinks);
        if let Some(r) = g.delivered_ranges(1) {
            first = Some((g.step_index(), r));
        }
        g.advance(&VEHICLE, &oracles, &mut sinks);
    }
    let (k, r) = first.unwrap();
    assert_eq!(k, 15);
    assert_eq!(r.t_s, 0.0);
    let chord = 2.0 * radius() * 0.15f64.sin();
    // Noise 0.05 m: within 5 sigma when valid.
    for x in [r.ahead, r.behind] {
        if x.valid {
            assert!((x.range_m - chord).abs() < 0.25, "{x:?} vs {chord}");
        }
    }
    assert_eq!(g.ranging_steps(), (10, 15));
}
