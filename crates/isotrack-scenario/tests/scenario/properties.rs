//! Property: whatever the (valid) gains, start, sensor and field, no NaN reaches a trace row,
//! and every metric is finite or absent.

use isotrack_scenario::parse_scenario;
use isotrack_sim::TraceRow;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn no_nan_in_traces_or_metrics(
        kind in prop_oneof![Just("pi_isoline"), Just("sliding_mode"), Just("suboptimal_sosm"), Just("pid"), Just("pid_crossing")],
        field in prop_oneof![Just("radial_exp"), Just("gaussian_plumes"), Just("linear_ramp")],
        x in -40.0..40.0f64, y in -40.0..40.0f64, h in -4.0..4.0f64,
        level in -5.0..25.0f64,
        rate in prop_oneof![Just(100.0), Just(10.0), Just(1.0)],
        noise in 0.0..0.5f64,
        limit in proptest::option::of(0.05..5.0f64),
        speed in 0.1..20.0f64,
        seed in 0u64..1000,
    ) {
        let mut sets = vec![
            format!("controller.kind={kind}"),
            format!("field.kind={field}"),
            format!("initial.x_m={x}"), format!("initial.y_m={y}"), format!("initial.heading_rad={h}"),
            format!("controller.level={level}"),
            format!("sensor.rate_hz={rate}"), format!("sensor.noise_std={noise}"),
            format!("vehicle.speed_mps={speed}"),
            format!("sim.seed={seed}"), "sim.duration_s=30".to_string(),
        ];
        if let Some(l) = limit {
            sets.push(format!("controller.max_turn_rate_radps={l}"));
        }
        let s = parse_scenario("", "<prop>", &sets).unwrap();
        let mut rows: Vec<TraceRow> = vec![];
        let r = s.run(&mut rows);
        for row in &rows {
            for v in [row.t_s, row.x_m, row.y_m, row.heading_rad, row.s, row.error, row.omega_radps] {
                prop_assert!(v.is_finite(), "{row:?}");
            }
            prop_assert!(row.s_measured.is_none_or(f64::is_finite));
        }
        let m = &r.metrics;
        for v in [m.steady_state_max_abs_error, m.steady_state_rms_error, m.steady_state_mean_error,
                  m.convergence_time_s, m.chattering_radps2, m.sign_changes_per_s,
                  m.steady_state_max_isoline_distance_m, m.steady_state_rms_isoline_distance_m].into_iter().flatten() {
            prop_assert!(v.is_finite());
        }
        prop_assert!(m.path_length_m.is_finite() && m.control_effort.is_finite());
    }
}
