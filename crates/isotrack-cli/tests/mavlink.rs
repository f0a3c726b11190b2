//! `isotrack sitl` and `isotrack fly` as processes: usage and data errors with their exit codes,
//! and a lockstep flight over UDP loopback whose run directory `plot` and `report` read.

mod common;
use common::{assert_fails, isotrack, stderr};
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

/// The port a `sitl` on `udpin:127.0.0.1:0` bound, from its first line on standard error
/// ("... vehicle on 127.0.0.1:PORT ...").
fn sitl_port(sitl: &mut std::process::Child) -> String {
    let mut line = String::new();
    BufReader::new(sitl.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    line.split("127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap_or_else(|| panic!("{line}"))
        .to_string()
}

#[test]
fn bad_options_are_usage_errors_and_unflyable_scenarios_data_errors() {
    let out = "udpout:127.0.0.1:9";
    for (args, code, needle) in [
        (
            vec!["fly", "--mavlink", "udp:127.0.0.1:5760"],
            64,
            "unknown link kind `udp`",
        ),
        (vec!["fly", "--mavlink", "nonsense"], 64, "expected udpin"),
        (
            vec!["fly", "--mavlink", "carrier:pigeon"],
            64,
            "unknown link kind",
        ),
        (
            vec!["sitl", "--mavlink", out, "--speedup", "0"],
            64,
            "--speedup",
        ),
        (
            vec!["sitl", "--mavlink", out, "--speedup", "1e-300"],
            64,
            "--speedup must be in [0.001, 1000]",
        ),
        (
            vec!["sitl", "--mavlink", out, "--system-id", "0"],
            64,
            "--system-id 0 is MAVLink's broadcast address",
        ),
        // fix33h: sitl's PX4-like fixed heartbeat rate, bounded; real time only.
        (
            vec!["sitl", "--mavlink", out, "--heartbeat-hz", "0"],
            64,
            "--heartbeat-hz must be a number > 0",
        ),
        (
            vec!["sitl", "--mavlink", out, "--heartbeat-hz", "100"],
            64,
            "--heartbeat-hz must be in [0.2, 50], got 100",
        ),
        (
            vec!["sitl", "--mavlink", out, "--heartbeat-hz", "1", "--lockstep"],
            64,
            "--heartbeat-hz",
        ),
        (
            vec!["fly", "--mavlink", out, "--timeout-s", "1e20"],
            64,
            "--timeout-s must be in [0.1, 86400]",
        ),
        // att33c item 3: below 0.1 s a flight ends at its first quiet moment; the rate
        // echoed as written, not as 300 digits; 255 is the ground stations' id (3b).
        (
            vec!["fly", "--mavlink", out, "--timeout-s", "1e-5"],
            64,
            "--timeout-s must be in [0.1, 86400], got 0.00001",
        ),
        (
            vec!["fly", "--mavlink", out, "--setpoint-rate-hz", "1e-300"],
            64,
            "got 1e-300",
        ),
        (
            vec!["fly", "--mavlink", out, "--system-id", "255"],
            64,
            "--system-id 255 is the ground stations'",
        ),
        (
            vec!["sitl", "--mavlink", out, "--system-id", "255"],
            64,
            "--system-id 255 is the ground stations'",
        ),
        (
            vec!["fly", "--mavlink", out, "--max-duration-s", "1e300"],
            64,
            "--max-duration-s",
        ),
        (
            vec!["sitl", "--mavlink", out, "--speedup", "nan"],
            64,
            "--speedup",
        ),
        (
            vec!["fly", "--mavlink", out, "--timeout-s=-1"],
            64,
            "--timeout-s",
        ),
        (
            vec!["fly", "--mavlink", out, "--fence-m", "inf"],
            64,
            "--fence-m",
        ),
        (
            vec!["fly", "--mavlink", out, "--max-duration-s", "0"],
            64,
            "--max-duration-s",
        ),
        (
            vec!["fly", "--mavlink", out, "--setpoint-rate-hz", "1"],
            64,
            "2 Hz",
        ),
        (
            vec!["fly", "--mavlink", out, "--sensor", "serial:/dev/ttyS0"],
            64,
            "serial",
        ),
        (
            vec!["fly", "--mavlink", out, "--sensor", "ELEVENCHARS"],
            64,
            "1 to 10",
        ),
        // att33b item 13: a malformed sensor address is a usage error, as --mavlink's.
        (
            vec!["fly", "--mavlink", out, "--sensor", "udp:127.0.0.1:99999"],
            64,
            "--sensor udp:127.0.0.1:99999",
        ),
        // att33d-9c: port 0 would be one nobody could send to.
        (
            vec!["fly", "--mavlink", out, "--sensor", "udp:127.0.0.1:0"],
            64,
            "--sensor udp:127.0.0.1:0: port 0",
        ),
        (
            vec!["fly", "--mavlink", out, "--system-id", "0"],
            64,
            "--system-id 0 is MAVLink's broadcast address",
        ),
        (
            vec!["fly", "--mavlink", out, "--target-system", "0"],
            64,
            "--target-system 0 is MAVLink's broadcast address",
        ),
        (
            vec!["fly", "--mavlink", out, "--allow-generic"],
            64,
            "--allow-generic goes with --take-control",
        ),
        (
            vec!["sitl", "--mavlink", out, "--speedup", "2", "--lockstep"],
            64,
            "cannot be used",
        ),
        (
            vec![
                "fly",
                "--mavlink",
                out,
                "--set",
                "controller.kind=gradient_reference",
            ],
            65,
            "gradient",
        ),
        (
            vec![
                "sitl",
                "--mavlink",
                out,
                "--set",
                "sim.dt_s=0.0005",
                "--set",
                "sensor.rate_hz=2000",
            ],
            65,
            "1000 Hz",
        ),
        (
            vec!["sitl", "--mavlink", out, "--set", "sitl.home_lat_deg=95"],
            65,
            "sitl.home_lat_deg",
        ),
        // At a pole the east-west scale cos(lat) vanishes: refused, both poles.
        (
            vec!["sitl", "--mavlink", out, "--set", "sitl.home_lat_deg=-90"],
            65,
            "sitl.home_lat_deg",
        ),
        (
            vec!["sitl", "--mavlink", out, "--set", "sitl.home_lat_deg=90"],
            65,
            "sitl.home_lat_deg",
        ),
        // ver33-5: a level beyond the +-1e12 a measurement may be: refused at start by both.
        (
            vec!["fly", "--mavlink", out, "--set", "controller.level=5e12"],
            65,
            "controller.level = ",
        ),
        (
            vec!["sitl", "--mavlink", out, "--set", "controller.level=-5e12"],
            65,
            "beyond the +-1e12 a measurement may be",
        ),
        // No trace rows, no positions: refused rather than a vehicle that never says where
        // it is.
        (
            vec!["sitl", "--mavlink", out, "--set", "output.record_rate_hz=0"],
            65,
            "output.record_rate_hz = 0: isotrack sitl sends its position telemetry once per trace row",
        ),
    ] {
        let o = isotrack(&args);
        assert_fails(&o, code, &[needle]);
    }
}

/// `sitl --lockstep` and `fly --take-control --out DIR` as two processes on ports of their own
/// (the vehicle binds port 0 and says which): the flight's run directory holds one trace row
/// per sample (20 s at 100 Hz: 2001), a summary that says the vehicle ended the run, and a
/// telemetry log of whole MAVLink 2 frames; `plot` and `report` read it.
#[test]
fn a_lockstep_flight_writes_a_run_directory_plot_and_report_read() {
    let dir = tempfile::tempdir().unwrap();
    let (sim_dir, fly_dir) = (dir.path().join("sitl"), dir.path().join("fly"));
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "sitl",
            "--mavlink",
            "udpin:127.0.0.1:0",
            "--lockstep",
            "--set",
        ])
        .arg("sim.duration_s=20")
        .arg("--out")
        .arg(&sim_dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "fly",
            "--take-control",
            "--arm",
            "--timeout-s",
            "60",
            "--set",
            "sim.duration_s=20",
        ])
        .arg("--mavlink")
        .arg(format!("udpout:127.0.0.1:{port}"))
        .arg("--out")
        .arg(&fly_dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(sitl.wait().unwrap().success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fly_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["end_reason"], "vehicle_ended");
    assert_eq!(summary["outcome"], "completed");
    // Written through the one summary type (a flight's record), its keys in the order the
    // flight's summary has always had them (FLYING.md): the link's counters, then the metrics.
    let text = std::fs::read_to_string(fly_dir.join("summary.json")).unwrap();
    let at = |k: &str| {
        text.find(&format!("\n  \"{k}\":"))
            .unwrap_or_else(|| panic!("no {k}"))
    };
    let order = [
        "isotrack_version",
        "scenario_path",
        "outcome",
        "outcome_detail",
        "end_reason",
        "failsafe",
        "failsafe_acknowledged",
        "t_end_s",
        "samples",
        "commands",
        "events",
        "frames_in",
        "frames_out",
        "junk_datagrams",
        "measurements_out_of_order",
        "measurements_repeated",
        "measurements_invalid",
        "measurements_other_sources",
        "metrics_over",
        "steady_state_max_abs_error",
        "track_losses",
        "scenario",
    ];
    for w in order.windows(2) {
        assert!(at(w[0]) < at(w[1]), "{} before {}", w[0], w[1]);
    }
    assert_eq!(summary.as_object().unwrap().len(), 19 + 12 + 1);
    assert_eq!(summary["measurements_invalid"], 0);
    assert_eq!(summary["samples"], 2001);
    assert_eq!(summary["commands"], 2001);
    let trace = std::fs::read_to_string(fly_dir.join("trace.csv")).unwrap();
    assert_eq!(trace.lines().count(), 1 + 2001);
    // Each row's position is the vehicle's at the latest telemetry row (10 Hz) at or before
    // its measurement's time, as LOCAL_POSITION_NED carries it (f32), never the one before.
    let rows = |p: &std::path::Path| -> Vec<Vec<f64>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    };
    let (flown, simulated) = (
        rows(&fly_dir.join("trace.csv")),
        rows(&sim_dir.join("trace.csv")),
    );
    for r in &flown {
        // On the wire's millisecond clock (the simulation's 0.7000000000000001 s is 700 ms).
        let ms = |t: f64| (t * 1000.0).round();
        let at = simulated
            .iter()
            .rev()
            .find(|q| ms(q[0]) <= ms(r[0]))
            .unwrap();
        assert_eq!(
            (r[1], r[2]),
            (at[1] as f32 as f64, at[2] as f32 as f64),
            "row at t = {} s (telemetry of {} s)",
            r[0],
            at[0]
        );
    }
    // The summary has a run's metrics, on the measured error (the trace's `error`): the
    // steady-state window is the last 20 % of the 20 s (t >= 16 s).
    let max = flown
        .iter()
        .filter(|r| r[0] >= 16.0)
        .fold(0.0f64, |m, r| m.max(r[5].abs()));
    assert_eq!(summary["steady_state_max_abs_error"].as_f64(), Some(max));
    assert!(summary["control_effort"].as_f64().is_some_and(|e| e > 0.0));
    // The telemetry log: (8-byte time, frame) records; each frame starts with MAVLink 2's 0xFD
    // and is 12 bytes + its payload length (+13 when signed) long.
    let log = std::fs::read(fly_dir.join("mavlink.tlog")).unwrap();
    let (mut at, mut frames) = (0, 0);
    while at < log.len() {
        let f = &log[at + 8..];
        assert_eq!(f[0], 0xFD, "a frame at byte {}", at + 8);
        let len = 12 + f[1] as usize + if f[2] & 1 == 1 { 13 } else { 0 };
        at += 8 + len;
        frames += 1;
    }
    assert_eq!(at, log.len());
    // At least the 2001 measurements received and the 2001 answers sent.
    assert!(frames >= 2 * 2001, "{frames}");
    let o = isotrack(&["plot", fly_dir.to_str().unwrap(), sim_dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(fly_dir.join("trajectory.png").exists());
    let page = dir.path().join("report.html");
    let o = isotrack(&[
        "report",
        fly_dir.to_str().unwrap(),
        "--out",
        page.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A flight that answered no measurement (att33b item 18): no rows, no end time (null in
    // the summary); `plot` says so in words, never "t = null s".
    let header = trace.lines().next().unwrap().to_string();
    std::fs::write(fly_dir.join("trace.csv"), header + "\n").unwrap();
    let mut empty = summary.clone();
    empty["t_end_s"] = serde_json::Value::Null;
    std::fs::write(
        fly_dir.join("summary.json"),
        serde_json::to_string_pretty(&empty).unwrap(),
    )
    .unwrap();
    let o = isotrack(&["plot", fly_dir.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(
        !o.status.success()
            && err.contains("before its first measurement")
            && !err.contains("null"),
        "{err}"
    );
}

/// Real time (20x): the vehicle does not wait for the companion, which answers every sample all
/// the same; the run completes and the companion sees it end. (No assertion on how long it
/// took.)
#[test]
fn a_real_time_flight_completes() {
    let dir = tempfile::tempdir().unwrap();
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "sitl",
            "--mavlink",
            "udpin:127.0.0.1:0",
            "--speedup",
            "20",
            "--set",
        ])
        .arg("sim.duration_s=30")
        .arg("--out")
        .arg(dir.path().join("sitl"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "30"])
        .arg("--mavlink")
        .arg(format!("udpout:127.0.0.1:{port}"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(out.contains("end         vehicle_ended"), "{out}");
    let s = sitl.wait_with_output().unwrap();
    assert!(s.status.success());
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("sitl/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["outcome"], "completed");
    assert_eq!(summary["samples"], 3001);
}

/// A failsafe with no vehicle to confirm it (nothing listens on the link) exits 69, and does
/// not claim to have commanded HOLD.
#[test]
fn an_unconfirmed_failsafe_exits_69() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "fly",
            "--mavlink",
            "udpout:127.0.0.1:9",
            "--timeout-s",
            "0.3",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(69), "{err}");
    assert!(!err.contains("HOLD commanded"), "{err}");
    assert!(err.contains("link_lost"), "{err}");
    assert!(err.contains("no vehicle was ever heard"), "{err}");
    assert!(!err.contains("failsafe mode was sent"), "{err}");
}

/// `fly --take-control` with the default (Dubins, ground) scenario against `sitl` flying Fig.
/// 3's fixed wing (`MAV_TYPE_FIXED_WING`): refused before any setpoint or command, naming
/// both, exit 65; the vehicle stays disarmed (its summary's events hold no arming).
#[cfg(unix)]
#[test]
fn a_scenario_of_another_kind_than_the_vehicle_exits_65() {
    let dir = tempfile::tempdir().unwrap();
    let fig3 = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig3-uav.toml"
    );
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sitl", fig3, "--mavlink", "udpin:127.0.0.1:0", "--lockstep"])
        .arg("--out")
        .arg(dir.path().join("sitl"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "30"])
        .arg("--mavlink")
        .arg(format!("udpout:127.0.0.1:{port}"))
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(65), "{err}");
    assert!(
        err.contains("vehicle_mismatch")
            && err.contains("MAV_TYPE_FIXED_WING")
            && err.contains("dubins"),
        "{err}"
    );
    signal(&sitl, "-INT");
    let s = sitl.wait_with_output().unwrap();
    assert_eq!(s.status.code(), Some(130));
    let summary = std::fs::read_to_string(dir.path().join("sitl/summary.json")).unwrap();
    assert!(!summary.contains("armed by"), "{summary}");
}

/// A lockstep `sitl` (`--timeout-s` as given) and a `fly --take-control --out` flying it, on a
/// run long enough to be caught in flight: returned once the companion's trace has rows on
/// disk.
#[cfg(unix)]
fn a_flight_under_way(
    dir: &std::path::Path,
    sitl_timeout_s: &str,
) -> (std::process::Child, std::process::Child) {
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "sitl",
            "--mavlink",
            "udpin:127.0.0.1:0",
            "--lockstep",
            "--timeout-s",
            sitl_timeout_s,
            "--set",
            "sim.duration_s=100000",
        ])
        .arg("--out")
        .arg(dir.join("sitl"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let fly = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "30"])
        .arg("--mavlink")
        .arg(format!("udpout:127.0.0.1:{port}"))
        .arg("--out")
        .arg(dir.join("fly"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let trace = dir.join("fly/trace.csv");
    let t0 = std::time::Instant::now();
    while std::fs::metadata(&trace).map_or(0, |m| m.len()) < 20_000 {
        assert!(
            t0.elapsed() < std::time::Duration::from_secs(120),
            "never flew"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    (sitl, fly)
}

#[cfg(unix)]
fn signal(child: &std::process::Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
}

/// The terminal closing (SIGHUP) stops `fly` as Ctrl-C does: HOLD commanded and confirmed,
/// `interrupted`, exit 75 (ended by a failsafe); the lockstep `sitl`, answered no more, ends
/// after its --timeout-s as `companion_lost`, exit 69. That timeout is 3 s: a HOLD stands once
/// the heartbeats have shown it for 1.1 s (the failsafe's confirmation span, att33f-3), which
/// the sitl's once-a-second heartbeat while it waits gives at its second beat in HOLD; with 1 s
/// it ended before, and the HOLD, shown once, was rightly not confirmed.
#[cfg(unix)]
#[test]
fn sighup_stops_fly_and_sitl_ends_without_its_companion() {
    let dir = tempfile::tempdir().unwrap();
    let (sitl, fly) = a_flight_under_way(dir.path(), "3");
    signal(&fly, "-HUP");
    let o = fly.wait_with_output().unwrap();
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(75), "{out}{err}");
    assert!(out.contains("end         interrupted"), "{out}");
    assert!(
        err.contains("HOLD commanded") && err.contains("the vehicle is in HOLD"),
        "{err}"
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("fly/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["end_reason"], "interrupted");
    assert_eq!(summary["failsafe_acknowledged"], true);
    let s = sitl.wait_with_output().unwrap();
    let out = String::from_utf8_lossy(&s.stdout);
    assert_eq!(s.status.code(), Some(69), "{out}");
    assert!(out.contains("outcome     companion_lost"), "{out}");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("sitl/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["outcome"], "companion_lost");
}

/// Ctrl-C (SIGINT) stops `sitl`: `interrupted` (not `completed`) on standard output and in
/// `summary.json`, exit 130; its companion sees the vehicle go away: a lost link (a failsafe,
/// its HOLD unconfirmed: exit 69), never `vehicle_ended` / `completed` with exit 0.
#[cfg(unix)]
#[test]
fn an_interrupted_sitl_says_interrupted() {
    let dir = tempfile::tempdir().unwrap();
    let (sitl, fly) = a_flight_under_way(dir.path(), "60");
    signal(&sitl, "-INT");
    let s = sitl.wait_with_output().unwrap();
    let out = String::from_utf8_lossy(&s.stdout);
    assert_eq!(s.status.code(), Some(130), "{out}");
    assert!(out.contains("outcome     interrupted"), "{out}");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("sitl/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["outcome"], "interrupted");
    let o = fly.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("end         link_lost"),
        "{err}"
    );
    assert!(err.contains("cut short (interrupted)"), "{err}");
    assert_eq!(o.status.code(), Some(69), "{err}");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("fly/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["outcome"], "failsafe");
    assert_eq!(summary["end_reason"], "link_lost");
}

/// A FIFO where `fly --out` would write its trace is refused at once (73), not opened (which
/// would block for ever without a reader).
#[cfg(unix)]
#[test]
fn a_fifo_in_the_run_directory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fly");
    std::fs::create_dir(&out).unwrap();
    let ok = Command::new("mkfifo")
        .arg(out.join("trace.csv"))
        .status()
        .unwrap();
    assert!(ok.success());
    let o = isotrack(&[
        "fly",
        "--mavlink",
        "udpout:127.0.0.1:9",
        "--timeout-s",
        "0.3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_fails(&o, 73, &["not a regular file"]);
}

/// `fly --out` killed (SIGKILL) mid-flight leaves a trace with whole rows: it is flushed at
/// least every second while rows come (here 1 row a second: a 1 Hz sensor in real time; an
/// 8 KiB write buffer would hold the first ~78 rows of about 105 bytes, longer than the 30 s
/// waited for 3 rows), and the scenario is written first.
#[cfg(unix)]
#[test]
fn a_killed_flight_leaves_a_readable_trace() {
    let dir = tempfile::tempdir().unwrap();
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sitl", "--mavlink", "udpin:127.0.0.1:0"])
        .args(["--set", "sim.duration_s=600", "--set", "sensor.rate_hz=1"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let out = dir.path().join("fly");
    let mut fly = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "30"])
        .args(["--set", "sensor.rate_hz=1"])
        .arg("--mavlink")
        .arg(format!("udpout:127.0.0.1:{port}"))
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let trace = out.join("trace.csv");
    let lines = || std::fs::read_to_string(&trace).map_or(0, |t| t.lines().count());
    let t0 = std::time::Instant::now();
    while lines() < 4 && t0.elapsed() < std::time::Duration::from_secs(30) {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    fly.kill().unwrap();
    fly.wait().unwrap();
    sitl.kill().unwrap();
    sitl.wait().unwrap();
    let text = std::fs::read_to_string(&trace).unwrap();
    let mut it = text.lines();
    assert!(
        it.next().is_some_and(|h| h.starts_with("t_s,x_m,y_m")),
        "{text}"
    );
    let rows: Vec<&str> = it.collect();
    assert!(rows.len() >= 3, "{text}");
    for r in rows {
        let cells: Vec<&str> = r.split(',').collect();
        assert_eq!(cells.len(), 8, "{r}");
        assert!(cells.iter().all(|c| c.parse::<f64>().is_ok()), "{r}");
    }
    assert!(out.join("scenario.toml").exists());
}

/// Takes the directory lock of `dir` as another command would.
#[cfg(unix)]
fn hold_lock(dir: &std::path::Path) -> std::fs::File {
    let f = std::fs::File::create(dir.join(".isotrack.lock")).unwrap();
    f.try_lock().unwrap();
    f
}

/// The files of `dir`, sorted.
fn names(dir: &std::path::Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

/// Issue 31: `sitl --out` and `fly --out` handle a directory holding an earlier run as `run
/// --out` does (the one run-directory writer): while another command holds its lock they exit 73
/// at once and leave the earlier run as it was; otherwise the flight replaces it, and no
/// `.isotrack.lock` is left behind.
#[cfg(unix)]
#[test]
fn sitl_and_fly_out_replace_an_earlier_run_as_run_out_does() {
    let dir = tempfile::tempdir().unwrap();
    let (sim_dir, fly_dir) = (dir.path().join("sitl"), dir.path().join("fly"));
    for d in [&sim_dir, &fly_dir] {
        let o = isotrack(&[
            "run",
            "--set",
            "sim.duration_s=5",
            "--quiet",
            "--out",
            d.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(names(d), ["scenario.toml", "summary.json", "trace.csv"]);
    }
    let earlier = std::fs::read(sim_dir.join("summary.json")).unwrap();
    // Locked by another command: 73 at once, nothing touched.
    for (cmd, d) in [("sitl", &sim_dir), ("fly", &fly_dir)] {
        let holder = hold_lock(d);
        let o = isotrack(&[
            cmd,
            "--mavlink",
            if cmd == "sitl" {
                "udpin:127.0.0.1:0"
            } else {
                "udpout:127.0.0.1:9"
            },
            "--timeout-s",
            "0.3",
            "--out",
            d.to_str().unwrap(),
        ]);
        assert_fails(&o, 73, &["is writing this directory"]);
        assert_eq!(std::fs::read(d.join("summary.json")).unwrap(), earlier);
        drop(holder);
        std::fs::remove_file(d.join(".isotrack.lock")).unwrap();
    }
    // A lockstep flight over both earlier runs.
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sitl", "--mavlink", "udpin:127.0.0.1:0", "--lockstep"])
        .args(["--set", "sim.duration_s=5", "--out"])
        .arg(&sim_dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "60"])
        .args(["--set", "sim.duration_s=5", "--mavlink"])
        .arg(format!("udpout:127.0.0.1:{port}"))
        .arg("--out")
        .arg(&fly_dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(sitl.wait().unwrap().success());
    assert_eq!(
        names(&sim_dir),
        ["scenario.toml", "summary.json", "trace.csv"]
    );
    assert_eq!(
        names(&fly_dir),
        ["mavlink.tlog", "scenario.toml", "summary.json", "trace.csv"]
    );
    let fly: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fly_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(fly["end_reason"], "vehicle_ended");
    // 5 s at the default 100 Hz sensor: samples at 0, 0.01, ..., 5 s.
    assert_eq!(fly["samples"], 501);
    let trace = std::fs::read_to_string(fly_dir.join("trace.csv")).unwrap();
    assert_eq!(trace.lines().count(), 1 + 501);
}

/// ver33-2: `fly`'s events reach standard error as they happen, not when the flight ends: the
/// vehicle it took ("vehicle: system 1, component 1 ...") is read from its standard error
/// while it still waits for the pilot's hand-over (it would wait for ever: the test interrupts
/// it only once the line came, or after 60 s without it).
#[test]
fn fly_writes_its_events_as_they_happen() {
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sitl", "--mavlink", "udpin:127.0.0.1:0", "--set"])
        .arg("sim.duration_s=600")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let port = sitl_port(&mut sitl);
    let mut fly = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "fly",
            "--mavlink",
            &format!("udpout:127.0.0.1:{port}"),
            "--timeout-s",
            "60",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = fly.stderr.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(err).lines() {
            let Ok(line) = line else { break };
            let _ = tx.send(line);
        }
    });
    let mut seen_live = false;
    let t0 = std::time::Instant::now();
    while t0.elapsed() < std::time::Duration::from_secs(60) {
        match rx.recv_timeout(std::time::Duration::from_millis(200)) {
            Ok(line) if line.contains("vehicle: system 1, component 1") => {
                seen_live = true;
                break;
            }
            _ => {}
        }
    }
    // SIGINT: fly's Ctrl-C (before control: nothing commanded, exit 79).
    let _ = Command::new("kill")
        .args(["-INT", &fly.id().to_string()])
        .status();
    let status = fly.wait().unwrap();
    reader.join().unwrap();
    let _ = sitl.kill();
    let _ = sitl.wait();
    assert!(
        seen_live,
        "the vehicle's line came only after the interrupt"
    );
    assert_eq!(status.code(), Some(79));
}

/// ver33-4 (a): `fly --take-control` hearing a twin companion's heartbeat (its own ids, system
/// 1, component 191) before any vehicle exits 79 (another controller: nothing commanded), as
/// FLYING.md says, not 69 "no vehicle was ever heard".
#[test]
fn a_twin_before_the_vehicle_exits_79() {
    let mut fly = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "fly",
            "--mavlink",
            "udpin:127.0.0.1:17531",
            "--take-control",
            "--timeout-s",
            "5",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let beat = mavlink::dialects::common::MavMessage::HEARTBEAT(
        mavlink::dialects::common::HEARTBEAT_DATA {
            mavtype: mavlink::dialects::common::MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            autopilot: mavlink::dialects::common::MavAutopilot::MAV_AUTOPILOT_INVALID,
            mavlink_version: 3,
            ..Default::default()
        },
    );
    let t0 = std::time::Instant::now();
    let mut seq = 0u8;
    while fly.try_wait().unwrap().is_none() && t0.elapsed() < std::time::Duration::from_secs(30) {
        let mut f = Vec::new();
        let header = mavlink::MavHeader {
            system_id: 1,
            component_id: 191,
            sequence: seq,
        };
        mavlink::write_v2_msg(&mut f, header, &beat).unwrap();
        seq = seq.wrapping_add(1);
        let _ = sock.send_to(&f, "127.0.0.1:17531");
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    let _ = fly.kill();
    let o = fly.wait_with_output().unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(79), "{e}");
    assert!(e.contains("a second companion with this one's ids"), "{e}");
}
