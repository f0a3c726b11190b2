//! Trace columns as the run writers read them from Python (a leaf: the single run's writer
//! in tools.rs and the team's in team.rs both use it).

use numpy::PyReadonlyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// One `trace.csv` column, checked to have `n` rows (a single run's and a team's).
pub(crate) fn column<'py>(
    trace: &Bound<'py, PyDict>,
    name: &str,
    n: Option<usize>,
) -> PyResult<Vec<f64>> {
    let v = trace
        .get_item(name)?
        .ok_or_else(|| PyValueError::new_err(format!("the trace has no column `{name}`")))?;
    let a: PyReadonlyArray1<'py, f64> = v.extract()?;
    let v = a.as_array().to_vec();
    match n {
        Some(n) if v.len() != n => Err(PyValueError::new_err(format!(
            "the trace's column `{name}` has {} rows, `t_s` has {n}",
            v.len()
        ))),
        _ => Ok(v),
    }
}

/// How many trace rows a save writes between two checks for Ctrl-C (`Python::check_signals`):
/// a few milliseconds of writing.
pub(crate) const SIGNAL_ROWS: usize = 1 << 14;
