//! The loop a scenario's law is checked with, shared by `check` ([`super::check`]), the
//! stability chart ([`super::map`]) and the team check ([`super::team`]): the gains and speed
//! ([`Law`]), the P law's orbit on a circular field ([`PLawOrbit`]), whether a loop can be
//! computed at all ([`not_computed`]) and the sampled loop before its gain and period are applied
//! ([`LoopSetup`]). A leaf of `check`: it uses only [`super::sampled`] and [`super::regions`],
//! never the parent module.

use super::regions::Regions;
use super::sampled::{self, EstimatorModel, HeadingDynamics, SampledLoop, SensorLag};
use crate::field::FieldModel;
use crate::schema::ControllerKind;
use crate::spec::LawSpec;
use crate::vehicle::{build_vehicle, VehicleModel};
use crate::Scenario;
use isotrack_core::estimate::DerivativeKind;
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::theory::{radial_exp_isoline_radius_m, radial_exp_p_orbit, CircularOrbit};
use isotrack_fields::AnalyticKind;

/// The gains and speed the theory needs.
#[derive(Clone, Copy)]
pub(super) struct Law {
    pub(super) kp: f64,
    pub(super) ki: f64,
    pub(super) c1: f64,
    pub(super) c2: f64,
    pub(super) v: f64,
}

/// The speed the law sees: the Dubins robot's, or the UAV's airspeed (its ground speed in calm
/// air), m/s.
pub(super) fn speed_mps(s: &Scenario) -> f64 {
    s.spec().vehicle.speed_mps()
}

/// Whether the scenario flies the paper's PI-like law (the propositions and the sampled check
/// are about it; the baselines have their own conditions, [`super::baselines`]).
pub(super) fn is_pi_isoline(s: &Scenario) -> bool {
    s.spec().controller.kind == ControllerKind::PiIsoline
}

pub(super) fn law(s: &Scenario) -> Law {
    // The check models the PI-like law (`is_pi_isoline`); for another law its verdicts do not
    // apply, and it reads the PID's own `kp`, `ki`, no `c1` and a unit `c2`.
    let (kp, ki, c1, c2) = match &s.spec().controller.law {
        LawSpec::PiIsoline(p) => (p.kp, p.ki, p.c1, p.c2),
        LawSpec::Pid(p) => (p.kp, p.ki, 0.0, 1.0),
        LawSpec::PidCrossing(p) => (p.pid.kp, p.pid.ki, 0.0, 1.0),
        _ => (0.0, 0.0, 0.0, 1.0),
    };
    Law {
        kp,
        ki,
        c1,
        c2,
        v: speed_mps(s),
    }
}

/// The isoline's curvature the sampled check uses: `1/r_d` on a circular field, else 0.
pub(super) fn curvature(s: &Scenario) -> f64 {
    match s.field() {
        FieldModel::Analytic(a) => match &a.kind {
            AnalyticKind::RadialExp(r) => {
                radial_exp_isoline_radius_m(r.i0, r.decay_per_m, s.level())
                    .map_or(0.0, |rd| 1.0 / rd)
            }
            _ => 0.0,
        },
        FieldModel::Grid(_) | FieldModel::Series(_) | FieldModel::Puff(_) => 0.0,
    }
}

/// The orbit the P law (`ki = 0`) settles on in a circular field and the field's own level set
/// through it.
pub(super) struct PLawOrbit {
    /// The orbit: radius `d*` and steady error `eps*`.
    pub(super) orbit: CircularOrbit,
    /// The field's slope there, `|dF/dd| = k F(d*)`.
    pub(super) slope: f64,
}

impl PLawOrbit {
    /// The loop linearised on the orbit: the slope and the curvature `1/d*` of the level set
    /// through it (the tanh's slope there follows from the curvature,
    /// [`SampledLoop::tanh_slope`]).
    pub(super) fn operating_point(&self, l: SampledLoop) -> SampledLoop {
        SampledLoop {
            slope: self.slope,
            curvature_per_m: 1.0 / self.orbit.radius_m,
            ..l
        }
    }

    pub(super) fn note(&self) -> String {
        format!(
            "with ki = 0 the P law settles on the orbit of radius {:.4} m where eps = {:.4} (kp*c1*tanh(eps/c2) balances the orbit's turn v/d); the loop is checked there, at the field's slope {} and curvature {:.6} 1/m",
            self.orbit.radius_m,
            self.orbit.error,
            if self.slope >= 1e-3 {
                format!("{:.6}", self.slope)
            } else {
                format!("{:.4e}", self.slope)
            },
            1.0 / self.orbit.radius_m
        )
    }
}

/// The P law's orbit on a circular field ([`radial_exp_p_orbit`]): `None` with an integral
/// term, on other fields, or when no orbit exists.
pub(super) fn p_law_orbit(s: &Scenario, l: &Law) -> Option<PLawOrbit> {
    p_law_orbit_at(s, l, l.kp)
}

/// [`p_law_orbit`] with the proportional gain `kp` in place of the scenario's: the orbit moves
/// with `kp` (further out, where the field is flatter, as `kp` falls), so a `kp` scan
/// recomputes it at every `kp` it examines.
pub(super) fn p_law_orbit_at(s: &Scenario, l: &Law, kp: f64) -> Option<PLawOrbit> {
    if !circular_p_law(s, l) {
        return None;
    }
    let FieldModel::Analytic(a) = s.field() else {
        return None;
    };
    let AnalyticKind::RadialExp(r) = &a.kind else {
        return None;
    };
    let orbit = radial_exp_p_orbit(r.i0, r.decay_per_m, s.level(), l.v, kp, l.c1, l.c2)?;
    // k F(d*) from F itself, not from eps* + s_d: far out, eps* ~ -s_d and the sum cancels
    // to nothing (kp = 0.001 on the paper's field: F = 5e-108, the sum 0).
    Some(PLawOrbit {
        orbit,
        slope: r.decay_per_m * r.i0 * (-r.decay_per_m * orbit.radius_m).exp(),
    })
}

/// Whether the loop is the P law (`ki = 0`) on a circular field, where it settles on an orbit
/// off the isoline rather than on it.
pub(super) fn circular_p_law(s: &Scenario, l: &Law) -> bool {
    l.ki == 0.0
        && matches!(s.field(), FieldModel::Analytic(a) if matches!(a.kind, AnalyticKind::RadialExp(_)))
}

/// The largest loop gain `kp v T max(alpha, 1) max(c1, 1) / min(c2, 1)` a cell is computed at:
/// beyond it the sampled matrices' products leave `f64` (`kp = 1e308` overflowed to an
/// infinite radius, labelled "no equilibrium" by mistake), and the cell is
/// [`super::map::CellStatus::NotComputed`] with a note, never guessed.
pub const MAX_LOOP_GAIN: f64 = 1e100;

/// The P law's orbit is examined only where its loop gain `kp*alpha*v*T` (`alpha` the field's
/// slope on the orbit) reaches this: the loop's damping per period is about half the gain
/// (`1 - rho = kp alpha v T / 2` for small gains, the continuous loop's `kp alpha v / 2` times
/// `T`), and below about `1e-8` it is within a few orders of the eigenvalues' rounding
/// (`~1e-15`): at small `kp` the orbit lies far out where the field is flat (`alpha` falls as
/// `exp(-k d*)`), and a scan that went on there fragmented the stable set into rounding noise.
pub(super) const P_ORBIT_MIN_LOOP_GAIN: f64 = 1e-8;

/// Why a loop is not computed: `check`, every cell of the chart and every `--verify` point go
/// through [`not_computed`], so they agree on what is computed (issue 29: chart cells at the
/// P law's flat orbit were coloured where `check` said "not computed").
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum NotComputed {
    /// The loop gain `kp v T max(alpha, 1) max(c1, 1) / min(c2, 1)` is past
    /// [`MAX_LOOP_GAIN`]: the sampled matrices' products leave `f64`.
    Overflow,
    /// The P law's orbit lies where the field is nearly flat: its loop gain `kp alpha v T` is
    /// below [`P_ORBIT_MIN_LOOP_GAIN`].
    FlatOrbit {
        /// `kp alpha v T` on the orbit.
        gain: f64,
    },
    /// The delay spans more than [`sampled::MAX_DELAY_STATES`] sensor periods.
    Delay {
        /// The delay, s.
        delay_s: f64,
        /// The delay in sensor periods.
        periods: f64,
    },
}

impl NotComputed {
    /// The reason in a sentence (`check`'s `not_computed`, verdict and warning).
    pub(super) fn reason(self) -> String {
        match self {
            Self::Overflow => format!(
                "the loop gain kp*v*T*max(alpha, 1)*max(c1, 1)/min(c2, 1) is beyond {:e}: the sampled matrices would overflow f64",
                MAX_LOOP_GAIN
            ),
            Self::FlatOrbit { gain } => format!(
                "the P law's orbit lies where the field is nearly flat: its loop gain kp*alpha*v*T = {gain:.3e} is below {P_ORBIT_MIN_LOOP_GAIN:e}, so its damping (about half that per period) is within rounding of zero and the spectral radius cannot tell stable from unstable"
            ),
            Self::Delay { delay_s, periods } => format!(
                "the delay of {} sensor periods ({} s) exceeds the {} periods the check models (one state each)",
                Num(periods),
                Echo(delay_s),
                sampled::MAX_DELAY_STATES
            ),
        }
    }

    /// The reason in a few words (the chart's CSV `note`).
    pub(super) fn short(self) -> &'static str {
        match self {
            Self::Overflow => "loop gain beyond 1e100: f64 would overflow",
            Self::FlatOrbit { .. } => {
                "the P law's orbit is where the field is flat: loop gain kp*alpha*v*T below 1e-8, not decided"
            }
            Self::Delay { .. } => "the delay spans more than 32 sensor periods",
        }
    }
}

/// Whether the loop `lp` (with the P law's `orbit` when it has one) can be computed, and why
/// not: the same test for `check`, the chart's cells and `--verify`.
pub(super) fn not_computed(lp: &SampledLoop, orbit: Option<&PLawOrbit>) -> Option<NotComputed> {
    let gain = lp.kp
        * lp.speed_mps.max(1.0)
        * lp.period_s.max(1.0)
        * lp.slope.abs().max(1.0)
        * lp.c1.abs().max(1.0)
        / lp.c2.abs().min(1.0);
    if gain.is_nan() || gain > MAX_LOOP_GAIN {
        return Some(NotComputed::Overflow);
    }
    if let Some(o) = orbit {
        let gain = lp.kp * o.slope * lp.speed_mps * lp.period_s;
        if gain.is_nan() || gain < P_ORBIT_MIN_LOOP_GAIN {
            return Some(NotComputed::FlatOrbit { gain });
        }
    }
    if lp.radius().is_none() {
        return Some(NotComputed::Delay {
            delay_s: lp.delay_s,
            periods: lp.delay_s / lp.period_s,
        });
    }
    None
}

/// The period, in samples, of the loop's dominant mode at `slope`: `2 pi / |arg z|` of the
/// eigenvalue `z` of largest modulus (2: the command alternates every sample; `None` for a
/// real positive `z`, a drift, or no matrix).
pub(super) fn growing_mode_period_samples(base: &SampledLoop, slope: f64) -> Option<f64> {
    SampledLoop { slope, ..*base }
        .closed_loop_matrix()
        .and_then(|m| {
            m.complex_eigenvalues()
                .iter()
                .copied()
                .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        })
        .map(|z| z.im.atan2(z.re).abs())
        .filter(|&arg| arg > 1e-9)
        .map(|arg| 2.0 * std::f64::consts::PI / arg)
}

/// The sensor's first-order lag as the simulator steps it (at `sim.dt_s`), if it has one.
pub(super) fn sensor_lag(s: &Scenario) -> Option<SensorLag> {
    let tau = s.spec().sensor.time_constant_s;
    (tau > 0.0).then(|| SensorLag {
        time_constant_s: tau,
        step_s: s.dt_s(),
    })
}

/// `count` slopes spread geometrically over `range`.
pub(super) fn spread(range: [f64; 2], count: usize) -> Vec<f64> {
    let [lo, hi] = range;
    if hi <= lo || count < 2 {
        return vec![hi];
    }
    (0..count)
        .map(|k| lo * (hi / lo).powf(k as f64 / (count - 1) as f64))
        .collect()
}

/// The sampled loop a scenario's law is checked with, before its gain and sensor period are
/// applied: the vehicle's heading dynamics, the estimator, the lag, the isoline's slopes and
/// curvature. [`super::sampled_report`] and the stability map ([`super::map`]) both go through
/// [`LoopSetup::at`]: one computation for the verdict and for every cell of the chart.
#[derive(Clone)]
pub(super) struct LoopSetup {
    /// The loop at the scenario's own gains and period, on the isoline.
    pub(super) base: SampledLoop,
    /// The isoline's slopes `[min, max]` (before the P law's orbit).
    pub(super) range: [f64; 2],
    /// The linear vehicle model's name.
    pub(super) model: &'static str,
    /// Remarks on what is modelled.
    pub(super) notes: Vec<String>,
}

impl LoopSetup {
    /// `Err(note)` when the sampled check does not apply (another law, no slope in the tube, a
    /// vehicle that cannot be built).
    pub(super) fn new(s: &Scenario, l: &Law, r: &Regions) -> Result<Self, String> {
        let f = s.file();
        if !is_pi_isoline(s) {
            return Err(
                "the sampled-data check models the PI-like law (controller.kind = \"pi_isoline\")"
                    .into(),
            );
        }
        let Some(range) = r.isoline_slope_range else {
            return Err("no slope in the tube: the level is not attained in the region".into());
        };
        let mut notes = vec![];
        let estimator = match s.spec().controller.derivative() {
            Some(DerivativeKind::BackwardDifference) | None => EstimatorModel::BackwardDifference,
            Some(DerivativeKind::FilteredDifference { tau_s }) => {
                EstimatorModel::FilteredDifference { tau_s }
            }
            Some(DerivativeKind::Levant { .. }) => {
                notes.push("Levant's differentiator is nonlinear; the check models it as the backward difference it converges to".to_string());
                EstimatorModel::BackwardDifference
            }
        };
        let (heading, model) = match build_vehicle(f) {
            Ok(VehicleModel::Dubins(_)) => (HeadingDynamics::Dubins, "dubins"),
            Ok(VehicleModel::FixedWing(w)) => (
                HeadingDynamics::CourseLoop(w.course_loop_model()),
                "fixed_wing_course_loop",
            ),
            Err(e) => return Err(format!("the vehicle cannot be built: {}", e.message)),
        };
        if s.max_turn_rate_radps().is_some() {
            notes.push("the turn-rate limit is a saturation the linear model leaves out (it holds while the limit is not reached)".into());
        }
        let base = SampledLoop {
            speed_mps: l.v,
            slope: range[1],
            curvature_per_m: curvature(s),
            kp: l.kp,
            ki: l.ki,
            c1: l.c1,
            c2: l.c2,
            period_s: 1.0 / s.spec().sensor.rate_hz,
            delay_s: s.spec().sensor.delay_s,
            estimator,
            heading,
            sensor_lag: sensor_lag(s),
        };
        Ok(Self {
            base,
            range,
            model,
            notes,
        })
    }

    /// The loop at gain `l.kp` (the rest of `l` as the scenario's) and sensor period
    /// `period_s`, with the slopes it is checked at: the isoline's own (4 spread over `range`),
    /// or with `ki = 0` on a circular field the slope and curvature of the orbit the P law
    /// settles on *at this `kp`* (returned too).
    pub(super) fn at(
        &self,
        s: &Scenario,
        l: &Law,
        period_s: f64,
    ) -> (SampledLoop, Vec<f64>, Option<PLawOrbit>) {
        let base = SampledLoop {
            kp: l.kp,
            period_s,
            ..self.base
        };
        match p_law_orbit(s, l) {
            Some(o) => (o.operating_point(base), vec![o.slope], Some(o)),
            None => (base, spread(self.range, 4), None),
        }
    }
}
