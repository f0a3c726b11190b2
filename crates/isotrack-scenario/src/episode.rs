//! A scenario's run driven one command at a time, by an agent outside the loop (the Python
//! package's Gymnasium environment, say) instead of a controller inside it.
//!
//! Same field, vehicle, sensor, plan and metrics as [`Scenario::run`]: the loop is
//! [`isotrack_sim::Episode`], the one [`Scenario::run`] drives with its controller, so an agent
//! that answers every sample as a controller would gives the same run, bit for bit.

use crate::field::FieldModel;
use crate::vehicle::VehicleModel;
use crate::Scenario;
use isotrack_core::{Vec2, Vehicle};
use isotrack_sim::{Episode, NoTrace, Oracles, Outcome, RunResult, Sample, TraceSink};
use isotrack_vehicles::{DubinsState, FixedWingState};

pub use crate::spec::sim::Start;

/// The loop state for the scenario's vehicle (boxed: over a kilobyte each, the sensor's
/// generator and the metrics' accumulators).
#[derive(Clone, Debug)]
enum VehicleEpisode {
    Dubins(Box<Episode<DubinsState>>),
    FixedWing(Box<Episode<FixedWingState>>),
}

/// One run of a scenario, paused at each delivered sample until [`command`](Self::command)
/// answers it. It shares the scenario's field (cloning a [`Scenario`] is cheap).
#[derive(Clone, Debug)]
pub struct ScenarioEpisode {
    scenario: Scenario,
    state: VehicleEpisode,
}

/// Runs `$body` with `$f` bound to the scenario's field as its concrete type (dispatched once per
/// call, so the steps inside are monomorphised).
macro_rules! with_field {
    ($scenario:expr, $f:ident => $body:expr) => {
        match $scenario.field() {
            FieldModel::Analytic($f) => $body,
            FieldModel::Grid($f) => $body,
            FieldModel::Puff(p) => {
                let $f = &**p;
                $body
            }
            FieldModel::Series(s) => {
                let $f = &**s;
                $body
            }
        }
    };
}

/// Runs `$body` with the oracles of `scenario` bound to `$o` (the isoline distance for
/// the metrics; the gradient for reference controllers only, never given to an agent).
macro_rules! with_oracles {
    ($scenario:expr, $o:ident => $body:expr) => {{
        let iso = $scenario.isoline();
        let dist = |t: f64, p: Vec2| iso.distance(t, p);
        let $o = Oracles {
            isoline_distance: Some(&dist),
            gradient: None,
        };
        $body
    }};
}

impl Scenario {
    /// The scenario's own start (`[initial]`).
    pub fn start(&self) -> Start {
        self.spec.start
    }

    /// The vehicle's speed at a start (Dubins: its constant speed; fixed wing: the trimmed ground
    /// speed, wind included), m/s.
    pub fn start_speed_mps(&self, start: Start) -> f64 {
        match &*self.vehicle {
            VehicleModel::Dubins(v) => v.speed_mps(&dubins_state(start)),
            VehicleModel::FixedWing(v) => {
                v.speed_mps(&v.initial_state(start.x_m, start.y_m, start.heading_rad))
            }
        }
    }

    /// An episode of this scenario from `start` (the scenario's own if `None`), with the sensor's
    /// noise and dropouts seeded by `sensor_seed` (`sim.seed` if `None`). Nothing is stepped yet.
    pub fn episode(&self, start: Option<Start>, sensor_seed: Option<u64>) -> ScenarioEpisode {
        let start = start.unwrap_or_else(|| self.start());
        let sensor = match sensor_seed {
            Some(seed) => self.sensor_seeded(seed),
            None => self.sensor(),
        };
        let plan = self.plan();
        let state = match &*self.vehicle {
            VehicleModel::Dubins(v) => VehicleEpisode::Dubins(Box::new(Episode::new(
                v,
                dubins_state(start),
                sensor,
                &plan,
            ))),
            VehicleModel::FixedWing(v) => {
                let x0 = v.initial_state(start.x_m, start.y_m, start.heading_rad);
                VehicleEpisode::FixedWing(Box::new(Episode::new(&**v, x0, sensor, &plan)))
            }
        };
        ScenarioEpisode {
            scenario: self.clone(),
            state,
        }
    }
}

fn dubins_state(start: Start) -> DubinsState {
    DubinsState {
        position_m: Vec2::new(start.x_m, start.y_m),
        heading_rad: start.heading_rad,
    }
}

impl ScenarioEpisode {
    /// Steps to the next delivered sample (returned; answer it with [`command`](Self::command)),
    /// or to the end of the run (`None`: see [`outcome`](Self::outcome)). An agent may read
    /// only `measurement` of the sample; the rest is ground truth (for rewards and logs).
    pub fn run_to_sample(&mut self) -> Option<Sample> {
        self.run_to_sample_traced(&mut NoTrace)
    }

    /// [`run_to_sample`](Self::run_to_sample), recording the trace rows of the steps it runs into
    /// `sink` (at the scenario's `output.record_rate_hz`): what a simulated vehicle reports as
    /// telemetry between samples (`isotrack sitl`).
    pub fn run_to_sample_traced<S: TraceSink + ?Sized>(&mut self, sink: &mut S) -> Option<Sample> {
        let s = &self.scenario;
        with_field!(s, field => with_oracles!(s, o => match (&mut self.state, &*s.vehicle) {
            (VehicleEpisode::Dubins(e), VehicleModel::Dubins(v)) => {
                e.run_to_sample(field, v, &o, sink)
            }
            (VehicleEpisode::FixedWing(e), VehicleModel::FixedWing(v)) => {
                e.run_to_sample(field, &**v, &o, sink)
            }
            _ => unreachable!("an episode's state is built for its scenario's vehicle"),
        }))
    }

    /// Answers the waiting sample with a turn-rate command, rad/s (held until the next sample;
    /// the scenario's turn-rate limit is the caller's to apply). A non-finite command ends the run
    /// as `diverged`.
    pub fn command(&mut self, omega_radps: f64) {
        self.command_traced(omega_radps, &mut NoTrace)
    }

    /// [`command`](Self::command), recording the sample step's trace row (if it is one) into
    /// `sink`.
    pub fn command_traced<S: TraceSink + ?Sized>(&mut self, omega_radps: f64, sink: &mut S) {
        let s = &self.scenario;
        with_oracles!(s, o => match (&mut self.state, &*s.vehicle) {
            (VehicleEpisode::Dubins(e), VehicleModel::Dubins(v)) => {
                e.command(omega_radps, v, &o, sink)
            }
            (VehicleEpisode::FixedWing(e), VehicleModel::FixedWing(v)) => {
                e.command(omega_radps, &**v, &o, sink)
            }
            _ => unreachable!("an episode's state is built for its scenario's vehicle"),
        })
    }

    /// The time of the current step, s.
    pub fn t_s(&self) -> f64 {
        match &self.state {
            VehicleEpisode::Dubins(e) => e.t_s(),
            VehicleEpisode::FixedWing(e) => e.t_s(),
        }
    }

    /// The scenario this episode runs.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// Ends the episode and returns its result, the last valid state's row into `sink` if the
    /// trace does not have it yet (as [`Scenario::run`] ends its trace).
    pub fn finish_traced<S: TraceSink + ?Sized>(self, sink: &mut S) -> RunResult {
        let r = match self.state {
            VehicleEpisode::Dubins(e) => e.finish(sink),
            VehicleEpisode::FixedWing(e) => e.finish(sink),
        };
        self.scenario.explain_end(r)
    }

    /// How the run ended, once it has.
    pub fn outcome(&self) -> Option<Outcome> {
        match &self.state {
            VehicleEpisode::Dubins(e) => e.outcome(),
            VehicleEpisode::FixedWing(e) => e.outcome(),
        }
    }

    /// The run's result so far (as [`Scenario::run`] reports it once the run has ended).
    pub fn result(&self) -> RunResult {
        let r = match &self.state {
            VehicleEpisode::Dubins(e) => e.clone().finish(&mut NoTrace),
            VehicleEpisode::FixedWing(e) => e.clone().finish(&mut NoTrace),
        };
        self.scenario.explain_end(r)
    }
}
