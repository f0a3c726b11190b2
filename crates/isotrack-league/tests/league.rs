//! The benchmark: the score formulas by hand, suite errors, seed draws, determinism over thread
//! counts, a registered controller on the same footing as the built-in laws (and the names it
//! may not take), and the tuning.

use isotrack_core::IsolineController;
use isotrack_league::run::{context, run_one, task_base};
use isotrack_league::score::{score, ScoreContext, Scoring};
use isotrack_league::suite::seed_overrides;
use isotrack_league::{run_benchmark, BenchError, Entrant, NameError, Options, Registry, Suite};
use isotrack_scenario::schema::ControllerKind;
use isotrack_sim::{NoTrace, Outcome, RunMetrics, RunResult};
use std::path::{Path, PathBuf};

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// Two short tasks, two laws, one tuning seed and two scoring seeds.
fn mini_suite(extra: &str) -> Suite {
    mini_suite_with("", extra)
}

/// [`mini_suite`] with `head` among the top-level keys and `first` in the first task.
fn mini_suite_with(head: &str, first: &str) -> Suite {
    let text = format!(
        r#"
name = "mini"
version = 1
{head}
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
{first}

[[task]]
id = "plumes"
title = "Gaussian plumes"
scenario = "gaussian-plumes-pm25.toml"
set = ["sim.duration_s=60.0", "controller.max_turn_rate_radps=1.0"]
length_m = 15.9
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
        reached_level: true,
        farthest_from_start_m: 10.0,
    }
}

/// The context of the hand-worked scores: steady window from 240 s, L = 5 m, v = 0.5 m/s.
fn ctx(scoring: Scoring) -> ScoreContext {
    ScoreContext {
        steady_start_s: 240.0,
        length_m: 5.0,
        speed_mps: 0.5,
        scoring,
    }
}

/// The documented formula 1, by hand: capture 1 - 60/240 = 0.75, band 0.8, distance
/// 1/(1 + 0.5/5) = 10/11, losses 1/2, effort: mean omega^2 = 20/300, w_ref^2 = (0.5/5)^2 = 0.01,
/// so 0.01/(1/15) = 0.15.
#[test]
fn score_is_the_documented_formula() {
    let ctx = ctx(Scoring::V1);
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

/// The metrics of a law that never came near the isoline: no convergence, never in the band,
/// so no track loss either; it barely turns (effort 1/300 rad^2/s over 300 s, within
/// w_ref^2 = 0.01); its steady RMS distance is 5 m = L.
fn never_captured() -> RunMetrics {
    RunMetrics {
        convergence_time_s: None,
        time_in_band_fraction: Some(0.0),
        track_losses: 0,
        control_effort: 1.0,
        steady_state_rms_isoline_distance_m: Some(5.0),
        ..metrics()
    }
}

/// Formula 1 paid a law that never captured the isoline: distance 1/(1 + 5/5) = 1/2, losses
/// 1/(1 + 0) = 1, effort 1, so 100 * (0.3/2 + 0.1 + 0.1) = 35. Formula 2 scales distance,
/// losses and effort by held = band = 0: the score is 0.
#[test]
fn formula_2_gives_nothing_for_an_isoline_never_captured() {
    let r = result(never_captured(), Outcome::Completed, 300.0);
    let v1 = score(&r, &ctx(Scoring::V1));
    assert!((v1.total - 35.0).abs() < 1e-9, "{v1:?}");
    assert_eq!(v1.parts, [0.0, 0.0, 0.5, 1.0, 1.0]);
    let v2 = score(&r, &ctx(Scoring::V2));
    assert_eq!(v2.total, 0.0, "{v2:?}");
    assert_eq!(v2.parts, [0.0; 5]);
}

/// A good run that converged at t = 0: capture 1, band 1, distance 10/11 (0.5 m at L = 5 m),
/// no loss, effort 0.15 (as in the formula-1 test): formula 2 gives exactly formula 1's
/// 100 * (0.2 + 0.3 + 0.3*10/11 + 0.1 + 0.1*0.15) = 89.77... (held = 1 once converged); so it does
/// for a run that converged later (t_c = 60 s, band 0.8, one loss).
#[test]
fn formula_2_equals_formula_1_once_converged() {
    let good = RunMetrics {
        convergence_time_s: Some(0.0),
        time_in_band_fraction: Some(1.0),
        track_losses: 0,
        ..metrics()
    };
    let r = result(good, Outcome::Completed, 300.0);
    let want = 100.0 * (0.2 + 0.3 + 0.3 * 10.0 / 11.0 + 0.1 + 0.1 * 0.15);
    for scoring in [Scoring::V1, Scoring::V2] {
        let s = score(&r, &ctx(scoring));
        assert!((s.total - want).abs() < 1e-9, "{scoring:?} {s:?}");
    }
    let later = result(metrics(), Outcome::Completed, 300.0);
    assert_eq!(
        score(&later, &ctx(Scoring::V1)),
        score(&later, &ctx(Scoring::V2))
    );
}

/// Not converged but in the band for 40 % of the steady window, one track loss: formula 2 pays
/// distance, losses and effort at 40 %: parts [0, 0.4, 0.4*10/11, 0.4*0.5, 0.4*0.15].
#[test]
fn formula_2_scales_the_holding_parts_by_the_band_share() {
    let m = RunMetrics {
        convergence_time_s: None,
        time_in_band_fraction: Some(0.4),
        ..metrics()
    };
    let s = score(&result(m, Outcome::Completed, 300.0), &ctx(Scoring::V2));
    let want = [0.0, 0.4, 0.4 * 10.0 / 11.0, 0.4 * 0.5, 0.4 * 0.15];
    for (got, w) in s.parts.iter().zip(want) {
        assert!((got - w).abs() < 1e-12, "{:?}", s.parts);
    }
    let total = 100.0 * (0.3 * 0.4 + 0.4 * (0.3 * 10.0 / 11.0 + 0.1 * 0.5 + 0.1 * 0.15));
    assert!((s.total - total).abs() < 1e-9);
}

/// The PI-like law with kp = 1e-9 and ki = 0 barely turns (|omega| <= 1e-9 * |eps|), so it
/// drives almost straight away from the isoline and never holds it. Run through the benchmark:
/// formula 1 pays it at least the effort part, 10 (its mean omega^2 is far below w_ref^2); formula
/// 2 scores it about 0 on every seed.
#[test]
fn a_law_that_never_captures_scores_about_0_with_formula_2() {
    let run = |scoring: i64| {
        let suite = mini_suite_with(
            &format!("scoring = {scoring}"),
            "[task.tuned.pi_isoline]\nkp = 1e-9\nki = 0.0\n",
        );
        let opts = Options {
            controllers: Some(vec!["pi_isoline".into()]),
            ..Options::default()
        };
        run_benchmark(&suite, &Registry::builtin(), &opts, &|_, _, _| {}).unwrap()
    };
    let (v1, v2) = (run(1), run(2));
    assert_eq!((v1.scoring, v2.scoring), (Scoring::V1, Scoring::V2));
    let circ1 = &v1.tasks[0];
    assert_eq!(circ1.gains["pi_isoline"]["kp"], 1e-9);
    for row in &circ1.runs {
        assert_eq!(row.outcome, "completed");
        assert_eq!(row.convergence_time_s, None);
        assert!(row.score.total >= 10.0, "{row:?}");
    }
    for row in &v2.tasks[0].runs {
        assert!(row.score.total < 1.0, "{row:?}");
    }
}

#[test]
fn suite_errors_are_located_and_seeds_disjoint() {
    let dir = scenarios();
    let e = Suite::parse(
        "name = \"x\"\nversion = 1\ncontrollers = [\"pid\"]\ntuning_seeds = [1]\nscoring_seeds = [2]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"s.toml\"\nlength_m = 1.0\nspeed = 3\n",
        "bad.toml",
        &dir,
    )
    .unwrap_err();
    assert_eq!(e.location.map(|l| l.0), Some(11), "{e}");
    assert!(e.to_string().starts_with("bad.toml:11:"), "{e}");
    let overlap = "name = \"x\"\nversion = 1\ncontrollers = [\"pid\"]\ntuning_seeds = [1, 2]\nscoring_seeds = [2, 3]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"s.toml\"\nlength_m = 1.0\n";
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

/// Issue 30: a line feed in a suite's TOML key (`vary."a\nerror: forged"`) is echoed escaped,
/// so the message stays one line; it was printed raw, starting a line of the file's author.
#[test]
fn suite_keys_are_echoed_on_one_line() {
    let dir = scenarios();
    let text = "name = \"x\"\nversion = 1\ncontrollers = [\"pid\"]\ntuning_seeds = [1]\nscoring_seeds = [2]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"s.toml\"\nlength_m = 1.0\nvary = { \"k\\nerror: forged\" = { uniform = [2.0, 1.0] } }\n";
    let e = Suite::parse(text, "lf.toml", &dir).unwrap_err();
    assert!(e.message.contains("vary k\\x0aerror: forged"), "{e}");
    assert!(!e.to_string().contains('\n'), "{e}");
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
    })
    .unwrap();
    let opts = Options {
        controllers: Some(vec!["pi_isoline".into(), "my_copy".into()]),
        ..Options::default()
    };
    let r = run_benchmark(&suite, &reg, &opts, &|_, _, _| {}).unwrap();
    for t in &r.tasks {
        assert_eq!(t.scores[0].1, t.scores[1].1, "task {}", t.id);
        assert!(t.gains.contains_key("pi_isoline") && !t.gains.contains_key("my_copy"));
        assert!(t.runs.iter().all(|r| r.outcome == "completed"));
    }
    assert_eq!(r.controllers, ["pi_isoline", "my_copy"]);
    // The suite's own list plus every registered controller by default.
    let all = isotrack_league::run::controllers_of(&suite, &reg, &Options::default()).unwrap();
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
                score(&r, &context(&sc, task, Scoring::V2)).total
            })
            .sum::<f64>()
            / seeds.len() as f64
    };
    for kind in [ControllerKind::PiIsoline, ControllerKind::SlidingMode] {
        let tuned = isotrack_league::tune::tune(&base, task, kind, seeds, Scoring::V2);
        assert_eq!(tuned.keys().map(|k| k.as_str()).collect::<Vec<_>>(), {
            let mut k = isotrack_league::tune::tuned_keys(kind).to_vec();
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
        isotrack_league::tune::candidates("kp", 10.0),
        [10.0, 5.0, 20.0, 2.5, 40.0]
    );
    assert_eq!(
        isotrack_league::tune::candidates("ki", 0.0),
        [0.0, 0.05, 0.2, 1.0]
    );
    assert_eq!(
        isotrack_league::tune::candidates("alpha_star", 0.5),
        [0.5, 0.25, 1.0, 0.125]
    );
}

/// A one-task suite over the circular scenario: `top` lines after `name`, then the task with
/// `task` lines after its `length_m`. Line numbers: `name` is line 1, `top` starts at line 2.
fn one_task(top: &str, task: &str) -> String {
    format!(
        "name = \"x\"\n{top}\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"paper-fig2b-circular.toml\"\nset = [\"sim.duration_s=20.0\"]\nlength_m = 6.93\n{task}"
    )
}

const TOP: &str =
    "version = 1\ncontrollers = [\"pi_isoline\", \"pid\"]\ntuning_seeds = [7]\nscoring_seeds = [1, 2]";

fn parse_err(text: &str) -> isotrack_league::SuiteError {
    Suite::parse(text, "s.toml", &scenarios()).unwrap_err()
}

/// What the file alone shows is refused at its line: no controllers, a law named twice or not
/// built in, a seed twice, ids equal ignoring case, `vary`/`set` of `sim.seed`, gains for a law
/// that is not built in.
#[test]
fn suite_checks_name_the_line() {
    let cases: [(String, usize, &str); 11] = [
        (
            one_task(&TOP.replace("[\"pi_isoline\", \"pid\"]", "[]"), ""),
            3,
            "controllers is empty",
        ),
        (
            one_task(&TOP.replace("\"pid\"]", "\"pi_isoline\"]"), ""),
            3,
            "`pi_isoline` appears twice",
        ),
        (
            one_task(&TOP.replace("\"pid\"]", "\"my_law\"]"), ""),
            3,
            "`my_law` is not a built-in law",
        ),
        (
            one_task(&TOP.replace("[1, 2]", "[1, 2, 1]"), ""),
            5,
            "scoring_seeds: seed 1 appears twice",
        ),
        (
            one_task(&TOP.replace("[7]", "[7, 7]"), ""),
            4,
            "tuning_seeds: seed 7 appears twice",
        ),
        (
            one_task(TOP, "vary = { \"sim.seed\" = { uniform = [0.0, 9.0] } }\n"),
            12,
            "vary sim.seed",
        ),
        (
            one_task(TOP, "").replace("\"sim.duration_s=20.0\"", "\"sim.seed=3\""),
            10,
            "set sim.seed has no effect",
        ),
        (
            one_task(TOP, "[task.tuned.my_law]\nkp = 1.0\n"),
            12,
            "tuned gains for `my_law`, which is not a built-in law",
        ),
        (
            one_task(TOP, "")
                + "[[task]]\nid = \"A\"\ntitle = \"b\"\nscenario = \"paper-fig2b-circular.toml\"\nlength_m = 1.0\n",
            13,
            "task id \"A\" differs from task id \"a\" only in case",
        ),
        // Issue 30 (att30c-17 for suites): draws that overflow to `inf`, refused by the
        // sweep's own check (`Dist::check_draws_finite`) at the `vary` key's line.
        (
            one_task(
                TOP,
                "[task.vary.\"initial.x_m\"]\nuniform = [-1e308, 1e308]\n",
            ),
            12,
            "is wider than the largest 64-bit float (about 1.8e308): every draw would be inf",
        ),
        (
            one_task(
                TOP,
                "[task.vary.\"initial.x_m\"]\nnormal = [0.0, 1e307]\n",
            ),
            12,
            "within 40 std: some draws would be inf",
        ),
    ];
    for (text, line, says) in cases {
        let e = parse_err(&text);
        assert_eq!(e.location.map(|l| l.0), Some(line), "{e}\n{text}");
        assert!(e.to_string().starts_with(&format!("s.toml:{line}:")), "{e}");
        assert!(e.message.contains(says), "{e}");
    }
    // A valid one parses; `scoring` takes 1 or 2 only.
    let ok = Suite::parse(&one_task(TOP, ""), "s.toml", &scenarios()).unwrap();
    assert_eq!(ok.scoring, Scoring::V2);
    let e = parse_err(&one_task(&format!("{TOP}\nscoring = 3"), ""));
    assert_eq!(e.location.map(|l| l.0), Some(6), "{e}");
    assert!(e.message.contains("the score formulas are 1 and 2"), "{e}");
}

/// What only the scenario shows is refused before any run, at the suite key it comes from: a
/// gain out of range or misspelt (at the gain's line), a `vary` key that is not a scenario key
/// or draws invalid values (at the `vary` key's line), a `set` entry (at its line).
#[test]
fn runs_the_scenario_refuses_fail_the_suite_at_their_line() {
    let run = |text: &str| {
        let suite = Suite::parse(text, "s.toml", &scenarios()).unwrap();
        match run_benchmark(
            &suite,
            &Registry::builtin(),
            &Options::default(),
            &|_, _, _| panic!("a run started"),
        ) {
            Err(BenchError::Suite(e)) => e,
            other => panic!("{:?}", other.map(|r| r.overall)),
        }
    };
    let cases: [(String, usize, &str); 6] = [
        (
            one_task(TOP, "[task.tuned.pi_isoline]\nkp = -5.0\nki = 1.0\n"),
            13,
            "tuned pi_isoline.kp = -5.0: `controller.kp`",
        ),
        (
            one_task(TOP, "[task.tuned.pid]\nkd = 1.0\nkpp = 2.0\n"),
            14,
            "tuned pid.kpp = 2.0",
        ),
        (
            one_task(
                TOP,
                "vary = { \"initial.heading\" = { uniform = [0.0, 1.0] } }\n",
            ),
            12,
            "vary initial.heading=",
        ),
        (
            one_task(
                TOP,
                "[task.vary.\"sensor.rate_hz\"]\nuniform = [-2.0, -1.0]\n",
            ),
            12,
            "`sensor.rate_hz`",
        ),
        (
            one_task(TOP, "").replace("\"sim.duration_s=20.0\"", "\"sim.duration_s=-1.0\""),
            10,
            "task a: ",
        ),
        (
            one_task(TOP, "").replace("\"sim.duration_s=20.0\"", "\"sim.durations=1.0\""),
            10,
            "sim.durations",
        ),
    ];
    for (text, line, says) in cases {
        let e = run(&text);
        assert_eq!(e.location.map(|l| l.0), Some(line), "{e}\n{text}");
        assert!(e.to_string().starts_with(&format!("s.toml:{line}:")), "{e}");
        assert!(e.message.contains(says), "{e}");
    }
}

/// A registered controller may not take a built-in law's name (its row would replace the law's),
/// an empty name, or one that breaks the Markdown table or CSV; the registry is then unchanged.
#[test]
fn registry_refuses_names_that_would_lie() {
    let make = |s: &isotrack_scenario::Scenario| {
        Box::new(s.controller()) as Box<dyn IsolineController + Send>
    };
    let mut reg = Registry::builtin();
    let names_before = reg.names().len();
    let long = "x".repeat(65);
    let cases: [(&str, NameError); 13] = [
        (
            "pi_isoline",
            NameError::Builtin("pi_isoline".into(), "pi_isoline"),
        ),
        ("PID", NameError::Builtin("PID".into(), "pid")),
        ("", NameError::Empty),
        ("a|b", NameError::BadChar("a|b".into(), '|')),
        ("a\nb", NameError::BadChar("a\nb".into(), '\n')),
        // Issue 30 (doors30a), item 7: a zero-width space or a joiner makes a name that prints
        // as another (`pi_isoline` + U+200B looks like the built-in's row).
        (
            "pi_isoline\u{200b}",
            NameError::BadChar("pi_isoline\u{200b}".into(), '\u{200b}'),
        ),
        (
            "my\u{2060}law",
            NameError::BadChar("my\u{2060}law".into(), '\u{2060}'),
        ),
        ("a\u{7}", NameError::BadChar("a\u{7}".into(), '\u{7}')),
        (
            "a\u{2028}b",
            NameError::BadChar("a\u{2028}b".into(), '\u{2028}'),
        ),
        // Issue 30 (att30b item 3): the one plain-text rule, format characters included (an
        // interlinear annotation mark, an Egyptian hieroglyph format control).
        (
            "a\u{fff9}b",
            NameError::BadChar("a\u{fff9}b".into(), '\u{fff9}'),
        ),
        (
            "a\u{13430}",
            NameError::BadChar("a\u{13430}".into(), '\u{13430}'),
        ),
        (" mine", NameError::Whitespace(" mine".into())),
        (&long, NameError::TooLong(65)),
    ];
    for (name, want) in cases {
        assert_eq!(reg.register(name, make), Err(want), "{name:?}");
    }
    assert_eq!(reg.names().len(), names_before);
    assert!(matches!(reg.get("pi_isoline"), Some(Entrant::Builtin(_))));
    // The messages say what was wrong.
    let e = reg.register("pi_isoline", make).unwrap_err().to_string();
    assert!(e.contains("built-in law \"pi_isoline\""), "{e}");
    let e = reg.register("a|b", make).unwrap_err().to_string();
    assert!(e.contains("'|'") && e.contains("Markdown"), "{e}");
    // A name of its own (64 characters, Unicode) is fine, and registering it again replaces it.
    let ok = "é".repeat(64);
    reg.register(&ok, make).unwrap();
    reg.register(&ok, make).unwrap();
    assert_eq!(reg.custom_names(), [ok.as_str()]);
}

/// Issue 30 (doors30a), item 7: smaller edits a suite accepted without a word are refused at
/// their line: gains for a built-in law the suite does not score (they never ran), a key `set`
/// twice in one task (the last silently won) or both `set` and drawn by `vary` (the draw
/// silently won), a suite name with a zero-width space.
#[test]
fn silent_suite_edits_are_refused_at_their_line() {
    let cases: [(String, usize, &str); 4] = [
        (
            one_task(TOP, "[task.tuned.sliding_mode]\ngamma = 0.3\n"),
            12,
            "tuned gains for sliding_mode, which the suite does not score (controllers = [pi_isoline, pid])",
        ),
        (
            one_task(TOP, "").replace(
                "\"sim.duration_s=20.0\"]",
                "\"sim.duration_s=20.0\", \"sensor.rate_hz=10\", \" sim.duration_s = 30.0\"]",
            ),
            10,
            "set assigns sim.duration_s twice (set[0] and set[2])",
        ),
        (
            one_task(TOP, "vary = { \"sim.duration_s\" = { uniform = [10.0, 20.0] } }\n"),
            10,
            "sim.duration_s is both set and in vary",
        ),
        (
            one_task(TOP, "").replacen("name = \"x\"", "name = \"x\u{200b}\"", 1),
            1,
            "visible name, without control or invisible (zero-width) characters",
        ),
    ];
    for (text, line, says) in cases {
        let e = parse_err(&text);
        assert_eq!(e.location.map(|l| l.0), Some(line), "{e}\n{text}");
        assert!(e.message.contains(says), "{e}");
    }
}

/// Issue 30 (fix30), item 7: a key set twice spelt otherwise (`sim . duration_s`, an inline
/// table `sim = { duration_s = 3.0 }`) is the same key; `set controller.kp` beside a tuned
/// `kp` (the tuned one silently won) is refused; a title with a bidi override, a zero-width
/// space, or of 100 000 characters is refused at its line.
#[test]
fn set_keys_are_compared_as_toml_reads_them_and_titles_bounded() {
    let twice = |second: &str| {
        one_task(TOP, "").replace(
            "\"sim.duration_s=20.0\"]",
            &format!("\"sim.duration_s=20.0\", {second}]"),
        )
    };
    let long_title = "t".repeat(100_000);
    let cases: Vec<(String, usize, &str)> = vec![
        (
            twice("\"sim . duration_s=3\""),
            10,
            "set assigns sim.duration_s twice (set[0] and set[1])",
        ),
        (
            twice("\"sim={duration_s=3.0}\""),
            10,
            "set assigns sim.duration_s twice (set[0] and set[1])",
        ),
        (
            twice("\"controller.kp=5.0\"") + "[task.tuned.pi_isoline]\nkp = 20.0\n",
            13,
            "assigns controller.kp and [task.tuned.pi_isoline] gives kp",
        ),
        (
            one_task(TOP, "").replacen("title = \"a\"", "title = \"a\u{202e}b\"", 1),
            8,
            // One escape form, as every message (att30c-10): not Debug-quoted, `\\` doubled.
            "title `a\\u{202e}b`: give at most 200 visible characters, without control or invisible",
        ),
        (
            one_task(TOP, "").replacen("title = \"a\"", "title = \"a\u{200b}\"", 1),
            8,
            "without control or invisible",
        ),
        (
            one_task(TOP, "").replacen("title = \"a\"", &format!("title = \"{long_title}\""), 1),
            8,
            "give at most 200 visible characters",
        ),
    ];
    for (text, line, says) in cases {
        let e = parse_err(&text);
        assert!(e.message.contains(says), "{e}");
        assert_eq!(e.location.map(|l| l.0), Some(line), "{e}");
    }
}

/// The team metrics `summary.json` records, for the hand-worked team scores.
fn team_record(
    count: usize,
    gap_cv: Option<f64>,
    mean_s: Option<f64>,
) -> isotrack_runs::summary::TeamRecord {
    isotrack_runs::summary::TeamRecord {
        count,
        isoline_length_m: Some(40.0),
        gap_cv,
        gap_cv_final: gap_cv,
        time_to_even_s: None,
        revisit_time_max_s: Some(30.0),
        revisit_time_mean_s: mean_s,
        revisit_time_ideal_s: Some(20.0),
        revisit_time_ideal_active_s: None,
        min_separation_m: Some(1.0),
        order_preserved: true,
        speed_range_mps: None,
        moving_isoline: None,
        open_isoline: None,
    }
}

/// The team score (docs/BENCHMARK.md, "Team score") by hand: 4 vehicles, each scoring the
/// hand-worked single run of `score_is_the_documented_formula` (formula 2, converged: the same
/// as formula 1, s = 0.2*0.75 + 0.3*0.8 + 0.3*10/11 + 0.1*0.5 + 0.1*0.15 per unit), gap CV 0.6
/// (spacing 1 - 0.6/sqrt(3)), mean revisit 25 s against the ideal 20 s (revisit 0.8; 16 s gives
/// 0.8 too: the ratio counts either way). One vehicle that left the field: tracking 3/4 of it,
/// held 3/4, spacing and revisit 0. No team metrics: the tracking half only. A team of one is
/// evenly spread (spacing 1).
#[test]
fn team_score_is_the_documented_formula() {
    use isotrack_league::score::team_score;
    let ctx = ctx(Scoring::V2);
    let s1 = 0.2 * 0.75 + 0.3 * 0.8 + 0.3 * 10.0 / 11.0 + 0.1 * 0.5 + 0.1 * 0.15;
    let ok = || result(metrics(), Outcome::Completed, 300.0);
    let runs = vec![ok(), ok(), ok(), ok()];
    let spacing = 1.0 - 0.6 / 3f64.sqrt();
    for mean in [25.0, 16.0] {
        let (s, p) = team_score(&runs, Some(&team_record(4, Some(0.6), Some(mean))), &ctx);
        let want = 100.0 * (0.5 * s1 + 0.25 * spacing + 0.25 * 0.8);
        assert!((s.total - want).abs() < 1e-9, "{} {want}", s.total);
        assert!((p.tracking - s1).abs() < 1e-12 && p.held == 1.0);
        assert!((p.spacing - spacing).abs() < 1e-12 && (p.revisit - 0.8).abs() < 1e-12);
    }
    // One of four left the field.
    let mut lost = runs.clone();
    lost[2] = result(metrics(), Outcome::LeftField, 100.0);
    let (s, p) = team_score(&lost, Some(&team_record(4, Some(0.6), Some(25.0))), &ctx);
    assert!(
        (s.total - 100.0 * 0.5 * 0.75 * s1).abs() < 1e-9,
        "{}",
        s.total
    );
    assert_eq!((p.held, p.spacing, p.revisit), (0.75, 0.0, 0.0));
    // No team metrics measured.
    let (s, _) = team_score(&runs, None, &ctx);
    assert!((s.total - 100.0 * 0.5 * s1).abs() < 1e-9);
    // A cluster (gap CV sqrt(N - 1)) scores no spacing; a team of one is evenly spread.
    let (_, p) = team_score(
        &runs,
        Some(&team_record(4, Some(3f64.sqrt()), Some(20.0))),
        &ctx,
    );
    assert_eq!((p.spacing, p.revisit), (0.0, 1.0));
    let (_, p) = team_score(
        &runs[..1],
        Some(&team_record(1, Some(0.0), Some(20.0))),
        &ctx,
    );
    assert_eq!(p.spacing, 1.0);
    // Never captured (formula 2): held is the band share, and scales both team terms.
    let mut m = metrics();
    m.convergence_time_s = None;
    let (_, p) = team_score(
        &[
            result(m.clone(), Outcome::Completed, 300.0),
            result(m, Outcome::Completed, 300.0),
        ],
        Some(&team_record(2, Some(0.0), Some(20.0))),
        &ctx,
    );
    assert!((p.held - 0.8).abs() < 1e-12 && (p.spacing - 0.8).abs() < 1e-12);
}

/// A registered controller flies one vehicle: on a team task it is refused before any run
/// (never scored 0), naming the task and the controller.
#[test]
fn a_registered_controller_is_refused_on_a_team_task() {
    let text = r#"
name = "team"
version = 1
controllers = ["pi_isoline"]
tuning_seeds = [11]
scoring_seeds = [1]

[[task]]
id = "ring"
title = "4 robots"
scenario = "team-circular-4.toml"
set = ["sim.duration_s=10.0"]
length_m = 6.93
"#;
    let suite = Suite::parse(text, "team.toml", &scenarios()).unwrap();
    let mut reg = Registry::builtin();
    reg.register("my_copy", |s: &isotrack_scenario::Scenario| {
        Box::new(s.controller()) as Box<dyn IsolineController + Send>
    })
    .unwrap();
    let e = run_benchmark(&suite, &reg, &Options::default(), &|_, _, _| {}).unwrap_err();
    assert!(
        matches!(&e, BenchError::TeamController { task, controller } if task == "ring" && controller == "my_copy"),
        "{e}"
    );
    // The built-in law alone runs the team: one row, with the team columns.
    let opts = Options {
        controllers: Some(vec!["pi_isoline".into()]),
        ..Options::default()
    };
    let r = run_benchmark(&suite, &reg, &opts, &|_, _, _| {}).unwrap();
    let t = &r.tasks[0];
    assert!(t.team);
    let row = t.runs[0].team.as_ref().expect("team columns");
    assert_eq!((row.vehicles, row.vehicles_completed), (4, 4));
}

/// The bundled team suite loads and every run it defines is valid (each law's recorded gains,
/// each scoring and tuning seed), every task is a team on a closed isoline (the refusals of
/// `run_benchmark` pass), the ERA5 task's scenario reads the repository's ERA5 file, shortened
/// to 8000 s with its 1 Hz sensor, and the volcano task flies 6 robots. Running it is the
/// benchmark's job (a few minutes); CI checks it this far.
#[test]
fn the_team_suite_is_valid_as_written() {
    let path = scenarios().join("../suites/team-v1.toml");
    let suite = Suite::load(&path).unwrap();
    let reg = Registry::builtin();
    let bases: Vec<_> = suite
        .tasks
        .iter()
        .map(|t| task_base(&suite, t).unwrap())
        .collect();
    isotrack_league::run::check_runs(&suite, &reg, &suite.controllers, &bases, true).unwrap();
    let ids: Vec<&str> = suite.tasks.iter().map(|t| t.id.as_str()).collect();
    assert_eq!(
        ids,
        ["circular-4", "volcano-6", "era5-uav-4", "puff-edge-3"]
    );
    let counts: Vec<usize> = bases
        .iter()
        .map(|b| b.spec().team.as_ref().unwrap().starts.len())
        .collect();
    assert_eq!(counts, [4, 6, 4, 3]);
    for b in &bases {
        assert!(b.team_isoline().as_team_isoline().is_some());
    }
    let era5 = bases[2].spec();
    assert_eq!(era5.sim.duration_s, 8000.0);
    assert_eq!(era5.sensor.rate_hz, 1.0);
}
