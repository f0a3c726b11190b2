//! The team check's reading of a ring on a known circle, shared by the check's rules
//! ([`super::team`]) and the shifted equilibrium ([`super::team::ShiftedEquilibrium`]): where a
//! start lies on the circle, the team's common speed, the direction of travel.
use super::setup::Law;
use crate::spec::TeamSpec;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::Vec2;
use isotrack_sim::team::arc::CircleArc;

/// How far from the circle, as a fraction of its radius, a start may lie and still be judged by
/// its angle about the centre (att44-1, -2, -5: a start 13 m off the circle was taken for the
/// point of the circle at its angle, where it does not join it).
pub(crate) const ON_CIRCLE_REL_TOL: f64 = 1e-3;

/// Start `i`'s angle about `circle`'s centre, rad, when it lies on the circle (within
/// [`ON_CIRCLE_REL_TOL`]); `None` otherwise (where it joins the circle is not the check's to
/// tell).
pub(crate) fn start_angle(team: &TeamSpec, circle: CircleArc, i: usize) -> Option<f64> {
    let d = Vec2::new(team.starts[i].x_m, team.starts[i].y_m) - circle.center_m;
    let r = d.norm();
    (r > 0.0 && (r - circle.radius_m).abs() <= ON_CIRCLE_REL_TOL * circle.radius_m)
        .then(|| d.y.atan2(d.x))
}

/// Where the clamp of att32d-2 is active: the team's common steady speed
/// `V = clamp(mean, max_i v_min_i, min_i v_max_i)` when it differs from `mean` (the mean
/// nominal speed, where the unsaturated loop settles: the gaps' sum is conserved, so the
/// speeds' mean offset is zero), with the vehicle whose bound sets it and which bound; `None`
/// when the mean lies in every envelope (or none is common: [`disjoint_envelopes`]).
pub(crate) fn common_speed(team: &TeamSpec, mean: f64) -> Option<(f64, usize, &'static str)> {
    let (lo, hi) = envelope_extremes(team);
    if lo.1 > hi.1 {
        None
    } else if mean > hi.1 {
        Some((hi.1, hi.0, "top speed v_max"))
    } else if mean < lo.1 {
        Some((lo.1, lo.0, "slowest speed v_min"))
    } else {
        None
    }
}

/// The direction the PI-like law travels a radial field's circle (att43-10, -11): `-1`
/// clockwise, `+1` counter-clockwise, `None` for another law. The field falls outward
/// (`team_arc`'s radial fields: `i0 > 0`, `k > 0`), so inside the circle `eps > 0` and the
/// law's steady term `kp c1 tanh(eps/c2)` turns the vehicle left (a positive turn rate is
/// counter-clockwise) when `kp c1 > 0`: on a clockwise orbit left is outward, back to the
/// circle, so the law travels clockwise, the paper's "higher values on the right"
/// (`controller.higher_side = "right"`); `"left"` mirrors the law (`omega -> -omega`), and so
/// does `kp c1 < 0`. A vehicle started the other way turns round.
pub(crate) fn travel_direction(s: &Scenario, l: &Law) -> Option<f64> {
    let side = s.spec().controller.pi_isoline()?.output.higher_side.sign();
    let k = l.kp * l.c1;
    (k != 0.0 && k.is_finite()).then(|| -k.signum() * side)
}

/// Two vehicles whose speed envelopes share no speed ([`disjoint_envelopes`]): vehicle
/// `fast`'s slowest command is above vehicle `slow`'s fastest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisjointEnvelopes {
    /// The vehicle with the largest `v_min_i` (the first in the listed order).
    pub fast: usize,
    /// Its `v_min_i`, m/s.
    pub fast_v_min_mps: f64,
    /// The vehicle with the smallest `v_max_i` (the first in the listed order).
    pub slow: usize,
    /// Its `v_max_i`, m/s.
    pub slow_v_max_mps: f64,
}

impl DisjointEnvelopes {
    /// Why the team fails, naming both vehicles and the keys.
    pub fn reason(&self) -> String {
        format!(
            "no speed is common to every vehicle's envelope: vehicle {}'s slowest command (v_min = {} m/s) is above vehicle {}'s fastest (v_max = {} m/s; team.vehicles, team.v_min_mps, team.v_max_mps), so the gaps cannot settle whatever the law: vehicle {} gains at least {} m/s on vehicle {} and laps it (robots pass through each other)",
            self.fast,
            Echo(self.fast_v_min_mps),
            self.slow,
            Echo(self.slow_v_max_mps),
            self.fast,
            Num(self.fast_v_min_mps - self.slow_v_max_mps),
            self.slow
        )
    }
}

/// Two vehicles of `team` with no common speed, or `None` (issue 32, att32d-1). A spread team
/// on a closed isoline keeps its gaps only if every vehicle moves at one common speed `V` in
/// steady state (each gap's rate is `v_{i+1} - v_i`, and the gaps sum to the isoline's
/// length): so `V` must lie in every envelope, `max_i v_min_i <= V <= min_i v_max_i`. When
/// `max_i v_min_i > min_i v_max_i` no such `V` exists: the vehicle with the largest `v_min`
/// gains at least the difference on the one with the smallest `v_max`, whatever the spacing
/// law commands, and laps it. `check` said `holds` and the robots passed through each other
/// (closest approach 1.3e-4 m).
pub fn disjoint_envelopes(team: &TeamSpec) -> Option<DisjointEnvelopes> {
    if team.count() < 2 || team.vehicles.is_empty() {
        return None;
    }
    let (fast, slow) = envelope_extremes(team);
    (fast.1 > slow.1).then_some(DisjointEnvelopes {
        fast: fast.0,
        fast_v_min_mps: fast.1,
        slow: slow.0,
        slow_v_max_mps: slow.1,
    })
}

/// The team's largest `v_min_i` and smallest `v_max_i`, m/s, each with the first vehicle (in the
/// listed order) that has it: the bounds of a common speed, `max_i v_min_i <= V <= min_i v_max_i`
/// ([`common_speed`], [`disjoint_envelopes`]).
fn envelope_extremes(team: &TeamSpec) -> ((usize, f64), (usize, f64)) {
    let (mut lo, mut hi) = ((0, f64::NEG_INFINITY), (0, f64::INFINITY));
    for i in 0..team.count() {
        let v = team.speeds(i);
        if v.min_mps > lo.1 {
            lo = (i, v.min_mps);
        }
        if v.max_mps < hi.1 {
            hi = (i, v.max_mps);
        }
    }
    (lo, hi)
}

/// The radius of the circle the team flies round the known circle `c`: the P law's orbit when
/// it has one (att43-6, [`super::setup::p_law_orbit`]), else the isoline's; the ranges are its
/// chords.
pub(crate) fn flown_circle_radius_m(s: &Scenario, l: &Law, c: CircleArc) -> f64 {
    super::setup::p_law_orbit(s, l)
        .map(|o| o.orbit.radius_m)
        .filter(|&f| f.is_finite() && f > 0.0)
        .unwrap_or(c.radius_m)
}

/// The starts' arc gaps on the known circle `circle`, measured on a circle of `radius` m about
/// its centre: gap `i` from vehicle `i` to the next listed one ahead in the direction of travel,
/// in `[0, 2 pi radius)` m (`None`: a start off the circle, or the direction not known).
pub(crate) fn deployed_gaps_ahead(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    circle: CircleArc,
    radius: f64,
) -> Option<Vec<f64>> {
    let dir = travel_direction(s, l)?;
    let angle = |i: usize| start_angle(team, circle, i);
    let n = team.count();
    (0..n)
        .map(|i| {
            let step = (dir * (angle((i + 1) % n)? - angle(i)?)).rem_euclid(std::f64::consts::TAU);
            Some(step * radius)
        })
        .collect()
}
