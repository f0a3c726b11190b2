//! Issue 32: `isotrack plot` of a team's run (scenarios/team-circular-4.toml): every vehicle's
//! path in its own colour, `team.*` with the gaps over time and the revisit time along the
//! isoline, `--animate` of the team; the numbers read off the trace against the geometry.
mod common;
use common::isotrack;
use isotrack_plot::{RunData, TeamTracks};
use std::f64::consts::{LN_2, PI};

const TEAM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/team-circular-4.toml"
);

/// With `none` every robot runs at `v0` on a field symmetric under rotation, so the cluster
/// keeps its deployed gaps: `0.3 R` ahead of robots 0, 1 and 2 (listed in the order of travel),
/// `L - 0.9 R` ahead of robot 3; every point of the isoline then waits `(L - 0.9 R)/v0` between
/// the cluster's passes, the longest unvisited time over a window longer than a lap.
#[test]
fn team_figures_and_their_numbers() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("run");
    let o = isotrack(&[
        "run",
        TEAM,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "team.spacing=\"none\"",
        "--set",
        "sim.duration_s=200.0",
        "--set",
        "metrics.steady_state_fraction=0.9",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let vehicles = RunData::load_team(&out).unwrap();
    assert_eq!(vehicles.len(), 4);
    let r = 10.0 * LN_2;
    let l = 2.0 * PI * r;
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert!((tracks.length_m() - l).abs() < 1e-9);
    let gaps = tracks.gaps(10);
    assert!(gaps.len() > 100);
    for (t, g) in &gaps {
        for (i, want) in [0.3 * r, 0.3 * r, 0.3 * r, l - 0.9 * r].iter().enumerate() {
            assert!(
                (g[i] - want).abs() < 0.02 * want,
                "t {t}: gap {i} {} vs {want}",
                g[i]
            );
        }
    }
    let wait = (l - 0.9 * r) / 0.5;
    let revisit = tracks.revisit_max(20.0);
    assert_eq!(revisit.len(), isotrack_plot::REVISIT_BINS);
    for (s, w) in &revisit {
        assert!((w - wait).abs() < 0.02 * wait, "at {s} m: {w} vs {wait}");
    }

    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--format",
        "svg",
        "--animate",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for f in [
        "trajectory.svg",
        "timeseries.svg",
        "team.svg",
        "animation.gif",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // Four paths, one per vehicle, each in its own colour, labelled in the legend.
    let svg = std::fs::read_to_string(out.join("trajectory.svg")).unwrap();
    for i in 0..4 {
        assert!(svg.contains(&format!("vehicle {i}")), "vehicle {i}");
    }
    let team = std::fs::read_to_string(out.join("team.svg")).unwrap();
    assert!(team.contains("gap ahead along the isoline"));
    assert!(team.contains("longest unvisited time"));
    // Titled by the scenario, not "4 runs".
    assert!(team.contains("team-circular-4"));

    // A vehicle cell that is not one of the team's: 65 naming its line (file line 4, the third
    // row: att32f-8, it was named "row 3"), no figure.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines: Vec<String> = trace.lines().map(str::to_string).collect();
    let last = lines[3].rfind(',').unwrap();
    lines[3] = format!("{},9", &lines[3][..last]);
    std::fs::write(out.join("trace.csv"), lines.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        d.path().join("f").to_str().unwrap(),
    ]);
    common::assert_fails(
        &o,
        65,
        &["trace.csv:4:", "not one of the team's 4 vehicles"],
    );
    // att32: a row missing (vehicle 2's at the second recorded time, file line 8: header, four
    // rows at t = 0, then vehicles 0 and 1) pairs vehicle 2's positions with the others' at
    // another time: 65 naming the line where its rows go wrong (line 11 then, vehicle 2's next
    // row, its second row but at the third time); the last row of a vehicle that completed
    // (vehicle 3's, the file's last line) likewise.
    let original: Vec<&str> = trace.lines().collect();
    assert!(original[7].ends_with(",2") && original[11].ends_with(",2"));
    let mut cut: Vec<&str> = original.clone();
    cut.remove(7);
    std::fs::write(out.join("trace.csv"), cut.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        d.path().join("f").to_str().unwrap(),
    ]);
    common::assert_fails(&o, 65, &["trace.csv:11:", "vehicle 2's row 2", "missing"]);
    let mut cut: Vec<&str> = original.clone();
    let last = cut.pop().unwrap();
    assert!(last.ends_with(",3"));
    std::fs::write(out.join("trace.csv"), cut.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        d.path().join("f").to_str().unwrap(),
    ]);
    common::assert_fails(
        &o,
        65,
        &["vehicle 3's rows end", "completed the run", "missing"],
    );
    // Back to the trace with the vehicle cell of another team.
    std::fs::write(out.join("trace.csv"), lines.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        d.path().join("r.html").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(65), "{}", common::stderr(&o));
}

/// Runs scenario `text` as a team into `dir/run` and draws it (`plot --format svg`); returns
/// the run directory.
fn run_and_plot(dir: &std::path::Path, text: &str) -> std::path::PathBuf {
    let scenario = dir.join("team.toml");
    std::fs::write(&scenario, text).unwrap();
    let out = dir.join("run");
    let o = isotrack(&[
        "run",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = isotrack(&["plot", out.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    out
}

/// Off a radial field: one isotropic Gaussian plume `F = 20 exp(-|p|^2/(2 * 5^2))`, whose
/// level-10 isoline is the circle of radius `r = 5 sqrt(2 ln 2)` (5.887 m). `team.svg` is drawn
/// along the polyline the metrics use (marching squares on 400 samples a side over the
/// plume's centre +- 8 sigma, `h = 80/399` m), labelled a closed isoline: every vertex lies on
/// the circle within linear interpolation's error along a lattice edge,
/// `h^2 max|F''|/(8 |F'|)` (`|F'| = 10 r/25`, `|F''| <= |F'|/r` there), doubled; its length
/// is the circle's within 0.1 %; the gaps read off the trace are the deployment's
/// (`none`: the field is symmetric under rotation), 0.5 r apart, and `L - r` ahead of the last.
#[test]
fn team_figure_off_a_radial_field_draws_the_metrics_polyline() {
    let d = tempfile::tempdir().unwrap();
    let sigma: f64 = 5.0;
    let r = sigma * (2.0 * LN_2).sqrt();
    let text = format!(
        "name = \"plume-team\"\n[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\n\
         sources = [{{ center_m = [0.0, 0.0], amplitude = 20.0, sigma_m = [5.0, 5.0], rotation_rad = 0.0 }}]\n\
         [vehicle]\nkind = \"dubins\"\nspeed_mps = 0.5\n\
         [controller]\nkind = \"pi_isoline\"\nlevel = 10.0\nkp = 10.0\nki = 1.0\nc1 = 0.2\nc2 = 1.0\n\
         [sensor]\nnoise_std = 0.0\n\
         [sim]\ndt_s = 0.01\nduration_s = 40.0\nseed = 0\n\
         [team]\nspacing = \"none\"\ncount = 3\n\
         spread = {{ along = \"arc\", center_m = [0.0, 0.0], radius_m = {r}, start_rad = 0.0, step_rad = 0.5, clockwise = true }}\n"
    );
    let out = run_and_plot(d.path(), &text);
    let vehicles = RunData::load_team(&out).unwrap();
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert!(tracks.is_closed());
    assert!(
        tracks.isoline_label.contains("closed"),
        "{}",
        tracks.isoline_label
    );
    let pts = tracks.arc.points();
    assert!(pts.len() > 100);
    assert_eq!(pts.first(), pts.last());
    let h = 80.0 / 399.0;
    let slope = 10.0 * r / (sigma * sigma);
    let tol = 2.0 * h * h * (slope / r) / (8.0 * slope);
    for p in &pts {
        assert!(
            (p.norm() - r).abs() <= tol,
            "{p:?}: {} vs {r} (tol {tol})",
            p.norm()
        );
    }
    let l = 2.0 * PI * r;
    assert!(
        (tracks.length_m() / l - 1.0).abs() < 1e-3,
        "{}",
        tracks.length_m()
    );
    for (t, g) in tracks.gaps(50) {
        for (i, want) in [0.5 * r, 0.5 * r, l - r].iter().enumerate() {
            assert!(
                (g[i] - want).abs() < 0.02 * want,
                "t {t}: gap {i} {} vs {want}",
                g[i]
            );
        }
    }
    let team = std::fs::read_to_string(out.join("team.svg")).unwrap();
    assert!(team.contains("true isoline s_d = 10 (closed)"));
    assert!(team.contains("gap ahead along the isoline"));
}

/// An open isoline: the line `y = 5` m of the plane `F = 0.1 y` (crossing the box the team can
/// reach), four robots heading west at `x = 12, 6, 3, 0` m under `none`: the gap ahead of the
/// first three is 6, 3, 3 m at every row, the one in front has none (NaN); the revisit time
/// read off the trace is at most the longest gap over `v0`, 12 s, to a bin's crossing (314/360
/// m at 0.5 m/s) and a trace row, and a point the team never covered has none; `team.svg` is
/// labelled an open isoline, with the mean gap's dashed lines from `summary.json`.
#[test]
fn team_figure_along_an_open_isoline() {
    let d = tempfile::tempdir().unwrap();
    let heading = PI;
    let text = format!(
        "name = \"plane-team\"\n[field]\nkind = \"linear_ramp\"\noffset = 0.0\ngradient_per_m = [0.0, 0.1]\n\
         [vehicle]\nkind = \"dubins\"\nspeed_mps = 0.5\n\
         [controller]\nkind = \"pi_isoline\"\nlevel = 0.5\nkp = 10.0\nki = 1.0\nc1 = 0.2\nc2 = 1.0\n\
         [sensor]\nnoise_std = 0.0\n\
         [sim]\ndt_s = 0.01\nduration_s = 120.0\nseed = 0\n\
         [team]\nspacing = \"none\"\n\
         starts = [{{x_m = 12.0, y_m = 5.0, heading_rad = {heading}}}, {{x_m = 6.0, y_m = 5.0, heading_rad = {heading}}}, \
         {{x_m = 3.0, y_m = 5.0, heading_rad = {heading}}}, {{x_m = 0.0, y_m = 5.0, heading_rad = {heading}}}]\n"
    );
    let out = run_and_plot(d.path(), &text);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let t = &summary["team"];
    assert!(t["metrics_note"].is_null(), "{t}");
    let stretch = t["open_isoline"]["stretch_length_m"].as_f64().unwrap();
    assert!((stretch - 12.0).abs() < 1e-6, "{t}");
    let vehicles = RunData::load_team(&out).unwrap();
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert!(!tracks.is_closed());
    assert!(
        tracks.isoline_label.contains("open"),
        "{}",
        tracks.isoline_label
    );
    assert!(tracks.arc.points().iter().all(|p| (p.y - 5.0).abs() < 1e-9));
    let gaps = tracks.gaps(2);
    assert!(gaps.len() > 100, "{}", gaps.len());
    for (t, g) in &gaps {
        for (i, want) in [6.0, 3.0, 3.0].iter().enumerate() {
            assert!(
                (g[i] - want).abs() < 1e-6,
                "t {t}: gap {i} {} vs {want}",
                g[i]
            );
        }
        assert!(
            g[3].is_nan(),
            "t {t}: the vehicle in front has no gap ahead: {}",
            g[3]
        );
    }
    let revisit = tracks.revisit_max(60.0);
    let tol = 314.0 / 360.0 / 0.5 + 0.1;
    let finite: Vec<f64> = revisit
        .iter()
        .map(|r| r.1)
        .filter(|w| w.is_finite())
        .collect();
    assert!(!finite.is_empty() && finite.len() < revisit.len());
    let worst = finite.iter().copied().fold(0.0, f64::max);
    assert!((worst - 12.0).abs() <= tol, "{worst}");
    let team = std::fs::read_to_string(out.join("team.svg")).unwrap();
    // nu36-12: a ramp without a domain has no edge: its line is cut at the box the team can
    // reach (it was labelled "open: it leaves the field").
    assert!(team.contains("open: cut at the box the team can reach"));
    assert!(!team.contains("leaves the field"));
    assert!(team.contains("mean gap S/(N-1)"));
    // nu36-11: the same team without a scenario `name` is titled by its run directory, as a
    // single run is, in all three figures (each was titled "vehicle 0").
    let unnamed = d.path().join("unnamed.toml");
    std::fs::write(&unnamed, text.replacen("name = \"plane-team\"\n", "", 1)).unwrap();
    let openrun = d.path().join("openrun");
    let o = isotrack(&[
        "run",
        unnamed.to_str().unwrap(),
        "--out",
        openrun.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = isotrack(&["plot", openrun.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for f in ["trajectory.svg", "timeseries.svg", "team.svg"] {
        let svg = std::fs::read_to_string(openrun.join(f)).unwrap();
        assert!(svg.contains("openrun"), "{f}: titled by its vehicle 0");
    }
    // nu36-16: two team runs plotted together: no team figure, and a note says why.
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        openrun.to_str().unwrap(),
        "--format",
        "svg",
        "--out",
        d.path().join("both").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(!d.path().join("both/team.svg").exists());
    assert!(
        common::stderr(&o).contains("note: no team figure"),
        "{}",
        common::stderr(&o)
    );
}

/// att32d-14: a vehicle that leaves the field early. The field is a grid pyramid on
/// `[0, 40]^2` m (`F = -10 + min(x, y, 40 - x, 40 - y)`, 1 m lattice); vehicle 3 starts at
/// (38, 20) m heading east (+x) at 3 m/s with `v_max_mps = 3` and a turn limit of 0.2 rad/s,
/// so it crosses the grid's edge `x = 40` m, 2 m away, no sooner than 2/3 s; the other three
/// stay inside. Its last row once went into `trace.csv` after every row at 60 s, so the run's
/// own `plot`/`report` refused it (65, "goes back in time"), and the run said `completed` with
/// `warnings: []`. Now the rows are in time order (checked here row by row, independently of
/// the reader), vehicle 3's last row is at its `t_end_s`, `plot` and `report` draw the run,
/// and stderr and `summary.json`'s `warnings` name vehicle 3, its outcome and its time.
#[test]
fn a_vehicle_that_leaves_the_field_early_is_plotted_and_named() {
    let d = tempfile::tempdir().unwrap();
    let grid: String = (0..41)
        .map(|i: i32| {
            (0..41)
                .map(|j: i32| format!("{:.1}", -10 + i.min(j).min(40 - i).min(40 - j)))
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    let grid_path = common::write(d.path(), "pyr.csv", &grid);
    let scenario = common::write(
        d.path(),
        "left.toml",
        &format!(
            r#"name = "team-left"
[field]
kind = "grid"
path = "{grid_path}"
spacing_m = [1.0, 1.0]
origin_m = [0.0, 0.0]
interpolation = "bilinear"
[vehicle]
kind = "dubins"
speed_mps = 0.5
[controller]
kind = "pi_isoline"
level = 5.0
kp = 2.0
ki = 0.0
c1 = 0.2
c2 = 1.0
max_turn_rate_radps = 0.2
[sensor]
rate_hz = 100.0
[sim]
dt_s = 0.01
duration_s = 60.0
[team]
count = 4
starts = [{{x_m=25.0,y_m=20.0,heading_rad=1.5707963}},{{x_m=25.0,y_m=22.0,heading_rad=1.5707963}},{{x_m=25.0,y_m=24.0,heading_rad=1.5707963}},{{x_m=38.0,y_m=20.0,heading_rad=0.0}}]
spacing = "range_balance"
k_v = 0.1
vehicles = [{{index = 3, speed_mps = 3.0, v_max_mps = 3.0}}]
"#
        ),
    );
    let out = d.path().join("run");
    let o = isotrack(&["run", &scenario, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let err = common::stderr(&o);
    assert!(
        err.contains(
            "warning: 1 of the 3 vehicles besides vehicle 0 did not complete the run (vehicle 3: left_field at t = "
        ),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["outcome"], "completed");
    let v3 = &summary["vehicles"][3];
    assert_eq!(v3["outcome"], "left_field");
    let t_end = v3["t_end_s"].as_f64().unwrap();
    assert!((2.0 / 3.0 - 0.01..10.0).contains(&t_end), "t_end {t_end}");
    let warnings = summary["warnings"].as_array().unwrap();
    assert!(
        warnings.iter().any(|w| w
            .as_str()
            .unwrap()
            .contains("vehicle 3: left_field at t = ")),
        "{warnings:?}"
    );
    // Every row at or after the one before; vehicle 3's rows end at its t_end_s.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut before = f64::NEG_INFINITY;
    let mut last3 = f64::NAN;
    for (n, line) in trace.lines().enumerate().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let t: f64 = cells[0].parse().unwrap();
        assert!(t >= before, "trace.csv:{}: t_s = {t} after {before}", n + 1);
        before = t;
        if *cells.last().unwrap() == "3" {
            last3 = t;
        }
    }
    assert!((last3 - t_end).abs() < 1e-9, "{last3} vs {t_end}");
    assert_eq!(before, 60.0);
    let o = isotrack(&["plot", out.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = isotrack(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        d.path().join("r.html").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
}

/// att32d-7: several team runs drawn together name each vehicle by its run (`DIR vehicle I`):
/// the legend tells two runs of the same field apart, and two runs over different fields are
/// refused naming both directories (the message read "in vehicle 0, unset in vehicle 0").
/// One run alone keeps `vehicle I`.
#[test]
fn several_team_runs_name_their_vehicles_by_run() {
    let d = tempfile::tempdir().unwrap();
    let run = |name: &str, sets: &[&str]| {
        let out = d.path().join(name);
        let mut args = vec!["run", TEAM, "--out", out.to_str().unwrap(), "--quiet"];
        for s in sets {
            args.extend(["--set", s]);
        }
        let o = isotrack(&args);
        assert!(o.status.success(), "{}", common::stderr(&o));
        out
    };
    let a = run("ra", &["sim.duration_s=5.0"]);
    let b = run("rb", &["sim.duration_s=5.0", "team.spacing=\"none\""]);
    let c = run("rc", &["sim.duration_s=5.0", "field.i0=30.0"]);
    let figs = d.path().join("figs");
    let o = isotrack(&[
        "plot",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--format",
        "svg",
        "--out",
        figs.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let svg = std::fs::read_to_string(figs.join("trajectory.svg")).unwrap();
    for i in 0..4 {
        for r in ["ra", "rb"] {
            assert!(svg.contains(&format!("{r} vehicle {i}")), "{r} vehicle {i}");
        }
    }
    let o = isotrack(&[
        "report",
        a.to_str().unwrap(),
        c.to_str().unwrap(),
        "--out",
        d.path().join("r.html").to_str().unwrap(),
    ]);
    common::assert_fails(&o, 65, &["ra vehicle 0", "rc vehicle 0"]);
    let o = isotrack(&["plot", a.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let svg = std::fs::read_to_string(a.join("trajectory.svg")).unwrap();
    assert!(svg.contains("vehicle 0") && !svg.contains("ra vehicle 0"));
    // att32d-16: with per-vehicle speeds the ideal is L/sum v0_i, and team.svg's legend says
    // so (it read "ideal L/(N v0)").
    let team = std::fs::read_to_string(a.join("team.svg")).unwrap();
    assert!(team.contains("ideal L/(N v0)"));
    let e = run(
        "re",
        &[
            "sim.duration_s=5.0",
            "team.vehicles=[{index=3, speed_mps=0.3}]",
        ],
    );
    let o = isotrack(&["plot", e.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let team = std::fs::read_to_string(e.join("team.svg")).unwrap();
    assert!(team.contains("ideal L/sum v0_i") && !team.contains("ideal L/(N v0)"));
}

/// A team on a pyramid grid (level 5: a square loop) whose vehicle 0 leaves the field early:
/// it starts at (38, 20) m heading +x at 3 m/s, 2 m from the grid's edge; the other three
/// start on the loop's side x = 25 m and complete the 60 s run. Returns the run directory.
fn vehicle_0_leaves(d: &std::path::Path) -> std::path::PathBuf {
    let grid: String = (0..41)
        .map(|i: i32| {
            (0..41)
                .map(|j: i32| format!("{:.1}", -10 + i.min(j).min(40 - i).min(40 - j)))
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    let grid_path = common::write(d, "pyr.csv", &grid);
    let scenario = common::write(
        d,
        "left0.toml",
        &format!(
            r#"name = "team-left-0"
[field]
kind = "grid"
path = "{grid_path}"
spacing_m = [1.0, 1.0]
origin_m = [0.0, 0.0]
interpolation = "bilinear"
[vehicle]
kind = "dubins"
speed_mps = 0.5
[controller]
kind = "pi_isoline"
level = 5.0
kp = 2.0
ki = 0.0
c1 = 0.2
c2 = 1.0
max_turn_rate_radps = 0.2
[sensor]
rate_hz = 100.0
[sim]
dt_s = 0.01
duration_s = 60.0
[team]
count = 4
starts = [{{x_m=38.0,y_m=20.0,heading_rad=0.0}},{{x_m=25.0,y_m=20.0,heading_rad=1.5707963}},{{x_m=25.0,y_m=22.0,heading_rad=1.5707963}},{{x_m=25.0,y_m=24.0,heading_rad=1.5707963}}]
spacing = "range_balance"
k_v = 0.1
vehicles = [{{index = 0, speed_mps = 3.0, v_max_mps = 3.0}}]
"#
        ),
    );
    let out = d.join("run");
    let o = isotrack(&["run", &scenario, "--out", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    out
}

/// att32e-2/-6: vehicle 0 ends first (left_field near 0.67 s). `plot` draws every vehicle to
/// its own end: the team figure's rows (read from `TeamTracks`, the numbers drawn) are every
/// recorded time of the vehicles that completed, counted here from trace.csv's text, and its
/// gaps go on to the run's 60 s; each vehicle's timeseries is its own rows. Before the fix the
/// reader bounded every row by the top-level (vehicle 0's) end time, refusing the others'
/// later rows, and the team figure stopped at the first vehicle's end.
#[test]
fn every_vehicle_is_drawn_to_its_own_end() {
    let d = tempfile::tempdir().unwrap();
    let out = vehicle_0_leaves(d.path());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["vehicles"][0]["outcome"], "left_field");
    let t0 = summary["vehicles"][0]["t_end_s"].as_f64().unwrap();
    assert!(t0 < 5.0, "{t0}");
    // Rows per vehicle and the last time, from the text.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut rows = [0usize; 4];
    let mut last_t = [f64::NAN; 4];
    for line in trace.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let v: usize = cells.last().unwrap().parse().unwrap();
        rows[v] += 1;
        last_t[v] = cells[0].parse().unwrap();
    }
    assert_eq!(last_t[1..], [60.0; 3]);
    assert!(
        rows[0] < rows[1] && rows[1] == rows[2] && rows[2] == rows[3],
        "{rows:?}"
    );
    let o = isotrack(&["plot", out.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = isotrack(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        d.path().join("r.html").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let vehicles = RunData::load_team(&out).unwrap();
    for (i, v) in vehicles.iter().enumerate() {
        assert_eq!(v.trace.len(), rows[i], "vehicle {i}");
        assert_eq!(v.trace.last().unwrap().t_s, last_t[i], "vehicle {i}");
    }
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert_eq!(tracks.rows, rows[1]);
    assert_eq!(tracks.vehicle_rows[1..], rows[1..]);
    assert!(tracks.vehicle_rows[0] <= rows[0]);
    let gaps = tracks.gaps(1);
    assert_eq!(gaps.last().unwrap().0, 60.0);
    // After vehicle 0's end it has no gap; the three others' gaps close the loop.
    let (_, g) = gaps.last().unwrap();
    assert!(g[0].is_nan());
    let l = tracks.length_m();
    let sum: f64 = g[1..].iter().sum();
    assert!((sum - l).abs() < 1e-9 * l, "{sum} vs {l}");
}

/// att32e-4: a trace row of a vehicle after its own end (summary.json's `vehicles[i].t_end_s`)
/// is refused by `plot` and `report` (65), naming trace.csv's line and the vehicle. Here
/// vehicle 1's end is set to 30 s in the summary while its rows go on to 60 s: the first of
/// its rows past 30 s (its line found here in the text) is named. Before the fix a vehicle's
/// rows were bounded only by the run's end, and the run loaded.
#[test]
fn a_row_after_its_vehicles_end_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let out = vehicle_0_leaves(d.path());
    let path = out.join("summary.json");
    let mut summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    summary["vehicles"][1]["t_end_s"] = serde_json::json!(30.0);
    // Ended there as vehicle 0 ended (not `completed` at 30 s of a 60 s run: att32g-7 refuses
    // that first, naming scenario.toml's duration).
    summary["vehicles"][1]["outcome"] = summary["vehicles"][0]["outcome"].clone();
    std::fs::write(&path, serde_json::to_string_pretty(&summary).unwrap()).unwrap();
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let line = trace
        .lines()
        .enumerate()
        .skip(1)
        .find(|(_, l)| {
            let c: Vec<&str> = l.split(',').collect();
            *c.last().unwrap() == "1" && c[0].parse::<f64>().unwrap() > 30.0
        })
        .map(|(n, _)| n + 1)
        .unwrap();
    let want = format!("trace.csv:{line}: vehicle 1 has a row at t = ");
    let o = isotrack(&["plot", out.to_str().unwrap(), "--format", "svg"]);
    common::assert_fails(&o, 65, &[&want, "after its end"]);
    let o = isotrack(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        d.path().join("r.html").to_str().unwrap(),
    ]);
    common::assert_fails(&o, 65, &[&want, "after its end"]);
}

/// att32f-1 and -2: a team's `summary.json` that does not match its trace is refused (65, the
/// file and the key named) by `plot` and `report`, not drawn: `vehicles` one short (vehicle 3
/// then had no end known, its rows cut at 1 s drawn as its end) or one long (a vehicle 4 with
/// no rows), `team.count` differing from `team.vehicle_count`, and `team` set to null beside
/// the trace's `vehicle` column (drawn as one vehicle jumping between the team's positions).
/// Before the fix every one of these exited 0 (the attacker's edits of a 3 s run of four).
#[test]
fn a_summary_that_does_not_match_its_team_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("run");
    let o = isotrack(&[
        "run",
        TEAM,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "sim.duration_s=3.0",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = isotrack(&["plot", out.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let short_trace: String = trace
        .lines()
        .enumerate()
        .filter(|(n, l)| {
            let c: Vec<&str> = l.split(',').collect();
            *n == 0 || !(*c.last().unwrap() == "3" && c[0].parse::<f64>().unwrap() > 1.0)
        })
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, bool, &[&str]); 5] = [
        (
            "vehicles-3",
            |s| {
                s["vehicles"].as_array_mut().unwrap().pop();
            },
            false,
            &[
                "summary.json's `vehicles` lists 3 vehicles",
                "team.vehicle_count = 4",
            ],
        ),
        (
            "vehicles-3-trunc",
            |s| {
                s["vehicles"].as_array_mut().unwrap().pop();
            },
            true,
            &[
                "summary.json's `vehicles` lists 3 vehicles",
                "team.vehicle_count = 4",
            ],
        ),
        (
            "vehicles-5",
            |s| {
                let v0 = s["vehicles"][0].clone();
                s["vehicles"].as_array_mut().unwrap().push(v0);
            },
            false,
            &[
                "summary.json's `vehicles` lists 5 vehicles",
                "team.vehicle_count = 4",
            ],
        ),
        (
            "count-3",
            |s| s["team"]["count"] = serde_json::json!(3),
            false,
            &["summary.json: team.count = 3", "team.vehicle_count = 4"],
        ),
        (
            "team-null",
            |s| s["team"] = serde_json::Value::Null,
            false,
            &[
                "trace.csv has a `vehicle` column",
                "summary.json's `team` is null",
            ],
        ),
    ];
    for (name, edit, cut, needles) in cases {
        let dir = d.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        std::fs::copy(out.join("scenario.toml"), dir.join("scenario.toml")).unwrap();
        let t = if cut { &short_trace } else { &trace };
        std::fs::write(dir.join("trace.csv"), t).unwrap();
        let mut s = summary.clone();
        edit(&mut s);
        std::fs::write(
            dir.join("summary.json"),
            serde_json::to_string_pretty(&s).unwrap(),
        )
        .unwrap();
        let o = isotrack(&["plot", dir.to_str().unwrap(), "--format", "svg"]);
        common::assert_fails(&o, 65, needles);
        let o = isotrack(&[
            "report",
            dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("{name}.html")).to_str().unwrap(),
        ]);
        common::assert_fails(&o, 65, needles);
    }
}

/// att32f-8: a vehicle whose summary ends it later than its rows is refused naming that
/// vehicle and its line in trace.csv (the file's line, header included). Vehicle 0 leaves the
/// field at 0.68 s, between the recorded times 0.6 and 0.7 s: its last row, alone at 0.68 s, is
/// its end. With `vehicles[0].t_end_s` set to 30 s, or vehicle 0 `completed` at 60 s, that row
/// is named (before the fix: "trace.csv:31: vehicle 1's row 8 is at t = 0.7000000000000001
/// s, but recorded time 8 is t = 0.68 s", a right row blamed); with its last row cut (its rows
/// then end at 0.6 s, on the recorded times, against its end at 0.68 s) the run was drawn; now
/// its new last row is named.
#[test]
fn a_summary_end_that_is_not_the_traces_names_the_vehicle_and_its_line() {
    let d = tempfile::tempdir().unwrap();
    let out = vehicle_0_leaves(d.path());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["vehicles"][0]["outcome"], "left_field");
    let t0 = summary["vehicles"][0]["t_end_s"].as_f64().unwrap();
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    // Vehicle 0's rows: (file line, time cell, time).
    let rows0: Vec<(usize, &str, f64)> = trace
        .lines()
        .enumerate()
        .skip(1)
        .filter(|(_, l)| l.ends_with(",0"))
        .map(|(n, l)| {
            let t = l.split(',').next().unwrap();
            (n + 1, t, t.parse().unwrap())
        })
        .collect();
    let (line0, cell0, last_t) = *rows0.last().unwrap();
    assert_eq!(last_t, t0);
    // Its end is off the recorded times: the only row at that time.
    let at_end = trace
        .lines()
        .skip(1)
        .filter(|l| l.split(',').next() == Some(cell0))
        .count();
    assert_eq!(at_end, 1, "vehicle 0's end at {t0} s is a recorded time");
    let (line_before, cell_before, _) = rows0[rows0.len() - 2];
    let cut: String = trace
        .lines()
        .enumerate()
        .filter(|(n, _)| n + 1 != line0)
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    type Edit = fn(&mut serde_json::Value);
    // The top level repeats vehicle 0's record (att36-15 refuses a summary where it does not),
    // so each edit changes both.
    let later: Edit = |s| {
        s["vehicles"][0]["t_end_s"] = serde_json::json!(30.0);
        s["t_end_s"] = serde_json::json!(30.0);
    };
    let completed: Edit = |s| {
        s["vehicles"][0]["t_end_s"] = serde_json::json!(60.0);
        s["vehicles"][0]["outcome"] = serde_json::json!("completed");
        s["t_end_s"] = serde_json::json!(60.0);
        s["outcome"] = serde_json::json!("completed");
    };
    let none: Edit = |_| {};
    let named = format!("trace.csv:{line0}: vehicle 0's last row is at t = {cell0} s");
    let cases: [(&str, Edit, &str, Vec<String>); 3] = [
        (
            "later",
            later,
            &trace,
            vec![
                named.clone(),
                "summary.json's vehicles[0] ends it at t = 30 s (left_field)".into(),
            ],
        ),
        (
            "completed",
            completed,
            &trace,
            vec![
                named,
                "summary.json's vehicles[0] ends it at t = 60 s (completed)".into(),
            ],
        ),
        (
            "cut",
            none,
            &cut,
            vec![
                format!("trace.csv:{line_before}: vehicle 0's rows end at t = {cell_before} s"),
                format!("summary.json's vehicles[0] ends it at t = {cell0} s (left_field)"),
            ],
        ),
    ];
    for (name, edit, t, needles) in cases {
        let dir = d.path().join(name);
        std::fs::create_dir(&dir).unwrap();
        std::fs::copy(out.join("scenario.toml"), dir.join("scenario.toml")).unwrap();
        std::fs::write(dir.join("trace.csv"), t).unwrap();
        let mut s = summary.clone();
        edit(&mut s);
        std::fs::write(
            dir.join("summary.json"),
            serde_json::to_string_pretty(&s).unwrap(),
        )
        .unwrap();
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        let o = isotrack(&["plot", dir.to_str().unwrap(), "--format", "svg"]);
        common::assert_fails(&o, 65, &needles);
        let o = isotrack(&[
            "report",
            dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("{name}.html")).to_str().unwrap(),
        ]);
        common::assert_fails(&o, 65, &needles);
    }
}

/// The circular field of team-circular-4 inside `domain_m` [-20, 20]^2, a 20 s run, the
/// `[team]` table `team` (four robots under `range_balance` unless it says otherwise).
fn domain_team(team: &str) -> String {
    format!(
        r#"name = "team-domain"
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
duration_s = 20.0
[team]
spacing = "range_balance"
k_v = 0.1
v_min_mps = 0.25
v_max_mps = 0.75
{team}
"#
    )
}

/// att32f-3: four robots start at x = 19.9 m heading out of the domain and all leave the field
/// within the first second, long before the steady window (16 s to 20 s). `summary.json`'s
/// `revisit_time_max_s` is null, and team.svg draws no revisit curve (labelled so): every bin
/// of `TeamTracks::revisit_max` is NaN (before the fix about 0.3 s each, the open interval at
/// the last row, as if the loop were revisited within 0.3 s). The time axis runs to the last
/// vehicle's end, `TeamTracks::end_s`, the latest `t_end_s` in summary.json. With two robots,
/// one on the circle through the run and one leaving at once, the gaps stop within the first
/// second while the axis runs to the run's 20 s.
#[test]
fn a_team_gone_before_the_window_has_no_revisit_curve() {
    let d = tempfile::tempdir().unwrap();
    let out = run_and_plot(
        d.path(),
        &domain_team(
            "count = 4\nstarts = [{ x_m = 19.9, y_m = 0.0, heading_rad = 0.0 }, { x_m = 19.9, y_m = 1.0, heading_rad = 0.0 }, { x_m = 19.9, y_m = 2.0, heading_rad = 0.0 }, { x_m = 19.9, y_m = 3.0, heading_rad = 0.0 }]",
        ),
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["team"]["revisit_time_max_s"].is_null(), "{}", s["team"]);
    let ends: Vec<f64> = (0..4)
        .map(|i| {
            assert_eq!(s["vehicles"][i]["outcome"], "left_field");
            s["vehicles"][i]["t_end_s"].as_f64().unwrap()
        })
        .collect();
    let last = ends.iter().copied().fold(0.0, f64::max);
    assert!(last < 1.0, "{ends:?}");
    let vehicles = RunData::load_team(&out).unwrap();
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert_eq!(tracks.end_s(), last);
    let ss = vehicles[0].steady_state_start_s();
    assert_eq!(ss, 16.0, "the last 20 % of 20 s");
    let revisit = tracks.revisit_max(ss);
    assert!(!revisit.is_empty() && revisit.iter().all(|r| r.1.is_nan()));
    let svg = std::fs::read_to_string(out.join("team.svg")).unwrap();
    assert!(svg.contains("no revisit time: no vehicle live in the steady window"));
    assert!(!svg.contains("revisit time, steady window"));

    let d2 = tempfile::tempdir().unwrap();
    let out = run_and_plot(
        d2.path(),
        &domain_team(
            "count = 2\nstarts = [{ x_m = 6.931471805599, y_m = 0.0, heading_rad = -1.570796326795 }, { x_m = 19.9, y_m = 2.0, heading_rad = 0.0 }]",
        ),
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["vehicles"][0]["outcome"], "completed");
    assert_eq!(s["vehicles"][1]["outcome"], "left_field");
    assert!(s["team"]["revisit_time_max_s"].as_f64().is_some());
    let vehicles = RunData::load_team(&out).unwrap();
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert_eq!(tracks.end_s(), 20.0);
    let gaps = tracks.gaps(1);
    assert!(gaps.last().unwrap().0 < 1.0, "{:?}", gaps.last());
    let svg = std::fs::read_to_string(out.join("team.svg")).unwrap();
    assert!(svg.contains("revisit time, steady window"));
}

/// nu36-2: team.svg's dashed references (the even gap `L/N` over the gaps, the ideal
/// `L/(N v0)` over the revisit curve) are drawn again over the curves, which settle on them and
/// hid them: each of their dashes (black, 2 px, horizontal) is in the SVG twice, the second
/// after the curves (before the fix no dash was drawn twice).
#[test]
fn team_figure_draws_its_dashed_references_over_the_curves() {
    let d = tempfile::tempdir().unwrap();
    let scenario = common::bundled("team-circular-4");
    let out = d.path().join("run");
    let o = isotrack(&[
        "run",
        &scenario,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "sim.duration_s=120.0",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let o = isotrack(&["plot", out.to_str().unwrap(), "--format", "svg"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let team = std::fs::read_to_string(out.join("team.svg")).unwrap();
    let dashes: Vec<Vec<(f64, f64)>> = common::polylines(&team, "#000000", "2")
        .into_iter()
        .filter(|p| p.len() == 2 && p[0].1 == p[1].1 && p[0].0 != p[1].0)
        .collect();
    let twice = dashes
        .iter()
        .filter(|p| dashes.iter().filter(|q| q == p).count() == 2)
        .count();
    assert!(
        twice >= 20,
        "{twice} of {} dashes drawn twice",
        dashes.len()
    );
}

/// mem45 (att43-17): `plot` and `report` of a team's run take memory growing with the rows and
/// the vehicles, not with their square. A team of 2000 Dubins robots listed one by one in
/// `team.starts` (team-circular-4's circle, evenly spread, 0.5 s: 6 rows each) is drawn and
/// paged under an address-space limit of 1 GB (`ulimit -v`); each of the 2000 vehicles once
/// held its own copy of the scenario and its recorded summary (the 2000 starts twice), about
/// 3.3 GB resident for `plot` and 7 GB for `report`, whose page, 350 MB, listed the starts in
/// each vehicle's summary. The legends name the first 9 vehicles and "and 1991 more".
#[test]
fn a_large_teams_figures_and_page_fit_a_memory_limit() {
    let n = 2000;
    let r = 10.0 * LN_2;
    let starts: Vec<String> = (0..n)
        .map(|i| {
            let th = -2.0 * PI * i as f64 / n as f64;
            format!(
                "{{ x_m = {:?}, y_m = {:?}, heading_rad = {:?} }}",
                r * th.cos(),
                r * th.sin(),
                th - 0.5 * PI
            )
        })
        .collect();
    let team = std::fs::read_to_string(TEAM).unwrap();
    let text: Vec<String> = team
        .lines()
        .filter(|l| !l.starts_with("count = ") && !l.starts_with("spread = "))
        .map(|l| match l {
            "duration_s = 300.0" => "duration_s = 0.5".to_string(),
            "[team]" => format!("[team]\nstarts = [\n{}\n]", starts.join(",\n")),
            _ => l.to_string(),
        })
        .collect();
    let d = tempfile::tempdir().unwrap();
    let scenario = common::write(d.path(), "big-team.toml", &(text.join("\n") + "\n"));
    let out = d.path().join("run");
    let o = isotrack(&["run", &scenario, "--out", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let limited = |args: &[&str]| {
        std::process::Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 1000000 && exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_isotrack"))
            .args(args)
            .output()
            .unwrap()
    };
    let figs = d.path().join("figs");
    let o = limited(&[
        "plot",
        out.to_str().unwrap(),
        "--format",
        "svg",
        "--out",
        figs.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for fig in ["trajectory.svg", "timeseries.svg"] {
        let svg = std::fs::read_to_string(figs.join(fig)).unwrap();
        let texts: Vec<String> = common::svg_texts(&svg).into_iter().map(|t| t.3).collect();
        let has = |s: &str| texts.iter().any(|t| t == s);
        assert!(has("vehicle 0") && has("vehicle 8"), "{fig}");
        assert!(!has("vehicle 9") && !has("vehicle 1999"), "{fig}");
        assert!(has("and 1991 more"), "{fig}");
    }
    let page = d.path().join("r.html");
    let o = limited(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    // The recorded scenario (its 2000 starts) once, in vehicle 0's summary.
    let html = std::fs::read_to_string(&page).unwrap();
    assert_eq!(
        html.matches("\"heading_rad\":").count(),
        n + 1,
        "the starts and [initial]"
    );
    let names: Vec<String> = (0..9).map(|i| format!("vehicle {i}")).collect();
    assert!(html.contains(&format!(
        "<h1>isotrack report: {}, and 1991 more</h1>",
        names.join(", ")
    )));
}
