//! Trace columns as the run writers read them from Python, and the one save of a run directory
//! from them (a leaf: the single run's writer in tools.rs and the team's in team.rs both use
//! it).

use isotrack_core::vehicle::Telemetry;
use isotrack_runs::rundir::RunDir;
use isotrack_runs::trace::{TraceWriter, TELEMETRY_COLUMNS, TRACE_COLUMNS};
use isotrack_scenario::Scenario;
use isotrack_sim::TraceRow;
use numpy::{Element, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::Path;

/// One `trace.csv` column, checked to have `n` rows (a single run's and a team's).
fn column<'py>(trace: &Bound<'py, PyDict>, name: &str, n: Option<usize>) -> PyResult<Vec<f64>> {
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

/// A trace's columns as `trace.csv` holds them, read from Python's dict of numpy arrays (a
/// single run's and a team's, whose `vehicle` column its writer reads apart): `t_s` first, then
/// the others, each checked to have `t_s`'s rows, in the file's order.
pub(crate) struct TraceColumns {
    t: Vec<f64>,
    /// [`TRACE_COLUMNS`] after `t_s`: `x_m`, `y_m`, `heading_rad`, `s`, `error`, `omega_radps`,
    /// `s_measured` (the indices [`TraceColumns::row`] reads).
    cols: Vec<Vec<f64>>,
    /// A flying vehicle's [`TELEMETRY_COLUMNS`].
    telemetry: Option<Vec<Vec<f64>>>,
}

impl TraceColumns {
    /// The columns of `trace` (with the telemetry when `flying`).
    pub(crate) fn read(trace: &Bound<'_, PyDict>, flying: bool) -> PyResult<Self> {
        let t = column(trace, TRACE_COLUMNS[0], None)?;
        let n = Some(t.len());
        let cols: Vec<Vec<f64>> = TRACE_COLUMNS[1..]
            .iter()
            .map(|c| column(trace, c, n))
            .collect::<PyResult<_>>()?;
        let telemetry: Option<Vec<Vec<f64>>> = flying
            .then(|| {
                TELEMETRY_COLUMNS
                    .iter()
                    .map(|c| column(trace, c, n))
                    .collect::<PyResult<_>>()
            })
            .transpose()?;
        Ok(Self { t, cols, telemetry })
    }

    /// The number of rows.
    pub(crate) fn rows(&self) -> usize {
        self.t.len()
    }

    /// Row `i` (`i` below [`TraceColumns::rows`]).
    fn row(&self, i: usize) -> TraceRow {
        let cols = &self.cols;
        let m = cols[6][i];
        TraceRow {
            t_s: self.t[i],
            x_m: cols[0][i],
            y_m: cols[1][i],
            heading_rad: cols[2][i],
            s: cols[3][i],
            error: cols[4][i],
            omega_radps: cols[5][i],
            // NaN in the numpy column is "no sample yet", an empty cell in the file.
            s_measured: (!m.is_nan()).then_some(m),
            telemetry: self.telemetry.as_ref().map(|tm| Telemetry {
                altitude_m: tm[0][i],
                airspeed_mps: tm[1][i],
                roll_rad: tm[2][i],
            }),
        }
    }

    /// Hands `record` each row with its index, in order, answering Ctrl-C while the trace is
    /// written (2 M rows take seconds): `Python::check_signals` every [`SIGNAL_ROWS`] rows and
    /// once more after the last row, just before the commit (ver30b-9), so that an interrupt
    /// before it always leaves the earlier run ([`save_run`]).
    pub(crate) fn stream(
        &self,
        py: Python<'_>,
        mut record: impl FnMut(usize, &TraceRow),
    ) -> PyResult<()> {
        let n = self.t.len();
        for i in 0..=n {
            if i % SIGNAL_ROWS == 0 || i == n {
                py.check_signals()?;
            }
            if i < n {
                record(i, &self.row(i));
            }
        }
        Ok(())
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

/// Saves run directory `dir` as `isotrack run --out` does, for a single run's save and a team's:
/// the one run-directory writer, created and locked as `run --out` does ([`SAVE_LOCK`],
/// att30c-6; the lock held until this returns); `write` streams the trace (a team's when
/// `team`) into a temporary file beside `trace.csv`, which is renamed into place with
/// `summary_json` and the resolved `scenario.toml` (after `note`, comment lines, when given)
/// written last, so that an interrupted save leaves an earlier run's files as they were. An
/// error of `write` (Ctrl-C, [`TraceColumns::stream`]) removes the temporary trace, and the
/// directory if this call made it (issue 30, att30b item 4), and is raised; a Ctrl-C after the
/// commit says the save completed ([`interrupt_after_save`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn save_run(
    py: Python<'_>,
    dir: &str,
    summary_json: &str,
    scenario: &Scenario,
    note: &str,
    done: Option<&Bound<'_, PyList>>,
    team: bool,
    write: impl FnOnce(&mut TraceWriter) -> PyResult<()>,
) -> PyResult<()> {
    let path = Path::new(dir);
    let flying = scenario.is_flying();
    let new_dir = std::fs::symlink_metadata(path).is_err();
    let out = RunDir::open(path, &[], &[], Some(SAVE_LOCK)).map_err(save_failure)?;
    let trace = if team {
        out.team_trace(flying)
    } else {
        out.trace(flying)
    };
    let mut file = trace.map_err(crate::errors::failure)?;
    if let Err(e) = write(file.writer()) {
        drop(out.abandon(file, "interrupted"));
        drop(out);
        if new_dir {
            let _ = std::fs::remove_dir(path);
        }
        return Err(e);
    }
    out.finish_json(
        file,
        &format!("{note}{}", isotrack_runs::summary::scenario_toml(scenario)),
        summary_json,
    )
    .map_err(crate::errors::failure)?;
    interrupt_after_save(py, dir, done)
}
