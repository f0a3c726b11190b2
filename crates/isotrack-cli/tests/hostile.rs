//! Hostile inputs (issue 16): each reproducer from the report, as a regression test. Every one
//! of these once panicked, hung, aborted or wrote a silently wrong file.

mod common;

use common::{assert_fails, isotrack, stderr, write};

/// Item 1: Values validation accepted and the builder rejected (exit 101 in build.rs): now refused
/// by validation, which calls the builder's own constructors.
#[test]
fn step_counts_beyond_the_limit_are_invalid_not_a_panic() {
    for (set, key) in [
        ("sensor.delay_s=1e16", "sensor.delay_s"),
        ("sensor.delay_s=9e13", "sensor.delay_s"),
        ("sensor.delay_s=1e6", "sensor.delay_s"),
        ("sensor.rate_hz=1e-14", "sensor.rate_hz"),
        ("output.record_rate_hz=1e-14", "output.record_rate_hz"),
        ("sim.duration_s=1e300", "sim.duration_s"),
    ] {
        let o = isotrack(&["run", "--set", set]);
        assert_fails(&o, 65, &[key]);
    }
}

/// Item 1: In a sweep grid an invalid value is one recorded run, not a dead sweep.
#[test]
fn an_invalid_grid_value_is_recorded_not_fatal() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "sc.toml", "sim.duration_s = 5.0\n");
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"sc.toml\"\n[grid]\nsensor.delay_s = [0.0, 1e16]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    // Every run recorded; the sweep exits 65 naming how many were invalid (issue 15 item 3).
    assert_fails(&o, 65, &["2 runs (2 new) of 2", "1 of them invalid"]);
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 2);
    assert!(rows[0].contains(",completed,"), "{}", rows[0]);
    assert!(rows[1].contains(",invalid_scenario,"), "{}", rows[1]);
    // 17. The true source is named: the sweep's grid, not `--set` or "(default value)".
    assert!(
        rows[1].contains("[grid] sensor.delay_s=1e16")
            || rows[1].contains("[grid] sensor.delay_s=10000000000000000"),
        "{}",
        rows[1]
    );
    assert!(!rows[1].contains("default value") && !rows[1].contains("--set"));
}

/// Item 2: A spacing that would make 1e10 nodes (69 GB) is an error naming the spacing that fits,
/// on the command line and in a scenario.
#[test]
fn interpolation_grids_are_capped() {
    let d = tempfile::tempdir().unwrap();
    let mut text = String::from("x_m,y_m,v\n");
    for i in 0..20 {
        let (x, y) = ((i * 37 % 100) as f64, (i * 61 % 100) as f64);
        text += &format!("{x},{y},{}\n", 1.0 + (i % 7) as f64);
    }
    let st = write(d.path(), "st.csv", &text);
    let g = d.path().join("g.csv");
    let o = isotrack(&[
        "interpolate",
        &st,
        "--value-column",
        "v",
        "--spacing-m",
        "1e-3",
        "--method",
        "idw",
        "--out",
        g.to_str().unwrap(),
    ]);
    assert_fails(&o, 64, &["--spacing-m", "at least 0.0"]);
    // Issue 30 item 19: the smallest spacing is said in six significant digits at most (not
    // `0.0024500000000000004`), rounded up, so the spacing it names is accepted.
    let e = stderr(&o);
    let least = e
        .split("at least ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap();
    let digits = least.trim_start_matches(['0', '.']).replace('.', "");
    assert!(digits.len() <= 6, "{least}: {e}");
    let o = isotrack(&[
        "interpolate",
        &st,
        "--value-column",
        "v",
        "--spacing-m",
        least,
        "--method",
        "idw",
        "--out",
        g.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{least}: {}", stderr(&o));
    let sc = write(
        d.path(),
        "sc.toml",
        "[field]\nkind = \"stations\"\npath = \"st.csv\"\nvalue_column = \"v\"\nmethod = \"idw\"\ngrid_spacing_m = 1e-3\n",
    );
    let o = isotrack(&["check", &sc]);
    assert_fails(&o, 65, &["field.grid_spacing_m", "at least"]);
    // 12. Without --spacing-m: 1/100 of the 96 m bounding box, not a 2 x 2 grid at 10 km.
    let o = isotrack(&[
        "interpolate",
        &st,
        "--value-column",
        "v",
        "--method",
        "idw",
        "--out",
        g.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.path().join("g.json")).unwrap()).unwrap();
    let shape = &side["shape_rows_cols"];
    assert!(
        shape[0].as_u64().unwrap() > 90 && shape[1].as_u64().unwrap() > 90,
        "{shape}"
    );
}

/// Item 3: `plot` on a trace at +-1e308 hung, on `inf` it panicked in plotters: a clear error
/// (a position), or the non-finite values left out (a drawn series).
#[test]
fn plot_refuses_absurd_values_and_skips_non_finite_ones() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=5",
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let trace = run.join("trace.csv");
    let text = std::fs::read_to_string(&trace).unwrap();
    let edit = |col: usize, v: &str| -> String {
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        let mut f: Vec<String> = lines[5].split(',').map(str::to_string).collect();
        f[col] = v.to_string();
        lines[5] = f.join(",");
        lines.join("\n") + "\n"
    };
    std::fs::write(&trace, edit(1, "1e308")).unwrap();
    let o = isotrack(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        d.path().join("p").to_str().unwrap(),
    ]);
    assert_fails(&o, 65, &["x_m = 1e308 is not a position within +-1e100 m"]);
    // A drawn series past +-1e100 is drawn at the bound, the panel's label saying so
    // (att46-13: a genuine run's turn rate reaches 5.6e299; `report` draws it too).
    std::fs::write(&trace, edit(4, "-1e308")).unwrap();
    let o = isotrack(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        d.path().join("p").to_str().unwrap(),
        "--format",
        "svg",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(d.path().join("p/timeseries.svg")).unwrap();
    assert!(svg.contains("clipped at"), "no clip note in the figure");
    // An infinite position is refused naming the row (the trace check `plot` and `report`
    // share, issue 30 att30c-18); a non-finite value in a drawn series is left out.
    std::fs::write(&trace, edit(1, "inf")).unwrap();
    let o = isotrack(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        d.path().join("p").to_str().unwrap(),
    ]);
    assert_fails(&o, 65, &["trace.csv:6: x_m = inf is not a position"]);
    std::fs::write(&trace, edit(4, "inf")).unwrap();
    let o = isotrack(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        d.path().join("p").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// att46-13: a genuine run whose turn rate passes +-1e100 (`controller.kp = 1e300`: the
/// first command is already -2e299 rad/s) was refused by `plot` and `run --plot` with 65 (a
/// data error) while `report` drew it: both draw it now, the turn-rate panel clipped at the
/// bound with a note in its label; a run within the bound has no note.
#[test]
fn plot_draws_a_genuine_run_past_the_axis_bound_clipped() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("g");
    let base = common::bundled("paper-fig2b-circular");
    let o = isotrack(&[
        "run",
        &base,
        "--set",
        "sim.duration_s=20",
        "--set",
        "controller.kp=1e300",
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let figs = d.path().join("figs");
    let o = isotrack(&[
        "plot",
        run.to_str().unwrap(),
        "--out",
        figs.to_str().unwrap(),
        "--format",
        "svg",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(figs.join("timeseries.svg")).unwrap();
    assert!(svg.contains("clipped at"), "no clip note in the figure");
    let o = isotrack(&[
        "report",
        run.to_str().unwrap(),
        "--out",
        d.path().join("g.html").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = isotrack(&[
        "run",
        &base,
        "--set",
        "sim.duration_s=20",
        "--set",
        "controller.kp=1e300",
        "--out",
        d.path().join("g2").to_str().unwrap(),
        "-q",
        "--plot",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The same scenario at its own gain: no clip, no note.
    let plain = d.path().join("plain");
    let o = isotrack(&[
        "run",
        &base,
        "--set",
        "sim.duration_s=20",
        "--out",
        plain.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = isotrack(&[
        "plot",
        plain.to_str().unwrap(),
        "--out",
        d.path().join("pf").to_str().unwrap(),
        "--format",
        "svg",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(d.path().join("pf/timeseries.svg")).unwrap();
    assert!(!svg.contains("clipped at"));
}

/// att43-15: `report` showed an edited summary.json's impossible numbers as the run's (a
/// negative `max |eps|`, a convergence time past a 5 s run's end, a team vehicle's negative
/// convergence time): `plot` and `report` refuse them (65) naming the key, as a sweep's row
/// check does; the unedited runs are drawn.
#[test]
fn plot_and_report_refuse_impossible_summary_numbers() {
    let d = tempfile::tempdir().unwrap();
    let single = d.path().join("single");
    let team = d.path().join("team");
    let run = |scenario: Option<String>, out: &std::path::Path| {
        let mut a = vec!["run".to_string()];
        a.extend(scenario);
        a.extend(
            [
                "--set",
                "sim.duration_s=5",
                "--out",
                out.to_str().unwrap(),
                "-q",
            ]
            .map(String::from),
        );
        let o = isotrack(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", stderr(&o));
    };
    run(None, &single);
    run(Some(common::bundled("team-circular-4")), &team);
    for dir in [&single, &team] {
        let o = isotrack(&[
            "report",
            dir.to_str().unwrap(),
            "--out",
            d.path().join("ok.html").to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    use serde_json::json;
    // att46-4: numbers each consistent with its neighbours' form but impossible by the metrics'
    // definitions (bounds from theory, in check.rs): a convergence at t = 0 (|eps| under the
    // tolerance, 1 % of the level 10 = 0.1, from then on) beside a steady-state maximum of 50;
    // a gap CV of 1000 for 4 vehicles (at most sqrt(3)); a speed range with min > max or
    // outside team-circular-4's envelope [0.25, 0.75] m/s (its team.v_min_mps and v_max_mps);
    // an even team (time_to_even_s = 0) with a final gap CV of 1.5 > 0.05; an isoline length
    // of 1 m on the 43.55 m circle (2 pi x 6.93 m).
    type Case<'a> = (
        &'a std::path::Path,
        Vec<(&'a str, serde_json::Value)>,
        &'a str,
    );
    let cases: Vec<Case> = vec![
        (
            &single,
            vec![("/steady_state_max_abs_error", json!(-5.0))],
            "steady_state_max_abs_error",
        ),
        (
            &single,
            vec![("/convergence_time_s", json!(1e9))],
            "convergence_time_s",
        ),
        (
            &single,
            vec![("/convergence_time_s", json!(-3.0))],
            "convergence_time_s",
        ),
        (
            &team,
            vec![("/vehicles/1/convergence_time_s", json!(-3.0))],
            "vehicles[1]: convergence_time_s",
        ),
        (
            &single,
            vec![
                ("/convergence_time_s", json!(0.0)),
                ("/steady_state_max_abs_error", json!(50.0)),
                ("/steady_state_rms_error", json!(40.0)),
            ],
            "steady_state_max_abs_error = 50 contradicts it (convergence_time_s = 0 s",
        ),
        (
            &team,
            vec![("/team/gap_cv", json!(1000.0))],
            "gap_cv = 1000 exceeds sqrt(N - 1) = 1.73205 for N = 4",
        ),
        (
            &team,
            vec![("/team/gap_cv_final", json!(1.7321))],
            "gap_cv_final = 1.7321 exceeds sqrt(N - 1)",
        ),
        (
            &team,
            vec![("/team/speed_range_mps", json!([0.75, 0.25]))],
            "speed_range_mps = [0.75, 0.25]: its slowest speed exceeds its fastest",
        ),
        (
            &team,
            vec![("/team/speed_range_mps", json!([0.25, 100.0]))],
            "leaves the team's speed envelope [0.25, 0.75] m/s",
        ),
        (
            &team,
            vec![("/team/speed_range_mps", json!([0.2, 0.75]))],
            "leaves the team's speed envelope [0.25, 0.75] m/s",
        ),
        (
            &team,
            vec![
                ("/team/time_to_even_s", json!(0.0)),
                ("/team/gap_cv_final", json!(1.5)),
            ],
            "time_to_even_s = 0 s where gap_cv_final = 1.5",
        ),
        (
            &team,
            vec![("/team/isoline_length_m", json!(1.0))],
            "isoline_length_m = 1 m is not the length of the run's isoline, 43.5517",
        ),
    ];
    for (k, (dir, edits, needle)) in cases.iter().enumerate() {
        assert_edit_refused(d.path(), &format!("edited{k}"), dir, edits, needle);
    }
}

/// A copy `name` (in `d`) of the run in `dir` with its `summary.json` edited at each JSON
/// pointer: `report` and `plot` refuse it (65) naming `needle`, and write nothing.
fn assert_edit_refused(
    d: &std::path::Path,
    name: &str,
    dir: &std::path::Path,
    edits: &[(&str, serde_json::Value)],
    needle: &str,
) {
    let copy = d.join(name);
    std::fs::create_dir(&copy).unwrap();
    for f in ["trace.csv", "scenario.toml", "summary.json"] {
        std::fs::copy(dir.join(f), copy.join(f)).unwrap();
    }
    let path = copy.join("summary.json");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    for (pointer, value) in edits {
        *j.pointer_mut(pointer).unwrap() = value.clone();
    }
    std::fs::write(&path, serde_json::to_string_pretty(&j).unwrap()).unwrap();
    for cmd in ["report", "plot"] {
        let out = d.join(format!(
            "{cmd}-{name}{}",
            if cmd == "report" { ".html" } else { "" }
        ));
        let o = isotrack(&[cmd, copy.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert_fails(&o, 65, &["summary.json: ", needle]);
        assert!(
            !out.exists(),
            "{cmd} wrote {} from an impossible summary",
            out.display()
        );
    }
}

/// att49-4/-5: rules checked one way only are checked both ways. A genuine run of the
/// paper's circle (600 s: its steady-state window [480, 600] s, 120 s, is longer than the 60 s
/// dwell) stays within the tolerance 0.1 over its window and converged before it; its summary
/// edited to a convergence after the window's start, or none, or an in-band share below 1
/// or past it, is refused. A genuine team run (team-circular-4, 300 s: window from 240 s) is
/// even from before its window; edited to a window-mean gap CV of 1.5 beside an even spread
/// from 1 s, to no even time beside a final CV of 0, to a negative isoline length or speed,
/// it is refused. Each names the key; the genuine runs are drawn.
#[test]
fn plot_and_report_refuse_one_way_rules_broken_the_other_way() {
    use serde_json::json;
    let d = tempfile::tempdir().unwrap();
    let (single, team) = (d.path().join("single"), d.path().join("team"));
    for (scenario, out) in [
        ("paper-fig2b-circular", &single),
        ("team-circular-4", &team),
    ] {
        let o = isotrack(&[
            "run",
            &common::bundled(scenario),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = isotrack(&[
            "report",
            out.to_str().unwrap(),
            "--out",
            d.path().join(format!("{scenario}.html")).to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let read = |dir: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
    };
    // The genuine numbers the edits contradict.
    let s = read(&single);
    assert!(
        s["steady_state_max_abs_error"].as_f64().unwrap() < 0.1,
        "{s}"
    );
    assert!(s["convergence_time_s"].as_f64().unwrap() <= 480.0, "{s}");
    assert_eq!(s["time_in_band_fraction"].as_f64(), Some(1.0), "{s}");
    let t = read(&team);
    assert!(
        t["team"]["time_to_even_s"].as_f64().unwrap() <= 240.0,
        "{t}"
    );
    assert!(t["team"]["gap_cv_final"].as_f64().unwrap() <= 0.05, "{t}");
    type Case<'a> = (
        &'a std::path::Path,
        Vec<(&'a str, serde_json::Value)>,
        &'a str,
    );
    let cases: Vec<Case> = vec![
        (
            &single,
            vec![("/convergence_time_s", json!(590.0))],
            "convergence_time_s = 590 s contradicts it (steady_state_max_abs_error",
        ),
        (
            &single,
            vec![("/convergence_time_s", json!(null))],
            "convergence_time_s = null contradicts it",
        ),
        (
            &single,
            vec![("/time_in_band_fraction", json!(0.5))],
            "time_in_band_fraction = 0.5",
        ),
        (
            &single,
            vec![("/time_in_band_fraction", json!(1.5))],
            "time_in_band_fraction = `1.5` is not a share",
        ),
        (
            &team,
            vec![("/team/time_to_even_s", json!(1.0)), ("/team/gap_cv", json!(1.5))],
            "gap_cv = 1.5 where time_to_even_s = 1 s is at or before the steady-state window's start (240 s)",
        ),
        (
            &team,
            vec![("/team/time_to_even_s", json!(null)), ("/team/gap_cv_final", json!(0.0))],
            "time_to_even_s = null where gap_cv_final = 0",
        ),
        (
            &team,
            vec![("/team/isoline_length_m", json!(-5.0))],
            "isoline_length_m = -5 m is negative",
        ),
        (
            &team,
            vec![("/team/speed_range_mps", json!([-50.0, 1e9]))],
            "speed_range_mps holds -50 m/s",
        ),
    ];
    for (k, (dir, edits, needle)) in cases.iter().enumerate() {
        assert_edit_refused(d.path(), &format!("way{k}"), dir, edits, needle);
    }
}

/// Item 4, 10, 15: `replay`: a span of 1e12 s is refused up front; the output may not be the input
/// (even spelled differently); a NaN altitude is refused at the door.
#[test]
fn replay_bounds_its_work_and_protects_its_input() {
    let d = tempfile::tempdir().unwrap();
    let head = "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n";
    let long = write(
        d.path(),
        "long.csv",
        &format!("{head}0,0,0,0,0.4\n1e12,0,0,0,0.4\n"),
    );
    let out = d.path().join("o.csv");
    let o = isotrack(&["replay", "--inputs", &long, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 65, &["1e12 s", "steps"]);
    let ok_text = format!("{head}0,-0.07,0,0,0.4\n1,-0.07,0,0,0.4\n");
    let ok = write(d.path(), "ok.csv", &ok_text);
    let alias = d.path().join(".").join("ok.csv");
    for target in [ok.clone(), alias.display().to_string()] {
        let o = isotrack(&["replay", "--inputs", &ok, "--out", &target]);
        assert_fails(&o, 64, &["is the input file"]);
        assert_eq!(std::fs::read_to_string(&ok).unwrap(), ok_text);
    }
    let o = isotrack(&[
        "replay",
        "--inputs",
        &ok,
        "--out",
        out.to_str().unwrap(),
        "--altitude-m",
        "nan",
    ]);
    assert_fails(&o, 64, &["--altitude-m"]);
    assert!(!out.exists());
}

/// Item 5: `--threads 100000` is capped (with a note), and the rows are those of one thread.
#[test]
fn threads_are_capped() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "sc.toml", "sim.duration_s = 2.0\n");
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"sc.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0, 20.0]\n",
    );
    let (a, b) = (d.path().join("a"), d.path().join("b"));
    let o = isotrack(&[
        "sweep",
        &sw,
        "--out",
        a.to_str().unwrap(),
        "--threads",
        "100000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("capped to"), "{}", stderr(&o));
    let o = isotrack(&["sweep", &sw, "--out", b.to_str().unwrap(), "--threads", "1"]);
    assert!(o.status.success());
    assert_eq!(
        std::fs::read(a.join("results.csv")).unwrap(),
        std::fs::read(b.join("results.csv")).unwrap()
    );
}

/// Item 6: Devices and directories are refused before reading: as a scenario, a grid, stations.
#[cfg(unix)]
#[test]
fn non_regular_files_are_refused() {
    let o = isotrack(&["run", "/dev/zero"]);
    assert_fails(&o, 66, &["not a regular file"]);
    let d = tempfile::tempdir().unwrap();
    let sc = write(
        d.path(),
        "sc.toml",
        "[field]\nkind = \"grid\"\npath = \"/dev/zero\"\nformat = \"csv\"\n",
    );
    let o = isotrack(&["run", &sc]);
    // 66 like a file on the command line (65 before the hostile review of issue 30).
    assert_fails(&o, 66, &["field.path", "not a regular file"]);
    let o = isotrack(&[
        "interpolate",
        "/dev/zero",
        "--value-column",
        "v",
        "--out",
        d.path().join("g.csv").to_str().unwrap(),
    ]);
    assert_fails(&o, 66, &["not a regular file"]);
    let big = d.path().join("big.toml");
    std::fs::write(&big, vec![b'#'; 2 << 20]).unwrap();
    let o = isotrack(&["run", big.to_str().unwrap()]);
    assert_fails(&o, 66, &["more than the 1048576"]);
}

/// Item 7: Run counts that overflow u64 wrapped to 2 (or 0) runs and exited 0.
#[test]
fn sweep_run_count_overflow_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "sc.toml", "[sim]\n");
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"sc.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0, 20.0]\n[random]\nruns = 6148914691236517206\ninitial.x_m = { uniform = [0.0, 1.0] }\n",
    );
    let o = isotrack(&["sweep", &sw, "--out", d.path().join("o").to_str().unwrap()]);
    assert_fails(&o, 65, &["more than 1000000000 runs"]);
    let keys: String = (0..64).map(|i| format!("sim.k{i} = [1, 2]\n")).collect();
    let sw = write(
        d.path(),
        "s2.toml",
        &format!("scenario = \"sc.toml\"\n[grid]\n{keys}"),
    );
    let o = isotrack(&["sweep", &sw, "--out", d.path().join("o2").to_str().unwrap()]);
    assert_fails(&o, 65, &["more than"]);
}

/// Item 8, 9: Resume and merge validate rows (field count, id range) and compare the sweep's
/// digest; merge will not overwrite a sweep's results without `--force`.
#[test]
fn resume_and_merge_trust_nothing() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "sc.toml", "sim.duration_s = 2.0\n");
    let grid =
        "scenario = \"sc.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0]\ncontroller.ki = [0.0, 1.0]\n";
    let sw = write(d.path(), "s.toml", grid);
    let p = |n: &str| d.path().join(n).display().to_string();
    assert!(isotrack(&["sweep", &sw, "--out", &p("full")])
        .status
        .success());
    let results = d.path().join("full/results.csv");
    let good = std::fs::read_to_string(&results).unwrap();
    // Damaged copies of row 2: (column, new value).
    let header: Vec<&str> = good.lines().next().unwrap().split(',').collect();
    let row2: Vec<&str> = good.lines().nth(3).unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let with = |c: usize, v: &str| {
        let mut r = row2.clone();
        r[c] = v;
        r.join(",") + "\n"
    };
    let n = header.len();
    for (bad_row, needle) in [
        (
            "3,1,2\n".to_string(),
            format!("3 fields where the header has {n}"),
        ),
        (
            with(0, "11"),
            "run_id 11 is beyond this sweep's 4 runs".into(),
        ),
        (
            with(col("t_end_s"), "abc"),
            "t_end_s = `abc` is not a number".into(),
        ),
        (
            with(col("outcome"), "exploded"),
            "outcome `exploded`".into(),
        ),
    ] {
        let (bad_row, needle) = (bad_row.as_str(), needle.as_str());
        let mut lines: Vec<&str> = good.lines().collect();
        lines.truncate(3);
        let text = lines.join("\n") + "\n" + bad_row;
        std::fs::write(&results, &text).unwrap();
        let o = isotrack(&["sweep", &sw, "--out", &p("full"), "--resume"]);
        assert_fails(&o, 65, &["results.csv:4: damaged row", needle]);
        assert_eq!(
            std::fs::read_to_string(&results).unwrap(),
            text,
            "left as it was"
        );
    }
    std::fs::write(&results, &good).unwrap();
    // A changed sweep file: resume refuses (digest), merge refuses to mix shards.
    let changed = write(d.path(), "s2.toml", &grid.replace("10.0", "12.0"));
    let o = isotrack(&["sweep", &changed, "--out", &p("full"), "--resume"]);
    assert_fails(&o, 65, &["made by a different sweep"]);
    assert!(
        isotrack(&["sweep", &sw, "--out", &p("a"), "--shard", "1/2"])
            .status
            .success()
    );
    assert!(
        isotrack(&["sweep", &changed, "--out", &p("b"), "--shard", "2/2"])
            .status
            .success()
    );
    let o = isotrack(&["merge", &p("a"), &p("b"), "--out", &p("m")]);
    assert_fails(&o, 65, &["a different sweep"]);
    assert!(
        isotrack(&["sweep", &sw, "--out", &p("c"), "--shard", "2/2"])
            .status
            .success()
    );
    // A damaged shard row is refused by merge too.
    let c_results = d.path().join("c/results.csv");
    let c_text = std::fs::read_to_string(&c_results).unwrap();
    std::fs::write(&c_results, format!("{c_text}9,1,2\n")).unwrap();
    let o = isotrack(&["merge", &p("a"), &p("c"), "--out", &p("m")]);
    assert_fails(&o, 65, &["damaged row"]);
    std::fs::write(&c_results, &c_text).unwrap();
    // --out an existing sweep: refused without --force, and never one of the inputs.
    let o = isotrack(&["merge", &p("a"), &p("c"), "--out", &p("full")]);
    assert_fails(&o, 73, &["--force"]);
    assert_eq!(std::fs::read_to_string(&results).unwrap(), good);
    let o = isotrack(&["merge", &p("a"), &p("c"), "--out", &p("a"), "--force"]);
    assert_fails(&o, 64, &["one of the inputs"]);
    let o = isotrack(&["merge", &p("a"), &p("c"), "--out", &p("full"), "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&results).unwrap(),
        good,
        "same bits as one process"
    );
}

/// Item 11: Trims outside the actuators' limits or the model's range exited 0; `trim`, `replay` and
/// `run` accept the same airspeeds (15..45 m/s).
#[test]
fn trim_replay_and_run_share_the_airspeed_range() {
    let d = tempfile::tempdir().unwrap();
    let inputs = write(
        d.path(),
        "in.csv",
        "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,-0.07,0,0,0.4\n1,-0.07,0,0,0.4\n",
    );
    let out = d.path().join("o.csv");
    for v in ["5", "14.9", "45.1", "80", "1000"] {
        assert_fails(
            &isotrack(&["trim", "--airspeed-mps", v]),
            64,
            &["15..45 m/s"],
        );
        let o = isotrack(&[
            "replay",
            "--inputs",
            &inputs,
            "--out",
            out.to_str().unwrap(),
            "--airspeed-mps",
            v,
        ]);
        assert_fails(&o, 64, &["15..45 m/s"]);
        let set = format!("vehicle.airspeed_mps={v}");
        let o = isotrack(&[
            "check",
            "--set",
            "vehicle.kind=fixed_wing",
            "--set",
            &set,
            "--set",
            "sim.dt_s=0.01",
        ]);
        assert_fails(&o, 65, &["15..45 m/s"]);
    }
    for v in ["15", "45"] {
        assert!(isotrack(&["trim", "--airspeed-mps", v]).status.success());
    }
}

/// Item 13, 14: Physical ranges: 1e308 m/s is refused; a start off the field writes the initial
/// state, and `plot` says why the run ended.
#[test]
fn physical_ranges_and_runs_that_end_at_t_zero() {
    let o = isotrack(&["run", "--set", "vehicle.speed_mps=1e308"]);
    assert_fails(
        &o,
        65,
        &["vehicle.speed_mps", "must be <= 1000 m/s, got 1e308"],
    );
    let o = isotrack(&["run", "--set", "initial.x_m=1e308"]);
    assert_fails(&o, 65, &["initial.x_m"]);
    // The same classes elsewhere: field values beyond the grids' limit (they made "no value"
    // at the start), a trace of 1e9 rows (100 GB) from a long duration.
    let o = isotrack(&[
        "run",
        "--set",
        "field.kind=linear_ramp",
        "--set",
        "field.gradient_per_m=[1e308, 1.0]",
    ]);
    assert_fails(&o, 65, &["field.gradient_per_m", "1e308"]);
    let o = isotrack(&["run", "--set", "controller.level=1e308"]);
    assert_fails(&o, 65, &["controller.level"]);
    let o = isotrack(&["run", "--set", "sim.duration_s=1e8"]);
    assert_fails(&o, 65, &["output.record_rate_hz", "trace rows"]);
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("r");
    // A 5 x 5 grid of no-data but one corner: the start (2, 2) is on the grid, with no value.
    let mut g = vec![vec!["NaN"; 5]; 5];
    g[0][0] = "1";
    let text: String = g.iter().map(|r| r.join(",") + "\n").collect();
    write(d.path(), "g.csv", &text);
    let sc = write(
        d.path(),
        "sc.toml",
        "[field]\nkind = \"grid\"\npath = \"g.csv\"\n[initial]\nx_m = 2.0\ny_m = 2.0\n",
    );
    let o = isotrack(&["run", &sc, "--out", run.to_str().unwrap(), "--plot"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let trace = std::fs::read_to_string(run.join("trace.csv")).unwrap();
    let rows: Vec<&str> = trace.lines().skip(1).collect();
    assert_eq!(rows, ["0.0,2.0,2.0,-1.5707963267948966,NaN,NaN,0.0,"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("left_field at t = 0.00 s"), "{stdout}");
}

/// Item 16: A 10 MB key made a 20 MB error; messages echo at most a few hundred characters.
#[test]
fn huge_keys_are_clipped_in_messages() {
    let d = tempfile::tempdir().unwrap();
    let key = "k".repeat(1_000_000);
    let sc = write(d.path(), "sc.toml", &format!("[sim]\n{key} = 1\n"));
    let o = isotrack(&["run", &sc]);
    assert_fails(&o, 65, &["more characters"]);
    assert!(stderr(&o).len() < 3000, "{} bytes", stderr(&o).len());
    // (One argument is limited to 128 kB by the OS.)
    let o = isotrack(&["run", "--set", &format!("sim.{}=1", &key[..100_000])]);
    assert_fails(&o, 65, &["more characters"]);
    assert!(stderr(&o).len() < 3000, "{} bytes", stderr(&o).len());
}

/// Item 17: Unknown keys in a sweep are the sweep file's error, found before any run; `--gain`
/// problems are labelled `--gain`, not `--set` or "(default value)".
#[test]
fn sweep_keys_are_checked_up_front_and_labelled() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "sc.toml", "[sim]\n");
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"sc.toml\"\n[grid]\ncontroller.kpp = [1.0]\n",
    );
    let out = d.path().join("o");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_fails(
        &o,
        65,
        &["[grid] controller.kpp=1.0", "unknown field `kpp`"],
    );
    assert!(!stderr(&o).contains("--set"));
    assert!(!out.join("results.csv").exists(), "nothing ran");
    let sw = write(
        d.path(),
        "s2.toml",
        "scenario = \"sc.toml\"\n[random]\nruns = 2\ncontroller.kind = { uniform = [0.0, 1.0] }\n",
    );
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 65, &["[random] controller.kind"]);
    let sc = write(d.path(), "c.toml", "sim.duration_s = 2.0\n");
    let o = isotrack(&[
        "compare",
        &sc,
        "--controllers",
        "sliding_mode",
        "--gain",
        "sliding_mode.gamma=-1",
    ]);
    assert_fails(
        &o,
        65,
        &["--gain sliding_mode.gamma=-1", "controller.gamma"],
    );
    assert!(!stderr(&o).contains("default value"), "{}", stderr(&o));
}

/// Item 18: Exit codes: a sweep whose scenario file is missing exits 66 (it was 65); wrong causes
/// are now the right ones.
#[test]
fn exit_codes_and_causes() {
    let d = tempfile::tempdir().unwrap();
    let sw = write(d.path(), "s.toml", "scenario = \"missing.toml\"\n");
    let o = isotrack(&["sweep", &sw, "--out", d.path().join("o").to_str().unwrap()]);
    assert_fails(&o, 66, &["missing.toml"]);
    let o = isotrack(&[
        "sweep",
        d.path().join("none.toml").to_str().unwrap(),
        "--out",
        d.path().join("o").to_str().unwrap(),
    ]);
    assert_fails(&o, 66, &["none.toml"]);
    let st = write(d.path(), "st.csv", "x_m,y_m,v\n0,0,1e300\n5,5,2\n9,1,4\n");
    let o = isotrack(&[
        "interpolate",
        &st,
        "--value-column",
        "v",
        "--out",
        d.path().join("g.csv").to_str().unwrap(),
    ]);
    assert_fails(&o, 65, &["st.csv:2: field 3", "1e300"]);
    assert!(!stderr(&o).contains("singular"));
    let g = write(d.path(), "g.csv", "0,1e308\n2,3\n");
    let _ = g;
    let sc = write(
        d.path(),
        "sc.toml",
        "[field]\nkind = \"grid\"\npath = \"g.csv\"\n",
    );
    let o = isotrack(&["run", &sc]);
    assert_fails(&o, 65, &["1e308", "column 1, row 0"]);
}

/// Issue 15 item 10: a start off a grid without a georeference names the extent and the keys
/// that set it (it ran and ended at t = 0 with no hint).
#[test]
fn a_start_outside_the_field_names_its_extent() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "g.csv", "0,1,2\n1,2,3\n2,3,4\n");
    let sc = write(
        d.path(),
        "sc.toml",
        "[field]\nkind = \"grid\"\npath = \"g.csv\"\n",
    );
    let o = isotrack(&["run", &sc]);
    assert_fails(
        &o,
        65,
        &[
            "initial.x_m",
            "the start (10, 0) m is outside",
            "x in [0, 2] m",
            "field.spacing_m",
        ],
    );
    let o = isotrack(&["run", "--set", "field.domain_m=[50.0, 60.0, 50.0, 60.0]"]);
    assert_fails(&o, 65, &["initial.x_m", "field.domain_m"]);
}

/// Regression (issue 30, item 4): a FIFO given as any input waited for a writer for ever.
/// Every input path refuses it without opening it: 66 for a file named on the command line
/// and for one a scenario names (naming the key: the hostile review of issue 30 found 65
/// there). Each call is killed after 20 s, so a
/// regression fails here rather than hanging the suite.
#[cfg(unix)]
#[test]
fn a_fifo_is_refused_by_every_input_path_without_waiting() {
    use common::{fifo, isotrack_within};
    let d = tempfile::tempdir().unwrap();
    let out = |n: &str| d.path().join(n).display().to_string();
    let p = fifo(d.path(), "p.toml");
    let csv = fifo(d.path(), "p.csv");
    let not_regular = ["not a regular file"];
    // run SCENARIO
    assert_fails(&isotrack_within(&["run", &p], 20), 66, &not_regular);
    // field.path
    let sc = write(
        d.path(),
        "sc.toml",
        &format!("[field]\nkind = \"grid\"\npath = \"{csv}\"\nformat = \"csv\"\n"),
    );
    assert_fails(
        &isotrack_within(&["run", &sc], 20),
        66,
        &["field.path", "not a regular file"],
    );
    // sweep SWEEP, and a sweep whose scenario is a FIFO
    assert_fails(
        &isotrack_within(&["sweep", &p, "--out", &out("s1")], 20),
        66,
        &not_regular,
    );
    let sw = write(
        d.path(),
        "sw.toml",
        "scenario = \"p.toml\"\n[grid]\nsim.seed = [1, 2]\n",
    );
    let o = isotrack_within(&["sweep", &sw, "--out", &out("s2")], 20);
    assert_fails(&o, 66, &not_regular);
    // replay --inputs
    assert_fails(
        &isotrack_within(&["replay", "--inputs", &csv, "--out", &out("r.csv")], 20),
        66,
        &not_regular,
    );
    // interpolate STATIONS
    assert_fails(
        &isotrack_within(
            &[
                "interpolate",
                &csv,
                "--value-column",
                "v",
                "--out",
                &out("g.csv"),
            ],
            20,
        ),
        66,
        &not_regular,
    );
    // benchmark SUITE: the file cannot be read (66), not an invalid suite (65)
    assert_fails(
        &isotrack_within(&["benchmark", &p, "--out", &out("b")], 20),
        66,
        &not_regular,
    );
}

/// Regression (issue 30, att30d-7): a NetCDF-4 grid whose group holds a hard link to itself or
/// to the root (13 KB of legal HDF5) aborted `run` with a stack overflow (exit 134). Refused
/// with 65 naming `field.path`, the file and the link; 3000 nested groups likewise.
#[test]
fn a_netcdf_group_cycle_is_refused_not_a_stack_overflow() {
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../isotrack-fields/tests/fixtures/netcdf");
    let d = tempfile::tempdir().unwrap();
    for (file, want) in [
        ("refused_group_loop.nc", "/g/loop -> /g"),
        ("refused_group_up.nc", "/g/up -> /"),
        ("refused_group_deep.nc", "group nesting exceeds 64 levels"),
    ] {
        let nc = fixtures.join(file);
        let sc = write(
            d.path(),
            "sc.toml",
            &format!(
                "[field]\nkind = \"grid\"\npath = {:?}\nvariable = \"v\"\n",
                nc.to_str().unwrap()
            ),
        );
        let o = isotrack(&["run", &sc]);
        assert_fails(&o, 65, &["field.path", file, want]);
        assert!(!stderr(&o).contains("overflow"), "{}", stderr(&o));
    }
}

/// Regression (issue 30, ver30-1): a relative `field.path` in a sweep's `[base]` or `[grid]`
/// was resolved against the working directory, not the sweep file's directory (as the sweep's
/// `scenario` is): the sweep worked only when started from that directory, and `--resume` from
/// another one (a requeued Slurm task) exited 65. Started from elsewhere (the test's working
/// directory is the crate's, which holds no `b.csv`), the paths are the sweep file's, recorded
/// by absolute path, and a `--resume` from a third directory keeps every row.
#[test]
fn sweep_file_paths_are_relative_to_the_sweep_file() {
    let d = tempfile::tempdir().unwrap();
    let (scen, sub) = (d.path().join("scen"), d.path().join("sub"));
    std::fs::create_dir_all(&scen).unwrap();
    std::fs::create_dir_all(&sub).unwrap();
    // A 21 x 21 ramp v = x (1 m spacing); the base file and the sweep's differ by a constant.
    let ramp = |offset: f64| {
        (0..21)
            .map(|_| {
                (0..21)
                    .map(|i| format!("{}", offset + f64::from(i)))
                    .collect::<Vec<_>>()
                    .join(",")
            })
            .collect::<Vec<_>>()
            .join("\n")
            + "\n"
    };
    write(&scen, "a.csv", &ramp(0.0));
    write(&sub, "b.csv", &ramp(1.0));
    write(&sub, "c.csv", &ramp(2.0));
    write(
        &scen,
        "sc.toml",
        "[field]\nkind = \"grid\"\npath = \"a.csv\"\n[initial]\nx_m = 10.0\ny_m = 10.0\n\
         [controller]\nlevel = 12.0\n[sim]\nduration_s = 1.0\n",
    );
    for (name, sweep, file) in [
        (
            "base.toml",
            "scenario = \"../scen/sc.toml\"\n[base]\nfield.path = \"b.csv\"\n\
             [grid]\ncontroller.kp = [5.0, 10.0]\n",
            "b.csv",
        ),
        (
            "grid.toml",
            "scenario = \"../scen/sc.toml\"\n[grid]\nfield.path = [\"b.csv\", \"c.csv\"]\n",
            "a.csv",
        ),
    ] {
        let s = write(&sub, name, sweep);
        let out = d.path().join(format!("o-{name}"));
        let o = isotrack(&["sweep", &s, "--out", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        let base = std::fs::read_to_string(out.join("base_scenario.toml")).unwrap();
        let dir = if file == "a.csv" { &scen } else { &sub };
        let want = dir.canonicalize().unwrap().join(file);
        assert!(base.contains(want.to_str().unwrap()), "{name}: {base}");
        let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
        assert_eq!(csv.lines().count(), 3, "{csv}");
        assert!(!csv.contains("invalid_scenario"), "{name}: {csv}");
        // A resume from another directory (given the sweep by a path relative to it), its
        // last row removed.
        let kept: String = csv.lines().take(2).map(|l| format!("{l}\n")).collect();
        std::fs::write(out.join("results.csv"), kept).unwrap();
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .current_dir(d.path())
            .args([
                "sweep",
                &format!("sub/{name}"),
                "--out",
                out.to_str().unwrap(),
            ])
            .arg("--resume")
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        assert_eq!(
            std::fs::read_to_string(out.join("results.csv")).unwrap(),
            csv
        );
    }
}

/// Regression (issue 30, att30d-13 a): a row converged at t = 0 (|eps| below the tolerance at
/// every step from the start) beside a steady-state maximum error far past the tolerance was
/// kept by `--resume`. The scenario's tolerance (1 % of its level) is below 1; the row's
/// maximum is above 1.
#[test]
fn resume_refuses_a_convergence_the_window_contradicts() {
    let d = tempfile::tempdir().unwrap();
    let scen = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/gaussian-plumes-pm25.toml");
    let sw = write(
        d.path(),
        "s.toml",
        &format!(
            "scenario = {:?}\n[base]\nsim.duration_s = 30.0\ncontroller.max_turn_rate_radps = 100.0\n[grid]\ncontroller.kp = [10.0, 20.0]\n",
            scen.to_str().unwrap()
        ),
    );
    let out = d.path().join("d");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let results = out.join("results.csv");
    let good = std::fs::read_to_string(&results).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let mut row: Vec<&str> = lines[1].split(',').collect();
    let max: f64 = row[col("steady_state_max_abs_error")].parse().unwrap();
    assert!(
        row[col("convergence_time_s")].is_empty() && max > 1.0,
        "{}",
        lines[1]
    );
    row[col("convergence_time_s")] = "0.0";
    std::fs::write(&results, format!("{}\n{}\n", lines[0], row.join(","))).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap(), "--resume"]);
    assert_fails(
        &o,
        65,
        &[
            "steady_state_max_abs_error",
            "contradicts it",
            "is at or before the steady-state window's start",
        ],
    );
    // Issue 30, att30d-1: cells a completed run always writes, emptied (the row otherwise
    // intact): its path length, its control effort (finite under the turn-rate limit of
    // 100 rad/s in [base], which no command of this run reaches), its window's RMS error
    // beside the maximum.
    for (name, needle) in [
        (
            "path_length_m",
            "path_length_m is empty in a `completed` row",
        ),
        (
            "control_effort",
            "control_effort is empty in a `completed` row",
        ),
        (
            "steady_state_rms_error",
            "steady_state_rms_error is empty beside steady_state_max_abs_error",
        ),
    ] {
        let mut row: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(row[col("outcome")], "completed", "{}", lines[1]);
        assert!(!row[col(name)].is_empty(), "{}", lines[1]);
        row[col(name)] = "";
        std::fs::write(&results, format!("{}\n{}\n", lines[0], row.join(","))).unwrap();
        let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap(), "--resume"]);
        assert_fails(&o, 65, &[needle]);
    }
    // The row as written resumes.
    std::fs::write(&results, format!("{}\n{}\n", lines[0], lines[1])).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap(), "--resume"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}
