//! Theory of a team's spacing loop (docs/TEAMS.md): `N` vehicles on one closed isoline of length
//! `L`, each setting its speed from the ranges to its ring neighbours,
//! `v_i = v0 + k_v (r_i_ahead - r_i_behind)` (the `range_balance` law, unsaturated).
//!
//! With `s_i` the arc coordinate of vehicle `i` and `g_i = s_{i+1} - s_i` the gap ahead of it,
//! and ranges that follow gaps with slope `c = dr/dg` near even spacing (`c = 1` when ranges are
//! arc gaps; `c = cos(pi/N)` for chords of a circle at even spacing, since a chord is
//! `2 R sin(g/(2R))`), `g_i' = v_{i+1} - v_i`, so
//!
//! ```text
//! g_i' = k_v c (g_{i+1} - 2 g_i + g_{i-1}),
//! ```
//!
//! the ring's discrete Laplacian. Its eigenvalues are `-lambda_m`,
//! `lambda_m = 2 - 2 cos(2 pi m/N)`, `m = 0..N-1` (a circulant matrix: Gray, "Toeplitz and
//! circulant matrices: a review", 2006, sec. 3.1); `m = 0` is the sum of the gaps, `L`, which is
//! conserved; every other mode decays, the slowest (`m = 1`) with time constant
//! `1/(k_v c lambda_1)`, so the gaps converge to `L/N`.
//!
//! Sampled at the ranging period `T` with a delay `d = (q + f) T` (`q` whole, `0 <= f < 1`), the
//! speed set from the sample taken at `t_j = jT` is applied from `t_j + d` until the next sample's
//! arrival. Over `[t_j, t_{j+1})` a mode `x` of the gaps then obeys (gain `a = k_v c lambda_m`)
//!
//! ```text
//! x_{j+1} = x_j - a (f T x_{j-q-1} + (1 - f) T x_{j-q}),
//! ```
//!
//! whose characteristic polynomial is `z^{q+2} - z^{q+1} + g (1 - f) z + g f` with `g = a T`
//! ([`spacing_mode_polynomial`]). The loop is stable when every mode's polynomial has all its
//! roots inside the unit circle; the Schur-Cohn test ([`schur_stable`]) decides it. For `f = 0`
//! this is the delayed difference equation `x_{j+1} - x_j + g x_{j-q} = 0`, stable iff
//! `0 < g < 2 cos(q pi / (2q + 1))` (Levin & May, "A note on difference-delay equations",
//! Theoretical Population Biology 9, 1976), so with no delay `g < 2` (forward Euler's limit). The
//! largest stable gain over the modes is set by the largest eigenvalue, `lambda_max = 4` for even
//! `N` (`2 - 2 cos(2 pi floor(N/2)/N)` for odd `N`): [`max_stable_spacing_gain`].

use crate::fmath;

/// Degree bound of [`schur_stable`] and of the spacing polynomial (a delay of up to 62 ranging
/// periods).
pub const MAX_DEGREE: usize = 64;

/// Eigenvalue `lambda_m = 2 - 2 cos(2 pi m / N)` of the ring Laplacian `L x_i = 2 x_i - x_{i+1} -
/// x_{i-1}` on `n` vertices (a circulant matrix: Gray 2006, sec. 3.1). `n = 0` gives 0.
pub fn ring_laplacian_eigenvalue(n: usize, m: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let (_, c) = fmath::sincos(2.0 * core::f64::consts::PI * (m % n) as f64 / n as f64);
    2.0 - 2.0 * c
}

/// The largest eigenvalue of the ring Laplacian on `n` vertices, `lambda_{floor(n/2)}`: 4 for
/// even `n`, `2 + 2 cos(pi/n)` for odd `n` (0 for `n < 2`; a ring of two has `lambda_1 = 4`).
pub fn ring_laplacian_max_eigenvalue(n: usize) -> f64 {
    if n < 2 {
        return 0.0;
    }
    ring_laplacian_eigenvalue(n, n / 2)
}

/// The ranging delay in whole periods and the fraction of one: `d = (q + f) T`, `q` whole,
/// `0 <= f < 1` (a delay within a part in 1e9 of a whole number of periods is that number).
/// `None` for invalid times or a delay past [`MAX_DEGREE`] periods.
pub fn split_delay(period_s: f64, delay_s: f64) -> Option<(usize, f64)> {
    if !(period_s > 0.0 && delay_s >= 0.0 && period_s.is_finite() && delay_s.is_finite()) {
        return None;
    }
    let r = delay_s / period_s;
    // A delay within a part in 1e9 of a whole number of periods is that number (steps are whole).
    let q = fmath::floor(r + 1e-9);
    let f = (r - q).max(0.0);
    let f = if f < 1e-9 { 0.0 } else { f };
    if q as usize + 2 > MAX_DEGREE {
        return None;
    }
    Some((q as usize, f))
}

/// The characteristic polynomial of one spacing mode sampled at period `T` with delay
/// `d = (q + f) T`, coefficients lowest degree first: `z^{q+2} - z^{q+1} + g (1 - f) z + g f`,
/// `g = a T` the mode's gain per period (module docs). Returns the degree (`q + 2`), or `None`
/// for a delay beyond [`MAX_DEGREE`] or invalid times.
pub fn spacing_mode_polynomial(
    gain_per_period: f64,
    period_s: f64,
    delay_s: f64,
    coeffs: &mut [f64; MAX_DEGREE + 1],
) -> Option<usize> {
    let (q, f) = split_delay(period_s, delay_s)?;
    *coeffs = [0.0; MAX_DEGREE + 1];
    let n = q + 2;
    coeffs[n] = 1.0;
    coeffs[n - 1] = -1.0;
    coeffs[1] += gain_per_period * (1.0 - f);
    coeffs[0] += gain_per_period * f;
    Some(n)
}

/// Whether every root of `p(z) = sum_k c_k z^k` (degree `n`, `c_n != 0`) lies strictly inside the
/// unit circle, by the Schur-Cohn reduction: if `|c_0| < |c_n|`, `p` is Schur-stable iff
/// `(c_n p(z) - c_0 z^n p(1/z)) / z` (degree `n - 1`) is; if `|c_0| >= |c_n|` it is not
/// (Marden, "Geometry of polynomials", 1966, sec. 42; Jury, "Theory and application of the
/// z-transform method", 1964). Coefficients past `n` are ignored.
pub fn schur_stable(coeffs: &[f64; MAX_DEGREE + 1], degree: usize) -> bool {
    let mut a = *coeffs;
    let mut n = degree.min(MAX_DEGREE);
    if a.iter().take(n + 1).any(|c| !c.is_finite()) || a[n] == 0.0 {
        return false;
    }
    while n > 0 {
        if a[0].abs() >= a[n].abs() {
            return false;
        }
        let (an, a0) = (a[n], a[0]);
        let mut b = [0.0; MAX_DEGREE + 1];
        let mut scale: f64 = 0.0;
        for j in 0..n {
            b[j] = an * a[j + 1] - a0 * a[n - 1 - j];
            scale = scale.max(b[j].abs());
        }
        if scale == 0.0 || !scale.is_finite() {
            return false;
        }
        for (aj, bj) in a.iter_mut().zip(b.iter()).take(n) {
            *aj = bj / scale;
        }
        n -= 1;
    }
    true
}

/// Whether one spacing mode with gain per period `g = k_v c lambda_m T` is stable, sampled at
/// period `period_s` with delay `delay_s` ([`spacing_mode_polynomial`], [`schur_stable`]);
/// `false` for a delay beyond [`MAX_DEGREE`] periods or invalid times. `g = 0` (a mode the law
/// does not act on) is marginal: not stable.
pub fn spacing_mode_stable(gain_per_period: f64, period_s: f64, delay_s: f64) -> bool {
    let mut c = [0.0; MAX_DEGREE + 1];
    match spacing_mode_polynomial(gain_per_period, period_s, delay_s, &mut c) {
        Some(n) if gain_per_period > 0.0 => schur_stable(&c, n),
        _ => false,
    }
}

/// The largest gain per period `g* = a T` up to which a spacing mode is stable at period
/// `period_s` with delay `delay_s`: the first `g` where [`spacing_mode_stable`] fails, found on a
/// grid of `g` in steps of 1/256 and refined by bisection to 1e-12 (the stable set starts at
/// `0+`; a gain past `g*` is reported unstable even if stability returned further on, which is
/// conservative). For `f = 0` it is Levin & May's `2 cos(q pi/(2q + 1))`; for a delay under one
/// period (`q = 0`, the quadratic `z^2 - (1 - g(1 - f)) z + g f`, Jury's conditions) it is
/// `min(1/f, 2/(1 - 2f))` (`1/f` for `f >= 1/2`): a delay of part of a period averages two
/// samples and can allow a larger gain than none (4 at `f = 1/4`, 2 at `f = 0` and `f = 1/2`).
/// `None` for invalid times or a delay past [`MAX_DEGREE`] periods.
pub fn max_stable_gain_per_period(period_s: f64, delay_s: f64) -> Option<f64> {
    split_delay(period_s, delay_s)?;
    let step = 1.0 / 256.0;
    let mut lo = step * 1e-3;
    if !spacing_mode_stable(lo, period_s, delay_s) {
        return Some(0.0);
    }
    // g* <= 4 (at most min(1/f, 2/(1 - 2f)) for q = 0, at f = 1/4; less for q > 0), so the
    // scan ends by 4 + step.
    let mut hi = step;
    while spacing_mode_stable(hi, period_s, delay_s) {
        lo = hi;
        hi += step;
        if hi > 8.0 {
            return Some(lo);
        }
    }
    while hi - lo > 1e-12 {
        let mid = 0.5 * (lo + hi);
        if spacing_mode_stable(mid, period_s, delay_s) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// The largest stable `k_v` (1/s) of `range_balance` for a ring of `n >= 2` vehicles, ranging
/// period `period_s`, delay `delay_s` and range slope `c = dr/dg` (1: ranges are arc gaps; a
/// chord of a circle at even spacing: `cos(pi/n)`): `k_v* = g* / (T c lambda_max)` with `g*` from
/// [`max_stable_gain_per_period`] and `lambda_max` from [`ring_laplacian_max_eigenvalue`]. `None`
/// for `n < 2`, `c <= 0` or invalid times.
pub fn max_stable_spacing_gain(
    n: usize,
    period_s: f64,
    delay_s: f64,
    range_slope: f64,
) -> Option<f64> {
    if n < 2 || !(range_slope > 0.0 && range_slope.is_finite()) {
        return None;
    }
    let g = max_stable_gain_per_period(period_s, delay_s)?;
    Some(g / (period_s * range_slope * ring_laplacian_max_eigenvalue(n)))
}

/// The spectral radius of a spacing mode's polynomial (the largest root magnitude): the `r`
/// where `p(r z)` stops being Schur-stable, by bisection to 1e-12. `None` for invalid times.
pub fn spacing_mode_spectral_radius(
    gain_per_period: f64,
    period_s: f64,
    delay_s: f64,
) -> Option<f64> {
    let mut c = [0.0; MAX_DEGREE + 1];
    let n = spacing_mode_polynomial(gain_per_period, period_s, delay_s, &mut c)?;
    // All roots inside radius r iff p(r z) (coefficients c_k r^k) is Schur-stable.
    let inside = |r: f64| {
        let mut s = [0.0; MAX_DEGREE + 1];
        let mut rk = 1.0;
        for k in 0..=n {
            s[k] = c[k] * rk;
            rk *= r;
        }
        schur_stable(&s, n)
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    while !inside(hi) {
        lo = hi;
        hi *= 2.0;
        if hi > 1e6 {
            return None;
        }
    }
    while hi - lo > 1e-12 {
        let mid = 0.5 * (lo + hi);
        if inside(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}

/// The slowest spacing mode's time constant, s, in continuous time: `1/(k_v c lambda_1)`,
/// `lambda_1 = 2 - 2 cos(2 pi/N)` (infinite for `n < 2` or a zero gain).
pub fn slowest_mode_time_constant_s(n: usize, k_v: f64, range_slope: f64) -> f64 {
    if n < 2 {
        return f64::INFINITY;
    }
    1.0 / (k_v * range_slope * ring_laplacian_eigenvalue(n, 1))
}

/// The slowest sampled spacing mode: the `m` in `1..=floor(N/2)` (the distinct nonzero
/// eigenvalues, `lambda_m = lambda_{N-m}`) whose polynomial has the largest spectral radius
/// ([`spacing_mode_spectral_radius`]), with that radius. Without delay and at a small gain this is
/// `m = 1`, as in continuous time; with a delay the modes of large `lambda_m` sit near the
/// stability edge and can decay far more slowly (N = 4, `T` = 1 s, `d` = 2 s, `k_v` = 0.2 1/s,
/// chords `c = cos(pi/4)`: `m = 2`, radius 0.9747, against 0.90 for `m = 1`). `None` for
/// `n < 2` or invalid times; ties keep the smaller `m`.
pub fn slowest_sampled_mode(
    n: usize,
    k_v: f64,
    range_slope: f64,
    period_s: f64,
    delay_s: f64,
) -> Option<(usize, f64)> {
    if n < 2 {
        return None;
    }
    let mut slowest: Option<(usize, f64)> = None;
    for m in 1..=n / 2 {
        let g = k_v * range_slope * ring_laplacian_eigenvalue(n, m) * period_s;
        let rho = spacing_mode_spectral_radius(g, period_s, delay_s)?;
        if slowest.is_none_or(|(_, r)| rho > r) {
            slowest = Some((m, rho));
        }
    }
    slowest
}

/// The slowest spacing mode's time constant, s, sampled at period `T` with delay `d`:
/// `-T / ln(rho)`, `rho` the largest spectral radius over the modes ([`slowest_sampled_mode`]);
/// infinite for a mode that does not decay. Tends to [`slowest_mode_time_constant_s`] (mode
/// `m = 1`) as `T, d -> 0`.
pub fn slowest_mode_time_constant_sampled_s(
    n: usize,
    k_v: f64,
    range_slope: f64,
    period_s: f64,
    delay_s: f64,
) -> Option<f64> {
    if n < 2 {
        return Some(f64::INFINITY);
    }
    let (_, rho) = slowest_sampled_mode(n, k_v, range_slope, period_s, delay_s)?;
    if rho >= 1.0 {
        return Some(f64::INFINITY);
    }
    Some(-period_s / fmath::ln(rho))
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    /// Eigenvalues against the circulant formula's special cases: `lambda_{N/2} = 4`, `lambda_0 =
    /// 0`, `lambda_1 (N = 4) = 2`, `lambda_1 (N = 6) = 1`, odd `N`'s maximum `2 + 2 cos(pi/N)`.
    #[test]
    fn ring_eigenvalues() {
        assert!(ring_laplacian_eigenvalue(4, 0).abs() < 1e-15);
        assert!((ring_laplacian_eigenvalue(4, 1) - 2.0).abs() < 1e-14);
        assert!((ring_laplacian_eigenvalue(6, 1) - 1.0).abs() < 1e-14);
        assert!((ring_laplacian_max_eigenvalue(4) - 4.0).abs() < 1e-14);
        let odd = 2.0 + 2.0 * (PI / 5.0).cos();
        assert!((ring_laplacian_max_eigenvalue(5) - odd).abs() < 1e-14);
    }

    /// With a ranging delay the slowest sampled mode is not `m = 1` (att32's case A: N = 4, 1 Hz
    /// ranging, 2 s delay, `k_v` = 0.2 1/s, chords `c = cos(pi/4)`). Checked against the decay of
    /// the mode's own difference equation `x_{j+1} = x_j - g x_{j-2}` stepped 4000 periods from a
    /// unit impulse (an independent computation: the envelope's log ratio over 1000 periods).
    #[test]
    fn the_slowest_sampled_mode_is_the_largest_radius() {
        let c = (PI / 4.0).cos();
        let (m, rho) = slowest_sampled_mode(4, 0.2, c, 1.0, 2.0).unwrap();
        assert_eq!(m, 2);
        let decay = |g: f64| {
            let mut x = [0.0f64; 4003];
            x[2] = 1.0;
            for j in 2..4002 {
                x[j + 1] = x[j] - g * x[j - 2];
            }
            let env = |a: usize| x[a..a + 50].iter().fold(0.0f64, |e, v| e.max(v.abs()));
            fmath::ln(env(3900) / env(2900)) / 1000.0
        };
        let g2 = 0.2 * c * ring_laplacian_eigenvalue(4, 2);
        let g1 = 0.2 * c * ring_laplacian_eigenvalue(4, 1);
        // Decay per period as ln(rho): mode 2's is its radius's, mode 1's is faster.
        let ln_rho = fmath::ln(rho);
        assert!(
            (decay(g2) - ln_rho).abs() < 2e-4,
            "{} vs {ln_rho}",
            decay(g2)
        );
        assert!(
            decay(g1) < ln_rho - 0.03,
            "mode 1 decays faster: {}",
            decay(g1)
        );
        let tau = slowest_mode_time_constant_sampled_s(4, 0.2, c, 1.0, 2.0).unwrap();
        assert!(
            (tau + 1.0 / fmath::ln(rho)).abs() < 1e-9 && tau > 35.0,
            "{tau}"
        );
        // No delay, small gain: m = 1, as in continuous time.
        assert_eq!(slowest_sampled_mode(6, 0.05, 1.0, 0.01, 0.0).unwrap().0, 1);
    }

    /// Schur-Cohn against polynomials with known roots.
    #[test]
    fn schur_cohn_known_roots() {
        let mut c = [0.0; MAX_DEGREE + 1];
        // (z - 0.5)(z + 0.9) = z^2 + 0.4 z - 0.45: stable.
        c[..3].copy_from_slice(&[-0.45, 0.4, 1.0]);
        assert!(schur_stable(&c, 2));
        // (z - 0.5)(z + 1.1) = z^2 + 0.6 z - 0.55: unstable.
        c[..3].copy_from_slice(&[-0.55, 0.6, 1.0]);
        assert!(!schur_stable(&c, 2));
        // z^2 + 0.81 (roots +-0.9i): stable; z^2 + 1.21: not.
        c[..3].copy_from_slice(&[0.81, 0.0, 1.0]);
        assert!(schur_stable(&c, 2));
        c[..3].copy_from_slice(&[1.21, 0.0, 1.0]);
        assert!(!schur_stable(&c, 2));
        // (z - 0.3)(z^2 - 1.6 z + 0.89) (roots 0.8 +- 0.5i, |.| = 0.943): stable.
        c[..4].copy_from_slice(&[-0.267, 0.89 + 0.48, -1.6 - 0.3, 1.0]);
        assert!(schur_stable(&c, 3));
    }

    /// No delay: `g* = 2` (forward Euler); whole-period delays: Levin & May's
    /// `2 cos(q pi/(2q + 1))` (1 for q = 1, 2 cos(2 pi/5) = 0.618 for q = 2).
    #[test]
    fn max_gain_matches_levin_may() {
        let t = 0.1;
        for q in 0..6usize {
            let g = max_stable_gain_per_period(t, q as f64 * t).unwrap();
            let lm = 2.0 * (q as f64 * PI / (2.0 * q as f64 + 1.0)).cos();
            assert!((g - lm).abs() < 1e-9, "q = {q}: {g} vs {lm}");
        }
    }

    /// A delay under one period: Jury's conditions on `z^2 - (1 - g(1 - f)) z + g f` give
    /// `g* = min(1/f, 2/(1 - 2f))` (`1/f` from `f = 1/2` on).
    #[test]
    fn fractional_delay_by_jury() {
        for f in [0.1f64, 0.25, 0.4, 0.5, 0.75, 0.9] {
            let closed = if f < 0.5 {
                (1.0 / f).min(2.0 / (1.0 - 2.0 * f))
            } else {
                1.0 / f
            };
            let g = max_stable_gain_per_period(2.0, 2.0 * f).unwrap();
            // At f = 1/4 both conditions meet (a double root at -1): 1e-7 there.
            assert!((g - closed).abs() < 1e-7, "f = {f}: {g} vs {closed}");
        }
    }

    /// Spectral radius: no delay, the root is `1 - g`; the sampled time constant tends to the
    /// continuous one for a short period.
    #[test]
    fn spectral_radius_and_time_constant() {
        let r = spacing_mode_spectral_radius(0.3, 1.0, 0.0).unwrap();
        assert!((r - 0.7).abs() < 1e-9, "{r}");
        let r = spacing_mode_spectral_radius(1.5, 1.0, 0.0).unwrap();
        assert!((r - 0.5).abs() < 1e-9, "{r}");
        let tc = slowest_mode_time_constant_s(4, 0.05, 1.0);
        assert!((tc - 10.0).abs() < 1e-12);
        let ts = slowest_mode_time_constant_sampled_s(4, 0.05, 1.0, 0.01, 0.0).unwrap();
        assert!((ts - tc).abs() / tc < 1e-2, "{ts} vs {tc}");
        let k = max_stable_spacing_gain(4, 0.1, 0.0, 1.0).unwrap();
        assert!((k - 2.0 / (0.1 * 4.0)).abs() < 1e-9);
    }
}
