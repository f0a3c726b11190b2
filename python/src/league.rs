//! `isotrack.benchmark`: a Python controller scored by the benchmark on the same tasks and seeds
//! as the built-in laws.

use crate::errors::ScenarioErrorPy;
use crate::guard::interruptible;
use crate::scenario::PyScenario;
use isotrack_core::{IsolineController, Measurement};
use isotrack_league::{run_benchmark, BenchError, ControllerFactory, Options, Registry, Suite};
use isotrack_scenario::Scenario;
use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The first Python exception of a benchmark (raised when it returns).
type FirstError = Arc<Mutex<Option<PyErr>>>;

fn keep(errors: &FirstError, e: PyErr) {
    if let Ok(mut slot) = errors.lock() {
        slot.get_or_insert(e);
    }
}

/// A Python callable `factory(scenario) -> controller`, called once per run.
struct PyFactory {
    factory: Py<PyAny>,
    errors: FirstError,
    cancel: Arc<AtomicBool>,
    /// Every object the factory returned, with the call (and the run's seed) it answered: one
    /// object returned twice would carry its state from run to run (refused).
    returned: Mutex<(crate::controller::Returned, u64)>,
}

impl ControllerFactory for PyFactory {
    fn make(&self, scenario: &Scenario) -> Box<dyn IsolineController + Send> {
        let obj = Python::attach(|py| {
            let native = Py::new(
                py,
                PyScenario {
                    inner: scenario.clone(),
                    origin: "<benchmark>".into(),
                    folder: None,
                },
            )?;
            let obj = self.factory.call1(py, (native,))?;
            let mut returned = self
                .returned
                .lock()
                .map_err(|_| PyValueError::new_err("controller_factory: a run panicked"))?;
            returned.1 += 1;
            let now = format!("run {} (seed {})", returned.1, scenario.spec().sim.seed);
            match returned.0.check(py, &obj, now.clone())? {
                Some(earlier) => Err(crate::controller::shared_across_runs(&earlier, &now)),
                None => Ok(obj),
            }
        });
        let obj = match obj {
            Ok(o) => Some(o),
            Err(e) => {
                keep(&self.errors, e);
                None
            }
        };
        Box::new(BenchController {
            obj,
            errors: self.errors.clone(),
            cancel: self.cancel.clone(),
        })
    }
}

/// A Python controller in a benchmark run: `update(t_s, value) -> omega`. An exception ends the
/// run (a NaN command: `diverged`) and is raised when the benchmark returns; so does a cancel
/// (Ctrl-C: a run in flight ends at its next sample).
struct BenchController {
    obj: Option<Py<PyAny>>,
    errors: FirstError,
    cancel: Arc<AtomicBool>,
}

impl IsolineController for BenchController {
    fn update(&mut self, m: &Measurement) -> f64 {
        if self.cancel.load(Ordering::Relaxed) {
            return f64::NAN;
        }
        let Some(obj) = self.obj.take() else {
            return f64::NAN;
        };
        Python::attach(|py| {
            match obj
                .call_method1(py, "update", (m.t_s, m.value))
                .and_then(|r| crate::controller::command_value(r.bind(py)))
            {
                Ok(w) => {
                    self.obj = Some(obj);
                    w
                }
                Err(e) => {
                    keep(&self.errors, e);
                    f64::NAN
                }
            }
        })
    }
    fn reset(&mut self) {}
}

/// Runs a suite with the Python controller `factory` registered as `name`: the result as JSON
/// (suite, controllers, per-task scores, runs and pictures, overall ranking); with `out`, the
/// leaderboard files and `index.html` written there as `isotrack benchmark` writes them.
#[pyfunction]
#[pyo3(signature = (factory, name, suite_path, controllers=None, tune=false, out=None, resume=false))]
#[allow(clippy::too_many_arguments)]
pub fn benchmark_json(
    py: Python<'_>,
    factory: Py<PyAny>,
    name: &str,
    suite_path: &str,
    controllers: Option<Vec<String>>,
    tune: bool,
    out: Option<&str>,
    resume: bool,
) -> PyResult<String> {
    check_name(name)?;
    let path = Path::new(suite_path);
    if !path.exists() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{suite_path}: no such suite file"
        )));
    }
    let suite = Suite::load(path).map_err(|e| ScenarioErrorPy::new_err(e.to_string()))?;
    // As `isotrack benchmark --out`: an existing benchmark refused unless `resume`, the
    // directory locked while this writes it.
    let _lock = out
        .map(|d| {
            isotrack_commands::league::open_out_dir(Path::new(d), resume).map_err(|f| {
                // The command's refusal names its flags (`--resume`, `--out`): said here in
                // this function's arguments.
                // Only where the command advises `--resume` (not beside a file no benchmark
                // writes, which is named instead).
                if !resume && f.message.contains("pass --resume") {
                    pyo3::exceptions::PyOSError::new_err(format!(
                        "{d} already holds a benchmark: pass resume=True to reuse its task \
                         results, or choose another out="
                    ))
                } else {
                    crate::errors::failure(f)
                }
            })
        })
        .transpose()?;
    // Every output name checked before any task runs: a user's file refused (att42-6).
    if let Some(d) = out {
        isotrack_commands::league::refuse_foreign_outputs(Path::new(d), &suite)
            .map_err(crate::errors::failure)?;
    }
    let errors: FirstError = Arc::new(Mutex::new(None));
    let cancel = Arc::new(AtomicBool::new(false));
    let mut registry = Registry::builtin();
    registry
        .register(
            name,
            PyFactory {
                factory,
                errors: errors.clone(),
                cancel: cancel.clone(),
                returned: Mutex::default(),
            },
        )
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let opts = Options {
        controllers,
        tune,
        resume_from: out.filter(|_| resume).map(std::path::PathBuf::from),
        cancel: Some(cancel.clone()),
        save_to: None,
    };
    let result = interruptible(py, &cancel, || {
        run_benchmark(&suite, &registry, &opts, &|_, _, _| {})
    })?
    .map_err(|e| match e {
        BenchError::Interrupted => PyKeyboardInterrupt::new_err(e.to_string()),
        _ => ScenarioErrorPy::new_err(e.to_string()),
    })?;
    if let Some(e) = errors.lock().ok().and_then(|mut s| s.take()) {
        return Err(e);
    }
    if let Some(dir) = out {
        isotrack_commands::league::write_outputs(&suite, path, &result, Path::new(dir), tune)
            .map_err(crate::errors::failure)?;
    }
    serde_json::to_string(&result).map_err(|e| ScenarioErrorPy::new_err(e.to_string()))
}

/// A name for the Python controller's row: not a built-in law's (it would replace that row),
/// not empty, nothing that breaks a Markdown table row or a line (`|`, control characters).
fn check_name(name: &str) -> PyResult<()> {
    isotrack_league::check_name(name).map_err(|e| PyValueError::new_err(e.to_string()))
}
