//! A 6-DOF fixed-wing UAV (the Aerosonde of Beard & McLain, 2012 parameters) flown by its
//! successive-loop-closure autopilot, driven by a course-rate command: the vehicle of the
//! paper's Sec. VI-C.
//!
//! Guidance interface: the isoline controller's `omega` (rad/s, positive = left, as for the
//! Dubins robot) is integrated into the course command, `chi_c' = -omega` (course is measured
//! clockwise from north); altitude and airspeed are held at their commands. One step of `dt`:
//! gusts advance, the autopilot (sample time `dt`) computes the deflections from the true state,
//! and RK4 integrates the 12-state model with deflections and wind held, forces re-evaluated at
//! every stage.
//!
//! Frames: the simulation's `(x east, y north)` is the model's `(pe, pn)`; a heading
//! counter-clockwise from east `h` is the course `chi = pi/2 - h` clockwise from north.

pub mod autopilot;
pub mod dynamics;
pub mod gains;
pub mod params;
pub mod replay;
pub mod trim;
pub mod wind;

use autopilot::{autopilot, AutopilotConfig, AutopilotState, Commands};
use dynamics::{air_data, r_body_to_ned, rk4_step, Deltas, EulerSinCos, State12, WindSample};
use gains::{compute_gains, course_loop_model, CourseLoopModel, Gains};
use isotrack_core::math::{wrap_angle, Pose2, Vec2};
use isotrack_core::vehicle::Telemetry;
use isotrack_core::Vehicle;
use params::Aerosonde;
use std::f64::consts::FRAC_PI_2;
use trim::{trim, trim_state, Trim, TrimError};
use wind::{Dryden, DrydenParams};

/// Configuration of a [`FixedWing`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedWingConfig {
    /// Commanded (and trim) airspeed, m/s.
    pub airspeed_mps: f64,
    /// Commanded altitude, m.
    pub altitude_m: f64,
    /// Steady wind `[east, north]`, m/s (the direction the air moves to).
    pub wind_mps: [f64; 2],
    /// Dryden gusts on top (seeded by `seed`).
    pub gusts: bool,
    /// Seed of the gusts.
    pub seed: u64,
    /// Trim feed-forward in the autopilot (see [`mod@autopilot`]).
    pub trim_feedforward: bool,
    /// Use the 2012 code's `a_V1` (with `C_L,delta_e`) for the airspeed gains.
    pub ecen674_gains: bool,
}

impl Default for FixedWingConfig {
    fn default() -> Self {
        Self {
            airspeed_mps: 30.0,
            altitude_m: 100.0,
            wind_mps: [0.0, 0.0],
            gusts: false,
            seed: 0,
            trim_feedforward: true,
            ecen674_gains: false,
        }
    }
}

/// The UAV: parameters, trim, gains and autopilot settings (immutable during a run).
#[derive(Clone, Debug)]
pub struct FixedWing {
    params: Aerosonde,
    derived: dynamics::Derived,
    trim: Trim,
    gains: Gains,
    ap: AutopilotConfig,
    cfg: FixedWingConfig,
}

/// The UAV's full state: airframe, autopilot memory, course command and gust generator.
#[derive(Clone, Debug)]
pub struct FixedWingState {
    /// `[pn, pe, pd, u, v, w, phi, theta, psi, p, q, r]`.
    pub x: State12,
    /// Autopilot memory.
    pub autopilot: AutopilotState,
    /// Course command, rad clockwise from north (continuous).
    pub course_cmd_rad: f64,
    /// Airspeed command of the autopilot's airspeed loop, m/s: the configured (trim)
    /// airspeed, unless a team's spacing law sets it ([`FixedWingVariableSpeed`]).
    pub airspeed_cmd_mps: f64,
    /// Ground course, rad clockwise from north (continuous).
    pub course_rad: f64,
    /// The last deflections.
    pub deltas: Deltas,
    /// The wind acting over the last step.
    pub wind: WindSample,
    gusts: Option<Dryden>,
    /// The sines and cosines of `x`'s Euler angles as the last step left them: the next step
    /// starts from them (used only while `x`'s angles are still theirs).
    euler: Option<EulerSinCos>,
}

impl FixedWing {
    /// Trims at the configured airspeed and computes the gains.
    pub fn new(cfg: FixedWingConfig) -> Result<Self, TrimError> {
        let params = Aerosonde::beard_mclain_2012();
        let trim = trim(&params, cfg.airspeed_mps)?;
        let gains = compute_gains(&params, &trim, cfg.ecen674_gains);
        Ok(Self {
            derived: dynamics::Derived::new(&params),
            params,
            trim,
            gains,
            ap: AutopilotConfig {
                trim_feedforward: cfg.trim_feedforward,
                ..AutopilotConfig::default()
            },
            cfg,
        })
    }

    /// The trim condition.
    pub fn trim(&self) -> &Trim {
        &self.trim
    }
    /// The autopilot gains.
    pub fn gains(&self) -> &Gains {
        &self.gains
    }
    /// The turn rate the airframe can fly in a coordinated turn at the autopilot's bank limit:
    /// `chi'_max = g*tan(phi_max)/V_a` (Beard & McLain 2012, eq. (9.14) with the bank limit of
    /// the roll loop), rad/s: 0.2741 at 30 m/s and 40 deg. Commands beyond it only saturate
    /// the roll loop.
    pub fn airframe_turn_rate_limit_radps(&self) -> f64 {
        self.params.g * self.ap.roll_max_rad.tan() / self.trim.airspeed_mps
    }
    /// The closed lateral loops as linear dynamics (for the sampled-data check).
    pub fn course_loop_model(&self) -> CourseLoopModel {
        course_loop_model(&self.params, &self.trim, &self.gains)
    }
    /// The configuration it was built with.
    pub fn config(&self) -> &FixedWingConfig {
        &self.cfg
    }
    /// The parameters.
    pub fn params(&self) -> &Aerosonde {
        &self.params
    }

    fn steady_ned(&self) -> [f64; 3] {
        [self.cfg.wind_mps[1], self.cfg.wind_mps[0], 0.0]
    }

    /// Trimmed, wings-level flight at `(x east, y north)` and the configured altitude, flying
    /// along `heading_rad` (counter-clockwise from east) over the ground: the airframe is
    /// crabbed into any steady wind so that its ground course is the heading given.
    pub fn initial_state(&self, x_m: f64, y_m: f64, heading_rad: f64) -> FixedWingState {
        self.initial_state_seeded(x_m, y_m, heading_rad, self.cfg.seed)
    }

    /// [`initial_state`](Self::initial_state) with the gusts (if any) seeded by `gust_seed`
    /// instead of the configuration's seed: each vehicle of a team its own gusts.
    pub fn initial_state_seeded(
        &self,
        x_m: f64,
        y_m: f64,
        heading_rad: f64,
        gust_seed: u64,
    ) -> FixedWingState {
        self.start_at(None, x_m, y_m, heading_rad, gust_seed)
    }

    /// [`initial_state_seeded`](Self::initial_state_seeded) trimmed at another airspeed
    /// `airspeed_mps` (a team member's own nominal airspeed, its airspeed command from the
    /// start) instead of the configured one: the airframe in level flight at that trim, the
    /// autopilot's integrators set for a bumpless start there
    /// ([`AutopilotState::from_trim_at`], the gains and feed-forward staying the configured
    /// trim's, as every step uses them), the gusts at that airspeed. At the configured airspeed
    /// it is [`initial_state_seeded`](Self::initial_state_seeded), bit for bit. Issue 32,
    /// att32d-13: a member with `airspeed_mps = 20` started at the scenario's 30 m/s and dipped
    /// to 17.6 m/s on the way down.
    pub fn initial_state_at_airspeed(
        &self,
        x_m: f64,
        y_m: f64,
        heading_rad: f64,
        gust_seed: u64,
        airspeed_mps: f64,
    ) -> Result<FixedWingState, TrimError> {
        if airspeed_mps == self.cfg.airspeed_mps {
            return Ok(self.initial_state_seeded(x_m, y_m, heading_rad, gust_seed));
        }
        let flown = trim(&self.params, airspeed_mps)?;
        Ok(self.start_at(Some(&flown), x_m, y_m, heading_rad, gust_seed))
    }

    /// The start trimmed at `other` (`None`: the configured trim).
    fn start_at(
        &self,
        other: Option<&Trim>,
        x_m: f64,
        y_m: f64,
        heading_rad: f64,
        gust_seed: u64,
    ) -> FixedWingState {
        let flown = other.unwrap_or(&self.trim);
        let airspeed_mps = flown.airspeed_mps;
        let chi = FRAC_PI_2 - heading_rad;
        let [wn, we, _] = self.steady_ned();
        // Crab: air velocity Va (cos psi, sin psi) + wind must point along chi.
        let (sc, cc) = isotrack_core::lanes::sin_cos(chi);
        let cross = -wn * sc + we * cc;
        let crab = (-(cross / airspeed_mps)).clamp(-1.0, 1.0).asin();
        let psi = chi + crab;
        let mut x = trim_state(flown, self.cfg.altitude_m, psi);
        x[0] = y_m;
        x[1] = x_m;
        // Ground velocity in body axes = air velocity + wind in body axes.
        let r = r_body_to_ned(0.0, x[7], psi);
        let wned = self.steady_ned();
        for i in 0..3 {
            x[3 + i] += r[0][i] * wned[0] + r[1][i] * wned[1] + r[2][i] * wned[2];
        }
        let gusts = self
            .cfg
            .gusts
            .then(|| Dryden::new(DrydenParams::default(), airspeed_mps, gust_seed));
        let mut s = FixedWingState {
            x,
            autopilot: match (self.cfg.trim_feedforward, other) {
                (false, _) => AutopilotState::default(),
                (true, None) => AutopilotState::from_trim(&self.trim, &self.gains),
                (true, Some(t)) => AutopilotState::from_trim_at(t, &self.trim, &self.gains),
            },
            course_cmd_rad: 0.0,
            airspeed_cmd_mps: airspeed_mps,
            course_rad: 0.0,
            deltas: Deltas {
                elevator_rad: flown.delta_e_rad,
                throttle: flown.delta_t,
                ..Deltas::default()
            },
            wind: WindSample {
                steady_ned_mps: wned,
                gust_body_mps: [0.0; 3],
            },
            gusts,
            euler: None,
        };
        s.course_rad = Self::ground_course(&s.x, chi);
        s.course_cmd_rad = s.course_rad;
        s
    }

    /// NED ground velocity `[pn', pe', pd']`.
    #[inline(always)]
    pub fn ground_velocity(x: &State12) -> [f64; 3] {
        let r = r_body_to_ned(x[6], x[7], x[8]);
        [
            r[0][0] * x[3] + r[0][1] * x[4] + r[0][2] * x[5],
            r[1][0] * x[3] + r[1][1] * x[4] + r[1][2] * x[5],
            r[2][0] * x[3] + r[2][1] * x[4] + r[2][2] * x[5],
        ]
    }

    /// The ground course, continuous with `previous` (rad clockwise from north).
    #[inline(always)]
    fn ground_course(x: &State12, previous: f64) -> f64 {
        Self::ground_course_with(x, &r_body_to_ned(x[6], x[7], x[8]), previous)
    }

    /// [`ground_course`](Self::ground_course) with `x`'s rotation body -> NED known.
    #[inline(always)]
    fn ground_course_with(x: &State12, r: &[[f64; 3]; 3], previous: f64) -> f64 {
        let v = [
            r[0][0] * x[3] + r[0][1] * x[4] + r[0][2] * x[5],
            r[1][0] * x[3] + r[1][1] * x[4] + r[1][2] * x[5],
        ];
        Self::course_from(v[0], v[1], previous)
    }

    /// The course of the ground velocity `(v_n, v_e)`, continuous with `previous` (kept when
    /// the aircraft hardly moves over the ground).
    #[inline(always)]
    fn course_from(vn: f64, ve: f64, previous: f64) -> f64 {
        if vn * vn + ve * ve < 1e-12 {
            return previous;
        }
        previous + wrap_angle(ve.atan2(vn) - previous)
    }

    /// Air data of a state under its last wind sample.
    pub fn air_data(&self, s: &FixedWingState) -> dynamics::AirData {
        let r = r_body_to_ned(s.x[6], s.x[7], s.x[8]);
        air_data(&s.x, &s.wind, &r)
    }

    /// Advances `s` by `dt_s` with the course command given directly (guidance bypassed): used by
    /// the turn-rate interface and by tests of the autopilot.
    pub fn step_with_commands(&self, s: &mut FixedWingState, cmd: &Commands, dt_s: f64) {
        step_closed_loop(self, s, cmd, dt_s);
    }

    /// Advances the bare airframe (no autopilot) with deflections `d` held, no gusts.
    pub fn step_open_loop(&self, x: &mut State12, d: &Deltas, dt_s: f64) {
        let wind = WindSample {
            steady_ned_mps: self.steady_ned(),
            gust_body_mps: [0.0; 3],
        };
        rk4_step(&self.params, &self.derived, x, d, &wind, dt_s);
    }
}

/// One closed-loop step: gusts, the autopilot (on the airspeed and ground course), RK4 with the
/// deflections held, the new ground course. Compiled for AVX-512, AVX2 and NEON besides the
/// baseline and picked at run time (`multiversion`): the Euler angles' `sin_cos` in lanes
/// (`isotrack_core::lanes`) then runs as one vector operation. The same numbers on every path
/// (IEEE operations only, no fused multiply-add).
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512dq+avx512vl+avx2+fma",
    "x86_64+avx2+fma",
    "aarch64+neon"
))]
fn step_closed_loop(v: &FixedWing, s: &mut FixedWingState, cmd: &Commands, dt_s: f64) {
    if let Some(g) = s.gusts.as_mut() {
        s.wind.gust_body_mps = g.step(dt_s);
    }
    // The attitude's sines and cosines: the last step's, unless the state was changed since.
    let euler = match s.euler {
        Some(e) if e.angles == [s.x[6], s.x[7], s.x[8]] => e,
        _ => EulerSinCos::of(&s.x),
    };
    let r = euler.rotation();
    let va = dynamics::airspeed_mps(&s.x, &s.wind, &r);
    let d = autopilot(
        &mut s.autopilot,
        &v.ap,
        &v.gains,
        &v.trim,
        &s.x,
        va,
        s.course_rad,
        cmd,
        dt_s,
    );
    s.deltas = d;
    dynamics::rk4_step_inline(&v.params, &v.derived, &mut s.x, &d, &s.wind, dt_s, &euler);
    let end = EulerSinCos::of(&s.x);
    s.course_rad = FixedWing::ground_course_with(&s.x, &end.rotation(), s.course_rad);
    s.euler = Some(end);
}

/// [`step_closed_loop`] of `N` aircraft at once, each with its own state and commands: the
/// gusts and the autopilot lane by lane (their own random streams and state machines), the
/// airframe (airspeed, RK4 with its four force evaluations, the new attitude's `sin_cos` and
/// ground course) in lanes, structure of arrays, so that its arithmetic vectorises in the
/// caller's instruction set (the batched loop is compiled for AVX-512, AVX2 and NEON). The
/// force model is the scalar step's body ([`dynamics::derivatives_lanes`]) and every other
/// formula the scalar step's, in the same order: each state ends as
/// [`step_closed_loop`] leaves it, bit for bit.
#[inline(always)]
fn step_closed_loop_lanes<const N: usize>(
    v: &FixedWing,
    s: &mut [FixedWingState; N],
    cmd: &[Commands; N],
    dt_s: f64,
) {
    let mut euler = dynamics::EulerLanes {
        sin: [[0.0; N]; 3],
        cos: [[0.0; N]; 3],
    };
    let mut wind = dynamics::WindLanes {
        steady_ned_mps: [[0.0; N]; 3],
        gust_body_mps: [[0.0; N]; 3],
    };
    let mut x = [[0.0; N]; 12];
    for (i, st) in s.iter_mut().enumerate() {
        if let Some(g) = st.gusts.as_mut() {
            st.wind.gust_body_mps = g.step(dt_s);
        }
        let e = match st.euler {
            Some(e) if e.angles == [st.x[6], st.x[7], st.x[8]] => e,
            _ => EulerSinCos::of(&st.x),
        };
        for k in 0..3 {
            euler.sin[k][i] = e.sin_cos(k).0;
            euler.cos[k][i] = e.sin_cos(k).1;
            wind.steady_ned_mps[k][i] = st.wind.steady_ned_mps[k];
            wind.gust_body_mps[k][i] = st.wind.gust_body_mps[k];
        }
        for (c, xc) in x.iter_mut().enumerate() {
            xc[i] = st.x[c];
        }
    }
    let va = dynamics::airspeed_lanes(&x, &wind, &euler.rotation());
    let mut d = dynamics::DeltasLanes {
        elevator_rad: [0.0; N],
        aileron_rad: [0.0; N],
        rudder_rad: [0.0; N],
        throttle: [0.0; N],
    };
    for (i, st) in s.iter_mut().enumerate() {
        let di = autopilot(
            &mut st.autopilot,
            &v.ap,
            &v.gains,
            &v.trim,
            &st.x,
            va[i],
            st.course_rad,
            &cmd[i],
            dt_s,
        );
        st.deltas = di;
        d.elevator_rad[i] = di.elevator_rad;
        d.aileron_rad[i] = di.aileron_rad;
        d.rudder_rad[i] = di.rudder_rad;
        d.throttle[i] = di.throttle;
    }
    dynamics::rk4_lanes(&v.params, &v.derived, &mut x, &d, &wind, dt_s, &euler);
    let end = dynamics::EulerLanes::of(&x);
    let r = end.rotation();
    // Ground velocity north and east (`ground_course_with`'s).
    let mut vn = [0.0; N];
    let mut ve = [0.0; N];
    for i in 0..N {
        vn[i] = r[0][0][i] * x[3][i] + r[0][1][i] * x[4][i] + r[0][2][i] * x[5][i];
        ve[i] = r[1][0][i] * x[3][i] + r[1][1][i] * x[4][i] + r[1][2][i] * x[5][i];
    }
    for (i, st) in s.iter_mut().enumerate() {
        for (c, xc) in x.iter().enumerate() {
            st.x[c] = xc[i];
        }
        st.course_rad = FixedWing::course_from(vn[i], ve[i], st.course_rad);
        st.euler = Some(EulerSinCos::from_lane(&end, &st.x, i));
    }
}

impl Vehicle for FixedWing {
    type State = FixedWingState;

    fn step(&self, s: &mut FixedWingState, omega_radps: f64, dt_s: f64) {
        // omega > 0 turns left: the course (clockwise from north) decreases.
        s.course_cmd_rad -= omega_radps * dt_s;
        let cmd = Commands {
            course_rad: s.course_cmd_rad,
            altitude_m: self.cfg.altitude_m,
            airspeed_mps: s.airspeed_cmd_mps,
        };
        self.step_with_commands(s, &cmd, dt_s);
    }

    /// The step of `N` aircraft with the airframe in lanes ([`step_closed_loop_lanes`]); each
    /// state is what [`step`](Vehicle::step) gives it, bit for bit.
    #[inline(always)]
    fn step_lanes<const N: usize>(
        &self,
        states: &mut [FixedWingState; N],
        omega_radps: &[f64; N],
        dt_s: f64,
    ) {
        let mut cmd = [Commands {
            course_rad: 0.0,
            altitude_m: self.cfg.altitude_m,
            airspeed_mps: 0.0,
        }; N];
        for ((s, c), &w) in states.iter_mut().zip(cmd.iter_mut()).zip(omega_radps) {
            s.course_cmd_rad -= w * dt_s;
            c.course_rad = s.course_cmd_rad;
            c.airspeed_mps = s.airspeed_cmd_mps;
        }
        step_closed_loop_lanes(self, states, &cmd, dt_s);
    }

    fn pose(&self, s: &FixedWingState) -> Pose2 {
        Pose2 {
            position: Vec2::new(s.x[1], s.x[0]),
            heading_rad: wrap_angle(FRAC_PI_2 - s.course_rad),
        }
    }

    fn speed_mps(&self, s: &FixedWingState) -> f64 {
        let v = Self::ground_velocity(&s.x);
        (v[0] * v[0] + v[1] * v[1]).sqrt()
    }

    fn telemetry(&self, s: &FixedWingState) -> Option<Telemetry> {
        Some(Telemetry {
            altitude_m: -s.x[2],
            airspeed_mps: self.air_data(s).va_mps,
            roll_rad: s.x[6],
        })
    }
}

/// The UAV with its airspeed commanded (a team's spacing law, docs/TEAMS.md): the command goes
/// to the autopilot's airspeed loop (throttle, and pitch in the altitude state machine's climb
/// and descend zones), held until the next one, saturated to `[min_airspeed_mps,
/// max_airspeed_mps]`, which must lie within [`COMMANDED_AIRSPEED_RANGE_MPS`] (20 to 45 m/s).
/// The gains stay those of the configured trim. At the
/// configured airspeed it flies as [`FixedWing`] does, bit for bit (the same command).
///
/// The speed the [`isotrack_core::SpeedCommand`] commands is the airspeed; the speed the
/// metrics read ([`Vehicle::speed_mps`]) is the ground speed (they differ by the wind).
#[derive(Clone, Debug)]
pub struct FixedWingVariableSpeed {
    /// The UAV.
    pub uav: FixedWing,
    /// Slowest airspeed command, m/s.
    pub min_airspeed_mps: f64,
    /// Fastest airspeed command, m/s.
    pub max_airspeed_mps: f64,
}

/// The airspeeds a commanded UAV may be sent to, m/s: the model's range
/// [`trim::AIRSPEED_RANGE_MPS`] (15 to 45 m/s, every trim within the actuators' limits and below
/// the stall blending, in wings-level flight) without its slow end: commanded to 15 m/s in a
/// turn at the controller's default limit (0.274 rad/s) the UAV stalls (angle of attack 1.47
/// rad); at 20 m/s it peaks at 0.428 rad, below alpha0 = 0.471 (test
/// `airspeed_commands_through_the_airspeed_loop`).
pub const COMMANDED_AIRSPEED_RANGE_MPS: (f64, f64) = (20.0, trim::AIRSPEED_RANGE_MPS.1);

/// Why an airspeed envelope is refused.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "the airspeed envelope [{min}, {max}] m/s must lie within the Aerosonde's safe range \
     for commanded airspeeds [{lo}, {hi}] m/s, with min <= max",
    lo = COMMANDED_AIRSPEED_RANGE_MPS.0,
    hi = COMMANDED_AIRSPEED_RANGE_MPS.1
)]
pub struct AirspeedEnvelopeError {
    /// The slowest airspeed asked, m/s.
    pub min: f64,
    /// The fastest, m/s.
    pub max: f64,
}

impl FixedWingVariableSpeed {
    /// `uav` with its airspeed commanded within `[min, max]` m/s (inside
    /// [`COMMANDED_AIRSPEED_RANGE_MPS`]).
    pub fn new(uav: FixedWing, min: f64, max: f64) -> Result<Self, AirspeedEnvelopeError> {
        let (lo, hi) = COMMANDED_AIRSPEED_RANGE_MPS;
        if !(lo <= min && min <= max && max <= hi) {
            return Err(AirspeedEnvelopeError { min, max });
        }
        Ok(Self {
            uav,
            min_airspeed_mps: min,
            max_airspeed_mps: max,
        })
    }
}

impl Vehicle for FixedWingVariableSpeed {
    type State = FixedWingState;

    #[inline]
    fn step(&self, s: &mut FixedWingState, omega_radps: f64, dt_s: f64) {
        self.uav.step(s, omega_radps, dt_s);
    }
    #[inline(always)]
    fn step_lanes<const N: usize>(
        &self,
        states: &mut [FixedWingState; N],
        omega_radps: &[f64; N],
        dt_s: f64,
    ) {
        self.uav.step_lanes(states, omega_radps, dt_s);
    }
    #[inline]
    fn pose(&self, s: &FixedWingState) -> Pose2 {
        self.uav.pose(s)
    }
    #[inline]
    fn speed_mps(&self, s: &FixedWingState) -> f64 {
        self.uav.speed_mps(s)
    }
    fn telemetry(&self, s: &FixedWingState) -> Option<Telemetry> {
        self.uav.telemetry(s)
    }
}

impl isotrack_core::SpeedCommand for FixedWingVariableSpeed {
    fn speed_envelope_mps(&self) -> (f64, f64) {
        (self.min_airspeed_mps, self.max_airspeed_mps)
    }

    fn command_speed(&self, s: &mut FixedWingState, speed_mps: f64) -> f64 {
        // max then min: a NaN command gives the slowest (f64::max ignores a NaN argument).
        let v = self
            .min_airspeed_mps
            .max(speed_mps)
            .min(self.max_airspeed_mps);
        s.airspeed_cmd_mps = v;
        v
    }
}

#[cfg(test)]
mod tests;
