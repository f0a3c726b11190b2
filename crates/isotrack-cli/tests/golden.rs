//! The golden manifest (issue 31): behaviour unchanged, proven. `tests/golden/MANIFEST.sha256`
//! holds the SHA-256 of every output of the commands listed in its header (`run --out` of every
//! bundled scenario, `check --json` of each, a sweep in two shards with an interrupted shard
//! resumed, and merged, `benchmark` on the standard suite, `compare`, an SVG `plot`); this test
//! runs them again with the release binary and compares, output by output. The `python/` lines
//! are the Python package's (`python/tests/test_golden.py`).
//!
//! `ISOTRACK_GOLDEN_UPDATE=1` rewrites the manifest's non-`python/` lines instead of comparing
//! (`scripts/golden.sh --update` regenerates both parts).

mod common;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The manifest, relative to the repository.
const MANIFEST: &str = "tests/golden/MANIFEST.sha256";
/// Set to `1` to rewrite the manifest instead of comparing.
const UPDATE_ENV: &str = "ISOTRACK_GOLDEN_UPDATE";
/// Lines the Python test owns.
const PYTHON_PREFIX: &str = "python/";
/// The sweep run in two shards (120 runs of 300 s: well under a second).
const SWEEP: &str = "sweeps/fig2b-gains.toml";
/// The suite `benchmark` runs.
const SUITE: &str = "suites/standard-v2.toml";
/// The scenarios `compare` runs with every controller: the paper's field, where every law tracks,
/// and three noisy plumes, where the baselines lose the isoline.
const COMPARE: [&str; 2] = ["paper-fig2b-circular", "gaussian-plumes-pm25"];
/// The run drawn as SVG.
const PLOT: &str = "paper-fig2b-circular";
/// Rows of shard 2's `results.csv` kept when it is cut as an interrupted sweep leaves it.
const KEPT_ROWS: usize = 5;

/// The manifest's header: what is hashed, how it is normalised, how to regenerate.
const HEADER: &str = "\
# isotrack golden manifest (issue 31): SHA-256 of every output below, as `sha256  name`, sorted.
# Checked by `cargo test --workspace --release` (crates/isotrack-cli/tests/golden.rs) and, for the
# python/ lines, by scripts/test-python.sh (python/tests/test_golden.py).
# Regenerate: scripts/golden.sh --update  (ISOTRACK_GOLDEN_UPDATE=1 on both tests); every line
# that changes must be listed in the commit message with the reason.
#
# Commands, run from the repository root; OUT is a fresh temporary directory:
#   run/NAME/*           isotrack run scenarios/NAME.toml --out OUT/run/NAME --quiet  (every file)
#   run/default/*        isotrack run --out OUT/run/default --quiet  (the built-in default);
#                        run/default/stdout.txt: the stdout of a plain `isotrack run`
#   check/NAME.json      stdout of isotrack check scenarios/NAME.toml --json  (default.json: no file)
#   sweep/whole/*        isotrack sweep sweeps/fig2b-gains.toml --out OUT/sweep/whole
#   sweep/shard-1/*      the same with --out OUT/sweep/shard-1 --shard 1/2 --threads 1
#   sweep/shard-2/*      the same with --out OUT/sweep/shard-2 --shard 2/2 --threads 2; then its
#                        results.csv cut to the header, 5 rows and half of the 6th (a killed
#                        sweep), then the same command with --resume
#   sweep/merged/*       isotrack merge OUT/sweep/shard-1 OUT/sweep/shard-2 --out OUT/sweep/merged
#   benchmark/*          isotrack benchmark suites/standard-v2.toml --out OUT/benchmark
#                        (benchmark/stdout.md: its stdout)
#   compare/NAME/*       isotrack compare scenarios/NAME.toml --out OUT/compare/NAME (all
#                        controllers; NAME/stdout.md: its stdout), NAME = paper-fig2b-circular,
#                        gaussian-plumes-pm25
#   plot/*               isotrack plot OUT/run/paper-fig2b-circular --format svg --out OUT/plot
#   python/default/*     isotrack.Scenario.default().run().save(DIR) (python/tests/test_golden.py);
#                        python/default/trace-arrays.f64le: Run.trace's columns in trace.csv's
#                        order, each as its name, a newline, then its values as little-endian
#                        float64 (NaN as 0x7ff8000000000000), all concatenated
#
# Normalised before hashing (text files; nothing else is changed, numbers never): OUT's
# absolute path -> <OUT>; the repository's absolute path -> <REPO>; the version string:
# `\"isotrack_version\": \"X\"` -> `\"isotrack_version\": \"<VERSION>\"` (summary.json) and
# `isotrack X` -> `isotrack <VERSION>` (benchmark index.html's generator, suite.toml's header);
# the value of `\"digest\":\"...\"` (a task's hash, which covers the version) in benchmark/
# files (tasks/*/task.json, index.html) -> <DIGEST>. Wall-clock times and thread counts appear
# in no output file (they are printed on stderr only, which is not hashed).
";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the repository")
}

/// Runs `isotrack args` from the repository root; its stdout. Panics with stderr on failure.
fn run_ok(repo: &Path, args: &[&str]) -> Vec<u8> {
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(args)
        .current_dir(repo)
        .output()
        .expect("the binary runs");
    assert_eq!(
        o.status.code(),
        Some(0),
        "isotrack {args:?}: {}",
        common::stderr(&o)
    );
    o.stdout
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Replaces the value of every `"digest":"VALUE"` (compact JSON) by `<DIGEST>`.
fn mask_digest(text: &str) -> String {
    const KEY: &str = "\"digest\":\"";
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find(KEY) {
        let value = at + KEY.len();
        out.push_str(&rest[..value]);
        out.push_str("<DIGEST>");
        rest = &rest[value..];
        rest = &rest[rest.find('"').unwrap_or(rest.len())..];
    }
    out.push_str(rest);
    out
}

/// The bytes hashed for output `name` (see the manifest's header).
fn normalised(name: &str, bytes: Vec<u8>, out: &Path, repo: &Path) -> Vec<u8> {
    let mut text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => return e.into_bytes(),
    };
    let v = env!("CARGO_PKG_VERSION");
    let rules = [
        (path_str(out).to_string(), "<OUT>".to_string()),
        (path_str(repo).to_string(), "<REPO>".to_string()),
        (
            format!("\"isotrack_version\": \"{v}\""),
            "\"isotrack_version\": \"<VERSION>\"".to_string(),
        ),
        (format!("isotrack {v}"), "isotrack <VERSION>".to_string()),
    ];
    for (from, to) in &rules {
        // A 50 MB trace holds none of them: no copy.
        if text.contains(from.as_str()) {
            text = text.replace(from.as_str(), to);
        }
    }
    if name.starts_with("benchmark/") {
        text = mask_digest(&text);
    }
    text.into_bytes()
}

fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// Every file under `dir`, as paths relative to it with `/` separators.
fn files_under(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, dir: &Path, acc: &mut Vec<String>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("a directory entry").path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(root, &p, acc);
            } else {
                let rel = p.strip_prefix(root).expect("under the root");
                let parts: Vec<&str> = rel.iter().map(|c| c.to_str().expect("UTF-8")).collect();
                acc.push(parts.join("/"));
            }
        }
    }
    let mut acc = vec![];
    walk(dir, dir, &mut acc);
    acc
}

/// Hashes of every output: name -> SHA-256 (hex) of its normalised bytes.
struct Hashes {
    out: PathBuf,
    repo: PathBuf,
    map: BTreeMap<String, String>,
}

impl Hashes {
    fn add(&mut self, name: &str, bytes: Vec<u8>) {
        let h = sha256_hex(&normalised(name, bytes, &self.out, &self.repo));
        assert!(
            self.map.insert(name.to_string(), h).is_none(),
            "{name} twice"
        );
    }

    /// Every file under `OUT/rel`, named `rel/...`.
    fn add_dir(&mut self, rel: &str) {
        let dir = self.out.join(rel);
        for f in files_under(&dir) {
            let bytes = std::fs::read(dir.join(&f)).expect("readable");
            self.add(&format!("{rel}/{f}"), bytes);
        }
    }
}

/// Bundled scenarios left out of the manifest: too slow to run on every test (issue 32: four
/// fixed-wing UAVs for 16 000 s on the ERA5 series, about a minute; three robots on a puff plume
/// whose isoline of the time is extracted every second, about 10 s). Their behaviour is tested
/// by their own tests (crates/isotrack-cli/tests/team_run.rs).
const NOT_PINNED: [&str; 2] = ["team-era5-uav-4", "team-puff-edge-3"];

/// The bundled scenarios' file stems, sorted (without [`NOT_PINNED`]).
fn scenario_stems(repo: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(repo.join("scenarios"))
        .expect("scenarios/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| p.file_stem().unwrap().to_str().unwrap().to_string())
        .filter(|s| !NOT_PINNED.contains(&s.as_str()))
        .collect();
    v.sort();
    v
}

/// Runs every command of the manifest's header into `out`; their hashes.
fn generate(repo: &Path, out: &Path) -> BTreeMap<String, String> {
    let mut h = Hashes {
        out: out.to_path_buf(),
        repo: repo.to_path_buf(),
        map: BTreeMap::new(),
    };
    let o = |rel: &str| path_str(&out.join(rel)).to_string();
    let stems = scenario_stems(repo);
    assert!(stems.len() >= 10, "{stems:?}");
    // Each run and check is one thread: run them on every core, results gathered in order.
    enum Job {
        Run(Option<String>),
        Check(Option<String>),
    }
    let jobs: Vec<Job> = std::iter::once(None)
        .chain(stems.iter().cloned().map(Some))
        .flat_map(|s| [Job::Run(s.clone()), Job::Check(s)])
        .collect();
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done: std::sync::Mutex<BTreeMap<usize, (String, Vec<u8>)>> = Default::default();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| loop {
                let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                let Some(job) = jobs.get(i) else { break };
                let scenario =
                    |s: &Option<String>| s.as_ref().map(|s| format!("scenarios/{s}.toml"));
                let name = |s: &Option<String>| s.clone().unwrap_or_else(|| "default".into());
                let result = match job {
                    Job::Run(s) => {
                        let dir = o(&format!("run/{}", name(s)));
                        let mut args = vec!["run"];
                        let sc = scenario(s);
                        args.extend(sc.as_deref());
                        args.extend(["--out", &dir, "--quiet"]);
                        run_ok(repo, &args);
                        (String::new(), vec![])
                    }
                    Job::Check(s) => {
                        let mut args = vec!["check"];
                        let sc = scenario(s);
                        args.extend(sc.as_deref());
                        args.push("--json");
                        (format!("check/{}.json", name(s)), run_ok(repo, &args))
                    }
                };
                done.lock().unwrap().insert(i, result);
            });
        }
    });
    for (name, stdout) in done.into_inner().unwrap().into_values() {
        if !name.is_empty() {
            h.add(&name, stdout);
        }
    }
    h.add_dir("run");
    h.add("run/default/stdout.txt", run_ok(repo, &["run"]));

    // A sweep whole, and in two shards of which the second is interrupted and resumed; merged.
    run_ok(repo, &["sweep", SWEEP, "--out", &o("sweep/whole")]);
    let shard = |k: &str, threads: &str, extra: &[&str]| {
        let dir = o(&format!("sweep/shard-{k}"));
        let spec = format!("{k}/2");
        let mut args = vec![
            "sweep",
            SWEEP,
            "--out",
            &dir,
            "--shard",
            &spec,
            "--threads",
            threads,
        ];
        args.extend(extra);
        run_ok(repo, &args);
    };
    shard("1", "1", &[]);
    shard("2", "2", &[]);
    let results = out.join("sweep/shard-2/results.csv");
    let text = std::fs::read_to_string(&results).expect("shard 2's results");
    let uninterrupted = text.clone();
    let lines: Vec<&str> = text.split_inclusive('\n').collect();
    assert!(lines.len() > KEPT_ROWS + 2, "{} lines", lines.len());
    let cut = lines[KEPT_ROWS + 1];
    let interrupted = lines[..=KEPT_ROWS].concat() + &cut[..cut.len() / 2];
    std::fs::write(&results, interrupted).expect("cut shard 2");
    shard("2", "2", &["--resume"]);
    // Resuming and merging change nothing (README, "Sweeps"): checked here as well as hashed.
    let read = |rel: &str| std::fs::read(out.join(rel)).expect(rel);
    assert!(
        read("sweep/shard-2/results.csv") == uninterrupted.as_bytes(),
        "shard 2 resumed after a cut differs from shard 2 run at once"
    );
    run_ok(
        repo,
        &[
            "merge",
            &o("sweep/shard-1"),
            &o("sweep/shard-2"),
            "--out",
            &o("sweep/merged"),
        ],
    );
    assert!(
        read("sweep/merged/results.csv") == read("sweep/whole/results.csv"),
        "the merged shards' results.csv differs from the sweep's run whole"
    );
    h.add_dir("sweep");

    let stdout = run_ok(repo, &["benchmark", SUITE, "--out", &o("benchmark")]);
    h.add_dir("benchmark");
    h.add("benchmark/stdout.md", stdout);

    for name in COMPARE {
        let rel = format!("compare/{name}");
        let scenario = format!("scenarios/{name}.toml");
        let stdout = run_ok(repo, &["compare", &scenario, "--out", &o(&rel)]);
        h.add_dir(&rel);
        h.add(&format!("{rel}/stdout.md"), stdout);
    }

    run_ok(
        repo,
        &[
            "plot",
            &o(&format!("run/{PLOT}")),
            "--format",
            "svg",
            "--out",
            &o("plot"),
        ],
    );
    h.add_dir("plot");
    h.map
}

/// The manifest's entries: name -> hash.
fn parse_manifest(text: &str) -> BTreeMap<String, String> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let (hash, name) = l
                .split_once("  ")
                .unwrap_or_else(|| panic!("{MANIFEST}: not `sha256  name`: {l}"));
            (name.to_string(), hash.to_string())
        })
        .collect()
}

fn render_manifest(entries: &BTreeMap<String, String>) -> String {
    let mut text = HEADER.to_string();
    for (name, hash) in entries {
        text += &format!("{hash}  {name}\n");
    }
    text
}

#[test]
fn outputs_match_the_golden_manifest() {
    let repo = repo();
    let manifest = repo.join(MANIFEST);
    let stored = std::fs::read_to_string(&manifest)
        .map(|t| parse_manifest(&t))
        .unwrap_or_default();
    let tmp = tempfile::tempdir().expect("a temporary directory");
    let out = tmp.path().canonicalize().expect("the temporary directory");
    let got = generate(&repo, &out);

    if std::env::var(UPDATE_ENV).as_deref() == Ok("1") {
        let mut entries: BTreeMap<String, String> = stored
            .into_iter()
            .filter(|(n, _)| n.starts_with(PYTHON_PREFIX))
            .collect();
        entries.extend(got);
        std::fs::create_dir_all(manifest.parent().unwrap()).expect("tests/golden/");
        std::fs::write(&manifest, render_manifest(&entries)).expect("write the manifest");
        return;
    }

    let want: BTreeMap<&String, &String> = stored
        .iter()
        .filter(|(n, _)| !n.starts_with(PYTHON_PREFIX))
        .collect();
    let mut problems = vec![];
    for (name, hash) in &want {
        match got.get(*name) {
            None => problems.push(format!("  missing:  {name} (no longer written)")),
            Some(g) if g != *hash => problems.push(format!("  changed:  {name}  {hash} -> {g}")),
            Some(_) => {}
        }
    }
    for (name, g) in &got {
        if !want.contains_key(name) {
            problems.push(format!("  new:      {name}  {g}"));
        }
    }
    if !problems.is_empty() {
        let kept = tmp.keep();
        panic!(
            "{} of {} outputs differ from {MANIFEST}:\n{}\n\
             The outputs are kept in {} (hashed after the normalisation the manifest's header \
             describes).\nIf every difference is intended, regenerate with \
             `scripts/golden.sh --update` (or ISOTRACK_GOLDEN_UPDATE=1 cargo test --workspace \
             --release --locked --all-features --test golden) and list every changed output in \
             the commit message, with the reason.",
            problems.len(),
            want.len().max(got.len()),
            problems.join("\n"),
            kept.display()
        );
    }
}
