//! From a resolved [`Scenario`] to runnable parts (controllers, the run's span), and running
//! them. The vehicle is [`crate::vehicle`]'s.

use crate::field::FieldModel;
use crate::schema::*;
use crate::spec::LawSpec;
use crate::vehicle::VehicleModel;
use crate::Scenario;
use isotrack_core::control::{
    GradientReference, GroundTruth, PiIsoline, Pid, PidCrossing, Search, SearchParams, SlidingMode,
    SuboptimalSosm,
};
use isotrack_core::math::Vec2;
use isotrack_core::{FieldDerivatives, IsolineController, Measurement, ScalarField};
use isotrack_sim::{simulate, Oracles, RunResult, Sensor, StepPlan, TraceSink};
use isotrack_vehicles::DubinsState;

/// The steps a run of a scenario spans, from its resolved file alone (no field built): what
/// bounds the `t_end_s`, `samples` and `convergence_time_s` a run can report (`--resume` and
/// `merge` check stored rows against them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSpan {
    /// Integration step `dt`, s.
    pub dt_s: f64,
    /// Planned steps `N = duration / dt`: a run ends at `t_end_s = k dt` with `k <= N`.
    pub n_steps: u64,
    /// Steps between samples `m = 1 / (rate dt)`: samples fall on steps `0, m, 2m, ...`, so a
    /// run that sensed steps `0..=k` delivered at most `floor(k / m) + 1`.
    pub steps_per_sample: u64,
    /// The fastest the vehicle moves over ground, m/s, where known: the Dubins robot's constant
    /// `vehicle.speed_mps` (default 0.5; its path over `t` is `v t`), in a team the most its
    /// spacing law sets, `team.v_max_mps` (default twice the speed); `None` for the fixed
    /// wing (wind adds to its airspeed).
    pub speed_max_mps: Option<f64>,
    /// The sensor's delay in steps `d = delay / dt`: no sample before step `d`, so a run that
    /// sensed steps `0..=s` (`s >= d`) delivered `floor(s / m) - ceil(d / m) + 1` samples
    /// before dropouts (the sample steps `j m` with `d <= j m <= s`).
    pub sensor_delay_steps: u64,
    /// Whether samples can be lost (`sensor.dropout_probability > 0`): then a run may deliver
    /// fewer than its sample steps, down to none.
    pub sensor_drops_samples: bool,
    /// The turn-rate limit every command of the run obeys, rad/s: `controller.max_turn_rate_radps`
    /// (every law's output stage saturates at it; the search phase flies open loop, within it:
    /// the spiral is capped at it and a lawnmower whose half-turns `2 v / search_spacing_m`
    /// exceed it is refused at load); unset on a fixed wing, the airframe's limit
    /// `g tan(phi_max) / V` of the trimmed vehicle, which every law but a `schedule` (its
    /// turn rates flown as written) flies then; `None` without one.
    pub turn_rate_limit_radps: Option<f64>,
    /// The step plan's metric windows ([`StepPlan::new`], what the run's metrics use): the
    /// steady-state window's first step `ss` (the last `metrics.steady_state_fraction` of the
    /// `N` steps) and the convergence dwell `w` in steps (`metrics.convergence_min_dwell_s`,
    /// rounded up, at most `N`). A run that ended at step `k` reports a convergence time only
    /// after staying within the tolerance for more than `w` steps up to `k`, so at most
    /// `(k - w) dt`; its per-second rates over the window divide by `(k - ss) dt`. `None` where
    /// `[metrics]` does not resolve.
    pub metric_steps: Option<MetricSteps>,
}

/// A run's metric windows in steps ([`RunSpan::metric_steps`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricSteps {
    /// The steady-state window's first step (`StepPlan::steady_state_start_step`).
    pub steady_state_start_step: u64,
    /// The convergence dwell, steps (`StepPlan::convergence_min_dwell_steps`).
    pub convergence_min_dwell_steps: u64,
    /// The convergence tolerance on `|eps|`, field units (`metrics.convergence_tolerance`):
    /// the bound of the in-band share and of a convergence.
    pub convergence_tolerance: f64,
}

/// The [`RunSpan`] of resolved scenario file `f` (`None` if its step counts are invalid, which
/// `resolve` refuses).
pub fn run_span(f: &ScenarioFile) -> Option<RunSpan> {
    let sim = crate::spec::SimSpec::new(&f.sim).ok()?;
    let sensor = crate::spec::sensor::sensor_config(&f.sensor).ok()?;
    // A team's row is vehicle 0's: its own override (`team.vehicles`, `index = 0`) sets its
    // sensor's rate and its speeds (issue 32, att32d-3 and -5: a sweep whose vehicle 0 had
    // its own `sensor_rate_hz` or `v_max_mps` refused its own rows, bounded by the team's).
    let own = f
        .team
        .as_ref()
        .and_then(|t| t.vehicles.as_ref())
        .and_then(|v| v.iter().find(|e| e.index == Some(0)));
    let rate_hz = own.and_then(|e| e.sensor_rate_hz).unwrap_or(sensor.rate_hz);
    Some(RunSpan {
        metric_steps: metric_steps(f, &sim),
        sensor_delay_steps: isotrack_sim::whole_steps(sensor.delay_s, sim.dt_s).ok()?,
        sensor_drops_samples: sensor.dropout_probability != 0.0,
        turn_rate_limit_radps: turn_rate_limit_radps(f),
        dt_s: sim.dt_s,
        n_steps: isotrack_sim::whole_steps(sim.duration_s, sim.dt_s).ok()?,
        steps_per_sample: isotrack_sim::whole_steps(1.0 / rate_hz, sim.dt_s)
            .ok()?
            .max(1),
        speed_max_mps: speed_max_mps(f, own),
    })
}

/// The metric windows of `f`'s run as the run's own step plan computes them ([`StepPlan::new`]
/// on `sim`'s step and duration and `[metrics]`; the record rate and level play no part in
/// them): `None` where `[metrics]` does not resolve.
fn metric_steps(f: &ScenarioFile, sim: &crate::spec::SimSpec) -> Option<MetricSteps> {
    crate::spec::MetricsSpec::new(&f.metrics, sim)
        .ok()
        .and_then(|m| {
            StepPlan::new(
                sim.dt_s,
                sim.duration_s,
                0.0,
                m.steady_state_fraction,
                m.convergence_tolerance,
                m.convergence_min_dwell_s,
                0.0,
            )
            .ok()
        })
        .map(|p| MetricSteps {
            steady_state_start_step: p.steady_state_start_step,
            convergence_min_dwell_steps: p.convergence_min_dwell_steps,
            convergence_tolerance: p.convergence_tolerance,
        })
}

/// The turn-rate limit every command of `f`'s run obeys ([`RunSpan::turn_rate_limit_radps`]):
/// `controller.max_turn_rate_radps`, which every law keeps, `schedule` included (resolution
/// refuses a schedule beyond it). Unset on a fixed wing, the limit every law flies is the
/// airframe's, `g tan(phi_max) / V` of the trimmed vehicle
/// ([`crate::vehicle::VehicleModel::airframe_turn_rate_limit_radps`], what
/// `crate::spec::ControllerSpec` resolves): the same resolved limit the run flies. `None`
/// without one, or when it is not a finite, non-negative rate.
fn turn_rate_limit_radps(f: &ScenarioFile) -> Option<f64> {
    match f.controller.max_turn_rate_radps {
        Some(w) => Some(w),
        // A `schedule` flies its turn rates as written (no output stage): no bound then.
        None if f.vehicle.kind == Some(crate::schema::VehicleKind::FixedWing)
            && f.controller.kind != Some(crate::schema::ControllerKind::Schedule) =>
        {
            crate::vehicle::build_vehicle(f)
                .ok()
                .and_then(|v| v.airframe_turn_rate_limit_radps())
        }
        None => None,
    }
    .filter(|w| w.is_finite() && *w >= 0.0)
}

/// The fastest `f`'s vehicle (vehicle 0 in a team, with its own overrides `own`) moves over
/// ground ([`RunSpan::speed_max_mps`]): the Dubins robot's constant `vehicle.speed_mps`
/// (default 0.5), in a team the most its spacing law sets; `None` for the fixed wing (wind
/// adds to its airspeed) or when it is not a finite, non-negative speed.
fn speed_max_mps(f: &ScenarioFile, own: Option<&TeamVehicleSection>) -> Option<f64> {
    match f.vehicle.kind {
        None | Some(crate::schema::VehicleKind::Dubins) => {
            let v0 = f.vehicle.speed_mps.unwrap_or(0.5);
            // A team's spacing law flies each robot at up to `team.v_max_mps` (default
            // `V_MAX_FACTOR v0`): the bound is the run's top speed, not the nominal one;
            // vehicle 0's own `speed_mps` and `v_max_mps` where it has them (its envelope
            // as `spec::team` resolves it: its own bound, else the team's, else the rule
            // at its own speed).
            let v0 = own.and_then(|e| e.speed_mps).unwrap_or(v0);
            let top = match &f.team {
                Some(t) => own
                    .and_then(|e| e.v_max_mps)
                    .or(t.v_max_mps)
                    .unwrap_or(crate::spec::team::V_MAX_FACTOR * v0)
                    .max(v0),
                None => v0,
            };
            Some(top).filter(|v| v.is_finite() && *v >= 0.0)
        }
        Some(crate::schema::VehicleKind::FixedWing) => None,
    }
}

/// `schedule`: a piecewise-constant turn rate `omega(t) = w_i` for `t_i <= t < t_{i+1}`
/// (zero before `t_0`), ignoring the measurement: for checking the closed loop against recorded
/// flights and studying the autopilot's responses. Switching happens at sensor samples.
#[derive(Clone, Debug)]
pub struct Schedule {
    steps: Vec<[f64; 2]>,
}

impl IsolineController for Schedule {
    fn update(&mut self, m: &Measurement) -> f64 {
        self.steps
            .iter()
            .rev()
            .find(|s| m.t_s >= s[0])
            .map_or(0.0, |s| s[1])
    }
    fn reset(&mut self) {}
}

/// Every controller a scenario can name, behind one type (static dispatch in the loop).
#[derive(Clone, Debug)]
pub enum ControllerModel {
    /// `pi_isoline`.
    PiIsoline(PiIsoline),
    /// `sliding_mode` and `sliding_mode_smooth`.
    SlidingMode(SlidingMode),
    /// `suboptimal_sosm`.
    SuboptimalSosm(SuboptimalSosm),
    /// `pid`.
    Pid(Pid),
    /// `pid_crossing`.
    PidCrossing(PidCrossing),
    /// `gradient_reference` (not coordinate-free).
    GradientReference(GradientReference),
    /// `schedule`.
    Schedule(Schedule),
}

macro_rules! each_controller {
    ($self:ident, $c:ident => $e:expr) => {
        match $self {
            ControllerModel::PiIsoline($c) => $e,
            ControllerModel::SlidingMode($c) => $e,
            ControllerModel::SuboptimalSosm($c) => $e,
            ControllerModel::Pid($c) => $e,
            ControllerModel::PidCrossing($c) => $e,
            ControllerModel::GradientReference($c) => $e,
            ControllerModel::Schedule($c) => $e,
        }
    };
}

/// The controller a run flies: the tracking law, or the tracking law behind a search phase.
/// (An enum, not a box: the step loop stays monomorphic.) Public so that a companion computer
/// (`isotrack fly`) flies exactly the law a run of the scenario flies.
#[derive(Clone, Debug)]
pub enum Tracker {
    /// The tracking law alone (`controller.search = "none"`).
    Tracking(ControllerModel),
    /// The tracking law behind its search phase.
    Searching(Search<ControllerModel>),
}

impl IsolineController for Tracker {
    #[inline]
    fn update(&mut self, m: &Measurement) -> f64 {
        match self {
            Tracker::Tracking(c) => c.update(m),
            Tracker::Searching(c) => c.update(m),
        }
    }
    fn reset(&mut self) {
        match self {
            Tracker::Tracking(c) => c.reset(),
            Tracker::Searching(c) => c.reset(),
        }
    }
    fn needs_ground_truth(&self) -> bool {
        match self {
            Tracker::Tracking(c) => c.needs_ground_truth(),
            Tracker::Searching(c) => c.needs_ground_truth(),
        }
    }
    fn update_with_truth(&mut self, m: &Measurement, truth: &GroundTruth) -> f64 {
        match self {
            Tracker::Tracking(c) => c.update_with_truth(m, truth),
            Tracker::Searching(c) => c.update_with_truth(m, truth),
        }
    }
    /// Lanes all tracking (no search phase) take [`ControllerModel`]'s lane form.
    #[inline(always)]
    fn update_lanes<const N: usize>(
        ctrls: &mut [Option<&mut Self>; N],
        ms: &[Measurement; N],
    ) -> [f64; N] {
        let mut inner: [Option<&mut ControllerModel>; N] = [const { None }; N];
        let mut all_tracking = true;
        for (slot, c) in inner.iter_mut().zip(ctrls.iter_mut()) {
            match c.as_deref_mut() {
                Some(Tracker::Tracking(m)) => *slot = Some(m),
                Some(Tracker::Searching(_)) => all_tracking = false,
                None => {}
            }
        }
        if all_tracking {
            return ControllerModel::update_lanes(&mut inner, ms);
        }
        isotrack_core::control::update_each(ctrls, ms)
    }
}

impl IsolineController for ControllerModel {
    #[inline]
    fn update(&mut self, m: &Measurement) -> f64 {
        each_controller!(self, c => c.update(m))
    }
    fn reset(&mut self) {
        each_controller!(self, c => c.reset())
    }
    fn needs_ground_truth(&self) -> bool {
        each_controller!(self, c => c.needs_ground_truth())
    }
    fn update_with_truth(&mut self, m: &Measurement, t: &GroundTruth) -> f64 {
        each_controller!(self, c => c.update_with_truth(m, t))
    }
    /// Lanes of PI-like laws take [`PiIsoline`]'s lane form; any other mix, one by one.
    #[inline(always)]
    fn update_lanes<const N: usize>(
        ctrls: &mut [Option<&mut Self>; N],
        ms: &[Measurement; N],
    ) -> [f64; N] {
        let mut pis: [Option<&mut PiIsoline>; N] = [const { None }; N];
        let mut all_pi = true;
        for (slot, c) in pis.iter_mut().zip(ctrls.iter_mut()) {
            match c.as_deref_mut() {
                Some(ControllerModel::PiIsoline(p)) => *slot = Some(p),
                Some(_) => all_pi = false,
                None => {}
            }
        }
        if all_pi {
            return PiIsoline::update_lanes(&mut pis, ms);
        }
        isotrack_core::control::update_each(ctrls, ms)
    }
}

impl Scenario {
    /// The level `s_d` the scenario tracks.
    pub fn level(&self) -> f64 {
        self.spec.controller.level
    }

    /// The turn-rate limit every controller's output stage applies, rad/s:
    /// `controller.max_turn_rate_radps` when set; otherwise, for `vehicle.kind = "fixed_wing"`,
    /// what the airframe can fly, `g*tan(phi_max)/V` (0.274 rad/s at 30 m/s and the autopilot's
    /// 40 deg bank limit), so a noisy measurement cannot command hundreds of rad/s; otherwise
    /// none ([`crate::spec::TurnRateLimit`]).
    pub fn max_turn_rate_radps(&self) -> Option<f64> {
        self.spec.controller.turn_rate_limit.radps()
    }

    /// The search phase before tracking (`controller.search`), its derived geometry applied
    /// (see [`crate::spec::ControllerSpec::search`]). `None` without a search.
    pub fn search(&self) -> Option<SearchParams> {
        self.spec.controller.search
    }

    /// The controller, at rest.
    pub fn controller(&self) -> ControllerModel {
        match &self.spec.controller.law {
            LawSpec::PiIsoline(p) => ControllerModel::PiIsoline(PiIsoline::new(*p)),
            LawSpec::SlidingMode(p) => ControllerModel::SlidingMode(SlidingMode::new(*p)),
            LawSpec::SuboptimalSosm(p) => ControllerModel::SuboptimalSosm(SuboptimalSosm::new(*p)),
            LawSpec::Pid(p) => ControllerModel::Pid(Pid::new(*p)),
            LawSpec::PidCrossing(p) => ControllerModel::PidCrossing(PidCrossing::new(*p)),
            LawSpec::GradientReference(p) => {
                ControllerModel::GradientReference(GradientReference::new(*p))
            }
            LawSpec::Schedule(steps) => ControllerModel::Schedule(Schedule {
                steps: steps.clone(),
            }),
        }
    }

    /// The sensor, seeded by `sim.seed`.
    pub fn sensor(&self) -> Sensor {
        self.sensor_seeded(self.spec.sim.seed)
    }

    /// The sensor, its noise and dropouts seeded by `seed`.
    pub fn sensor_seeded(&self, seed: u64) -> Sensor {
        Sensor::new(self.spec.sensor, self.dt_s(), seed)
            // `resolve_sensor` calls this constructor with the same values (the seed aside,
            // which cannot make it fail), and every `Scenario` comes out of `resolve`.
            .expect("validated by resolve: Sensor::new")
    }

    /// Integration step, s.
    pub fn dt_s(&self) -> f64 {
        self.spec.sim.dt_s
    }

    /// How long the error must stay within the convergence tolerance, up to the end, for a
    /// convergence time to be reported: `metrics.convergence_min_dwell_s`, default 10 % of
    /// `sim.duration_s`, s.
    pub fn convergence_min_dwell_s(&self) -> f64 {
        self.spec.metrics.convergence_min_dwell_s
    }

    /// The step plan (durations as step counts).
    pub fn plan(&self) -> StepPlan {
        let (sim, m) = (&self.spec.sim, &self.spec.metrics);
        StepPlan::new(
            sim.dt_s,
            sim.duration_s,
            self.spec.output.record_rate_hz,
            m.steady_state_fraction,
            m.convergence_tolerance,
            m.convergence_min_dwell_s,
            self.level(),
        )
        .map(|p| p.with_track_loss_band(m.track_loss_band))
        // `resolve_sim` and `resolve_output` apply the same `whole_steps` rule to the duration
        // and recording period, the only inputs that can make it fail.
        .expect("validated by resolve: StepPlan::new")
    }

    /// Runs the scenario, recording the trace into `sink`.
    pub fn run<S: TraceSink + ?Sized>(&self, sink: &mut S) -> RunResult {
        let mut controller = self.tracker();
        self.run_with(&mut controller, sink)
    }

    /// The controller a run of this scenario flies (behind its search phase, if any): its law,
    /// output stage (turn-rate limit, side), anti-windup and derivative estimator, at rest.
    pub fn tracker(&self) -> Tracker {
        match self.search() {
            Some(params) => Tracker::Searching(Search::new(self.controller(), params)),
            None => Tracker::Tracking(self.controller()),
        }
    }

    /// Runs the scenario with another controller in the loop (a user's own law, from Python
    /// say): the same field, vehicle, sensor, plan and metrics; the controller sees only the
    /// measurements.
    pub fn run_with<C: IsolineController + ?Sized, S: TraceSink + ?Sized>(
        &self,
        controller: &mut C,
        sink: &mut S,
    ) -> RunResult {
        let r = match self.field() {
            FieldModel::Analytic(f) => self.run_on(f, controller, sink),
            FieldModel::Grid(f) => self.run_on(f, controller, sink),
            FieldModel::Puff(f) => self.run_on(&**f, controller, sink),
            FieldModel::Series(f) => self.run_on(&**f, controller, sink),
        };
        self.explain_end(r)
    }

    /// A run's result with its end explained in the scenario's terms: past the last frame of a
    /// time series with `after_last_frame = "end"`, a `left_field` says the data ended.
    pub fn explain_end(&self, mut r: RunResult) -> RunResult {
        if let FieldModel::Series(f) = self.field() {
            let end = f.last_frame_run_time_s();
            if r.outcome == isotrack_sim::Outcome::LeftField && r.t_end_s + self.dt_s() > end {
                r.outcome_detail = Some(format!(
                    "the field's data ended: its last frame is at t = {} s of the run (field.after_last_frame = \"end\")",
                    isotrack_core::numtext::Num(end)
                ));
            }
        }
        r
    }

    /// Runs the scenario on a given field (dispatched once, so the loop is monomorphised per
    /// field type).
    fn run_on<
        F: ScalarField + FieldDerivatives + Sync,
        C: IsolineController + ?Sized,
        S: TraceSink + ?Sized,
    >(
        &self,
        field: &F,
        controller: &mut C,
        sink: &mut S,
    ) -> RunResult {
        let iso = self.isoline();
        let dist = |t: f64, p: Vec2| iso.distance(t, p);
        let grad = |t: f64, p: Vec2| Some((field.gradient(t, p)?, field.hessian(t, p)?));
        let oracles = Oracles {
            isoline_distance: Some(&dist),
            gradient: Some(&grad),
        };
        let sensor = self.sensor();
        let plan = self.plan();
        let crate::episode::Start {
            x_m: x,
            y_m: y,
            heading_rad: h,
        } = self.start();
        match &*self.vehicle {
            VehicleModel::Dubins(vehicle) => {
                let x0 = DubinsState {
                    position_m: Vec2::new(x, y),
                    heading_rad: h,
                };
                simulate(
                    field, vehicle, x0, controller, sensor, &plan, &oracles, sink,
                )
            }
            VehicleModel::FixedWing(vehicle) => {
                let x0 = vehicle.initial_state(x, y, h);
                simulate(
                    field, &**vehicle, x0, controller, sensor, &plan, &oracles, sink,
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::parse_scenario;
    use isotrack_core::control::{IsolineController, Measurement};

    /// Samples that wind up a law's state (the PI-like law's integral, the estimator's memory).
    fn wind_up(c: &mut impl IsolineController) -> f64 {
        let mut last = 0.0;
        for k in 0..20 {
            last = c.update(&Measurement {
                t_s: 0.1 * k as f64,
                value: 7.0 + 0.05 * k as f64,
            });
        }
        last
    }

    /// `reset` brings the law (alone, or behind a search) back to rest: the same answers as a
    /// fresh one.
    #[test]
    fn controllers_reset_to_rest() {
        for text in [
            "",
            "[controller]\nsearch = \"spiral\"\nsearch_handover = 0.1\n",
        ] {
            let s = parse_scenario(text, "<test>", &[]).unwrap();
            let fresh = wind_up(&mut s.tracker());
            let mut t = s.tracker();
            wind_up(&mut t);
            t.reset();
            assert_eq!(wind_up(&mut t), fresh, "{text}");
            let fresh = wind_up(&mut s.controller());
            let mut c = s.controller();
            wind_up(&mut c);
            c.reset();
            assert_eq!(wind_up(&mut c), fresh, "{text}");
        }
    }

    /// Only the gradient-reference law flies on ground truth, with or without a search.
    #[test]
    fn only_the_gradient_reference_law_needs_ground_truth() {
        for (text, wants) in [
            ("", false),
            ("[controller]\nsearch = \"spiral\"\n", false),
            ("[controller]\nkind = \"gradient_reference\"\n", true),
            (
                "[controller]\nkind = \"gradient_reference\"\nsearch = \"spiral\"\n",
                true,
            ),
        ] {
            let s = parse_scenario(text, "<test>", &[]).unwrap();
            assert_eq!(s.tracker().needs_ground_truth(), wants, "{text}");
            assert_eq!(s.controller().needs_ground_truth(), wants, "{text}");
        }
    }

    /// The convergence dwell defaults to 10 % of the run.
    #[test]
    fn convergence_dwell_defaults_to_a_tenth_of_the_run() {
        let s = parse_scenario("[sim]\nduration_s = 50.0\n", "<test>", &[]).unwrap();
        assert_eq!(s.convergence_min_dwell_s(), 5.0);
        let s = parse_scenario(
            "[sim]\nduration_s = 50.0\n[metrics]\nconvergence_min_dwell_s = 7.0\n",
            "<test>",
            &[],
        )
        .unwrap();
        assert_eq!(s.convergence_min_dwell_s(), 7.0);
    }
}
