//! The check of a stored `results.csv` row: `--resume` and `merge` trust a row only after it.

use crate::sweep::rows::numeric_columns;
use isotrack_scenario::sweep::SweepPlan;

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
/// columns of run `id` are recomputed from the plan and must match).
pub struct RowRules<'a> {
    /// The sweep's `results.csv` header.
    pub header: &'a [String],
    /// The sweep's run count.
    pub total: u64,
    /// The sweep's plan.
    pub plan: &'a SweepPlan,
}

/// Checks one stored row against the sweep: its field count, its `run_id` within the plan, the
/// plan's columns recomputed from the run id, a known outcome and metric values isotrack can
/// have written ([`check_metrics`]). Rows are trusted on `--resume` and `merge` only after
/// this.
pub fn check_row(rules: &RowRules<'_>, line: &str) -> Result<u64, String> {
    let header = rules.header;
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .from_reader(line.as_bytes());
    let rec = r
        .records()
        .next()
        .and_then(Result::ok)
        .ok_or("not a CSV row")?;
    if rec.len() != header.len() {
        return Err(format!(
            "{} fields where the header has {}",
            rec.len(),
            header.len()
        ));
    }
    let id: u64 = rec[0]
        .parse()
        .map_err(|_| format!("run_id `{}` is not a run number", clip(&rec[0])))?;
    if id >= rules.total {
        return Err(format!(
            "run_id {id} is beyond this sweep's {} runs",
            rules.total
        ));
    }
    for ((name, cell), want) in header[1..]
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
    check_metrics(outcome, &cell)?;
    Ok(id)
}

/// The metric cells of one row are what isotrack writes: an `invalid_scenario` row has none; a
/// `completed` row no `outcome_detail`; a run's row has `t_end_s` and `samples`; every number
/// is finite (non-finite metrics are written empty) and not subnormal, the quantities that
/// cannot be negative are not (nor `-0.0`), an RMS is at most its
/// maximum and `|mean|` at most the maximum (to rounding), the convergence time at most the run's
/// end, and `samples` a whole number of at most one per step ([`isotrack_sim::MAX_STEPS`] + 1).
fn check_metrics<'c>(outcome: &str, cell: &dyn Fn(&str) -> &'c str) -> Result<(), String> {
    let numeric = numeric_columns();
    if outcome == "invalid_scenario" {
        if let Some(n) = numeric.iter().find(|n| !cell(n).is_empty()) {
            return Err(format!("{n} holds a value in an invalid_scenario row"));
        }
        return Ok(());
    }
    // The detail says why a run did not complete: a completed row has none.
    if outcome == "completed" && !cell("outcome_detail").is_empty() {
        return Err("outcome_detail holds text in a `completed` row".to_string());
    }
    for n in ["t_end_s", "samples"] {
        if cell(n).is_empty() {
            return Err(format!("{n} is empty in a `{outcome}` row"));
        }
    }
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
        // A subnormal (below 2.2e-308, `5e-324`) is no value a run produces: times are
        // multiples of a step far above it, and sums of squares of it vanish.
        if v != 0.0 && !v.is_normal() {
            return Err(format!(
                "{n} = `{c}` is subnormal (below {:e}): not a value a run produces",
                f64::MIN_POSITIVE
            ));
        }
        value.insert(n, v);
    }
    let samples = cell("samples");
    match samples.parse::<u64>() {
        Ok(k) if k <= isotrack_sim::MAX_STEPS + 1 => {}
        _ => {
            return Err(format!(
                "samples = `{}` is not a whole number of samples (at most {})",
                clip(samples),
                isotrack_sim::MAX_STEPS + 1
            ))
        }
    }
    // Rounding: an RMS of equal values may exceed their maximum by an ulp or so.
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

/// User text from a damaged file, clipped for a message.
pub fn clip(text: &str) -> String {
    isotrack_scenario::load::clip(text)
}
