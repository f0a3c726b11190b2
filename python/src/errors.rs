//! The package's Python exception, `isotrack.ScenarioError`, and a scenario error as it.

use isotrack_runs::{exit, Failure};
use isotrack_scenario::ScenarioError;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::PyErr;

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

pub(crate) fn scenario_err(e: ScenarioError) -> PyErr {
    ScenarioErrorPy::new_err(e.to_string())
}

/// A command-line failure as the Python exception of its exit code (README, "Exit codes").
pub(crate) fn failure(f: Failure) -> PyErr {
    match f.code {
        exit::USAGE => PyValueError::new_err(f.message),
        exit::DATAERR => ScenarioErrorPy::new_err(f.message),
        exit::NOINPUT => PyFileNotFoundError::new_err(f.message),
        exit::CANTCREAT | exit::OSERR => PyOSError::new_err(f.message),
        _ => PyRuntimeError::new_err(f.message),
    }
}
