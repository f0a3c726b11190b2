//! Two senders with one (system, component) id on one link (two PX4s left at the default
//! `MAV_SYS_ID` 1 behind one router): told apart by what MAVLink gives, each sender's frame
//! sequence numbers.
//!
//! A MAVLink sender numbers its frames 0, 1, ..., 255, 0, ... (the header's `seq`, one counter
//! per sender and link). One sender's frames, as received, step forward: by 1, or by more where
//! frames were lost (a radio's loss, frames of another dialect skipped); a frame behind the
//! newest is a late one (a link that reorders), rare. Two senders with the same ids, interleaved,
//! each keep their own counter: every time the frames switch from the sender whose counter is
//! ahead to the one behind, the sequence steps back. Frames behind the newest are counted over
//! the vehicle's last [`SEQUENCE_WINDOW_FRAMES`] frames; [`OUT_OF_SEQUENCE_LIMIT`] of them is
//! two senders (a link that reorders that much is not flown either). A step of 1 to 128 is
//! forward (loss of up to 127 frames), 129 to 255 behind (the header's `seq` is a modulo-256
//! counter "used to detect packet loss": MAVLink 2 packet format, mavlink.io). A frame with the newest's number
//! and another content (two senders whose counters agree) counts as behind; a true duplicate (a
//! link that doubles frames, the same content) does not.
//!
//! Two vehicles far apart show too in their positions: a position farther from the last than
//! [`MAX_GROUND_SPEED_MPS`] covers in the time between them, plus [`POSITION_JUMP_MARGIN_M`],
//! is a jump; one is a reset of the estimator's reference (a GPS glitch), [`POSITION_JUMPS_LIMIT`]
//! within the last [`POSITION_WINDOW`] positions are two vehicles' positions interleaved.

use mavlink::dialects::common::MavMessage;
use std::collections::VecDeque;

/// The frames of the vehicle's ids over which out-of-sequence ones are counted.
pub const SEQUENCE_WINDOW_FRAMES: u64 = 512;

/// Out-of-sequence frames within [`SEQUENCE_WINDOW_FRAMES`] that make two senders: a sender
/// switch per cycle of two interleaved vehicles (every second at least), against a late frame
/// now and then of one vehicle (a reordering link: 12 in 512 is 2.3 % of frames late).
pub const OUT_OF_SEQUENCE_LIMIT: usize = 12;

/// The fastest the bridge's vehicles move over the ground, m/s (360 km/h: a small fixed wing
/// at its top airspeed with a gale behind it; a rover far less).
pub const MAX_GROUND_SPEED_MPS: f64 = 100.0;

/// What a position may move beyond [`MAX_GROUND_SPEED_MPS`] x the time between two, m (the
/// estimator's noise, a GPS fix's step).
pub const POSITION_JUMP_MARGIN_M: f64 = 20.0;

/// Positions over which jumps are counted.
pub const POSITION_WINDOW: u64 = 64;

/// Jumps within [`POSITION_WINDOW`] positions that make two vehicles: a reset is one, a
/// one-frame glitch two (out and back), two glitches four (ver33c-2); two vehicles
/// interleaved jump at every switch.
pub const POSITION_JUMPS_LIMIT: usize = 5;

/// The sequence numbers of the frames of one (system, component), watched for a second sender.
#[derive(Default)]
pub struct SequenceWatch {
    /// The newest frame's sequence number and message.
    last: Option<(u8, MavMessage)>,
    /// Per sequence number, the message of the last frame that carried it: a frame behind the
    /// newest identical to it is a copy the link delivered again (a duplicate), not a second
    /// sender's (ver33c-5).
    by_number: Vec<Option<MavMessage>>,
    /// Duplicates (a frame identical to the last one with its number), not counted.
    pub duplicates: u64,
    window: Window,
    /// Out-of-sequence frames in all.
    pub out_of_sequence: u64,
}

impl SequenceWatch {
    /// A frame numbered `seq` carrying `msg`: whether the window now holds
    /// [`OUT_OF_SEQUENCE_LIMIT`] out-of-sequence frames (two senders).
    pub fn frame(&mut self, seq: u8, msg: &MavMessage) -> bool {
        if self.by_number.is_empty() {
            self.by_number = vec![None; 256];
        }
        // A copy is a frame identical to the last one with its number and not ahead of the
        // newest: a frame one to 128 numbers ahead is a new one even if identical to the frame
        // 256 numbers before it (a vehicle's unchanging heartbeat that falls on the number of
        // its last one: dropped as a copy, its heartbeats would go unheard).
        let ahead = self
            .last
            .as_ref()
            .is_some_and(|(last, _)| (1..=128).contains(&seq.wrapping_sub(*last)));
        let copy = !ahead && self.by_number[seq as usize].as_ref() == Some(msg);
        let behind = match &self.last {
            None => false,
            Some((last, _)) => match seq.wrapping_sub(*last) {
                // The same number, or a number behind: a duplicate if the same frame as the
                // last with that number, else another sender's (or a late frame).
                _ if copy => {
                    self.duplicates += 1;
                    return false;
                }
                0 => true,
                // Forward: the next frame, or some lost between.
                1..=128 => false,
                _ => true,
            },
        };
        self.by_number[seq as usize] = Some(msg.clone());
        self.last = Some((seq, msg.clone()));
        if behind {
            self.out_of_sequence += 1;
        }
        self.window.push(SEQUENCE_WINDOW_FRAMES, behind) >= OUT_OF_SEQUENCE_LIMIT
    }
}

/// Counts of events within a window of the last `window` items (frames, positions).
#[derive(Default)]
struct Window {
    items: u64,
    recent: VecDeque<u64>,
}

impl Window {
    /// One more item, an event or not: how many events the window holds.
    fn push(&mut self, window: u64, event: bool) -> usize {
        self.items += 1;
        while self
            .recent
            .front()
            .is_some_and(|&f| f + window <= self.items)
        {
            self.recent.pop_front();
        }
        if event {
            self.recent.push_back(self.items);
        }
        self.recent.len()
    }
}

/// The vehicle's positions, watched for jumps no airframe makes.
#[derive(Default)]
pub struct PositionWatch {
    /// The last position (x east, y north), m, its time on the vehicle's clock, ms, and when
    /// it came on the companion's, s.
    last: Option<((f64, f64), u32, f64)>,
    jumps: Window,
    /// The last jump: its length, m, and the time it spanned, s.
    pub last_jump: Option<(f64, f64)>,
}

impl PositionWatch {
    /// A position `p`, m, stamped `ms` on the vehicle's clock, arrived at `wall_s` on the
    /// companion's: whether [`POSITION_JUMPS_LIMIT`] jumps are within the window. The time
    /// between two positions is the longer of the two clocks' (a vehicle clock that went back,
    /// another vehicle's, gives none): the bound errs on the side of no jump.
    pub fn position(&mut self, p: (f64, f64), ms: u32, wall_s: f64) -> bool {
        let jump = match self.last {
            None => false,
            Some((q, last_ms, last_wall)) => {
                let clock_s = match ms.wrapping_sub(last_ms) {
                    d if d < 1 << 31 => d as f64 / 1000.0,
                    _ => 0.0,
                };
                let dt_s = clock_s.max(wall_s - last_wall).max(0.0);
                let d = (p.0 - q.0).hypot(p.1 - q.1);
                let jump = d > MAX_GROUND_SPEED_MPS * dt_s + POSITION_JUMP_MARGIN_M;
                if jump {
                    self.last_jump = Some((d, dt_s));
                }
                jump
            }
        };
        self.last = Some((p, ms, wall_s));
        self.jumps.push(POSITION_WINDOW, jump) >= POSITION_JUMPS_LIMIT
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::*;

    fn msg(k: u32) -> MavMessage {
        MavMessage::SYSTEM_TIME(SYSTEM_TIME_DATA {
            time_unix_usec: 0,
            time_boot_ms: k,
        })
    }

    /// A small deterministic generator (a 64-bit LCG, Knuth's MMIX constants).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// Feeds `frames` (sequence, content id); the frame index at which two senders were seen.
    fn first_alarm(frames: &[(u8, u32)]) -> Option<usize> {
        let mut w = SequenceWatch::default();
        frames.iter().position(|&(s, k)| w.frame(s, &msg(k)))
    }

    /// One sender's frames over a link that loses a share `loss` of them, in bursts of up to
    /// `burst`, swaps neighbours with probability `swap` and delays one by up to `late`
    /// places with probability `delay`.
    fn one_sender(
        n: usize,
        loss: f64,
        burst: usize,
        swap: f64,
        delay: f64,
        seed: u64,
    ) -> Vec<(u8, u32)> {
        let mut r = Lcg(seed);
        let mut sent: Vec<(u8, u32)> = Vec::new();
        let mut k = 0u32;
        while sent.len() < n {
            if r.next() < loss {
                k += 1 + (r.next() * burst as f64) as u32;
                continue;
            }
            sent.push((k as u8, k));
            k += 1;
        }
        let mut i = 0;
        while i + 1 < sent.len() {
            if r.next() < swap {
                sent.swap(i, i + 1);
                i += 2;
            } else {
                i += 1;
            }
        }
        let mut i = 0;
        while i + 20 < sent.len() {
            if r.next() < delay {
                let f = sent.remove(i);
                sent.insert(i + 1 + (r.next() * 15.0) as usize, f);
                i += 20;
            } else {
                i += 1;
            }
        }
        sent
    }

    /// Ordinary loss (up to 60 %, in bursts of up to 300 frames: a radio fading), reordering
    /// (0.2 % of neighbours swapped, 0.1 % of frames delayed by up to 15 places) and duplicates
    /// never make two senders.
    #[test]
    fn loss_and_reordering_are_one_sender() {
        for seed in 1..40u64 {
            for (loss, burst) in [(0.0, 1), (0.1, 1), (0.3, 5), (0.6, 3), (0.002, 300)] {
                let f = one_sender(5000, loss, burst, 0.002, 0.001, seed);
                assert_eq!(
                    first_alarm(&f),
                    None,
                    "seed {seed} loss {loss} burst {burst}"
                );
            }
        }
        // ver33c-5: a fifth of the frames delivered again, identical, up to 6 frames late (a
        // mesh radio): duplicates, no second sender.
        let mut r = Lcg(11);
        let mut late: Vec<(u8, u32)> = Vec::new();
        for k in 0..5000u32 {
            late.push((k as u8, k));
            if r.next() < 0.2 {
                let back = (r.next() * 7.0) as u32;
                let j = k.saturating_sub(back);
                late.push((j as u8, j));
            }
        }
        assert_eq!(first_alarm(&late), None);
        // Every frame doubled (a link that duplicates): the same content, no second sender.
        let doubled: Vec<(u8, u32)> = (0..3000u32)
            .flat_map(|k| [(k as u8, k), (k as u8, k)])
            .collect();
        assert_eq!(first_alarm(&doubled), None);
        // The counter's wrap 255 -> 0 is a step forward.
        let wrap: Vec<(u8, u32)> = (250..270u32).map(|k| (k as u8, k)).collect();
        assert_eq!(first_alarm(&wrap), None);
    }

    /// Two senders interleaved, at their own rates and with any offset between their counters
    /// (including none: the same numbers, different contents), are two within a second of
    /// their frames (two 25-frame-a-second vehicles: 50 frames a second).
    #[test]
    fn two_interleaved_senders_are_seen() {
        for offset in [0u32, 1, 2, 10, 64, 127, 128, 129, 200, 255] {
            for (rate_a, rate_b) in [(1.0, 1.0), (1.0, 0.3), (0.4, 1.0), (1.0, 0.1)] {
                let mut r = Lcg(offset as u64 + 7);
                let (mut a, mut b) = (0u32, offset);
                let (mut ta, mut tb) = (0.0f64, 0.0f64);
                let mut f = Vec::new();
                for _ in 0..400 {
                    // The next frame is the sender whose next send time is sooner, with jitter.
                    if ta <= tb {
                        f.push((a as u8, 1_000_000 + a));
                        a += 1;
                        ta += (1.0 + 0.3 * r.next()) / rate_a;
                    } else {
                        f.push((b as u8, 2_000_000 + b));
                        b += 1;
                        tb += (1.0 + 0.3 * r.next()) / rate_b;
                    }
                }
                let at = first_alarm(&f);
                // The slower sender's frames set the pace: LIMIT of its switches.
                let bound = ((OUT_OF_SEQUENCE_LIMIT as f64 + 1.0) * (rate_a + rate_b)
                    / rate_a.min(rate_b)
                    * 1.4) as usize
                    + 10;
                assert!(
                    at.is_some_and(|i| i < bound),
                    "offset {offset} rates {rate_a}/{rate_b}: {at:?} (bound {bound})"
                );
            }
        }
    }

    /// A vehicle at 30 m/s reporting at 10 Hz with 10 m of noise, one reset of 500 m, two
    /// one-frame glitches of 500 m 2 s apart, a burst of positions arriving at once after a 3 s
    /// outage: no two vehicles. Two vehicles 300 m apart interleaved: two, at the fifth switch.
    #[test]
    fn position_jumps() {
        let mut r = Lcg(3);
        let mut w = PositionWatch::default();
        for k in 0..2000u32 {
            let reset = if k > 700 { 500.0 } else { 0.0 };
            let glitch = if k == 300 || k == 320 { 500.0 } else { 0.0 };
            let x = 3.0 * k as f64 + reset + glitch + 10.0 * (r.next() - 0.5);
            // Positions 1000..1030 queued through an outage, delivered within a millisecond.
            let wall = if (1000..1030).contains(&k) {
                100.0
            } else {
                k as f64 * 0.1
            };
            assert!(!w.position((x, 0.0), 100 * k, wall), "{k}");
        }
        let mut w = PositionWatch::default();
        let alarms: Vec<bool> = (0..8u32)
            .map(|k| {
                let p = if k.is_multiple_of(2) {
                    (0.0, 0.0)
                } else {
                    (300.0, 0.0)
                };
                w.position(p, 1000 + 50 * k, 0.05 * k as f64)
            })
            .collect();
        assert_eq!(
            alarms,
            [false, false, false, false, false, true, true, true]
        );
        assert_eq!(w.last_jump.map(|j| j.0), Some(300.0));
    }
}
