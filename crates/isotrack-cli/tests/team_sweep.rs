//! Issue 32: `isotrack sweep` over team keys of scenarios/team-circular-4.toml: `results.csv`
//! gains the team columns (last, for a base with `[team]` only), with numbers from the
//! geometry: the ideal revisit time `L/(N v0)` and, for the `none` law (every robot at `v0` on
//! a field symmetric under rotation), the deployed cluster's gap CV.
mod common;
use common::{assert_fails, isotrack, write};
use std::f64::consts::{LN_2, PI};

const TEAM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/team-circular-4.toml"
);

const TEAM_COLUMNS: [&str; 7] = [
    "gap_cv",
    "time_to_even_s",
    "revisit_time_max_s",
    "revisit_time_mean_s",
    "revisit_time_ideal_s",
    "min_separation_m",
    "order_preserved",
];

/// The gap CV of robots `0.3 rad` apart on a circle (`n` of them): gaps `0.3` (`n - 1` times)
/// and `2 pi - 0.3 (n - 1)`, population standard deviation over the mean `2 pi/n`.
fn cluster_cv(n: usize) -> f64 {
    let mut gaps = vec![0.3; n - 1];
    gaps.push(2.0 * PI - 0.3 * (n - 1) as f64);
    let mean = 2.0 * PI / n as f64;
    (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n as f64).sqrt() / mean
}

fn read_csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(str::to_string).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(str::to_string).collect())
        .collect();
    (header, rows)
}

#[test]
fn team_keys_sweep_with_team_columns() {
    let d = tempfile::tempdir().unwrap();
    let sweep = write(
        d.path(),
        "team.toml",
        &format!(
            "scenario = {TEAM:?}\n[base]\nsim.duration_s = 120.0\n[grid]\nteam.count = [3, 4]\nteam.spacing = [\"none\", \"range_balance\"]\nteam.k_v = [0.1]\nteam.ranging.noise_std_m = [0.0]\n"
        ),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let (header, rows) = read_csv(&out.join("results.csv"));
    assert_eq!(header[header.len() - 7..], TEAM_COLUMNS);
    assert_eq!(rows.len(), 4);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let f = |r: &Vec<String>, n: &str| r[col(n)].parse::<f64>().unwrap();
    let l = 2.0 * PI * 10.0 * LN_2;
    for r in &rows {
        assert_eq!(r[col("outcome")], "completed", "{r:?}");
        let n: usize = r[col("team.count")].parse().unwrap();
        // L/(N v0) with v0 = 0.5 m/s.
        let ideal = l / (n as f64 * 0.5);
        assert!(
            (f(r, "revisit_time_ideal_s") - ideal).abs() < 1e-9 * ideal,
            "{r:?}"
        );
        let cv = f(r, "gap_cv");
        if r[col("team.spacing")] == "none" {
            // Spacing stays as deployed: the cluster's CV.
            let want = cluster_cv(n);
            assert!((cv - want).abs() < 0.01 * want, "n {n}: {cv} vs {want}");
            assert_eq!(r[col("order_preserved")], "true");
        } else {
            assert!(cv < 0.5 * cluster_cv(n), "n {n}: {cv}");
        }
        assert!(f(r, "min_separation_m") > 0.0);
    }
    // --resume reads the team rows back (each checked) and runs nothing new.
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("(0 new)"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // A damaged team cell is refused on --resume.
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let bad = text.replacen(",true\n", ",maybe\n", 1);
    assert_ne!(bad, text);
    std::fs::write(out.join("results.csv"), bad).unwrap();
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(!o.status.success());
    assert!(
        common::stderr(&o).contains("order_preserved"),
        "{}",
        common::stderr(&o)
    );
}

/// A single-vehicle base keeps its columns; a team key swept onto it is an invalid run naming
/// `[team]`, not a row under the wrong header.
#[test]
fn team_keys_on_a_single_vehicle_base_are_invalid_runs() {
    let d = tempfile::tempdir().unwrap();
    let one = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig2b-circular.toml"
    );
    let sweep = write(
        d.path(),
        "one.toml",
        &format!("scenario = {one:?}\n[base]\nsim.duration_s = 10.0\n[grid]\nteam.count = [2]\n"),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 65, &["invalid"]);
    let (header, rows) = read_csv(&out.join("results.csv"));
    assert!(!header.iter().any(|h| h == "gap_cv"), "{header:?}");
    assert_eq!(
        rows[0][header.iter().position(|h| h == "outcome").unwrap()],
        "invalid_scenario"
    );
    assert!(rows[0].last().is_some());
    let detail = &rows[0][header.iter().position(|h| h == "outcome_detail").unwrap()];
    assert!(detail.contains("team"), "{detail}");
}

/// Replaces cell `col` of data row `row` (0-based) of CSV `text` with `value`.
fn with_cell(text: &str, row: usize, col: &str, value: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let header: Vec<String> = lines[0].split(',').map(str::to_string).collect();
    let i = header.iter().position(|h| h == col).unwrap();
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(lines[row + 1].as_bytes());
    let mut cells: Vec<String> = r
        .records()
        .next()
        .unwrap()
        .unwrap()
        .iter()
        .map(str::to_string)
        .collect();
    cells[i] = value.to_string();
    let mut w = csv::WriterBuilder::new().from_writer(vec![]);
    w.write_record(&cells).unwrap();
    lines[row + 1] = String::from_utf8(w.into_inner().unwrap())
        .unwrap()
        .trim_end()
        .to_string();
    lines.join("\n") + "\n"
}

/// att30b item 9: a team row's cells bounded by its run (a 30 s run of robots 0.5 m/s, at most
/// 1 m/s under range_balance, that start on a circle of radius 10 ln 2 m): times within 30 s,
/// the separation within the starts' spread plus twice the top speed over the run, and the ideal
/// revisit time exactly `L/(N v0)`. Refused by `--resume` and by `merge`, naming the column.
#[test]
fn team_cells_are_bounded_by_their_run() {
    let d = tempfile::tempdir().unwrap();
    let sweep = write(
        d.path(),
        "team.toml",
        &format!("scenario = {TEAM:?}\n[base]\nsim.duration_s = 30.0\n[grid]\nsensor.noise_std = [0.0]\n"),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    // 2 pi 10 ln 2 / (4 x 0.5): the ideal as written, and one ulp off it.
    let ideal = 2.0 * PI * 10.0 * LN_2 / (4.0 * 0.5);
    let (header, rows) = read_csv(&out.join("results.csv"));
    let written: f64 = rows[0][header
        .iter()
        .position(|h| h == "revisit_time_ideal_s")
        .unwrap()]
    .parse()
    .unwrap();
    assert!((written - ideal).abs() < 1e-12 * ideal);
    let ulp_off = f64::from_bits(written.to_bits() + 1).to_string();
    for (col, value) in [
        ("time_to_even_s", "31.0"),
        ("revisit_time_max_s", "1e300"),
        ("revisit_time_mean_s", "30.5"),
        ("min_separation_m", "1e300"),
        ("revisit_time_ideal_s", "5.0"),
        ("revisit_time_ideal_s", ulp_off.as_str()),
    ] {
        let bad = with_cell(&text, 0, col, value);
        let o_dir = d.path().join(format!("o-{col}-{value}"));
        std::fs::create_dir_all(&o_dir).unwrap();
        for f in ["sweep.json", "sweep.toml", "base_scenario.toml"] {
            std::fs::copy(out.join(f), o_dir.join(f)).unwrap();
        }
        std::fs::write(o_dir.join("results.csv"), &bad).unwrap();
        let o = isotrack(&[
            "sweep",
            &sweep,
            "--out",
            o_dir.to_str().unwrap(),
            "--resume",
        ]);
        assert_fails(&o, 65, &["results.csv:2", col]);
        let m = isotrack(&[
            "merge",
            o_dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("m-{col}-{value}")).to_str().unwrap(),
        ]);
        assert_fails(&m, 65, &["results.csv:2", col]);
    }
}

/// Issue 30: a team sweep's `invalid_scenario` row whose reason starts `[team]:` (the team
/// engine's refusal, found by flying it) is checked on `--resume` and `merge` as any other
/// invalid row: the reason recomputed from the row's scenario and compared. Here the field
/// drifts, so it has no fixed circle, and `arc_reference` (which needs the true isoline) is
/// refused by the engine: that row is kept as the sweep wrote it; the same row with another
/// `[team]:` reason, or run 0's (`range_balance`, which flies) relabelled with it, is refused
/// naming file, line and column (both were kept before).
#[test]
fn team_engine_refusals_are_recomputed_on_resume_and_merge() {
    let d = tempfile::tempdir().unwrap();
    let sweep = write(
        d.path(),
        "team.toml",
        &format!(
            "scenario = {TEAM:?}\n[base]\nsim.duration_s = 5.0\nfield.drift_mps = [0.001, 0.0]\n[grid]\nteam.spacing = [\"range_balance\", \"arc_reference\"]\n"
        ),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 65, &["invalid"]);
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let (header, rows) = read_csv(&out.join("results.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    assert_eq!(rows[0][col("outcome")], "completed", "{text}");
    assert_eq!(rows[1][col("outcome")], "invalid_scenario", "{text}");
    let reason = &rows[1][col("outcome_detail")];
    assert!(
        reason.starts_with("[team]: ") && reason.contains("arc_reference"),
        "{reason}"
    );
    let resume = |name: &str, results: &str| {
        let o_dir = d.path().join(name);
        std::fs::create_dir_all(&o_dir).unwrap();
        for f in ["sweep.json", "sweep.toml", "base_scenario.toml"] {
            std::fs::copy(out.join(f), o_dir.join(f)).unwrap();
        }
        std::fs::write(o_dir.join("results.csv"), results).unwrap();
        let o = isotrack(&[
            "sweep",
            &sweep,
            "--out",
            o_dir.to_str().unwrap(),
            "--resume",
        ]);
        let m = isotrack(&[
            "merge",
            o_dir.to_str().unwrap(),
            "--out",
            d.path().join(format!("m-{name}")).to_str().unwrap(),
        ]);
        (o, m)
    };
    // As written: kept (the reason recomputed is the same); the resume reruns nothing and
    // still reports the invalid run.
    let (o, m) = resume("clean", &text);
    for o in [&o, &m] {
        let e = common::stderr(o);
        assert!(matches!(o.status.code(), Some(0 | 65)), "{e}");
        assert!(
            !e.contains("results.csv:") && !e.contains("panicked"),
            "{e}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(d.path().join("clean/results.csv")).unwrap(),
        text
    );
    // Another engine reason for run 1.
    let other = "[team]: a team needs at least one vehicle";
    let (o, m) = resume("reason", &with_cell(&text, 1, "outcome_detail", other));
    let column = format!("column {} (outcome_detail)", col("outcome_detail") + 1);
    for o in [&o, &m] {
        assert_fails(
            o,
            65,
            &[
                "results.csv:3",
                &column,
                "not the reason the team engine gives run 1",
            ],
        );
    }
    // Run 0, which flies, relabelled with run 1's refusal (run 1's line under run 0's id and
    // values, run 0's own line removed).
    let mut relabelled = with_cell(&text, 1, "run_id", "0");
    for c in ["team.spacing", "sim.seed"] {
        relabelled = with_cell(&relabelled, 1, c, &rows[0][col(c)]);
    }
    let lines: Vec<&str> = relabelled.lines().collect();
    let only = format!("{}\n{}\n", lines[0], lines[2]);
    let (o, m) = resume("relabelled", &only);
    let column = format!("column {} (outcome)", col("outcome") + 1);
    for o in [&o, &m] {
        assert_fails(
            o,
            65,
            &["results.csv:2", &column, "whose team the engine flies"],
        );
    }
}

/// att32d-3 and -5: a team row is vehicle 0's, so its bounds (`samples`, `path_length_m`)
/// come from vehicle 0's own resolved settings, its `team.vehicles` override included. Under
/// `none` on the circular field every robot flies its `v0_i` for the whole run, so vehicle
/// 0's row has `rate * T + 1` samples (one at every multiple of `1 / rate` in `[0, T]`) and a
/// path of `v0_0 T`; with 10 Hz against the scenario's 100 Hz and 0.8 m/s past the team's
/// top speed `team.v_max_mps = 0.75` the sweep once refused its own rows (65, "samples = 101
/// is below the 1001 ...", "path_length_m ... exceeds 0.75 m/s ..."), and `--resume` too. The override in the base (a plan that varies another key) and varied by the
/// grid itself (`team.vehicles`), each finished and then resumed.
#[test]
fn vehicle_0_overrides_bound_its_own_rows() {
    let d = tempfile::tempdir().unwrap();
    let t = 10.0;
    for (name, base, grid, want) in [
        (
            "base",
            "team.vehicles = [{index=0, sensor_rate_hz=10.0, speed_mps=0.8, v_max_mps=0.9}]\nteam.v_max_mps = 0.75\n",
            "team.k_v = [0.1, 0.2]\n",
            [(10.0, 0.8), (10.0, 0.8)],
        ),
        (
            "grid",
            "team.v_max_mps = 0.75\n",
            "team.vehicles = [[{index=0, sensor_rate_hz=10.0, speed_mps=0.8, v_max_mps=0.9}], [{index=0, sensor_rate_hz=20.0, speed_mps=0.7, v_max_mps=0.9}]]\n",
            [(10.0, 0.8), (20.0, 0.7)],
        ),
    ] {
        let sweep = write(
            d.path(),
            &format!("{name}.toml"),
            &format!(
                "scenario = {TEAM:?}\n[base]\nsim.duration_s = {t:?}\nteam.spacing = \"none\"\n{base}[grid]\n{grid}"
            ),
        );
        let out = d.path().join(name);
        let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{name}: {}", common::stderr(&o));
        let (header, rows) = read_csv(&out.join("results.csv"));
        let col = |n: &str| header.iter().position(|h| h == n).unwrap();
        assert_eq!(rows.len(), 2);
        for (r, (rate, v0)) in rows.iter().zip(want) {
            assert_eq!(r[col("outcome")], "completed", "{r:?}");
            let samples: f64 = r[col("samples")].parse().unwrap();
            assert_eq!(samples, rate * t + 1.0, "{name}: {r:?}");
            let path: f64 = r[col("path_length_m")].parse().unwrap();
            // Each step's chord of a turn at rate w falls short of `v dt` by `(w dt)^2/24`
            // of it (about 3e-8 at the circle's `w = v/R`): within 1e-5.
            assert!(
                (path - v0 * t).abs() < 1e-5 * v0 * t,
                "{name}: {path} vs {}",
                v0 * t
            );
        }
        let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap(), "--resume"]);
        assert!(o.status.success(), "{name} --resume: {}", common::stderr(&o));
    }
}

/// att32d-6: a team row's `warnings` cell carries `check`'s team failure, as `isotrack run`
/// warns it. Four robots ranging at 10 Hz without delay on the circle: the spacing loop is
/// stable up to `k_v* = 2/(0.1 cos(pi/4) 4) = 7.07 1/s`, so the row at `k_v = 10` warns and
/// the row at `k_v = 0.1` does not; `--resume` recomputes and accepts both cells.
#[test]
fn a_team_row_warns_when_the_team_check_fails() {
    let d = tempfile::tempdir().unwrap();
    let sweep = write(
        d.path(),
        "kv.toml",
        &format!(
            "scenario = {TEAM:?}\n[base]\nsim.duration_s = 10.0\n[grid]\nteam.k_v = [0.1, 10.0]\n"
        ),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let (header, rows) = read_csv(&out.join("results.csv"));
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    assert_eq!(rows[0][col("warnings")], "", "{:?}", rows[0]);
    assert!(
        rows[1][col("warnings")].starts_with(
            "the team check fails: the spacing loop is unstable: team.k_v = 10 is past"
        ),
        "{:?}",
        rows[1]
    );
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
}
