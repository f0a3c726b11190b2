//! The command line's tools for Python: the `isotrack` command itself (the package's console
//! entry runs it in this module, so one build gives both), run directories written as
//! `isotrack run --out` writes them, `plot`, `report` and the controller variants of `compare`.

use crate::columns::{save_run, TraceColumns};
use crate::errors::failure;
use crate::scenario::PyScenario;
use isotrack_commands::cli::{FigureOptions, ImageFormat, PlotArgs, ReportArgs};
use isotrack_runs::sweep::prepared::PreparedSweep;
use isotrack_runs::sweep::rows::{row_fields, run_scenario, team_row_fields};
use isotrack_runs::Failure;
use isotrack_scenario::Scenario;
use isotrack_sim::TraceSink;
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The `isotrack` command line: `argv` with the program name first; returns the exit code.
/// Output goes to the process's stdout and stderr, as the binary's does; a panic (its message
/// already printed by the panic hook) exits 101, as the binary's does, never a Python traceback.
#[pyfunction]
pub fn cli_main(py: Python<'_>, argv: Vec<String>) -> u8 {
    let code = py.detach(|| {
        std::panic::catch_unwind(|| isotrack_commands::entry::main_with(argv)).unwrap_or(101)
    });
    let _ = std::io::stdout().flush();
    code
}

/// Writes a run directory as `isotrack run --out` does: `trace.csv` from the run's columns
/// (numbers in the same shortest round-trip form, so they read back bit for bit),
/// `summary.json` (its text) and the resolved `scenario.toml` (after `note`, comment lines,
/// when given). Holding the directory's lock as `run --out` does ([`crate::columns::SAVE_LOCK`],
/// [`save_run`]): another writer there is refused with an `OSError` naming it, and a
/// `run --out` while this writes exits 73.
#[pyfunction]
#[pyo3(signature = (dir, summary_json, scenario, trace, note="", done=None))]
pub fn write_run(
    py: Python<'_>,
    dir: &str,
    summary_json: &str,
    scenario: &PyScenario,
    trace: &Bound<'_, PyDict>,
    note: &str,
    done: Option<&Bound<'_, PyList>>,
) -> PyResult<()> {
    let cols = TraceColumns::read(trace, scenario.inner.is_flying())?;
    save_run(
        py,
        dir,
        summary_json,
        &scenario.inner,
        note,
        done,
        false,
        |w| cols.stream(py, |_, row| w.record(row)),
    )
}

/// `isotrack plot RUN_DIR... [--out DIR] [--format png|svg] [--animate]` with the default look;
/// a sweep directory takes `x`, `group` and `metric`. Ctrl-C raises `KeyboardInterrupt` at
/// once; the figures are rendered in a staging directory and moved into place whole
/// ([`staged`]).
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
            colormap: None,
            dpi: 100.0,
        },
    };
    if !args.runs.iter().all(|d| d.is_dir()) {
        // Refused at once, with the command's message (nothing is created for it).
        return crate::guard::no_panic(|| {
            py.detach(|| {
                isotrack_commands::console::quietly(|| isotrack_commands::figures::plot(&args))
            })
            .map_err(failure)
        });
    }
    let dir = args.out.clone().unwrap_or_else(|| args.runs[0].clone());
    // att40-27: a run or sweep directory drawn into is locked as `isotrack plot` locks it
    // (refused while `run --out` or a sweep writes it: a writer's lock file is there), for the
    // whole render and move; a folder that is neither gets no lock file (the command refuses
    // it, 66, 1a9b2e4).
    // A sweep directory is locked by the command itself (its input, att38-8): locked here too,
    // this process would refuse itself (att41-16).
    let lock_file = dir.join(isotrack_runs::sweep::lock::LOCK_FILE).exists();
    let holds_run =
        !dir.join("results.csv").exists() && (dir.join("summary.json").exists() || lock_file);
    let _lock = if dir.is_dir() && holds_run {
        Some(isotrack_runs::sweep::lock::lock_output_dir(&dir, "plot").map_err(failure)?)
    } else {
        None
    };
    staged(py, &dir, Guard::Figures, move |staging| {
        let mut args = args;
        args.out = Some(staging.to_path_buf());
        isotrack_commands::figures::plot(&args)
    })
}

/// What [`staged`] checks in the destination before moving the files drawn over it.
#[derive(Clone, Copy, PartialEq)]
enum Guard {
    /// Nothing (a report's page named by the caller).
    Nothing,
    /// The figures `isotrack plot` refuses to replace unless isotrack wrote them
    /// (att40-25: `trajectory.*`, `timeseries.*`, `team.*`, `animation.gif`, att41-10: a
    /// sweep's `sweep_*_vs_*.png`/`.svg`, without
    /// isotrack's mark, or not a regular file): refused (OSError naming the file) before any is
    /// moved. The command checks them in the directory it draws in, which for this wrapper is
    /// the staging directory, empty.
    Figures,
}

/// The first file of `from` whose namesake in `to` [`Guard::Figures`] refuses, with why.
fn foreign_figure(from: &Path, to: &Path) -> PyResult<()> {
    let io = |p: &Path, e: std::io::Error| PyOSError::new_err(format!("{}: {e}", p.display()));
    for entry in std::fs::read_dir(from).map_err(|e| io(from, e))? {
        let name = entry.map_err(|e| io(from, e))?.file_name();
        let n = name.to_string_lossy();
        // att41-10 (Python addendum): a sweep's figure too, `sweep_METRIC_vs_X.png`/`.svg`.
        let figure = ["trajectory.", "timeseries.", "team."]
            .iter()
            .any(|p| n.starts_with(p))
            || n == "animation.gif"
            || (n.starts_with("sweep_") && (n.ends_with(".png") || n.ends_with(".svg")));
        if !figure {
            continue;
        }
        let target = to.join(&name);
        if let Ok(m) = std::fs::symlink_metadata(&target) {
            if !m.is_file() {
                return Err(PyOSError::new_err(format!(
                    "{} is not a regular file (a link, FIFO, directory or device): isotrack never replaces it; move it away, or draw elsewhere (out=DIR)",
                    target.display()
                )));
            }
        }
        isotrack_commands::figures::refuse_foreign_figures(to, &[n.to_string()])
            .map_err(failure)?;
    }
    Ok(())
}

/// A fresh staging directory in `dir`: `.isotrack-partial-PID-N`, hidden, removed once its
/// files are moved out (or the work is abandoned).
fn staging_dir(dir: &Path) -> PyResult<PathBuf> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let io = |p: &Path, e: std::io::Error| {
        PyOSError::new_err(format!("cannot create {}: {e}", p.display()))
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    loop {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let p = dir.join(format!(".isotrack-partial-{}-{n}", std::process::id()));
        match std::fs::create_dir(&p) {
            Ok(()) => return Ok(p),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io(&p, e)),
        }
    }
}

/// Renders into a staging directory inside `dir` on a thread of its own while this thread
/// answers Ctrl-C ([`crate::guard::detached_then`]), then moves each file written into `dir`
/// (a rename within one directory: a file appears whole or not at all). On
/// `KeyboardInterrupt` the staging directory is removed, at once and again when the render
/// ends (it goes on, its output discarded, as `check`'s does), so no half-written file is ever
/// under the name the caller asked for.
fn staged(
    py: Python<'_>,
    dir: &Path,
    guard: Guard,
    render: impl FnOnce(&Path) -> Result<(), Failure> + Send + 'static,
) -> PyResult<()> {
    // The directories this call creates (`dir` and any missing parent, deepest first): removed
    // again, when empty, unless the figures were moved into them, so that Ctrl-C or a failure
    // leaves nothing behind, an empty output directory included, as the command does.
    let made: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|p| !p.as_os_str().is_empty() && std::fs::symlink_metadata(p).is_err())
        .map(Path::to_path_buf)
        .collect();
    let unmake = |made: &[PathBuf]| {
        for d in made {
            let _ = std::fs::remove_dir(d);
        }
    };
    let staging = staging_dir(dir).inspect_err(|_| unmake(&made))?;
    let (theirs, gone, made_too) = (staging.clone(), staging.clone(), made.clone());
    let outcome = crate::guard::no_panic(|| {
        crate::guard::detached_then(
            py,
            move || isotrack_commands::console::quietly(|| render(&theirs)),
            move || {
                let _ = std::fs::remove_dir_all(&gone);
                // An abandoned render ends later: the directories this call made go then too
                // (empty only: another writer's files are never touched).
                unmake(&made_too);
            },
        )
    });
    let moved = match outcome {
        Ok(Ok(())) => match guard {
            Guard::Figures => {
                foreign_figure(&staging, dir).and_then(|()| move_files(&staging, dir))
            }
            Guard::Nothing => move_files(&staging, dir),
        },
        // Named as the caller named them, not by the staging directory.
        Ok(Err(f)) => Err(failure(Failure {
            message: f
                .message
                .replace(&staging.display().to_string(), &dir.display().to_string()),
            ..f
        })),
        Err(e) => {
            let _ = std::fs::remove_dir_all(&staging);
            unmake(&made);
            return Err(e);
        }
    };
    let _ = std::fs::remove_dir_all(&staging);
    if moved.is_err() {
        unmake(&made);
    }
    moved
}

/// Moves the files of `from` into `to` (renames: the same file system).
fn move_files(from: &Path, to: &Path) -> PyResult<()> {
    let io = |p: &Path, e: std::io::Error| PyOSError::new_err(format!("{}: {e}", p.display()));
    for entry in std::fs::read_dir(from).map_err(|e| io(from, e))? {
        let entry = entry.map_err(|e| io(from, e))?;
        let target = to.join(entry.file_name());
        std::fs::rename(entry.path(), &target).map_err(|e| io(&target, e))?;
    }
    Ok(())
}

/// `isotrack report RUN_DIR... --out FILE`, interruptible and staged as [`plot`].
#[pyfunction]
pub fn report(py: Python<'_>, runs: Vec<PathBuf>, out: PathBuf) -> PyResult<()> {
    if runs.is_empty() {
        return Err(PyValueError::new_err(
            "report needs at least one run directory",
        ));
    }
    let name = out
        .file_name()
        .ok_or_else(|| PyValueError::new_err(format!("{}: not a file name", out.display())))?
        .to_owned();
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    staged(py, &dir, Guard::Nothing, move |staging| {
        isotrack_commands::league::report(&ReportArgs {
            runs,
            out: staging.join(name),
        })
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
    isotrack_commands::compare::check_gains(&gains).map_err(failure)?;
    let inner = isotrack_commands::compare::variant(&scenario.inner, k, &gains, &scenario.origin)
        .map_err(failure)?;
    Ok(PyScenario {
        inner,
        origin: scenario.origin.clone(),
        folder: scenario.folder.clone(),
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
) -> PyResult<crate::sweep::SweepCells> {
    let sweep = crate::sweep::prepare(text, name)?;
    let mut factory = SweepFactory {
        factory: &factory,
        label: &sweep.label,
        // A relative path the factory's scenario is `set` to is read as the sweep reads its own.
        folder: crate::scenario::absolute_dir(&sweep.plan.dir),
        returned: crate::controller::Returned::default(),
    };
    let team = sweep.base.spec().team.is_some();
    let kinds = crate::sweep::column_kinds(&sweep.plan, team);
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
        let fields = if team {
            factory.team_row(py, &sweep, id)?
        } else {
            let result = factory.run(py, &sweep, id, &mut watch)?;
            row_fields(&sweep.plan, id, result)
        };
        rows.push(fields);
        report(id + 1)?;
    }
    crate::sweep::literal_cells(&sweep.plan, &kinds, &mut rows);
    Ok((sweep.header, kinds, rows))
}

/// A sweep's `controller_factory` ([`sweep_cells_with`]): called with each run's scenario (for a
/// team, once per vehicle), never to return one object for two runs or vehicles.
struct SweepFactory<'a> {
    factory: &'a Py<PyAny>,
    /// The sweep's label, in its scenarios' origin (`sweep LABEL run ID`).
    label: &'a str,
    /// The folder a relative path the factory's scenario is `set` to is read against.
    folder: PathBuf,
    /// Every object returned so far, with the run (and vehicle) it flies.
    returned: crate::controller::Returned,
}

impl SweepFactory<'_> {
    /// `factory(scenario)` for run `id`, a new native scenario for each call.
    fn call(&self, py: Python<'_>, scenario: &Scenario, id: u64) -> PyResult<Py<PyAny>> {
        let native = Py::new(
            py,
            PyScenario {
                inner: scenario.clone(),
                origin: format!("sweep {} run {}", self.label, id),
                folder: Some(self.folder.clone()),
            },
        )?;
        self.factory.call1(py, (native,))
    }

    /// Records `obj` as flying `now`: refused when the factory returned it for an earlier run.
    fn check_new(&mut self, py: Python<'_>, obj: &Py<PyAny>, now: String) -> PyResult<()> {
        if let Some(earlier) = self.returned.check(py, obj, now.clone())? {
            return Err(crate::controller::shared_across_runs(&earlier, &now));
        }
        Ok(())
    }

    /// Run `id`'s `results.csv` fields, a team's: each vehicle flies its own controller (the
    /// factory is called once per vehicle), the runs on this thread.
    fn team_row(
        &mut self,
        py: Python<'_>,
        sweep: &PreparedSweep,
        id: u64,
    ) -> PyResult<Vec<String>> {
        let scenario = match run_scenario(&sweep.plan, &sweep.base, id, &sweep.label) {
            Err(e) => return Ok(team_row_fields(&sweep.plan, id, Err(e), String::new())),
            Ok(scenario) => scenario,
        };
        let n = scenario.spec().team.as_ref().map_or(0, |t| t.count());
        let mut objs = Vec::with_capacity(n);
        for _ in 0..n {
            let obj = self.call(py, &scenario, id)?;
            // One object for two vehicles would interleave their samples through one state (an
            // integral, a last time): refused, never flown shared.
            if let Some(j) = objs.iter().position(|o: &Py<PyAny>| o.is(&obj)) {
                return Err(PyValueError::new_err(format!(
                    "controller_factory returned the same object for vehicles {j} and {} of run \
                     {id}: each vehicle flies its own instance (its state is its own, never \
                     shared); return a new controller at every call",
                    objs.len()
                )));
            }
            self.check_new(py, &obj, format!("vehicle {} of run {id}", objs.len()))?;
            objs.push(obj);
        }
        let (r, _) = crate::team::run_team_python(py, &scenario, objs, false)?;
        Ok(team_row_fields(&sweep.plan, id, Ok(Some(r)), String::new()))
    }

    /// Run `id`'s result, a single vehicle's, flown on this thread by the factory's controller
    /// (`reset()` first when it has the method): its first exception is raised, and Ctrl-C
    /// (`watch`) stops it within a sample.
    fn run(
        &mut self,
        py: Python<'_>,
        sweep: &PreparedSweep,
        id: u64,
        watch: &mut crate::guard::SignalWatch,
    ) -> PyResult<Result<isotrack_sim::RunResult, String>> {
        let scenario = match run_scenario(&sweep.plan, &sweep.base, id, &sweep.label) {
            Err(e) => return Ok(Err(e)),
            Ok(scenario) => scenario,
        };
        let obj = self.call(py, &scenario, id)?;
        self.check_new(py, &obj, format!("run {id}"))?;
        let mut c =
            crate::controller::PyController::started(py, obj, scenario.max_turn_rate_radps())?;
        let r = py.detach(|| {
            scenario.run_with_watched(&mut c, &mut isotrack_sim::NoTrace, &mut || {
                watch.keep_going()
            })
        });
        if let Some(e) = c.error.or(watch.error.take()) {
            return Err(e);
        }
        r.ok_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err("stopped"))
            .map(Ok)
    }
}
