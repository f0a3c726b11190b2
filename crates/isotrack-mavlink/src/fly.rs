//! `isotrack fly`: the companion computer. It runs the scenario's own law
//! ([`Scenario::tracker`]: search phase, anti-windup, turn-rate limit, derivative estimator) on
//! the measurements it receives, and only on them (coordinate-free: positions are logged and
//! checked against the fence, never given to the law), and sends the command as the vehicle's
//! setpoint: a fixed wing's coordinated-turn roll `phi = -atan(omega V / g)` within the bank
//! limit, a ground vehicle's yaw rate, both as `SET_ATTITUDE_TARGET`, stamped with the time of
//! the measurement they answer, and repeated at a steady rate (PX4's offboard mode needs 2 Hz).
//!
//! Control: with `take_control` it arms and switches to OFFBOARD (holding the measurements
//! until it has control, so the law starts at the first one); without, it waits for the pilot
//! to do so, answering with neutral setpoints meanwhile. Failsafes (each logged): Ctrl-C
//! ([`FlyOptions::stop`]), `max_duration_s` of vehicle time, no message from the vehicle or no
//! measurement for `timeout_s` of wall time, leaving the fence: the setpoints stop and the
//! vehicle is switched to HOLD (or RETURN).

use crate::link::{Link, LinkError, LinkStats, Received};
use crate::mirror::Transport;
use crate::vehicle_state::{Mode, PX4_MAIN_AUTO, PX4_MAIN_OFFBOARD, PX4_SUB_LOITER, PX4_SUB_RTL};
use crate::wire;
use isotrack_core::{IsolineController, Measurement};
use isotrack_scenario::Scenario;
use isotrack_sim::{TraceRow, TraceSink};
use mavlink::dialects::common::*;
use std::collections::VecDeque;
use std::net::UdpSocket;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The `time_boot_ms` of a setpoint that answers no measurement (sent before the first one).
pub const NOT_AN_ANSWER_MS: u32 = u32::MAX;

/// The largest step of the measurements' clock (`time_boot_ms`) between two measurements
/// received, forwards or backwards, s: a larger one (a rebooted or spoofed clock) is a sensor
/// fault, and fails safe (`sensor_clock_jump`).
pub const MAX_MEASUREMENT_STEP_S: f64 = 60.0;

/// How long after the first autopilot heard a second one (another system or component) makes
/// the vehicle ambiguous (`two_vehicles`), s.
pub const TWO_VEHICLES_WINDOW_S: f64 = 1.0;

/// The longest unterminated line kept from a UDP sensor's datagrams, bytes.
pub const MAX_PARTIAL_LINE_BYTES: usize = 1024;

/// The measurements' clock as received: only a measurement newer than every one before it
/// counts as one for the sensor-loss timer (the companion's own monotonic clock).
struct SensorClock {
    /// The newest `time_boot_ms` received.
    newest_ms: Option<u32>,
    /// When the newest measurement (or, before any, the vehicle's first message) arrived.
    last: Instant,
    /// A jump of the clock, to fail safe on.
    fault: Option<String>,
}

impl SensorClock {
    /// Takes in a received measurement: queued unless its time jumps.
    fn receive(&mut self, queue: &mut VecDeque<(u32, f64)>, ms: u32, v: f64) {
        let max_ms = (MAX_MEASUREMENT_STEP_S * 1000.0) as u32;
        match self.newest_ms {
            Some(n) if ms <= n => {
                if n - ms > max_ms {
                    self.fault.get_or_insert(format!(
                        "the measurement's time jumped back from {} s to {} s (a rebooted or spoofed clock)",
                        wire::time_s(n),
                        wire::time_s(ms)
                    ));
                    return;
                }
                // A repeat (answered again) or a late one (dropped): no news of the sensor.
                queue.push_back((ms, v));
            }
            Some(n) if ms - n > max_ms => {
                self.fault.get_or_insert(format!(
                    "the measurement's time jumped ahead from {} s to {} s (a spoofed clock)",
                    wire::time_s(n),
                    wire::time_s(ms)
                ));
            }
            _ => {
                self.newest_ms = Some(ms);
                self.last = Instant::now();
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
    /// Parses `--sensor`: `NAME`, `mavlink:NAME` or `udp:HOST:PORT`.
    pub fn parse(s: &str) -> Result<Self, String> {
        if let Some(a) = s.strip_prefix("udp:") {
            return Ok(SensorSource::UdpLines(a.to_string()));
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

/// The mode a failsafe switches to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailsafeAction {
    /// HOLD (PX4 AUTO.LOITER).
    Hold,
    /// RETURN (PX4 AUTO.RTL).
    Return,
}

/// What the companion commands when it lets go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum WayOut {
    /// The failsafe mode.
    Mode(Mode),
    /// Disarm (a vehicle the companion armed on the ground).
    Disarm,
}

/// Options of [`run_fly`].
#[derive(Clone, Debug)]
pub struct FlyOptions {
    /// The link address (see [`crate::link`]).
    pub url: String,
    /// Where the measurements come from.
    pub sensor: SensorSource,
    /// Arm and switch to OFFBOARD (else wait for the pilot to).
    pub take_control: bool,
    /// End after this much vehicle time since the first measurement, s.
    pub max_duration_s: Option<f64>,
    /// Fail safe after this long without a message from the vehicle or a measurement, wall s.
    pub timeout_s: f64,
    /// Fail safe when farther than this from the first received position, m.
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
}

impl FlyOptions {
    /// Defaults: `ISO_S`, no take-over, a 3 s timeout, no fence, HOLD, 10 Hz setpoints, system
    /// 1 (the vehicle's own system, as a companion computer is).
    pub fn new(url: &str) -> Self {
        Self {
            url: url.to_string(),
            sensor: SensorSource::Named(wire::MEASUREMENT_NAME.into()),
            take_control: false,
            max_duration_s: None,
            timeout_s: 3.0,
            fence_m: None,
            failsafe: FailsafeAction::Hold,
            setpoint_rate_hz: 10.0,
            system_id: 1,
            target_system: None,
            stop: Arc::new(AtomicBool::new(false)),
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
    /// (`STATUSTEXT` "isotrack sitl: run ended"): failsafe.
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
    /// Whether the vehicle acknowledged the failsafe mode (or, after a refused take-over, the
    /// mode or the disarm commanded).
    pub failsafe_acknowledged: bool,
    /// Whether anything was commanded on the way out (a failsafe's mode, or after a refused
    /// take-over of an armed vehicle, HOLD/RETURN or a disarm).
    pub way_out_commanded: bool,
    /// The link's counters.
    pub link: LinkStats,
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

struct Fly<'a> {
    link: Link,
    opts: &'a FlyOptions,
    transport: Transport,
    target: Option<(u32, u8)>,
    armed: bool,
    mode: Option<Mode>,
    /// The command in force (None: neutral, before the law has control).
    current: Option<f64>,
    last_answer_ms: Option<u32>,
    /// The vehicle refused to arm or to switch to OFFBOARD.
    refused: bool,
    /// The vehicle has been armed and in OFFBOARD (the companion had control).
    in_control: bool,
    /// The companion has sent an arm command.
    arm_sent: bool,
    /// The vehicle was disarmed when first heard and armed on the companion's command: it is
    /// still on the ground, and disarming it is the way out of a refused take-over.
    armed_by_us: bool,
    /// The first `GLOBAL_POSITION_INT` fix, about which global positions are projected while
    /// no `LOCAL_POSITION_NED` has come.
    global_origin: Option<crate::geo::Home>,
    /// A finite `LOCAL_POSITION_NED` has come (positions are local from then on).
    local_seen: bool,
    /// The vehicle announced the end of its run (`STATUSTEXT` "isotrack sitl: run ended").
    run_ended: bool,
    /// When the last finite position arrived.
    position_at: Option<Instant>,
    /// The companion has asked for OFFBOARD.
    offboard_sent: bool,
    /// When the vehicle was first heard.
    target_at: Option<Instant>,
    /// Another autopilot heard within [`TWO_VEHICLES_WINDOW_S`] of the vehicle.
    other_vehicle: Option<(u32, u8)>,
    events: Vec<String>,
    t0: Instant,
}

impl Fly<'_> {
    fn event(&mut self, what: String) {
        let t = self.t0.elapsed().as_secs_f64();
        self.events.push(format!("wall {t:.3} s: {what}"));
    }

    fn send(&mut self, m: MavMessage) -> Result<(), FlyError> {
        self.link.send(&m).map(|_| ()).map_err(FlyError::Io)
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

    /// The setpoint of the command in force, stamped `ms`.
    fn setpoint(&mut self, ms: u32) -> Result<(), FlyError> {
        let Some((sys, comp)) = self.target else {
            return Ok(());
        };
        let w = self.current.unwrap_or(0.0);
        let ignore_rates = AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_ROLL_RATE_IGNORE
            | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_PITCH_RATE_IGNORE
            | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_THROTTLE_IGNORE;
        let (q, yaw_rate, mask) = match self.transport {
            Transport::FixedWing { airspeed_mps } => (
                wire::quaternion_of_roll(wire::roll_of_turn_rate(w, airspeed_mps)),
                0.0,
                ignore_rates
                    | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_BODY_YAW_RATE_IGNORE,
            ),
            Transport::Ground => (
                [1.0, 0.0, 0.0, 0.0],
                wire::yaw_rate_of_turn_rate(w),
                ignore_rates | AttitudeTargetTypemask::ATTITUDE_TARGET_TYPEMASK_ATTITUDE_IGNORE,
            ),
        };
        self.send(MavMessage::SET_ATTITUDE_TARGET(SET_ATTITUDE_TARGET_DATA {
            time_boot_ms: ms,
            q,
            body_roll_rate: 0.0,
            body_pitch_rate: 0.0,
            body_yaw_rate: yaw_rate,
            thrust: 0.0,
            target_system: sys as u8,
            target_component: comp,
            type_mask: mask,
        }))
    }

    fn set_mode_params(mode: Mode) -> [f32; 3] {
        let (main, sub) = match mode {
            Mode::Offboard => (PX4_MAIN_OFFBOARD, 0),
            Mode::Return => (PX4_MAIN_AUTO, PX4_SUB_RTL),
            _ => (PX4_MAIN_AUTO, PX4_SUB_LOITER),
        };
        // param1: MAV_MODE_FLAG_CUSTOM_MODE_ENABLED.
        [1.0, main as f32, sub as f32]
    }
}

/// Flies `scenario`'s law over `opts.url`, recording one trace row per answered measurement
/// (received position, measured value as `s`, the command) into `sink`; `on_ready` is told the
/// local address once the link is open. `log` receives nothing here: see [`Link::log_to`] via
/// `link_setup`, called on the link before the flight starts (the raw MAVLink log).
pub fn run_fly<S: TraceSink + ?Sized>(
    scenario: &Scenario,
    opts: &FlyOptions,
    sink: &mut S,
    link_setup: &mut dyn FnMut(&mut Link) -> std::io::Result<()>,
) -> Result<FlyReport, FlyError> {
    let mut law = scenario.tracker();
    if law.needs_ground_truth() {
        return Err(FlyError::Scenario(
            "controller.kind = \"gradient_reference\" needs the field's gradient at the vehicle: it cannot fly on measurements alone".into(),
        ));
    }
    crate::sitl::check_wire_times(scenario).map_err(FlyError::Scenario)?;
    let mut link = Link::open(&opts.url, opts.system_id, 191).map_err(FlyError::Link)?;
    link_setup(&mut link).map_err(FlyError::Io)?;
    let lines = match &opts.sensor {
        SensorSource::UdpLines(a) => {
            let s = UdpSocket::bind(a)
                .map_err(|e| FlyError::Link(LinkError::Io(format!("--sensor udp:{a}: {e}"))))?;
            s.set_nonblocking(true).map_err(FlyError::Io)?;
            Some(s)
        }
        SensorSource::Named(_) => None,
    };
    let wanted: Vec<u8> = match &opts.sensor {
        SensorSource::Named(n) => n.as_bytes().to_vec(),
        SensorSource::UdpLines(_) => Vec::new(),
    };
    let level = scenario.level();
    let mut fly = Fly {
        link,
        opts,
        transport: Transport::of(scenario),
        target: None,
        armed: false,
        mode: None,
        current: None,
        last_answer_ms: None,
        refused: false,
        in_control: false,
        arm_sent: false,
        armed_by_us: false,
        global_origin: None,
        local_seen: false,
        run_ended: false,
        position_at: None,
        offboard_sent: false,
        target_at: None,
        other_vehicle: None,
        events: Vec::new(),
        t0: Instant::now(),
    };
    // Never a panic on a huge timeout (the CLI bounds it to a day).
    let timeout =
        Duration::try_from_secs_f64(opts.timeout_s.max(0.0)).unwrap_or(Duration::from_secs(86_400));
    let period = Duration::from_secs_f64(1.0 / opts.setpoint_rate_hz.max(2.0));
    let mut queue: VecDeque<(u32, f64)> = VecDeque::new();
    let mut commands = Vec::new();
    let (mut samples, mut t_first, mut t_last) = (0u64, None::<f64>, None::<f64>);
    let mut last_link = Instant::now();
    let mut clock = SensorClock {
        newest_ms: None,
        last: Instant::now(),
        fault: None,
    };
    let mut first_wall: Option<Instant> = None;
    let mut t_control: Option<f64> = None;
    let mut skipping_line = false;
    let mut next_setpoint = Instant::now();
    let mut next_heartbeat = Instant::now();
    let mut next_control = Instant::now();
    let mut control_tries = 0u32;
    let mut was_armed = false;
    let mut pos: Option<(f64, f64)> = None;
    let mut heading = 0.0;
    let mut home: Option<(f64, f64)> = None;
    let mut home_local = false;
    // Since the vehicle's first message (the fence's wait for a position).
    let mut clock_start = Instant::now();
    let mut vehicle_done = false;
    let mut mavlink1_logged = false;
    let mut partial: Vec<u8> = Vec::new();
    let mut buf = vec![0u8; 65_536];
    let end = 'flight: loop {
        if opts.stop.load(Ordering::Relaxed) {
            break 'flight FlyEnd::Interrupted;
        }
        let now = Instant::now();
        if now >= next_heartbeat {
            fly.heartbeat()?;
            next_heartbeat = now + Duration::from_secs(1);
        }
        let had_target = fly.target.is_some();
        for r in fly
            .link
            .poll(Duration::from_millis(10))
            .map_err(FlyError::Io)?
        {
            handle(
                &mut fly,
                &r,
                &wanted,
                &mut queue,
                &mut last_link,
                &mut clock,
                &mut pos,
                &mut heading,
                &mut vehicle_done,
            );
        }
        if let (Some(a), Some(b)) = (fly.target, fly.other_vehicle) {
            fly.event(format!(
                "two autopilots heard within {TWO_VEHICLES_WINDOW_S} s: system {}, component {} and system {}, component {}: which to fly is ambiguous, nothing commanded (pick one with --target-system)",
                a.0, a.1, b.0, b.1
            ));
            break 'flight FlyEnd::TwoVehicles;
        }
        if fly.link.stats.mavlink1_frames > 0 && !mavlink1_logged {
            mavlink1_logged = true;
            fly.event(
                "MAVLink 1 frames received and ignored: this bridge speaks MAVLink 2 only (set the autopilot's link to MAVLink 2)".into(),
            );
        }
        if !had_target && fly.target.is_some() {
            // The sensor's silence counts from the vehicle's first message.
            clock.last = Instant::now();
            clock_start = Instant::now();
        }
        if let Some(s) = &lines {
            // At most MAX_DATAGRAMS_PER_POLL datagrams a turn: a flood delays, never starves,
            // the link. A line may span datagrams: the tail after the last newline waits for
            // the rest (at most MAX_PARTIAL_LINE_BYTES, else dropped).
            for _ in 0..crate::link::MAX_DATAGRAMS_PER_POLL {
                let Ok((n, _)) = s.recv_from(&mut buf) else {
                    break;
                };
                partial.extend_from_slice(&buf[..n]);
                if skipping_line {
                    // The rest of a dropped over-long line is no line.
                    match partial.iter().position(|&b| b == b'\n') {
                        Some(i) => {
                            partial.drain(..=i);
                            skipping_line = false;
                        }
                        None => {
                            partial.clear();
                            continue;
                        }
                    }
                }
                let Some(end) = partial.iter().rposition(|&b| b == b'\n') else {
                    if partial.len() > MAX_PARTIAL_LINE_BYTES {
                        partial.clear();
                        skipping_line = true;
                    }
                    continue;
                };
                let text = String::from_utf8_lossy(&partial[..end]).into_owned();
                partial.drain(..=end);
                if partial.len() > MAX_PARTIAL_LINE_BYTES {
                    partial.clear();
                    skipping_line = true;
                }
                for line in text.lines() {
                    let mut it = line.split(',');
                    let (Some(t), Some(v), None) = (it.next(), it.next(), it.next()) else {
                        continue;
                    };
                    if let (Ok(t), Ok(v)) = (t.trim().parse::<f64>(), v.trim().parse::<f64>()) {
                        if let (Some(ms), true) = (wire::time_ms(t), v.is_finite()) {
                            clock.receive(&mut queue, ms, v);
                        }
                    }
                }
            }
        }
        // The fence, on the received position (never given to the law).
        if let (Some(f), None, true) = (opts.fence_m, pos, fly.target.is_some()) {
            if clock_start.elapsed() > timeout {
                fly.event(format!(
                    "fence: no position from the vehicle for {} s, the fence of {f} m cannot be kept",
                    opts.timeout_s
                ));
                break 'flight FlyEnd::Fence;
            }
        }
        if let (Some(f), Some(at)) = (opts.fence_m, fly.position_at) {
            // The fence never silently switches off: positions that stop (or turn non-finite,
            // which are dropped) end the flight.
            if at.elapsed() > timeout {
                fly.event(format!(
                    "position_lost: no finite position from the vehicle for {} s, the fence of {f} m cannot be kept",
                    opts.timeout_s
                ));
                break 'flight FlyEnd::Fence;
            }
        }
        if fly.local_seen && !home_local {
            // Positions were projected from GLOBAL_POSITION_INT: the fence re-anchors on the
            // first local one.
            home_local = true;
            home = None;
        }
        if let Some(p) = pos {
            let h = *home.get_or_insert(p);
            if let Some(f) = opts.fence_m {
                let d = ((p.0 - h.0).powi(2) + (p.1 - h.1).powi(2)).sqrt();
                if d > f {
                    fly.event(format!("fence: {d:.1} m from the start, beyond {f} m"));
                    break 'flight FlyEnd::Fence;
                }
            }
        }
        if fly.armed != was_armed {
            // Armed: ask for OFFBOARD at once.
            was_armed = fly.armed;
            next_control = Instant::now();
        }
        let active = fly.armed && fly.mode == Some(Mode::Offboard);
        if active {
            fly.in_control = true;
            // --max-duration-s counts from here (the companion's clock).
            first_wall.get_or_insert_with(Instant::now);
        } else if fly.in_control {
            // Nothing of the companion's leaves OFFBOARD or disarms during the flight: a pilot
            // (or the autopilot's own failsafe) took over. Stop at once and command nothing.
            fly.event(format!(
                "pilot_took_over: the vehicle is {} in {}, not commanded by the companion: setpoints stopped, nothing commanded",
                if fly.armed { "armed" } else { "disarmed" },
                fly.mode.map_or("an unknown mode", |m| m.name())
            ));
            break 'flight FlyEnd::PilotTookOver;
        }
        // Taking control: arm, then OFFBOARD, retried every 0.5 s.
        if opts.take_control && !active && fly.refused {
            fly.event("the vehicle refused to arm or to switch to OFFBOARD".into());
            break 'flight FlyEnd::ControlRefused;
        }
        // Nothing is armed before the sensor and the position are there: a take-over waits
        // for the first measurement and the first position (each within --timeout-s, below).
        let ready = clock.newest_ms.is_some() && pos.is_some();
        if opts.take_control
            && !active
            && fly.target.is_some()
            && !ready
            && clock.newest_ms.is_some()
            && clock_start.elapsed() > timeout
        {
            fly.event(format!(
                "no position from the vehicle for {} s: control not taken",
                opts.timeout_s
            ));
            break 'flight FlyEnd::SensorLost;
        }
        if opts.take_control
            && !active
            && ready
            && fly.target.is_some()
            && Instant::now() >= next_control
        {
            control_tries += 1;
            if control_tries > 20 {
                fly.event("the vehicle did not arm or switch to OFFBOARD in 10 s".into());
                break 'flight FlyEnd::ControlRefused;
            }
            if !fly.armed {
                fly.arm_sent = true;
                fly.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, [1.0, 0.0, 0.0])?;
            } else {
                // PX4 wants setpoints before the switch.
                fly.setpoint(fly.last_answer_ms.unwrap_or(NOT_AN_ANSWER_MS))?;
                fly.offboard_sent = true;
                fly.command(
                    MavCmd::MAV_CMD_DO_SET_MODE,
                    Fly::set_mode_params(Mode::Offboard),
                )?;
            }
            next_control = Instant::now() + Duration::from_millis(500);
        }
        let holding = opts.take_control && !active;
        if !holding {
            while let Some((ms, v)) = queue.pop_front() {
                if let Some(last) = fly.last_answer_ms {
                    if ms < last {
                        continue;
                    }
                    if ms == last {
                        // A repeat (the vehicle lost our answer?): the same answer again, within
                        // a UDP sensor's --setpoint-rate-hz.
                        if lines.is_none() || Instant::now() >= next_setpoint {
                            fly.setpoint(ms)?;
                            next_setpoint = Instant::now() + period;
                        }
                        continue;
                    }
                }
                let m = Measurement {
                    t_s: wire::time_s(ms),
                    value: v,
                };
                t_first.get_or_insert(m.t_s);
                // --max-duration-s counts from the first measurement the law answers in
                // control (vehicle time).
                let first = if active {
                    Some(*t_control.get_or_insert(m.t_s))
                } else {
                    None
                };
                if let (Some(max), Some(first)) = (opts.max_duration_s, first) {
                    if m.t_s - first >= max {
                        fly.event(format!(
                            "max duration {max} s reached at vehicle time {} s",
                            m.t_s
                        ));
                        break 'flight FlyEnd::MaxDuration;
                    }
                }
                samples += 1;
                t_last = Some(m.t_s);
                if active {
                    let w = law.update(&m);
                    if !w.is_finite() {
                        fly.event(format!(
                            "the law's command is not finite at t = {} s",
                            m.t_s
                        ));
                        break 'flight FlyEnd::LawNotFinite;
                    }
                    commands.push((ms, w));
                    fly.current = Some(w);
                } else {
                    fly.current = None;
                }
                fly.last_answer_ms = Some(ms);
                // A MAVLink sensor's every sample is answered (a lockstep vehicle waits for
                // it); a UDP sensor's answers keep to --setpoint-rate-hz (the periodic
                // setpoint carries the newest command): a fast sensor does not multiply the
                // setpoints.
                if lines.is_none() || Instant::now() >= next_setpoint {
                    fly.setpoint(ms)?;
                    next_setpoint = Instant::now() + period;
                }
                let (x, y) = pos.unwrap_or((f64::NAN, f64::NAN));
                sink.record(&TraceRow {
                    t_s: m.t_s,
                    x_m: x,
                    y_m: y,
                    heading_rad: heading,
                    s: v,
                    error: v - level,
                    omega_radps: fly.current.unwrap_or(0.0),
                    s_measured: Some(v),
                    telemetry: None,
                });
            }
        } else if queue.len() > 100_000 {
            queue.pop_front();
        }
        if vehicle_done && !fly.run_ended {
            fly.event("the vehicle powered off without ending its run: vehicle lost".into());
            break 'flight FlyEnd::VehicleLost;
        }
        if vehicle_done {
            fly.event("the vehicle ended its run".into());
            break 'flight FlyEnd::VehicleEnded;
        }
        let now = Instant::now();
        if fly.target.is_some() && now >= next_setpoint {
            fly.setpoint(fly.last_answer_ms.unwrap_or(NOT_AN_ANSWER_MS))?;
            next_setpoint = now + period;
        }
        if now.duration_since(last_link) > timeout {
            fly.event(format!(
                "no message from the vehicle for {} s",
                opts.timeout_s
            ));
            break 'flight FlyEnd::LinkLost;
        }
        if let Some(what) = clock.fault.take() {
            fly.event(what);
            break 'flight FlyEnd::SensorClockJump;
        }
        if let (Some(max), Some(w)) = (opts.max_duration_s, first_wall) {
            // The companion's own clock too: a vehicle clock that stalls cannot stretch the run.
            if now.duration_since(w).as_secs_f64() >= max {
                fly.event(format!(
                    "max duration {max} s reached on the companion's clock"
                ));
                break 'flight FlyEnd::MaxDuration;
            }
        }
        if now.duration_since(clock.last) > timeout {
            fly.event(format!("no measurement for {} s", opts.timeout_s));
            break 'flight FlyEnd::SensorLost;
        }
    };
    // The way out: the failsafe mode; after a refused take-over, a disarm if the companion
    // armed the vehicle on the ground, else the failsafe mode if it is armed.
    let mode = match opts.failsafe {
        FailsafeAction::Hold => Mode::Hold,
        FailsafeAction::Return => Mode::Return,
    };
    // Before the companion had control, a failsafe commands nothing on a vehicle it never
    // controlled (a pilot's, or a disarmed one): only a vehicle it armed itself is disarmed, and
    // one it asked for OFFBOARD is switched to the failsafe mode.
    let stopping = end.is_failsafe() || end == FlyEnd::ControlRefused;
    let way_out = if end.is_failsafe() && (fly.in_control || fly.target.is_none()) {
        Some(WayOut::Mode(mode))
    } else if stopping && fly.armed && fly.armed_by_us {
        Some(WayOut::Disarm)
    } else if stopping && fly.armed && (end == FlyEnd::ControlRefused || fly.offboard_sent) {
        Some(WayOut::Mode(mode))
    } else {
        None
    };
    if way_out.is_none() && end.is_failsafe() {
        fly.event(format!(
            "failsafe ({}) before the companion had control: nothing commanded, the vehicle's mode stands",
            end.as_str()
        ));
    }
    let mut acknowledged = false;
    if let Some(way) = way_out {
        let what = match way {
            WayOut::Mode(m) => format!("{} commanded", m.name()),
            WayOut::Disarm => "disarm commanded (armed by the companion, on the ground)".into(),
        };
        fly.event(if fly.target.is_some() {
            format!("failsafe ({}): setpoints stopped, {what}", end.as_str())
        } else {
            format!(
                "failsafe ({}): no vehicle heard, nothing to command",
                end.as_str()
            )
        });
        // Every 0.3 s until the vehicle acknowledges it or reports it, or the link is lost (no
        // message from the vehicle for --timeout-s; at least 5 tries even then: the vehicle
        // may hear what it cannot answer).
        let mut tries = 0u32;
        let mut way_refused = false;
        let mut given_up = None;
        // A signal from here on (the one that may have caused the failsafe is spent) ends the
        // retries; so does their bound, 3 x --timeout-s within [3, 30] s.
        opts.stop.store(false, Ordering::SeqCst);
        let retry_end = Instant::now()
            + Duration::from_secs_f64((3.0 * opts.timeout_s.max(0.0)).clamp(3.0, 30.0));
        while fly.target.is_some() {
            let lost = Instant::now().duration_since(last_link) > timeout;
            if lost && tries >= 5 {
                break;
            }
            if opts.stop.load(Ordering::SeqCst) {
                given_up = Some("stopped by a signal");
                break;
            }
            if Instant::now() >= retry_end {
                given_up = Some("retries' bound reached");
                break;
            }
            tries += 1;
            match way {
                WayOut::Mode(m) => {
                    fly.command(MavCmd::MAV_CMD_DO_SET_MODE, Fly::set_mode_params(m))?
                }
                WayOut::Disarm => {
                    fly.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, [0.0, 0.0, 0.0])?
                }
            }
            let until = Instant::now() + Duration::from_millis(300);
            while Instant::now() < until && !acknowledged && !way_refused {
                for r in fly
                    .link
                    .poll(Duration::from_millis(20))
                    .map_err(FlyError::Io)?
                {
                    if Some((r.header.system_id, r.header.component_id)) != fly.target {
                        continue;
                    }
                    last_link = Instant::now();
                    if let MavMessage::COMMAND_ACK(a) = &r.msg {
                        let ours = match way {
                            WayOut::Mode(_) => MavCmd::MAV_CMD_DO_SET_MODE,
                            WayOut::Disarm => MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                        };
                        // A refusal (not "busy, try again"): retrying changes nothing.
                        if a.command == ours
                            && matches!(
                                a.result,
                                MavResult::MAV_RESULT_DENIED
                                    | MavResult::MAV_RESULT_UNSUPPORTED
                                    | MavResult::MAV_RESULT_FAILED
                            )
                        {
                            way_refused = true;
                        }
                    }
                    // Confirmed by the vehicle's heartbeat only (an acknowledgement is a promise:
                    // a vehicle may accept and stay in OFFBOARD).
                    acknowledged |= match (&r.msg, way) {
                        (MavMessage::HEARTBEAT(h), WayOut::Mode(m)) => {
                            Mode::from_custom_mode(h.custom_mode) == Some(m)
                        }
                        (MavMessage::HEARTBEAT(h), WayOut::Disarm) => !h
                            .base_mode
                            .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED),
                        _ => false,
                    };
                }
            }
            if acknowledged || way_refused {
                break;
            }
        }
        fly.event(if acknowledged {
            match way {
                WayOut::Mode(m) => format!("the vehicle is in {} ({tries} tries)", m.name()),
                WayOut::Disarm => format!("the vehicle is disarmed ({tries} tries)"),
            }
        } else if fly.target.is_none() {
            "no failsafe mode was sent".to_string()
        } else {
            format!(
                "the vehicle did not confirm the {} ({tries} tries, {})",
                match way {
                    WayOut::Mode(m) => m.name(),
                    WayOut::Disarm => "disarm",
                },
                if way_refused {
                    "refused"
                } else {
                    given_up.unwrap_or("link lost")
                }
            )
        });
    }
    Ok(FlyReport {
        end,
        commands,
        samples,
        t_first_s: t_first,
        t_last_s: t_last,
        events: fly.events,
        failsafe_acknowledged: acknowledged,
        way_out_commanded: way_out.is_some(),
        link: fly.link.stats,
    })
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

/// Handles one received message.
#[allow(clippy::too_many_arguments)]
fn handle(
    fly: &mut Fly<'_>,
    r: &Received,
    wanted: &[u8],
    queue: &mut VecDeque<(u32, f64)>,
    last_link: &mut Instant,
    clock: &mut SensorClock,
    pos: &mut Option<(f64, f64)>,
    heading: &mut f64,
    vehicle_done: &mut bool,
) {
    let from = (r.header.system_id, r.header.component_id);
    if let MavMessage::HEARTBEAT(h) = &r.msg {
        let wanted_system = fly.opts.target_system.is_none_or(|n| from.0 == n as u32);
        if is_autopilot(h) && from != (fly.opts.system_id as u32, 191) && wanted_system {
            match (fly.target, fly.target_at) {
                (None, _) => {
                    fly.target = Some(from);
                    fly.target_at = Some(Instant::now());
                    fly.event(format!(
                        "vehicle: system {}, component {}{}",
                        from.0,
                        from.1,
                        if fly.opts.target_system.is_some() {
                            " (--target-system)"
                        } else {
                            " (the first autopilot heard)"
                        }
                    ));
                }
                (Some(t), Some(at))
                    if t != from
                        && fly.opts.target_system.is_none()
                        && at.elapsed().as_secs_f64() < TWO_VEHICLES_WINDOW_S =>
                {
                    fly.other_vehicle.get_or_insert(from);
                }
                _ => {}
            }
        }
    }
    let Some(target) = fly.target else { return };
    // The measurement may come from another component of the vehicle's system.
    if from.0 != target.0 {
        return;
    }
    if let MavMessage::NAMED_VALUE_FLOAT(n) = &r.msg {
        if !wanted.is_empty() && name_of(&n.name[..]) == wanted && n.value.is_finite() {
            clock.receive(queue, n.time_boot_ms, n.value as f64);
        }
        return;
    }
    if from != target {
        return;
    }
    *last_link = Instant::now();
    match &r.msg {
        MavMessage::HEARTBEAT(h) => {
            let armed = h
                .base_mode
                .contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
            let mode = Mode::from_custom_mode(h.custom_mode);
            if armed && !fly.armed && fly.arm_sent && !fly.in_control {
                fly.armed_by_us = true;
            }
            if armed != fly.armed || mode != fly.mode {
                fly.event(format!(
                    "vehicle {} in {}",
                    if armed { "armed" } else { "disarmed" },
                    mode.map_or("an unknown mode", |m| m.name())
                ));
            }
            fly.armed = armed;
            fly.mode = mode;
            if h.system_status == MavState::MAV_STATE_POWEROFF {
                *vehicle_done = true;
            }
        }
        // Acknowledgements go to every peer of the vehicle: once in control, they may answer
        // someone else's command, and say nothing about ours.
        MavMessage::COMMAND_ACK(a) if !fly.in_control => {
            let ok = a.result == MavResult::MAV_RESULT_ACCEPTED;
            fly.event(format!("{:?}: {:?}", a.command, a.result));
            if ok && a.command == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM && fly.arm_sent {
                if !fly.armed {
                    fly.armed_by_us = true;
                }
                fly.armed = true;
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
                fly.refused = true;
            }
        }
        // A non-finite position is no position (it would switch the fence off).
        MavMessage::LOCAL_POSITION_NED(p) if p.x.is_finite() && p.y.is_finite() => {
            fly.local_seen = true;
            fly.position_at = Some(Instant::now());
            *pos = Some((p.y as f64, p.x as f64));
        }
        MavMessage::GLOBAL_POSITION_INT(g) if !fly.local_seen => {
            let (lat, lon) = (g.lat as f64 * 1e-7, g.lon as f64 * 1e-7);
            if lat.abs() <= 90.0 && lon.abs() <= 180.0 && !(g.lat == 0 && g.lon == 0) {
                let o = *fly.global_origin.get_or_insert(crate::geo::Home {
                    lat_deg: lat,
                    lon_deg: lon,
                    alt_m: 0.0,
                });
                fly.position_at = Some(Instant::now());
                *pos = Some(o.to_local_m(lat, lon));
            }
        }
        MavMessage::STATUSTEXT(t)
            if name_of(&t.text[..]).starts_with(b"isotrack sitl: run ended") =>
        {
            fly.run_ended = true;
        }
        MavMessage::ATTITUDE(a) => {
            *heading = isotrack_core::math::wrap_angle(std::f64::consts::FRAC_PI_2 - a.yaw as f64);
        }
        _ => {}
    }
}
