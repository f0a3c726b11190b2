//! Writing a run directory: `trace.csv`, `summary.json` and the resolved `scenario.toml`, the
//! one way every command writes one (`run --out`, `compare --out`'s per-law directories,
//! `figures --runs`, `sitl --out`, `fly --out`, the Python package's `Run.save`).
//!
//! [`RunDir::open`] readies the directory (no output over an input, not a folder holding an
//! input, created, locked when the command locks it, no output an existing link, FIFO or
//! device, no run file there that is not an earlier isotrack run's: [`not_an_earlier_run`])
//! and changes nothing in it: an earlier run there stands until the new one has
//! something to write. [`RunDir::trace`] streams the trace into a temporary file beside
//! `trace.csv`; [`RunDir::finish`] removes the old summary, renames the trace into place,
//! writes `scenario.toml` and then `summary.json` (atomically, last: a directory with a summary
//! is whole), so a run refused or failed before its end leaves the earlier run whole. A run
//! watched as it goes ([`RunDir::live_trace`]: `sitl`, `fly`, called once the flight has
//! something to record) removes the old summary when it starts `trace.csv` in place; a run
//! interrupted after that leaves a directory without a summary, which readers refuse, never an
//! old summary beside a new trace.

use crate::failure::{exit, Failure};
use crate::files::{refuse_non_regular, same_file, temp_beside, write_atomic};
use crate::owned::shell_quoted;
use crate::summary::Summary;
use crate::sweep::lock::{lock_output_dir, DirLock};
use crate::trace::TraceWriter;
use isotrack_scenario::Scenario;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files of a run directory.
pub const RUN_FILES: [&str; 3] = ["trace.csv", "summary.json", "scenario.toml"];

/// The other files isotrack writes into a run directory: `plot`'s (and `run --plot`'s) figures
/// in either format, `plot --animate`'s `animation.gif` and `fly`'s `mavlink.tlog`. A new run
/// replacing the directory never removes them (a file of one of these names may be the user's:
/// att36-1, att38-1, where deleting them lost a user's pictures); those left from before the
/// run are named by [`RunDir::outputs_from_before`], which `run` prints as a note (nu-21: an
/// earlier run's figures left beside the new trace read as this run's).
pub const RUN_OUTPUTS: [&str; 8] = [
    "trajectory.png",
    "trajectory.svg",
    "timeseries.png",
    "timeseries.svg",
    "team.png",
    "team.svg",
    "animation.gif",
    "mavlink.tlog",
];

/// The files a command reads for `scenario`: the scenario file (if any) and the data files its
/// field names (`field.path`, `field.paths`: absolute once the scenario is built). An output
/// that is one of them is refused (64), never written over.
pub fn input_files(scenario_file: Option<&Path>, scenario: &Scenario) -> Vec<PathBuf> {
    scenario_file
        .map(Path::to_path_buf)
        .into_iter()
        .chain(
            scenario
                .spec()
                .field
                .data_files()
                .into_iter()
                .map(PathBuf::from),
        )
        .collect()
}

/// `it` or `them`, `is` or `are`, for `n` files.
fn it_them(n: usize) -> (&'static str, &'static str) {
    if n == 1 {
        ("it", "is")
    } else {
        ("them", "are")
    }
}

/// Why the run files already in the existing directory `dir` ([`RUN_FILES`] and the command's
/// own `extra`, e.g. `fly`'s `mavlink.tlog`) are not an earlier isotrack run's, which a new
/// run may replace (att39-1, att39-4: a user's own `summary.json`, `trace.csv`,
/// `scenario.toml` or `mavlink.tlog` was replaced without a word); `None` when there is none
/// of them, or when `summary.json` is one an isotrack of any version wrote
/// ([`crate::summary::not_isotracks`]: a JSON object with `isotrack_version`, `outcome` and
/// `scenario`; the other files beside it are then that run's, but `extra`: a flight's own
/// files, `fly`'s `mavlink.tlog`, are that run's only beside a flight's summary
/// ([`crate::summary::is_flights`]; att41-1: a run writes no log, so one beside a simulated
/// run's summary is the user's).
///
/// Refused: a `summary.json` that is not isotrack's (or larger than
/// [`crate::summary::MAX_SUMMARY_BYTES`], never read whole, or unreadable), and run files with
/// no `summary.json` beside them (the user's own; isotrack writes a run's summary last, so a
/// run killed before its end leaves none either: its files are moved away by hand). Files
/// named as figures ([`RUN_OUTPUTS`] but `extra`) are no run files: never replaced, a
/// directory holding only them (or the user's other files) is run into. `summary.json` is
/// read without following a link nor opening a FIFO ([`RunDir::open`] refuses those first).
pub fn not_an_earlier_run(dir: &Path, extra: &[&str]) -> Option<String> {
    let summary = dir.join("summary.json");
    if std::fs::symlink_metadata(&summary).is_ok() {
        let max = crate::summary::MAX_SUMMARY_BYTES;
        let refused = |why: String| {
            Some(format!(
                "{} is not an isotrack run's summary ({why}): refusing to replace it; move it away or use another --out",
                shell_quoted(&summary)
            ))
        };
        let text = match crate::owned::read_capped(&summary, max) {
            Ok(Some(bytes)) => match String::from_utf8(bytes) {
                Ok(text) => text,
                Err(_) => return refused("not UTF-8 text".into()),
            },
            Ok(None) => {
                return refused(format!(
                    "larger than {} MiB, which no isotrack summary is",
                    max >> 20
                ))
            }
            Err(e) => return refused(format!("it cannot be read: {e}")),
        };
        if let Some(why) = crate::summary::not_isotracks(&text) {
            return refused(why);
        }
        // att41-1: the `extra` files are a flight's (`fly`'s `mavlink.tlog`): that run's only
        // beside a flight's summary. Beside a simulated run's (which writes no log) it is the
        // user's own, as with no summary at all.
        let theirs = present_files(dir, extra);
        if theirs.is_empty() || crate::summary::is_flights(&text) {
            return None;
        }
        let (it, is) = it_them(theirs.len());
        return Some(format!(
            "{} {is} not an isotrack flight's: the summary.json beside {it} is a simulated run's (no `end_reason` key, which every flight's summary has), and only `fly --out` writes {it}: refusing to replace {it}; move {it} away or use another --out",
            theirs.join(", ")
        ));
    }
    let run_files: Vec<&str> = RUN_FILES.iter().chain(extra).copied().collect();
    let present = present_files(dir, &run_files);
    if present.is_empty() {
        return None;
    }
    let (it, is) = it_them(present.len());
    Some(format!(
        "{} {is} not an isotrack run's: no summary.json beside {it} (isotrack writes a run's summary.json last; a run killed before its end leaves none either): refusing to replace {it}; move {it} away or use another --out",
        present.join(", ")
    ))
}

/// The paths of those of `names` (but `summary.json`) that are in `dir`, for a message.
fn present_files(dir: &Path, names: &[&str]) -> Vec<String> {
    names
        .iter()
        .filter(|n| **n != "summary.json")
        .map(|n| dir.join(n))
        .filter(|p| std::fs::symlink_metadata(p).is_ok())
        .map(|p| shell_quoted(&p))
        .collect()
}

/// [`not_an_earlier_run`] as the failure (exit 73), for a command that checks its run
/// directories before it runs anything (`compare`'s per-law directories).
pub fn refuse_not_an_earlier_run(dir: &Path, extra: &[&str]) -> Result<(), Failure> {
    match not_an_earlier_run(dir, extra) {
        Some(message) => Err(Failure {
            code: exit::CANTCREAT,
            message,
        }),
        None => Ok(()),
    }
}

/// The [`RUN_OUTPUTS`] but `extra` in `dir` (anything there but a directory).
fn present_outputs(dir: &Path, extra: &[&str]) -> Vec<&'static str> {
    RUN_OUTPUTS
        .into_iter()
        .filter(|n| !extra.contains(n))
        .filter(|n| std::fs::symlink_metadata(dir.join(n)).is_ok_and(|m| !m.is_dir()))
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

/// Why `dir` cannot be a run directory when something other than a directory is there (or a
/// link to one): what it is, named. `None` for a directory, a link to one, or nothing.
fn not_a_directory(dir: &Path) -> Option<String> {
    let m = std::fs::symlink_metadata(dir).ok()?;
    if m.is_dir() {
        return None;
    }
    if m.file_type().is_symlink() {
        let to = std::fs::read_link(dir)
            .map(|t| t.display().to_string())
            .unwrap_or_else(|_| "?".into());
        return match std::fs::metadata(dir) {
            Ok(t) if t.is_dir() => None,
            Ok(t) => Some(format!(
                "it is a symbolic link to {to}, which is {}, not a directory",
                kind_of(&t)
            )),
            Err(e) => Some(format!(
                "it is a symbolic link to {to}, which cannot be followed ({e}): a dangling link, not a directory"
            )),
        };
    }
    Some(format!("it exists and is {}, not a directory", kind_of(&m)))
}

/// Refuses (73) anything at `dir` but a directory of its own, where a command writes a
/// directory whose name it picks itself inside an output directory (`compare --out CMP`'s
/// `CMP/LAW`): a symbolic link (even to a directory: att44-12, `CMP/pid` linking to another
/// run had that run replaced by the pid law's), a file, a FIFO; named, with what it is. A
/// directory named on the command line may be a link ([`RunDir::open`]: the user named it).
pub fn refuse_not_own_directory(dir: &Path) -> Result<(), Failure> {
    let Ok(m) = std::fs::symlink_metadata(dir) else {
        return Ok(());
    };
    if m.is_dir() {
        return Ok(());
    }
    let what = if m.file_type().is_symlink() {
        let to = std::fs::read_link(dir)
            .map(|t| t.display().to_string())
            .unwrap_or_else(|_| "?".into());
        format!("a symbolic link (to {to})")
    } else {
        kind_of(&m).to_string()
    };
    Err(Failure {
        code: exit::CANTCREAT,
        message: format!(
            "{} is {what}, not a directory: isotrack writes a directory of its own there and never writes through a link nor over another file; move it away or use another --out",
            shell_quoted(dir)
        ),
    })
}

/// What a file is, in words (`a FIFO (named pipe)`, `a regular file`, ...).
fn kind_of(m: &std::fs::Metadata) -> &'static str {
    let t = m.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_block_device() || t.is_char_device() {
            return "a device";
        }
    }
    if t.is_file() {
        "a regular file"
    } else if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else {
        "not a regular file"
    }
}

/// When the existing directory `dir` holds one of `inputs` at any depth (it is the scenario
/// file's folder, or a parent of it; through links): the message that refuses it. A run
/// directory is the command's own (its files, a lock, later plots): never a folder of inputs.
fn holds_an_input(dir: &Path, inputs: &[PathBuf]) -> Option<String> {
    let d = std::fs::canonicalize(dir).ok()?;
    let input = inputs
        .iter()
        .find(|i| std::fs::canonicalize(i).is_ok_and(|c| c.starts_with(&d)))?;
    Some(format!(
        "cannot write run directory {}: it holds the input {} (the scenario's folder or a parent of it): a run directory is the command's own, give --out a directory of its own",
        shell_quoted(dir),
        input.display()
    ))
}

/// `cannot write PATH: WHY` (the path shell-quoted, att41-2), exit 73.
fn cant(path: &Path, e: impl std::fmt::Display) -> Failure {
    Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", shell_quoted(path)),
    }
}

/// A run directory being written ([`RunDir::open`], then [`RunDir::trace`] and
/// [`RunDir::finish`]); its lock, if it took one, is held until this is dropped (so a command
/// that adds files after the run, as `run --plot`, still holds it).
#[derive(Debug)]
pub struct RunDir {
    dir: PathBuf,
    lock: Option<DirLock>,
    /// Whether [`RunDir::open`] created the directory (removed again by
    /// [`RunDir::release_unused`] when nothing was written).
    created: bool,
    /// The directories [`RunDir::open`] created (parents included), registered to be removed
    /// (when still empty) if the command is interrupted ([`crate::cleanup::create_dir_all`]: att46-10, an interrupted
    /// `compare` into a new `--out` left its laws' empty directories behind).
    _created_pending: Vec<crate::cleanup::Pending>,
    /// The [`RUN_OUTPUTS`] in the directory when it was opened but the command's own `extra`
    /// files (`fly`'s `mavlink.tlog`, replaced as the earlier run's): not written by
    /// this command ([`RunDir::outputs_from_before`]; att39-7: told by name, not by
    /// modification time, which missed one dated in the future).
    before: Vec<&'static str>,
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
    /// `mavlink.tlog`) one of `inputs` ([`input_files`]; exit 64), `dir` itself a directory (or
    /// absent, or a link to a directory; a FIFO, file, device or dangling link there is refused
    /// naming what it is, exit 73) and not one holding an input at any depth (the scenario's
    /// folder or a parent of it, exit 73: a run directory is the command's own), created,
    /// locked for `command` when given (exit 73 while another command writes it; `None` where
    /// the caller holds a lock on a parent or writes no lock, as `Run.save`), and none of its
    /// files an existing link, FIFO, directory or device (exit 73), nor one that is not an
    /// earlier isotrack run's ([`not_an_earlier_run`]: a user's own `summary.json`, or
    /// `trace.csv`, `scenario.toml`, `extra` with no summary beside them; exit 73 naming it,
    /// before the command runs anything). Nothing in it is changed yet: an earlier run's files
    /// stand until [`RunDir::finish`] or [`RunDir::live_trace`].
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
        if let Some(why) = not_a_directory(dir) {
            return Err(Failure {
                code: exit::CANTCREAT,
                message: format!("cannot write run directory {}: {why}", shell_quoted(dir)),
            });
        }
        if let Some(message) = holds_an_input(dir, inputs) {
            return Err(Failure {
                code: exit::CANTCREAT,
                message,
            });
        }
        let created = std::fs::symlink_metadata(dir).is_err();
        // Each level created (parents included, att48-5) is removed on an interrupt while empty.
        let created_pending = crate::cleanup::create_dir_all(dir).map_err(|e| cant(dir, e))?;
        let lock = command.map(|c| lock_output_dir(dir, c)).transpose()?;
        for name in &names {
            let p = dir.join(name);
            refuse_non_regular(&p).map_err(|e| cant(&p, e))?;
        }
        // Only now, the lock held (no isotrack command is midway through replacing the
        // directory) and no run file a link or FIFO: whose files are these? A user's are
        // refused before anything runs (the lock file is removed again as the lock drops).
        refuse_not_an_earlier_run(dir, extra)?;
        // Holding the lock, no other command writes here, and the directory is an earlier
        // run's or holds no run file: temporaries a killed process left (`.trace.csv.PID.tmp`,
        // its PID gone) are removed. Only now: a folder refused above loses nothing (att41-13).
        if lock.is_some() {
            crate::cleanup::remove_stale_temporaries(dir, &names);
        }
        let before = present_outputs(dir, extra);
        Ok(RunDir {
            dir: dir.to_path_buf(),
            lock,
            created,
            _created_pending: created_pending,
            before,
        })
    }

    /// Lets go of a directory nothing was written to (a flight that never started): the lock
    /// released, and the directory removed again if [`RunDir::open`] created it and it is
    /// empty. An earlier run's files are left as they were.
    pub fn release_unused(self) {
        let RunDir {
            dir,
            lock,
            created,
            _created_pending,
            ..
        } = self;
        drop(lock);
        if created {
            let _ = std::fs::remove_dir(&dir);
        }
    }

    /// Removes the old `summary.json` (the directory's earlier run is being replaced). Nothing
    /// else: a figure or log of an earlier run may as well be the user's own file of that name
    /// ([`RUN_OUTPUTS`]), and isotrack never removes a file it may not have written.
    fn remove_old_summary(&self) -> Result<(), Failure> {
        let summary = self.path("summary.json");
        match std::fs::remove_file(&summary) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(cant(&summary, e)),
            _ => {}
        }
        Ok(())
    }

    /// The [`RUN_OUTPUTS`] (but the command's own `extra`) that were in the directory when it
    /// was opened and are there still: an earlier run's figures or logs, or the user's files
    /// of those names, beside this run's files and not this run's (nu-21; never removed):
    /// what `run`'s note names (`note_outputs_from_before` in isotrack-commands), printed by
    /// `compare` for each law's directory and by `sitl` and `fly --out` too.
    pub fn outputs_from_before(&self) -> Vec<&'static str> {
        let now = present_outputs(&self.dir, &[]);
        self.before
            .iter()
            .copied()
            .filter(|n| now.contains(n))
            .collect()
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

    /// Finishes a directory whose live trace ([`RunDir::live_trace`]) could not be written to
    /// its end (a disk that filled mid-flight): the trace is left as far as it was written,
    /// `scenario.toml` and then `summary.json` (which says so, `summary`'s to say) written
    /// atomically as [`RunDir::finish`] writes them, so what a flight did (its end, its events)
    /// is kept. A summary that cannot be written either is the failure (exit 73).
    pub fn finish_incomplete<S: Serialize>(
        &self,
        trace: TraceFile,
        scenario_toml: &str,
        summary: &Summary<S>,
    ) -> Result<(), Failure> {
        let TraceFile { writer, tmp, .. } = trace;
        let summary = summary.to_json();
        // One step an interrupt never cuts (as `finish_text`).
        crate::cleanup::whole(|| {
            let _ = writer.finish();
            if let Some(tmp) = &tmp {
                let _ = std::fs::rename(tmp, self.path("trace.csv"));
            }
            self.remove_old_summary()?;
            self.write_scenario_and_summary(scenario_toml, &summary)
        })
    }

    /// `scenario.toml` and then `summary.json` (last: a directory with a summary is whole),
    /// each written atomically.
    fn write_scenario_and_summary(
        &self,
        scenario_toml: &str,
        summary: &str,
    ) -> Result<(), Failure> {
        let resolved = self.path("scenario.toml");
        write_atomic(&resolved, scenario_toml.as_bytes()).map_err(|e| cant(&resolved, e))?;
        let p = self.path("summary.json");
        write_atomic(&p, summary.as_bytes()).map_err(|e| cant(&p, e))
    }

    /// Starts `trace.csv` written in place as the run goes, for a run watched while it flies
    /// (`sitl`, `fly`: `tail -f DIR/trace.csv`): the old summary is removed first (the earlier
    /// run is replaced from here on); the summary, written last by [`RunDir::finish`], still
    /// marks the directory whole.
    pub fn live_trace(&self, flying: bool) -> Result<TraceFile, Failure> {
        self.remove_old_summary()?;
        let path = self.path("trace.csv");
        // A fresh file, never the earlier run's truncated in place: that file may have other
        // hard links (a `cp -al` / `rsync --link-dest` snapshot of the earlier run), which
        // would be rewritten with this flight's rows (att36-13). Only a regular file is
        // removed; anything else at the name is refused by the create below as before.
        if std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_file()) {
            std::fs::remove_file(&path).map_err(|e| cant(&path, e))?;
        }
        let writer = TraceWriter::create(&path, flying).map_err(|e| cant(&path, e))?;
        Ok(TraceFile {
            writer,
            tmp: None,
            _pending: None,
        })
    }

    /// Finishes the directory: the old summary removed, the trace flushed and renamed into
    /// place, the resolved `scenario.toml` written, then `summary.json`, each atomically, the
    /// summary last.
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

    /// The replacement itself, as one step an interrupt never cuts
    /// ([`crate::cleanup::whole`]): Ctrl-C while it runs is answered once the new run is whole,
    /// and one that came before it leaves the earlier run whole (att46-10: the interrupt
    /// removed the temporary trace after the old summary was removed, so the directory was
    /// left with the earlier trace and no summary, and `cannot write trace.csv` printed).
    fn finish_text(
        &self,
        trace: TraceFile,
        scenario_toml: &str,
        summary: &str,
    ) -> Result<(), Failure> {
        crate::cleanup::whole(|| self.replace_run(trace, scenario_toml, summary))
    }

    /// [`RunDir::finish_text`]'s step: the old summary removed, the trace renamed into place,
    /// `scenario.toml` and `summary.json` written.
    fn replace_run(
        &self,
        trace: TraceFile,
        scenario_toml: &str,
        summary: &str,
    ) -> Result<(), Failure> {
        let path = self.path("trace.csv");
        let TraceFile { writer, tmp, .. } = trace;
        if let Err(e) = self.remove_old_summary() {
            if let Some(tmp) = &tmp {
                let _ = std::fs::remove_file(tmp);
            }
            return Err(e);
        }
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
        self.write_scenario_and_summary(scenario_toml, summary)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isotrack_sim::{TraceRow, TraceSink};

    /// att33c item 10: a live trace whose writes failed (a disk that filled: ENOSPC) keeps its
    /// first error; `finish` fails with it, `finish_incomplete` still writes `scenario.toml`
    /// and `summary.json`.
    #[test]
    fn a_trace_on_a_full_disk_still_gets_its_summary() {
        let d = tempfile::tempdir().unwrap();
        let out = RunDir::open(d.path(), &[], &[], None).unwrap();
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let trace = || {
            let mut writer = TraceWriter::create(&d.path().join("trace.csv"), false).unwrap();
            writer.record(&TraceRow {
                t_s: 0.0,
                x_m: 0.0,
                y_m: 0.0,
                heading_rad: 0.0,
                s: 1.0,
                error: 0.0,
                omega_radps: 0.0,
                s_measured: None,
                telemetry: None,
            });
            writer.fail_with(std::io::Error::from_raw_os_error(28));
            assert_eq!(
                writer.error().map(|e| e.raw_os_error()),
                Some(Some(28)),
                "ENOSPC"
            );
            TraceFile {
                writer,
                tmp: None,
                _pending: None,
            }
        };
        let summary = Summary::of_run(
            &scenario,
            None,
            &scenario.run(&mut isotrack_sim::NoTrace),
            &[],
        );
        assert!(out.finish(trace(), "x = 1\n", &summary).is_err());
        assert!(!d.path().join("summary.json").exists());
        out.finish_incomplete(trace(), "x = 1\n", &summary).unwrap();
        assert!(d.path().join("summary.json").exists());
        assert_eq!(
            std::fs::read_to_string(d.path().join("scenario.toml")).unwrap(),
            "x = 1\n"
        );
    }

    /// att38-1 (att36-1's second door): a new run over an earlier run's directory removes none
    /// of the files named as isotrack's figures and logs (an earlier run's, or the user's:
    /// isotrack cannot tell, and deleting lost a user's pictures on the second run into their
    /// folder); [`RunDir::outputs_from_before`] names those there when it was opened (nu-21's
    /// note), whatever their date (att39-7: one dated a day ahead was missed by modification
    /// time), not one first written since, nor the command's own extra file.
    #[test]
    fn a_new_run_removes_no_figure_and_names_those_from_before() {
        let d = tempfile::tempdir().unwrap();
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let summary = Summary::of_run(
            &scenario,
            None,
            &scenario.run(&mut isotrack_sim::NoTrace),
            &[],
        );
        // A flight's directory (its summary has `end_reason`): its `mavlink.tlog` is `fly`'s
        // own extra file (att41-1: beside a simulated run's summary it is the user's).
        let flight = summary
            .to_json()
            .replacen('{', "{\"end_reason\": \"vehicle_ended\",", 1);
        std::fs::write(d.path().join("summary.json"), flight).unwrap();
        let old: Vec<&str> = RUN_OUTPUTS
            .into_iter()
            .filter(|n| *n != "timeseries.svg")
            .collect();
        for name in ["notes.txt", "my.png"].iter().chain(old.iter()) {
            std::fs::write(d.path().join(name), b"old").unwrap();
        }
        let ahead = std::time::SystemTime::now() + std::time::Duration::from_secs(86_400);
        std::fs::File::options()
            .write(true)
            .open(d.path().join("trajectory.svg"))
            .unwrap()
            .set_modified(ahead)
            .unwrap();
        let out = RunDir::open(d.path(), &[], &["mavlink.tlog"], None).unwrap();
        let trace = out.trace(false).unwrap();
        out.finish(trace, "x = 1\n", &summary).unwrap();
        // A figure first written after the run opened is not from before.
        std::fs::write(d.path().join("timeseries.svg"), b"new").unwrap();
        for name in ["notes.txt", "my.png"].iter().chain(old.iter()) {
            assert_eq!(
                std::fs::read(d.path().join(name)).unwrap(),
                b"old",
                "{name}"
            );
        }
        let before: Vec<&str> = old
            .iter()
            .copied()
            .filter(|n| *n != "mavlink.tlog")
            .collect();
        assert_eq!(out.outputs_from_before(), before);
    }

    /// att36-1, att39-1: a folder that never held an isotrack run but has files named
    /// `scenario.toml`, `trace.csv` or `summary.json` (a user's project folder, a JSON file of
    /// its own keys) is not an earlier run: the run is refused (73, naming the file) before
    /// anything is written, and every file there is left as it was, the lock file removed
    /// again. A `summary.json` must read as one an isotrack wrote, so a bare `{}`, one missing
    /// `isotrack_version` or one larger than any summary (never read whole) is the user's.
    #[test]
    fn a_folder_with_files_named_as_a_runs_is_not_an_earlier_run() {
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let summary = Summary::of_run(
            &scenario,
            None,
            &scenario.run(&mut isotrack_sim::NoTrace),
            &[],
        );
        let mut not_isotracks = summary.to_json().replace("isotrack_version", "version");
        assert!(Summary::from_json(&not_isotracks).is_err());
        not_isotracks.push('\n');
        for (present, summary_text, named, why) in [
            (
                vec!["scenario.toml"],
                None,
                "scenario.toml",
                "no summary.json beside it",
            ),
            (
                vec!["trace.csv"],
                None,
                "trace.csv",
                "no summary.json beside it",
            ),
            (
                vec!["scenario.toml", "trace.csv"],
                Some("{}"),
                "summary.json",
                "no `isotrack_version` key",
            ),
            (
                vec![],
                Some("{\"notes\": \"mine\"}"),
                "summary.json",
                "no `isotrack_version` key",
            ),
            (
                vec!["trace.csv"],
                Some(not_isotracks.as_str()),
                "summary.json",
                "no `isotrack_version` key",
            ),
            (
                vec![],
                Some("{\"isotrack_version\": 1, \"outcome\": \"x\", \"scenario\": {}}"),
                "summary.json",
                "its `isotrack_version` is not a string",
            ),
            (vec![], Some("[1, 2]"), "summary.json", "not a JSON object"),
            (vec![], Some("my notes"), "summary.json", "not JSON"),
        ] {
            let d = tempfile::tempdir().unwrap();
            for name in &present {
                std::fs::write(d.path().join(name), b"the user's\n").unwrap();
            }
            if let Some(text) = summary_text {
                std::fs::write(d.path().join("summary.json"), text).unwrap();
            }
            for name in RUN_OUTPUTS {
                std::fs::write(d.path().join(name), b"mine").unwrap();
            }
            let before = listing(d.path());
            let e = RunDir::open(d.path(), &[], &[], Some("run")).unwrap_err();
            assert_eq!(e.code, exit::CANTCREAT, "{}", e.message);
            let file = d.path().join(named).display().to_string();
            for part in [
                file.as_str(),
                why,
                "refusing to replace",
                "use another --out",
            ] {
                assert!(
                    e.message.contains(part),
                    "{present:?} {summary_text:?}: {part:?} not in {}",
                    e.message
                );
            }
            assert_eq!(listing(d.path()), before, "{present:?} {summary_text:?}");
        }
    }

    /// att41-13: a folder refused as holding the user's run files loses nothing first: a
    /// stale-looking `.trace.csv.NNN.tmp` (NNN no live process) and a `.isotrack.lock` of the
    /// user's (no lock record in it) are left as they were; in an earlier run's directory the
    /// stale temporary is removed as before. Fails on the source before (both files deleted
    /// before the refusal).
    #[test]
    fn a_refused_folder_loses_no_temporary_nor_lock_file() {
        let d = tempfile::tempdir().unwrap();
        // No process has pid 4194304 + 1 (above Linux's pid_max).
        let tmp = ".trace.csv.4194305.tmp";
        std::fs::write(d.path().join("trace.csv"), b"mine\n").unwrap();
        std::fs::write(d.path().join(tmp), b"my backup\n").unwrap();
        let before = listing(d.path());
        let e = RunDir::open(d.path(), &[], &[], Some("run")).unwrap_err();
        assert_eq!(e.code, exit::CANTCREAT, "{}", e.message);
        assert_eq!(listing(d.path()), before);
        std::fs::write(d.path().join(".isotrack.lock"), b"my lock notes\n").unwrap();
        let before = listing(d.path());
        let e = RunDir::open(d.path(), &[], &[], Some("run")).unwrap_err();
        assert_eq!(e.code, exit::CANTCREAT, "{}", e.message);
        assert!(e.message.contains(".isotrack.lock"), "{}", e.message);
        assert_eq!(listing(d.path()), before);
        // An earlier run's directory: its stale temporary goes.
        let d = tempfile::tempdir().unwrap();
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let summary = Summary::of_run(
            &scenario,
            None,
            &scenario.run(&mut isotrack_sim::NoTrace),
            &[],
        );
        std::fs::write(d.path().join("summary.json"), summary.to_json()).unwrap();
        std::fs::write(d.path().join(tmp), b"a killed run's\n").unwrap();
        let out = RunDir::open(d.path(), &[], &[], Some("run")).unwrap();
        assert!(!d.path().join(tmp).exists());
        drop(out);
    }

    /// The files of `dir` (hidden ones too) with their bytes, sorted.
    fn listing(dir: &Path) -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let bytes = std::fs::read(e.path()).unwrap_or_default();
                (e.file_name().to_string_lossy().into_owned(), bytes)
            })
            .collect();
        v.sort();
        v
    }

    /// att39-1, att39-4: `fly`'s `mavlink.tlog` (its `extra` file) with no summary beside it is
    /// a user's log, refused naming it; a 2 GiB `summary.json` (sparse) is refused without
    /// being read whole; a `summary.json` that is a FIFO is refused as before, not opened.
    #[cfg(unix)]
    #[test]
    fn a_users_log_a_huge_summary_and_a_fifo_are_refused() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("mavlink.tlog"), b"my own flight").unwrap();
        // `run` and `sitl` write no mavlink.tlog: a figure-named file, kept and run into.
        RunDir::open(d.path(), &[], &[], None).unwrap();
        let e = RunDir::open(d.path(), &[], &["mavlink.tlog"], Some("fly")).unwrap_err();
        assert_eq!(e.code, exit::CANTCREAT);
        let tlog = d.path().join("mavlink.tlog").display().to_string();
        assert!(
            e.message.contains(&tlog) && e.message.contains("no summary.json beside it"),
            "{}",
            e.message
        );
        assert_eq!(
            std::fs::read(d.path().join("mavlink.tlog")).unwrap(),
            b"my own flight"
        );

        let d = tempfile::tempdir().unwrap();
        let f = std::fs::File::create(d.path().join("summary.json")).unwrap();
        f.set_len(2 << 30).unwrap();
        drop(f);
        let t = std::time::Instant::now();
        let e = RunDir::open(d.path(), &[], &[], None).unwrap_err();
        assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
        assert!(e.message.contains("larger than 16 MiB"), "{}", e.message);

        let d = tempfile::tempdir().unwrap();
        let fifo = d.path().join("summary.json");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if made {
            let e = RunDir::open(d.path(), &[], &[], None).unwrap_err();
            assert!(e.message.contains("not a regular file"), "{}", e.message);
        }
    }

    /// What counts as an earlier isotrack run (att39-1): a `summary.json` any isotrack wrote,
    /// whatever its version's keys: the first version's (`d905a43`: no `warnings`, no
    /// `data_files`), a flight's (`fly`: `end_reason`, no metrics), a Python controller's
    /// (`controller`), one with keys a later isotrack adds (a team's `team`, ...); the run is
    /// replaced, the figures named as isotrack's kept. A `mavlink.tlog` is the run's (replaced
    /// by `fly --out`) only beside a flight's summary (att41-1).
    #[test]
    fn every_isotracks_summary_is_an_earlier_run() {
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let result = scenario.run(&mut isotrack_sim::NoTrace);
        let summary = Summary::of_run(&scenario, None, &result, &[]);
        // As d905a43's `write_summary` wrote it: version, path, the flattened RunResult of the
        // time, the scenario.
        let first = r#"{
  "isotrack_version": "0.1.0",
  "scenario_path": null,
  "outcome": "completed",
  "outcome_detail": null,
  "t_end_s": 60.0,
  "steps": 60000,
  "samples": 6000,
  "end_position_m": [1.0, 2.0],
  "convergence_time_s": 3.5,
  "steady_state_max_abs_error": 0.01,
  "scenario": {"sim": {"dt_s": 0.001}}
}
"#;
        let flight = r#"{"isotrack_version": "0.1.0", "scenario_path": "f.toml",
            "outcome": "failsafe", "outcome_detail": "link lost", "end_reason": "link_lost",
            "failsafe": true, "failsafe_acknowledged": false, "t_end_s": 12.5, "samples": 7,
            "commands": 3, "events": ["link lost"], "frames_in": 10, "frames_out": 11,
            "junk_datagrams": 1, "scenario": {}}"#;
        let python = summary.to_json().replacen(
            "\"isotrack_version\"",
            "\"controller\": {\"kind\": \"python\", \"class\": \"Mine\"},\n  \"isotrack_version\"",
            1,
        );
        let later = summary
            .to_json()
            .replacen("{", "{\"a_key_of_isotrack_9\": [1],", 1);
        for (what, text) in [
            ("the first version's", first.to_string()),
            ("a flight's", flight.to_string()),
            ("a Python controller's", python),
            ("a later version's", later),
            ("this version's", summary.to_json()),
        ] {
            assert_eq!(crate::summary::not_isotracks(&text), None, "{what}");
            let d = tempfile::tempdir().unwrap();
            std::fs::write(d.path().join("summary.json"), &text).unwrap();
            std::fs::write(d.path().join("trace.csv"), b"t_s\n").unwrap();
            std::fs::write(d.path().join("mavlink.tlog"), b"its log").unwrap();
            std::fs::write(d.path().join("trajectory.png"), b"its figure").unwrap();
            let flight = what == "a flight's";
            if !flight {
                // att41-1: a run writes no log; the one beside its summary is the user's, so
                // `fly --out` is refused (73, naming it), every file as it was; `run` (no
                // extra file) replaces the run and keeps the log.
                let before = listing(d.path());
                let e = RunDir::open(d.path(), &[], &["mavlink.tlog"], Some("fly")).unwrap_err();
                assert_eq!(e.code, exit::CANTCREAT, "{what}");
                let tlog = d.path().join("mavlink.tlog").display().to_string();
                for part in [tlog.as_str(), "not an isotrack flight's", "no `end_reason`"] {
                    assert!(e.message.contains(part), "{what}: {}", e.message);
                }
                assert_eq!(listing(d.path()), before, "{what}");
            }
            let extra: &[&str] = if flight { &["mavlink.tlog"] } else { &[] };
            let out = RunDir::open(d.path(), &[], extra, Some("fly"))
                .unwrap_or_else(|e| panic!("{what}: {}", e.message));
            let trace = out.trace(false).unwrap();
            out.finish(trace, "x = 1\n", &summary).unwrap();
            assert_eq!(
                std::fs::read_to_string(d.path().join("summary.json")).unwrap(),
                summary.to_json(),
                "{what}"
            );
            assert_eq!(
                std::fs::read(d.path().join("trajectory.png")).unwrap(),
                b"its figure"
            );
            if !flight {
                assert_eq!(
                    std::fs::read(d.path().join("mavlink.tlog")).unwrap(),
                    b"its log"
                );
            }
        }
    }
}
