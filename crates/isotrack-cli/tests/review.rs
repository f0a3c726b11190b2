//! The hostile review's leftovers of issue 30, end to end: messages that echo the user's own
//! value exactly, user text with terminal controls escaped, locks released after a failed
//! command, 66 for every unreadable file named inside another, reads counted on bytes read,
//! `benchmark --out` locked, "did you mean" for unknown keys, and the flat-start warning.
mod common;
use common::{assert_fails, isotrack, isotrack_within, stderr, write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Item 1: a value the user wrote is echoed as written (`got -1.0000001`, not `got -1`), and a
/// tiny rate is never a 300-digit decimal; computed values are rounded (no line of the error
/// has a run of more than 17 digits).
#[test]
fn messages_echo_the_users_value_as_written() {
    let o = isotrack(&["run", "--set", "controller.kp=-1.0000001"]);
    assert_fails(&o, 65, &["`controller.kp`: must be > 0, got -1.0000001"]);
    let o = isotrack(&["run", "--set", "sensor.rate_hz=1e-300"]);
    assert_fails(&o, 65, &["the sample period 1/1e-300 s"]);
    let o = isotrack(&["run", "--set", "sim.dt_s=1e-300"]);
    assert_eq!(o.status.code(), Some(65));
    for o in [&o, &isotrack(&["run", "--set", "sensor.rate_hz=1e-300"])] {
        let e = stderr(o);
        let longest_digits = e
            .split(|c: char| !c.is_ascii_digit())
            .map(str::len)
            .max()
            .unwrap_or(0);
        assert!(longest_digits <= 17, "{e}");
        // The baselines' warnings name their tube and its gammas (about 470 characters); the
        // console bounds every line at 1000.
        assert!(e.lines().all(|l| l.len() < 1000), "{e}");
    }
    let o = isotrack(&["check", "--tube-halfwidth=-0.000000123456789"]);
    assert_fails(&o, 64, &["got -1.23456789e-7"]);
    let d = tempfile::tempdir().unwrap();
    let inputs = write(
        d.path(),
        "in.csv",
        "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,0,0,0,0.5\n",
    );
    let out = d.path().join("o.csv").display().to_string();
    let o = isotrack(&[
        "replay",
        "--inputs",
        &inputs,
        "--out",
        &out,
        "--altitude-m",
        "1e300",
    ]);
    assert_fails(&o, 64, &["got 1e300"]);
}

/// Item 2: user text with terminal controls (ESC, BEL, CR, C1, bidi overrides) is escaped on
/// its way to standard error and standard output; the raw bytes never reach the terminal.
#[test]
fn terminal_controls_in_user_text_are_escaped() {
    let raw = |o: &std::process::Output| {
        let all = [o.stdout.as_slice(), o.stderr.as_slice()].concat();
        let text = String::from_utf8_lossy(&all).into_owned();
        assert!(
            !text
                .chars()
                .any(|c| matches!(c, '\u{1b}' | '\u{7}' | '\r' | '\u{9b}' | '\u{202e}')),
            "{text:?}"
        );
        text
    };
    let o = isotrack(&["run", "--set", "controller.k\u{1b}[31mp\u{7}=1"]);
    assert_eq!(o.status.code(), Some(65));
    let e = raw(&o);
    assert!(e.contains("controller.k\\x1b[31mp\\x07"), "{e}");
    let o = isotrack(&["run", "/nonexistent/evil\u{202e}lmth.\r\u{9b}.toml"]);
    assert_eq!(o.status.code(), Some(66));
    let e = raw(&o);
    assert!(e.contains("evil\\u{202e}lmth.\\x0d\\u{9b}.toml"), "{e}");
    // A scenario file whose name carries them, run: its name on standard output is escaped.
    let d = tempfile::tempdir().unwrap();
    let name = "s\u{1b}]0;owned\u{7}.toml";
    let sc = write(d.path(), name, "[sim]\nduration_s = 1.0\n");
    let o = isotrack(&["run", &sc]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = raw(&o);
    assert!(out.contains("s\\x1b]0;owned\\x07.toml"), "{out}");
    // A value inside a file (a grid path, the escape written as TOML spells it).
    let sc = write(
        d.path(),
        "g.toml",
        "[field]\nkind = \"grid\"\npath = \"no\\u001b[2Jsuch.csv\"\n",
    );
    let o = isotrack(&["run", &sc]);
    assert_eq!(o.status.code(), Some(66));
    assert!(raw(&o).contains("no\\x1b[2Jsuch.csv"), "{}", raw(&o));
    // A unit with an escape is refused (issue 30, fix30c: one plain-text rule for every
    // source), its text escaped in the message.
    let o = isotrack(&["show", "--set", "field.units=a\u{1b}b"]);
    assert_eq!(o.status.code(), Some(65));
    assert!(raw(&o).contains("a\\x1bb"), "{}", raw(&o));
}

/// Whether some process holds the lock of `dir` (probed with a shared lock, released at once).
fn locked(dir: &Path) -> bool {
    match std::fs::File::open(dir.join(".isotrack.lock")) {
        Ok(f) => matches!(f.try_lock_shared(), Err(std::fs::TryLockError::WouldBlock)),
        Err(_) => false,
    }
}

/// Item 4: a failed `merge` and a sweep stopped by Ctrl-C leave no lock: the next command on
/// the directory is not refused. (The review's report did not reproduce as a refusal: the
/// lock is an OS lock on the file, released on every exit; the file left behind is not a
/// lock. This pins it.)
#[cfg(unix)]
#[test]
fn a_failed_or_interrupted_command_leaves_no_lock() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("m");
    let out_s = out.display().to_string();
    let empty = d.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    for _ in 0..2 {
        let o = isotrack(&["merge", empty.to_str().unwrap(), "--out", &out_s]);
        assert_fails(&o, 66, &["no readable sweep.json"]);
        assert!(!locked(&out));
    }
    let scen = repo().join("scenarios/paper-fig2b-circular.toml");
    let small = write(
        d.path(),
        "small.toml",
        &format!(
            "scenario = {:?}\n[base]\nsim.duration_s = 2.0\n[grid]\nsim.seed = [1, 2]\n",
            scen.display().to_string()
        ),
    );
    let o = isotrack(&["sweep", &small, "--out", &out_s]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A sweep interrupted by SIGINT (Ctrl-C) while it holds the lock.
    let long = write(
        d.path(),
        "long.toml",
        &format!(
            "scenario = {:?}\n[random]\nruns = 4000\nseed = 5\ninitial.x_m = {{ uniform = [-12.0, 12.0] }}\n",
            scen.display().to_string()
        ),
    );
    let dir2 = d.path().join("s");
    let dir2_s = dir2.display().to_string();
    let mut first = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sweep", &long, "--out", &dir2_s, "--threads", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !locked(&dir2) {
        assert!(t0.elapsed() < Duration::from_secs(60), "never locked");
        assert!(first.try_wait().unwrap().is_none(), "ended before caught");
        std::thread::sleep(Duration::from_millis(5));
    }
    let ok = Command::new("kill")
        .args(["-INT", &first.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let status = first.wait().unwrap();
    assert!(!status.success());
    assert!(!locked(&dir2), "Ctrl-C left the lock held");
    // Issue 30 (att30b item 10): nor the lock file (README: "the holder removes the file when
    // done (an error and Ctrl-C included)"); the exit code is 130, 128 + SIGINT.
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert!(
        !dir2.join(".isotrack.lock").exists(),
        "Ctrl-C left the lock file"
    );
    let o = isotrack(&["sweep", &small, "--out", &dir2_s, "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Issue 30 (att30b item 10): `run --out` stopped by Ctrl-C (SIGINT), SIGTERM or SIGHUP while
/// it streams the trace leaves neither `.isotrack.lock` nor its `.trace.csv.PID.tmp`, and exits
/// 130 / 143 / 129 (128 + the signal); a temporary file a killed run left (its PID gone) is removed
/// by the next `run --out` into the directory.
#[cfg(unix)]
#[test]
fn an_interrupted_run_out_leaves_no_lock_file_nor_temporary_trace() {
    let d = tempfile::tempdir().unwrap();
    let temporaries = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .map(|it| {
                it.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.ends_with(".tmp") || n == ".isotrack.lock")
                    .collect()
            })
            .unwrap_or_default()
    };
    // SIGHUP (a closed terminal or ssh session) as SIGTERM: 129 (att30c-7).
    for (signal, code) in [("-INT", 130), ("-TERM", 143), ("-HUP", 129)] {
        let out = d.path().join(format!("r{code}"));
        let out_s = out.display().to_string();
        // 1e6 s at 100 Hz recorded: minutes of trace.
        let mut run = Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .args(["run", "--set", "sim.duration_s=1e6", "--out", &out_s])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let t0 = Instant::now();
        while !temporaries(&out)
            .iter()
            .any(|n| n.starts_with(".trace.csv."))
        {
            assert!(t0.elapsed() < Duration::from_secs(60), "no temporary trace");
            assert!(run.try_wait().unwrap().is_none(), "ended before caught");
            std::thread::sleep(Duration::from_millis(5));
        }
        let ok = Command::new("kill")
            .args([signal, &run.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
        let status = run.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{signal}: {status:?}");
        assert_eq!(temporaries(&out), Vec::<String>::new(), "{signal}");
    }
    // The interrupted runs created their directories: removed again, empty (att46-10).
    for code in [130, 143, 129] {
        assert!(!d.path().join(format!("r{code}")).exists(), "r{code} left");
    }
    // A temporary trace of a process that is gone (killed with SIGKILL, which nothing can
    // answer) is removed by the next run into the directory; another name is kept.
    let out = d.path().join("r130");
    std::fs::create_dir(&out).unwrap();
    let mut gone = Command::new("true").spawn().unwrap();
    let pid = gone.id();
    gone.wait().unwrap();
    std::fs::write(out.join(format!(".trace.csv.{pid}.tmp")), "t_s\n").unwrap();
    std::fs::write(out.join("notes.tmp"), "mine").unwrap();
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=1",
        "--out",
        &out.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(temporaries(&out), vec!["notes.tmp".to_string()]);
}

/// att30c-7 (a): a SIGINT the command was started with ignored (`trap '' INT`, a script's
/// `cmd &`) stays ignored, as shells expect: Ctrl-C does not stop `run --out`; SIGTERM still
/// does, removing its temporary trace and lock file (143).
#[cfg(unix)]
#[test]
fn an_inherited_ignored_sigint_stays_ignored() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("r");
    let litter = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .map(|it| {
                it.flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.ends_with(".tmp") || n == ".isotrack.lock")
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut run = Command::new("sh")
        .args([
            "-c",
            "trap '' INT; exec \"$0\" run --set sim.duration_s=1e6 --out \"$1\"",
            env!("CARGO_BIN_EXE_isotrack"),
            &out.display().to_string(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !litter(&out).iter().any(|n| n.starts_with(".trace.csv.")) {
        assert!(t0.elapsed() < Duration::from_secs(60), "no temporary trace");
        assert!(run.try_wait().unwrap().is_none(), "ended before caught");
        std::thread::sleep(Duration::from_millis(5));
    }
    let pid = run.id().to_string();
    let kill = |signal: &str| {
        let ok = Command::new("kill").args([signal, &pid]).status().unwrap();
        assert!(ok.success());
    };
    kill("-INT");
    std::thread::sleep(Duration::from_millis(500));
    assert!(
        run.try_wait().unwrap().is_none(),
        "an ignored SIGINT stopped the run"
    );
    kill("-TERM");
    let status = run.wait().unwrap();
    assert_eq!(status.code(), Some(143), "{status:?}");
    assert_eq!(litter(&out), Vec::<String>::new());
}

/// Item 5: a FIFO, a directory or a device named inside a file (a scenario's `field.path` or
/// `field.paths`, a suite task's scenario, a sweep's base scenario) exits 66 like one named on
/// the command line; a benchmark task's FIFO scenario once exited 65.
#[cfg(unix)]
#[test]
fn unreadable_files_named_inside_files_exit_66() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let fifo = common::fifo(p, "f.toml");
    let fifo_csv = common::fifo(p, "f.csv");
    let dir = p.join("adir.csv");
    std::fs::create_dir(&dir).unwrap();
    let grid = |name: &str, path: &str| {
        write(
            p,
            name,
            &format!("[field]\nkind = \"grid\"\npath = {path:?}\nformat = \"csv\"\n"),
        )
    };
    let by_fifo = grid("g1.toml", &fifo_csv);
    let by_dir = grid("g2.toml", dir.to_str().unwrap());
    let by_dev = grid("g3.toml", "/dev/zero");
    let missing = grid("g4.toml", "/nonexistent/g.csv");
    for sc in [&by_fifo, &by_dir, &by_dev, &missing] {
        let o = isotrack_within(&["run", sc], 20);
        assert_fails(&o, 66, &["field.path"]);
    }
    let paths = write(
        p,
        "g5.toml",
        &format!(
            "[field]\nkind = \"grid\"\npaths = [{:?}, \"/dev/zero\"]\nframe_times_s = [0.0, 1.0]\nformat = \"csv\"\n",
            repo().join("data/volcano/volcano.csv").display().to_string()
        ),
    );
    assert_fails(&isotrack_within(&["run", &paths], 20), 66, &["field.paths"]);
    // A sweep whose base scenario names a FIFO grid.
    let sw = write(
        p,
        "sw.toml",
        "scenario = \"g1.toml\"\n[grid]\nsim.seed = [1, 2]\n",
    );
    let out = p.join("out").display().to_string();
    assert_fails(
        &isotrack_within(&["sweep", &sw, "--out", &out], 20),
        66,
        &["field.path"],
    );
    // A suite whose task scenario is a FIFO, or names one.
    for (name, scen) in [("s1.toml", fifo.as_str()), ("s2.toml", by_fifo.as_str())] {
        let suite = write(
            p,
            name,
            &format!(
                "name = \"x\"\nversion = 1\ncontrollers = [\"pi_isoline\"]\ntuning_seeds = [7]\nscoring_seeds = [1]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = {scen:?}\nlength_m = 6.93\n"
            ),
        );
        let b = p.join(format!("b-{name}")).display().to_string();
        let o = isotrack_within(&["benchmark", &suite, "--out", &b], 20);
        assert_fails(&o, 66, &["task a", "not a regular file"]);
    }
    // replay --inputs a directory.
    let o = isotrack(&["replay", "--inputs", dir.to_str().unwrap(), "--out", &out]);
    assert_fails(&o, 66, &["not a regular file"]);
}

/// Item 6: a `/proc` file declares 0 bytes: read as a CSV grid, `/proc/self/pagemap` took 11 s
/// and 4 GiB of memory before failing, then (att41-22: the data file read whole) 7 s to the
/// grid's size cap before the kernel's EINVAL. Now every input path refuses a kernel
/// pseudo-file (`/proc`, `/sys`: its filesystem, asked before a byte is read) with 66, naming
/// the file, the key or argument and what it is: a field's `path`, the scenario itself,
/// `replay --inputs`, `interpolate`'s stations, a sweep's file.
#[cfg(target_os = "linux")]
#[test]
fn proc_files_are_refused_quickly() {
    let d = tempfile::tempdir().unwrap();
    if !Path::new("/proc/self/pagemap").exists() {
        return;
    }
    let pseudo = "kernel pseudo-file on /proc";
    let sc = write(
        d.path(),
        "pm.toml",
        "[field]\nkind = \"grid\"\npath = \"/proc/self/pagemap\"\nformat = \"csv\"\n",
    );
    let o = isotrack_within(&["run", &sc], 20);
    assert_fails(&o, 66, &["field.path", "pagemap", pseudo]);
    let o = isotrack_within(&["check", &sc], 20);
    assert_fails(&o, 66, &["field.path", "pagemap", pseudo]);
    let o = isotrack_within(&["run", "/proc/self/maps"], 20);
    assert_fails(&o, 66, &["/proc/self/maps", pseudo]);
    let out = d.path().join("r.csv").display().to_string();
    let o = isotrack_within(
        &["replay", "--inputs", "/proc/self/maps", "--out", &out],
        20,
    );
    assert_fails(&o, 66, &["--inputs", "/proc/self/maps", pseudo]);
    let o = isotrack_within(
        &[
            "interpolate",
            "/proc/self/maps",
            "--value-column",
            "v",
            "--out",
            &out,
        ],
        20,
    );
    assert_fails(&o, 66, &["/proc/self/maps", pseudo]);
    let o = isotrack_within(
        &[
            "sweep",
            "/proc/self/maps",
            "--out",
            &d.path().join("s").display().to_string(),
        ],
        20,
    );
    assert_fails(&o, 66, &["/proc/self/maps", pseudo]);
}

/// A one-task suite over the circular scenario, 20 s runs.
fn tiny_suite(dir: &Path) -> String {
    let scen = repo().join("scenarios/paper-fig2b-circular.toml");
    write(
        dir,
        "tiny.toml",
        &format!(
            "name = \"x\"\nversion = 1\ncontrollers = [\"pi_isoline\"]\ntuning_seeds = [7]\nscoring_seeds = [1]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = {:?}\nset = [\"sim.duration_s=20.0\"]\nlength_m = 6.93\n",
            scen.display().to_string()
        ),
    )
}

/// Item 8: `benchmark --out DIR` takes the same lock as `sweep` and `merge`: a second writer
/// exits 73 and writes nothing; the lock goes with the command (a failed one included).
#[test]
fn benchmark_out_is_locked() {
    let d = tempfile::tempdir().unwrap();
    let suite = tiny_suite(d.path());
    let out = d.path().join("b");
    std::fs::create_dir(&out).unwrap();
    let holder = std::fs::File::create(out.join(".isotrack.lock")).unwrap();
    holder.try_lock().unwrap();
    let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 73, &["is writing this directory", ".isotrack.lock"]);
    assert!(!out.join("leaderboard.csv").exists());
    drop(holder);
    let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!locked(&out));
    // A failed one (the directory holds results) leaves it unlocked too.
    let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 73, &["already holds a benchmark"]);
    assert!(!locked(&out));
}

/// Item 9: an unknown key gets the nearest keys of its section; in `[controller]` those of the
/// scenario's controller kind.
#[test]
fn unknown_keys_get_a_did_you_mean() {
    let o = isotrack(&["run", "--set", "controller.kq=1"]);
    assert_fails(&o, 65, &["did you mean `kp` or `ki`?"]);
    let o = isotrack(&[
        "run",
        "--set",
        "controller.kind=pid",
        "--set",
        "controller.kdd=1",
    ]);
    assert_fails(&o, 65, &["controller.kind = \"pid\"", "did you mean `kd`?"]);
    let d = tempfile::tempdir().unwrap();
    let sc = write(d.path(), "t.toml", "[sim]\ndt_sec = 0.01\n");
    let o = isotrack(&["run", &sc]);
    assert_fails(&o, 65, &["t.toml:2:1", "did you mean `dt_s`?"]);
}

/// Item 10: a start far from a plume (flat background: the law circles for the whole run)
/// is warned about by `run` (stderr and summary.json) and `check`, pointing to
/// `controller.search`; the bundled paper scenario is not.
#[test]
fn a_flat_start_is_warned_about() {
    let d = tempfile::tempdir().unwrap();
    let sc = write(
        d.path(),
        "far.toml",
        "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{ center_m = [0.0, 0.0], amplitude = 10.0, sigma_m = [5.0, 5.0], rotation_rad = 0.0 }]\n[controller]\nlevel = 5.0\n[initial]\nx_m = 60.0\n[sim]\nduration_s = 20.0\n",
    );
    let out = d.path().join("run");
    let o = isotrack(&["run", &sc, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("warning: flat background at the start"),
        "{}",
        stderr(&o)
    );
    assert!(stderr(&o).contains("controller.search"));
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(
        summary.contains("flat background at the start"),
        "{summary}"
    );
    let o = isotrack(&["check", &sc]);
    assert!(
        stdout(&o).contains("warning: flat background at the start"),
        "{}",
        stdout(&o)
    );
    let o = isotrack(&["run", &sc, "--set", "controller.search=spiral"]);
    assert!(!stderr(&o).contains("flat background"), "{}", stderr(&o));
    let paper = repo().join("scenarios/paper-fig2b-circular.toml");
    let o = isotrack(&["check", paper.to_str().unwrap()]);
    assert!(!stdout(&o).contains("flat background"), "{}", stdout(&o));
}

/// A hostile review's data loss (found on `check --map`, and `run --out` had it too): a scenario
/// whose grid is `DIR/trace.csv`, or a run re-run into its own directory, had its input replaced
/// by the output, exit 0. Now 64, and the inputs are left as they were.
#[test]
fn run_out_never_writes_over_its_inputs() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    std::fs::create_dir_all(&out).unwrap();
    let grid = out.join("trace.csv");
    std::fs::copy(repo().join("data/volcano/volcano.csv"), &grid).unwrap();
    let before = std::fs::read(&grid).unwrap();
    let text = std::fs::read_to_string(repo().join("scenarios/volcano.toml"))
        .unwrap()
        .replace("../data/volcano/volcano.csv", grid.to_str().unwrap());
    let sc = d.path().join("v.toml");
    std::fs::write(&sc, text).unwrap();
    let o = isotrack(&["run", sc.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_fails(&o, 64, &["an output cannot be one of the inputs"]);
    assert_eq!(
        std::fs::read(&grid).unwrap(),
        before,
        "the grid is untouched"
    );
    // A run directory's own scenario.toml run again into that directory, with an edit.
    let run_dir = d.path().join("r");
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=5",
        "--out",
        run_dir.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let own = run_dir.join("scenario.toml");
    let kept = std::fs::read(&own).unwrap();
    let o = isotrack(&[
        "run",
        own.to_str().unwrap(),
        "--set",
        "sim.duration_s=6",
        "--out",
        run_dir.to_str().unwrap(),
    ]);
    assert_fails(&o, 64, &["scenario.toml", "one of the inputs"]);
    assert_eq!(
        std::fs::read(&own).unwrap(),
        kept,
        "the scenario file is untouched"
    );
}

/// The longest run of digits in `text`.
fn longest_digit_run(text: &str) -> usize {
    text.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

/// Issue 30 item 19, hostile review: an echo of something long the user wrote (a 40 000-character
/// `--set` value, a 5 000-character scenario path, a 100 000-character sweep path) is clipped:
/// no line the command prints is longer than the console's 1 000-character bound plus its
/// `... (N more characters)` tail, and the tail says how much was left out.
#[test]
fn long_echoes_are_clipped() {
    let value = format!("field.center_m={}", "[".repeat(40_000));
    let long_path = "a/".repeat(2_500) + "s.toml";
    let sweep_path = "b".repeat(100_000);
    for (args, code) in [
        (vec!["run", "--set", value.as_str()], 65),
        (vec!["run", long_path.as_str()], 66),
        (vec!["show", long_path.as_str()], 66),
        (
            vec!["sweep", sweep_path.as_str(), "--out", "unused-dir"],
            66,
        ),
    ] {
        let o = isotrack(&args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(code), "{}", &e[..e.len().min(2000)]);
        let longest = e.lines().map(|l| l.chars().count()).max().unwrap_or(0);
        assert!(
            longest <= 1_040,
            "{longest} characters: {}",
            &e[..e.len().min(2000)]
        );
        assert!(
            e.contains("more characters)"),
            "{}",
            &e[..e.len().min(2000)]
        );
        assert!(e.len() < 4_000, "{} bytes", e.len());
    }
}

/// Computed numbers in warnings and notes are rounded (6 significant digits): the sliding-mode
/// warning with `gamma = 1e300` says `mu = gamma*delta = 1e300` (gamma times the default
/// `delta = 1`), not 301 digits; `interpolate --spacing-m 333.58524070059883` reports
/// `333.585 m spacing`.
#[test]
fn computed_numbers_in_messages_are_rounded() {
    let circular = repo().join("scenarios/paper-fig2b-circular.toml");
    let run = [
        "run",
        "--set",
        "controller.kind=sliding_mode",
        "--set",
        "controller.gamma=1e300",
        "--set",
        "sim.duration_s=1",
    ];
    let compare = [
        "compare",
        circular.to_str().unwrap(),
        "--controllers",
        "sliding_mode",
        "--gain",
        "sliding_mode.gamma=1e300",
        "--set",
        "sim.duration_s=1",
    ];
    let d = tempfile::tempdir().unwrap();
    let cmp_out = d.path().join("cmp");
    let compare: Vec<&str> = compare
        .into_iter()
        .chain(["--out", cmp_out.to_str().unwrap()])
        .collect();
    for args in [&run[..], &compare[..]] {
        let o = isotrack(args);
        let e = stderr(&o) + &stdout(&o);
        assert!(e.contains("mu = gamma*delta = 1e300 "), "{e}");
        assert!(longest_digit_run(&e) <= 17, "{e}");
        // The baselines' warnings name their tube and its gammas (about 470 characters); the
        // console bounds every line at 1000.
        assert!(e.lines().all(|l| l.len() < 1000), "{e}");
    }
    let stations = write(
        d.path(),
        "st.csv",
        "x_m,y_m,no2\n0,0,10\n1000,0,20\n0,1000,30\n1000,1000,40\n",
    );
    let out = d.path().join("g.csv");
    let o = isotrack(&[
        "interpolate",
        &stations,
        "--value-column",
        "no2",
        "--method",
        "idw",
        "--spacing-m",
        "333.58524070059883",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s = stdout(&o);
    assert!(s.contains(" 333.585 m spacing"), "{s}");
    assert!(longest_digit_run(&s) <= 9, "{s}");
}

/// An SVG is well-formed XML whatever the title or run directory name holds: XML 1.0 forbids
/// the C0 controls but tab, newline and carriage return even as character references, so
/// `--title $'a\x01b'` and a run directory `rd\x01x` must leave no such byte in the file.
#[test]
fn svg_text_has_no_control_characters() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("rd\u{1}x");
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=5",
        "--out",
        run.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for title in [None, Some("a\u{1}b\u{1f}c\u{8}")] {
        let out = d.path().join(if title.is_some() { "t" } else { "n" });
        let mut args = vec![
            "plot",
            run.to_str().unwrap(),
            "--format",
            "svg",
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(t) = title {
            args.extend(["--title", t]);
        }
        let o = isotrack(&args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let mut svgs = 0;
        for f in std::fs::read_dir(&out).unwrap() {
            let p = f.unwrap().path();
            if p.extension().is_some_and(|e| e == "svg") {
                svgs += 1;
                let bytes = std::fs::read(&p).unwrap();
                assert!(
                    bytes
                        .iter()
                        .all(|&b| b >= 0x20 || matches!(b, b'\t' | b'\n' | b'\r')),
                    "{} holds a control byte",
                    p.display()
                );
                assert!(std::str::from_utf8(&bytes).unwrap().contains("<svg"));
            }
        }
        assert!(svgs > 0);
    }
}

/// `figures --scenarios DIR` whose scenario is missing or a FIFO: 66 (cannot open an input),
/// as for every other command, not 65.
#[test]
fn figures_unreadable_scenario_is_66() {
    let d = tempfile::tempdir().unwrap();
    let missing = d.path().join("none");
    std::fs::create_dir(&missing).unwrap();
    let fifos = d.path().join("fifos");
    std::fs::create_dir(&fifos).unwrap();
    common::fifo(&fifos, "paper-fig2a-field.toml");
    for dir in [&missing, &fifos] {
        let o = isotrack_within(
            &[
                "figures",
                "--scenarios",
                dir.to_str().unwrap(),
                "--out",
                d.path().join("out").to_str().unwrap(),
                "--runs",
                d.path().join("runs").to_str().unwrap(),
            ],
            60,
        );
        assert_fails(&o, 66, &["paper-fig2a-field.toml"]);
    }
}

/// att41-12 SAFETY: `figures --out DIR` replaced the user's own `fig2b.png` (their edited
/// version, no isotrack mark) without a word. A file of a paper figure's name that isotrack did
/// not write is refused (73, naming it) before any run: no run directory made, every file as
/// it was; with `--svg`, the SVGs too. Fails on the source before (exit 0, the file replaced).
#[test]
fn figures_never_replace_a_users_file_named_as_a_figure() {
    let d = tempfile::tempdir().unwrap();
    let scenarios = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    for (name, svg) in [("fig2b.png", false), ("fig3c.svg", true)] {
        let out = d.path().join(format!("out_{svg}"));
        let runs = d.path().join(format!("runs_{svg}"));
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join(name), b"MY FIG").unwrap();
        let mut args = vec![
            "figures",
            "--scenarios",
            scenarios.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--runs",
            runs.to_str().unwrap(),
        ];
        if svg {
            args.push("--svg");
        }
        let o = isotrack_within(&args, 120);
        let named = out.join(name).display().to_string();
        assert_fails(
            &o,
            73,
            &[&named, "not a figure isotrack wrote", "move it away"],
        );
        assert!(!runs.exists(), "a run was made");
        let left: Vec<_> = std::fs::read_dir(&out).unwrap().flatten().collect();
        assert_eq!(left.len(), 1, "{left:?}");
        assert_eq!(std::fs::read(out.join(name)).unwrap(), b"MY FIG");
    }
}

/// Blame and wording: a step so small that the default sensor rate `1/dt` is infinite blames
/// `sim.dt_s`, not the unwritten `sensor.rate_hz`; a suite seed beyond TOML's integers names
/// the range and echoes the value; the PI-like law on a level the field does not attain says
/// so in the verdict; `compare --gain foo.kp=1` names the known kinds.
#[test]
fn blame_and_wording() {
    let o = isotrack(&["run", "--set", "sim.dt_s=1e-320"]);
    assert_fails(&o, 65, &["`sim.dt_s`: got 1e-320"]);
    assert!(!stderr(&o).contains("`sensor.rate_hz`"), "{}", stderr(&o));

    let d = tempfile::tempdir().unwrap();
    let suite = write(
        d.path(),
        "seed.toml",
        "name = \"x\"\nversion = 1\ncontrollers = [\"pi_isoline\"]\ntuning_seeds = []\nscoring_seeds = [1, 9223372036854775808]\n[[task]]\nid = \"a\"\ntitle = \"a\"\nscenario = \"s.toml\"\nlength_m = 1.0\n",
    );
    let out = d.path().join("o");
    let o = isotrack(&["benchmark", &suite, "--out", out.to_str().unwrap()]);
    assert_fails(
        &o,
        65,
        &[
            "seed.toml:5:",
            "scoring_seeds: seeds are integers from 0 to 9223372036854775807",
            "got 9223372036854775808",
        ],
    );
    assert!(!stderr(&o).contains("expected u64"), "{}", stderr(&o));
    let beyond_u64 = write(
        d.path(),
        "big.toml",
        &std::fs::read_to_string(&suite)
            .unwrap()
            .replace("9223372036854775808", "18446744073709551616"),
    );
    let o = isotrack(&["benchmark", &beyond_u64, "--out", out.to_str().unwrap()]);
    assert_fails(
        &o,
        65,
        &[
            "big.toml:5:21: seeds are integers from 0 to 9223372036854775807",
            "got 18446744073709551616",
        ],
    );
    assert!(!out.join("leaderboard.csv").exists());

    let volcano = repo().join("scenarios/volcano.toml");
    let o = isotrack(&[
        "check",
        volcano.to_str().unwrap(),
        "--set",
        "controller.level=1000",
    ]);
    let s = stdout(&o);
    let verdict = s
        .lines()
        .find(|l| l.contains("no guarantee"))
        .unwrap_or_else(|| panic!("{s}"));
    assert!(verdict.contains("not attained"), "{verdict}");
    assert!(!verdict.contains("are for the PI-like law"), "{verdict}");

    let o = isotrack(&["compare", volcano.to_str().unwrap(), "--gain", "foo.kp=1"]);
    assert_fails(
        &o,
        64,
        &[
            "`foo` is not a controller kind",
            "known kinds: ",
            "sliding_mode",
        ],
    );
    let o = isotrack(&[
        "compare",
        volcano.to_str().unwrap(),
        "--gain",
        "sliding_mod.gamma=1",
    ]);
    assert_fails(&o, 64, &["did you mean `sliding_mode`"]);
}

/// `check --map --kp-range 1e-320:1e300`: the refusal echoes the range as the user wrote it
/// (`1e-320`), not the subnormal rounded to 6 digits (`9.99989e-321`).
#[test]
fn map_range_is_echoed_as_written() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("m");
    let o = isotrack(&[
        "check",
        "--map",
        "--kp-range",
        "1e-320:1e300",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = stderr(&o);
    assert!(matches!(o.status.code(), Some(64 | 65)), "{e}");
    assert!(e.contains("1e-320"), "{e}");
    assert!(!e.contains("9.99989e-321"), "{e}");
}

/// Issue 30 (att30b items 3 and 13): the one plain-text rule covers every format character
/// and the line and paragraph separators, and what it refuses is never shown raw. A scenario
/// `name` with U+2028 or U+FFF9 (an invisible interlinear annotation mark) is refused naming
/// the key, the character shown as `\u{fff9}`; a run directory named with U+2028, ESC or
/// U+202E is echoed escaped on the console and in `report.html`'s `<title>` and `<h1>`.
#[test]
fn invisible_and_separator_characters_are_refused_and_never_shown_raw() {
    let d = tempfile::tempdir().unwrap();
    for (cp, ch) in [
        ("2028", '\u{2028}'),
        ("FFF9", '\u{fff9}'),
        ("13430", '\u{13430}'),
    ] {
        let path = write(
            d.path(),
            &format!("s{cp}.toml"),
            &format!("name = \"a{ch}b\"\n[sim]\nduration_s = 1.0\n"),
        );
        let o = isotrack(&["run", &path]);
        assert_fails(&o, 65, &["name", "control or invisible"]);
        let e = stderr(&o);
        assert!(!e.contains(ch), "U+{cp} shown raw: {e}");
        assert!(
            e.contains(&format!("a\\u{{{}}}b", cp.to_lowercase())),
            "U+{cp}: {e}"
        );
    }
    for name in ["r\u{2028}x", "d\u{1b}[31mred", "d\u{202e}evil"] {
        let dir = d.path().join(name);
        let dir_s = dir.display().to_string();
        let o = isotrack(&["run", "--set", "sim.duration_s=1", "--out", &dir_s]);
        assert!(o.status.success(), "{}", stderr(&o));
        let out = String::from_utf8_lossy(&o.stdout).into_owned() + &stderr(&o);
        for c in ['\u{2028}', '\u{1b}', '\u{202e}'] {
            assert!(!out.contains(c), "{name:?}: {out:?}");
        }
        let page = d.path().join("r.html");
        let o = isotrack(&["report", &dir_s, "--out", &page.display().to_string()]);
        assert!(o.status.success(), "{}", stderr(&o));
        let html = std::fs::read_to_string(&page).unwrap();
        for c in ['\u{2028}', '\u{1b}', '\u{202e}'] {
            assert!(
                !html.contains(c),
                "{name:?}: raw U+{:04X} in report.html",
                c as u32
            );
        }
    }
}

/// Issue 30 (att30c-18): one trace check shared by `plot` and `report`. `report` drew a map
/// 1e300 m wide where `plot` refused, and both took a time going back, a last row at 1e9 s in
/// a 5 s run and a NaN position: each is refused by both (65), naming the row.
#[test]
fn plot_and_report_refuse_the_same_doctored_traces_naming_the_row() {
    let d = tempfile::tempdir().unwrap();
    let base = d.path().join("base");
    let o = isotrack(&[
        "run",
        "--out",
        base.to_str().unwrap(),
        "--set",
        "sim.duration_s=5",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let trace = std::fs::read_to_string(base.join("trace.csv")).unwrap();
    let lines: Vec<&str> = trace.lines().collect();
    let last = lines.len() - 1;
    for (tag, row, col, value, said) in [
        ("huge_x", 10, 1, "1e300", "is not a position within"),
        ("nan_x", 10, 1, "NaN", "is not a position within"),
        ("back", 10, 0, "0.05", "goes back in time"),
        (
            "past_end",
            last,
            0,
            "1e9",
            "past the run's end (summary.json: t_end_s",
        ),
    ] {
        let dir = d.path().join(tag);
        std::fs::create_dir(&dir).unwrap();
        for f in ["summary.json", "scenario.toml"] {
            std::fs::copy(base.join(f), dir.join(f)).unwrap();
        }
        let mut doctored: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        let mut cells: Vec<&str> = lines[row].split(',').collect();
        cells[col] = value;
        doctored[row] = cells.join(",");
        std::fs::write(dir.join("trace.csv"), doctored.join("\n") + "\n").unwrap();
        let at = format!("trace.csv:{}: ", row + 1);
        let report = d.path().join(format!("{tag}.html"));
        let o = isotrack(&[
            "report",
            dir.to_str().unwrap(),
            "--out",
            report.to_str().unwrap(),
        ]);
        assert_fails(&o, 65, &[&at, said]);
        assert!(!report.exists(), "{tag}: a page was written");
        let figs = d.path().join(format!("{tag}-plot"));
        let o = isotrack(&[
            "plot",
            dir.to_str().unwrap(),
            "--out",
            figs.to_str().unwrap(),
        ]);
        assert_fails(&o, 65, &[&at, said]);
    }
    // The run as written passes both.
    let o = isotrack(&[
        "report",
        base.to_str().unwrap(),
        "--out",
        d.path().join("ok.html").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}
