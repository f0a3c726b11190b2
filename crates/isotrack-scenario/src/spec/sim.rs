//! `[sim]`, `[metrics]`, `[output]`, `[initial]` and `[sitl]`.

use super::settled;
use crate::issue::Issue;
use crate::schema::{InitialSection, MetricsSection, OutputSection, SimSection, SitlSection};

/// Default `sim.dt_s`, s.
pub const DT_S: f64 = 0.01;
/// Default `sim.duration_s`, s (the paper's Fig. 2(b) runs 600 s).
pub const DURATION_S: f64 = 600.0;
/// Default `sim.seed`.
pub const SEED: u64 = 0;
/// Default `metrics.steady_state_fraction`: the last 20 % of the run.
pub const STEADY_STATE_FRACTION: f64 = 0.2;
/// Default `metrics.convergence_min_dwell_s` as a fraction of `sim.duration_s` (10 %).
pub const DWELL_FRACTION: f64 = 0.1;
/// Default `metrics.track_loss_band` in convergence tolerances (5x), as
/// [`isotrack_sim::StepPlan::new`] sets it.
pub const TRACK_LOSS_BAND_TOLERANCES: f64 = 5.0;
/// Default `output.record_rate_hz`: ten trace rows a second.
pub const RECORD_RATE_HZ: f64 = 10.0;
/// Default `initial.x_m`, m (the paper's Fig. 2(b) start).
pub const START_X_M: f64 = 10.0;
/// Default `initial.y_m`, m.
pub const START_Y_M: f64 = 0.0;
/// Default `initial.heading_rad`: -pi/2 (south), rad counter-clockwise from +x.
pub const START_HEADING_RAD: f64 = -std::f64::consts::FRAC_PI_2;

/// Where and how a run starts: position, m, and heading, rad (counter-clockwise from +x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Start {
    /// Start position x, m.
    pub x_m: f64,
    /// Start position y, m.
    pub y_m: f64,
    /// Start heading, rad.
    pub heading_rad: f64,
}

/// `[sim]` resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimSpec {
    /// Integration step, s.
    pub dt_s: f64,
    /// Run length, s (a whole number of steps).
    pub duration_s: f64,
    /// Seed of the run's random streams.
    pub seed: u64,
}

impl SimSpec {
    /// From a resolved `[sim]`.
    pub fn new(s: &SimSection) -> Result<Self, Issue> {
        Ok(Self {
            dt_s: settled(&s.dt_s, "sim.dt_s")?,
            duration_s: settled(&s.duration_s, "sim.duration_s")?,
            seed: settled(&s.seed, "sim.seed")?,
        })
    }
}

/// `[metrics]` resolved, the derived defaults applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricsSpec {
    /// The steady-state window's share of the run, at its end.
    pub steady_state_fraction: f64,
    /// Tolerance on `|eps|` for the convergence time, field units.
    pub convergence_tolerance: f64,
    /// How long `|eps|` must stay within the tolerance, s: given, or [`DWELL_FRACTION`] of the
    /// duration (derived: not written into the resolved file, so it follows a swept duration).
    pub convergence_min_dwell_s: f64,
    /// The track-loss band on `|eps|`, field units: given, or
    /// [`TRACK_LOSS_BAND_TOLERANCES`] tolerances (derived).
    pub track_loss_band: f64,
}

impl MetricsSpec {
    /// From a resolved `[metrics]` and the resolved `[sim]`.
    pub fn new(m: &MetricsSection, sim: &SimSpec) -> Result<Self, Issue> {
        let tol = settled(&m.convergence_tolerance, "metrics.convergence_tolerance")?;
        Ok(Self {
            steady_state_fraction: settled(
                &m.steady_state_fraction,
                "metrics.steady_state_fraction",
            )?,
            convergence_tolerance: tol,
            convergence_min_dwell_s: m
                .convergence_min_dwell_s
                .unwrap_or(DWELL_FRACTION * sim.duration_s),
            track_loss_band: m
                .track_loss_band
                .unwrap_or(TRACK_LOSS_BAND_TOLERANCES * tol),
        })
    }
}

/// `[output]` resolved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputSpec {
    /// Trace rows per second; 0: no trace.
    pub record_rate_hz: f64,
}

impl OutputSpec {
    /// From a resolved `[output]`.
    pub fn new(o: &OutputSection) -> Result<Self, Issue> {
        Ok(Self {
            record_rate_hz: settled(&o.record_rate_hz, "output.record_rate_hz")?,
        })
    }
}

/// The start pose of a resolved `[initial]`.
pub fn start(i: &InitialSection) -> Result<Start, Issue> {
    Ok(Start {
        x_m: settled(&i.x_m, "initial.x_m")?,
        y_m: settled(&i.y_m, "initial.y_m")?,
        heading_rad: settled(&i.heading_rad, "initial.heading_rad")?,
    })
}

/// `[sitl]` with its defaults ([`SitlSection`]'s constants: PX4's SITL home). Not written into
/// the resolved file (a run that never flies over MAVLink does not need them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SitlSpec {
    /// Latitude of the local origin, deg.
    pub home_lat_deg: f64,
    /// Longitude of the local origin, deg.
    pub home_lon_deg: f64,
    /// Altitude of the local origin above mean sea level, m.
    pub home_alt_m: f64,
}

impl SitlSpec {
    /// From a resolved `[sitl]`.
    pub fn new(s: &SitlSection) -> Self {
        Self {
            home_lat_deg: s.home_lat_deg(),
            home_lon_deg: s.home_lon_deg(),
            home_alt_m: s.home_alt_m(),
        }
    }
}
