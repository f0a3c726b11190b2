//! The benchmark: the score formula by hand, suite errors, seed draws, determinism over thread
//! counts, a registered controller on the same footing as the built-in laws, and the tuning.

use isotrack_bench::run::{context, run_one, task_base};
use isotrack_bench::score::{score, ScoreContext};
use isotrack_bench::suite::seed_overrides;
use isotrack_bench::{run_benchmark, Entrant, Options, Registry, Suite};
use isotrack_core::IsolineController;
use isotrack_scenario::schema::ControllerKind;
use isotrack_sim::{NoTrace, Outcome, RunMetrics, RunResult};
use std::path::{Path, PathBuf};

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// Two short tasks, two laws, one tuning seed and two scoring seeds.
fn mini_suite(extra: &str) -> Suite {
    let text = format!(
        r#"
name = "mini"
version = 1
controllers = ["pi_isoline", "sliding_mode"]
tuning_seeds = [11]
scoring_seeds = [1, 2]

[[task]]
id = "circular"
title = "circular field, 10 Hz"
scenario = "paper-fig2b-circular.toml"
set = ["sim.duration_s=60.0", "sensor.rate_hz=10.0", "controller.max_turn_rate_radps=1.0"]
length_m = 6.93
vary = {{ "initial.x_m" = {{ uniform = [8.0, 12.0] }}, "initial.heading_rad" = {{ uniform = [-3.0, 3.0] }} }}

[[task]]
id = "plumes"
title = "Gaussian plumes"
scenario = "gaussian-plumes-pm25.toml"
set = ["sim.duration_s=60.0", "controller.max_turn_rate_radps=1.0"]
length_m = 15.9
{extra}
"#
    );
    Suite::parse(&text, "mini.toml", &scenarios()).unwrap()
}

fn result(metrics: RunMetrics, outcome: Outcome, t_end_s: f64) -> RunResult {
    RunResult {
        outcome,
        outcome_detail: None,
        t_end_s,
        steps: 0,
        samples: 0,
        samples_dropped: 0,
        end_position_m: [0.0, 0.0],
        metrics,
    }
}

fn metrics() -> RunMetrics {
    RunMetrics {
        steady_state_max_abs_error: Some(0.1),
        steady_state_rms_error: Some(0.05),
        steady_state_mean_error: Some(0.0),
        convergence_time_s: Some(60.0),
        path_length_m: 100.0,
        control_effort: 20.0,
        chattering_radps2: Some(0.0),
        sign_changes_per_s: Some(0.0),
        steady_state_max_isoline_distance_m: Some(1.0),
        steady_state_rms_isoline_distance_m: Some(0.5),
        time_in_band_fraction: Some(0.8),
        track_losses: 1,
    }
}

/// The documented formula, by hand: capture 1 - 60/240 = 0.75, band 0.8, distance
/// 1/(1 + 0.5/5) = 10/11, losses 1/2, effort: mean omega^2 = 20/300, w_ref^2 = (0.5/5)^2 = 0.01,
/// so 0.01/(1/15) = 0.15.
#[test]
fn score_is_the_documented_formula() {
    let ctx = ScoreContext {
        steady_start_s: 240.0,
        length_m: 5.0,
        speed_mps: 0.5,
    };
    let s = score(&result(metrics(), Outcome::Completed, 300.0), &ctx);
    let parts = [0.75, 0.8, 10.0 / 11.0, 0.5, 0.15];
    for (got, want) in s.parts.iter().zip(parts) {
        assert!((got - want).abs() < 1e-12, "{:?}", s.parts);
    }
    let want = 100.0 * (0.2 * 0.75 + 0.3 * 0.8 + 0.3 * 10.0 / 11.0 + 0.1 * 0.5 + 0.1 * 0.15);
    assert!((s.total - want).abs() < 1e-9);
    // Effort within the curvature demand is full marks; never converging is no capture.
    let mut m = metrics();
    m.control_effort = 1.0;
    m.convergence_time_s = None;
    let s = score(&result(m, Outcome::Completed, 300.0), &ctx);
    assert_eq!((s.parts[0], s.parts[4]), (0.0, 1.0));
    // A run that does not complete scores 0.
    for o in [Outcome::LeftField, Outcome::Diverged] {
        assert_eq!(score(&result(metrics(), o, 300.0), &ctx).total, 0.0);
    }
}

#[test]
fn suite_errors_are_located_and_seeds_disjoint() {
    let dir = scenarios();
    let e = Suite::parse(
        "name = \"x\"\nversion = 1\ncontrollers = []\ntuning_seeds = [1]\nscoring_seeds = [2]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"s.toml\"\nlength_m = 1.0\nspeed = 3\n",
        "bad.toml",
        &dir,
    )
    .unwrap_err();
    assert_eq!(e.location.map(|l| l.0), Some(11), "{e}");
    assert!(e.to_string().starts_with("bad.toml:11:"), "{e}");
    let overlap = "name = \"x\"\nversion = 1\ncontrollers = []\ntuning_seeds = [1, 2]\nscoring_seeds = [2, 3]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"s.toml\"\nlength_m = 1.0\n";
    let e = Suite::parse(overlap, "o.toml", &dir).unwrap_err();
    assert!(
        e.message
            .contains("seed 2 is both a tuning and a scoring seed"),
        "{e}"
    );
    let dup = overlap.replace("[1, 2]", "[1]")
        + "[[task]]\nid = \"a\"\ntitle = \"b\"\nscenario = \"s.toml\"\nlength_m = 1.0\n";
    let e = Suite::parse(&dup, "d.toml", &dir).unwrap_err();
    assert!(e.message.contains("appears twice"), "{e}");
    let zero = overlap
        .replace("[1, 2]", "[1]")
        .replace("length_m = 1.0", "length_m = 0.0");
    assert!(Suite::parse(&zero, "z.toml", &dir)
        .unwrap_err()
        .message
        .contains("length_m"));
}

/// A seed's draws: the same for the same seed, within the uniform bounds, different seeds
/// different; `sim.seed` is the seed.
#[test]
fn seed_draws_are_reproducible_and_bounded() {
    let suite = mini_suite("");
    let t = &suite.tasks[0];
    assert_eq!(seed_overrides(t, 5), seed_overrides(t, 5));
    assert_ne!(seed_overrides(t, 5), seed_overrides(t, 6));
    for seed in 0..200 {
        let o = seed_overrides(t, seed);
        let x: f64 = o[1].strip_prefix("initial.x_m=").unwrap().parse().unwrap();
        let h: f64 = o[0]
            .strip_prefix("initial.heading_rad=")
            .unwrap()
            .parse()
            .unwrap();
        assert!((8.0..12.0).contains(&x) && (-3.0..3.0).contains(&h));
        assert_eq!(o[2], format!("sim.seed={seed}"));
    }
}

/// Bit-identical results on one thread and on two.
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let suite = mini_suite("");
    let reg = Registry::builtin();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run_benchmark(&suite, &reg, &Options::default(), &|_, _, _| {}))
            .unwrap()
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a, b);
    assert_eq!(a.tasks.len(), 2);
    assert_eq!(a.tasks[0].runs.len(), 4);
    // The paper's law on its own circular field captures the isoline: a high score.
    let pi = a.tasks[0]
        .scores
        .iter()
        .find(|s| s.0 == "pi_isoline")
        .unwrap()
        .1;
    assert!(pi > 60.0, "{pi}");
}

/// A registered controller is scored on the same tasks and seeds: the built-in PI-like law
/// registered as a user's own scores exactly what the built-in does (no tuned gains recorded,
/// so both run the scenario's gains).
#[test]
fn a_registered_controller_is_scored_like_the_builtin_laws() {
    let suite = mini_suite("");
    let mut reg = Registry::builtin();
    reg.register("my_copy", |s: &isotrack_scenario::Scenario| {
        Box::new(s.controller()) as Box<dyn IsolineController + Send>
    });
    let opts = Options {
        controllers: Some(vec!["pi_isoline".into(), "my_copy".into()]),
        ..Options::default()
    };
    let r = run_benchmark(&suite, &reg, &opts, &|_, _, _| {}).unwrap();
    for t in &r.tasks {
        assert_eq!(t.scores[0].1, t.scores[1].1, "task {}", t.id);
        assert!(t.gains.contains_key("pi_isoline") && !t.gains.contains_key("my_copy"));
    }
    assert_eq!(r.controllers, ["pi_isoline", "my_copy"]);
    // The suite's own list plus every registered controller by default.
    let all = isotrack_bench::run::controllers_of(&suite, &reg, &Options::default()).unwrap();
    assert_eq!(all, ["pi_isoline", "sliding_mode", "my_copy"]);
    let unknown = Options {
        controllers: Some(vec!["nope".into()]),
        ..Options::default()
    };
    assert!(run_benchmark(&suite, &reg, &unknown, &|_, _, _| {}).is_err());
}

/// The tuning's coordinate search starts from the law's gains and keeps a candidate only when it
/// scores better on the tuning seeds: the tuned gains never score worse there.
#[test]
fn tuning_never_worsens_the_tuning_score() {
    let suite = mini_suite("");
    let task = &suite.tasks[0];
    let base = task_base(&suite, task).unwrap();
    let seeds = &suite.tuning_seeds;
    let mean = |kind: ControllerKind, g: Option<&std::collections::BTreeMap<String, f64>>| {
        let e = Entrant::Builtin(kind);
        seeds
            .iter()
            .map(|s| {
                let (sc, r) = run_one(&base, task, &e, g, *s, &mut NoTrace).unwrap();
                score(&r, &context(&sc, task)).total
            })
            .sum::<f64>()
            / seeds.len() as f64
    };
    for kind in [ControllerKind::PiIsoline, ControllerKind::SlidingMode] {
        let tuned = isotrack_bench::tune::tune(&base, task, kind, seeds);
        assert_eq!(tuned.keys().map(|k| k.as_str()).collect::<Vec<_>>(), {
            let mut k = isotrack_bench::tune::tuned_keys(kind).to_vec();
            k.sort();
            k
        });
        assert!(
            mean(kind, Some(&tuned)) >= mean(kind, None),
            "{kind:?} {tuned:?}"
        );
    }
    // The candidates: multiples of the current value, the current one first; from 0 a ladder.
    assert_eq!(
        isotrack_bench::tune::candidates("kp", 10.0),
        [10.0, 5.0, 20.0, 2.5, 40.0]
    );
    assert_eq!(
        isotrack_bench::tune::candidates("ki", 0.0),
        [0.0, 0.05, 0.2, 1.0]
    );
    assert_eq!(
        isotrack_bench::tune::candidates("alpha_star", 0.5),
        [0.5, 0.25, 1.0, 0.125]
    );
}
