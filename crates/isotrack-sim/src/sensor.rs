//! The sensor: the only path from the world to a controller.

use isotrack_core::Measurement;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::VecDeque;

/// Sensor settings in physical units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorConfig {
    /// Sampling rate, Hz (> 0). The sample period must be a whole number of simulation steps.
    pub rate_hz: f64,
    /// Standard deviation of the additive white Gaussian noise, field units (>= 0).
    pub noise_std: f64,
    /// Transport delay, seconds (>= 0): a whole number of simulation steps.
    pub delay_s: f64,
}

/// Why a [`SensorConfig`] cannot run at a given step size.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensorError {
    /// The sample period is not a whole number of steps.
    #[error("the sample period 1/{rate_hz} s is not a whole number of steps of {dt_s} s")]
    RateNotMultiple {
        /// Requested rate, Hz.
        rate_hz: f64,
        /// Step, s.
        dt_s: f64,
    },
    /// The delay is not a whole number of steps.
    #[error("the delay {delay_s} s is not a whole number of steps of {dt_s} s")]
    DelayNotMultiple {
        /// Requested delay, s.
        delay_s: f64,
        /// Step, s.
        dt_s: f64,
    },
}

/// Converts a duration to a whole number of steps, if it is one (to 1e-9 relative).
pub(crate) fn whole_steps(duration_s: f64, dt_s: f64) -> Option<u64> {
    let n = duration_s / dt_s;
    let r = n.round();
    ((n - r).abs() <= 1e-9 * r.max(1.0) && (0.0..9.0e15).contains(&r)).then_some(r as u64)
}

/// Samples the true field value every `rate_hz`, delays it by `delay_s`, adds seeded Gaussian
/// noise: `s_meas(t_k) = F(p(t_k - delay)) + noise_std * n_k`, `n_k ~ N(0, 1)` from a ChaCha8
/// stream seeded by the run's seed, so a run is reproducible bit for bit.
///
/// The measurement carries the time it is delivered (`t_k`); the controller does not know the
/// delay. Before the first delayed value exists the sensor delivers nothing and the controller's
/// initial command (zero) is held.
#[derive(Clone, Debug)]
pub struct Sensor {
    every: u64,
    /// Steps until the next sample (a countdown instead of `k % every`: a 64-bit division per
    /// step costs more than the rest of the sensor).
    countdown: u64,
    delay_steps: usize,
    noise_std: f64,
    history: VecDeque<f64>,
    rng: ChaCha8Rng,
}

impl Sensor {
    /// A sensor for steps of `dt_s`, its noise seeded by `seed`.
    pub fn new(cfg: SensorConfig, dt_s: f64, seed: u64) -> Result<Self, SensorError> {
        let every = whole_steps(1.0 / cfg.rate_hz, dt_s)
            .filter(|&n| n >= 1)
            .ok_or(SensorError::RateNotMultiple {
                rate_hz: cfg.rate_hz,
                dt_s,
            })?;
        let delay_steps = whole_steps(cfg.delay_s, dt_s).ok_or(SensorError::DelayNotMultiple {
            delay_s: cfg.delay_s,
            dt_s,
        })? as usize;
        Ok(Self {
            every,
            countdown: 0,
            delay_steps,
            noise_std: cfg.noise_std,
            history: VecDeque::with_capacity(delay_steps + 1),
            rng: ChaCha8Rng::seed_from_u64(seed),
        })
    }

    /// Steps between samples.
    pub fn steps_per_sample(&self) -> u64 {
        self.every
    }

    /// Called at every step `k = 0, 1, 2, ...`, in order and exactly once each, with the step's
    /// time and the true value at the vehicle. Returns the measurement on sample steps (`k` a
    /// multiple of the sample period) once the delay has filled, `None` otherwise.
    pub fn observe(&mut self, t_s: f64, true_value: f64) -> Option<Measurement> {
        let sample_now = self.countdown == 0;
        self.countdown = if sample_now {
            self.every - 1
        } else {
            self.countdown - 1
        };
        let delayed = if self.delay_steps == 0 {
            true_value
        } else {
            self.history.push_back(true_value);
            if self.history.len() <= self.delay_steps {
                return None;
            }
            self.history.pop_front()?
        };
        if !sample_now {
            return None;
        }
        let noise = if self.noise_std > 0.0 {
            let n: f64 = StandardNormal.sample(&mut self.rng);
            self.noise_std * n
        } else {
            0.0
        };
        Some(Measurement {
            t_s,
            value: delayed + noise,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_at_rate_with_delay() {
        let cfg = SensorConfig {
            rate_hz: 10.0,
            noise_std: 0.0,
            delay_s: 0.2,
        };
        let mut s = Sensor::new(cfg, 0.01, 1).unwrap();
        assert_eq!(s.steps_per_sample(), 10);
        let mut got = vec![];
        for k in 0..100u64 {
            if let Some(m) = s.observe(k as f64 * 0.01, k as f64) {
                got.push((k, m.value));
            }
        }
        // First sample at k = 20 (delay filled), reporting the value of step 0.
        assert_eq!(got[0], (20, 0.0));
        assert_eq!(got[1], (30, 10.0));
        assert_eq!(got.len(), 8);
    }

    #[test]
    fn rejects_incommensurate_rate() {
        let cfg = SensorConfig {
            rate_hz: 30.0,
            noise_std: 0.0,
            delay_s: 0.0,
        };
        assert!(Sensor::new(cfg, 0.01, 1).is_err());
        let cfg = SensorConfig {
            rate_hz: 1000.0,
            noise_std: 0.0,
            delay_s: 0.0,
        };
        assert!(Sensor::new(cfg, 0.01, 1).is_err(), "faster than the step");
    }

    #[test]
    fn noise_is_seeded_and_has_the_right_spread() {
        let cfg = SensorConfig {
            rate_hz: 100.0,
            noise_std: 0.5,
            delay_s: 0.0,
        };
        let draw = |seed| {
            let mut s = Sensor::new(cfg, 0.01, seed).unwrap();
            (0..20000u64)
                .map(|_| s.observe(0.0, 3.0).unwrap().value)
                .collect::<Vec<_>>()
        };
        let a = draw(7);
        assert_eq!(a, draw(7));
        assert_ne!(a, draw(8));
        let n = a.len() as f64;
        let mean = a.iter().sum::<f64>() / n;
        let var = a.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        // Mean 3 within 4 standard errors (0.5/sqrt(20000) = 0.0035); std 0.5 within 3 %.
        assert!((mean - 3.0).abs() < 0.015, "mean {mean}");
        assert!((var.sqrt() - 0.5).abs() < 0.015, "std {}", var.sqrt());
    }
}
