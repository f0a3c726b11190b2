//! Run outputs: the trace CSV, the summary JSON and the resolved scenario.

use isotrack_scenario::{Scenario, ScenarioFile};
use isotrack_sim::{RunResult, TraceRow, TraceSink};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The columns of `trace.csv`, in order.
pub const TRACE_COLUMNS: [&str; 8] = [
    "t_s",
    "x_m",
    "y_m",
    "heading_rad",
    "s",
    "error",
    "omega_radps",
    "s_measured",
];

/// The columns a flying vehicle adds to `trace.csv` (roll positive right wing down).
pub const TELEMETRY_COLUMNS: [&str; 3] = ["altitude_m", "airspeed_mps", "roll_rad"];

/// Streams `trace.csv` while the run goes: a header row, then one row per recorded step, so a
/// long run's trace never has to fit in memory. Numbers are written in Rust's shortest
/// round-trip form ([`num`]), so they read back bit-identical; `s_measured` is empty before the
/// first measurement; a flying vehicle adds [`TELEMETRY_COLUMNS`]. The first write error is kept
/// and returned by [`TraceWriter::finish`].
pub struct TraceWriter {
    w: csv::Writer<std::fs::File>,
    flying: bool,
    buf: Vec<String>,
    error: Option<std::io::Error>,
}

impl TraceWriter {
    /// Creates the file and writes the header.
    pub fn create(path: &Path, flying: bool) -> std::io::Result<Self> {
        let mut w = csv::Writer::from_path(path)?;
        let mut header: Vec<&str> = TRACE_COLUMNS.to_vec();
        if flying {
            header.extend(TELEMETRY_COLUMNS);
        }
        w.write_record(&header)?;
        Ok(Self {
            w,
            flying,
            buf: Vec::with_capacity(header.len()),
            error: None,
        })
    }

    /// Flushes; the first error met while writing, if any.
    pub fn finish(mut self) -> std::io::Result<()> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.w.flush()
    }
}

impl TraceSink for TraceWriter {
    fn record(&mut self, r: &TraceRow) {
        if self.error.is_some() {
            return;
        }
        self.buf.clear();
        for v in [
            r.t_s,
            r.x_m,
            r.y_m,
            r.heading_rad,
            r.s,
            r.error,
            r.omega_radps,
        ] {
            self.buf.push(num(v));
        }
        self.buf.push(r.s_measured.map(num).unwrap_or_default());
        if self.flying {
            let t = r.telemetry.unwrap_or_default();
            for v in [t.altitude_m, t.airspeed_mps, t.roll_rad] {
                self.buf.push(num(v));
            }
        }
        if let Err(e) = self.w.write_record(&self.buf) {
            self.error = Some(e.into());
        }
    }
}

/// Runs `scenario`, streaming its trace into `path`.
pub fn run_to_trace(scenario: &Scenario, path: &Path) -> std::io::Result<RunResult> {
    let mut w = TraceWriter::create(path, scenario.is_flying())?;
    let r = scenario.run(&mut w);
    w.finish()?;
    Ok(r)
}

/// A number as written in CSV outputs: the shortest string that reads back to the same `f64`,
/// in scientific notation when that is shorter (`7.105427357601002e-15`, `0.5`, `600.0`).
pub fn num(v: f64) -> String {
    format!("{v:?}")
}

/// The content of `summary.json`.
#[derive(Debug, Serialize)]
pub struct Summary<'a> {
    /// isotrack's version.
    pub isotrack_version: &'static str,
    /// The scenario file as given, or `null` for the built-in default.
    pub scenario_path: Option<String>,
    /// The run's outcome and metrics (flattened: `outcome`, `steady_state_max_abs_error`, ...).
    #[serde(flatten)]
    pub result: &'a RunResult,
    /// Warnings about the scenario (also printed on stderr): noise through a backward
    /// difference, a sampled loop that `isotrack check` finds unstable.
    pub warnings: &'a [String],
    /// The fully resolved scenario.
    pub scenario: &'a ScenarioFile,
}

/// Writes `summary.json` (pretty-printed; non-finite or undefined metrics are `null`).
pub fn write_summary(
    path: &Path,
    scenario: &Scenario,
    scenario_path: Option<&Path>,
    result: &RunResult,
    warnings: &[String],
) -> std::io::Result<()> {
    let s = Summary {
        isotrack_version: env!("CARGO_PKG_VERSION"),
        scenario_path: scenario_path.map(|p| p.display().to_string()),
        result,
        warnings,
        scenario: scenario.file(),
    };
    let text = summary_to_json(&s).map_err(std::io::Error::other)?;
    std::fs::write(path, text + "\n")
}

/// `summary.json`'s text (pretty-printed; non-finite metrics are `null`): one rendering for the
/// file and for the Python package.
pub fn summary_to_json(s: &Summary<'_>) -> serde_json::Result<String> {
    serde_json::to_string_pretty(s)
}

/// The resolved scenario as TOML (reads back as the same scenario).
pub fn scenario_toml(scenario: &Scenario) -> String {
    toml::to_string(scenario.file()).unwrap_or_else(|e| format!("# cannot render: {e}\n"))
}

/// The files a command reads for `scenario`: the scenario file (if any) and the data files its
/// field names (`field.path`, `field.paths`: absolute once the scenario is built). An output
/// that is one of them is refused (64), never written over.
pub fn input_files(scenario_file: Option<&Path>, scenario: &Scenario) -> Vec<PathBuf> {
    let field = &scenario.file().field;
    scenario_file
        .map(Path::to_path_buf)
        .into_iter()
        .chain(field.path.iter().map(PathBuf::from))
        .chain(field.paths.iter().flatten().map(PathBuf::from))
        .collect()
}

/// When `output` is one of `inputs` (the same file, through links): the message that refuses it.
pub fn input_clash(inputs: &[PathBuf], output: &Path) -> Option<String> {
    let input = inputs.iter().find(|i| same_file(i, output))?;
    Some(format!(
        "{} is an input ({}): an output cannot be one of the inputs",
        output.display(),
        input.display()
    ))
}

/// Whether two paths name the same existing file (same device and inode), not just the same
/// string: `a/../a/x` and a hard link count.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) if x == y => true,
        _ => {
            #[cfg(unix)]
            {
                use std::os::unix::fs::MetadataExt;
                match (std::fs::metadata(a), std::fs::metadata(b)) {
                    (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
                    _ => false,
                }
            }
            #[cfg(not(unix))]
            false
        }
    }
}
