//! Throughput of the simulation loop on the paper's Fig. 2(b) scenario (Dubins robot, circular
//! field, PI-like law, 100 Hz sensing, dt = 0.01 s, 600 s = 60 000 steps), on the analytic field
//! and on a grid sampled from it; and the same step as one flat loop (`dubins_flat_loop_600s`),
//! the floor a single run can reach.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use isotrack_core::control::{PiIsoline, PiIsolineParams};
use isotrack_core::math::Vec2;
use isotrack_core::ScalarField;
use isotrack_fields::grid::{Grid2, GridField, Interpolation};
use isotrack_fields::{AnalyticField, AnalyticKind, RadialExp};
use isotrack_sim::{
    simulate, simulate_batch, BatchRun, NoTrace, Oracles, Sensor, SensorConfig, StepPlan, TraceRow,
    TraceSink,
};
use isotrack_vehicles::{Dubins, DubinsState};
use std::hint::black_box;

/// One 600 s run of the Fig. 2(b) setting on `field`, recording into `sink` at `record_rate_hz`.
fn run_on<F: ScalarField, S: TraceSink>(field: &F, record_rate_hz: f64, sink: &mut S) -> u64 {
    let vehicle = Dubins { speed_mps: 0.5 };
    let x0 = DubinsState {
        position_m: Vec2::new(10.0, 0.0),
        heading_rad: -std::f64::consts::FRAC_PI_2,
    };
    let mut c = PiIsoline::new(PiIsolineParams::paper_fig2b(10.0));
    let cfg = SensorConfig {
        rate_hz: 100.0,
        ..SensorConfig::default()
    };
    let sensor = Sensor::new(cfg, 0.01, 0).unwrap();
    let plan = StepPlan::new(0.01, 600.0, record_rate_hz, 0.2, 0.1, 60.0, 10.0).unwrap();
    simulate(
        field,
        &vehicle,
        x0,
        &mut c,
        sensor,
        &plan,
        &Oracles::default(),
        sink,
    )
    .steps
}

fn bench(c: &mut Criterion) {
    let analytic = AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()));
    bench_one_run(c, &analytic);
    bench_eight_runs(c, &analytic);
    bench_grid(c);
}

/// One run on the analytic field, without a trace and recording at 10 Hz.
fn bench_one_run(c: &mut Criterion, analytic: &AnalyticField) {
    let mut g = c.benchmark_group("dubins_circular_600s");
    g.throughput(Throughput::Elements(60_000));
    g.bench_function("trace_off", |b| {
        b.iter(|| black_box(run_on(analytic, 0.0, &mut NoTrace)))
    });
    g.bench_function("trace_10hz", |b| {
        b.iter(|| {
            let mut rows: Vec<TraceRow> = Vec::with_capacity(6002);
            black_box(run_on(analytic, 10.0, &mut rows))
        })
    });
    g.finish();
}

/// The same run, 8 of them from spread starts: stepped together in lanes, and one by one.
fn bench_eight_runs(c: &mut Criterion, analytic: &AnalyticField) {
    let starts: Vec<DubinsState> = (0..8)
        .map(|i| DubinsState {
            position_m: Vec2::new(10.0 - i as f64, 0.5 * i as f64),
            heading_rad: -std::f64::consts::FRAC_PI_2 + 0.3 * i as f64,
        })
        .collect();
    let plan = StepPlan::new(0.01, 600.0, 0.0, 0.2, 0.1, 60.0, 10.0).unwrap();
    let sensor = || {
        let cfg = SensorConfig {
            rate_hz: 100.0,
            ..SensorConfig::default()
        };
        Sensor::new(cfg, 0.01, 0).unwrap()
    };
    let vehicle = Dubins { speed_mps: 0.5 };
    let mut g = c.benchmark_group("dubins_circular_600s_x8");
    g.throughput(Throughput::Elements(8 * 60_000));
    g.bench_function("batched", |b| {
        b.iter(|| {
            let runs = starts
                .iter()
                .map(|&x0| BatchRun {
                    x0,
                    controller: PiIsoline::new(PiIsolineParams::paper_fig2b(10.0)),
                    sensor: sensor(),
                    oracles: Oracles::default(),
                })
                .collect();
            black_box(simulate_batch(analytic, &vehicle, &plan, runs))
        })
    });
    g.bench_function("one_by_one", |b| {
        b.iter(|| {
            starts
                .iter()
                .map(|&x0| {
                    let mut c = PiIsoline::new(PiIsolineParams::paper_fig2b(10.0));
                    simulate(
                        analytic,
                        &vehicle,
                        x0,
                        &mut c,
                        sensor(),
                        &plan,
                        &Oracles::default(),
                        &mut NoTrace,
                    )
                    .steps
                })
                .sum::<u64>()
        })
    });
    g.finish();
}

/// One run on a 0.25 m grid sampled from the circular field (161 x 161 nodes), bicubic and
/// bilinear.
fn bench_grid(c: &mut Criterion) {
    let grid = Grid2::from_fn(161, 161, Vec2::new(-20.0, -20.0), [0.25, 0.25], |p| {
        20.0 * (-0.1 * p.norm()).exp()
    })
    .unwrap();
    let mut g = c.benchmark_group("dubins_grid_600s");
    g.throughput(Throughput::Elements(60_000));
    for (name, interp) in [
        ("bicubic", Interpolation::Bicubic),
        ("bilinear", Interpolation::Bilinear),
    ] {
        let field = GridField::new(grid.clone(), interp);
        g.bench_function(name, |b| {
            b.iter(|| black_box(run_on(&field, 0.0, &mut NoTrace)))
        });
    }
    g.finish();
}

/// The floor of one run: the Fig. 2(b) step written as one flat loop with nothing but its chain
/// (field, backward difference, PI-like law, RK4 Dubins step by angle addition; no sensor model,
/// metrics, outcomes or trace), with elementary functions `exp`, `tanh`, `sin_cos` (of the
/// heading) and `sin_cos_turn` (of the half turn angle).
#[inline(always)]
fn flat_loop(
    n: usize,
    exp: impl Fn(f64) -> f64,
    tanh: impl Fn(f64) -> f64,
    sin_cos: impl Fn(f64) -> (f64, f64),
    sin_cos_turn: impl Fn(f64) -> (f64, f64),
) -> f64 {
    let (i0, k, level) = (20.0, 0.1, 10.0);
    let (v, kp, ki, c1, c2, dt) = (0.5, 10.0, 1.0, 0.2, 1.0, 0.01);
    let (mut x, mut y, mut th): (f64, f64, f64) =
        (black_box(10.0), 0.0, -std::f64::consts::FRAC_PI_2);
    let (mut sigma, mut prev, mut worst) = (0.0, 0.0, 0.0f64);
    for i in 0..=n {
        let eps = i0 * exp(-k * (x * x + y * y).sqrt()) - level;
        let mut e = c1 * tanh(eps / c2);
        if i > 0 {
            e += (eps - prev) / dt;
            sigma += e * dt;
        }
        prev = eps;
        worst = worst.max(eps.abs());
        let w = kp * e + ki * sigma;
        let (s0, c0) = sin_cos(th);
        let (sa, ca) = sin_cos_turn(w * (0.5 * dt));
        let (s1, c1h) = (s0 * ca + c0 * sa, c0 * ca - s0 * sa);
        let (s2, c2h) = (s1 * ca + c1h * sa, c1h * ca - s1 * sa);
        x += v * dt / 6.0 * (c0 + 4.0 * c1h + c2h);
        y += v * dt / 6.0 * (s0 + 4.0 * s1 + s2);
        th += w * dt;
    }
    worst
}

fn floor(c: &mut Criterion) {
    use isotrack_core::lanes;
    let mut g = c.benchmark_group("dubins_flat_loop_600s");
    g.throughput(Throughput::Elements(60_000));
    g.bench_function("platform_libm", |b| {
        b.iter(|| {
            black_box(flat_loop(
                60_000,
                f64::exp,
                f64::tanh,
                f64::sin_cos,
                f64::sin_cos,
            ))
        })
    });
    g.bench_function("lanes", |b| {
        b.iter(|| {
            black_box(flat_loop(
                60_000,
                lanes::exp,
                lanes::tanh,
                lanes::sin_cos,
                lanes::sin_cos_small_angle,
            ))
        })
    });
    g.finish();
}

criterion_group!(benches, bench, floor);
criterion_main!(benches);
