//! The in-process mirror of a lockstep flight: the scenario's own loop
//! ([`isotrack_scenario::ScenarioEpisode`]) and law ([`Scenario::tracker`]), with the
//! measurement and the setpoint rounded as MAVLink carries them ([`crate::wire`]). A lockstep
//! `isotrack fly` against `isotrack sitl` must give the same commands and the same run, bit for
//! bit; with [`Rounding::None`] the mirror is `isotrack run` itself.

use crate::wire;
use isotrack_core::IsolineController;
use isotrack_scenario::spec::VehicleSpec;
use isotrack_scenario::Scenario;
use isotrack_sim::{RunResult, TraceSink};

/// How numbers cross between the law and the vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rounding {
    /// As over MAVLink: time to the millisecond, values and setpoints to `f32`.
    Wire,
    /// Not at all: the law's commands reach the vehicle as they are (`isotrack run`).
    None,
}

/// How the vehicle turns the companion's turn-rate command into what it flies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Transport {
    /// A fixed wing: a coordinated-turn roll setpoint at `airspeed_mps`.
    FixedWing {
        /// The airspeed of the roll <-> turn-rate relation, m/s (the scenario's
        /// `vehicle.airspeed_mps`).
        airspeed_mps: f64,
    },
    /// A ground vehicle: a yaw-rate setpoint.
    Ground,
}

impl Transport {
    /// The transport of a scenario's vehicle.
    pub fn of(s: &Scenario) -> Self {
        match s.spec().vehicle {
            VehicleSpec::FixedWing(c) => Transport::FixedWing {
                airspeed_mps: c.airspeed_mps,
            },
            VehicleSpec::Dubins { .. } => Transport::Ground,
        }
    }

    /// The turn rate the vehicle flies for a command `omega` that crossed the wire.
    pub fn flown(&self, omega_radps: f64) -> f64 {
        match *self {
            Transport::FixedWing { airspeed_mps } => {
                wire::fixed_wing_round_trip(omega_radps, airspeed_mps)
            }
            Transport::Ground => wire::ground_round_trip(omega_radps),
        }
    }
}

/// What the mirror flew.
#[derive(Clone, Debug)]
pub struct MirrorRun {
    /// Per sample: the sample's wire time, ms, and the law's command, rad/s.
    pub commands: Vec<(u32, f64)>,
    /// The run's result.
    pub result: RunResult,
}

/// Runs `scenario` in process as a lockstep flight would (or as `isotrack run` does, with
/// [`Rounding::None`]), recording its trace into `sink`.
pub fn mirror<S: TraceSink + ?Sized>(
    scenario: &Scenario,
    rounding: Rounding,
    sink: &mut S,
) -> MirrorRun {
    let mut ep = scenario.episode(None, None);
    let mut law = scenario.tracker();
    let transport = Transport::of(scenario);
    let mut commands = Vec::new();
    while let Some(sample) = ep.run_to_sample_traced(sink) {
        let m = match rounding {
            Rounding::Wire => wire::on_wire(sample.measurement),
            Rounding::None => sample.measurement,
        };
        let w = law.update(&m);
        commands.push((wire::time_ms(m.t_s).unwrap_or(u32::MAX), w));
        let flown = match rounding {
            Rounding::Wire => transport.flown(w),
            Rounding::None => w,
        };
        ep.command_traced(flown, sink);
    }
    MirrorRun {
        commands,
        result: ep.finish_traced(sink),
    }
}
