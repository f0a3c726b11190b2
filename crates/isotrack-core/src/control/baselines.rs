//! The methods Dong & You compare themselves with, as baselines behind the same trait.
//!
//! Each law is stated with its inputs, its source and how far it is trusted
//! (docs/BASELINES.md): **verified** means checked in the primary text,
//! **reconstructed** means rebuilt from abstracts and secondary sources. Every law is written
//! for [`HigherSide::Right`](super::HigherSide) (the paper's convention) and goes through the
//! shared [`OutputStage`] (direction and turn-rate limit); every `eps'` comes from the shared
//! [`DerivativeEstimator`].

use super::{GroundTruth, IsolineController, Measurement, OutputStage};
use crate::estimate::{DerivativeEstimator, DerivativeKind};
use crate::math::{wrap_angle, Vec2};

fn sgn(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Parameters of [`SlidingMode`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlidingModeParams {
    /// Desired level `s0`.
    pub level: f64,
    /// Maximum turn rate `u_max`, rad/s (> 0): the law's output magnitude.
    pub max_turn_rate_radps: f64,
    /// Slope `gamma` of the saturated-linear `chi`, 1/s (> 0).
    pub gamma: f64,
    /// Linear zone `delta` of `chi`, field units (> 0); `mu = gamma*delta`.
    pub delta: f64,
    /// `None`: the discontinuous law. `Some(phi)`: a boundary layer of width `phi` (field units
    /// per second), `sgn(sigma) -> sat(sigma/phi)`.
    pub boundary_layer: Option<f64>,
    /// Turning direction (the limit is `max_turn_rate_radps` itself).
    pub output: OutputStage,
    /// Estimator for `s'`.
    pub derivative: DerivativeKind,
}

/// Matveev, Teimoori & Savkin's sliding-mode level-set law (Automatica 48(9), 2012;
/// **reconstructed**, structure verified in their 2011 Automatica paper):
///
/// ```text
/// omega = u_max * sgn(s' + chi(s - s0)),
/// chi(z) = gamma*z for |z| <= delta, gamma*delta*sgn(z) otherwise.
/// ```
///
/// Inputs: `s` and `s'` only. With a boundary layer (`sliding_mode_smooth`) `sgn` becomes
/// `sat(sigma/phi)`: continuous, *not* the paper's law; it separates "discontinuity" from
/// "structure". Works when `u_max` exceeds the isoline's curvature demand `v/r` and
/// `mu = gamma*delta < v*inf|grad F|` (baselines.md section 1).
#[derive(Clone, Debug)]
pub struct SlidingMode {
    p: SlidingModeParams,
    d: DerivativeEstimator,
}

impl SlidingMode {
    /// A controller at rest.
    pub fn new(p: SlidingModeParams) -> Self {
        Self {
            d: DerivativeEstimator::new(p.derivative),
            p,
        }
    }
}

impl IsolineController for SlidingMode {
    fn update(&mut self, m: &Measurement) -> f64 {
        let p = &self.p;
        let eps = m.value - p.level;
        let s_dot = self.d.update(m.t_s, m.value);
        let chi = if eps.abs() <= p.delta {
            p.gamma * eps
        } else {
            p.gamma * p.delta * sgn(eps)
        };
        let sigma = s_dot + chi;
        let u = match p.boundary_layer {
            None => sgn(sigma),
            Some(phi) => (sigma / phi).clamp(-1.0, 1.0),
        };
        let u = if u.is_finite() { u } else { 0.0 };
        let out = OutputStage {
            max_turn_rate_radps: Some(p.max_turn_rate_radps),
            ..p.output
        };
        out.apply(p.max_turn_rate_radps * u)
    }
    fn reset(&mut self) {
        self.d.reset();
    }
}

/// Parameters of [`SuboptimalSosm`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SuboptimalSosmParams {
    /// Desired level `s_d`.
    pub level: f64,
    /// Control amplitude `U`, rad/s (> 0).
    pub max_turn_rate_radps: f64,
    /// Modulation factor `alpha*` in `(0, 1]`.
    pub alpha_star: f64,
    /// Turning direction.
    pub output: OutputStage,
    /// Estimator for `sigma'`, whose sign changes mark the extrema of `sigma`.
    pub derivative: DerivativeKind,
}

/// Bartolini, Ferrara & Usai's suboptimal second-order sliding mode (IEEE TAC 43(2), 1998) on
/// `sigma = s - s_d`, as used for boundary tracking by Mellucci, Menon, Edwards & Challenor
/// (ACC 2017, IEEE TCST 2019; **reconstructed**):
///
/// ```text
/// omega = alpha(t) * U * sgn(sigma - sigma_M/2),
/// alpha = alpha* if (sigma - sigma_M/2)(sigma_M - sigma) > 0, else 1,
/// ```
///
/// `sigma_M` the value of `sigma` at its last extremum (a sign change of the estimated
/// `sigma'`), initially `sigma(0)`. The sign is the one for `g = v grad F . h_perp < 0` (higher
/// values on the right). Inputs: `s` and the sign of `s'`.
#[derive(Clone, Debug)]
pub struct SuboptimalSosm {
    p: SuboptimalSosmParams,
    d: DerivativeEstimator,
    sigma_m: Option<f64>,
    last_dsign: f64,
    last_sigma: f64,
}

impl SuboptimalSosm {
    /// A controller at rest.
    pub fn new(p: SuboptimalSosmParams) -> Self {
        Self {
            d: DerivativeEstimator::new(p.derivative),
            p,
            sigma_m: None,
            last_dsign: 0.0,
            last_sigma: 0.0,
        }
    }
}

impl IsolineController for SuboptimalSosm {
    fn update(&mut self, m: &Measurement) -> f64 {
        let p = &self.p;
        let sigma = m.value - p.level;
        let ds = self.d.update(m.t_s, sigma);
        let dsign = sgn(ds);
        let sm = *self.sigma_m.get_or_insert(sigma);
        let sm = if dsign != 0.0 && self.last_dsign != 0.0 && dsign != self.last_dsign {
            // sigma' changed sign between the last two samples: an extremum at about the
            // previous sample.
            self.sigma_m = Some(self.last_sigma);
            self.last_sigma
        } else {
            sm
        };
        if dsign != 0.0 {
            self.last_dsign = dsign;
        }
        self.last_sigma = sigma;
        let alpha = if (sigma - 0.5 * sm) * (sm - sigma) > 0.0 {
            p.alpha_star
        } else {
            1.0
        };
        let out = OutputStage {
            max_turn_rate_radps: Some(p.max_turn_rate_radps),
            ..p.output
        };
        out.apply(alpha * p.max_turn_rate_radps * sgn(sigma - 0.5 * sm))
    }
    fn reset(&mut self) {
        self.d.reset();
        self.sigma_m = None;
        self.last_dsign = 0.0;
        self.last_sigma = 0.0;
    }
}

/// Parameters of [`Pid`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidParams {
    /// Desired level `s_d`.
    pub level: f64,
    /// Proportional gain on `eps`, rad/s per field unit.
    pub kp: f64,
    /// Integral gain, rad/s^2 per field unit.
    pub ki: f64,
    /// Derivative gain on `eps'`, rad per field unit.
    pub kd: f64,
    /// Direction and optional limit.
    pub output: OutputStage,
    /// Estimator for `eps'`.
    pub derivative: DerivativeKind,
}

/// A linear PID on `eps` (an ablation of Dong & You's law: their `e` with `tanh` replaced by its
/// linearisation; baselines.md section 6, **our baseline**):
///
/// ```text
/// omega = kd*eps' + kp*eps + ki*integral(eps dt).
/// ```
///
/// With `kd = kp_DY`, `kp = kp_DY*c1/c2 + ki_DY`, `ki = ki_DY*c1/c2` it is the linearisation of
/// the PI-like law about the isoline. Far from the isoline it asks for `|eps'| > v|grad F|`, which
/// the vehicle cannot deliver: that is what the `tanh` saturation is for.
#[derive(Clone, Debug)]
pub struct Pid {
    p: PidParams,
    d: DerivativeEstimator,
    integral: f64,
    last_t: Option<f64>,
}

impl Pid {
    /// A controller at rest.
    pub fn new(p: PidParams) -> Self {
        Self {
            d: DerivativeEstimator::new(p.derivative),
            p,
            integral: 0.0,
            last_t: None,
        }
    }
    /// The raw (pre-output-stage) PID value for a sample.
    fn raw(&mut self, m: &Measurement) -> (f64, f64) {
        let eps = m.value - self.p.level;
        let eps_dot = self.d.update(m.t_s, eps);
        let dt = self.last_t.map_or(0.0, |t0| (m.t_s - t0).max(0.0));
        self.last_t = Some(m.t_s);
        if eps.is_finite() {
            self.integral += dt * eps;
        }
        (
            self.p.kd * eps_dot + self.p.kp * eps + self.p.ki * self.integral,
            eps,
        )
    }
}

impl IsolineController for Pid {
    fn update(&mut self, m: &Measurement) -> f64 {
        let (u, _) = self.raw(m);
        let w = self.p.output.apply(u);
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }
    fn reset(&mut self) {
        self.d.reset();
        self.integral = 0.0;
        self.last_t = None;
    }
}

/// Parameters of [`PidCrossing`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PidCrossingParams {
    /// The PID underneath.
    pub pid: PidParams,
    /// Initial crossing angle `beta_0`, rad (> 0).
    pub crossing_angle_rad: f64,
    /// Target time between crossings `T*`, s (> 0).
    pub crossing_period_s: f64,
    /// Turn rate used to execute the crossing turn, rad/s (> 0).
    pub turn_rate_radps: f64,
}

/// PID with adaptive crossing-angle correction, after Newaz, Jeong & Chong (J. Intell. Robot.
/// Syst. 90, 2018; **reconstructed, low confidence**: only the citation was available).
///
/// Between crossings the [`Pid`] steers. At each crossing of the level (a sign change of `eps`)
/// the vehicle adds a turn of `beta_k` back towards the isoline (left after a low-to-high
/// crossing, right after high-to-low, for higher values on the right), executed open-loop at
/// `turn_rate_radps` (the controller knows its own commands, not its heading). The angle adapts
/// to the time `T_k` since the previous crossing: `beta_{k+1} = clamp(beta_k*sqrt(T_k/T*), 0.02,
/// 1.5)`: frequent crossings mean a too-steep zig-zag. Inputs: `s` only.
#[derive(Clone, Debug)]
pub struct PidCrossing {
    p: PidCrossingParams,
    pid: Pid,
    beta: f64,
    last_sign: f64,
    last_cross_t: Option<f64>,
    /// Remaining turn `(angle left, direction)`.
    kick: Option<(f64, f64)>,
    last_t: Option<f64>,
}

impl PidCrossing {
    /// A controller at rest.
    pub fn new(p: PidCrossingParams) -> Self {
        Self {
            pid: Pid::new(p.pid),
            beta: p.crossing_angle_rad,
            p,
            last_sign: 0.0,
            last_cross_t: None,
            kick: None,
            last_t: None,
        }
    }
    /// The current crossing angle `beta_k`, rad.
    pub fn crossing_angle_rad(&self) -> f64 {
        self.beta
    }
}

impl IsolineController for PidCrossing {
    fn update(&mut self, m: &Measurement) -> f64 {
        let (u, eps) = self.pid.raw(m);
        let dt = self.last_t.map_or(0.0, |t0| (m.t_s - t0).max(0.0));
        self.last_t = Some(m.t_s);
        let sign = sgn(eps);
        if sign != 0.0 && self.last_sign != 0.0 && sign != self.last_sign {
            if let Some(tc) = self.last_cross_t {
                let period = (m.t_s - tc).max(1e-9);
                self.beta = (self.beta * crate::fmath::sqrt(period / self.p.crossing_period_s))
                    .clamp(0.02, 1.5);
            }
            self.last_cross_t = Some(m.t_s);
            // Now above (sign > 0): turn left, towards lower values (they lie on the left).
            self.kick = Some((self.beta, sign));
        }
        if sign != 0.0 {
            self.last_sign = sign;
        }
        let mut u = u;
        if let Some((left, dir)) = self.kick {
            let done = self.p.turn_rate_radps * dt;
            let remaining = left - done;
            if remaining <= 0.0 {
                self.kick = None;
            } else {
                self.kick = Some((remaining, dir));
                u += dir * self.p.turn_rate_radps;
            }
        }
        let w = self.p.pid.output.apply(u);
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }
    fn reset(&mut self) {
        self.pid.reset();
        self.beta = self.p.crossing_angle_rad;
        self.last_sign = 0.0;
        self.last_cross_t = None;
        self.kick = None;
        self.last_t = None;
    }
}

/// Parameters of [`GradientReference`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GradientReferenceParams {
    /// Desired level `s_d`.
    pub level: f64,
    /// Convergence gain `k_e` on the distance estimate `(F - s_d)/|grad F|`, 1/m (> 0).
    pub ke: f64,
    /// Heading gain `k_theta`, 1/s (> 0).
    pub k_heading: f64,
    /// Direction and optional limit.
    pub output: OutputStage,
}

/// A guiding-vector-field reference (Kapitanyuk, Proskurnikov & Cao, IEEE TCST 2018,
/// arXiv:1610.04391) that uses the **true position, heading and gradient**: **not
/// coordinate-free**, the reference for what that information would buy, not a fair competitor.
///
/// ```text
/// n = grad F/|grad F|,  tau = rot(+90 deg) n = (-n_y, n_x)  (higher values on the right),
/// m = tau - k_e * ((F - s_d)/|grad F|) * n,
/// omega = v * tau^T H tau / |grad F|  -  k_theta * wrap(theta - atan2(m)),
/// ```
///
/// the first term the feed-forward of the isoline's curvature (`H` the Hessian), so the vehicle
/// needs no heading error to follow a curved isoline.
#[derive(Clone, Debug)]
pub struct GradientReference {
    p: GradientReferenceParams,
}

impl GradientReference {
    /// The controller.
    pub fn new(p: GradientReferenceParams) -> Self {
        Self { p }
    }
}

impl IsolineController for GradientReference {
    fn update(&mut self, _m: &Measurement) -> f64 {
        0.0
    }
    fn reset(&mut self) {}
    fn needs_ground_truth(&self) -> bool {
        true
    }
    fn update_with_truth(&mut self, _m: &Measurement, t: &GroundTruth) -> f64 {
        let p = &self.p;
        let Some((g, h)) = t.derivatives.filter(|(g, _)| g.norm() > 0.0) else {
            return 0.0;
        };
        let gn = g.norm();
        let n = g * (1.0 / gn);
        // Tangent with higher values on the right (mirrored by the output stage for "left":
        // the mirrored law turns the other way, so mirror the tangent too).
        let side = p.output.higher_side.sign();
        let tau = Vec2::new(-n.y, n.x) * side;
        let dist = (t.value - p.level) / gn;
        let m = tau - n * (p.ke * dist);
        let err = wrap_angle(t.pose.heading_rad - crate::fmath::atan2(m.y, m.x));
        // Curvature feed-forward along tau (tau = side * rot90(n)): v * side * tau^T H tau / |g|.
        let tht = tau.x * (h[0][0] * tau.x + h[0][1] * tau.y)
            + tau.y * (h[1][0] * tau.x + h[1][1] * tau.y);
        let ff = t.speed_mps * side * tht / gn;
        // The output stage multiplies by `side`; undo it so the command turns towards `m`.
        let w = p.output.apply((ff - p.k_heading * err) * side);
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::HigherSide;

    fn out(limit: Option<f64>) -> OutputStage {
        OutputStage {
            higher_side: HigherSide::Right,
            max_turn_rate_radps: limit,
        }
    }

    #[test]
    fn sliding_mode_is_bang_bang_and_smooth_variant_is_not() {
        let mut p = SlidingModeParams {
            level: 10.0,
            max_turn_rate_radps: 0.5,
            gamma: 0.2,
            delta: 1.0,
            boundary_layer: None,
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        };
        let mut c = SlidingMode::new(p);
        // eps = -3 (beyond delta): chi = -0.2; s' = 0 on the first sample -> omega = -u_max.
        assert_eq!(
            c.update(&Measurement {
                t_s: 0.0,
                value: 7.0
            }),
            -0.5
        );
        // s rising at 0.3/s: sigma = 0.3 - 0.2 > 0 -> +u_max.
        assert_eq!(
            c.update(&Measurement {
                t_s: 1.0,
                value: 7.3
            }),
            0.5
        );
        p.boundary_layer = Some(1.0);
        let mut c = SlidingMode::new(p);
        c.update(&Measurement {
            t_s: 0.0,
            value: 7.0,
        });
        let w = c.update(&Measurement {
            t_s: 1.0,
            value: 7.3,
        });
        assert!((w - 0.5 * 0.1).abs() < 1e-12, "{w}");
    }

    /// The boundary-layer sliding mode by hand, inside and outside chi's linear zone:
    /// `omega = U sat((s' + chi(eps))/phi)`, `chi = gamma eps` for `|eps| <= delta`, else
    /// `gamma delta sgn(eps)` (gamma 0.3, delta 2, phi 0.5, U 0.8).
    #[test]
    fn smooth_sliding_mode_by_hand() {
        let p = SlidingModeParams {
            level: 10.0,
            max_turn_rate_radps: 0.8,
            gamma: 0.3,
            delta: 2.0,
            boundary_layer: Some(0.5),
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        };
        // eps = -0.6, s' = 0.4: sigma = 0.4 - 0.18 = 0.22, omega = 0.8 * 0.44.
        // eps = -3.5, s' = 0.5: sigma = 0.5 - 0.6 = -0.1, omega = 0.8 * -0.2.
        for (v0, v1, want) in [(9.0, 9.4, 0.8 * 0.44), (6.0, 6.5, 0.8 * -0.2)] {
            let mut c = SlidingMode::new(p);
            c.update(&Measurement {
                t_s: 0.0,
                value: v0,
            });
            let w = c.update(&Measurement {
                t_s: 1.0,
                value: v1,
            });
            assert!((w - want).abs() < 1e-12, "{v0} -> {v1}: {w} vs {want}");
        }
    }

    /// The suboptimal SOSM's first command: `alpha = 1` (no extremum yet), so
    /// `omega = U sgn(sigma - sigma_M/2)` with `sigma_M = sigma`: the sign of the error.
    #[test]
    fn sosm_first_command_is_the_sign_of_the_error() {
        let p = SuboptimalSosmParams {
            level: 5.0,
            max_turn_rate_radps: 0.6,
            alpha_star: 0.5,
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        };
        for (value, want) in [(4.0, -0.6), (8.0, 0.6)] {
            let mut c = SuboptimalSosm::new(p);
            let w = c.update(&Measurement { t_s: 0.0, value });
            assert_eq!(w, want, "{value}");
        }
    }

    /// PID-with-crossing's kick by hand: no PID gains, a crossing from below at t = 0.1 s
    /// turns at 0.5 rad/s (towards the lower side, `+`) until 0.32 rad are done: the six
    /// samples 0.1 .. 0.6 s (0.05 rad each), then nothing; after `reset` the same again.
    #[test]
    fn crossing_kick_by_hand() {
        let mut p = pid_params();
        (p.kp, p.ki, p.kd) = (0.0, 0.0, 0.0);
        let mut c = PidCrossing::new(PidCrossingParams {
            pid: p,
            crossing_angle_rad: 0.32,
            crossing_period_s: 20.0,
            turn_rate_radps: 0.5,
        });
        let want = [0.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.0, 0.0, 0.0];
        for _ in 0..2 {
            let mut got = [f64::NAN; 10];
            for (k, g) in got.iter_mut().enumerate() {
                let value = if k == 0 { 9.0 } else { 11.0 };
                *g = c.update(&Measurement {
                    t_s: 0.1 * k as f64,
                    value,
                });
            }
            assert_eq!(got, want);
            c.reset();
        }
    }

    /// The gradient-reference law by hand in general position (every term non-zero): gradient (6, 8), Hessian
    /// [[2, 0.5], [0.5, 1]], value 25 on level 16, heading 1 rad, v = 1.5, ke = 0.5,
    /// k_heading = 0.7: n = (0.6, 0.8), tau = (-0.8, 0.6), m = tau - 0.5 * 0.9 n = (-1.07, 0.24),
    /// tau^T H tau = 1.16, omega = 1.5 * 1.16/10 - 0.7 * wrap(1 - atan2(0.24, -1.07)).
    #[test]
    fn gradient_reference_in_general_position() {
        let mut c = GradientReference::new(GradientReferenceParams {
            level: 16.0,
            ke: 0.5,
            k_heading: 0.7,
            output: out(None),
        });
        let truth = GroundTruth {
            pose: crate::math::Pose2 {
                position: Vec2::new(3.0, 4.0),
                heading_rad: 1.0,
            },
            speed_mps: 1.5,
            value: 25.0,
            derivatives: Some((Vec2::new(6.0, 8.0), [[2.0, 0.5], [0.5, 1.0]])),
        };
        let m = Measurement {
            t_s: 0.0,
            value: 25.0,
        };
        let err = 1.0 - libm::atan2(0.24, -1.07);
        let want = 1.5 * 1.16 / 10.0 - 0.7 * err;
        let got = c.update_with_truth(&m, &truth);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }

    /// A PID on level 10 with kp 2, ki 0.5, kd 3, no limit, backward difference.
    fn pid_params() -> PidParams {
        PidParams {
            level: 10.0,
            kp: 2.0,
            ki: 0.5,
            kd: 3.0,
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        }
    }

    /// The trait's default `update_lanes` (and `update_each`): each law updated in turn with its
    /// own measurement, the `None` lanes answering 0 and left alone.
    #[test]
    fn default_lane_update_is_each_law_in_turn() {
        let p = pid_params();
        let (mut a, mut b) = (Pid::new(p), Pid::new(p));
        let (mut a1, mut b1) = (Pid::new(p), Pid::new(p));
        for k in 0..4 {
            let t_s = 0.5 * k as f64;
            let ms = [
                Measurement {
                    t_s,
                    value: 12.0 - k as f64,
                },
                Measurement { t_s, value: 99.0 },
                Measurement {
                    t_s,
                    value: 7.0 + 0.5 * k as f64,
                },
            ];
            let got = Pid::update_lanes(&mut [Some(&mut a), None, Some(&mut b)], &ms);
            let want = [a1.update(&ms[0]), 0.0, b1.update(&ms[2])];
            assert_eq!(got, want, "sample {k}");
            assert!(got[0] != 0.0 && got[2] != 0.0);
            let each = crate::control::update_each(&mut [Some(&mut a1), None], &[ms[0], ms[1]]);
            let again = a.update(&ms[0]);
            assert_eq!(each, [again, 0.0]);
        }
    }

    #[test]
    fn pid_law_by_hand() {
        let mut c = Pid::new(pid_params());
        c.update(&Measurement {
            t_s: 0.0,
            value: 9.0,
        });
        let w = c.update(&Measurement {
            t_s: 0.5,
            value: 9.5,
        });
        // eps = -0.5, eps' = 1, integral = 0.5*(-0.5) = -0.25
        assert!(
            (w - (3.0 * 1.0 + 2.0 * -0.5 + 0.5 * -0.25)).abs() < 1e-12,
            "{w}"
        );
    }

    #[test]
    fn crossing_angle_adapts_to_the_crossing_period() {
        let pid = PidParams {
            level: 0.0,
            kp: 0.0,
            ki: 0.0,
            kd: 0.0,
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        };
        let mut c = PidCrossing::new(PidCrossingParams {
            pid,
            crossing_angle_rad: 0.5,
            crossing_period_s: 20.0,
            turn_rate_radps: 0.5,
        });
        // Crossings every 5 s (too often): beta shrinks by sqrt(5/20) = 0.5 per crossing.
        let mut t = 0.0;
        let mut kicks = 0;
        for k in 0..40 {
            let v = if (k / 10) % 2 == 0 { -1.0 } else { 1.0 };
            let w = c.update(&Measurement { t_s: t, value: v });
            if w != 0.0 {
                kicks += 1;
            }
            t += 0.5;
        }
        assert!(kicks > 0);
        assert!(
            (c.crossing_angle_rad() - 0.5 * 0.5 * 0.5).abs() < 1e-9,
            "{}",
            c.crossing_angle_rad()
        );
    }

    #[test]
    fn gradient_reference_turns_towards_the_field() {
        let mut c = GradientReference::new(GradientReferenceParams {
            level: 10.0,
            ke: 1.0,
            k_heading: 1.0,
            output: out(None),
        });
        assert!(c.needs_ground_truth());
        // On the isoline with higher values north, the tangent with them on the right is west.
        let truth = |heading: f64| GroundTruth {
            pose: crate::math::Pose2 {
                position: Vec2::default(),
                heading_rad: heading,
            },
            speed_mps: 1.0,
            value: 10.0,
            derivatives: Some((Vec2::new(0.0, 1.0), [[0.0; 2]; 2])),
        };
        let m = Measurement {
            t_s: 0.0,
            value: 10.0,
        };
        assert_eq!(c.update_with_truth(&m, &truth(core::f64::consts::PI)), 0.0);
        // Heading a little south of west (pi + 0.2): turn right, back to west.
        assert!(c.update_with_truth(&m, &truth(core::f64::consts::PI + 0.2)) < 0.0);
        // Heading a little north of west: turn left.
        assert!(c.update_with_truth(&m, &truth(core::f64::consts::PI - 0.2)) > 0.0);
    }

    /// The suboptimal second-order sliding mode, sample by sample by hand (level 0, u_max 1,
    /// alpha* 0.5, backward difference, dt 1 s): sigma_M is the first sample, then the sample
    /// before each sign change of sigma'; omega = alpha u_max sgn(sigma - sigma_M/2) with
    /// alpha = alpha* when (sigma - sigma_M/2)(sigma_M - sigma) > 0, else 1.
    #[test]
    fn suboptimal_sosm_by_hand() {
        let p = SuboptimalSosmParams {
            level: 0.0,
            max_turn_rate_radps: 1.0,
            alpha_star: 0.5,
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        };
        let sigmas = [1.0, 0.8, 0.5, 0.6, 0.2, 0.4, 0.35];
        // k=0: sM=1, (0.5)(0)=0 -> alpha 1, sgn(0.5) = 1.
        // k=1: sigma' < 0, sM=1, (0.3)(0.2) > 0 -> 0.5 sgn(0.3) = 0.5.
        // k=2: sM=1, sgn(0.5 - 0.5) = 0.
        // k=3: sigma' turns > 0: sM = 0.5, (0.35)(-0.1) < 0 -> sgn(0.35) = 1.
        // k=4: sigma' turns < 0: sM = 0.6, sgn(0.2 - 0.3) = -1.
        // k=5: turns > 0: sM = 0.2, sgn(0.4 - 0.1) = 1.
        // k=6: turns < 0: sM = 0.4, (0.15)(0.05) > 0 -> 0.5 sgn(0.15) = 0.5.
        let want = [1.0, 0.5, 0.0, 1.0, -1.0, 1.0, 0.5];
        let mut c = SuboptimalSosm::new(p);
        for round in 0..2 {
            for (k, (s, w)) in sigmas.iter().zip(want).enumerate() {
                let got = c.update(&Measurement {
                    t_s: k as f64,
                    value: *s,
                });
                assert_eq!(got, w, "round {round}, sample {k}");
            }
            c.reset();
        }
        // Mirrored for higher values on the left.
        let mut l = SuboptimalSosm::new(SuboptimalSosmParams {
            output: OutputStage {
                higher_side: HigherSide::Left,
                max_turn_rate_radps: None,
            },
            ..p
        });
        for (k, (s, w)) in sigmas.iter().zip(want).enumerate() {
            let got = l.update(&Measurement {
                t_s: k as f64,
                value: *s,
            });
            assert_eq!(got, -w, "left, sample {k}");
        }
    }

    /// The guiding-vector-field reference by hand: gradient g = (0, 2), Hessian diag(0.5, 0),
    /// value s_d + 1, heading 3 rad, v = 2, ke = 0.5, k_heading = 1. n = (0, 1),
    /// tau = (-1, 0), distance (s - s_d)/|g| = 0.5, m = tau - ke d n = (-1, -0.25),
    /// err = wrap(3 - atan2(-0.25, -1)), feed-forward v tau'H tau / |g| = 2 * 0.5 / 2 = 0.5,
    /// omega = 0.5 - err.
    #[test]
    fn gradient_reference_by_hand() {
        let p = GradientReferenceParams {
            level: 10.0,
            ke: 0.5,
            k_heading: 1.0,
            output: out(None),
        };
        let mut c = GradientReference::new(p);
        assert!(c.needs_ground_truth());
        let m = Measurement {
            t_s: 0.0,
            value: 11.0,
        };
        assert_eq!(c.update(&m), 0.0);
        let truth = |derivatives| GroundTruth {
            pose: crate::math::Pose2 {
                position: Vec2::new(0.0, 0.0),
                heading_rad: 3.0,
            },
            speed_mps: 2.0,
            value: 11.0,
            derivatives,
        };
        let h: crate::math::Mat2 = [[0.5, 0.0], [0.0, 0.0]];
        let w = c.update_with_truth(&m, &truth(Some((Vec2::new(0.0, 2.0), h))));
        let err = crate::math::wrap_angle(3.0 - (-0.25f64).atan2(-1.0));
        assert!((err - (3.0 - (-0.25f64).atan2(-1.0) - 2.0 * core::f64::consts::PI)).abs() < 1e-12);
        assert!((w - (0.5 - err)).abs() < 1e-12, "{w} vs {}", 0.5 - err);
        // No gradient, or a zero one: no command.
        assert_eq!(c.update_with_truth(&m, &truth(None)), 0.0);
        assert_eq!(
            c.update_with_truth(&m, &truth(Some((Vec2::new(0.0, 0.0), h)))),
            0.0
        );
        // Limited by the output stage.
        let mut lim = GradientReference::new(GradientReferenceParams {
            output: out(Some(0.1)),
            ..p
        });
        assert_eq!(
            lim.update_with_truth(&m, &truth(Some((Vec2::new(0.0, 2.0), h)))),
            0.1
        );
    }

    /// reset() returns every baseline to its first-sample behaviour.
    #[test]
    fn resets_forget_the_past() {
        let seq = [7.0, 7.4, 8.1, 9.5, 10.2, 10.1];
        let check = |c: &mut dyn IsolineController| {
            let mut first = [0.0; 6];
            for (k, v) in seq.iter().enumerate() {
                first[k] = c.update(&Measurement {
                    t_s: k as f64,
                    value: *v,
                });
            }
            c.reset();
            for (k, v) in seq.iter().enumerate() {
                let again = c.update(&Measurement {
                    t_s: 10.0 + k as f64,
                    value: *v,
                });
                assert_eq!(again, first[k], "sample {k}");
            }
        };
        check(&mut SlidingMode::new(SlidingModeParams {
            level: 10.0,
            max_turn_rate_radps: 0.5,
            gamma: 0.2,
            delta: 1.0,
            boundary_layer: Some(0.05),
            output: out(None),
            derivative: DerivativeKind::FilteredDifference { tau_s: 1.0 },
        }));
        check(&mut Pid::new(PidParams {
            level: 10.0,
            kp: 3.0,
            ki: 0.2,
            kd: 10.0,
            output: out(None),
            derivative: DerivativeKind::BackwardDifference,
        }));
    }
}
