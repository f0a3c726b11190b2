//! The baselines on the paper's circular field: each converges under its own conditions, the
//! sliding-mode law fails below the curvature demand `u_max < v/r_d`, and the chattering metric
//! separates the discontinuous laws from the continuous ones.

use isotrack_core::theory::radial_exp_isoline_radius_m;
use isotrack_scenario::parse_scenario;
use isotrack_sim::{NoTrace, Outcome, RunResult};

fn run(kind: &str, sets: &[&str]) -> RunResult {
    let mut all = vec![format!("controller.kind={kind}")];
    all.extend(sets.iter().map(|s| s.to_string()));
    let s = parse_scenario("", "<test>", &all).unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.outcome, Outcome::Completed, "{kind}");
    r
}

fn steady(r: &RunResult) -> f64 {
    r.metrics.steady_state_max_abs_error.unwrap()
}

/// Every law converges on the circular field from the default start with its defaults
/// (u_max = 1 rad/s well above v/r_d = 0.072 rad/s for the sliding modes); the continuous laws
/// with an integral (or the true gradient) to machine precision, the others to a small residual.
#[test]
fn every_baseline_converges_on_the_circular_field() {
    for (kind, tol) in [
        ("pi_isoline", 1e-9),
        ("pid", 1e-9),
        ("gradient_reference", 1e-9),
        ("sliding_mode", 5e-3),
        ("suboptimal_sosm", 5e-3),
        ("pid_crossing", 5e-3),
        ("sliding_mode_smooth", 5e-2),
    ] {
        let r = run(kind, &[]);
        assert!(steady(&r) < tol, "{kind}: steady max |eps| {}", steady(&r));
        assert!(r.metrics.convergence_time_s.is_some(), "{kind}");
    }
}

/// The boundary layer leaves the P-like steady offset of a continuous law without integral:
/// on the orbit `u_max*sigma/phi = -v/d`, with `sigma = chi(eps) = gamma*eps` inside the linear
/// zone, so `eps* = -v*phi/(u_max*gamma*d*)` (d* close to r_d): an independent check of the law.
#[test]
fn smooth_sliding_mode_offset_matches_its_closed_form() {
    let r = run("sliding_mode_smooth", &[]);
    let r_d = radial_exp_isoline_radius_m(20.0, 0.1, 10.0).unwrap();
    // Defaults: phi = 0.05, u_max = 1, gamma = 0.2; v = 0.5. The orbit sits |eps*|/alpha
    // = 0.02 m outside r_d (alpha = k*s_d = 1): a 0.3 % effect, inside the tolerance.
    let predicted = 0.5 * 0.05 / (1.0 * 0.2 * r_d);
    let mean = r.metrics.steady_state_mean_error.unwrap();
    assert!(
        ((-mean) - predicted).abs() < 0.02 * predicted,
        "{mean} vs -{predicted}"
    );
}

/// The discontinuous law's residual is a sampling effect: it scales with the sample period.
#[test]
fn sliding_mode_residual_scales_with_the_sample_period() {
    let e100 = steady(&run("sliding_mode", &["sensor.rate_hz=100"]));
    let e25 = steady(&run("sliding_mode", &["sensor.rate_hz=25"]));
    let ratio = e25 / e100;
    assert!(
        (2.5..6.0).contains(&ratio),
        "4x the period gave {ratio}x the residual"
    );
}

/// `u_max` below the isoline's curvature demand `v/r_d = 0.072 rad/s` cannot turn tightly
/// enough and fails; well above it works (baselines.md section 1).
#[test]
fn sliding_mode_needs_u_max_above_v_over_r_d() {
    let r_d = radial_exp_isoline_radius_m(20.0, 0.1, 10.0).unwrap();
    let demand = 0.5 / r_d;
    let low = run(
        "sliding_mode",
        &[&format!("controller.max_turn_rate_radps={}", 0.7 * demand)],
    );
    assert!(
        steady(&low) > 1.0,
        "u_max = 0.7 v/r_d: steady max |eps| {}",
        steady(&low)
    );
    let high = run("sliding_mode", &["controller.max_turn_rate_radps=0.5"]);
    assert!(steady(&high) < 5e-3, "u_max = 0.5: {}", steady(&high));
}

/// Total variation of omega per second: the sgn laws chatter at the sampling rate, the
/// continuous laws do not.
#[test]
fn chattering_separates_sgn_laws_from_smooth_ones() {
    let chat = |k: &str| run(k, &[]).metrics.chattering_radps2.unwrap();
    for k in ["sliding_mode", "suboptimal_sosm"] {
        assert!(chat(k) > 10.0, "{k}: {}", chat(k));
    }
    for k in [
        "pi_isoline",
        "pid",
        "sliding_mode_smooth",
        "gradient_reference",
    ] {
        assert!(chat(k) < 1e-6, "{k}: {}", chat(k));
    }
}

/// Every controller honours the common turn-rate limit and the turning direction.
#[test]
fn limits_and_direction_are_common() {
    use isotrack_sim::TraceRow;
    for kind in [
        "pi_isoline",
        "sliding_mode",
        "sliding_mode_smooth",
        "suboptimal_sosm",
        "pid",
        "pid_crossing",
        "gradient_reference",
    ] {
        for side in ["right", "left"] {
            let s = parse_scenario(
                "",
                "<test>",
                &[
                    format!("controller.kind={kind}"),
                    "controller.max_turn_rate_radps=0.3".into(),
                    format!("controller.higher_side={side}"),
                ],
            )
            .unwrap();
            let mut rows: Vec<TraceRow> = vec![];
            s.run(&mut rows);
            assert!(rows.iter().all(|r| r.omega_radps.abs() <= 0.3), "{kind}");
            // Direction of travel once tracking: clockwise (negative angular momentum) for
            // "right", counter-clockwise for "left".
            let tail = &rows[rows.len() - 100..];
            let l: f64 = tail
                .windows(2)
                .map(|w| w[0].x_m * (w[1].y_m - w[0].y_m) - w[0].y_m * (w[1].x_m - w[0].x_m))
                .sum();
            let want = if side == "right" { -1.0 } else { 1.0 };
            assert!(l * want > 0.0, "{kind} {side}: {l}");
        }
    }
}
