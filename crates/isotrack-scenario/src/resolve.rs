//! Defaults and validation: a [`ScenarioFile`] in, a [`Scenario`] with every applicable key set
//! (or every problem found, each naming its key) out.

use crate::schema::*;
use isotrack_core::control::HigherSide;

/// A problem with one key's value.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Issue {
    /// Dotted key, e.g. `controller.kp`.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

#[derive(Default)]
struct Checker {
    issues: Vec<Issue>,
}

impl Checker {
    fn fail(&mut self, key: &str, message: impl Into<String>) {
        self.issues.push(Issue {
            key: key.to_string(),
            message: message.into(),
        });
    }
    fn finite(&mut self, key: &str, x: f64) -> bool {
        if x.is_finite() {
            true
        } else {
            self.fail(key, format!("must be a finite number, got {x}"));
            false
        }
    }
    fn positive(&mut self, key: &str, x: f64) {
        if self.finite(key, x) && x <= 0.0 {
            self.fail(key, format!("must be > 0, got {x}"));
        }
    }
    fn non_negative(&mut self, key: &str, x: f64) {
        if self.finite(key, x) && x < 0.0 {
            self.fail(key, format!("must be >= 0, got {x}"));
        }
    }
    fn all_finite(&mut self, key: &str, xs: &[f64]) {
        if xs.iter().any(|x| !x.is_finite()) {
            self.fail(key, format!("must hold finite numbers, got {xs:?}"));
        }
    }
    fn unused<T>(&mut self, key: &str, v: &Option<T>, why: &str) {
        if v.is_some() {
            self.fail(key, format!("does not apply {why}"));
        }
    }
}

/// The default `gaussian_plumes` sources: three overlapping, rotated, anisotropic plumes whose
/// level-10 isoline is one closed, non-convex curve about 60 m long.
pub fn default_plumes() -> Vec<PlumeSpec> {
    vec![
        PlumeSpec {
            center_m: [0.0, 0.0],
            amplitude: 20.0,
            sigma_m: [12.0, 7.0],
            rotation_rad: 0.5,
        },
        PlumeSpec {
            center_m: [18.0, 10.0],
            amplitude: 12.0,
            sigma_m: [6.0, 9.0],
            rotation_rad: -0.3,
        },
        PlumeSpec {
            center_m: [-10.0, 15.0],
            amplitude: 8.0,
            sigma_m: [8.0, 5.0],
            rotation_rad: 1.0,
        },
    ]
}

/// `(key, is set)` for every kind-specific key of `[field]`, to reject keys of another kind.
fn field_keys_present(fd: &FieldSection) -> [(&'static str, bool); 19] {
    [
        ("i0", fd.i0.is_some()),
        ("decay_per_m", fd.decay_per_m.is_some()),
        ("center_m", fd.center_m.is_some()),
        ("background", fd.background.is_some()),
        ("sources", fd.sources.is_some()),
        ("offset", fd.offset.is_some()),
        ("gradient_per_m", fd.gradient_per_m.is_some()),
        ("domain_m", fd.domain_m.is_some()),
        ("path", fd.path.is_some()),
        ("format", fd.format.is_some()),
        ("variable", fd.variable.is_some()),
        ("spacing_m", fd.spacing_m.is_some()),
        ("origin_m", fd.origin_m.is_some()),
        ("interpolation", fd.interpolation.is_some()),
        ("crop_cells", fd.crop_cells.is_some()),
        ("value_floor", fd.value_floor.is_some()),
        ("value_log10", fd.value_log10.is_some()),
        ("value_scale", fd.value_scale.is_some()),
        ("value_offset", fd.value_offset.is_some()),
    ]
}

/// Defaults and checks of a `grid` field (the file itself is read when the scenario is built).
fn resolve_grid(c: &mut Checker, fd: &mut FieldSection) {
    if fd.path.as_deref().is_none_or(str::is_empty) {
        c.fail("field.path", "is required for field.kind = \"grid\"");
    }
    if let Some(sp) = fd.spacing_m {
        for v in sp {
            c.positive("field.spacing_m", v);
        }
    }
    if let Some(o) = fd.origin_m {
        c.all_finite("field.origin_m", &o);
    }
    fd.interpolation.get_or_insert(InterpolationName::Bicubic);
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
                format!("must be > 0 with value_log10 = true, got {fl}"),
            );
        }
    }
    fd.value_log10.get_or_insert(false);
    let scale = *fd.value_scale.get_or_insert(1.0);
    if c.finite("field.value_scale", scale) && scale == 0.0 {
        c.fail("field.value_scale", "must not be 0");
    }
    c.finite("field.value_offset", *fd.value_offset.get_or_insert(0.0));
}

/// Fills the defaults of every applicable key and validates every value. Files named by the
/// scenario are read later, when the [`crate::Scenario`] is built.
pub fn resolve(mut f: ScenarioFile) -> Result<ScenarioFile, Vec<Issue>> {
    let mut c = Checker::default();

    // [sim]
    let dt = *f.sim.dt_s.get_or_insert(0.01);
    c.positive("sim.dt_s", dt);
    let duration = *f.sim.duration_s.get_or_insert(600.0);
    c.positive("sim.duration_s", duration);
    f.sim.seed.get_or_insert(0);
    if dt > 0.0 && duration > 0.0 && dt.is_finite() && duration.is_finite() {
        let n = duration / dt;
        if (n - n.round()).abs() > 1e-9 * n.round().max(1.0) {
            c.fail(
                "sim.duration_s",
                format!("must be a whole number of steps of sim.dt_s = {dt} s, got {duration} s"),
            );
        } else if n.round() > 1.0e10 {
            c.fail("sim.duration_s", format!("{n} steps is more than 1e10"));
        }
    }

    // [field]
    let fk = *f.field.kind.get_or_insert(FieldKind::RadialExp);
    let fd = &mut f.field;
    let (kind_name, allowed): (&str, &[&str]) = match fk {
        FieldKind::RadialExp => ("radial_exp", &["i0", "decay_per_m", "center_m", "domain_m"]),
        FieldKind::GaussianPlumes => ("gaussian_plumes", &["background", "sources", "domain_m"]),
        FieldKind::LinearRamp => ("linear_ramp", &["offset", "gradient_per_m", "domain_m"]),
        FieldKind::Grid => (
            "grid",
            &[
                "path",
                "format",
                "spacing_m",
                "origin_m",
                "interpolation",
                "crop_cells",
                "value_floor",
                "value_log10",
                "value_scale",
                "value_offset",
            ],
        ),
    };
    for (key, present) in field_keys_present(fd) {
        if present && !allowed.contains(&key) {
            c.fail(
                &format!("field.{key}"),
                format!("does not apply to field.kind = \"{kind_name}\""),
            );
        }
    }
    match fk {
        FieldKind::RadialExp => {
            c.positive("field.i0", *fd.i0.get_or_insert(20.0));
            c.positive("field.decay_per_m", *fd.decay_per_m.get_or_insert(0.1));
            c.all_finite("field.center_m", fd.center_m.get_or_insert([0.0, 0.0]));
        }
        FieldKind::GaussianPlumes => {
            c.finite("field.background", *fd.background.get_or_insert(0.0));
            let sources = fd.sources.get_or_insert_with(default_plumes);
            if sources.is_empty() {
                c.fail("field.sources", "must hold at least one source");
            }
            for (i, s) in sources.iter().enumerate() {
                c.all_finite(&format!("field.sources[{i}].center_m"), &s.center_m);
                c.finite(&format!("field.sources[{i}].amplitude"), s.amplitude);
                c.finite(&format!("field.sources[{i}].rotation_rad"), s.rotation_rad);
                for sg in s.sigma_m {
                    c.positive(&format!("field.sources[{i}].sigma_m"), sg);
                }
            }
        }
        FieldKind::LinearRamp => {
            c.finite("field.offset", *fd.offset.get_or_insert(0.0));
            let g = *fd.gradient_per_m.get_or_insert([0.0, 1.0]);
            c.all_finite("field.gradient_per_m", &g);
            if g == [0.0, 0.0] {
                c.fail(
                    "field.gradient_per_m",
                    "must not be zero (a flat field has no isolines)",
                );
            }
        }
        FieldKind::Grid => resolve_grid(&mut c, fd),
    }
    if let Some(d) = fd.domain_m {
        c.all_finite("field.domain_m", &d);
        if !(d[0] < d[1] && d[2] < d[3]) {
            c.fail(
                "field.domain_m",
                format!("must be [x_min, x_max, y_min, y_max] with min < max, got {d:?}"),
            );
        }
    }

    // [vehicle]
    match *f.vehicle.kind.get_or_insert(VehicleKind::Dubins) {
        VehicleKind::Dubins => {
            c.positive("vehicle.speed_mps", *f.vehicle.speed_mps.get_or_insert(0.5));
        }
    }

    // [initial]
    c.finite("initial.x_m", *f.initial.x_m.get_or_insert(10.0));
    c.finite("initial.y_m", *f.initial.y_m.get_or_insert(0.0));
    c.finite(
        "initial.heading_rad",
        *f.initial
            .heading_rad
            .get_or_insert(-std::f64::consts::FRAC_PI_2),
    );

    // [sensor]
    let rate = *f
        .sensor
        .rate_hz
        .get_or_insert(if dt > 0.0 { 1.0 / dt } else { 1.0 });
    c.positive("sensor.rate_hz", rate);
    c.non_negative("sensor.noise_std", *f.sensor.noise_std.get_or_insert(0.0));
    let delay = *f.sensor.delay_s.get_or_insert(0.0);
    c.non_negative("sensor.delay_s", delay);
    if dt > 0.0 && dt.is_finite() && rate > 0.0 && rate.is_finite() {
        let n = 1.0 / (rate * dt);
        if n < 1.0 - 1e-9 || (n - n.round()).abs() > 1e-9 * n.round().max(1.0) {
            c.fail(
                "sensor.rate_hz",
                format!(
                    "the sample period must be a whole number (>= 1) of steps of sim.dt_s = {dt} s; got {rate} Hz"
                ),
            );
        }
        if delay.is_finite() && delay > 0.0 {
            let m = delay / dt;
            if (m - m.round()).abs() > 1e-9 * m.round().max(1.0) {
                c.fail(
                    "sensor.delay_s",
                    format!("must be a whole number of steps of sim.dt_s = {dt} s, got {delay} s"),
                );
            }
        }
    }

    // [controller]
    let ct = &mut f.controller;
    match *ct.kind.get_or_insert(ControllerKind::PiIsoline) {
        ControllerKind::PiIsoline => {
            c.finite("controller.level", *ct.level.get_or_insert(10.0));
            c.positive("controller.kp", *ct.kp.get_or_insert(10.0));
            c.non_negative("controller.ki", *ct.ki.get_or_insert(1.0));
            c.positive("controller.c1", *ct.c1.get_or_insert(0.2));
            c.positive("controller.c2", *ct.c2.get_or_insert(1.0));
            ct.higher_side.get_or_insert(HigherSide::Right);
            if let Some(m) = ct.max_turn_rate_radps {
                c.positive("controller.max_turn_rate_radps", m);
            }
            let aw = *ct.anti_windup.get_or_insert(AntiWindupKind::None);
            let why = |k: &str| format!("to controller.anti_windup = \"{k}\"");
            match aw {
                AntiWindupKind::None => {
                    c.unused(
                        "controller.integral_limit_radps",
                        &ct.integral_limit_radps,
                        &why("none"),
                    );
                    c.unused("controller.integral_band", &ct.integral_band, &why("none"));
                    c.unused(
                        "controller.tracking_time_s",
                        &ct.tracking_time_s,
                        &why("none"),
                    );
                }
                AntiWindupKind::Clamp => {
                    c.unused("controller.integral_band", &ct.integral_band, &why("clamp"));
                    c.unused(
                        "controller.tracking_time_s",
                        &ct.tracking_time_s,
                        &why("clamp"),
                    );
                    let default = ct
                        .max_turn_rate_radps
                        .unwrap_or(ct.kp.unwrap_or(0.0) * ct.c1.unwrap_or(0.0));
                    c.positive(
                        "controller.integral_limit_radps",
                        *ct.integral_limit_radps.get_or_insert(default),
                    );
                }
                AntiWindupKind::Conditional => {
                    c.unused(
                        "controller.integral_limit_radps",
                        &ct.integral_limit_radps,
                        &why("conditional"),
                    );
                    c.unused(
                        "controller.tracking_time_s",
                        &ct.tracking_time_s,
                        &why("conditional"),
                    );
                    let default = ct.c2.unwrap_or(1.0);
                    c.positive(
                        "controller.integral_band",
                        *ct.integral_band.get_or_insert(default),
                    );
                }
                AntiWindupKind::BackCalculation => {
                    c.unused(
                        "controller.integral_limit_radps",
                        &ct.integral_limit_radps,
                        &why("back_calculation"),
                    );
                    c.unused(
                        "controller.integral_band",
                        &ct.integral_band,
                        &why("back_calculation"),
                    );
                    c.positive(
                        "controller.tracking_time_s",
                        *ct.tracking_time_s.get_or_insert(1.0),
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
    }
    match *ct
        .derivative
        .get_or_insert(DerivativeKindName::BackwardDifference)
    {
        DerivativeKindName::BackwardDifference => {
            let why = "to controller.derivative = \"backward_difference\"";
            c.unused("controller.derivative_tau_s", &ct.derivative_tau_s, why);
            c.unused(
                "controller.derivative_lipschitz",
                &ct.derivative_lipschitz,
                why,
            );
        }
        DerivativeKindName::FilteredDifference => {
            let why = "to controller.derivative = \"filtered_difference\"";
            c.unused(
                "controller.derivative_lipschitz",
                &ct.derivative_lipschitz,
                why,
            );
            c.positive(
                "controller.derivative_tau_s",
                *ct.derivative_tau_s.get_or_insert(0.1),
            );
        }
        DerivativeKindName::Levant => {
            let why = "to controller.derivative = \"levant\"";
            c.unused("controller.derivative_tau_s", &ct.derivative_tau_s, why);
            c.positive(
                "controller.derivative_lipschitz",
                *ct.derivative_lipschitz.get_or_insert(1.0),
            );
        }
    }

    // [metrics]
    let frac = *f.metrics.steady_state_fraction.get_or_insert(0.2);
    if c.finite("metrics.steady_state_fraction", frac) && !(frac > 0.0 && frac <= 1.0) {
        c.fail(
            "metrics.steady_state_fraction",
            format!("must be in (0, 1], got {frac}"),
        );
    }
    let level = f.controller.level.unwrap_or(0.0);
    let tol_default = if level != 0.0 && level.is_finite() {
        0.01 * level.abs()
    } else {
        0.01
    };
    c.positive(
        "metrics.convergence_tolerance",
        *f.metrics.convergence_tolerance.get_or_insert(tol_default),
    );

    // [output]
    let rec = *f.output.record_rate_hz.get_or_insert(10.0);
    c.non_negative("output.record_rate_hz", rec);
    if rec > 0.0 && rec.is_finite() && dt > 0.0 && dt.is_finite() {
        let n = 1.0 / (rec * dt);
        if n < 1.0 - 1e-9 || (n - n.round()).abs() > 1e-9 * n.round().max(1.0) {
            c.fail(
                "output.record_rate_hz",
                format!("the recording period must be a whole number (>= 1) of steps of sim.dt_s = {dt} s; got {rec} Hz"),
            );
        }
    }

    if c.issues.is_empty() {
        Ok(f)
    } else {
        Err(c.issues)
    }
}
