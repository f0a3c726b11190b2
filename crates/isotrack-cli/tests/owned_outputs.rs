//! Issues 30/32 (att42): every command that writes into a directory replaces only what an
//! isotrack wrote there. A user's file of an output's name is refused (73, naming it) before
//! the command runs anything, every file as it was byte for byte; an earlier isotrack's
//! outputs are replaced (or resumed) as before. `sweep` and `merge` (att42-4), `benchmark`
//! (att42-6), `interpolate`'s sidecar (att42-7), `compare`'s per-law directories (att42-11).
#![cfg(unix)]
mod common;
use common::{assert_fails, isotrack_within, stderr, write};
use std::path::{Path, PathBuf};

const SCEN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/paper-fig2b-circular.toml"
);

/// Every file under `dir` (hidden ones and subdirectories' too) with its bytes (a FIFO's:
/// none), by path relative to `dir`, sorted; a directory as its name with a `/`.
fn listing(dir: &Path) -> Vec<(String, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(String, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            let rel = p.strip_prefix(root).unwrap().display().to_string();
            let t = e.file_type().unwrap();
            if t.is_dir() {
                out.push((rel + "/", vec![]));
                walk(root, &p, out);
            } else if t.is_file() {
                out.push((rel, std::fs::read(&p).unwrap()));
            } else {
                out.push((rel, vec![]));
            }
        }
    }
    let mut v = vec![];
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// A 2-run sweep file (20 s runs of Fig. 2(b), `controller.kp` 5 and 10) in `dir`.
fn sweep_file(dir: &Path) -> String {
    write(
        dir,
        "sw.toml",
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 20.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n"
        ),
    )
}

fn run(args: &[&str]) -> std::process::Output {
    isotrack_within(args, 120)
}

fn ok(args: &[&str]) {
    let o = run(args);
    assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
}

/// att42-4: `sweep --out DIR` (and `--force`, `--resume`) and `merge ... --out DIR --force`
/// replaced a user's `sweep.toml`, `base_scenario.toml` and `sweep.json` in DIR without a
/// word. Each (and a `results.csv` that is no sweep's) is refused (73, naming it) before
/// anything is written or removed, DIR as it was byte for byte.
#[test]
fn sweep_and_merge_never_replace_a_users_sweep_files() {
    let d = tempfile::tempdir().unwrap();
    let sw = sweep_file(d.path());
    let shard = d.path().join("shard");
    ok(&["sweep", &sw, "--out", shard.to_str().unwrap()]);
    let shard = shard.to_str().unwrap();
    for (name, text, what) in [
        (
            "sweep.toml",
            "# my own sweep notes\n",
            "is not an isotrack sweep's",
        ),
        (
            "base_scenario.toml",
            "# my own base scenario\n",
            "is not an isotrack sweep's",
        ),
        (
            "sweep.json",
            "{\"sweep\": \"mine\"}\n",
            "is not an isotrack sweep's manifest",
        ),
        (
            "results.csv",
            "x,y\n1,2\n",
            "is not an isotrack sweep's results",
        ),
    ] {
        let dir = d.path().join(format!("user-{name}"));
        std::fs::create_dir_all(&dir).unwrap();
        write(&dir, name, text);
        let before = listing(&dir);
        let out = dir.to_str().unwrap();
        let file = dir.join(name).display().to_string();
        for args in [
            vec!["sweep", &sw, "--out", out],
            vec!["sweep", &sw, "--out", out, "--force"],
            vec!["sweep", &sw, "--out", out, "--resume"],
            vec!["merge", shard, "--out", out, "--force"],
        ] {
            let o = run(&args);
            assert_fails(&o, 73, &[&file, what, "refusing to replace it"]);
            assert_eq!(listing(&dir), before, "{args:?}");
        }
    }
}

/// att42-4: a sweep whose base scenario is `DIR/base_scenario.toml` wrote its resolved keys
/// over it, its own input. Refused (64, naming the file and the input), the file as it was;
/// a sweep run again from an earlier sweep's own `DIR/sweep.toml` (which it would write back
/// as it is) is no clash.
#[test]
fn a_sweep_never_writes_over_its_own_input() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("out");
    std::fs::create_dir_all(&dir).unwrap();
    let base = write(
        &dir,
        "base_scenario.toml",
        &(std::fs::read_to_string(SCEN).unwrap() + "# my edits\n"),
    );
    let sw = write(
        d.path(),
        "sw.toml",
        &format!("scenario = {base:?}\n[base]\nsim.duration_s = 20.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n"),
    );
    let before = listing(&dir);
    let o = run(&["sweep", &sw, "--out", dir.to_str().unwrap()]);
    assert_fails(&o, 64, &[&base, "is an input", "use another --out"]);
    assert_eq!(listing(&dir), before);
    // An earlier sweep's own sweep.toml (its scenario an absolute path) run again into it.
    let d2 = d.path().join("again");
    ok(&[
        "sweep",
        &sweep_file(d.path()),
        "--out",
        d2.to_str().unwrap(),
    ]);
    let own = d2.join("sweep.toml");
    let bytes = std::fs::read(&own).unwrap();
    let results = std::fs::read(d2.join("results.csv")).unwrap();
    ok(&[
        "sweep",
        own.to_str().unwrap(),
        "--out",
        d2.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(std::fs::read(&own).unwrap(), bytes);
    assert_eq!(std::fs::read(d2.join("results.csv")).unwrap(), results);
}

/// An earlier isotrack sweep's directory is isotrack's: resumed, started over, merged over
/// as before, also one an older isotrack wrote without `sweep.json` (its results.csv begins
/// with `run_id,`) and one a sweep killed after its manifest left (sweep.json alone).
#[test]
fn an_earlier_sweep_is_still_replaced_and_resumed() {
    let d = tempfile::tempdir().unwrap();
    let sw = sweep_file(d.path());
    let dir = d.path().join("out");
    let out = dir.to_str().unwrap();
    ok(&["sweep", &sw, "--out", out]);
    let results = std::fs::read(dir.join("results.csv")).unwrap();
    ok(&["sweep", &sw, "--out", out, "--resume"]);
    ok(&["sweep", &sw, "--out", out, "--force"]);
    let merged = d.path().join("merged");
    ok(&["merge", out, "--out", merged.to_str().unwrap()]);
    ok(&["merge", out, "--out", merged.to_str().unwrap(), "--force"]);
    assert_eq!(std::fs::read(merged.join("results.csv")).unwrap(), results);
    // An older isotrack's: no sweep.json.
    std::fs::remove_file(dir.join("sweep.json")).unwrap();
    ok(&["sweep", &sw, "--out", out, "--force"]);
    assert_eq!(std::fs::read(dir.join("results.csv")).unwrap(), results);
    // A sweep killed after its manifest: no results.csv yet.
    std::fs::remove_file(dir.join("results.csv")).unwrap();
    ok(&["sweep", &sw, "--out", out]);
    assert_eq!(std::fs::read(dir.join("results.csv")).unwrap(), results);
}

/// A one-task suite (the circular scenario, 20 s, two laws, tuning and scoring seeds) in
/// `dir`.
fn one_task_suite(dir: &Path) -> String {
    write(
        dir,
        "suite.in.toml",
        &format!(
            "name = \"x\"\nversion = 1\ncontrollers = [\"pi_isoline\", \"pid\"]\ntuning_seeds = [7]\nscoring_seeds = [1, 2]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = {SCEN:?}\nset = [\"sim.duration_s=20.0\"]\nlength_m = 6.93\n"
        ),
    )
}

/// att42-6: `benchmark --out DIR` replaced a user's `index.html`, `leaderboard.md` and
/// `suite.toml`, and a FIFO or link there was refused only once every task had run. Every
/// output name is checked before the first task runs: a user's file of one of them is refused
/// (73, naming it; no task's progress line printed), DIR as it was byte for byte; an earlier
/// benchmark's outputs are replaced by `--resume` as before.
#[test]
fn benchmark_checks_every_output_before_any_task_runs() {
    let d = tempfile::tempdir().unwrap();
    let suite = one_task_suite(d.path());
    for name in [
        "index.html",
        "leaderboard.md",
        "suite.toml",
        "leaderboard.csv",
        "tasks/a/results.csv",
        "tasks/a/task.json",
    ] {
        let dir = d.path().join(format!("user-{}", name.replace('/', "-")));
        let file = dir.join(name);
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(&file, "<p>my own page</p>\n").unwrap();
        let before = listing(&dir);
        let o = run(&[
            "benchmark",
            &suite,
            "--out",
            dir.to_str().unwrap(),
            "--resume",
        ]);
        assert_fails(
            &o,
            73,
            &[
                &file.display().to_string(),
                "is not an isotrack benchmark's",
                "refusing to replace it",
            ],
        );
        assert!(!stderr(&o).contains("task 1/1"), "{}", stderr(&o));
        assert_eq!(listing(&dir), before, "{name}");
    }
    // A FIFO where the page goes: refused before any task (it was once every task had run).
    let dir = d.path().join("fifo");
    std::fs::create_dir_all(&dir).unwrap();
    common::fifo(&dir, "index.html");
    let o = run(&["benchmark", &suite, "--out", dir.to_str().unwrap()]);
    assert_fails(&o, 73, &["index.html"]);
    assert!(!stderr(&o).contains("task 1/1"), "{}", stderr(&o));
    assert!(!dir.join("tasks").exists());
    // An earlier benchmark's outputs: replaced as before.
    let dir = d.path().join("bench");
    let out = dir.to_str().unwrap();
    ok(&["benchmark", &suite, "--out", out]);
    let board = std::fs::read(dir.join("leaderboard.csv")).unwrap();
    ok(&["benchmark", &suite, "--out", out, "--resume"]);
    assert_eq!(std::fs::read(dir.join("leaderboard.csv")).unwrap(), board);
    // own42: without --resume, "pass --resume" was advised for a user's leaderboard.csv, and
    // beside a user's index.html, where --resume is refused too: the user's file is named
    // instead; the advice stays for an earlier benchmark whose every file is a benchmark's.
    let o = run(&["benchmark", &suite, "--out", out]);
    assert_fails(&o, 73, &["already holds a benchmark", "pass --resume"]);
    std::fs::write(dir.join("index.html"), "<p>my own page</p>\n").unwrap();
    let user = d.path().join("user-board");
    std::fs::create_dir(&user).unwrap();
    std::fs::write(user.join("leaderboard.csv"), "my,own,board\n").unwrap();
    for (at, named) in [(&dir, "index.html"), (&user, "leaderboard.csv")] {
        let before = listing(at);
        let o = run(&["benchmark", &suite, "--out", at.to_str().unwrap()]);
        let file = at.join(named).display().to_string();
        assert_fails(&o, 73, &[&file, "is not an isotrack benchmark's"]);
        assert!(!stderr(&o).contains("--resume"), "{}", stderr(&o));
        assert_eq!(listing(at), before, "{named}");
    }
    // att46-8: an earlier benchmark's tasks/ alone (its top-level files moved away) holds its
    // results: refused with the --resume advice naming the task's file, nothing replaced (an
    // edited results.csv row included).
    let fresh = d.path().join("fresh");
    ok(&["benchmark", &suite, "--out", fresh.to_str().unwrap()]);
    let only_tasks = d.path().join("only-tasks");
    std::fs::create_dir_all(only_tasks.join("tasks")).unwrap();
    std::fs::rename(fresh.join("tasks/a"), only_tasks.join("tasks/a")).unwrap();
    let csv = only_tasks.join("tasks/a/results.csv");
    let mut rows = std::fs::read_to_string(&csv).unwrap();
    rows.push_str("pid,9999,0.5\n");
    std::fs::write(&csv, &rows).unwrap();
    let before = listing(&only_tasks);
    let o = run(&["benchmark", &suite, "--out", only_tasks.to_str().unwrap()]);
    let named = only_tasks.join("tasks/a/results.csv").display().to_string();
    assert_fails(
        &o,
        73,
        &["already holds a benchmark", &named, "pass --resume"],
    );
    assert!(!stderr(&o).contains("task 1/1"), "{}", stderr(&o));
    assert_eq!(listing(&only_tasks), before);
    // Beside a file no benchmark writes (the top or a task's directory), the file is named
    // and no --resume advised (README: only where every file is a benchmark's).
    for extra in ["notes.txt", "tasks/a/extra.csv"] {
        let at = d.path().join(format!("extra-{}", extra.replace('/', "-")));
        std::fs::create_dir_all(at.join("tasks")).unwrap();
        std::fs::create_dir_all(at.join("tasks/a")).unwrap();
        std::fs::copy(
            only_tasks.join("tasks/a/task.json"),
            at.join("tasks/a/task.json"),
        )
        .unwrap();
        std::fs::write(at.join(extra), "mine\n").unwrap();
        let before = listing(&at);
        let o = run(&["benchmark", &suite, "--out", at.to_str().unwrap()]);
        let file = at.join(extra).display().to_string();
        assert_fails(
            &o,
            73,
            &[
                "already holds a benchmark",
                &file,
                "which no benchmark writes",
            ],
        );
        assert!(!stderr(&o).contains("--resume"), "{}", stderr(&o));
        assert_eq!(listing(&at), before, "{extra}");
    }
    // A directory holding only files no benchmark writes is no benchmark: it runs.
    let notes = d.path().join("notes-only");
    std::fs::create_dir_all(&notes).unwrap();
    std::fs::write(notes.join("notes.txt"), "mine\n").unwrap();
    ok(&["benchmark", &suite, "--out", notes.to_str().unwrap()]);
    assert_eq!(
        std::fs::read_to_string(notes.join("notes.txt")).unwrap(),
        "mine\n"
    );
}

/// Four stations on a 100 m square and one in the middle, column `v`, in `dir/st.csv`.
fn stations(dir: &Path) -> String {
    write(
        dir,
        "st.csv",
        "x_m,y_m,v\n0,0,10\n100,0,20\n0,100,30\n100,100,40\n50,50,25\n",
    )
}

fn interpolate(st: &str, out: &Path) -> std::process::Output {
    run(&[
        "interpolate",
        st,
        "--value-column",
        "v",
        "--method",
        "idw",
        "--spacing-m",
        "25",
        "--out",
        out.to_str().unwrap(),
    ])
}

/// att42-7: `interpolate --out g.json` wrote the grid, then its sidecar (the grid's name with
/// `.json`) over it: exit 0, the grid gone. Refused (64, naming `--out` and the file), nothing
/// written. The sidecar, a name isotrack chose, never replaces a user's `g.json` beside
/// `--out g.csv` (73, naming it); an isotrack sidecar is replaced, and the grid named on the
/// command line is the user's to replace (as `cp`).
#[test]
fn interpolate_never_writes_its_sidecar_over_the_grid_nor_a_users_file() {
    let d = tempfile::tempdir().unwrap();
    let st = stations(d.path());
    for name in ["g.json", "G.JSON"] {
        let out = d.path().join(name);
        let o = interpolate(&st, &out);
        assert_fails(&o, 64, &["--out", name, "would replace the grid itself"]);
        assert!(!out.exists());
    }
    let out = d.path().join("g.csv");
    let side = d.path().join("g.json");
    std::fs::write(&side, "{\"my\": \"notes\"}\n").unwrap();
    std::fs::write(&out, "my grid\n").unwrap();
    let o = interpolate(&st, &out);
    assert_fails(
        &o,
        73,
        &[
            &side.display().to_string(),
            "is not an isotrack grid's sidecar",
        ],
    );
    assert_eq!(std::fs::read(&side).unwrap(), b"{\"my\": \"notes\"}\n");
    assert_eq!(std::fs::read(&out).unwrap(), b"my grid\n");
    std::fs::remove_file(&side).unwrap();
    // The named grid is replaced; the sidecar written, then replaced by the next run.
    let o = interpolate(&st, &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let first = std::fs::read(&side).unwrap();
    let o = interpolate(&st, &out);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(std::fs::read(&side).unwrap(), first);
    // 5 x 5 nodes, 25 m apart over the 100 m square.
    assert_eq!(std::fs::read_to_string(&out).unwrap().lines().count(), 5);
}

/// Puts a user's file into compare directory `CMP`; returns its path.
type MakeUsersFile = fn(&Path) -> PathBuf;

/// att42-11: `compare --out CMP`'s up-front checks missed a user's `.isotrack.lock` (and a
/// file where a law's directory goes) in `CMP/LAW`: the laws before it ran and were written,
/// then compare was refused. Every law's directory is checked (and locked) before any law
/// runs: refused (73, naming the file), no law's run written, CMP as it was byte for byte.
#[test]
fn compare_checks_every_laws_directory_before_any_law_runs() {
    let d = tempfile::tempdir().unwrap();
    let cases: [(&str, MakeUsersFile); 2] = [
        ("lock", |cmp| {
            std::fs::create_dir_all(cmp.join("pid")).unwrap();
            PathBuf::from(write(&cmp.join("pid"), ".isotrack.lock", "my lock notes\n"))
        }),
        ("file", |cmp| {
            std::fs::create_dir_all(cmp).unwrap();
            PathBuf::from(write(cmp, "pid", "my notes on pid\n"))
        }),
    ];
    for (name, make) in cases {
        let cmp = d.path().join(name);
        let file = make(&cmp);
        let before = listing(&cmp);
        let o = run(&[
            "compare",
            SCEN,
            "--controllers",
            "pi_isoline,pid",
            "--set",
            "sim.duration_s=20",
            "--out",
            cmp.to_str().unwrap(),
        ]);
        assert_fails(&o, 73, &["pid"]);
        // Named as it is (the temporary directory's name has no character to quote).
        let shown = file.display().to_string();
        assert!(stderr(&o).contains(&shown), "{shown}: {}", stderr(&o));
        assert_eq!(listing(&cmp), before, "{name}");
    }
}
