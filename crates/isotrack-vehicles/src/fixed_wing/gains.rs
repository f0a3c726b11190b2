//! Autopilot gains from the model by Beard & McLain's successive-loop-closure formulas
//! (chapter 6; `compute_gains.m`; docs/FIXED-WING.md section 3).

use super::params::Aerosonde;
use super::trim::Trim;
use serde::Serialize;

/// The autopilot gains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[allow(missing_docs)] // the book's names
pub struct Gains {
    pub kp_phi: f64,
    pub kd_phi: f64,
    pub ki_phi: f64,
    pub kp_chi: f64,
    pub ki_chi: f64,
    pub kp_theta: f64,
    pub kd_theta: f64,
    /// DC gain of the pitch loop.
    pub k_theta_dc: f64,
    pub kp_v: f64,
    pub ki_v: f64,
    pub kp_v2: f64,
    pub ki_v2: f64,
    pub kp_h: f64,
    pub ki_h: f64,
}

/// Design parameters: the book's choices (roll e_max 15 deg, zeta 1.2, ki 0.2; course W 8,
/// zeta 0.707; pitch e_max 10 deg, zeta 0.707; airspeed omega 5, zeta 0.707; airspeed-from-pitch
/// W 7; altitude W 10, zeta 1.2; surfaces 45 deg).
///
/// `a_V1` uses `C_D,delta_e` as in the book; `ecen674_a_v1 = true` uses `C_L,delta_e` as the
/// 2012 code does (a typo there: it moves `kp_v` from 0.13259 to 0.13177).
pub fn compute_gains(p: &Aerosonde, t: &Trim, ecen674_a_v1: bool) -> Gains {
    let va = t.airspeed_mps;
    let (rho, s, c, jy) = (p.rho, p.s, p.c, p.jy);
    let d45 = 45f64.to_radians();
    // Roll.
    let (e_phi_max, zeta_phi) = (15f64.to_radians(), 1.2);
    let (a_phi1, a_phi2) = roll_coefficients(p, va);
    let kp_phi = d45 / e_phi_max * a_phi2.signum();
    let w_phi = (a_phi2.abs() * d45 / e_phi_max).sqrt();
    let kd_phi = (2.0 * zeta_phi * w_phi - a_phi1) / a_phi2;
    // Course.
    let (w_chi_ratio, zeta_chi) = (8.0, 0.707);
    let w_chi = w_phi / w_chi_ratio;
    let kp_chi = 2.0 * zeta_chi * w_chi * va / p.g;
    let ki_chi = w_chi * w_chi * va / p.g;
    // Pitch.
    let (e_theta_max, zeta_theta) = (10f64.to_radians(), 0.707);
    let a_th1 = -rho * va * va * c * s * p.c_m_q * c / (4.0 * jy * va);
    let a_th2 = -rho * va * va * c * s * p.c_m_alpha / (2.0 * jy);
    let a_th3 = rho * va * va * c * s * p.c_m_de / (2.0 * jy);
    let kp_theta = d45 / e_theta_max * a_th3.signum();
    let w_theta = (a_th2 + d45 / e_theta_max * a_th3.abs()).sqrt();
    let kd_theta = (2.0 * zeta_theta * w_theta - a_th1) / a_th3;
    let k_theta_dc = kp_theta * a_th3 / (a_th2 + kp_theta * a_th3);
    // Airspeed from throttle.
    let c_de = if ecen674_a_v1 { p.c_l_de } else { p.c_d_de };
    let a_v1 = rho * va * s / p.mass_kg
        * (p.c_d0 + p.c_d_alpha * t.alpha_rad + c_de * t.delta_e_rad)
        + rho * p.s_prop * p.c_prop * va / p.mass_kg;
    let a_v2 = rho * p.s_prop * p.c_prop * p.k_motor * p.k_motor * t.delta_t / p.mass_kg;
    let (w_v, zeta_v) = (5.0, 0.707);
    let ki_v = w_v * w_v / a_v2;
    let kp_v = (2.0 * zeta_v * w_v - a_v1) / a_v2;
    // Airspeed from pitch.
    let w_v2 = w_theta / 7.0;
    let ki_v2 = -w_v2 * w_v2 / (k_theta_dc * p.g);
    let kp_v2 = (a_v1 - 2.0 * 0.707 * w_v2) / (k_theta_dc * p.g);
    // Altitude from pitch.
    let (w_h, zeta_h) = (w_theta / 10.0, 1.2);
    let ki_h = w_h * w_h / (k_theta_dc * va);
    let kp_h = 2.0 * zeta_h * w_h / (k_theta_dc * va);
    Gains {
        kp_phi,
        kd_phi,
        ki_phi: 0.2,
        kp_chi,
        ki_chi,
        kp_theta,
        kd_theta,
        k_theta_dc,
        kp_v,
        ki_v,
        kp_v2,
        ki_v2,
        kp_h,
        ki_h,
    }
}

/// The roll dynamics' coefficients `phi'' = -a_phi1 phi' + a_phi2 delta_a` (Beard & McLain
/// eq. 5.26): `a_phi1 = -rho Va^2 S b C_p_p b / (4 Va)`, `a_phi2 = rho Va^2 S b C_p_delta_a / 2`.
fn roll_coefficients(p: &Aerosonde, va: f64) -> (f64, f64) {
    let (cpp, cpda) = p.c_p_p_and_da();
    let a_phi1 = -0.5 * p.rho * va * va * p.s * p.b * cpp * p.b / (2.0 * va);
    let a_phi2 = 0.5 * p.rho * va * va * p.s * p.b * cpda;
    (a_phi1, a_phi2)
}

/// The closed lateral loops as linear dynamics, for the sampled-data check of the isoline law
/// on the UAV (`isotrack check`, docs/SAMPLED.md). Beard & McLain chapter 6, with the roll
/// loop's small integrator left out:
///
/// ```text
/// roll:    phi'' = -2 zeta_phi w_phi phi' + w_phi^2 (phi_c - phi),
///          w_phi^2 = kp_phi a_phi2,  2 zeta_phi w_phi = a_phi1 + a_phi2 kd_phi
/// course:  chi' = (g / Va) phi,   phi_c = kp_chi (chi_c - chi) + ki_chi integral(chi_c - chi)
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CourseLoopModel {
    /// Natural frequency of the closed roll loop `w_phi`, rad/s.
    pub roll_natural_frequency_radps: f64,
    /// Damping ratio of the closed roll loop `zeta_phi`.
    pub roll_damping_ratio: f64,
    /// Course loop proportional gain `kp_chi`, rad of bank per rad of course error.
    pub kp_chi: f64,
    /// Course loop integral gain `ki_chi`, rad of bank per rad*s of course error.
    pub ki_chi: f64,
    /// `g / Va`, 1/s: course rate per radian of bank (coordinated turn, small bank).
    pub g_over_airspeed_per_s: f64,
}

/// The lateral loop model at the trim airspeed for the given gains.
pub fn course_loop_model(p: &Aerosonde, t: &Trim, g: &Gains) -> CourseLoopModel {
    let va = t.airspeed_mps;
    let (a_phi1, a_phi2) = roll_coefficients(p, va);
    let w2 = g.kp_phi * a_phi2;
    let w = w2.max(0.0).sqrt();
    CourseLoopModel {
        roll_natural_frequency_radps: w,
        roll_damping_ratio: (a_phi1 + a_phi2 * g.kd_phi) / (2.0 * w),
        kp_chi: g.kp_chi,
        ki_chi: g.ki_chi,
        g_over_airspeed_per_s: p.g / va,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed_wing::trim::trim;

    fn close(a: f64, b: f64, what: &str) {
        assert!(
            (a - b).abs() <= 5e-5 * b.abs().max(1.0),
            "{what}: {a} vs {b}"
        );
    }

    /// The gain table of docs/FIXED-WING.md section 3 at 30 m/s, both rows.
    #[test]
    fn reproduces_the_gain_table_at_30() {
        let p = Aerosonde::beard_mclain_2012();
        let t = trim(&p, 30.0).unwrap();
        for (ecen, kp_v, kp_v2) in [(true, 0.13177, -0.20288), (false, 0.13259, -0.20767)] {
            let g = compute_gains(&p, &t, ecen);
            close(g.kp_phi, 3.0, "kp_phi");
            close(g.kd_phi, 0.28121, "kd_phi");
            close(g.ki_phi, 0.2, "ki_phi");
            close(g.kp_chi, 9.0697, "kp_chi");
            close(g.ki_chi, 13.440, "ki_chi");
            close(g.kp_theta, -4.5, "kp_theta");
            close(g.kd_theta, -0.61001, "kd_theta");
            close(g.kp_v, kp_v, "kp_v");
            close(g.ki_v, 0.51497, "ki_v");
            close(g.kp_v2, kp_v2, "kp_v2");
            close(g.ki_v2, -0.33627, "ki_v2");
            close(g.kp_h, 0.10991, "kp_h");
            close(g.ki_h, 0.053826, "ki_h");
            close(g.k_theta_dc, 0.8555, "K_theta_DC");
        }
    }

    #[test]
    fn gains_at_35_match_the_file_default_row() {
        let p = Aerosonde::beard_mclain_2012();
        let g = compute_gains(&p, &trim(&p, 35.0).unwrap(), true);
        close(g.kd_phi, 0.24103, "kd_phi");
        close(g.kp_chi, 12.345, "kp_chi");
        close(g.ki_chi, 21.342, "ki_chi");
        close(g.kd_theta, -0.52286, "kd_theta");
        close(g.kp_v, 0.11173, "kp_v");
        close(g.ki_v, 0.44229, "ki_v");
        close(g.ki_h, 0.062797, "ki_h");
    }

    #[test]
    fn course_loop_model_has_the_design_damping_and_bandwidth() {
        // compute_gains places the roll loop at zeta = 1.2 and the course loop at
        // w_chi = w_phi / 8, zeta_chi = 0.707 (Beard & McLain section 6.3): the model read back
        // from the gains must show those design values.
        let p = Aerosonde::beard_mclain_2012();
        let t = trim(&p, 30.0).unwrap();
        let g = compute_gains(&p, &t, false);
        let m = course_loop_model(&p, &t, &g);
        assert!((m.roll_damping_ratio - 1.2).abs() < 1e-12, "{m:?}");
        let w_chi = m.roll_natural_frequency_radps / 8.0;
        assert!((m.kp_chi * m.g_over_airspeed_per_s - 2.0 * 0.707 * w_chi).abs() < 1e-12);
        assert!((m.ki_chi * m.g_over_airspeed_per_s - w_chi * w_chi).abs() < 1e-12);
        assert!((m.g_over_airspeed_per_s - p.g / 30.0).abs() < 1e-15);
    }
}
