//! The batched path (`Scenario::run_batch`, runs stepped together in SIMD lanes) against the
//! scalar one (`Scenario::run`, each run alone): every metric of every run equal, over sweeps
//! with mixed outcomes, every field kind, the Dubins robot and every controller of its path.

use isotrack_scenario::load::load_scenario;
use isotrack_scenario::Scenario;
use isotrack_sim::{NoTrace, Outcome, RunResult};

/// `n` variants of `base` (`sets` applied to it), run `i` with the overrides `vary(i)`.
fn variants(base: &[&str], n: usize, vary: impl Fn(usize) -> Vec<String>) -> Vec<Scenario> {
    variants_of(None, base, n, vary)
}

/// [`variants`] of a scenario file of the repository (`scenarios/NAME.toml`).
fn variants_of(
    file: Option<&str>,
    base: &[&str],
    n: usize,
    vary: impl Fn(usize) -> Vec<String>,
) -> Vec<Scenario> {
    let sets: Vec<String> = base.iter().map(|s| s.to_string()).collect();
    let path = file.map(|f| {
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenarios/{f}.toml"))
    });
    let base = load_scenario(path.as_deref(), &sets).expect("base scenario");
    (0..n)
        .map(|i| base.derive(&vary(i), "test").expect("variant"))
        .collect()
}

/// A pseudo-random start in `[-r, r]^2` with a heading, per run (SplitMix64, fixed).
fn start(i: usize, r: f64) -> Vec<String> {
    let mut z = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut x = z;
        x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((x ^ (x >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    vec![
        format!("initial.x_m={}", r * (2.0 * next() - 1.0)),
        format!("initial.y_m={}", r * (2.0 * next() - 1.0)),
        format!(
            "initial.heading_rad={}",
            std::f64::consts::TAU * next() - std::f64::consts::PI
        ),
        format!("sim.seed={i}"),
    ]
}

/// Each run's batched result equals its scalar result, field for field and bit for bit (which
/// is within any relative tolerance, 1e-9 included). Returns the outcomes.
fn check(runs: &[Scenario]) -> Vec<Outcome> {
    let batched = Scenario::run_batch(runs);
    assert_eq!(batched.len(), runs.len());
    for (i, (s, b)) in runs.iter().zip(&batched).enumerate() {
        let alone: RunResult = s.run(&mut NoTrace);
        assert_eq!(&alone, b, "run {i}");
        // Bit for bit, not only ==: the same sign of zero, the same NaN-free numbers.
        let bits = |r: &RunResult| format!("{r:?}");
        assert_eq!(bits(&alone), bits(b), "run {i}");
    }
    batched.iter().map(|r| r.outcome).collect()
}

#[test]
fn default_scenario_sweep_with_mixed_outcomes() {
    // A bounded domain so that starts near its edge leave the field; a short run; 19 runs: two
    // full groups of 8 and a padded one of 3.
    let runs = variants(
        &[
            "field.domain_m=[-12.0, 12.0, -12.0, 12.0]",
            "sim.duration_s=60",
            "sensor.noise_std=0.01",
            "sensor.dropout_probability=0.05",
        ],
        19,
        |i| {
            let mut v = start(i, 11.0);
            if i % 4 == 0 {
                // At the domain's edge, heading out: leaves within a second.
                v.extend(["initial.x_m=11.99".into(), "initial.heading_rad=0.0".into()]);
            }
            v
        },
    );
    let outcomes = check(&runs);
    assert!(outcomes.contains(&Outcome::Completed), "{outcomes:?}");
    assert!(outcomes.contains(&Outcome::LeftField), "{outcomes:?}");
}

#[test]
fn a_diverging_run_is_masked_and_the_others_go_on() {
    // kp = 1e308 with c1 = 50 makes the command overflow to infinity at the first sample
    // away from the isoline (kp c1 tanh(eps/c2) > 1.8e308 once |tanh(eps/c2)| > 0.036): those
    // runs end diverged at t = 0, the lanes beside them complete. (kp = 1e308 alone, with the
    // default c1 = 0.2, gives a finite command of up to 2e307 rad/s: the robot spins, its
    // heading wrapped past 1e7 rad, and the run completes.)
    let runs = variants(&["sim.duration_s=20"], 8, |i| {
        let mut v = start(i, 9.0);
        if i % 3 == 1 {
            v.push("controller.kp=1e308".into());
            v.push("controller.c1=50".into());
        }
        v
    });
    let outcomes = check(&runs);
    assert!(outcomes.contains(&Outcome::Diverged), "{outcomes:?}");
    assert!(outcomes.contains(&Outcome::Completed), "{outcomes:?}");
}

#[test]
fn every_controller_of_the_dubins_path() {
    for kind in [
        "pi_isoline",
        "sliding_mode",
        "suboptimal_sosm",
        "pid",
        "pid_crossing",
        "gradient_reference",
    ] {
        let runs = variants(
            &["sim.duration_s=40", &format!("controller.kind=\"{kind}\"")],
            9,
            |i| start(i, 10.0),
        );
        check(&runs);
    }
    // The PI-like law's anti-windup schemes and estimators, and a search phase first.
    for extra in [
        "controller.anti_windup=\"clamp\"",
        "controller.anti_windup=\"back_calculation\"\ncontroller.max_turn_rate_radps=1.0",
        "controller.derivative=\"levant\"",
        "controller.search=\"spiral\"",
    ] {
        let mut base = vec!["sim.duration_s=40"];
        base.extend(extra.split('\n'));
        let runs = variants(&base, 5, |i| start(i, 10.0));
        check(&runs);
    }
}

#[test]
fn every_analytic_field_and_a_grid() {
    for field in [
        vec!["field.kind=\"gaussian_plumes\""],
        vec!["field.kind=\"linear_ramp\""],
        vec!["field.drift_mps=[0.05, 0.0]"],
    ] {
        let mut base = field.clone();
        base.push("sim.duration_s=30");
        let runs = variants(&base, 9, |i| start(i, 10.0));
        check(&runs);
    }
}

#[test]
fn grids_and_a_puff_plume_fall_back_to_per_lane_values() {
    // The NO2 grid (bicubic, and bilinear), starts spread so that some leave its domain.
    for interp in ["bicubic", "bilinear"] {
        let runs = variants_of(
            Some("paper-fig2a-field"),
            &[
                "sim.duration_s=60",
                &format!("field.interpolation=\"{interp}\""),
            ],
            11,
            |i| start(i, 22.0),
        );
        let outcomes = check(&runs);
        assert!(outcomes.contains(&Outcome::Completed), "{outcomes:?}");
        assert!(outcomes.contains(&Outcome::LeftField), "{outcomes:?}");
    }
    let runs = variants_of(Some("puff-plume-edge"), &["sim.duration_s=20"], 4, |i| {
        vec![format!("sim.seed={i}")]
    });
    check(&runs);
}

#[test]
fn scenarios_that_differ_in_field_are_not_grouped_but_still_right() {
    // Alternating decay rates: two fields, so every group is one run; the answers still match.
    let runs = variants(&["sim.duration_s=20"], 6, |i| {
        let mut v = start(i, 9.0);
        v.push(format!("field.decay_per_m={}", 0.1 + 0.01 * (i % 2) as f64));
        v
    });
    check(&runs);
}

#[test]
fn the_fixed_wing_uav_steps_in_lanes_with_the_same_results() {
    // Fig. 3's UAV (its airframe in lanes, `FixedWing::step_lanes`), 11 runs: a group of 8 and
    // a padded one of 3 (the runs differ in start, heading and sim.seed, so in gust seed too,
    // and still share lanes). Every third run starts 100 m inside the map's east edge flying
    // east (it leaves the field within seconds, its lane masked) beside runs that complete.
    // In calm air and in Dryden gusts. (A UAV lane that diverges beside finite ones:
    // `fixed_wing::tests::lanes_of_4_and_8_equal_one_at_a_time_in_calm_air_and_in_gusts`.)
    for gusts in ["false", "true"] {
        let runs = variants_of(
            Some("paper-fig3-uav"),
            &["sim.duration_s=40", &format!("vehicle.gusts={gusts}")],
            11,
            |i| {
                let mut v = start(i, 2500.0);
                if i % 3 == 1 {
                    v.push("initial.x_m=3900".into());
                    v.push("initial.heading_rad=0".into());
                }
                v
            },
        );
        let outcomes = check(&runs);
        for o in [Outcome::Completed, Outcome::LeftField] {
            assert!(
                outcomes.contains(&o),
                "gusts {gusts}: {o:?} in {outcomes:?}"
            );
        }
    }
}
