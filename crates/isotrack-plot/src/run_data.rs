//! Reading a run directory.

use crate::PlotError;
use isotrack_runs::trace::TRACE_COLUMNS;
use isotrack_scenario::{load_scenario, Scenario};
use isotrack_sim::TraceRow;
use std::path::{Path, PathBuf};

/// A finished run, as written by `isotrack run --out DIR` (or one directory of `compare`).
#[derive(Clone, Debug)]
pub struct RunData {
    /// Label for legends (the directory name).
    pub name: String,
    /// The directory.
    pub dir: PathBuf,
    /// The trace.
    pub trace: Vec<TraceRow>,
    /// `summary.json`.
    pub summary: serde_json::Value,
    /// The resolved scenario (its field rebuilt for the map).
    pub scenario: Scenario,
}

impl RunData {
    /// Loads `DIR/trace.csv`, `DIR/summary.json` and `DIR/scenario.toml`.
    pub fn load(dir: &Path) -> Result<Self, PlotError> {
        let err = |m: String| PlotError::Data(format!("{}: {m}", dir.display()));
        let cannot = |m: String| PlotError::Input(format!("{}: {m}", dir.display()));
        let summary: serde_json::Value = serde_json::from_str(
            &isotrack_fields::io::read_text_limited(&dir.join("summary.json"), 16 << 20)
                .map_err(|e| cannot(format!("summary.json: {e} (is this a run directory?)")))?,
        )
        .map_err(|e| err(format!("summary.json: {e}")))?;
        let scenario = load_scenario(Some(&dir.join("scenario.toml")), &[]).map_err(|e| {
            let m = format!("scenario.toml: {e}");
            if e.is_unreadable_input() {
                cannot(m)
            } else {
                err(m)
            }
        })?;
        let mut rdr = csv::Reader::from_reader(crate::open_input(&dir.join("trace.csv"))?);
        let headers = rdr
            .headers()
            .map_err(|e| err(format!("trace.csv: {e}")))?
            .clone();
        let col = |n: &str| {
            headers
                .iter()
                .position(|h| h == n)
                .ok_or_else(|| err(format!("trace.csv has no column `{n}`")))
        };
        // The numeric columns every trace has (TRACE_COLUMNS: `t_s` ... `omega_radps`), then the
        // optional `s_measured` (empty before the first measurement).
        let [t_s, x_m, y_m, heading_rad, s, error, omega_radps, s_measured] = TRACE_COLUMNS;
        let idx = [
            col(t_s)?,
            col(x_m)?,
            col(y_m)?,
            col(heading_rad)?,
            col(s)?,
            col(error)?,
            col(omega_radps)?,
        ];
        let meas = headers.iter().position(|h| h == s_measured);
        let mut trace = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(|e| err(format!("trace.csv: {e}")))?;
            let line = rec.position().map_or(0, |p| p.line());
            let mut v = [0.0; 7];
            for (k, &i) in idx.iter().enumerate() {
                v[k] = rec.get(i).and_then(|t| t.parse().ok()).ok_or_else(|| {
                    err(format!(
                        "trace.csv:{line}: column {} is not a number",
                        headers.get(i).unwrap_or("?")
                    ))
                })?;
            }
            let m = meas.and_then(|i| rec.get(i)).and_then(|t| t.parse().ok());
            trace.push(TraceRow {
                t_s: v[0],
                x_m: v[1],
                y_m: v[2],
                heading_rad: v[3],
                s: v[4],
                error: v[5],
                omega_radps: v[6],
                s_measured: m,
                telemetry: None,
            });
        }
        if trace.is_empty() {
            let why = if scenario.file().output.record_rate_hz == Some(0.0) {
                "the trace was turned off (output.record_rate_hz = 0)".to_string()
            } else {
                format!(
                    "the run ended at t = {} s: {} ({})",
                    summary["t_end_s"],
                    summary["outcome"].as_str().unwrap_or("?"),
                    summary["outcome_detail"].as_str().unwrap_or("no detail")
                )
            };
            return Err(err(format!("trace.csv has no rows: {why}")));
        }
        let name = dir.file_name().map_or_else(
            || dir.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(Self {
            name,
            dir: dir.to_path_buf(),
            trace,
            summary,
            scenario,
        })
    }

    /// Start of the steady-state window, s.
    pub fn steady_state_start_s(&self) -> f64 {
        let f = self.scenario.file();
        (1.0 - f.metrics.steady_state_fraction.unwrap_or(0.2)) * f.sim.duration_s.unwrap_or(0.0)
    }
}
