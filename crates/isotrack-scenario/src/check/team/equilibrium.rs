//! Where the gaps can stand still at all (issue 32, att44-6, -7, -8): the equilibrium of
//! `range_balance` with unequal nominal speeds solved on a known circle (docs/TEAMS.md, "Per-vehicle
//! overrides"), and the arcs that vehicles with no speed room (`v_min_i = v_max_i`) keep.

use crate::check::team_ring::{common_speed, disjoint_envelopes, start_angle, travel_direction};
use crate::spec::TeamSpec;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_sim::team::metrics::TeamMetricsConfig;
use isotrack_sim::team::spacing::{RingMode, SpacingLaw};
use serde::Serialize;
use std::f64::consts::TAU;

use crate::check::setup::Law;

/// `range_balance`'s equilibrium with unequal nominal speeds on a known circle: every vehicle
/// flies one speed `V`, so vehicle `i`'s range ahead exceeds its range behind by
/// `d_i = (V - v0_i)/k_v` (the vehicle whose envelope bound sets `V` takes up the rest), the
/// ranges are chords `2 R' sin(theta/2)` of the circle flown (radius `R'`) and the arcs sum to
/// a turn. Solved by bisection on the ranges' common offset.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShiftedEquilibrium {
    /// The common speed `V`, m/s.
    pub speed_mps: f64,
    /// The spread of the ranges the differences `d_i` need round the ring (largest partial sum
    /// less the smallest), m.
    pub range_span_m: f64,
    /// The longest range a law can see: the circle's diameter `2 R'`, or
    /// `team.ranging.max_range_m` when shorter, m.
    pub largest_range_m: f64,
    /// `exists` (the ranges below), `none` (the span reaches `largest_range_m`, or the arcs
    /// overfill the circle even with two vehicles touching) or `past_half_circle` (a gap would
    /// exceed half the circle, where the range shrinks as the gap grows: not the linear loop).
    pub status: &'static str,
    /// Each vehicle's range ahead at the equilibrium (listed order), m (empty unless `exists`).
    pub ranges_m: Vec<f64>,
}

impl ShiftedEquilibrium {
    /// Whether the equilibrium exists.
    pub fn exists(&self) -> bool {
        self.status == "exists"
    }
}

/// The vehicles of `team` with no speed room (`v_min_i = v_max_i`), in the listed order.
pub(super) fn pinned(team: &TeamSpec) -> Vec<usize> {
    (0..team.count())
        .filter(|&i| {
            let v = team.speeds(i);
            v.min_mps == v.max_mps
        })
        .collect()
}

/// The keys that pin the vehicles `ids` (each with `v_min_i = v_max_i`): the overrides in
/// `team.vehicles` and the team's own `team.v_min_mps = team.v_max_mps`, with the speed.
pub(super) fn pinned_keys(team: &TeamSpec, ids: &[usize]) -> String {
    let list = |v: &[usize]| {
        v.iter()
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (own, team_wide): (Vec<usize>, Vec<usize>) =
        ids.iter().partition(|&&i| team.vehicle(i).is_some());
    let mut parts = vec![];
    if !own.is_empty() {
        parts.push(format!(
            "team.vehicles index {}: v_min_mps = v_max_mps = {} m/s",
            list(&own),
            Echo(team.speeds(own[0]).max_mps)
        ));
    }
    if !team_wide.is_empty() {
        let whom = if own.is_empty() {
            String::new()
        } else {
            format!(
                " for vehicle{} {}",
                if team_wide.len() > 1 { "s" } else { "" },
                list(&team_wide)
            )
        };
        parts.push(format!(
            "team.v_min_mps = team.v_max_mps = {} m/s{whom}",
            Echo(team.v_min_mps)
        ));
    }
    parts.join("; ")
}

/// att44-8: two or more vehicles of `team` with no speed room fly their one speed whatever the
/// law commands, so the arc from each to the next of them along the ring never changes; the
/// vehicles between two of them can at best share that arc evenly (with one nominal speed the
/// law's equilibrium is equal ranges, on a circle equal gaps). The gap CV of that best case
/// decides: above the even 0.05 the team cannot even out (`fails`, naming the keys in force).
/// `None` with fewer than two such vehicles, unequal nominal speeds, every vehicle pinned (the
/// caller's rule), or when the deployment on a known circle is not known (a start off it, no
/// PI-like law to tell the direction of travel).
pub(super) fn pinned_arcs_claim(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
) -> Option<(crate::check::Verdict, String)> {
    let n = team.count();
    let ids = pinned(team);
    if ids.len() < 2 || ids.len() == n || team.nominal_speeds_mps().len() != 1 {
        return None;
    }
    if !matches!(team.ring, RingMode::Listed) {
        return None;
    }
    let circle = s.team_arc()?;
    let dir = travel_direction(s, l)?;
    let angle = |i: usize| start_angle(team, circle, i);
    let mut gaps = Vec::with_capacity(n);
    for (k, &a) in ids.iter().enumerate() {
        let b = ids[(k + 1) % ids.len()];
        let count = (b + n - a) % n;
        let arc = (dir * (angle(b)? - angle(a)?)).rem_euclid(TAU);
        gaps.extend(std::iter::repeat_n(arc / count as f64, count));
    }
    let mean = TAU / n as f64;
    let cv = (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n as f64).sqrt() / mean;
    let even = TeamMetricsConfig::default().even_gap_cv;
    (cv > even).then(|| {
        (
            crate::check::Verdict::Fails,
            format!(
                "vehicles {} have no speed room ({}): each flies its one speed whatever {} commands, so the arc from each to the next of them along the ring stays as deployed, and the vehicles between can at best share it evenly: a gap CV of {} > {} at best (even spacing is not reached)",
                ids.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(", "),
                pinned_keys(team, &ids),
                team.law.name(),
                Num(cv),
                Num(even)
            ),
        )
    })
}

/// [`ShiftedEquilibrium`] of `team` flying `range_balance` (gain `k_v > 0`) with unequal
/// nominal speeds on a known circle of flown radius `flown_m`; `None` for another team, for
/// two or more vehicles with no speed room ([`pinned_arcs_claim`]'s) or where the clamp to the
/// envelopes is set by two vehicles at once (the equilibrium is then a family).
pub(super) fn shifted_equilibrium(team: &TeamSpec, flown_m: f64) -> Option<ShiftedEquilibrium> {
    let SpacingLaw::RangeBalance { gain_per_s: k_v } = team.law else {
        return None;
    };
    let n = team.count();
    let ids = pinned(team);
    if k_v <= 0.0 || n < 3 || team.nominal_speeds_mps().len() < 2 || ids.len() > 1 {
        return None;
    }
    if !(flown_m.is_finite() && flown_m > 0.0) || disjoint_envelopes(team).is_some() {
        return None;
    }
    let mean = team.ideal_speed_mps();
    // The vehicle that takes up the rest: the one pinned, or the one whose bound sets V.
    let (speed, absorber) = match (ids.first(), common_speed(team, mean)) {
        (Some(&p), _) => (team.speeds(p).max_mps, p),
        (None, Some((v, i, _))) => {
            let ties = (0..n)
                .filter(|&j| {
                    let e = team.speeds(j);
                    e.min_mps == v || e.max_mps == v
                })
                .count();
            if ties > 1 {
                return None;
            }
            (v, i)
        }
        (None, None) => (mean, 0),
    };
    let d = |i: usize| (speed - team.speeds(i).nominal_mps) / k_v;
    // Partial sums along the ring from the absorber: the range ahead of vehicle a + k is
    // x + p[k].
    let mut p = vec![0.0; n];
    for k in 1..n {
        p[k] = p[k - 1] + d((absorber + k) % n);
    }
    let lo_p = p.iter().copied().fold(f64::INFINITY, f64::min);
    let hi_p = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let diameter = 2.0 * flown_m;
    let largest = diameter.min(team.ranging.max_range_m);
    let mut eq = ShiftedEquilibrium {
        speed_mps: speed,
        range_span_m: hi_p - lo_p,
        largest_range_m: largest,
        status: "none",
        ranges_m: vec![],
    };
    if hi_p - lo_p >= largest {
        return Some(eq);
    }
    let arcs = |x: f64| {
        p.iter()
            .map(|pk| 2.0 * ((x + pk) / diameter).clamp(0.0, 1.0).asin())
            .sum::<f64>()
    };
    let (mut lo, mut hi) = (-lo_p, diameter - hi_p);
    if arcs(lo) >= TAU {
        return Some(eq);
    }
    if arcs(hi) < TAU {
        eq.status = "past_half_circle";
        return Some(eq);
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if arcs(mid) < TAU {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let x = 0.5 * (lo + hi);
    let mut ranges = vec![0.0; n];
    for (k, pk) in p.iter().enumerate() {
        ranges[(absorber + k) % n] = x + pk;
    }
    eq.status = "exists";
    eq.ranges_m = ranges;
    Some(eq)
}

/// The verdict [`ShiftedEquilibrium`] gives: `fails` when none exists (att44-6: the slower
/// vehicles fall behind for ever and are lapped), `not_applicable` when a gap would pass half
/// the circle or the ranges it needs reach past `team.ranging.max_range_m` (att44-7: there the
/// law sees `max_range_m`, and the equilibrium the loop converges to does not form); `None`
/// when it exists within the range.
pub(super) fn shifted_claim(
    team: &TeamSpec,
    eq: &ShiftedEquilibrium,
) -> Option<(crate::check::Verdict, String)> {
    let SpacingLaw::RangeBalance { gain_per_s: k_v } = team.law else {
        return None;
    };
    let m = team.ranging.max_range_m;
    let intro = format!(
        "unequal nominal speeds (team.vehicles): the gaps stand still only where every vehicle flies one speed V = {} m/s, so vehicle i's range ahead must exceed its range behind by (V - v0_i)/k_v (team.k_v = {})",
        Num(eq.speed_mps),
        Echo(k_v)
    );
    let limit = if m < eq.largest_range_m * (1.0 + 1e-12) {
        format!("team.ranging.max_range_m = {}", Echo(m))
    } else {
        format!("the circle's diameter {} m", Num(eq.largest_range_m))
    };
    match eq.status {
        "none" => {
            // The vehicle furthest from V, and the speed its widest range difference gives.
            let (i, gap) = (0..team.count())
                .map(|i| (i, eq.speed_mps - team.speeds(i).nominal_mps))
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                .unwrap_or((0, 0.0));
            let v0 = team.speeds(i).nominal_mps;
            let best = v0 + gap.signum() * k_v * eq.largest_range_m;
            Some((
                crate::check::Verdict::Fails,
                format!(
                    "{intro}; round the ring these differences need ranges {} m apart, {}, so no equilibrium exists: the gaps never stand still, the slower vehicles fall behind for ever and are lapped (robots pass through each other); raise team.k_v or bring the speeds closer",
                    Num(eq.range_span_m),
                    if eq.range_span_m >= eq.largest_range_m {
                        format!(
                            "and no range exceeds {limit} (vehicle {i} at v0 = {} m/s reaches at most {} m/s against V)",
                            Echo(v0),
                            Num(best)
                        )
                    } else {
                        "and even with two vehicles touching their arcs overfill the circle".into()
                    }
                ),
            ))
        }
        "past_half_circle" => Some((
            crate::check::Verdict::NotApplicable,
            format!(
                "{intro}; the ranges this needs put one gap past half the circle, where the range shrinks as the gap grows, so the linear loop does not describe the equilibrium; run it to see whether the team settles"
            ),
        )),
        _ => {
            let widest = eq.ranges_m.iter().copied().fold(0.0, f64::max);
            (widest > m).then(|| {
                (
                    crate::check::Verdict::NotApplicable,
                    format!(
                        "{intro}; on this circle that is the ranges ({}) m (chords whose arcs sum to the circle), and team.ranging.max_range_m = {} is short of the longest, {} m: where a neighbour falls silent range_balance sees max_range_m instead, so the equilibrium the linear loop converges to does not form; run it to see where the team settles",
                        eq.ranges_m.iter().map(|r| Num(*r).to_string()).collect::<Vec<_>>().join(", "),
                        Echo(m),
                        Num(widest)
                    ),
                )
            })
        }
    }
}

/// att44-10: the discovery probe of `team` (`team.ring = "discovered"`) commands
/// `v0 + probe_speed_delta_mps` (`DISCOVERY_PROBE_FRACTION v0`), saturated to the envelope:
/// with `team.v_max_mps <= v0` it changes no speed, the range rates that sort the vehicles
/// ahead from those behind are zero, and the probes cannot find the ring (the run's law is off).
/// The `fails` reason, `None` when the probe changes the speed.
pub(super) fn probe_cannot_fly(team: &TeamSpec) -> Option<String> {
    let RingMode::Discover(d) = team.ring else {
        return None;
    };
    let v0 = team.nominal_speed_mps;
    let probe = v0 + d.probe_speed_delta_mps;
    (team.v_max_mps <= v0 && d.probe_speed_delta_mps > 0.0).then(|| {
        format!(
            "team.ring = \"discovered\" with team.v_max_mps = {} m/s: each vehicle's probe commands v0 + v0/4 = {} m/s, saturated to v_max = v0, so it changes no speed and the range rates that tell the vehicles ahead from those behind are zero: the probes cannot find the ring, and without it the spacing law is off for the whole run (the run warns it); raise team.v_max_mps above v0 (to {} m/s for the whole probe) or list the ring",
            Echo(team.v_max_mps),
            Num(probe),
            Num(probe)
        )
    })
}

/// The probe's speed change when the envelope cuts it (`v0 < team.v_max_mps < v0 + dv`): the
/// not-modelled note's words, `None` when the whole probe is flown.
pub(super) fn probe_cut_note(team: &TeamSpec) -> Option<String> {
    let RingMode::Discover(d) = team.ring else {
        return None;
    };
    let v0 = team.nominal_speed_mps;
    let probe = v0 + d.probe_speed_delta_mps;
    (team.v_max_mps > v0 && team.v_max_mps < probe).then(|| {
        format!(
            "the probe's command v0 + v0/4 = {} m/s is saturated to team.v_max_mps = {} m/s, a speed change of {} m/s instead of {} (range rates that much smaller against the noise)",
            Num(probe),
            Echo(team.v_max_mps),
            Num(team.v_max_mps - v0),
            Num(d.probe_speed_delta_mps)
        )
    })
}
