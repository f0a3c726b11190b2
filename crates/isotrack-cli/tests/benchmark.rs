//! `isotrack benchmark` and `isotrack report` end to end: the files, their columns and values,
//! resume, exit codes; and the HTML pages in a real browser (headless Chromium): the DOM they
//! build, no script error, and a screenshot that is not blank.

mod browser;
mod common;
use browser::{assert_no_script_error, assert_not_blank, chromium, load};
use common::{assert_fails, isotrack, stderr, write};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A two-task suite over the repository's scenarios (short runs).
fn mini_suite(dir: &Path) -> String {
    let scen = repo().join("scenarios");
    write(
        dir,
        "mini.toml",
        &format!(
            r#"name = "mini"
version = 1
controllers = ["pi_isoline", "sliding_mode_smooth"]
tuning_seeds = [11]
scoring_seeds = [1, 2]

[[task]]
id = "circular"
title = "circular field, 10 Hz"
scenario = "{s}/paper-fig2b-circular.toml"
set = ["sim.duration_s=60.0", "sensor.rate_hz=10.0", "controller.max_turn_rate_radps=1.0"]
length_m = 6.93
vary = {{ "initial.heading_rad" = {{ uniform = [-3.0, 3.0] }} }}

[[task]]
id = "volcano"
title = "volcano DEM"
scenario = "{s}/volcano.toml"
set = ["sim.duration_s=200.0"]
length_m = 313.0
"#,
            s = scen.display()
        ),
    )
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn benchmark_writes_the_leaderboard_and_resumes() {
    let d = tempfile::tempdir().unwrap();
    let suite = mini_suite(d.path());
    let out = d.path().join("out");
    let o = isotrack(&[
        "benchmark",
        &suite,
        "--out",
        out.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let md = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        md.starts_with("| rank | controller | overall | circular | volcano |"),
        "{md}"
    );
    let csv = read(&out.join("leaderboard.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "rank,controller,overall,circular,volcano");
    assert_eq!(lines.len(), 3);
    // Overall = mean of the task scores; ranked best first.
    let rows: Vec<Vec<f64>> = lines[1..]
        .iter()
        .map(|l| l.split(',').skip(2).map(|v| v.parse().unwrap()).collect())
        .collect();
    for r in &rows {
        assert!((r[0] - (r[1] + r[2]) / 2.0).abs() < 0.011, "{r:?}");
        assert!(r.iter().all(|v| (0.0..=100.0).contains(v)));
    }
    assert!(rows[0][0] >= rows[1][0]);
    // Each task's results: one row per controller and scoring seed; score = the weighted parts.
    let res = read(&out.join("tasks/circular/results.csv"));
    let mut it = res.lines();
    assert_eq!(
        it.next().unwrap(),
        "controller,seed,outcome,score,capture,band,distance,losses,effort,convergence_time_s,time_in_band_fraction,steady_state_rms_isoline_distance_m,track_losses,control_effort,steady_state_rms_error"
    );
    let runs: Vec<Vec<&str>> = it.map(|l| l.split(',').collect()).collect();
    assert_eq!(runs.len(), 4);
    for r in &runs {
        let v = |i: usize| r[i].parse::<f64>().unwrap();
        let weighted = 100.0 * (0.2 * v(4) + 0.3 * v(5) + 0.3 * v(6) + 0.1 * v(7) + 0.1 * v(8));
        assert!((v(3) - weighted).abs() < 1e-9, "{r:?}");
    }
    // The page names every controller and task; the suite as run loads again.
    let html = read(&out.join("index.html"));
    for n in ["pi_isoline", "sliding_mode_smooth", "circular", "volcano"] {
        assert!(html.contains(n), "{n}");
    }
    assert!(
        !html.contains("http://") || !html.contains("<script src"),
        "no external script"
    );
    let as_run = out.join("suite.toml");
    assert!(read(&as_run).contains("[task.tuned.pi_isoline]"));
    // Again without --resume: refused; with --resume: the same results, reused.
    let again = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert_fails(&again, 73, &["already holds a benchmark", "--resume"]);
    let resumed = isotrack(&[
        "benchmark",
        &suite,
        "--out",
        out.to_str().unwrap(),
        "--resume",
        "--threads",
        "1",
    ]);
    assert_eq!(resumed.status.code(), Some(0), "{}", stderr(&resumed));
    assert_eq!(read(&out.join("leaderboard.csv")), csv);
    let json: serde_json::Value =
        serde_json::from_str(&read(&out.join("tasks/circular/task.json"))).unwrap();
    assert_eq!(json["runs"].as_array().unwrap().len(), 4);
    // The suite as run (absolute scenario paths, the gains recorded) gives the same scores.
    let out2 = d.path().join("out2");
    let o = isotrack(&[
        "benchmark",
        as_run.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(read(&out2.join("leaderboard.csv")), csv);
}

#[test]
fn benchmark_exit_codes() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let out = out.to_str().unwrap();
    assert_fails(
        &isotrack(&["benchmark", "/nonexistent/suite.toml", "--out", out]),
        66,
        &["no such suite file"],
    );
    let bad = write(d.path(), "bad.toml", "name = \"x\"\nversion = 1\n");
    assert_fails(
        &isotrack(&["benchmark", &bad, "--out", out]),
        65,
        &["bad.toml", "missing field"],
    );
    let suite = mini_suite(d.path());
    assert_fails(
        &isotrack(&["benchmark", &suite, "--out", out, "--controllers", "nope"]),
        64,
        &["unknown controller `nope`"],
    );
    let missing_scenario = write(
        d.path(),
        "m.toml",
        "name = \"x\"\nversion = 1\ncontrollers = [\"pi_isoline\"]\ntuning_seeds = []\nscoring_seeds = [1]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"nope.toml\"\nlength_m = 1.0\n",
    );
    let o = isotrack(&["benchmark", &missing_scenario, "--out", out]);
    assert!(
        matches!(o.status.code(), Some(65) | Some(66)),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("task a"), "{}", stderr(&o));
}

/// A one-task suite `NAME.toml` in `dir` (the circular scenario, 20 s) with `top` lines after
/// `name` (line 1) and `task` lines after the task's `length_m` (line 11; `top` is 4 lines).
fn one_task(dir: &Path, name: &str, top: &str, task: &str) -> String {
    let scen = repo().join("scenarios/paper-fig2b-circular.toml");
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "name = \"x\"\n{top}\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"{}\"\nset = [\"sim.duration_s=20.0\"]\nlength_m = 6.93\n{task}",
            scen.display()
        ),
    )
}

const TOP: &str =
    "version = 1\ncontrollers = [\"pi_isoline\", \"pid\"]\ntuning_seeds = [7]\nscoring_seeds = [1, 2]";

/// Issue 30 item 17: each of these suites used to exit 0 with every run `invalid_scenario` and
/// score 0, or run a law twice, or count a seed twice; now each exits 65 naming the suite file,
/// line and column, and nothing is written.
#[test]
fn benchmark_refuses_invalid_suites_at_their_line() {
    let d = tempfile::tempdir().unwrap();
    let second = "[[task]]\nid = \"A\"\ntitle = \"b\"\nscenario = \"s.toml\"\nlength_m = 1.0\n";
    let cases: [(&str, String, &str, &str); 8] = [
        ("kp", TOP.into(), "[task.tuned.pi_isoline]\nkp = -5.0\n", "kp.toml:13:1: task a, tuned pi_isoline.kp = -5.0: `controller.kp`: must be > 0"),
        ("misspelt", TOP.into(), "[task.tuned.pid]\nkpp = 2.0\n", "misspelt.toml:13:1: task a, tuned pid.kpp = 2.0: `controller.kpp`: unknown field `kpp`"),
        ("unknown_law", TOP.into(), "[task.tuned.my_law]\nkp = 2.0\n", "unknown_law.toml:12:13: task a: tuned gains for `my_law`, which is not a built-in law"),
        ("vary_seed", TOP.into(), "vary = { \"sim.seed\" = { uniform = [0.0, 9.0] } }\n", "vary_seed.toml:12:10: task a: vary sim.seed"),
        ("no_controllers", TOP.replace("[\"pi_isoline\", \"pid\"]", "[]"), "", "no_controllers.toml:3:1: controllers is empty"),
        ("twice", TOP.replace("\"pid\"]", "\"pi_isoline\"]"), "", "twice.toml:3:30: controllers: `pi_isoline` appears twice"),
        ("seeds", TOP.replace("[1, 2]", "[1, 2, 2]"), "", "seeds.toml:5:24: scoring_seeds: seed 2 appears twice"),
        ("ids", TOP.into(), second, "ids.toml:13:1: task id \"A\" differs from task id \"a\" only in case"),
    ];
    for (name, top, task, says) in cases {
        let suite = one_task(d.path(), name, &top, task);
        let out = d.path().join(format!("out-{name}"));
        let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
        assert_fails(&o, 65, &[says]);
        assert!(!out.join("leaderboard.csv").exists(), "{name}");
    }
}

/// A controller named twice on the command line is a usage error (64), not a doubled row.
#[test]
fn benchmark_refuses_a_controller_named_twice() {
    let d = tempfile::tempdir().unwrap();
    let suite = one_task(d.path(), "ok", TOP, "");
    let out = d.path().join("o");
    let o = isotrack(&[
        "benchmark",
        &suite,
        "--out",
        out.to_str().unwrap(),
        "--controllers",
        "pid,pid",
    ]);
    assert_fails(&o, 64, &["controller `pid` is named twice"]);
}

#[test]
fn report_of_runs_and_its_errors() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=60",
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let page = d.path().join("r/report.html");
    let o = isotrack(&[
        "report",
        run.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let html = read(&page);
    assert!(
        html.contains("id=\"play\"") && html.contains("id=\"time\"") && html.contains("\"runs\"")
    );
    // The trace is in the page: 601 rows at 10 Hz over 60 s.
    let t0 = html.find("\"t\":[").unwrap();
    let t = &html[t0 + 5..t0 + 5 + html[t0 + 5..].find(']').unwrap()];
    assert_eq!(t.split(',').count(), 601);
    assert_fails(
        &isotrack(&["report", "/nonexistent", "--out", page.to_str().unwrap()]),
        66,
        &["summary.json"],
    );
}

#[test]
fn html_pages_in_a_real_browser() {
    let Some(browser) = chromium() else { return };
    let d = tempfile::tempdir().unwrap();
    let suite = mini_suite(d.path());
    let out = d.path().join("bench");
    let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let index = out.join("index.html");
    let (dom, log) = load(&browser, &index, &d.path().join("p1"), &["--dump-dom"]);
    assert!(
        dom.contains("data-ready=\"1\""),
        "the page's script did not finish: {log}"
    );
    assert_no_script_error(&log);
    assert!(dom.contains("ready: 2 controllers, 2 tasks"));
    for c in ["pi_isoline", "sliding_mode_smooth"] {
        // One leaderboard row and one row per task table.
        assert_eq!(
            dom.matches(&format!("<tr data-controller=\"{c}\"")).count(),
            3,
            "{c}"
        );
    }
    for t in ["circular", "volcano"] {
        assert!(dom.contains(&format!("data-task=\"{t}\"")), "{t}");
        assert!(dom.contains(&format!("data-col=\"{t}\"")), "{t}");
    }
    let shot = d.path().join("index.png");
    load(
        &browser,
        &index,
        &d.path().join("p2"),
        &[
            "--window-size=1200,1600",
            &format!("--screenshot={}", shot.display()),
        ],
    );
    assert_not_blank(&shot);

    let run = d.path().join("run");
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=60",
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report = d.path().join("report.html");
    let o = isotrack(&[
        "report",
        run.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (dom, log) = load(&browser, &report, &d.path().join("p3"), &["--dump-dom"]);
    assert!(
        dom.contains("data-ready=\"1\""),
        "the report's script did not finish: {log}"
    );
    assert_no_script_error(&log);
    assert!(dom.contains("ready: 1 run(s)"));
    for s in ["error", "s_measured", "omega"] {
        assert!(dom.contains(&format!("data-series=\"{s}\"")), "{s}");
    }
    let shot = d.path().join("report.png");
    load(
        &browser,
        &report,
        &d.path().join("p4"),
        &[
            "--window-size=1280,900",
            &format!("--screenshot={}", shot.display()),
        ],
    );
    assert_not_blank(&shot);
}

/// `benchmark --resume` reuses a task's `task.json` only once checked (att30b item 11): its
/// runs are exactly the suite's controllers x seeds, each value one a run can have (as a
/// sweep's stored rows), and its scores, title and picture are recomputed, never read.
#[test]
fn resume_checks_task_json() {
    let d = tempfile::tempdir().unwrap();
    let scen = repo().join("scenarios");
    let suite = write(
        d.path(),
        "one.toml",
        &format!(
            r#"name = "one"
version = 1
controllers = ["pi_isoline", "sliding_mode"]
tuning_seeds = [9001]
scoring_seeds = [1, 2]

[[task]]
id = "c"
title = "circular"
scenario = "{s}/paper-fig2b-circular.toml"
length_m = 6.93
set = ["sim.duration_s=60.0", "controller.max_turn_rate_radps=1.0"]
vary = {{ "initial.x_m" = {{ uniform = [8.0, 14.0] }} }}
"#,
            s = scen.display()
        ),
    );
    let first = d.path().join("first");
    let o = isotrack(&["benchmark", &suite, "--out", first.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let board = read(&first.join("leaderboard.csv"));
    let results = read(&first.join("tasks/c/results.csv"));
    let stored: serde_json::Value =
        serde_json::from_str(&read(&first.join("tasks/c/task.json"))).unwrap();
    // Resume after `edit`: its exit code, stderr and the out dir.
    let resume = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let out = d.path().join(name);
        std::fs::create_dir_all(out.join("tasks/c")).unwrap();
        for f in [
            "leaderboard.csv",
            "leaderboard.md",
            "index.html",
            "suite.toml",
        ] {
            std::fs::copy(first.join(f), out.join(f)).unwrap();
        }
        std::fs::copy(
            first.join("tasks/c/results.csv"),
            out.join("tasks/c/results.csv"),
        )
        .unwrap();
        let mut t = stored.clone();
        edit(&mut t);
        std::fs::write(out.join("tasks/c/task.json"), t.to_string()).unwrap();
        let o = isotrack(&[
            "benchmark",
            &suite,
            "--out",
            out.to_str().unwrap(),
            "--resume",
        ]);
        (o, out)
    };
    // Untouched: reused as is.
    let (o, out) = resume("same", &|_| {});
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(read(&out.join("leaderboard.csv")), board);
    assert_eq!(read(&out.join("tasks/c/results.csv")), results);
    // Edited scores, title and picture: recomputed from the runs and the suite, so the
    // leaderboard is the first run's.
    let (o, out) = resume("scores", &|t| {
        t["scores"] = serde_json::json!([["sliding_mode", 99.0], ["pi_isoline", 1.0]]);
        t["title"] = serde_json::json!("c\u{202e}<script>");
        t["picture"]["n"] = serde_json::json!(100_000_000u64);
    });
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(read(&out.join("leaderboard.csv")), board);
    let again: serde_json::Value =
        serde_json::from_str(&read(&out.join("tasks/c/task.json"))).unwrap();
    assert_eq!(again["title"], "circular");
    assert_eq!(again["picture"]["n"], 64);
    assert_eq!(again["scores"], stored["scores"]);
    // Edited run scores: recomputed too.
    let (o, out) = resume("run-score", &|t| {
        t["runs"][0]["score"]["total"] = serde_json::json!(100.0);
    });
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(read(&out.join("leaderboard.csv")), board);
    // Impossible values and runs the suite does not define: refused (65), naming the file and
    // the field. The limit 1 rad/s held over 60 s bounds the effort by 1^2 x 60 = 60 rad^2/s.
    type Edit<'a> = (&'a str, &'a dyn Fn(&mut serde_json::Value), &'a str);
    let cases: [Edit; 7] = [
        (
            "neg",
            &|t| t["runs"][0]["control_effort"] = serde_json::json!(-1.0),
            "runs[0].control_effort",
        ),
        (
            "big",
            &|t| t["runs"][2]["control_effort"] = serde_json::json!(1e9),
            "runs[2].control_effort",
        ),
        (
            "seed",
            &|t| t["runs"][2]["seed"] = serde_json::json!(77),
            "runs[2].seed",
        ),
        (
            "ctl",
            &|t| t["runs"][3]["controller"] = serde_json::json!("pid"),
            "runs[3].controller",
        ),
        (
            "band",
            &|t| t["runs"][1]["time_in_band_fraction"] = serde_json::json!(1.5),
            "runs[1].time_in_band_fraction",
        ),
        (
            "conv",
            &|t| t["runs"][1]["convergence_time_s"] = serde_json::json!(61.0),
            "runs[1].convergence_time_s",
        ),
        (
            "fewer",
            &|t| {
                t["runs"].as_array_mut().unwrap().pop();
            },
            "runs: 3 runs where the suite scores 4",
        ),
    ];
    for (name, edit, needle) in cases {
        let (o, _) = resume(name, edit);
        assert_fails(&o, 65, &["task.json", needle]);
    }
    // Issue 30, att30d-13: metrics that contradict each other under the tolerance (0.1 in the
    // scenario): a run rewritten as always in the band (every step of the window within 0.1)
    // beside a steady-state RMS error of 0.5.
    let (o, _) = resume("contradicts", &|t| {
        t["runs"][0]["time_in_band_fraction"] = serde_json::json!(1.0);
        t["runs"][0]["steady_state_rms_error"] = serde_json::json!(0.5);
    });
    assert_fails(
        &o,
        65,
        &[
            "task.json",
            "contradicts it",
            "metrics.convergence_tolerance = 0.1",
        ],
    );
}

/// `20 scale exp(-0.1 r)` around the origin as a CSV grid (no header, row 0 south), 81 x 81
/// nodes, 0.5 m apart from (-20, -20) m with the scenario's `spacing_m` and `origin_m`.
fn radial_csv(scale: f64) -> String {
    let n = 81;
    let mut t = String::new();
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                let (x, y) = (0.5 * (i as f64 - 40.0), 0.5 * (j as f64 - 40.0));
                format!("{}", 20.0 * scale * (-0.1 * (x * x + y * y).sqrt()).exp())
            })
            .collect();
        t.push_str(&row.join(","));
        t.push('\n');
    }
    t
}

/// ver30b-3 / att30d-10, the benchmark's half: a task's `task.json` digest covered its
/// scenario file's bytes but not the grid file the scenario names, so `benchmark --resume`
/// after the grid file was rewritten reused the scores computed on the old field without a
/// word. The digest covers each data file's SHA-256: the task is run again, and its results
/// are a fresh benchmark's on the new file; with the file unchanged it is reused.
#[test]
fn resume_runs_a_task_again_when_its_data_file_changed() {
    let d = tempfile::tempdir().unwrap();
    let grid = write(d.path(), "f.csv", &radial_csv(1.0));
    write(
        d.path(),
        "s.toml",
        "[field]\nkind = \"grid\"\npath = \"f.csv\"\nspacing_m = [0.5, 0.5]\norigin_m = [-20.0, -20.0]\n[initial]\nx_m = 5.0\ny_m = 0.0\n[sim]\nduration_s = 20.0\n",
    );
    let suite = write(
        d.path(),
        "grid.toml",
        r#"name = "grid"
version = 1
controllers = ["pi_isoline", "sliding_mode"]
tuning_seeds = [9001]
scoring_seeds = [1, 2]

[[task]]
id = "g"
title = "CSV grid"
scenario = "s.toml"
length_m = 63.0
vary = { "initial.heading_rad" = { uniform = [-3.0, 3.0] } }
"#,
    );
    let bench = |out: &Path, resume: bool| {
        let mut args = vec!["benchmark", &suite, "--out", out.to_str().unwrap()];
        if resume {
            args.push("--resume");
        }
        let o = isotrack(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        read(&out.join("tasks/g/results.csv"))
    };
    let (first, fresh) = (d.path().join("first"), d.path().join("fresh"));
    let old = bench(&first, false);
    // Unchanged: reused (the same bytes).
    assert_eq!(bench(&first, true), old);
    std::fs::write(&grid, radial_csv(1.1)).unwrap();
    let new = bench(&fresh, false);
    assert_ne!(new, old, "the two fields must score differently");
    // Rewritten: run again, as a fresh benchmark on the new file.
    assert_eq!(bench(&first, true), new);
    assert_eq!(
        read(&first.join("leaderboard.csv")),
        read(&fresh.join("leaderboard.csv"))
    );
}
