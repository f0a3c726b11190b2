//! Neighbour ranging (e.g. UWB two-way ranging): each vehicle measures the distance to its two
//! ring neighbours, the one ahead and the one behind, at `rate_hz`, with additive Gaussian noise,
//! a maximum range, dropouts and a delivery delay, from its own seeded streams. `O(1)` per vehicle
//! per sample (two ranges), memory bounded by the delay (the samples in flight).

use crate::sensor::{nearest_valid_rates, whole_steps, StepsError};
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::Vec2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::VecDeque;

/// Ranging settings (`team.ranging.*`), SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangingConfig {
    /// Ranging rate, Hz (> 0): the period a whole number of simulation steps.
    pub rate_hz: f64,
    /// Standard deviation of the additive Gaussian range noise, m (>= 0).
    pub noise_std_m: f64,
    /// Beyond this true distance a neighbour does not answer (the range is invalid), m (> 0;
    /// infinite: no limit).
    pub max_range_m: f64,
    /// Probability that a range is lost (invalid), in `[0, 1]`.
    pub dropout_probability: f64,
    /// Delivery delay, s (>= 0; a whole number of steps): a range measured at `t` arrives at
    /// `t + delay_s`.
    pub delay_s: f64,
}

impl Default for RangingConfig {
    /// Ideal ranging at 10 Hz: no noise, range limit, dropouts or delay.
    fn default() -> Self {
        Self {
            rate_hz: 10.0,
            noise_std_m: 0.0,
            max_range_m: f64::INFINITY,
            dropout_probability: 0.0,
            delay_s: 0.0,
        }
    }
}

/// Why ranging settings are refused (the key named).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RangingError {
    /// A setting out of its range.
    #[error("team.ranging.{key} = {} is out of range: {expected}", Echo(*.value))]
    OutOfRange {
        /// The key.
        key: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// A rate whose period is not a whole number (>= 1) of steps: the rate as given, its
    /// period rounded, and the nearest valid rates ([`nearest_valid_rates`], the sensor's rule).
    #[error(
        "team.ranging.rate_hz = {} Hz: its period {} s {reason} of {} s (at least one); {}",
        Echo(*.rate_hz),
        Num(1.0 / *.rate_hz),
        Echo(*.dt_s),
        nearest_valid_rates(*.rate_hz, *.dt_s)
    )]
    RateNotWholeSteps {
        /// The rate, Hz.
        rate_hz: f64,
        /// The step, s.
        dt_s: f64,
        /// What is wrong.
        reason: StepsError,
    },
    /// A time not a whole number of steps.
    #[error("team.ranging.{key} = {} s {reason} of {} s", Echo(*.value), Echo(*.dt_s))]
    NotWholeSteps {
        /// The key.
        key: &'static str,
        /// Its value, s.
        value: f64,
        /// The step, s.
        dt_s: f64,
        /// What is wrong.
        reason: StepsError,
    },
}

/// One range: the measured distance, m, and whether it is valid (a neighbour that did not
/// answer, or a lost packet, gives an invalid range whose value is NaN).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Measured distance, m (NaN if invalid).
    pub range_m: f64,
    /// Whether the neighbour answered.
    pub valid: bool,
}

impl Range {
    /// An invalid range.
    pub const INVALID: Range = Range {
        range_m: f64::NAN,
        valid: false,
    };
}

/// The ranges of one sample, as delivered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangeSample {
    /// Time the ranges were measured, s.
    pub t_s: f64,
    /// To the neighbour ahead.
    pub ahead: Range,
    /// To the neighbour behind.
    pub behind: Range,
}

/// One vehicle's ranging unit.
#[derive(Clone, Debug)]
pub struct Ranging {
    cfg: RangingConfig,
    every: u64,
    countdown: u64,
    delay_steps: u64,
    in_flight: VecDeque<(u64, RangeSample)>,
    noise: ChaCha8Rng,
    dropout: ChaCha8Rng,
}

impl Ranging {
    /// A ranging unit for steps of `dt_s`, seeded by `seed` (noise and dropouts from their own
    /// streams, so turning one on leaves the other's draws as they were).
    pub fn new(cfg: RangingConfig, dt_s: f64, seed: u64) -> Result<Self, RangingError> {
        let bad = |key, value, expected| RangingError::OutOfRange {
            key,
            value,
            expected,
        };
        if !(cfg.rate_hz > 0.0 && cfg.rate_hz.is_finite()) {
            return Err(bad("rate_hz", cfg.rate_hz, "a positive finite rate"));
        }
        if !(cfg.noise_std_m >= 0.0 && cfg.noise_std_m.is_finite()) {
            return Err(bad("noise_std_m", cfg.noise_std_m, "finite and >= 0"));
        }
        if cfg.max_range_m.is_nan() || cfg.max_range_m <= 0.0 {
            return Err(bad("max_range_m", cfg.max_range_m, "> 0"));
        }
        if !(0.0..=1.0).contains(&cfg.dropout_probability) {
            return Err(bad(
                "dropout_probability",
                cfg.dropout_probability,
                "in [0, 1]",
            ));
        }
        let steps = |key, value: f64| {
            whole_steps(value, dt_s).map_err(|reason| RangingError::NotWholeSteps {
                key,
                value,
                dt_s,
                reason,
            })
        };
        let rate_error = |reason| RangingError::RateNotWholeSteps {
            rate_hz: cfg.rate_hz,
            dt_s,
            reason,
        };
        let every = whole_steps(1.0 / cfg.rate_hz, dt_s).map_err(rate_error)?;
        if every == 0 {
            return Err(rate_error(StepsError::NotWhole));
        }
        let delay_steps = steps("delay_s", cfg.delay_s)?;
        let mut dropout = ChaCha8Rng::seed_from_u64(seed);
        dropout.set_stream(1);
        Ok(Self {
            cfg,
            every,
            countdown: 0,
            delay_steps,
            in_flight: VecDeque::with_capacity((delay_steps / every + 1).min(1024) as usize),
            noise: ChaCha8Rng::seed_from_u64(seed),
            dropout,
        })
    }

    /// The settings.
    pub fn config(&self) -> &RangingConfig {
        &self.cfg
    }

    /// Steps between samples.
    pub fn steps_per_sample(&self) -> u64 {
        self.every
    }

    /// Steps between a sample's measurement and its delivery.
    pub fn delay_steps(&self) -> u64 {
        self.delay_steps
    }

    /// Whether step `k`'s call to [`observe`](Self::observe) measures (a countdown from step 0).
    #[inline(always)]
    pub fn measures_now(&self) -> bool {
        self.countdown == 0
    }

    /// Advances the schedule by one step; returns whether this step is a ranging step.
    #[inline(always)]
    pub fn tick(&mut self) -> bool {
        let now = self.countdown == 0;
        self.countdown = if now {
            self.every - 1
        } else {
            self.countdown - 1
        };
        now
    }

    /// One range to a neighbour at true distance `true_m` (`None`: it does not answer, e.g. it
    /// has left the run): noise and dropout are drawn on every call, valid or not, so that the
    /// streams stay aligned with the sample count.
    #[inline]
    pub fn measure(&mut self, true_m: Option<f64>) -> Range {
        let z: f64 = if self.cfg.noise_std_m > 0.0 {
            StandardNormal.sample(&mut self.noise)
        } else {
            0.0
        };
        let lost = self.cfg.dropout_probability > 0.0
            && rand::RngExt::random::<f64>(&mut self.dropout) < self.cfg.dropout_probability;
        match true_m {
            Some(r) if r.is_finite() && r <= self.cfg.max_range_m && !lost => Range {
                // A range is never negative.
                range_m: (r + self.cfg.noise_std_m * z).max(0.0),
                valid: true,
            },
            _ => Range::INVALID,
        }
    }

    /// Called at every step `k` (time `t_s`), in order: on a ranging step, measures the ranges
    /// from `me` to `ahead` and `behind` (`None`: no answer) and sends them; returns the sample
    /// delivered at this step, if any (measured `delay_s` earlier).
    #[inline]
    pub fn observe(
        &mut self,
        k: u64,
        t_s: f64,
        me: Vec2,
        ahead: Option<Vec2>,
        behind: Option<Vec2>,
    ) -> Option<RangeSample> {
        if self.tick() {
            let ahead = self.measure(ahead.map(|p| (p - me).norm()));
            let behind = self.measure(behind.map(|p| (p - me).norm()));
            let sample = RangeSample { t_s, ahead, behind };
            if self.delay_steps == 0 {
                return Some(sample);
            }
            self.in_flight.push_back((k + self.delay_steps, sample));
        }
        match self.in_flight.front() {
            Some(&(due, _)) if due <= k => self.in_flight.pop_front().map(|(_, s)| s),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg() -> RangingConfig {
        RangingConfig {
            rate_hz: 10.0,
            ..RangingConfig::default()
        }
    }

    /// att32: a rate whose period is no whole number of steps is named by its key with its
    /// value in Hz (not its period under the rate's key, in 16 digits), the period rounded, and
    /// the nearest valid rates `1/(k dt)`: 3 Hz at 0.01 s is 33.3 steps, so 1/0.34 s and
    /// 1/0.33 s, each accepted as written. Above `1/dt` (500 Hz) only `1/dt` itself.
    #[test]
    fn a_rate_off_the_steps_says_so_in_hz() {
        let at = |rate_hz| Ranging::new(RangingConfig { rate_hz, ..cfg() }, 0.01, 0);
        let e = at(3.0).unwrap_err().to_string();
        assert!(
            e.starts_with("team.ranging.rate_hz = 3 Hz: its period 0.333333 s is not a whole number of steps of 0.01 s"),
            "{e}"
        );
        assert!(!e.contains("0.3333333"), "{e}");
        let rates: Vec<f64> = e
            .split_once("nearest valid rates are ")
            .unwrap()
            .1
            .split(" and ")
            .map(|p| p.split(' ').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(rates.len(), 2, "{e}");
        for (got, want) in rates.iter().zip([1.0 / 0.34, 1.0 / 0.33]) {
            assert!((got / want - 1.0).abs() < 1e-8, "{got} vs {want}");
            assert!(at(*got).is_ok(), "{got}");
        }
        let e = at(500.0).unwrap_err().to_string();
        assert!(
            e.contains("rate_hz = 500 Hz") && e.contains("nearest valid rate is 100 Hz"),
            "{e}"
        );
    }

    /// Ideal ranging at 10 Hz with dt = 0.01 s: a sample every 10 steps, the true distances.
    #[test]
    fn ideal_samples_every_period() {
        let mut r = Ranging::new(cfg(), 0.01, 1).unwrap();
        let me = Vec2::new(0.0, 0.0);
        let mut got = vec![];
        for k in 0..35u64 {
            if let Some(s) = r.observe(
                k,
                k as f64 * 0.01,
                me,
                Some(Vec2::new(3.0, 4.0)),
                Some(Vec2::new(-1.0, 0.0)),
            ) {
                got.push((k, s));
            }
        }
        assert_eq!(got.iter().map(|g| g.0).collect::<Vec<_>>(), [0, 10, 20, 30]);
        assert_eq!(got[1].1.ahead.range_m, 5.0);
        assert_eq!(got[1].1.behind.range_m, 1.0);
        assert!(got[1].1.ahead.valid);
    }

    /// A delay of 0.25 s at 10 Hz: the sample of step 10 arrives at step 35, stamped 0.1 s; the
    /// queue holds at most ceil(25/10) samples.
    #[test]
    fn delay_delivers_later_in_order() {
        let c = RangingConfig {
            delay_s: 0.25,
            ..cfg()
        };
        let mut r = Ranging::new(c, 0.01, 1).unwrap();
        let mut got = vec![];
        for k in 0..60u64 {
            let p = Vec2::new(k as f64, 0.0);
            if let Some(s) = r.observe(k, k as f64 * 0.01, Vec2::new(0.0, 0.0), Some(p), None) {
                got.push((k, s));
            }
            assert!(r.in_flight.len() <= 3);
        }
        assert_eq!(
            got.iter().map(|g| g.0).collect::<Vec<_>>(),
            [25, 35, 45, 55]
        );
        assert_eq!(got[1].1.ahead.range_m, 10.0);
        assert!((got[1].1.t_s - 0.1).abs() < 1e-15);
        assert!(!got[1].1.behind.valid);
    }

    /// Beyond max_range: invalid; noise has the configured spread (the mean of 20 000 squared
    /// errors within 3 % of sigma^2); dropouts at their rate (within 5 standard errors); the
    /// same seed gives the same ranges.
    #[test]
    fn noise_dropout_range_and_seed() {
        let c = RangingConfig {
            noise_std_m: 0.2,
            max_range_m: 6.0,
            dropout_probability: 0.1,
            ..cfg()
        };
        let mut r = Ranging::new(c, 0.01, 7).unwrap();
        assert!(!r.measure(Some(6.5)).valid);
        let n = 20_000;
        let (mut sq, mut ok) = (0.0, 0);
        for _ in 0..n {
            let m = r.measure(Some(5.0));
            if m.valid {
                sq += (m.range_m - 5.0).powi(2);
                ok += 1;
            }
        }
        let var = sq / ok as f64;
        assert!((var / 0.04 - 1.0).abs() < 0.03, "{var}");
        let p_lost = 1.0 - ok as f64 / n as f64;
        let se = (0.1f64 * 0.9 / n as f64).sqrt();
        assert!((p_lost - 0.1).abs() < 5.0 * se, "{p_lost}");
        let mut a = Ranging::new(c, 0.01, 3).unwrap();
        let mut b = Ranging::new(c, 0.01, 3).unwrap();
        for _ in 0..100 {
            let (x, y) = (a.measure(Some(2.0)), b.measure(Some(2.0)));
            assert_eq!(x.range_m.to_bits(), y.range_m.to_bits());
        }
        assert!(Ranging::new(
            RangingConfig {
                rate_hz: 30.0,
                ..cfg()
            },
            0.01,
            0
        )
        .is_err());
        assert!(Ranging::new(
            RangingConfig {
                dropout_probability: 1.5,
                ..cfg()
            },
            0.01,
            0
        )
        .is_err());
    }
}
