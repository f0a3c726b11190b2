//! 6-DOF closed-loop steps per second: autopilot + RK4 (four force evaluations) per 0.01 s step,
//! the UAV turning at 0.05 rad/s, with and without Dryden gusts; one aircraft, and 8 in lanes.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use isotrack_core::Vehicle;
use isotrack_vehicles::{FixedWing, FixedWingConfig};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("fixed_wing_closed_loop");
    const STEPS: u64 = 10_000;
    g.throughput(Throughput::Elements(STEPS));
    for (name, gusts) in [("calm", false), ("dryden_gusts", true)] {
        let uav = FixedWing::new(FixedWingConfig {
            gusts,
            ..FixedWingConfig::default()
        })
        .unwrap();
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut s = uav.initial_state(0.0, 0.0, 0.0);
                for _ in 0..STEPS {
                    uav.step(&mut s, black_box(0.05), 0.01);
                }
                black_box(s.x[0])
            })
        });
    }
    g.finish();
    // The same per aircraft, 8 stepped together in lanes (`step_lanes`, what a batched sweep
    // does): 8 x STEPS aircraft-steps per iteration.
    let mut g = c.benchmark_group("fixed_wing_closed_loop_x8");
    g.throughput(Throughput::Elements(8 * STEPS));
    for (name, gusts) in [("calm", false), ("dryden_gusts", true)] {
        let uav = FixedWing::new(FixedWingConfig {
            gusts,
            ..FixedWingConfig::default()
        })
        .unwrap();
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut s: [_; 8] = std::array::from_fn(|i| {
                    uav.initial_state_seeded(0.0, 0.0, 0.1 * i as f64, i as u64)
                });
                for _ in 0..STEPS {
                    uav.step_lanes(&mut s, black_box(&[0.05; 8]), 0.01);
                }
                black_box(s[0].x[0])
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
