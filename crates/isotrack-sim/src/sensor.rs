//! The sensor: the only path from the world to a controller.
//!
//! Per simulation step `dt` the true value `x_k` passes through, in order: the sensing element's
//! first-order lag, the transport delay, sampling at the rate, additive noise and bias drift,
//! quantisation, the range, and dropouts ([`Sensor::observe`]).
//!
//! The lag (`time_constant_s = tau`) updates `y_k = y_{k-1} + (1 - exp(-dt/tau)) (x_k - y_{k-1})`:
//! the exact solution of `y' = (x - y)/tau` when the input is held at `x_k` over the step, so a
//! step input is followed exactly (`1 - exp(-t/tau)` at every step). It is not exact for an input
//! that changes within a step: on a ramp `x = r t` it settles at a lag
//! `x_k - y_k = r dt / (exp(dt/tau) - 1) = r (tau - dt/2 + dt^2/(12 tau) - ...)`, about
//! `r (tau - dt/2)`, where the continuous lag is `r tau` (derived from the update: a constant lag
//! `e` needs `e = (1 - a)(r dt + e)`, `a = 1 - exp(-dt/tau)`; tested). With `dt << tau` the
//! difference, `r dt / 2`, is small: 0.005 r at the default `dt = 0.01 s`.

use isotrack_core::numtext::{Echo, Num, NumDown};
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
    /// First-order response time constant, s (0: instantaneous): the sensing element follows
    /// the true value by `y' = (x - y)/tau` (metal-oxide gas sensors: 10-30 s), integrated
    /// over each step as `y += (1 - exp(-dt/tau)) (x - y)`, starting settled: exact for an input
    /// held over the step; on a ramp of slope `r` it lags by `r (tau - dt/2)` (to first order in
    /// `dt/tau`), not the continuous `r tau` (module docs).
    pub time_constant_s: f64,
    /// Output range `[min, max]` (saturation), field units.
    pub range: Option<[f64; 2]>,
    /// Output resolution, field units (0: none): readings are rounded to a multiple of it.
    pub resolution: f64,
    /// Probability that a sample is lost (the controller holds its last command).
    pub dropout_probability: f64,
    /// Bias random walk, field units per sqrt(s): the bias moves by `sigma*sqrt(T)*N(0,1)`
    /// at each sample `T` apart, starting at 0.
    pub bias_drift_per_sqrt_s: f64,
}

impl Default for SensorConfig {
    /// An ideal sensor at 1 Hz: no noise, delay, lag, limits, quantisation, dropouts or bias.
    fn default() -> Self {
        Self {
            rate_hz: 1.0,
            noise_std: 0.0,
            delay_s: 0.0,
            time_constant_s: 0.0,
            range: None,
            resolution: 0.0,
            dropout_probability: 0.0,
            bias_drift_per_sqrt_s: 0.0,
        }
    }
}

/// Why a [`SensorConfig`] cannot run at a given step size.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensorError {
    /// The sample period is not a whole number (>= 1) of steps, or too many.
    #[error("the sample period 1/{} s {reason} of {} s", Echo(*.rate_hz), Echo(*.dt_s))]
    RateNotMultiple {
        /// Requested rate, Hz.
        rate_hz: f64,
        /// Step, s.
        dt_s: f64,
        /// What is wrong with it.
        reason: StepsError,
    },
    /// The delay is not a whole number of steps, or too many.
    #[error("the delay {} s {reason} of {} s", Echo(*.delay_s), Echo(*.dt_s))]
    DelayNotMultiple {
        /// Requested delay, s.
        delay_s: f64,
        /// Step, s.
        dt_s: f64,
        /// What is wrong with it.
        reason: StepsError,
    },
    /// The delay holds more samples in flight than [`MAX_SAMPLES_IN_FLIGHT`].
    #[error(
        "the delay {} s holds {in_flight} samples in flight at {} Hz; at most {max} are allowed (delay <= {} s at this rate)",
        Echo(*.delay_s),
        Echo(*.rate_hz),
        NumDown(MAX_SAMPLES_IN_FLIGHT as f64 / *.rate_hz),
        max = MAX_SAMPLES_IN_FLIGHT
    )]
    DelayTooLong {
        /// Requested delay, s.
        delay_s: f64,
        /// Sampling rate, Hz.
        rate_hz: f64,
        /// Samples the delay would hold.
        in_flight: u64,
    },
    /// A setting in field units outside [`SENSOR_VALUE_RANGE`] (`resolution` may also be 0).
    #[error("{} field units is outside [{}, {}]", Echo(*.value), Echo(SENSOR_VALUE_RANGE.0), Echo(SENSOR_VALUE_RANGE.1))]
    OutOfRange {
        /// The setting: `resolution`, `noise_std` or `bias_drift_per_sqrt_s`.
        key: &'static str,
        /// Its value.
        value: f64,
    },
}

/// The range of the sensor's settings in field units besides 0 (`resolution`, `noise_std`,
/// `bias_drift_per_sqrt_s`, field units or field units per sqrt(s)). Field values are bounded
/// by 1e100 (`isotrack_fields::grid::MAX_ABS_VALUE`), so with settings in this range
/// `value/resolution` stays within 1e200 and `noise_std * n` within 1e101: no reading
/// overflows. (A resolution of 1e-310 made every reading `inf` while the run "completed".)
pub const SENSOR_VALUE_RANGE: (f64, f64) = (1e-100, 1e100);

/// Checks one setting against [`SENSOR_VALUE_RANGE`] (0 is allowed: the feature is off).
fn in_sensor_range(key: &'static str, value: f64) -> Result<(), SensorError> {
    let (lo, hi) = SENSOR_VALUE_RANGE;
    if value == 0.0 || (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(SensorError::OutOfRange { key, value })
    }
}

/// The most samples a delay may hold in flight (16 Mi values, 128 MiB): the delay line stores
/// one value per sample, not per step, so this bounds its memory whatever the step size.
pub const MAX_SAMPLES_IN_FLIGHT: u64 = 1 << 24;

/// The most steps any duration may span (a run, a sample period, a delay, a recording period):
/// 1e10 steps is 28 hours at the default 0.01 s step and well inside `f64`'s exact integers, so
/// step counts and step times stay exact.
pub const MAX_STEPS: u64 = 10_000_000_000;

/// Why a duration is not a usable step count.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StepsError {
    /// Not a whole number of steps (to 1e-9 relative), or negative, or not a number.
    #[error("is not a whole number of steps")]
    NotWhole,
    /// More than [`MAX_STEPS`] steps.
    #[error("is more than {MAX_STEPS} steps")]
    TooMany,
}

/// Converts a duration to a whole number of steps, if it is one (to 1e-9 relative) and at most
/// [`MAX_STEPS`]. The single rule used by validation and by the builders, so the two agree.
pub fn whole_steps(duration_s: f64, dt_s: f64) -> Result<u64, StepsError> {
    let n = duration_s / dt_s;
    let r = n.round();
    if !(n.is_finite() && r >= 0.0 && (n - r).abs() <= 1e-9 * r.max(1.0)) {
        // A huge finite count is "too many" before it is "not whole": at 1e17 steps every f64
        // is whole, and the honest complaint is the size.
        return Err(if n > MAX_STEPS as f64 {
            StepsError::TooMany
        } else {
            StepsError::NotWhole
        });
    }
    if r > MAX_STEPS as f64 {
        return Err(StepsError::TooMany);
    }
    Ok(r as u64)
}

/// A ChaCha8 generator for `seed` on its own stream.
fn stream(seed: u64, id: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(id);
    r
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
    delay_steps: u64,
    /// Steps until the true value is next stored: only the values of steps `j` with
    /// `(j + delay_steps) % every == 0` are ever delivered, so only those are kept.
    store_countdown: u64,
    /// Steps until the first delayed value exists (counts `delay_steps` down to 0).
    warmup: u64,
    noise_std: f64,
    history: VecDeque<f64>,
    rng: ChaCha8Rng,
    /// `1 - exp(-dt/tau)` (1 for an instantaneous sensor).
    lag_gain: f64,
    /// The sensing element's state (`None` before the first step: it starts settled).
    lagged: Option<f64>,
    range: Option<[f64; 2]>,
    resolution: f64,
    dropout_probability: f64,
    /// Bias step per sample, field units (`sigma*sqrt(T)`).
    bias_step: f64,
    bias: f64,
    /// Dropouts and bias walk draw from their own streams, so turning one on leaves the
    /// noise of every other sample as it was.
    dropout_rng: ChaCha8Rng,
    bias_rng: ChaCha8Rng,
    dropped: u64,
    /// No lag, delay, noise, bias, quantisation, range or dropouts: a sample is the true value
    /// on sample steps. [`observe`](Self::observe) then skips the rest of its checks (a
    /// tenth of the instructions of a 100 Hz run's step went to them).
    ideal: bool,
}

impl Sensor {
    /// A sensor for steps of `dt_s`, its noise seeded by `seed`.
    pub fn new(cfg: SensorConfig, dt_s: f64, seed: u64) -> Result<Self, SensorError> {
        in_sensor_range("resolution", cfg.resolution)?;
        in_sensor_range("noise_std", cfg.noise_std)?;
        in_sensor_range("bias_drift_per_sqrt_s", cfg.bias_drift_per_sqrt_s)?;
        let every = whole_steps(1.0 / cfg.rate_hz, dt_s)
            .and_then(|n| {
                if n >= 1 {
                    Ok(n)
                } else {
                    Err(StepsError::NotWhole)
                }
            })
            .map_err(|reason| SensorError::RateNotMultiple {
                rate_hz: cfg.rate_hz,
                dt_s,
                reason,
            })?;
        let delay_steps =
            whole_steps(cfg.delay_s, dt_s).map_err(|reason| SensorError::DelayNotMultiple {
                delay_s: cfg.delay_s,
                dt_s,
                reason,
            })?;
        let in_flight = delay_steps.div_ceil(every);
        if in_flight > MAX_SAMPLES_IN_FLIGHT {
            return Err(SensorError::DelayTooLong {
                delay_s: cfg.delay_s,
                rate_hz: cfg.rate_hz,
                in_flight,
            });
        }
        let lag_gain = if cfg.time_constant_s > 0.0 {
            -(-dt_s / cfg.time_constant_s).exp_m1()
        } else {
            1.0
        };
        let bias_step = cfg.bias_drift_per_sqrt_s * (every as f64 * dt_s).sqrt();
        // Each feature's own test in `observe` (a NaN setting is "off" there).
        let any_feature = lag_gain < 1.0
            || delay_steps > 0
            || cfg.noise_std > 0.0
            || bias_step > 0.0
            || cfg.resolution > 0.0
            || cfg.range.is_some()
            || cfg.dropout_probability > 0.0;
        Ok(Self {
            every,
            countdown: 0,
            delay_steps,
            store_countdown: (every - delay_steps % every) % every,
            warmup: delay_steps,
            noise_std: cfg.noise_std,
            // Grows as needed: a long delay allocates only what a run reaches.
            history: VecDeque::with_capacity((in_flight as usize + 1).min(4096)),
            rng: ChaCha8Rng::seed_from_u64(seed),
            lag_gain,
            lagged: None,
            range: cfg.range,
            resolution: cfg.resolution,
            dropout_probability: cfg.dropout_probability,
            bias_step,
            bias: 0.0,
            dropout_rng: stream(seed, 1),
            bias_rng: stream(seed, 2),
            dropped: 0,
            ideal: !any_feature,
        })
    }

    /// Steps between samples.
    pub fn steps_per_sample(&self) -> u64 {
        self.every
    }

    /// Samples lost to dropouts so far.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Called at every step `k = 0, 1, 2, ...`, in order and exactly once each, with the step's
    /// time and the true value at the vehicle. Returns the measurement on sample steps (`k` a
    /// multiple of the sample period) once the delay has filled, `None` otherwise.
    #[inline(always)]
    pub fn observe(&mut self, t_s: f64, true_value: f64) -> Option<Measurement> {
        if self.ideal {
            let sample_now = self.tick();
            return sample_now.then_some(Measurement {
                t_s,
                value: true_value,
            });
        }
        let true_value = self.lag(true_value);
        let sample_now = self.tick();
        let delayed = self.delayed(true_value, sample_now)?;
        if !sample_now {
            return None;
        }
        let value = self.corrupted(delayed);
        if self.dropout_probability > 0.0 {
            let u: f64 = rand::RngExt::random(&mut self.dropout_rng);
            if u < self.dropout_probability {
                self.dropped += 1;
                return None;
            }
        }
        Some(Measurement { t_s, value })
    }

    /// Whether this step is a sample step, the countdown to the next one advanced: samples
    /// fall every `every` steps, from step 0.
    #[inline(always)]
    fn tick(&mut self) -> bool {
        let sample_now = self.countdown == 0;
        self.countdown = if sample_now {
            self.every - 1
        } else {
            self.countdown - 1
        };
        sample_now
    }

    /// The sensing element's first-order lag, acting on the true value at every step:
    /// `y += g (x - y)` from `y = x` at the first step (the value itself without a lag,
    /// `g = 1`).
    #[inline(always)]
    fn lag(&mut self, true_value: f64) -> f64 {
        if self.lag_gain < 1.0 {
            let y = self.lagged.get_or_insert(true_value);
            *y += self.lag_gain * (true_value - *y);
            *y
        } else {
            true_value
        }
    }

    /// The value the delay line gives at this step (`sample_now`: a sample step): without a
    /// delay the value itself; else the value of step `k - delay_steps` on a sample step once
    /// the delay has filled, `None` before or between samples. Only the steps that will be
    /// sampled are stored, one every `every` steps.
    #[inline(always)]
    fn delayed(&mut self, true_value: f64, sample_now: bool) -> Option<f64> {
        if self.delay_steps == 0 {
            return Some(true_value);
        }
        if self.store_countdown == 0 {
            self.history.push_back(true_value);
            self.store_countdown = self.every - 1;
        } else {
            self.store_countdown -= 1;
        }
        if self.warmup > 0 {
            self.warmup -= 1;
            return None;
        }
        if !sample_now {
            return None;
        }
        // The front is the value of step `k - delay_steps`: stored steps and sample steps
        // are both `every` apart, and the first stored one is the first with
        // `j + delay_steps` a multiple of `every`.
        self.history.pop_front()
    }

    /// A sample's value as the instrument reports it: plus white noise and the bias's random
    /// walk (each stream drawn only when present), quantised to the resolution, clamped to the
    /// range.
    #[inline(always)]
    fn corrupted(&mut self, delayed: f64) -> f64 {
        let noise = if self.noise_std > 0.0 {
            let n: f64 = StandardNormal.sample(&mut self.rng);
            self.noise_std * n
        } else {
            0.0
        };
        if self.bias_step > 0.0 {
            let n: f64 = StandardNormal.sample(&mut self.bias_rng);
            self.bias += self.bias_step * n;
        }
        // Noise and bias are added only when present: `x + 0.0` is not free on the step's chain
        // of dependent operations (and the same number but for the sign of a zero).
        let mut value = delayed;
        if self.noise_std > 0.0 {
            value += noise;
        }
        if self.bias != 0.0 {
            value += self.bias;
        }
        if self.resolution > 0.0 {
            value = (value / self.resolution).round() * self.resolution;
        }
        if let Some([lo, hi]) = self.range {
            value = value.clamp(lo, hi);
        }
        value
    }
}

/// The valid sampling rates nearest `rate_hz` at step `dt_s`, as a sentence: `1/(k dt)` for the
/// whole step counts `k = floor(n)` (the next rate above) and `k = ceil(n)` (the next below)
/// round the period's `n = 1/(rate_hz dt_s)` steps, kept in `1..=MAX_STEPS` (a rate above
/// `1/dt` has only the one below: one step per period). Each rate is written as the shortest
/// decimal that is itself valid (a rate rounded to six digits, `3.0303` for `1/0.33 s`, would be
/// refused again: the period must be whole to 1e-9 relative, [`whole_steps`]).
pub fn nearest_valid_rates(rate_hz: f64, dt_s: f64) -> String {
    let n = 1.0 / (rate_hz * dt_s);
    let max = MAX_STEPS as f64;
    let mut ks: Vec<f64> = [n.floor(), n.ceil()]
        .into_iter()
        .map(|k| {
            if k.is_finite() {
                k.clamp(1.0, max)
            } else {
                max
            }
        })
        .collect();
    ks.dedup();
    // The lower rate (more steps) first.
    ks.sort_by(|a, b| b.total_cmp(a));
    ks.dedup();
    let text: Vec<String> = ks
        .iter()
        .map(|&k| {
            let exact = 1.0 / (k * dt_s);
            let valid = (0..17)
                .filter_map(|d| format!("{exact:.d$e}").parse::<f64>().ok())
                .find(|&v| whole_steps(1.0 / v, dt_s) == Ok(k as u64))
                .unwrap_or(exact);
            format!(
                "{} Hz ({} step{} of {} s, a period of {} s)",
                Echo(valid),
                Num(k),
                if k == 1.0 { "" } else { "s" },
                Echo(dt_s),
                Num(k * dt_s)
            )
        })
        .collect();
    match text.as_slice() {
        [one] => format!("the nearest valid rate is {one}"),
        _ => format!("the nearest valid rates are {}", text.join(" and ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ideal sensor's shortcut gives what the general path gives: the same sensor with a
    /// range that clips nothing (which takes the general path) reports the same samples at the
    /// same steps, bit for bit, at 100 Hz and every third step.
    #[test]
    fn the_ideal_shortcut_is_the_general_path() {
        for rate_hz in [100.0, 100.0 / 3.0] {
            let ideal = SensorConfig {
                rate_hz,
                ..SensorConfig::default()
            };
            let general = SensorConfig {
                range: Some([f64::NEG_INFINITY, f64::INFINITY]),
                ..ideal
            };
            let mut a = Sensor::new(ideal, 0.01, 3).unwrap();
            let mut b = Sensor::new(general, 0.01, 3).unwrap();
            assert!(a.ideal && !b.ideal);
            let mut delivered = 0;
            for k in 0..300u64 {
                let (t, v) = (k as f64 * 0.01, (k as f64 * 0.37).sin() * 1e3);
                let (ma, mb) = (a.observe(t, v), b.observe(t, v));
                assert_eq!(
                    ma.map(|m| (m.t_s.to_bits(), m.value.to_bits())),
                    mb.map(|m| (m.t_s.to_bits(), m.value.to_bits())),
                    "step {k}"
                );
                delivered += usize::from(ma.is_some());
            }
            assert_eq!(delivered, if rate_hz == 100.0 { 300 } else { 100 });
        }
        // Each feature on its own leaves the shortcut.
        let base = SensorConfig::default();
        for cfg in [
            SensorConfig {
                noise_std: 0.1,
                ..base
            },
            SensorConfig {
                delay_s: 0.02,
                ..base
            },
            SensorConfig {
                time_constant_s: 0.5,
                ..base
            },
            SensorConfig {
                resolution: 0.01,
                ..base
            },
            SensorConfig {
                range: Some([0.0, 1.0]),
                ..base
            },
            SensorConfig {
                dropout_probability: 0.1,
                ..base
            },
            SensorConfig {
                bias_drift_per_sqrt_s: 0.1,
                ..base
            },
        ] {
            assert!(!Sensor::new(cfg, 0.01, 0).unwrap().ideal, "{cfg:?}");
        }
        assert!(Sensor::new(base, 0.01, 0).unwrap().ideal);
    }

    #[test]
    fn samples_at_rate_with_delay() {
        let cfg = SensorConfig {
            rate_hz: 10.0,
            noise_std: 0.0,
            delay_s: 0.2,
            ..SensorConfig::default()
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

    /// Against the definition: a sample at step `k` (a multiple of the period, `k >= d`) reports
    /// the true value of step `k - d`, for delays shorter than, equal to and longer than the
    /// sample period and not multiples of it.
    #[test]
    fn delay_line_delivers_the_value_of_step_k_minus_d() {
        for every in [1u64, 3, 10] {
            for d in [0u64, 1, 2, 3, 7, 10, 23, 30] {
                let cfg = SensorConfig {
                    rate_hz: 100.0 / every as f64,
                    noise_std: 0.0,
                    delay_s: d as f64 * 0.01,
                    ..SensorConfig::default()
                };
                let mut s = Sensor::new(cfg, 0.01, 1).unwrap();
                for k in 0..200u64 {
                    let got = s.observe(k as f64, k as f64 * 2.0 + 1.0).map(|m| m.value);
                    let want = (k % every == 0 && k >= d).then(|| (k - d) as f64 * 2.0 + 1.0);
                    assert_eq!(got, want, "every {every}, delay {d}, step {k}");
                }
                assert!(s.history.len() as u64 <= d.div_ceil(every) + 1);
            }
        }
    }

    #[test]
    fn rejects_a_delay_beyond_the_samples_in_flight_bound() {
        let cfg = |delay_s| SensorConfig {
            rate_hz: 100.0,
            noise_std: 0.0,
            delay_s,
            ..SensorConfig::default()
        };
        // 1e16 s at 0.01 s steps: 1e18 steps; before the bound this panicked in the builder.
        assert!(matches!(
            Sensor::new(cfg(1.0e16), 0.01, 1),
            Err(SensorError::DelayNotMultiple {
                reason: StepsError::TooMany,
                ..
            })
        ));
        assert!(matches!(
            Sensor::new(cfg(1.1e7), 0.001, 1),
            Err(SensorError::DelayNotMultiple {
                reason: StepsError::TooMany,
                ..
            })
        ));
        assert!(matches!(
            Sensor::new(cfg(1.0e6), 0.01, 1),
            Err(SensorError::DelayTooLong {
                in_flight: 100_000_000,
                ..
            })
        ));
        let ok = Sensor::new(cfg(1.0e5), 0.01, 1).unwrap();
        assert!(ok.history.capacity() < 10_000, "allocates lazily");
    }

    /// The first-order lag against its closed form: a unit step at t = 0 read through
    /// `tau = 2 s` is `1 - exp(-t/tau)` at every sample, exactly (the discretisation is exact for
    /// a step held over each step).
    #[test]
    fn first_order_step_response_is_the_closed_form() {
        let cfg = SensorConfig {
            rate_hz: 10.0,
            time_constant_s: 2.0,
            ..SensorConfig::default()
        };
        let mut s = Sensor::new(cfg, 0.01, 1).unwrap();
        // Settled at 0 before the step: the first step sees 0, then 1 from step 1 on.
        let mut got = vec![];
        for k in 0..1001u64 {
            let x = if k == 0 { 0.0 } else { 1.0 };
            if let Some(m) = s.observe(k as f64 * 0.01, x) {
                got.push((k, m.value));
            }
        }
        for (k, v) in got {
            let want = 1.0 - (-(k as f64 * 0.01) / 2.0).exp();
            assert!((v - want).abs() < 1e-12, "step {k}: {v} vs {want}");
        }
    }

    /// The lag on a ramp `x_k = r k dt`, against the value derived by hand from the update
    /// `y_k = y_{k-1} + a (x_k - y_{k-1})`, `a = 1 - exp(-dt/tau)`: a constant lag `e = x_k - y_k`
    /// satisfies `e = (1 - a)(r dt + e)`, so `e = r dt (1 - a)/a = r dt / (exp(dt/tau) - 1)`,
    /// whose expansion is `r (tau - dt/2 + dt^2/(12 tau) - ...)`. At dt = 0.1 s, tau = 0.3 s,
    /// r = 2: e = 0.2/(e^(1/3) - 1) = 0.505545..., within r dt^2/(12 tau) = 0.00556 of
    /// r (tau - dt/2) = 0.5 and 0.1 short of the continuous lag r tau = 0.6 (about r dt/2).
    #[test]
    fn first_order_lag_on_a_ramp_is_r_tau_minus_half_a_step() {
        for (dt, tau, r) in [(0.1, 0.3, 2.0), (0.01, 2.0, 0.5)] {
            let cfg = SensorConfig {
                rate_hz: 1.0 / dt,
                time_constant_s: tau,
                ..SensorConfig::default()
            };
            let mut s = Sensor::new(cfg, dt, 1).unwrap();
            // 60 time constants: the start's transient, (1 - a)^k = exp(-k dt/tau), is gone.
            let steps = (60.0 * tau / dt) as u64;
            let mut lag = f64::NAN;
            for k in 0..=steps {
                let x = r * k as f64 * dt;
                lag = x - s.observe(k as f64 * dt, x).unwrap().value;
            }
            let exact = r * dt / ((dt / tau).exp() - 1.0);
            assert!((lag - exact).abs() < 1e-9 * r * tau, "{lag} vs {exact}");
            let first_order = r * (tau - dt / 2.0);
            assert!((lag - first_order).abs() <= 1.01 * r * dt * dt / (12.0 * tau));
            assert!(((r * tau - lag) - r * dt / 2.0).abs() <= 1.01 * r * dt * dt / (12.0 * tau));
        }
    }

    /// Quantisation rounds to the resolution, then the range saturates.
    #[test]
    fn resolution_and_range() {
        let cfg = SensorConfig {
            rate_hz: 100.0,
            resolution: 0.25,
            range: Some([-1.0, 2.0]),
            ..SensorConfig::default()
        };
        let mut s = Sensor::new(cfg, 0.01, 1).unwrap();
        let read = |s: &mut Sensor, x| s.observe(0.0, x).unwrap().value;
        assert_eq!(read(&mut s, 0.37), 0.25);
        assert_eq!(read(&mut s, 0.38), 0.5);
        assert_eq!(read(&mut s, -3.0), -1.0);
        assert_eq!(read(&mut s, 7.1), 2.0);
    }

    /// Dropouts: the count equals the draws below `p` on the sensor's own stream (stream 1 of
    /// the seed), reproduced here independently; noise on other samples is unchanged.
    #[test]
    fn dropouts_are_exact_and_leave_the_noise_alone() {
        let base = SensorConfig {
            rate_hz: 100.0,
            noise_std: 0.3,
            ..SensorConfig::default()
        };
        let with = SensorConfig {
            dropout_probability: 0.2,
            ..base
        };
        let (mut a, mut b) = (
            Sensor::new(base, 0.01, 9).unwrap(),
            Sensor::new(with, 0.01, 9).unwrap(),
        );
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        rng.set_stream(1);
        let mut want_dropped = 0;
        for k in 0..5000u64 {
            let ma = a.observe(k as f64, 1.0).unwrap();
            let u: f64 = rand::RngExt::random(&mut rng);
            let mb = b.observe(k as f64, 1.0);
            if u < 0.2 {
                want_dropped += 1;
                assert!(mb.is_none());
            } else {
                assert_eq!(mb.unwrap().value, ma.value, "same noise draw");
            }
        }
        assert_eq!(b.dropped(), want_dropped);
        assert!((800..1200).contains(&want_dropped), "{want_dropped}");
    }

    /// The bias walk has variance `sigma^2 * t`: over 400 seeded sensors, at t = 100 s the
    /// sample variance of the reading is 0.01^2 * 100 = 0.01 within 15 %.
    #[test]
    fn bias_random_walk_variance() {
        let cfg = SensorConfig {
            rate_hz: 1.0,
            bias_drift_per_sqrt_s: 0.01,
            ..SensorConfig::default()
        };
        let finals: Vec<f64> = (0..400u64)
            .map(|seed| {
                let mut s = Sensor::new(cfg, 0.1, seed).unwrap();
                let mut last = 0.0;
                for k in 0..1000u64 {
                    if let Some(m) = s.observe(k as f64 * 0.1, 0.0) {
                        last = m.value;
                    }
                }
                last
            })
            .collect();
        let n = finals.len() as f64;
        let mean = finals.iter().sum::<f64>() / n;
        let var = finals.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        // 100 samples 1 s apart: t = 100 s of walk.
        assert!((var - 0.01).abs() < 0.15 * 0.01, "{var}");
    }

    #[test]
    fn rejects_incommensurate_rate() {
        let cfg = SensorConfig {
            rate_hz: 30.0,
            noise_std: 0.0,
            delay_s: 0.0,
            ..SensorConfig::default()
        };
        assert!(Sensor::new(cfg, 0.01, 1).is_err());
        let cfg = SensorConfig {
            rate_hz: 1000.0,
            noise_std: 0.0,
            delay_s: 0.0,
            ..SensorConfig::default()
        };
        assert!(Sensor::new(cfg, 0.01, 1).is_err(), "faster than the step");
    }

    #[test]
    fn noise_is_seeded_and_has_the_right_spread() {
        let cfg = SensorConfig {
            rate_hz: 100.0,
            noise_std: 0.5,
            delay_s: 0.0,
            ..SensorConfig::default()
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
