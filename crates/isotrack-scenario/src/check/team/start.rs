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
use isotrack_sim::team::spacing::{
    balance_speed, RingMode, SpacingLaw, MIN_RATE_FIT_RANGES, RANGE_HOLD_S,
};
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
/// ring: `fails`; under [`PROBE_PICKS_RIGHT`], or with dropouts and the mean kept per slot
/// `n_eff = probe_s rate_hz (1 - p)` under the need, they may not: `not_applicable` (without
/// dropouts the slots' exact counts decide, att53t-3). Without
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
    // att53t-3: without dropouts every slot's count is exact (all_fit 1 when each holds `need`),
    // and the mean n_eff (below `need` when some slots hold one fewer) adds nothing.
    let lossless = r.dropout_probability == 0.0;
    if all_fit >= PROBE_PICKS_RIGHT && (lossless || n_eff >= need as f64) {
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

/// Ranging periods the start model ([`closest_in_model`]) steps past the first delivery: enough
/// for the transient of a delayed loop (its overshoot peaks a few periods after the first
/// ranges that show a drift arrive) and for a slow loop to have turned.
const MODEL_PERIODS: u64 = 40;

/// At most this many vehicle-events in the start model: a team and delay past it are not
/// modelled ([`delay_drift_claim`] says `not_applicable`), so the model's time and the samples
/// it holds in flight stay bounded (att54t-7).
const MODEL_WORK: u64 = 4_000_000;

/// The closest any listed neighbours come in the start model ([`delay_drift_claim`]): vehicle
/// `i` and the one ahead of it.
struct Closest {
    /// The vehicle behind, listed.
    i: usize,
    /// Its deployed arc gap ahead, m.
    deployed_m: f64,
    /// The gap at `t = d` (every vehicle at its own `v0` until then), m.
    at_delay_m: f64,
    /// The gap at `t = d + T` (each holding the command of the ranges measured at `t = 0`), m.
    at_period_m: f64,
    /// The least gap over the model's horizon, m, and when, s.
    least_m: f64,
    least_s: f64,
    /// When the gap reaches zero (the two pass through each other), s.
    crossing_s: Option<f64>,
    /// How much closer a lost range can bring the two, m (0 without dropouts).
    lost_m: f64,
}

/// att50-5, att53t-1, -2, -8: `range_balance` on a listed ring whose start the sampled linear
/// loop does not describe: unequal nominal speeds with a ranging delay `d`, or ranges lost at a
/// period `T` past [`RANGE_HOLD_S`] with a finite `max_range_m`. The first ranges, measured at
/// `t = 0`, arrive at `d` (the engine's first ranging step is step 0): until then each vehicle
/// flies its own `v0_i`; from then on each holds the command of the last ranges delivered,
/// `sat(v0_i + k_v (r_ahead - r_behind))`, the ranges measured at `k T` acting from `k T + d`.
/// [`closest_in_model`] steps that (arc positions on the flown circle, chord ranges) for
/// [`MODEL_PERIODS`] periods past the delay, so a delayed loop that keeps closing a gap after
/// `d + T` (att53t-1) is seen. A gap that reaches zero means two robots pass through each other
/// and the listed ring is no longer the order of travel: `fails`; one under
/// [`CLOSE_APPROACH_M`]: `not_applicable`. The model keeps every range; with
/// `dropout_probability > 0` a lost range can close a gap further: a lost first range keeps a
/// vehicle on its `v0` one more period (`|v0_j - v0_i| T`, att53t-2), and with a finite
/// `max_range_m` and `T > RANGE_HOLD_S` a lost range reads `max_range_m` and kicks a vehicle to
/// a bound for a period (`(v_max_i - v_min_j) T`, att53t-8): a least gap within that of
/// [`CLOSE_APPROACH_M`] is `not_applicable` too. `None` otherwise (one nominal speed and no
/// such kick, no delay, another law or ring, off a known circle).
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
    let (d, t) = (r.delay_s, 1.0 / r.rate_hz);
    let drift = r.delay_s > 0.0 && unequal;
    let lossy = r.dropout_probability > 0.0;
    let kick = lossy && r.max_range_m.is_finite() && t > RANGE_HOLD_S;
    if !((drift || kick) && gain_per_s != 0.0 && n >= 3 && listed) {
        return None;
    }
    // The model queues every ranging sample in flight (d / T periods x N vehicles) and steps
    // N vehicles per event: past MODEL_WORK vehicle-events it is not run, and the start is
    // not vouched for (att54t-7: N = 1000, d = 5000 s at 100 Hz took 20 s and 7.8 GB).
    let work = n as f64 * ((d / t).ceil() + MODEL_PERIODS as f64);
    if work > MODEL_WORK as f64 {
        return Some((
            Verdict::NotApplicable,
            format!(
                "range_balance with team.ranging.delay_s = {} s at {} Hz and {n} vehicles: the start before the loop acts (each vehicle on its own command until the first ranges arrive, then ranges applied d later) would need {} vehicle-steps to model, past the check's bound of {MODEL_WORK}: the start is not checked; a shorter delay or fewer vehicles bring it within reach",
                Echo(d),
                Echo(r.rate_hz),
                Num(work)
            ),
        ));
    }
    let c = closest_in_model(s, l, team, gain_per_s, lossy && drift, kick)?;
    if c.least_m >= CLOSE_APPROACH_M + c.lost_m && c.crossing_s.is_none() {
        return None;
    }
    let (i, j) = (c.i, (c.i + 1) % n);
    let outcome = match c.crossing_s {
        Some(at) => format!(
            "they pass through each other at t = {} s, so the listed ring is no longer the order of travel and range_balance drives neighbours together",
            Num(at)
        ),
        None if c.least_m < CLOSE_APPROACH_M => format!(
            "under the run's close-approach distance {} m: two robots may meet before the loop settles",
            Num(CLOSE_APPROACH_M)
        ),
        None => format!(
            "the model keeps every range, but with team.ranging.dropout_probability = {} a lost range can close the gap by up to {} m more ({}), which would bring it under the run's close-approach distance {} m: two robots may meet",
            Echo(r.dropout_probability),
            Num(c.lost_m),
            lost_range_effect(drift, kick),
            Num(CLOSE_APPROACH_M)
        ),
    };
    let verdict = match c.crossing_s {
        Some(_) => Verdict::Fails,
        None => Verdict::NotApplicable,
    };
    let cause = if drift {
        format!(
            "unequal nominal speeds and team.ranging.delay_s = {} s",
            Echo(d)
        )
    } else {
        format!(
            "team.ranging.max_range_m = {} and ranging every {} s",
            Echo(r.max_range_m),
            Num(t)
        )
    };
    Some((
        verdict,
        format!(
            "range_balance with {cause}: the first ranges, measured at t = 0, arrive at t = d, so until then every vehicle flies its own v0, and until the ranges measured at T = {} s arrive (t = d + T = {} s) each holds the command of the first: vehicle {i} (v0 = {} m/s) and vehicle {j} ahead of it (v0 = {} m/s) go from a deployed gap of {} m to {} m at t = d and {} m at t = d + T; stepping on (the ranges measured every T applied d later, saturated, on the flown circle, for {MODEL_PERIODS} periods past the delay), the least gap is {} m at t = {} s; {outcome}; {}",
            Num(t),
            Num(d + t),
            Echo(team.speeds(i).nominal_mps),
            Echo(team.speeds(j).nominal_mps),
            Num(c.deployed_m),
            Num(c.at_delay_m),
            Num(c.at_period_m),
            Num(c.least_m),
            Num(c.least_s),
            if drift {
                "shorten team.ranging.delay_s, deploy the faster vehicles further behind the slower, or give the vehicles one nominal speed"
            } else {
                "range faster than every 1 s (a lost range is then held), lower the dropouts, or deploy the vehicles further apart"
            }
        ),
    ))
}

/// The lost-range effects [`delay_drift_claim`] adds, named.
fn lost_range_effect(drift: bool, kick: bool) -> &'static str {
    match (drift, kick) {
        (true, true) => "a lost first range keeps a vehicle on its own v0 one more period, |v0_j - v0_i| T, or a lost range read as max_range_m kicks a vehicle to a bound for a period, (v_max_i - v_min_j) T",
        (true, false) => "a lost first range keeps a vehicle on its own v0 one more period: |v0_j - v0_i| T",
        _ => "a lost range, past the 1 s hold, is read as max_range_m and kicks a vehicle to a bound for a period: (v_max_i - v_min_j) T",
    }
}

/// [`Closest`] for `range_balance` at gain `k_v` on the known circle (arc gaps on the circle
/// flown), `None` off it: the start model of [`delay_drift_claim`], stepped from event to
/// event (the ranging instants `k T` and the deliveries `k T + d`). Between events every speed
/// is constant, so each gap moves on a line: its least is at an event, its first zero where the
/// line crosses it (the model stops there). `drift_lost`, `kick_lost`: add the lost-range
/// effects to [`Closest::lost_m`].
fn closest_in_model(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    k_v: f64,
    drift_lost: bool,
    kick_lost: bool,
) -> Option<Closest> {
    let circle = s.team_arc()?;
    let radius = flown_circle_radius_m(s, l, circle);
    let gaps = deployed_gaps_ahead(s, l, team, circle, radius)?;
    let n = team.count();
    let r = &team.ranging;
    let (d, t) = (r.delay_s, 1.0 / r.rate_hz);
    let start = |i: usize| Vec2::new(team.starts[i].x_m, team.starts[i].y_m);
    let speeds: Vec<_> = (0..n).map(|i| team.speeds(i)).collect();
    // Arc positions along the travel: gap i = pos[i + 1] - pos[i] (the last one wraps).
    let length: f64 = gaps.iter().sum();
    let mut pos: Vec<f64> = gaps
        .iter()
        .scan(0.0, |at, g| {
            let here = *at;
            *at += g;
            Some(here)
        })
        .collect();
    let gap = |pos: &[f64], i: usize| {
        let ahead = if i + 1 == n {
            pos[0] + length
        } else {
            pos[i + 1]
        };
        ahead - pos[i]
    };
    // A neighbour beyond the range does not answer: the law sees max_range_m. The first
    // ranges are the starts' distances, later ones chords of the arc gaps.
    let chord = |g: f64| (2.0 * radius * (g / (2.0 * radius)).sin()).abs();
    let measure = |pos: &[f64], k: u64| -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                let (a, b) = ((i + 1) % n, (i + n - 1) % n);
                let (ahead, behind) = if k == 0 {
                    ((start(a) - start(i)).norm(), (start(i) - start(b)).norm())
                } else {
                    (chord(gap(pos, i)), chord(gap(pos, b)))
                };
                (ahead.min(r.max_range_m), behind.min(r.max_range_m))
            })
            .collect()
    };
    let mut cmd: Vec<f64> = speeds.iter().map(|m| m.nominal_mps).collect();
    let delay_periods = (d / t).ceil() as u64;
    let periods =
        (MODEL_PERIODS + delay_periods).min((MODEL_WORK / n as u64).max(delay_periods + 2));
    // The gaps at d and d + T on their lines (the model overwrites them when it gets there;
    // a crossing before stops it).
    let first: Vec<f64> = measure(&pos, 0)
        .iter()
        .zip(&speeds)
        .map(|(&(a, b), m)| m.saturate(balance_speed(m.nominal_mps, k_v, a, b)))
        .collect();
    let mut out: Vec<Closest> = (0..n)
        .map(|i| {
            let j = (i + 1) % n;
            let at_delay_m = gaps[i] + (cmd[j] - cmd[i]) * d;
            (i, at_delay_m, at_delay_m + (first[j] - first[i]) * t)
        })
        .map(|(i, at_delay_m, at_period_m)| Closest {
            i,
            deployed_m: gaps[i],
            at_delay_m,
            at_period_m,
            least_m: gaps[i],
            least_s: 0.0,
            crossing_s: None,
            lost_m: 0.0,
        })
        .collect();
    let mut pending = std::collections::VecDeque::new();
    let (mut sampled, mut delivered, mut now) = (0_u64, 0_u64, 0.0_f64);
    while delivered < periods {
        let (t_sample, t_deliver) = (sampled as f64 * t, delivered as f64 * t + d);
        let next = t_sample.min(t_deliver);
        let span = next - now;
        let mut crossed = false;
        for (i, c) in out.iter_mut().enumerate() {
            let before = gap(&pos, i);
            let rate = cmd[(i + 1) % n] - cmd[i];
            let after = before + rate * span;
            if after <= 0.0 && c.crossing_s.is_none() {
                let at = if before <= 0.0 {
                    now
                } else {
                    now + before / -rate
                };
                (c.crossing_s, c.least_m, c.least_s) = (Some(at), 0.0, at);
                crossed = true;
            } else if after < c.least_m {
                (c.least_m, c.least_s) = (after, next);
            }
        }
        if crossed {
            break;
        }
        for (p, v) in pos.iter_mut().zip(&cmd) {
            *p += v * span;
        }
        now = next;
        if t_sample <= t_deliver {
            pending.push_back(measure(&pos, sampled));
            sampled += 1;
            continue;
        }
        for (c, i) in out.iter_mut().zip(0..) {
            match delivered {
                0 => c.at_delay_m = gap(&pos, i),
                1 => c.at_period_m = gap(&pos, i),
                _ => {}
            }
        }
        let ranges = pending.pop_front()?;
        for (i, (ahead, behind)) in ranges.into_iter().enumerate() {
            cmd[i] = speeds[i].saturate(balance_speed(speeds[i].nominal_mps, k_v, ahead, behind));
        }
        delivered += 1;
    }
    for c in &mut out {
        let (a, b) = (&speeds[c.i], &speeds[(c.i + 1) % n]);
        let drift = (a.nominal_mps - b.nominal_mps).abs() * t;
        let kick = (a.max_mps - b.min_mps).max(0.0) * t;
        c.lost_m = f64::max(
            if drift_lost { drift } else { 0.0 },
            if kick_lost { kick } else { 0.0 },
        );
    }
    out.into_iter().min_by(|a, b| {
        let cross = |c: &Closest| c.crossing_s.unwrap_or(f64::INFINITY);
        let margin = |c: &Closest| c.least_m - c.lost_m;
        cross(a)
            .total_cmp(&cross(b))
            .then(margin(a).total_cmp(&margin(b)))
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
