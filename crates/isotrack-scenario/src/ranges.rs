//! The physical ranges of the keys that are not bounded by their meaning (README, "Scenario
//! files"): wide enough for any robot or aircraft, narrow enough that positions, path lengths
//! and step counts stay far from `f64` overflow.

/// Largest `|initial.x_m|`, `|initial.y_m|`, `|field.center_m|`, domain and source
/// coordinates, m (about 1.6 x the Earth's circumference).
pub const MAX_COORDINATE_M: f64 = 6.4e7;
/// Largest `|value|` of an analytic field's parameters (`i0`, `background`, `amplitude`,
/// `offset`, `gradient_per_m` per metre) and of `controller.level`: the grids' limit, so
/// values, differences and slopes stay finite (`isotrack_fields::grid::MAX_ABS_VALUE`).
pub const MAX_FIELD_VALUE: f64 = isotrack_fields::grid::MAX_ABS_VALUE;
/// Smallest plume width `sigma_m`, m: narrower plumes overflow `d^2/sigma^2`.
pub const MIN_LENGTH_M: f64 = 1.0e-9;
/// The most trace rows a run may write (`sim.duration_s * output.record_rate_hz`): about
/// 10 GB of CSV.
pub const MAX_TRACE_ROWS: u64 = 100_000_000;
/// Largest `vehicle.speed_mps` of the Dubins robot, m/s (well past any aircraft).
pub const MAX_SPEED_MPS: f64 = 1.0e3;
/// The Aerosonde model's airspeed range, m/s (`vehicle.airspeed_mps`, `isotrack trim`,
/// `isotrack replay`).
pub const AIRSPEED_RANGE_MPS: (f64, f64) = isotrack_vehicles::fixed_wing::trim::AIRSPEED_RANGE_MPS;
/// The held altitudes of the fixed-wing UAV, m: above the 50 m take-off zone, at most
/// 20 km (the model's atmosphere is constant).
pub const ALTITUDE_RANGE_M: (f64, f64) = (50.0, 20_000.0);
/// Largest `|vehicle.wind_mps|` component and `|field.drift_mps|` component, m/s.
pub const MAX_WIND_MPS: f64 = 1.0e2;
/// Largest `|initial.heading_rad|` and `|field.sources[i].rotation_rad|`, rad (about 159
/// turns): an angle is meant modulo 2 pi, and past about 1e16 rad a step's turn
/// `omega dt` is below one ulp of the heading (the turn vanishes); at 1e3 rad the ulp is
/// 1.1e-13 rad.
pub const MAX_ANGLE_RAD: f64 = 1.0e3;
