//! `[vehicle]`: the kind with its own parameters.

use super::settled;
use crate::issue::Issue;
use crate::schema::{VehicleKind, VehicleSection};
use isotrack_vehicles::FixedWingConfig;

/// Default `vehicle.speed_mps` of the Dubins robot, m/s (the paper's Fig. 2(b)).
pub const DUBINS_SPEED_MPS: f64 = 0.5;
/// Default `vehicle.airspeed_mps` of the fixed wing, m/s (Aerosonde trim, Beard & McLain).
pub const AIRSPEED_MPS: f64 = 30.0;
/// Default `vehicle.altitude_m` of the fixed wing, m.
pub const ALTITUDE_M: f64 = 100.0;
/// Default `vehicle.wind_mps`, m/s: calm.
pub const WIND_MPS: [f64; 2] = [0.0, 0.0];
/// Default `vehicle.gusts`: no Dryden gusts.
pub const GUSTS: bool = false;
/// Default `vehicle.trim_feedforward`: on (the book's autopilot; false is the 2012 code).
pub const TRIM_FEEDFORWARD: bool = true;
/// Default `vehicle.ecen674_gains`: off (the book's airspeed-gain formula).
pub const ECEN674_GAINS: bool = false;

/// `[vehicle]` resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VehicleSpec {
    /// `dubins`: constant speed, m/s.
    Dubins {
        /// Speed, m/s.
        speed_mps: f64,
    },
    /// `fixed_wing`: the Aerosonde's configuration (its gust seed is `sim.seed`).
    FixedWing(FixedWingConfig),
}

impl VehicleSpec {
    /// From a resolved `[vehicle]` and `sim.seed`.
    pub fn new(v: &VehicleSection, seed: u64) -> Result<Self, Issue> {
        Ok(match settled(&v.kind, "vehicle.kind")? {
            VehicleKind::Dubins => VehicleSpec::Dubins {
                speed_mps: settled(&v.speed_mps, "vehicle.speed_mps")?,
            },
            VehicleKind::FixedWing => VehicleSpec::FixedWing(FixedWingConfig {
                airspeed_mps: settled(&v.airspeed_mps, "vehicle.airspeed_mps")?,
                altitude_m: settled(&v.altitude_m, "vehicle.altitude_m")?,
                wind_mps: settled(&v.wind_mps, "vehicle.wind_mps")?,
                gusts: settled(&v.gusts, "vehicle.gusts")?,
                seed,
                trim_feedforward: settled(&v.trim_feedforward, "vehicle.trim_feedforward")?,
                ecen674_gains: settled(&v.ecen674_gains, "vehicle.ecen674_gains")?,
            }),
        })
    }

    /// The commanded speed, m/s: the Dubins robot's speed, the fixed wing's airspeed.
    pub fn speed_mps(&self) -> f64 {
        match self {
            VehicleSpec::Dubins { speed_mps } => *speed_mps,
            VehicleSpec::FixedWing(c) => c.airspeed_mps,
        }
    }
}
