//! `check`'s team verdict where the gaps cannot stand still where the linear loop says (issue 32,
//! att44-3, -6, -7, -8, -10; docs/TEAMS.md, "What range_balance can do with the gaps"): the
//! equilibrium of unequal nominal speeds solved here by an independent bisection, the arcs that
//! vehicles with no speed room keep, the discovery probe the envelope cuts, against simulation
//! on `scenarios/team-circular-4.toml` (four robots on the circle of radius `10 ln 2`).

use super::team_check::{circular, close, spread_cv, team_metrics};
use isotrack_scenario::check::{check, Verdict};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The isoline's radius, m.
pub(crate) fn radius() -> f64 {
    10.0 * std::f64::consts::LN_2
}

/// The equilibrium ranges of `range_balance` with nominal speeds `v0` and gain `k_v` on a circle
/// of radius `r`, by direct statement: every vehicle at `V = mean v0`, so
/// `range_i = range_0 + sum_{j = 1..=i} (V - v0_j)/k_v`, with `range_0` bisected until the arcs
/// `2 asin(range_i/(2 r))` sum to a turn; `None` when the ranges cannot all lie in `(0, 2r)`.
pub(crate) fn equilibrium_ranges(r: f64, v0: &[f64], k_v: f64) -> Option<Vec<f64>> {
    let v = v0.iter().sum::<f64>() / v0.len() as f64;
    let offsets: Vec<f64> = (0..v0.len())
        .map(|i| (1..=i).map(|j| (v - v0[j]) / k_v).sum())
        .collect();
    let min = offsets.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = offsets.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    if max - min >= 2.0 * r {
        return None;
    }
    let turn = |r0: f64| -> f64 {
        offsets
            .iter()
            .map(|o| 2.0 * ((r0 + o) / (2.0 * r)).asin())
            .sum()
    };
    let (mut lo, mut hi) = (-min, 2.0 * r - max);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if turn(mid) < TAU {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(offsets.iter().map(|o| lo + o).collect())
}

/// The gap CV of arcs with chords `ranges` on a circle of radius `r`.
pub(crate) fn cv_of_chords(r: f64, ranges: &[f64]) -> f64 {
    let arcs: Vec<f64> = ranges
        .iter()
        .map(|c| 2.0 * (c / (2.0 * r)).asin())
        .collect();
    let mean = arcs.iter().sum::<f64>() / arcs.len() as f64;
    let var = arcs.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / arcs.len() as f64;
    var.sqrt() / mean
}

const SLOW_3: &str = "team.vehicles=[{index=3,speed_mps=0.3}]";

/// att44-6: vehicle 3 at 0.3 m/s, the others at 0.5: the team's speed is V = 0.45 m/s and
/// vehicle 3's range ahead must exceed its range behind by 0.15/k_v. With k_v = 0.01 that is
/// 15 m, more than the circle's diameter 2 R = 13.86 m: no equilibrium, the check fails (it
/// said `holds`). The run shows why: vehicle 3 commands at most 0.3 + k_v 2 R, and the commands'
/// sum stays 4 x 0.45 (the range terms cancel round the ring, none saturates), so the other
/// three's mean speed is at least (4 x 0.45 - v_3 max)/3: with k_v = 0.005 (v_3 <= 0.369 m/s,
/// the others' mean >= 0.477 m/s) over 600 s they gain 64.5 m on it on average, more than the
/// isoline's 43.6 m, so one passes it: the order is lost.
/// With k_v = 0.02 (10 m < 13.86 m) the equilibrium exists and is the one solved here (the
/// start from the bundled cluster meets before it: `fails`, by the start rule).
#[test]
fn unequal_speeds_with_no_equilibrium_fail() {
    let r = radius();
    let v0 = [0.5, 0.5, 0.5, 0.3];
    for k_v in [0.01, 0.005] {
        assert!(equilibrium_ranges(r, &v0, k_v).is_none());
        let s = circular(&[&format!("team.k_v={k_v}"), SLOW_3]);
        let t = check(&s, None).team.unwrap();
        assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
        assert!(
            t.verdict_reason.contains("no equilibrium exists"),
            "{}",
            t.verdict_reason
        );
        let eq = t.spacing.shifted_equilibrium.unwrap();
        assert_eq!(eq.status, "none");
        assert!(close(eq.range_span_m, 0.15 / k_v, 1e-12), "{eq:?}");
        assert!(close(eq.largest_range_m, 2.0 * r, 1e-12), "{eq:?}");
        assert!(close(eq.speed_mps, 0.45, 1e-12), "{eq:?}");
    }
    let k_v = 0.005;
    let (v3_max, l) = (0.3 + k_v * 2.0 * r, TAU * r);
    let others = (4.0 * 0.45 - v3_max) / 3.0;
    let duration = 600.0;
    assert!((others - v3_max) * duration > l * 1.4);
    let s = circular(&[
        &format!("team.k_v={k_v}"),
        SLOW_3,
        &format!("sim.duration_s={duration}"),
    ]);
    let m = team_metrics(&s);
    assert!(!m.order_preserved, "{m:?}");

    let ranges = equilibrium_ranges(r, &v0, 0.02).unwrap();
    let s = circular(&["team.k_v=0.02", SLOW_3, "sim.duration_s=40"]);
    let t = check(&s, None).team.unwrap();
    // The equilibrium exists, but from the bundled cluster (2.08 m apart) vehicle 2 (0.5 m/s)
    // runs into vehicle 3 (0.3 m/s) ahead of it before the loop has spread them: the start
    // rule's model (att54t: run at d = 0 too) passes them through each other, `fails` (it
    // said `holds`), and so does the run.
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    let at: f64 = t
        .verdict_reason
        .split("through each other at t = ")
        .nth(1)
        .and_then(|x| x.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("{}", t.verdict_reason));
    let m = team_metrics(&s);
    assert!(m.min_separation_m.unwrap() < 0.5, "{m:?}");
    let met = m.closest_approach.as_ref().unwrap().t_s;
    assert!((met - at).abs() < 1.0, "{met} vs {at}");
    let eq = t.spacing.shifted_equilibrium.unwrap();
    assert_eq!(eq.status, "exists");
    for (a, b) in eq.ranges_m.iter().zip(&ranges) {
        assert!(close(*a, *b, 1e-9), "{eq:?} vs {ranges:?}");
    }
}

/// att44-7: k_v = 0.05, vehicle 3 at 0.3 m/s: the equilibrium's ranges (bisection here) are
/// (10.238, 9.238, 8.238, 11.238) m; with max_range_m = 10, above the even spacing's 9.80 m but
/// short of two of them, the law sees 10 m there and that equilibrium does not form: the check
/// is `not_applicable` naming the longest (it said `holds`). The runs: without the limit the team
/// settles at the equilibrium's gap CV; with it, far from it.
#[test]
fn an_equilibrium_past_the_range_limit_is_not_judged_holds() {
    let r = radius();
    let ranges = equilibrium_ranges(r, &[0.5, 0.5, 0.5, 0.3], 0.05).unwrap();
    for (a, b) in ranges.iter().zip([10.238, 9.238, 8.238, 11.238]) {
        assert!((a - b).abs() < 1e-3, "{ranges:?}");
    }
    let want_cv = cv_of_chords(r, &ranges);
    let s = circular(&["team.k_v=0.05", SLOW_3, "team.ranging.max_range_m=10.0"]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::NotApplicable, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("unequal nominal speeds") && t.verdict_reason.contains("11.23"),
        "{}",
        t.verdict_reason
    );
    let limited = team_metrics(&s).gap_cv.unwrap();
    let s = circular(&["team.k_v=0.05", SLOW_3]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let eq = t.spacing.shifted_equilibrium.unwrap();
    for (a, b) in eq.ranges_m.iter().zip(&ranges) {
        assert!(close(*a, *b, 1e-9), "{eq:?} vs {ranges:?}");
    }
    let free = team_metrics(&s).gap_cv.unwrap();
    assert!((free - want_cv).abs() < 0.01, "{free} vs {want_cv}");
    assert!((limited - want_cv).abs() > 0.1, "{limited} vs {want_cv}");
}

/// att44-8: vehicles 0, 1 and 2 with no speed room (`team.vehicles` v_min = v_max = 0.5) fly
/// 0.5 m/s whatever the law says, so the arcs 0 -> 1 and 1 -> 2 stay 0.3 rad and 2 -> 0 stays
/// the rest: at best gaps (0.3, 0.3, (2 pi - 0.6)/2, (2 pi - 0.6)/2), a gap CV far above 0.05:
/// `fails` (it said `holds`), quoting the overrides; the run never does better. Every vehicle
/// pinned by its override is quoted by them (not `team.v_min_mps`). Two pinned vehicles already
/// a quarter turn apart (an even start) leave the loop's `holds`.
#[test]
fn vehicles_with_no_speed_room_keep_their_arcs() {
    let pin = |i: usize| format!("{{index={i},v_min_mps=0.5,v_max_mps=0.5}}");
    let three = format!("team.vehicles=[{},{},{}]", pin(0), pin(1), pin(2));
    let rest = (TAU - 0.6) / 2.0;
    let gaps = [0.3, 0.3, rest, rest];
    let mean = TAU / 4.0;
    let best = (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / 4.0).sqrt() / mean;
    let s = circular(&[&three, "sim.duration_s=100"]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason
            .contains("team.vehicles index 0, 1, 2: v_min_mps = v_max_mps = 0.5 m/s")
            && t.verdict_reason.contains(&format!("{best:.4}")[..5]),
        "{} ({best})",
        t.verdict_reason
    );
    let m = team_metrics(&s);
    assert!(
        m.gap_cv_final.unwrap() >= best * (1.0 - 2e-3),
        "{m:?} vs {best}"
    );
    assert_eq!(m.time_to_even_s, None, "{m:?}");

    let all = format!(
        "team.vehicles=[{},{},{},{}]",
        pin(0),
        pin(1),
        pin(2),
        pin(3)
    );
    let t = check(&circular(&[&all]), None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("team.vehicles index 0, 1, 2, 3")
            && !t.verdict_reason.contains("team.v_min_mps"),
        "{}",
        t.verdict_reason
    );

    let two = format!("team.vehicles=[{},{}]", pin(0), pin(1));
    let s = circular(&[&two, &format!("team.spread.step_rad={FRAC_PI_2}")]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
}

/// att44-10: a discovered ring with team.v_max_mps = v0 = 0.5: each probe commands
/// v0 + v0/4 = 0.625 m/s, saturated to 0.5, so no probe changes a speed and the ring is not
/// found; the law is off and the team keeps its cluster (the deployment's gap CV). `fails`
/// naming both (it said `holds`). With v_max = 0.55 the probe is cut to 0.05 m/s but still
/// sorts the ring: the loop's verdict, and a note giving the cut.
#[test]
fn a_discovery_probe_the_envelope_cannot_fly_fails() {
    let s = circular(&[
        "team.ring=\"discovered\"",
        "team.v_max_mps=0.5",
        "sim.duration_s=150",
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("team.v_max_mps = 0.5") && t.verdict_reason.contains("0.625 m/s"),
        "{}",
        t.verdict_reason
    );
    let m = team_metrics(&s);
    let want = spread_cv(0.3, 4);
    assert!(
        close(m.gap_cv_final.unwrap(), want, 2e-3),
        "{m:?} vs {want}"
    );
    assert_eq!(m.time_to_even_s, None, "{m:?}");

    let s = circular(&[
        "team.ring=\"discovered\"",
        "team.v_max_mps=0.55",
        "sim.duration_s=150",
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    assert!(
        t.spacing
            .not_modelled
            .iter()
            .any(|w| w.contains("a speed change of 0.05 m/s instead of 0.125")),
        "{:?}",
        t.spacing.not_modelled
    );
}

/// att44-3: twenty robots with max_range_m just above the even spacing's range
/// `e = 2 R sin(pi/20)`: the verdict stays `holds` (every equilibrium is even), but a silent
/// gap closes at only `2 k_v (max_range_m - e)` while its vehicles' other neighbours sit at `e`,
/// and the check now says the time constants hold once every neighbour is in range.
#[test]
fn a_range_just_above_the_even_spacing_notes_the_slow_spread() {
    let r = radius();
    let e = 2.0 * r * (PI / 20.0).sin();
    let m = 1.02 * e;
    let s = circular(&[
        "team.count=20",
        "team.spread.step_rad=0.0942",
        &format!("team.ranging.max_range_m={m}"),
    ]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let v = t.spacing.silent_gap_closing_mps.unwrap();
    assert!(close(v, 2.0 * 0.1 * (m - e), 1e-9), "{v}");
    assert!(
        t.spacing
            .not_modelled
            .iter()
            .any(|w| w.contains("once every neighbour is in range")),
        "{:?}",
        t.spacing.not_modelled
    );
    // No range limit: nothing falls silent, no such field.
    let t = check(&circular(&["team.count=20"]), None).team.unwrap();
    assert_eq!(t.spacing.silent_gap_closing_mps, None);
}

/// att50-2: `arc_reference` with vehicle 3 at 0.3 m/s, the others at 0.5, four evenly spread:
/// its arc gaps stand still only where every vehicle flies V = 0.45 m/s, `g_i - g_{i-1} =
/// (V - v0_i)/k_v` (slope 1), so with `a = 0.05/k_v` the gaps ahead are `x - a, x - 2a, x - 3a,
/// x` and they sum to `L`: `x = (L + 6a)/4`, vehicle 2's gap `(L - 6a)/4` (closed form here).
/// k_v = 0.005: -4.11 m, no equilibrium with the listed order (`fails`; the run puts two robots
/// on one point); k_v = 0.007018: 0.20 m, under the 0.5 m close approach (`fails`); k_v = 0.02:
/// 7.14 m, the equilibrium solved and `holds` (all three said `holds` without an equilibrium).
#[test]
fn arc_reference_with_unequal_speeds_is_judged_by_its_equilibrium() {
    let l = TAU * radius();
    let gaps = |k_v: f64| {
        let a = 0.05 / k_v;
        let x = (l + 6.0 * a) / 4.0;
        [x - a, x - 2.0 * a, x - 3.0 * a, x]
    };
    let set = |k_v: f64, extra: &[&str]| {
        let mut sets = vec![
            "team.spacing=\"arc_reference\"".to_string(),
            format!("team.k_v={k_v}"),
            SLOW_3.to_string(),
            format!("team.spread.step_rad={FRAC_PI_2}"),
        ];
        sets.extend(extra.iter().map(|s| s.to_string()));
        let refs: Vec<&str> = sets.iter().map(String::as_str).collect();
        circular(&refs)
    };
    // No equilibrium: vehicle 2 would need a negative gap.
    assert!(gaps(0.005)[2] < -4.0);
    let s = set(0.005, &["sim.duration_s=1500"]);
    let t = check(&s, None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("no equilibrium exists") && t.verdict_reason.contains("arc gap"),
        "{}",
        t.verdict_reason
    );
    assert_eq!(t.spacing.shifted_equilibrium.unwrap().status, "none");
    let m = team_metrics(&s);
    assert!(m.min_separation_m.unwrap() < 0.5, "{m:?}");
    // An equilibrium under the close approach.
    let want = gaps(0.007018);
    assert!(want[2] > 0.15 && want[2] < 0.25, "{want:?}");
    let t = check(&set(0.007018, &[]), None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Fails, "{}", t.verdict_reason);
    assert!(
        t.verdict_reason.contains("close-approach distance 0.5 m"),
        "{}",
        t.verdict_reason
    );
    let eq = t.spacing.shifted_equilibrium.unwrap();
    for (a, b) in eq.ranges_m.iter().zip(want) {
        assert!(close(*a, b, 1e-9), "{eq:?} vs {want:?}");
    }
    // The equilibrium well apart: holds, at the closed form's gaps.
    let want = gaps(0.02);
    let t = check(&set(0.02, &[]), None).team.unwrap();
    assert_eq!(t.verdict, Verdict::Holds, "{}", t.verdict_reason);
    let eq = t.spacing.shifted_equilibrium.unwrap();
    assert!(close(eq.speed_mps, 0.45, 1e-12), "{eq:?}");
    assert!(close(eq.largest_range_m, l, 1e-12), "{eq:?}");
    for (a, b) in eq.ranges_m.iter().zip(want) {
        assert!(close(*a, b, 1e-9), "{eq:?} vs {want:?}");
    }
}
