//! Throughput of a team: a ring of 1000 Dubins robots on the paper's circular field (the level-1
//! isoline, radius 10 ln 20 = 29.96 m), the Fig. 2(b) PI-like law at 100 Hz, dt = 0.01 s,
//! `range_balance` on ideal 10 Hz ranging, 60 s = 6 000 steps = 6 M vehicle-steps per
//! iteration (the 600 s run is ten of them; the memory does not grow with the duration:
//! the driver keeps per-vehicle state only). `team_metrics_1hz` adds the team metrics sampled
//! once a second.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use isotrack_core::control::{PiIsoline, PiIsolineParams};
use isotrack_core::math::Vec2;
use isotrack_fields::{AnalyticField, AnalyticKind, RadialExp};
use isotrack_sim::team::arc::{ArcProjection, CircleArc};
use isotrack_sim::team::metrics::TeamMetricsConfig;
use isotrack_sim::team::ranging::RangingConfig;
use isotrack_sim::team::spacing::{RingMode, SpacingConfig, SpacingLaw};
use isotrack_sim::{
    Group, NoTrace, Oracles, Sensor, SensorConfig, StepPlan, TeamConfig, TeamMember, TeamThreads,
};
use isotrack_vehicles::{DubinsState, DubinsVariableSpeed};
use std::hint::black_box;

const N: usize = 1000;

fn run(metrics_every: Option<u64>) -> u64 {
    run_on(N, metrics_every, TeamThreads::new(1))
}

fn run_on(n: usize, metrics_every: Option<u64>, threads: TeamThreads) -> u64 {
    let field = AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()));
    let r = 10.0 * 20f64.ln();
    let v = DubinsVariableSpeed {
        min_speed_mps: 0.25,
        max_speed_mps: 0.75,
    };
    let members = (0..n)
        .map(|i| {
            // Evenly spread but for a sawtooth of 10 % of a gap, clockwise.
            let th = -2.0 * std::f64::consts::PI * (i as f64 + 0.1 * (i % 3) as f64) / n as f64;
            let x0 = DubinsState {
                position_m: Vec2::new(r * th.cos(), r * th.sin()),
                heading_rad: th - std::f64::consts::FRAC_PI_2,
            };
            TeamMember {
                x0: v.state(x0, 0.5),
                controller: PiIsoline::new(PiIsolineParams::paper_fig2b(1.0)),
                sensor: Sensor::new(
                    SensorConfig {
                        rate_hz: 100.0,
                        ..SensorConfig::default()
                    },
                    0.01,
                    i as u64,
                )
                .unwrap(),
                ranging_seed: i as u64,
            }
        })
        .collect();
    let plan = StepPlan::new(0.01, 60.0, 0.0, 0.2, 0.1, 10.0, 1.0).unwrap();
    let cfg = TeamConfig {
        ranging: RangingConfig {
            rate_hz: 10.0,
            ..RangingConfig::default()
        },
        spacing: SpacingConfig {
            law: SpacingLaw::RangeBalance { gain_per_s: 0.1 },
            nominal_speed_mps: 0.5,
            ring: RingMode::Listed,
        },
        metrics: TeamMetricsConfig {
            every_steps: metrics_every.unwrap_or(1),
            ..TeamMetricsConfig::default()
        },
    };
    let arc = CircleArc {
        center_m: Vec2::new(0.0, 0.0),
        radius_m: r,
    };
    let arc_ref: Option<&dyn ArcProjection> = metrics_every.map(|_| &arc as &dyn ArcProjection);
    let mut g = Group::new(&v, &plan, cfg, members, arc_ref).unwrap();
    g.drive_threads(
        &field,
        &v,
        &Oracles::default(),
        &mut [] as &mut [NoTrace],
        threads,
    );
    let res = g.finish(&mut [] as &mut [NoTrace]);
    res.runs.iter().map(|r| r.steps).sum()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("team_ring_1000_dubins_60s");
    g.sample_size(10);
    g.throughput(Throughput::Elements((N * 6000) as u64));
    g.bench_function("range_balance", |b| b.iter(|| black_box(run(None))));
    g.bench_function("team_metrics_1hz", |b| b.iter(|| black_box(run(Some(100)))));
    for t in [1, 2] {
        g.bench_function(format!("threads_{t}"), |b| {
            b.iter(|| black_box(run_on(N, None, TeamThreads::new(t))))
        });
    }
    g.finish();
    let mut g = c.benchmark_group("team_ring_small_dubins_60s");
    g.sample_size(10);
    for n in [64, 128, 256, 512] {
        g.throughput(Throughput::Elements((n * 6000) as u64));
        for t in [1, 2] {
            let split = TeamThreads {
                threads: t,
                min_vehicles_per_thread: 8,
            };
            g.bench_function(format!("{n}/threads_{t}"), |b| {
                b.iter(|| black_box(run_on(n, None, split)))
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
