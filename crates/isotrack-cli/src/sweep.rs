//! `isotrack sweep` and `isotrack merge`.
//!
//! Crash safety: every finished run appends one complete line to `results.csv` (one `write` of
//! the whole line, then a flush), so a sweep killed at any moment leaves complete rows plus at
//! most one partial last line. `--resume` drops that partial line, keeps every complete row, runs
//! only the missing ids, and at the end the file is rewritten sorted by `run_id` (to a temporary
//! file, then renamed), so it is the same bit for bit whatever the thread count, the shard split
//! or the interruptions.

use crate::cli::{MergeArgs, SweepArgs};
use crate::exit;
use crate::output::num;
use crate::run::Failure;
use indicatif::{ProgressBar, ProgressStyle};
use isotrack_scenario::sweep::SweepPlan;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::{RunResult, LANES};
#[allow(unused_imports)]
use rayon::iter::IntoParallelIterator;
use rayon::prelude::*;
use serde_json::json;

use std::io::Write;
use std::path::{Path, PathBuf};

/// The metric columns of `results.csv`, after `run_id` and the varied keys.
pub const METRIC_COLUMNS: [&str; 14] = [
    "outcome",
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "steady_state_mean_error",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
    "path_length_m",
    "control_effort",
    "chattering_radps2",
    "sign_changes_per_s",
    "t_end_s",
    "samples",
    "outcome_detail",
];

/// The failure code of a sweep stopped through `sweep_in_memory`'s `cancel` (128 + SIGINT, the
/// shells' convention; library callers report it as their own interruption).
pub const INTERRUPTED: u8 = 130;

fn fail(code: u8, message: String) -> Failure {
    Failure { code, message }
}

fn csv_line(fields: &[String]) -> String {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = w.write_record(fields);
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// The rows of runs `ids` (CSV lines with their newlines, in `ids` order). A run whose values
/// make an invalid scenario is recorded (`invalid_scenario`, the reason in `outcome_detail`),
/// never fatal to the sweep. The valid runs are run together ([`Scenario::run_batch`]: runs
/// sharing the field, vehicle and plan step in SIMD lanes, each with the result it has alone).
fn run_rows(plan: &SweepPlan, base: &Scenario, ids: &[u64], sweep_name: &str) -> Vec<String> {
    let derived: Vec<Result<Scenario, String>> = ids
        .iter()
        .map(|&id| run_scenario(plan, base, id, sweep_name))
        .collect();
    let valid: Vec<Scenario> = derived
        .iter()
        .filter_map(|d| d.as_ref().ok())
        .cloned()
        .collect();
    let mut results = Scenario::run_batch(&valid).into_iter();
    ids.iter()
        .zip(derived)
        .map(|(&id, d)| {
            // run_batch answers every valid scenario, in order.
            let result = d.and_then(|_| {
                results
                    .next()
                    .ok_or_else(|| "the batch returned no result for this run".to_string())
            });
            csv_line(&row_fields(plan, id, result))
        })
        .collect()
}

/// The scenario of run `id` of a sweep (its base with the run's assignments), or why it is
/// invalid, on one line.
pub fn run_scenario(
    plan: &SweepPlan,
    base: &Scenario,
    id: u64,
    sweep_name: &str,
) -> Result<Scenario, String> {
    let origin = format!("sweep {sweep_name} run {id}");
    base.derive_with(&plan.run_assignments(id, &origin), &origin)
        .map_err(|e| e.to_string().replace('\n', " "))
}

/// The `results.csv` fields of run `id`: its id, the plan's cells, then the
/// [`METRIC_COLUMNS`] of its result, or of an invalid scenario (outcome `invalid_scenario`,
/// the reason in `outcome_detail`).
pub fn row_fields(plan: &SweepPlan, id: u64, result: Result<RunResult, String>) -> Vec<String> {
    // A metric that is not a finite number is written as an empty cell (as summary.json writes
    // null): a results file never holds `NaN` or `inf`, so --resume and merge can refuse them.
    let fin = |x: f64| if x.is_finite() { num(x) } else { String::new() };
    let opt = |x: Option<f64>| x.map(fin).unwrap_or_default();
    let mut fields = vec![id.to_string()];
    fields.extend(plan.run_cells(id));
    match result {
        Ok(r) => {
            let m = &r.metrics;
            fields.extend([
                r.outcome.as_str().to_string(),
                opt(m.convergence_time_s),
                opt(m.steady_state_max_abs_error),
                opt(m.steady_state_rms_error),
                opt(m.steady_state_mean_error),
                opt(m.steady_state_max_isoline_distance_m),
                opt(m.steady_state_rms_isoline_distance_m),
                fin(m.path_length_m),
                fin(m.control_effort),
                opt(m.chattering_radps2),
                opt(m.sign_changes_per_s),
                fin(r.t_end_s),
                r.samples.to_string(),
                r.outcome_detail.unwrap_or_default(),
            ]);
        }
        Err(e) => {
            fields.push("invalid_scenario".into());
            fields.extend(std::iter::repeat_n(String::new(), METRIC_COLUMNS.len() - 2));
            fields.push(e);
        }
    }
    fields
}

/// The base scenario of a sweep: its file with `sets`, then the sweep's `[base]`, which must
/// make a valid scenario on its own; then every key of the sweep checked against the schema
/// (unknown keys and wrong types are the sweep file's errors, found before anything runs).
fn sweep_base(plan: &SweepPlan, sets: &[String], label: &str) -> Result<Scenario, Failure> {
    let base = load_scenario(Some(&plan.scenario), sets).map_err(crate::run::invalid)?;
    let base_assign = plan.run_assignments(0, label);
    let base = base
        .derive_with(&base_assign[..plan.base.len()], label)
        .map_err(|e| fail(exit::DATAERR, format!("{label}: [base]: {e}")))?;
    plan.check_keys(&base, label)
        .map_err(|e| fail(exit::DATAERR, e.to_string()))?;
    Ok(base)
}

/// The `results.csv` header of a sweep.
fn results_header(plan: &SweepPlan) -> Vec<String> {
    let mut header: Vec<String> = vec!["run_id".into()];
    header.extend(plan.columns());
    header.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()));
    header
}

/// A worker pool of `threads` (capped; all cores by default).
/// The worker pool for `--threads` (capped at 8 per core, see `thread_count`).
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, Failure> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = thread_count(threads) {
        b = b.num_threads(t);
    }
    b.build()
        .map_err(|e| fail(exit::OSERR, format!("cannot start threads: {e}")))
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
        let header = results_header(&plan);
        Ok(Self {
            plan,
            base,
            header,
            label,
        })
    }
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

/// Parses `K/N`.
fn parse_shard(s: &str) -> Result<(u64, u64), Failure> {
    let bad = || {
        fail(
            exit::USAGE,
            format!("--shard {s}: expected K/N with 1 <= K <= N"),
        )
    };
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u64, u64) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || n == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// The `outcome` values a row may hold.
const OUTCOMES: [&str; 4] = ["completed", "diverged", "left_field", "invalid_scenario"];

/// The metric columns that hold a quantity that cannot be negative (times, maxima, RMS values,
/// lengths, efforts, rates).
const NON_NEGATIVE_COLUMNS: [&str; 10] = [
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
    "path_length_m",
    "control_effort",
    "chattering_radps2",
    "sign_changes_per_s",
    "t_end_s",
];

/// What a stored row must be: the sweep's header, its run count and its plan (the varied
/// columns of run `id` are recomputed from the plan and must match).
struct RowRules<'a> {
    header: &'a [String],
    total: u64,
    plan: &'a SweepPlan,
}

/// Checks one stored row against the sweep: its field count, its `run_id` within the plan, the
/// plan's columns recomputed from the run id, a known outcome and metric values isotrack can
/// have written ([`check_metrics`]). Rows are trusted on `--resume` and `merge` only after
/// this.
fn check_row(rules: &RowRules<'_>, line: &str) -> Result<u64, String> {
    let header = rules.header;
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(line.as_bytes());
    let rec = r
        .records()
        .next()
        .and_then(Result::ok)
        .ok_or("not a CSV row")?;
    if rec.len() != header.len() {
        return Err(format!(
            "{} fields where the header has {}",
            rec.len(),
            header.len()
        ));
    }
    let id: u64 = rec[0]
        .parse()
        .map_err(|_| format!("run_id `{}` is not a run number", clip(&rec[0])))?;
    if id >= rules.total {
        return Err(format!(
            "run_id {id} is beyond this sweep's {} runs",
            rules.total
        ));
    }
    for ((name, cell), want) in header[1..]
        .iter()
        .zip(rec.iter().skip(1))
        .zip(rules.plan.run_cells(id))
    {
        if cell != want {
            return Err(format!(
                "{name} = `{}` where the sweep's plan gives run {id} `{}`",
                clip(cell),
                clip(&want)
            ));
        }
    }
    let cell = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .and_then(|i| rec.get(i))
            .unwrap_or("")
    };
    let outcome = cell("outcome");
    if !OUTCOMES.contains(&outcome) {
        return Err(format!(
            "outcome `{}` is not one of {OUTCOMES:?}",
            clip(outcome)
        ));
    }
    check_metrics(outcome, &cell)?;
    Ok(id)
}

/// The metric cells of one row are what isotrack writes: an `invalid_scenario` row has none; a
/// run's row has `t_end_s` and `samples`; every number is finite (non-finite metrics are
/// written empty), the quantities that cannot be negative are not, an RMS is at most its
/// maximum and `|mean|` at most the maximum (to rounding), the convergence time at most the run's
/// end, and `samples` a whole number of at most one per step ([`isotrack_sim::MAX_STEPS`] + 1).
fn check_metrics<'c>(outcome: &str, cell: &dyn Fn(&str) -> &'c str) -> Result<(), String> {
    let numeric = &METRIC_COLUMNS[1..METRIC_COLUMNS.len() - 1];
    if outcome == "invalid_scenario" {
        if let Some(n) = numeric.iter().find(|n| !cell(n).is_empty()) {
            return Err(format!("{n} holds a value in an invalid_scenario row"));
        }
        return Ok(());
    }
    for n in ["t_end_s", "samples"] {
        if cell(n).is_empty() {
            return Err(format!("{n} is empty in a `{outcome}` row"));
        }
    }
    let mut value = std::collections::HashMap::new();
    for &n in numeric.iter().filter(|n| **n != "samples") {
        let c = cell(n);
        if c.is_empty() {
            continue;
        }
        let v: f64 = c
            .parse()
            .map_err(|_| format!("{n} = `{}` is not a number", clip(c)))?;
        if !v.is_finite() {
            return Err(format!("{n} = `{c}` is not a finite number"));
        }
        if v < 0.0 && NON_NEGATIVE_COLUMNS.contains(&n) {
            return Err(format!("{n} = `{c}` is negative"));
        }
        value.insert(n, v);
    }
    let samples = cell("samples");
    match samples.parse::<u64>() {
        Ok(k) if k <= isotrack_sim::MAX_STEPS + 1 => {}
        _ => {
            return Err(format!(
                "samples = `{}` is not a whole number of samples (at most {})",
                clip(samples),
                isotrack_sim::MAX_STEPS + 1
            ))
        }
    }
    // Rounding: an RMS of equal values may exceed their maximum by an ulp or so.
    let at_most = |a: &str, b: &str, what: &str| -> Result<(), String> {
        match (value.get(a), value.get(b)) {
            (Some(x), Some(y)) if x.abs() > y * (1.0 + 1e-12) => {
                Err(format!("{a} = {x:?} exceeds {b} = {y:?} ({what})"))
            }
            _ => Ok(()),
        }
    };
    at_most(
        "steady_state_rms_error",
        "steady_state_max_abs_error",
        "an RMS is at most the maximum",
    )?;
    at_most(
        "steady_state_mean_error",
        "steady_state_max_abs_error",
        "|mean| is at most the maximum",
    )?;
    at_most(
        "steady_state_rms_isoline_distance_m",
        "steady_state_max_isoline_distance_m",
        "an RMS is at most the maximum",
    )?;
    at_most(
        "convergence_time_s",
        "t_end_s",
        "convergence happens within the run",
    )
}

/// User text from a damaged file, clipped for a message.
fn clip(text: &str) -> String {
    isotrack_scenario::load::clip(text)
}

/// One row of a results file: its run id and where its line is (not the line: a sweep's
/// memory must not grow with its run count).
#[derive(Clone, Copy, Debug)]
struct RowRef {
    id: u64,
    /// Which of the indexed files.
    file: usize,
    offset: u64,
    len: usize,
    /// 1-based line number, for messages.
    line: u64,
}

/// A results file, indexed: its header, where each row is, and how many rows are
/// `invalid_scenario`.
struct ResultsIndex {
    header: String,
    rows: Vec<RowRef>,
    invalid: u64,
}

/// Indexes `path` (file number `file` for [`RowRef::file`]) in one streaming pass, checking
/// every row (field count, `run_id` below `total`, known outcome, numeric metrics). A cut-off last
/// line (a killed sweep) is left out, and with `repair` cut from the file.
fn index_results(
    path: &Path,
    file: usize,
    repair: bool,
    total: u64,
    plan: &SweepPlan,
) -> Result<ResultsIndex, Failure> {
    use std::io::BufRead;
    let cannot = |e: std::io::Error| {
        fail(
            exit::NOINPUT,
            format!("cannot read {}: {e}", path.display()),
        )
    };
    let mut rdr = std::io::BufReader::new(isotrack_fields::io::open_regular(path).map_err(cannot)?);
    let mut line = String::new();
    let mut offset = rdr.read_line(&mut line).map_err(cannot)? as u64;
    let cut_at = |at: u64| -> Result<(), Failure> {
        if !repair {
            return Ok(());
        }
        let repair_fail = |e: std::io::Error| {
            fail(
                exit::CANTCREAT,
                format!("cannot repair {}: {e}", path.display()),
            )
        };
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(repair_fail)?
            .set_len(at)
            .map_err(repair_fail)
    };
    if !line.ends_with('\n') {
        // No complete header: an empty file, or one cut before its first newline.
        cut_at(0)?;
        return Ok(ResultsIndex {
            header: String::new(),
            rows: vec![],
            invalid: 0,
        });
    }
    let header = std::mem::take(&mut line);
    let columns: Vec<String> = csv_fields(&header).ok_or_else(|| {
        fail(
            exit::DATAERR,
            format!("{}:1: the header is not a CSV line", path.display()),
        )
    })?;
    let outcome_col = columns.iter().position(|c| c == "outcome");
    let mut rows = vec![];
    let mut invalid = 0;
    for number in 2u64.. {
        line.clear();
        let n = rdr.read_line(&mut line).map_err(|e| {
            fail(
                exit::DATAERR,
                format!("{}:{number}: damaged row ({e})", path.display()),
            )
        })?;
        if n == 0 {
            break;
        }
        if !line.ends_with('\n') {
            cut_at(offset)?;
            break;
        }
        // Rows are written whole; a line that does not check is a damaged file, not ours to
        // guess at.
        let rules = RowRules {
            header: &columns,
            total,
            plan,
        };
        let id = check_row(&rules, &line).map_err(|why| {
            let shown: String = line.trim_end().chars().take(120).collect();
            fail(
                exit::DATAERR,
                format!(
                    "{}:{number}: damaged row ({why}): `{shown}`; remove the line (or the file) and --resume",
                    path.display()
                ),
            )
        })?;
        if outcome_col.is_some_and(|c| {
            csv_fields(&line)
                .is_some_and(|f| f.get(c).map(String::as_str) == Some("invalid_scenario"))
        }) {
            invalid += 1;
        }
        rows.push(RowRef {
            id,
            file,
            offset,
            len: n,
            line: number,
        });
        offset += n as u64;
    }
    Ok(ResultsIndex {
        header,
        rows,
        invalid,
    })
}

/// Sorts `rows` by run id; the ids that appear more than once (first occurrences listed).
fn sort_rows(rows: &mut [RowRef]) -> Vec<RowRef> {
    rows.sort_by_key(|r| (r.id, r.file, r.offset));
    rows.windows(2)
        .filter(|w| w[0].id == w[1].id)
        .map(|w| w[1])
        .collect()
}

/// Writes the sorted `rows` (read back from `sources`, by [`RowRef::file`]) under `header` to
/// `path` atomically (temporary file, then rename). Memory: one line at a time.
fn write_sorted(
    path: &Path,
    header: &str,
    rows: &[RowRef],
    sources: &[PathBuf],
) -> Result<(), Failure> {
    use std::io::{Read, Seek, SeekFrom};
    let tmp = path.with_extension("csv.tmp");
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", path.display()),
        )
    };
    let mut inputs = sources
        .iter()
        .map(|p| {
            isotrack_fields::io::open_regular(p)
                .map(std::io::BufReader::new)
                .map_err(|e| fail(exit::NOINPUT, format!("cannot read {}: {e}", p.display())))
        })
        .collect::<Result<Vec<_>, Failure>>()?;
    let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(cant)?);
    f.write_all(header.as_bytes()).map_err(cant)?;
    let mut at = vec![u64::MAX; inputs.len()];
    let mut buf = Vec::new();
    for r in rows {
        let src = &mut inputs[r.file];
        // Rows finish roughly in id order, so most reads follow on from the last: seek (which
        // drops the reader's buffer) only when they do not.
        if at[r.file] != r.offset {
            src.seek(SeekFrom::Start(r.offset)).map_err(cant)?;
        }
        buf.resize(r.len, 0);
        src.read_exact(&mut buf).map_err(cant)?;
        at[r.file] = r.offset + r.len as u64;
        f.write_all(&buf).map_err(cant)?;
    }
    f.into_inner()
        .map_err(|e| cant(e.into_error()))?
        .sync_all()
        .map_err(cant)?;
    std::fs::rename(&tmp, path).map_err(cant)
}

/// Fields of one CSV line (`None` if it does not parse).
fn csv_fields(line: &str) -> Option<Vec<String>> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(line.as_bytes());
    let rec = r.records().next()?.ok()?;
    Some(rec.iter().map(str::to_string).collect())
}

/// The digest that names a sweep: SHA-256 of the sweep file's bytes and of the resolved base
/// scenario (every default filled in, so a changed default or scenario file changes it too).
/// Stored in `sweep.json`; `--resume` and `merge` refuse rows made under another digest.
fn sweep_digest(sweep_file: &[u8], base_toml: &str) -> String {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    h.update((sweep_file.len() as u64).to_le_bytes());
    h.update(sweep_file);
    h.update(base_toml.as_bytes());
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// The most worker threads per core `--threads` may ask for: beyond a few per core, threads
/// only add scheduling and memory (100 000 threads once stalled a sweep before its first row).
const MAX_THREADS_PER_CORE: usize = 8;

/// The thread count to use for `--threads` (capped, with a note on stderr).
fn thread_count(requested: Option<usize>) -> Option<usize> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cap = MAX_THREADS_PER_CORE * cores;
    requested.map(|t| {
        if t > cap {
            errln!(
                "note: --threads {t} capped to {cap} ({MAX_THREADS_PER_CORE} per core on {cores} cores); results do not depend on it"
            );
        }
        t.clamp(1, cap)
    })
}

/// Reads `DIR/sweep.json`.
fn read_manifest(dir: &Path) -> Result<serde_json::Value, Failure> {
    let path = dir.join("sweep.json");
    let text = isotrack_fields::io::read_text_limited(&path, 1 << 20).map_err(|e| {
        fail(
            exit::NOINPUT,
            format!("{}: no readable sweep.json ({e})", dir.display()),
        )
    })?;
    serde_json::from_str(&text).map_err(|e| fail(exit::DATAERR, format!("{}: {e}", path.display())))
}

/// The file in an output directory whose operating-system lock marks the directory as being
/// written (README, "Sweeps"). The lock, not the file, is what counts: it is released when its
/// holder exits in any way (SIGKILL and a crashed node included), so a file left behind is
/// never a stale lock.
pub const LOCK_FILE: &str = ".isotrack.lock";

/// Takes the exclusive lock of output directory `dir` (an advisory `flock`-style lock on
/// [`LOCK_FILE`], std's `File::try_lock`): held until the returned file is dropped or the
/// process ends. A second sweep or merge writing the same directory (a requeued Slurm task
/// while the old one still runs) exits 73 instead of running everything again beside it.
pub fn lock_output_dir(dir: &Path) -> Result<std::fs::File, Failure> {
    let path = dir.join(LOCK_FILE);
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot lock {}: {e}", path.display()),
        )
    };
    let f = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(cant)?;
    match f.try_lock() {
        Ok(()) => Ok(f),
        Err(std::fs::TryLockError::WouldBlock) => Err(fail(
            exit::CANTCREAT,
            format!(
                "{}: another isotrack sweep or merge is writing this directory (it holds the lock on {LOCK_FILE}); wait for it to end, or use another --out",
                dir.display()
            ),
        )),
        Err(std::fs::TryLockError::Error(e)) => Err(cant(e)),
    }
}

/// Refuses to read shard directory `dir` while a sweep still writes it (it holds the lock of
/// [`lock_output_dir`]): its rows are not all there yet. A directory without a lock file was
/// never locked (nothing to wait for).
fn check_not_being_written(dir: &Path) -> Result<(), Failure> {
    let Ok(f) = std::fs::File::open(dir.join(LOCK_FILE)) else {
        return Ok(());
    };
    match f.try_lock_shared() {
        Err(std::fs::TryLockError::WouldBlock) => Err(fail(
            exit::CANTCREAT,
            format!(
                "{}: a sweep is still writing this directory (it holds the lock on {LOCK_FILE}); merge once it has ended",
                dir.display()
            ),
        )),
        _ => Ok(()),
    }
}

/// `isotrack sweep`.
pub fn sweep(a: &SweepArgs) -> Result<(), Failure> {
    let sweep_bytes =
        isotrack_fields::io::read_limited(&a.sweep, isotrack_scenario::MAX_SCENARIO_FILE_BYTES)
            .map_err(|e| {
                fail(
                    exit::NOINPUT,
                    format!("{}: cannot read: {e}", a.sweep.display()),
                )
            })?;
    let text = String::from_utf8(sweep_bytes.clone()).map_err(|_| {
        fail(
            exit::DATAERR,
            format!("{}: not UTF-8 text", a.sweep.display()),
        )
    })?;
    let plan = SweepPlan::parse(&text, &a.sweep).map_err(|e| fail(exit::DATAERR, e.to_string()))?;
    let name = a.sweep.display().to_string();
    let base = sweep_base(&plan, &a.set, &name)?;
    let (k, n) = match &a.shard {
        Some(s) => parse_shard(s)?,
        None => (1, 1),
    };
    let total = plan.total();
    let shard_runs = total / n + u64::from(total % n >= k);
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", a.out.display()),
        )
    };
    let base_toml = crate::output::scenario_toml(&base);
    let digest = sweep_digest(&sweep_bytes, &base_toml);
    for note in plan.duplicate_notes() {
        errln!("note: {note}");
    }
    std::fs::create_dir_all(&a.out).map_err(cant)?;
    // Held to the end of the sweep (dropped on return, released by the OS on any exit).
    let _lock = lock_output_dir(&a.out)?;
    let results = a.out.join("results.csv");
    let header = results_header(&plan);
    let header_line = csv_line(&header);
    if results.exists() && a.force {
        std::fs::remove_file(&results).map_err(cant)?;
    }
    if results.exists() && !a.resume {
        return Err(fail(
            exit::CANTCREAT,
            format!(
                "{} exists: pass --resume to continue that sweep, --force to start over, or another --out",
                results.display()
            ),
        ));
    }
    if results.exists() && a.resume {
        let stored = read_manifest(&a.out)?;
        if stored["digest"].as_str() != Some(digest.as_str()) {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: made by a different sweep (the sweep file or its resolved base scenario changed since; digest {} here, {} now): start a new --out",
                    a.out.display(),
                    stored["digest"].as_str().unwrap_or("missing"),
                    digest
                ),
            ));
        }
    }
    // The runs already done (their ids only, sorted).
    let done: Vec<u64> = if results.exists() {
        let idx = index_results(&results, 0, true, total, &plan)?;
        if idx.header.is_empty() {
            std::fs::write(&results, &header_line).map_err(cant)?;
        } else if idx.header != header_line {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: its columns differ from this sweep's",
                    results.display()
                ),
            ));
        }
        let mut rows = idx.rows;
        if let Some(d) = sort_rows(&mut rows).first() {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}:{}: damaged row (run {} appears twice); remove the line (or the file) and --resume",
                    results.display(),
                    d.line,
                    d.id
                ),
            ));
        }
        if let Some(r) = rows.iter().find(|r| r.id % n != k - 1) {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: run {} is not in shard {k}/{n}: resume with the shard it was started with",
                    results.display(),
                    r.id
                ),
            ));
        }
        rows.iter().map(|r| r.id).collect()
    } else {
        vec![]
    };
    // The sweep, its digest and its plan, kept next to the results (written before the first row, so
    // every results.csv has the sweep.json that says which sweep made it; on --resume only
    // after its rows and digest are checked).
    std::fs::write(a.out.join("sweep.toml"), &sweep_bytes).map_err(cant)?;
    std::fs::write(a.out.join("base_scenario.toml"), &base_toml).map_err(cant)?;
    let manifest = json!({
        "sweep": name,
        "scenario": plan.scenario.display().to_string(),
        "digest": digest,
        "total_runs": total,
        "shard": [k, n],
        "shard_runs": shard_runs,
        "columns": header,
    });
    std::fs::write(
        a.out.join("sweep.json"),
        serde_json::to_string_pretty(&manifest).unwrap_or_default() + "\n",
    )
    .map_err(cant)?;

    if !results.exists() {
        std::fs::write(&results, &header_line).map_err(cant)?;
    }
    let new_runs = shard_runs - done.len() as u64;
    let pb = runs_progress_bar(new_runs);
    let pool = worker_pool(a.threads)?;
    let started = std::time::Instant::now();
    let (tx, rx) = std::sync::mpsc::channel::<String>();
    let write_result: Result<(), Failure> = std::thread::scope(|scope| {
        let writer = scope.spawn(|| -> Result<(), Failure> {
            let mut f = std::fs::OpenOptions::new()
                .append(true)
                .open(&results)
                .map_err(cant)?;
            for line in rx {
                f.write_all(line.as_bytes()).map_err(cant)?;
                f.flush().map_err(cant)?;
                pb.inc(1);
            }
            f.sync_all().map_err(cant)
        });
        // The shard's ids are generated, not listed up front: memory stays flat however
        // large the sweep.
        // Runs go in groups of LANES consecutive ones (stepped together, see run_rows).
        pool.install(|| {
            (0..shard_runs.div_ceil(LANES as u64))
                .into_par_iter()
                .for_each_with(tx, |tx, c| {
                    let ids: Vec<u64> = (c * LANES as u64
                        ..((c + 1) * LANES as u64).min(shard_runs))
                        .map(|i| i * n + (k - 1))
                        .filter(|id| done.binary_search(id).is_err())
                        .collect();
                    for row in run_rows(&plan, &base, &ids, &name) {
                        let _ = tx.send(row);
                    }
                })
        });
        writer
            .join()
            .unwrap_or_else(|_| Err(fail(exit::CANTCREAT, "the results writer stopped".into())))
    });
    write_result?;
    pb.finish_and_clear();
    let idx = index_results(&results, 0, false, total, &plan)?;
    let mut rows = idx.rows;
    if let Some(d) = sort_rows(&mut rows).first() {
        return Err(fail(
            exit::DATAERR,
            format!(
                "{}:{}: run {} appears twice",
                results.display(),
                d.line,
                d.id
            ),
        ));
    }
    write_sorted(&results, &idx.header, &rows, std::slice::from_ref(&results))?;
    let invalid = idx.invalid;
    let summary = format!(
        "{} runs ({} new) of {} in {:.2} s -> {}",
        rows.len(),
        new_runs,
        if n > 1 {
            format!("shard {k}/{n} ({shard_runs} of {total})")
        } else {
            format!("{total}")
        },
        started.elapsed().as_secs_f64(),
        results.display()
    );
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

/// The plan of shard directory `dir`, from its `sweep.toml`, after checking that its
/// `sweep.toml` and `base_scenario.toml` are those its `sweep.json` digest names (a shard whose
/// files were edited is refused: its rows' plan columns are checked against this plan).
fn shard_plan(dir: &Path, digest: &str) -> Result<SweepPlan, Failure> {
    let read = |name: &str| {
        let p = dir.join(name);
        isotrack_fields::io::read_limited(&p, isotrack_scenario::MAX_SCENARIO_FILE_BYTES)
            .map_err(|e| fail(exit::NOINPUT, format!("cannot read {}: {e}", p.display())))
    };
    let (sweep_bytes, base) = (read("sweep.toml")?, read("base_scenario.toml")?);
    let base = String::from_utf8_lossy(&base);
    if sweep_digest(&sweep_bytes, &base) != digest {
        return Err(fail(
            exit::DATAERR,
            format!(
                "{}: sweep.toml or base_scenario.toml is not the sweep its sweep.json names (digest {digest}): the shard was edited; run it again",
                dir.display()
            ),
        ));
    }
    let path = dir.join("sweep.toml");
    let text = String::from_utf8_lossy(&sweep_bytes);
    SweepPlan::parse(&text, &path).map_err(|e| fail(exit::DATAERR, e.to_string()))
}

/// `isotrack merge`: the shards of one sweep (same digest) into one directory; refuses missing,
/// duplicate or damaged rows, and an `--out` holding another sweep's results unless `--force`.
pub fn merge(a: &MergeArgs) -> Result<(), Failure> {
    let mut header: Option<String> = None;
    let mut first: Option<(u64, String, serde_json::Value)> = None;
    let mut all: Vec<RowRef> = vec![];
    let mut sources: Vec<PathBuf> = vec![];
    let out_results = a.out.join("results.csv");
    for d in &a.dirs {
        if crate::output::same_file(&d.join("results.csv"), &out_results) {
            return Err(fail(
                exit::USAGE,
                format!("--out {} is one of the inputs", a.out.display()),
            ));
        }
    }
    if out_results.exists() && !a.force {
        return Err(fail(
            exit::CANTCREAT,
            format!(
                "{} exists: pass --force to replace it, or another --out",
                out_results.display()
            ),
        ));
    }
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", a.out.display()),
        )
    };
    std::fs::create_dir_all(&a.out).map_err(cant)?;
    let _lock = lock_output_dir(&a.out)?;
    for d in &a.dirs {
        check_not_being_written(d)?;
        let m = read_manifest(d)?;
        let t = m["total_runs"].as_u64().ok_or_else(|| {
            fail(
                exit::DATAERR,
                format!("{}/sweep.json: no total_runs", d.display()),
            )
        })?;
        let digest = m["digest"].as_str().map(str::to_string).ok_or_else(|| {
            fail(
                exit::DATAERR,
                format!(
                    "{}/sweep.json: no digest (made by an older isotrack): run that shard again",
                    d.display()
                ),
            )
        })?;
        let plan = shard_plan(d, &digest)?;
        match &first {
            Some((t0, d0, _)) if *t0 != t || *d0 != digest => {
                return Err(fail(
                    exit::DATAERR,
                    format!(
                        "{}: a different sweep from {} (sweep file, base scenario or seed differ: digest {digest} vs {d0})",
                        d.display(),
                        a.dirs[0].display()
                    ),
                ));
            }
            Some(_) => {}
            None => first = Some((t, digest, m)),
        }
        let path = d.join("results.csv");
        let idx = index_results(&path, sources.len(), false, t, &plan)?;
        if header.as_ref().is_some_and(|x| *x != idx.header) {
            return Err(fail(
                exit::DATAERR,
                format!("{}: different columns", d.display()),
            ));
        }
        header = Some(idx.header);
        all.extend(idx.rows);
        sources.push(path);
    }
    let mut dupes: Vec<u64> = sort_rows(&mut all).iter().map(|r| r.id).collect();
    dupes.dedup();
    let (total, _, mut manifest) = first.unwrap_or((0, String::new(), json!({})));
    if !dupes.is_empty() {
        let list: Vec<String> = dupes.iter().take(10).map(|i| i.to_string()).collect();
        return Err(fail(
            exit::DATAERR,
            format!(
                "{} runs appear in more than one input: {}",
                dupes.len(),
                list.join(", ")
            ),
        ));
    }
    let n_missing = total - all.len() as u64;
    if n_missing > 0 {
        // The gaps in the sorted ids.
        let mut list: Vec<String> = vec![];
        let mut next = 0u64;
        for id in all.iter().map(|r| r.id).chain(std::iter::once(total)) {
            while next < id && list.len() < 10 {
                list.push(next.to_string());
                next += 1;
            }
            next = id + 1;
        }
        return Err(fail(
            exit::DATAERR,
            format!(
                "{n_missing} of {total} runs are missing (e.g. {}): finish or --resume those shards first",
                list.join(", ")
            ),
        ));
    }
    write_sorted(
        &out_results,
        header.as_deref().unwrap_or(""),
        &all,
        &sources,
    )?;
    if let Some(first) = a.dirs.first() {
        for f in ["sweep.toml", "base_scenario.toml"] {
            if first.join(f).exists() && !crate::output::same_file(&first.join(f), &a.out.join(f)) {
                std::fs::copy(first.join(f), a.out.join(f)).map_err(cant)?;
            }
        }
        manifest["shard"] = json!([1, 1]);
        manifest["shard_runs"] = json!(total);
        manifest["merged_from"] = json!(a
            .dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>());
        std::fs::write(
            a.out.join("sweep.json"),
            serde_json::to_string_pretty(&manifest).unwrap_or_default() + "\n",
        )
        .map_err(cant)?;
    }
    outln!(
        "merged {total} runs from {} directories -> {}",
        a.dirs.len(),
        out_results.display()
    );
    Ok(())
}
