//! `isotrack._native`: the engine for Python. Scenarios load, override and resolve exactly as on
//! the command line; runs return the `summary.json` content and the `trace.csv` columns as
//! numpy arrays; a Python object with `update(t_s, value) -> omega` can fly in place of the
//! built-in controller. The engine runs with the GIL released (a Python controller takes it
//! back for each of its samples only).

use numpy::PyArray1;
use pyo3::prelude::*;

mod columns;
mod controller;
mod env;
mod errors;
mod guard;
mod league;
mod scenario;
mod sweep;
mod team;
mod tools;
mod values;

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
    m.add_class::<scenario::PyScenario>()?;
    m.add_class::<env::PyEnvBatch>()?;
    m.add_class::<team::PyTeamEnv>()?;
    m.add_function(wrap_pyfunction!(team::team_run, m)?)?;
    m.add_function(wrap_pyfunction!(team::write_team_run, m)?)?;
    m.add_function(wrap_pyfunction!(columns::after_save_message, m)?)?;
    m.add_function(wrap_pyfunction!(team::is_team, m)?)?;
    m.add_function(wrap_pyfunction!(team::team_count, m)?)?;
    m.add(
        "ScenarioError",
        m.py().get_type::<errors::ScenarioErrorPy>(),
    )?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(file_sha256, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_cells, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep_base_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(values::toml_cell, m)?)?;
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
