//! Score your own Rust controller with the benchmark, beside the paper's law:
//!
//! ```sh
//! cargo run --release -p isotrack-league --example own_controller [SUITE.toml]
//! ```
//!
//! The law here is a saturated "PD on the measurement": `omega = kd*deps + kp*tanh(eps/c)`, with
//! `eps = s - s_d` and `deps` its backward difference. It sees only `Measurement { t_s, value }`.

use isotrack_core::{IsolineController, Measurement};
use isotrack_league::leaderboard::leaderboard_md;
use isotrack_league::{run_benchmark, Options, Registry, Suite};
use isotrack_scenario::Scenario;
use std::path::PathBuf;

struct TanhPd {
    level: f64,
    kp: f64,
    kd: f64,
    c: f64,
    prev: Option<(f64, f64)>,
}

impl IsolineController for TanhPd {
    fn update(&mut self, m: &Measurement) -> f64 {
        let eps = m.value - self.level;
        let deps = match self.prev {
            Some((t, e)) if m.t_s > t => (eps - e) / (m.t_s - t),
            _ => 0.0,
        };
        self.prev = Some((m.t_s, eps));
        self.kd * deps + self.kp * (eps / self.c).tanh()
    }
    fn reset(&mut self) {
        self.prev = None;
    }
}

fn main() {
    let suite_path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../suites/standard-v2.toml")
        });
    let suite = match Suite::load(&suite_path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(65);
        }
    };
    let mut registry = Registry::builtin();
    // The one registration line: a name and a factory from the run's scenario (a built-in
    // law's name, an empty one or one with '|' is refused).
    let registered = registry.register("tanh_pd", |s: &Scenario| {
        Box::new(TanhPd {
            level: s.level(),
            kp: 2.0,
            kd: 10.0,
            c: 1.0,
            prev: None,
        }) as Box<dyn IsolineController + Send>
    });
    if let Err(e) = registered {
        eprintln!("error: {e}");
        std::process::exit(64);
    }
    let opts = Options {
        controllers: Some(vec!["pi_isoline".into(), "tanh_pd".into()]),
        ..Options::default()
    };
    let progress = |i: usize, n: usize, id: &str| eprintln!("task {}/{n}: {id}", i + 1);
    match run_benchmark(&suite, &registry, &opts, &progress) {
        Ok(r) => print!("{}", leaderboard_md(&r)),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(65);
        }
    }
}
