//! `check`'s spacing loop linearised where the team settles (issue 32, att46-1, -16, -9, -7, -5;
//! docs/TEAMS.md, "Theory"): at a shifted equilibrium of unequal nominal speeds each gap has its
//! own chord slope `c_i = cos(g_i/(2R))`, and vehicles with no speed room fix their positions in
//! the frame moving at their speed. The numbers here are the gaps' matrix `L diag(c_i)` built in
//! the test (its eigenvalues by nalgebra's general, non-symmetric solver, not the check's
//! symmetric `K`), closed forms (`2 - 2 cos(pi/N)`) and the equilibria solved by the test's own
//! bisection, against simulation on `scenarios/team-circular-4.toml`'s circle.

use super::team_check::{circular, circular_text, close, team_metrics};
use super::team_check_equilibrium::{cv_of_chords, equilibrium_ranges, radius};
use isotrack_scenario::check::{check, Verdict};
use isotrack_scenario::{parse_scenario, Scenario};
use nalgebra::DMatrix;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The largest eigenvalue of the gaps' loop `g' = -k_v L diag(c) g` (per unit `k_v`): `L` the
/// ring Laplacian `2 g_i - g_{i+1} - g_{i-1}` times `diag(c)`, by nalgebra's general
/// eigenvalue solver (the matrix is not symmetric); its eigenvalues are real.
fn largest_gap_eigenvalue(c: &[f64]) -> f64 {
    let n = c.len();
    let l = DMatrix::from_fn(n, n, |i, j| {
        if i == j {
            2.0
        } else if (i + 1) % n == j || (j + 1) % n == i {
            -1.0
        } else {
            0.0
        }
    });
    let m = l * DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(c));
    m.complex_eigenvalues()
        .iter()
        .map(|z| {
            assert!(z.im.abs() < 1e-9, "{z}");
            z.re
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The chord slopes `cos(g/(2R)) = sqrt(1 - (r/(2R))^2)` of ranges `r` on the circle.
fn chord_slopes(ranges: &[f64]) -> Vec<f64> {
    let d = 2.0 * radius();
    ranges
        .iter()
        .map(|r| (1.0 - (r / d).powi(2)).sqrt())
        .collect()
}

/// team-circular-4's text with `[team]`'s `spread` replaced by listed `starts` on the circle at
/// the angles `at` (clockwise travel: heading `angle - pi/2`).
pub(crate) fn at_angles(at: &[f64], sets: &[&str]) -> Scenario {
    let r = radius();
    let starts: Vec<String> = at
        .iter()
        .map(|a| {
            format!(
                "{{x_m = {}, y_m = {}, heading_rad = {}}}",
                r * a.cos(),
                r * a.sin(),
                a - FRAC_PI_2
            )
        })
        .collect();
    let text: String = circular_text()
        .lines()
        .map(|l| {
            if l.starts_with("spread =") {
                format!("starts = [{}]", starts.join(", "))
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    parse_scenario(&text, "team-circular-4.toml", &sets).unwrap()
}

/// The angles of starts (clockwise from 0) whose chords ahead are `ranges`, one perturbed by
/// `nudge` rad.
fn angles_of(ranges: &[f64], nudge: f64) -> Vec<f64> {
    let d = 2.0 * radius();
    let mut at = vec![0.0];
    for r in &ranges[..ranges.len() - 1] {
        let last = at[at.len() - 1];
        at.push(last - 2.0 * (r / d).asin());
    }
    at[1] += nudge;
    at
}

/// att46-1 (SAFETY): three vehicles at 0.5294 / 1.3513 / 0.5193 m/s (mean 0.8), k_v = 0.12,
/// 0.1 Hz ranging. At even spacing `k_v* = 2/(T cos(pi/3) 3) = 0.1333` and the check said
/// `holds`; at the shifted equilibrium the slopes are about 0.128, 0.751, 0.559 and the gaps'
/// largest eigenvalue 1.99, so `k_v* = 2/(T 1.99) = 0.1005 < 0.12`: unstable, `fails`. The run
/// from the equilibrium (nudged 0.02 rad) saturates at v_min (the gaps swing), while at 0.2 Hz
/// (`k_v* = 0.201`) it stays near V.
#[test]
fn a_shifted_equilibrium_past_its_own_stable_gain_fails() {
    let v0 = [0.5293797830565965, 1.351316676200574, 0.5193035407428296];
    let ranges = equilibrium_ranges(radius(), &v0, 0.12).unwrap();
    let mu = largest_gap_eigenvalue(&chord_slopes(&ranges));
    assert!((mu - 1.99).abs() < 0.01, "{mu}");
    let want = 2.0 / (10.0 * mu);
    assert!((want - 0.1005).abs() < 1e-3, "{want}");
    let vehicles = format!(
        "team.vehicles=[{{index=0,speed_mps={}}},{{index=1,speed_mps={}}},{{index=2,speed_mps={}}}]",
        v0[0], v0[1], v0[2]
    );
    let at = angles_of(&ranges, 0.02);
    let base = [
        "team.count=3",
        "team.k_v=0.12",
        "team.v_min_mps=0.1",
        "team.v_max_mps=2.0",
        "sim.duration_s=800",
    ];
    let mut sets: Vec<&str> = base.to_vec();
    sets.push(&vehicles);
    let slow = [sets.clone(), vec!["team.ranging.rate_hz=0.1"]].concat();
    let s = at_angles(&at, &slow);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    let k = t.spacing.max_stable_k_v_per_s.unwrap();
    assert!(close(k, want, 1e-9), "{k} vs {want}");
    assert_eq!(t.spacing.linearised_about, Some("shifted_equilibrium"));
    let m = team_metrics(&s);
    let [lo, _] = m.speed_range_mps.unwrap();
    assert!(lo < 0.1 + 1e-9, "{m:?}");

    let fast = [sets, vec!["team.ranging.rate_hz=0.2"]].concat();
    let s = at_angles(&at, &fast);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    assert!(close(
        t.spacing.max_stable_k_v_per_s.unwrap(),
        2.0 / (5.0 * mu),
        1e-9
    ));
    // Never saturated (the first period flies the v0_i, 0.519 to 1.351), and settled at the
    // equilibrium's gap CV.
    let m = team_metrics(&s);
    let [lo, hi] = m.speed_range_mps.unwrap();
    assert!(lo > 0.4 && hi < 1.5, "{m:?}");
    let want_cv = cv_of_chords(radius(), &ranges);
    assert!(
        (m.gap_cv_final.unwrap() - want_cv).abs() < 2e-3,
        "{m:?} vs {want_cv}"
    );
}

/// att46-16, the converse: four at 1.8218 / 0.1782 / 1.8218 / 0.1782 m/s (mean 1), k_v =
/// 0.0778, 0.1 Hz: at even spacing `k_v* = 2/(T cos(pi/4) 4) = 0.0707` and the check said
/// `fails`; at the equilibrium the gaps' largest eigenvalue is 2.383, `k_v* = 0.0839 > 0.0778`:
/// stable, and the run settles (no speed near either bound).
#[test]
fn a_shifted_equilibrium_within_its_own_stable_gain_holds() {
    let v0 = [
        1.821798496760,
        0.178201503240,
        1.821798496760,
        0.178201503240,
    ];
    let ranges = equilibrium_ranges(radius(), &v0, 0.0778).unwrap();
    let mu = largest_gap_eigenvalue(&chord_slopes(&ranges));
    assert!((mu - 2.383).abs() < 2e-3, "{mu}");
    let want = 2.0 / (10.0 * mu);
    assert!(want > 0.0778 && (want - 0.0839).abs() < 1e-3, "{want}");
    let vehicles = format!(
        "team.vehicles=[{}]",
        (0..4)
            .map(|i| format!("{{index={i},speed_mps={}}}", v0[i]))
            .collect::<Vec<_>>()
            .join(",")
    );
    let s = at_angles(
        &angles_of(&ranges, 0.01),
        &[
            "team.k_v=0.0778",
            "team.v_min_mps=0.1",
            "team.v_max_mps=2.5",
            "team.ranging.rate_hz=0.1",
            "sim.duration_s=800",
            &vehicles,
        ],
    );
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    assert!(close(t.spacing.max_stable_k_v_per_s.unwrap(), want, 1e-9));
    // Never saturated at 0.1 or 2.5 (the first period flies the v0_i, 0.178 and 1.822), and
    // settled at the equilibrium's gap CV.
    let m = team_metrics(&s);
    let [lo, hi] = m.speed_range_mps.unwrap();
    assert!(lo > 0.15 && hi < 2.4, "{m:?}");
    let want_cv = cv_of_chords(radius(), &ranges);
    assert!(
        (m.gap_cv_final.unwrap() - want_cv).abs() < 2e-3,
        "{m:?} vs {want_cv}"
    );
}

/// att46-9: one vehicle with no speed room at v0 among four (k_v = 0.1, c = cos(pi/4)): in the
/// frame moving at v0 it stands still and the other three form a Dirichlet path, slowest
/// eigenvalue `2 - 2 cos(pi/4)` (not the ring's `2 - 2 cos(pi/2) = 2`): continuous time
/// constant `1/(k_v c (2 - 2 cos(pi/4)))` = 24.1 s (the run's fitted 24.3 s), not 7.07 s; and no
/// "unequal nominal speeds" note when every speed is equal.
#[test]
fn one_vehicle_with_no_speed_room_slows_the_modes() {
    let c = (PI / 4.0).cos();
    let s = circular(&[
        "team.vehicles=[{index=0,speed_mps=0.5,v_min_mps=0.5,v_max_mps=0.5}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
    ]);
    let t = check(&s, None).team.unwrap();
    let sp = &t.spacing;
    assert_eq!(sp.linearised_about, Some("pinned"));
    let want = 1.0 / (0.1 * c * (2.0 - 2.0 * (PI / 4.0).cos()));
    assert!((want - 24.14).abs() < 0.01, "{want}");
    let got = sp.slowest_time_constant_continuous_s.unwrap();
    assert!(close(got, want, 1e-9), "{got} vs {want}");
    // The largest: 2 - 2 cos(3 pi/4), k_v* = 2/(T c lambda) at 10 Hz.
    let top = 2.0 - 2.0 * (3.0 * PI / 4.0).cos();
    assert!(close(
        sp.max_stable_k_v_per_s.unwrap(),
        2.0 / (0.1 * c * top),
        1e-9
    ));
    assert!(
        !sp.not_modelled
            .iter()
            .any(|w| w.contains("unequal nominal speeds")),
        "{:?}",
        sp.not_modelled
    );
}

/// The arcs (rad) of two chords `x` and `x + step` of the circle that together fill `arc`
/// (bisection here).
fn two_chords_filling(step: f64, arc: f64) -> (f64, f64) {
    let d = 2.0 * radius();
    let fill = |x: f64| 2.0 * (x / d).asin() + 2.0 * ((x + step) / d).asin();
    let (mut lo, mut hi) = (0.0, d - step);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if fill(mid) < arc {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (2.0 * (lo / d).asin(), 2.0 * ((lo + step) / d).asin())
}

/// The population CV of arcs about a quarter turn.
fn quarter_cv(arcs: &[f64]) -> f64 {
    let mean = TAU / 4.0;
    (arcs.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / 4.0).sqrt() / mean
}

/// att46-7, att50-10: vehicles 0 and 2 pinned at 0.4 m/s, 1 and 3 free at v0 = 0.5, k_v =
/// 0.02, spread evenly: the team flies 0.4, so each free vehicle needs its range ahead 0.1/k_v
/// = 5 m shorter than behind: chords x and x + 5 of arcs summing to half the circle, gap CV
/// about 0.33; the run settles there. One rule for unequal nominal speeds (att50-10): `holds`
/// claims convergence to that shifted equilibrium, printed with its gap CV, not evenness, with
/// any number of vehicles of no speed room (it was `fails` with two or more and `holds` with
/// one at ten times the CV). Three pinned at 0.5 and one free at 0.4, `k_v = 0.08`: the free
/// vehicle's run fills half the circle with chords `x`, `x + 1.25`, gap CV 0.057: `holds` too.
#[test]
fn pinned_vehicles_slower_than_the_free_hold_at_their_shifted_equilibrium() {
    let (short, long) = two_chords_filling(5.0, PI);
    let cv = quarter_cv(&[short, long, short, long]);
    assert!((cv - 0.33).abs() < 0.01, "{cv}");
    let pin = |i: usize, v: f64| format!("{{index={i},speed_mps={v},v_min_mps={v},v_max_mps={v}}}");
    let s = circular(&[
        &format!("team.vehicles=[{},{}]", pin(0, 0.4), pin(2, 0.4)),
        &format!("team.spread.step_rad={FRAC_PI_2}"),
        "team.k_v=0.02",
        "sim.duration_s=1500",
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let eq = t.spacing.shifted_equilibrium.as_ref().unwrap();
    assert!(close(eq.gap_cv.unwrap(), cv, 1e-9), "{eq:?} vs {cv}");
    assert!(close(eq.speed_mps, 0.4, 1e-12), "{eq:?}");
    let text = t.lines().join("\n");
    assert!(
        text.contains("shifted equilibrium (unequal nominal speeds)"),
        "{text}"
    );
    let m = team_metrics(&s);
    assert!((m.gap_cv_final.unwrap() - cv).abs() < 0.01, "{m:?} vs {cv}");
    let (a2, a3) = two_chords_filling(1.25, PI);
    let cv3 = quarter_cv(&[FRAC_PI_2, FRAC_PI_2, a2, a3]);
    assert!((cv3 - 0.057).abs() < 0.001, "{cv3}");
    let three = circular(&[
        &format!(
            "team.vehicles=[{},{},{},{{index=3,speed_mps=0.4}}]",
            pin(0, 0.5),
            pin(1, 0.5),
            pin(2, 0.5)
        ),
        &format!("team.spread.step_rad={FRAC_PI_2}"),
        "team.k_v=0.08",
    ]);
    let t = check(&three, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let eq = t.spacing.shifted_equilibrium.as_ref().unwrap();
    assert!(close(eq.gap_cv.unwrap(), cv3, 1e-9), "{eq:?} vs {cv3}");
}

/// att46-5: four evenly spread, k_v = 0.02, speeds 0.74 / 0.26 / 0.5 / 0.5: the equilibrium
/// (bisection here) puts vehicles 0 and 1 4.9 mm apart, under the run's 0.5 m close approach:
/// `fails`, naming the range (it said `holds`); the run comes as close.
#[test]
fn an_equilibrium_closer_than_a_collision_fails() {
    let v0 = [0.74, 0.26, 0.5, 0.5];
    let ranges = equilibrium_ranges(radius(), &v0, 0.02).unwrap();
    assert!(ranges[0] < 0.01, "{ranges:?}");
    let s = circular(&[
        "team.vehicles=[{index=0,speed_mps=0.74},{index=1,speed_mps=0.26}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
        "team.k_v=0.02",
        "team.v_min_mps=0.1",
        "team.v_max_mps=1.0",
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("close-approach distance 0.5 m"),
        "{}",
        t.verdict_reason
    );
}

/// team-circular-4 with its field written as one isotropic Gaussian source whose level-10
/// isoline is the same circle (`20 exp(-r^2/(2 s^2)) = 10` at `r = 10 ln 2`: `s = r/sqrt(2 ln
/// 2)`): the check extracts it as a closed polyline, not a known circle.
fn gaussian(sets: &[&str]) -> Scenario {
    let sigma = radius() / (2.0 * std::f64::consts::LN_2).sqrt();
    let mut text = String::new();
    let mut skip = false;
    for l in circular_text().lines() {
        if l.starts_with("[field]") {
            text.push_str(&format!(
                "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [ {{ center_m = [0.0, 0.0], amplitude = 20.0, sigma_m = [{sigma}, {sigma}], rotation_rad = 0.0 }} ]\n"
            ));
            skip = true;
        } else if l.starts_with('[') {
            skip = false;
        }
        if !skip {
            text.push_str(l);
            text.push('\n');
        }
    }
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    parse_scenario(&text, "team-gaussian-4.toml", &sets).unwrap()
}

/// att46-15, -14: on the extracted circle, vehicle 3 at 0.3 m/s with k_v = 0.01 needs ranges
/// 0.15/0.01 = 15 m apart, past the loop's longest chord (its diameter, 13.86 m): `fails` as on
/// the known circle (it said `holds`); with k_v = 0.05 (3 m) the equilibrium is not solved off a
/// circle: `not_applicable`. Two vehicles pinned: their arcs are not measured there:
/// `not_applicable` (the known circle's twin `fails`).
#[test]
fn an_extracted_loop_never_holds_what_a_circle_fails() {
    let slow = "team.vehicles=[{index=3,speed_mps=0.3}]";
    assert!(15.0 > 2.0 * radius());
    let t = check(&gaussian(&["team.k_v=0.01", slow]), None)
        .team
        .unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("no equilibrium exists"),
        "{}",
        t.verdict_reason
    );
    let t = check(&gaussian(&["team.k_v=0.05", slow]), None)
        .team
        .unwrap();
    assert_eq!(t.verdict, Verdict::NotApplicable, "{}", t.verdict_reason);
    let pins = "team.vehicles=[{index=0,v_min_mps=0.5,v_max_mps=0.5},{index=1,v_min_mps=0.5,v_max_mps=0.5}]";
    let t = check(&gaussian(&[pins]), None).team.unwrap();
    assert_eq!(t.verdict, Verdict::NotApplicable, "{}", t.verdict_reason);
    let t = check(&circular(&[pins]), None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
}

/// att46-6: a discovered ring with v_max = 0.5005 (v0 = 0.5) and ranging noise 0.05 m: the probe
/// moves a range by 0.0005 x 10 s = 5 mm, under the fitted change's deviation
/// `0.05 sqrt(12/100)` = 17.3 mm of a least-squares slope over the slot's 100 ranges:
/// `not_applicable` (it said `holds`); the run finds no ring and keeps its cluster. With
/// v_max = 0.55 (0.5 m) the loop's verdict.
#[test]
fn a_discovery_probe_under_the_noise_is_not_judged_holds() {
    let dev = 0.05 * (12.0f64 / 100.0).sqrt();
    assert!(0.0005 * 10.0 < dev && 0.05 * 10.0 > dev);
    let sets = |v: &str| {
        vec![
            "team.ring=\"discovered\"".to_string(),
            "team.ranging.noise_std_m=0.05".to_string(),
            format!("team.v_max_mps={v}"),
            "sim.duration_s=200".to_string(),
        ]
    };
    let s = parse_scenario(&circular_text(), "t.toml", &sets("0.5005")).unwrap();
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::NotApplicable, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("0.0173205"),
        "{}",
        t.verdict_reason
    );
    let m = team_metrics(&s);
    assert_eq!(m.time_to_even_s, None, "{m:?}");
    let s = parse_scenario(&circular_text(), "t.toml", &sets("0.55")).unwrap();
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
}

/// The standard normal's CDF by Simpson's rule on its density from -12 (independent of the
/// check's tail formula).
fn normal_cdf(m: f64) -> f64 {
    let (a, k) = (-12.0, 20_000);
    let h = (m - a) / k as f64;
    let pdf = |x: f64| (-x * x / 2.0).exp() / (2.0 * PI).sqrt();
    let inner: f64 = (1..k)
        .map(|i| pdf(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (pdf(a) + inner + pdf(m)) * h / 3.0
}

/// att50-3: a discovered ring, noise 0.05 m at 10 Hz, 10 s probe slots, the bundled cluster
/// (0.3 rad between neighbours: a range shows `cos(0.15)` of the probe). With v_max = 0.5025
/// and dropout 0.8 the slot keeps `n = 100 x 0.2 = 20` ranges: deviation `0.05 sqrt(12/20)` =
/// 38.7 mm against a 24.7 mm change (it counted 100 ranges, 17.3 mm, and said `holds`; the run
/// finds no ring). With v_max = 0.5019 and no dropout the change is 1.08 deviations: each of
/// the 8 picks right with probability `Phi(1.08)`, all with 0.30 < 0.99: `not_applicable` (the
/// runs lost the ring in 2 of 4 seeds); with v_max = 0.51 (5.7 deviations) `holds`.
#[test]
fn a_discovery_probe_is_judged_with_its_dropouts_and_all_its_picks() {
    let slope = 0.15f64.cos();
    let sets = |v: &str, p: &str| {
        vec![
            "team.ring=\"discovered\"".to_string(),
            "team.ranging.noise_std_m=0.05".to_string(),
            format!("team.ranging.dropout_probability={p}"),
            format!("team.v_max_mps={v}"),
            "sim.duration_s=200".to_string(),
        ]
    };
    let all_right =
        |dv: f64, n: f64| normal_cdf(dv * 10.0 * slope / (0.05 * (12.0 / n).sqrt())).powi(8);
    for (v, p, dv, n) in [
        ("0.5025", "0.8", 0.0025, 20.0),
        ("0.5019", "0.0", 0.0019, 100.0),
    ] {
        let want = all_right(dv, n);
        assert!(want < 0.99, "{want}");
        let s = parse_scenario(&circular_text(), "t.toml", &sets(v, p)).unwrap();
        let t = check(&s, None).team.unwrap();
        assert_eq!(t.verdict, Verdict::NotApplicable, "{}", t.verdict_reason);
        let shown: f64 = t
            .verdict_reason
            .split("all of them with ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|x| x.parse().ok())
            .unwrap_or_else(|| panic!("{}", t.verdict_reason));
        assert!((shown - want).abs() < 1e-4, "{shown} vs {want}");
    }
    let dev = 0.05 * (12.0f64 / 20.0).sqrt();
    assert!((dev - 0.0387298).abs() < 1e-6);
    let s = parse_scenario(&circular_text(), "t.toml", &sets("0.5025", "0.8")).unwrap();
    let m = team_metrics(&s);
    assert_eq!(m.time_to_even_s, None, "{m:?}");
    assert!(all_right(0.01, 100.0) > 0.99);
    let s = parse_scenario(&circular_text(), "t.toml", &sets("0.51", "0.0")).unwrap();
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
}

/// att50-1: vehicle 3 at 0.3 m/s in [0.15, 0.35], the others 0.5 in [0.25, 0.75], k_v = 0.1,
/// 10 Hz: mean v0 0.45 is past vehicle 3's v_max, so V = 0.35 and vehicle 3 takes up the rest:
/// the ranges ahead are `x - 1.5, x - 3, x - 4.5, x` (bisection here) and vehicle 3 commands
/// `0.3 + 0.1 x 4.5 = 0.75`, deep past its bound: a small perturbation leaves it at 0.35, a
/// pin. `K` over vehicles 0..2 (the Dirichlet path, built here, its eigenvalues by the general
/// solver) gives the slowest `mu` 0.390: `tau = -T/ln(1 - k_v mu T)` = 25.6 s (the check kept
/// vehicle 3 free and said 8.05 s; the run's gaps decayed with 25.9 s).
#[test]
fn a_vehicle_saturated_at_the_equilibrium_is_linearised_as_a_pin() {
    let d = 2.0 * radius();
    let offsets = [-1.5, -3.0, -4.5, 0.0];
    let arcs = |x: f64| -> f64 { offsets.iter().map(|o| 2.0 * ((x + o) / d).asin()).sum() };
    let (mut lo, mut hi) = (4.5, d);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if arcs(mid) < TAU {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let ranges: Vec<f64> = offsets.iter().map(|o| lo + o).collect();
    assert!((ranges[3] - 11.902).abs() < 1e-3, "{ranges:?}");
    assert!(0.3 + 0.1 * (ranges[3] - ranges[2]) > 0.35);
    let c = chord_slopes(&ranges);
    let k = DMatrix::from_row_slice(
        3,
        3,
        &[
            c[3] + c[0],
            -c[0],
            0.0,
            -c[0],
            c[0] + c[1],
            -c[1],
            0.0,
            -c[1],
            c[1] + c[2],
        ],
    );
    let mu_min = k
        .complex_eigenvalues()
        .iter()
        .map(|z| z.re)
        .fold(f64::INFINITY, f64::min);
    let tau = -0.1 / (1.0 - 0.1 * mu_min * 0.1).ln();
    assert!((tau - 25.61).abs() < 0.02, "{tau}");
    let s = circular(&[
        "team.vehicles=[{index=3,speed_mps=0.3,v_min_mps=0.15,v_max_mps=0.35}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
        "team.k_v=0.1",
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let eq = t.spacing.shifted_equilibrium.as_ref().unwrap();
    for (a, b) in eq.ranges_m.iter().zip(&ranges) {
        assert!(close(*a, *b, 1e-9), "{eq:?} vs {ranges:?}");
    }
    assert_eq!(t.spacing.linearised_about, Some("pinned"));
    let got = t.spacing.slowest_time_constant_s.unwrap();
    assert!(close(got, tau, 1e-9), "{got} vs {tau}");
    let cont = t.spacing.slowest_time_constant_continuous_s.unwrap();
    assert!(close(cont, 1.0 / (0.1 * mu_min), 1e-9), "{cont}");
}

/// att50-4 (SAFETY): four evenly spread, ranging at 0.05 Hz (T = 20 s), envelope [0.1, 1.0],
/// nominal speeds chosen so the equilibrium's gaps are about 1 / 14 / 14 / 14.55 m. At
/// k_v = 0.02556 the fastest mode's gain per period `g = k_v mu_max T` is 1.4 (the gaps' matrix
/// built here): each sample overshoots by `g - 1` of the error, and the first carries vehicle
/// 0's gap `0.4 x 9.9 = 4 m` past its 1 m equilibrium (it said `holds`; the run drives vehicle
/// 0 through vehicle 1, 6 mm apart); the start rule's model, run at d = 0 too (att54t), shows
/// the pass-through in the first period: `fails`. The control at k_v = 0.01826 (g = 1.0003)
/// overshoots by 3 mm: `holds`.
#[test]
fn an_overshoot_past_the_close_approach_is_not_judged_holds() {
    let r = radius();
    let cases = [
        (
            0.02556,
            [0.781766584731, 0.225495506956, 0.5, 0.492737908313],
        ),
        (
            0.01826,
            [0.701293342613, 0.303894677504, 0.5, 0.494811979883],
        ),
    ];
    for (k, (k_v, v0)) in cases.into_iter().enumerate() {
        let ranges = equilibrium_ranges(r, &v0, k_v).unwrap();
        let g = k_v * largest_gap_eigenvalue(&chord_slopes(&ranges)) * 20.0;
        let arcs: Vec<f64> = ranges
            .iter()
            .map(|c| 2.0 * r * (c / (2.0 * r)).asin())
            .collect();
        let error = arcs
            .iter()
            .map(|a| (a - TAU * r / 4.0).abs())
            .fold(0.0, f64::max);
        let overshoot = (g - 1.0) * error;
        let vehicles: Vec<String> = v0
            .iter()
            .enumerate()
            .map(|(i, v)| format!("{{index={i},speed_mps={v}}}"))
            .collect();
        let s = circular(&[
            &format!("team.vehicles=[{}]", vehicles.join(",")),
            &format!("team.spread.step_rad={FRAC_PI_2}"),
            &format!("team.k_v={k_v}"),
            "team.v_min_mps=0.1",
            "team.v_max_mps=1.0",
            "team.ranging.rate_hz=0.05",
            "sim.duration_s=200",
        ]);
        let t = check(&s, None).team.unwrap();
        if k == 0 {
            assert!(
                (g - 1.4).abs() < 1e-3 && arcs[0] - overshoot < 0.5,
                "{g} {arcs:?}"
            );
            // The start rule (att54t: its model runs at d = 0 too) sees it first: the ranges
            // measured at t = 0 are even, so the first commands are the v0 and gap 0 closes at
            // v0_0 - v0_1 for the whole first period of 20 s, L/4 = 10.888 m in
            // 10.888/0.556 = 19.57 s: the two pass through each other, `fails`.
            assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
            let at: f64 = t
                .verdict_reason
                .split("through each other at t = ")
                .nth(1)
                .and_then(|x| x.split(' ').next())
                .and_then(|x| x.parse().ok())
                .unwrap_or_else(|| panic!("{}", t.verdict_reason));
            let want = TAU * r / 4.0 / (v0[0] - v0[1]);
            assert!((at - want).abs() < 1e-4, "{at} vs {want}");
            let m = team_metrics(&s);
            assert!(m.min_separation_m.unwrap() < 0.5, "{m:?}");
        } else {
            assert!(g > 1.0 && arcs[0] - overshoot > 0.5, "{g} {arcs:?}");
            assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
        }
    }
}

/// The numbers after `key` in `text` up to the next `:`, comma-separated.
fn numbers_after(text: &str, key: &str) -> Vec<f64> {
    let at = text
        .find(key)
        .unwrap_or_else(|| panic!("{key} not in {text}"))
        + key.len();
    let rest = &text[at..];
    rest[..rest.find(':').unwrap()]
        .split(", ")
        .map(|x| x.trim().parse().unwrap())
        .collect()
}

/// att50-11, att50-10: att50-01's B team (vehicle 0 with no speed room at 0.4 m/s, the others
/// free at 0.5 in [0.25, 0.75], k_v = 0.1, evenly spread). The team flies V = 0.4, so each free
/// vehicle's range ahead is 1 m shorter than behind: chords x, x - 1, x - 2, x - 3 whose arcs sum
/// to a turn (bisection here), about 11.24 / 10.24 / 9.24 / 8.24 m, slopes
/// `sqrt(1 - (r/2R)^2)` about 0.586 / 0.674 / 0.746 / 0.804. The page names them as the
/// linearisation's (it named the even spacing's `cos(pi/4)` only), calls vehicle 0 pinned, not
/// saturated, quotes its own envelope [0.4, 0.4], and says what `holds` claims (convergence to
/// that equilibrium, its gap CV beside it); the JSON says which slopes (`linearised_slopes`,
/// `gap_slopes`). The A team (vehicle 3 at 0.3 in [0.15, 0.35]) names vehicle 3 saturated.
#[test]
fn the_page_names_the_linearisations_slopes_and_its_fixed_vehicles() {
    let r = radius();
    let offsets = [0.0, -1.0, -2.0, -3.0];
    let turn = |x: f64| -> f64 {
        offsets
            .iter()
            .map(|o| 2.0 * ((x + o) / (2.0 * r)).asin())
            .sum()
    };
    let (mut lo, mut hi) = (3.0, 2.0 * r);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if turn(mid) < TAU {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let ranges: Vec<f64> = offsets.iter().map(|o| lo + o).collect();
    assert!((ranges[0] - 11.24).abs() < 0.01, "{ranges:?}");
    let slopes = chord_slopes(&ranges);
    assert!((slopes[0] - 0.586).abs() < 1e-3 && (slopes[3] - 0.804).abs() < 1e-3);
    let s = circular(&[
        "team.vehicles=[{index=0,speed_mps=0.4,v_min_mps=0.4,v_max_mps=0.4}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let sp = &t.spacing;
    assert_eq!(sp.linearised_about, Some("pinned"));
    assert_eq!(sp.linearised_slopes, Some("shifted_equilibrium"));
    assert_eq!(sp.pinned_vehicles, vec![0]);
    assert!(sp.saturated_vehicles.is_empty());
    for (a, b) in sp.gap_slopes.iter().zip(&slopes) {
        assert!(close(*a, *b, 1e-9), "{:?} vs {slopes:?}", sp.gap_slopes);
    }
    let text = t.lines().join("\n");
    let key = "linearised about the shifted equilibrium with vehicle 0 (no speed room: v_min_i = v_max_i, pinned) fixed in the frame moving at the team's speed V, each gap with its own chord slope cos(g_i/(2R')) = ";
    let shown = numbers_after(&text, key);
    assert_eq!(shown.len(), 4, "{text}");
    for (a, b) in shown.iter().zip(&slopes) {
        assert!((a - b).abs() < 1e-5, "{shown:?} vs {slopes:?}");
    }
    assert!(
        text.contains("the linearisation below uses each gap's own chord slope instead"),
        "{text}"
    );
    assert!(
        text.contains(
            "the one speed of vehicle 0 (v_min_i = v_max_i: no speed room, pinned, not saturated"
        ),
        "{text}"
    );
    assert!(!text.contains("saturated there"), "{text}");
    assert!(
        text.contains("stays in its own envelope: vehicle 0 [0.4, 0.4] (team.vehicles), the others the team's [team.v_min_mps, team.v_max_mps] = [0.25, 0.75] m/s; vehicle 0 fixed in the linearisation"),
        "{text}"
    );
    // att50-10: what `holds` claims, with the equilibrium's gap CV on the page.
    let cv = cv_of_chords(r, &ranges);
    let line = text
        .lines()
        .find(|l| l.contains("shifted equilibrium (unequal nominal speeds)"))
        .unwrap_or_else(|| panic!("{text}"));
    let got: f64 = line
        .split("gap CV ")
        .nth(1)
        .unwrap()
        .split(':')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((got - cv).abs() < 1e-5, "{got} vs {cv}");
    assert!(line.contains("what `holds` claims"), "{line}");
    assert!(
        text.contains("`holds` then claims that the loop converges to that equilibrium"),
        "{text}"
    );
    // A: vehicle 3 saturated at its own top speed (its command 0.75 > 0.35).
    let a = circular(&[
        "team.vehicles=[{index=3,speed_mps=0.3,v_min_mps=0.15,v_max_mps=0.35}]",
        &format!("team.spread.step_rad={FRAC_PI_2}"),
    ]);
    let t = check(&a, None).team.unwrap();
    assert_eq!(t.spacing.saturated_vehicles, vec![3]);
    assert!(t.spacing.pinned_vehicles.is_empty());
    let text = t.lines().join("\n");
    assert!(
        text.contains("linearised about the shifted equilibrium with vehicle 3 (saturated: the command there is past the vehicle's own envelope bound) fixed"),
        "{text}"
    );
    assert!(
        text.contains("its own envelope: vehicle 3 [0.15, 0.35] (team.vehicles)"),
        "{text}"
    );
}
