//! `isotrack compare`: the paper's law against the baselines on one scenario.

use crate::cli::CompareArgs;
use crate::exit;
use crate::output::{num, run_to_trace, scenario_toml, write_summary};
use crate::run::invalid;
use crate::run::Failure;
use isotrack_scenario::schema::ControllerKind;
use isotrack_scenario::{apply_assignments, build_derived, load_scenario, Assignment, Scenario};
use isotrack_sim::{NoTrace, RunResult};
use std::io::Write;
use std::path::Path;

/// The columns of `comparison.csv`, in order.
pub const COMPARISON_COLUMNS: [&str; 10] = [
    "controller",
    "outcome",
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "chattering_radps2",
    "sign_changes_per_s",
    "control_effort",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
];

/// The scenario with `kind` as its controller: the scenario's own section when it already uses
/// that kind; otherwise the kind's defaults with the shared keys (level, turning side, turn-rate
/// limit, derivative estimator) carried over; then the `--gain` overrides for that kind.
pub fn variant(
    base: &Scenario,
    kind: ControllerKind,
    gains: &[String],
    origin: &str,
) -> Result<Scenario, Failure> {
    let mut file = base.file().clone();
    file.controller = file.controller.switched_to(kind);
    let prefix = format!("{}.", kind.name());
    let sets: Vec<Assignment> = gains
        .iter()
        .filter_map(|g| {
            g.strip_prefix(&prefix).map(|rest| Assignment {
                arg: format!("controller.{rest}"),
                label: format!("--gain {g}"),
            })
        })
        .collect();
    let file = apply_assignments(&file, &sets).map_err(invalid)?;
    build_derived(
        file,
        &format!("{origin} [{}]", kind.name()),
        Path::new("."),
        &sets,
    )
    .map_err(invalid)
}

/// Checks that each `--gain` is `KIND.KEY=VALUE` with a known kind.
pub fn check_gains(gains: &[String]) -> Result<(), Failure> {
    for g in gains {
        let ok = g
            .split_once('.')
            .and_then(|(k, rest)| ControllerKind::from_name(k).map(|_| rest.contains('=')));
        if ok != Some(true) {
            // Name the known kinds, and the nearest to what was typed (`--gain foo.kp=1`).
            let names = ControllerKind::ALL.map(|k| k.name());
            let typed = g.split_once('.').map_or(g.as_str(), |(k, _)| k);
            let kind_note = if ControllerKind::from_name(typed).is_some() {
                String::new()
            } else {
                let near = isotrack_scenario::load::closest_names(typed, &names);
                format!(
                    "; `{}` is not a controller kind{}; known kinds: {}",
                    isotrack_scenario::load::clip(typed),
                    if near.is_empty() {
                        String::new()
                    } else {
                        format!(" (did you mean `{}`?)", near.join("`, `"))
                    },
                    names.join(", ")
                )
            };
            return Err(Failure {
                code: exit::USAGE,
                message: format!(
                    "--gain {}: expected KIND.KEY=VALUE, e.g. sliding_mode.gamma=0.3{kind_note}",
                    isotrack_scenario::load::clip(g)
                ),
            });
        }
    }
    Ok(())
}

fn cell(x: Option<f64>) -> String {
    x.map_or_else(String::new, num)
}

fn md(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.3e}"))
}

/// Runs the command.
pub fn compare(a: &CompareArgs) -> Result<(), Failure> {
    let base = load_scenario(Some(&a.scenario), &a.set).map_err(invalid)?;
    let kinds: Vec<ControllerKind> = if a.controllers.is_empty() {
        ControllerKind::ALL.to_vec()
    } else {
        a.controllers
            .iter()
            .map(|n| {
                ControllerKind::from_name(n.trim()).ok_or_else(|| Failure {
                    code: exit::USAGE,
                    message: format!(
                        "unknown controller `{n}`; known: {}",
                        ControllerKind::ALL.map(|k| k.name()).join(", ")
                    ),
                })
            })
            .collect::<Result<_, _>>()?
    };
    check_gains(&a.gain)?;
    let origin = a.scenario.display().to_string();
    let cant = |what: &Path, e: std::io::Error| Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", what.display()),
    };
    let mut results: Vec<(ControllerKind, RunResult)> = Vec::new();
    for kind in kinds {
        let s = variant(&base, kind, &a.gain, &origin)?;
        // A baseline outside its own stated gain condition is said, not only run.
        let warnings = isotrack_scenario::check::baselines::baseline_warnings(&s);
        for w in &warnings {
            errln!("warning: {w}");
        }
        let r = if let Some(dir) = &a.out {
            let d = dir.join(kind.name());
            std::fs::create_dir_all(&d).map_err(|e| cant(&d, e))?;
            let r = run_to_trace(&s, &d.join("trace.csv")).map_err(|e| cant(&d, e))?;
            write_summary(
                &d.join("summary.json"),
                &s,
                Some(&a.scenario),
                &r,
                &isotrack_scenario::check::warnings(&s),
            )
            .map_err(|e| cant(&d, e))?;
            std::fs::write(d.join("scenario.toml"), scenario_toml(&s)).map_err(|e| cant(&d, e))?;
            r
        } else {
            s.run(&mut NoTrace)
        };
        results.push((kind, r));
    }
    outln!(
        "| controller | outcome | convergence (s) | steady max\\|eps\\| | steady rms | chattering (rad/s^2) | sign changes/s | effort (rad^2/s) | max isoline dist (m) |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|");
    for (k, r) in &results {
        let m = &r.metrics;
        outln!(
            "| {}{} | {} | {} | {} | {} | {} | {} | {:.3} | {} |",
            k.name(),
            if *k == ControllerKind::GradientReference {
                " (not coordinate-free)"
            } else {
                ""
            },
            r.outcome.as_str(),
            m.convergence_time_s
                .map_or("never".into(), |t| format!("{t:.1}")),
            md(m.steady_state_max_abs_error),
            md(m.steady_state_rms_error),
            md(m.chattering_radps2),
            m.sign_changes_per_s
                .map_or("-".into(), |v| format!("{v:.2}")),
            m.control_effort,
            md(m.steady_state_max_isoline_distance_m),
        );
    }
    if let Some(dir) = &a.out {
        let p = dir.join("comparison.csv");
        let mut w = std::io::BufWriter::new(std::fs::File::create(&p).map_err(|e| cant(&p, e))?);
        let mut text = COMPARISON_COLUMNS.join(",") + "\n";
        for (k, r) in &results {
            let m = &r.metrics;
            text += &[
                k.name().to_string(),
                r.outcome.as_str().to_string(),
                cell(m.convergence_time_s),
                cell(m.steady_state_max_abs_error),
                cell(m.steady_state_rms_error),
                cell(m.chattering_radps2),
                cell(m.sign_changes_per_s),
                num(m.control_effort),
                cell(m.steady_state_max_isoline_distance_m),
                cell(m.steady_state_rms_isoline_distance_m),
            ]
            .join(",");
            text += "\n";
        }
        w.write_all(text.as_bytes())
            .and_then(|_| w.flush())
            .map_err(|e| cant(&p, e))?;
        outln!(
            "\nwrote {} and one run directory per controller",
            p.display()
        );
    }
    Ok(())
}
