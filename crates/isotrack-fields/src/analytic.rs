//! Closed-form scalar fields with exact gradients and Hessians.

use isotrack_core::lanes;
use isotrack_core::math::{Mat2, Vec2};
use isotrack_core::{FieldDerivatives, ScalarField};

/// The paper's circular field (eq. (4)): `F(p) = i0*exp(-k*|p - p0|)`.
///
/// Level sets are circles about `p0`: the level `s` lies at radius `ln(i0/s)/k`. The gradient has
/// norm `k*F` and points to the source; the Hessian is
/// `F''*r r^T + F'/d*(I - r r^T)` with `F' = -k*F`, `F'' = k^2*F`, `r` the unit radial vector.
/// At the source itself the field is not differentiable (gradient and Hessian are `None`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadialExp {
    /// Peak value `i0` at the source (field units).
    pub i0: f64,
    /// Decay rate `k`, 1/m.
    pub decay_per_m: f64,
    /// Source position `p0`, metres.
    pub center_m: Vec2,
}

impl RadialExp {
    /// The field of the paper's Sec. VI-B: `20*exp(-0.1*|p|)`.
    pub fn paper() -> Self {
        Self {
            i0: 20.0,
            decay_per_m: 0.1,
            center_m: Vec2::new(0.0, 0.0),
        }
    }
    fn eval(&self, p: Vec2) -> f64 {
        self.i0 * lanes::exp(-self.decay_per_m * (p - self.center_m).norm())
    }
    fn grad(&self, p: Vec2) -> Option<Vec2> {
        let r = p - self.center_m;
        let d = r.norm();
        if d == 0.0 {
            return None;
        }
        let f = self.eval(p);
        Some(r * (-self.decay_per_m * f / d))
    }
    fn hess(&self, p: Vec2) -> Option<Mat2> {
        let r = p - self.center_m;
        let d = r.norm();
        if d == 0.0 {
            return None;
        }
        let f = self.eval(p);
        let k = self.decay_per_m;
        let (ux, uy) = (r.x / d, r.y / d);
        let f1 = -k * f;
        let f2 = k * k * f;
        let t = f1 / d;
        Some([
            [f2 * ux * ux + t * (1.0 - ux * ux), (f2 - t) * ux * uy],
            [(f2 - t) * ux * uy, f2 * uy * uy + t * (1.0 - uy * uy)],
        ])
    }
}

/// One anisotropic Gaussian source of a [`GaussianPlumes`] field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plume {
    /// Source centre, metres.
    pub center_m: Vec2,
    /// Peak amplitude above the background (field units; may be negative for a sink).
    pub amplitude: f64,
    /// Standard deviations along the plume's own axes, metres (> 0).
    pub sigma_m: [f64; 2],
    /// Rotation of the plume's first axis from +x, radians counter-clockwise.
    pub rotation_rad: f64,
}

impl Plume {
    /// `S^-1` with `S = R diag(sx^2, sy^2) R^T`.
    fn inverse_covariance(&self) -> Mat2 {
        let (s, c) = lanes::sin_cos(self.rotation_rad);
        let a = 1.0 / (self.sigma_m[0] * self.sigma_m[0]);
        let b = 1.0 / (self.sigma_m[1] * self.sigma_m[1]);
        // R diag(a, b) R^T
        [
            [a * c * c + b * s * s, (a - b) * c * s],
            [(a - b) * c * s, a * s * s + b * c * c],
        ]
    }
}

/// A sum of anisotropic Gaussian plumes over a background:
/// `F(p) = b + sum_i A_i*exp(-1/2 (p - c_i)^T S_i^-1 (p - c_i))`.
///
/// Gradient `-sum_i g_i S_i^-1 d_i` and Hessian `sum_i g_i (S_i^-1 d_i d_i^T S_i^-1 - S_i^-1)`,
/// with `g_i` the i-th term and `d_i = p - c_i`. With two or more overlapping sources the isolines
/// are non-circular and non-convex, like a PM2.5 map interpolated from a few hot spots.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussianPlumes {
    /// Background level (field units).
    pub background: f64,
    /// The sources.
    pub plumes: Vec<Plume>,
}

impl GaussianPlumes {
    fn terms(&self, p: Vec2) -> impl Iterator<Item = (f64, Vec2, Mat2)> + '_ {
        self.plumes.iter().map(move |pl| {
            let si = pl.inverse_covariance();
            let d = p - pl.center_m;
            let sd = Vec2::new(
                si[0][0] * d.x + si[0][1] * d.y,
                si[1][0] * d.x + si[1][1] * d.y,
            );
            let g = pl.amplitude * lanes::exp(-0.5 * d.dot(sd));
            (g, sd, si)
        })
    }
    fn eval(&self, p: Vec2) -> f64 {
        self.background + self.terms(p).map(|(g, _, _)| g).sum::<f64>()
    }
    fn grad(&self, p: Vec2) -> Vec2 {
        self.terms(p)
            .fold(Vec2::default(), |acc, (g, sd, _)| acc - sd * g)
    }
    fn hess(&self, p: Vec2) -> Mat2 {
        let mut h = [[0.0; 2]; 2];
        for (g, sd, si) in self.terms(p) {
            let v = [sd.x, sd.y];
            for i in 0..2 {
                for j in 0..2 {
                    h[i][j] += g * (v[i] * v[j] - si[i][j]);
                }
            }
        }
        h
    }
}

/// A linear ramp `F(p) = offset + g . p`: straight, parallel isolines; gradient `g`, Hessian 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearRamp {
    /// Value at the origin (field units).
    pub offset: f64,
    /// Gradient `g`, field units per metre.
    pub gradient_per_m: Vec2,
}

/// The analytic field kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum AnalyticKind {
    /// See [`RadialExp`].
    RadialExp(RadialExp),
    /// See [`GaussianPlumes`].
    GaussianPlumes(GaussianPlumes),
    /// See [`LinearRamp`].
    LinearRamp(LinearRamp),
}

/// An analytic field with an optional rectangular domain `[x_min, x_max, y_min, y_max]` (metres)
/// outside which it has no value (a vehicle that leaves it ends its run as `left_field`), and an
/// optional constant drift: the pattern moves at `drift_mps`,
/// `F(t, p) = F0(p - drift_mps * t)` (a plume carried by the wind; the domain stays put).
#[derive(Clone, Debug, PartialEq)]
pub struct AnalyticField {
    /// The closed form.
    pub kind: AnalyticKind,
    /// Optional domain `[x_min, x_max, y_min, y_max]`, metres.
    pub domain_m: Option<[f64; 4]>,
    /// Velocity of the pattern, m/s (zero: a static field).
    pub drift_mps: Vec2,
}

impl AnalyticField {
    /// An unbounded field.
    pub fn new(kind: AnalyticKind) -> Self {
        Self {
            kind,
            domain_m: None,
            drift_mps: Vec2::default(),
        }
    }
    /// The point of the static pattern seen at `p` at time `t`.
    #[inline]
    fn local(&self, t_s: f64, p: Vec2) -> Vec2 {
        if self.drift_mps == Vec2::default() {
            p
        } else {
            p - self.drift_mps * t_s
        }
    }
    fn inside(&self, p: Vec2) -> bool {
        match self.domain_m {
            None => p.is_finite(),
            Some([x0, x1, y0, y1]) => p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1,
        }
    }
}

impl ScalarField for AnalyticField {
    #[inline]
    fn value(&self, t_s: f64, p: Vec2) -> Option<f64> {
        if !self.inside(p) {
            return None;
        }
        let p = self.local(t_s, p);
        let v = match &self.kind {
            AnalyticKind::RadialExp(f) => f.eval(p),
            AnalyticKind::GaussianPlumes(f) => f.eval(p),
            AnalyticKind::LinearRamp(f) => f.offset + f.gradient_per_m.dot(p),
        };
        v.is_finite().then_some(v)
    }

    /// The formulas of [`value`](ScalarField::value) in lanes: `exp` vectorises, the numbers
    /// are `value`'s bit for bit (the same operations in the same order; `NaN` for `None`).
    #[inline(always)]
    fn value_lanes<const N: usize>(&self, t_s: f64, x: &[f64; N], y: &[f64; N]) -> [f64; N] {
        let mut px = *x;
        let mut py = *y;
        let mut inside = [true; N];
        for i in 0..N {
            inside[i] = self.inside(Vec2::new(x[i], y[i]));
            let p = self.local(t_s, Vec2::new(x[i], y[i]));
            (px[i], py[i]) = (p.x, p.y);
        }
        let mut v = [0.0; N];
        match &self.kind {
            AnalyticKind::RadialExp(f) => {
                let mut arg = [0.0; N];
                for i in 0..N {
                    arg[i] = -f.decay_per_m * (Vec2::new(px[i], py[i]) - f.center_m).norm();
                }
                let e = lanes::exp_lanes(arg);
                for i in 0..N {
                    v[i] = f.i0 * e[i];
                }
            }
            AnalyticKind::GaussianPlumes(f) => {
                // The same sum as `terms`: background + term_1 + term_2 + ... in order.
                let mut terms = [0.0; N];
                v = [f.background; N];
                let mut first = true;
                for pl in &f.plumes {
                    let si = pl.inverse_covariance();
                    let mut arg = [0.0; N];
                    for i in 0..N {
                        let d = Vec2::new(px[i], py[i]) - pl.center_m;
                        let sd = Vec2::new(
                            si[0][0] * d.x + si[0][1] * d.y,
                            si[1][0] * d.x + si[1][1] * d.y,
                        );
                        arg[i] = -0.5 * d.dot(sd);
                    }
                    let e = lanes::exp_lanes(arg);
                    for i in 0..N {
                        let g = pl.amplitude * e[i];
                        terms[i] = if first { g } else { terms[i] + g };
                    }
                    first = false;
                }
                if !first {
                    for i in 0..N {
                        v[i] += terms[i];
                    }
                }
            }
            AnalyticKind::LinearRamp(f) => {
                for i in 0..N {
                    v[i] = f.offset + f.gradient_per_m.dot(Vec2::new(px[i], py[i]));
                }
            }
        }
        for i in 0..N {
            if !(inside[i] && v[i].is_finite()) {
                v[i] = f64::NAN;
            }
        }
        v
    }
}

impl FieldDerivatives for AnalyticField {
    fn gradient(&self, t_s: f64, p: Vec2) -> Option<Vec2> {
        if !self.inside(p) {
            return None;
        }
        let p = self.local(t_s, p);
        match &self.kind {
            AnalyticKind::RadialExp(f) => f.grad(p),
            AnalyticKind::GaussianPlumes(f) => Some(f.grad(p)),
            AnalyticKind::LinearRamp(f) => Some(f.gradient_per_m),
        }
    }
    fn hessian(&self, t_s: f64, p: Vec2) -> Option<Mat2> {
        if !self.inside(p) {
            return None;
        }
        let p = self.local(t_s, p);
        match &self.kind {
            AnalyticKind::RadialExp(f) => f.hess(p),
            AnalyticKind::GaussianPlumes(f) => Some(f.hess(p)),
            AnalyticKind::LinearRamp(_) => Some([[0.0; 2]; 2]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn plumes() -> AnalyticField {
        AnalyticField::new(AnalyticKind::GaussianPlumes(GaussianPlumes {
            background: 1.0,
            plumes: vec![
                Plume {
                    center_m: Vec2::new(0.0, 0.0),
                    amplitude: 20.0,
                    sigma_m: [12.0, 6.0],
                    rotation_rad: 0.4,
                },
                Plume {
                    center_m: Vec2::new(15.0, 8.0),
                    amplitude: 12.0,
                    sigma_m: [5.0, 9.0],
                    rotation_rad: -0.3,
                },
            ],
        }))
    }

    fn fields() -> Vec<AnalyticField> {
        vec![
            AnalyticField::new(AnalyticKind::RadialExp(RadialExp {
                i0: 20.0,
                decay_per_m: 0.1,
                center_m: Vec2::new(1.0, -2.0),
            })),
            plumes(),
            AnalyticField::new(AnalyticKind::LinearRamp(LinearRamp {
                offset: 3.0,
                gradient_per_m: Vec2::new(0.5, -0.25),
            })),
        ]
    }

    /// Central differences of `value` (independent of the closed-form gradient).
    fn fd_grad(f: &AnalyticField, p: Vec2, h: f64) -> Vec2 {
        let v = |q: Vec2| f.value(0.0, q).unwrap();
        Vec2::new(
            (v(p + Vec2::new(h, 0.0)) - v(p - Vec2::new(h, 0.0))) / (2.0 * h),
            (v(p + Vec2::new(0.0, h)) - v(p - Vec2::new(0.0, h))) / (2.0 * h),
        )
    }

    proptest! {
        #[test]
        fn gradient_matches_finite_differences(x in -30.0..30.0f64, y in -30.0..30.0f64) {
            for f in fields() {
                let p = Vec2::new(x, y);
                if let Some(g) = f.gradient(0.0, p) {
                    let fd = fd_grad(&f, p, 1e-5);
                    let scale = 1.0 + g.norm();
                    prop_assert!((g - fd).norm() < 1e-6 * scale, "{:?} vs {:?}", g, fd);
                }
            }
        }

        #[test]
        fn hessian_matches_finite_differences_of_gradient(x in -30.0..30.0f64, y in -30.0..30.0f64) {
            for f in fields() {
                let p = Vec2::new(x, y);
                let h = 1e-5;
                if (p - Vec2::new(1.0, -2.0)).norm() < 1e-3 { continue; }
                // Defined everywhere but at a radial field's centre (excluded above).
                let hs = f.hessian(0.0, p);
                prop_assert!(hs.is_some(), "no Hessian at {:?}", p);
                if let Some(hs) = hs {
                    let gx = (f.gradient(0.0, p + Vec2::new(h, 0.0)).unwrap() - f.gradient(0.0, p - Vec2::new(h, 0.0)).unwrap()) * (0.5 / h);
                    let gy = (f.gradient(0.0, p + Vec2::new(0.0, h)).unwrap() - f.gradient(0.0, p - Vec2::new(0.0, h)).unwrap()) * (0.5 / h);
                    let scale = 1.0 + hs[0][0].abs() + hs[1][1].abs() + hs[0][1].abs();
                    prop_assert!((hs[0][0] - gx.x).abs() < 1e-5 * scale);
                    prop_assert!((hs[0][1] - gx.y).abs() < 1e-5 * scale);
                    prop_assert!((hs[1][0] - gy.x).abs() < 1e-5 * scale);
                    prop_assert!((hs[1][1] - gy.y).abs() < 1e-5 * scale);
                }
            }
        }
    }

    #[test]
    fn paper_field_level_10_is_at_10_ln2() {
        let f = AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()));
        let r = 10.0 * std::f64::consts::LN_2;
        for k in 0..8 {
            let a = k as f64 * 0.7;
            let v = f.value(0.0, Vec2::from_angle(a) * r).unwrap();
            assert!((v - 10.0).abs() < 1e-12);
        }
    }

    #[test]
    fn drift_moves_the_pattern() {
        let mut f = AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()));
        f.drift_mps = Vec2::new(0.5, -0.2);
        // At t = 10 s the source is at (5, -2).
        assert_eq!(f.value(10.0, Vec2::new(5.0, -2.0)), Some(20.0));
        assert_eq!(f.value(0.0, Vec2::new(0.0, 0.0)), Some(20.0));
        let g = f.gradient(10.0, Vec2::new(8.0, -2.0)).unwrap();
        assert!(
            g.x < 0.0 && g.y.abs() < 1e-12,
            "points back to the moved source: {g:?}"
        );
    }

    #[test]
    fn domain_bounds_the_field() {
        let mut f = fields().remove(2);
        f.domain_m = Some([-1.0, 1.0, -1.0, 1.0]);
        assert!(f.value(0.0, Vec2::new(0.5, 0.5)).is_some());
        assert!(f.value(0.0, Vec2::new(1.5, 0.5)).is_none());
        assert!(f.gradient(0.0, Vec2::new(1.5, 0.5)).is_none());
        assert!(f.value(0.0, Vec2::new(f64::NAN, 0.5)).is_none());
    }

    /// The plumes by the textbook formula, written independently of `inverse_covariance`:
    /// `b + sum A exp(-(u^2/sx^2 + v^2/sy^2)/2)` with `(u, v)` the offset in the plume's own
    /// axes, `u = cos(r) dx + sin(r) dy`, `v = -sin(r) dx + cos(r) dy`.
    #[test]
    fn plume_values_by_hand() {
        let f = plumes();
        let AnalyticKind::GaussianPlumes(g) = &f.kind else {
            unreachable!()
        };
        for (x, y) in [
            (0.0, 0.0),
            (3.0, -2.0),
            (15.0, 8.0),
            (7.5, 4.0),
            (-20.0, 11.0),
        ] {
            let mut want = g.background;
            for pl in &g.plumes {
                let (dx, dy) = (x - pl.center_m.x, y - pl.center_m.y);
                let (sr, cr) = (pl.rotation_rad.sin(), pl.rotation_rad.cos());
                let (u, v) = (cr * dx + sr * dy, -sr * dx + cr * dy);
                let q = (u / pl.sigma_m[0]).powi(2) + (v / pl.sigma_m[1]).powi(2);
                want += pl.amplitude * (-0.5 * q).exp();
            }
            let got = f.value(0.0, Vec2::new(x, y)).unwrap();
            assert!(
                (got - want).abs() < 1e-12 * want.abs(),
                "({x}, {y}): {got} vs {want}"
            );
        }
        // At a source: the background plus its amplitude plus the other plume's tail.
        let at0 = f.value(0.0, Vec2::new(0.0, 0.0)).unwrap();
        assert!(at0 > 21.0 && at0 < 21.0 + 12.0, "{at0}");
        // The radial field's Hessian in closed form at (d, 0) from its centre: f'' = k^2 F
        // along the radius, f'/d = -k F/d across it.
        let r = fields().remove(0);
        let (d, k) = (5.0f64, 0.1f64);
        let fv = 20.0 * (-k * d).exp();
        let h = r.hessian(0.0, Vec2::new(1.0 + d, -2.0)).unwrap();
        assert!((h[0][0] - k * k * fv).abs() < 1e-12);
        assert!((h[1][1] + k * fv / d).abs() < 1e-12);
        assert!(h[0][1].abs() < 1e-15 && h[1][0].abs() < 1e-15);
        assert!(
            r.hessian(0.0, Vec2::new(1.0, -2.0)).is_none(),
            "undefined at the centre"
        );
    }

    /// The lanes form is the scalar one, bit for bit, for every kind, with a domain and a
    /// drift, and NaN where the field has no value.
    #[test]
    fn value_lanes_equal_value_bit_for_bit() {
        let xs = [0.0, 3.5, -12.0, 15.0, 1.0, 40.0, f64::NAN, -0.7];
        let ys = [0.0, -2.0, 9.0, 8.0, -2.0, 1.0, 0.0, 33.0];
        for mut f in fields() {
            for (domain, drift) in [
                (None, Vec2::default()),
                (Some([-20.0, 20.0, -20.0, 20.0]), Vec2::new(0.3, -0.1)),
            ] {
                f.domain_m = domain;
                f.drift_mps = drift;
                for t in [0.0, 7.0] {
                    let lanes = f.value_lanes(t, &xs, &ys);
                    for i in 0..8 {
                        let one = f.value(t, Vec2::new(xs[i], ys[i])).unwrap_or(f64::NAN);
                        assert_eq!(lanes[i].to_bits(), one.to_bits(), "{:?} lane {i}", f.kind);
                    }
                }
            }
        }
        // A field without plumes is its background, as `value` says.
        let empty = AnalyticField::new(AnalyticKind::GaussianPlumes(GaussianPlumes {
            background: 2.5,
            plumes: vec![],
        }));
        assert_eq!(empty.value_lanes(0.0, &[1.0], &[2.0]), [2.5]);
        assert_eq!(empty.value(0.0, Vec2::new(1.0, 2.0)), Some(2.5));
    }
}
