//! # isotrack-scenario
//!
//! A scenario is a TOML file describing one run: `[field]`, `[vehicle]`, `[initial]`, `[sensor]`,
//! `[controller]`, `[sim]`, `[metrics]`, `[output]`. Every key has a default (the paper's
//! Fig. 2(b) setting), so an empty file is a valid scenario and the built-in default.
//!
//! * [`schema`]: the sections and keys (the file format, documented key by key).
//! * [`load`]: reading a file, applying `--set KEY=VALUE` overrides, and errors that name the file,
//!   line and key ([`ScenarioError`]).
//! * [`resolve`]: filling defaults and validating values, giving a [`Scenario`] whose every key is
//!   explicit (what `summary.json` records).
//! * [`build`]: turning a resolved scenario into field, vehicle, sensor and controller, and
//!   running it ([`Scenario::run`]).
#![deny(missing_docs)]

pub mod assign;
mod batch;
pub mod build;
pub mod check;
pub mod episode;
pub mod error;
pub mod field;
mod issue;
pub mod load;
pub mod ranges;
pub mod resolve;
pub mod schema;
pub mod spec;
pub mod sweep;
mod team;
pub mod tomltext;
pub mod vehicle;
mod watch;

use assign::locate_derived;
pub use assign::{apply_assignments, Assignment};
pub use build::{ControllerModel, Tracker};
pub use episode::{ScenarioEpisode, Start};
pub use error::{ErrorLocation, LocatedIssue, ScenarioError};
pub use load::{
    build_derived, load_scenario, parse_scenario, parse_scenario_in, MAX_SCENARIO_FILE_BYTES,
};
pub use schema::ScenarioFile;
pub use team::{TeamIsolineModel, ARC_REFERENCE_NO_ISOLINE, ARC_REFERENCE_WITHOUT_ARC};

use field::{build_field, FieldModel, IsolineOracle, LonLatFrame};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// A resolved, validated scenario with its field built (files read): ready to run, any number of
/// times. Cloning shares everything (the keys, the settings, the field): a clone costs the same
/// whatever the scenario holds (mem45: a team's `team.starts` list, `N` starts, was copied into
/// each of the `N` vehicles `plot` and `report` read, `O(N^2)` memory).
#[derive(Clone, Debug)]
pub struct Scenario {
    /// The resolved keys: the user's, and every default resolution wrote (what `scenario.toml`
    /// records).
    file: Arc<ScenarioFile>,
    /// The user's own keys ([`Scenario::given`]): what [`Scenario::derive`] and sweeps apply
    /// their assignments to before resolving once.
    given: Arc<ScenarioFile>,
    /// Every setting in force, typed ([`spec`]).
    spec: Arc<spec::ScenarioSpec>,
    field: Arc<FieldModel>,
    vehicle: Arc<vehicle::VehicleModel>,
    isoline: Arc<OnceLock<IsolineOracle>>,
    /// Warnings from the field's files ([`field::BuiltField::notes`]).
    field_notes: Arc<Vec<String>>,
    /// The `[field]` section as resolution left it, before its files filled keys in (paths
    /// absolute): a variant whose resolved `[field]` is this one shares the field.
    resolved_field: Arc<schema::FieldSection>,
    /// Where a lon/lat grid's local metres are on the Earth ([`field::BuiltField::lonlat`]).
    lonlat: Option<LonLatFrame>,
    /// The SHA-256 of each data file the field was read from, as read
    /// ([`field::BuiltField::digests`]).
    digests: Arc<BTreeMap<String, String>>,
}

/// The field of a resolved file, built from its spec ([`spec::FieldSpec`], read before the
/// files fill their keys), with `sim.seed` seeding a puff plume's meander.
fn build_field_of(
    file: &ScenarioFile,
    base_dir: &Path,
) -> Result<field::BuiltField, resolve::Issue> {
    let seed = spec::SimSpec::new(&file.sim)?.seed;
    build_field(&spec::FieldSpec::new(&file.field, seed)?, base_dir)
}

/// The start position `[x, y]` of a resolved file, m.
fn start_xy(file: &ScenarioFile) -> Result<[f64; 2], resolve::Issue> {
    let s = spec::sim::start(&file.initial)?;
    Ok([s.x_m, s.y_m])
}

/// Whether `[initial]`'s position places a vehicle: a single vehicle, a team of one without
/// `team.starts` or `team.spread`, or a line spread without its own `x_m` and `y_m` (its first
/// start defaults to `[initial]`'s). With `team.starts`, an arc spread or a line spread with its
/// own position, `[initial]` flies nobody and is not checked against the field (nu-14: the
/// unused default start (10, 0) m outside a `domain_m` refused a team whose starts were all
/// inside).
fn initial_places_a_vehicle(file: &ScenarioFile) -> bool {
    let Some(t) = &file.team else {
        return true;
    };
    match (&t.starts, &t.spread) {
        (Some(_), _) => false,
        (None, Some(sp)) => {
            sp.along == Some(schema::SpreadAlong::Line) && (sp.x_m.is_none() || sp.y_m.is_none())
        }
        (None, None) => true,
    }
}

/// The vehicle (`vehicle`, when the caller shares one already built) and the spec of resolved
/// `file`, its starts checked against `field`: `[initial]`'s `start` where it places a vehicle
/// ([`initial_places_a_vehicle`]), every team vehicle's start. Every value error found is
/// listed (nu-14: a start outside the field hid a `team.starts`/`team.spread` conflict).
fn checked_parts(
    file: &ScenarioFile,
    start: [f64; 2],
    field: &FieldModel,
    vehicle: Option<Arc<vehicle::VehicleModel>>,
) -> Result<(Arc<vehicle::VehicleModel>, spec::ScenarioSpec), Vec<resolve::Issue>> {
    let mut issues = Vec::new();
    if initial_places_a_vehicle(file) {
        if let Err(i) = field::check_start(start, field) {
            issues.push(i);
        }
    }
    let vehicle = match vehicle {
        Some(v) => v,
        None => match vehicle::build_vehicle(file) {
            Ok(v) => Arc::new(v),
            Err(i) => {
                issues.push(i);
                return Err(issues);
            }
        },
    };
    let spec = match spec::ScenarioSpec::new(file, vehicle.airframe_turn_rate_limit_radps()) {
        Ok(s) => s,
        Err(i) => {
            issues.push(i);
            return Err(issues);
        }
    };
    if let Some(t) = &spec.team {
        if let Err(i) = field::check_team_starts(file.team.as_ref(), &t.starts, field) {
            issues.push(i);
        }
    }
    if issues.is_empty() {
        Ok((vehicle, spec))
    } else {
        Err(issues)
    }
}

/// `[field]` with the data files named as the built field read them (`field.path`,
/// `field.paths` made absolute, [`field::FileFilled`]), its other keys as they are: the user's
/// keys then name the same files from any directory.
fn with_absolute_paths(
    section: &schema::FieldSection,
    filled: &field::FileFilled,
) -> schema::FieldSection {
    let mut s = section.clone();
    if filled.path.is_some() {
        s.path.clone_from(&filled.path);
    }
    if filled.paths.is_some() {
        s.paths.clone_from(&filled.paths);
    }
    s
}

/// A field built for a resolved file: the model and its notes, the resolved `[field]` before
/// the files filled keys in (paths absolute), and where a lon/lat grid is.
struct FieldParts {
    model: Arc<FieldModel>,
    notes: Arc<Vec<String>>,
    resolved_field: Arc<schema::FieldSection>,
    lonlat: Option<LonLatFrame>,
    digests: Arc<BTreeMap<String, String>>,
}

/// Builds the field of resolved `file` (files relative to `base_dir`), records the keys its
/// files filled into `file` and names the files by absolute path in `given` (the user's keys).
fn build_recorded(
    file: &mut ScenarioFile,
    given: &mut ScenarioFile,
    base_dir: &Path,
) -> Result<FieldParts, resolve::Issue> {
    let built = build_field_of(file, base_dir)?;
    given.field = with_absolute_paths(&given.field, &built.filled);
    let resolved_field = with_absolute_paths(&file.field, &built.filled);
    built.filled.record(&mut file.field);
    Ok(FieldParts {
        model: Arc::new(built.model),
        notes: Arc::new(built.notes),
        resolved_field: Arc::new(resolved_field),
        lonlat: built.lonlat,
        digests: Arc::new(built.digests),
    })
}

impl PartialEq for Scenario {
    fn eq(&self, other: &Self) -> bool {
        self.file == other.file
    }
}

impl Scenario {
    /// Resolves `file` (defaults, checks) and builds its field, reading files relative to
    /// `base_dir`. `file` is the user's keys ([`Scenario::given`]).
    pub fn from_file(file: ScenarioFile, base_dir: &Path) -> Result<Self, Vec<resolve::Issue>> {
        let mut given = file.clone();
        let mut file = resolve::resolve(file)?;
        let parts = build_recorded(&mut file, &mut given, base_dir).map_err(|i| vec![i])?;
        let start = start_xy(&file).map_err(|i| vec![i])?;
        let (vehicle, spec) = checked_parts(&file, start, &parts.model, None)?;
        Ok(Self {
            file: Arc::new(file),
            given: Arc::new(given),
            spec: Arc::new(spec),
            field: parts.model,
            vehicle,
            isoline: Arc::new(OnceLock::new()),
            field_notes: parts.notes,
            resolved_field: parts.resolved_field,
            lonlat: parts.lonlat,
            digests: parts.digests,
        })
    }

    /// A variant of this scenario: its own keys ([`Scenario::given`]) with the `KEY=VALUE`
    /// overrides applied, resolved once, exactly as `isotrack run FILE --set ...` (a default
    /// that follows another key follows the override: `sim.dt_s = 0.02` samples at 50 Hz
    /// where `sensor.rate_hz` is unset). The field, vehicle and true isoline are shared with
    /// `self` (not rebuilt, files not re-read) when the variant leaves their sections and the
    /// level unchanged: sweeps stay cheap and their memory flat.
    ///
    /// Problems are located at the override (`{origin}: KEY=VALUE`) or as inherited from `self`.
    pub fn derive(&self, overrides: &[String], origin: &str) -> Result<Self, ScenarioError> {
        let assignments: Vec<Assignment> = overrides
            .iter()
            .map(|o| Assignment::new(o.clone(), origin))
            .collect();
        self.derive_with(&assignments, origin)
    }

    /// As [`Scenario::derive`], each assignment carrying its own label for messages; a
    /// relative file path an assignment gives (`field.path`, `field.paths`) is relative to the
    /// working directory, as a Python `Scenario.set` is.
    pub fn derive_with(
        &self,
        assignments: &[Assignment],
        origin: &str,
    ) -> Result<Self, ScenarioError> {
        self.derive_with_in(assignments, origin, Path::new("."))
    }

    /// As [`Scenario::derive_with`], a relative file path an assignment gives relative to
    /// `base_dir`: a sweep's `[base]`, `[grid]` and `[random]` paths are relative to the sweep
    /// file, as its `scenario` is (issue 30, ver30-1: they were relative to the working
    /// directory, so `--resume` from another directory could not read them).
    pub fn derive_with_in(
        &self,
        assignments: &[Assignment],
        origin: &str,
        base_dir: &Path,
    ) -> Result<Self, ScenarioError> {
        let given = apply_assignments(&self.given, assignments)?;
        let no_team = self.given.team.is_none();
        let located = |issues: Vec<resolve::Issue>| {
            let e = locate_derived(issues, origin, assignments);
            if no_team {
                assign::blame_team_onto_no_team(e, assignments)
            } else {
                e
            }
        };
        self.derived_from(given, &located, base_dir)
    }

    /// A variant of this scenario from a whole scenario file `file` (this scenario's resolved
    /// file with keys changed: `compare`'s law and its `--gain`s), resolved and built as
    /// [`build_derived`] builds it (problems located at the assignment that set the key, else
    /// against `origin`), but flying this scenario's field itself, no file read again, when
    /// its resolved `[field]` is this one's (att41-8: `compare` read the field once per law, so
    /// a data file replaced meanwhile gave its laws different fields). Files a changed
    /// `[field]` names are relative to `base_dir`.
    pub fn variant_of_file(
        &self,
        file: ScenarioFile,
        origin: &str,
        assignments: &[Assignment],
        base_dir: &Path,
    ) -> Result<Self, ScenarioError> {
        let located = |issues: Vec<resolve::Issue>| locate_derived(issues, origin, assignments);
        self.derived_from(file, &located, base_dir)
    }

    /// The variant whose own keys are `given`: resolved once; this scenario's field, notes,
    /// digests, vehicle and isoline shared where its resolved sections leave them unchanged
    /// (the `[field]` as resolution left it, or as the files filled it in), else built again
    /// (files relative to `base_dir`).
    fn derived_from(
        &self,
        mut given: ScenarioFile,
        located: &dyn Fn(Vec<resolve::Issue>) -> ScenarioError,
        base_dir: &Path,
    ) -> Result<Self, ScenarioError> {
        let mut file = resolve::resolve(given.clone()).map_err(located)?;
        // A puff plume's meander follows sim.seed: a new seed is a new field.
        let seeded =
            matches!(*self.field, FieldModel::Puff(_)) && file.sim.seed != self.file.sim.seed;
        let same_field = file.field == *self.resolved_field || file.field == self.file.field;
        let parts = if same_field && !seeded {
            // The same resolved section reads the same files: the keys they filled are this
            // scenario's.
            file.field = self.file.field.clone();
            FieldParts {
                model: self.field.clone(),
                notes: self.field_notes.clone(),
                resolved_field: self.resolved_field.clone(),
                lonlat: self.lonlat,
                digests: self.digests.clone(),
            }
        } else {
            // Another source or other keys: its files are read again and fill their own keys
            // (a hostile review: a sweep over `field.path` once ran every file on the first
            // one's grid).
            build_recorded(&mut file, &mut given, base_dir).map_err(|i| located(vec![i]))?
        };
        let start = start_xy(&file).map_err(|i| located(vec![i]))?;
        let same_vehicle = file.vehicle == self.file.vehicle && file.sim.seed == self.file.sim.seed;
        let (vehicle, spec) = checked_parts(
            &file,
            start,
            &parts.model,
            same_vehicle.then(|| self.vehicle.clone()),
        )
        .map_err(located)?;
        let isoline = if Arc::ptr_eq(&parts.model, &self.field)
            && file.controller.level == self.file.controller.level
        {
            self.isoline.clone()
        } else {
            Arc::new(OnceLock::new())
        };
        Ok(Self {
            file: Arc::new(file),
            given: Arc::new(given),
            spec: Arc::new(spec),
            field: parts.model,
            vehicle,
            isoline,
            field_notes: parts.notes,
            resolved_field: parts.resolved_field,
            lonlat: parts.lonlat,
            digests: parts.digests,
        })
    }

    /// This scenario flown by the built-in law `kind` (see
    /// [`schema::ControllerSection::switched_to`]: the law's defaults, the shared keys kept);
    /// the field, vehicle and isoline are shared, not rebuilt.
    pub fn with_controller_kind(
        &self,
        kind: schema::ControllerKind,
    ) -> Result<Self, ScenarioError> {
        if self.file.controller.kind == Some(kind) {
            return Ok(self.clone());
        }
        let mut file = (*self.file).clone();
        file.controller = file.controller.switched_to(kind);
        let mut given = (*self.given).clone();
        given.controller = given.controller.switched_to(kind);
        let origin = format!("controller.kind = \"{}\"", kind.name());
        let file = resolve::resolve(file).map_err(|issues| locate_derived(issues, &origin, &[]))?;
        let spec = spec::ScenarioSpec::new(&file, self.vehicle.airframe_turn_rate_limit_radps())
            .map_err(|i| locate_derived(vec![i], &origin, &[]))?;
        Ok(Self {
            file: Arc::new(file),
            given: Arc::new(given),
            spec: Arc::new(spec),
            field: self.field.clone(),
            vehicle: self.vehicle.clone(),
            isoline: self.isoline.clone(),
            field_notes: self.field_notes.clone(),
            resolved_field: self.resolved_field.clone(),
            lonlat: self.lonlat,
            digests: self.digests.clone(),
        })
    }

    /// Where the field's local metres are on the Earth, when its file is a longitude/latitude
    /// grid whose spacing the scenario keeps ([`field::BuiltField::lonlat`]).
    pub fn lonlat_frame(&self) -> Option<LonLatFrame> {
        self.lonlat
    }

    /// Whether the field changes with time: a grid time series, a puff plume, or an analytic
    /// field with a drift.
    pub fn is_time_varying(&self) -> bool {
        match &*self.field {
            FieldModel::Series(_) | FieldModel::Puff(_) => true,
            FieldModel::Analytic(a) => a.drift_mps != isotrack_core::Vec2::default(),
            FieldModel::Grid(_) => false,
        }
    }

    /// Whether the vehicle flies (its trace has altitude, airspeed and roll).
    pub fn is_flying(&self) -> bool {
        matches!(*self.vehicle, vehicle::VehicleModel::FixedWing(_))
    }

    /// The field.
    pub fn field(&self) -> &FieldModel {
        &self.field
    }

    /// The true isoline of the tracked level (built on first use, then shared).
    pub fn isoline(&self) -> &IsolineOracle {
        self.isoline
            .get_or_init(|| IsolineOracle::new(&self.field, self.level()))
    }

    /// The resolved keys (serialise this to record the exact run; it reads back as the same
    /// scenario).
    pub fn file(&self) -> &ScenarioFile {
        &self.file
    }

    /// The user's own keys: the scenario file with its `--set` overrides (and a sweep's
    /// `[base]` and run assignments), every default left unset, the field's data files named
    /// by absolute path. Resolving it gives [`Scenario::file`]; a sweep keeps it as
    /// `base_scenario.toml`, so that `isotrack run base_scenario.toml --set ...` resolves a
    /// run's keys once, as the sweep does.
    pub fn given(&self) -> &ScenarioFile {
        &self.given
    }

    /// Whether `other` flies this scenario's field itself, as read when it was made (the same
    /// built field: a variant whose resolved `[field]` is unchanged shares it and reads no file
    /// again, see [`Scenario::derive_with_in`]); `false` when either one read its files itself.
    pub fn shares_field_with(&self, other: &Scenario) -> bool {
        Arc::ptr_eq(&self.field, &other.field)
    }

    /// Every setting in force, typed, the derived ones computed (read settings here, not from
    /// [`Scenario::file`]).
    pub fn spec(&self) -> &spec::ScenarioSpec {
        &self.spec
    }

    /// The SHA-256 of each data file the field was read from (`field.path`, `field.paths`), by
    /// absolute path, of the bytes the field was parsed from (read once: att41-22); empty for a
    /// field read from no file. A variant sharing this field ([`Scenario::derive`],
    /// [`Scenario::with_controller_kind`]) shares these; one that read its files again has its
    /// own. What `summary.json`'s `data_files` records.
    pub fn data_file_digests(&self) -> &BTreeMap<String, String> {
        &self.digests
    }

    /// Warnings the field's files give (a grid file's `units` against `field.units`): part of
    /// [`check::warnings`], which `run` prints and `check` reports.
    pub fn field_warnings(&self) -> &[String] {
        &self.field_notes
    }

    /// The built-in default: the paper's Fig. 2(b) setting (what an empty file resolves to).
    pub fn default_paper_fig2b() -> Self {
        Self::from_file(ScenarioFile::default(), Path::new("."))
            .expect("the built-in default scenario is valid")
    }
}
