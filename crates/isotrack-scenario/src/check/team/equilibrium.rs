//! Where the gaps can stand still at all (issue 32, att44-6, -7, -8): the equilibrium of
//! `range_balance` with unequal nominal speeds solved on a known circle (docs/TEAMS.md, "Per-vehicle
//! overrides"), and the arcs that vehicles with no speed room (`v_min_i = v_max_i`) keep.

use crate::check::team_ring::{common_speed, disjoint_envelopes, start_angle, travel_direction};
use crate::check::Verdict;
use crate::spec::TeamSpec;
use crate::team::TeamIsolineModel;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_sim::team::arc::{ArcProjection, CircleArc};
use isotrack_sim::team::metrics::{TeamMetricsConfig, CLOSE_APPROACH_M};
use isotrack_sim::team::spacing::{RingMode, SpacingLaw};
use serde::Serialize;
use std::f64::consts::TAU;

use crate::check::setup::Law;

/// `range_balance`'s (or `arc_reference`'s, att50-2: its arc gaps for the ranges) equilibrium
/// with unequal nominal speeds on a known circle: every vehicle flies one speed `V`, so vehicle
/// `i`'s range ahead exceeds its range behind by
/// `d_i = (V - v0_i)/k_v` (the vehicle whose envelope bound sets `V` takes up the rest, each of
/// them the rest of its run to the next when two or more set it, att50-9; with
/// vehicles of no speed room, `V` is their speed and each takes up the rest of its run to the
/// next of them, att46-7), the ranges are chords `2 R' sin(theta/2)` of the circle flown
/// (radius `R'`) and the arcs sum to a turn (each run's to the arc its two ends keep). Solved
/// by bisection on the ranges' common offset.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ShiftedEquilibrium {
    /// The common speed `V`, m/s.
    pub speed_mps: f64,
    /// The spread of the ranges the differences `d_i` need round the ring (largest partial sum
    /// less the smallest), m.
    pub range_span_m: f64,
    /// The longest range a law can see: the circle's diameter `2 R'`, or
    /// `team.ranging.max_range_m` when shorter (`arc_reference`: the isoline's length), m.
    pub largest_range_m: f64,
    /// `exists` (the ranges below), `none` (the span reaches `largest_range_m`, or the arcs
    /// overfill the circle even with two vehicles touching) or `past_half_circle` (a gap would
    /// exceed half the circle, where the range shrinks as the gap grows: not the linear loop).
    pub status: &'static str,
    /// Each vehicle's range ahead at the equilibrium (listed order; `arc_reference`: its arc
    /// gap ahead), m (empty unless `exists`).
    pub ranges_m: Vec<f64>,
    /// The gap CV of the equilibrium's arcs (absent unless `exists`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gap_cv: Option<f64>,
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

/// att50-1: the vehicles of `team` saturated at an envelope bound at the equilibrium `eq`
/// (listed order): vehicle `i`'s command there, `v0_i + k_v (r_i - r_{i-1})`, strictly outside
/// `[v_min_i, v_max_i]` (the one whose bound sets `V`, taking up the rest). A small perturbation
/// leaves it saturated at `V`, so the linearisation pins it as a vehicle of no speed room.
/// Empty when `eq` does not exist or another law.
pub(super) fn saturated(team: &TeamSpec, eq: &ShiftedEquilibrium) -> Vec<usize> {
    let k_v = match team.law {
        SpacingLaw::RangeBalance { gain_per_s } | SpacingLaw::ArcReference { gain_per_s } => {
            gain_per_s
        }
        SpacingLaw::None => return vec![],
    };
    let n = eq.ranges_m.len();
    if !eq.exists() || n != team.count() {
        return vec![];
    }
    // att53t-5: an anchor settled ON its bound (its command the bound, to rounding) is not
    // saturated: it can move one way.
    let tol = ON_BOUND_REL_TOL * eq.speed_mps.abs().max(1.0);
    (0..n)
        .filter(|&i| {
            let e = team.speeds(i);
            let cmd = e.nominal_mps + k_v * (eq.ranges_m[i] - eq.ranges_m[(i + n - 1) % n]);
            e.min_mps < e.max_mps && (cmd > e.max_mps + tol || cmd < e.min_mps - tol)
        })
        .collect()
}

/// att53t-10: a vehicle counts as near one envelope bound (one-sided) only when its room to it
/// is at most this fraction of its room to the other: with rooms alike both sides cut the
/// corrections alike, and a strict `room < other` was a knife edge (a nominal speed 1e-7 m/s
/// off the others' tipped a centred team, [0.25, 0.75] about 0.5, to "near v_max", which hid
/// its time constants and, through the start rule's horizon, turned its verdict).
pub const NEAR_BOUND_ROOM_RATIO: f64 = 0.5;

/// Relative tolerance within which a speed counts as ON an envelope bound (att51-7).
pub const ON_BOUND_REL_TOL: f64 = 1e-9;

/// att51-7: the vehicles of `team` free in the linearisation (`pins[i]` false, with speed room)
/// whose equilibrium command, the common speed `speed`, sits on one of its envelope bounds
/// ([`bound_side`]): e.g. `team.v_max_mps = v0`. Such a vehicle can move only one way (a
/// correction that asks it past the bound is cut), so half of the linear law acts on it and the
/// linear time constants do not describe the decay. Listed order.
pub(super) fn on_bound(team: &TeamSpec, speed: f64, pins: &[bool], reach_mps: f64) -> Vec<usize> {
    (0..team.count())
        .filter(|&i| !pins.get(i).copied().unwrap_or(false))
        .filter(|&i| bound_side(team, speed, i, reach_mps).is_some())
        .collect()
}

/// Which envelope bound vehicle `i`'s command at `speed` sits on: `Some(true)` its `v_max`,
/// `Some(false)` its `v_min`, `None` neither (or no speed room). With `reach_mps = 0`, ON it
/// within the rounding of [`ON_BOUND_REL_TOL`]; with `reach_mps > 0` (att53t-10: the largest
/// correction the deployment asks), near it: the room to that bound under `reach_mps` and at
/// most [`NEAR_BOUND_ROOM_RATIO`] of the room to the other bound, so the near side cuts the
/// corrections for longer than the far side saturates them (with rooms alike both cut alike: no
/// one-sided law).
fn bound_side(team: &TeamSpec, speed: f64, i: usize, reach_mps: f64) -> Option<bool> {
    let e = team.speeds(i);
    if e.min_mps >= e.max_mps {
        return None;
    }
    let tol = (ON_BOUND_REL_TOL * speed.abs().max(1.0)).max(reach_mps);
    let (top, bottom) = ((e.max_mps - speed).abs(), (speed - e.min_mps).abs());
    let one_way = |room: f64, other: f64| {
        room <= tol && (reach_mps == 0.0 || room <= NEAR_BOUND_ROOM_RATIO * other)
    };
    if one_way(top, bottom) {
        Some(true)
    } else if one_way(bottom, top) {
        Some(false)
    } else {
        None
    }
}

/// Whether the vehicles `ids` (from [`on_bound`] with the same `reach_mps`) all sit on the same
/// side: each at its `v_max` (only slowing acts), or each at its `v_min` (only speeding up).
pub(super) fn on_one_bound(team: &TeamSpec, speed: f64, ids: &[usize], reach_mps: f64) -> bool {
    let side = |want: bool| {
        ids.iter()
            .all(|&i| bound_side(team, speed, i, reach_mps) == Some(want))
    };
    side(true) || side(false)
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
    let ids = pinned(team);
    let gaps = pinned_best_arcs(s, l, team)?;
    let n = gaps.len();
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

/// [`pinned_arcs_claim`]'s best case: each vehicle's arc ahead (listed order, rad) when the
/// vehicles between two with no speed room share the arc the two keep evenly; `None` in the
/// cases that claim leaves out.
pub(super) fn pinned_best_arcs(s: &Scenario, l: &Law, team: &TeamSpec) -> Option<Vec<f64>> {
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
    let mut gaps = vec![0.0; n];
    for (k, &a) in ids.iter().enumerate() {
        let b = ids[(k + 1) % ids.len()];
        let count = (b + n - a) % n;
        let arc = (dir * (angle(b)? - angle(a)?)).rem_euclid(TAU);
        (0..count).for_each(|j| gaps[(a + j) % n] = arc / count as f64);
    }
    Some(gaps)
}

/// How a law's measured gap maps to arc round the circle: `range_balance` ranges chords
/// `2 R' sin(theta/2)` of the circle flown, `arc_reference` the arc gaps themselves on the
/// isoline's circle (slope 1, att50-2). The one difference between the two laws' equilibria.
#[derive(Clone, Copy, Debug)]
enum GapMap {
    /// Chords of a circle of this diameter, m.
    Chord(f64),
    /// Arcs of a circle of this radius, m.
    Arc(f64),
}

impl GapMap {
    /// The angle (rad) a measured gap `g` spans, `g` clamped to `[0, upper]`.
    fn angle(self, g: f64) -> f64 {
        match self {
            GapMap::Chord(d) => 2.0 * (g / d).clamp(0.0, 1.0).asin(),
            GapMap::Arc(r) => g.clamp(0.0, TAU * r) / r,
        }
    }

    /// The largest gap the map holds: the diameter, or the whole circle's length, m.
    fn upper(self) -> f64 {
        match self {
            GapMap::Chord(d) => d,
            GapMap::Arc(r) => TAU * r,
        }
    }
}

/// [`ShiftedEquilibrium`] of `team` flying `range_balance` or `arc_reference` (gain `k_v > 0`)
/// with unequal nominal speeds on `circle`, flown at radius `flown_m(V)` at the common speed `V`
/// (att50-12); `None` for another team, or with two or more anchors (vehicles with no speed room,
/// or saturated at the bound that sets `V`, att50-9) whose arcs are not known (a start off the
/// circle, no PI-like law to tell the direction of travel).
///
/// Vehicles with no speed room (`v_min_i = v_max_i`, att46-7) fly their one speed, which is
/// then the common speed `V`; each takes up the rest of its own run of the ring, so from each
/// to the next of them the gaps of the vehicles between follow the differences and their
/// arcs sum to the arc the two keep (a whole turn with one of them). `arc_reference` (att50-2)
/// is the same with its arc gaps on the isoline for the ranges ([`GapMap`]): linear, so the
/// common offset is `(L - sum p_k)/N` (the bisection finds it).
pub(super) fn shifted_equilibrium(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    circle: CircleArc,
    flown_m: impl Fn(f64) -> f64,
) -> Option<ShiftedEquilibrium> {
    let n = team.count();
    let ids = pinned(team);
    if n < 3 || team.nominal_speeds_mps().len() < 2 || ids.len() == n {
        return None;
    }
    let speed = equilibrium_speed(team);
    // att50-12: every vehicle flies V at the equilibrium, so the circle flown is V's (the P
    // law's orbit moves with the speed).
    let (k_v, map) = match team.law {
        SpacingLaw::RangeBalance { gain_per_s } => {
            (gain_per_s, GapMap::Chord(2.0 * flown_m(speed)))
        }
        SpacingLaw::ArcReference { gain_per_s } => (gain_per_s, GapMap::Arc(circle.radius_m)),
        SpacingLaw::None => return None,
    };
    if k_v <= 0.0 || !(map.upper().is_finite() && map.upper() > 0.0) {
        return None;
    }
    if disjoint_envelopes(team).is_some() {
        return None;
    }
    let runs = equilibrium_runs(s, l, team, circle, speed, &ids)?;
    let d = |i: usize| (speed - team.speeds(i).nominal_mps) / k_v;
    let largest = match map {
        GapMap::Chord(diameter) => diameter.min(team.ranging.max_range_m),
        GapMap::Arc(_) => map.upper(),
    };
    let mut eq = ShiftedEquilibrium {
        speed_mps: speed,
        range_span_m: 0.0,
        largest_range_m: largest,
        status: "exists",
        ranges_m: vec![0.0; n],
        gap_cv: None,
    };
    let sums = run_partial_sums(&runs, n, d);
    let mut arcs: Vec<f64> = runs.iter().map(|r| r.2).collect();
    if ids.is_empty() && runs.len() >= 2 {
        // att53t-5: saturated anchors keep their arcs only while each stays saturated.
        let anchors: Vec<Anchor> = runs
            .iter()
            .map(|&(a, _, _)| Anchor {
                d: d(a),
                side: if team.speeds(a).max_mps == speed {
                    1.0
                } else {
                    -1.0
                },
            })
            .collect();
        settle_anchor_arcs(&mut arcs, &sums, &anchors, map, largest);
    }
    for ((&(a, count, _), p), &arc) in runs.iter().zip(&sums).zip(&arcs) {
        let lo_p = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi_p = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        eq.range_span_m = eq.range_span_m.max(hi_p - lo_p);
        match solve_run(p, map, eq.largest_range_m, arc) {
            Ok(x) => (0..count).for_each(|k| eq.ranges_m[(a + k) % n] = x + p[k]),
            Err(why) => eq.status = worse(eq.status, why),
        }
    }
    if !eq.exists() {
        eq.ranges_m.clear();
        return Some(eq);
    }
    eq.gap_cv = Some(angle_cv(&eq.ranges_m, map));
    Some(eq)
}

/// Partial sums along each run `(a, count, arc)` of the ring from its first vehicle `a`:
/// `p[0] = 0`, `p[k] = p[k - 1] + d(a + k)`, so the gap ahead of `a + k` is `x + p[k]` for the
/// run's offset `x`.
fn run_partial_sums(
    runs: &[(usize, usize, f64)],
    n: usize,
    d: impl Fn(usize) -> f64,
) -> Vec<Vec<f64>> {
    runs.iter()
        .map(|&(a, count, _)| {
            let mut p = vec![0.0; count];
            for k in 1..count {
                p[k] = p[k - 1] + d((a + k) % n);
            }
            p
        })
        .collect()
}

/// The coefficient of variation of the gaps' angles `map.angle(r_i)` about the even `2 pi / N`
/// (the population standard deviation over the mean).
fn angle_cv(ranges_m: &[f64], map: GapMap) -> f64 {
    let n = ranges_m.len() as f64;
    let mean = TAU / n;
    let var = ranges_m
        .iter()
        .map(|r| (map.angle(*r) - mean).powi(2))
        .sum::<f64>()
        / n;
    var.sqrt() / mean
}

/// The common speed `V` of the equilibrium of `team` (docs/TEAMS.md, "Per-vehicle
/// overrides"): the one speed of its vehicles with no speed room, else the mean nominal speed
/// clamped to every envelope ([`common_speed`]), else that mean.
pub(super) fn equilibrium_speed(team: &TeamSpec) -> f64 {
    match (
        pinned(team).first(),
        common_speed(team, team.ideal_speed_mps()),
    ) {
        (Some(&p), _) => team.speeds(p).max_mps,
        (None, Some((v, _, _))) => v,
        (None, None) => team.ideal_speed_mps(),
    }
}

/// The vehicles of `team` (with speed room) whose envelope bound is the common speed `speed`
/// when that clamp sets it (att50-9: two or more saturate there at once); empty when the mean
/// nominal speed is within every envelope.
pub(super) fn bound_setters(team: &TeamSpec, speed: f64) -> Vec<usize> {
    if common_speed(team, team.ideal_speed_mps()).is_none() {
        return vec![];
    }
    (0..team.count())
        .filter(|&j| {
            let e = team.speeds(j);
            e.min_mps < e.max_mps && (e.min_mps == speed || e.max_mps == speed)
        })
        .collect()
}

/// The runs of the ring each taken up by one vehicle (the first of the run): `(first, count of
/// gaps, arc they fill, rad)`. The anchors are the vehicles pinned (no speed room), else those
/// whose envelope bound sets `speed` ([`bound_setters`]; vehicle 0 when none does). With one
/// anchor, the whole turn from it; with more (att50-9: two saturated at one bound act as pins
/// too), from each to the next of them, filling the arc between their starts (`None` when not
/// known): for saturated anchors the transient moves those arcs before they saturate, so the
/// deployed arcs are the model's, kept while each anchor stays saturated there (else moved
/// until it is ON its bound, [`settle_anchor_arcs`], att53t-5).
fn equilibrium_runs(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    circle: CircleArc,
    speed: f64,
    ids: &[usize],
) -> Option<Vec<(usize, usize, f64)>> {
    let n = team.count();
    let setters = bound_setters(team, speed);
    let anchors = if ids.is_empty() { &setters } else { ids };
    match anchors {
        [] => Some(vec![(0, n, TAU)]),
        [one] => Some(vec![(*one, n, TAU)]),
        ids => {
            let dir = travel_direction(s, l)?;
            let angle = |i: usize| start_angle(team, circle, i);
            let mut runs = Vec::with_capacity(ids.len());
            for (k, &a) in ids.iter().enumerate() {
                let b = ids[(k + 1) % ids.len()];
                let arc = (dir * (angle(b)? - angle(a)?)).rem_euclid(TAU);
                runs.push((a, (b + n - a) % n, arc));
            }
            Some(runs)
        }
    }
}

/// A vehicle saturated at the bound that sets the common speed, first of its run
/// ([`settle_anchor_arcs`]).
#[derive(Clone, Copy, Debug)]
struct Anchor {
    /// `(V - v0_i)/k_v`: the range difference at which its command is exactly `V`, m.
    d: f64,
    /// `1` when `V` is its `v_max` (saturated while `r_i - r_{i-1} >= d`), `-1` at `v_min`.
    side: f64,
}

/// att53t-5: the arcs of runs led by vehicles saturated at the bound that sets `V` (two or more
/// at one bound, att50-9). An anchor flies `V` only while its command is past its bound
/// (`side (r_i - r_{i-1} - d) >= 0`, its range behind the last of the previous run); a deployed
/// arc that leaves it short is not an equilibrium: the anchor is free, moves, and stops ON its
/// bound. So each anchor whose command falls short is moved along the ring (its arc behind
/// traded against its arc ahead, by bisection) until its command is exactly the bound, sweep
/// after sweep, until none falls short; arcs that keep every anchor saturated stay as deployed.
/// The excesses sum to `-sum_i d_i`, which the clamp that sets `V` makes of the anchors' sign, so
/// a settled arrangement exists.
fn settle_anchor_arcs(
    arcs: &mut [f64],
    sums: &[Vec<f64>],
    anchors: &[Anchor],
    map: GapMap,
    largest: f64,
) {
    let m = arcs.len();
    // A run's common offset at `arc`, +-infinity where it cannot fit (too short or too long).
    let offset = |k: usize, arc: f64| match solve_run(&sums[k], map, largest, arc) {
        Ok(x) => x,
        Err("past_half_circle") => f64::INFINITY,
        Err(_) => f64::NEG_INFINITY,
    };
    let tol = 1e-9 * largest.max(1.0);
    for _ in 0..64 * m {
        let mut moved = false;
        for k in 0..m {
            let before = (k + m - 1) % m;
            let last = sums[before].last().copied().unwrap_or(0.0);
            // The anchor's range difference less d, its arc behind grown by `delta`
            // (decreasing in `delta`).
            let f = |delta: f64| {
                offset(k, arcs[k] - delta)
                    - offset(before, arcs[before] + delta)
                    - last
                    - anchors[k].d
            };
            if anchors[k].side * f(0.0) >= -tol {
                continue;
            }
            let (mut lo, mut hi) = (-arcs[before], arcs[k]);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if f(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let delta = 0.5 * (lo + hi);
            arcs[before] += delta;
            arcs[k] -= delta;
            moved = true;
        }
        if !moved {
            break;
        }
    }
}

/// att46-14, -15: the rules a known circle decides, on a closed isoline the check extracts
/// instead (`Scenario::team_isoline`): unequal nominal speeds whose range differences span at
/// least the loop's longest chord (its largest vertex-to-vertex distance) have no equilibrium,
/// `fails` as on a circle; short of it the equilibrium is not solved off a circle, and two or
/// more vehicles with no speed room keep arcs the check does not measure there: both
/// `not_applicable` (never `holds`). `None` on a circle, another isoline, or with neither.
pub(super) fn extracted_claim(s: &Scenario, team: &TeamSpec) -> Option<(Verdict, String)> {
    let TeamIsolineModel::Polyline(p) = s.team_isoline() else {
        return None;
    };
    if !p.is_closed() {
        return None;
    }
    let ids = pinned(team);
    let unequal = team.nominal_speeds_mps().len() > 1;
    if let (true, SpacingLaw::RangeBalance { gain_per_s: k_v }) = (unequal, team.law) {
        // The vehicle that takes up the rest, as on a circle: the pinned one, the one whose
        // bound sets V, else any (the differences then sum to zero).
        let (speed, first) = match (ids.first(), common_speed(team, team.ideal_speed_mps())) {
            (Some(&i), _) => (team.speeds(i).max_mps, i),
            (None, Some((v, i, _))) => (v, i),
            (None, None) => (team.ideal_speed_mps(), 0),
        };
        let n = team.count();
        let mut sums = vec![0.0; n];
        for k in 1..n {
            let i = (first + k) % n;
            sums[k] = sums[k - 1] + (speed - team.speeds(i).nominal_mps) / k_v;
        }
        let span = sums.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - sums.iter().copied().fold(f64::INFINITY, f64::min);
        let v = p.vertices();
        let longest = v
            .iter()
            .enumerate()
            .flat_map(|(i, a)| v[i + 1..].iter().map(move |b| (*b - *a).norm()))
            .fold(0.0, f64::max)
            .min(team.ranging.max_range_m);
        let intro = format!(
            "unequal nominal speeds (team.vehicles) on an extracted closed isoline: the gaps stand still only where every vehicle flies one speed V = {} m/s, so vehicle i's range ahead must exceed its range behind by (V - v0_i)/k_v (team.k_v = {}); round the ring these differences need ranges {} m apart",
            Num(speed),
            Echo(k_v),
            Num(span)
        );
        return Some(if span >= longest && ids.len() < 2 {
            (Verdict::Fails, format!("{intro}, and no range on this loop exceeds {} m (its longest chord, or team.ranging.max_range_m when shorter), so no equilibrium exists: the slower vehicles fall behind for ever and are lapped (robots pass through each other); raise team.k_v or bring the speeds closer", Num(longest)))
        } else {
            (Verdict::NotApplicable, format!("{intro}, within its longest chord {} m, but the equilibrium is solved on a known circle only (its chords' arcs), so whether it forms, and how even it is, is not the check's to tell here; run it to see where the team settles", Num(longest)))
        });
    }
    (ids.len() >= 2 && ids.len() < team.count()).then(|| {
        (
            Verdict::NotApplicable,
            format!(
                "vehicles {} have no speed room ({}): each flies its one speed, so the arc from each to the next of them stays as deployed, and on an extracted closed isoline the check does not measure those arcs (a known circle's rule): whether the vehicles between can even out is not the check's to tell here; run it",
                ids.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(", "),
                pinned_keys(team, &ids)
            ),
        )
    })
}

/// The common offset `x` of a run's gaps `x + p[k]` (measured as `map` says) whose arcs sum to
/// `arc`, by bisection; `Err("none")` when the gaps cannot fit (their span reaches `largest`,
/// or even at their shortest their arcs overfill `arc`), `Err("past_half_circle")` when filling
/// it takes a chord past half the circle (never for arc gaps).
fn solve_run(p: &[f64], map: GapMap, largest: f64, arc: f64) -> Result<f64, &'static str> {
    let lo_p = p.iter().copied().fold(f64::INFINITY, f64::min);
    let hi_p = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi_p - lo_p >= largest {
        return Err("none");
    }
    let arcs = |x: f64| p.iter().map(|pk| map.angle(x + pk)).sum::<f64>();
    let (mut lo, mut hi) = (-lo_p, map.upper() - hi_p);
    if arcs(lo) >= arc {
        return Err("none");
    }
    if arcs(hi) < arc {
        return Err("past_half_circle");
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if arcs(mid) < arc {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// Of two statuses, the one that decides: `none` over `past_half_circle` over `exists`.
fn worse(a: &'static str, b: &'static str) -> &'static str {
    if a == "none" || b == "none" {
        "none"
    } else if a == "past_half_circle" || b == "past_half_circle" {
        "past_half_circle"
    } else {
        "exists"
    }
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
    let (k_v, word) = match team.law {
        SpacingLaw::RangeBalance { gain_per_s } => (gain_per_s, "range"),
        SpacingLaw::ArcReference { gain_per_s } => (gain_per_s, "arc gap"),
        SpacingLaw::None => return None,
    };
    let m = team.ranging.max_range_m;
    let intro = format!(
        "unequal nominal speeds (team.vehicles): the gaps stand still only where every vehicle flies one speed V = {} m/s, so vehicle i's {word} ahead must exceed its {word} behind by (V - v0_i)/k_v (team.k_v = {})",
        Num(eq.speed_mps),
        Echo(k_v)
    );
    let limit = if word == "arc gap" {
        format!("the isoline's length {} m", Num(eq.largest_range_m))
    } else if m < eq.largest_range_m * (1.0 + 1e-12) {
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
                    "{intro}; round the ring these differences need {word}s {} m apart, {}, so no equilibrium exists: the gaps never stand still, the slower vehicles fall behind for ever and are lapped (robots pass through each other); raise team.k_v or bring the speeds closer",
                    Num(eq.range_span_m),
                    if eq.range_span_m >= eq.largest_range_m {
                        format!(
                            "and no {word} exceeds {limit} (vehicle {i} at v0 = {} m/s reaches at most {} m/s against V)",
                            Echo(v0),
                            Num(best)
                        )
                    } else {
                        "and even with two vehicles touching their arcs overfill the circle (one vehicle would have to pass another)".into()
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
        _ => exists_claim(team, eq, &intro, word),
    }
}

/// [`shifted_claim`] of an equilibrium that exists: `not_applicable` when a range passes
/// `team.ranging.max_range_m` (the equilibrium does not form), `fails` when a range is under
/// the run's close-approach distance (att46-5: the law drives two vehicles together and holds
/// them there, a collision); `None` otherwise: its evenness is not judged (att50-10: `holds`
/// claims convergence to it, with any number of vehicles of no speed room).
fn exists_claim(
    team: &TeamSpec,
    eq: &ShiftedEquilibrium,
    intro: &str,
    word: &str,
) -> Option<(crate::check::Verdict, String)> {
    let m = team.ranging.max_range_m;
    let list = || {
        eq.ranges_m
            .iter()
            .map(|r| Num(*r).to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let widest = eq.ranges_m.iter().copied().fold(0.0, f64::max);
    if widest > m && word == "range" {
        return Some((
            crate::check::Verdict::NotApplicable,
            format!(
                "{intro}; on this circle that is the ranges ({}) m (chords whose arcs sum to the circle), and team.ranging.max_range_m = {} is short of the longest, {} m: where a neighbour falls silent range_balance sees max_range_m instead, so the equilibrium the linear loop converges to does not form; run it to see where the team settles",
                list(),
                Echo(m),
                Num(widest)
            ),
        ));
    }
    let n = eq.ranges_m.len();
    let (i, closest) = eq
        .ranges_m
        .iter()
        .copied()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    if closest < CLOSE_APPROACH_M {
        return Some((
            crate::check::Verdict::Fails,
            format!(
                "{intro}; on this circle that is the {word}s ({}) m, and vehicle {i}'s {word} to vehicle {} ahead, {} m, is under the run's close-approach distance {} m: the law drives them together and holds them there (a collision), and the gaps never even out; raise team.k_v or bring the speeds closer",
                list(),
                (i + 1) % n,
                Num(closest),
                Num(CLOSE_APPROACH_M)
            ),
        ));
    }
    // att50-10, att53t (item 8): with unequal nominal speeds `holds` claims convergence to this
    // equilibrium (its gap CV on the page), not evenness, whatever the vehicles of no speed
    // room: one rule for any number of them.
    None
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

/// The probability the discovery's picks must all be right for `check` to say `holds`
/// (att50-3): `Phi(m)^(2 N) >= 0.99` for the probe's change `m` fitted deviations above zero.
pub const PROBE_PICKS_RIGHT: f64 = 0.99;

/// The standard normal's upper tail `Phi(-m) = erfc(m/sqrt 2)/2` (`libm::erfc`: accurate in the
/// far tail, where `1 - Phi(m)` by subtraction would lose it).
fn normal_upper_tail(m: f64) -> f64 {
    0.5 * libm::erfc(m / std::f64::consts::SQRT_2)
}

/// att46-6, att50-3: the discovery probe of `team` whose range change is lost in the ranging
/// noise. In its slot of `S = probe_s` the prober fits each neighbour's range rate by least
/// squares to the ranges it gets, `n = S rate_hz (1 - p)` of them (`p =
/// team.ranging.dropout_probability`: a dropped range is no sample); the probe moves a
/// neighbour's range by `dv S cos(theta/2)` (`dv = min(v_max, v0 + probe_speed_delta_mps) -
/// v0`, the speed change the envelope leaves; `theta` the arc to the neighbour about the
/// circle's centre, `slope` the least `cos(theta/2)` of the starts' neighbours, 1 when not
/// known), and noise of deviation `sigma` (`team.ranging.noise_std_m`) gives the fitted change a
/// deviation of `sigma sqrt(12/n)` (a least-squares slope's, times `S`). With the change `m`
/// such deviations each pick is right with probability `Phi(m)`, and the ring needs all `2 N`
/// right: under [`PROBE_PICKS_RIGHT`] the probes may not find it (and the law is off for the
/// run without it): the `not_applicable` reason, `None` otherwise (or without noise;
/// `team.v_max_mps <= v0` is [`probe_cannot_fly`]'s).
pub(super) fn probe_below_noise(team: &TeamSpec, slope: f64) -> Option<String> {
    let RingMode::Discover(d) = team.ring else {
        return None;
    };
    let v0 = team.nominal_speed_mps;
    let sigma = team.ranging.noise_std_m;
    let dv = (v0 + d.probe_speed_delta_mps).min(team.v_max_mps) - v0;
    let kept = 1.0 - team.ranging.dropout_probability;
    let samples = (d.probe_s * team.ranging.rate_hz).floor() * kept;
    if !(sigma > 0.0 && dv > 0.0 && samples > 0.0) {
        return None;
    }
    let change = dv * d.probe_s * slope.clamp(0.0, 1.0);
    let noise = sigma * (12.0 / samples).sqrt();
    let picks = 2 * team.count();
    let all_right = (1.0 - normal_upper_tail(change / noise)).powi(picks as i32);
    (all_right < PROBE_PICKS_RIGHT).then(|| {
        format!(
            "team.ring = \"discovered\": the probe changes a speed by {} m/s (team.v_max_mps = {} m/s against v0 = {} m/s), moving a neighbour's range by about {} m over its {} s slot (dv S cos(theta/2), theta the widest arc to a neighbour under half the circle), {} deviations of the {} m that team.ranging.noise_std_m = {} leaves in the fitted change ({} ranges kept of the slot's {} at team.ranging.dropout_probability = {}: sigma sqrt(12/n)): each of the ring's {picks} picks is right with probability Phi({}), all of them with {} < {}, so the probes may not find the ring, and without it the spacing law is off for the whole run; raise team.v_max_mps, lower the noise or the dropouts, or list the ring",
            Num(dv),
            Echo(team.v_max_mps),
            Echo(v0),
            Num(change),
            Num(d.probe_s),
            Num(change / noise),
            Num(noise),
            Echo(sigma),
            Num(samples),
            (d.probe_s * team.ranging.rate_hz).floor(),
            Echo(team.ranging.dropout_probability),
            Num(change / noise),
            Num(all_right),
            Num(PROBE_PICKS_RIGHT)
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

#[cfg(test)]
mod tests {
    use super::normal_upper_tail;

    /// `Phi(-m)` at known quantiles: 1/2 at 0, 2.5 % at 1.959963984540054, and the far tail
    /// `Phi(-8) = 6.220960574271784e-16` (to 1e-12 relative: where 1 - Phi(8) by subtraction is
    /// lost, and Abramowitz & Stegun 7.1.26's absolute 1.5e-7 was all of it).
    #[test]
    fn the_normal_tail_at_known_quantiles() {
        assert_eq!(normal_upper_tail(0.0), 0.5);
        assert!((normal_upper_tail(1.959963984540054) - 0.025).abs() < 1e-15);
        assert!((normal_upper_tail(-1.959963984540054) - 0.975).abs() < 1e-15);
        let far = normal_upper_tail(8.0);
        assert!((far / 6.220960574271784e-16 - 1.0).abs() < 1e-12, "{far}");
    }
}
