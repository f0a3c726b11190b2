//! Before the spacing loop acts (docs/TEAMS.md, "Theory"): what the sampled linear loop of the
//! team check does not see at the start of a run, each a claim on the team verdict
//! ([`super::spacing_claim`]):
//!
//! * the discovery's probe slots (att51-5, [`probe_slots_claim`]): whether every slot holds
//!   the ranges the prober's rate fit needs;
//! * the ranging delay with unequal nominal speeds (att50-5, [`delay_drift_claim`]): how the
//!   gaps move before the first ranges that show any drift arrive.

use super::equilibrium::PROBE_PICKS_RIGHT;
use crate::check::setup::Law;
use crate::check::team_ring::{deployed_gaps_ahead, flown_circle_radius_m};
use crate::check::Verdict;
use crate::spec::TeamSpec;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::Vec2;
use isotrack_sim::team::metrics::CLOSE_APPROACH_M;
use isotrack_sim::team::spacing::{balance_speed, RingMode, SpacingLaw, MIN_RATE_FIT_RANGES};
use isotrack_sim::whole_steps;

/// The ranging instants in each probe slot of a discovery, as the engine schedules them: a
/// ranging unit measures at the steps that are multiples of its period's `every` steps (from
/// step 0), and slot `j` spans the steps `[a, a + P)`, `a = settle + j P` (`settle_s` and
/// `probe_s` rounded to steps, `P` at least one). `None` when the rate is not whole steps (the
/// run refuses it).
pub(super) fn probe_slot_ranges(
    dt_s: f64,
    rate_hz: f64,
    settle_s: f64,
    probe_s: f64,
    slots: usize,
) -> Option<Vec<u64>> {
    let every = whole_steps(1.0 / rate_hz, dt_s).ok().filter(|&e| e > 0)?;
    let settle = (settle_s / dt_s).round() as u64;
    let probe = ((probe_s / dt_s).round() as u64).max(1);
    // The multiples of `every` in [0, k).
    let before = |k: u64| k.div_ceil(every);
    Some(
        (0..slots as u64)
            .map(|j| {
                let a = settle + j * probe;
                before(a + probe) - before(a)
            })
            .collect(),
    )
}

/// `P(X >= k)` for `X ~ Binomial(n, q)`: one minus the terms below `k`, summed directly (the
/// workspace has no binomial distribution), clamped to `[0, 1]`.
pub(super) fn binomial_at_least(n: u64, q: f64, k: usize) -> f64 {
    let mut below = 0.0;
    let mut choose = 1.0; // C(n, i)
    for i in 0..(k as u64).min(n + 1) {
        below += choose * q.powf(i as f64) * (1.0 - q).powf((n - i) as f64);
        choose *= (n - i) as f64 / (i + 1) as f64;
    }
    (1.0 - below).clamp(0.0, 1.0)
}

/// att51-5: a discovered ring whose probe slots do not hold the ranges the prober needs. In its
/// slot each prober fits every vehicle's range rate to the ranges it gets and needs at least
/// [`MIN_RATE_FIT_RANGES`] to one vehicle for a rate; a neighbour without a rate is not picked
/// (another vehicle, or none, is). Slot `j` holds `n_j` ranging instants
/// ([`probe_slot_ranges`]: with slow ranging 2 or 3 in a 10 s slot, by the slot's phase), each
/// range kept with probability `1 - p` (`p = team.ranging.dropout_probability`, drawn per
/// range), so a neighbour gets its rate with `P(Binomial(n_j, 1 - p) >= 3)`, and the ring needs
/// both neighbours of every prober (one with two vehicles): the product over the slots. With
/// that product 0 (a slot with fewer instants than the fit needs) the probes cannot find the
/// ring: `fails`; under [`PROBE_PICKS_RIGHT`], or with the mean kept per slot
/// `n_eff = probe_s rate_hz (1 - p)` under the need, they may not: `not_applicable`. Without
/// the ring the spacing law is off for the whole run (the run warns it). `None` otherwise.
pub(super) fn probe_slots_claim(s: &Scenario, team: &TeamSpec) -> Option<(Verdict, String)> {
    let RingMode::Discover(d) = team.ring else {
        return None;
    };
    let n = team.count();
    let r = &team.ranging;
    if n < 2 {
        return None;
    }
    let slots = probe_slot_ranges(s.dt_s(), r.rate_hz, d.settle_s, d.probe_s, n)?;
    let kept = 1.0 - r.dropout_probability;
    let need = MIN_RATE_FIT_RANGES;
    let fits_per_slot = (n - 1).min(2);
    let all_fit: f64 = slots
        .iter()
        .map(|&m| binomial_at_least(m, kept, need).powi(fits_per_slot as i32))
        .product();
    let n_eff = d.probe_s * r.rate_hz * kept;
    if all_fit >= PROBE_PICKS_RIGHT && n_eff >= need as f64 {
        return None;
    }
    let (verdict, can) = if all_fit == 0.0 {
        (Verdict::Fails, "cannot")
    } else {
        (Verdict::NotApplicable, "may not")
    };
    // At most 64 slots (the discovery's team size limit): every one listed.
    let by_slot = format!("by slot {slots:?}");
    Some((
        verdict,
        format!(
            "team.ring = \"discovered\" with team.ranging.rate_hz = {} Hz and team.ranging.dropout_probability = {}: each prober fits a vehicle's range rate to the ranges of its {} s slot and needs at least {need} to it for a rate; the slots (after settle_s = {} s, ranging every {} s) hold {by_slot} ranging instants, n_eff = probe_s rate_hz (1 - dropout_probability) = {} kept on average, and the ring's {} fits (each prober's neighbours) all get {need} with probability {} (each P(Binomial(n, 1 - p) >= {need})), {} {}: the probes {can} find the ring, and without it the spacing law is off for the whole run (the run warns it); raise team.ranging.rate_hz (a period of at most probe_s/{need} = {} s puts {need} instants in every slot), lower the dropouts, or list the ring",
            Echo(r.rate_hz),
            Echo(r.dropout_probability),
            Num(d.probe_s),
            Num(d.settle_s),
            Num(1.0 / r.rate_hz),
            Num(n_eff),
            fits_per_slot * n,
            Num(all_fit),
            if all_fit < PROBE_PICKS_RIGHT { "<" } else { ">=" },
            Num(PROBE_PICKS_RIGHT),
            Num(d.probe_s / need as f64)
        ),
    ))
}

/// The closest any listed neighbours come before the loop acts on a drift
/// ([`delay_drift_claim`]): vehicle `i` and the one ahead of it.
struct Closest {
    /// The vehicle behind, listed.
    i: usize,
    /// Its deployed arc gap ahead, m.
    deployed_m: f64,
    /// The gap at `t = d` (every vehicle at its own `v0` until then), m.
    at_delay_m: f64,
    /// The gap at `t = d + T` (each holding the command of the ranges measured at `t = 0`), m.
    at_period_m: f64,
    /// When the gap reaches zero within `[0, d + T]` (the two pass through each other), s.
    crossing_s: Option<f64>,
}

/// att50-5: `range_balance` with unequal nominal speeds and a ranging delay `d`. The first
/// ranges, measured at `t = 0`, arrive at `d` (the engine's first ranging step is step 0):
/// until then each vehicle flies its own `v0_i`, so gap `i` (vehicle `i` to the one ahead)
/// moves by `(v0_{i+1} - v0_i) d`; from `d` to `d + T`, when the first ranges that show any of
/// that drift arrive, each holds the command of the ranges measured at `t = 0` (the starts'
/// distances), `sat(v0_i + k_v (r_ahead - r_behind))`, so the gap moves by the difference of
/// those times `T`. The linear loop starts from the end of that: on a known circle, with the
/// first ranges kept (a lost one holds the vehicles open loop longer), a gap that reaches zero
/// in `[0, d + T]` means two robots pass through each other and the listed ring is no longer
/// the order of travel: `fails`; one under [`CLOSE_APPROACH_M`]: `not_applicable`. `None`
/// otherwise (one nominal speed, no delay, another law or ring, off a known circle).
pub(super) fn delay_drift_claim(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
) -> Option<(Verdict, String)> {
    let SpacingLaw::RangeBalance { gain_per_s } = team.law else {
        return None;
    };
    let r = &team.ranging;
    let n = team.count();
    let unequal = team.nominal_speeds_mps().len() > 1;
    let listed = matches!(team.ring, RingMode::Listed);
    if !(r.delay_s > 0.0 && gain_per_s != 0.0 && n >= 3 && unequal && listed) {
        return None;
    }
    let c = closest_before_loop(s, l, team, gain_per_s)?;
    let least = c.at_delay_m.min(c.at_period_m);
    if least >= CLOSE_APPROACH_M && c.crossing_s.is_none() {
        return None;
    }
    let (i, j) = (c.i, (c.i + 1) % n);
    let (d, t) = (r.delay_s, 1.0 / r.rate_hz);
    let outcome = match c.crossing_s {
        Some(at) => format!(
            "they pass through each other at t = {} s, so the listed ring is no longer the order of travel and range_balance drives neighbours together",
            Num(at)
        ),
        None => format!(
            "under the run's close-approach distance {} m: two robots may meet before the loop acts",
            Num(CLOSE_APPROACH_M)
        ),
    };
    let verdict = match c.crossing_s {
        Some(_) => Verdict::Fails,
        None => Verdict::NotApplicable,
    };
    Some((
        verdict,
        format!(
            "range_balance with unequal nominal speeds and team.ranging.delay_s = {} s: the first ranges, measured at t = 0, arrive at t = d, so until then every vehicle flies its own v0, and until the ranges measured at T = {} s arrive (t = d + T = {} s) each holds the command of the first: vehicle {i} (v0 = {} m/s) and vehicle {j} ahead of it (v0 = {} m/s) go from a deployed gap of {} m to {} m at t = d and {} m at t = d + T; {outcome}; shorten team.ranging.delay_s, deploy the faster vehicles further behind the slower, or give the vehicles one nominal speed",
            Echo(d),
            Num(t),
            Num(d + t),
            Echo(team.speeds(i).nominal_mps),
            Echo(team.speeds(j).nominal_mps),
            Num(c.deployed_m),
            Num(c.at_delay_m),
            Num(c.at_period_m)
        ),
    ))
}

/// [`Closest`] for `range_balance` at gain `k_v` on the known circle (arc gaps on the circle
/// flown), `None` off it: each gap's path over `[0, d]` and `[d, d + T]` is a line, so its
/// least is at an end, and the first zero (if any) is where that line crosses it.
fn closest_before_loop(s: &Scenario, l: &Law, team: &TeamSpec, k_v: f64) -> Option<Closest> {
    let circle = s.team_arc()?;
    let gaps = deployed_gaps_ahead(s, l, team, circle, flown_circle_radius_m(s, l, circle))?;
    let n = team.count();
    let r = &team.ranging;
    let (d, t) = (r.delay_s, 1.0 / r.rate_hz);
    let start = |i: usize| Vec2::new(team.starts[i].x_m, team.starts[i].y_m);
    // A neighbour beyond the range does not answer: the law sees max_range_m.
    let range = |i: usize, j: usize| (start(j) - start(i)).norm().min(r.max_range_m);
    let v0: Vec<f64> = (0..n).map(|i| team.speeds(i).nominal_mps).collect();
    let held: Vec<f64> = (0..n)
        .map(|i| {
            let (ahead, behind) = (range(i, (i + 1) % n), range(i, (i + n - 1) % n));
            team.speeds(i)
                .saturate(balance_speed(v0[i], k_v, ahead, behind))
        })
        .collect();
    (0..n)
        .map(|i| {
            let j = (i + 1) % n;
            let (open, closed) = (v0[j] - v0[i], held[j] - held[i]);
            let at_delay_m = gaps[i] + open * d;
            let at_period_m = at_delay_m + closed * t;
            let crossing_s = if at_delay_m <= 0.0 {
                // open < 0 here, or the two start together (gap 0, open 0).
                Some(if open < 0.0 { gaps[i] / -open } else { 0.0 })
            } else if at_period_m <= 0.0 {
                Some(d + at_delay_m / -closed)
            } else {
                None
            };
            Closest {
                i,
                deployed_m: gaps[i],
                at_delay_m,
                at_period_m,
                crossing_s,
            }
        })
        .min_by(|a, b| {
            let least = |c: &Closest| c.crossing_s.unwrap_or(f64::INFINITY);
            least(a).total_cmp(&least(b)).then(
                a.at_delay_m
                    .min(a.at_period_m)
                    .total_cmp(&b.at_delay_m.min(b.at_period_m)),
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 0.25 Hz ranging (every 4 s) in 10 s slots after 60 s: instants at 60, 64, 68 | 72, 76 |
    /// 80, 84, 88 | 92, 96 s; 0.4 Hz (every 2.5 s): 4 each; a slot of one step at a ranging
    /// step every step: 1 each.
    #[test]
    fn slot_instants_by_hand() {
        assert_eq!(
            probe_slot_ranges(0.01, 0.25, 60.0, 10.0, 4),
            Some(vec![3, 2, 3, 2])
        );
        assert_eq!(
            probe_slot_ranges(0.01, 0.4, 60.0, 10.0, 4),
            Some(vec![4, 4, 4, 4])
        );
        assert_eq!(
            probe_slot_ranges(0.01, 100.0, 0.0, 0.01, 3),
            Some(vec![1, 1, 1])
        );
        assert_eq!(probe_slot_ranges(0.01, 3.0, 60.0, 10.0, 4), None);
    }

    /// `P(Binomial(10, 0.2) >= 3) = 1 - (0.8^10 + 10 (0.2) 0.8^9 + 45 (0.04) 0.8^8)`
    /// `= 1 - (0.1073741824 + 0.268435456 + 0.301989888) = 0.3222004736`; certain and
    /// impossible ends.
    #[test]
    fn binomial_tail_by_hand() {
        assert!((binomial_at_least(10, 0.2, 3) - 0.322_200_473_6).abs() < 1e-12);
        assert_eq!(binomial_at_least(2, 1.0, 3), 0.0);
        assert_eq!(binomial_at_least(3, 1.0, 3), 1.0);
        assert_eq!(binomial_at_least(100, 0.0, 3), 0.0);
        assert_eq!(binomial_at_least(5, 0.5, 0), 1.0);
    }
}
