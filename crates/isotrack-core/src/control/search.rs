//! A search phase before tracking: on a flat background (no gradient) every tracking law, which
//! steers by changes of the measurement, has nothing to steer by, and the vehicle circles forever.
//! [`Search`] flies an open-loop pattern until the measured value has moved by a stated amount
//! from its first sample, then hands over to the tracking law for good.
//!
//! Coordinate-free: the pattern is a function of time since the first sample and of the
//! vehicle's own speed (known to it: it is the speed it is commanded to fly), never of position;
//! the hand-over looks only at measurements.

use super::{GroundTruth, IsolineController, Measurement};
use crate::fmath;

/// The search pattern, as a turn-rate program `omega(t)` (rad/s, positive left) of the time `t`
/// since the search began.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SearchPattern {
    /// An Archimedean spiral `r = b*theta/(2*pi)` flown at speed `v`: arms `b` apart (the
    /// swept width), so the area covered grows as `v*b*t`. Its arc length is
    /// `b*theta^2/(4*pi)` (for `theta >> 1`), so `theta(t) = sqrt(4*pi*v*t/b)` and
    /// `omega(t) = sqrt(pi*v/(b*t))`, capped at `max_turn_rate_radps` near the start.
    Spiral {
        /// Arm spacing `b`, m.
        spacing_m: f64,
        /// Vehicle speed `v`, m/s.
        speed_mps: f64,
        /// The largest turn rate flown (the start of the spiral), rad/s.
        max_turn_rate_radps: f64,
    },
    /// A lawnmower (boustrophedon): straight legs of `leg_m`, joined by half-turns of diameter
    /// `spacing_m` (turn rate `2*v/spacing_m` for `pi*spacing_m/(2*v)` s), alternately left and
    /// right, so successive legs are `spacing_m` apart.
    Lawnmower {
        /// Leg length, m.
        leg_m: f64,
        /// Distance between legs, m.
        spacing_m: f64,
        /// Vehicle speed, m/s.
        speed_mps: f64,
    },
}

impl SearchPattern {
    /// The turn rate at `t_s` seconds into the search, rad/s.
    pub fn turn_rate_radps(&self, t_s: f64) -> f64 {
        match *self {
            SearchPattern::Spiral {
                spacing_m,
                speed_mps,
                max_turn_rate_radps,
            } => {
                if t_s <= 0.0 {
                    return max_turn_rate_radps;
                }
                let w = fmath::sqrt(core::f64::consts::PI * speed_mps / (spacing_m * t_s));
                w.min(max_turn_rate_radps)
            }
            SearchPattern::Lawnmower {
                leg_m,
                spacing_m,
                speed_mps,
            } => {
                let leg_s = leg_m / speed_mps;
                let turn_radps = 2.0 * speed_mps / spacing_m;
                let turn_s = core::f64::consts::PI / turn_radps;
                let period = leg_s + turn_s;
                let k = fmath::floor(t_s.max(0.0) / period);
                let into = t_s.max(0.0) - k * period;
                if into < leg_s {
                    0.0
                } else if (k as u64).is_multiple_of(2) {
                    turn_radps
                } else {
                    -turn_radps
                }
            }
        }
    }
}

/// Search settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchParams {
    /// The pattern flown until hand-over.
    pub pattern: SearchPattern,
    /// Hand over once `|s - s_first| >= handover_delta` (field units, > 0): the vehicle has
    /// found a gradient to steer by.
    pub handover_delta: f64,
}

/// A tracking law `C` preceded by a search phase (see the module docs). The tracking law sees
/// only the measurements from the hand-over on: its integrator and derivative estimator start
/// there.
#[derive(Clone, Debug)]
pub struct Search<C> {
    inner: C,
    params: SearchParams,
    first: Option<Measurement>,
    /// Time of the hand-over, s (`None` while searching).
    handed_over_at_s: Option<f64>,
}

impl<C> Search<C> {
    /// `inner` preceded by the search `params`.
    pub fn new(inner: C, params: SearchParams) -> Self {
        Self {
            inner,
            params,
            first: None,
            handed_over_at_s: None,
        }
    }

    /// When the search handed over to the tracking law, s (`None` while still searching).
    pub fn handed_over_at_s(&self) -> Option<f64> {
        self.handed_over_at_s
    }

    /// Whether this sample ends the search (and records the hand-over).
    fn hands_over(&mut self, m: &Measurement) -> bool {
        if self.handed_over_at_s.is_some() {
            return true;
        }
        let first = *self.first.get_or_insert(*m);
        if m.value.is_finite() && (m.value - first.value).abs() >= self.params.handover_delta {
            self.handed_over_at_s = Some(m.t_s);
            return true;
        }
        false
    }

    fn search_command(&self, m: &Measurement) -> f64 {
        let t0 = self.first.map_or(m.t_s, |f| f.t_s);
        self.params.pattern.turn_rate_radps(m.t_s - t0)
    }
}

impl<C: IsolineController> IsolineController for Search<C> {
    fn update(&mut self, m: &Measurement) -> f64 {
        if self.hands_over(m) {
            self.inner.update(m)
        } else {
            self.search_command(m)
        }
    }

    fn reset(&mut self) {
        self.inner.reset();
        self.first = None;
        self.handed_over_at_s = None;
    }

    fn needs_ground_truth(&self) -> bool {
        self.inner.needs_ground_truth()
    }

    fn update_with_truth(&mut self, m: &Measurement, truth: &GroundTruth) -> f64 {
        if self.hands_over(m) {
            self.inner.update_with_truth(m, truth)
        } else {
            self.search_command(m)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The spiral's turn rate is the Archimedean one: integrating omega from the cap on gives
    /// theta(t) = sqrt(4*pi*v*t/b) (checked at t = 400 s, where the cap's share is negligible).
    #[test]
    fn spiral_turn_rate_integrates_to_the_archimedean_angle() {
        let p = SearchPattern::Spiral {
            spacing_m: 2.0,
            speed_mps: 0.5,
            max_turn_rate_radps: 1.0,
        };
        let dt = 1e-3;
        let mut theta = 0.0;
        let mut t = 0.0;
        while t < 400.0 {
            theta += p.turn_rate_radps(t + 0.5 * dt) * dt;
            t += dt;
        }
        // Before t_c = pi*v/(b*w_max^2) the cap turns w_max*t_c instead of the formula's
        // 2*w_max*t_c, so theta(t) = sqrt(4*pi*v*t/b) - pi*v/(b*w_max) after it.
        let pi = core::f64::consts::PI;
        let want = (4.0 * pi * 0.5 * 400.0 / 2.0f64).sqrt() - pi * 0.5 / (2.0 * 1.0);
        assert!((theta - want).abs() < 1e-3, "{theta} vs {want}");
        assert_eq!(p.turn_rate_radps(0.0), 1.0);
    }

    /// The lawnmower: straight for leg/v, then a half-turn of pi (integral of omega) at
    /// 2v/spacing, alternating sides.
    #[test]
    fn lawnmower_legs_and_half_turns() {
        let p = SearchPattern::Lawnmower {
            leg_m: 10.0,
            spacing_m: 2.0,
            speed_mps: 0.5,
        };
        // Leg 20 s, turn rate 0.5 rad/s for 2*pi s.
        assert_eq!(p.turn_rate_radps(10.0), 0.0);
        // The turn starts at the leg's end exactly (20 s).
        assert_eq!(p.turn_rate_radps(20.0), 0.5);
        assert_eq!(p.turn_rate_radps(21.0), 0.5);
        let period = 20.0 + 2.0 * core::f64::consts::PI;
        assert_eq!(p.turn_rate_radps(period + 1.0), 0.0);
        assert_eq!(p.turn_rate_radps(period + 21.0), -0.5);
        let dt = 1e-4;
        let turned: f64 = (0..(period / dt) as usize)
            .map(|k| p.turn_rate_radps((k as f64 + 0.5) * dt) * dt)
            .sum();
        assert!((turned - core::f64::consts::PI).abs() < 1e-3, "{turned}");
    }

    struct Echo;
    impl IsolineController for Echo {
        fn update(&mut self, m: &Measurement) -> f64 {
            -m.value
        }
        fn reset(&mut self) {}
    }

    /// Hands over at the first sample that moved by the delta, and never goes back.
    #[test]
    fn hands_over_once_the_measurement_moves() {
        let pattern = SearchPattern::Spiral {
            spacing_m: 1.0,
            speed_mps: 1.0,
            max_turn_rate_radps: 0.7,
        };
        let mut s = Search::new(
            Echo,
            SearchParams {
                pattern,
                handover_delta: 0.5,
            },
        );
        let m = |t_s, value| Measurement { t_s, value };
        assert_eq!(s.update(&m(0.0, 3.0)), 0.7);
        assert_eq!(s.update(&m(1.0, 3.4)), pattern.turn_rate_radps(1.0));
        assert_eq!(s.handed_over_at_s(), None);
        assert_eq!(s.update(&m(2.0, 2.5)), -2.5);
        assert_eq!(s.handed_over_at_s(), Some(2.0));
        assert_eq!(s.update(&m(3.0, 3.0)), -3.0, "stays handed over");
        s.reset();
        assert_eq!(s.update(&m(4.0, 3.0)), 0.7);
    }

    /// A law that flies on ground truth (its command: ten times the true speed).
    struct Truthy;
    impl IsolineController for Truthy {
        fn update(&mut self, _m: &Measurement) -> f64 {
            0.0
        }
        fn reset(&mut self) {}
        fn needs_ground_truth(&self) -> bool {
            true
        }
        fn update_with_truth(&mut self, _m: &Measurement, t: &GroundTruth) -> f64 {
            10.0 * t.speed_mps
        }
    }

    /// The search asks for ground truth when its law does, and hands the truth to it once it has
    /// handed over (before that it flies its pattern).
    #[test]
    fn ground_truth_passes_through_to_the_law() {
        let pattern = SearchPattern::Spiral {
            spacing_m: 1.0,
            speed_mps: 1.0,
            max_turn_rate_radps: 0.7,
        };
        let params = SearchParams {
            pattern,
            handover_delta: 0.5,
        };
        assert!(!Search::new(Echo, params).needs_ground_truth());
        let mut s = Search::new(Truthy, params);
        assert!(s.needs_ground_truth());
        let truth = GroundTruth {
            pose: crate::math::Pose2 {
                position: crate::math::Vec2::new(0.0, 0.0),
                heading_rad: 0.0,
            },
            speed_mps: 0.25,
            value: 3.0,
            derivatives: None,
        };
        let m = |t_s, value| Measurement { t_s, value };
        assert_eq!(s.update_with_truth(&m(0.0, 3.0), &truth), 0.7);
        assert_eq!(s.update_with_truth(&m(1.0, 2.0), &truth), 2.5);
    }
}
