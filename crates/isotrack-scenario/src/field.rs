//! The scenario's field: every kind behind one type, built (and for files, loaded) once.

use crate::issue::Issue;
use crate::schema::FieldSection;
use crate::spec::field::{
    FieldKindSpec, FieldSpec, FrameTimes, GridFiles, GridSpec, StationsMethod, StationsSpec,
    ValueTransform,
};
use isotrack_core::math::{Mat2, Vec2};
use isotrack_core::numtext::{Echo, Num};
use isotrack_core::{FieldDerivatives, ScalarField};
use isotrack_fields::grid::{Grid2, GridField, GridSeries};
use isotrack_fields::io::{load_series_read, read_limited, ReadWhole};
use isotrack_fields::isoline::{newton_distance, IsolineSegments};
use isotrack_fields::puff::PuffPlume;
use isotrack_fields::{AnalyticField, AnalyticKind};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Where a longitude/latitude grid's local metres are on the Earth: the projection of
/// [`isotrack_fields::georef`] (equirectangular, mean Earth radius `R`), with the local origin
/// and the reference latitude of the file's grid, after `field.crop_cells` and
/// `field.origin_m`:
///
/// ```text
/// lon = lon0 + x / (R cos(ref_lat)),   lat = lat0 + y / R      (radians)
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LonLatFrame {
    /// Longitude of the local origin `(0, 0)`, deg.
    pub lon0_deg: f64,
    /// Latitude of the local origin, deg.
    pub lat0_deg: f64,
    /// The latitude whose cosine scales east-west distances (the file's grid's middle), deg.
    pub ref_lat_deg: f64,
}

/// Every field a scenario can name.
#[derive(Clone, Debug)]
pub enum FieldModel {
    /// `radial_exp`, `gaussian_plumes`, `linear_ramp`.
    Analytic(AnalyticField),
    /// `grid`, one frame.
    Grid(GridField),
    /// `grid`, a time series of frames (shared: a sweep loads it once).
    Series(Arc<GridSeries>),
    /// `puff_plume` (its meander seeded by `sim.seed`).
    Puff(Arc<PuffPlume>),
}

impl ScalarField for FieldModel {
    #[inline]
    fn value(&self, t_s: f64, p: Vec2) -> Option<f64> {
        match self {
            FieldModel::Analytic(f) => f.value(t_s, p),
            FieldModel::Grid(f) => f.value(t_s, p),
            FieldModel::Series(f) => f.value(t_s, p),
            FieldModel::Puff(f) => f.value(t_s, p),
        }
    }
}

impl FieldDerivatives for FieldModel {
    fn gradient(&self, t_s: f64, p: Vec2) -> Option<Vec2> {
        match self {
            FieldModel::Analytic(f) => f.gradient(t_s, p),
            FieldModel::Grid(f) => f.gradient(t_s, p),
            FieldModel::Series(f) => f.gradient(t_s, p),
            FieldModel::Puff(f) => f.gradient(t_s, p),
        }
    }
    fn hessian(&self, t_s: f64, p: Vec2) -> Option<Mat2> {
        match self {
            FieldModel::Analytic(f) => f.hessian(t_s, p),
            FieldModel::Grid(f) => f.hessian(t_s, p),
            FieldModel::Series(f) => f.hessian(t_s, p),
            FieldModel::Puff(f) => f.hessian(t_s, p),
        }
    }
}

/// The extent a start must lie in (`[x0, x1, y0, y1]`, m) and the keys that set it: a grid's
/// node extent, an analytic field's or a puff plume's `domain_m` (`None`: no bound).
fn start_extent(field: &FieldModel) -> Option<([f64; 4], &'static str)> {
    const GRID_KEYS: &str = "field.origin_m and field.spacing_m (by default the file's georeference; a CSV or .npy grid has none: origin [0, 0], spacing 1 m)";
    match field {
        FieldModel::Grid(g) => Some((g.grid().extent_m(), GRID_KEYS)),
        FieldModel::Series(g) => Some((g.extent_m(), GRID_KEYS)),
        FieldModel::Analytic(AnalyticField { domain_m, .. }) => {
            domain_m.map(|d| (d, "field.domain_m"))
        }
        FieldModel::Puff(p) => p.params().domain_m.map(|d| (d, "field.domain_m")),
    }
}

/// Whether `[x, y]` lies outside `field`'s start extent: `Some((extent, keys, x inside))`.
fn outside(start: [f64; 2], field: &FieldModel) -> Option<([f64; 4], &'static str, bool)> {
    let [x, y] = start;
    let (e, set_by) = start_extent(field)?;
    let x_in = (e[0]..=e[1]).contains(&x);
    (!(x_in && (e[2]..=e[3]).contains(&y))).then_some((e, set_by, x_in))
}

/// "spans x in [..] m and y in [..] m, set by ..." of an extent.
fn spans(e: [f64; 4], set_by: &str) -> String {
    format!(
        "which spans x in [{}, {}] m and y in [{}, {}] m, set by {set_by}",
        Num(e[0]),
        Num(e[1]),
        Num(e[2]),
        Num(e[3])
    )
}

/// Checks that the start lies on the field: inside a grid's node extent or an analytic
/// field's `domain_m`. A start outside once ended the run at t = 0 with `left_field` and no
/// hint; the issue names the extent and the keys that set it.
pub(crate) fn check_start(start: [f64; 2], field: &FieldModel) -> Result<(), Issue> {
    let Some((e, set_by, x_in)) = outside(start, field) else {
        return Ok(());
    };
    let [x, y] = start;
    let key = if x_in { "initial.y_m" } else { "initial.x_m" };
    Err(Issue {
        key: key.into(),
        unreadable: false,
        message: format!(
            "the start ({}, {}) m is outside the field, {}",
            Echo(x),
            Echo(y),
            spans(e, set_by)
        ),
    })
}

/// Checks that every team vehicle's start lies on the field, as [`check_start`] checks a
/// single vehicle's (att32e-5: a team start outside a grid was accepted, and the vehicle
/// ended at t = 0 with `left_field`). The issue names the vehicle and the key that placed it:
/// `team.starts[I].x_m` (or `.y_m`) for a listed pose, `team.spread` for a spread along a line
/// or an arc (a team of one without either starts at `[initial]`, checked by
/// [`check_start`]).
pub(crate) fn check_team_starts(
    team: Option<&crate::schema::TeamSection>,
    starts: &[crate::spec::sim::Start],
    field: &FieldModel,
) -> Result<(), Issue> {
    let Some(team) = team else {
        return Ok(());
    };
    for (i, s) in starts.iter().enumerate() {
        let Some((e, set_by, x_in)) = outside([s.x_m, s.y_m], field) else {
            continue;
        };
        let key = if team.starts.is_some() {
            format!("team.starts[{i}].{}", if x_in { "y_m" } else { "x_m" })
        } else if team.spread.is_some() {
            "team.spread".to_string()
        } else {
            continue;
        };
        return Err(Issue {
            key,
            unreadable: false,
            message: format!(
                "puts vehicle {i}'s start at ({}, {}) m, outside the field, {}",
                Echo(s.x_m),
                Echo(s.y_m),
                spans(e, set_by)
            ),
        });
    }
    Ok(())
}

/// The true isoline of a field, for the distance metric.
#[derive(Clone, Debug)]
pub enum IsolineOracle {
    /// Root finding along the gradient (analytic fields).
    Newton(AnalyticField, f64),
    /// The circle `|p - c - drift t| = ln(I0/level)/k` of a radial field without a domain:
    /// the distance in closed form (what Newton converges to, at a fraction of its cost: a
    /// sweep asks for it at every step of the steady-state window).
    Circle {
        /// Centre at `t = 0`, m.
        center_m: Vec2,
        /// Drift of the field, m/s.
        drift_mps: Vec2,
        /// Radius `ln(I0/level)/k`, m.
        radius_m: f64,
    },
    /// Marching-squares segments (gridded fields).
    Segments(IsolineSegments),
    /// The isoline of a time series at the query time (see [`MovingIsoline`]).
    Moving(Arc<MovingIsoline>),
    /// No isoline distance (a field without one: a puff plume in still air).
    None,
}

impl IsolineOracle {
    /// Builds the oracle for `level` (refining grids 4 times per cell).
    pub fn new(field: &FieldModel, level: f64) -> Self {
        match field {
            FieldModel::Analytic(f) => match (&f.kind, f.domain_m) {
                (AnalyticKind::RadialExp(r), None)
                    if r.i0 > 0.0 && level > 0.0 && level < r.i0 && r.decay_per_m > 0.0 =>
                {
                    IsolineOracle::Circle {
                        center_m: r.center_m,
                        drift_mps: f.drift_mps,
                        radius_m: (r.i0 / level).ln() / r.decay_per_m,
                    }
                }
                _ => IsolineOracle::Newton(f.clone(), level),
            },
            FieldModel::Grid(g) => IsolineOracle::Segments(IsolineSegments::for_grid(g, level, 4)),
            FieldModel::Series(s) => {
                IsolineOracle::Moving(Arc::new(MovingIsoline::new(s.clone(), level)))
            }
            FieldModel::Puff(pf) => mean_plume_isoline(pf, level),
        }
    }
    /// Distance from `p` to the isoline at time `t_s`, m.
    pub fn distance(&self, t_s: f64, p: Vec2) -> Option<f64> {
        match self {
            IsolineOracle::Newton(f, level) => newton_distance(f, t_s, p, *level),
            IsolineOracle::Circle {
                center_m,
                drift_mps,
                radius_m,
            } => Some(((p - (*center_m + *drift_mps * t_s)).norm() - radius_m).abs()),
            IsolineOracle::Segments(s) => s.distance(p),
            IsolineOracle::Moving(m) => m.distance(t_s, p),
            IsolineOracle::None => None,
        }
    }
}

/// The isoline metric of a puff plume: the distance to the isoline of its long-run mean field
/// without meander (the Gaussian-plume formula; a plume's instantaneous isolines are filaments
/// and puffs), by marching squares over the plume's reach (400 cells along the wind).
fn mean_plume_isoline(pf: &PuffPlume, level: f64) -> IsolineOracle {
    let pp = pf.params();
    let u = pp.wind_mps.norm();
    if u <= 0.0 {
        return IsolineOracle::None;
    }
    let reach = u * pp.max_age_s;
    let width = 4.0 * (pp.puff_sigma0_m.powi(2) + 2.0 * pp.diffusivity_m2ps * pp.max_age_s).sqrt();
    let h = (reach / 400.0).max(1e-3);
    let n = ((2.0 * (reach + width)) / h).ceil() as usize + 1;
    let origin = pp.source_m - Vec2::new(reach + width, reach + width);
    if n > 4000 {
        return IsolineOracle::None;
    }
    IsolineOracle::Segments(IsolineSegments::from_samples(origin, h, n, n, level, |p| {
        pf.gaussian_plume_mean(p)
    }))
}

/// The most segments [`MovingIsoline`] keeps cached over all its isolines: 2^23 (256 MiB of
/// segments, as many as one isoline of [`isotrack_fields::isoline::MAX_ISOLINE_SAMPLES`] can
/// have).
pub const MAX_CACHED_SEGMENTS: usize = 1 << 23;

/// The isoline of a grid time series as it moves: the marching-squares isoline of the
/// time-interpolated field (the same blend of frames the run sees), recomputed every
/// `bucket_s` of run time (1/8 of the shortest frame interval, in run time) at the bucket's
/// middle, and cached (the 64 most recent, and no more than [`MAX_CACHED_SEGMENTS`]
/// segments in all). Between recomputations the isoline is taken as
/// fixed: the metric's time resolution.
pub struct MovingIsoline {
    series: Arc<GridSeries>,
    level: f64,
    bucket_s: f64,
    cache: Mutex<Vec<(i64, Arc<Option<IsolineSegments>>)>>,
}

impl std::fmt::Debug for MovingIsoline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "MovingIsoline(level {}, every {} s)",
            self.level, self.bucket_s
        )
    }
}

impl MovingIsoline {
    /// The isoline of `level` in `series`.
    pub fn new(series: Arc<GridSeries>, level: f64) -> Self {
        let t = series.times_s();
        let min_gap = t
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let bucket_s = if min_gap.is_finite() {
            min_gap / 8.0 / series.field_time_scale()
        } else {
            f64::INFINITY
        };
        Self {
            series,
            level,
            bucket_s,
            cache: Mutex::new(Vec::new()),
        }
    }

    /// Run-time resolution of the moving isoline, s.
    pub fn bucket_s(&self) -> f64 {
        self.bucket_s
    }

    /// The isoline at run time `t_s` (`None` where the series has ended).
    pub fn at(&self, t_s: f64) -> Arc<Option<IsolineSegments>> {
        let b = if self.bucket_s.is_finite() {
            (t_s / self.bucket_s).floor() as i64
        } else {
            0
        };
        if let Ok(c) = self.cache.lock() {
            if let Some((_, seg)) = c.iter().find(|(k, _)| *k == b) {
                return seg.clone();
            }
        }
        let mid = if self.bucket_s.is_finite() {
            (b as f64 + 0.5) * self.bucket_s
        } else {
            0.0
        };
        let seg = Arc::new(self.series.grid_at(mid).map(|g| {
            IsolineSegments::for_grid(
                &GridField::new(g, self.series.interpolation()),
                self.level,
                4,
            )
        }));
        if let Ok(mut c) = self.cache.lock() {
            if c.len() >= 64 {
                c.remove(0);
            }
            c.push((b, seg.clone()));
            // And at most MAX_CACHED_SEGMENTS in all (a noisy field's isoline can have 2^23
            // segments: 64 of them would not fit in memory); the newest always stays.
            let count = |c: &[(i64, Arc<Option<IsolineSegments>>)]| -> usize {
                c.iter()
                    .map(|(_, s)| s.as_ref().as_ref().map_or(0, |s| s.segments().len()))
                    .sum()
            };
            while c.len() > 1 && count(&c) > MAX_CACHED_SEGMENTS {
                c.remove(0);
            }
        }
        seg
    }

    /// Distance from `p` to the isoline at run time `t_s`, m.
    pub fn distance(&self, t_s: f64, p: Vec2) -> Option<f64> {
        self.at(t_s).as_ref().as_ref()?.distance(p)
    }
}

fn v2(a: [f64; 2]) -> Vec2 {
    Vec2::new(a[0], a[1])
}

/// The `[field]` keys a field's files filled in, to record into the resolved file (so that it
/// reproduces the run from anywhere): each `Some` is written, each `None` left as it was.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FileFilled {
    /// `field.path`, made absolute.
    pub path: Option<String>,
    /// `field.paths`, made absolute.
    pub paths: Option<Vec<String>>,
    /// `field.spacing_m`: the grid's, as used.
    pub spacing_m: Option<[f64; 2]>,
    /// `field.origin_m`: the grid's south-west node, as used.
    pub origin_m: Option<[f64; 2]>,
    /// `field.grid_spacing_m` of `stations`: the spacing they were interpolated at.
    pub grid_spacing_m: Option<f64>,
    /// `field.units`, from the grid files' own `units` (see [`adopt_file_units`]).
    pub units: Option<String>,
}

impl FileFilled {
    /// Writes the filled keys into `f`.
    pub fn record(&self, f: &mut FieldSection) {
        if let Some(p) = &self.path {
            f.path = Some(p.clone());
        }
        if let Some(p) = &self.paths {
            f.paths = Some(p.clone());
        }
        if let Some(s) = self.spacing_m {
            f.spacing_m = Some(s);
        }
        if let Some(o) = self.origin_m {
            f.origin_m = Some(o);
        }
        if let Some(g) = self.grid_spacing_m {
            f.grid_spacing_m = Some(g);
        }
        if let Some(u) = &self.units {
            f.units = Some(u.clone());
        }
    }
}

/// A field built from its spec: the model, the keys its files filled, the warnings their
/// contents give, and where a longitude/latitude grid is on the Earth.
#[derive(Clone, Debug)]
pub struct BuiltField {
    /// The field.
    pub model: FieldModel,
    /// The keys its files filled ([`FileFilled::record`] them into the resolved file).
    pub filled: FileFilled,
    /// Warnings the files' contents give: a grid file's `units` (NetCDF's CF attribute) that
    /// differs from `field.units`, or that a value transform makes stale.
    pub notes: Vec<String>,
    /// Where the field's local metres are on the Earth when its file is a longitude/latitude
    /// grid (NetCDF, GeoTIFF in degrees) whose spacing the scenario leaves as the file gives it
    /// (`None` otherwise: a `field.spacing_m` of its own unties the metres from the degrees).
    pub lonlat: Option<LonLatFrame>,
    /// The SHA-256 of each data file the field was read from, by absolute path (as
    /// [`FileFilled`] names it), of the very bytes parsed (att41-22: hashed as read, not by
    /// reading the file again after the load).
    pub digests: BTreeMap<String, String>,
}

/// Builds the field of a resolved `[field]` ([`FieldSpec`], read before its files): grid paths
/// are taken relative to `base_dir`. A file fills the keys the spec leaves to it (its spacing
/// and origin, its values' units when `field.units` is unset and no value transform changes the
/// unit, the stations' grid spacing): the scenario's own values always win.
pub fn build_field(spec: &FieldSpec, base_dir: &Path) -> Result<BuiltField, Issue> {
    let mut filled = FileFilled::default();
    let mut notes = Vec::new();
    let mut lonlat = None;
    let mut digests = BTreeMap::new();
    let model = match &spec.kind {
        FieldKindSpec::Analytic(a) => FieldModel::Analytic(a.clone()),
        FieldKindSpec::PuffPlume(p) => FieldModel::Puff(Arc::new(PuffPlume::new(*p))),
        FieldKindSpec::Grid(g) => {
            let into = Filling {
                filled: &mut filled,
                notes: &mut notes,
                lonlat: &mut lonlat,
                digests: &mut digests,
            };
            build_grid(g, spec.units.as_deref(), base_dir, into)?
        }
        FieldKindSpec::Stations(s) => {
            FieldModel::Grid(build_stations(s, base_dir, &mut filled, &mut digests)?)
        }
    };
    Ok(BuiltField {
        model,
        filled,
        notes,
        lonlat,
        digests,
    })
}

/// What building a grid fills besides the field.
struct Filling<'a> {
    filled: &'a mut FileFilled,
    notes: &'a mut Vec<String>,
    lonlat: &'a mut Option<LonLatFrame>,
    /// Each file's SHA-256 as read ([`BuiltField::digests`]).
    digests: &'a mut BTreeMap<String, String>,
}

/// A file named by the scenario, relative to its directory.
pub(crate) fn resolve_one(p: &str, base_dir: &Path) -> PathBuf {
    let mut path = PathBuf::from(p);
    if path.is_relative() {
        path = base_dir.join(path);
    }
    path.canonicalize().unwrap_or(path)
}

/// A file's load error as an issue of `key`: a file that cannot be read at all (missing, a
/// FIFO, a directory, beyond its size limit) is marked so (exit 66), what it holds is 65.
fn load_issue(key: &str, prefix: &str, e: isotrack_fields::io::LoadError) -> Issue {
    Issue {
        key: key.to_string(),
        message: format!("{prefix}{e}"),
        unreadable: e.unreadable,
    }
}

/// `field.units` from the grid files' own `units` (issue 30: a NetCDF variable in `K` or
/// `ug m-3` was shown with no unit): taken (returned) when the scenario leaves `field.units`
/// unset (`given`) and no value transform (`value_scale`, `value_offset`, `value_log10`)
/// changes what the unit describes; a warning (in `notes`) when `field.units` is set to another
/// unit, when a transform leaves the unit unknown, or when the files of `field.paths` disagree.
fn adopt_file_units(
    given: Option<&str>,
    transform: &ValueTransform,
    file_units: &[(String, String)],
    notes: &mut Vec<String>,
) -> Option<String> {
    let clip = |t: &str| isotrack_core::numtext::Clipped(t).to_string();
    let (path, units) = file_units.first()?;
    if let Some((other, u)) = file_units.iter().find(|(_, u)| u != units) {
        notes.push(format!(
            "the grid files give their values in different units: `{}` ({}) and `{}` ({})",
            clip(units),
            clip(path),
            clip(u),
            clip(other)
        ));
    }
    let transformed = transform.changes_unit();
    match given {
        Some(given) if given.trim() != units => notes.push(format!(
            "field.units = \"{}\" but {} gives its values in `{}` (the variable's `units` attribute){}: the figures and the report say \"{}\"",
            clip(given),
            clip(path),
            clip(units),
            if transformed { ", before field.value_scale / value_offset / value_log10" } else { "" },
            clip(given)
        )),
        Some(_) => {}
        None if transformed => notes.push(format!(
            "{} gives its values in `{}` (the variable's `units` attribute), but field.value_scale / value_offset / value_log10 change them: set field.units to the unit of the transformed values (the figures and the report show none)",
            clip(path),
            clip(units)
        )),
        None => return Some(clip(units)),
    }
    None
}

/// Stations: read, interpolate onto a grid over their bounding box, then georeference
/// overrides as for `grid`.
fn build_stations(
    s: &StationsSpec,
    base_dir: &Path,
    filled: &mut FileFilled,
    digests: &mut BTreeMap<String, String>,
) -> Result<GridField, Issue> {
    use isotrack_fields::stations::{Idw, OrdinaryKriging, StationInterpolator, Stations};
    let issue = |key: &str, message: String| Issue {
        key: key.to_string(),
        message,
        unreadable: false,
    };
    let path = resolve_one(&s.path, base_dir);
    let (st, digest) = Stations::from_csv_hashed(&path, &s.value_column)
        .map_err(|e| load_issue("field.path", "", e))?;
    digests.insert(path.display().to_string(), digest);
    let ext = st.extent_m();
    let spacing = s.grid_spacing_m.unwrap_or(st.default_spacing_m());
    let grid = match s.method {
        StationsMethod::Idw { power } => Idw::new(st, power).to_grid(ext, spacing),
        StationsMethod::Kriging => OrdinaryKriging::new(st)
            .map_err(|e| issue("field.path", format!("{}: {e}", path.display())))?
            .to_grid(ext, spacing),
    }
    .map_err(|e| issue("field.grid_spacing_m", e.to_string()))?;
    let new_spacing = s.georeference.spacing_m.unwrap_or(grid.spacing_m());
    let origin = s.georeference.origin_m.map(v2).unwrap_or(grid.origin_m());
    let grid = grid
        .with_georeference(origin, new_spacing)
        .map_err(|e| issue("field.spacing_m", e.to_string()))?;
    filled.path = Some(path.display().to_string());
    filled.grid_spacing_m = Some(spacing);
    filled.spacing_m = Some(grid.spacing_m());
    filled.origin_m = Some([grid.origin_m().x, grid.origin_m().y]);
    Ok(GridField::new(grid, s.interpolation))
}

/// One frame as the scenario asks: cropped, re-georeferenced, values transformed.
fn prepare_frame(g: &GridSpec, mut grid: Grid2) -> Result<Grid2, Issue> {
    let issue = |key: &str, message: String| Issue {
        key: key.to_string(),
        message,
        unreadable: false,
    };
    if let Some([c0, c1, r0, r1]) = g.crop_cells {
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
    let spacing = g.georeference.spacing_m.unwrap_or(grid.spacing_m());
    let origin = g.georeference.origin_m.map(v2).unwrap_or(grid.origin_m());
    grid = grid
        .with_georeference(origin, spacing)
        .map_err(|e| issue("field.spacing_m", e.to_string()))?;
    let ValueTransform {
        floor,
        log10: log,
        scale,
        offset,
    } = g.transform;
    if log && floor.is_none() && grid.value_range().0 <= 0.0 {
        return Err(issue(
            "field.value_log10",
            format!(
                "the grid has values <= 0 (min {}); set field.value_floor to a positive value",
                Num(grid.value_range().0)
            ),
        ));
    }
    if g.transform.changes_values() {
        grid = grid
            .map_values(|v| {
                let v = floor.map_or(v, |fl| v.max(fl));
                let v = if log { v.log10() } else { v };
                scale * v + offset
            })
            .map_err(|e| issue("field.path", format!("after the value transform: {e}")))?;
    }
    Ok(grid)
}

/// What a grid field's files gave: their frames, the one file's frame times (its own time
/// axis), the units each file states, the first file's georeference, and the one file (for
/// messages about its time axis).
struct GridFilesRead {
    raw: Vec<Grid2>,
    file_times: Option<Vec<f64>>,
    file_units: Vec<(String, String)>,
    georef: isotrack_fields::georef::Georeference,
    one_file: Option<String>,
}

/// What identifies a file named twice in `field.paths` (att43-7): its absolute path (symbolic
/// links and `dir/../dir` spellings resolved, [`resolve_one`]), and on Unix its device and
/// inode ([`dev_inode`]), so a hard link is the same file too.
type FileId = (PathBuf, Option<(u64, u64)>);

/// Whether two [`FileId`]s are one file: the same path, or the same device and inode.
fn same_file_as(a: &FileId, b: &FileId) -> bool {
    a.0 == b.0 || (a.1.is_some() && a.1 == b.1)
}

/// The device and inode of the file at `path` (Unix; `None` elsewhere or if unknown).
fn dev_inode(path: &Path) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

/// Reads `field.path` (one file, any number of frames) or `field.paths` (one frame per file),
/// recording the paths as absolute into `filled`, the files' warnings into `notes` and the
/// SHA-256 of each file's bytes as parsed into `digests`. Each distinct file is read once
/// (`read`: [`read_limited`] but in tests): a file `field.paths` names twice (two spellings, a
/// link) gives its one frame, as read, to each place (att43-7: it was read twice, and a file
/// changing meanwhile gave two frames under one digest).
fn read_grid_files(
    g: &GridSpec,
    base_dir: &Path,
    filled: &mut FileFilled,
    notes: &mut Vec<String>,
    digests: &mut BTreeMap<String, String>,
    read: ReadWhole<'_>,
) -> Result<GridFilesRead, Issue> {
    // (file, its values' units) of the files that give one.
    let mut file_units: Vec<(String, String)> = Vec::new();
    let mut georef = isotrack_fields::georef::Georeference::None;
    // The one file (for messages about its time axis).
    let mut one_file: Option<String> = None;
    let (raw, file_times) = match &g.files {
        GridFiles::Paths(list) => {
            let (frames, abs) = read_frame_files(
                list,
                g,
                base_dir,
                FrameFilesOut {
                    notes,
                    digests,
                    file_units: &mut file_units,
                    georef: &mut georef,
                },
                read,
            )?;
            filled.paths = Some(abs);
            (frames, None)
        }
        GridFiles::Path(p) => {
            let path = resolve_one(p, base_dir);
            let (s, digest) = load_series_read(&path, g.format, g.variable.as_deref(), read)
                .map_err(|e| load_issue("field.path", "", e))?;
            digests.insert(path.display().to_string(), digest);
            filled.path = Some(path.display().to_string());
            one_file = filled.path.clone();
            notes.extend(s.warnings);
            file_units.extend(s.units.map(|u| (path.display().to_string(), u)));
            georef = s.georeference;
            (s.frames, s.frame_times_s)
        }
    };
    Ok(GridFilesRead {
        raw,
        file_times,
        file_units,
        georef,
        one_file,
    })
}

/// Where [`read_frame_files`] records what it learns besides the frames: the files' warnings,
/// each file's digest, the units of the files that give one, and the first file's
/// georeference.
struct FrameFilesOut<'a> {
    notes: &'a mut Vec<String>,
    digests: &'a mut BTreeMap<String, String>,
    file_units: &'a mut Vec<(String, String)>,
    georef: &'a mut isotrack_fields::georef::Georeference,
}

/// The frames of `field.paths` (one per file, in order) and the files' absolute paths: each
/// distinct file read once, a file named twice giving its one frame, as read, to each place
/// (att43-7); a file holding other than one frame is an error naming it.
fn read_frame_files(
    list: &[String],
    g: &GridSpec,
    base_dir: &Path,
    out: FrameFilesOut<'_>,
    read: ReadWhole<'_>,
) -> Result<(Vec<Grid2>, Vec<String>), Issue> {
    let mut frames: Vec<Grid2> = Vec::with_capacity(list.len());
    let mut abs = Vec::with_capacity(list.len());
    // Each distinct file read so far, with the index of its frame and its digest.
    let mut read_before: Vec<(FileId, usize, String)> = Vec::new();
    for (k, p) in list.iter().enumerate() {
        let path = resolve_one(p, base_dir);
        let id = (path.clone(), dev_inode(&path));
        if let Some((_, at, digest)) = read_before.iter().find(|(o, ..)| same_file_as(o, &id)) {
            out.digests
                .insert(path.display().to_string(), digest.clone());
            frames.push(frames[*at].clone());
            abs.push(path.display().to_string());
            continue;
        }
        let (s, digest) = load_series_read(&path, g.format, g.variable.as_deref(), read)
            .map_err(|e| load_issue("field.paths", &format!("file {k}: "), e))?;
        out.digests
            .insert(path.display().to_string(), digest.clone());
        read_before.push((id, frames.len(), digest));
        if s.frames.len() != 1 {
            return Err(Issue {
                key: "field.paths".to_string(),
                message: format!(
                    "file {k} ({}) holds {} frames; each file of field.paths must hold one",
                    path.display(),
                    s.frames.len()
                ),
                unreadable: false,
            });
        }
        out.notes.extend(s.warnings);
        out.file_units
            .extend(s.units.map(|u| (path.display().to_string(), u)));
        if k == 0 {
            *out.georef = s.georeference;
        }
        frames.extend(s.frames);
        abs.push(path.display().to_string());
    }
    Ok((frames, abs))
}

/// A `grid` field: one frame (a [`GridField`]) or a time series (a [`GridSeries`]) from
/// `field.path` (a 3-D `.npy` or a NetCDF with a time axis gives several frames) or
/// `field.paths` (one frame per file). Paths are recorded back as absolute.
fn build_grid(
    g: &GridSpec,
    units: Option<&str>,
    base_dir: &Path,
    into: Filling<'_>,
) -> Result<FieldModel, Issue> {
    let Filling {
        filled,
        notes,
        lonlat,
        digests,
    } = into;
    let GridFilesRead {
        raw,
        file_times,
        file_units,
        georef,
        one_file,
    } = read_grid_files(g, base_dir, filled, notes, digests, &read_limited)?;
    filled.units = adopt_file_units(units, &g.transform, &file_units, notes);
    // The file's own position of the (cropped) south-west node, and its spacing: what
    // field.origin_m and field.spacing_m replace.
    let natural = raw.first().map(|grid| {
        let o = match g.crop_cells {
            Some([c0, _, r0, _]) => grid.node_m(c0, r0),
            None => grid.origin_m(),
        };
        (o, grid.spacing_m())
    });
    let n = raw.len();
    let mut frames = Vec::with_capacity(n);
    for (k, grid) in raw.into_iter().enumerate() {
        frames.push(prepare_frame(g, grid).map_err(|mut i| {
            if n > 1 {
                i.message = format!("frame {k}: {}", i.message);
            }
            i
        })?);
    }
    if let Some(frame) = lonlat_frame(georef, natural, frames.first()) {
        *lonlat = Some(frame);
    }
    // Record what was used, so the resolved scenario reproduces the run from anywhere.
    filled.spacing_m = Some(frames[0].spacing_m());
    filled.origin_m = Some([frames[0].origin_m().x, frames[0].origin_m().y]);
    grid_in_time(g, frames, file_times, one_file.as_deref())
}

/// The prepared `frames` as one [`GridField`] (one frame, no times) or a [`GridSeries`] at the
/// scenario's frame times or the file's own (`file_times`, of `one_file`).
fn grid_in_time(
    g: &GridSpec,
    frames: Vec<Grid2>,
    file_times: Option<Vec<f64>>,
    one_file: Option<&str>,
) -> Result<FieldModel, Issue> {
    let issue = |key: &str, message: String| Issue {
        key: key.to_string(),
        message,
        unreadable: false,
    };
    let n = frames.len();
    let interp = g.interpolation;
    // Where the times come from, to blame the right key when they cannot make a series: a bad
    // time axis read from a file is the file's (`field.path`), not a default's.
    let (times, times_key, from_file) = match (&g.frame_times, file_times) {
        (FrameTimes::Given(t), _) => (Some(t.clone()), "field.frame_times_s", false),
        (FrameTimes::Interval(dt), _) => (
            Some((0..n).map(|k| k as f64 * dt).collect()),
            "field.frame_interval_s",
            false,
        ),
        (FrameTimes::FromFile, file) => (file, "field.path", true),
    };
    let times = match times {
        Some(t) => t,
        None if n == 1 => {
            let g = frames.into_iter().next().ok_or_else(|| issue("field.path", "no frame".into()))?;
            return Ok(FieldModel::Grid(GridField::new(g, interp)));
        }
        None => {
            return Err(issue(
                "field.frame_interval_s",
                format!("the file holds {n} frames and no frame times: give field.frame_interval_s or field.frame_times_s"),
            ))
        }
    };
    if times.len() != n {
        return Err(issue(
            "field.frame_times_s",
            format!("{} frame times for {n} frames", times.len()),
        ));
    }
    // Field time is measured from the first frame; the origin counts from there.
    let t0 = times[0];
    let series = GridSeries::new(
        frames,
        times.iter().map(|t| t - t0).collect(),
        interp,
        g.time_interpolation,
        g.time_origin_s,
        g.time_scale,
        g.after_last_frame,
    )
    .map_err(|e| {
        let e = e.to_string();
        let e = if from_file {
            format!(
                "the time axis read from {}: {e}",
                one_file.unwrap_or("the file")
            )
        } else {
            e
        };
        issue(times_key, e)
    })?;
    Ok(FieldModel::Series(Arc::new(series)))
}

/// Where a lon/lat grid's local metres are on the Earth: the file's local (0, 0) is
/// `(lon0, lat0)`, and local `p` is the file's `p - origin + o` (`natural`: the file's own
/// position `o` of the cropped south-west node, and its spacing). `None` for another
/// georeference, or when the scenario changes the spacing (`first`: the first frame as used).
fn lonlat_frame(
    georef: isotrack_fields::georef::Georeference,
    natural: Option<(Vec2, [f64; 2])>,
    first: Option<&Grid2>,
) -> Option<LonLatFrame> {
    let (
        isotrack_fields::georef::Georeference::LonLat {
            lon0_deg,
            lat0_deg,
            ref_lat_deg,
            ..
        },
        Some((o, sp)),
        Some(first),
    ) = (georef, natural, first)
    else {
        return None;
    };
    // Local p is the file's p - origin + o; the file's local (0, 0) is (lon0, lat0).
    if first.spacing_m() != sp {
        return None;
    }
    let k = isotrack_fields::georef::EARTH_RADIUS_M * std::f64::consts::PI / 180.0;
    let shift = o - first.origin_m();
    Some(LonLatFrame {
        lon0_deg: lon0_deg + shift.x / (k * ref_lat_deg.to_radians().cos()),
        lat0_deg: lat0_deg + shift.y / k,
        ref_lat_deg,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// att43-7: `field.paths` naming one file three times (as written, as `vdir/../vdir/`, and
    /// through a hard link) reads it once: the reader here gives other bytes at every later
    /// read (a file rewritten while the scenario loads), yet every frame is the first read's
    /// (its values, 1 to 9 as written) and every path's digest is that read's SHA-256. Before,
    /// each name was read again: three reads, frames of other content under one digest.
    #[test]
    fn a_file_named_twice_is_read_once() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("vdir")).unwrap();
        let first = b"1,2,3\n4,5,6\n7,8,9\n".to_vec();
        let later = b"9,9,9\n9,9,9\n9,9,9\n".to_vec();
        std::fs::write(d.path().join("vdir/v.csv"), &first).unwrap();
        std::fs::hard_link(d.path().join("vdir/v.csv"), d.path().join("h.csv")).unwrap();
        let text = "[field]\nkind = \"grid\"\npaths = [\"vdir/v.csv\", \"h.csv\", \"vdir/../vdir/v.csv\"]\nframe_times_s = [0.0, 100.0, 200.0]\n[initial]\nx_m = 1.0\ny_m = 1.0\n[controller]\nlevel = 5.0\n";
        let s = crate::parse_scenario_in(text, "s.toml", &[], d.path()).unwrap();
        let FieldKindSpec::Grid(g) = &s.spec().field.kind else {
            panic!("not a grid")
        };
        let mut g = g.clone();
        g.files = GridFiles::Paths(
            ["vdir/v.csv", "vdir/../vdir/v.csv", "h.csv"]
                .map(String::from)
                .to_vec(),
        );
        let reads = std::cell::Cell::new(0);
        let read = |_: &Path, _: u64| {
            reads.set(reads.get() + 1);
            Ok(if reads.get() == 1 {
                first.clone()
            } else {
                later.clone()
            })
        };
        let (mut filled, mut notes, mut digests) = Default::default();
        let got =
            read_grid_files(&g, d.path(), &mut filled, &mut notes, &mut digests, &read).unwrap();
        assert_eq!(reads.get(), 1);
        assert_eq!(got.raw.len(), 3);
        for f in &got.raw {
            // Row 0 is the file's first line (south), column 0 west: 1, 2, 3 along it.
            let row0: Vec<f64> = (0..3).map(|c| f.at(c, 0)).collect();
            let row2: Vec<f64> = (0..3).map(|c| f.at(c, 2)).collect();
            assert_eq!((row0, row2), (vec![1.0, 2.0, 3.0], vec![7.0, 8.0, 9.0]));
        }
        let sha = isotrack_fields::io::sha256_hex(&first);
        let want: BTreeMap<String, String> = [
            d.path().join("vdir/v.csv").canonicalize().unwrap(),
            d.path().join("h.csv").canonicalize().unwrap(),
        ]
        .into_iter()
        .map(|p| (p.display().to_string(), sha.clone()))
        .collect();
        assert_eq!(digests, want);
    }
}
