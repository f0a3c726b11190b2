//! The simulation loop.

use crate::kernel::{ask, Sensed, VehicleRun};
use crate::run::{Oracles, Outcome, RunResult, Sample, StepPlan};
use crate::sensor::Sensor;
use crate::trace::TraceSink;
use isotrack_core::{IsolineController, ScalarField, Vehicle};

/// Runs one simulation: `field`, `vehicle` from `x0`, `controller` behind `sensor`, for
/// `plan.n_steps` steps, recording into `sink`. See the crate documentation for the order of a step.
/// `oracles.isoline_distance`, if given, is evaluated at every step of the steady-state window for
/// the isoline-distance metrics; `oracles.gradient` feeds [`GroundTruth`] to a reference
/// controller that asks for it (`needs_ground_truth`), and no other.
///
/// This is [`Episode`] driven by `controller`: the loop pauses at each delivered sample and the
/// controller's answer is the command held until the next one.
///
/// Generic over every part so the loop is monomorphised: no dynamic dispatch in the hot path.
///
/// [`GroundTruth`]: isotrack_core::control::GroundTruth
#[allow(clippy::too_many_arguments)]
pub fn simulate<F, V, C, S>(
    field: &F,
    vehicle: &V,
    x0: V::State,
    controller: &mut C,
    sensor: Sensor,
    plan: &StepPlan,
    oracles: &Oracles<'_>,
    sink: &mut S,
) -> RunResult
where
    F: ScalarField + ?Sized,
    V: Vehicle,
    C: IsolineController + ?Sized,
    S: TraceSink + ?Sized,
{
    let wants_truth = controller.needs_ground_truth();
    let mut episode = Episode::new(vehicle, x0, sensor, plan);
    episode.drive(field, vehicle, oracles, sink, |sample| {
        ask(controller, wants_truth, sample, oracles.gradient)
    });
    episode.finish(sink)
}

/// One run of the loop, paused at each delivered sample for the command to hold until the next
/// one: the form [`simulate`] drives with a controller, and an external agent (a reinforcement
/// learning environment, say) drives one command at a time. The step order is the crate's:
/// [`run_to_sample`](Self::run_to_sample) performs steps 1-2 (and 3-5 of the steps without a
/// sample) up to the next sample; [`command`](Self::command) completes that step (3-5).
///
/// The episode owns the vehicle's state and the clock; the bookkeeping of each step is the
/// step kernel's (`kernel::VehicleRun`, the same the batched loop runs in lanes). The field,
/// vehicle and oracles are lent to each call, so that one shared field serves many episodes.
#[derive(Clone, Debug)]
pub struct Episode<X> {
    x: X,
    /// The current step.
    k: u64,
    run: VehicleRun<true>,
    /// The sample waiting for its command.
    pending: Option<Sample>,
}

impl<X: Clone> Episode<X> {
    /// An episode of `plan` for `vehicle` from `x0`, behind `sensor`, at step 0 (nothing run).
    pub fn new<V: Vehicle<State = X>>(vehicle: &V, x0: X, sensor: Sensor, plan: &StepPlan) -> Self {
        let run = VehicleRun::new(plan, sensor, vehicle.pose(&x0));
        Self {
            x: x0,
            k: 0,
            run,
            pending: None,
        }
    }

    /// Steps until the sensor delivers a sample (returned; the episode then waits for
    /// [`command`](Self::command)) or the run ends (`None`; see [`outcome`](Self::outcome)).
    /// Called while a sample waits, it returns that sample again.
    pub fn run_to_sample<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) -> Option<Sample>
    where
        F: ScalarField + ?Sized,
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if let Some(sample) = self.pending {
            return Some(sample);
        }
        self.advance(field, vehicle, oracles, sink, |_| None)
    }

    /// Runs the episode to its end, answering every sample with `controller(sample)`: what
    /// [`simulate`] does. (One loop with the answer inlined, not `run_to_sample` and `command`
    /// in turn: pausing at every sample costs the 100 Hz loop about a tenth of its speed.)
    #[inline]
    pub fn drive<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
        mut controller: impl FnMut(&Sample) -> f64,
    ) where
        F: ScalarField + ?Sized,
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if let Some(sample) = self.run_to_sample(field, vehicle, oracles, sink) {
            let w = controller(&sample);
            self.command(w, vehicle, oracles, sink);
        }
        self.advance(field, vehicle, oracles, sink, |s| Some(controller(s)));
    }

    /// The loop: steps until `answer` returns `None` for a delivered sample (which then waits,
    /// and is returned) or the run ends (`None`). `answer` returning `Some(omega)` commands the
    /// sample and goes on.
    #[inline(always)]
    fn advance<F, V, S>(
        &mut self,
        field: &F,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
        mut answer: impl FnMut(&Sample) -> Option<f64>,
    ) -> Option<Sample>
    where
        F: ScalarField + ?Sized,
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        while self.run.is_running() {
            let k = self.k;
            let t = k as f64 * self.run.plan().dt_s;
            let value_at = |p| field.value(t, p).unwrap_or(f64::NAN);
            let command = match self.run.sense(vehicle, &self.x, k, t, value_at, sink) {
                Sensed::Ended => break,
                Sensed::Held => None,
                Sensed::Sampled(m) => {
                    let sample = self.run.sample(m, vehicle.speed_mps(&self.x));
                    let command = answer(&sample);
                    if command.is_none() {
                        self.pending = Some(sample);
                        return Some(sample);
                    }
                    command
                }
            };
            self.complete(command, t, vehicle, oracles, sink);
        }
        None
    }

    /// Answers the waiting sample with the turn-rate command `omega_radps` (held until the next
    /// sample) and completes its step. A non-finite command ends the run as `diverged`. Without a
    /// waiting sample it does nothing.
    #[inline]
    pub fn command<V, S>(
        &mut self,
        omega_radps: f64,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) where
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        if self.pending.take().is_some() {
            let t = self.t_s();
            self.complete(Some(omega_radps), t, vehicle, oracles, sink);
        }
    }

    /// The kernel's rest of the current step (time `t_s`), then step 5: the vehicle's move (none
    /// once the run ends).
    #[inline(always)]
    fn complete<V, S>(
        &mut self,
        command: Option<f64>,
        t_s: f64,
        vehicle: &V,
        oracles: &Oracles<'_>,
        sink: &mut S,
    ) where
        V: Vehicle<State = X>,
        S: TraceSink + ?Sized,
    {
        let k = self.k;
        if self
            .run
            .complete(command, k, t_s, vehicle, &self.x, oracles, sink)
        {
            vehicle.step(&mut self.x, self.run.omega_radps(), self.run.plan().dt_s);
            self.k += 1;
        }
    }

    /// How the run ended, once it has (`None` while it runs).
    pub fn outcome(&self) -> Option<Outcome> {
        self.run.outcome()
    }

    /// Time of the current step, s.
    pub fn t_s(&self) -> f64 {
        self.k as f64 * self.run.plan().dt_s
    }

    /// The vehicle's state.
    pub fn state(&self) -> &X {
        &self.x
    }

    /// The command being held, rad/s.
    pub fn omega_radps(&self) -> f64 {
        self.run.omega_radps()
    }

    /// Ends the episode (a run still going ends as it stands, as `completed` would at its end)
    /// and returns its result; the last valid state is always in the trace.
    pub fn finish<S: TraceSink + ?Sized>(self, sink: &mut S) -> RunResult {
        self.run.finish(sink)
    }
}
