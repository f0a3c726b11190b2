//! `[sensor]`: the sensor's configuration, every key settled (`range` stays optional: no range
//! is a setting of its own, readings do not saturate).

use super::settled;
use crate::issue::Issue;
use crate::schema::SensorSection;
use isotrack_sim::SensorConfig;

/// Default `sensor.noise_std`, field units: noiseless (the paper's simulations).
pub const NOISE_STD: f64 = 0.0;
/// Default `sensor.delay_s`, s: none.
pub const DELAY_S: f64 = 0.0;
/// Default `sensor.time_constant_s`, s: an instantaneous response.
pub const TIME_CONSTANT_S: f64 = 0.0;
/// Default `sensor.resolution`, field units: no rounding.
pub const RESOLUTION: f64 = 0.0;
/// Default `sensor.dropout_probability`: no sample lost.
pub const DROPOUT_PROBABILITY: f64 = 0.0;
/// Default `sensor.bias_drift_per_sqrt_s`, field units per sqrt(s): no drift.
pub const BIAS_DRIFT_PER_SQRT_S: f64 = 0.0;

/// The default `sensor.rate_hz`: one sample a step, `1/dt_s` Hz (written into the resolved
/// file, so `show` prints it and a run's `scenario.toml` records it).
pub fn default_rate_hz(dt_s: f64) -> f64 {
    1.0 / dt_s
}

/// The sensor of a resolved `[sensor]`.
pub fn sensor_config(s: &SensorSection) -> Result<SensorConfig, Issue> {
    Ok(SensorConfig {
        rate_hz: settled(&s.rate_hz, "sensor.rate_hz")?,
        noise_std: settled(&s.noise_std, "sensor.noise_std")?,
        delay_s: settled(&s.delay_s, "sensor.delay_s")?,
        time_constant_s: settled(&s.time_constant_s, "sensor.time_constant_s")?,
        range: s.range,
        resolution: settled(&s.resolution, "sensor.resolution")?,
        dropout_probability: settled(&s.dropout_probability, "sensor.dropout_probability")?,
        bias_drift_per_sqrt_s: settled(&s.bias_drift_per_sqrt_s, "sensor.bias_drift_per_sqrt_s")?,
    })
}
