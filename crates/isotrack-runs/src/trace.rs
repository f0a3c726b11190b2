//! `trace.csv`: its columns (defined once, for the writer here and for `isotrack-plot`'s
//! reader) and the writer that streams it while a run goes.

use isotrack_scenario::Scenario;
use isotrack_sim::{RunResult, TraceRow, TraceSink};
use std::path::Path;

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

/// The column a team's trace adds (last): the vehicle's index in the team's listed order.
pub const VEHICLE_COLUMN: &str = "vehicle";

/// Streams `trace.csv` while the run goes: a header row, then one row per recorded step, so a
/// long run's trace never has to fit in memory. Numbers are written in Rust's shortest
/// round-trip form ([`num`]), so they read back bit-identical; `s_measured` is empty before the
/// first measurement; a flying vehicle adds [`TELEMETRY_COLUMNS`]. The first write error is kept
/// and returned by [`TraceWriter::finish`].
pub struct TraceWriter {
    w: csv::Writer<std::fs::File>,
    flying: bool,
    /// A team's trace: rows end with the vehicle's index ([`VEHICLE_COLUMN`]).
    team: bool,
    buf: Vec<String>,
    error: Option<std::io::Error>,
}

impl TraceWriter {
    /// Creates the file and writes the header. An existing path that is not a regular file (a
    /// link, a FIFO) is refused ([`crate::files::create_output`]).
    pub fn create(path: &Path, flying: bool) -> std::io::Result<Self> {
        Self::create_with(path, flying, false)
    }

    /// As [`TraceWriter::create`], for a team: the header ends with [`VEHICLE_COLUMN`], and rows
    /// are written through [`TeamTraceSink`]s.
    pub fn create_team(path: &Path, flying: bool) -> std::io::Result<Self> {
        Self::create_with(path, flying, true)
    }

    fn create_with(path: &Path, flying: bool, team: bool) -> std::io::Result<Self> {
        // Never into a FIFO (it would block) nor through a link: `files::create_output`.
        let mut w = csv::Writer::from_writer(crate::files::create_output(path)?);
        let mut header: Vec<&str> = TRACE_COLUMNS.to_vec();
        if flying {
            header.extend(TELEMETRY_COLUMNS);
        }
        if team {
            header.push(VEHICLE_COLUMN);
        }
        w.write_record(&header)?;
        Ok(Self {
            w,
            flying,
            team,
            buf: Vec::with_capacity(header.len()),
            error: None,
        })
    }

    /// Hands the rows written so far to the operating system (they survive the process being
    /// killed); an error is kept, as a write error is, for [`TraceWriter::finish`].
    pub fn flush(&mut self) {
        if self.error.is_none() {
            if let Err(e) = self.w.flush() {
                self.error = Some(e);
            }
        }
    }

    /// The first error met while writing or flushing, if any (rows after it are not written).
    pub fn error(&self) -> Option<&std::io::Error> {
        self.error.as_ref()
    }

    /// Flushes; the first error met while writing, if any.
    pub fn finish(mut self) -> std::io::Result<()> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.w.flush()
    }
}

impl TraceWriter {
    /// Writes one row, with `vehicle` in the last column of a team's trace.
    fn write_row(&mut self, r: &TraceRow, vehicle: usize) {
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
        if self.team {
            self.buf.push(vehicle.to_string());
        }
        if let Err(e) = self.w.write_record(&self.buf) {
            self.error = Some(e.into());
        }
    }
}

impl TraceSink for TraceWriter {
    fn record(&mut self, r: &TraceRow) {
        self.write_row(r, 0);
    }
}

/// One team member's sink into the team's one [`TraceWriter`] (made by
/// [`TraceWriter::create_team`]): its rows carry its index. The team steps its vehicles in
/// order, so the file holds, for each recorded step, vehicle 0's row, then 1's, ...
pub struct TeamTraceSink<'a, 'w> {
    writer: &'a std::cell::RefCell<&'w mut TraceWriter>,
    vehicle: usize,
}

impl<'a, 'w> TeamTraceSink<'a, 'w> {
    /// One sink per vehicle of a team of `count`, all into `writer`.
    pub fn for_team(
        writer: &'a std::cell::RefCell<&'w mut TraceWriter>,
        count: usize,
    ) -> Vec<Self> {
        (0..count).map(|vehicle| Self { writer, vehicle }).collect()
    }
}

impl TraceSink for TeamTraceSink<'_, '_> {
    fn record(&mut self, r: &TraceRow) {
        self.writer.borrow_mut().write_row(r, self.vehicle);
    }
}

/// Runs `scenario`'s team (its `[team]` section), streaming one trace of every vehicle into
/// `writer` (made by [`TraceWriter::create_team`]: a [`VEHICLE_COLUMN`] last; the caller
/// finishes it, as [`crate::rundir::RunDir::finish`]), over the threads `threads` allows for
/// the team's size (the same trace on any number). `None` without a team; `Some(Err)` with
/// the engine's reason when it refuses the team.
pub fn run_team_into(
    scenario: &Scenario,
    writer: &mut TraceWriter,
    threads: isotrack_sim::TeamThreads,
) -> Option<Result<isotrack_sim::TeamResult, String>> {
    let count = scenario.spec().team.as_ref()?.count();
    let w = std::cell::RefCell::new(writer);
    let mut sinks = TeamTraceSink::for_team(&w, count);
    Some(
        scenario
            .run_team_threads(&mut sinks, threads)?
            .map_err(|e| e.to_string()),
    )
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
