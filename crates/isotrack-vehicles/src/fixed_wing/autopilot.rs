//! Beard & McLain's successive-loop-closure autopilot (chapter 6; `autopilot.m` version 2 of
//! the paper's simulator), with the choices the original leaves open made explicit:
//!
//! * every PI integrates by the trapezoid rule and has the original's anti-windup
//!   `I += (Ts/ki)(u_sat - u)`, computed on the loop's full output (for the roll loop, after the
//!   `-kd_phi p` term);
//! * the course error is wrapped to `(-pi, pi]` and the measured course is the true ground-track
//!   course `atan2(pe', pn')` kept continuous (the original feeds the heading and does not wrap);
//! * **trim feed-forward** (on by default): the trim throttle and elevator are added to the
//!   throttle and elevator loop outputs, so a start from trim has no airspeed dip (without it the
//!   original dips about 1.6 m/s, recovered in about 3 s); `trim_feedforward = false` is the
//!   original;
//! * with trim feed-forward the altitude loop also starts bumpless: its integrator starts at
//!   `theta*/ki_h`, so the pitch command starts at the trim pitch (otherwise it starts at 0 and
//!   the aircraft sinks about 0.4 m before the integrator catches up);
//! * the longitudinal integrators reset when the altitude state machine changes zone; the
//!   airspeed-from-pitch output is limited to `+-theta_max` (20 deg).
//!
//! Limits: bank +-40 deg, pitch command +-40 deg in altitude hold, surfaces +-45 deg, throttle
//! [0, 1]. No yaw damper (`delta_r = 0`), as in the original.

use super::dynamics::{Deltas, State12};
use super::gains::Gains;
use super::trim::Trim;
use isotrack_core::math::wrap_angle;

/// One PI loop's memory.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PiState {
    integral: f64,
    e_prev: f64,
}

impl PiState {
    /// `u = sat(kp e + ki I + extra)` with the trapezoid integral and anti-windup.
    #[allow(clippy::too_many_arguments)] // the loop's own gains and limits, spelled out
    #[inline(always)] // compiled with the (multiversioned) step that calls it
    pub fn update(
        &mut self,
        e: f64,
        kp: f64,
        ki: f64,
        extra: f64,
        lo: f64,
        hi: f64,
        ts: f64,
    ) -> f64 {
        self.integral += 0.5 * ts * (e + self.e_prev);
        self.e_prev = e;
        let u = kp * e + ki * self.integral + extra;
        let us = u.clamp(lo, hi);
        if ki != 0.0 {
            self.integral += ts / ki * (us - u);
        }
        us
    }
}

/// Altitude state machine zones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Zone {
    /// `h <= 50 m`.
    TakeOff,
    /// `h <= h_c - 10 m`.
    Climb,
    /// `h >= h_c + 10 m`.
    Descend,
    /// Otherwise.
    Hold,
}

/// The autopilot's memory.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AutopilotState {
    course: PiState,
    roll: PiState,
    altitude: PiState,
    airspeed_throttle: PiState,
    airspeed_pitch: PiState,
    zone: Option<Zone>,
}

impl AutopilotState {
    /// A bumpless start from trim: the altitude integrator holds the trim pitch.
    pub fn from_trim(trim: &Trim, g: &Gains) -> Self {
        let mut s = Self::default();
        if g.ki_h != 0.0 {
            s.altitude.integral = trim.alpha_rad / g.ki_h;
        }
        s
    }

    /// A bumpless start in level flight trimmed at `flown` (another airspeed than the trim
    /// `ff` whose throttle and elevator the autopilot feeds forward, with gains `g`), in
    /// altitude hold: at the start the throttle loop gives `ff.delta_t + ki_v I_v =
    /// flown.delta_t` (its error zero), so `I_v = (flown.delta_t - ff.delta_t)/ki_v`; the
    /// elevator `kp_theta (theta_c - theta) + ff.delta_e = flown.delta_e` at `theta =
    /// flown.alpha` (level flight), so the altitude loop's pitch command is `theta_c =
    /// flown.alpha + (flown.delta_e - ff.delta_e)/kp_theta = ki_h I_h`. With `flown = ff` it
    /// is [`from_trim`](Self::from_trim)'s (the same numbers).
    pub fn from_trim_at(flown: &Trim, ff: &Trim, g: &Gains) -> Self {
        let mut s = Self::default();
        let theta_c = if g.kp_theta != 0.0 {
            flown.alpha_rad + (flown.delta_e_rad - ff.delta_e_rad) / g.kp_theta
        } else {
            flown.alpha_rad
        };
        if g.ki_h != 0.0 {
            s.altitude.integral = theta_c / g.ki_h;
        }
        if g.ki_v != 0.0 {
            s.airspeed_throttle.integral = (flown.delta_t - ff.delta_t) / g.ki_v;
        }
        s
    }
}

/// Commands to the autopilot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Commands {
    /// Course, rad clockwise from north (continuous, not wrapped).
    pub course_rad: f64,
    /// Altitude, m.
    pub altitude_m: f64,
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
}

/// Limits and options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutopilotConfig {
    /// Bank limit, rad (40 deg).
    pub roll_max_rad: f64,
    /// Pitch-command limit in altitude hold, rad (40 deg).
    pub pitch_max_rad: f64,
    /// Take-off pitch and airspeed-from-pitch limit, rad (20 deg).
    pub theta_max_rad: f64,
    /// Surface limit, rad (45 deg).
    pub surface_max_rad: f64,
    /// Add the trim throttle and elevator to the loop outputs.
    pub trim_feedforward: bool,
}

impl Default for AutopilotConfig {
    fn default() -> Self {
        Self {
            roll_max_rad: 40f64.to_radians(),
            pitch_max_rad: 40f64.to_radians(),
            theta_max_rad: 20f64.to_radians(),
            surface_max_rad: 45f64.to_radians(),
            trim_feedforward: true,
        }
    }
}

/// One autopilot update at sample time `ts`: true state, its airspeed `va_mps` and ground course
/// `course_rad` (continuous) in; actuator deflections out.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn autopilot(
    st: &mut AutopilotState,
    cfg: &AutopilotConfig,
    g: &Gains,
    trim: &Trim,
    x: &State12,
    va_mps: f64,
    course_rad: f64,
    cmd: &Commands,
    ts: f64,
) -> Deltas {
    let (phi, theta) = (x[6], x[7]);
    let (p, q) = (x[9], x[10]);
    let h = -x[2];
    let da = lateral(st, cfg, g, phi, p, course_rad, cmd.course_rad, ts);
    let zone = Zone::of(h, cmd.altitude_m);
    st.enter(zone);
    let (dt, theta_c) = longitudinal(st, cfg, g, trim, zone, h, va_mps, cmd, ts);
    let ff_e = if cfg.trim_feedforward {
        trim.delta_e_rad
    } else {
        0.0
    };
    let de = (g.kp_theta * (theta_c - theta) - g.kd_theta * q + ff_e)
        .clamp(-cfg.surface_max_rad, cfg.surface_max_rad);
    Deltas {
        elevator_rad: de,
        aileron_rad: da,
        rudder_rad: 0.0,
        throttle: dt.clamp(0.0, 1.0),
    }
}

/// The lateral loops: the course error (wrapped to `(-pi, pi]`) gives the roll command
/// (limited to the bank limit), the roll error with the `-kd_phi p` damping the aileron
/// (limited to the surface limit), rad.
#[allow(clippy::too_many_arguments)] // the loop's own inputs, spelled out
#[inline(always)]
fn lateral(
    st: &mut AutopilotState,
    cfg: &AutopilotConfig,
    g: &Gains,
    phi: f64,
    p: f64,
    course_rad: f64,
    course_cmd_rad: f64,
    ts: f64,
) -> f64 {
    let e_chi = wrap_angle(course_cmd_rad - course_rad);
    let phi_c = st.course.update(
        e_chi,
        g.kp_chi,
        g.ki_chi,
        0.0,
        -cfg.roll_max_rad,
        cfg.roll_max_rad,
        ts,
    );
    st.roll.update(
        phi_c - phi,
        g.kp_phi,
        g.ki_phi,
        -g.kd_phi * p,
        -cfg.surface_max_rad,
        cfg.surface_max_rad,
        ts,
    )
}

impl Zone {
    /// The altitude state machine's zone at altitude `h` (m) for the commanded `altitude_m`.
    #[inline(always)]
    fn of(h: f64, altitude_m: f64) -> Self {
        if h <= 50.0 {
            Zone::TakeOff
        } else if h <= altitude_m - 10.0 {
            Zone::Climb
        } else if h >= altitude_m + 10.0 {
            Zone::Descend
        } else {
            Zone::Hold
        }
    }
}

impl AutopilotState {
    /// Enter `zone`: the longitudinal integrators reset when the zone changes.
    #[inline(always)]
    fn enter(&mut self, zone: Zone) {
        if self.zone.is_some_and(|z| z != zone) {
            self.altitude = PiState::default();
            self.airspeed_throttle = PiState::default();
            self.airspeed_pitch = PiState::default();
        }
        self.zone = Some(zone);
    }
}

/// The longitudinal loops of `zone`: the throttle and the pitch command (rad). Take-off: half
/// throttle, pitch `theta_max`; climb (half throttle) and descend (none): pitch from the
/// airspeed error; hold: throttle from the airspeed error (plus the trim throttle with
/// feed-forward), pitch from the altitude error.
#[allow(clippy::too_many_arguments)] // the loops' own inputs, spelled out
#[inline(always)]
fn longitudinal(
    st: &mut AutopilotState,
    cfg: &AutopilotConfig,
    g: &Gains,
    trim: &Trim,
    zone: Zone,
    h: f64,
    va_mps: f64,
    cmd: &Commands,
    ts: f64,
) -> (f64, f64) {
    let ff_t = if cfg.trim_feedforward {
        trim.delta_t
    } else {
        0.0
    };
    let e_va = cmd.airspeed_mps - va_mps;
    match zone {
        Zone::TakeOff => (0.5, cfg.theta_max_rad),
        Zone::Climb | Zone::Descend => {
            let th = st.airspeed_pitch.update(
                e_va,
                g.kp_v2,
                g.ki_v2,
                0.0,
                -cfg.theta_max_rad,
                cfg.theta_max_rad,
                ts,
            );
            (if zone == Zone::Climb { 0.5 } else { 0.0 }, th)
        }
        Zone::Hold => {
            let dt = st
                .airspeed_throttle
                .update(e_va, g.kp_v, g.ki_v, ff_t, 0.0, 1.0, ts);
            let th = st.altitude.update(
                cmd.altitude_m - h,
                g.kp_h,
                g.ki_h,
                0.0,
                -cfg.pitch_max_rad,
                cfg.pitch_max_rad,
                ts,
            );
            (dt, th)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The loop's PI by hand: a trapezoid integral, and while saturated the integral is pulled
    /// back by `ts/ki (u_sat - u)` (the 2012 code's anti-windup); with `ki = 0` no pull (and no
    /// division by zero).
    #[test]
    fn pi_loop_by_hand() {
        let mut s = PiState::default();
        // e = 1 after 0: integral 0.5 * 0.1 * (1 + 0) = 0.05; u = 2 * 1 + 0.5 * 0.05 = 2.025,
        // saturated at 1: integral += 0.1 / 0.5 * (1 - 2.025).
        let u = s.update(1.0, 2.0, 0.5, 0.0, -1.0, 1.0, 0.1);
        assert_eq!(u, 1.0);
        assert!(
            (s.integral - (0.05 + 0.2 * (1.0 - 2.025))).abs() < 1e-15,
            "{}",
            s.integral
        );
        assert_eq!(s.e_prev, 1.0);
        // Unsaturated: e = 0.2: integral += 0.5 * 0.1 * (0.2 + 1); u = 0.4 + 0.5 I + 0.1.
        let i0 = s.integral;
        let u = s.update(0.2, 2.0, 0.5, 0.1, -1.0, 1.0, 0.1);
        let i1 = i0 + 0.05 * 1.2;
        assert!((s.integral - i1).abs() < 1e-15);
        assert!((u - (0.4 + 0.5 * i1 + 0.1)).abs() < 1e-15);
        // ki = 0: the integral still accumulates (unused), no pull.
        let mut p = PiState::default();
        let u = p.update(3.0, 1.0, 0.0, 0.0, -1.0, 1.0, 0.1);
        assert_eq!(u, 1.0);
        assert!((p.integral - 0.15).abs() < 1e-15);
    }
}
