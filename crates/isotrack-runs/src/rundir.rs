//! Writing a run directory: `trace.csv`, `summary.json` and the resolved `scenario.toml`, the
//! one way every command writes one (`run --out`, `compare --out`'s per-law directories,
//! `figures --runs`, `sitl --out`, `fly --out`, the Python package's `Run.save`).
//!
//! [`RunDir::open`] readies the directory (no output over an input, not a folder holding an
//! input, created, locked when the command locks it, no output an existing link, FIFO or
//! device) and changes nothing in it: an earlier run there stands until the new one has
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
/// replacing the directory removes them with the old summary (nu-21: an earlier run's figures
/// were left beside the new trace, read as this run's); files of any other name are the user's
/// and are never touched.
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
        dir.display(),
        input.display()
    ))
}

/// The largest `summary.json` read to tell whether a directory holds an earlier run (a run's
/// is a few kB; a team's, one object per vehicle, well under this).
const SUMMARY_MAX_BYTES: u64 = 64 << 20;

/// Whether `dir` holds an earlier isotrack run: its `summary.json` a regular file that reads
/// as isotrack's own summary ([`Summary::from_json`]: its keys, `isotrack_version`, the
/// resolved `scenario`, the outcome). A file merely named `scenario.toml`, `trace.csv` or
/// `summary.json` (a user's project folder, att36-1) is not a run: the files there named as
/// isotrack's figures are the user's and are never removed.
fn holds_a_run(dir: &Path) -> bool {
    let p = dir.join("summary.json");
    let Ok(m) = std::fs::symlink_metadata(&p) else {
        return false;
    };
    if !m.is_file() || m.len() > SUMMARY_MAX_BYTES {
        return false;
    }
    std::fs::read_to_string(&p).is_ok_and(|text| Summary::from_json(&text).is_ok())
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
    /// Whether [`RunDir::open`] created the directory (removed again by
    /// [`RunDir::release_unused`] when nothing was written).
    created: bool,
    /// The command's own files besides [`RUN_FILES`] (`fly`'s `mavlink.tlog`), never removed
    /// as an earlier run's output.
    extra: Vec<String>,
    /// Whether the directory held an earlier run when opened (its `summary.json` isotrack's
    /// own, [`holds_a_run`]): only then are [`RUN_OUTPUTS`] an earlier run's, removed when it
    /// is replaced; in a directory that held no run (a user's folder that merely has a file
    /// named `scenario.toml`, `trace.csv` or `summary.json`), a `trajectory.png` is the user's
    /// and stays.
    earlier_run: bool,
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
    /// files an existing link, FIFO, directory or device (exit 73). Nothing in it is changed
    /// yet: an earlier run's files stand until [`RunDir::finish`] or [`RunDir::live_trace`].
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
                message: format!("cannot write run directory {}: {why}", dir.display()),
            });
        }
        if let Some(message) = holds_an_input(dir, inputs) {
            return Err(Failure {
                code: exit::CANTCREAT,
                message,
            });
        }
        let created = std::fs::symlink_metadata(dir).is_err();
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
        let earlier_run = holds_a_run(dir);
        Ok(RunDir {
            dir: dir.to_path_buf(),
            lock,
            created,
            extra: extra.iter().map(|e| e.to_string()).collect(),
            earlier_run,
        })
    }

    /// Lets go of a directory nothing was written to (a flight that never started): the lock
    /// released, and the directory removed again if [`RunDir::open`] created it and it is
    /// empty. An earlier run's files are left as they were.
    pub fn release_unused(self) {
        let RunDir {
            dir, lock, created, ..
        } = self;
        drop(lock);
        if created {
            let _ = std::fs::remove_dir(&dir);
        }
    }

    /// Removes the old `summary.json` (the directory's earlier run is being replaced), then,
    /// if the directory held an earlier run when opened, that run's other outputs
    /// ([`RUN_OUTPUTS`] but the command's own `extra`): a
    /// regular file or a link of that name is removed (a link itself, never what it points
    /// to); anything else there (a directory the user made) is left.
    fn remove_old_summary(&self) -> Result<(), Failure> {
        let summary = self.path("summary.json");
        match std::fs::remove_file(&summary) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(cant(&summary, e)),
            _ => {}
        }
        for name in RUN_OUTPUTS {
            if !self.earlier_run || self.extra.iter().any(|e| e == name) {
                continue;
            }
            let p = self.path(name);
            let Ok(m) = std::fs::symlink_metadata(&p) else {
                continue;
            };
            if m.is_dir() {
                continue;
            }
            match std::fs::remove_file(&p) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(cant(&p, e)),
                _ => {}
            }
        }
        Ok(())
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
        let _ = writer.finish();
        if let Some(tmp) = &tmp {
            let _ = std::fs::rename(tmp, self.path("trace.csv"));
        }
        self.remove_old_summary()?;
        let resolved = self.path("scenario.toml");
        write_atomic(&resolved, scenario_toml.as_bytes()).map_err(|e| cant(&resolved, e))?;
        let p = self.path("summary.json");
        write_atomic(&p, summary.to_json().as_bytes()).map_err(|e| cant(&p, e))
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

    fn finish_text(
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
        let resolved = self.path("scenario.toml");
        write_atomic(&resolved, scenario_toml.as_bytes()).map_err(|e| cant(&resolved, e))?;
        let p = self.path("summary.json");
        write_atomic(&p, summary.as_bytes()).map_err(|e| cant(&p, e))
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

    /// nu-21: a new run over an earlier run's directory removes that run's figures
    /// (`trajectory`, `timeseries`, `team` in PNG and SVG, `animation.gif`) and `fly`'s
    /// `mavlink.tlog`, keeps every file of another name, and a command's own extra file
    /// (`fly`'s tlog) is not removed; in a directory that held no run, nothing but the run's
    /// own files is touched.
    #[test]
    fn a_new_run_removes_the_earlier_runs_figures_and_nothing_else() {
        let d = tempfile::tempdir().unwrap();
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let summary = Summary::of_run(
            &scenario,
            None,
            &scenario.run(&mut isotrack_sim::NoTrace),
            &[],
        );
        let kept = ["notes.txt", "team.jpg", "my.png", "trajectory.png.bak"];
        let old = [
            "trajectory.png",
            "trajectory.svg",
            "timeseries.png",
            "timeseries.svg",
            "team.png",
            "team.svg",
            "animation.gif",
            "mavlink.tlog",
        ];
        // A directory that held no run: a file named as a figure is the user's, kept.
        let user = tempfile::tempdir().unwrap();
        std::fs::write(user.path().join("trajectory.png"), b"mine").unwrap();
        let out = RunDir::open(user.path(), &[], &[], None).unwrap();
        let trace = out.trace(false).unwrap();
        out.finish(trace, "x = 1\n", &summary).unwrap();
        assert_eq!(
            std::fs::read(user.path().join("trajectory.png")).unwrap(),
            b"mine"
        );
        // An earlier run (its summary.json there, isotrack's own): its figures go.
        std::fs::write(d.path().join("summary.json"), summary.to_json()).unwrap();
        for name in kept.iter().chain(old.iter()) {
            std::fs::write(d.path().join(name), b"old").unwrap();
        }
        let out = RunDir::open(d.path(), &[], &[], None).unwrap();
        let trace = out.trace(false).unwrap();
        out.finish(trace, "x = 1\n", &summary).unwrap();
        for name in old {
            assert!(!d.path().join(name).exists(), "{name} left");
        }
        for name in kept {
            assert_eq!(
                std::fs::read(d.path().join(name)).unwrap(),
                b"old",
                "{name}"
            );
        }
        // A command's own extra file stays (fly writes its tlog before the first trace row).
        std::fs::write(d.path().join("mavlink.tlog"), b"new").unwrap();
        std::fs::write(d.path().join("team.png"), b"old").unwrap();
        let out = RunDir::open(d.path(), &[], &["mavlink.tlog"], None).unwrap();
        let trace = out.live_trace(false).unwrap();
        out.finish(trace, "x = 1\n", &summary).unwrap();
        assert_eq!(
            std::fs::read(d.path().join("mavlink.tlog")).unwrap(),
            b"new"
        );
        assert!(!d.path().join("team.png").exists());
    }

    /// att36-1: a folder that never held an isotrack run but has files named `scenario.toml`,
    /// `trace.csv` and `summary.json` (a user's project folder, a JSON file of its own keys) is
    /// not an earlier run: a new run writes its own three files there and removes none of the
    /// user's files named as isotrack's figures; `summary.json` must read as isotrack's own
    /// summary, so a bare `{}` or one missing `isotrack_version` does not make a run either.
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
        for (present, summary_text) in [
            (vec!["scenario.toml"], None),
            (vec!["trace.csv"], None),
            (vec!["scenario.toml", "trace.csv"], Some("{}")),
            (vec![], Some("{\"notes\": \"mine\"}")),
            (vec!["trace.csv"], Some(not_isotracks.as_str())),
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
            let out = RunDir::open(d.path(), &[], &[], None).unwrap();
            let trace = out.trace(false).unwrap();
            out.finish(trace, "x = 1\n", &summary).unwrap();
            for name in RUN_OUTPUTS {
                assert_eq!(
                    std::fs::read(d.path().join(name)).ok().as_deref(),
                    Some(&b"mine"[..]),
                    "{name} of a folder holding {present:?} and summary {summary_text:?}"
                );
            }
            assert_eq!(
                std::fs::read_to_string(d.path().join("summary.json")).unwrap(),
                summary.to_json()
            );
        }
    }
}
