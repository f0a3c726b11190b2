//! Per-vehicle overrides (`[[team.vehicles]]`, issue 32 item 1, docs/TEAMS.md "Per-vehicle
//! overrides") against theory: a slower vehicle under `none` is lapped at the speed difference;
//! under `range_balance` the team settles at the mean nominal speed (or the slow vehicle's top
//! speed when the mean is past it) with the gap offsets the ring's steady state predicts; the
//! refusals name their keys; the check covers every vehicle's speed and sensor rate.

use isotrack_scenario::check::check;
use isotrack_scenario::{parse_scenario, Scenario};
use isotrack_sim::{TraceRow, TraceSink};
use std::f64::consts::TAU;
use std::path::Path;

/// The isoline of team-circular-4: a circle of radius `10 ln 2` m about the origin.
const R: f64 = 10.0 * std::f64::consts::LN_2;

fn circular_text() -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/team-circular-4.toml");
    std::fs::read_to_string(p).unwrap()
}

/// team-circular-4 with `extra` appended to its `[team]` (the file's last section).
fn circular_with(extra: &str, sets: &[&str]) -> Result<Scenario, String> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    parse_scenario(
        &format!("{}\n{extra}\n", circular_text()),
        "team-circular-4.toml",
        &sets,
    )
    .map_err(|e| e.to_string())
}

/// Each vehicle's rows.
fn run_rows(s: &Scenario) -> (isotrack_sim::TeamResult, Vec<Vec<TraceRow>>) {
    let n = s.spec().team.as_ref().unwrap().count();
    let mut sinks: Vec<Vec<TraceRow>> = vec![Vec::new(); n];
    let r = s.run_team(&mut sinks).unwrap().unwrap();
    (r, sinks)
}

/// The unwrapped clockwise arc travelled from the first row, m, at each row.
fn arc_travel(rows: &[TraceRow]) -> Vec<f64> {
    let mut out = Vec::with_capacity(rows.len());
    let mut prev = rows[0].y_m.atan2(rows[0].x_m);
    let mut acc = 0.0;
    for r in rows {
        let a = r.y_m.atan2(r.x_m);
        let mut d = prev - a; // clockwise positive
        d -= TAU * (d / TAU).round();
        acc += d;
        prev = a;
        out.push(acc * R);
    }
    out
}

/// Least-squares slope of `y` over `t`.
fn slope(t: &[f64], y: &[f64]) -> f64 {
    let n = t.len() as f64;
    let (mt, my) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let num: f64 = t.iter().zip(y).map(|(a, b)| (a - mt) * (b - my)).sum();
    let den: f64 = t.iter().map(|a| (a - mt) * (a - mt)).sum();
    num / den
}

/// A slower vehicle under `none` (vehicle 3 at 0.3 m/s, the others at 0.5 m/s): each vehicle
/// holds its own speed, so the fast ones gain `0.2 m/s` on it and lap it every
/// `L/0.2 = 217.8 s`. Over the second half of 300 s the arc vehicle 0 gains on vehicle 3 grows
/// at 0.2 m/s (within 0.5 %); vehicle 0 passes it twice (0.9 R = 6.24 m behind at the start,
/// it catches up at `6.24/0.2 = 31 s` and again at `(6.24 + L)/0.2 = 249 s`), so the order is
/// not preserved; the ideal revisit time is `L/sum v0_i = L/1.8`.
#[test]
fn a_slower_vehicle_under_none_is_lapped_at_the_speed_difference() {
    let s = circular_with(
        "vehicles = [{ index = 3, speed_mps = 0.3 }]",
        &["team.spacing=\"none\"", "output.record_rate_hz=10.0"],
    )
    .unwrap();
    let t = s.spec().team.as_ref().unwrap();
    let m3 = t.speeds(3);
    // The team's explicit envelope is the default of the vehicle's.
    assert_eq!((m3.nominal_mps, m3.min_mps, m3.max_mps), (0.3, 0.25, 0.75));
    assert_eq!(t.speeds(0).nominal_mps, 0.5);
    let (r, rows) = run_rows(&s);
    let a0 = arc_travel(&rows[0]);
    let a3 = arc_travel(&rows[3]);
    let times: Vec<f64> = rows[0].iter().map(|r| r.t_s).collect();
    let half = times.len() / 2;
    let rel: Vec<f64> = a0.iter().zip(&a3).map(|(x, y)| x - y).collect();
    let v_rel = slope(&times[half..], &rel[half..]);
    assert!((v_rel - 0.2).abs() < 0.001, "relative speed {v_rel}");
    // Each vehicle at its own speed (the robot flies its command exactly).
    assert!((slope(&times[half..], &a3[half..]) - 0.3).abs() < 0.002);
    assert!((slope(&times[half..], &a0[half..]) - 0.5).abs() < 0.002);
    // Passes: the arc gained crosses 0.9 R and 0.9 R + L, not 0.9 R + 2 L.
    let gain_end = rel[rel.len() - 1];
    let first = 0.9 * R;
    let l = TAU * R;
    assert!(
        gain_end > first + l && gain_end < first + 2.0 * l,
        "{gain_end}"
    );
    let team = r.team.unwrap();
    assert!(!team.order_preserved);
    let ideal = team.revisit_time_ideal_s;
    assert!(
        (ideal - l / 1.8).abs() < 1e-9 * ideal,
        "{ideal} vs {}",
        l / 1.8
    );
}

/// The ring's steady state with unequal nominal speeds `v0_i`: every vehicle at the common
/// speed `V` (the gaps stand still), so vehicle `i`'s law gives
/// `r_i - r_{i-1} = (V - v0_i)/k_v` for its range ahead `r_i` and behind `r_{i-1}` (chords);
/// summed around the ring the left side vanishes, so `V = mean v0_i` when no command saturates.
/// A vehicle saturated at its top speed `V = v_max_s` takes up the rest,
/// `r_s - r_{s-1} = -sum_{i != s} (V - v0_i)/k_v`. The chords `r_i` then follow from one unknown,
/// fixed by the arc gaps `2 R asin(r_i/(2R))` summing to `L = 2 pi R` (bisection).
fn steady_gaps(v0: &[f64], v: f64, k_v: f64, saturated: Option<usize>) -> Vec<f64> {
    let n = v0.len();
    let mut d: Vec<f64> = v0.iter().map(|u| (v - u) / k_v).collect();
    if let Some(s) = saturated {
        d[s] = 0.0;
        d[s] = -d.iter().sum::<f64>();
    }
    // r_i = x + sum_{j=1..=i} d_j (r_0 = x).
    let offsets: Vec<f64> = (0..n).map(|i| d[1..=i].iter().sum()).collect();
    let arcs = |x: f64| -> Vec<f64> {
        offsets
            .iter()
            .map(|o| 2.0 * R * ((x + o) / (2.0 * R)).clamp(-1.0, 1.0).asin())
            .collect()
    };
    let (mut lo, mut hi) = (
        -offsets.iter().cloned().fold(f64::INFINITY, f64::min),
        2.0 * R - offsets.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
    );
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if arcs(mid).iter().sum::<f64>() < TAU * R {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    arcs(0.5 * (lo + hi))
}

/// The arc gap ahead of each vehicle (to the next in the listed order, clockwise) at row `k`.
fn gaps_at(rows: &[Vec<TraceRow>], k: usize) -> Vec<f64> {
    let n = rows.len();
    (0..n)
        .map(|i| {
            let a = rows[i][k].y_m.atan2(rows[i][k].x_m);
            let b = rows[(i + 1) % n][k].y_m.atan2(rows[(i + 1) % n][k].x_m);
            let mut g = a - b;
            g -= TAU * (g / TAU).floor();
            g * R
        })
        .collect()
}

/// `range_balance` with vehicle 3 at 0.3 m/s and the others at 0.5 m/s (k_v = 0.1, ideal
/// ranging): within the slow vehicle's envelope (top 0.75 m/s) the team settles at the mean
/// `V = 0.45 m/s`, each vehicle moving at it, with the slow one's gap ahead 1.5 m (chord)
/// longer than its gap behind and every other's 0.5 m shorter ([`steady_gaps`]: within 3 cm);
/// with the slow vehicle's top speed at 0.35 m/s, under the mean, the team settles at 0.35 m/s
/// instead, the others' chord offsets -1.5 m and the slow one's +4.5 m.
#[test]
fn range_balance_settles_within_the_slow_vehicle_envelope() {
    let v0 = [0.5, 0.5, 0.5, 0.3];
    for (extra, v, saturated) in [
        ("vehicles = [{ index = 3, speed_mps = 0.3 }]", 0.45, None),
        (
            "vehicles = [{ index = 3, speed_mps = 0.3, v_max_mps = 0.35 }]",
            0.35,
            Some(3),
        ),
    ] {
        let s = circular_with(
            extra,
            &["sim.duration_s=600.0", "output.record_rate_hz=10.0"],
        )
        .unwrap();
        let (r, rows) = run_rows(&s);
        let want = steady_gaps(&v0, v, 0.1, saturated);
        let last = rows[0].len() - 1;
        let got = gaps_at(&rows, last);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 0.03, "{extra}: gaps {got:?} vs {want:?}");
        }
        // Not the even spacing: the offsets are far beyond the tolerance.
        assert!(want.iter().any(|w| (w - TAU * R / 4.0).abs() > 0.4));
        // Every vehicle at the common speed over the last 60 s.
        let times: Vec<f64> = rows[0].iter().map(|r| r.t_s).collect();
        let from = times.len() - 600;
        for (i, rs) in rows.iter().enumerate() {
            let a = arc_travel(rs);
            let u = slope(&times[from..], &a[from..]);
            assert!(
                (u - v).abs() < 0.002,
                "{extra}: vehicle {i} at {u} m/s, want {v}"
            );
        }
        let team = r.team.unwrap();
        assert!(team.order_preserved);
        let l = TAU * R;
        assert!((team.revisit_time_ideal_s - l / 1.8).abs() < 1e-9 * l);
    }
}

/// The refusals name their key: an entry without `index`, an index past the team, one given
/// twice, the other vehicle kind's speed key, a key that makes no sense per vehicle, an
/// envelope that does not hold the speed, a sensor rate that is no whole number of steps, and
/// unequal speeds with a discovered ring.
#[test]
fn bad_overrides_are_refused_by_key() {
    for (extra, sets, key) in [
        (
            "vehicles = [{ speed_mps = 0.3 }]",
            vec![],
            "team.vehicles[0].index",
        ),
        (
            "vehicles = [{ index = 4 }]",
            vec![],
            "team.vehicles[0].index",
        ),
        (
            "vehicles = [{ index = 1 }, { index = 1, speed_mps = 0.4 }]",
            vec![],
            "team.vehicles[1].index",
        ),
        (
            "vehicles = [{ index = 1, airspeed_mps = 0.4 }]",
            vec![],
            "team.vehicles[0].airspeed_mps",
        ),
        (
            "vehicles = [{ index = 1, kind = \"dubins\" }]",
            vec![],
            "kind",
        ),
        ("vehicles = [{ index = 1, level = 3.0 }]", vec![], "level"),
        (
            "vehicles = [{ index = 1, speed_mps = 0.2 }]",
            vec![],
            "team.vehicles[0].v_min_mps",
        ),
        (
            "vehicles = [{ index = 1, speed_mps = 0.8 }]",
            vec![],
            "team.vehicles[0].v_max_mps",
        ),
        (
            "vehicles = [{ index = 2, sensor_rate_hz = 30.0 }]",
            vec![],
            "team.vehicles[0].sensor_rate_hz",
        ),
        (
            "vehicles = [{ index = 2, sensor_noise_std = -1.0 }]",
            vec![],
            "team.vehicles[0].sensor_noise_std",
        ),
        (
            "vehicles = [{ index = 2, speed_mps = 0.4 }]",
            vec!["team.ring=\"discovered\"", "sim.duration_s=200.0"],
            "team.vehicles[0].speed_mps",
        ),
        // att32d-11: an envelope of its own under discovery, refused at its key (the engine
        // refused it after `check` said holds, with "team.vehicles = 4 is out of range").
        (
            "vehicles = [{ index = 2, v_max_mps = 0.55 }]",
            vec!["team.ring=\"discovered\"", "sim.duration_s=200.0"],
            "team.vehicles[0].v_max_mps",
        ),
        (
            "vehicles = [{ index = 1, sensor_rate_hz = 50.0 }, { index = 2, v_min_mps = 0.3 }]",
            vec!["team.ring=\"discovered\"", "sim.duration_s=200.0"],
            "team.vehicles[1].v_min_mps",
        ),
    ] {
        let e = circular_with(extra, &sets).unwrap_err();
        assert!(e.contains(key), "{extra}: {e}");
    }
    // The defaults: without team.v_min_mps / v_max_mps the vehicle's envelope is the team's
    // rule at its own speed (v0/2, 2 v0).
    let text = circular_text()
        .replace("v_min_mps = 0.25\n", "")
        .replace("v_max_mps = 0.75\n", "");
    let s = parse_scenario(
        &format!("{text}\nvehicles = [{{ index = 2, speed_mps = 0.4, sensor_rate_hz = 20.0 }}]\n"),
        "<test>",
        &[],
    )
    .unwrap();
    let t = s.spec().team.as_ref().unwrap();
    let m = t.speeds(2);
    assert_eq!((m.nominal_mps, m.min_mps, m.max_mps), (0.4, 0.2, 0.8));
    assert_eq!((t.v_min_mps, t.v_max_mps), (0.25, 1.0));
    assert_eq!(t.speed_envelope_mps(), (0.2, 1.0));
    assert_eq!(t.sensor(2, s.spec().sensor).rate_hz, 20.0);
    assert_eq!(t.sensor(1, s.spec().sensor).rate_hz, 100.0);
}

/// Overrides that restate the team's settings change nothing: the run is the one without
/// them, bit for bit (the engine then gets no per-vehicle speeds and the same sensors).
#[test]
fn overrides_equal_to_the_team_change_nothing() {
    let plain = circular_with("", &["sim.duration_s=30.0"]).unwrap();
    let same = circular_with(
        "vehicles = [{ index = 1, speed_mps = 0.5, v_min_mps = 0.25, v_max_mps = 0.75, sensor_noise_std = 0.0, sensor_rate_hz = 100.0 }]",
        &["sim.duration_s=30.0"],
    )
    .unwrap();
    assert!(same.spec().team.as_ref().unwrap().member_speeds().is_none());
    let (a, ra) = run_rows(&plain);
    let (b, rb) = run_rows(&same);
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
    assert_eq!(format!("{ra:?}"), format!("{rb:?}"));
}

/// A vehicle's own sensor: its noise makes its measurements differ from its truth while the
/// others' (noiseless) equal theirs; its rate spaces its samples.
#[test]
fn a_vehicle_has_its_own_sensor() {
    struct Samples(Vec<(f64, f64, Option<f64>)>);
    impl TraceSink for Samples {
        fn record(&mut self, r: &TraceRow) {
            self.0.push((r.t_s, r.s, r.s_measured));
        }
    }
    let s = circular_with(
        "vehicles = [{ index = 1, sensor_noise_std = 0.05 }, { index = 2, sensor_rate_hz = 4.0 }]",
        &["sim.duration_s=10.0", "output.record_rate_hz=100.0"],
    )
    .unwrap();
    let mut sinks: Vec<Samples> = (0..4).map(|_| Samples(Vec::new())).collect();
    s.run_team(&mut sinks).unwrap().unwrap();
    let noisy = |k: usize| {
        sinks[k]
            .0
            .iter()
            .filter(|(_, s, m)| m.is_some_and(|m| m != *s))
            .count()
    };
    assert!(noisy(1) > 900, "{}", noisy(1));
    assert_eq!(noisy(0), 0);
    assert_eq!(noisy(3), 0);
    // Vehicle 2 samples every 0.25 s: its measurement changes at most 4 times a second.
    let changes = sinks[2].0.windows(2).filter(|w| w[0].2 != w[1].2).count();
    assert!((38..=41).contains(&changes), "{changes}");
}

/// `check`'s team section with a slow vehicle and a slower sensor: the tracking grid spans the
/// union of the envelopes and holds each `v0_i`; at each speed the radius is the worst over the
/// vehicles' sensor rates, each the single-vehicle check's at that rate and speed; the spacing
/// loop's modes are linearised at the shifted equilibrium (each gap's own chord slope), and the
/// shifted equilibrium is noted.
#[test]
fn the_check_covers_every_vehicle() {
    let s = circular_with(
        "vehicles = [{ index = 3, speed_mps = 0.3, v_min_mps = 0.2, sensor_rate_hz = 4.0 }]",
        &[],
    )
    .unwrap();
    let t = check(&s, None).team.unwrap();
    let tr = &t.tracking;
    assert_eq!(tr.speed_range_mps, [0.2, 0.75]);
    assert_eq!(tr.speeds_mps[0], 0.2);
    assert!(tr.speeds_mps.contains(&0.3) && tr.speeds_mps.contains(&0.5));
    assert_eq!(tr.sensor_rates_hz, [4.0, 100.0]);
    let k = tr.speeds_mps.len() - 1;
    for (i, v) in [(0usize, 0.2), (k, 0.75)] {
        let worst = [4.0, 100.0]
            .iter()
            .map(|rate| {
                let one = circular_with(
                    "",
                    &[
                        &format!("vehicle.speed_mps={v}"),
                        &format!("sensor.rate_hz={rate}"),
                        "team.v_min_mps=0.2",
                        "team.v_max_mps=0.75",
                    ],
                )
                .unwrap();
                check(&one, None).sampled.spectral_radius.unwrap()
            })
            .fold(f64::NEG_INFINITY, f64::max);
        let got = tr.spectral_radii[i].unwrap();
        assert!(
            (got - worst).abs() <= 1e-12 * worst,
            "{v}: {got} vs {worst}"
        );
    }
    // att46-1: the modes are the loop's at its shifted equilibrium, not the even spacing's:
    // each gap's chord slope from the solved ranges, the largest eigenvalue of the gaps'
    // `L diag(c_i)` (nalgebra's general solver here) giving k_v*.
    assert_eq!(t.spacing.linearised_about, Some("shifted_equilibrium"));
    let eq = t.spacing.shifted_equilibrium.as_ref().unwrap();
    let d = 2.0 * 10.0 * std::f64::consts::LN_2;
    let c: Vec<f64> = eq
        .ranges_m
        .iter()
        .map(|r| (1.0 - (r / d).powi(2)).sqrt())
        .collect();
    let n = c.len();
    let l = nalgebra::DMatrix::from_fn(n, n, |i, j| match (i, j) {
        _ if i == j => 2.0,
        _ if (i + 1) % n == j || (j + 1) % n == i => -1.0,
        _ => 0.0,
    }) * nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&c));
    let mu = l
        .complex_eigenvalues()
        .iter()
        .map(|z| z.re)
        .fold(f64::NEG_INFINITY, f64::max);
    let want = 2.0 / (0.1 * mu);
    let got = t.spacing.max_stable_k_v_per_s.unwrap();
    assert!((got - want).abs() <= 1e-9 * want, "{got} vs {want}");
    assert!(t
        .spacing
        .not_modelled
        .iter()
        .any(|m| m.starts_with("team.vehicles: unequal nominal speeds")));
    // `none` checks the nominal speeds only.
    let none = circular_with(
        "vehicles = [{ index = 3, speed_mps = 0.3 }]",
        &["team.spacing=\"none\""],
    )
    .unwrap();
    let tr = check(&none, None).team.unwrap().tracking;
    assert_eq!(tr.speeds_mps, [0.3, 0.5]);
}

/// att32d-1: envelopes with no common speed. Vehicle 1 never commands less than 0.5 m/s,
/// vehicle 3 never more than 0.35 m/s: a spread team keeps its gaps only at one common speed
/// in every envelope (each gap's rate is `v_{i+1} - v_i`), and none exists, so vehicle 1
/// gains at least 0.15 m/s on vehicle 3 whatever `range_balance` commands. `check` fails
/// naming both (it said `holds`), `run`'s warnings say so; the run shows the lapping: vehicle
/// 1's arc travelled exceeds vehicle 3's by at least `0.15 t`.
#[test]
fn disjoint_envelopes_fail_the_check_and_warn() {
    let s = circular_with(
        "vehicles = [{ index = 3, speed_mps = 0.3, v_max_mps = 0.35 }, { index = 1, speed_mps = 0.6, v_min_mps = 0.5 }]",
        &["sim.duration_s=60.0"],
    )
    .unwrap();
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict.as_str(), "fails", "{}", t.verdict_reason);
    for needle in [
        "vehicle 1's slowest command (v_min = 0.5",
        "vehicle 3's fastest (v_max = 0.35",
    ] {
        assert!(t.verdict_reason.contains(needle), "{}", t.verdict_reason);
    }
    let w = isotrack_scenario::check::warnings(&s);
    assert!(
        w.iter()
            .any(|w| w.starts_with("the team check fails: no speed is common")),
        "{w:?}"
    );
    let (_, rows) = run_rows(&s);
    let (a1, a3) = (arc_travel(&rows[1]), arc_travel(&rows[3]));
    let k = rows[1].len() - 1;
    let t_end = rows[1][k].t_s;
    assert!(
        a1[k] - a3[k] >= 0.15 * t_end * 0.99,
        "{} vs {}",
        a1[k] - a3[k],
        0.15 * t_end
    );
    // Envelopes that share a speed (0.35 m/s here): no such failure, no warning.
    let ok = circular_with(
        "vehicles = [{ index = 3, speed_mps = 0.3, v_max_mps = 0.35 }, { index = 1, speed_mps = 0.6, v_min_mps = 0.35 }]",
        &[],
    )
    .unwrap();
    assert!(
        isotrack_scenario::check::team::disjoint_envelopes(ok.spec().team.as_ref().unwrap())
            .is_none()
    );
    assert!(!isotrack_scenario::check::warnings(&ok)
        .iter()
        .any(|w| w.contains("no speed is common")));
}

/// att32d-6: `run`'s warnings (and so `summary.json`'s) carry `check`'s team failure, as they
/// carry a single run's unstable sampled loop. The spacing loop of 4 robots on the circle with
/// ranging at 10 Hz and no delay is stable up to `k_v* = 2/(T cos(pi/4) lambda_max)` with
/// `lambda_max = 4`, `2/(0.1 * 0.7071 * 4) = 7.07 1/s` (Gray 2006, the ring's Laplacian):
/// `k_v = 10` warns, `k_v = 5` does not. A vehicle's own sensor rate of 4 Hz with `kp = 50` makes
/// the tracking loop unstable at its speeds (att32d-10): the team check fails and warns too.
#[test]
fn a_failing_team_check_is_a_run_warning() {
    let k_v_star = 2.0 / (0.1 * (std::f64::consts::PI / 4.0).cos() * 4.0);
    assert!(5.0 < k_v_star && k_v_star < 10.0);
    let team_warning = |sets: &[&str], extra: &str| {
        let s = circular_with(extra, sets).unwrap();
        isotrack_scenario::check::warnings(&s)
            .into_iter()
            .find(|w| w.starts_with("the team check fails"))
    };
    let w = team_warning(&["team.k_v=10.0"], "").expect("k_v = 10 warns");
    assert!(
        w.contains("team.k_v = 10 is past the largest stable k_v*"),
        "{w}"
    );
    assert_eq!(team_warning(&["team.k_v=5.0"], ""), None);
    let w = team_warning(
        &["controller.kp=50.0"],
        "vehicles = [{ index = 2, sensor_rate_hz = 4.0 }]",
    )
    .expect("a 4 Hz vehicle warns");
    assert!(w.contains("tracking loop is unstable"), "{w}");
    assert_eq!(team_warning(&["controller.kp=50.0"], ""), None);
}

/// att32d-10: the backward difference's noise warning for a vehicle's own sensor noise, with
/// its own number `sqrt(2) noise rate` (0.05 at 100 Hz: 7.071e0), naming the vehicle; none
/// for the others, none without noise.
#[test]
fn a_vehicle_noise_override_warns_naming_the_vehicle() {
    let s = circular_with("vehicles = [{ index = 2, sensor_noise_std = 0.05 }]", &[]).unwrap();
    let w = isotrack_scenario::check::warnings(&s);
    let noise: Vec<&String> = w
        .iter()
        .filter(|w| w.contains("backward difference"))
        .collect();
    assert_eq!(noise.len(), 1, "{w:?}");
    let want = format!("{:.3e}", std::f64::consts::SQRT_2 * 0.05 * 100.0);
    assert!(noise[0].starts_with("vehicle 2: its sensor noise (0.05 field units at 100 Hz"));
    assert!(noise[0].contains(&want), "{} vs {want}", noise[0]);
    let plain = circular_with("", &[]).unwrap();
    assert!(!isotrack_scenario::check::warnings(&plain)
        .iter()
        .any(|w| w.contains("backward difference")));
}

/// att32d-2: vehicle 3 at 0.3 m/s with top speed 0.35 m/s, the others at 0.5 m/s: the mean
/// nominal speed 0.45 m/s is past vehicle 3's top, so the team settles at
/// `V = clamp(0.45, max v_min_i, min v_max_i) = 0.35 m/s` (the simulation's, checked in
/// `range_balance_settles_within_the_slow_vehicle_envelope`): the check's note says so and
/// names vehicle 3 (it said "the team moves at the mean v0 = 0.45 m/s"); within the envelope
/// (top 0.75 m/s) it still says the mean.
#[test]
fn the_equilibrium_note_clamps_to_the_envelopes() {
    let note = |extra: &str| {
        let s = circular_with(extra, &[]).unwrap();
        check(&s, None)
            .team
            .unwrap()
            .spacing
            .not_modelled
            .into_iter()
            .find(|m| m.starts_with("team.vehicles: unequal nominal speeds"))
            .unwrap()
    };
    let v = 0.45_f64.clamp(0.25, 0.35);
    let n = note("vehicles = [{ index = 3, speed_mps = 0.3, v_max_mps = 0.35 }]");
    assert!(
        n.contains(&format!(
            "min v_max_i) = {v} m/s, vehicle 3's top speed v_max"
        )),
        "{n}"
    );
    assert!(n.contains("L/(N V)"), "{n}");
    let n = note("vehicles = [{ index = 3, speed_mps = 0.3 }]");
    assert!(
        n.contains("the team moves at the mean v0 = 0.45 m/s"),
        "{n}"
    );
}

/// att32d-9: `team.k_v = 0` under `range_balance` commands `v0` whatever the ranges: no
/// spacing loop (every mode's roots at `z = 1`, marginal), so `check` neither calls 0 "past
/// k_v*" nor gives a saturation bound, and checks the tracking loop at `v0` only, as for
/// `none`; the run is the `none` run (the same team metrics, bit for bit).
#[test]
fn k_v_zero_is_no_spacing_loop() {
    let zero = circular_with("", &["team.k_v=0.0", "sim.duration_s=20.0"]).unwrap();
    let t = check(&zero, None).team.unwrap();
    assert_ne!(t.verdict.as_str(), "fails", "{}", t.verdict_reason);
    assert!(!t.spacing.applicable);
    assert!(
        t.spacing
            .note
            .starts_with("team.k_v = 0: range_balance commands v0"),
        "{}",
        t.spacing.note
    );
    assert_eq!(t.spacing.saturated_gap_amplitude_m, None);
    assert_eq!(t.spacing.saturated_gap_cv_max, None);
    assert_eq!(t.tracking.speeds_mps, [0.5]);
    let none = circular_with("", &["team.spacing=\"none\"", "sim.duration_s=20.0"]).unwrap();
    let a = zero
        .run_team(&mut [] as &mut [isotrack_sim::NoTrace])
        .unwrap()
        .unwrap();
    let b = none
        .run_team(&mut [] as &mut [isotrack_sim::NoTrace])
        .unwrap()
        .unwrap();
    assert_eq!(format!("{:?}", a.team), format!("{:?}", b.team));
}

/// att32d-15: past `k_v*` the saturated gaps swing by up to the widest speed difference any
/// vehicle can command times `T + d`: with vehicle 1's top at 0.95 m/s and vehicle 2's bottom
/// at 0.05 m/s, `(0.95 - 0.05) 0.1 = 0.09 m` (the team's [0.25, 0.75] gave 0.05 m, which the
/// simulation exceeds: 0.084 m), and the CV bound `0.09 N/L`. The simulation's last 20 % of
/// 400 s stays within it.
#[test]
fn the_saturation_bound_uses_every_envelope() {
    let s = circular_with(
        "vehicles = [{ index = 1, v_max_mps = 0.95 }, { index = 2, v_min_mps = 0.05 }]",
        &[
            "team.k_v=20.0",
            "sim.duration_s=400.0",
            "output.record_rate_hz=10.0",
        ],
    )
    .unwrap();
    let sp = check(&s, None).team.unwrap().spacing;
    let amp = (0.95 - 0.05) * 0.1;
    let got = sp.saturated_gap_amplitude_m.unwrap();
    assert!((got - amp).abs() < 1e-12, "{got} vs {amp}");
    let cv = sp.saturated_gap_cv_max.unwrap();
    assert!((cv - amp * 4.0 / (TAU * R)).abs() < 1e-12, "{cv}");
    let (_, rows) = run_rows(&s);
    let even = TAU * R / 4.0;
    let from = rows[0].len() * 4 / 5;
    let mut worst: f64 = 0.0;
    for k in from..rows[0].len() {
        for g in gaps_at(&rows, k) {
            worst = worst.max((g - even).abs());
        }
    }
    assert!(
        worst > 0.05,
        "the team's own envelope would bound it: {worst}"
    );
    assert!(worst <= amp, "{worst} vs {amp}");
}

/// att32d-13: a fixed wing with its own nominal airspeed starts trimmed at it, not at the
/// scenario's `vehicle.airspeed_mps` (30 m/s): its first trace row reads its own `v0_i`
/// (20 and 44 m/s here), and under `none` (the command `v0_i` throughout) its airspeed stays
/// within 1.5 m/s of it for the whole run (it began 10 m/s off and, from 30 m/s, dipped to
/// 17.6 m/s). The vehicle without an override flies as in the team without overrides, bit for
/// bit. Three UAVs on the circle of radius 600 m of a radial field, no gusts.
#[test]
fn a_fixed_wing_member_starts_at_its_own_airspeed() {
    let uav = "[field]\nkind = \"radial_exp\"\ni0 = 20.0\ndecay_per_m = 0.001\n\
        [vehicle]\nkind = \"fixed_wing\"\nairspeed_mps = 30.0\n\
        [sensor]\nrate_hz = 1.0\n\
        [controller]\nlevel = 10.976\nkp = 150.0\nki = 0.0\nc1 = 0.0005\nc2 = 0.1\n\
        [sim]\ndt_s = 0.01\nduration_s = 60.0\nseed = 9\n\
        [team]\nspacing = \"none\"\nspread = { along = \"arc\", radius_m = 600.0, step_rad = 0.5 }\ncount = 3\n";
    let overrides =
        "vehicles = [{ index = 1, airspeed_mps = 20.0 }, { index = 2, airspeed_mps = 44.0 }]\n";
    let rows = |text: &str| {
        let s = parse_scenario(text, "<test>", &[]).unwrap();
        let mut sinks = vec![Vec::<TraceRow>::new(), Vec::new(), Vec::new()];
        s.run_team(&mut sinks).unwrap().unwrap();
        sinks
    };
    let sinks = rows(&format!("{uav}{overrides}"));
    for (i, v0) in [(0, 30.0), (1, 20.0), (2, 44.0)] {
        let first = sinks[i][0].telemetry.unwrap().airspeed_mps;
        assert!((first - v0).abs() < 1e-9, "vehicle {i}: starts at {first}");
        for row in &sinks[i] {
            let va = row.telemetry.unwrap().airspeed_mps;
            assert!(
                (va - v0).abs() < 1.5,
                "vehicle {i} at t = {}: {va}",
                row.t_s
            );
        }
    }
    let plain = rows(uav);
    assert_eq!(format!("{:?}", sinks[0]), format!("{:?}", plain[0]));
}

/// att32d-16: an envelope bound the entry does not give, refused at the entry's key, says where
/// it comes from, and a fixed wing's top is its safe airspeed (45 m/s), not the scenario bound
/// (the message read "must be in [the vehicle's nominal speed 45, 1000], got 40").
#[test]
fn an_inherited_bound_is_named_in_the_refusal() {
    let uav = "[field]\nkind = \"radial_exp\"\ni0 = 20.0\ndecay_per_m = 0.001\n\
        [vehicle]\nkind = \"fixed_wing\"\nairspeed_mps = 30.0\n\
        [controller]\nlevel = 10.976\nkp = 150.0\nki = 0.0\nc1 = 0.0005\nc2 = 0.1\n\
        [team]\nspacing = \"none\"\ncount = 2\nv_max_mps = 40.0\n\
        spread = { along = \"arc\", radius_m = 600.0, step_rad = 0.5 }\n\
        vehicles = [{ index = 0, airspeed_mps = 45.0 }]\n";
    let e = parse_scenario(uav, "<test>", &[]).unwrap_err().to_string();
    for needle in [
        "team.vehicles[0].v_max_mps",
        "[the vehicle's nominal speed 45, 45], got 40 (not given here: from team.v_max_mps)",
    ] {
        assert!(e.contains(needle), "{e}");
    }
}

/// att32d-16: the tracking grid over `[0.1, 0.9]` m/s has `0.1 + 0.8 * 2/8`, which rounds to
/// 0.30000000000000004; vehicle 3's nominal 0.3 m/s takes its place rather than being listed
/// beside it: nine speeds, 0.3 once.
#[test]
fn the_tracking_grid_lists_a_nominal_speed_once() {
    let s = circular_with(
        "vehicles = [{ index = 3, speed_mps = 0.3, v_min_mps = 0.1, v_max_mps = 0.9 }]",
        &[],
    )
    .unwrap();
    let tr = check(&s, None).team.unwrap().tracking;
    assert_eq!(tr.speed_range_mps, [0.1, 0.9]);
    assert_ne!(0.1 + 0.8 * 2.0 / 8.0, 0.3);
    assert_eq!(
        tr.speeds_mps
            .iter()
            .filter(|v| (**v - 0.3).abs() < 1e-6)
            .count(),
        1,
        "{:?}",
        tr.speeds_mps
    );
    assert!(tr.speeds_mps.contains(&0.3) && tr.speeds_mps.contains(&0.5));
    // The grid's nine points, 0.5 (the others' speed) among them.
    assert_eq!(tr.speeds_mps.len(), 9, "{:?}", tr.speeds_mps);
}

/// ver30b-6: a discovered ring of four needs a run longer than 60 + 4 * 10 = 100 s (the probes
/// must end before the run does): 100 s is refused with a message that says "longer than"
/// (it said "needs 100 s ... but sim.duration_s = 100"), without the stray "= ", and 100.01 s
/// is accepted.
#[test]
fn a_discovered_ring_needs_a_run_longer_than_its_probes() {
    let e = circular_with("", &["team.ring=\"discovered\"", "sim.duration_s=100.0"]).unwrap_err();
    assert!(
        e.contains("`team.ring`: \"discovered\" needs a run longer than 100 s (60 s settling + 10 s per vehicle"),
        "{e}"
    );
    assert!(circular_with("", &["team.ring=\"discovered\"", "sim.duration_s=100.01"]).is_ok());
}
