//! The README's measured numbers, rerun: each bundled scenario (and the anti-windup study) is
//! run afresh and its metrics, formatted at the README's precision, must appear in README.md
//! as printed. A change of the engine that moves a published number fails here until the
//! README says the new one. (The command each number comes from is named next to it in the
//! README: `isotrack run SCENARIO --out DIR`, or the one given with the table.)

use isotrack_scenario::load_scenario;
use isotrack_sim::{NoTrace, Outcome, RunResult};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn readme() -> String {
    std::fs::read_to_string(repo().join("README.md")).unwrap()
}

fn run(name: &str, sets: &[&str]) -> RunResult {
    let path = repo().join("scenarios").join(format!("{name}.toml"));
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let s = load_scenario(Some(&path), &sets).unwrap();
    s.run(&mut NoTrace)
}

/// Asserts that README.md contains `text`.
fn printed(readme: &str, text: &str) {
    assert!(
        readme.contains(text),
        "README.md does not say what a fresh run gives:\n  {text}"
    );
}

/// The table "Measured with `isotrack run SCENARIO --out DIR`".
#[test]
fn the_bundled_scenario_table_is_what_the_runs_give() {
    let readme = readme();
    let m = |name: &str| {
        let r = run(name, &[]);
        assert_eq!(r.outcome, Outcome::Completed, "{name}");
        r.metrics
    };
    // The paper's run ends on the isoline to rounding: printed as a bound.
    let a = m("paper-fig2b-circular");
    assert!(a.steady_state_max_abs_error.unwrap() < 1e-14);
    assert!(a.steady_state_max_isoline_distance_m.unwrap() < 1e-14);
    printed(
        &readme,
        "| `paper-fig2b-circular` | completed | < 1e-14 (rounding) | < 1e-14 m |",
    );
    for (name, label, digits, suffix) in [
        ("paper-fig2a-field", "(kriged NO2, ug/m^3)", 2, ""),
        ("volcano", "(m of elevation)", 2, " (10 m grid)"),
        ("topobathy-bc", "(m of depth)", 1, " (2.43 km grid)"),
    ] {
        let r = m(name);
        printed(
            &readme,
            &format!(
                "| `{name}` {label} | completed | {:.3} | {:.d$} m / {:.d$} m{suffix} |",
                r.steady_state_max_abs_error.unwrap(),
                r.steady_state_max_isoline_distance_m.unwrap(),
                r.steady_state_rms_isoline_distance_m.unwrap(),
                d = digits
            ),
        );
    }
    let ash = m("name-volcanic-ash");
    printed(
        &readme,
        &format!(
            "| `name-volcanic-ash` (log units) | completed | {:.3} | {:.2} m / {:.2} m (0.25 m cells) |",
            ash.steady_state_max_abs_error.unwrap(),
            ash.steady_state_max_isoline_distance_m.unwrap(),
            ash.steady_state_rms_isoline_distance_m.unwrap()
        ),
    );
}

/// The bullets on `paper-fig3-uav`, `era5-isotherm-uav` and `puff-plume-edge`.
#[test]
fn the_bundled_scenario_bullets_are_what_the_runs_give() {
    let readme = readme().replace("\n  ", " ");
    let uav = run("paper-fig3-uav", &[]);
    assert_eq!(uav.outcome, Outcome::Completed);
    let u = &uav.metrics;
    printed(
        &readme,
        &format!(
            "converges in {:.0} s, then stays within {:.0} m (RMS {:.0} m) of the true isoline, `|eps| <= {:.2}`",
            u.convergence_time_s.unwrap(),
            u.steady_state_max_isoline_distance_m.unwrap(),
            u.steady_state_rms_isoline_distance_m.unwrap(),
            u.steady_state_max_abs_error.unwrap()
        ),
    );
    let era5 = run("era5-isotherm-uav", &[]);
    assert_eq!(era5.outcome, Outcome::Completed);
    let e = &era5.metrics;
    printed(
        &readme,
        &format!(
            "steady max |eps| {:.4} degC, within {:.0} m of the moving isotherm (RMS {:.0} m)",
            e.steady_state_max_abs_error.unwrap(),
            e.steady_state_max_isoline_distance_m.unwrap(),
            e.steady_state_rms_isoline_distance_m.unwrap()
        ),
    );
    let puff = run("puff-plume-edge", &[]);
    assert_eq!(puff.outcome, Outcome::Completed);
    let p = &puff.metrics;
    assert_eq!(p.track_losses, 0, "the README says: no track loss");
    printed(
        &readme,
        &format!(
            "within 0.5 of the level {:.0} % of the last 2 minutes, no track loss, within {:.1} m (RMS {:.1} m)",
            100.0 * p.time_in_band_fraction.unwrap(),
            p.steady_state_max_isoline_distance_m.unwrap(),
            p.steady_state_rms_isoline_distance_m.unwrap()
        ),
    );
}

/// The anti-windup table, by the command printed above it.
#[test]
fn the_anti_windup_table_is_what_the_runs_give() {
    let readme = readme();
    for (kind, row) in [
        ("none", "| `none` (the paper) |"),
        ("clamp", "| `clamp` (`\\|ki*sigma\\| <= kp*c1`) |"),
        (
            "conditional",
            "| `conditional` (`\\|eps\\| < c2`), **recommended** |",
        ),
    ] {
        let r = run(
            "circular-far-start-antiwindup",
            &[
                "sim.duration_s=3000",
                "metrics.convergence_tolerance=0.001",
                &format!("controller.anti_windup=\"{kind}\""),
            ],
        );
        assert_eq!(r.outcome, Outcome::Completed, "{kind}");
        let t = r.metrics.convergence_time_s.unwrap();
        printed(&readme, &format!("{row} {t:.0} s |"));
    }
}
