//! `isotrack._native`: the engine for Python. Scenarios load, override and resolve exactly as on
//! the command line; runs return the `summary.json` content and the `trace.csv` columns as
//! numpy arrays; a Python object with `update(t_s, value) -> omega` can fly in place of the
//! built-in controller. The engine runs with the GIL released (a Python controller takes it
//! back for each of its samples only).

use guard::{no_panic, SignalWatch};
use isotrack_core::{IsolineController, Measurement, ScalarField, Vec2};
use isotrack_scenario::{load_scenario, parse_scenario, Scenario, ScenarioError};
use isotrack_sim::{RunResult, TraceRow};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use std::path::Path;
use std::sync::atomic::AtomicBool;

mod env;
mod guard;
mod league;
mod team;
mod tools;

/// The Python exception, named `isotrack.ScenarioError` in tracebacks.
mod py_errors {
    use pyo3::exceptions::PyValueError;
    pyo3::create_exception!(
        isotrack,
        ScenarioError,
        PyValueError,
        "An invalid scenario or override: the message the CLI prints (file, line, column, key). \
         A `ValueError`."
    );
}
pub(crate) use py_errors::ScenarioError as ScenarioErrorPy;

fn scenario_err(e: ScenarioError) -> PyErr {
    ScenarioErrorPy::new_err(e.to_string())
}

/// A resolved scenario (every default filled in). Immutable: `set` returns a new one.
#[pyclass(name = "Scenario", module = "isotrack._native", frozen)]
struct PyScenario {
    inner: Scenario,
    origin: String,
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
        })
    }

    /// A scenario file (TOML); files it names are relative to it.
    #[staticmethod]
    fn from_file(path: &str) -> PyResult<Self> {
        let inner = no_panic(|| load_scenario(Some(Path::new(path)), &[]).map_err(scenario_err))?;
        Ok(Self {
            inner,
            origin: path.to_string(),
        })
    }

    /// Scenario text (TOML); files it names are relative to the current directory.
    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Self> {
        let inner = no_panic(|| parse_scenario(text, "<toml>", &[]).map_err(scenario_err))?;
        Ok(Self {
            inner,
            origin: "<toml>".into(),
        })
    }

    /// A new scenario with the dotted `key` set to `value` (the rules of `--set`; errors are
    /// raised as `isotrack.ScenarioError` with the CLI's message). The key is checked to be a
    /// dotted key and the value converted to TOML here: neither is ever read as TOML text.
    fn set(&self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Self> {
        no_panic(|| {
            check_key(key)?;
            let literal = toml_literal(&toml_value(key, value, 0)?);
            let inner = self
                .inner
                .derive(&[format!("{key}={literal}")], &self.origin)
                .map_err(|e| ScenarioErrorPy::new_err(as_written(&e.to_string(), value)))?;
            Ok(Self {
                inner,
                origin: self.origin.clone(),
            })
        })
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
                if obj.bind(py).hasattr("reset")? {
                    obj.call_method0(py, "reset")?;
                }
                let mut c = PyController {
                    obj,
                    error: None,
                    max_turn_rate_radps: scenario.max_turn_rate_radps(),
                };
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

/// The most dotted parts of a key (`isotrack_scenario`'s limit for `--set`) and the deepest
/// nesting of lists in a value (a scenario's deepest value is a list of pairs).
const MAX_KEY_PARTS: usize = isotrack_scenario::load::MAX_KEY_PARTS;
const MAX_VALUE_DEPTH: usize = 8;

/// A `Scenario.set` key: dotted parts of letters, digits, `_` and `-` (TOML's bare keys), at
/// most [`MAX_KEY_PARTS`] of them. Anything else is refused here, so that no key is ever read
/// as TOML (`"sim.duration_s = 7 #"` once set the duration to 7).
fn check_key(key: &str) -> PyResult<()> {
    let shown = isotrack_scenario::load::clip(key);
    let parts: Vec<&str> = key.split('.').collect();
    if parts.len() > MAX_KEY_PARTS {
        return Err(ScenarioErrorPy::new_err(format!(
            "`{shown}`: a key has at most {MAX_KEY_PARTS} dotted parts, this one has {}",
            parts.len()
        )));
    }
    let bare = |p: &str| {
        !p.is_empty()
            && p.chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    };
    if !parts.iter().all(|p| bare(p)) {
        return Err(ScenarioErrorPy::new_err(format!(
            "`{shown}`: not a dotted key such as controller.kp (letters, digits, `_` and `-` \
             between the dots)"
        )));
    }
    Ok(())
}

/// A value as a TOML literal for `--set`, its floats in the shortest form that reads back
/// exactly (`1e300`, not the 301 digits the `toml` crate writes, which every error message
/// would echo): Rust's `{:?}` of a finite `f64`, which TOML reads (`1e300`, `0.1`, `10.0`).
fn toml_literal(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(f) if f.is_finite() => format!("{f:?}"),
        toml::Value::Array(items) => {
            let parts: Vec<String> = items.iter().map(toml_literal).collect();
            format!("[{}]", parts.join(", "))
        }
        other => other.to_string(),
    }
}

/// A scenario error about a float given for an integer key, as the user wrote it: serde
/// echoes the float through its own formatting (`2.0**64` as `floating point
/// `18446744073709552000.0``, digits the user never wrote), and does not say which integers
/// the key takes. The float is echoed as Python's `repr` and the range named (TOML's integers
/// are 64-bit signed, so an unsigned key takes 0 ..= 2**63-1).
fn as_written(message: &str, value: &Bound<'_, PyAny>) -> String {
    const FLOAT: &str = "invalid type: floating point `";
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        return message.to_string();
    }
    let Some(start) = message.find(FLOAT) else {
        return message.to_string();
    };
    let rest = &message[start + FLOAT.len()..];
    let Some(close) = rest.find('`') else {
        return message.to_string();
    };
    let after = &rest[close + 1..];
    let (expected, tail) = match after.strip_prefix(", expected ") {
        Some(e) => {
            let end = e
                .find(|c: char| !c.is_ascii_alphanumeric())
                .unwrap_or(e.len());
            (&e[..end], &e[end..])
        }
        None => ("", after),
    };
    let range = match expected {
        "u8" => "an integer in 0 ..= 255",
        "u16" => "an integer in 0 ..= 65535",
        "u32" => "an integer in 0 ..= 4294967295 (2**32-1)",
        "u64" | "usize" => "an integer in 0 ..= 9223372036854775807 (2**63-1, TOML's largest)",
        "i32" => "an integer in -2147483648 ..= 2147483647",
        "i64" | "isize" => "an integer in -2**63 ..= 2**63-1",
        _ => return message.to_string(),
    };
    format!(
        "{}{} is a float; this key takes {range}, written without a decimal point{tail}",
        &message[..start],
        shown(value)
    )
}

/// A value's `repr` for a message, clipped (a million-element list once made a megabyte error),
/// or its type when it has no `repr` (an int past Python's digit limit).
fn shown(v: &Bound<'_, PyAny>) -> String {
    let text = v
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| format!("a {}", v.get_type()));
    isotrack_scenario::load::clip(&text)
}

/// A Python value as a TOML value for `--set`: booleans, integers (64-bit), finite floats,
/// strings, and lists or tuples of them nested at most [`MAX_VALUE_DEPTH`] deep (a list that
/// holds itself is refused, not followed).
fn toml_value(key: &str, v: &Bound<'_, PyAny>, depth: usize) -> PyResult<toml::Value> {
    let bad = |what: String| ScenarioErrorPy::new_err(format!("`{key}`: {what}"));
    if depth > MAX_VALUE_DEPTH {
        return Err(bad(format!(
            "lists nested more than {MAX_VALUE_DEPTH} deep (or a list that holds itself)"
        )));
    }
    if let Ok(b) = v.extract::<bool>() {
        return Ok(toml::Value::Boolean(b));
    }
    if v.is_instance_of::<pyo3::types::PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(bad(format!(
                "{} does not fit in a 64-bit integer (-2**63 ..= 2**63-1, TOML's integers)",
                shown(v)
            ))),
        };
    }
    if let Ok(s) = v.extract::<String>() {
        return Ok(toml::Value::String(s));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items: PyResult<Vec<toml::Value>> = v
            .try_iter()?
            .map(|item| toml_value(key, &item?, depth + 1))
            .collect();
        return Ok(toml::Value::Array(items?));
    }
    // A numpy integer (`np.int64`, `np.uint64`, ...) is not a Python int: taken exactly through
    // `operator.index`, never through a float (which rounds past 2**53).
    // A numpy array has `__index__` but refuses it unless it is a 0-d integer array: then it is
    // no integer, and is read as a float below (or refused, naming the key).
    let exact = if !v.is_instance_of::<pyo3::types::PyFloat>() && v.hasattr("__index__")? {
        v.py().import("operator")?.call_method1("index", (v,)).ok()
    } else {
        None
    };
    if let Some(exact) = exact {
        return match exact.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(bad(format!(
                "{} does not fit in a 64-bit integer (-2**63 ..= 2**63-1, TOML's integers)",
                shown(v)
            ))),
        };
    }
    if let Ok(f) = v.extract::<f64>() {
        if !f.is_finite() {
            return Err(bad(format!("{f} is not a finite number")));
        }
        return Ok(toml::Value::Float(f));
    }
    Err(bad(format!(
        "cannot use {} as a scenario value (numbers, booleans, strings or lists of them)",
        shown(v)
    )))
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
    d.set_item("t_s", PyArray1::from_vec(py, col(&|r| r.t_s)))?;
    d.set_item("x_m", PyArray1::from_vec(py, col(&|r| r.x_m)))?;
    d.set_item("y_m", PyArray1::from_vec(py, col(&|r| r.y_m)))?;
    d.set_item(
        "heading_rad",
        PyArray1::from_vec(py, col(&|r| r.heading_rad)),
    )?;
    d.set_item("s", PyArray1::from_vec(py, col(&|r| r.s)))?;
    d.set_item("error", PyArray1::from_vec(py, col(&|r| r.error)))?;
    d.set_item(
        "omega_radps",
        PyArray1::from_vec(py, col(&|r| r.omega_radps)),
    )?;
    d.set_item(
        "s_measured",
        PyArray1::from_vec(py, col(&|r| r.s_measured.unwrap_or(f64::NAN))),
    )?;
    if flying {
        let t = |r: &TraceRow| r.telemetry.unwrap_or_default();
        d.set_item(
            "altitude_m",
            PyArray1::from_vec(py, col(&|r| t(r).altitude_m)),
        )?;
        d.set_item(
            "airspeed_mps",
            PyArray1::from_vec(py, col(&|r| t(r).airspeed_mps)),
        )?;
        d.set_item("roll_rad", PyArray1::from_vec(py, col(&|r| t(r).roll_rad)))?;
    }
    Ok(d)
}

/// A Python object as a coordinate-free controller: `update(t_s, value) -> omega`, clipped to
/// the scenario's turn-rate limit as every built-in law's output is. The first exception is kept
/// (and raised when the run returns); the run then ends as `diverged` (the command is NaN), the
/// loop's own way of stopping.
struct PyController {
    obj: Py<PyAny>,
    error: Option<PyErr>,
    max_turn_rate_radps: Option<f64>,
}

impl IsolineController for PyController {
    fn update(&mut self, m: &Measurement) -> f64 {
        if self.error.is_some() {
            return f64::NAN;
        }
        Python::attach(|py| {
            match self
                .obj
                .call_method1(py, "update", (m.t_s, m.value))
                .and_then(|r| command_value(r.bind(py)))
            {
                Ok(w) => match self.max_turn_rate_radps {
                    // NaN passes (and ends the run as `diverged`).
                    Some(m) => w.clamp(-m, m),
                    None => w,
                },
                Err(e) => {
                    self.error = Some(e);
                    f64::NAN
                }
            }
        })
    }
    fn reset(&mut self) {}
}

/// A controller's `update` answer as a turn rate (rad/s): a real number, never a bool (`True`
/// would fly 1 rad/s; every numeric argument of the package refuses bools too).
pub(crate) fn command_value(r: &Bound<'_, PyAny>) -> PyResult<f64> {
    let is_bool = r.is_instance_of::<pyo3::types::PyBool>()
        || r.get_type()
            .fully_qualified_name()
            .is_ok_and(|n| n == "numpy.bool" || n == "numpy.bool_");
    if is_bool {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "controller.update() must return a turn rate (a number, rad/s), got {} (a bool)",
            shown(r)
        )));
    }
    r.extract::<f64>()
}

/// A sweep's answer to Python: `results.csv`'s header, each column's kind, and its cells.
pub(crate) type SweepCells = (Vec<String>, Vec<&'static str>, Vec<Vec<String>>);

/// A sweep from its file's text: `(header, kinds, rows)`: `results.csv`'s header, each
/// column's kind ([`column_kinds`]) and its cells in `run_id` order; `name` names the sweep in
/// messages and anchors its relative `scenario` path. `progress(done, total)`, a Python
/// callable, is called on this thread about every 20 ms while the runs go and once at the end.
/// Ctrl-C stops it between batches of runs.
#[pyfunction]
#[pyo3(signature = (text, name, threads=None, progress=None))]
fn sweep_cells(
    py: Python<'_>,
    text: &str,
    name: &str,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<SweepCells> {
    use std::sync::atomic::{AtomicU64, Ordering};
    let prepared = isotrack_runs::sweep::prepared::PreparedSweep::new(text, Path::new(name))
        .map_err(sweep_failure)?;
    let kinds = column_kinds(&prepared.plan);
    let cancel = AtomicBool::new(false);
    let (done, total) = (AtomicU64::new(0), AtomicU64::new(prepared.plan.total()));
    let report = |d: u64, t: u64| {
        done.fetch_max(d, Ordering::Relaxed);
        total.store(t, Ordering::Relaxed);
    };
    let mut shown = None;
    let mut tick = |py: Python<'_>| -> PyResult<()> {
        let now = (done.load(Ordering::Relaxed), total.load(Ordering::Relaxed));
        match &progress {
            Some(cb) if shown != Some(now) => {
                shown = Some(now);
                cb.call1(py, now).map(drop)
            }
            _ => Ok(()),
        }
    };
    let (header, rows) = guard::interruptible_ticking(
        py,
        &cancel,
        || {
            // Nothing printed (the threads cap's note is Python's warning, see `sweep`).
            isotrack_runs::sweep::prepared::sweep_in_memory(
                text,
                Path::new(name),
                threads,
                progress
                    .is_some()
                    .then_some(&report as &(dyn Fn(u64, u64) + Sync)),
                &cancel,
            )
        },
        &mut tick,
    )?
    .map_err(sweep_failure)?;
    Ok((header, kinds, rows))
}

/// A sweep's failure as the Python exception of its kind.
fn sweep_failure(f: isotrack_runs::Failure) -> PyErr {
    match f.code {
        66 => pyo3::exceptions::PyFileNotFoundError::new_err(f.message),
        isotrack_runs::sweep::prepared::INTERRUPTED => {
            pyo3::exceptions::PyKeyboardInterrupt::new_err(f.message)
        }
        _ => ScenarioErrorPy::new_err(f.message),
    }
}

/// The kind of each `results.csv` column of a sweep, from the plan (never from the cells, so
/// that a column's kind does not depend on which runs it holds): `"int"` for `run_id`,
/// `samples`, a derived `sim.seed` and a swept key whose values are all integers; `"float"` for
/// the metrics, `[random]` keys and swept keys of numbers; `"bool"` for swept booleans; `"str"`
/// for `outcome`, `outcome_detail`, `warnings` and any other swept key.
pub(crate) fn column_kinds(plan: &isotrack_scenario::sweep::SweepPlan) -> Vec<&'static str> {
    let kind = |values: &mut dyn Iterator<Item = Option<&toml::Value>>| {
        let (mut ints, mut floats, mut bools, mut n) = (0, 0, 0, 0);
        for v in values {
            n += 1;
            match v {
                Some(toml::Value::Integer(_)) => ints += 1,
                Some(toml::Value::Float(_)) => floats += 1,
                Some(toml::Value::Boolean(_)) => bools += 1,
                _ => {}
            }
        }
        if n > 0 && ints == n {
            "int"
        } else if n > 0 && ints + floats == n {
            "float"
        } else if n > 0 && bools == n {
            "bool"
        } else {
            "str"
        }
    };
    let mut kinds = vec!["int"];
    for (_, list) in &plan.grid {
        let width = list.first().and_then(|v| v.as_array()).map(|a| a.len());
        let split = width.is_some_and(|w| {
            list.iter()
                .all(|v| v.as_array().is_some_and(|a| a.len() == w))
        });
        match width {
            Some(w) if split => kinds.extend(
                (0..w).map(|i| kind(&mut list.iter().map(|v| v.as_array().and_then(|a| a.get(i))))),
            ),
            _ => kinds.push(kind(&mut list.iter().map(Some))),
        }
    }
    kinds.extend(plan.random.iter().map(|_| "float"));
    if plan.derives_seed {
        kinds.push("int");
    }
    kinds.extend(
        isotrack_runs::sweep::rows::METRIC_COLUMNS
            .iter()
            .map(|c| match *c {
                "outcome" | "outcome_detail" | "warnings" => "str",
                "samples" => "int",
                _ => "float",
            }),
    );
    kinds
}

/// The SHA-256 of the file at `path`, lowercase hex: isotrack's one content digest
/// ([`isotrack_runs::files::sha256_file`], also what a run records in `summary.json`'s
/// `data_files`); `OSError` when it cannot be read.
#[pyfunction]
fn file_sha256(py: Python<'_>, path: std::path::PathBuf) -> PyResult<String> {
    py.detach(|| isotrack_runs::files::sha256_file(&path))
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", path.display())))
}

/// The isotrack version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // numpy's C API now, once: fetched lazily it may be fetched while a KeyboardInterrupt is
    // pending, and rust-numpy then panics ("Failed to access NumPy array API capsule").
    PyArray1::<f64>::zeros(m.py(), 0, false);
    m.add_class::<PyScenario>()?;
    m.add_class::<env::PyEnvBatch>()?;
    m.add_class::<team::PyTeamEnv>()?;
    m.add_function(wrap_pyfunction!(team::team_run, m)?)?;
    m.add_function(wrap_pyfunction!(team::write_team_run, m)?)?;
    m.add_function(wrap_pyfunction!(team::is_team, m)?)?;
    m.add("ScenarioError", m.py().get_type::<ScenarioErrorPy>())?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(file_sha256, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_cells, m)?)?;
    m.add_function(wrap_pyfunction!(league::benchmark_json, m)?)?;
    m.add_function(wrap_pyfunction!(tools::cli_main, m)?)?;
    m.add_function(wrap_pyfunction!(tools::write_run, m)?)?;
    m.add_function(wrap_pyfunction!(tools::plot, m)?)?;
    m.add_function(wrap_pyfunction!(tools::report, m)?)?;
    m.add_function(wrap_pyfunction!(tools::controller_variant, m)?)?;
    m.add_function(wrap_pyfunction!(tools::controller_kinds, m)?)?;
    m.add_function(wrap_pyfunction!(tools::sweep_cells_with, m)?)?;
    Ok(())
}
