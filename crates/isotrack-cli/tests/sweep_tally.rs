//! Issue 30 (items a and b of the run-files work): a sweep is not silent about runs that did
//! not complete or ended with a warning, and the output-directory lock names its holder.
mod common;
use common::{assert_fails, bundled, isotrack, stderr, sweep_file, swept, write};

/// A 5 m Gaussian plume (peak 10, level 5): started 5 m from its centre the PI-like law tracks
/// it; started 60 m away the field's slope there is exp(-60^2/50) = 5e-32 of the peak, nothing
/// next to c1*tanh(5) = 0.2, so the law circles where it starts (check::flat_start).
const PLUME: &str = "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{ center_m = [0.0, 0.0], amplitude = 10.0, sigma_m = [5.0, 5.0], rotation_rad = 0.0 }]\n[controller]\nlevel = 5.0\n[sim]\nduration_s = 20.0\n";

/// Runs 1 and 3 (started 60 m out) get a flat-start warning in their `warnings` cell; runs 0
/// and 2 (5 m out) none; the sweep's stderr says 2 of 4 runs with their ids, and every other
/// column keeps its place (the new column is the last).
#[test]
fn a_sweep_tallies_and_records_runs_with_warnings() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0]\ninitial.x_m = [5.0, 60.0]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning: 2 of 4 runs did not complete or ended with a warning (run_id 1, 3)"),
        "{err}"
    );
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let n = header.len();
    assert_eq!(
        &header[n - 3..],
        ["samples", "outcome_detail", "warnings"],
        "the columns before stay in place"
    );
    let rows: Vec<csv::StringRecord> = rdr.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let far = &r[header.iter().position(|h| h == "initial.x_m").unwrap()] == "60.0";
        assert_eq!(&r[n - 1].is_empty(), &!far, "{r:?}");
        if far {
            assert!(
                r[n - 1].starts_with("flat start") && r[n - 1].contains("controller.search"),
                "{r:?}"
            );
        }
    }
    // Resumed, the tally counts the kept rows too.
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("2 of 4 runs"), "{}", stderr(&o));
}

/// A sweep without such runs prints no tally.
#[test]
fn a_sweep_without_warnings_prints_no_tally() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [4.0, 5.0]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// While a benchmark holds an output directory (this process, through the benchmark's own
/// `open_out_dir`), a sweep and a merge there are refused naming the benchmark and its pid,
/// not "sweep, merge or benchmark"; released, the lock file is left empty.
#[test]
fn the_lock_message_names_the_command_that_holds_it() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [4.0, 5.0]\n",
    );
    let out = d.path().join("bench");
    let lock = isotrack_commands::league::open_out_dir(&out, false).unwrap();
    let holder = format!("another isotrack benchmark pid {}", std::process::id());
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 73, &[&holder, "is writing this directory"]);
    assert!(!stderr(&o).contains("sweep, merge or benchmark"));
    let o = isotrack(&[
        "merge",
        out.to_str().unwrap(),
        "--out",
        d.path().join("m").to_str().unwrap(),
    ]);
    assert_fails(
        &o,
        73,
        &[
            &format!("an isotrack benchmark pid {}", std::process::id()),
            "is still writing",
        ],
    );
    drop(lock);
    assert!(
        !out.join(".isotrack.lock").exists(),
        "a released lock leaves no lock file"
    );
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Copies sweep output `from` to `to` with `results.csv` replaced by `text`.
fn copy_with(from: &std::path::Path, to: &std::path::Path, text: &str) {
    std::fs::create_dir_all(to).unwrap();
    for f in ["sweep.json", "sweep.toml", "base_scenario.toml"] {
        std::fs::copy(from.join(f), to.join(f)).unwrap();
    }
    std::fs::write(to.join("results.csv"), text).unwrap();
}

/// `row` (1-based line) of `text` with its last cell (`warnings`) set to `w`.
fn with_warnings(text: &str, line: usize, w: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let l = &lines[line - 1];
    // The warnings cell is the last: quoted when it holds a comma.
    let cut = if l.ends_with('"') {
        l[..l.len() - 1].rfind(",\"").unwrap()
    } else {
        l.rfind(',').unwrap()
    };
    lines[line - 1] = format!("{},{w}", &l[..cut]);
    lines.join("\n") + "\n"
}

/// att30b item 16: the `warnings` cell is recomputed from the run's scenario on `--resume`
/// and `merge` (a blanked warning, or text on a run without one, is a damaged row), and its
/// numbers are the console's rounding (6 significant digits), never 17.
#[test]
fn the_warnings_cell_is_recomputed_and_rounded() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [5.0, 60.0]\n",
    );
    let out = d.path().join("out");
    let text = swept(&sw, &out, &[]);
    let far = text.lines().nth(2).unwrap();
    assert!(far.contains("flat start"), "{far}");
    // No number of more than 6 significant digits in the warning.
    let w = &far[far.find("flat start").unwrap()..];
    let longest = w
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap();
    assert!(longest <= 6, "{w}");
    for (name, line, value) in [("blank", 3, ""), ("made-up", 2, "x")] {
        let o_dir = d.path().join(name);
        copy_with(&out, &o_dir, &with_warnings(&text, line, value));
        let o = isotrack(&["sweep", &sw, "--out", o_dir.to_str().unwrap(), "--resume"]);
        assert_fails(&o, 65, &[&format!("results.csv:{line}"), "warnings"]);
        let m = isotrack(&[
            "merge",
            o_dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("m-{name}")).to_str().unwrap(),
        ]);
        assert_fails(&m, 65, &[&format!("results.csv:{line}"), "warnings"]);
    }
}

/// att30b item 6 (its reverse half): a valid run's row relabelled `invalid_scenario` (dropped
/// from every statistic) is refused on `--resume` and `merge`, and an invalid run's row must
/// give the reason the plan gives it. Run 1 (dt 0.03 s against a 100 Hz sensor) is invalid.
#[test]
fn invalid_scenario_rows_are_recomputed() {
    let d = tempfile::tempdir().unwrap();
    let sw = sweep_file(
        d.path(),
        "s.toml",
        &bundled("paper-fig2b-circular"),
        "[base]\nsim.duration_s = 20.0\n[grid]\nsim.dt_s = [0.01, 0.03]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(65), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[2].contains(",invalid_scenario,"), "{}", lines[2]);
    let header: Vec<&str> = lines[0].split(',').collect();
    let at = header.iter().position(|h| *h == "outcome").unwrap();
    // Run 0 relabelled: its plan columns, outcome invalid_scenario, every metric empty, a
    // made-up reason, no warnings.
    let mut cells: Vec<String> = lines[1].split(',').take(at).map(str::to_string).collect();
    cells.push("invalid_scenario".into());
    cells.extend(std::iter::repeat_n(String::new(), header.len() - at - 3));
    cells.push("made up".into());
    cells.push(String::new());
    let relabelled = cells.join(",");
    // Run 1's reason changed.
    let reason = lines[2].replacen("sim.dt_s", "sim.dt_x", 1);
    assert_ne!(reason, lines[2]);
    for (name, line, row, needle) in [
        ("valid", 2, relabelled.as_str(), "outcome"),
        ("reason", 3, reason.as_str(), "outcome_detail"),
    ] {
        let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
        l[line - 1] = row.to_string();
        let o_dir = d.path().join(name);
        copy_with(&out, &o_dir, &(l.join("\n") + "\n"));
        let o = isotrack(&["sweep", &sw, "--out", o_dir.to_str().unwrap(), "--resume"]);
        assert_fails(&o, 65, &[&format!("results.csv:{line}"), needle]);
        let m = isotrack(&[
            "merge",
            o_dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("m-{name}")).to_str().unwrap(),
        ]);
        assert_fails(&m, 65, &[&format!("results.csv:{line}"), needle]);
    }
}

/// Brief fix30f item F: a fixed wing without `controller.max_turn_rate_radps` flies the
/// airframe's limit `g tan(40 deg) / V` (0.274 rad/s at 30 m/s) under every law but a
/// schedule; a sliding-mode row's `control_effort` is bounded by it over the run, `0.274^2 x 20
/// s = 1.5 rad^2/s`: 10 (within `1^2 x 20`, the Dubins sliding mode's default) is refused.
#[test]
fn fixed_wing_rows_are_bounded_by_the_airframes_turn_limit() {
    let d = tempfile::tempdir().unwrap();
    write(
        d.path(),
        "fw.toml",
        "[field]\nkind = \"radial_exp\"\ndecay_per_m = 0.001\n[vehicle]\nkind = \"fixed_wing\"\n[initial]\nx_m = 700.0\n[sim]\nduration_s = 20.0\n[sensor]\nrate_hz = 1.0\n[controller]\nkind = \"sliding_mode\"\n",
    );
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"fw.toml\"\n[grid]\nsensor.noise_std = [0.0]\n",
    );
    let out = d.path().join("out");
    let text = swept(&sw, &out, &[]);
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let at = header.iter().position(|h| *h == "control_effort").unwrap();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    let limit = 9.80665 * 40f64.to_radians().tan() / 30.0;
    let effort: f64 = row[at].parse().unwrap();
    assert!(effort <= limit * limit * 20.0 * (1.0 + 1e-9), "{effort}");
    let mut bad: Vec<String> = row.iter().map(|s| s.to_string()).collect();
    bad[at] = "10.0".into();
    let doctored = format!("{}\n{}\n", text.lines().next().unwrap(), bad.join(","));
    let o_dir = d.path().join("bad");
    copy_with(&out, &o_dir, &doctored);
    let o = isotrack(&["sweep", &sw, "--out", o_dir.to_str().unwrap(), "--resume"]);
    assert_fails(
        &o,
        65,
        &["results.csv:2", "control_effort", "turn-rate limit"],
    );
}

/// att30c-3 (a, b): a row is kept only as isotrack writes it, byte for byte (a quoted
/// `"completed"` reads as `completed` but would be copied verbatim), and a row that did not
/// complete says why (an empty `outcome_detail` in a `diverged` row is refused).
#[test]
fn rows_are_kept_only_as_isotrack_writes_them() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [5.0, 6.0]\n",
    );
    let out = d.path().join("out");
    let text = swept(&sw, &out, &[]);
    let row = text.lines().nth(1).unwrap();
    assert!(row.contains(",completed,"), "{row}");
    for (name, edited, needle) in [
        (
            "quoted",
            row.replacen(",completed,", ",\"completed\",", 1),
            "as isotrack writes",
        ),
        (
            "nodetail",
            row.replacen(",completed,", ",diverged,", 1),
            "outcome_detail is empty",
        ),
    ] {
        let o_dir = d.path().join(name);
        copy_with(&out, &o_dir, &text.replacen(row, &edited, 1));
        let o = isotrack(&["sweep", &sw, "--out", o_dir.to_str().unwrap(), "--resume"]);
        assert_fails(&o, 65, &["results.csv:2", needle]);
        let m = isotrack(&[
            "merge",
            o_dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("m-{name}")).to_str().unwrap(),
        ]);
        assert_fails(&m, 65, &["results.csv:2", needle]);
    }
}

/// att30c-3 (c, d): the bounds the run's metric windows set, from what
/// `isotrack_sim::Metrics::finish` computes. The plume runs 20 s in steps of 0.01 s (N = 2000):
/// the convergence dwell is 10 % of the run, 200 steps, so a convergence time is at most
/// (2000 - 200) x 0.01 s = 18 s (`t_end_s` itself, 20.0, is refused; 18.0 kept); the
/// steady-state window is the last 20 %, steps 1600 to 2000, 4 s, so `sign_changes_per_s` is a
/// count over 4 s: 66.123456 (264.49 changes) is refused, 66.25 (265) kept. Each refusal
/// names file, line and column, on `--resume` and `merge` alike.
#[test]
fn convergence_and_sign_change_cells_are_bounded_by_the_metric_windows() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [5.0, 6.0]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let row = text.lines().nth(1).unwrap();
    assert!(row.contains(",completed,") && !row.contains('"'), "{row}");
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    // A convergence time past the steady window's start (16 s) is consistent only with a window
    // that is not wholly within the tolerance (0.05): the edits of convergence_time_s also set
    // the window's maximum to 0.06, so each is judged by the dwell bound alone.
    let with = |name: &str, v: &str| {
        let mut cells: Vec<&str> = row.split(',').collect();
        cells[col(name)] = v;
        if name == "convergence_time_s" {
            cells[col("steady_state_max_abs_error")] = "0.06";
        }
        text.replacen(row, &cells.join(","), 1)
    };
    let latest = format!("{:?}", 1800.0 * 0.01);
    assert_eq!(latest, "18.0");
    for (name, key, v, kept) in [
        ("conv_end", "convergence_time_s", "20.0", false),
        ("conv_late", "convergence_time_s", "18.01", false),
        ("conv_latest", "convergence_time_s", latest.as_str(), true),
        ("signs_frac", "sign_changes_per_s", "66.123456", false),
        ("signs_whole", "sign_changes_per_s", "66.25", true),
    ] {
        let o_dir = d.path().join(name);
        copy_with(&out, &o_dir, &with(key, v));
        let o = isotrack(&["sweep", &sw, "--out", o_dir.to_str().unwrap(), "--resume"]);
        let m = isotrack(&[
            "merge",
            o_dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("m-{name}")).to_str().unwrap(),
        ]);
        if kept {
            assert!(o.status.success(), "{name}: {}", stderr(&o));
            assert!(m.status.success(), "{name}: {}", stderr(&m));
            continue;
        }
        let column = format!("column {} ({key})", col(key) + 1);
        let says = match name {
            "conv_end" => "convergence_time_s = 20 s is later than t_end_s - metrics.convergence_min_dwell_s = 18 s",
            "signs_frac" => "sign_changes_per_s = 66.123456 is not a whole number of sign changes",
            _ => key,
        };
        for o in [&o, &m] {
            assert_fails(o, 65, &["results.csv:2", &column, says]);
        }
    }
}
