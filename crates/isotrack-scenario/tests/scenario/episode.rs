//! A scenario driven one command at a time (`Scenario::episode`) is the same run as
//! `Scenario::run` when each sample is answered by the scenario's own controller: bit for bit,
//! for every outcome, vehicle and sensor model.

use isotrack_core::IsolineController;
use isotrack_scenario::{load_scenario, parse_scenario, parse_scenario_in, Scenario, Start};
use isotrack_sim::{NoTrace, Outcome, RunResult};
use std::path::Path;

/// Drives an episode with the scenario's controller, as an agent outside the loop would.
fn driven(s: &Scenario, start: Option<Start>, seed: Option<u64>) -> RunResult {
    let mut c = s.controller();
    let mut e = s.episode(start, seed);
    let mut samples = 0u64;
    while let Some(sample) = e.run_to_sample() {
        samples += 1;
        e.command(c.update(&sample.measurement));
    }
    let r = e.result();
    assert_eq!(r.samples, samples);
    r
}

fn scenario(sets: &[&str]) -> Scenario {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    parse_scenario("", "<test>", &sets).unwrap()
}

#[test]
fn default_run_is_the_same_driven_from_outside() {
    let s = scenario(&[]);
    let r = driven(&s, None, None);
    assert_eq!(r, s.run(&mut NoTrace));
    assert_eq!(r.outcome, Outcome::Completed);
    assert_eq!(r.steps, 60_000);
}

/// Noise, delay, lag, quantisation and dropouts: the sensor state travels with the episode.
#[test]
fn imperfect_sensor_run_is_the_same_driven_from_outside() {
    let s = scenario(&[
        "sensor.noise_std=0.02",
        "sensor.delay_s=0.05",
        "sensor.time_constant_s=0.1",
        "sensor.resolution=0.001",
        "sensor.dropout_probability=0.2",
        "sensor.rate_hz=20",
        "sim.duration_s=120",
        "sim.seed=7",
    ]);
    let r = driven(&s, None, None);
    assert_eq!(r, s.run(&mut NoTrace));
    // About a fifth of the samples dropped (binomial: within 4 standard deviations).
    let taken = (r.samples + r.samples_dropped) as f64;
    let sd = (taken * 0.2 * 0.8).sqrt();
    assert!(
        (r.samples_dropped as f64 - 0.2 * taken).abs() < 4.0 * sd,
        "{r:?}"
    );
    // The sensor seed is the episode's: another seed, another noise, another run; the same seed
    // as `sim.seed`, the same run.
    assert_eq!(driven(&s, None, Some(7)), r);
    assert_ne!(driven(&s, None, Some(8)), r);
}

/// A start given to the episode is the start `[initial]` would give.
#[test]
fn episode_start_is_the_initial_section() {
    let s = scenario(&["sim.duration_s=60"]);
    let start = Start {
        x_m: -3.0,
        y_m: 12.5,
        heading_rad: 0.7,
    };
    let moved = s
        .derive(
            &[
                "initial.x_m=-3.0".into(),
                "initial.y_m=12.5".into(),
                "initial.heading_rad=0.7".into(),
            ],
            "<test>",
        )
        .unwrap();
    assert_eq!(driven(&s, Some(start), None), moved.run(&mut NoTrace));
    assert_eq!(moved.start(), start);
}

/// The 6-DOF UAV at 1 Hz on a real map (the paper's Fig. 3), shortened.
#[test]
fn uav_run_is_the_same_driven_from_outside() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper-fig3-uav.toml");
    let s = load_scenario(Some(&path), &["sim.duration_s=120".into()]).unwrap();
    let r = driven(&s, None, None);
    assert_eq!(r, s.run(&mut NoTrace));
    assert_eq!(r.samples, 121);
    // At 30 m/s (trimmed, calm) the speed at the start is the airspeed.
    assert!((s.start_speed_mps(s.start()) - 30.0).abs() < 1e-6);
}

/// A run that leaves a gridded field ends the same way, with the same detail, either way.
#[test]
fn left_field_is_the_same_driven_from_outside() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let text = std::fs::read_to_string(dir.join("volcano.toml")).unwrap();
    // No feedback (a zero turn-rate schedule): the robot drives straight off the DEM.
    let text = text.replace(
        "[controller]\nkind = \"pi_isoline\"\nlevel = 135.0\nkp = 5.0\nki = 0.0\nc1 = 0.1\nc2 = 2.0",
        "[controller]\nkind = \"schedule\"\nlevel = 135.0\ncourse_rate_radps = [[0.0, 0.0]]",
    );
    let s = parse_scenario_in(&text, "volcano.toml", &[], &dir).unwrap();
    let r = driven(&s, None, None);
    assert_eq!(r.outcome, Outcome::LeftField);
    assert_eq!(r, s.run(&mut NoTrace));
}

/// A non-finite command ends the run as `diverged` at the sample that gave it.
#[test]
fn non_finite_command_diverges() {
    let s = scenario(&[]);
    let mut e = s.episode(None, None);
    for _ in 0..100 {
        e.run_to_sample().unwrap();
        e.command(0.1);
    }
    let t = e.run_to_sample().unwrap().measurement.t_s;
    assert!((t - 1.0).abs() < 1e-12);
    e.command(f64::NAN);
    assert_eq!(e.outcome(), Some(Outcome::Diverged));
    assert!(e.run_to_sample().is_none());
    let r = e.result();
    assert_eq!(r.outcome, Outcome::Diverged);
    assert_eq!(r.steps, 99);
    assert!(r.outcome_detail.unwrap().contains("t = 1 s"));
}

/// Issue 30 (att30b item 15): the time in `outcome_detail` is a computed number and is shown
/// as numtext shows computed numbers (six significant digits): a robot driving straight east
/// at 2 m/s from x = -0.695 m leaves the field's domain (x <= 12 m) at the step of
/// t = 635 x 0.01 s, which as an `f64` prints as 6.3500000000000005; the detail says 6.35.
#[test]
fn the_detail_shows_computed_times_short() {
    let s = parse_scenario(
        "[sim]\nduration_s = 20.0\ndt_s = 0.01\n[field]\ndomain_m = [-12.0, 12.0, -12.0, 12.0]\n[vehicle]\nspeed_mps = 2.0\n[initial]\nx_m = -0.695\ny_m = 0.0\nheading_rad = 0.0\n[controller]\nkind = \"schedule\"\ncourse_rate_radps = [[0.0, 0.0]]\n",
        "s.toml",
        &[],
    )
    .unwrap();
    let r = s.run(&mut NoTrace);
    assert_eq!(r.outcome, Outcome::LeftField);
    let detail = r.outcome_detail.unwrap();
    assert!(detail.ends_with("t = 6.35 s"), "{detail}");
}
