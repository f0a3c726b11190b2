//! `isotrack sitl`: a scenario's vehicle, field and sensor as a MAVLink 2 vehicle.
//!
//! The loop is the scenario's own ([`isotrack_scenario::ScenarioEpisode`]): at each sensor sample
//! the vehicle sends the measurement (`NAMED_VALUE_FLOAT` [`wire::MEASUREMENT_NAME`]) and holds,
//! until the next sample, the turn rate its mode gives ([`Mode`]): in OFFBOARD (armed), the last
//! valid setpoint of the companion that took control. Telemetry is sent at the scenario's
//! recording rate (`output.record_rate_hz`, at least [`MIN_TELEMETRY_RATE_HZ`]: a lower rate,
//! or 0, which turns the trace off, is refused before the link opens, since positions would
//! stop): `GLOBAL_POSITION_INT`, `LOCAL_POSITION_NED`, `ATTITUDE`, `VFR_HUD`; once per
//! simulated second `HEARTBEAT`, `SYS_STATUS`, `EXTENDED_SYS_STATE`, `SYSTEM_TIME` and
//! `HOME_POSITION`.
//!
//! Start: the run (and its clock, real time or lockstep) starts on the first frame of a peer
//! that talks to this vehicle ([`starts_the_run`]): a `HEARTBEAT` of a ground station or a
//! companion (`MAV_TYPE_GCS`, `MAV_TYPE_ONBOARD_CONTROLLER`), or a message addressed to this
//! system (`target_system` = `--system-id`). A stray frame (another vehicle's heartbeat, a
//! message for another system, a TCP connection that says nothing) starts nothing. While it
//! waits, the vehicle sends only its `HEARTBEAT`, once a wall-clock second, to the peers the
//! link has (a ground station waits for a vehicle's heartbeat before it speaks).
//!
//! Pacing: [`Pace::RealTime`] keeps simulated time at `speedup` x the wall clock, and the
//! setpoint in force at a sample is held to the next one; the offboard failsafe switches to HOLD
//! when no valid setpoint came for [`SitlOptions::setpoint_timeout_s`] of simulated time.
//! [`Pace::Lockstep`] sends a sample and waits until it is answered, so the flight does not
//! depend on the machine's speed. The answer is a valid setpoint (one that moves the vehicle:
//! see [`SitlReport::setpoints_refused`]) stamped with the sample's `time_boot_ms` (`isotrack
//! fly`'s answer), or stamped newer than every setpoint its sender sent before (a ground station
//! or SDK that stamps setpoints with its own clock, as MAVSDK's Offboard plugin does: one sample
//! per new setpoint), that came while the vehicle was armed in OFFBOARD (it follows setpoints).
//! Nothing else advances the run: heartbeats, commands, requests for telemetry or parameters,
//! refused setpoints, a setpoint repeated with the same stamp, one stamped
//! [`NOT_AN_ANSWER_MS`], or any answer while the vehicle is disarmed or in MANUAL, HOLD or
//! RETURN: while nobody flies it by setpoints (a companion waiting for the pilot answers with
//! neutral setpoints) simulated time stands still, so the run does not fly itself to its end
//! before a ground station has armed it and switched it to OFFBOARD. A companion that answers
//! a sample before it has control answers it again once it has (`isotrack fly` repeats its
//! setpoint at a steady rate, and the vehicle sends the sample again each wall-clock second).
//!
//! Out-of-order setpoints: a setpoint stamped older than the last one applied from the same
//! sender (system, component), by at most [`REORDER_WINDOW_MS`], moves nothing and is counted
//! ([`SitlReport::setpoints_out_of_order`]): UDP may deliver late. One older by more is the
//! sender's clock restarting (a ground station or companion restarted): it is applied, and
//! logged.
//!
//! Peers: the link drops a peer silent for [`SitlOptions::companion_timeout_s`] (see
//! [`crate::link`]); the vehicle's log keeps at most [`MAX_EVENTS`] events (then counts them),
//! so a flood of refused commands does not grow its memory.

use crate::geo::Frame;
use crate::link::{Link, LinkError, LinkStats, Received};
use crate::mirror::Transport;
use crate::vehicle_state::Mode;
use crate::wire;
use isotrack_core::math::{wrap_angle, Pose2};
use isotrack_core::numtext::{Echo, Num};
use isotrack_scenario::{Scenario, ScenarioEpisode};
use isotrack_sim::{RunResult, Sample, TraceRow, TraceSink};
use mavlink::dialects::common::*;
use mavlink::Message as _;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

pub use crate::wire::check_wire_times;

/// How simulated time goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pace {
    /// `speedup` simulated seconds per wall-clock second.
    RealTime {
        /// Simulated seconds per wall-clock second (> 0).
        speedup: f64,
    },
    /// One sensor period per answer of the companion.
    Lockstep,
}

/// Options of [`run_sitl`].
#[derive(Clone, Debug)]
pub struct SitlOptions {
    /// The link address (see [`crate::link`]).
    pub url: String,
    /// How simulated time goes.
    pub pace: Pace,
    /// The vehicle's MAVLink system id (component 1, the autopilot).
    pub system_id: u8,
    /// Simulated seconds without a valid setpoint, in OFFBOARD, before the vehicle holds
    /// (real time only).
    pub setpoint_timeout_s: f64,
    /// Set from outside (Ctrl-C) to end the run where it stands.
    pub stop: Arc<AtomicBool>,
    /// Lockstep: end the run when no message came from anyone for this long, wall s (the
    /// companion is gone: it ended or failed safe, and nobody will answer the sample). Also,
    /// in both paces, how long a peer of a `udpin:`/`tcpin:` link may be silent before the
    /// link drops it.
    pub companion_timeout_s: f64,
    /// `HEARTBEAT` at this fixed rate of the wall clock only, Hz, as PX4 beats (1 Hz): never
    /// after a command's acknowledgement or a mode change, so that a companion learns of a
    /// switch only from the next beat (up to a period later); the first beat as soon as a peer
    /// is there. On the wall clock, also with a speed-up. `None` (the default): once a
    /// simulated second and after every change (at once). Not in lockstep.
    pub heartbeat_hz: Option<f64>,
}

impl SitlOptions {
    /// Defaults: real time, system 1, a 1 s setpoint timeout (PX4's `COM_OF_LOSS_T`).
    pub fn new(url: &str) -> Self {
        Self {
            url: url.to_string(),
            pace: Pace::RealTime { speedup: 1.0 },
            system_id: 1,
            setpoint_timeout_s: 1.0,
            stop: Arc::new(AtomicBool::new(false)),
            companion_timeout_s: 10.0,
            heartbeat_hz: None,
        }
    }
}

/// What a simulated flight did.
#[derive(Clone, Debug)]
pub struct SitlReport {
    /// The run's result (as `isotrack run` reports it).
    pub result: RunResult,
    /// Per sample: its wire time, ms, and the turn rate the vehicle flew from it, rad/s.
    pub flown: Vec<(u32, f64)>,
    /// Mode changes, failsafes and refused commands, in order, with their simulated time.
    pub events: Vec<String>,
    /// Setpoints that moved nothing: not finite, not for this system, not from the companion in
    /// control, or of the wrong kind.
    pub setpoints_refused: u64,
    /// Setpoints ignored because they were stamped older than the last one applied from
    /// their sender (by at most [`REORDER_WINDOW_MS`]).
    pub setpoints_out_of_order: u64,
    /// The link's counters.
    pub link: LinkStats,
    /// Whether the run was stopped from outside before its end.
    pub interrupted: bool,
    /// Whether a lockstep run ended because nobody answered for
    /// [`SitlOptions::companion_timeout_s`].
    pub companion_lost: bool,
    /// Whether the run started (a peer talked to the vehicle): a run that never did recorded
    /// nothing (`sitl --out` leaves an earlier run in its directory as it was).
    pub started: bool,
}

/// Why a simulated flight could not start.
#[derive(Debug)]
pub enum SitlError {
    /// The link (see [`LinkError`]).
    Link(LinkError),
    /// The scenario cannot be flown over MAVLink (a sensor faster than the millisecond clock,
    /// a run longer than `time_boot_ms` counts).
    Scenario(String),
    /// The socket failed while flying.
    Io(std::io::Error),
}

impl std::fmt::Display for SitlError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SitlError::Link(e) => e.fmt(f),
            SitlError::Scenario(m) => f.write_str(m),
            SitlError::Io(e) => write!(f, "link: {e}"),
        }
    }
}

/// The characters of one `STATUSTEXT` (MAVLink's `text[50]`).
pub const STATUSTEXT_CHARS: usize = 50;

/// The `STATUSTEXT` of sitl's own offboard failsafe (att33d-9d: its event, "failsafe: no valid
/// setpoint for 1 s in OFFBOARD: HOLD", is longer than one `STATUSTEXT` holds).
pub const OFFBOARD_LOST_STATUSTEXT: &str = "failsafe: offboard setpoints lost: HOLD";

/// The lowest `output.record_rate_hz` `isotrack sitl` flies with, Hz: its position telemetry
/// goes out once per trace row, and a ground station or companion expects positions at least
/// once a second (the 1 Hz group's rate).
pub const MIN_TELEMETRY_RATE_HZ: f64 = 1.0;

/// Checks what `isotrack sitl` needs of a scenario beyond [`check_wire_times`]: telemetry at
/// least [`MIN_TELEMETRY_RATE_HZ`] (`output.record_rate_hz`), and a home (or a lon/lat field's
/// georeference) the local-to-WGS84 map holds at ([`Frame::of`]).
pub fn check_sitl_scenario(s: &Scenario) -> Result<(), String> {
    let rate = s.spec().output.record_rate_hz;
    if rate.is_nan() || rate < MIN_TELEMETRY_RATE_HZ {
        return Err(format!(
            "output.record_rate_hz = {}: isotrack sitl sends its position telemetry once per trace row, so the rate must be at least {} Hz (0 turns the trace, and the positions, off; the default is 10)",
            Echo(rate),
            Echo(MIN_TELEMETRY_RATE_HZ)
        ));
    }
    crate::wire::check_level(s)?;
    Frame::of(s).map(|_| ())
}

/// Whether a frame of another sender starts the run (see the module's "Start"): a heartbeat of
/// a ground station or companion, or a message addressed to `system_id`.
pub fn starts_the_run(msg: &MavMessage, system_id: u8) -> bool {
    match msg {
        MavMessage::HEARTBEAT(h) => matches!(
            h.mavtype,
            MavType::MAV_TYPE_GCS | MavType::MAV_TYPE_ONBOARD_CONTROLLER
        ),
        m => m.target_system_id() == Some(system_id),
    }
}

/// Whether a command or setpoint addressed to (`target_system`, `target_component`) is this
/// vehicle's (`system_id`, component 1, `MAV_COMP_ID_AUTOPILOT1`): its system and its component
/// or 0 (every component), as PX4 takes them; a command for another component of its system
/// (a camera's, a gimbal's) is that component's to answer.
pub fn for_this_vehicle(target_system: u8, target_component: u8, system_id: u8) -> bool {
    target_system == system_id && matches!(target_component, 0 | 1)
}

/// A `COMMAND_INT` as the `COMMAND_LONG` it stands for (PX4 takes both for one command):
/// `param1` to `param4` as they are, `x`, `y` (scaled integers) and `z` as `param5` to
/// `param7`.
pub fn command_of_int(c: &COMMAND_INT_DATA) -> COMMAND_LONG_DATA {
    COMMAND_LONG_DATA {
        param1: c.param1,
        param2: c.param2,
        param3: c.param3,
        param4: c.param4,
        param5: c.x as f32,
        param6: c.y as f32,
        param7: c.z,
        command: c.command,
        target_system: c.target_system,
        target_component: c.target_component,
        confirmation: 0,
    }
}

/// The ground station's system id (QGroundControl's and MAVProxy's default): it may arm,
/// change the mode and disarm as a pilot would, but never flies the vehicle by setpoints.
pub const GCS_SYSTEM_ID: u8 = 255;

/// `param2` of `MAV_CMD_COMPONENT_ARM_DISARM` that forces it (PX4, ArduPilot): needed to disarm
/// a flying vehicle from another system than the one in control.
pub const FORCE_CODE: f32 = 21196.0;

/// The `time_boot_ms` of a setpoint that answers no sample (`isotrack fly` sends it before its
/// first measurement): applied, but it never answers a lockstep sample nor counts as the
/// sender's clock.
pub const NOT_AN_ANSWER_MS: u32 = u32::MAX;

/// How far back, ms, a setpoint's stamp may be from its sender's last applied one and still
/// count as late (out of order, ignored) rather than a restarted clock (applied). Steps are
/// taken modulo 2^32 ms: a stamp just before the sender's `time_boot_ms` wrapped, coming after
/// one just after, is late too; one just after, coming after one just before, is newer
/// ([`wire::wrapped_forward`]), not a restart.
pub const REORDER_WINDOW_MS: u32 = 10_000;

/// The most senders whose last setpoint stamp the vehicle remembers (the least recent
/// forgotten first).
pub const MAX_SETPOINT_SENDERS: usize = 8;

/// The most events the vehicle logs; later ones are counted, and the count logged at the end.
pub const MAX_EVENTS: usize = 1000;

/// A setpoint that moved the vehicle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Applied {
    /// Its stamp.
    ms: u32,
    /// Whether it is newer than every setpoint its sender sent before (or its sender's
    /// first, or after its clock restarted).
    newer: bool,
    /// Whether the vehicle followed setpoints when it came ([`Autopilot::follows_setpoints`]):
    /// only then may it answer a lockstep sample.
    followed: bool,
}

/// The autopilot's state between samples.
struct Autopilot {
    system_id: u8,
    armed: bool,
    mode: Mode,
    /// The companion in control (the one that armed it or switched it to OFFBOARD, or, armed by
    /// the ground station, the first to send a valid setpoint): `(system, component)`.
    owner: Option<(u32, u8)>,
    /// The source address the owner took control from (UDP): setpoints with the owner's ids
    /// from another address are a second companion with the same ids ([`Autopilot::twin`]).
    owner_addr: Option<std::net::SocketAddr>,
    /// Addresses that sent setpoints with the owner's ids, logged (the most recent
    /// [`MAX_SETPOINT_SENDERS`]).
    twins_logged: Vec<std::net::SocketAddr>,
    /// A fixed wing (in flight whenever armed): a disarm from another system than the owner
    /// needs PX4's force code.
    flying: bool,
    /// The last valid setpoint of the owner: turn rate, rad/s, and the simulated time it came.
    setpoint: Option<(f64, f64)>,
    /// The wall-clock instant of the last valid setpoint (the stream a lockstep vehicle,
    /// whose simulated time stands still while nobody flies it, checks before OFFBOARD).
    setpoint_wall: Option<Instant>,
    /// When setpoints count as streaming ([`Autopilot::streaming`]).
    stream: Stream,
    /// The simulated time of the last switch to OFFBOARD: the offboard failsafe's clock runs
    /// from it or from the last valid setpoint, whichever is later.
    offboard_since_s: f64,
    transport: Transport,
    loiter_radps: f64,
    turn_limit_radps: f64,
    /// The largest turn rate a ground vehicle's yaw-rate setpoint gives, rad/s: the scenario's
    /// turn-rate limit, else [`MAX_GROUND_TURN_RATE_RADPS`].
    ground_max_radps: f64,
    /// A yaw rate beyond `ground_max_radps` has been clamped and logged.
    clamp_logged: bool,
    events: Vec<String>,
    /// Events not logged (past [`MAX_EVENTS`]).
    events_dropped: u64,
    refused: u64,
    out_of_order: u64,
    /// The stamp of the last setpoint applied from each sender, the most recent
    /// [`MAX_SETPOINT_SENDERS`] senders.
    stamps: Vec<((u32, u8), u32)>,
    /// Senders whose heartbeat says `MAV_TYPE_GCS` (MAVSDK's ground station is system 245, not
    /// 255), the most recent [`MAX_GROUND_STATIONS`].
    ground_stations: Vec<(u32, u8)>,
}

/// The most ground stations (by heartbeat) the vehicle remembers.
pub const MAX_GROUND_STATIONS: usize = 8;

/// The largest turn rate a ground vehicle flies from a yaw-rate setpoint when its scenario has
/// no turn-rate limit (`controller.max_turn_rate_radps` unset on the Dubins robot), rad/s:
/// a bound on what a setpoint may ask (a yaw rate of 1e30 rad/s would otherwise be flown),
/// five times the largest command of the default scenario's law (1.98 rad/s).
pub const MAX_GROUND_TURN_RATE_RADPS: f64 = 10.0;

/// When a vehicle counts its setpoints as streaming, as PX4 requires before it switches to
/// OFFBOARD (its offboard signal not lost): a valid setpoint within `within_s` of simulated
/// time (real time), or, in lockstep (where simulated time stands still while nobody flies
/// the vehicle), within `within_wall` of wall time.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stream {
    /// Within this many simulated seconds ([`SitlOptions::setpoint_timeout_s`]).
    Simulated { within_s: f64 },
    /// Within this wall time ([`SitlOptions::companion_timeout_s`]).
    Wall { within: Duration },
}

impl Autopilot {
    /// A disarmed vehicle in MANUAL with no owner, nothing logged: `turn_limit_radps` is the
    /// turn rate a fixed wing's roll setpoints are bounded by (its loiter at half of it),
    /// `ground_max_radps` the ground vehicle's ([`MAX_GROUND_TURN_RATE_RADPS`] without a limit).
    fn new(
        system_id: u8,
        flying: bool,
        stream: Stream,
        transport: Transport,
        turn_limit_radps: f64,
        ground_max_radps: f64,
    ) -> Self {
        Autopilot {
            system_id,
            armed: false,
            mode: Mode::Manual,
            owner: None,
            owner_addr: None,
            twins_logged: Vec::new(),
            flying,
            setpoint: None,
            setpoint_wall: None,
            stream,
            offboard_since_s: 0.0,
            transport,
            loiter_radps: 0.5 * turn_limit_radps,
            turn_limit_radps,
            ground_max_radps,
            clamp_logged: false,
            events: Vec::new(),
            events_dropped: 0,
            refused: 0,
            out_of_order: 0,
            stamps: Vec::new(),
            ground_stations: Vec::new(),
        }
    }

    /// Whether `from` is a ground station: system [`GCS_SYSTEM_ID`], or a sender whose
    /// heartbeat says `MAV_TYPE_GCS`.
    fn is_gcs(&self, from: (u32, u8)) -> bool {
        from.0 == GCS_SYSTEM_ID as u32 || self.ground_stations.contains(&from)
    }

    /// Remembers a ground station's heartbeat.
    fn heard_gcs(&mut self, from: (u32, u8)) {
        if !self.ground_stations.contains(&from) {
            if self.ground_stations.len() == MAX_GROUND_STATIONS {
                self.ground_stations.remove(0);
            }
            self.ground_stations.push(from);
        }
    }

    fn event(&mut self, t_s: f64, what: String) {
        if self.events.len() >= MAX_EVENTS {
            self.events_dropped += 1;
            return;
        }
        self.events.push(format!("t = {} s: {what}", Num(t_s)));
    }

    /// Whether a setpoint of `from` stamped `ms` is applied (`Some(newer)`), or ignored as out
    /// of order (`None`, counted). Records the stamp of an applied one.
    fn order(&mut self, t_s: f64, from: (u32, u8), ms: u32) -> Option<bool> {
        if ms == NOT_AN_ANSWER_MS {
            return Some(false);
        }
        let i = self.stamps.iter().position(|(f, _)| *f == from);
        // Steps modulo 2^32: the sender's clock wraps after 49.7 days (see
        // `wire::MAX_WRAP_STEP_MS`).
        let newer = match i.map(|i| self.stamps[i].1) {
            None => true,
            Some(last) if ms == last => false,
            // Older by at most the window, across the wrap or not: late.
            Some(last) if last.wrapping_sub(ms) <= REORDER_WINDOW_MS => {
                self.out_of_order += 1;
                return None;
            }
            Some(last) if ms > last || wire::wrapped_forward(last, ms) => true,
            Some(last) => {
                self.event(
                    t_s,
                    format!(
                        "setpoint clock of system {}, component {} went back from {last} to {ms} ms: taken as restarted",
                        from.0, from.1
                    ),
                );
                true
            }
        };
        if let Some(i) = i {
            self.stamps.remove(i);
        } else if self.stamps.len() == MAX_SETPOINT_SENDERS {
            self.stamps.remove(0);
        }
        self.stamps.push((from, ms));
        Some(newer)
    }

    /// Whether the vehicle follows setpoints: armed, in OFFBOARD (ArduPilot's GUIDED is the
    /// same mode here). Only then does a lockstep run advance on an answer: while disarmed,
    /// or in MANUAL, HOLD or RETURN, nobody flies it by setpoints, and simulated time stands
    /// still (a disarmed vehicle does not move).
    fn follows_setpoints(&self) -> bool {
        self.armed && self.mode == Mode::Offboard
    }

    /// Whether setpoints are streaming at simulated time `t_s` ([`Stream`]): PX4 refuses
    /// OFFBOARD without them.
    fn streaming(&self, t_s: f64) -> bool {
        match self.stream {
            Stream::Simulated { within_s } => {
                self.setpoint.is_some_and(|(_, at)| t_s - at <= within_s)
            }
            Stream::Wall { within } => self.setpoint_wall.is_some_and(|w| w.elapsed() <= within),
        }
    }

    /// Whether the offboard failsafe trips at simulated time `t_s`: armed in OFFBOARD with no
    /// valid setpoint for more than `timeout_s`, counted from the later of the last valid
    /// setpoint and the switch to OFFBOARD.
    fn offboard_lost(&self, t_s: f64, timeout_s: f64) -> bool {
        self.follows_setpoints()
            && self
                .setpoint
                .is_none_or(|(_, at)| t_s - at.max(self.offboard_since_s) > timeout_s)
    }

    /// The turn rate the vehicle holds from a sample at `pose`.
    fn turn_rate(&self, pose: Option<Pose2>) -> f64 {
        if !self.armed {
            return 0.0;
        }
        match self.mode {
            Mode::Manual => 0.0,
            Mode::Hold => self.loiter_radps,
            Mode::Offboard => self.setpoint.map_or(0.0, |(w, _)| w),
            Mode::Return => {
                let Some(p) = pose else { return 0.0 };
                let d = p.position.norm();
                if d < 2.0 * self.loiter_radius_m() {
                    return self.loiter_radps;
                }
                // Bearing to home, proportional steering saturated at the turn-rate limit.
                let bearing = (-p.position.y).atan2(-p.position.x);
                let e = wrap_angle(bearing - p.heading_rad);
                (2.0 * e).clamp(-self.turn_limit_radps, self.turn_limit_radps)
            }
        }
    }

    fn loiter_radius_m(&self) -> f64 {
        match self.transport {
            Transport::FixedWing { airspeed_mps } => airspeed_mps / self.loiter_radps,
            Transport::Ground => 1.0,
        }
    }

    /// Whether a setpoint from `from` at source address `addr` comes with the owner's system
    /// and component id but from another address than the one that took control: a second
    /// companion with the same ids (two `fly` with the default ids). Refused (counted), each
    /// address logged once. Not for a ground station's ids (`MAV_TYPE_GCS` heartbeat).
    fn twin(&mut self, t_s: f64, from: (u32, u8), addr: Option<std::net::SocketAddr>) -> bool {
        let (Some(a), Some(o)) = (addr, self.owner_addr) else {
            return false;
        };
        // A ground station (by its heartbeat) is one operator whatever socket it speaks from.
        if self.owner != Some(from) || a == o || self.is_gcs(from) {
            return false;
        }
        self.refused += 1;
        if !self.twins_logged.contains(&a) {
            if self.twins_logged.len() == MAX_SETPOINT_SENDERS {
                self.twins_logged.remove(0);
            }
            self.twins_logged.push(a);
            self.event(
                t_s,
                format!(
                    "refused setpoints from {a} with the ids of the companion in control (system {}, component {}), which took control from {o}: a second companion with the same ids (give each its own --system-id); logged once per address",
                    from.0, from.1
                ),
            );
        }
        true
    }

    /// After a command or setpoint from source address `addr`: a new owner took control from
    /// it; no owner, no address.
    fn owner_seen(&mut self, had_owner: bool, addr: Option<std::net::SocketAddr>) {
        if self.owner.is_none() {
            self.owner_addr = None;
        } else if !had_owner {
            self.owner_addr = addr;
        }
    }

    /// Whether `from` may command the vehicle: anyone while it is disarmed or has no owner,
    /// else its owner and the ground station ([`GCS_SYSTEM_ID`]).
    fn may_command(&self, from: (u32, u8)) -> bool {
        !self.armed || self.is_gcs(from) || self.owner.is_none_or(|o| o == from)
    }

    fn deny(&mut self, t_s: f64, from: (u32, u8), what: &str) -> MavResult {
        self.event(
            t_s,
            format!(
                "refused {what} from system {}, component {}",
                from.0, from.1
            ),
        );
        MavResult::MAV_RESULT_DENIED
    }

    /// Handles a command; returns the acknowledgement's result.
    fn command(&mut self, t_s: f64, from: (u32, u8), c: &COMMAND_LONG_DATA) -> MavResult {
        match c.command {
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => self.arm_disarm(t_s, from, c),
            MavCmd::MAV_CMD_DO_SET_MODE if !self.may_command(from) => {
                self.deny(t_s, from, "mode change (another system has control)")
            }
            MavCmd::MAV_CMD_DO_SET_MODE => self.set_mode(t_s, from, c),
            _ => MavResult::MAV_RESULT_UNSUPPORTED,
        }
    }

    /// `MAV_CMD_COMPONENT_ARM_DISARM` as PX4 answers it.
    fn arm_disarm(&mut self, t_s: f64, from: (u32, u8), c: &COMMAND_LONG_DATA) -> MavResult {
        let gcs = self.is_gcs(from);
        // As PX4: forced exactly when param2 is the force code; any other value (0, or
        // the NaN that MAVSDK puts in parameters it does not use) is an ordinary request.
        let forced = c.param2 == FORCE_CODE;
        if c.param1 == 1.0 {
            if !self.may_command(from) {
                return self.deny(t_s, from, "arming (another system has control)");
            }
            if !self.armed {
                self.armed = true;
                // The ground station arms as a pilot: it takes no control.
                self.owner = (!gcs).then_some(from);
                self.event(t_s, format!("armed by system {}", from.0));
            }
            MavResult::MAV_RESULT_ACCEPTED
        } else if c.param1 == 0.0 {
            let owner = self.owner == Some(from);
            // As PX4 ("Disarming denied: not landed"): an unforced disarm in the air
            // is refused whoever sends it, the owner too.
            if self.armed && self.flying && !forced {
                return self.deny(
                    t_s,
                    from,
                    "disarm in flight (not landed: needs force code 21196)",
                );
            }
            if self.armed && !owner && !gcs && !forced {
                return self.deny(t_s, from, "disarm (another system has control)");
            }
            self.armed = false;
            self.owner = None;
            self.event(t_s, format!("disarmed by system {}", from.0));
            MavResult::MAV_RESULT_ACCEPTED
        } else {
            MavResult::MAV_RESULT_DENIED
        }
    }

    /// `MAV_CMD_DO_SET_MODE` (PX4's custom modes) from a system that may command.
    fn set_mode(&mut self, t_s: f64, from: (u32, u8), c: &COMMAND_LONG_DATA) -> MavResult {
        let gcs = self.is_gcs(from);
        match Mode::from_px4(c.param2, c.param3) {
            Some(Mode::Offboard) if c.param1 as u32 & 1 == 1 && !self.streaming(t_s) => {
                // As PX4: no OFFBOARD before setpoints stream (its offboard signal lost).
                self.event(
                    t_s,
                    format!(
                        "refused OFFBOARD from system {}, component {}: no setpoint streaming (a valid one must come first)",
                        from.0, from.1
                    ),
                );
                MavResult::MAV_RESULT_TEMPORARILY_REJECTED
            }
            Some(m) if c.param1 as u32 & 1 == 1 => {
                if m != self.mode {
                    self.event(t_s, format!("mode {} by system {}", m.name(), from.0));
                    if m == Mode::Offboard {
                        self.offboard_since_s = t_s;
                    }
                }
                self.mode = m;
                if m == Mode::Offboard && !gcs && self.owner.is_none() {
                    self.owner = Some(from);
                }
                MavResult::MAV_RESULT_ACCEPTED
            }
            _ => {
                self.event(
                    t_s,
                    format!(
                        "refused mode (base {}, main {}, sub {}) from system {}",
                        c.param1, c.param2, c.param3, from.0
                    ),
                );
                MavResult::MAV_RESULT_DENIED
            }
        }
    }

    /// Handles a setpoint; returns its time stamp (and whether it is its sender's newest) if
    /// it is a valid setpoint, in order, of the companion in control, of any companion on
    /// board (a component of the vehicle's own system: as in PX4, setpoints are not bound to
    /// who switched the mode), or of anyone while no companion is in control (MAVSDK as a
    /// ground station flying offboard itself included); never of system 255, the operator's
    /// ground station.
    fn setpoint(
        &mut self,
        t_s: f64,
        from: (u32, u8),
        s: &SET_ATTITUDE_TARGET_DATA,
    ) -> Option<Applied> {
        let on_board = from.0 == self.system_id as u32;
        if !for_this_vehicle(s.target_system, s.target_component, self.system_id)
            || (self.owner.is_some_and(|o| o != from) && !on_board)
            || from.0 == GCS_SYSTEM_ID as u32
        {
            self.refused += 1;
            return None;
        }
        if !used_fields_finite(s) {
            self.refused += 1;
            return None;
        }
        let w = self.turn_rate_of_setpoint(t_s, from, s);
        match w {
            Some(w) if w.is_finite() => {
                let newer = self.order(t_s, from, s.time_boot_ms)?;
                if self.armed && self.owner.is_none() {
                    // Armed by the ground station: the first companion to fly it owns it.
                    self.owner = Some(from);
                }
                self.setpoint = Some((w, t_s));
                self.setpoint_wall = Some(Instant::now());
                Some(Applied {
                    ms: s.time_boot_ms,
                    newer,
                    followed: self.follows_setpoints(),
                })
            }
            _ => {
                self.refused += 1;
                None
            }
        }
    }

    /// The turn rate a setpoint asks of this vehicle, rad/s: a fixed wing's from the roll of its
    /// attitude (or the coordinated-turn roll of its yaw rate), a ground vehicle's from its yaw
    /// rate, clamped to the turn-rate limit (logged once); `None` where the mask leaves nothing
    /// this vehicle flies by.
    fn turn_rate_of_setpoint(
        &mut self,
        t_s: f64,
        from: (u32, u8),
        s: &SET_ATTITUDE_TARGET_DATA,
    ) -> Option<f64> {
        let m = s.type_mask;
        let attitude =
            !m.contains(AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE);
        let yaw_rate =
            !m.contains(AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE);
        match self.transport {
            Transport::FixedWing { airspeed_mps } if attitude => {
                wire::roll_of_quaternion(s.q).map(|r| wire::turn_rate_of_roll(r, airspeed_mps))
            }
            // A fixed wing turns by banking: the yaw rate's coordinated-turn roll
            // atan(r V / g), within the bank limit, as the roll path.
            Transport::FixedWing { airspeed_mps } if yaw_rate => {
                wire::turn_rate_of_yaw_rate(s.body_yaw_rate).map(|w| {
                    wire::turn_rate_of_roll(wire::roll_of_turn_rate(w, airspeed_mps), airspeed_mps)
                })
            }
            // Within the scenario's turn-rate limit (else MAX_GROUND_TURN_RATE_RADPS), as the
            // single run's output stage bounds the law.
            Transport::Ground if yaw_rate => {
                wire::turn_rate_of_yaw_rate(s.body_yaw_rate).map(|w| {
                    let max = self.ground_max_radps;
                    if w.abs() > max && !self.clamp_logged {
                        self.clamp_logged = true;
                        self.event(
                            t_s,
                            format!(
                                "yaw rate {:?} rad/s from system {}, component {} clamped to the turn-rate limit {} rad/s (logged once)",
                                s.body_yaw_rate,
                                from.0,
                                from.1,
                                Echo(max)
                            ),
                        );
                    }
                    w.clamp(-max, max)
                })
            }
            _ => None,
        }
    }
}

/// A received frame's sender.
/// Every field a setpoint's mask does not ignore is a number: the vehicle flies at the scenario's
/// speed and ignores the thrust and the roll and pitch rates' values, but a setpoint carrying an
/// infinite thrust is no valid setpoint.
fn used_fields_finite(s: &SET_ATTITUDE_TARGET_DATA) -> bool {
    let m = s.type_mask;
    [
        (
            AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE,
            s.body_roll_rate,
        ),
        (
            AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE,
            s.body_pitch_rate,
        ),
        (
            AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE,
            s.thrust,
        ),
    ]
    .iter()
    .all(|(bit, v)| m.contains(*bit) || v.is_finite())
}

fn sender(r: &Received) -> (u32, u8) {
    (r.header.system_id, r.header.component_id)
}

struct Sitl<'a> {
    link: Link,
    ap: Autopilot,
    home: Frame,
    scenario: &'a Scenario,
    stop: Arc<AtomicBool>,
    /// The next whole simulated second at which the 1 Hz group goes out.
    next_slow_s: f64,
    last_heartbeat_wall: Instant,
    /// [`SitlOptions::heartbeat_hz`]'s period: heartbeats on it only.
    heartbeat_period: Option<Duration>,
    speed_mps: f64,
    /// When the last valid frame of another sender came.
    last_heard: Instant,
    /// Telemetry (a position) has gone out.
    telemetry_sent: bool,
    /// The first MAVLink 1 frame has been logged.
    mavlink1_logged: bool,
    /// A peer has talked to the vehicle ([`starts_the_run`]).
    started: bool,
}

impl Sitl<'_> {
    fn send(&mut self, m: MavMessage) -> Result<(), SitlError> {
        self.link.send(&m).map(|_| ()).map_err(SitlError::Io)
    }

    /// A heartbeat after a change of mode or arming: at once, unless it beats at a fixed rate
    /// only ([`SitlOptions::heartbeat_hz`]).
    fn changed_heartbeat(&mut self) -> Result<(), SitlError> {
        if self.heartbeat_period.is_none() {
            self.heartbeat(false)?;
        }
        Ok(())
    }

    fn heartbeat(&mut self, ended: bool) -> Result<(), SitlError> {
        let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        if self.ap.armed {
            base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        let flying = self.scenario.is_flying();
        self.last_heartbeat_wall = Instant::now();
        self.send(MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: self.ap.mode.custom_mode(),
            mavtype: if flying {
                MavType::MAV_TYPE_FIXED_WING
            } else {
                MavType::MAV_TYPE_GROUND_ROVER
            },
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: base,
            system_status: if ended {
                MavState::MAV_STATE_POWEROFF
            } else {
                MavState::MAV_STATE_ACTIVE
            },
            mavlink_version: 3,
        }))
    }

    /// A `COMMAND_ACK` addressed, as PX4 addresses it, to the command's sender: its
    /// `target_system` and `target_component` extension fields (MAVLink 2), so that a ground
    /// station and a companion on one link each tell their own acknowledgements from the
    /// other's.
    fn command_ack(
        &mut self,
        command: MavCmd,
        result: MavResult,
        to: (u32, u8),
    ) -> Result<(), SitlError> {
        let ack = MavMessage::COMMAND_ACK(COMMAND_ACK_DATA { command, result });
        // The extensions after `command` (2 bytes) and `result` (1): `progress` (u8, 0),
        // `result_param2` (i32, 0), `target_system`, `target_component`.
        let to_system = u8::try_from(to.0).unwrap_or(0);
        let extensions = [0, 0, 0, 0, 0, to_system, to.1];
        self.link
            .send_extended(
                &ack,
                <COMMAND_ACK_DATA as mavlink::MessageData>::EXTRA_CRC,
                3,
                &extensions,
            )
            .map(|_| ())
            .map_err(SitlError::Io)
    }

    /// `EXTENDED_SYS_STATE`: the landed state, as PX4's land detectors report it here: a
    /// fixed wing armed is in the air (the scenario flies it from its start; disarmed, it is
    /// on the ground); a ground vehicle is always on the ground. A ground station (MAVSDK's
    /// `in_air`, `landed_state`) reads it.
    fn extended_sys_state(&mut self) -> Result<(), SitlError> {
        let landed_state = if self.ap.flying && self.ap.armed {
            MavLandedState::MAV_LANDED_STATE_IN_AIR
        } else {
            MavLandedState::MAV_LANDED_STATE_ON_GROUND
        };
        self.send(MavMessage::EXTENDED_SYS_STATE(EXTENDED_SYS_STATE_DATA {
            vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
            landed_state,
        }))
    }

    /// A `STATUSTEXT` of `text`, at most [`STATUSTEXT_CHARS`] bytes (a longer one is cut:
    /// keep them short).
    fn statustext(&mut self, severity: MavSeverity, text: &str) -> Result<(), SitlError> {
        let mut bytes = [0u8; 50];
        for (b, c) in bytes.iter_mut().zip(text.bytes()) {
            *b = c;
        }
        self.send(MavMessage::STATUSTEXT(STATUSTEXT_DATA {
            severity,
            text: bytes.into(),
        }))
    }

    /// The once-a-second group, when `t_s` has reached it.
    fn slow_group(&mut self, t_s: f64) -> Result<(), SitlError> {
        if t_s < self.next_slow_s {
            return Ok(());
        }
        self.next_slow_s = t_s.floor() + 1.0;
        let ms = wire::time_ms(t_s).unwrap_or(u32::MAX);
        if self.heartbeat_period.is_none() {
            self.heartbeat(false)?;
        }
        // Present, enabled and healthy: what a ground station's health reads (MAVSDK: the gyro,
        // accelerometer and magnetometer calibrations, GPS for the global and local position,
        // the pre-arm check for `is_armable`; home comes with `HOME_POSITION`).
        let sensors = MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_GPS
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_GYRO
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_ACCEL
            | MavSysStatusSensor::MAV_SYS_STATUS_SENSOR_3D_MAG
            | MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK;
        self.send(MavMessage::SYS_STATUS(SYS_STATUS_DATA {
            onboard_control_sensors_present: sensors,
            onboard_control_sensors_enabled: sensors,
            onboard_control_sensors_health: sensors,
            load: 0,
            voltage_battery: u16::MAX,
            current_battery: -1,
            battery_remaining: -1,
            ..Default::default()
        }))?;
        self.extended_sys_state()?;
        let unix_us = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_micros() as u64);
        self.send(MavMessage::SYSTEM_TIME(SYSTEM_TIME_DATA {
            time_unix_usec: unix_us,
            time_boot_ms: ms,
        }))?;
        let h = self.home.home;
        self.send(MavMessage::HOME_POSITION(HOME_POSITION_DATA {
            latitude: (h.lat_deg * 1e7).round() as i32,
            longitude: (h.lon_deg * 1e7).round() as i32,
            altitude: (h.alt_m * 1e3).round() as i32,
            q: [1.0, 0.0, 0.0, 0.0],
            ..Default::default()
        }))
    }

    /// The telemetry of one trace row.
    fn telemetry(&mut self, r: &TraceRow) -> Result<(), SitlError> {
        self.slow_group(r.t_s)?;
        self.telemetry_sent = true;
        let ms = wire::time_ms(r.t_s).unwrap_or(u32::MAX);
        let (lat, lon) = self.home.to_lat_lon_deg(r.x_m, r.y_m);
        let t = r.telemetry;
        let alt_rel = t.map_or(0.0, |t| t.altitude_m);
        let airspeed = t.map_or(self.speed_mps, |t| t.airspeed_mps);
        let roll = t.map_or(0.0, |t| t.roll_rad);
        // Yaw: the ground course, clockwise from north.
        let yaw = wrap_angle(std::f64::consts::FRAC_PI_2 - r.heading_rad);
        let (vn, ve) = (self.speed_mps * yaw.cos(), self.speed_mps * yaw.sin());
        let hdg_deg = yaw.to_degrees().rem_euclid(360.0);
        // A position that is no number (a diverged run) goes out as unknown (`INT32_MAX`,
        // outside every latitude; `NaN` locally), never as 0 deg, 0 deg.
        let deg_e7 = |d: f64| {
            if d.is_finite() {
                (d * 1e7).round() as i32
            } else {
                i32::MAX
            }
        };
        self.send(MavMessage::GLOBAL_POSITION_INT(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: ms,
            lat: deg_e7(lat),
            lon: deg_e7(lon),
            alt: ((self.home.home.alt_m + alt_rel) * 1e3).round() as i32,
            relative_alt: (alt_rel * 1e3).round() as i32,
            vx: (vn * 100.0).round().clamp(-32767.0, 32767.0) as i16,
            vy: (ve * 100.0).round().clamp(-32767.0, 32767.0) as i16,
            vz: 0,
            hdg: ((hdg_deg * 100.0).round() as u16) % 36000,
        }))?;
        self.send(MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
            time_boot_ms: ms,
            x: r.y_m as f32,
            y: r.x_m as f32,
            z: -alt_rel as f32,
            vx: vn as f32,
            vy: ve as f32,
            vz: 0.0,
        }))?;
        self.send(MavMessage::ATTITUDE(ATTITUDE_DATA {
            time_boot_ms: ms,
            roll: roll as f32,
            pitch: 0.0,
            yaw: yaw as f32,
            rollspeed: 0.0,
            pitchspeed: 0.0,
            yawspeed: (-r.omega_radps) as f32,
        }))?;
        self.send(MavMessage::VFR_HUD(VFR_HUD_DATA {
            airspeed: airspeed as f32,
            groundspeed: self.speed_mps as f32,
            alt: (self.home.home.alt_m + alt_rel) as f32,
            climb: 0.0,
            heading: hdg_deg.round() as i16 % 360,
            throttle: 50,
        }))?;
        Ok(())
    }

    /// Handles what arrives within `timeout`; returns the setpoints applied.
    fn handle_inbound(&mut self, t_s: f64, timeout: Duration) -> Result<Vec<Applied>, SitlError> {
        if self
            .heartbeat_period
            .is_some_and(|p| self.last_heartbeat_wall.elapsed() >= p)
        {
            self.heartbeat(false)?;
        }
        let got = self.link.poll(timeout).map_err(SitlError::Io)?;
        if self.link.stats.mavlink1_frames > 0 && !self.mavlink1_logged {
            self.mavlink1_logged = true;
            self.ap.event(
                t_s,
                "MAVLink 1 frames received and ignored: this vehicle speaks MAVLink 2 only".into(),
            );
        }
        let mut answers = Vec::new();
        let me = (self.ap.system_id as u32, 1u8);
        for r in got {
            let from = sender(&r);
            if from == me {
                continue;
            }
            self.last_heard = Instant::now();
            self.started |= starts_the_run(&r.msg, self.ap.system_id);
            match &r.msg {
                MavMessage::COMMAND_LONG(_) | MavMessage::COMMAND_INT(_) => {
                    let c = match &r.msg {
                        MavMessage::COMMAND_INT(c) => command_of_int(c),
                        MavMessage::COMMAND_LONG(c) => c.clone(),
                        _ => continue,
                    };
                    if !for_this_vehicle(c.target_system, c.target_component, self.ap.system_id) {
                        continue;
                    }
                    let had_owner = self.ap.owner.is_some();
                    let result = self.ap.command(t_s, from, &c);
                    self.ap.owner_seen(had_owner, r.from);
                    self.command_ack(c.command, result, from)?;
                    // The new state at once (PX4 reports it only in the next heartbeat:
                    // `heartbeat_hz`).
                    self.changed_heartbeat()?;
                    self.extended_sys_state()?;
                }
                MavMessage::HEARTBEAT(h) if h.mavtype == MavType::MAV_TYPE_GCS => {
                    self.ap.heard_gcs(from);
                }
                MavMessage::SET_ATTITUDE_TARGET(s) => {
                    if s.target_system == self.ap.system_id && self.ap.twin(t_s, from, r.from) {
                        continue;
                    }
                    let had_owner = self.ap.owner.is_some();
                    if let Some(a) = self.ap.setpoint(t_s, from, s) {
                        answers.push(a);
                    }
                    self.ap.owner_seen(had_owner, r.from);
                }
                _ => {}
            }
        }
        Ok(answers)
    }
}

/// A trace sink that keeps the rows for telemetry and passes them on.
struct Tee<'a, S: ?Sized> {
    rows: Vec<TraceRow>,
    sink: &'a mut S,
}

impl<S: TraceSink + ?Sized> TraceSink for Tee<'_, S> {
    fn record(&mut self, row: &TraceRow) {
        self.rows.push(*row);
        self.sink.record(row);
    }
}

/// Runs `scenario` as a MAVLink vehicle on `opts.url`, recording its trace into `sink`;
/// `on_ready` is told the local address once the link is open (the port of `udpin:HOST:0`;
/// never called for a serial link: see [`run_sitl_on`]). Waits for the first message of a peer
/// before the run starts.
pub fn run_sitl<S: TraceSink + ?Sized>(
    scenario: &Scenario,
    opts: &SitlOptions,
    sink: &mut S,
    on_ready: &mut dyn FnMut(SocketAddr),
) -> Result<SitlReport, SitlError> {
    run_sitl_on(scenario, opts, sink, &mut |l| {
        if let Ok(a) = l.local_addr() {
            on_ready(a)
        }
    })
}

/// As [`run_sitl`], `on_ready` given the link itself once it is open (its address, or its
/// serial device: [`Link::describe`]).
pub fn run_sitl_on<S: TraceSink + ?Sized>(
    scenario: &Scenario,
    opts: &SitlOptions,
    sink: &mut S,
    on_ready: &mut dyn FnMut(&Link),
) -> Result<SitlReport, SitlError> {
    check_wire_times(scenario).map_err(SitlError::Scenario)?;
    check_sitl_scenario(scenario).map_err(SitlError::Scenario)?;
    let frame = Frame::of(scenario).map_err(SitlError::Scenario)?;
    let mut link = Link::open(&opts.url, opts.system_id, 1).map_err(SitlError::Link)?;
    link.set_peer_timeout(companion_timeout(opts));
    on_ready(&link);
    let mut sitl = Sitl::new(scenario, opts, link, frame);
    sitl.wait_for_peer()?;
    let mut ep = scenario.episode(None, None);
    let mut flown = Vec::new();
    let ended = sitl.fly(&mut ep, opts, sink, &mut flown)?;
    let t_end = ep.t_s();
    let result = ep.finish_traced(&mut Tee {
        rows: Vec::new(),
        sink: &mut *sink,
    });
    let how = match ended {
        Ended::Interrupted => "interrupted",
        Ended::CompanionLost => "companion_lost",
        Ended::Run => result.outcome.as_str(),
    };
    sitl.log_counts();
    sitl.ap
        .events
        .push(format!("t = {} s: run ended ({how})", Num(t_end)));
    let text = format!("isotrack sitl: run ended ({how})");
    sitl.statustext(MavSeverity::MAV_SEVERITY_NOTICE, &text)?;
    for _ in 0..3 {
        sitl.heartbeat(true)?;
    }
    Ok(SitlReport {
        result,
        flown,
        events: sitl.ap.events,
        setpoints_refused: sitl.ap.refused,
        setpoints_out_of_order: sitl.ap.out_of_order,
        link: sitl.link.stats,
        interrupted: ended == Ended::Interrupted,
        companion_lost: ended == Ended::CompanionLost,
        started: sitl.started,
    })
}

/// [`SitlOptions::companion_timeout_s`] as a wall time (a day where it is too large to be one).
fn companion_timeout(opts: &SitlOptions) -> Duration {
    Duration::try_from_secs_f64(opts.companion_timeout_s.max(0.0))
        .unwrap_or(Duration::from_secs(86_400))
}

/// How a sitl run's loop ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ended {
    /// The episode ended (its outcome says how).
    Run,
    /// Stopped from outside ([`SitlOptions::stop`]: Ctrl-C).
    Interrupted,
    /// In lockstep, nobody answered for [`SitlOptions::companion_timeout_s`].
    CompanionLost,
}

impl<'a> Sitl<'a> {
    /// The vehicle of `scenario` on `link`, disarmed in MANUAL, before any peer has talked.
    fn new(scenario: &'a Scenario, opts: &SitlOptions, link: Link, home: Frame) -> Self {
        let turn_limit = scenario.max_turn_rate_radps().unwrap_or(0.2);
        let stream = match opts.pace {
            Pace::RealTime { .. } => Stream::Simulated {
                within_s: opts.setpoint_timeout_s,
            },
            Pace::Lockstep => Stream::Wall {
                within: companion_timeout(opts),
            },
        };
        let ap = Autopilot::new(
            opts.system_id,
            scenario.is_flying(),
            stream,
            Transport::of(scenario),
            turn_limit,
            scenario
                .max_turn_rate_radps()
                .unwrap_or(MAX_GROUND_TURN_RATE_RADPS),
        );
        Sitl {
            link,
            ap,
            home,
            scenario,
            stop: opts.stop.clone(),
            next_slow_s: 0.0,
            last_heartbeat_wall: Instant::now(),
            heartbeat_period: match opts.pace {
                Pace::RealTime { .. } => opts
                    .heartbeat_hz
                    .filter(|hz| hz.is_finite() && *hz > 0.0)
                    .and_then(|hz| Duration::try_from_secs_f64(1.0 / hz).ok()),
                Pace::Lockstep => None,
            },
            speed_mps: scenario.start_speed_mps(scenario.start()),
            last_heard: Instant::now(),
            telemetry_sent: false,
            mavlink1_logged: false,
            started: false,
        }
    }
}

impl Sitl<'_> {
    /// Waits until a peer talks to the vehicle (a `udpin:` link learns its peer from its first
    /// message; a stray frame starts nothing) or the run is stopped. Meanwhile the vehicle
    /// beats once a wall-clock second to the peers it has (a `udpout:`/`tcpout:`/serial link's
    /// own: a ground station such as MAVSDK waits for a vehicle's heartbeat before it says
    /// anything).
    fn wait_for_peer(&mut self) -> Result<(), SitlError> {
        let mut beaten = false;
        while !self.started {
            if self.stop.load(Ordering::Relaxed) {
                break;
            }
            if !beaten
                || self.last_heartbeat_wall.elapsed()
                    >= self.heartbeat_period.unwrap_or(Duration::from_secs(1))
            {
                beaten = true;
                self.heartbeat(false)?;
            }
            self.handle_inbound(0.0, Duration::from_millis(100))?;
        }
        if self.started && self.heartbeat_period.is_some() {
            // A peer is there now (a `udpin:` link's first beats had nowhere to go): beat at
            // once, as PX4 beats from its boot, then every period (ver33c-3).
            self.heartbeat(false)?;
        }
        Ok(())
    }

    /// Flies the episode sample by sample: each sample's rows go out as telemetry (in real
    /// time: at their wall-clock instants), the measurement as `NAMED_VALUE_FLOAT`, then the
    /// vehicle turns as its setpoints say (lockstep: once the companion has answered the
    /// sample); the turn rate flown at each sample is pushed onto `flown`.
    fn fly<S: TraceSink + ?Sized>(
        &mut self,
        ep: &mut ScenarioEpisode,
        opts: &SitlOptions,
        sink: &mut S,
        flown: &mut Vec<(u32, f64)>,
    ) -> Result<Ended, SitlError> {
        let wall0 = Instant::now();
        loop {
            if self.stop.load(Ordering::Relaxed) {
                return Ok(Ended::Interrupted);
            }
            let mut tee = Tee {
                rows: Vec::new(),
                sink: &mut *sink,
            };
            let sample = ep.run_to_sample_traced(&mut tee);
            let rows = std::mem::take(&mut tee.rows);
            for r in &rows {
                if let Pace::RealTime { speedup } = opts.pace {
                    wait_until(
                        self,
                        r.t_s,
                        wall0 + Duration::from_secs_f64(r.t_s / speedup),
                    )?;
                }
                self.telemetry(r)?;
            }
            let Some(sample) = sample else {
                return Ok(Ended::Run);
            };
            let t = sample.measurement.t_s;
            let ms = wire::time_ms(t).unwrap_or(u32::MAX);
            if let Pace::RealTime { speedup } = opts.pace {
                wait_until(self, t, wall0 + Duration::from_secs_f64(t / speedup))?;
            }
            self.slow_group(t)?;
            let iso = measurement_message(ms, sample.measurement.value);
            self.send(iso.clone())?;
            match opts.pace {
                Pace::Lockstep => {
                    if let Some(ended) = self.await_answer(&sample, ms, &iso, opts)? {
                        return Ok(ended);
                    }
                }
                Pace::RealTime { .. } => {
                    self.handle_inbound(t, Duration::ZERO)?;
                    self.offboard_failsafe(t, opts.setpoint_timeout_s)?;
                }
            }
            let w = self.ap.turn_rate(Some(sample.pose));
            flown.push((ms, w));
            let mut tee = Tee {
                rows: Vec::new(),
                sink: &mut *sink,
            };
            ep.command_traced(w, &mut tee);
            for r in &std::mem::take(&mut tee.rows) {
                self.telemetry(r)?;
            }
        }
    }

    /// In lockstep, waits for the companion's answer to the sample stamped `ms` (a setpoint
    /// followed, stamped `ms` or newer): `None` once it came, else how the run ends (stopped,
    /// or nobody heard from for [`SitlOptions::companion_timeout_s`]). Every wall-clock second
    /// without an answer the heartbeat and the sample go again.
    fn await_answer(
        &mut self,
        sample: &Sample,
        ms: u32,
        iso: &MavMessage,
        opts: &SitlOptions,
    ) -> Result<Option<Ended>, SitlError> {
        let t = sample.measurement.t_s;
        loop {
            if self.stop.load(Ordering::Relaxed) {
                return Ok(Some(Ended::Interrupted));
            }
            let answers = self.handle_inbound(t, Duration::from_millis(50))?;
            if answers
                .iter()
                .any(|a| a.followed && (a.ms == ms || a.newer))
            {
                return Ok(None);
            }
            if self.last_heard.elapsed() > companion_timeout(opts) {
                let what = format!(
                    "no message from anyone for {} s: the companion is gone, run ended",
                    Echo(opts.companion_timeout_s)
                );
                self.ap.event(t, what);
                return Ok(Some(Ended::CompanionLost));
            }
            if self.last_heartbeat_wall.elapsed() >= Duration::from_secs(1) {
                // A lost datagram must not stall the run: the sample goes again with the
                // heartbeat (the companion answers a repeat with its answer again).
                self.heartbeat(false)?;
                if !self.telemetry_sent {
                    // The first sample's position comes with its answer's step: a companion
                    // that waits for a position before taking control gets the sample's pose
                    // now.
                    let row = self.sample_row(sample);
                    self.telemetry(&row)?;
                }
                self.send(iso.clone())?;
            }
        }
    }

    /// The trace row of a sample's pose, before any command (turn rate 0).
    fn sample_row(&self, sample: &Sample) -> TraceRow {
        let p = sample.pose;
        TraceRow {
            t_s: sample.measurement.t_s,
            x_m: p.position.x,
            y_m: p.position.y,
            heading_rad: p.heading_rad,
            s: sample.true_value,
            error: sample.true_value - self.scenario.level(),
            omega_radps: 0.0,
            s_measured: Some(sample.measurement.value),
            telemetry: None,
        }
    }

    /// PX4's offboard failsafe in real time: no valid setpoint for `timeout_s` in OFFBOARD
    /// switches to HOLD, logged, told by STATUSTEXT and a heartbeat at once.
    fn offboard_failsafe(&mut self, t_s: f64, timeout_s: f64) -> Result<(), SitlError> {
        if !self.ap.offboard_lost(t_s, timeout_s) {
            return Ok(());
        }
        self.ap.mode = Mode::Hold;
        let what = format!(
            "failsafe: no valid setpoint for {} s in OFFBOARD: HOLD",
            Echo(timeout_s)
        );
        self.ap.event(t_s, what);
        // STATUSTEXT holds 50 characters (MAVLink 2 chunks them beyond, which not every
        // reader joins): the short form, the event says it all.
        self.statustext(MavSeverity::MAV_SEVERITY_WARNING, OFFBOARD_LOST_STATUSTEXT)?;
        self.changed_heartbeat()
    }

    /// The end's counts in the log: events past the bound, setpoints out of order, junk.
    fn log_counts(&mut self) {
        if self.ap.events_dropped > 0 {
            // Past the bound: the count, and the end, are logged all the same.
            let n = self.ap.events_dropped;
            self.ap.events.push(format!("{n} more events not logged"));
        }
        if self.ap.out_of_order > 0 {
            let n = self.ap.out_of_order;
            self.ap.events.push(format!(
                "{n} setpoints out of order ignored (stamped older than their sender's last)"
            ));
        }
        if self.link.stats.junk_datagrams > 0 {
            // Junk (bad checksums, truncated frames, not MAVLink) moves nothing: dropped,
            // counted.
            let n = self.link.stats.junk_datagrams;
            self.ap.events.push(format!(
                "{n} datagrams without a valid MAVLink 2 frame dropped (bad checksum, truncated, not MAVLink)"
            ));
        }
    }
}

/// The measurement as MAVLink carries it: `NAMED_VALUE_FLOAT` named [`wire::MEASUREMENT_NAME`].
fn measurement_message(ms: u32, value: f64) -> MavMessage {
    let mut name = [0u8; 10];
    for (b, c) in name.iter_mut().zip(wire::MEASUREMENT_NAME.bytes()) {
        *b = c;
    }
    MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
        time_boot_ms: ms,
        value: value as f32,
        name: name.into(),
    })
}

/// Waits (handling what arrives) until the wall clock reaches `deadline`.
fn wait_until(sitl: &mut Sitl<'_>, t_s: f64, deadline: Instant) -> Result<(), SitlError> {
    loop {
        let now = Instant::now();
        if now >= deadline || sitl.stop.load(Ordering::Relaxed) {
            return Ok(());
        }
        sitl.handle_inbound(t_s, (deadline - now).min(Duration::from_millis(20)))?;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// att33d-9d: the STATUSTEXTs sitl sends fit one `STATUSTEXT`'s 50 characters, whole: the
    /// offboard failsafe's and the end of a run's longest ("companion_lost").
    #[test]
    fn statustexts_fit_one_frame() {
        assert!(OFFBOARD_LOST_STATUSTEXT.len() <= STATUSTEXT_CHARS);
        assert!("isotrack sitl: run ended (companion_lost)".len() <= STATUSTEXT_CHARS);
        assert!("isotrack sitl: run ended (interrupted)".len() <= STATUSTEXT_CHARS);
    }

    fn autopilot() -> Autopilot {
        let mut ap = Autopilot::new(
            1,
            false,
            Stream::Simulated { within_s: 1.0 },
            Transport::Ground,
            0.2,
            0.2,
        );
        ap.armed = true;
        ap.mode = Mode::Offboard;
        ap.loiter_radps = 0.1;
        ap
    }

    /// A sender's `time_boot_ms` wraps at 2^32 ms (49.7 days): `2^32 - 500` then `499` is a
    /// step of 1000 ms forward (newer, no restart logged), and a stamp from before the wrap
    /// that comes late (`2^32 - 200` after `499`: 700 ms older) is out of order, not newer.
    /// A real jump back (by more than the window, not a consistent step across the wrap) is
    /// still a restart, logged.
    #[test]
    fn a_setpoint_clock_that_wraps_steps_forward() {
        let mut ap = autopilot();
        let gcs = (245, 190);
        assert_eq!(ap.order(0.0, gcs, u32::MAX - 500), Some(true));
        assert_eq!(ap.order(0.0, gcs, 499), Some(true));
        assert!(ap.events.is_empty(), "{:?}", ap.events);
        assert_eq!(ap.order(0.0, gcs, u32::MAX - 200), None);
        assert_eq!(ap.out_of_order, 1);
        assert_eq!(ap.order(0.0, gcs, 1499), Some(true));
        assert_eq!(ap.order(0.0, gcs, 1499), Some(false));
        // 50 000 s later, then back to 1 000 ms: a restarted clock.
        assert_eq!(ap.order(0.0, gcs, 50_000_000), Some(true));
        assert_eq!(ap.order(0.0, gcs, 1_000), Some(true));
        assert_eq!(ap.events.len(), 1, "{:?}", ap.events);
        assert!(
            ap.events[0].contains("taken as restarted"),
            "{:?}",
            ap.events
        );
    }

    /// What starts the run: a ground station's or companion's heartbeat, a message addressed to
    /// this system; not another vehicle's heartbeat, nor a message for another system, nor a
    /// message addressed to nobody in particular.
    #[test]
    fn only_a_peer_talking_to_the_vehicle_starts_the_run() {
        let beat = |mavtype| {
            MavMessage::HEARTBEAT(HEARTBEAT_DATA {
                mavtype,
                ..Default::default()
            })
        };
        let command = |target_system| {
            MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
                target_system,
                ..Default::default()
            })
        };
        assert!(starts_the_run(&beat(MavType::MAV_TYPE_GCS), 1));
        assert!(starts_the_run(
            &beat(MavType::MAV_TYPE_ONBOARD_CONTROLLER),
            1
        ));
        assert!(starts_the_run(&command(1), 1));
        assert!(starts_the_run(&command(7), 7));
        assert!(!starts_the_run(&beat(MavType::MAV_TYPE_QUADROTOR), 1));
        assert!(!starts_the_run(&beat(MavType::MAV_TYPE_FIXED_WING), 1));
        assert!(!starts_the_run(&command(2), 1));
        assert!(!starts_the_run(
            &MavMessage::STATUSTEXT(STATUSTEXT_DATA::default()),
            1
        ));
    }

    fn command_long(command: MavCmd, p1: f32, p2: f32, p3: f32) -> COMMAND_LONG_DATA {
        COMMAND_LONG_DATA {
            param1: p1,
            param2: p2,
            param3: p3,
            command,
            target_system: 1,
            target_component: 1,
            ..Default::default()
        }
    }

    /// A yaw-rate setpoint (attitude ignored) answering no sample, with `thrust` and the
    /// extra `ignore` bits.
    fn yaw_rate(r: f32, thrust: f32, ignore: AttitudeTargetTypemask) -> SET_ATTITUDE_TARGET_DATA {
        SET_ATTITUDE_TARGET_DATA {
            time_boot_ms: NOT_AN_ANSWER_MS,
            q: [1.0, 0.0, 0.0, 0.0],
            body_yaw_rate: r,
            thrust,
            target_system: 1,
            target_component: 1,
            type_mask: AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE | ignore,
            ..Default::default()
        }
    }

    const ACCEPTED: MavResult = MavResult::MAV_RESULT_ACCEPTED;
    const DENIED: MavResult = MavResult::MAV_RESULT_DENIED;

    /// att33c items 11 and 11b: commands and setpoints for another component of the vehicle's
    /// system (a camera's 99) are not the autopilot's: never executed nor answered; its own
    /// component (1) and every component (0) are. A COMMAND_INT is the COMMAND_LONG it
    /// stands for: the arming it carries arms the vehicle.
    #[test]
    fn only_the_autopilots_component_is_commanded() {
        assert!(for_this_vehicle(1, 1, 1) && for_this_vehicle(1, 0, 1));
        assert!(!for_this_vehicle(1, 99, 1) && !for_this_vehicle(2, 1, 1));
        let mut ap = autopilot();
        let mut s = yaw_rate(0.1, 0.0, AttitudeTargetTypemask::empty());
        s.target_component = 99;
        assert!(ap.setpoint(0.0, (1, 191), &s).is_none());
        assert_eq!(ap.refused, 1);
        s.target_component = 0;
        assert!(ap.setpoint(0.0, (1, 191), &s).is_some());
        ap.armed = false;
        ap.mode = Mode::Manual;
        let arm = command_of_int(&COMMAND_INT_DATA {
            param1: 1.0,
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            target_system: 1,
            target_component: 1,
            x: 7,
            z: 2.5,
            ..Default::default()
        });
        assert_eq!((arm.param1, arm.param5, arm.param7), (1.0, 7.0, 2.5));
        assert_eq!(ap.command(0.0, (245, 190), &arm), ACCEPTED);
        assert!(ap.armed);
    }

    /// The ground-station rule of docs/FLYING.md: a ground station (MAVSDK's system 245 by
    /// its `MAV_TYPE_GCS` heartbeat) arms the vehicle without owning it; system 255's
    /// setpoints are refused, a 245's fly it (MAVSDK flying Offboard itself) and make it the
    /// owner. Then, the vehicle a fixed wing in the air: the owner's own unforced disarm (param2
    /// NaN, as MAVSDK sends it) is refused, as PX4 refuses one not landed; forced, accepted.
    #[test]
    fn a_ground_station_flies_by_setpoints_but_never_disarms_in_the_air_unforced() {
        let mut ap = autopilot();
        ap.armed = false;
        ap.mode = Mode::Manual;
        ap.flying = true;
        let (mavsdk, qgc) = ((245, 190), (255, 190));
        ap.heard_gcs(mavsdk);
        let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
        assert_eq!(
            ap.command(0.0, mavsdk, &command_long(arm, 1.0, f32::NAN, 0.0)),
            ACCEPTED
        );
        assert_eq!(ap.owner, None, "arming as a pilot takes no control");
        let none = AttitudeTargetTypemask::empty();
        assert!(ap.setpoint(0.0, qgc, &yaw_rate(0.1, 0.5, none)).is_none());
        assert_eq!(ap.refused, 1);
        assert!(ap
            .setpoint(0.0, mavsdk, &yaw_rate(0.1, 0.5, none))
            .is_some());
        assert_eq!(ap.owner, Some(mavsdk));
        let unforced = command_long(arm, 0.0, f32::NAN, 0.0);
        assert_eq!(ap.command(1.0, mavsdk, &unforced), DENIED);
        assert_eq!(ap.command(1.0, qgc, &unforced), DENIED);
        assert!(ap.armed);
        let forced = command_long(arm, 0.0, FORCE_CODE, 0.0);
        assert_eq!(ap.command(2.0, qgc, &forced), ACCEPTED);
        assert!(!ap.armed);
        // A ground vehicle is on the ground: its owner disarms it unforced.
        let mut rover = autopilot();
        rover.owner = Some((1, 191));
        assert_eq!(rover.command(0.0, (1, 191), &unforced), ACCEPTED);
    }

    /// As PX4: OFFBOARD is refused (temporarily) until setpoints stream, a valid one within
    /// the setpoint timeout (1 s here); the offboard failsafe's 1 s then runs from the switch
    /// when the last setpoint came before it: a setpoint at 2.0 s, the switch at 2.5 s, no
    /// failsafe at 3.4 s (0.9 s after the switch), one at 3.6 s.
    #[test]
    fn offboard_needs_setpoints_streaming_and_its_failsafe_counts_from_the_switch() {
        let mut ap = autopilot();
        ap.armed = false;
        ap.mode = Mode::Manual;
        let c = (1, 191);
        let offboard = command_long(MavCmd::MAV_CMD_DO_SET_MODE, 1.0, 6.0, 0.0);
        let arm = command_long(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, 1.0, 0.0, 0.0);
        assert_eq!(ap.command(0.0, c, &arm), ACCEPTED);
        let rejected = MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        assert_eq!(ap.command(0.0, c, &offboard), rejected);
        assert_eq!(ap.mode, Mode::Manual);
        let none = AttitudeTargetTypemask::empty();
        assert!(ap.setpoint(0.5, c, &yaw_rate(0.0, 0.0, none)).is_some());
        // 1.5 s later the stream is gone.
        assert_eq!(ap.command(2.0, c, &offboard), rejected);
        assert!(ap.setpoint(2.0, c, &yaw_rate(0.0, 0.0, none)).is_some());
        assert_eq!(ap.command(2.5, c, &offboard), ACCEPTED);
        assert_eq!(ap.mode, Mode::Offboard);
        assert!(!ap.offboard_lost(3.4, 1.0));
        assert!(ap.offboard_lost(3.6, 1.0));
    }

    /// A setpoint whose thrust is used (not masked) must be a number: +inf refused; the same
    /// with the thrust ignored moves the vehicle.
    #[test]
    fn an_infinite_thrust_is_no_valid_setpoint() {
        let mut ap = autopilot();
        let c = (1, 191);
        let none = AttitudeTargetTypemask::empty();
        assert!(ap
            .setpoint(0.0, c, &yaw_rate(0.1, f32::INFINITY, none))
            .is_none());
        assert!(ap
            .setpoint(0.0, c, &yaw_rate(0.1, f32::NAN, none))
            .is_none());
        assert_eq!((ap.refused, ap.setpoint), (2, None));
        let ignored = AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE;
        assert!(ap
            .setpoint(0.0, c, &yaw_rate(0.1, f32::INFINITY, ignored))
            .is_some());
        assert_eq!(ap.setpoint.map(|(w, _)| w), Some(-(0.1f32 as f64)));
    }

    /// A ground vehicle's yaw rate beyond its turn-rate limit (0.2 rad/s here) flies at the
    /// limit, in its direction (a yaw rate of 1e30 clockwise: -0.2), logged once.
    #[test]
    fn a_ground_yaw_rate_is_clamped_to_the_turn_rate_limit() {
        let mut ap = autopilot();
        let c = (1, 191);
        let none = AttitudeTargetTypemask::empty();
        assert!(ap.setpoint(0.0, c, &yaw_rate(1e30, 0.0, none)).is_some());
        assert_eq!(ap.setpoint.map(|(w, _)| w), Some(-0.2));
        assert!(ap.setpoint(0.1, c, &yaw_rate(-5.0, 0.0, none)).is_some());
        assert_eq!(ap.setpoint.map(|(w, _)| w), Some(0.2));
        assert_eq!(ap.events.len(), 1, "{:?}", ap.events);
        assert!(ap.events[0].contains("clamped"), "{:?}", ap.events);
        assert!(ap.setpoint(0.2, c, &yaw_rate(0.05, 0.0, none)).is_some());
        assert_eq!(ap.setpoint.map(|(w, _)| w), Some(-(0.05f32 as f64)));
    }
}
