//! att40-3: the check of a run directory's `scenario.toml` against its `summary.json` compares
//! both after resolving, every key; a run of each bundled scenario (`scenarios/*.toml`, cut
//! short), written as `isotrack run --out DIR` writes it, is read back whole: no false refusal.
//! att49-4/-5: at 600 s too (a steady-state window of 120 s or more, longer than the 60 s dwell, where
//! the window's numbers tie the convergence time and the team's even spread both ways), so
//! the rules `plot` and `report` check a summary by are met by every genuine run.

use isotrack_plot::RunData;
use isotrack_runs::summary::{scenario_toml, Summary};
use std::path::Path;

#[test]
fn an_unedited_run_of_every_bundled_scenario_is_read() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut names: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 10, "{names:?}");
    let d = tempfile::tempdir().unwrap();
    for (path, duration) in names.iter().flat_map(|p| [(p, "3.0"), (p, "600.0")]) {
        let set = [format!("sim.duration_s = {duration}")];
        let s = isotrack_scenario::load_scenario(Some(path), &set)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let dir = d.path().join(format!(
            "{}-{duration}",
            path.file_stem().unwrap().to_string_lossy()
        ));
        let out = isotrack_runs::rundir::RunDir::open(&dir, &[], &[], None).unwrap();
        let vehicles = if s.spec().team.is_some() {
            let mut trace = out.team_trace(s.is_flying()).unwrap();
            let team = isotrack_runs::trace::run_team_into(
                &s,
                trace.writer(),
                isotrack_sim::TeamThreads::new(1),
            )
            .unwrap()
            .unwrap();
            let summary = Summary::of_team(&s, Some(path), &team, &[]);
            out.finish(trace, &scenario_toml(&s), &summary).unwrap();
            team.runs.len()
        } else {
            let mut trace = out.trace(s.is_flying()).unwrap();
            let r = s.run(trace.writer());
            let summary = Summary::of_run(&s, Some(path), &r, &[]);
            out.finish(trace, &scenario_toml(&s), &summary).unwrap();
            1
        };
        let read =
            RunData::load_team(&dir).unwrap_or_else(|e| panic!("{}: refused: {e}", dir.display()));
        assert_eq!(read.len(), vehicles, "{}", dir.display());
    }
}
