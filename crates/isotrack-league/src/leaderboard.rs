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
    use isotrack_runs::results::real_cell;
    let mut s = RESULTS_COLUMNS.join(",") + "\n";
    for r in runs {
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
        s += &isotrack_runs::sweep::rows::csv_line(&cells);
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

/// Writes `leaderboard.csv`, `leaderboard.md` and each task's `results.csv` and `task.json`
/// under `dir`.
pub fn write_files(r: &BenchResult, dir: &Path) -> Result<(), BenchError> {
    let io = |p: &Path, e: std::io::Error| BenchError::Io {
        path: p.display().to_string(),
        message: e.to_string(),
    };
    let write = |p: &Path, text: &str| -> Result<(), BenchError> {
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
        }
        isotrack_runs::files::write_atomic(p, text.as_bytes()).map_err(|e| io(p, e))
    };
    write(&dir.join("leaderboard.csv"), &leaderboard_csv(r))?;
    write(&dir.join("leaderboard.md"), &leaderboard_md(r))?;
    for t in &r.tasks {
        write_task(t, dir)?;
    }
    Ok(())
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
    if let Some(parent) = json.parent() {
        std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
    }
    let csv = json.with_file_name("results.csv");
    // Never through a link nor into a FIFO: `isotrack_runs::files::write_atomic`.
    isotrack_runs::files::write_atomic(&csv, results_csv(&t.runs).as_bytes())
        .map_err(|e| io(&csv, e))?;
    isotrack_runs::files::write_atomic(
        &json,
        serde_json::to_string(t).unwrap_or_default().as_bytes(),
    )
    .map_err(|e| io(&json, e))
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
