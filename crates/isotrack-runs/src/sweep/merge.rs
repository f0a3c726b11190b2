//! Shards of one sweep merged into one directory (`isotrack merge`).

use crate::failure::{exit, fail, Failure};
use crate::files::same_file;
use crate::sweep::check::RunSpans;
use crate::sweep::index::{index_results, read_header, sort_rows, write_sorted_temp, RowRef};
use crate::sweep::lock::{check_not_being_written, lock_output_dir};
use crate::sweep::manifest::{
    check_data_files, check_engine, check_recorded_files_now, engine, read_manifest,
    recorded_files, shard_plan, unrecorded_engine_note,
};
use crate::sweep::rows::{csv_line, results_header};
use serde_json::json;
use std::path::{Path, PathBuf};

/// The shards read so far: the first one's run count, digest and manifest, the header, every
/// row and the files they are in.
#[derive(Default)]
struct Shards {
    first: Option<(u64, String, serde_json::Value)>,
    header: Option<String>,
    rows: Vec<RowRef>,
    sources: Vec<PathBuf>,
    /// Whether a shard's `sweep.json` records no engine ([`check_engine`]).
    unrecorded_engine: bool,
    /// The first shard whose `sweep.json` records no engine, and the first that records this
    /// one (att38-5: both at once are the rows of two isotracks, merged silently before).
    engines: [Option<PathBuf>; 2],
}

/// Merges the shard directories `dirs` of one sweep (same digest) into `out`: refuses missing,
/// duplicate or damaged rows, a shard a command still writes, and an `out` holding another
/// sweep's results unless `force`. Returns the number of runs merged. Each level of `out` it
/// creates is removed again, when still empty, if the merge is interrupted
/// ([`crate::cleanup::create_dir_all`]), and the merged table goes in place with its manifest
/// in one step an interrupt never cuts ([`crate::cleanup::whole`]; att51-6: Ctrl-C left a
/// `results.csv` without `sweep.json`, which `sweep --resume` then called an older isotrack's).
pub fn merge(dirs: &[PathBuf], out: &Path, force: bool) -> Result<u64, Failure> {
    let out_results = out.join("results.csv");
    for d in dirs {
        if same_file(&d.join("results.csv"), &out_results) {
            return Err(fail(
                exit::USAGE,
                format!("--out {} is one of the inputs", out.display()),
            ));
        }
    }
    if out_results.exists() && !force {
        return Err(fail(
            exit::CANTCREAT,
            format!(
                "{} exists: pass --force to replace it, or another --out",
                crate::owned::shell_quoted(&out_results)
            ),
        ));
    }
    let cant = cant_write(out);
    let _created = crate::cleanup::create_dir_all(out).map_err(cant)?;
    let _lock = lock_output_dir(out, "merge")?;
    // Whose files are there (att42-4: a user's sweep.toml, base_scenario.toml or sweep.json
    // was replaced), before any is written.
    crate::sweep::manifest::refuse_foreign_sweep_files(out)?;
    let mut shards = Shards::default();
    for d in dirs {
        read_shard(&mut shards, d, dirs)?;
    }
    let mut dupes: Vec<u64> = sort_rows(&mut shards.rows).iter().map(|r| r.id).collect();
    dupes.dedup();
    let (total, _, manifest) = shards.first.take().unwrap_or((0, String::new(), json!({})));
    check_complete(&shards.rows, &dupes, total)?;
    let files = merged_manifest(dirs, out, manifest, total, !shards.unrecorded_engine)?;
    // The table written into its temporary (removed if interrupted), then put in place after
    // its manifest: an earlier table removed first, so that no results.csv is ever beside a
    // manifest not its own, even if the process is killed (SIGKILL) between two renames.
    let table = write_sorted_temp(
        &out_results,
        shards.header.as_deref().unwrap_or(""),
        &shards.rows,
        &shards.sources,
    )?;
    crate::cleanup::whole(|| {
        match std::fs::remove_file(&out_results) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(cant(e)),
            _ => {}
        }
        for (path, bytes) in &files {
            crate::files::write_atomic(path, bytes).map_err(cant)?;
        }
        table.put_in_place()
    })?;
    Ok(total)
}

/// Notes whether shard `d` records this engine (`engine_known`) or none; refuses (65) a merge
/// holding both (att38-5: the rows of two isotracks were merged silently, the stamp dropped).
fn refuse_engines_mixed(shards: &mut Shards, d: &Path, engine_known: bool) -> Result<(), Failure> {
    shards.engines[usize::from(engine_known)].get_or_insert_with(|| d.to_path_buf());
    if let [Some(old), Some(new)] = &shards.engines {
        return Err(fail(
            exit::DATAERR,
            format!(
                "{}: computed by another isotrack than {} (its sweep.json records no engine: it was begun by an isotrack older than {}, which {} records): a sweep's rows must all be one isotrack's; run that shard again with this isotrack",
                old.display(),
                new.display(),
                engine(),
                new.display()
            ),
        ));
    }
    Ok(())
}

/// Reads shard directory `d` into `shards`: refused while being written, without a manifest
/// or digest, edited since, from another sweep than the first shard, or with other columns.
fn read_shard(shards: &mut Shards, d: &Path, dirs: &[PathBuf]) -> Result<(), Failure> {
    check_not_being_written(d)?;
    let m = read_manifest(d)?;
    let (t, digest) = manifest_identity(d, &m)?;
    let engine_known = check_engine(d, &m)?;
    shards.unrecorded_engine |= !engine_known;
    refuse_engines_mixed(shards, d, engine_known)?;
    let (mut plan, base) = shard_plan(d, &digest)?;
    // A relative file path in the sweep's `[grid]` or `[base]` names a file beside the sweep
    // file, not beside the shard's copy of it: the runs are resolved from the sweep file's
    // directory while that file is still there (fix30k: a sweep over `field.path = ["a.csv",
    // ...]` refused its own shards' rows, every run "invalid" for want of `SHARD/a.csv`).
    if let Some(sweep) = m["sweep"].as_str().map(Path::new).filter(|p| p.is_file()) {
        plan.dir = sweep.parent().unwrap_or(Path::new(".")).to_path_buf();
    }
    check_recorded_files_now(d, &m)?;
    // The rows are also checked against each run's own scenario (its warnings, team bounds,
    // validity and reason) when the shard's base builds here (its field's files readable).
    let built = isotrack_scenario::Scenario::from_file(base.clone(), d).ok();
    let name = m["sweep"].as_str().unwrap_or_default().to_string();
    let spans = RunSpans::new(&plan, &base);
    let spans = match &built {
        Some(b) => spans.with_scenario(b, &name),
        None => spans,
    };
    // The columns this sweep writes: the manifest's (`columns`, where recorded) and the
    // file's header must be exactly them, as `sweep --resume` checks (a renamed or swapped
    // column would mislabel every value; a BOM, CRLF or control character is no header
    // isotrack writes).
    let expected = results_header(&plan, base.team.is_some());
    check_manifest_columns(d, &m, &expected)?;
    let (k, n) = manifest_shard(d, &m)?;
    check_same_sweep(shards, d, dirs, t, digest, m)?;
    let path = d.join("results.csv");
    check_header_columns(&path, &expected)?;
    let idx = index_results(&path, shards.sources.len(), false, t, &plan, &spans).map_err(|e| {
        if engine_known {
            e
        } else {
            unrecorded_engine_note(e, d)
        }
    })?;
    check_rows_in_shard(&path, &idx.rows, k, n)?;
    if shards.header.as_ref().is_some_and(|x| *x != idx.header) {
        return Err(fail(
            exit::DATAERR,
            format!("{}: different columns", d.display()),
        ));
    }
    shards.header = Some(idx.header);
    shards.rows.extend(idx.rows);
    shards.sources.push(path);
    Ok(())
}

/// The columns shard `d`'s manifest `m` records (`columns`, where recorded) must be this
/// sweep's, `expected`.
fn check_manifest_columns(
    d: &Path,
    m: &serde_json::Value,
    expected: &[String],
) -> Result<(), Failure> {
    if m.get("columns").is_some_and(|c| *c != json!(expected)) {
        return Err(fail(
            exit::DATAERR,
            format!(
                "{}/sweep.json: its columns differ from this sweep's",
                d.display()
            ),
        ));
    }
    Ok(())
}

/// The header of the shard's table at `path` (when it has one) must be exactly the one
/// isotrack writes for this sweep's columns, `expected`.
fn check_header_columns(path: &Path, expected: &[String]) -> Result<(), Failure> {
    let header = read_header(path)?;
    if !header.is_empty() && header != csv_line(expected) {
        return Err(fail(
            exit::DATAERR,
            format!(
                "{}: its columns differ from this sweep's (the header must be exactly the one isotrack writes: {})",
                path.display(),
                isotrack_scenario::load::clip(expected.join(",").as_str())
            ),
        ));
    }
    Ok(())
}

/// Every row of the shard's table at `path` must be of shard `k`/`n` that its manifest names
/// (`id % n == k - 1`, [`manifest_shard`]).
fn check_rows_in_shard(path: &Path, rows: &[RowRef], k: u64, n: u64) -> Result<(), Failure> {
    if let Some(r) = rows.iter().find(|r| r.id % n != k - 1) {
        return Err(fail(
            exit::DATAERR,
            format!(
                "{}:{}: run {} is not in shard {k}/{n} that its sweep.json names",
                path.display(),
                r.line,
                r.id
            ),
        ));
    }
    Ok(())
}

/// Which sweep shard `d`'s manifest `m` is of: its run count (`total_runs`) and its `digest`
/// (of the sweep file, base scenario and seed; a manifest without one was made by an older
/// isotrack and is refused).
fn manifest_identity(d: &Path, m: &serde_json::Value) -> Result<(u64, String), Failure> {
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
    Ok((t, digest))
}

/// The manifest's shard `[k, n]` (1 <= k <= n, as `--shard` takes): every row of the shard
/// must be in it (`id % n == k - 1`), a shard holding another's rows is damaged.
fn manifest_shard(d: &Path, m: &serde_json::Value) -> Result<(u64, u64), Failure> {
    let shard = m
        .get("shard")
        .and_then(|s| s.as_array())
        .and_then(|a| match a.as_slice() {
            [k, n] => Some((k.as_u64()?, n.as_u64()?)),
            _ => None,
        });
    shard.filter(|&(k, n)| (1..=n).contains(&k)).ok_or_else(|| {
        fail(
            exit::DATAERR,
            format!(
                "{}/sweep.json: shard must be [k, n] with 1 <= k <= n",
                d.display()
            ),
        )
    })
}

/// Shard `d` (`t` runs, `digest`, manifest `m`) is of the same sweep as the first shard read,
/// over the same data files; the first shard is recorded as the one the others are held to.
fn check_same_sweep(
    shards: &mut Shards,
    d: &Path,
    dirs: &[PathBuf],
    t: u64,
    digest: String,
    m: serde_json::Value,
) -> Result<(), Failure> {
    match &shards.first {
        Some((t0, d0, _)) if *t0 != t || *d0 != digest => Err(fail(
            exit::DATAERR,
            format!(
                "{}: a different sweep from {} (sweep file, base scenario or seed differ: digest {digest} vs {d0})",
                d.display(),
                dirs[0].display()
            ),
        )),
        Some((_, _, m0)) => {
            check_same_names(d, &m, &dirs[0], m0)?;
            let first = recorded_files(m0);
            let against = format!("in {}'s", dirs[0].display());
            check_data_files(d, &m, &first, &against)
        }
        None => {
            shards.first = Some((t, digest, m));
            Ok(())
        }
    }
}

/// The keys of a shard's `sweep.json` that name its sweep file and base scenario, copied into
/// the merged manifest from the first shard: every shard must name the same files.
const NAMING_KEYS: [&str; 2] = ["sweep", "scenario"];

/// Refuses (65, naming the file and the key) shard `d` whose manifest `m` names another sweep
/// file or base scenario ([`NAMING_KEYS`]) than the first shard's (`first`, manifest `m0`): two
/// paths that differ as text and do not name one file (att53o-10: an edited `scenario` or
/// `sweep` was copied into the merged manifest without a check, which then named another
/// scenario for every row). The digest, which every shard must share, covers the sweep file's
/// and the base scenario's contents, not these names; so a name typed another way (`s.toml`,
/// `./s.toml`, `/abs/s.toml`: relative to where each shard ran, unknown here) or a copy of the
/// file of the same name is the same file (att55o-4: honest shards started as `sw1.toml` and
/// `./sw1.toml` were refused when merged from another directory).
fn check_same_names(
    d: &Path,
    m: &serde_json::Value,
    first: &Path,
    m0: &serde_json::Value,
) -> Result<(), Failure> {
    for key in NAMING_KEYS {
        let (here, there) = (m.get(key), m0.get(key));
        let same = match (
            here.and_then(serde_json::Value::as_str),
            there.and_then(serde_json::Value::as_str),
        ) {
            (Some(a), Some(b)) => {
                let (a, b) = (Path::new(a), Path::new(b));
                a == b || same_file(a, b) || a.file_name() == b.file_name()
            }
            _ => here == there,
        };
        if !same {
            let shown = |v: Option<&serde_json::Value>| {
                v.map_or("none".to_string(), |v| {
                    isotrack_scenario::load::clip(&v.to_string())
                })
            };
            return Err(fail(
                exit::DATAERR,
                format!(
                    "{}: `{key}` is {} where {} has {}: the shards of one sweep name the same files (edited since?); run that shard again, or restore its sweep.json",
                    crate::owned::shell_quoted(&d.join("sweep.json")),
                    shown(here),
                    crate::owned::shell_quoted(&first.join("sweep.json")),
                    shown(there)
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses runs that appear more than once (`dupes`) or are missing from the sorted `rows` of
/// a sweep of `total` runs (the first ten listed).
fn check_complete(rows: &[RowRef], dupes: &[u64], total: u64) -> Result<(), Failure> {
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
    let n_missing = total - rows.len() as u64;
    if n_missing > 0 {
        // The gaps in the sorted ids.
        let mut list: Vec<String> = vec![];
        let mut next = 0u64;
        for id in rows.iter().map(|r| r.id).chain(std::iter::once(total)) {
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
    Ok(())
}

/// The files of the merged sweep's manifest in `out`, each with its bytes, in the order they
/// are written: the first shard's `sweep.json` as one whole sweep (`shard = [1, 1]`,
/// `merged_from` the shard directories), then its `sweep.toml` and `base_scenario.toml` (when
/// there, and not already the same file).
fn merged_manifest(
    dirs: &[PathBuf],
    out: &Path,
    mut manifest: serde_json::Value,
    total: u64,
    record_engine: bool,
) -> Result<Vec<(PathBuf, Vec<u8>)>, Failure> {
    let Some(first) = dirs.first() else {
        return Ok(vec![]);
    };
    let mut files = vec![];
    for f in ["sweep.toml", "base_scenario.toml"] {
        if first.join(f).exists() && !same_file(&first.join(f), &out.join(f)) {
            // Read as a regular file of bounded size, written never through a link nor into a
            // FIFO (73 at once).
            let bytes =
                isotrack_fields::io::read_limited(&first.join(f), 64 << 20).map_err(|e| {
                    fail(
                        exit::NOINPUT,
                        format!("cannot read {}: {e}", first.join(f).display()),
                    )
                })?;
            files.push((out.join(f), bytes));
        }
    }
    // Every shard this engine's: the merged rows are too; else none is claimed.
    if let Some(m) = manifest.as_object_mut() {
        if record_engine {
            m.insert("engine".into(), json!(engine()));
        } else {
            m.remove("engine");
        }
    }
    manifest["shard"] = json!([1, 1]);
    manifest["shard_runs"] = json!(total);
    manifest["merged_from"] = json!(dirs
        .iter()
        .map(|d| d.display().to_string())
        .collect::<Vec<_>>());
    let json = serde_json::to_string_pretty(&manifest).unwrap_or_default() + "\n";
    // The manifest first: the two files after it are never without it
    // ([`crate::sweep::manifest::refuse_foreign_sweep_files`] tells them a sweep's by it).
    files.insert(0, (out.join("sweep.json"), json.into_bytes()));
    Ok(files)
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
