//! `check`'s spacing loop where vehicles sit on their envelope bounds at the equilibrium, and how
//! far its time constants describe the decay (issue 32, att51-7, att50-9, -12, -6, -13;
//! docs/TEAMS.md, "Theory"): equilibria solved by the test's own bisection, eigenvalues of the
//! 2 x 2 Dirichlet matrix in closed form, the P law's orbit from its balance `kp c1 tanh(eps/c2)
//! = v/d`, against simulation on `scenarios/team-circular-4.toml`'s circle.

use super::team_check::{circular, circular_text, close, team_metrics};
use super::team_check_equilibrium::radius;
use super::team_check_linearised::at_angles;
use isotrack_scenario::check::{check, Verdict};
use isotrack_scenario::parse_scenario;
use isotrack_sim::TraceRow;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Bisection of an increasing `f` for `f(x) = target` on `[lo, hi]`.
fn bisect(f: impl Fn(f64) -> f64, target: f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The largest deviation from the even arc gap `L/4` of the gaps (clockwise, listed order) of
/// the four vehicles' rows at the row whose time is nearest `t`.
fn even_deviation(rows: &[Vec<TraceRow>], t: f64) -> f64 {
    let k = rows[0]
        .iter()
        .enumerate()
        .min_by(|a, b| (a.1.t_s - t).abs().total_cmp(&(b.1.t_s - t).abs()))
        .unwrap()
        .0;
    let n = rows.len();
    (0..n)
        .map(|i| {
            let a = rows[i][k].y_m.atan2(rows[i][k].x_m);
            let b = rows[(i + 1) % n][k].y_m.atan2(rows[(i + 1) % n][k].x_m);
            ((a - b).rem_euclid(TAU) - FRAC_PI_2).abs() * radius()
        })
        .fold(0.0, f64::max)
}

/// att51-7: `team.v_max_mps = v0 = 0.5`: at the even equilibrium every command is v0, on the
/// bound, so a vehicle asked to speed up stays at v0: only the slowing half of each correction
/// acts. The corrections sum to zero, so one vehicle at least is cut; the slowest pattern cuts
/// one (a pin) and slows the rest, the one-pin path's first mode `c (2 - 2 cos(pi/4))`:
/// 24.1 s continuous, where the check said the ring's 7.02 s. The run's gaps decay with it
/// (the deviation from even over 150..250 s). With vehicle 0 given room (`v_max` 0.75) the
/// rest are one-sided and vehicle 0 is not: no time constant (`not_applicable`).
#[test]
fn a_team_on_its_envelope_bound_decays_as_the_one_pin_path() {
    let c = (PI / 4.0).cos();
    let mu = c * (2.0 - 2.0 * (PI / 4.0).cos());
    let cont = 1.0 / (0.1 * mu);
    let sampled = -0.1 / (1.0 - 0.1 * mu * 0.1).ln();
    assert!((cont - 24.142).abs() < 1e-3, "{cont}");
    let s = circular(&["team.v_max_mps=0.5", "output.record_rate_hz=1"]);
    let t = check(&s, None).team.unwrap();
    let sp = &t.spacing;
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    assert_eq!(sp.one_sided_vehicles, [0, 1, 2, 3]);
    assert_eq!(sp.time_constants, Some("one_sided"));
    assert!(
        close(sp.slowest_time_constant_s.unwrap(), sampled, 1e-9),
        "{sp:?}"
    );
    assert!(close(
        sp.slowest_time_constant_continuous_s.unwrap(),
        cont,
        1e-9
    ));
    let text = t.lines().join("\n");
    assert!(text.contains("slowest mode (one-sided)"), "{text}");
    let mut rows: Vec<Vec<TraceRow>> = vec![Vec::new(); 4];
    s.run_team(&mut rows).unwrap().unwrap();
    let (early, late) = (even_deviation(&rows, 150.0), even_deviation(&rows, 250.0));
    let fit = 100.0 / (early / late).ln();
    assert!(
        (fit - sampled).abs() < 0.05 * sampled,
        "{fit} vs {sampled} ({early}, {late})"
    );
    let ctl = circular(&[]);
    let c = check(&ctl, None).team.unwrap().spacing;
    assert!(c.one_sided_vehicles.is_empty() && c.time_constants.is_none());
    let mixed = circular(&[
        "team.v_max_mps=0.5",
        "team.vehicles=[{index=0,speed_mps=0.5,v_max_mps=0.75}]",
    ]);
    let t = check(&mixed, None).team.unwrap();
    assert_eq!(t.spacing.one_sided_vehicles, [1, 2, 3]);
    assert_eq!(t.spacing.time_constants, Some("not_applicable"));
    assert_eq!(t.spacing.slowest_time_constant_s, None);
    let text = t.lines().join("\n");
    assert!(
        text.contains("time constant not applicable: vehicles 1, 2, 3"),
        "{text}"
    );
}

/// The largest [`even_deviation`] over the rows from `from` to `to` s.
fn worst_even_deviation(rows: &[Vec<TraceRow>], from: f64, to: f64) -> f64 {
    rows[0]
        .iter()
        .filter(|r| r.t_s >= from && r.t_s <= to)
        .map(|r| even_deviation(rows, r.t_s))
        .fold(0.0, f64::max)
}

/// att53t-4: every vehicle on `v_max = v0 = 0.5`, 10 Hz ranging, no delay, evenly spread but
/// vehicle 1 0.3 rad off. A vehicle asked to
/// speed up is cut, so the ring's alternating mode (`lambda = 4`, unstable past the free ring's
/// `k_v* = 2/(T c 4)` = 7.07) cannot grow: only patterns whose free vehicles all slow survive,
/// and the fastest is a lone free vehicle between two cut ones, `mu = 2c`, stable while
/// `k_v T 2c < 2`: `k_v* = 2/(T 2c)` = 14.14. At `k_v = 10` the check said `fails`; the run
/// settles (the gaps' deviation from L/4 over 30..40 s under a millimetre); at 16 the lone
/// vehicle's overshoot grows and the run keeps swinging (by more than 5 mm, within the
/// envelope's `(v_max - v_min) T` = 25 mm).
#[test]
fn a_one_sided_team_is_stable_up_to_its_fastest_piece() {
    let c = (PI / 4.0).cos();
    let ring = 2.0 / (0.1 * c * 4.0);
    let one_sided = 2.0 / (0.1 * c * 2.0);
    assert!((ring - 7.0711).abs() < 1e-4 && (one_sided - 14.1421).abs() < 1e-4);
    let at = [0.0, -FRAC_PI_2 + 0.3, -PI, -1.5 * PI];
    let deviation = |k_v: f64| {
        let s = at_angles(
            &at,
            &[
                "team.v_max_mps=0.5",
                &format!("team.k_v={k_v}"),
                "sim.duration_s=40",
                "output.record_rate_hz=10",
            ],
        );
        let t = check(&s, None).team.unwrap();
        let sp = &t.spacing;
        assert!(sp.one_sided_stability, "{sp:?}");
        assert!(
            close(sp.max_stable_k_v_per_s.unwrap(), one_sided, 1e-9),
            "{sp:?}"
        );
        assert!(close(sp.lambda_max.unwrap(), 2.0, 1e-12));
        let text = t.lines().join("\n");
        assert!(text.contains("one-sided law's fastest piece"), "{text}");
        let mut rows: Vec<Vec<TraceRow>> = vec![Vec::new(); 4];
        s.run_team(&mut rows).unwrap().unwrap();
        (t.verdict, worst_even_deviation(&rows, 30.0, 40.0))
    };
    let (verdict, settled) = deviation(10.0);
    assert_eq!(verdict, Verdict::Holds);
    assert!(settled < 1e-3, "{settled}");
    let (verdict, swinging) = deviation(16.0);
    assert_eq!(verdict, Verdict::Fails);
    assert!(swinging > 5e-3 && swinging < 0.025 + 1e-3, "{swinging}");
}

/// att53t-10: four evenly spread but vehicle 1 0.3 rad off, `v_max = 0.5005` (v0 0.5): the
/// deployment asks corrections of up to `k_v` times a range difference of 2.9 m, far past the
/// 0.0005 m/s of room above v0 (and under the 0.25 below), so from the deployment down to range
/// differences of `0.0005/k_v` = 5 mm the law is the one-sided one: its time constant, the
/// one-pin path's `-T/ln(1 - k_v T c (2 - 2 cos(pi/4)))` = 24.1 s, not the ring's 7.02 s (the
/// check gave 7.02 s from a 1e-9 tolerance). The run's decay over 10..60 s agrees within 10 %;
/// with `v_max = 0.75` (as much room above as below) the linear loop's time constant stands, and
/// the bundled cluster (corrections past both bounds' equal rooms) is not one-sided either.
#[test]
fn a_team_near_its_bound_decays_one_sided_from_its_deployment() {
    let c = (PI / 4.0).cos();
    let mu = c * (2.0 - 2.0 * (PI / 4.0).cos());
    let sampled = -0.1 / (1.0 - 0.1 * mu * 0.1).ln();
    assert!((sampled - 24.09).abs() < 0.01, "{sampled}");
    let at = [0.0, -FRAC_PI_2 + 0.3, -PI, -1.5 * PI];
    let s = at_angles(
        &at,
        &[
            "team.v_max_mps=0.5005",
            "sim.duration_s=60",
            "output.record_rate_hz=1",
        ],
    );
    let t = check(&s, None).team.unwrap();
    let sp = &t.spacing;
    assert_eq!(sp.time_constants, Some("one_sided"), "{sp:?}");
    assert_eq!(sp.one_sided_vehicles, [0, 1, 2, 3]);
    assert!(
        close(sp.one_sided_room_mps.unwrap(), 0.0005, 1e-9),
        "{sp:?}"
    );
    assert!(!sp.one_sided_stability);
    assert!(
        close(sp.slowest_time_constant_s.unwrap(), sampled, 1e-9),
        "{sp:?}"
    );
    let text = t.lines().join("\n");
    assert!(text.contains("near the bound, not on it"), "{text}");
    let mut rows: Vec<Vec<TraceRow>> = vec![Vec::new(); 4];
    s.run_team(&mut rows).unwrap().unwrap();
    let (early, late) = (even_deviation(&rows, 10.0), even_deviation(&rows, 60.0));
    let fit = 50.0 / (early / late).ln();
    assert!((fit - sampled).abs() < 0.1 * sampled, "{fit} vs {sampled}");
    let roomy = check(&at_angles(&at, &["team.v_max_mps=0.75"]), None)
        .team
        .unwrap();
    assert_eq!(roomy.spacing.time_constants, None);
    assert!(roomy.spacing.one_sided_vehicles.is_empty());
    let bundled = check(&circular(&[]), None).team.unwrap();
    assert!(bundled.spacing.one_sided_vehicles.is_empty());
}

/// att50-9: vehicles 2 and 3 at 0.3 m/s in [0.15, 0.35], 0 and 1 at 0.5, k_v = 0.1, evenly
/// spread: mean v0 0.4 is past both slow vehicles' v_max, so V = 0.35 is set by both and both
/// saturate (pins). Between them the deployed arcs: a quarter turn from 2 to 3, three quarters
/// from 3 round to 2 filled by ranges `x, x - 1.5, x - 3` ((V - v0)/k_v = -1.5). The free
/// vehicles 0, 1 see `K = [[c3 + c0, -c0], [-c0, c0 + c1]]`: its smallest eigenvalue in closed
/// form gives `tau = -T/ln(1 - k_v mu T)` = 14.49 s (the check said 7.02 s of the free ring at
/// even spacing); the run settles at the equilibrium's gap CV 0.139.
#[test]
fn two_vehicles_saturated_at_one_bound_are_both_pins() {
    let d = 2.0 * radius();
    let arcs = |x: f64| -> f64 {
        [0.0, -1.5, -3.0]
            .iter()
            .map(|o| 2.0 * ((x + o) / d).asin())
            .sum()
    };
    let x = bisect(arcs, 1.5 * PI, 3.0, d);
    let ranges = [x - 1.5, x - 3.0, d * (PI / 4.0).sin(), x];
    assert!(0.3 + 0.1 * (ranges[2] - ranges[1]) > 0.35);
    assert!(0.3 + 0.1 * (ranges[3] - ranges[2]) > 0.35);
    let c: Vec<f64> = ranges
        .iter()
        .map(|r| (1.0 - (r / d).powi(2)).sqrt())
        .collect();
    let (a, b, e) = (c[3] + c[0], -c[0], c[0] + c[1]);
    let mu = 0.5 * (a + e - ((a - e).powi(2) + 4.0 * b * b).sqrt());
    let tau = -0.1 / (1.0 - 0.1 * mu * 0.1).ln();
    assert!((tau - 14.49).abs() < 0.01, "{tau}");
    let arcs_of: Vec<f64> = ranges.iter().map(|r| 2.0 * (r / d).asin()).collect();
    let cv =
        (arcs_of.iter().map(|g| (g - FRAC_PI_2).powi(2)).sum::<f64>() / 4.0).sqrt() / FRAC_PI_2;
    let s = circular(&[
        "team.vehicles=[{index=2,speed_mps=0.3,v_min_mps=0.15,v_max_mps=0.35},{index=3,speed_mps=0.3,v_min_mps=0.15,v_max_mps=0.35}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
        "team.k_v=0.1",
    ]);
    let t = check(&s, None).team.unwrap();
    let eq = t.spacing.shifted_equilibrium.as_ref().unwrap();
    assert!(eq.exists(), "{eq:?}");
    for (got, want) in eq.ranges_m.iter().zip(&ranges) {
        assert!(close(*got, *want, 1e-9), "{eq:?} vs {ranges:?}");
    }
    assert!(close(eq.gap_cv.unwrap(), cv, 1e-9));
    assert_eq!(t.spacing.linearised_about, Some("pinned"));
    let got = t.spacing.slowest_time_constant_s.unwrap();
    assert!(close(got, tau, 1e-9), "{got} vs {tau}");
    let run = team_metrics(&s).gap_cv_final.unwrap();
    assert!((run - cv).abs() < 0.005, "{run} vs {cv}");
}

/// att53t-5: att50-9's team (vehicles 2, 3 at 0.3 m/s in [0.15, 0.35], 0, 1 at 0.5, `k_v =
/// 0.1`, V = 0.35) deployed with the arc from 2 to 3 at 4 m (and 18 m), the other three equal.
/// The free vehicles need `r0 - r3 = r1 - r0 = -1.5` m; an anchor flies V only while its
/// command `0.3 + 0.1 (r_i - r_{i-1})` is at least 0.35, `r_i - r_{i-1} >= 0.5`, and the four
/// differences sum to zero, so the two anchors' share 3 m. Kept as deployed, the 4 m arc left
/// vehicle 2 at `r2 - r1 = -5.7` (command 0.13: not saturated, not an equilibrium); the run
/// moves it back until it is ON its bound: `r2 - r1 = 0.5`, `r3 - r2 = 2.5`, ranges `y, y - 1.5,
/// y - 1, y + 1.5` with arcs summing to a turn (the 18 m arc: vehicle 3 on its bound, `y, y -
/// 1.5, y + 1, y + 1.5`). Vehicle 2 is then no pin but one-sided: no linear time constant. The
/// run settles at the gap CV of those ranges.
#[test]
fn anchors_deployed_off_their_bound_settle_on_it() {
    let d = 2.0 * radius();
    let l = TAU * radius();
    for (arc_m, offsets, on_bound, pin) in [
        (4.0, [0.0, -1.5, -1.0, 1.5], 2usize, 3usize),
        (18.0, [0.0, -1.5, 1.0, 1.5], 3, 2),
    ] {
        let turn = |y: f64| -> f64 { offsets.iter().map(|o| 2.0 * ((y + o) / d).asin()).sum() };
        let y = bisect(turn, TAU, 1.5, d - 1.5);
        let ranges: Vec<f64> = offsets.iter().map(|o| y + o).collect();
        let arcs: Vec<f64> = ranges.iter().map(|r| 2.0 * (r / d).asin()).collect();
        let cv =
            (arcs.iter().map(|g| (g - FRAC_PI_2).powi(2)).sum::<f64>() / 4.0).sqrt() / FRAC_PI_2;
        let g = (l - arc_m) / 3.0 / radius();
        let at = [0.0, -g, -2.0 * g, -2.0 * g - arc_m / radius()];
        let s = at_angles(
            &at,
            &[
                "team.vehicles=[{index=2,speed_mps=0.3,v_min_mps=0.15,v_max_mps=0.35},{index=3,speed_mps=0.3,v_min_mps=0.15,v_max_mps=0.35}]",
                "team.k_v=0.1",
            ],
        );
        let t = check(&s, None).team.unwrap();
        let sp = &t.spacing;
        let eq = sp.shifted_equilibrium.as_ref().unwrap();
        for (got, want) in eq.ranges_m.iter().zip(&ranges) {
            assert!(close(*got, *want, 1e-9), "{eq:?} vs {ranges:?}");
        }
        assert!(close(eq.gap_cv.unwrap(), cv, 1e-9), "{eq:?} vs {cv}");
        assert_eq!(sp.saturated_vehicles, [pin], "{sp:?}");
        assert!(sp.one_sided_vehicles.contains(&on_bound), "{sp:?}");
        assert_eq!(sp.time_constants, Some("not_applicable"));
        let run = team_metrics(&s).gap_cv_final.unwrap();
        assert!((run - cv).abs() < 0.005, "{arc_m}: {run} vs {cv}");
    }
}

/// The P law's orbit radius at speed `v` on team-circular-4's field with `kp = 1`: `kp c1
/// tanh(eps(d)/c2) = v/d`, `eps = 10 - 20 exp(-0.1 d)`, `c1 = 0.2`, `c2 = 1`.
fn p_orbit(v: f64) -> f64 {
    let f = |d: f64| 0.2 * (10.0 - 20.0 * (-0.1 * d).exp()).tanh() - v / d;
    bisect(f, 0.0, radius(), 50.0)
}

/// att50-12: P law (`ki = 0`), vehicle 3 at 0.2 m/s in [0.1, 0.75], k_v = 0.02: every vehicle
/// flies V = mean v0 = 0.425 at the equilibrium, on the orbit of radius 7.2386 m (not v0's
/// 7.2951 m). There the differences (ranges `y, y - 3.75, y - 7.5, y + 3.75`) need the last gap
/// past half the circle: `past_half_circle`, `not_applicable` (the check said `exists` on the
/// wider circle). The run settles on that branch: the root nearest the diameter of
/// `sum_{k<3} 2 asin(r_k/D) + 2 pi - 2 asin(r_3/D) = 2 pi`, gap CV 0.645.
#[test]
fn a_p_law_equilibrium_is_solved_on_the_orbit_of_its_common_speed() {
    let orbit = p_orbit(0.425);
    assert!((orbit - 7.2386).abs() < 1e-4 && (p_orbit(0.5) - 7.2951).abs() < 1e-4);
    let d = 2.0 * orbit;
    let offsets = [0.0, -3.75, -7.5];
    let front = |y: f64| {
        offsets
            .iter()
            .map(|o| 2.0 * ((y + o) / d).asin())
            .sum::<f64>()
    };
    assert!(front(d - 3.75) + PI < TAU, "a gap past half the circle");
    let excess = |y: f64| front(y) - 2.0 * ((y + 3.75) / d).asin();
    let peak = (0..=1000)
        .map(|k| 7.5 + (d - 11.25) * k as f64 / 1000.0)
        .max_by(|a, b| excess(*a).total_cmp(&excess(*b)))
        .unwrap();
    let y = bisect(|y| -excess(y), 0.0, peak, d - 3.75);
    let mut arcs: Vec<f64> = offsets.iter().map(|o| 2.0 * ((y + o) / d).asin()).collect();
    arcs.push(TAU - arcs.iter().sum::<f64>());
    assert!(arcs[3] > PI, "{arcs:?}");
    let cv = (arcs.iter().map(|g| (g - FRAC_PI_2).powi(2)).sum::<f64>() / 4.0).sqrt() / FRAC_PI_2;
    let s = circular(&[
        "controller.kp=1",
        "controller.ki=0",
        "team.vehicles=[{index=3,speed_mps=0.2,v_min_mps=0.1,v_max_mps=0.75}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
        "team.k_v=0.02",
        "sim.duration_s=1500",
    ]);
    let t = check(&s, None).team.unwrap();
    let eq = t.spacing.shifted_equilibrium.as_ref().unwrap();
    assert!(close(eq.speed_mps, 0.425, 1e-12));
    assert!(close(eq.largest_range_m, d, 1e-9), "{eq:?} vs {d}");
    assert_eq!(eq.status, "past_half_circle");
    assert_eq!(t.verdict, Verdict::NotApplicable, "{}", t.verdict_reason);
    let run = team_metrics(&s).gap_cv_final.unwrap();
    assert!((run - cv).abs() < 0.005, "{run} vs {cv}");
}

/// att50-6: off a known circle `range_balance`'s slope is the conservative `c = 1`, the largest
/// a range can have, so the time constants (`1/(k_v lambda_1)` = 5 s continuous here) are lower
/// bounds of the loop's and are labelled so (on the circle the same team's is
/// `1/(k_v cos(pi/4) 2)` = 7.07 s).
#[test]
fn time_constants_from_the_conservative_slope_are_lower_bounds() {
    let plume = "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{ center_m = [0.0, 0.0], amplitude = 20.0, sigma_m = [8.0, 8.0], rotation_rad = 0.0 }]\n[controller]\nlevel = 10.0\n[vehicle]\nkind = \"dubins\"\nspeed_mps = 0.5\n[sim]\nduration_s = 60.0\n[team]\ncount = 4\nspread = { along = \"arc\", center_m = [0.0, 0.0], radius_m = 6.66, step_rad = 0.3 }\nk_v = 0.1\nranging = { rate_hz = 10.0 }\n";
    let p = parse_scenario(plume, "<test>", &[]).unwrap();
    let t = check(&p, None).team.unwrap();
    let sp = &t.spacing;
    assert_eq!(sp.range_slope_source, Some("conservative"));
    assert_eq!(sp.time_constants, Some("lower_bound"));
    assert!(close(
        sp.slowest_time_constant_continuous_s.unwrap(),
        5.0,
        1e-12
    ));
    let text = t.lines().join("\n");
    assert!(text.contains("time constant at least "), "{text}");
    let circle = check(&circular(&[]), None).team.unwrap().spacing;
    let on_circle = circle.slowest_time_constant_continuous_s.unwrap();
    assert!(close(
        on_circle,
        1.0 / (0.1 * (PI / 4.0).cos() * 2.0),
        1e-12
    ));
    assert!(on_circle > 5.0);
}

/// att53t-6: the conservative `c = 1` gives every mode its largest gain, but with a delay (or a
/// gain per period past 1) a sampled mode overshoots and its radius is not monotone in the
/// gain: a gaussian plume whose level-10 set is team-circular-4's circle (`sigma^2 = R^2/(2 ln
/// 2)`), `k_v = 0.15`, 1 Hz, 2 s delay: at `c = 1` the `m = 2` mode has `g = 0.6`, near the
/// delayed loop's `g* = 2 cos(2 pi/5)` = 0.618, and a sampled "at least 116 s" (the run decays
/// some ten times faster). The sampled value is not given there; the continuous one,
/// `1/(k_v lambda_1) = 1/(0.15 x 2)` = 3.33 s, stays a lower bound, and the run's decay (the
/// deviation from L/4 between 40 and 100 s) is slower than it and far faster than 116 s.
#[test]
fn a_delayed_loop_gets_no_sampled_bound_from_the_conservative_slope() {
    let r = radius();
    let sigma = (r * r / (2.0 * std::f64::consts::LN_2)).sqrt();
    let plume = format!("[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{{ center_m = [0.0, 0.0], amplitude = 20.0, sigma_m = [{sigma}, {sigma}], rotation_rad = 0.0 }}]\n[controller]\nlevel = 10.0\n[vehicle]\nkind = \"dubins\"\nspeed_mps = 0.5\n[sim]\nduration_s = 100.0\n[output]\nrecord_rate_hz = 1.0\n[team]\ncount = 4\nspread = {{ along = \"arc\", center_m = [0.0, 0.0], radius_m = {r}, step_rad = 0.3 }}\nk_v = 0.15\nranging = {{ rate_hz = 1.0, delay_s = 2.0 }}\n");
    let p = parse_scenario(&plume, "<test>", &[]).unwrap();
    let t = check(&p, None).team.unwrap();
    let sp = &t.spacing;
    assert_eq!(sp.range_slope_source, Some("conservative"));
    assert_eq!(sp.time_constants, Some("lower_bound"));
    assert_eq!(sp.slowest_time_constant_s, None, "{sp:?}");
    let cont = 1.0 / (0.15 * 2.0);
    assert!(close(
        sp.slowest_time_constant_continuous_s.unwrap(),
        cont,
        1e-12
    ));
    let text = t.lines().join("\n");
    assert!(text.contains("not bounded by c = 1"), "{text}");
    let mut rows: Vec<Vec<TraceRow>> = vec![Vec::new(); 4];
    p.run_team(&mut rows).unwrap().unwrap();
    let (early, late) = (even_deviation(&rows, 40.0), even_deviation(&rows, 100.0));
    let fit = 60.0 / (early / late).ln();
    assert!(fit > cont && fit < 116.0 / 4.0, "{fit} ({early}, {late})");
}

/// att50-13: 600 vehicles evenly on a 693 m circle, vehicle 0 with no speed room: 599 free, past
/// the dense limit, so the spectrum is two bounds. The smallest's lower bound is the Dirichlet
/// path of 599, `c (2 - 2 cos(pi/600))`, listed over `c`; the page names the two as bounds (not
/// "m = 1", "m = 2"), and the continuous time constant `1/(k_v c lambda)` as at most that, the
/// sampled one not computed (it said "none (does not decay)").
#[test]
fn bounds_past_the_dense_limit_are_named_bounds() {
    let r = 1000.0 * std::f64::consts::LN_2;
    let s = parse_scenario(
        &circular_text(),
        "t.toml",
        &[
            "field.decay_per_m=0.001".to_string(),
            "team.count=600".to_string(),
            format!("team.spread.radius_m={r}"),
            format!("team.spread.step_rad={}", TAU / 600.0),
            "team.vehicles=[{index=0,speed_mps=0.5,v_min_mps=0.5,v_max_mps=0.5}]".to_string(),
        ],
    )
    .unwrap();
    let t = check(&s, None).team.unwrap();
    let sp = &t.spacing;
    assert!(sp.eigenvalue_bounds);
    assert_eq!(sp.time_constants, Some("upper_bound"));
    let lambda = 2.0 - 2.0 * (PI / 600.0).cos();
    assert!(close(sp.lambda_min.unwrap(), lambda, 1e-9), "{sp:?}");
    let c = (PI / 600.0).cos();
    let tau = sp.slowest_time_constant_continuous_s.unwrap();
    assert!(close(tau, 1.0 / (0.1 * c * lambda), 1e-9), "{tau}");
    let text = t.lines().join("\n");
    assert!(
        text.contains("lower bound of the smallest: lambda"),
        "{text}"
    );
    assert!(
        text.contains("upper bound of the largest: lambda"),
        "{text}"
    );
    assert!(text.contains("not computed past the dense limit"), "{text}");
    assert!(!text.contains("does not decay"), "{text}");
}
