//! `isotrack check`: the paper's theory applied to a scenario, before flying it.
//!
//! * Prop. 1 (circular fields, `radial_exp`): the paper's sufficient conditions and the exact
//!   Routh-Hurwitz local condition, reported separately ([`isotrack_core::theory`]). The slope
//!   `alpha` is the field's radial slope on the isoline, `|dF/dd| = k*s_d` for
//!   `F = i0*exp(-k*d)` (the linearisation depends only on it).
//! * Prop. 2 (any smooth field, `ki = 0`): `gamma1, gamma2, gamma3` are estimated from the
//!   field's own gradient and Hessian on a 601 x 601 lattice over the operating region, keeping
//!   the points of the tube `|F - s_d| <= tube_halfwidth` (default `c2`, the linear zone of
//!   `tanh`) connected to the start, i.e. round the isoline the vehicle will reach first. The
//!   angle margin `phi` is chosen for each purpose: `min_kp` minimises the gain requirement over
//!   `phi`; `error_bound` uses the largest `phi` at which the scenario's `kp` meets the
//!   conditions (the bound shrinks as `sin(phi)` grows). The unit-consistent form is reported as
//!   `min_kp` / `error_bound`, the paper's printed form alongside (they agree when `c2 = 1`).

use crate::field::FieldModel;
use crate::schema::FieldKind;
use crate::Scenario;
use isotrack_core::math::{sym_spectral_norm, Vec2};
use isotrack_core::theory::{
    prop1_characteristic_polynomial, prop1_exact_local_condition, prop1_paper_conditions,
    prop2_error_bound, prop2_min_kp, prop2_paper_min_kp, radial_exp_isoline_radius_m, FieldBounds,
};
use isotrack_core::{FieldDerivatives, ScalarField};
use isotrack_fields::AnalyticKind;
use serde::Serialize;

/// Prop. 1 report. All `None` when the field is not circular.
#[derive(Clone, Debug, Serialize)]
pub struct Prop1Report {
    /// Whether Prop. 1 applies (a `radial_exp` field).
    pub applicable: bool,
    /// Radial slope on the isoline, field units per metre.
    pub alpha: Option<f64>,
    /// Isoline radius `r_d`, m.
    pub r_d_m: Option<f64>,
    /// `kp(kp - 2) v alpha > ki` and `v alpha > c1`.
    pub paper_conditions_hold: Option<bool>,
    /// Routh-Hurwitz on the linearisation (necessary and sufficient locally).
    pub exact_local_condition_holds: Option<bool>,
    /// `[a2, a1, a0]` of `l^3 + a2 l^2 + a1 l + a0`.
    pub characteristic_polynomial: Option<[f64; 3]>,
    /// Why not applicable, or remarks.
    pub note: String,
}

impl Prop1Report {
    fn not_applicable(note: String) -> Self {
        Self {
            applicable: false,
            alpha: None,
            r_d_m: None,
            paper_conditions_hold: None,
            exact_local_condition_holds: None,
            characteristic_polynomial: None,
            note,
        }
    }
}

/// Prop. 2 report.
#[derive(Clone, Debug, Serialize)]
pub struct Prop2Report {
    /// Prop. 2 is stated for `ki = 0`.
    pub applicable: bool,
    /// Half-width of the tube `|F - s_d| <= tube_halfwidth` the bounds are taken over.
    pub tube_halfwidth: f64,
    /// Lattice points of the tube component round the target isoline.
    pub samples_in_tube: usize,
    /// `min |grad F|` in the tube.
    pub gamma1: Option<f64>,
    /// `max |grad F|` in the tube.
    pub gamma2: Option<f64>,
    /// `max ||hess F||` in the tube.
    pub gamma3: Option<f64>,
    /// The scenario's gains meet the (unit-consistent) conditions at some angle margin.
    pub conditions_hold: bool,
    /// Predicted `limsup |eps|` (null when the conditions fail).
    pub error_bound: Option<f64>,
    /// The angle margin used for `error_bound`, rad.
    pub error_bound_phi_rad: Option<f64>,
    /// The smallest `kp` meeting the conditions (over all angle margins).
    pub min_kp: Option<f64>,
    /// The angle margin that gives `min_kp`, rad.
    pub min_kp_phi_rad: Option<f64>,
    /// `min_kp` by the paper's printed form.
    pub paper_min_kp: Option<f64>,
    /// `error_bound` by the paper's printed form (at `error_bound_phi_rad`).
    pub paper_error_bound: Option<f64>,
    /// The initial angle `phi(t0)` between `-grad F` and the heading (paper Fig. 1(c)), rad.
    pub initial_phi_rad: Option<f64>,
    /// Whether `phi(t0)` lies in the sector `[-pi + phi, -phi]` the proposition assumes (at
    /// `error_bound_phi_rad`).
    pub initial_heading_in_sector: Option<bool>,
    /// Remarks.
    pub note: String,
}

/// The full report.
#[derive(Clone, Debug, Serialize)]
pub struct CheckReport {
    /// Prop. 1.
    pub prop1: Prop1Report,
    /// Prop. 2.
    pub prop2: Prop2Report,
}

/// The region over which the field is sampled: the grid, the domain, or a box round the
/// analytic field's features and the start.
fn region(s: &Scenario) -> [f64; 4] {
    let f = s.file();
    let start = Vec2::new(f.initial.x_m.unwrap_or(0.0), f.initial.y_m.unwrap_or(0.0));
    let grow = |mut r: [f64; 4], p: Vec2, m: f64| {
        r[0] = r[0].min(p.x - m);
        r[1] = r[1].max(p.x + m);
        r[2] = r[2].min(p.y - m);
        r[3] = r[3].max(p.y + m);
        r
    };
    let empty = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    match s.field() {
        FieldModel::Grid(g) => g.grid().extent_m(),
        FieldModel::Analytic(a) => {
            if let Some(d) = a.domain_m {
                return d;
            }
            match &a.kind {
                AnalyticKind::RadialExp(r) => {
                    let rd =
                        radial_exp_isoline_radius_m(r.i0, r.decay_per_m, s.level()).unwrap_or(10.0);
                    grow(grow(empty, r.center_m, 3.0 * rd), start, 1.0)
                }
                AnalyticKind::GaussianPlumes(p) => {
                    p.plumes.iter().fold(grow(empty, start, 1.0), |r, pl| {
                        grow(r, pl.center_m, 4.0 * pl.sigma_m[0].max(pl.sigma_m[1]))
                    })
                }
                AnalyticKind::LinearRamp(_) => grow(empty, start, 100.0),
            }
        }
    }
}

/// Samples the field's bounds over the part of the tube `|F - s_d| <= tube` connected to the
/// start: lattice points in the tube, flood-filled (4-neighbours) from the tube point nearest the
/// start, so other components of the level set (other peaks, saddles elsewhere) do not count.
fn tube_bounds(
    field: &FieldModel,
    region: [f64; 4],
    start: Vec2,
    level: f64,
    tube: f64,
) -> (Option<FieldBounds>, usize) {
    const N: usize = 601;
    let at = |i: usize, j: usize| {
        Vec2::new(
            region[0] + (region[1] - region[0]) * i as f64 / (N - 1) as f64,
            region[2] + (region[3] - region[2]) * j as f64 / (N - 1) as f64,
        )
    };
    let mut in_tube = vec![false; N * N];
    let mut seed: Option<(usize, f64)> = None;
    for j in 0..N {
        for i in 0..N {
            let p = at(i, j);
            if field
                .value(0.0, p)
                .is_some_and(|v| (v - level).abs() <= tube)
            {
                in_tube[j * N + i] = true;
                let d = (p - start).norm();
                if seed.is_none_or(|(_, best)| d < best) {
                    seed = Some((j * N + i, d));
                }
            }
        }
    }
    let Some((seed, _)) = seed else {
        return (None, 0);
    };
    let mut seen = vec![false; N * N];
    let mut stack = vec![seed];
    seen[seed] = true;
    let (mut g1, mut g2, mut g3, mut n) = (f64::INFINITY, 0.0f64, 0.0f64, 0usize);
    while let Some(k) = stack.pop() {
        let (i, j) = (k % N, k / N);
        let p = at(i, j);
        if let (Some(g), Some(h)) = (field.gradient(0.0, p), field.hessian(0.0, p)) {
            n += 1;
            g1 = g1.min(g.norm());
            g2 = g2.max(g.norm());
            g3 = g3.max(sym_spectral_norm(&h));
        }
        let mut push = |q: usize| {
            if in_tube[q] && !seen[q] {
                seen[q] = true;
                stack.push(q);
            }
        };
        if i > 0 {
            push(k - 1);
        }
        if i + 1 < N {
            push(k + 1);
        }
        if j > 0 {
            push(k - N);
        }
        if j + 1 < N {
            push(k + N);
        }
    }
    (
        (n > 0).then_some(FieldBounds {
            gamma1: g1,
            gamma2: g2,
            gamma3: g3,
        }),
        n,
    )
}

/// Runs the checks; `tube_halfwidth` defaults to `c2`.
pub fn check(s: &Scenario, tube_halfwidth: Option<f64>) -> CheckReport {
    let f = s.file();
    let c = &f.controller;
    let (kp, ki, c1, c2) = (
        c.kp.unwrap_or(0.0),
        c.ki.unwrap_or(0.0),
        c.c1.unwrap_or(0.0),
        c.c2.unwrap_or(1.0),
    );
    // The speed the law sees: the Dubins robot's, or the UAV's airspeed (its ground speed in
    // calm air; the propositions are for a unicycle, which the autopilot only approximates).
    let v = f
        .vehicle
        .speed_mps
        .or(f.vehicle.airspeed_mps)
        .unwrap_or(0.0);
    let level = s.level();

    // Prop. 1
    let prop1 = match (f.field.kind, s.field()) {
        (Some(FieldKind::RadialExp), FieldModel::Analytic(a)) => {
            let AnalyticKind::RadialExp(r) = &a.kind else {
                unreachable!("radial_exp builds RadialExp")
            };
            match radial_exp_isoline_radius_m(r.i0, r.decay_per_m, level) {
                Some(rd) => {
                    let alpha = r.decay_per_m * level;
                    Prop1Report {
                        applicable: true,
                        alpha: Some(alpha),
                        r_d_m: Some(rd),
                        paper_conditions_hold: Some(prop1_paper_conditions(alpha, v, kp, ki, c1)),
                        exact_local_condition_holds: Some(prop1_exact_local_condition(alpha, v, rd, kp, ki, c1, c2)),
                        characteristic_polynomial: Some(prop1_characteristic_polynomial(alpha, v, rd, kp, ki, c1, c2)),
                        note: "alpha = k*s_d, the radial slope on the isoline; the paper's conditions are sufficient, the Routh-Hurwitz one is exact (locally)".into(),
                    }
                }
                None => Prop1Report::not_applicable(format!(
                    "level {level} is not attained by the field (0 < level < i0 is needed)"
                )),
            }
        }
        _ => Prop1Report::not_applicable(
            "Prop. 1 is for circular fields (field.kind = \"radial_exp\")".into(),
        ),
    };

    // Prop. 2
    let tube = tube_halfwidth.unwrap_or(c2);
    let p0 = Vec2::new(f.initial.x_m.unwrap_or(0.0), f.initial.y_m.unwrap_or(0.0));
    let (bounds, n) = tube_bounds(s.field(), region(s), p0, level, tube);
    let phis: Vec<f64> = (1..1000)
        .map(|k| k as f64 * std::f64::consts::FRAC_PI_2 / 1000.0)
        .collect();
    let mut rep = Prop2Report {
        applicable: ki == 0.0,
        tube_halfwidth: tube,
        samples_in_tube: n,
        gamma1: bounds.map(|b| b.gamma1),
        gamma2: bounds.map(|b| b.gamma2),
        gamma3: bounds.map(|b| b.gamma3),
        conditions_hold: false,
        error_bound: None,
        error_bound_phi_rad: None,
        min_kp: None,
        min_kp_phi_rad: None,
        paper_min_kp: None,
        paper_error_bound: None,
        initial_phi_rad: None,
        initial_heading_in_sector: None,
        note: String::new(),
    };
    let Some(b) = bounds else {
        rep.note = format!(
            "no lattice point has |F - s_d| <= {tube}: the level is not attained in the region"
        );
        return CheckReport { prop1, prop2: rep };
    };
    let best = phis
        .iter()
        .filter_map(|&phi| prop2_min_kp(&b, v, c1, c2, phi).map(|k| (k, phi)))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    rep.min_kp = best.map(|x| x.0);
    rep.min_kp_phi_rad = best.map(|x| x.1);
    rep.paper_min_kp = phis
        .iter()
        .filter_map(|&phi| prop2_paper_min_kp(&b, v, kp, c1, c2, phi).0)
        .min_by(|a, b| a.total_cmp(b));
    // The largest margin at which kp works gives the tightest bound.
    if let Some(&phi) = phis
        .iter()
        .rev()
        .find(|&&phi| prop2_error_bound(&b, v, kp, c1, c2, phi).is_some())
    {
        rep.error_bound_phi_rad = Some(phi);
        rep.paper_error_bound = prop2_paper_min_kp(&b, v, kp, c1, c2, phi).1;
        if rep.applicable {
            rep.conditions_hold = true;
            rep.error_bound = prop2_error_bound(&b, v, kp, c1, c2, phi);
        }
    }
    // The initial heading condition phi(t0) in [-pi + phi, -phi].
    if let Some(g) = s.field().gradient(0.0, p0).filter(|g| g.norm() > 0.0) {
        let h = Vec2::from_angle(f.initial.heading_rad.unwrap_or(0.0));
        let minus_n = -g;
        // Signed angle from -grad F to h, counter-clockwise positive; the paper's law as printed
        // (higher values on the right) wants phi in (-pi, 0); mirror for "left".
        let mut phi0 = minus_n.cross(h).atan2(minus_n.dot(h));
        if c.higher_side == Some(isotrack_core::control::HigherSide::Left) {
            phi0 = -phi0;
        }
        rep.initial_phi_rad = Some(phi0);
        if let Some(m) = rep.error_bound_phi_rad {
            rep.initial_heading_in_sector = Some(phi0 <= -m && phi0 >= -std::f64::consts::PI + m);
        }
    }
    let mut notes = vec![];
    if !rep.applicable {
        notes
            .push("Prop. 2 is stated for ki = 0; the numbers are for the P part alone".to_string());
    }
    if v * b.gamma1 <= c1 {
        notes.push(format!(
            "v*gamma1 = {:.4} <= c1 = {c1}: somewhere in the tube the sliding surface cannot be reached (decrease c1 or the tube)",
            v * b.gamma1
        ));
    }
    if let Some(eb) = rep.error_bound {
        if eb > tube {
            notes.push(format!("the bound {eb:.4} exceeds the tube {tube}: the gammas may not hold along the orbit"));
        }
    }
    if c2 != 1.0 {
        notes.push("c2 != 1: the paper's printed form differs from the unit-consistent one (paper_* fields)".into());
    }
    rep.note = notes.join("; ");
    CheckReport { prop1, prop2: rep }
}
