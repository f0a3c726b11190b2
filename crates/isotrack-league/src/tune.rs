//! The tuning procedure: a coordinate search over each built-in law's main gains, scored on the
//! tuning seeds only (docs/BENCHMARK.md states the same).
//!
//! For each key of the law, in the order of [`tuned_keys`]: try the current value times
//! `1, 0.5, 2, 0.25, 4` (or `0, 0.05, 0.2, 1` when it is 0; `alpha_star` capped at 1); keep the
//! value with the best mean score over the tuning seeds, the current one on ties. One pass over
//! the keys. Starting point: the task scenario's own gains when it uses the law, else the law's
//! defaults.

use crate::one_run::run_scored;
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
    let mut gains: BTreeMap<String, f64> = BTreeMap::new();
    // The starting point: the resolved gains of the law on this task.
    let Ok(start) = base.with_controller_kind(kind) else {
        return gains;
    };
    for key in tuned_keys(kind) {
        if let Some(v) = resolved(&start, key) {
            gains.insert(key.to_string(), v);
        }
    }
    if seeds.is_empty() {
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
        let tried: Vec<(f64, f64)> = candidates(key, current)
            .par_iter()
            .map(|&v| {
                let mut g = gains.clone();
                g.insert(key.to_string(), v);
                (v, mean_score(&g))
            })
            .collect();
        // The first candidate is the current value: it wins ties.
        let mut best = tried[0];
        for &(v, s) in &tried[1..] {
            if s > best.1 {
                best = (v, s);
            }
        }
        gains.insert(key.to_string(), best.0);
    }
    gains
}
