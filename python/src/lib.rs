//! `isotrack._native`: the engine for Python. Scenarios load, override and resolve exactly as on
//! the command line; runs return the `summary.json` content and the `trace.csv` columns as
//! numpy arrays; a Python object with `update(t_s, value) -> omega` can fly in place of the
//! built-in controller. The engine runs with the GIL released (a Python controller takes it
//! back for each of its samples only).

use isotrack_core::{IsolineController, Measurement, ScalarField, Vec2};
use isotrack_scenario::{load_scenario, parse_scenario, Scenario, ScenarioError};
use isotrack_sim::{RunResult, TraceRow};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::Path;

mod bench;
mod env;

pyo3::create_exception!(
    _native,
    ScenarioErrorPy,
    PyException,
    "An invalid scenario or override: the message the CLI prints (file, line, column, key)."
);

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
        let inner = load_scenario(None, &[]).map_err(scenario_err)?;
        Ok(Self {
            inner,
            origin: "<built-in default>".into(),
        })
    }

    /// A scenario file (TOML); files it names are relative to it.
    #[staticmethod]
    fn from_file(path: &str) -> PyResult<Self> {
        let inner = load_scenario(Some(Path::new(path)), &[]).map_err(scenario_err)?;
        Ok(Self {
            inner,
            origin: path.to_string(),
        })
    }

    /// Scenario text (TOML); files it names are relative to the current directory.
    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Self> {
        let inner = parse_scenario(text, "<toml>", &[]).map_err(scenario_err)?;
        Ok(Self {
            inner,
            origin: "<toml>".into(),
        })
    }

    /// A new scenario with the dotted `key` set to `value` (the rules of `--set`; errors are
    /// raised as `isotrack.ScenarioError` with the CLI's message).
    fn set(&self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<Self> {
        let literal = toml_literal(value)?;
        let inner = self
            .inner
            .derive(&[format!("{key}={literal}")], &self.origin)
            .map_err(scenario_err)?;
        Ok(Self {
            inner,
            origin: self.origin.clone(),
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
        isotrack_cli::output::scenario_toml(&self.inner)
    }

    /// Runs the scenario: `(summary_json, trace_columns)`. `record_rate_hz` overrides
    /// `output.record_rate_hz`; `controller` (an object with `update(t_s, value) -> omega` and
    /// an optional `reset()`) replaces the scenario's controller.
    #[pyo3(signature = (record_rate_hz=None, controller=None))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        record_rate_hz: Option<f64>,
        controller: Option<Py<PyAny>>,
    ) -> PyResult<(String, Bound<'py, PyDict>)> {
        let scenario = match record_rate_hz {
            Some(r) => self
                .inner
                .derive(&[format!("output.record_rate_hz={r:?}")], &self.origin)
                .map_err(scenario_err)?,
            None => self.inner.clone(),
        };
        let mut rows: Vec<TraceRow> = Vec::new();
        let (result, failure) = match controller {
            None => (py.detach(|| scenario.run(&mut rows)), None),
            Some(obj) => {
                if obj.bind(py).hasattr("reset")? {
                    obj.call_method0(py, "reset")?;
                }
                let mut c = PyController {
                    obj,
                    error: None,
                    max_turn_rate_radps: scenario.max_turn_rate_radps(),
                };
                let r = py.detach(|| scenario.run_with(&mut c, &mut rows));
                (r, c.error)
            }
        };
        if let Some(e) = failure {
            return Err(e);
        }
        let summary = summary_json(&scenario, &self.origin, &result)?;
        Ok((summary, trace_columns(py, &rows, scenario.is_flying())?))
    }

    /// The field's values at `(x, y)` (numpy arrays of one shape, m) at time `t` (s); NaN where
    /// the field has no value.
    #[pyo3(signature = (x, y, t=0.0))]
    fn field_values<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (x, y) = (x.as_slice()?, y.as_slice()?);
        if x.len() != y.len() {
            return Err(PyValueError::new_err(format!(
                "x and y differ in length ({} and {})",
                x.len(),
                y.len()
            )));
        }
        let field = self.inner.field();
        let v: Vec<f64> = py.detach(|| {
            x.iter()
                .zip(y)
                .map(|(&a, &b)| field.value(t, Vec2::new(a, b)).unwrap_or(f64::NAN))
                .collect()
        });
        Ok(PyArray1::from_vec(py, v))
    }

    /// `isotrack check --json` for this scenario.
    #[pyo3(signature = (tube_halfwidth=None))]
    fn check_json(&self, py: Python<'_>, tube_halfwidth: Option<f64>) -> PyResult<String> {
        let r = py.detach(|| isotrack_scenario::check::check(&self.inner, tube_halfwidth));
        serde_json::to_string(&r).map_err(|e| PyValueError::new_err(e.to_string()))
    }
}

/// A Python value as a TOML literal for `--set` (numbers, booleans, strings, lists of them).
fn toml_literal(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(b) = v.extract::<bool>() {
        return Ok(b.to_string());
    }
    if let Ok(i) = v.extract::<i64>() {
        return Ok(i.to_string());
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(format!("{f:?}"));
    }
    if let Ok(s) = v.extract::<String>() {
        return Ok(format!("{s:?}"));
    }
    if let Ok(items) = v.extract::<Vec<Bound<'_, PyAny>>>() {
        let parts: PyResult<Vec<String>> = items.iter().map(toml_literal).collect();
        return Ok(format!("[{}]", parts?.join(", ")));
    }
    Err(PyValueError::new_err(format!(
        "cannot use {} as a scenario value (numbers, booleans, strings or lists of them)",
        v.repr()?
    )))
}

/// The content of `summary.json`, as the CLI writes it.
fn summary_json(s: &Scenario, origin: &str, r: &RunResult) -> PyResult<String> {
    let warnings = isotrack_scenario::check::warnings(s);
    let summary = isotrack_cli::output::Summary {
        isotrack_version: env!("CARGO_PKG_VERSION"),
        scenario_path: (!origin.starts_with('<')).then(|| origin.to_string()),
        result: r,
        warnings: &warnings,
        scenario: s.file(),
    };
    isotrack_cli::output::summary_to_json(&summary)
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The `trace.csv` columns as numpy arrays (`s_measured` NaN where no sample was delivered).
fn trace_columns<'py>(
    py: Python<'py>,
    rows: &[TraceRow],
    flying: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&TraceRow) -> f64| -> Vec<f64> { rows.iter().map(f).collect() };
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
                .and_then(|r| r.extract::<f64>(py))
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

/// A sweep from its file's text: `(header, rows)` of `results.csv`'s cells in `run_id` order;
/// `name` names the sweep in messages and anchors its relative `scenario` path.
#[pyfunction]
#[pyo3(signature = (text, name, threads=None, progress=false))]
fn sweep_cells(
    py: Python<'_>,
    text: &str,
    name: &str,
    threads: Option<usize>,
    progress: bool,
) -> PyResult<(Vec<String>, Vec<Vec<String>>)> {
    py.detach(|| isotrack_cli::sweep::sweep_in_memory(text, Path::new(name), threads, progress))
        .map_err(|f| match f.code {
            66 => pyo3::exceptions::PyFileNotFoundError::new_err(f.message),
            _ => ScenarioErrorPy::new_err(f.message),
        })
}

/// The isotrack version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScenario>()?;
    m.add_class::<env::PyEnvBatch>()?;
    m.add("ScenarioError", m.py().get_type::<ScenarioErrorPy>())?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_cells, m)?)?;
    m.add_function(wrap_pyfunction!(bench::benchmark_json, m)?)?;
    Ok(())
}
