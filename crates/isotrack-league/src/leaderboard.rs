//! The benchmark's files: `leaderboard.csv`, `leaderboard.md`, and per task `tasks/ID/results.csv`
//! (every scored run) and `tasks/ID/task.json` (what `--resume` reuses and the HTML page draws).

use crate::results::{task_file, BenchError, BenchResult, RunRow, TaskResult};
use std::fmt::Write as _;
use std::path::Path;

/// The columns of `leaderboard.csv`: `rank, controller, overall`, then one per task id.
pub fn leaderboard_csv(r: &BenchResult) -> String {
    let mut s = String::from("rank,controller,overall");
    for t in &r.tasks {
        s.push(',');
        s.push_str(&t.id);
    }
    s.push('\n');
    for (rank, (c, overall)) in r.overall.iter().enumerate() {
        let _ = write!(s, "{},{},{:.2}", rank + 1, csv_cell(c), overall);
        for t in &r.tasks {
            let v = t.scores.iter().find(|(n, _)| n == c).map_or(0.0, |x| x.1);
            let _ = write!(s, ",{v:.2}");
        }
        s.push('\n');
    }
    s
}

/// Text as one Markdown table cell, shown as written: `|` escaped (`\|`, it would end the
/// cell), `<` and `&` as HTML entities (`<!--` would hide the rest of the table in a renderer,
/// `<script>` run), a line break or any other control character as a space (it would end the
/// row). Every Markdown table isotrack writes puts its text through this one function.
pub fn md_cell(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '|' => s.push_str("\\|"),
            '<' => s.push_str("&lt;"),
            '&' => s.push_str("&amp;"),
            c if c.is_control() => s.push(' '),
            c => s.push(c),
        }
    }
    s
}

/// The leaderboard as a Markdown table (ranked), and a table of the tasks.
pub fn leaderboard_md(r: &BenchResult) -> String {
    let mut s = format!(
        "| rank | controller | overall |{}\n|---|---|---|{}\n",
        r.tasks
            .iter()
            .map(|t| format!(" {} |", md_cell(&t.id)))
            .collect::<String>(),
        "---|".repeat(r.tasks.len())
    );
    for (rank, (c, overall)) in r.overall.iter().enumerate() {
        let _ = write!(s, "| {} | {} | **{:.1}** |", rank + 1, md_cell(c), overall);
        for t in &r.tasks {
            let v = t.scores.iter().find(|(n, _)| n == c).map_or(0.0, |x| x.1);
            let _ = write!(s, " {v:.1} |");
        }
        s.push('\n');
    }
    s.push_str("\n| task | what |\n|---|---|\n");
    for t in &r.tasks {
        let _ = writeln!(s, "| {} | {} |", md_cell(&t.id), md_cell(&t.title));
    }
    s
}

/// The columns of a task's `results.csv`.
pub const RESULTS_COLUMNS: [&str; 15] = [
    "controller",
    "seed",
    "outcome",
    "score",
    "capture",
    "band",
    "distance",
    "losses",
    "effort",
    "convergence_time_s",
    "time_in_band_fraction",
    "steady_state_rms_isoline_distance_m",
    "track_losses",
    "control_effort",
    "steady_state_rms_error",
];

/// A task's `results.csv`: one row per scored run, its cells as every results file writes them
/// (`isotrack-runs`: numbers in the shortest round-trip form, empty where undefined or not
/// finite; CSV quoting where a cell needs it).
pub fn results_csv(runs: &[RunRow]) -> String {
    let mut s = RESULTS_COLUMNS.join(",") + "\n";
    for r in runs {
        s += &isotrack_runs::sweep::rows::csv_line(&run_cells(r));
    }
    s
}

/// The [`RESULTS_COLUMNS`] cells of one scored run.
fn run_cells(r: &RunRow) -> Vec<String> {
    use isotrack_runs::results::real_cell;
    let p = r.score.parts;
    let mut cells = vec![r.controller.clone(), r.seed.to_string(), r.outcome.clone()];
    cells.extend([r.score.total, p[0], p[1], p[2], p[3], p[4]].map(|x| real_cell(Some(x))));
    cells.extend([
        real_cell(r.convergence_time_s),
        real_cell(r.time_in_band_fraction),
        real_cell(r.steady_state_rms_isoline_distance_m),
        r.track_losses.to_string(),
        real_cell(Some(r.control_effort)),
        real_cell(r.steady_state_rms_error),
    ]);
    cells
}

/// The columns a team task's `results.csv` adds after [`RESULTS_COLUMNS`] (then
/// `isotrack_runs::sweep::rows::TEAM_COLUMNS`, the team metrics): the team's size, how many of
/// its vehicles completed, and the team parts of the score (docs/BENCHMARK.md, "Team score":
/// `score = 100 * (0.50 tracking + 0.25 spacing + 0.25 revisit)`; `spacing` and `revisit` are
/// the scaled ones, as `distance`, `losses` and `effort` are).
pub const TEAM_SCORE_COLUMNS: [&str; 6] = [
    "vehicles",
    "vehicles_completed",
    "tracking",
    "held",
    "spacing",
    "revisit",
];

/// A task's `results.csv`: [`results_csv`], and for a team task the team columns
/// ([`TEAM_SCORE_COLUMNS`], then `isotrack_runs::sweep::rows::TEAM_COLUMNS`) after each row's
/// cells (empty for an invalid run).
pub fn task_results_csv(t: &TaskResult) -> String {
    if !t.team {
        return results_csv(&t.runs);
    }
    use isotrack_runs::results::real_cell;
    use isotrack_runs::sweep::rows::{csv_line, team_record_cells, TEAM_COLUMNS};
    let mut header: Vec<String> = RESULTS_COLUMNS.iter().map(|c| c.to_string()).collect();
    header.extend(TEAM_SCORE_COLUMNS.iter().map(|c| c.to_string()));
    header.extend(TEAM_COLUMNS.iter().map(|c| c.to_string()));
    let mut s = header.join(",") + "\n";
    for r in &t.runs {
        let mut cells = run_cells(r);
        match &r.team {
            Some(tm) => {
                cells.extend([tm.vehicles.to_string(), tm.vehicles_completed.to_string()]);
                let p = tm.parts;
                cells
                    .extend([p.tracking, p.held, p.spacing, p.revisit].map(|x| real_cell(Some(x))));
                cells.extend(team_record_cells(tm.metrics.as_ref()));
            }
            None => cells.extend(vec![
                String::new();
                TEAM_SCORE_COLUMNS.len() + TEAM_COLUMNS.len()
            ]),
        }
        s += &csv_line(&cells);
    }
    s
}

fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Writes each task's `results.csv` and `task.json` under `dir`, then the top-level files:
/// `leaderboard.csv`, `leaderboard.md` and `more` (each a name and its text: `benchmark`'s
/// `index.html` and `suite.toml`), put in place together as one step an interrupt never cuts
/// ([`isotrack_runs::cleanup::whole`]): an interrupted benchmark leaves the earlier set whole
/// or this one (att53o-9: Ctrl-C while they were written left this run's leaderboard beside
/// the earlier run's `index.html` and `suite.toml`). The texts are made before the step, so it
/// holds the writes only.
pub fn write_files(r: &BenchResult, dir: &Path, more: &[(&str, String)]) -> Result<(), BenchError> {
    let io = |p: &Path, e: std::io::Error| BenchError::Io {
        path: p.display().to_string(),
        message: e.to_string(),
    };
    for t in &r.tasks {
        write_task(t, dir)?;
    }
    let board = [
        ("leaderboard.csv", leaderboard_csv(r)),
        ("leaderboard.md", leaderboard_md(r)),
    ];
    let top: Vec<(std::path::PathBuf, &str)> = board
        .iter()
        .chain(more)
        .map(|(n, t)| (dir.join(n), t.as_str()))
        .collect();
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    isotrack_runs::cleanup::whole(|| {
        for (p, text) in &top {
            // Never through a link nor into a FIFO: `isotrack_runs::files::write_atomic`.
            isotrack_runs::files::write_atomic(p, text.as_bytes()).map_err(|e| io(p, e))?;
        }
        Ok(())
    })
}

/// Writes one finished task's `tasks/ID/results.csv` and `tasks/ID/task.json` under `dir`
/// (`task.json` last: it is what `--resume` reuses), as the task finishes, so an interrupted
/// benchmark keeps its finished tasks.
pub fn write_task(t: &TaskResult, dir: &Path) -> Result<(), BenchError> {
    let io = |p: &Path, e: std::io::Error| BenchError::Io {
        path: p.display().to_string(),
        message: e.to_string(),
    };
    let json = task_file(dir, &t.id);
    let csv = json.with_file_name("results.csv");
    let (csv_text, json_text) = (
        task_results_csv(t),
        serde_json::to_string(t).unwrap_or_default(),
    );
    // The task's directory (`tasks/ID`, and `tasks`) removed again while empty if the command is
    // interrupted, and its two files written in one step an interrupt never cuts: Ctrl-C leaves
    // the task whole or no trace of it (att51-4: the empty `tasks/ID` chain was left).
    isotrack_runs::cleanup::whole(|| {
        let _created = match json.parent() {
            Some(parent) => {
                isotrack_runs::cleanup::create_dir_all(parent).map_err(|e| io(parent, e))?
            }
            None => vec![],
        };
        // Never through a link nor into a FIFO: `isotrack_runs::files::write_atomic`.
        isotrack_runs::files::write_atomic(&csv, csv_text.as_bytes()).map_err(|e| io(&csv, e))?;
        isotrack_runs::files::write_atomic(&json, json_text.as_bytes()).map_err(|e| io(&json, e))
    })
}

#[cfg(test)]
mod tests {
    use super::md_cell;

    /// Each character that would break a Markdown table cell or inject HTML, escaped; the rest
    /// as written.
    #[test]
    fn markdown_cells_are_escaped() {
        assert_eq!(md_cell("a|b"), "a\\|b");
        assert_eq!(md_cell("<!--<script>"), "&lt;!--&lt;script>");
        assert_eq!(md_cell("two\nlines\r\t"), "two lines  ");
        assert_eq!(md_cell("R&D"), "R&amp;D");
        assert_eq!(md_cell("circular field, 10 Hz"), "circular field, 10 Hz");
    }
}
