//! att41-14: a run directory an older isotrack wrote is read by `plot` and `report` (the run
//! reader, `RunData`), as `run --out` takes it for an earlier isotrack run.

use isotrack_plot::RunData;
use isotrack_runs::summary::{scenario_toml, Summary};

/// A summary as isotrack wrote it before a4299e9 (git history: `summary.json` then had no
/// `warnings`; no `samples_dropped`, `time_in_band_fraction`, `track_losses`, which came with
/// the sensor's dropouts in a5cd644; no `data_files`, nu40-4) is read: no warnings, no samples
/// dropped (the sensor had no dropouts), the rest as written. Before the fix `plot` and
/// `report` refused it (65) with serde's "missing field `warnings`".
#[test]
fn an_older_isotracks_summary_is_read() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("old");
    let s = isotrack_scenario::parse_scenario("[sim]\nduration_s = 20.0\n", "<test>", &[]).unwrap();
    let out = isotrack_runs::rundir::RunDir::open(&dir, &[], &[], None).unwrap();
    let mut trace = out.trace(s.is_flying()).unwrap();
    let r = s.run(trace.writer());
    let summary = Summary::of_run(&s, None, &r, &[]);
    out.finish(trace, &scenario_toml(&s), &summary).unwrap();
    let p = dir.join("summary.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    let m = v.as_object_mut().unwrap();
    for key in [
        "warnings",
        "samples_dropped",
        "time_in_band_fraction",
        "track_losses",
        "data_files",
    ] {
        m.remove(key);
    }
    let samples = m["samples"].as_u64().unwrap();
    std::fs::write(&p, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    let run = RunData::load(&dir).unwrap_or_else(|e| panic!("refused: {e}"));
    let isotrack_runs::summary::Ended::Run(end) = &run.summary.ended else {
        panic!("read as a flight")
    };
    assert!(end.warnings.is_empty());
    assert_eq!(end.record.samples_dropped, 0);
    assert_eq!(end.record.samples, samples);
    assert!(end.data_files.is_empty());
    assert!(!run.trace.is_empty());
}
