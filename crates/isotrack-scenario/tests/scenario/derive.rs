//! Derived scenarios (what a sweep builds per run): equality follows the file, and a derived
//! scenario rebuilds exactly what its overrides change; the moving isoline's time resolution.

use isotrack_core::math::Vec2;
use isotrack_fields::grid::{AfterLastFrame, Grid2, GridSeries, Interpolation, TimeInterpolation};
use isotrack_scenario::field::MovingIsoline;
use isotrack_scenario::parse_scenario;
use isotrack_sim::NoTrace;
use std::sync::Arc;

#[test]
fn equality_follows_the_resolved_file() {
    let base = parse_scenario("", "<test>", &[]).unwrap();
    let kp5 = base.derive(&["controller.kp=5".into()], "<test>").unwrap();
    let kp5_again = base.derive(&["controller.kp=5".into()], "<test>").unwrap();
    assert!(kp5 != base);
    assert!(kp5 == kp5_again);
    assert!(base == parse_scenario("", "<test>", &[]).unwrap());
}

/// A derived scenario with another speed flies at it: over 10 s a Dubins robot's path is
/// `v * 10 s` (summed as chords of its arcs, within 0.1 mm).
#[test]
fn a_derived_vehicle_is_rebuilt() {
    let base = parse_scenario("", "<test>", &["sim.duration_s=10".into()]).unwrap();
    for (sets, v) in [
        (vec![], 0.5),
        (vec!["vehicle.speed_mps=1.25".to_string()], 1.25),
    ] {
        let s = base.derive(&sets, "<test>").unwrap();
        let path = s.run(&mut NoTrace).metrics.path_length_m;
        assert!((path - 10.0 * v).abs() < 1e-4, "{sets:?}: path {path} m");
    }
}

/// The moving isoline is recomputed every 1/8 of the shortest frame interval, in run time:
/// frames 3600 s and 1800 s apart at 60 s of field time per run second give 1800/8/60 s.
#[test]
fn moving_isoline_bucket_is_an_eighth_of_the_shortest_frame_gap() {
    let frame =
        |k: f64| Grid2::from_fn(4, 4, Vec2::new(0.0, 0.0), [1.0, 1.0], move |p| k + p.x).unwrap();
    let series = GridSeries::new(
        vec![frame(0.0), frame(1.0), frame(2.0)],
        vec![0.0, 3600.0, 5400.0],
        Interpolation::Bilinear,
        TimeInterpolation::Linear,
        0.0,
        60.0,
        AfterLastFrame::Hold,
    )
    .unwrap();
    let m = MovingIsoline::new(Arc::new(series), 1.5);
    assert!(
        (m.bucket_s() - 1800.0 / 8.0 / 60.0).abs() < 1e-12,
        "{}",
        m.bucket_s()
    );
}

/// A run's result as text (every metric, outcome and count), to compare runs whole.
fn fingerprint(s: &isotrack_scenario::Scenario) -> String {
    format!("{:?}", s.run(&mut NoTrace))
}

/// What a derived scenario shares with its base (the field, read once for a sweep) and what it
/// rebuilds: a new seed is a new puff plume (its meander) and a new gusty UAV (its gusts), the
/// same field otherwise; a changed field key is a new field. Each derived run equals the same
/// scenario parsed afresh.
#[test]
fn derived_scenarios_share_exactly_what_is_unchanged() {
    let base = parse_scenario("", "<test>", &["sim.duration_s=5".into()]).unwrap();
    for sets in [["controller.kp=5"], ["sim.seed=5"]] {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let d = base.derive(&sets, "<test>").unwrap();
        assert!(std::ptr::eq(base.field(), d.field()), "{sets:?}");
    }
    let d = base.derive(&["field.i0=30".into()], "<test>").unwrap();
    assert!(!std::ptr::eq(base.field(), d.field()));
    let fresh = parse_scenario(
        "",
        "<test>",
        &["sim.duration_s=5".into(), "field.i0=30".into()],
    )
    .unwrap();
    assert_eq!(fingerprint(&d), fingerprint(&fresh));
    assert_ne!(fingerprint(&d), fingerprint(&base));

    for text in [
        "[field]\nkind = \"puff_plume\"\n[initial]\nx_m = 5.0\ny_m = 2.0\n[controller]\nlevel = 3.0\n",
        "[vehicle]\nkind = \"fixed_wing\"\ngusts = true\n[field]\ni0 = 20.0\ndecay_per_m = 0.001\n[controller]\nlevel = 10.0\n[initial]\nx_m = 693.0\n",
    ] {
        let sets = ["sim.duration_s=5".to_string()];
        let base = parse_scenario(text, "<test>", &sets).unwrap();
        let d = base.derive(&["sim.seed=9".into()], "<test>").unwrap();
        let fresh =
            parse_scenario(text, "<test>", &[sets[0].clone(), "sim.seed=9".into()]).unwrap();
        assert_eq!(fingerprint(&d), fingerprint(&fresh), "{text}");
        assert_ne!(fingerprint(&d), fingerprint(&base), "{text}");
    }
}

/// The true isoline is shared while the field and the level are; a new level or a new field
/// gets its own.
#[test]
fn the_isoline_follows_the_field_and_the_level() {
    let base = parse_scenario("", "<test>", &["sim.duration_s=5".into()]).unwrap();
    let kp = base.derive(&["controller.kp=5".into()], "<test>").unwrap();
    assert!(std::ptr::eq(base.isoline(), kp.isoline()));
    for set in ["controller.level=5", "field.i0=30"] {
        let d = base.derive(&[set.into()], "<test>").unwrap();
        assert!(!std::ptr::eq(base.isoline(), d.isoline()), "{set}");
    }
}

/// Switching the law keeps the field and vehicle and takes the new law's defaults; the same kind
/// is the scenario itself.
#[test]
fn with_controller_kind_switches_the_law() {
    use isotrack_scenario::schema::ControllerKind;
    let base = parse_scenario("", "<test>", &[]).unwrap();
    let sm = base
        .with_controller_kind(ControllerKind::SlidingMode)
        .unwrap();
    assert_eq!(sm.file().controller.kind, Some(ControllerKind::SlidingMode));
    assert_eq!(sm.file().controller.gamma, Some(0.2));
    assert_eq!(sm.file().controller.kp, None);
    assert!(std::ptr::eq(base.field(), sm.field()));
    let same = base
        .with_controller_kind(ControllerKind::PiIsoline)
        .unwrap();
    assert!(same == base);
}

#[test]
fn only_the_fixed_wing_uav_flies() {
    let dubins = parse_scenario("", "<test>", &[]).unwrap();
    assert!(!dubins.is_flying());
    let uav = parse_scenario("[vehicle]\nkind = \"fixed_wing\"\n", "<test>", &[]).unwrap();
    assert!(uav.is_flying());
}

/// A variant that reads another file takes that file's own geometry, not the one the first
/// file filled in (a hostile review: a sweep over `field.path` ran every file on the first
/// file's grid, silently). Two ESRI ASCII grids of the same values, cell 0.5 m and 1 m, origin
/// (-20, -20) and (-40, -40): the variant on the second has the second's spacing and origin,
/// exactly as a scenario loaded on it directly; a key the user sets stays the user's.
#[test]
fn a_variant_on_another_file_takes_its_geometry() {
    let d = tempfile::tempdir().unwrap();
    let asc = |name: &str, cell: f64| {
        let n = 81;
        let mut t = format!(
            "ncols {n}\nnrows {n}\nxllcorner {}\nyllcorner {}\ncellsize {cell}\n",
            -cell * n as f64 / 2.0,
            -cell * n as f64 / 2.0
        );
        for j in 0..n {
            let row: Vec<String> = (0..n)
                .map(|i| {
                    let (x, y) = (i as f64 - 40.0, j as f64 - 40.0);
                    format!("{}", 20.0 * (-0.1 * (x * x + y * y).sqrt()).exp())
                })
                .collect();
            t.push_str(&row.join(" "));
            t.push('\n');
        }
        let p = d.path().join(name);
        std::fs::write(&p, t).unwrap();
        p.display().to_string()
    };
    let (a, b) = (asc("a.asc", 0.5), asc("b.asc", 1.0));
    let sets = |p: &str| {
        vec![
            "field.kind=\"grid\"".to_string(),
            format!("field.path=\"{p}\""),
            "initial.x_m=5".into(),
            "initial.y_m=0".into(),
        ]
    };
    let base = parse_scenario("", "<test>", &sets(&a)).unwrap();
    let direct = parse_scenario("", "<test>", &sets(&b)).unwrap();
    let variant = base
        .derive(&[format!("field.path=\"{b}\"")], "<test>")
        .unwrap();
    assert_eq!(direct.file().field.spacing_m, Some([1.0, 1.0]));
    assert_eq!(
        variant.file().field.spacing_m,
        direct.file().field.spacing_m
    );
    assert_eq!(variant.file().field.origin_m, direct.file().field.origin_m);
    // The user's own key, set with the new path, is kept.
    let own = base
        .derive(
            &[
                format!("field.path=\"{b}\""),
                "field.spacing_m=[2.0, 2.0]".into(),
            ],
            "<test>",
        )
        .unwrap();
    assert_eq!(own.file().field.spacing_m, Some([2.0, 2.0]));
    // Without another file, the filled-in geometry stays.
    let kp = base.derive(&["controller.kp=5".into()], "<test>").unwrap();
    assert_eq!(kp.file().field.spacing_m, Some([0.5, 0.5]));
}

/// nu-19: a team key assigned onto a base without `[team]` (a sweep's `[grid] team.k_v`) is
/// located at that assignment, naming the key and saying the base has no `[team]` (it was
/// "a value of the base scenario or its default" asking for `team.count`); with `team.count`
/// assigned too, the variant is a team.
#[test]
fn a_team_key_onto_a_base_without_team_names_the_assignment() {
    use isotrack_scenario::Assignment;
    let base = parse_scenario("", "<test>", &[]).unwrap();
    let a = Assignment {
        arg: "team.k_v=0.05".into(),
        label: "sweep s.toml run 0, [grid] team.k_v=0.05".into(),
    };
    let e = base
        .derive_with(std::slice::from_ref(&a), "sweep s.toml run 0")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "sweep s.toml run 0, [grid] team.k_v=0.05: `team.k_v`: the base scenario has no [team]"
        ),
        "{e}"
    );
    assert!(!e.contains("a value of the base scenario"), "{e}");
    let count = Assignment {
        arg: "team.count=1".into(),
        label: "sweep s.toml run 0, [grid] team.count=1".into(),
    };
    let s = base.derive_with(&[a, count], "sweep s.toml run 0").unwrap();
    assert_eq!(s.spec().team.as_ref().map(|t| t.count()), Some(1));
}
