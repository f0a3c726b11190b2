//! The trace streams to disk in constant memory: a run writing 500 001 trace rows (about 50 MB
//! of rows if they were kept) raises this process's peak resident memory (VmHWM, the kernel's
//! own accounting) by far less. Its own test binary, so no other test shares the process.

use clap::Parser;
use isotrack_commands::cli::{Cli, Command};

/// Peak resident set size of this process, kB (Linux `/proc/self/status`).
fn vm_hwm_kb() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[test]
fn a_long_trace_streams_in_constant_memory() {
    let Some(before) = vm_hwm_kb() else {
        eprintln!("skipped: no /proc/self/status");
        return;
    };
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("run");
    let cli = Cli::try_parse_from([
        "isotrack",
        "run",
        "--set",
        "sim.duration_s=5000",
        "--set",
        "output.record_rate_hz=100",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ])
    .unwrap();
    let Command::Run(args) = &cli.command else {
        unreachable!()
    };
    isotrack_commands::run::run(args)
        .map_err(|f| f.message)
        .unwrap();
    let after = vm_hwm_kb().unwrap();
    let rows = std::fs::read_to_string(out.join("trace.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    assert_eq!(rows, 500_001);
    // Holding the rows (104 bytes each) would take about 50 MB.
    let row_bytes = std::mem::size_of::<isotrack_sim::TraceRow>() as u64;
    let held_kb = rows as u64 * row_bytes / 1024;
    assert!(held_kb > 50_000, "{held_kb} kB");
    let grew = after.saturating_sub(before);
    eprintln!("peak grew {grew} kB; rows held would be {held_kb} kB");
    assert!(
        grew < held_kb / 5,
        "peak memory grew by {grew} kB writing {rows} rows ({held_kb} kB if held)"
    );
}
