//! Issue 30, item 13: a reader that closes standard output (`isotrack check | head -c1`) or
//! standard error never makes a command panic (exit 101 and a backtrace); the command finishes
//! its work and exits 0 (README, "Exit codes"), and a standard output that fails otherwise
//! (`/dev/full`) exits 73.
mod common;
use common::{isotrack, stderr, write};
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// The binary with `args`, its standard output (and with `close_stderr` its standard error too)
/// a pipe whose reading end is closed before the process starts: every write to it fails with
/// `EPIPE`, deterministically (no race with a reader).
fn with_closed_pipe(args: &[&str], close_stderr: bool) -> Output {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let mut c = Command::new(env!("CARGO_BIN_EXE_isotrack"));
    c.args(args).stdin(Stdio::null());
    if close_stderr {
        c.stderr(writer.try_clone().expect("the pipe's writer"));
    }
    c.stdout(writer).output().expect("the binary runs")
}

fn assert_quiet_success(args: &[&str], close_stderr: bool) {
    let o = with_closed_pipe(args, close_stderr);
    let e = stderr(&o);
    assert!(
        !e.contains("panicked") && !e.contains("Broken pipe"),
        "{args:?}: {e}"
    );
    assert_eq!(o.status.code(), Some(0), "{args:?}: {e}");
}

/// Every command that prints, each with its standard output closed, then with both streams
/// closed (a run whose warnings go to standard error).
#[test]
fn every_command_survives_a_closed_standard_output() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n).display().to_string();
    let short = "sim.duration_s=5.0";
    // A run directory for plot and report, made with an open pipe.
    assert!(isotrack(&["run", "--out", &p("run"), "--set", short])
        .status
        .success());
    let stations = write(
        d.path(),
        "st.csv",
        "x_m,y_m,no2\n0,0,10\n100,0,20\n0,100,30\n100,100,40\n50,50,25\n",
    );
    let inputs = write(
        d.path(),
        "in.csv",
        "t_s,delta_e_rad,delta_a_rad,delta_r_rad,delta_t\n0,-0.12,0,0,0.68\n1,-0.12,0,0,0.68\n",
    );
    write(d.path(), "sc.toml", "sim.duration_s = 2.0\n");
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"sc.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0]\n",
    );
    assert!(isotrack(&["sweep", &sw, "--out", &p("shard")])
        .status
        .success());
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper-fig2b-circular.toml")
        .display()
        .to_string();
    let commands: Vec<Vec<String>> = [
        vec!["run", "--set", short],
        vec!["show"],
        vec!["check"],
        vec!["check", "--json"],
        vec![
            "compare",
            &scenario,
            "--controllers",
            "pi_isoline,sliding_mode",
            "--set",
            short,
        ],
        vec!["trim", "--airspeed-mps", "30"],
        vec!["trim", "--airspeed-mps", "30", "--json"],
        vec!["replay", "--inputs", &inputs, "--out", &p("replay.csv")],
        vec![
            "interpolate",
            &stations,
            "--value-column",
            "no2",
            "--method",
            "idw",
            "--spacing-m",
            "25",
            "--out",
            &p("g.csv"),
        ],
        vec!["plot", &p("run"), "--out", &p("plots")],
        vec!["report", &p("run"), "--out", &p("report.html")],
        vec!["sweep", &sw, "--out", &p("sweep"), "--force"],
        vec!["merge", &p("shard"), "--out", &p("merged"), "--force"],
        vec!["--help"],
    ]
    .iter()
    .map(|v| v.iter().map(|s| s.to_string()).collect())
    .collect();
    for args in &commands {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_quiet_success(&args, false);
    }
    // The work is done whatever became of the output: the files are there, whole.
    assert!(d.path().join("replay.csv").is_file());
    assert!(d.path().join("report.html").is_file());
    let merged = std::fs::read_to_string(d.path().join("merged/results.csv")).unwrap();
    assert_eq!(merged.lines().count(), 3, "{merged}");
    // Both streams closed, on a run that warns on standard error (noise through a backward
    // difference) and fails on it (an invalid value): exits 0 and 65, never 101.
    assert_quiet_success(
        &["run", "--set", short, "--set", "sensor.noise_std=0.1"],
        true,
    );
    let o = with_closed_pipe(&["run", "--set", "controller.kp=-1"], true);
    assert_eq!(o.status.code(), Some(65));
}

/// A standard output that cannot be written for another reason than a closed pipe is an output
/// that cannot be written: exit 73, said on standard error.
#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_output_exits_73() {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .expect("/dev/full");
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .arg("show")
        .stdout(full)
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(73), "{e}");
    assert!(e.contains("cannot write standard output"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}

/// Hostile review of issue 30: `isotrack --help > /dev/full` (and `--version`, a command's
/// `--help`) exited 0 although nothing was written: clap printed the text and ignored the
/// error. The text goes through the console like every other line: 73 on a full disk, 0 on
/// a closed pipe.
#[cfg(target_os = "linux")]
#[test]
fn help_and_version_on_a_full_standard_output_exit_73() {
    for args in [
        &["--help"][..],
        &["--version"],
        &["-V"],
        &["run", "--help"],
        &["help", "sweep"],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full");
        let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .args(args)
            .stdout(full)
            .output()
            .unwrap();
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(73), "{args:?}: {e}");
        assert!(e.contains("cannot write standard output"), "{e}");
        assert_quiet_success(args, false);
        assert_quiet_success(args, true);
    }
    // And the help still reaches a working standard output.
    let o = isotrack(&["--help"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).contains("Usage: isotrack"));
}
