//! The scenario file format.
//!
//! Every key is optional in a file; [`crate::resolve`] fills the defaults listed here and checks
//! that each key applies to the chosen `kind`. Units are in the key names. Coordinates: x east,
//! y north, headings counter-clockwise from +x, turn rates positive to the left.
//!
//! ```toml
//! [field]
//! kind = "radial_exp"          # radial_exp | gaussian_plumes | linear_ramp
//! i0 = 20.0                    # radial_exp: F = i0*exp(-decay_per_m*|p - center_m|)
//! decay_per_m = 0.1
//! center_m = [0.0, 0.0]
//! # domain_m = [-50, 50, -50, 50]   # optional [x_min, x_max, y_min, y_max]; outside: no value
//!
//! [vehicle]
//! kind = "dubins"
//! speed_mps = 0.5
//!
//! [initial]
//! x_m = 10.0
//! y_m = 0.0
//! heading_rad = 1.5707963267948966
//!
//! [sensor]
//! rate_hz = 100.0              # default: every step (1/sim.dt_s)
//! noise_std = 0.0              # field units
//! delay_s = 0.0
//!
//! [controller]
//! kind = "pi_isoline"
//! level = 10.0
//! kp = 10.0
//! ki = 1.0
//! c1 = 0.2
//! c2 = 1.0
//! higher_side = "right"        # right (paper: clockwise around a maximum) | left
//! # max_turn_rate_radps = 1.0  # optional |omega| limit
//! anti_windup = "none"         # none | clamp | conditional | back_calculation
//! derivative = "backward_difference"   # backward_difference | filtered_difference | levant
//!
//! [sim]
//! dt_s = 0.01
//! duration_s = 600.0
//! seed = 0
//!
//! [metrics]
//! steady_state_fraction = 0.2
//! convergence_tolerance = 0.1  # default: 1 % of |controller.level| (0.01 if the level is 0)
//! convergence_min_dwell_s = 60.0  # default: 10 % of sim.duration_s
//!
//! [output]
//! record_rate_hz = 10.0        # trace rows per second; 0 turns the trace off
//!
//! [sitl]                       # isotrack sitl: where local metres are on the Earth (WGS84)
//! home_lat_deg = 47.397742     # the local origin's latitude, deg (default: PX4's SITL home)
//! home_lon_deg = 8.545594      # its longitude, deg
//! home_alt_m = 488.0           # its altitude above mean sea level, m
//! ```

use serde::{Deserialize, Serialize};

/// A scenario file. Unknown keys are rejected everywhere.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioFile {
    /// Optional short name.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Optional free-text description.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// The scalar field.
    pub field: FieldSection,
    /// The vehicle.
    pub vehicle: VehicleSection,
    /// The initial state.
    pub initial: InitialSection,
    /// The sensor.
    pub sensor: SensorSection,
    /// The controller.
    pub controller: ControllerSection,
    /// Integration and run length.
    pub sim: SimSection,
    /// Metric settings.
    pub metrics: MetricsSection,
    /// Output settings.
    pub output: OutputSection,
    /// Where `isotrack sitl` puts the run on the Earth (written only when set).
    #[serde(skip_serializing_if = "SitlSection::is_unset")]
    pub sitl: SitlSection,
    /// A team of vehicles sharing the field and the clock (docs/TEAMS.md); absent: one vehicle,
    /// and nothing of a run changes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub team: Option<TeamSection>,
}

/// Field kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldKind {
    /// `F = i0*exp(-decay_per_m*|p - center_m|)` (the paper's circular field, eq. (4)).
    RadialExp,
    /// `F = background + sum_i amplitude_i*exp(-1/2 d_i^T S_i^-1 d_i)` over `sources`.
    GaussianPlumes,
    /// `F = offset + gradient_per_m . p`.
    LinearRamp,
    /// A gridded field read from `path`, interpolated.
    Grid,
    /// Scattered station values (`path`, a CSV) interpolated onto a grid (IDW or ordinary
    /// kriging), then interpolated like a `grid`.
    Stations,
    /// Puffs released at a source, carried by a meandering wind, growing by diffusion (after
    /// Farrell et al. 2002, simplified: 2-D, one spatially uniform wind for every puff, no
    /// centre-relative dispersion; see `isotrack_fields::puff`).
    PuffPlume,
}

/// Station interpolation methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StationMethod {
    /// Ordinary kriging with a fitted variogram.
    Kriging,
    /// Inverse-distance weighting.
    Idw,
}

/// Grid file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GridFormatName {
    /// CSV, no header, row 0 = south.
    Csv,
    /// NumPy `.npy`.
    Npy,
    /// ESRI ASCII grid.
    Asc,
    /// GeoTIFF.
    Geotiff,
    /// NetCDF (CF); needs the `netcdf` feature.
    Netcdf,
}

/// Grid interpolation schemes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InterpolationName {
    /// Bilinear (C0).
    Bilinear,
    /// Catmull-Rom bicubic (C1).
    Bicubic,
}

/// Interpolation between the frames of a time series (`field.time_interpolation`; default
/// [`crate::spec::field::TIME_INTERPOLATION`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeInterpolationName {
    /// The frame nearest in time.
    Nearest,
    /// Linear between the two frames around the time.
    Linear,
    /// Catmull-Rom over four frames.
    Cubic,
}

/// What a time series does past its last frame (`field.after_last_frame`; default
/// [`crate::spec::field::AFTER_LAST_FRAME`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AfterLastFrameName {
    /// The last frame holds.
    Hold,
    /// The field ends: outcome `left_field`, the detail says the data ended.
    End,
}

/// `[field]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FieldSection {
    /// Field kind (default `radial_exp`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<FieldKind>,
    /// Any kind: the field's units, for figure labels (e.g. `"ug/m^3"`; default none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub units: Option<String>,
    /// `radial_exp`: peak value (default 20).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub i0: Option<f64>,
    /// `radial_exp`: decay rate, 1/m (default 0.1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub decay_per_m: Option<f64>,
    /// `radial_exp`: source position, m (default `[0, 0]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub center_m: Option<[f64; 2]>,
    /// `gaussian_plumes`: background level (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub background: Option<f64>,
    /// `gaussian_plumes`: the sources (default: a three-source PM2.5-like map).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sources: Option<Vec<PlumeSpec>>,
    /// `linear_ramp`: value at the origin (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset: Option<f64>,
    /// `linear_ramp`: gradient, field units per metre (default `[0, 1]`: increasing northward).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gradient_per_m: Option<[f64; 2]>,
    /// Analytic kinds: optional domain `[x_min, x_max, y_min, y_max]`, m; outside it the field
    /// has no value and a run ends as `left_field`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub domain_m: Option<[f64; 4]>,
    /// Analytic kinds: the pattern's constant drift `[vx, vy]`, m/s: `F(t, p) = F0(p - v t)`, a
    /// time-varying field (default `[0, 0]`). The isoline-distance metric follows the moving
    /// isoline; `isotrack check` analyses the field at t = 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drift_mps: Option<[f64; 2]>,
    /// `grid`: the file, relative to the scenario file (the resolved scenario records it
    /// absolute).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<String>,
    /// `grid`: `csv`, `npy`, `asc`, `geotiff` or `netcdf` (default: from the extension).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub format: Option<GridFormatName>,
    /// `stations`: the value column of the CSV (required).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_column: Option<String>,
    /// `stations`: `kriging` (default) or `idw`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<StationMethod>,
    /// `stations`, `idw`: the power (default 2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub idw_power: Option<f64>,
    /// `stations`: spacing of the grid the stations are interpolated onto, in the stations'
    /// metres (default: 1/100 of the larger side of their bounding box).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid_spacing_m: Option<f64>,
    /// `grid`, NetCDF: the variable to read (default: the first 2-D data variable).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub variable: Option<String>,
    /// `grid`: node spacing `[dx, dy]`, m, overriding the file's georeference (default: the
    /// file's, or 1 m when it has none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spacing_m: Option<[f64; 2]>,
    /// `grid`: position of the south-west node (after cropping), m, overriding the file's
    /// georeference (default: the file's, or `[0, 0]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub origin_m: Option<[f64; 2]>,
    /// `grid`: `bilinear` or `bicubic` (default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interpolation: Option<InterpolationName>,
    /// `grid`: keep only columns `c0..=c1` and rows `r0..=r1`: `[c0, c1, r0, r1]` (row 0 south).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crop_cells: Option<[usize; 4]>,
    /// `grid`: raise values below this floor to it before the transform (e.g. the zeros of a
    /// plume before `value_log10`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_floor: Option<f64>,
    /// `grid`: take `log10` of the (floored) values (default false).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_log10: Option<bool>,
    /// `grid`: multiply by this after the log (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_scale: Option<f64>,
    /// `grid`: then add this (default 0). The transform is
    /// `v -> value_scale * [log10](max(v, value_floor)) + value_offset`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub value_offset: Option<f64>,
    /// `puff_plume`: source position, m (default [0, 0]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source_m: Option<[f64; 2]>,
    /// `puff_plume`: puffs released per second (default 2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub release_rate_hz: Option<f64>,
    /// `puff_plume`: mass of a puff, field units x m^2 (default 10).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub puff_mass: Option<f64>,
    /// `puff_plume`: initial puff width, m (default 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub puff_sigma0_m: Option<f64>,
    /// `puff_plume`: diffusivity, m^2/s (default 0.05).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub diffusivity_m2ps: Option<f64>,
    /// `puff_plume`: mean wind `[east, north]`, m/s (default [0.5, 0]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wind_mps: Option<[f64; 2]>,
    /// `puff_plume`: meander standard deviation per component, m/s (default 0.1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub meander_std_mps: Option<f64>,
    /// `puff_plume`: meander correlation time, s (default 20).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub meander_correlation_s: Option<f64>,
    /// `puff_plume`: puffs older than this are dropped, s (default 120).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_age_s: Option<f64>,
    /// `grid`: a time series as a list of 2-D files, one frame each (instead of `path`),
    /// relative to the scenario file; needs `frame_times_s`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paths: Option<Vec<String>>,
    /// `grid`: the frame times, s (field time, strictly increasing): one per file of `paths`,
    /// or one per frame of a 3-D `.npy` / NetCDF (replacing the file's own times).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_times_s: Option<Vec<f64>>,
    /// `grid`: frames this many seconds apart, from 0 (for a 3-D `.npy`, which has no times).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frame_interval_s: Option<f64>,
    /// `grid` time series: `nearest`, `linear` (default) or `cubic` between frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_interpolation: Option<TimeInterpolationName>,
    /// `grid` time series: the field time at run time 0, s after the first frame (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_origin_s: Option<f64>,
    /// `grid` time series: seconds of field time per second of run time (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_scale: Option<f64>,
    /// `grid` time series: `hold` (default) or `end` past the last frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub after_last_frame: Option<AfterLastFrameName>,
}

/// One Gaussian source of a `gaussian_plumes` field.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlumeSpec {
    /// Centre, m.
    pub center_m: [f64; 2],
    /// Peak amplitude above the background.
    pub amplitude: f64,
    /// Standard deviations along the plume's axes, m.
    pub sigma_m: [f64; 2],
    /// Rotation of the first axis from +x, rad (default 0).
    #[serde(default)]
    pub rotation_rad: f64,
}

/// Vehicle kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VehicleKind {
    /// The Dubins robot of the paper, eq. (5).
    Dubins,
    /// The Aerosonde 6-DOF UAV with Beard & McLain's autopilot (paper Sec. VI-C).
    FixedWing,
}

/// `[vehicle]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct VehicleSection {
    /// Vehicle kind (default `dubins`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<VehicleKind>,
    /// `dubins`: constant speed, m/s (default 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed_mps: Option<f64>,
    /// `fixed_wing`: commanded and trim airspeed, m/s (default 30).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub airspeed_mps: Option<f64>,
    /// `fixed_wing`: commanded altitude, m (default 100).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub altitude_m: Option<f64>,
    /// `fixed_wing`: steady wind `[east, north]`, m/s (default `[0, 0]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wind_mps: Option<[f64; 2]>,
    /// `fixed_wing`: Dryden gusts, seeded by `sim.seed` (default false).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gusts: Option<bool>,
    /// `fixed_wing`: trim feed-forward in the autopilot (default true; false is the 2012 code).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trim_feedforward: Option<bool>,
    /// `fixed_wing`: the 2012 code's airspeed-gain formula (`C_L,delta_e` in `a_V1`; default
    /// false, the book's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ecen674_gains: Option<bool>,
}

/// `[initial]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct InitialSection {
    /// East position, m (default 10).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_m: Option<f64>,
    /// North position, m (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub y_m: Option<f64>,
    /// Heading, rad counter-clockwise from +x (default -pi/2: south).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_rad: Option<f64>,
}

/// `[sensor]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorSection {
    /// Sampling rate, Hz (default: every step, `1/sim.dt_s`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_hz: Option<f64>,
    /// Standard deviation of additive Gaussian noise, field units (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_std: Option<f64>,
    /// Transport delay, s (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delay_s: Option<f64>,
    /// First-order response time constant, s (default 0: instantaneous).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_constant_s: Option<f64>,
    /// Output range `[min, max]`, field units: readings saturate (default none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range: Option<[f64; 2]>,
    /// Output resolution, field units: readings are rounded to it (default 0: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resolution: Option<f64>,
    /// Probability a sample is lost, in [0, 1) (default 0); counted in `samples_dropped`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dropout_probability: Option<f64>,
    /// Bias random walk, field units per sqrt(s) (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bias_drift_per_sqrt_s: Option<f64>,
}

/// Controller kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// Dong & You's PI-like law, eqs. (2)-(3).
    PiIsoline,
    /// Matveev et al.'s sliding mode `u_max*sgn(s' + chi(s - s0))` (reconstructed).
    SlidingMode,
    /// The same with a boundary layer (continuous; not the paper's law).
    SlidingModeSmooth,
    /// Bartolini-type suboptimal second-order sliding mode (Mellucci et al.; reconstructed).
    SuboptimalSosm,
    /// Linear PID on `eps` (ablation of the PI-like law).
    Pid,
    /// PID with adaptive crossing-angle correction (Newaz et al.; reconstruction).
    PidCrossing,
    /// Guiding vector field with true position and gradient: NOT coordinate-free (reference).
    GradientReference,
    /// Piecewise-constant turn rate from `course_rate_radps`, ignoring measurements.
    Schedule,
}

impl ControllerKind {
    /// Every kind, in the order `compare` runs them.
    pub const ALL: [ControllerKind; 7] = [
        // (`schedule` is not a tracking law, so it is not in the comparison set.)
        ControllerKind::PiIsoline,
        ControllerKind::SlidingMode,
        ControllerKind::SlidingModeSmooth,
        ControllerKind::SuboptimalSosm,
        ControllerKind::Pid,
        ControllerKind::PidCrossing,
        ControllerKind::GradientReference,
    ];
    /// The snake_case name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::PiIsoline => "pi_isoline",
            ControllerKind::SlidingMode => "sliding_mode",
            ControllerKind::SlidingModeSmooth => "sliding_mode_smooth",
            ControllerKind::SuboptimalSosm => "suboptimal_sosm",
            ControllerKind::Pid => "pid",
            ControllerKind::PidCrossing => "pid_crossing",
            ControllerKind::GradientReference => "gradient_reference",
            ControllerKind::Schedule => "schedule",
        }
    }
    /// The kind of a name (the comparison set only).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Anti-windup schemes (see `isotrack_core::control::AntiWindup`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AntiWindupKind {
    /// Integrate always (the paper).
    None,
    /// `|ki*sigma| <= integral_limit_radps`.
    Clamp,
    /// Integrate only while `|eps| < integral_band`.
    Conditional,
    /// `sigma' = e + (u_sat - u)/(ki*tracking_time_s)` against `max_turn_rate_radps`.
    BackCalculation,
}

/// Derivative estimators (see `isotrack_core::estimate`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DerivativeKindName {
    /// Backward difference.
    BackwardDifference,
    /// Low-pass filtered backward difference (`derivative_tau_s`).
    FilteredDifference,
    /// Levant's robust exact differentiator (`derivative_lipschitz`).
    Levant,
}

/// Search patterns flown before tracking (`controller.search`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SearchKind {
    /// No search: the tracking law from the start (default).
    #[default]
    None,
    /// An Archimedean spiral, arms `search_spacing_m` apart.
    Spiral,
    /// A lawnmower: legs of `search_leg_m`, `search_spacing_m` apart.
    Lawnmower,
}

/// `[controller]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControllerSection {
    /// Controller kind (default `pi_isoline`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<ControllerKind>,
    /// Desired level `s_d`, field units (default 10).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<f64>,
    /// `pi_isoline`: `kp > 0` (default 10). `pid`, `pid_crossing`: the gain on `eps` (default 3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kp: Option<f64>,
    /// `pi_isoline`: `ki >= 0` (default 1). `pid`, `pid_crossing`: the integral gain (default 0.2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ki: Option<f64>,
    /// `pid`, `pid_crossing`: the gain on `eps'` (default 10). The PID defaults are the
    /// linearisation of the default PI-like law (`kd = kp`, `kp = kp*c1/c2 + ki`, `ki = ki*c1/c2`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kd: Option<f64>,
    /// `sliding_mode(_smooth)`: slope of `chi`, 1/s (default 0.2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gamma: Option<f64>,
    /// `sliding_mode(_smooth)`: linear zone of `chi`, field units (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta: Option<f64>,
    /// `sliding_mode_smooth`: boundary-layer width, field units per second (default 0.05).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub boundary_layer: Option<f64>,
    /// `suboptimal_sosm`: modulation factor `alpha*` in (0, 1] (default 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_star: Option<f64>,
    /// `pid_crossing`: initial crossing angle, rad (default 0.3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crossing_angle_rad: Option<f64>,
    /// `pid_crossing`: target time between crossings, s (default 20).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crossing_period_s: Option<f64>,
    /// `pid_crossing`: turn rate of the crossing turn, rad/s (default `max_turn_rate_radps` or
    /// 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub crossing_turn_rate_radps: Option<f64>,
    /// `gradient_reference`: gain on the distance estimate, 1/m (default 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ke: Option<f64>,
    /// `gradient_reference`: heading gain, 1/s (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_heading: Option<f64>,
    /// `schedule`: `[[t0, w0], [t1, w1], ...]`: turn rate `w_i` (rad/s) from time `t_i` (s) on,
    /// times increasing; zero before `t0`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub course_rate_radps: Option<Vec<[f64; 2]>>,
    /// `c1 > 0`, field units per second (default 0.2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c1: Option<f64>,
    /// `c2 > 0`, field units (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub c2: Option<f64>,
    /// Which side the higher values lie on: `right` (default; the paper) or `left`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub higher_side: Option<isotrack_core::control::HigherSide>,
    /// Turn-rate limit `|omega| <= max_turn_rate_radps`, rad/s: optional for the continuous laws;
    /// the amplitude `u_max` / `U` of `sliding_mode(_smooth)` and `suboptimal_sosm` (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_turn_rate_radps: Option<f64>,
    /// Anti-windup scheme (default `none`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub anti_windup: Option<AntiWindupKind>,
    /// `clamp`: bound on `|ki*sigma|`, rad/s (default: `max_turn_rate_radps` if set, else
    /// `kp*c1`, the proportional term's own reach).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integral_limit_radps: Option<f64>,
    /// `conditional`: integrate while `|eps| < integral_band`, field units (default `c2`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub integral_band: Option<f64>,
    /// `back_calculation`: tracking time constant, s (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tracking_time_s: Option<f64>,
    /// Derivative estimator for `eps'` (default `backward_difference`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub derivative: Option<DerivativeKindName>,
    /// `filtered_difference`: filter time constant, s (default 0.1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub derivative_tau_s: Option<f64>,
    /// `levant`: bound `L` on `|s''|`, field units/s^2 (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub derivative_lipschitz: Option<f64>,
    /// A search pattern flown before tracking, any controller (default `none`): it hands over
    /// once the measurement has moved by `search_handover` from its first sample.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search: Option<SearchKind>,
    /// Spiral arm spacing or lawnmower leg spacing, m (default: the minimum turning diameter
    /// `2*v/omega_max`, `omega_max` the turn-rate limit or 1 rad/s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_spacing_m: Option<f64>,
    /// `lawnmower`: leg length, m (default 10 x the spacing).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_leg_m: Option<f64>,
    /// Hand over once `|s - s_first| >= search_handover`, field units (default 1 % of
    /// `|level|`, or 0.01 for level 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search_handover: Option<f64>,
}

impl ControllerSection {
    /// The section for another kind: unchanged when it already is `kind`; otherwise the kind's
    /// defaults with the keys every law shares carried over (level, turning side, turn-rate
    /// limit, the search phase flown before tracking (`search`, `search_spacing_m`,
    /// `search_leg_m`, `search_handover`), and, for the laws that differentiate the
    /// measurement, the derivative estimator). A gain of one law (`kp` of the PI-like law, say)
    /// is not the same gain of another (`kp` of the PID), so none is carried. Used by `compare`
    /// and the benchmark: every law flies the same search (without it, from a start on a flat
    /// background, only the law given one would ever find the isoline).
    pub fn switched_to(&self, kind: ControllerKind) -> ControllerSection {
        if self.kind == Some(kind) {
            return self.clone();
        }
        let takes_derivative = !matches!(
            kind,
            ControllerKind::GradientReference | ControllerKind::Schedule
        );
        ControllerSection {
            kind: Some(kind),
            level: self.level,
            higher_side: self.higher_side,
            max_turn_rate_radps: self.max_turn_rate_radps,
            derivative: self.derivative.filter(|_| takes_derivative),
            derivative_tau_s: self.derivative_tau_s.filter(|_| takes_derivative),
            derivative_lipschitz: self.derivative_lipschitz.filter(|_| takes_derivative),
            search: self.search,
            search_spacing_m: self.search_spacing_m,
            search_leg_m: self.search_leg_m,
            search_handover: self.search_handover,
            ..ControllerSection::default()
        }
    }
}

/// `[sim]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimSection {
    /// Integration step, s (default 0.01).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dt_s: Option<f64>,
    /// Run length, s (default 600); a whole number of steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    /// Seed of the run's random streams (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// `[metrics]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MetricsSection {
    /// Fraction of the planned duration, at its end, that forms the steady-state window
    /// (default 0.2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steady_state_fraction: Option<f64>,
    /// Tolerance on `|eps|` for the convergence time, field units (default 1 % of
    /// `|controller.level|`, or 0.01 if the level is 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub convergence_tolerance: Option<f64>,
    /// How long the error must stay within the tolerance, up to the end of the run, for a
    /// convergence time to be reported, s (default 10 % of `sim.duration_s`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub convergence_min_dwell_s: Option<f64>,
    /// The track-loss band on `|eps|`, field units: once within the tolerance, leaving this
    /// band counts as a track loss (default 5 x the tolerance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub track_loss_band: Option<f64>,
}

/// `[output]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSection {
    /// Trace rows per second (default 10); 0 turns the trace off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record_rate_hz: Option<f64>,
}

/// `[sitl]`: the home position of `isotrack sitl`, the point on the Earth where the local origin
/// `(x, y) = (0, 0)` is (the MAVLink messages carry WGS84 latitude, longitude and altitude).
/// Defaults (PX4's SITL home, Zurich): 47.397742 deg, 8.545594 deg, 488 m. Not filled into the
/// resolved file (a run that never flies over MAVLink does not need them).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SitlSection {
    /// Latitude of the local origin, deg, in [-89, 89] (default 47.397742).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub home_lat_deg: Option<f64>,
    /// Longitude of the local origin, deg, in [-180, 180] (default 8.545594).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub home_lon_deg: Option<f64>,
    /// Altitude of the local origin above mean sea level, m, in [-1000, 10000] (default 488).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub home_alt_m: Option<f64>,
}

impl SitlSection {
    /// Default home latitude, deg (PX4's SITL home).
    pub const DEFAULT_HOME_LAT_DEG: f64 = 47.397742;
    /// Default home longitude, deg.
    pub const DEFAULT_HOME_LON_DEG: f64 = 8.545594;
    /// Default home altitude above mean sea level, m.
    pub const DEFAULT_HOME_ALT_M: f64 = 488.0;

    /// Whether no key of the section is set (it is then left out of the resolved file).
    pub fn is_unset(&self) -> bool {
        *self == SitlSection::default()
    }
    /// The home latitude, deg.
    pub fn home_lat_deg(&self) -> f64 {
        self.home_lat_deg.unwrap_or(Self::DEFAULT_HOME_LAT_DEG)
    }
    /// The home longitude, deg.
    pub fn home_lon_deg(&self) -> f64 {
        self.home_lon_deg.unwrap_or(Self::DEFAULT_HOME_LON_DEG)
    }
    /// The home altitude above mean sea level, m.
    pub fn home_alt_m(&self) -> f64 {
        self.home_alt_m.unwrap_or(Self::DEFAULT_HOME_ALT_M)
    }
}

/// `[team]`: several vehicles on one isoline, spread by a spacing law (docs/TEAMS.md). Every
/// key has a default (`crate::spec::team`); the starts are `starts` or `spread`, exactly one.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TeamSection {
    /// Number of vehicles, 1 to `spec::team::MAX_COUNT`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub count: Option<u64>,
    /// One start pose per vehicle, in the order of travel along the isoline (the listed ring).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub starts: Option<Vec<InitialSection>>,
    /// The starts spread along an arc or a line.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spread: Option<TeamSpread>,
    /// The spacing law: `none`, `range_balance` (coordinate-free) or `arc_reference` (the
    /// true arc gaps: a reference, not coordinate-free). Default `range_balance`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spacing: Option<SpacingName>,
    /// The spacing gain `k_v`, 1/s (default [`crate::spec::team::K_V_PER_S`], 0.1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k_v: Option<f64>,
    /// Slowest speed the law may command, m/s (default half of `vehicle.speed_mps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_min_mps: Option<f64>,
    /// Fastest speed the law may command, m/s (default twice `vehicle.speed_mps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_max_mps: Option<f64>,
    /// How each vehicle knows its neighbours: `listed` (the listed order is the order of
    /// travel) or `discovered` (from ranges and range rates after deployment). Default `listed`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ring: Option<RingName>,
    /// Neighbour ranging.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranging: Option<TeamRangingSection>,
    /// Per-vehicle overrides (`[[team.vehicles]]`, each naming its vehicle by `index`): a
    /// vehicle's own nominal speed, envelope and sensor noise and rate.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vehicles: Option<Vec<TeamVehicleSection>>,
}

/// `[[team.vehicles]]`: one vehicle's own settings, where they make sense for one member of a
/// team sharing one vehicle model, tracking law, field and ranging (docs/TEAMS.md, "Per-vehicle
/// overrides"). Any other key is refused by name.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TeamVehicleSection {
    /// The vehicle, `0..team.count` in the listed order (required; each at most once).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index: Option<u64>,
    /// A Dubins robot's nominal speed `v0_i`, m/s (default `vehicle.speed_mps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed_mps: Option<f64>,
    /// A fixed-wing UAV's nominal airspeed command `v0_i`, m/s, within the Aerosonde's safe
    /// commanded range (default `vehicle.airspeed_mps`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub airspeed_mps: Option<f64>,
    /// Its slowest command, m/s (default `team.v_min_mps` if given, else the team's default
    /// rule at `v0_i`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_min_mps: Option<f64>,
    /// Its fastest command, m/s (default `team.v_max_mps` if given, else the team's default
    /// rule at `v0_i`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub v_max_mps: Option<f64>,
    /// Its sensor's noise standard deviation, field units (default `sensor.noise_std`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_noise_std: Option<f64>,
    /// Its sensor's sampling rate, Hz, a whole number of steps per sample (default
    /// `sensor.rate_hz`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_rate_hz: Option<f64>,
}

/// `team.spread`: `count` starts along an arc (`center_m`, `radius_m`, the first at
/// `start_rad`, the next `step_rad` further counter-clockwise, each heading along the circle,
/// clockwise when `clockwise`) or a line (the first at `x_m, y_m`, the next `step_m` further
/// along `direction_rad`, all heading `heading_rad`).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TeamSpread {
    /// `arc` or `line`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub along: Option<SpreadAlong>,
    /// `arc`: centre, m (default `[0, 0]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub center_m: Option<[f64; 2]>,
    /// `arc`: radius, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius_m: Option<f64>,
    /// `arc`: angle of the first start, rad counter-clockwise from +x (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub start_rad: Option<f64>,
    /// `arc`: angle between consecutive starts, rad (default `2 pi/count`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step_rad: Option<f64>,
    /// `arc`: travel clockwise (default true, the paper's direction around a maximum).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clockwise: Option<bool>,
    /// `line`: first start, m (default `initial.x_m`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub x_m: Option<f64>,
    /// `line`: first start, m (default `initial.y_m`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub y_m: Option<f64>,
    /// `line`: every vehicle's heading, rad (default `initial.heading_rad`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_rad: Option<f64>,
    /// `line`: distance between consecutive starts, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub step_m: Option<f64>,
    /// `line`: direction of the line, rad (default: `heading_rad` + pi, behind each other).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction_rad: Option<f64>,
}

/// `team.spread.along`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpreadAlong {
    /// Along a circular arc.
    Arc,
    /// Along a straight line.
    Line,
}

/// `team.spacing`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpacingName {
    /// Every vehicle at the nominal speed.
    None,
    /// `v0 + k_v (r_ahead - r_behind)` from ranges (coordinate-free).
    RangeBalance,
    /// The same law on the true arc gaps (a reference, not coordinate-free).
    ArcReference,
}

/// `team.ring`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RingName {
    /// The listed order is the order of travel.
    Listed,
    /// Found from ranges and range rates after deployment.
    Discovered,
}

/// `team.ranging`: each vehicle ranges its two ring neighbours (e.g. UWB two-way ranging).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct TeamRangingSection {
    /// Ranging rate, Hz (default 10; its period a whole number of steps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_hz: Option<f64>,
    /// Standard deviation of the range noise, m (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_std_m: Option<f64>,
    /// Beyond this distance a neighbour does not answer, m (default: no limit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_range_m: Option<f64>,
    /// Probability a range is lost, in [0, 1] (default 0).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dropout_probability: Option<f64>,
    /// Delivery delay, s (default 0; a whole number of steps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delay_s: Option<f64>,
}
