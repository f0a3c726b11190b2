//! # isotrack-vehicles
//!
//! Vehicle models behind the [`Vehicle`] trait of `isotrack-core`: a turn-rate command in, a pose
//! out, each model owning its integrator.
//!
//! * [`dubins`]: the paper's Dubins robot (eq. (5)), RK4 with the command held over the step.
#![deny(missing_docs)]

pub mod dubins;

pub use dubins::{Dubins, DubinsState};
pub use isotrack_core::Vehicle;
