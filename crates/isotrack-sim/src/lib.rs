//! # isotrack-sim
//!
//! One simulation loop for every field, vehicle and controller ([`simulate`]), the sensor model
//! between the world and the controller ([`Sensor`]), streaming run metrics ([`Metrics`]) and
//! trace recording ([`TraceSink`]).
//!
//! One step `k` (time `t_k = k*dt`), in this order:
//! 1. `pose = vehicle.pose(x_k)`; a non-finite pose ends the run as `diverged`;
//! 2. `s_k = field.value(t_k, pose)`; no value ends the run as `left_field`, and so does a value
//!    that is not finite (NaN, as `value_lanes` gives for no value, or infinite): one rule for a
//!    run alone, in a batch or driven from outside;
//! 3. on sample steps the [`Sensor`] turns the (possibly delayed) true value into a noisy
//!    [`Measurement`](isotrack_core::Measurement) and the controller updates `omega`, which is
//!    otherwise held;
//! 4. metrics and (at the recording rate) the trace observe `(t_k, pose, s_k, omega)`;
//! 5. `x_{k+1} = vehicle.step(x_k, omega, dt)`.
//!
//! Steps 1-4 of each vehicle are one implementation, the step kernel (`kernel::VehicleRun`: the
//! sensor, metrics, held command, sample count, end and trace of one vehicle; the vehicle's
//! state, the clock and the field belong to its driver), whichever way a run is driven:
//! [`Episode`] (one vehicle: [`simulate`], a traced run, an agent from outside) or
//! [`simulate_batch`] (up to [`LANES`] vehicles, the field and step 5 in SIMD lanes) or a
//! [`team`] ([`Group`]: `N` vehicles on one clock, spreading out along one isoline by a spacing
//! law from neighbour ranges; docs/TEAMS.md).
#![deny(missing_docs)]

mod batch;
mod kernel;
mod metrics;
mod run;
mod sensor;
mod simulation;
pub mod team;
mod trace;

pub use batch::{simulate_batch, BatchRun, LANES};
pub use metrics::{Metrics, MetricsConfig, RunMetrics};
pub use run::{
    GradientFn, IsolineDistanceFn, Oracles, Outcome, RunResult, Sample, StepPlan, StepPlanError,
};
pub use sensor::{
    nearest_valid_rates, whole_steps, Sensor, SensorConfig, SensorError, StepsError,
    MAX_SAMPLES_IN_FLIGHT, MAX_STEPS, SENSOR_VALUE_RANGE,
};
pub use simulation::{simulate, Episode};
pub use team::{
    simulate_team, Group, MemberSpeeds, TeamConfig, TeamError, TeamMember, TeamResult, TeamThreads,
};
pub use trace::{NoTrace, TraceRow, TraceSink};
