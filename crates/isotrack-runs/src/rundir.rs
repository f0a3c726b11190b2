//! Writing a run directory: `trace.csv`, `summary.json` and the resolved `scenario.toml`, the
//! one way every command writes one (`run --out`, `compare --out`'s per-law directories,
//! `figures --runs`, `sitl --out`, `fly --out`, the Python package's `Run.save`).
//!
//! [`RunDir::open`] readies the directory (no output over an input, created, locked when the
//! command locks it, no output an existing link, FIFO or device, the old summary removed);
//! [`RunDir::trace`] streams the trace into a temporary file beside `trace.csv` (or
//! [`RunDir::live_trace`] into `trace.csv` itself, for a flight watched as it goes);
//! [`RunDir::finish`] renames it into place, writes `scenario.toml` and then `summary.json`
//! (atomically, last: a directory with a summary is whole). A run interrupted in between leaves
//! a directory without a summary, which readers refuse, never an old summary beside a new trace.

use crate::failure::{exit, Failure};
use crate::files::{refuse_non_regular, same_file, temp_beside, write_atomic};
use crate::summary::Summary;
use crate::sweep::lock::{lock_output_dir, DirLock};
use crate::trace::TraceWriter;
use isotrack_scenario::Scenario;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files of a run directory.
pub const RUN_FILES: [&str; 3] = ["trace.csv", "summary.json", "scenario.toml"];

/// The files a command reads for `scenario`: the scenario file (if any) and the data files its
/// field names (`field.path`, `field.paths`: absolute once the scenario is built). An output
/// that is one of them is refused (64), never written over.
pub fn input_files(scenario_file: Option<&Path>, scenario: &Scenario) -> Vec<PathBuf> {
    let field = &scenario.file().field;
    scenario_file
        .map(Path::to_path_buf)
        .into_iter()
        .chain(field.path.iter().map(PathBuf::from))
        .chain(field.paths.iter().flatten().map(PathBuf::from))
        .collect()
}

/// When `output` is one of `inputs` (the same file, through links): the message that refuses it.
pub fn input_clash(inputs: &[PathBuf], output: &Path) -> Option<String> {
    let input = inputs.iter().find(|i| same_file(i, output))?;
    Some(format!(
        "{} is an input ({}): an output cannot be one of the inputs",
        output.display(),
        input.display()
    ))
}

/// `cannot write PATH: WHY`, exit 73.
fn cant(path: &Path, e: impl std::fmt::Display) -> Failure {
    Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", path.display()),
    }
}

/// A run directory being written ([`RunDir::open`], then [`RunDir::trace`] and
/// [`RunDir::finish`]); its lock, if it took one, is held until this is dropped (so a command
/// that adds files after the run, as `run --plot`, still holds it).
#[derive(Debug)]
pub struct RunDir {
    dir: PathBuf,
    lock: Option<DirLock>,
}

/// `trace.csv` being streamed into a temporary file beside it ([`RunDir::trace`]).
pub struct TraceFile {
    writer: TraceWriter,
    /// The temporary file renamed into place when finished (`None`: written in place).
    tmp: Option<PathBuf>,
    /// The temporary file removed if the process is interrupted ([`crate::cleanup`]).
    _pending: Option<crate::cleanup::Pending>,
}

impl TraceFile {
    /// The writer to record rows into (a [`isotrack_sim::TraceSink`]).
    pub fn writer(&mut self) -> &mut TraceWriter {
        &mut self.writer
    }
}

impl RunDir {
    /// Readies run directory `dir`: none of its files ([`RUN_FILES`] and `extra`, e.g. `fly`'s
    /// `mavlink.tlog`) one of `inputs` ([`input_files`]; exit 64), the directory created, locked
    /// for `command` when given (exit 73 while another command writes it; `None` where the
    /// caller holds a lock on a parent or writes no lock, as `Run.save`), none of its files an
    /// existing link, FIFO, directory or device (exit 73), and the old `summary.json` removed.
    pub fn open(
        dir: &Path,
        inputs: &[PathBuf],
        extra: &[&str],
        command: Option<&str>,
    ) -> Result<RunDir, Failure> {
        let names: Vec<&str> = RUN_FILES.iter().chain(extra).copied().collect();
        for name in &names {
            if let Some(message) = input_clash(inputs, &dir.join(name)) {
                return Err(Failure {
                    code: exit::USAGE,
                    message,
                });
            }
        }
        std::fs::create_dir_all(dir).map_err(|e| cant(dir, e))?;
        let lock = command.map(|c| lock_output_dir(dir, c)).transpose()?;
        // Holding the lock, no other command writes here: temporaries a killed process left
        // (`.trace.csv.PID.tmp`, its PID gone) are removed.
        if lock.is_some() {
            crate::cleanup::remove_stale_temporaries(dir, &names);
        }
        for name in &names {
            let p = dir.join(name);
            refuse_non_regular(&p).map_err(|e| cant(&p, e))?;
        }
        let summary = dir.join("summary.json");
        match std::fs::remove_file(&summary) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(cant(&summary, e)),
            _ => {}
        }
        Ok(RunDir {
            dir: dir.to_path_buf(),
            lock,
        })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// `DIR/name`.
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// Whether this holds the directory's lock.
    pub fn is_locked(&self) -> bool {
        self.lock.is_some()
    }

    /// Starts `trace.csv` (with a flying vehicle's telemetry columns when `flying`): streamed
    /// into a temporary file beside it, renamed into place by [`RunDir::finish`].
    pub fn trace(&self, flying: bool) -> Result<TraceFile, Failure> {
        self.temp_trace(TraceWriter::create, flying)
    }

    /// Starts a team's `trace.csv` (`[team]`: a `vehicle` column last,
    /// [`TraceWriter::create_team`]), as [`RunDir::trace`] streamed into a temporary file
    /// renamed into place by [`RunDir::finish`].
    pub fn team_trace(&self, flying: bool) -> Result<TraceFile, Failure> {
        self.temp_trace(TraceWriter::create_team, flying)
    }

    /// `trace.csv` made by `create` in a temporary file beside it.
    fn temp_trace(
        &self,
        create: fn(&Path, bool) -> std::io::Result<TraceWriter>,
        flying: bool,
    ) -> Result<TraceFile, Failure> {
        let path = self.path("trace.csv");
        let tmp = temp_beside(&path);
        let writer = create(&tmp, flying).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            cant(&path, e)
        })?;
        Ok(TraceFile {
            writer,
            _pending: Some(crate::cleanup::register(&tmp)),
            tmp: Some(tmp),
        })
    }

    /// Abandons a trace that will not be finished (the run was refused): its temporary file
    /// is removed, and `why` returned as the failure to write `trace.csv` (exit 73).
    pub fn abandon(&self, trace: TraceFile, why: impl std::fmt::Display) -> Failure {
        let TraceFile { writer, tmp, .. } = trace;
        drop(writer);
        if let Some(tmp) = &tmp {
            let _ = std::fs::remove_file(tmp);
        }
        cant(&self.path("trace.csv"), why)
    }

    /// Starts `trace.csv` written in place as the run goes, for a run watched while it flies
    /// (`sitl`, `fly`: `tail -f DIR/trace.csv`); the summary, written last by
    /// [`RunDir::finish`], still marks the directory whole.
    pub fn live_trace(&self, flying: bool) -> Result<TraceFile, Failure> {
        let path = self.path("trace.csv");
        let writer = TraceWriter::create(&path, flying).map_err(|e| cant(&path, e))?;
        Ok(TraceFile {
            writer,
            tmp: None,
            _pending: None,
        })
    }

    /// Finishes the directory: the trace flushed and renamed into place, the resolved
    /// `scenario.toml` written, then `summary.json`, each atomically, the summary last.
    pub fn finish<S: Serialize>(
        &self,
        trace: TraceFile,
        scenario_toml: &str,
        summary: &Summary<S>,
    ) -> Result<(), Failure> {
        self.finish_text(trace, scenario_toml, &summary.to_json())
    }

    /// [`RunDir::finish`] with the summary's text as given (the Python package's `Run.summary`,
    /// written byte for byte), checked first to read back as a [`Summary`]
    /// ([`Summary::from_json`]: exit 65 with the reason when it does not).
    pub fn finish_json(
        &self,
        trace: TraceFile,
        scenario_toml: &str,
        summary_json: &str,
    ) -> Result<(), Failure> {
        if let Err(e) = Summary::from_json(summary_json) {
            if let Some(tmp) = &trace.tmp {
                let _ = std::fs::remove_file(tmp);
            }
            return Err(Failure {
                code: exit::DATAERR,
                message: format!("summary: {e}"),
            });
        }
        let text = if summary_json.ends_with('\n') {
            summary_json.to_string()
        } else {
            format!("{summary_json}\n")
        };
        self.finish_text(trace, scenario_toml, &text)
    }

    fn finish_text(
        &self,
        trace: TraceFile,
        scenario_toml: &str,
        summary: &str,
    ) -> Result<(), Failure> {
        let path = self.path("trace.csv");
        let TraceFile { writer, tmp, .. } = trace;
        writer
            .finish()
            .and_then(|()| match &tmp {
                Some(tmp) => std::fs::rename(tmp, &path),
                None => Ok(()),
            })
            .map_err(|e| {
                if let Some(tmp) = &tmp {
                    let _ = std::fs::remove_file(tmp);
                }
                cant(&path, e)
            })?;
        let resolved = self.path("scenario.toml");
        write_atomic(&resolved, scenario_toml.as_bytes()).map_err(|e| cant(&resolved, e))?;
        let p = self.path("summary.json");
        write_atomic(&p, summary.as_bytes()).map_err(|e| cant(&p, e))
    }
}
