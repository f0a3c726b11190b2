//! Issue 32: a team's run directory as `plot` and `report` read it (`RunData::load_team`) and its
//! figure's revisit panel (`team_figure`): the checks of the directory's files against each
//! other name the right file, key, vehicle and line (att32g-4, -5, -7, -9), and the figure's
//! steady window is the metrics' (att32g-1, -2).

use isotrack_plot::{team_figure, Format, RunData, Style};
use isotrack_runs::summary::{scenario_toml, Summary};
use std::path::Path;

/// Team-circular-4's field, vehicle and controller (the level-10 circle of radius
/// `10 ln 2 = 6.93 m`, domain +-20 m), four Dubins robots at 0.5 m/s from `starts`, under
/// `spacing`, for `duration_s`.
fn scenario(starts: [(f64, f64, f64); 4], spacing: &str, duration_s: f64) -> String {
    let starts: Vec<String> = starts
        .iter()
        .map(|(x, y, h)| format!("{{ x_m = {x:?}, y_m = {y:?}, heading_rad = {h:?} }}"))
        .collect();
    format!(
        r#"name = "team-dir"
[field]
kind = "radial_exp"
i0 = 20.0
decay_per_m = 0.1
center_m = [0.0, 0.0]
domain_m = [-20.0, 20.0, -20.0, 20.0]
[vehicle]
kind = "dubins"
speed_mps = 0.5
[controller]
kind = "pi_isoline"
level = 10.0
kp = 10.0
ki = 1.0
c1 = 0.2
c2 = 1.0
[sim]
dt_s = 0.01
duration_s = {duration_s:?}
seed = 0
[team]
count = 4
starts = [{}]
spacing = "{spacing}"
k_v = 0.1
v_min_mps = 0.25
v_max_mps = 0.75
ring = "listed"
ranging = {{ rate_hz = 10.0, noise_std_m = 0.0, dropout_probability = 0.0, delay_s = 0.0 }}
"#,
        starts.join(", ")
    )
}

const R: f64 = 6.931471805599453;

/// Two robots on the circle, two at the domain's edge heading out (they leave the field), 1 s.
fn two_leave(y2: f64) -> [(f64, f64, f64); 4] {
    [
        (R, 0.0, -std::f64::consts::FRAC_PI_2),
        (19.9, 2.0, 0.0),
        (19.9, y2, 0.0),
        (0.0, R, 0.0),
    ]
}

/// Runs `text` into `dir` as `isotrack run --out DIR` writes a team's run.
fn make_team_run(dir: &Path, text: &str) {
    let s = isotrack_scenario::parse_scenario(text, "<test>", &[]).unwrap();
    let out = isotrack_runs::rundir::RunDir::open(dir, &[], &[], None).unwrap();
    let mut trace = out.team_trace(s.is_flying()).unwrap();
    let team =
        isotrack_runs::trace::run_team_into(&s, trace.writer(), isotrack_sim::TeamThreads::new(1))
            .unwrap()
            .unwrap();
    let summary = Summary::of_team(&s, None, &team, &[]);
    out.finish(trace, &scenario_toml(&s), &summary).unwrap();
}

fn summary_of(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// A copy of run `from` at `to`, its summary edited by `edit`, its trace replaced by `trace`.
fn edited(
    from: &Path,
    to: &Path,
    edit: impl FnOnce(&mut serde_json::Value),
    trace: Option<&str>,
) -> std::path::PathBuf {
    std::fs::create_dir_all(to).unwrap();
    for f in ["scenario.toml", "trace.csv", "summary.json"] {
        std::fs::copy(from.join(f), to.join(f)).unwrap();
    }
    let mut s = summary_of(from);
    edit(&mut s);
    std::fs::write(
        to.join("summary.json"),
        serde_json::to_string_pretty(&s).unwrap(),
    )
    .unwrap();
    if let Some(t) = trace {
        std::fs::write(to.join("trace.csv"), t).unwrap();
    }
    to.to_path_buf()
}

fn refusal(dir: &Path) -> String {
    match RunData::load_team(dir) {
        Ok(_) => panic!("{}: accepted", dir.display()),
        Err(e @ isotrack_plot::PlotError::Data(_)) => e.to_string(),
        Err(e) => panic!("{}: not a data error (65): {e}", dir.display()),
    }
}

/// att32g-9: a trace.csv with `\r\n` line endings (saved by a Windows editor) is read as
/// written, and every trace.csv:LINE named is the file's line (the header is line 1), as with
/// `\n`: a vehicle cell that is no vehicle on file line 4, a time NaN on file line 7. Before the
/// fix both were named one line too early (3, 6).
#[test]
fn a_crlf_trace_names_the_files_lines() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &scenario(two_leave(3.0), "none", 1.0));
    let trace = std::fs::read_to_string(run.join("trace.csv")).unwrap();
    let lines: Vec<&str> = trace.lines().collect();
    let crlf = |ls: &[String]| ls.join("\r\n") + "\r\n";
    let as_is: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    let ok = edited(&run, &d.path().join("ok"), |_| {}, Some(&crlf(&as_is)));
    assert_eq!(RunData::load_team(&ok).unwrap().len(), 4);
    let mut ghost = as_is.clone();
    let cut = ghost[3].rfind(',').unwrap();
    ghost[3] = format!("{},9", &ghost[3][..cut]);
    let mut nan = as_is.clone();
    let cut = nan[6].find(',').unwrap();
    nan[6] = format!("NaN{}", &nan[6][cut..]);
    for (name, t, needle) in [
        (
            "ghost",
            ghost,
            "trace.csv:4: the vehicle column is not one of the team's 4 vehicles",
        ),
        ("nan", nan, "trace.csv:7: t_s = NaN is not a time"),
    ] {
        for (ending, text) in [("lf", t.join("\n") + "\n"), ("crlf", crlf(&t))] {
            let dir = edited(
                &run,
                &d.path().join(format!("{name}-{ending}")),
                |_| {},
                Some(&text),
            );
            let m = refusal(&dir);
            assert!(m.contains(needle), "{name} {ending}: {m}");
        }
    }
}

/// att32g-5: a vehicle with `t_end_s: null` in summary.json (a run writes every vehicle's end)
/// is refused naming the key, its rows intact or cut short (before the fix both were drawn, the
/// cut rows as the vehicle's end).
#[test]
fn a_vehicle_with_no_end_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &scenario(two_leave(3.0), "none", 1.0));
    let s = summary_of(&run);
    assert_eq!(s["vehicles"][2]["outcome"], "left_field");
    let trace = std::fs::read_to_string(run.join("trace.csv")).unwrap();
    // Vehicle 2's rows after 0.1 s cut.
    let cut: String = trace
        .lines()
        .filter(|l| {
            !(l.ends_with(",2") && l.split(',').next().unwrap().parse::<f64>().unwrap() > 0.1)
        })
        .map(|l| format!("{l}\n"))
        .collect();
    for (name, t) in [("intact", None), ("cut", Some(cut.as_str()))] {
        let dir = edited(
            &run,
            &d.path().join(name),
            |s| s["vehicles"][2]["t_end_s"] = serde_json::Value::Null,
            t,
        );
        let m = refusal(&dir);
        assert!(
            m.contains("summary.json: vehicles[2].t_end_s is null"),
            "{name}: {m}"
        );
    }
}

/// att32g-4: vehicles 1 and 2 leave the field together (1e-9 m apart, heading out at the
/// domain's edge; a 3 s run), at one step between two recorded times: their last rows are the only rows at
/// that time. A summary ending one of them later (or `completed`) is refused naming that
/// vehicle and the line of its last row; before the fix vehicle 1's was blamed on vehicle 0 at
/// a right line ("vehicle 0's row 4 ... a row of the team's trace is missing"), and vehicle 2's
/// message said its row was "alone" at that time.
#[test]
fn two_vehicles_ending_together_blame_the_one_whose_summary_differs() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &scenario(two_leave(2.000000001), "none", 3.0));
    let s = summary_of(&run);
    let t1 = s["vehicles"][1]["t_end_s"].as_f64().unwrap();
    assert_eq!(s["vehicles"][1]["outcome"], "left_field");
    assert_eq!(s["vehicles"][2]["t_end_s"].as_f64().unwrap(), t1);
    assert!(
        ((t1 * 10.0).round() - t1 * 10.0).abs() > 1e-6,
        "{t1} s is a recorded time"
    );
    let trace = std::fs::read_to_string(run.join("trace.csv")).unwrap();
    let last_line = |v: &str| {
        trace
            .lines()
            .enumerate()
            .filter(|(_, l)| l.ends_with(&format!(",{v}")))
            .map(|(n, _)| n + 1)
            .last()
            .unwrap()
    };
    let at_end = trace
        .lines()
        .filter(|l| l.split(',').next().unwrap().parse::<f64>().ok() == Some(t1))
        .count();
    assert_eq!(at_end, 2);
    for v in [1usize, 2] {
        let later = edited(
            &run,
            &d.path().join(format!("later{v}")),
            |s| s["vehicles"][v]["t_end_s"] = serde_json::json!(t1 + 1.0),
            None,
        );
        let completed = edited(
            &run,
            &d.path().join(format!("completed{v}")),
            |s| {
                s["vehicles"][v]["t_end_s"] = serde_json::json!(3.0);
                s["vehicles"][v]["outcome"] = serde_json::json!("completed");
            },
            None,
        );
        for dir in [later, completed] {
            let m = refusal(&dir);
            let want = format!(
                "trace.csv:{}: vehicle {v}'s last row is at t = {t1} s",
                last_line(&v.to_string())
            );
            assert!(m.contains(&want), "{}: {m}\nwanted {want}", dir.display());
            assert!(
                m.contains(&format!("summary.json's vehicles[{v}] ends it at")),
                "{m}"
            );
            assert!(!m.contains("alone"), "{m}");
        }
    }
}

/// Sets `sim.duration_s` in `dir`'s scenario.toml.
fn set_duration(dir: &Path, d: f64) {
    let p = dir.join("scenario.toml");
    let mut t: toml::Table = std::fs::read_to_string(&p).unwrap().parse().unwrap();
    t["sim"]["duration_s"] = toml::Value::Float(d);
    std::fs::write(&p, toml::to_string(&t).unwrap()).unwrap();
}

/// att32g-7: a run directory whose scenario.toml has another `sim.duration_s` than the run's
/// (its vehicles `completed` at 1 s) is refused naming the key, a longer one (the figure's
/// steady window was then after every row: "no vehicle live in the steady window") and a
/// shorter one (rows past it drawn) alike. Before the fix both were drawn.
#[test]
fn a_scenario_duration_that_is_not_the_runs_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &scenario(two_leave(3.0), "none", 1.0));
    assert_eq!(RunData::load_team(&run).unwrap().len(), 4);
    for (name, dur) in [("longer", 300.0), ("shorter", 0.5)] {
        let dir = edited(&run, &d.path().join(name), |_| {}, None);
        set_duration(&dir, dur);
        let m = refusal(&dir);
        assert!(
            m.contains(&format!("scenario.toml: sim.duration_s = {dur} s")),
            "{name}: {m}"
        );
        assert!(
            m.contains("summary.json's vehicles[0] ends it at t = 1 s (completed)"),
            "{m}"
        );
    }
}

/// The text of `dir`'s team figure (SVG).
fn figure_text(dir: &Path) -> String {
    let vehicles = RunData::load_team(dir).unwrap();
    let path = dir.join("team.svg");
    let st = Style::new(Format::Svg);
    team_figure(&vehicles, &path, &st, "").unwrap();
    std::fs::read_to_string(path).unwrap()
}

/// att32g-1: four robots at the domain's edge heading out (all-leave), vehicle 0 last, at
/// 0.32 s. The steady window is the last 20 % of the run, from step ceil(0.8 n) (the metrics').
/// A run of 0.4 s (40 steps): the window from step 32, where vehicle 0 is live (its last
/// step): summary.json has a revisit time and the figure draws it (before the fix its window
/// began at (1 - 0.2) 0.4 = 0.32000000000000006 s, after vehicle 0's end: "no vehicle live").
/// A run of 0.41 s: the window from step 33, after every end: no revisit time in summary.json
/// (before the fix 0.33 s, a sample with nobody live) nor in the figure.
#[test]
fn the_figures_window_is_the_metrics() {
    let d = tempfile::tempdir().unwrap();
    let starts = [
        (19.9, 0.0, 0.0),
        (19.9, 1.0, 0.0),
        (19.9, 2.0, 0.0),
        (19.9, 3.0, 0.0),
    ];
    let a = d.path().join("d0.4");
    make_team_run(&a, &scenario(starts, "range_balance", 0.4));
    let s = summary_of(&a);
    let ends: Vec<f64> = (0..4)
        .map(|i| s["vehicles"][i]["t_end_s"].as_f64().unwrap())
        .collect();
    assert_eq!(ends.iter().copied().fold(0.0, f64::max), 32.0 * 0.01);
    assert!(s["team"]["revisit_time_max_s"].is_number(), "{}", s["team"]);
    let text = figure_text(&a);
    assert!(text.contains("revisit time, steady window"));
    assert!(!text.contains("no revisit time"));

    let b = d.path().join("d0.41");
    make_team_run(&b, &scenario(starts, "range_balance", 0.41));
    let s = summary_of(&b);
    assert!(s["team"]["revisit_time_max_s"].is_null(), "{}", s["team"]);
    assert!(s["team"]["revisit_time_mean_s"].is_null(), "{}", s["team"]);
    let text = figure_text(&b);
    assert!(text.contains("no revisit time: no vehicle live in the steady window"));
}

/// att32g-2: on an open polyline isoline (the plane `F = 0.1 y` at 0.5, y = 5 m, cut by the
/// domain) the metrics sample every 0.1 s, from step 0: a 0.19 s run's window (from step
/// ceil(0.8 x 19) = 16) holds no sample (the next one, step 20, is after the run), so
/// summary.json has no revisit time although all four robots flew the whole run; the figure
/// says so, not "no vehicle live in the steady window".
#[test]
fn a_window_without_a_metrics_sample_says_so() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("open");
    let text = r#"name = "open-plane"
[field]
kind = "linear_ramp"
offset = 0.0
gradient_per_m = [0.0, 0.1]
domain_m = [-20.0, 40.0, -20.0, 20.0]
[vehicle]
kind = "dubins"
speed_mps = 0.5
[controller]
level = 0.5
kp = 10.0
ki = 0.0
c1 = 0.02
c2 = 0.1
[sim]
duration_s = 0.19
[team]
count = 4
starts = [
  { x_m = 12.0, y_m = 5.0, heading_rad = 3.141592653589793 },
  { x_m = 8.0, y_m = 5.0, heading_rad = 3.141592653589793 },
  { x_m = 4.0, y_m = 5.0, heading_rad = 3.141592653589793 },
  { x_m = 0.0, y_m = 5.0, heading_rad = 3.141592653589793 },
]
spacing = "none"
"#;
    make_team_run(&dir, text);
    let s = summary_of(&dir);
    for i in 0..4 {
        assert_eq!(s["vehicles"][i]["outcome"], "completed");
    }
    assert!(s["team"]["revisit_time_max_s"].is_null(), "{}", s["team"]);
    let fig = figure_text(&dir);
    assert!(
        fig.contains(
            "no revisit time: no metrics sample in the steady window (sampled every 0.1 s)"
        ),
        "{fig}"
    );
    assert!(!fig.contains("no vehicle live"));
}

/// Sets `section.key` in `dir`'s scenario.toml to `v` (the section made when absent).
fn set_key(dir: &Path, section: &str, key: &str, v: toml::Value) {
    let p = dir.join("scenario.toml");
    let mut t: toml::Table = std::fs::read_to_string(&p).unwrap().parse().unwrap();
    t.entry(section)
        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        .as_table_mut()
        .unwrap()
        .insert(key.into(), v);
    std::fs::write(&p, toml::to_string(&t).unwrap()).unwrap();
}

/// att36-5: a run directory whose scenario.toml was edited after the run (the level, the
/// field's i0 and centre, the speed, the steady fraction, the record rate), or whose
/// summary.json's own resolved scenario was, is refused (65) naming the key and both values,
/// for a team's run and a single vehicle's alike; the directory as written is read. Before the
/// fix every one of them was drawn against the edited scenario.
#[test]
fn a_scenario_edited_after_the_run_is_refused_naming_the_key() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &scenario(two_leave(3.0), "none", 1.0));
    assert_eq!(RunData::load_team(&run).unwrap().len(), 4);
    let cases: [(&str, &str, toml::Value, &str); 6] = [
        (
            "controller",
            "level",
            toml::Value::Float(12.0),
            "controller.level = 12.0",
        ),
        ("field", "i0", toml::Value::Float(25.0), "field.i0 = 25.0"),
        (
            "field",
            "center_m",
            toml::Value::Array(vec![toml::Value::Float(3.0), toml::Value::Float(0.0)]),
            "field.center_m[0] = 3.0",
        ),
        (
            "vehicle",
            "speed_mps",
            toml::Value::Float(0.7),
            "vehicle.speed_mps = 0.7",
        ),
        (
            "metrics",
            "steady_state_fraction",
            toml::Value::Float(0.25),
            "metrics.steady_state_fraction = 0.25",
        ),
        (
            "output",
            "record_rate_hz",
            toml::Value::Float(5.0),
            "output.record_rate_hz = 5.0",
        ),
    ];
    for (i, (section, key, v, named)) in cases.into_iter().enumerate() {
        let dir = edited(&run, &d.path().join(format!("e{i}")), |_| {}, None);
        set_key(&dir, section, key, v);
        let m = refusal(&dir);
        assert!(m.contains(&format!("scenario.toml: {named}")), "{m}");
        assert!(m.contains("summary.json's scenario"), "{m}");
    }
    // summary.json's own scenario edited, scenario.toml as written.
    let dir = edited(
        &run,
        &d.path().join("json"),
        |s| s["scenario"]["controller"]["level"] = serde_json::json!(12.0),
        None,
    );
    let m = refusal(&dir);
    assert!(
        m.contains("scenario.toml: controller.level = 10.0, but summary.json's scenario (the one the run flew) has controller.level = 12.0"),
        "{m}"
    );
    // att40-4: a seed past 2^53 edited by one (as f64 the two were one number).
    let dir = edited(
        &run,
        &d.path().join("seed"),
        |s| s["scenario"]["sim"]["seed"] = serde_json::json!(1_152_921_504_606_846_976_u64),
        None,
    );
    set_key(
        &dir,
        "sim",
        "seed",
        toml::Value::Integer(1_152_921_504_606_846_977),
    );
    let m = refusal(&dir);
    assert!(
        m.contains("scenario.toml: sim.seed = 1152921504606846977, but summary.json's scenario (the one the run flew) has sim.seed = 1152921504606846976"),
        "{m}"
    );
    // A single vehicle's run: the same rule.
    let single = d.path().join("single");
    {
        let s =
            isotrack_scenario::parse_scenario("[sim]\nduration_s = 2.0\n", "<test>", &[]).unwrap();
        let out = isotrack_runs::rundir::RunDir::open(&single, &[], &[], None).unwrap();
        let mut trace = out.trace(s.is_flying()).unwrap();
        let r = s.run(trace.writer());
        let summary = Summary::of_run(&s, None, &r, &[]);
        out.finish(trace, &scenario_toml(&s), &summary).unwrap();
    }
    assert!(RunData::load(&single).is_ok());
    set_key(&single, "controller", "level", toml::Value::Float(14.0));
    match RunData::load(&single) {
        Err(e @ isotrack_plot::PlotError::Data(_)) => {
            assert!(
                e.to_string()
                    .contains("scenario.toml: controller.level = 14.0"),
                "{e}"
            )
        }
        other => panic!("{other:?}"),
    }
}

/// att36-15: a team's summary.json whose vehicle has an outcome isotrack never writes
/// ("exploded"), or whose top-level outcome or end (documented as vehicle 0's) is not
/// vehicle 0's, is refused naming the key; the run as written is read. Before the fix all
/// three were drawn and reported as given.
#[test]
fn a_summary_whose_outcomes_are_not_a_runs_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &scenario(two_leave(3.0), "none", 1.0));
    let dir = edited(
        &run,
        &d.path().join("exploded"),
        |s| s["vehicles"][1]["outcome"] = serde_json::json!("exploded"),
        None,
    );
    let m = refusal(&dir);
    assert!(m.contains("vehicles[1].outcome = \"exploded\""), "{m}");
    let dir = edited(
        &run,
        &d.path().join("top"),
        |s| s["t_end_s"] = serde_json::json!(0.5),
        None,
    );
    let m = refusal(&dir);
    assert!(m.contains("is not vehicles[0]'s"), "{m}");
    let dir = edited(
        &run,
        &d.path().join("top_outcome"),
        |s| s["outcome"] = serde_json::json!("diverged"),
        None,
    );
    let m = refusal(&dir);
    assert!(m.contains("the top-level outcome diverged"), "{m}");
}

/// Runs `text` (one vehicle) into `dir` as `isotrack run --out DIR` writes it.
fn make_single_run(dir: &Path, text: &str) {
    let s = isotrack_scenario::parse_scenario(text, "<test>", &[]).unwrap();
    let out = isotrack_runs::rundir::RunDir::open(dir, &[], &[], None).unwrap();
    let mut trace = out.trace(s.is_flying()).unwrap();
    let r = s.run(trace.writer());
    let summary = Summary::of_run(&s, None, &r, &[]);
    out.finish(trace, &scenario_toml(&s), &summary).unwrap();
}

/// att40-3: a key added to scenario.toml that the resolved file leaves out when it is unset
/// (an analytic field's `drift_mps` and `domain_m`, `team.ranging.max_range_m`, the derived
/// `metrics.convergence_min_dwell_s` and `metrics.track_loss_band`) is a difference, refused
/// (65) naming the key and both values, the summary's "(unset: the default)"; so is a summary
/// whose scenario is `{}` (the check was off) or no scenario. A key added with the value it
/// resolves to anyway (a zero drift; the dwell 2 s, 10 % of the 20 s run, which is what an
/// unset dwell is derived as, docs) is the same run and read. Before the fix every edit was drawn: the
/// keys one side had were skipped.
#[test]
fn a_key_the_resolved_file_leaves_out_added_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let single = d.path().join("single");
    make_single_run(&single, "[sim]\nduration_s = 20.0\n");
    assert!(RunData::load(&single).is_ok());
    let refused = |dir: &Path| match RunData::load(dir) {
        Err(e @ isotrack_plot::PlotError::Data(_)) => e.to_string(),
        other => panic!("{}: {other:?}", dir.display()),
    };
    let two = |a: f64, b: f64| toml::Value::Array(vec![a.into(), b.into()]);
    let cases: [(&str, &str, toml::Value, &str); 4] = [
        (
            "field",
            "drift_mps",
            two(0.5, 0.0),
            "field.drift_mps = [0.5,0.0]",
        ),
        (
            "field",
            "domain_m",
            toml::Value::Array(vec![2.5.into(), 10.5.into(), (-7.0).into(), 0.5.into()]),
            "field.domain_m = [2.5,10.5,-7.0,0.5]",
        ),
        (
            "metrics",
            "convergence_min_dwell_s",
            toml::Value::Float(3.0),
            "metrics.convergence_min_dwell_s = 3.0",
        ),
        (
            "metrics",
            "track_loss_band",
            toml::Value::Float(7.0),
            "metrics.track_loss_band = 7.0",
        ),
    ];
    for (i, (section, key, v, named)) in cases.into_iter().enumerate() {
        let dir = edited(&single, &d.path().join(format!("s{i}")), |_| {}, None);
        set_key(&dir, section, key, v);
        let m = refused(&dir);
        assert!(
            m.contains(&format!(
                "scenario.toml: {named}, but summary.json's scenario (the one the run flew) has {}.{key} = (unset: the default)",
                section
            )),
            "{m}"
        );
    }
    // The same keys at the values they resolve to anyway: the same run, read.
    for (i, (section, key, v)) in [
        ("field", "drift_mps", two(0.0, 0.0)),
        (
            "metrics",
            "convergence_min_dwell_s",
            toml::Value::Float(2.0),
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let dir = edited(&single, &d.path().join(format!("same{i}")), |_| {}, None);
        set_key(&dir, section, key, v);
        assert!(RunData::load(&dir).is_ok(), "{section}.{key}");
    }
    // summary.json's scenario `{}`, or not a scenario: not this run's.
    for (name, scenario, needle) in [
        (
            "empty",
            serde_json::json!({}),
            "summary.json's scenario is empty",
        ),
        (
            "alien",
            serde_json::json!({"colour": "red"}),
            "summary.json's scenario is not a scenario",
        ),
    ] {
        let dir = edited(
            &single,
            &d.path().join(name),
            |s| s["scenario"] = scenario,
            None,
        );
        let m = refused(&dir);
        assert!(m.contains(needle), "{m}");
        assert!(m.contains("not this run's"), "{m}");
    }
    // A team's run: `team.ranging.max_range_m` added.
    let run = d.path().join("team");
    make_team_run(&run, &scenario(two_leave(3.0), "none", 1.0));
    let dir = edited(&run, &d.path().join("range"), |_| {}, None);
    let p = dir.join("scenario.toml");
    let mut t: toml::Table = std::fs::read_to_string(&p).unwrap().parse().unwrap();
    t["team"]["ranging"]
        .as_table_mut()
        .unwrap()
        .insert("max_range_m".into(), toml::Value::Float(5.0));
    std::fs::write(&p, toml::to_string(&t).unwrap()).unwrap();
    let m = refusal(&dir);
    assert!(
        m.contains("scenario.toml: team.ranging.max_range_m = 5.0, but summary.json's scenario (the one the run flew) has team.ranging.max_range_m = (unset: the default)"),
        "{m}"
    );
}

/// mem45 (att43-17): a team's vehicles hold the team's scenario and summary once, not each a
/// copy: every vehicle's [`RunData::scenario`] shares vehicle 0's keys and settings (the same
/// `team.starts`, 300 of them, in memory once), and only vehicle 0's summary keeps the
/// recorded `scenario` (summary.json's, which lists the 300 starts again). Copies in each
/// vehicle took memory growing as the square of the team (2.6 GB for 10 000 vehicles).
#[test]
fn a_teams_vehicles_share_one_scenario() {
    let n = 300;
    let starts: Vec<String> = (0..n)
        .map(|i| {
            let th = -std::f64::consts::TAU * i as f64 / n as f64;
            format!(
                "{{ x_m = {:?}, y_m = {:?}, heading_rad = {:?} }}",
                R * th.cos(),
                R * th.sin(),
                th - std::f64::consts::FRAC_PI_2
            )
        })
        .collect();
    let text = scenario(two_leave(3.0), "none", 0.2)
        .replace("count = 4\n", "")
        .lines()
        .map(|l| {
            if l.starts_with("starts = ") {
                format!("starts = [{}]", starts.join(", "))
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    make_team_run(&run, &text);
    let vehicles = RunData::load_team(&run).unwrap();
    assert_eq!(vehicles.len(), n);
    let first = &vehicles[0];
    assert_eq!(first.scenario.spec().team.as_ref().unwrap().starts.len(), n);
    assert_eq!(first.summary.scenario, summary_of(&run)["scenario"]);
    for (i, v) in vehicles.iter().enumerate().skip(1) {
        assert!(
            std::ptr::eq(v.scenario.spec(), first.scenario.spec()),
            "vehicle {i}: its own copy of the settings"
        );
        assert!(
            std::ptr::eq(v.scenario.file(), first.scenario.file()),
            "vehicle {i}: its own copy of the keys"
        );
        assert!(v.summary.scenario.is_null(), "vehicle {i}");
    }
}
