//! `[team]`: several vehicles on one clock and one field, spread along the isoline by a spacing
//! law (docs/TEAMS.md, `isotrack_sim::team`). The defaults are written once here; the resolved
//! file keeps the user's keys as given (the defaults below apply when it is read again).

use super::sim::SimSpec;
use super::sim::Start;
use super::vehicle::VehicleSpec;
use crate::issue::Issue;
use crate::ranges::MAX_COORDINATE_M;
use crate::schema::{
    InitialSection, RingName, SpacingName, SpreadAlong, TeamSection, TeamSpread, TeamVehicleSection,
};
use isotrack_core::numtext::Echo;
use isotrack_sim::team::ranging::{Ranging, RangingConfig};
use isotrack_sim::team::spacing::{DiscoveryConfig, RingMode, SpacingLaw};
use isotrack_sim::{MemberSpeeds, Sensor, SensorConfig};
use isotrack_vehicles::fixed_wing::COMMANDED_AIRSPEED_RANGE_MPS;

/// Largest `team.count`: the issue's scale target is a ring of 1 000 robots; ten times that
/// keeps a run's memory (per vehicle: state, sensor, ranging queue) in megabytes.
pub const MAX_COUNT: u64 = 10_000;
/// Largest `team.count` with `team.ring = "discovered"`: each probe fits a range rate to every
/// other vehicle (`O(N)` per sample) and the probes take `N` slots one after another.
pub const MAX_DISCOVERED_COUNT: u64 = 64;
/// Default `team.spread.center_m` of an arc spread, m: the origin.
pub const SPREAD_CENTER_M: [f64; 2] = [0.0, 0.0];
/// Default `team.spread.start_rad` of an arc spread: the first start on +x from the centre.
pub const SPREAD_START_RAD: f64 = 0.0;
/// Default `team.spread.clockwise` of an arc spread (`team.spread.step_rad` defaults to
/// `2 pi / team.count`: the starts evenly around the circle).
pub const SPREAD_CLOCKWISE: bool = true;
/// Default `team.spacing`: the coordinate-free law.
pub const SPACING: SpacingName = SpacingName::RangeBalance;
/// Default `team.k_v`, 1/s: the engine's tested gain (four robots from a cluster on the paper's
/// circle spread to `gap_cv < 0.05` within 300 s), far below the largest stable gain at 10 Hz
/// ranging (`isotrack_core::spacing::max_stable_spacing_gain`: about 7 1/s there).
pub const K_V_PER_S: f64 = 0.1;
/// Default `team.v_min_mps` as a fraction of the nominal speed.
pub const V_MIN_FRACTION: f64 = 0.5;
/// Default `team.v_max_mps` as a multiple of the nominal speed.
pub const V_MAX_FACTOR: f64 = 2.0;
/// Default `team.ring`.
pub const RING: RingName = RingName::Listed;
/// Discovered ring: time all fly at `v0` before the probes, s.
pub const DISCOVERY_SETTLE_S: f64 = 60.0;
/// Discovered ring: length of each vehicle's probe slot, s.
pub const DISCOVERY_PROBE_S: f64 = 10.0;
/// Discovered ring: the probe's speed step as a fraction of `v0`.
pub const DISCOVERY_PROBE_FRACTION: f64 = 0.25;

/// `[team]` resolved: the starts in the listed order (the order of travel along the isoline for
/// the listed ring), the law, the envelope and the ranging.
#[derive(Clone, Debug, PartialEq)]
pub struct TeamSpec {
    /// One start per vehicle.
    pub starts: Vec<Start>,
    /// The spacing law with its gain.
    pub law: SpacingLaw,
    /// Nominal speed `v0` (`vehicle.speed_mps`), m/s.
    pub nominal_speed_mps: f64,
    /// Slowest commanded speed, m/s.
    pub v_min_mps: f64,
    /// Fastest commanded speed, m/s.
    pub v_max_mps: f64,
    /// How the ring is known.
    pub ring: RingMode,
    /// Neighbour ranging.
    pub ranging: RangingConfig,
    /// Per-vehicle overrides (`[[team.vehicles]]`), by ascending index, every value resolved
    /// (empty: every vehicle has the team's settings).
    pub vehicles: Vec<TeamVehicleSpec>,
}

/// One vehicle's own settings (`[[team.vehicles]]`), resolved: its nominal speed and envelope
/// (the team's where not given) and its sensor's noise and rate (the scenario's where `None`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TeamVehicleSpec {
    /// The vehicle, in the listed order.
    pub index: usize,
    /// Its nominal speed (airspeed command for a fixed wing) `v0_i`, m/s.
    pub nominal_speed_mps: f64,
    /// Its slowest command, m/s.
    pub v_min_mps: f64,
    /// Its fastest command, m/s.
    pub v_max_mps: f64,
    /// Its sensor's noise standard deviation, field units (`None`: `sensor.noise_std`).
    pub sensor_noise_std: Option<f64>,
    /// Its sensor's rate, Hz (`None`: `sensor.rate_hz`).
    pub sensor_rate_hz: Option<f64>,
}

impl TeamSpec {
    /// Number of vehicles.
    pub fn count(&self) -> usize {
        self.starts.len()
    }

    /// Vehicle `i`'s nominal speed and envelope (its override, else the team's).
    pub fn speeds(&self, i: usize) -> MemberSpeeds {
        match self.vehicle(i) {
            Some(v) => MemberSpeeds {
                nominal_mps: v.nominal_speed_mps,
                min_mps: v.v_min_mps,
                max_mps: v.v_max_mps,
            },
            None => MemberSpeeds {
                nominal_mps: self.nominal_speed_mps,
                min_mps: self.v_min_mps,
                max_mps: self.v_max_mps,
            },
        }
    }

    /// Vehicle `i`'s override, if it has one.
    pub fn vehicle(&self, i: usize) -> Option<&TeamVehicleSpec> {
        self.vehicles
            .binary_search_by_key(&i, |v| v.index)
            .ok()
            .map(|k| &self.vehicles[k])
    }

    /// Whether some vehicle's speeds differ from the team's.
    pub fn has_speed_overrides(&self) -> bool {
        self.vehicles.iter().any(|v| {
            (v.nominal_speed_mps, v.v_min_mps, v.v_max_mps)
                != (self.nominal_speed_mps, self.v_min_mps, self.v_max_mps)
        })
    }

    /// Every vehicle's speeds for the engine (`isotrack_sim::Group::set_member_speeds`), or
    /// `None` when every vehicle has the team's (the run is then the one without overrides).
    pub fn member_speeds(&self) -> Option<Vec<MemberSpeeds>> {
        self.has_speed_overrides()
            .then(|| (0..self.count()).map(|i| self.speeds(i)).collect())
    }

    /// The union of the vehicles' envelopes `[min v_min_i, max v_max_i]`, m/s: what the
    /// spacing law may command in the team (the vehicle model's envelope).
    pub fn speed_envelope_mps(&self) -> (f64, f64) {
        let mut lo_hi = if self.vehicles.len() < self.count() {
            (self.v_min_mps, self.v_max_mps)
        } else {
            (f64::INFINITY, f64::NEG_INFINITY)
        };
        for v in &self.vehicles {
            lo_hi = (lo_hi.0.min(v.v_min_mps), lo_hi.1.max(v.v_max_mps));
        }
        lo_hi
    }

    /// The distinct nominal speeds `v0_i`, ascending.
    pub fn nominal_speeds_mps(&self) -> Vec<f64> {
        let mut v: Vec<f64> = self.vehicles.iter().map(|v| v.nominal_speed_mps).collect();
        if self.vehicles.len() < self.count() {
            v.push(self.nominal_speed_mps);
        }
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }

    /// The speed of the ideal revisit time `L/(N v)`: `v0`, or with per-vehicle speeds their
    /// mean `sum v0_i / N` (a team at its own speeds passes a point `sum v0_i / L` times a
    /// second on average, as an even team at the mean speed does).
    pub fn ideal_speed_mps(&self) -> f64 {
        match self.member_speeds() {
            None => self.nominal_speed_mps,
            Some(m) => m.iter().map(|s| s.nominal_mps).sum::<f64>() / m.len() as f64,
        }
    }

    /// Vehicle `i`'s sensor: `base` (the scenario's) with its override's noise and rate.
    pub fn sensor(&self, i: usize, base: SensorConfig) -> SensorConfig {
        match self.vehicle(i) {
            None => base,
            Some(v) => SensorConfig {
                noise_std: v.sensor_noise_std.unwrap_or(base.noise_std),
                rate_hz: v.sensor_rate_hz.unwrap_or(base.rate_hz),
                ..base
            },
        }
    }

    /// The distinct sensor rates of the team's vehicles, Hz, ascending (`base` the scenario's).
    pub fn sensor_rates_hz(&self, base: f64) -> Vec<f64> {
        let mut r: Vec<f64> = self
            .vehicles
            .iter()
            .map(|v| v.sensor_rate_hz.unwrap_or(base))
            .collect();
        if self.vehicles.len() < self.count() {
            r.push(base);
        }
        r.sort_by(f64::total_cmp);
        r.dedup();
        r
    }

    /// Vehicle `i`'s sensor seed: `sim.seed` for vehicle 0 (a team of one senses as the single
    /// run does), a SplitMix64 mix of the seed and `i` for the others.
    pub fn sensor_seed(seed: u64, i: usize) -> u64 {
        if i == 0 {
            seed
        } else {
            splitmix(seed ^ splitmix(2 * i as u64))
        }
    }

    /// Vehicle `i`'s gust seed (a fixed wing with `vehicle.gusts`): `seed` (the vehicle's
    /// configured one) for vehicle 0, as the single run; a SplitMix64 mix for the others.
    pub fn gust_seed(seed: u64, i: usize) -> u64 {
        if i == 0 {
            seed
        } else {
            splitmix(seed ^ splitmix(!(i as u64)))
        }
    }

    /// Vehicle `i`'s ranging seed (a stream of its own, apart from every sensor's).
    pub fn ranging_seed(seed: u64, i: usize) -> u64 {
        splitmix(seed ^ splitmix(2 * i as u64 + 1))
    }

    /// From `[team]` (absent: `None`), the resolved vehicle, sim and `[initial]` start. Each
    /// concept is resolved by its own function, in this order (the first refusal is reported):
    /// the count, the starts, the law, the speed envelope, the ring, the ranging.
    pub fn new(
        t: &Option<TeamSection>,
        vehicle: &VehicleSpec,
        sim: &SimSpec,
        initial: Start,
        sensor: &SensorConfig,
    ) -> Result<Option<Self>, Issue> {
        let Some(t) = t else { return Ok(None) };
        let (v0, airframe) = nominal_speed(vehicle);
        let count = count_of(t)?;
        let n = count as usize;
        let starts = starts_of(t, n, count, initial)?;
        let law = law_of(t)?;
        let (v_min, v_max) = envelope_of(t, v0, airframe)?;
        let ring = ring_of(t, count, v0, sim)?;
        let ranging = ranging_of(t, sim)?;
        let team = Envelope {
            v0,
            v_min,
            v_max,
            airframe,
        };
        let vehicles = vehicles_of(t, n, vehicle, &team, &ring, sensor, sim)?;
        Ok(Some(Self {
            starts,
            law,
            nominal_speed_mps: v0,
            v_min_mps: v_min,
            v_max_mps: v_max,
            ring,
            ranging,
            vehicles,
        }))
    }
}

/// The speed the spacing law commands: the Dubins robot's speed, the fixed wing's airspeed
/// (through its autopilot's airspeed loop, within the model's safe range, the second value).
fn nominal_speed(vehicle: &VehicleSpec) -> (f64, Option<(f64, f64)>) {
    match vehicle {
        VehicleSpec::Dubins { speed_mps } => (*speed_mps, None),
        VehicleSpec::FixedWing(cfg) => (cfg.airspeed_mps, Some(COMMANDED_AIRSPEED_RANGE_MPS)),
    }
}

/// `team.count`, or the length of `team.starts`, in `[1, MAX_COUNT]`.
fn count_of(t: &TeamSection) -> Result<u64, Issue> {
    let count = match (t.count, &t.starts) {
        (Some(c), _) => c,
        (None, Some(s)) => s.len() as u64,
        (None, None) => return Err(issue("team.count", "is required".into())),
    };
    if !(1..=MAX_COUNT).contains(&count) {
        return Err(issue(
            "team.count",
            format!("must be in [1, {MAX_COUNT}], got {count}"),
        ));
    }
    Ok(count)
}

/// The `n` starts: `team.starts` (one per vehicle), `team.spread` (an arc or a line), or, for a
/// team of one without either, `[initial]`.
fn starts_of(t: &TeamSection, n: usize, count: u64, initial: Start) -> Result<Vec<Start>, Issue> {
    match (&t.starts, &t.spread) {
        (Some(_), Some(_)) => Err(issue(
            "team.starts",
            "and team.spread are both given: give one".into(),
        )),
        (Some(list), None) => listed_starts(list, n, count),
        (None, Some(sp)) => match sp.along {
            None => Err(issue(
                "team.spread.along",
                "is required (\"arc\" or \"line\")".into(),
            )),
            Some(SpreadAlong::Arc) => arc_starts(sp, n),
            Some(SpreadAlong::Line) => line_starts(sp, n, initial),
        },
        (None, None) if n == 1 => Ok(vec![initial]),
        (None, None) => Err(issue(
            "team.starts",
            "or team.spread is required for more than one vehicle".into(),
        )),
    }
}

/// `team.starts`: `count` poses, every key required.
fn listed_starts(list: &[InitialSection], n: usize, count: u64) -> Result<Vec<Start>, Issue> {
    if list.len() != n {
        return Err(issue(
            "team.starts",
            format!("has {} poses for team.count = {count}", list.len()),
        ));
    }
    list.iter()
        .enumerate()
        .map(|(i, p)| {
            let key = |k: &str| format!("team.starts[{i}].{k}");
            Ok(Start {
                x_m: coordinate(&key("x_m"), p.x_m)?,
                y_m: coordinate(&key("y_m"), p.y_m)?,
                heading_rad: finite(&key("heading_rad"), p.heading_rad)?,
            })
        })
        .collect()
}

/// `team.spread` along an arc: start `i` at angle `start_rad -+ i step_rad` (minus when
/// clockwise) on the circle, heading along the travel; the line's keys refused.
fn arc_starts(sp: &TeamSpread, n: usize) -> Result<Vec<Start>, Issue> {
    for (k, set) in [
        ("x_m", sp.x_m.is_some()),
        ("y_m", sp.y_m.is_some()),
        ("heading_rad", sp.heading_rad.is_some()),
        ("step_m", sp.step_m.is_some()),
        ("direction_rad", sp.direction_rad.is_some()),
    ] {
        if set {
            return Err(issue(
                &format!("team.spread.{k}"),
                "applies to along = \"line\" only".into(),
            ));
        }
    }
    let c = sp.center_m.unwrap_or(SPREAD_CENTER_M);
    let cx = coordinate("team.spread.center_m", Some(c[0]))?;
    let cy = coordinate("team.spread.center_m", Some(c[1]))?;
    let r = positive("team.spread.radius_m", sp.radius_m)?;
    if r > MAX_COORDINATE_M {
        return Err(issue(
            "team.spread.radius_m",
            format!(
                "must be at most {}, got {}",
                Echo(MAX_COORDINATE_M),
                Echo(r)
            ),
        ));
    }
    let th0 = finite(
        "team.spread.start_rad",
        Some(sp.start_rad.unwrap_or(SPREAD_START_RAD)),
    )?;
    let step = finite(
        "team.spread.step_rad",
        Some(sp.step_rad.unwrap_or(std::f64::consts::TAU / n as f64)),
    )?;
    let cw = sp.clockwise.unwrap_or(SPREAD_CLOCKWISE);
    // The next start `step` further along the travel: the listed order is the
    // order of travel (the listed ring's `ahead(i) = i + 1`).
    let sign = if cw { -1.0 } else { 1.0 };
    Ok((0..n)
        .map(|i| {
            let th = th0 + sign * step * i as f64;
            Start {
                x_m: cx + r * th.cos(),
                y_m: cy + r * th.sin(),
                heading_rad: th + sign * std::f64::consts::FRAC_PI_2,
            }
        })
        .collect())
}

/// `team.spread` along a line: start `i` at `(x_m, y_m) + i step_m (cos, sin)(direction_rad)`,
/// all heading `heading_rad`; the arc's keys refused.
fn line_starts(sp: &TeamSpread, n: usize, initial: Start) -> Result<Vec<Start>, Issue> {
    for (k, set) in [
        ("center_m", sp.center_m.is_some()),
        ("radius_m", sp.radius_m.is_some()),
        ("start_rad", sp.start_rad.is_some()),
        ("step_rad", sp.step_rad.is_some()),
        ("clockwise", sp.clockwise.is_some()),
    ] {
        if set {
            return Err(issue(
                &format!("team.spread.{k}"),
                "applies to along = \"arc\" only".into(),
            ));
        }
    }
    let x = coordinate("team.spread.x_m", Some(sp.x_m.unwrap_or(initial.x_m)))?;
    let y = coordinate("team.spread.y_m", Some(sp.y_m.unwrap_or(initial.y_m)))?;
    let h = finite(
        "team.spread.heading_rad",
        Some(sp.heading_rad.unwrap_or(initial.heading_rad)),
    )?;
    let step = positive("team.spread.step_m", sp.step_m)?;
    let dir = finite(
        "team.spread.direction_rad",
        Some(sp.direction_rad.unwrap_or(h)),
    )?;
    let far = step * (n - 1) as f64;
    if !(x.abs() + far <= MAX_COORDINATE_M && y.abs() + far <= MAX_COORDINATE_M) {
        return Err(issue(
            "team.spread.step_m",
            format!(
                "puts the last start beyond {} m (step {} m x {} vehicles)",
                Echo(MAX_COORDINATE_M),
                Echo(step),
                n - 1
            ),
        ));
    }
    Ok((0..n)
        .map(|i| Start {
            x_m: x + step * i as f64 * dir.cos(),
            y_m: y + step * i as f64 * dir.sin(),
            heading_rad: h,
        })
        .collect())
}

/// `team.spacing` with its gain `team.k_v` (>= 0).
fn law_of(t: &TeamSection) -> Result<SpacingLaw, Issue> {
    let k_v = non_negative("team.k_v", Some(t.k_v.unwrap_or(K_V_PER_S)))?;
    Ok(match t.spacing.unwrap_or(SPACING) {
        SpacingName::None => SpacingLaw::None,
        SpacingName::RangeBalance => SpacingLaw::RangeBalance { gain_per_s: k_v },
        SpacingName::ArcReference => SpacingLaw::ArcReference { gain_per_s: k_v },
    })
}

/// `[team.v_min_mps, team.v_max_mps]` around `v0` (defaults `v0/2` and `2 v0`, within the
/// airframe's safe commanded airspeeds `airframe` for a fixed wing).
fn envelope_of(
    t: &TeamSection,
    v0: f64,
    airframe: Option<(f64, f64)>,
) -> Result<(f64, f64), Issue> {
    let (lo, hi) = airframe.unwrap_or((0.0, f64::INFINITY));
    let v_min = positive(
        "team.v_min_mps",
        Some(t.v_min_mps.unwrap_or((V_MIN_FRACTION * v0).max(lo))),
    )?;
    let v_max = positive(
        "team.v_max_mps",
        Some(t.v_max_mps.unwrap_or((V_MAX_FACTOR * v0).min(hi))),
    )?;
    if airframe.is_some() {
        for (key, v) in [("team.v_min_mps", v_min), ("team.v_max_mps", v_max)] {
            if !(lo..=hi).contains(&v) {
                return Err(issue(
                    key,
                    format!(
                        "is an airspeed command for vehicle.kind = \"fixed_wing\" and must lie within the Aerosonde's safe airspeed range [{}, {}] m/s, got {}",
                        Echo(lo),
                        Echo(hi),
                        Echo(v)
                    ),
                ));
            }
        }
    }
    if v_min > v0 {
        return Err(issue(
            "team.v_min_mps",
            format!(
                "must be at most vehicle.speed_mps = {}, got {}",
                Echo(v0),
                Echo(v_min)
            ),
        ));
    }
    let max = crate::ranges::MAX_SPEED_MPS;
    if v_max < v0 || v_max > max {
        return Err(issue(
            "team.v_max_mps",
            format!(
                "must be in [vehicle.speed_mps = {}, {}], got {}",
                Echo(v0),
                Echo(max),
                Echo(v_max)
            ),
        ));
    }
    Ok((v_min, v_max))
}

/// `team.ring`: listed, or discovered (at most [`MAX_DISCOVERED_COUNT`] vehicles, the probes
/// ending before the run does).
fn ring_of(t: &TeamSection, count: u64, v0: f64, sim: &SimSpec) -> Result<RingMode, Issue> {
    Ok(match t.ring.unwrap_or(RING) {
        RingName::Listed => RingMode::Listed,
        RingName::Discovered => {
            if count > MAX_DISCOVERED_COUNT {
                return Err(issue(
                    "team.ring",
                    format!("\"discovered\" is for at most {MAX_DISCOVERED_COUNT} vehicles (O(N) per probe sample), got team.count = {count}"),
                ));
            }
            let d = DiscoveryConfig {
                settle_s: DISCOVERY_SETTLE_S,
                probe_s: DISCOVERY_PROBE_S,
                probe_speed_delta_mps: DISCOVERY_PROBE_FRACTION * v0,
            };
            let end = d.settle_s + d.probe_s * count as f64;
            if end >= sim.duration_s {
                return Err(issue(
                    "team.ring",
                    format!(
                        "\"discovered\" needs a run longer than {} s ({} s settling + {} s per vehicle: the probes must end before the run does), but sim.duration_s = {}",
                        Echo(end),
                        Echo(d.settle_s),
                        Echo(d.probe_s),
                        Echo(sim.duration_s)
                    ),
                ));
            }
            RingMode::Discover(d)
        }
    })
}

/// `team.ranging` with its defaults ([`RangingConfig::default`]), checked as the ranging unit
/// the run builds checks it.
fn ranging_of(t: &TeamSection, sim: &SimSpec) -> Result<RangingConfig, Issue> {
    let r = t.ranging.clone().unwrap_or_default();
    let dflt = RangingConfig::default();
    let ranging = RangingConfig {
        rate_hz: finite(
            "team.ranging.rate_hz",
            Some(r.rate_hz.unwrap_or(dflt.rate_hz)),
        )?,
        noise_std_m: non_negative(
            "team.ranging.noise_std_m",
            Some(r.noise_std_m.unwrap_or(dflt.noise_std_m)),
        )?,
        max_range_m: match r.max_range_m {
            None => dflt.max_range_m,
            v => positive("team.ranging.max_range_m", v)?,
        },
        dropout_probability: non_negative(
            "team.ranging.dropout_probability",
            Some(r.dropout_probability.unwrap_or(dflt.dropout_probability)),
        )?,
        delay_s: non_negative(
            "team.ranging.delay_s",
            Some(r.delay_s.unwrap_or(dflt.delay_s)),
        )?,
    };
    // A delay past the run's end is no delay anyone means, and it would hold every range
    // measured in the run in flight.
    if ranging.delay_s > sim.duration_s {
        return Err(issue(
            "team.ranging.delay_s",
            format!(
                "must be at most sim.duration_s = {}, got {}",
                Echo(sim.duration_s),
                Echo(ranging.delay_s)
            ),
        ));
    }
    // The rest (rate and delay whole numbers of steps, the probability in [0, 1]) as the
    // ranging unit the run builds decides it, so a value that passes here cannot fail there.
    Ranging::new(ranging, sim.dt_s, 0).map_err(|e| {
        let msg = e.to_string();
        let key = msg.split(' ').next().unwrap_or("team.ranging").to_string();
        Issue {
            message: msg
                .strip_prefix(&key)
                .map_or(msg.clone(), |m| m.trim_start().to_string()),
            key,
            unreadable: false,
        }
    })?;
    Ok(ranging)
}

/// The team's resolved speeds, the defaults of its vehicles' overrides.
struct Envelope {
    v0: f64,
    v_min: f64,
    v_max: f64,
    airframe: Option<(f64, f64)>,
}

/// `[[team.vehicles]]`: each entry's vehicle (`index`, once each), its nominal speed (the
/// vehicle kind's key: `speed_mps` for a Dubins robot, `airspeed_mps` for a fixed wing), its
/// envelope around it (default: `team.v_min_mps` / `team.v_max_mps` when given, else the team's
/// default rule at its own speed) and its sensor's noise and rate, checked as the team's and
/// the sensor's are. Unequal speeds with a discovered ring are refused (its probes assume one).
fn vehicles_of(
    t: &TeamSection,
    n: usize,
    vehicle: &VehicleSpec,
    team: &Envelope,
    ring: &RingMode,
    sensor: &SensorConfig,
    sim: &SimSpec,
) -> Result<Vec<TeamVehicleSpec>, Issue> {
    let Some(list) = &t.vehicles else {
        return Ok(Vec::new());
    };
    let fixed_wing = matches!(vehicle, VehicleSpec::FixedWing(_));
    let mut out: Vec<TeamVehicleSpec> = Vec::with_capacity(list.len());
    // The entry naming each vehicle so far: a duplicate is found in O(1), the list in O(n).
    let mut seen: Vec<Option<usize>> = vec![None; n];
    for (k, e) in list.iter().enumerate() {
        let index = entry_index(e, k, n, &mut seen)?;
        let speeds = entry_speeds(t, e, k, fixed_wing, team)?;
        if matches!(ring, RingMode::Discover(_)) {
            // The engine runs a discovered ring with the team's speeds only (its probes step
            // one vehicle while the others fly v0 in the team's envelope): an envelope of its
            // own is refused here, at its key, as a speed is (att32d-11: `check` said holds,
            // then the engine refused without a key).
            for (name, own, of_team) in [
                (speeds.key, speeds.v0, team.v0),
                ("v_min_mps", speeds.v_min, team.v_min),
                ("v_max_mps", speeds.v_max, team.v_max),
            ] {
                if own != of_team {
                    return Err(issue(
                        &entry_key(k, name),
                        format!(
                            "= {} differs from the team's {} m/s, but team.ring = \"discovered\" probes with every other vehicle at the team's nominal speed and envelope: give the vehicles the team's speeds or use team.ring = \"listed\"",
                            Echo(own),
                            Echo(of_team)
                        ),
                    ));
                }
            }
        }
        let (noise, rate) = entry_sensor(e, k, sensor, sim)?;
        out.push(TeamVehicleSpec {
            index,
            nominal_speed_mps: speeds.v0,
            v_min_mps: speeds.v_min,
            v_max_mps: speeds.v_max,
            sensor_noise_std: noise,
            sensor_rate_hz: rate,
        });
    }
    out.sort_by_key(|v| v.index);
    Ok(out)
}

/// The key `team.vehicles[k].name`.
fn entry_key(k: usize, name: &str) -> String {
    format!("team.vehicles[{k}].{name}")
}

/// The vehicle entry `k` names: its `index`, required, in `0 .. n`, and named by no earlier
/// entry (`seen[i]`: the entry naming vehicle `i` so far).
fn entry_index(
    e: &TeamVehicleSection,
    k: usize,
    n: usize,
    seen: &mut [Option<usize>],
) -> Result<usize, Issue> {
    let index = match e.index {
        None => {
            return Err(issue(
                &entry_key(k, "index"),
                "is required (the vehicle, 0 .. team.count - 1 in the listed order)".into(),
            ))
        }
        Some(i) if i >= n as u64 => {
            return Err(issue(
                &entry_key(k, "index"),
                format!("must be in [0, {}] (team.count = {n}), got {i}", n - 1),
            ))
        }
        Some(i) => i as usize,
    };
    if let Some(j) = seen[index] {
        return Err(issue(
            &entry_key(k, "index"),
            format!("= {index} is given twice (also team.vehicles[{j}]): one entry per vehicle"),
        ));
    }
    seen[index] = Some(k);
    Ok(index)
}

/// One vehicle entry's nominal speed (under `key`, the vehicle kind's speed key) and envelope.
#[derive(Clone, Copy)]
struct EntrySpeeds {
    key: &'static str,
    v0: f64,
    v_min: f64,
    v_max: f64,
    /// Where `v_min` and `v_max` come from when the entry does not give them (for messages:
    /// att32d-16, a refusal named `team.vehicles[0].v_max_mps`, which the user never set).
    v_min_from: &'static str,
    v_max_from: &'static str,
}

/// Where an envelope bound the entry does not give comes from: "" (its own), the team's key,
/// or the team's rule at the entry's speed.
fn bound_source(own: Option<f64>, of_team: Option<f64>, team_key: &'static str) -> &'static str {
    match (own, of_team) {
        (Some(_), _) => "",
        (None, Some(_)) => team_key,
        (None, None) => "the team's default rule at the vehicle's speed",
    }
}

/// Entry `k`'s nominal speed (the vehicle kind's key: `speed_mps` for a Dubins robot,
/// `airspeed_mps` for a fixed wing; the other kind's key refused) and its envelope around it
/// (default: `team.v_min_mps` / `team.v_max_mps` when given, else the team's default rule at
/// its own speed), within a fixed wing's safe airspeeds and [`crate::ranges::MAX_SPEED_MPS`].
fn entry_speeds(
    t: &TeamSection,
    e: &TeamVehicleSection,
    k: usize,
    fixed_wing: bool,
    team: &Envelope,
) -> Result<EntrySpeeds, Issue> {
    let key = |name: &str| entry_key(k, name);
    let (speed_key, given, wrong) = if fixed_wing {
        (
            "airspeed_mps",
            e.airspeed_mps,
            e.speed_mps.map(|_| {
                (
                    "speed_mps",
                    "a Dubins robot's speed; a fixed wing's is airspeed_mps",
                )
            }),
        )
    } else {
        (
            "speed_mps",
            e.speed_mps,
            e.airspeed_mps.map(|_| {
                (
                    "airspeed_mps",
                    "a fixed wing's airspeed command; a Dubins robot's is speed_mps",
                )
            }),
        )
    };
    if let Some((name, why)) = wrong {
        return Err(issue(&key(name), format!("is {why}")));
    }
    let v0 = positive(&key(speed_key), Some(given.unwrap_or(team.v0)))?;
    let (lo, hi) = team.airframe.unwrap_or((0.0, f64::INFINITY));
    // An envelope bound: the entry's own, else the team's when given, else the rule at v0.
    let bound = |name: &str, own: Option<f64>, of_team: Option<f64>, team_value: f64, rule: f64| {
        positive(
            &key(name),
            Some(own.unwrap_or(of_team.map_or(rule, |_| team_value))),
        )
    };
    let (min_rule, max_rule) = ((V_MIN_FRACTION * v0).max(lo), (V_MAX_FACTOR * v0).min(hi));
    let v_min = bound("v_min_mps", e.v_min_mps, t.v_min_mps, team.v_min, min_rule)?;
    let v_max = bound("v_max_mps", e.v_max_mps, t.v_max_mps, team.v_max, max_rule)?;
    let speeds = EntrySpeeds {
        key: speed_key,
        v0,
        v_min,
        v_max,
        v_min_from: bound_source(e.v_min_mps, t.v_min_mps, "team.v_min_mps"),
        v_max_from: bound_source(e.v_max_mps, t.v_max_mps, "team.v_max_mps"),
    };
    check_entry_speeds(&speeds, k, team)?;
    Ok(speeds)
}

/// Checks entry `k`'s speeds: within a fixed wing's safe airspeeds (`team.airframe`), the
/// nominal speed at most [`crate::ranges::MAX_SPEED_MPS`], the envelope around it.
fn check_entry_speeds(speeds: &EntrySpeeds, k: usize, team: &Envelope) -> Result<(), Issue> {
    let key = |name: &str| entry_key(k, name);
    let EntrySpeeds {
        key: speed_key,
        v0,
        v_min,
        v_max,
        v_min_from,
        v_max_from,
    } = *speeds;
    // ", inherited from team.v_max_mps" where the entry does not give the bound.
    let from = |src: &str| {
        if src.is_empty() {
            String::new()
        } else {
            format!(" (not given here: from {src})")
        }
    };
    let (lo, hi) = team.airframe.unwrap_or((0.0, f64::INFINITY));
    if team.airframe.is_some() {
        for (name, v) in [(speed_key, v0), ("v_min_mps", v_min), ("v_max_mps", v_max)] {
            if !(lo..=hi).contains(&v) {
                return Err(issue(
                    &key(name),
                    format!(
                        "is an airspeed command for vehicle.kind = \"fixed_wing\" and must lie within the Aerosonde's safe airspeed range [{}, {}] m/s, got {}",
                        Echo(lo),
                        Echo(hi),
                        Echo(v)
                    ),
                ));
            }
        }
    }
    let max = crate::ranges::MAX_SPEED_MPS;
    if v0 > max {
        return Err(issue(
            &key(speed_key),
            format!("must be at most {}, got {}", Echo(max), Echo(v0)),
        ));
    }
    if v_min > v0 {
        return Err(issue(
            &key("v_min_mps"),
            format!(
                "must be at most the vehicle's nominal speed {} m/s, got {}{}",
                Echo(v0),
                Echo(v_min),
                from(v_min_from)
            ),
        ));
    }
    // The top a vehicle can have: a fixed wing's safe airspeed, else the scenario bound.
    let top = max.min(hi);
    if v_max < v0 || v_max > top {
        return Err(issue(
            &key("v_max_mps"),
            format!(
                "must be in [the vehicle's nominal speed {}, {}], got {}{}",
                Echo(v0),
                Echo(top),
                Echo(v_max),
                from(v_max_from)
            ),
        ));
    }
    Ok(())
}

/// Entry `k`'s own sensor noise and rate (`None` where it keeps the team's `sensor`), checked
/// as the run builds its sensor: a rate whose period is not a whole number of steps is refused
/// here, by key.
fn entry_sensor(
    e: &TeamVehicleSection,
    k: usize,
    sensor: &SensorConfig,
    sim: &SimSpec,
) -> Result<(Option<f64>, Option<f64>), Issue> {
    let noise = match e.sensor_noise_std {
        None => None,
        v => Some(non_negative(&entry_key(k, "sensor_noise_std"), v)?),
    };
    let rate = match e.sensor_rate_hz {
        None => None,
        v => Some(positive(&entry_key(k, "sensor_rate_hz"), v)?),
    };
    let cfg = SensorConfig {
        noise_std: noise.unwrap_or(sensor.noise_std),
        rate_hz: rate.unwrap_or(sensor.rate_hz),
        ..*sensor
    };
    if let Err(err) = Sensor::new(cfg, sim.dt_s, 0) {
        let name = if rate.is_some() {
            "sensor_rate_hz"
        } else {
            "sensor_noise_std"
        };
        return Err(issue(&entry_key(k, name), err.to_string()));
    }
    Ok((noise, rate))
}

/// SplitMix64's finaliser (Steele, Lea & Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): distinct inputs give well-mixed, distinct seeds.
fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn issue(key: &str, message: String) -> Issue {
    Issue {
        key: key.to_string(),
        message,
        unreadable: false,
    }
}

fn finite(key: &str, v: Option<f64>) -> Result<f64, Issue> {
    let Some(x) = v else {
        return Err(issue(key, "is required".into()));
    };
    if !x.is_finite() {
        return Err(issue(
            key,
            format!("must be a finite number, got {}", Echo(x)),
        ));
    }
    if x != 0.0 && !x.is_normal() {
        return Err(issue(
            key,
            format!(
                "must not be subnormal (below {} in magnitude), got {}",
                Echo(f64::MIN_POSITIVE),
                Echo(x)
            ),
        ));
    }
    Ok(x)
}

fn non_negative(key: &str, v: Option<f64>) -> Result<f64, Issue> {
    let x = finite(key, v)?;
    if x < 0.0 {
        return Err(issue(key, format!("must be >= 0, got {}", Echo(x))));
    }
    Ok(x)
}

fn positive(key: &str, v: Option<f64>) -> Result<f64, Issue> {
    let x = finite(key, v)?;
    if x <= 0.0 {
        return Err(issue(key, format!("must be > 0, got {}", Echo(x))));
    }
    Ok(x)
}

fn coordinate(key: &str, v: Option<f64>) -> Result<f64, Issue> {
    let x = finite(key, v)?;
    if x.abs() > MAX_COORDINATE_M {
        return Err(issue(
            key,
            format!(
                "must be within +-{} m, got {}",
                Echo(MAX_COORDINATE_M),
                Echo(x)
            ),
        ));
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_scenario;

    fn team_of(text: &str) -> TeamSpec {
        let s = parse_scenario(text, "<test>", &[]).unwrap();
        s.spec().team.clone().unwrap()
    }

    /// An arc spread: start `i` at `R (cos(th0 - i step), sin(th0 - i step))` heading along the
    /// clockwise travel (`th - pi/2`); the defaults from the README (v0/2, 2 v0, k_v 0.1, 10 Hz,
    /// listed ring, range_balance).
    #[test]
    fn an_arc_spread_and_the_defaults() {
        let t = team_of(
            "[team]\ncount = 3\nspread = { along = \"arc\", radius_m = 2.0, start_rad = 1.0, step_rad = 0.5 }\n",
        );
        assert_eq!(t.count(), 3);
        for (i, s) in t.starts.iter().enumerate() {
            let th = 1.0 - 0.5 * i as f64;
            assert!((s.x_m - 2.0 * th.cos()).abs() < 1e-12);
            assert!((s.y_m - 2.0 * th.sin()).abs() < 1e-12);
            assert!((s.heading_rad - (th - std::f64::consts::FRAC_PI_2)).abs() < 1e-12);
        }
        assert_eq!(
            (t.v_min_mps, t.v_max_mps, t.nominal_speed_mps),
            (0.25, 1.0, 0.5)
        );
        assert_eq!(t.law, SpacingLaw::RangeBalance { gain_per_s: 0.1 });
        assert_eq!(t.ring, RingMode::Listed);
        assert_eq!(t.ranging, RangingConfig::default());
    }

    /// A line spread: start `i` at `(x, y) + i step (cos dir, sin dir)`, every heading the
    /// same; the default step direction is the heading.
    #[test]
    fn a_line_spread() {
        let t = team_of(
            "[team]\ncount = 3\nspread = { along = \"line\", x_m = 1.0, y_m = 2.0, heading_rad = 0.0, step_m = 1.5 }\n",
        );
        let xy: Vec<(f64, f64, f64)> = t
            .starts
            .iter()
            .map(|s| (s.x_m, s.y_m, s.heading_rad))
            .collect();
        assert_eq!(xy, vec![(1.0, 2.0, 0.0), (2.5, 2.0, 0.0), (4.0, 2.0, 0.0)]);
    }

    /// No `[team]`: no team (the single run, unchanged).
    #[test]
    fn no_team_section_no_team() {
        let s = parse_scenario("", "<test>", &[]).unwrap();
        assert!(s.spec().team.is_none());
    }

    /// Distinct seeds for every vehicle's sensor and ranging, vehicle 0's sensor the run's.
    #[test]
    fn seeds_are_distinct() {
        let mut all: Vec<u64> = (0..1000)
            .flat_map(|i| [TeamSpec::sensor_seed(7, i), TeamSpec::ranging_seed(7, i)])
            .collect();
        assert_eq!(all[0], 7);
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 2000);
    }
}
