//! # isotrack-vehicles
//!
//! Vehicle models behind the [`Vehicle`] trait of `isotrack-core`: a turn-rate command in, a pose
//! out, each model owning its integrator.
//!
//! * [`dubins`]: the paper's Dubins robot (eq. (5)), RK4 with the command held over the step.
//! * [`fixed_wing`]: the Aerosonde 6-DOF UAV with Beard & McLain's autopilot, trim, gains, and
//!   Dryden wind (the paper's Sec. VI-C vehicle).
#![deny(missing_docs)]

pub mod dubins;
pub mod fixed_wing;

pub use dubins::{Dubins, DubinsSpeedState, DubinsState, DubinsVariableSpeed};
pub use fixed_wing::{
    AirspeedEnvelopeError, FixedWing, FixedWingConfig, FixedWingState, FixedWingVariableSpeed,
    COMMANDED_AIRSPEED_RANGE_MPS,
};
pub use isotrack_core::{SpeedCommand, Vehicle};
