//! Trace columns as the run writers read them from Python (a leaf: the single run's writer
//! in tools.rs and the team's in team.rs both use it).

use numpy::{Element, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

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
    let v = copy_interruptible(trace.py(), &a)?;
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

/// A copy of column `a`, answering Ctrl-C (`Python::check_signals`) every [`SIGNAL_ROWS`]
/// values: the columns of a multi-million-row run are copied before a save writes its first
/// row (seven `to_vec` copies of 6e6 rows held a `KeyboardInterrupt` for 2.1 s on a loaded
/// machine, growing with the trace), so the copy answers as the writing does.
pub(crate) fn copy_interruptible<T: Element + Copy>(
    py: Python<'_>,
    a: &PyReadonlyArray1<'_, T>,
) -> PyResult<Vec<T>> {
    let view = a.as_array();
    let mut v = Vec::with_capacity(view.len());
    for (i, &x) in view.iter().enumerate() {
        if i % SIGNAL_ROWS == 0 {
            py.check_signals()?;
        }
        v.push(x);
    }
    Ok(v)
}

/// The holder `Run.save` records in a run directory's lock file (`.isotrack.lock`, the lock of
/// `isotrack run --out`, [`isotrack_runs::sweep::lock::lock_output_dir`]): a command refused
/// there names it (`another isotrack Run.save pid 1234 on node7 is writing this directory`).
pub(crate) const SAVE_LOCK: &str = "Run.save";

/// What a `KeyboardInterrupt` says when it came after a save's commit: `dir` holds the new run,
/// whole. One text for the check right after the commit ([`interrupt_after_save`]) and for the
/// Python wrapper, which raises it for an interrupt that Python delivers once the native call
/// has returned (`Run.save`, `_native.after_save_message`).
#[pyfunction]
pub fn after_save_message(dir: &str) -> String {
    format!(
        "interrupted after the save completed: {dir} holds the new run, whole (the interrupt \
         came during the final writes, after the earlier run was replaced)"
    )
}

/// The check for Ctrl-C right after a save's commit (ver30b-9): the signal handler runs here
/// rather than after the call returns, so that a `KeyboardInterrupt` that came during the final
/// writes (the summary, the scenario, their fsyncs and renames: past the last check before the
/// commit, after which the earlier run is replaced) says that the save completed and `dir`
/// holds the new run, whole. Another exception of a handler is raised as it is.
///
/// `done` (the caller's list) gets `True` appended first: a signal that arrives after this
/// check, while the call is returning, is delivered by Python in the caller (CPython runs
/// pending handlers right after a native call returns), where the list tells the wrapper that
/// the save had completed (the CI run of 2026-11-27 saw that window: a bare `KeyboardInterrupt`
/// with the new run in place).
pub(crate) fn interrupt_after_save(
    py: Python<'_>,
    dir: &str,
    done: Option<&Bound<'_, PyList>>,
) -> PyResult<()> {
    use pyo3::exceptions::PyKeyboardInterrupt;
    if let Some(done) = done {
        done.append(true)?;
    }
    match py.check_signals() {
        Ok(()) => Ok(()),
        Err(e) if e.is_instance_of::<PyKeyboardInterrupt>(py) => {
            let said = PyKeyboardInterrupt::new_err(after_save_message(dir));
            said.set_cause(py, Some(e));
            Err(said)
        }
        Err(e) => Err(e),
    }
}

/// A run directory's refusal to `Run.save` in Python's words: the command line's "use another
/// --out" (a flag the caller has not got) said as "save into another directory".
pub(crate) fn save_failure(f: isotrack_runs::Failure) -> PyErr {
    crate::errors::failure(isotrack_runs::Failure {
        message: f
            .message
            .replace("or use another --out", "or save into another directory")
            .replace("give --out a directory", "save into a directory"),
        ..f
    })
}
