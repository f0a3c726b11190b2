//! `isotrack sweep` and `isotrack merge`: their arguments and what they print. The engine (plan
//! execution, manifest, resume index, merge, the output-directory lock) is `isotrack-runs`'
//! `sweep` module, re-exported here for the other commands and the Python package.

use crate::cli::{MergeArgs, SweepArgs};
use crate::exit;
use crate::run::Failure;
use indicatif::{ProgressBar, ProgressStyle};
pub use isotrack_runs::sweep::index::MAX_RESULTS_FILE_BYTES;
pub use isotrack_runs::sweep::lock::{lock_output_dir, DirLock, LOCK_FILE};
pub use isotrack_runs::sweep::prepared::{sweep_in_memory, PreparedSweep, INTERRUPTED};
pub use isotrack_runs::sweep::rows::{row_fields, run_scenario, METRIC_COLUMNS};
use isotrack_runs::sweep::run::{SweepJob, SweepReport};

fn fail(code: u8, message: String) -> Failure {
    Failure { code, message }
}

/// The worker pool for `--threads` (capped at 8 per core; all cores by default), the cap's
/// note printed on stderr.
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, Failure> {
    let (pool, note) = isotrack_runs::sweep::pool::worker_pool_noted(threads)?;
    if let Some(note) = note {
        errln!("{note}");
    }
    Ok(pool)
}

/// The sweep's progress bar on stderr (hidden when stderr is not a terminal).
fn runs_progress_bar(runs: u64) -> ProgressBar {
    let pb = ProgressBar::new(runs);
    pb.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} runs, ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    pb
}

/// The most shards `--shard K/N` may split a sweep into (a job array of a million tasks).
const MAX_SHARDS: u64 = 1_000_000;

/// Parses `K/N`: decimal digits without sign, spaces or leading zeros, `1 <= K <= N <=`
/// [`MAX_SHARDS`].
fn parse_shard(s: &str) -> Result<(u64, u64), Failure> {
    let bad = || {
        fail(
            exit::USAGE,
            format!("--shard {s}: expected K/N with 1 <= K <= N"),
        )
    };
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    // Canonical digits only (`01/2` and `+1/2` once named shard 1 of 2), and a count a job
    // array can have.
    let canonical = |t: &str| {
        !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()) && (t == "0" || !t.starts_with('0'))
    };
    if !canonical(k) || !canonical(n) {
        return Err(bad());
    }
    let (k, n): (u64, u64) = (k.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    if n > MAX_SHARDS {
        return Err(fail(
            exit::USAGE,
            format!("--shard {s}: at most {MAX_SHARDS} shards"),
        ));
    }
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// `isotrack sweep`.
pub fn sweep(a: &SweepArgs) -> Result<(), Failure> {
    let job = SweepJob::prepare(&a.sweep, &a.set)?;
    let (k, n) = match &a.shard {
        Some(s) => parse_shard(s)?,
        None => (1, 1),
    };
    for note in job.plan.duplicate_notes() {
        errln!("note: {note}");
    }
    let opened_at = std::time::SystemTime::now();
    let _said = say_runs_on_interrupt(&a.out, job.shard_runs((k, n)), a.resume);
    let out = job.open_output(&a.out, (k, n), a.resume, a.force)?;
    if a.force {
        note_figures_from_before(&a.out, opened_at);
    }
    let new_runs = out.shard_runs - out.done.len() as u64;
    let pb = runs_progress_bar(new_runs);
    let pool = worker_pool(a.threads)?;
    let started = std::time::Instant::now();
    job.run_missing(&out, &pool, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let report = job.finish(&out)?;
    let total = job.plan.total();
    let summary = format!(
        "{} runs ({} new) of {} in {:.2} s -> {}",
        report.rows,
        new_runs,
        if n > 1 {
            format!("shard {k}/{n} ({} of {total})", out.shard_runs)
        } else {
            format!("{total}")
        },
        started.elapsed().as_secs_f64(),
        isotrack_runs::owned::shell_quoted(&out.results)
    );
    print_tally(&report);
    let invalid = report.invalid;
    if invalid > 0 {
        // Every run is recorded, but a sweep with invalid runs did not do what it was asked.
        return Err(fail(
            exit::DATAERR,
            format!(
                "{summary}; {invalid} of them invalid (outcome invalid_scenario; the reason is in outcome_detail)"
            ),
        ));
    }
    outln!("{summary}");
    Ok(())
}

/// The sweep figures `plot` writes (`sweep_METRIC_vs_X[_by_GROUP].png` or `.svg`) in sweep
/// directory `dir` from before `since`, named in a note after `--force` started the sweep
/// over: an earlier sweep's figures beside the new results.csv read as this sweep's (att36-11,
/// nu-21's class). They are not removed: a file of such a name may be the user's, and isotrack
/// never removes a file it may not have written (att38-1's rule; `run` says the same of a run
/// directory's figures).
fn note_figures_from_before(dir: &std::path::Path, since: std::time::SystemTime) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut names: Vec<String> = entries
        .flatten()
        .filter(|e| {
            e.metadata()
                .is_ok_and(|m| m.is_file() && m.modified().map_or(true, |t| t < since))
        })
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| {
            n.starts_with("sweep_")
                && n.contains("_vs_")
                && (n.ends_with(".png") || n.ends_with(".svg"))
        })
        .collect();
    if names.is_empty() {
        return;
    }
    names.sort();
    const NAMED: usize = 5;
    let more = names.len().saturating_sub(NAMED);
    names.truncate(NAMED);
    let shown: Vec<String> = names
        .iter()
        .map(|n| isotrack_scenario::load::clip(n))
        .collect();
    errln!(
        "note: {} also holds {}{} from before this sweep, not this sweep's (isotrack never removes a file it may not have written): `isotrack plot {}` draws this sweep's",
        isotrack_runs::owned::shell_quoted(dir),
        shown.join(", "),
        if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        },
        isotrack_runs::owned::shell_quoted(dir)
    );
}

/// The one-line tally of the runs that did not complete or ended with a warning, on stderr
/// (nothing when there are none): how many, the first few run ids, where the reasons are.
fn print_tally(report: &SweepReport) {
    let f = &report.flagged;
    if f.count == 0 {
        return;
    }
    let ids: Vec<String> = f.first_ids.iter().map(u64::to_string).collect();
    let more = if f.count > f.first_ids.len() as u64 {
        ", ..."
    } else {
        ""
    };
    errln!(
        "warning: {} of {} runs did not complete or ended with a warning (run_id {}{more}): see their outcome, outcome_detail and warnings columns",
        f.count,
        report.rows,
        ids.join(", ")
    );
}

/// The rows (whole lines after the header) of `results.csv` at `path` when it is not the file
/// `before` names ([`isotrack_runs::files::identity`]): a table this command put in place (a
/// sweep's, renewed or begun, or a merge's); also when it is still that file if `continued`
/// (`sweep --resume`: the rows it continues are held, renewed yet or not; att53o-1); `None`
/// when it is absent or still the earlier one.
fn rows_held(path: &std::path::Path, before: Option<(u64, u64)>, continued: bool) -> Option<u64> {
    use std::io::Read;
    let now = isotrack_runs::files::identity(path);
    if now.is_none() || (now == before && !continued) {
        return None;
    }
    let mut f = isotrack_runs::files::open_read_regular(path).ok()?;
    let (mut lines, mut buf) = (0u64, vec![0u8; 1 << 16]);
    loop {
        match f.read(&mut buf) {
            Ok(0) => break,
            Ok(k) => lines += buf[..k].iter().filter(|&&b| b == b'\n').count() as u64,
            Err(_) => return None,
        }
    }
    Some(lines.saturating_sub(1))
}

/// Registers the line an interrupted `sweep --out DIR` says on exit (att51-3: it stopped
/// silently): how many of the shard's `runs` DIR holds (the same sweep with `--resume`
/// continues; under `resume` the rows it continues count before its table is renewed:
/// att53o-1, "nothing written" of a directory holding 100 resumed runs), or that it wrote
/// nothing (its manifest goes in place whole or not at all, and a directory it created is
/// removed while still empty).
fn say_runs_on_interrupt(
    out: &std::path::Path,
    runs: u64,
    resume: bool,
) -> isotrack_runs::cleanup::OnInterrupt {
    say_rows_on_interrupt(out, resume, move |q, n| {
        format!(
            "interrupted: {q} holds {n} of {runs} run{}; the same sweep with `--resume` continues",
            if runs == 1 { "" } else { "s" }
        )
    })
}

/// Registers the line an interrupted `merge --out DIR` says on exit (att51-6: it stopped
/// silently): the merged table and its manifest went in place together, or nothing was
/// written.
fn say_merge_on_interrupt(out: &std::path::Path) -> isotrack_runs::cleanup::OnInterrupt {
    say_rows_on_interrupt(out, false, |q, n| {
        format!("interrupted after the merge was written: {q} holds its {n} runs")
    })
}

/// The one interrupt note of `sweep` and `merge`: `held(DIR quoted, rows)` when `DIR/results.csv`
/// is a table this command wrote, or the one it `continued` ([`rows_held`]), else that
/// nothing was written to DIR.
fn say_rows_on_interrupt(
    out: &std::path::Path,
    continued: bool,
    held: impl Fn(&str, u64) -> String + Send + 'static,
) -> isotrack_runs::cleanup::OnInterrupt {
    let out = out.to_path_buf();
    let results = out.join("results.csv");
    let before = isotrack_runs::files::identity(&results);
    isotrack_runs::cleanup::on_interrupt(move || {
        let q = isotrack_runs::owned::shell_quoted(&out);
        match rows_held(&results, before, continued) {
            Some(n) => errln!("{}", held(&q, n)),
            None => errln!("interrupted: nothing written to {q}"),
        }
    })
}

/// `isotrack merge`: the shards of one sweep (same digest) into one directory; refuses missing,
/// duplicate or damaged rows, and an `--out` holding another sweep's results unless `--force`.
pub fn merge(a: &MergeArgs) -> Result<(), Failure> {
    let _said = say_merge_on_interrupt(&a.out);
    let total = isotrack_runs::sweep::merge::merge(&a.dirs, &a.out, a.force)?;
    outln!(
        "merged {total} runs from {} directories -> {}",
        a.dirs.len(),
        isotrack_runs::owned::shell_quoted(&a.out.join("results.csv"))
    );
    Ok(())
}
