//! Issue 15 item 11: a search phase before tracking. On a flat background the tracking law has
//! no gradient to steer by and circles where it starts; a spiral or lawnmower search finds the
//! plume and hands over.

use isotrack_scenario::parse_scenario;
use isotrack_sim::{NoTrace, RunResult};

/// A 20-unit plume (sigma 3 m) at `center` on a zero background; the start at the origin.
fn flat(center: [f64; 2], heading: f64, sets: &[&str]) -> RunResult {
    let text = format!(
        "[sim]\nduration_s = 1500.0\n[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\n\
         [[field.sources]]\ncenter_m = [{:?}, {:?}]\namplitude = 20.0\nsigma_m = [3.0, 3.0]\nrotation_rad = 0.0\n\
         [initial]\nx_m = 0.0\ny_m = 0.0\nheading_rad = {heading:?}\n[controller]\nanti_windup = \"conditional\"\n",
        center[0], center[1]
    );
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    parse_scenario(&text, "<test>", &sets)
        .unwrap()
        .run(&mut NoTrace)
}

#[test]
fn a_spiral_finds_a_plume_the_tracking_law_alone_never_reaches() {
    // The plume's value at the start is 20*exp(-225/18) = 7e-5: no gradient to speak of.
    let alone = flat([15.0, 0.0], 1.0, &[]);
    assert!(alone.metrics.convergence_time_s.is_none());
    assert!(alone.metrics.steady_state_max_abs_error.unwrap() > 9.99);
    let spiral = flat(
        [15.0, 0.0],
        1.0,
        &[
            "controller.search=spiral",
            "controller.search_spacing_m=2.0",
        ],
    );
    assert!(spiral.metrics.convergence_time_s.is_some());
    assert!(spiral.metrics.steady_state_max_abs_error.unwrap() < 1e-6);
}

#[test]
fn a_lawnmower_finds_it_sooner_than_circling() {
    let alone = flat([10.0, 8.0], 0.0, &[]);
    let mower = flat(
        [10.0, 8.0],
        0.0,
        &[
            "controller.search=lawnmower",
            "controller.search_spacing_m=2.0",
        ],
    );
    let t_mower = mower.metrics.convergence_time_s.unwrap();
    assert!(mower.metrics.steady_state_max_abs_error.unwrap() < 1e-6);
    assert!(alone
        .metrics
        .convergence_time_s
        .is_none_or(|t| t > 2.0 * t_mower));
}

/// Off by default, and its keys are refused without it (or, for the leg, without a lawnmower).
#[test]
fn off_by_default_and_keys_checked() {
    let s = parse_scenario("", "<test>", &[]).unwrap();
    assert!(s.search().is_none());
    let e = parse_scenario("", "<test>", &["controller.search_spacing_m=2.0".into()]).unwrap_err();
    assert!(
        e.to_string()
            .contains("does not apply to controller.search = \"none\""),
        "{e}"
    );
    let e = parse_scenario(
        "",
        "<test>",
        &[
            "controller.search=spiral".into(),
            "controller.search_leg_m=5.0".into(),
        ],
    )
    .unwrap_err();
    assert!(e.to_string().contains("search_leg_m"), "{e}");
    // Defaults: spacing = 2*v/omega_max = 2*0.5/1 = 1 m, hand-over 1 % of level 10.
    let s = parse_scenario("", "<test>", &["controller.search=lawnmower".into()]).unwrap();
    let p = s.search().unwrap();
    assert_eq!(p.handover_delta, 0.1);
    assert_eq!(
        p.pattern,
        isotrack_core::control::SearchPattern::Lawnmower {
            leg_m: 10.0,
            spacing_m: 1.0,
            speed_mps: 0.5
        }
    );
    // With a turn-rate limit and another speed: spacing 2*2/0.5 = 8 m, legs 10*8 = 80 m; the
    // spiral starts at that limit. Level -4: hand-over at 1 % of |level|.
    let sets = |kind: &str| -> Vec<String> {
        [
            format!("controller.search={kind}"),
            "controller.max_turn_rate_radps=0.5".into(),
            "vehicle.speed_mps=2.0".into(),
            "controller.level=-4.0".into(),
        ]
        .into()
    };
    let p = parse_scenario("", "<test>", &sets("lawnmower"))
        .unwrap()
        .search()
        .unwrap();
    assert_eq!(p.handover_delta, 0.04);
    assert_eq!(
        p.pattern,
        isotrack_core::control::SearchPattern::Lawnmower {
            leg_m: 80.0,
            spacing_m: 8.0,
            speed_mps: 2.0
        }
    );
    let p = parse_scenario("", "<test>", &sets("spiral"))
        .unwrap()
        .search()
        .unwrap();
    assert_eq!(
        p.pattern,
        isotrack_core::control::SearchPattern::Spiral {
            spacing_m: 8.0,
            speed_mps: 2.0,
            max_turn_rate_radps: 0.5
        }
    );
}
