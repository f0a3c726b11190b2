//! The check of a stored `results.csv` row: `--resume` and `merge` trust a row only after it.

use crate::sweep::rows::numeric_columns;
use isotrack_core::numtext::{Echo, Num};
use isotrack_scenario::build::{run_span, RunSpan};
use isotrack_scenario::sweep::SweepPlan;
use isotrack_scenario::{apply_assignments, ScenarioFile};

/// The `outcome` values a row may hold.
const OUTCOMES: [&str; 4] = ["completed", "diverged", "left_field", "invalid_scenario"];

/// The metric columns that hold a quantity that cannot be negative (times, maxima, RMS values,
/// lengths, efforts, rates).
const NON_NEGATIVE_COLUMNS: [&str; 10] = [
    "convergence_time_s",
    "steady_state_max_abs_error",
    "steady_state_rms_error",
    "steady_state_max_isoline_distance_m",
    "steady_state_rms_isoline_distance_m",
    "path_length_m",
    "control_effort",
    "chattering_radps2",
    "sign_changes_per_s",
    "t_end_s",
];

/// What a stored row must be: the sweep's header, its run count and its plan (the varied
/// columns of run `id` are recomputed from the plan and must match), and the spans of its runs
/// (what bounds each run's `t_end_s`, `samples` and `convergence_time_s`).
pub struct RowRules<'a> {
    /// The sweep's `results.csv` header.
    pub header: &'a [String],
    /// The sweep's run count.
    pub total: u64,
    /// The sweep's plan.
    pub plan: &'a SweepPlan,
    /// The runs' own step counts.
    pub spans: &'a RunSpans<'a>,
}

/// The keys of a run's scenario that its [`RunSpan`] depends on (`sim.dt_s`,
/// `sim.duration_s`, the sensor's rate, delay and dropouts, the vehicle's kind and speed, the
/// controller's kind and turn-rate limit, a team's top speed and per-vehicle overrides (vehicle
/// 0's own sensor rate and speeds), the metrics' steady-state fraction, convergence dwell and
/// convergence tolerance (att30d-13's bounds; by default 1 % of `controller.level`), or their
/// whole tables).
const SPAN_KEYS: [&str; 21] = [
    "metrics",
    "metrics.steady_state_fraction",
    "metrics.convergence_tolerance",
    "metrics.convergence_min_dwell_s",
    "sim",
    "sensor",
    "sim.dt_s",
    "sim.duration_s",
    "sensor.rate_hz",
    "sensor.delay_s",
    "sensor.dropout_probability",
    "vehicle",
    "vehicle.kind",
    "vehicle.speed_mps",
    "controller",
    "controller.kind",
    "controller.max_turn_rate_radps",
    "controller.level",
    "team",
    "team.v_max_mps",
    "team.vehicles",
];

/// The [`RunSpan`] of each run of a sweep, from its base scenario's own keys
/// ([`isotrack_scenario::Scenario::given`], `base_scenario.toml`): the base's own when the plan
/// varies none of [`SPAN_KEYS`], else each run's (the base's keys with the run's assignments,
/// resolved once, as the sweep runs it: no field is built, no file read).
pub struct RunSpans<'a> {
    base: &'a ScenarioFile,
    plan: &'a SweepPlan,
    base_span: Option<RunSpan>,
    per_run: bool,
    built: Option<(&'a isotrack_scenario::Scenario, &'a str)>,
}

impl<'a> RunSpans<'a> {
    /// The spans of the runs of `plan` over the base scenario's own keys `base`.
    pub fn new(plan: &'a SweepPlan, base: &'a ScenarioFile) -> Self {
        // Every vehicle key too: the fixed wing's turn-rate limit g tan(phi_max) / V follows
        // its airspeed (att30d-5: a sweep over vehicle.airspeed_mps refused its own rows
        // against the base's 30 m/s limit).
        let per_run = plan
            .varied_keys()
            .iter()
            .any(|k| SPAN_KEYS.contains(&k.as_str()) || k.starts_with("vehicle."));
        Self {
            base,
            plan,
            base_span: isotrack_scenario::resolve::resolve(base.clone())
                .ok()
                .as_ref()
                .and_then(run_span),
            per_run,
            built: None,
        }
    }

    /// With the sweep's built base scenario and its name in messages: each row is then also
    /// checked against its run's own scenario ([`crate::sweep::rows::run_scenario`], as the
    /// sweep derives it): a valid run's `warnings` cell against the warnings recomputed
    /// ([`crate::sweep::rows::run_warnings`]), its team cells against its [`TeamBounds`], and an
    /// `invalid_scenario` row against the run's validity and reason.
    pub fn with_scenario(mut self, base: &'a isotrack_scenario::Scenario, name: &'a str) -> Self {
        self.built = Some((base, name));
        self
    }

    /// Run `id`'s scenario as the sweep derives it (`None` without a built base).
    fn scenario(&self, id: u64) -> Option<Result<isotrack_scenario::Scenario, String>> {
        let (base, name) = self.built?;
        Some(crate::sweep::rows::run_scenario(self.plan, base, id, name))
    }

    /// The span of run `id` (`Ok(None)` when it has none: its row is checked without one), or
    /// why its scenario is invalid when the plan varies a key of its span ([`SPAN_KEYS`]) and
    /// the run's values do not apply or resolve: such a run is never run, its row is
    /// `invalid_scenario` (a sweep records the same error for it).
    pub fn of(&self, id: u64) -> Result<Option<RunSpan>, String> {
        if !self.per_run {
            return Ok(self.base_span);
        }
        let file = apply_assignments(self.base, &self.plan.run_assignments(id, ""))
            .map_err(|e| e.to_string())?;
        let resolved = isotrack_scenario::resolve::resolve(file).map_err(|issues| {
            issues
                .iter()
                .map(|i| format!("`{}`: {}", i.key, i.message))
                .collect::<Vec<_>>()
                .join("; ")
        })?;
        Ok(run_span(&resolved))
    }
}

/// Checks one stored row against the sweep: its field count, its `run_id` within the plan, the
/// plan's columns recomputed from the run id, a known outcome and metric values isotrack can
/// have written ([`check_metrics`]). Rows are trusted on `--resume` and `merge` only after
/// this.
pub fn check_row(rules: &RowRules<'_>, line: &str) -> Result<u64, String> {
    let header = rules.header;
    let rec = crate::sweep::rows::csv_record(line).ok_or("not a CSV row")?;
    let id = row_run_id(rules, &rec)?;
    check_plan_cells(rules, &rec, id)?;
    check_written_form(&rec, line)?;
    let cell = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .and_then(|i| rec.get(i))
            .unwrap_or("")
    };
    let outcome = cell("outcome");
    if !OUTCOMES.contains(&outcome) {
        return Err(format!(
            "outcome `{}` is not one of {OUTCOMES:?}",
            clip(outcome)
        ));
    }
    check_metrics(outcome, &cell, true)?;
    if header
        .iter()
        .any(|h| h == crate::sweep::rows::TEAM_COLUMNS[0])
    {
        check_team_cells(outcome, &cell)?;
    }
    check_text_cells(&cell)?;
    let column = |name: &str| {
        let i = header.iter().position(|h| h == name).unwrap_or(0);
        format!("column {} ({name})", i + 1)
    };
    if outcome == "invalid_scenario" {
        check_invalid(rules, id, cell("outcome_detail"), &column)?;
    } else {
        // A run whose scenario the plan makes invalid was never run: a row claiming it ran
        // (another run's metrics under its id) would enter every statistic.
        match rules.spans.of(id) {
            Err(why) => {
                return Err(format!(
                    "{}: outcome = {outcome} for run {id}, whose scenario is invalid under the sweep's plan ({}): it was never run, its row is invalid_scenario",
                    column("outcome"),
                    clip(&why.replace('\n', " "))
                ))
            }
            Ok(Some(span)) => check_span(&span, outcome, &cell, &column)?,
            Ok(None) => {}
        }
        check_against_scenario(rules, id, &cell, &column)?;
    }
    Ok(id)
}

/// The run a row is of: the row has the header's field count, and its first cell is a run
/// number written as isotrack writes it (canonical digits) within the sweep's `total` runs.
fn row_run_id(rules: &RowRules<'_>, rec: &csv::StringRecord) -> Result<u64, String> {
    if rec.len() != rules.header.len() {
        return Err(format!(
            "{} fields where the header has {}",
            rec.len(),
            rules.header.len()
        ));
    }
    let id: u64 = rec[0]
        .parse()
        .ok()
        // Canonical digits, as isotrack writes them (no `+0`, no `00`).
        .filter(|id: &u64| id.to_string() == rec[0])
        .ok_or_else(|| format!("run_id `{}` is not a run number", clip(&rec[0])))?;
    if id >= rules.total {
        return Err(format!(
            "run_id {id} is beyond this sweep's {} runs",
            rules.total
        ));
    }
    Ok(id)
}

/// The plan's columns of run `id` ([`SweepPlan::run_cells`], recomputed from the run id) are
/// the row's cells after its `run_id`, in the header's order.
fn check_plan_cells(rules: &RowRules<'_>, rec: &csv::StringRecord, id: u64) -> Result<(), String> {
    for ((name, cell), want) in rules.header[1..]
        .iter()
        .zip(rec.iter().skip(1))
        .zip(rules.plan.run_cells(id))
    {
        if cell != want {
            return Err(format!(
                "{name} = `{}` where the sweep's plan gives run {id} `{}`",
                clip(cell),
                clip(&want)
            ));
        }
    }
    Ok(())
}

/// The line as isotrack writes it: its cells written again (quoted only where they must be,
/// [`crate::sweep::rows::csv_line`]) give the line back byte for byte; a quoted `"completed"`
/// reads as `completed` but is no line of isotrack's, and resume/merge copy lines verbatim
/// (att30c-3 a).
fn check_written_form(rec: &csv::StringRecord, line: &str) -> Result<(), String> {
    let fields: Vec<String> = rec.iter().map(str::to_string).collect();
    let rewritten = crate::sweep::rows::csv_line(&fields);
    if rewritten.trim_end_matches('\n') != line.trim_end_matches('\n') {
        return Err(
            "the line is not written as isotrack writes its cells (a cell quoted that needs no quotes, or another form)".to_string(),
        );
    }
    Ok(())
}

/// Text cells are isotrack's own messages: never a control character (an escape sequence, a
/// line break) nor a bidirectional or zero-width format character
/// ([`isotrack_core::numtext::is_not_plain`]).
fn check_text_cells<'c>(cell: &dyn Fn(&str) -> &'c str) -> Result<(), String> {
    for name in ["warnings", "outcome_detail"] {
        if cell(name).chars().any(isotrack_core::numtext::is_not_plain) {
            return Err(format!(
                "{name} holds a control or format character (`{}`)",
                clip(cell(name))
            ));
        }
    }
    Ok(())
}

/// An `invalid_scenario` row: the run's scenario must be invalid under the plan, for the
/// reason the sweep records (`outcome_detail`, recomputed). Without a built base, only what
/// resolving tells: nothing to refuse (a scenario can resolve and still fail to build).
/// A team run whose scenario is valid can still be refused by the team engine (`[team]: ...`):
/// such a row's reason is recomputed as the sweep finds it ([`crate::sweep::rows::team_refusal`])
/// and compared, as any other invalid row's.
fn check_invalid(
    rules: &RowRules<'_>,
    id: u64,
    detail: &str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    match rules.spans.scenario(id) {
        None => Ok(()),
        Some(Ok(s)) if detail.starts_with("[team]: ") => {
            match crate::sweep::rows::team_refusal(&s).map(|w| crate::sweep::rows::text_cell(&w)) {
                Some(why) if why == detail => Ok(()),
                Some(why) => Err(format!(
                    "{}: outcome_detail = `{}` is not the reason the team engine gives run {id}: `{}`",
                    column("outcome_detail"),
                    clip(detail),
                    clip(&why)
                )),
                None => Err(format!(
                    "{}: outcome = invalid_scenario (`{}`) for run {id}, whose team the engine flies: it is run, its row holds its results",
                    column("outcome"),
                    clip(detail)
                )),
            }
        }
        Some(Ok(_)) => Err(format!(
            "{}: outcome = invalid_scenario for run {id}, whose scenario is valid under the sweep's plan: it is run, its row holds its results",
            column("outcome")
        )),
        Some(Err(why)) if crate::sweep::rows::text_cell(&why) != detail => Err(format!(
            "{}: outcome_detail = `{}` is not the reason the sweep's plan gives run {id}: `{}`",
            column("outcome_detail"),
            clip(detail),
            clip(&why)
        )),
        Some(Err(_)) => Ok(()),
    }
}

/// A run's row against its own scenario ([`RunSpans::with_scenario`]; nothing without one):
/// the scenario valid, the `warnings` cell the warnings recomputed from it (a team run's may add
/// the vehicles that did not complete, found by running it), its team cells within its
/// [`TeamBounds`].
fn check_against_scenario<'c>(
    rules: &RowRules<'_>,
    id: u64,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let s = match rules.spans.scenario(id) {
        None => return Ok(()),
        Some(Ok(s)) => s,
        Some(Err(why)) => {
            return Err(format!(
                "{}: outcome = {} for run {id}, whose scenario is invalid under the sweep's plan ({}): it was never run, its row is invalid_scenario",
                column("outcome"),
                clip(cell("outcome")),
                clip(&why)
            ))
        }
    };
    let want = crate::sweep::rows::text_cell(&crate::sweep::rows::run_warnings(&s));
    let got = cell("warnings");
    let team = s.spec().team.is_some();
    // A team run's own additions, after the scenario's warnings and `; `: its close approach
    // (`vehicles I and J came within D m of each other at t = T s (...)...`, nu39-3) and/or
    // `not every vehicle completed (vehicle I: OUTCOME, ...); the metric columns are vehicle
    // 0's`, in that order (what the run gave: not recomputed here).
    let unfinished = |r: &str| {
        r.strip_prefix("not every vehicle completed (vehicle ")
            .is_some_and(|r| r.ends_with("); the metric columns are vehicle 0's"))
    };
    let approach = |r: &str| r.starts_with("vehicles ") && r.contains(" came within ");
    let team_tail = |rest: &str| match rest.split_once("; not every vehicle completed (") {
        _ if unfinished(rest) => true,
        Some((a, _)) => approach(a) && unfinished(&rest[a.len() + 2..]),
        None => approach(rest) && !rest.contains("; "),
    };
    let ok = got == want
        || (team
            && if want.is_empty() {
                team_tail(got)
            } else {
                got.strip_prefix(&format!("{want}; "))
                    .is_some_and(team_tail)
            });
    if !ok {
        return Err(format!(
            "{}: warnings = `{}` is not what run {id}'s scenario gives: `{}`",
            column("warnings"),
            clip(got),
            clip(&want)
        ));
    }
    if let Some(b) = TeamBounds::of(&s) {
        if header_has_team(rules) {
            check_team_bounds(cell, &b, column)?;
        }
    }
    Ok(())
}

/// Whether the sweep's rows have the team columns.
fn header_has_team(rules: &RowRules<'_>) -> bool {
    rules
        .header
        .iter()
        .any(|h| h == crate::sweep::rows::TEAM_COLUMNS[0])
}

/// The team columns of a team sweep's row ([`crate::sweep::rows::TEAM_COLUMNS`]): empty in an
/// `invalid_scenario` row; else each number empty or finite, not negative and not subnormal,
/// and `order_preserved` `true`, `false` or empty (no team metrics).
fn check_team_cells<'c>(outcome: &str, cell: &dyn Fn(&str) -> &'c str) -> Result<(), String> {
    let cols = crate::sweep::rows::TEAM_COLUMNS;
    if outcome == "invalid_scenario" {
        if let Some(n) = cols.iter().find(|n| !cell(n).is_empty()) {
            return Err(format!("{n} holds a value in an invalid_scenario row"));
        }
        return Ok(());
    }
    for &n in cols.iter().filter(|n| **n != "order_preserved") {
        let c = cell(n);
        if c.is_empty() {
            continue;
        }
        let ok = c.parse::<f64>().is_ok_and(|v| {
            v.is_finite() && (v == 0.0 || v.is_normal()) && v >= 0.0 && !c.starts_with('-')
        });
        if !ok {
            return Err(format!(
                "{n} = `{}` is not a finite, non-negative number",
                clip(c)
            ));
        }
    }
    let o = cell("order_preserved");
    if !["", "true", "false"].contains(&o) {
        return Err(format!(
            "order_preserved = `{}` is not true or false",
            clip(o)
        ));
    }
    // Team metrics exist together: no ideal revisit time without them. With them it may be
    // empty: an open isoline's is the mean gap over the samples with two vehicles on the curve,
    // none when every vehicle left it first (nu40-12: the writer gave such a row, this check
    // called it damaged, and the sweep could never finish).
    if o.is_empty() && !cell("revisit_time_ideal_s").is_empty() {
        return Err("revisit_time_ideal_s is given without order_preserved".into());
    }
    Ok(())
}

#[cfg(test)]
mod team_cell_tests {
    use super::check_team_cells;

    fn cells<'a>(order: &'a str, ideal: &'a str) -> impl Fn(&str) -> &'a str {
        move |n: &str| match n {
            "order_preserved" => order,
            "revisit_time_ideal_s" => ideal,
            _ => "",
        }
    }

    /// nu40-12: a team run on an open isoline whose vehicles all left it before two were on
    /// the curve has team metrics (order_preserved) and no ideal revisit time: a valid row.
    /// An ideal revisit time without any team metric is not.
    #[test]
    fn an_open_runs_row_without_an_ideal_revisit_time_is_valid() {
        assert_eq!(check_team_cells("left_field", &cells("true", "")), Ok(()));
        assert_eq!(
            check_team_cells("completed", &cells("false", "12.5")),
            Ok(())
        );
        assert_eq!(check_team_cells("completed", &cells("", "")), Ok(()));
        assert!(check_team_cells("completed", &cells("", "12.5")).is_err());
    }
}

/// The cells a run's own step counts bound ([`RunSpan`]): `t_end_s` is `k dt` for a whole
/// `k <= N` (the planned steps: not past the duration); `convergence_time_s` is 0 or `j dt`
/// for a whole `1 <= j <= k` (never a fraction of a step, never below `dt`); `samples` is at
/// most the sample steps of the steps sensed `0..=s` past the sensor's delay of `d` steps,
/// `floor(s / m) - ceil(d / m) + 1` (0 when `s < d`), where `s = k` or, for a `diverged` run
/// (ended by a non-finite command, sensed the step after its last valid one), `min(k + 1, N)`;
/// and, without dropouts, at least those of the steps `0..=k`, `floor(k / m) - ceil(d / m) + 1`
/// ([`fewest_samples`]): without dropouts a completed run's count is exactly that. Under a
/// turn-rate limit `L` (`|omega| <= L` for every command), `control_effort = sum omega^2 dt`
/// over at most `min(k + 1, N)` held commands is at most `L^2 dt min(k + 1, N)`, and `chattering_radps2` (the total variation of `omega` over the
/// window, at most `2 L` a step, over the window's duration) at most `2 L / dt`. Each error
/// names its column.
pub fn check_span<'c>(
    span: &RunSpan,
    outcome: &str,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let Some((t_end, k_end)) = span_end(span, cell, column)? else {
        return Ok(());
    };
    let end = SpanEnd {
        span,
        outcome,
        t_end,
        k_end,
    };
    if let Some(c) = cell_value(cell, "convergence_time_s") {
        if c != 0.0 && !steps_of(span, c).is_some_and(|j| (1..=k_end).contains(&j)) {
            return Err(format!(
                "{}: convergence_time_s = {} s is neither 0 nor a whole number of the run's steps of {} s up to t_end_s = {} s",
                column("convergence_time_s"),
                Echo(c),
                Echo(span.dt_s),
                Echo(t_end)
            ));
        }
    }
    if let Ok(samples) = cell("samples").parse::<u64>() {
        check_span_samples(&end, samples, column)?;
    }
    if let Some(limit) = span.turn_rate_limit_radps {
        check_span_turn_rate(&end, limit, cell, column)?;
    }
    check_span_motion(&end, cell, column)?;
    // Last: the bounds above name the more basic fault of a row first.
    if let Some(ms) = span.metric_steps {
        check_metric_windows(&ms, span.dt_s, outcome, k_end, t_end, cell, column)?;
    }
    Ok(())
}

/// Where a row's run ended, as [`check_span`] reads it.
struct SpanEnd<'s> {
    /// The run's span.
    span: &'s RunSpan,
    /// The row's `outcome`.
    outcome: &'s str,
    /// The row's `t_end_s`, in s.
    t_end: f64,
    /// The steps `k` with `t_end_s = k dt`.
    k_end: u64,
}

impl SpanEnd<'_> {
    /// The steps a row's run sensed and moved: `k`, or for a `diverged` run (ended by a
    /// non-finite command, sensed and moved the step after its last valid one) `min(k + 1, N)`.
    fn steps_taken(&self) -> u64 {
        if self.outcome == "diverged" {
            (self.k_end + 1).min(self.span.n_steps)
        } else {
            self.k_end
        }
    }
}

/// Whole steps as a run computes its times (`k as f64 * dt`, `k <= N`): `None` for any other
/// value.
fn steps_of(span: &RunSpan, t: f64) -> Option<u64> {
    let dt = span.dt_s;
    let k = (t / dt).round();
    (k >= 0.0 && k <= span.n_steps as f64 && k * dt == t).then_some(k as u64)
}

/// The number in cell `n` (`None` when it is empty or no number).
fn cell_value<'c>(cell: &dyn Fn(&str) -> &'c str, n: &str) -> Option<f64> {
    cell(n).parse::<f64>().ok()
}

/// A row's end, `t_end_s = k dt` and `k`: not past the run's duration `N dt`, a whole number
/// of steps. A record without `t_end_s` (a benchmark task's run, of a run that did not
/// complete) is bounded by the whole run: `k <= N`; a sweep row always has one
/// ([`check_metrics`]). `Ok(None)`: a `t_end_s` that is no number, refused by
/// [`check_metrics`], bounds nothing here.
fn span_end<'c>(
    span: &RunSpan,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<Option<(f64, u64)>, String> {
    let dt = span.dt_s;
    let duration = span.n_steps as f64 * dt;
    let t_end = match cell_value(cell, "t_end_s") {
        Some(t) => t,
        None if cell("t_end_s").is_empty() => duration,
        None => return Ok(None),
    };
    if t_end > duration {
        return Err(format!(
            "{}: t_end_s = {} s is past the run's duration, {} steps of {} s = {} s",
            column("t_end_s"),
            Echo(t_end),
            span.n_steps,
            Echo(dt),
            Num(duration)
        ));
    }
    let Some(k_end) = steps_of(span, t_end) else {
        return Err(format!(
            "{}: t_end_s = {} s is not a whole number of the run's steps of {} s",
            column("t_end_s"),
            Echo(t_end),
            Echo(dt)
        ));
    };
    Ok(Some((t_end, k_end)))
}

/// The `samples` cell between the fewest a run without dropouts takes up to its end
/// ([`fewest_samples`]) and the most any run can take over the steps it sensed
/// ([`SpanEnd::steps_taken`], [`delivered_samples`]).
fn check_span_samples(
    end: &SpanEnd<'_>,
    samples: u64,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let span = end.span;
    let most = delivered_samples(span, end.steps_taken());
    if samples > most {
        return Err(format!(
            "{}: samples = {samples} exceeds the {most} a run can take up to t_end_s = {} s (one every {} steps of {} s from step {})",
            column("samples"),
            Echo(end.t_end),
            span.steps_per_sample,
            Echo(span.dt_s),
            span.sensor_delay_steps
        ));
    }
    let fewest = fewest_samples(span, end.outcome, end.k_end);
    if samples < fewest {
        return Err(format!(
            "{}: samples = {samples} is below the {fewest} a run without dropouts takes up to t_end_s = {} s (one every {} steps of {} s from step {})",
            column("samples"),
            Echo(end.t_end),
            span.steps_per_sample,
            Echo(span.dt_s),
            span.sensor_delay_steps
        ));
    }
    Ok(())
}

/// The cells a turn-rate limit `L` bounds: `control_effort = sum omega^2 dt` over the
/// `min(k + 1, N)` commands held is at most `L^2 dt min(k + 1, N)` (and so present unless the
/// run diverged), `chattering_radps2` at most `2 L / dt` (a swing of `2 L` every step).
fn check_span_turn_rate<'c>(
    end: &SpanEnd<'_>,
    limit: f64,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let (dt, outcome) = (end.span.dt_s, end.outcome);
    // Commands held over the steps integrated: `k` for a run that completed at step `k =
    // N`, `k + 1` for one that ended in the step after its last valid one.
    let held = (end.k_end + 1).min(end.span.n_steps);
    let most_effort = limit * limit * dt * held as f64;
    // Under the limit the effort is finite (at most `most_effort`): only a diverged run's
    // is written empty (att30d-1).
    if outcome != "diverged" && most_effort.is_finite() && cell("control_effort").is_empty() {
        return Err(format!(
            "{}: control_effort is empty in a `{outcome}` row: under the turn-rate limit {} rad/s it is at most {} rad^2/s",
            column("control_effort"),
            Echo(limit),
            Num(most_effort)
        ));
    }
    if let Some(e) = cell_value(cell, "control_effort") {
        if e > most_effort * (1.0 + 1e-6) {
            return Err(format!(
                "{}: control_effort = {} exceeds {} rad^2/s, the turn-rate limit {} rad/s held over {held} steps of {} s",
                column("control_effort"),
                Echo(e),
                Num(most_effort),
                Echo(limit),
                Echo(dt)
            ));
        }
    }
    if let Some(c) = cell_value(cell, "chattering_radps2") {
        let most = 2.0 * limit / dt;
        if c > most * (1.0 + 1e-6) {
            return Err(format!(
                "{}: chattering_radps2 = {} exceeds {} rad/s^2, a swing of twice the turn-rate limit {} rad/s every step of {} s",
                column("chattering_radps2"),
                Echo(c),
                Num(most),
                Echo(limit),
                Echo(dt)
            ));
        }
    }
    Ok(())
}

/// The cells the steps themselves bound: `sign_changes_per_s` at most one per step (`1 / dt`
/// per second); `path_length_m` no longer than the fastest speed over the steps moved
/// ([`SpanEnd::steps_taken`]), +1 %.
fn check_span_motion<'c>(
    end: &SpanEnd<'_>,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let dt = end.span.dt_s;
    if let Some(r) = cell_value(cell, "sign_changes_per_s") {
        if r > (1.0 / dt) * (1.0 + 1e-9) {
            return Err(format!(
                "{}: sign_changes_per_s = {} exceeds one per step of {} s",
                column("sign_changes_per_s"),
                Echo(r),
                Echo(dt)
            ));
        }
    }
    if let (Some(v), Some(len)) = (end.span.speed_max_mps, cell_value(cell, "path_length_m")) {
        let moved = end.steps_taken();
        let moved_s = moved as f64 * dt;
        if len > v * moved_s * 1.01 + 1e-9 {
            return Err(format!(
                "{}: path_length_m = {} m exceeds {} m/s x {moved} steps of {} s = {} s (t_end_s = {} s)",
                column("path_length_m"),
                Echo(len),
                Echo(v),
                Echo(dt),
                Num(moved_s),
                Echo(end.t_end)
            ));
        }
    }
    Ok(())
}

/// The cells the run's metric windows bound ([`isotrack_scenario::build::MetricSteps`], from
/// the run's step plan), as `isotrack_sim::Metrics::finish` computes them over the steps
/// `0..=k` observed by a run that ended at step `k` (`t_end_s = k dt`):
///
/// * `convergence_time_s` is reported by a `completed` run only, and only after the error
///   stayed within the tolerance for more than the dwell's `w` steps up to `k`: `0` needs
///   `k >= w`, `j dt` needs `j <= k - w`, so it is at most `(k - w) dt` (att30c-3 c: `t_end_s`
///   itself is no convergence time).
/// * `sign_changes_per_s` is a whole count `n` of sign changes over the steady-state window
///   from step `ss` to `k`, divided by its duration `(k - ss) dt` (`n <= k - ss`, one per
///   step at most): the cell must be `n / ((k - ss) dt)` for a whole `n`, bit for bit as the
///   division gives it (the cell is checked to be the shortest round-trip form of its value
///   before); no window (`k <= ss`), no rate (att30c-3 d).
fn check_metric_windows<'c>(
    ms: &isotrack_scenario::build::MetricSteps,
    dt: f64,
    outcome: &str,
    k_end: u64,
    t_end: f64,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let value = |n: &str| cell(n).parse::<f64>().ok();
    let w = ms.convergence_min_dwell_steps;
    if let Some(c) = value("convergence_time_s") {
        if outcome != "completed" {
            return Err(format!(
                "{}: convergence_time_s = {} s in a `{outcome}` row: only a run that completed reports a convergence time",
                column("convergence_time_s"),
                Echo(c)
            ));
        }
        // In whole steps (check_span has checked `c = j dt` for a whole `j`, or 0).
        let j = (c / dt).round();
        if k_end < w || j > (k_end - w) as f64 {
            let latest = k_end.saturating_sub(w) as f64 * dt;
            return Err(format!(
                "{}: convergence_time_s = {} s is later than t_end_s - metrics.convergence_min_dwell_s = {} s ({k_end} - {w} steps of {} s): a convergence time needs the error within the tolerance for more than the dwell's {w} steps up to the end",
                column("convergence_time_s"),
                Echo(c),
                Num(latest),
                Echo(dt)
            ));
        }
    }
    check_tolerance_implications(ms, dt, cell, column)?;
    if outcome == "completed" {
        check_converged_window(ms, dt, k_end, cell, column)?;
    }
    // A completed run observed every step of its window (`k_end = N`, the window from step
    // `ss`): its sign-change rate (a count over the window's duration, always finite) is there
    // once the window spans a step (att30d-1). A task's run records no rates (no `samples`).
    let ss = ms.steady_state_start_step;
    if outcome == "completed"
        && k_end > ss + 2
        && !cell("samples").is_empty()
        && cell("sign_changes_per_s").is_empty()
    {
        return Err(format!(
            "{}: sign_changes_per_s is empty in a `completed` row whose steady-state window spans steps {ss} to {k_end}",
            column("sign_changes_per_s")
        ));
    }
    // A benchmark task's record has no `t_end_s`: its end step is known only for a run that
    // completed (`k = N`).
    let end_known = !cell("t_end_s").is_empty() || outcome == "completed";
    if let Some(r) = value("sign_changes_per_s").filter(|_| end_known) {
        let ss = ms.steady_state_start_step;
        let steps = k_end.saturating_sub(ss);
        let window_s = steps as f64 * dt;
        // The count `n` whose `n / window` the metrics wrote: the two whole numbers nearest
        // `r window` (the product rounds), each within one per step.
        let whole = steps > 0
            && [(r * window_s).floor(), (r * window_s).ceil()]
                .iter()
                .any(|&n| n >= 0.0 && n <= steps as f64 && n / window_s == r);
        if !whole {
            return Err(format!(
                "{}: sign_changes_per_s = {} is not a whole number of sign changes (at most one per step) over the steady-state window of {steps} steps of {} s = {} s (steps {ss} to {k_end}, t_end_s = {} s)",
                column("sign_changes_per_s"),
                Echo(r),
                Echo(dt),
                Num(window_s),
                Echo(t_end)
            ));
        }
    }
    Ok(())
}

/// The metrics that the convergence tolerance `tol` ties together, as
/// `isotrack_sim::Metrics` computes them (issue 30, att30d-13: a row or task with a
/// convergence time of 0 beside a steady-state error far past the tolerance, or an in-band
/// share of 1 beside an RMS error past it, was kept, and raised a task's score):
/// * a convergence time `c = j dt` at or before the steady-state window's first step `s`
///   (`j <= s`) means `|eps_k| < tol` at every step from `j` to the end, so over the window the
///   maximum `|eps|` is below `tol`, the RMS at most it (to rounding) and every step in the
///   band (`time_in_band_fraction = 1`);
/// * `time_in_band_fraction = 1` (every window step with `|eps| <= tol`: `n / n`, exact) means
///   a maximum and an RMS of at most `tol`;
/// * a maximum of at most `tol` means every window step in the band: a share of 1.
///
/// Each error names its column and the tolerance.
fn check_tolerance_implications<'c>(
    ms: &isotrack_scenario::build::MetricSteps,
    dt: f64,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let value = |n: &str| cell(n).parse::<f64>().ok();
    let tol = ms.convergence_tolerance;
    let ss = ms.steady_state_start_step;
    let (max, rms, share) = (
        value("steady_state_max_abs_error"),
        value("steady_state_rms_error"),
        value("time_in_band_fraction"),
    );
    // An RMS of values all within the tolerance may exceed it by rounding only.
    let rms_over = |r: f64| r > tol * (1.0 + 1e-12);
    let contradicts = |name: &str, v: f64, why: &str| {
        Err(format!(
            "{}: {name} = {} contradicts it ({why})",
            column(name),
            Echo(v)
        ))
    };
    if let Some(c) = value("convergence_time_s").filter(|c| (c / dt).round() <= ss as f64) {
        let why = format!(
            "convergence_time_s = {} s is at or before the steady-state window's start ({} s): |error| stays below metrics.convergence_tolerance = {} from then to the end",
            Echo(c),
            Num(ss as f64 * dt),
            Echo(tol)
        );
        if let Some(m) = max.filter(|&m| m >= tol) {
            return contradicts("steady_state_max_abs_error", m, &why);
        }
        if let Some(r) = rms.filter(|&r| rms_over(r)) {
            return contradicts("steady_state_rms_error", r, &why);
        }
        if let Some(f) = share.filter(|&f| f != 1.0) {
            return contradicts(
                "time_in_band_fraction",
                f,
                &format!("{why}, so every step of the window is in the band"),
            );
        }
    }
    if share == Some(1.0) {
        let why = format!(
            "time_in_band_fraction = 1 puts every step of the steady-state window within metrics.convergence_tolerance = {}",
            Echo(tol)
        );
        if let Some(m) = max.filter(|&m| m > tol) {
            return contradicts("steady_state_max_abs_error", m, &why);
        }
        if let Some(r) = rms.filter(|&r| rms_over(r)) {
            return contradicts("steady_state_rms_error", r, &why);
        }
    }
    // A NaN error (no value) is outside the band but leaves the maximum alone; it makes the
    // RMS NaN (no number), so the maximum speaks for every step only beside a finite RMS.
    if let (Some(m), Some(f), Some(_)) = (max, share, rms.filter(|r| r.is_finite())) {
        if m <= tol && f != 1.0 {
            return Err(format!(
                "{}: time_in_band_fraction = {} where steady_state_max_abs_error = {} is within metrics.convergence_tolerance = {}: every step of the window is in the band (a share of 1)",
                column("time_in_band_fraction"),
                Echo(f),
                Echo(m),
                Echo(tol)
            ));
        }
    }
    Ok(())
}

/// The converse of [`check_tolerance_implications`]' first rule (att49-5), for a run that
/// completed at step `k` (`t_end_s = k dt`) with its steady-state window from step `s`:
/// a window maximum `|eps|` below the tolerance (the metrics' strict `|eps| < tol`), with a
/// finite RMS (no step without an error value: a NaN counts as outside the band but leaves
/// the maximum alone, and makes the RMS NaN), puts no violation at any step from `s` to `k`,
/// so the last one, if any, is at a step `j < s`. The run then converged at `(j + 1) dt <= s dt`
/// (or 0 with none) as soon as the steps inside after it, `k - j - 1 >= k - s`, exceed the
/// dwell's `w` (or `k >= w`): so when `k - s >= w`, `convergence_time_s` is there and at or
/// before the window's start.
fn check_converged_window<'c>(
    ms: &isotrack_scenario::build::MetricSteps,
    dt: f64,
    k_end: u64,
    cell: &dyn Fn(&str) -> &'c str,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let value = |n: &str| cell(n).parse::<f64>().ok();
    let (tol, ss, w) = (
        ms.convergence_tolerance,
        ms.steady_state_start_step,
        ms.convergence_min_dwell_steps,
    );
    let within = value("steady_state_max_abs_error").filter(|&m| m < tol);
    let rms_finite = value("steady_state_rms_error").is_some_and(f64::is_finite);
    let (Some(m), true) = (within, rms_finite) else {
        return Ok(());
    };
    if k_end < ss || k_end - ss < w {
        return Ok(());
    }
    let c = value("convergence_time_s");
    if c.is_some_and(|c| (c / dt).round() <= ss as f64) {
        return Ok(());
    }
    Err(format!(
        "{}: convergence_time_s = {} contradicts it (steady_state_max_abs_error = {} is below metrics.convergence_tolerance = {} over the whole steady-state window, steps {ss} to {k_end} of {} s, at least metrics.convergence_min_dwell_s = {} s long: the run converged at or before the window's start, {} s)",
        column("convergence_time_s"),
        c.map_or("null".to_string(), |c| format!("{} s", Echo(c))),
        Echo(m),
        Echo(tol),
        Echo(dt),
        Num(w as f64 * dt),
        Num(ss as f64 * dt)
    ))
}

/// The fewest samples a run of `span` that ended as `outcome` at step `k_end` delivered: none
/// when the sensor drops samples, or when the run ended before completing its first step
/// (`k_end = 0`, not `completed`: it sensed nothing or only its start); else the sample steps
/// `j m` (`m` steps per sample) from the delay's `d` steps to `k_end`, every one of which
/// the run sensed, `floor(k_end / m) - ceil(d / m) + 1` (0 when `k_end < d`).
pub fn fewest_samples(span: &RunSpan, outcome: &str, k_end: u64) -> u64 {
    if span.sensor_drops_samples || (k_end == 0 && outcome != "completed") {
        return 0;
    }
    delivered_samples(span, k_end)
}

/// The samples a run of `span` delivers over the steps `0..=s` without dropouts: the sample
/// steps `j m` (`m` steps per sample) from the sensor's delay of `d` steps to `s`,
/// `floor(s / m) - ceil(d / m) + 1`, 0 when `s < d` (a delayed sensor delivers nothing
/// before its delay). The most any run delivers (dropouts only remove samples).
fn delivered_samples(span: &RunSpan, s: u64) -> u64 {
    let (m, d) = (span.steps_per_sample, span.sensor_delay_steps);
    if s < d {
        return 0;
    }
    (s / m + 1).saturating_sub(d.div_ceil(m))
}

/// The metric cells of one row are what isotrack writes: an `invalid_scenario` row has none; a
/// `completed` row no `outcome_detail`; a run's row has `t_end_s` and `samples`; every number
/// is finite (non-finite metrics are written empty; subnormals are kept), the quantities that
/// cannot be negative are not (nor `-0.0`), an RMS is at most its
/// maximum and `|mean|` at most the maximum (to rounding), the convergence time at most the run's
/// end, and `samples` a whole number of at most one per step ([`isotrack_sim::MAX_STEPS`] + 1).
///
/// `whole_row`: the record is a whole `results.csv` row (a sweep's), so `t_end_s` and `samples`
/// must be there; a benchmark task's run (`task.json`) records neither, and its
/// `time_in_band_fraction` (a share, in `[0, 1]`) and `track_losses` (a whole number) besides.
pub fn check_metrics<'c>(
    outcome: &str,
    cell: &dyn Fn(&str) -> &'c str,
    whole_row: bool,
) -> Result<(), String> {
    let numeric = numeric_columns();
    if !OUTCOMES.contains(&outcome) {
        return Err(format!(
            "outcome `{}` is not one of {OUTCOMES:?}",
            clip(outcome)
        ));
    }
    check_share_cell(outcome, cell)?;
    if outcome == "invalid_scenario" {
        if let Some(n) = numeric.iter().find(|n| !cell(n).is_empty()) {
            return Err(format!("{n} holds a value in an invalid_scenario row"));
        }
        return Ok(());
    }
    check_run_end_cells(outcome, cell, whole_row)?;
    let value = numeric_values(numeric, cell)?;
    check_samples_cell(cell, whole_row)?;
    check_emptied_cells(outcome, cell, whole_row)?;
    check_metric_orderings(&value)
}

/// `time_in_band_fraction`, when given (a benchmark task's run records it): not in an
/// `invalid_scenario` row, a share in `[0, 1]` written as isotrack writes it
/// ([`crate::results::real_cell`]).
fn check_share_cell<'c>(outcome: &str, cell: &dyn Fn(&str) -> &'c str) -> Result<(), String> {
    let share = cell("time_in_band_fraction");
    if !share.is_empty() {
        if outcome == "invalid_scenario" {
            return Err("time_in_band_fraction holds a value in an invalid_scenario row".into());
        }
        let ok = share.parse::<f64>().is_ok_and(|v| {
            (0.0..=1.0).contains(&v)
                && !v.is_sign_negative()
                && crate::results::real_cell(Some(v)) == share
        });
        if !ok {
            return Err(format!(
                "time_in_band_fraction = `{}` is not a share in [0, 1]",
                clip(share)
            ));
        }
    }
    Ok(())
}

/// The cells that say how a run ended: the detail says why a run did not complete, so a
/// completed row has none and (in a whole row) a row that did not complete always one (the run
/// ends with its reason; att30c-3 b); a whole row has `t_end_s` and `samples`.
fn check_run_end_cells<'c>(
    outcome: &str,
    cell: &dyn Fn(&str) -> &'c str,
    whole_row: bool,
) -> Result<(), String> {
    if outcome == "completed" && !cell("outcome_detail").is_empty() {
        return Err("outcome_detail holds text in a `completed` row".to_string());
    }
    if whole_row && outcome != "completed" && cell("outcome_detail").is_empty() {
        return Err(format!(
            "outcome_detail is empty in a `{outcome}` row: a run that did not complete says why"
        ));
    }
    for n in ["t_end_s", "samples"].into_iter().filter(|_| whole_row) {
        if cell(n).is_empty() {
            return Err(format!("{n} is empty in a `{outcome}` row"));
        }
    }
    Ok(())
}

/// The values of the non-empty numeric cells but `samples`, each a finite number, not negative
/// (nor `-0.0`) in [`NON_NEGATIVE_COLUMNS`], written in isotrack's own form.
fn numeric_values<'c>(
    numeric: &'static [&'static str],
    cell: &dyn Fn(&str) -> &'c str,
) -> Result<std::collections::HashMap<&'static str, f64>, String> {
    let mut value = std::collections::HashMap::new();
    for &n in numeric.iter().filter(|n| **n != "samples") {
        let c = cell(n);
        if c.is_empty() {
            continue;
        }
        let v: f64 = c
            .parse()
            .map_err(|_| format!("{n} = `{}` is not a number", clip(c)))?;
        if !v.is_finite() {
            return Err(format!("{n} = `{c}` is not a finite number"));
        }
        // `-0.0` too: isotrack never writes a negative zero in these columns.
        if v.is_sign_negative() && NON_NEGATIVE_COLUMNS.contains(&n) {
            return Err(format!("{n} = `{c}` is negative"));
        }
        // Written as isotrack writes it ([`crate::results::real_cell`], the shortest
        // round-trip form): `+7.000e0` reads as 7 but is no cell of isotrack's, and `merge`
        // would copy it verbatim (issue 30, fix30c).
        let canonical = crate::results::real_cell(Some(v));
        if c != canonical {
            return Err(format!(
                "{n} = `{}` is not how isotrack writes {canonical}",
                clip(c)
            ));
        }
        // A subnormal (below 2.2e-308) is a value a run does produce (issue 30: a gain of
        // 1e-155 gives a control effort of 8e-311, a field of 4e-308 subnormal errors): kept,
        // as the writer writes it. The times are bounded to whole steps by `check_span`.
        value.insert(n, v);
    }
    Ok(value)
}

/// `samples`: a whole number in canonical digits of at most one per step
/// ([`isotrack_sim::MAX_STEPS`] + 1); empty only outside a whole row.
fn check_samples_cell<'c>(cell: &dyn Fn(&str) -> &'c str, whole_row: bool) -> Result<(), String> {
    let samples = cell("samples");
    match samples.parse::<u64>() {
        _ if samples.is_empty() && !whole_row => Ok(()),
        // Canonical digits, as isotrack writes them (no `+70`, no `070`).
        Ok(k) if k <= isotrack_sim::MAX_STEPS + 1 && k.to_string() == samples => Ok(()),
        _ => Err(format!(
            "samples = `{}` is not a whole number of samples (at most {})",
            clip(samples),
            isotrack_sim::MAX_STEPS + 1
        )),
    }
}

/// The orderings between metrics that hold by their definitions: an RMS and a `|mean|` at most
/// their window's maximum, the convergence time at most the run's end (to rounding: an RMS of
/// equal values may exceed their maximum by an ulp or so).
fn check_metric_orderings(value: &std::collections::HashMap<&str, f64>) -> Result<(), String> {
    let at_most = |a: &str, b: &str, what: &str| -> Result<(), String> {
        match (value.get(a), value.get(b)) {
            (Some(x), Some(y)) if x.abs() > y * (1.0 + 1e-12) => {
                Err(format!("{a} = {x:?} exceeds {b} = {y:?} ({what})"))
            }
            _ => Ok(()),
        }
    };
    at_most(
        "steady_state_rms_error",
        "steady_state_max_abs_error",
        "an RMS is at most the maximum",
    )?;
    at_most(
        "steady_state_mean_error",
        "steady_state_max_abs_error",
        "|mean| is at most the maximum",
    )?;
    at_most(
        "steady_state_rms_isoline_distance_m",
        "steady_state_max_isoline_distance_m",
        "an RMS is at most the maximum",
    )?;
    at_most(
        "convergence_time_s",
        "t_end_s",
        "convergence happens within the run",
    )
}

/// The metric cells a run always has, or has together, as `isotrack_sim::Metrics::finish`
/// writes them (issue 30, att30d-1: a `completed` row with `path_length_m` emptied, or
/// `steady_state_rms_error` alone emptied beside its window's maximum, was kept). A run that
/// completed or left the field has a finite path length (a bounded speed over finitely many
/// steps; only a diverged run's can be non-finite, written empty; the control effort is
/// bounded only under a turn-rate limit: [`check_span`]). A completed run's error is finite at
/// every step, so the steady-state window's maximum, RMS and mean are all there or all missing
/// (no window), the two isoline distances likewise, unless the maximum is so large that the
/// sum of squares overflows (at or past 1e100 here, far below any overflow with at most 2^53
/// steps: an RMS of a field in the 1e200s is written empty). In a whole row only (a
/// benchmark task's run records fewer metrics).
fn check_emptied_cells<'c>(
    outcome: &str,
    cell: &dyn Fn(&str) -> &'c str,
    whole_row: bool,
) -> Result<(), String> {
    if !whole_row {
        return Ok(());
    }
    if (outcome == "completed" || outcome == "left_field") && cell("path_length_m").is_empty() {
        return Err(format!(
            "path_length_m is empty in a `{outcome}` row: a run that did not diverge has a finite path length"
        ));
    }
    if outcome != "completed" {
        return Ok(());
    }
    let groups: [(&str, &[&str]); 2] = [
        (
            "steady_state_max_abs_error",
            &["steady_state_rms_error", "steady_state_mean_error"],
        ),
        (
            "steady_state_max_isoline_distance_m",
            &["steady_state_rms_isoline_distance_m"],
        ),
    ];
    for (max, others) in groups {
        let m = cell(max);
        let small = m.parse::<f64>().is_ok_and(|v| v < 1e100);
        for n in others {
            if small && cell(n).is_empty() {
                return Err(format!(
                    "{n} is empty beside {max} = {} in a `completed` row: the metrics of one window are written together",
                    clip(m)
                ));
            }
            if m.is_empty() && !cell(n).is_empty() {
                return Err(format!(
                    "{max} is empty beside {n} = {} in a `completed` row: the metrics of one window are written together",
                    clip(cell(n))
                ));
            }
        }
    }
    Ok(())
}

/// User text from a damaged file, clipped for a message.
pub fn clip(text: &str) -> String {
    isotrack_scenario::load::clip(text)
}

/// What bounds a team run's team metrics, from its scenario ([`TeamBounds::of`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TeamBounds {
    /// The run's planned duration `N dt`, s: every time the metrics measure (a sample time, an
    /// interval between passes, an open interval to the end) lies within it.
    pub duration_s: f64,
    /// The farthest two vehicles can be apart at any time of the run, m: the largest distance
    /// between two starts plus twice the top speed over the duration (+1 %); `None` where the
    /// top ground speed is not known (a fixed wing: wind adds to its airspeed).
    pub reach_m: Option<f64>,
    /// The ideal revisit time `L / (N v0)`, s, of a run along a fixed closed isoline (its
    /// length `L` as the run measures it); `None` for an isoline that moves (its `L` is the
    /// mean of the lengths the run saw), an open one (its ideal is the stretch the team
    /// covered) or none.
    pub ideal_s: Option<f64>,
    /// The team's vehicle count `N`: a gap CV is at most `sqrt(N - 1)` ([`max_gap_cv`]).
    pub count: usize,
    /// The speeds a vehicle of the team can hold, `[min v_min_i, max v_max_i]`, m/s
    /// ([`isotrack_scenario::spec::team::TeamSpec::speed_envelope_mps`]: every command is
    /// saturated to its vehicle's envelope and a Dubins robot holds its command); `None` for a
    /// fixed wing, whose ground speed (what the metrics sample) adds the wind to its airspeed.
    pub speed_envelope_mps: Option<(f64, f64)>,
    /// The length of a fixed closed isoline, m, as the run measures it (the `L` of
    /// [`TeamBounds::ideal_s`]; on a known circle `2 pi R`): the summary's
    /// `isoline_length_m`. `None` where `ideal_s` is.
    pub isoline_length_m: Option<f64>,
    /// The steady-state window's start `ss dt`, s (the run's step plan's; at or before the
    /// window's first team sample); `None` without a window in the plan.
    pub window_start_s: Option<f64>,
}

/// The largest gap CV of a team of `n` vehicles: `sqrt(n - 1)` (0 for one vehicle or none).
///
/// The metrics' gap CV (`isotrack_sim::team::metrics`) is the *population* standard deviation
/// of `k` arc gaps `g_j >= 0` over their mean `m = S / k`, with `S` their sum (a closed
/// isoline: the `k <= n` live vehicles' gaps round the loop, `S = L`; an open one: the `k =
/// live - 1 <= n - 1` gaps along the team's stretch). Since every `g_j >= 0`, `sum g_j^2 <=
/// (sum g_j)^2 = S^2`, so the variance `(1/k) sum g_j^2 - m^2 <= S^2 / k - m^2 = (k - 1) m^2`
/// and the CV is at most `sqrt(k - 1) <= sqrt(n - 1)`, reached when one gap holds the whole
/// length (every vehicle at one point). `gap_cv`, a mean of such CVs over the steady window,
/// is bounded alike.
pub fn max_gap_cv(n: usize) -> f64 {
    (n.saturating_sub(1) as f64).sqrt()
}

impl TeamBounds {
    /// The bounds of a run of team scenario `s` (`None` without `[team]`).
    pub fn of(s: &isotrack_scenario::Scenario) -> Option<TeamBounds> {
        let team = s.spec().team.as_ref()?;
        let span = run_span(s.file())?;
        let duration_s = span.n_steps as f64 * span.dt_s;
        let mut spread = 0.0f64;
        for a in &team.starts {
            for b in &team.starts {
                spread = spread.max((a.x_m - b.x_m).hypot(a.y_m - b.y_m));
            }
        }
        let reach_m = span
            .speed_max_mps
            .map(|v| (spread + 2.0 * v * duration_s) * 1.01 + 1e-9);
        let n = team.starts.len() as f64;
        let isoline_length_m = match s.team_isoline().as_team_isoline() {
            Some(isotrack_sim::team::TeamIsoline::Fixed(a)) if a.is_closed() => Some(a.length_m()),
            _ => None,
        };
        let ideal_s = isoline_length_m.map(|l| l / (n * team.ideal_speed_mps()));
        let fixed_wing =
            s.file().vehicle.kind == Some(isotrack_scenario::schema::VehicleKind::FixedWing);
        Some(TeamBounds {
            duration_s,
            reach_m,
            ideal_s,
            count: team.count(),
            speed_envelope_mps: (!fixed_wing).then(|| team.speed_envelope_mps()),
            isoline_length_m,
            window_start_s: span
                .metric_steps
                .map(|ms| ms.steady_state_start_step as f64 * span.dt_s),
        })
    }
}

/// The team cells of a team run's row bounded by its scenario ([`TeamBounds`]): the times
/// (`time_to_even_s`, `revisit_time_max_s`, `revisit_time_mean_s`) within the run's duration and
/// the mean revisit at most the longest (to rounding); `min_separation_m` within the vehicles'
/// reach; `gap_cv` at most [`max_gap_cv`] of the team's count; `revisit_time_ideal_s` exactly
/// the recomputed `L / (N v0)` (bit for bit: the run computes it the same way), where the
/// isoline is fixed. Each error names its column.
pub fn check_team_bounds<'c>(
    cell: &dyn Fn(&str) -> &'c str,
    b: &TeamBounds,
    column: &dyn Fn(&str) -> String,
) -> Result<(), String> {
    let value = |n: &str| cell(n).parse::<f64>().ok();
    for n in [
        "time_to_even_s",
        "revisit_time_max_s",
        "revisit_time_mean_s",
    ] {
        if let Some(t) = value(n) {
            if t > b.duration_s * (1.0 + 1e-12) {
                return Err(format!(
                    "{}: {n} = {} s is past the run's duration, {} s",
                    column(n),
                    Echo(t),
                    Num(b.duration_s)
                ));
            }
        }
    }
    if let (Some(mean), Some(max)) = (value("revisit_time_mean_s"), value("revisit_time_max_s")) {
        if mean > max * (1.0 + 1e-12) {
            return Err(format!(
                "{}: revisit_time_mean_s = {} s exceeds revisit_time_max_s = {} s (a mean interval is at most the longest)",
                column("revisit_time_mean_s"),
                Echo(mean),
                Echo(max)
            ));
        }
    }
    if let Some(cv) = value("gap_cv") {
        check_gap_cv("gap_cv", cv, b.count).map_err(|m| format!("{}: {m}", column("gap_cv")))?;
    }
    // att49-4: `time_to_even_s = t` has every sample from `t` to the end evenly spread (each
    // sample above the threshold or without a CV resets it): from at or before the window's
    // start, every window sample's CV is at most the threshold, and so is their mean (to
    // rounding).
    let even = isotrack_sim::team::metrics::TeamMetricsConfig::default().even_gap_cv;
    if let (Some(t), Some(cv), Some(start)) =
        (value("time_to_even_s"), value("gap_cv"), b.window_start_s)
    {
        if t <= start && cv > even * (1.0 + 1e-12) {
            return Err(format!(
                "{}: gap_cv = {} where time_to_even_s = {} s is at or before the steady-state window's start ({} s): every sample of the window has a gap CV at most {}, and so has their mean",
                column("gap_cv"),
                Echo(cv),
                Echo(t),
                Num(start),
                Echo(even)
            ));
        }
    }
    if let (Some(sep), Some(reach)) = (value("min_separation_m"), b.reach_m) {
        if sep > reach {
            return Err(format!(
                "{}: min_separation_m = {} m exceeds {} m, the farthest two vehicles can be apart (their starts' spread plus twice the top speed over the run)",
                column("min_separation_m"),
                Echo(sep),
                Num(reach)
            ));
        }
    }
    if let (Some(got), Some(want)) = (value("revisit_time_ideal_s"), b.ideal_s) {
        if got != want {
            return Err(format!(
                "{}: revisit_time_ideal_s = {} s is not the run's L/(N v0) = {} s",
                column("revisit_time_ideal_s"),
                Echo(got),
                Echo(want)
            ));
        }
    }
    Ok(())
}

/// A team run's metrics as `summary.json` and a benchmark's `task.json` record them, checked
/// as a sweep row's team cells are (the same cells, [`crate::sweep::rows::team_record_cells`]:
/// their form, then [`check_team_bounds`]).
pub fn check_team_record(
    m: &crate::summary::TeamRecord,
    b: Option<&TeamBounds>,
) -> Result<(), String> {
    let cells = crate::sweep::rows::team_record_cells(Some(m));
    let names = crate::sweep::rows::TEAM_COLUMNS;
    let cell = |n: &str| {
        names
            .iter()
            .position(|c| *c == n)
            .and_then(|i| cells.get(i))
            .map_or("", |c| c.as_str())
    };
    check_team_cells("completed", &cell)?;
    check_team_record_numbers(m, b)?;
    match b {
        Some(b) => check_team_bounds(&cell, b, &|n| n.to_string()),
        None => Ok(()),
    }
}

/// A gap CV (`gap_cv` or `gap_cv_final`) of a team of `n` vehicles at least 0 (a standard
/// deviation over a positive mean gap, L/N) and at most [`max_gap_cv`] (to rounding: the bound
/// is reached exactly with every vehicle at one point).
fn check_gap_cv(key: &str, cv: f64, n: usize) -> Result<(), String> {
    check_cv_not_negative(key, cv)?;
    let most = max_gap_cv(n);
    if cv > most * (1.0 + 1e-9) + 1e-12 {
        return Err(format!(
            "{key} = {} exceeds sqrt(N - 1) = {} for N = {n} vehicles, the largest coefficient of variation of their gaps (all of the isoline in one gap)",
            Echo(cv),
            Num(most)
        ));
    }
    Ok(())
}

/// A gap CV is at least 0: a standard deviation over the gaps' positive mean, L/N (att49-4).
fn check_cv_not_negative(key: &str, cv: f64) -> Result<(), String> {
    if cv < 0.0 {
        return Err(format!(
            "{key} = {} is negative: a coefficient of variation of the gaps is a standard deviation over their positive mean",
            Echo(cv)
        ));
    }
    Ok(())
}

/// The team record's numbers that no sweep row holds, as the team metrics
/// (`isotrack_sim::team::metrics::TeamMetrics::finish`) give them (att46-4: each edited into a
/// genuine run's summary was shown as the run's):
/// * `time_to_even_s` is the first sample of the last run of samples with a gap CV at or
///   below the even threshold (0.05) that lasts to the end: every sample without one resets
///   it, so with it the last sample's CV, `gap_cv_final`, is there and at most the threshold;
/// * `speed_range_mps` is the slowest and the fastest speed a vehicle held at a sample:
///   `min <= max`, both within the team's envelope where it bounds the speed held
///   ([`TeamBounds::speed_envelope_mps`]);
/// * conversely a `gap_cv_final` at most the threshold sets `time_to_even_s` (att49-4);
/// * `isoline_length_m` and every speed of `speed_range_mps` at least 0 (att49-4);
/// * `gap_cv_final` at most [`max_gap_cv`] of the team's count;
/// * `isoline_length_m` the fixed closed isoline's length ([`TeamBounds::isoline_length_m`]).
fn check_team_record_numbers(
    m: &crate::summary::TeamRecord,
    b: Option<&TeamBounds>,
) -> Result<(), String> {
    if let Some(cv) = m.gap_cv_final {
        check_cv_not_negative("gap_cv_final", cv)?;
    }
    check_time_to_even(m)?;
    // A length and a ground speed (a magnitude; a robot's speed command is saturated to its
    // positive envelope) are at least 0, whatever the isoline or airframe.
    if let Some(l) = m.isoline_length_m.filter(|&l| l < 0.0) {
        return Err(format!(
            "isoline_length_m = {} m is negative: a length is at least 0",
            Echo(l)
        ));
    }
    check_speed_range(m.speed_range_mps, b)?;
    let Some(b) = b else { return Ok(()) };
    if let Some(cv) = m.gap_cv_final {
        check_gap_cv("gap_cv_final", cv, b.count)?;
    }
    if let (Some(got), Some(want)) = (m.isoline_length_m, b.isoline_length_m) {
        if (got - want).abs() > want.abs() * 1e-9 {
            return Err(format!(
                "isoline_length_m = {} m is not the length of the run's isoline, {} m",
                Echo(got),
                Echo(want)
            ));
        }
    }
    Ok(())
}

/// `time_to_even_s` and `gap_cv_final` of team record `m` agree: an even spread that lasts to
/// the end (a gap CV at or below the team metrics' even threshold) has a final gap CV at most the threshold,
/// and a final CV at most the threshold starts one (att49-4).
fn check_time_to_even(m: &crate::summary::TeamRecord) -> Result<(), String> {
    let even = isotrack_sim::team::metrics::TeamMetricsConfig::default().even_gap_cv;
    if let Some(t) = m.time_to_even_s {
        if !m.gap_cv_final.is_some_and(|cv| cv <= even) {
            let last = m
                .gap_cv_final
                .map_or("null".to_string(), |cv| Echo(cv).to_string());
            return Err(format!(
                "time_to_even_s = {} s where gap_cv_final = {last}: a team evenly spread from then to the end has a final gap CV at most {}",
                Echo(t),
                Echo(even)
            ));
        }
    }
    // att49-4: a final CV at most the threshold starts an even spread at the last sample at the
    // latest (`even_since` is set by every such sample), so `time_to_even_s` is there.
    if let (None, Some(cv)) = (m.time_to_even_s, m.gap_cv_final.filter(|&cv| cv <= even)) {
        return Err(format!(
            "time_to_even_s = null where gap_cv_final = {}: a team whose last sample's gap CV is at most {} is evenly spread from that sample on at the latest",
            Echo(cv),
            Echo(even)
        ));
    }
    Ok(())
}

/// A team record's `speed_range_mps`, `range`: every speed at least 0, the slowest at most the
/// fastest, both within the team's speed envelope where bounds `b` give one.
fn check_speed_range(
    range: Option<[Option<f64>; 2]>,
    b: Option<&TeamBounds>,
) -> Result<(), String> {
    if let Some(v) = range.into_iter().flatten().flatten().find(|&v| v < 0.0) {
        return Err(format!(
            "speed_range_mps holds {} m/s: a vehicle's speed is at least 0",
            Echo(v)
        ));
    }
    if let Some([Some(lo), Some(hi)]) = range {
        if lo > hi {
            return Err(format!(
                "speed_range_mps = [{}, {}]: its slowest speed exceeds its fastest",
                Echo(lo),
                Echo(hi)
            ));
        }
        if let Some((v_min, v_max)) = b.and_then(|b| b.speed_envelope_mps) {
            if lo < v_min * (1.0 - 1e-12) || hi > v_max * (1.0 + 1e-12) {
                return Err(format!(
                    "speed_range_mps = [{}, {}] m/s leaves the team's speed envelope [{}, {}] m/s (every speed command is saturated to it)",
                    Echo(lo),
                    Echo(hi),
                    Echo(v_min),
                    Echo(v_max)
                ));
            }
        }
    }
    Ok(())
}

/// A simulated run's `summary.json` checked as a sweep's row is (att43-15: `report` showed an
/// edited summary's impossible numbers, a negative `max |eps|`, a convergence time past the
/// run's end, as the run's): the record's metrics by [`check_metrics`] (every number finite
/// and of its sign, an RMS at most its maximum, the convergence time at most `t_end_s`, ...)
/// and, for a completed run, by the tolerance's implications over the run's steady-state
/// window ([`check_tolerance_implications`], the window and tolerance of `scenario`'s own
/// step plan: a convergence at or before the window's start puts its maximum under the
/// tolerance), each vehicle's of a team's run too, and a team's metrics by
/// [`check_team_record`] within the bounds of `scenario`'s team ([`TeamBounds`]). A flight's summary and a cut `sitl` run's
/// (`interrupted`, `companion_lost`: no row of a sweep) are not checked here. The error names
/// the key (`vehicles[2].convergence_time_s`, `team: ...`).
pub fn check_run_summary(
    summary: &crate::summary::Summary,
    scenario: &isotrack_scenario::Scenario,
) -> Result<(), String> {
    let crate::summary::Ended::Run(end) = &summary.ended else {
        return Ok(());
    };
    let metric_steps =
        run_span(scenario.file()).and_then(|s| s.metric_steps.map(|ms| (ms, s.dt_s)));
    let check = |r: &crate::results::RunRecord, key: &str| -> Result<(), String> {
        if !OUTCOMES.contains(&r.outcome.as_str()) || r.outcome == "invalid_scenario" {
            return Ok(());
        }
        let columns = &crate::sweep::rows::SWEEP_COLUMNS;
        let cells = crate::results::result_cells(columns, Ok(r));
        // Not a sweep column, but the record's (att49-5: an edited share went unchecked).
        let share = crate::results::real_cell(r.metrics.time_in_band_fraction);
        let cell = |n: &str| {
            if n == "time_in_band_fraction" {
                return share.as_str();
            }
            columns
                .iter()
                .position(|c| c.name() == n)
                .and_then(|i| cells.get(i))
                .map_or("", |c| c.as_str())
        };
        check_metrics(&r.outcome, &cell, true).map_err(|m| format!("{key}{m}"))?;
        // The convergence time, the steady-state window's numbers and the tolerance tie
        // together as in a sweep's row (att46-4: a convergence time of 1 s beside a
        // steady-state maximum of 50 past a tolerance of 0.1 was shown as the run's).
        match metric_steps {
            Some((ms, dt)) if r.outcome == "completed" => {
                let name = |n: &str| n.to_string();
                check_tolerance_implications(&ms, dt, &cell, &name)
                    .and_then(|_| match r.t_end_s.map(|t| (t / dt).round()) {
                        Some(k) if k >= 0.0 => {
                            check_converged_window(&ms, dt, k as u64, &cell, &name)
                        }
                        _ => Ok(()),
                    })
                    .map_err(|m| format!("{key}{m}"))
            }
            _ => Ok(()),
        }
    };
    check(&end.record, "")?;
    for (i, v) in end.vehicles.iter().flatten().enumerate() {
        check(v, &format!("vehicles[{i}]: "))?;
    }
    if let Some(m) = end.team.as_ref().and_then(|t| t.metrics.as_ref()) {
        check_team_record(m, TeamBounds::of(scenario).as_ref())
            .map_err(|m| format!("team: {m}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod team_record_tests {
    use super::{check_team_record, check_team_record_numbers, max_gap_cv, TeamBounds};
    use crate::summary::TeamRecord;

    /// The population CV of `gaps`, computed here from its definition.
    fn population_cv(gaps: &[f64]) -> f64 {
        let n = gaps.len() as f64;
        let mean = gaps.iter().sum::<f64>() / n;
        let var = gaps.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / n;
        var.sqrt() / mean
    }

    /// att46-4: the largest gap CV of N vehicles is reached with every vehicle at one point
    /// (one gap the whole loop): sqrt(N - 1) (4 vehicles: sqrt(3)); any other spread is below.
    #[test]
    fn the_gap_cv_bound_is_the_all_in_one_gap_spread() {
        for n in 2..9usize {
            let mut gaps = vec![0.0; n];
            gaps[0] = 43.55;
            let cv = population_cv(&gaps);
            assert!((cv - max_gap_cv(n)).abs() < 1e-12, "n = {n}: {cv}");
            let spread: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
            assert!(population_cv(&spread) < max_gap_cv(n));
        }
        assert_eq!(max_gap_cv(4), 3f64.sqrt());
        assert_eq!(max_gap_cv(1), 0.0);
    }

    fn record() -> TeamRecord {
        TeamRecord {
            count: 4,
            isoline_length_m: Some(43.55),
            gap_cv: Some(0.01),
            gap_cv_final: Some(0.01),
            time_to_even_s: Some(0.0),
            revisit_time_max_s: None,
            revisit_time_mean_s: None,
            revisit_time_ideal_s: None,
            revisit_time_ideal_active_s: None,
            min_separation_m: None,
            order_preserved: true,
            speed_range_mps: Some([Some(0.25), Some(0.75)]),
            moving_isoline: None,
            open_isoline: None,
        }
    }

    const BOUNDS: TeamBounds = TeamBounds {
        duration_s: 100.0,
        reach_m: None,
        ideal_s: None,
        count: 4,
        speed_envelope_mps: Some((0.25, 0.75)),
        isoline_length_m: Some(43.55),
        window_start_s: Some(50.0),
    };

    /// att49-4: the rules that held one way only hold both ways: a `time_to_even_s` at or
    /// before the window's start (50 s) with a window-mean `gap_cv` above 0.05, a null
    /// `time_to_even_s` beside a final CV at most 0.05, a negative isoline length or speed are
    /// refused naming the key; the edges a run can give are kept (an even spread from after
    /// the window's start beside any mean; a mean of exactly 0.05; a final CV above 0.05 with
    /// no time; a speed of 0; any of these without bounds where none is needed).
    #[test]
    fn team_rules_hold_both_ways() {
        let refused = |edit: fn(&mut TeamRecord), needle: &str| {
            let mut r = record();
            edit(&mut r);
            let e = check_team_record(&r, Some(&BOUNDS)).unwrap_err();
            assert!(e.contains(needle), "{e}");
        };
        refused(
            |r| (r.time_to_even_s, r.gap_cv) = (Some(1.0), Some(1.5)),
            "gap_cv = 1.5 where time_to_even_s = 1 s is at or before",
        );
        refused(
            |r| (r.time_to_even_s, r.gap_cv) = (Some(50.0), Some(0.0500001)),
            "gap_cv = 0.0500001 where time_to_even_s = 50 s",
        );
        refused(
            |r| (r.time_to_even_s, r.gap_cv_final) = (None, Some(0.0)),
            "time_to_even_s = null where gap_cv_final = 0",
        );
        refused(
            |r| (r.time_to_even_s, r.gap_cv_final) = (None, Some(0.05)),
            "time_to_even_s = null where gap_cv_final = 0.05",
        );
        refused(
            |r| r.isoline_length_m = Some(-5.0),
            "isoline_length_m = -5 m is negative",
        );
        refused(
            |r| r.speed_range_mps = Some([Some(-50.0), Some(1e9)]),
            "speed_range_mps holds -50 m/s",
        );
        let kept = |edit: fn(&mut TeamRecord)| {
            let mut r = record();
            edit(&mut r);
            assert_eq!(check_team_record(&r, Some(&BOUNDS)), Ok(()));
        };
        kept(|r| (r.time_to_even_s, r.gap_cv) = (Some(50.5), Some(1.5)));
        kept(|r| (r.time_to_even_s, r.gap_cv) = (Some(10.0), Some(0.05)));
        kept(|r| (r.time_to_even_s, r.gap_cv_final) = (None, Some(0.0500001)));
        kept(|r| (r.time_to_even_s, r.gap_cv_final) = (None, None));
        kept(|r| r.speed_range_mps = Some([Some(0.25), Some(0.25)]));
        // Without a window in the plan the mean is not tied to the time.
        let mut r = record();
        (r.time_to_even_s, r.gap_cv) = (Some(1.0), Some(1.5));
        let no_window = TeamBounds {
            window_start_s: None,
            ..BOUNDS
        };
        assert_eq!(check_team_record(&r, Some(&no_window)), Ok(()));
        // Signs and the null time need no bounds (an open or moving isoline, a fixed wing).
        let mut r = record();
        r.isoline_length_m = Some(-5.0);
        assert!(check_team_record_numbers(&r, None).is_err());
        let mut r = record();
        r.speed_range_mps = Some([Some(-1.0), Some(1.0)]);
        assert!(check_team_record_numbers(&r, None).is_err());
    }

    /// att46-4: each number edited to one the metrics cannot give is refused naming its key;
    /// the record as a run gives it (its bounds reached exactly) is kept.
    #[test]
    fn impossible_team_numbers_are_refused() {
        assert_eq!(check_team_record_numbers(&record(), Some(&BOUNDS)), Ok(()));
        let mut at_bounds = record();
        at_bounds.time_to_even_s = None;
        at_bounds.gap_cv_final = Some(3f64.sqrt());
        assert_eq!(check_team_record_numbers(&at_bounds, Some(&BOUNDS)), Ok(()));
        // att49-4 addendum: a CV is never negative (std >= 0 over a mean L/N > 0).
        let mut negative = record();
        negative.time_to_even_s = None;
        negative.gap_cv_final = Some(-0.5);
        let refused = check_team_record_numbers(&negative, Some(&BOUNDS)).unwrap_err();
        assert!(
            refused.contains("gap_cv_final = -0.5 is negative"),
            "{refused}"
        );
        type Edit = fn(&mut TeamRecord);
        let cases: [(Edit, &str); 6] = [
            (
                |r| (r.time_to_even_s, r.gap_cv_final) = (None, Some(1.8)),
                "gap_cv_final = 1.8 exceeds",
            ),
            (
                |r| r.gap_cv_final = Some(0.06),
                "time_to_even_s = 0 s where gap_cv_final = 0.06",
            ),
            (
                |r| r.gap_cv_final = None,
                "time_to_even_s = 0 s where gap_cv_final = null",
            ),
            (
                |r| r.speed_range_mps = Some([Some(0.5), Some(0.4)]),
                "slowest speed exceeds",
            ),
            (
                |r| r.speed_range_mps = Some([Some(0.25), Some(0.76)]),
                "speed envelope",
            ),
            (|r| r.isoline_length_m = Some(1.0), "isoline_length_m = 1 m"),
        ];
        for (edit, needle) in cases {
            let mut r = record();
            edit(&mut r);
            let e = check_team_record_numbers(&r, Some(&BOUNDS)).unwrap_err();
            assert!(e.contains(needle), "{e}");
        }
        // A fixed wing's ground speed is not bounded by its airspeed envelope.
        let mut r = record();
        r.speed_range_mps = Some([Some(0.1), Some(30.0)]);
        let wing = TeamBounds {
            speed_envelope_mps: None,
            ..BOUNDS
        };
        assert_eq!(check_team_record_numbers(&r, Some(&wing)), Ok(()));
    }
}
