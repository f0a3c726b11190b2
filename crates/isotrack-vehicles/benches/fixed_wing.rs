//! 6-DOF closed-loop steps per second: autopilot + RK4 (four force evaluations) per 0.01 s step,
//! the UAV turning at 0.05 rad/s, with and without Dryden gusts.
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
}

criterion_group!(benches, bench);
criterion_main!(benches);
