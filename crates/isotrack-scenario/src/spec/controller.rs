//! `[controller]`: the law with its typed parameters, the output stage (the turn-rate limit in
//! force, given or derived) and the search flown before tracking.

use super::{settled, VehicleSpec};
use crate::issue::Issue;
use crate::schema::{
    AntiWindupKind, ControllerKind, ControllerSection, DerivativeKindName, SearchKind,
};
use isotrack_core::control::{
    AntiWindup, GradientReferenceParams, OutputStage, PiIsolineParams, PidCrossingParams,
    PidParams, SearchParams, SearchPattern, SlidingModeParams, SuboptimalSosmParams,
};
use isotrack_core::estimate::DerivativeKind;
use isotrack_core::numtext::{Echo, Num, NumDown};

/// Default `controller.level`, field units: the paper's Fig. 2(b) setting (Dong & You).
pub const LEVEL: f64 = 10.0;
/// Default `kp` of `pi_isoline` (paper Fig. 2(b)).
pub const PI_KP: f64 = 10.0;
/// Default `ki` of `pi_isoline` (paper Fig. 2(b)).
pub const PI_KI: f64 = 1.0;
/// Default `c1` of `pi_isoline`, field units per second (paper Fig. 2(b)).
pub const PI_C1: f64 = 0.2;
/// Default `c2` of `pi_isoline`, field units (paper Fig. 2(b)).
pub const PI_C2: f64 = 1.0;
/// Default `kp` of `pid`/`pid_crossing`: the linearisation of the default PI-like law,
/// `kp*c1/c2 + ki` = 10*0.2/1 + 1 = 3.
pub const PID_KP: f64 = 3.0;
/// Default `ki` of `pid`/`pid_crossing`: `ki*c1/c2` = 1*0.2/1 = 0.2.
pub const PID_KI: f64 = 0.2;
/// Default `kd` of `pid`/`pid_crossing`: `kp` of the PI-like law, 10.
pub const PID_KD: f64 = 10.0;
/// Default `gamma` of `sliding_mode(_smooth)`, 1/s (Matveev et al., reconstructed).
pub const SM_GAMMA: f64 = 0.2;
/// Default `delta` of `sliding_mode(_smooth)`, field units.
pub const SM_DELTA: f64 = 1.0;
/// Default `boundary_layer` of `sliding_mode_smooth`, field units per second.
pub const SM_BOUNDARY_LAYER: f64 = 0.05;
/// Default `max_turn_rate_radps` of the bang-bang laws (`sliding_mode(_smooth)`,
/// `suboptimal_sosm`): their amplitude `u_max`, rad/s.
pub const BANG_BANG_U_MAX_RADPS: f64 = 1.0;
/// Default `alpha_star` of `suboptimal_sosm` (Bartolini's modulation factor, in (0, 1]).
pub const SOSM_ALPHA_STAR: f64 = 0.5;
/// Default `crossing_angle_rad` of `pid_crossing` (Newaz et al., reconstructed).
pub const CROSSING_ANGLE_RAD: f64 = 0.3;
/// Default `crossing_period_s` of `pid_crossing`.
pub const CROSSING_PERIOD_S: f64 = 20.0;
/// Default `crossing_turn_rate_radps` of `pid_crossing` without a `max_turn_rate_radps` (with
/// one, that limit).
pub const CROSSING_TURN_RATE_RADPS: f64 = 0.5;
/// Default `ke` of `gradient_reference`, 1/m.
pub const GR_KE: f64 = 0.5;
/// Default `k_heading` of `gradient_reference`, 1/s.
pub const GR_K_HEADING: f64 = 1.0;
/// Default `tracking_time_s` of the back-calculation anti-windup, s.
pub const TRACKING_TIME_S: f64 = 1.0;
/// Default `derivative_tau_s` of the filtered difference, s.
pub const DERIVATIVE_TAU_S: f64 = 0.1;
/// Default `derivative_lipschitz` of Levant's differentiator, field units/s^2.
pub const DERIVATIVE_LIPSCHITZ: f64 = 1.0;
/// The turn rate a search plans with when no limit is in force, rad/s (its spacing is the
/// turning diameter `2*v/omega`).
pub const SEARCH_TURN_RATE_RADPS: f64 = 1.0;
/// Default lawnmower leg, in spacings.
pub const SEARCH_LEG_SPACINGS: f64 = 10.0;

/// 1 % of `|level|`, or 0.01 for level 0: the default of `metrics.convergence_tolerance` and
/// `controller.search_handover`.
pub fn one_percent_of_level(level: f64) -> f64 {
    if level != 0.0 && level.is_finite() {
        0.01 * level.abs()
    } else {
        0.01
    }
}

/// The turn-rate limit of every law's output stage, and where it comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TurnRateLimit {
    /// No limit (`controller.max_turn_rate_radps` unset on the Dubins robot).
    None,
    /// `controller.max_turn_rate_radps`, rad/s (given, or the bang-bang laws' default
    /// amplitude).
    Given(f64),
    /// Derived from the fixed-wing airframe, `g*tan(phi_max)/V` rad/s (`phi_max` the
    /// autopilot's 40 deg bank limit, `V` the airspeed): not written into the resolved file,
    /// since it follows the airspeed a sweep or `--set` may change.
    Airframe(f64),
}

impl TurnRateLimit {
    /// The limit, rad/s, if any.
    pub fn radps(self) -> Option<f64> {
        match self {
            TurnRateLimit::None => None,
            TurnRateLimit::Given(w) | TurnRateLimit::Airframe(w) => Some(w),
        }
    }
}

/// A law with its parameters (the core crate's own parameter types; each holds the level, the
/// output stage and, where the law differentiates the measurement, the estimator).
#[derive(Clone, Debug, PartialEq)]
pub enum LawSpec {
    /// `pi_isoline`.
    PiIsoline(PiIsolineParams),
    /// `sliding_mode` (`boundary_layer` `None`) and `sliding_mode_smooth` (`Some`).
    SlidingMode(SlidingModeParams),
    /// `suboptimal_sosm`.
    SuboptimalSosm(SuboptimalSosmParams),
    /// `pid`.
    Pid(PidParams),
    /// `pid_crossing`.
    PidCrossing(PidCrossingParams),
    /// `gradient_reference`.
    GradientReference(GradientReferenceParams),
    /// `schedule`: `[t_s, omega_radps]` pairs.
    Schedule(Vec<[f64; 2]>),
}

/// `[controller]` resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerSpec {
    /// The kind (`sliding_mode` and `sliding_mode_smooth` share [`LawSpec::SlidingMode`]).
    pub kind: ControllerKind,
    /// The level `s_d` tracked, field units.
    pub level: f64,
    /// The turn-rate limit in force (also in the law's output stage).
    pub turn_rate_limit: TurnRateLimit,
    /// The law.
    pub law: LawSpec,
    /// The search flown before tracking, its derived geometry applied (`None`:
    /// `controller.search = "none"`).
    pub search: Option<SearchParams>,
}

impl ControllerSpec {
    /// From a resolved `[controller]`, the resolved vehicle (its speed sets the search geometry)
    /// and the airframe's own turn-rate limit (`None` for the Dubins robot).
    pub fn new(
        c: &ControllerSection,
        vehicle: &VehicleSpec,
        airframe_turn_rate_limit_radps: Option<f64>,
    ) -> Result<Self, Issue> {
        let kind = settled(&c.kind, "controller.kind")?;
        let level = settled(&c.level, "controller.level")?;
        let turn_rate_limit = match (c.max_turn_rate_radps, airframe_turn_rate_limit_radps) {
            (Some(w), _) => TurnRateLimit::Given(w),
            (None, Some(w)) => TurnRateLimit::Airframe(w),
            (None, None) => TurnRateLimit::None,
        };
        // A schedule is flown open loop: on the fixed wing an entry beyond the airframe's
        // own limit would fly a turn the airframe cannot (5 rad/s against 0.274 rad/s at
        // 30 m/s), as a given limit is refused at resolution (issue 30, att30c-5).
        if let (ControllerKind::Schedule, TurnRateLimit::Airframe(l)) = (kind, turn_rate_limit) {
            let entries = c.course_rate_radps.as_deref().unwrap_or_default();
            if let Some((i, [_, w])) = entries.iter().enumerate().find(|(_, e)| e[1].abs() > l) {
                return Err(Issue {
                    key: format!("controller.course_rate_radps[{i}]"),
                    message: format!(
                        "turn rate {} rad/s exceeds the fixed wing's own limit g*tan(40 deg)/V = {} rad/s at vehicle.airspeed_mps = {} m/s, the limit every controller keeps: give |omega| <= {} or fly faster",
                        Echo(*w),
                        Num(l),
                        Echo(vehicle.speed_mps()),
                        NumDown(l)
                    ),
                    unreadable: false,
                });
            }
        }
        let output = OutputStage {
            higher_side: settled(&c.higher_side, "controller.higher_side")?,
            max_turn_rate_radps: turn_rate_limit.radps(),
        };
        let law = law(c, kind, level, output)?;
        let search = search(c, level, vehicle.speed_mps(), turn_rate_limit)?;
        Ok(Self {
            kind,
            level,
            turn_rate_limit,
            law,
            search,
        })
    }

    /// The PI-like law's parameters, if the law is `pi_isoline`.
    pub fn pi_isoline(&self) -> Option<&PiIsolineParams> {
        match &self.law {
            LawSpec::PiIsoline(p) => Some(p),
            _ => None,
        }
    }

    /// The derivative estimator of the laws that differentiate the measurement.
    pub fn derivative(&self) -> Option<DerivativeKind> {
        match &self.law {
            LawSpec::PiIsoline(p) => Some(p.derivative),
            LawSpec::SlidingMode(p) => Some(p.derivative),
            LawSpec::SuboptimalSosm(p) => Some(p.derivative),
            LawSpec::Pid(p) => Some(p.derivative),
            LawSpec::PidCrossing(p) => Some(p.pid.derivative),
            LawSpec::GradientReference(_) | LawSpec::Schedule(_) => None,
        }
    }
}

/// The estimator of `eps'` (`controller.derivative*`).
fn derivative(c: &ControllerSection) -> Result<DerivativeKind, Issue> {
    Ok(match settled(&c.derivative, "controller.derivative")? {
        DerivativeKindName::BackwardDifference => DerivativeKind::BackwardDifference,
        DerivativeKindName::FilteredDifference => DerivativeKind::FilteredDifference {
            tau_s: settled(&c.derivative_tau_s, "controller.derivative_tau_s")?,
        },
        DerivativeKindName::Levant => DerivativeKind::Levant {
            lipschitz: settled(&c.derivative_lipschitz, "controller.derivative_lipschitz")?,
        },
    })
}

fn anti_windup(c: &ControllerSection) -> Result<AntiWindup, Issue> {
    Ok(match settled(&c.anti_windup, "controller.anti_windup")? {
        AntiWindupKind::None => AntiWindup::None,
        AntiWindupKind::Clamp => AntiWindup::Clamp {
            limit_radps: settled(&c.integral_limit_radps, "controller.integral_limit_radps")?,
        },
        AntiWindupKind::Conditional => AntiWindup::Conditional {
            band: settled(&c.integral_band, "controller.integral_band")?,
        },
        AntiWindupKind::BackCalculation => AntiWindup::BackCalculation {
            tracking_time_s: settled(&c.tracking_time_s, "controller.tracking_time_s")?,
        },
    })
}

/// The law of `kind` with its resolved gains.
fn law(
    c: &ControllerSection,
    kind: ControllerKind,
    level: f64,
    output: OutputStage,
) -> Result<LawSpec, Issue> {
    let key = |name: &str| format!("controller.{name}");
    let pid = |c: &ControllerSection| -> Result<PidParams, Issue> {
        Ok(PidParams {
            level,
            kp: settled(&c.kp, &key("kp"))?,
            ki: settled(&c.ki, &key("ki"))?,
            kd: settled(&c.kd, &key("kd"))?,
            output,
            derivative: derivative(c)?,
        })
    };
    // The bang-bang laws' amplitude: the limit in force (given, or the fixed wing's airframe
    // limit; resolution sets 1 rad/s for the Dubins robot without one).
    let amplitude = || match output.max_turn_rate_radps {
        Some(w) => Ok(w),
        None => settled(&c.max_turn_rate_radps, &key("max_turn_rate_radps")),
    };
    let sliding = |boundary_layer| -> Result<SlidingModeParams, Issue> {
        Ok(SlidingModeParams {
            level,
            max_turn_rate_radps: amplitude()?,
            gamma: settled(&c.gamma, &key("gamma"))?,
            delta: settled(&c.delta, &key("delta"))?,
            boundary_layer,
            output,
            derivative: derivative(c)?,
        })
    };
    Ok(match kind {
        ControllerKind::PiIsoline => LawSpec::PiIsoline(PiIsolineParams {
            level,
            kp: settled(&c.kp, &key("kp"))?,
            ki: settled(&c.ki, &key("ki"))?,
            c1: settled(&c.c1, &key("c1"))?,
            c2: settled(&c.c2, &key("c2"))?,
            output,
            anti_windup: anti_windup(c)?,
            derivative: derivative(c)?,
        }),
        ControllerKind::SlidingMode => LawSpec::SlidingMode(sliding(None)?),
        ControllerKind::SlidingModeSmooth => LawSpec::SlidingMode(sliding(Some(settled(
            &c.boundary_layer,
            &key("boundary_layer"),
        )?))?),
        ControllerKind::SuboptimalSosm => LawSpec::SuboptimalSosm(SuboptimalSosmParams {
            level,
            max_turn_rate_radps: amplitude()?,
            alpha_star: settled(&c.alpha_star, &key("alpha_star"))?,
            output,
            derivative: derivative(c)?,
        }),
        ControllerKind::Pid => LawSpec::Pid(pid(c)?),
        ControllerKind::PidCrossing => LawSpec::PidCrossing(PidCrossingParams {
            pid: pid(c)?,
            crossing_angle_rad: settled(&c.crossing_angle_rad, &key("crossing_angle_rad"))?,
            crossing_period_s: settled(&c.crossing_period_s, &key("crossing_period_s"))?,
            turn_rate_radps: settled(
                &c.crossing_turn_rate_radps,
                &key("crossing_turn_rate_radps"),
            )?,
        }),
        ControllerKind::GradientReference => LawSpec::GradientReference(GradientReferenceParams {
            level,
            ke: settled(&c.ke, &key("ke"))?,
            k_heading: settled(&c.k_heading, &key("k_heading"))?,
            output,
        }),
        ControllerKind::Schedule => {
            LawSpec::Schedule(settled(&c.course_rate_radps, &key("course_rate_radps"))?)
        }
    })
}

/// The search before tracking with its derived geometry: spacing the minimum turning diameter
/// `2*v/omega_max` (`omega_max` the turn-rate limit in force, [`SEARCH_TURN_RATE_RADPS`]
/// without one), lawnmower legs [`SEARCH_LEG_SPACINGS`] spacings, hand-over at
/// [`one_percent_of_level`]. `None` without a search.
fn search(
    c: &ControllerSection,
    level: f64,
    speed_mps: f64,
    limit: TurnRateLimit,
) -> Result<Option<SearchParams>, Issue> {
    let w_max = limit.radps().unwrap_or(SEARCH_TURN_RATE_RADPS);
    let spacing_m = c.search_spacing_m.unwrap_or(2.0 * speed_mps / w_max);
    let pattern = match settled(&c.search, "controller.search")? {
        SearchKind::None => return Ok(None),
        SearchKind::Spiral => SearchPattern::Spiral {
            spacing_m,
            speed_mps,
            max_turn_rate_radps: w_max,
        },
        SearchKind::Lawnmower => {
            // The half-turns fly `2 v / spacing` open loop, past the output stage: under a
            // turn-rate limit `L` that is a turn the vehicle cannot fly (and a run whose
            // control effort exceeds `L^2` per second), so a spacing below the turning
            // diameter `2 v / L` is refused (the default spacing is that diameter; the
            // tolerance covers its rounding).
            if let Some(l) = limit.radps() {
                let turn_radps = 2.0 * speed_mps / spacing_m;
                if turn_radps > l * (1.0 + 1e-9) {
                    return Err(Issue {
                        key: "controller.search_spacing_m".to_string(),
                        message: format!(
                            "the lawnmower's half-turns at 2 v / search_spacing_m = 2 x {} m/s / {} m = {} rad/s exceed the turn-rate limit {} rad/s (controller.max_turn_rate_radps or the airframe's): give search_spacing_m >= 2 v / limit = {} m",
                            Echo(speed_mps),
                            Echo(spacing_m),
                            Num(turn_radps),
                            Echo(l),
                            Num(2.0 * speed_mps / l)
                        ),
                        unreadable: false,
                    });
                }
            }
            SearchPattern::Lawnmower {
                leg_m: c.search_leg_m.unwrap_or(SEARCH_LEG_SPACINGS * spacing_m),
                spacing_m,
                speed_mps,
            }
        }
    };
    Ok(Some(SearchParams {
        pattern,
        handover_delta: c.search_handover.unwrap_or(one_percent_of_level(level)),
    }))
}
