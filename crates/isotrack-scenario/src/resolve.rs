//! Defaults and validation: a [`ScenarioFile`] in, a [`crate::Scenario`] with every applicable key set
//! (or every problem found, each naming its key) out.

use crate::schema::*;
use crate::spec::controller as C;
use crate::spec::field as F;
use crate::spec::sensor as N;
use crate::spec::sim as S;
use crate::spec::vehicle as V;
use isotrack_core::control::HigherSide;
pub use isotrack_sim::nearest_valid_rates;
use isotrack_sim::{whole_steps, Sensor, SensorConfig, SensorError, StepPlan, StepPlanError};

pub use crate::issue::Issue;

#[derive(Default)]
struct Checker {
    issues: Vec<Issue>,
}

impl Checker {
    fn fail(&mut self, key: &str, message: impl Into<String>) {
        self.issues.push(Issue {
            key: key.to_string(),
            message: message.into(),
            unreadable: false,
        });
    }
    fn finite(&mut self, key: &str, x: f64) -> bool {
        if x.is_finite() {
            true
        } else {
            self.fail(key, format!("must be a finite number, got {}", Echo(x)));
            false
        }
    }
    fn positive(&mut self, key: &str, x: f64) {
        if self.finite(key, x) && x <= 0.0 {
            self.fail(key, format!("must be > 0, got {}", Echo(x)));
        } else {
            self.not_subnormal(key, x);
        }
    }
    fn non_negative(&mut self, key: &str, x: f64) {
        if self.finite(key, x) && x < 0.0 {
            self.fail(key, format!("must be >= 0, got {}", Echo(x)));
        } else {
            self.not_subnormal(key, x);
        }
    }
    /// Refuses a subnormal `x` (non-zero, below `f64::MIN_POSITIVE` = 2.2e-308 in magnitude):
    /// no gain, time or length anyone means, and a product or quotient of one underflows to 0
    /// or overflows (`kp = 1e-310` was accepted as a law that never turns).
    fn not_subnormal(&mut self, key: &str, x: f64) {
        if x != 0.0 && x.is_finite() && !x.is_normal() {
            self.fail(
                key,
                format!(
                    "must not be subnormal (below {} in magnitude), got {}",
                    Echo(f64::MIN_POSITIVE),
                    Echo(x)
                ),
            );
        }
    }
    /// Rejects every present key of `section` that is not in `allowed` for the chosen
    /// `choice` (e.g. `field.kind = "grid"`).
    /// Each key of `set` (the keys set in `[section]`, [`keys_set`]) that is not `allowed` for
    /// the kind `choice` names.
    fn inapplicable(
        &mut self,
        section: &str,
        choice: &str,
        allowed: &[&str],
        set: Option<Vec<String>>,
    ) {
        let Some(set) = set else {
            self.fail(
                &format!("{section}.kind"),
                "cannot list the section's keys (an internal error: please report it)",
            );
            return;
        };
        for key in set {
            if !allowed.contains(&key.as_str()) {
                self.fail(
                    &format!("{section}.{key}"),
                    format!("does not apply to {choice}"),
                );
            }
        }
    }
    /// A finite number within `[lo, hi]` (the physical range of the key).
    fn within(&mut self, key: &str, x: f64, lo: f64, hi: f64, unit: &str) -> bool {
        if !self.finite(key, x) {
            return false;
        }
        if !(lo..=hi).contains(&x) {
            self.fail(
                key,
                format!(
                    "must be in [{}, {}] {unit}, got {}",
                    Echo(lo),
                    Echo(hi),
                    Echo(x)
                ),
            );
            return false;
        }
        true
    }
    /// A field value (or level, or slope per metre) within [`ranges::MAX_FIELD_VALUE`].
    fn field_value(&mut self, key: &str, x: f64) {
        let m = ranges::MAX_FIELD_VALUE;
        self.within(key, x, -m, m, "field units");
    }
    /// A position coordinate, m, within [`ranges::MAX_COORDINATE_M`].
    fn coordinate(&mut self, key: &str, x: f64) {
        let m = ranges::MAX_COORDINATE_M;
        self.within(key, x, -m, m, "m");
    }
    /// A wind or drift vector, m/s, each component within [`ranges::MAX_WIND_MPS`].
    fn speeds(&mut self, key: &str, xs: &[f64]) {
        let m = ranges::MAX_WIND_MPS;
        if xs.iter().any(|x| !(x.is_finite() && x.abs() <= m)) {
            self.fail(
                key,
                format!(
                    "must hold finite numbers within [-{}, {}] m/s, got {}",
                    Echo(m),
                    Echo(m),
                    EchoList(xs)
                ),
            );
        }
    }
    /// A sensor setting in field units (`resolution`, `noise_std`, `bias_drift_per_sqrt_s`):
    /// 0 (off) or within [`isotrack_sim::SENSOR_VALUE_RANGE`], so no reading overflows.
    fn sensor_setting(&mut self, key: &str, x: f64) {
        let (lo, hi) = isotrack_sim::SENSOR_VALUE_RANGE;
        if self.finite(key, x) && x != 0.0 && !(lo..=hi).contains(&x) {
            self.fail(
                key,
                format!(
                    "must be 0 (off) or in [{}, {}] field units, got {}",
                    Echo(lo),
                    Echo(hi),
                    Echo(x)
                ),
            );
        }
    }
    fn all_finite(&mut self, key: &str, xs: &[f64]) {
        if xs.iter().any(|x| !x.is_finite()) {
            self.fail(
                key,
                format!("must hold finite numbers, got {}", EchoList(xs)),
            );
        }
    }
}

/// The keys of `family` (`(key, is set)`) that are set: the keys of one option of a kind (an
/// anti-windup's, a derivative estimator's), checked against the option chosen.
fn given(family: &[(&str, bool)]) -> Option<Vec<String>> {
    Some(
        family
            .iter()
            .filter(|(_, set)| *set)
            .map(|(k, _)| k.to_string())
            .collect(),
    )
}

/// The keys set in a section, in the schema's order, less `shared` (the keys every kind
/// takes): read from the section's own serialization (every key is an `Option` skipped when
/// unset), so that a key added to the schema is checked against the kinds without a hand-kept
/// list. `None` if the section cannot be serialised (it always can: it is what
/// `scenario.toml` is written from).
fn keys_set<T: serde::Serialize>(section: &T, shared: &[&str]) -> Option<Vec<String>> {
    match toml::Value::try_from(section) {
        Ok(toml::Value::Table(t)) => Some(
            t.keys()
                .filter(|k| !shared.contains(&k.as_str()))
                .cloned()
                .collect(),
        ),
        _ => None,
    }
}

/// Defaults and checks of a `grid` field (the file itself is read when the scenario is built).
/// `puff_plume`: defaults and ranges. The puffs alive at once (`release_rate_hz * max_age_s`)
/// are bounded, so a query stays cheap.
fn resolve_puff(c: &mut Checker, fd: &mut FieldSection) {
    for x in *fd.source_m.get_or_insert(F::PUFF_SOURCE_M) {
        c.coordinate("field.source_m", x);
    }
    let rate = *fd.release_rate_hz.get_or_insert(F::PUFF_RELEASE_RATE_HZ);
    c.positive("field.release_rate_hz", rate);
    let mass = *fd.puff_mass.get_or_insert(F::PUFF_MASS);
    c.positive("field.puff_mass", mass);
    c.field_value("field.puff_mass", mass);
    c.within(
        "field.puff_sigma0_m",
        *fd.puff_sigma0_m.get_or_insert(F::PUFF_SIGMA0_M),
        ranges::MIN_LENGTH_M,
        ranges::MAX_COORDINATE_M,
        "m",
    );
    c.non_negative(
        "field.diffusivity_m2ps",
        *fd.diffusivity_m2ps.get_or_insert(F::PUFF_DIFFUSIVITY_M2PS),
    );
    let w = *fd.wind_mps.get_or_insert(F::PUFF_WIND_MPS);
    c.speeds("field.wind_mps", &w);
    let meander = *fd.meander_std_mps.get_or_insert(F::PUFF_MEANDER_STD_MPS);
    c.speeds("field.meander_std_mps", &[meander]);
    c.non_negative("field.meander_std_mps", meander);
    // `-0.0` is calm as `0.0` is: stored as `0.0`, so two calm plumes are one field.
    if let Some(m) = fd.meander_std_mps.as_mut().filter(|m| **m == 0.0) {
        *m = 0.0;
    }
    c.positive(
        "field.meander_correlation_s",
        *fd.meander_correlation_s
            .get_or_insert(F::PUFF_MEANDER_CORRELATION_S),
    );
    let age = *fd.max_age_s.get_or_insert(F::PUFF_MAX_AGE_S);
    c.positive("field.max_age_s", age);
    c.field_value(
        "field.background",
        *fd.background.get_or_insert(F::BACKGROUND),
    );
    if rate.is_finite() && age.is_finite() && rate * age > 100_000.0 {
        c.fail(
            "field.max_age_s",
            format!("release_rate_hz x max_age_s = {} puffs alive at once; at most 100000 (each query visits them all)", Num(rate * age)),
        );
    }
}

/// The time-series keys of a `grid` field.
fn resolve_frames(c: &mut Checker, fd: &mut FieldSection) {
    if let Some(paths) = &fd.paths {
        if paths.is_empty() || paths.iter().any(|p| p.is_empty()) {
            c.fail("field.paths", "must list at least one file, none empty");
        }
        match &fd.frame_times_s {
            None => c.fail(
                "field.frame_times_s",
                "is required with field.paths (one time per file)",
            ),
            Some(t) if t.len() != paths.len() => c.fail(
                "field.frame_times_s",
                format!(
                    "has {} times for {} files in field.paths",
                    t.len(),
                    paths.len()
                ),
            ),
            _ => {}
        }
    }
    if let Some(t) = &fd.frame_times_s {
        if let Some(k) = (0..t.len()).find(|&k| !t[k].is_finite() || (k > 0 && t[k] <= t[k - 1])) {
            c.fail(
                "field.frame_times_s",
                format!(
                    "must be finite and strictly increasing (time {k} is {})",
                    Echo(t[k])
                ),
            );
        }
        if fd.frame_interval_s.is_some() {
            c.fail(
                "field.frame_interval_s",
                "give field.frame_times_s or field.frame_interval_s, not both",
            );
        }
    }
    if let Some(dt) = fd.frame_interval_s {
        c.positive("field.frame_interval_s", dt);
    }
    fd.time_interpolation.get_or_insert(F::TIME_INTERPOLATION);
    c.finite(
        "field.time_origin_s",
        *fd.time_origin_s.get_or_insert(F::TIME_ORIGIN_S),
    );
    c.positive(
        "field.time_scale",
        *fd.time_scale.get_or_insert(F::TIME_SCALE),
    );
    fd.after_last_frame.get_or_insert(F::AFTER_LAST_FRAME);
}

fn resolve_grid(c: &mut Checker, fd: &mut FieldSection) {
    match (fd.path.as_deref(), &fd.paths) {
        (Some(_), Some(_)) => c.fail("field.paths", "give field.path or field.paths, not both"),
        (None | Some(""), None) => c.fail(
            "field.path",
            "is required for field.kind = \"grid\" (or field.paths)",
        ),
        _ => {}
    }
    resolve_frames(c, fd);
    resolve_grid_georeference(c, fd);
    if let Some([c0, c1, r0, r1]) = fd.crop_cells {
        if c0 >= c1 || r0 >= r1 {
            c.fail(
                "field.crop_cells",
                format!(
                    "must be [c0, c1, r0, r1] with c0 < c1 and r0 < r1, got {:?}",
                    [c0, c1, r0, r1]
                ),
            );
        }
    }
    if let Some(fl) = fd.value_floor {
        c.finite("field.value_floor", fl);
        if fd.value_log10 == Some(true) && fl <= 0.0 {
            c.fail(
                "field.value_floor",
                format!("must be > 0 with value_log10 = true, got {}", Echo(fl)),
            );
        }
    }
    fd.value_log10.get_or_insert(F::VALUE_LOG10);
    let scale = *fd.value_scale.get_or_insert(F::VALUE_SCALE);
    if c.finite("field.value_scale", scale) && scale == 0.0 {
        c.fail("field.value_scale", "must not be 0");
    }
    c.finite(
        "field.value_offset",
        *fd.value_offset.get_or_insert(F::VALUE_OFFSET),
    );
}

/// The sections whose keys depend on their `kind`.
pub const KINDED_SECTIONS: [&str; 3] = ["field", "vehicle", "controller"];

/// Switching kinds: removes from a scenario table's `[section]` (one of [`KINDED_SECTIONS`]) the
/// keys that do not apply to its `kind` (the keys every kind shares stay: `field.units`, the
/// controller's `level`, `higher_side`, `max_turn_rate_radps` and search keys). Applied when
/// `--set SECTION.kind=...` changes the kind (the file's keys for the old kind go, so the new
/// kind's defaults apply), and to each run of a sweep that varies a kind: a resolved scenario
/// holds every default of its kind, which another kind would refuse. Returns the dropped keys.
pub fn drop_inapplicable_keys(table: &mut toml::Table, section: &str) -> Vec<String> {
    let Some(toml::Value::Table(sec)) = table.get_mut(section) else {
        return vec![];
    };
    let kind = sec.get("kind");
    let (allowed, shared): (&[&str], &[&str]) = match section {
        "field" => match kind_or(kind, F::KIND) {
            Some(k) => (field_kind_keys(k).1, &FIELD_SHARED_KEYS),
            None => return vec![],
        },
        "vehicle" => match kind_or(kind, VehicleKind::Dubins) {
            Some(k) => (vehicle_kind_keys(k).1, &["kind"]),
            None => return vec![],
        },
        "controller" => match kind_or(kind, ControllerKind::PiIsoline) {
            Some(k) => (controller_allowed(k), &CONTROLLER_SHARED_KEYS),
            None => return vec![],
        },
        _ => return vec![],
    };
    let dropped: Vec<String> = sec
        .keys()
        .filter(|k| !shared.contains(&k.as_str()) && !allowed.contains(&k.as_str()))
        .cloned()
        .collect();
    for k in &dropped {
        sec.remove(k);
    }
    dropped
}

/// The kind a section's `kind` value names, `default` when unset; `None` for an unknown kind
/// (which the schema reports).
fn kind_or<K: serde::de::DeserializeOwned>(kind: Option<&toml::Value>, default: K) -> Option<K> {
    match kind {
        None => Some(default),
        Some(k) => k.clone().try_into().ok(),
    }
}

/// The `[field]` keys every kind takes: the kind and the values' units.
const FIELD_SHARED_KEYS: [&str; 2] = ["kind", "units"];

/// The `[controller]` keys every kind takes: the kind, the level, the output stage and the
/// search before tracking.
const CONTROLLER_SHARED_KEYS: [&str; 8] = [
    "kind",
    "level",
    "higher_side",
    "max_turn_rate_radps",
    "search",
    "search_spacing_m",
    "search_leg_m",
    "search_handover",
];

/// Every `[controller]` key that applies to `kind`: the shared ones, then the law's own (the
/// lists [`drop_inapplicable_keys`] and validation use), for "did you mean" suggestions.
pub(crate) fn controller_keys(kind: ControllerKind) -> Vec<&'static str> {
    let mut keys = CONTROLLER_SHARED_KEYS.to_vec();
    keys.extend_from_slice(controller_allowed(kind));
    keys
}

/// The keys each controller kind takes besides `kind`, `level`, `higher_side`,
/// `max_turn_rate_radps`.
fn controller_allowed(kind: ControllerKind) -> &'static [&'static str] {
    const D: [&str; 3] = ["derivative", "derivative_tau_s", "derivative_lipschitz"];
    match kind {
        ControllerKind::PiIsoline => &[
            "kp",
            "ki",
            "c1",
            "c2",
            "anti_windup",
            "integral_limit_radps",
            "integral_band",
            "tracking_time_s",
            D[0],
            D[1],
            D[2],
        ],
        ControllerKind::SlidingMode => &["gamma", "delta", D[0], D[1], D[2]],
        ControllerKind::SlidingModeSmooth => {
            &["gamma", "delta", "boundary_layer", D[0], D[1], D[2]]
        }
        ControllerKind::SuboptimalSosm => &["alpha_star", D[0], D[1], D[2]],
        ControllerKind::Pid => &["kp", "ki", "kd", D[0], D[1], D[2]],
        ControllerKind::PidCrossing => &[
            "kp",
            "ki",
            "kd",
            "crossing_angle_rad",
            "crossing_period_s",
            "crossing_turn_rate_radps",
            D[0],
            D[1],
            D[2],
        ],
        ControllerKind::GradientReference => &["ke", "k_heading"],
        ControllerKind::Schedule => &["course_rate_radps"],
    }
}

/// `controller.search*`: any controller may search first. Defaults that follow other keys
/// (spacing, leg, hand-over) are left unset and applied by `Scenario::search`.
fn resolve_search(c: &mut Checker, ct: &mut ControllerSection) {
    let kind = *ct.search.get_or_insert(SearchKind::None);
    let name = match kind {
        SearchKind::None => "none",
        SearchKind::Spiral => "spiral",
        SearchKind::Lawnmower => "lawnmower",
    };
    let applies = |key: &str| match key {
        "search_leg_m" => kind == SearchKind::Lawnmower,
        _ => kind != SearchKind::None,
    };
    for (key, v) in [
        ("search_spacing_m", ct.search_spacing_m),
        ("search_leg_m", ct.search_leg_m),
        ("search_handover", ct.search_handover),
    ] {
        let Some(v) = v else { continue };
        let full = format!("controller.{key}");
        if !applies(key) {
            c.fail(
                &full,
                format!("does not apply to controller.search = \"{name}\""),
            );
        } else if key == "search_handover" {
            c.positive(&full, v);
            c.field_value(&full, v);
        } else {
            c.within(
                &full,
                v,
                ranges::MIN_LENGTH_M,
                ranges::MAX_COORDINATE_M,
                "m",
            );
        }
    }
}

/// `[controller]`: the keys allowed for the chosen law, the shared output stage, the law's gains
/// and the derivative estimator.
///
/// `fixed_wing`: the vehicle is the UAV, whose airframe sets the turn-rate limit when
/// `max_turn_rate_radps` is not given (for every law, the bang-bang laws' amplitude included:
/// [`crate::spec::ControllerSpec::new`]).
fn resolve_controller(c: &mut Checker, ct: &mut ControllerSection, fixed_wing: bool) {
    resolve_search(c, ct);
    let kind = *ct.kind.get_or_insert(ControllerKind::PiIsoline);
    let allowed = controller_allowed(kind);
    let choice = format!("controller.kind = \"{}\"", kind.name());
    let set = keys_set(ct, &CONTROLLER_SHARED_KEYS);
    c.inapplicable("controller", &choice, allowed, set);
    c.field_value("controller.level", *ct.level.get_or_insert(C::LEVEL));
    ct.higher_side.get_or_insert(HigherSide::Right);
    let bang_bang = matches!(
        kind,
        ControllerKind::SlidingMode
            | ControllerKind::SlidingModeSmooth
            | ControllerKind::SuboptimalSosm
    );
    // On the fixed wing an unset limit is the airframe's (g tan(40 deg) / V, known once the
    // vehicle is trimmed), the bang-bang amplitude included: 1 rad/s there was 3.6 x what the
    // airframe flies at 30 m/s (issue 30, att30b item 14).
    if bang_bang && !fixed_wing {
        ct.max_turn_rate_radps
            .get_or_insert(C::BANG_BANG_U_MAX_RADPS);
    }
    if let Some(m) = ct.max_turn_rate_radps {
        c.positive("controller.max_turn_rate_radps", m);
    }
    resolve_gains(c, ct, kind);
    if !matches!(
        kind,
        ControllerKind::GradientReference | ControllerKind::Schedule
    ) {
        resolve_derivative(c, ct);
    }
}

/// The gains of the chosen law (with its defaults) and their ranges.
fn resolve_gains(c: &mut Checker, ct: &mut ControllerSection, kind: ControllerKind) {
    let pos = |c: &mut Checker, key: &str, v: &mut Option<f64>, d: f64| {
        c.positive(key, *v.get_or_insert(d))
    };
    let nonneg = |c: &mut Checker, key: &str, v: &mut Option<f64>, d: f64| {
        c.non_negative(key, *v.get_or_insert(d))
    };
    match kind {
        ControllerKind::PiIsoline => {
            pos(c, "controller.kp", &mut ct.kp, C::PI_KP);
            nonneg(c, "controller.ki", &mut ct.ki, C::PI_KI);
            pos(c, "controller.c1", &mut ct.c1, C::PI_C1);
            pos(c, "controller.c2", &mut ct.c2, C::PI_C2);
            resolve_anti_windup(c, ct);
        }
        ControllerKind::SlidingMode | ControllerKind::SlidingModeSmooth => {
            pos(c, "controller.gamma", &mut ct.gamma, C::SM_GAMMA);
            pos(c, "controller.delta", &mut ct.delta, C::SM_DELTA);
            if kind == ControllerKind::SlidingModeSmooth {
                pos(
                    c,
                    "controller.boundary_layer",
                    &mut ct.boundary_layer,
                    C::SM_BOUNDARY_LAYER,
                );
            }
        }
        ControllerKind::SuboptimalSosm => {
            let a = *ct.alpha_star.get_or_insert(C::SOSM_ALPHA_STAR);
            if c.finite("controller.alpha_star", a) && !(a > 0.0 && a <= 1.0) {
                c.fail(
                    "controller.alpha_star",
                    format!("must be in (0, 1], got {}", Echo(a)),
                );
            } else {
                c.not_subnormal("controller.alpha_star", a);
            }
        }
        ControllerKind::Pid | ControllerKind::PidCrossing => {
            nonneg(c, "controller.kp", &mut ct.kp, C::PID_KP);
            nonneg(c, "controller.ki", &mut ct.ki, C::PID_KI);
            nonneg(c, "controller.kd", &mut ct.kd, C::PID_KD);
            if kind == ControllerKind::PidCrossing {
                pos(
                    c,
                    "controller.crossing_angle_rad",
                    &mut ct.crossing_angle_rad,
                    C::CROSSING_ANGLE_RAD,
                );
                pos(
                    c,
                    "controller.crossing_period_s",
                    &mut ct.crossing_period_s,
                    C::CROSSING_PERIOD_S,
                );
                let d = ct
                    .max_turn_rate_radps
                    .unwrap_or(C::CROSSING_TURN_RATE_RADPS);
                pos(
                    c,
                    "controller.crossing_turn_rate_radps",
                    &mut ct.crossing_turn_rate_radps,
                    d,
                );
            }
        }
        ControllerKind::GradientReference => {
            pos(c, "controller.ke", &mut ct.ke, C::GR_KE);
            pos(
                c,
                "controller.k_heading",
                &mut ct.k_heading,
                C::GR_K_HEADING,
            );
        }
        ControllerKind::Schedule => resolve_schedule(c, ct),
    }
}

/// `controller.kind = "schedule"`: `[t_s, omega_radps]` pairs, finite, times increasing.
fn resolve_schedule(c: &mut Checker, ct: &mut ControllerSection) {
    let sched = ct.course_rate_radps.get_or_insert_with(Vec::new);
    if sched.is_empty() {
        c.fail(
            "controller.course_rate_radps",
            "must hold at least one [t_s, omega_radps] pair",
        );
    }
    for (i, [t, w]) in sched.iter().enumerate() {
        if !(t.is_finite() && w.is_finite()) {
            c.fail(
                &format!("controller.course_rate_radps[{i}]"),
                "must be finite",
            );
        }
        if i > 0 && *t <= sched[i - 1][0] {
            c.fail(
                &format!("controller.course_rate_radps[{i}]"),
                "times must increase",
            );
        }
        // The limit is every controller's (README): a schedule beyond it would fly a turn
        // rate the scenario says the vehicle cannot (issue 30, att30b item 12).
        if let Some(l) = ct.max_turn_rate_radps {
            if w.abs() > l {
                c.fail(
                    &format!("controller.course_rate_radps[{i}]"),
                    format!(
                        "turn rate {} rad/s exceeds controller.max_turn_rate_radps = {} rad/s, the limit every controller keeps: give |omega| <= {} or raise the limit",
                        Echo(*w),
                        Echo(l),
                        Echo(l)
                    ),
                );
            }
        }
    }
}

fn resolve_anti_windup(c: &mut Checker, ct: &mut ControllerSection) {
    let aw = *ct.anti_windup.get_or_insert(AntiWindupKind::None);
    let (name, own): (&str, Option<&str>) = match aw {
        AntiWindupKind::None => ("none", None),
        AntiWindupKind::Clamp => ("clamp", Some("integral_limit_radps")),
        AntiWindupKind::Conditional => ("conditional", Some("integral_band")),
        AntiWindupKind::BackCalculation => ("back_calculation", Some("tracking_time_s")),
    };
    c.inapplicable(
        "controller",
        &format!("controller.anti_windup = \"{name}\""),
        own.as_slice(),
        given(&[
            ("integral_limit_radps", ct.integral_limit_radps.is_some()),
            ("integral_band", ct.integral_band.is_some()),
            ("tracking_time_s", ct.tracking_time_s.is_some()),
        ]),
    );
    match aw {
        AntiWindupKind::None => {}
        AntiWindupKind::Clamp => {
            let default = ct
                .max_turn_rate_radps
                .unwrap_or(ct.kp.unwrap_or(0.0) * ct.c1.unwrap_or(0.0));
            c.positive(
                "controller.integral_limit_radps",
                *ct.integral_limit_radps.get_or_insert(default),
            );
        }
        AntiWindupKind::Conditional => {
            let default = ct.c2.unwrap_or(1.0);
            c.positive(
                "controller.integral_band",
                *ct.integral_band.get_or_insert(default),
            );
        }
        AntiWindupKind::BackCalculation => {
            c.positive(
                "controller.tracking_time_s",
                *ct.tracking_time_s.get_or_insert(C::TRACKING_TIME_S),
            );
            if ct.max_turn_rate_radps.is_none() {
                c.fail(
                    "controller.anti_windup",
                    "\"back_calculation\" needs controller.max_turn_rate_radps (it acts on the saturation)",
                );
            }
        }
    }
}

fn resolve_derivative(c: &mut Checker, ct: &mut ControllerSection) {
    let kind = *ct
        .derivative
        .get_or_insert(DerivativeKindName::BackwardDifference);
    let (name, own): (&str, Option<&str>) = match kind {
        DerivativeKindName::BackwardDifference => ("backward_difference", None),
        DerivativeKindName::FilteredDifference => ("filtered_difference", Some("derivative_tau_s")),
        DerivativeKindName::Levant => ("levant", Some("derivative_lipschitz")),
    };
    c.inapplicable(
        "controller",
        &format!("controller.derivative = \"{name}\""),
        own.as_slice(),
        given(&[
            ("derivative_tau_s", ct.derivative_tau_s.is_some()),
            ("derivative_lipschitz", ct.derivative_lipschitz.is_some()),
        ]),
    );
    match kind {
        DerivativeKindName::BackwardDifference => {}
        DerivativeKindName::FilteredDifference => {
            c.positive(
                "controller.derivative_tau_s",
                *ct.derivative_tau_s.get_or_insert(C::DERIVATIVE_TAU_S),
            );
        }
        DerivativeKindName::Levant => {
            c.positive(
                "controller.derivative_lipschitz",
                *ct.derivative_lipschitz
                    .get_or_insert(C::DERIVATIVE_LIPSCHITZ),
            );
        }
    }
}

/// Fills the defaults of every applicable key and validates every value. Files named by the
/// scenario are read later, when the [`crate::Scenario`] is built.
pub fn resolve(mut f: ScenarioFile) -> Result<ScenarioFile, Vec<Issue>> {
    let mut c = Checker::default();
    let dt = resolve_sim(&mut c, &mut f.sim);
    resolve_field(&mut c, &mut f.field);
    resolve_vehicle(&mut c, &mut f.vehicle, dt);
    resolve_initial(&mut c, &mut f.initial);
    let duration = f.sim.duration_s.unwrap_or(S::DURATION_S);
    resolve_sensor(&mut c, &mut f.sensor, dt, duration);
    let fixed_wing = f.vehicle.kind == Some(VehicleKind::FixedWing);
    resolve_controller(&mut c, &mut f.controller, fixed_wing);
    resolve_metrics(&mut c, &mut f);
    resolve_output(&mut c, &mut f);
    resolve_sitl(&mut c, &f.sitl);
    resolve_text(&mut c, &f);
    if c.issues.is_empty() {
        Ok(f)
    } else {
        Err(c.issues)
    }
}

/// The scenario's own strings that reach the console, `scenario.toml`, figures and pages
/// (`name`, `description`, `field.units`, `field.value_column`, `field.variable`): plain text
/// ([`isotrack_core::numtext::is_not_plain`], the rule for NetCDF attributes and suite names
/// too), but a description may span lines (LF, CRLF) and hold tabs.
fn resolve_text(c: &mut Checker, f: &ScenarioFile) {
    use isotrack_core::numtext::{is_not_plain, Clipped};
    for (key, text, lines) in [
        ("name", &f.name, false),
        ("description", &f.description, true),
        ("field.units", &f.field.units, false),
        ("field.value_column", &f.field.value_column, false),
        ("field.variable", &f.field.variable, false),
    ] {
        let Some(text) = text else { continue };
        let bad = |ch: char| is_not_plain(ch) && !(lines && matches!(ch, '\n' | '\r' | '\t'));
        // The scenario's `name` and `description` are text to read, never compared as an
        // identifier: a joiner there is kept where a script or an emoji needs it (att30c-9).
        let prose = matches!(key, "name" | "description");
        let chars: Vec<char> = text.chars().collect();
        let found = chars
            .iter()
            .enumerate()
            .find(|&(i, &ch)| bad(ch) && !(prose && joins_a_script(&chars, i)))
            .map(|(_, &ch)| ch);
        if let Some(ch) = found {
            c.fail(
                key,
                format!(
                    "holds a control or invisible character (U+{:04X}) in `{}`: write it as plain text",
                    ch as u32,
                    Clipped(text)
                ),
            );
        }
    }
}

/// Whether `chars[i]` is a joiner (ZWNJ U+200C, ZWJ U+200D) between two visible characters
/// outside ASCII: Persian's `می‌خواهم` (a ZWNJ), a Devanagari half-form (a ZWJ after the
/// virama), an emoji family (ZWJs between the emoji). There it reorders nothing and hides
/// nothing: it shapes the letters on either side, which are shown. Between ASCII letters
/// (`pi_iso` ZWJ `line`), at an end, or beside a space or another invisible character it shows
/// nothing at all, so it stays refused there (issue 30, att30c-9; README "Scenario files").
fn joins_a_script(chars: &[char], i: usize) -> bool {
    use isotrack_core::numtext::is_not_plain;
    let visible = |c: Option<&char>| {
        c.is_some_and(|&c| !c.is_ascii() && !c.is_whitespace() && !is_not_plain(c))
    };
    matches!(chars[i], '\u{200c}' | '\u{200d}')
        && i > 0
        && visible(chars.get(i - 1))
        && visible(chars.get(i + 1))
}

/// A number in messages: the one formatting of every message (six significant digits, plain
/// when ordinary, scientific when huge or tiny, so `1e307` is not echoed as 308 digits nor a
/// computed `0.0024500000000000004` as 17).
pub(crate) use isotrack_core::numtext::{Echo, EchoList, Num};

pub use crate::ranges;

/// `[sim]`; returns the step (s) for the sections whose checks depend on it.
fn resolve_sim(c: &mut Checker, sim: &mut SimSection) -> f64 {
    let dt = *sim.dt_s.get_or_insert(S::DT_S);
    c.positive("sim.dt_s", dt);
    let duration = *sim.duration_s.get_or_insert(S::DURATION_S);
    c.positive("sim.duration_s", duration);
    sim.seed.get_or_insert(S::SEED);
    if dt > 0.0 && duration > 0.0 && dt.is_finite() && duration.is_finite() {
        if duration < dt {
            // `1e-12` s would run 0 steps and be reported `completed`.
            c.fail(
                "sim.duration_s",
                format!(
                    "{} s is shorter than one step (sim.dt_s = {} s)",
                    Echo(duration),
                    Echo(dt)
                ),
            );
        } else if let Err(reason) = whole_steps(duration, dt) {
            c.fail(
                "sim.duration_s",
                format!("{} s {reason} of sim.dt_s = {} s", Echo(duration), Echo(dt)),
            );
        }
    }
    dt
}

/// `[field]`: the keys allowed for the chosen kind, its defaults and checks.
fn resolve_field(c: &mut Checker, fd: &mut FieldSection) {
    let fk = *fd.kind.get_or_insert(F::KIND);
    let (kind_name, allowed) = field_kind_keys(fk);
    let choice = format!("field.kind = \"{kind_name}\"");
    c.inapplicable("field", &choice, allowed, keys_set(fd, &FIELD_SHARED_KEYS));
    match fk {
        FieldKind::RadialExp => resolve_radial_exp(c, fd),
        FieldKind::GaussianPlumes => resolve_gaussian_plumes(c, fd),
        FieldKind::LinearRamp => resolve_linear_ramp(c, fd),
        FieldKind::Grid => resolve_grid(c, fd),
        FieldKind::PuffPlume => resolve_puff(c, fd),
        FieldKind::Stations => resolve_stations(c, fd),
    }
    if let Some(v) = fd.drift_mps {
        c.speeds("field.drift_mps", &v);
    }
    if let Some(d) = fd.domain_m {
        for x in d {
            c.coordinate("field.domain_m", x);
        }
        if !(d[0] < d[1] && d[2] < d[3]) {
            c.fail(
                "field.domain_m",
                format!(
                    "must be [x_min, x_max, y_min, y_max] with min < max, got {}",
                    EchoList(&d)
                ),
            );
        }
    }
}

/// A field kind's name and the `[field]` keys that apply to it.
fn field_kind_keys(kind: FieldKind) -> (&'static str, &'static [&'static str]) {
    match kind {
        FieldKind::RadialExp => (
            "radial_exp",
            &["i0", "decay_per_m", "center_m", "domain_m", "drift_mps"],
        ),
        FieldKind::GaussianPlumes => (
            "gaussian_plumes",
            &["background", "sources", "domain_m", "drift_mps"],
        ),
        FieldKind::LinearRamp => (
            "linear_ramp",
            &["offset", "gradient_per_m", "domain_m", "drift_mps"],
        ),
        FieldKind::Stations => (
            "stations",
            &[
                "path",
                "value_column",
                "method",
                "idw_power",
                "grid_spacing_m",
                "spacing_m",
                "origin_m",
                "interpolation",
            ],
        ),
        FieldKind::PuffPlume => (
            "puff_plume",
            &[
                "source_m",
                "release_rate_hz",
                "puff_mass",
                "puff_sigma0_m",
                "diffusivity_m2ps",
                "wind_mps",
                "meander_std_mps",
                "meander_correlation_s",
                "max_age_s",
                "background",
                "domain_m",
            ],
        ),
        FieldKind::Grid => (
            "grid",
            &[
                "path",
                "format",
                "variable",
                "spacing_m",
                "origin_m",
                "interpolation",
                "crop_cells",
                "value_floor",
                "value_log10",
                "value_scale",
                "value_offset",
                "paths",
                "frame_times_s",
                "frame_interval_s",
                "time_interpolation",
                "time_origin_s",
                "time_scale",
                "after_last_frame",
            ],
        ),
    }
}

/// `field.kind = "radial_exp"`: `F = i0 exp(-decay |p - center|)`.
fn resolve_radial_exp(c: &mut Checker, fd: &mut FieldSection) {
    let i0 = *fd.i0.get_or_insert(F::RADIAL_I0);
    c.positive("field.i0", i0);
    c.field_value("field.i0", i0);
    c.positive(
        "field.decay_per_m",
        *fd.decay_per_m.get_or_insert(F::RADIAL_DECAY_PER_M),
    );
    for x in *fd.center_m.get_or_insert(F::RADIAL_CENTER_M) {
        c.coordinate("field.center_m", x);
    }
}

/// `field.kind = "gaussian_plumes"`: a background and at least one source.
fn resolve_gaussian_plumes(c: &mut Checker, fd: &mut FieldSection) {
    c.field_value(
        "field.background",
        *fd.background.get_or_insert(F::BACKGROUND),
    );
    let sources = fd.sources.get_or_insert_with(F::default_plumes);
    if sources.is_empty() {
        c.fail("field.sources", "must hold at least one source");
    }
    for (i, s) in sources.iter().enumerate() {
        for x in s.center_m {
            c.coordinate(&format!("field.sources[{i}].center_m"), x);
        }
        c.field_value(&format!("field.sources[{i}].amplitude"), s.amplitude);
        c.within(
            &format!("field.sources[{i}].rotation_rad"),
            s.rotation_rad,
            -ranges::MAX_ANGLE_RAD,
            ranges::MAX_ANGLE_RAD,
            "rad",
        );
        for sg in s.sigma_m {
            let key = format!("field.sources[{i}].sigma_m");
            c.within(
                &key,
                sg,
                ranges::MIN_LENGTH_M,
                ranges::MAX_COORDINATE_M,
                "m",
            );
        }
    }
}

/// `field.kind = "linear_ramp"`: `F = offset + g . p` with `g != 0`.
fn resolve_linear_ramp(c: &mut Checker, fd: &mut FieldSection) {
    c.field_value("field.offset", *fd.offset.get_or_insert(F::RAMP_OFFSET));
    let g = *fd.gradient_per_m.get_or_insert(F::RAMP_GRADIENT_PER_M);
    for gi in g {
        c.field_value("field.gradient_per_m", gi);
    }
    if g == [0.0, 0.0] {
        c.fail(
            "field.gradient_per_m",
            "must not be zero (a flat field has no isolines)",
        );
    }
}

/// A grid's `spacing_m` and `origin_m` overrides (checked when given) and its interpolation
/// (bicubic by default): shared by `grid` and `stations`.
fn resolve_grid_georeference(c: &mut Checker, fd: &mut FieldSection) {
    if let Some(sp) = fd.spacing_m {
        for v in sp {
            c.positive("field.spacing_m", v);
        }
    }
    if let Some(o) = fd.origin_m {
        c.all_finite("field.origin_m", &o);
    }
    fd.interpolation.get_or_insert(F::INTERPOLATION);
}

/// `field.kind = "stations"`: the file and column, the method and the grid it is put on.
fn resolve_stations(c: &mut Checker, fd: &mut FieldSection) {
    if fd.path.as_deref().is_none_or(str::is_empty) {
        c.fail("field.path", "is required for field.kind = \"stations\"");
    }
    if fd.value_column.as_deref().is_none_or(str::is_empty) {
        c.fail(
            "field.value_column",
            "is required for field.kind = \"stations\"",
        );
    }
    let m = *fd.method.get_or_insert(F::STATIONS_METHOD);
    if m == StationMethod::Idw {
        c.positive("field.idw_power", *fd.idw_power.get_or_insert(F::IDW_POWER));
    } else if fd.idw_power.is_some() {
        c.fail(
            "field.idw_power",
            "does not apply to field.method = \"kriging\"",
        );
    }
    if let Some(g) = fd.grid_spacing_m {
        c.positive("field.grid_spacing_m", g);
    }
    resolve_grid_georeference(c, fd);
}

/// `[vehicle]`: the keys allowed for the chosen kind, its defaults and physical ranges.
fn resolve_vehicle(c: &mut Checker, vd: &mut VehicleSection, dt: f64) {
    let vk = *vd.kind.get_or_insert(VehicleKind::Dubins);
    let (vname, vallowed) = vehicle_kind_keys(vk);
    c.inapplicable(
        "vehicle",
        &format!("vehicle.kind = \"{vname}\""),
        vallowed,
        keys_set(vd, &["kind"]),
    );
    match vk {
        VehicleKind::Dubins => {
            let v = *vd.speed_mps.get_or_insert(V::DUBINS_SPEED_MPS);
            c.positive("vehicle.speed_mps", v);
            if v > ranges::MAX_SPEED_MPS {
                c.fail(
                    "vehicle.speed_mps",
                    format!("must be <= {} m/s, got {}", ranges::MAX_SPEED_MPS, Echo(v)),
                );
            }
        }
        VehicleKind::FixedWing => {
            let va = *vd.airspeed_mps.get_or_insert(V::AIRSPEED_MPS);
            c.positive("vehicle.airspeed_mps", va);
            let (lo, hi) = ranges::AIRSPEED_RANGE_MPS;
            if va.is_finite() && !(lo..=hi).contains(&va) {
                c.fail(
                    "vehicle.airspeed_mps",
                    format!(
                        "the Aerosonde model is valid for {}..{} m/s, got {}",
                        Echo(lo),
                        Echo(hi),
                        Echo(va)
                    ),
                );
            }
            let h = *vd.altitude_m.get_or_insert(V::ALTITUDE_M);
            let (lo, hi) = ranges::ALTITUDE_RANGE_M;
            if c.finite("vehicle.altitude_m", h) && !(h > lo && h <= hi) {
                c.fail(
                    "vehicle.altitude_m",
                    format!(
                        "must be above the {} m take-off zone and at most {} m, got {}",
                        Echo(lo),
                        Echo(hi),
                        Echo(h)
                    ),
                );
            }
            let w = *vd.wind_mps.get_or_insert(V::WIND_MPS);
            c.speeds("vehicle.wind_mps", &w);
            vd.gusts.get_or_insert(V::GUSTS);
            vd.trim_feedforward.get_or_insert(V::TRIM_FEEDFORWARD);
            vd.ecen674_gains.get_or_insert(V::ECEN674_GAINS);
            if dt > 0.02 {
                c.fail("sim.dt_s", format!("must be <= 0.02 s for vehicle.kind = \"fixed_wing\" (the autopilot runs at the step), got {}", Echo(dt)));
            }
        }
    }
}

/// A vehicle kind's name and the `[vehicle]` keys that apply to it.
fn vehicle_kind_keys(kind: VehicleKind) -> (&'static str, &'static [&'static str]) {
    match kind {
        VehicleKind::Dubins => ("dubins", &["speed_mps"]),
        VehicleKind::FixedWing => (
            "fixed_wing",
            &[
                "airspeed_mps",
                "altitude_m",
                "wind_mps",
                "gusts",
                "trim_feedforward",
                "ecen674_gains",
            ],
        ),
    }
}

/// `[sitl]`: the home position, when given, within the ranges of [`SitlSection`] (a latitude
/// short of the poles, where the east-west scale `cos(lat)` of the local-to-WGS84 mapping
/// vanishes).
fn resolve_sitl(c: &mut Checker, s: &SitlSection) {
    for (key, v, lo, hi) in [
        ("sitl.home_lat_deg", s.home_lat_deg, -89.0, 89.0),
        ("sitl.home_lon_deg", s.home_lon_deg, -180.0, 180.0),
        ("sitl.home_alt_m", s.home_alt_m, -1000.0, 10000.0),
    ] {
        if let Some(v) = v {
            if c.finite(key, v) && !(lo..=hi).contains(&v) {
                c.fail(
                    key,
                    format!("must be in [{}, {}], got {}", Num(lo), Num(hi), Num(v)),
                );
            }
        }
    }
}

/// `[initial]`: the pose, within [`ranges::MAX_COORDINATE_M`].
fn resolve_initial(c: &mut Checker, init: &mut InitialSection) {
    c.coordinate("initial.x_m", *init.x_m.get_or_insert(S::START_X_M));
    c.coordinate("initial.y_m", *init.y_m.get_or_insert(S::START_Y_M));
    c.within(
        "initial.heading_rad",
        *init.heading_rad.get_or_insert(S::START_HEADING_RAD),
        -ranges::MAX_ANGLE_RAD,
        ranges::MAX_ANGLE_RAD,
        "rad",
    );
}

/// `[sensor]`: decided by [`Sensor::new`] itself, the constructor the builder calls, so a value
/// that passes here cannot fail there.
fn resolve_sensor(c: &mut Checker, sn: &mut SensorSection, dt: f64, duration_s: f64) {
    let (rate, tiny_step) = resolve_sensor_rate(c, sn, dt);
    c.positive("sensor.rate_hz", rate);
    let (noise, delay) = resolve_sensor_settings(c, sn);
    if tiny_step {
        return; // already reported
    }
    check_sensor_timing(c, dt, duration_s, rate, noise, delay);
}

/// `sensor.rate_hz`, one sample a step (`1/sim.dt_s`) by default, and whether the step is so
/// small that this default is not finite (reported on `sim.dt_s`; the rate is then 1 Hz, so
/// that nothing else is reported about it).
fn resolve_sensor_rate(c: &mut Checker, sn: &mut SensorSection, dt: f64) -> (f64, bool) {
    // The default rate is one sample a step: a step so small that `1/dt` is infinite
    // (`sim.dt_s = 1e-320`) is the step's fault, not the (unwritten) rate's.
    let tiny_step = sn.rate_hz.is_none() && dt > 0.0 && !(1.0 / dt).is_finite();
    if tiny_step {
        c.fail(
            "sim.dt_s",
            format!(
                "got {}: the default sensor.rate_hz = 1/sim.dt_s is not finite (give a larger step)",
                Echo(dt)
            ),
        );
    }
    let rate = *sn.rate_hz.get_or_insert(if dt > 0.0 && !tiny_step {
        crate::spec::sensor::default_rate_hz(dt)
    } else {
        1.0
    });
    (rate, tiny_step)
}

/// The sensor's other settings with their defaults and ranges: noise, delay, time constant,
/// resolution, dropout probability in `[0, 1)`, bias drift and the range `[min, max]`.
/// Returns the noise and the delay, which the timing check needs.
fn resolve_sensor_settings(c: &mut Checker, sn: &mut SensorSection) -> (f64, f64) {
    let noise = *sn.noise_std.get_or_insert(N::NOISE_STD);
    c.sensor_setting("sensor.noise_std", noise);
    let delay = *sn.delay_s.get_or_insert(N::DELAY_S);
    c.non_negative("sensor.delay_s", delay);
    let tau = *sn.time_constant_s.get_or_insert(N::TIME_CONSTANT_S);
    c.non_negative("sensor.time_constant_s", tau);
    let resolution = *sn.resolution.get_or_insert(N::RESOLUTION);
    c.sensor_setting("sensor.resolution", resolution);
    let p = *sn.dropout_probability.get_or_insert(N::DROPOUT_PROBABILITY);
    if c.finite("sensor.dropout_probability", p) && !(0.0..1.0).contains(&p) {
        c.fail(
            "sensor.dropout_probability",
            format!("must be in [0, 1), got {}", Echo(p)),
        );
    } else {
        c.not_subnormal("sensor.dropout_probability", p);
    }
    let drift = *sn
        .bias_drift_per_sqrt_s
        .get_or_insert(N::BIAS_DRIFT_PER_SQRT_S);
    c.sensor_setting("sensor.bias_drift_per_sqrt_s", drift);
    if let Some([lo, hi]) = sn.range {
        c.all_finite("sensor.range", &[lo, hi]);
        if lo >= hi || lo.is_nan() || hi.is_nan() {
            c.fail(
                "sensor.range",
                format!(
                    "must be [min, max] with min < max, got [{}, {}]",
                    Echo(lo),
                    Echo(hi)
                ),
            );
        }
    }
    (noise, delay)
}

/// The sensor's timing as [`Sensor::new`] decides it (the rate a whole number of steps, the
/// delay within the run), once `dt`, the rate and the delay are each valid on their own.
fn check_sensor_timing(
    c: &mut Checker,
    dt: f64,
    duration_s: f64,
    rate: f64,
    noise: f64,
    delay: f64,
) {
    let all_finite = [dt, rate, delay].iter().all(|x| x.is_finite());
    if !(all_finite && dt > 0.0 && rate > 0.0 && delay >= 0.0) {
        return; // already reported
    }
    if delay > duration_s {
        c.fail(
            "sensor.delay_s",
            format!(
                "{} s is longer than the run (sim.duration_s = {} s): no measurement would arrive",
                Echo(delay),
                Echo(duration_s)
            ),
        );
        return;
    }
    let cfg = SensorConfig {
        rate_hz: rate,
        noise_std: noise,
        delay_s: delay,
        ..SensorConfig::default()
    };
    match Sensor::new(cfg, dt, 0) {
        Ok(_) => {}
        Err(e @ SensorError::RateNotMultiple { .. }) => c.fail(
            "sensor.rate_hz",
            format!(
                "{e}; the period must be a whole number >= 1 of sim.dt_s steps: {}",
                nearest_valid_rates(rate, dt)
            ),
        ),
        // Reported above, with the key's own message.
        Err(SensorError::OutOfRange { .. }) => {}
        Err(e) => c.fail("sensor.delay_s", e.to_string()),
    }
}

/// `[metrics]`.
fn resolve_metrics(c: &mut Checker, f: &mut ScenarioFile) {
    let frac = *f
        .metrics
        .steady_state_fraction
        .get_or_insert(S::STEADY_STATE_FRACTION);
    if c.finite("metrics.steady_state_fraction", frac) && !(frac > 0.0 && frac <= 1.0) {
        c.fail(
            "metrics.steady_state_fraction",
            format!("must be in (0, 1], got {}", Echo(frac)),
        );
    } else {
        c.not_subnormal("metrics.steady_state_fraction", frac);
    }
    let level = f.controller.level.unwrap_or(0.0);
    let tol_default = C::one_percent_of_level(level);
    c.positive(
        "metrics.convergence_tolerance",
        *f.metrics.convergence_tolerance.get_or_insert(tol_default),
    );
    if let Some(b) = f.metrics.track_loss_band {
        let tol = f.metrics.convergence_tolerance.unwrap_or(0.0);
        if c.finite("metrics.track_loss_band", b) && b < tol {
            c.fail(
                "metrics.track_loss_band",
                format!(
                    "must be >= metrics.convergence_tolerance = {}, got {}",
                    Echo(tol),
                    Echo(b)
                ),
            );
        }
    }
    // The dwell's default follows the duration (10 %), which a sweep or `--set` may change
    // after this file was resolved, so it is left unset here and applied by `Scenario::plan`.
    if let Some(dwell) = f.metrics.convergence_min_dwell_s {
        let duration = f.sim.duration_s.unwrap_or(S::DURATION_S);
        if c.finite("metrics.convergence_min_dwell_s", dwell)
            && !(dwell >= 0.0 && (!duration.is_finite() || dwell <= duration))
        {
            c.fail(
                "metrics.convergence_min_dwell_s",
                format!(
                    "must be in [0, sim.duration_s = {}] s, got {}",
                    Echo(duration),
                    Echo(dwell)
                ),
            );
        }
    }
}

/// `[output]`, and the step plan: decided by [`StepPlan::new`] itself, the constructor the
/// builder calls.
fn resolve_output(c: &mut Checker, f: &mut ScenarioFile) {
    let rec = *f.output.record_rate_hz.get_or_insert(S::RECORD_RATE_HZ);
    c.non_negative("output.record_rate_hz", rec);
    let (dt, duration) = (
        f.sim.dt_s.unwrap_or(S::DT_S),
        f.sim.duration_s.unwrap_or(S::DURATION_S),
    );
    let sane = |x: f64| x.is_finite() && x > 0.0;
    if !(sane(dt) && sane(duration) && rec.is_finite() && rec >= 0.0) {
        return; // already reported
    }
    match StepPlan::new(dt, duration, rec, 0.2, 0.1, 0.0, 0.0) {
        Err(e @ StepPlanError::RecordRateNotMultiple { .. }) => c.fail(
            "output.record_rate_hz",
            format!(
                "{e}; the period must be a whole number >= 1 of sim.dt_s steps (0 turns the trace off): {}",
                nearest_valid_rates(rec, dt)
            ),
        ),
        Ok(plan) if plan.record_every > 0 => {
            let rows = plan.n_steps / plan.record_every + 1;
            if rows > ranges::MAX_TRACE_ROWS {
                c.fail(
                    "output.record_rate_hz",
                    format!(
                        "{rows} trace rows over sim.duration_s = {} s is more than {}; lower the rate (0 turns the trace off)",
                        Echo(duration),
                        ranges::MAX_TRACE_ROWS
                    ),
                );
            }
        }
        _ => {}
    }
}
