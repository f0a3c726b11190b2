//! `isotrack benchmark` of team tasks (docs/BENCHMARK.md, "Team tasks"): every scored row is
//! the team score formula applied to the `summary.json` that `isotrack run` writes for the same
//! run (computed here, independently of the league's code), failures score as documented, and
//! the suite surface refuses what the team engine refuses (65, naming the suite's line).

mod common;
use common::{assert_fails, isotrack, write};
use serde_json::Value;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// The task's `set` entries (each flag of `isotrack run --set` and of the suite).
const RING_SET: [&str; 5] = [
    "sim.duration_s=120.0",
    "metrics.steady_state_fraction=0.5",
    "controller.max_turn_rate_radps=1.0",
    "sensor.noise_std=0.01",
    "team.ranging={ rate_hz = 10.0, noise_std_m = 0.1, dropout_probability = 0.1, delay_s = 0.0 }",
];

/// A volcano team driving straight off the DEM (`kp` ~ 0, heading north from 50 m below the
/// grid's top edge): every vehicle leaves the field.
const LOST_SET: [&str; 6] = [
    "sim.duration_s=120.0",
    "controller.level=135.1",
    "initial.heading_rad=1.5707963267948966",
    "team.count=3",
    "team.spread={ along = \"line\", step_m = 10.0 }",
    "team.spacing=\"range_balance\"",
];

fn toml_list(set: &[&str]) -> String {
    let items: Vec<String> = set.iter().map(|s| format!("'{s}'")).collect::<Vec<_>>();
    format!("[{}]", items.join(", "))
}

fn suite(dir: &Path) -> String {
    let s = scenarios();
    write(
        dir,
        "team.toml",
        &format!(
            r#"name = "team-mini"
version = 1
controllers = ["pi_isoline"]
tuning_seeds = [11]
scoring_seeds = [1, 2]

[[task]]
id = "ring"
title = "4 robots, noisy sensing and lossy ranging"
scenario = "{ring}"
length_m = 6.93
set = {ring_set}

[task.tuned.pi_isoline]
kp = 10.0
ki = 1.0

[[task]]
id = "lost"
title = "3 robots that drive off the DEM"
scenario = "{volcano}"
length_m = 313.0
set = {lost_set}

[task.tuned.pi_isoline]
kp = 1e-9
ki = 0.0
"#,
            ring = s.join("team-circular-4.toml").display(),
            volcano = s.join("volcano.toml").display(),
            ring_set = toml_list(&RING_SET),
            lost_set = toml_list(&LOST_SET),
        ),
    )
}

fn rows(path: &Path) -> Vec<HashMap<String, String>> {
    common::csv_rows(path)
}

fn num(v: &Value) -> Option<f64> {
    v.as_f64()
}

/// One vehicle's score by formula 2, from its `summary.json` record (`vehicles[i]`):
/// `(score / 100, held)`. `t_w` the steady window's start, `v` the speed, `l` the length.
fn vehicle_score(m: &Value, t_w: f64, v: f64, l: f64) -> (f64, f64) {
    if m["outcome"] != "completed" {
        return (0.0, 0.0);
    }
    let tc = num(&m["convergence_time_s"]);
    let capture = tc.map_or(0.0, |t| (1.0 - t / t_w).clamp(0.0, 1.0));
    let band = num(&m["time_in_band_fraction"]).unwrap_or(0.0);
    let distance =
        num(&m["steady_state_rms_isoline_distance_m"]).map_or(0.0, |d| 1.0 / (1.0 + d / l));
    let losses = 1.0 / (1.0 + m["track_losses"].as_u64().unwrap() as f64);
    let mean_w2 = num(&m["control_effort"]).unwrap() / num(&m["t_end_s"]).unwrap();
    let w_ref2 = (v / l) * (v / l);
    let effort = if mean_w2 <= w_ref2 {
        1.0
    } else {
        w_ref2 / mean_w2
    };
    let held = if tc.is_some() { 1.0 } else { band };
    let s = 0.2 * capture + 0.3 * band + held * (0.3 * distance + 0.1 * losses + 0.1 * effort);
    (s, held)
}

/// The team score of a run's `summary.json` (docs/BENCHMARK.md, "Team score"):
/// `(score, tracking, held, spacing, revisit)`.
fn team_score(summary: &Value, t_w: f64, v: f64, l: f64) -> [f64; 5] {
    let vehicles = summary["vehicles"].as_array().unwrap();
    let n = vehicles.len() as f64;
    let (mut tracking, mut held) = (0.0, 0.0);
    for m in vehicles {
        let (s, h) = vehicle_score(m, t_w, v, l);
        tracking += s / n;
        held += h / n;
    }
    let all = vehicles.iter().all(|m| m["outcome"] == "completed");
    let t = &summary["team"];
    let (mut spacing, mut revisit) = (0.0, 0.0);
    if all {
        if let Some(cv) = num(&t["gap_cv"]) {
            spacing = (1.0 - cv / (n - 1.0).sqrt()).clamp(0.0, 1.0);
        }
        if let (Some(m), Some(i)) = (
            num(&t["revisit_time_mean_s"]),
            num(&t["revisit_time_ideal_s"]),
        ) {
            revisit = (m / i).min(i / m);
        }
    }
    let (spacing, revisit) = (held * spacing, held * revisit);
    [
        100.0 * (0.5 * tracking + 0.25 * spacing + 0.25 * revisit),
        tracking,
        held,
        spacing,
        revisit,
    ]
}

/// A task of the test suite: id, scenario, `set`, the gains as `--set`, the steady window's
/// start t_w (s), the speed v0 (m/s) and `length_m`.
type Task<'a> = (&'a str, &'a str, &'a [&'a str], [&'a str; 2], f64, f64, f64);

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
        "{what}: results.csv {a} against the formula on summary.json {b}"
    );
}

#[test]
fn team_suite_scores_are_the_formula_of_the_runs_summaries() {
    let d = tempfile::tempdir().unwrap();
    let suite = suite(d.path());
    let out = d.path().join("out");
    let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let tasks: [Task; 2] = [
        (
            "ring",
            "team-circular-4.toml",
            &RING_SET,
            ["controller.kp=10.0", "controller.ki=1.0"],
            60.0,
            0.5,
            6.93,
        ),
        (
            "lost",
            "volcano.toml",
            &LOST_SET,
            ["controller.kp=1e-9", "controller.ki=0.0"],
            96.0,
            2.0,
            313.0,
        ),
    ];
    let mut scores = vec![];
    for (id, scen, set, gains, t_w, v, l) in tasks {
        let rows = rows(&out.join("tasks").join(id).join("results.csv"));
        assert_eq!(rows.len(), 2, "{id}: one row per scoring seed");
        for row in rows {
            let seed = &row["seed"];
            let run = d.path().join(format!("run-{id}-{seed}"));
            let mut args = vec![
                "run".to_string(),
                scenarios().join(scen).display().to_string(),
            ];
            for s in set.iter().chain(gains.iter()) {
                args.extend(["--set".to_string(), s.to_string()]);
            }
            args.extend([
                "--set".into(),
                format!("sim.seed={seed}"),
                "--out".into(),
                run.display().to_string(),
            ]);
            let a: Vec<&str> = args.iter().map(String::as_str).collect();
            let r = isotrack(&a);
            assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
            let summary: Value =
                serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap())
                    .unwrap();
            let [score, tracking, held, spacing, revisit] = team_score(&summary, t_w, v, l);
            let cell = |k: &str| {
                row[k]
                    .parse::<f64>()
                    .unwrap_or_else(|_| panic!("{k}: {:?}", row[k]))
            };
            close(cell("score"), score, &format!("{id} seed {seed} score"));
            if id == "lost" {
                assert_eq!((cell("spacing"), cell("revisit")), (0.0, 0.0));
            }
            close(cell("tracking"), tracking, "tracking");
            close(cell("held"), held, "held");
            close(cell("spacing"), spacing, "spacing");
            close(cell("revisit"), revisit, "revisit");
            let n = summary["vehicles"].as_array().unwrap().len();
            assert_eq!(row["vehicles"], n.to_string());
            let completed = summary["vehicles"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|m| m["outcome"] == "completed")
                .count();
            assert_eq!(row["vehicles_completed"], completed.to_string());
            // The metric columns are vehicle 0's (summary.json's top level), the team cells
            // its team object's (serde_json reads a number to within an ulp or so).
            close(
                cell("control_effort"),
                num(&summary["control_effort"]).unwrap(),
                "control_effort",
            );
            match num(&summary["team"]["gap_cv"]) {
                Some(cv) => close(cell("gap_cv"), cv, "gap_cv"),
                None => assert_eq!(row["gap_cv"], ""),
            }
            scores.push((id, completed, score, row["outcome"].clone()));
        }
    }
    // What the formula gives here: the ring spreads (its spacing and revisit terms count); the
    // lost team's three vehicles leave the field, so the row's outcome is theirs, and the team
    // terms are 0 (checked by the formula above: spacing = revisit = 0 when a vehicle did not
    // complete). Before att32e-3 vehicle 0 completed without converging: its two neighbours,
    // gone, stayed in its ring as parked vehicles whose ranges it kept balancing; now the ring
    // closes around them, vehicle 0 is left alone at its nominal speed and leaves the field
    // too.
    for (id, completed, score, outcome) in scores {
        match id {
            "ring" => {
                assert_eq!((completed, outcome.as_str()), (4, "completed"));
                // Spread (gap CV about 0.01) but, with the sensor's noise, never converged
                // (held about half: the band share): the team terms count at that share.
                assert!(score > 25.0, "ring: {score}");
            }
            _ => {
                assert_eq!((completed, outcome.as_str()), (0, "left_field"));
                assert!(score < 50.0 / 3.0, "lost: {score}");
            }
        }
    }
}

/// A team task's scenario problems are the suite's (65, at the line of the `set` entry or the
/// task's `scenario`), found before any run; a team task on an isoline that is not closed is
/// refused, not scored on its tracking half.
#[test]
fn team_tasks_the_engine_refuses_are_suite_errors() {
    let d = tempfile::tempdir().unwrap();
    let volcano = scenarios().join("volcano.toml");
    let cases: [(&str, &str, &[&str]); 4] = [
        ("\"team.count=0\"", "team.count", &["team-bad.toml:10:", "must be in [1, 10000]"]),
        ("\"team.bogus=1.0\"", "team.bogus", &["team-bad.toml:10:", "unknown field `bogus`"]),
        (
            "\"team.count=3\", \"team.spread={ along = 'line', step_m = 10.0 }\", \"team.ranging={ rate_hz = 3.0 }\"",
            "rate_hz",
            &["team-bad.toml:", "rate_hz"],
        ),
        // The 110.3 m contour leaves the DEM: no closed loop for the team metrics.
        (
            "\"controller.level=110.3\", \"team.count=3\", \"team.spread={ along = 'line', step_m = 10.0 }\"",
            "closed isoline",
            &["team-bad.toml:7:1", "needs a closed isoline"],
        ),
    ];
    for (i, (set, what, needles)) in cases.into_iter().enumerate() {
        let suite = write(
            d.path(),
            "team-bad.toml",
            &format!(
                "name = \"bad\"\nversion = 1\ncontrollers = [\"pi_isoline\"]\ntuning_seeds = [11]\nscoring_seeds = [1]\n[[task]]\nscenario = \"{}\"\nid = \"v\"\ntitle = \"volcano team\"\nset = [{set}]\nlength_m = 313.0\n",
                volcano.display()
            ),
        );
        let out = d.path().join(format!("out{i}"));
        let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
        assert_fails(&o, 65, needles);
        assert!(
            !out.join("tasks").exists(),
            "{what}: nothing ran before the refusal"
        );
    }
}
