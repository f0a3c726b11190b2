//! The Aerosonde parameter set of Beard & McLain (2012), Table E.2, as used by the paper's
//! simulator (`magiccjae/ecen674`, `param_chap10.m`).

/// Airframe, aerodynamic and propulsion parameters, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(missing_docs)] // field names are the book's symbols; units in the struct doc
pub struct Aerosonde {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertias Jx, Jy, Jz, Jxz, kg m^2.
    pub jx: f64,
    pub jy: f64,
    pub jz: f64,
    pub jxz: f64,
    /// Wing area S (m^2), span b (m), chord c (m).
    pub s: f64,
    pub b: f64,
    pub c: f64,
    /// Propeller disc area (m^2), air density (kg/m^3), Oswald efficiency.
    pub s_prop: f64,
    pub rho: f64,
    pub e: f64,
    /// Gravity, m/s^2 (9.8 in the 2012 code).
    pub g: f64,
    pub c_l0: f64,
    pub c_l_alpha: f64,
    pub c_l_q: f64,
    pub c_l_de: f64,
    pub c_d0: f64,
    pub c_d_alpha: f64,
    pub c_d_q: f64,
    pub c_d_de: f64,
    pub c_d_p: f64,
    pub c_m0: f64,
    pub c_m_alpha: f64,
    pub c_m_q: f64,
    pub c_m_de: f64,
    /// Stall blending: transition rate M and cut-off angle alpha0 (rad).
    pub stall_m: f64,
    pub alpha0: f64,
    pub c_y0: f64,
    pub c_y_beta: f64,
    pub c_y_p: f64,
    pub c_y_r: f64,
    pub c_y_da: f64,
    pub c_y_dr: f64,
    pub c_ell0: f64,
    pub c_ell_beta: f64,
    pub c_ell_p: f64,
    pub c_ell_r: f64,
    pub c_ell_da: f64,
    pub c_ell_dr: f64,
    pub c_n0: f64,
    pub c_n_beta: f64,
    pub c_n_p: f64,
    pub c_n_r: f64,
    pub c_n_da: f64,
    pub c_n_dr: f64,
    /// Propulsion (2012 model): C_prop, k_motor, k_Tp, k_Omega.
    pub c_prop: f64,
    pub k_motor: f64,
    pub k_tp: f64,
    pub k_omega: f64,
}

impl Aerosonde {
    /// The 2012 set (docs/FIXED-WING.md section 1, column "2012/ecen674").
    pub const fn beard_mclain_2012() -> Self {
        Self {
            mass_kg: 13.5,
            jx: 0.8244,
            jy: 1.135,
            jz: 1.759,
            jxz: 0.1204,
            s: 0.55,
            b: 2.8956,
            c: 0.18994,
            s_prop: 0.2027,
            rho: 1.2682,
            e: 0.9,
            g: 9.8,
            c_l0: 0.28,
            c_l_alpha: 3.45,
            c_l_q: 0.0,
            c_l_de: -0.36,
            c_d0: 0.03,
            c_d_alpha: 0.30,
            c_d_q: 0.0,
            c_d_de: 0.0,
            c_d_p: 0.0437,
            c_m0: -0.02338,
            c_m_alpha: -0.38,
            c_m_q: -3.6,
            c_m_de: -0.5,
            stall_m: 50.0,
            alpha0: 0.4712,
            c_y0: 0.0,
            c_y_beta: -0.98,
            c_y_p: 0.0,
            c_y_r: 0.0,
            c_y_da: 0.0,
            c_y_dr: -0.17,
            c_ell0: 0.0,
            c_ell_beta: -0.12,
            c_ell_p: -0.26,
            c_ell_r: 0.14,
            c_ell_da: 0.08,
            c_ell_dr: 0.105,
            c_n0: 0.0,
            c_n_beta: 0.25,
            c_n_p: 0.022,
            c_n_r: -0.35,
            c_n_da: 0.06,
            c_n_dr: -0.032,
            c_prop: 1.0,
            k_motor: 80.0,
            k_tp: 0.0,
            k_omega: 0.0,
        }
    }

    /// Aspect ratio `b^2/S`.
    pub fn aspect_ratio(&self) -> f64 {
        self.b * self.b / self.s
    }

    /// The inertia combinations `Gamma, Gamma_1..Gamma_8` of the book (eq. 3.13), with the
    /// book's `Gamma_2 = (Jz(Jz - Jy) + Jxz^2)/Gamma` (the 2012 code forgets the division).
    pub fn gammas(&self) -> [f64; 9] {
        let (jx, jy, jz, jxz) = (self.jx, self.jy, self.jz, self.jxz);
        let g = jx * jz - jxz * jxz;
        [
            g,
            jxz * (jx - jy + jz) / g,
            (jz * (jz - jy) + jxz * jxz) / g,
            jz / g,
            jxz / g,
            (jz - jx) / jy,
            jxz / jy,
            ((jx - jy) * jx + jxz * jxz) / g,
            jx / g,
        ]
    }

    /// Roll-rate coefficients `C_p* = Gamma3 C_ell* + Gamma4 C_n*` for `* = p, delta_a`.
    pub fn c_p_p_and_da(&self) -> (f64, f64) {
        let gm = self.gammas();
        (
            gm[3] * self.c_ell_p + gm[4] * self.c_n_p,
            gm[3] * self.c_ell_da + gm[4] * self.c_n_da,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derived_values_match_the_reference() {
        let p = Aerosonde::beard_mclain_2012();
        let gm = p.gammas();
        let want = [
            1.43562, 0.121472, 0.774655, 1.22525, 0.083866, 0.823436, 0.106079, -0.168263, 0.574245,
        ];
        for (k, (a, b)) in gm.iter().zip(want).enumerate() {
            // The reference rounds to 6 significant digits.
            assert!((a - b).abs() < 1e-5 * b.abs(), "Gamma{k}: {a} vs {b}");
        }
        let (cpp, cpda) = p.c_p_p_and_da();
        assert!((cpp + 0.31672).abs() < 1e-5, "{cpp}");
        assert!((cpda - 0.103052).abs() < 1e-6, "{cpda}");
        assert!((p.aspect_ratio() - 15.245).abs() < 1e-3);
    }

    /// The lateral coefficients, as published for the 2012 airframe (docs/FIXED-WING.md,
    /// section 1: Beard & McLain's Aerosonde table).
    #[test]
    fn lateral_coefficients_are_the_published_table() {
        let p = Aerosonde::beard_mclain_2012();
        let got = [
            [p.c_y0, p.c_y_beta, p.c_y_p, p.c_y_r, p.c_y_da, p.c_y_dr],
            [
                p.c_ell0,
                p.c_ell_beta,
                p.c_ell_p,
                p.c_ell_r,
                p.c_ell_da,
                p.c_ell_dr,
            ],
            [p.c_n0, p.c_n_beta, p.c_n_p, p.c_n_r, p.c_n_da, p.c_n_dr],
        ];
        let want = [
            [0.0, -0.98, 0.0, 0.0, 0.0, -0.17],
            [0.0, -0.12, -0.26, 0.14, 0.08, 0.105],
            [0.0, 0.25, 0.022, -0.35, 0.06, -0.032],
        ];
        assert_eq!(got, want);
    }
}
