//! Issue 31, "Sweeps keep the user's own keys apart from the materialised defaults": a sweep's
//! run is exactly `isotrack run` of the user's scenario + `[base]` + the row's assignments,
//! resolved once, so a default that follows another key follows the row. README's re-run recipe
//! (`isotrack run DIR/base_scenario.toml --set KEY=VALUE ...`) gives each row, every metric, and
//! `--resume` and `merge` keep such rows.
mod common;
use common::{bundled, csv_rows, isotrack, stderr, sweep_file, swept, write};
use std::collections::HashMap;
use std::path::Path;

/// 20 s of the built-in default with `sensor.rate_hz` unset: its default is one sample a step,
/// `1/sim.dt_s`.
const SCENARIO: &str = "[sim]\nduration_s = 20.0\n";

/// The step swept over 0.01 and 0.02 s, a `[base]` key besides.
const SWEEP: &str =
    "scenario = \"s.toml\"\n[base]\ncontroller.kp = 8.0\n[grid]\nsim.dt_s = [0.01, 0.02]\n";

/// The numeric result columns a row shares with `summary.json`.
const METRICS: [&str; 12] = [
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "steady_state_mean_error",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
    "path_length_m",
    "control_effort",
    "chattering_radps2",
    "sign_changes_per_s",
    "t_end_s",
    "samples",
];

/// The rows of `DIR/results.csv`, each as column -> cell.
fn rows(dir: &Path) -> Vec<HashMap<String, String>> {
    csv_rows(&dir.join("results.csv"))
}

/// Runs the sweep into `out` with `extra` arguments; panics on failure.
fn sweep(sw: &str, out: &Path, extra: &[&str]) {
    swept(sw, out, extra);
}

/// `isotrack merge DIRS --out OUT`, which must succeed; the merged `results.csv`'s bytes.
fn merged(dirs: &[&Path], out: &Path) -> Vec<u8> {
    let mut args = vec!["merge"];
    args.extend(dirs.iter().map(|d| d.to_str().unwrap()));
    args.extend(["--out", out.to_str().unwrap()]);
    let o = isotrack(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read(out.join("results.csv")).unwrap()
}

#[test]
fn a_swept_step_is_followed_by_the_sensor_rate_as_run_follows_it() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "s.toml", SCENARIO);
    let sw = write(d.path(), "sweep.toml", SWEEP);
    let whole = d.path().join("whole");
    sweep(&sw, &whole, &[]);

    // base_scenario.toml holds the user's keys: the file's and [base]'s, no materialised
    // sensor rate.
    let base: toml::Table =
        toml::from_str(&std::fs::read_to_string(whole.join("base_scenario.toml")).unwrap())
            .unwrap();
    assert_eq!(base["controller"]["kp"].as_float(), Some(8.0));
    assert_eq!(base["sim"]["duration_s"].as_float(), Some(20.0));
    assert!(
        base.get("sensor").and_then(|s| s.get("rate_hz")).is_none(),
        "{base:?}"
    );

    let got = rows(&whole);
    assert_eq!(got.len(), 2);
    for (row, (dt, rate_hz)) in got.iter().zip([("0.01", 100.0), ("0.02", 50.0)]) {
        assert_eq!(row["sim.dt_s"], dt, "{row:?}");
        assert_eq!(row["outcome"], "completed", "{row:?}");
        // Samples at t = 0, 1/rate, ..., 20 s: 20 * rate + 1.
        assert_eq!(
            row["samples"],
            format!("{}", 20.0 * rate_hz + 1.0),
            "{row:?}"
        );

        // README's recipe, run apart: the same run, every metric bit for bit.
        let r = d.path().join(format!("rerun-{dt}"));
        let base_path = whole.join("base_scenario.toml");
        let dt_set = format!("sim.dt_s={}", row["sim.dt_s"]);
        let seed_set = format!("sim.seed={}", row["sim.seed"]);
        let o = isotrack(&[
            "run",
            base_path.to_str().unwrap(),
            "--set",
            &dt_set,
            "--set",
            &seed_set,
            "--out",
            r.to_str().unwrap(),
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(r.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(
            summary["scenario"]["sensor"]["rate_hz"].as_f64(),
            Some(rate_hz)
        );
        assert_eq!(summary["outcome"].as_str(), Some(row["outcome"].as_str()));
        for m in METRICS {
            let cell = &row[m];
            match summary[m].as_f64() {
                None => assert!(cell.is_empty(), "{m}: {cell} vs {}", summary[m]),
                Some(v) => assert_eq!(
                    cell.parse::<f64>().unwrap().to_bits(),
                    v.to_bits(),
                    "{m}: row {cell}, run {v}"
                ),
            }
        }
    }

    // --resume keeps both rows (each checked against its own run's 100 or 50 Hz): a directory
    // cut to the second row alone gets the first again, byte for byte.
    let bytes = std::fs::read(whole.join("results.csv")).unwrap();
    let text = String::from_utf8(bytes.clone()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let cut = d.path().join("cut");
    std::fs::create_dir(&cut).unwrap();
    for f in ["sweep.json", "sweep.toml", "base_scenario.toml"] {
        std::fs::copy(whole.join(f), cut.join(f)).unwrap();
    }
    std::fs::write(
        cut.join("results.csv"),
        format!("{}\n{}\n", lines[0], lines[2]),
    )
    .unwrap();
    sweep(&sw, &cut, &["--resume"]);
    assert_eq!(std::fs::read(cut.join("results.csv")).unwrap(), bytes);

    // Two shards merged: the same rows.
    let (s1, s2, merged_dir) = (
        d.path().join("s1"),
        d.path().join("s2"),
        d.path().join("merged"),
    );
    sweep(&sw, &s1, &["--shard", "1/2"]);
    sweep(&sw, &s2, &["--shard", "2/2"]);
    assert_eq!(merged(&[&s1, &s2], &merged_dir), bytes);
}

/// Paper Fig. 3's UAV swept over its airspeed, 20 s runs.
const AIRSPEED: &str =
    "[base]\nsim.duration_s = 20.0\n[grid]\nvehicle.airspeed_mps = [20.0, 40.0]\ncontroller.kp = [50.0]\n";

/// att30d-5: a fixed-wing sweep over `vehicle.airspeed_mps` exited 65 on its own first row:
/// the row check bounded `control_effort` by the turn-rate limit `g tan(40 deg) / V` of the
/// base's 30 m/s (0.274 rad/s, 1.50 rad^2/s over 20 s), not of the run's own 20 m/s (0.411
/// rad/s, 3.38 rad^2/s). Each row is checked against its own run: the sweep completes, resumes
/// (nothing to do, the same bytes) and merges.
#[test]
fn a_sweep_over_the_airspeed_checks_each_row_against_its_own_turn_limit() {
    let d = tempfile::tempdir().unwrap();
    let sw = sweep_file(d.path(), "f.toml", &bundled("paper-fig3-uav"), AIRSPEED);
    let out = d.path().join("out");
    sweep(&sw, &out, &[]);
    let got = rows(&out);
    for (row, v) in got.iter().zip([20.0f64, 40.0]) {
        let limit = 9.80665 * 40f64.to_radians().tan() / v;
        let effort: f64 = row["control_effort"].parse().unwrap();
        assert!(effort <= limit * limit * 20.0 * (1.0 + 1e-9), "{row:?}");
    }
    let bytes = std::fs::read(out.join("results.csv")).unwrap();
    sweep(&sw, &out, &["--resume"]);
    assert_eq!(std::fs::read(out.join("results.csv")).unwrap(), bytes);
    assert_eq!(merged(&[&out], &d.path().join("merged")), bytes);
}

/// Runs `isotrack` with `args` in directory `dir`.
fn isotrack_in(dir: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// A sweep of [`SCENARIO`] whose run 1 is invalid (`controller.kp = -1`).
const ONE_INVALID: &str = "scenario = \"s.toml\"\n[grid]\ncontroller.kp = [10.0, -1.0]\n";

/// att30d-3: an `invalid_scenario` row's reason held the sweep file's path as typed, so a
/// `--resume` naming it another way (`./s.toml`, an absolute path from another directory: a
/// requeued job) refused the sweep's own rows, and shards started with two spellings merged
/// into mixed reasons. The reason names the run only, on one line with single spaces: resumed
/// from another directory by an absolute path the sweep keeps its rows (exit 65 for the one
/// invalid run, as the first time), and shards named two ways merge to the same bytes.
#[test]
fn an_invalid_rows_reason_does_not_depend_on_how_the_sweep_is_named() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "s.toml", SCENARIO);
    let sw = write(d.path(), "sweep.toml", ONE_INVALID);
    let o = isotrack_in(d.path(), &["sweep", "sweep.toml", "--out", "whole"]);
    assert_eq!(o.status.code(), Some(65), "{}", stderr(&o));
    let whole = d.path().join("whole");
    let got = rows(&whole);
    assert_eq!(got[1]["outcome"], "invalid_scenario");
    let detail = &got[1]["outcome_detail"];
    assert!(
        detail.starts_with("invalid scenario: sweep run 1, [grid] controller.kp=-1.0: "),
        "{detail}"
    );
    assert!(
        !detail.contains("  ") && !detail.contains("sweep.toml"),
        "{detail}"
    );
    let bytes = std::fs::read(whole.join("results.csv")).unwrap();
    // Resumed from another directory, the sweep named by its absolute path.
    let elsewhere = d.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let whole_s = whole.display().to_string();
    let o = isotrack_in(&elsewhere, &["sweep", &sw, "--out", &whole_s, "--resume"]);
    assert_eq!(o.status.code(), Some(65), "{}", stderr(&o));
    assert!(!stderr(&o).contains("damaged row"), "{}", stderr(&o));
    assert_eq!(std::fs::read(whole.join("results.csv")).unwrap(), bytes);
    // Two shards, the sweep named two ways, merged: the same rows.
    let o = isotrack_in(
        d.path(),
        &["sweep", "./sweep.toml", "--out", "s1", "--shard", "1/2"],
    );
    assert_ne!(o.status.code(), Some(101), "{}", stderr(&o));
    let s2 = d.path().join("s2").display().to_string();
    let o = isotrack_in(&elsewhere, &["sweep", &sw, "--out", &s2, "--shard", "2/2"]);
    assert_eq!(o.status.code(), Some(65), "{}", stderr(&o));
    let o = isotrack_in(d.path(), &["merge", "s1", "s2", "--out", "m"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(d.path().join("m/results.csv")).unwrap(),
        bytes
    );
}

/// An ESRI ASCII grid of `20 scale exp(-0.1 r)` around the origin, 81 x 81 nodes 0.5 m apart.
fn radial_asc(scale: f64) -> String {
    let n = 81;
    let mut t = format!("ncols {n}\nnrows {n}\nxllcorner -20.25\nyllcorner -20.25\ncellsize 0.5\n");
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                let (x, y) = (0.5 * (i as f64 - 40.0), 0.5 * (j as f64 - 40.0));
                format!("{}", 20.0 * scale * (-0.1 * (x * x + y * y).sqrt()).exp())
            })
            .collect();
        t.push_str(&row.join(" "));
        t.push('\n');
    }
    t
}

/// att30d-10: the sweep's digest covers its data file's path, not its content, so a grid file
/// rewritten between two shards (or before a `--resume`) was never noticed: one results.csv
/// over two fields. sweep.json records each data file's SHA-256; a changed file is refused
/// (65, naming the file) by `--resume` and by `merge`.
#[test]
fn a_data_file_changed_between_parts_of_a_sweep_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let asc = write(d.path(), "f.asc", &radial_asc(1.0));
    write(
        d.path(),
        "s.toml",
        "[field]\nkind = \"grid\"\npath = \"f.asc\"\n[initial]\nx_m = 5.0\ny_m = 0.0\n[sim]\nduration_s = 20.0\n",
    );
    let sw = write(
        d.path(),
        "sweep.toml",
        "scenario = \"s.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let (s1, s2) = (d.path().join("s1"), d.path().join("s2"));
    sweep(&sw, &s1, &["--shard", "1/2"]);
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(s1.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(manifest["data_files"].as_object().map(|o| o.len()), Some(1));
    std::fs::write(&asc, radial_asc(1.05)).unwrap();
    sweep(&sw, &s2, &["--shard", "2/2"]);
    let name = std::fs::canonicalize(&asc).unwrap().display().to_string();
    let m = d.path().join("m").display().to_string();
    let o = isotrack(&[
        "merge",
        s1.to_str().unwrap(),
        s2.to_str().unwrap(),
        "--out",
        &m,
    ]);
    common::assert_fails(&o, 65, &[&name, "data file"]);
    let o = isotrack(&[
        "sweep",
        &sw,
        "--out",
        s1.to_str().unwrap(),
        "--shard",
        "1/2",
        "--resume",
    ]);
    common::assert_fails(&o, 65, &[&name, "data file"]);
    // The file as it was: both go through.
    std::fs::write(&asc, radial_asc(1.0)).unwrap();
    sweep(&sw, &s1, &["--shard", "1/2", "--resume"]);
}

/// `20 scale exp(-0.1 r)` around the origin as a CSV grid (no header, row 0 south), 81 x 81
/// nodes: with `field.spacing_m = [0.5, 0.5]` and `field.origin_m = [-20, -20]` the grid of
/// [`radial_asc`].
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

/// The SHA-256 of `bytes` in hex, computed here (sha2), not by isotrack.
fn sha256_hex(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// ver30b-3: a sweep whose `[grid]` varies `field.path` over two CSV files recorded in
/// sweep.json only the base scenario's file, so a rewritten second file was never noticed:
/// `--resume` and `merge` kept rows computed on the old file without a word. sweep.json
/// records every file a run reads; `--resume` and `merge` (of shards run before the edit, or
/// on both sides of it) refuse the edited one (65, naming it); the files as they were go
/// through.
#[test]
fn every_field_file_a_grid_of_runs_reads_is_checked() {
    let d = tempfile::tempdir().unwrap();
    let a = write(d.path(), "a.csv", &radial_csv(1.0));
    let b = write(d.path(), "b.csv", &radial_csv(1.05));
    write(
        d.path(),
        "s.toml",
        "[field]\nkind = \"grid\"\npath = \"a.csv\"\nspacing_m = [0.5, 0.5]\norigin_m = [-20.0, -20.0]\n[initial]\nx_m = 5.0\ny_m = 0.0\n[sim]\nduration_s = 20.0\n",
    );
    let sw = write(
        d.path(),
        "sweep.toml",
        "scenario = \"s.toml\"\n[grid]\nfield.path = [\"a.csv\", \"b.csv\"]\n",
    );
    let (whole, s1, s2) = (
        d.path().join("whole"),
        d.path().join("s1"),
        d.path().join("s2"),
    );
    sweep(&sw, &whole, &[]);
    sweep(&sw, &s1, &["--shard", "1/2"]);
    sweep(&sw, &s2, &["--shard", "2/2"]);
    let name = |p: &str| std::fs::canonicalize(p).unwrap().display().to_string();
    let (a_name, b_name) = (name(&a), name(&b));
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("sweep.json")).unwrap()).unwrap();
    let expected = serde_json::json!({
        a_name.clone(): sha256_hex(radial_csv(1.0).as_bytes()),
        b_name.clone(): sha256_hex(radial_csv(1.05).as_bytes()),
    });
    assert_eq!(manifest["data_files"], expected, "{manifest}");
    // The two runs read different files: their rows differ.
    let got = rows(&whole);
    assert_eq!(got.len(), 2);
    assert!(METRICS.iter().any(|c| got[0][*c] != got[1][*c]), "{got:?}");

    // b.csv rewritten: every way of keeping the old rows is refused, naming it.
    std::fs::write(&b, radial_csv(1.1)).unwrap();
    let resume = |dir: &Path, shard: Option<&str>| {
        let mut args = vec!["sweep", &sw, "--out", dir.to_str().unwrap(), "--resume"];
        if let Some(s) = shard {
            args.extend(["--shard", s]);
        }
        isotrack(&args)
    };
    common::assert_fails(&resume(&whole, None), 65, &[&b_name, "data file"]);
    common::assert_fails(&resume(&s1, Some("1/2")), 65, &[&b_name, "data file"]);
    let m = d.path().join("m");
    let merge = |dirs: &[&Path]| {
        let mut args = vec!["merge"];
        args.extend(dirs.iter().map(|d| d.to_str().unwrap()));
        args.extend(["--out", m.to_str().unwrap(), "--force"]);
        isotrack(&args)
    };
    common::assert_fails(&merge(&[&s1, &s2]), 65, &[&b_name, "data file"]);
    // A shard run after the edit beside one run before it.
    let s2_new = d.path().join("s2_new");
    sweep(&sw, &s2_new, &["--shard", "2/2"]);
    common::assert_fails(&merge(&[&s1, &s2_new]), 65, &[&b_name, "data file"]);
    assert!(!m.join("results.csv").exists());

    // The files as they were: resume and merge go through.
    std::fs::write(&b, radial_csv(1.05)).unwrap();
    let o = resume(&whole, None);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = resume(&s1, Some("1/2"));
    assert!(o.status.success(), "{}", stderr(&o));
    let o = merge(&[&s1, &s2]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(m.join("results.csv")).unwrap(),
        std::fs::read(whole.join("results.csv")).unwrap()
    );
}

/// nu-15: a data file a sweep's runs read that does not exist is a missing input, refused
/// before any run with the README table's 66 naming it: in `[grid] field.path` (each of its
/// runs was `invalid_scenario` after every other run had run, exit 65) and in `[base]` (65).
#[test]
fn a_missing_data_file_of_a_sweep_is_refused_before_any_run() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "f.asc", &radial_asc(1.0));
    write(
        d.path(),
        "s.toml",
        "[field]\nkind = \"grid\"\npath = \"f.asc\"\n[initial]\nx_m = 5.0\ny_m = 0.0\n[sim]\nduration_s = 20.0\n",
    );
    let grid = write(
        d.path(),
        "grid.toml",
        "scenario = \"s.toml\"\n[grid]\nfield.path = [\"f.asc\", \"nowhere.asc\"]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let out = d.path().join("g");
    let o = isotrack(&["sweep", &grid, "--out", out.to_str().unwrap()]);
    common::assert_fails(&o, 66, &["nowhere.asc", "cannot be read"]);
    assert!(
        !out.join("results.csv").exists()
            || std::fs::read_to_string(out.join("results.csv"))
                .unwrap()
                .lines()
                .count()
                <= 1,
        "no run ran"
    );
    let base = write(
        d.path(),
        "base.toml",
        "scenario = \"s.toml\"\n[base]\nfield.path = \"nowhere.asc\"\n[grid]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let o = isotrack(&[
        "sweep",
        &base,
        "--out",
        d.path().join("b").to_str().unwrap(),
    ]);
    common::assert_fails(&o, 66, &["nowhere.asc", "[base]"]);
}

/// The scenario of the data-file tests below: a grid field read from `f.asc`, 20 s.
const GRID_SCENARIO: &str = "[field]\nkind = \"grid\"\npath = \"f.asc\"\n[initial]\nx_m = 5.0\ny_m = 0.0\n[sim]\nduration_s = 20.0\n";

/// Whether directory `out` holds no row of a run (no results.csv, or its header only).
fn no_run_in(out: &Path) -> bool {
    std::fs::read_to_string(out.join("results.csv")).map_or(true, |t| t.lines().count() <= 1)
}

/// att30n-2: a `[grid] field.path` value holding a line break (a legal file name) was written
/// as a quoted two-line cell, then the sweep's own final pass refused its own row as damaged
/// (exit 65 after every run) and `--resume` could never finish. It is refused before any run
/// (65), naming the key and the value escaped.
#[test]
fn a_grid_value_with_a_line_break_is_refused_before_any_run() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "f.asc", &radial_asc(1.0));
    write(d.path(), "new\nline.asc", &radial_asc(1.0));
    write(d.path(), "s.toml", GRID_SCENARIO);
    let sw = write(
        d.path(),
        "sweep.toml",
        "scenario = \"s.toml\"\n[grid]\nfield.path = [\"f.asc\", \"new\\nline.asc\"]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let out = d.path().join("o");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    common::assert_fails(
        &o,
        65,
        &["[grid] field.path value 2 \"new\\nline.asc\"", "line break"],
    );
    assert!(no_run_in(&out));
}

/// att30n-9 and att30n-13: a `[grid]` data file beyond its size limit (4 GiB, a sparse file
/// here) was hashed whole (28 s) before any run, then each of its runs was `invalid_scenario`
/// and the sweep exited 65 after running everything; an unreadable one was refused 66 without
/// the key or the value as written. Both are refused 66 before any run, at once (the size
/// from the metadata), naming `[grid] field.path value 2` as the sweep file writes it.
#[test]
fn a_grid_data_file_beyond_its_limit_or_missing_is_refused_at_once_by_its_key() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "f.asc", &radial_asc(1.0));
    write(d.path(), "s.toml", GRID_SCENARIO);
    let huge = d.path().join("huge.asc");
    std::fs::write(&huge, radial_asc(1.0)).unwrap();
    let len = (4u64 << 30) + 1;
    std::fs::OpenOptions::new()
        .write(true)
        .open(&huge)
        .unwrap()
        .set_len(len)
        .unwrap();
    let sw = write(
        d.path(),
        "sweep.toml",
        "scenario = \"s.toml\"\n[grid]\nfield.path = [\"f.asc\", \"huge.asc\"]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let out = d.path().join("o");
    let t0 = std::time::Instant::now();
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    let took = t0.elapsed();
    common::assert_fails(
        &o,
        66,
        &[
            "[grid] field.path value 2 \"huge.asc\"",
            &format!(
                "{len} bytes is more than the {} this reader accepts",
                4u64 << 30
            ),
        ],
    );
    assert!(no_run_in(&out));
    // Hashing 4 GiB takes many seconds; the metadata, milliseconds (a loaded machine: 5 s).
    assert!(took.as_secs_f64() < 5.0, "{took:?}");
    let sw = write(
        d.path(),
        "sweep2.toml",
        "scenario = \"s.toml\"\n[grid]\nfield.path = [\"f.asc\", \"nowhere.asc\"]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    common::assert_fails(
        &o,
        66,
        &[
            "[grid] field.path value 2 \"nowhere.asc\"",
            "nowhere.asc, which runs of the sweep read, cannot be read",
        ],
    );
    assert!(no_run_in(&out));
}

/// att30n-14: `merge` of shards whose data file is gone called a good row "damaged" and
/// advised deleting it ("remove the line ... and --resume"), which `--resume` then refused 66.
/// Both say the data file cannot be read (66, naming it), never "damaged"; the file put back,
/// the merge goes through.
#[test]
fn a_sweep_whose_data_file_is_gone_says_so() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "f.asc", &radial_asc(1.0));
    let b = write(d.path(), "b.asc", &radial_asc(1.05));
    write(d.path(), "s.toml", GRID_SCENARIO);
    let sw = write(
        d.path(),
        "sweep.toml",
        "scenario = \"s.toml\"\n[grid]\nfield.path = [\"f.asc\", \"b.asc\"]\n",
    );
    let (s1, s2, m) = (d.path().join("s1"), d.path().join("s2"), d.path().join("m"));
    sweep(&sw, &s1, &["--shard", "1/2"]);
    sweep(&sw, &s2, &["--shard", "2/2"]);
    let name = std::fs::canonicalize(&b).unwrap().display().to_string();
    let moved = d.path().join("b.moved");
    std::fs::rename(&b, &moved).unwrap();
    let merge = || {
        isotrack(&[
            "merge",
            s1.to_str().unwrap(),
            s2.to_str().unwrap(),
            "--out",
            m.to_str().unwrap(),
        ])
    };
    let o = merge();
    common::assert_fails(&o, 66, &[&name, "cannot be read now", "restore it"]);
    assert!(!stderr(&o).contains("damaged"), "{}", stderr(&o));
    let o = isotrack(&[
        "sweep",
        &sw,
        "--out",
        s2.to_str().unwrap(),
        "--shard",
        "2/2",
        "--resume",
    ]);
    common::assert_fails(&o, 66, &["b.asc", "cannot be read"]);
    assert!(!stderr(&o).contains("damaged"), "{}", stderr(&o));
    std::fs::rename(&moved, &b).unwrap();
    let o = merge();
    assert!(o.status.success(), "{}", stderr(&o));
}

/// att30n-1: past 4096 combinations of the `[grid]` values that choose the field's files the
/// sweep's data files are a superset, and a file no run reads (a path beside an analytic kind)
/// was refused 66 as one "which runs of the sweep read"; with 4096 values it ran. Whatever the
/// count, a file no run reads is not refused, and one a run reads still is.
#[test]
fn a_data_file_no_run_reads_is_not_refused_whatever_the_combinations() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "f.asc", &radial_asc(1.0));
    write(d.path(), "s.toml", GRID_SCENARIO);
    let names: Vec<String> = (0..=4096).map(|i| format!("\"none{i}.asc\"")).collect();
    let sweep_of = |file: &str, kind: &str| {
        write(
            d.path(),
            file,
            &format!(
                "scenario = \"s.toml\"\n[base]\nsim.duration_s = 0.5\n[grid]\nfield.kind = [\"{kind}\"]\nfield.path = [{}]\n",
                names.join(", ")
            ),
        )
    };
    let radial = sweep_of("radial.toml", "radial_exp");
    let out = d.path().join("r");
    let o = isotrack(&[
        "sweep",
        &radial,
        "--out",
        out.to_str().unwrap(),
        "--shard",
        "1/4097",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = rows(&out);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0]["outcome"], "completed", "{got:?}");
    let grid = sweep_of("grid.toml", "grid");
    let out = d.path().join("g");
    let o = isotrack(&[
        "sweep",
        &grid,
        "--out",
        out.to_str().unwrap(),
        "--shard",
        "1/4097",
    ]);
    common::assert_fails(
        &o,
        66,
        &[
            "[grid] field.path value 1 \"none0.asc\"",
            "which runs of the sweep read,",
        ],
    );
    assert!(no_run_in(&out));
}

/// att38-6: every string a TOML file can hold round-trips through `results.csv` and its resume
/// index. File names TOML escapes (`\u0301`: a macOS NFD `café`, a zero-width space, U+2028,
/// U+0085, a vertical tab) were written back as Rust's `\u{301}`, which no TOML reads, and the
/// sweep was refused with a TOML error blaming the user's quoting. Each is swept (every run
/// completed), its cell is the file's name exactly, and `--resume` keeps every row.
#[test]
fn grid_file_names_with_any_character_toml_holds_are_swept_and_resumed() {
    let d = tempfile::tempdir().unwrap();
    let names = [
        "f.asc",
        "cafe\u{301}.asc",
        "z\u{200b}y.asc",
        "x\u{2028}y.asc",
        "x\u{85}y.asc",
        "x\u{b}y.asc",
        "x\ty \"q\" \\.asc",
    ];
    for n in names {
        write(d.path(), n, &radial_asc(1.0));
    }
    write(d.path(), "s.toml", GRID_SCENARIO);
    // As a user's TOML file holds them: escapes for what TOML cannot hold as it is.
    let toml_list = "[\"f.asc\", \"cafe\\u0301.asc\", \"z\\u200by.asc\", \"x\\u2028y.asc\", \"x\\u0085y.asc\", \"x\\u000by.asc\", \"x\\ty \\\"q\\\" \\\\.asc\"]";
    let sw = write(
        d.path(),
        "sweep.toml",
        &format!("scenario = \"s.toml\"\n[grid]\nfield.path = {toml_list}\n"),
    );
    let out = d.path().join("o");
    let outs = out.to_str().unwrap();
    let o = isotrack(&["sweep", &sw, "--out", outs]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let rows = csv_rows(&out.join("results.csv"));
    assert_eq!(rows.len(), names.len());
    for (row, name) in rows.iter().zip(names) {
        assert_eq!(row["field.path"], name);
        assert_eq!(row["outcome"], "completed", "{name:?}: {row:?}");
    }
    let before = std::fs::read(out.join("results.csv")).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", outs, "--resume"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("results.csv")).unwrap(), before);
}

/// att38-6: a `[grid]` value every run refuses (a tab in `field.units` or `name`, a control
/// character) makes its run `invalid_scenario`, the reason quoting the value; the reason's tab
/// was written as it is, then the sweep's own final check refused its row as damaged (65
/// "damaged row"), and every `--resume` wrote it again and refused it again. The row is kept:
/// the value's cell holds the tab exactly, the reason shows it escaped, the sweep ends as one
/// with an invalid run (65 saying so) and `--resume` finds every run done.
#[test]
fn a_run_refusing_a_grid_value_with_a_tab_is_recorded_and_resumed() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "s.toml", SCENARIO);
    for key in ["field.units", "name"] {
        let sw = write(
            d.path(),
            "sweep.toml",
            &format!("scenario = \"s.toml\"\n[grid]\n{key} = [\"a\", \"tab\\there\"]\n"),
        );
        let out = d.path().join(format!("o_{key}"));
        let outs = out.to_str().unwrap();
        for extra in [&[][..], &["--resume"][..]] {
            let mut args = vec!["sweep", &sw, "--out", outs];
            args.extend(extra);
            let o = isotrack(&args);
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(65), "{key} {extra:?}: {e}");
            assert!(!e.contains("damaged row"), "{key} {extra:?}: {e}");
            assert!(e.contains("1 of them invalid"), "{key} {extra:?}: {e}");
            let rows = csv_rows(&out.join("results.csv"));
            assert_eq!(rows.len(), 2, "{key} {extra:?}");
            assert_eq!(rows[0]["outcome"], "completed");
            assert_eq!(rows[1][key], "tab\there");
            assert_eq!(rows[1]["outcome"], "invalid_scenario");
            let why = &rows[1]["outcome_detail"];
            assert!(why.contains("tab\\x09here") && !why.contains('\t'), "{why}");
        }
    }
}
