//! `--mavlink` links other than UDP on the command line (issue 33): bad addresses and devices
//! with the README's exit codes, a lon/lat field's home, and `sitl` and `fly` as two processes
//! in lockstep over TCP.

mod common;
use common::{assert_fails, fifo, isotrack, stderr};
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

/// A TCP port on 127.0.0.1 where nobody listens (bound, then released).
fn closed_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    l.local_addr().unwrap().port()
}

#[test]
fn bad_links_exit_with_the_readme_codes() {
    let dir = tempfile::tempdir().unwrap();
    let pipe = fifo(dir.path(), "radio");
    let plain = common::write(dir.path(), "plain", "");
    let missing = dir.path().join("ttyNONE").display().to_string();
    let closed = format!("tcpout:127.0.0.1:{}", closed_port());
    for (cmd, url, code, needle) in [
        ("sitl", "tcpin:127.0.0.1".to_string(), 64, "has no port"),
        ("fly", "tcpout://:5760".to_string(), 64, "both given"),
        (
            "fly",
            "udpin:127.0.0.1:70000".to_string(),
            64,
            "not a number in [0, 65535]",
        ),
        (
            "sitl",
            "serial:/dev/ttyS0".to_string(),
            64,
            "expected serial:DEVICE:BAUD",
        ),
        (
            "sitl",
            "serial:/dev/ttyS0:56000".to_string(),
            64,
            "is not one of",
        ),
        ("fly", "carrier:pigeon".to_string(), 64, "unknown link kind"),
        (
            "sitl",
            format!("serial:{pipe}:57600"),
            66,
            "is a FIFO, not a serial port",
        ),
        (
            "fly",
            format!("serial:{pipe}:57600"),
            66,
            "is a FIFO, not a serial port",
        ),
        (
            "sitl",
            format!("serial:{plain}:57600"),
            66,
            "is a regular file",
        ),
        ("fly", format!("serial:{missing}:57600"), 66, "cannot open"),
        (
            "sitl",
            "serial:/dev/null:57600".to_string(),
            66,
            "not a terminal",
        ),
        ("fly", closed.clone(), 69, "cannot connect"),
        ("sitl", closed.clone(), 69, "cannot connect"),
    ] {
        // A FIFO must be refused at once, never opened (which would block for ever).
        let o = common::isotrack_within(&[cmd, "--mavlink", &url], 60);
        assert_fails(&o, code, &[needle, "--mavlink"]);
    }
}

/// A lon/lat field (ERA5, NetCDF in degrees) is its own georeference: `sitl.home_*` set to
/// another point is refused (65), naming the key and the field's origin.
#[test]
fn a_home_that_contradicts_a_lonlat_field_is_refused() {
    let scenario = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/era5-isotherm-uav.toml"
    );
    let o = isotrack(&[
        "sitl",
        scenario,
        "--mavlink",
        "udpin:127.0.0.1:0",
        "--set",
        "sitl.home_lat_deg=47.397742",
    ]);
    assert_fails(
        &o,
        65,
        &[
            "sitl.home_lat_deg = 47.397742",
            "latitude 50, longitude -10 deg",
        ],
    );
}

/// `sitl --mavlink tcpin:127.0.0.1:0 --lockstep` and `fly --take-control --mavlink
/// tcpout:...`: the flight completes (every one of the 2001 samples answered), both exit 0.
#[test]
fn a_lockstep_flight_over_tcp() {
    let dir = tempfile::tempdir().unwrap();
    let mut sitl = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["sitl", "--mavlink", "tcpin:127.0.0.1:0", "--lockstep"])
        .args(["--set", "sim.duration_s=20"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(sitl.stderr.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = line
        .split("127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .unwrap_or_else(|| panic!("{line}"))
        .to_string();
    assert!(line.contains("(tcpin:127.0.0.1:0)"), "{line}");
    let fly_dir = dir.path().join("fly");
    let o = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(["fly", "--take-control", "--arm", "--timeout-s", "60"])
        .args(["--set", "sim.duration_s=20", "--mavlink"])
        .arg(format!("tcpout:127.0.0.1:{port}"))
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
    assert_eq!(summary["commands"], 2001);
}
