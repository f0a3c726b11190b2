//! `fly --out`, `sitl --out` and `run --out` share one rule for an existing run directory
//! (issue 33): it is replaced only once the new run has something to write. A flight that
//! never starts (no vehicle heard, its port taken) leaves an earlier flight whole and creates
//! nothing; a folder holding the scenario (or a parent of it) is refused (73), as is an `--out`
//! that is a FIFO, a file or a dangling link, named with what it is.

#![cfg(unix)]

mod common;
use common::{assert_fails, isotrack, isotrack_within, stderr};

/// The files of `dir` (hidden ones too) with their bytes, sorted.
fn contents(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap_or_default(),
            )
        })
        .collect();
    v.sort();
    v
}

/// An earlier flight's directory (a run's files and a raw log), its summary a flight's: a
/// run's with the `end_reason` key every flight's summary has (att41-1: a log beside a
/// simulated run's summary is the user's, never replaced).
fn earlier_flight(d: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=5",
        "--quiet",
        "--out",
        d.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let summary = std::fs::read_to_string(d.join("summary.json")).unwrap();
    let flight = summary.replacen('{', "{\"end_reason\": \"vehicle_ended\",", 1);
    std::fs::write(d.join("summary.json"), flight).unwrap();
    std::fs::write(d.join("mavlink.tlog"), b"an earlier flight's log").unwrap();
    contents(d)
}

#[test]
fn a_flight_that_never_starts_leaves_an_earlier_flight_whole() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("flight");
    let earlier = earlier_flight(&d);
    // No vehicle ever heard: exit 69, nothing sent, and nothing written.
    let o = isotrack_within(
        &[
            "fly",
            "--mavlink",
            "udpin:127.0.0.1:0",
            "--timeout-s",
            "0.3",
            "--out",
            d.to_str().unwrap(),
        ],
        60,
    );
    assert_fails(&o, 69, &["no vehicle was ever heard", "nothing written to"]);
    assert_eq!(contents(&d), earlier);
    // Nor into a directory that was not there: none is created.
    let fresh = dir.path().join("fresh");
    let o = isotrack_within(
        &[
            "fly",
            "--mavlink",
            "udpin:127.0.0.1:0",
            "--timeout-s",
            "0.3",
            "--out",
            fresh.to_str().unwrap(),
        ],
        60,
    );
    assert_fails(&o, 69, &["nothing written to"]);
    assert!(!fresh.exists());
    // A port another process holds: `fly` and `sitl` refused (71), the directory untouched.
    let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let url = format!("udpin:{}", taken.local_addr().unwrap());
    for cmd in ["fly", "sitl"] {
        let o = isotrack_within(&[cmd, "--mavlink", &url, "--out", d.to_str().unwrap()], 60);
        assert_fails(&o, 71, &["the port is taken", "nothing written to"]);
        assert_eq!(contents(&d), earlier, "{cmd}");
    }
}

#[test]
fn an_out_holding_the_scenario_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("scenarios");
    std::fs::create_dir(&folder).unwrap();
    let scenario = folder.join("s.toml");
    std::fs::copy(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/paper-fig2b-circular.toml"
        ),
        &scenario,
    )
    .unwrap();
    let s = scenario.to_str().unwrap();
    for out in [&folder, dir.path()] {
        let out = out.to_str().unwrap();
        for args in [
            vec!["run", s, "--set", "sim.duration_s=1", "--out", out],
            vec!["fly", s, "--mavlink", "udpout:127.0.0.1:9", "--out", out],
            vec!["sitl", s, "--mavlink", "udpin:127.0.0.1:0", "--out", out],
        ] {
            let o = isotrack_within(&args, 60);
            assert_fails(&o, 73, &["holds the input", "s.toml"]);
        }
    }
    let left: Vec<String> = contents(&folder).into_iter().map(|e| e.0).collect();
    assert_eq!(left, ["s.toml"]);
}

#[test]
fn an_out_that_is_no_directory_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let fifo = common::fifo(p, "fifo");
    std::fs::write(p.join("file"), "x").unwrap();
    std::os::unix::fs::symlink(p.join("nowhere"), p.join("dangling")).unwrap();
    std::os::unix::fs::symlink(&fifo, p.join("to-fifo")).unwrap();
    for (name, what) in [
        ("fifo", "a FIFO"),
        ("file", "a regular file"),
        ("dangling", "dangling link"),
        ("to-fifo", "a FIFO"),
    ] {
        let d = p.join(name);
        let d = d.to_str().unwrap();
        for args in [
            vec!["run", "--set", "sim.duration_s=1", "--out", d],
            vec!["fly", "--mavlink", "udpout:127.0.0.1:9", "--out", d],
        ] {
            let o = isotrack_within(&args, 60);
            assert_fails(&o, 73, &[d, what, "not a directory"]);
            assert!(!stderr(&o).contains("os error 17"), "{}", stderr(&o));
        }
    }
}

/// `--out` through a link to a directory writes the run in the directory it points to; the
/// link stays a link.
#[test]
fn out_through_a_link_to_a_directory_writes_there() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("real");
    std::fs::create_dir(&real).unwrap();
    let link = dir.path().join("link");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let o = isotrack(&[
        "run",
        "--set",
        "sim.duration_s=1",
        "--quiet",
        "--out",
        link.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let names: Vec<String> = contents(&real).into_iter().map(|e| e.0).collect();
    assert_eq!(names, ["scenario.toml", "summary.json", "trace.csv"]);
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
}

/// `sitl --out` interrupted before any peer talked to it (its run never started) leaves an
/// earlier run in `DIR` whole (it replaced it with a header-only trace before).
#[test]
fn a_sitl_interrupted_before_its_run_starts_leaves_an_earlier_run_whole() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("vehicle");
    let earlier = earlier_flight(&d);
    let mut sitl = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sitl", "--mavlink", "udpin:127.0.0.1:0", "--out"])
        .arg(&d)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufReader::new(sitl.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert!(line.contains("vehicle on"), "{line}");
    let ok = std::process::Command::new("kill")
        .args(["-INT", &sitl.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success());
    let o = sitl.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130));
    assert_eq!(contents(&d), earlier);
}

/// att39-4 SAFETY: `fly --out UF` replaced a user's own `UF/mavlink.tlog` (a real flight's
/// log, no isotrack summary beside it) without a word. It is refused (73, naming the file)
/// before the link is opened: no frame reaches the vehicle (nothing to arm it), and every file
/// is as it was. Likewise `sitl --out` and `fly --out` into a folder with a user's own
/// `summary.json` (att39-1), and a `trace.csv` with no summary.
#[test]
fn fly_and_sitl_out_never_replace_a_users_files() {
    let dir = tempfile::tempdir().unwrap();
    let vehicle = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let to_vehicle = format!("udpout:{}", vehicle.local_addr().unwrap());
    let folders: [(&str, &str, &[u8], &str); 3] = [
        (
            "tlog",
            "mavlink.tlog",
            b"my own tlog from a real flight",
            "no summary.json beside it",
        ),
        (
            "summary",
            "summary.json",
            b"{\"my\": \"results\"}\n",
            "is not an isotrack run's summary",
        ),
        (
            "trace",
            "trace.csv",
            b"t,my,data\n",
            "no summary.json beside it",
        ),
    ];
    for (name, file, text, why) in folders {
        let uf = dir.path().join(name);
        std::fs::create_dir(&uf).unwrap();
        std::fs::write(uf.join(file), text).unwrap();
        std::fs::write(uf.join("notes.txt"), b"mine").unwrap();
        let before = contents(&uf);
        let named = uf.join(file).display().to_string();
        let u = uf.to_str().unwrap();
        let fly = [
            "fly",
            "--mavlink",
            &to_vehicle,
            "--take-control",
            "--arm",
            "--max-duration-s",
            "3",
            "--out",
            u,
        ];
        let o = isotrack_within(&fly, 60);
        assert_fails(&o, 73, &[&named, why, "use another --out"]);
        assert!(!stderr(&o).contains("companion on"), "{}", stderr(&o));
        assert_eq!(contents(&uf), before, "fly into {name}");
        if file != "mavlink.tlog" {
            let o = isotrack_within(&["sitl", "--mavlink", "udpin:127.0.0.1:0", "--out", u], 60);
            assert_fails(&o, 73, &[&named, why, "use another --out"]);
            assert!(!stderr(&o).contains("vehicle on"), "{}", stderr(&o));
            assert_eq!(contents(&uf), before, "sitl into {name}");
        }
    }
    // Nothing was ever sent to the vehicle.
    vehicle
        .set_read_timeout(Some(std::time::Duration::from_millis(500)))
        .unwrap();
    let mut buf = [0u8; 512];
    assert!(
        vehicle.recv_from(&mut buf).is_err(),
        "a frame reached the vehicle"
    );
}

/// att41-1 SAFETY: `fly --out DIR` replaced the user's own `mavlink.tlog` (their ground
/// station's log) kept beside a simulated run's `summary.json`: a run writes no log, so no
/// isotrack wrote that one. Refused (73, naming it) before the link is opened: no frame reaches
/// the vehicle, every file as it was. `run --out` into the same folder still replaces the run
/// and keeps the log. Fails on the source before (fly flew, and its log replaced the user's).
#[test]
fn fly_out_never_replaces_a_log_beside_a_simulated_runs_summary() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("simrun");
    let u = d.to_str().unwrap();
    let run = ["run", "--set", "sim.duration_s=5", "--quiet", "--out", u];
    let o = isotrack(&run);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::write(d.join("mavlink.tlog"), b"MY QGC LOG").unwrap();
    let before = contents(&d);
    let vehicle = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let to_vehicle = format!("udpout:{}", vehicle.local_addr().unwrap());
    let o = isotrack_within(
        &[
            "fly",
            "--mavlink",
            &to_vehicle,
            "--take-control",
            "--arm",
            "--max-duration-s",
            "3",
            "--out",
            u,
        ],
        60,
    );
    let tlog = d.join("mavlink.tlog").display().to_string();
    assert_fails(
        &o,
        73,
        &[&tlog, "not an isotrack flight's", "use another --out"],
    );
    assert!(!stderr(&o).contains("companion on"), "{}", stderr(&o));
    assert_eq!(contents(&d), before);
    vehicle
        .set_read_timeout(Some(std::time::Duration::from_millis(500)))
        .unwrap();
    let mut buf = [0u8; 512];
    assert!(
        vehicle.recv_from(&mut buf).is_err(),
        "a frame reached the vehicle"
    );
    let o = isotrack(&run);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(d.join("mavlink.tlog")).unwrap(),
        b"MY QGC LOG"
    );
}
