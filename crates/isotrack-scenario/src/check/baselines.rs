//! The baselines' own gain conditions (docs/BASELINES.md, sections 1 and 2), checked on the
//! scenario's field so `compare` and `run` can say when a baseline runs outside them.
//!
//! Both are the sufficient conditions that document derives (`[D]`) or reconstructs (`[R]`);
//! the gradient and Hessian bounds `gamma1..3` are `isotrack check`'s own computation (the same
//! 601 x 601 lattice and margins as Prop. 2), over the tube `|F - s_d| <= H` round the target
//! isoline, `H` the linear zone `delta` for the sliding modes and 1 for the suboptimal SOSM: the
//! numbers the `tube` line of `isotrack check --tube-halfwidth H` prints. (`check`'s first
//! line, `start to tube`, bounds a larger region, from the start's level to the tube, and is
//! not what these conditions use.) Each warning names its tube and gives its `gamma`s.

use super::regions::{regions, CHECK_LATTICE};
use super::setup::speed_mps;
use crate::schema::ControllerKind;
use crate::spec::LawSpec;
use crate::Scenario;
use isotrack_core::numtext::{Echo, Num, NumUp};

/// Warnings for a baseline whose gains violate its stated condition on this scenario (empty
/// for the paper's law and for laws without a stated condition, and when the bounds cannot be
/// taken).
pub fn baseline_warnings(s: &Scenario) -> Vec<String> {
    let c = &s.spec().controller;
    let kind = c.kind;
    let v = speed_mps(s);
    // Which tube, and why that half-width; the law's amplitude `u_bar`.
    let (tube, why, u_bar) = match &c.law {
        LawSpec::SlidingMode(p) => (
            p.delta,
            "delta, the law's linear zone",
            p.max_turn_rate_radps,
        ),
        LawSpec::SuboptimalSosm(p) => (1.0, "1 field unit", p.max_turn_rate_radps),
        _ => return vec![],
    };
    let Some(b) = regions(s, tube, CHECK_LATTICE, true).tube else {
        return vec![];
    };
    let warnings = match &c.law {
        LawSpec::SuboptimalSosm(p) => {
            sosm_conditions(v, u_bar, p.alpha_star, b.gamma1, b.gamma2, b.gamma3)
        }
        LawSpec::SlidingMode(p) => {
            sliding_mode_conditions(v, u_bar, p.gamma, tube, b.gamma1, b.gamma3)
        }
        _ => vec![],
    };
    let warnings: Vec<String> = match kind {
        ControllerKind::SuboptimalSosm => warnings,
        _ => warnings
            .into_iter()
            .map(|w| w.replacen("sliding_mode:", &format!("{}:", kind.name()), 1))
            .collect(),
    };
    let gamma3 = b
        .gamma3
        .map_or_else(|| "none (no Hessian)".to_string(), |g| Num(g).to_string());
    let region = format!(
        "; gamma1 = {} <= |grad F| <= gamma2 = {}, ||hess F|| <= gamma3 = {}, over the tube |F - s_d| <= {} ({why}) round the isoline, lattice margins included: the `tube` line of `isotrack check --tube-halfwidth {}` (not its `start to tube` line, a larger region)",
        Num(b.gamma1),
        Num(b.gamma2),
        gamma3,
        Echo(tube),
        Echo(tube),
    );
    warnings.into_iter().map(|w| w + &region).collect()
}

/// Matveev et al.'s sliding mode, `mu = gamma*delta`: (a) `mu < v*inf|grad F|` (the surface is
/// reachable), (b) `u_bar > (v*sup||hess F|| + gamma*mu/v) / sqrt(inf|grad F|^2 - mu^2/v^2)`
/// (the turn rate can hold it), docs/BASELINES.md section 1 `[D]`.
pub fn sliding_mode_conditions(
    v: f64,
    u_bar: f64,
    gamma: f64,
    delta: f64,
    grad_min: f64,
    hess_max: Option<f64>,
) -> Vec<String> {
    let mu = gamma * delta;
    let mut w = vec![];
    if mu >= v * grad_min {
        w.push(format!(
            "sliding_mode: mu = gamma*delta = {} is not below v*gamma1 = {}: the sliding surface may not be reachable (docs/BASELINES.md, condition (a))",
            Num(mu),
            Num(v * grad_min)
        ));
        return w;
    }
    if let Some(h) = hess_max {
        let need = (v * h + gamma * mu / v) / (grad_min * grad_min - mu * mu / (v * v)).sqrt();
        if u_bar <= need {
            w.push(format!(
                "sliding_mode: the turn-rate limit {} rad/s is not above {} rad/s = (v*gamma3 + gamma*mu/v)/sqrt(gamma1^2 - mu^2/v^2): it may not hold the surface (docs/BASELINES.md, condition (b))",
                Echo(u_bar),
                NumUp(need)
            ));
        }
    }
    w
}

/// The suboptimal SOSM on `s'' = f + g*omega` with `|f| <= Fb = v^2*sup||hess F||`,
/// `G1 = v*inf|grad F| <= g <= G2 = v*sup|grad F|` (heading tangent): `alpha* < 3*G1/G2` and
/// `U > max(Fb/(alpha*G1), 4*Fb/(3*G1 - alpha*G2))`, docs/BASELINES.md section 2 `[R]`.
pub fn sosm_conditions(
    v: f64,
    u: f64,
    alpha: f64,
    grad_min: f64,
    grad_max: f64,
    hess_max: Option<f64>,
) -> Vec<String> {
    let (g1, g2) = (v * grad_min, v * grad_max);
    let mut w = vec![];
    if !(alpha > 0.0 && alpha <= 1.0 && alpha < 3.0 * g1 / g2) {
        w.push(format!(
            "suboptimal_sosm: alpha_star = {} is not in (0, min(1, 3*G1/G2 = {})), G1 = v*gamma1, G2 = v*gamma2 (docs/BASELINES.md, section 2)",
            Echo(alpha),
            Num(3.0 * g1 / g2)
        ));
        return w;
    }
    if let Some(h) = hess_max {
        let fb = v * v * h;
        let need = (fb / (alpha * g1)).max(4.0 * fb / (3.0 * g1 - alpha * g2));
        if u <= need {
            w.push(format!(
                "suboptimal_sosm: the turn-rate amplitude U = {} rad/s is not above max(Fb/(alpha*G1), 4Fb/(3G1 - alpha*G2)) = {} rad/s, Fb = v^2*gamma3, G1 = v*gamma1, G2 = v*gamma2 (docs/BASELINES.md, section 2)",
                Echo(u),
                Num(need)
            ));
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the paper's circular field near the isoline (|grad F| = alpha_f = 0.1*10 = 1 per m at
    /// r = 6.93 m, curvature 1/r), condition (b) reduces to u_bar > v/r_d when mu is small:
    /// BASELINES.md's simulation has u_bar = 0.08 failing and 0.5 holding at v = 0.5, r = 5.
    #[test]
    fn sliding_mode_condition_b_is_v_over_r_on_a_circle() {
        // |grad F| = 1, ||hess F|| = 1/r = 0.2 (unit gradient), v = 0.5: need ~0.1 + small.
        let ok = sliding_mode_conditions(0.5, 0.5, 0.01, 0.01, 1.0, Some(0.2));
        assert!(ok.is_empty(), "{ok:?}");
        let bad = sliding_mode_conditions(0.5, 0.08, 0.01, 0.01, 1.0, Some(0.2));
        assert_eq!(bad.len(), 1);
        assert!(bad[0].contains("condition (b)"));
        // (a): mu = 0.6 >= v*|grad F| = 0.5.
        let a = sliding_mode_conditions(0.5, 5.0, 0.6, 1.0, 1.0, Some(0.2));
        assert!(a[0].contains("condition (a)"), "{a:?}");
    }

    /// The SOSM bounds by hand: v = 1, grad in [1, 2], hess 0.5: G1 = 1, G2 = 2, Fb = 0.5;
    /// alpha = 0.5 < 3/2; U > max(0.5/0.5, 2/(3 - 1)) = 1.
    #[test]
    fn sosm_conditions_by_hand() {
        assert!(sosm_conditions(1.0, 1.01, 0.5, 1.0, 2.0, Some(0.5)).is_empty());
        assert_eq!(
            sosm_conditions(1.0, 0.99, 0.5, 1.0, 2.0, Some(0.5)).len(),
            1
        );
        assert!(sosm_conditions(1.0, 9.0, 1.0, 1.0, 4.0, Some(0.5))[0].contains("alpha_star"));
        // Each term of the amplitude bound where it is the larger one (Fb = 0.5, G1 = 1):
        // alpha = 0.2, G2 = 2: Fb/(alpha G1) = 2.5 over 4 Fb/(3 G1 - alpha G2) = 0.769;
        // alpha = 0.9, G2 = 3: 4 Fb/(3 - 2.7) = 6.667 over Fb/(alpha G1) = 0.556.
        for (alpha, g2, need) in [(0.2, 2.0, 2.5), (0.9, 3.0, 2.0 / 0.3)] {
            let w = sosm_conditions(1.0, need - 0.01, alpha, 1.0, g2, Some(0.5));
            assert_eq!(w.len(), 1, "alpha {alpha}: {w:?}");
            assert!(w[0].contains(&Num(need).to_string()), "{w:?}");
            assert!(sosm_conditions(1.0, need + 0.01, alpha, 1.0, g2, Some(0.5)).is_empty());
        }
        // Fb scales with v^2 and G1, G2 with v: v = 2 doubles the bound (Fb/(alpha G1) = 5).
        let w = sosm_conditions(2.0, 4.99, 0.2, 1.0, 2.0, Some(0.5));
        assert!(w.len() == 1 && w[0].contains("= 5 rad/s"), "{w:?}");
        assert!(sosm_conditions(2.0, 5.01, 0.2, 1.0, 2.0, Some(0.5)).is_empty());
    }

    /// Condition (b) with a large `mu`: v = 1, gamma = 0.5, delta = 1 (mu = 0.5), |grad F| >= 1,
    /// ||hess F|| <= 0.2 need `u_bar > (0.2 + 0.25)/sqrt(1 - 0.25) = 0.5196` rad/s.
    #[test]
    fn sliding_mode_condition_b_by_hand() {
        let need = 0.45 / 0.75f64.sqrt();
        assert!(sliding_mode_conditions(1.0, need + 1e-3, 0.5, 1.0, 1.0, Some(0.2)).is_empty());
        let w = sliding_mode_conditions(1.0, need - 1e-3, 0.5, 1.0, 1.0, Some(0.2));
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("0.5196"), "{}", w[0]);
        // Condition (a): mu = v*|grad F| exactly is not below it.
        let w = sliding_mode_conditions(0.5, 1.0, 0.5, 1.0, 1.0, Some(0.2));
        assert!(w[0].contains("condition (a)"), "{}", w[0]);
    }

    /// Both conditions where `v` and `|grad F|` are not 1, so every product and quotient shows:
    /// v = 2, min|grad F| = 0.5, ||hess F|| <= 0.25, gamma = 0.3, delta = 1 (mu = 0.3):
    /// (a) 0.3 < v*0.5 = 1 holds; (b) needs u_bar > (2*0.25 + 0.3*0.3/2)/sqrt(0.25 - 0.09/4)
    /// = 0.545/sqrt(0.2275) = 1.14263 rad/s. With gamma = 2 (mu = 2), (a) fails: 2 >= 1,
    /// though 2 < v/min|grad F| = 4.
    #[test]
    fn sliding_mode_conditions_away_from_unit_speed_and_slope() {
        let need = 0.545 / 0.2275f64.sqrt();
        assert!((need - 1.142_63).abs() < 1e-5);
        let w = sliding_mode_conditions(2.0, need - 1e-3, 0.3, 1.0, 0.5, Some(0.25));
        assert_eq!(w.len(), 1, "{w:?}");
        // The limit needed is rounded up (a rounded-down one would read as enough).
        assert!(w[0].contains(&NumUp(need).to_string()), "{}", w[0]);
        assert!(sliding_mode_conditions(2.0, need + 1e-3, 0.3, 1.0, 0.5, Some(0.25)).is_empty());
        let a = sliding_mode_conditions(2.0, 100.0, 2.0, 1.0, 0.5, Some(0.25));
        assert_eq!(a.len(), 1, "{a:?}");
        assert!(
            a[0].contains("condition (a)") && a[0].contains("v*gamma1 = 1:"),
            "{}",
            a[0]
        );
        // Without a Hessian bound only (a) can be checked.
        assert!(sliding_mode_conditions(2.0, 1e-3, 0.3, 1.0, 0.5, None).is_empty());
    }

    /// The SOSM at v = 2 with |grad F| in [0.5, 1.5]: G1 = 1, G2 = 3, Fb = 4*0.5 = 2. alpha = 0.9
    /// is below 3 G1/G2 = 1; U > max(2/0.9, 8/(3 - 2.7)) = 26.667. The admissible alpha is open at
    /// both ends: 0 and 3 G1/G2 itself (0.75 with v = 1, |grad F| in [1, 4]) are refused.
    #[test]
    fn sosm_conditions_away_from_unit_speed() {
        let need = 8.0 / 0.3;
        let w = sosm_conditions(2.0, need - 0.01, 0.9, 0.5, 1.5, Some(0.5));
        assert_eq!(w.len(), 1, "{w:?}");
        // The limit needed is rounded up (a rounded-down one would read as enough).
        assert!(w[0].contains(&NumUp(need).to_string()), "{}", w[0]);
        assert!(sosm_conditions(2.0, need + 0.01, 0.9, 0.5, 1.5, Some(0.5)).is_empty());
        for (alpha, grad_max) in [(0.0, 2.0), (0.75, 4.0)] {
            let w = sosm_conditions(1.0, 1e9, alpha, 1.0, grad_max, Some(0.5));
            assert_eq!(w.len(), 1, "alpha {alpha}: {w:?}");
            assert!(w[0].contains("alpha_star"), "{}", w[0]);
        }
        assert!(sosm_conditions(1.0, 1e9, 0.74, 1.0, 4.0, Some(0.5)).is_empty());
    }
}
