//! Issue 32: `isotrack sweep` over team keys of scenarios/team-circular-4.toml: `results.csv`
//! gains the team columns (last, for a base with `[team]` only), with numbers from the
//! geometry: the ideal revisit time `L/(N v0)` and, for the `none` law (every robot at `v0` on
//! a field symmetric under rotation), the deployed cluster's gap CV.
mod common;
use common::{assert_fails, isotrack, write};
use std::f64::consts::{LN_2, PI};

const TEAM: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../scenarios/team-circular-4.toml"
);

const TEAM_COLUMNS: [&str; 7] = [
    "gap_cv",
    "time_to_even_s",
    "revisit_time_max_s",
    "revisit_time_mean_s",
    "revisit_time_ideal_s",
    "min_separation_m",
    "order_preserved",
];

/// The gap CV of robots `0.3 rad` apart on a circle (`n` of them): gaps `0.3` (`n - 1` times)
/// and `2 pi - 0.3 (n - 1)`, population standard deviation over the mean `2 pi/n`.
fn cluster_cv(n: usize) -> f64 {
    let mut gaps = vec![0.3; n - 1];
    gaps.push(2.0 * PI - 0.3 * (n - 1) as f64);
    let mean = 2.0 * PI / n as f64;
    (gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n as f64).sqrt() / mean
}

fn read_csv(path: &std::path::Path) -> (Vec<String>, Vec<Vec<String>>) {
    let mut r = csv::Reader::from_path(path).unwrap();
    let header = r.headers().unwrap().iter().map(str::to_string).collect();
    let rows = r
        .records()
        .map(|x| x.unwrap().iter().map(str::to_string).collect())
        .collect();
    (header, rows)
}

#[test]
fn team_keys_sweep_with_team_columns() {
    let d = tempfile::tempdir().unwrap();
    let sweep = write(
        d.path(),
        "team.toml",
        &format!(
            "scenario = {TEAM:?}\n[base]\nsim.duration_s = 120.0\n[grid]\nteam.count = [3, 4]\nteam.spacing = [\"none\", \"range_balance\"]\nteam.k_v = [0.1]\nteam.ranging.noise_std_m = [0.0]\n"
        ),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let (header, rows) = read_csv(&out.join("results.csv"));
    assert_eq!(header[header.len() - 7..], TEAM_COLUMNS);
    assert_eq!(rows.len(), 4);
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let f = |r: &Vec<String>, n: &str| r[col(n)].parse::<f64>().unwrap();
    let l = 2.0 * PI * 10.0 * LN_2;
    for r in &rows {
        assert_eq!(r[col("outcome")], "completed", "{r:?}");
        let n: usize = r[col("team.count")].parse().unwrap();
        // L/(N v0) with v0 = 0.5 m/s.
        let ideal = l / (n as f64 * 0.5);
        assert!(
            (f(r, "revisit_time_ideal_s") - ideal).abs() < 1e-9 * ideal,
            "{r:?}"
        );
        let cv = f(r, "gap_cv");
        if r[col("team.spacing")] == "none" {
            // Spacing stays as deployed: the cluster's CV.
            let want = cluster_cv(n);
            assert!((cv - want).abs() < 0.01 * want, "n {n}: {cv} vs {want}");
            assert_eq!(r[col("order_preserved")], "true");
        } else {
            assert!(cv < 0.5 * cluster_cv(n), "n {n}: {cv}");
        }
        assert!(f(r, "min_separation_m") > 0.0);
    }
    // --resume reads the team rows back (each checked) and runs nothing new.
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("(0 new)"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // A damaged team cell is refused on --resume.
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let bad = text.replacen(",true\n", ",maybe\n", 1);
    assert_ne!(bad, text);
    std::fs::write(out.join("results.csv"), bad).unwrap();
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap(), "--resume"]);
    assert!(!o.status.success());
    assert!(
        common::stderr(&o).contains("order_preserved"),
        "{}",
        common::stderr(&o)
    );
}

/// A single-vehicle base keeps its columns; a team key swept onto it is an invalid run naming
/// `[team]`, not a row under the wrong header.
#[test]
fn team_keys_on_a_single_vehicle_base_are_invalid_runs() {
    let d = tempfile::tempdir().unwrap();
    let one = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/paper-fig2b-circular.toml"
    );
    let sweep = write(
        d.path(),
        "one.toml",
        &format!("scenario = {one:?}\n[base]\nsim.duration_s = 10.0\n[grid]\nteam.count = [2]\n"),
    );
    let out = d.path().join("out");
    let o = isotrack(&["sweep", &sweep, "--out", out.to_str().unwrap()]);
    assert_fails(&o, 65, &["invalid"]);
    let (header, rows) = read_csv(&out.join("results.csv"));
    assert!(!header.iter().any(|h| h == "gap_cv"), "{header:?}");
    assert_eq!(
        rows[0][header.iter().position(|h| h == "outcome").unwrap()],
        "invalid_scenario"
    );
    assert!(rows[0].last().is_some());
    let detail = &rows[0][header.iter().position(|h| h == "outcome_detail").unwrap()];
    assert!(detail.contains("team"), "{detail}");
}
