//! Helpers shared by the CLI's end-to-end tests: run the binary, read its stderr, write inputs,
//! check a failure.
#![allow(dead_code)] // each test file uses its own subset

use std::path::Path;
use std::process::{Command, Output};

/// Runs the `isotrack` binary with `args`.
pub fn isotrack(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// The run's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Writes `text` to `dir/name`; returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

/// Checks a failure: the exit code, no panic, and the message contains every `needle`.
pub fn assert_fails(o: &Output, code: i32, needles: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(code), "stderr: {e}");
    assert!(!e.contains("panicked"), "panic: {e}");
    for n in needles {
        assert!(e.contains(n), "expected `{n}` in: {e}");
    }
}

/// The `<text>` elements of an SVG: (x, y, text-anchor, content).
pub fn svg_texts(svg: &str) -> Vec<(f64, f64, String, String)> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(tag[at..at + tag[at..].find('"')?].to_string())
    };
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let (tag, rest) = t.split_once('>')?;
            let content = rest.split("</text>").next()?.trim().to_string();
            let x = attr(tag, "x")?.parse().ok()?;
            let y = attr(tag, "y")?.parse().ok()?;
            Some((x, y, attr(tag, "text-anchor").unwrap_or_default(), content))
        })
        .collect()
}

/// Least-squares line `pixel = a + b*value` through an axis's tick labels.
pub fn axis_fit(ticks: &[(f64, f64)]) -> (f64, f64) {
    assert!(ticks.len() >= 3, "{ticks:?}");
    let n = ticks.len() as f64;
    let (mv, mp) = (
        ticks.iter().map(|t| t.0).sum::<f64>() / n,
        ticks.iter().map(|t| t.1).sum::<f64>() / n,
    );
    let b = ticks.iter().map(|t| (t.0 - mv) * (t.1 - mp)).sum::<f64>()
        / ticks.iter().map(|t| (t.0 - mv).powi(2)).sum::<f64>();
    (mp - b * mv, b)
}

/// The points of the SVG's polylines drawn with `stroke` at `width`.
pub fn polylines(svg: &str, stroke: &str, width: &str) -> Vec<Vec<(f64, f64)>> {
    let needle = format!("stroke=\"{stroke}\" stroke-width=\"{width}\" points=\"");
    svg.split("<polyline")
        .skip(1)
        .filter_map(|p| {
            let at = p.find(&needle)? + needle.len();
            let pts = &p[at..at + p[at..].find('"')?];
            Some(
                pts.split_whitespace()
                    .map(|xy| {
                        let (x, y) = xy.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect(),
            )
        })
        .collect()
}

/// Runs the `isotrack` binary with `args` and no standard input, killed after `secs` seconds: a
/// regression that makes it wait (on a FIFO, say) fails the test instead of hanging it.
pub fn isotrack_within(args: &[&str], secs: u64) -> Output {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let start = std::time::Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > std::time::Duration::from_secs(secs) {
            child.kill().ok();
            child.wait().ok();
            panic!("isotrack {args:?} still running after {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

/// Makes a FIFO (named pipe) at `dir/name` with `mkfifo`; returns its path.
#[cfg(unix)]
pub fn fifo(dir: &Path, name: &str) -> String {
    let p = dir.join(name);
    let ok = Command::new("mkfifo")
        .arg(&p)
        .status()
        .expect("mkfifo runs");
    assert!(ok.success(), "mkfifo {}", p.display());
    p.display().to_string()
}

/// The path of the bundled scenario `scenarios/NAME.toml`.
pub fn bundled(name: &str) -> String {
    format!("{}/../../scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// Writes the sweep file `dir/name` over scenario file `scenario` (written as a TOML string)
/// with the sections `body`; returns its path.
pub fn sweep_file(dir: &Path, name: &str, scenario: &str, body: &str) -> String {
    write(dir, name, &format!("scenario = {scenario:?}\n{body}"))
}

/// Runs `isotrack sweep SW --out OUT` with `extra` arguments, which must succeed; returns the
/// `results.csv` it leaves.
pub fn swept(sw: &str, out: &Path, extra: &[&str]) -> String {
    let mut args = vec!["sweep", sw, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = isotrack(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read_to_string(out.join("results.csv")).unwrap()
}

/// The rows of CSV file `path` (a header line, then rows), each as column -> cell.
pub fn csv_rows(path: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            header
                .iter()
                .cloned()
                .zip(rec.iter().map(String::from))
                .collect()
        })
        .collect()
}

/// A `results.csv` text cut at its commas (rows whose cells hold none), to edit a row cell by
/// cell: its header and its rows.
pub struct Cells<'a> {
    /// The column names.
    pub header: Vec<&'a str>,
    /// The rows, each its cells.
    pub rows: Vec<Vec<&'a str>>,
}

impl<'a> Cells<'a> {
    /// `text` cut into lines and cells.
    pub fn of(text: &'a str) -> Self {
        let mut lines = text.lines().map(|l| l.split(',').collect::<Vec<&str>>());
        let header = lines.next().unwrap_or_default();
        Self {
            header,
            rows: lines.collect(),
        }
    }

    /// The index of column `name`.
    pub fn col(&self, name: &str) -> usize {
        self.header.iter().position(|h| *h == name).unwrap()
    }
}

/// Starts isotrack with `args` (stderr piped) and sends it SIGINT once `ready()` holds (or it
/// ended first: its status says so).
#[cfg(unix)]
pub fn interrupted_when(args: &[&str], ready: impl Fn() -> bool) -> std::process::Output {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let mut child = Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !ready() && child.try_wait().unwrap().is_none() {
        assert!(t0.elapsed() < Duration::from_secs(120), "never ready");
        std::thread::sleep(Duration::from_millis(1));
    }
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    child.wait_with_output().unwrap()
}

/// Tries an interrupted run (`attempt(i)` for try `i`, [`interrupted_when`]) up to `attempts`
/// times, until one is caught before it finished: that try's number and output (its exit
/// status not 0); `None` when each try finished first.
pub fn first_caught(
    attempts: usize,
    mut attempt: impl FnMut(usize) -> Output,
) -> Option<(usize, Output)> {
    (0..attempts)
        .map(|i| (i, attempt(i)))
        .find(|(_, o)| o.status.code() != Some(0))
}
