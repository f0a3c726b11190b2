//! The spec's defaults against the README's table ("Scenario files"), an independent source,
//! and the derived values against their formulas.

use super::*;
use crate::parse_scenario;
use crate::schema::ControllerKind;
use isotrack_core::control::{AntiWindup, HigherSide, SearchPattern};
use isotrack_core::estimate::DerivativeKind;

fn spec_of(text: &str) -> ScenarioSpec {
    parse_scenario(text, "<test>", &[]).unwrap().spec().clone()
}

/// An empty file: the README's defaults, every section.
#[test]
fn an_empty_file_has_the_readme_defaults() {
    let s = spec_of("");
    assert_eq!(
        s.sim,
        SimSpec {
            dt_s: 0.01,
            duration_s: 600.0,
            seed: 0
        }
    );
    assert_eq!(s.vehicle, VehicleSpec::Dubins { speed_mps: 0.5 });
    assert_eq!(
        (s.start.x_m, s.start.y_m, s.start.heading_rad),
        (10.0, 0.0, -std::f64::consts::FRAC_PI_2)
    );
    // sensor.rate_hz = 1/sim.dt_s = 100 Hz; the rest off.
    assert_eq!(s.sensor.rate_hz, 100.0);
    assert_eq!(
        [
            s.sensor.noise_std,
            s.sensor.delay_s,
            s.sensor.time_constant_s,
            s.sensor.resolution,
            s.sensor.dropout_probability,
            s.sensor.bias_drift_per_sqrt_s
        ],
        [0.0; 6]
    );
    assert_eq!(s.sensor.range, None);
    let c = &s.controller;
    assert_eq!(c.kind, ControllerKind::PiIsoline);
    assert_eq!(c.turn_rate_limit, TurnRateLimit::None);
    assert_eq!(c.search, None);
    let p = c.pi_isoline().unwrap();
    // Paper Table III: level 10, kp 10, ki 1, c1 0.2, c2 1.
    assert_eq!(
        (p.level, p.kp, p.ki, p.c1, p.c2),
        (10.0, 10.0, 1.0, 0.2, 1.0)
    );
    assert_eq!(p.anti_windup, AntiWindup::None);
    assert_eq!(p.derivative, DerivativeKind::BackwardDifference);
    assert_eq!(p.output.higher_side, HigherSide::Right);
    assert_eq!(p.output.max_turn_rate_radps, None);
    // Tolerance 1 % of |level| = 0.1; dwell 10 % of 600 s; band 5 tolerances.
    assert_eq!(
        s.metrics,
        MetricsSpec {
            steady_state_fraction: 0.2,
            convergence_tolerance: 0.1,
            convergence_min_dwell_s: 60.0,
            track_loss_band: 0.5,
        }
    );
    assert_eq!(s.output.record_rate_hz, 10.0);
    assert_eq!(
        (s.sitl.home_lat_deg, s.sitl.home_lon_deg, s.sitl.home_alt_m),
        (47.397742, 8.545594, 488.0)
    );
}

/// Each law's own defaults (README, `controller.kind`; the PID's are the linearisation of the
/// default PI-like law: `kp*c1/c2 + ki` = 3, `ki*c1/c2` = 0.2, `kd = kp` = 10).
#[test]
fn each_law_has_its_documented_defaults() {
    let law = |kind: &str| spec_of(&format!("[controller]\nkind = \"{kind}\"\n")).controller;
    match law("pid").law {
        LawSpec::Pid(p) => assert_eq!((p.kp, p.ki, p.kd), (3.0, 0.2, 10.0)),
        l => panic!("{l:?}"),
    }
    match law("pid_crossing").law {
        LawSpec::PidCrossing(p) => {
            assert_eq!((p.pid.kp, p.pid.ki, p.pid.kd), (3.0, 0.2, 10.0));
            assert_eq!(
                (p.crossing_angle_rad, p.crossing_period_s, p.turn_rate_radps),
                (0.3, 20.0, 0.5)
            );
        }
        l => panic!("{l:?}"),
    }
    let c = law("sliding_mode");
    match c.law {
        LawSpec::SlidingMode(p) => {
            assert_eq!((p.gamma, p.delta, p.boundary_layer), (0.2, 1.0, None));
            assert_eq!(p.max_turn_rate_radps, 1.0);
        }
        l => panic!("{l:?}"),
    }
    assert_eq!(c.turn_rate_limit, TurnRateLimit::Given(1.0));
    match law("sliding_mode_smooth").law {
        LawSpec::SlidingMode(p) => assert_eq!(p.boundary_layer, Some(0.05)),
        l => panic!("{l:?}"),
    }
    match law("suboptimal_sosm").law {
        LawSpec::SuboptimalSosm(p) => assert_eq!((p.alpha_star, p.max_turn_rate_radps), (0.5, 1.0)),
        l => panic!("{l:?}"),
    }
    match law("gradient_reference").law {
        LawSpec::GradientReference(p) => assert_eq!((p.ke, p.k_heading), (0.5, 1.0)),
        l => panic!("{l:?}"),
    }
}

/// The anti-windup schemes' defaults: the clamp at `kp*c1` (no limit given) or the turn-rate
/// limit, the band at `c2`, the tracking time 1 s; the estimators' 0.1 s and 1.
#[test]
fn anti_windup_and_estimator_defaults() {
    let pi = |text: &str| *spec_of(text).controller.pi_isoline().unwrap();
    let p = pi("[controller]\nanti_windup = \"clamp\"\nkp = 4.0\nc1 = 0.5\n");
    assert_eq!(p.anti_windup, AntiWindup::Clamp { limit_radps: 2.0 });
    let p = pi("[controller]\nanti_windup = \"clamp\"\nmax_turn_rate_radps = 0.7\n");
    assert_eq!(p.anti_windup, AntiWindup::Clamp { limit_radps: 0.7 });
    let p = pi("[controller]\nanti_windup = \"conditional\"\nc2 = 3.0\n");
    assert_eq!(p.anti_windup, AntiWindup::Conditional { band: 3.0 });
    let p = pi("[controller]\nanti_windup = \"back_calculation\"\nmax_turn_rate_radps = 1.0\n");
    assert_eq!(
        p.anti_windup,
        AntiWindup::BackCalculation {
            tracking_time_s: 1.0
        }
    );
    let p = pi("[controller]\nderivative = \"filtered_difference\"\n");
    assert_eq!(
        p.derivative,
        DerivativeKind::FilteredDifference { tau_s: 0.1 }
    );
    let p = pi("[controller]\nderivative = \"levant\"\n");
    assert_eq!(p.derivative, DerivativeKind::Levant { lipschitz: 1.0 });
}

/// The fixed wing's derived turn-rate limit is `g*tan(40 deg)/V` (Beard & McLain's g = 9.8
/// m/s^2: 9.8*0.839100/30 = 0.274106 rad/s at the default 30 m/s; 0.205579 at 40 m/s), in
/// every law's output stage; a given limit wins.
#[test]
fn the_fixed_wing_turn_rate_limit_is_derived_from_its_airspeed() {
    for (va, want) in [(30.0, 0.274_106), (40.0, 0.205_579)] {
        let s = spec_of(&format!(
            "[vehicle]\nkind = \"fixed_wing\"\nairspeed_mps = {va}\n"
        ));
        let TurnRateLimit::Airframe(w) = s.controller.turn_rate_limit else {
            panic!("{:?}", s.controller.turn_rate_limit)
        };
        assert!((w - want).abs() < 1e-6, "{w} vs {want}");
        let p = s.controller.pi_isoline().unwrap();
        assert_eq!(p.output.max_turn_rate_radps, Some(w));
    }
    let s = spec_of("[vehicle]\nkind = \"fixed_wing\"\n[controller]\nmax_turn_rate_radps = 0.1\n");
    assert_eq!(s.controller.turn_rate_limit, TurnRateLimit::Given(0.1));
}

/// Issue 30 (att30b item 14): on the fixed wing the bang-bang laws (`sliding_mode`,
/// `sliding_mode_smooth`, `suboptimal_sosm`) take the airframe's limit as their amplitude and
/// output stage, as the PI law does (`g*tan(40 deg)/V` = 0.274106 rad/s at 30 m/s); they
/// resolved 1 rad/s, 3.6 times what the airframe flies. A given limit still wins, and the
/// Dubins robot keeps its 1 rad/s default.
#[test]
fn the_fixed_wing_bang_bang_laws_take_the_airframe_limit() {
    let want = 0.274_106;
    for kind in ["sliding_mode", "sliding_mode_smooth", "suboptimal_sosm"] {
        let s = spec_of(&format!(
            "[vehicle]\nkind = \"fixed_wing\"\n[controller]\nkind = \"{kind}\"\n"
        ));
        let TurnRateLimit::Airframe(w) = s.controller.turn_rate_limit else {
            panic!("{kind}: {:?}", s.controller.turn_rate_limit)
        };
        assert!((w - want).abs() < 1e-6, "{kind}: {w}");
        let (amplitude, output) = match s.controller.law {
            LawSpec::SlidingMode(p) => (p.max_turn_rate_radps, p.output.max_turn_rate_radps),
            LawSpec::SuboptimalSosm(p) => (p.max_turn_rate_radps, p.output.max_turn_rate_radps),
            l => panic!("{l:?}"),
        };
        assert!((amplitude - want).abs() < 1e-6, "{kind}: {amplitude}");
        assert_eq!(output, Some(amplitude), "{kind}");
        let s = spec_of(&format!(
            "[vehicle]\nkind = \"fixed_wing\"\n[controller]\nkind = \"{kind}\"\nmax_turn_rate_radps = 0.2\n"
        ));
        assert_eq!(s.controller.turn_rate_limit, TurnRateLimit::Given(0.2));
        let s = spec_of(&format!("[controller]\nkind = \"{kind}\"\n"));
        assert_eq!(s.controller.turn_rate_limit, TurnRateLimit::Given(1.0));
    }
}

/// Issue 30 (att30b item 12): `schedule` flew 1 rad/s under `max_turn_rate_radps = 0.1`
/// (the limit README says every controller keeps): a schedule entry beyond the limit is
/// refused, naming the entry; one within it (or without a limit) is kept.
#[test]
fn a_schedule_beyond_the_turn_rate_limit_is_refused() {
    let base =
        "[controller]\nkind = \"schedule\"\ncourse_rate_radps = [[0.0, 0.05], [1.0, -1.0]]\n";
    let e = parse_scenario(&format!("{base}max_turn_rate_radps = 0.1\n"), "<test>", &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("controller.course_rate_radps[1]") && e.contains("exceeds") && e.contains("0.1"),
        "{e}"
    );
    assert!(!e.contains("course_rate_radps[0]"), "{e}");
    parse_scenario(&format!("{base}max_turn_rate_radps = 1.0\n"), "<test>", &[]).unwrap();
    parse_scenario(base, "<test>", &[]).unwrap();
}

/// Issue 30 (att30c-5): on the fixed wing without a given limit, a schedule entry of 5 rad/s
/// flew past the airframe's own `g*tan(40 deg)/V` (0.274106 rad/s at 30 m/s): refused naming
/// the entry and the derived limit, as a given limit is; entries within it fly.
#[test]
fn a_fixed_wing_schedule_beyond_the_airframe_limit_is_refused() {
    let fw = "[vehicle]\nkind = \"fixed_wing\"\n[controller]\nkind = \"schedule\"\n";
    let e = parse_scenario(
        &format!("{fw}course_rate_radps = [[0.0, 0.2], [1.0, 5.0]]\n"),
        "<test>",
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("controller.course_rate_radps[1]") && e.contains("0.274106"),
        "{e}"
    );
    // Just inside the limit (0.274106 rounded down) flies; just above it does not.
    parse_scenario(
        &format!("{fw}course_rate_radps = [[0.0, -0.2741]]\n"),
        "<test>",
        &[],
    )
    .unwrap();
    assert!(parse_scenario(
        &format!("{fw}course_rate_radps = [[0.0, -0.27411]]\n"),
        "<test>",
        &[]
    )
    .is_err());
}

/// Issue 30 (att30c-9): a joiner (ZWNJ U+200C, ZWJ U+200D) in a scenario's `name` or
/// `description` between two visible characters outside ASCII (Persian, a Devanagari
/// half-form, an emoji family) is kept; between ASCII letters, at an end, beside a space, or in
/// an identifying string (`field.units`) it is refused, as every other invisible character.
#[test]
fn joiners_are_kept_where_a_script_needs_them() {
    for (key, value) in [
        (
            "name",
            "\u{645}\u{6cc}\u{200c}\u{62e}\u{648}\u{627}\u{647}\u{645}",
        ),
        ("description", "\u{915}\u{94d}\u{200d}\u{937} half-form"),
        ("name", "family \u{1f468}\u{200d}\u{1f469}\u{200d}\u{1f467}"),
    ] {
        let text = format!("{key} = {}\n", toml::Value::String(value.into()));
        let s = parse_scenario(&text, "<test>", &[]).unwrap_or_else(|e| panic!("{key}: {e}"));
        let got = if key == "name" {
            s.file().name.clone()
        } else {
            s.file().description.clone()
        };
        assert_eq!(got.as_deref(), Some(value));
    }
    for (key, value) in [
        ("name", "pi_iso\u{200d}line"),
        ("name", "\u{645}\u{6cc}\u{200c}"),
        ("name", "\u{200d}\u{1f468}"),
        ("description", "\u{645} \u{200c}\u{62e}"),
        ("field.units", "\u{645}\u{200c}\u{62e}"),
    ] {
        let text = if key == "field.units" {
            format!("[field]\nunits = {}\n", toml::Value::String(value.into()))
        } else {
            format!("{key} = {}\n", toml::Value::String(value.into()))
        };
        let e = parse_scenario(&text, "<test>", &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("control or invisible character (U+200"),
            "{key} {value:?}: {e}"
        );
    }
}

/// The search geometry: spacing `2*v/omega_max` (1 rad/s without a limit), legs 10 spacings,
/// hand-over 1 % of |level|.
#[test]
fn search_geometry_is_derived() {
    let s =
        spec_of("[controller]\nsearch = \"lawnmower\"\nlevel = 4.0\n[vehicle]\nspeed_mps = 2.0\n");
    let sp = s.controller.search.unwrap();
    assert_eq!(sp.handover_delta, 0.04);
    match sp.pattern {
        SearchPattern::Lawnmower {
            leg_m,
            spacing_m,
            speed_mps,
        } => assert_eq!((leg_m, spacing_m, speed_mps), (40.0, 4.0, 2.0)),
        p => panic!("{p:?}"),
    }
    let s = spec_of("[controller]\nsearch = \"spiral\"\nmax_turn_rate_radps = 0.5\n");
    match s.controller.search.unwrap().pattern {
        SearchPattern::Spiral {
            spacing_m,
            max_turn_rate_radps,
            ..
        } => assert_eq!((spacing_m, max_turn_rate_radps), (2.0, 0.5)),
        p => panic!("{p:?}"),
    }
}

/// A lawnmower flies its half-turns at `2 v / search_spacing_m` past the output stage: with
/// v = 1 m/s (the default speed) and a limit of 0.5 rad/s the turning diameter is 2 v / L = 4 m,
/// so 0.2 m (5 rad/s) is refused naming the key, 4 m (exactly 0.5 rad/s) and the derived
/// default are accepted (issue 30).
#[test]
fn a_lawnmower_tighter_than_the_turn_rate_limit_is_refused() {
    let base = "[vehicle]\nspeed_mps = 1.0\n[controller]\nsearch = \"lawnmower\"\nmax_turn_rate_radps = 0.5\n";
    let e = parse_scenario(&format!("{base}search_spacing_m = 0.2\n"), "<test>", &[])
        .expect_err("a 5 rad/s half-turn under a 0.5 rad/s limit is refused")
        .to_string();
    assert!(e.contains("controller.search_spacing_m"), "{e}");
    assert!(e.contains("4 m"), "{e}");
    let s = spec_of(&format!("{base}search_spacing_m = 4.0\n"));
    assert!(s.controller.search.is_some());
    let s = spec_of(base);
    match s.controller.search.unwrap().pattern {
        SearchPattern::Lawnmower { spacing_m, .. } => assert_eq!(spacing_m, 4.0),
        p => panic!("{p:?}"),
    }
}

/// Issue 30 (fix30c), item 6: the scenario's strings follow the rule of NetCDF attributes and
/// suite names: NUL, ESC, U+202E, U+200B in `name` or `field.units` are refused naming the key;
/// a description may span lines; plain Unicode (`µg/m³`) passes.
#[test]
fn scenario_strings_are_plain_text() {
    for (set, key) in [
        ("field.units=\"m\\u0000\\u001b[31mRED\"", "field.units"),
        ("name=\"a\\u202eb\"", "name"),
        ("name=\"pi\\u200b\"", "name"),
        ("description=\"x\\u0007y\"", "description"),
    ] {
        let e = parse_scenario("", "<test>", &[set.to_string()])
            .err()
            .unwrap_or_else(|| panic!("{set} is refused"))
            .to_string();
        assert!(
            e.contains(key) && e.contains("control or invisible"),
            "{set}: {e}"
        );
    }
    let s = parse_scenario(
        "name = \"plume µ\"\ndescription = \"\"\"two\r\nlines\tand a tab\"\"\"\n[field]\nunits = \"µg/m³\"\n",
        "<test>",
        &[],
    );
    assert!(s.is_ok(), "{:?}", s.err().map(|e| e.to_string()));
}

/// A derived default follows a variant's own values (a swept duration, a new airspeed).
#[test]
fn derived_values_follow_a_variant() {
    let s = parse_scenario("", "<test>", &[]).unwrap();
    let v = s.derive(&["sim.duration_s=50.0".into()], "<test>").unwrap();
    assert_eq!(v.spec().metrics.convergence_min_dwell_s, 5.0);
    let s = parse_scenario("[vehicle]\nkind = \"fixed_wing\"\n", "<test>", &[]).unwrap();
    let v = s
        .derive(&["vehicle.airspeed_mps=40.0".into()], "<test>")
        .unwrap();
    let w = v.spec().controller.turn_rate_limit.radps().unwrap();
    assert!((w - 0.205_579).abs() < 1e-6, "{w}");
}

/// A file resolution did not settle is an issue naming the key, not a panic.
#[test]
fn an_unsettled_key_is_an_issue() {
    let e = ScenarioSpec::new(&ScenarioFile::default(), None).unwrap_err();
    assert_eq!(e.key, "sim.dt_s");
}

/// `show`: the fixed wing's turn-rate limit, the dwell, the band and the search geometry appear
/// as commented-out keys in their sections (numbers from the formulas: 9.8*tan(40 deg)/30,
/// 10 % of 600 s, 5 x 0.1, 2*30/0.274106, 10 spacings, 1 % of 10), the rate and tolerance
/// marked derived; reading it back gives the same scenario, and showing that the same text.
#[test]
fn show_prints_every_value_in_force_and_reads_back_the_same() {
    let text = "[vehicle]\nkind = \"fixed_wing\"\n[controller]\nsearch = \"lawnmower\"\n";
    let s = parse_scenario(text, "<test>", &[]).unwrap();
    let resolved = toml::to_string(s.file()).unwrap();
    let shown = show::with_derived(&s, &resolved);
    let section_of = |needle: &str| {
        let i = shown
            .find(needle)
            .unwrap_or_else(|| panic!("{needle} in\n{shown}"));
        shown[..i]
            .rfind("\n[")
            .map(|j| shown[j + 1..].lines().next().unwrap().to_string())
    };
    let w: f64 = 9.8 * 40f64.to_radians().tan() / 30.0;
    let spacing = 2.0 * 30.0 / w;
    for (line, section) in [
        (
            format!("# max_turn_rate_radps = {w:?}  # derived"),
            "[controller]",
        ),
        (
            format!("# search_spacing_m = {spacing:?}  # derived"),
            "[controller]",
        ),
        (
            format!("# search_leg_m = {:?}  # derived", 10.0 * spacing),
            "[controller]",
        ),
        ("# search_handover = 0.1  # derived".into(), "[controller]"),
        (
            "# convergence_min_dwell_s = 60.0  # derived".into(),
            "[metrics]",
        ),
        ("# track_loss_band = 0.5  # derived".into(), "[metrics]"),
        ("rate_hz = 100.0  # derived: 1/sim.dt_s".into(), "[sensor]"),
        ("convergence_tolerance = 0.1  # derived".into(), "[metrics]"),
        ("# home_lat_deg = 47.397742".into(), "[field]"),
    ] {
        if section != "[field]" {
            assert_eq!(
                section_of(&line).as_deref(),
                Some(section),
                "{line}\n{shown}"
            );
        } else {
            assert!(shown.contains(&line), "{line}\n{shown}");
        }
    }
    let again = parse_scenario(&shown, "<shown>", &[]).unwrap();
    assert_eq!(again.file(), s.file());
    assert_eq!(again.spec(), s.spec());
    let shown_again = show::with_derived(&again, &toml::to_string(again.file()).unwrap());
    assert_eq!(shown_again, shown);
    // A given value that is not the formula's is not marked.
    let s = parse_scenario("[sensor]\nrate_hz = 50.0\n", "<test>", &[]).unwrap();
    let shown = show::with_derived(&s, &toml::to_string(s.file()).unwrap());
    assert!(shown.lines().any(|l| l == "rate_hz = 50.0"), "{shown}");
    assert!(!shown.contains("max_turn_rate_radps"), "{shown}");
}

/// nu-18: `show` gives the `[team]` values in force the file leaves out, each in its section:
/// the law (`range_balance`), `k_v` 0.1, the envelope `v0/2 = 0.25`, `2 v0 = 1.0` m/s, the ring
/// (`listed`), a line spread's first pose from `[initial]` (3, 4) m heading 0.5 rad and its
/// direction (= heading), the ranging's five defaults (10 Hz, no noise, no limit, no loss, no
/// delay) under a commented `[team.ranging]`; an arc spread's centre (the origin), first angle
/// 0, step `2 pi/3` and sense (clockwise). Comments only: the output reads back as the same
/// scenario, and showing it again gives the same text.
#[test]
fn show_gives_the_team_defaults() {
    let text = "[initial]\nx_m = 3.0\ny_m = 4.0\nheading_rad = 0.5\n[team]\ncount = 3\nspread = { along = \"line\", step_m = 1.0 }\n";
    let s = parse_scenario(text, "<test>", &[]).unwrap();
    let shown = show::with_derived(&s, &toml::to_string(s.file()).unwrap());
    let section_of = |shown: &str, needle: &str| {
        let i = shown
            .find(needle)
            .unwrap_or_else(|| panic!("{needle} in\n{shown}"));
        shown[..i]
            .rfind("\n[")
            .map(|j| shown[j + 1..].lines().next().unwrap().to_string())
    };
    for (line, section) in [
        ("# spacing = \"range_balance\"  # default", "[team]"),
        ("# k_v = 0.1  # default", "[team]"),
        ("# v_min_mps = 0.25  # derived: half", "[team]"),
        ("# v_max_mps = 1.0  # derived: twice", "[team]"),
        ("# ring = \"listed\"  # default", "[team]"),
        ("# [team.ranging]", "[team]"),
        ("# rate_hz = 10.0  # default", "[team]"),
        ("# noise_std_m = 0.0  # default", "[team]"),
        ("# max_range_m = inf  # default: no limit", "[team]"),
        ("# dropout_probability = 0.0  # default", "[team]"),
        ("# delay_s = 0.0  # default", "[team]"),
        ("# x_m = 3.0  # derived: initial.x_m", "[team.spread]"),
        ("# y_m = 4.0  # derived: initial.y_m", "[team.spread]"),
        (
            "# heading_rad = 0.5  # derived: initial.heading_rad",
            "[team.spread]",
        ),
        (
            "# direction_rad = 0.5  # derived: heading_rad",
            "[team.spread]",
        ),
    ] {
        assert_eq!(
            section_of(&shown, line).as_deref(),
            Some(section),
            "{line}\n{shown}"
        );
    }
    let again = parse_scenario(&shown, "<shown>", &[]).unwrap();
    assert_eq!(again.file(), s.file());
    assert_eq!(again.spec(), s.spec());
    let shown_again = show::with_derived(&again, &toml::to_string(again.file()).unwrap());
    assert_eq!(shown_again, shown);
    // Given keys are not repeated; an arc spread's defaults; given ranging keys stand.
    let text = "[team]\ncount = 3\nring = \"listed\"\nk_v = 0.2\nspread = { along = \"arc\", radius_m = 5.0 }\nranging = { rate_hz = 5.0 }\n";
    let s = parse_scenario(text, "<test>", &[]).unwrap();
    let shown = show::with_derived(&s, &toml::to_string(s.file()).unwrap());
    assert!(!shown.contains("# ring"), "{shown}");
    assert!(!shown.contains("# k_v"), "{shown}");
    assert!(!shown.contains("# rate_hz"), "{shown}");
    assert!(!shown.contains("# [team.ranging]"), "{shown}");
    let step = format!(
        "# step_rad = {:?}  # derived: 2 pi/count",
        std::f64::consts::TAU / 3.0
    );
    for line in [
        "# center_m = [0.0, 0.0]  # default",
        "# start_rad = 0.0  # default",
        &step,
        "# clockwise = true  # default",
    ] {
        assert_eq!(
            section_of(&shown, line).as_deref(),
            Some("[team.spread]"),
            "{line}"
        );
    }
    assert_eq!(
        section_of(&shown, "# noise_std_m = 0.0  # default").as_deref(),
        Some("[team.ranging]")
    );
    let again = parse_scenario(&shown, "<shown>", &[]).unwrap();
    assert_eq!(again.file(), s.file());
}

/// nu36-13: a `[team]` given by `starts` alone (or `starts` and `vehicles`, arrays of tables
/// only) is written as `[[team.starts]]` tables with no `[team]` header of its own: `show` adds
/// the header once for all the team's commented values (it once added one per line, 12 `[team]`
/// headers, which TOML refuses as a duplicate key), and the output reads back as the same
/// scenario and shows again as the same text.
#[test]
fn show_of_a_team_given_by_starts_alone_is_valid_toml() {
    let starts = "starts = [{x_m = 6.93, y_m = 0.0, heading_rad = -1.5708}, {x_m = -6.93, y_m = 0.0, heading_rad = 1.5708}]\n";
    for text in [
        format!("[team]\n{starts}"),
        format!("[team]\n{starts}vehicles = [{{index = 1, speed_mps = 0.4}}]\n"),
    ] {
        let s = parse_scenario(&text, "<test>", &[]).unwrap();
        let shown = show::with_derived(&s, &toml::to_string(s.file()).unwrap());
        assert_eq!(
            shown.lines().filter(|l| l.trim() == "[team]").count(),
            1,
            "{shown}"
        );
        assert!(toml::from_str::<toml::Table>(&shown).is_ok(), "{shown}");
        assert!(
            shown.contains("# count = 2  # derived: the length of team.starts"),
            "{shown}"
        );
        let again = parse_scenario(&shown, "<shown>", &[]).unwrap();
        assert_eq!(again.file(), s.file());
        assert_eq!(again.spec(), s.spec());
        let shown_again = show::with_derived(&again, &toml::to_string(again.file()).unwrap());
        assert_eq!(shown_again, shown);
    }
}

/// A description holding lines that look like a section and a key stays text: `show` marks only
/// the real ones, and its output reads back as the same scenario.
#[test]
fn show_is_not_fooled_by_a_multi_line_string() {
    let text = "description = \"\"\"\nfoo\n[metrics]\nrate_hz = 1\n[sensor]\nrate_hz = 2\n\"\"\"\n[controller]\nsearch = \"spiral\"\n";
    let s = parse_scenario(text, "<test>", &[]).unwrap();
    let shown = show::with_derived(&s, &toml::to_string(s.file()).unwrap());
    let again = parse_scenario(&shown, "<shown>", &[]).unwrap();
    assert_eq!(again.file(), s.file(), "{shown}");
    assert_eq!(shown.matches("# derived: 1/sim.dt_s").count(), 1, "{shown}");
    assert_eq!(
        shown.matches("# convergence_min_dwell_s").count(),
        1,
        "{shown}"
    );
}

/// The noise warning names the backward difference only for a law that has one: the old
/// fallback `derivative.unwrap_or(BackwardDifference)` warned `gradient_reference` and
/// `schedule` too (reachable: `compare` on gaussian-plumes-pm25, noise 0.01), advising a
/// `controller.derivative` that resolve refuses for them.
#[test]
fn the_noise_warning_is_only_for_a_law_with_a_backward_difference() {
    let noisy = "[sensor]\nnoise_std = 0.01\n[sim]\nduration_s = 1.0\n";
    let warned = |controller: &str| {
        let s =
            parse_scenario(&format!("{noisy}[controller]\n{controller}"), "<test>", &[]).unwrap();
        crate::check::warnings(&s)
            .iter()
            .any(|w| w.contains("through a backward difference"))
    };
    assert!(warned(""));
    assert!(warned("kind = \"pid\"\n"));
    assert!(!warned("derivative = \"levant\"\n"));
    assert!(!warned("kind = \"gradient_reference\"\n"));
    assert!(!warned(
        "kind = \"schedule\"\ncourse_rate_radps = [[0.0, 0.1]]\n"
    ));
}

/// `[field]` typed: each kind's defaults are the README table's ("Scenario files": radial 20,
/// 0.1, [0, 0]; ramp 0, [0, 1]; puff [0, 0], 2, 10, 0.5, 0.05, [0.5, 0], 0.1, 20, 120, 0),
/// without a drift or a domain, the meander seeded by `sim.seed`.
#[test]
fn the_field_spec_holds_the_readme_defaults() {
    use isotrack_core::Vec2;
    use isotrack_fields::{AnalyticField, AnalyticKind, LinearRamp, RadialExp};
    let s = spec_of("");
    assert_eq!(s.field.units, None);
    assert_eq!(
        s.field.kind,
        FieldKindSpec::Analytic(AnalyticField {
            kind: AnalyticKind::RadialExp(RadialExp {
                i0: 20.0,
                decay_per_m: 0.1,
                center_m: Vec2::new(0.0, 0.0),
            }),
            domain_m: None,
            drift_mps: Vec2::new(0.0, 0.0),
        })
    );
    let s = spec_of("[field]\nkind = \"linear_ramp\"\ndrift_mps = [0.5, -1.0]\n");
    assert_eq!(
        s.field.kind,
        FieldKindSpec::Analytic(AnalyticField {
            kind: AnalyticKind::LinearRamp(LinearRamp {
                offset: 0.0,
                gradient_per_m: Vec2::new(0.0, 1.0),
            }),
            domain_m: None,
            drift_mps: Vec2::new(0.5, -1.0),
        })
    );
    let s = spec_of("[field]\nkind = \"puff_plume\"\n[sim]\nseed = 7\n");
    let FieldKindSpec::PuffPlume(p) = s.field.kind else {
        panic!("{:?}", s.field)
    };
    assert_eq!(
        (p.source_m, p.release_rate_hz, p.puff_mass, p.puff_sigma0_m),
        (Vec2::new(0.0, 0.0), 2.0, 10.0, 0.5)
    );
    assert_eq!(
        (p.diffusivity_m2ps, p.wind_mps, p.meander_std_mps),
        (0.05, Vec2::new(0.5, 0.0), 0.1)
    );
    assert_eq!(
        (p.meander_correlation_s, p.max_age_s, p.background, p.seed),
        (20.0, 120.0, 0.0, 7)
    );
    assert_eq!(p.domain_m, None);
    let s = spec_of("[field]\nkind = \"gaussian_plumes\"\n");
    let FieldKindSpec::Analytic(a) = s.field.kind else {
        panic!()
    };
    let AnalyticKind::GaussianPlumes(g) = a.kind else {
        panic!()
    };
    assert_eq!((g.background, g.plumes.len()), (0.0, 3));
}

/// A grid's spec: the README's defaults (bicubic; no floor, no log, scale 1, offset 0; linear
/// in time, origin 0, scale 1, hold), and once built the keys its file fills: a CSV grid has no
/// georeference, so spacing 1 m and origin [0, 0] (README), in the spec as in the resolved file.
#[test]
fn a_grid_spec_has_the_readme_defaults_and_what_its_file_fills() {
    use super::field::{FrameTimes, GridFiles, GridGeoreference, ValueTransform};
    use isotrack_fields::grid::{AfterLastFrame, Interpolation, TimeInterpolation};
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("g.csv"), "1,2,3\n4,5,6\n7,8,9\n").unwrap();
    let text = "[field]\nkind = \"grid\"\npath = \"g.csv\"\n[initial]\nx_m = 1.0\ny_m = 1.0\n[controller]\nlevel = 5.0\n";
    let s = crate::parse_scenario_in(text, "<test>", &[], d.path()).unwrap();
    let FieldKindSpec::Grid(g) = &s.spec().field.kind else {
        panic!("{:?}", s.spec().field)
    };
    let abs = d.path().join("g.csv").canonicalize().unwrap();
    assert_eq!(g.files, GridFiles::Path(abs.display().to_string()));
    assert_eq!(
        g.georeference,
        GridGeoreference {
            spacing_m: Some([1.0, 1.0]),
            origin_m: Some([0.0, 0.0]),
        }
    );
    assert_eq!(
        (s.file().field.spacing_m, s.file().field.origin_m),
        (Some([1.0, 1.0]), Some([0.0, 0.0]))
    );
    assert_eq!(g.interpolation, Interpolation::Bicubic);
    assert_eq!(
        g.transform,
        ValueTransform {
            floor: None,
            log10: false,
            scale: 1.0,
            offset: 0.0,
        }
    );
    assert_eq!(g.frame_times, FrameTimes::FromFile);
    assert_eq!(
        (g.time_interpolation, g.time_origin_s, g.time_scale),
        (TimeInterpolation::Linear, 0.0, 1.0)
    );
    assert_eq!(g.after_last_frame, AfterLastFrame::Hold);
    assert_eq!(
        (g.format, g.variable.as_deref(), g.crop_cells),
        (None, None, None)
    );
}

/// A field key resolution should have settled but did not is an issue naming it.
#[test]
fn an_unsettled_field_key_is_an_issue() {
    let e = FieldSpec::new(&crate::schema::FieldSection::default(), 0).unwrap_err();
    assert_eq!(e.key, "field.kind");
    let f = crate::schema::FieldSection {
        kind: Some(crate::schema::FieldKind::RadialExp),
        ..Default::default()
    };
    assert_eq!(FieldSpec::new(&f, 0).unwrap_err().key, "field.i0");
}
