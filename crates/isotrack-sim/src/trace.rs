//! Trace recording.

/// One recorded row of a run (the CSV trace's columns).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRow {
    /// Time, s.
    pub t_s: f64,
    /// East position, m.
    pub x_m: f64,
    /// North position, m.
    pub y_m: f64,
    /// Heading (course), rad counter-clockwise from +x, wrapped to `(-pi, pi]`.
    pub heading_rad: f64,
    /// True field value at the vehicle `s = F(t, p)`.
    pub s: f64,
    /// True tracking error `eps = s - s_d`.
    pub error: f64,
    /// Turn-rate command held over the next step, rad/s.
    pub omega_radps: f64,
    /// The last measurement the controller received (noise and delay included), if any yet.
    pub s_measured: Option<f64>,
    /// Altitude, airspeed and roll of a flying vehicle.
    pub telemetry: Option<isotrack_core::vehicle::Telemetry>,
}

/// Receives the rows the simulation records.
pub trait TraceSink {
    /// Records one row.
    fn record(&mut self, row: &TraceRow);

    /// Whether it keeps the rows it is given (`true` but for [`NoTrace`]): a run into a sink
    /// that keeps none builds none (the recording schedule runs on all the same).
    #[inline(always)]
    fn keeps_rows(&self) -> bool {
        true
    }
}

/// Records nothing (benchmarks, sweeps).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoTrace;

impl TraceSink for NoTrace {
    #[inline]
    fn record(&mut self, _row: &TraceRow) {}

    #[inline(always)]
    fn keeps_rows(&self) -> bool {
        false
    }
}

impl TraceSink for Vec<TraceRow> {
    fn record(&mut self, row: &TraceRow) {
        self.push(*row);
    }
}
