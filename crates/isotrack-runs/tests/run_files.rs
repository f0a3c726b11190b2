//! The run directory through the library: `summary.json`'s one type (written as before, read
//! back with clear errors), the one results-row builder, and the one run-directory writer.

use isotrack_runs::exit;
use isotrack_runs::results::{result_cells, Column, RunRecord};
use isotrack_runs::rundir::RunDir;
use isotrack_runs::summary::{scenario_toml, Ended, Summary};
use isotrack_scenario::parse_scenario;
use isotrack_sim::{NoTrace, RunResult};

/// A short run of the built-in default scenario.
fn short_run() -> (isotrack_scenario::Scenario, RunResult) {
    let s = parse_scenario("", "<test>", &["sim.duration_s=20.0".into()]).unwrap();
    let r = s.run(&mut NoTrace);
    (s, r)
}

/// The record serialises exactly as the run's result does (the keys and values `summary.json`
/// has always had, in the same order), so a metric added to `RunResult` and not to the record
/// fails here instead of silently leaving summary.json.
#[test]
fn the_record_is_the_result_as_summary_json_writes_it() {
    let (_, r) = short_run();
    assert_eq!(
        serde_json::to_string_pretty(&RunRecord::of(&r)).unwrap(),
        serde_json::to_string_pretty(&r).unwrap()
    );
}

/// Non-finite numbers are `null` in the file (as serde writes a NaN `f64`) and `None` once read.
#[test]
fn non_finite_numbers_are_null_and_read_back_as_none() {
    let (s, mut r) = short_run();
    r.metrics.path_length_m = f64::NAN;
    r.metrics.control_effort = f64::INFINITY;
    r.t_end_s = f64::NEG_INFINITY;
    let text = Summary::of_run(&s, None, &r, &[]).to_json();
    assert!(text.contains("\"path_length_m\": null"), "{text}");
    assert!(text.contains("\"control_effort\": null"), "{text}");
    assert!(text.contains("\"t_end_s\": null"), "{text}");
    assert!(text.ends_with("}\n"));
    let back = Summary::from_json(&text).unwrap();
    let rec = back.record().unwrap();
    assert_eq!(rec.metrics.path_length_m, None);
    assert_eq!(rec.metrics.control_effort, None);
    assert_eq!(back.t_end_s(), None);
    assert_eq!(back.scenario_path, None);
    assert_eq!(back.outcome(), "completed");
}

/// What was written reads back as the same summary, and rendering it again gives the same text.
#[test]
fn a_summary_reads_back_as_written() {
    let (s, r) = short_run();
    let warnings = vec!["a warning".to_string()];
    let written = Summary::of_run(&s, Some(std::path::Path::new("x.toml")), &r, &warnings);
    let text = written.to_json();
    let back = Summary::from_json(&text).unwrap();
    assert_eq!(back.scenario_path.as_deref(), Some("x.toml"));
    assert_eq!(back.isotrack_version, env!("CARGO_PKG_VERSION"));
    match &back.ended {
        Ended::Run(e) => {
            assert_eq!(e.warnings, warnings);
            assert_eq!(e.record.steps, r.steps);
            assert_eq!(e.record.samples, r.samples);
        }
        Ended::Flight(_) => panic!("a run read as a flight"),
    }
    assert_eq!(back.ended, written.ended);
    // The scenario read back as JSON (its keys sorted): the same values.
    assert_eq!(back.scenario, serde_json::to_value(s.file()).unwrap());
}

/// A summary that is not one: the error says what is wrong (JSON position, missing key, type).
#[test]
fn a_bad_summary_is_a_clear_error() {
    let e = Summary::from_json("{\"outcome\": \"completed\"}").unwrap_err();
    assert!(!e.unreadable);
    assert!(e.message.contains("missing field"), "{}", e.message);
    let e = Summary::from_json("{\n  \"outcome\": ").unwrap_err();
    assert!(e.message.contains("line 2"), "{}", e.message);
    let e = Summary::from_json("[1, 2]").unwrap_err();
    assert!(e.message.contains("not a JSON object"), "{}", e.message);
    let (s, r) = short_run();
    let good = Summary::of_run(&s, None, &r, &[]).to_json();
    let bad = good.replacen("\"steps\": ", "\"steps\": \"many\", \"was\": ", 1);
    let e = Summary::from_json(&bad).unwrap_err();
    assert!(e.message.contains("invalid type"), "{}", e.message);
    let dir = tempfile::tempdir().unwrap();
    let e = Summary::read(&dir.path().join("summary.json")).unwrap_err();
    assert!(
        e.unreadable && e.message.contains("summary.json"),
        "{}",
        e.message
    );
}

/// A flight's summary (`end_reason`) reads as a flight, with its counters.
#[test]
fn a_flight_summary_reads_as_a_flight() {
    let text = r#"{"isotrack_version": "0", "scenario_path": null, "outcome": "failsafe",
        "outcome_detail": "link lost", "end_reason": "link_lost", "failsafe": true,
        "failsafe_acknowledged": false, "t_end_s": 12.5, "samples": 7, "commands": 3,
        "events": ["link lost"], "frames_in": 10, "frames_out": 11, "junk_datagrams": 1,
        "scenario": {}}"#;
    let s = Summary::from_json(text).unwrap();
    match &s.ended {
        Ended::Flight(f) => {
            assert_eq!(f.end_reason, "link_lost");
            assert_eq!((f.samples, f.commands, f.frames_out), (7, 3, 11));
        }
        Ended::Run(_) => panic!("a flight read as a run"),
    }
    assert_eq!(s.outcome(), "failsafe");
    assert_eq!(s.t_end_s(), Some(12.5));
    assert!(s.record().is_none());
}

/// att33c items 10 and 13: a flight records its data files' digests as a run does (so `plot`
/// compares them, never calling a fresh flight "an older run"), and a flight whose recording
/// stopped says why (`recording_incomplete`); both absent when empty, and read back.
#[test]
fn a_flight_summary_keeps_its_data_files_and_an_incomplete_recording() {
    let text = r#"{"isotrack_version": "0", "scenario_path": null, "outcome": "completed",
        "outcome_detail": "ended", "end_reason": "vehicle_ended", "failsafe": false,
        "failsafe_acknowledged": false, "t_end_s": 12.5, "samples": 7, "commands": 3,
        "events": [], "frames_in": 10, "frames_out": 11, "junk_datagrams": 1,
        "recording_incomplete": "cannot write trace.csv: No space left on device",
        "data_files": {"/d/no2.csv": "ab12"}, "scenario": {}}"#;
    let s = Summary::from_json(text).unwrap();
    let digests = s.data_files().unwrap();
    assert_eq!(digests.get("/d/no2.csv").map(String::as_str), Some("ab12"));
    let Ended::Flight(f) = &s.ended else {
        panic!("a flight read as a run")
    };
    assert!(f
        .recording_incomplete
        .as_deref()
        .unwrap()
        .contains("No space"));
    let mut whole = f.clone();
    whole.recording_incomplete = None;
    whole.data_files.clear();
    let json = serde_json::to_string(&whole).unwrap();
    assert!(
        !json.contains("recording_incomplete") && !json.contains("data_files"),
        "{json}"
    );
}

/// The row builder: a run's cells by name, an undefined number empty, an invalid run's row.
#[test]
fn the_row_builder_writes_cells_and_invalid_rows() {
    let (_, mut r) = short_run();
    r.metrics.convergence_time_s = None;
    r.metrics.control_effort = 2.5;
    r.metrics.path_length_m = f64::NAN;
    let rec = RunRecord::of(&r);
    let cols = [
        Column::Outcome,
        Column::ConvergenceTimeS,
        Column::ControlEffort,
        Column::PathLengthM,
        Column::Samples,
        Column::OutcomeDetail,
    ];
    assert_eq!(
        result_cells(&cols, Ok(&rec)),
        ["completed", "", "2.5", "", &r.samples.to_string(), ""]
    );
    assert_eq!(
        result_cells(&cols, Err("bad key")),
        ["invalid_scenario", "", "", "", "", "bad key"]
    );
    let names: Vec<&str> = cols.iter().map(|c| c.name()).collect();
    assert_eq!(
        names,
        [
            "outcome",
            "convergence_time_s",
            "control_effort",
            "path_length_m",
            "samples",
            "outcome_detail"
        ]
    );
}

/// The one writer: the three files, the summary last and whole; the old summary standing until
/// the new run finishes (then gone before the new trace is in place); an input never written
/// over (64); a FIFO refused at once (73).
#[test]
fn the_run_directory_writer() {
    let (s, r0) = short_run();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("run");
    std::fs::create_dir_all(&d).unwrap();
    // An earlier run's summary, as an isotrack wrote it (an ad-hoc "old" was no isotrack's
    // summary: since att39-1 such a file is the user's, and refused).
    let old = Summary::of_run(&s, Some(std::path::Path::new("old.toml")), &r0, &[]).to_json();
    std::fs::write(d.join("summary.json"), &old).unwrap();
    let out = RunDir::open(&d, &[], &[], Some("run")).unwrap();
    assert!(out.is_locked());
    assert_eq!(
        std::fs::read_to_string(d.join("summary.json")).unwrap(),
        old,
        "the earlier run stands until the new one has something to write"
    );
    // A second writer of the same directory is refused while the first holds it.
    let second = RunDir::open(&d, &[], &[], Some("run")).unwrap_err();
    assert_eq!(second.code, exit::CANTCREAT, "{}", second.message);
    let mut trace = out.trace(false).unwrap();
    let r = s.run(trace.writer());
    assert_eq!(r, r0);
    assert!(
        !d.join("trace.csv").exists(),
        "the trace appears whole, once finished"
    );
    out.finish(
        trace,
        &scenario_toml(&s),
        &Summary::of_run(&s, None, &r, &[]),
    )
    .unwrap();
    let trace = std::fs::read_to_string(d.join("trace.csv")).unwrap();
    let mut lines = trace.lines();
    assert_eq!(
        lines.next(),
        Some(isotrack_runs::trace::TRACE_COLUMNS.join(",").as_str())
    );
    assert!(lines.count() > 1);
    let back = Summary::read(&d.join("summary.json")).unwrap();
    assert_eq!(back.record().unwrap(), &RunRecord::of(&r));
    assert_eq!(
        std::fs::read_to_string(d.join("scenario.toml")).unwrap(),
        scenario_toml(&s)
    );
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    drop(out);

    // An output that is an input: refused before anything is written.
    let input = d.join("scenario.toml");
    let e = RunDir::open(&d, std::slice::from_ref(&input), &[], None).unwrap_err();
    assert_eq!(e.code, exit::USAGE, "{}", e.message);
    assert!(d.join("summary.json").exists(), "nothing touched");

    // A summary the one reader refuses is not written: the earlier run stands whole.
    let earlier = std::fs::read(d.join("summary.json")).unwrap();
    let out = RunDir::open(&d, &[], &[], None).unwrap();
    let trace = out.trace(false).unwrap();
    let e = out
        .finish_json(trace, &scenario_toml(&s), "{\"outcome\": \"completed\"}")
        .unwrap_err();
    assert_eq!(e.code, exit::DATAERR, "{}", e.message);
    assert_eq!(std::fs::read(d.join("summary.json")).unwrap(), earlier);
}

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

/// An earlier run stands whole until the new one has something to write: a run refused after
/// the directory was readied (its trace abandoned) or one that recorded nothing (let go
/// unused) changes nothing, and a directory `open` created for nothing is removed again; a
/// live trace (a flight) replaces the earlier run once it starts.
#[test]
fn an_earlier_run_stands_until_the_new_one_writes() {
    let (s, r) = short_run();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("run");
    let out = RunDir::open(&d, &[], &[], Some("run")).unwrap();
    let trace = out.trace(false).unwrap();
    out.finish(
        trace,
        &scenario_toml(&s),
        &Summary::of_run(&s, None, &r, &[]),
    )
    .unwrap();
    drop(out);
    let earlier = contents(&d);
    assert_eq!(earlier.len(), 3, "{:?}", earlier.iter().map(|e| &e.0));

    let out = RunDir::open(&d, &[], &[], Some("run")).unwrap();
    let trace = out.trace(false).unwrap();
    let e = out.abandon(trace, "refused");
    assert_eq!(e.code, exit::CANTCREAT);
    drop(out);
    assert_eq!(
        contents(&d),
        earlier,
        "an abandoned run changed the directory"
    );

    RunDir::open(&d, &[], &[], Some("fly"))
        .unwrap()
        .release_unused();
    assert_eq!(contents(&d), earlier, "an unused directory changed");

    let fresh = dir.path().join("fresh");
    RunDir::open(&fresh, &[], &[], Some("fly"))
        .unwrap()
        .release_unused();
    assert!(!fresh.exists(), "a directory created for nothing is left");

    let out = RunDir::open(&d, &[], &[], Some("fly")).unwrap();
    let _live = out.live_trace(false).unwrap();
    assert!(
        !d.join("summary.json").exists(),
        "a live trace beside the earlier run's summary"
    );
}

/// att36-13: a live trace (`sitl`, `fly --out`) over an earlier run's `trace.csv` is a new
/// file: a hard link to the earlier one (a `cp -al` snapshot) keeps the earlier rows, where
/// truncating in place rewrote the snapshot with the new flight's.
#[cfg(unix)]
#[test]
fn a_live_trace_never_writes_through_a_hard_link() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("run");
    std::fs::create_dir(&d).unwrap();
    std::fs::write(d.join("trace.csv"), b"the earlier run's rows\n").unwrap();
    // The earlier run's summary as an isotrack wrote it (a bare `{}` is no isotrack's summary:
    // since att39-1 such a directory is the user's, and refused).
    let (s, r) = short_run();
    std::fs::write(
        d.join("summary.json"),
        Summary::of_run(&s, None, &r, &[]).to_json(),
    )
    .unwrap();
    let snapshot = dir.path().join("snapshot-trace.csv");
    std::fs::hard_link(d.join("trace.csv"), &snapshot).unwrap();
    let out = RunDir::open(&d, &[], &[], Some("fly")).unwrap();
    let mut live = out.live_trace(false).unwrap();
    live.writer().flush();
    drop(live);
    assert_eq!(
        std::fs::read(&snapshot).unwrap(),
        b"the earlier run's rows\n",
        "the snapshot was rewritten"
    );
    let now = std::fs::read_to_string(d.join("trace.csv")).unwrap();
    assert!(now.starts_with("t_s,"), "{now}");
}

/// `DIR` that is no directory is refused (73) naming it and what it is: a FIFO, a regular
/// file, a dangling link, a link to a FIFO; a link to a directory is followed (the run is
/// written in the directory it points to).
#[cfg(unix)]
#[test]
fn an_out_that_is_no_directory_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let fifo = p.join("fifo");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
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
        let e = RunDir::open(&d, &[], &[], Some("run")).unwrap_err();
        assert_eq!(e.code, exit::CANTCREAT, "{}", e.message);
        assert!(
            e.message.contains(&d.display().to_string())
                && e.message.contains(what)
                && e.message.contains("not a directory")
                && !e.message.contains("os error 17"),
            "{name}: {}",
            e.message
        );
    }
    let real = p.join("real");
    std::fs::create_dir(&real).unwrap();
    std::os::unix::fs::symlink(&real, p.join("link")).unwrap();
    let (s, r) = short_run();
    let out = RunDir::open(&p.join("link"), &[], &[], Some("run")).unwrap();
    let trace = out.trace(false).unwrap();
    out.finish(
        trace,
        &scenario_toml(&s),
        &Summary::of_run(&s, None, &r, &[]),
    )
    .unwrap();
    assert!(real.join("summary.json").exists());
    assert!(std::fs::symlink_metadata(p.join("link"))
        .unwrap()
        .file_type()
        .is_symlink());
}

/// A run directory that holds an input (the scenario file's folder, or a parent of it; through
/// a link too) is refused (73) before anything is created or written in it.
#[cfg(unix)]
#[test]
fn a_folder_holding_an_input_is_no_run_directory() {
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("scenarios");
    std::fs::create_dir(&folder).unwrap();
    let input = folder.join("s.toml");
    std::fs::write(&input, "").unwrap();
    std::os::unix::fs::symlink(&folder, dir.path().join("link")).unwrap();
    for d in [
        folder.clone(),
        dir.path().to_path_buf(),
        dir.path().join("link"),
    ] {
        let e = RunDir::open(&d, std::slice::from_ref(&input), &[], Some("run")).unwrap_err();
        assert_eq!(e.code, exit::CANTCREAT, "{}", e.message);
        assert!(
            e.message.contains("holds the input") && e.message.contains("s.toml"),
            "{}",
            e.message
        );
    }
    let mut left: Vec<_> = std::fs::read_dir(&folder)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    left.sort();
    assert_eq!(left, ["s.toml"]);
    // A sibling folder is fine.
    RunDir::open(
        &dir.path().join("out"),
        std::slice::from_ref(&input),
        &[],
        None,
    )
    .unwrap();
}

/// A FIFO where a run file goes is refused at once (it would block the write for ever).
#[cfg(unix)]
#[test]
fn a_fifo_in_the_run_directory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("trace.csv");
    let ok = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !ok {
        return;
    }
    let e = RunDir::open(dir.path(), &[], &[], None).unwrap_err();
    assert_eq!(e.code, exit::CANTCREAT);
    assert!(e.message.contains("not a regular file"), "{}", e.message);
}

/// A team's summary (issue 32 through the one type): vehicle 0's record on top, then the
/// `team` object and the `vehicles` array after `data_files` and before `scenario`; the team
/// object's metrics are the engine's `TeamSummary` as serde writes it (so the bytes are those
/// `summary.json` had before the one type), and the whole reads back as written.
#[test]
fn a_team_summary_is_vehicle_0_then_team_and_vehicles() {
    let s = parse_scenario(
        "[team]\ncount = 3\nspread = { along = \"arc\", center_m = [0.0, 0.0], radius_m = 6.931471805599453, start_rad = 0.0, step_rad = 0.5, clockwise = true }\nspacing = \"range_balance\"\n",
        "<test>",
        &["sim.duration_s=20.0".into()],
    )
    .unwrap();
    let t = s
        .run_team(&mut [] as &mut [NoTrace])
        .expect("a team")
        .unwrap();
    assert_eq!(t.runs.len(), 3);
    let summary = Summary::of_team(&s, None, &t, &[]);
    let text = summary.to_json();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    // Vehicle 0's result on top, as a single run's would be.
    assert_eq!(v["steps"], serde_json::json!(t.runs[0].steps));
    assert_eq!(v["outcome"], serde_json::json!(t.runs[0].outcome.as_str()));
    // Key order: ... warnings, team, vehicles, scenario.
    let at = |k: &str| text.find(&format!("\n  \"{k}\":")).unwrap();
    assert!(at("warnings") < at("team") && at("team") < at("vehicles"));
    assert!(at("vehicles") < at("scenario"));
    // `vehicles`: each run's result as the engine serialises it.
    assert_eq!(v["vehicles"], serde_json::to_value(&t.runs).unwrap());
    // `team`: the engine's team summary, after the count, law and ring.
    let team = v["team"].as_object().unwrap();
    assert_eq!(team["vehicle_count"], serde_json::json!(3));
    assert_eq!(team["spacing"], serde_json::json!("range_balance"));
    assert_eq!(team["coordinate_free"], serde_json::json!(true));
    assert_eq!(team["neighbours"], serde_json::to_value(&t.ring).unwrap());
    let metrics = serde_json::to_value(t.team.as_ref().expect("a radial field")).unwrap();
    for (k, x) in metrics.as_object().unwrap() {
        assert_eq!(&team[k], x, "team.{k}");
    }
    assert_eq!(team.len(), 4 + metrics.as_object().unwrap().len());
    let back = Summary::from_json(&text).unwrap();
    assert_eq!(back.team().unwrap().vehicle_count, 3);
    assert_eq!(back.ended, summary.ended);
    // One vehicle's summary has neither at its top level (its scenario keeps `[team]`).
    let one = Summary::of_run(&s, None, &t.runs[0], &[]).to_json();
    assert!(!one.contains("\n  \"team\":") && !one.contains("\n  \"vehicles\":"));
    assert_eq!(Summary::from_json(&one).unwrap().team(), None);
}

/// Issue 31: a lock let go leaves no `.isotrack.lock`; while held, a second writer is refused
/// (73); a file someone put at the path after the holder's is not the holder's to remove.
#[test]
fn a_released_lock_leaves_no_lock_file() {
    use isotrack_runs::sweep::lock::{lock_output_dir, LOCK_FILE};
    let d = tempfile::tempdir().unwrap();
    let lock = lock_output_dir(d.path(), "sweep").unwrap();
    assert!(d.path().join(LOCK_FILE).is_file());
    let again = lock_output_dir(d.path(), "merge").unwrap_err();
    assert_eq!(again.code, exit::CANTCREAT);
    assert!(again.message.contains("sweep pid"), "{}", again.message);
    drop(lock);
    assert!(!d.path().join(LOCK_FILE).exists());
    // Locked again after it was let go; another file put in its place stays.
    let lock = lock_output_dir(d.path(), "sweep").unwrap();
    std::fs::remove_file(d.path().join(LOCK_FILE)).unwrap();
    std::fs::write(d.path().join(LOCK_FILE), "someone else's\n").unwrap();
    drop(lock);
    assert_eq!(
        std::fs::read_to_string(d.path().join(LOCK_FILE)).unwrap(),
        "someone else's\n"
    );
}

/// att41-22: `summary.json`'s `data_files` names each data file by the SHA-256 of the bytes the
/// field was parsed from. The grid is replaced (renamed over, as `mv` does) after the scenario
/// loaded it: the summary still names the loaded file's digest (`sha256sum` of its text:
/// 9bad80dc...), not the new file's (39768365...), and `data_files_as_read` warns that the file
/// changed. Before the fix the digests were taken by reading the files again, after the load:
/// they named the new file, for a run on the old field.
#[test]
fn data_files_name_the_bytes_the_field_was_parsed_from() {
    let d = tempfile::tempdir().unwrap();
    let grid = d.path().join("g.csv");
    std::fs::write(&grid, "0,1,2\n10,11,12\n20,21,22\n30,31,32\n").unwrap();
    let s = isotrack_scenario::parse_scenario_in(
        "[field]\nkind = \"grid\"\npath = \"g.csv\"\n[initial]\nx_m = 1.0\ny_m = 1.0\n[controller]\nlevel = 15.0\n[sim]\nduration_s = 1.0\n",
        "<test>",
        &[],
        d.path(),
    );
    let s = match s {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    };
    let replacement = d.path().join("new.csv");
    std::fs::write(
        &replacement,
        "100,101,102\n110,111,112\n120,121,122\n130,131,132\n",
    )
    .unwrap();
    std::fs::rename(&replacement, &grid).unwrap();
    let key = std::fs::canonicalize(&grid).unwrap().display().to_string();
    let old = "9bad80dc300f30f8e4254a6025fde01952b4a378655dbd2c11405b20e70d8472";
    let read = isotrack_runs::summary::data_file_digests(&s);
    assert_eq!(read.get(&key).map(String::as_str), Some(old), "{read:?}");
    let r = s.run(&mut NoTrace);
    let mut summary = Summary::of_run(&s, None, &r, &[]);
    assert_eq!(
        summary
            .data_files()
            .and_then(|f| f.get(&key))
            .map(String::as_str),
        Some(old)
    );
    let w = summary.data_files_as_read(read).expect("a warning");
    assert!(w.contains("(SHA-256 9bad80dc300f30f8 as read)"), "{w}");
}

/// att41-17: a flight's summary (`sitl --out`, `fly --out`) records the data files as the field
/// was read and, when a file changed since, says so in its `events` (a flight has no
/// `warnings`), as a run's does in `warnings`. Here the recorded digest is not the file's (as
/// when the file was replaced during the flight): the digest as read is kept and the warning
/// names the file. Before the fix a flight's summary was left as it was (no warning, and the
/// digests were the files' after the flight).
#[test]
fn a_flight_names_its_data_files_as_read_and_says_when_one_changed() {
    let d = tempfile::tempdir().unwrap();
    let grid = d.path().join("g.csv");
    std::fs::write(&grid, "0,1,2\n10,11,12\n20,21,22\n30,31,32\n").unwrap();
    let text = r#"{"isotrack_version": "0", "scenario_path": null, "outcome": "completed",
        "outcome_detail": "ended", "end_reason": "vehicle_ended", "failsafe": false,
        "failsafe_acknowledged": false, "t_end_s": 12.5, "samples": 7, "commands": 3,
        "events": ["ended"], "frames_in": 10, "frames_out": 11, "junk_datagrams": 1,
        "scenario": {}}"#;
    let path = grid.display().to_string();
    let as_read = "39768365d30bd35f3790aacbf5e60e7e1fe99fe9e5c78b92dd46e1c9f9294e2e";
    let mut s = Summary::from_json(text).unwrap();
    let read = std::collections::BTreeMap::from([(path.clone(), as_read.to_string())]);
    let w = s.data_files_as_read(read).expect("a warning");
    assert!(
        w.contains(&format!("{path} (SHA-256 39768365d30bd35f as read)")),
        "{w}"
    );
    let Ended::Flight(f) = &s.ended else {
        panic!("a flight read as a run")
    };
    assert_eq!(f.data_files.get(&path).map(String::as_str), Some(as_read));
    assert_eq!(f.events, ["ended".to_string(), w.clone()]);
    assert_eq!(f.outcome_detail, "ended");
    // The file as read (its SHA-256 by sha256sum: 9bad80dc...): no warning, nothing added.
    let mut s = Summary::from_json(text).unwrap();
    let same = "9bad80dc300f30f8e4254a6025fde01952b4a378655dbd2c11405b20e70d8472";
    assert_eq!(
        s.data_files_as_read(std::collections::BTreeMap::from([(path, same.to_string())])),
        None
    );
    let Ended::Flight(f) = &s.ended else {
        panic!("a flight read as a run")
    };
    assert_eq!(f.events, ["ended"]);
}

/// att41-3: the close-approach warning gives the reason the team's settings give. Team-circular-4
/// with no spacing law and vehicle 3 at 0.3 m/s (the others 0.5): the others lap it, vehicles
/// 2 and 3 meeting at about 10 s; the reason is the lapping, every `L/|v0_2 - v0_3|` with `L`
/// the circle's length `2 pi 10 ln 2 = 43.55 m`, so 217.76 s, and it no longer blames a spacing
/// law or advises `team.ring = "discovered"` (which refuses per-vehicle speeds). The reasons of
/// the other teams: no law at one speed; a law on a listed ring at one speed (the advice kept);
/// a law on a discovered ring (no advice).
#[test]
fn the_close_approach_reason_fits_the_team() {
    use isotrack_runs::summary::{approach_reason, team_warnings};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/team-circular-4.toml");
    let lap = isotrack_scenario::load_scenario(
        Some(&path),
        &[
            "team.spacing=\"none\"".into(),
            "team.vehicles=[{index = 3, speed_mps = 0.3}]".into(),
            "sim.duration_s=20".into(),
        ],
    )
    .unwrap();
    let team = lap.run_team(&mut [] as &mut [NoTrace]).unwrap().unwrap();
    let w = team_warnings(&lap, &team);
    let w = w
        .iter()
        .find(|w| w.contains(" came within "))
        .unwrap_or_else(|| panic!("no close approach in {w:?}"));
    assert!(w.starts_with("vehicles 2 and 3 came within "), "{w}");
    assert!(
        w.contains("vehicle 2 flies at 0.5 m/s and vehicle 3 at 0.3 m/s (team.vehicles) and with no spacing law (team.spacing = \"none\") each keeps its speed: the faster laps the slower every L/|v0_2 - v0_3| = "),
        "{w}"
    );
    let every: f64 = w
        .split("v0_3| = ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{w}"));
    // The text prints 6 significant digits (217.759): within half a unit of the last.
    let l = 2.0 * std::f64::consts::PI * 10.0 * std::f64::consts::LN_2;
    assert!((every - l / 0.2).abs() < 5e-4, "{every} vs {}", l / 0.2);
    assert!(!w.contains("discovered") && !w.contains("drove"), "{w}");
    // The other teams' reasons (from the settings alone).
    let spec_of = |sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        isotrack_scenario::load_scenario(Some(&path), &sets)
            .unwrap()
            .spec()
            .team
            .clone()
            .unwrap()
    };
    let none = spec_of(&["team.spacing=\"none\""]);
    assert!(approach_reason([0, 1], l, Some(&none)).starts_with("no spacing law holds them apart"));
    let listed = spec_of(&[]);
    assert!(approach_reason([0, 1], l, Some(&listed)).contains("try team.ring = \"discovered\""));
    let discovered = spec_of(&["team.ring=\"discovered\""]);
    assert_eq!(
        approach_reason([0, 1], l, Some(&discovered)),
        "the spacing law drove them together, or they started too close"
    );
}

/// att43-9: four robots deployed 0.03 rad apart on the circle of radius 10 ln 2 start
/// `2 r sin(0.015)` = 0.2079 m apart, inside the 0.5 m of a close approach, at t = 0, before any
/// law acted: the warning says they were deployed that close, not that "the spacing law drove
/// them together" (nor to try a discovered ring).
#[test]
fn a_close_approach_at_the_start_is_the_deployments() {
    use isotrack_runs::summary::team_warnings;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/team-circular-4.toml");
    let s = isotrack_scenario::load_scenario(
        Some(&path),
        &[
            "team.spread.step_rad=0.03".into(),
            "sim.duration_s=5".into(),
        ],
    )
    .unwrap();
    let team = s.run_team(&mut [] as &mut [NoTrace]).unwrap().unwrap();
    let w = team_warnings(&s, &team);
    let w = w
        .iter()
        .find(|w| w.contains(" came within "))
        .unwrap_or_else(|| panic!("no close approach in {w:?}"));
    let r = 10.0 * std::f64::consts::LN_2;
    let d = 2.0 * r * 0.015f64.sin();
    assert!(w.contains(&format!("{d:.5}")[..5]), "{w} ({d})");
    assert!(w.contains("at t = 0 s"), "{w}");
    assert!(
        w.ends_with(
            "they were deployed that close (team.starts, team.spread): no law had acted yet"
        ),
        "{w}"
    );
    assert!(!w.contains("drove") && !w.contains("discovered"), "{w}");
}
