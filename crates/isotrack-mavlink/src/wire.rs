//! What the numbers become on the wire: MAVLink carries times as whole milliseconds (`u32`
//! `time_boot_ms`) and values as `f32`, so the companion's law sees the measurement rounded, and
//! the vehicle the setpoint rounded. Both ends and the in-process mirror
//! ([`crate::mirror`]) use these functions, so a lockstep flight and the mirror do the same
//! arithmetic, bit for bit.
//!
//! Frames: isotrack's turn rate `omega` is positive to the left (counter-clockwise seen from
//! above, x east, y north); MAVLink's body frame is forward-right-down, so a left turn is a
//! negative roll (left wing down) and a negative body yaw rate.

use isotrack_core::Measurement;
use isotrack_scenario::Scenario;

/// Gravity in the coordinated-turn relation, m/s^2: 9.8, the `g` of the simulated Aerosonde (Beard & McLain 2012), so that the relation is the airframe's own.
pub const G_MPS2: f64 = 9.8;

/// The bank limit of the fixed-wing setpoints, rad: 40 deg, the roll loop's limit of the
/// simulated autopilot (Beard & McLain 2012, Sec. 6.5).
pub const BANK_LIMIT_RAD: f64 = 40.0 * std::f64::consts::PI / 180.0;

/// The name of the `NAMED_VALUE_FLOAT` that carries the measurement (`--sensor` default).
pub const MEASUREMENT_NAME: &str = "ISO_S";

/// Milliseconds since boot of a time in seconds, as `time_boot_ms` carries it: rounded to the
/// nearest millisecond; `None` past `u32::MAX` ms (49.7 days) or for a negative or non-finite
/// time.
pub fn time_ms(t_s: f64) -> Option<u32> {
    let ms = (t_s * 1000.0).round();
    (ms.is_finite() && (0.0..=u32::MAX as f64).contains(&ms)).then_some(ms as u32)
}

/// The largest forward step, ms, across the wrap of `time_boot_ms` (2^32 ms, 49.7 days after
/// boot) read as the clock wrapping rather than jumping back: 60 s, the largest step of a
/// measurement's clock `isotrack fly` takes as no fault (`fly::MAX_MEASUREMENT_STEP_S`).
pub const MAX_WRAP_STEP_MS: u32 = 60_000;

/// Whether `to` follows `from` on `time_boot_ms`'s clock across its wrap: `to < from`, and
/// `(to - from) mod 2^32 <= MAX_WRAP_STEP_MS` (the clock passed `u32::MAX` and went on from
/// 0: `u32::MAX - 500` then `499` is a step of 1000 ms forward).
pub fn wrapped_forward(from: u32, to: u32) -> bool {
    to < from && to.wrapping_sub(from) <= MAX_WRAP_STEP_MS
}

/// `ms` (a `time_boot_ms`, which wraps at 2^32 ms) unwrapped next to `near` (an unwrapped
/// time, ms): of `ms + k 2^32`, `k >= 0`, the one nearest `near`, so that a step across a wrap
/// is a small step (`unwrap_ms(2^32 - 500, 499) = 2^32 + 499`), and a step of less than 2^31 ms
/// either way is the step it was.
pub fn unwrap_ms(near: u64, ms: u32) -> u64 {
    const TURN: u64 = 1 << 32;
    let c = (near & !(TURN - 1)) | ms as u64;
    [c.checked_sub(TURN), Some(c), c.checked_add(TURN)]
        .into_iter()
        .flatten()
        .min_by_key(|u| u.abs_diff(near))
        .unwrap_or(c)
}

/// The `time_boot_ms` of an unwrapped time, ms: modulo 2^32.
pub fn wire_ms(unwrapped_ms: u64) -> u32 {
    (unwrapped_ms & 0xFFFF_FFFF) as u32
}

/// Seconds of an unwrapped time, ms ([`unwrap_ms`]).
pub fn unwrapped_s(ms: u64) -> f64 {
    ms as f64 / 1000.0
}

/// Seconds of a `time_boot_ms`.
pub fn time_s(ms: u32) -> f64 {
    ms as f64 / 1000.0
}

/// A measurement as the companion receives it over MAVLink: the time to the millisecond, the
/// value to `f32` (a value outside `f32`'s range becomes infinite, as `f32` casts do).
pub fn on_wire(m: Measurement) -> Measurement {
    Measurement {
        t_s: time_s(time_ms(m.t_s).unwrap_or(u32::MAX)),
        value: m.value as f32 as f64,
    }
}

/// The coordinated-turn roll of a turn rate: `phi = -atan(omega V / g)` (Beard & McLain 2012,
/// eq. (9.14); minus: a left turn banks left, negative in MAVLink's frame), within
/// [`BANK_LIMIT_RAD`], rad.
pub fn roll_of_turn_rate(omega_radps: f64, airspeed_mps: f64) -> f64 {
    (-(omega_radps * airspeed_mps / G_MPS2).atan()).clamp(-BANK_LIMIT_RAD, BANK_LIMIT_RAD)
}

/// The turn rate of a coordinated turn at roll `phi`: `omega = -g tan(phi) / V`, rad/s (the
/// inverse of [`roll_of_turn_rate`] inside the bank limit; `phi` is clamped to it first).
pub fn turn_rate_of_roll(roll_rad: f64, airspeed_mps: f64) -> f64 {
    -G_MPS2 * roll_rad.clamp(-BANK_LIMIT_RAD, BANK_LIMIT_RAD).tan() / airspeed_mps
}

/// The attitude quaternion `[w, x, y, z]` (body to NED) of a roll with zero pitch and yaw, as
/// `SET_ATTITUDE_TARGET` carries it (`f32`).
pub fn quaternion_of_roll(roll_rad: f64) -> [f32; 4] {
    let h = 0.5 * roll_rad;
    [h.cos() as f32, h.sin() as f32, 0.0, 0.0]
}

/// The roll of an attitude quaternion `[w, x, y, z]`, rad:
/// `atan2(2(w x + y z), 1 - 2(x^2 + y^2))` (the ZYX Euler roll). `None` for a quaternion that is
/// not finite or not of unit norm within 1 % (a corrupt or hostile setpoint moves nothing).
pub fn roll_of_quaternion(q: [f32; 4]) -> Option<f64> {
    let [w, x, y, z] = q.map(f64::from);
    let n2 = w * w + x * x + y * y + z * z;
    if !n2.is_finite() || !(0.98..=1.02).contains(&n2) {
        return None;
    }
    Some((2.0 * (w * x + y * z)).atan2(1.0 - 2.0 * (x * x + y * y)))
}

/// The body yaw rate (MAVLink: positive clockwise seen from above) of a turn rate, as `f32`.
pub fn yaw_rate_of_turn_rate(omega_radps: f64) -> f32 {
    (-omega_radps) as f32
}

/// The turn rate of a body yaw rate; `None` if it is not finite.
pub fn turn_rate_of_yaw_rate(yaw_rate_radps: f32) -> Option<f64> {
    yaw_rate_radps
        .is_finite()
        .then_some(-(yaw_rate_radps as f64))
}

/// The turn rate a fixed-wing vehicle flies for the companion's command `omega`: through the
/// roll setpoint on the wire (`f32` quaternion) and back.
pub fn fixed_wing_round_trip(omega_radps: f64, airspeed_mps: f64) -> f64 {
    let q = quaternion_of_roll(roll_of_turn_rate(omega_radps, airspeed_mps));
    roll_of_quaternion(q).map_or(0.0, |r| turn_rate_of_roll(r, airspeed_mps))
}

/// The turn rate a ground vehicle flies for the companion's command `omega`: through the `f32`
/// yaw rate and back.
pub fn ground_round_trip(omega_radps: f64) -> f64 {
    turn_rate_of_yaw_rate(yaw_rate_of_turn_rate(omega_radps)).unwrap_or(0.0)
}

/// The length of a MAVLink 2 frame's start byte and header (unsigned, 8-bit system ids), bytes.
const V2_HEADER_LEN: usize = 10;

/// A MAVLink 2 `frame` (as `mavlink::write_v2_msg` writes it: unsigned, trailing zeros of its
/// payload truncated) with the bytes of the message's extension fields appended: the payload
/// padded with zeros to its `base_len` bytes, then `extensions`, its trailing zeros truncated
/// again (at least one byte kept), the length byte set and the checksum (CRC-16/MCRF4XX of the
/// header after the start byte and the payload, then `extra_crc`, the message's CRC_EXTRA)
/// computed again (<https://mavlink.io/en/guide/serialization.html>). A frame that is not
/// such a MAVLink 2 frame comes back unchanged.
pub fn extend_v2_frame(frame: &[u8], extra_crc: u8, base_len: usize, extensions: &[u8]) -> Vec<u8> {
    let unsigned_v2 = frame.len() >= V2_HEADER_LEN + 2 && frame[0] == 0xFD && frame[2] == 0;
    let len = frame.get(1).map_or(0, |l| *l as usize);
    if !unsigned_v2 || frame.len() != V2_HEADER_LEN + len + 2 || base_len + extensions.len() > 255 {
        return frame.to_vec();
    }
    let mut payload = frame[V2_HEADER_LEN..V2_HEADER_LEN + len].to_vec();
    payload.resize(base_len.max(len), 0);
    payload.extend_from_slice(extensions);
    while payload.len() > 1 && payload.last() == Some(&0) {
        payload.pop();
    }
    let mut out = frame[..V2_HEADER_LEN].to_vec();
    out[1] = payload.len() as u8;
    out.extend_from_slice(&payload);
    let crc = mavlink::calculate_crc(&out[1..], extra_crc);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// The largest magnitude of a measurement's value, in the field's units: a value beyond it
/// (as a non-finite one) is no measurement, dropped and counted (`measurements_invalid`).
/// No sensor reads 10^12 of its unit (ppm, Pa, K, mg/m^3); within it, the error's squares
/// summed over any flight stay far from f64's overflow (the metrics), the trace stays within
/// the +-10^100 `isotrack plot` shows, and one rule holds for both paths (MAVLink's f32
/// carries up to 3.4e38, a UDP line any f64).
pub const MAX_MEASUREMENT_ABS: f64 = 1e12;

/// Whether `v` is a measurement's value: finite and within [`MAX_MEASUREMENT_ABS`].
pub fn plausible_value(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_MEASUREMENT_ABS
}

/// Refuses a scenario whose `controller.level` is beyond [`MAX_MEASUREMENT_ABS`]: every
/// measurement at the level would be dropped as implausible, and the flight could only end
/// `sensor_lost` (ver33-5). `fly` and `sitl` refuse it before anything is opened.
pub fn check_level(scenario: &Scenario) -> Result<(), String> {
    let level = scenario.level();
    if plausible_value(level) {
        return Ok(());
    }
    Err(format!(
        "controller.level = {}: beyond the +-{MAX_MEASUREMENT_ABS:e} a measurement may be over MAVLink or --sensor lines (fly drops every measurement beyond it as implausible, so no measurement at the level could be flown): scale the field and the level down",
        isotrack_core::numtext::Echo(level)
    ))
}

/// Checks that a scenario's times fit MAVLink's millisecond clock: sensor samples at least 1 ms
/// apart (else two samples share a `time_boot_ms`) and a run shorter than `u32::MAX` ms.
pub fn check_wire_times(s: &Scenario) -> Result<(), String> {
    let rate = s.spec().sensor.rate_hz;
    if rate > 1000.0 {
        return Err(format!(
            "sensor.rate_hz = {rate}: MAVLink stamps samples to the millisecond, so at most 1000 Hz"
        ));
    }
    let d = s.spec().sim.duration_s;
    if time_ms(d).is_none() {
        return Err(format!(
            "sim.duration_s = {d}: longer than MAVLink's time_boot_ms counts ({} s)",
            u32::MAX as f64 / 1000.0
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 30 m/s aircraft turning at 0.2741 rad/s banks 40 deg: tan(40 deg) = 0.8391 =
    /// 0.2741 * 30 / 9.8. Left turn (omega > 0) = negative roll.
    #[test]
    fn coordinated_turn_at_the_bank_limit() {
        let w = 9.8 * 40f64.to_radians().tan() / 30.0;
        assert!((w - 0.274_1).abs() < 1e-4);
        assert!((roll_of_turn_rate(w, 30.0) + 40f64.to_radians()).abs() < 1e-12);
        assert_eq!(roll_of_turn_rate(10.0, 30.0), -BANK_LIMIT_RAD);
        assert!((turn_rate_of_roll(-40f64.to_radians(), 30.0) - w).abs() < 1e-12);
        // The round trip through f32 keeps 6-7 digits.
        let back = fixed_wing_round_trip(0.1, 30.0);
        assert!((back - 0.1).abs() < 1e-6, "{back}");
        assert_eq!(ground_round_trip(0.25), 0.25);
    }

    /// A quaternion of a 30 deg roll: [cos 15 deg, sin 15 deg, 0, 0].
    #[test]
    fn quaternions() {
        let q = quaternion_of_roll(30f64.to_radians());
        assert!((q[0] as f64 - 15f64.to_radians().cos()).abs() < 1e-7);
        let r = roll_of_quaternion(q).unwrap();
        assert!((r - 30f64.to_radians()).abs() < 1e-6);
        assert_eq!(roll_of_quaternion([f32::NAN, 0.0, 0.0, 0.0]), None);
        assert_eq!(roll_of_quaternion([0.0; 4]), None);
        assert_eq!(roll_of_quaternion([2.0, 0.0, 0.0, 0.0]), None);
        assert_eq!(turn_rate_of_yaw_rate(f32::INFINITY), None);
    }

    /// Unwrapping: 2^32 - 500 then 499 is 1000 ms later; a late 2^32 - 200 after that is
    /// 700 ms earlier; a step back of 50 000 s stays one; the wire value is modulo 2^32.
    #[test]
    fn the_clock_unwraps() {
        let t = 1u64 << 32;
        assert_eq!(unwrap_ms(t - 500, 499), t + 499);
        assert_eq!(unwrap_ms(t + 499, u32::MAX - 199), t - 200);
        assert_eq!(unwrap_ms(t + 499, 1499), t + 1499);
        assert_eq!(unwrap_ms(50_000_000, 1000), 1000);
        assert_eq!(unwrap_ms(0, 4_000_000_000), 4_000_000_000);
        assert_eq!(wire_ms(t + 499), 499);
        assert!(wrapped_forward(u32::MAX - 500, 499));
        assert!(!wrapped_forward(499, u32::MAX - 500));
        assert!(!wrapped_forward(u32::MAX - 500, 70_000));
    }

    /// Times go to the nearest millisecond; beyond u32 they are refused.
    #[test]
    fn times() {
        assert_eq!(time_ms(0.3), Some(300));
        assert_eq!(time_ms(1.0004), Some(1000));
        assert_eq!(time_ms(-1.0), None);
        assert_eq!(time_ms(5e6), None);
        let m = on_wire(Measurement {
            t_s: 0.1 * 3.0,
            value: 0.1,
        });
        assert_eq!(m.t_s, 0.3);
        assert_eq!(m.value, 0.1f32 as f64);
    }

    /// A `COMMAND_ACK` (command 400, result ACCEPTED = 0: the crate truncates the result
    /// byte) extended with its target (system 245, component 190): the payload is the
    /// little-endian command, the result, `progress` and `result_param2` zero, then the
    /// target, 10 bytes; the frame passes the `mavlink` crate's own checksum check on reading,
    /// and reads back as the same acknowledgement.
    #[test]
    fn an_extended_frame_carries_its_extensions_and_a_valid_checksum() {
        use mavlink::dialects::common::*;
        use mavlink::MessageData;
        let ack = MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            result: MavResult::MAV_RESULT_ACCEPTED,
        });
        let header = mavlink::MavHeader {
            system_id: 1,
            component_id: 1,
            sequence: 7,
        };
        let mut frame = Vec::new();
        mavlink::write_v2_msg(&mut frame, header, &ack).unwrap();
        assert_eq!(frame[1], 2, "the crate truncates the zero result");
        let out = extend_v2_frame(
            &frame,
            COMMAND_ACK_DATA::EXTRA_CRC,
            3,
            &[0, 0, 0, 0, 0, 245, 190],
        );
        assert_eq!(out[1], 10);
        assert_eq!(&out[10..20], &[0x90, 0x01, 0, 0, 0, 0, 0, 0, 245, 190]);
        assert_eq!(&out[..10], {
            let mut h = frame[..10].to_vec();
            h[1] = 10;
            h
        });
        let read = |bytes: &[u8]| {
            mavlink::MavlinkReader::new(bytes)
                .read_any_message::<MavMessage>()
                .ok()
        };
        let (h, back) = read(&out).expect("a valid frame");
        assert_eq!((h.system_id, h.component_id, h.sequence), (1, 1, 7));
        assert_eq!(back, ack);
        // The reader checks the checksum: the same bytes with the old one do not read.
        let mut stale = out.clone();
        let n = stale.len();
        stale[n - 2..].copy_from_slice(&frame[frame.len() - 2..]);
        assert!(read(&stale).is_none());
        // A zero target truncates back to the crate's own frame.
        let plain = extend_v2_frame(&frame, COMMAND_ACK_DATA::EXTRA_CRC, 3, &[0; 7]);
        assert_eq!(plain, frame);
    }
}
