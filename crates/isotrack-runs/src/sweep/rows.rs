//! The rows of `results.csv`: its columns, the row of one run, and runs run together.

use crate::results::{real_cell, result_cells, Column, RunRecord};
use crate::summary::TeamRecord;
use isotrack_core::numtext::Num;
use isotrack_scenario::sweep::SweepPlan;
use isotrack_scenario::Scenario;
use isotrack_sim::team::metrics::TeamSummary;
use isotrack_sim::{NoTrace, RunResult, TeamError, TeamResult};

/// The metric columns of `results.csv`, after `run_id` and the varied keys: the outcome, the
/// metrics, `outcome_detail`, then `warnings` (what [`run_warnings`] says about the run's
/// scenario; empty for most runs).
pub const METRIC_COLUMNS: [&str; 15] = [
    "outcome",
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "steady_state_mean_error",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
    "path_length_m",
    "control_effort",
    "chattering_radps2",
    "sign_changes_per_s",
    "t_end_s",
    "samples",
    "outcome_detail",
    "warnings",
];

/// The result columns of a sweep's row, [`METRIC_COLUMNS`] but `warnings` (built by
/// [`result_cells`]).
pub const SWEEP_COLUMNS: [Column; 14] = [
    Column::Outcome,
    Column::ConvergenceTimeS,
    Column::SteadyStateMaxAbsError,
    Column::SteadyStateRmsError,
    Column::SteadyStateMeanError,
    Column::SteadyStateMaxIsolineDistanceM,
    Column::SteadyStateRmsIsolineDistanceM,
    Column::PathLengthM,
    Column::ControlEffort,
    Column::ChatteringRadps2,
    Column::SignChangesPerS,
    Column::TEndS,
    Column::Samples,
    Column::OutcomeDetail,
];

/// The team columns of `results.csv`, after [`METRIC_COLUMNS`], in a sweep whose base scenario
/// has `[team]` (and only there: a single-vehicle sweep's file is unchanged): the `team` object
/// of `summary.json` (docs/TEAMS.md, "Team metrics"). Empty when the run has no team metrics (an
/// isoline without an arc-length projection, an invalid run); `order_preserved` is `true` or
/// `false`. The [`METRIC_COLUMNS`] of a team run are vehicle 0's, as `summary.json`'s top level.
pub const TEAM_COLUMNS: [&str; 7] = [
    "gap_cv",
    "time_to_even_s",
    "revisit_time_max_s",
    "revisit_time_mean_s",
    "revisit_time_ideal_s",
    "min_separation_m",
    "order_preserved",
];

/// The numeric columns of [`METRIC_COLUMNS`] (all but `outcome`, `outcome_detail` and
/// `warnings`).
pub fn numeric_columns() -> &'static [&'static str] {
    &METRIC_COLUMNS[1..METRIC_COLUMNS.len() - 2]
}

/// The warnings a sweep records for a run's scenario (its `warnings` cell; empty when none):
/// the checks cheap enough to make for every run, today a start on a flat background where the
/// PI-like law circles for the whole run ([`isotrack_scenario::check::flat_start`], the warning
/// `isotrack run` prints, its numbers rounded as the console's: [`Num`], 6 significant digits). `isotrack check`'s sampled-loop warning needs a lattice scan of the
/// field per run and is left to `isotrack run`/`check` on the run's scenario. A team's row
/// (whose run costs far more than the scan) adds `check`'s team failure
/// ([`isotrack_scenario::check::team_warning`], as `isotrack run` warns it; att32d-6).
pub fn run_warnings(scenario: &Scenario) -> String {
    let flat = flat_start_warning(scenario);
    match isotrack_scenario::check::team_warning(scenario) {
        None => flat,
        Some(t) if flat.is_empty() => t,
        Some(t) => format!("{flat}; {t}"),
    }
}

/// The flat-start warning of [`run_warnings`] (empty when none).
fn flat_start_warning(scenario: &Scenario) -> String {
    isotrack_scenario::check::flat_start(scenario).map_or_else(String::new, |f| {
        format!(
            "flat start: within {} m of it v*|grad F| is at most {} field units/s (under {} % of c1*tanh(|eps|/c2) = {}) so the vehicle circles where it starts; set controller.search",
            Num(f.radius_m),
            Num(f.slope_term),
            isotrack_scenario::check::FLAT_START_FRACTION * 100.0,
            Num(f.level_term)
        )
    })
}

/// One CSV line of `fields`, with its newline.
pub fn csv_line(fields: &[String]) -> String {
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    let _ = w.write_record(fields);
    String::from_utf8(w.into_inner().unwrap_or_default()).unwrap_or_default()
}

/// Fields of one CSV line (`None` if it does not parse).
pub fn csv_fields(line: &str) -> Option<Vec<String>> {
    let rec = csv_record(line)?;
    Some(rec.iter().map(str::to_string).collect())
}

/// The first record of `line` as a fresh `csv` reader (default settings, no header row)
/// reads it; `None` if it does not parse.
///
/// Building a reader builds its parser's automaton, about 270 k instructions, twice as many as
/// a sweep's row takes to check (issue 34: every row of a sweep is read twice when it ends).
/// So each thread keeps one reader over a line it swaps, and starts it afresh for each line
/// with `seek_raw` to the start: the parser reset, its line count 1, the end of input
/// forgotten, and no header handling (a seeked reader has done with its header: this one
/// read an empty one when it was made). It is flexible: a fresh reader compares no first
/// record's field count with anything, and neither may this one, which has read other lines
/// before. Test: `csv_record_reads_as_a_fresh_reader`.
pub(crate) fn csv_record(line: &str) -> Option<csv::StringRecord> {
    thread_local! {
        static READER: std::cell::RefCell<csv::Reader<OneLine>> = std::cell::RefCell::new({
            let mut r = csv::ReaderBuilder::new()
                .has_headers(false)
                .flexible(true)
                .from_reader(OneLine::default());
            // The header read now, from nothing, so that no later seek reads one.
            let _ = r.byte_headers();
            r
        });
    }
    READER.with_borrow_mut(|r| {
        let source = r.get_mut();
        source.bytes.clear();
        source.bytes.extend_from_slice(line.as_bytes());
        r.seek_raw(std::io::SeekFrom::Start(0), csv::Position::new())
            .ok()?;
        let rec = r.records().next()?.ok();
        // Not kept: a long line's bytes are not held past the call.
        r.get_mut().bytes = Vec::new();
        rec
    })
}

/// The line [`csv_record`]'s reader reads: its bytes, and where the reader is in them.
#[derive(Default)]
struct OneLine {
    bytes: Vec<u8>,
    at: usize,
}

impl std::io::Read for OneLine {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let rest = self.bytes.get(self.at..).unwrap_or_default();
        let n = rest.len().min(buf.len());
        buf[..n].copy_from_slice(&rest[..n]);
        self.at += n;
        Ok(n)
    }
}

impl std::io::Seek for OneLine {
    fn seek(&mut self, to: std::io::SeekFrom) -> std::io::Result<u64> {
        // Only the start is ever asked for (`csv::Position::new()`).
        self.at = match to {
            std::io::SeekFrom::Start(n) => usize::try_from(n).unwrap_or(usize::MAX),
            _ => {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::Unsupported,
                    "a line is read from its start",
                ))
            }
        };
        Ok(self.at as u64)
    }
}

/// The rows of runs `ids` (CSV lines with their newlines, in `ids` order). A run whose values
/// make an invalid scenario is recorded (`invalid_scenario`, the reason in `outcome_detail`),
/// never fatal to the sweep. The valid runs are run together ([`Scenario::run_batch`]: runs
/// sharing the field, vehicle and plan step in SIMD lanes, each with the result it has alone).
pub fn run_rows(plan: &SweepPlan, base: &Scenario, ids: &[u64], sweep_name: &str) -> Vec<String> {
    let derived: Vec<Result<Scenario, String>> = ids
        .iter()
        .map(|&id| run_scenario(plan, base, id, sweep_name))
        .collect();
    if base.spec().team.is_some() {
        return ids
            .iter()
            .zip(derived)
            .map(|(&id, d)| {
                let (result, team, warnings) = match d {
                    Ok(s) => {
                        let mut warnings = run_warnings(&s);
                        let (result, team) = run_team_row(&s, &mut warnings);
                        (result, team, warnings)
                    }
                    Err(e) => (Err(e), None, String::new()),
                };
                let mut fields = row_fields_warned(plan, id, result, warnings);
                fields.extend(team_cells(team.as_ref()));
                csv_line(&fields)
            })
            .collect();
    }
    let valid: Vec<Scenario> = derived
        .iter()
        .filter_map(|d| d.as_ref().ok())
        .cloned()
        .collect();
    let mut results = Scenario::run_batch(&valid).into_iter();
    ids.iter()
        .zip(derived)
        .map(|(&id, d)| {
            let warnings = d.as_ref().map(run_warnings).unwrap_or_default();
            // run_batch answers every valid scenario, in order.
            let result = d.and_then(|_| {
                results
                    .next()
                    .ok_or_else(|| "the batch returned no result for this run".to_string())
            });
            csv_line(&row_fields_warned(plan, id, result, warnings))
        })
        .collect()
}

/// A team run for a row: vehicle 0's result (as `summary.json`'s top level) and the team
/// metrics; every other vehicle that did not complete is named in `warnings`.
fn run_team_row(
    s: &Scenario,
    warnings: &mut String,
) -> (Result<RunResult, String>, Option<TeamSummary>) {
    team_row_parts(
        s.run_team(&mut [] as &mut [NoTrace]),
        s.spec().team.as_ref(),
        warnings,
    )
}

/// Why the team engine refuses team scenario `s`, as a team sweep records it in
/// `outcome_detail` (`[team]: ...`), or `None` when it flies the team (or `s` has none): found
/// as the sweep finds it, by running the team ([`run_team_row`]; the engine's refusals come
/// before its first step, so only a team it flies costs a run). `--resume` and `merge` check a
/// kept `[team]:` row with it.
pub fn team_refusal(s: &Scenario) -> Option<String> {
    s.spec().team.as_ref()?;
    run_team_row(s, &mut String::new()).0.err()
}

/// The `results.csv` fields of run `id` of a team sweep from its team run `team` (run by the
/// caller: with Python controllers, say; `Err` an invalid scenario's reason): the row
/// [`run_rows`] writes for it, [`METRIC_COLUMNS`] vehicle 0's then [`TEAM_COLUMNS`].
pub fn team_row_fields(
    plan: &SweepPlan,
    id: u64,
    team: Result<Option<Result<TeamResult, TeamError>>, String>,
    mut warnings: String,
) -> Vec<String> {
    let (result, summary) = match team {
        Ok(t) => team_row_parts(t, None, &mut warnings),
        Err(e) => (Err(e), None),
    };
    let mut fields = row_fields_warned(plan, id, result, warnings);
    fields.extend(team_cells(summary.as_ref()));
    fields
}

/// Vehicle 0's result and the team metrics of a team run; every other vehicle that did not
/// complete is named in `warnings`, as is a close approach (its reason from the team's settings
/// `spec` when known).
fn team_row_parts(
    team: Option<Result<TeamResult, TeamError>>,
    spec: Option<&isotrack_scenario::spec::team::TeamSpec>,
    warnings: &mut String,
) -> (Result<RunResult, String>, Option<TeamSummary>) {
    match team {
        None => (Err("no [team] section".into()), None),
        Some(Err(e)) => (Err(format!("[team]: {e}")), None),
        Some(Ok(t)) => {
            let others: Vec<String> = t
                .runs
                .iter()
                .enumerate()
                .skip(1)
                .filter(|(_, r)| r.outcome != isotrack_sim::Outcome::Completed)
                .map(|(i, r)| format!("vehicle {i}: {}", r.outcome.as_str()))
                .collect();
            if let Some(c) = crate::summary::close_approach(&t, spec) {
                if !warnings.is_empty() {
                    warnings.push_str("; ");
                }
                warnings.push_str(&c);
            }
            if !others.is_empty() {
                if !warnings.is_empty() {
                    warnings.push_str("; ");
                }
                warnings.push_str(&format!(
                    "not every vehicle completed ({}); the metric columns are vehicle 0's",
                    others.join(", ")
                ));
            }
            let mut runs = t.runs.into_iter();
            match runs.next() {
                Some(r0) => (Ok(r0), t.team),
                None => (Err("[team]: no vehicle".into()), None),
            }
        }
    }
}

/// The [`TEAM_COLUMNS`] cells of a team run (empty cells without team metrics).
pub fn team_cells(team: Option<&TeamSummary>) -> Vec<String> {
    team_record_cells(team.map(TeamRecord::of).as_ref())
}

/// The [`TEAM_COLUMNS`] cells of a team run's metrics as `summary.json` records them (empty
/// cells without team metrics; a number not finite is `None` there, an empty cell here): the
/// one builder of these cells, for a sweep's `results.csv` ([`team_cells`]) and a benchmark
/// team task's.
pub fn team_record_cells(team: Option<&TeamRecord>) -> Vec<String> {
    let Some(t) = team else {
        return vec![String::new(); TEAM_COLUMNS.len()];
    };
    vec![
        real_cell(t.gap_cv),
        real_cell(t.time_to_even_s),
        real_cell(t.revisit_time_max_s),
        real_cell(t.revisit_time_mean_s),
        real_cell(t.revisit_time_ideal_s),
        real_cell(t.min_separation_m),
        t.order_preserved.to_string(),
    ]
}

/// The scenario of run `id` of a sweep (its base with the run's assignments), or why it is
/// invalid, on one line (its lines joined by one space). The reason names the run, not the
/// sweep file (`_sweep_name`): a row is the same however the sweep file was named (`s.toml`,
/// `./s.toml`, an absolute path), so `--resume` and `merge` recompute it from any directory.
pub fn run_scenario(
    plan: &SweepPlan,
    base: &Scenario,
    id: u64,
    _sweep_name: &str,
) -> Result<Scenario, String> {
    let origin = format!("sweep run {id}");
    let s = base
        .derive_with_in(&plan.run_assignments(id, &origin), &origin, &plan.dir)
        .map_err(|e| one_line(&e.to_string()))?;
    // The header's team columns are the base's: every run of a sweep is a team, or none is.
    match (base.spec().team.is_some(), s.spec().team.is_some()) {
        (false, true) => {
            return Err(format!(
                "{origin}: [team]: the sweep's base scenario has no [team], so its results have no team columns: give the base a [team] to sweep team keys"
            ))
        }
        (true, false) => {
            return Err(format!("{origin}: [team]: this run has no team while the base has one"))
        }
        _ => {}
    }
    Ok(s)
}

/// `text` on one line: its lines trimmed and joined by one space (a message's indented second
/// line reads `invalid scenario: sweep run 1 ...`, not with the indent's spaces).
fn one_line(text: &str) -> String {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The `results.csv` fields of run `id` without warnings (a run with a controller of the
/// caller's, which the scenario's warnings are not about): [`row_fields_warned`].
pub fn row_fields(plan: &SweepPlan, id: u64, result: Result<RunResult, String>) -> Vec<String> {
    row_fields_warned(plan, id, result, String::new())
}

/// The `results.csv` fields of run `id`: its id, the plan's cells, then the
/// [`METRIC_COLUMNS`] of its result, or of an invalid scenario (outcome `invalid_scenario`,
/// the reason in `outcome_detail`), and its `warnings` cell ([`run_warnings`]).
pub fn row_fields_warned(
    plan: &SweepPlan,
    id: u64,
    result: Result<RunResult, String>,
    warnings: String,
) -> Vec<String> {
    // A metric that is not a finite number is written as an empty cell (as summary.json writes
    // null): a results file never holds `NaN` or `inf`, so --resume and merge can refuse them.
    let record = result.as_ref().map(RunRecord::of);
    let mut fields = vec![id.to_string()];
    fields.extend(plan.run_cells(id));
    let mut cells = result_cells(&SWEEP_COLUMNS, record.as_ref().map_err(|e| e.as_str()));
    if let Some(detail) = SWEEP_COLUMNS
        .iter()
        .position(|&c| c == Column::OutcomeDetail)
        .and_then(|i| cells.get_mut(i))
    {
        *detail = text_cell(detail);
    }
    fields.extend(cells);
    fields.push(text_cell(&warnings));
    fields
}

/// A text cell of `results.csv` (`outcome_detail`, `warnings`: isotrack's messages) as a row
/// holds it: every character that is not plain text
/// ([`isotrack_core::numtext::is_not_plain`]: a control, the tab included, a format or
/// separator character) escaped as a message shows it, `\x09` below U+0080 and `\u{2028}`
/// above. A message may quote a user's value (`invalid scenario: ... holds a control or
/// invisible character (U+0009) in `tab<TAB>here``); written as it is, the row was refused
/// by the sweep's own check when the sweep ended, and by every `--resume` after it, which
/// wrote it again (att38-6). `--resume` and `merge` compare a row's cells with the messages
/// recomputed through this too. The varied keys' cells hold the values as they are.
pub fn text_cell(text: &str) -> String {
    use std::fmt::Write;
    if !text.chars().any(isotrack_core::numtext::is_not_plain) {
        return text.to_string();
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if !isotrack_core::numtext::is_not_plain(c) {
            out.push(c);
        } else if (c as u32) < 0x80 {
            let _ = write!(out, "\\x{:02x}", c as u32);
        } else {
            let _ = write!(out, "\\u{{{:x}}}", c as u32);
        }
    }
    out
}

/// The `results.csv` header of a sweep: [`TEAM_COLUMNS`] last when its base has `[team]`
/// (`team`).
pub fn results_header(plan: &SweepPlan, team: bool) -> Vec<String> {
    let mut header: Vec<String> = vec!["run_id".into()];
    header.extend(plan.columns());
    header.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()));
    if team {
        header.extend(TEAM_COLUMNS.iter().map(|c| c.to_string()));
    }
    header
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep's header names are the names of the columns its rows are built from, then
    /// `warnings`.
    #[test]
    fn metric_columns_are_the_sweep_columns_then_warnings() {
        let names: Vec<&str> = SWEEP_COLUMNS.iter().map(|c| c.name()).collect();
        assert_eq!(names[..], METRIC_COLUMNS[..14]);
        assert_eq!(METRIC_COLUMNS[14], "warnings");
    }

    /// The first record of `line` as a reader made for it alone reads it (what `csv_fields`
    /// did before issue 34).
    fn fresh(line: &str) -> Option<Vec<String>> {
        let mut r = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(line.as_bytes());
        let rec = r.records().next()?.ok()?;
        Some(rec.iter().map(str::to_string).collect())
    }

    /// Issue 34: the one reader a thread reuses reads every line as a reader made for it
    /// would, whatever came before: after an empty line (no byte read: a plain `seek` to the
    /// start would be skipped and the reader stay at its end), after a line of more or fewer
    /// fields (a reader that is not flexible refuses a second record of another length), after
    /// an unterminated quote, a line longer than the reader's 8 KiB buffer, lines of several
    /// records, blank lines, CR LF, quotes doubled and quoted line breaks.
    #[test]
    fn csv_record_reads_as_a_fresh_reader() {
        let long = format!("1,\"{}\",3\n", "x,".repeat(10_000));
        let lines = [
            "a,b,c\n",
            "",
            "1,2,3\n",
            "\n",
            "x\n",
            "1,2\n",
            "\"unterminated,4\n",
            "p,q,r,s,t\n",
            "\r\n",
            "\n\nafter,blank\n",
            "two,records\nsecond,one,here\n",
            "crlf,line\r\n",
            "\"quo\"\"ted\",\"line\nbreak\",\n",
            long.as_str(),
            "no newline at the end",
            ",,\n",
            "\u{feff}bom,1\n",
            "",
            "last,1,2,3\n",
        ];
        for _ in 0..2 {
            for line in lines {
                assert_eq!(csv_fields(line), fresh(line), "{line:?}");
            }
        }
        assert_eq!(
            csv_fields("a,\"b,c\",d\n"),
            Some(vec!["a".to_string(), "b,c".to_string(), "d".to_string()])
        );
        assert_eq!(csv_fields(""), None);
        assert_eq!(csv_fields("1,2\n").map(|f| f.len()), Some(2));
    }
}
