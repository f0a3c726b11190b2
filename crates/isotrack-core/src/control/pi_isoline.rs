//! Dong & You's PI-like isoline controller.

use super::{HigherSide, IsolineController, Measurement, OutputStage};
use crate::estimate::{DerivativeEstimator, DerivativeKind};

/// Anti-windup scheme for the integral state `sigma` of [`PiIsoline`].
///
/// The paper has none. Far from the isoline `tanh(eps/c2)` saturates, `e` keeps one sign for a
/// long time and `sigma` grows, and after arrival the robot must first unwind it: with `ki = 1`
/// from 20 m out on the paper's circular field this costs on the order of 1000 s (see the
/// `circular-far-start-antiwindup` scenario and README).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum AntiWindup {
    /// Integrate always (the paper's law).
    #[default]
    None,
    /// Clamp the integral action: `|ki*sigma| <= limit_radps`. A turn rate beyond the vehicle's
    /// reach, or beyond the curvature `v/r` of any isoline worth tracking, is never useful.
    Clamp {
        /// Bound on `|ki*sigma|`, rad/s (> 0).
        limit_radps: f64,
    },
    /// Conditional integration (an "integrator zone"): integrate only while `|eps| < band`, i.e.
    /// near the isoline where `tanh(eps/c2)` is not saturated; hold `sigma` elsewhere.
    Conditional {
        /// Half-width of the integration zone in field units (> 0).
        band: f64,
    },
    /// Back-calculation against the turn-rate limit:
    /// `sigma' = e + (u_sat - u)/(ki*T_t)`, `u = kp*e + ki*sigma`. Needs `max_turn_rate_radps`
    /// to have any effect. While saturated this is a leak towards
    /// `sigma_ss = T_t*e + (u_sat - kp*e)/ki` with time constant `T_t`, stepped exactly over the
    /// sample interval: `sigma <- sigma_ss + (sigma - sigma_ss)*exp(-dt/T_t)`. (Explicit Euler
    /// multiplies `sigma - sigma_ss` by `1 - dt/T_t` and diverges once `dt > 2*T_t`: the
    /// property test found NaN commands at `dt = 1.55 s`, `T_t = 0.01 s`.)
    BackCalculation {
        /// Tracking time constant `T_t`, seconds (> 0).
        tracking_time_s: f64,
    },
}

/// Parameters of [`PiIsoline`]; see its documentation for the law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PiIsolineParams {
    /// Desired level `s_d` (field units).
    pub level: f64,
    /// Proportional gain `kp > 0`, rad per field unit.
    pub kp: f64,
    /// Integral gain `ki >= 0`, rad/s per field unit.
    pub ki: f64,
    /// Sliding-surface slope limit `c1 > 0`, field units per second.
    pub c1: f64,
    /// Sliding-surface softness `c2 > 0`, field units.
    pub c2: f64,
    /// Turning direction and turn-rate limit.
    pub output: OutputStage,
    /// Anti-windup scheme.
    pub anti_windup: AntiWindup,
    /// Estimator for `eps'`.
    pub derivative: DerivativeKind,
}

impl PiIsolineParams {
    /// The paper's Fig. 2(b) gains (Table III): `kp = 10, ki = 1, c1 = 0.2, c2 = 1`, direction as
    /// printed, no limit, no anti-windup, backward difference.
    pub fn paper_fig2b(level: f64) -> Self {
        Self {
            level,
            kp: 10.0,
            ki: 1.0,
            c1: 0.2,
            c2: 1.0,
            output: OutputStage {
                higher_side: HigherSide::Right,
                max_turn_rate_radps: None,
            },
            anti_windup: AntiWindup::None,
            derivative: DerivativeKind::BackwardDifference,
        }
    }
}

/// Dong & You's coordinate-free PI-like controller (paper eqs. (2)-(3)):
///
/// ```text
/// omega = kp*e + ki*sigma,   sigma' = e,
/// e     = eps' + c1*tanh(eps/c2),   eps = s - s_d,
/// ```
///
/// in discrete time at the sensor rate: at sample `k` (time `t_k`, interval `T_k = t_k - t_{k-1}`)
/// `eps'_k` comes from the [`DerivativeEstimator`], `sigma_k = sigma_{k-1} + T_k*e_k` (backward
/// Euler), and `omega_k` is held until the next sample. Then the shared [`OutputStage`] applies
/// the direction and the optional limit, and the [`AntiWindup`] scheme guards `sigma`.
///
/// On the first sample no derivative is known yet: `eps'_0 = 0`.
///
/// Source: F. Dong and K. You, "Coordinate-free isoline tracking in unknown 2-D scalar fields",
/// arXiv:2003.12684 (2020), eqs. (2)-(3).
#[derive(Clone, Debug)]
pub struct PiIsoline {
    params: PiIsolineParams,
    estimator: DerivativeEstimator,
    sigma: f64,
    last_t_s: Option<f64>,
    last_e: f64,
}

impl PiIsoline {
    /// A controller at rest (`sigma = 0`).
    pub fn new(params: PiIsolineParams) -> Self {
        Self {
            estimator: DerivativeEstimator::new(params.derivative),
            params,
            sigma: 0.0,
            last_t_s: None,
            last_e: 0.0,
        }
    }
    /// The parameters.
    pub fn params(&self) -> &PiIsolineParams {
        &self.params
    }
    /// The integral state `sigma` (field units).
    pub fn sigma(&self) -> f64 {
        self.sigma
    }
    /// The last sliding variable `e` (field units per second).
    pub fn last_e(&self) -> f64 {
        self.last_e
    }
}

impl PiIsoline {
    /// `eps = s - s_d` and the estimate of `eps'` from a sample (the estimator advances).
    #[inline(always)]
    fn error_and_rate(&mut self, m: &Measurement) -> (f64, f64) {
        let eps = m.value - self.params.level;
        (eps, self.estimator.update(m.t_s, eps))
    }

    /// The rest of the law once `e = eps' + c1 tanh(eps/c2)` is known: `sigma` (with the
    /// anti-windup scheme) and the command through the output stage.
    #[inline(always)]
    fn integrate_and_command(&mut self, m: &Measurement, eps: f64, e: f64) -> f64 {
        let p = &self.params;
        if !e.is_finite() {
            // A non-finite measurement: hold the integral and command nothing new from it. The
            // clock does not advance either, so the next finite sample integrates the whole
            // interval since the last finite one and no time is lost from `sigma`.
            return p.output.apply(p.kp * self.last_e + p.ki * self.sigma);
        }
        let dt = match self.last_t_s {
            Some(t0) if m.t_s > t0 => m.t_s - t0,
            _ => 0.0,
        };
        self.last_t_s = Some(m.t_s);
        self.last_e = e;

        let mut sigma = self.sigma;
        match p.anti_windup {
            AntiWindup::None => sigma += dt * e,
            AntiWindup::Clamp { limit_radps } => {
                sigma += dt * e;
                if p.ki > 0.0 {
                    let s_max = limit_radps / p.ki;
                    sigma = sigma.clamp(-s_max, s_max);
                }
            }
            AntiWindup::Conditional { band } => {
                if libm::fabs(eps) < band {
                    sigma += dt * e;
                }
            }
            AntiWindup::BackCalculation { tracking_time_s } => {
                // The unsaturated output with the previous sigma decides whether the loop is
                // saturated over this interval; saturated, sigma relaxes exactly towards its
                // equilibrium (see `AntiWindup::BackCalculation`), else it integrates `e`.
                let u = p.kp * e + p.ki * sigma;
                let u_sat = crate::math::saturate(u, p.output.max_turn_rate_radps);
                if p.ki > 0.0 && u_sat != u {
                    let sigma_ss = tracking_time_s * e + (u_sat - p.kp * e) / p.ki;
                    let decay = crate::fmath::exp(-dt / tracking_time_s);
                    sigma = sigma_ss + (sigma - sigma_ss) * decay;
                } else {
                    sigma += dt * e;
                }
            }
        }
        self.sigma = sigma;
        p.output.apply(p.kp * e + p.ki * self.sigma)
    }
}

impl IsolineController for PiIsoline {
    #[inline]
    fn update(&mut self, m: &Measurement) -> f64 {
        let (eps, eps_dot) = self.error_and_rate(m);
        // eps * (1/c2): the reciprocal does not depend on the sample, so it is computed off
        // the step's chain of dependent operations, which then holds a multiply instead of a
        // division (within an ulp of eps/c2). For the paper's c2 = 1 the multiply is skipped
        // (it is exact there): a branch, not a select, so that it leaves the chain too.
        let tanh_term = if self.params.c2 == 1.0 {
            crate::fmath::tanh(eps)
        } else {
            crate::fmath::tanh(eps * (1.0 / self.params.c2))
        };
        let e = eps_dot + self.params.c1 * tanh_term;
        self.integrate_and_command(m, eps, e)
    }

    /// The law of `N` controllers with the `tanh` in lanes (each its own gains): the answers
    /// and states of [`update`](IsolineController::update), bit for bit.
    #[inline(always)]
    fn update_lanes<const N: usize>(
        ctrls: &mut [Option<&mut Self>; N],
        ms: &[Measurement; N],
    ) -> [f64; N] {
        let mut eps = [0.0; N];
        let mut eps_dot = [0.0; N];
        let mut arg = [0.0; N];
        for i in 0..N {
            if let Some(c) = ctrls[i].as_deref_mut() {
                (eps[i], eps_dot[i]) = c.error_and_rate(&ms[i]);
                arg[i] = eps[i] * (1.0 / c.params.c2);
            }
        }
        let th = crate::lanes::tanh_lanes(arg);
        let mut out = [0.0; N];
        for i in 0..N {
            if let Some(c) = ctrls[i].as_deref_mut() {
                let e = eps_dot[i] + c.params.c1 * th[i];
                out[i] = c.integrate_and_command(&ms[i], eps[i], e);
            }
        }
        out
    }

    fn reset(&mut self) {
        self.estimator.reset();
        self.sigma = 0.0;
        self.last_t_s = None;
        self.last_e = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn params() -> PiIsolineParams {
        PiIsolineParams::paper_fig2b(10.0)
    }

    #[test]
    fn first_sample_is_pure_tanh_term() {
        let mut c = PiIsoline::new(params());
        // eps = 2, eps' = 0 on the first sample: omega = kp*c1*tanh(2).
        let w = c.update(&Measurement {
            t_s: 0.0,
            value: 12.0,
        });
        assert_relative_eq!(w, 10.0 * 0.2 * crate::fmath::tanh(2.0), epsilon = 1e-12);
    }

    /// `c2` scales the error inside the tanh: with c2 = 4, the first command is
    /// `kp c1 tanh(eps/4)`, in the scalar and the lane form alike.
    #[test]
    fn c2_scales_the_error_inside_the_tanh() {
        let p = PiIsolineParams {
            c2: 4.0,
            ..params()
        };
        let m = Measurement {
            t_s: 0.0,
            value: 13.0,
        };
        let want = 10.0 * 0.2 * libm::tanh(3.0 / 4.0);
        let w = PiIsoline::new(p).update(&m);
        assert_relative_eq!(w, want, epsilon = 1e-12);
        let (mut a, mut b) = (PiIsoline::new(p), PiIsoline::new(p));
        let out = PiIsoline::update_lanes(&mut [Some(&mut a), Some(&mut b)], &[m, m]);
        assert_eq!(out, [w, w]);
    }

    #[test]
    fn a_non_finite_sample_does_not_advance_the_clock() {
        // eps = 2 at t = 0 and t = 2, a NaN at t = 1. The integral must cover the whole
        // interval [0, 2]: sigma = 2 s * e with e = 0 + c1*tanh(2/c2) (backward difference over
        // the two finite samples gives eps' = 0).
        let p = params();
        let mut c = PiIsoline::new(p);
        let at = |t_s: f64, value: f64| Measurement { t_s, value };
        c.update(&at(0.0, 12.0));
        c.update(&at(1.0, f64::NAN));
        c.update(&at(2.0, 12.0));
        let e = p.c1 * (2.0f64 / p.c2).tanh();
        assert_relative_eq!(c.sigma(), 2.0 * e, max_relative = 1e-12);
    }

    #[test]
    fn law_matches_hand_computation() {
        let mut c = PiIsoline::new(params());
        c.update(&Measurement {
            t_s: 0.0,
            value: 9.0,
        });
        let w = c.update(&Measurement {
            t_s: 0.1,
            value: 9.05,
        });
        // eps = -0.95, eps' = 0.5, e = 0.5 + 0.2 tanh(-0.95); sigma after first sample = 0
        // (dt = 0), after second = 0.1 e.
        let e = 0.5 + 0.2 * crate::fmath::tanh(-0.95);
        assert_relative_eq!(w, 10.0 * e + 1.0 * 0.1 * e, epsilon = 1e-12);
    }

    #[test]
    fn left_mirrors_right() {
        let mut r = PiIsoline::new(params());
        let mut l = PiIsoline::new(PiIsolineParams {
            output: OutputStage {
                higher_side: HigherSide::Left,
                max_turn_rate_radps: None,
            },
            ..params()
        });
        for k in 0..50 {
            let m = Measurement {
                t_s: k as f64 * 0.1,
                value: 10.0 + libm::sin(k as f64 * 0.3),
            };
            assert_eq!(r.update(&m), -l.update(&m));
        }
    }

    #[test]
    fn turn_rate_limit_and_clamp_hold() {
        let mut c = PiIsoline::new(PiIsolineParams {
            output: OutputStage {
                higher_side: HigherSide::Right,
                max_turn_rate_radps: Some(0.3),
            },
            anti_windup: AntiWindup::Clamp { limit_radps: 0.2 },
            ..params()
        });
        for k in 0..1000 {
            let w = c.update(&Measurement {
                t_s: k as f64 * 0.1,
                value: 0.0,
            });
            assert!(w.abs() <= 0.3 + 1e-15);
        }
        assert!((c.sigma() * 1.0).abs() <= 0.2 + 1e-12);
    }

    #[test]
    fn conditional_integration_holds_far_from_isoline() {
        let mut c = PiIsoline::new(PiIsolineParams {
            anti_windup: AntiWindup::Conditional { band: 1.0 },
            ..params()
        });
        for k in 0..100 {
            c.update(&Measurement {
                t_s: k as f64 * 0.1,
                value: 5.0,
            });
        }
        assert_eq!(c.sigma(), 0.0);
    }

    /// Back-calculation by hand: with a constant error (eps' = 0 after the first sample) the
    /// law's raw output u = kp e + ki sigma is saturated at 1 rad/s, and each step relaxes
    /// sigma exactly towards sigma_ss = Tt e + (u_sat - kp e)/ki with time constant Tt.
    #[test]
    fn back_calculation_by_hand() {
        let mut p = params();
        p.anti_windup = AntiWindup::BackCalculation {
            tracking_time_s: 2.0,
        };
        p.output.max_turn_rate_radps = Some(1.0);
        p.ki = 0.5;
        let mut c = PiIsoline::new(p);
        let e = 0.2 * crate::fmath::tanh(3.0); // eps = 3
        let mut sigma = 0.0;
        for k in 0..5 {
            let w = c.update(&Measurement {
                t_s: 0.1 * k as f64,
                value: 13.0,
            });
            if k > 0 {
                // Saturated (u = 10 e + sigma > 1): exact relaxation towards
                // sigma_ss = Tt e + (1 - kp e) / ki over dt = 0.1 s, Tt = 2 s.
                let u = 10.0 * e + 0.5 * sigma;
                assert!(u > 1.0);
                let sigma_ss = 2.0 * e + (1.0 - 10.0 * e) / 0.5;
                sigma = sigma_ss + (sigma - sigma_ss) * (-0.1f64 / 2.0).exp();
            }
            assert_relative_eq!(c.sigma(), sigma, epsilon = 1e-14);
            assert_eq!(w, 1.0);
        }
        assert!(
            c.sigma() < 4.0 * 0.1 * e,
            "the excess bled off the integral"
        );
    }

    /// Back-calculation switching between saturated and free intervals: a negative error winds
    /// the integral down against the limit, then a positive one leaves the raw output
    /// `kp e + ki sigma` inside the limit while `kp e - ki sigma` would not be (where a wrong sign
    /// or sum in `u` would call the interval saturated). Followed by hand through every sample.
    #[test]
    fn back_calculation_decides_saturation_from_kp_e_plus_ki_sigma() {
        let (kp, ki, c1, tt, lim) = (2.0, 2.0, 0.2, 2.0, 1.0);
        let mut p = params();
        p.kp = kp;
        p.ki = ki;
        p.anti_windup = AntiWindup::BackCalculation {
            tracking_time_s: tt,
        };
        p.output.max_turn_rate_radps = Some(lim);
        let mut c = PiIsoline::new(p);
        // eps: -0.45 for 12 s, up by 0.1 per second to 0.45, held.
        let eps_of = |k: usize| match k {
            0..=11 => -0.45,
            12..=20 => -0.45 + 0.1 * (k - 11) as f64,
            _ => 0.45,
        };
        let (mut sigma, mut prev, mut t_prev): (f64, f64, f64) = (0.0, 0.0, 0.0);
        let (mut free, mut saturated, mut only_with_plus) = (0, 0, 0);
        for k in 0..29 {
            let t = k as f64;
            let eps = eps_of(k);
            let eps_dot = if k == 0 {
                0.0
            } else {
                (eps - prev) / (t - t_prev)
            };
            let e = eps_dot + c1 * crate::fmath::tanh(eps);
            let dt = if k == 0 { 0.0 } else { t - t_prev };
            let u = kp * e + ki * sigma;
            let u_sat = u.clamp(-lim, lim);
            if u_sat != u {
                saturated += 1;
                let ss = tt * e + (u_sat - kp * e) / ki;
                sigma = ss + (sigma - ss) * crate::fmath::exp(-dt / tt);
            } else {
                free += 1;
                if (kp * e - ki * sigma).abs() > lim {
                    only_with_plus += 1;
                }
                sigma += dt * e;
            }
            let w = c.update(&Measurement {
                t_s: t,
                value: 10.0 + eps,
            });
            assert_relative_eq!(c.sigma(), sigma, epsilon = 1e-12);
            assert_relative_eq!(w, (kp * e + ki * sigma).clamp(-lim, lim), epsilon = 1e-12);
            (prev, t_prev) = (eps, t);
        }
        assert!(
            free > 5 && saturated > 5,
            "{free} free, {saturated} saturated"
        );
        assert!(only_with_plus >= 3, "{only_with_plus}");
    }

    /// The proptest's failing case (kept): a 1.55 s sample interval against a 0.01 s tracking
    /// time, huge measurements, a 0.001 rad/s limit. Explicit Euler multiplied sigma by
    /// |1 - dt/Tt| = 154 per sample, to infinity and NaN; the exact step stays finite.
    #[test]
    fn back_calculation_is_stable_for_any_sample_interval() {
        let mut p = params();
        p.kp = 0.001;
        p.ki = 93.13172049213503;
        p.c1 = 0.001;
        p.c2 = 0.001;
        p.level = 0.0;
        p.output.max_turn_rate_radps = Some(0.001);
        p.anti_windup = AntiWindup::BackCalculation {
            tracking_time_s: 0.01,
        };
        let mut c = PiIsoline::new(p);
        let values = [251130458.66864976, -155986695.2969847, 0.0, 0.0, 0.0, 0.0];
        for (k, v) in values.iter().cycle().take(200).enumerate() {
            let w = c.update(&Measurement {
                t_s: 1.5502517567745357 * k as f64,
                value: *v,
            });
            assert!(w.is_finite() && w.abs() <= 0.001, "sample {k}: {w}");
            assert!(c.sigma().is_finite(), "sample {k}: sigma {}", c.sigma());
        }
    }

    /// Clamp by hand: sigma integrates e dt and is held within |ki sigma| <= limit.
    #[test]
    fn clamp_by_hand() {
        let mut p = params();
        p.ki = 0.5;
        p.anti_windup = AntiWindup::Clamp { limit_radps: 0.05 };
        let mut c = PiIsoline::new(p);
        let e = 0.2 * crate::fmath::tanh(2.0);
        let mut sigma: f64 = 0.0;
        for k in 0..8 {
            c.update(&Measurement {
                t_s: 0.1 * k as f64,
                value: 12.0,
            });
            if k > 0 {
                sigma = (sigma + 0.1 * e).min(0.05 / 0.5);
            }
            assert_relative_eq!(c.sigma(), sigma, epsilon = 1e-15);
        }
        assert_eq!(c.sigma(), 0.1, "held at the clamp");
        // ki = 0: no integral action to clamp, sigma integrates freely.
        p.ki = 0.0;
        let mut c = PiIsoline::new(p);
        for k in 0..8 {
            c.update(&Measurement {
                t_s: 0.1 * k as f64,
                value: 12.0,
            });
        }
        assert_relative_eq!(c.sigma(), 0.7 * e, epsilon = 1e-15);
    }

    /// Conditional integration by hand: only while |eps| < band (strictly).
    #[test]
    fn conditional_by_hand() {
        let mut p = params();
        p.anti_windup = AntiWindup::Conditional { band: 1.0 };
        for (value, integrates) in [(12.0, false), (11.0, false), (10.5, true), (9.6, true)] {
            let mut c = PiIsoline::new(p);
            for k in 0..3 {
                c.update(&Measurement {
                    t_s: 0.5 * k as f64,
                    value,
                });
            }
            let e = 0.2 * crate::fmath::tanh(value - 10.0);
            let want = if integrates { 1.0 * e } else { 0.0 };
            assert_relative_eq!(c.sigma(), want, epsilon = 1e-15);
        }
    }

    /// c2 scales the error inside tanh; a repeated time does not integrate; a NaN sample
    /// answers kp e_last + ki sigma; reset forgets everything; last_e is the sliding variable.
    #[test]
    fn scaling_repeats_nan_and_reset() {
        let mut p = params();
        p.c2 = 2.0;
        let mut c = PiIsoline::new(p);
        let w0 = c.update(&Measurement {
            t_s: 0.0,
            value: 13.0,
        });
        let e = 0.2 * crate::fmath::tanh(3.0 / 2.0);
        assert_relative_eq!(w0, 10.0 * e, epsilon = 1e-15);
        assert_relative_eq!(c.last_e(), e, epsilon = 1e-15);
        c.update(&Measurement {
            t_s: 1.0,
            value: 13.0,
        });
        assert_relative_eq!(c.sigma(), 1.0 * e, epsilon = 1e-15);
        c.update(&Measurement {
            t_s: 1.0,
            value: 13.0,
        });
        assert_relative_eq!(c.sigma(), 1.0 * e, epsilon = 1e-15);
        let w = c.update(&Measurement {
            t_s: 2.0,
            value: f64::NAN,
        });
        assert_relative_eq!(w, 10.0 * c.last_e() + 1.0 * c.sigma(), epsilon = 1e-15);
        assert_relative_eq!(c.last_e(), e, epsilon = 1e-15);
        c.reset();
        assert_eq!((c.sigma(), c.last_e()), (0.0, 0.0));
        let again = c.update(&Measurement {
            t_s: 5.0,
            value: 13.0,
        });
        assert_relative_eq!(again, 10.0 * e, epsilon = 1e-15);
    }

    /// Back-calculation off the limit integrates e dt like the plain law; with ki = 0 there is no
    /// integral action to bleed, so sigma integrates e dt even on the limit. A sample whose time
    /// runs backwards integrates nothing.
    #[test]
    fn back_calculation_unsaturated_no_ki_and_backward_time() {
        let mut p = params();
        p.anti_windup = AntiWindup::BackCalculation {
            tracking_time_s: 0.5,
        };
        p.output.max_turn_rate_radps = Some(100.0);
        let mut c = PiIsoline::new(p);
        let e = 0.2 * crate::fmath::tanh(0.3);
        for k in 0..4 {
            c.update(&Measurement {
                t_s: 0.25 * k as f64,
                value: 10.3,
            });
        }
        assert_relative_eq!(c.sigma(), 0.75 * e, epsilon = 1e-15);
        // ki = 0 and saturated (limit 0.01 < kp e): still plain integration.
        p.ki = 0.0;
        p.output.max_turn_rate_radps = Some(0.01);
        let mut c = PiIsoline::new(p);
        for k in 0..4 {
            let w = c.update(&Measurement {
                t_s: 0.25 * k as f64,
                value: 10.3,
            });
            assert_eq!(w, 0.01);
        }
        assert_relative_eq!(c.sigma(), 0.75 * e, epsilon = 1e-15);
        // Time running backwards: no integration (and the estimate holds).
        let mut c = PiIsoline::new(params());
        for t in [1.0, 2.0, 1.5] {
            c.update(&Measurement {
                t_s: t,
                value: 10.3,
            });
        }
        assert_relative_eq!(c.sigma(), 1.0 * e, epsilon = 1e-15);
    }

    /// The trait's defaults: a coordinate-free law asks for no ground truth, and given some
    /// anyway it answers as from the measurement alone.
    #[test]
    fn trait_defaults_ignore_ground_truth() {
        let mut a = PiIsoline::new(params());
        let mut b = PiIsoline::new(params());
        assert!(!a.needs_ground_truth());
        let truth = crate::control::GroundTruth {
            pose: crate::math::Pose2 {
                position: crate::math::Vec2::new(1.0, 2.0),
                heading_rad: 0.3,
            },
            speed_mps: 0.5,
            value: 12.5,
            derivatives: None,
        };
        for k in 0..3 {
            let m = Measurement {
                t_s: k as f64,
                value: 12.0 - k as f64,
            };
            let wa = a.update_with_truth(&m, &truth);
            assert!(wa != 0.0);
            assert_eq!(wa, b.update(&m));
        }
    }
}

#[cfg(test)]
mod proptests {
    use super::*;
    use crate::estimate::DerivativeKind;
    use proptest::prelude::*;

    fn any_anti_windup() -> impl Strategy<Value = AntiWindup> {
        prop_oneof![
            Just(AntiWindup::None),
            (1e-3..10.0f64).prop_map(|l| AntiWindup::Clamp { limit_radps: l }),
            (1e-3..10.0f64).prop_map(|b| AntiWindup::Conditional { band: b }),
            (1e-2..10.0f64).prop_map(|t| AntiWindup::BackCalculation { tracking_time_s: t }),
        ]
    }

    fn any_derivative() -> impl Strategy<Value = DerivativeKind> {
        prop_oneof![
            Just(DerivativeKind::BackwardDifference),
            (1e-3..10.0f64).prop_map(|t| DerivativeKind::FilteredDifference { tau_s: t }),
            (1e-3..100.0f64).prop_map(|l| DerivativeKind::Levant { lipschitz: l }),
        ]
    }

    proptest! {
        /// For any valid gains and any finite measurement sequence the command is finite, and
        /// within the turn-rate limit when there is one.
        #[test]
        fn command_is_finite_and_limited(
            kp in 1e-3..1e3f64, ki in 0.0..1e2f64, c1 in 1e-3..1e2f64, c2 in 1e-3..1e2f64,
            level in -1e6..1e6f64,
            limit in proptest::option::of(1e-3..10.0f64),
            left in any::<bool>(),
            aw in any_anti_windup(), d in any_derivative(),
            dt in 1e-3..2.0f64,
            values in proptest::collection::vec(-1e9..1e9f64, 1..200),
        ) {
            let mut c = PiIsoline::new(PiIsolineParams {
                level, kp, ki, c1, c2,
                output: OutputStage {
                    higher_side: if left { HigherSide::Left } else { HigherSide::Right },
                    max_turn_rate_radps: limit,
                },
                anti_windup: aw,
                derivative: d,
            });
            for (k, v) in values.iter().enumerate() {
                let w = c.update(&Measurement { t_s: k as f64 * dt, value: *v });
                prop_assert!(w.is_finite(), "omega = {w}");
                if let Some(l) = limit {
                    prop_assert!(w.abs() <= l, "|{w}| > {l}");
                }
            }
        }
    }
}
