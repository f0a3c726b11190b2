//! Spacing laws: how each vehicle of a team sets its speed (docs/TEAMS.md).
//!
//! * `none`: every vehicle at `v0`; the spacing stays as deployed.
//! * `range_balance`: `v_i = sat[v_min, v_max](v0 + k_v (r_i_ahead - r_i_behind))` from the two
//!   ranges to the ring neighbours. Coordinate-free: it uses ranges and neighbour identities
//!   only. The gaps then obey the ring's discrete Laplacian (`isotrack_core::spacing`).
//! * `arc_reference`: the same law on the true arc-length gaps along the isoline (ground truth:
//!   a reference, not coordinate-free, like `gradient_reference`).
//!
//! Which neighbour is ahead: the ring is either fixed at deployment (the listed order is the
//! order along the direction of travel, `ahead(i) = i + 1 mod N`) or found after deployment from
//! ranges and their rates ([`DiscoveryConfig`]): once the team has settled on the isoline at
//! `v0`, each vehicle in turn (its slot fixed by its identity) flies `v0 + dv` for `probe_s` and
//! fits the rate of its range to every vehicle that answers; a vehicle it closes on is ahead of
//! it, one it draws away from is behind (for arc gaps under half the isoline, where a chord grows
//! with the gap). Its neighbour ahead is the nearest vehicle ahead (with none ahead: the farthest
//! behind, across the team's empty stretch), its neighbour behind likewise.

use super::ranging::Range;

/// The spacing law (`team.spacing`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpacingLaw {
    /// All vehicles at the nominal speed.
    None,
    /// `v0 + k_v (r_ahead - r_behind)`, ranges only (coordinate-free).
    RangeBalance {
        /// `k_v`, 1/s.
        gain_per_s: f64,
    },
    /// `v0 + k_v (g_ahead - g_behind)` with the true arc gaps (a reference, not
    /// coordinate-free).
    ArcReference {
        /// `k_v`, 1/s.
        gain_per_s: f64,
    },
}

impl SpacingLaw {
    /// The name in scenario files.
    pub fn name(&self) -> &'static str {
        match self {
            SpacingLaw::None => "none",
            SpacingLaw::RangeBalance { .. } => "range_balance",
            SpacingLaw::ArcReference { .. } => "arc_reference",
        }
    }

    /// Whether the law uses only what a coordinate-free vehicle may know.
    pub fn is_coordinate_free(&self) -> bool {
        !matches!(self, SpacingLaw::ArcReference { .. })
    }
}

/// Finding the ring from ranges and range rates after deployment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscoveryConfig {
    /// Time all fly at `v0` before the probes (to settle onto the isoline), s.
    pub settle_s: f64,
    /// Length of each vehicle's probe slot, s (vehicle `i`'s slot starts at
    /// `settle_s + i probe_s`).
    pub probe_s: f64,
    /// Speed added during a vehicle's own probe, m/s (its sign does not matter).
    pub probe_speed_delta_mps: f64,
}

/// How vehicles know their neighbours.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RingMode {
    /// Fixed at deployment: the listed order is the order along the direction of travel.
    Listed,
    /// Found from ranges and range rates after deployment.
    Discover(DiscoveryConfig),
}

/// The spacing settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpacingConfig {
    /// The law.
    pub law: SpacingLaw,
    /// The nominal speed `v0`, m/s.
    pub nominal_speed_mps: f64,
    /// How the ring is known.
    pub ring: RingMode,
}

/// `v0 + k_v (ahead - behind)`, unsaturated (the vehicle saturates it to its envelope).
#[inline(always)]
pub fn balance_speed(v0: f64, gain_per_s: f64, ahead_m: f64, behind_m: f64) -> f64 {
    v0 + gain_per_s * (ahead_m - behind_m)
}

/// How long a neighbour's last valid range stands in for invalid ones, s; after it (or with
/// none yet) the neighbour counts as at the maximum range (no answer: out of range).
pub const RANGE_HOLD_S: f64 = 1.0;

/// The range a law uses for one neighbour: the valid one; else the last valid one for up to
/// [`RANGE_HOLD_S`] (a lost packet); else `max_range_m` (a neighbour that does not answer is at
/// least that far; with no range limit, the last valid range is held indefinitely).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeldRange {
    last_m: f64,
    last_t_s: f64,
}

impl Default for HeldRange {
    fn default() -> Self {
        Self {
            last_m: f64::NAN,
            last_t_s: f64::NEG_INFINITY,
        }
    }
}

impl HeldRange {
    /// The range to use for `r`, measured at `t_s` (`None`: no range known at all).
    #[inline]
    pub fn update(&mut self, r: Range, t_s: f64, max_range_m: f64) -> Option<f64> {
        if r.valid {
            self.last_m = r.range_m;
            self.last_t_s = t_s;
            return Some(r.range_m);
        }
        if !self.last_m.is_nan()
            && (t_s - self.last_t_s <= RANGE_HOLD_S || !max_range_m.is_finite())
        {
            return Some(self.last_m);
        }
        max_range_m.is_finite().then_some(max_range_m)
    }
}

/// Closes the ring around vehicle `i`, whose run has ended (docs/TEAMS.md "Vehicles that end
/// early"): every vehicle whose neighbour ahead was `i` takes `i`'s neighbour ahead, every one
/// whose neighbour behind was `i` takes `i`'s neighbour behind, and `i` leaves the ring
/// (`ring[i] = None`). A vehicle left with no neighbour but itself has none (`None`); one left
/// with itself on one side only takes its other neighbour on both. The one place a ring (listed
/// or discovered) drops a vehicle. Returns the vehicles whose neighbours changed, with a flag
/// per side (`[ahead, behind]`), in index order. `O(N)`.
pub fn leave_ring(ring: &mut [Option<[u32; 2]>], i: usize) -> Vec<(usize, [bool; 2])> {
    let mut changed = Vec::new();
    let Some([a, b]) = ring.get_mut(i).and_then(Option::take) else {
        return changed;
    };
    let me = i as u32;
    for (j, r) in ring.iter_mut().enumerate() {
        let Some([ja, jb]) = r.as_mut() else {
            continue;
        };
        let flags = [*ja == me, *jb == me];
        if !(flags[0] || flags[1]) {
            continue;
        }
        if flags[0] {
            *ja = a;
        }
        if flags[1] {
            *jb = b;
        }
        let own = j as u32;
        *r = match (*ja == own, *jb == own) {
            (true, true) => None,
            (true, false) => Some([*jb, *jb]),
            (false, true) => Some([*ja, *ja]),
            (false, false) => Some([*ja, *jb]),
        };
        changed.push((j, flags));
    }
    changed
}

/// Why `ring` is not one ring through the vehicles `live` marks, in words (`None`: it is).
/// One ring: every live vehicle has neighbours `[ahead, behind]`, both live and not itself;
/// `behind(ahead(i)) = i` and `ahead(behind(i)) = i` (each vehicle the ahead of exactly one and
/// the behind of exactly one); following "ahead" from any live vehicle visits every live one
/// before it returns (one cycle, not several). With two live vehicles each is the other's
/// ahead and behind; a lone live vehicle has none (`None`). Vehicles not live are not looked
/// at. `O(N)`.
pub fn ring_fault(ring: &[Option<[u32; 2]>], live: &[bool]) -> Option<String> {
    let is_live = |j: u32| live.get(j as usize).copied().unwrap_or(false);
    let members: Vec<usize> = (0..ring.len().min(live.len()))
        .filter(|&i| live[i])
        .collect();
    if members.len() == 1 {
        let i = members[0];
        return ring[i].map(|_| format!("vehicle {i}, the only one flying, has neighbours"));
    }
    for &i in &members {
        let Some([a, b]) = ring[i] else {
            return Some(format!("vehicle {i} has no neighbours"));
        };
        for (side, j) in [("ahead", a), ("behind", b)] {
            if j as usize == i {
                return Some(format!("vehicle {i} is its own neighbour {side}"));
            }
            if !is_live(j) {
                return Some(format!(
                    "vehicle {i}'s neighbour {side} is vehicle {j}, which is not flying"
                ));
            }
        }
        if ring[a as usize].map(|r| r[1]) != Some(i as u32) {
            return Some(format!(
                "vehicle {i}'s neighbour ahead is vehicle {a}, whose neighbour behind is not vehicle {i}"
            ));
        }
        if ring[b as usize].map(|r| r[0]) != Some(i as u32) {
            return Some(format!(
                "vehicle {i}'s neighbour behind is vehicle {b}, whose neighbour ahead is not vehicle {i}"
            ));
        }
    }
    if let Some(&start) = members.first() {
        let (mut at, mut steps) = (start, 0usize);
        loop {
            at = ring[at].map_or(start, |r| r[0] as usize);
            steps += 1;
            if at == start || steps > members.len() {
                break;
            }
        }
        if steps != members.len() {
            return Some(format!(
                "following the neighbours ahead from vehicle {start} returns after {steps} of the {} vehicles flying: more than one ring",
                members.len()
            ));
        }
    }
    None
}

/// The fewest ranges to one vehicle from which a discovery probe fits its range rate
/// ([`RateFit`]): a neighbour ranged fewer times in the prober's slot is not picked (att51-5:
/// `isotrack check` asks every slot for this many, `team.ring = "discovered"`).
pub const MIN_RATE_FIT_RANGES: usize = 3;

/// A least-squares line through `(t, r)` samples: the range rate and mean range to one vehicle
/// during a probe.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RateFit {
    n: f64,
    st: f64,
    sr: f64,
    stt: f64,
    str_: f64,
}

impl RateFit {
    pub(crate) fn add(&mut self, t: f64, r: f64) {
        self.n += 1.0;
        self.st += t;
        self.sr += r;
        self.stt += t * t;
        self.str_ += t * r;
    }

    /// `(slope m/s, mean range m)` with at least [`MIN_RATE_FIT_RANGES`] samples.
    pub(crate) fn fit(&self) -> Option<(f64, f64)> {
        if self.n < MIN_RATE_FIT_RANGES as f64 {
            return None;
        }
        let den = self.n * self.stt - self.st * self.st;
        if den.is_nan() || den <= 0.0 {
            return None;
        }
        Some((
            (self.n * self.str_ - self.st * self.sr) / den,
            self.sr / self.n,
        ))
    }
}

/// The neighbours a probing vehicle picks from its fits `(vehicle, slope, mean range)`:
/// `(ahead, behind)`, with `probe_sign` the sign of its speed change (ranges to vehicles ahead
/// then fall, for a positive change).
pub(crate) fn pick_neighbours(
    fits: &[(u32, f64, f64)],
    probe_sign: f64,
) -> (Option<u32>, Option<u32>) {
    let ahead: Vec<&(u32, f64, f64)> = fits.iter().filter(|f| f.1 * probe_sign < 0.0).collect();
    let behind: Vec<&(u32, f64, f64)> = fits.iter().filter(|f| f.1 * probe_sign > 0.0).collect();
    let nearest = |v: &[&(u32, f64, f64)]| {
        v.iter()
            .min_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)))
            .map(|f| f.0)
    };
    let farthest = |v: &[&(u32, f64, f64)]| {
        v.iter()
            .max_by(|a, b| a.2.total_cmp(&b.2).then(b.0.cmp(&a.0)))
            .map(|f| f.0)
    };
    let a = nearest(&ahead).or_else(|| farthest(&behind));
    let b = nearest(&behind).or_else(|| farthest(&ahead));
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// att32f-5's tables: the one the lossy ranging found (vehicle 3 the ahead of two, vehicle
    /// 0 of none) and what closing it around vehicle 2 left (vehicle 0 orphaned) are not rings;
    /// a ring, the two-vehicle ring, a lone vehicle and two rings of two are told apart.
    #[test]
    fn ring_faults() {
        let all = [true; 4];
        let bad = [Some([1, 3]), Some([3, 3]), Some([3, 1]), Some([2, 1])];
        assert!(ring_fault(&bad, &all).is_some());
        let orphaned = [Some([1, 3]), Some([3, 3]), None, Some([1, 1])];
        assert!(ring_fault(&orphaned, &[true, true, false, true]).is_some());
        let ring = [Some([1, 3]), Some([2, 0]), Some([3, 1]), Some([0, 2])];
        assert_eq!(ring_fault(&ring, &all), None);
        // Not in the listed order: 0 -> 2 -> 1 -> 3 -> 0.
        let found = [Some([2, 3]), Some([3, 2]), Some([1, 0]), Some([0, 1])];
        assert_eq!(ring_fault(&found, &all), None);
        let mut closed = ring;
        leave_ring(&mut closed, 2);
        assert_eq!(ring_fault(&closed, &[true, true, false, true]), None);
        let two = [Some([1, 1]), None, Some([0, 0]), None];
        assert!(ring_fault(&two, &all).is_some());
        assert!(ring_fault(&two, &[true, false, false, false]).is_some());
        let pair = [Some([2, 2]), None, Some([0, 0]), None];
        assert_eq!(ring_fault(&pair, &[true, false, true, false]), None);
        let lone = [None, None, None, None];
        assert_eq!(ring_fault(&lone, &[false, true, false, false]), None);
        let two_rings = [Some([1, 1]), Some([0, 0]), Some([3, 3]), Some([2, 2])];
        let why = ring_fault(&two_rings, &all).unwrap();
        assert!(why.contains("more than one ring"), "{why}");
        assert!(ring_fault(&lone, &all).is_some());
    }

    #[test]
    fn law_names_and_labels() {
        assert_eq!(SpacingLaw::None.name(), "none");
        let rb = SpacingLaw::RangeBalance { gain_per_s: 0.1 };
        assert!(rb.is_coordinate_free());
        assert!(!SpacingLaw::ArcReference { gain_per_s: 0.1 }.is_coordinate_free());
        assert_eq!(balance_speed(0.5, 0.1, 12.0, 10.0), 0.5 + 0.2);
    }

    /// Lost ranges: held for a second, then the maximum range; with none yet, the maximum.
    #[test]
    fn held_ranges() {
        let mut h = HeldRange::default();
        assert_eq!(h.update(Range::INVALID, 0.0, 20.0), Some(20.0));
        let ok = Range {
            range_m: 5.0,
            valid: true,
        };
        assert_eq!(h.update(ok, 1.0, 20.0), Some(5.0));
        assert_eq!(h.update(Range::INVALID, 1.9, 20.0), Some(5.0));
        assert_eq!(h.update(Range::INVALID, 2.5, 20.0), Some(20.0));
        assert_eq!(h.update(Range::INVALID, 9.0, f64::INFINITY), Some(5.0));
        assert_eq!(
            HeldRange::default().update(Range::INVALID, 0.0, f64::INFINITY),
            None
        );
    }

    /// A ring 0 -> 1 -> 2 -> 3 -> 0 ([ahead, behind]): vehicle 1 leaves, so 0's ahead is 2 and
    /// 2's behind is 0; then 3 leaves (0 and 2 each other's both neighbours); then 2 (0 alone).
    #[test]
    fn leaving_closes_the_ring() {
        let mut ring: Vec<Option<[u32; 2]>> = (0..4u32)
            .map(|i| Some([(i + 1) % 4, (i + 3) % 4]))
            .collect();
        let changed = leave_ring(&mut ring, 1);
        assert_eq!(changed, vec![(0, [true, false]), (2, [false, true])]);
        assert_eq!(ring, vec![Some([2, 3]), None, Some([3, 0]), Some([0, 2])]);
        leave_ring(&mut ring, 3);
        assert_eq!(ring, vec![Some([2, 2]), None, Some([0, 0]), None]);
        leave_ring(&mut ring, 2);
        assert_eq!(ring, vec![None; 4]);
        // Leaving twice, or with no ring yet, changes nothing.
        assert!(leave_ring(&mut ring, 2).is_empty());
        assert!(leave_ring(&mut ring, 9).is_empty());
    }

    /// A line r = 3 - 0.5 t: slope and mean by hand; picking neighbours: nearest ahead and
    /// behind; the team's front vehicle (none ahead) takes the farthest behind.
    #[test]
    fn fit_and_pick() {
        let mut f = RateFit::default();
        for i in 0..5 {
            let t = i as f64;
            f.add(t, 3.0 - 0.5 * t);
        }
        let (m, r) = f.fit().unwrap();
        assert!((m + 0.5).abs() < 1e-12 && (r - 2.0).abs() < 1e-12);
        let fits = [(1, -0.4, 5.0), (2, -0.4, 3.0), (3, 0.4, 4.0), (4, 0.4, 9.0)];
        assert_eq!(pick_neighbours(&fits, 1.0), (Some(2), Some(3)));
        assert_eq!(pick_neighbours(&fits, -1.0), (Some(3), Some(2)));
        let front = [(1, 0.4, 2.0), (2, 0.4, 6.0), (3, 0.4, 4.0)];
        assert_eq!(pick_neighbours(&front, 1.0), (Some(2), Some(1)));
    }
}
