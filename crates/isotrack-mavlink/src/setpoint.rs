//! The longitudinal half of a fixed wing's `SET_ATTITUDE_TARGET` from `isotrack fly`: the law
//! commands the turn (the roll, [`crate::wire::roll_of_turn_rate`]); PX4's fixed-wing offboard
//! attitude control also flies the quaternion's pitch and the thrust field, so they carry an
//! altitude hold and an airspeed hold instead of zeros.
//!
//! * Pitch: `theta = clamp(k_h dz(h_c - h), -theta_max, theta_max)`, the altitude-hold loop of
//!   Beard & McLain 2012 (Ch. 6, the longitudinal autopilot's altitude hold using commanded
//!   pitch, `theta_c = k_p,h (h_c - h)`, saturated), with a dead
//!   zone `dz(e) = sign(e) max(|e| - d, 0)` of [`ALTITUDE_DEAD_BAND_M`] so that baro and GPS
//!   noise do not pitch the aircraft; `h_c` is the first altitude received once the companion
//!   has control.
//! * Thrust: `delta_t = clamp(delta_trim + k_V (V_c - V), 0, 1)`, the airspeed hold using
//!   throttle of Beard & McLain 2012 (Ch. 6, `delta_t = delta_t* + k_p,V (V_c - V)`),
//!   `V_c` the scenario's `vehicle.airspeed_mps`, `V` the vehicle's `VFR_HUD.airspeed`; the
//!   trim alone while no airspeed has come.

/// The altitude-hold gain `k_h`, rad of pitch per metre of altitude error.
pub const ALTITUDE_GAIN_RAD_PER_M: f64 = 0.02;
/// The dead zone of the altitude error, m: within it the pitch is 0.
pub const ALTITUDE_DEAD_BAND_M: f64 = 2.0;
/// The pitch limit `theta_max`, rad (15 deg).
pub const PITCH_LIMIT_RAD: f64 = 15.0 * std::f64::consts::PI / 180.0;
/// The trim thrust `delta_trim` (0 to 1).
pub const THRUST_TRIM: f64 = 0.5;
/// The airspeed-hold gain `k_V`, thrust per m/s of airspeed error.
pub const AIRSPEED_GAIN_PER_MPS: f64 = 0.05;

/// The pitch that holds `target_m` at altitude `altitude_m`, rad (positive nose up); 0 while
/// either is unknown or not finite.
pub fn pitch_of_altitude(target_m: Option<f64>, altitude_m: Option<f64>) -> f64 {
    let (Some(c), Some(h)) = (target_m, altitude_m) else {
        return 0.0;
    };
    let e = c - h;
    if !e.is_finite() {
        return 0.0;
    }
    let dz = e.signum() * (e.abs() - ALTITUDE_DEAD_BAND_M).max(0.0);
    (ALTITUDE_GAIN_RAD_PER_M * dz).clamp(-PITCH_LIMIT_RAD, PITCH_LIMIT_RAD)
}

/// The thrust that holds airspeed `target_mps` at airspeed `airspeed_mps` (0 to 1); the trim
/// while the airspeed is unknown or not finite.
pub fn thrust_of_airspeed(target_mps: f64, airspeed_mps: Option<f64>) -> f64 {
    match airspeed_mps.map(|v| target_mps - v) {
        Some(e) if e.is_finite() => (THRUST_TRIM + AIRSPEED_GAIN_PER_MPS * e).clamp(0.0, 1.0),
        _ => THRUST_TRIM,
    }
}

/// The attitude quaternion `[w, x, y, z]` (body to NED, ZYX Euler angles) of a roll `phi` and
/// a pitch `theta` with zero yaw: `[c_phi c_theta, s_phi c_theta, c_phi s_theta,
/// -s_phi s_theta]` of the half angles, as `f32`. With `theta = 0` it is
/// [`crate::wire::quaternion_of_roll`] bit for bit.
pub fn quaternion_of_roll_pitch(roll_rad: f64, pitch_rad: f64) -> [f32; 4] {
    if pitch_rad == 0.0 {
        return crate::wire::quaternion_of_roll(roll_rad);
    }
    let (sp, cp) = (0.5 * roll_rad).sin_cos();
    let (st, ct) = (0.5 * pitch_rad).sin_cos();
    [
        (cp * ct) as f32,
        (sp * ct) as f32,
        (cp * st) as f32,
        (-sp * st) as f32,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 10 m low: 8 m beyond the dead zone, 0.16 rad nose up; 100 m high: the limit, nose down.
    #[test]
    fn altitude_hold() {
        assert_eq!(pitch_of_altitude(Some(100.0), Some(99.0)), 0.0);
        assert!((pitch_of_altitude(Some(100.0), Some(90.0)) - 0.16).abs() < 1e-12);
        assert_eq!(
            pitch_of_altitude(Some(100.0), Some(200.0)),
            -PITCH_LIMIT_RAD
        );
        assert_eq!(pitch_of_altitude(None, Some(90.0)), 0.0);
        assert_eq!(pitch_of_altitude(Some(100.0), Some(f64::NAN)), 0.0);
    }

    /// 5 m/s slow: 0.5 + 0.25; far too fast: 0.
    #[test]
    fn airspeed_hold() {
        assert!((thrust_of_airspeed(30.0, Some(25.0)) - 0.75).abs() < 1e-12);
        assert_eq!(thrust_of_airspeed(30.0, Some(60.0)), 0.0);
        assert_eq!(thrust_of_airspeed(30.0, None), THRUST_TRIM);
    }

    /// The quaternion's ZYX roll and pitch come back: roll atan2(2(wx + yz), 1 - 2(x^2 + y^2)),
    /// pitch asin(2(wy - zx)).
    #[test]
    fn quaternion_round_trip() {
        let q = quaternion_of_roll_pitch(-0.5, 0.2).map(f64::from);
        let roll =
            (2.0 * (q[0] * q[1] + q[2] * q[3])).atan2(1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]));
        let pitch = (2.0 * (q[0] * q[2] - q[3] * q[1])).asin();
        assert!(
            (roll + 0.5).abs() < 1e-6 && (pitch - 0.2).abs() < 1e-6,
            "{roll} {pitch}"
        );
        assert_eq!(
            quaternion_of_roll_pitch(0.3, 0.0),
            crate::wire::quaternion_of_roll(0.3)
        );
    }
}
