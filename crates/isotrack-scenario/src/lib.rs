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
pub use team::TeamIsolineModel;

use field::{build_field, FieldModel, IsolineOracle, LonLatFrame};
use std::path::Path;
use std::sync::{Arc, OnceLock};

/// A resolved, validated scenario with its field built (files read): ready to run, any number of
/// times (cloning shares the field).
#[derive(Clone, Debug)]
pub struct Scenario {
    /// The resolved keys: the user's, and every default resolution wrote (what `scenario.toml`
    /// records; sweeps and `--set` apply to it).
    file: ScenarioFile,
    /// Every setting in force, typed ([`spec`]).
    spec: spec::ScenarioSpec,
    field: Arc<FieldModel>,
    vehicle: Arc<vehicle::VehicleModel>,
    isoline: Arc<OnceLock<IsolineOracle>>,
    /// Warnings from the field's files ([`field::BuiltField::notes`]).
    field_notes: Arc<Vec<String>>,
    /// The `[field]` keys its files filled in (geometry, units), not the user's: a variant
    /// that reads another file drops them, so that the new file's own are used.
    file_filled_keys: Arc<Vec<String>>,
    /// Where a lon/lat grid's local metres are on the Earth ([`field::BuiltField::lonlat`]).
    lonlat: Option<LonLatFrame>,
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

/// The keys set in `after` but not in `before` (`path`/`paths`, made absolute, excepted).
fn filled_keys(before: &schema::FieldSection, after: &schema::FieldSection) -> Vec<String> {
    let (b, a) = (field_table(before), field_table(after));
    a.keys()
        .filter(|k| !b.contains_key(*k) && *k != "path" && *k != "paths")
        .cloned()
        .collect()
}

fn field_table(f: &schema::FieldSection) -> toml::Table {
    match toml::Value::try_from(f) {
        Ok(toml::Value::Table(t)) => t,
        _ => toml::Table::new(),
    }
}

/// Whether assignment `arg` (`KEY=VALUE`) names another source for the field's data.
fn names_another_field_source(arg: &str) -> bool {
    let key = arg.split_once('=').map_or("", |(k, _)| k.trim());
    matches!(
        key,
        "field" | "field.kind" | "field.path" | "field.paths" | "field.variable" | "field.format"
    )
}

impl PartialEq for Scenario {
    fn eq(&self, other: &Self) -> bool {
        self.file == other.file
    }
}

impl Scenario {
    /// Resolves `file` (defaults, checks) and builds its field, reading files relative to
    /// `base_dir`.
    pub fn from_file(file: ScenarioFile, base_dir: &Path) -> Result<Self, Vec<resolve::Issue>> {
        let mut file = resolve::resolve(file)?;
        let built = build_field_of(&file, base_dir).map_err(|i| vec![i])?;
        let given = file.field.clone();
        built.filled.record(&mut file.field);
        let filled = filled_keys(&given, &file.field);
        let (field, notes, lonlat) = (built.model, built.notes, built.lonlat);
        field::check_start(start_xy(&file).map_err(|i| vec![i])?, &field).map_err(|i| vec![i])?;
        let vehicle = vehicle::build_vehicle(&file).map_err(|i| vec![i])?;
        let spec = spec::ScenarioSpec::new(&file, vehicle.airframe_turn_rate_limit_radps())
            .map_err(|i| vec![i])?;
        Ok(Self {
            file,
            spec,
            field: Arc::new(field),
            vehicle: Arc::new(vehicle),
            isoline: Arc::new(OnceLock::new()),
            field_notes: Arc::new(notes),
            file_filled_keys: Arc::new(filled),
            lonlat,
        })
    }

    /// A variant of this scenario with `KEY=VALUE` overrides applied to its resolved keys. The
    /// field, vehicle and true isoline are shared with `self` (not rebuilt, files not re-read)
    /// when the variant leaves their sections and the level unchanged: sweeps stay cheap and
    /// their memory flat.
    ///
    /// Problems are located at the override (`{origin}: KEY=VALUE`) or as inherited from `self`.
    pub fn derive(&self, overrides: &[String], origin: &str) -> Result<Self, ScenarioError> {
        let assignments: Vec<Assignment> = overrides
            .iter()
            .map(|o| Assignment::new(o.clone(), origin))
            .collect();
        self.derive_with(&assignments, origin)
    }

    /// As [`Scenario::derive`], each assignment carrying its own label for messages.
    pub fn derive_with(
        &self,
        assignments: &[Assignment],
        origin: &str,
    ) -> Result<Self, ScenarioError> {
        // Another file: the keys the old file filled in (its geometry, its units) are not the
        // user's and must not override the new file's own (a hostile review: a sweep over
        // `field.path` ran every file on the first one's grid).
        let new_source = assignments
            .iter()
            .any(|a| names_another_field_source(&a.arg));
        let file = if new_source && !self.file_filled_keys.is_empty() {
            let mut base = self.file.clone();
            let mut t = field_table(&base.field);
            for k in self.file_filled_keys.iter() {
                t.remove(k);
            }
            base.field = toml::Value::Table(t).try_into().unwrap_or(base.field);
            apply_assignments(&base, assignments)?
        } else {
            apply_assignments(&self.file, assignments)?
        };
        let located = |issues: Vec<resolve::Issue>| locate_derived(issues, origin, assignments);
        let mut file = resolve::resolve(file).map_err(located)?;
        // A puff plume's meander follows sim.seed: a new seed is a new field.
        let seeded =
            matches!(*self.field, FieldModel::Puff(_)) && file.sim.seed != self.file.sim.seed;
        let mut lonlat = self.lonlat;
        let (field, field_notes, file_filled_keys) = if file.field == self.file.field && !seeded {
            (
                self.field.clone(),
                self.field_notes.clone(),
                self.file_filled_keys.clone(),
            )
        } else {
            let built = build_field_of(&file, Path::new(".")).map_err(|i| located(vec![i]))?;
            let given = file.field.clone();
            built.filled.record(&mut file.field);
            let mut filled = filled_keys(&given, &file.field);
            if !new_source {
                filled.extend(self.file_filled_keys.iter().cloned());
            }
            lonlat = built.lonlat;
            (
                Arc::new(built.model),
                Arc::new(built.notes),
                Arc::new(filled),
            )
        };
        let start = start_xy(&file).map_err(|i| located(vec![i]))?;
        field::check_start(start, &field).map_err(|i| located(vec![i]))?;
        let same_vehicle = file.vehicle == self.file.vehicle && file.sim.seed == self.file.sim.seed;
        let vehicle = if same_vehicle {
            self.vehicle.clone()
        } else {
            Arc::new(vehicle::build_vehicle(&file).map_err(|i| located(vec![i]))?)
        };
        let isoline = if Arc::ptr_eq(&field, &self.field)
            && file.controller.level == self.file.controller.level
        {
            self.isoline.clone()
        } else {
            Arc::new(OnceLock::new())
        };
        let spec = spec::ScenarioSpec::new(&file, vehicle.airframe_turn_rate_limit_radps())
            .map_err(|i| located(vec![i]))?;
        Ok(Self {
            file,
            spec,
            field,
            vehicle,
            isoline,
            field_notes,
            file_filled_keys,
            lonlat,
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
        let mut file = self.file.clone();
        file.controller = file.controller.switched_to(kind);
        let origin = format!("controller.kind = \"{}\"", kind.name());
        let file = resolve::resolve(file).map_err(|issues| locate_derived(issues, &origin, &[]))?;
        let spec = spec::ScenarioSpec::new(&file, self.vehicle.airframe_turn_rate_limit_radps())
            .map_err(|i| locate_derived(vec![i], &origin, &[]))?;
        Ok(Self {
            file,
            spec,
            field: self.field.clone(),
            vehicle: self.vehicle.clone(),
            isoline: self.isoline.clone(),
            field_notes: self.field_notes.clone(),
            file_filled_keys: self.file_filled_keys.clone(),
            lonlat: self.lonlat,
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

    /// Every setting in force, typed, the derived ones computed (read settings here, not from
    /// [`Scenario::file`]).
    pub fn spec(&self) -> &spec::ScenarioSpec {
        &self.spec
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
