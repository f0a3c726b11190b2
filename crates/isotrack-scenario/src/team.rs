//! Running a scenario's `[team]` ([`crate::spec::TeamSpec`]) through
//! [`isotrack_sim::Group`]: every vehicle the scenario's field, tracking law and sensor (its
//! own seeded streams), a Dubins robot whose speed, or a fixed-wing UAV whose airspeed command,
//! the spacing law sets within `[team.v_min_mps, team.v_max_mps]` (docs/TEAMS.md).

use crate::field::{FieldModel, IsolineOracle, MovingIsoline};
use crate::spec::TeamSpec;
use crate::vehicle::VehicleModel;
use crate::Scenario;
use isotrack_core::math::Vec2;
use isotrack_core::{FieldDerivatives, IsolineController, ScalarField, SpeedCommand};
use isotrack_fields::isoline::IsolineSegments;
use isotrack_fields::puff::PuffPlume;
use isotrack_fields::AnalyticKind;
use isotrack_sim::team::arc::{pick_piece, ArcProjection, CircleArc, MovingArc, PolylineArc};
use isotrack_sim::team::metrics::TeamMetricsConfig;
use isotrack_sim::team::spacing::{SpacingConfig, SpacingLaw};
use isotrack_sim::team::TeamIsoline;
use isotrack_sim::{
    Group, MemberSpeeds, Oracles, Sensor, TeamConfig, TeamError, TeamMember, TeamResult,
    TeamThreads, TraceSink,
};
use isotrack_vehicles::{DubinsState, DubinsVariableSpeed, FixedWingVariableSpeed};
use std::sync::Arc;

/// Samples per side of the lattice an analytic field's (or a puff plume's) isoline is
/// extracted on by marching squares for the team metrics (at most `LATTICE^2` field values per
/// extraction).
pub const TEAM_LATTICE: usize = 400;
/// A puff plume's isoline of the time is extracted again every this many seconds of the run
/// (it moves continuously; the extraction costs `PUFF_LATTICE^2` field values).
pub const PUFF_ISOLINE_PERIOD_S: f64 = 1.0;
/// Samples per side of the lattice a puff plume's isoline is extracted on (each value visits
/// the live puffs near it: a coarser lattice than [`TEAM_LATTICE`] keeps the extractions, one
/// per [`PUFF_ISOLINE_PERIOD_S`], within a few times the run's own cost).
pub const PUFF_LATTICE: usize = 200;
/// Team metrics along a polyline (an extracted isoline) are sampled every this many seconds
/// (a whole number of steps, at least one): each sample projects every vehicle onto the
/// polyline (`O(vertices)` each).
pub const POLYLINE_METRICS_PERIOD_S: f64 = 0.1;

/// The true isoline a team's metrics measure along ([`Scenario::team_isoline`]).
pub enum TeamIsolineModel {
    /// The circle of a radial field that does not drift (exact).
    Circle(CircleArc),
    /// An isoline of a static field, extracted once by marching squares: the piece (a closed
    /// loop, or an open chain that leaves the field: [`PolylineArc::open`]) most of the
    /// team's starts are nearest to.
    Polyline(PolylineArc),
    /// An isoline that moves (a time series of frames, a puff plume): the isoline of the
    /// time, extracted again per frame (per [`PUFF_ISOLINE_PERIOD_S`] for a puff plume).
    Moving(Box<dyn MovingArc + Send>),
    /// None: why.
    None(&'static str),
}

impl TeamIsolineModel {
    /// The engine's view of it (`None` for [`TeamIsolineModel::None`]).
    pub fn as_team_isoline(&self) -> Option<TeamIsoline<'_>> {
        match self {
            TeamIsolineModel::Circle(c) => Some(TeamIsoline::Fixed(c)),
            TeamIsolineModel::Polyline(p) => Some(TeamIsoline::Fixed(p)),
            TeamIsolineModel::Moving(m) => Some(TeamIsoline::Moving(&**m)),
            TeamIsolineModel::None(_) => None,
        }
    }

    /// Whether it is an open isoline (one that leaves the field: the team metrics of
    /// [`isotrack_sim::team::metrics::OpenIsolineStats`]).
    pub fn is_open(&self) -> bool {
        matches!(self, TeamIsolineModel::Polyline(p) if !p.is_closed())
    }
}

/// Why a scenario's team has no metrics (`summary.json`'s `team.metrics_note`).
pub const NO_CLOSED_ISOLINE: &str = "no team metrics: the field has no isoline at controller.level to measure along (no closed loop and no open piece leaving the field)";
/// The note for a drifting analytic field, a radial one included (att32g-6: the note said
/// radial fields were followed; their team metrics are not wired: the arc projection is of a
/// fixed isoline).
pub const DRIFTING_FIELD: &str =
    "no team metrics: the team metrics do not follow the isoline of a drifting analytic field (a radial one included), for now";

/// Why `isotrack run` refuses `team.spacing = "arc_reference"` on a radial field whose values
/// never reach `controller.level` (att36-8: it was refused with
/// [`ARC_REFERENCE_WITHOUT_ARC`], false there: the field is a radial one that does not drift).
pub const ARC_REFERENCE_NO_ISOLINE: &str = "team.spacing = \"arc_reference\" needs the isoline's arc length, but the field has no isoline at controller.level: a radial field i0 exp(-k r) takes values in (0, i0] only, and the level is not among them";

/// Why `isotrack run` refuses a scenario whose law is `arc_reference` on a field without a
/// known arc length ([`Scenario::team_refusal`]; exit 65), and why `check` says its team
/// section does not apply (att32g-3: one text for both).
pub const ARC_REFERENCE_WITHOUT_ARC: &str = "team.spacing = \"arc_reference\" needs the isoline's arc length, known for a radial field that does not drift (its circle inside the field's domain_m) only, for now";

/// Marching squares stitch end points closer than this (relative to the coordinates' scale)
/// into one vertex.
fn loop_tolerance_m(scale_m: f64) -> f64 {
    (1e-9 * scale_m.abs()).max(1e-6)
}

fn closed_loops(s: &IsolineSegments) -> Vec<Vec<Vec2>> {
    let scale = s
        .segments()
        .iter()
        .map(|(a, b)| a.x.abs().max(a.y.abs()).max(b.x.abs()).max(b.y.abs()))
        .fold(0.0, f64::max);
    s.closed_loops(loop_tolerance_m(scale))
}

/// The piece of the isoline `s` the `starts` are on ([`pick_piece`]), as a polyline: a closed
/// loop (oriented counter-clockwise) or an open chain (from the free end marching squares
/// lists first).
fn polyline_of(s: &IsolineSegments, starts: &[Vec2]) -> TeamIsolineModel {
    let loops = closed_loops(s);
    let chains = open_chains(s);
    let picked = match pick_piece(&loops, &chains, starts) {
        Some(Ok(j)) => PolylineArc::aligned(loops[j].clone(), None).ok(),
        Some(Err(j)) => PolylineArc::open(chains[j].clone()).ok(),
        None => None,
    };
    match picked {
        Some(p) => TeamIsolineModel::Polyline(p),
        None => TeamIsolineModel::None(NO_CLOSED_ISOLINE),
    }
}

fn open_chains(s: &IsolineSegments) -> Vec<Vec<Vec2>> {
    let scale = s
        .segments()
        .iter()
        .map(|(a, b)| a.x.abs().max(a.y.abs()).max(b.x.abs()).max(b.y.abs()))
        .fold(0.0, f64::max);
    s.open_chains(loop_tolerance_m(scale))
}

/// Marching squares of `f` over `box_m = [x0, x1, y0, y1]` on a lattice of at most `lattice`
/// samples per side (square cells).
fn lattice_segments(
    box_m: [f64; 4],
    lattice: usize,
    level: f64,
    f: impl Fn(Vec2) -> Option<f64>,
) -> Option<IsolineSegments> {
    let [x0, x1, y0, y1] = box_m;
    let side = (x1 - x0).max(y1 - y0);
    if !(side > 0.0 && side.is_finite()) {
        return None;
    }
    let h = side / (lattice - 1) as f64;
    let nx = (((x1 - x0) / h).ceil() as usize + 1).clamp(2, lattice);
    let ny = (((y1 - y0) / h).ceil() as usize + 1).clamp(2, lattice);
    Some(IsolineSegments::from_samples(
        Vec2::new(x0, y0),
        h,
        nx,
        ny,
        level,
        f,
    ))
}

/// The box an analytic field's closed isolines lie in: its domain, or (Gaussian plumes) the
/// sources' centres widened by 8 of their largest sigma (where a plume is `exp(-32)` of its
/// peak); `None` where unbounded (a linear ramp's isolines are straight lines).
fn analytic_box(f: &isotrack_fields::AnalyticField) -> Option<[f64; 4]> {
    if let Some(d) = f.domain_m {
        return Some(d);
    }
    match &f.kind {
        AnalyticKind::GaussianPlumes(g) if !g.plumes.is_empty() => {
            let mut b = [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            for p in &g.plumes {
                let w = 8.0 * p.sigma_m[0].max(p.sigma_m[1]);
                b = [
                    b[0].min(p.center_m.x - w),
                    b[1].max(p.center_m.x + w),
                    b[2].min(p.center_m.y - w),
                    b[3].max(p.center_m.y + w),
                ];
            }
            b.iter().all(|v| v.is_finite()).then_some(b)
        }
        _ => None,
    }
}

/// A time series' isoline: the marching-squares isoline of the field of the time, one version
/// per [`MovingIsoline::bucket_s`] (the true-isoline metric's own resolution: 1/8 of the
/// shortest frame interval).
struct SeriesArc(Arc<MovingIsoline>);

impl MovingArc for SeriesArc {
    fn version(&self, t_s: f64) -> Option<i64> {
        let b = self.0.bucket_s();
        Some(if b.is_finite() {
            (t_s / b).floor() as i64
        } else {
            0
        })
    }
    fn loops(&self, version: i64) -> Vec<Vec<Vec2>> {
        let b = self.0.bucket_s();
        let t = if b.is_finite() {
            (version as f64 + 0.5) * b
        } else {
            0.0
        };
        match self.0.at(t).as_ref() {
            Some(s) => closed_loops(s),
            None => Vec::new(),
        }
    }
}

/// A puff plume's isoline of the time: one version per [`PUFF_ISOLINE_PERIOD_S`], extracted at
/// the period's start, on [`PUFF_LATTICE`] samples a side, over the box the live puffs can reach: along the wind from the source
/// to its reach `|U| max_age`, widened by four puff widths at `max_age` plus three standard
/// deviations of the meander's displacement over `max_age`
/// (`std(u') sqrt(2 T_c max_age)`, a correlated velocity's integral).
struct PuffArc {
    plume: Arc<PuffPlume>,
    level: f64,
    box_m: [f64; 4],
}

impl PuffArc {
    fn new(plume: Arc<PuffPlume>, level: f64) -> Self {
        let p = *plume.params();
        let u = p.wind_mps;
        let reach = u * p.max_age_s;
        let width = 4.0 * (p.puff_sigma0_m.powi(2) + 2.0 * p.diffusivity_m2ps * p.max_age_s).sqrt();
        let meander =
            3.0 * p.meander_std_mps * (2.0 * p.meander_correlation_s * p.max_age_s).sqrt();
        let m = width + meander;
        let (a, b) = (p.source_m, p.source_m + reach);
        let mut box_m = [
            a.x.min(b.x) - m,
            a.x.max(b.x) + m,
            a.y.min(b.y) - m,
            a.y.max(b.y) + m,
        ];
        if let Some(d) = p.domain_m {
            box_m = [
                box_m[0].max(d[0]),
                box_m[1].min(d[1]),
                box_m[2].max(d[2]),
                box_m[3].min(d[3]),
            ];
        }
        Self {
            plume,
            level,
            box_m,
        }
    }
}

impl MovingArc for PuffArc {
    fn version(&self, t_s: f64) -> Option<i64> {
        Some((t_s / PUFF_ISOLINE_PERIOD_S).floor() as i64)
    }
    fn loops(&self, version: i64) -> Vec<Vec<Vec2>> {
        let t = version as f64 * PUFF_ISOLINE_PERIOD_S;
        lattice_segments(self.box_m, PUFF_LATTICE, self.level, |p| {
            self.plume.value(t, p)
        })
        .map(|s| closed_loops(&s))
        .unwrap_or_default()
    }
}

impl Scenario {
    /// The circle of a radial field that does not drift (`None` otherwise): the exact isoline
    /// of [`Scenario::team_isoline`] there. With a `domain_m`, the circle when it lies inside
    /// the domain (its box `center -+ R` within the domain's, touching allowed): the field is
    /// the same along it, so it is the isoline whole (att32f-7: `arc_reference` was refused
    /// there, and the metrics measured along its marching-squares polygon); a domain that cuts
    /// the circle leaves open arcs, measured as an open isoline.
    pub fn team_arc(&self) -> Option<CircleArc> {
        match self.isoline() {
            IsolineOracle::Circle {
                center_m,
                drift_mps,
                radius_m,
            } if drift_mps.x == 0.0 && drift_mps.y == 0.0 => Some(CircleArc {
                center_m: *center_m,
                radius_m: *radius_m,
            }),
            _ => self.circle_inside_domain(),
        }
    }

    /// A radial field's circle at the level when the field has a `domain_m` containing it and
    /// does not drift.
    fn circle_inside_domain(&self) -> Option<CircleArc> {
        let FieldModel::Analytic(f) = self.field() else {
            return None;
        };
        let (AnalyticKind::RadialExp(r), Some([x0, x1, y0, y1])) = (&f.kind, f.domain_m) else {
            return None;
        };
        let level = self.level();
        if f.drift_mps.x != 0.0
            || f.drift_mps.y != 0.0
            || !(r.i0 > 0.0 && level > 0.0 && level < r.i0 && r.decay_per_m > 0.0)
        {
            return None;
        }
        let radius_m = (r.i0 / level).ln() / r.decay_per_m;
        let c = r.center_m;
        let inside = radius_m.is_finite()
            && x0 <= c.x - radius_m
            && c.x + radius_m <= x1
            && y0 <= c.y - radius_m
            && c.y + radius_m <= y1;
        inside.then_some(CircleArc {
            center_m: c,
            radius_m,
        })
    }

    /// The true isoline for the team metrics and the `arc_reference` law: the circle of a
    /// radial field that does not drift; for another static field, the piece of its isoline
    /// (marching squares: the grid's, or an analytic field's over its domain, its sources'
    /// reach or, for a linear ramp without a domain, the box the team can reach in the run)
    /// most of the team's starts are nearest to: a closed loop, or an open chain that leaves
    /// the field (docs/TEAMS.md "Open isolines"); for a time series or a puff plume, the
    /// isoline of the time ([`TeamIsolineModel::Moving`], closed loops only). No isoline there
    /// gives no metrics ([`NO_CLOSED_ISOLINE`]).
    pub fn team_isoline(&self) -> TeamIsolineModel {
        if let Some(c) = self.team_arc() {
            return TeamIsolineModel::Circle(c);
        }
        let level = self.level();
        let starts: Vec<Vec2> = match self.spec().team.as_ref() {
            Some(t) => t.starts.iter().map(|s| Vec2::new(s.x_m, s.y_m)).collect(),
            None => {
                let s = self.start();
                vec![Vec2::new(s.x_m, s.y_m)]
            }
        };
        match self.field() {
            FieldModel::Analytic(f) => {
                if f.drift_mps.x != 0.0 || f.drift_mps.y != 0.0 {
                    return TeamIsolineModel::None(DRIFTING_FIELD);
                }
                match analytic_box(f)
                    .or_else(|| self.team_reach_box(f, &starts))
                    .and_then(|b| lattice_segments(b, TEAM_LATTICE, level, |p| f.value(0.0, p)))
                {
                    Some(s) => polyline_of(&s, &starts),
                    None => TeamIsolineModel::None(NO_CLOSED_ISOLINE),
                }
            }
            FieldModel::Grid(_) => match self.isoline() {
                IsolineOracle::Segments(s) => polyline_of(s, &starts),
                _ => TeamIsolineModel::None(NO_CLOSED_ISOLINE),
            },
            FieldModel::Series(_) => match self.isoline() {
                IsolineOracle::Moving(m) => {
                    TeamIsolineModel::Moving(Box::new(SeriesArc(m.clone())))
                }
                _ => TeamIsolineModel::None(NO_CLOSED_ISOLINE),
            },
            FieldModel::Puff(p) => {
                TeamIsolineModel::Moving(Box::new(PuffArc::new(p.clone(), level)))
            }
        }
    }

    /// A linear ramp without a domain (its isoline a straight line without end): the box the
    /// team can reach in the run, the starts' box widened on every side by 1.25 times the
    /// fastest speed times the duration, plus 1 m (a margin for wind), where its isoline is
    /// an open chain.
    fn team_reach_box(
        &self,
        f: &isotrack_fields::AnalyticField,
        starts: &[Vec2],
    ) -> Option<[f64; 4]> {
        if !matches!(f.kind, AnalyticKind::LinearRamp(_)) || starts.is_empty() {
            return None;
        }
        let v = match self.spec().team.as_ref() {
            Some(t) => t.speed_envelope_mps().1,
            None => self.spec().vehicle.speed_mps(),
        };
        let reach = 1.25 * v * self.spec().sim.duration_s + 1.0;
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in starts {
            b = [
                b[0].min(p.x - reach),
                b[1].max(p.x + reach),
                b[2].min(p.y - reach),
                b[3].max(p.y + reach),
            ];
        }
        b.iter().all(|x| x.is_finite()).then_some(b)
    }

    /// Why `isotrack run` refuses this scenario's team before it starts, or `None`:
    /// `team.spacing = "arc_reference"` needs the true arc length ([`Scenario::team_arc`]:
    /// a radial field that does not drift, its circle inside its `domain_m`).
    pub fn team_refusal(&self) -> Option<&'static str> {
        let arc_law = self
            .spec()
            .team
            .as_ref()
            .is_some_and(|t| matches!(t.law, SpacingLaw::ArcReference { .. }));
        if !arc_law || self.team_arc().is_some() {
            return None;
        }
        Some(if self.radial_without_level() {
            ARC_REFERENCE_NO_ISOLINE
        } else {
            ARC_REFERENCE_WITHOUT_ARC
        })
    }

    /// A radial field (`i0 exp(-k r)`, `i0 > 0`, `k > 0`) whose values `(0, i0]` do not hold
    /// `controller.level` (`level <= 0` or `level >= i0`: at `i0` the "isoline" is the centre
    /// alone): no isoline at the level at all.
    fn radial_without_level(&self) -> bool {
        let FieldModel::Analytic(f) = self.field() else {
            return false;
        };
        let AnalyticKind::RadialExp(r) = &f.kind else {
            return false;
        };
        let level = self.level();
        r.i0 > 0.0 && r.decay_per_m > 0.0 && !(level > 0.0 && level < r.i0)
    }

    /// Why a team run of this scenario has no team metrics (`summary.json`'s
    /// `team.metrics_note`).
    pub fn team_metrics_note(&self) -> &'static str {
        match self.team_isoline() {
            TeamIsolineModel::None(note) => note,
            _ => NO_CLOSED_ISOLINE,
        }
    }

    /// Runs the scenario's team (`None` without a `[team]` section), vehicle `i` recording its
    /// trace into `sinks[i]` (`sinks` empty: no trace).
    pub fn run_team<S: TraceSink>(&self, sinks: &mut [S]) -> Option<Result<TeamResult, TeamError>> {
        self.run_team_threads(sinks, TeamThreads::new(1))
    }

    /// [`run_team`](Self::run_team) over the threads `threads` allows for the team's size
    /// ([`Group::drive_threads`]): the same result and trace, bit for bit, on any number.
    pub fn run_team_threads<S: TraceSink>(
        &self,
        sinks: &mut [S],
        threads: TeamThreads,
    ) -> Option<Result<TeamResult, TeamError>> {
        let n = self.spec().team.as_ref()?.count();
        let controllers = (0..n).map(|_| self.tracker()).collect();
        self.run_team_with_threads(controllers, sinks, threads)
    }

    /// [`run_team`](Self::run_team) with other controllers in the loop, `controllers[i]`
    /// steering vehicle `i` in place of the scenario's tracking law (a user's own law, from
    /// Python say): the same field, vehicles, sensors, ranging, spacing law and metrics; each
    /// controller sees only its own vehicle's measurements. One controller per vehicle.
    pub fn run_team_with<C: IsolineController + Send, S: TraceSink>(
        &self,
        controllers: Vec<C>,
        sinks: &mut [S],
    ) -> Option<Result<TeamResult, TeamError>> {
        self.run_team_with_threads(controllers, sinks, TeamThreads::new(1))
    }

    fn run_team_with_threads<C: IsolineController + Send, S: TraceSink>(
        &self,
        controllers: Vec<C>,
        sinks: &mut [S],
        threads: TeamThreads,
    ) -> Option<Result<TeamResult, TeamError>> {
        let team = self.spec().team.as_ref()?;
        if controllers.len() != team.count() {
            return Some(Err(TeamError::OutOfRange {
                key: "count",
                value: controllers.len() as f64,
                expected: "one controller per vehicle",
            }));
        }
        Some(match self.field() {
            FieldModel::Analytic(f) => self.run_team_on(f, team, controllers, sinks, threads),
            FieldModel::Grid(f) => self.run_team_on(f, team, controllers, sinks, threads),
            FieldModel::Puff(f) => self.run_team_on(&**f, team, controllers, sinks, threads),
            FieldModel::Series(f) => self.run_team_on(&**f, team, controllers, sinks, threads),
        })
    }

    fn run_team_on<F, C, S>(
        &self,
        field: &F,
        team: &TeamSpec,
        controllers: Vec<C>,
        sinks: &mut [S],
        threads: TeamThreads,
    ) -> Result<TeamResult, TeamError>
    where
        F: ScalarField + FieldDerivatives + Sync,
        C: IsolineController + Send,
        S: TraceSink,
    {
        let iso = self.isoline();
        let dist = |t: f64, p: Vec2| iso.distance(t, p);
        let grad = |t: f64, p: Vec2| Some((field.gradient(t, p)?, field.hessian(t, p)?));
        let oracles = Oracles {
            isoline_distance: Some(&dist),
            gradient: Some(&grad),
        };
        let model = self.team_isoline();
        let cfg = self.team_config(team, &model);
        let isoline = model.as_team_isoline();
        // The vehicle model's envelope holds every vehicle's own (the team's without
        // per-vehicle overrides); each vehicle's speeds are set on the group.
        let (lo, hi) = team.speed_envelope_mps();
        let speeds = team.member_speeds();
        let r = match &*self.vehicle {
            VehicleModel::Dubins(_) => {
                let vehicle = DubinsVariableSpeed {
                    min_speed_mps: lo,
                    max_speed_mps: hi,
                };
                let members = self.team_members(team, controllers, |_, s| {
                    vehicle.state(
                        DubinsState {
                            position_m: Vec2::new(s.x_m, s.y_m),
                            heading_rad: s.heading_rad,
                        },
                        team.nominal_speed_mps,
                    )
                })?;
                drive(
                    field, &vehicle, cfg, members, speeds, isoline, &oracles, sinks, self, threads,
                )?
            }
            VehicleModel::FixedWing(w) => {
                let vehicle = FixedWingVariableSpeed::new((**w).clone(), lo, hi).map_err(|_| {
                    TeamError::OutOfRange {
                        key: "v_min_mps",
                        value: lo,
                        expected: "an airspeed envelope within the Aerosonde's safe range",
                    }
                })?;
                let gust_seed = w.config().seed;
                // Each UAV starts trimmed at its own nominal airspeed v0_i (att32d-13: at the
                // scenario's, it began 10 m/s off its command). Validation holds every v0_i in
                // [20, 45] m/s, where the Aerosonde trims; a trim that failed anyway would start
                // it at the scenario's, as before.
                let members = self.team_members(team, controllers, |i, s| {
                    let seed = TeamSpec::gust_seed(gust_seed, i);
                    w.initial_state_at_airspeed(
                        s.x_m,
                        s.y_m,
                        s.heading_rad,
                        seed,
                        team.speeds(i).nominal_mps,
                    )
                    .unwrap_or_else(|_| w.initial_state_seeded(s.x_m, s.y_m, s.heading_rad, seed))
                })?;
                drive(
                    field, &vehicle, cfg, members, speeds, isoline, &oracles, sinks, self, threads,
                )?
            }
        };
        Ok(TeamResult {
            runs: r.runs.into_iter().map(|x| self.explain_end(x)).collect(),
            ..r
        })
    }

    /// How often the team metrics sample, in steps: every step along a circle (exact:
    /// `exact_circle`), every [`POLYLINE_METRICS_PERIOD_S`] (rounded to whole steps, at least
    /// one) along an extracted isoline. A team figure's steady window starts at the metrics'
    /// first sample in it (att32g-1).
    pub fn team_metrics_every_steps(&self, exact_circle: bool) -> u64 {
        if exact_circle {
            TeamMetricsConfig::default().every_steps
        } else {
            ((POLYLINE_METRICS_PERIOD_S / self.dt_s()).round() as u64).max(1)
        }
    }

    /// The team's configuration: its ranging and spacing law, and its metrics sampled every
    /// step on a circle (exact) or without an isoline, every [`POLYLINE_METRICS_PERIOD_S`] on
    /// an extracted one.
    pub fn team_config(&self, team: &TeamSpec, model: &TeamIsolineModel) -> TeamConfig {
        let every_steps = self.team_metrics_every_steps(matches!(
            model,
            TeamIsolineModel::Circle(_) | TeamIsolineModel::None(_)
        ));
        let metrics = TeamMetricsConfig {
            every_steps,
            ..TeamMetricsConfig::default()
        };
        TeamConfig {
            ranging: team.ranging,
            spacing: SpacingConfig {
                law: team.law,
                nominal_speed_mps: team.nominal_speed_mps,
                ring: team.ring,
            },
            metrics,
        }
    }

    /// The team's members in start order: vehicle `i` starts at `x0(i, start)`, flown by the
    /// `i`-th of `controllers`, with the scenario's sensor with its override's noise and rate
    /// (the same sensor as `sensor_seeded` without one) and its own seeded streams.
    fn team_members<X, C>(
        &self,
        team: &TeamSpec,
        controllers: Vec<C>,
        x0: impl Fn(usize, &crate::spec::sim::Start) -> X,
    ) -> Result<Vec<TeamMember<X, C>>, TeamError> {
        let (seed, base) = (self.spec().sim.seed, self.spec().sensor);
        let mut controllers = controllers.into_iter();
        team.starts
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let controller = controllers.next().ok_or(TeamError::Empty)?;
                let sensor = Sensor::new(
                    team.sensor(i, base),
                    self.dt_s(),
                    TeamSpec::sensor_seed(seed, i),
                )
                .map_err(|_| TeamError::OutOfRange {
                    key: "vehicles",
                    value: team.sensor(i, base).rate_hz,
                    expected: "a sensor rate of a whole number of steps per sample",
                })?;
                Ok(TeamMember {
                    x0: x0(i, s),
                    controller,
                    sensor,
                    ranging_seed: TeamSpec::ranging_seed(seed, i),
                })
            })
            .collect()
    }
}

/// [`Group::with_isoline`], driven to the end.
#[allow(clippy::too_many_arguments)]
fn drive<F, V, C, S>(
    field: &F,
    vehicle: &V,
    cfg: TeamConfig,
    members: Vec<TeamMember<V::State, C>>,
    speeds: Option<Vec<MemberSpeeds>>,
    isoline: Option<TeamIsoline<'_>>,
    oracles: &Oracles<'_>,
    sinks: &mut [S],
    scenario: &Scenario,
    threads: TeamThreads,
) -> Result<TeamResult, TeamError>
where
    F: ScalarField + Sync,
    V: SpeedCommand + Sync,
    V::State: Send,
    C: IsolineController + Send,
    S: TraceSink,
{
    if !sinks.is_empty() && sinks.len() != members.len() {
        return Err(TeamError::Sinks {
            sinks: sinks.len(),
            vehicles: members.len(),
        });
    }
    let mut g = Group::with_isoline(vehicle, &scenario.plan(), cfg, members, isoline)?;
    if let Some(speeds) = speeds {
        g.set_member_speeds(vehicle, speeds)?;
    }
    g.drive_threads(field, vehicle, oracles, sinks, threads);
    Ok(g.finish(sinks))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_scenario;
    use isotrack_sim::team::arc::ArcProjection;
    use isotrack_sim::TraceRow;

    /// A fixed-wing UAV with gusts and a noisy sensor on the circular field (radius 600 m).
    const UAV: &str = "[field]\nkind = \"radial_exp\"\ni0 = 20.0\ndecay_per_m = 0.001\n\
        [vehicle]\nkind = \"fixed_wing\"\nairspeed_mps = 30.0\ngusts = true\n\
        [initial]\nx_m = 600.0\ny_m = 0.0\nheading_rad = -1.5707963267948966\n\
        [sensor]\nrate_hz = 1.0\nnoise_std = 0.01\n\
        [controller]\nlevel = 10.976\nkp = 150.0\nki = 0.0\nc1 = 0.0005\nc2 = 0.1\n\
        [sim]\ndt_s = 0.01\nduration_s = 60.0\nseed = 9\n";

    /// A team of one fixed-wing UAV with the `none` law flies the single run, bit for bit:
    /// the same result and the same trace (its airspeed command the configured airspeed,
    /// its gusts and sensor seeded as the single run's).
    #[test]
    fn a_team_of_one_fixed_wing_is_the_single_run() {
        let single = parse_scenario(UAV, "<test>", &[]).unwrap();
        let mut alone: Vec<TraceRow> = Vec::new();
        let r = single.run(&mut alone);
        let team = parse_scenario(
            &format!("{UAV}[team]\ncount = 1\nspacing = \"none\"\n"),
            "<test>",
            &[],
        )
        .unwrap();
        let t = team.spec().team.as_ref().unwrap();
        assert_eq!((t.v_min_mps, t.v_max_mps), (20.0, 45.0));
        let mut sinks = vec![Vec::<TraceRow>::new()];
        let tr = team.run_team(&mut sinks).unwrap().unwrap();
        assert_eq!(format!("{:?}", tr.runs[0]), format!("{r:?}"));
        assert!(alone.len() > 100);
        assert_eq!(format!("{:?}", sinks[0]), format!("{alone:?}"));
        // range_balance with one vehicle has no neighbour: the same flight too.
        let team = parse_scenario(
            &format!("{UAV}[team]\ncount = 1\nspacing = \"range_balance\"\n"),
            "<test>",
            &[],
        )
        .unwrap();
        let tr = team
            .run_team(&mut [] as &mut [Vec<TraceRow>])
            .unwrap()
            .unwrap();
        assert_eq!(format!("{:?}", tr.runs[0]), format!("{r:?}"));
    }

    /// A fixed-wing team's envelope outside the Aerosonde's safe commanded airspeeds [20, 45] m/s
    /// is refused by key; inside it, accepted.
    #[test]
    fn a_fixed_wing_envelope_is_checked() {
        for (set, key) in [
            ("team.v_min_mps=10.0", "team.v_min_mps"),
            ("team.v_max_mps=50.0", "team.v_max_mps"),
        ] {
            let e = parse_scenario(
                &format!("{UAV}[team]\ncount = 1\n"),
                "<test>",
                &[set.to_string()],
            )
            .unwrap_err();
            let text = format!("{e:?}");
            assert!(text.contains(key) && text.contains("[20, 45]"), "{text}");
        }
        let ok = parse_scenario(
            &format!("{UAV}[team]\ncount = 1\nv_min_mps = 25.0\nv_max_mps = 35.0\n"),
            "<test>",
            &[],
        )
        .unwrap();
        let t = ok.spec().team.clone().unwrap();
        assert_eq!((t.v_min_mps, t.v_max_mps), (25.0, 35.0));
    }

    /// Two fixed-wing UAVs a quarter of the circle apart, `arc_reference` from 25 to 35 m/s:
    /// each UAV's airspeed stays within the envelope up to the airspeed loop's transients
    /// (2.5 m/s), and the team's speeds (ground speeds, in still air) likewise.
    #[test]
    fn a_fixed_wing_team_flies_its_airspeed_commands() {
        let s = parse_scenario(
            &format!(
                "{UAV}[team]\nspacing = \"arc_reference\"\nk_v = 0.05\nv_min_mps = 25.0\n\
                 v_max_mps = 35.0\nspread = {{ along = \"arc\", radius_m = 600.0, step_rad = 0.5 }}\n\
                 count = 2\n"
            ),
            "<test>",
            &["vehicle.gusts=false".into()],
        )
        .unwrap();
        let mut sinks = vec![Vec::<TraceRow>::new(), Vec::new()];
        let r = s.run_team(&mut sinks).unwrap().unwrap();
        let t = r.team.unwrap();
        let [lo, hi] = t.speed_range_mps.unwrap();
        // Ground speeds of airspeeds within the envelope, up to the airspeed loop's transient
        // after a step of the command (a 5 m/s step undershoots by about 2 m/s).
        assert!(lo > 22.5 && hi < 37.5, "{lo} {hi}");
        // The gap behind vehicle 0 is the larger one at first: it slows, 1 speeds up.
        assert!(hi > 31.0 && lo < 29.0, "{lo} {hi}");
        for rows in &sinks {
            for row in rows {
                let va = row.telemetry.unwrap().airspeed_mps;
                assert!((22.5..37.5).contains(&va), "airspeed {va}");
            }
        }
    }

    /// A fixed-wing team of 60 UAVs (gusts, noisy sensors; `range_balance` on noisy, lossy,
    /// delayed ranging) flies the same on 1, 2, 3 and 7 threads, bit for bit: every result,
    /// team metric and trace row, the rows in the same order (one log, as the trace file).
    #[test]
    fn a_fixed_wing_team_is_the_same_on_any_threads() {
        use isotrack_sim::TeamThreads;
        use std::cell::RefCell;
        struct Log<'a>(&'a RefCell<Vec<(usize, TraceRow)>>, usize);
        impl TraceSink for Log<'_> {
            fn record(&mut self, r: &TraceRow) {
                self.0.borrow_mut().push((self.1, *r));
            }
        }
        let s = parse_scenario(
            &format!(
                "{UAV}[team]\nspacing = \"range_balance\"\nk_v = 0.05\ncount = 60\n\
                 spread = {{ along = \"arc\", radius_m = 600.0, step_rad = 0.104 }}\n\
                 ranging = {{ rate_hz = 5.0, noise_std_m = 2.0, dropout_probability = 0.2, delay_s = 0.4 }}\n"
            ),
            "<test>",
            &["sim.duration_s=20.0".into(), "output.record_rate_hz=100.0".into()],
        )
        .unwrap();
        let go = |threads: usize| {
            let log = RefCell::new(Vec::new());
            let mut sinks: Vec<Log<'_>> = (0..60).map(|i| Log(&log, i)).collect();
            let split = TeamThreads {
                threads,
                min_vehicles_per_thread: 8,
            };
            assert_eq!(split.parts(60), threads);
            let r = s.run_team_threads(&mut sinks, split).unwrap().unwrap();
            drop(sinks);
            let log = log.into_inner();
            assert!(log.len() >= 60 * 2000, "{}", log.len());
            format!("{r:?}\n{log:?}")
        };
        let one = go(1);
        for threads in [2, 3, 7] {
            assert!(go(threads) == one, "{threads} threads differ from one");
        }
    }

    /// The ellipse of a single Gaussian plume, `A exp(-(u^2/sx^2 + v^2/sy^2)/2) = level`:
    /// semi-axes `s sqrt(2 ln(A/level))`. The team's isoline (marching squares over the
    /// sources' reach) has the ellipse's perimeter, by the integral of `|r'(t)|`
    /// (Simpson, 20 000 intervals), to 0.1 %.
    #[test]
    fn a_plume_ellipse_has_its_perimeter() {
        let s = parse_scenario(
            "[field]\nkind = \"gaussian_plumes\"\nsources = [{ center_m = [3.0, -2.0], amplitude = 20.0, sigma_m = [12.0, 7.0], rotation_rad = 0.5 }]\n\
             [initial]\nx_m = 17.0\ny_m = 5.0\n[controller]\nlevel = 10.0\n",
            "<test>",
            &[],
        )
        .unwrap();
        let k = (2.0 * 2f64.ln()).sqrt();
        let (a, b) = (12.0 * k, 7.0 * k);
        let n = 20_000;
        let speed = |t: f64| (a * a * t.sin().powi(2) + b * b * t.cos().powi(2)).sqrt();
        let h = 2.0 * std::f64::consts::PI / n as f64;
        let per = (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * speed(i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0;
        match s.team_isoline() {
            TeamIsolineModel::Polyline(p) => {
                assert!(
                    (p.length_m() / per - 1.0).abs() < 1e-3,
                    "{} vs {per}",
                    p.length_m()
                );
                assert!(p.twice_signed_area_m2() > 0.0);
                // The ellipse's area pi a b, to the polygon's.
                let area = 0.5 * p.twice_signed_area_m2();
                let want = std::f64::consts::PI * a * b;
                assert!((area / want - 1.0).abs() < 2e-3, "{area} vs {want}");
            }
            _ => panic!("no polyline"),
        }
        // A linear ramp's isoline is a straight line: no closed isoline, an open one (cut by
        // the box the vehicle can reach).
        let s = parse_scenario(
            "[field]\nkind = \"linear_ramp\"\noffset = 0.0\ngradient_per_m = [1.0, 0.0]\n",
            "<test>",
            &[],
        )
        .unwrap();
        assert!(s.team_isoline().is_open());
    }

    /// A domain that holds the whole circle (att32f-7): the paper's radial field with
    /// `field.domain_m` = [-20, 20]^2 around its level-10 circle (radius 10 ln 2 = 6.93 m) is
    /// measured along the exact circle, as without a domain (it was a marching-squares polyline,
    /// its metrics within the lattice's error of these), and the team, which never nears the
    /// domain's edge, flies the same run: the same team metrics to the last bit.
    #[test]
    fn a_circle_inside_the_domain_gives_the_circle_metrics() {
        let base = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/team-circular-4.toml"
        ))
        .unwrap();
        let circle = parse_scenario(&base, "<test>", &["sim.duration_s=200".into()]).unwrap();
        let inside = parse_scenario(
            &base,
            "<test>",
            &[
                "sim.duration_s=200".into(),
                "field.domain_m=[-20.0, 20.0, -20.0, 20.0]".into(),
            ],
        )
        .unwrap();
        assert!(matches!(circle.team_isoline(), TeamIsolineModel::Circle(_)));
        assert!(matches!(inside.team_isoline(), TeamIsolineModel::Circle(_)));
        let go = |s: &Scenario| {
            s.run_team(&mut [] as &mut [Vec<TraceRow>])
                .unwrap()
                .unwrap()
                .team
                .unwrap()
        };
        let (tc, ti) = (go(&circle), go(&inside));
        assert_eq!(tc.gap_cv, ti.gap_cv);
        assert_eq!(tc.revisit_time_max_s, ti.revisit_time_max_s);
        assert_eq!(tc.time_to_even_s, ti.time_to_even_s);
        assert!(tc.gap_cv.is_some() && tc.revisit_time_max_s.is_some());
    }

    /// att32 and the volcano task's 135.1 m: the DEM's integer elevations (and their
    /// interpolated quarter steps) put the levels 134.5, 135 and 135.5 m exactly on samples of
    /// the refined lattice, where the ends of marching squares' segments meet several at one
    /// point and a stitch by distance lost the loop. Joined by their lattice edges (the tie
    /// rule of `isotrack_fields::isoline`), each closes; the isoline's length is continuous in
    /// the level, so each is within 1 % of the loops at the untied levels either side
    /// (134.45/134.55, 134.95/135.05, 135.45/135.55 m), whose extraction has no tie.
    #[test]
    fn volcano_contours_at_lattice_levels_close() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/volcano.toml");
        let length = |level: f64| {
            let s = crate::load_scenario(
                Some(std::path::Path::new(path)),
                &[
                    format!("controller.level={level:?}"),
                    "team.count=6".into(),
                    "team.spread={ along = \"line\", step_m = 10.0 }".into(),
                ],
            )
            .unwrap();
            match s.team_isoline() {
                TeamIsolineModel::Polyline(p) => p.length_m(),
                _ => panic!("no closed loop at {level} m"),
            }
        };
        for tied in [134.5, 135.0, 135.5] {
            let l = length(tied);
            for near in [tied - 0.05, tied + 0.05] {
                let m = length(near);
                assert!(
                    (l / m - 1.0).abs() < 0.01,
                    "{tied} m: {l} m vs {near} m: {m} m"
                );
            }
        }
    }
}
