//! The `isotrack` binary end to end: outputs, overrides, and every bad-input path (clear
//! message, non-zero exit, never a panic).

mod common;

use common::{assert_fails, isotrack, stderr, write};
use std::path::Path;
use std::process::{Command, Output};

#[test]
fn default_run_prints_a_summary() {
    let o = isotrack(&["run"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("outcome     completed"), "{out}");
    assert!(out.contains("convergence"), "{out}");
}

#[test]
fn out_dir_has_trace_summary_and_resolved_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run1");
    let o = isotrack(&[
        "run",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "controller.kp=20",
        "--set",
        "sim.duration_s=60",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));

    // trace.csv: header and 10 Hz rows over 60 s (601 rows), no NaN anywhere.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines = trace.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "t_s",
        "x_m",
        "y_m",
        "heading_rad",
        "s",
        "error",
        "omega_radps",
    ] {
        assert!(header.contains(&col), "missing column {col}: {header:?}");
    }
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 601);
    assert!(!trace.to_lowercase().contains("nan"));
    let t_col = header.iter().position(|c| *c == "t_s").unwrap();
    let t1: f64 = rows[1][t_col].parse().unwrap();
    assert!(
        (t1 - 0.1).abs() < 1e-12,
        "10 Hz recording: second row at {t1}"
    );
    // error = s - level on every row.
    let (si, ei) = (
        header.iter().position(|c| *c == "s").unwrap(),
        header.iter().position(|c| *c == "error").unwrap(),
    );
    for r in &rows {
        let s: f64 = r[si].parse().unwrap();
        let e: f64 = r[ei].parse().unwrap();
        assert!((s - 10.0 - e).abs() < 1e-12);
    }

    // summary.json: the required keys and the resolved scenario with the override applied.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["outcome"], "completed");
    for k in [
        "steady_state_max_abs_error",
        "steady_state_rms_error",
        "steady_state_mean_error",
        "convergence_time_s",
        "scenario",
    ] {
        assert!(summary.get(k).is_some(), "missing {k}");
    }
    assert_eq!(summary["scenario"]["controller"]["kp"], 20.0);
    assert_eq!(summary["scenario"]["sim"]["dt_s"], 0.01);
    assert_eq!(summary["scenario"]["field"]["kind"], "radial_exp");

    // The resolved scenario runs again to the same result.
    let out2 = dir.path().join("run2");
    let o = isotrack(&[
        "run",
        out.join("scenario.toml").to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(out.join("trace.csv")).unwrap(),
        std::fs::read(out2.join("trace.csv")).unwrap()
    );
}

#[test]
fn never_converged_is_null_in_json() {
    let dir = tempfile::tempdir().unwrap();
    let o = isotrack(&[
        "run",
        "--out",
        dir.path().to_str().unwrap(),
        "--set",
        "sim.duration_s=5",
    ]);
    assert!(o.status.success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert!(summary["convergence_time_s"].is_null());
}

#[test]
fn toml_syntax_error() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(dir.path(), "bad.toml", "[controller]\nkp = = 3\n");
    assert_fails(&isotrack(&["run", &f]), 65, &["bad.toml:2"]);
}

#[test]
fn unknown_key() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(
        dir.path(),
        "bad.toml",
        "[sim]\ndt_s = 0.01\ndt_sec = 0.02\n",
    );
    assert_fails(
        &isotrack(&["run", &f]),
        65,
        &["bad.toml:3", "dt_sec", "sim.dt_sec"],
    );
    let f = write(dir.path(), "bad2.toml", "[simulation]\ndt_s = 0.01\n");
    assert_fails(&isotrack(&["run", &f]), 65, &["bad2.toml:1", "simulation"]);
}

#[test]
fn invalid_values() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(
        dir.path(),
        "bad.toml",
        "[controller]\nkp = 0\nc2 = -1\n\n[sim]\ndt_s = -0.01\n\n[initial]\nx_m = nan\n",
    );
    let o = isotrack(&["run", &f]);
    assert_fails(
        &o,
        65,
        &[
            "bad.toml:2:6: `controller.kp`: must be > 0",
            "bad.toml:3:6: `controller.c2`: must be > 0",
            "bad.toml:6:8: `sim.dt_s`: must be > 0",
            "bad.toml:9:7: `initial.x_m`: must be a finite number",
        ],
    );
    let f = write(dir.path(), "ki.toml", "[controller]\nki = -0.5\n");
    assert_fails(
        &isotrack(&["run", &f]),
        65,
        &["ki.toml:2", "controller.ki", ">= 0"],
    );
    let f = write(dir.path(), "ty.toml", "[sim]\nduration_s = \"long\"\n");
    assert_fails(
        &isotrack(&["run", &f]),
        65,
        &["ty.toml:2", "sim.duration_s"],
    );
    let f = write(
        dir.path(),
        "step.toml",
        "[sim]\ndt_s = 0.03\nduration_s = 1.0\n",
    );
    assert_fails(
        &isotrack(&["run", &f]),
        65,
        &["sim.duration_s", "whole number"],
    );
    let f = write(
        dir.path(),
        "kind.toml",
        "[field]\nkind = \"linear_ramp\"\ni0 = 3\n",
    );
    assert_fails(
        &isotrack(&["run", &f]),
        65,
        &["kind.toml:3", "field.i0", "does not apply"],
    );
}

#[test]
fn bad_overrides() {
    assert_fails(
        &isotrack(&["run", "--set", "controller.kp=-2"]),
        65,
        &["--set controller.kp=-2", "must be > 0"],
    );
    assert_fails(
        &isotrack(&["run", "--set", "controller.kz=2"]),
        65,
        &["--set controller.kz=2", "kz"],
    );
    assert_fails(
        &isotrack(&["run", "--set", "controller.kp"]),
        65,
        &["KEY=VALUE"],
    );
    assert_fails(
        &isotrack(&["run", "--set", "sim.dt_s=fast"]),
        65,
        &["--set sim.dt_s=fast"],
    );
}

#[test]
fn missing_file() {
    assert_fails(
        &isotrack(&["run", "/nonexistent/scenario.toml"]),
        66,
        &["/nonexistent/scenario.toml", "cannot read"],
    );
}

#[test]
fn unwritable_output() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = write(dir.path(), "file", "x");
    assert_fails(
        &isotrack(&[
            "run",
            "--out",
            &format!("{blocker}/sub"),
            "--set",
            "sim.duration_s=1",
        ]),
        73,
        &["cannot write"],
    );
}

#[test]
fn bad_command_line() {
    let o = isotrack(&["run", "--frobnicate"]);
    assert_eq!(o.status.code(), Some(64));
    assert!(!stderr(&o).contains("panicked"));
}

/// A withheld Prop. 2 bound is no claim (review): the text says so and prints no bound, the
/// JSON's `error_bound` is null and the conditional value has its own key.
#[test]
fn check_claims_no_withheld_bound() {
    let sets = [
        "--set",
        "controller.ki=0",
        "--set",
        "controller.kp=20",
        "--set",
        "sensor.resolution=0.5",
    ];
    let o = isotrack(&[&["check"][..], &sets[..]].concat());
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        text.contains("NO bound on limsup|eps| is claimed"),
        "{text}"
    );
    assert!(!text.contains("limsup|eps| <= 0.17"), "{text}");
    assert!(text.contains("bound not claimed"), "{text}");
    let o = isotrack(&[&["check", "--json"][..], &sets[..]].concat());
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["prop2"]["error_bound"].is_null(), "{}", j["prop2"]);
    assert!(j["prop2"]["paper_error_bound"].is_null());
    let b = j["prop2"]["error_bound_if_not_withheld"].as_f64().unwrap();
    assert!((b / 0.17721 - 1.0).abs() < 1e-3, "{b}");
}

#[test]
fn check_json_has_the_documented_keys() {
    let o = isotrack(&["check", "--json", "--set", "controller.ki=0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["prop1"]["paper_conditions_hold"], true);
    assert_eq!(j["prop1"]["exact_local_condition_holds"], true);
    assert_eq!(j["prop2"]["conditions_hold"], true);
    assert!(j["prop2"]["error_bound"].as_f64().unwrap() > 0.0);
    assert!(j["prop2"]["min_kp"].as_f64().unwrap() > 0.0);
    // The discrete loop (issue 29): the stable kp set, the matrices, the polynomial, margins.
    let sm = &j["sampled"];
    assert!(
        sm["kp_intervals"].as_array().unwrap()[0]
            .as_array()
            .unwrap()
            .len()
            == 2
    );
    assert_eq!(sm["slope_exact"], true);
    // With ki = 0 the P law is checked on its orbit, outside the isoline.
    assert_eq!(sm["stable_over_tube"], true);
    assert!(sm["p_law_orbit_error"].as_f64().unwrap() < 0.0);
    let d = &sm["discrete_loop"];
    for key in [
        "phi",
        "gamma",
        "c",
        "closed_loop",
        "characteristic_polynomial",
    ] {
        assert!(d[key].is_array(), "{key}");
    }
    assert!(d["gain_margin"].as_f64().unwrap() > 1.0);
    assert!(d["phase_margin_deg"].as_f64().unwrap() > 0.0);
    assert!(j["prop2"]["bound_withheld"].as_array().unwrap().is_empty());
    // Not circular: prop1 fields are null; ki > 0: Prop. 2 does not apply, bound null.
    let o = isotrack(&["check", "--json", "--set", "field.kind=linear_ramp"]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["prop1"]["paper_conditions_hold"].is_null());
    assert!(j["prop2"]["error_bound"].is_null());
    assert_eq!(j["prop2"]["conditions_hold"], false);
    // Human output.
    let o = isotrack(&["check"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("Routh-Hurwitz"));
    for line in [
        "on the isoline",
        "over the whole tube",
        "stable kp: [",
        "gain margin",
    ] {
        assert!(text.contains(line), "{line}: {text}");
    }
}

#[test]
fn nodata_in_a_grid_ends_the_run_as_left_field() {
    let dir = tempfile::tempdir().unwrap();
    // A 20 x 20 ramp (value = column) with a NaN block in columns 12..16.
    let mut csv = String::new();
    for _ in 0..20 {
        let row: Vec<String> = (0..20)
            .map(|i| {
                if (12..16).contains(&i) {
                    "NaN".into()
                } else {
                    format!("{i}")
                }
            })
            .collect();
        csv += &row.join(",");
        csv += "\n";
    }
    write(dir.path(), "hole.csv", &csv);
    let scen = write(
        dir.path(),
        "hole.toml",
        "[field]\nkind = \"grid\"\npath = \"hole.csv\"\n[initial]\nx_m = 2.0\ny_m = 10.0\nheading_rad = 0.0\n\
         [vehicle]\nspeed_mps = 1.0\n[controller]\nlevel = 100.0\nkp = 1e-6\nki = 0.0\n[sim]\nduration_s = 60.0\n",
    );
    let out = dir.path().join("out");
    let o = isotrack(&["run", &scen, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["outcome"], "left_field");
    let x_end = s["end_position_m"][0].as_f64().unwrap();
    // Bicubic: the stencil of the cell [10, 11] already touches the NaN column 12.
    assert!(
        (9.9..12.0).contains(&x_end),
        "stopped before the hole: {x_end}"
    );
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    assert!(!trace.to_lowercase().contains("nan"));
    // A bad grid file is a scenario error naming the file and line.
    write(dir.path(), "bad.csv", "1,2\n3\n");
    let bad = write(
        dir.path(),
        "bad.toml",
        "[field]\nkind = \"grid\"\npath = \"bad.csv\"\n",
    );
    assert_fails(
        &isotrack(&["run", &bad]),
        65,
        &["field.path", "bad.csv:2", "ragged"],
    );
}

#[test]
fn compare_writes_the_documented_csv() {
    let dir = tempfile::tempdir().unwrap();
    let scen = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig2b-circular.toml"
    );
    let o = isotrack(&[
        "compare",
        scen,
        "--controllers",
        "pi_isoline,sliding_mode",
        "--set",
        "sim.duration_s=120",
        "--gain",
        "sliding_mode.gamma=0.3",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("| pi_isoline | completed"), "{out}");
    let csv = std::fs::read_to_string(dir.path().join("comparison.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "controller",
        "outcome",
        "convergence_time_s",
        "steady_state_max_abs_error",
        "steady_state_rms_error",
        "chattering_radps2",
        "sign_changes_per_s",
        "control_effort",
        "steady_state_max_isoline_distance_m",
    ] {
        assert!(header.contains(&col), "missing {col}");
    }
    assert_eq!(lines.count(), 2);
    // The per-controller run records the gain override.
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("sliding_mode/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(s["scenario"]["controller"]["gamma"], 0.3);
    assert_eq!(s["scenario"]["controller"]["kind"], "sliding_mode");
    // Bad controller names and gains are usage errors.
    assert_fails(
        &isotrack(&["compare", scen, "--controllers", "bogus"]),
        64,
        &["bogus"],
    );
    assert_fails(
        &isotrack(&["compare", scen, "--gain", "gamma=1"]),
        64,
        &["KIND.KEY=VALUE"],
    );
}

#[test]
fn trim_json_reproduces_the_trim_table() {
    let o = isotrack(&["trim", "--airspeed-mps", "30", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((j["alpha_rad"].as_f64().unwrap() - 0.0330598).abs() < 1e-6);
    assert!((j["delta_e_rad"].as_f64().unwrap() + 0.0718854).abs() < 1e-6);
    assert!((j["delta_t"].as_f64().unwrap() - 0.398352).abs() < 1e-6);
    assert!((j["gains"]["kp_chi"].as_f64().unwrap() - 9.0697).abs() < 1e-3);
    assert_fails(&isotrack(&["trim", "--airspeed-mps=-3"]), 64, &["airspeed"]);
}

#[test]
fn replay_of_trim_inputs_stays_in_trim_and_bad_files_fail() {
    let dir = tempfile::tempdir().unwrap();
    // The trim inputs at 30 m/s, full precision, for 20 s: straight and level.
    let j: serde_json::Value =
        serde_json::from_slice(&isotrack(&["trim", "--airspeed-mps", "30", "--json"]).stdout)
            .unwrap();
    let (de, dt) = (
        j["delta_e_rad"].as_f64().unwrap(),
        j["delta_t"].as_f64().unwrap(),
    );
    let mut text = String::from("t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n");
    for k in 0..=20 {
        text += &format!("{k},{de:?},0,0,{dt:?}\n");
    }
    let inp = write(dir.path(), "in.csv", &text);
    let out = dir.path().join("out.csv");
    let o = isotrack(&["replay", "--inputs", &inp, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(&out).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[..4], ["t_s", "north_m", "east_m", "altitude_m"]);
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(last[0], 20.0);
    assert!((last[1] - 600.0).abs() < 0.01, "north {}", last[1]);
    assert!((last[3] - 100.0).abs() < 1e-3, "altitude {}", last[3]);
    assert!((last[4] - 30.0).abs() < 1e-4, "airspeed {}", last[4]);
    // Bad input files.
    let bad = write(
        dir.path(),
        "bad.csv",
        "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,0,0,0,0.4\n0,0,0,0,0.4\n",
    );
    assert_fails(
        &isotrack(&["replay", "--inputs", &bad, "--out", out.to_str().unwrap()]),
        65,
        &["line 3", "increase"],
    );
    let bad = write(dir.path(), "bad2.csv", "t_s,delta_e\n0,0\n");
    assert_fails(
        &isotrack(&["replay", "--inputs", &bad, "--out", out.to_str().unwrap()]),
        65,
        &["delta_e_rad"],
    );
    let bad = write(
        dir.path(),
        "bad3.csv",
        "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,x,0,0,0.4\n",
    );
    assert_fails(
        &isotrack(&["replay", "--inputs", &bad, "--out", out.to_str().unwrap()]),
        65,
        &["line 2", "delta_e_rad"],
    );
    // Inputs the airframe model does not cover, and an ambiguous header (a hostile review:
    // `delta_e_rad = 100` and `delta_t = -1` replayed as valid flights; a second `t_s` column
    // was ignored).
    for (name, text, want) in [
        (
            "e.csv",
            "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,0,0,0,0.4\n1,100,0,0,0.4\n",
            ["line 3", "delta_e_rad"],
        ),
        (
            "t.csv",
            "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,0,0,0,-1\n",
            ["line 2", "delta_t"],
        ),
        (
            "d.csv",
            "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t,t_s\n0,0,0,0,0.4,5\n",
            ["line 1", "t_s"],
        ),
    ] {
        let bad = write(dir.path(), name, text);
        let _ = std::fs::remove_file(&out);
        assert_fails(
            &isotrack(&["replay", "--inputs", &bad, "--out", out.to_str().unwrap()]),
            65,
            &want,
        );
        assert!(!out.exists(), "{name}: no output for a refused input");
    }
}

#[test]
fn fixed_wing_scenario_traces_telemetry() {
    let dir = tempfile::tempdir().unwrap();
    let scen = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig3-uav.toml"
    );
    let o = isotrack(&[
        "run",
        scen,
        "--set",
        "sim.duration_s=60",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let trace = std::fs::read_to_string(dir.path().join("trace.csv")).unwrap();
    let header = trace.lines().next().unwrap();
    assert!(
        header.ends_with("altitude_m,airspeed_mps,roll_rad"),
        "{header}"
    );
}

#[test]
fn run_plot_and_plot_command_write_images() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let o = isotrack(&[
        "run",
        "--out",
        a.to_str().unwrap(),
        "--plot",
        "-q",
        "--set",
        "sim.duration_s=30",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["trajectory.png", "timeseries.png"] {
        let bytes = std::fs::read(a.join(f)).unwrap();
        assert_eq!(&bytes[1..4], b"PNG", "{f}");
    }
    let b = dir.path().join("b");
    isotrack(&[
        "run",
        "--out",
        b.to_str().unwrap(),
        "-q",
        "--set",
        "sim.duration_s=30",
        "--set",
        "initial.x_m=-8",
    ]);
    let out = dir.path().join("both");
    let o = isotrack(&[
        "plot",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--format",
        "svg",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(out.join("trajectory.svg"))
        .unwrap()
        .contains("<svg"));
    // --plot needs --out; a non-run directory is a clear error.
    assert_eq!(isotrack(&["run", "--plot"]).status.code(), Some(64));
    assert_fails(
        &isotrack(&["plot", dir.path().to_str().unwrap()]),
        66,
        &["summary.json"],
    );
}

/// The test sweep holds invalid runs on purpose (`ki = -1`): every run is recorded, and the
/// sweep exits 65 naming how many were invalid.
fn assert_sweep_with_invalid_runs(o: &Output) {
    assert_fails(o, 65, &["of them invalid (outcome invalid_scenario"]);
}

fn sweep_file(dir: &Path, runs: u32, duration: f64) -> String {
    let scen = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig2b-circular.toml"
    );
    write(
        dir,
        "sweep.toml",
        &format!(
            "scenario = {scen:?}\n[base]\nsim.duration_s = {duration:?}\n[grid]\ncontroller.kp = [5.0, 10.0]\ncontroller.ki = [0.0, 1.0, -1.0]\n\
             [random]\nruns = {runs}\nseed = 3\ninitial.x_m = {{ uniform = [-12.0, 12.0] }}\nsensor.noise_std = {{ normal = [0.01, 0.002] }}\n"
        ),
    )
}

#[test]
fn sweeps_are_identical_across_threads_and_shards_and_merge_checks_coverage() {
    let dir = tempfile::tempdir().unwrap();
    let sw = sweep_file(dir.path(), 4, 30.0);
    let full = dir.path().join("full");
    let o = isotrack(&[
        "sweep",
        &sw,
        "--out",
        full.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    assert_sweep_with_invalid_runs(&o);
    let one = dir.path().join("one");
    isotrack(&[
        "sweep",
        &sw,
        "--out",
        one.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    let reference = std::fs::read(full.join("results.csv")).unwrap();
    assert_eq!(reference, std::fs::read(one.join("results.csv")).unwrap());
    let text = String::from_utf8(reference.clone()).unwrap();
    assert_eq!(text.lines().count(), 1 + 24);
    assert!(!text.to_lowercase().contains("nan"));
    // ki = -1 is invalid: recorded as such, not a crash.
    assert!(text.contains("invalid_scenario"));
    assert!(text.lines().next().unwrap().starts_with(
        "run_id,controller.ki,controller.kp,initial.x_m,sensor.noise_std,sim.seed,outcome"
    ));
    // Three shards, merged: identical.
    let mut shards = vec![];
    for k in 1..=3 {
        let d = dir.path().join(format!("s{k}"));
        let o = isotrack(&[
            "sweep",
            &sw,
            "--out",
            d.to_str().unwrap(),
            "--shard",
            &format!("{k}/3"),
        ]);
        assert_sweep_with_invalid_runs(&o);
        shards.push(d.to_str().unwrap().to_string());
    }
    let merged = dir.path().join("merged");
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(String::as_str));
    args.extend(["--out", merged.to_str().unwrap()]);
    let o = isotrack(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        reference,
        std::fs::read(merged.join("results.csv")).unwrap()
    );
    // Missing and duplicate shards are refused.
    assert_fails(
        &isotrack(&[
            "merge",
            &shards[0],
            &shards[1],
            "--out",
            merged.to_str().unwrap(),
            "--force",
        ]),
        65,
        &["missing"],
    );
    assert_fails(
        &isotrack(&[
            "merge",
            &shards[0],
            &shards[1],
            &shards[2],
            &shards[2],
            "--out",
            merged.to_str().unwrap(),
            "--force",
        ]),
        65,
        &["more than one"],
    );
    // An existing output needs --resume; bad shard specs are usage errors.
    assert_fails(
        &isotrack(&["sweep", &sw, "--out", full.to_str().unwrap()]),
        73,
        &["--resume"],
    );
    assert_fails(
        &isotrack(&[
            "sweep",
            &sw,
            "--out",
            full.to_str().unwrap(),
            "--shard",
            "4/3",
        ]),
        64,
        &["K/N"],
    );
}

/// A fixed-wing sweep (its airframes stepped in SIMD lanes, 8 at a time) writes the same
/// `results.csv`, byte for byte, as the same runs unbatched (one shard per run: every group a
/// single run, merged) and on 1 and 2 threads: calm and gusty runs, each with its own seed.
#[test]
fn fixed_wing_sweeps_are_identical_batched_and_unbatched() {
    let dir = tempfile::tempdir().unwrap();
    let scen = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig3-uav.toml"
    );
    let sw = write(
        dir.path(),
        "uav.toml",
        &format!(
            "scenario = {scen:?}\n[base]\nsim.duration_s = 30.0\n[grid]\nvehicle.gusts = [false, true]\n\
             [random]\nruns = 6\nseed = 5\ninitial.x_m = {{ uniform = [-3500.0, 3500.0] }}\n\
             initial.heading_rad = {{ uniform = [-3.0, 3.0] }}\n"
        ),
    );
    let run = |name: &str, extra: &[&str]| {
        let d = dir.path().join(name);
        let mut args = vec!["sweep", &sw, "--out", d.to_str().unwrap()];
        args.extend(extra);
        let o = isotrack(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        d
    };
    let two = std::fs::read(run("two", &["--threads", "2"]).join("results.csv")).unwrap();
    let one = std::fs::read(run("one", &["--threads", "1"]).join("results.csv")).unwrap();
    assert_eq!(two, one);
    let shards: Vec<String> = (1..=12)
        .map(|k| {
            let d = run(&format!("s{k}"), &["--shard", &format!("{k}/12")]);
            d.to_str().unwrap().to_string()
        })
        .collect();
    let merged = dir.path().join("merged");
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(String::as_str));
    args.extend(["--out", merged.to_str().unwrap()]);
    let o = isotrack(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(two, std::fs::read(merged.join("results.csv")).unwrap());
    let text = String::from_utf8(two).unwrap();
    assert_eq!(text.lines().count(), 1 + 12);
    assert!(
        text.contains(",completed,") && text.contains(",left_field,"),
        "{text}"
    );
}

#[test]
fn a_damaged_sweep_resumes_to_the_same_results() {
    let dir = tempfile::tempdir().unwrap();
    let sw = sweep_file(dir.path(), 3, 20.0);
    let full = dir.path().join("full");
    isotrack(&["sweep", &sw, "--out", full.to_str().unwrap()]);
    let reference = std::fs::read_to_string(full.join("results.csv")).unwrap();
    // Keep the header and 5 rows, then half of the next row with no newline.
    let part = dir.path().join("part");
    std::fs::create_dir_all(&part).unwrap();
    let lines: Vec<&str> = reference.lines().collect();
    let mut damaged = lines[..6].join("\n") + "\n";
    damaged += &lines[6][..lines[6].len() / 2];
    std::fs::write(part.join("results.csv"), damaged).unwrap();
    std::fs::copy(full.join("sweep.json"), part.join("sweep.json")).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", part.to_str().unwrap(), "--resume"]);
    assert_sweep_with_invalid_runs(&o);
    assert_eq!(
        reference,
        std::fs::read_to_string(part.join("results.csv")).unwrap()
    );
}

#[cfg(unix)]
#[test]
fn a_sigkilled_sweep_resumes_to_the_same_results() {
    let dir = tempfile::tempdir().unwrap();
    let sw = sweep_file(dir.path(), 40, 200.0); // 240 runs
    let full = dir.path().join("full");
    isotrack(&["sweep", &sw, "--out", full.to_str().unwrap()]);
    let reference = std::fs::read(full.join("results.csv")).unwrap();
    let killed = dir.path().join("killed");
    let results = killed.join("results.csv");
    let rows = || {
        std::fs::read_to_string(&results)
            .map(|t| t.lines().count().saturating_sub(1))
            .unwrap_or(0)
    };
    // Three kills, each once the sweep has written more rows than before but not all of them:
    // the kill provably lands mid-run, and the file it leaves is incomplete (no final sort).
    let mut before = 0;
    for _ in 0..3 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .args(["sweep", &sw, "--out", killed.to_str().unwrap(), "--resume"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let started = std::time::Instant::now();
        while rows() < before + 5 && started.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        let _ = child.kill(); // SIGKILL
        let _ = child.wait();
        let after = rows();
        assert!(
            after > before && after < 240,
            "the kill did not land mid-run: {before} -> {after} of 240 rows"
        );
        assert_ne!(std::fs::read(&results).unwrap(), reference);
        before = after;
    }
    let o = isotrack(&["sweep", &sw, "--out", killed.to_str().unwrap(), "--resume"]);
    assert_sweep_with_invalid_runs(&o);
    assert_eq!(
        reference,
        std::fs::read(killed.join("results.csv")).unwrap()
    );
}

#[test]
fn check_uses_the_uav_airspeed() {
    // The ERA5 isotherm flown at 30 m/s: its gamma1 is small but not 0, so the remark carries
    // v*gamma1 (with gamma1 = 0, as on the Fig. 3 map, no c1 helps and no product is quoted).
    let scen = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/era5-isotherm-uav.toml"
    );
    let o = isotrack(&["check", scen, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The reachability remark is computed with v = 30 m/s (the airspeed), not 0.
    let g1 = j["prop2"]["gamma1"].as_f64().unwrap();
    assert!(g1 > 0.0, "{g1}");
    let note = j["prop2"]["note"].as_str().unwrap();
    assert!(
        note.contains(&format!(
            "v*gamma1 = {} <=",
            isotrack_core::numtext::Num(30.0 * g1)
        )),
        "{note}"
    );
}

/// `run` warns on stderr and in summary.json about noise through a backward difference and a
/// loop that is unstable at the sensor's rate; `check` gives the verdict first and says whether
/// the rate is the limit.
#[test]
fn run_and_check_warn_about_noise_and_an_unstable_sampled_loop() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let sets = [
        "--set",
        "sensor.rate_hz=1",
        "--set",
        "sensor.noise_std=0.01",
    ];
    let o = isotrack(&[&["run", "--out", out.to_str().unwrap()][..], &sets[..]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("warning: sensor noise"), "{err}");
    assert!(
        err.contains("warning: the loop sampled at 1 Hz is unstable"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let w = summary["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 2, "{w:?}");
    // The default at 100 Hz without noise: no warning.
    let quiet = dir.path().join("q");
    let o = isotrack(&["run", "--out", quiet.to_str().unwrap()]);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(quiet.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["warnings"].as_array().unwrap().len(), 0);

    let o = isotrack(&[&["check"][..], &sets[..]].concat());
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(text.starts_with("verdict: fails"), "{text}");
    assert!(text.contains("sensor rate: the limit"), "{text}");
    let o = isotrack(&[&["check", "--json"][..], &sets[..]].concat());
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["verdict"], "fails");
    assert_eq!(j["sampled"]["stable"], false);
    assert!(j["sampled"]["max_period_s"].as_f64().unwrap() < 1.0);
    assert!(j["sampled"]["spectral_radius"].as_f64().unwrap() > 1.0);
    assert_eq!(j["prop2"]["bound_applies"], false);
    assert!(
        j["sampled"]["max_kp"].is_null(),
        "ki = 1 at 1 Hz: no kp is stable"
    );
}
