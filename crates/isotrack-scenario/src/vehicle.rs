//! The vehicle a resolved scenario flies, built from its spec ([`crate::spec::VehicleSpec`]).

use crate::schema::ScenarioFile;
use crate::spec::VehicleSpec;
use isotrack_vehicles::{Dubins, FixedWing};

/// Every vehicle a scenario can name.
#[derive(Clone, Debug)]
pub enum VehicleModel {
    /// `dubins`.
    Dubins(Dubins),
    /// `fixed_wing` (trimmed, gains computed).
    FixedWing(Box<FixedWing>),
}

impl VehicleModel {
    /// The turn rate the airframe can fly, rad/s: `g*tan(phi_max)/V` for the fixed wing
    /// ([`FixedWing::airframe_turn_rate_limit_radps`]); `None` for the Dubins robot (any).
    pub fn airframe_turn_rate_limit_radps(&self) -> Option<f64> {
        match self {
            VehicleModel::FixedWing(w) => Some(w.airframe_turn_rate_limit_radps()),
            VehicleModel::Dubins(_) => None,
        }
    }
}

/// Builds (and for the UAV, trims) the vehicle of a resolved scenario.
pub fn build_vehicle(f: &ScenarioFile) -> Result<VehicleModel, crate::resolve::Issue> {
    let seed = crate::spec::SimSpec::new(&f.sim)?.seed;
    Ok(match crate::spec::VehicleSpec::new(&f.vehicle, seed)? {
        VehicleSpec::Dubins { speed_mps } => VehicleModel::Dubins(Dubins { speed_mps }),
        VehicleSpec::FixedWing(cfg) => {
            VehicleModel::FixedWing(Box::new(FixedWing::new(cfg).map_err(|e| {
                crate::resolve::Issue {
                    key: "vehicle.airspeed_mps".into(),
                    message: e.to_string(),
                    unreadable: false,
                }
            })?))
        }
    })
}
