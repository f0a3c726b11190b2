//! Wind: a steady part plus Dryden turbulence (MIL-F-8785C low-altitude form, as in Beard &
//! McLain section 4.4), seeded.
//!
//! Transfer functions at the nominal airspeed `Va`:
//! `H_u = s_u sqrt(2 Va/L_u)/(s + Va/L_u)`,
//! `H_v = s_v sqrt(3 Va/L_v)(s + Va/(sqrt(3) L_v))/(s + Va/L_v)^2`, `H_w` likewise with `L_w, s_w`,
//! driven by unit-intensity white noise, realised in controllable canonical form and integrated
//! by Euler-Maruyama at the simulation step (`x += dt A x + B sqrt(dt) n`, `n ~ N(0, 1)` from a
//! ChaCha8 stream): the gusts' standard deviations approach `s_u, s_v, s_w`.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Dryden parameters (the book's low-altitude, light-turbulence values by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrydenParams {
    /// Scale lengths `L_u, L_v, L_w`, m.
    pub length_m: [f64; 3],
    /// Intensities `sigma_u, sigma_v, sigma_w`, m/s.
    pub sigma_mps: [f64; 3],
}

impl Default for DrydenParams {
    fn default() -> Self {
        Self {
            length_m: [200.0, 200.0, 50.0],
            sigma_mps: [1.06, 1.06, 0.7],
        }
    }
}

/// The gust generator's state.
#[derive(Clone, Debug)]
pub struct Dryden {
    /// Output gains `s sqrt(2 Va/L_u)`, `s sqrt(3 Va/L)` (v, w), precomputed.
    gain: [f64; 3],
    /// The filters' break frequencies `Va/L_u`, `Va/L_v`, `Va/L_w`, 1/s, precomputed.
    rate: [f64; 3],
    /// `(dt, sqrt(dt))` of the last step: the noise's scale, recomputed only when `dt` changes.
    sqrt_dt: (f64, f64),
    xu: f64,
    xv: [f64; 2],
    xw: [f64; 2],
    rng: ChaCha8Rng,
}

impl Dryden {
    /// A generator at rest for nominal airspeed `va_mps`, seeded by `seed` (its own stream, so
    /// gusts and sensor noise never share random numbers).
    pub fn new(params: DrydenParams, va_mps: f64, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(0x6775_7374); // "gust"
        let [lu, lv, lw] = params.length_m;
        let [su, sv, sw] = params.sigma_mps;
        Self {
            gain: [
                su * (2.0 * va_mps / lu).sqrt(),
                sv * (3.0 * va_mps / lv).sqrt(),
                sw * (3.0 * va_mps / lw).sqrt(),
            ],
            rate: [va_mps / lu, va_mps / lv, va_mps / lw],
            sqrt_dt: (0.0, 0.0),
            xu: 0.0,
            xv: [0.0; 2],
            xw: [0.0; 2],
            rng,
        }
    }

    /// Advances by `dt_s` and returns the body-axis gusts `[u, v, w]`, m/s.
    #[inline(always)]
    pub fn step(&mut self, dt_s: f64) -> [f64; 3] {
        let [au, av, aw] = self.rate;
        let [gu_k, gv_k, gw_k] = self.gain;
        if self.sqrt_dt.0 != dt_s {
            self.sqrt_dt = (dt_s, dt_s.sqrt());
        }
        let sq = self.sqrt_dt.1;
        let mut n = || -> f64 { StandardNormal.sample(&mut self.rng) };
        let (nu, nv, nw) = (n(), n(), n());
        // u: x' = -a x + w, y = s sqrt(2 Va/L) x.
        self.xu += -au * self.xu * dt_s + sq * nu;
        let gu = gu_k * self.xu;
        // v, w: x1' = x2, x2' = -a^2 x1 - 2a x2 + w, y = K (a/sqrt(3) x1 + x2).
        let second = |x: &mut [f64; 2], a: f64, k: f64, noise: f64| {
            let (x1, x2) = (x[0], x[1]);
            x[0] += x2 * dt_s;
            x[1] += (-a * a * x1 - 2.0 * a * x2) * dt_s + sq * noise;
            k * (a * 0.577_350_269_189_625_8 * x[0] + x[1]) // 1/sqrt(3)
        };
        let gv = second(&mut self.xv, av, gv_k, nv);
        let gw = second(&mut self.xw, aw, gw_k, nw);
        [gu, gv, gw]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gust_intensities_approach_sigma_and_are_seeded() {
        let mut d = Dryden::new(DrydenParams::default(), 30.0, 7);
        let n = 400_000;
        let mut acc = [0.0f64; 3];
        let mut first = None;
        for k in 0..n {
            let g = d.step(0.01);
            if k == 0 {
                first = Some(g);
            }
            if k > 10_000 {
                for i in 0..3 {
                    acc[i] += g[i] * g[i];
                }
            }
        }
        let sd: Vec<f64> = acc
            .iter()
            .map(|a| (a / (n - 10_001) as f64).sqrt())
            .collect();
        for (s, want) in sd.iter().zip([1.06, 1.06, 0.7]) {
            assert!((s - want).abs() < 0.15 * want, "std {s} vs {want}");
        }
        let mut d2 = Dryden::new(DrydenParams::default(), 30.0, 7);
        assert_eq!(Some(d2.step(0.01)), first);
    }

    /// The Dryden filters' defining property, sharply: each output's variance is sigma^2
    /// (for `v`, `w`: `K^2 (1 + b^2/a^2)/(4a) = sigma^2` with `K^2 = 3 a sigma^2`, `b = a/sqrt(3)`),
    /// here with short scale lengths (10, 10, 5 m at 30 m/s: correlation times 0.33 s and
    /// 0.17 s), so 1000 s hold about 3000 of them and the standard deviation is known to ~2 %.
    #[test]
    fn gust_variances_are_sigma_squared() {
        let params = DrydenParams {
            length_m: [10.0, 10.0, 5.0],
            sigma_mps: [1.0, 2.0, 0.5],
        };
        let mut d = Dryden::new(params, 30.0, 3);
        let (n, skip) = (1_000_000, 10_000);
        let mut acc = [0.0f64; 3];
        for k in 0..n {
            let g = d.step(0.001);
            if k >= skip {
                for i in 0..3 {
                    acc[i] += g[i] * g[i];
                }
            }
        }
        for (i, (a, want)) in acc.iter().zip(params.sigma_mps).enumerate() {
            let sd = (a / (n - skip) as f64).sqrt();
            assert!(
                (sd - want).abs() < 0.06 * want,
                "component {i}: std {sd} vs {want}"
            );
        }
    }
}
