//! `isotrack run`, `isotrack show` and `isotrack check`.

use crate::cli::{CheckArgs, RunArgs, ScenarioArgs};
use crate::exit;
use crate::output::{scenario_toml, RunDir, Summary};
use isotrack_core::numtext::Echo;
use isotrack_scenario::Scenario;
use isotrack_sim::{NoTrace, RunResult};

/// A command's failure: the message and the exit code (see [`crate::exit`]).
pub use isotrack_runs::Failure;

pub use crate::load::{invalid, load};

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.4e}"))
}

/// A team line's time or distance with its unit: to 0.01 as the line's other times and
/// its ideal print (nu36-3: `revisit max 2.1780e1 s (ideal 21.78 s)` mixed two formats), a
/// value below 0.01 in [`fmt_opt`]'s form so that it does not print as 0.00; `n/a` alone
/// (never `n/a m`) when missing or not finite.
fn fmt_opt_unit(x: Option<f64>, unit: &str) -> String {
    match x {
        Some(v) if v.is_finite() && (v == 0.0 || v.abs() >= 0.01) => format!("{v:.2} {unit}"),
        // att38-4: under 0.01 in decimals too, to three significant digits (`0.00069 m` beside
        // `2.07 m`, not `6.9315e-4 m`), in exponent form only below 1e-9.
        Some(v) if v.is_finite() && v.abs() >= 1e-9 => format!("{} {unit}", significant(v, 3)),
        Some(v) if v.is_finite() => format!("{v:.2e} {unit}"),
        _ => "n/a".to_string(),
    }
}

/// `v` (finite, not zero) in decimals to `digits` significant digits, trailing zeros kept.
fn significant(v: f64, digits: i32) -> String {
    let mag = v.abs().log10().floor() as i32;
    let decimals = (digits - 1 - mag).clamp(0, 17) as usize;
    format!("{v:.decimals$}")
}

/// A team line's ratio (`gap_cv`): four significant digits in decimals between 1e-3 and 1e4
/// (att38-4: `1.7321e0` printed in exponent form at any size), in exponent form outside (a
/// converged team's `2.900e-11`); `n/a` when missing or not finite.
fn fmt_ratio(x: Option<f64>) -> String {
    match x {
        Some(0.0) => "0".to_string(),
        Some(v) if v.is_finite() && (1e-3..1e4).contains(&v.abs()) => significant(v, 4),
        Some(v) if v.is_finite() => format!("{v:.3e}"),
        _ => "n/a".to_string(),
    }
}

/// A few lines a person reads after a run.
pub fn human_summary(name: &str, s: &Scenario, r: &RunResult) -> String {
    let m = &r.metrics;
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
        100.0 * s.spec().metrics.steady_state_fraction,
        fmt_opt(m.steady_state_max_abs_error),
        fmt_opt(m.steady_state_rms_error),
        fmt_opt(m.steady_state_mean_error),
    );
    out += &format!(
        "convergence {} (|eps| < {})\n",
        m.convergence_time_s
            .map_or_else(|| "never".to_string(), |t| format!("{t:.2} s")),
        Echo(s.spec().metrics.convergence_tolerance)
    );
    // Non-finite values print as in summary.json (null there, n/a here), never as `inf`.
    let fixed = |x: f64, digits: usize| {
        if x.is_finite() {
            format!("{x:.digits$}")
        } else {
            "n/a".to_string()
        }
    };
    out += &format!(
        "path {} m   control effort {} rad^2/s   chattering {} rad/s^2\n",
        fixed(m.path_length_m, 1),
        fixed(m.control_effort, 4),
        fmt_opt(m.chattering_radps2)
    );
    out
}

/// A team's lines after [`human_summary`] (vehicle 0's): the team metrics, or, without them,
/// `summary.json`'s `team.metrics_note` for `scenario` (one source for the reason, nu-16).
pub fn team_summary(scenario: &Scenario, t: &isotrack_sim::TeamResult) -> String {
    let mut out = format!("team        {} vehicles", t.runs.len());
    match &t.team {
        Some(m) => {
            // An open isoline's ideal is NaN without a steady-window sample of two vehicles
            // on it (`null` in summary.json): `n/a` as its neighbours print (att32f-4).
            let ideal = m.revisit_time_ideal_s;
            let ideal = if ideal.is_finite() {
                format!("{ideal:.2} s")
            } else {
                "n/a".to_string()
            };
            // nu36-14: a team that lost a vehicle has the ideal of those still flying too.
            let ideal = match m.revisit_time_ideal_active_s {
                Some(a) if a.is_finite() && a != m.revisit_time_ideal_s => {
                    format!("{ideal}; {a:.2} s for the vehicles still flying")
                }
                _ => ideal,
            };
            out += &format!(
                "  gap_cv {}  time_to_even {}  revisit max {} (ideal {ideal})  min separation {}\n",
                fmt_ratio(m.gap_cv),
                m.time_to_even_s
                    .map_or_else(|| "never".to_string(), |t| format!("{t:.2} s")),
                fmt_opt_unit(m.revisit_time_max_s, "s"),
                fmt_opt_unit(m.min_separation_m, "m"),
            );
        }
        None => out += &format!("  ({})\n", scenario.team_metrics_note()),
    }
    out
}

/// `team.spacing = "arc_reference"` needs the true isoline's arc length (a radial field that
/// does not drift, its circle inside its `domain_m` if it has one, for now): refused before
/// anything is written (exit 65).
pub fn refuse_team_without_isoline(scenario: &Scenario) -> Result<(), Failure> {
    match scenario.team_refusal() {
        Some(why) => Err(Failure {
            code: exit::DATAERR,
            message: why.into(),
        }),
        None => Ok(()),
    }
}

/// Refuses a scenario with `[team]` in a command that runs one vehicle (`compare`, `sitl`,
/// `fly`): exit 65, rather than flying one vehicle as if the section were not there.
pub fn refuse_team(scenario: &Scenario, command: &str) -> Result<(), Failure> {
    if scenario.spec().team.is_some() {
        return Err(Failure {
            code: exit::DATAERR,
            message: format!(
                "[team]: `isotrack {command}` runs one vehicle; a team is run by `isotrack run` only, for now (docs/TEAMS.md)"
            ),
        });
    }
    Ok(())
}

/// `isotrack run`.
pub fn run(args: &RunArgs) -> Result<(), Failure> {
    let scenario = load(&args.scenario)?;
    // The data files as read by the load just made (nu40-4: hashed after the run, a file
    // replaced meanwhile was named by its new digest).
    let read = isotrack_runs::summary::data_file_digests(&scenario);
    refuse_team_without_isoline(&scenario)?;
    let warnings = isotrack_scenario::check::warnings(&scenario);
    for w in &warnings {
        errln!("warning: {w}");
    }
    let threads = team_threads(args, &scenario);
    let name = args.scenario.scenario.as_ref().map_or_else(
        || "<built-in default: paper Fig. 2(b)>".to_string(),
        |p| p.display().to_string(),
    );
    match &args.out {
        Some(dir) => run_into_dir(args, &scenario, &name, dir, read, &warnings, threads),
        None => run_unrecorded(args, &scenario, &name, threads),
    }
}

/// The threads a team steps over: `--threads` (capped as a sweep's; all cores by default), the
/// cap's note on stderr for a team.
fn team_threads(args: &RunArgs, scenario: &Scenario) -> isotrack_sim::TeamThreads {
    let (count, note) = isotrack_runs::sweep::pool::thread_count(args.threads);
    if let (Some(note), Some(_)) = (note, scenario.spec().team.as_ref()) {
        errln!("{note}");
    }
    isotrack_sim::TeamThreads::new(
        count.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())),
    )
}

/// `isotrack run` without `--out`: the run (a team's or one vehicle's), its summary lines on
/// stdout unless `--quiet`, nothing written.
fn run_unrecorded(
    args: &RunArgs,
    scenario: &Scenario,
    name: &str,
    threads: isotrack_sim::TeamThreads,
) -> Result<(), Failure> {
    if let Some(team) = scenario.run_team_threads(&mut [] as &mut [NoTrace], threads) {
        let team = team.map_err(|e| Failure {
            code: exit::DATAERR,
            message: e.to_string(),
        })?;
        warn_unfinished(scenario, Some(&team));
        if !args.quiet {
            out!("{}", human_summary(name, scenario, &team.runs[0]));
            out!("{}", team_summary(scenario, &team));
        }
    } else {
        let result = scenario.run(&mut NoTrace);
        if !args.quiet {
            out!("{}", human_summary(name, scenario, &result));
        }
    }
    Ok(())
}

/// `isotrack run --out DIR`: the run directory opened (refusals before the run), the run
/// recorded into it, its summary lines, then `--plot`'s figures and the note on files from
/// before this run.
fn run_into_dir(
    args: &RunArgs,
    scenario: &Scenario,
    name: &str,
    dir: &std::path::Path,
    read: std::collections::BTreeMap<String, String>,
    warnings: &[String],
    threads: isotrack_sim::TeamThreads,
) -> Result<(), Failure> {
    let out = open_run_dir(args, scenario, dir)?;
    let (result, team) = record_run(args, scenario, &out, read, warnings, threads)?;
    if !args.quiet {
        out!("{}", human_summary(name, scenario, &result));
        if let Some(t) = &team {
            out!("{}", team_summary(scenario, t));
        }
        outln!(
            "wrote       {}, {}, {}",
            isotrack_runs::owned::shell_quoted(&out.path("trace.csv")),
            isotrack_runs::owned::shell_quoted(&out.path("summary.json")),
            isotrack_runs::owned::shell_quoted(&out.path("scenario.toml"))
        );
    }
    plot_and_note_before(args, dir, team.as_ref().is_some_and(|t| t.team.is_some()))
}

/// Opens the run directory `dir` of `isotrack run --out`, refusing before the run what it
/// must not write over.
fn open_run_dir(
    args: &RunArgs,
    scenario: &Scenario,
    dir: &std::path::Path,
) -> Result<RunDir, Failure> {
    // An output that is one of the inputs (the scenario file, the field's data) is refused
    // before anything is written: a run directory never replaces what it was made from.
    // One writer per run directory (as sweeps): a second `run --out D` at once exits 73.
    let inputs = crate::output::input_files(args.scenario.scenario.as_deref(), scenario);
    let out = RunDir::open(dir, &inputs, &[], Some("run"))?;
    // `--plot` into a folder holding the user's own trajectory.png (no isotrack mark) is
    // refused before the run, not after it (att38-9).
    if args.plot {
        crate::figures::refuse_foreign_figures(
            dir,
            &crate::figures::run_figure_names(
                isotrack_plot::Format::Png,
                scenario.spec().team.is_some(),
            ),
        )?;
    }
    Ok(out)
}

/// Runs `scenario` into the run directory `out`: its trace, then its `summary.json` and
/// `scenario.toml`. Returns vehicle 0's result and, for a team, the team's.
fn record_run(
    args: &RunArgs,
    scenario: &Scenario,
    out: &RunDir,
    read: std::collections::BTreeMap<String, String>,
    warnings: &[String],
    threads: isotrack_sim::TeamThreads,
) -> Result<(RunResult, Option<isotrack_sim::TeamResult>), Failure> {
    // A team (`[team]`) writes one trace with a `vehicle` column; its summary's top-level
    // metrics are vehicle 0's, beside the `team` object and the `vehicles` array.
    let mut trace_file = if scenario.spec().team.is_some() {
        out.team_trace(scenario.is_flying())?
    } else {
        out.trace(scenario.is_flying())?
    };
    let team = match isotrack_runs::trace::run_team_into(scenario, trace_file.writer(), threads) {
        Some(Ok(t)) => Some(t),
        Some(Err(e)) => return Err(refused_team(out, trace_file, e)),
        None => None,
    };
    warn_unfinished(scenario, team.as_ref());
    let file = args.scenario.scenario.as_deref();
    let (result, mut summary) = match &team {
        Some(t) => (
            t.runs[0].clone(),
            Summary::of_team(scenario, file, t, warnings),
        ),
        None => {
            let r = scenario.run(trace_file.writer());
            let s = Summary::of_run(scenario, file, &r, warnings);
            (r, s)
        }
    };
    if let Some(w) = summary.data_files_as_read(read) {
        errln!("warning: {w}");
    }
    out.finish(trace_file, &scenario_toml(scenario), &summary)?;
    Ok((result, team))
}

/// After a run into `dir`: `--plot`'s figures drawn, then the note on the figures and logs
/// there from before this run ([`note_outputs_from_before`]; `team_figure`: whether this run
/// draws a team figure).
fn plot_and_note_before(
    args: &RunArgs,
    dir: &std::path::Path,
    team_figure: bool,
) -> Result<(), Failure> {
    // Every file named as a figure or log here now is from before this run (the run wrote
    // none yet), whatever its date (att39-7: by modification time, one dated in the future
    // was missed); --plot's own are struck off below.
    let mut before = outputs_present(dir);
    if args.plot {
        let st = crate::figures::style(&args.look, isotrack_plot::Format::Png)?;
        // att48-2: Ctrl-C while drawing left the new run beside the earlier figures, silently;
        // it now says the same note, naming the files not yet redrawn (each figure is renamed
        // into place, a new file: one still the file it was is from before this run).
        let _said = note_on_interrupt(&before, dir, team_figure);
        let written = crate::figures::plot_dirs(&[dir.to_path_buf()], &st, dir)?;
        before.retain(|n| {
            !written
                .iter()
                .any(|w| std::path::Path::new(w).file_name() == Some(std::ffi::OsStr::new(n)))
        });
        if !args.quiet {
            outln!("plotted     {}", written.join(", "));
        }
    }
    note_outputs_from_before(&before, dir, team_figure);
    Ok(())
}

/// Registers, for an interrupt while `--plot` draws into `dir`, the note on the files there from
/// before this run ([`note_outputs_from_before`]): of `before`, those still the same file
/// (device and inode) as now, i.e. not yet replaced by a figure of this run.
fn note_on_interrupt(
    before: &[&'static str],
    dir: &std::path::Path,
    team_figure: bool,
) -> isotrack_runs::cleanup::OnInterrupt {
    let identity = isotrack_runs::files::identity;
    let was: Vec<(&'static str, Option<(u64, u64)>)> = before
        .iter()
        .map(|&n| (n, identity(&dir.join(n))))
        .collect();
    let dir = dir.to_path_buf();
    isotrack_runs::cleanup::on_interrupt(move || {
        let still: Vec<&str> = was
            .iter()
            .filter(|(n, id)| id.is_some() && identity(&dir.join(n)) == *id)
            .map(|(n, _)| *n)
            .collect();
        note_outputs_from_before(&still, &dir, team_figure);
    })
}

/// An earlier run's figures (or the user's files of those names) in the run directory `dir`,
/// never removed: said, so that they are not read as this run's (nu-21; att38-1). Also
/// `compare`'s per-law directories and `sitl`/`fly --out` (att39-1 addendum), with the files
/// [`isotrack_runs::rundir::RunDir::outputs_from_before`] names; `team_figure`: whether this
/// run draws a team figure (a team run with team metrics).
pub(crate) fn note_outputs_from_before(before: &[&str], dir: &std::path::Path, team_figure: bool) {
    if before.is_empty() {
        return;
    }
    let q = isotrack_runs::owned::shell_quoted(dir);
    // att40-1: only a regular file with isotrack's mark is redrawn by `plot`; it refuses (73)
    // anything else of a figure's name (the user's own file, an older isotrack's unmarked
    // figure, a link or FIFO), so the advice for those is to move them.
    // Looked at once per file (the mark test reads the file).
    let foreign_files: Vec<&str> = before
        .iter()
        .copied()
        .filter(|&n| {
            n != "mavlink.tlog"
                && (std::fs::symlink_metadata(dir.join(n)).map_or(true, |m| !m.is_file())
                    || isotrack_plot::refuse_foreign_figure(&dir.join(n)).is_err())
        })
        .collect();
    let foreign = |n: &str| foreign_files.contains(&n);
    let has =
        |f: &dyn Fn(&str) -> bool| before.iter().copied().filter(|n| f(n)).collect::<Vec<_>>();
    let is_team = |n: &str| n.starts_with("team.");
    // att40-2: a team figure is drawn only for a team run with team metrics.
    let redrawn = |n: &str| !foreign(n) && n != "mavlink.tlog" && (team_figure || !is_team(n));
    let mut advice = Vec::new();
    let png = has(&|n| redrawn(n) && n.ends_with(".png"));
    if !png.is_empty() {
        advice.push(format!("`isotrack plot {q}` redraws {}", png.join(", ")));
    }
    let svg = has(&|n| redrawn(n) && n.ends_with(".svg"));
    if !svg.is_empty() {
        advice.push(format!(
            "`isotrack plot {q} --format svg` redraws {}",
            svg.join(", ")
        ));
    }
    if has(&|n| redrawn(n) && n == "animation.gif").len() == 1 {
        advice.push(format!(
            "`isotrack plot {q} --animate` redraws animation.gif"
        ));
    }
    let them = |v: &[&str]| if v.len() == 1 { "it" } else { "them" };
    let is_are = |v: &[&str]| if v.len() == 1 { "is" } else { "are" };
    let mine = has(&|n| foreign(n));
    if !mine.is_empty() {
        advice.push(format!(
            "{} {} not a figure isotrack wrote (your own file, an older isotrack's or not a regular file), which `plot` will not replace: move {} away",
            mine.join(", "),
            is_are(&mine),
            them(&mine)
        ));
    }
    let team_stale = has(&|n| !foreign(n) && !team_figure && is_team(n));
    if !team_stale.is_empty() {
        advice.push(format!(
            "{} {} a team figure, and this run draws none: move {} away",
            team_stale.join(", "),
            is_are(&team_stale),
            them(&team_stale)
        ));
    }
    if before.contains(&"mavlink.tlog") {
        advice.push("mavlink.tlog is a flight's log, no output of this run: move it away".into());
    }
    errln!(
        "note: {q} also holds {} from before this run, not this run's (isotrack never removes a file it may not have written): {}",
        before.join(", "),
        advice.join("; ")
    );
}

/// The files named as isotrack's figures and logs ([`isotrack_runs::rundir::RUN_OUTPUTS`])
/// in `dir`.
fn outputs_present(dir: &std::path::Path) -> Vec<&'static str> {
    isotrack_runs::rundir::RUN_OUTPUTS
        .into_iter()
        .filter(|n| std::fs::symlink_metadata(dir.join(n)).is_ok_and(|m| !m.is_dir()))
        .collect()
}

/// A team run's warnings ([`isotrack_runs::summary::team_warnings`]: a discovered ring that
/// was not one ring; the vehicles that did not complete, other than vehicle 0, whose outcome
/// the summary prints), each a `warning:` line on stderr (`summary.json` lists them in
/// `warnings`).
fn warn_unfinished(scenario: &Scenario, team: Option<&isotrack_sim::TeamResult>) {
    for w in team
        .map(|t| isotrack_runs::summary::team_warnings(scenario, t))
        .unwrap_or_default()
    {
        errln!("warning: {w}");
    }
}

/// A team the engine refuses (a `TeamError`: a setting resolution let through) with `--out`:
/// invalid data, exit 65 with the engine's message, as without `--out` (it exited 73, "cannot
/// write trace.csv", before: the refusal is no output's fault). The trace begun is removed, so
/// nothing is written.
fn refused_team(out: &RunDir, trace: isotrack_runs::rundir::TraceFile, why: String) -> Failure {
    let _ = out.abandon(trace, &why);
    Failure {
        code: exit::DATAERR,
        message: why,
    }
}

/// `isotrack show`.
pub fn show(args: &ScenarioArgs) -> Result<(), Failure> {
    let scenario = load(args)?;
    out_data!(
        "{}",
        isotrack_scenario::spec::show::with_derived(&scenario, &scenario_toml(&scenario))
    );
    Ok(())
}

/// `isotrack check`.
pub fn check(args: &CheckArgs) -> Result<(), Failure> {
    if let Some(h) = args.tube_halfwidth {
        if !(h.is_finite() && h > 0.0 && h.is_normal()) {
            return Err(Failure {
                code: exit::USAGE,
                message: format!(
                    "--tube-halfwidth must be > 0 (not subnormal), got {}",
                    Echo(h)
                ),
            });
        }
    }
    let parsed = crate::checkmap::precheck(args)?;
    let scenario = load(&args.scenario)?;
    let r = isotrack_scenario::check::check(&scenario, args.tube_halfwidth);
    let map = if args.map {
        Some(crate::checkmap::write_map(args, &scenario, parsed)?)
    } else {
        None
    };
    if args.json {
        out_data!("{}\n", check_json(&r, map.as_ref()));
    } else {
        for line in crate::check_text::render(&r) {
            outln!("{line}");
        }
        if let Some(m) = &map {
            crate::checkmap::print_report(m);
        }
    }
    // Ctrl-C during --verify: the report above covers the runs that finished (marked
    // partial); the command still says it was interrupted and exits 128 + the signal (130
    // for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP).
    if let Some(runs) = map.as_ref().and_then(|m| m.verify_runs.as_ref()) {
        if runs.partial {
            return Err(Failure {
                code: isotrack_runs::signals::interrupted_exit_code(),
                message: format!(
                    "interrupted during --verify: {} of {} runs finished; the chart and verify.csv hold what was done (the report above is partial)",
                    runs.finished, runs.requested
                ),
            });
        }
    }
    Ok(())
}

/// `check --json`: the report alone (unchanged) without `--map`; with it, a `map` key naming
/// the files written and the chart's counts.
fn check_json(
    r: &isotrack_scenario::check::CheckReport,
    map: Option<&crate::checkmap::MapReport>,
) -> String {
    match map {
        Some(m) => {
            #[derive(serde::Serialize)]
            struct WithMap<'a> {
                #[serde(flatten)]
                report: &'a isotrack_scenario::check::CheckReport,
                map: &'a crate::checkmap::MapReport,
            }
            serde_json::to_string_pretty(&WithMap { report: r, map: m }).unwrap_or_default()
        }
        None => serde_json::to_string_pretty(r).unwrap_or_default(),
    }
}

#[cfg(test)]
mod tests {

    use super::*;

    /// A team refused by the engine with `--out` exits 65 (invalid data, as without `--out`),
    /// never 73 (an output that cannot be written), with the engine's message, and leaves no
    /// `trace.csv` nor its temporary file.
    #[test]
    fn a_team_the_engine_refuses_is_invalid_data_with_out_too() {
        let dir =
            std::env::temp_dir().join(format!("isotrack-refused-team-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let out = RunDir::open(&dir, &[], &[], Some("run")).unwrap();
        let trace = out.team_trace(false).unwrap();
        let why = isotrack_sim::TeamError::NoIsoline.to_string();
        let f = refused_team(&out, trace, why.clone());
        assert_eq!(f.code, 65);
        assert_eq!(f.code, exit::DATAERR);
        assert_eq!(f.message, why);
        drop(out);
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("trace"))
            .collect();
        assert!(left.is_empty(), "trace files left: {left:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// att32f-4: an open isoline's ideal revisit time with no steady-window sample of two
    /// vehicles is NaN (`null` in summary.json): the console prints `n/a` as for its
    /// neighbours (it printed `ideal NaN s`); a finite one prints as before, to 0.01 s.
    #[test]
    fn a_team_line_prints_no_nan() {
        let summary = |ideal: f64| isotrack_sim::team::metrics::TeamSummary {
            count: 4,
            isoline_length_m: 41.33,
            gap_cv: None,
            gap_cv_final: None,
            time_to_even_s: None,
            revisit_time_max_s: None,
            revisit_time_mean_s: None,
            revisit_time_ideal_s: ideal,
            revisit_time_ideal_active_s: None,
            min_separation_m: Some(9.8026),
            closest_approach: None,
            order_preserved: true,
            speed_range_mps: None,
            moving_isoline: None,
            open_isoline: None,
        };
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let line = |ideal: f64| {
            team_summary(
                &scenario,
                &isotrack_sim::TeamResult {
                    runs: Vec::new(),
                    team: Some(summary(ideal)),
                    ring: Vec::new(),
                    warnings: Vec::new(),
                },
            )
        };
        let nan = line(f64::NAN);
        assert_eq!(
            nan,
            "team        0 vehicles  gap_cv n/a  time_to_even never  revisit max n/a (ideal n/a)  min separation 9.80 m\n"
        );
        assert!(line(21.7656).contains("(ideal 21.77 s)"));
    }

    /// nu36-3: the team line prints its times and distances in one format, to 0.01 (as
    /// `time_to_even` and the ideal revisit time print): team-circular-4's revisit max 21.78 s
    /// beside its ideal 21.78 s and min separation 2.0717 m as 2.07 m (they printed
    /// `2.1780e1 s` and `2.0717e0 m`); a separation under 0.01 m keeps its digits.
    #[test]
    fn a_team_line_prints_one_number_format() {
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let line = |revisit: f64, separation: f64| {
            team_summary(
                &scenario,
                &isotrack_sim::TeamResult {
                    runs: Vec::new(),
                    team: Some(isotrack_sim::team::metrics::TeamSummary {
                        count: 4,
                        isoline_length_m: 43.55,
                        gap_cv: Some(2.9e-11),
                        gap_cv_final: None,
                        time_to_even_s: Some(55.07),
                        revisit_time_max_s: Some(revisit),
                        revisit_time_mean_s: None,
                        revisit_time_ideal_s: 21.7759,
                        revisit_time_ideal_active_s: None,
                        min_separation_m: Some(separation),
                        closest_approach: None,
                        order_preserved: true,
                        speed_range_mps: None,
                        moving_isoline: None,
                        open_isoline: None,
                    }),
                    ring: Vec::new(),
                    warnings: Vec::new(),
                },
            )
        };
        assert_eq!(
            line(21.78, 2.0717),
            "team        0 vehicles  gap_cv 2.900e-11  time_to_even 55.07 s  revisit max 21.78 s (ideal 21.78 s)  min separation 2.07 m\n"
        );
        assert!(line(15166.2, 29404.0)
            .contains("revisit max 15166.20 s (ideal 21.78 s)  min separation 29404.00 m"));
        // att38-4: under 0.01 m in decimals (three significant digits), not `1.2000e-3 m`.
        assert!(line(21.78, 0.0012).contains("min separation 0.00120 m"));
        assert!(line(21.78, 6.9315e-4).contains("min separation 0.000693 m"));
    }

    /// att38-4: gap_cv in decimals to four significant digits between 1e-3 and 1e4
    /// (`sqrt(3) = 1.7321` prints `1.732`, not `1.7321e0`; 0.183 prints `0.1830`), in exponent
    /// form outside; nu36-14: a team that lost a vehicle names the ideal of the vehicles
    /// still flying beside the deployed one (`L/(3 v0)` = 43.56/1.5 = 29.04 s beside
    /// `L/(4 v0)` = 21.78 s).
    #[test]
    fn a_team_line_prints_gap_cv_in_decimals_and_the_live_ideal() {
        assert_eq!(fmt_ratio(Some(3f64.sqrt())), "1.732");
        assert_eq!(fmt_ratio(Some(0.183)), "0.1830");
        assert_eq!(fmt_ratio(Some(2.9e-11)), "2.900e-11");
        assert_eq!(fmt_ratio(Some(0.0)), "0");
        assert_eq!(fmt_ratio(None), "n/a");
        let scenario = isotrack_scenario::load_scenario(None, &[]).unwrap();
        let line = team_summary(
            &scenario,
            &isotrack_sim::TeamResult {
                runs: Vec::new(),
                team: Some(isotrack_sim::team::metrics::TeamSummary {
                    count: 4,
                    isoline_length_m: 43.55,
                    gap_cv: Some(3f64.sqrt()),
                    gap_cv_final: None,
                    time_to_even_s: None,
                    revisit_time_max_s: Some(29.04),
                    revisit_time_mean_s: None,
                    revisit_time_ideal_s: 21.78,
                    revisit_time_ideal_active_s: Some(29.04),
                    min_separation_m: Some(2.0717),
                    closest_approach: None,
                    order_preserved: true,
                    speed_range_mps: None,
                    moving_isoline: None,
                    open_isoline: None,
                }),
                ring: Vec::new(),
                warnings: Vec::new(),
            },
        );
        assert!(line.contains("gap_cv 1.732  "), "{line}");
        assert!(
            line.contains("(ideal 21.78 s; 29.04 s for the vehicles still flying)"),
            "{line}"
        );
    }
}
