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
use isotrack_sim::NoTrace;
use rayon::prelude::*;
use serde_json::json;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::Path;

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

fn fail(code: u8, message: String) -> Failure {
    Failure { code, message }
}

fn csv_line(fields: &[String]) -> String {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = w.write_record(fields);
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// One run's row (as a CSV line with its newline).
fn run_row(plan: &SweepPlan, base: &Scenario, id: u64) -> String {
    let vals = plan.run_values(id);
    let mut fields = vec![id.to_string()];
    fields.extend(vals.iter().map(|v| v.trim_matches('"').to_string()));
    let opt = |x: Option<f64>| x.map(num).unwrap_or_default();
    match base.derive(&plan.run_overrides(id), &format!("sweep run {id}")) {
        Ok(s) => {
            let r = s.run(&mut NoTrace);
            let m = &r.metrics;
            fields.extend([
                r.outcome.as_str().to_string(),
                opt(m.convergence_time_s),
                opt(m.steady_state_max_abs_error),
                opt(m.steady_state_rms_error),
                opt(m.steady_state_mean_error),
                opt(m.steady_state_max_isoline_distance_m),
                opt(m.steady_state_rms_isoline_distance_m),
                num(m.path_length_m),
                num(m.control_effort),
                opt(m.chattering_radps2),
                opt(m.sign_changes_per_s),
                num(r.t_end_s),
                r.samples.to_string(),
                r.outcome_detail.unwrap_or_default(),
            ]);
        }
        Err(e) => {
            fields.push("invalid_scenario".into());
            fields.extend(std::iter::repeat_n(String::new(), METRIC_COLUMNS.len() - 2));
            fields.push(e.to_string().replace('\n', " "));
        }
    }
    csv_line(&fields)
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

/// Reads the complete rows of `results.csv`: `(header, rows by run_id)`. A trailing line
/// without its newline (a run cut off mid-write) is dropped, and the file truncated to the last
/// complete line when `repair` is set.
fn read_results(path: &Path, repair: bool) -> Result<(String, BTreeMap<u64, String>), Failure> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        fail(
            exit::NOINPUT,
            format!("cannot read {}: {e}", path.display()),
        )
    })?;
    let complete = match text.rfind('\n') {
        Some(i) => &text[..=i],
        None => "",
    };
    if repair && complete.len() != text.len() {
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map_err(|e| {
                fail(
                    exit::CANTCREAT,
                    format!("cannot repair {}: {e}", path.display()),
                )
            })?;
        f.set_len(complete.len() as u64).map_err(|e| {
            fail(
                exit::CANTCREAT,
                format!("cannot repair {}: {e}", path.display()),
            )
        })?;
    }
    let mut lines = complete.split_inclusive('\n');
    let header = lines.next().unwrap_or("").to_string();
    let mut rows = BTreeMap::new();
    for line in lines {
        // Rows are written whole; a line that does not parse is a damaged file, not ours to
        // guess at.
        let id: u64 = line
            .split(',')
            .next()
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| {
                fail(
                    exit::DATAERR,
                    format!("{}: damaged row `{}`", path.display(), line.trim_end()),
                )
            })?;
        if rows.insert(id, line.to_string()).is_some() {
            return Err(fail(
                exit::DATAERR,
                format!("{}: run {id} appears twice", path.display()),
            ));
        }
    }
    Ok((header, rows))
}

/// Writes `rows` sorted by id under `header` atomically (temporary file, then rename).
fn write_sorted(path: &Path, header: &str, rows: &BTreeMap<u64, String>) -> Result<(), Failure> {
    let tmp = path.with_extension("csv.tmp");
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", path.display()),
        )
    };
    let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(cant)?);
    f.write_all(header.as_bytes()).map_err(cant)?;
    for line in rows.values() {
        f.write_all(line.as_bytes()).map_err(cant)?;
    }
    f.into_inner()
        .map_err(|e| cant(e.into_error()))?
        .sync_all()
        .map_err(cant)?;
    std::fs::rename(&tmp, path).map_err(cant)
}

/// `isotrack sweep`.
pub fn sweep(a: &SweepArgs) -> Result<(), Failure> {
    let plan = SweepPlan::load(&a.sweep).map_err(|e| {
        fail(
            if e.message.starts_with("cannot read") {
                exit::NOINPUT
            } else {
                exit::DATAERR
            },
            e.to_string(),
        )
    })?;
    let base =
        load_scenario(Some(&plan.scenario), &[]).map_err(|e| fail(exit::DATAERR, e.to_string()))?;
    // The base overrides must make a valid scenario on their own.
    let base = base
        .derive(&plan.base, &a.sweep.display().to_string())
        .map_err(|e| fail(exit::DATAERR, format!("{}: [base]: {e}", a.sweep.display())))?;
    let (k, n) = match &a.shard {
        Some(s) => parse_shard(s)?,
        None => (1, 1),
    };
    let total = plan.total();
    let ids: Vec<u64> = (0..total).filter(|id| id % n == k - 1).collect();
    let cant = |e: std::io::Error| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", a.out.display()),
        )
    };
    std::fs::create_dir_all(&a.out).map_err(cant)?;
    let results = a.out.join("results.csv");
    let mut header: Vec<String> = vec!["run_id".into()];
    header.extend(plan.varied_keys());
    header.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()));
    let header_line = csv_line(&header);
    let done: BTreeMap<u64, String> = if results.exists() {
        if !a.resume {
            return Err(fail(
                exit::CANTCREAT,
                format!(
                    "{} exists: pass --resume to continue that sweep, or another --out",
                    results.display()
                ),
            ));
        }
        let (h, rows) = read_results(&results, true)?;
        if h.is_empty() {
            std::fs::write(&results, &header_line).map_err(cant)?;
        } else if h != header_line {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: its columns differ from this sweep's",
                    results.display()
                ),
            ));
        }
        rows
    } else {
        std::fs::write(&results, &header_line).map_err(cant)?;
        BTreeMap::new()
    };
    // Keep the resolved sweep next to its results.
    std::fs::copy(&a.sweep, a.out.join("sweep.toml")).map_err(cant)?;
    std::fs::write(
        a.out.join("base_scenario.toml"),
        crate::output::scenario_toml(&base),
    )
    .map_err(cant)?;
    let manifest = json!({
        "sweep": a.sweep.display().to_string(),
        "scenario": plan.scenario.display().to_string(),
        "total_runs": total,
        "shard": [k, n],
        "shard_runs": ids.len(),
        "columns": header,
    });
    std::fs::write(
        a.out.join("sweep.json"),
        serde_json::to_string_pretty(&manifest).unwrap_or_default() + "\n",
    )
    .map_err(cant)?;

    let pending: Vec<u64> = ids
        .iter()
        .copied()
        .filter(|id| !done.contains_key(id))
        .collect();
    let pb = ProgressBar::new(pending.len() as u64);
    pb.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} runs, ETA {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(t) = a.threads {
            b = b.num_threads(t.max(1));
        }
        b.build()
            .map_err(|e| fail(exit::USAGE, format!("cannot start threads: {e}")))?
    };
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
        pool.install(|| {
            pending.par_iter().for_each_with(tx, |tx, &id| {
                let _ = tx.send(run_row(&plan, &base, id));
            })
        });
        writer
            .join()
            .unwrap_or_else(|_| Err(fail(exit::CANTCREAT, "the results writer stopped".into())))
    });
    write_result?;
    pb.finish_and_clear();
    let (h, rows) = read_results(&results, false)?;
    write_sorted(&results, &h, &rows)?;
    println!(
        "{} runs ({} new) of {} in {:.2} s -> {}",
        rows.len(),
        pending.len(),
        if n > 1 {
            format!("shard {k}/{n} ({} of {total})", ids.len())
        } else {
            format!("{total}")
        },
        started.elapsed().as_secs_f64(),
        results.display()
    );
    Ok(())
}

/// `isotrack merge`.
pub fn merge(a: &MergeArgs) -> Result<(), Failure> {
    let mut header: Option<String> = None;
    let mut total: Option<u64> = None;
    let mut all: BTreeMap<u64, String> = BTreeMap::new();
    let mut dupes = BTreeSet::new();
    for d in &a.dirs {
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("sweep.json")).map_err(|e| {
                fail(
                    exit::NOINPUT,
                    format!("{}: no sweep.json ({e})", d.display()),
                )
            })?)
            .map_err(|e| fail(exit::DATAERR, format!("{}/sweep.json: {e}", d.display())))?;
        let t = m["total_runs"].as_u64().ok_or_else(|| {
            fail(
                exit::DATAERR,
                format!("{}/sweep.json: no total_runs", d.display()),
            )
        })?;
        if total.is_some_and(|x| x != t) {
            return Err(fail(
                exit::DATAERR,
                format!("{}: a different sweep ({t} runs)", d.display()),
            ));
        }
        total = Some(t);
        let (h, rows) = read_results(&d.join("results.csv"), false)?;
        if header.as_ref().is_some_and(|x| *x != h) {
            return Err(fail(
                exit::DATAERR,
                format!("{}: different columns", d.display()),
            ));
        }
        header = Some(h);
        for (id, line) in rows {
            if all.insert(id, line).is_some() {
                dupes.insert(id);
            }
        }
    }
    let total = total.unwrap_or(0);
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
    let missing: Vec<u64> = (0..total).filter(|i| !all.contains_key(i)).collect();
    if !missing.is_empty() {
        let list: Vec<String> = missing.iter().take(10).map(|i| i.to_string()).collect();
        return Err(fail(
            exit::DATAERR,
            format!(
                "{} of {total} runs are missing (e.g. {}): finish or --resume those shards first",
                missing.len(),
                list.join(", ")
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
    write_sorted(
        &a.out.join("results.csv"),
        header.as_deref().unwrap_or(""),
        &all,
    )?;
    if let Some(first) = a.dirs.first() {
        for f in ["sweep.toml", "base_scenario.toml"] {
            if first.join(f).exists() {
                std::fs::copy(first.join(f), a.out.join(f)).map_err(cant)?;
            }
        }
        let mut m: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(first.join("sweep.json")).unwrap_or_default(),
        )
        .unwrap_or(json!({}));
        m["shard"] = json!([1, 1]);
        m["shard_runs"] = json!(total);
        m["merged_from"] = json!(a
            .dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>());
        std::fs::write(
            a.out.join("sweep.json"),
            serde_json::to_string_pretty(&m).unwrap_or_default() + "\n",
        )
        .map_err(cant)?;
    }
    println!(
        "merged {total} runs from {} directories -> {}",
        a.dirs.len(),
        a.out.join("results.csv").display()
    );
    Ok(())
}
