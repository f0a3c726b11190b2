//! A sweep run into an output directory (`isotrack sweep`): read and checked
//! ([`SweepJob::prepare`]), its directory opened, locked and checked for `--resume`
//! ([`SweepJob::open_output`]), the missing runs run and appended ([`SweepJob::run_missing`]),
//! then `results.csv` rewritten sorted ([`SweepJob::finish`]).

use crate::failure::{exit, fail, Failure};
use crate::sweep::check::RunSpans;
use crate::sweep::index::{index_results, sort_rows, write_sorted};
use crate::sweep::lock::{lock_output_dir, DirLock};
use crate::sweep::manifest::SWEEP_FILES;
use crate::sweep::manifest::{
    check_data_files, check_engine, data_files_entry, engine, given_toml,
    plan_data_file_digests_all, read_manifest, refuse_foreign_sweep_files, sweep_digest,
    unrecorded_engine_note,
};
use crate::sweep::prepared::sweep_base;
use crate::sweep::rows::{csv_fields, csv_line, results_header, run_rows};
use isotrack_scenario::sweep::SweepPlan;
use isotrack_scenario::Scenario;
use isotrack_sim::LANES;
#[allow(unused_imports)]
use rayon::iter::IntoParallelIterator;
use rayon::prelude::*;
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A sweep file read and checked, with its base scenario and digest: ready to run into a
/// directory.
pub struct SweepJob {
    /// The sweep file's path.
    pub path: PathBuf,
    /// The sweep file's bytes (kept as `sweep.toml`).
    pub sweep_bytes: Vec<u8>,
    /// The plan.
    pub plan: SweepPlan,
    /// The sweep's name in messages (its path).
    pub name: String,
    /// The base scenario (its file with the `--set` overrides, then `[base]`).
    pub base: Scenario,
    /// The base scenario's own keys as TOML ([`Scenario::given`], kept as
    /// `base_scenario.toml`): each run is these keys with its assignments, resolved once.
    pub base_toml: String,
    /// The sweep's digest ([`sweep_digest`]).
    pub digest: String,
    /// The `results.csv` header.
    pub header: Vec<String>,
    /// The SHA-256 of every data file a run reads, by path ([`plan_data_file_digests_all`]),
    /// taken once as the sweep starts: what `sweep.json` records and `--resume` checks.
    pub data_files: std::collections::BTreeMap<String, String>,
}

/// An output directory opened for a sweep: locked, its `results.csv` holding at least the
/// header, and the runs already done.
pub struct SweepOutput {
    /// The directory.
    pub dir: PathBuf,
    /// `DIR/results.csv`.
    pub results: PathBuf,
    /// The shard `(k, n)`: the runs with `id % n == k - 1`.
    pub shard: (u64, u64),
    /// How many runs the shard holds.
    pub shard_runs: u64,
    /// The ids already done (sorted).
    pub done: Vec<u64>,
    /// The directory's lock, held while this lives.
    pub lock: DirLock,
    /// The levels of the directory the sweep created, removed if it is interrupted while they
    /// are still empty ([`crate::cleanup::create_dir_all`]), held while this lives.
    _created: Vec<crate::cleanup::Pending>,
}

/// What a finished sweep holds.
pub struct SweepReport {
    /// The rows of `results.csv` (the shard's runs).
    pub rows: u64,
    /// How many of them are `invalid_scenario`.
    pub invalid: u64,
    /// Runs that did not complete or ended with a warning: how many, and the first few ids.
    pub flagged: crate::sweep::index::Flagged,
}

/// Refuses (65, before any run) a `[grid]` value holding a line break (a string, or one in
/// a list or table: `field.path = ["new\nline.csv"]`, a legal file name), naming its key and
/// the value escaped: its `results.csv` cell would span two lines, which the sweep's own row
/// check (`--resume`, `merge`, the final pass) reads as a damaged row (att30n-2: every run
/// ran, then the sweep refused its own row, and `--resume` could never finish).
fn refuse_line_breaks(plan: &SweepPlan, name: &str) -> Result<(), Failure> {
    fn breaks(v: &toml::Value) -> bool {
        match v {
            toml::Value::String(s) => s.contains(['\n', '\r']),
            toml::Value::Array(a) => a.iter().any(breaks),
            toml::Value::Table(t) => t.iter().any(|(k, v)| k.contains(['\n', '\r']) || breaks(v)),
            _ => false,
        }
    }
    for (k, list) in &plan.grid {
        if let Some((i, v)) = list.iter().enumerate().find(|(_, v)| breaks(v)) {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{name}: [grid] {k} value {} {}: holds a line break, which a row of results.csv cannot hold; rename the file (or choose another value)",
                    i + 1,
                    isotrack_scenario::load::clip(&isotrack_scenario::sweep::value_literal(v))
                ),
            ));
        }
    }
    Ok(())
}

impl SweepJob {
    /// Reads and checks sweep file `path`, its base scenario with `sets` applied.
    pub fn prepare(path: &Path, sets: &[String]) -> Result<Self, Failure> {
        let sweep_bytes =
            isotrack_fields::io::read_limited(path, isotrack_scenario::MAX_SCENARIO_FILE_BYTES)
                .map_err(|e| {
                    fail(
                        exit::NOINPUT,
                        format!("{}: cannot read: {e}", path.display()),
                    )
                })?;
        let text = String::from_utf8(sweep_bytes.clone())
            .map_err(|_| fail(exit::DATAERR, format!("{}: not UTF-8 text", path.display())))?;
        let plan = SweepPlan::parse(&text, path).map_err(|e| fail(exit::DATAERR, e.to_string()))?;
        let name = path.display().to_string();
        refuse_line_breaks(&plan, &name)?;
        let base = sweep_base(&plan, sets, &name)?;
        let base_toml = given_toml(base.given());
        let digest = sweep_digest(&sweep_bytes, &base_toml);
        let header = results_header(&plan, base.spec().team.is_some());
        let data_files = plan_data_file_digests_all(&plan, base.given(), &name)?;
        Ok(Self {
            path: path.to_path_buf(),
            sweep_bytes,
            plan,
            name,
            base,
            base_toml,
            digest,
            header,
            data_files,
        })
    }

    /// How many runs shard `(k, n)` of this sweep holds (the runs with `id % n == k - 1`).
    pub fn shard_runs(&self, (k, n): (u64, u64)) -> u64 {
        let total = self.plan.total();
        total / n + u64::from(total % n >= k)
    }

    /// Opens output directory `out` for shard `(k, n)`: creates it (each level it creates
    /// removed again, when still empty, if the sweep is interrupted:
    /// [`crate::cleanup::create_dir_all`]) and locks it; with an existing `results.csv`,
    /// refuses it unless `resume` (or replaces it with `force`), checks on `--resume` that the
    /// same sweep made it and indexes its rows (a cut-off last line dropped); then, in one step
    /// an interrupt never cuts ([`crate::cleanup::whole`]: att51-3, Ctrl-C left `sweep.json`
    /// alone, or beside `sweep.toml`, with a false "cannot write DIR"), writes `sweep.json`,
    /// `sweep.toml`, `base_scenario.toml` and the header of a new `results.csv`.
    pub fn open_output(
        &self,
        out: &Path,
        shard: (u64, u64),
        resume: bool,
        force: bool,
    ) -> Result<SweepOutput, Failure> {
        let shard_runs = self.shard_runs(shard);
        let cant = cant_write(out);
        self.refuse_inputs_as_outputs(out)?;
        let created = crate::cleanup::create_dir_all(out).map_err(cant)?;
        // Held to the end of the sweep (dropped with the output, released by the OS on any
        // exit).
        let lock = lock_output_dir(out, "sweep")?;
        // Whose files are there (att42-4), before anything is removed or written.
        refuse_foreign_sweep_files(out)?;
        let results = out.join("results.csv");
        // The rows there that this sweep continues (`--force` replaces them instead).
        let kept = results.exists() && !force;
        if kept && !resume {
            return Err(fail(
                exit::CANTCREAT,
                format!(
                    "{} exists: pass --resume to continue that sweep, --force to start over, or another --out",
                    crate::owned::shell_quoted(&results)
                ),
            ));
        }
        // Whether the rows there are of a known engine (a new results.csv: this one's).
        let engine_known = if kept {
            self.check_same_sweep(out)?
        } else {
            true
        };
        let done = if kept {
            self.resumed_ids(&results, shard).map_err(|e| {
                if engine_known {
                    e
                } else {
                    unrecorded_engine_note(e, out)
                }
            })?
        } else {
            vec![]
        };
        // Rows of an unknown engine kept: the manifest does not claim them for this one.
        let record_engine = engine_known || done.is_empty();
        crate::cleanup::whole(|| {
            if results.exists() && !kept {
                std::fs::remove_file(&results).map_err(cant)?;
            }
            // The rows kept are appended to in a file of their own (att36-13 addendum): a hard
            // link to the results.csv resumed (a `cp -al` snapshot) keeps the rows it had.
            if kept {
                crate::files::renew_inode(&results).map_err(cant)?;
            }
            self.write_manifest(out, shard, shard_runs, record_engine)?;
            if !kept {
                crate::files::write_atomic(&results, csv_line(&self.header).as_bytes())
                    .map_err(cant)?;
            }
            Ok::<(), Failure>(())
        })?;
        Ok(SweepOutput {
            dir: out.to_path_buf(),
            results,
            shard,
            shard_runs,
            done,
            lock,
            _created: created,
        })
    }

    /// Refuses (64) a sweep whose output in `out` (`sweep.json`, `sweep.toml`,
    /// `base_scenario.toml`, `results.csv`) is one of its inputs (the sweep file, its base
    /// scenario, a data file a run reads), through links too (att42-4: a sweep whose base
    /// scenario was `DIR/base_scenario.toml` wrote its resolved keys over it). A `sweep.toml` or
    /// `base_scenario.toml` that already holds exactly what the sweep would write there (the
    /// sweep file `DIR/sweep.toml` of an earlier sweep run again) is no clash: it is left as
    /// it is.
    fn refuse_inputs_as_outputs(&self, out: &Path) -> Result<(), Failure> {
        let inputs: Vec<PathBuf> = [self.path.clone(), self.plan.scenario.clone()]
            .into_iter()
            .chain(self.data_files.keys().map(PathBuf::from))
            .collect();
        for name in SWEEP_FILES.iter().chain(&["results.csv"]) {
            let o = out.join(name);
            let Some(input) = inputs.iter().find(|i| crate::files::same_file(i, &o)) else {
                continue;
            };
            if self.unchanged(&o, name) {
                continue;
            }
            return Err(fail(
                exit::USAGE,
                format!(
                    "{} is an input ({}): an output cannot be one of the inputs; use another --out",
                    crate::owned::shell_quoted(&o),
                    input.display()
                ),
            ));
        }
        Ok(())
    }

    /// Whether `path` (the sweep directory's file `name`) already holds what the sweep writes
    /// there (`sweep.toml`, `base_scenario.toml`): writing it would change nothing.
    fn unchanged(&self, path: &Path, name: &str) -> bool {
        let new: &[u8] = match name {
            "sweep.toml" => &self.sweep_bytes,
            "base_scenario.toml" => self.base_toml.as_bytes(),
            _ => return false,
        };
        crate::owned::read_capped(path, new.len() as u64).is_ok_and(|b| b.as_deref() == Some(new))
    }

    /// Refuses directory `out` on `--resume` when its `sweep.json` names another digest or
    /// another engine ([`check_engine`]), or when an older isotrack wrote it (no `sweep.json`,
    /// or one without a digest: [`older_format`]). Returns whether its engine is recorded.
    fn check_same_sweep(&self, out: &Path) -> Result<bool, Failure> {
        if !out.join("sweep.json").exists() {
            return Err(older_format(
                out,
                "it has a results.csv but no sweep.json, which every sweep writes before its first row",
            ));
        }
        let stored = read_manifest(out)?;
        if stored.get("digest").is_none() {
            return Err(older_format(
                out,
                "its sweep.json has no digest naming the sweep that made it",
            ));
        }
        if stored["digest"].as_str() != Some(self.digest.as_str()) {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: made by a different sweep (the sweep file or its resolved base scenario changed since; digest {} here, {} now): start a new --out",
                    out.display(),
                    stored["digest"].as_str().unwrap_or("missing"),
                    self.digest
                ),
            ));
        }
        let known = check_engine(out, &stored)?;
        check_data_files(out, &stored, &self.data_files, "now")?;
        Ok(known)
    }

    /// The runs already in `results` (their ids only, sorted), each row checked, a cut-off
    /// last line cut, a header-less file given the header.
    fn resumed_ids(&self, results: &Path, (k, n): (u64, u64)) -> Result<Vec<u64>, Failure> {
        let cant = cant_write(results.parent().unwrap_or(Path::new(".")));
        let spans =
            RunSpans::new(&self.plan, self.base.given()).with_scenario(&self.base, &self.name);
        let idx = index_results(results, 0, true, self.plan.total(), &self.plan, &spans)?;
        let header_line = csv_line(&self.header);
        if idx.header.is_empty() {
            crate::files::write_atomic(results, header_line.as_bytes()).map_err(cant)?;
        } else if idx.header != header_line {
            let stored = csv_fields(&idx.header).unwrap_or_default();
            let missing: Vec<&str> = self
                .header
                .iter()
                .filter(|c| !stored.contains(c))
                .map(String::as_str)
                .collect();
            let dir = results.parent().unwrap_or(Path::new("."));
            if !missing.is_empty() && stored.iter().all(|c| self.header.contains(c)) {
                return Err(older_format(
                    dir,
                    &format!(
                        "its results.csv lacks the column{} `{}` that this isotrack writes",
                        if missing.len() == 1 { "" } else { "s" },
                        missing.join("`, `")
                    ),
                ));
            }
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
        Ok(rows.iter().map(|r| r.id).collect())
    }

    /// The sweep, its resolved base scenario and its manifest, kept next to the results
    /// (written before the first row, so every `results.csv` has the `sweep.json` that says
    /// which sweep made it).
    fn write_manifest(
        &self,
        out: &Path,
        (k, n): (u64, u64),
        shard_runs: u64,
        record_engine: bool,
    ) -> Result<(), Failure> {
        let cant = cant_write(out);
        let mut manifest = json!({
            "sweep": self.name,
            "scenario": self.plan.scenario.display().to_string(),
            "digest": self.digest,
            "total_runs": self.plan.total(),
            "shard": [k, n],
            "shard_runs": shard_runs,
            "columns": self.header,
        });
        // The data files of every run by content: --resume and merge refuse rows over another
        // version of them.
        if let Some(files) = data_files_entry(&self.data_files) {
            manifest["data_files"] = files;
        }
        if record_engine {
            manifest["engine"] = json!(engine());
        }
        // The manifest first, so that the two files after it are never without it (a sweep
        // killed between them leaves them the sweep's, [`refuse_foreign_sweep_files`]).
        // Never through a link nor into a
        // FIFO (73 at once): `files::write_atomic`; a file that already holds its bytes (the
        // sweep's own input: [`SweepJob::refuse_inputs_as_outputs`]) is left as it is.
        crate::files::write_atomic(
            &out.join("sweep.json"),
            (serde_json::to_string_pretty(&manifest).unwrap_or_default() + "\n").as_bytes(),
        )
        .map_err(cant)?;
        for (name, bytes) in [
            ("sweep.toml", self.sweep_bytes.as_slice()),
            ("base_scenario.toml", self.base_toml.as_bytes()),
        ] {
            let p = out.join(name);
            if !self.unchanged(&p, name) {
                crate::files::write_atomic(&p, bytes).map_err(cant)?;
            }
        }
        Ok(())
    }

    /// Runs the shard's runs not yet done on `pool`, appending each row to `results.csv` as it
    /// finishes (one whole line, then a flush) and calling `row_written` after each.
    pub fn run_missing(
        &self,
        out: &SweepOutput,
        pool: &rayon::ThreadPool,
        row_written: &(dyn Fn() + Sync),
    ) -> Result<(), Failure> {
        let (k, n) = out.shard;
        let cant = cant_write(&out.dir);
        let (tx, rx) = std::sync::mpsc::channel::<String>();
        std::thread::scope(|scope| {
            let writer = scope.spawn(|| -> Result<(), Failure> {
                // Not through a link, never blocking on a FIFO (`files::open_regular`), then
                // appended to.
                let mut f = crate::files::open_regular(&out.results, false, false)
                    .and_then(|mut f| {
                        use std::io::Seek;
                        f.seek(std::io::SeekFrom::End(0)).map(|_| f)
                    })
                    .map_err(cant)?;
                for line in rx {
                    f.write_all(line.as_bytes()).map_err(cant)?;
                    f.flush().map_err(cant)?;
                    row_written();
                }
                f.sync_all().map_err(cant)
            });
            // The shard's ids are generated, not listed up front: memory stays flat however
            // large the sweep.
            // Runs go in groups of LANES consecutive ones (stepped together, see run_rows).
            pool.install(|| {
                (0..out.shard_runs.div_ceil(LANES as u64))
                    .into_par_iter()
                    .for_each_with(tx, |tx, c| {
                        let ids: Vec<u64> = (c * LANES as u64
                            ..((c + 1) * LANES as u64).min(out.shard_runs))
                            .map(|i| i * n + (k - 1))
                            .filter(|id| out.done.binary_search(id).is_err())
                            .collect();
                        for row in run_rows(&self.plan, &self.base, &ids, &self.name) {
                            let _ = tx.send(row);
                        }
                    })
            });
            writer
                .join()
                .unwrap_or_else(|_| Err(fail(exit::CANTCREAT, "the results writer stopped".into())))
        })
    }

    /// Rewrites `results.csv` sorted by `run_id` (atomically), after checking that no run
    /// appears twice; what it holds.
    pub fn finish(&self, out: &SweepOutput) -> Result<SweepReport, Failure> {
        let results = &out.results;
        let spans =
            RunSpans::new(&self.plan, self.base.given()).with_scenario(&self.base, &self.name);
        let idx = index_results(results, 0, false, self.plan.total(), &self.plan, &spans)?;
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
        write_sorted(results, &idx.header, &rows, std::slice::from_ref(results))?;
        Ok(SweepReport {
            rows: rows.len() as u64,
            invalid: idx.invalid,
            flagged: idx.flagged,
        })
    }
}

/// The failure for `--resume` of sweep directory `out` written by an older isotrack (`why`
/// says how that shows): its rows cannot be checked against this sweep, so they are not
/// trusted. Exit 65, as a directory made by another sweep; what to do instead.
fn older_format(out: &Path, why: &str) -> Failure {
    fail(
        exit::DATAERR,
        format!(
            "{}: a sweep directory written by an older isotrack ({why}): --resume cannot check its rows against this sweep, so it does not continue it. Run the sweep again into a new --out, or into this one with --force (its results.csv is replaced)",
            out.display()
        ),
    )
}

/// The failure for an output in directory `out` that cannot be written.
fn cant_write(out: &Path) -> impl Fn(std::io::Error) -> Failure + Copy + '_ {
    move |e| {
        fail(
            exit::CANTCREAT,
            format!("cannot write {}: {e}", out.display()),
        )
    }
}
