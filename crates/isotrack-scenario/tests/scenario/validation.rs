//! Defaults and validation, key by key, against the README's "Scenario files" table: every
//! default it lists, and every range on both sides of its bound (the value at the bound accepted,
//! the next one refused, naming exactly the keys at fault and no other).

use isotrack_core::control::HigherSide;
use isotrack_scenario::resolve::{resolve, Issue};
use isotrack_scenario::schema::*;
use isotrack_scenario::ScenarioFile;

fn resolved(text: &str) -> Result<ScenarioFile, Vec<Issue>> {
    let file: ScenarioFile = toml::from_str(text).unwrap_or_else(|e| panic!("{text}: {e}"));
    resolve(file)
}

/// The keys `text` is refused for, sorted, one entry per issue (empty: accepted).
fn refused(text: &str) -> Vec<String> {
    match resolved(text) {
        Ok(_) => vec![],
        Err(issues) => {
            let mut keys: Vec<String> = issues.into_iter().map(|i| i.key).collect();
            keys.sort();
            keys
        }
    }
}

fn check(cases: &[(&str, &[&str])]) {
    let mut wrong = Vec::new();
    for (text, want) in cases {
        let got = refused(text);
        let mut want: Vec<String> = want.iter().map(|k| k.to_string()).collect();
        want.sort();
        if got != want {
            wrong.push(format!("{text:?}: refused for {got:?}, expected {want:?}"));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// [`check`] for cases whose text is built (`format!`).
fn check_built(cases: &[(String, Vec<&str>)]) {
    let cases: Vec<(&str, &[&str])> = cases
        .iter()
        .map(|(t, v)| (t.as_str(), v.as_slice()))
        .collect();
    check(&cases);
}

/// The README's defaults: the paper's Fig. 2(b) setting (Table III gains, start (10, 0, -pi/2)).
#[test]
fn an_empty_file_resolves_to_the_documented_defaults() {
    let f = resolved("").unwrap();
    assert_eq!(f.field.kind, Some(FieldKind::RadialExp));
    assert_eq!(f.field.i0, Some(20.0));
    assert_eq!(f.field.decay_per_m, Some(0.1));
    assert_eq!(f.field.center_m, Some([0.0, 0.0]));
    assert_eq!(f.vehicle.kind, Some(VehicleKind::Dubins));
    assert_eq!(f.vehicle.speed_mps, Some(0.5));
    assert_eq!(f.initial.x_m, Some(10.0));
    assert_eq!(f.initial.y_m, Some(0.0));
    assert_eq!(f.initial.heading_rad, Some(-std::f64::consts::FRAC_PI_2));
    assert_eq!(f.controller.kind, Some(ControllerKind::PiIsoline));
    assert_eq!(f.controller.level, Some(10.0));
    assert_eq!(
        (
            f.controller.kp,
            f.controller.ki,
            f.controller.c1,
            f.controller.c2
        ),
        (Some(10.0), Some(1.0), Some(0.2), Some(1.0))
    );
    assert_eq!(f.controller.higher_side, Some(HigherSide::Right));
    assert_eq!(f.controller.max_turn_rate_radps, None);
    assert_eq!(f.controller.anti_windup, Some(AntiWindupKind::None));
    assert_eq!(
        f.controller.derivative,
        Some(DerivativeKindName::BackwardDifference)
    );
    assert_eq!(f.controller.search, Some(SearchKind::None));
    assert_eq!(
        (f.sim.dt_s, f.sim.duration_s, f.sim.seed),
        (Some(0.01), Some(600.0), Some(0))
    );
    // sensor.rate_hz defaults to 1/sim.dt_s; the sensor is ideal.
    assert_eq!(f.sensor.rate_hz, Some(100.0));
    for v in [
        f.sensor.noise_std,
        f.sensor.delay_s,
        f.sensor.time_constant_s,
        f.sensor.resolution,
        f.sensor.dropout_probability,
        f.sensor.bias_drift_per_sqrt_s,
    ] {
        assert_eq!(v, Some(0.0));
    }
    assert_eq!(f.sensor.range, None);
    assert_eq!(f.metrics.steady_state_fraction, Some(0.2));
    // 1 % of |level|.
    assert_eq!(f.metrics.convergence_tolerance, Some(0.1));
    assert_eq!(f.output.record_rate_hz, Some(10.0));
}

/// Defaults that follow other keys (README): the rate follows the step, the tolerance the level,
/// the clamp the turn-rate limit or `kp*c1`, the band `c2`, the crossing turn rate the limit.
#[test]
fn derived_defaults_follow_their_keys() {
    let f = resolved("[sim]\ndt_s = 0.02\n").unwrap();
    assert_eq!(f.sensor.rate_hz, Some(50.0));
    let f = resolved("[controller]\nlevel = -4.0\n").unwrap();
    assert_eq!(f.metrics.convergence_tolerance, Some(0.04));
    let f = resolved("[controller]\nlevel = 0.0\n").unwrap();
    assert_eq!(f.metrics.convergence_tolerance, Some(0.01));
    let f = resolved("[controller]\nanti_windup = \"clamp\"\nkp = 4.0\nc1 = 0.5\n").unwrap();
    assert_eq!(f.controller.integral_limit_radps, Some(2.0));
    let f = resolved("[controller]\nanti_windup = \"clamp\"\nmax_turn_rate_radps = 0.7\n").unwrap();
    assert_eq!(f.controller.integral_limit_radps, Some(0.7));
    let f = resolved("[controller]\nanti_windup = \"conditional\"\nc2 = 3.0\n").unwrap();
    assert_eq!(f.controller.integral_band, Some(3.0));
    let f =
        resolved("[controller]\nanti_windup = \"back_calculation\"\nmax_turn_rate_radps = 1.0\n")
            .unwrap();
    assert_eq!(f.controller.tracking_time_s, Some(1.0));
    let f = resolved("[controller]\nderivative = \"filtered_difference\"\n").unwrap();
    assert_eq!(f.controller.derivative_tau_s, Some(0.1));
    let f = resolved("[controller]\nderivative = \"levant\"\n").unwrap();
    assert_eq!(f.controller.derivative_lipschitz, Some(1.0));
    let f = resolved("[controller]\nkind = \"pid_crossing\"\n").unwrap();
    assert_eq!(f.controller.crossing_turn_rate_radps, Some(0.5));
    assert_eq!(
        (f.controller.kp, f.controller.ki, f.controller.kd),
        (Some(3.0), Some(0.2), Some(10.0))
    );
    assert_eq!(f.controller.crossing_angle_rad, Some(0.3));
    assert_eq!(f.controller.crossing_period_s, Some(20.0));
    let f = resolved("[controller]\nkind = \"pid_crossing\"\nmax_turn_rate_radps = 0.8\n").unwrap();
    assert_eq!(f.controller.crossing_turn_rate_radps, Some(0.8));
    // The sliding modes act at the turn-rate limit: 1 rad/s unless given.
    for kind in ["sliding_mode", "sliding_mode_smooth", "suboptimal_sosm"] {
        let f = resolved(&format!("[controller]\nkind = \"{kind}\"\n")).unwrap();
        assert_eq!(f.controller.max_turn_rate_radps, Some(1.0), "{kind}");
    }
    let f = resolved("[controller]\nkind = \"sliding_mode_smooth\"\n").unwrap();
    assert_eq!(
        (
            f.controller.gamma,
            f.controller.delta,
            f.controller.boundary_layer
        ),
        (Some(0.2), Some(1.0), Some(0.05))
    );
    let f = resolved("[controller]\nkind = \"suboptimal_sosm\"\n").unwrap();
    assert_eq!(f.controller.alpha_star, Some(0.5));
    let f = resolved("[controller]\nkind = \"gradient_reference\"\n").unwrap();
    assert_eq!(
        (f.controller.ke, f.controller.k_heading),
        (Some(0.5), Some(1.0))
    );
    // The tracking laws get the default estimator; the open-loop and gradient laws none.
    assert_eq!(f.controller.derivative, None);
    for kind in ["pid", "sliding_mode", "suboptimal_sosm"] {
        let f = resolved(&format!("[controller]\nkind = \"{kind}\"\n")).unwrap();
        assert_eq!(
            f.controller.derivative,
            Some(DerivativeKindName::BackwardDifference),
            "{kind}"
        );
    }
    let f = resolved("[vehicle]\nkind = \"fixed_wing\"\n[sim]\ndt_s = 0.01\n").unwrap();
    assert_eq!(
        (f.vehicle.airspeed_mps, f.vehicle.altitude_m),
        (Some(30.0), Some(100.0))
    );
    assert_eq!(f.vehicle.wind_mps, Some([0.0, 0.0]));
    assert_eq!(
        (
            f.vehicle.gusts,
            f.vehicle.trim_feedforward,
            f.vehicle.ecen674_gains
        ),
        (Some(false), Some(true), Some(false))
    );
}

#[test]
fn field_defaults_per_kind() {
    let f = resolved("[field]\nkind = \"linear_ramp\"\n").unwrap();
    assert_eq!(
        (f.field.offset, f.field.gradient_per_m),
        (Some(0.0), Some([0.0, 1.0]))
    );
    let f = resolved("[field]\nkind = \"gaussian_plumes\"\n").unwrap();
    assert_eq!(f.field.background, Some(0.0));
    assert_eq!(f.field.sources.as_ref().map(Vec::len), Some(3));
    let f = resolved("[field]\nkind = \"puff_plume\"\n").unwrap();
    assert_eq!(f.field.source_m, Some([0.0, 0.0]));
    assert_eq!(
        (
            f.field.release_rate_hz,
            f.field.puff_mass,
            f.field.puff_sigma0_m,
            f.field.diffusivity_m2ps
        ),
        (Some(2.0), Some(10.0), Some(0.5), Some(0.05))
    );
    assert_eq!(f.field.wind_mps, Some([0.5, 0.0]));
    assert_eq!(
        (
            f.field.meander_std_mps,
            f.field.meander_correlation_s,
            f.field.max_age_s,
            f.field.background
        ),
        (Some(0.1), Some(20.0), Some(120.0), Some(0.0))
    );
    let f = resolved("[field]\nkind = \"grid\"\npath = \"a.csv\"\n").unwrap();
    assert_eq!(f.field.interpolation, Some(InterpolationName::Bicubic));
    assert_eq!(
        (
            f.field.value_log10,
            f.field.value_scale,
            f.field.value_offset
        ),
        (Some(false), Some(1.0), Some(0.0))
    );
    assert_eq!(
        f.field.time_interpolation,
        Some(TimeInterpolationName::Linear)
    );
    assert_eq!(
        (f.field.time_origin_s, f.field.time_scale),
        (Some(0.0), Some(1.0))
    );
    assert_eq!(f.field.after_last_frame, Some(AfterLastFrameName::Hold));
    let f =
        resolved("[field]\nkind = \"stations\"\npath = \"s.csv\"\nvalue_column = \"v\"\n").unwrap();
    assert_eq!(f.field.method, Some(StationMethod::Kriging));
    assert_eq!(f.field.idw_power, None);
    assert_eq!(f.field.interpolation, Some(InterpolationName::Bicubic));
    let f = resolved(
        "[field]\nkind = \"stations\"\npath = \"s.csv\"\nvalue_column = \"v\"\nmethod = \"idw\"\n",
    )
    .unwrap();
    assert_eq!(f.field.idw_power, Some(2.0));
}

#[test]
fn sim_and_initial_ranges() {
    check(&[
        ("[sim]\ndt_s = 0.0\n", &["sim.dt_s"]),
        ("[sim]\ndt_s = -0.01\n", &["sim.dt_s"]),
        ("[sim]\nduration_s = 0.0\n", &["sim.duration_s"]),
        // 1e300 s: more steps than the limit; 0.015 s: not a whole number of 0.01 s steps.
        ("[sim]\nduration_s = 1e300\n", &["sim.duration_s"]),
        ("[sim]\nduration_s = 0.015\n", &["sim.duration_s"]),
        ("[sim]\nduration_s = 0.02\n", &[]),
        ("[initial]\nx_m = 6.4e7\n", &[]),
        ("[initial]\nx_m = 6.41e7\n", &["initial.x_m"]),
        ("[initial]\ny_m = -6.41e7\n", &["initial.y_m"]),
        ("[initial]\nheading_rad = nan\n", &["initial.heading_rad"]),
        ("[initial]\nheading_rad = 100.0\n", &[]),
    ]);
}

#[test]
fn analytic_field_ranges() {
    check(&[
        ("[field]\ni0 = 0.0\n", &["field.i0"]),
        ("[field]\ni0 = 1e100\n", &[]),
        ("[field]\ni0 = 2e100\n", &["field.i0"]),
        ("[field]\ndecay_per_m = 0.0\n", &["field.decay_per_m"]),
        ("[field]\ncenter_m = [0.0, 6.41e7]\n", &["field.center_m"]),
        ("[field]\ncenter_m = [-6.4e7, 6.4e7]\n", &[]),
        ("[field]\noffset = 1.0\n", &["field.offset"]),
        ("[field]\ndomain_m = [-100.0, 100.0, -100.0, 100.0]\n", &[]),
        ("[field]\ndomain_m = [1.0, 1.0, -100.0, 100.0]\n", &["field.domain_m"]),
        ("[field]\ndomain_m = [-100.0, 100.0, 2.0, 1.0]\n", &["field.domain_m"]),
        ("[field]\ndomain_m = [-100.0, 100.0, 1.0, 1.0]\n", &["field.domain_m"]),
        ("[field]\ndomain_m = [2.0, 1.0, -100.0, 100.0]\n", &["field.domain_m"]),
        (
            "[field]\ndomain_m = [-7e7, 100.0, -100.0, 100.0]\n",
            &["field.domain_m"],
        ),
        ("[field]\ndrift_mps = [100.0, -100.0]\n", &[]),
        ("[field]\ndrift_mps = [0.0, 100.5]\n", &["field.drift_mps"]),
        ("[field]\nkind = \"linear_ramp\"\ngradient_per_m = [0.0, 0.0]\n", &["field.gradient_per_m"]),
        ("[field]\nkind = \"linear_ramp\"\ngradient_per_m = [1e-300, 0.0]\n", &[]),
        (
            "[field]\nkind = \"linear_ramp\"\ngradient_per_m = [0.0, 2e100]\noffset = -2e100\n",
            &["field.gradient_per_m", "field.offset"],
        ),
        ("[field]\nkind = \"linear_ramp\"\ni0 = 1.0\n", &["field.i0"]),
        ("[field]\nkind = \"gaussian_plumes\"\nsources = []\n", &["field.sources"]),
        (
            "[field]\nkind = \"gaussian_plumes\"\nbackground = nan\n",
            &["field.background"],
        ),
        (
            "[field]\nkind = \"gaussian_plumes\"\n[[field.sources]]\ncenter_m = [0.0, 7e7]\namplitude = 3e100\nsigma_m = [1e-9, 0.0]\nrotation_rad = inf\n",
            &[
                "field.sources[0].amplitude",
                "field.sources[0].center_m",
                "field.sources[0].rotation_rad",
                "field.sources[0].sigma_m",
            ],
        ),
    ]);
}

#[test]
fn puff_plume_ranges() {
    let p = "[field]\nkind = \"puff_plume\"\n";
    let cases: Vec<(String, Vec<&str>)> = vec![
        ("release_rate_hz = 0.0", vec!["field.release_rate_hz"]),
        ("puff_mass = 0.0", vec!["field.puff_mass"]),
        ("puff_mass = 2e100", vec!["field.puff_mass"]),
        ("puff_sigma0_m = 1e-9", vec![]),
        ("puff_sigma0_m = 1e-10", vec!["field.puff_sigma0_m"]),
        ("diffusivity_m2ps = 0.0", vec![]),
        ("diffusivity_m2ps = -0.1", vec!["field.diffusivity_m2ps"]),
        ("wind_mps = [100.5, 0.0]", vec!["field.wind_mps"]),
        ("meander_std_mps = 0.0", vec![]),
        ("meander_std_mps = -0.1", vec!["field.meander_std_mps"]),
        ("meander_std_mps = 101.0", vec!["field.meander_std_mps"]),
        (
            "meander_correlation_s = 0.0",
            vec!["field.meander_correlation_s"],
        ),
        ("max_age_s = 0.0", vec!["field.max_age_s"]),
        // At most 1e5 puffs alive at once: 1000 Hz x 100 s is the limit.
        ("release_rate_hz = 1000.0\nmax_age_s = 100.0", vec![]),
        (
            "release_rate_hz = 1000.0\nmax_age_s = 100.5",
            vec!["field.max_age_s"],
        ),
        ("source_m = [6.5e7, 0.0]", vec!["field.source_m"]),
        ("background = -2e100", vec!["field.background"]),
        ("i0 = 1.0", vec!["field.i0"]),
    ]
    .into_iter()
    .map(|(k, v)| (format!("{p}{k}\n"), v))
    .collect();
    check_built(&cases);
}

#[test]
fn grid_and_stations_keys() {
    let g = "[field]\nkind = \"grid\"\n";
    let st = "[field]\nkind = \"stations\"\n";
    let text: Vec<(String, Vec<&str>)> = vec![
        (g.to_string(), vec!["field.path"]),
        (format!("{g}path = \"\"\n"), vec!["field.path"]),
        (
            format!("{g}path = \"a.csv\"\npaths = [\"a.csv\"]\nframe_times_s = [0.0]\n"),
            vec!["field.paths"],
        ),
        (
            format!("{g}paths = []\n"),
            vec!["field.frame_times_s", "field.paths"],
        ),
        (
            format!("{g}paths = [\"a.csv\", \"\"]\nframe_times_s = [0.0, 1.0]\n"),
            vec!["field.paths"],
        ),
        (
            format!("{g}paths = [\"a.csv\", \"b.csv\"]\nframe_times_s = [0.0, 1.0]\n"),
            vec![],
        ),
        (
            format!("{g}paths = [\"a.csv\", \"b.csv\"]\nframe_times_s = [0.0]\n"),
            vec!["field.frame_times_s"],
        ),
        (
            format!("{g}paths = [\"a.csv\", \"b.csv\"]\nframe_times_s = [1.0, 1.0]\n"),
            vec!["field.frame_times_s"],
        ),
        (
            format!("{g}paths = [\"a.csv\", \"b.csv\"]\nframe_times_s = [nan, 1.0]\n"),
            vec!["field.frame_times_s"],
        ),
        (
            format!("{g}path = \"a.nc\"\nframe_times_s = [0.0, 1.0]\nframe_interval_s = 1.0\n"),
            vec!["field.frame_interval_s"],
        ),
        (
            format!("{g}path = \"a.npy\"\nframe_interval_s = 3600.0\n"),
            vec![],
        ),
        (
            format!("{g}path = \"a.npy\"\nframe_interval_s = 0.0\n"),
            vec!["field.frame_interval_s"],
        ),
        (
            format!("{g}path = \"a.npy\"\ntime_scale = 0.0\ntime_origin_s = inf\n"),
            vec!["field.time_origin_s", "field.time_scale"],
        ),
        (
            format!("{g}path = \"a.csv\"\ncrop_cells = [0, 1, 0, 1]\n"),
            vec![],
        ),
        (
            format!("{g}path = \"a.csv\"\ncrop_cells = [2, 2, 0, 1]\n"),
            vec!["field.crop_cells"],
        ),
        (
            format!("{g}path = \"a.csv\"\ncrop_cells = [0, 1, 3, 3]\n"),
            vec!["field.crop_cells"],
        ),
        (format!("{g}path = \"a.csv\"\nvalue_floor = 0.0\n"), vec![]),
        (
            format!("{g}path = \"a.csv\"\nvalue_floor = 0.0\nvalue_log10 = true\n"),
            vec!["field.value_floor"],
        ),
        (
            format!("{g}path = \"a.csv\"\nvalue_floor = 1e-12\nvalue_log10 = true\n"),
            vec![],
        ),
        (
            format!("{g}path = \"a.csv\"\nvalue_floor = nan\n"),
            vec!["field.value_floor"],
        ),
        (
            format!("{g}path = \"a.csv\"\nvalue_scale = 0.0\nvalue_offset = nan\n"),
            vec!["field.value_offset", "field.value_scale"],
        ),
        (format!("{g}path = \"a.csv\"\nvalue_scale = -1.0\n"), vec![]),
        (
            format!("{g}path = \"a.csv\"\nspacing_m = [1.0, 0.0]\norigin_m = [0.0, nan]\n"),
            vec!["field.origin_m", "field.spacing_m"],
        ),
        (
            format!("{g}path = \"a.csv\"\ndomain_m = [0.0, 1.0, 0.0, 1.0]\n"),
            vec!["field.domain_m"],
        ),
        (st.to_string(), vec!["field.path", "field.value_column"]),
        (
            format!("{st}path = \"s.csv\"\nvalue_column = \"\"\n"),
            vec!["field.value_column"],
        ),
        (
            format!("{st}path = \"s.csv\"\nvalue_column = \"v\"\nidw_power = 2.0\n"),
            vec!["field.idw_power"],
        ),
        (
            format!(
                "{st}path = \"s.csv\"\nvalue_column = \"v\"\nmethod = \"idw\"\nidw_power = 0.0\n"
            ),
            vec!["field.idw_power"],
        ),
        (
            format!("{st}path = \"s.csv\"\nvalue_column = \"v\"\ngrid_spacing_m = 0.0\n"),
            vec!["field.grid_spacing_m"],
        ),
        (
            format!("{st}path = \"s.csv\"\nvalue_column = \"v\"\nspacing_m = [-1.0, 1.0]\n"),
            vec!["field.spacing_m"],
        ),
        (
            format!("{st}path = \"s.csv\"\nvalue_column = \"v\"\ncrop_cells = [0, 1, 0, 1]\n"),
            vec!["field.crop_cells"],
        ),
    ];
    check_built(&text);
}

#[test]
fn vehicle_ranges() {
    let fw = "[vehicle]\nkind = \"fixed_wing\"\n";
    let text: Vec<(String, Vec<&str>)> = vec![
        ("[vehicle]\nspeed_mps = 1000.0\n".into(), vec![]),
        (
            "[vehicle]\nspeed_mps = 1000.5\n".into(),
            vec!["vehicle.speed_mps"],
        ),
        (
            "[vehicle]\nspeed_mps = 0.0\n".into(),
            vec!["vehicle.speed_mps"],
        ),
        (
            "[vehicle]\nairspeed_mps = 30.0\n".into(),
            vec!["vehicle.airspeed_mps"],
        ),
        (format!("{fw}airspeed_mps = 15.0\n"), vec![]),
        (format!("{fw}airspeed_mps = 45.0\n"), vec![]),
        (
            format!("{fw}airspeed_mps = 14.9\n"),
            vec!["vehicle.airspeed_mps"],
        ),
        (
            format!("{fw}airspeed_mps = 45.1\n"),
            vec!["vehicle.airspeed_mps"],
        ),
        (
            format!("{fw}airspeed_mps = 0.0\n"),
            vec!["vehicle.airspeed_mps"; 2],
        ),
        (
            format!("{fw}altitude_m = 50.0\n"),
            vec!["vehicle.altitude_m"],
        ),
        (format!("{fw}altitude_m = 50.5\n"), vec![]),
        (format!("{fw}altitude_m = 20000.0\n"), vec![]),
        (
            format!("{fw}altitude_m = 20000.5\n"),
            vec!["vehicle.altitude_m"],
        ),
        (
            format!("{fw}altitude_m = nan\n"),
            vec!["vehicle.altitude_m"],
        ),
        (format!("{fw}wind_mps = [-100.0, 100.0]\n"), vec![]),
        (
            format!("{fw}wind_mps = [-100.5, 0.0]\n"),
            vec!["vehicle.wind_mps"],
        ),
        (format!("{fw}speed_mps = 1.0\n"), vec!["vehicle.speed_mps"]),
        // The autopilot runs at the step: at most 0.02 s.
        (format!("{fw}[sim]\ndt_s = 0.02\n"), vec![]),
        (format!("{fw}[sim]\ndt_s = 0.025\n"), vec!["sim.dt_s"]),
        ("[sim]\ndt_s = 0.05\n".into(), vec![]),
    ];
    check_built(&text);
}

#[test]
fn sensor_ranges() {
    check(&[
        ("[sensor]\nrate_hz = 0.0\n", &["sensor.rate_hz"]),
        // The period must be a whole number of 0.01 s steps: 1/30 s is not, 1/20 s is.
        ("[sensor]\nrate_hz = 30.0\n", &["sensor.rate_hz"]),
        ("[sensor]\nrate_hz = 20.0\n", &[]),
        ("[sensor]\nrate_hz = 200.0\n", &["sensor.rate_hz"]),
        ("[sensor]\nnoise_std = -0.1\n", &["sensor.noise_std"]),
        ("[sensor]\ndelay_s = -0.01\n", &["sensor.delay_s"]),
        ("[sensor]\ndelay_s = 0.015\n", &["sensor.delay_s"]),
        ("[sensor]\ndelay_s = 0.5\n", &[]),
        // At most sim.duration_s.
        ("[sensor]\ndelay_s = 10.0\n[sim]\nduration_s = 10.0\n", &[]),
        (
            "[sensor]\ndelay_s = 10.5\n[sim]\nduration_s = 10.0\n",
            &["sensor.delay_s"],
        ),
        (
            "[sensor]\ntime_constant_s = -1.0\n",
            &["sensor.time_constant_s"],
        ),
        ("[sensor]\nresolution = -1.0\n", &["sensor.resolution"]),
        // Issue 30 item 14: a resolution of 1e-310 made every reading `inf` (value/resolution
        // overflows) and the run "completed"; the settings in field units are bounded.
        ("[sensor]\nresolution = 1e-310\n", &["sensor.resolution"]),
        ("[sensor]\nresolution = 1e-101\n", &["sensor.resolution"]),
        ("[sensor]\nresolution = 1e-100\n", &[]),
        ("[sensor]\nresolution = 1e101\n", &["sensor.resolution"]),
        ("[sensor]\nnoise_std = 1e300\n", &["sensor.noise_std"]),
        ("[sensor]\nnoise_std = 5e-324\n", &["sensor.noise_std"]),
        (
            "[sensor]\nbias_drift_per_sqrt_s = 1e200\n",
            &["sensor.bias_drift_per_sqrt_s"],
        ),
        (
            "[sensor]\nbias_drift_per_sqrt_s = -1.0\n",
            &["sensor.bias_drift_per_sqrt_s"],
        ),
        ("[sensor]\ndropout_probability = 0.999\n", &[]),
        (
            "[sensor]\ndropout_probability = 1.0\n",
            &["sensor.dropout_probability"],
        ),
        (
            "[sensor]\ndropout_probability = -0.01\n",
            &["sensor.dropout_probability"],
        ),
        ("[sensor]\nrange = [0.0, 1.0]\n", &[]),
        ("[sensor]\nrange = [1.0, 1.0]\n", &["sensor.range"]),
        ("[sensor]\nrange = [2.0, 1.0]\n", &["sensor.range"]),
        ("[sensor]\nrange = [0.0, inf]\n", &["sensor.range"]),
        (
            "[sensor]\nrange = [nan, 1.0]\n",
            &["sensor.range", "sensor.range"],
        ),
    ]);
}

/// The `Hz` values a refusal of `key` suggests, in order.
fn suggested_rates(text: &str, key: &str) -> Vec<f64> {
    let issues = resolved(text).expect_err(text);
    let issue = issues.iter().find(|i| i.key == key).expect(key);
    let m = &issue.message;
    let tail = m
        .split_once("the nearest valid rate")
        .unwrap_or_else(|| panic!("{key} suggests no valid rate: {m}"))
        .1;
    tail.split(" Hz")
        .filter_map(|part| part.rsplit(' ').next()?.parse::<f64>().ok())
        .collect()
}

/// A sensor rate whose period is not a whole number of steps names the valid rates either side,
/// `1/(k dt)`: 3 Hz at dt = 0.01 s is 33.3 steps, so 1/0.34 s = 2.941 Hz and 1/0.33 s = 3.030 Hz;
/// at dt = 0.03 s, 0.7 Hz is 47.6 steps: 1/1.44 s and 1/1.41 s. Above 1/dt only 1/dt itself
/// (one step) is near. Each suggested number, typed back as written, is accepted.
#[test]
fn an_invalid_rate_names_the_nearest_valid_rates() {
    // (The trace's default 10 Hz is no whole number of 0.03 s steps either: off there.)
    let cases: [(&str, f64, f64, &str, Vec<f64>); 4] = [
        (
            "sensor.rate_hz",
            3.0,
            0.01,
            "",
            vec![1.0 / 0.34, 1.0 / 0.33],
        ),
        (
            "sensor.rate_hz",
            0.7,
            0.03,
            "[output]\nrecord_rate_hz = 0.0\n",
            vec![1.0 / 1.44, 1.0 / 1.41],
        ),
        ("sensor.rate_hz", 200.0, 0.01, "", vec![100.0]),
        (
            "output.record_rate_hz",
            3.0,
            0.01,
            "",
            vec![1.0 / 0.34, 1.0 / 0.33],
        ),
    ];
    for (key, rate, dt, extra, want) in cases {
        let (section, name) = key.split_once('.').unwrap();
        let text = |r: f64| format!("{extra}[{section}]\n{name} = {r:?}\n[sim]\ndt_s = {dt:?}\n");
        let got = suggested_rates(&text(rate), key);
        assert_eq!(got.len(), want.len(), "{}: {got:?}", text(rate));
        for (g, w) in got.iter().zip(&want) {
            assert!(
                (g / w - 1.0).abs() < 1e-8,
                "{key} {rate}: suggested {g}, want {w}"
            );
            assert_eq!(refused(&text(*g)), Vec::<String>::new(), "{}", text(*g));
        }
    }
}

#[test]
fn controller_ranges_and_kinds() {
    check(&[
        ("[controller]\nkp = 0.0\n", &["controller.kp"]),
        ("[controller]\nki = 0.0\n", &[]),
        ("[controller]\nki = -1.0\n", &["controller.ki"]),
        ("[controller]\nc1 = 0.0\nc2 = -1.0\n", &["controller.c1", "controller.c2"]),
        ("[controller]\nlevel = 2e100\n", &["controller.level"]),
        ("[controller]\nmax_turn_rate_radps = 0.0\n", &["controller.max_turn_rate_radps"]),
        ("[controller]\ngamma = 0.2\n", &["controller.gamma"]),
        ("[controller]\nkind = \"sliding_mode\"\nkp = 1.0\n", &["controller.kp"]),
        ("[controller]\nkind = \"sliding_mode\"\ngamma = 0.0\ndelta = 0.0\n", &["controller.delta", "controller.gamma"]),
        ("[controller]\nkind = \"sliding_mode\"\nboundary_layer = 0.1\n", &["controller.boundary_layer"]),
        ("[controller]\nkind = \"sliding_mode_smooth\"\nboundary_layer = 0.0\n", &["controller.boundary_layer"]),
        ("[controller]\nkind = \"suboptimal_sosm\"\nalpha_star = 1.0\n", &[]),
        ("[controller]\nkind = \"suboptimal_sosm\"\nalpha_star = 1.01\n", &["controller.alpha_star"]),
        ("[controller]\nkind = \"suboptimal_sosm\"\nalpha_star = 0.0\n", &["controller.alpha_star"]),
        ("[controller]\nkind = \"suboptimal_sosm\"\nalpha_star = nan\n", &["controller.alpha_star"]),
        ("[controller]\nkind = \"pid\"\nkp = 0.0\nki = 0.0\nkd = 0.0\n", &[]),
        ("[controller]\nkind = \"pid\"\nkd = -1.0\n", &["controller.kd"]),
        ("[controller]\nkind = \"pid\"\ncrossing_angle_rad = 0.3\n", &["controller.crossing_angle_rad"]),
        ("[controller]\nkind = \"pid_crossing\"\ncrossing_angle_rad = 0.0\ncrossing_period_s = 0.0\ncrossing_turn_rate_radps = 0.0\n", &["controller.crossing_angle_rad", "controller.crossing_period_s", "controller.crossing_turn_rate_radps"]),
        ("[controller]\nkind = \"gradient_reference\"\nke = 0.0\nk_heading = 0.0\n", &["controller.k_heading", "controller.ke"]),
        ("[controller]\nkind = \"gradient_reference\"\nderivative = \"levant\"\n", &["controller.derivative"]),
        ("[controller]\nkind = \"schedule\"\n", &["controller.course_rate_radps"]),
        ("[controller]\nkind = \"schedule\"\ncourse_rate_radps = [[0.0, 0.1], [5.0, -0.1]]\n", &[]),
        ("[controller]\nkind = \"schedule\"\ncourse_rate_radps = [[0.0, 0.1], [0.0, -0.1]]\n", &["controller.course_rate_radps[1]"]),
        ("[controller]\nkind = \"schedule\"\ncourse_rate_radps = [[0.0, nan]]\n", &["controller.course_rate_radps[0]"]),
        ("[controller]\nkind = \"schedule\"\nkp = 1.0\n", &["controller.course_rate_radps", "controller.kp"]),
    ]);
}

#[test]
fn anti_windup_estimator_and_search_keys() {
    check(&[
        ("[controller]\nintegral_band = 1.0\n", &["controller.integral_band"]),
        ("[controller]\nanti_windup = \"clamp\"\nintegral_band = 1.0\n", &["controller.integral_band"]),
        ("[controller]\nanti_windup = \"clamp\"\nintegral_limit_radps = 0.0\n", &["controller.integral_limit_radps"]),
        ("[controller]\nanti_windup = \"conditional\"\nintegral_band = 0.0\n", &["controller.integral_band"]),
        ("[controller]\nanti_windup = \"conditional\"\ntracking_time_s = 1.0\n", &["controller.tracking_time_s"]),
        ("[controller]\nanti_windup = \"back_calculation\"\n", &["controller.anti_windup"]),
        ("[controller]\nanti_windup = \"back_calculation\"\nmax_turn_rate_radps = 1.0\ntracking_time_s = 0.0\n", &["controller.tracking_time_s"]),
        ("[controller]\nanti_windup = \"back_calculation\"\nmax_turn_rate_radps = 1.0\nintegral_limit_radps = 1.0\n", &["controller.integral_limit_radps"]),
        ("[controller]\nderivative_tau_s = 0.1\n", &["controller.derivative_tau_s"]),
        ("[controller]\nderivative = \"filtered_difference\"\nderivative_tau_s = 0.0\n", &["controller.derivative_tau_s"]),
        ("[controller]\nderivative = \"filtered_difference\"\nderivative_lipschitz = 1.0\n", &["controller.derivative_lipschitz"]),
        ("[controller]\nderivative = \"levant\"\nderivative_lipschitz = 0.0\n", &["controller.derivative_lipschitz"]),
        ("[controller]\nderivative = \"levant\"\nderivative_tau_s = 1.0\n", &["controller.derivative_tau_s"]),
        ("[controller]\nsearch_spacing_m = 1.0\n", &["controller.search_spacing_m"]),
        ("[controller]\nsearch = \"spiral\"\nsearch_spacing_m = 1.0\nsearch_handover = 0.1\n", &[]),
        ("[controller]\nsearch = \"spiral\"\nsearch_leg_m = 10.0\n", &["controller.search_leg_m"]),
        ("[controller]\nsearch = \"lawnmower\"\nsearch_leg_m = 10.0\nsearch_spacing_m = 1e-9\n", &[]),
        ("[controller]\nsearch = \"lawnmower\"\nsearch_leg_m = 1e-10\n", &["controller.search_leg_m"]),
        ("[controller]\nsearch = \"lawnmower\"\nsearch_spacing_m = 7e7\n", &["controller.search_spacing_m"]),
        ("[controller]\nsearch = \"spiral\"\nsearch_handover = 0.0\n", &["controller.search_handover"]),
        ("[controller]\nsearch = \"spiral\"\nsearch_handover = 2e100\n", &["controller.search_handover"]),
    ]);
}

#[test]
fn metrics_and_output_ranges() {
    check(&[
        ("[metrics]\nsteady_state_fraction = 1.0\n", &[]),
        (
            "[metrics]\nsteady_state_fraction = 0.0\n",
            &["metrics.steady_state_fraction"],
        ),
        (
            "[metrics]\nsteady_state_fraction = 1.01\n",
            &["metrics.steady_state_fraction"],
        ),
        (
            "[metrics]\nsteady_state_fraction = nan\n",
            &["metrics.steady_state_fraction"],
        ),
        (
            "[metrics]\nconvergence_tolerance = 0.0\n",
            &["metrics.convergence_tolerance"],
        ),
        // The band is at least the tolerance (0.1 by default at level 10).
        ("[metrics]\ntrack_loss_band = 0.1\n", &[]),
        (
            "[metrics]\ntrack_loss_band = 0.09\n",
            &["metrics.track_loss_band"],
        ),
        (
            "[metrics]\ntrack_loss_band = 0.5\nconvergence_tolerance = 0.6\n",
            &["metrics.track_loss_band"],
        ),
        ("[metrics]\nconvergence_min_dwell_s = 600.0\n", &[]),
        ("[metrics]\nconvergence_min_dwell_s = 0.0\n", &[]),
        (
            "[metrics]\nconvergence_min_dwell_s = 600.5\n",
            &["metrics.convergence_min_dwell_s"],
        ),
        (
            "[metrics]\nconvergence_min_dwell_s = 20.0\n[sim]\nduration_s = 10.0\n",
            &["metrics.convergence_min_dwell_s"],
        ),
        (
            "[metrics]\nconvergence_min_dwell_s = -1.0\n",
            &["metrics.convergence_min_dwell_s"],
        ),
        ("[output]\nrecord_rate_hz = 0.0\n", &[]),
        ("[output]\nrecord_rate_hz = 100.0\n", &[]),
        (
            "[output]\nrecord_rate_hz = -1.0\n",
            &["output.record_rate_hz"],
        ),
        (
            "[output]\nrecord_rate_hz = 30.0\n",
            &["output.record_rate_hz"],
        ),
        // At most 1e8 trace rows: 1e6 s at 100 Hz is 1e8 + 1.
        (
            "[output]\nrecord_rate_hz = 100.0\n[sim]\nduration_s = 999999.99\n",
            &[],
        ),
        (
            "[output]\nrecord_rate_hz = 100.0\n[sim]\nduration_s = 1000000.0\n",
            &["output.record_rate_hz"],
        ),
        (
            "[output]\nrecord_rate_hz = 0.0\n[sim]\nduration_s = 1000000.0\n",
            &[],
        ),
    ]);
}

/// Every problem is reported at once, not the first only.
#[test]
fn all_problems_are_reported_together() {
    let got = refused("[sim]\ndt_s = 0.0\n[controller]\nkp = 0.0\n[sensor]\nnoise_std = -1.0\n");
    assert_eq!(got, ["controller.kp", "sensor.noise_std", "sim.dt_s"]);
}

/// The names of the laws are the README's, and each reads back as its kind.
#[test]
fn controller_kind_names_round_trip() {
    let names = [
        "pi_isoline",
        "schedule",
        "sliding_mode",
        "sliding_mode_smooth",
        "suboptimal_sosm",
        "pid",
        "pid_crossing",
        "gradient_reference",
    ];
    for name in names {
        let kind: ControllerKind = toml::Value::String(name.into()).try_into().unwrap();
        assert_eq!(kind.name(), name);
        if kind != ControllerKind::Schedule {
            assert_eq!(ControllerKind::from_name(name), Some(kind));
        }
    }
    assert_eq!(ControllerKind::from_name("bogus"), None);
    assert_eq!(ControllerKind::ALL.len(), names.len() - 1);
}

/// Switching laws carries the shared keys and the estimator (to the laws that differentiate
/// the measurement), never a gain; the same kind is the section itself.
#[test]
fn switched_to_carries_the_shared_keys_only() {
    let pi = resolved(
        "[controller]\nlevel = 5.0\nmax_turn_rate_radps = 0.8\nhigher_side = \"left\"\nkp = 3.0\nderivative = \"levant\"\nderivative_lipschitz = 2.0\n",
    )
    .unwrap()
    .controller;
    let pid = pi.switched_to(ControllerKind::Pid);
    assert_eq!(pid.kind, Some(ControllerKind::Pid));
    assert_eq!(
        (pid.level, pid.max_turn_rate_radps, pid.higher_side),
        (Some(5.0), Some(0.8), Some(HigherSide::Left))
    );
    assert_eq!(pid.derivative, Some(DerivativeKindName::Levant));
    assert_eq!(pid.derivative_lipschitz, Some(2.0));
    assert_eq!((pid.kp, pid.ki, pid.c1), (None, None, None));
    for kind in [ControllerKind::GradientReference, ControllerKind::Schedule] {
        let other = pi.switched_to(kind);
        assert_eq!(other.derivative, None, "{kind:?}");
        assert_eq!(other.derivative_lipschitz, None, "{kind:?}");
        assert_eq!(other.level, Some(5.0));
    }
    assert_eq!(pi.switched_to(ControllerKind::PiIsoline), pi);
    // The search phase is the scenario's, not a law's: every law flies it (compare's fairness:
    // from a flat start only the law given a search could find the isoline).
    let searching = resolved(
        "[controller]\nsearch = \"lawnmower\"\nsearch_spacing_m = 3.0\nsearch_leg_m = 40.0\nsearch_handover = 0.5\n",
    )
    .unwrap()
    .controller;
    for kind in ControllerKind::ALL {
        let other = searching.switched_to(kind);
        assert_eq!(
            (
                other.search,
                other.search_spacing_m,
                other.search_leg_m,
                other.search_handover
            ),
            (
                Some(SearchKind::Lawnmower),
                Some(3.0),
                Some(40.0),
                Some(0.5)
            ),
            "{kind:?}"
        );
    }
    // Every switched section resolves (the schedule needs its pairs).
    for kind in ControllerKind::ALL {
        let mut f: ScenarioFile = toml::from_str("").unwrap();
        f.controller = pi.switched_to(kind);
        assert!(resolve(f).is_ok(), "{kind:?}");
    }
}

/// A start outside the field's domain names the coordinate that is out (both: `x`).
#[test]
fn a_start_outside_the_domain_names_its_coordinate() {
    let domain = "[field]\ndomain_m = [-20.0, 20.0, -20.0, 20.0]\n";
    for (start, key) in [
        ("x_m = 10.0\ny_m = 30.0", Some("initial.y_m")),
        ("x_m = 30.0\ny_m = 0.0", Some("initial.x_m")),
        ("x_m = 30.0\ny_m = 30.0", Some("initial.x_m")),
        ("x_m = 20.0\ny_m = -20.0", None),
    ] {
        let text = format!("{domain}[initial]\n{start}\n");
        let got = isotrack_scenario::parse_scenario(&text, "<test>", &[]);
        let keys: Vec<Option<String>> = match &got {
            Ok(_) => vec![],
            Err(e) => e.issues().iter().map(|i| i.key.clone()).collect(),
        };
        let want: Vec<Option<String>> = key.iter().map(|k| Some(k.to_string())).collect();
        assert_eq!(keys, want, "{start}");
    }
}

/// Numbers in messages: plain when ordinary, scientific when huge or tiny (a value of 1e300 is
/// not echoed as 301 digits).
#[test]
fn numbers_in_messages_stay_short() {
    for (text, shown) in [
        ("[initial]\nx_m = 1e300\n", "got 1e300"),
        ("[controller]\nkp = 0.0\n", "got 0"),
        ("[controller]\nkp = -0.5\n", "got -0.5"),
        ("[sensor]\nnoise_std = -1e-7\n", "got -1e-7"),
    ] {
        let issues = resolved(text).unwrap_err();
        assert!(
            issues[0].message.contains(shown),
            "{text}: {}",
            issues[0].message
        );
        assert!(issues[0].message.len() < 120, "{}", issues[0].message);
    }
}

/// An override's error stays located at its `--set` when a later override switches a kind
/// (the switch forgets only the switched section's earlier overrides), and a key of another
/// kind set on a derived scenario is refused, not dropped.
#[test]
fn overrides_keep_their_location_across_a_kind_switch() {
    let sets: Vec<String> = ["sensor.noise_std=-1", "controller.kind=\"sliding_mode\""]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let e = isotrack_scenario::parse_scenario("", "s.toml", &sets)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--set sensor.noise_std=-1"), "{e}");
    let s = isotrack_scenario::parse_scenario("", "s.toml", &[]).unwrap();
    let e = s
        .derive(&["controller.boundary_layer=0.1".into()], "<test>")
        .unwrap_err()
        .to_string();
    assert!(e.contains("boundary_layer"), "{e}");
}

/// `[sitl]`: the home position's ranges (README), at and past each bound; unset, the section
/// stays out of the resolved file and the defaults are PX4's SITL home.
#[test]
fn sitl_home_ranges() {
    check(&[
        (
            "[sitl]\nhome_lat_deg = 89.0\nhome_lon_deg = -180.0\nhome_alt_m = 10000.0\n",
            &[],
        ),
        (
            "[sitl]\nhome_lat_deg = -89.0\nhome_lon_deg = 180.0\nhome_alt_m = -1000.0\n",
            &[],
        ),
        ("[sitl]\nhome_lat_deg = 89.01\n", &["sitl.home_lat_deg"]),
        ("[sitl]\nhome_lat_deg = nan\n", &["sitl.home_lat_deg"]),
        ("[sitl]\nhome_lon_deg = 180.5\n", &["sitl.home_lon_deg"]),
        ("[sitl]\nhome_alt_m = -1000.5\n", &["sitl.home_alt_m"]),
        ("[sitl]\nhome_alt_m = inf\n", &["sitl.home_alt_m"]),
    ]);
    let f = resolved("").unwrap();
    assert!(f.sitl.is_unset());
    assert_eq!(
        (
            f.sitl.home_lat_deg(),
            f.sitl.home_lon_deg(),
            f.sitl.home_alt_m()
        ),
        (47.397742, 8.545594, 488.0)
    );
    assert!(!toml::to_string(&f).unwrap().contains("[sitl]"));
    let f = resolved("[sitl]\nhome_alt_m = 12.5\n").unwrap();
    assert!(toml::to_string(&f)
        .unwrap()
        .contains("[sitl]\nhome_alt_m = 12.5"));
    assert!(toml::from_str::<ScenarioFile>("[sitl]\nhome_height_m = 3.0\n").is_err());
}

/// A `--set` value is one TOML value, parsed on its own: a newline cannot add a second key and
/// a `#` cannot hide the rest (a hostile review: `sim.duration_s=7.0\nsim.seed=3` set the
/// duration and silently dropped the seed; `sim.duration_s=7 # c` was accepted); bare words
/// (a kind, a name with spaces) stay strings.
#[test]
fn set_values_are_one_toml_value() {
    let parse = |set: &str| isotrack_scenario::parse_scenario("", "s.toml", &[set.to_string()]);
    for bad in [
        "sim.duration_s=7.0\nsim.seed=3",
        "sim.duration_s=7 # c",
        "sim.duration_s=7\r\nsim.seed=3",
        "name=[1, 2",
    ] {
        let e = parse(bad).unwrap_err().to_string();
        assert!(e.contains("is not one TOML value"), "{bad:?}: {e}");
    }
    let s = parse("sim.duration_s=7").unwrap();
    assert_eq!(s.file().sim.duration_s, Some(7.0));
    let s = parse("name=my run").unwrap();
    assert_eq!(s.file().name.as_deref(), Some("my run"));
    let s = parse("vehicle.kind=dubins").unwrap();
    assert_eq!(s.file().name, None);
}

/// The keys of a section as the schema itself names them: serde's "expected one of" list for an
/// unknown key (no hand-kept list).
fn schema_keys<T: serde::de::DeserializeOwned + std::fmt::Debug>() -> Vec<String> {
    let e = toml::from_str::<T>("zz_not_a_key = 1")
        .unwrap_err()
        .to_string();
    let list = e.split_once(", expected ").unwrap().1;
    list.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

/// A value `key` takes in section `T` (the first of a few shapes that reads).
fn a_value_of<T: serde::de::DeserializeOwned>(key: &str) -> String {
    [
        "1.0",
        "[1.0, 2.0]",
        "[0, 1, 0, 1]",
        "[0.0, 1.0, 0.0, 1.0]",
        "\"x\"",
        "true",
        "[\"x\"]",
        "[1.0]",
        "[[0.0, 0.1]]",
        "[{ center_m = [0.0, 0.0], amplitude = 1.0, sigma_m = [1.0, 1.0] }]",
        "\"bilinear\"",
        "\"idw\"",
        "\"csv\"",
        "\"cubic\"",
        "\"end\"",
        "\"conditional\"",
        "\"levant\"",
        "\"spiral\"",
        "\"left\"",
        "\"fixed_wing\"",
        "\"pid\"",
    ]
    .into_iter()
    .find(|v| toml::from_str::<T>(&format!("{key} = {v}")).is_ok())
    .unwrap_or_else(|| panic!("no test value reads as {key}"))
    .to_string()
}

/// Every key of `[field]`, `[controller]` and `[vehicle]`, as the schema names them (a key added
/// to the schema is in this test without editing a list), is refused under some kind ("does not
/// apply to") and taken under another, except the kind itself and the keys every kind shares.
#[test]
fn every_schema_key_is_checked_against_the_kinds() {
    let kinds = |section: &str| -> Vec<String> {
        let e = toml::from_str::<ScenarioFile>(&format!("[{section}]\nkind = \"zz\"\n"))
            .unwrap_err()
            .to_string();
        let list = e.split_once(", expected ").unwrap().1;
        list.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    let shared: &[(&str, &[&str])] = &[
        ("field", &["kind", "units"]),
        ("vehicle", &["kind"]),
        (
            "controller",
            &[
                "kind",
                "level",
                "higher_side",
                "max_turn_rate_radps",
                "search",
                "search_spacing_m",
                "search_leg_m",
                "search_handover",
            ],
        ),
    ];
    for (section, keys, value) in [
        (
            "field",
            schema_keys::<FieldSection>(),
            a_value_of::<FieldSection> as fn(&str) -> String,
        ),
        (
            "controller",
            schema_keys::<ControllerSection>(),
            a_value_of::<ControllerSection>,
        ),
        (
            "vehicle",
            schema_keys::<VehicleSection>(),
            a_value_of::<VehicleSection>,
        ),
    ] {
        let kinds = kinds(section);
        assert!(kinds.len() >= 2, "{section}: {kinds:?}");
        let shared = shared.iter().find(|(s, _)| *s == section).unwrap().1;
        assert!(keys.len() > shared.len() + 3, "{section}: {keys:?}");
        for key in keys.iter().filter(|k| !shared.contains(&k.as_str())) {
            let v = value(key);
            let refused = |kind: &str| {
                let text = format!("[{section}]\nkind = \"{kind}\"\n{key} = {v}\n");
                let full = format!("{section}.{key}");
                let kind_msg = format!("does not apply to {section}.kind = ");
                resolved(&text).err().is_some_and(|issues| {
                    issues
                        .iter()
                        .any(|i| i.key == full && i.message.starts_with(&kind_msg))
                })
            };
            let by_kind: Vec<bool> = kinds.iter().map(|k| refused(k)).collect();
            assert!(
                by_kind.iter().any(|r| *r) && by_kind.iter().any(|r| !*r),
                "{section}.{key} = {v}: refused by kind {kinds:?}: {by_kind:?}"
            );
        }
    }
}
