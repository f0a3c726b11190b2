//! Issue 32: `isotrack plot` of a team's run (scenarios/team-circular-4.toml): every vehicle's
//! path in its own colour, `team.*` with the gaps over time and the revisit time along the
//! isoline, `--animate` of the team; the numbers read off the trace against the geometry.
mod common;
use common::isotrack;
use isotrack_plot::{RunData, TeamTracks};
use std::f64::consts::{LN_2, PI};

const TEAM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/team-circular-4.toml"
);

/// With `none` every robot runs at `v0` on a field symmetric under rotation, so the cluster
/// keeps its deployed gaps: `0.3 R` ahead of robots 0, 1 and 2 (listed in the order of travel),
/// `L - 0.9 R` ahead of robot 3; every point of the isoline then waits `(L - 0.9 R)/v0` between
/// the cluster's passes, the longest unvisited time over a window longer than a lap.
#[test]
fn team_figures_and_their_numbers() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("run");
    let o = isotrack(&[
        "run",
        TEAM,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "team.spacing=\"none\"",
        "--set",
        "sim.duration_s=200.0",
        "--set",
        "metrics.steady_state_fraction=0.9",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let vehicles = RunData::load_team(&out).unwrap();
    assert_eq!(vehicles.len(), 4);
    let r = 10.0 * LN_2;
    let l = 2.0 * PI * r;
    let tracks = TeamTracks::new(&vehicles).unwrap();
    assert!((tracks.length_m() - l).abs() < 1e-9);
    let gaps = tracks.gaps(10);
    assert!(gaps.len() > 100);
    for (t, g) in &gaps {
        for (i, want) in [0.3 * r, 0.3 * r, 0.3 * r, l - 0.9 * r].iter().enumerate() {
            assert!(
                (g[i] - want).abs() < 0.02 * want,
                "t {t}: gap {i} {} vs {want}",
                g[i]
            );
        }
    }
    let wait = (l - 0.9 * r) / 0.5;
    let revisit = tracks.revisit_max(20.0);
    assert_eq!(revisit.len(), isotrack_plot::REVISIT_BINS);
    for (s, w) in &revisit {
        assert!((w - wait).abs() < 0.02 * wait, "at {s} m: {w} vs {wait}");
    }

    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--format",
        "svg",
        "--animate",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    for f in [
        "trajectory.svg",
        "timeseries.svg",
        "team.svg",
        "animation.gif",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // Four paths, one per vehicle, each in its own colour, labelled in the legend.
    let svg = std::fs::read_to_string(out.join("trajectory.svg")).unwrap();
    for i in 0..4 {
        assert!(svg.contains(&format!("vehicle {i}")), "vehicle {i}");
    }
    let team = std::fs::read_to_string(out.join("team.svg")).unwrap();
    assert!(team.contains("gap ahead along the isoline"));
    assert!(team.contains("longest unvisited time"));
    // Titled by the scenario, not "4 runs".
    assert!(team.contains("team-circular-4"));

    // A vehicle cell that is not one of the team's: 65 naming the row, no figure.
    let trace = std::fs::read_to_string(out.join("trace.csv")).unwrap();
    let mut lines: Vec<String> = trace.lines().map(str::to_string).collect();
    let last = lines[3].rfind(',').unwrap();
    lines[3] = format!("{},9", &lines[3][..last]);
    std::fs::write(out.join("trace.csv"), lines.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        d.path().join("f").to_str().unwrap(),
    ]);
    common::assert_fails(
        &o,
        65,
        &["trace.csv row 3", "not one of the team's 4 vehicles"],
    );
    // att32: a row missing (vehicle 2's at the second recorded time, file line 8: header, four
    // rows at t = 0, then vehicles 0 and 1) pairs vehicle 2's positions with the others' at
    // another time: 65 naming the line where its rows go wrong (line 11 then, vehicle 2's next
    // row, its second row but at the third time); the last row of a vehicle that completed
    // (vehicle 3's, the file's last line) likewise.
    let original: Vec<&str> = trace.lines().collect();
    assert!(original[7].ends_with(",2") && original[11].ends_with(",2"));
    let mut cut: Vec<&str> = original.clone();
    cut.remove(7);
    std::fs::write(out.join("trace.csv"), cut.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        d.path().join("f").to_str().unwrap(),
    ]);
    common::assert_fails(&o, 65, &["trace.csv:11:", "vehicle 2's row 2", "missing"]);
    let mut cut: Vec<&str> = original.clone();
    let last = cut.pop().unwrap();
    assert!(last.ends_with(",3"));
    std::fs::write(out.join("trace.csv"), cut.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "plot",
        out.to_str().unwrap(),
        "--out",
        d.path().join("f").to_str().unwrap(),
    ]);
    common::assert_fails(
        &o,
        65,
        &["vehicle 3's rows end", "completed the run", "missing"],
    );
    // Back to the trace with the vehicle cell of another team.
    std::fs::write(out.join("trace.csv"), lines.join("\n") + "\n").unwrap();
    let o = isotrack(&[
        "report",
        out.to_str().unwrap(),
        "--out",
        d.path().join("r.html").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(65), "{}", common::stderr(&o));
}
