//! Issue 30 (items a and b of the run-files work): a sweep is not silent about runs that did
//! not complete or ended with a warning, and the output-directory lock names its holder.
mod common;
use common::{assert_fails, isotrack, stderr, write};

/// A 5 m Gaussian plume (peak 10, level 5): started 5 m from its centre the PI-like law tracks
/// it; started 60 m away the field's slope there is exp(-60^2/50) = 5e-32 of the peak, nothing
/// next to c1*tanh(5) = 0.2, so the law circles where it starts (check::flat_start).
const PLUME: &str = "[field]\nkind = \"gaussian_plumes\"\nbackground = 0.0\nsources = [{ center_m = [0.0, 0.0], amplitude = 10.0, sigma_m = [5.0, 5.0], rotation_rad = 0.0 }]\n[controller]\nlevel = 5.0\n[sim]\nduration_s = 20.0\n";

/// Runs 1 and 3 (started 60 m out) get a flat-start warning in their `warnings` cell; runs 0
/// and 2 (5 m out) none; the sweep's stderr says 2 of 4 runs with their ids, and every other
/// column keeps its place (the new column is the last).
#[test]
fn a_sweep_tallies_and_records_runs_with_warnings() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ncontroller.kp = [5.0, 10.0]\ninitial.x_m = [5.0, 60.0]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("warning: 2 of 4 runs did not complete or ended with a warning (run_id 1, 3)"),
        "{err}"
    );
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let n = header.len();
    assert_eq!(
        &header[n - 3..],
        ["samples", "outcome_detail", "warnings"],
        "the columns before stay in place"
    );
    let rows: Vec<csv::StringRecord> = rdr.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 4);
    for r in &rows {
        let far = &r[header.iter().position(|h| h == "initial.x_m").unwrap()] == "60.0";
        assert_eq!(&r[n - 1].is_empty(), &!far, "{r:?}");
        if far {
            assert!(
                r[n - 1].starts_with("flat start") && r[n - 1].contains("controller.search"),
                "{r:?}"
            );
        }
    }
    // Resumed, the tally counts the kept rows too.
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("2 of 4 runs"), "{}", stderr(&o));
}

/// A sweep without such runs prints no tally.
#[test]
fn a_sweep_without_warnings_prints_no_tally() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [4.0, 5.0]\n",
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
}

/// While a benchmark holds an output directory (this process, through the benchmark's own
/// `open_out_dir`), a sweep and a merge there are refused naming the benchmark and its pid,
/// not "sweep, merge or benchmark"; released, the lock file is left empty.
#[test]
fn the_lock_message_names_the_command_that_holds_it() {
    let d = tempfile::tempdir().unwrap();
    write(d.path(), "plume.toml", PLUME);
    let sw = write(
        d.path(),
        "s.toml",
        "scenario = \"plume.toml\"\n[grid]\ninitial.x_m = [4.0, 5.0]\n",
    );
    let out = d.path().join("bench");
    let lock = isotrack_commands::league::open_out_dir(&out, false).unwrap();
    let holder = format!("another isotrack benchmark pid {}", std::process::id());
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 73, &[&holder, "is writing this directory"]);
    assert!(!stderr(&o).contains("sweep, merge or benchmark"));
    let o = isotrack(&[
        "merge",
        out.to_str().unwrap(),
        "--out",
        d.path().join("m").to_str().unwrap(),
    ]);
    assert_fails(
        &o,
        73,
        &[
            &format!("an isotrack benchmark pid {}", std::process::id()),
            "is still writing",
        ],
    );
    drop(lock);
    assert_eq!(
        std::fs::read_to_string(out.join(".isotrack.lock")).unwrap(),
        "",
        "a released lock leaves an empty file"
    );
    let o = isotrack(&["sweep", &sw, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
}
