//! Wings-level trim at a given airspeed and zero flight-path angle.

use super::dynamics::{derivatives, Deltas, State12, WindSample};
use super::params::Aerosonde;
use isotrack_core::numtext::Echo;

/// A trim condition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trim {
    /// Airspeed, m/s.
    pub airspeed_mps: f64,
    /// Angle of attack (= pitch, gamma = 0), rad.
    pub alpha_rad: f64,
    /// Elevator, rad.
    pub delta_e_rad: f64,
    /// Throttle, 0..1.
    pub delta_t: f64,
    /// Body velocities `u, w`, m/s.
    pub u_mps: f64,
    /// See `u_mps`.
    pub w_mps: f64,
}

/// Why trim failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TrimError {
    /// Newton's method did not converge.
    #[error("no trim found at {} m/s (Newton's method did not converge)", Echo(*.0))]
    NoConvergence(f64),
    /// Bad airspeed.
    #[error("airspeed must be finite and > 0, got {}", Echo(*.0))]
    BadAirspeed(f64),
    /// Outside [`AIRSPEED_RANGE_MPS`].
    #[error("the Aerosonde model is valid for {lo}..{hi} m/s, got {}", Echo(*.0), lo = AIRSPEED_RANGE_MPS.0, hi = AIRSPEED_RANGE_MPS.1)]
    OutOfRange(f64),
    /// The trim needs an input beyond its actuator's limit, or an angle of attack past the
    /// model's stall blending.
    #[error("no feasible trim at {} m/s: {what} = {value:.4} is beyond {limit}", Echo(*.airspeed_mps))]
    Infeasible {
        /// Airspeed, m/s.
        airspeed_mps: f64,
        /// The quantity.
        what: &'static str,
        /// Its trim value.
        value: f64,
        /// The limit, as text with units.
        limit: &'static str,
    },
}

/// The airspeeds the Aerosonde model and its autopilot are used at, m/s: every trim in it is
/// within the actuators' limits and below the stall blending (from 15 to 45 m/s: throttle
/// 0.213 to 0.595, elevator -0.324 to -0.025 rad, alpha 0.365 to -0.029 rad, alpha0 = 0.47);
/// `run`, `trim` and `replay` all accept exactly this range.
pub const AIRSPEED_RANGE_MPS: (f64, f64) = (15.0, 45.0);

/// Throttle range.
const THROTTLE_RANGE: (f64, f64) = (0.0, 1.0);
/// Surface limit, rad (45 deg, the autopilot's `surface_max_rad`).
const SURFACE_MAX_RAD: f64 = std::f64::consts::FRAC_PI_4;

/// The trim state vector at altitude `h` (position at the origin, heading `psi`).
pub fn trim_state(t: &Trim, altitude_m: f64, psi_rad: f64) -> State12 {
    [
        0.0,
        0.0,
        -altitude_m,
        t.u_mps,
        0.0,
        t.w_mps,
        0.0,
        t.alpha_rad,
        psi_rad,
        0.0,
        0.0,
        0.0,
    ]
}

/// Solves `u' = w' = q' = 0` for `(alpha, delta_e, delta_t)` with `theta = alpha` (wings level,
/// `gamma = 0`, `beta = 0`), no wind, by Newton's method with a central-difference Jacobian.
pub fn trim(p: &Aerosonde, airspeed_mps: f64) -> Result<Trim, TrimError> {
    if !(airspeed_mps.is_finite() && airspeed_mps > 0.0) {
        return Err(TrimError::BadAirspeed(airspeed_mps));
    }
    if !(AIRSPEED_RANGE_MPS.0..=AIRSPEED_RANGE_MPS.1).contains(&airspeed_mps) {
        return Err(TrimError::OutOfRange(airspeed_mps));
    }
    let gm = super::dynamics::Derived::new(p);
    let trim_of = |z: [f64; 3]| Trim {
        airspeed_mps,
        alpha_rad: z[0],
        delta_e_rad: z[1],
        delta_t: z[2],
        u_mps: airspeed_mps * z[0].cos(),
        w_mps: airspeed_mps * z[0].sin(),
    };
    let residual = |z: [f64; 3]| {
        let t = trim_of(z);
        let x = trim_state(&t, 100.0, 0.0);
        let d = Deltas {
            elevator_rad: z[1],
            throttle: z[2],
            ..Deltas::default()
        };
        let f = derivatives(p, &gm, &x, &d, &WindSample::default());
        [f[3], f[5], f[10]]
    };
    let mut z = [0.03, -0.07, 0.4];
    for _ in 0..50 {
        let r = residual(z);
        if r.iter().all(|v| v.abs() < 1e-13) {
            break;
        }
        let mut jac = nalgebra::Matrix3::<f64>::zeros();
        for j in 0..3 {
            let h = 1e-7;
            let (mut zp, mut zm) = (z, z);
            zp[j] += h;
            zm[j] -= h;
            let (rp, rm) = (residual(zp), residual(zm));
            for i in 0..3 {
                jac[(i, j)] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        let step = jac
            .lu()
            .solve(&nalgebra::Vector3::new(r[0], r[1], r[2]))
            .ok_or(TrimError::NoConvergence(airspeed_mps))?;
        for i in 0..3 {
            z[i] -= step[i];
        }
    }
    let r = residual(z);
    if !r.iter().all(|v| v.abs() < 1e-9) || !z.iter().all(|v| v.is_finite()) {
        return Err(TrimError::NoConvergence(airspeed_mps));
    }
    let infeasible = |what, value, limit| TrimError::Infeasible {
        airspeed_mps,
        what,
        value,
        limit,
    };
    if !(THROTTLE_RANGE.0..=THROTTLE_RANGE.1).contains(&z[2]) {
        return Err(infeasible("throttle delta_t", z[2], "[0, 1]"));
    }
    if z[1].abs() > SURFACE_MAX_RAD {
        return Err(infeasible("elevator delta_e (rad)", z[1], "+-pi/4 rad"));
    }
    if z[0].abs() >= p.alpha0 {
        return Err(infeasible(
            "alpha (rad)",
            z[0],
            "the stall blending angle alpha0 = 0.47 rad",
        ));
    }
    Ok(trim_of(z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trim table of docs/FIXED-WING.md section 4, to 1e-4.
    #[test]
    fn reproduces_the_trim_table() {
        let p = Aerosonde::beard_mclain_2012();
        for (va, alpha, de, dt, u, w) in [
            (25.0, 0.082157, -0.109199, 0.333516, 24.9157, 2.0516),
            (30.0, 0.0330598, -0.0718854, 0.398352, 29.9836, 0.99161),
            (35.0, 0.003406, -0.049349, 0.463819, 34.9998, 0.1192),
        ] {
            let t = trim(&p, va).unwrap();
            assert!(
                (t.alpha_rad - alpha).abs() < 1e-4,
                "{va}: alpha {}",
                t.alpha_rad
            );
            assert!(
                (t.delta_e_rad - de).abs() < 1e-4,
                "{va}: de {}",
                t.delta_e_rad
            );
            assert!((t.delta_t - dt).abs() < 1e-4, "{va}: dt {}", t.delta_t);
            assert!(
                (t.u_mps - u).abs() < 1e-4 && (t.w_mps - w).abs() < 1e-4,
                "{va}: u, w {} {}",
                t.u_mps,
                t.w_mps
            );
        }
    }

    /// A non-positive or non-finite airspeed is a bad value; a finite one outside the model's
    /// [15, 45] m/s is out of its range; both ends of the range trim.
    #[test]
    fn airspeeds_are_refused_by_kind() {
        let p = Aerosonde::beard_mclain_2012();
        for va in [0.0, -30.0, f64::NAN, f64::INFINITY] {
            assert!(
                matches!(trim(&p, va), Err(TrimError::BadAirspeed(_))),
                "{va}"
            );
        }
        for va in [14.99, 45.01, 1e-3] {
            assert!(
                matches!(trim(&p, va), Err(TrimError::OutOfRange(_))),
                "{va}"
            );
        }
        for va in [AIRSPEED_RANGE_MPS.0, AIRSPEED_RANGE_MPS.1] {
            assert!(trim(&p, va).is_ok(), "{va}");
        }
    }

    /// A trim beyond an actuator is refused by name: an airframe pitching up with `C_m0 = 1`
    /// needs about `-C_m0 / C_m_de = 1 rad` of elevator (more than pi/4), a weak motor more than
    /// full throttle.
    #[test]
    fn trims_beyond_the_actuators_are_infeasible() {
        let nose_up = Aerosonde {
            c_m0: 1.0,
            ..Aerosonde::beard_mclain_2012()
        };
        let weak = Aerosonde {
            k_motor: 30.0,
            ..Aerosonde::beard_mclain_2012()
        };
        for (p, want) in [(nose_up, "elevator"), (weak, "throttle")] {
            match trim(&p, 30.0) {
                Err(TrimError::Infeasible { what, .. }) => {
                    assert!(what.starts_with(want), "{what}")
                }
                other => panic!("{want}: {other:?}"),
            }
        }
    }
}
