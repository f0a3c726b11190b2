//! The command line's tools for Python: the `isotrack` command itself (the package's console
//! entry runs it in this module, so one build gives both), run directories written as
//! `isotrack run --out` writes them, `plot`, `report` and the controller variants of `compare`.

use crate::{PyScenario, ScenarioErrorPy};
use isotrack_cli::cli::{FigureOptions, ImageFormat, PlotArgs, ReportArgs};
use isotrack_runs::summary::scenario_toml;
use isotrack_runs::trace::{TraceWriter, TELEMETRY_COLUMNS};
use isotrack_runs::{exit, Failure};
use isotrack_core::vehicle::Telemetry;
use isotrack_sim::{TraceRow, TraceSink};
use numpy::PyReadonlyArray1;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::io::Write;
use std::path::{Path, PathBuf};

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

/// The `isotrack` command line: `argv` with the program name first; returns the exit code.
/// Output goes to the process's stdout and stderr, as the binary's does; a panic (its message
/// already printed by the panic hook) exits 101, as the binary's does, never a Python traceback.
#[pyfunction]
pub fn cli_main(py: Python<'_>, argv: Vec<String>) -> u8 {
    let code = py.detach(|| {
        std::panic::catch_unwind(|| isotrack_cli::entry::main_with(argv)).unwrap_or(101)
    });
    let _ = std::io::stdout().flush();
    code
}

/// One `trace.csv` column, checked to have `n` rows.
fn column<'py>(trace: &Bound<'py, PyDict>, name: &str, n: Option<usize>) -> PyResult<Vec<f64>> {
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

/// Writes a run directory as `isotrack run --out` does: `trace.csv` from the run's columns
/// (numbers in the same shortest round-trip form, so they read back bit for bit),
/// `summary.json` (its text) and the resolved `scenario.toml`.
#[pyfunction]
pub fn write_run(
    dir: &str,
    summary_json: &str,
    scenario: &PyScenario,
    trace: &Bound<'_, PyDict>,
) -> PyResult<()> {
    let dir = Path::new(dir);
    let io = |what: &Path, e: std::io::Error| {
        PyOSError::new_err(format!("cannot write {}: {e}", what.display()))
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let flying = scenario.inner.is_flying();
    let t = column(trace, "t_s", None)?;
    let n = Some(t.len());
    let cols: Vec<Vec<f64>> = ["x_m", "y_m", "heading_rad", "s", "error", "omega_radps"]
        .iter()
        .chain(["s_measured"].iter())
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
    let path = dir.join("trace.csv");
    let mut w = TraceWriter::create(&path, flying).map_err(|e| io(&path, e))?;
    for (i, &t_s) in t.iter().enumerate() {
        let m = cols[6][i];
        w.record(&TraceRow {
            t_s,
            x_m: cols[0][i],
            y_m: cols[1][i],
            heading_rad: cols[2][i],
            s: cols[3][i],
            error: cols[4][i],
            omega_radps: cols[5][i],
            // NaN in the numpy column is "no sample yet", an empty cell in the file.
            s_measured: (!m.is_nan()).then_some(m),
            telemetry: telemetry.as_ref().map(|tm| Telemetry {
                altitude_m: tm[0][i],
                airspeed_mps: tm[1][i],
                roll_rad: tm[2][i],
            }),
        });
    }
    w.finish().map_err(|e| io(&path, e))?;
    let path = dir.join("summary.json");
    std::fs::write(&path, format!("{summary_json}\n")).map_err(|e| io(&path, e))?;
    let path = dir.join("scenario.toml");
    std::fs::write(&path, scenario_toml(&scenario.inner)).map_err(|e| io(&path, e))?;
    Ok(())
}

/// `isotrack plot RUN_DIR... [--out DIR] [--format png|svg] [--animate]` with the default look;
/// a sweep directory takes `x`, `group` and `metric`.
#[pyfunction]
#[pyo3(signature = (runs, out=None, svg=false, animate=false, x=None, group=None, metric=None))]
#[allow(clippy::too_many_arguments)]
pub fn plot(
    py: Python<'_>,
    runs: Vec<PathBuf>,
    out: Option<PathBuf>,
    svg: bool,
    animate: bool,
    x: Option<String>,
    group: Option<String>,
    metric: Option<String>,
) -> PyResult<()> {
    if runs.is_empty() {
        return Err(PyValueError::new_err(
            "plot needs at least one run directory",
        ));
    }
    let args = PlotArgs {
        runs,
        format: if svg {
            ImageFormat::Svg
        } else {
            ImageFormat::Png
        },
        out,
        x,
        animate,
        group,
        metric: metric.unwrap_or_else(|| "steady_state_max_abs_error".into()),
        look: FigureOptions {
            size: None,
            font_size: None,
            title: None,
            colormap: "viridis".into(),
            dpi: 100.0,
        },
    };
    crate::guard::no_panic(|| {
        py.detach(|| isotrack_cli::console::quietly(|| isotrack_cli::figures::plot(&args)))
            .map_err(failure)
    })
}

/// `isotrack report RUN_DIR... --out FILE`.
#[pyfunction]
pub fn report(py: Python<'_>, runs: Vec<PathBuf>, out: PathBuf) -> PyResult<()> {
    if runs.is_empty() {
        return Err(PyValueError::new_err(
            "report needs at least one run directory",
        ));
    }
    let args = ReportArgs { runs, out };
    crate::guard::no_panic(|| {
        py.detach(|| isotrack_cli::console::quietly(|| isotrack_cli::league::report(&args)))
            .map_err(failure)
    })
}

/// The scenario flown by the built-in law `kind` as `isotrack compare` flies it: the
/// scenario's own section when it already uses that kind, else the kind's defaults with the
/// shared keys carried over; then the `gains` (`KIND.KEY=VALUE`, as `--gain`) for that kind.
#[pyfunction]
pub fn controller_variant(
    scenario: &PyScenario,
    kind: &str,
    gains: Vec<String>,
) -> PyResult<PyScenario> {
    use isotrack_scenario::schema::ControllerKind;
    let k = ControllerKind::from_name(kind.trim()).ok_or_else(|| {
        PyValueError::new_err(format!(
            "unknown controller `{}`; known: {}",
            isotrack_scenario::load::clip(kind),
            ControllerKind::ALL.map(|k| k.name()).join(", ")
        ))
    })?;
    isotrack_cli::compare::check_gains(&gains).map_err(failure)?;
    let inner = isotrack_cli::compare::variant(&scenario.inner, k, &gains, &scenario.origin)
        .map_err(failure)?;
    Ok(PyScenario {
        inner,
        origin: scenario.origin.clone(),
    })
}

/// The built-in laws' names, in the order `isotrack compare` runs them.
#[pyfunction]
pub fn controller_kinds() -> Vec<&'static str> {
    isotrack_scenario::schema::ControllerKind::ALL
        .map(|k| k.name())
        .to_vec()
}

/// A sweep flown by a Python controller: `factory(scenario)` is called for each run with that
/// run's scenario and returns an object with `update(t_s, value) -> omega` (and an optional
/// `reset()`); the runs go one after another on this thread. Returns `results.csv`'s header and
/// kinds and rows as `sweep_cells` does (`progress(done, total)` called before the first run
/// and after each); the first exception of a factory or controller is raised, and Ctrl-C stops
/// it within a sample.
#[pyfunction]
#[pyo3(signature = (text, name, factory, progress=None))]
pub fn sweep_cells_with(
    py: Python<'_>,
    text: &str,
    name: &str,
    factory: Py<PyAny>,
    progress: Option<Py<PyAny>>,
) -> PyResult<crate::SweepCells> {
    use isotrack_runs::sweep::prepared::PreparedSweep;
    use isotrack_runs::sweep::rows::{row_fields, run_scenario};
    let sweep = PreparedSweep::new(text, Path::new(name)).map_err(failure)?;
    let kinds = crate::column_kinds(&sweep.plan);
    let mut rows = Vec::new();
    let mut watch = crate::guard::SignalWatch::new();
    let total = sweep.plan.total();
    let report = |done: u64| -> PyResult<()> {
        match &progress {
            Some(cb) => cb.call1(py, (done, total)).map(drop),
            None => Ok(()),
        }
    };
    report(0)?;
    for id in 0..total {
        let result = match run_scenario(&sweep.plan, &sweep.base, id, &sweep.label) {
            Err(e) => Err(e),
            Ok(scenario) => {
                let native = Py::new(
                    py,
                    PyScenario {
                        inner: scenario.clone(),
                        origin: format!("sweep {} run {id}", sweep.label),
                    },
                )?;
                let obj = factory.call1(py, (native,))?;
                if obj.bind(py).hasattr("reset")? {
                    obj.call_method0(py, "reset")?;
                }
                let mut c = crate::PyController {
                    obj,
                    error: None,
                    max_turn_rate_radps: scenario.max_turn_rate_radps(),
                };
                let r = py.detach(|| {
                    scenario.run_with_watched(&mut c, &mut isotrack_sim::NoTrace, &mut || {
                        watch.keep_going()
                    })
                });
                if let Some(e) = c.error.or(watch.error.take()) {
                    return Err(e);
                }
                r.ok_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err("stopped"))
                    .map(Ok)?
            }
        };
        rows.push(row_fields(&sweep.plan, id, result));
        report(id + 1)?;
    }
    Ok((sweep.header, kinds, rows))
}
