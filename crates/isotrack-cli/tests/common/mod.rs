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
