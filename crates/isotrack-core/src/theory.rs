//! Closed forms from the paper and from our derivations (docs/BASELINES.md,
//! section 0), usable on board (`no_std`) and as independent oracles in tests.
//!
//! Notation: Dubins robot at speed `v`, circular field with isoline radius `r_d` and radial slope
//! `alpha = |dF/dd|` at `r_d`, the PI-like law with gains `kp, ki, c1, c2`.

/// Radius of the level-`level` isoline of `F = i0*exp(-k*d)`: `r = ln(i0/level)/k`, or `None`
/// if the level is not attained (`level <= 0` or `level >= i0`) or `k <= 0`.
pub fn radial_exp_isoline_radius_m(i0: f64, decay_per_m: f64, level: f64) -> Option<f64> {
    if !(level > 0.0 && level < i0 && decay_per_m > 0.0) {
        return None;
    }
    Some(crate::fmath::ln(i0 / level) / decay_per_m)
}

/// The orbit the P-like law (`ki = 0`) settles on in a circular field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircularOrbit {
    /// Orbit radius `d*`, metres.
    pub radius_m: f64,
    /// Steady tracking error `eps* = F(d*) - s_d` (field units; negative: the orbit lies outside
    /// the isoline, on the lower side).
    pub error: f64,
}

/// Steady orbit of the P-like law (`ki = 0`, direction as printed) on `F = i0*exp(-k*d)`.
///
/// On a circular orbit of radius `d` the measurement is constant, so `eps' = 0` and the turn rate
/// must equal the orbit's `-v/d` (clockwise): `kp*c1*tanh(eps*/c2) = -v/d*`, that is
///
/// ```text
/// |eps*| = c2*atanh(v/(kp*c1*d*)),   eps* = F(d*) - s_d,
/// ```
///
/// (baselines.md section 0, derived for the linear radial profile; it holds for any decreasing
/// radial profile because only `F(d*)` enters). Solved for `d*` by bisection on
/// `g(d) = c1*tanh((F(d) - s_d)/c2) + v/(kp*d)`, strictly decreasing for `d > r_d` with
/// `g(r_d) > 0`. Returns `None` when no orbit exists (`kp*c1*d* <= v` everywhere, or invalid
/// parameters).
pub fn radial_exp_p_orbit(
    i0: f64,
    decay_per_m: f64,
    level: f64,
    speed_mps: f64,
    kp: f64,
    c1: f64,
    c2: f64,
) -> Option<CircularOrbit> {
    let r_d = radial_exp_isoline_radius_m(i0, decay_per_m, level)?;
    if !(speed_mps > 0.0 && kp > 0.0 && c1 > 0.0 && c2 > 0.0) {
        return None;
    }
    // g(d) = c1*tanh((F(d) - s_d)/c2) + v/(kp*d). At d = r_d, g = v/(kp*r_d) > 0. As d grows,
    // F(d) - s_d decreases to -s_d, so g tends to c1*tanh(-s_d/c2) < 0 if that beats v/(kp*d).
    // g is strictly decreasing for d > r_d (both terms decrease), so the root is unique.
    let g = |d: f64| {
        c1 * crate::fmath::tanh((i0 * crate::fmath::exp(-decay_per_m * d) - level) / c2)
            + speed_mps / (kp * d)
    };
    let mut lo = r_d;
    let mut hi = r_d.max(1e-9);
    let mut found = false;
    for _ in 0..200 {
        hi *= 2.0;
        if g(hi) < 0.0 {
            found = true;
            break;
        }
    }
    if !found {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let d = 0.5 * (lo + hi);
    Some(CircularOrbit {
        radius_m: d,
        error: i0 * crate::fmath::exp(-decay_per_m * d) - level,
    })
}

/// Coefficients `[a2, a1, a0]` of the characteristic polynomial `l^3 + a2*l^2 + a1*l + a0` of the
/// PI-like law linearised about the tracking orbit of a circular field (`ki > 0`; baselines.md
/// section 0, from the paper's Jacobian `A` in the proof of Prop. 1):
///
/// ```text
/// a2 = kp*alpha*v,  a1 = alpha*v*kp*c1/c2 + alpha*v*ki + v^2/r_d^2,  a0 = alpha*v*ki*c1/c2.
/// ```
pub fn prop1_characteristic_polynomial(
    alpha: f64,
    speed_mps: f64,
    r_d_m: f64,
    kp: f64,
    ki: f64,
    c1: f64,
    c2: f64,
) -> [f64; 3] {
    let av = alpha * speed_mps;
    [
        kp * av,
        av * kp * c1 / c2 + av * ki + speed_mps * speed_mps / (r_d_m * r_d_m),
        av * ki * c1 / c2,
    ]
}

/// Exact local (Routh-Hurwitz) stability condition of the tracking orbit on a circular field:
/// `kp*(alpha*v*(c1/c2)*kp + alpha*v*ki + v^2/r_d^2) > ki*c1/c2` (i.e. `a2*a1 > a0` with all
/// coefficients positive). Necessary and sufficient for local exponential stability; any `kp > 0`
/// works when `ki = 0`. (baselines.md section 0.)
pub fn prop1_exact_local_condition(
    alpha: f64,
    speed_mps: f64,
    r_d_m: f64,
    kp: f64,
    ki: f64,
    c1: f64,
    c2: f64,
) -> bool {
    let [a2, a1, a0] = prop1_characteristic_polynomial(alpha, speed_mps, r_d_m, kp, ki, c1, c2);
    if ki == 0.0 {
        return a2 > 0.0 && a1 > 0.0;
    }
    a2 > 0.0 && a1 > 0.0 && a0 > 0.0 && a2 * a1 > a0
}

/// The paper's Prop. 1 sufficient conditions: `kp*(kp - 2)*v*alpha_min > ki` and
/// `v*alpha_min > c1 > 0`. Sufficient, not necessary (baselines.md section 0).
pub fn prop1_paper_conditions(alpha_min: f64, speed_mps: f64, kp: f64, ki: f64, c1: f64) -> bool {
    kp * (kp - 2.0) * speed_mps * alpha_min > ki && speed_mps * alpha_min > c1 && c1 > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn isoline_radius_of_paper_field() {
        // 20 exp(-0.1 d) = 10 at d = 10 ln 2.
        let r = radial_exp_isoline_radius_m(20.0, 0.1, 10.0).unwrap();
        assert_relative_eq!(r, 10.0 * core::f64::consts::LN_2, epsilon = 1e-12);
    }

    #[test]
    fn orbit_satisfies_the_balance() {
        let o = radial_exp_p_orbit(20.0, 0.1, 10.0, 0.5, 10.0, 0.2, 1.0).unwrap();
        // kp*c1*tanh(eps/c2) = -v/d
        assert_relative_eq!(
            10.0 * 0.2 * crate::fmath::tanh(o.error),
            -0.5 / o.radius_m,
            epsilon = 1e-12
        );
        assert!(o.error < 0.0 && o.radius_m > 10.0 * core::f64::consts::LN_2);
    }

    #[test]
    fn paper_conditions_imply_exact_ones() {
        // baselines.md: kp = 1, ki = 0.05, c1 = 0.5, c2 = 1, v = alpha = 1, r_d = 10 violates the
        // paper's condition but satisfies the exact one; kp = ki = 0.05 violates the exact one.
        assert!(!prop1_paper_conditions(1.0, 1.0, 1.0, 0.05, 0.5));
        assert!(prop1_exact_local_condition(
            1.0, 1.0, 10.0, 1.0, 0.05, 0.5, 1.0
        ));
        assert!(!prop1_exact_local_condition(
            1.0, 1.0, 10.0, 0.05, 0.05, 0.5, 1.0
        ));
    }

    /// Prop. 1's polynomial by hand (alpha = 1, v = 0.5, r_d = ln 2 / 0.1, the paper's gains):
    /// `s^3 + kp a v s^2 + (a v kp c1/c2 + a v ki + v^2/r_d^2) s + a v ki c1/c2`.
    #[test]
    fn prop1_polynomial_and_conditions_by_hand() {
        let r = 2f64.ln() / 0.1;
        let [a2, a1, a0] = prop1_characteristic_polynomial(1.0, 0.5, r, 10.0, 1.0, 0.2, 2.0);
        assert_eq!(a2, 10.0 * 0.5);
        assert!((a1 - (0.5 * 10.0 * 0.2 / 2.0 + 0.5 * 1.0 + 0.25 / (r * r))).abs() < 1e-15);
        assert!((a0 - 0.5 * 1.0 * 0.2 / 2.0).abs() < 1e-15);
        // Routh-Hurwitz for s^3 + a2 s^2 + a1 s + a0: all positive and a2 a1 > a0.
        assert!(prop1_exact_local_condition(
            1.0, 0.5, r, 10.0, 1.0, 0.2, 2.0
        ));
        // a2 a1 < a0: kp tiny, ki large.
        assert!(!prop1_exact_local_condition(
            1.0, 0.5, r, 0.01, 100.0, 0.2, 1.0
        ));
        // ki = 0: the second-order conditions only (a0 = 0 is no failure).
        assert!(prop1_exact_local_condition(
            1.0, 0.5, r, 10.0, 0.0, 0.2, 1.0
        ));
        assert!(!prop1_exact_local_condition(
            1.0, 0.5, r, -1.0, 0.0, 0.2, 1.0
        ));
        // The paper's sufficient conditions: kp (kp - 2) v a > ki, v a > c1 > 0.
        assert!(prop1_paper_conditions(1.0, 0.5, 10.0, 1.0, 0.2));
        assert!(!prop1_paper_conditions(1.0, 0.5, 10.0, 40.0, 0.2)); // 40 = kp (kp - 2) v a
        assert!(prop1_paper_conditions(1.0, 0.5, 10.0, 39.9, 0.2));
        assert!(!prop1_paper_conditions(1.0, 0.5, 10.0, 1.0, 0.5)); // v a = c1
        assert!(!prop1_paper_conditions(1.0, 0.5, 10.0, 1.0, 0.0));
    }

    /// The isoline radius ln(I0/s_d)/k exists only for 0 < s_d < I0 and k > 0.
    #[test]
    fn isoline_radius_domain() {
        assert_eq!(
            radial_exp_isoline_radius_m(20.0, 0.1, 10.0),
            Some(2f64.ln() / 0.1)
        );
        for (i0, k, l) in [
            (20.0, 0.1, 0.0),
            (20.0, 0.1, 20.0),
            (20.0, 0.0, 10.0),
            (20.0, 0.1, 25.0),
        ] {
            assert_eq!(radial_exp_isoline_radius_m(i0, k, l), None, "{i0} {k} {l}");
        }
        assert_eq!(
            radial_exp_p_orbit(20.0, 0.1, 10.0, 0.0, 10.0, 0.2, 1.0),
            None
        );
        assert_eq!(
            radial_exp_p_orbit(20.0, 0.1, 10.0, 0.5, 0.0, 0.2, 1.0),
            None
        );
        assert_eq!(
            radial_exp_p_orbit(20.0, 0.1, 10.0, 0.5, 10.0, 0.0, 1.0),
            None
        );
        assert_eq!(
            radial_exp_p_orbit(20.0, 0.1, 10.0, 0.5, 10.0, 0.2, 0.0),
            None
        );
        // The paper's P law: |eps*| = c2 atanh(v / (kp c1 d*)) at the orbit d*.
        let o = radial_exp_p_orbit(20.0, 0.1, 10.0, 0.5, 10.0, 0.2, 1.0).unwrap();
        assert!((o.error + (0.5f64 / (10.0 * 0.2 * o.radius_m)).atanh()).abs() < 1e-12);
        assert!((o.error - (20.0 * (-0.1 * o.radius_m).exp() - 10.0)).abs() < 1e-15);
        assert!((o.error - -0.035_896_6).abs() < 1e-6, "{}", o.error);
        // A weak law still has an orbit, far out: g(d) = c1 tanh(-s_d/c2) + v/(kp d) = 0.
        let far = radial_exp_p_orbit(20.0, 0.1, 10.0, 50.0, 0.01, 0.001, 1.0).unwrap();
        let g = 0.001 * ((20.0 * (-0.1 * far.radius_m).exp() - 10.0) / 1.0).tanh()
            + 50.0 / (0.01 * far.radius_m);
        assert!(g.abs() < 1e-9 && far.radius_m > 1e6, "{far:?}");
    }
}

/// Bounds of the field over the operating region, Prop. 2's assumption (paper eq. (20)):
/// `gamma1 <= |grad F| <= gamma2`, `|hess F| <= gamma3`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldBounds {
    /// Lower bound on the gradient norm (field units per metre).
    pub gamma1: f64,
    /// Upper bound on the gradient norm.
    pub gamma2: f64,
    /// Upper bound on the Hessian's spectral norm (field units per square metre).
    pub gamma3: f64,
}

/// Prop. 2's gain condition in the unit-consistent form (baselines.md section 0), for the angle
/// margin `phi` (the paper's epsilon, in `(0, pi/2)`): the smallest `kp` with
///
/// ```text
/// kp > max( gamma3*v / (gamma1*sin(phi)*(v*gamma1*cos(phi) - c1)),
///           (c2*gamma3*v + c1*gamma2) / (c2*c1*gamma1*sin(phi)) ).
/// ```
///
/// `None` when `v*gamma1*cos(phi) <= c1` (the sliding surface cannot be reached at that margin)
/// or the bounds are degenerate. The paper prints the second term without the `c2` in the
/// denominator; the two agree for `c2 = 1` (see [`prop2_paper_min_kp`]).
pub fn prop2_min_kp(
    b: &FieldBounds,
    speed_mps: f64,
    c1: f64,
    c2: f64,
    phi_rad: f64,
) -> Option<f64> {
    prop2_terms(b, speed_mps, c1, c2, phi_rad).map(|(k1, k2)| k1.max(k2 / c2))
}

/// The two gain terms of Prop. 2,
/// `(gamma3*v/(gamma1*sin(phi)*(v*gamma1*cos(phi) - c1)), (c2*gamma3*v + c1*gamma2)/(c1*gamma1*sin(phi)))`
/// (the second without the `c2` the unit-consistent form divides by), or `None` when the surface
/// is unreachable at `phi`.
fn prop2_terms(
    b: &FieldBounds,
    speed_mps: f64,
    c1: f64,
    c2: f64,
    phi_rad: f64,
) -> Option<(f64, f64)> {
    let (s, c) = crate::fmath::sincos(phi_rad);
    let reach = speed_mps * b.gamma1 * c - c1;
    if !(b.gamma1 > 0.0 && reach > 0.0 && s > 0.0) {
        return None;
    }
    let k1 = b.gamma3 * speed_mps / (b.gamma1 * s * reach);
    let k2 = (c2 * b.gamma3 * speed_mps + c1 * b.gamma2) / (c1 * b.gamma1 * s);
    Some((k1, k2))
}

/// Prop. 2's steady-state bound in the unit-consistent form:
/// `limsup |eps| <= c2*atanh( (c2*gamma3*v + c1*gamma2) / (kp*c1*c2*gamma1*sin(phi)) )`,
/// `None` unless `kp` satisfies [`prop2_min_kp`] at `phi`.
pub fn prop2_error_bound(
    b: &FieldBounds,
    speed_mps: f64,
    kp: f64,
    c1: f64,
    c2: f64,
    phi_rad: f64,
) -> Option<f64> {
    let (k1, k2) = prop2_terms(b, speed_mps, c1, c2, phi_rad)?;
    if kp <= k1.max(k2 / c2) {
        return None;
    }
    let arg = k2 / (kp * c2);
    (arg < 1.0).then(|| c2 * libm::atanh(arg))
}

/// The paper's printed Prop. 2 (`c2` absent from the second denominator and from the bound):
/// `(min_kp, bound)`; not invariant under rescaling the field when `c2 != 1`.
pub fn prop2_paper_min_kp(
    b: &FieldBounds,
    speed_mps: f64,
    kp: f64,
    c1: f64,
    c2: f64,
    phi_rad: f64,
) -> (Option<f64>, Option<f64>) {
    let Some((k1, k2)) = prop2_terms(b, speed_mps, c1, c2, phi_rad) else {
        return (None, None);
    };
    let min = k1.max(k2);
    let arg = k2 / kp;
    (Some(min), (kp > min && arg < 1.0).then(|| libm::atanh(arg)))
}

#[cfg(test)]
mod prop1_by_hand_tests {
    use super::*;

    /// `kp (kp - 2) v alpha > ki` and `v alpha > c1 > 0` by hand: kp 3, v 0.5, alpha 2 give
    /// 3 and 1.
    #[test]
    fn prop1_paper_conditions_by_hand() {
        assert!(prop1_paper_conditions(2.0, 0.5, 3.0, 2.9, 0.9));
        assert!(!prop1_paper_conditions(2.0, 0.5, 3.0, 3.1, 0.9));
        assert!(!prop1_paper_conditions(2.0, 0.5, 3.0, 2.9, 1.1));
        assert!(!prop1_paper_conditions(2.0, 0.5, 3.0, 2.9, 0.0));
    }

    /// The P-law's orbit solves `c1 tanh((F(d) - s_d)/c2) + v/(kp d) = 0` (evaluated here with
    /// libm), outside the isoline; no orbit without speed or gains.
    /// With `ki = 0` both `a2 = kp alpha v` and `a1` must be positive: a small negative `kp`
    /// leaves `a1 = alpha v kp c1/c2 + v^2/r^2` positive but `a2` negative: unstable.
    #[test]
    fn p_law_needs_both_coefficients_positive() {
        let (alpha, v, r, c1, c2) = (0.5, 1.0, 1.0, 0.2, 1.0);
        let [a2, a1, _] = prop1_characteristic_polynomial(alpha, v, r, -0.01, 0.0, c1, c2);
        assert!(a2 < 0.0 && a1 > 0.0, "{a2} {a1}");
        assert!(!prop1_exact_local_condition(
            alpha, v, r, -0.01, 0.0, c1, c2
        ));
        assert!(prop1_exact_local_condition(alpha, v, r, 0.01, 0.0, c1, c2));
    }

    #[test]
    fn p_orbit_solves_its_equation() {
        let (i0, k, level, v, kp, c1, c2) = (20.0, 0.1, 10.0, 2.0, 4.0, 0.3, 2.0);
        let o = radial_exp_p_orbit(i0, k, level, v, kp, c1, c2).unwrap();
        let f = |d: f64| i0 * libm::exp(-k * d);
        let residual = c1 * libm::tanh((f(o.radius_m) - level) / c2) + v / (kp * o.radius_m);
        assert!(residual.abs() < 1e-12, "{residual}");
        assert!(o.radius_m > libm::log(2.0) / k);
        assert!((o.error - (f(o.radius_m) - level)).abs() < 1e-12);
        for (v, kp, c1, c2) in [
            (0.0, 4.0, 0.3, 2.0),
            (2.0, 0.0, 0.3, 2.0),
            (2.0, 4.0, 0.0, 2.0),
            (2.0, 4.0, 0.3, 0.0),
        ] {
            assert!(
                radial_exp_p_orbit(i0, k, level, v, kp, c1, c2).is_none(),
                "{v} {kp} {c1} {c2}"
            );
        }
    }
}

#[cfg(test)]
mod prop2_tests {
    use super::*;

    /// On the circular field the bound must cover the exact P-law orbit error
    /// (gamma1 = gamma2 = alpha, gamma3 = alpha/d_min, phi = pi/2 at the orbit).
    #[test]
    fn bound_covers_the_exact_circular_error() {
        let (v, kp, c1, c2) = (0.5, 10.0, 0.2, 1.0);
        // Linear radial profile F = s_d - alpha (d - r_d), alpha = 1, r_d = 6.93.
        let alpha = 1.0;
        let b = FieldBounds {
            gamma1: alpha,
            gamma2: alpha,
            gamma3: alpha / 6.0,
        };
        let phi = 0.9;
        let bound = prop2_error_bound(&b, v, kp, c1, c2, phi).unwrap();
        let exact = c2 * libm::atanh(v / (kp * c1 * 6.93));
        assert!(bound >= exact, "{bound} < {exact}");
        // Rescaling the field by 10 (and c1, c2 with it) rescales the balanced bound by 10.
        let b10 = FieldBounds {
            gamma1: 10.0 * b.gamma1,
            gamma2: 10.0 * b.gamma2,
            gamma3: 10.0 * b.gamma3,
        };
        let bound10 = prop2_error_bound(&b10, v, kp / 10.0, 10.0 * c1, 10.0 * c2, phi).unwrap();
        assert!((bound10 - 10.0 * bound).abs() < 1e-9 * bound10);
        // With c2 = 1 the printed and balanced forms agree.
        let (pmin, pb) = prop2_paper_min_kp(&b, v, kp, c1, c2, phi);
        assert_eq!(pmin, prop2_min_kp(&b, v, c1, c2, phi));
        assert!((pb.unwrap() - bound).abs() < 1e-12);
    }

    /// Prop. 2's terms, minimum gain and bound evaluated by hand from the stated formulas
    /// (unit-consistent form) at one point, and the printed form's at another `c2`.
    #[test]
    fn prop2_by_hand() {
        let b = FieldBounds {
            gamma1: 0.8,
            gamma2: 1.3,
            gamma3: 0.25,
        };
        let (v, c1, c2, phi) = (0.5, 0.2, 2.0, 0.9f64);
        let (s, c) = (phi.sin(), phi.cos());
        let k1 = b.gamma3 * v / (b.gamma1 * s * (v * b.gamma1 * c - c1));
        let k2 = (c2 * b.gamma3 * v + c1 * b.gamma2) / (c1 * b.gamma1 * s);
        let min = k1.max(k2 / c2);
        let got = prop2_min_kp(&b, v, c1, c2, phi).unwrap();
        assert!((got - min).abs() < 1e-12 * min, "{got} vs {min}");
        for kp in [1.01 * min, 2.0 * min, 10.0 * min] {
            let want = c2 * (k2 / (kp * c2)).atanh();
            let bound = prop2_error_bound(&b, v, kp, c1, c2, phi).unwrap();
            assert!(
                (bound - want).abs() < 1e-12 * want,
                "kp {kp}: {bound} vs {want}"
            );
        }
        // Below the minimum gain: no bound.
        assert!(prop2_error_bound(&b, v, 0.99 * min, c1, c2, phi).is_none());
        // The printed form: min over (k1, k2), bound atanh(k2 / kp) (no c2).
        let kp = 3.0 * k1.max(k2);
        let (pmin, pb) = prop2_paper_min_kp(&b, v, kp, c1, c2, phi);
        assert!((pmin.unwrap() - k1.max(k2)).abs() < 1e-12 * k1.max(k2));
        assert!((pb.unwrap() - (k2 / kp).atanh()).abs() < 1e-12);
        let (_, none) = prop2_paper_min_kp(&b, v, 0.5 * k1.max(k2), c1, c2, phi);
        assert!(none.is_none());
    }

    #[test]
    fn unreachable_surface_has_no_min_kp() {
        let b = FieldBounds {
            gamma1: 0.1,
            gamma2: 0.2,
            gamma3: 0.01,
        };
        // v*gamma1 = 0.05 < c1 = 0.2 at any phi.
        assert!(prop2_min_kp(&b, 0.5, 0.2, 1.0, 0.3).is_none());
    }

    /// At the edges of Prop. 2's conditions the terms do not exist: no angle margin
    /// (`sin(phi) = 0`), no gradient (`gamma1 = 0`), or a surface exactly unreachable
    /// (`v gamma1 cos(phi) = c1`).
    #[test]
    fn prop2_terms_vanish_at_the_edges() {
        let b = FieldBounds {
            gamma1: 0.5,
            gamma2: 1.0,
            gamma3: 0.1,
        };
        assert!(prop2_terms(&b, 1.0, 0.1, 1.0, 0.0).is_none());
        let flat = FieldBounds { gamma1: 0.0, ..b };
        assert!(prop2_terms(&flat, 1.0, -0.1, 1.0, 0.5).is_none());
        let phi = 0.5;
        let c1 = 1.0 * b.gamma1 * crate::fmath::sincos(phi).1;
        assert!(prop2_terms(&b, 1.0, c1, 1.0, phi).is_none());
        assert!(prop2_terms(&b, 1.0, 0.9 * c1, 1.0, phi).is_some());
    }

    /// The printed bound needs `kp` strictly above the printed minimum: at the minimum (here
    /// the first term, `k1 > k2`) and just below it there is no bound.
    #[test]
    fn printed_bound_needs_kp_above_its_minimum() {
        // A surface barely reachable (v gamma1 cos(phi) = 0.439 just above c1 = 0.42):
        // k1 = gamma3 v/(gamma1 s (v gamma1 c - c1)) dominates.
        let b = FieldBounds {
            gamma1: 0.5,
            gamma2: 0.6,
            gamma3: 0.2,
        };
        let (v, c1, c2, phi) = (1.0, 0.42, 1.0, 0.5);
        let (k1, k2) = prop2_terms(&b, v, c1, c2, phi).unwrap();
        assert!(k1 > k2, "{k1} {k2}");
        let (min, _) = prop2_paper_min_kp(&b, v, 100.0, c1, c2, phi);
        assert_eq!(min, Some(k1));
        assert_eq!(prop2_paper_min_kp(&b, v, k1, c1, c2, phi).1, None);
        assert_eq!(prop2_paper_min_kp(&b, v, 0.99 * k1, c1, c2, phi).1, None);
        let (_, bound) = prop2_paper_min_kp(&b, v, 2.0 * k1, c1, c2, phi);
        let want = libm::atanh(k2 / (2.0 * k1));
        assert!((bound.unwrap() - want).abs() < 1e-15);
    }
}
