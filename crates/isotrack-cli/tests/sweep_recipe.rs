//! Issue 31, "Sweeps keep the user's own keys apart from the materialised defaults": a sweep's
//! run is exactly `isotrack run` of the user's scenario + `[base]` + the row's assignments,
//! resolved once, so a default that follows another key follows the row. README's re-run recipe
//! (`isotrack run DIR/base_scenario.toml --set KEY=VALUE ...`) gives each row, every metric, and
//! `--resume` and `merge` keep such rows.
mod common;
use common::{isotrack, stderr, write};
use std::collections::BTreeMap;
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
fn rows(dir: &Path) -> Vec<BTreeMap<String, String>> {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            header
                .iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()
        })
        .collect()
}

/// Runs the sweep into `out` with `extra` arguments; panics on failure.
fn sweep(sw: &str, out: &Path, extra: &[&str]) {
    let mut args = vec!["sweep", sw, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = isotrack(&args);
    assert!(o.status.success(), "{}", stderr(&o));
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
    let (s1, s2, merged) = (
        d.path().join("s1"),
        d.path().join("s2"),
        d.path().join("merged"),
    );
    sweep(&sw, &s1, &["--shard", "1/2"]);
    sweep(&sw, &s2, &["--shard", "2/2"]);
    let o = isotrack(&[
        "merge",
        s1.to_str().unwrap(),
        s2.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(merged.join("results.csv")).unwrap(), bytes);
}
