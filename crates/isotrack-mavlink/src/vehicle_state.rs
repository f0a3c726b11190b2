//! The simulated autopilot's modes and who may command it: what `isotrack sitl` answers to
//! `COMMAND_LONG` and `SET_ATTITUDE_TARGET`, kept apart from the sockets so that it is tested
//! alone.
//!
//! Modes use PX4's encoding (`HEARTBEAT.custom_mode = main << 16 | sub << 24`, with
//! `MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`): MANUAL (main 1), AUTO.LOITER (4, 3), AUTO.RTL (4, 5) and
//! OFFBOARD (6).

/// PX4's custom main mode MANUAL.
pub const PX4_MAIN_MANUAL: u8 = 1;
/// PX4's custom main mode AUTO.
pub const PX4_MAIN_AUTO: u8 = 4;
/// PX4's custom main mode OFFBOARD.
pub const PX4_MAIN_OFFBOARD: u8 = 6;
/// PX4's AUTO sub mode LOITER.
pub const PX4_SUB_LOITER: u8 = 3;
/// PX4's AUTO sub mode RTL.
pub const PX4_SUB_RTL: u8 = 5;

/// A flight mode of the simulated autopilot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// The pilot's: the vehicle holds its course (turn rate 0).
    Manual,
    /// Loiter: a steady left turn at half the turn-rate limit.
    Hold,
    /// Return: steer towards home, then loiter there.
    Return,
    /// Follow the companion's setpoints.
    Offboard,
}

impl Mode {
    /// PX4's `custom_mode` of this mode.
    pub fn custom_mode(self) -> u32 {
        let (main, sub) = match self {
            Mode::Manual => (PX4_MAIN_MANUAL, 0),
            Mode::Hold => (PX4_MAIN_AUTO, PX4_SUB_LOITER),
            Mode::Return => (PX4_MAIN_AUTO, PX4_SUB_RTL),
            Mode::Offboard => (PX4_MAIN_OFFBOARD, 0),
        };
        ((main as u32) << 16) | ((sub as u32) << 24)
    }

    /// The mode of PX4's main and sub mode (as `MAV_CMD_DO_SET_MODE` carries them in its
    /// parameters 2 and 3), if the simulated autopilot has it.
    pub fn from_px4(main: f32, sub: f32) -> Option<Mode> {
        match (main, sub) {
            (m, _) if m == PX4_MAIN_MANUAL as f32 => Some(Mode::Manual),
            (m, _) if m == PX4_MAIN_OFFBOARD as f32 => Some(Mode::Offboard),
            (m, s) if m == PX4_MAIN_AUTO as f32 && s == PX4_SUB_LOITER as f32 => Some(Mode::Hold),
            (m, s) if m == PX4_MAIN_AUTO as f32 && s == PX4_SUB_RTL as f32 => Some(Mode::Return),
            _ => None,
        }
    }

    /// The mode of a `HEARTBEAT.custom_mode`.
    pub fn from_custom_mode(c: u32) -> Option<Mode> {
        Mode::from_px4(((c >> 16) & 0xff) as f32, ((c >> 24) & 0xff) as f32)
    }

    /// Its name in logs.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Manual => "MANUAL",
            Mode::Hold => "HOLD",
            Mode::Return => "RETURN",
            Mode::Offboard => "OFFBOARD",
        }
    }
}
