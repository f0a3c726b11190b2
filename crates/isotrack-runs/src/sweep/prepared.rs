//! A sweep read and checked before it runs, and a whole sweep run in memory (the Python
//! package's `sweep`).

use crate::failure::{exit, fail, scenario_failure, Failure};
use crate::sweep::pool::worker_pool;
use crate::sweep::rows::{csv_fields, results_header, run_rows};
use isotrack_scenario::sweep::SweepPlan;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::LANES;
#[allow(unused_imports)]
use rayon::iter::IntoParallelIterator;
use rayon::prelude::*;
use std::path::Path;

/// The failure code of a sweep stopped through `sweep_in_memory`'s `cancel` (128 + SIGINT, the
/// shells' convention; library callers report it as their own interruption).
pub const INTERRUPTED: u8 = 130;

/// The base scenario of a sweep: its file with `sets`, then the sweep's `[base]`, which must
/// make a valid scenario on its own; then every key of the sweep checked against the schema
/// (unknown keys and wrong types are the sweep file's errors, found before anything runs).
pub fn sweep_base(plan: &SweepPlan, sets: &[String], label: &str) -> Result<Scenario, Failure> {
    let base = load_scenario(Some(&plan.scenario), sets).map_err(scenario_failure)?;
    let base_assign = plan.run_assignments(0, label);
    let base = base
        .derive_with_in(&base_assign[..plan.base.len()], label, &plan.dir)
        .map_err(|e| {
            // A data file `[base]` names that cannot be read is a missing input (66, the
            // README's table), as for `isotrack run` (nu-15: it was 65).
            let code = if e.is_unreadable_input() {
                exit::NOINPUT
            } else {
                exit::DATAERR
            };
            fail(code, format!("{label}: [base]: {e}"))
        })?;
    plan.check_keys(&base, label)
        .map_err(|e| fail(exit::DATAERR, e.to_string()))?;
    Ok(base)
}

/// A whole sweep in memory, for library callers (the Python package): the sweep file's text
/// (`name` names it in messages; its `scenario` path is relative to `dir`), `threads` workers
/// (capped as for `--threads`). Returns the `results.csv` header and rows as fields, in
/// `run_id` order: the same cells the CLI writes. `progress(done, total)`, if given, is called
/// once before the first run (`done = 0`) and after each batch of runs, from the worker
/// threads (the front end shows it its own way: the Python package on `sys.stderr`). Setting
/// `cancel` (from another thread: a front end's Ctrl-C) stops it before its next batch of runs,
/// with a failure saying so.
pub fn sweep_in_memory(
    text: &str,
    name: &Path,
    threads: Option<usize>,
    progress: Option<&(dyn Fn(u64, u64) + Sync)>,
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<(Vec<String>, Vec<Vec<String>>), Failure> {
    let cancelled = || cancel.load(std::sync::atomic::Ordering::Relaxed);
    let PreparedSweep {
        plan,
        base,
        header,
        label,
    } = PreparedSweep::new(text, name)?;
    let pool = worker_pool(threads)?;
    let total = plan.total();
    let done = std::sync::atomic::AtomicU64::new(0);
    if let Some(p) = progress {
        p(0, total);
    }
    let lines: Vec<String> = pool.install(|| {
        (0..total.div_ceil(LANES as u64))
            .into_par_iter()
            .flat_map_iter(|c| {
                if cancelled() {
                    return Vec::new();
                }
                let ids: Vec<u64> =
                    (c * LANES as u64..((c + 1) * LANES as u64).min(total)).collect();
                let rows = run_rows(&plan, &base, &ids, &label);
                if let Some(p) = progress {
                    let n = rows.len() as u64;
                    p(
                        done.fetch_add(n, std::sync::atomic::Ordering::Relaxed) + n,
                        total,
                    );
                }
                rows
            })
            .collect()
    });
    if cancelled() {
        return Err(fail(INTERRUPTED, "interrupted".into()));
    }
    let rows = lines
        .iter()
        .map(|l| csv_fields(l).unwrap_or_default())
        .collect();
    Ok((header, rows))
}

/// A sweep read and checked, ready to run run by run (the Python package runs a sweep with a
/// Python controller this way: [`run_scenario`], then [`row_fields`]).
pub struct PreparedSweep {
    /// The plan.
    pub plan: SweepPlan,
    /// The base scenario (its file, then `[base]`).
    pub base: Scenario,
    /// The `results.csv` header.
    pub header: Vec<String>,
    /// The sweep's name in messages.
    pub label: String,
}

impl PreparedSweep {
    /// The sweep file's text (`name` names it in messages; its `scenario` path is relative to
    /// `name`'s directory), parsed and checked as `isotrack sweep` checks it before running.
    pub fn new(text: &str, name: &Path) -> Result<Self, Failure> {
        let plan = SweepPlan::parse(text, name).map_err(|e| fail(exit::DATAERR, e.to_string()))?;
        let label = name.display().to_string();
        let base = sweep_base(&plan, &[], &label)?;
        // A team's sweep has the team columns, as `isotrack sweep` writes them.
        let header = results_header(&plan, base.spec().team.is_some());
        Ok(Self {
            plan,
            base,
            header,
            label,
        })
    }
}
