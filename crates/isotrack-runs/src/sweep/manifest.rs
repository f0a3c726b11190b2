//! The manifest of a sweep directory: `sweep.json`, the digest that names a sweep, and the plan
//! of a shard directory checked against its digest.

use crate::failure::{exit, fail, Failure};
use isotrack_scenario::sweep::SweepPlan;
use isotrack_scenario::ScenarioFile;
use std::collections::BTreeMap;
use std::path::Path;

/// The revision of the engine that computes a sweep's rows, raised by hand whenever a change
/// gives an existing run other numbers (att32f-7's circle in a domain moved the team metrics
/// in the 6th digit): 1 is the first recorded. `sweep.json` records [`engine`]; `--resume` and
/// `merge` refuse a directory begun by another engine (att32g-8: such rows were refused as
/// "damaged", with advice that misdiagnosed them).
pub const ENGINE_REVISION: u32 = 1;

/// What `sweep.json`'s `engine` records: `isotrack VERSION engine REVISION`.
pub fn engine() -> String {
    format!(
        "isotrack {} engine {ENGINE_REVISION}",
        env!("CARGO_PKG_VERSION")
    )
}

/// Checks directory `dir`'s manifest's `engine` against this isotrack's ([`engine`]): another
/// one is refused (65) as computed by another isotrack; returns whether one is recorded (a
/// `sweep.json` from before the engine was recorded has none: its rows are checked as they
/// are, and a refused row says the engine is unknown, [`unrecorded_engine_note`]).
pub fn check_engine(dir: &Path, manifest: &serde_json::Value) -> Result<bool, Failure> {
    match manifest.get("engine") {
        None => Ok(false),
        Some(e) if e.as_str() == Some(engine().as_str()) => Ok(true),
        Some(e) => Err(fail(
            exit::DATAERR,
            format!(
                "{}: computed by another isotrack ({} in its sweep.json; this is {}): its rows' numbers are that isotrack's, and a sweep's rows must all be one isotrack's; finish it with the isotrack that began it, or run it again into a new --out",
                dir.display(),
                isotrack_scenario::load::clip(&e.as_str().map_or_else(|| e.to_string(), str::to_string)),
                engine()
            ),
        )),
    }
}

/// A row refused in directory `dir`, whose `sweep.json` records no engine ([`check_engine`]):
/// the refusal (65) says the row may be whole and computed by an older isotrack.
pub fn unrecorded_engine_note(f: Failure, dir: &Path) -> Failure {
    if f.code != exit::DATAERR || !f.message.contains("damaged row") {
        return f;
    }
    Failure {
        code: f.code,
        message: format!(
            "{}; note: {}/sweep.json records no engine (it was begun by an isotrack older than {}): a whole row computed by another isotrack, whose numbers differ, is refused so too; if so, run the sweep again into a new --out",
            f.message,
            dir.display(),
            engine()
        ),
    }
}

/// The digest that names a sweep: SHA-256 of the sweep file's bytes, of its base scenario's own
/// keys as `base_scenario.toml` holds them ([`given_toml`]), and of those keys resolved (every
/// default filled in, no file read: so a changed default or scenario file changes it too).
/// Stored in `sweep.json`; `--resume` and `merge` refuse rows made under another digest.
pub fn sweep_digest(sweep_file: &[u8], base_toml: &str) -> String {
    use sha2::{Digest, Sha256};
    let resolved = toml::from_str::<ScenarioFile>(base_toml)
        .ok()
        .and_then(|f| isotrack_scenario::resolve::resolve(f).ok())
        .and_then(|f| isotrack_scenario::tomltext::to_toml(&f).ok())
        .unwrap_or_default();
    let mut h = Sha256::new();
    h.update((sweep_file.len() as u64).to_le_bytes());
    h.update(sweep_file);
    h.update((base_toml.len() as u64).to_le_bytes());
    h.update(base_toml.as_bytes());
    h.update(resolved.as_bytes());
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// A sweep's base scenario's own keys ([`isotrack_scenario::Scenario::given`]) as TOML: what
/// `base_scenario.toml` holds, so that `isotrack run base_scenario.toml --set KEY=VALUE ...`
/// resolves a run's keys once, as the sweep does.
pub fn given_toml(given: &ScenarioFile) -> String {
    isotrack_scenario::tomltext::to_toml(given)
        .unwrap_or_else(|e| format!("# cannot render: {e}\n"))
}

/// The data files a sweep's `sweep.json` records (`data_files`: the SHA-256 of each file a run
/// of the sweep reads, [`plan_data_file_digests`], by absolute path; absent without files).
pub fn recorded_files(manifest: &serde_json::Value) -> BTreeMap<String, String> {
    manifest
        .get("data_files")
        .and_then(|d| d.as_object())
        .map(|o| {
            o.iter()
                .map(|(k, v)| (k.clone(), v.as_str().unwrap_or_default().to_string()))
                .collect()
        })
        .unwrap_or_default()
}

/// Refuses (65, naming the file) a data file whose SHA-256 in `manifest` (of the directory
/// `dir`) is not `now`'s, the files' digests against which its rows are to be kept: the rows
/// were computed on another version of the field (att30d-10: shards and resumed runs over a
/// rewritten grid file were merged into one results.csv). `against` says what `now` is.
pub fn check_data_files(
    dir: &Path,
    manifest: &serde_json::Value,
    now: &BTreeMap<String, String>,
    against: &str,
) -> Result<(), Failure> {
    let then = recorded_files(manifest);
    let shown = |d: Option<&String>| d.map_or("none".to_string(), |d| d.clone());
    for path in then.keys().chain(now.keys()) {
        let (a, b) = (then.get(path), now.get(path));
        if a != b {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: the field's data file {path} is not the one its rows were computed on (SHA-256 {} in its sweep.json, {} {against}): start a new --out, or restore the file",
                    dir.display(),
                    shown(a),
                    shown(b)
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses (65, naming the file) shard directory `dir` when a data file its `manifest`
/// records (`data_files`) holds other bytes now than its rows were computed on: `merge` of
/// shards all run before a grid file was rewritten would otherwise write their rows as this
/// sweep's over the new file. A recorded file that cannot be read now (gone, moved, not
/// readable) is refused too (66, naming it): each row is checked against its run's scenario,
/// which reads the file, so its good rows would be called damaged (att30n-14).
pub fn check_recorded_files_now(dir: &Path, manifest: &serde_json::Value) -> Result<(), Failure> {
    for (path, then) in recorded_files(manifest) {
        let now = crate::files::sha256_data_file(Path::new(&path)).map_err(|e| {
            fail(
                exit::NOINPUT,
                format!(
                    "{}: the field's data file {path}, on which its rows were computed (its sweep.json's data_files), cannot be read now: {e}; restore it there (its rows are checked against it), or run the sweep again",
                    dir.display()
                ),
            )
        })?;
        if now != then {
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: the field's data file {path} is not the one its rows were computed on (SHA-256 {then} in its sweep.json, {now} now): run the sweep again, or restore the file",
                    dir.display()
                ),
            ));
        }
    }
    Ok(())
}

/// The SHA-256 of every data file a run of `plan` reads ([`SweepPlan::data_files`], for a
/// base whose own keys are `given`), by absolute path ([`crate::files::sha256_data_file`]);
/// for a sweep whose `[grid]` chooses no files, the base's. Taken as a sweep starts: a data
/// file a run would read that cannot be read now (missing, not a regular file, unreadable,
/// beyond its size limit: checked before it is read) is refused before any run,
/// [`exit::NOINPUT`] naming it and the `[grid]` value that names it as written (nu-15: a
/// `[grid] field.path` value naming no file was found only after every other run had run,
/// each of its runs `invalid_scenario`, exit 65; att30n-9, -13). Past
/// [`isotrack_scenario::sweep::MAX_FILE_COMBINATIONS`] combinations (a superset of the
/// files), an unreadable file is refused only when a run reads it
/// ([`SweepPlan::reads_files`]; att30n-1), or, when that cannot be told, with a message that
/// says so; a file no run reads is not recorded.
pub fn plan_data_file_digests_all(
    plan: &SweepPlan,
    given: &ScenarioFile,
    label: &str,
) -> Result<BTreeMap<String, String>, Failure> {
    let superset = plan.data_files_are_a_superset();
    let mut files = BTreeMap::new();
    let mut unreadable = vec![];
    for p in plan.data_files(given) {
        match crate::files::sha256_data_file(Path::new(&p)) {
            Ok(d) => {
                files.insert(p, d);
            }
            Err(e) => {
                if !superset {
                    return Err(unreadable_data_file(plan, label, &p, &e, Some(true)));
                }
                unreadable.push((p, e));
            }
        }
    }
    let paths: Vec<String> = unreadable.iter().map(|u| u.0.clone()).collect();
    let reads = plan.reads_files(given, &paths);
    match unreadable
        .iter()
        .zip(reads)
        .find(|(_, r)| *r != Some(false))
    {
        Some(((p, e), r)) => Err(unreadable_data_file(plan, label, p, e, r)),
        None => Ok(files),
    }
}

/// The refusal (66) of data file `p` of sweep `label`'s `plan` that cannot be read (`e`),
/// naming the `[grid]` value that names it ([`SweepPlan::file_origin`]); `reads`, whether a
/// run reads it (`None`: past [`isotrack_scenario::sweep::MAX_FILE_COMBINATIONS`]
/// combinations, not told).
fn unreadable_data_file(
    plan: &SweepPlan,
    label: &str,
    p: &str,
    e: &std::io::Error,
    reads: Option<bool>,
) -> Failure {
    let who = match reads {
        None => format!(
            "which runs of the sweep may read (its [grid] values that choose the field's files make more than {} combinations: not told apart)",
            isotrack_scenario::sweep::MAX_FILE_COMBINATIONS
        ),
        Some(_) => "which runs of the sweep read".to_string(),
    };
    let message = match plan.file_origin(p) {
        Some(origin) => format!("{label}: {origin}: the data file {p}, {who}, cannot be read: {e}"),
        None => format!(
            "{label}: the data file {p}, {who} (`field.path` or `field.paths` of its scenario, [base] or [grid]), cannot be read: {e}"
        ),
    };
    fail(exit::NOINPUT, message)
}

/// The `data_files` entry of `sweep.json`: each data file's SHA-256 by path (`None` without
/// files: the manifest of a sweep over an analytic field is unchanged).
pub fn data_files_entry(files: &BTreeMap<String, String>) -> Option<serde_json::Value> {
    (!files.is_empty()).then(|| serde_json::json!(files))
}

/// Reads `DIR/sweep.json`.
pub fn read_manifest(dir: &Path) -> Result<serde_json::Value, Failure> {
    let path = dir.join("sweep.json");
    let text = isotrack_fields::io::read_text_limited(&path, MAX_MANIFEST_BYTES).map_err(|e| {
        fail(
            exit::NOINPUT,
            format!("{}: no readable sweep.json ({e})", dir.display()),
        )
    })?;
    serde_json::from_str(&text).map_err(|e| fail(exit::DATAERR, format!("{}: {e}", path.display())))
}

/// The plan of shard directory `dir`, from its `sweep.toml`, and its base scenario's own keys,
/// from its `base_scenario.toml`, after checking that both are those its `sweep.json`
/// digest names (a shard whose files were edited is refused: its rows' plan columns are checked
/// against this plan, their times and sample counts against the base's step counts).
pub fn shard_plan(dir: &Path, digest: &str) -> Result<(SweepPlan, ScenarioFile), Failure> {
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
                "{}: sweep.toml or base_scenario.toml is not the sweep its sweep.json names (digest {digest}): the shard was edited, or an older isotrack wrote it; run it again",
                dir.display()
            ),
        ));
    }
    let path = dir.join("sweep.toml");
    let text = String::from_utf8_lossy(&sweep_bytes);
    let plan = SweepPlan::parse(&text, &path).map_err(|e| fail(exit::DATAERR, e.to_string()))?;
    let base: ScenarioFile = toml::from_str(&base).map_err(|e| {
        fail(
            exit::DATAERR,
            format!(
                "{}: {}",
                dir.join("base_scenario.toml").display(),
                e.message().trim()
            ),
        )
    })?;
    Ok((plan, base))
}

/// The files `sweep` and `merge` write into a sweep directory besides `results.csv`, the
/// manifest first.
pub const SWEEP_FILES: [&str; 3] = ["sweep.json", "sweep.toml", "base_scenario.toml"];

/// The largest `sweep.json` read ([`read_manifest`]'s cap).
const MAX_MANIFEST_BYTES: u64 = 1 << 20;

/// Refuses (73, naming it, before `sweep` or `merge` writes or removes anything) a file of
/// sweep directory `dir` that no isotrack sweep wrote (att42-4: a user's `sweep.toml`,
/// `base_scenario.toml` or `sweep.json` there was replaced without a word). Isotrack's are told
/// as follows: `sweep.json` is a JSON object with the `sweep` and `scenario` strings and the
/// `total_runs` number every manifest has had; `results.csv` is empty or begins with `run_id,`
/// (every sweep's header); `sweep.toml` and `base_scenario.toml` are the sweep's beside either
/// of those (every sweep writes its manifest before them, an older isotrack's results.csv may
/// have no manifest, and a merge cut short may have its results.csv but no manifest yet).
/// Anything else of those names is the user's. A link, FIFO or directory there is refused too.
pub fn refuse_foreign_sweep_files(dir: &Path) -> Result<(), Failure> {
    use crate::owned::{empty_or_starts_with, json_object_with, refuse_foreign};
    let results = dir.join("results.csv");
    refuse_foreign(
        &results,
        |p| empty_or_starts_with(p, b"run_id,"),
        "an isotrack sweep's results",
        "its first line does not begin with `run_id,`, as every sweep's results.csv does",
    )?;
    let manifest = dir.join("sweep.json");
    refuse_foreign(
        &manifest,
        |p| json_object_with(p, MAX_MANIFEST_BYTES, &["sweep", "scenario"], &["total_runs"]),
        "an isotrack sweep's manifest",
        "not a JSON object with the `sweep`, `scenario` and `total_runs` keys every sweep.json has had",
    )?;
    let exists = |p: &Path| std::fs::symlink_metadata(p).is_ok();
    let a_sweeps = exists(&manifest) || exists(&results);
    for name in &SWEEP_FILES[1..] {
        refuse_foreign(
            &dir.join(name),
            |_| Ok(a_sweeps),
            "an isotrack sweep's",
            "no sweep.json nor results.csv beside it: no sweep's directory",
        )?;
    }
    Ok(())
}
