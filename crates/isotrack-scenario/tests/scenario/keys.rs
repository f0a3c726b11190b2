//! The scenario keys of the README, one by one: each takes effect, and gives the number its
//! documented formula gives (computed here independently: the transform applied by hand to
//! the nodes, exact interpolation of a quadratic, the steady window recomputed from the trace,
//! the integral term reconstructed from the trace's own columns, the P-law's closed-form orbit,
//! the wind triangle).

use isotrack_core::math::Vec2;
use isotrack_core::theory::radial_exp_p_orbit;
use isotrack_core::ScalarField;
use isotrack_scenario::{parse_scenario, parse_scenario_in, Scenario, ScenarioError};
use isotrack_sim::{NoTrace, Outcome, RunResult, TraceRow};
use std::path::Path;

/// A CSV grid (no header, row 0 south) of `f(column, row)`.
fn write_csv(dir: &Path, name: &str, nx: usize, ny: usize, f: impl Fn(usize, usize) -> f64) {
    let mut text = String::new();
    for r in 0..ny {
        let row: Vec<String> = (0..nx).map(|c| format!("{:?}", f(c, r))).collect();
        text += &row.join(",");
        text.push('\n');
    }
    std::fs::write(dir.join(name), text).unwrap();
}

/// A `.npy` file (format 1.0, little-endian f64, C order, shape (rows, cols), row 0 south), as
/// numpy's `np.save` writes it.
fn write_npy(dir: &Path, name: &str, nx: usize, ny: usize, f: impl Fn(usize, usize) -> f64) {
    let dict = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({ny}, {nx}), }}");
    // Magic (6) + version (2) + length (2) + dict + padding + '\n', a multiple of 64.
    let unpadded = 10 + dict.len() + 1;
    let header = format!("{dict}{}\n", " ".repeat((64 - unpadded % 64) % 64));
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for r in 0..ny {
        for c in 0..nx {
            bytes.extend(f(c, r).to_le_bytes());
        }
    }
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// A 3-D `.npy` of `frames` frames of `ny x nx` (shape (frames, rows, cols)), frame `k` holding
/// `f(k)` everywhere.
fn write_npy_frames(dir: &Path, name: &str, frames: usize, f: impl Fn(usize) -> f64) {
    let (nx, ny) = (4, 4);
    let dict =
        format!("{{'descr': '<f8', 'fortran_order': False, 'shape': ({frames}, {ny}, {nx}), }}");
    let unpadded = 10 + dict.len() + 1;
    let header = format!("{dict}{}\n", " ".repeat((64 - unpadded % 64) % 64));
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for k in 0..frames {
        for _ in 0..nx * ny {
            bytes.extend(f(k).to_le_bytes());
        }
    }
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// A file of several frames needs their times (from the file, `frame_interval_s` or
/// `frame_times_s`); a file of one frame is a plain grid without them.
#[test]
fn a_file_of_frames_needs_their_times() {
    use isotrack_scenario::field::FieldModel;
    let d = tempfile::tempdir().unwrap();
    write_npy_frames(d.path(), "two.npy", 2, |k| k as f64);
    write_npy_frames(d.path(), "one.npy", 1, |_| 5.0);
    let err = grid_scenario(d.path(), "path = \"two.npy\"", (1.5, 1.5))
        .unwrap_err()
        .to_string();
    assert!(err.contains("holds 2 frames and no frame times"), "{err}");
    let s = grid_scenario(
        d.path(),
        "path = \"two.npy\"\nframe_interval_s = 10.0",
        (1.5, 1.5),
    )
    .unwrap();
    assert!(matches!(s.field(), FieldModel::Series(_)));
    let s = grid_scenario(d.path(), "path = \"one.npy\"", (1.5, 1.5)).unwrap();
    assert!(matches!(s.field(), FieldModel::Grid(_)));
}

/// The scenario of `[field]` lines `field` (files relative to `dir`), starting at `start`.
fn grid_scenario(dir: &Path, field: &str, start: (f64, f64)) -> Result<Scenario, ScenarioError> {
    let text = format!(
        "[field]\nkind = \"grid\"\n{field}\n[initial]\nx_m = {:?}\ny_m = {:?}\n",
        start.0, start.1
    );
    parse_scenario_in(&text, "<test>", &[], dir)
}

fn value(s: &Scenario, x: f64, y: f64) -> Option<f64> {
    s.field().value(0.0, Vec2::new(x, y))
}

/// `value_floor`, `value_log10`, `value_scale`, `value_offset`:
/// `v -> scale*log10(max(v, floor)) + offset` on every node (the interpolant passes through
/// the nodes), and bilinear interpolation of the transformed nodes between them.
#[test]
fn value_transforms_follow_the_formula_node_by_node() {
    let dir = tempfile::tempdir().unwrap();
    // Values spanning decades, some below the floor (and zero, whose log would be -inf).
    let raw = |c: usize, r: usize| 10f64.powi(r as i32 - 2) * c as f64;
    write_csv(dir.path(), "g.csv", 5, 5, raw);
    let (floor, scale, offset) = (0.05, 2.0, 1.0);
    let by_hand = |v: f64| scale * v.max(floor).log10() + offset;
    let s = grid_scenario(
        dir.path(),
        "path = \"g.csv\"\ninterpolation = \"bilinear\"\nvalue_floor = 0.05\nvalue_log10 = true\nvalue_scale = 2.0\nvalue_offset = 1.0",
        (2.0, 2.0),
    )
    .unwrap();
    for r in 0..5 {
        for c in 0..5 {
            let got = value(&s, c as f64, r as f64).unwrap();
            let want = by_hand(raw(c, r));
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1.0),
                "node ({c}, {r}): {got} vs {want}"
            );
        }
    }
    // Between nodes: the mean of the four transformed corners (the transform is applied to the
    // nodes, then interpolated).
    let mid = value(&s, 2.5, 1.5).unwrap();
    let corners = [(2, 1), (3, 1), (2, 2), (3, 2)].map(|(c, r)| by_hand(raw(c, r)));
    let mean = corners.iter().sum::<f64>() / 4.0;
    assert!((mid - mean).abs() < 1e-12, "{mid} vs {mean}");

    // Without log10: max(v, floor) scaled and offset, linear.
    let s = grid_scenario(
        dir.path(),
        "path = \"g.csv\"\nvalue_floor = 0.5\nvalue_scale = -3.0\nvalue_offset = 7.0",
        (2.0, 2.0),
    )
    .unwrap();
    for (c, r) in [(1, 1), (2, 2), (3, 3), (1, 3)] {
        let want = -3.0 * raw(c, r).max(0.5) + 7.0;
        assert!((value(&s, c as f64, r as f64).unwrap() - want).abs() < 1e-12);
    }
    // log10 of a grid holding 0 without a floor: refused, naming the key.
    let err = grid_scenario(
        dir.path(),
        "path = \"g.csv\"\nvalue_log10 = true",
        (2.0, 2.0),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("field.value_log10"), "{err}");
}

/// `crop_cells = [c0, c1, r0, r1]` keeps columns c0..=c1 and rows r0..=r1, where they were
/// (the kept nodes keep their positions); outside them the field has no value.
#[test]
fn crop_keeps_the_named_columns_and_rows() {
    let dir = tempfile::tempdir().unwrap();
    let raw = |c: usize, r: usize| (10 * c + r) as f64;
    write_csv(dir.path(), "g.csv", 6, 5, raw);
    let s = grid_scenario(
        dir.path(),
        "path = \"g.csv\"\ninterpolation = \"bilinear\"\ncrop_cells = [1, 3, 2, 4]",
        (2.0, 3.0),
    )
    .unwrap();
    for c in 1..=3 {
        for r in 2..=4 {
            assert_eq!(value(&s, c as f64, r as f64), Some(raw(c, r)), "({c}, {r})");
        }
    }
    for (x, y) in [(0.5, 3.0), (3.5, 3.0), (2.0, 1.5), (2.0, 4.5)] {
        assert_eq!(value(&s, x, y), None, "({x}, {y}) was cropped away");
    }
    // With origin_m: the south-west node of the crop moves there.
    let s = grid_scenario(
        dir.path(),
        "path = \"g.csv\"\ninterpolation = \"bilinear\"\ncrop_cells = [1, 3, 2, 4]\norigin_m = [100.0, 200.0]\nspacing_m = [2.0, 3.0]",
        (102.0, 203.0),
    )
    .unwrap();
    assert_eq!(value(&s, 100.0, 200.0), Some(raw(1, 2)));
    assert_eq!(value(&s, 104.0, 206.0), Some(raw(3, 4)));
    // A crop beyond the grid names the key.
    let err = grid_scenario(
        dir.path(),
        "path = \"g.csv\"\ncrop_cells = [1, 9, 0, 2]",
        (2.0, 1.0),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("field.crop_cells"), "{err}");
}

/// `format` reads a file whatever its extension; without it a text file with an unknown
/// extension is refused, naming the key to set (a binary one is read by its signature).
#[test]
fn format_overrides_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    let raw = |c: usize, r: usize| (c * c + 3 * r) as f64 + 0.25;
    write_csv(dir.path(), "g.dat", 5, 4, raw);
    write_npy(dir.path(), "g.bin", 5, 4, raw);
    let csv = grid_scenario(dir.path(), "path = \"g.dat\"\nformat = \"csv\"", (2.0, 2.0)).unwrap();
    let npy = grid_scenario(dir.path(), "path = \"g.bin\"\nformat = \"npy\"", (2.0, 2.0)).unwrap();
    for (x, y) in [(1.0, 1.0), (2.0, 2.0), (1.5, 1.25), (2.75, 1.5)] {
        let (a, b) = (value(&csv, x, y).unwrap(), value(&npy, x, y).unwrap());
        assert_eq!(a, b, "({x}, {y})");
    }
    assert_eq!(value(&npy, 3.0, 2.0), Some(raw(3, 2)));
    // A binary file's signature names its format whatever the extension (README
    // `field.format`); a text file with an unknown extension needs the key.
    let by_content = grid_scenario(dir.path(), "path = \"g.bin\"", (2.0, 2.0)).unwrap();
    assert_eq!(value(&by_content, 3.0, 2.0), Some(raw(3, 2)));
    let err = grid_scenario(dir.path(), "path = \"g.dat\"", (2.0, 2.0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("field.format"), "{err}");
    // The wrong format for the bytes is an error, not a silent misreading.
    assert!(grid_scenario(dir.path(), "path = \"g.bin\"\nformat = \"csv\"", (2.0, 2.0)).is_err());
}

/// `variable` picks a NetCDF variable; without it the first 2-D data variable is read.
#[test]
fn variable_selects_the_named_netcdf_variable() {
    use netcdf3::{DataSet, FileWriter, Version};
    let dir = tempfile::tempdir().unwrap();
    let (nx, ny) = (4usize, 3usize);
    let mut ds = DataSet::new();
    ds.add_fixed_dim("y", ny).unwrap();
    ds.add_fixed_dim("x", nx).unwrap();
    for axis in ["x", "y"] {
        ds.add_var_f64(axis, &[axis]).unwrap();
        ds.add_var_attr_string(axis, "units", "m").unwrap();
    }
    ds.add_var_f64("first", &["y", "x"]).unwrap();
    ds.add_var_f64("second", &["y", "x"]).unwrap();
    let path = dir.path().join("two.nc");
    let mut w = FileWriter::create_new(&path).unwrap();
    w.set_def(&ds, Version::Classic, 0).unwrap();
    w.write_var_f64("x", &[0.0, 10.0, 20.0, 30.0]).unwrap();
    w.write_var_f64("y", &[0.0, 10.0, 20.0]).unwrap();
    let first: Vec<f64> = (0..nx * ny).map(|i| i as f64).collect();
    let second: Vec<f64> = (0..nx * ny).map(|i| 100.0 - 2.0 * i as f64).collect();
    w.write_var_f64("first", &first).unwrap();
    w.write_var_f64("second", &second).unwrap();
    w.close().unwrap();
    let at = |s: &Scenario, c: usize, r: usize| value(s, 10.0 * c as f64, 10.0 * r as f64);
    let default = grid_scenario(dir.path(), "path = \"two.nc\"", (15.0, 10.0)).unwrap();
    let named = grid_scenario(
        dir.path(),
        "path = \"two.nc\"\nvariable = \"second\"",
        (15.0, 10.0),
    )
    .unwrap();
    for (c, r) in [(1, 1), (2, 1), (1, 0), (3, 2)] {
        // y increases with the row index: row r of the file is y = 10 r.
        assert_eq!(
            at(&default, c, r),
            Some(first[r * nx + c]),
            "first ({c}, {r})"
        );
        assert_eq!(
            at(&named, c, r),
            Some(second[r * nx + c]),
            "second ({c}, {r})"
        );
    }
    let err = grid_scenario(
        dir.path(),
        "path = \"two.nc\"\nvariable = \"third\"",
        (15.0, 10.0),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("third"), "{err}");
}

/// `interpolation` on `F = x^2 + 2 y^2` sampled at 1 m: `bicubic` (Catmull-Rom) is exact for
/// quadratics; `bilinear` is linear between nodes, `x^2` on [2, 3] becoming `5x - 6`.
#[test]
fn interpolation_bilinear_and_bicubic_on_a_quadratic() {
    let dir = tempfile::tempdir().unwrap();
    let f = |x: f64, y: f64| x * x + 2.0 * y * y;
    write_csv(dir.path(), "q.csv", 7, 7, |c, r| f(c as f64, r as f64));
    let cubic = grid_scenario(dir.path(), "path = \"q.csv\"", (3.0, 3.0)).unwrap();
    let linear = grid_scenario(
        dir.path(),
        "path = \"q.csv\"\ninterpolation = \"bilinear\"",
        (3.0, 3.0),
    )
    .unwrap();
    let lin1 = |x: f64| {
        let (a, t) = (x.floor(), x - x.floor());
        (1.0 - t) * a * a + t * (a + 1.0) * (a + 1.0)
    };
    for (x, y) in [(2.5, 2.5), (2.25, 3.5), (3.1, 2.7), (1.9, 4.05)] {
        let c = value(&cubic, x, y).unwrap();
        assert!((c - f(x, y)).abs() < 1e-12, "bicubic ({x}, {y}): {c}");
        let l = value(&linear, x, y).unwrap();
        let want = lin1(x) + 2.0 * lin1(y);
        assert!(
            (l - want).abs() < 1e-12,
            "bilinear ({x}, {y}): {l} vs {want}"
        );
        assert!(l > f(x, y), "chords lie above a convex function");
    }
}

/// A default-scenario run recorded at every step (`output.record_rate_hz = 100`), with `pairs`.
fn recorded(pairs: &[&str]) -> (RunResult, Vec<TraceRow>) {
    let mut sets: Vec<String> = vec!["output.record_rate_hz=100".into()];
    sets.extend(pairs.iter().map(|s| s.to_string()));
    let s = parse_scenario("", "<test>", &sets).unwrap();
    let mut rows = Vec::new();
    let r = s.run(&mut rows);
    (r, rows)
}

/// `metrics.steady_state_fraction`: the window is the last fraction of the run. The window's
/// max |eps| and RMS recomputed from the trace's error column match the summary's.
#[test]
fn steady_state_fraction_sets_the_window() {
    let mut maxima = vec![];
    for fraction in [0.2, 0.5, 0.9] {
        let (r, rows) = recorded(&[
            "initial.x_m=25",
            "sim.duration_s=200",
            &format!("metrics.steady_state_fraction={fraction}"),
        ]);
        assert_eq!(r.outcome, Outcome::Completed);
        assert_eq!(rows.len(), 20_001, "one row per step");
        let start = ((1.0 - fraction) * 20_000.0_f64).round() as usize;
        let window: Vec<f64> = rows[start..].iter().map(|row| row.error).collect();
        let max = window.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        let rms = (window.iter().map(|e| e * e).sum::<f64>() / window.len() as f64).sqrt();
        let m = &r.metrics;
        assert_eq!(
            m.steady_state_max_abs_error,
            Some(max),
            "fraction {fraction}"
        );
        let got_rms = m.steady_state_rms_error.unwrap();
        assert!((got_rms - rms).abs() <= 1e-12 * rms, "{got_rms} vs {rms}");
        maxima.push(max);
    }
    // A converging run: the longer window reaches back to larger errors.
    assert!(maxima[0] < maxima[1] && maxima[1] < maxima[2], "{maxima:?}");
}

/// `output.record_rate_hz`: 0 records nothing and changes no metric; 4 Hz records every 25th
/// step, at t = 0, 0.25, 0.5, ...
#[test]
fn record_rate_zero_records_nothing_and_changes_no_result() {
    let s = |rate: &str| {
        parse_scenario(
            "",
            "<test>",
            &[
                format!("output.record_rate_hz={rate}"),
                "sim.duration_s=60".into(),
            ],
        )
        .unwrap()
    };
    let mut none = Vec::new();
    let r0 = s("0").run(&mut none);
    assert!(none.is_empty(), "{} rows at rate 0", none.len());
    let mut four = Vec::new();
    let r4 = s("4").run(&mut four);
    assert_eq!(four.len(), 60 * 4 + 1);
    for (i, row) in four.iter().enumerate() {
        assert!(
            (row.t_s - 0.25 * i as f64).abs() < 1e-9,
            "row {i} at {}",
            row.t_s
        );
    }
    let r_none = s("0").run(&mut NoTrace);
    for r in [&r4, &r_none] {
        assert_eq!(r.outcome, r0.outcome);
        assert_eq!(format!("{:?}", r.metrics), format!("{:?}", r0.metrics));
    }
}

/// The integral term `ki*sigma` of each step, reconstructed from the trace alone: with a
/// noiseless sensor sampling every step, the law's `eps'` is the backward difference of the
/// trace's error column, `e = eps' + c1 tanh(eps/c2)`, and `ki*sigma = omega - kp*e`
/// (no turn-rate limit).
fn integral_terms(rows: &[TraceRow], kp: f64, c1: f64, c2: f64) -> Vec<f64> {
    rows.windows(2)
        .map(|w| {
            let eps_dot = (w[1].error - w[0].error) / (w[1].t_s - w[0].t_s);
            let e = eps_dot + c1 * (w[1].error / c2).tanh();
            w[1].omega_radps - kp * e
        })
        .collect()
}

/// `controller.anti_windup` with its parameters, from a far start where the plain integral
/// winds up: `clamp` bounds `|ki*sigma|` by `integral_limit_radps` and reaches it;
/// `conditional` freezes `sigma` while `|eps| >= integral_band`.
#[test]
fn anti_windup_parameters_act_as_documented() {
    let (kp, c1, c2) = (10.0, 0.2, 1.0);
    let far = ["initial.x_m=30", "sim.duration_s=150"];
    let (_, plain) = recorded(&far);
    let wound = integral_terms(&plain, kp, c1, c2)
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let limit = 0.3;
    assert!(wound > 2.0 * limit, "the plain integral winds up: {wound}");

    let (_, clamped) = recorded(&[
        far[0],
        far[1],
        "controller.anti_windup=\"clamp\"",
        &format!("controller.integral_limit_radps={limit}"),
    ]);
    let terms = integral_terms(&clamped, kp, c1, c2);
    let peak = terms.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        peak <= limit + 1e-9,
        "clamped integral term {peak} > {limit}"
    );
    assert!(peak >= limit - 1e-9, "the clamp is reached: {peak}");

    let band = 0.5;
    let (_, cond) = recorded(&[
        far[0],
        far[1],
        "controller.anti_windup=\"conditional\"",
        &format!("controller.integral_band={band}"),
    ]);
    let terms = integral_terms(&cond, kp, c1, c2);
    let (mut frozen, mut moving) = (0, 0);
    for (k, w) in terms.windows(2).enumerate() {
        // terms[k + 1] belongs to row k + 2; sigma changes there only if |eps| < band.
        let eps = cond[k + 2].error;
        if eps.abs() >= band {
            assert!((w[1] - w[0]).abs() < 1e-9, "sigma moved at |eps| = {eps}");
            frozen += 1;
        } else if (w[1] - w[0]).abs() > 1e-9 {
            moving += 1;
        }
    }
    assert!(
        frozen > 1000 && moving > 1000,
        "{frozen} frozen, {moving} moving"
    );

    // back_calculation with its tracking time: needs the limit, and the time constant matters.
    let bc = |tt: &str| {
        recorded(&[
            far[0],
            far[1],
            "controller.max_turn_rate_radps=1",
            "controller.anti_windup=\"back_calculation\"",
            &format!("controller.tracking_time_s={tt}"),
        ])
        .0
    };
    let (fast, slow) = (bc("0.5"), bc("20"));
    assert_eq!(
        (fast.outcome, slow.outcome),
        (Outcome::Completed, Outcome::Completed)
    );
    assert_ne!(
        fast.metrics.steady_state_max_abs_error,
        slow.metrics.steady_state_max_abs_error
    );
}

/// Every estimator of `eps'` (`controller.derivative` with its parameter) in the closed loop:
/// on a steady orbit `eps'` is 0, so with `ki = 0` each reaches the P-law's closed-form orbit,
/// `|eps*| = c2 atanh(v/(kp c1 d*))` (`radial_exp_p_orbit`), within 1 %. The Levant
/// differentiator's Lipschitz constant and the filter's time constant change the transient.
#[test]
fn every_estimator_reaches_the_p_law_orbit_in_closed_loop() {
    let (v, kp, c1, c2) = (0.5, 10.0, 0.2, 1.0);
    let orbit = radial_exp_p_orbit(20.0, 0.1, 10.0, v, kp, c1, c2).unwrap();
    let closed = c2 * (v / (kp * c1 * orbit.radius_m)).atanh();
    let mut transients = vec![];
    for est in [
        "controller.derivative=\"backward_difference\"",
        "controller.derivative=\"filtered_difference\"",
        "controller.derivative=\"levant\"",
    ] {
        for param in [
            "",
            "controller.derivative_tau_s=0.5",
            "controller.derivative_lipschitz=5",
        ] {
            let applies = match param {
                "" => true,
                p if p.contains("tau") => est.contains("filtered"),
                _ => est.contains("levant"),
            };
            if !applies {
                continue;
            }
            let mut sets = vec![
                est.to_string(),
                "controller.ki=0".into(),
                "sim.duration_s=800".into(),
            ];
            if !param.is_empty() {
                sets.push(param.into());
            }
            let s = parse_scenario("", "<test>", &sets).unwrap();
            let r = s.run(&mut NoTrace);
            assert_eq!(r.outcome, Outcome::Completed, "{sets:?}");
            let sim = r.metrics.steady_state_mean_error.unwrap();
            let rel = (sim.abs() - closed).abs() / closed;
            assert!(rel < 0.01, "{sets:?}: {sim} vs closed form {closed}");
            transients.push(r.metrics.path_length_m);
        }
    }
    // Five settings, five different transients (each parameter reaches the law).
    assert_eq!(transients.len(), 5);
    for i in 0..5 {
        for j in 0..i {
            assert_ne!(transients[i], transients[j], "settings {i} and {j}");
        }
    }
}

/// The UAV on a scheduled 0.1 rad/s turn for 150 s (more than two full circles).
fn uav_turn(extra: &[&str]) -> Vec<TraceRow> {
    let mut sets: Vec<String> = vec![
        "vehicle.kind=\"fixed_wing\"".into(),
        "controller.kind=\"schedule\"".into(),
        "controller.course_rate_radps=[[0.0, 0.1]]".into(),
        "sim.duration_s=150".into(),
        "output.record_rate_hz=10".into(),
    ];
    sets.extend(extra.iter().map(|s| s.to_string()));
    let s = parse_scenario("", "<test>", &sets).unwrap();
    let mut rows = Vec::new();
    assert_eq!(s.run(&mut rows).outcome, Outcome::Completed);
    rows
}

/// Ground speeds over the last 100 s, from the trace's positions (0.1 s apart).
fn ground_speeds(rows: &[TraceRow]) -> (f64, f64) {
    let tail = &rows[rows.len() - 1001..];
    let speeds: Vec<f64> = tail
        .windows(2)
        .map(|w| (w[1].x_m - w[0].x_m).hypot(w[1].y_m - w[0].y_m) / (w[1].t_s - w[0].t_s))
        .collect();
    let lo = speeds.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = speeds.iter().copied().fold(0.0, f64::max);
    (lo, hi)
}

/// `vehicle.wind_mps`: circling at 30 m/s airspeed in a 6 m/s wind, the ground speed runs
/// through `30 - 6` (into the wind) to `30 + 6` (with it), the wind triangle; calm, it stays
/// at 30.
#[test]
fn wind_makes_the_ground_speed_run_through_the_wind_triangle() {
    let (lo, hi) = ground_speeds(&uav_turn(&[]));
    assert!(lo > 29.5 && hi < 30.5, "calm: {lo} .. {hi}");
    let windy = uav_turn(&["vehicle.wind_mps=[6.0, 0.0]"]);
    let (lo, hi) = ground_speeds(&windy);
    assert!((lo - 24.0).abs() < 0.6, "into the wind: {lo}");
    assert!((hi - 36.0).abs() < 0.6, "with the wind: {hi}");
    // The airspeed the autopilot holds is unchanged by a steady wind.
    for row in &windy[windy.len() - 1000..] {
        let a = row.telemetry.unwrap().airspeed_mps;
        assert!((a - 30.0).abs() < 0.5, "airspeed {a}");
    }
}

/// `vehicle.gusts`: Dryden gusts change the flight (gusty != calm), seeded by `sim.seed`
/// (the same seed repeats it, another seed differs), and the airspeed wanders around its
/// command instead of holding it.
#[test]
fn gusts_change_the_flight_and_follow_the_seed() {
    let calm = uav_turn(&[]);
    let gusty = uav_turn(&["vehicle.gusts=true"]);
    let again = uav_turn(&["vehicle.gusts=true"]);
    let other = uav_turn(&["vehicle.gusts=true", "sim.seed=7"]);
    let end = |rows: &[TraceRow]| {
        let r = rows.last().unwrap();
        (r.x_m, r.y_m)
    };
    assert_ne!(end(&calm), end(&gusty));
    assert_eq!(end(&gusty), end(&again));
    assert_ne!(end(&gusty), end(&other));
    let spread = |rows: &[TraceRow]| {
        let a: Vec<f64> = rows[500..]
            .iter()
            .map(|r| r.telemetry.unwrap().airspeed_mps)
            .collect();
        let mean = a.iter().sum::<f64>() / a.len() as f64;
        (a.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
    };
    let (sc, sg) = (spread(&calm), spread(&gusty));
    assert!(sc < 0.05, "calm airspeed spread {sc}");
    assert!(
        sg > 5.0 * sc && sg > 0.1,
        "gusty airspeed spread {sg} vs calm {sc}"
    );
}
