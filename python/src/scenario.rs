//! The `Scenario` class: a resolved scenario, its overrides, its runs, its field's values and
//! its check.

use crate::controller::PyController;
use crate::errors::{scenario_err, ScenarioErrorPy};
use crate::guard::{self, no_panic, SignalWatch};
use crate::values::{as_written, check_key, toml_literal, toml_value};
use isotrack_core::{ScalarField, Vec2};
use isotrack_runs::trace::{TELEMETRY_COLUMNS, TRACE_COLUMNS};
use isotrack_scenario::{load_scenario, parse_scenario, Scenario};
use isotrack_sim::{RunResult, TraceRow};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// A resolved scenario (every default filled in). Immutable: `set` returns a new one.
#[pyclass(name = "Scenario", module = "isotrack._native", frozen)]
pub(crate) struct PyScenario {
    pub(crate) inner: Scenario,
    /// Names the scenario in messages (the path as given to `from_file`, `<toml>`, ...).
    pub(crate) origin: String,
    /// The absolute folder a relative file path given to `set` is read against: the scenario
    /// file's folder as it was when the file was read (`from_file`; a sweep's folder for the
    /// scenarios of a sweep), `None` for the working directory (`default()`, `from_toml`).
    /// Taken once, never looked up again from `origin` (att30n-4: after a `chdir` the same
    /// `set` read another file), and kept by every scenario derived from this one and through
    /// pickling (att30n-11).
    pub(crate) folder: Option<PathBuf>,
}

#[pymethods]
impl PyScenario {
    /// The built-in default: the paper's Fig. 2(b) setting.
    #[staticmethod]
    fn default() -> PyResult<Self> {
        let inner = no_panic(|| load_scenario(None, &[]).map_err(scenario_err))?;
        Ok(Self {
            inner,
            origin: "<built-in default>".into(),
            folder: None,
        })
    }

    /// A scenario file (TOML); files it names are relative to it.
    #[staticmethod]
    fn from_file(path: &str) -> PyResult<Self> {
        let inner = no_panic(|| load_scenario(Some(Path::new(path)), &[]).map_err(scenario_err))?;
        Ok(Self {
            inner,
            origin: path.to_string(),
            folder: Some(absolute_folder(Path::new(path))),
        })
    }

    /// Scenario text (TOML); files it names are relative to the current directory.
    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Self> {
        let inner = no_panic(|| parse_scenario(text, "<toml>", &[]).map_err(scenario_err))?;
        Ok(Self {
            inner,
            origin: "<toml>".into(),
            folder: None,
        })
    }

    /// A new scenario with the dotted `key` set to `value` (the rules of `--set`; errors are
    /// raised as `isotrack.ScenarioError` with the CLI's message). The key is checked to be a
    /// dotted key and the value converted to TOML here: neither is ever read as TOML text.
    fn set(&self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Self> {
        no_panic(|| {
            check_key(key)?;
            let v = toml_value(key, value, 0)?;
            let literal = toml_literal(&v);
            let inner = self.derive(&[format!("{key}={literal}")]).map_err(|e| {
                // A table's error is said of the key inside it that is wrong, as `--set
                // controller.kp=true` says it (ver30b-10): each of its keys set alone,
                // the first refused named.
                let m = self
                    .inner_error(key, &v)
                    .unwrap_or_else(|| as_written(&e.to_string(), value));
                ScenarioErrorPy::new_err(crate::values::no_type_names(&m))
            })?;
            Ok(Self {
                inner,
                origin: self.origin.clone(),
                folder: self.folder.clone(),
            })
        })
    }

    /// A new scenario with every `(key, value)` of `pairs` set at once (the rules of several
    /// `--set` in one command line): keys that bound each other (`team.v_min_mps` and
    /// `vehicle.speed_mps`, say) are checked together, in whatever order they are given, where
    /// [`set`](Self::set) one at a time checks each against the others' current values.
    fn set_many(&self, py: Python<'_>, pairs: Vec<(String, Py<PyAny>)>) -> PyResult<Self> {
        no_panic(|| {
            let mut sets = Vec::with_capacity(pairs.len());
            let mut keys = Vec::with_capacity(pairs.len());
            for (key, value) in &pairs {
                check_key(key)?;
                let v = toml_value(key, value.bind(py), 0)?;
                let mut set = Vec::new();
                crate::values::keys_set(key, &v, &mut set);
                keys.push(set);
                sets.push(format!("{key}={}", toml_literal(&v)));
            }
            let names: Vec<&str> = pairs.iter().map(|(k, _)| k.as_str()).collect();
            crate::values::check_once(&names, &keys)?;
            let inner = self.derive(&sets).map_err(|e| {
                let m = e.to_string();
                ScenarioErrorPy::new_err(crate::values::no_type_names(&match pairs.as_slice() {
                    [(_, value)] => as_written(&m, value.bind(py)),
                    _ => m,
                }))
            })?;
            Ok(Self {
                inner,
                origin: self.origin.clone(),
                folder: self.folder.clone(),
            })
        })
    }

    /// The data files the scenario's field reads (`field.path`, every `field.paths` entry),
    /// absolute, in the scenario's order: what `summary.json`'s `data_files` records.
    fn data_files(&self) -> Vec<String> {
        self.inner
            .spec()
            .field
            .data_files()
            .into_iter()
            .map(str::to_string)
            .collect()
    }

    /// The SHA-256 (lowercase hex) of each data file by absolute path, of the bytes the field
    /// was parsed from (one read: `Scenario::data_file_digests`), so the digest Python keeps
    /// is the field's and never a second read's (a file changed between the two would be
    /// recorded as flown while the old field flew).
    fn data_file_digests(&self) -> std::collections::BTreeMap<String, String> {
        self.inner.data_file_digests().clone()
    }

    /// Whether `other` flies this scenario's field as it was read (no file read again since):
    /// a `set` of keys outside the resolved `[field]` shares it.
    fn shares_field(&self, other: &PyScenario) -> bool {
        self.inner.shares_field_with(&other.inner)
    }

    /// The scenario's name in messages (the path given to `from_file`, `<toml>`, ...).
    #[getter]
    fn origin(&self) -> &str {
        &self.origin
    }

    /// The folder (absolute) a relative file path given to `set` is read against, `None` for
    /// the working directory at the time of the `set` (what pickling carries).
    #[getter]
    fn folder(&self) -> Option<String> {
        self.folder
            .as_ref()
            .map(|f| f.to_string_lossy().into_owned())
    }

    /// This scenario named `origin` in messages, a relative file path given to `set` read
    /// against `folder` (`None`: the working directory): an unpickled scenario takes back the
    /// folder and name it was pickled with.
    #[pyo3(signature = (origin, folder=None))]
    fn relocated(&self, origin: &str, folder: Option<&str>) -> Self {
        Self {
            inner: self.inner.clone(),
            origin: origin.to_string(),
            folder: folder.map(PathBuf::from),
        }
    }

    /// The level `s_d` the scenario tracks (field units).
    #[getter]
    fn level(&self) -> f64 {
        self.inner.level()
    }

    /// The turn-rate limit applied to every controller's command, rad/s (`None`: no limit).
    #[getter]
    fn max_turn_rate_radps(&self) -> Option<f64> {
        self.inner.max_turn_rate_radps()
    }

    /// The resolved scenario as TOML (what `isotrack show` prints).
    fn to_toml(&self) -> String {
        isotrack_runs::summary::scenario_toml(&self.inner)
    }

    /// Runs the scenario: `(summary_json, trace_columns, scenario_flown)`. `record_rate_hz` overrides
    /// `output.record_rate_hz`; `controller` (an object with `update(t_s, value) -> omega` and
    /// an optional `reset()`) replaces the scenario's controller.
    #[pyo3(signature = (record_rate_hz=None, controller=None))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        record_rate_hz: Option<f64>,
        controller: Option<Py<PyAny>>,
    ) -> PyResult<(String, Bound<'py, PyDict>, PyScenario)> {
        if self.inner.spec().team.is_some() {
            return Err(PyValueError::new_err(
                "[team]: Scenario.run() runs one vehicle; a team is run by `isotrack run` only, for now (docs/TEAMS.md)",
            ));
        }
        no_panic(|| self.run_inner(py, record_rate_hz, controller))
    }

    /// The field's values at `(x, y)` (numpy arrays of one shape, m) at time `t` (s, within the
    /// run: `0 <= t <= sim.duration_s`); NaN where the field has no value.
    #[pyo3(signature = (x, y, t=0.0))]
    fn field_values<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        no_panic(|| self.field_values_inner(py, x, y, t))
    }

    /// `isotrack check --json` for this scenario; `tube_halfwidth` (field units) > 0.
    #[pyo3(signature = (tube_halfwidth=None))]
    fn check_json(&self, py: Python<'_>, tube_halfwidth: Option<f64>) -> PyResult<String> {
        if let Some(h) = tube_halfwidth {
            if !(h.is_finite() && h > 0.0) {
                return Err(PyValueError::new_err(format!(
                    "tube_halfwidth must be a finite number > 0 (field units), got {h:?}"
                )));
            }
        }
        // Ctrl-C answered at once (a puff plume's check over a long run takes minutes); the
        // check itself cannot be cancelled and finishes on its own thread, its answer dropped.
        let scenario = self.inner.clone();
        guard::detached(py, move || {
            serde_json::to_string(&isotrack_scenario::check::check(&scenario, tube_halfwidth))
        })?
        .map_err(|e| PyValueError::new_err(e.to_string()))
    }
}

impl PyScenario {
    /// This scenario with `KEY=VALUE` overrides applied, as `isotrack run FILE --set ...`: a
    /// relative file path an override gives (`field.path`, `field.paths`) is relative to the
    /// scenario file's folder for a scenario read from a file (the CLI's rule, nu-12: the same
    /// `set` once named another file from Python), taken when the file was read (`folder`),
    /// to the working directory otherwise (`default()`, `from_toml`, as their own paths are).
    fn derive(&self, overrides: &[String]) -> Result<Scenario, isotrack_scenario::ScenarioError> {
        let assignments: Vec<isotrack_scenario::Assignment> = overrides
            .iter()
            .map(|o| isotrack_scenario::Assignment::new(o.clone(), &self.origin))
            .collect();
        let folder = self.folder.as_deref().unwrap_or(Path::new("."));
        self.inner
            .derive_with_in(&assignments, &self.origin, folder)
    }

    /// The error of the first key inside the table `v` (set at `key`) that is refused when set
    /// alone as a dotted key; `None` when `v` is no table or each of its keys is taken alone.
    fn inner_error(&self, key: &str, v: &toml::Value) -> Option<String> {
        if !matches!(v, toml::Value::Table(_)) {
            return None;
        }
        let mut leaves = Vec::new();
        crate::values::leaves(key, v, &mut leaves);
        leaves.into_iter().find_map(|(k, x)| {
            self.derive(&[format!("{k}={}", toml_literal(x))])
                .err()
                .map(|e| e.to_string())
        })
    }

    fn run_inner<'py>(
        &self,
        py: Python<'py>,
        record_rate_hz: Option<f64>,
        controller: Option<Py<PyAny>>,
    ) -> PyResult<(String, Bound<'py, PyDict>, PyScenario)> {
        let scenario = match record_rate_hz {
            Some(r) if !r.is_finite() => {
                return Err(ScenarioErrorPy::new_err(format!(
                    "`output.record_rate_hz`: {r:?} is not a finite number"
                )))
            }
            Some(r) => self
                .inner
                .derive(
                    &[format!(
                        "output.record_rate_hz={}",
                        toml_literal(&toml::Value::Float(r))
                    )],
                    &self.origin,
                )
                .map_err(scenario_err)?,
            None => self.inner.clone(),
        };
        let mut rows: Vec<TraceRow> = Vec::new();
        let mut watch = SignalWatch::new();
        let (result, failure) = match controller {
            None => (
                py.detach(|| scenario.run_watched(&mut rows, &mut || watch.keep_going())),
                None,
            ),
            Some(obj) => {
                let mut c = PyController::started(py, obj, scenario.max_turn_rate_radps())?;
                let r = py.detach(|| {
                    scenario.run_with_watched(&mut c, &mut rows, &mut || watch.keep_going())
                });
                (r, c.error)
            }
        };
        // The controller's own exception (a KeyboardInterrupt inside it, too) first, then one
        // that stopped the run, then any signal that came at its very end.
        if let Some(e) = failure.or(watch.error) {
            return Err(e);
        }
        py.check_signals()?;
        let Some(result) = result else {
            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(
                "the run was stopped",
            ));
        };
        let summary = summary_json(&scenario, &self.origin, &result)?;
        let trace = trace_columns(py, &rows, scenario.is_flying())?;
        let flown = PyScenario {
            inner: scenario,
            origin: self.origin.clone(),
            folder: self.folder.clone(),
        };
        Ok((summary, trace, flown))
    }

    fn field_values_inner<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let duration = self.inner.spec().sim.duration_s;
        if !(0.0..=duration).contains(&t) {
            return Err(PyValueError::new_err(format!(
                "t = {t:?} s is outside the run: 0 <= t <= sim.duration_s = {duration:?} s"
            )));
        }
        let (x, y) = (x.as_slice()?, y.as_slice()?);
        if x.len() != y.len() {
            return Err(PyValueError::new_err(format!(
                "x and y differ in length ({} and {})",
                x.len(),
                y.len()
            )));
        }
        let field = self.inner.field();
        // In blocks of a millisecond or so, so that Ctrl-C is answered between them (a puff
        // plume's value sums hundreds of puffs: a million points take seconds).
        let mut watch = SignalWatch::reading_the_clock_every(1);
        let v: Option<Vec<f64>> = py.detach(|| {
            let mut v = Vec::with_capacity(x.len());
            for (xs, ys) in x.chunks(256).zip(y.chunks(256)) {
                if !watch.keep_going() {
                    return None;
                }
                v.extend(
                    xs.iter()
                        .zip(ys)
                        .map(|(&a, &b)| field.value(t, Vec2::new(a, b)).unwrap_or(f64::NAN)),
                );
            }
            Some(v)
        });
        if let Some(e) = watch.error {
            return Err(e);
        }
        let v = v.ok_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err("stopped"))?;
        Ok(PyArray1::from_vec(py, v))
    }
}

/// The folder of the file at `path` as an absolute path, taken now
/// ([`absolute_dir`]: canonical when it can be).
pub(crate) fn absolute_folder(path: &Path) -> PathBuf {
    absolute_dir(path.parent().unwrap_or(Path::new(".")))
}

/// The content of `summary.json`, as the CLI writes it ([`isotrack_runs::summary::Summary`],
/// without its final newline).
fn summary_json(s: &Scenario, origin: &str, r: &RunResult) -> PyResult<String> {
    let warnings = isotrack_scenario::check::warnings(s);
    let path = (!origin.starts_with('<')).then(|| std::path::Path::new(origin));
    let text = isotrack_runs::summary::Summary::of_run(s, path, r, &warnings).to_json();
    Ok(text.trim_end_matches('\n').to_string())
}

/// The `trace.csv` columns as numpy arrays (`s_measured` NaN where no sample was delivered).
fn trace_columns<'py>(
    py: Python<'py>,
    rows: &[TraceRow],
    flying: bool,
) -> PyResult<Bound<'py, PyDict>> {
    trace_columns_by(py, rows, |r| r, flying)
}

/// [`trace_columns`] of any rows holding a [`TraceRow`] (`row` reads it): the single run's
/// and a team's (`team::team_columns`, which adds the `vehicle` column) are one code.
pub(crate) fn trace_columns_by<'py, T>(
    py: Python<'py>,
    rows: &[T],
    row: impl Fn(&T) -> &TraceRow,
    flying: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col =
        |f: &dyn Fn(&TraceRow) -> f64| -> Vec<f64> { rows.iter().map(|r| f(row(r))).collect() };
    // Named as `trace.csv`'s columns, in its order (`isotrack_runs::trace`, one home).
    let [t_s, x_m, y_m, heading_rad, s, error, omega_radps, s_measured] = TRACE_COLUMNS;
    let set =
        |name: &str, f: &dyn Fn(&TraceRow) -> f64| d.set_item(name, PyArray1::from_vec(py, col(f)));
    set(t_s, &|r| r.t_s)?;
    set(x_m, &|r| r.x_m)?;
    set(y_m, &|r| r.y_m)?;
    set(heading_rad, &|r| r.heading_rad)?;
    set(s, &|r| r.s)?;
    set(error, &|r| r.error)?;
    set(omega_radps, &|r| r.omega_radps)?;
    set(s_measured, &|r| r.s_measured.unwrap_or(f64::NAN))?;
    if flying {
        let [altitude_m, airspeed_mps, roll_rad] = TELEMETRY_COLUMNS;
        let t = |r: &TraceRow| r.telemetry.unwrap_or_default();
        set(altitude_m, &|r| t(r).altitude_m)?;
        set(airspeed_mps, &|r| t(r).airspeed_mps)?;
        set(roll_rad, &|r| t(r).roll_rad)?;
    }
    Ok(d)
}

/// The folder `dir` (a sweep file's or a scenario file's; empty: the working directory) as an
/// absolute path, taken now: canonical when it can be (symbolic links and `..` resolved, as the
/// kernel reads a path through it), else the working directory joined with it.
pub(crate) fn absolute_dir(dir: &Path) -> PathBuf {
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    std::fs::canonicalize(dir)
        .or_else(|_| std::path::absolute(dir))
        .unwrap_or_else(|_| dir.to_path_buf())
}
