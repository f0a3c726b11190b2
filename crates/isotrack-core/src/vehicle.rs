//! The vehicle trait: a turn-rate command in, a pose out.

use crate::math::Pose2;

/// A vehicle driven by a turn-rate (course-rate) command `omega` in rad/s, positive to the left
/// (counter-clockwise seen from above).
///
/// Each vehicle owns its integration scheme: the simulation loop only asks it to advance one step
/// with the command held (zero-order hold) and reads its pose.
pub trait Vehicle {
    /// The full state (whatever the model needs).
    type State: Clone;
    /// Advances `state` by `dt_s` seconds with `omega_radps` held over the step.
    fn step(&self, state: &mut Self::State, omega_radps: f64, dt_s: f64);
    /// Position and course of the state; the sensor samples the field at this position.
    fn pose(&self, state: &Self::State) -> Pose2;
    /// The position of the state, metres: `pose(state).position`, which a vehicle may give
    /// without computing the rest of the pose (the batched loop asks for it every step).
    #[inline]
    fn position(&self, state: &Self::State) -> crate::math::Vec2 {
        self.pose(state).position
    }
    /// Ground speed in m/s (for metrics such as path length per unit time).
    fn speed_mps(&self, state: &Self::State) -> f64;
    /// Extra quantities a flying vehicle reports (altitude, airspeed, roll); `None` for a
    /// ground robot.
    fn telemetry(&self, _state: &Self::State) -> Option<Telemetry> {
        None
    }
    /// [`step`](Self::step) of `N` runs at once, each with its own command: what a batched
    /// sweep does every step. The default steps each in turn; a vehicle whose step vectorises
    /// (the Dubins robot) overrides it with the same arithmetic in lanes, so each state is the
    /// one `step` gives, bit for bit.
    #[inline]
    fn step_lanes<const N: usize>(
        &self,
        states: &mut [Self::State; N],
        omega_radps: &[f64; N],
        dt_s: f64,
    ) where
        Self: Sized,
    {
        for (s, &w) in states.iter_mut().zip(omega_radps) {
            self.step(s, w, dt_s);
        }
    }
}

/// A vehicle whose forward speed can be commanded, within an envelope: what a team's spacing
/// law drives (docs/TEAMS.md). The command is held until the next one (zero-order hold), like
/// the turn rate.
pub trait SpeedCommand: Vehicle {
    /// The speed envelope `(v_min, v_max)`, m/s, `0 < v_min <= v_max`.
    fn speed_envelope_mps(&self) -> (f64, f64);
    /// Holds `speed_mps`, saturated to the envelope (a NaN holds `v_min`), from the next step on;
    /// returns the speed held.
    fn command_speed(&self, state: &mut Self::State, speed_mps: f64) -> f64;
}

/// What a flying vehicle adds to the trace.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Telemetry {
    /// Altitude above the reference, m.
    pub altitude_m: f64,
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
    /// Roll angle, rad, positive right wing down.
    pub roll_rad: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Pose2, Vec2};

    struct Still;
    impl Vehicle for Still {
        type State = ();
        fn step(&self, _: &mut (), _: f64, _: f64) {}
        fn pose(&self, _: &()) -> Pose2 {
            Pose2 {
                position: Vec2::new(0.0, 0.0),
                heading_rad: 0.0,
            }
        }
        fn speed_mps(&self, _: &()) -> f64 {
            0.0
        }
    }

    /// A vehicle that does not fly reports no telemetry by default.
    #[test]
    fn telemetry_defaults_to_none() {
        assert_eq!(Still.telemetry(&()), None);
    }

    /// A point moving along x at the commanded rate (state: its x, m).
    struct Slider;
    impl Vehicle for Slider {
        type State = f64;
        fn step(&self, x: &mut f64, omega_radps: f64, dt_s: f64) {
            *x += omega_radps * dt_s;
        }
        fn pose(&self, x: &f64) -> Pose2 {
            Pose2 {
                position: Vec2::new(*x, -1.0),
                heading_rad: 0.0,
            }
        }
        fn speed_mps(&self, _: &f64) -> f64 {
            1.0
        }
    }

    /// The defaults: `position` is the pose's, `step_lanes` steps each state with its command.
    #[test]
    fn default_position_and_lane_step() {
        assert_eq!(Slider.position(&2.5), Vec2::new(2.5, -1.0));
        let mut xs = [0.0, 1.0, -2.0];
        Slider.step_lanes(&mut xs, &[1.0, -3.0, 0.5], 0.5);
        assert_eq!(xs, [0.5, -0.5, -1.75]);
    }
}
