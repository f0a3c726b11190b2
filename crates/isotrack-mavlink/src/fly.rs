//! `isotrack fly`: the companion computer. It runs the scenario's own law
//! ([`Scenario::tracker`]: search phase, anti-windup, turn-rate limit, derivative estimator) on
//! the measurements it receives, and only on them (coordinate-free: positions are logged and
//! checked against the fence, never given to the law), and sends the command as the vehicle's
//! setpoint: a fixed wing's coordinated-turn roll `phi = -atan(omega V / g)` within the bank
//! limit (with the altitude hold's pitch and the airspeed hold's thrust, [`crate::setpoint`]),
//! a ground vehicle's yaw rate, both as `SET_ATTITUDE_TARGET`, stamped with the time of the
//! measurement they answer, and repeated at a steady rate (PX4's offboard mode needs 2 Hz).
//!
//! Control: with `take_control` it arms and switches to OFFBOARD (ArduPilot: GUIDED; the mode
//! numbers are the vehicle's firmware's, [`crate::modes`]), holding the measurements until it
//! has control, so the law starts at the first one; without, it waits for the pilot to do so,
//! answering with neutral setpoints meanwhile. Failsafes (each logged): Ctrl-C
//! ([`FlyOptions::stop`]), `max_duration_s` of vehicle time, no message from the vehicle or no
//! measurement for `timeout_s` of wall time, leaving the fence: the setpoints stop and the
//! vehicle is switched to HOLD (or RETURN, LOITER). What it records: [`crate::record`].
//!
//! The flight is one loop ([`Flight::turn`]), each turn: the heartbeat, what the link brought
//! ([`Flight::handle`]), the UDP sensor's lines, the fence, control, the measurements queued
//! (answered by the law), the ends; then the way out ([`Flight::let_go`]).

use crate::link::{Link, LinkError, LinkStats, Received};
use crate::mirror::Transport;
use crate::modes::{Firmware, FlyMode};
use crate::record::Recorder;
use crate::same_ids::FrameKind;
use crate::wire;
use isotrack_core::{IsolineController, Measurement};
use isotrack_scenario::{Scenario, Tracker};
use isotrack_sim::{RunMetrics, TraceRow, TraceSink};
use mavlink::dialects::common::*;
use std::collections::VecDeque;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The companion's MAVLink component id: `MAV_COMP_ID_ONBOARD_COMPUTER`.
pub const COMPANION_COMPONENT: u8 = 191;

/// The `time_boot_ms` of a setpoint that answers no measurement (sent before the first one).
pub const NOT_AN_ANSWER_MS: u32 = u32::MAX;

/// The largest step of the measurements' clock (`time_boot_ms`) between two measurements
/// received, forwards or backwards, s: a larger one (a rebooted or spoofed clock) is a sensor
/// fault, and fails safe (`sensor_clock_jump`).
pub const MAX_MEASUREMENT_STEP_S: f64 = 60.0;

/// How long after the first autopilot is heard `take_control` sends it nothing but heartbeats
/// (no setpoint, no command), s: two of an autopilot's 1 Hz heartbeats, so that a second vehicle
/// on the link (another system or component) is heard first. A second one heard at any time
/// before the companion has control makes the vehicle ambiguous (`two_vehicles`); in control,
/// it is logged once.
pub const TWO_VEHICLES_WINDOW_S: f64 = 2.0;

/// The shortest silence of the vehicle's heartbeats that ends a flight (`link_lost`) even
/// while its other messages come, s: `timeout_s`, but at least this (autopilots beat at 1 Hz).
pub const MIN_HEARTBEAT_TIMEOUT_S: f64 = 3.0;

/// How long `take_control` retries the arming and the switch to OFFBOARD (every 0.5 s, at
/// most 20 commands), s, from its first command: an accepted switch is not sent again before
/// a heartbeat newer than the acknowledgement (PX4 beats at 1 Hz), so the tries alone would
/// stretch to 20 heartbeats (att45f-8).
pub const TAKE_CONTROL_S: f64 = 10.0;

/// The largest step back of the vehicle's own clock (`time_boot_ms` of its `ATTITUDE`,
/// positions, `SYSTEM_TIME`) that is not a reboot, s: a larger one means its
/// autopilot restarted (its clock begins again at 0), and the flight ends `vehicle_lost`.
pub const REBOOT_STEP_S: f64 = 1.0;

/// How long a vehicle in control that disarmed without the companion asking is watched for
/// a reboot (its clock going back, [`REBOOT_STEP_S`]) before the disarm is taken as a
/// pilot's (`pilot_took_over`), s; it ends at the vehicle's first time-stamped message. No
/// setpoint leaves meanwhile.
pub const REBOOT_WATCH_S: f64 = 1.0;

/// The most events a flight keeps (as `sitl` keeps at most 1000): the first
/// `MAX_EVENTS - EVENTS_KEPT_LAST` and the last [`EVENTS_KEPT_LAST`] (the end and the way out),
/// the ones between counted in one event in their place.
pub const MAX_EVENTS: usize = 1000;

/// Of [`MAX_EVENTS`], how many of the last events are kept.
pub const EVENTS_KEPT_LAST: usize = 100;

/// The shortest wall time between two logged changes of the vehicle's mode or arming, s: the
/// changes between (a heartbeat flapping between two modes) are counted in the next one logged.
pub const MODE_EVENT_INTERVAL_S: f64 = 1.0;

/// The longest unterminated line kept from a UDP sensor's datagrams, bytes.
pub const MAX_PARTIAL_LINE_BYTES: usize = 1024;

pub use crate::wire::{check_level, plausible_value, MAX_MEASUREMENT_ABS};

/// Parses a UDP sensor line `t_s,value`: its time on the wire (ms, [`wire::time_ms`]) and
/// value, or `None` when it is no measurement (not two numbers, a time out of range, a value
/// not [`plausible_value`]).
pub fn parse_sensor_line(line: &str) -> Option<(u32, f64)> {
    let mut it = line.split(',');
    let (t, v) = match (it.next(), it.next(), it.next()) {
        (Some(t), Some(v), None) => (t.trim().parse::<f64>().ok()?, v.trim().parse::<f64>().ok()?),
        _ => return None,
    };
    let ms = wire::time_ms(t)?;
    plausible_value(v).then_some((ms, v))
}

/// Whether data holds a complete valid sensor line ([`parse_sensor_line`]): one ended by a
/// newline. A tail without its newline is no line yet (it may never end: a stray "0,9" must
/// not lock the sensor, ver33-7).
fn holds_a_valid_line(data: &[u8]) -> bool {
    let text = String::from_utf8_lossy(data);
    let complete = text.matches('\n').count();
    text.split('\n')
        .take(complete)
        .any(|l| parse_sensor_line(l).is_some())
}

/// The most times a failsafe's way out (a mode or a disarm) is commanded, one every 0.3 s,
/// before it is given up unconfirmed (besides the time bound of 3 x `timeout_s` within
/// [3, 30] s).
pub const MAX_WAY_OUT_TRIES: u32 = 20;

/// How long after the companion sent an arming or a mode switch an acknowledgement of that
/// command is taken as the answer to it, s. `COMMAND_ACK` as the `mavlink` crate decodes it
/// here carries no target (MAVLink 2's `target_system`/`target_component` extensions are not
/// in its common dialect's struct): an acknowledgement of a command the companion did not send,
/// or sent longer ago, answers someone else (a ground station's arming) and is neither logged
/// as the companion's nor taken as a refusal.
pub const ACK_WINDOW_S: f64 = 1.0;

/// The altitude change a fixed wing's altitude hold takes as flown beyond its airframe's
/// reach, m: between two altitudes `dt` apart (the vehicle's clock), a change larger than
/// `V dt` (`vehicle.airspeed_mps`: no aeroplane climbs or sinks faster than it flies) plus this
/// margin (baro noise, a gust, `f32` rounding) is a step of the altitude's reference (an EKF
/// height reset, a baro glitch, a switch of the height source), not a climb: the hold's
/// target is moved by the same step (its pitch stays what it was: trim when on target),
/// logged ("altitude step of X m ignored").
pub const ALTITUDE_STEP_MARGIN_M: f64 = 10.0;

/// The `MAV_TYPE`s a fixed-wing scenario (`vehicle.kind = "fixed_wing"`) flies: its roll
/// setpoint is a coordinated turn's, for an aeroplane. VTOLs are refused: whether one flies
/// as an aeroplane or hovers is not in its heartbeat.
pub const FIXED_WING_TYPES: &[MavType] = &[MavType::MAV_TYPE_FIXED_WING];

/// The `MAV_TYPE`s a ground scenario (`vehicle.kind = "dubins"`) flies: its setpoint is a yaw
/// rate with attitude and thrust ignored, for a vehicle that keeps its own speed on the
/// ground or water.
pub const GROUND_TYPES: &[MavType] = &[
    MavType::MAV_TYPE_GROUND_ROVER,
    MavType::MAV_TYPE_SURFACE_BOAT,
];

/// Whether a vehicle's heartbeat `type` fits the scenario's vehicle kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KindMatch {
    /// One of the kind's types ([`FIXED_WING_TYPES`], [`GROUND_TYPES`]).
    Yes,
    /// `MAV_TYPE_GENERIC` ("a generic micro air vehicle", what MAVSDK's autopilot server
    /// announces): it says nothing of the airframe; flown as the scenario's kind, with a
    /// warning logged, when the pilot hands over; with `take_control` refused unless
    /// [`FlyOptions::allow_generic`].
    Unknown,
    /// Another type: refused before any setpoint or command (`vehicle_mismatch`).
    No,
}

/// Whether a vehicle announcing `mavtype` flies a scenario whose setpoints are `transport`'s.
pub fn vehicle_kind_match(transport: Transport, mavtype: MavType) -> KindMatch {
    let types = match transport {
        Transport::FixedWing { .. } => FIXED_WING_TYPES,
        Transport::Ground => GROUND_TYPES,
    };
    if types.contains(&mavtype) {
        KindMatch::Yes
    } else if mavtype == MavType::MAV_TYPE_GENERIC {
        KindMatch::Unknown
    } else {
        KindMatch::No
    }
}

/// The scenario's vehicle kind in messages.
fn kind_name(transport: Transport) -> &'static str {
    match transport {
        Transport::FixedWing { .. } => "a fixed wing (vehicle.kind = \"fixed_wing\")",
        Transport::Ground => "a ground vehicle (vehicle.kind = \"dubins\")",
    }
}

/// The measurements' clock as received: only a measurement newer than every one before it
/// counts as one for the sensor-loss timer (the companion's own monotonic clock).
/// `time_boot_ms` wraps at 2^32 ms (49.7 days after the vehicle's boot): times are unwrapped
/// ([`wire::unwrap_ms`]), so a step across the wrap is the small step it is, not a jump.
struct SensorClock {
    /// The newest time received, unwrapped, ms.
    newest_ms: Option<u64>,
    /// When the newest measurement (or, before any, the vehicle's first message) arrived.
    last: Instant,
    /// A jump of the clock, to fail safe on.
    fault: Option<String>,
    /// Measurements received since the newest one that were not newer (a frozen sensor
    /// resending its last time), for the sensor-loss message.
    not_newer: u64,
    /// The time the measurements' clock jumped back to (unwrapped, ms) and when that
    /// measurement came, with the fault: a step of the vehicle's own clock to the same time is
    /// the same step ([`Flight::same_step_as_sensor`]), no reboot seen a second time.
    back_to: Option<(u64, Instant)>,
}

impl SensorClock {
    /// Takes in a received measurement: queued unless its time jumps.
    fn receive(&mut self, queue: &mut VecDeque<(u64, f64)>, ms: u32, v: f64) {
        let max_ms = (MAX_MEASUREMENT_STEP_S * 1000.0) as u64;
        let ms = self.newest_ms.map_or(ms as u64, |n| wire::unwrap_ms(n, ms));
        match self.newest_ms {
            Some(n) if ms <= n => {
                if n - ms > max_ms {
                    if self.fault.is_none() {
                        self.back_to = Some((ms, Instant::now()));
                    }
                    self.fault.get_or_insert(format!(
                        "the measurement's time jumped back from {} s to {} s (a rebooted or spoofed clock)",
                        wire::unwrapped_s(n),
                        wire::unwrapped_s(ms)
                    ));
                    return;
                }
                // A repeat (answered again) or a late one (dropped): no news of the sensor.
                self.not_newer += 1;
                queue.push_back((ms, v));
            }
            Some(n) if ms - n > max_ms => {
                self.fault.get_or_insert(format!(
                    "the measurement's time jumped ahead from {} s to {} s (a spoofed clock)",
                    wire::unwrapped_s(n),
                    wire::unwrapped_s(ms)
                ));
            }
            _ => {
                self.newest_ms = Some(ms);
                self.last = Instant::now();
                self.not_newer = 0;
                queue.push_back((ms, v));
            }
        }
    }
}

/// Where the measurements come from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SensorSource {
    /// `NAMED_VALUE_FLOAT` messages of the vehicle with this name (at most 10 characters).
    Named(String),
    /// Text lines `t_s,value` in UDP datagrams received on this address (`udp:HOST:PORT`).
    UdpLines(String),
}

impl SensorSource {
    /// Parses `--sensor`: `NAME`, `mavlink:NAME` or `udp:HOST:PORT` (its address checked as
    /// [`crate::link::resolve`] does).
    pub fn parse(s: &str) -> Result<Self, String> {
        if let Some(a) = s.strip_prefix("udp:") {
            // A malformed address is a usage error, as --mavlink's.
            return match crate::link::resolve(a) {
                Err(LinkError::Address(m)) => Err(format!("--sensor udp:{a}: {m}")),
                // Port 0 binds a port the system picks, which no sensor could be told
                // (att33d-9c).
                Ok(addr) if addr.port() == 0 => Err(format!(
                    "--sensor udp:{a}: port 0 would be a port the system picks, which no sensor could know: give the port the sensor sends to"
                )),
                _ => Ok(SensorSource::UdpLines(a.to_string())),
            };
        }
        if s.starts_with("serial:") {
            return Err(format!(
                "--sensor {s}: serial sensors are not supported yet (use udp:HOST:PORT)"
            ));
        }
        let name = s.strip_prefix("mavlink:").unwrap_or(s);
        if name.is_empty() || name.len() > 10 || !name.is_ascii() {
            return Err(format!(
                "--sensor {s}: a NAMED_VALUE_FLOAT name is 1 to 10 ASCII characters"
            ));
        }
        Ok(SensorSource::Named(name.to_string()))
    }
}

/// The mode a failsafe switches to (each firmware's number: [`crate::modes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailsafeAction {
    /// HOLD (PX4 AUTO.LOITER; ArduCopter and ArduPlane LOITER, ArduRover HOLD).
    Hold,
    /// RETURN (PX4 AUTO.RTL; ArduPilot RTL).
    Return,
    /// LOITER (PX4 AUTO.LOITER; ArduPilot LOITER).
    Loiter,
}

impl FailsafeAction {
    /// The mode it commands.
    pub fn mode(self) -> FlyMode {
        match self {
            FailsafeAction::Hold => FlyMode::Hold,
            FailsafeAction::Return => FlyMode::Return,
            FailsafeAction::Loiter => FlyMode::Loiter,
        }
    }
}

/// What the companion commands when it lets go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum WayOut {
    /// The failsafe mode.
    Mode(FlyMode),
    /// Disarm (a vehicle the companion armed on the ground).
    Disarm,
    /// The failsafe mode, for a vehicle that accepted the switch to OFFBOARD before the
    /// companion saw it in control: confirmed by a heartbeat in any mode but OFFBOARD.
    LeaveOffboard(FlyMode),
}

/// The vehicle's answer to a way out.
enum Answer {
    /// Its heartbeat shows what was commanded.
    Confirmed,
    /// Its heartbeat shows another safe mode ([`Firmware::safe_mode_name`]).
    OtherSafeMode(&'static str),
    /// It refused (`DENIED`, `UNSUPPORTED`, `FAILED`).
    Refused,
    /// Its heartbeat shows a mode (or a disarm) the companion did not command and that is
    /// not a safe one: a pilot took over during the retries (its word is final).
    PilotTookOver(String),
    /// Once a second sender with the vehicle's ids has been seen: a heartbeat of the ids
    /// shows a mode (or a disarm) the companion did not command, a pilot's or the second
    /// sender's, which nothing tells apart (att41f-3): the retries stop, nothing more is
    /// commanded (the vehicle flown keeps the way out already commanded, or falls to its own
    /// offboard-loss failsafe; a pilot's mode stands).
    NotCommanded(String),
}

/// A heartbeat's answer during the failsafe's retries awaiting confirmation (att33e-1,
/// att33f-3): the heartbeats of the vehicle's ids must show it for [`Flight::confirm_span`],
/// none contradicting, before it is taken, whichever it is (the way out confirmed, another
/// safe mode, or a pilot's change): a second vehicle with the ids beats too, and its heartbeat
/// in the mode commanded (or disarmed, for a disarm) would end the retries while the vehicle
/// flown, which refused them, stays in OFFBOARD.
struct AnswerSeen {
    /// A pilot's change ([`Answer::PilotTookOver`]) rather than the way out's (confirmed,
    /// another safe mode): a heartbeat showing the other kind contradicts it.
    pilots: bool,
    /// What a pilot's change shows, in words (`in MANUAL`); empty for the way out's.
    what: String,
    /// When the first heartbeat showing it came (or the last older one contradicting it).
    at: Instant,
    /// Shown by a heartbeat in a doubt of the frame counter (att42f-5): a pilot's word for the
    /// retries (none is sent meanwhile, and a second sender proven after it stops them), but
    /// never the vehicle's answer: a heartbeat applied after the doubt starts its span over.
    in_doubt: bool,
    /// The doubts of the frame counter opened before a pilot's word was FIRST heard (in a
    /// doubt: before that one; kept when heartbeats applied after the resync repeat it,
    /// att49f-3): a heartbeat applied after it that contradicts it with a doubt between is two
    /// senders' ([`Flight::contradicted_across_a_doubt`], att45f-4).
    doubts: u64,
}

/// What the failsafe's retries have seen of the vehicle's heartbeats so far.
#[derive(Default)]
struct RetryWatch {
    /// The answer shown, awaiting confirmation: no retry is sent meanwhile.
    seen: Option<AnswerSeen>,
    /// A disarm was commanded (the way out before a second sender was seen).
    disarm_sent: bool,
    /// Once a second sender has been seen: since the last command sent, a heartbeat of the ids
    /// showed it still armed in the mode the companion left it in ([`Flight::left_in`]): the
    /// only reason for a retry then (att42f-2).
    left_shown: bool,
    /// A heartbeat of the ids older than the last applied was heard during the retries (a
    /// second counter's, or one sender's late one): a change they show is no sure pilot's.
    older: bool,
    /// The last heartbeat applied showed the vehicle armed (at the start: as last known).
    armed_shown: bool,
    /// The silence of the vehicle's ids before the frame being read, s.
    silent_s: f64,
    /// The last disarm shown came after a silence of more than [`REBOOT_STEP_S`] (as
    /// [`Flight::disarm_after_silence`] in control, att53f-2).
    disarm_after_silence: bool,
}

impl RetryWatch {
    /// A heartbeat applied during the retries showing the vehicle `armed` or not: a disarm
    /// right after a silence of more than [`REBOOT_STEP_S`] may be a reboot's.
    fn arming_shown(&mut self, armed: bool) {
        if !armed && self.armed_shown {
            self.disarm_after_silence = self.silent_s > REBOOT_STEP_S;
        } else if armed {
            self.disarm_after_silence = false;
        }
        self.armed_shown = armed;
    }

    /// A heartbeat not applied (older than the last applied, or in a doubt of the frame
    /// counter) showing `answer`: if it shows nothing yet, or the other kind of answer than
    /// the one awaited, that one has not stood uncontradicted: its span starts again.
    fn contradicted_by(&mut self, answer: &Option<Answer>) {
        let pilots = matches!(answer, Some(Answer::PilotTookOver(_)));
        if let Some(seen) = self.seen.as_mut() {
            if answer.is_none() || seen.pilots != pilots {
                seen.at = Instant::now();
            }
        }
    }
}

/// The state the failsafe's retries ([`Flight::command_way_out`]) carry from one try to the
/// next.
struct WayOutRetries {
    /// The way out commanded (the failsafe mode once a second sender is seen).
    way: WayOut,
    /// Its command.
    cmd: MavCmd,
    /// Its command's parameters.
    params: [f32; 3],
    /// The vehicle's mode and arming as the failsafe began (as last confirmed: not a pilot's
    /// word still awaiting confirmation, which may be a second vehicle's): a change to
    /// anything else than what is commanded (or another safe mode) is a pilot's.
    before: (Option<u32>, bool),
    /// When the retries' bound passes.
    end: Instant,
    /// The tries sent so far.
    tries: u32,
    /// When the vehicle last acknowledged the command as ACCEPTED: it is not sent again
    /// before a heartbeat newer than that says what the vehicle did (with a 1 Hz heartbeat a
    /// retry would yank back a pilot who took over meanwhile).
    accepted: Option<Instant>,
    /// A heartbeat's answer awaiting confirmation (att33e-1, att33f-3: taken once it has
    /// stood, none contradicting, for `span`; no retry meanwhile).
    watch: RetryWatch,
    /// How long an answer must stand ([`Flight::confirm_span`]).
    span: Duration,
    /// The vehicle refused the way out: an unaddressed refusal may answer someone else's
    /// same command (att33e-5), so the retries go on to their bound, which then says so.
    refused: bool,
    /// A second sender with the ids was seen before the retries began, or its log was
    /// written since.
    told: bool,
}

/// What the checks of a frame heard during the failsafe's retries decide
/// ([`Flight::retry_frame`]).
enum RetryFrame {
    /// The listen ends with this answer (`None`: its autopilot rebooted).
    End(Option<Answer>),
    /// Nothing more to read in the frame.
    Done,
    /// A frame of the vehicle, its message to read, with its unwrapped number.
    Read(u64),
}

/// Options of [`run_fly`].
#[derive(Clone, Debug)]
pub struct FlyOptions {
    /// The link address (see [`crate::link`]).
    pub url: String,
    /// Where the measurements come from.
    pub sensor: SensorSource,
    /// Switch to OFFBOARD (else wait for the pilot to); a disarmed vehicle only with `arm`.
    pub take_control: bool,
    /// With `take_control`, also arm a disarmed vehicle (a simulator's, such as `isotrack
    /// sitl`, which flies from its start); without it a disarmed vehicle is refused
    /// (`control_refused`, nothing commanded): a real aircraft is armed and flown to the area
    /// by its pilot.
    pub arm: bool,
    /// With `take_control`, also take a vehicle announcing `MAV_TYPE_GENERIC` (which says
    /// nothing of its airframe); without it such a vehicle is refused (`vehicle_mismatch`)
    /// before any setpoint or command. Without `take_control` it is flown with a warning.
    pub allow_generic: bool,
    /// End after this long since the companion has control, s: on the vehicle's clock from
    /// the first measurement answered in control, on the companion's own clock from when the
    /// vehicle was first heard armed and in OFFBOARD, whichever ends first.
    pub max_duration_s: Option<f64>,
    /// Fail safe after this long without a message from the vehicle or a measurement, wall s.
    pub timeout_s: f64,
    /// Fail safe when farther than this from the position where the companion got control
    /// (armed and in OFFBOARD), m; not enforced before.
    pub fence_m: Option<f64>,
    /// The mode a failsafe switches to.
    pub failsafe: FailsafeAction,
    /// Setpoints per wall-clock second besides the answers (>= 2 for PX4's offboard mode).
    pub setpoint_rate_hz: f64,
    /// This companion's system id (component 191, an onboard computer).
    pub system_id: u8,
    /// The vehicle's system id (`--target-system`); `None`: the first autopilot heard, and a
    /// second one heard within [`TWO_VEHICLES_WINDOW_S`] of it ends the flight.
    pub target_system: Option<u8>,
    /// Set from outside (Ctrl-C) to stop.
    pub stop: Arc<AtomicBool>,
    /// Called with each event as it happens (the operator's terminal: `fly` writes them to
    /// standard error at once, not when the flight ends): the first
    /// [`MAX_EVENTS`] `- EVENTS_KEPT_LAST`, then one line saying the rest are printed at the
    /// end ([`FlyReport::events_live`] says how many of the report's went out so).
    pub live_events: Option<LiveEvents>,
}

/// A writer of events as they happen ([`FlyOptions::live_events`]).
#[derive(Clone)]
pub struct LiveEvents(pub Arc<dyn Fn(&str) + Send + Sync>);

impl std::fmt::Debug for LiveEvents {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("LiveEvents")
    }
}

impl FlyOptions {
    /// Defaults: `ISO_S`, no take-over, a 3 s timeout, no fence, HOLD, 10 Hz setpoints, system
    /// 1 (the vehicle's own system, as a companion computer is).
    pub fn new(url: &str) -> Self {
        Self {
            url: url.to_string(),
            sensor: SensorSource::Named(wire::MEASUREMENT_NAME.into()),
            take_control: false,
            arm: false,
            allow_generic: false,
            max_duration_s: None,
            timeout_s: 3.0,
            fence_m: None,
            failsafe: FailsafeAction::Hold,
            setpoint_rate_hz: 10.0,
            system_id: 1,
            target_system: None,
            stop: Arc::new(AtomicBool::new(false)),
            live_events: None,
        }
    }
}

/// How a flight ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlyEnd {
    /// The vehicle reported the end of its run (`MAV_STATE_POWEROFF`).
    VehicleEnded,
    /// Stopped from outside (Ctrl-C): failsafe.
    Interrupted,
    /// `max_duration_s` reached: failsafe.
    MaxDuration,
    /// No message from the vehicle for `timeout_s`: failsafe.
    LinkLost,
    /// No measurement for `timeout_s`: failsafe.
    SensorLost,
    /// Outside the fence: failsafe.
    Fence,
    /// The law's command was not finite: failsafe.
    LawNotFinite,
    /// The vehicle refused to arm or to switch to OFFBOARD.
    ControlRefused,
    /// The vehicle reported `MAV_STATE_POWEROFF` without announcing the end of its run
    /// (`STATUSTEXT` "isotrack sitl: run ended"), or its autopilot rebooted (its clock went
    /// back by more than [`REBOOT_STEP_S`]), or a second vehicle with its ids was heard
    /// ([`crate::same_ids`]; before control nothing is commanded): failsafe.
    VehicleLost,
    /// The measurements' clock jumped by more than [`MAX_MEASUREMENT_STEP_S`]: failsafe.
    SensorClockJump,
    /// Once the companion had control, the vehicle left OFFBOARD or disarmed without the
    /// companion asking (a pilot or the autopilot took over): the setpoints stop at once and
    /// nothing is commanded, so the pilot's mode stands.
    PilotTookOver,
    /// Two autopilots were heard within [`TWO_VEHICLES_WINDOW_S`] (without
    /// `FlyOptions::target_system`): which one to fly is ambiguous, nothing is commanded.
    TwoVehicles,
    /// The vehicle's heartbeat `type` does not fit the scenario's vehicle kind
    /// ([`vehicle_kind_match`]): nothing is sent but heartbeats, no setpoint, no command.
    VehicleMismatch,
    /// Another controller holds the vehicle: with `take_control`, the vehicle was armed and in
    /// OFFBOARD before the companion commanded either; or setpoints for the vehicle came from
    /// another system or component. A failsafe: before control nothing is commanded; in
    /// control the setpoints stop and the failsafe mode is commanded.
    AnotherController,
}

impl FlyEnd {
    /// Its name in the summary (`end_reason`).
    pub fn as_str(self) -> &'static str {
        match self {
            FlyEnd::VehicleEnded => "vehicle_ended",
            FlyEnd::Interrupted => "interrupted",
            FlyEnd::MaxDuration => "max_duration",
            FlyEnd::LinkLost => "link_lost",
            FlyEnd::SensorLost => "sensor_lost",
            FlyEnd::Fence => "fence",
            FlyEnd::LawNotFinite => "law_not_finite",
            FlyEnd::ControlRefused => "control_refused",
            FlyEnd::SensorClockJump => "sensor_clock_jump",
            FlyEnd::VehicleLost => "vehicle_lost",
            FlyEnd::PilotTookOver => "pilot_took_over",
            FlyEnd::TwoVehicles => "two_vehicles",
            FlyEnd::VehicleMismatch => "vehicle_mismatch",
            FlyEnd::AnotherController => "another_controller",
        }
    }
    /// Whether it is a failsafe (setpoints stopped, hold/return commanded).
    pub fn is_failsafe(self) -> bool {
        !matches!(
            self,
            FlyEnd::VehicleEnded
                | FlyEnd::ControlRefused
                | FlyEnd::PilotTookOver
                | FlyEnd::TwoVehicles
                | FlyEnd::VehicleMismatch
        )
    }
}

/// What a flight did.
#[derive(Clone, Debug)]
pub struct FlyReport {
    /// How it ended.
    pub end: FlyEnd,
    /// Per measurement answered by the law: its wire time, ms, and the command, rad/s.
    pub commands: Vec<(u32, f64)>,
    /// Measurements received.
    pub samples: u64,
    /// Vehicle time of the first and last measurement, s.
    pub t_first_s: Option<f64>,
    /// Vehicle time of the last measurement, s.
    pub t_last_s: Option<f64>,
    /// Events (control, failsafes), in order.
    pub events: Vec<String>,
    /// How many of the first `events` went to [`FlyOptions::live_events`] as they happened
    /// (the rest, from the count of those not kept on, were not).
    pub events_live: usize,
    /// Whether the vehicle acknowledged the failsafe mode (or, after a refused take-over, the
    /// mode or the disarm commanded).
    pub failsafe_acknowledged: bool,
    /// Whether anything was commanded on the way out (a failsafe's mode, or after a refused
    /// take-over of an armed vehicle, HOLD/RETURN or a disarm).
    pub way_out_commanded: bool,
    /// The link's counters.
    pub link: LinkStats,
    /// The tracking metrics of the measured error series ([`crate::record`]).
    pub metrics: RunMetrics,
    /// What the metrics were computed over, in words (the planned window, or what was flown
    /// of a flight that ended early, or why there are none).
    pub metrics_over: String,
    /// Whether a vehicle (an autopilot's heartbeat) was heard at all.
    pub vehicle_heard: bool,
    /// Measurements older than one already answered: dropped, never given to the law.
    pub measurements_out_of_order: u64,
    /// Measurements with the time of one already answered (a repeat): answered again with the
    /// same setpoint, never given to the law twice.
    pub measurements_repeated: u64,
    /// A pilot took over during the failsafe's retries (a mode or disarm the companion did not
    /// command): the retries stopped unconfirmed, the pilot's mode stands.
    pub way_out_overridden: bool,
    /// Measurements that were no measurement: a `NAMED_VALUE_FLOAT` of the sensor's name whose
    /// value is not [`plausible_value`], a UDP sensor line that is not `t_s,value` with both
    /// numbers, a time in [0, 4294967.295] s and a plausible value, or longer than
    /// [`MAX_PARTIAL_LINE_BYTES`], a UDP datagram without a valid line before the sensor's first:
    /// dropped, never given to the law; the first logged.
    pub measurements_invalid: u64,
    /// Measurements from another sender than the sensor's (the first sender of a valid one):
    /// a `NAMED_VALUE_FLOAT` of its name from another (system, component), a UDP sensor's
    /// datagram from another address; dropped, never given to the law; the first logged.
    pub measurements_other_sources: u64,
    /// With `target_system`, the first autopilot heard of another system (system, component):
    /// a vehicle was there, not the one asked for (a mistyped id?).
    pub other_system_heard: Option<(u32, u8)>,
    /// Why the raw MAVLink log ([`Link::log_to`]) stopped short, and when (a full disk): its
    /// frames after that are missing (logged when it happened).
    pub log_incomplete: Option<String>,
}

/// Why a flight could not start.
#[derive(Debug)]
pub enum FlyError {
    /// The link or the sensor address.
    Link(LinkError),
    /// The scenario's law cannot fly coordinate-free (it needs ground truth).
    Scenario(String),
    /// The socket failed.
    Io(std::io::Error),
}

impl std::fmt::Display for FlyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FlyError::Link(e) => e.fmt(f),
            FlyError::Scenario(m) => f.write_str(m),
            FlyError::Io(e) => write!(f, "link: {e}"),
        }
    }
}

fn name_of(c: &[u8]) -> &[u8] {
    let n = c.iter().position(|&b| b == 0).unwrap_or(c.len());
    &c[..n]
}

/// A flight under way: the link, the vehicle as heard, the law and what is recorded.
struct Flight<'a, S: ?Sized> {
    link: Link,
    opts: &'a FlyOptions,
    transport: Transport,
    law: Tracker,
    level: f64,
    sink: &'a mut S,
    flush: &'a mut dyn FnMut(&mut S),
    record: Recorder,
    events: Vec<String>,
    /// The last events once [`MAX_EVENTS`] `- EVENTS_KEPT_LAST` are kept, at most
    /// [`EVENTS_KEPT_LAST`].
    events_last: VecDeque<String>,
    /// Events dropped between the first and the last kept.
    events_dropped: u64,
    /// When a change of the vehicle's mode or arming was last logged, and how many came since
    /// without being logged ([`MODE_EVENT_INTERVAL_S`]).
    mode_logged_at: Option<Instant>,
    modes_unlogged: u64,
    t0: Instant,
    timeout: Duration,
    period: Duration,
    // The vehicle as heard.
    target: Option<(u32, u8)>,
    target_at: Option<Instant>,
    /// Another autopilot heard within [`TWO_VEHICLES_WINDOW_S`] of the vehicle.
    other_vehicle: Option<(u32, u8)>,
    /// With `target_system`, the first autopilot heard of another system.
    other_system: Option<(u32, u8)>,
    /// Why the vehicle's type does not fit the scenario (refused before anything is sent).
    mismatch: Option<String>,
    /// Why another controller holds the vehicle (setpoints from someone else).
    other_controller: Option<String>,
    /// How the vehicle's run ended (`STATUSTEXT` "isotrack sitl: run ended (HOW)").
    run_end_how: Option<String>,
    /// The vehicle said it is going away (its run interrupted): the link is as good as lost.
    link_gone: bool,
    /// A pilot took over during the failsafe's retries (they stopped).
    way_out_overridden: bool,
    /// The control command sent last and when (its acknowledgement is the companion's).
    awaiting: Option<(MavCmd, Instant)>,
    firmware: Firmware,
    /// The vehicle's heartbeat `type` (its kind, checked against the scenario's).
    vehicle_type: MavType,
    /// The vehicle's heartbeat `autopilot`.
    autopilot: MavAutopilot,
    armed: bool,
    custom_mode: Option<u32>,
    /// The vehicle announced the end of its run (`STATUSTEXT` "isotrack sitl: run ended").
    run_ended: bool,
    /// The vehicle reported `MAV_STATE_POWEROFF`.
    vehicle_done: bool,
    last_link: Instant,
    /// When the vehicle's last heartbeat applied came (its mode and arming as known).
    last_heartbeat: Instant,
    /// When the last heartbeat of the vehicle's ids came, applied or not (a late one older
    /// than the last applied, or any after a second sender was seen): the link is alive.
    beat_heard: Instant,
    /// The unwrapped frame number of the last heartbeat applied ([`crate::same_ids`]): a
    /// heartbeat is applied only if its number is newer (older news is never applied).
    beat_number: Option<u64>,
    /// A second sender with the vehicle's ids has been seen ([`Flight::second_sender_seen`]):
    /// no heartbeat of the ids is taken as the vehicle's word any more, no disarm is sent.
    second_sender: bool,
    /// The flight ended `vehicle_lost` on a second sender with the vehicle's ids (not on a
    /// reboot): [`Flight::word_before_second_sender`].
    lost_to_second_sender: bool,
    /// The newest time of the vehicle's own clock heard (unwrapped, ms) and when it came.
    vehicle_ms: Option<(u64, Instant)>,
    /// The landed state of the vehicle's last `EXTENDED_SYS_STATE` (none: it sends none):
    /// in the air, a vehicle the companion armed is never disarmed (att37-3).
    landed: Option<MavLandedState>,
    /// The vehicle's clock went back ([`REBOOT_STEP_S`]): its autopilot rebooted.
    reboot: Option<String>,
    /// Time-stamped frames in a row more than [`REBOOT_STEP_S`] behind the newest (one is a
    /// late frame; two, a reboot).
    clock_behind: u32,
    /// The vehicle's clock went back (a reboot found, or with the measurements' clock): from
    /// and to what time (unwrapped, ms) and when ([`Flight::clock_ahead_of_reboot`]).
    rebased: Option<(u64, u64, Instant)>,
    /// In control, the vehicle disarmed without the companion asking: since when (watched for
    /// a reboot for [`REBOOT_WATCH_S`]).
    disarm_seen: Option<Instant>,
    mavlink1_logged: bool,
    /// A second companion with the same ids has been heard (logged once).
    twin_logged: bool,
    /// The companion's own frames have come back (logged once).
    echo_logged: bool,
    /// In control, since when the vehicle's heartbeat has shown no known mode (armed).
    unknown_mode_since: Option<Instant>,
    /// The last disarm came after a silence of the vehicle's of more than [`REBOOT_STEP_S`].
    disarm_after_silence: bool,
    /// A peripheral's GENERIC heartbeat beside the autopilot has been logged.
    peripheral_logged: bool,
    /// A second autopilot heard in control has been logged.
    late_vehicle_logged: bool,
    /// The source address of the vehicle's frames (UDP), and why a second one makes it two.
    vehicle_addr: Option<std::net::SocketAddr>,
    same_ids: Option<String>,
    /// Why the raw MAVLink log stopped short (logged once, when it happened).
    log_incomplete: Option<String>,
    /// The sequence numbers of the vehicle's frames, watched for a second sender with its ids.
    seq_watch: crate::same_ids::SequenceWatch,
    /// When the vehicle's ids last sent a frame the frame watch classed no copy (new, late or
    /// in a doubt): a copy in a doubt keeps the link only as of then ([`Flight::copy_frame`]).
    fresh_at: Instant,
    /// The doubts of the frame counter logged as they opened ([`Flight::doubt_news`]).
    doubts_logged: u64,
    /// The vehicle's positions, watched for jumps no airframe makes.
    pos_watch: crate::same_ids::PositionWatch,
    /// With `take_control`, [`TWO_VEHICLES_WINDOW_S`] has passed (the sensor's timer was
    /// restarted then).
    window_passed: bool,
    // Control.
    /// The vehicle refused to arm or to switch to OFFBOARD.
    refused: bool,
    /// What it refused and how (`OFFBOARD: MAV_RESULT_TEMPORARILY_REJECTED`).
    refusal: Option<String>,
    /// A refusal heard, not yet the vehicle's last word (ver33b-11): the command refused and
    /// when. An acknowledgement carries no sender's request (an unaddressed `DENIED` may answer
    /// a ground station's same command): the take-over ends only once a heartbeat newer than
    /// the refusal (and than any acceptance after it) shows the command not carried out.
    refusal_pending: Option<(MavCmd, Instant)>,
    /// A heartbeat of the vehicle's ids showed a pilot's word ([`Flight::shows_pilots_word`]):
    /// the pilot's once confirmed ([`LeaveSeen`], ver33c-1).
    leave_seen: Option<LeaveSeen>,
    /// Doubts about the vehicle's frame counter that ended resynchronised (one sender's burst
    /// loss, as far as fly could tell), counted for the log.
    resyncs: u32,
    /// Heartbeats of the vehicle's ids handled.
    heartbeats: u64,
    /// When the vehicle's last heartbeat (applied) came, and the longest gap between two
    /// applied over the flight, s: how long a pilot's word waits for confirmation
    /// ([`Flight::confirm_span`]).
    beat_at: Option<Instant>,
    longest_beat_gap_s: f64,
    /// Armed and in OFFBOARD this turn.
    active: bool,
    /// The vehicle has been armed and in OFFBOARD (the companion had control).
    in_control: bool,
    arm_sent: bool,
    /// Disarmed when first heard and armed on the companion's command: still on the ground.
    armed_by_us: bool,
    offboard_sent: bool,
    /// When the vehicle last acknowledged the companion's switch to OFFBOARD as `ACCEPTED`
    /// before control: the switch is not sent again until a heartbeat newer than it shows
    /// what the vehicle did (a third mode is a pilot's; the old one, a switch not made).
    offboard_accepted_at: Option<Instant>,
    /// With `take_control`: the vehicle's mode when the companion sent its first control
    /// command (a change to anything but OFFBOARD before control is a pilot's).
    mode_at_first_command: Option<Option<u32>>,
    /// With `take_control`: the vehicle has been armed since the companion's first control
    /// command (a disarm after it is a pilot's).
    armed_since_command: bool,
    was_armed: bool,
    next_control: Instant,
    /// With `take_control`: the arming and switch commands sent ([`TAKE_CONTROL_S`]).
    control_tries: u32,
    /// With `take_control`: when the first of them was due ([`TAKE_CONTROL_S`] from there).
    control_first_at: Option<Instant>,
    tel: Telemetry,
    // The sensor.
    lines: Option<UdpSocket>,
    wanted: Vec<u8>,
    partial: Vec<u8>,
    skipping_line: bool,
    /// The UDP sensor's datagram buffer (empty without one).
    buf: Vec<u8>,
    /// The UDP sensor's address: the first sender of a valid line's.
    sensor_from: Option<std::net::SocketAddr>,
    /// The `NAMED_VALUE_FLOAT` sensor's (system, component): the first sender of a valid
    /// measurement of its name.
    meas_from: Option<(u32, u8)>,
    /// Measurements (or UDP datagrams) from other senders than the sensor's, dropped.
    other_sources: u64,
    /// Before the UDP sensor is known: the sender of the last datagram dropped (no complete
    /// valid line) and its unterminated tail, which that sender's next datagram may end (`[0]`:
    /// a tail that is no line, over-long).
    pre_lock_tail: Option<(std::net::SocketAddr, Vec<u8>)>,
    /// Measurements that were none (non-finite, malformed lines), dropped.
    invalid: u64,
    /// Held measurements dropped for a newer one while control was being taken.
    held_dropped: u64,
    clock: SensorClock,
    /// Since the vehicle's first message (the fence's wait for a position).
    clock_start: Instant,
    /// Measurements waiting: unwrapped time, ms ([`SensorClock`]), and value.
    queue: VecDeque<(u64, f64)>,
    /// While `take_control` holds the measurements: how many queued ones were already
    /// looked at for copies, and the newest (unwrapped) time held.
    held_scanned: usize,
    held_newest: Option<u64>,
    ans: Answers,
    next_setpoint: Instant,
    next_heartbeat: Instant,
}

/// The vehicle's positions, altitude and airspeed as received (the fence, the trace, the fixed
/// wing's altitude and airspeed holds; never the law).
#[derive(Default)]
struct Telemetry {
    /// The first `GLOBAL_POSITION_INT` fix, about which global positions are projected while
    /// no `LOCAL_POSITION_NED` has come.
    global_origin: Option<crate::geo::Home>,
    /// A finite `LOCAL_POSITION_NED` has come (positions are local from then on).
    local_seen: bool,
    pos: Option<(f64, f64)>,
    /// When the last finite position arrived.
    position_at: Option<Instant>,
    /// The fence's centre.
    home: Option<(f64, f64)>,
    home_local: bool,
    altitude_m: Option<f64>,
    /// When the altitude arrived (older than `timeout_s`: unknown, the pitch hold's 0).
    altitude_at: Option<Instant>,
    altitude_target_m: Option<f64>,
    /// The last altitude received (stale or not) and its time on the vehicle's clock
    /// (unwrapped, ms): a step beyond [`ALTITUDE_STEP_MARGIN_M`] is a reset.
    last_altitude: Option<(f64, u64)>,
    airspeed_mps: Option<f64>,
    /// When the airspeed arrived (older than `timeout_s`: unknown, the trim thrust).
    airspeed_at: Option<Instant>,
    /// A stale altitude or airspeed has been logged (once each).
    stale_logged: (bool, bool),
    /// The hold's target re-referenced after an altitude outage has been logged (once).
    rereferenced_logged: bool,
}

/// In control, a heartbeat of the vehicle's ids that showed it out of OFFBOARD or disarmed; during
/// a take-over, one that showed a pilot's change ([`Flight::shows_pilots_word`]) (ver33c-1). A
/// second vehicle left at the same ids behind one router (its own frame counter)
/// beats too, and its first heartbeat looks exactly like a pilot's switch: taken at its word,
/// the companion would stop and command nothing, and the vehicle flown would be left in
/// OFFBOARD without setpoints. So the change is the pilot's word only once confirmed: the
/// heartbeats of its ids applied (newer than the last applied: an older one is older news,
/// never applied, but one contradicting the word restarts its span) show it, none
/// contradicting, for longer than the vehicle's heartbeat period ([`Flight::confirm_span`]),
/// within which the vehicle flown, if it is another, beats too. Until then the last setpoint
/// is repeated (an autopilot out of OFFBOARD or GUIDED ignores offboard setpoints, so a pilot
/// loses nothing), no measurement is answered, and during a take-over nothing more is
/// commanded: however it turns out, the flight ends. A second sender with the ids seen
/// ([`crate::same_ids`]: two different frames with one number) ends it `vehicle_lost`; a
/// newer heartbeat that no longer shows the word, without one, is one sender's change and
/// back (the pilot's word, as ever).
#[derive(Clone, Debug)]
struct LeaveSeen {
    /// When the heartbeat that showed it came, and how long it must stand uncontradicted
    /// ([`Flight::confirm_span`]).
    at: Instant,
    span: Duration,
    /// The vehicle's mode and arming before that heartbeat (as last confirmed).
    before: (Option<u32>, bool),
    /// What it showed, in words (`disarmed in MANUAL`).
    what: String,
    /// Confirmed: the pilot's word.
    confirmed: bool,
    /// Confirmed by a heartbeat that no longer shows it (one sender's change and back).
    back: bool,
    /// The frame watch's doubts opened before it ([`crate::same_ids::SequenceWatch::doubts`]).
    doubts: u64,
}

/// The law's answers so far.
#[derive(Default)]
struct Answers {
    /// The command in force (None: neutral, before the law has control).
    current: Option<f64>,
    /// Unwrapped, ms.
    last_answer_ms: Option<u64>,
    commands: Vec<(u32, f64)>,
    samples: u64,
    t_first: Option<f64>,
    t_last: Option<f64>,
    /// Vehicle time of the first measurement answered in control.
    t_control: Option<f64>,
    /// When the companion got control (its own clock).
    first_wall: Option<Instant>,
    out_of_order: u64,
    repeated: u64,
    /// The last answer was the law's (in control), not a neutral setpoint.
    last_answer_in_control: bool,
    /// The first repeat has been logged.
    repeat_logged: bool,
}

/// Flies `scenario`'s law over `opts.url`, recording one trace row per answered measurement
/// (the position and heading at its time, measured value as `s`, the command) into `sink`;
/// `link_setup` is called on the link before the flight starts (the raw MAVLink log:
/// [`Link::log_to`]).
pub fn run_fly<S: TraceSink + ?Sized>(
    scenario: &Scenario,
    opts: &FlyOptions,
    sink: &mut S,
    link_setup: &mut dyn FnMut(&mut Link) -> std::io::Result<()>,
) -> Result<FlyReport, FlyError> {
    run_fly_flushing(scenario, opts, sink, &mut |_| {}, link_setup)
}

/// [`run_fly`], calling `flush` on the sink every [`crate::record::FLUSH_EVERY_ROWS`] rows and
/// every [`crate::record::FLUSH_INTERVAL_S`] of wall time while rows come, and at the end: a
/// companion killed mid-flight leaves the trace up to the last flush.
pub fn run_fly_flushing<S: TraceSink + ?Sized>(
    scenario: &Scenario,
    opts: &FlyOptions,
    sink: &mut S,
    flush: &mut dyn FnMut(&mut S),
    link_setup: &mut dyn FnMut(&mut Link) -> std::io::Result<()>,
) -> Result<FlyReport, FlyError> {
    let mut f = Flight::open(scenario, opts, sink, flush, link_setup)?;
    let end = loop {
        if let Some(end) = f.turn()? {
            break end;
        }
    };
    // A change of mode or arming still pending is the vehicle's last known state.
    f.flush_mode_log(true);
    let (acknowledged, way_out) = f.let_go(end)?;
    f.check_log();
    if let (Err(e), None) = (f.link.finish_log(), &f.log_incomplete) {
        let note = format!("cannot write the MAVLink log: {e}: its last frames are missing");
        f.event(note.clone());
        f.log_incomplete = Some(note);
    }
    f.record.finish(f.sink, f.flush);
    let completed = matches!(end, FlyEnd::VehicleEnded | FlyEnd::MaxDuration);
    let (metrics, metrics_over) = f.record.metrics(completed);
    let events = f.take_events();
    let events_live = if opts.live_events.is_some() {
        events.len().min(MAX_EVENTS - EVENTS_KEPT_LAST)
    } else {
        0
    };
    Ok(FlyReport {
        end,
        events_live,
        metrics,
        metrics_over,
        vehicle_heard: f.target.is_some(),
        commands: f.ans.commands,
        samples: f.ans.samples,
        t_first_s: f.ans.t_first,
        t_last_s: f.ans.t_last,
        events,
        failsafe_acknowledged: acknowledged,
        way_out_commanded: way_out,
        link: f.link.stats,
        measurements_out_of_order: f.ans.out_of_order,
        measurements_repeated: f.ans.repeated,
        way_out_overridden: f.way_out_overridden,
        measurements_invalid: f.invalid,
        measurements_other_sources: f.other_sources,
        other_system_heard: f.other_system,
        log_incomplete: f.log_incomplete,
    })
}

impl<'a, S: TraceSink + ?Sized> Flight<'a, S> {
    /// Checks the scenario, opens the link and the sensor.
    fn open(
        scenario: &Scenario,
        opts: &'a FlyOptions,
        sink: &'a mut S,
        flush: &'a mut dyn FnMut(&mut S),
        link_setup: &mut dyn FnMut(&mut Link) -> std::io::Result<()>,
    ) -> Result<Self, FlyError> {
        if scenario.tracker().needs_ground_truth() {
            return Err(FlyError::Scenario(
                "controller.kind = \"gradient_reference\" needs the field's gradient at the vehicle: it cannot fly on measurements alone".into(),
            ));
        }
        crate::wire::check_wire_times(scenario).map_err(FlyError::Scenario)?;
        check_level(scenario).map_err(FlyError::Scenario)?;
        let mut link =
            Link::open(&opts.url, opts.system_id, COMPANION_COMPONENT).map_err(FlyError::Link)?;
        link_setup(&mut link).map_err(FlyError::Io)?;
        let lines = match &opts.sensor {
            SensorSource::UdpLines(a) => {
                let s = UdpSocket::bind(a).map_err(|e| {
                    let taken = if e.kind() == std::io::ErrorKind::AddrInUse {
                        "the port is taken (by --mavlink's own udpin: port, or another process), and a port is never shared: "
                    } else {
                        ""
                    };
                    FlyError::Link(LinkError::Io(format!("--sensor udp:{a}: {taken}{e}")))
                })?;
                s.set_nonblocking(true).map_err(FlyError::Io)?;
                Some(s)
            }
            SensorSource::Named(_) => None,
        };
        Ok(Self::start(scenario, opts, sink, flush, link, lines))
    }

    /// The flight's state at its start, on an open link and sensor.
    // Long by choice: one struct literal, a line per field of the flight's state; grouped into
    // sub-structs, the file's ~650 `self.` uses of these fields would all change with it.
    fn start(
        scenario: &Scenario,
        opts: &'a FlyOptions,
        sink: &'a mut S,
        flush: &'a mut dyn FnMut(&mut S),
        link: Link,
        lines: Option<UdpSocket>,
    ) -> Self {
        let wanted = match &opts.sensor {
            SensorSource::Named(n) => n.as_bytes().to_vec(),
            SensorSource::UdpLines(_) => Vec::new(),
        };
        let opts_udp = lines.is_some();
        let planned_s = opts
            .max_duration_s
            .unwrap_or(scenario.file().sim.duration_s.unwrap_or(600.0));
        let now = Instant::now();
        Self {
            link,
            opts,
            transport: Transport::of(scenario),
            law: scenario.tracker(),
            level: scenario.level(),
            sink,
            flush,
            record: Recorder::new(scenario, planned_s),
            events: Vec::new(),
            events_last: VecDeque::new(),
            events_dropped: 0,
            mode_logged_at: None,
            modes_unlogged: 0,
            t0: now,
            // Never a panic on a huge timeout (the CLI bounds it to a day).
            timeout: Duration::try_from_secs_f64(opts.timeout_s.max(0.0))
                .unwrap_or(Duration::from_secs(86_400)),
            period: Duration::from_secs_f64(1.0 / opts.setpoint_rate_hz.max(2.0)),
            target: None,
            target_at: None,
            other_vehicle: None,
            other_system: None,
            mismatch: None,
            other_controller: None,
            run_end_how: None,
            link_gone: false,
            way_out_overridden: false,
            awaiting: None,
            firmware: Firmware::Px4,
            vehicle_type: MavType::MAV_TYPE_GENERIC,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            armed: false,
            custom_mode: None,
            run_ended: false,
            vehicle_done: false,
            last_link: now,
            last_heartbeat: now,
            beat_heard: now,
            beat_number: None,
            second_sender: false,
            lost_to_second_sender: false,
            vehicle_ms: None,
            reboot: None,
            landed: None,
            clock_behind: 0,
            rebased: None,
            disarm_seen: None,
            mavlink1_logged: false,
            twin_logged: false,
            echo_logged: false,
            unknown_mode_since: None,
            disarm_after_silence: false,
            peripheral_logged: false,
            late_vehicle_logged: false,
            vehicle_addr: None,
            same_ids: None,
            log_incomplete: None,
            seq_watch: Default::default(),
            fresh_at: now,
            doubts_logged: 0,
            pos_watch: Default::default(),
            window_passed: false,
            refused: false,
            refusal: None,
            refusal_pending: None,
            leave_seen: None,
            resyncs: 0,
            heartbeats: 0,
            beat_at: None,
            longest_beat_gap_s: 0.0,
            active: false,
            in_control: false,
            arm_sent: false,
            armed_by_us: false,
            offboard_sent: false,
            offboard_accepted_at: None,
            mode_at_first_command: None,
            armed_since_command: false,
            was_armed: false,
            next_control: now,
            control_tries: 0,
            control_first_at: None,
            tel: Telemetry::default(),
            lines,
            wanted,
            partial: Vec::new(),
            skipping_line: false,
            buf: if opts_udp {
                vec![0u8; 65_536]
            } else {
                Vec::new()
            },
            sensor_from: None,
            meas_from: None,
            other_sources: 0,
            pre_lock_tail: None,
            invalid: 0,
            held_dropped: 0,
            clock: SensorClock {
                newest_ms: None,
                last: now,
                fault: None,
                not_newer: 0,
                back_to: None,
            },
            clock_start: now,
            queue: VecDeque::new(),
            held_scanned: 0,
            held_newest: None,
            ans: Answers::default(),
            next_setpoint: now,
            next_heartbeat: now,
        }
    }

    fn event(&mut self, what: String) {
        let t = self.t0.elapsed().as_secs_f64();
        let line = format!("wall {t:.3} s: {what}");
        if self.events.len() < MAX_EVENTS - EVENTS_KEPT_LAST {
            if let Some(live) = &self.opts.live_events {
                (live.0)(&line);
            }
            self.events.push(line);
            return;
        }
        if self.events_last.is_empty() && self.events_dropped == 0 {
            if let Some(live) = &self.opts.live_events {
                (live.0)(&format!(
                    "wall {t:.3} s: {} events so far: the next are no longer printed as they happen (the last {} are printed at the end, the ones between counted)",
                    MAX_EVENTS - EVENTS_KEPT_LAST,
                    EVENTS_KEPT_LAST - 1
                ));
            }
        }
        self.events_last.push_back(line);
        if self.events_last.len() > EVENTS_KEPT_LAST - 1 {
            self.events_last.pop_front();
            self.events_dropped += 1;
        }
    }

    /// The events kept: the first ones, a count of those dropped between (if any), the last.
    fn take_events(&mut self) -> Vec<String> {
        let mut all = std::mem::take(&mut self.events);
        if self.events_dropped > 0 {
            all.push(format!(
                "{} events not kept (a flight keeps its first {} and its last {})",
                self.events_dropped,
                MAX_EVENTS - EVENTS_KEPT_LAST,
                EVENTS_KEPT_LAST - 1
            ));
        }
        all.extend(self.events_last.drain(..));
        all
    }

    fn send(&mut self, m: MavMessage) -> Result<(), FlyError> {
        self.link.send(&m).map(|_| ()).map_err(FlyError::Io)
    }

    /// One turn of the flight's loop; `Some` when the flight ends.
    fn turn(&mut self) -> Result<Option<FlyEnd>, FlyError> {
        if self.opts.stop.load(Ordering::Relaxed) {
            return Ok(Some(FlyEnd::Interrupted));
        }
        let now = Instant::now();
        if now >= self.next_heartbeat {
            self.heartbeat()?;
            self.next_heartbeat = now + Duration::from_secs(1);
        }
        let had_target = self.target.is_some();
        for r in self
            .link
            .poll(Duration::from_millis(10))
            .map_err(FlyError::Io)?
        {
            self.handle(&r);
        }
        self.flush_mode_log(false);
        if let Some(end) = self.check_vehicles(had_target) {
            return Ok(Some(end));
        }
        self.read_lines();
        let end = match self.check_fence() {
            Some(end) => Some(end),
            None => match self.control()? {
                Some(end) => Some(end),
                None => self.answer_queue()?,
            },
        };
        if end.is_some() {
            return Ok(end);
        }
        let end = self.check_ends()?;
        self.record.tick(self.sink, self.flush);
        self.check_log();
        Ok(end)
    }

    /// The two-vehicles check, the MAVLink 1 notice, and the sensor's timer from the vehicle's
    /// first message.
    fn check_vehicles(&mut self, had_target: bool) -> Option<FlyEnd> {
        if let Some(why) = self.mismatch.take() {
            self.event(why);
            return Some(FlyEnd::VehicleMismatch);
        }
        if let Some(why) = self.other_controller.take() {
            self.event(why);
            return Some(FlyEnd::AnotherController);
        }
        if let Some(why) = self.reboot.take() {
            self.event(why);
            return Some(FlyEnd::VehicleLost);
        }
        if let Some(why) = self.same_ids.take() {
            // Before control the companion goes no further (nothing commanded, exit 79, unless
            // a command already went out: the way out of it); in control, the way out.
            self.event(format!("vehicle_lost: {why}"));
            self.lost_to_second_sender = true;
            return Some(FlyEnd::VehicleLost);
        }
        if let (Some(a), Some(b)) = (self.target, self.other_vehicle) {
            let advice = if a.0 == b.0 {
                "both on one system, which --target-system cannot tell apart: have one of the two stop announcing itself as a vehicle's autopilot"
            } else {
                "pick one with --target-system"
            };
            let lag_s = self.target_at.map_or(0.0, |t| t.elapsed().as_secs_f64());
            let when = if self.in_control {
                format!("{lag_s:.1} s after the first, in control")
            } else {
                format!("{lag_s:.1} s after the first, before control")
            };
            // Something commanded already (control, an accepted OFFBOARD, an arming): the way
            // out of it goes to the vehicle flown (ver33b-1); else nothing is.
            let commanded = self.two_vehicles_way_out().is_some();
            self.event(format!(
                "two autopilots heard: system {}, component {} and system {}, component {} ({when}): which to fly is ambiguous, {} ({advice})",
                a.0,
                a.1,
                b.0,
                b.1,
                if commanded {
                    "the way out is commanded to the first"
                } else {
                    "nothing commanded"
                }
            ));
            return Some(FlyEnd::TwoVehicles);
        }
        if self.link.stats.mavlink1_frames > 0 && !self.mavlink1_logged {
            self.mavlink1_logged = true;
            self.event(
                "MAVLink 1 frames received and ignored: this bridge speaks MAVLink 2 only (set the autopilot's link to MAVLink 2)".into(),
            );
        }
        if !had_target && self.target.is_some() {
            // The sensor's silence counts from the vehicle's first message.
            self.clock.last = Instant::now();
            self.clock_start = Instant::now();
            self.last_heartbeat = Instant::now();
            self.beat_heard = Instant::now();
        }
        None
    }

    /// The vehicle's end, the periodic setpoint, and the timers: link, sensor clock, the
    /// companion's own clock for `max_duration_s`, sensor.
    fn check_ends(&mut self) -> Result<Option<FlyEnd>, FlyError> {
        if self.vehicle_done && self.run_ended {
            if let Some(how) = self
                .run_end_how
                .clone()
                .filter(|h| h == "interrupted" || h == "companion_lost")
            {
                // The vehicle went away before its run's end (Ctrl-C on `sitl`): a lost link,
                // not a completed flight.
                self.event(format!(
                    "link_lost: the vehicle's run was cut short ({how}) and it powered off: the vehicle is gone"
                ));
                self.link_gone = true;
                return Ok(Some(FlyEnd::LinkLost));
            }
        }
        if self.vehicle_done && !self.run_ended {
            self.event("the vehicle powered off without ending its run: vehicle lost".into());
            return Ok(Some(FlyEnd::VehicleLost));
        }
        if self.vehicle_done {
            self.event("the vehicle ended its run".into());
            return Ok(Some(FlyEnd::VehicleEnded));
        }
        let now = Instant::now();
        if self.target.is_some() && now >= self.next_setpoint {
            if self.may_send_setpoints() {
                self.setpoint(
                    self.ans
                        .last_answer_ms
                        .map_or(NOT_AN_ANSWER_MS, wire::wire_ms),
                )?;
            } else {
                // No setpoint may leave yet: a heartbeat at the setpoints' rate instead keeps
                // the companion heard (a lockstep vehicle counts its silence).
                self.heartbeat()?;
            }
            self.next_setpoint = now + self.period;
        }
        if let Some(what) = self.link_silent() {
            self.event(what);
            return Ok(Some(FlyEnd::LinkLost));
        }
        if let Some(what) = self.clock.fault.take() {
            self.event(what);
            return Ok(Some(FlyEnd::SensorClockJump));
        }
        if let (Some(max), Some(w)) = (self.opts.max_duration_s, self.ans.first_wall) {
            // The companion's own clock too: a vehicle clock that stalls cannot stretch the run.
            if now.duration_since(w).as_secs_f64() >= max {
                self.event(format!(
                    "max duration {max} s reached on the companion's clock"
                ));
                return Ok(Some(FlyEnd::MaxDuration));
            }
        }
        let waiting = self.opts.take_control && !self.window_passed;
        if !waiting && now.duration_since(self.clock.last) > self.timeout {
            self.event(match self.clock.not_newer {
                0 => format!("no measurement for {} s", self.opts.timeout_s),
                n => format!(
                    "no new measurement for {} s (the sensor's time not advancing: {n} measurements at or before its last time {} s)",
                    self.opts.timeout_s,
                    self.clock.newest_ms.map_or(0.0, wire::unwrapped_s)
                ),
            });
            return Ok(Some(FlyEnd::SensorLost));
        }
        Ok(None)
    }

    /// Whether the link is lost, in control and in the failsafe's retries alike (att45f-3):
    /// no message from the vehicle for `--timeout-s`, or no autopilot's heartbeat of its ids
    /// for that (at least [`MIN_HEARTBEAT_TIMEOUT_S`]; other messages may still come, a ground
    /// station's heartbeat with the ids among them, which says nothing of the vehicle's link),
    /// in words.
    fn link_silent(&self) -> Option<String> {
        let now = Instant::now();
        if now.duration_since(self.last_link) > self.timeout {
            return Some(format!(
                "no message from the vehicle for {} s{}",
                self.opts.timeout_s,
                self.doubt_at_loss()
            ));
        }
        let heartbeat_timeout = self
            .timeout
            .max(Duration::from_secs_f64(MIN_HEARTBEAT_TIMEOUT_S));
        // Without heartbeats the vehicle's mode and arming (a pilot's take-over, a disarm, the
        // autopilot's own failsafe) are unknown.
        (self.target.is_some() && now.duration_since(self.beat_heard) > heartbeat_timeout).then(
            || {
                format!(
                    "no heartbeat from the vehicle for {} s (other messages may still come): its mode and arming are unknown{}",
                    heartbeat_timeout.as_secs_f64(),
                    self.doubt_at_loss()
                )
            },
        )
    }

    /// Logs the raw MAVLink log's first write error at once (a disk that filled mid-flight):
    /// the flight goes on, the log's frames after it are missing (ver33-6).
    fn check_log(&mut self) {
        if self.log_incomplete.is_some() {
            return;
        }
        let Some(e) = self.link.log_error().map(|e| e.to_string()) else {
            return;
        };
        let t = self.t0.elapsed().as_secs_f64();
        let note = format!(
            "cannot write the MAVLink log: {e}: it stopped near wall {t:.3} s (the frames after it are missing)"
        );
        self.event(format!("{note}; the flight goes on"));
        self.log_incomplete = Some(note);
    }

    fn heartbeat(&mut self) -> Result<(), FlyError> {
        self.send(MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }))
    }

    fn command(&mut self, cmd: MavCmd, p: [f32; 3]) -> Result<(), FlyError> {
        let Some((sys, comp)) = self.target else {
            return Ok(());
        };
        self.send(MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: p[0],
            param2: p[1],
            param3: p[2],
            command: cmd,
            target_system: sys as u8,
            target_component: comp,
            ..Default::default()
        }))
    }

    /// The setpoint of the command in force, stamped `ms`: a fixed wing's roll of the turn,
    /// pitch of the altitude hold and thrust of the airspeed hold (body rates ignored); a ground
    /// vehicle's yaw rate (attitude and thrust ignored).
    fn setpoint(&mut self, ms: u32) -> Result<(), FlyError> {
        let Some((sys, comp)) = self.target else {
            return Ok(());
        };
        if !self.may_send_setpoints() {
            return Ok(());
        }
        let w = self.ans.current.unwrap_or(0.0);
        let ignore_rates = AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE
            | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE;
        let (q, yaw_rate, thrust, mask) = match self.transport {
            Transport::FixedWing { airspeed_mps } => {
                self.forget_stale_telemetry();
                let roll = wire::roll_of_turn_rate(w, airspeed_mps);
                let pitch = crate::setpoint::pitch_of_altitude(
                    self.tel.altitude_target_m,
                    self.tel.altitude_m,
                );
                (
                    crate::setpoint::quaternion_of_roll_pitch(roll, pitch),
                    0.0,
                    crate::setpoint::thrust_of_airspeed(airspeed_mps, self.tel.airspeed_mps) as f32,
                    ignore_rates
                        | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE,
                )
            }
            Transport::Ground => (
                [1.0, 0.0, 0.0, 0.0],
                wire::yaw_rate_of_turn_rate(w),
                0.0,
                ignore_rates
                    | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE
                    | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
            ),
        };
        self.send(MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            time_boot_ms: ms,
            q,
            body_roll_rate: 0.0,
            body_pitch_rate: 0.0,
            body_yaw_rate: yaw_rate,
            thrust,
            target_system: sys as u8,
            target_component: comp,
            type_mask: mask,
        }))
    }

    /// An altitude or airspeed older than `timeout_s` is unknown (the pitch hold's 0, the trim
    /// thrust), never flown on as if fresh: positions that stop would otherwise hold a frozen
    /// altitude error's pitch for ever. Logged once each.
    fn forget_stale_telemetry(&mut self) {
        let timeout = self.timeout;
        let stale = |at: Option<Instant>| at.is_some_and(|a| a.elapsed() > timeout);
        if self.tel.altitude_m.is_some() && stale(self.tel.altitude_at) {
            self.tel.altitude_m = None;
            if !self.tel.stale_logged.0 {
                self.tel.stale_logged.0 = true;
                self.event(format!(
                    "no altitude from the vehicle for {} s: the altitude hold's pitch is 0 until one comes",
                    self.opts.timeout_s
                ));
            }
        }
        if self.tel.airspeed_mps.is_some() && stale(self.tel.airspeed_at) {
            self.tel.airspeed_mps = None;
            if !self.tel.stale_logged.1 {
                self.tel.stale_logged.1 = true;
                self.event(format!(
                    "no airspeed from the vehicle for {} s: the thrust is the trim's until one comes",
                    self.opts.timeout_s
                ));
            }
        }
    }

    /// Whether a setpoint may leave: never before the vehicle is accepted (its type fits the
    /// scenario, [`vehicle_kind_match`], `MAV_TYPE_GENERIC` only as the rules say, and no other
    /// reason to refuse it pending); with `take_control`, only for a vehicle whose modes are
    /// known here (else control is never taken) and once it is armed (PX4 wants setpoints
    /// before the switch to OFFBOARD; none goes to a disarmed vehicle);
    /// without, the neutral setpoints that let the pilot hand over (PX4 refuses OFFBOARD
    /// without a stream) go to an accepted vehicle.
    fn may_send_setpoints(&self) -> bool {
        if self.opts.take_control && !self.window_closed() {
            return false;
        }
        if self.mismatch.is_some()
            || self.other_controller.is_some()
            || self.refused
            || self.disarm_seen.is_some()
        {
            return false;
        }
        let kind = vehicle_kind_match(self.transport, self.vehicle_type);
        let accepted = match kind {
            KindMatch::Yes => true,
            KindMatch::Unknown => !self.opts.take_control || self.opts.allow_generic,
            KindMatch::No => false,
        };
        if !accepted {
            return false;
        }
        if self.opts.take_control {
            // Before control, only once `take_control` has decided to take this vehicle (its
            // first command sent): a vehicle armed in RETURN or LAND is never sent a setpoint
            // while fly waits for the sensor and the position (a loaded machine widened that
            // window: take_control_never_pulls_a_vehicle_out_of_its_return).
            return self.in_control
                || (self.armed
                    && self.mode_at_first_command.is_some()
                    && self.firmware.set_mode_params(FlyMode::Offboard).is_some());
        }
        true
    }

    /// Reads the UDP sensor's datagrams: at most [`crate::link::MAX_DATAGRAMS_PER_POLL`] a
    /// turn (a flood delays, never starves, the link). A line may span datagrams: the tail
    /// after the last newline waits for the rest (at most [`MAX_PARTIAL_LINE_BYTES`], else
    /// dropped).
    fn read_lines(&mut self) {
        let Some(s) = self.lines.take() else {
            return;
        };
        let mut text = String::new();
        let mut overlong = 0u64;
        for _ in 0..crate::link::MAX_DATAGRAMS_PER_POLL {
            let Ok((n, from)) = s.recv_from(&mut self.buf) else {
                break;
            };
            if !self.sensor_datagram_taken(from, n) {
                continue;
            }
            self.partial.extend_from_slice(&self.buf[..n]);
            if self.skipping_line {
                // The rest of a dropped over-long line is no line.
                match self.partial.iter().position(|&b| b == b'\n') {
                    Some(i) => {
                        self.partial.drain(..=i);
                        self.skipping_line = false;
                    }
                    None => {
                        self.partial.clear();
                        continue;
                    }
                }
            }
            let Some(end) = self.partial.iter().rposition(|&b| b == b'\n') else {
                if self.partial.len() > MAX_PARTIAL_LINE_BYTES {
                    self.partial.clear();
                    self.skipping_line = true;
                    overlong += 1;
                }
                continue;
            };
            text.push_str(&String::from_utf8_lossy(&self.partial[..end]));
            text.push('\n');
            self.partial.drain(..=end);
            if self.partial.len() > MAX_PARTIAL_LINE_BYTES {
                self.partial.clear();
                self.skipping_line = true;
                overlong += 1;
            }
        }
        self.lines = Some(s);
        for _ in 0..overlong {
            self.invalid_measurement(format!(
                "a --sensor line longer than {MAX_PARTIAL_LINE_BYTES} bytes"
            ));
        }
        for line in text.lines() {
            if line.trim().is_empty() {
                continue;
            }
            match parse_sensor_line(line) {
                Some((ms, v)) => self.clock.receive(&mut self.queue, ms, v),
                None => {
                    let shown: String = line.chars().take(80).collect();
                    self.invalid_measurement(format!(
                        "the --sensor line {shown:?} is not `t_s,value` (two numbers, t_s in [0, 4294967.295] s, value finite within +-{MAX_MEASUREMENT_ABS:e})"
                    ));
                }
            }
        }
    }

    /// Whether the UDP sensor's datagram of `n` bytes (in `buf`) from `from` is the sensor's.
    /// The sensor is the first sender of a datagram holding a complete valid line (ended by
    /// its newline; an unterminated tail locks nothing): before it, a
    /// datagram without one (a port scanner's, a broadcast) is no measurement (counted in
    /// `measurements_invalid`) and locks nothing. Another sender's datagrams are dropped
    /// (counted in `measurements_other_sources`, logged once).
    fn sensor_datagram_taken(&mut self, from: std::net::SocketAddr, n: usize) -> bool {
        match self.sensor_from {
            Some(a) if a == from => true,
            None => {
                // This sender's unterminated tail before, dropped, waits for its end here (a
                // line may span datagrams); a NUL marks one that is no line (over-long).
                let mut joined = match self.pre_lock_tail.take() {
                    Some((a, t)) if a == from => t,
                    _ => Vec::new(),
                };
                let tail_len = joined.len();
                joined.extend_from_slice(&self.buf[..n]);
                if holds_a_valid_line(&joined) {
                    if joined[..tail_len] == [0] {
                        // The rest of a dropped over-long line is no line either.
                        self.skipping_line = true;
                    } else {
                        self.partial = joined[..tail_len].to_vec();
                    }
                    self.sensor_from = Some(from);
                    self.event(format!(
                        "sensor: --sensor lines from {from} (the first sender of a valid line; any other sender's are dropped)"
                    ));
                    return true;
                }
                let start = joined
                    .iter()
                    .rposition(|&b| b == b'\n')
                    .map_or(0, |i| i + 1);
                let tail = &joined[start..];
                self.pre_lock_tail = Some((
                    from,
                    if tail.len() > MAX_PARTIAL_LINE_BYTES || (start == 0 && tail.starts_with(&[0]))
                    {
                        vec![0]
                    } else {
                        tail.to_vec()
                    },
                ));
                self.invalid_measurement(format!(
                    "a --sensor datagram from {from} holding no `t_s,value` line, before the sensor's first valid one"
                ));
                false
            }
            Some(_) => {
                self.other_source(format!("--sensor: a datagram from {from}"));
                false
            }
        }
    }

    /// A measurement that is none: dropped (never given to the law), counted, the first one
    /// logged.
    fn invalid_measurement(&mut self, what: String) {
        self.invalid += 1;
        if self.invalid == 1 {
            self.event(format!(
                "{what}: dropped, no measurement (counted in measurements_invalid, logged once)"
            ));
        }
    }

    /// The fence, on the received position (never given to the law), once the companion has
    /// control: centred on the position where control began (a pilot may fly the vehicle to
    /// the area first, FLYING.md's recipe), never enforced before (a failsafe before control
    /// commands nothing anyway); no position for `timeout_s` since control began, positions
    /// that stop, or farther than `fence_m` from that centre.
    fn check_fence(&mut self) -> Option<FlyEnd> {
        let timeout_s = self.opts.timeout_s;
        let f = self.opts.fence_m?;
        let control_at = self.ans.first_wall.filter(|_| self.in_control)?;
        if self.tel.pos.is_none() && control_at.elapsed() > self.timeout {
            self.event(format!(
                "fence: no position from the vehicle for {timeout_s} s since the companion has control, the fence of {f} m cannot be kept"
            ));
            return Some(FlyEnd::Fence);
        }
        if let Some(at) = self.tel.position_at {
            // The fence never silently switches off: positions that stop (or turn non-finite,
            // which are dropped) end the flight.
            if at.elapsed() > self.timeout {
                self.event(format!(
                    "position_lost: no finite position from the vehicle for {timeout_s} s, the fence of {f} m cannot be kept"
                ));
                return Some(FlyEnd::Fence);
            }
        }
        if self.tel.local_seen && !self.tel.home_local {
            // Positions were projected from GLOBAL_POSITION_INT: the fence re-anchors on the
            // first local one.
            self.tel.home_local = true;
            self.tel.home = None;
        }
        let p = self.tel.pos?;
        let h = *self.tel.home.get_or_insert(p);
        let d = ((p.0 - h.0).powi(2) + (p.1 - h.1).powi(2)).sqrt();
        if d > f {
            self.event(format!(
                "fence: {d:.1} m from where the companion got control, beyond {f} m"
            ));
            return Some(FlyEnd::Fence);
        }
        None
    }

    /// Control: in OFFBOARD or not, a pilot's take-over, and with `take_control` the arming
    /// and the switch to OFFBOARD (retried every 0.5 s for 10 s), once the sensor and a
    /// position are there.
    fn control(&mut self) -> Result<Option<FlyEnd>, FlyError> {
        if let Some(end) = self.note_active() {
            return Ok(Some(end));
        }
        if let Some(end) = self.unconfirmed_leave() {
            return Ok(Some(end));
        }
        if let Some(end) = self.offboard_not_ours() {
            return Ok(Some(end));
        }
        if self.active {
            self.control_taken();
        } else if self.in_control {
            return Ok(self.control_left());
        }
        if !self.opts.take_control || self.active {
            return Ok(None);
        }
        if self.refusal_still_pending() {
            return Ok(None);
        }
        if self.refused {
            let what = match self.refusal.take() {
                Some(r) => format!("the vehicle refused {r}"),
                None => format!(
                    "the vehicle refused to arm or to switch to {}",
                    self.firmware.name_of(FlyMode::Offboard)
                ),
            };
            self.event(what);
            return Ok(Some(FlyEnd::ControlRefused));
        }
        if let Some(end) = self.pilot_during_take_over() {
            return Ok(Some(end));
        }
        if self.pilots_word_pending() {
            // A pilot's word awaiting confirmation: nothing more commanded meanwhile.
            return Ok(None);
        }
        self.take_control()
    }

    /// Decides whether the vehicle is flown now (`active`: armed in OFFBOARD, or in control
    /// armed in an unknown mode) (FLYING.md, "Control"); asks for OFFBOARD at once on an
    /// arming; ends the flight (`LinkLost`) on no known mode for `timeout_s` in control.
    fn note_active(&mut self) -> Option<FlyEnd> {
        if self.armed != self.was_armed {
            // Armed: ask for OFFBOARD at once.
            self.was_armed = self.armed;
            self.next_control = Instant::now();
        }
        self.active = self.armed
            && self
                .custom_mode
                .is_some_and(|c| self.firmware.is_in(c, FlyMode::Offboard));
        if self.in_control && self.armed && self.custom_mode.is_none() {
            // In control, a heartbeat armed in an unknown mode (no custom-mode flag: a relay
            // rewriting base_mode, a glitch) is no pilot's word (ver33b-10): the companion
            // carries on as in control, logged once; no known mode for `timeout_s` is a lost
            // link (the way out commanded: OFFBOARD may still hold).
            let since = *self.unknown_mode_since.get_or_insert_with(Instant::now);
            if since.elapsed() > self.timeout {
                self.event(format!(
                    "no known mode from the vehicle for {} s (armed, its heartbeat without a custom mode): its mode is unknown, the link as good as lost",
                    self.opts.timeout_s
                ));
                return Some(FlyEnd::LinkLost);
            }
            self.active = true;
        } else {
            self.unknown_mode_since = None;
        }
        None
    }

    /// Decides whether a vehicle armed in OFFBOARD is someone else's to fly (FLYING.md,
    /// "Another controller", "The pilot's word is final"): another controller's, before the
    /// companion asked for it, or a pilot's, armed again after a disarm watched for a reboot.
    fn offboard_not_ours(&mut self) -> Option<FlyEnd> {
        if self.active && self.opts.take_control && !self.in_control && !self.offboard_sent {
            // Armed and in OFFBOARD, and the companion asked for neither: someone else (another
            // companion, a ground station's offboard) holds it. --take-control never joins.
            let offboard = self.firmware.name_of(FlyMode::Offboard);
            self.event(format!(
                "another_controller: the vehicle is armed and in {offboard} and the companion commanded neither: another controller holds it; nothing commanded (without --take-control, fly flies a vehicle its pilot has put in {offboard})"
            ));
            self.active = false;
            return Some(FlyEnd::AnotherController);
        }
        if self.active && self.in_control && self.disarm_seen.is_some() {
            // Disarmed and armed again while the disarm was watched for a reboot: the disarm
            // was nobody's here, so a pilot's (att33d-3): never flown on, no setpoint.
            self.event(format!(
                "pilot_took_over: the vehicle was disarmed, not by the companion, and is armed again in {}: setpoints stopped, nothing commanded",
                self.mode_name()
            ));
            self.active = false;
            return Some(FlyEnd::PilotTookOver);
        }
        None
    }

    /// The companion has control (FLYING.md, "Control"): the first time, the change that gave
    /// it and a refusal it overrode are logged, and --max-duration-s starts counting.
    fn control_taken(&mut self) {
        if !self.in_control && self.held_dropped > 0 {
            // None held: those from before a doubt of the frame counter were dropped at its
            // resync, none came since (att53f-8).
            let from = if self.queue.is_empty() {
                "the first measurement to come"
            } else {
                "the newest measurement held meanwhile"
            };
            self.event(format!(
                "control taken: the law starts from {from} ({} older ones dropped, never answered)",
                self.held_dropped
            ));
        }
        if !self.in_control {
            // The change that gave the companion control is logged at once (ver33-3).
            self.flush_mode_log(true);
            if self.refusal_pending.take().is_some() {
                let refusal = self.refusal.take().unwrap_or_default();
                self.event(format!(
                    "the refusal heard ({refusal}) was not the vehicle's last word: its heartbeat shows it armed in {} (the refusal answered someone else's command)",
                    self.mode_name()
                ));
            }
        }
        self.in_control = true;
        // --max-duration-s counts from here (the companion's clock).
        self.ans.first_wall.get_or_insert_with(Instant::now);
    }

    /// Decides what the vehicle leaving OFFBOARD or disarmed, in control and not commanded by
    /// the companion, means (FLYING.md, "The pilot's word is final"): `None` while a disarm
    /// is watched for a reboot (no setpoint meanwhile), else a pilot took over.
    fn control_left(&mut self) -> Option<FlyEnd> {
        if !self.armed {
            // A disarm nobody here commanded: a pilot's, or an autopilot that rebooted (its
            // heartbeat may come before its clock says so). No setpoint leaves while the
            // vehicle's next time-stamped message is awaited (REBOOT_WATCH_S at most).
            let since = *self.disarm_seen.get_or_insert_with(Instant::now);
            let clock_since = self.vehicle_ms.is_some_and(|(_, at)| at > since);
            if !clock_since && since.elapsed().as_secs_f64() < REBOOT_WATCH_S {
                return None;
            }
        }
        // Nothing of the companion's leaves OFFBOARD or disarms during the flight: a pilot
        // (or the autopilot's own failsafe) took over. Stop at once and command nothing.
        self.flush_mode_log(true);
        let what = format!(
            "pilot_took_over: the vehicle is {} in {}, not commanded by the companion{}: setpoints stopped, nothing commanded",
            if self.armed { "armed" } else { "disarmed" },
            self.mode_name(),
            self.maybe_rebooted()
        );
        self.event(what);
        Some(FlyEnd::PilotTookOver)
    }

    /// The vehicle shown disarmed after a silence of more than [`REBOOT_STEP_S`]
    /// ([`Flight::disarm_after_silence`]: a reboot whose clock did not go back far enough to
    /// say so, or not yet in two frames, looks the same as a pilot's disarm, att33d-9a), in
    /// words for the log line that ends the flight: taken as the pilot's, or a failsafe while
    /// it awaits confirmation (att49f's CB: `sensor_clock_jump`, a measurement stamped by the
    /// rebooted clock); empty otherwise.
    fn maybe_rebooted(&self) -> String {
        silence_note(!self.armed && self.disarm_after_silence)
    }

    /// A refusal heard ([`Flight::refusal_pending`], ver33b-11) is the vehicle's last word once
    /// a heartbeat newer than it, and than any acceptance of the switch after it, shows the
    /// command not carried out, or `timeout_s` passes without one (`refused`). A command
    /// carried out all the same (armed; armed in OFFBOARD is control taken, in `control`)
    /// answered someone else's: the take-over goes on. Nothing is commanded while it is
    /// pending; whether it is.
    fn refusal_still_pending(&mut self) -> bool {
        let Some((cmd, at)) = self.refusal_pending else {
            return false;
        };
        let newest = match self.offboard_accepted_at {
            Some(a) if cmd == MavCmd::MAV_CMD_DO_SET_MODE && a > at => a,
            _ => at,
        };
        let heard = self.last_heartbeat > newest;
        if !heard && newest.elapsed() < self.timeout {
            return true;
        }
        self.refusal_pending = None;
        if heard && cmd == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && self.armed {
            let refusal = self.refusal.take().unwrap_or_default();
            self.event(format!(
                "the refusal heard ({refusal}) was not the vehicle's last word: its heartbeat shows it armed since (the refusal answered someone else's command): the take-over goes on"
            ));
            return false;
        }
        self.refused = true;
        false
    }

    /// In control, a change out of OFFBOARD or a disarm not yet confirmed ([`LeaveSeen`],
    /// ver33c-1) is flown on (`active`); one confirmed by a heartbeat back in OFFBOARD (one
    /// sender's change and back) is the pilot's word: `pilot_took_over`, nothing commanded.
    fn unconfirmed_leave(&mut self) -> Option<FlyEnd> {
        let l = self.leave_seen.as_ref()?;
        if !l.confirmed {
            if self.in_control {
                self.active = true;
            }
            return None;
        }
        if !l.back {
            return None;
        }
        let what = l.what.clone();
        self.flush_mode_log(true);
        self.event(format!(
            "pilot_took_over: the vehicle was {what}, then {} in {}, neither commanded by the companion ({}){}: setpoints stopped, nothing commanded",
            if self.armed { "armed" } else { "disarmed" },
            self.mode_name(),
            match (self.seq_watch.doubts, self.resyncs) {
                (0, _) => "no second sender with its ids seen: one sender's".to_string(),
                (d, n) => format!(
                    "no second sender with its ids proven, though its frame counter was in doubt {d} time{} before the word ({n} resynchronised as one sender's)",
                    if d == 1 { "" } else { "s" }
                ),
            },
            if self.in_control { "" } else { ", during the take-over" }
        ));
        self.active = false;
        Some(FlyEnd::PilotTookOver)
    }

    /// The pilot's word is final during a take-over too: once the companion has sent its first
    /// control command (an arming or the switch to OFFBOARD), a disarm after the vehicle was
    /// armed, or a change of mode to anything but OFFBOARD, that the companion did not command
    /// ends the take-over once the next heartbeat confirms it ([`LeaveSeen`]): never re-armed,
    /// nothing more commanded (`pilot_took_over`).
    fn pilot_during_take_over(&mut self) -> Option<FlyEnd> {
        let before = self.mode_at_first_command?;
        if self.armed {
            self.armed_since_command = true;
        }
        let offboard = self
            .custom_mode
            .is_some_and(|c| self.firmware.is_in(c, FlyMode::Offboard));
        let what = if self.armed_since_command && !self.armed {
            "disarmed"
        } else if before.is_some() && self.custom_mode != before && !offboard {
            "switched"
        } else {
            return None;
        };
        if self.leave_seen.as_ref().is_none_or(|l| !l.confirmed) {
            // Not yet confirmed by the next heartbeat ([`LeaveSeen`], ver33c-1).
            return None;
        }
        let mode = self.mode_name();
        self.event(format!(
            "pilot_took_over during the take-over: the vehicle was {what} (now {} in {mode}) before the companion had control, not by its command: nothing more commanded, the pilot's word stands",
            if self.armed { "armed" } else { "disarmed" }
        ));
        Some(FlyEnd::PilotTookOver)
    }

    /// Why `take_control` does not take the vehicle as it is, if it does not: a return or a
    /// landing; armed, a mode not on [`Firmware::takeover_allowed`]'s list, or an unknown one
    /// (no custom mode in its heartbeat), or PX4's numbers read from an autopilot that is not
    /// PX4 (`MAV_AUTOPILOT_GENERIC` and others: their modes are not known here). A disarmed
    /// vehicle (armed only with `arm`, a simulator's) is taken from any mode but a return or a
    /// landing.
    fn not_takeable(&self) -> Option<String> {
        if let Some(name) = self
            .custom_mode
            .and_then(|c| self.firmware.returning_or_landing(c))
        {
            return Some(format!(
                "{name} (returning or landing: its autopilot's failsafe or its pilot's choice)"
            ));
        }
        if !self.armed {
            return None;
        }
        if self.firmware == Firmware::Px4 && self.autopilot != MavAutopilot::MAV_AUTOPILOT_PX4 {
            return Some(format!(
                "{} (its autopilot is {:?}, whose mode numbers are not known here: only MAV_AUTOPILOT_PX4's and ArduPilot's are)",
                self.mode_name(),
                self.autopilot
            ));
        }
        match self.custom_mode {
            None => Some("an unknown mode (its heartbeat carries no custom mode)".into()),
            Some(c) if !self.firmware.takeover_allowed(c) => Some(format!(
                "{} (not a mode a pilot flies or holds in: taking off, landing, avoiding, on a mission or unknown here; see docs/FLYING.md for the modes taken)",
                self.mode_name()
            )),
            Some(_) => None,
        }
    }

    /// The vehicle's mode in logs.
    fn mode_name(&self) -> String {
        self.custom_mode
            .map_or("an unknown mode".into(), |c| self.firmware.mode_name(c))
    }

    /// Whether [`TWO_VEHICLES_WINDOW_S`] has passed since the vehicle was first heard (always,
    /// with `target_system`): before, nothing but heartbeats is sent.
    fn window_closed(&self) -> bool {
        self.opts.target_system.is_some()
            || self
                .target_at
                .is_some_and(|at| at.elapsed().as_secs_f64() >= TWO_VEHICLES_WINDOW_S)
    }

    /// `take_control`'s steps: nothing is armed before the sensor and the position are there
    /// (each within `timeout_s`) and [`TWO_VEHICLES_WINDOW_S`] has passed; then arm, then
    /// OFFBOARD.
    fn take_control(&mut self) -> Result<Option<FlyEnd>, FlyError> {
        if self.target.is_none() || !self.window_closed() {
            return Ok(None);
        }
        if !self.window_passed {
            // The sensor's and the position's silence count from here: the window was the
            // companion's own wait (a lockstep vehicle resends its unanswered sample meanwhile).
            self.window_passed = true;
            self.clock.last = Instant::now();
            self.clock_start = Instant::now();
        }
        let ready = self.clock.newest_ms.is_some() && self.tel.pos.is_some();
        if !ready && self.clock.newest_ms.is_some() && self.clock_start.elapsed() > self.timeout {
            self.event(format!(
                "no position from the vehicle for {} s: control not taken",
                self.opts.timeout_s
            ));
            return Ok(Some(FlyEnd::SensorLost));
        }
        if !ready || Instant::now() < self.next_control {
            return Ok(None);
        }
        if self.armed
            && self
                .offboard_accepted_at
                .is_some_and(|at| self.last_heartbeat <= at)
        {
            // Accepted: never sent again before a heartbeat newer than the acknowledgement
            // says what the vehicle did (with a 1 Hz heartbeat a retry would override a pilot
            // who switched meanwhile); nor given up before it, at the bound too (att45f-8: a
            // vehicle that may be in OFFBOARD is commanded out of it, one that shows the
            // pilot's mode is left in it). Its silence is a lost link ([`Flight::link_silent`]).
            self.next_control = Instant::now() + Duration::from_millis(100);
            return Ok(None);
        }
        let offboard = self.firmware.name_of(FlyMode::Offboard);
        let first = *self.control_first_at.get_or_insert_with(Instant::now);
        if self.control_tries >= 20 || first.elapsed().as_secs_f64() >= TAKE_CONTROL_S {
            self.event(format!(
                "the vehicle did not arm or switch to {offboard} in {TAKE_CONTROL_S} s"
            ));
            return Ok(Some(FlyEnd::ControlRefused));
        }
        self.control_tries += 1;
        // Without a mode table for this vehicle nothing is commanded, not even the arming
        // (an armed vehicle that fly cannot switch to OFFBOARD would only be disarmed again).
        let Some(p) = self.firmware.set_mode_params(FlyMode::Offboard) else {
            let what = format!(
                "{}: no mode table here, control not taken",
                self.firmware.name()
            );
            self.event(what);
            return Ok(Some(FlyEnd::ControlRefused));
        };
        if self.mode_at_first_command.is_none() {
            if let Some(end) = self.first_command_refused() {
                return Ok(Some(end));
            }
        }
        self.command_control(p)?;
        self.next_control = Instant::now() + Duration::from_millis(500);
        Ok(None)
    }

    /// Decides, before the first command of the take-over, whether the vehicle may be taken
    /// (FLYING.md, "Control"): never from a mode its pilot does not fly or hold in, never a
    /// disarmed one without --arm (`ControlRefused`, logged); else notes its mode and arming
    /// then.
    fn first_command_refused(&mut self) -> Option<FlyEnd> {
        // A vehicle on its way home or down (its autopilot's failsafe, or its pilot's
        // choice), taking off, avoiding traffic, or in a mode not known here is never
        // pulled out of it: an armed vehicle is taken only from a mode its pilot flies or
        // holds in ([`Firmware::takeover_allowed`]).
        if let Some(why) = self.not_takeable() {
            self.event(format!(
                "the vehicle is {} in {why}: --take-control never pulls it out, nothing commanded",
                if self.armed { "armed" } else { "disarmed" }
            ));
            return Some(FlyEnd::ControlRefused);
        }
        if !self.armed && !self.opts.arm {
            self.event(
                "the vehicle is disarmed: --take-control arms it only with --arm (for simulators: a real aircraft is armed and flown to the area by its pilot, then taken over), nothing commanded".into(),
            );
            return Some(FlyEnd::ControlRefused);
        }
        self.mode_at_first_command = Some(self.custom_mode);
        self.armed_since_command = self.armed;
        None
    }

    /// The take-over's next command (FLYING.md, "Control"): the arming of a disarmed vehicle,
    /// else a setpoint and the switch to OFFBOARD (`offboard`: its parameters).
    fn command_control(&mut self, offboard: [f32; 3]) -> Result<(), FlyError> {
        if !self.armed {
            self.arm_sent = true;
            self.awaiting = Some((MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, Instant::now()));
            self.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, [1.0, 0.0, 0.0])?;
        } else {
            // PX4 wants setpoints before the switch.
            self.setpoint(
                self.ans
                    .last_answer_ms
                    .map_or(NOT_AN_ANSWER_MS, wire::wire_ms),
            )?;
            self.offboard_sent = true;
            self.awaiting = Some((MavCmd::MAV_CMD_DO_SET_MODE, Instant::now()));
            self.command(MavCmd::MAV_CMD_DO_SET_MODE, offboard)?;
        }
        Ok(())
    }

    /// Answers the measurements queued (held while `take_control` waits for control): a new
    /// one by the law (in control) or a neutral setpoint, a repeat by the same setpoint again,
    /// an older one dropped; each new one recorded.
    fn answer_queue(&mut self) -> Result<Option<FlyEnd>, FlyError> {
        if self.pilots_word_pending() {
            // A pilot's word awaiting confirmation ends the flight however it turns out
            // ([`LeaveSeen`]): no measurement is answered meanwhile (the vehicle may be the
            // pilot's already); the last setpoint is repeated (`check_ends`).
            return Ok(None);
        }
        if self.opts.take_control && !self.active {
            // A vehicle sends again the measurement nobody answered (sitl in lockstep, every
            // second): held copies of one time are one measurement, never a repeat to count.
            // Only what came since the last turn is looked at (the cost stays per message).
            // Only the newest one is kept: once in control, the law starts from the freshest
            // sample, never a burst of stale ones (a slow take-over of a fast sensor).
            let start = self.held_scanned.min(self.queue.len());
            let fresh: Vec<(u64, f64)> = self.queue.drain(start..).collect();
            for (ms, v) in fresh {
                if self.held_newest == Some(ms) {
                    continue;
                }
                if self.held_newest.is_some_and(|n| ms < n) {
                    self.held_dropped += 1;
                    continue;
                }
                self.held_newest = Some(ms);
                self.held_dropped += self.queue.len() as u64;
                self.queue.clear();
                self.queue.push_back((ms, v));
            }
            self.held_scanned = self.queue.len();
            return Ok(None);
        }
        while let Some((ms, v)) = self.queue.pop_front() {
            match self.ans.last_answer_ms {
                Some(last) if ms < last => self.out_of_order(ms, last),
                Some(last) if ms == last => self.repeat(ms)?,
                _ => {
                    if let Some(end) = self.answer(ms, v)? {
                        return Ok(Some(end));
                    }
                }
            }
        }
        Ok(None)
    }

    /// A measurement older than one answered: dropped (counted, logged once).
    fn out_of_order(&mut self, ms: u64, last: u64) {
        self.ans.out_of_order += 1;
        if self.ans.out_of_order == 1 {
            self.event(format!(
                "a measurement stamped {} s came after one stamped {} s: out of order, dropped (never given to the law; counted in measurements_out_of_order, logged once)",
                wire::unwrapped_s(ms),
                wire::unwrapped_s(last)
            ));
        }
    }

    /// A repeat (the vehicle lost the answer?): the same answer again, within a UDP sensor's
    /// `setpoint_rate_hz`; counted, logged once.
    fn repeat(&mut self, ms: u64) -> Result<(), FlyError> {
        // Before control the vehicle waits for a pilot (or for OFFBOARD) and sends its
        // unanswered sample again: expected, not counted.
        // Nor are copies of the measurement held through a take-over that arrive after control
        // (sent before the vehicle saw the answer; a loaded machine widens that window).
        if self.active && self.ans.last_answer_in_control && self.held_newest != Some(ms) {
            self.ans.repeated += 1;
        }
        if self.ans.repeated == 1 && !self.ans.repeat_logged {
            self.ans.repeat_logged = true;
            self.event(format!(
                "the measurement stamped {} s came again: answered again, not given to the law twice (counted in measurements_repeated, logged once)",
                wire::unwrapped_s(ms)
            ));
        }
        if self.lines.is_none() || Instant::now() >= self.next_setpoint {
            self.setpoint(wire::wire_ms(ms))?;
            self.next_setpoint = Instant::now() + self.period;
        }
        Ok(())
    }

    /// A new measurement: the law's answer (in control), its setpoint and its trace row.
    fn answer(&mut self, unwrapped_ms: u64, v: f64) -> Result<Option<FlyEnd>, FlyError> {
        // The law's time is unwrapped (never going back at the wrap); the wire's stamps are
        // `time_boot_ms`.
        let ms = wire::wire_ms(unwrapped_ms);
        let m = Measurement {
            t_s: wire::unwrapped_s(unwrapped_ms),
            value: v,
        };
        self.ans.t_first.get_or_insert(m.t_s);
        // --max-duration-s counts from the first measurement the law answers in control
        // (vehicle time).
        if self.active {
            let first = *self.ans.t_control.get_or_insert(m.t_s);
            if let Some(max) = self.opts.max_duration_s {
                if m.t_s - first >= max {
                    self.event(format!(
                        "max duration {max} s reached at vehicle time {} s",
                        m.t_s
                    ));
                    return Ok(Some(FlyEnd::MaxDuration));
                }
            }
        }
        self.ans.samples += 1;
        self.ans.t_last = Some(m.t_s);
        if self.active {
            let w = self.law.update(&m);
            if !w.is_finite() {
                self.event(format!(
                    "the law's command is not finite at t = {} s",
                    m.t_s
                ));
                return Ok(Some(FlyEnd::LawNotFinite));
            }
            self.ans.commands.push((ms, w));
            self.ans.current = Some(w);
            self.record.observe(m.t_s, v - self.level, w);
        } else {
            self.ans.current = None;
        }
        self.ans.last_answer_ms = Some(unwrapped_ms);
        self.ans.last_answer_in_control = self.active;
        // A MAVLink sensor's every sample is answered (a lockstep vehicle waits for it); a UDP
        // sensor's answers keep to --setpoint-rate-hz (the periodic setpoint carries the newest
        // command): a fast sensor does not multiply the setpoints.
        if self.lines.is_none() || Instant::now() >= self.next_setpoint {
            self.setpoint(ms)?;
            self.next_setpoint = Instant::now() + self.period;
        }
        let row = TraceRow {
            t_s: m.t_s,
            x_m: f64::NAN,
            y_m: f64::NAN,
            heading_rad: f64::NAN,
            s: v,
            error: v - self.level,
            omega_radps: self.ans.current.unwrap_or(0.0),
            s_measured: Some(v),
            telemetry: None,
        };
        // A MAVLink measurement is on the vehicle's clock: paired by time; a UDP line by arrival.
        let at = self.lines.is_none().then_some(ms);
        self.record.row(self.sink, row, at);
        Ok(None)
    }

    /// Handles one received message: the vehicle's heartbeat (which vehicle, its firmware,
    /// armed, mode), the measurement, acknowledgements, positions, attitude, airspeed.
    fn handle(&mut self, r: &Received) {
        let from = (r.header.system_id, r.header.component_id);
        if self.link.is_own_echo(r) {
            // The companion's own frame come back (a loop in the link): no twin's (ver33-4).
            if !self.echo_logged {
                self.echo_logged = true;
                self.event(
                    "the companion's own frames came back (the same ids, numbers and contents it sent: a loop in the link?): ignored, not a second companion".into(),
                );
            }
            return;
        }
        if let MavMessage::HEARTBEAT(h) = &r.msg {
            if from == (self.opts.system_id as u32, COMPANION_COMPONENT) {
                self.twin_heard(r.from);
            }
            self.find_vehicle(from, h);
        }
        let Some(target) = self.target else { return };
        // The frame's unwrapped number on the vehicle's counter (its ids' frames only).
        let mut number = None;
        let mut kind = None;
        if from == target {
            match self.ids_frame(r) {
                // A copy of a frame already handled, delivered again (maybe late: att33f-2):
                // never evidence, never applied; in a doubt, the link speaking all the same
                // ([`Flight::copy_frame`]).
                (FrameKind::Copy, _) => return self.copy_frame(&r.msg),
                // In a doubt (a first conflict, att37-1): the link is alive, nothing else but a
                // pilot's word a heartbeat shows (att42f-5).
                (FrameKind::Doubt, _) => {
                    self.doubt_frame(&r.msg);
                    if let MavMessage::HEARTBEAT(h) = &r.msg {
                        self.doubt_word(h);
                    }
                    return;
                }
                (k, n) => (kind, number) = (Some(k), Some(n)),
            }
        }
        self.foreign_setpoint(from, target, &r.msg);
        // The measurement may come from another component of the vehicle's system.
        if from.0 != target.0 {
            return;
        }
        if let MavMessage::NAMED_VALUE_FLOAT(n) = &r.msg {
            if !self.wanted.is_empty() && name_of(&n.name[..]) == self.wanted {
                self.named_measurement(from, n);
            }
            return;
        }
        if from != target {
            return;
        }
        let silent_s = self.last_link.elapsed().as_secs_f64();
        self.last_link = Instant::now();
        match &r.msg {
            MavMessage::HEARTBEAT(h) => self.vehicle_beat(h, number, silent_s),
            _ => self.vehicle_telemetry(r, kind),
        }
    }

    /// Decides what a heartbeat of the vehicle's ids (number `number` on their frame counter,
    /// after `silent_s` without a frame of theirs) says in control (FLYING.md, "The vehicle",
    /// "The pilot's word is final"): nothing of the vehicle if not an autopilot's; only that
    /// the link is alive after a second sender or if older than the last applied; else the
    /// vehicle's state.
    fn vehicle_beat(&mut self, h: &HEARTBEAT_DATA, number: Option<u64>, silent_s: f64) {
        // Not an autopilot's (a ground station's, an onboard controller's: att42f-4): never
        // the vehicle's state, nor its heartbeat (it says nothing of the vehicle's link).
        if !is_autopilot(h) {
            return;
        }
        if self.second_sender {
            // Every heartbeat of the ids keeps the link alive (S11: a link that delivers each
            // heartbeat one frame late); after a second sender none is the vehicle's word.
            self.beat_heard = Instant::now();
        } else if number.zip(self.beat_number).is_some_and(|(n, b)| n <= b) {
            // Older than the last heartbeat applied (a late one, att33e-2): not the vehicle's
            // state now, never applied (a late OFFBOARD one after a pilot's MANUAL would read
            // as a change and back); one that contradicts a pilot's word pending restarts it.
            self.beat_heard = Instant::now();
            self.older_beat(h);
        } else {
            self.last_heartbeat = Instant::now();
            self.beat_heard = self.last_heartbeat;
            self.beat_number = number.or(self.beat_number);
            let was_armed = self.armed;
            let was = (self.custom_mode, self.armed);
            self.vehicle_heartbeat(h);
            self.watch_leave(was);
            self.note_beat();
            if was_armed && !self.armed {
                // A disarm after a silence: a reboot (whose clock need not go back far
                // enough to say so) looks the same as a pilot's disarm (att33d-9a).
                self.disarm_after_silence = silent_s > REBOOT_STEP_S;
            }
        }
    }

    /// Takes what a frame of the vehicle's ids other than a heartbeat (`kind` on their frame
    /// counter) tells (FLYING.md, "Control", "Setpoint"): an acknowledgement before control, its
    /// position, attitude, airspeed, landed state, a simulator's end of run.
    fn vehicle_telemetry(&mut self, r: &Received, kind: Option<FrameKind>) {
        match &r.msg {
            // Acknowledgements go to every peer of the vehicle: once in control, they may
            // answer someone else's command, and say nothing about ours.
            MavMessage::COMMAND_ACK(a) if !self.in_control && !self.ack_for_another(r) => {
                self.acknowledged(a)
            }
            // A non-finite position is no position (it would switch the fence off).
            MavMessage::LOCAL_POSITION_NED(p) if p.x.is_finite() && p.y.is_finite() => {
                self.tel.local_seen = true;
                if p.z.is_finite() {
                    self.altitude(-p.z as f64, p.time_boot_ms);
                }
                self.position(p.time_boot_ms, (p.y as f64, p.x as f64));
            }
            // Invalid: marked in the trace (no position), never the last one repeated.
            MavMessage::LOCAL_POSITION_NED(p) if self.tel.local_seen => {
                self.record.no_position(p.time_boot_ms)
            }
            MavMessage::GLOBAL_POSITION_INT(g) if !self.tel.local_seen => self.global_position(g),
            MavMessage::STATUSTEXT(t)
                if name_of(&t.text[..]).starts_with(b"isotrack sitl: run ended") =>
            {
                self.run_ended = true;
                // "run ended (HOW)": HOW is the run's outcome, or how it was cut short.
                let text = String::from_utf8_lossy(name_of(&t.text[..])).into_owned();
                self.run_end_how = text
                    .split_once('(')
                    .and_then(|(_, rest)| rest.split_once(')'))
                    .map(|(how, _)| how.to_string());
            }
            MavMessage::ATTITUDE(a) if a.yaw.is_finite() => {
                let heading =
                    isotrack_core::math::wrap_angle(std::f64::consts::FRAC_PI_2 - a.yaw as f64);
                self.record.heading(a.time_boot_ms, heading);
            }
            MavMessage::VFR_HUD(v) if v.airspeed.is_finite() => {
                self.tel.airspeed_mps = Some(v.airspeed as f64);
                self.tel.airspeed_at = Some(Instant::now());
            }
            // Newer than the last (a late one is the vehicle's past).
            MavMessage::EXTENDED_SYS_STATE(e) if kind == Some(FrameKind::New) => {
                self.landed = Some(e.landed_state)
            }
            _ => {}
        }
    }

    /// A frame of the vehicle's ids through every check of a second sender or a reboot, one
    /// and the same in control ([`Flight::handle`]) and in the failsafe's retries
    /// ([`Flight::await_way_out`], att45f-1/-2/-10): its source address
    /// ([`Flight::vehicle_address`]), its number on their frame counter
    /// ([`Flight::vehicle_sender`]); then, unless a copy or in a doubt, a new frame's clock
    /// ([`Flight::vehicle_time`]: the reboot test reads new frames only, a late one or a copy
    /// is one sender's reordered past, never its clock begun again, att37-2) and a position's
    /// jump ([`Flight::position_jumps`]). Returns what the frame is and its unwrapped number.
    fn ids_frame(&mut self, r: &Received) -> (FrameKind, u64) {
        self.vehicle_address(r.from);
        let before = (self.seq_watch.in_doubt(), self.seq_watch.resyncs);
        let (kind, number) = self.vehicle_sender(r);
        self.doubt_news(kind, r.header.sequence, before);
        if matches!(kind, FrameKind::Copy | FrameKind::Doubt) {
            return (kind, number);
        }
        if kind == FrameKind::New {
            if let Some(ms) = vehicle_time_ms(&r.msg) {
                self.vehicle_time(ms);
            }
        }
        if let Some((ms, p)) = self.position_of(&r.msg) {
            self.position_jumps(ms, p);
        }
        (kind, number)
    }

    /// The position (x east, y north, m) a frame of the vehicle's ids gives, stamped with its
    /// clock: a finite `LOCAL_POSITION_NED`'s, or a `GLOBAL_POSITION_INT`'s while no local
    /// position has come ([`Flight::global_local`]).
    fn position_of(&mut self, msg: &MavMessage) -> Option<(u32, (f64, f64))> {
        match msg {
            MavMessage::LOCAL_POSITION_NED(p) if p.x.is_finite() && p.y.is_finite() => {
                Some((p.time_boot_ms, (p.y as f64, p.x as f64)))
            }
            MavMessage::GLOBAL_POSITION_INT(g) if !self.tel.local_seen => {
                self.global_local(g).map(|p| (g.time_boot_ms, p))
            }
            _ => None,
        }
    }

    /// A frame of the vehicle's ids in a doubt ([`FrameKind::Doubt`]: a first conflict of
    /// their frame numbers, two senders not proven): the link is alive; nothing in it is the
    /// vehicle's state or a confirmation (a heartbeat in it showing a pilot's word counts as
    /// one awaiting confirmation: [`Flight::doubt_word`]).
    fn doubt_frame(&mut self, msg: &MavMessage) {
        self.heard_at(msg, Instant::now());
    }

    /// A frame of the vehicle's ids classed a copy ([`FrameKind::Copy`]): never evidence, never
    /// applied, and outside a doubt nothing more (a link that doubles frames). In a doubt of
    /// the frame counter it keeps the link alive as every frame of the doubt does
    /// ([`Flight::doubt_frame`], an autopilot's heartbeat the vehicle's heartbeat heard), but
    /// only as of the last frame of the ids that was no copy ([`Flight::fresh_at`]): a copy
    /// there is one in either window, and an unchanging heartbeat is identical to the last one
    /// with its number (its next one, on a counter the doubt has not settled, may read as that
    /// one's copy), while a repeater re-sending a dead vehicle's last frame sends nothing else
    /// (att49f-1: a doubt fed only copies never settles, and kept the link without bound).
    fn copy_frame(&mut self, msg: &MavMessage) {
        if self.seq_watch.in_doubt() {
            self.heard_at(msg, self.fresh_at);
        }
    }

    /// A frame of the vehicle's ids that keeps the link alive as if it had come `at` (never
    /// moving the link's clocks back), an autopilot's heartbeat the vehicle's heartbeat heard.
    fn heard_at(&mut self, msg: &MavMessage, at: Instant) {
        self.last_link = self.last_link.max(at);
        if matches!(msg, MavMessage::HEARTBEAT(h) if is_autopilot(h)) {
            self.beat_heard = self.beat_heard.max(at);
        }
    }

    /// After a frame of the vehicle's ids (`kind`, numbered `seq`; `before`: whether a doubt
    /// was open and the resynchronisations before it): when the ids last sent a frame that
    /// was no copy ([`Flight::copy_frame`]), and the log of a doubt of their frame counter that
    /// opens (once each) or ends by a silence (its other ends are logged where they happen:
    /// [`Flight::vehicle_sender`], a resynchronisation or a second sender proven).
    fn doubt_news(&mut self, kind: FrameKind, seq: u8, before: (bool, u64)) {
        if kind != FrameKind::Copy {
            self.fresh_at = Instant::now();
        }
        if kind == FrameKind::Doubt && self.seq_watch.doubts > self.doubts_logged {
            self.doubts_logged = self.seq_watch.doubts;
            self.event(format!(
                "the vehicle's frame counter in doubt: a frame numbered {seq} is another than the one seen with its number (a burst of frames lost, or another sender with the ids): nothing received from the ids is applied until the doubt ends (settled on one counter, two senders proven, or a silence), and copies of their frames keep the link alive only as of the last frame that was none"
            ));
        }
        let (was_in_doubt, resyncs) = before;
        let ended = was_in_doubt && !self.seq_watch.in_doubt();
        if ended && kind != FrameKind::Conflict && self.seq_watch.resyncs == resyncs {
            self.event(
                "the doubt of the vehicle's frame counter ended with a silence of its ids: the frame watch starts afresh (this frame the first)".into(),
            );
        }
    }

    /// The doubt of the vehicle's frame counter open when the link is lost, in words (empty
    /// if none): copies of the vehicle's frames kept it no longer than its last frame that
    /// was none ([`Flight::copy_frame`]).
    fn doubt_at_loss(&self) -> String {
        if !self.seq_watch.in_doubt() {
            return String::new();
        }
        format!(
            " (the vehicle's frame counter in doubt; the last frame of its ids that was no copy came at wall {:.3} s)",
            self.fresh_at.duration_since(self.t0).as_secs_f64()
        )
    }

    /// Whether the vehicle's last `EXTENDED_SYS_STATE` said it is in the air (taking off,
    /// flying or landing).
    /// A ground scenario's vehicle (a rover, a boat) is on the ground whatever it reports
    /// (att39f-4: PX4's rover land detector says IN_AIR whenever armed, so a rover fly armed
    /// on the ground was left armed in HOLD instead of getting the owed disarm).
    fn reports_in_air(&self) -> bool {
        !matches!(self.transport, Transport::Ground)
            && matches!(
                self.landed,
                Some(
                    MavLandedState::MAV_LANDED_STATE_IN_AIR
                        | MavLandedState::MAV_LANDED_STATE_TAKEOFF
                        | MavLandedState::MAV_LANDED_STATE_LANDING
                )
            )
    }

    /// The way out owed to a vehicle the companion armed and never had in control
    /// ([`Flight::disarm_owed`]): the disarm (forced), but the failsafe mode if the vehicle
    /// reports itself in the air (att37-3: `isotrack sitl`'s fixed wing, armed).
    fn owed_way_out(&self) -> WayOut {
        if self.reports_in_air() {
            WayOut::Mode(self.opts.failsafe.mode())
        } else {
            WayOut::Disarm
        }
    }

    /// A `NAMED_VALUE_FLOAT` of the sensor's name from the vehicle's system: the first sender
    /// (system, component) of a valid one is the sensor, as a UDP sensor's first sender is;
    /// another component's are dropped (counted in `measurements_other_sources`, logged once),
    /// never flown (two senders interleaving would flip the law's error). A value not
    /// [`plausible_value`] is no measurement.
    fn named_measurement(&mut self, from: (u32, u8), n: &NAMED_VALUE_FLOAT_DATA) {
        let v = n.value as f64;
        if self.meas_from.is_some_and(|m| m != from) {
            self.other_source(format!(
                "NAMED_VALUE_FLOAT {} from system {}, component {}",
                String::from_utf8_lossy(&self.wanted),
                from.0,
                from.1
            ));
            return;
        }
        if !plausible_value(v) {
            self.invalid_measurement(format!(
                "NAMED_VALUE_FLOAT {} stamped {} s from system {}, component {} is {} (a plausible value is finite and within +-{MAX_MEASUREMENT_ABS:e})",
                String::from_utf8_lossy(&self.wanted),
                wire::time_s(n.time_boot_ms),
                from.0,
                from.1,
                isotrack_core::numtext::Echo(v)
            ));
            return;
        }
        if self.meas_from.is_none() {
            self.meas_from = Some(from);
            self.event(format!(
                "sensor: NAMED_VALUE_FLOAT {} from system {}, component {} (the first sender of a valid one; any other sender's are dropped)",
                String::from_utf8_lossy(&self.wanted),
                from.0,
                from.1
            ));
        }
        self.clock.receive(&mut self.queue, n.time_boot_ms, v);
    }

    /// A measurement (or a UDP sensor's datagram) from another sender than the sensor's:
    /// dropped, counted, the first logged.
    fn other_source(&mut self, what: String) {
        self.other_sources += 1;
        if self.other_sources == 1 {
            let sensor = match (self.meas_from, self.sensor_from) {
                (Some(m), _) => format!("system {}, component {}", m.0, m.1),
                (None, Some(a)) => a.to_string(),
                (None, None) => "none yet".into(),
            };
            self.event(format!(
                "{what}: not the sensor ({sensor}, the first sender of a valid measurement): dropped, as every other sender's (counted in measurements_other_sources, logged once)"
            ));
        }
    }

    /// The source address of a frame with the vehicle's ids (UDP): the first one is the
    /// vehicle's; a second address sending with the same ids is a second vehicle left at the
    /// same system id (two PX4s at the default 1 on one radio), whose measurements and
    /// positions would mix with the first's (att33d-10): the flight ends `vehicle_lost`, before
    /// control with nothing commanded, in control with the way out commanded.
    fn vehicle_address(&mut self, addr: Option<std::net::SocketAddr>) {
        let Some(a) = addr else { return };
        match self.vehicle_addr {
            None => self.vehicle_addr = Some(a),
            Some(first) if first != a && self.same_ids.is_none() => {
                let t = self.target.unwrap_or_default();
                self.second_sender_seen(format!(
                    "two vehicles with the ids (system {}, component {}): frames from {first} and from {a} (two autopilots left at one system id on one link, or one vehicle over two paths): their measurements and positions would mix, which to fly is ambiguous",
                    t.0, t.1
                ));
            }
            _ => {}
        }
    }

    /// A frame with the vehicle's ids, checked for a second sender with them on one address
    /// ([`crate::same_ids`]): two different frames with one number within the window, a
    /// heartbeat of another type or autopilot than the vehicle's first. Returns what the frame
    /// is ([`FrameKind`]) and its unwrapped number.
    fn vehicle_sender(&mut self, r: &Received) -> (FrameKind, u64) {
        let wall_s = self.t0.elapsed().as_secs_f64();
        let (kind, number) = self.seq_watch.frame(r.header.sequence, &r.msg, wall_s);
        let t = self.target.unwrap_or_default();
        let ids = format!(
            "two vehicles with the ids (system {}, component {})",
            t.0, t.1
        );
        if let Some(rs) = self.seq_watch.take_resync() {
            // A doubt ended with no proof: one sender whose link lost a burst. The heartbeats'
            // "newer than the last applied" starts again here (the next one is applied), and a
            // pilot's word awaiting confirmation stands its span again from now.
            self.beat_number = None;
            if let Some(l) = self.leave_seen.as_mut().filter(|l| !l.confirmed) {
                l.at = Instant::now();
            }
            self.held_before_the_doubt_dropped();
            self.resyncs += 1;
            self.event(format!(
                "the vehicle's frame counter jumped by {} numbers ({} frames lost in a burst?) and nothing showed a second sender in the next {} frames ({:.2} s) of doubt: resynchronised as one sender{} (the frames of the doubt were not applied; {} such jump{} since the start; another conflict within {} s of this is taken as a second sender)",
                rs.jump,
                (rs.jump as u32 + 255) % 256,
                rs.frames,
                rs.secs,
                if rs.on_old {
                    ", on the counter from before the jump (the frames after it were strays, or the sender lost 256 more than the jump)"
                } else {
                    ""
                },
                self.resyncs,
                if self.resyncs == 1 { "" } else { "s" },
                crate::same_ids::RESYNC_MEMORY_S
            ));
        }
        match (
            kind,
            self.seq_watch.resumed_from,
            self.seq_watch.after_resync_s,
        ) {
            (FrameKind::Conflict, Some(old), _) => self.second_sender_seen(format!(
                "{ids}: a frame numbered {} goes on from the counter's {old}, more than {} numbers past it, with frames of the counter that came back behind {old} at a conflict there between them (one sender's own late frames go at most a few numbers past {old}; two counters going on side by side are two senders'): their measurements and positions would mix, which to fly is ambiguous",
                r.header.sequence,
                crate::same_ids::REORDER
            )),
            (FrameKind::Conflict, None, Some(after_s)) => self.second_sender_seen(format!(
                "{ids}: a frame numbered {} conflicts with the one seen with its number {after_s:.1} s after the counter was resynchronised as one sender's (a link loses a burst of one sender's frames now and then, not twice within {} s; a second sender near the vehicle's counter conflicts at each of its frames): their measurements and positions would mix, which to fly is ambiguous",
                r.header.sequence,
                crate::same_ids::RESYNC_MEMORY_S
            )),
            (FrameKind::Conflict, None, None) => self.second_sender_seen(format!(
                "{ids}: two different frames numbered {} within the last {} numbers of their counter (a link loses, delays or doubles one sender's frames, never numbers two different ones alike: MAVLink's frame counters of two senders): their measurements and positions would mix, which to fly is ambiguous",
                r.header.sequence,
                crate::same_ids::SEQUENCE_WINDOW
            )),
            _ => {}
        }
        // A heartbeat that is no autopilot's (a ground station or an onboard controller
        // misconfigured with the vehicle's ids, att42f-4) is never the vehicle's state, nor
        // another vehicle: only its frame counts, above, as any frame of the ids (whoever sends
        // frames with the ids numbers them on its own counter, so a sender other than the
        // vehicle shows there as a second sender; skipping its heartbeats would leave its
        // other frames with the ids to the counter all the same).
        if let (FrameKind::New | FrameKind::Late, MavMessage::HEARTBEAT(h)) = (kind, &r.msg) {
            if is_autopilot(h) && (h.mavtype != self.vehicle_type || h.autopilot != self.autopilot)
            {
                self.second_sender_seen(format!(
                    "{ids}: a heartbeat of {:?} ({:?}) after the vehicle's {:?} ({:?}) (a second vehicle with its ids, or its autopilot changed): which to fly is ambiguous",
                    h.mavtype, h.autopilot, self.vehicle_type, self.autopilot
                ));
            }
        }
        (kind, number)
    }

    /// A doubt of the vehicle's frame counter ended resynchronised while `take_control` holds
    /// the measurements: those held are from before the doubt (nothing of the ids is applied
    /// in it), dropped as older ones are (counted in the "control taken" line), so that the law
    /// starts from a measurement received after the resync and `--max-duration-s`, on the
    /// vehicle's clock from the first measurement answered in control, counts from control's
    /// start (att53f-8: control taken 20 ms after a resync answered one 1.4 s old first, and
    /// the 3 s flight was cut to 1.56 s).
    fn held_before_the_doubt_dropped(&mut self) {
        if !self.opts.take_control || self.active || self.in_control {
            return;
        }
        self.held_dropped += self.queue.len() as u64;
        self.queue.clear();
        self.held_scanned = 0;
        // A lockstep vehicle sends its unanswered measurement again: held as received now.
        self.held_newest = None;
    }

    /// A second sender with the vehicle's ids, `why`: the flight ends `vehicle_lost`
    /// ([`Flight::check_vehicles`]), and from now on no heartbeat of the ids is the vehicle's
    /// word (neither a pilot's nor a confirmation) and no disarm is sent: either sender may
    /// be the vehicle, maybe flying ([`Flight::way_out`]).
    fn second_sender_seen(&mut self, why: String) {
        if !self.second_sender {
            self.second_sender = true;
            // A reboot found in the same poll and not yet acted on is the second sender's
            // clock interleaved with the vehicle's (att53f-7), no reboot: from here on the
            // clock watch reads nothing ([`Flight::vehicle_time`]).
            self.reboot = None;
            self.clock_behind = 0;
            self.same_ids.get_or_insert(why);
        }
    }

    /// A heartbeat of the vehicle's ids older than the last applied one (a late one): never
    /// applied; if it shows another arming or mode than a pilot's word still awaiting
    /// confirmation, the word has not stood uncontradicted: its span starts again (a second
    /// vehicle whose frame counter runs ahead of the vehicle's makes every heartbeat of the
    /// vehicle's older than its own, att33h-2/-3; one sender's heartbeat delivered after a
    /// newer one only delays the word).
    fn older_beat(&mut self, h: &HEARTBEAT_DATA) {
        let armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        let shows = (mode_of(h), armed);
        let now = (self.custom_mode, self.armed);
        if let Some(l) = self.leave_seen.as_mut().filter(|l| !l.confirmed) {
            if shows != now {
                l.at = Instant::now();
            }
        }
    }

    /// A time of the vehicle's own clock: one more than [`REBOOT_STEP_S`] behind the newest is
    /// a reboot (its autopilot's clock begins again at 0). A reboot found makes the rebooted
    /// clock the newest: the watch goes on from it, so the failsafe's retries that follow
    /// (att45f-10) stop only on a reboot after it, never on the one that caused the failsafe,
    /// whose frames all lie behind the clock before it (att49f-2).
    ///
    /// Once a second sender with the ids has been seen, the watch reads nothing: two autopilots
    /// never share a clock, and their interleaved frames step it back and forth, which is no
    /// reboot of the vehicle flown (att53f-6: the second sender's clock 50 s behind stopped the
    /// two-sender retries after 1 try as "its autopilot rebooted").
    fn vehicle_time(&mut self, ms: u32) {
        if self.second_sender {
            return;
        }
        let now = Instant::now();
        let Some((newest, _)) = self.vehicle_ms else {
            self.vehicle_ms = Some((ms as u64, now));
            return;
        };
        let t = wire::unwrap_ms(newest, ms);
        if t + ((REBOOT_STEP_S * 1000.0) as u64) < newest {
            if self.same_step_as_sensor(t) {
                // The step back the measurements' clock made (`sensor_clock_jump`, the
                // failsafe it ends control with): one step is seen once (att53f-1).
                self.clock_rebased(newest, t, now);
                return;
            }
            // One frame that far back is a late one (a link that reorders or delays), dropped;
            // two in a row are the clock begun again: a reboot (att33d-4).
            self.clock_behind += 1;
            if self.clock_behind < 2 {
                return;
            }
            self.reboot.get_or_insert(format!(
                "vehicle_lost: the vehicle's clock (time_boot_ms) went back from {} s to {} s: its autopilot rebooted (not a pilot's take-over)",
                wire::unwrapped_s(newest),
                wire::unwrapped_s(t)
            ));
            self.clock_rebased(newest, t, now);
            return;
        } else {
            self.clock_behind = 0;
        }
        if self.clock_ahead_of_reboot(t) {
            return;
        }
        self.vehicle_ms = Some((newest.max(t), now));
    }

    /// After the vehicle's clock went back ([`Flight::rebased`]), whether a time `t`
    /// (unwrapped, ms) runs ahead of the rebooted clock by more than the time since plus
    /// [`REBOOT_STEP_S`], back at (within [`REBOOT_STEP_S`]) or past the time it went back from
    /// (att53f-4: a second sender at the vehicle's address with a clock 50 s behind read as a
    /// reboot, then the vehicle's own clock back where it was): no rebooted autopilot's clock
    /// does that, two clocks are two senders ([`Flight::second_sender_seen`]).
    fn clock_ahead_of_reboot(&mut self, t: u64) -> bool {
        let Some((from, to, at)) = self.rebased else {
            return false;
        };
        let since = at.elapsed().as_millis() as u64;
        let step = (REBOOT_STEP_S * 1000.0) as u64;
        if t <= to + since + step || t + step < from {
            return false;
        }
        let ids = self.target.unwrap_or_default();
        self.second_sender_seen(format!(
            "two vehicles with the ids (system {}, component {}): the vehicle's clock (time_boot_ms) went back from {} s to {} s (read as its autopilot's reboot), then a frame of the ids stamped {} s came {:.3} s after, {:.3} s ahead of that clock: no rebooted autopilot's clock runs ahead so; two clocks are two senders: their measurements and positions would mix, which to fly is ambiguous",
            ids.0,
            ids.1,
            wire::unwrapped_s(from),
            wire::unwrapped_s(to),
            wire::unwrapped_s(t),
            since as f64 / 1000.0,
            (t - to - since) as f64 / 1000.0
        ));
        true
    }

    /// Whether a time `t` (unwrapped, ms) of the vehicle's clock, more than [`REBOOT_STEP_S`]
    /// behind its newest, lies where the measurements' clock jumped back to
    /// ([`SensorClock::back_to`], as much later as has passed since, within [`REBOOT_STEP_S`]):
    /// the measurement stamped by the vehicle's clock, the two went back together, one step
    /// (taken once: a later step is another).
    fn same_step_as_sensor(&mut self, t: u64) -> bool {
        let Some((back, at)) = self.clock.back_to else {
            return false;
        };
        let newest = self.vehicle_ms.map_or(t, |v| v.0);
        let expected =
            wire::unwrap_ms(newest, wire::wire_ms(back)) + at.elapsed().as_millis() as u64;
        let same = t.abs_diff(expected) <= (REBOOT_STEP_S * 1000.0) as u64;
        if same {
            self.clock.back_to = None;
        }
        same
    }

    /// The vehicle's clock watch re-based on `t` (unwrapped, ms), where its clock went back
    /// to from `newest` (a reboot found, or the measurements' step back): the watch goes on
    /// from the rebooted clock.
    fn clock_rebased(&mut self, newest: u64, t: u64, now: Instant) {
        self.clock_behind = 0;
        self.vehicle_ms = Some((t, now));
        self.rebased = Some((newest, t, now));
    }

    /// A heartbeat: the first autopilot heard is the vehicle (or `target_system`'s); another
    /// within [`TWO_VEHICLES_WINDOW_S`] makes it ambiguous.
    fn find_vehicle(&mut self, from: (u32, u8), h: &HEARTBEAT_DATA) {
        let wanted_system = self.opts.target_system.is_none_or(|n| from.0 == n as u32);
        if !is_autopilot(h) || from == (self.opts.system_id as u32, 191) {
            return;
        }
        if !wanted_system {
            if self.other_system.is_none() {
                self.other_system = Some(from);
                self.event(format!(
                    "an autopilot of system {} (component {}) beats, not --target-system {}: not flown (a mistyped id?)",
                    from.0,
                    from.1,
                    self.opts.target_system.unwrap_or(0)
                ));
            }
            return;
        }
        match (self.target, self.target_at) {
            (None, _) => {
                self.target = Some(from);
                self.target_at = Some(Instant::now());
                self.firmware = Firmware::of(h.autopilot, h.mavtype);
                self.vehicle_type = h.mavtype;
                self.autopilot = h.autopilot;
                self.check_kind(from, h.mavtype);
                let what = format!(
                    "vehicle: system {}, component {}{}, {} modes",
                    from.0,
                    from.1,
                    if self.opts.target_system.is_some() {
                        " (--target-system)"
                    } else {
                        " (the first autopilot heard)"
                    },
                    self.firmware.name()
                );
                self.event(what);
            }
            (Some(t), _) if t != from && t.0 == from.0 && self.peripheral(t, from, h) => {}
            (Some(t), Some(at)) if t != from && self.opts.target_system.is_none() => {
                if !self.in_control || at.elapsed().as_secs_f64() < TWO_VEHICLES_WINDOW_S {
                    self.other_vehicle.get_or_insert(from);
                } else if !self.late_vehicle_logged {
                    self.late_vehicle_logged = true;
                    self.event(format!(
                        "another autopilot (system {}, component {}) heard in flight: not flown, the companion flies system {}, component {}",
                        from.0, from.1, t.0, t.1
                    ));
                }
            }
            _ => {}
        }
    }

    /// Two autopilot heartbeats on one system, the vehicle's `t` and `from`'s `h`: a
    /// `MAV_TYPE_GENERIC` one on another component than `MAV_COMP_ID_AUTOPILOT1` (1) beside
    /// component 1's is a peripheral (a MAVSDK-based payload announces GENERIC), not a second
    /// vehicle: ignored (logged once). Heard first, it gives way to component 1 while nothing
    /// has been commanded. Whether that was the case.
    fn peripheral(&mut self, t: (u32, u8), from: (u32, u8), h: &HEARTBEAT_DATA) -> bool {
        let generic = |c: u8, ty: MavType| c != 1 && ty == MavType::MAV_TYPE_GENERIC;
        let what = if from.1 == 1
            && generic(t.1, self.vehicle_type)
            && h.mavtype != MavType::MAV_TYPE_GENERIC
        {
            if self.mode_at_first_command.is_some() || self.in_control || self.arm_sent {
                return false;
            }
            // Component 1 is the vehicle: taken instead, as if heard first.
            self.target = Some(from);
            self.vehicle_addr = None;
            self.seq_watch = Default::default();
            self.beat_number = None;
            self.pos_watch = Default::default();
            self.firmware = Firmware::of(h.autopilot, h.mavtype);
            self.vehicle_type = h.mavtype;
            self.autopilot = h.autopilot;
            self.mismatch = None;
            self.check_kind(from, h.mavtype);
            format!(
                "vehicle: system {}, component 1 (its autopilot), {} modes, not component {} (MAV_TYPE_GENERIC: a peripheral, ignored)",
                from.0,
                self.firmware.name(),
                t.1
            )
        } else if t.1 == 1 && generic(from.1, h.mavtype) {
            format!(
                "a MAV_TYPE_GENERIC heartbeat from system {}, component {}: a peripheral beside the vehicle's autopilot (component 1), ignored",
                from.0, from.1
            )
        } else {
            return false;
        };
        if !self.peripheral_logged {
            self.peripheral_logged = true;
            self.event(what);
        }
        true
    }

    /// Whether the vehicle's `type` fits the scenario's kind: a mismatch ends the flight before
    /// any setpoint or command; `MAV_TYPE_GENERIC` is flown with a warning when the pilot
    /// hands over, and refused with `take_control` unless `allow_generic`.
    fn check_kind(&mut self, from: (u32, u8), mavtype: MavType) {
        let kind = kind_name(self.transport);
        let types = match self.transport {
            Transport::FixedWing { .. } => FIXED_WING_TYPES,
            Transport::Ground => GROUND_TYPES,
        };
        let list = types
            .iter()
            .map(|t| format!("{t:?}"))
            .collect::<Vec<_>>()
            .join(", ");
        match vehicle_kind_match(self.transport, mavtype) {
            KindMatch::Yes => {}
            KindMatch::Unknown if self.opts.take_control && !self.opts.allow_generic => {
                self.mismatch = Some(format!(
                    "vehicle_mismatch: the vehicle (system {}, component {}) announces {mavtype:?}, which says nothing of its airframe: --take-control refuses it before any setpoint or command (the scenario's vehicle is {kind}: {list}); if it is one, pass --allow-generic",
                    from.0, from.1
                ));
            }
            KindMatch::Unknown => self.event(format!(
                "the vehicle (system {}, component {}) announces {mavtype:?}, which says nothing of its airframe: flown as the scenario's vehicle, {kind}; make sure it is one ({list})",
                from.0, from.1
            )),
            KindMatch::No => {
                self.mismatch = Some(format!(
                    "vehicle_mismatch: the scenario's vehicle is {kind}, but the vehicle (system {}, component {}) announces {mavtype:?}: refused before any setpoint or command (the scenario's kind flies {list}, or MAV_TYPE_GENERIC)",
                    from.0, from.1
                ));
            }
        }
    }

    /// A setpoint for the vehicle's system from another sender than the companion (heard
    /// through a router that forwards every component's traffic, or the vehicle's own link):
    /// another controller.
    fn foreign_setpoint(&mut self, from: (u32, u8), target: (u32, u8), msg: &MavMessage) {
        if self.other_controller.is_some() {
            return;
        }
        // The link never hands the companion its own frames back: a setpoint with its own
        // system and component id comes from a twin (a second companion with the same ids).
        let twin = from == (self.opts.system_id as u32, 191);
        let (what, to) = match msg {
            MavMessage::SET_ATTITUDE_TARGET(m) => ("SET_ATTITUDE_TARGET", m.target_system),
            MavMessage::SET_POSITION_TARGET_LOCAL_NED(m) => {
                ("SET_POSITION_TARGET_LOCAL_NED", m.target_system)
            }
            MavMessage::SET_POSITION_TARGET_GLOBAL_INT(m) => {
                ("SET_POSITION_TARGET_GLOBAL_INT", m.target_system)
            }
            _ => return,
        };
        if to as u32 != target.0 {
            return;
        }
        self.other_controller = Some(format!(
            "another_controller: {what} for the vehicle (system {}) from system {}, component {}, not the companion{}: another controller is flying it; the companion's setpoints stop",
            target.0,
            from.0,
            from.1,
            if twin {
                " (its own ids: a second companion with the same --system-id)"
            } else {
                ""
            }
        ));
    }

    /// A heartbeat with the companion's own ids (the link never hands it its own frames): a
    /// second companion with the same `--system-id`. Logged once; with `take_control` the
    /// companion goes no further (`another_controller`: before control nothing is commanded,
    /// in control the failsafe's way out), as two companions would fly one vehicle.
    fn twin_heard(&mut self, addr: Option<std::net::SocketAddr>) {
        if self.twin_logged {
            return;
        }
        self.twin_logged = true;
        let what = format!(
            "a second companion with this one's ids (system {}, component {COMPANION_COMPONENT}) beats{}",
            self.opts.system_id,
            addr.map_or(String::new(), |a| format!(" from {a}"))
        );
        if self.opts.take_control {
            self.other_controller.get_or_insert(format!(
                "another_controller: {what}: two companions would fly one vehicle, --take-control goes no further (give each companion its own --system-id)"
            ));
        } else {
            self.event(format!(
                "{what}: two companions would fly one vehicle (give each its own --system-id); its setpoints, if any come, end this flight (another_controller)"
            ));
        }
    }

    /// The vehicle's heartbeat: armed, mode, powered off.
    fn vehicle_heartbeat(&mut self, h: &HEARTBEAT_DATA) {
        let armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        if armed && !self.armed && self.arm_sent && !self.in_control {
            self.armed_by_us = true;
        }
        let mode = mode_of(h);
        let changed = armed != self.armed || mode != self.custom_mode;
        self.armed = armed;
        self.custom_mode = mode;
        if changed {
            // A heartbeat flapping between two modes logs at most one change a second, the
            // ones between counted in it; the last one pending is logged when the second has
            // passed (`flush_mode_log`), never lost (ver33-3).
            self.modes_unlogged += 1;
            self.flush_mode_log(false);
        }
        if h.system_status == MavState::MAV_STATE_POWEROFF {
            self.vehicle_done = true;
        }
    }

    /// Whether a pilot's word shown by the heartbeats awaits confirmation ([`LeaveSeen`]).
    fn pilots_word_pending(&self) -> bool {
        self.leave_seen.as_ref().is_some_and(|l| !l.confirmed)
    }

    /// A heartbeat of the vehicle's (applied) came now: the gap since the last one noted,
    /// the longest kept ([`Flight::confirm_span`]).
    fn note_beat(&mut self) {
        let now = Instant::now();
        if let Some(at) = self.beat_at {
            let gap_s = now.duration_since(at).as_secs_f64();
            self.longest_beat_gap_s = self.longest_beat_gap_s.max(gap_s);
        }
        self.beat_at = Some(now);
    }

    /// How long a pilot's word shown by the vehicle's heartbeats must stand, none contradicting,
    /// before it is taken ([`LeaveSeen`]), and a failsafe's way out shown by them before it is
    /// confirmed: 1.1 x the vehicle's heartbeat period, within [1.1, 5] s: long enough that the
    /// vehicle flown, if the heartbeats were another's, has beaten meanwhile (att33f-1).
    ///
    /// The period is the LONGEST gap between two heartbeats of the ids applied over the
    /// whole flight, at least 1 s (MAVLink's nominal 1 Hz heartbeat; PX4's and ArduPilot's),
    /// not a guess of the next gap from the last few: a second vehicle with the ids beating
    /// faster than the vehicle flown (its beats applied count as the vehicle's: the two
    /// cannot be told apart before they disagree), a heartbeat rate dropped (5 Hz to 1 Hz, a
    /// stream-rate change) or a jitter's long gap after short ones shortened such a guess below
    /// the vehicle's own period, and a second vehicle's word then stood before the vehicle
    /// flown beat. A maximum only grows: nothing a second sender sends can shorten it, so it
    /// needs no freezing on a sign of one, a pending word or a failsafe (freezing could only
    /// keep it shorter); a long gap (a heartbeat lost) lengthens the wait for a pilot's word,
    /// which ends the flight however it turns out and commands nothing against the pilot
    /// meanwhile. Not covered: a vehicle whose period is longer than any gap seen so far and
    /// than 1 s (its first long jitter gap, or a vehicle beating slower than 1 Hz).
    fn confirm_span(&self) -> Duration {
        let period_s = self.longest_beat_gap_s.max(1.0);
        Duration::from_secs_f64((1.1 * period_s).min(5.0))
    }

    /// Whether the vehicle's arming and mode, as its heartbeats show them, are a pilot's word
    /// the companion did not command: in control, out of OFFBOARD or disarmed (armed in an
    /// unknown mode is not, ver33b-10); during a take-over (once a control command went out), a
    /// disarm after it was armed, or another mode than before that command and not OFFBOARD.
    fn shows_pilots_word(&self) -> bool {
        self.is_pilots_word(self.custom_mode, self.armed)
    }

    /// Whether a vehicle in `mode`, armed or not, shows a pilot's word
    /// ([`Flight::shows_pilots_word`]).
    fn is_pilots_word(&self, mode: Option<u32>, armed: bool) -> bool {
        let offboard = mode.is_some_and(|c| self.firmware.is_in(c, FlyMode::Offboard));
        if self.in_control {
            return !(armed && (mode.is_none() || offboard));
        }
        let Some(before) = self.mode_at_first_command else {
            return false;
        };
        (self.armed_since_command && !armed) || (before.is_some() && mode != before && !offboard)
    }

    /// The doubts of the vehicle's frame counter opened before a pilot's word was FIRST heard
    /// ([`LeaveSeen::doubts`], [`AnswerSeen::doubts`]), heard now (`in_doubt`: in a doubt,
    /// which then counts as one since the word: a heartbeat applied after it that no longer
    /// shows the word is two senders', a second sender's heartbeat having opened the doubt,
    /// att39f-3, never one sender's change and back).
    fn doubts_before_word(&self, in_doubt: bool) -> u64 {
        self.seq_watch.doubts.saturating_sub(u64::from(in_doubt))
    }

    /// A pilot's `word` awaiting confirmation, first heard after `before` doubts of the frame
    /// counter ([`Flight::doubts_before_word`]), then a heartbeat applied showing `state`
    /// instead: with a doubt opened since the word was first heard, however many heartbeats
    /// applied repeated it after the resync, no change and back of one sender but two senders
    /// (logged, [`Flight::second_sender_seen`]; att39f-3, in the failsafe's retries too:
    /// att45f-4, att49f-3). The one rule for control ([`Flight::watch_leave`]) and the
    /// retries ([`Flight::answer_stands`]); returns whether it found two senders.
    fn contradicted_across_a_doubt(&mut self, word: &str, before: u64, state: &str) -> bool {
        let n = self.seq_watch.doubts.saturating_sub(before);
        if n == 0 {
            return false;
        }
        let t = self.target.unwrap_or_default();
        self.second_sender_seen(format!(
            "two vehicles with the ids (system {}, component {}): the heartbeats showed it {word}, then {state}, with {n} doubt{} of the frame counter between (a pilot's change and back comes from one counter with no doubt between; a second sender's heartbeat taken as the vehicle's, then the vehicle's own, with one): which to fly is ambiguous",
            t.0,
            t.1,
            if n == 1 { "" } else { "s" }
        ));
        true
    }

    /// What a heartbeat shows, in words: `armed in MANUAL`, `disarmed in an unknown mode`.
    fn shown_state(&self, h: &HEARTBEAT_DATA) -> String {
        let armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        format!(
            "{} in {}",
            if armed { "armed" } else { "disarmed" },
            mode_of(h).map_or("an unknown mode".into(), |c| self.firmware.mode_name(c))
        )
    }

    /// A heartbeat of the vehicle's ids in a doubt of their frame counter ([`FrameKind::Doubt`]):
    /// never the vehicle's state, but if it shows a pilot's word ([`Flight::is_pilots_word`]) it
    /// counts as one awaiting confirmation (att42f-5, [`LeaveSeen`]), as if applied: nothing more
    /// is commanded meanwhile, a second sender proven after it ends the flight with nothing
    /// commanded ([`Flight::word_before_second_sender`]), a failsafe meanwhile commands nothing
    /// against it, and after a resynchronisation the heartbeats applied confirm it (its span
    /// starts at the resynchronisation) or contradict it (a doubt between: two senders). A pilot
    /// may switch while a burst loss of one sender's frames is in doubt; taken as nothing, their
    /// MANUAL was commanded against when a second burst proved "two senders".
    fn doubt_word(&mut self, h: &HEARTBEAT_DATA) {
        let armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        let mode = mode_of(h);
        if self.leave_seen.is_some() || !is_autopilot(h) || !self.is_pilots_word(mode, armed) {
            return;
        }
        let what = self.shown_state(h);
        self.leave_seen = Some(LeaveSeen {
            at: Instant::now(),
            span: self.confirm_span(),
            before: (self.custom_mode, self.armed),
            what,
            confirmed: false,
            back: false,
            doubts: self.doubts_before_word(true),
        });
    }

    /// The vehicle's heartbeat just handled (applied): in control or during a take-over, a
    /// pilot's word ([`Flight::shows_pilots_word`]) is watched until confirmed
    /// ([`LeaveSeen`]); `was` is its mode and arming before it.
    fn watch_leave(&mut self, was: (Option<u32>, bool)) {
        self.heartbeats += 1;
        if self.mode_at_first_command.is_some() && self.armed {
            self.armed_since_command = true;
        }
        let shows_control = !self.shows_pilots_word();
        let span = self.confirm_span();
        let state = format!(
            "{} in {}",
            if self.armed { "armed" } else { "disarmed" },
            self.mode_name()
        );
        // A heartbeat newer than the word's that no longer shows it, a doubt of the frame
        // counter since the word (att39f-3: a second sender's heartbeat taken as the vehicle's,
        // then the vehicle's own, a doubt between): two senders, not one sender's change and
        // back (nothing commanded: the word was heard before,
        // [`Flight::word_before_second_sender`]).
        if let Some((word, before)) = self
            .leave_seen
            .as_ref()
            .filter(|l| shows_control && !l.confirmed)
            .map(|l| (l.what.clone(), l.doubts))
        {
            if self.contradicted_across_a_doubt(&word, before, &state) {
                return;
            }
        }
        match (&mut self.leave_seen, shows_control) {
            (None, true) => {}
            (None, false) => {
                self.leave_seen = Some(LeaveSeen {
                    at: Instant::now(),
                    span,
                    before: was,
                    what: state,
                    confirmed: false,
                    back: false,
                    doubts: self.doubts_before_word(false),
                })
            }
            // Late frames (a link that reorders) change nothing (att33e-6, att33g-2).
            (Some(l), false) if !l.confirmed && l.at.elapsed() >= l.span => l.confirmed = true,
            // A heartbeat newer than the word's that no longer shows it, and no second sender
            // seen: one sender's change and back, the pilot's word all the same.
            (Some(l), true) if !l.confirmed => (l.confirmed, l.back) = (true, true),
            _ => {}
        }
    }

    /// Logs the vehicle's arming and mode as they are, if a change of them is pending and
    /// [`MODE_EVENT_INTERVAL_S`] has passed since the last logged (or `now`: control taken,
    /// the flight's end), the changes not logged between counted in it.
    fn flush_mode_log(&mut self, now: bool) {
        if self.modes_unlogged == 0 {
            return;
        }
        let due = now
            || self
                .mode_logged_at
                .is_none_or(|at| at.elapsed().as_secs_f64() >= MODE_EVENT_INTERVAL_S);
        if !due {
            return;
        }
        let between = match std::mem::take(&mut self.modes_unlogged) - 1 {
            0 => String::new(),
            n => format!(" ({n} changes of mode or arming since the last logged, not logged)"),
        };
        let what = format!(
            "vehicle {} in {}{between}",
            if self.armed { "armed" } else { "disarmed" },
            self.mode_name()
        );
        self.event(what);
        self.mode_logged_at = Some(Instant::now());
    }

    /// Whether `r` is an acknowledgement addressed to someone else than the companion (its
    /// `target_system` another system, or its `target_component` another component; 0 is
    /// unaddressed, anyone's): a ground station's answer, never the companion's.
    fn ack_for_another(&self, r: &Received) -> bool {
        r.ack_target.is_some_and(|(sys, comp)| {
            sys != 0 && (sys != self.opts.system_id || (comp != 0 && comp != COMPANION_COMPONENT))
        })
    }

    /// An acknowledgement before the companion has control: an accepted arming, or a refusal.
    fn acknowledged(&mut self, a: &COMMAND_ACK_DATA) {
        // Only the answer to the command the companion sent last, within ACK_WINDOW_S: any
        // other acknowledgement answers someone else (a ground station arming the vehicle).
        let ours = self.awaiting.is_some_and(|(cmd, at)| {
            cmd == a.command && at.elapsed().as_secs_f64() <= ACK_WINDOW_S
        });
        if !ours {
            return;
        }
        let ok = a.result == MavResult::MAV_RESULT_ACCEPTED;
        if ok {
            // A refusal leaves the command awaited: an unaddressed refusal may answer another's
            // same command, the vehicle's acceptance of ours may follow (ver33b-11).
            self.awaiting = None;
        }
        self.event(format!("{:?}: {:?}", a.command, a.result));
        if ok && a.command == MavCmd::MAV_CMD_DO_SET_MODE && self.offboard_sent {
            self.offboard_accepted_at = Some(Instant::now());
        }
        if ok && a.command == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && self.arm_sent {
            if !self.armed {
                self.armed_by_us = true;
            }
            self.armed = true;
        }
        let control = matches!(
            a.command,
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM | MavCmd::MAV_CMD_DO_SET_MODE
        );
        // A refusal, not a "still working on it".
        if control
            && !matches!(
                a.result,
                MavResult::MAV_RESULT_ACCEPTED | MavResult::MAV_RESULT_IN_PROGRESS
            )
        {
            self.refusal_pending = Some((a.command, Instant::now()));
            let what = if a.command == MavCmd::MAV_CMD_DO_SET_MODE {
                format!("the switch to {}", self.firmware.name_of(FlyMode::Offboard))
            } else {
                "to arm".to_string()
            };
            self.refusal = Some(format!("{what}: {:?}", a.result));
        }
    }

    /// A `GLOBAL_POSITION_INT` while no local position has come: projected about the first fix.
    fn global_position(&mut self, g: &GLOBAL_POSITION_INT_DATA) {
        if let Some(p) = self.global_local(g) {
            self.altitude(g.relative_alt as f64 * 1e-3, g.time_boot_ms);
            self.position(g.time_boot_ms, p);
        } else if self.tel.global_origin.is_some() {
            // No fix (or out of range) after positions: marked in the trace.
            self.record.no_position(g.time_boot_ms);
        }
    }

    /// A `GLOBAL_POSITION_INT`'s fix projected about the first one (x east, y north, m), if it
    /// is one (in range, not 0, 0).
    fn global_local(&mut self, g: &GLOBAL_POSITION_INT_DATA) -> Option<(f64, f64)> {
        let (lat, lon) = (g.lat as f64 * 1e-7, g.lon as f64 * 1e-7);
        if lat.abs() > 90.0 || lon.abs() > 180.0 || (g.lat == 0 && g.lon == 0) {
            return None;
        }
        let o = *self.tel.global_origin.get_or_insert(crate::geo::Home {
            lat_deg: lat,
            lon_deg: lon,
            alt_m: 0.0,
        });
        Some(o.to_local_m(lat, lon))
    }

    /// An altitude above home, m, stamped `ms` (the vehicle's clock). The first one received
    /// once the companion has control is the altitude the fixed wing's pitch holds (not one
    /// from before: a vehicle's first reports may not be its flight's). A fixed wing's step
    /// beyond its airframe's reach ([`ALTITUDE_STEP_MARGIN_M`]) moves that target by the step.
    fn altitude(&mut self, h_m: f64, ms: u32) {
        let t = match self.tel.last_altitude {
            Some((_, prev)) => wire::unwrap_ms(prev, ms),
            None => ms as u64,
        };
        // After an outage (no altitude for `timeout_s`: the hold was already at pitch 0, the
        // aircraft not held meanwhile) the gap would stretch the bound `V dt + 10 m` without
        // limit, so that a reset then is flown as a climb (ver33-1): the first new altitude
        // is compared with nothing, the hold's target becomes it (logged once).
        let was_unknown = self.tel.altitude_m.is_none()
            || self
                .tel
                .altitude_at
                .is_some_and(|a| a.elapsed() > self.timeout);
        if let (Transport::FixedWing { .. }, true, Some((prev_h, _)), Some(c)) = (
            self.transport,
            was_unknown,
            self.tel.last_altitude,
            self.tel.altitude_target_m,
        ) {
            self.tel.altitude_target_m = Some(h_m);
            if !self.tel.rereferenced_logged {
                self.tel.rereferenced_logged = true;
                self.event(format!(
                    "altitude back after none for {} s (from {} m to {} m): not compared with the old one, the altitude hold's target re-referenced from {} m to it (logged once)",
                    self.opts.timeout_s,
                    isotrack_core::numtext::Num(prev_h),
                    isotrack_core::numtext::Num(h_m),
                    isotrack_core::numtext::Num(c),
                ));
            }
        } else if let (Transport::FixedWing { airspeed_mps }, false, Some((prev_h, prev_t))) =
            (self.transport, was_unknown, self.tel.last_altitude)
        {
            let dt_s = t.saturating_sub(prev_t) as f64 / 1000.0;
            let step = h_m - prev_h;
            if step.abs() > airspeed_mps * dt_s + ALTITUDE_STEP_MARGIN_M {
                let shifted = self.tel.altitude_target_m.map(|c| c + step);
                self.tel.altitude_target_m = shifted;
                self.event(format!(
                    "altitude step of {} m ignored (from {} m to {} m in {} s: beyond the {} m/s a fixed wing at {} m/s airspeed climbs or sinks): a reset of the altitude's reference, {}",
                    isotrack_core::numtext::Num(step),
                    isotrack_core::numtext::Num(prev_h),
                    isotrack_core::numtext::Num(h_m),
                    isotrack_core::numtext::Num(dt_s),
                    isotrack_core::numtext::Num(airspeed_mps),
                    isotrack_core::numtext::Num(airspeed_mps),
                    if shifted.is_some() {
                        "the altitude hold's target moved with it (its pitch stays)"
                    } else {
                        "no altitude held yet"
                    }
                ));
            }
        }
        self.tel.last_altitude = Some((h_m, t.max(self.tel.last_altitude.map_or(0, |l| l.1))));
        self.tel.altitude_m = Some(h_m);
        self.tel.altitude_at = Some(Instant::now());
        if self.in_control && self.tel.altitude_target_m.is_none() {
            self.tel.altitude_target_m = Some(h_m);
        }
    }

    /// A finite position (x east, y north), m, stamped `ms` (its jump checked before:
    /// [`Flight::ids_frame`]).
    fn position(&mut self, ms: u32, p: (f64, f64)) {
        self.tel.position_at = Some(Instant::now());
        self.tel.pos = Some(p);
        self.record.position(ms, p, self.in_control);
    }

    /// A position of the vehicle's ids (x east, y north, m) stamped `ms`, watched for jumps
    /// farther than a vehicle covers ([`crate::same_ids::PositionWatch`]): two vehicles'
    /// positions interleaving are a second sender.
    fn position_jumps(&mut self, ms: u32, p: (f64, f64)) {
        let wall_s = self.t0.elapsed().as_secs_f64();
        if self.pos_watch.position(p, ms, wall_s) && self.same_ids.is_none() {
            let t = self.target.unwrap_or_default();
            let (d, dt) = self.pos_watch.last_jump.unwrap_or_default();
            self.second_sender_seen(format!(
                "two vehicles with the ids (system {}, component {}): {} of their last {} positions jumped farther than {} m/s covers (the last {} m in {} s): two vehicles' positions interleaving, which to fly is ambiguous",
                t.0,
                t.1,
                crate::same_ids::POSITION_JUMPS_LIMIT,
                crate::same_ids::POSITION_WINDOW,
                crate::same_ids::MAX_GROUND_SPEED_MPS,
                isotrack_core::numtext::Num(d),
                isotrack_core::numtext::Num(dt),
            ));
        }
    }

    /// The way out of `end`: the failsafe mode once the companion had control (or with no
    /// vehicle heard: nothing is sent); before, after a refused take-over or a failsafe, a
    /// disarm if the companion armed the vehicle on the ground; nothing on a vehicle it never
    /// controlled nor armed (a pilot's, armed in MANUAL: its mode stands).
    /// Whether failsafe `end` came while a disarm nobody here commanded was watched for a
    /// reboot (in control), and is not the reboot itself (`vehicle_lost`).
    fn pilots_disarm_watched(&self, end: FlyEnd) -> bool {
        end.is_failsafe()
            && end != FlyEnd::VehicleLost
            && self.in_control
            && !self.armed
            && self.disarm_seen.is_some()
    }

    /// The way out after `two_vehicles`, if the companion commanded anything before it
    /// (ver33b-1): the failsafe mode in control, out of an accepted OFFBOARD, or the disarm of
    /// a vehicle it armed; `None` when nothing was commanded.
    fn two_vehicles_way_out(&self) -> Option<WayOut> {
        let mode = self.opts.failsafe.mode();
        if self.in_control {
            Some(WayOut::Mode(mode))
        } else if self.disarm_owed() {
            // Armed by the companion on the ground and never flown: disarmed, whatever mode
            // it was switched to (ver33c-6), unless confirmed disarmed (att33f-6), or in the
            // failsafe mode if it reports itself in the air (att37-3).
            Some(self.owed_way_out())
        } else if self.offboard_accepted_at.is_some() {
            Some(WayOut::LeaveOffboard(mode))
        } else {
            None
        }
    }

    /// The way out of `end` ([`Flight::way_out_one_sender`]'s), but once a second sender with
    /// the vehicle's ids has been seen, the `--failsafe` mode in place of any (never a disarm:
    /// either sender may be the vehicle, and the companion cannot tell which is on the ground),
    /// and still nothing where nothing would be commanded (the companion commanded nothing
    /// before).
    fn way_out(&self, end: FlyEnd) -> Option<WayOut> {
        if self.word_before_second_sender(end).is_some() {
            return None;
        }
        let way = self.way_out_one_sender(end);
        if self.second_sender {
            way.map(|_| WayOut::Mode(self.opts.failsafe.mode()))
        } else {
            way
        }
    }

    /// What a pilot's word showed ([`LeaveSeen`], awaiting confirmation or confirmed), if the
    /// flight ends `vehicle_lost` on a second sender with the vehicle's ids (not a reboot) after
    /// a heartbeat applied before it showed that word (att39f-1/-2): then NOTHING is commanded.
    /// Frame numbers are 8-bit, so one sender over a lossy link and two senders with one id
    /// cannot be told apart in every case; the way out is chosen so that neither reading
    /// costs the vehicle: if the word was the pilot's (one sender read as two), the pilot keeps
    /// the vehicle (no HOLD against the pilot's MANUAL); if it was the second sender's, the
    /// vehicle flown is still in OFFBOARD with no setpoints, and its autopilot's own
    /// offboard-loss failsafe takes it. A heartbeat is applied only outside a doubt and before
    /// a second sender is seen ([`crate::same_ids`]), and one in a doubt counts as a word only
    /// before ([`Flight::doubt_word`]), so a word is always heard before that.
    fn word_before_second_sender(&self, end: FlyEnd) -> Option<&str> {
        if end != FlyEnd::VehicleLost || !self.lost_to_second_sender {
            return None;
        }
        self.leave_seen.as_ref().map(|l| l.what.as_str())
    }

    /// The way out of `end` with one sender of the vehicle's ids.
    fn way_out_one_sender(&self, end: FlyEnd) -> Option<WayOut> {
        if end == FlyEnd::TwoVehicles {
            return self.two_vehicles_way_out();
        }
        if end.is_failsafe() && end != FlyEnd::VehicleLost && self.pilots_word_pending() {
            // A failsafe (a link lost, Ctrl-C, ...) while a pilot's word awaits confirmation
            // (att33f-7): the pilot's mode stands, nothing is commanded against it (a second
            // vehicle's word, not yet told apart, leaves the vehicle flown to its own
            // offboard-loss failsafe).
            return None;
        }
        if self.pilots_disarm_watched(end) {
            // A failsafe while a disarm nobody here commanded is watched for a reboot: the
            // disarm is the pilot's, whose mode stands (ver33b-5); a reboot established
            // (`vehicle_lost`) is not.
            return None;
        }
        let mode = self.opts.failsafe.mode();
        let stopping = end.is_failsafe() || end == FlyEnd::ControlRefused;
        if end.is_failsafe() && (self.in_control || self.target.is_none()) {
            Some(WayOut::Mode(mode))
        } else if stopping && self.disarm_owed() {
            // Armed by the companion on the ground and never flown: disarmed (forced), even
            // after an accepted OFFBOARD, never left armed in a hold on the ground (ver33c-6);
            // a disarmed heartbeat not confirmed (a second vehicle's, att33f-6) changes nothing;
            // the failsafe mode instead if the vehicle reports itself in the air (att37-3).
            Some(self.owed_way_out())
        } else if end == FlyEnd::ControlRefused
            && self
                .offboard_accepted_at
                .is_some_and(|at| self.last_heartbeat <= at)
        {
            // A refused take-over after the vehicle accepted the switch to OFFBOARD, no
            // heartbeat since saying what it did (ver33b-11): it may be in OFFBOARD with nobody
            // sending setpoints: commanded out of it.
            Some(WayOut::LeaveOffboard(mode))
        } else if end.is_failsafe() && self.offboard_accepted_at.is_some() {
            // The vehicle accepted the switch to OFFBOARD and no heartbeat has shown it yet:
            // it may be in OFFBOARD with nobody sending setpoints. The way out is commanded
            // until a heartbeat shows it out of OFFBOARD (any mode: the pilot's stands).
            Some(WayOut::LeaveOffboard(mode))
        } else {
            // A vehicle the companion never controlled nor armed (a pilot's, armed in MANUAL,
            // whose OFFBOARD switch was refused or never answered): its mode stands.
            None
        }
    }

    /// What the failsafe's log says once a second sender with the vehicle's ids was seen
    /// (empty before).
    fn second_sender_note(&self) -> String {
        if !self.second_sender {
            return String::new();
        }
        let t = self.target.unwrap_or_default();
        format!(
            ": a second sender with the vehicle's ids (system {}, component {}) was seen, and nothing tells the two apart: no heartbeat of the ids is taken as a confirmation or a pilot's word, and no disarm is sent (either may be the vehicle, maybe flying); {} is commanded to the retries' bound, or until a heartbeat of the ids shows a mode or arming the companion did not command (a pilot's or the second sender's: then nothing more). A vehicle armed on the ground must be disarmed by its operator (PX4's preflight auto-disarm may do it)",
            t.0,
            t.1,
            self.firmware.name_of(self.opts.failsafe.mode())
        )
    }

    /// Lets go after `end`: commands the way out until the vehicle confirms it; returns
    /// (confirmed, anything commanded).
    fn let_go(&mut self, end: FlyEnd) -> Result<(bool, bool), FlyError> {
        let Some(way) = self.way_out(end) else {
            if let Some(word) = self.word_before_second_sender(end) {
                self.event(format!(
                    "failsafe (vehicle_lost) after the vehicle's heartbeats showed it {word} (a pilot's word, or the second sender's): setpoints stopped, nothing commanded, the pilot's mode stands (a vehicle still in {} falls to its own offboard-loss failsafe)",
                    self.firmware.name_of(FlyMode::Offboard)
                ));
                return Ok((false, false));
            }
            if self.pilots_disarm_watched(end) {
                self.event(format!(
                    "failsafe ({}): the vehicle had just been disarmed, not by the companion (a pilot's disarm, watched for a reboot): nothing commanded, the pilot's mode stands",
                    end.as_str()
                ));
                return Ok((false, false));
            }
            if end.is_failsafe() && self.pilots_word_pending() && end != FlyEnd::VehicleLost {
                self.event(format!(
                    "failsafe ({}) while the vehicle's heartbeats showed it {}, not yet confirmed as its pilot's{}: nothing commanded against it, the pilot's mode stands",
                    end.as_str(),
                    self.leave_seen.as_ref().map_or(String::new(), |l| l.what.clone()),
                    self.maybe_rebooted()
                ));
            } else if end.is_failsafe() {
                self.event(format!(
                    "failsafe ({}) before the companion had control: nothing commanded, the vehicle's mode stands",
                    end.as_str()
                ));
            }
            return Ok((false, false));
        };
        let what = match way {
            WayOut::Mode(m) if !self.second_sender && self.disarm_owed() => format!(
                "{} commanded (armed by the companion, but the vehicle reports itself in the air in its EXTENDED_SYS_STATE: never disarmed)",
                self.firmware.name_of(m)
            ),
            WayOut::Mode(m) => format!("{} commanded", self.firmware.name_of(m)),
            WayOut::LeaveOffboard(m) => format!(
                "{} commanded (the vehicle accepted the switch to {} before control: it is commanded out of it until a heartbeat shows another mode)",
                self.firmware.name_of(m),
                self.firmware.name_of(FlyMode::Offboard)
            ),
            WayOut::Disarm => "disarm commanded (armed by the companion, on the ground)".into(),
        };
        if self.target.is_none() {
            self.event(format!(
                "failsafe ({}): no vehicle was ever heard: nothing sent, nothing to confirm",
                end.as_str()
            ));
            return Ok((false, false));
        }
        self.event(format!(
            "failsafe ({}): setpoints stopped, {what}{}",
            end.as_str(),
            self.second_sender_note()
        ));
        let (confirmed, tries, why) = self.command_way_out(way)?;
        // The way out may have turned to the failsafe mode (a second sender seen meanwhile).
        let way = if self.second_sender {
            WayOut::Mode(self.opts.failsafe.mode())
        } else {
            way
        };
        let what = self.way_out_name(way);
        self.event(match (confirmed, way) {
            // `why` is the other safe mode the vehicle went to, when it did.
            (true, WayOut::Mode(_) | WayOut::LeaveOffboard(_)) if !why.is_empty() => {
                format!("the vehicle is in {why}, not the {what} commanded ({tries} tries)")
            }
            (true, WayOut::Mode(_) | WayOut::LeaveOffboard(_)) => {
                format!("the vehicle is in {what} ({tries} tries)")
            }
            (true, WayOut::Disarm) => format!("the vehicle is disarmed ({tries} tries)"),
            (false, _) => format!("the vehicle did not confirm the {what} ({tries} tries, {why})"),
        });
        Ok((confirmed, true))
    }

    /// The command and parameters of `way`; `None` for a mode without a table here.
    fn way_out_command(&self, way: WayOut) -> Option<(MavCmd, [f32; 3])> {
        match way {
            WayOut::Mode(m) | WayOut::LeaveOffboard(m) => self
                .firmware
                .set_mode_params(m)
                .map(|p| (MavCmd::MAV_CMD_DO_SET_MODE, p)),
            // Forced (param2 21196, MAVLink's magic number): only a vehicle the companion armed
            // itself on the ground and never had in OFFBOARD is disarmed, and an autopilot that
            // counts a fixed wing as flying (isotrack sitl) refuses an unforced disarm.
            WayOut::Disarm => Some((MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, [0.0, 21196.0, 0.0])),
        }
    }

    /// Commands `way` every 0.3 s until the vehicle's heartbeat confirms it or it refuses it,
    /// or the link is lost (no message from the vehicle for `timeout_s`; at least 5 tries even
    /// then, the vehicle may hear what it cannot answer, unless it acknowledged the command
    /// as accepted), a new signal arrives, or the
    /// retries' bound passes (3 x `timeout_s` within [3, 30] s). Returns (confirmed, tries, why
    /// not); confirmed in another safe mode than `way`'s, the third is that mode's name.
    fn command_way_out(&mut self, way: WayOut) -> Result<(bool, u32, &'static str), FlyError> {
        let Some((cmd, params)) = self.way_out_command(way) else {
            return Ok((false, 0, "no mode table for this vehicle here"));
        };
        // A signal from here on (the one that may have caused the failsafe is spent) ends the
        // retries.
        self.opts.stop.store(false, Ordering::SeqCst);
        let mut r = WayOutRetries {
            way,
            cmd,
            params,
            before: self.confirmed_state(),
            end: Instant::now()
                + Duration::from_secs_f64((3.0 * self.opts.timeout_s.max(0.0)).clamp(3.0, 30.0)),
            tries: 0,
            accepted: None,
            watch: RetryWatch {
                armed_shown: self.armed,
                ..Default::default()
            },
            span: self.confirm_span(),
            refused: false,
            told: self.second_sender,
        };
        loop {
            if let Some(why) = self.reboot.take() {
                // Its autopilot rebooted during the retries (att45f-10): what its heartbeats
                // show from now on (a disarm, its boot mode) is the reboot's, no pilot's word
                // nor an answer; nothing more is commanded.
                self.event(format!(
                    "during the failsafe's retries, {why}: the retries stop, nothing more commanded"
                ));
                return Ok((false, r.tries, "its autopilot rebooted"));
            }
            if let Some(ended) = self.second_sender_in_retries(&mut r) {
                return Ok(ended);
            }
            if let Some(why) = self.retries_over(&r) {
                self.word_held(&r.watch);
                return Ok((false, r.tries, why));
            }
            if self.retry_due(&r) {
                r.tries += 1;
                r.watch.disarm_sent |= matches!(r.way, WayOut::Disarm);
                r.watch.left_shown = false;
                self.command(r.cmd, r.params)?;
            }
            let answer = self.await_way_out(&mut r)?;
            if let Some(ended) = self.way_out_answered(&mut r, answer) {
                return Ok(ended);
            }
        }
    }

    /// The name of what `way` commands: its mode's, or `disarm`.
    fn way_out_name(&self, way: WayOut) -> &'static str {
        match way {
            WayOut::Mode(m) | WayOut::LeaveOffboard(m) => self.firmware.name_of(m),
            WayOut::Disarm => "disarm",
        }
    }

    /// Decides what a second sender with the vehicle's ids, seen during the failsafe's retries
    /// (FLYING.md, Failsafes, "Two senders"), changes in them: the retries end
    /// (`Some`) on a pilot's word heard before it; else, once, the way out turns to the
    /// failsafe mode (never a disarm) and no heartbeat's answer is awaited any more.
    fn second_sender_in_retries(
        &mut self,
        r: &mut WayOutRetries,
    ) -> Option<(bool, u32, &'static str)> {
        if self.second_sender && !r.told {
            // How it was seen (the same checks as in control: [`Flight::ids_frame`]).
            if let Some(why) = self.same_ids.take() {
                self.event(format!("during the failsafe's retries, {why}"));
            }
            // A second sender with the ids seen during the retries after a heartbeat
            // showed a pilot's word, awaiting confirmation (att41f-2): as for a word heard
            // before the proof that ends the flight ([`Flight::word_before_second_sender`]),
            // nothing more is commanded: the word was the pilot's (one sender read as two),
            // whose mode stands, or the second sender's, and the vehicle flown keeps the
            // way out already commanded or falls to its own offboard-loss failsafe.
            if let Some(word) = r.watch.seen.as_ref().filter(|s| s.pilots) {
                self.word_before_second_sender_in_retries(&word.what);
                return Some((false, r.tries, "a pilot's word before a second sender"));
            }
            // A second sender with the ids seen during the retries: no answer of the
            // heartbeats any more, never a disarm (either may be the vehicle, maybe
            // flying): the failsafe mode instead, to the bound or to a heartbeat showing a
            // mode the companion did not command ([`Answer::NotCommanded`]).
            r.told = true;
            if !matches!(r.way, WayOut::Mode(_)) {
                r.way = WayOut::Mode(self.opts.failsafe.mode());
                let Some(c) = self.way_out_command(r.way) else {
                    return Some((false, r.tries, "no mode table for this vehicle here"));
                };
                (r.cmd, r.params) = c;
                r.accepted = None;
            }
            let note = self.second_sender_note();
            self.event(format!("during the failsafe's retries{note}"));
        }
        if self.second_sender {
            // No answer awaited holds the retries back any more.
            r.watch.seen = None;
        }
        None
    }

    /// Decides whether the failsafe's retries are over unconfirmed (FLYING.md, "Failsafes"):
    /// why (a lost link, their bound, a signal), or `None` to go on.
    fn retries_over(&self, r: &WayOutRetries) -> Option<&'static str> {
        let lost = self.link_gone || self.link_silent().is_some();
        // At least 5 tries before a lost link ends them (a vehicle may hear what it cannot
        // answer), unless it acknowledged the command as accepted: it heard it, and it is
        // not sent again before a heartbeat says what it did (att37-5).
        // After a second sender a retry waits for a heartbeat showing the vehicle still in
        // the mode it was left in (att42f-2): none comes over a lost link.
        if lost && (r.tries >= 5 || r.accepted.is_some() || (self.second_sender && r.tries > 0)) {
            return Some("link lost");
        }
        let bound = match (r.refused, self.second_sender) {
            (true, _) => "refused",
            (false, true) => {
                "retries' bound reached; a second sender with the ids: no heartbeat confirms it"
            }
            (false, false) => "retries' bound reached",
        };
        if r.tries >= MAX_WAY_OUT_TRIES {
            return Some(bound);
        }
        if self.opts.stop.load(Ordering::SeqCst) {
            return Some("stopped by a signal");
        }
        if Instant::now() >= r.end {
            return Some(bound);
        }
        None
    }

    /// Decides whether the way out is sent again now (FLYING.md, "Failsafes"): never while a
    /// heartbeat's answer awaits confirmation.
    fn retry_due(&self, r: &WayOutRetries) -> bool {
        // After a second sender, once the way out has gone out, a retry only on a heartbeat
        // of the ids heard since the last one showing the vehicle still in the mode it was
        // left in (att42f-2: [`Flight::left_in`]), sent as soon as it is heard; never on one
        // showing the way out (a retry a heartbeat period after the last, 0.03 to 0.3 s
        // after any heartbeat, overrode a pilot's switch made in between). With one sender,
        // every 0.3 s, or once the vehicle accepted it, after a heartbeat newer than that.
        let due = if self.second_sender && r.tries > 0 {
            r.watch.left_shown
        } else {
            r.accepted.is_none_or(|at| self.last_heartbeat > at)
        };
        due && r.watch.seen.is_none()
    }

    /// Decides what the vehicle's `answer` to a try means for the failsafe's retries
    /// (FLYING.md, "Failsafes"): their end (`Some`: confirmed, another safe mode, a pilot's
    /// or a second sender's mode), or `None` to go on (a refusal is noted for the bound).
    fn way_out_answered(
        &mut self,
        r: &mut WayOutRetries,
        answer: Option<Answer>,
    ) -> Option<(bool, u32, &'static str)> {
        let tries = r.tries;
        match answer {
            Some(Answer::Confirmed) => Some((true, tries, "")),
            Some(Answer::OtherSafeMode(name)) => {
                let asked = self.way_out_name(r.way);
                self.event(format!(
                    "the vehicle went to {name}, not the {asked} commanded: a safe mode all the same, the failsafe ends there (not insisted on)"
                ));
                Some((true, tries, name))
            }
            Some(Answer::Refused) => {
                r.refused = true;
                None
            }
            Some(Answer::NotCommanded(what)) => {
                if let Some(word) = r.watch.seen.as_ref().filter(|s| s.pilots && !r.told) {
                    // The second sender was seen in this listen, after the word.
                    self.word_before_second_sender_in_retries(&word.what);
                    return Some((false, tries, "a pilot's word before a second sender"));
                }
                let t = self.target.unwrap_or_default();
                self.event(format!(
                    "during the failsafe's retries, a second sender with the vehicle's ids (system {}, component {}) seen: a heartbeat of the ids shows {what}, which the companion did not command: a pilot's or the second sender's; nothing more commanded (the pilot's mode stands; the vehicle flown keeps the {} already commanded, or falls to its own offboard-loss failsafe)",
                    t.0,
                    t.1,
                    self.firmware.name_of(self.opts.failsafe.mode())
                ));
                self.way_out_overridden = true;
                Some((false, tries, "a mode the companion did not command shown"))
            }
            Some(Answer::PilotTookOver(what)) => self.pilots_change_in_retries(r, &what),
            None => None,
        }
    }

    /// Decides what a change the heartbeats showed during the retries, not commanded by the
    /// companion and confirmed as it stood (`what`: `disarmed`, `in MANUAL`), ends them with
    /// (FLYING.md, "The pilot's word is final", "reboots"): the reboot's when the vehicle's
    /// clock went back as the failsafe began (att53f-3: its boot state, no pilot's word); a
    /// pilot's or the second sender's after a doubt of the frame counter (att42f-3); else the
    /// pilot's (a disarm after a silence noted as maybe a reboot's, att53f-2). Nothing more is
    /// commanded either way.
    fn pilots_change_in_retries(
        &mut self,
        r: &WayOutRetries,
        what: &str,
    ) -> Option<(bool, u32, &'static str)> {
        if let Some((from, to, _)) = self.rebased {
            self.event(format!(
                "during the failsafe's retries, the heartbeats of the vehicle's ids show it {what}, which the companion did not command: its autopilot rebooted (its clock went back from {} s to {} s as the failsafe began), and what it shows after is the reboot's (a disarm, its boot mode), no pilot's word: the retries stop, nothing more commanded",
                wire::unwrapped_s(from),
                wire::unwrapped_s(to)
            ));
            return Some((false, r.tries, "its autopilot rebooted"));
        }
        self.way_out_overridden = true;
        let note = silence_note(what == "disarmed" && r.watch.disarm_after_silence);
        if let Some(why) = self.twin_doubt(&r.watch) {
            // A second counter with the ids was seen (att42f-3): the heartbeats' word may be
            // a second sender's, never asserted a pilot's.
            self.event(format!(
                "during the failsafe's retries: the heartbeats of the vehicle's ids show it {what}, which the companion did not command{note}: a pilot's or the second sender's ({why}); the retries stop, nothing more commanded (the pilot's mode stands)"
            ));
            return Some((false, r.tries, "a mode the companion did not command shown"));
        }
        self.event(format!(
            "pilot_took_over during the failsafe: the vehicle is {what}, not commanded by the companion{note}: the retries stop, the pilot's mode stands"
        ));
        Some((false, r.tries, "a pilot took over"))
    }

    /// The failsafe's retries end unconfirmed (their bound, a lost link, a signal) while a
    /// pilot's word heard in a doubt of the frame counter still holds them (att45f-11: a doubt
    /// longer than the retries, on a slow link): logged, so that the end is not read as a
    /// vehicle that ignored the way out in OFFBOARD.
    fn word_held(&mut self, watch: &RetryWatch) {
        if let Some(seen) = watch.seen.as_ref().filter(|s| s.pilots && s.in_doubt) {
            let what = seen.what.clone();
            self.event(format!(
                "during the failsafe's retries, a heartbeat of the vehicle's ids in a doubt of their frame counter showed it {what} (a pilot's word, or a second sender's), neither confirmed nor contradicted before the retries ended: none was sent since"
            ));
        }
    }

    /// Why a change the heartbeats showed during the retries, confirmed as a pilot's, may be a
    /// second sender's (att42f-3): a second sender with the ids seen, a doubt of their frame
    /// counter (a first conflict: maybe a second counter, resynchronised), or a heartbeat older
    /// than the last applied heard during the retries (a second counter ahead makes the
    /// vehicle's own older). `None`: one counter all along, the pilot's.
    fn twin_doubt(&self, watch: &RetryWatch) -> Option<&'static str> {
        if self.second_sender {
            Some("a second sender with the ids was seen")
        } else if self.seq_watch.doubts > 0 {
            Some("their frame counter was in doubt before: a second counter, maybe")
        } else if watch.older {
            Some("a heartbeat of the ids older than the last applied came during the retries: a second counter ahead, maybe")
        } else {
            None
        }
    }

    /// The failsafe's retries stop on a second sender with the vehicle's ids seen after a
    /// heartbeat showed `word`, a pilot's word awaiting confirmation (att41f-2): logged, nothing
    /// more commanded.
    fn word_before_second_sender_in_retries(&mut self, word: &str) {
        let t = self.target.unwrap_or_default();
        self.event(format!(
            "during the failsafe's retries: a second sender with the vehicle's ids (system {}, component {}) was seen after the vehicle's heartbeats showed it {word} (a pilot's word, or the second sender's, awaiting confirmation): the retries stop, nothing more commanded, the pilot's mode stands (a vehicle still in {} falls to its own offboard-loss failsafe)",
            t.0,
            t.1,
            self.firmware.name_of(FlyMode::Offboard)
        ));
        self.way_out_overridden = true;
    }

    /// Listens 0.3 s (after a second sender, less once a heartbeat shows the vehicle still in
    /// the mode it was left in: a retry is due, `watch.left_shown`) for the vehicle's answer to
    /// the retries' way out: `Some(true)` confirmed by its heartbeat
    /// (an acknowledgement is a promise: a vehicle may accept and stay in OFFBOARD),
    /// `Some(false)` refused (`DENIED`, `UNSUPPORTED`, `FAILED`: retrying changes nothing),
    /// unless an acceptance followed the refusal within the listen (ver33b-11).
    fn await_way_out(&mut self, retries: &mut WayOutRetries) -> Result<Option<Answer>, FlyError> {
        let until = Instant::now() + Duration::from_millis(300);
        // A refusal heard and no acceptance after it: an unaddressed refusal may answer
        // someone else's same command, the vehicle's acceptance of this one may follow
        // (ver33b-11): a refusal is the answer only if none came by the end of the listen.
        let mut refused = false;
        let mut retry_now = false;
        while Instant::now() < until && !retry_now {
            for r in self
                .link
                .poll(Duration::from_millis(20))
                .map_err(FlyError::Io)?
            {
                let number = match self.retry_frame(&r, retries, &mut retry_now) {
                    RetryFrame::End(answer) => return Ok(answer),
                    RetryFrame::Done => continue,
                    RetryFrame::Read(number) => number,
                };
                if let Some(answer) = self.retry_message(&r, number, retries, &mut refused) {
                    return Ok(Some(answer));
                }
            }
        }
        Ok(refused.then_some(Answer::Refused))
    }

    /// Decides what a frame heard during the failsafe's retries is before its message is
    /// read (FLYING.md, Failsafes, "Two senders"; "The vehicle"): another autopilot's, a copy,
    /// one in a doubt of the frame counter, not an autopilot's, an acknowledgement of another
    /// peer's command (nothing more to read); the end of the listen (its autopilot rebooted,
    /// or an answer of a heartbeat not applied); or the vehicle's, to read on. Sets
    /// `retry_now` when a heartbeat after a second sender shows a retry due.
    fn retry_frame(
        &mut self,
        r: &Received,
        retries: &mut WayOutRetries,
        retry_now: &mut bool,
    ) -> RetryFrame {
        let from = (r.header.system_id, r.header.component_id);
        if Some(from) != self.target {
            // Another autopilot first heard now is logged as in control (att45f-9),
            // never flown.
            if let MavMessage::HEARTBEAT(h) = &r.msg {
                self.find_vehicle(from, h);
            }
            return RetryFrame::Done;
        }
        let (kind, number) = self.ids_frame(r);
        if self.reboot.is_some() {
            // Its autopilot rebooted: the retries stop there (att45f-10).
            return RetryFrame::End(None);
        }
        if kind == FrameKind::Copy {
            // Delivered again: no answer, nothing applied ([`Flight::copy_frame`]).
            self.copy_frame(&r.msg);
            return RetryFrame::Done;
        }
        if matches!(&r.msg, MavMessage::HEARTBEAT(h) if !is_autopilot(h)) {
            // No autopilot's heartbeat (a ground station's or an onboard controller's
            // with the vehicle's ids, att42f-4): never the vehicle's answer, state or
            // word (its frame counted above, as any of the ids'), nor its heartbeat:
            // the link is lost without the vehicle's for long (att45f-3:
            // [`Flight::link_silent`], as in control).
            self.last_link = Instant::now();
            return RetryFrame::Done;
        }
        if let MavMessage::HEARTBEAT(h) = &r.msg {
            if self.second_sender || kind == FrameKind::Doubt {
                let (answer, left) =
                    self.unapplied_beat(h, retries.way, retries.before, &mut retries.watch);
                if answer.is_some() {
                    return RetryFrame::End(answer);
                }
                // After a proof, a retry goes out at once on a heartbeat showing the
                // vehicle still in the mode it was left in (att42f-2): the listen ends
                // with this poll's frames.
                *retry_now |= left;
                retries.watch.left_shown |= left;
            }
        }
        if kind == FrameKind::Doubt {
            // In a doubt: the link is alive, no answer.
            self.doubt_frame(&r.msg);
            return RetryFrame::Done;
        }
        retries.watch.silent_s = self.last_link.elapsed().as_secs_f64();
        self.last_link = Instant::now();
        if self.ack_for_another(r) {
            return RetryFrame::Done;
        }
        RetryFrame::Read(number)
    }

    /// Decides what a message of the vehicle (number `number` on its frame counter) heard
    /// during the failsafe's retries answers (FLYING.md, "Failsafes"): an acknowledgement of
    /// the way out (accepted, or `refused` until an acceptance follows), a heartbeat whose
    /// answer has stood for the retries' span (`Some`), or, after a second sender or older
    /// than the last applied, a heartbeat that only says the link is alive.
    fn retry_message(
        &mut self,
        r: &Received,
        number: u64,
        retries: &mut WayOutRetries,
        refused: &mut bool,
    ) -> Option<Answer> {
        let (way, cmd, before) = (retries.way, retries.cmd, retries.before);
        match &r.msg {
            // After a second sender: heard (the link alive), never an answer.
            MavMessage::HEARTBEAT(_) if self.second_sender => {
                self.beat_heard = Instant::now();
                return None;
            }
            // Older than the last applied (a late one): not the vehicle's answer now;
            // one showing another answer than the one awaited restarts its span.
            MavMessage::HEARTBEAT(h) if self.beat_number.is_some_and(|b| number <= b) => {
                self.beat_heard = Instant::now();
                retries.watch.older = true;
                let answer = self.heartbeat_answer(h, way, before);
                retries.watch.contradicted_by(&answer);
                return None;
            }
            MavMessage::HEARTBEAT(h) => {
                self.last_heartbeat = Instant::now();
                self.beat_heard = self.last_heartbeat;
                self.beat_number = Some(number);
                retries.watch.arming_shown(
                    h.base_mode
                        .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
                );
            }
            MavMessage::COMMAND_ACK(a)
                if a.command == cmd && a.result == MavResult::MAV_RESULT_ACCEPTED =>
            {
                retries.accepted = Some(Instant::now());
                *refused = false;
            }
            _ => {}
        }
        match &r.msg {
            MavMessage::COMMAND_ACK(a)
                if a.command == cmd
                    && matches!(
                        a.result,
                        MavResult::MAV_RESULT_DENIED
                            | MavResult::MAV_RESULT_UNSUPPORTED
                            | MavResult::MAV_RESULT_FAILED
                    ) =>
            {
                *refused = true
            }
            MavMessage::HEARTBEAT(h) => {
                // A second vehicle with the ids may beat too (att33e-1, att33f-3):
                // an answer once it has stood, none contradicting, for `span`.
                let answer = self.heartbeat_answer(h, way, before);
                return self.answer_stands(h, answer, &mut retries.watch, retries.span);
            }
            _ => {}
        }
        None
    }
}

impl<S: TraceSink + ?Sized> Flight<'_, S> {
    /// A heartbeat's `answer` (applied: newer than the last) during the retries, watched
    /// ([`AnswerSeen`]): the answer once heartbeats have shown it for `span` with none
    /// contradicting (one showing nothing yet, or the other kind of answer, starts over).
    fn answer_stands(
        &mut self,
        h: &HEARTBEAT_DATA,
        answer: Option<Answer>,
        watch: &mut RetryWatch,
        span: Duration,
    ) -> Option<Answer> {
        let pilots = matches!(answer, Some(Answer::PilotTookOver(_)));
        if let Some((word, before)) = watch
            .seen
            .as_ref()
            .filter(|s| s.pilots && !pilots)
            .map(|s| (s.what.clone(), s.doubts))
        {
            // A pilot's word, then contradicted by a heartbeat applied with a doubt of the
            // frame counter since the word was first heard (heard in the doubt, then maybe
            // repeated by heartbeats applied after the resync, att49f-3): no change and back
            // of one sender, two senders (att45f-4, the rule of control); the word stays
            // seen, and the retries stop with nothing more commanded
            // ([`Flight::word_before_second_sender_in_retries`]).
            let state = self.shown_state(h);
            if self.contradicted_across_a_doubt(&word, before, &state) {
                return None;
            }
        }
        if let (Some(seen), true) = (&watch.seen, answer.is_some()) {
            // A word heard in a doubt is no answer of the vehicle's: its span starts here.
            if seen.pilots == pilots && !seen.in_doubt {
                return (seen.at.elapsed() >= span).then_some(answer).flatten();
            }
        }
        // A word heard in a doubt and repeated now keeps the doubts from when it was first
        // heard (as in control, [`LeaveSeen::doubts`]).
        let doubts = match &watch.seen {
            Some(s) if s.pilots && pilots => s.doubts,
            _ => self.doubts_before_word(false),
        };
        watch.seen = answer.as_ref().map(|a| AnswerSeen {
            pilots,
            what: match a {
                Answer::PilotTookOver(w) => w.clone(),
                _ => String::new(),
            },
            at: Instant::now(),
            in_doubt: false,
            doubts,
        });
        None
    }

    /// A heartbeat of the ids (an autopilot's) during the retries of `way` that is no answer
    /// of the vehicle's: heard after a second sender was seen, or in a doubt of the frame
    /// counter. After a second sender, a mode or arming the companion did not command (a
    /// pilot's, or the second sender's) stops the retries ([`Answer::NotCommanded`],
    /// att41f-3), and whether it shows the vehicle still in the mode it was left in (the only
    /// reason for a retry then: [`Flight::left_in`], att42f-2) is the second value. Before one,
    /// in a doubt, such a mode or arming is a pilot's word awaiting confirmation (att42f-5,
    /// [`AnswerSeen::in_doubt`]): no retry meanwhile, and a second sender proven after it stops
    /// the retries with nothing more commanded
    /// ([`Flight::word_before_second_sender_in_retries`]).
    fn unapplied_beat(
        &self,
        h: &HEARTBEAT_DATA,
        way: WayOut,
        before: (Option<u32>, bool),
        watch: &mut RetryWatch,
    ) -> (Option<Answer>, bool) {
        if self.second_sender {
            let way = WayOut::Mode(self.opts.failsafe.mode());
            if let Some(w) = self.word_not_commanded(h, way, before, watch.disarm_sent) {
                return (Some(Answer::NotCommanded(w)), false);
            }
            return (None, self.left_in(h, before));
        }
        // One showing another answer than the one awaited (a second counter's heartbeat
        // applied before the doubt, the vehicle's own in it) restarts its span, as an older
        // one does: it has not stood uncontradicted.
        watch.contradicted_by(&self.heartbeat_answer(h, way, before));
        if let Some(what) = self.word_not_commanded(h, way, before, watch.disarm_sent) {
            if watch.seen.as_ref().is_none_or(|s| !s.pilots) {
                watch.seen = Some(AnswerSeen {
                    pilots: true,
                    what,
                    at: Instant::now(),
                    in_doubt: true,
                    doubts: self.doubts_before_word(true),
                });
            }
        }
        (None, false)
    }

    /// What a heartbeat during the retries of `way` shows that the companion did not command,
    /// in words (`in MANUAL`, `in RETURN`, `disarmed`): another mode than the way out's and the
    /// one the failsafe began in (OFFBOARD is the companion's; a safe one counts), or a disarm
    /// of a vehicle armed as the failsafe began unless the companion commanded one
    /// (`disarm_sent`), whatever mode it shows, the way out's included (att42f-1: a pilot's
    /// disarm of a vehicle already in HOLD).
    fn word_not_commanded(
        &self,
        h: &HEARTBEAT_DATA,
        way: WayOut,
        before: (Option<u32>, bool),
        disarm_sent: bool,
    ) -> Option<String> {
        let armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        // A disarm the companion commanded is no word ([`Flight::heartbeat_answer`] takes an
        // uncommanded one as a pilot's in any mode).
        let before = (before.0, before.1 && !disarm_sent);
        match self.heartbeat_answer(h, way, before) {
            Some(Answer::PilotTookOver(_)) if !armed && disarm_sent => None,
            Some(Answer::PilotTookOver(w)) => Some(w),
            Some(Answer::OtherSafeMode(n)) => Some(format!("in {n}")),
            _ => None,
        }
    }

    /// Whether a heartbeat shows the vehicle still armed in the mode the companion left it in:
    /// OFFBOARD, or the mode the failsafe began in (`before`), not the `--failsafe` mode. After
    /// a second sender, the only evidence that the way out is still owed (att42f-2): a retry is
    /// sent on it, never on a heartbeat showing the way out or a mode nobody here commanded.
    fn left_in(&self, h: &HEARTBEAT_DATA, before: (Option<u32>, bool)) -> bool {
        let armed = h
            .base_mode
            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
        // The mode the failsafe began in is the companion's only on a vehicle it armed: on one
        // its pilot armed (a take-over from POSCTL whose OFFBOARD was accepted but never shown)
        // it is the pilot's mode (att45f-7), no reason for a retry.
        mode_of(h).is_some_and(|c| {
            armed
                && !self.firmware.is_in(c, self.opts.failsafe.mode())
                && (self.firmware.is_in(c, FlyMode::Offboard)
                    || (self.armed_by_us && before.0 == Some(c)))
        })
    }

    /// The vehicle's mode and arming as last confirmed: before a pilot's word still awaiting
    /// confirmation ([`LeaveSeen`]: it may be a second vehicle's), else as its heartbeats show.
    fn confirmed_state(&self) -> (Option<u32>, bool) {
        match &self.leave_seen {
            Some(l) if !l.confirmed => l.before,
            _ => (self.custom_mode, self.armed),
        }
    }

    /// Whether the forced disarm is owed on the way out: the companion armed the vehicle on
    /// the ground and never had it in control, and no confirmed heartbeat shows it disarmed
    /// (ver33c-6; att33f-6: a second vehicle's disarmed heartbeat, unconfirmed, is no reason
    /// to skip it).
    fn disarm_owed(&self) -> bool {
        self.armed_by_us && !self.in_control && (self.armed || self.confirmed_state().1)
    }

    /// What a heartbeat of the vehicle's (applied) during the retries of `way` answers:
    /// the mode commanded (or, for a disarm, disarmed), another safe mode, a pilot's change
    /// ([`Flight::pilots_change`]; out of OFFBOARD in any other mode for `LeaveOffboard`), or
    /// nothing yet.
    fn heartbeat_answer(
        &self,
        h: &HEARTBEAT_DATA,
        way: WayOut,
        before: (Option<u32>, bool),
    ) -> Option<Answer> {
        let safe = |c: u32| self.firmware.safe_mode_name(c).map(Answer::OtherSafeMode);
        if way != WayOut::Disarm && self.uncommanded_disarm(h, before) {
            // A disarm the companion did not command is a pilot's word whatever mode it shows,
            // the way out's or another safe one included (att45f-5).
            return Some(Answer::PilotTookOver("disarmed".into()));
        }
        match way {
            WayOut::LeaveOffboard(m) => {
                let c = mode_of(h)?;
                if self.firmware.is_in(c, m) {
                    return Some(Answer::Confirmed);
                }
                // Out of OFFBOARD in another mode (the pilot's, or the one it never left): the
                // pilot's mode stands.
                safe(c).or_else(|| {
                    (!self.firmware.is_in(c, FlyMode::Offboard)).then(|| {
                        Answer::PilotTookOver(format!("in {}", self.firmware.mode_name(c)))
                    })
                })
            }
            WayOut::Mode(m) => match mode_of(h) {
                Some(c) if self.firmware.is_in(c, m) => Some(Answer::Confirmed),
                c => c
                    .and_then(safe)
                    .or_else(|| self.pilots_change(h, before).map(Answer::PilotTookOver)),
            },
            WayOut::Disarm
                if !h
                    .base_mode
                    .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED) =>
            {
                Some(Answer::Confirmed)
            }
            WayOut::Disarm => self.pilots_change(h, before).map(Answer::PilotTookOver),
        }
    }

    /// Whether a heartbeat during the failsafe's retries shows disarmed a vehicle armed as the
    /// failsafe began (`before`): with a way out other than the disarm, nobody here commanded
    /// it.
    fn uncommanded_disarm(&self, h: &HEARTBEAT_DATA, before: (Option<u32>, bool)) -> bool {
        before.1
            && !h
                .base_mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
    }

    /// A heartbeat during the failsafe's retries that shows what a pilot did: a mode other
    /// than the one the vehicle was in as the failsafe began (and not a safe one, checked
    /// before), or a disarm the companion did not command; in words (`in MANUAL`, `disarmed`).
    fn pilots_change(&self, h: &HEARTBEAT_DATA, before: (Option<u32>, bool)) -> Option<String> {
        if self.uncommanded_disarm(h, before) {
            return Some("disarmed".into());
        }
        // OFFBOARD, which the companion itself asked for (a switch answered late) or flew in,
        // is no pilot's: it is what the way out takes the vehicle out of.
        // A heartbeat without a custom mode (MAV_MODE_FLAG_CUSTOM_MODE_ENABLED clear) says
        // nothing of the mode: neither a confirmation nor a pilot's.
        let now = mode_of(h)?;
        let own =
            (self.offboard_sent || self.in_control) && self.firmware.is_in(now, FlyMode::Offboard);
        if before.0.is_some_and(|m| m != now) && !own {
            return Some(format!("in {}", self.firmware.mode_name(now)));
        }
        None
    }
}

/// A heartbeat's custom mode: `custom_mode` only with `MAV_MODE_FLAG_CUSTOM_MODE_ENABLED` in its
/// `base_mode` (MAVLink: without the flag `custom_mode` means nothing), else unknown (`None`):
/// such a heartbeat neither hands over (OFFBOARD unknown) nor confirms a failsafe's mode.
pub fn mode_of(h: &HEARTBEAT_DATA) -> Option<u32> {
    h.base_mode
        .contains(MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)
        .then_some(h.custom_mode)
}

/// The note of a disarm that came after a silence of the vehicle's of more than
/// [`REBOOT_STEP_S`] (`disarm_after_silence`), in control ([`Flight::maybe_rebooted`]) and in
/// the failsafe's retries alike (att53f-2); empty otherwise.
fn silence_note(disarm_after_silence: bool) -> String {
    if disarm_after_silence {
        format!(
            " (or its autopilot rebooted: it was silent for more than {REBOOT_STEP_S} s before the disarm)"
        )
    } else {
        String::new()
    }
}

/// The `time_boot_ms` of a message stamped with the sender's clock since its boot (the ones
/// an autopilot sends here), if it is one. Not the measurement's: its clock may be a sensor's
/// own, and its jumps are [`MAX_MEASUREMENT_STEP_S`]'s.
fn vehicle_time_ms(msg: &MavMessage) -> Option<u32> {
    match msg {
        MavMessage::ATTITUDE(m) => Some(m.time_boot_ms),
        MavMessage::LOCAL_POSITION_NED(m) => Some(m.time_boot_ms),
        MavMessage::GLOBAL_POSITION_INT(m) => Some(m.time_boot_ms),
        MavMessage::SYSTEM_TIME(m) => Some(m.time_boot_ms),
        _ => None,
    }
}

/// Whether a heartbeat is a vehicle's autopilot: an autopilot (not `MAV_AUTOPILOT_INVALID`)
/// of a vehicle type. A gimbal, camera, ground station or another companion on the vehicle's
/// system also beats, some of them with the autopilot's `autopilot` field: never the vehicle.
pub fn is_autopilot(h: &HEARTBEAT_DATA) -> bool {
    use MavType::*;
    h.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID
        && matches!(
            h.mavtype,
            // GENERIC: "a generic micro air vehicle", what MAVSDK's autopilot server announces.
            MAV_TYPE_GENERIC
                | MAV_TYPE_FIXED_WING
                | MAV_TYPE_QUADROTOR
                | MAV_TYPE_COAXIAL
                | MAV_TYPE_HELICOPTER
                | MAV_TYPE_AIRSHIP
                | MAV_TYPE_FREE_BALLOON
                | MAV_TYPE_ROCKET
                | MAV_TYPE_GROUND_ROVER
                | MAV_TYPE_SURFACE_BOAT
                | MAV_TYPE_SUBMARINE
                | MAV_TYPE_HEXAROTOR
                | MAV_TYPE_OCTOROTOR
                | MAV_TYPE_TRICOPTER
                | MAV_TYPE_FLAPPING_WING
                | MAV_TYPE_KITE
                | MAV_TYPE_VTOL_TAILSITTER_DUOROTOR
                | MAV_TYPE_VTOL_TAILSITTER_QUADROTOR
                | MAV_TYPE_VTOL_TILTROTOR
                | MAV_TYPE_VTOL_FIXEDROTOR
                | MAV_TYPE_VTOL_TAILSITTER
                | MAV_TYPE_VTOL_TILTWING
                | MAV_TYPE_DODECAROTOR
                | MAV_TYPE_DECAROTOR
                | MAV_TYPE_PARAFOIL
                | MAV_TYPE_GENERIC_MULTIROTOR
                | MAV_TYPE_GROUND_QUADRUPED
        )
}
