//! Issue 11: time-varying gridded fields. The three ways to give frames (a NetCDF time axis, a
//! 3-D `.npy` with an interval, a list of 2-D files with times) make the same run on the same
//! data; the bundled ERA5 scenario tracks its isotherm.

use isotrack_scenario::{load_scenario, parse_scenario_in};
use isotrack_sim::{NoTrace, RunResult};
use std::path::Path;

fn data() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/era5_t2m_uk")
}

/// The ERA5 UAV setting over `frames` hours from frame 132, with `field` keys.
fn run(field: &str, dir: &Path) -> (RunResult, isotrack_scenario::Scenario) {
    let text = format!(
        "[sim]\ndt_s = 0.01\nduration_s = 1800.0\n[field]\nkind = \"grid\"\n{field}\n\
         [vehicle]\nkind = \"fixed_wing\"\naltitude_m = 300.0\n\
         [initial]\nx_m = 305253.0\ny_m = 750566.0\nheading_rad = -1.5707963267948966\n\
         [sensor]\nrate_hz = 1.0\n[controller]\nlevel = 4.0\nkp = 150.0\nki = 0.0\nc1 = 0.0005\nc2 = 0.1\n"
    );
    let s = parse_scenario_in(&text, "<test>", &[], dir).unwrap();
    (s.run(&mut NoTrace), s)
}

#[test]
fn netcdf_npy_and_file_list_make_the_same_run() {
    let d = data();
    let (nc, s) = run(
        "path = \"era5_t2m_uk.nc\"\nvariable = \"t2m\"\ntime_origin_s = 475200.0",
        &d,
    );
    let sp = s.file().field.spacing_m.unwrap();
    let (npy, _) = run(
        &format!(
            "path = \"era5_t2m_uk.npy\"\nframe_interval_s = 3600.0\ntime_origin_s = 475200.0\nspacing_m = [{:?}, {:?}]\norigin_m = [0.0, 0.0]",
            sp[0], sp[1]
        ),
        &d,
    );
    // Frames 132..=134 as CSV files, field time from 0.
    let tmp = tempfile::tempdir().unwrap();
    let series = isotrack_fields::io::load_series(&d.join("era5_t2m_uk.npy"), None, None).unwrap();
    let mut names = vec![];
    for k in 132..=134 {
        let g = &series.frames[k];
        let text: String = (0..g.ny())
            .map(|iy| {
                (0..g.nx())
                    .map(|ix| format!("{:?}", g.at(ix, iy)))
                    .collect::<Vec<_>>()
                    .join(",")
                    + "\n"
            })
            .collect();
        let name = format!("f{k}.csv");
        std::fs::write(tmp.path().join(&name), text).unwrap();
        names.push(format!("{name:?}"));
    }
    let (list, _) = run(
        &format!(
            "paths = [{}]\nframe_times_s = [0.0, 3600.0, 7200.0]\nspacing_m = [{:?}, {:?}]\norigin_m = [0.0, 0.0]",
            names.join(", "),
            sp[0],
            sp[1]
        ),
        tmp.path(),
    );
    assert_eq!(nc.outcome, isotrack_sim::Outcome::Completed);
    assert_eq!(nc, npy, "NetCDF and .npy");
    assert_eq!(nc, list, "NetCDF and a file list");
}

/// The bundled scenario: the UAV holds the moving 4 degC isotherm for 7 hours within a few
/// thousandths of a degree, and within a kilometre of the (time-interpolated) isotherm.
#[test]
fn the_era5_isotherm_scenario_tracks() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/era5-isotherm-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.outcome, isotrack_sim::Outcome::Completed);
    assert_eq!(r.t_end_s, 25200.0);
    let m = &r.metrics;
    assert!(m.steady_state_max_abs_error.unwrap() < 0.01, "{m:?}");
    assert!(
        m.steady_state_max_isoline_distance_m.unwrap() < 1000.0,
        "{m:?}"
    );
}

/// Past the last frame with `after_last_frame = "end"` the run ends, saying the data ended.
#[test]
fn the_data_can_end() {
    let d = data();
    let (r, _) = run(
        "path = \"era5_t2m_uk.nc\"\nvariable = \"t2m\"\ntime_origin_s = 600000.0\nafter_last_frame = \"end\"",
        &d,
    );
    // The last frame is at 167 h = 601200 s of field time: 1200 s into the run.
    assert_eq!(r.outcome, isotrack_sim::Outcome::LeftField);
    assert!((r.t_end_s - 1200.0).abs() <= 0.01, "{}", r.t_end_s);
    assert!(r.outcome_detail.unwrap().contains("data ended"));
}

/// Only a run that ends because the data ended is explained so: a robot that drives off a
/// series' grid while frames remain ends with the position it left at, and a run that
/// completes carries no detail.
#[test]
fn only_the_data_ending_is_explained_as_such() {
    let d = tempfile::tempdir().unwrap();
    for (name, v) in [("a.csv", 0.0), ("b.csv", 1.0)] {
        let rows: Vec<String> = (0..11)
            .map(|j| vec![format!("{}", j as f64 + v); 11].join(","))
            .collect();
        std::fs::write(d.path().join(name), rows.join("\n") + "\n").unwrap();
    }
    // F = y + t/100 on [0, 10]^2 for 100 s of frames; the robot starts at (5, 5) heading east
    // at 0.5 m/s with a P law too weak to turn it (kp = 1e-6): it leaves at x = 10 near t = 10 s.
    let text = |extra: &str| {
        format!(
            "[field]\nkind = \"grid\"\npaths = [\"a.csv\", \"b.csv\"]\nframe_times_s = [0.0, 100.0]\nafter_last_frame = \"end\"\ninterpolation = \"bilinear\"\n[initial]\nx_m = 5.0\ny_m = 5.0\nheading_rad = 0.0\n[controller]\nlevel = 5.0\nkp = 1e-6\nki = 0.0\n[sim]\nduration_s = 50.0\n{extra}"
        )
    };
    let s = parse_scenario_in(&text(""), "s.toml", &[], d.path()).unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.outcome, isotrack_sim::Outcome::LeftField);
    assert!(r.t_end_s > 9.0 && r.t_end_s < 11.0, "{}", r.t_end_s);
    let detail = r.outcome_detail.unwrap();
    assert!(
        detail.contains("no value at") && !detail.contains("data ended"),
        "{detail}"
    );
    // Inside the grid for the whole run (heading north from the middle, 5 s): completed.
    let s = parse_scenario_in(
        &text("").replace("duration_s = 50.0", "duration_s = 5.0"),
        "s.toml",
        &["initial.heading_rad=1.5707963267948966".into()],
        d.path(),
    )
    .unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.outcome, isotrack_sim::Outcome::Completed);
    assert_eq!(r.outcome_detail, None);
    // The last frame one step after the step that found no value: the next step would still
    // have had data, so the robot left the grid, the data did not end.
    let half_second_steps = text("dt_s = 0.5\n[output]\nrecord_rate_hz = 0.0\n");
    let s = parse_scenario_in(&half_second_steps, "s.toml", &[], d.path()).unwrap();
    let left = s.run(&mut NoTrace).t_end_s;
    let last_frame = left + 0.5;
    let text_last = half_second_steps.replace(
        "frame_times_s = [0.0, 100.0]",
        &format!("frame_times_s = [0.0, {last_frame:?}]"),
    );
    let r = parse_scenario_in(&text_last, "s.toml", &[], d.path())
        .unwrap()
        .run(&mut NoTrace);
    assert_eq!(r.outcome, isotrack_sim::Outcome::LeftField);
    assert_eq!(r.t_end_s, left, "the same step leaves the grid");
    let detail = r.outcome_detail.unwrap();
    assert!(!detail.contains("data ended"), "{detail}");
}

/// Sensor dynamics in a run: every sample is delivered or counted as dropped (exactly, for a
/// seeded run), the keys are recorded in the resolved scenario, and a lagged, quantised,
/// saturating, drifting sensor still lets the default scenario track.
#[test]
fn sensor_dynamics_in_a_run() {
    let sets: Vec<String> = [
        "sensor.dropout_probability=0.1",
        "sensor.time_constant_s=0.5",
        "sensor.resolution=0.001",
        "sensor.range=[0.0, 50.0]",
        "sensor.bias_drift_per_sqrt_s=0.0001",
        "controller.derivative=filtered_difference",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let s = load_scenario(None, &sets).unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.samples + r.samples_dropped, 60_001);
    assert!(
        (5_000..7_000).contains(&r.samples_dropped),
        "{}",
        r.samples_dropped
    );
    assert_eq!(r, s.run(&mut NoTrace), "seeded: the same run again");
    assert_eq!(s.file().sensor.time_constant_s, Some(0.5));
    assert!(
        r.metrics.steady_state_max_abs_error.unwrap() < 0.1,
        "{:?}",
        r.metrics
    );
    let e = load_scenario(None, &["sensor.dropout_probability=1.0".into()]).unwrap_err();
    assert!(e.to_string().contains("sensor.dropout_probability"), "{e}");
}

/// `check` on the bundled ERA5 scenario: the isotherm moves (metres per second, well below the
/// UAV's 30 m/s), so it is trackable; the report says how it was sampled.
#[test]
fn check_reports_the_isoline_speed() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/era5-isotherm-uav.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let m = isotrack_scenario::check::check(&s, None).moving;
    assert!(m.time_varying);
    let (max, p95) = (
        m.isoline_speed_max_mps.unwrap(),
        m.isoline_speed_p95_mps.unwrap(),
    );
    assert!(p95 > 0.1 && p95 <= max && max < 30.0, "{m:?}");
    assert_eq!(m.trackable, Some(true));
    assert!(m.samples > 100);
}

/// The puff plume: the same seed, the same run; another seed (also through `derive`, as a
/// sweep does) another meander and another run; the bundled edge-tracking scenario holds the
/// plume's edge most of the time.
#[test]
fn puff_plume_runs_are_seeded() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/puff-plume-edge.toml");
    let s = load_scenario(Some(&p), &["sim.duration_s=120.0".into()]).unwrap();
    let a = s.run(&mut NoTrace);
    assert_eq!(a, s.run(&mut NoTrace));
    let other = s.derive(&["sim.seed=5".into()], "<test>").unwrap();
    assert_ne!(a, other.run(&mut NoTrace), "the meander follows sim.seed");
    let again = other.derive(&["sim.seed=0".into()], "<test>").unwrap();
    assert_eq!(a, again.run(&mut NoTrace));
    let m = isotrack_scenario::check::check(&s, None).moving;
    assert!(m.time_varying && m.isoline_speed_max_mps.is_some(), "{m:?}");
}

/// The puff plume's isoline metric is the distance to the isoline of its long-run mean (the
/// Gaussian plume): at x = 20 m downwind the level-3 isoline is at
/// `y = sy sqrt(2 ln(C0/3))`, `sy^2 = 0.25 + 2*0.05*20/0.5`, `C0 = 20/(0.5 sqrt(2 pi) sy)`.
#[test]
fn puff_isoline_metric_is_the_mean_plume() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/puff-plume-edge.toml");
    let s = load_scenario(Some(&p), &[]).unwrap();
    let sy = (0.25f64 + 2.0 * 0.05 * 20.0 / 0.5).sqrt();
    let c0 = 20.0 / (0.5 * (2.0 * std::f64::consts::PI).sqrt() * sy);
    let y = sy * (2.0 * (c0 / 3.0).ln()).sqrt();
    let iso = s.isoline();
    let on = iso
        .distance(0.0, isotrack_core::Vec2::new(20.0, y))
        .unwrap();
    assert!(on < 0.05, "{on}");
    let off = iso
        .distance(0.0, isotrack_core::Vec2::new(20.0, y + 1.0))
        .unwrap();
    assert!((off - 1.0).abs() < 0.1, "{off}");
}

/// A puff plume in a 1 m/s wind along x without meander (the default release: 2 puffs of 10
/// per second), tracked at level 0.2, with further `[field]` keys `extra`.
fn plume_at_level_0_2(extra: &str) -> isotrack_scenario::Scenario {
    isotrack_scenario::parse_scenario(
        &format!("[field]\nkind = \"puff_plume\"\nwind_mps = [1.0, 0.0]\nmeander_std_mps = 0.0\n{extra}[controller]\nlevel = 0.2\n[initial]\nx_m = 5.0\n"),
        "<test>",
        &[],
    )
    .unwrap()
}

/// Where the 2-D Gaussian plume of [`plume_at_level_0_2`] crosses 0.2 at `x` m downwind: `y =
/// s sqrt(2 ln(C0/0.2))`, `s^2 = sigma0^2 + 2 K x/u`, `C0 = 20/(u sqrt(2 pi) s)`, u = 1 m/s.
fn gaussian_plume_isoline_y(sigma0_m: f64, diffusivity_m2ps: f64, x: f64) -> f64 {
    let s2 = sigma0_m * sigma0_m + 2.0 * diffusivity_m2ps * x;
    let c0 = 20.0 / (2.0 * std::f64::consts::PI * s2).sqrt();
    (2.0 * s2 * (c0 / 0.2).ln()).sqrt()
}

/// The mean plume's isoline is drawn over the plume's reach and width, `u T` downwind plus
/// `4 sqrt(sigma0^2 + 2 K T)` about the source: a wide, short-lived plume (u = 1 m/s, T = 20 s,
/// K = 5.62 m^2/s: a window of +-80 m) still has its level-0.2 isoline at x = 60 m, where the
/// 2-D Gaussian plume puts it at `y = s sqrt(2 ln(C0/0.2))`, `s^2 = 0.25 + 2 K x/u`,
/// `C0 = 20/(u sqrt(2 pi) s)`.
#[test]
fn a_wide_plumes_isoline_is_drawn_to_its_width() {
    let s = plume_at_level_0_2("max_age_s = 20.0\ndiffusivity_m2ps = 5.62\n");
    let x = 60.0;
    let y = gaussian_plume_isoline_y(0.5, 5.62, x);
    assert!((y - 24.0).abs() < 1.0, "{y}");
    let iso = s.isoline();
    let on = iso.distance(0.0, isotrack_core::Vec2::new(x, y)).unwrap();
    assert!(on < 0.05, "{on}");
    let off = iso
        .distance(0.0, isotrack_core::Vec2::new(x, y + 1.0))
        .unwrap();
    assert!((off - 1.0).abs() < 0.1, "{off}");
}

/// The value transform with each of its keys alone (floor, log10, scale, offset: each one on
/// its own is applied), a bad frame of a series named by its index, and several files without
/// times refused.
#[test]
fn value_transform_keys_alone_and_frame_errors() {
    use isotrack_core::{math::Vec2, ScalarField};
    let d = tempfile::tempdir().unwrap();
    let write = |name: &str, v: f64| {
        let row = vec![format!("{v}"); 4].join(",");
        std::fs::write(d.path().join(name), format!("{row}\n{row}\n{row}\n{row}\n")).unwrap();
    };
    write("hundred.csv", 100.0);
    write("zero.csv", 0.0);
    let base = "[field]\nkind = \"grid\"\npath = \"hundred.csv\"\ninterpolation = \"bilinear\"\n[initial]\nx_m = 1.5\ny_m = 1.5\n[controller]\nlevel = 1.0\n";
    let p = Vec2::new(1.5, 1.5);
    for (set, want) in [
        ("field.value_floor=150.0", 150.0),
        ("field.value_log10=true", 2.0),
        ("field.value_scale=0.5", 50.0),
        ("field.value_offset=-30.0", 70.0),
    ] {
        let s = parse_scenario_in(base, "s.toml", &[set.into()], d.path()).unwrap();
        let got = s.field().value(0.0, p).unwrap();
        assert!((got - want).abs() < 1e-12, "{set}: {got}");
    }
    // A series whose second frame cannot take the log: the message names the frame.
    let series = "[field]\nkind = \"grid\"\npaths = [\"hundred.csv\", \"zero.csv\"]\nframe_times_s = [0.0, 10.0]\nvalue_log10 = true\n[initial]\nx_m = 1.5\ny_m = 1.5\n[controller]\nlevel = 1.0\n";
    let e = parse_scenario_in(series, "s.toml", &[], d.path())
        .unwrap_err()
        .to_string();
    assert!(e.contains("frame 1: the grid has values <= 0"), "{e}");
    // One frame alone: no frame number.
    let one = base.replace("hundred.csv", "zero.csv");
    let e = parse_scenario_in(&one, "s.toml", &["field.value_log10=true".into()], d.path())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the grid has values <= 0") && !e.contains("frame 0"),
        "{e}"
    );
    // Two files and no times.
    let untimed = series
        .replace("frame_times_s = [0.0, 10.0]\n", "")
        .replace("value_log10 = true\n", "");
    let e = parse_scenario_in(&untimed, "s.toml", &[], d.path())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("field.frame_times_s`: is required with field.paths"),
        "{e}"
    );
}

/// Field time counts from the first frame, whatever the frames' own times: frames at 100 s and
/// 200 s (constant 1 and 3) give 1 at t = 0, 2 at t = 50 s and 3 at t = 100 s.
#[test]
fn field_time_starts_at_the_first_frame() {
    use isotrack_core::{math::Vec2, ScalarField};
    use isotrack_scenario::field::FieldModel;
    let d = tempfile::tempdir().unwrap();
    for (name, v) in [("a.csv", 1.0), ("b.csv", 3.0)] {
        let row = vec![format!("{v}"); 4].join(",");
        std::fs::write(d.path().join(name), format!("{row}\n{row}\n{row}\n{row}\n")).unwrap();
    }
    let text = "[field]\nkind = \"grid\"\npaths = [\"a.csv\", \"b.csv\"]\nframe_times_s = [100.0, 200.0]\ninterpolation = \"bilinear\"\n[initial]\nx_m = 1.5\ny_m = 1.5\n[controller]\nlevel = 2.0\n";
    let s = parse_scenario_in(text, "s.toml", &[], d.path()).unwrap();
    // The isoline moves with the frames, recomputed every eighth of the 100 s between them.
    let iso = format!("{:?}", s.isoline());
    assert!(
        iso.contains("MovingIsoline(level 2, every 12.5 s)"),
        "{iso}"
    );
    let FieldModel::Series(series) = s.field() else {
        panic!("not a series")
    };
    let p = Vec2::new(1.5, 1.5);
    for (t, want) in [(0.0, 1.0), (50.0, 2.0), (100.0, 3.0)] {
        let got = series.value(t, p).unwrap();
        assert!((got - want).abs() < 1e-12, "t = {t}: {got}");
    }
}

/// A puff plume's isoline metric is the long-run mean plume's isoline: on the axis it crosses
/// the level where the 2-D Gaussian plume `R M / (u sqrt(2 pi) sigma)`,
/// `sigma^2 = sigma0^2 + 2 K x / u`, equals it (the defaults and level 10: x = 11.5 m; the
/// along-wind diffusion this slender-plume formula leaves out moves it by about 0.25 m at this
/// Peclet number, u x / K = 115).
#[test]
fn the_puff_plume_isoline_is_the_mean_plumes() {
    use isotrack_core::math::Vec2;
    let s = isotrack_scenario::parse_scenario(
        "[field]\nkind = \"puff_plume\"\n[controller]\nlevel = 10.0\n[initial]\nx_m = 5.0\n",
        "<test>",
        &[],
    )
    .unwrap();
    let (rate, mass, u, sigma0, k, level) = (2.0, 10.0, 0.5, 0.5, 0.05, 10.0);
    let sigma = rate * mass / (u * (2.0 * std::f64::consts::PI).sqrt() * level);
    let x = (sigma * sigma - sigma0 * sigma0) / (2.0 * k) * u;
    assert!((x - 11.5).abs() < 0.1, "{x}");
    let d = s.isoline().distance(0.0, Vec2::new(x, 0.0)).unwrap();
    assert!(d < 0.5, "{d} m from the isoline");
    // Off the plume, the distance is at least the way back to it.
    let far = s.isoline().distance(0.0, Vec2::new(x, 20.0)).unwrap();
    assert!(far > 15.0, "{far}");
}

/// The mean plume's isoline window ends exactly `u T + 4 sqrt(sigma0^2 + 2 K T)` downwind of the
/// source, on a lattice of `u T / 400` m (here u = 1 m/s, T = 400 s, sigma0 = 5 m,
/// K = 0.09375 m^2/s: 400 + 40 = 440 m on a 1 m lattice, every number exact). The level-0.2
/// isoline still runs there: at x = 440 m the 2-D Gaussian plume puts it at
/// `y = s sqrt(2 ln(C0/0.2))`, `s^2 = 25 + 2 K x/u = 107.5`, `C0 = 20/(u sqrt(2 pi) s)`. It is
/// drawn up to the window's edge and not a lattice cell beyond.
#[test]
fn the_mean_plumes_isoline_ends_at_the_windows_edge() {
    use isotrack_core::math::Vec2;
    let s =
        plume_at_level_0_2("max_age_s = 400.0\npuff_sigma0_m = 5.0\ndiffusivity_m2ps = 0.09375\n");
    let x = 440.0;
    let y = gaussian_plume_isoline_y(5.0, 0.09375, x);
    assert!((y - 17.0).abs() < 0.1, "{y}");
    let iso = s.isoline();
    let on = iso.distance(0.0, Vec2::new(x, y)).unwrap();
    assert!(on < 0.02, "{on} m from the isoline at the window's edge");
    // One metre past the edge the nearest point is the isoline's end, about 1 m back.
    let past = iso.distance(0.0, Vec2::new(x + 1.0, y)).unwrap();
    assert!((past - 1.0).abs() < 0.02, "{past}");
}

/// Issue 30 item 19: a time axis read from a file that cannot make a series (times not
/// increasing) is blamed on the file (`field.path`, naming it), not on
/// `field.frame_times_s (default value)`, which the scenario never set.
#[test]
fn a_bad_time_axis_in_a_file_is_the_files() {
    use netcdf3::{DataSet, FileWriter, Version};
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("bad_times.nc");
    let mut ds = DataSet::new();
    ds.add_fixed_dim("time", 3).unwrap();
    ds.add_fixed_dim("lat", 3).unwrap();
    ds.add_fixed_dim("lon", 3).unwrap();
    ds.add_var_f64("time", &["time"]).unwrap();
    ds.add_var_attr_string("time", "units", "hours since 2019-03-01 00:00:00")
        .unwrap();
    ds.add_var_f64("lat", &["lat"]).unwrap();
    ds.add_var_attr_string("lat", "units", "degrees_north")
        .unwrap();
    ds.add_var_f64("lon", &["lon"]).unwrap();
    ds.add_var_attr_string("lon", "units", "degrees_east")
        .unwrap();
    ds.add_var_f64("v", &["time", "lat", "lon"]).unwrap();
    let mut w = FileWriter::create_new(&path).unwrap();
    w.set_def(&ds, Version::Classic, 0).unwrap();
    w.write_var_f64("time", &[0.0, 2.0, 1.0]).unwrap();
    w.write_var_f64("lat", &[50.0, 50.01, 50.02]).unwrap();
    w.write_var_f64("lon", &[10.0, 10.01, 10.02]).unwrap();
    w.write_var_f64("v", &(0..27).map(f64::from).collect::<Vec<_>>())
        .unwrap();
    w.close().unwrap();
    let text = "[field]\nkind = \"grid\"\npath = \"bad_times.nc\"\nvariable = \"v\"\n[initial]\nx_m = 700.0\ny_m = 1100.0\n";
    let e = isotrack_scenario::parse_scenario_in(text, "s.toml", &[], d.path())
        .unwrap_err()
        .to_string();
    assert!(e.contains("`field.path`"), "{e}");
    assert!(e.contains("bad_times.nc"), "{e}");
    assert!(!e.contains("frame_times_s"), "{e}");
    assert!(e.contains("the time axis read from"), "{e}");
}

/// Issue 30: a NetCDF variable's CF `units` (the xarray fixtures' `v` is in `K`) becomes
/// `field.units` when the scenario leaves it unset, recorded in the resolved scenario (so the
/// run directory's plots and report show it); a `field.units` that says otherwise is kept and
/// warned about naming both; a value transform leaves it unset, with a warning.
#[test]
fn a_netcdf_variables_units_are_the_fields_unless_the_scenario_says_otherwise() {
    let dir =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../isotrack-fields/tests/fixtures/netcdf");
    let sc = |extra: &str| {
        parse_scenario_in(
            &format!(
                "[field]\nkind = \"grid\"\npath = \"netcdf4_nc4_xy_contig.nc\"\n{extra}\n\
                 [initial]\nx_m = 502000.0\ny_m = 4604000.0\n[controller]\nlevel = 12.0\n"
            ),
            "<test>",
            &[],
            &dir,
        )
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let warnings = |s: &isotrack_scenario::Scenario| isotrack_scenario::check::warnings(s);
    let units_warning = |w: &[String]| w.iter().find(|l| l.contains("`K`")).cloned();

    let s = sc("");
    assert_eq!(s.file().field.units.as_deref(), Some("K"));
    assert_eq!(units_warning(&warnings(&s)), None);
    // Recorded: the resolved scenario (what a run directory keeps) says it.
    let toml = toml::to_string(s.file()).unwrap();
    assert!(toml.contains("units = \"K\""), "{toml}");
    // Derived without touching the field: same units, no warning.
    let d = s.derive(&["sim.duration_s=10.0".into()], "<set>").unwrap();
    assert_eq!(d.file().field.units.as_deref(), Some("K"));
    assert_eq!(units_warning(&warnings(&d)), None);

    let s = sc("units = \"degC\"");
    assert_eq!(s.file().field.units.as_deref(), Some("degC"));
    let w = units_warning(&warnings(&s)).expect("a warning naming both units");
    assert!(w.contains("field.units = \"degC\""), "{w}");
    assert!(w.contains("netcdf4_nc4_xy_contig.nc"), "{w}");
    // The same through a derived scenario.
    let d = sc("")
        .derive(&["field.units=\"ppm\"".into()], "<set>")
        .unwrap();
    let w = units_warning(&warnings(&d)).expect("a warning naming both units");
    assert!(w.contains("field.units = \"ppm\""), "{w}");

    let s = sc("value_offset = 0.5");
    assert_eq!(s.file().field.units, None);
    let w = units_warning(&warnings(&s)).expect("a warning about the transform");
    assert!(w.contains("value_offset"), "{w}");
}
