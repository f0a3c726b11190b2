//! `[field]`: the kind with its own typed parameters, every default written once here.
//!
//! [`crate::resolve::resolve`] writes each default below into the resolved file (so that
//! `scenario.toml` records it); [`FieldSpec::new`] reads the resolved file. A grid's or the
//! stations' files then fill the keys they provide and the scenario leaves unset (the node
//! spacing and origin, the stations' grid spacing, the values' units): [`crate::field::build_field`]
//! reads the spec built before the files, returns what they filled
//! ([`crate::field::FileFilled`]), which is recorded into the resolved file, and the scenario's
//! spec ([`crate::Scenario::spec`]) is read from that file: there every such key is `Some`.
//!
//! One default is not written into the resolved file: an analytic field's drift
//! [`DRIFT_MPS`] (a steady field's `scenario.toml` carries no `drift_mps`); `isotrack show`
//! prints it as a commented-out key.

use super::settled;
use crate::issue::Issue;
use crate::schema::{
    AfterLastFrameName, FieldKind, FieldSection, GridFormatName, InterpolationName, PlumeSpec,
    StationMethod, TimeInterpolationName,
};
use isotrack_core::math::Vec2;
use isotrack_fields::grid::{AfterLastFrame, Interpolation, TimeInterpolation};
use isotrack_fields::io::GridFormat;
use isotrack_fields::puff::PuffPlumeParams;
use isotrack_fields::{AnalyticField, AnalyticKind, GaussianPlumes, LinearRamp, Plume, RadialExp};

/// Default `field.kind`: the paper's circular field `radial_exp` (Dong & You, eq. (4)).
pub const KIND: FieldKind = FieldKind::RadialExp;
/// Default `field.i0` of `radial_exp`, field units: the paper's Fig. 2(b) peak.
pub const RADIAL_I0: f64 = 20.0;
/// Default `field.decay_per_m` of `radial_exp`, 1/m (the paper's Fig. 2(b)).
pub const RADIAL_DECAY_PER_M: f64 = 0.1;
/// Default `field.center_m` of `radial_exp`, m: the origin.
pub const RADIAL_CENTER_M: [f64; 2] = [0.0, 0.0];
/// Default `field.background` of `gaussian_plumes` and `puff_plume`, field units.
pub const BACKGROUND: f64 = 0.0;
/// Default `field.offset` of `linear_ramp`, field units.
pub const RAMP_OFFSET: f64 = 0.0;
/// Default `field.gradient_per_m` of `linear_ramp`, field units per metre: increasing northward.
pub const RAMP_GRADIENT_PER_M: [f64; 2] = [0.0, 1.0];
/// Drift of an analytic field without `field.drift_mps`, m/s: none (a steady field). Not
/// written into the resolved file (applied by [`FieldSpec::new`]).
pub const DRIFT_MPS: [f64; 2] = [0.0, 0.0];
/// Default `field.interpolation` of `grid` and `stations`: Catmull-Rom bicubic (C1, so the
/// gradient the laws and the check use is continuous).
pub const INTERPOLATION: InterpolationName = InterpolationName::Bicubic;
/// Default `field.value_log10` of `grid`: values as the file gives them.
pub const VALUE_LOG10: bool = false;
/// Default `field.value_scale` of `grid`.
pub const VALUE_SCALE: f64 = 1.0;
/// Default `field.value_offset` of `grid`, field units.
pub const VALUE_OFFSET: f64 = 0.0;
/// Default `field.time_interpolation` of a `grid` time series: linear between frames.
pub const TIME_INTERPOLATION: TimeInterpolationName = TimeInterpolationName::Linear;
/// Default `field.time_origin_s` of a `grid` time series, s after the first frame.
pub const TIME_ORIGIN_S: f64 = 0.0;
/// Default `field.time_scale` of a `grid` time series: field time runs as run time.
pub const TIME_SCALE: f64 = 1.0;
/// Default `field.after_last_frame` of a `grid` time series: the last frame holds.
pub const AFTER_LAST_FRAME: AfterLastFrameName = AfterLastFrameName::Hold;
/// Default `field.method` of `stations`: ordinary kriging with a fitted variogram.
pub const STATIONS_METHOD: StationMethod = StationMethod::Kriging;
/// Default `field.idw_power` of `stations` with `method = "idw"` (Shepard's classic power).
pub const IDW_POWER: f64 = 2.0;
/// Default `field.source_m` of `puff_plume`, m.
pub const PUFF_SOURCE_M: [f64; 2] = [0.0, 0.0];
/// Default `field.release_rate_hz` of `puff_plume`: puffs per second.
pub const PUFF_RELEASE_RATE_HZ: f64 = 2.0;
/// Default `field.puff_mass` of `puff_plume`, field units x m^2.
pub const PUFF_MASS: f64 = 10.0;
/// Default `field.puff_sigma0_m` of `puff_plume`: a puff's initial width, m.
pub const PUFF_SIGMA0_M: f64 = 0.5;
/// Default `field.diffusivity_m2ps` of `puff_plume`, m^2/s.
pub const PUFF_DIFFUSIVITY_M2PS: f64 = 0.05;
/// Default `field.wind_mps` of `puff_plume`, m/s: a light breeze eastward.
pub const PUFF_WIND_MPS: [f64; 2] = [0.5, 0.0];
/// Default `field.meander_std_mps` of `puff_plume`, m/s per component.
pub const PUFF_MEANDER_STD_MPS: f64 = 0.1;
/// Default `field.meander_correlation_s` of `puff_plume`, s.
pub const PUFF_MEANDER_CORRELATION_S: f64 = 20.0;
/// Default `field.max_age_s` of `puff_plume`: older puffs are dropped, s.
pub const PUFF_MAX_AGE_S: f64 = 120.0;

/// The default `gaussian_plumes` sources: three overlapping, rotated, anisotropic plumes whose
/// level-10 isoline is one closed, non-convex curve about 60 m long.
pub fn default_plumes() -> Vec<PlumeSpec> {
    vec![
        PlumeSpec {
            center_m: [0.0, 0.0],
            amplitude: 20.0,
            sigma_m: [12.0, 7.0],
            rotation_rad: 0.5,
        },
        PlumeSpec {
            center_m: [18.0, 10.0],
            amplitude: 12.0,
            sigma_m: [6.0, 9.0],
            rotation_rad: -0.3,
        },
        PlumeSpec {
            center_m: [-10.0, 15.0],
            amplitude: 8.0,
            sigma_m: [8.0, 5.0],
            rotation_rad: 1.0,
        },
    ]
}

/// `[field]` resolved: the kind with its parameters, and the values' units.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldSpec {
    /// The values' unit, for labels (`None`: none given and, for a grid, none in its files;
    /// figures say "field units").
    pub units: Option<String>,
    /// The kind and its parameters.
    pub kind: FieldKindSpec,
}

/// A field kind with its typed parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldKindSpec {
    /// `radial_exp`, `gaussian_plumes`, `linear_ramp`: the closed form, its `domain_m` (`None`:
    /// everywhere, the user's choice) and drift ([`DRIFT_MPS`] unless given).
    Analytic(AnalyticField),
    /// `grid`: one file or a time series.
    Grid(GridSpec),
    /// `stations`: scattered values put on a grid.
    Stations(StationsSpec),
    /// `puff_plume`: the plume's parameters, its meander seeded by `sim.seed`.
    PuffPlume(PuffPlumeParams),
}

/// Where a `grid` field's frames come from.
#[derive(Clone, Debug, PartialEq)]
pub enum GridFiles {
    /// `field.path`: one file (one frame, or a 3-D `.npy` / a NetCDF with a time axis).
    Path(String),
    /// `field.paths`: one frame per file.
    Paths(Vec<String>),
}

/// The frame times of a `grid` field.
#[derive(Clone, Debug, PartialEq)]
pub enum FrameTimes {
    /// `field.frame_times_s`, s.
    Given(Vec<f64>),
    /// `field.frame_interval_s`: frames this far apart from 0, s.
    Interval(f64),
    /// The file's own time axis (a NetCDF's), or none (one frame).
    FromFile,
}

/// A value transform `v -> scale * [log10](max(v, floor)) + offset`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValueTransform {
    /// `field.value_floor` (`None`: no floor, the user's choice).
    pub floor: Option<f64>,
    /// `field.value_log10`.
    pub log10: bool,
    /// `field.value_scale`.
    pub scale: f64,
    /// `field.value_offset`.
    pub offset: f64,
}

impl ValueTransform {
    /// Whether the transform changes any value (then a file's `units` no longer describe them).
    pub fn changes_values(&self) -> bool {
        self.floor.is_some() || self.log10 || self.scale != 1.0 || self.offset != 0.0
    }
    /// Whether the transform changes the unit (a floor keeps it; log, scale and offset do not).
    pub fn changes_unit(&self) -> bool {
        self.log10 || self.scale != 1.0 || self.offset != 0.0
    }
}

/// The georeference a grid is put on: each `None` is the file's own (the scenario leaves the
/// key unset); once the field is built, [`crate::Scenario::spec`] holds both.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridGeoreference {
    /// `field.spacing_m`, m.
    pub spacing_m: Option<[f64; 2]>,
    /// `field.origin_m`: the south-west node after cropping, m.
    pub origin_m: Option<[f64; 2]>,
}

/// `field.kind = "grid"` resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct GridSpec {
    /// The files.
    pub files: GridFiles,
    /// `field.format` (`None`: from each file's extension).
    pub format: Option<GridFormat>,
    /// `field.variable` of a NetCDF (`None`: its first 2-D data variable).
    pub variable: Option<String>,
    /// `field.spacing_m` and `field.origin_m`.
    pub georeference: GridGeoreference,
    /// `field.interpolation`.
    pub interpolation: Interpolation,
    /// `field.crop_cells` `[c0, c1, r0, r1]` (`None`: the whole grid).
    pub crop_cells: Option<[usize; 4]>,
    /// `field.value_floor`, `value_log10`, `value_scale`, `value_offset`.
    pub transform: ValueTransform,
    /// The frame times.
    pub frame_times: FrameTimes,
    /// `field.time_interpolation`.
    pub time_interpolation: TimeInterpolation,
    /// `field.time_origin_s`, s.
    pub time_origin_s: f64,
    /// `field.time_scale`.
    pub time_scale: f64,
    /// `field.after_last_frame`.
    pub after_last_frame: AfterLastFrame,
}

/// How stations are interpolated onto their grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StationsMethod {
    /// Ordinary kriging with a fitted variogram.
    Kriging,
    /// Inverse-distance weighting with this power.
    Idw {
        /// `field.idw_power`.
        power: f64,
    },
}

/// `field.kind = "stations"` resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct StationsSpec {
    /// `field.path`: the CSV.
    pub path: String,
    /// `field.value_column`.
    pub value_column: String,
    /// `field.method` (with `idw_power`).
    pub method: StationsMethod,
    /// `field.grid_spacing_m`, in the stations' metres (`None`: 1/100 of the larger side of
    /// their bounding box; once built, the spacing used).
    pub grid_spacing_m: Option<f64>,
    /// `field.spacing_m` and `field.origin_m`.
    pub georeference: GridGeoreference,
    /// `field.interpolation`.
    pub interpolation: Interpolation,
}

fn v2(a: [f64; 2]) -> Vec2 {
    Vec2::new(a[0], a[1])
}

fn interpolation(f: &FieldSection) -> Result<Interpolation, Issue> {
    Ok(match settled(&f.interpolation, "field.interpolation")? {
        InterpolationName::Bilinear => Interpolation::Bilinear,
        InterpolationName::Bicubic => Interpolation::Bicubic,
    })
}

/// `field.spacing_m` and `field.origin_m`.
fn georeference(f: &FieldSection) -> GridGeoreference {
    GridGeoreference {
        spacing_m: f.spacing_m,
        origin_m: f.origin_m,
    }
}

/// A resolved `[field]` of kind `grid`: its files, format, georeference, value transform and
/// frames in time.
fn grid_spec(f: &FieldSection) -> Result<GridSpec, Issue> {
    Ok(GridSpec {
        files: match &f.paths {
            Some(p) => GridFiles::Paths(p.clone()),
            None => GridFiles::Path(settled(&f.path, "field.path")?),
        },
        format: f.format.map(|g| match g {
            GridFormatName::Csv => GridFormat::Csv,
            GridFormatName::Npy => GridFormat::Npy,
            GridFormatName::Asc => GridFormat::Asc,
            GridFormatName::Geotiff => GridFormat::GeoTiff,
            GridFormatName::Netcdf => GridFormat::NetCdf,
        }),
        variable: f.variable.clone(),
        georeference: georeference(f),
        interpolation: interpolation(f)?,
        crop_cells: f.crop_cells,
        transform: ValueTransform {
            floor: f.value_floor,
            log10: settled(&f.value_log10, "field.value_log10")?,
            scale: settled(&f.value_scale, "field.value_scale")?,
            offset: settled(&f.value_offset, "field.value_offset")?,
        },
        frame_times: match (&f.frame_times_s, f.frame_interval_s) {
            (Some(t), _) => FrameTimes::Given(t.clone()),
            (None, Some(dt)) => FrameTimes::Interval(dt),
            (None, None) => FrameTimes::FromFile,
        },
        time_interpolation: match settled(&f.time_interpolation, "field.time_interpolation")? {
            TimeInterpolationName::Nearest => TimeInterpolation::Nearest,
            TimeInterpolationName::Linear => TimeInterpolation::Linear,
            TimeInterpolationName::Cubic => TimeInterpolation::Cubic,
        },
        time_origin_s: settled(&f.time_origin_s, "field.time_origin_s")?,
        time_scale: settled(&f.time_scale, "field.time_scale")?,
        after_last_frame: match settled(&f.after_last_frame, "field.after_last_frame")? {
            AfterLastFrameName::Hold => AfterLastFrame::Hold,
            AfterLastFrameName::End => AfterLastFrame::End,
        },
    })
}

/// A resolved `[field]` of kind `stations`: the CSV, its value column and the interpolation
/// method onto the grid.
fn stations_spec(f: &FieldSection) -> Result<StationsSpec, Issue> {
    Ok(StationsSpec {
        path: settled(&f.path, "field.path")?,
        value_column: settled(&f.value_column, "field.value_column")?,
        method: match settled(&f.method, "field.method")? {
            StationMethod::Kriging => StationsMethod::Kriging,
            StationMethod::Idw => StationsMethod::Idw {
                power: settled(&f.idw_power, "field.idw_power")?,
            },
        },
        grid_spacing_m: f.grid_spacing_m,
        georeference: georeference(f),
        interpolation: interpolation(f)?,
    })
}

/// A resolved `[field]` of kind `puff_plume`; `seed` (`sim.seed`) seeds its meander.
fn puff_plume_params(f: &FieldSection, seed: u64) -> Result<PuffPlumeParams, Issue> {
    Ok(PuffPlumeParams {
        source_m: v2(settled(&f.source_m, "field.source_m")?),
        release_rate_hz: settled(&f.release_rate_hz, "field.release_rate_hz")?,
        puff_mass: settled(&f.puff_mass, "field.puff_mass")?,
        puff_sigma0_m: settled(&f.puff_sigma0_m, "field.puff_sigma0_m")?,
        diffusivity_m2ps: settled(&f.diffusivity_m2ps, "field.diffusivity_m2ps")?,
        wind_mps: v2(settled(&f.wind_mps, "field.wind_mps")?),
        meander_std_mps: settled(&f.meander_std_mps, "field.meander_std_mps")?,
        meander_correlation_s: settled(&f.meander_correlation_s, "field.meander_correlation_s")?,
        max_age_s: settled(&f.max_age_s, "field.max_age_s")?,
        background: settled(&f.background, "field.background")?,
        seed,
        domain_m: f.domain_m,
    })
}

impl FieldSpec {
    /// From a resolved `[field]`; `seed` (`sim.seed`) seeds a puff plume's meander.
    pub fn new(f: &FieldSection, seed: u64) -> Result<Self, Issue> {
        let analytic = |kind| {
            FieldKindSpec::Analytic(AnalyticField {
                kind,
                domain_m: f.domain_m,
                drift_mps: v2(f.drift_mps.unwrap_or(DRIFT_MPS)),
            })
        };
        let kind = match settled(&f.kind, "field.kind")? {
            FieldKind::RadialExp => analytic(AnalyticKind::RadialExp(RadialExp {
                i0: settled(&f.i0, "field.i0")?,
                decay_per_m: settled(&f.decay_per_m, "field.decay_per_m")?,
                center_m: v2(settled(&f.center_m, "field.center_m")?),
            })),
            FieldKind::GaussianPlumes => analytic(AnalyticKind::GaussianPlumes(GaussianPlumes {
                background: settled(&f.background, "field.background")?,
                plumes: settled(&f.sources, "field.sources")?
                    .into_iter()
                    .map(|s| Plume {
                        center_m: v2(s.center_m),
                        amplitude: s.amplitude,
                        sigma_m: s.sigma_m,
                        rotation_rad: s.rotation_rad,
                    })
                    .collect(),
            })),
            FieldKind::LinearRamp => analytic(AnalyticKind::LinearRamp(LinearRamp {
                offset: settled(&f.offset, "field.offset")?,
                gradient_per_m: v2(settled(&f.gradient_per_m, "field.gradient_per_m")?),
            })),
            FieldKind::Grid => FieldKindSpec::Grid(grid_spec(f)?),
            FieldKind::Stations => FieldKindSpec::Stations(stations_spec(f)?),
            FieldKind::PuffPlume => FieldKindSpec::PuffPlume(puff_plume_params(f, seed)?),
        };
        Ok(Self {
            units: f.units.clone(),
            kind,
        })
    }

    /// The analytic or puff field's `domain_m` (`None`: everywhere; a grid's extent is its
    /// nodes').
    pub fn domain_m(&self) -> Option<[f64; 4]> {
        match &self.kind {
            FieldKindSpec::Analytic(a) => a.domain_m,
            FieldKindSpec::PuffPlume(p) => p.domain_m,
            FieldKindSpec::Grid(_) | FieldKindSpec::Stations(_) => None,
        }
    }

    /// The data files the field reads (`field.path`, `field.paths`; absolute once built).
    pub fn data_files(&self) -> Vec<&str> {
        match &self.kind {
            FieldKindSpec::Grid(g) => match &g.files {
                GridFiles::Path(p) => vec![p.as_str()],
                GridFiles::Paths(ps) => ps.iter().map(String::as_str).collect(),
            },
            FieldKindSpec::Stations(s) => vec![s.path.as_str()],
            FieldKindSpec::Analytic(_) | FieldKindSpec::PuffPlume(_) => vec![],
        }
    }
}
