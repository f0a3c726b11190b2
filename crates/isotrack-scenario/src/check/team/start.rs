//! Before the spacing loop acts (docs/TEAMS.md, "Theory"): what the sampled linear loop of the
//! team check does not see at the start of a run, each a claim on the team verdict
//! ([`super::spacing_claim`]):
//!
//! * the discovery's probe slots (att51-5, [`probe_slots_claim`]): whether every slot holds
//!   the ranges the prober's rate fit needs;
//! * the start rule of `range_balance` on a listed ring ([`start_claim`]: att50-5, att53t,
//!   att54t): when the start matters (unequal nominal speeds, a ranging delay, losses, noise,
//!   a range limit), whether the start model's least gaps, less what the model does not carry,
//!   stay over the close-approach distance.

use super::equilibrium::PROBE_PICKS_RIGHT;
use crate::check::setup::Law;
use crate::check::team_ring::{
    deployed_gaps_ahead, flown_circle_radius_m, start_angle, ON_CIRCLE_REL_TOL,
};
use crate::check::Verdict;
use crate::spec::TeamSpec;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::Vec2;
use isotrack_sim::team::metrics::CLOSE_APPROACH_M;
use isotrack_sim::team::spacing::{
    balance_speed, RingMode, SpacingLaw, MIN_RATE_FIT_RANGES, RANGE_HOLD_S,
};
use isotrack_sim::{whole_steps, MemberSpeeds};

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

/// The start model steps at least this many ranging periods past the delay (a short delay's
/// transient: its overshoot peaks a few periods after the first ranges that show a drift).
const MODEL_MIN_PERIODS: f64 = 40.0;

/// ... and at least this many delays past `d + T`: a delayed loop's error turns about `2 d`
/// after the first delivery, whatever the period (att54t-1: `T = 0.5 s`, `d = 30 s` undershot
/// 111 periods past `d`).
const MODEL_DELAYS: f64 = 4.0;

/// ... and at least this many of the sampled loop's slowest time constants (the loop settled).
const MODEL_TIME_CONSTANTS: f64 = 3.0;

/// At most this many vehicle-events (every vehicle at every ranging instant and every delivery)
/// over the start model's whole horizon; past it the model is not run (att54t-7). The model
/// holds only the commands in flight (`ceil(d/T) + 1` per vehicle).
const MODEL_WORK: u64 = 4_000_000;

/// A run of lost ranges longer than the loss margin carries may have at most this chance over
/// the horizon's ranges (`M p^k <= 0.01`).
const LOSS_RUN_CHANCE: f64 = 0.01;

/// The ranging noise's deviations the noise margin covers.
const NOISE_SIGMAS: f64 = 3.0;

/// How long the start rule looks: from `t = 0` to
/// `d + T + max(40 T, 4 d, 3 tau)`, `tau` the sampled loop's slowest time constant.
struct Horizon {
    /// The ranging delay `d`, s.
    delay_s: f64,
    /// The ranging period `T`, s.
    period_s: f64,
    /// The sampled loop's slowest time constant `tau`, s (`None`: not known).
    tau_s: Option<f64>,
    /// The horizon's end, s (without `tau` when it is not known: a lower bound).
    end_s: f64,
}

impl Horizon {
    /// The horizon of `team`'s start, given the spacing loop's slowest time constant `tau_s`
    /// (the sampled one, else the continuous; `None`: not known).
    fn of(team: &TeamSpec, tau_s: Option<f64>) -> Self {
        let r = &team.ranging;
        let (d, t) = (r.delay_s, 1.0 / r.rate_hz);
        let tau_s = tau_s.filter(|x| x.is_finite() && *x > 0.0);
        let past = (MODEL_MIN_PERIODS * t)
            .max(MODEL_DELAYS * d)
            .max(MODEL_TIME_CONSTANTS * tau_s.unwrap_or(0.0));
        Self {
            delay_s: d,
            period_s: t,
            tau_s,
            end_s: d + t + past,
        }
    }

    /// Whether the horizon is known to cover the loop's settling (`tau` known), else why not.
    fn settles(&self) -> Result<(), String> {
        match self.tau_s {
            Some(_) => Ok(()),
            None => Err("the spacing loop's slowest time constant is not known, so neither is how long the start's transient lasts".into()),
        }
    }

    /// The ranging instants in the horizon, `ceil(end/T)`.
    fn periods(&self) -> f64 {
        (self.end_s / self.period_s).ceil()
    }

    /// The periods a command is in flight before the loop sees its effect, `ceil(d/T) + 1`.
    fn in_flight(&self) -> f64 {
        (self.delay_s / self.period_s).ceil() + 1.0
    }

    /// "to t = ... s = d + T + max(40 T, 4 d, 3 tau), tau = ... s".
    fn text(&self) -> String {
        match self.tau_s {
            Some(tau) => format!(
                "to t = {} s = d + T + max(40 T, 4 d, 3 tau) with tau = {} s, the spacing loop's slowest time constant",
                Num(self.end_s),
                Num(tau)
            ),
            None => format!(
                "at least to t = {} s = d + T + max(40 T, 4 d), the spacing loop's time constant not known",
                Num(self.end_s)
            ),
        }
    }
}

/// The smallest run `k` of consecutive losses whose chance among `ranges` ranges is small:
/// `ranges p^k <= LOSS_RUN_CHANCE` (0 without losses; at least 1 with).
fn loss_run(p: f64, ranges: f64) -> f64 {
    if p <= 0.0 {
        return 0.0;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    ((LOSS_RUN_CHANCE / ranges).ln() / p.ln()).ceil().max(1.0)
}

/// What the start model does not carry, for one pair (vehicle `i` behind, `j` ahead).
struct Margin {
    /// `w = max(0, v_max_i - v_min_j)`: how fast a wrong command can close the pair, m/s.
    closing_mps: f64,
    /// `min(w, 2 x 3 k_v sigma)`: how far the noise can err the pair's closing rate, m/s.
    noise_mps: f64,
    /// Lost ranges: `w k T`, m.
    loss_m: f64,
    /// Ranging noise: `min(w, 6 k_v sigma) (q + 1) T`, m.
    noise_m: f64,
}

impl Margin {
    /// Pair `i`'s margin with runs of `k` losses ([`loss_run`]).
    fn of(team: &TeamSpec, k_v: f64, h: &Horizon, k: f64, i: usize) -> Self {
        let j = (i + 1) % team.count();
        let w = (team.speeds(i).max_mps - team.speeds(j).min_mps).max(0.0);
        let noise_mps = w.min(2.0 * NOISE_SIGMAS * k_v.abs() * team.ranging.noise_std_m);
        Self {
            closing_mps: w,
            noise_mps,
            loss_m: if k > 0.0 { w * k * h.period_s } else { 0.0 },
            noise_m: noise_mps * h.in_flight() * h.period_s,
        }
    }

    /// Both margins, m.
    fn total_m(&self) -> f64 {
        self.loss_m + self.noise_m
    }
}

/// The least gap of one pair over the horizon (vehicle `i` and the one ahead of it).
struct Closest {
    /// The vehicle behind, listed.
    i: usize,
    /// Its deployed gap ahead, m (an arc on the flown circle; the starts' distance when the
    /// model is not run).
    deployed_m: f64,
    /// The gap at `t = d` (every vehicle at its own `v0` until then), m.
    at_delay_m: f64,
    /// The gap at `t = d + T` (each holding the command of the ranges measured at `t = 0`), m.
    at_period_m: f64,
    /// The least gap over the horizon, m, and when, s.
    least_m: f64,
    least_s: f64,
    /// When the gap reaches zero (the two pass through each other), s.
    crossing_s: Option<f64>,
}

impl Closest {
    /// A gap that stands at `gap_m` (the starts' distance, the model not run).
    fn standing(i: usize, gap_m: f64) -> Self {
        Self {
            i,
            deployed_m: gap_m,
            at_delay_m: gap_m,
            at_period_m: gap_m,
            least_m: gap_m,
            least_s: 0.0,
            crossing_s: None,
        }
    }
}

/// The start rule's kinematic model of `range_balance` on a known circle: arc positions on the
/// flown circle, each vehicle on its own `v0` until its first command arrives, the commands
/// `sat(v0_i + k_v (r_ahead - r_behind))` of the ranges measured at `k T` (the starts'
/// distances at 0, chords of the arc gaps later, at most `max_range_m`) acting from `k T + d`.
/// Between events every speed is constant, so each gap moves on a line.
struct StartModel {
    speeds: Vec<MemberSpeeds>,
    k_v: f64,
    radius_m: f64,
    max_range_m: f64,
    length_m: f64,
    starts: Vec<Vec2>,
    /// Arc positions along the travel: gap `i = pos[i + 1] - pos[i]` (the last one wraps).
    pos: Vec<f64>,
    /// The commands in force.
    cmd: Vec<f64>,
}

impl StartModel {
    /// The model of `team`'s start, or why it cannot be run: no known circle, a start off it,
    /// no known direction of travel, or past [`MODEL_WORK`] over `h`.
    fn new(s: &Scenario, l: &Law, team: &TeamSpec, k_v: f64, h: &Horizon) -> Result<Self, String> {
        let n = team.count();
        let circle = s.team_arc().ok_or(
            "the isoline is not known to be a circle (an open, extracted or moving isoline; the model runs on a known circle)",
        )?;
        if let Some(i) = (0..n).find(|&i| start_angle(team, circle, i).is_none()) {
            let at = Vec2::new(team.starts[i].x_m, team.starts[i].y_m) - circle.center_m;
            return Err(format!(
                "vehicle {i}'s start is {} m off the circle of radius {} m, past {ON_CIRCLE_REL_TOL} of it (the model sets every start on the circle)",
                Num((at.norm() - circle.radius_m).abs()),
                Num(circle.radius_m)
            ));
        }
        let radius_m = flown_circle_radius_m(s, l, circle);
        let gaps = deployed_gaps_ahead(s, l, team, circle, radius_m)
            .ok_or("the direction of travel on the circle is not known (not the PI-like law)")?;
        let work = n as f64 * 2.0 * (h.periods() + 1.0);
        if work > MODEL_WORK as f64 {
            return Err(format!(
                "the model would need {} vehicle-events over its horizon ({n} vehicles, {} ranging instants {}), past the check's bound of {MODEL_WORK}",
                Num(work),
                Num(h.periods()),
                h.text()
            ));
        }
        let speeds: Vec<_> = (0..n).map(|i| team.speeds(i)).collect();
        let pos = gaps
            .iter()
            .scan(0.0, |at, g| {
                let here = *at;
                *at += g;
                Some(here)
            })
            .collect();
        Ok(Self {
            cmd: speeds.iter().map(|m| m.nominal_mps).collect(),
            speeds,
            k_v,
            radius_m,
            max_range_m: team.ranging.max_range_m,
            length_m: gaps.iter().sum(),
            starts: team
                .starts
                .iter()
                .map(|p| Vec2::new(p.x_m, p.y_m))
                .collect(),
            pos,
        })
    }

    /// Gap `i` (vehicle `i` to the one ahead), m.
    fn gap(&self, i: usize) -> f64 {
        let n = self.pos.len();
        let ahead = if i + 1 == n {
            self.pos[0] + self.length_m
        } else {
            self.pos[i + 1]
        };
        ahead - self.pos[i]
    }

    /// Every vehicle's command from the ranges measured now (`first`: the starts' distances).
    fn commands(&self, first: bool) -> Vec<f64> {
        let n = self.pos.len();
        let chord = |g: f64| (2.0 * self.radius_m * (g / (2.0 * self.radius_m)).sin()).abs();
        (0..n)
            .map(|i| {
                let (a, b) = ((i + 1) % n, (i + n - 1) % n);
                let (ahead, behind) = if first {
                    (
                        (self.starts[a] - self.starts[i]).norm(),
                        (self.starts[i] - self.starts[b]).norm(),
                    )
                } else {
                    (chord(self.gap(i)), chord(self.gap(b)))
                };
                let m = &self.speeds[i];
                let (ahead, behind) = (ahead.min(self.max_range_m), behind.min(self.max_range_m));
                m.saturate(balance_speed(m.nominal_mps, self.k_v, ahead, behind))
            })
            .collect()
    }

    /// Each pair's gap over the next `span` s from `now` (on a line): its least, and its first
    /// zero. Whether a gap reached zero (the model stops there).
    fn track(&self, out: &mut [Closest], now: f64, span: f64) -> bool {
        let n = self.pos.len();
        let mut crossed = false;
        for (i, c) in out.iter_mut().enumerate() {
            let before = self.gap(i);
            let rate = self.cmd[(i + 1) % n] - self.cmd[i];
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
                (c.least_m, c.least_s) = (after, now + span);
            }
        }
        crossed
    }

    /// Every pair's [`Closest`] over `h`, stepped event to event (the ranging instants `k T`,
    /// the deliveries `k T + d`), holding only the commands in flight.
    fn run(mut self, h: &Horizon) -> Vec<Closest> {
        let n = self.pos.len();
        let (d, t) = (h.delay_s, h.period_s);
        // The gaps at d and d + T on their lines (overwritten when the model gets there; a
        // crossing before stops it).
        let first = self.commands(true);
        let mut out: Vec<Closest> = (0..n)
            .map(|i| {
                let j = (i + 1) % n;
                let mut c = Closest::standing(i, self.gap(i));
                c.at_delay_m = c.deployed_m + (self.cmd[j] - self.cmd[i]) * d;
                c.at_period_m = c.at_delay_m + (first[j] - first[i]) * t;
                c
            })
            .collect();
        let mut pending = std::collections::VecDeque::new();
        let (mut sampled, mut delivered, mut now) = (0_u64, 0_u64, 0.0_f64);
        loop {
            let (t_sample, t_deliver) = (sampled as f64 * t, delivered as f64 * t + d);
            let event = t_sample.min(t_deliver);
            let next = event.min(h.end_s);
            if self.track(&mut out, now, next - now) {
                break;
            }
            for (p, v) in self.pos.iter_mut().zip(&self.cmd) {
                *p += v * (next - now);
            }
            now = next;
            if event > h.end_s {
                break;
            }
            if t_sample <= t_deliver {
                pending.push_back(self.commands(sampled == 0));
                sampled += 1;
                continue;
            }
            for (i, c) in out.iter_mut().enumerate() {
                match delivered {
                    0 => c.at_delay_m = self.gap(i),
                    1 => c.at_period_m = self.gap(i),
                    _ => {}
                }
            }
            if let Some(cmd) = pending.pop_front() {
                self.cmd = cmd;
            }
            delivered += 1;
        }
        out
    }
}

/// What makes `team`'s start matter to the verdict (unequal nominal speeds, a ranging delay,
/// losses, noise, a range limit), in words; `None` when nothing does (one nominal speed, no
/// delay, ideal unlimited ranging: the sampled loop describes the start).
fn start_matters(team: &TeamSpec) -> Option<String> {
    let r = &team.ranging;
    let mut why = vec![];
    if team.nominal_speeds_mps().len() > 1 {
        why.push("unequal nominal speeds".to_string());
    }
    for (key, value, on) in [
        ("delay_s", r.delay_s, r.delay_s > 0.0),
        (
            "dropout_probability",
            r.dropout_probability,
            r.dropout_probability > 0.0,
        ),
        ("noise_std_m", r.noise_std_m, r.noise_std_m > 0.0),
        ("max_range_m", r.max_range_m, r.max_range_m.is_finite()),
    ] {
        if on {
            why.push(format!("team.ranging.{key} = {}", Echo(value)));
        }
    }
    (!why.is_empty()).then(|| why.join(", "))
}

/// att50-5, att53t-1/-2/-8, att54t-1..-13: the START RULE of `range_balance` on a listed ring
/// (docs/TEAMS.md, "the start"), one conservative rule. The sampled linear loop does not see
/// the start when it matters ([`start_matters`]: unequal nominal speeds, `delay_s > 0`,
/// dropouts, noise, a finite `max_range_m`); then the start is vouched for (`None`: the loop's
/// verdict stands) only when all of:
///
/// * (a) the model can be run ([`StartModel`]): a known circle, every start on it (within
///   `ON_CIRCLE_REL_TOL` of its radius), the direction of travel known. Otherwise the only
///   exception is one nominal speed with no delay, whose gaps stand until the first commands act
///   at `t = 0`: the starts' neighbour distances stand in for the model; any other start is
///   `not_applicable`, naming the precondition that failed;
/// * (b) the model's horizon covers the transient ([`Horizon`]: `d + T + max(40 T, 4 d, 3 tau)`),
///   within [`MODEL_WORK`] vehicle-events over all of it, else `not_applicable` naming the bound;
/// * (c) each pair's least gap, less one margin for what the model does not carry
///   ([`Margin`]: for the pair `i` behind `j`, `w = max(0, v_max_i - v_min_j)`; a run of `k`
///   losses, the shortest with `M p^k <= 0.01` among the horizon's `M = 2 N ceil(end/T)`
///   ranges, keeps a wrong command (stale, none yet, or `max_range_m`) for `k T`: `w k T`; the
///   noise errs the pair's closing rate by up to `min(w, 3 x 2 k_v sigma)` for the
///   `ceil(d/T) + 1` periods in flight), is at least [`CLOSE_APPROACH_M`]; a gap through zero
///   in the model `fails` (two robots pass through each other), one within its margin of the
///   close-approach distance is `not_applicable`, with the numbers.
///
/// `None` for another law, `k_v = 0`, fewer than three vehicles or a discovered ring.
pub(super) fn start_claim(
    s: &Scenario,
    l: &Law,
    team: &TeamSpec,
    tau_s: Option<f64>,
) -> Option<(Verdict, String)> {
    let SpacingLaw::RangeBalance { gain_per_s: k_v } = team.law else {
        return None;
    };
    if k_v == 0.0 || team.count() < 3 || !matches!(team.ring, RingMode::Listed) {
        return None;
    }
    let matters = start_matters(team)?;
    let not_checked = |why: String| {
        Some((
            Verdict::NotApplicable,
            format!("range_balance's start is not checked ({matters}; docs/TEAMS.md, the start rule): {why}"),
        ))
    };
    let h = Horizon::of(team, tau_s);
    let trivial = team.nominal_speeds_mps().len() == 1 && team.ranging.delay_s == 0.0;
    let model = StartModel::new(s, l, team, k_v, &h).and_then(|m| h.settles().map(|()| m));
    let (gaps, model) = match model {
        Ok(m) => (m.run(&h), None),
        Err(why) if trivial => match h.settles() {
            Ok(()) => (starts_gaps(team), Some(why)),
            Err(unknown) => return not_checked(unknown),
        },
        Err(why) => {
            return not_checked(format!(
                "the start rule needs its model: {why}; only one nominal speed with no ranging delay may use the starts' distances instead"
            ))
        }
    };
    judge(team, k_v, &h, &gaps, model.as_deref(), &matters)
}

/// The starts' neighbour distances as standing gaps (the start rule's trivial case).
fn starts_gaps(team: &TeamSpec) -> Vec<Closest> {
    let n = team.count();
    let at = |i: usize| Vec2::new(team.starts[i].x_m, team.starts[i].y_m);
    (0..n)
        .map(|i| Closest::standing(i, (at((i + 1) % n) - at(i)).norm()))
        .collect()
}

/// [`start_claim`]'s verdict on the least gaps `gaps` (`no_model`: why the model was not run,
/// the starts' distances standing in).
fn judge(
    team: &TeamSpec,
    k_v: f64,
    h: &Horizon,
    gaps: &[Closest],
    no_model: Option<&str>,
    matters: &str,
) -> Option<(Verdict, String)> {
    let n = team.count();
    let ranges = 2.0 * n as f64 * h.periods();
    let k = loss_run(team.ranging.dropout_probability, ranges);
    let crossing = gaps
        .iter()
        .filter_map(|c| c.crossing_s.map(|at| (c, at)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((c, at)) = crossing {
        return Some((
            Verdict::Fails,
            format!(
                "range_balance's start ({matters}): {}; they pass through each other at t = {} s, so the listed ring is no longer the order of travel and range_balance drives neighbours together; {START_ADVICE}",
                course_text(team, h, c, no_model),
                Num(at)
            ),
        ));
    }
    let (c, m) = gaps
        .iter()
        .map(|c| (c, Margin::of(team, k_v, h, k, c.i)))
        .min_by(|a, b| (a.0.least_m - a.1.total_m()).total_cmp(&(b.0.least_m - b.1.total_m())))?;
    if c.least_m - m.total_m() >= CLOSE_APPROACH_M {
        return None;
    }
    Some((
        Verdict::NotApplicable,
        format!(
            "range_balance's start ({matters}): {}; {}, which leaves {} m, under the run's close-approach distance {} m: two robots may meet before the loop settles; {START_ADVICE}",
            course_text(team, h, c, no_model),
            margin_text(team, h, c.i, &m, k, ranges),
            Num(c.least_m - m.total_m()),
            Num(CLOSE_APPROACH_M)
        ),
    ))
}

/// What the start rule's reasons advise.
const START_ADVICE: &str = "deploy the vehicles further apart (the faster further behind the slower), shorten team.ranging.delay_s, range more often or lose fewer ranges, or give the vehicles one nominal speed";

/// How pair `c`'s gap goes in the model (or stands, `no_model`), to its least.
fn course_text(team: &TeamSpec, h: &Horizon, c: &Closest, no_model: Option<&str>) -> String {
    let (i, j) = (c.i, (c.i + 1) % team.count());
    if let Some(why) = no_model {
        return format!(
            "with one nominal speed and no ranging delay the gaps stand until the first commands act at t = 0 (the model is not run: {why}): vehicle {i} and vehicle {j} ahead of it start {} m apart, the least gap is {} m at t = 0 s",
            Num(c.deployed_m),
            Num(c.least_m)
        );
    }
    format!(
        "the first ranges, measured at t = 0, arrive at t = d = {} s, so until then every vehicle flies its own v0, and until the ranges measured at T = {} s arrive (t = d + T = {} s) each holds the command of the first: vehicle {i} (v0 = {} m/s) and vehicle {j} ahead of it (v0 = {} m/s) go from a deployed gap of {} m to {} m at t = d and {} m at t = d + T; stepping on (the ranges measured every T applied d later, saturated, on the flown circle, {}), the least gap is {} m at t = {} s",
        Num(h.delay_s),
        Num(h.period_s),
        Num(h.delay_s + h.period_s),
        Echo(team.speeds(i).nominal_mps),
        Echo(team.speeds(j).nominal_mps),
        Num(c.deployed_m),
        Num(c.at_delay_m),
        Num(c.at_period_m),
        h.text(),
        Num(c.least_m),
        Num(c.least_s)
    )
}

/// Pair `i`'s margin `m`, each part with its numbers (`k` losses in a row among `ranges`).
fn margin_text(team: &TeamSpec, h: &Horizon, i: usize, m: &Margin, k: f64, ranges: f64) -> String {
    let j = (i + 1) % team.count();
    let r = &team.ranging;
    let loss = if k > 0.0 {
        format!(
            "at team.ranging.dropout_probability p = {} a run of k = {} losses in a row, the shortest whose chance among the horizon's M = 2 N ceil(end/T) = {} ranges is small (M p^k = {} <= {LOSS_RUN_CHANCE}), keeps a wrong command (stale, none yet, or read as max_range_m) for k T = {} s",
            Echo(r.dropout_probability),
            Num(k),
            Num(ranges),
            Num(ranges * r.dropout_probability.powf(k)),
            Num(k * h.period_s)
        )
    } else {
        "no range is lost".to_string()
    };
    format!(
        "what the model does not carry takes a margin of {} m off it: lost ranges {} m ({loss}, closing at most w = v_max_{i} - v_min_{j} = {} m/s) and ranging noise {} m (team.ranging.noise_std_m sigma = {}: the commands carry k_v (n_ahead - n_behind), so the pair's closing rate errs by up to min(w, 3 x 2 k_v sigma) = {} m/s for the ceil(d/T) + 1 = {} periods in flight)",
        Num(m.total_m()),
        Num(m.loss_m),
        Num(m.closing_mps),
        Num(m.noise_m),
        Echo(r.noise_std_m),
        Num(m.noise_mps),
        Num(h.in_flight())
    )
}

/// The not-modelled line on `team.ranging.dropout_probability` (`None` without losses): what a
/// lost range does at the ranging period (`isotrack_sim::team::spacing::HeldRange`): within
/// [`RANGE_HOLD_S`] of the last valid range it is held; past it it reads `max_range_m`, or,
/// without a range limit, the last valid range is held for ever; a lost first range reads
/// `max_range_m`, or leaves the vehicle on its `v0`. The start rule's margin carries them.
pub(super) fn dropout_note(team: &TeamSpec) -> Option<String> {
    let r = &team.ranging;
    if r.dropout_probability <= 0.0 {
        return None;
    }
    let t = 1.0 / r.rate_hz;
    let what = if t <= RANGE_HOLD_S {
        "a lost range is held up to 1 s: an extra, random delay".to_string()
    } else if r.max_range_m.is_finite() {
        format!(
            "ranging every {} s, past the 1 s a lost range is held: each lost range is read as team.ranging.max_range_m = {}, a kick towards a speed bound for a period",
            Num(t),
            Echo(r.max_range_m)
        )
    } else {
        format!(
            "ranging every {} s, past the 1 s a lost range is held, but with no team.ranging.max_range_m the last valid range is held for ever: each loss one more period of delay; a lost first range leaves the vehicle on its v0",
            Num(t)
        )
    };
    Some(format!(
        "team.ranging.dropout_probability = {} ({what})",
        Echo(r.dropout_probability)
    ))
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
