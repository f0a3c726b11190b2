//! `isotrack check --map --out DIR [--verify N]` end to end (issue 29): the files and their
//! documented shape, `check --json` unchanged without `--map`, the same bytes on any thread
//! count, and every bad input with the README's exit code.

mod common;
use common::{assert_fails, isotrack, isotrack_within, stderr};
use std::collections::BTreeSet;
use std::path::Path;

const MAP_COLUMNS: [&str; 9] = [
    "kp",
    "sensor_rate_hz",
    "sensor_period_s",
    "spectral_radius",
    "stable",
    "status",
    "slope_min",
    "slope_max",
    "note",
];

const VERIFY_COLUMNS: [&str; 11] = [
    "run",
    "kp",
    "sensor_rate_hz",
    "spectral_radius",
    "predicted",
    "outcome",
    "agrees",
    "near_boundary",
    "error_range",
    "mean_abs_turn_radps",
    "detail",
];

fn scenario() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/paper-fig2b-circular.toml")
        .display()
        .to_string()
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(String::from).collect())
        .collect();
    (header, rows)
}

/// Test (4): the chart's CSV parses back with the documented columns, one row per grid point
/// (the grid's ends exact, spaced evenly in log), `stable` is `spectral_radius < 1`, the period
/// is `1/rate`; the pictures are real images; `--json` names the files and is otherwise the
/// report `check --json` prints without `--map`.
#[test]
fn the_chart_is_a_tidy_csv_and_two_pictures() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("chart");
    let sc = scenario();
    let args = [
        "check",
        sc.as_str(),
        "--set",
        "controller.ki=0",
        "--map",
        "--out",
        out.to_str().unwrap(),
        "--kp-range",
        "0.5:50",
        "--rate-range",
        "1:100",
        "--map-size",
        "7x5",
        "--json",
    ];
    let o = isotrack(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let mut with: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let map = with.as_object_mut().unwrap().remove("map").unwrap();
    let plain = isotrack(&["check", sc.as_str(), "--set", "controller.ki=0", "--json"]);
    let plain: serde_json::Value = serde_json::from_slice(&plain.stdout).unwrap();
    assert!(plain.get("map").is_none());
    assert_eq!(with, plain, "the report is the same with and without --map");
    let files: Vec<&str> = map["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    for name in [
        "stability_map.csv",
        "stability_map.png",
        "stability_map.svg",
    ] {
        let p = out.join(name);
        assert!(files.contains(&p.to_str().unwrap()), "{files:?}");
    }
    assert!(map["verify"].is_null());

    let (header, rows) = read_csv(&out.join("stability_map.csv"));
    assert_eq!(header, MAP_COLUMNS);
    assert_eq!(rows.len(), 35);
    let col = |name: &str| MAP_COLUMNS.iter().position(|c| *c == name).unwrap();
    let f = |r: &Vec<String>, name: &str| r[col(name)].parse::<f64>().unwrap();
    let kps: BTreeSet<u64> = rows.iter().map(|r| f(r, "kp").to_bits()).collect();
    let rates: BTreeSet<u64> = rows
        .iter()
        .map(|r| f(r, "sensor_rate_hz").to_bits())
        .collect();
    assert_eq!((kps.len(), rates.len()), (7, 5));
    let mut kps: Vec<f64> = kps.into_iter().map(f64::from_bits).collect();
    kps.sort_by(f64::total_cmp);
    assert_eq!((kps[0], kps[6]), (0.5, 50.0));
    for w in kps.windows(2) {
        assert!(
            (w[1] / w[0] / 100f64.powf(1.0 / 6.0) - 1.0).abs() < 1e-12,
            "{w:?}"
        );
    }
    let mut stable = 0;
    for r in &rows {
        assert!((f(r, "sensor_period_s") * f(r, "sensor_rate_hz") - 1.0).abs() < 1e-15);
        let rho = f(r, "spectral_radius");
        assert_eq!(r[col("stable")], (rho < 1.0).to_string(), "{r:?}");
        let status = &r[col("status")];
        assert_eq!(status, if rho < 1.0 { "stable" } else { "unstable" });
        stable += usize::from(rho < 1.0);
        // The P law on a circular field: the orbit's slope, one value per kp.
        assert_eq!(r[col("slope_min")], r[col("slope_max")]);
    }
    assert!(
        stable > 0 && stable < 35,
        "both sides on the chart: {stable}"
    );
    assert_eq!(map["cells_stable"], stable);

    let img = image::open(out.join("stability_map.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(img.dimensions(), (1000, 800));
    let colours: BTreeSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 20, "{} colours", colours.len());
    let svg = std::fs::read_to_string(out.join("stability_map.svg")).unwrap();
    assert!(svg.contains("spectral radius") && svg.contains("the P law"));
}

/// `--verify`: `verify.csv` has the documented columns and one row per run, each outcome one
/// of the documented ones; the chart and the runs are the same bytes on one thread and on
/// three; the JSON counts agree with the file.
#[test]
fn verify_writes_its_runs_and_is_the_same_on_any_thread_count() {
    let d = tempfile::tempdir().unwrap();
    let sc = scenario();
    let run = |dir: &str, threads: &str| {
        let out = d.path().join(dir);
        let o = isotrack(&[
            "check",
            sc.as_str(),
            "--set",
            "controller.ki=0",
            "--set",
            "sim.duration_s=200",
            "--map",
            "--out",
            out.to_str().unwrap(),
            "--kp-range",
            "0.3:30",
            "--rate-range",
            "1:10",
            "--map-size",
            "9x5",
            "--verify",
            "10",
            "--threads",
            threads,
            "--json",
        ]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (out, j)
    };
    let (one, j) = run("one", "1");
    let (three, _) = run("three", "3");
    for name in ["stability_map.csv", "verify.csv"] {
        assert_eq!(
            std::fs::read(one.join(name)).unwrap(),
            std::fs::read(three.join(name)).unwrap(),
            "{name}"
        );
    }
    let (header, rows) = read_csv(&one.join("verify.csv"));
    assert_eq!(header, VERIFY_COLUMNS);
    assert_eq!(rows.len(), 10);
    let mut agree = 0;
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r[0], k.to_string());
        assert!([
            "saturated",
            "undetermined",
            "stalled",
            "converged",
            "limit_cycle",
            "diverged",
            "left_field",
            "invalid"
        ]
        .contains(&r[5].as_str()));
        assert!(["stable", "unstable", "no_equilibrium", "not_computed"].contains(&r[4].as_str()));
        agree += usize::from(r[6] == "true");
    }
    let v = &j["map"]["verify"];
    assert_eq!(v["agree"], agree);
    let compared = rows.iter().filter(|r| !r[6].is_empty()).count();
    assert_eq!(v["compared"], compared);
    let undetermined = rows.iter().filter(|r| r[5] == "undetermined").count();
    assert_eq!(v["undetermined"], undetermined);
    assert_eq!(v["not_compared"], 10 - compared);
    let runs = &j["map"]["verify_runs"];
    assert_eq!(
        (&runs["requested"], &runs["finished"]),
        (&10.into(), &10.into())
    );
    assert_eq!(runs["partial"], false);
}

/// Test (5): bad inputs give the README's exit codes, with a message naming the flag, before
/// anything is written: 64 for the command line (an option of `--map` without it, `--map`
/// without `--out`, a malformed or empty range, a rate faster than the simulation steps, a
/// grid too large, a verify count out of range or too many steps in all); 73 for an output
/// that cannot be written (a file where the directory should be, a FIFO where a file goes,
/// refused at once rather than blocking); 65 for a scenario the chart does not apply to.
#[test]
fn bad_map_inputs_have_the_readmes_exit_codes() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let out = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, i32, &str)> = vec![
        (vec!["--out", out], 64, "--out is an option of --map"),
        (vec!["--verify", "5"], 64, "--verify is an option of --map"),
        (vec!["--dpi", "0"], 64, "--dpi is an option of --map"),
        (
            vec!["--colormap", "nope"],
            64,
            "--colormap is an option of --map",
        ),
        (vec!["--size", "0x0"], 64, "--size is an option of --map"),
        (vec!["--title", "t"], 64, "--title is an option of --map"),
        (
            vec!["--font-size", "3"],
            64,
            "--font-size is an option of --map",
        ),
        (
            vec!["--threads", "2"],
            64,
            "--threads is an option of --map",
        ),
        (vec!["--map"], 64, "--map needs --out"),
        // Issue 29 (fix29c), 3: gray and copper drew byte-identical charts (the chart's own
        // diverging palette); refused with --map, the default's name as much as any other.
        (
            vec!["--map", "--out", out, "--colormap", "gray"],
            64,
            "--colormap is not an option of check --map",
        ),
        (
            vec!["--map", "--out", out, "--colormap", "copper"],
            64,
            "--colormap is not an option of check --map",
        ),
        (
            vec!["--map", "--out", out, "--colormap", "viridis"],
            64,
            "--colormap is not an option of check --map",
        ),
        (
            vec!["--colormap", "viridis"],
            64,
            "--colormap is an option of --map",
        ),
        (
            vec!["--map", "--out", out, "--kp-range", "5:1"],
            64,
            "--kp-range",
        ),
        (
            vec!["--map", "--out", out, "--kp-range", "0:1"],
            64,
            "--kp-range",
        ),
        (
            vec!["--map", "--out", out, "--kp-range", "abc"],
            64,
            "--kp-range",
        ),
        (
            vec!["--map", "--out", out, "--rate-range", "1:nan"],
            64,
            "--rate-range",
        ),
        (
            vec!["--map", "--out", out, "--rate-range", "1:1000"],
            64,
            "at most 100 Hz",
        ),
        // A hostile review's two hangs: a period beyond MAX_STEPS steps, and HI/LO overflowing.
        (
            vec!["--map", "--out", out, "--rate-range", "1e-50:2e-50"],
            64,
            "slower than a sensor period may be",
        ),
        (
            vec!["--map", "--out", out, "--kp-range", "1e-310:1"],
            64,
            "subnormal",
        ),
        // No rate 1/(k dt) in 60..65 Hz at dt 0.01 s: verify runs would fall outside the chart.
        (
            vec![
                "--map",
                "--out",
                out,
                "--rate-range",
                "60:65",
                "--map-size",
                "3x3",
                "--verify",
                "3",
            ],
            64,
            "whole number of sim.dt_s",
        ),
        (
            vec!["--map", "--out", out, "--map-size", "1000x1000"],
            64,
            "--map-size",
        ),
        (
            vec!["--map", "--out", out, "--map-size", "300x300"],
            64,
            "at most 40000",
        ),
        (
            vec!["--map", "--out", out, "--map-size", "1x5"],
            64,
            "--map-size",
        ),
        (
            vec!["--map", "--out", out, "--map-size", "7by5"],
            64,
            "--map-size",
        ),
        // A hostile review: accepted silently. Exactly NxM, decimal digits and a lower-case x.
        (
            vec!["--map", "--out", out, "--map-size", "3X4"],
            64,
            "--map-size",
        ),
        (
            vec!["--map", "--out", out, "--map-size", "+3x4"],
            64,
            "--map-size",
        ),
        (
            vec!["--map", "--out", out, "--map-size", "3x 4"],
            64,
            "--map-size",
        ),
        (
            vec!["--map", "--out", out, "--threads", "0"],
            64,
            "--threads",
        ),
        (vec!["--map", "--out", out, "--verify", "0"], 64, "--verify"),
        (
            vec!["--map", "--out", out, "--verify", "100000"],
            64,
            "--verify",
        ),
        (
            vec![
                "--map",
                "--out",
                out,
                "--verify",
                "1000",
                "--set",
                "sim.duration_s=30000",
            ],
            64,
            "simulation steps",
        ),
        (
            vec![
                "--map",
                "--out",
                out,
                "--set",
                "controller.kind=sliding_mode",
            ],
            65,
            "PI-like law",
        ),
    ];
    for (args, code, needle) in cases {
        let mut all = vec!["check"];
        all.extend(args.iter());
        let o = isotrack(&all);
        assert_fails(&o, code, &[needle]);
        assert!(!Path::new(out).exists(), "{args:?} wrote {out}");
    }
    // A huge value is echoed clipped (README: at most 200 characters of any value).
    let huge = "9".repeat(100_000);
    let o = isotrack(&["check", "--map", "--out", out, "--kp-range", &huge]);
    assert_fails(&o, 64, &["--kp-range", "more characters"]);
    assert!(stderr(&o).len() < 1000, "{}", stderr(&o).len());
    // A regular file where the directory goes.
    let file = common::write(d.path(), "file", "x");
    let o = isotrack(&["check", "--map", "--out", &file, "--map-size", "3x3"]);
    assert_fails(&o, 73, &["cannot write"]);
    // A FIFO where the CSV goes: refused at once, never opened.
    #[cfg(unix)]
    {
        let dir = d.path().join("fifo");
        std::fs::create_dir(&dir).unwrap();
        common::fifo(&dir, "stability_map.csv");
        let o = isotrack_within(
            &[
                "check",
                "--map",
                "--out",
                dir.to_str().unwrap(),
                "--map-size",
                "3x3",
            ],
            60,
        );
        assert_fails(&o, 73, &["not a regular file"]);
    }
}

/// A hostile review's data loss: a scenario whose grid file is `DIR/stability_map.csv` had its
/// data replaced by the chart (exit 0). Every output is checked against the scenario's data files
/// too: 64, and the grid left as it was.
#[test]
fn the_chart_never_overwrites_the_fields_data_file() {
    let d = tempfile::tempdir().unwrap();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = d.path().join("o");
    std::fs::create_dir_all(&out).unwrap();
    let grid = out.join("stability_map.csv");
    std::fs::copy(repo.join("data/volcano/volcano.csv"), &grid).unwrap();
    let before = std::fs::read(&grid).unwrap();
    let text = std::fs::read_to_string(repo.join("scenarios/volcano.toml"))
        .unwrap()
        .replace("../data/volcano/volcano.csv", grid.to_str().unwrap());
    assert!(
        text.contains(grid.to_str().unwrap()),
        "the scenario names the grid"
    );
    let sc = d.path().join("v.toml");
    std::fs::write(&sc, text).unwrap();
    let o = isotrack(&[
        "check",
        sc.to_str().unwrap(),
        "--map",
        "--out",
        out.to_str().unwrap(),
        "--map-size",
        "3x3",
    ]);
    assert_fails(&o, 64, &["an output cannot be one of the inputs"]);
    assert_eq!(
        std::fs::read(&grid).unwrap(),
        before,
        "the grid is untouched"
    );
}

fn map_args<'a>(out: &'a str, sc: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec![
        "check",
        sc,
        "--set",
        "controller.ki=0",
        "--set",
        "sim.duration_s=100",
        "--map",
        "--out",
        out,
        "--kp-range",
        "0.3:30",
        "--rate-range",
        "1:10",
        "--map-size",
        "5x3",
    ];
    v.extend_from_slice(extra);
    v
}

/// A hostile review: `verify.csv` from an earlier `--verify` stayed beside a chart made
/// without it (a reader mixes them). It is removed, with a note.
#[test]
fn a_stale_verify_csv_is_removed() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let (o, sc) = (out.to_str().unwrap(), scenario());
    let r = isotrack(&map_args(o, &sc, &["--verify", "2"]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    assert!(out.join("verify.csv").exists());
    let r = isotrack(&map_args(o, &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    assert!(
        !out.join("verify.csv").exists(),
        "a stale verify.csv stayed"
    );
    assert!(stderr(&r).contains("removed"), "{}", stderr(&r));
    assert!(out.join("stability_map.csv").exists());
}

/// The files of `dir` (hidden ones too) with their bytes, sorted.
fn listing(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let bytes = std::fs::read(e.path()).unwrap_or_default();
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    v.sort();
    v
}

/// att41-11 SAFETY: `check --map --out DIR` deleted the user's own `verify.csv` (no --verify
/// even asked for) and replaced their `stability_map.csv`, `.png`, `.svg`. A table no
/// `.isotrack-tables.json` records and a figure without isotrack's mark are the user's:
/// refused (73, naming the file) before anything is computed, every file as it was. So is an
/// older isotrack's chart table (its eight columns, before `note`; recorded nowhere) and the
/// unmarked figures beside it (att44-4, att44-11: the grace att42-2 gave them is over, since a
/// copy of this isotrack's chart made without its record passed for one). Fails on the source
/// before (exit 0, verify.csv gone, the others replaced).
#[test]
fn the_chart_never_replaces_nor_removes_a_users_file() {
    let d = tempfile::tempdir().unwrap();
    let sc = scenario();
    let older = format!(
        "{}\n1,1,1,0.5,true,stable,1,1\n",
        MAP_COLUMNS[..8].join(",")
    );
    let unrecorded = "no .isotrack-tables.json beside it records it";
    for (name, text, why) in [
        ("stability_map.csv", "MY DATA\n", unrecorded),
        ("stability_map.csv", older.as_str(), unrecorded),
        ("verify.csv", "MY VERIFY\n", unrecorded),
        (
            "stability_map.png",
            "MY PIC\n",
            "not a figure isotrack wrote",
        ),
        (
            "stability_map.svg",
            "<svg/>\n",
            "not a figure isotrack wrote",
        ),
    ] {
        let out = d
            .path()
            .join(format!("{}-{}", name.replace('.', "_"), text.len()));
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join(name), text).unwrap();
        std::fs::write(out.join("notes.txt"), "mine").unwrap();
        let before = listing(&out);
        let r = isotrack(&map_args(out.to_str().unwrap(), &sc, &[]));
        let named = out.join(name).display().to_string();
        assert_fails(&r, 73, &[&named, why, "move it away"]);
        assert_eq!(listing(&out), before, "{name}");
    }
}

/// att44-4, att44-11 SAFETY: a chart directory copied the usual way (`cp -r D/* E/`: the glob
/// leaves `.isotrack-tables.json` behind) passed for an older isotrack's: the user's
/// annotation of `E/stability_map.csv` was replaced (exit 0), and so were the user's own
/// unmarked `stability_map.png` and `.svg` put beside the copied table. Each is refused (73,
/// naming it), E as it was byte for byte; in D, where the record is, a second `check --map`
/// replaces the chart as before. Fails on the source before (exit 0, the files replaced).
#[test]
fn a_chart_copied_without_its_record_is_not_taken_for_isotracks() {
    let d = tempfile::tempdir().unwrap();
    let sc = scenario();
    let dd = d.path().join("D");
    let r = isotrack(&map_args(dd.to_str().unwrap(), &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    let copy = |e: &Path| {
        std::fs::create_dir(e).unwrap();
        for f in [
            "stability_map.csv",
            "stability_map.png",
            "stability_map.svg",
        ] {
            std::fs::copy(dd.join(f), e.join(f)).unwrap();
        }
    };
    // E5: the copied table annotated; E6: the copied table, the user's own figures (no
    // isotrack mark) beside it; E7: those figures alone. Each refused, naming the file.
    let (e5, e6, e7) = (
        d.path().join("E5"),
        d.path().join("E6"),
        d.path().join("E7"),
    );
    copy(&e5);
    let csv = e5.join("stability_map.csv");
    let mut mine = std::fs::read_to_string(&csv).unwrap();
    mine.push_str("# mine\n");
    std::fs::write(&csv, &mine).unwrap();
    for e in [&e6, &e7] {
        copy(e);
        std::fs::write(
            e.join("stability_map.png"),
            b"\x89PNG\r\n\x1a\nmy own picture",
        )
        .unwrap();
        std::fs::write(e.join("stability_map.svg"), "<svg>my own drawing</svg>\n").unwrap();
    }
    std::fs::remove_file(e7.join("stability_map.csv")).unwrap();
    let unrecorded = "no .isotrack-tables.json beside it records it";
    for (e, named, why) in [
        (&e5, "stability_map.csv", unrecorded),
        (&e6, "stability_map.csv", unrecorded),
        (&e7, "stability_map.png", "not a figure isotrack wrote"),
    ] {
        let before = listing(e);
        let r = isotrack(&map_args(e.to_str().unwrap(), &sc, &[]));
        let path = e.join(named).display().to_string();
        assert_fails(&r, 73, &[&path, why, "move it away"]);
        assert_eq!(&listing(e), &before, "{}", e.display());
    }
    assert_eq!(std::fs::read_to_string(&csv).unwrap(), mine);
    // D itself, its record beside its files: replaced as before.
    let r = isotrack(&map_args(dd.to_str().unwrap(), &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
}

/// att42-8 SAFETY: the header and the mark said who first wrote a file, not that nobody edited
/// it since: the user's edited `stability_map.csv` (the same header, a cell changed) and
/// annotated `stability_map.svg` (a `<text>` added in Inkscape or by hand, the mark kept) were
/// replaced without a word. Each is refused (73, naming it and saying it was edited since
/// isotrack wrote it) before anything is computed, every file as it was; as isotrack wrote
/// them, a second `check --map` replaces them; a `verify.csv` of the user's with isotrack's
/// header, in a directory where isotrack records its tables and none of that name, is the
/// user's too.
#[test]
fn a_chart_edited_since_isotrack_wrote_it_is_the_users() {
    let d = tempfile::tempdir().unwrap();
    let sc = scenario();
    let out = d.path().join("o");
    let outs = out.display().to_string();
    let r = isotrack(&map_args(&outs, &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    assert!(out.join(".isotrack-tables.json").exists());
    let r = isotrack(&map_args(&outs, &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    let csv = out.join("stability_map.csv");
    let svg = out.join("stability_map.svg");
    let (table, figure) = (std::fs::read(&csv).unwrap(), std::fs::read(&svg).unwrap());
    let text = String::from_utf8(figure.clone()).unwrap();
    let at = text.rfind("</svg>").unwrap();
    let annotated = format!(
        "{}<text x=\"9\" y=\"9\">my note</text>{}",
        &text[..at],
        &text[at..]
    );
    let mut edited = table.clone();
    let last = edited.len() - 2;
    edited[last] = if edited[last] == b'1' { b'2' } else { b'1' };
    for (file, bytes) in [(&csv, edited), (&svg, annotated.into_bytes())] {
        std::fs::write(file, &bytes).unwrap();
        let before = listing(&out);
        let r = isotrack(&map_args(&outs, &sc, &[]));
        let named = file.display().to_string();
        assert_fails(
            &r,
            73,
            &[&named, "edited since isotrack wrote it", "move it away"],
        );
        assert_eq!(listing(&out), before, "{named}");
        std::fs::write(&csv, &table).unwrap();
        std::fs::write(&svg, &figure).unwrap();
    }
    let mine = format!("{}\n0,1,1,1,1,1,1,1,1,1,mine\n", VERIFY_COLUMNS.join(","));
    std::fs::write(out.join("verify.csv"), &mine).unwrap();
    let r = isotrack(&map_args(&outs, &sc, &[]));
    assert_fails(&r, 73, &["verify.csv", "records none of this name"]);
    assert_eq!(
        std::fs::read_to_string(out.join("verify.csv")).unwrap(),
        mine
    );
    std::fs::remove_file(out.join("verify.csv")).unwrap();
    let r = isotrack(&map_args(&outs, &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
}

/// One writer per directory: while another holds `DIR/.isotrack.lock` (as `sweep` does),
/// `check --map --out DIR` exits 73 and writes nothing.
#[test]
fn a_locked_output_directory_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    std::fs::create_dir_all(&out).unwrap();
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(out.join(".isotrack.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let sc = scenario();
    let r = isotrack(&map_args(out.to_str().unwrap(), &sc, &[]));
    assert_fails(&r, 73, &["lock"]);
    assert!(!out.join("stability_map.csv").exists());
    drop(lock);
    let r = isotrack(&map_args(out.to_str().unwrap(), &sc, &[]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
}

/// A hostile review: `--kp-range 1:1e308` printed a 309-digit number. The user's numbers are
/// echoed as written, and the cells past the float range are "not computed", with a note, not
/// "no equilibrium".
#[test]
fn huge_ranges_are_echoed_as_written_and_not_called_no_equilibrium() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let sc = scenario();
    let r = isotrack(&[
        "check",
        sc.as_str(),
        "--set",
        "controller.ki=0",
        "--map",
        "--out",
        out.to_str().unwrap(),
        "--kp-range",
        "1:1e308",
        "--map-size",
        "3x2",
    ]);
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    let text = String::from_utf8_lossy(&r.stdout).to_string();
    assert!(text.contains("kp 1 .. 1e308"), "{text}");
    assert!(!text.contains("0000000000"), "{text}");
    let (_, rows) = read_csv(&out.join("stability_map.csv"));
    let top: Vec<_> = rows.iter().filter(|r| r[0] == "1e308").collect();
    assert_eq!(top.len(), 2);
    for r in top {
        assert_eq!(r[5], "not_computed", "{r:?}");
        assert!(r[8].contains("overflow"), "{r:?}");
    }
}

/// Runs `check --map --verify 60` on one thread over 20000 s runs into `out`, sends `signal`
/// (`-INT`, `-TERM`, `-HUP`) once the chart is written and the runs have started, and returns
/// the command's output.
#[cfg(unix)]
fn verify_stopped_by(signal: &str, out: &Path) -> std::process::Output {
    let sc = scenario();
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_isotrack"))
        .args([
            "check",
            sc.as_str(),
            "--set",
            "sim.duration_s=20000",
            "--map",
            "--out",
            out.to_str().unwrap(),
            "--map-size",
            "5x3",
            "--verify",
            "60",
            "--threads",
            "1",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let svg = out.join("stability_map.svg");
    for _ in 0..1200 {
        if svg.exists() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    assert!(svg.exists(), "the chart is written before the runs");
    std::thread::sleep(std::time::Duration::from_millis(300));
    let kill = std::process::Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    child.wait_with_output().unwrap()
}

/// Ctrl-C during `--verify` keeps the chart, written before the runs start, prints the report
/// of the runs that finished, marked partial, writes them to `verify.csv` (as many rows as the
/// report says finished) and exits 130 (128 + SIGINT) saying so (issue 29: no report at all).
#[cfg(unix)]
#[test]
fn ctrl_c_during_verify_keeps_the_chart() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let o = verify_stopped_by("-INT", &out);
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(stderr(&o).contains("interrupted"), "{}", stderr(&o));
    assert!(out.join("stability_map.png").exists() && out.join("stability_map.csv").exists());
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    let line = text
        .lines()
        .find(|l| l.contains("verify: PARTIAL (interrupted)"))
        .unwrap_or_else(|| panic!("no partial report: {text}"));
    let finished: usize = line
        .split("PARTIAL (interrupted): ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!(line.contains("of 60 runs finished"), "{line}");
    let (_, rows) = read_csv(&out.join("verify.csv"));
    assert_eq!(rows.len(), finished, "{line}");
}

/// Issue 29: the chart's files were written through a symbolic link planted in DIR (the link's
/// target overwritten). Each is refused (exit 73) and the target is left as it was.
#[cfg(unix)]
#[test]
fn the_charts_files_never_follow_a_link() {
    let sc = scenario();
    for name in [
        "stability_map.csv",
        "stability_map.png",
        "stability_map.svg",
        "verify.csv",
    ] {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("o");
        std::fs::create_dir_all(&out).unwrap();
        let target = d.path().join("precious.txt");
        std::fs::write(&target, "keep me").unwrap();
        std::os::unix::fs::symlink(&target, out.join(name)).unwrap();
        let o = isotrack(&map_args(out.to_str().unwrap(), &sc, &["--verify", "1"]));
        assert_fails(&o, 73, &[name]);
        assert_eq!(
            std::fs::read_to_string(&target).unwrap(),
            "keep me",
            "{name}"
        );
    }
}

/// Issue 29: a hostile review's inputs the chart accepted: `--map-size 04x3`, `--verify +5`,
/// `--verify 05`, `--threads +2` (counts are canonical digits, as `--shard`), a subnormal
/// `controller.kp = 1e-310` (its default range kp/100 .. 100 kp is subnormal: the key is
/// named) and `--kp-range 1e-310:1`. Each exits 64 with the reason. A 5000-character title
/// with an escape character is drawn clipped and escaped, as every echoed text.
#[test]
fn counts_are_canonical_ranges_normal_and_titles_bounded() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("o");
    let (o, sc) = (out.to_str().unwrap(), scenario());
    for (extra, needle) in [
        (vec!["--map-size", "04x3"], "--map-size"),
        (vec!["--verify", "+5"], "--verify"),
        (vec!["--verify", "05"], "--verify"),
        (vec!["--threads", "+2"], "--threads"),
        (vec!["--kp-range", "1e-310:1"], "subnormal"),
    ] {
        let mut args = vec!["check", sc.as_str(), "--map", "--out", o];
        args.extend_from_slice(&extra);
        let r = isotrack(&args);
        assert_fails(&r, 64, &[needle]);
    }
    let r = isotrack(&[
        "check",
        &sc,
        "--set",
        "controller.kp=1e-310",
        "--map",
        "--out",
        o,
    ]);
    // A subnormal gain is an invalid scenario (65), refused by `resolve` before the map.
    assert_fails(&r, 65, &["controller.kp", "subnormal"]);
    let title: String = std::iter::once('T')
        .chain(std::iter::once('\u{1b}'))
        .chain("x".repeat(5000).chars())
        .collect();
    let r = isotrack(&map_args(o, &sc, &["--title", &title]));
    assert_eq!(r.status.code(), Some(0), "{}", stderr(&r));
    let svg = std::fs::read_to_string(out.join("stability_map.svg")).unwrap();
    assert!(!svg.contains('\u{1b}'), "a raw escape character in the SVG");
    assert!(svg.contains("more characters)"), "the title is clipped");
    assert!(!svg.contains(&"x".repeat(1000)));
}

/// Issue 29 (fix29c), 3: `check --help` said `--colormap ... [default: viridis]` while the chart
/// is drawn in its own diverging palette: the help no longer claims a default for the chart and
/// says the chart refuses it.
#[test]
fn the_help_does_not_promise_a_colormap_for_the_chart() {
    let o = isotrack(&["check", "--help"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let help = String::from_utf8(o.stdout).unwrap();
    assert!(!help.contains("[default: viridis]"), "{help}");
    assert!(help.contains("Not for `check --map`"), "{help}");
}

/// att30c-7 (c): SIGTERM (a scheduler's) and SIGHUP (the terminal closed) during `--verify`
/// stop it as Ctrl-C does (the runs that finished reported, marked partial), and the command
/// exits 128 + the signal, 143 and 129, not Ctrl-C's 130.
#[cfg(unix)]
#[test]
fn sigterm_and_sighup_during_verify_exit_128_plus_the_signal() {
    for (signal, code) in [("-TERM", 143), ("-HUP", 129)] {
        let d = tempfile::tempdir().unwrap();
        let o = verify_stopped_by(signal, &d.path().join("o"));
        assert_eq!(o.status.code(), Some(code), "{signal}: {}", stderr(&o));
        assert!(stderr(&o).contains("interrupted"), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(text.contains("verify: PARTIAL (interrupted)"), "{text}");
    }
}

/// The arguments of a small chart (8 x 8, two verify runs, one thread) of `sc` into `out`: the
/// earlier chart the interrupt tests replace.
fn small_chart<'a>(sc: &'a str, out: &'a str) -> [&'a str; 11] {
    [
        "check",
        sc,
        "--map",
        "--map-size",
        "8x8",
        "--verify",
        "2",
        "--threads",
        "1",
        "--out",
        out,
    ]
}

/// att46-12: `check --map --verify N --out M` into M's own earlier chart, interrupted (exit
/// 130) before its chart is written, removed the earlier `verify.csv` up front while the
/// earlier `stability_map.csv` and figures stayed: a chart without its verification. The
/// earlier `verify.csv` now goes only as the new chart's table replaces the earlier one, in
/// the same step. The signal comes at a controlled point: as soon as the second command holds
/// M's lock (a 200x200 chart is then still being computed). After exit 130 either the earlier
/// chart's table and its `verify.csv` are there byte for byte, or the chart's table is new and
/// the earlier `verify.csv` is gone; no temporary nor lock file is left.
#[cfg(unix)]
#[test]
fn ctrl_c_before_the_new_chart_keeps_the_earlier_verify_csv() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let sc = scenario();
    let d = tempfile::tempdir().unwrap();
    let mut caught = false;
    for attempt in 0..4 {
        let m = d.path().join(format!("M{attempt}"));
        let ms = m.display().to_string();
        let first = small_chart(&sc, &ms);
        let o = isotrack_within(&first, 120);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let (csv, verify) = (m.join("stability_map.csv"), m.join("verify.csv"));
        let (csv0, verify0) = (
            std::fs::read(&csv).unwrap(),
            std::fs::read(&verify).unwrap(),
        );
        let lock = m.join(".isotrack.lock");
        let mut child = Command::new(env!("CARGO_BIN_EXE_isotrack"))
            .args([
                "check",
                sc.as_str(),
                "--map",
                "--map-size",
                "200x200",
                "--verify",
                "4",
                "--threads",
                "1",
                "--out",
                ms.as_str(),
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let t0 = Instant::now();
        while !lock.exists() && child.try_wait().unwrap().is_none() {
            assert!(t0.elapsed() < Duration::from_secs(120), "never locked");
            std::thread::sleep(Duration::from_millis(1));
        }
        // It may have ended first: its exit status says so below.
        let _ = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status();
        let o = child.wait_with_output().unwrap();
        if o.status.code() == Some(0) {
            continue;
        }
        assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
        let litter: Vec<String> = std::fs::read_dir(&m)
            .unwrap()
            .flatten()
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| n.ends_with(".tmp") || n.contains(".tmp.") || n == ".isotrack.lock")
            .collect();
        assert_eq!(litter, Vec::<String>::new(), "attempt {attempt}");
        let csv1 = std::fs::read(&csv).unwrap();
        if csv1 == csv0 {
            caught = true;
            assert_eq!(
                std::fs::read(&verify).ok().as_ref(),
                Some(&verify0),
                "attempt {attempt}: the earlier chart lost its verify.csv"
            );
        } else if verify.exists() {
            assert_ne!(
                std::fs::read(&verify).unwrap(),
                verify0,
                "attempt {attempt}"
            );
        }
        // The next check into M takes every file there for isotrack's.
        let o = isotrack_within(&first, 120);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    }
    assert!(caught, "never interrupted before the new chart");
}

/// Starts `check SCENARIO --map --map-size 200x200 --threads 1 --out OUT` (stderr piped) and
/// sends it SIGINT once `ready(OUT)` holds (or it ended first: its status says so).
#[cfg(unix)]
fn big_chart_interrupted_when(
    sc: &str,
    out: &Path,
    ready: impl Fn(&Path) -> bool,
) -> std::process::Output {
    let o = out.display().to_string();
    let args = [
        "check",
        sc,
        "--map",
        "--map-size",
        "200x200",
        "--threads",
        "1",
        "--out",
        &o,
    ];
    common::interrupted_when(&args, || ready(out))
}

/// att48-1: `check --map --out M` into M's earlier chart, interrupted while drawing its
/// figures, left the NEW stability_map.csv (recorded) beside the earlier chart's .png/.svg,
/// the earlier verify.csv gone, and now and then printed "cannot draw
/// M/.stability_map.png.PID.tmp.png: No such file". The figures are drawn into their
/// temporaries first, then table and figures go in place in one uncut step. The signal comes
/// at a controlled point: as soon as the PNG's temporary appears. After exit 130 (quiet: no
/// error) M holds the earlier chart whole (table, both figures and verify.csv byte for byte)
/// or the new one whole (all three replaced, no verify.csv), and no temporary nor lock.
#[cfg(unix)]
#[test]
fn ctrl_c_while_drawing_leaves_one_chart_whole() {
    let sc = scenario();
    let d = tempfile::tempdir().unwrap();
    let mut caught = 0;
    for attempt in 0..4 {
        let m = d.path().join(format!("M{attempt}"));
        let ms = m.display().to_string();
        let first = small_chart(&sc, &ms);
        let o = isotrack_within(&first, 120);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let names = [
            "stability_map.csv",
            "stability_map.png",
            "stability_map.svg",
            "verify.csv",
        ];
        let before: Vec<Vec<u8>> = names
            .iter()
            .map(|n| std::fs::read(m.join(n)).unwrap())
            .collect();
        let drawing = |m: &Path| {
            std::fs::read_dir(m).unwrap().flatten().any(|e| {
                let n = e.file_name().to_string_lossy().into_owned();
                n.starts_with(".stability_map.png.") && n.contains(".tmp")
            })
        };
        let o = big_chart_interrupted_when(&sc, &m, drawing);
        let err = stderr(&o);
        if o.status.code() == Some(0) {
            continue;
        }
        assert_eq!(o.status.code(), Some(130), "attempt {attempt}: {err}");
        assert!(!err.contains("error"), "attempt {attempt}: {err}");
        let litter: Vec<String> = std::fs::read_dir(&m)
            .unwrap()
            .flatten()
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| n.ends_with(".tmp") || n.contains(".tmp.") || n == ".isotrack.lock")
            .collect();
        assert_eq!(litter, Vec::<String>::new(), "attempt {attempt}");
        let now: Vec<Option<Vec<u8>>> = names
            .iter()
            .map(|n| std::fs::read(m.join(n)).ok())
            .collect();
        let kept: Vec<bool> = now
            .iter()
            .zip(&before)
            .map(|(n, b)| n.as_ref() == Some(b))
            .collect();
        caught += 1;
        if kept != [true; 4] {
            assert_eq!(kept, [false; 4], "attempt {attempt}: a mixed chart");
            assert!(now[..3].iter().all(Option::is_some), "attempt {attempt}");
            assert_eq!(
                now[3], None,
                "attempt {attempt}: the earlier verify.csv kept"
            );
        }
    }
    assert!(caught > 0, "never interrupted while drawing");
}

/// att48-5: `check --map --out a/b/c` (none of them there) interrupted before writing anything
/// left the directories it created, empty. Each level it created is removed (innermost first);
/// the folder the user gave as its parent stays.
#[cfg(unix)]
#[test]
fn ctrl_c_before_the_chart_leaves_no_directory_it_created() {
    let sc = scenario();
    let d = tempfile::tempdir().unwrap();
    let mut caught = false;
    for attempt in 0..4 {
        let top = d.path().join(format!("a{attempt}"));
        let c = top.join("b").join("c");
        let o = big_chart_interrupted_when(&sc, &c, |c| c.join(".isotrack.lock").exists());
        if o.status.code() == Some(0) {
            continue;
        }
        assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
        caught = true;
        assert!(!top.exists(), "attempt {attempt}: {} left", top.display());
    }
    assert!(d.path().is_dir());
    assert!(caught, "never interrupted before the chart");
}

/// att51-1: `check --map --verify N --out M` interrupted after its chart was in place but
/// before the verify runs answered the signal exited 130 saying nothing of the verify (only
/// "interrupted during --verify: K of N runs finished" later on). Signalled as soon as the
/// chart's SVG is in place (a 200 x 200 chart: its verify points take a while): exit 130, the
/// chart whole, and the line says 0 of the 200 runs (each 20000 s: none finishes first).
#[cfg(unix)]
#[test]
fn ctrl_c_after_the_chart_before_any_verify_run_says_so() {
    let sc = scenario();
    let d = tempfile::tempdir().unwrap();
    let m = d.path().join("M");
    let ms = m.display().to_string();
    let args = [
        "check",
        sc.as_str(),
        "--set",
        "sim.duration_s=20000",
        "--map",
        "--map-size",
        "200x200",
        "--verify",
        "200",
        "--threads",
        "1",
        "--out",
        &ms,
    ];
    let o = common::interrupted_when(&args, || m.join("stability_map.svg").exists());
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(
        err.contains("interrupted during --verify: 0 of 200 runs finished"),
        "{err}"
    );
    for f in [
        "stability_map.csv",
        "stability_map.png",
        "stability_map.svg",
    ] {
        assert!(m.join(f).is_file(), "{f}: {err}");
    }
}
