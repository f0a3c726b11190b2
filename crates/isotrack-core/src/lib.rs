//! # isotrack-core
//!
//! The `no_std` heart of isotrack: everything a coordinate-free isoline tracker needs on board,
//! and the traits the rest of the toolkit plugs into.
//!
//! * [`control`]: the controller trait ([`control::IsolineController`]) that sees only
//!   [`control::Measurement`]s (a time stamp and a field value, nothing else), and Dong & You's
//!   PI-like law ([`control::PiIsoline`]).
//! * [`estimate`]: derivative estimators that turn the sampled measurement into `eps'`.
//! * [`field`]: the scalar-field traits. A controller never gets a field; the sensor does.
//! * [`vehicle`]: the vehicle trait (a turn-rate command in, a pose out).
//! * [`theory`]: closed forms from the paper and our derivations (steady states, stability
//!   conditions), used by checks and by tests as independent oracles.
//! * [`spacing`]: the theory of a team's spacing loop (ring Laplacian, sampled and delayed).
//! * [`math`]: small 2-D geometry helpers.
//! * [`lanes`]: elementary functions (`exp`, `tanh`, `sin_cos`) written once, branch-free, for
//!   one value and for `N` lanes at a time.
//! * [`numtext`]: the one formatting of numbers and user text in messages.
//!
//! Sign conventions, everywhere: x east, y north, heading counter-clockwise from +x, and a
//! positive turn rate turns left (counter-clockwise seen from above).
#![no_std]
#![deny(missing_docs)]

pub mod control;
pub mod estimate;
pub mod field;
mod fmath;
pub mod lanes;
pub mod math;
pub mod numtext;
pub mod spacing;
pub mod theory;
pub mod vehicle;

pub use control::{IsolineController, Measurement};
pub use field::{FieldDerivatives, ScalarField};
pub use math::{Pose2, Vec2};
pub use vehicle::{SpeedCommand, Vehicle};
