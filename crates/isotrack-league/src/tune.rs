//! The tuning procedure: a coordinate search over each built-in law's main gains, scored on the
//! tuning seeds only (docs/BENCHMARK.md states the same).
//!
//! For each key of the law, in the order of [`tuned_keys`]: try the current value times
//! `1, 0.5, 2, 0.25, 4` (or `0, 0.05, 0.2, 1` when it is 0; `alpha_star` capped at 1); keep the
//! value with the best mean score over the tuning seeds, the current one on ties. One pass over
//! the keys. Starting point: the task scenario's own gains when it uses the law, else the law's
//! defaults.

use crate::one_run::{run_scored, run_scored_lanes, LaneJob};
use crate::registry::Entrant;
use crate::score::Scoring;
use crate::suite::Task;
use isotrack_scenario::schema::ControllerKind;
use isotrack_scenario::Scenario;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// The keys the tuning varies for a law.
pub fn tuned_keys(kind: ControllerKind) -> &'static [&'static str] {
    match kind {
        ControllerKind::PiIsoline => &["kp", "ki"],
        ControllerKind::SlidingMode => &["gamma", "delta"],
        ControllerKind::SlidingModeSmooth => &["gamma", "boundary_layer"],
        ControllerKind::SuboptimalSosm => &["alpha_star"],
        ControllerKind::Pid => &["kp", "ki", "kd"],
        ControllerKind::PidCrossing => &["kp", "kd"],
        ControllerKind::GradientReference => &["ke", "k_heading"],
        ControllerKind::Schedule => &[],
    }
}

/// The candidate values tried for a key whose current value is `v`.
pub fn candidates(key: &str, v: f64) -> Vec<f64> {
    let mut c: Vec<f64> = if v == 0.0 {
        vec![0.0, 0.05, 0.2, 1.0]
    } else {
        [1.0, 0.5, 2.0, 0.25, 4.0].iter().map(|m| v * m).collect()
    };
    if key == "alpha_star" {
        c = c.into_iter().map(|x| x.min(1.0)).collect();
    }
    let mut out: Vec<f64> = vec![];
    for x in c {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// The resolved value of `controller.KEY` in a scenario.
fn resolved(s: &Scenario, key: &str) -> Option<f64> {
    let v = toml::Value::try_from(s.file()).ok()?;
    v.get("controller")?.get(key)?.as_float()
}

/// Tunes `kind` on `task` over `seeds`, by the score formula `scoring`: the gains to record
/// (`KEY = value`).
pub fn tune(
    base: &Scenario,
    task: &Task,
    kind: ControllerKind,
    seeds: &[u64],
    scoring: Scoring,
) -> BTreeMap<String, f64> {
    let entrant = Entrant::Builtin(kind);
    let mut gains = starting_gains(base, kind);
    if gains.is_empty() || seeds.is_empty() {
        return gains;
    }
    // Each seed's scenario (its `sim.seed`), shared by every candidate's run of that seed: a
    // field that follows the seed and its isoline are built once per seed.
    let seeded: Vec<Option<Scenario>> = seeds
        .iter()
        .map(|seed| base.derive(&[format!("sim.seed={seed}")], "seed").ok())
        .collect();
    let mean_score = |g: &BTreeMap<String, f64>| -> f64 {
        let total: f64 = seeds
            .par_iter()
            .zip(&seeded)
            .map(|(seed, b)| {
                let b = b.as_ref().unwrap_or(base);
                match run_scored(b, task, &entrant, Some(g), *seed, scoring) {
                    Ok(r) => r.score.total,
                    Err(_) => f64::NEG_INFINITY,
                }
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum();
        total / seeds.len() as f64
    };
    for key in tuned_keys(kind) {
        let Some(&current) = gains.get(*key) else {
            continue;
        };
        let tried: Vec<(f64, f64)> = if base.spec().team.is_none() {
            in_lanes(
                &Trials {
                    base,
                    seeded: &seeded,
                    task,
                    entrant: &entrant,
                    seeds,
                    scoring,
                },
                &gains,
                key,
                &candidates(key, current),
            )
        } else {
            candidates(key, current)
                .par_iter()
                .map(|&v| {
                    let mut g = gains.clone();
                    g.insert(key.to_string(), v);
                    (v, mean_score(&g))
                })
                .collect()
        };
        gains.insert(key.to_string(), best_candidate(&tried));
    }
    gains
}

/// The starting point of a tuning: the resolved gains of law `kind` on the task's scenario
/// `base` (its tuned keys, [`tuned_keys`]); none when the law does not apply to it.
fn starting_gains(base: &Scenario, kind: ControllerKind) -> BTreeMap<String, f64> {
    let mut gains: BTreeMap<String, f64> = BTreeMap::new();
    let Ok(start) = base.with_controller_kind(kind) else {
        return gains;
    };
    for key in tuned_keys(kind) {
        if let Some(v) = resolved(&start, key) {
            gains.insert(key.to_string(), v);
        }
    }
    gains
}

/// The value of the best-scoring `(value, mean score)` trial; the first candidate is the
/// current value, and it wins ties.
fn best_candidate(tried: &[(f64, f64)]) -> f64 {
    let mut best = tried[0];
    for &(v, s) in &tried[1..] {
        if s > best.1 {
            best = (v, s);
        }
    }
    best.0
}

/// What a law's trial runs share: the task's base scenario and its seeds' scenarios.
struct Trials<'a> {
    base: &'a Scenario,
    seeded: &'a [Option<Scenario>],
    task: &'a Task,
    entrant: &'a Entrant,
    seeds: &'a [u64],
    scoring: Scoring,
}

/// Each value of `values` for `key` (the other gains `gains`) and its mean score over the
/// seeds, as `tune`'s `mean_score` gives it, the runs of one vehicle stepped together
/// ([`run_scored_lanes`], issue 34): every (value, seed) run, seed by seed, in chunks of
/// [`isotrack_sim::LANES`]; each score is the one the run gives alone, and each mean is summed
/// in the seeds' order, as before.
fn in_lanes(
    t: &Trials<'_>,
    gains: &BTreeMap<String, f64>,
    key: &str,
    values: &[f64],
) -> Vec<(f64, f64)> {
    let trial: Vec<BTreeMap<String, f64>> = values
        .iter()
        .map(|&v| {
            let mut g = gains.clone();
            g.insert(key.to_string(), v);
            g
        })
        .collect();
    // (value, seed) by their places, seed by seed.
    let pairs: Vec<(usize, usize)> = (0..t.seeds.len())
        .flat_map(|k| (0..trial.len()).map(move |c| (c, k)))
        .collect();
    let scored: Vec<Vec<((usize, usize), f64)>> = pairs
        .par_chunks(isotrack_sim::LANES)
        .map(|chunk| {
            let jobs: Vec<LaneJob<'_>> = chunk
                .iter()
                .map(|&(c, k)| LaneJob {
                    base: t.seeded[k].as_ref().unwrap_or(t.base),
                    entrant: t.entrant,
                    gains: Some(&trial[c]),
                    seed: t.seeds[k],
                })
                .collect();
            let scores = run_scored_lanes(&jobs, t.task, t.scoring)
                .into_iter()
                .map(|r| r.map_or(f64::NEG_INFINITY, |r| r.score.total));
            chunk.iter().copied().zip(scores).collect()
        })
        .collect();
    let mut table = vec![vec![0.0; t.seeds.len()]; trial.len()];
    for ((c, k), score) in scored.into_iter().flatten() {
        table[c][k] = score;
    }
    values
        .iter()
        .zip(&table)
        .map(|(&v, row)| (v, row.iter().sum::<f64>() / t.seeds.len() as f64))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::suite::Suite;

    /// Issue 34: the tuning's trials stepped in lanes give each value the mean score of its
    /// runs flown one at a time ([`run_scored`], summed in the seeds' order): the 6-DOF UAV in
    /// gusts (a gust seed per lane) and a puff plume (a field per seed), five values of `kp`
    /// on three seeds.
    #[test]
    fn trials_in_lanes_score_as_runs_one_at_a_time() {
        let text = r#"
name = "trials"
version = 1
controllers = ["pi_isoline"]
tuning_seeds = [9001, 9002, 9003]
scoring_seeds = [1]

[[task]]
id = "uav"
title = "UAV in gusts"
scenario = "paper-fig3-uav.toml"
set = ["sim.duration_s=30.0", "vehicle.wind_mps=[6.0, 2.0]", "vehicle.gusts=true"]
length_m = 2131.0
vary = { "initial.heading_rad" = { uniform = [-3.0, 3.0] } }

[[task]]
id = "puff"
title = "puff plume"
scenario = "puff-plume-edge.toml"
set = ["sim.duration_s=20.0"]
length_m = 50.0
"#;
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let suite = Suite::parse(text, "trials.toml", &dir).unwrap();
        let entrant = Entrant::Builtin(ControllerKind::PiIsoline);
        for task in &suite.tasks {
            let base = crate::run::task_base(&suite, task).unwrap();
            let seeds = &suite.tuning_seeds;
            let seeded: Vec<Option<Scenario>> = seeds
                .iter()
                .map(|seed| base.derive(&[format!("sim.seed={seed}")], "seed").ok())
                .collect();
            let gains: BTreeMap<String, f64> = [("kp".to_string(), 8.0), ("ki".to_string(), 0.2)]
                .into_iter()
                .collect();
            let values = candidates("kp", 8.0);
            assert_eq!(values.len(), 5);
            let t = Trials {
                base: &base,
                seeded: &seeded,
                task,
                entrant: &entrant,
                seeds,
                scoring: suite.scoring,
            };
            let got = in_lanes(&t, &gains, "kp", &values);
            let want: Vec<(f64, f64)> = values
                .iter()
                .map(|&v| {
                    let mut g = gains.clone();
                    g.insert("kp".into(), v);
                    let scores: Vec<f64> = seeds
                        .iter()
                        .zip(&seeded)
                        .map(|(seed, b)| {
                            run_scored(
                                b.as_ref().unwrap(),
                                task,
                                &entrant,
                                Some(&g),
                                *seed,
                                suite.scoring,
                            )
                            .map_or(f64::NEG_INFINITY, |r| r.score.total)
                        })
                        .collect();
                    (v, scores.iter().sum::<f64>() / seeds.len() as f64)
                })
                .collect();
            assert_eq!(format!("{got:?}"), format!("{want:?}"), "task {}", task.id);
        }
    }
}
