//! `isotrack compare`: the paper's law against the baselines on one scenario.

use crate::cli::CompareArgs;
use crate::exit;
use crate::output::{scenario_toml, RunDir, Summary};
use crate::run::invalid;
use crate::run::Failure;
use isotrack_runs::results::{result_cells, Column, RunRecord};
use isotrack_scenario::schema::ControllerKind;
use isotrack_scenario::{apply_assignments, load_scenario, Assignment, Scenario};
use isotrack_sim::{NoTrace, RunResult};
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

/// The result columns of `comparison.csv`, after `controller` ([`COMPARISON_COLUMNS`]).
pub const COMPARISON_RESULT_COLUMNS: [Column; 9] = [
    Column::Outcome,
    Column::ConvergenceTimeS,
    Column::SteadyStateMaxAbsError,
    Column::SteadyStateRmsError,
    Column::ChatteringRadps2,
    Column::SignChangesPerS,
    Column::ControlEffort,
    Column::SteadyStateMaxIsolineDistanceM,
    Column::SteadyStateRmsIsolineDistanceM,
];

/// The scenario with `kind` as its controller: the scenario's own section when it already uses
/// that kind; otherwise the kind's defaults with the shared keys (level, turning side, turn-rate
/// limit, derivative estimator) carried over; then the `--gain` overrides for that kind. The
/// variant flies `base`'s field itself, as read once ([`Scenario::variant_of_file`]): every
/// law of a comparison flies the same field (att41-8: each law read the data files again, so
/// a file replaced during a compare gave its laws different fields).
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
    base.variant_of_file(
        file,
        &format!("{origin} [{}]", kind.name()),
        &sets,
        Path::new("."),
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

/// Whether run `r` never reached the level (at no step within the convergence tolerance nor
/// across the isoline: [`isotrack_sim::RunMetrics::reached_level`], every step counted, not
/// only the recorded rows), with how far it went from its start, m.
fn never_reached(r: &RunResult) -> Option<f64> {
    (!r.metrics.reached_level).then_some(r.metrics.farthest_from_start_m)
}

fn md(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.3e}"))
}

/// Runs the command.
pub fn compare(a: &CompareArgs) -> Result<(), Failure> {
    let base = load_scenario(Some(&a.scenario), &a.set).map_err(invalid)?;
    crate::run::refuse_team(&base, "compare")?;
    let kinds = chosen_kinds(&a.controllers)?;
    check_gains(&a.gain)?;
    let origin = a.scenario.display().to_string();
    // Every law's scenario is built before any directory is opened or any law runs: a
    // `--gain` a later law refuses fails the command with nothing written (own42: the laws
    // before it had run and their directories stayed behind).
    let variants = kinds
        .iter()
        .map(|&kind| variant(&base, kind, &a.gain, &origin).map(|s| (kind, s)))
        .collect::<Result<Vec<_>, _>>()?;
    // Held while the runs write into `--out` (released when dropped), with each law's run
    // directory, opened (checked and locked) before any law runs.
    let (_lock, law_dirs) = match &a.out {
        Some(dir) => {
            let (lock, dirs) = open_out(a, dir, &base, &kinds)?;
            (Some(lock), dirs)
        }
        None => (None, vec![]),
    };
    let table = a.out.as_ref().map(|dir| dir.join("comparison.csv"));
    let progress = std::sync::Arc::new(std::sync::Mutex::new(Progress::default()));
    let _said = table
        .as_ref()
        .map(|t| say_progress_on_interrupt(&progress, t));
    let mut law_dirs = law_dirs.into_iter();
    let mut results: Vec<(ControllerKind, RunResult)> = Vec::new();
    // The laws whose true error never reached the level (at any step, whatever the trace
    // records), with how far each went from its start, m.
    let mut never: Vec<(ControllerKind, f64)> = Vec::new();
    for (kind, s) in variants {
        // A baseline outside its own stated gain condition is said, not only run.
        let warnings = isotrack_scenario::check::baselines::baseline_warnings(&s);
        for w in &warnings {
            errln!("warning: {w}");
        }
        let r = match law_dirs.next() {
            Some(out) => match run_into(a, &base, &s, &out, table.as_deref(), &progress) {
                Ok(r) => r,
                Err(e) => {
                    // The laws' directories not yet written: removed again where this
                    // call created them (an earlier run's files there are left as they were).
                    law_dirs.for_each(RunDir::release_unused);
                    out.release_unused();
                    return Err(e);
                }
            },
            None => s.run(&mut NoTrace),
        };
        if let Some(far) = never_reached(&r) {
            never.push((kind, far));
        }
        results.push((kind, r));
    }
    print_table(&results, &never);
    if !never.is_empty() {
        outln!("\n{}", never_reached_note(&base, &never));
    }
    if let Some(p) = &table {
        write_comparison(p, &results)?;
        outln!(
            "\nwrote {} and one run directory per controller",
            p.display()
        );
    }
    Ok(())
}

/// Runs law scenario `s` into its run directory `out` (compare's lock and `out`'s held): its
/// trace, summary and scenario written, the notes `run` gives said. The earlier
/// `comparison.csv` at `table` (README, "Ctrl-C") is removed, with its record, in the same step
/// an interrupt never cuts as the law's run replaces the directory's
/// ([`isotrack_runs::cleanup::whole`]; att46-11: an interrupted compare left the earlier table,
/// still recorded as isotrack's, beside law directories holding the new runs): until a law is
/// replaced the earlier comparison stands whole, and from then on no table claims to describe
/// the laws until the new one is written after the last law.
fn run_into(
    a: &CompareArgs,
    base: &Scenario,
    s: &Scenario,
    out: &RunDir,
    table: Option<&Path>,
    progress: &std::sync::Mutex<Progress>,
) -> Result<RunResult, Failure> {
    // The directory's lock is held for all of them, and each law's directory is locked too:
    // a `run --out CMP/LAW` meanwhile never saw the parent's lock, both wrote the directory
    // and the run's result vanished (att36-9).
    let mut trace = out.trace(s.is_flying())?;
    let r = s.run(trace.writer());
    let warnings = isotrack_scenario::check::warnings(s);
    let mut summary = Summary::of_run(s, Some(&a.scenario), &r, &warnings);
    // Every law flew the field as read when the scenario loaded; a data file changed since is
    // said (as `run` says it), and data_files names the one flown.
    if let Some(w) = summary.data_files_as_read(base.data_file_digests().clone()) {
        errln!("warning: {w}");
    }
    isotrack_runs::cleanup::whole(|| {
        let removed = match table {
            Some(t) => isotrack_runs::owned::remove_table(t).map_err(|e| cant(t, e))?,
            None => false,
        };
        out.finish(trace, &scenario_toml(s), &summary)?;
        // In the same step: an interrupt says what the directory holds (att48-6).
        let mut p = progress.lock().unwrap_or_else(|e| e.into_inner());
        p.replaced.push(out.dir().to_path_buf());
        p.table_removed |= removed;
        Ok::<(), Failure>(())
    })?;
    // An earlier run's figures there are not this run's: said, as `run` says it.
    crate::run::note_outputs_from_before(&out.outputs_from_before(), out.dir(), false);
    Ok(r)
}

/// What a `compare --out` has replaced so far, said if it is interrupted
/// ([`say_progress_on_interrupt`]).
#[derive(Debug, Default)]
struct Progress {
    /// The laws' directories that hold this compare's run.
    replaced: Vec<std::path::PathBuf>,
    /// Whether an earlier `comparison.csv` was removed.
    table_removed: bool,
}

/// Registers the line an interrupted `compare --out` says on exit (att48-6: it removed the
/// earlier `comparison.csv` and left laws of two comparisons without a word): which laws hold
/// this compare's run, and that the table (`table`) is removed until a re-run writes it.
/// Nothing is said before the first law is replaced: the directory is then as it was.
fn say_progress_on_interrupt(
    progress: &std::sync::Arc<std::sync::Mutex<Progress>>,
    table: &Path,
) -> isotrack_runs::cleanup::OnInterrupt {
    let (progress, table) = (progress.clone(), table.to_path_buf());
    isotrack_runs::cleanup::on_interrupt(move || {
        let p = progress.lock().unwrap_or_else(|e| e.into_inner());
        if p.replaced.is_empty() {
            return;
        }
        let laws: Vec<String> = p
            .replaced
            .iter()
            .map(|d| isotrack_runs::owned::shell_quoted(d))
            .collect();
        let removed = if p.table_removed {
            "the earlier one was removed (it described other runs)"
        } else {
            "none is written"
        };
        errln!(
            "interrupted: {} now {} this compare's run (any other law's directory its earlier run); {} holds no comparison ({removed}): run the same compare again to write it",
            laws.join(", "),
            if laws.len() == 1 { "holds" } else { "hold" },
            isotrack_runs::owned::shell_quoted(&table)
        );
    })
}

/// The laws `--controller` names (every built-in law when none is named); an unknown name is a
/// usage error listing the known ones.
fn chosen_kinds(names: &[String]) -> Result<Vec<ControllerKind>, Failure> {
    if names.is_empty() {
        return Ok(ControllerKind::ALL.to_vec());
    }
    names
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
        .collect()
}

/// The failure for output `what` that cannot be written.
fn cant(what: &Path, e: std::io::Error) -> Failure {
    Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", what.display()),
    }
}

/// `--out DIR` opened for the runs of `kinds`: nothing written over an input (the scenario
/// file, its field's data: exit 64), and one writer per directory (the lock, as sweeps: a
/// second at once exits 73); every output that exists must be a regular file. Returns the
/// lock and each law's run directory, in `kinds`' order, every one opened
/// ([`RunDir::open`]: checked and locked) before any law runs (att42-11: a user's
/// `.isotrack.lock` or a file that is no directory at `DIR/LAW` was found only when that law's
/// turn came, after the laws before it had run and been written); on a refusal, the law
/// directories this created are removed again.
fn open_out(
    a: &CompareArgs,
    dir: &Path,
    base: &Scenario,
    kinds: &[ControllerKind],
) -> Result<(OutLock, Vec<RunDir>), Failure> {
    let inputs = crate::output::input_files(Some(&a.scenario), base);
    let mut outputs = vec![dir.join("comparison.csv")];
    for kind in kinds {
        for f in ["trace.csv", "summary.json", "scenario.toml"] {
            outputs.push(dir.join(kind.name()).join(f));
        }
    }
    for o in &outputs {
        if let Some(message) = crate::output::input_clash(&inputs, o) {
            return Err(Failure {
                code: exit::USAGE,
                message,
            });
        }
    }
    // Each directory this created (parents included, att48-5) is removed again (when empty)
    // if the compare is interrupted, after its laws' (att46-10 addendum); held with the lock.
    let created = isotrack_runs::cleanup::create_dir_all(dir).map_err(|e| cant(dir, e))?;
    let lock = (crate::sweep::lock_output_dir(dir, "compare")?, created);
    // att44-12: `CMP/LAW` is a name compare picks: a link there (to another run elsewhere) was
    // followed and that run replaced; a link or anything but a directory is refused, named.
    for kind in kinds {
        isotrack_runs::rundir::refuse_not_own_directory(&dir.join(kind.name()))?;
    }
    for o in &outputs {
        isotrack_runs::files::refuse_non_regular(o).map_err(|e| cant(o, e))?;
    }
    // Whose files are there (att39-1), before any law runs: a comparison.csv that is not
    // isotrack's, or a law's directory holding run files that are not an earlier isotrack
    // run's, is refused (73) naming it; the lock is removed again as it drops.
    refuse_foreign_comparison(&dir.join("comparison.csv"))?;
    let mut laws: Vec<RunDir> = Vec::with_capacity(kinds.len());
    for kind in kinds {
        match RunDir::open(&dir.join(kind.name()), &[], &[], Some("compare")) {
            Ok(law) => laws.push(law),
            Err(e) => {
                laws.into_iter().for_each(RunDir::release_unused);
                return Err(e);
            }
        }
    }
    Ok((lock, laws))
}

/// `--out DIR`'s lock, with DIR's registration for removal on an interrupt when this compare
/// created it and each parent it created ([`isotrack_runs::cleanup::create_dir_all`]); both
/// held to the end.
type OutLock = (crate::sweep::DirLock, Vec<isotrack_runs::cleanup::Pending>);

/// Refuses (73) an existing `comparison.csv` that an isotrack did not write, or that was edited
/// since ([`isotrack_runs::owned::refuse_foreign_csv`], att39-1, att42-8, att44-4): its size and
/// SHA-256 are not those `compare` recorded in the directory when it wrote it, or no record
/// there holds it. Never read through a link nor from a FIFO (refused before this).
fn refuse_foreign_comparison(p: &Path) -> Result<(), Failure> {
    isotrack_runs::owned::refuse_foreign_csv(p, "an isotrack comparison")
}

/// The comparison table on stdout (Markdown): one row per law, a law in `never` marked as
/// never having reached the level.
fn print_table(results: &[(ControllerKind, RunResult)], never: &[(ControllerKind, f64)]) {
    outln!(
        "| controller | outcome | convergence (s) | steady max\\|eps\\| | steady rms | chattering (rad/s^2) | sign changes/s | effort (rad^2/s) | max isoline dist (m) |"
    );
    outln!("|---|---|---|---|---|---|---|---|---|");
    for (k, r) in results {
        let m = &r.metrics;
        outln!(
            "| {}{} | {} | {} | {} | {} | {} | {} | {:.3} | {} |",
            k.name(),
            if *k == ControllerKind::GradientReference {
                " (not coordinate-free)"
            } else {
                ""
            },
            if never.iter().any(|(n, _)| n == k) {
                format!("{}, never reached s_d", r.outcome.as_str())
            } else {
                r.outcome.as_str().to_string()
            },
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
}

/// `comparison.csv` at `p`: [`COMPARISON_COLUMNS`], one row per law; written as every table is
/// ([`isotrack_runs::owned::write_table`]: a new file renamed over the old one, att46-2: it was
/// rewritten in place, so a hard-linked copy of the earlier table changed; then recorded).
fn write_comparison(p: &Path, results: &[(ControllerKind, RunResult)]) -> Result<(), Failure> {
    let mut text = COMPARISON_COLUMNS.join(",") + "\n";
    for (k, r) in results {
        // The one row builder (isotrack-runs): the law's name, then its result's cells.
        let mut row = vec![k.name().to_string()];
        row.extend(result_cells(
            &COMPARISON_RESULT_COLUMNS,
            Ok(&RunRecord::of(r)),
        ));
        text += &row.join(",");
        text += "\n";
    }
    // Recorded as written (att42-8): a later `compare` tells it from the user's edit.
    isotrack_runs::owned::write_table(p, text.as_bytes()).map_err(|e| cant(p, e))
}

/// The note under the table for the laws that never reached the isoline: what their rows
/// measure, how far each went from its start, and what gives every law a fair start;
/// `pid_crossing` adds its turn only at a crossing of the level, so without one it flies
/// exactly as `pid`.
fn never_reached_note(base: &Scenario, never: &[(ControllerKind, f64)]) -> String {
    use isotrack_core::numtext::Num;
    let tol = base.spec().metrics.convergence_tolerance;
    let mut note = format!(
        "never reached s_d: at every step the true error kept its sign and stayed outside the convergence tolerance ({}), so these laws never found the isoline and their rows (effort, chattering, steady errors) measure circling or wandering, not tracking:\n",
        Num(tol)
    );
    let pid_too = never.iter().any(|(k, _)| *k == ControllerKind::Pid);
    for (k, far) in never {
        note += &format!("- {}: at most {} m from its start", k.name(), Num(*far));
        if *k == ControllerKind::PidCrossing && pid_too {
            note += " (the same run as pid: pid_crossing adds its turn only at a crossing of the level, and there was none)";
        }
        note += "\n";
    }
    note += if base.search().is_none() {
        "A law circles where it starts when its command sits at the turn-rate limit (a linear law far from the level asks for kp*|eps|) or when the field there has too little slope for it to act on (v|grad F| small next to what its gains ask; the baselines' own conditions are in docs/BASELINES.md, and broken ones are warned about above). A start nearer the isoline, or a search phase (controller.search = \"spiral\" or \"lawnmower\", flown by every law here), gives every law the same chance."
    } else {
        "Every law flew the scenario's search (controller.search) before its own law; these still never reached the isoline within the run."
    };
    note
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `comparison.csv`'s header is `controller` then the names of the columns its rows are
    /// built from (the one row builder, isotrack-runs).
    #[test]
    fn the_header_names_the_built_columns() {
        let names: Vec<&str> = COMPARISON_RESULT_COLUMNS.iter().map(|c| c.name()).collect();
        assert_eq!(COMPARISON_COLUMNS[0], "controller");
        assert_eq!(COMPARISON_COLUMNS[1..], names[..]);
    }

    /// att41-8: every law of a comparison flies the base scenario's field itself, as read once
    /// (the same built field, the same data-file digests), a law with `--gain`s too; its
    /// controller is the law's. Before the fix each law's variant read the data files again
    /// (`build_derived`), so a file replaced during a compare gave the laws different fields
    /// and a law's summary the new file's digest.
    #[test]
    fn every_law_flies_the_field_read_once() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/volcano.toml");
        let base = load_scenario(Some(&path), &["sim.duration_s=5".to_string()]).unwrap();
        assert_eq!(base.data_file_digests().len(), 1);
        let gains = ["sliding_mode.gamma=0.3".to_string()];
        for kind in ControllerKind::ALL {
            let v = variant(&base, kind, &gains, "volcano")
                .unwrap_or_else(|e| panic!("{}: {}", kind.name(), e.message));
            assert_eq!(v.file().controller.kind, Some(kind));
            assert!(
                base.shares_field_with(&v),
                "{} read the field again",
                kind.name()
            );
            assert_eq!(v.data_file_digests(), base.data_file_digests());
        }
        let smc = variant(&base, ControllerKind::SlidingMode, &gains, "volcano").unwrap();
        assert_eq!(
            serde_json::to_value(&smc.file().controller).unwrap()["gamma"],
            serde_json::json!(0.3)
        );
    }
}
