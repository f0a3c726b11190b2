//! `isotrack benchmark` and `isotrack report`.

use crate::cli::{BenchmarkArgs, ReportArgs};
use crate::exit;
use crate::run::Failure;
use crate::sweep::worker_pool;
use isotrack_league::leaderboard::{leaderboard_md, write_files};
use isotrack_league::{run_benchmark, BenchError, Options, Registry, Suite};
use std::path::{Path, PathBuf};

fn fail(code: u8, message: String) -> Failure {
    Failure { code, message }
}

/// The bundled standard suite, relative to the repository.
pub const STANDARD_SUITE: &str = "suites/standard-v2.toml";

/// Where the bundled standard suite is: [`STANDARD_SUITE`] under the working directory, else
/// under the repository the binary was built in (`target/<profile>/isotrack`).
fn default_suite() -> Result<PathBuf, Failure> {
    let rel = Path::new(STANDARD_SUITE);
    if rel.is_file() {
        return Ok(rel.to_path_buf());
    }
    if let Ok(exe) = std::env::current_exe() {
        for up in exe.ancestors().skip(1).take(4) {
            let p = up.join(rel);
            if p.is_file() {
                return Ok(p);
            }
        }
    }
    Err(fail(
        exit::NOINPUT,
        format!("no suite given and {STANDARD_SUITE} not found here or beside the binary: run from the isotrack repository or pass the suite file"),
    ))
}

fn bench_failure(e: BenchError) -> Failure {
    match e {
        BenchError::UnknownController(_)
        | BenchError::DuplicateController(_)
        | BenchError::TeamController { .. } => fail(exit::USAGE, e.to_string()),
        BenchError::Io { .. } => fail(exit::CANTCREAT, e.to_string()),
        // A task's scenario (or a file it names) cannot be read: missing, a FIFO, a
        // directory, a device: 66, as for `sweep`'s base scenario.
        BenchError::Task { .. } => fail(exit::NOINPUT, e.to_string()),
        _ => fail(exit::DATAERR, e.to_string()),
    }
}

/// `isotrack benchmark [SUITE] --out DIR [--controllers a,b] [--threads N] [--resume] [--tune]`.
pub fn benchmark(a: &BenchmarkArgs) -> Result<(), Failure> {
    let path = match &a.suite {
        Some(p) => p.clone(),
        None => default_suite()?,
    };
    if !path.exists() {
        return Err(fail(
            exit::NOINPUT,
            format!("{}: no such suite file", path.display()),
        ));
    }
    // The suite as run goes to DIR/suite.toml: never over the suite being read (64).
    if let Some(m) =
        crate::output::input_clash(std::slice::from_ref(&path), &a.out.join("suite.toml"))
    {
        return Err(fail(exit::USAGE, m));
    }
    // Unreadable (missing, a FIFO, a directory, too big) is 66; what it says is 65.
    let text = Suite::read(&path).map_err(|e| {
        fail(
            exit::NOINPUT,
            format!("{}: cannot read: {e}", path.display()),
        )
    })?;
    let suite = Suite::from_text(&path, &text).map_err(|e| fail(exit::DATAERR, e.to_string()))?;
    // Whose files are there first: "pass --resume" is advised only where --resume would
    // find every output a benchmark's.
    let (_created, _lock) = lock_out_dir(&a.out)?;
    refuse_foreign_outputs(&a.out, &suite)?;
    refuse_other_suite(&a.out, &suite)?;
    let registry = Registry::builtin();
    let opts = Options {
        controllers: (!a.controllers.is_empty()).then(|| a.controllers.clone()),
        tune: a.tune,
        resume_from: a.resume.then(|| a.out.clone()),
        cancel: None,
        save_to: Some(a.out.clone()),
    };
    let stored = StoredTasks::read(&a.out, &suite, &registry, &opts);
    refuse_finished_benchmark(&a.out, a.resume, Some(&stored))?;
    if a.resume {
        stored.note_replaced(&a.out);
    }
    let _said = say_tasks_on_interrupt(&a.out, stored);
    let pool = worker_pool(a.threads)?;
    let started = std::time::Instant::now();
    let progress = |i: usize, n: usize, id: &str| {
        errln!(
            "[{:>6.1} s] task {}/{n}: {id}",
            started.elapsed().as_secs_f64(),
            i + 1
        )
    };
    let result = pool
        .install(|| run_benchmark(&suite, &registry, &opts, &progress))
        .map_err(bench_failure)?;
    write_outputs(&suite, &path, &result, &a.out, a.tune)?;
    out!("{}", leaderboard_md(&result));
    errln!(
        "{} tasks in {:.1} s: {}",
        result.tasks.len(),
        started.elapsed().as_secs_f64(),
        a.out.display()
    );
    Ok(())
}

/// This suite's tasks whose results a benchmark directory holds (`tasks/ID/task.json`), and
/// what `--resume` does with them: reuses those whose digest is this run's, reruns and replaces
/// the others (att53o-3, -7: a plain run advised `--resume` "to reuse its task results" where
/// every digest differed, another controller set or a `suite.toml` gone, and `--resume` then
/// replaced every task without a word).
struct StoredTasks {
    /// Each task of the suite with this run's digest, in the suite's order; the digest `None`
    /// where it is not known before running (`--tune`, a task that cannot be built:
    /// [`isotrack_league::run::task_digests`]).
    tasks: Vec<(String, Option<String>)>,
    /// Of the tasks stored when the command began, the ids of those `--resume` reuses and of
    /// those it replaces (`None`: not known before running).
    split: Option<(Vec<String>, Vec<String>)>,
}

impl StoredTasks {
    /// What `out` holds of `suite`'s tasks for this run (`reg`, `opts`); the digests are
    /// computed (each task's scenario loaded) only when some task is stored.
    fn read(out: &Path, suite: &Suite, reg: &Registry, opts: &Options) -> Self {
        let stored: Vec<&str> = suite
            .tasks
            .iter()
            .map(|t| t.id.as_str())
            .filter(|id| isotrack_league::run::task_file(out, id).is_file())
            .collect();
        let digests = (!stored.is_empty())
            .then(|| isotrack_league::run::task_digests(suite, reg, opts))
            .flatten();
        let tasks: Vec<(String, Option<String>)> = match &digests {
            Some(d) => d
                .iter()
                .map(|(id, g)| (id.clone(), Some(g.clone())))
                .collect(),
            None => suite.tasks.iter().map(|t| (t.id.clone(), None)).collect(),
        };
        let split = digests.map(|d| {
            stored
                .iter()
                .map(|id| id.to_string())
                .partition(|id| d.iter().any(|(i, g)| i == id && is_this_runs(out, id, g)))
        });
        Self { tasks, split }
    }

    /// Says (a note on stderr) how many of the stored tasks `--resume` reuses, and which it
    /// replaces, when it replaces any.
    fn note_replaced(&self, out: &Path) {
        let Some((reused, replaced)) = &self.split else {
            return;
        };
        if replaced.is_empty() {
            return;
        }
        errln!(
            "note: --resume reuses {} of the {} tasks {} holds; the results of {} ({}) are another run's (another controller set, gains, scenario, data file, suite or isotrack) and are replaced",
            reused.len(),
            reused.len() + replaced.len(),
            isotrack_runs::owned::shell_quoted(out),
            replaced.len(),
            named_ids(replaced)
        );
    }

    /// How many of the suite's tasks `out` holds finished for this run: a stored `task.json`
    /// whose digest is this run's (any, where that is not known).
    fn finished(&self, out: &Path) -> usize {
        self.tasks
            .iter()
            .filter(|(id, digest)| match digest {
                Some(g) => is_this_runs(out, id, g),
                None => isotrack_league::run::task_file(out, id).is_file(),
            })
            .count()
    }
}

/// Whether `out/tasks/ID/task.json` holds results of digest `digest` (this run's).
fn is_this_runs(out: &Path, id: &str, digest: &str) -> bool {
    isotrack_league::run::stored_digest(out, id).as_deref() == Some(digest)
}

/// The first few of task `ids`, for a message (`a, b, c and 7 more`).
fn named_ids(ids: &[String]) -> String {
    const NAMED: usize = 3;
    let shown: Vec<String> = ids
        .iter()
        .take(NAMED)
        .map(|i| isotrack_scenario::load::clip(i))
        .collect();
    match ids.len().saturating_sub(NAMED) {
        0 => shown.join(", "),
        more => format!("{} and {more} more", shown.join(", ")),
    }
}

/// Registers the line an interrupted `benchmark --out DIR` says on exit (att48-3: it stopped
/// silently, and nothing said that `--resume` continues): how many of the suite's tasks DIR
/// holds finished for this run (`tasks/ID/task.json` of this run's digest, what `--resume`
/// reuses: att53o-7, a stored task of another controller set, to be rerun, was counted, and so
/// was any `task.json` under `tasks/`), 0 included.
fn say_tasks_on_interrupt(out: &Path, stored: StoredTasks) -> isotrack_runs::cleanup::OnInterrupt {
    let out = out.to_path_buf();
    isotrack_runs::cleanup::on_interrupt(move || {
        let n = stored.finished(&out);
        let q = isotrack_runs::owned::shell_quoted(&out);
        match n {
            // att51-4: before the first task finished it said nothing.
            0 if out.is_dir() => errln!(
                "interrupted: {q} holds 0 of the {} tasks finished",
                stored.tasks.len()
            ),
            0 => errln!("interrupted before any task finished: nothing written to {q}"),
            _ => errln!(
                "interrupted: {q} holds {n} of the {} tasks finished; the same benchmark with `--resume` continues",
                stored.tasks.len()
            ),
        }
    })
}

/// Makes benchmark output directory `out` ready: creates it, takes its operating-system lock
/// ([`crate::sweep::lock_output_dir`], held while the returned file lives: a second benchmark
/// writing the same directory fails instead of overwriting it) and refuses one that already
/// holds a benchmark unless `resume` ([`refuse_finished_benchmark`]).
pub fn open_out_dir(out: &Path, resume: bool) -> Result<crate::sweep::DirLock, Failure> {
    let (_, lock) = lock_out_dir(out)?;
    refuse_finished_benchmark(out, resume, None)?;
    Ok(lock)
}

/// Creates benchmark output directory `out` and takes its lock ([`open_out_dir`]); returned
/// with the levels of `out` it created, removed if the command is interrupted while they are
/// still empty ([`isotrack_runs::cleanup::create_dir_all`]; att51-4: `a/b/c` was left): hold
/// both to the end.
fn lock_out_dir(
    out: &Path,
) -> Result<(Vec<isotrack_runs::cleanup::Pending>, crate::sweep::DirLock), Failure> {
    let created = isotrack_runs::cleanup::create_dir_all(out)
        .map_err(|e| fail(exit::CANTCREAT, format!("{}: {e}", out.display())))?;
    // One writer per directory, as for `sweep` and `merge`: the lock is taken before the
    // directory is looked at, held to the end of the command by the caller, and released by the
    // OS however the process ends.
    Ok((created, crate::sweep::lock_output_dir(out, "benchmark")?))
}

/// Refuses (73) benchmark directory `out` when it holds an earlier benchmark's results and
/// not `resume`: one of its top-level files ([`BENCHMARK_FILES`]) or a task's
/// `tasks/ID/results.csv` or `task.json` (att46-8: a directory left with only an earlier
/// benchmark's `tasks/`, its top-level files moved away, had its task results replaced
/// without a word). The file found is named; each is checked to be a benchmark's first (one
/// no benchmark wrote is refused as the user's: own42, "pass --resume" was advised for the
/// user's own file, which `--resume` refuses too). "pass --resume" is advised only where every
/// file there is one a benchmark writes (README "Whose file an output replaces"): a file of
/// another name beside the benchmark's (hidden ones, the lock and temporaries, aside) is
/// named instead; and only where `--resume` would reuse a stored task (`stored`, when known:
/// att53o-3, -7): where it would reuse none, the refusal says so and how to keep them.
/// `benchmark` calls it after [`refuse_foreign_outputs`].
fn refuse_finished_benchmark(
    out: &Path,
    resume: bool,
    stored: Option<&StoredTasks>,
) -> Result<(), Failure> {
    if resume {
        return Ok(());
    }
    let (found, other) = benchmark_entries(out);
    let Some((file, _)) = found.first() else {
        return Ok(());
    };
    for (p, start) in &found {
        refuse_foreign_benchmark_file(p, start)?;
    }
    // att49-9: the directory quoted as the file is (a name with a space or a line break).
    let quoted = isotrack_runs::owned::shell_quoted;
    if let Some(o) = other.first() {
        return Err(fail(
            exit::CANTCREAT,
            format!(
                "{} already holds a benchmark ({}) and {}, which no benchmark writes: move it away or choose another --out",
                quoted(out),
                quoted(file),
                quoted(o)
            ),
        ));
    }
    if let Some((reused, replaced)) = stored.and_then(|s| s.split.as_ref()) {
        if reused.is_empty() && !replaced.is_empty() {
            return Err(fail(
                exit::CANTCREAT,
                format!(
                    "{} already holds a benchmark ({}) whose {} stored tasks are another run's (another controller set, gains, scenario, data file, suite or isotrack): --resume would reuse none of them and replace them all; choose another --out to keep them, or move them away",
                    quoted(out),
                    quoted(file),
                    replaced.len()
                ),
            ));
        }
        if !replaced.is_empty() {
            return Err(fail(
                exit::CANTCREAT,
                format!(
                    "{} already holds a benchmark ({}): pass --resume to reuse {} of its {} stored tasks (the results of {} are another run's and would be replaced), or choose another --out",
                    quoted(out),
                    quoted(file),
                    reused.len(),
                    reused.len() + replaced.len(),
                    named_ids(replaced)
                ),
            ));
        }
    }
    Err(fail(
        exit::CANTCREAT,
        format!(
            "{} already holds a benchmark ({}): pass --resume to reuse its task results, or choose another --out",
            quoted(out),
            quoted(file)
        ),
    ))
}

/// Refuses (73, with or without `--resume`) benchmark directory `out` whose `suite.toml` (the
/// suite as an earlier benchmark ran it) names another suite than `suite` (its `name` or
/// `version`): `--resume` would reuse none of its tasks and replace them all, and a plain run
/// was advised `--resume` for it (att49-7: a standard-v2 benchmark's directory, run with
/// standard-v1 and `--resume` as advised, lost every v2 result without a word). A `suite.toml`
/// that cannot be read as a suite's `name` and `version` is left to the other checks.
fn refuse_other_suite(out: &Path, suite: &Suite) -> Result<(), Failure> {
    let path = out.join("suite.toml");
    let Ok(text) = Suite::read(&path) else {
        return Ok(());
    };
    let Ok(table) = text.parse::<toml::Table>() else {
        return Ok(());
    };
    let (Some(name), Some(version)) = (
        table.get("name").and_then(toml::Value::as_str),
        table.get("version").and_then(toml::Value::as_integer),
    ) else {
        return Ok(());
    };
    if name == suite.name && version == i64::from(suite.version) {
        return Ok(());
    }
    let quoted = isotrack_runs::owned::shell_quoted;
    Err(fail(
        exit::CANTCREAT,
        format!(
            "{} holds a benchmark of another suite ({}: `{}` version {}; this one is `{}` version {}): --resume would reuse none of its tasks and replace them all; choose another --out, or move it away",
            quoted(out),
            quoted(&path),
            isotrack_scenario::load::clip(name),
            version,
            isotrack_scenario::load::clip(&suite.name),
            suite.version
        ),
    ))
}

/// What benchmark directory `out` holds, in name order: the files a benchmark writes
/// ([`BENCHMARK_FILES`], then `tasks/ID/results.csv` and `tasks/ID/task.json`), each with the
/// start every benchmark's has (`""` for a `task.json`: any start), and the entries no
/// benchmark writes (any other name at the top, in `tasks/` or in a `tasks/ID/`; hidden
/// names, the lock and the writers' temporaries, aside).
fn benchmark_entries(out: &Path) -> (Vec<(PathBuf, &'static str)>, Vec<PathBuf>) {
    let (mut found, mut other) = (Vec::new(), Vec::new());
    let names = |d: &Path| -> Vec<(String, PathBuf)> {
        let mut v: Vec<(String, PathBuf)> = std::fs::read_dir(d)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| (e.file_name().to_string_lossy().into_owned(), e.path()))
            .filter(|(n, _)| !n.starts_with('.'))
            .collect();
        v.sort();
        v
    };
    for (name, path) in names(out) {
        match BENCHMARK_FILES.iter().find(|(n, _)| *n == name) {
            Some((_, start)) => found.push((path, *start)),
            None if name == "tasks" && path.is_dir() => {}
            None => other.push(path),
        }
    }
    for (_, task) in names(&out.join("tasks")) {
        if !task.is_dir() {
            other.push(task);
            continue;
        }
        for (name, path) in names(&task) {
            match name.as_str() {
                "results.csv" => found.push((path, TASK_RESULTS_START)),
                "task.json" => found.push((path, "")),
                _ => other.push(path),
            }
        }
    }
    (found, other)
}

/// The start of every file a benchmark writes into its directory, as every isotrack has
/// written it since the command came: a file of one of these names that does not begin so
/// (nor is empty) is the user's.
const BENCHMARK_FILES: [(&str, &str); 4] = [
    ("leaderboard.csv", "rank,controller,overall"),
    ("leaderboard.md", "| rank | controller | overall |"),
    (
        "index.html",
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" content=\"isotrack ",
    ),
    ("suite.toml", "# The suite as run by isotrack "),
];

/// The start of each task's `tasks/ID/results.csv`, as [`BENCHMARK_FILES`].
const TASK_RESULTS_START: &str = "controller,seed,";

/// The largest `tasks/ID/task.json` read (as `--resume` reads it).
const MAX_TASK_JSON_BYTES: u64 = 64 << 20;

/// Refuses (73, naming it) a file of benchmark directory `out` that `suite`'s benchmark would
/// replace and that no benchmark wrote (att42-6: a user's `index.html`, `leaderboard.md` or
/// `suite.toml` was replaced, and a link or FIFO there refused only once every task had
/// run): every output name is checked before any task runs, each told by its first bytes
/// ([`BENCHMARK_FILES`], [`TASK_RESULTS_START`]), a `tasks/ID/task.json` as a JSON object with
/// the `id`, `title` and `digest` strings every one has had (its keys in any order: an
/// edited one is `--resume`'s to judge); an older benchmark's are replaced as before. A
/// `tasks/ID` that is not a directory is refused too. Call it holding the directory's lock
/// ([`open_out_dir`]).
pub fn refuse_foreign_outputs(out: &Path, suite: &Suite) -> Result<(), Failure> {
    use isotrack_runs::owned::{json_object_with, refuse_foreign, shell_quoted};
    for (name, start) in BENCHMARK_FILES {
        refuse_foreign_benchmark_file(&out.join(name), start)?;
    }
    for task in &suite.tasks {
        let dir = out.join("tasks").join(&task.id);
        for d in [out.join("tasks"), dir.clone()] {
            if std::fs::symlink_metadata(&d).is_ok_and(|m| !m.is_dir()) {
                return Err(fail(
                    exit::CANTCREAT,
                    format!(
                        "{} is not a directory: the benchmark writes its tasks' results there; move it away or use another --out",
                        shell_quoted(&d)
                    ),
                ));
            }
        }
        refuse_foreign_benchmark_file(&dir.join("results.csv"), TASK_RESULTS_START)?;
        refuse_foreign(
            &dir.join("task.json"),
            |p| json_object_with(p, MAX_TASK_JSON_BYTES, &["id", "title", "digest"], &[]),
            "an isotrack benchmark's",
            "not a JSON object with the `id`, `title` and `digest` every task.json has had",
        )?;
    }
    Ok(())
}

/// Refuses (73) a file `p` of a benchmark's directory that is not empty and does not begin
/// with `start`, as every benchmark's has ([`BENCHMARK_FILES`], [`TASK_RESULTS_START`]).
fn refuse_foreign_benchmark_file(p: &Path, start: &str) -> Result<(), Failure> {
    use isotrack_runs::owned::{empty_or_starts_with, refuse_foreign};
    refuse_foreign(
        p,
        |p| empty_or_starts_with(p, start.as_bytes()),
        "an isotrack benchmark's",
        &format!(
            "it does not begin with `{}`, as every benchmark's does",
            start.lines().last().unwrap_or_default()
        ),
    )
}

/// Writes a finished benchmark into `out`: its tasks, then the leaderboard files, `index.html`
/// and `suite.toml` (the suite `path` as run, with the gains each task's scores used; `tune`:
/// they were tuned afresh) put in place together, as one step an interrupt never cuts
/// ([`write_files`]; att53o-9).
pub fn write_outputs(
    suite: &Suite,
    path: &Path,
    result: &isotrack_league::BenchResult,
    out: &Path,
    tune: bool,
) -> Result<(), Failure> {
    // The suite as run: the gains every built-in law ran with recorded per task.
    let mut as_run = suite.clone();
    for (task, res) in as_run.tasks.iter_mut().zip(&result.tasks) {
        task.tuned = res.gains.clone();
        // Absolute, so that DIR/suite.toml runs from where it is.
        let abs =
            std::path::absolute(suite.scenario_path(task)).unwrap_or(suite.scenario_path(task));
        task.scenario = abs.display().to_string();
    }
    // A built-in law run beyond the suite's own (`--controllers`) is one the suite as run
    // scores: its gains are recorded, so it is listed (a suite refuses gains for a law it
    // does not score).
    let run_laws: Vec<String> = result
        .tasks
        .iter()
        .flat_map(|t| t.gains.keys().cloned())
        .collect();
    for law in run_laws {
        if !as_run.controllers.contains(&law) {
            as_run.controllers.push(law);
        }
    }
    let header = format!(
        "The suite as run by isotrack {} ({}): the tuned gains of each task are the ones its\nscores used{}.",
        env!("CARGO_PKG_VERSION"),
        path.display(),
        if tune { ", tuned afresh on the tuning seeds (--tune)" } else { "" }
    );
    let more = [
        ("index.html", isotrack_league::benchmark_page(result)),
        ("suite.toml", as_run.to_toml(&header)),
    ];
    write_files(result, out, &more).map_err(bench_failure)
}

/// `isotrack report RUN_DIR... --out report.html`.
pub fn report(a: &ReportArgs) -> Result<(), Failure> {
    let dirs: Vec<&Path> = a.runs.iter().map(|p| p.as_path()).collect();
    let (html, notes) = isotrack_html::report_page_with_notes(&dirs).map_err(|e| match e {
        isotrack_html::ReportError::Input(m) => fail(exit::NOINPUT, m),
        isotrack_html::ReportError::Data(m) => fail(exit::DATAERR, m),
    })?;
    for n in notes {
        errln!("warning: {n}");
    }
    // The page never replaces a file it was made from (64): the run directories' files.
    let inputs: Vec<std::path::PathBuf> = a
        .runs
        .iter()
        .flat_map(|d| ["trace.csv", "summary.json", "scenario.toml"].map(|f| d.join(f)))
        .collect();
    if let Some(m) = crate::output::input_clash(&inputs, &a.out) {
        return Err(fail(exit::USAGE, m));
    }
    if let Some(parent) = a.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|e| fail(exit::CANTCREAT, format!("{}: {e}", parent.display())))?;
    }
    // Not into a FIFO nor through a link (73 at once): written atomically beside it.
    isotrack_runs::files::write_atomic(&a.out, html.as_bytes())
        .map_err(|e| fail(exit::CANTCREAT, format!("{}: {e}", a.out.display())))?;
    errln!("wrote {}", a.out.display());
    Ok(())
}
