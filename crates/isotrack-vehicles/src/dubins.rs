//! The Dubins robot of the paper, eq. (5): `p' = v [cos(theta), sin(theta)]`, `theta' = omega`.

use isotrack_core::lanes;
use isotrack_core::math::{wrap_angle, Pose2, Vec2};
use isotrack_core::{SpeedCommand, Vehicle};

/// The largest `|heading|` a step leaves as it is, rad (about 1.6 million turns): past it the
/// step wraps the heading into `(-pi, pi]` (its remainder modulo `2 pi`). Without a bound, a
/// law with huge gains (no turn-rate limit) drives the heading past `1e16` rad, where one ulp
/// exceeds `2 pi` and `sin`/`cos` of it, the direction the robot moves in, is noise. Wrapping
/// at every step would change the bits of every trace (the `sin_cos` of `theta` and of
/// `theta - 2 pi n` differ by rounding), and so would a bound a bundled run reaches: `pid` on
/// the PM2.5 plumes (`compare`) spins at up to 1 190 rad/s and turns 3.7e5 rad in its 600 s.
/// At `1e7` rad one ulp is `1.9e-9` rad, so the positions stay as accurate as a run needs, and
/// every bundled output is byte-identical (`tests/golden`).
pub const HEADING_WRAP_RAD: f64 = 1.0e7;

/// State of a [`Dubins`] robot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DubinsState {
    /// Position, metres.
    pub position_m: Vec2,
    /// Heading, radians counter-clockwise from +x, kept continuous (not wrapped) so that the
    /// number of turns can be read from it, up to [`HEADING_WRAP_RAD`]: past it the step wraps
    /// it into `(-pi, pi]` (see there); [`Vehicle::pose`] reports it wrapped to `(-pi, pi]`.
    pub heading_rad: f64,
}

/// A Dubins robot (unicycle at constant speed): `p' = v [cos(theta), sin(theta)]`,
/// `theta' = omega` (Dong & You, eq. (5)).
///
/// Integration: classical RK4 with `omega` held over the step. Because the right-hand side does not
/// depend on the position and `theta'` is constant over the step, the stages are
/// `k1 = h(theta)`, `k2 = k3 = h(theta + omega*dt/2)`, `k4 = h(theta + omega*dt)` with
/// `h = v [cos, sin]`, so RK4 is exactly Simpson's rule `p += dt/6 (k1 + 4 k2 + k4)`: three
/// `sin_cos` evaluations per step instead of four, the same numbers as a generic RK4. The stage
/// directions are then obtained by rotating `h(theta)` by `a = omega*dt/2` twice (one `sin_cos`
/// of `a` instead of two of the stage angles): the same values up to rounding, and a third of
/// the step's cost. Local error `O(v*(omega*dt)^4*dt)`; the heading is exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dubins {
    /// Constant forward speed `v`, m/s.
    pub speed_mps: f64,
}

impl Dubins {
    /// Simpson's rule over the step from `(sin, cos)` of the heading and of `a = omega*dt/2`.
    #[inline(always)]
    fn advance(
        &self,
        s: &mut DubinsState,
        omega_radps: f64,
        dt_s: f64,
        sc1: (f64, f64),
        sca: (f64, f64),
    ) {
        advance_at(self.speed_mps, s, omega_radps, dt_s, sc1, sca);
    }
}

/// Simpson's rule over the step at speed `speed_mps` (the arithmetic of [`Dubins`], shared with
/// [`DubinsVariableSpeed`] so that both give the same numbers at the same speed).
#[inline(always)]
fn advance_at(
    speed_mps: f64,
    s: &mut DubinsState,
    omega_radps: f64,
    dt_s: f64,
    (s1, c1): (f64, f64),
    (sa, ca): (f64, f64),
) {
    // Rotate (c1, s1) by a, then by a again.
    let (c2, s2) = (c1 * ca - s1 * sa, s1 * ca + c1 * sa);
    let (c4, s4) = (c2 * ca - s2 * sa, s2 * ca + c2 * sa);
    let k = speed_mps * dt_s / 6.0;
    s.position_m.x += k * (c1 + 4.0 * c2 + c4);
    s.position_m.y += k * (s1 + 4.0 * s2 + s4);
    s.heading_rad += omega_radps * dt_s;
    if s.heading_rad.abs() > HEADING_WRAP_RAD {
        s.heading_rad = wrap_far_heading(s.heading_rad);
    }
}

/// `theta` (beyond [`HEADING_WRAP_RAD`]) into `(-pi, pi]`: `theta mod 2 pi`, the remainder of
/// the double exact (IEEE 754 `fmod`) however large `theta` is, where `theta - 2 pi
/// round(theta / 2 pi)` is not (past `2^53` its rounding exceeds `2 pi`). An infinite
/// heading becomes NaN: non-finite either way, and the run ends as `diverged`.
#[inline(never)]
#[cold]
fn wrap_far_heading(theta_rad: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = theta_rad % TAU;
    if r > PI {
        r - TAU
    } else if r <= -PI {
        r + TAU
    } else {
        r
    }
}

/// State of a [`DubinsVariableSpeed`] robot: the Dubins state and the speed held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DubinsSpeedState {
    /// Position and heading.
    pub dubins: DubinsState,
    /// The speed held over the next step, m/s (inside the envelope).
    pub speed_mps: f64,
}

/// A Dubins robot whose speed is commanded within `[min_speed_mps, max_speed_mps]` (the
/// [`SpeedCommand`] a team's spacing law drives): `p' = v [cos(theta), sin(theta)]`,
/// `theta' = omega`, with `v` held over each step like `omega`. The integration is [`Dubins`]'s,
/// so at a constant speed `v` it moves as `Dubins { speed_mps: v }` does, bit for bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DubinsVariableSpeed {
    /// Slowest speed, m/s (> 0).
    pub min_speed_mps: f64,
    /// Fastest speed, m/s (>= `min_speed_mps`).
    pub max_speed_mps: f64,
}

impl DubinsVariableSpeed {
    /// A state at `dubins` holding `speed_mps`, saturated to the envelope.
    pub fn state(&self, dubins: DubinsState, speed_mps: f64) -> DubinsSpeedState {
        let mut s = DubinsSpeedState {
            dubins,
            speed_mps: self.min_speed_mps,
        };
        self.command_speed(&mut s, speed_mps);
        s
    }
}

impl Vehicle for DubinsVariableSpeed {
    type State = DubinsSpeedState;

    #[inline]
    fn step(&self, s: &mut DubinsSpeedState, omega_radps: f64, dt_s: f64) {
        let (s1, c1) = lanes::sin_cos(s.dubins.heading_rad);
        let (sa, ca) = lanes::sin_cos_small_angle(omega_radps * (0.5 * dt_s));
        advance_at(
            s.speed_mps,
            &mut s.dubins,
            omega_radps,
            dt_s,
            (s1, c1),
            (sa, ca),
        );
    }

    /// The step of `N` robots with their `sin_cos` in lanes; each state is what
    /// [`step`](Vehicle::step) gives it, bit for bit.
    #[inline(always)]
    fn step_lanes<const N: usize>(
        &self,
        states: &mut [DubinsSpeedState; N],
        omega_radps: &[f64; N],
        dt_s: f64,
    ) {
        let mut th = [0.0; N];
        let mut half = [0.0; N];
        for i in 0..N {
            th[i] = states[i].dubins.heading_rad;
            half[i] = omega_radps[i] * (0.5 * dt_s);
        }
        let (s1, c1) = lanes::sin_cos_lanes(th);
        let (sa, ca) = lanes::sin_cos_small_angle_lanes(half);
        for i in 0..N {
            let v = states[i].speed_mps;
            advance_at(
                v,
                &mut states[i].dubins,
                omega_radps[i],
                dt_s,
                (s1[i], c1[i]),
                (sa[i], ca[i]),
            );
        }
    }

    #[inline]
    fn pose(&self, s: &DubinsSpeedState) -> Pose2 {
        Pose2 {
            position: s.dubins.position_m,
            heading_rad: wrap_angle(s.dubins.heading_rad),
        }
    }

    #[inline]
    fn position(&self, s: &DubinsSpeedState) -> Vec2 {
        s.dubins.position_m
    }

    fn speed_mps(&self, s: &DubinsSpeedState) -> f64 {
        s.speed_mps
    }
}

impl SpeedCommand for DubinsVariableSpeed {
    fn speed_envelope_mps(&self) -> (f64, f64) {
        (self.min_speed_mps, self.max_speed_mps)
    }

    #[inline]
    fn command_speed(&self, s: &mut DubinsSpeedState, speed_mps: f64) -> f64 {
        // max then min: a NaN command gives v_min (f64::max ignores a NaN argument).
        let v = self.min_speed_mps.max(speed_mps).min(self.max_speed_mps);
        s.speed_mps = v;
        v
    }
}

impl Vehicle for Dubins {
    type State = DubinsState;

    #[inline]
    fn step(&self, s: &mut DubinsState, omega_radps: f64, dt_s: f64) {
        let (s1, c1) = lanes::sin_cos(s.heading_rad);
        // omega (dt/2): one multiply on the loop's chain instead of two; the same double as
        // (omega/2) dt, since halving is exact.
        let (sa, ca) = lanes::sin_cos_small_angle(omega_radps * (0.5 * dt_s));
        self.advance(s, omega_radps, dt_s, (s1, c1), (sa, ca));
    }

    /// The step of `N` robots with their `sin_cos` in lanes (vectorised); each state is what
    /// [`step`](Vehicle::step) gives it, bit for bit.
    #[inline(always)]
    fn step_lanes<const N: usize>(
        &self,
        states: &mut [DubinsState; N],
        omega_radps: &[f64; N],
        dt_s: f64,
    ) {
        let mut th = [0.0; N];
        let mut half = [0.0; N];
        for i in 0..N {
            th[i] = states[i].heading_rad;
            half[i] = omega_radps[i] * (0.5 * dt_s);
        }
        let (s1, c1) = lanes::sin_cos_lanes(th);
        let (sa, ca) = lanes::sin_cos_small_angle_lanes(half);
        for i in 0..N {
            self.advance(
                &mut states[i],
                omega_radps[i],
                dt_s,
                (s1[i], c1[i]),
                (sa[i], ca[i]),
            );
        }
    }

    #[inline]
    fn pose(&self, s: &DubinsState) -> Pose2 {
        Pose2 {
            position: s.position_m,
            heading_rad: wrap_angle(s.heading_rad),
        }
    }

    #[inline]
    fn position(&self, s: &DubinsState) -> Vec2 {
        s.position_m
    }

    fn speed_mps(&self, _s: &DubinsState) -> f64 {
        self.speed_mps
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    #[test]
    fn straight_line() {
        let d = Dubins { speed_mps: 2.0 };
        let mut s = DubinsState {
            position_m: Vec2::new(1.0, 1.0),
            heading_rad: PI / 2.0,
        };
        for _ in 0..100 {
            d.step(&mut s, 0.0, 0.01);
        }
        assert_relative_eq!(s.position_m.x, 1.0, epsilon = 1e-12);
        assert_relative_eq!(s.position_m.y, 3.0, epsilon = 1e-12);
    }

    #[test]
    fn constant_turn_closes_a_circle_of_radius_v_over_omega() {
        // omega = 0.1 rad/s, v = 0.5 m/s: radius 5 m, period 2 pi/0.1 s. The exact arc is
        // p(t) = p0 + (v/omega) [sin(th0 + omega t) - sin th0, -cos(th0 + omega t) + cos th0].
        let d = Dubins { speed_mps: 0.5 };
        let mut s = DubinsState {
            position_m: Vec2::new(0.0, 0.0),
            heading_rad: 0.3,
        };
        let dt = 0.01;
        let n = 3000;
        for _ in 0..n {
            d.step(&mut s, 0.1, dt);
        }
        let t = n as f64 * dt;
        let r = 5.0;
        let ex = r * ((0.3 + 0.1 * t).sin() - 0.3f64.sin());
        let ey = r * (-(0.3 + 0.1 * t).cos() + 0.3f64.cos());
        assert_relative_eq!(s.position_m.x, ex, epsilon = 1e-10);
        assert_relative_eq!(s.position_m.y, ey, epsilon = 1e-10);
        assert_relative_eq!(s.heading_rad, 0.3 + 0.1 * t, epsilon = 1e-12);
    }

    #[test]
    fn positive_omega_turns_left() {
        let d = Dubins { speed_mps: 1.0 };
        let mut s = DubinsState {
            position_m: Vec2::new(0.0, 0.0),
            heading_rad: 0.0,
        };
        for _ in 0..10 {
            d.step(&mut s, 0.5, 0.1);
        }
        assert!(
            s.position_m.y > 0.0,
            "heading east and turning left goes north"
        );
    }

    /// Eight robots stepped in lanes are each where `step` puts it, bit for bit (turn rates of
    /// both signs, zero, and a heading far past 2 pi), and the pose wraps the heading.
    #[test]
    fn lanes_step_each_robot_as_step_does() {
        let d = Dubins { speed_mps: 0.7 };
        let omega = [0.0, 0.3, -1.2, 2.5, -0.01, 1.0, 0.05, -3.0];
        let mut lanes: [DubinsState; 8] = core::array::from_fn(|i| DubinsState {
            position_m: Vec2::new(i as f64, -2.0 * i as f64),
            heading_rad: -3.0 + 1.7 * i as f64 + if i == 7 { 40.0 } else { 0.0 },
        });
        let mut alone = lanes;
        for _ in 0..500 {
            d.step_lanes(&mut lanes, &omega, 0.02);
            for (s, &w) in alone.iter_mut().zip(&omega) {
                d.step(s, w, 0.02);
            }
        }
        for (a, b) in lanes.iter().zip(&alone) {
            assert_eq!(a.position_m.x.to_bits(), b.position_m.x.to_bits());
            assert_eq!(a.position_m.y.to_bits(), b.position_m.y.to_bits());
            assert_eq!(a.heading_rad.to_bits(), b.heading_rad.to_bits());
            assert_eq!(d.position(a), a.position_m);
            let h = d.pose(a).heading_rad;
            assert!(h > -PI && h <= PI);
            assert!((h - wrap_angle(a.heading_rad)).abs() == 0.0);
        }
        // 500 steps of 0.02 s at the heading's rate: the heading advanced by omega * 10 s.
        assert!((alone[1].heading_rad - (-3.0 + 1.7 + 0.3 * 10.0)).abs() < 1e-12);
        assert_eq!(d.speed_mps(&alone[0]), 0.7);
    }

    /// At a constant speed the variable-speed robot moves as the constant-speed one does, bit
    /// for bit, alone and in lanes; commands saturate to the envelope (NaN: `v_min`).
    #[test]
    fn variable_speed_matches_constant_speed_and_saturates() {
        let d = Dubins { speed_mps: 0.7 };
        let v = DubinsVariableSpeed {
            min_speed_mps: 0.2,
            max_speed_mps: 1.0,
        };
        let start = DubinsState {
            position_m: Vec2::new(1.0, -2.0),
            heading_rad: 0.4,
        };
        let (mut a, mut b) = (start, v.state(start, 0.7));
        let mut lanes = [v.state(start, 0.7); 3];
        for k in 0..400 {
            let w = 0.3 * ((k % 7) as f64 - 3.0);
            d.step(&mut a, w, 0.01);
            v.step(&mut b, w, 0.01);
            v.step_lanes(&mut lanes, &[w; 3], 0.01);
        }
        assert_eq!(a.position_m.x.to_bits(), b.dubins.position_m.x.to_bits());
        assert_eq!(a.position_m.y.to_bits(), b.dubins.position_m.y.to_bits());
        assert_eq!(a.heading_rad.to_bits(), b.dubins.heading_rad.to_bits());
        assert_eq!(lanes[2], b);
        assert_eq!(v.command_speed(&mut b, 3.0), 1.0);
        assert_eq!(v.command_speed(&mut b, 0.0), 0.2);
        assert_eq!(v.command_speed(&mut b, f64::NAN), 0.2);
        assert_eq!(v.command_speed(&mut b, 0.5), 0.5);
        assert_eq!(v.speed_mps(&b), 0.5);
        assert_eq!(v.speed_envelope_mps(), (0.2, 1.0));
    }
}
