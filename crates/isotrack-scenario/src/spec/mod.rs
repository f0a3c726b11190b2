//! The resolved scenario as typed values: what a run is built from.
//!
//! [`crate::resolve::resolve`] fills every default into the (everything-optional)
//! [`ScenarioFile`] and validates it; [`ScenarioSpec::new`] then reads that file once into plain,
//! typed fields: per-kind enums with their own parameters ([`LawSpec::PiIsoline`] holds
//! `kp, ki, c1, c2, ..`), no `Option` that resolution settles (an `Option` left here is a choice
//! of the user's: no turn-rate limit, no sensor range, no search), and the derived values (the
//! fixed-wing's turn-rate limit `g*tan(phi_max)/V`, the search geometry, the convergence dwell,
//! the track-loss band) computed once. Consumers read the spec; none falls back to a default of
//! its own.
//!
//! Every default is written once, as a `const` in the section's module (with its source), and
//! used by `resolve` (which writes it into the resolved file, so that `scenario.toml` records
//! it) or, for the derived ones, by the section's constructor here.
//!
//! One file per section: [`field`], [`controller`], [`sensor`], [`vehicle`], [`sim`] (`[sim]`,
//! `[metrics]`, `[output]`, `[initial]`, `[sitl]`), [`team`]. The field is built from its spec
//! by [`crate::field::build_field`]; a grid's or the stations' files fill the keys the scenario
//! leaves to them (spacing, origin, units), which are recorded into the resolved file before
//! the scenario's spec is read from it.

pub mod controller;
pub mod field;
pub mod sensor;
pub mod show;
pub mod sim;
pub mod team;
pub mod vehicle;

pub use controller::{ControllerSpec, LawSpec, TurnRateLimit};
pub use field::{FieldKindSpec, FieldSpec};
pub use sim::{MetricsSpec, OutputSpec, SimSpec, SitlSpec};
pub use team::TeamSpec;
pub use vehicle::VehicleSpec;

pub(crate) use crate::issue::settled;
use crate::issue::Issue;
use crate::schema::ScenarioFile;
use isotrack_sim::SensorConfig;
pub use sim::Start;

/// A resolved scenario's settings, every one explicit (see the [module](self) docs).
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioSpec {
    /// `[sim]`.
    pub sim: SimSpec,
    /// `[field]`, with what its files filled in.
    pub field: FieldSpec,
    /// `[vehicle]`.
    pub vehicle: VehicleSpec,
    /// `[initial]`: the start pose.
    pub start: Start,
    /// `[sensor]`.
    pub sensor: SensorConfig,
    /// `[controller]`, with the derived turn-rate limit and search geometry.
    pub controller: ControllerSpec,
    /// `[metrics]`, with the derived dwell and track-loss band.
    pub metrics: MetricsSpec,
    /// `[output]`.
    pub output: OutputSpec,
    /// `[sitl]`, the home position with its defaults.
    pub sitl: SitlSpec,
    /// `[team]`: several vehicles sharing one clock and one field (`None`: one vehicle).
    pub team: Option<TeamSpec>,
}

impl ScenarioSpec {
    /// The spec of a file [`crate::resolve::resolve`] has resolved. `airframe_turn_rate_limit_radps`
    /// is what the built vehicle can fly (`g*tan(phi_max)/V` for the fixed wing,
    /// [`isotrack_vehicles::FixedWing::airframe_turn_rate_limit_radps`]; `None` for the Dubins
    /// robot). A key resolution should have settled but did not is an [`Issue`] naming it, not a
    /// panic (it cannot happen for a file out of `resolve`).
    pub fn new(
        f: &ScenarioFile,
        airframe_turn_rate_limit_radps: Option<f64>,
    ) -> Result<Self, Issue> {
        let sim = SimSpec::new(&f.sim)?;
        let field = FieldSpec::new(&f.field, sim.seed)?;
        let vehicle = VehicleSpec::new(&f.vehicle, sim.seed)?;
        let start = sim::start(&f.initial)?;
        let sensor = sensor::sensor_config(&f.sensor)?;
        let controller =
            ControllerSpec::new(&f.controller, &vehicle, airframe_turn_rate_limit_radps)?;
        let metrics = MetricsSpec::new(&f.metrics, &sim)?;
        let output = OutputSpec::new(&f.output)?;
        let sitl = SitlSpec::new(&f.sitl);
        let team = TeamSpec::new(&f.team, &vehicle, &sim, start, &sensor)?;
        Ok(Self {
            sim,
            field,
            vehicle,
            start,
            sensor,
            controller,
            metrics,
            output,
            sitl,
            team,
        })
    }
}

#[cfg(test)]
mod tests;
