//! The flight modes `isotrack fly` commands and recognises, per autopilot: PX4 and ArduPilot
//! number their modes differently, and ArduPilot's numbers differ between its firmwares
//! (Copter, Plane, Rover), so the same `custom_mode` 4 is PX4's AUTO, ArduCopter's GUIDED,
//! ArduPlane's ACRO and ArduRover's HOLD. The table is picked from the vehicle's `HEARTBEAT`
//! (`autopilot`, then `type`), never assumed.
//!
//! Sources: PX4's `px4_custom_mode.h` (`custom_mode = main << 16 | sub << 24`; main 4 AUTO with
//! sub 3 LOITER and 5 RTL, main 6 OFFBOARD), ArduPilot's `mode.h` of ArduCopter (GUIDED 4,
//! LOITER 5, RTL 6), ArduPlane (RTL 11, LOITER 12, GUIDED 15) and Rover (HOLD 4, LOITER 5,
//! RTL 11, GUIDED 15). `MAV_CMD_DO_SET_MODE` carries `param1 = MAV_MODE_FLAG_CUSTOM_MODE_ENABLED`
//! (1) and the custom mode: PX4's main and sub mode in `param2` and `param3`, ArduPilot's number
//! in `param2`.

use mavlink::dialects::common::{MavAutopilot, MavType};

/// A mode the companion commands or waits for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlyMode {
    /// The mode that follows the companion's setpoints: PX4 OFFBOARD, ArduPilot GUIDED.
    Offboard,
    /// Hold where it is: PX4 AUTO.LOITER (PX4's Hold), ArduCopter LOITER, ArduPlane LOITER (a
    /// plane cannot stop: it circles), ArduRover HOLD.
    Hold,
    /// Circle or hover about where it is: PX4 AUTO.LOITER, ArduCopter LOITER, ArduPlane LOITER,
    /// ArduRover LOITER.
    Loiter,
    /// Return home: PX4 AUTO.RTL, ArduPilot RTL.
    Return,
}

/// Whose mode numbers the vehicle speaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Firmware {
    /// PX4 (and every autopilot that is not ArduPilot: isotrack's `sitl`, MAVSDK's server).
    Px4,
    /// ArduPilot's multirotors and helicopters (ArduCopter).
    ArduCopter,
    /// ArduPilot's fixed wings and VTOLs (ArduPlane, QuadPlane).
    ArduPlane,
    /// ArduPilot's ground vehicles and boats (Rover).
    ArduRover,
    /// ArduPilot on a vehicle type whose table is not known here (a submarine, a blimp, ...):
    /// no mode is commanded.
    ArduOther,
}

/// PX4's custom main mode AUTO.
const PX4_AUTO: u32 = 4;
/// PX4's custom main mode OFFBOARD.
const PX4_OFFBOARD: u32 = 6;
/// PX4's AUTO sub mode LOITER.
const PX4_LOITER: u32 = 3;
/// PX4's AUTO sub mode RTL.
const PX4_RTL: u32 = 5;
/// PX4's AUTO sub mode LAND.
const PX4_LAND: u32 = 6;
/// ArduCopter's LAND.
const ARDUCOPTER_LAND: u32 = 9;

/// ArduCopter's modes, number and name, as its `mode.h` lists them.
const ARDUCOPTER_MODES: &[(u32, &str)] = &[
    (0, "STABILIZE"),
    (1, "ACRO"),
    (2, "ALT_HOLD"),
    (3, "AUTO"),
    (4, "GUIDED"),
    (5, "LOITER"),
    (6, "RTL"),
    (7, "CIRCLE"),
    (9, "LAND"),
    (11, "DRIFT"),
    (13, "SPORT"),
    (14, "FLIP"),
    (15, "AUTOTUNE"),
    (16, "POSHOLD"),
    (17, "BRAKE"),
    (18, "THROW"),
    (19, "AVOID_ADSB"),
    (20, "GUIDED_NOGPS"),
    (21, "SMART_RTL"),
    (22, "FLOWHOLD"),
    (23, "FOLLOW"),
    (24, "ZIGZAG"),
    (25, "SYSTEMID"),
    (26, "AUTOROTATE"),
    (27, "AUTO_RTL"),
    (28, "TURTLE"),
];

/// ArduPlane's modes, number and name, as its `mode.h` lists them.
const ARDUPLANE_MODES: &[(u32, &str)] = &[
    (0, "MANUAL"),
    (1, "CIRCLE"),
    (2, "STABILIZE"),
    (3, "TRAINING"),
    (4, "ACRO"),
    (5, "FLY_BY_WIRE_A"),
    (6, "FLY_BY_WIRE_B"),
    (7, "CRUISE"),
    (8, "AUTOTUNE"),
    (10, "AUTO"),
    (11, "RTL"),
    (12, "LOITER"),
    (13, "TAKEOFF"),
    (14, "AVOID_ADSB"),
    (15, "GUIDED"),
    (16, "INITIALISING"),
    (17, "QSTABILIZE"),
    (18, "QHOVER"),
    (19, "QLOITER"),
    (20, "QLAND"),
    (21, "QRTL"),
    (22, "QAUTOTUNE"),
    (23, "QACRO"),
    (24, "THERMAL"),
    (25, "LOITER_ALT_QLAND"),
    (26, "AUTOLAND"),
];

/// Rover's modes, number and name, as its `mode.h` lists them.
const ARDUROVER_MODES: &[(u32, &str)] = &[
    (0, "MANUAL"),
    (1, "ACRO"),
    (3, "STEERING"),
    (4, "HOLD"),
    (5, "LOITER"),
    (6, "FOLLOW"),
    (7, "SIMPLE"),
    (8, "DOCK"),
    (9, "CIRCLE"),
    (10, "AUTO"),
    (11, "RTL"),
    (12, "SMART_RTL"),
    (15, "GUIDED"),
    (16, "INITIALISING"),
];

impl Firmware {
    /// The firmware of a vehicle's heartbeat: `MAV_AUTOPILOT_ARDUPILOTMEGA` picks ArduPilot's
    /// table by `type`; any other autopilot speaks PX4's.
    pub fn of(autopilot: MavAutopilot, mavtype: MavType) -> Self {
        use MavType::*;
        if autopilot != MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA {
            return Firmware::Px4;
        }
        match mavtype {
            MAV_TYPE_QUADROTOR
            | MAV_TYPE_COAXIAL
            | MAV_TYPE_HELICOPTER
            | MAV_TYPE_HEXAROTOR
            | MAV_TYPE_OCTOROTOR
            | MAV_TYPE_TRICOPTER
            | MAV_TYPE_DODECAROTOR
            | MAV_TYPE_DECAROTOR
            | MAV_TYPE_GENERIC_MULTIROTOR => Firmware::ArduCopter,
            MAV_TYPE_FIXED_WING
            | MAV_TYPE_VTOL_TAILSITTER_DUOROTOR
            | MAV_TYPE_VTOL_TAILSITTER_QUADROTOR
            | MAV_TYPE_VTOL_TILTROTOR
            | MAV_TYPE_VTOL_FIXEDROTOR
            | MAV_TYPE_VTOL_TAILSITTER
            | MAV_TYPE_VTOL_TILTWING => Firmware::ArduPlane,
            MAV_TYPE_GROUND_ROVER | MAV_TYPE_SURFACE_BOAT => Firmware::ArduRover,
            _ => Firmware::ArduOther,
        }
    }

    /// Its name in logs.
    pub fn name(self) -> &'static str {
        match self {
            Firmware::Px4 => "PX4",
            Firmware::ArduCopter => "ArduCopter",
            Firmware::ArduPlane => "ArduPlane",
            Firmware::ArduRover => "ArduRover",
            Firmware::ArduOther => "ArduPilot (unknown vehicle type)",
        }
    }

    /// ArduPilot's custom mode number of `m`, if this is ArduPilot and has it.
    fn ardupilot_number(self, m: FlyMode) -> Option<u32> {
        use FlyMode::*;
        match (self, m) {
            (Firmware::ArduCopter, Offboard) => Some(4),
            (Firmware::ArduCopter, Hold | Loiter) => Some(5),
            (Firmware::ArduCopter, Return) => Some(6),
            (Firmware::ArduPlane, Offboard) => Some(15),
            (Firmware::ArduPlane, Hold | Loiter) => Some(12),
            (Firmware::ArduPlane, Return) => Some(11),
            (Firmware::ArduRover, Offboard) => Some(15),
            (Firmware::ArduRover, Hold) => Some(4),
            (Firmware::ArduRover, Loiter) => Some(5),
            (Firmware::ArduRover, Return) => Some(11),
            _ => None,
        }
    }

    /// PX4's main and sub mode of `m`.
    fn px4(m: FlyMode) -> (u32, u32) {
        match m {
            FlyMode::Offboard => (PX4_OFFBOARD, 0),
            FlyMode::Hold | FlyMode::Loiter => (PX4_AUTO, PX4_LOITER),
            FlyMode::Return => (PX4_AUTO, PX4_RTL),
        }
    }

    /// `MAV_CMD_DO_SET_MODE`'s parameters 1 to 3 for `m`: `[1, main, sub]` (PX4) or
    /// `[1, number, 0]` (ArduPilot); `None` where the table has no such mode.
    pub fn set_mode_params(self, m: FlyMode) -> Option<[f32; 3]> {
        if self == Firmware::Px4 {
            let (main, sub) = Firmware::px4(m);
            return Some([1.0, main as f32, sub as f32]);
        }
        self.ardupilot_number(m).map(|n| [1.0, n as f32, 0.0])
    }

    /// Whether a heartbeat's `custom_mode` is `m` (PX4: OFFBOARD by its main mode alone, the
    /// AUTO modes by main and sub mode; ArduPilot: the number).
    pub fn is_in(self, custom_mode: u32, m: FlyMode) -> bool {
        if self == Firmware::Px4 {
            let (main, sub) = ((custom_mode >> 16) & 0xff, (custom_mode >> 24) & 0xff);
            let (want_main, want_sub) = Firmware::px4(m);
            return main == want_main && (m == FlyMode::Offboard || sub == want_sub);
        }
        self.ardupilot_number(m) == Some(custom_mode)
    }

    /// The safe mode a heartbeat's `custom_mode` is, if it is one: the table's hold, loiter
    /// and return (whichever the failsafe asked for), and the landings PX4 AUTO.LAND (main 4,
    /// sub 6) and ArduCopter LAND (9). A failsafe that asked for one and sees the vehicle in
    /// another (asked RTL, it loiters: its own failsafe, or a pilot's choice) is over: the
    /// vehicle is out of the companion's setpoints and somewhere safe, and insisting would
    /// fight it. Sources as for the table: PX4's `px4_custom_mode.h` (AUTO sub mode LAND 6),
    /// ArduCopter's `mode.h` (LAND 9).
    pub fn safe_mode_name(self, custom_mode: u32) -> Option<&'static str> {
        for m in [FlyMode::Hold, FlyMode::Loiter, FlyMode::Return] {
            if self.is_in(custom_mode, m) {
                return Some(self.name_of(m));
            }
        }
        let land = match self {
            Firmware::Px4 => {
                (custom_mode >> 16) & 0xff == PX4_AUTO && (custom_mode >> 24) & 0xff == PX4_LAND
            }
            Firmware::ArduCopter => custom_mode == ARDUCOPTER_LAND,
            _ => false,
        };
        land.then_some("LAND")
    }

    /// The return or landing a heartbeat's `custom_mode` is, if it is one (the autopilot's own
    /// failsafe, or its pilot's choice, bringing the vehicle home or down): PX4 AUTO.RTL,
    /// AUTO.LAND and AUTO.PRECLAND (main 4, sub 5, 6, 9); ArduCopter RTL 6, LAND 9,
    /// SMART_RTL 21; ArduPlane RTL 11, QLAND 20, QRTL 21; Rover RTL 11, SMART_RTL 12. Sources
    /// as for the table (PX4's `px4_custom_mode.h`, ArduPilot's `mode.h` of each firmware).
    pub fn returning_or_landing(self, custom_mode: u32) -> Option<&'static str> {
        match self {
            Firmware::Px4 => {
                let (main, sub) = ((custom_mode >> 16) & 0xff, (custom_mode >> 24) & 0xff);
                match (main, sub) {
                    (PX4_AUTO, PX4_RTL) => Some("AUTO.RTL"),
                    (PX4_AUTO, PX4_LAND) => Some("AUTO.LAND"),
                    (PX4_AUTO, 9) => Some("AUTO.PRECLAND"),
                    _ => None,
                }
            }
            Firmware::ArduCopter => match custom_mode {
                6 => Some("RTL"),
                ARDUCOPTER_LAND => Some("LAND"),
                21 => Some("SMART_RTL"),
                _ => None,
            },
            Firmware::ArduPlane => match custom_mode {
                11 => Some("RTL"),
                20 => Some("QLAND"),
                21 => Some("QRTL"),
                _ => None,
            },
            Firmware::ArduRover => match custom_mode {
                11 => Some("RTL"),
                12 => Some("SMART_RTL"),
                _ => None,
            },
            Firmware::ArduOther => None,
        }
    }

    /// Whether `--take-control` takes an armed vehicle from `custom_mode`: only a mode its pilot
    /// flies or holds in, never a take-off, a landing or return, traffic avoidance, a mission or
    /// a mode not known here (an allow-list, att33d-1). PX4 (`px4_custom_mode.h`): MANUAL,
    /// ALTCTL, POSCTL, ACRO, STABILIZED, RATTITUDE (each with sub-mode 0 only: not POSCTL.ORBIT
    /// (3, 1) nor POSCTL.SLOW (3, 2)), AUTO.LOITER. ArduPlane (`mode.h`): MANUAL,
    /// CIRCLE, STABILIZE, TRAINING, ACRO, FLY_BY_WIRE_A, FLY_BY_WIRE_B, CRUISE, LOITER.
    /// Rover: MANUAL, ACRO, STEERING, HOLD, LOITER. ArduCopter: STABILIZE, ACRO, ALT_HOLD,
    /// LOITER, POSHOLD.
    pub fn takeover_allowed(self, custom_mode: u32) -> bool {
        match self {
            Firmware::Px4 => {
                let (main, sub) = ((custom_mode >> 16) & 0xff, (custom_mode >> 24) & 0xff);
                // (main, sub) exactly: a sub-mode outside AUTO is not the pilot's (POSCTL.ORBIT,
                // 3.1, a ground station's automatic circle) or unknown here (ver33b-2).
                (matches!(main, 1 | 2 | 3 | 5 | 7 | 8) && sub == 0)
                    || (main == PX4_AUTO && sub == PX4_LOITER)
            }
            Firmware::ArduPlane => matches!(custom_mode, 0..=7 | 12),
            Firmware::ArduRover => matches!(custom_mode, 0 | 1 | 3 | 4 | 5),
            Firmware::ArduCopter => matches!(custom_mode, 0 | 1 | 2 | 5 | 16),
            Firmware::ArduOther => false,
        }
    }

    /// The name of a heartbeat's `custom_mode` in logs ("OFFBOARD", "GUIDED", "RTL", or the
    /// number).
    pub fn mode_name(self, custom_mode: u32) -> String {
        let named = |m: FlyMode| self.is_in(custom_mode, m).then(|| self.name_of(m));
        // Hold before Loiter: where both are one mode, its name is the hold's.
        [
            FlyMode::Offboard,
            FlyMode::Hold,
            FlyMode::Loiter,
            FlyMode::Return,
        ]
        .into_iter()
        .find_map(named)
        .map(str::to_string)
        .unwrap_or_else(|| match self {
            Firmware::Px4 => px4_mode_name(custom_mode),
            _ => self.ardupilot_mode_name(custom_mode).map_or_else(
                || format!("{} mode {custom_mode}", self.name()),
                str::to_string,
            ),
        })
    }

    /// An ArduPilot mode's name, as the `Mode::Number` enum of its firmware's `mode.h` names it
    /// (ArduCopter, ArduPlane, Rover); `None` for a number not there (or PX4, or ArduPilot on
    /// another vehicle type).
    pub fn ardupilot_mode_name(self, custom_mode: u32) -> Option<&'static str> {
        let table: &[(u32, &str)] = match self {
            Firmware::ArduCopter => ARDUCOPTER_MODES,
            Firmware::ArduPlane => ARDUPLANE_MODES,
            Firmware::ArduRover => ARDUROVER_MODES,
            Firmware::Px4 | Firmware::ArduOther => &[],
        };
        table
            .iter()
            .find(|(n, _)| *n == custom_mode)
            .map(|(_, name)| *name)
    }

    /// The name of `m` in this firmware ("OFFBOARD" / "GUIDED", "HOLD", ...).
    pub fn name_of(self, m: FlyMode) -> &'static str {
        match (self, m) {
            (Firmware::Px4, FlyMode::Offboard) => "OFFBOARD",
            (_, FlyMode::Offboard) => "GUIDED",
            (Firmware::Px4, FlyMode::Hold) => "HOLD",
            (Firmware::Px4, FlyMode::Loiter) => "LOITER",
            (Firmware::Px4, FlyMode::Return) => "RETURN",
            (Firmware::ArduRover, FlyMode::Hold) => "HOLD",
            (_, FlyMode::Hold | FlyMode::Loiter) => "LOITER",
            (_, FlyMode::Return) => "RTL",
        }
    }
}

/// A PX4 `custom_mode`'s name (main mode in bits 16..24, AUTO's sub mode in bits 24..32; PX4's
/// `px4_custom_mode.h`): `MANUAL`, `POSCTL`, `AUTO.MISSION`, ...; an unknown one by its
/// numbers (`PX4 mode 9.0`).
pub fn px4_mode_name(custom_mode: u32) -> String {
    let (main, sub) = ((custom_mode >> 16) & 0xff, (custom_mode >> 24) & 0xff);
    let name = match main {
        1 => Some("MANUAL"),
        2 => Some("ALTCTL"),
        3 => Some("POSCTL"),
        4 => match sub {
            1 => Some("AUTO.READY"),
            2 => Some("AUTO.TAKEOFF"),
            3 => Some("AUTO.LOITER"),
            4 => Some("AUTO.MISSION"),
            5 => Some("AUTO.RTL"),
            6 => Some("AUTO.LAND"),
            8 => Some("AUTO.FOLLOW_TARGET"),
            9 => Some("AUTO.PRECLAND"),
            _ => None,
        },
        5 => Some("ACRO"),
        6 => Some("OFFBOARD"),
        7 => Some("STABILIZED"),
        8 => Some("RATTITUDE"),
        _ => None,
    };
    match (name, custom_mode) {
        (Some(n), _) => n.to_string(),
        // 0 is no mode (MAVSDK's autopilot server before a mode is set).
        (None, 0) => "custom mode 0 (none)".into(),
        (None, _) => format!("PX4 mode {main}.{sub}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use FlyMode::*;

    /// ArduPilot's tables (mode.h of ArduCopter, ArduPlane, Rover) and PX4's encoding.
    #[test]
    fn tables() {
        let ap = MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA;
        let copter = Firmware::of(ap, MavType::MAV_TYPE_QUADROTOR);
        let plane = Firmware::of(ap, MavType::MAV_TYPE_FIXED_WING);
        let rover = Firmware::of(ap, MavType::MAV_TYPE_GROUND_ROVER);
        let px4 = Firmware::of(
            MavAutopilot::MAV_AUTOPILOT_PX4,
            MavType::MAV_TYPE_FIXED_WING,
        );
        assert_eq!(
            (copter, plane, rover, px4),
            (
                Firmware::ArduCopter,
                Firmware::ArduPlane,
                Firmware::ArduRover,
                Firmware::Px4
            )
        );
        let p2 = |f: Firmware, m| f.set_mode_params(m).map(|p| p[1]);
        assert_eq!(
            [Offboard, Hold, Loiter, Return].map(|m| p2(copter, m)),
            [Some(4.0), Some(5.0), Some(5.0), Some(6.0)]
        );
        assert_eq!(
            [Offboard, Hold, Loiter, Return].map(|m| p2(plane, m)),
            [Some(15.0), Some(12.0), Some(12.0), Some(11.0)]
        );
        assert_eq!(
            [Offboard, Hold, Loiter, Return].map(|m| p2(rover, m)),
            [Some(15.0), Some(4.0), Some(5.0), Some(11.0)]
        );
        assert_eq!(px4.set_mode_params(Return), Some([1.0, 4.0, 5.0]));
        assert_eq!(px4.set_mode_params(Offboard), Some([1.0, 6.0, 0.0]));
        assert!(px4.is_in((4 << 16) | (3 << 24), Hold));
        assert!(!px4.is_in((4 << 16) | (5 << 24), Hold));
        assert!(px4.is_in(6 << 16, Offboard));
        // ArduCopter's 4 is GUIDED, ArduPlane's 4 ACRO: never taken for a hold or OFFBOARD.
        assert!(copter.is_in(4, Offboard) && !plane.is_in(4, Offboard) && !plane.is_in(4, Hold));
        // att33c item 7: every mode of mode.h by its name, an unknown number as a number.
        assert_eq!(plane.mode_name(6), "FLY_BY_WIRE_B");
        assert_eq!(plane.mode_name(0), "MANUAL");
        assert_eq!(plane.mode_name(99), "ArduPlane mode 99");
        assert_eq!(rover.mode_name(0), "MANUAL");
        assert_eq!(copter.mode_name(16), "POSHOLD");
        assert_eq!(px4.mode_name(0), "custom mode 0 (none)");
        assert_eq!(px4.mode_name(9 << 16), "PX4 mode 9.0");
        assert_eq!(
            Firmware::of(ap, MavType::MAV_TYPE_SUBMARINE).set_mode_params(Hold),
            None
        );
    }

    /// att33d-1: an armed vehicle is taken over only from a pilot's mode: PX4 POSCTL and
    /// AUTO.LOITER yes, AUTO.TAKEOFF (4, 2), (4, 7), AUTO.FOLLOW_TARGET (4, 8), AUTO.VTOL_TAKEOFF
    /// (4, 10), AUTO.MISSION and no mode (0) no; ArduPlane FLY_BY_WIRE_A yes, TAKEOFF 13,
    /// AVOID_ADSB 14, INITIALISING 16, LOITER_ALT_QLAND 25, AUTOLAND 26 no.
    #[test]
    fn take_over_only_from_a_pilots_mode() {
        let px4 = Firmware::Px4;
        assert!(px4.takeover_allowed(3 << 16) && px4.takeover_allowed((4 << 16) | (3 << 24)));
        for sub in [2u32, 4, 7, 8, 10] {
            assert!(!px4.takeover_allowed((4 << 16) | (sub << 24)), "4.{sub}");
        }
        assert!(!px4.takeover_allowed(0) && !px4.takeover_allowed(6 << 16));
        // ver33b-2: outside AUTO the sub-mode must be 0: POSCTL.ORBIT (3, 1), POSCTL.SLOW (3, 2)
        // and a MANUAL with a sub-mode PX4 never sends (1, 5) are refused.
        for (main, sub) in [(3u32, 1u32), (3, 2), (1, 5)] {
            assert!(
                !px4.takeover_allowed((main << 16) | (sub << 24)),
                "{main}.{sub}"
            );
        }
        let plane = Firmware::of(
            MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA,
            MavType::MAV_TYPE_FIXED_WING,
        );
        assert!(plane.takeover_allowed(5) && plane.takeover_allowed(12));
        for m in [13u32, 14, 16, 25, 26, 10, 11, 15] {
            assert!(!plane.takeover_allowed(m), "{m}");
        }
    }

    /// The safe modes that end a failsafe: PX4 AUTO.LOITER (4, 3), AUTO.RTL (4, 5), AUTO.LAND
    /// (4, 6), never OFFBOARD (6) or MANUAL (1); ArduPlane LOITER 12, RTL 11, never its GUIDED
    /// 15 or ACRO 4; ArduCopter LAND 9; Rover HOLD 4.
    #[test]
    fn safe_modes() {
        let ap = MavAutopilot::MAV_AUTOPILOT_ARDUPILOTMEGA;
        let px4 = Firmware::Px4;
        assert_eq!(px4.safe_mode_name((4 << 16) | (3 << 24)), Some("HOLD"));
        assert_eq!(px4.safe_mode_name((4 << 16) | (5 << 24)), Some("RETURN"));
        assert_eq!(px4.safe_mode_name((4 << 16) | (6 << 24)), Some("LAND"));
        assert_eq!(px4.safe_mode_name(6 << 16), None);
        assert_eq!(px4.safe_mode_name(1 << 16), None);
        let plane = Firmware::of(ap, MavType::MAV_TYPE_FIXED_WING);
        assert_eq!(plane.safe_mode_name(12), Some("LOITER"));
        assert_eq!(plane.safe_mode_name(11), Some("RTL"));
        assert_eq!(plane.safe_mode_name(15), None);
        assert_eq!(plane.safe_mode_name(4), None);
        let copter = Firmware::of(ap, MavType::MAV_TYPE_QUADROTOR);
        assert_eq!(copter.safe_mode_name(9), Some("LAND"));
        let rover = Firmware::of(ap, MavType::MAV_TYPE_GROUND_ROVER);
        assert_eq!(rover.safe_mode_name(4), Some("HOLD"));
        assert_eq!(rover.safe_mode_name(15), None);
    }
}
