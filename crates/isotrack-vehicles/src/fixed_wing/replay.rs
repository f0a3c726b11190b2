//! Open-loop replay of the 6-DOF airframe (`isotrack replay`): control-surface deflections and
//! throttle given at time stamps are held piecewise constant (zero-order hold) over each
//! interval and the bare airframe (Beard & McLain 2012, ch. 3-4: the 12 states of
//! [`dynamics`](super::dynamics), no autopilot, no gusts) is integrated in RK4 steps of at most
//! [`REPLAY_STEP_S`]; one output record per input time stamp, the state *at* that time stamp
//! (before its deflections act). The front end parses the file; this module is the kernel.

use super::dynamics::{air_data, r_body_to_ned, Deltas, State12, WindSample};
use super::FixedWing;

/// The largest integration step of a replay, s.
pub const REPLAY_STEP_S: f64 = 0.01;

/// The most integration steps one replay takes: 1e8 steps of 0.01 s (about 12 days of flight,
/// a minute or two of CPU).
pub const MAX_REPLAY_STEPS: u64 = 100_000_000;

/// The largest control-surface deflection a replay accepts, rad: the autopilot's saturation
/// (Beard & McLain 2012, sec. 6.3: `delta_a_max = delta_e_max = 45 deg`; docs/FIXED-WING.md);
/// past it the linear aerodynamic coefficients are meaningless.
pub const MAX_DEFLECTION_RAD: f64 = core::f64::consts::FRAC_PI_4;

/// Whether `d` is a command the airframe model covers: each deflection within
/// +-[`MAX_DEFLECTION_RAD`], the throttle in `[0, 1]`; the error names the first input out of
/// range (`delta_e_rad`, `delta_a_rad`, `delta_r_rad`, `delta_t`).
pub fn check_deltas(d: &Deltas) -> Result<(), String> {
    for (name, v) in [
        ("delta_e_rad", d.elevator_rad),
        ("delta_a_rad", d.aileron_rad),
        ("delta_r_rad", d.rudder_rad),
    ] {
        if v.is_nan() || v.abs() > MAX_DEFLECTION_RAD {
            return Err(format!(
                "`{name}` = {v} rad is outside +-{MAX_DEFLECTION_RAD:.4} rad (45 deg, the surfaces' limit)"
            ));
        }
    }
    if !(0.0..=1.0).contains(&d.throttle) {
        return Err(format!(
            "`delta_t` = {} is outside [0, 1] (throttle fraction)",
            d.throttle
        ));
    }
    Ok(())
}

/// The columns of one replay record ([`record`]), in order.
pub const REPLAY_COLUMNS: [&str; 16] = [
    "t_s",
    "north_m",
    "east_m",
    "altitude_m",
    "airspeed_mps",
    "alpha_rad",
    "beta_rad",
    "roll_rad",
    "pitch_rad",
    "yaw_rad",
    "u_mps",
    "v_mps",
    "w_mps",
    "p_radps",
    "q_radps",
    "r_radps",
];

/// Why a replay stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum ReplayError {
    /// No input rows.
    Empty,
    /// The time stamps span more than [`MAX_REPLAY_STEPS`] steps of [`REPLAY_STEP_S`].
    TooLong {
        /// The span of the time stamps, s.
        span_s: f64,
    },
    /// The state became non-finite after the interval that starts at `t_s`.
    Diverged {
        /// The start of the interval after which the state was not finite, s.
        t_s: f64,
    },
}

impl core::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Empty => write!(f, "no input rows"),
            Self::TooLong { span_s } => write!(
                f,
                "the time stamps span {span_s:e} s: more than {MAX_REPLAY_STEPS} steps of {REPLAY_STEP_S} s ({:e} s); split the file",
                MAX_REPLAY_STEPS as f64 * REPLAY_STEP_S
            ),
            Self::Diverged { t_s } => write!(f, "the state diverged after t = {t_s} s"),
        }
    }
}

/// The output record of state `x` at time `t_s`, in [`REPLAY_COLUMNS`]' order: position (north,
/// east, altitude = -down), air data without wind, Euler angles, body velocities and rates.
pub fn record(t_s: f64, x: &State12) -> [f64; 16] {
    let r = r_body_to_ned(x[6], x[7], x[8]);
    let air = air_data(x, &WindSample::default(), &r);
    [
        t_s,
        x[0],
        x[1],
        -x[2],
        air.va_mps,
        air.alpha_rad,
        air.beta_rad,
        x[6],
        x[7],
        x[8],
        x[3],
        x[4],
        x[5],
        x[9],
        x[10],
        x[11],
    ]
}

/// Whether `rows` can be replayed: not empty, and their time stamps span at most
/// [`MAX_REPLAY_STEPS`] steps (checked before any output is created).
pub fn validate(rows: &[(f64, Deltas)]) -> Result<(), ReplayError> {
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        return Err(ReplayError::Empty);
    };
    let span_s = last.0 - first.0;
    if span_s / REPLAY_STEP_S > MAX_REPLAY_STEPS as f64 {
        return Err(ReplayError::TooLong { span_s });
    }
    Ok(())
}

/// Replays `rows` (time stamps strictly increasing, finite: the caller checks them) from state
/// `x`: calls `emit(record)` for each row's time stamp, then holds its deflections until the
/// next time stamp in `n = ceil(span / REPLAY_STEP_S)` equal steps. `emit`'s error stops the
/// replay and is returned as `Ok(Err(e))`; a replay error as `Err`.
pub fn replay<E>(
    uav: &FixedWing,
    mut x: State12,
    rows: &[(f64, Deltas)],
    mut emit: impl FnMut(&[f64; 16]) -> Result<(), E>,
) -> Result<Result<(), E>, ReplayError> {
    validate(rows)?;
    for (k, &(t, d)) in rows.iter().enumerate() {
        if let Err(e) = emit(&record(t, &x)) {
            return Ok(Err(e));
        }
        if let Some(&(t_next, _)) = rows.get(k + 1) {
            let span = t_next - t;
            let n = (span / REPLAY_STEP_S).ceil().max(1.0) as usize;
            let h = span / n as f64;
            for _ in 0..n {
                uav.step_open_loop(&mut x, &d, h);
            }
            if !x.iter().all(|v| v.is_finite()) {
                return Err(ReplayError::Diverged { t_s: t });
            }
        }
    }
    Ok(Ok(()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed_wing::trim::trim_state;
    use crate::FixedWingConfig;

    /// At trim with the trim deflections held the airframe flies straight and level at the trim
    /// airspeed (Beard & McLain 2012, sec. 5.3): after 10 s the altitude and airspeed are those
    /// of the trim to within the integration error, north advanced by V * t.
    #[test]
    fn trim_deflections_hold_level_flight() {
        let uav = FixedWing::new(FixedWingConfig::default()).unwrap();
        let trim = *uav.trim();
        let x0 = trim_state(&trim, 100.0, 0.0);
        let d = Deltas {
            elevator_rad: trim.delta_e_rad,
            aileron_rad: 0.0,
            rudder_rad: 0.0,
            throttle: trim.delta_t,
        };
        let rows = [(0.0, d), (10.0, d)];
        let mut out = Vec::new();
        replay(&uav, x0, &rows, |r| {
            out.push(*r);
            Ok::<(), ()>(())
        })
        .unwrap()
        .unwrap();
        assert_eq!(out.len(), 2);
        let last = out[1];
        assert_eq!(last[0], 10.0);
        assert!((last[3] - 100.0).abs() < 0.05, "altitude {}", last[3]);
        assert!(
            (last[4] - trim.airspeed_mps).abs() < 1e-3,
            "airspeed {}",
            last[4]
        );
        assert!(
            (last[1] - 10.0 * trim.airspeed_mps).abs() < 0.05,
            "north {}",
            last[1]
        );
    }

    /// The surfaces' limit is 45 deg and the throttle a fraction: at the bounds accepted, past
    /// them refused (a hostile review: `delta_e_rad = 100` flew a "valid" trajectory).
    #[test]
    fn deflections_and_throttle_within_their_limits() {
        let at = Deltas {
            elevator_rad: MAX_DEFLECTION_RAD,
            aileron_rad: -MAX_DEFLECTION_RAD,
            rudder_rad: 0.0,
            throttle: 1.0,
        };
        assert_eq!(check_deltas(&at), Ok(()));
        assert_eq!(
            check_deltas(&Deltas {
                throttle: 0.0,
                ..at
            }),
            Ok(())
        );
        let past = MAX_DEFLECTION_RAD + 1e-9;
        for (d, name) in [
            (
                Deltas {
                    elevator_rad: past,
                    ..at
                },
                "delta_e_rad",
            ),
            (
                Deltas {
                    aileron_rad: -past,
                    ..at
                },
                "delta_a_rad",
            ),
            (
                Deltas {
                    rudder_rad: 100.0,
                    ..at
                },
                "delta_r_rad",
            ),
            (
                Deltas {
                    throttle: -1e-12,
                    ..at
                },
                "delta_t",
            ),
            (
                Deltas {
                    throttle: 1.0 + 1e-12,
                    ..at
                },
                "delta_t",
            ),
        ] {
            let e = check_deltas(&d).unwrap_err();
            assert!(e.contains(name), "{e}");
        }
    }

    #[test]
    fn refuses_empty_and_too_long_inputs() {
        let uav = FixedWing::new(FixedWingConfig::default()).unwrap();
        let x0 = trim_state(uav.trim(), 100.0, 0.0);
        let ok = |_: &[f64; 16]| Ok::<(), ()>(());
        assert_eq!(replay(&uav, x0, &[], ok), Err(ReplayError::Empty));
        let d = Deltas::default();
        let rows = [(0.0, d), (1e12, d)];
        assert!(matches!(
            replay(&uav, x0, &rows, ok),
            Err(ReplayError::TooLong { .. })
        ));
    }
}
