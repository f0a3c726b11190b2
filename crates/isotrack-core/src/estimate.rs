//! Derivative estimators: `eps'(t_k)` from the samples `eps(t_0), ..., eps(t_k)` alone.
//!
//! The paper's law needs `eps' = s'` but the robot only samples `s`. Every controller in isotrack
//! takes one of these estimators, so the choice of estimator is separate from the choice of law.
//!
//! All estimators return `0.0` until they have enough samples (one for Levant's differentiator,
//! two for the differences) and never return a non-finite value for finite input.

/// Which derivative estimator to use, with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum DerivativeKind {
    /// Backward difference `(x_k - x_{k-1}) / (t_k - t_{k-1})`.
    BackwardDifference,
    /// Backward difference through a first-order low-pass filter with time constant `tau_s`,
    /// discretised exactly for the sample interval `T`: `y_k = a*y_{k-1} + (1 - a)*d_k`,
    /// `a = exp(-T/tau_s)`.
    FilteredDifference {
        /// Filter time constant, seconds (> 0).
        tau_s: f64,
    },
    /// Levant's first-order robust exact differentiator (Levant 1998, "Robust exact
    /// differentiation via sliding mode technique", Automatica 34(3)):
    /// `z0' = z1 - l1*L^(1/2)*|z0 - x|^(1/2)*sgn(z0 - x)`, `z1' = -l0*L*sgn(z0 - x)`,
    /// `l1 = 1.5`, `l0 = 1.1`, integrated by explicit Euler over each sample interval.
    /// `L` bounds `|x''|` (field units per s^2).
    Levant {
        /// Lipschitz constant of the derivative, `L >= sup |x''|` (> 0).
        lipschitz: f64,
    },
}

/// A derivative estimator's state. Build one with [`DerivativeEstimator::new`].
#[derive(Clone, Debug)]
pub struct DerivativeEstimator {
    kind: DerivativeKind,
    last: Option<(f64, f64)>,
    estimate: f64,
    primed: bool,
    z0: f64,
}

impl DerivativeEstimator {
    /// A fresh estimator of the given kind.
    pub fn new(kind: DerivativeKind) -> Self {
        Self {
            kind,
            last: None,
            estimate: 0.0,
            primed: false,
            z0: 0.0,
        }
    }

    /// The estimator's kind and parameters.
    pub fn kind(&self) -> DerivativeKind {
        self.kind
    }

    /// Forgets all samples.
    pub fn reset(&mut self) {
        *self = Self::new(self.kind);
    }

    /// Feeds the sample `x` taken at `t_s` and returns the derivative estimate at `t_s`.
    ///
    /// A sample whose time does not advance (`t_s <= ` the previous one) leaves the estimate
    /// unchanged.
    #[inline(always)]
    pub fn update(&mut self, t_s: f64, x: f64) -> f64 {
        let Some((t_prev, x_prev)) = self.last else {
            self.last = Some((t_s, x));
            self.z0 = x;
            self.estimate = 0.0;
            return 0.0;
        };
        let dt = t_s - t_prev;
        if dt.is_nan() || dt <= 0.0 || !x.is_finite() {
            return self.estimate;
        }
        self.last = Some((t_s, x));
        let raw = (x - x_prev) / dt;
        self.estimate = match self.kind {
            DerivativeKind::BackwardDifference => raw,
            DerivativeKind::FilteredDifference { tau_s } => {
                if self.primed {
                    let a = crate::fmath::exp(-dt / tau_s);
                    a * self.estimate + (1.0 - a) * raw
                } else {
                    self.primed = true;
                    raw
                }
            }
            DerivativeKind::Levant { lipschitz } => {
                // Explicit Euler over the sample interval, the standard sampled implementation
                // (Levant 2003, "Higher-order sliding modes, differentiation and output-feedback
                // control", Int. J. Control 76(9-10), Sec. 5): accuracy O(L*T^2) on z0, O(L*T)
                // on z1 in the absence of noise.
                let err = self.z0 - x;
                let sgn = if err > 0.0 {
                    1.0
                } else if err < 0.0 {
                    -1.0
                } else {
                    0.0
                };
                let z1 = self.estimate;
                let z0_dot = z1
                    - 1.5
                        * crate::fmath::sqrt(lipschitz)
                        * crate::fmath::sqrt(libm::fabs(err))
                        * sgn;
                let z1_dot = -1.1 * lipschitz * sgn;
                self.z0 += dt * z0_dot;
                z1 + dt * z1_dot
            }
        };
        if !self.estimate.is_finite() {
            self.estimate = 0.0;
        }
        self.estimate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn backward_difference_is_exact_on_a_line() {
        let mut d = DerivativeEstimator::new(DerivativeKind::BackwardDifference);
        assert_eq!(d.update(0.0, 1.0), 0.0);
        for k in 1..10 {
            let t = k as f64 * 0.1;
            assert_relative_eq!(d.update(t, 1.0 + 3.0 * t), 3.0, epsilon = 1e-9);
        }
    }

    #[test]
    fn filtered_difference_converges_to_a_ramp_slope() {
        let mut d = DerivativeEstimator::new(DerivativeKind::FilteredDifference { tau_s: 0.2 });
        let mut est = 0.0;
        for k in 0..200 {
            let t = k as f64 * 0.01;
            est = d.update(t, -2.0 * t);
        }
        assert_relative_eq!(est, -2.0, epsilon = 1e-9);
    }

    #[test]
    fn filtered_difference_attenuates_alternating_noise() {
        // +-1 alternation at 100 Hz: backward difference is +-200, the filter (tau = 1 s) must cut
        // it by about T/(2*tau) relative to raw.
        let mut d = DerivativeEstimator::new(DerivativeKind::FilteredDifference { tau_s: 1.0 });
        let mut worst: f64 = 0.0;
        for k in 0..2000 {
            let t = k as f64 * 0.01;
            let x = if k % 2 == 0 { 1.0 } else { -1.0 };
            let e = d.update(t, x);
            if k > 1000 {
                worst = worst.max(e.abs());
            }
        }
        assert!(worst < 2.0, "filtered noise amplitude {worst}");
    }

    #[test]
    fn levant_tracks_a_sine_derivative() {
        // x = sin(t): |x''| <= 1, use L = 2. After the finite-time transient, |z1 - cos t| is
        // small (O(L*T) = 0.02 at T = 0.01).
        let mut d = DerivativeEstimator::new(DerivativeKind::Levant { lipschitz: 2.0 });
        let mut worst: f64 = 0.0;
        for k in 0..3000 {
            let t = k as f64 * 0.01;
            let e = d.update(t, libm::sin(t));
            if t > 10.0 {
                worst = worst.max((e - libm::cos(t)).abs());
            }
        }
        assert!(worst < 0.05, "Levant error {worst}");
    }

    #[test]
    fn non_advancing_time_keeps_estimate() {
        let mut d = DerivativeEstimator::new(DerivativeKind::BackwardDifference);
        d.update(0.0, 0.0);
        let e = d.update(1.0, 2.0);
        assert_eq!(d.update(1.0, 100.0), e);
    }

    /// The filtered difference by hand: the first difference raw, then
    /// `a*previous + (1 - a)*raw` with `a = exp(-dt/tau)`.
    #[test]
    fn filtered_difference_by_hand() {
        let mut d = DerivativeEstimator::new(DerivativeKind::FilteredDifference { tau_s: 0.5 });
        d.update(0.0, 0.0);
        assert_eq!(d.update(0.1, 0.3), 0.3 / 0.1);
        let a = crate::fmath::exp(-0.2 / 0.5);
        let want = a * 3.0 + (1.0 - a) * ((0.5 - 0.3) / 0.2);
        assert_relative_eq!(d.update(0.3, 0.5), want, epsilon = 1e-14);
    }

    /// Levant's differentiator, one explicit Euler step by hand from z0 = x(0), z1 = 0:
    /// err = z0 - x, z0' = z1 - 1.5 sqrt(L) sqrt(|err|) sgn(err), z1' = -1.1 L sgn(err);
    /// the estimate is z1 + dt z1'. With no error (err = 0) nothing moves.
    #[test]
    fn levant_step_by_hand() {
        let l = 4.0;
        let mut d = DerivativeEstimator::new(DerivativeKind::Levant { lipschitz: l });
        d.update(0.0, 1.0);
        // err = 1 - 1.25 = -0.25 < 0: sgn = -1.
        let z1 = d.update(0.5, 1.25);
        assert_relative_eq!(z1, 0.0 + 0.5 * (1.1 * l), epsilon = 1e-14);
        // z0 = 1 + 0.5 * (0 + 1.5 * 2 * 0.5) = 1.75; next err = 1.75 - 1.0 = 0.75 > 0.
        let z1b = d.update(1.0, 1.0);
        assert_relative_eq!(z1b, z1 - 0.5 * 1.1 * l, epsilon = 1e-14);
        let mut still = DerivativeEstimator::new(DerivativeKind::Levant { lipschitz: l });
        still.update(0.0, 2.0);
        assert_eq!(still.update(0.5, 2.0), 0.0);
        // With z0 on the sample exactly (err = 0), z1 holds: z0 = 1 + 0.5 * 1.5 = 1.75 above.
        let mut e = DerivativeEstimator::new(DerivativeKind::Levant { lipschitz: l });
        e.update(0.0, 1.0);
        let z1 = e.update(0.5, 1.25);
        assert_eq!(e.update(1.0, 1.75), z1);
        // ... and from rest it answers the next move (err = 2 - 3 = -1: z1 = 0.5 * 1.1 L).
        assert_relative_eq!(still.update(1.0, 3.0), 0.5 * 1.1 * l, epsilon = 1e-14);
    }
}
