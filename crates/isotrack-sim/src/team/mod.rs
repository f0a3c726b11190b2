//! Teams: `N` vehicles on one clock and one field, each with its own sensor, controller, metrics
//! and ranging unit, spreading out along one isoline by a spacing law (docs/TEAMS.md).
//!
//! A team step `k` (time `t_k`) is the crate's step for every vehicle, through the one step
//! kernel (`kernel::VehicleRun`, as [`Episode`](crate::Episode) and the batched lanes drive it):
//! 1. every vehicle's position, and the field there, [`LANES`](crate::LANES) at a time;
//! 2. each vehicle's kernel `sense` (its sensor's sample, if any); the controllers answer the
//!    samples (in lanes, like a batch);
//! 3. each vehicle's ranging unit measures its two ring neighbours (on its ranging steps) and
//!    delivers what arrives now; the spacing law answers from that alone (or, for the
//!    `arc_reference` law, from the true arc gaps) with a speed command, held until its next
//!    answer;
//! 4. each vehicle's kernel `complete` (metrics, trace, the end), then the team metrics;
//! 5. each vehicle that goes on holds its speed command (saturated to the envelope) and moves,
//!    `LANES` at a time.
//!
//! Every vehicle's numbers depend only on its own streams (sensor, ranging) and on the
//! positions of step `k`: a run is the same bit for bit however it is scheduled. One vehicle
//! with the `none` law and ideal ranging moves as `simulate` moves it.

pub mod arc;
pub mod metrics;
pub mod ranging;
pub mod spacing;

use crate::batch::LANES;
use crate::kernel::{ask, Sensed, VehicleRun};
use crate::run::{Oracles, Outcome, RunResult, StepPlan};
use crate::sensor::Sensor;
use crate::trace::TraceSink;
use arc::{wrap_arc, ArcProjection};
use isotrack_core::{IsolineController, Measurement, ScalarField, SpeedCommand, Vec2};
use metrics::{TeamMetrics, TeamMetricsConfig, TeamSummary};
use ranging::{RangeSample, Ranging, RangingConfig, RangingError};
use spacing::{
    balance_speed, pick_neighbours, DiscoveryConfig, HeldRange, RateFit, RingMode, SpacingConfig,
    SpacingLaw,
};

/// One member of a team: where it starts, what steers it, what it senses, and the seed of its
/// ranging unit.
pub struct TeamMember<X, C> {
    /// Initial vehicle state (its speed is set to the nominal speed at the start).
    pub x0: X,
    /// Its tracking controller.
    pub controller: C,
    /// Its sensor (its own seeded streams).
    pub sensor: Sensor,
    /// Seed of its ranging unit's streams.
    pub ranging_seed: u64,
}

/// A team's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TeamConfig {
    /// Neighbour ranging.
    pub ranging: RangingConfig,
    /// The spacing law, the nominal speed and the ring.
    pub spacing: SpacingConfig,
    /// The team metrics (computed when an isoline to project on is given).
    pub metrics: TeamMetricsConfig,
}

/// Why a team cannot run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TeamError {
    /// No members.
    #[error("a team needs at least one vehicle")]
    Empty,
    /// Trace sinks not one per vehicle.
    #[error("{sinks} trace sinks for {vehicles} vehicles")]
    Sinks {
        /// Sinks given.
        sinks: usize,
        /// Vehicles.
        vehicles: usize,
    },
    /// The ranging settings.
    #[error(transparent)]
    Ranging(#[from] RangingError),
    /// `arc_reference` needs the true isoline.
    #[error(
        "team.spacing = \"arc_reference\" needs the true isoline (a closed isoline to project on)"
    )]
    NoIsoline,
    /// A setting out of range.
    #[error("team.{key} = {value} is out of range: {expected}")]
    OutOfRange {
        /// The key.
        key: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
}

/// What a team run produced.
#[derive(Clone, Debug, PartialEq)]
pub struct TeamResult {
    /// Each vehicle's run, in the listed order.
    pub runs: Vec<RunResult>,
    /// The team metrics (with an isoline to project on).
    pub team: Option<TeamSummary>,
    /// Each vehicle's `[ahead, behind]` neighbours as used at the end (`None` before a ring was
    /// found).
    pub ring: Vec<Option<[u32; 2]>>,
}

/// The probe of ring discovery in progress.
struct Discovery {
    cfg: DiscoveryConfig,
    settle_steps: u64,
    probe_steps: u64,
    fits: Vec<RateFit>,
    found: Vec<Option<[u32; 2]>>,
}

/// The true isoline a team projects on: lent by the caller ([`Group::new`]) or owned by the
/// team ([`Group::new_owning_arc`], for a team held across calls, e.g. by an environment).
enum ArcRef<'a> {
    Lent(&'a dyn ArcProjection),
    Owned(Box<dyn ArcProjection + Send + 'a>),
}

/// The projection behind an [`ArcRef`].
#[inline(always)]
fn arc_of<'b>(a: &'b Option<ArcRef<'_>>) -> Option<&'b dyn ArcProjection> {
    match a {
        Some(ArcRef::Lent(a)) => Some(*a),
        Some(ArcRef::Owned(a)) => Some(&**a),
        None => None,
    }
}

/// A team on one clock: the vehicles' states (in chunks of [`LANES`]), their runs in the step
/// kernel, controllers, ranging units and spacing state. The field, the vehicle model, the
/// oracles and the trace sinks are lent to each step, as for an [`Episode`](crate::Episode).
pub struct Group<'a, X, C> {
    n: usize,
    k: u64,
    /// Vehicles whose run goes on.
    running: usize,
    plan: StepPlan,
    cfg: TeamConfig,
    states: Vec<[X; LANES]>,
    runs: Vec<VehicleRun<true>>,
    controllers: Vec<C>,
    wants_truth: Vec<bool>,
    ranging: Vec<Ranging>,
    ring: Vec<Option<[u32; 2]>>,
    held: Vec<[HeldRange; 2]>,
    speed_cmd: Vec<f64>,
    discovery: Option<Discovery>,
    arc: Option<ArcRef<'a>>,
    metrics: Option<TeamMetrics>,
    /// The latest range sample each vehicle's ranging unit delivered (for an agent outside the
    /// loop; `None` before the first).
    delivered: Vec<Option<RangeSample>>,
    /// Speeds commanded from outside the loop, held ([`Group::hold_speed`]; `None`: every
    /// vehicle flies its spacing law's command).
    speed_override: Option<Vec<f64>>,
    /// The measurement each vehicle's sensor delivered at its last sample (this step's when
    /// `command` is `Some`).
    measured: Vec<Measurement>,
    // Per-step scratch.
    positions: Vec<Vec2>,
    values: Vec<f64>,
    alive: Vec<bool>,
    speeds: Vec<f64>,
    command: Vec<Option<f64>>,
    omega: Vec<f64>,
}

impl<'a, X: Clone, C: IsolineController> Group<'a, X, C> {
    /// A team of `members` with `vehicle`'s model, at step 0. `arc`: the true isoline, for the
    /// team metrics and the `arc_reference` law (ground truth; never for a coordinate-free law).
    pub fn new<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: TeamConfig,
        members: Vec<TeamMember<X, C>>,
        arc: Option<&'a dyn ArcProjection>,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        Self::with_arc(vehicle, plan, cfg, members, arc.map(ArcRef::Lent))
    }

    /// [`Group::new`] with the true isoline owned by the team (for a team held across calls,
    /// e.g. by an environment stepped from outside).
    pub fn new_owning_arc<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: TeamConfig,
        members: Vec<TeamMember<X, C>>,
        arc: Option<Box<dyn ArcProjection + Send + 'a>>,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        Self::with_arc(vehicle, plan, cfg, members, arc.map(ArcRef::Owned))
    }

    fn with_arc<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: TeamConfig,
        members: Vec<TeamMember<X, C>>,
        arc: Option<ArcRef<'a>>,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        let n = members.len();
        let Some(first) = members.first() else {
            return Err(TeamError::Empty);
        };
        let v0 = cfg.spacing.nominal_speed_mps;
        if !(v0 > 0.0 && v0.is_finite()) {
            return Err(TeamError::OutOfRange {
                key: "nominal_speed_mps",
                value: v0,
                expected: "a positive finite speed",
            });
        }
        match cfg.spacing.law {
            SpacingLaw::RangeBalance { gain_per_s } | SpacingLaw::ArcReference { gain_per_s }
                if !(gain_per_s >= 0.0 && gain_per_s.is_finite()) =>
            {
                return Err(TeamError::OutOfRange {
                    key: "spacing_gain_per_s",
                    value: gain_per_s,
                    expected: "finite and >= 0",
                });
            }
            SpacingLaw::ArcReference { .. } if arc.is_none() => return Err(TeamError::NoIsoline),
            _ => {}
        }
        let discovery = match cfg.spacing.ring {
            RingMode::Listed => None,
            RingMode::Discover(d) => {
                let ok = |x: f64| x.is_finite() && x >= 0.0;
                let valid = ok(d.settle_s)
                    && d.probe_s > 0.0
                    && ok(d.probe_s)
                    && d.probe_speed_delta_mps.is_finite()
                    && d.probe_speed_delta_mps != 0.0;
                if !valid {
                    return Err(TeamError::OutOfRange {
                        key: "ring.discover",
                        value: d.probe_s,
                        expected: "settle_s >= 0, probe_s > 0, a non-zero finite probe speed",
                    });
                }
                Some(Discovery {
                    cfg: d,
                    settle_steps: (d.settle_s / plan.dt_s).round() as u64,
                    probe_steps: ((d.probe_s / plan.dt_s).round() as u64).max(1),
                    fits: vec![RateFit::default(); n],
                    found: vec![None; n],
                })
            }
        };
        let ring = match discovery {
            Some(_) => vec![None; n],
            None => (0..n)
                .map(|i| (n > 1).then(|| [((i + 1) % n) as u32, ((i + n - 1) % n) as u32]))
                .collect(),
        };
        let pad = first.x0.clone();
        let chunks = n.div_ceil(LANES);
        let mut states: Vec<[X; LANES]> = (0..chunks)
            .map(|_| core::array::from_fn(|_| pad.clone()))
            .collect();
        let mut runs = Vec::with_capacity(n);
        let mut controllers = Vec::with_capacity(n);
        let mut wants_truth = Vec::with_capacity(n);
        let mut ranging = Vec::with_capacity(n);
        let mut speed_cmd = Vec::with_capacity(n);
        for (i, m) in members.into_iter().enumerate() {
            let mut x = m.x0;
            speed_cmd.push(vehicle.command_speed(&mut x, v0));
            runs.push(VehicleRun::new(plan, m.sensor, vehicle.pose(&x)));
            wants_truth.push(m.controller.needs_ground_truth());
            controllers.push(m.controller);
            ranging.push(Ranging::new(cfg.ranging, plan.dt_s, m.ranging_seed)?);
            states[i / LANES][i % LANES] = x;
        }
        let metrics = arc_of(&arc).map(|a| {
            let mc = TeamMetricsConfig {
                steady_state_start_step: plan.steady_state_start_step,
                ..cfg.metrics
            };
            TeamMetrics::new(mc, n, a.length_m(), plan.dt_s, v0)
        });
        Ok(Self {
            n,
            k: 0,
            running: n,
            plan: *plan,
            cfg,
            states,
            runs,
            controllers,
            wants_truth,
            ranging,
            ring,
            held: vec![[HeldRange::default(); 2]; n],
            speed_cmd,
            discovery,
            arc,
            metrics,
            delivered: vec![None; n],
            speed_override: None,
            measured: vec![
                Measurement {
                    t_s: 0.0,
                    value: 0.0
                };
                n
            ],
            positions: vec![Vec2::new(0.0, 0.0); n],
            values: vec![0.0; n],
            alive: vec![false; n],
            speeds: vec![0.0; n],
            command: vec![None; n],
            omega: vec![0.0; n],
        })
    }

    /// Vehicle `i`'s state.
    pub fn state(&self, i: usize) -> &X {
        &self.states[i / LANES][i % LANES]
    }

    /// Each vehicle's `[ahead, behind]` neighbours (`None` while the ring is being found).
    pub fn ring(&self) -> &[Option<[u32; 2]>] {
        &self.ring
    }

    /// Whether any vehicle's run goes on.
    pub fn is_running(&self) -> bool {
        self.running > 0
    }

    /// Number of vehicles.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the team has no vehicle (never: [`Group::new`] refuses an empty team).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The step the next [`advance`](Self::advance) completes (after [`sense`](Self::sense)),
    /// or the next [`sense`](Self::sense) begins.
    pub fn step_index(&self) -> u64 {
        self.k
    }

    /// The plan.
    pub fn plan(&self) -> &StepPlan {
        &self.plan
    }

    /// Whether vehicle `i`'s run goes on.
    pub fn is_vehicle_running(&self, i: usize) -> bool {
        self.runs[i].is_running()
    }

    /// How vehicle `i`'s run ended, once it has.
    pub fn outcome(&self, i: usize) -> Option<Outcome> {
        self.runs[i].outcome()
    }

    /// Between [`sense`](Self::sense) and [`advance`](Self::advance): vehicle `i`'s sample of
    /// this step and its tracking controller's answer, rad/s (`None`: no sample this step, its
    /// command held).
    pub fn sampled(&self, i: usize) -> Option<(Measurement, f64)> {
        self.command[i].map(|w| (self.measured[i], w))
    }

    /// Between [`sense`](Self::sense) and [`advance`](Self::advance): replaces vehicle `i`'s
    /// answer to this step's sample by `omega_radps` (an agent outside the loop steering it;
    /// a non-finite one ends its run as `diverged`, as a controller's would). Returns whether
    /// it had a sample (without one its command is held, and nothing is replaced).
    pub fn replace_answer(&mut self, i: usize, omega_radps: f64) -> bool {
        match &mut self.command[i] {
            Some(w) => {
                *w = omega_radps;
                true
            }
            None => false,
        }
    }

    /// Vehicle `i`'s speed command from its spacing law (held since its last answer), m/s,
    /// before the envelope's saturation.
    pub fn law_speed_mps(&self, i: usize) -> f64 {
        self.speed_cmd[i]
    }

    /// Commands vehicle `i`'s speed from outside the loop, m/s, held from this step on in
    /// place of its spacing law's (saturated to the vehicle's envelope as the law's is). Once
    /// one vehicle's speed is held, every vehicle's is (the others' at their law's command of
    /// this moment until set).
    pub fn hold_speed(&mut self, i: usize, speed_mps: f64) {
        let o = self
            .speed_override
            .get_or_insert_with(|| self.speed_cmd.clone());
        o[i] = speed_mps;
    }

    /// The latest range sample vehicle `i`'s ranging unit delivered (`None` before the first).
    pub fn delivered_ranges(&self, i: usize) -> Option<RangeSample> {
        self.delivered[i]
    }

    /// Vehicle `i`'s `[ahead, behind]` neighbours (`None` while the ring is being found).
    pub fn neighbours(&self, i: usize) -> Option<[u32; 2]> {
        self.ring[i]
    }

    /// Vehicle `i`'s position and the true field value there at the last step sensed
    /// (ground truth: for rewards and logs, never an observation).
    pub fn sensed_truth(&self, i: usize) -> (Vec2, f64) {
        (self.positions[i], self.values[i])
    }

    /// The ranging unit's steps per sample and its delay in steps (the same for every vehicle).
    pub fn ranging_steps(&self) -> (u64, u64) {
        let r = &self.ranging[0];
        (r.steps_per_sample(), r.delay_steps())
    }

    /// Runs every step to the end (the loop compiled for AVX-512, AVX2 and the baseline, one
    /// picked at run time, as the batched loop is: the same numbers on each).
    pub fn drive<F, V, S>(&mut self, field: &F, vehicle: &V, oracles: &Oracles<'_>, sinks: &mut [S])
    where
        F: ScalarField,
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        drive_lanes(self, field, vehicle, oracles, sinks);
    }

    /// One team step (module docs). `sinks` has one trace sink per vehicle (fewer: the rest
    /// record nothing).
    pub fn step<F, V, S>(&mut self, field: &F, vehicle: &V, oracles: &Oracles<'_>, sinks: &mut [S])
    where
        F: ScalarField,
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        self.step_inline(field, vehicle, oracles, sinks);
    }

    #[inline(always)]
    fn step_inline<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sinks: &mut [S],
    ) where
        F: ScalarField,
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        self.sense_inline(field, vehicle, oracles, sinks);
        self.advance_inline(vehicle, oracles, sinks);
    }

    /// The first half of the next team step (module docs, 1-3): the positions, the samples
    /// and the tracking controllers' answers, the ranging and the spacing law. The step then
    /// waits for [`advance`](Self::advance); in between, an agent outside the loop may read
    /// each vehicle's sample ([`sampled`](Self::sampled)) and replace its answer
    /// ([`replace_answer`](Self::replace_answer)) and speed ([`hold_speed`](Self::hold_speed)).
    /// `sense` then `advance` is [`step`](Self::step), bit for bit.
    pub fn sense<F, V, S>(&mut self, field: &F, vehicle: &V, oracles: &Oracles<'_>, sinks: &mut [S])
    where
        F: ScalarField,
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        self.sense_inline(field, vehicle, oracles, sinks);
    }

    /// The second half of the step [`sense`](Self::sense) began (module docs, 4-5): each
    /// vehicle's metrics and trace, the team metrics, the move.
    pub fn advance<V, S>(&mut self, vehicle: &V, oracles: &Oracles<'_>, sinks: &mut [S])
    where
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        self.advance_inline(vehicle, oracles, sinks);
    }

    #[inline(always)]
    fn sense_inline<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sinks: &mut [S],
    ) where
        F: ScalarField,
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        let n = self.n;
        let k = self.k;
        let dt = self.plan.dt_s;
        let t = k as f64 * dt;
        // 1. Positions and the field there, in lanes.
        for (c, chunk) in self.states.iter().enumerate() {
            let mut px = [0.0; LANES];
            let mut py = [0.0; LANES];
            for (l, s) in chunk.iter().enumerate() {
                let p = vehicle.position(s);
                (px[l], py[l]) = (p.x, p.y);
            }
            let v = field.value_lanes(t, &px, &py);
            for l in 0..LANES.min(n - c * LANES) {
                let i = c * LANES + l;
                self.positions[i] = Vec2::new(px[l], py[l]);
                self.values[i] = v[l];
            }
        }
        // 2. Sense; the controllers answer.
        let mut no_sink = crate::trace::NoTrace;
        for c in 0..self.states.len() {
            let mut sampled = [false; LANES];
            let mut ms = [Measurement {
                t_s: 0.0,
                value: 0.0,
            }; LANES];
            for l in 0..LANES.min(n - c * LANES) {
                let i = c * LANES + l;
                self.command[i] = None;
                self.alive[i] = false;
                if !self.runs[i].is_running() {
                    continue;
                }
                let value = self.values[i];
                let state = &self.states[c][l];
                let sensed = match sinks.get_mut(i) {
                    Some(s) => self.runs[i].sense(vehicle, state, k, t, |_| value, s),
                    None => self.runs[i].sense(vehicle, state, k, t, |_| value, &mut no_sink),
                };
                match sensed {
                    Sensed::Ended => continue,
                    Sensed::Held => {}
                    Sensed::Sampled(m) if self.wants_truth[i] => {
                        self.measured[i] = m;
                        let sample = self.runs[i].sample(m, vehicle.speed_mps(state));
                        self.command[i] = Some(ask(
                            &mut self.controllers[i],
                            true,
                            &sample,
                            oracles.gradient,
                        ));
                    }
                    Sensed::Sampled(m) => {
                        self.measured[i] = m;
                        ms[l] = m;
                        sampled[l] = true;
                    }
                }
                self.alive[i] = true;
            }
            if sampled.iter().any(|&s| s) {
                let base = c * LANES;
                let end = (base + LANES).min(n);
                let mut ctrls: [Option<&mut C>; LANES] = [const { None }; LANES];
                for (l, ctrl) in self.controllers[base..end].iter_mut().enumerate() {
                    if sampled[l] {
                        ctrls[l] = Some(ctrl);
                    }
                }
                let w = C::update_lanes(&mut ctrls, &ms);
                for l in 0..LANES {
                    if sampled[l] {
                        self.command[base + l] = Some(w[l]);
                    }
                }
            }
        }
        // 3. Ranging and the spacing law.
        self.space(k, t, vehicle);
    }

    #[inline(always)]
    fn advance_inline<V, S>(&mut self, vehicle: &V, oracles: &Oracles<'_>, sinks: &mut [S])
    where
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        let n = self.n;
        let k = self.k;
        let dt = self.plan.dt_s;
        let t = k as f64 * dt;
        let mut no_sink = crate::trace::NoTrace;
        // 4. Complete each vehicle's step; the team metrics.
        for i in 0..n {
            if !self.alive[i] {
                continue;
            }
            let state = &self.states[i / LANES][i % LANES];
            let goes_on = match sinks.get_mut(i) {
                Some(s) => self.runs[i].complete(self.command[i], k, t, vehicle, state, oracles, s),
                None => self.runs[i].complete(
                    self.command[i],
                    k,
                    t,
                    vehicle,
                    state,
                    oracles,
                    &mut no_sink,
                ),
            };
            // A vehicle that does not go on (completed, or ended at its command) sensed this
            // step: its position counts for the team metrics below, but it does not move.
            let _ = goes_on;
            self.omega[i] = self.runs[i].omega_radps();
            self.speeds[i] = vehicle.speed_mps(state);
        }
        if let (Some(m), Some(a)) = (self.metrics.as_mut(), arc_of(&self.arc)) {
            if m.due() {
                m.observe(k, a, &self.positions, &self.speeds, &self.alive);
            }
        }
        // 5. Hold the speed commands and move, in lanes.
        let mut running = 0;
        for (c, chunk) in self.states.iter_mut().enumerate() {
            let mut w = [0.0; LANES];
            for l in 0..LANES.min(n - c * LANES) {
                let i = c * LANES + l;
                if self.runs[i].is_running() {
                    let v = match &self.speed_override {
                        None => self.speed_cmd[i],
                        Some(o) => o[i],
                    };
                    vehicle.command_speed(&mut chunk[l], v);
                    running += 1;
                }
                w[l] = self.omega[i];
            }
            vehicle.step_lanes(chunk, &w, dt);
        }
        self.running = running;
        self.k += 1;
    }

    /// Step 3: the ranging units and the spacing law (or the ring discovery) set `speed_cmd`.
    fn space<V: SpeedCommand<State = X>>(&mut self, k: u64, t: f64, vehicle: &V) {
        let n = self.n;
        let v0 = self.cfg.spacing.nominal_speed_mps;
        if let Some(d) = self.discovery.as_mut() {
            let (pos, alive) = (&self.positions, &self.alive);
            if Self::discover(
                d,
                k,
                self.plan.dt_s,
                v0,
                pos,
                alive,
                &mut self.ranging,
                &mut self.speed_cmd,
            ) {
                self.ring = core::mem::take(&mut d.found);
                self.discovery = None;
            }
            return;
        }
        let max_range = self.cfg.ranging.max_range_m;
        for i in 0..n {
            if !self.alive[i] {
                continue;
            }
            let Some([a, b]) = self.ring[i] else {
                continue;
            };
            let (a, b) = (a as usize, b as usize);
            match self.cfg.spacing.law {
                SpacingLaw::None => {
                    // The ranging unit still runs (its streams as with any law).
                    let pa = self.alive[a].then(|| self.positions[a]);
                    let pb = self.alive[b].then(|| self.positions[b]);
                    if let Some(r) = self.ranging[i].observe(k, t, self.positions[i], pa, pb) {
                        self.delivered[i] = Some(r);
                    }
                    self.speed_cmd[i] = v0;
                }
                SpacingLaw::RangeBalance { gain_per_s } => {
                    let pa = self.alive[a].then(|| self.positions[a]);
                    let pb = self.alive[b].then(|| self.positions[b]);
                    if let Some(r) = self.ranging[i].observe(k, t, self.positions[i], pa, pb) {
                        self.delivered[i] = Some(r);
                        let ra = self.held[i][0].update(r.ahead, r.t_s, max_range);
                        let rb = self.held[i][1].update(r.behind, r.t_s, max_range);
                        if let (Some(ra), Some(rb)) = (ra, rb) {
                            self.speed_cmd[i] = balance_speed(v0, gain_per_s, ra, rb);
                        }
                    }
                }
                SpacingLaw::ArcReference { gain_per_s } => {
                    // The true arc gaps on the ranging unit's schedule, without its noise,
                    // losses or delay.
                    let now = self.ranging[i].measures_now();
                    self.ranging[i].observe(k, t, self.positions[i], None, None);
                    if !now {
                        continue;
                    }
                    let Some(arc) = arc_of(&self.arc) else {
                        continue;
                    };
                    let l = arc.length_m();
                    let me = arc.project(self.positions[i]);
                    let pa = arc.project(self.positions[a]);
                    let pb = arc.project(self.positions[b]);
                    if let (Some(me), Some(pa), Some(pb)) = (me, pa, pb) {
                        let heading = vehicle.pose(self.state(i)).heading_rad;
                        let dir = if me.tangent.dot(Vec2::from_angle(heading)) >= 0.0 {
                            1.0
                        } else {
                            -1.0
                        };
                        let ga = wrap_arc(dir * (pa.s_m - me.s_m), l);
                        let gb = wrap_arc(dir * (me.s_m - pb.s_m), l);
                        self.speed_cmd[i] = balance_speed(v0, gain_per_s, ga, gb);
                    }
                }
            }
        }
    }

    /// Ring discovery at step `k`: all at `v0` until `settle_s`, then vehicle `p` probes in its
    /// slot, ranging to every vehicle that answers on its ranging steps (its own ranging unit:
    /// noise, range limit and losses; the range's time stamp is its measurement time, so the
    /// delivery delay does not bias the rate); at the slot's end it picks its neighbours. Returns
    /// whether the ring is complete (after the last slot). Costs `O(N)` per probe sample, `O(N^2)`
    /// over the discovery: for small teams (a large ring is fixed at deployment).
    #[allow(clippy::too_many_arguments)]
    fn discover(
        d: &mut Discovery,
        k: u64,
        dt: f64,
        v0: f64,
        positions: &[Vec2],
        alive: &[bool],
        ranging: &mut [Ranging],
        speed_cmd: &mut [f64],
    ) -> bool {
        let n = positions.len();
        speed_cmd.iter_mut().for_each(|s| *s = v0);
        let probe = (k >= d.settle_steps).then(|| {
            let since = k - d.settle_steps;
            (since / d.probe_steps, since % d.probe_steps)
        });
        // The prober ranges on its own ranging steps; every unit's schedule keeps running.
        let prober = probe.and_then(|(slot, _)| (slot < n as u64).then_some(slot as usize));
        let measuring = prober.is_some_and(|p| ranging[p].measures_now());
        for (i, r) in ranging.iter_mut().enumerate() {
            if alive[i] {
                r.tick();
            }
        }
        let Some((slot, in_slot)) = probe else {
            return false;
        };
        let Some(p) = prober else {
            return true;
        };
        if in_slot == 0 {
            d.fits.iter_mut().for_each(|f| *f = RateFit::default());
        }
        let dv = d.cfg.probe_speed_delta_mps;
        if alive[p] {
            speed_cmd[p] = v0 + dv;
            if measuring {
                let t_rel = in_slot as f64 * dt;
                for j in 0..n {
                    if j == p {
                        continue;
                    }
                    let truth = alive[j].then(|| (positions[j] - positions[p]).norm());
                    let r = ranging[p].measure(truth);
                    if r.valid {
                        d.fits[j].add(t_rel, r.range_m);
                    }
                }
            }
        }
        if in_slot + 1 == d.probe_steps {
            let fits: Vec<(u32, f64, f64)> = (0..n)
                .filter_map(|j| d.fits[j].fit().map(|(m, r)| (j as u32, m, r)))
                .collect();
            let (a, b) = pick_neighbours(&fits, dv.signum());
            d.found[p] = match (a, b) {
                (Some(a), Some(b)) if n > 1 => Some([a, b]),
                _ => None,
            };
            let _ = slot;
            return p + 1 == n;
        }
        false
    }

    /// Ends the team run (runs still going end as they stand) and returns the results.
    pub fn finish<S: TraceSink>(self, sinks: &mut [S]) -> TeamResult {
        let mut no_sink = crate::trace::NoTrace;
        let runs = self
            .runs
            .into_iter()
            .enumerate()
            .map(|(i, r)| match sinks.get_mut(i) {
                Some(s) => r.finish(s),
                None => r.finish(&mut no_sink),
            })
            .collect();
        TeamResult {
            runs,
            team: self.metrics.as_ref().map(|m| m.finish()),
            ring: self.ring,
        }
    }
}

/// [`Group::drive`]'s loop, compiled for each target (the lanes' `sin_cos` and the field's
/// formula vectorise wider with AVX2 / AVX-512; no fused multiply-add, so the same numbers).
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "aarch64+neon"
))]
fn drive_lanes<X, C, F, V, S>(
    g: &mut Group<'_, X, C>,
    field: &F,
    vehicle: &V,
    oracles: &Oracles<'_>,
    sinks: &mut [S],
) where
    X: Clone,
    C: IsolineController,
    F: ScalarField,
    V: SpeedCommand<State = X>,
    S: TraceSink,
{
    while g.is_running() {
        g.step_inline(field, vehicle, oracles, sinks);
    }
}

/// Runs a team to the end: [`Group::new`], [`Group::drive`], [`Group::finish`].
#[allow(clippy::too_many_arguments)]
pub fn simulate_team<F, V, C, S>(
    field: &F,
    vehicle: &V,
    plan: &StepPlan,
    cfg: TeamConfig,
    members: Vec<TeamMember<V::State, C>>,
    arc: Option<&dyn ArcProjection>,
    oracles: &Oracles<'_>,
    sinks: &mut [S],
) -> Result<TeamResult, TeamError>
where
    F: ScalarField,
    V: SpeedCommand,
    C: IsolineController,
    S: TraceSink,
{
    let n = members.len();
    if !sinks.is_empty() && sinks.len() != n {
        return Err(TeamError::Sinks {
            sinks: sinks.len(),
            vehicles: n,
        });
    }
    let mut g = Group::new(vehicle, plan, cfg, members, arc)?;
    g.drive(field, vehicle, oracles, sinks);
    Ok(g.finish(sinks))
}
