//! `isotrack run` and `isotrack show`.

use crate::cli::{RunArgs, ScenarioArgs};
use crate::exit;
use crate::output::{scenario_toml, write_summary, write_trace};
use isotrack_scenario::{load_scenario, Scenario, ScenarioError};
use isotrack_sim::{NoTrace, RunResult, TraceRow};

/// A command's failure: the message and the exit code.
#[derive(Debug)]
pub struct Failure {
    /// Exit code (see [`crate::exit`]).
    pub code: u8,
    /// What to print on stderr.
    pub message: String,
}

/// Loads the scenario named by the arguments.
pub fn load(args: &ScenarioArgs) -> Result<Scenario, Failure> {
    load_scenario(args.scenario.as_deref(), &args.set).map_err(|e| Failure {
        code: match e {
            ScenarioError::Io { .. } => exit::NOINPUT,
            ScenarioError::Invalid(_) => exit::DATAERR,
        },
        message: e.to_string(),
    })
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.4e}"))
}

/// A few lines a person reads after a run.
pub fn human_summary(name: &str, s: &Scenario, r: &RunResult) -> String {
    let m = &r.metrics;
    let f = s.file();
    let mut out = String::new();
    out += &format!("scenario    {name}\n");
    out += &format!(
        "outcome     {} at t = {:.2} s ({} steps, {} samples){}\n",
        r.outcome.as_str(),
        r.t_end_s,
        r.steps,
        r.samples,
        r.outcome_detail
            .as_ref()
            .map(|d| format!(": {d}"))
            .unwrap_or_default()
    );
    out += &format!(
        "steady state (last {:.0} %)  max|eps| {}  rms {}  mean {}\n",
        100.0 * f.metrics.steady_state_fraction.unwrap_or(0.2),
        fmt_opt(m.steady_state_max_abs_error),
        fmt_opt(m.steady_state_rms_error),
        fmt_opt(m.steady_state_mean_error),
    );
    out += &format!(
        "convergence {} (|eps| < {})\n",
        m.convergence_time_s
            .map_or_else(|| "never".to_string(), |t| format!("{t:.2} s")),
        f.metrics.convergence_tolerance.unwrap_or_default()
    );
    out += &format!(
        "path {:.1} m   control effort {:.4} rad^2/s   chattering {} rad/s^2\n",
        m.path_length_m,
        m.control_effort,
        fmt_opt(m.chattering_radps2)
    );
    out
}

/// `isotrack run`.
pub fn run(args: &RunArgs) -> Result<(), Failure> {
    let scenario = load(&args.scenario)?;
    let name = args.scenario.scenario.as_ref().map_or_else(
        || "<built-in default: paper Fig. 2(b)>".to_string(),
        |p| p.display().to_string(),
    );
    let result = if let Some(dir) = &args.out {
        let cant = |what: &str, e: std::io::Error| Failure {
            code: exit::CANTCREAT,
            message: format!("cannot write {what}: {e}"),
        };
        std::fs::create_dir_all(dir).map_err(|e| cant(&dir.display().to_string(), e))?;
        let mut rows: Vec<TraceRow> = Vec::new();
        let result = scenario.run(&mut rows);
        let trace = dir.join("trace.csv");
        write_trace(&trace, &rows).map_err(|e| cant(&trace.display().to_string(), e))?;
        let summary = dir.join("summary.json");
        write_summary(
            &summary,
            &scenario,
            args.scenario.scenario.as_deref(),
            &result,
        )
        .map_err(|e| cant(&summary.display().to_string(), e))?;
        let resolved = dir.join("scenario.toml");
        std::fs::write(&resolved, scenario_toml(&scenario))
            .map_err(|e| cant(&resolved.display().to_string(), e))?;
        if !args.quiet {
            print!("{}", human_summary(&name, &scenario, &result));
            println!(
                "wrote       {}, {}, {}",
                trace.display(),
                summary.display(),
                resolved.display()
            );
        }
        result
    } else {
        let result = scenario.run(&mut NoTrace);
        if !args.quiet {
            print!("{}", human_summary(&name, &scenario, &result));
        }
        result
    };
    let _ = result;
    Ok(())
}

/// `isotrack show`.
pub fn show(args: &ScenarioArgs) -> Result<(), Failure> {
    let scenario = load(args)?;
    print!("{}", scenario_toml(&scenario));
    Ok(())
}
