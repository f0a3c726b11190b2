//! A sweep's inner loop on one core: derive a variant of the default scenario (new start and
//! noise seed, field shared) and run it, 20 times per iteration (20 x 60 000 steps). And one run
//! of the default scenario as `isotrack run` does it in-process (load and resolve, the scenario's
//! warnings for `summary.json`, the run with its 10 Hz trace kept in memory): the reference for
//! the Python package's `Scenario.run()`, which does the same.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::{NoTrace, TraceRow};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let base = Scenario::default_paper_fig2b();
    let mut g = c.benchmark_group("sweep_default_scenario");
    g.sample_size(10);
    g.throughput(Throughput::Elements(20));
    g.bench_function("derive_and_run_20", |b| {
        b.iter(|| {
            for k in 0..20 {
                let s = base
                    .derive(
                        &[
                            format!("initial.x_m={}", -10.0 + k as f64),
                            format!("sim.seed={k}"),
                        ],
                        "bench",
                    )
                    .unwrap();
                black_box(s.run(&mut NoTrace).steps);
            }
        })
    });
    g.finish();

    let mut g = c.benchmark_group("default_scenario");
    g.throughput(Throughput::Elements(60_000));
    g.bench_function("load_warn_and_run_trace_10hz", |b| {
        b.iter(|| {
            let s = load_scenario(None, &[]).unwrap();
            black_box(isotrack_scenario::check::warnings(&s));
            let mut rows: Vec<TraceRow> = Vec::new();
            black_box(s.run(&mut rows).steps);
            black_box(rows.len())
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
