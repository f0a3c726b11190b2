//! A sweep run for Python: `results.csv`'s header, each column's kind and its cells.

use crate::errors::ScenarioErrorPy;
use crate::guard;
use crate::scenario::PyScenario;
use pyo3::prelude::*;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// A sweep's answer to Python: `results.csv`'s header, each column's kind, and its cells.
pub(crate) type SweepCells = (Vec<String>, Vec<&'static str>, Vec<Vec<String>>);

/// A sweep from its file's text: `(header, kinds, rows)`: `results.csv`'s header, each
/// column's kind ([`column_kinds`]) and its cells in `run_id` order; `name` names the sweep in
/// messages and anchors its relative `scenario` path. `progress(done, total)`, a Python
/// callable, is called on this thread about every 20 ms while the runs go and once at the end.
/// Ctrl-C stops it between batches of runs.
#[pyfunction]
#[pyo3(signature = (text, name, threads=None, progress=None))]
pub(crate) fn sweep_cells(
    py: Python<'_>,
    text: &str,
    name: &str,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<SweepCells> {
    use std::sync::atomic::{AtomicU64, Ordering};
    let prepared = prepare(text, name)?;
    let kinds = column_kinds(&prepared.plan, prepared.base.spec().team.is_some());
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
    let mut rows = rows;
    literal_cells(&prepared.plan, &kinds, &mut rows);
    Ok((header, kinds, rows))
}

/// A sweep prepared from its file's text (`name` names it and anchors its `scenario` path).
/// A `scenario` that cannot be read gets the class the same file gets as a top-level argument
/// (ver30b-12): `IsADirectoryError` for a directory, `OSError` for a FIFO, a device or a
/// socket (never opened), `FileNotFoundError` when it is missing.
///
/// Every data file a run of the sweep reads (`field.path`, `field.paths`, of its scenario,
/// `[base]` or `[grid]`) is then checked as `isotrack sweep` checks it before any run (exit 66
/// there): one that cannot be read is a `FileNotFoundError` with the CLI's message, before any
/// run (att30n-10: Python ran the sweep, those runs `invalid_scenario`).
pub(crate) fn prepare(
    text: &str,
    name: &str,
) -> PyResult<isotrack_runs::sweep::prepared::PreparedSweep> {
    let prepared = prepare_base(text, name)?;
    isotrack_runs::sweep::manifest::plan_data_file_digests_all(
        &prepared.plan,
        prepared.base.given(),
        &prepared.label,
    )
    .map_err(sweep_failure)?;
    Ok(prepared)
}

/// The scenario every run of a sweep is derived from: the sweep file's `scenario` with its
/// `[base]` keys set, a relative file path later given to its `set` read against the sweep
/// file's folder, as the sweep reads its `[grid]` and `[base]` values (att30n-3: a row's
/// relative `field.path` cell set on the sweep's `scenario` file was read against that file's
/// folder: another file). Setting a row's swept keys on it and running it gives the row again.
#[pyfunction]
pub(crate) fn sweep_base_scenario(text: &str, name: &str) -> PyResult<PyScenario> {
    let prepared = prepare(text, name)?;
    Ok(PyScenario {
        inner: prepared.base,
        origin: format!("<sweep {}>", prepared.label),
        folder: Some(crate::scenario::absolute_dir(&prepared.plan.dir)),
    })
}

/// [`prepare`] without the check of its data files.
fn prepare_base(text: &str, name: &str) -> PyResult<isotrack_runs::sweep::prepared::PreparedSweep> {
    isotrack_runs::sweep::prepared::PreparedSweep::new(text, Path::new(name)).map_err(|f| {
        if f.code != isotrack_runs::exit::NOINPUT {
            return sweep_failure(f);
        }
        let plan = isotrack_scenario::sweep::SweepPlan::parse(text, Path::new(name));
        match plan.ok().map(|p| std::fs::metadata(&p.scenario)) {
            Some(Ok(m)) if m.is_dir() => pyo3::exceptions::PyIsADirectoryError::new_err(f.message),
            Some(Ok(m)) if !m.is_file() => pyo3::exceptions::PyOSError::new_err(f.message),
            _ => sweep_failure(f),
        }
    })
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
/// for `outcome`, `outcome_detail`, `warnings` and any other swept key; `"table"` for a swept
/// key (or an element of a split one) with a table among its values, whose cells
/// [`literal_cells`] rewrites as TOML literals. A team's sweep (`team`) ends with the team
/// columns: `"float"`, `order_preserved` `"bool"`.
pub(crate) fn column_kinds(
    plan: &isotrack_scenario::sweep::SweepPlan,
    team: bool,
) -> Vec<&'static str> {
    let kind = |values: &mut dyn Iterator<Item = Option<&toml::Value>>| {
        let (mut ints, mut floats, mut bools, mut tables, mut n) = (0, 0, 0, 0, 0);
        for v in values {
            n += 1;
            match v {
                Some(toml::Value::Integer(_)) => ints += 1,
                Some(toml::Value::Float(_)) => floats += 1,
                Some(toml::Value::Boolean(_)) => bools += 1,
                Some(toml::Value::Table(_)) => tables += 1,
                _ => {}
            }
        }
        if tables > 0 {
            "table"
        } else if n > 0 && ints == n {
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
    if team {
        kinds.extend(isotrack_runs::sweep::rows::TEAM_COLUMNS.iter().map(|c| {
            if *c == "order_preserved" {
                "bool"
            } else {
                "float"
            }
        }));
    }
    kinds
}

/// Rewrites the cells of the `"table"` columns ([`column_kinds`]) as the TOML literals of the
/// values the runs set (strings quoted, as `--set` reads them), so that Python reads each cell
/// back as the value itself: a table (`{ ki = 1.0, kp = 2.0 }`) as a dict, a string as a str,
/// never one mistaken for the other (`results.csv` writes a string unquoted). A row's run is
/// its `run_id` (its first cell); the values are picked as [`SweepPlan::run_cells`] picks them.
///
/// [`SweepPlan::run_cells`]: isotrack_scenario::sweep::SweepPlan::run_cells
pub(crate) fn literal_cells(
    plan: &isotrack_scenario::sweep::SweepPlan,
    kinds: &[&str],
    rows: &mut [Vec<String>],
) {
    use isotrack_scenario::sweep::value_literal;
    // Each grid key's first column and, for a key whose values are arrays of one length
    // (split into `KEY[i]` columns), that length.
    let mut spans = Vec::with_capacity(plan.grid.len());
    let mut col = 1;
    for (_, list) in &plan.grid {
        let width = list.first().and_then(|v| v.as_array()).map(|a| a.len());
        let split = width.filter(|&w| {
            list.iter()
                .all(|v| v.as_array().is_some_and(|a| a.len() == w))
        });
        spans.push((col, split));
        col += split.unwrap_or(1);
    }
    if !(1..col).any(|c| kinds.get(c) == Some(&"table")) {
        return;
    }
    for row in rows.iter_mut() {
        let Some(id) = row.first().and_then(|c| c.parse::<u64>().ok()) else {
            continue;
        };
        let mut g = id / plan.draws.max(1);
        let mut picked = vec![0; plan.grid.len()];
        for (i, (_, list)) in plan.grid.iter().enumerate().rev() {
            let n = list.len().max(1) as u64;
            picked[i] = (g % n) as usize;
            g /= n;
        }
        for ((first, split), ((_, list), &p)) in spans.iter().zip(plan.grid.iter().zip(&picked)) {
            let Some(v) = list.get(p) else { continue };
            let values: Vec<&toml::Value> = match (split, v.as_array()) {
                (Some(_), Some(a)) => a.iter().collect(),
                _ => vec![v],
            };
            for (k, x) in values.into_iter().enumerate() {
                let c = first + k;
                if kinds.get(c) == Some(&"table") {
                    if let Some(cell) = row.get_mut(c) {
                        *cell = value_literal(x);
                    }
                }
            }
        }
    }
}
