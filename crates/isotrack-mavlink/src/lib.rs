//! # isotrack-mavlink
//!
//! The MAVLink 2 bridge, at the edge of the workspace (the `no_std` core and its laws know
//! nothing of MAVLink): [`sitl`] plays a scenario's vehicle, field and sensor as a MAVLink
//! vehicle; [`fly`] is the companion computer that flies the scenario's law on the measurements
//! it receives; [`wire`] is what the numbers become on the wire; [`mirror`] runs a scenario in
//! process with the same rounding, the reference a lockstep flight must reproduce bit for bit.
//! Framing, checksums and the common dialect are the `mavlink` crate's; [`link`] owns the link
//! (UDP, TCP or serial).
#![deny(missing_docs)]

pub mod fly;
pub mod geo;
pub mod link;
pub mod mirror;
pub mod modes;
pub mod record;
pub mod same_ids;
pub mod setpoint;
pub mod sitl;
pub mod vehicle_state;
pub mod wire;
