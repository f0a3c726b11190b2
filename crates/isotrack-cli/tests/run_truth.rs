//! Issue 30 (att43): a run directory tells the truth about the data it ran over, and bad input
//! never aborts: a grid file too large for the memory (att43-5), runs over the same bytes at
//! two paths (att43-12), summaries without or with foreign data-file digests (att43-4).

mod common;
use common::{assert_fails, isotrack, stderr};
use std::path::Path;

/// The volcano scenario with its grid at `grid` (a path relative to the scenario's folder).
fn volcano_at(dir: &Path, name: &str, grid: &str) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/../../scenarios/volcano.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("../data/volcano/volcano.csv", grid);
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

fn volcano_csv() -> String {
    std::fs::read_to_string(format!(
        "{}/../../data/volcano/volcano.csv",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// `run SCENARIO --out DIR` for 2 s; panics unless it exits 0.
fn run_into(scen: &str, out: &Path) {
    let o = isotrack(&[
        "run",
        scen,
        "--set",
        "sim.duration_s=2",
        "--out",
        &out.display().to_string(),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// att43-5: a 3 GiB grid file (sparse: no disk) under an address-space limit of 1.5 GB aborted
/// (rc 134, "memory allocation of 3221225472 bytes failed"): the file is read whole, into one
/// buffer. Now it is the Limits table's memory refusal: 65, naming `field.path`, the file, the
/// bytes wanted and the memory.
#[cfg(target_os = "linux")]
#[test]
fn a_grid_larger_than_the_memory_is_refused_not_aborted() {
    let d = tempfile::tempdir().unwrap();
    let big = d.path().join("big.csv");
    std::fs::write(&big, "1,2\n3,4\n").unwrap();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&big)
        .unwrap()
        .set_len(3 << 30)
        .unwrap();
    let scen = volcano_at(d.path(), "big.toml", "big.csv");
    let o = std::process::Command::new("sh")
        .args([
            "-c",
            "ulimit -v 1500000 && exec \"$0\" run \"$1\" --set sim.duration_s=10 --quiet",
            env!("CARGO_BIN_EXE_isotrack"),
            &scen,
        ])
        .output()
        .unwrap();
    assert_fails(
        &o,
        65,
        &[
            "field.path",
            "big.csv",
            "3221225472 bytes",
            "memory this process may use",
        ],
    );
}

/// att43-12: two runs over the same bytes at two paths (a copied data folder) were refused as
/// "runs over different fields" though both summaries record the same SHA-256: compared by
/// their digests, they are drawn together; other bytes at the second path are still refused.
#[test]
fn runs_over_the_same_bytes_at_two_paths_are_one_field() {
    let d = tempfile::tempdir().unwrap();
    let csv = volcano_csv();
    for sub in ["a", "b"] {
        std::fs::create_dir(d.path().join(sub)).unwrap();
        std::fs::write(d.path().join(sub).join("v.csv"), &csv).unwrap();
    }
    let sa = volcano_at(d.path(), "sa.toml", "a/v.csv");
    let sb = volcano_at(d.path(), "sb.toml", "b/v.csv");
    run_into(&sa, &d.path().join("ra"));
    run_into(&sb, &d.path().join("rb"));
    let dir = |n: &str| d.path().join(n).display().to_string();
    for cmd in ["plot", "report"] {
        let out = dir(&format!("out-{cmd}"));
        let o = isotrack(&[cmd, &dir("ra"), &dir("rb"), "--out", &out]);
        assert_eq!(o.status.code(), Some(0), "{cmd}: {}", stderr(&o));
    }
    // Other bytes at b's path (every 0 a 5: another terrain), run again: two fields.
    std::fs::write(d.path().join("b/v.csv"), csv.replace('0', "5")).unwrap();
    run_into(&sb, &d.path().join("rb2"));
    let o = isotrack(&["plot", &dir("ra"), &dir("rb2"), "--out", &dir("x")]);
    assert_fails(&o, 65, &["different fields", "field.path"]);
}

/// att43-4: a run whose summary.json has no `data_files` (an older isotrack's) or `{}` was
/// drawn over the data file as it is now without a word: now with a note saying so. A summary
/// naming a file the scenario does not read (even with that file's right digest) is not this
/// run's: refused (65) naming `data_files` and the file; one lacking a file the scenario
/// reads too.
#[test]
fn a_summary_without_or_with_foreign_digests_is_said_or_refused() {
    let d = tempfile::tempdir().unwrap();
    let csv = volcano_csv();
    std::fs::write(d.path().join("v.csv"), &csv).unwrap();
    let other = d.path().join("other.csv");
    std::fs::write(&other, csv.replace('0', "5")).unwrap();
    let scen = volcano_at(d.path(), "s.toml", "v.csv");
    let run = d.path().join("r");
    run_into(&scen, &run);
    let summary_path = run.join("summary.json");
    let original: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&summary_path).unwrap()).unwrap();
    let with = |data_files: Option<serde_json::Value>| {
        let mut s = original.clone();
        let m = s.as_object_mut().unwrap();
        match data_files {
            Some(v) => m.insert("data_files".into(), v),
            None => m.remove("data_files"),
        };
        std::fs::write(&summary_path, s.to_string()).unwrap();
    };
    let plot = || {
        isotrack(&[
            "plot",
            &run.display().to_string(),
            "--out",
            &d.path().join("figs").display().to_string(),
        ])
    };
    for data_files in [None, Some(serde_json::json!({}))] {
        with(data_files);
        let o = plot();
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("recorded no data_files digests")
                && e.contains("the field drawn is its data file as it is now"),
            "{e}"
        );
    }
    // The other file, with its right digest: not the scenario's file.
    let sha = |p: &Path| {
        use sha2::Digest;
        sha2::Sha256::digest(std::fs::read(p).unwrap())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect::<String>()
    };
    let other_key = other.canonicalize().unwrap().display().to_string();
    with(Some(serde_json::json!({ other_key.clone(): sha(&other) })));
    assert_fails(
        &plot(),
        65,
        &["data_files names", "other.csv", "does not read"],
    );
    // The scenario's file and the other: still not this run's.
    let mine = d.path().join("v.csv").canonicalize().unwrap();
    let mine_key = mine.display().to_string();
    with(Some(serde_json::json!({
        mine_key.clone(): sha(&mine),
        other_key: sha(&other),
    })));
    assert_fails(&plot(), 65, &["data_files names", "other.csv"]);
    // As the run wrote it: drawn, no note.
    with(original.get("data_files").cloned());
    let o = plot();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("data_files"), "{}", stderr(&o));
    assert_eq!(
        original["data_files"],
        serde_json::json!({ mine_key: sha(&mine) })
    );
}
