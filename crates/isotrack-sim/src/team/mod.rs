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
use crate::trace::{NoTrace, TraceRow, TraceSink};
use arc::{pick_loop, wrap_arc, ArcProjection, MovingArc, PolylineArc};
use isotrack_core::{IsolineController, Measurement, ScalarField, SpeedCommand, Vec2};
use metrics::{TeamMetrics, TeamMetricsConfig, TeamSummary};
use ranging::{RangeSample, Ranging, RangingConfig, RangingError};
use spacing::{
    balance_speed, leave_ring, pick_neighbours, ring_fault, DiscoveryConfig, HeldRange, RateFit,
    RingMode, SpacingConfig, SpacingLaw,
};

/// The [`Slab`] of a whole [`Group`] (`$g`), its trace sinks `$sinks`: each field borrowed on
/// its own, so that the positions, the ring and the rest stay readable beside it.
macro_rules! slab {
    ($g:expr, $sinks:expr) => {
        Slab {
            base: 0,
            n: $g.n,
            states: &mut $g.states,
            runs: &mut $g.runs,
            controllers: &mut $g.controllers,
            wants_truth: &$g.wants_truth,
            ranging: &mut $g.ranging,
            held: &mut $g.held,
            speed_cmd: &mut $g.speed_cmd,
            delivered: &mut $g.delivered,
            measured: &mut $g.measured,
            values: &mut $g.values,
            speeds: &mut $g.speeds,
            command: &mut $g.command,
            omega: &mut $g.omega,
            sinks: $sinks,
        }
    };
}

/// The [`Shared`] view of a [`Group`] (`$g`) at step `$k`, time `$t`.
macro_rules! shared {
    ($g:expr, $k:expr, $t:expr) => {
        Shared {
            k: $k,
            t: $t,
            dt: $g.plan.dt_s,
            positions: &$g.positions,
            alive: &$g.alive,
            ring: &$g.ring,
            spacing: $g.cfg.spacing,
            max_range_m: $g.cfg.ranging.max_range_m,
            arc: arc_of(&$g.arc).or($g
                .moving
                .as_ref()
                .and_then(|c| c.arc.as_ref())
                .map(|a| a as &dyn ArcProjection)),
            speed_override: $g.speed_override.as_deref(),
            member_speeds: $g.member_speeds.as_deref(),
        }
    };
}

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

/// One vehicle's own speeds (`team.vehicles` overrides, docs/TEAMS.md "Per-vehicle
/// overrides"): its nominal speed `v0_i`, which the spacing law commands about
/// (`v0_i + k_v (r_ahead - r_behind)`; the `none` law holds it), and its envelope
/// `[min, max]`, every command saturated to it (inside the vehicle model's own envelope).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemberSpeeds {
    /// Nominal speed `v0_i`, m/s.
    pub nominal_mps: f64,
    /// Slowest command, m/s.
    pub min_mps: f64,
    /// Fastest command, m/s.
    pub max_mps: f64,
}

impl MemberSpeeds {
    /// `speed_mps` saturated to the envelope (a NaN gives `min`, as the vehicle models do).
    #[inline(always)]
    pub fn saturate(&self, speed_mps: f64) -> f64 {
        self.min_mps.max(speed_mps).min(self.max_mps)
    }
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
    /// `arc_reference` needs the true isoline, closed (its ring of arc gaps wraps around).
    #[error(
        "team.spacing = \"arc_reference\" needs the true isoline (a closed isoline to project on)"
    )]
    NoIsoline,
    /// Per-vehicle speeds or envelopes with ring discovery: its probes step one vehicle's
    /// speed while every other flies the team's nominal speed within the team's envelope.
    #[error("team.vehicles: per-vehicle speeds or envelopes with team.ring = \"discovered\": its probes assume every vehicle at the team's nominal speed and envelope (give the vehicles the team's speeds or use team.ring = \"listed\")")]
    SpeedsWithDiscovery,
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
    /// found, and for a vehicle whose run ended other than by completing, even at the last
    /// step: it left the ring, which closed around it).
    pub ring: Vec<Option<[u32; 2]>>,
    /// The engine's warnings about the run (a discovered ring that was not one ring: the
    /// spacing law turned off), for the run's `warnings`.
    pub warnings: Vec<String>,
}

/// The true isoline a team's metrics (and the `arc_reference` law) measure along.
#[derive(Clone, Copy)]
pub enum TeamIsoline<'a> {
    /// One isoline for the whole run (a circle, a polyline extracted once).
    Fixed(&'a dyn ArcProjection),
    /// The isoline of the time, extracted again when its version changes (checked at each
    /// metrics sample): the loop most vehicles are nearest to ([`arc::pick_loop`]), oriented
    /// and started as the last one ([`PolylineArc::aligned`]).
    Moving(&'a dyn MovingArc),
}

/// The true isoline a team owns ([`Group::new_owning_isoline`], for a team held across calls,
/// e.g. by an environment stepped from outside): [`TeamIsoline`] owned.
pub enum OwnedTeamIsoline<'a> {
    /// One isoline for the whole run.
    Fixed(Box<dyn ArcProjection + Send + 'a>),
    /// The isoline of the time.
    Moving(Box<dyn MovingArc + Send + 'a>),
}

/// A moving isoline's source: lent by the caller or owned by the team.
enum MovingRef<'a> {
    Lent(&'a dyn MovingArc),
    Owned(Box<dyn MovingArc + Send + 'a>),
}

impl MovingRef<'_> {
    fn get(&self) -> &dyn MovingArc {
        match self {
            MovingRef::Lent(m) => *m,
            MovingRef::Owned(m) => &**m,
        }
    }
}

/// The moving isoline in force.
struct Current<'a> {
    source: MovingRef<'a>,
    version: Option<i64>,
    arc: Option<PolylineArc>,
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

/// Checks a team's spacing settings: a positive finite nominal speed, a finite gain >= 0,
/// and for the `arc_reference` law a true isoline to refer to (a fixed closed `arc`, or a
/// `moving` one).
fn check_spacing(
    spacing: &SpacingConfig,
    arc: Option<&dyn ArcProjection>,
    moving: bool,
) -> Result<(), TeamError> {
    let v0 = spacing.nominal_speed_mps;
    if !(v0 > 0.0 && v0.is_finite()) {
        return Err(TeamError::OutOfRange {
            key: "nominal_speed_mps",
            value: v0,
            expected: "a positive finite speed",
        });
    }
    match spacing.law {
        SpacingLaw::RangeBalance { gain_per_s } | SpacingLaw::ArcReference { gain_per_s }
            if !(gain_per_s >= 0.0 && gain_per_s.is_finite()) =>
        {
            Err(TeamError::OutOfRange {
                key: "spacing_gain_per_s",
                value: gain_per_s,
                expected: "finite and >= 0",
            })
        }
        SpacingLaw::ArcReference { .. }
            if (arc.is_none() && !moving) || arc.is_some_and(|a| !a.is_closed()) =>
        {
            Err(TeamError::NoIsoline)
        }
        _ => Ok(()),
    }
}

impl Discovery {
    /// The ring discovery of `ring` for `n` vehicles stepped at `plan.dt_s` (`None`: the ring
    /// is listed); an error for a probe out of range.
    fn of(ring: RingMode, plan: &StepPlan, n: usize) -> Result<Option<Self>, TeamError> {
        let RingMode::Discover(d) = ring else {
            return Ok(None);
        };
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
        Ok(Some(Self {
            cfg: d,
            settle_steps: (d.settle_s / plan.dt_s).round() as u64,
            probe_steps: ((d.probe_s / plan.dt_s).round() as u64).max(1),
            fits: vec![RateFit::default(); n],
            found: vec![None; n],
        }))
    }
}

/// The ring a team of `n` starts with: each vehicle's neighbours ahead and behind in the
/// listed order (none for one vehicle), or none yet where the ring is `discovered`.
fn starting_ring(n: usize, discovered: bool) -> Vec<Option<[u32; 2]>> {
    if discovered {
        vec![None; n]
    } else {
        (0..n)
            .map(|i| (n > 1).then(|| [((i + 1) % n) as u32, ((i + n - 1) % n) as u32]))
            .collect()
    }
}

/// Each vehicle's own parts as a team starts, in the members' order: states in chunks of
/// [`LANES`] (the last chunk padded), runs in the step kernel, controllers (and whether each
/// needs the ground truth), ranging units and first speed commands.
struct Started<X, C> {
    states: Vec<[X; LANES]>,
    runs: Vec<VehicleRun<true>>,
    controllers: Vec<C>,
    wants_truth: Vec<bool>,
    ranging: Vec<Ranging>,
    speed_cmd: Vec<f64>,
}

impl<X: Clone, C: IsolineController> Started<X, C> {
    /// Starts `members` on `vehicle` at `plan`, each commanded the nominal speed, the spare
    /// lanes of the last chunk holding `pad`; an error for a ranging unit's settings.
    fn of<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: &TeamConfig,
        members: Vec<TeamMember<X, C>>,
        pad: X,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        let n = members.len();
        let v0 = cfg.spacing.nominal_speed_mps;
        let chunks = n.div_ceil(LANES);
        let mut s = Self {
            states: (0..chunks)
                .map(|_| core::array::from_fn(|_| pad.clone()))
                .collect(),
            runs: Vec::with_capacity(n),
            controllers: Vec::with_capacity(n),
            wants_truth: Vec::with_capacity(n),
            ranging: Vec::with_capacity(n),
            speed_cmd: Vec::with_capacity(n),
        };
        for (i, m) in members.into_iter().enumerate() {
            let mut x = m.x0;
            s.speed_cmd.push(vehicle.command_speed(&mut x, v0));
            s.runs
                .push(VehicleRun::new(plan, m.sensor, vehicle.pose(&x)));
            s.wants_truth.push(m.controller.needs_ground_truth());
            s.controllers.push(m.controller);
            s.ranging
                .push(Ranging::new(cfg.ranging, plan.dt_s, m.ranging_seed)?);
            s.states[i / LANES][i % LANES] = x;
        }
        Ok(s)
    }
}

/// A team's metrics along its true isoline (`arc`, or a `moving` one): `n` vehicles at the
/// nominal speed `v0_mps`, stepped every `dt_s`; `None` without an isoline.
fn team_metrics(
    mc: TeamMetricsConfig,
    arc: Option<&dyn ArcProjection>,
    moving: bool,
    n: usize,
    dt_s: f64,
    v0_mps: f64,
) -> Option<TeamMetrics> {
    let v0 = v0_mps;
    match (arc, moving) {
        (Some(a), _) if !a.is_closed() => {
            // Bins as long as a vehicle at `v0` moves in a metrics sample: an open
            // isoline's length is mostly ground the team never covers.
            let step_m = v0 * mc.every_steps.max(1) as f64 * dt_s;
            let mc = TeamMetricsConfig {
                revisit_bins: metrics::open_revisit_bins(a.length_m(), step_m, mc.revisit_bins),
                ..mc
            };
            Some(TeamMetrics::new(mc, n, a.length_m(), dt_s, v0).open())
        }
        (Some(a), _) => Some(TeamMetrics::new(mc, n, a.length_m(), dt_s, v0)),
        (None, true) => Some(TeamMetrics::new(mc, n, f64::NAN, dt_s, v0).moving()),
        (None, false) => None,
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
    /// Vehicles whose run went on when the ring was last closed around the ended ones
    /// ([`Group::close_ring`]).
    ring_running: usize,
    /// Whether each vehicle has left the ring (its run ended).
    left_ring: Vec<bool>,
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
    moving: Option<Current<'a>>,
    metrics: Option<TeamMetrics>,
    /// The latest range sample each vehicle's ranging unit delivered (for an agent outside the
    /// loop; `None` before the first).
    delivered: Vec<Option<RangeSample>>,
    /// Speeds commanded from outside the loop, held ([`Group::hold_speed`]; `None`: every
    /// vehicle flies its spacing law's command).
    speed_override: Option<Vec<f64>>,
    /// Each vehicle's own nominal speed and envelope ([`Group::set_member_speeds`]; `None`:
    /// every vehicle at `cfg.spacing.nominal_speed_mps` within the vehicle model's envelope).
    member_speeds: Option<Vec<MemberSpeeds>>,
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
    /// The engine's warnings ([`TeamResult::warnings`]).
    warnings: Vec<String>,
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
        Self::with_arc(vehicle, plan, cfg, members, arc.map(ArcRef::Lent), None)
    }

    /// [`new`](Self::new) with an isoline that may move ([`TeamIsoline::Moving`]: the
    /// `arc_reference` law then uses the isoline of the last metrics sample).
    pub fn with_isoline<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: TeamConfig,
        members: Vec<TeamMember<X, C>>,
        isoline: Option<TeamIsoline<'a>>,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        let (arc, moving) = match isoline {
            Some(TeamIsoline::Fixed(a)) => (Some(ArcRef::Lent(a)), None),
            Some(TeamIsoline::Moving(m)) => (None, Some(MovingRef::Lent(m))),
            None => (None, None),
        };
        Self::with_arc(vehicle, plan, cfg, members, arc, moving)
    }

    /// [`with_isoline`](Self::with_isoline) with the true isoline owned by the team (for a
    /// team held across calls, e.g. by an environment stepped from outside: the same metrics
    /// as the run's, on a closed, open or moving isoline).
    pub fn new_owning_isoline<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: TeamConfig,
        members: Vec<TeamMember<X, C>>,
        isoline: Option<OwnedTeamIsoline<'a>>,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        let (arc, moving) = match isoline {
            Some(OwnedTeamIsoline::Fixed(a)) => (Some(ArcRef::Owned(a)), None),
            Some(OwnedTeamIsoline::Moving(m)) => (None, Some(MovingRef::Owned(m))),
            None => (None, None),
        };
        Self::with_arc(vehicle, plan, cfg, members, arc, moving)
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
        Self::with_arc(vehicle, plan, cfg, members, arc.map(ArcRef::Owned), None)
    }

    fn with_arc<V>(
        vehicle: &V,
        plan: &StepPlan,
        cfg: TeamConfig,
        members: Vec<TeamMember<X, C>>,
        arc: Option<ArcRef<'a>>,
        moving: Option<MovingRef<'a>>,
    ) -> Result<Self, TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        let moving = moving.map(|m| Current {
            source: m,
            version: None,
            arc: None,
        });
        let n = members.len();
        let Some(first) = members.first() else {
            return Err(TeamError::Empty);
        };
        let v0 = cfg.spacing.nominal_speed_mps;
        check_spacing(&cfg.spacing, arc_of(&arc), moving.is_some())?;
        let discovery = Discovery::of(cfg.spacing.ring, plan, n)?;
        let ring = starting_ring(n, discovery.is_some());
        let pad = first.x0.clone();
        let Started {
            states,
            runs,
            controllers,
            wants_truth,
            ranging,
            speed_cmd,
        } = Started::of(vehicle, plan, &cfg, members, pad)?;
        let mc = TeamMetricsConfig {
            steady_state_start_step: plan.steady_state_start_step,
            ..cfg.metrics
        };
        let metrics = team_metrics(mc, arc_of(&arc), moving.is_some(), n, plan.dt_s, v0);
        Ok(Self {
            n,
            k: 0,
            running: n,
            ring_running: n,
            left_ring: vec![false; n],
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
            moving,
            metrics,
            delivered: vec![None; n],
            speed_override: None,
            member_speeds: None,
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
            warnings: Vec::new(),
        })
    }

    /// Gives each vehicle its own nominal speed and envelope (per-vehicle overrides), before
    /// the first step: vehicle `i` then starts at `speeds[i].nominal_mps`, its spacing law
    /// commands about it, and every command (the law's, a held one) is saturated to its own
    /// `[min_mps, max_mps]`, which must lie inside the vehicle model's envelope. The ideal
    /// revisit time uses the mean nominal speed ([`TeamMetrics::set_nominal_speed`]). Refused
    /// after the first step, for a length other than the team's, an envelope that does not
    /// hold its nominal speed, and with ring discovery (its probes assume one nominal speed).
    pub fn set_member_speeds<V>(
        &mut self,
        vehicle: &V,
        speeds: Vec<MemberSpeeds>,
    ) -> Result<(), TeamError>
    where
        V: SpeedCommand<State = X>,
    {
        let bad = |key: &'static str, value: f64, expected: &'static str| {
            Err(TeamError::OutOfRange {
                key,
                value,
                expected,
            })
        };
        if self.k != 0 || speeds.len() != self.n {
            return bad(
                "vehicles",
                speeds.len() as f64,
                "one entry per vehicle, set before the first step",
            );
        }
        if self.discovery.is_some() {
            return Err(TeamError::SpeedsWithDiscovery);
        }
        let (lo, hi) = vehicle.speed_envelope_mps();
        for m in &speeds {
            let ok = m.min_mps.is_finite()
                && m.max_mps.is_finite()
                && lo <= m.min_mps
                && m.min_mps <= m.nominal_mps
                && m.nominal_mps <= m.max_mps
                && m.max_mps <= hi;
            if !ok {
                return bad(
                    "vehicles",
                    m.nominal_mps,
                    "min <= nominal <= max, inside the vehicle model's envelope",
                );
            }
        }
        for (i, m) in speeds.iter().enumerate() {
            let x = &mut self.states[i / LANES][i % LANES];
            self.speed_cmd[i] = vehicle.command_speed(x, m.nominal_mps);
        }
        if let Some(metrics) = self.metrics.as_mut() {
            let sum: f64 = speeds.iter().map(|m| m.nominal_mps).sum();
            metrics.set_nominal_speed(sum / self.n as f64);
            let own: Vec<f64> = speeds.iter().map(|m| m.nominal_mps).collect();
            metrics.set_member_speeds(&own);
        }
        self.member_speeds = Some(speeds);
        Ok(())
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

    /// Gives every vehicle's speed back to its spacing law from this step on (undoes
    /// [`hold_speed`](Self::hold_speed)): a run's steps that no outside command can answer
    /// any more are flown as the run's own loop flies them.
    pub fn release_speeds(&mut self) {
        self.speed_override = None;
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

    /// [`drive`](Self::drive) over the threads `threads` allows for the team's size
    /// ([`TeamThreads::parts`]; a rayon pool of its own; one thread if none can be started). Each step, the vehicles are split into
    /// contiguous parts, one per thread; a vehicle reads only the positions of the step
    /// (its neighbours', for ranging) and writes only its own state, so every number, trace
    /// row and metric is the same bit for bit on any number of threads. The trace rows are
    /// written into `sinks` on the caller's thread, in the order one thread records them. Ring
    /// discovery (`O(N)` per probe sample: for small teams) steps on one thread.
    pub fn drive_threads<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sinks: &mut [S],
        threads: TeamThreads,
    ) where
        X: Send,
        C: Send,
        F: ScalarField + Sync,
        V: SpeedCommand<State = X> + Sync,
        S: TraceSink,
    {
        let parts = threads.parts(self.n);
        let pool = if parts > 1 {
            rayon::ThreadPoolBuilder::new()
                .num_threads(parts)
                .build()
                .ok()
        } else {
            None
        };
        let Some(pool) = pool else {
            return self.drive(field, vehicle, oracles, sinks);
        };
        let mut rows: Vec<Vec<TraceRow>> = vec![Vec::new(); sinks.len()];
        let mut log: Vec<(u32, TraceRow)> = Vec::new();
        // Without a trace the whole run is one block; with one, the rows of a block are held
        // (at most `TRACE_BLOCK_ROWS` of them, whatever the duration) until the caller's
        // thread writes them.
        let block = if sinks.is_empty() {
            u64::MAX
        } else {
            (TRACE_BLOCK_ROWS / self.n).max(1) as u64
        };
        while self.is_running() {
            if self.discovery.is_some() {
                self.step_inline(field, vehicle, oracles, sinks);
                continue;
            }
            pool.install(|| {
                par_block(
                    self, field, vehicle, oracles, &mut rows, &mut log, parts, block,
                )
            });
            for (v, row) in log.drain(..) {
                sinks[v as usize].record(&row);
            }
        }
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
        let k = self.k;
        let t = k as f64 * self.plan.dt_s;
        let discovering = self.discovery.is_some();
        {
            // 1-2. Positions, the field there and the samples, in lanes; the controllers answer.
            let mut slab = slab!(self, sinks);
            slab.sense(
                field,
                vehicle,
                oracles,
                k,
                t,
                &mut self.positions,
                &mut self.alive,
            );
            // 3. Ranging and the spacing law.
            if !discovering {
                slab.space(&shared!(self, k, t), vehicle);
            }
        }
        if discovering {
            self.discover_step(k);
        }
    }

    #[inline(always)]
    fn advance_inline<V, S>(&mut self, vehicle: &V, oracles: &Oracles<'_>, sinks: &mut [S])
    where
        V: SpeedCommand<State = X>,
        S: TraceSink,
    {
        let k = self.k;
        let t = k as f64 * self.plan.dt_s;
        // 4. Complete each vehicle's step; the team metrics.
        slab!(self, &mut *sinks).complete(&shared!(self, k, t), vehicle, oracles);
        self.observe_team(k, t);
        // 5. Hold the speed commands and move, in lanes.
        self.running = slab!(self, sinks).advance(&shared!(self, k, t), vehicle);
        self.close_ring();
        self.k += 1;
    }

    /// After a step's move: the ring closes around every vehicle whose run ended at this step
    /// (docs/TEAMS.md "Vehicles that end early"; [`leave_ring`]): its end is announced to its
    /// two neighbours, who range their new neighbours from the next step on. A neighbour whose
    /// neighbour changed forgets the range it held ([`HeldRange`]); one left alone flies its
    /// nominal speed. `O(1)` unless a run ended (then `O(N)` per ended vehicle). At the run's
    /// last step the vehicles that completed stay in the ring (`summary.json`'s
    /// `team.neighbours` is the ring at the end), but a vehicle that ended otherwise at that
    /// same step leaves it (att32f-9: the ring was not closed once no run went on, so such a
    /// vehicle stayed its neighbours' neighbour). During ring discovery no ring exists yet: the
    /// vehicles that ended leave the found ring when it is complete ([`Group::discover_step`]).
    fn close_ring(&mut self) {
        if self.running >= self.ring_running {
            return;
        }
        self.ring_running = self.running;
        if self.discovery.is_some() {
            return;
        }
        for i in 0..self.n {
            if self.left_ring[i]
                || self.runs[i].is_running()
                || self.runs[i].outcome() == Some(Outcome::Completed)
            {
                continue;
            }
            self.left_ring[i] = true;
            for (j, sides) in leave_ring(&mut self.ring, i) {
                for (side, changed) in sides.into_iter().enumerate() {
                    if changed {
                        self.held[j][side] = HeldRange::default();
                    }
                }
                if self.ring[j].is_none() {
                    self.speed_cmd[j] = self
                        .member_speeds
                        .as_ref()
                        .map_or(self.cfg.spacing.nominal_speed_mps, |m| m[j].nominal_mps);
                }
            }
        }
    }

    /// The team metrics of step `k` (time `t`), when due: after every vehicle's step 4, read
    /// from the positions, speeds and liveness of the step.
    fn observe_team(&mut self, k: u64, t: f64) {
        if let Some(m) = self.metrics.as_mut() {
            if m.due() {
                match (arc_of(&self.arc), self.moving.as_mut()) {
                    (Some(a), _) => m.observe(k, a, &self.positions, &self.speeds, &self.alive),
                    (None, Some(cur)) => {
                        if cur.refresh(t, &self.positions, &self.alive) {
                            m.extracted();
                        }
                        match &cur.arc {
                            Some(a) => m.observe(k, a, &self.positions, &self.speeds, &self.alive),
                            None => m.skip(k),
                        }
                    }
                    (None, None) => {}
                }
            }
        }
    }

    /// Step 3 during ring discovery: the probe sets `speed_cmd`; the ring once found.
    fn discover_step(&mut self, k: u64) {
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
                let found = core::mem::take(&mut d.found);
                self.ring = found.clone();
                self.discovery = None;
                // The vehicles whose runs ended during the discovery leave the found ring.
                self.ring_running = self.n;
                self.close_ring();
                self.check_found_ring(k, &found);
            }
        }
    }
    /// The ring just found at step `k` (`found`: the table the probes picked, before closing
    /// around the vehicles that ended during the discovery), checked: one ring through the
    /// vehicles still flying ([`ring_fault`]). A table that is not (lossy or slow ranging:
    /// att32f-5, `[[1,3],[3,3],[3,1],[2,1]]`) would pull vehicles toward each other and orphan
    /// a live one when the ring closes: the spacing law is turned off instead (no vehicle has
    /// neighbours; each flies its nominal speed for the rest of the run), with a warning.
    fn check_found_ring(&mut self, k: u64, found: &[Option<[u32; 2]>]) {
        let live: Vec<bool> = self.left_ring.iter().map(|l| !l).collect();
        let Some(fault) = ring_fault(&self.ring, &live) else {
            return;
        };
        let table: Vec<String> = found
            .iter()
            .map(|r| r.map_or_else(|| "null".to_string(), |[a, b]| format!("[{a},{b}]")))
            .collect();
        self.warnings.push(format!(
            "team.ring = \"discovered\": the neighbours found by the probes (ending at t = {} s) are not one ring through the vehicles flying ({fault}; [ahead, behind] by vehicle: [{}]); the spacing law is off: every vehicle flies its nominal speed for the rest of the run, unspaced (team.neighbours all null). The ranging is too lossy, slow or short for the probes (more rate_hz or max_range_m: each vehicle must range its neighbours at the start; less dropout_probability or delay_s), or list the ring (team.ring = \"listed\")",
            isotrack_core::numtext::Num(k as f64 * self.plan.dt_s),
            table.join(",")
        ));
        for (i, r) in self.ring.iter_mut().enumerate() {
            *r = None;
            self.held[i] = [HeldRange::default(); 2];
            self.speed_cmd[i] = self
                .member_speeds
                .as_ref()
                .map_or(self.cfg.spacing.nominal_speed_mps, |m| m[i].nominal_mps);
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
            warnings: self.warnings,
        }
    }
}

/// The fewest vehicles a thread of a team steps by default ([`TeamThreads::new`]): below
/// twice as many a team steps on one thread. A vehicle-step costs about 60 ns on one thread
/// and a threaded step two hand-overs (rayon joins); on the loaded machine of BENCHMARKS.md's
/// team rows a second thread made no team of 64 to 1000 robots faster, so the bound is
/// conservative: a thread's 256 vehicles are about 15 us of work per step.
pub const MIN_VEHICLES_PER_THREAD: usize = 256;

/// How a team is split over threads ([`Group::drive_threads`]); results do not depend on it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TeamThreads {
    /// The most threads (0 and 1: one).
    pub threads: usize,
    /// The fewest vehicles a thread steps (rounded up to whole [`LANES`] chunks): a team of
    /// fewer than twice as many steps on one thread.
    pub min_vehicles_per_thread: usize,
}

impl TeamThreads {
    /// Up to `threads` threads, each stepping at least [`MIN_VEHICLES_PER_THREAD`] vehicles.
    pub fn new(threads: usize) -> Self {
        Self {
            threads,
            min_vehicles_per_thread: MIN_VEHICLES_PER_THREAD,
        }
    }

    /// The threads a team of `n` vehicles steps on (>= 1).
    pub fn parts(&self, n: usize) -> usize {
        let per = self.min_vehicles_per_thread.div_ceil(LANES).max(1);
        self.threads.min(n.div_ceil(LANES) / per).max(1)
    }
}

/// With traces, a threaded team returns to the caller's thread (which writes the trace rows,
/// in the order one thread records them) after at most this many rows' worth of steps.
const TRACE_BLOCK_ROWS: usize = 1 << 16;

/// What every vehicle of a step reads in steps 3-5 (besides its own state): the positions and
/// liveness of step `k` (its neighbours'), the ring, the settings, the true isoline in force and
/// the held speeds. Written by no one during those steps.
struct Shared<'s> {
    k: u64,
    t: f64,
    dt: f64,
    positions: &'s [Vec2],
    alive: &'s [bool],
    ring: &'s [Option<[u32; 2]>],
    spacing: SpacingConfig,
    max_range_m: f64,
    arc: Option<&'s dyn ArcProjection>,
    speed_override: Option<&'s [f64]>,
    member_speeds: Option<&'s [MemberSpeeds]>,
}

/// A contiguous range of a team's vehicles, whole [`LANES`] chunks (the last one may be
/// partial), from vehicle `base`: its own part of every per-vehicle array, so that each range
/// steps on its own thread. Indices into its arrays are local (`j`; vehicle `base + j`).
struct Slab<'s, X, C, S> {
    base: usize,
    n: usize,
    states: &'s mut [[X; LANES]],
    runs: &'s mut [VehicleRun<true>],
    controllers: &'s mut [C],
    wants_truth: &'s [bool],
    ranging: &'s mut [Ranging],
    held: &'s mut [[HeldRange; 2]],
    speed_cmd: &'s mut [f64],
    delivered: &'s mut [Option<RangeSample>],
    measured: &'s mut [Measurement],
    values: &'s mut [f64],
    speeds: &'s mut [f64],
    command: &'s mut [Option<f64>],
    omega: &'s mut [f64],
    sinks: &'s mut [S],
}

/// Work that splits into two at a [`LANES`] chunk boundary.
trait Split: Sized + Send {
    /// Its chunks.
    fn chunks(&self) -> usize;
    /// The first `chunks` chunks and the rest.
    fn split(self, chunks: usize) -> (Self, Self);
}

impl<X: Send, C: Send, S: Send> Split for Slab<'_, X, C, S> {
    fn chunks(&self) -> usize {
        self.states.len()
    }

    fn split(self, chunks: usize) -> (Self, Self) {
        let mid = (chunks * LANES).min(self.n);
        let (st0, st1) = self.states.split_at_mut(chunks);
        let (ru0, ru1) = self.runs.split_at_mut(mid);
        let (co0, co1) = self.controllers.split_at_mut(mid);
        let (wt0, wt1) = self.wants_truth.split_at(mid);
        let (ra0, ra1) = self.ranging.split_at_mut(mid);
        let (he0, he1) = self.held.split_at_mut(mid);
        let (sc0, sc1) = self.speed_cmd.split_at_mut(mid);
        let (de0, de1) = self.delivered.split_at_mut(mid);
        let (me0, me1) = self.measured.split_at_mut(mid);
        let (va0, va1) = self.values.split_at_mut(mid);
        let (sp0, sp1) = self.speeds.split_at_mut(mid);
        let (cm0, cm1) = self.command.split_at_mut(mid);
        let (om0, om1) = self.omega.split_at_mut(mid);
        let sinks_mid = mid.min(self.sinks.len());
        let (si0, si1) = self.sinks.split_at_mut(sinks_mid);
        (
            Slab {
                base: self.base,
                n: mid,
                states: st0,
                runs: ru0,
                controllers: co0,
                wants_truth: wt0,
                ranging: ra0,
                held: he0,
                speed_cmd: sc0,
                delivered: de0,
                measured: me0,
                values: va0,
                speeds: sp0,
                command: cm0,
                omega: om0,
                sinks: si0,
            },
            Slab {
                base: self.base + mid,
                n: self.n - mid,
                states: st1,
                runs: ru1,
                controllers: co1,
                wants_truth: wt1,
                ranging: ra1,
                held: he1,
                speed_cmd: sc1,
                delivered: de1,
                measured: me1,
                values: va1,
                speeds: sp1,
                command: cm1,
                omega: om1,
                sinks: si1,
            },
        )
    }
}

/// A [`Slab`] with its own part of the positions and liveness, which steps 1-2 write.
struct Front<'s, X, C, S> {
    slab: Slab<'s, X, C, S>,
    positions: &'s mut [Vec2],
    alive: &'s mut [bool],
}

impl<X: Send, C: Send, S: Send> Split for Front<'_, X, C, S> {
    fn chunks(&self) -> usize {
        self.slab.chunks()
    }

    fn split(self, chunks: usize) -> (Self, Self) {
        let mid = (chunks * LANES).min(self.slab.n);
        let (s0, s1) = self.slab.split(chunks);
        let (p0, p1) = self.positions.split_at_mut(mid);
        let (a0, a1) = self.alive.split_at_mut(mid);
        (
            Front {
                slab: s0,
                positions: p0,
                alive: a0,
            },
            Front {
                slab: s1,
                positions: p1,
                alive: a1,
            },
        )
    }
}

/// `f` on each of `parts` contiguous pieces of `item` (as even as whole chunks allow), in
/// parallel on the current rayon pool; the sum of what it returns.
fn in_parts<T: Split, P: Fn(T) -> usize + Sync>(item: T, parts: usize, f: &P) -> usize {
    if parts <= 1 {
        return f(item);
    }
    let left = parts / 2;
    let (a, b) = {
        let c = item.chunks() * left / parts;
        item.split(c)
    };
    let (x, y) = rayon::join(|| in_parts(a, left, f), || in_parts(b, parts - left, f));
    x + y
}

/// The positions `(x, y)` of one chunk's vehicles at `t` and the field there, in lanes.
#[inline(always)]
fn chunk_field_values<F, V, X>(
    field: &F,
    vehicle: &V,
    chunk: &[X; LANES],
    t: f64,
) -> ([f64; LANES], [f64; LANES], [f64; LANES])
where
    F: ScalarField,
    V: SpeedCommand<State = X>,
{
    let mut px = [0.0; LANES];
    let mut py = [0.0; LANES];
    for (l, s) in chunk.iter().enumerate() {
        let p = vehicle.position(s);
        (px[l], py[l]) = (p.x, p.y);
    }
    let v = field.value_lanes(t, &px, &py);
    (px, py, v)
}

/// One chunk's controllers answer the samples of the lanes `sampled` (measurements `ms`)
/// together, in lanes: `command[l]` is set for each lane sampled.
#[inline(always)]
fn answer_in_lanes<C: IsolineController>(
    controllers: &mut [C],
    sampled: &[bool; LANES],
    ms: &[Measurement; LANES],
    command: &mut [Option<f64>],
) {
    if sampled.iter().any(|&s| s) {
        let mut ctrls: [Option<&mut C>; LANES] = [const { None }; LANES];
        for (l, ctrl) in controllers.iter_mut().enumerate() {
            if sampled[l] {
                ctrls[l] = Some(ctrl);
            }
        }
        let w = C::update_lanes(&mut ctrls, ms);
        for (l, cmd) in command.iter_mut().enumerate() {
            if sampled[l] {
                *cmd = Some(w[l]);
            }
        }
    }
}

impl<X: Clone, C: IsolineController, S: TraceSink> Slab<'_, X, C, S> {
    /// Steps 1-2 for the slab's vehicles: the positions and the field there, in lanes; each
    /// vehicle's kernel `sense`; the controllers answer the samples in lanes. `positions` and
    /// `alive` are the slab's own (local indices).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn sense<F, V>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        k: u64,
        t: f64,
        positions: &mut [Vec2],
        alive: &mut [bool],
    ) where
        F: ScalarField,
        V: SpeedCommand<State = X>,
    {
        let n = self.n;
        let mut no_sink = NoTrace;
        for (c, chunk) in self.states.iter().enumerate() {
            let base = c * LANES;
            let m = LANES.min(n - base);
            let (px, py, v) = chunk_field_values(field, vehicle, chunk, t);
            let mut sampled = [false; LANES];
            let mut ms = [Measurement {
                t_s: 0.0,
                value: 0.0,
            }; LANES];
            for l in 0..m {
                let i = base + l;
                positions[i] = Vec2::new(px[l], py[l]);
                let value = v[l];
                self.values[i] = value;
                self.command[i] = None;
                alive[i] = false;
                if !self.runs[i].is_running() {
                    continue;
                }
                let state = &chunk[l];
                let sensed = match self.sinks.get_mut(i) {
                    Some(s) => self.runs[i].sense(vehicle, state, k, t, |_| value, s),
                    None => self.runs[i].sense(vehicle, state, k, t, |_| value, &mut no_sink),
                };
                match sensed {
                    Sensed::Ended => continue,
                    Sensed::Held => {}
                    Sensed::Sampled(mm) if self.wants_truth[i] => {
                        self.measured[i] = mm;
                        let sample = self.runs[i].sample(mm, vehicle.speed_mps(state));
                        self.command[i] = Some(ask(
                            &mut self.controllers[i],
                            true,
                            &sample,
                            oracles.gradient,
                        ));
                    }
                    Sensed::Sampled(mm) => {
                        self.measured[i] = mm;
                        ms[l] = mm;
                        sampled[l] = true;
                    }
                }
                alive[i] = true;
            }
            answer_in_lanes(
                &mut self.controllers[base..base + m],
                &sampled,
                &ms,
                &mut self.command[base..base + m],
            );
        }
    }

    /// Step 3 for the slab's vehicles (not during ring discovery): each ranging unit measures
    /// its two ring neighbours (their positions of this step, from `sh`) and delivers what
    /// arrives now; the spacing law answers with a speed command.
    #[inline(always)]
    fn space<V: SpeedCommand<State = X>>(&mut self, sh: &Shared<'_>, vehicle: &V) {
        let (k, t) = (sh.k, sh.t);
        for j in 0..self.n {
            let i = self.base + j;
            if !sh.alive[i] {
                continue;
            }
            let v0 = sh
                .member_speeds
                .map_or(sh.spacing.nominal_speed_mps, |m| m[i].nominal_mps);
            let Some([a, b]) = sh.ring[i] else {
                continue;
            };
            let (a, b) = (a as usize, b as usize);
            let me = sh.positions[i];
            match sh.spacing.law {
                SpacingLaw::None => {
                    // The ranging unit still runs (its streams as with any law).
                    let pa = sh.alive[a].then(|| sh.positions[a]);
                    let pb = sh.alive[b].then(|| sh.positions[b]);
                    if let Some(r) = self.ranging[j].observe(k, t, me, pa, pb) {
                        self.delivered[j] = Some(r);
                    }
                    self.speed_cmd[j] = v0;
                }
                SpacingLaw::RangeBalance { gain_per_s } => {
                    let pa = sh.alive[a].then(|| sh.positions[a]);
                    let pb = sh.alive[b].then(|| sh.positions[b]);
                    if let Some(r) = self.ranging[j].observe(k, t, me, pa, pb) {
                        self.delivered[j] = Some(r);
                        let [ha, hb] = &mut self.held[j];
                        let ra = ha.update(r.ahead, r.t_s, sh.max_range_m);
                        let rb = hb.update(r.behind, r.t_s, sh.max_range_m);
                        if let (Some(ra), Some(rb)) = (ra, rb) {
                            self.speed_cmd[j] = balance_speed(v0, gain_per_s, ra, rb);
                        }
                    }
                }
                SpacingLaw::ArcReference { gain_per_s } => {
                    // The true arc gaps on the ranging unit's schedule, without its noise,
                    // losses or delay.
                    let now = self.ranging[j].measures_now();
                    self.ranging[j].observe(k, t, me, None, None);
                    if !now {
                        continue;
                    }
                    let Some(arc) = sh.arc else {
                        continue;
                    };
                    let l = arc.length_m();
                    let pm = arc.project(me);
                    let pa = arc.project(sh.positions[a]);
                    let pb = arc.project(sh.positions[b]);
                    if let (Some(pm), Some(pa), Some(pb)) = (pm, pa, pb) {
                        let heading = vehicle.pose(&self.states[j / LANES][j % LANES]).heading_rad;
                        let dir = if pm.tangent.dot(Vec2::from_angle(heading)) >= 0.0 {
                            1.0
                        } else {
                            -1.0
                        };
                        let ga = wrap_arc(dir * (pa.s_m - pm.s_m), l);
                        let gb = wrap_arc(dir * (pm.s_m - pb.s_m), l);
                        self.speed_cmd[j] = balance_speed(v0, gain_per_s, ga, gb);
                    }
                }
            }
        }
    }

    /// Step 4 for the slab's vehicles: each live one's kernel `complete` (metrics, trace, the
    /// end); its command held and speed kept for the move and the team metrics.
    #[inline(always)]
    fn complete<V: SpeedCommand<State = X>>(
        &mut self,
        sh: &Shared<'_>,
        vehicle: &V,
        oracles: &Oracles<'_>,
    ) {
        let mut no_sink = NoTrace;
        for j in 0..self.n {
            if !sh.alive[self.base + j] {
                continue;
            }
            let state = &self.states[j / LANES][j % LANES];
            let command = self.command[j];
            // A vehicle that does not go on (completed, or ended at its command) sensed this
            // step: its position counts for the team metrics, but it does not move.
            let _goes_on = match self.sinks.get_mut(j) {
                Some(s) => self.runs[j].complete(command, sh.k, sh.t, vehicle, state, oracles, s),
                None => self.runs[j].complete(
                    command,
                    sh.k,
                    sh.t,
                    vehicle,
                    state,
                    oracles,
                    &mut no_sink,
                ),
            };
            self.omega[j] = self.runs[j].omega_radps();
            self.speeds[j] = vehicle.speed_mps(state);
        }
    }

    /// Step 5 for the slab's vehicles: each that goes on holds its speed command (saturated to
    /// the envelope) and moves, in lanes. Returns how many go on.
    #[inline(always)]
    fn advance<V: SpeedCommand<State = X>>(&mut self, sh: &Shared<'_>, vehicle: &V) -> usize {
        let n = self.n;
        let mut running = 0;
        for (c, chunk) in self.states.iter_mut().enumerate() {
            let mut w = [0.0; LANES];
            for l in 0..LANES.min(n - c * LANES) {
                let j = c * LANES + l;
                if self.runs[j].is_running() {
                    let v = match sh.speed_override {
                        None => self.speed_cmd[j],
                        Some(o) => o[self.base + j],
                    };
                    let v = match sh.member_speeds {
                        None => v,
                        Some(m) => m[self.base + j].saturate(v),
                    };
                    vehicle.command_speed(&mut chunk[l], v);
                    running += 1;
                }
                w[l] = self.omega[j];
            }
            vehicle.step_lanes(chunk, &w, sh.dt);
        }
        running
    }
}

/// Moves the rows each vehicle recorded in the last half step into `log`, in vehicle order (the
/// order the team records them on one thread).
fn drain_rows(rows: &mut [Vec<TraceRow>], log: &mut Vec<(u32, TraceRow)>) {
    for (v, r) in rows.iter_mut().enumerate() {
        log.extend(r.drain(..).map(|row| (v as u32, row)));
    }
}

/// Steps 1-2 of one part of a threaded team step (compiled as [`drive_lanes`] is).
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "aarch64+neon"
))]
fn front_part<X, C, F, V>(
    p: Front<'_, X, C, Vec<TraceRow>>,
    field: &F,
    vehicle: &V,
    oracles: &Oracles<'_>,
    k: u64,
    t: f64,
) where
    X: Clone,
    C: IsolineController,
    F: ScalarField,
    V: SpeedCommand<State = X>,
{
    let Front {
        mut slab,
        positions,
        alive,
    } = p;
    slab.sense(field, vehicle, oracles, k, t, positions, alive);
}

/// Steps 3-5 of one part of a threaded team step; how many of its vehicles go on.
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "aarch64+neon"
))]
fn back_part<X, C, V>(
    mut s: Slab<'_, X, C, Vec<TraceRow>>,
    sh: &Shared<'_>,
    vehicle: &V,
    oracles: &Oracles<'_>,
) -> usize
where
    X: Clone,
    C: IsolineController,
    V: SpeedCommand<State = X>,
{
    s.space(sh, vehicle);
    s.complete(sh, vehicle, oracles);
    s.advance(sh, vehicle)
}

/// Up to `steps` team steps over `parts` threads of the current rayon pool (stopping at the
/// end, or during ring discovery, which steps on one thread). Each step: every part's steps 1-2;
/// then every part's steps 3-5 (a vehicle reads only its own state and the positions and
/// liveness of the step, all written before); then the team metrics. Each vehicle's numbers
/// are those of one thread, bit for bit; the trace rows go into `log` in one thread's order.
#[allow(clippy::too_many_arguments)]
fn par_block<X, C, F, V>(
    g: &mut Group<'_, X, C>,
    field: &F,
    vehicle: &V,
    oracles: &Oracles<'_>,
    rows: &mut [Vec<TraceRow>],
    log: &mut Vec<(u32, TraceRow)>,
    parts: usize,
    steps: u64,
) where
    X: Clone + Send,
    C: IsolineController + Send,
    F: ScalarField + Sync,
    V: SpeedCommand<State = X> + Sync,
{
    let mut left = steps;
    while left > 0 && g.is_running() && g.discovery.is_none() {
        left -= 1;
        let k = g.k;
        let t = k as f64 * g.plan.dt_s;
        let front = Front {
            slab: slab!(g, &mut *rows),
            positions: &mut g.positions,
            alive: &mut g.alive,
        };
        in_parts(front, parts, &|p| {
            front_part(p, field, vehicle, oracles, k, t);
            0
        });
        drain_rows(rows, log);
        let sh = shared!(g, k, t);
        let running = in_parts(slab!(g, &mut *rows), parts, &|s| {
            back_part(s, &sh, vehicle, oracles)
        });
        g.running = running;
        g.close_ring();
        drain_rows(rows, log);
        g.observe_team(k, t);
        g.k += 1;
    }
}

impl Current<'_> {
    /// Extracts the isoline again if its version at `t_s` differs from the one in force;
    /// returns whether it did. Without a version (the field ended) or a closed loop, no isoline.
    fn refresh(&mut self, t_s: f64, positions: &[Vec2], alive: &[bool]) -> bool {
        let v = self.source.get().version(t_s);
        if v == self.version {
            return false;
        }
        self.version = v;
        let Some(v) = v else {
            self.arc = None;
            return false;
        };
        let loops = self.source.get().loops(v);
        let live: Vec<Vec2> = positions
            .iter()
            .zip(alive)
            .filter(|(_, a)| **a)
            .map(|(p, _)| *p)
            .collect();
        let voters = if live.is_empty() { positions } else { &live };
        let prev = self.arc.take();
        self.arc = pick_loop(&loops, voters)
            .and_then(|j| PolylineArc::aligned(loops[j].clone(), prev.as_ref()).ok());
        true
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
