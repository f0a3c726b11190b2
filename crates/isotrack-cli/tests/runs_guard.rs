//! Issue 30 (runs-guard): the output-directory lock never writes through a link; `run --out`
//! and `compare --out` take the lock and write their files atomically (no old summary beside a
//! new trace); an output that is a FIFO exits 73 at once; an output that is an input exits 64.
#![cfg(unix)]
mod common;
use common::{assert_fails, fifo, isotrack, isotrack_within, write};
use std::path::{Path, PathBuf};
use std::process::Output;

const SCEN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/paper-fig2b-circular.toml"
);

/// A short run of the paper's Fig. 2(b) scenario (20 s instead of 600 s).
const SHORT: &str = "sim.duration_s=20";

/// Takes the directory lock of `dir` as another command would (holder `sweep pid 1`).
fn hold_lock(dir: &Path) -> std::fs::File {
    std::fs::create_dir_all(dir).unwrap();
    let f = std::fs::File::create(dir.join(".isotrack.lock")).unwrap();
    f.try_lock().unwrap();
    f
}

/// Item 1: a `.isotrack.lock` that is a link to a user's file: `sweep`, `sweep --resume` and
/// `merge` refuse the directory (73) and the file keeps its bytes.
#[test]
fn a_lock_file_that_is_a_link_is_refused_and_its_target_kept() {
    let d = tempfile::tempdir().unwrap();
    let victim = write(d.path(), "victim.txt", "data\n");
    let sw = write(
        d.path(),
        "s.toml",
        &format!("scenario = {SCEN:?}\n[grid]\nsim.duration_s = [1.0]\n"),
    );
    let r = d.path().join("r");
    std::fs::create_dir_all(&r).unwrap();
    std::os::unix::fs::symlink(&victim, r.join(".isotrack.lock")).unwrap();
    let rs = r.display().to_string();
    for args in [
        vec!["sweep", &sw, "--out", &rs],
        vec!["sweep", &sw, "--out", &rs, "--resume"],
    ] {
        let o = isotrack_within(&args, 60);
        assert_fails(&o, 73, &[".isotrack.lock", "not a regular file"]);
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "data\n");
    }
    // A merge into it, from a real shard.
    let shard = d.path().join("shard");
    let o = isotrack(&["sweep", &sw, "--out", &shard.display().to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = isotrack_within(&["merge", &shard.display().to_string(), "--out", &rs], 60);
    assert_fails(&o, 73, &[".isotrack.lock", "not a regular file"]);
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "data\n");
    // A dangling link is not followed to create its target either.
    let ghost = d.path().join("ghost.txt");
    let r2 = d.path().join("r2");
    std::fs::create_dir_all(&r2).unwrap();
    std::os::unix::fs::symlink(&ghost, r2.join(".isotrack.lock")).unwrap();
    let o = isotrack_within(&["sweep", &sw, "--out", &r2.display().to_string()], 60);
    assert_fails(&o, 73, &[".isotrack.lock"]);
    assert!(!ghost.exists());
}

/// Item 2: `run --out D` and `compare --out D` while another command holds D's lock exit 73
/// and write nothing; a run that ends leaves trace, summary and scenario and no temporary file.
#[test]
fn run_and_compare_out_take_the_directory_lock() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let os = out.display().to_string();
    let holder = hold_lock(&out);
    let o = isotrack_within(&["run", SCEN, "--set", SHORT, "--out", &os], 60);
    assert_fails(&o, 73, &["is writing this directory"]);
    assert!(!out.join("trace.csv").exists() && !out.join("summary.json").exists());
    let o = isotrack_within(
        &[
            "compare",
            SCEN,
            "--set",
            SHORT,
            "--controllers",
            "pid",
            "--out",
            &os,
        ],
        60,
    );
    assert_fails(&o, 73, &["is writing this directory"]);
    assert!(!out.join("comparison.csv").exists() && !out.join("pid").exists());
    drop(holder);
    let o = isotrack_within(&["run", SCEN, "--set", SHORT, "--out", &os, "--quiet"], 120);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    // No lock file left behind either (issue 31: the lock's holder removes it as it lets go).
    assert_eq!(names, ["scenario.toml", "summary.json", "trace.csv"]);
}

/// Item 2: a run killed mid-way over an old run directory leaves no summary (the old one is
/// removed before anything is written), so the directory is not a mix plot and report accept.
#[test]
fn a_killed_run_leaves_no_stale_summary() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let os = out.display().to_string();
    let o = isotrack_within(&["run", SCEN, "--set", SHORT, "--out", &os, "--quiet"], 120);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(out.join("summary.json").exists());
    let old_trace = std::fs::read(out.join("trace.csv")).unwrap();
    // A long run (1e6 s at dt 0.01 s: far longer than the test waits), killed once it writes.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["run", SCEN, "--set", "sim.duration_s=1000000", "--out", &os])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while out.join("summary.json").exists() {
        assert!(
            t0.elapsed().as_secs() < 60,
            "the old summary was never removed"
        );
        assert!(child.try_wait().unwrap().is_none(), "ended before caught");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!out.join("summary.json").exists());
    // The trace in place is still the old one, whole: the new one streamed to a temporary file.
    assert_eq!(std::fs::read(out.join("trace.csv")).unwrap(), old_trace);
    let o = isotrack_within(
        &[
            "report",
            &os,
            "--out",
            &d.path().join("r.html").display().to_string(),
        ],
        60,
    );
    assert_ne!(
        o.status.code(),
        Some(0),
        "report accepted a directory without a summary"
    );
}

/// Item 6: an output that is a FIFO exits 73 at once (never waits for a reader).
#[test]
fn fifo_outputs_exit_73_at_once() {
    let d = tempfile::tempdir().unwrap();
    for name in ["trace.csv", "summary.json"] {
        let out = d.path().join(format!("run-{name}"));
        std::fs::create_dir_all(&out).unwrap();
        fifo(&out, name);
        let o = isotrack_within(
            &[
                "run",
                SCEN,
                "--set",
                SHORT,
                "--out",
                &out.display().to_string(),
            ],
            30,
        );
        assert_fails(&o, 73, &[name, "not a regular file"]);
    }
    // A good run directory for `report`.
    let run = d.path().join("run");
    let o = isotrack(&[
        "run",
        SCEN,
        "--set",
        SHORT,
        "--out",
        &run.display().to_string(),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let f = fifo(d.path(), "report.html");
    let o = isotrack_within(&["report", &run.display().to_string(), "--out", &f], 30);
    assert_fails(&o, 73, &["not a regular file"]);
    let stations = write(
        d.path(),
        "st.csv",
        "x_m,y_m,v\n0,0,1\n100,0,2\n0,100,3\n100,100,4\n",
    );
    let f = fifo(d.path(), "grid.csv");
    let o = isotrack_within(
        &[
            "interpolate",
            &stations,
            "--value-column",
            "v",
            "--method",
            "idw",
            "--spacing-m",
            "25",
            "--out",
            &f,
        ],
        30,
    );
    assert_fails(&o, 73, &["not a regular file"]);
    let head = "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n";
    let inputs = write(
        d.path(),
        "in.csv",
        &format!("{head}0,-0.07,0,0,0.4\n1,-0.07,0,0,0.4\n"),
    );
    let f = fifo(d.path(), "replay.csv");
    let o = isotrack_within(&["replay", "--inputs", &inputs, "--out", &f], 30);
    assert_fails(&o, 73, &["not a regular file"]);
    let cmp = d.path().join("cmp");
    std::fs::create_dir_all(&cmp).unwrap();
    fifo(&cmp, "comparison.csv");
    let o = isotrack_within(
        &[
            "compare",
            SCEN,
            "--set",
            SHORT,
            "--controllers",
            "pid",
            "--out",
            &cmp.display().to_string(),
        ],
        30,
    );
    assert_fails(&o, 73, &["comparison.csv", "not a regular file"]);
}

/// Item 7: an output that is one of the command's inputs exits 64 and the input keeps its bytes.
#[test]
fn outputs_that_are_inputs_exit_64() {
    let d = tempfile::tempdir().unwrap();
    let st_text = "x_m,y_m,v\n0,0,1\n100,0,2\n0,100,3\n100,100,4\n";
    let stations = write(d.path(), "stc.csv", st_text);
    let o = isotrack(&[
        "interpolate",
        &stations,
        "--value-column",
        "v",
        "--method",
        "idw",
        "--spacing-m",
        "25",
        "--out",
        &stations,
    ]);
    assert_fails(&o, 64, &["is an input"]);
    assert_eq!(std::fs::read_to_string(&stations).unwrap(), st_text);
    let run = d.path().join("run");
    let o = isotrack(&[
        "run",
        SCEN,
        "--set",
        SHORT,
        "--out",
        &run.display().to_string(),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let trace = run.join("trace.csv");
    let before = std::fs::read(&trace).unwrap();
    let o = isotrack(&[
        "report",
        &run.display().to_string(),
        "--out",
        &trace.display().to_string(),
    ]);
    assert_fails(&o, 64, &["is an input"]);
    assert_eq!(std::fs::read(&trace).unwrap(), before);
    // compare: the scenario's field file is D/comparison.csv.
    let cmp = d.path().join("cmp");
    std::fs::create_dir_all(&cmp).unwrap();
    let repo = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let field = cmp.join("comparison.csv");
    std::fs::copy(
        format!("{repo}/data/no2_germany_kriged/no2_germany_kriged.csv"),
        &field,
    )
    .unwrap();
    let field_text = std::fs::read(&field).unwrap();
    let o = isotrack(&[
        "compare",
        &format!("{repo}/scenarios/paper-fig2a-field.toml"),
        "--set",
        &format!("field.path={:?}", field.display().to_string()),
        "--controllers",
        "pid",
        "--out",
        &cmp.display().to_string(),
    ]);
    assert_fails(&o, 64, &["is an input"]);
    assert_eq!(std::fs::read(&field).unwrap(), field_text);
    // benchmark: DIR/suite.toml is the suite being read.
    let bench = d.path().join("bench");
    std::fs::create_dir_all(&bench).unwrap();
    let suite = bench.join("suite.toml");
    std::fs::copy(format!("{repo}/suites/standard-v1.toml"), &suite).unwrap();
    let suite_text = std::fs::read(&suite).unwrap();
    let o = isotrack(&[
        "benchmark",
        &suite.display().to_string(),
        "--out",
        &bench.display().to_string(),
    ]);
    assert_fails(&o, 64, &["is an input"]);
    assert_eq!(std::fs::read(&suite).unwrap(), suite_text);
}

/// Item 9: `--shard` takes canonical digits and at most a million shards; an empty scenario
/// file (whitespace and comments only) is refused (65) instead of running the default.
#[test]
fn shard_counts_are_bounded_and_empty_scenarios_refused() {
    let d = tempfile::tempdir().unwrap();
    let sw = write(
        d.path(),
        "s.toml",
        &format!("scenario = {SCEN:?}\n[grid]\nsim.duration_s = [1.0]\n"),
    );
    let out = d.path().join("o").display().to_string();
    for shard in [
        "1/1000000000000",
        "01/2",
        "1/02",
        "+1/2",
        " 1/2",
        "1/1000001",
    ] {
        let o = isotrack(&["sweep", &sw, "--out", &out, "--shard", shard]);
        assert_fails(&o, 64, &["--shard"]);
    }
    let o = isotrack(&["sweep", &sw, "--out", &out, "--shard", "1/1000000"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    for text in ["", "\n  \n", "# nothing\n\n   # here\n"] {
        let sc = write(d.path(), "empty.toml", text);
        let o = isotrack(&["run", &sc]);
        assert_fails(&o, 65, &["empty scenario file", "omit the argument"]);
    }
}

/// Item 8: Ctrl-C of `benchmark` keeps the tasks that finished: once task 2 has started, task
/// 1's `task.json` is on disk, and a SIGINT then leaves it there for `--resume`.
#[test]
fn an_interrupted_benchmark_keeps_its_finished_tasks() {
    use std::io::BufRead;
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("b");
    let suite = concat!(env!("CARGO_MANIFEST_DIR"), "/../../suites/standard-v1.toml");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "benchmark",
            suite,
            "--out",
            &out.display().to_string(),
            "--threads",
            "1",
        ])
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    let mut second = false;
    for line in err.by_ref() {
        if line.unwrap().contains("task 2/") {
            second = true;
            break;
        }
    }
    assert!(second, "the benchmark never started task 2");
    let ok = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let rest: Vec<String> = err.map_while(Result::ok).collect();
    let status = child.wait().unwrap();
    let first = out.join("tasks").join("circular-100hz").join("task.json");
    assert!(first.is_file(), "task 1's results were lost");
    assert!(!out.join("leaderboard.csv").exists());
    // att48-3: exit 130 says how many finished tasks are kept and that --resume continues
    // (it was silent); the count is the task.json files there.
    assert_eq!(status.code(), Some(130));
    let n = std::fs::read_dir(out.join("tasks"))
        .unwrap()
        .flatten()
        .filter(|e| e.path().join("task.json").is_file())
        .count();
    let said =
        format!("holds {n} of the 10 tasks finished; the same benchmark with `--resume` continues");
    assert!(
        rest.iter()
            .any(|l| l.starts_with("interrupted: ") && l.ends_with(&said)),
        "{rest:?}"
    );
}

/// Issue 30 (fix30, item 1): every other file a command writes into its output directory
/// (`sweep`'s and `merge`'s sweep.toml, base_scenario.toml, sweep.json; `benchmark`'s
/// suite.toml, leaderboard.md, index.html, tasks/ID/task.json; `run --plot` and `plot`'s
/// figures, `plot SWEEP`'s) was written through a symbolic link planted there (its target
/// overwritten, exit 0) and waited on a FIFO. Each is refused with 73 at once, the link's
/// target kept.
#[test]
fn every_output_file_refuses_a_link_and_a_fifo() {
    let d = tempfile::tempdir().unwrap();
    let w = d.path();
    let sc = write(w, "sc.toml", "sim.duration_s = 2.0\n");
    let sw = write(
        w,
        "s.toml",
        "scenario = \"sc.toml\"\n[grid]\nsensor.rate_hz = [10.0, 100.0]\n",
    );
    let suite = write(
        w,
        "suite.toml",
        "name = \"hs\"\nversion = 1\nscoring = 2\ncontrollers = [\"pi_isoline\"]\ntuning_seeds = [9]\nscoring_seeds = [1]\n[[task]]\nid = \"t1\"\ntitle = \"t\"\nscenario = \"sc.toml\"\nlength_m = 5.0\n",
    );
    let src = w.join("src").display().to_string();
    let o = isotrack(&["sweep", &sw, "--out", &src]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let run = w.join("run").display().to_string();
    let o = isotrack(&["run", &sc, "--out", &run, "--quiet"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let cases: Vec<(&str, Vec<&str>)> = vec![
        ("sweep.toml", vec!["sweep", &sw, "--out"]),
        ("base_scenario.toml", vec!["sweep", &sw, "--out"]),
        ("sweep.json", vec!["sweep", &sw, "--out"]),
        ("sweep.toml", vec!["merge", &src, "--out"]),
        ("base_scenario.toml", vec!["merge", &src, "--out"]),
        ("sweep.json", vec!["merge", &src, "--out"]),
        (
            "suite.toml",
            vec!["benchmark", &suite, "--threads", "1", "--out"],
        ),
        (
            "leaderboard.md",
            vec!["benchmark", &suite, "--threads", "1", "--out"],
        ),
        (
            "index.html",
            vec!["benchmark", &suite, "--threads", "1", "--out"],
        ),
        (
            "tasks/t1/task.json",
            vec!["benchmark", &suite, "--threads", "1", "--out"],
        ),
        (
            "trajectory.png",
            vec!["run", &sc, "--plot", "--quiet", "--out"],
        ),
        (
            "timeseries.svg",
            vec!["plot", &run, "--format", "svg", "--out"],
        ),
        (
            "sweep_steady_state_max_abs_error_vs_sensor_rate_hz.png",
            vec!["plot", &src, "--x", "sensor.rate_hz", "--out"],
        ),
    ];
    for (i, (name, args)) in cases.iter().enumerate() {
        for kind in ["link", "fifo"] {
            let out = w.join(format!("o{i}-{kind}"));
            let file = out.join(name);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            let victim = w.join(format!("victim{i}"));
            std::fs::write(&victim, "VICTIM\n").unwrap();
            if kind == "link" {
                std::os::unix::fs::symlink(&victim, &file).unwrap();
            } else {
                fifo(
                    file.parent().unwrap(),
                    file.file_name().unwrap().to_str().unwrap(),
                );
            }
            let os = out.display().to_string();
            let mut a = args.clone();
            a.push(&os);
            let o = isotrack_within(&a, 120);
            assert_fails(&o, 73, &["not a regular file"]);
            assert_eq!(
                std::fs::read_to_string(&victim).unwrap(),
                "VICTIM\n",
                "{args:?} {name} {kind}"
            );
        }
    }
    // `sweep --resume` over a finished sweep whose sweep.json became a link.
    let re = w.join("re");
    let o = isotrack(&["sweep", &sw, "--out", &re.display().to_string()]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    // The link's target holds the manifest itself (so it is read as the sweep's), but is
    // not written through.
    let victim = w.join("victim-resume");
    let manifest = std::fs::read_to_string(re.join("sweep.json")).unwrap();
    std::fs::write(&victim, &manifest).unwrap();
    std::fs::remove_file(re.join("sweep.json")).unwrap();
    std::os::unix::fs::symlink(&victim, re.join("sweep.json")).unwrap();
    let o = isotrack_within(
        &["sweep", &sw, "--out", &re.display().to_string(), "--resume"],
        60,
    );
    assert_fails(&o, 73, &["sweep.json", "not a regular file"]);
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), manifest);
}

/// Issue 30 (fix30b), item 5 (item 13 of the hostile list): `plot` of a sweep directory builds
/// its file name from column names (`sweep_{metric}_vs_{x}.svg`). A varied column and a metric
/// whose names carry a `/`, `..`, an escape sequence and a right-to-left override (a
/// hand-made `results.csv`) write one file inside `--out`, named with ASCII letters, digits,
/// `_` and `-` only, and the SVG (its title and axis labels name the columns) holds no control
/// character but the line breaks and tabs XML allows, and no bidirectional control.
#[test]
fn sweep_plot_file_names_and_text_are_safe_from_column_names() {
    let d = tempfile::tempdir().unwrap();
    let sweep = d.path().join("sw");
    std::fs::create_dir_all(&sweep).unwrap();
    let x = "../../x/\u{1b}[31mkey\u{202e}gnp";
    let metric = "m/..\u{1b}]0;title\u{7}\u{202e}err";
    std::fs::write(
        sweep.join("results.csv"),
        format!("run_id,\"{x}\",\"{metric}\"\n0,1.0,2.0\n1,2.0,3.0\n2,3.0,5.0\n"),
    )
    .unwrap();
    let out = d.path().join("out");
    let o = isotrack_within(
        &[
            "plot",
            sweep.to_str().unwrap(),
            "--x",
            x,
            "--metric",
            metric,
            "--format",
            "svg",
            "--out",
            out.to_str().unwrap(),
        ],
        120,
    );
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    // Only the figure, inside --out: nothing beside the sweep or above it.
    let written: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(written.len(), 1, "{written:?}");
    let name = &written[0];
    assert!(
        name.starts_with("sweep_") && name.ends_with(".svg"),
        "{name}"
    );
    let stem = name.strip_suffix(".svg").unwrap();
    assert!(
        stem.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'),
        "{name}"
    );
    let mut top: Vec<String> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    top.sort();
    assert_eq!(top, ["out", "sw"]);
    assert!(!d.path().join("x").exists() && !sweep.join("x").exists());
    let svg = std::fs::read_to_string(out.join(name)).unwrap();
    let bad: Vec<char> = svg
        .chars()
        .filter(|&c| {
            (c.is_control() && !matches!(c, '\n' | '\t' | '\r'))
                || matches!(c, '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}' | '\u{feff}')
        })
        .collect();
    assert!(bad.is_empty(), "{bad:?}");
    // The columns are still named in the figure (their printable part).
    assert!(
        svg.contains("]0;title") && svg.contains("gnp"),
        "labels kept"
    );
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

/// att36-1, att39-1: `run --out A` into a user's folder that never held an isotrack run but
/// has a `scenario.toml` of its own (not the input), a `trace.csv` or a `summary.json` of its
/// own keys is refused (73, naming the file) before any run: the user's files, those and the
/// ones named as isotrack's figures (`trajectory.png`, `team.svg`, `animation.gif`, ...), are
/// as they were (before att39-1 the three run files were replaced without a word; att36-1's
/// test asserted that overwrite). A folder
/// holding only files named as figures is run into, and keeps them, run after run (att38-1).
/// A real earlier run's figures (written by `run --plot`) are kept too, with a note (nu-21).
#[test]
fn run_out_keeps_a_users_files_named_as_figures_in_a_folder_that_held_no_run() {
    let d = tempfile::tempdir().unwrap();
    let input = write(d.path(), "in.toml", &std::fs::read_to_string(SCEN).unwrap());
    let figures = [
        "trajectory.png",
        "team.svg",
        "timeseries.svg",
        "animation.gif",
    ];
    let scen = std::fs::read_to_string(SCEN).unwrap();
    let mine = "{\"my\": \"results, 3 weeks of work\"}\n";
    for (i, (files, named, why)) in [
        (
            vec![("scenario.toml", scen.as_str())],
            "scenario.toml",
            "no summary.json beside it",
        ),
        (
            vec![("trace.csv", "a,b\n1,2\n")],
            "trace.csv",
            "no summary.json beside it",
        ),
        (
            vec![("summary.json", "{\"notes\": \"mine\"}\n")],
            "summary.json",
            "is not an isotrack run's summary (no `isotrack_version` key)",
        ),
        // att39-1's folder: the user's JSON, data and notes, none of them replaced.
        (
            vec![
                ("summary.json", mine),
                ("trace.csv", "t,my,data\n"),
                ("scenario.toml", "# my own notes\n"),
            ],
            "summary.json",
            "is not an isotrack run's summary (no `isotrack_version` key)",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let a = d.path().join(format!("user-{i}"));
        std::fs::create_dir_all(&a).unwrap();
        for (name, text) in &files {
            write(&a, name, text);
        }
        for f in figures {
            write(&a, f, "MY PICTURE\n");
        }
        let before = listing(&a);
        let o = isotrack(&[
            "run",
            &input,
            "--out",
            &a.display().to_string(),
            "--set",
            SHORT,
        ]);
        let file = a.join(named).display().to_string();
        assert_fails(
            &o,
            73,
            &[&file, why, "refusing to replace it", "use another --out"],
        );
        assert!(
            o.stdout.is_empty(),
            "refused before the run: {}",
            String::from_utf8_lossy(&o.stdout)
        );
        // Every file as it was (no lock file, no temporary left either).
        assert_eq!(listing(&a), before, "{files:?}");
    }
    // Figures only: run into, twice (att38-1: the second run, the summary now isotrack's),
    // the user's figures kept each time.
    let a = d.path().join("user-figures");
    std::fs::create_dir_all(&a).unwrap();
    for f in figures {
        write(&a, f, "MY PICTURE\n");
    }
    for _ in 0..2 {
        let o = isotrack(&[
            "run",
            &input,
            "--out",
            &a.display().to_string(),
            "--quiet",
            "--set",
            SHORT,
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
        for f in figures {
            assert_eq!(
                std::fs::read_to_string(a.join(f)).ok().as_deref(),
                Some("MY PICTURE\n"),
                "{f} after a run"
            );
        }
        assert!(std::fs::read_to_string(a.join("summary.json"))
            .unwrap()
            .contains("\"isotrack_version\""));
        // att40-1: the note does not tell the user that `plot` redraws their own files (it
        // refuses them, 73): it says to move them.
        let err = common::stderr(&o);
        assert!(
            err.contains("not a figure isotrack wrote") && err.contains("move them away"),
            "{err}"
        );
        assert!(!err.contains("redraws"), "{err}");
    }
    // nu-21: a real run's figures are kept as well, and the new run says they are not its own.
    let r = d.path().join("r").display().to_string();
    let o = isotrack(&[
        "run", &input, "--out", &r, "--quiet", "--plot", "--set", SHORT,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(Path::new(&r).join("trajectory.png").exists());
    let o = isotrack(&["run", &input, "--out", &r, "--quiet", "--set", SHORT]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(Path::new(&r).join("trajectory.png").exists());
    let err = common::stderr(&o);
    assert!(
        err.contains("also holds trajectory.png, timeseries.png from before this run"),
        "{err}"
    );
    assert!(
        err.contains("plot' redraws trajectory.png, timeseries.png")
            || err.contains(" redraws trajectory.png, timeseries.png"),
        "{err}"
    );
    assert!(!err.contains("not a figure isotrack wrote"), "{err}");
    // Drawn again (run --plot), the figures are this run's: no note.
    let o = isotrack(&[
        "run", &input, "--out", &r, "--quiet", "--plot", "--set", SHORT,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(
        !common::stderr(&o).contains("from before this run"),
        "{}",
        common::stderr(&o)
    );
}

/// att36-2: `plot DIR` of a run directory another command is writing (its lock held, as
/// `run --out DIR` holds it while it replaces the run) is refused (73) before anything is
/// read or drawn, so no figure lands beside another run's summary; once the lock is free the
/// same plot draws, and leaves no lock file behind.
#[test]
fn plot_refuses_a_run_directory_being_written() {
    let d = tempfile::tempdir().unwrap();
    let r = d.path().join("r");
    let rs = r.display().to_string();
    let o = isotrack(&["run", SCEN, "--out", &rs, "--quiet", "--set", SHORT]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let lock = hold_lock(&r);
    let o = isotrack_within(&["plot", &rs], 60);
    assert_fails(&o, 73, &["is writing this directory", ".isotrack.lock"]);
    assert!(!r.join("trajectory.png").exists());
    assert!(!r.join("timeseries.png").exists());
    // att38-2: in the window where the run has removed the old summary and not yet renamed
    // the new one in, the directory reads as no run: still 73 naming the holder, not 66.
    let summary = std::fs::read(r.join("summary.json")).unwrap();
    std::fs::remove_file(r.join("summary.json")).unwrap();
    let o = isotrack_within(&["plot", &rs], 60);
    assert_fails(&o, 73, &["is writing this directory"]);
    std::fs::write(r.join("summary.json"), summary).unwrap();
    drop(lock);
    std::fs::remove_file(r.join(".isotrack.lock")).unwrap();
    let o = isotrack_within(&["plot", &rs], 60);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(r.join("trajectory.png").exists());
    assert!(!r.join(".isotrack.lock").exists());
}

/// A finished 2-run sweep (20 s runs of Fig. 2(b), `controller.kp` 5 and 10) in `dir/name`.
fn small_sweep(dir: &Path, name: &str) -> (String, std::path::PathBuf) {
    let sw = write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 20.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n"
        ),
    );
    let out = dir.join(name);
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    (sw, out)
}

/// The names in `dir` that start with `prefix`.
fn names_starting(dir: &Path, prefix: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| n.starts_with(prefix))
        .collect();
    v.sort();
    v
}

/// att38-8: `plot SWEEP` while another command (`sweep --resume`, `sweep --force`, a merge)
/// holds the sweep directory's lock drew the rows so far into it, exit 0. It is refused (73,
/// naming the holder) and draws nothing, also with `--out` elsewhere; the lock free, it draws
/// and leaves no lock file.
#[test]
fn plot_refuses_a_sweep_directory_being_written() {
    let d = tempfile::tempdir().unwrap();
    let (_, out) = small_sweep(d.path(), "sw");
    let outs = out.display().to_string();
    let elsewhere = d.path().join("figs");
    let lock = hold_lock(&out);
    let o = isotrack_within(&["plot", &outs], 60);
    assert_fails(&o, 73, &["is writing this directory", ".isotrack.lock"]);
    let o = isotrack_within(&["plot", &outs, "--out", elsewhere.to_str().unwrap()], 60);
    assert_fails(&o, 73, &["is writing this directory"]);
    assert!(names_starting(&out, "sweep_").is_empty());
    assert!(!elsewhere.exists() || names_starting(&elsewhere, "sweep_").is_empty());
    // `sweep --force` has replaced results.csv by its header alone: 73 too, not "no run has".
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    std::fs::write(out.join("results.csv"), results.lines().next().unwrap()).unwrap();
    let o = isotrack_within(&["plot", &outs], 60);
    assert_fails(&o, 73, &["is writing this directory"]);
    std::fs::write(out.join("results.csv"), &results).unwrap();
    drop(lock);
    std::fs::remove_file(out.join(".isotrack.lock")).unwrap();
    let o = isotrack_within(&["plot", &outs], 60);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert_eq!(
        names_starting(&out, "sweep_"),
        ["sweep_steady_state_max_abs_error_vs_controller_kp.png"]
    );
    assert!(!out.join(".isotrack.lock").exists());
}

/// att41-10 SAFETY: `plot SWEEP` (into the sweep, or `--out DIR`) replaced the user's own file
/// named as a sweep figure (`sweep_METRIC_vs_X.png`/`.svg`, no isotrack mark) without a word,
/// where `plot RUN` refuses one. Refused the same way (73, naming it, before anything is
/// drawn: the folder as it was); isotrack's own earlier sweep figure (marked) is redrawn.
/// Fails on the source before (exit 0, the user's file a PNG).
#[test]
fn plot_of_a_sweep_never_replaces_a_users_file_named_as_its_figure() {
    let d = tempfile::tempdir().unwrap();
    let (_, out) = small_sweep(d.path(), "sw");
    let outs = out.display().to_string();
    let po = d.path().join("po");
    std::fs::create_dir(&po).unwrap();
    let pos = po.display().to_string();
    for (dir, name, args) in [
        (
            &out,
            "sweep_steady_state_max_abs_error_vs_controller_kp.png",
            vec!["plot", &outs],
        ),
        (
            &po,
            "sweep_steady_state_max_abs_error_vs_controller_kp.svg",
            vec!["plot", &outs, "--format", "svg", "--out", &pos],
        ),
    ] {
        std::fs::write(dir.join(name), b"MY OWN SWEEP PLOT").unwrap();
        let before = listing(dir);
        let o = isotrack_within(&args, 60);
        let named = dir.join(name).display().to_string();
        assert_fails(
            &o,
            73,
            &[&named, "not a figure isotrack wrote", "move it away"],
        );
        assert!(!String::from_utf8_lossy(&o.stdout).contains("wrote"));
        assert_eq!(listing(dir), before, "{name}");
        std::fs::remove_file(dir.join(name)).unwrap();
    }
    // Its own figure, marked, is redrawn.
    let args = ["plot", &outs, "--format", "svg", "--out", &pos];
    for _ in 0..2 {
        let o = isotrack_within(&args, 60);
        assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    }
}

/// att41-2: a refusal names the file as run's note does, shell-quoted: a directory whose name
/// holds a line break and `error: ...` printed it raw, forging a second `error:` line. Now one
/// `error:` line, the path as bash's `$'...'` to paste; a run directory's refusal and a
/// figure's alike. Fails on the source before (two `error:` lines, the path raw).
#[test]
fn a_refusal_names_the_file_as_one_shell_word() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("nl\nerror: none, all fine");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("trace.csv"), b"u\n").unwrap();
    let ds = dir.to_str().unwrap();
    let quoted = format!(
        "$'{}/nl\\x0aerror: none, all fine/trace.csv'",
        d.path().display()
    );
    let o = isotrack_within(&["run", "--set", "sim.duration_s=1", "--out", ds], 60);
    assert_fails(&o, 73, &[&quoted, "not an isotrack run's"]);
    let e = common::stderr(&o);
    assert_eq!(
        e.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{e}"
    );
    // A figure of the user's there: plot's refusal quotes it too.
    std::fs::remove_file(dir.join("trace.csv")).unwrap();
    std::fs::write(dir.join("trajectory.png"), b"MY FIGURE").unwrap();
    let r = d.path().join("r");
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=1",
        "--quiet",
        "--out",
        r.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = isotrack_within(&["plot", r.to_str().unwrap(), "--out", ds], 60);
    let quoted = quoted.replace("trace.csv", "trajectory.png");
    assert_fails(&o, 73, &[&quoted, "not a figure isotrack wrote"]);
    let e = common::stderr(&o);
    assert_eq!(
        e.lines().filter(|l| l.starts_with("error:")).count(),
        1,
        "{e}"
    );
}

/// att36-11: `sweep --force` starts over beside the earlier sweep's `plot` figures, which then
/// read as the new results' figures. isotrack cannot tell its figure from a user's file of that
/// name, and never removes a file it may not have written (att38-1's rule): it keeps them and
/// says so, naming them, as `run` does of a run directory's figures.
#[test]
fn sweep_force_names_the_figures_from_before_and_keeps_them() {
    let d = tempfile::tempdir().unwrap();
    let (sw, out) = small_sweep(d.path(), "sw");
    let outs = out.display().to_string();
    let o = isotrack_within(&["plot", &outs], 60);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let fig = out.join("sweep_steady_state_max_abs_error_vs_controller_kp.png");
    let bytes = std::fs::read(&fig).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", &outs, "--force"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let e = common::stderr(&o);
    assert!(
        e.contains("sweep_steady_state_max_abs_error_vs_controller_kp.png")
            && e.contains("from before this sweep"),
        "{e}"
    );
    assert_eq!(std::fs::read(&fig).unwrap(), bytes);
    // A sweep into a fresh directory, or --force with no figure there, says nothing of it.
    std::fs::remove_file(&fig).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", &outs, "--force"]);
    assert!(!common::stderr(&o).contains("from before"));
}

/// att36-13 addendum: `sweep --resume` appended its rows to results.csv in place, so a hard
/// link to it (a `cp -al` snapshot of the half-done sweep) grew with them. The snapshot keeps
/// the rows it had; the resumed sweep's file holds every run.
#[test]
fn sweep_resume_leaves_a_hard_linked_snapshot_as_it_was() {
    let d = tempfile::tempdir().unwrap();
    let (sw, out) = small_sweep(d.path(), "sw");
    let outs = out.display().to_string();
    let results = out.join("results.csv");
    let full = std::fs::read_to_string(&results).unwrap();
    let cut: String = full.lines().take(2).map(|l| format!("{l}\n")).collect();
    std::fs::write(&results, &cut).unwrap();
    let snap = d.path().join("snapshot.csv");
    std::fs::hard_link(&results, &snap).unwrap();
    let o = isotrack(&["sweep", &sw, "--out", &outs, "--resume"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert_eq!(std::fs::read_to_string(&snap).unwrap(), cut);
    assert_eq!(std::fs::read_to_string(&results).unwrap(), full);
}

/// att38-11: `merge` hashed a recorded data file replaced by a huge one in full (5 GB: 10 s)
/// before refusing it, where `sweep` refuses it from its size (att30n-9). A file larger than
/// any field's reader accepts is refused from its size: 66 saying so, no SHA-256 of it.
#[test]
fn merge_refuses_a_data_file_grown_beyond_the_readers_limit_from_its_size() {
    let d = tempfile::tempdir().unwrap();
    let n = 41;
    let mut asc = format!("ncols {n}\nnrows {n}\nxllcorner -20.5\nyllcorner -20.5\ncellsize 1.0\n");
    for j in 0..n {
        let row: Vec<String> = (0..n)
            .map(|i| {
                let (x, y) = (i as f64 - 20.0, j as f64 - 20.0);
                format!("{}", 20.0 * (-0.1 * (x * x + y * y).sqrt()).exp())
            })
            .collect();
        asc.push_str(&row.join(" "));
        asc.push('\n');
    }
    let data = write(d.path(), "f.asc", &asc);
    write(
        d.path(),
        "s.toml",
        "[field]\nkind = \"grid\"\npath = \"f.asc\"\n[initial]\nx_m = 5.0\ny_m = 0.0\n[sim]\nduration_s = 5.0\n",
    );
    let sw = write(
        d.path(),
        "sw.toml",
        "scenario = \"s.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0]\n",
    );
    let shard = |k: &str| {
        let out = d.path().join(format!("m{k}"));
        let o = isotrack(&[
            "sweep",
            &sw,
            "--out",
            out.to_str().unwrap(),
            "--shard",
            &format!("{k}/2"),
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
        out.display().to_string()
    };
    let (m1, m2) = (shard("1"), shard("2"));
    // Sparse: no byte of it is stored, but a hash would read all of them.
    std::fs::remove_file(&data).unwrap();
    let f = std::fs::File::create(&data).unwrap();
    f.set_len(isotrack_fields::io::MAX_GRID_FILE_BYTES + 1)
        .unwrap();
    let merged = d.path().join("mm").display().to_string();
    let o = isotrack_within(&["merge", &m1, &m2, "--out", &merged], 120);
    assert_fails(&o, 66, &["f.asc", "bytes is more than the"]);
    assert!(
        !common::stderr(&o).contains("SHA-256"),
        "{}",
        common::stderr(&o)
    );
}

/// att36-9: `compare --out CMP` locked CMP only, so a `run --out CMP/pi_isoline` meanwhile
/// (which locks CMP/pi_isoline) wrote the very directory compare was writing, both exit 0, one
/// result gone. compare locks each law's directory while it writes it: while another command
/// holds it, compare is refused (73, naming the holder) and writes nothing there; free, compare
/// writes it and leaves no lock file.
#[test]
fn compare_locks_each_laws_directory_while_it_writes_it() {
    let d = tempfile::tempdir().unwrap();
    let cmp = d.path().join("cmp");
    let law = cmp.join("pi_isoline");
    let lock = hold_lock(&law);
    let args = [
        "compare",
        SCEN,
        "--controllers",
        "pi_isoline",
        "--set",
        SHORT,
        "--out",
        cmp.to_str().unwrap(),
    ];
    let o = isotrack_within(&args, 120);
    assert_fails(&o, 73, &["is writing this directory", "pi_isoline"]);
    assert!(!law.join("summary.json").exists());
    drop(lock);
    std::fs::remove_file(law.join(".isotrack.lock")).unwrap();
    let o = isotrack_within(&args, 120);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(law.join("summary.json").exists());
    assert!(!law.join(".isotrack.lock").exists());
}

/// att39-1 (addendum): `compare --out CMP` replaced a user's own `CMP/comparison.csv` and a
/// user's `CMP/pid/summary.json` without a word. Both are refused (73, naming the file) before
/// any law runs (no law's directory written), every file as it was; a comparison.csv and
/// per-law runs compare wrote are replaced by the next compare as before, which names a figure
/// left in a law's directory as not this run's (compare printed no note at all).
#[test]
fn compare_out_never_replaces_a_users_comparison_or_summary() {
    let d = tempfile::tempdir().unwrap();
    let args = |cmp: &Path| {
        vec![
            "compare".to_string(),
            SCEN.to_string(),
            "--controllers".into(),
            "pi_isoline,pid".into(),
            "--set".into(),
            SHORT.into(),
            "--out".into(),
            cmp.display().to_string(),
        ]
    };
    let run = |cmp: &Path| {
        let a = args(cmp);
        isotrack_within(&a.iter().map(String::as_str).collect::<Vec<_>>(), 120)
    };
    // The user's comparison of their own controllers.
    let cmp = d.path().join("cmp-csv");
    std::fs::create_dir_all(&cmp).unwrap();
    write(
        &cmp,
        "comparison.csv",
        "my comparison of my own controllers\n",
    );
    let before = listing(&cmp);
    let o = run(&cmp);
    let file = cmp.join("comparison.csv").display().to_string();
    assert_fails(
        &o,
        73,
        &[&file, "is not an isotrack comparison", "use another --out"],
    );
    assert_eq!(listing(&cmp), before);
    // A law's directory holding the user's summary.json (and a figure).
    let cmp = d.path().join("cmp-law");
    std::fs::create_dir_all(cmp.join("pid")).unwrap();
    write(&cmp.join("pid"), "summary.json", "{\"mine\": 1}\n");
    write(&cmp.join("pid"), "trajectory.png", "mine\n");
    let before = (listing(&cmp), listing(&cmp.join("pid")));
    let o = run(&cmp);
    let file = cmp.join("pid/summary.json").display().to_string();
    assert_fails(
        &o,
        73,
        &[
            &file,
            "is not an isotrack run's summary",
            "use another --out",
        ],
    );
    assert_eq!((listing(&cmp), listing(&cmp.join("pid"))), before);
    // compare's own outputs: replaced by the next compare; a figure left in a law's directory
    // is kept and named as not this run's, as `run` names it.
    let cmp = d.path().join("cmp");
    let o = run(&cmp);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(!common::stderr(&o).contains("from before this run"));
    write(&cmp.join("pid"), "trajectory.png", "MY PICTURE\n");
    let o = run(&cmp);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let note = format!(
        "note: {} also holds trajectory.png from before this run, not this run's",
        cmp.join("pid").display()
    );
    assert!(common::stderr(&o).contains(&note), "{}", common::stderr(&o));
    assert_eq!(
        std::fs::read_to_string(cmp.join("pid/trajectory.png")).unwrap(),
        "MY PICTURE\n"
    );
    // att42-8: compare's own comparison.csv edited since (compare's header, a row appended by
    // hand) is the user's now: refused (73, saying so), as it was.
    let table = cmp.join("comparison.csv");
    let mut edited = std::fs::read_to_string(&table).unwrap();
    edited.push_str("my_law,converged\n");
    std::fs::write(&table, &edited).unwrap();
    let o = run(&cmp);
    let file = table.display().to_string();
    assert_fails(&o, 73, &[&file, "edited since isotrack wrote it"]);
    assert_eq!(std::fs::read_to_string(&table).unwrap(), edited);
}

/// `compare SCEN --controllers pi_isoline,pid --set SHORT --out CMP` with `extra` arguments.
fn compare_into(cmp: &Path, extra: &[&str]) -> std::process::Output {
    let cmp = cmp.display().to_string();
    let mut args = vec![
        "compare",
        SCEN,
        "--controllers",
        "pi_isoline,pid",
        "--set",
        SHORT,
        "--out",
        &cmp,
    ];
    args.extend_from_slice(extra);
    isotrack_within(&args, 120)
}

/// att44-4 SAFETY: a comparison copied the usual way (`cp -r D/* E/`: the glob leaves
/// `.isotrack-tables.json` behind) passed for an older isotrack's by its first line: the
/// user's annotation of `E/comparison.csv` was replaced (exit 0), and so was a user's own
/// table that merely began with compare's header, in a fresh folder. Without a record beside
/// it no table is isotrack's: each is refused (73, naming it, saying no record holds it)
/// before any law runs, the folder as it was byte for byte; D, its record beside it, is
/// replaced as before. Fails on the source before (exit 0, the edits replaced).
#[test]
fn a_comparison_copied_without_its_record_is_not_taken_for_isotracks() {
    let d = tempfile::tempdir().unwrap();
    let dd = d.path().join("D");
    let o = compare_into(&dd, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let table = std::fs::read_to_string(dd.join("comparison.csv")).unwrap();
    let header = table.lines().next().unwrap().to_string();
    for (name, text) in [
        (
            "E4",
            format!("{table}# my annotation: pid chatter is the sensor,,\n"),
        ),
        ("E4-plain", table.clone()),
        ("E3", format!("{header}\nmy_law,completed\n")),
    ] {
        let e = d.path().join(name);
        std::fs::create_dir(&e).unwrap();
        write(&e, "comparison.csv", &text);
        let before = listing(&e);
        let o = compare_into(&e, &[]);
        let file = e.join("comparison.csv").display().to_string();
        assert_fails(
            &o,
            73,
            &[
                &file,
                "no .isotrack-tables.json beside it records it",
                "use another --out",
            ],
        );
        assert_eq!(listing(&e), before, "{name}");
    }
    let o = compare_into(&dd, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
}

/// att44-12: `compare --out CMP` followed a symbolic link at `CMP/pid` (a name compare picks)
/// and replaced the run directory it pointed to elsewhere with the pid law's run (exit 0). A
/// link at a law's directory, even to a directory, is refused (73, naming it and what it is)
/// before any law runs: the linked run as it was, CMP holding the link alone.
#[test]
fn compare_never_writes_a_laws_run_through_a_link() {
    let d = tempfile::tempdir().unwrap();
    let keep = d.path().join("keep");
    let o = isotrack_within(
        &["run", SCEN, "--set", SHORT, "--out", keep.to_str().unwrap()],
        120,
    );
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let kept = listing(&keep);
    let cmp = d.path().join("H7");
    std::fs::create_dir(&cmp).unwrap();
    std::os::unix::fs::symlink(&keep, cmp.join("pid")).unwrap();
    let o = compare_into(&cmp, &[]);
    let link = cmp.join("pid").display().to_string();
    assert_fails(&o, 73, &[&link, "is a symbolic link", "not a directory"]);
    assert_eq!(listing(&keep), kept);
    let left: Vec<String> = std::fs::read_dir(&cmp)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["pid"]);
}

/// own42: a `--gain` the second law refuses (`pid.kd = -1`) failed compare only when that
/// law's turn came: the first law had run into `CMP/pi_isoline` and `CMP/pid` stayed behind
/// empty. Every law's scenario is built first: refused (65, naming the gain) with nothing
/// written, CMP not created.
#[test]
fn a_gain_a_later_law_refuses_leaves_nothing_behind() {
    let d = tempfile::tempdir().unwrap();
    let cmp = d.path().join("C");
    let o = compare_into(&cmp, &["--gain", "pid.kd=-1"]);
    assert_fails(&o, 65, &["--gain pid.kd=-1", "controller.kd"]);
    assert!(
        !cmp.exists(),
        "{:?}",
        std::fs::read_dir(&cmp).map(|r| r.count())
    );
}

/// att38-10: Ctrl-C during `plot` left `.trajectory.png.PID.tmp.png` in the run directory,
/// which no later command removed. The interrupted plot removes its temporary figure (exit
/// 130), as `run --out` removes its temporary trace.
#[test]
fn ctrl_c_during_plot_leaves_no_temporary_figure() {
    let d = tempfile::tempdir().unwrap();
    let r = d.path().join("r");
    let rs = r.display().to_string();
    // 6000 s of Fig. 2(b): a trajectory long enough to catch plot drawing it.
    let o = isotrack(&[
        "run",
        SCEN,
        "--out",
        &rs,
        "--quiet",
        "--set",
        "sim.duration_s=6000",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let temporary = |r: &Path| {
        std::fs::read_dir(r)
            .unwrap()
            .flatten()
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| n.contains(".tmp"))
            .collect::<Vec<_>>()
    };
    let mut caught = false;
    for _ in 0..20 {
        let mut plot = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .args(["plot", &rs])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let t0 = std::time::Instant::now();
        while temporary(&r).is_empty() && plot.try_wait().unwrap().is_none() {
            assert!(t0.elapsed() < std::time::Duration::from_secs(60));
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        if plot.try_wait().unwrap().is_some() {
            continue;
        }
        let kill = std::process::Command::new("kill")
            .args(["-INT", &plot.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let status = plot.wait().unwrap();
        if status.code() == Some(0) {
            // Ended before the signal came.
            continue;
        }
        caught = true;
        assert_eq!(status.code(), Some(130));
        assert_eq!(temporary(&r), Vec::<String>::new());
        assert!(!r.join(".isotrack.lock").exists());
        break;
    }
    assert!(caught, "plot was never caught drawing");
}

/// att38-9: `run --out U --plot` into a folder that never held a run, holding the user's own
/// `trajectory.png`, replaced it without a word; `plot RUN --out U` too. Both are refused (73)
/// naming the file, before the run (no trace written) and before any figure, and the user's
/// file is as it was; with the file moved away both draw, and a second `plot` replaces
/// isotrack's own (marked) figures.
#[test]
fn plot_never_replaces_a_users_file_named_as_a_figure() {
    let d = tempfile::tempdir().unwrap();
    let input = write(d.path(), "in.toml", &std::fs::read_to_string(SCEN).unwrap());
    let u = d.path().join("U");
    std::fs::create_dir_all(&u).unwrap();
    write(&u, "trajectory.png", "MY PICTURE\n");
    let us = u.display().to_string();
    let o = isotrack(&[
        "run", &input, "--out", &us, "--quiet", "--plot", "--set", SHORT,
    ]);
    assert_fails(&o, 73, &["trajectory.png is not a figure isotrack wrote"]);
    assert!(!u.join("trace.csv").exists());
    assert_eq!(
        std::fs::read_to_string(u.join("trajectory.png")).unwrap(),
        "MY PICTURE\n"
    );
    let r = d.path().join("r").display().to_string();
    let o = isotrack(&["run", &input, "--out", &r, "--quiet", "--set", SHORT]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = isotrack(&["plot", &r, "--out", &us]);
    assert_fails(&o, 73, &["trajectory.png is not a figure isotrack wrote"]);
    assert_eq!(
        std::fs::read_to_string(u.join("trajectory.png")).unwrap(),
        "MY PICTURE\n"
    );
    assert!(!u.join("timeseries.png").exists());
    std::fs::rename(u.join("trajectory.png"), d.path().join("mine.png")).unwrap();
    for _ in 0..2 {
        let o = isotrack(&["plot", &r, "--out", &us]);
        assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    }
    let png = std::fs::read(u.join("trajectory.png")).unwrap();
    assert!(png.windows(17).any(|w| w == b"Software\0isotrack"));
}

/// att39-9: `plot DIR` of a folder that is neither a run nor a sweep created a lock file in
/// it (to name a holder, att38-2) and, where it could not (a read-only folder), said "cannot
/// lock" (73) instead of what the folder is. Without a writer's lock file there, plot says
/// 66 and leaves the folder as it was.
#[test]
fn plot_of_a_folder_that_is_no_run_says_so_and_writes_nothing_there() {
    let d = tempfile::tempdir().unwrap();
    let f = d.path().join("notes");
    std::fs::create_dir_all(&f).unwrap();
    write(&f, "notes.txt", "mine\n");
    let o = isotrack_within(&["plot", f.to_str().unwrap()], 60);
    assert_fails(&o, 66, &["is neither a run directory"]);
    let names: Vec<_> = std::fs::read_dir(&f)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("notes.txt")]);
}

/// att40-23: `plot SWEEP --out ELSEWHERE` of a sweep directory this user cannot write (a
/// colleague's sweep, a read-only mount), no writer's lock file in it, draws into ELSEWHERE
/// (it was refused 73, "cannot write figures into SWEEP ... give --out a directory you can
/// write"); the sweep is left as it was, no lock file created. Drawn by the user `nobody`
/// (setpriv) when the tests run as root, who writes everywhere; skipped where neither works.
#[test]
fn a_read_only_sweep_is_plotted_into_another_out() {
    use std::os::unix::fs::PermissionsExt;
    let d = tempfile::tempdir().unwrap();
    std::fs::set_permissions(d.path(), std::fs::Permissions::from_mode(0o777)).unwrap();
    let sw = write(
        d.path(),
        "sw.toml",
        &format!("scenario = {SCEN:?}\n[base]\nsim.duration_s = 5.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n"),
    );
    let sweep = d.path().join("swd");
    let o = isotrack(&["sweep", &sw, "--out", sweep.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let names = |p: &Path| -> Vec<String> { listing(p).into_iter().map(|(n, _)| n).collect() };
    let before = names(&sweep);
    for e in std::fs::read_dir(&sweep).unwrap() {
        let p = e.unwrap().path();
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o444)).unwrap();
    }
    std::fs::set_permissions(&sweep, std::fs::Permissions::from_mode(0o555)).unwrap();
    let out = d.path().join("figs");
    let root = std::process::Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    let o = if root {
        match std::process::Command::new("setpriv")
            .args(["--reuid=65534", "--regid=65534", "--clear-groups"])
            .arg(env!("CARGO_BIN_EXE_isotrack"))
            .args([
                "plot",
                sweep.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
        {
            Ok(o) if !common::stderr(&o).contains("setpriv:") => o,
            _ => {
                eprintln!("skipped: running as root without setpriv to draw as another user");
                std::fs::set_permissions(&sweep, std::fs::Permissions::from_mode(0o755)).unwrap();
                return;
            }
        }
    } else {
        isotrack(&[
            "plot",
            sweep.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    std::fs::set_permissions(&sweep, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert!(
        names(&out)
            .iter()
            .any(|f| f.starts_with("sweep_") && f.ends_with(".png")),
        "{:?}",
        names(&out)
    );
    assert_eq!(names(&sweep), before);
}

/// nu40-4: a data file replaced while `run --out` flies: the run flew the field read before it,
/// and summary.json's `data_files` names that file's SHA-256 (it named the new file's: the
/// digest was taken after the run), with a warning saying the file changed. The digests are
/// computed here by sha2 from the bytes written.
#[test]
fn a_data_file_replaced_during_the_run_is_named_as_read() {
    use sha2::Digest;
    let d = tempfile::tempdir().unwrap();
    let data = d.path().join("data");
    std::fs::create_dir_all(&data).unwrap();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let original = std::fs::read(format!("{root}/data/volcano/volcano.csv")).unwrap();
    let csv = data.join("volcano.csv");
    std::fs::write(&csv, &original).unwrap();
    let scen = std::fs::read_to_string(format!("{root}/scenarios/volcano.toml"))
        .unwrap()
        .replace("../data/volcano/volcano.csv", "data/volcano.csv");
    let input = write(d.path(), "volcano.toml", &scen);
    let out = d.path().join("run");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["run", &input, "--out", out.to_str().unwrap(), "--quiet"])
        .args(["--set", "sim.duration_s=200000"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The live trace appears once the scenario is loaded (and its files hashed).
    let t0 = std::time::Instant::now();
    while !std::fs::read_dir(&out).is_ok_and(|mut r| {
        r.any(|e| e.is_ok_and(|e| e.file_name().to_string_lossy().starts_with(".trace.csv.")))
    }) {
        assert!(t0.elapsed().as_secs() < 60, "no live trace");
        assert!(child.try_wait().unwrap().is_none(), "the run ended first");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let mut changed = String::from_utf8(original.clone()).unwrap();
    changed.push_str("\n# edited\n");
    std::fs::write(&csv, &changed).unwrap();
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let hex = |b: &[u8]| {
        sha2::Sha256::digest(b)
            .iter()
            .map(|x| format!("{x:02x}"))
            .collect::<String>()
    };
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let files = s["data_files"].as_object().unwrap();
    assert_eq!(files.len(), 1, "{files:?}");
    let (_, digest) = files.iter().next().unwrap();
    assert_eq!(digest.as_str(), Some(hex(&original).as_str()));
    assert_ne!(hex(&original), hex(changed.as_bytes()));
    let warned = s["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w.as_str().unwrap().starts_with("a data file changed"));
    assert!(warned, "{}", s["warnings"]);
    assert!(common::stderr(&o).contains("warning: a data file changed"));
}

/// The names in `dir` starting with `prefix`, sorted (none when `dir` cannot be read).
fn entries(dir: &Path, prefix: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| e.file_name().into_string().ok())
        .filter(|n| n.starts_with(prefix))
        .collect();
    v.sort();
    v
}

/// The `t_end_s` of the run in `law` (its summary.json), `None` without a summary.
fn run_end_s(law: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(law.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["t_end_s"].as_f64()
}

/// The temporary and lock files anywhere in `dir` (one level of law directories).
fn litter(dir: &Path) -> Vec<String> {
    let mut found = vec![];
    for d in std::iter::once(dir.to_path_buf()).chain(
        std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_dir()),
    ) {
        found.extend(
            entries(&d, ".")
                .into_iter()
                .filter(|n| n.ends_with(".tmp") || n == ".isotrack.lock")
                .map(|n| d.join(n).display().to_string()),
        );
    }
    found
}

/// att46-10 SAFETY, att46-11: Ctrl-C during `compare --out CMP` (into CMP's own earlier
/// comparison, or into a new CMP) at a controlled point: the moment the first law's temporary
/// trace is renamed into place, i.e. inside the replacement of its run directory. Before the
/// fix the interrupt removed the law's temporary files while the replacement ran: the law's
/// earlier summary.json was gone beside its earlier trace.csv and scenario.toml (the next
/// compare refused 73 "not an isotrack run's"), a spurious "cannot write pid/scenario.toml"
/// was printed, and the earlier comparison.csv (still recorded as isotrack's) stayed beside
/// a law holding the new run. Now, after exit 130: every law directory holds the earlier run
/// whole (t_end 20 s) or the new one (1200 s), or is absent when it did not exist before; no
/// temporary nor lock file; no error printed; `comparison.csv` is the earlier table byte for
/// byte when no law was replaced, and is gone (its record entry too) once one was; a plain
/// re-run into CMP succeeds.
#[test]
fn an_interrupted_compare_leaves_every_law_whole_and_no_stale_table() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let d = tempfile::tempdir().unwrap();
    let laws = ["pid", "sliding_mode"];
    let args = |cmp: &Path, duration: &str| {
        vec![
            "compare".to_string(),
            SCEN.to_string(),
            "--controllers".into(),
            laws.join(","),
            "--set".into(),
            format!("sim.duration_s={duration}"),
            "--out".into(),
            cmp.display().to_string(),
        ]
    };
    let mut caught = 0;
    for attempt in 0..8 {
        let cmp = d.path().join(format!("C{attempt}"));
        let fresh = attempt % 2 == 1;
        let table = cmp.join("comparison.csv");
        let earlier = if fresh {
            None
        } else {
            let a = args(&cmp, "20");
            let o = isotrack_within(&a.iter().map(String::as_str).collect::<Vec<_>>(), 120);
            assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
            Some(std::fs::read(&table).unwrap())
        };
        let mut child = Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .args(args(&cmp, "1200"))
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // The first law's temporary trace: seen, then gone (renamed into place).
        let first = cmp.join(laws[0]);
        let (t0, mut seen) = (Instant::now(), false);
        while child.try_wait().unwrap().is_none() {
            assert!(t0.elapsed() < Duration::from_secs(120), "never caught");
            let tmp = !entries(&first, ".trace.csv.").is_empty();
            if tmp {
                seen = true;
            } else if seen {
                // It may have ended first: its exit status says so below.
                let _ = Command::new("kill")
                    .args(["-INT", &child.id().to_string()])
                    .status();
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let o = child.wait_with_output().unwrap();
        let err = common::stderr(&o);
        if o.status.code() == Some(0) {
            // Finished before the signal came: nothing to check here.
            continue;
        }
        caught += 1;
        assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
        assert!(
            !err.lines().any(|l| l.starts_with("error")),
            "attempt {attempt}: {err}"
        );
        assert_eq!(litter(&cmp), Vec::<String>::new(), "attempt {attempt}");
        let mut replaced = false;
        for law in laws {
            let dir = cmp.join(law);
            match run_end_s(&dir) {
                Some(1200.0) => replaced = true,
                Some(20.0) if !fresh => {}
                None if fresh => assert!(
                    !dir.exists(),
                    "attempt {attempt}: {law} left without a run: {:?}",
                    entries(&dir, "")
                ),
                other => panic!(
                    "attempt {attempt}: {law}: t_end {other:?}, files {:?}",
                    entries(&dir, "")
                ),
            }
        }
        let record = std::fs::read_to_string(cmp.join(".isotrack-tables.json")).unwrap_or_default();
        if replaced {
            assert!(
                !table.exists(),
                "attempt {attempt}: a table beside new runs"
            );
            assert!(!record.contains("comparison.csv"), "{record}");
            // att48-6: exit 130 says which laws hold the new run and that the table is gone
            // until a re-run writes it (it was silent).
            let said = err
                .lines()
                .find(|l| l.starts_with("interrupted: "))
                .unwrap_or_else(|| panic!("attempt {attempt}: nothing said: {err}"));
            assert!(said.contains(laws[0]), "{said}");
            assert!(
                said.contains("comparison.csv holds no comparison"),
                "{said}"
            );
            assert!(said.contains("run the same compare again"), "{said}");
            let removed = "the earlier one was removed";
            assert_eq!(said.contains(removed), !fresh, "attempt {attempt}: {said}");
        } else if let Some(earlier) = &earlier {
            assert_eq!(
                &std::fs::read(&table).unwrap(),
                earlier,
                "attempt {attempt}"
            );
        }
        let a = args(&cmp, "20");
        let o = isotrack_within(&a.iter().map(String::as_str).collect::<Vec<_>>(), 120);
        assert_eq!(
            o.status.code(),
            Some(0),
            "attempt {attempt}: {}",
            common::stderr(&o)
        );
    }
    assert!(caught > 0, "compare was never caught replacing a law");
}

/// att46-2: `compare --out` rewrote `comparison.csv` in place (same inode), so a hard-linked
/// copy of the earlier table silently took the new one. It is replaced as every table is (a
/// new file renamed into place, then recorded): the copy keeps the earlier bytes, the new
/// table is another file holding the new rows (another duration: other results), and a
/// further compare into CMP still takes it for isotrack's.
#[test]
fn compare_replaces_its_table_by_rename() {
    use std::os::unix::fs::MetadataExt;
    let d = tempfile::tempdir().unwrap();
    let cmp = d.path().join("H");
    let o = compare_into(&cmp, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let table = cmp.join("comparison.csv");
    let kept = d.path().join("kept.csv");
    std::fs::hard_link(&table, &kept).unwrap();
    let earlier = std::fs::read(&kept).unwrap();
    let o = compare_into(&cmp, &["--set", "sim.duration_s=22"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    assert_eq!(
        std::fs::read(&kept).unwrap(),
        earlier,
        "the kept copy changed"
    );
    assert_ne!(std::fs::read(&table).unwrap(), earlier);
    assert_ne!(
        std::fs::metadata(&kept).unwrap().ino(),
        std::fs::metadata(&table).unwrap().ino()
    );
    assert_eq!(litter(&cmp), Vec::<String>::new());
    let o = compare_into(&cmp, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
}

/// att48-2: `run --out P --plot` interrupted while drawing left the new run beside the earlier
/// run's figures and said nothing (a plain `run --out` names them). It now says the same note
/// on exit 130: the figures not yet redrawn are from before this run. The signal comes as the
/// trajectory's temporary appears (neither figure redrawn yet).
#[test]
fn ctrl_c_while_run_plots_names_the_figures_from_before() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("p");
    let ps = p.display().to_string();
    let o = isotrack(&[
        "run", SCEN, "--out", &ps, "--quiet", "--plot", "--set", SHORT,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let (attempt, o) =
        run_plot_caught_drawing(|_| p.clone()).expect("run --plot was never caught drawing");
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
    assert!(
        err.contains("also holds trajectory.png, timeseries.png from before this run"),
        "attempt {attempt}: {err}"
    );
    assert!(!err.contains("error"), "attempt {attempt}: {err}");
    assert_eq!(litter(&p), Vec::<String>::new(), "attempt {attempt}");
    // The interrupted run's directory takes the next run.
    let o = isotrack(&[
        "run", SCEN, "--out", &ps, "--quiet", "--plot", "--set", SHORT,
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
}

/// `run SCEN --out P --quiet --plot`, long enough (6000 s) to be caught drawing, interrupted as
/// the trajectory's temporary appears in P (`out(attempt)`), tried up to 6 times
/// ([`common::first_caught`]): the first try caught before it finished, its number and output.
fn run_plot_caught_drawing(out: impl Fn(usize) -> PathBuf) -> Option<(usize, Output)> {
    common::first_caught(6, |attempt| {
        let p = out(attempt);
        let ps = p.display().to_string();
        let args = [
            "run",
            SCEN,
            "--out",
            &ps,
            "--quiet",
            "--plot",
            "--set",
            "sim.duration_s=6000",
        ];
        common::interrupted_when(&args, || !entries(&p, ".trajectory.png.").is_empty())
    })
}

/// att48-5: `run --out a/b/c` (none there) interrupted while running removed `c` but left the
/// parents `a/b` and `a` it created; `plot RUN --out x/y` interrupted while drawing left the
/// directories it created. Every level the command created is removed (innermost first).
#[test]
fn ctrl_c_leaves_no_directory_the_command_created() {
    let d = tempfile::tempdir().unwrap();
    let top = d.path().join("a");
    let c = top.join("b").join("c");
    let cs = c.display().to_string();
    let args = [
        "run",
        SCEN,
        "--out",
        &cs,
        "--quiet",
        "--set",
        "sim.duration_s=30000",
    ];
    let o = common::interrupted_when(&args, || !entries(&c, ".trace.csv.").is_empty());
    assert_eq!(o.status.code(), Some(130), "{}", common::stderr(&o));
    assert!(!top.exists(), "{} left", top.display());
    assert!(d.path().is_dir());
    // A run long enough to catch plot drawing it, drawn into a new x/y.
    let r = d.path().join("r");
    let rs = r.display().to_string();
    let o = isotrack(&[
        "run",
        SCEN,
        "--out",
        &rs,
        "--quiet",
        "--set",
        "sim.duration_s=6000",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let mut caught = false;
    for attempt in 0..6 {
        let x = d.path().join(format!("x{attempt}"));
        let y = x.join("y");
        let ys = y.display().to_string();
        let o = common::interrupted_when(&["plot", &rs, "--out", &ys], || {
            !entries(&y, ".trajectory.png.").is_empty()
        });
        if o.status.code() == Some(0) {
            continue;
        }
        assert_eq!(o.status.code(), Some(130), "{}", common::stderr(&o));
        caught = true;
        assert!(!x.exists(), "attempt {attempt}: {} left", x.display());
    }
    assert!(caught, "plot was never caught drawing");
}

/// The files of a sweep directory once its manifest is in place (a merge's too), by name.
const SWEEP_DIR: [&str; 4] = [
    "base_scenario.toml",
    "results.csv",
    "sweep.json",
    "sweep.toml",
];

/// att51-3: `sweep --out a/b/c` (none there) interrupted in its first milliseconds left the
/// empty `a`, `a/b`, `a/b/c` it created, or `c` holding `sweep.json` alone (or beside
/// `sweep.toml`) with a false "error: cannot write a/b/c: No such file or directory", and said
/// nothing. Signalled once `a` exists: after exit 130, either nothing of it is left and it says
/// "nothing written", or `c` holds its manifest whole with the header of results.csv (no lock,
/// no temporary) and it says 0 of 4 runs; never an error. Signalled once `sweep.json` is there
/// (the manifest's step under way): always the manifest whole.
#[test]
fn an_interrupted_sweep_leaves_its_manifest_whole_or_nothing_and_says_so() {
    let d = tempfile::tempdir().unwrap();
    let sw = write(
        d.path(),
        "sw.toml",
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 30000.0\n[grid]\ncontroller.kp = [5.0, 10.0, 20.0, 40.0]\n"
        ),
    );
    let whole = |c: &Path, err: &str, why: &str| {
        assert_eq!(entries(c, ""), SWEEP_DIR, "{why}: {err}");
        let results = std::fs::read_to_string(c.join("results.csv")).unwrap();
        assert_eq!(results.lines().count(), 1, "{why}: {results}");
        let said = format!(
            "interrupted: {} holds 0 of 4 runs; the same sweep with `--resume` continues",
            c.display()
        );
        assert!(err.contains(&said), "{why}: {err}");
    };
    for attempt in 0..4 {
        let top = d.path().join(format!("a{attempt}"));
        let c = top.join("b").join("c");
        let cs = c.display().to_string();
        let args = ["sweep", &sw, "--out", &cs, "--threads", "1"];
        let o = common::interrupted_when(&args, || top.exists());
        let err = common::stderr(&o);
        assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
        assert!(!err.contains("error"), "attempt {attempt}: {err}");
        if top.exists() {
            whole(&c, &err, &format!("attempt {attempt}"));
        } else {
            let said = format!("interrupted: nothing written to {cs}");
            assert!(err.contains(&said), "attempt {attempt}: {err}");
        }
    }
    let c = d.path().join("m").join("b").join("c");
    let cs = c.display().to_string();
    let args = ["sweep", &sw, "--out", &cs, "--threads", "1"];
    let o = common::interrupted_when(&args, || c.join("sweep.json").exists());
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(!err.contains("error"), "{err}");
    whole(&c, &err, "once sweep.json is there");
}

/// att51-6: `merge H1 H2 --out a/b/c` interrupted a few milliseconds in left `c` holding
/// results.csv without sweep.json (the same merge then refused 73, `sweep --resume` called it
/// an older isotrack's), or the empty levels it created, with no word. Signalled once `a`
/// exists: after exit 130, nothing of it is left ("nothing written"), or `c` holds the merged
/// table with its whole manifest (no lock, no temporary) and says so; never an error.
#[test]
fn an_interrupted_merge_leaves_its_table_with_its_manifest_or_nothing() {
    let d = tempfile::tempdir().unwrap();
    let seeds: Vec<String> = (1..=200).map(|k| k.to_string()).collect();
    let sw = write(
        d.path(),
        "sw.toml",
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 2.0\n[grid]\nsim.seed = [{}]\n",
            seeds.join(", ")
        ),
    );
    let (h1, h2) = (d.path().join("H1"), d.path().join("H2"));
    common::swept(&sw, &h1, &["--shard", "1/2"]);
    common::swept(&sw, &h2, &["--shard", "2/2"]);
    let (h1, h2) = (h1.display().to_string(), h2.display().to_string());
    let mut caught = 0;
    for attempt in 0..10 {
        let top = d.path().join(format!("a{attempt}"));
        let c = top.join("b").join("c");
        let cs = c.display().to_string();
        let o = common::interrupted_when(&["merge", &h1, &h2, "--out", &cs], || top.exists());
        let err = common::stderr(&o);
        if o.status.code() == Some(0) {
            continue;
        }
        caught += 1;
        assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
        assert!(!err.contains("error"), "attempt {attempt}: {err}");
        if top.exists() {
            assert_eq!(entries(&c, ""), SWEEP_DIR, "attempt {attempt}: {err}");
            let said = format!("interrupted after the merge was written: {cs} holds its 200 runs");
            assert!(err.contains(&said), "attempt {attempt}: {err}");
        } else {
            let said = format!("interrupted: nothing written to {cs}");
            assert!(err.contains(&said), "attempt {attempt}: {err}");
        }
    }
    assert!(caught > 0, "the merge was never interrupted");
}

/// att51-4: `benchmark --out a/b/c` interrupted before its first task finished left the empty
/// `a/b/c/tasks/TASK` chain it created and said nothing. Signalled once `a` exists: after exit
/// 130 every level it created is gone and it says no task finished; a task that did finish
/// is there whole (its results.csv beside its task.json) and counted.
#[test]
fn an_interrupted_benchmark_leaves_no_empty_directory_and_says_0() {
    let d = tempfile::tempdir().unwrap();
    let suite = concat!(env!("CARGO_MANIFEST_DIR"), "/../../suites/standard-v1.toml");
    let top = d.path().join("a");
    let c = top.join("b").join("c");
    let cs = c.display().to_string();
    let args = ["benchmark", suite, "--out", &cs, "--threads", "1"];
    let o = common::interrupted_when(&args, || top.exists());
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    let tasks = entries(&c.join("tasks"), "");
    for t in &tasks {
        assert_eq!(
            entries(&c.join("tasks").join(t), ""),
            ["results.csv", "task.json"],
            "{err}"
        );
    }
    if tasks.is_empty() {
        assert!(!top.exists(), "{} left: {err}", top.display());
        let said = format!("interrupted before any task finished: nothing written to {cs}");
        assert!(err.contains(&said), "{err}");
    } else {
        let n = tasks.len();
        let said = format!("interrupted: {cs} holds {n} of the 10 tasks finished");
        assert!(err.contains(&said), "{err}");
    }
}

/// att51-2: `run --out NEW --plot` interrupted while drawing, with no earlier figures in NEW,
/// said nothing of the figures. It says they were not drawn and what draws them.
#[test]
fn ctrl_c_while_drawing_says_which_figures_are_not_drawn() {
    let d = tempfile::tempdir().unwrap();
    let p_of = |attempt: usize| d.path().join(format!("p{attempt}"));
    let (attempt, o) = run_plot_caught_drawing(p_of).expect("run --plot was never caught drawing");
    let (p, err) = (p_of(attempt), common::stderr(&o));
    assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
    let said = format!(
        "interrupted before the figures were drawn: `isotrack plot {}` draws them",
        p.display()
    );
    assert!(err.contains(&said), "attempt {attempt}: {err}");
    assert!(!p.join("trajectory.png").exists());
}

/// att49-7: a directory holding another suite's benchmark (its suite.toml names `standard`
/// version 2) was advised "pass --resume to reuse its task results", and `--resume` then
/// reused nothing and replaced every result. Both are refused 73 naming the two suites.
/// att49-9: the refusal names the directory quoted for a shell, as it quotes the file.
#[test]
fn a_benchmark_of_another_suite_is_refused_and_the_directory_quoted() {
    let d = tempfile::tempdir().unwrap();
    let suite = concat!(env!("CARGO_MANIFEST_DIR"), "/../../suites/standard-v1.toml");
    let v2 = d.path().join("sp ace");
    std::fs::create_dir(&v2).unwrap();
    write(
        &v2,
        "suite.toml",
        "# The suite as run by isotrack 0.1.0 (suites/standard-v2.toml)\nname = \"standard\"\nversion = 2\n",
    );
    let q = format!("'{}'", v2.display());
    let qf = format!("'{}'", v2.join("suite.toml").display());
    for extra in [&[][..], &["--resume"][..]] {
        let mut args = vec!["benchmark", suite, "--out", v2.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = isotrack_within(&args, 60);
        assert_fails(
            &o,
            73,
            &[
                &format!("{q} holds a benchmark of another suite ({qf}: `standard` version 2; this one is `standard` version 1)"),
                "--resume would reuse none of its tasks",
            ],
        );
        assert!(!common::stderr(&o).contains("pass --resume"));
    }
    let same = d.path().join("sp ace2");
    std::fs::create_dir(&same).unwrap();
    write(&same, "leaderboard.csv", "rank,controller,overall\n");
    let o = isotrack_within(&["benchmark", suite, "--out", same.to_str().unwrap()], 60);
    let (q2, qf2) = (
        format!("'{}'", same.display()),
        format!("'{}'", same.join("leaderboard.csv").display()),
    );
    assert_fails(
        &o,
        73,
        &[&format!(
            "{q2} already holds a benchmark ({qf2}): pass --resume"
        )],
    );
}

/// att53o-2: `--out u/b/../c` (the user's `u`, no `u/b`): the command made `u/b` to pass
/// through it, the interrupt removed it as empty, and the note then read `u/b/../c` through the
/// missing level: "nothing written" of a directory holding the sweep's manifest (or a
/// benchmark's finished task). The directory is settled once, before anything is created
/// (`u/c`): no `u/b` is made, and the note names `u/c` with what it holds.
#[test]
fn a_parent_step_through_a_level_the_command_made_is_settled_first() {
    let d = tempfile::tempdir().unwrap();
    let u = d.path().join("u");
    std::fs::create_dir(&u).unwrap();
    let sw = write(
        d.path(),
        "sw.toml",
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 30000.0\n[grid]\ncontroller.kp = [5.0, 10.0, 20.0, 40.0]\n"
        ),
    );
    let c = u.join("c");
    let through = u.join("b").join("..").join("c").display().to_string();
    let args = ["sweep", &sw, "--out", &through, "--threads", "1"];
    let o = common::interrupted_when(&args, || c.join("sweep.json").exists());
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert_eq!(entries(&c, ""), SWEEP_DIR, "{err}");
    assert!(!u.join("b").exists(), "{err}");
    let said = format!(
        "interrupted: {} holds 0 of 4 runs; the same sweep with `--resume` continues",
        c.display()
    );
    assert!(err.contains(&said), "{err}");
    assert!(!err.contains("nothing written"), "{err}");
    // A benchmark, once its first task is in place.
    let suite = concat!(env!("CARGO_MANIFEST_DIR"), "/../../suites/standard-v1.toml");
    let e = u.join("e");
    let through = u.join("x").join("..").join("e").display().to_string();
    let args = [
        "benchmark",
        suite,
        "--controllers",
        "pi_isoline",
        "--out",
        &through,
        "--threads",
        "1",
    ];
    let o = common::interrupted_when(&args, || {
        std::fs::read_dir(e.join("tasks"))
            .is_ok_and(|mut r| r.any(|t| t.is_ok_and(|t| t.path().join("task.json").exists())))
    });
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(!u.join("x").exists(), "{err}");
    let n = entries(&e.join("tasks"), "").len();
    assert!(n > 0, "{err}");
    let said = format!(
        "interrupted: {} holds {n} of the 10 tasks finished",
        e.display()
    );
    assert!(err.contains(&said), "{err}");
}

/// The bundled standard-v1 suite.
const STANDARD_V1: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../suites/standard-v1.toml");

/// A finished `benchmark standard-v1 --controllers pi_isoline --out DIR` (10 tasks).
fn benchmarked(dir: &Path) {
    let o = isotrack_within(
        &[
            "benchmark",
            STANDARD_V1,
            "--controllers",
            "pi_isoline",
            "--out",
            dir.to_str().unwrap(),
        ],
        300,
    );
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
}

/// A copy of directory `from` at `to` (`cp -a`).
fn copied(from: &Path, to: &Path) {
    let ok = std::process::Command::new("cp")
        .arg("-a")
        .arg(from)
        .arg(to)
        .status()
        .unwrap();
    assert!(ok.success());
}

/// att53o-9: a benchmark interrupted while it wrote its top-level files left this run's
/// leaderboard.csv (and .md) beside the earlier run's index.html and suite.toml. They are put
/// in place together: signalled the moment the new leaderboard.csv is in place (a `--resume`
/// reusing every task, so each file is renewed), the four are all the earlier run's files or
/// all this run's (told by their inodes), whether the signal came in time (130) or not (0).
#[test]
fn an_interrupted_benchmark_leaves_its_top_level_files_of_one_run() {
    let d = tempfile::tempdir().unwrap();
    let first = d.path().join("first");
    benchmarked(&first);
    let top = [
        "leaderboard.csv",
        "leaderboard.md",
        "index.html",
        "suite.toml",
    ];
    for attempt in 0..4 {
        let b = d.path().join(format!("b{attempt}"));
        copied(&first, &b);
        let before: Vec<_> = top
            .iter()
            .map(|n| isotrack_runs_identity(&b.join(n)))
            .collect();
        let bs = b.display().to_string();
        let args = [
            "benchmark",
            STANDARD_V1,
            "--controllers",
            "pi_isoline",
            "--out",
            &bs,
            "--resume",
        ];
        let csv = b.join("leaderboard.csv");
        let o = common::interrupted_when(&args, || isotrack_runs_identity(&csv) != before[0]);
        let err = common::stderr(&o);
        let renewed: Vec<bool> = top
            .iter()
            .zip(&before)
            .map(|(n, was)| isotrack_runs_identity(&b.join(n)) != *was)
            .collect();
        assert!(
            matches!(o.status.code(), Some(0 | 130)),
            "attempt {attempt}: {err}"
        );
        assert!(
            renewed.iter().all(|r| *r == renewed[0]),
            "attempt {attempt}: {top:?} renewed {renewed:?}: {err}"
        );
        assert!(litter(&b).is_empty(), "attempt {attempt}: {:?}", litter(&b));
    }
}

/// The device and inode of the file at `p` (`None` when absent).
fn isotrack_runs_identity(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::symlink_metadata(p)
        .ok()
        .map(|m| (m.dev(), m.ino()))
}

/// att53o-3, -7: a benchmark directory whose stored tasks `--resume` would not reuse (another
/// `--controllers` set: the digest covers it; and so with its suite.toml gone) was advised
/// "pass --resume to reuse its task results", and `--resume` then replaced every task without
/// a word. The advice is given only where `--resume` reuses a stored task, naming how many;
/// where it reuses none, the refusal says so and how to keep them; `--resume` that replaces
/// stored tasks says how many of them it reuses and which it replaces. The same run is still
/// advised `--resume`, plainly.
#[test]
fn a_benchmark_advises_resume_only_where_it_reuses_results() {
    let d = tempfile::tempdir().unwrap();
    let a = d.path().join("a");
    benchmarked(&a);
    let aq = a.to_str().unwrap();
    let bench = |controllers: &str, extra: &[&str]| {
        let mut args = vec![
            "benchmark",
            STANDARD_V1,
            "--controllers",
            controllers,
            "--out",
            aq,
        ];
        args.extend_from_slice(extra);
        isotrack_within(&args, 300)
    };
    let o = bench("pi_isoline", &[]);
    assert_fails(&o, 73, &["pass --resume to reuse its task results"]);
    let none = "whose 10 stored tasks are another run's (another controller set";
    let keep =
        "--resume would reuse none of them and replace them all; choose another --out to keep them";
    let o = bench("pid", &[]);
    assert_fails(&o, 73, &[none, keep]);
    assert!(!common::stderr(&o).contains("pass --resume"));
    // Its suite.toml gone: the same.
    std::fs::rename(a.join("suite.toml"), d.path().join("suite.toml")).unwrap();
    let o = bench("pid", &[]);
    assert_fails(&o, 73, &[none, keep]);
    // One task of another digest: --resume reuses 9 of 10, and says so.
    let task = a.join("tasks/circular-1hz/task.json");
    let mut t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&task).unwrap()).unwrap();
    t["digest"] = serde_json::json!("0".repeat(64));
    std::fs::write(&task, t.to_string()).unwrap();
    let o = bench("pi_isoline", &[]);
    assert_fails(
        &o,
        73,
        &["pass --resume to reuse 9 of its 10 stored tasks (the results of circular-1hz are another run's and would be replaced)"],
    );
    let o = bench("pi_isoline", &["--resume"]);
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let said = format!("note: --resume reuses 9 of the 10 tasks {aq} holds; the results of 1 (circular-1hz) are another run's");
    assert!(err.contains(&said), "{err}");
    // Another controller set with --resume: every task replaced, said.
    let o = bench("pid", &["--resume"]);
    let err = common::stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let said = format!("note: --resume reuses 0 of the 10 tasks {aq} holds; the results of 10 (circular-100hz, circular-1hz, plumes-noisy-10hz and 7 more) are another run's");
    assert!(err.contains(&said), "{err}");
}

/// att53o-1: `sweep --resume` interrupted before it renewed the table said "nothing written"
/// of a directory holding the 100 runs it resumed. Signalled once it holds the directory's
/// lock (before or after the renewal), it says how many of the 400 runs DIR holds, at least
/// the 100 it began with, and that `--resume` continues.
#[test]
fn an_interrupted_sweep_resume_counts_the_runs_it_continues() {
    let d = tempfile::tempdir().unwrap();
    let seeds: Vec<String> = (1..=400).map(|k| k.to_string()).collect();
    let sw = write(
        d.path(),
        "sw.toml",
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 2.0\n[grid]\nsim.seed = [{}]\n",
            seeds.join(", ")
        ),
    );
    let full = d.path().join("full");
    common::swept(&sw, &full, &[]);
    let text = std::fs::read_to_string(full.join("results.csv")).unwrap();
    let cut: String = text.lines().take(101).map(|l| format!("{l}\n")).collect();
    let mut caught = 0;
    for attempt in 0..4 {
        let r = d.path().join(format!("r{attempt}"));
        copied(&full, &r);
        std::fs::write(r.join("results.csv"), &cut).unwrap();
        let rs = r.display().to_string();
        let args = ["sweep", &sw, "--out", &rs, "--resume", "--threads", "1"];
        let o = common::interrupted_when(&args, || r.join(".isotrack.lock").exists());
        let err = common::stderr(&o);
        if o.status.code() == Some(0) {
            continue;
        }
        assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
        caught += 1;
        assert!(!err.contains("nothing written"), "attempt {attempt}: {err}");
        let rows = std::fs::read_to_string(r.join("results.csv"))
            .unwrap()
            .lines()
            .count()
            - 1;
        assert!(rows >= 100, "attempt {attempt}: {rows}");
        let said = format!(
            "interrupted: {rs} holds {rows} of 400 runs; the same sweep with `--resume` continues"
        );
        assert!(err.contains(&said), "attempt {attempt}: {err}");
    }
    assert!(caught > 0, "the sweep was never interrupted");
}

/// att53o-4: the lock refusal (benchmark, sweep), a FIFO at a benchmark's suite.toml, and
/// sweep's and merge's "results.csv exists" printed the directory raw: a name with a line
/// break cut the message in two lines. Each names it as one shell word (`$'...'`), on one line.
#[test]
fn refusals_name_a_directory_with_a_line_break_as_one_word() {
    let d = tempfile::tempdir().unwrap();
    let n = d.path().join("n l\nx");
    let q = |p: &Path| format!("$'{}'", p.display().to_string().replace('\n', "\\x0a"));
    let one_line = |o: &std::process::Output| {
        let err = common::stderr(o);
        assert_eq!(err.lines().filter(|l| !l.is_empty()).count(), 1, "{err}");
    };
    // Locked.
    let lock = hold_lock(&n);
    let o = isotrack_within(
        &["benchmark", STANDARD_V1, "--out", n.to_str().unwrap()],
        60,
    );
    assert_fails(&o, 73, &[&format!("{}: another isotrack", q(&n))]);
    one_line(&o);
    drop(lock);
    // A FIFO at suite.toml.
    fifo(&n, "suite.toml");
    let o = isotrack_within(
        &["benchmark", STANDARD_V1, "--out", n.to_str().unwrap()],
        60,
    );
    assert_fails(
        &o,
        73,
        &[&format!(
            "{} exists and is not a regular file",
            q(&n.join("suite.toml"))
        )],
    );
    one_line(&o);
    // A sweep's and a merge's results.csv there.
    let sw = write(
        d.path(),
        "sw.toml",
        &format!(
            "scenario = {SCEN:?}\n[base]\nsim.duration_s = 2.0\n[grid]\ncontroller.kp = [5.0]\n"
        ),
    );
    let s = d.path().join("s l\nx");
    common::swept(&sw, &s, &[]);
    let o = isotrack(&["sweep", &sw, "--out", s.to_str().unwrap()]);
    assert_fails(
        &o,
        73,
        &[&format!(
            "{} exists: pass --resume",
            q(&s.join("results.csv"))
        )],
    );
    one_line(&o);
    let m = d.path().join("m l\nx");
    let o = isotrack(&["merge", s.to_str().unwrap(), "--out", m.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", common::stderr(&o));
    let o = isotrack(&["merge", s.to_str().unwrap(), "--out", m.to_str().unwrap()]);
    assert_fails(
        &o,
        73,
        &[&format!(
            "{} exists: pass --force",
            q(&m.join("results.csv"))
        )],
    );
    one_line(&o);
}

/// att53o-5: `run --out NEW --plot` interrupted after the run was in place, while its trace
/// was read back for the figures, exited 130 without a word of them (the note was registered
/// once the trace was read). Signalled as soon as the run's summary.json is there, it says
/// the figures are not drawn (or which are), and how to draw them.
#[test]
fn ctrl_c_while_plot_reads_the_run_says_the_figures_are_not_drawn() {
    let d = tempfile::tempdir().unwrap();
    let mut caught = 0;
    for attempt in 0..3 {
        let p = d.path().join(format!("p{attempt}"));
        let ps = p.display().to_string();
        let args = [
            "run",
            SCEN,
            "--out",
            &ps,
            "--quiet",
            "--plot",
            "--set",
            "sim.duration_s=30000",
        ];
        let o = common::interrupted_when(&args, || p.join("summary.json").exists());
        let err = common::stderr(&o);
        if o.status.code() == Some(0) {
            continue;
        }
        assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
        caught += 1;
        let before = format!("interrupted before the figures were drawn: `isotrack plot {ps}`");
        assert!(
            err.contains(&before) || err.contains("interrupted while drawing the figures"),
            "attempt {attempt}: {err}"
        );
    }
    assert!(caught > 0, "run --plot was never interrupted");
}
