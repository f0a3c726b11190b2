//! `isotrack sitl` and `isotrack fly`: the MAVLink bridge (crate `isotrack-mavlink`) on the
//! command line.

use crate::cli::{FailsafeArg, FlyArgs, SitlArgs};
use crate::exit;
use crate::output::{scenario_toml, RunDir, Summary};
use crate::run::{load, Failure};
use isotrack_core::numtext::{Echo, Num};
use isotrack_mavlink::fly::{
    run_fly_flushing, FailsafeAction, FlyEnd, FlyError, FlyOptions, FlyReport, SensorSource,
};
use isotrack_mavlink::link::LinkError;
use isotrack_mavlink::sitl::{run_sitl_on, Pace, SitlError, SitlOptions, SitlReport};
use isotrack_runs::results::MetricsRecord;
use isotrack_runs::rundir::TraceFile;
use isotrack_runs::summary::{data_file_digests, Ended, FlightRecord};
use isotrack_scenario::{Scenario, ScenarioFile};
use isotrack_sim::{NoTrace, TraceRow, TraceSink};
use std::path::{Path, PathBuf};

fn usage(message: String) -> Failure {
    Failure {
        code: exit::USAGE,
        message,
    }
}

fn cant(what: &Path, e: std::io::Error) -> Failure {
    Failure {
        code: exit::CANTCREAT,
        message: format!("cannot write {}: {e}", what.display()),
    }
}

fn link_failure(e: LinkError) -> Failure {
    match e {
        LinkError::Address(m) => usage(format!("--mavlink {m}")),
        LinkError::Io(m) => Failure {
            code: exit::OSERR,
            message: m,
        },
        LinkError::Device(m) => Failure {
            code: exit::NOINPUT,
            message: format!("--mavlink {m}"),
        },
        LinkError::Unavailable(m) => Failure {
            code: exit::UNAVAILABLE,
            message: format!("--mavlink {m}"),
        },
    }
}

/// Checks that `v`, if given, is a finite number > 0 and not subnormal (`1e-310` s or Hz
/// divides into infinity), echoed as written.
fn positive(flag: &str, v: Option<f64>) -> Result<(), Failure> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0 && x.is_normal()) => Err(usage(format!(
            "{flag} must be a number > 0 (not subnormal), got {}",
            Echo(x)
        ))),
        _ => Ok(()),
    }
}

/// Checks that `v`, if given, is in `[lo, hi]` (a duration beyond `hi` overflows the clocks).
fn within(flag: &str, v: Option<f64>, lo: f64, hi: f64) -> Result<(), Failure> {
    match v {
        Some(x) if !(x.is_finite() && (lo..=hi).contains(&x)) => Err(usage(format!(
            "{flag} must be in [{}, {}], got {}",
            Echo(lo),
            Echo(hi),
            Echo(x)
        ))),
        _ => Ok(()),
    }
}

/// Readies run directory `dir` ([`RunDir::open`]: nothing over an input (64), not a folder
/// holding an input (73), created and locked as sweeps lock theirs (73 while another command
/// writes it), no output an existing link, FIFO or device (73)), with `extra` files besides the
/// run's. Nothing in it changes until the run has something to record ([`LiveOut`]).
fn prepare_out(
    dir: &Path,
    args: &crate::cli::ScenarioArgs,
    scenario: &isotrack_scenario::Scenario,
    extra: &[&str],
    command: &str,
) -> Result<RunDir, Failure> {
    let inputs = crate::output::input_files(args.scenario.as_deref(), scenario);
    RunDir::open(dir, &inputs, extra, Some(command))
}

/// A run directory written as the run goes, once it has something to record: until its first
/// trace row (or [`LiveOut::start`] at the end, for a flight that commanded the vehicle without
/// a row) an earlier run there stands untouched, so a start that fails (no vehicle heard, the
/// port taken, a vehicle refused) destroys nothing. Then: the files staged beside (`fly`'s raw
/// MAVLink log) renamed into place, `scenario.toml` written (a run killed mid-way leaves a
/// directory `plot` reads), the old summary removed and `trace.csv` started in place
/// ([`RunDir::live_trace`]); the summary comes last ([`RunDir::finish`]).
struct LiveOut {
    out: Option<RunDir>,
    scenario_toml: String,
    flying: bool,
    /// Files written under a temporary name while the run has not started: (temporary, final).
    staged: Vec<(PathBuf, PathBuf)>,
    trace: Option<TraceFile>,
    /// The first failure to start or write the directory (reported at the end, exit 73).
    error: Option<Failure>,
    /// The trace's first write error, as logged when it came, and the time of the last row
    /// handed to the trace then (the recording stopped there; the flight went on).
    trace_failed: Option<String>,
    /// The time of the last row recorded, s.
    last_row_t_s: Option<f64>,
    /// Another file of the run that could not be written to its end (`fly`'s
    /// `mavlink.tlog`), as logged when it happened: in `recording_incomplete` too (ver33-6).
    other_failed: Option<String>,
    /// The command writing (`fly`, `sitl`), for its log line.
    command: &'static str,
}

impl LiveOut {
    fn new(
        out: Option<RunDir>,
        scenario: &isotrack_scenario::Scenario,
        flying: bool,
        command: &'static str,
    ) -> Self {
        LiveOut {
            out,
            scenario_toml: scenario_toml(scenario),
            flying,
            staged: Vec::new(),
            trace: None,
            error: None,
            trace_failed: None,
            last_row_t_s: None,
            other_failed: None,
            command,
        }
    }

    /// Logs the trace's first write error at once (a disk that filled mid-flight): the run goes
    /// on, its recording stopped; the summary, written at the end, says so.
    fn check_trace(&mut self) {
        if self.trace_failed.is_some() {
            return;
        }
        let Some(e) = self
            .trace
            .as_mut()
            .and_then(|t| t.writer().error().map(|e| e.to_string()))
        else {
            return;
        };
        let path = self
            .out
            .as_ref()
            .map_or(PathBuf::from("trace.csv"), |o| o.path("trace.csv"));
        let at = self
            .last_row_t_s
            .map_or("its start".to_string(), |t| format!("t = {} s", Num(t)));
        let note = format!(
            "cannot write {}: {e}: recording stopped near {at} (the rows after it are missing)",
            path.display()
        );
        errln!(
            "isotrack {}: {note}; the flight goes on, summary.json will say so",
            self.command
        );
        self.trace_failed = Some(note);
    }

    /// Starts the directory (once; a failure is kept in `error`).
    fn start(&mut self) {
        let Some(out) = self.out.as_ref() else {
            return;
        };
        if self.trace.is_some() || self.error.is_some() {
            return;
        }
        let started = (|| {
            for (tmp, path) in std::mem::take(&mut self.staged) {
                std::fs::rename(&tmp, &path).map_err(|e| {
                    let _ = std::fs::remove_file(&tmp);
                    cant(&path, e)
                })?;
            }
            let p = out.path("scenario.toml");
            isotrack_runs::files::write_atomic(&p, self.scenario_toml.as_bytes())
                .map_err(|e| cant(&p, e))?;
            out.live_trace(self.flying)
        })();
        match started {
            Ok(t) => self.trace = Some(t),
            Err(e) => self.error = Some(e),
        }
    }

    /// Flushes the trace (a flight killed mid-way leaves it up to the last flush).
    fn flush(&mut self) {
        if let Some(t) = self.trace.as_mut() {
            t.writer().flush();
        }
        self.check_trace();
    }

    /// Ends the directory: the summary written (through [`RunDir::finish`]) if it was started;
    /// else the staged files removed and the directory let go ([`RunDir::release_unused`]),
    /// its earlier contents as they were. Returns whether anything was written.
    /// A trace that could not be written to its end (logged when it happened,
    /// [`LiveOut::check_trace`]) still gets its summary, given the note (`summary`'s argument;
    /// `None` for a whole trace), and the end is the failure to write it (exit 73).
    fn end<S: serde::Serialize>(
        mut self,
        summary: impl FnOnce(Option<&str>) -> Summary<S>,
    ) -> Result<bool, Failure> {
        if let Some(t) = self.trace.as_mut() {
            t.writer().flush();
        }
        self.check_trace();
        let Some(out) = self.out.take() else {
            return Ok(false);
        };
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let failed = match (self.trace_failed.take(), self.other_failed.take()) {
            (Some(a), Some(b)) => Some(format!("{a}; {b}")),
            (a, b) => a.or(b),
        };
        // An earlier run's figures (or log, for `sitl`) there are not this run's: said once
        // the run is written, as `run` says it (nu-21, att39-1 addendum).
        let note_before = |out: &RunDir| {
            crate::run::note_outputs_from_before(&out.outputs_from_before(), out.dir(), false)
        };
        match self.trace.take() {
            Some(trace) => match failed {
                Some(note) => {
                    out.finish_incomplete(trace, &self.scenario_toml, &summary(Some(&note)))?;
                    note_before(&out);
                    Err(Failure {
                        code: exit::CANTCREAT,
                        message: format!(
                            "{note}; summary.json written with recording_incomplete (the flight itself ended as it says)"
                        ),
                    })
                }
                None => {
                    out.finish(trace, &self.scenario_toml, &summary(None))?;
                    note_before(&out);
                    Ok(true)
                }
            },
            None => {
                for (tmp, _) in std::mem::take(&mut self.staged) {
                    let _ = std::fs::remove_file(&tmp);
                }
                out.release_unused();
                Ok(false)
            }
        }
    }
}

impl LiveOut {
    /// Leaves the directory of a run that failed: a started one as it is (its trace flushed,
    /// no summary: readers refuse it, never an old summary beside a new trace); else the staged
    /// files removed and the directory let go, its earlier contents as they were. Returns
    /// whether it had been started.
    fn abandon(mut self) -> bool {
        self.flush();
        if self.trace.is_some() {
            return true;
        }
        for (tmp, _) in std::mem::take(&mut self.staged) {
            let _ = std::fs::remove_file(&tmp);
        }
        if let Some(out) = self.out.take() {
            out.release_unused();
        }
        false
    }
}

impl TraceSink for LiveOut {
    fn record(&mut self, row: &TraceRow) {
        self.start();
        if let Some(t) = self.trace.as_mut() {
            t.writer().record(row);
            self.last_row_t_s = Some(row.t_s);
        }
        self.check_trace();
    }
}

/// The note when a run directory was left as it was (nothing to record).
fn untouched_note(command: &str, dir: &Path) {
    errln!(
        "isotrack {command}: nothing written to {}: the run recorded nothing (its earlier contents, if any, stand)",
        dir.display()
    );
}

/// The range of `--speedup`.
pub const SPEEDUP_RANGE: (f64, f64) = (1e-3, 1e3);
/// The range of `sitl --heartbeat-hz`, Hz: MAVLink's heartbeat is 1 Hz, at least 0.2 Hz (a
/// companion's link timeout is a few seconds), at most 50 Hz.
pub const HEARTBEAT_HZ_RANGE: (f64, f64) = (0.2, 50.0);
/// The largest `--timeout-s`, s (a day).
pub const MAX_TIMEOUT_S: f64 = 86_400.0;
/// The smallest `--timeout-s`, s: the loops poll every 10 to 50 ms, and a vehicle beats at
/// 1 Hz; below this a flight or a lockstep run would end at its first quiet moment.
pub const MIN_TIMEOUT_S: f64 = 0.1;

/// Refuses `--system-id 255`, the ground stations' id (QGroundControl's, MAVProxy's): `sitl`
/// refuses every setpoint from system 255, and a vehicle or companion with it would be taken
/// for the operator's ground station.
fn not_a_ground_stations_id(flag: &str, id: u8) -> Result<(), Failure> {
    if id == GCS_SYSTEM_ID {
        return Err(usage(format!(
            "{flag} 255 is the ground stations' system id (QGroundControl's, MAVProxy's): give 1 to 254"
        )));
    }
    Ok(())
}

/// The ground stations' system id.
const GCS_SYSTEM_ID: u8 = 255;
/// The largest `--max-duration-s`, s: MAVLink's `time_boot_ms` span.
pub const MAX_DURATION_S: f64 = u32::MAX as f64 / 1000.0;

/// `sitl`'s options checked before anything is loaded or opened: the usage errors (64).
fn check_sitl_args(args: &SitlArgs) -> Result<(), Failure> {
    positive("--speedup", args.speedup)?;
    within("--speedup", args.speedup, SPEEDUP_RANGE.0, SPEEDUP_RANGE.1)?;
    positive("--timeout-s", Some(args.timeout_s))?;
    within(
        "--timeout-s",
        Some(args.timeout_s),
        MIN_TIMEOUT_S,
        MAX_TIMEOUT_S,
    )?;
    positive("--heartbeat-hz", args.heartbeat_hz)?;
    within(
        "--heartbeat-hz",
        args.heartbeat_hz,
        HEARTBEAT_HZ_RANGE.0,
        HEARTBEAT_HZ_RANGE.1,
    )?;
    not_a_ground_stations_id("--system-id", args.system_id)?;
    if args.system_id == 0 {
        // Messages addressed to system 0 are for everyone: a vehicle cannot be it.
        return Err(usage(
            "--system-id 0 is MAVLink's broadcast address, not a vehicle's: give 1 to 255".into(),
        ));
    }
    Ok(())
}

/// `isotrack sitl`.
pub fn sitl(args: &SitlArgs) -> Result<(), Failure> {
    check_sitl_args(args)?;
    let scenario = load(&args.scenario)?;
    crate::run::refuse_team(&scenario, "sitl")?;
    let opts = sitl_options(args);
    let out = match &args.out {
        Some(dir) => Some(prepare_out(dir, &args.scenario, &scenario, &[], "sitl")?),
        None => None,
    };
    // Written from the run's first row: a start that fails (the port taken) changes nothing.
    let mut live = LiveOut::new(out, &scenario, scenario.is_flying(), "sitl");
    let sink: &mut dyn TraceSink = if live.out.is_some() {
        &mut live
    } else {
        &mut NoTrace
    };
    let report = run_sitl_on(&scenario, &opts, sink, &mut |l| {
        errln!(
            "isotrack sitl: vehicle on {} ({})",
            l.describe(),
            args.mavlink
        );
    });
    let report = match report {
        Ok(r) => r,
        Err(e) => {
            if let (Some(dir), false) = (&args.out, live.abandon()) {
                untouched_note("sitl", dir);
            }
            return Err(sitl_failure(e));
        }
    };
    for e in &report.events {
        errln!("isotrack sitl: {e}");
    }
    let cut = cut_short(&report, args.timeout_s);
    // A run that started (a peer talked to the vehicle) writes its directory even without a
    // trace row (a lockstep run nobody flew); one that never started leaves DIR as it was.
    if report.started {
        live.start();
    }
    let wrote = live.end(|incomplete| {
        let mut warnings = report.events.clone();
        warnings.extend(incomplete.map(|n| format!("recording_incomplete: {n}")));
        let mut summary = Summary::of_run(
            &scenario,
            args.scenario.scenario.as_deref(),
            &report.result,
            &warnings,
        );
        if let (Some((outcome, detail)), Ended::Run(r)) = (&cut, &mut summary.ended) {
            r.record.outcome = (*outcome).to_string();
            r.record.outcome_detail = Some(detail.clone());
        }
        // att41-17: the data files as the field was read (before the run), and a word when
        // one changed since, as `run` records them.
        if let Some(w) = summary.data_files_as_read(data_file_digests(&scenario)) {
            errln!("warning: {w}");
        }
        summary
    })?;
    if let (Some(dir), false) = (&args.out, wrote) {
        untouched_note("sitl", dir);
    }
    sitl_exit(&report, cut)
}

/// The end line on stdout and the exit of a sitl run that ran (README's exit table): 130 when
/// interrupted, 69 when the lockstep companion was lost, else 0.
fn sitl_exit(report: &SitlReport, cut: Option<(&str, String)>) -> Result<(), Failure> {
    outln!(
        "outcome     {} at t = {} s ({} samples, {} setpoints refused, {} setpoints out of order)",
        cut.as_ref().map_or(report.result.outcome.as_str(), |c| c.0),
        Num(report.result.t_end_s),
        report.result.samples,
        report.setpoints_refused,
        report.setpoints_out_of_order,
    );
    if report.interrupted {
        return Err(Failure {
            code: crate::sweep::INTERRUPTED,
            message: "interrupted".into(),
        });
    }
    if report.companion_lost {
        return Err(Failure {
            code: exit::UNAVAILABLE,
            message: cut.map(|c| c.1).unwrap_or_default(),
        });
    }
    Ok(())
}

/// The vehicle's options of `sitl`'s arguments, Ctrl-C wired.
fn sitl_options(args: &SitlArgs) -> SitlOptions {
    let mut opts = SitlOptions::new(&args.mavlink);
    opts.system_id = args.system_id;
    opts.pace = if args.lockstep {
        Pace::Lockstep
    } else {
        Pace::RealTime {
            speedup: args.speedup.unwrap_or(1.0),
        }
    };
    opts.companion_timeout_s = args.timeout_s;
    opts.heartbeat_hz = args.heartbeat_hz;
    opts.stop = isotrack_runs::signals::interrupt_flag();
    opts
}

/// The exit of a sitl run that could not run (README's exit table).
fn sitl_failure(e: SitlError) -> Failure {
    match e {
        SitlError::Link(l) => link_failure(l),
        SitlError::Scenario(m) => Failure {
            code: exit::DATAERR,
            message: m,
        },
        SitlError::Io(e) => Failure {
            code: exit::OSERR,
            message: format!("link: {e}"),
        },
    }
}

/// A sitl run cut short is no `completed` run: its outcome and detail, `interrupted` (Ctrl-C,
/// SIGTERM, SIGHUP), as `run` says, or `companion_lost` (lockstep, nobody answered for
/// `timeout_s`); `None` for a run that ended by itself.
fn cut_short(report: &SitlReport, timeout_s: f64) -> Option<(&'static str, String)> {
    if report.interrupted {
        Some((
            "interrupted",
            "stopped by a signal (Ctrl-C, SIGTERM or SIGHUP)".to_string(),
        ))
    } else if report.companion_lost {
        Some((
            "companion_lost",
            format!(
                "lockstep: no message from the companion for {} s",
                Echo(timeout_s)
            ),
        ))
    } else {
        None
    }
}

/// `fly`'s exit code when it stopped before it had control (see [`exit::NOTHING_COMMANDED`]).
pub const NOTHING_COMMANDED: u8 = exit::NOTHING_COMMANDED;

/// `fly`'s options checked before anything is loaded or opened: the usage errors (64).
fn check_fly_args(args: &FlyArgs) -> Result<(), Failure> {
    positive("--max-duration-s", args.max_duration_s)?;
    positive("--timeout-s", Some(args.timeout_s))?;
    within(
        "--timeout-s",
        Some(args.timeout_s),
        MIN_TIMEOUT_S,
        MAX_TIMEOUT_S,
    )?;
    not_a_ground_stations_id("--system-id", args.system_id)?;
    within("--max-duration-s", args.max_duration_s, 0.0, MAX_DURATION_S)?;
    positive("--fence-m", args.fence_m)?;
    if !(args.setpoint_rate_hz.is_finite() && (2.0..=1000.0).contains(&args.setpoint_rate_hz)) {
        return Err(usage(format!(
            "--setpoint-rate-hz must be in [2, 1000] (PX4's offboard mode needs 2 Hz), got {}",
            Echo(args.setpoint_rate_hz)
        )));
    }
    if args.system_id == 0 || args.target_system == Some(0) {
        // Messages from or to system 0 are broadcasts: no companion or vehicle is it.
        return Err(usage(format!(
            "{} 0 is MAVLink's broadcast address, not a system's: give 1 to 255",
            if args.system_id == 0 {
                "--system-id"
            } else {
                "--target-system"
            }
        )));
    }
    if args.arm && !args.take_control {
        return Err(usage(
            "--arm goes with --take-control (without it, fly waits for the pilot to arm and hand over)".into(),
        ));
    }
    if args.allow_generic && !args.take_control {
        return Err(usage(
            "--allow-generic goes with --take-control (without it, a MAV_TYPE_GENERIC vehicle is flown when its pilot hands over, with a warning)".into(),
        ));
    }
    Ok(())
}

/// The bridge's options of `fly`'s arguments, its sensor parsed, Ctrl-C wired, events written
/// live.
fn fly_options(args: &FlyArgs, sensor: SensorSource) -> FlyOptions {
    let mut opts = FlyOptions::new(&args.mavlink);
    opts.sensor = sensor;
    opts.take_control = args.take_control;
    opts.arm = args.arm;
    opts.allow_generic = args.allow_generic;
    opts.max_duration_s = args.max_duration_s;
    opts.timeout_s = args.timeout_s;
    opts.fence_m = args.fence_m;
    opts.setpoint_rate_hz = args.setpoint_rate_hz;
    opts.system_id = args.system_id;
    opts.target_system = args.target_system;
    opts.failsafe = match args.failsafe {
        FailsafeArg::Hold => FailsafeAction::Hold,
        FailsafeArg::Return => FailsafeAction::Return,
        FailsafeArg::Loiter => FailsafeAction::Loiter,
    };
    opts.stop = isotrack_runs::signals::interrupt_flag();
    // Each event on standard error as it happens (unbuffered: a line at a time), not when the
    // flight ends (ver33-2): the operator watching the companion's terminal sees a rejected
    // sensor, a pilot's take-over or a failsafe at once.
    opts.live_events = Some(isotrack_mavlink::fly::LiveEvents(std::sync::Arc::new(
        |e| {
            errln!("isotrack fly: {e}");
        },
    )));
    opts
}

/// The end line on stdout and the exit of a flight that ran (README's exit table): 69, 65, 79,
/// 75 as it ended and what was commanded.
fn fly_exit(report: &FlyReport, args: &FlyArgs) -> Result<(), Failure> {
    outln!(
        "end         {} ({} measurements, {} law commands)",
        report.end.as_str(),
        report.samples,
        report.commands.len()
    );
    check_stopped_before_control(report, args)?;
    if report.end == FlyEnd::PilotTookOver {
        errln!("isotrack fly: pilot_took_over: the companion let go, nothing commanded");
    }
    check_way_out(report)
}

/// A flight that stopped before it had any vehicle to command (README's exit table): two
/// autopilots heard (69), a vehicle of another kind than the scenario's (65), another
/// controller (79), or no vehicle heard before a failsafe (69).
fn check_stopped_before_control(report: &FlyReport, args: &FlyArgs) -> Result<(), Failure> {
    if report.end == FlyEnd::TwoVehicles && !report.way_out_commanded {
        return Err(Failure {
            code: exit::UNAVAILABLE,
            message: "two autopilots heard: which to fly is ambiguous, nothing commanded (see above: on two systems, pick one with --target-system)".into(),
        });
    }
    if report.end == FlyEnd::VehicleMismatch {
        return Err(Failure {
            code: exit::DATAERR,
            message: "the scenario's vehicle kind does not fit the vehicle's type (see above): nothing commanded".into(),
        });
    }
    if report.end == FlyEnd::AnotherController && !report.way_out_commanded {
        // A twin companion heard before any vehicle (ver33-4) or another controller before
        // control: the companion went no further.
        return Err(Failure {
            code: NOTHING_COMMANDED,
            message: "another_controller: another controller or a second companion with this one's ids (see above): the companion went no further and commanded nothing (the vehicle's mode stands)".into(),
        });
    }
    if report.end.is_failsafe() && !report.vehicle_heard {
        let heard = never_heard(report, args);
        return Err(Failure {
            code: exit::UNAVAILABLE,
            message: format!(
                "failsafe ({}): {heard}: nothing was sent",
                report.end.as_str()
            ),
        });
    }
    Ok(())
}

/// Why no vehicle was heard on `--mavlink`: another system's autopilot than `--target-system`,
/// frames without an autopilot's HEARTBEAT, or nothing at all.
fn never_heard(report: &FlyReport, args: &FlyArgs) -> String {
    match (report.other_system_heard, args.target_system) {
        (Some((sys, comp)), Some(want)) => format!(
            "the vehicle of --target-system {want} was never heard on {}, only system {sys}'s autopilot (component {comp}): a mistyped id?",
            args.mavlink
        ),
        _ if report.link.frames_in > 0 => format!(
            "no vehicle was ever heard on {}: {} frames came, but no autopilot's HEARTBEAT (one beating slower than --timeout-s, or no autopilot among the senders)",
            args.mavlink, report.link.frames_in
        ),
        _ => format!("no vehicle was ever heard on {}", args.mavlink),
    }
}

/// The exit of a flight past its contact with the vehicle, as it ended and what was commanded
/// (README's exit table): 79 with nothing commanded, 69 for a way out overridden or
/// unconfirmed, 75 for one the vehicle confirmed, 0 for a flight that ended on its own.
fn check_way_out(report: &FlyReport) -> Result<(), Failure> {
    let commanded = report.way_out_commanded;
    if report.end.is_failsafe() && !commanded {
        return Err(Failure {
            code: NOTHING_COMMANDED,
            message: format!(
                "failsafe ({}): the companion stopped and commanded nothing, before it had control of the vehicle or after the vehicle's heartbeats showed a pilot's word (see above): the vehicle's mode stands",
                report.end.as_str()
            ),
        });
    }
    if commanded && report.way_out_overridden {
        return Err(Failure {
            code: exit::UNAVAILABLE,
            message: format!(
                "failsafe ({}): a pilot took over during the retries (see above): they stopped unconfirmed, the pilot's mode stands",
                report.end.as_str()
            ),
        });
    }
    if commanded && !report.failsafe_acknowledged {
        return Err(Failure {
            code: exit::UNAVAILABLE,
            message: format!(
                "failsafe ({}): the vehicle did not confirm the failsafe mode",
                report.end.as_str()
            ),
        });
    }
    if report.end == FlyEnd::ControlRefused && !commanded {
        // Control was not taken and no way out was sent: the vehicle's mode stands (README's
        // exit table: 79, nothing commanded).
        return Err(Failure {
            code: NOTHING_COMMANDED,
            message: "control_refused: control was not taken (see above): the companion stopped and commanded nothing (the vehicle's mode stands)".into(),
        });
    }
    if commanded && report.end == FlyEnd::MaxDuration {
        return Err(Failure {
            code: exit::FAILSAFE,
            message: "the flight ended at its --max-duration-s (max_duration): the way out was commanded, confirmed by the vehicle".into(),
        });
    }
    if commanded {
        return Err(Failure {
            code: exit::FAILSAFE,
            message: format!(
                "the flight was ended by a failsafe ({}), confirmed by the vehicle",
                report.end.as_str(),
            ),
        });
    }
    Ok(())
}

/// The exit of a flight that could not fly (README's exit table): an I/O error writing the raw
/// log at `log` (when that is what failed) names the log's file.
fn fly_failure(e: FlyError, log: Option<&Path>) -> Failure {
    match e {
        FlyError::Io(e) if log.is_some() => cant(log.unwrap_or(Path::new("?")), e),
        FlyError::Link(l) => link_failure(l),
        FlyError::Scenario(m) => Failure {
            code: exit::DATAERR,
            message: m,
        },
        FlyError::Io(e) => Failure {
            code: exit::OSERR,
            message: format!("link: {e}"),
        },
    }
}

/// A flight's summary.json: its record as it ended (`incomplete`: the trace's recording note).
fn flight_summary<'a>(
    report: &FlyReport,
    args: &FlyArgs,
    scenario: &'a Scenario,
    incomplete: Option<&str>,
) -> Summary<&'a ScenarioFile> {
    Summary {
        isotrack_version: env!("CARGO_PKG_VERSION").to_string(),
        scenario_path: args
            .scenario
            .scenario
            .as_ref()
            .map(|p| p.display().to_string()),
        ended: Ended::Flight(FlightRecord {
            outcome: if report.end.is_failsafe() {
                "failsafe"
            } else if report.end == FlyEnd::VehicleEnded {
                "completed"
            } else {
                report.end.as_str()
            }
            .to_string(),
            outcome_detail: report.events.last().cloned().unwrap_or_default(),
            end_reason: report.end.as_str().to_string(),
            failsafe: report.end.is_failsafe(),
            failsafe_acknowledged: report.failsafe_acknowledged,
            t_end_s: report.t_last_s,
            samples: report.samples,
            commands: report.commands.len() as u64,
            events: report.events.clone(),
            frames_in: report.link.frames_in,
            frames_out: report.link.frames_out,
            junk_datagrams: report.link.junk_datagrams,
            measurements_out_of_order: report.measurements_out_of_order,
            measurements_repeated: report.measurements_repeated,
            measurements_invalid: report.measurements_invalid,
            measurements_other_sources: report.measurements_other_sources,
            recording_incomplete: incomplete.map(String::from),
            data_files: data_file_digests(scenario),
            metrics_over: report.metrics_over.to_string(),
            metrics: MetricsRecord::of(&report.metrics),
        }),
        scenario: scenario.file(),
        controller: None,
    }
}

/// `isotrack fly`.
pub fn fly(args: &FlyArgs) -> Result<(), Failure> {
    check_fly_args(args)?;
    let sensor = SensorSource::parse(&args.sensor).map_err(usage)?;
    let scenario = load(&args.scenario)?;
    crate::run::refuse_team(&scenario, "fly")?;
    let opts = fly_options(args, sensor);
    // Readied (and locked) by the one run-directory writer, and written once the flight has
    // something to record (LiveOut): a start that fails leaves an earlier flight there whole.
    let out = match &args.out {
        Some(dir) => Some(prepare_out(
            dir,
            &args.scenario,
            &scenario,
            &["mavlink.tlog"],
            "fly",
        )?),
        None => None,
    };
    let mut live = LiveOut::new(out, &scenario, false, "fly");
    // The raw log goes into a temporary file beside `mavlink.tlog`, renamed into place when the
    // flight starts its directory.
    let log_path = args.out.as_ref().map(|d| {
        let p = d.join("mavlink.tlog");
        (isotrack_runs::files::temp_beside(&p), p)
    });
    if let Some((tmp, p)) = &log_path {
        live.staged.push((tmp.clone(), p.clone()));
    }
    let mut log_error = None;
    let mut flush = |t: &mut LiveOut| t.flush();
    let report = run_fly_flushing(&scenario, &opts, &mut live, &mut flush, &mut |link| {
        errln!(
            "isotrack fly: companion on {} ({})",
            link.describe(),
            args.mavlink
        );
        if let Some((tmp, _)) = &log_path {
            if let Err(e) = link.log_to(tmp) {
                log_error = Some(e.to_string());
                return Err(e);
            }
        }
        Ok(())
    });
    let report = match report {
        Ok(r) => r,
        Err(e) => {
            let started = live.abandon();
            if let (Some(dir), false) = (&args.out, started) {
                untouched_note("fly", dir);
            }
            let log = log_path.as_ref().map(|(_, p)| p.as_path());
            return Err(fly_failure(e, log.filter(|_| log_error.is_some())));
        }
    };
    for e in report.events.iter().skip(report.events_live) {
        errln!("isotrack fly: {e}");
    }
    if let (Some(note), Some((_, p))) = (&report.log_incomplete, &log_path) {
        live.other_failed = Some(format!("{}: {note}", p.display()));
    }
    // A flight that recorded no row but commanded the vehicle (a way out after a refused
    // take-over) still writes its directory: what was commanded is on record.
    if report.way_out_commanded {
        live.start();
    }
    let wrote = live.end(|incomplete| {
        let mut summary = flight_summary(&report, args, &scenario, incomplete);
        // att41-17: the data files as the field was read (before the flight), and a word
        // (in `events` too) when one changed since, as `run` records them.
        if let Some(w) = summary.data_files_as_read(data_file_digests(&scenario)) {
            errln!("warning: {w}");
        }
        summary
    })?;
    if let (Some(dir), false) = (&args.out, wrote) {
        untouched_note("fly", dir);
    }
    fly_exit(&report, args)
}
