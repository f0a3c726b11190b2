//! The scenario's field: every kind behind one type, built (and for files, loaded) once.

use crate::resolve::Issue;
use crate::schema::*;
use isotrack_core::math::{Mat2, Vec2};
use isotrack_core::{FieldDerivatives, ScalarField};
use isotrack_fields::grid::{GridField, Interpolation};
use isotrack_fields::io::{load_grid_variable, GridFormat};
use isotrack_fields::isoline::{newton_distance, IsolineSegments};
use isotrack_fields::{AnalyticField, AnalyticKind, GaussianPlumes, LinearRamp, Plume, RadialExp};
use std::path::{Path, PathBuf};

/// Every field a scenario can name.
#[derive(Clone, Debug)]
pub enum FieldModel {
    /// `radial_exp`, `gaussian_plumes`, `linear_ramp`.
    Analytic(AnalyticField),
    /// `grid`.
    Grid(GridField),
}

impl ScalarField for FieldModel {
    #[inline]
    fn value(&self, t_s: f64, p: Vec2) -> Option<f64> {
        match self {
            FieldModel::Analytic(f) => f.value(t_s, p),
            FieldModel::Grid(f) => f.value(t_s, p),
        }
    }
}

impl FieldDerivatives for FieldModel {
    fn gradient(&self, t_s: f64, p: Vec2) -> Option<Vec2> {
        match self {
            FieldModel::Analytic(f) => f.gradient(t_s, p),
            FieldModel::Grid(f) => f.gradient(t_s, p),
        }
    }
    fn hessian(&self, t_s: f64, p: Vec2) -> Option<Mat2> {
        match self {
            FieldModel::Analytic(f) => f.hessian(t_s, p),
            FieldModel::Grid(f) => f.hessian(t_s, p),
        }
    }
}

/// Checks that the start lies on the field: inside a grid's node extent or an analytic
/// field's `domain_m`. A start outside once ended the run at t = 0 with `left_field` and no
/// hint; the issue names the extent and the keys that set it.
pub(crate) fn check_start(file: &ScenarioFile, field: &FieldModel) -> Result<(), Issue> {
    let (x, y) = (
        file.initial.x_m.unwrap_or(10.0),
        file.initial.y_m.unwrap_or(0.0),
    );
    let (e, set_by) = match field {
        FieldModel::Grid(g) => (
            g.grid().extent_m(),
            "field.origin_m and field.spacing_m (by default the file's georeference; a CSV or .npy grid has none: origin [0, 0], spacing 1 m)",
        ),
        FieldModel::Analytic(_) => match file.field.domain_m {
            Some(d) => (d, "field.domain_m"),
            None => return Ok(()),
        },
    };
    if (e[0]..=e[1]).contains(&x) && (e[2]..=e[3]).contains(&y) {
        return Ok(());
    }
    let key = if (e[0]..=e[1]).contains(&x) {
        "initial.y_m"
    } else {
        "initial.x_m"
    };
    Err(Issue {
        key: key.into(),
        message: format!(
            "the start ({x}, {y}) m is outside the field, which spans x in [{}, {}] m and y in [{}, {}] m, set by {set_by}",
            e[0], e[1], e[2], e[3]
        ),
    })
}

/// The true isoline of a field, for the distance metric.
#[derive(Clone, Debug)]
pub enum IsolineOracle {
    /// Root finding along the gradient (analytic fields).
    Newton(AnalyticField, f64),
    /// Marching-squares segments (gridded fields).
    Segments(IsolineSegments),
}

impl IsolineOracle {
    /// Builds the oracle for `level` (refining grids 4 times per cell).
    pub fn new(field: &FieldModel, level: f64) -> Self {
        match field {
            FieldModel::Analytic(f) => IsolineOracle::Newton(f.clone(), level),
            FieldModel::Grid(g) => IsolineOracle::Segments(IsolineSegments::for_grid(g, level, 4)),
        }
    }
    /// Distance from `p` to the isoline at time `t_s`, m.
    pub fn distance(&self, t_s: f64, p: Vec2) -> Option<f64> {
        match self {
            IsolineOracle::Newton(f, level) => newton_distance(f, t_s, p, *level),
            IsolineOracle::Segments(s) => s.distance(p),
        }
    }
}

fn v2(a: [f64; 2]) -> Vec2 {
    Vec2::new(a[0], a[1])
}

/// Builds the field of a resolved `[field]` section; grid paths are taken relative to
/// `base_dir` and recorded back into the section as absolute paths.
pub fn build_field(f: &mut FieldSection, base_dir: &Path) -> Result<FieldModel, Issue> {
    let analytic = |kind| {
        FieldModel::Analytic(AnalyticField {
            kind,
            domain_m: f.domain_m,
            drift_mps: v2(f.drift_mps.unwrap_or_default()),
        })
    };
    Ok(match f.kind.unwrap_or(FieldKind::RadialExp) {
        FieldKind::RadialExp => analytic(AnalyticKind::RadialExp(RadialExp {
            i0: f.i0.unwrap_or(20.0),
            decay_per_m: f.decay_per_m.unwrap_or(0.1),
            center_m: v2(f.center_m.unwrap_or_default()),
        })),
        FieldKind::GaussianPlumes => analytic(AnalyticKind::GaussianPlumes(GaussianPlumes {
            background: f.background.unwrap_or_default(),
            plumes: f
                .sources
                .clone()
                .unwrap_or_default()
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
            offset: f.offset.unwrap_or_default(),
            gradient_per_m: v2(f.gradient_per_m.unwrap_or([0.0, 1.0])),
        })),
        FieldKind::Grid => FieldModel::Grid(build_grid(f, base_dir)?),
        FieldKind::Stations => FieldModel::Grid(build_stations(f, base_dir)?),
    })
}

fn resolve_path(f: &FieldSection, base_dir: &Path) -> PathBuf {
    let mut path = PathBuf::from(f.path.clone().unwrap_or_default());
    if path.is_relative() {
        path = base_dir.join(path);
    }
    path.canonicalize().unwrap_or(path)
}

/// Stations: read, interpolate onto a grid over their bounding box, then georeference
/// overrides as for `grid`.
fn build_stations(f: &mut FieldSection, base_dir: &Path) -> Result<GridField, Issue> {
    use isotrack_fields::stations::{Idw, OrdinaryKriging, StationInterpolator, Stations};
    let issue = |key: &str, message: String| Issue {
        key: key.to_string(),
        message,
    };
    let path = resolve_path(f, base_dir);
    let col = f.value_column.clone().unwrap_or_default();
    let st = Stations::from_csv(&path, &col).map_err(|e| issue("field.path", e.to_string()))?;
    let ext = st.extent_m();
    let spacing = f.grid_spacing_m.unwrap_or(st.default_spacing_m());
    let grid = match f.method.unwrap_or(StationMethod::Kriging) {
        StationMethod::Idw => Idw::new(st, f.idw_power.unwrap_or(2.0)).to_grid(ext, spacing),
        StationMethod::Kriging => OrdinaryKriging::new(st)
            .map_err(|e| issue("field.path", format!("{}: {e}", path.display())))?
            .to_grid(ext, spacing),
    }
    .map_err(|e| issue("field.grid_spacing_m", e.to_string()))?;
    let new_spacing = f.spacing_m.unwrap_or(grid.spacing_m());
    let origin = f.origin_m.map(v2).unwrap_or(grid.origin_m());
    let grid = grid
        .with_georeference(origin, new_spacing)
        .map_err(|e| issue("field.spacing_m", e.to_string()))?;
    f.path = Some(path.display().to_string());
    f.grid_spacing_m = Some(spacing);
    f.spacing_m = Some(grid.spacing_m());
    f.origin_m = Some([grid.origin_m().x, grid.origin_m().y]);
    let interp = match f.interpolation.unwrap_or(InterpolationName::Bicubic) {
        InterpolationName::Bilinear => Interpolation::Bilinear,
        InterpolationName::Bicubic => Interpolation::Bicubic,
    };
    Ok(GridField::new(grid, interp))
}

fn build_grid(f: &mut FieldSection, base_dir: &Path) -> Result<GridField, Issue> {
    let issue = |key: &str, message: String| Issue {
        key: key.to_string(),
        message,
    };
    let path = resolve_path(f, base_dir);
    let format = f.format.map(|g| match g {
        GridFormatName::Csv => GridFormat::Csv,
        GridFormatName::Npy => GridFormat::Npy,
        GridFormatName::Asc => GridFormat::Asc,
        GridFormatName::Geotiff => GridFormat::GeoTiff,
        GridFormatName::Netcdf => GridFormat::NetCdf,
    });
    let loaded = load_grid_variable(&path, format, f.variable.as_deref())
        .map_err(|e| issue("field.path", e.to_string()))?;
    let mut grid = loaded.grid;
    if let Some([c0, c1, r0, r1]) = f.crop_cells {
        if c1 >= grid.nx() || r1 >= grid.ny() {
            return Err(issue(
                "field.crop_cells",
                format!(
                    "{:?} is outside the {} x {} grid (columns x rows)",
                    [c0, c1, r0, r1],
                    grid.nx(),
                    grid.ny()
                ),
            ));
        }
        grid = grid
            .crop(c0, c1, r0, r1)
            .map_err(|e| issue("field.crop_cells", e.to_string()))?;
    }
    let spacing = f.spacing_m.unwrap_or(grid.spacing_m());
    let origin = f.origin_m.map(v2).unwrap_or(grid.origin_m());
    grid = grid
        .with_georeference(origin, spacing)
        .map_err(|e| issue("field.spacing_m", e.to_string()))?;
    let floor = f.value_floor;
    let log = f.value_log10.unwrap_or(false);
    if log && floor.is_none() && grid.value_range().0 <= 0.0 {
        return Err(issue(
            "field.value_log10",
            format!(
                "the grid has values <= 0 (min {}); set field.value_floor to a positive value",
                grid.value_range().0
            ),
        ));
    }
    let (scale, offset) = (f.value_scale.unwrap_or(1.0), f.value_offset.unwrap_or(0.0));
    if floor.is_some() || log || scale != 1.0 || offset != 0.0 {
        grid = grid
            .map_values(|v| {
                let v = floor.map_or(v, |fl| v.max(fl));
                let v = if log { v.log10() } else { v };
                scale * v + offset
            })
            .map_err(|e| issue("field.path", format!("after the value transform: {e}")))?;
    }
    // Record what was used, so the resolved scenario reproduces the run from anywhere.
    f.path = Some(path.display().to_string());
    f.spacing_m = Some(grid.spacing_m());
    f.origin_m = Some([grid.origin_m().x, grid.origin_m().y]);
    let interp = match f.interpolation.unwrap_or(InterpolationName::Bicubic) {
        InterpolationName::Bilinear => Interpolation::Bilinear,
        InterpolationName::Bicubic => Interpolation::Bicubic,
    };
    Ok(GridField::new(grid, interp))
}
