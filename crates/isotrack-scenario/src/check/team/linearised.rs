//! The spacing loop linearised about the equilibrium the team converges to (issue 32, att46-1,
//! -16, -9; docs/TEAMS.md, "Theory"): one linearisation for every case, even spacing, a shifted
//! equilibrium of unequal nominal speeds and vehicles with no speed room.
//!
//! With `x_i` vehicle `i`'s arc position in the frame moving at the common speed `V`, `g_i =
//! x_{i+1} - x_i` its gap ahead and `c_i = dr/dg` the range slope of that gap at the equilibrium
//! (`cos(g_i/(2R))` for a chord of a circle of radius `R`), the unsaturated law linearised is
//!
//! ```text
//! x_i' = k_v (c_i dx_{i+1} - (c_i + c_{i-1}) dx_i + c_{i-1} dx_{i-1})      (free vehicle)
//! x_i' = 0                                                                   (pinned: its speed is V)
//! ```
//!
//! i.e. `x' = -k_v K x` with `K = D^T C D` (`D` the ring's difference, `C = diag(c_i)`),
//! symmetric positive semidefinite, restricted to the free vehicles (the pinned positions are
//! fixed: a Dirichlet problem). Without a pin `K`'s one zero is the ring's translation (the
//! gaps' sum) and its other eigenvalues are those of the gaps' `L C` (`AB` and `BA` share their
//! nonzero eigenvalues); at even spacing `c_i = c` and they are `c lambda_m`. Each eigenvalue
//! `mu` is one mode with gain per period `k_v mu T`.

use isotrack_core::spacing::ring_laplacian_eigenvalue;
use nalgebra::DMatrix;

/// Up to this many free vehicles the eigenvalues are computed exactly (a dense symmetric
/// eigen-decomposition, `O(n^3)`); beyond, with unequal slopes or pins, bounds
/// ([`LoopSpectrum::exact`] false).
pub const MAX_DENSE_VEHICLES: usize = 512;

/// The eigenvalues of the linearised loop's `K` ([`loop_spectrum`]), over a reference slope
/// `c`.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopSpectrum {
    /// `mu/c` for the distinct eigenvalues `mu` of the modes the law acts on (the translation's
    /// zero left out), ascending; within a relative 1e-9 counted once. At even spacing of a free
    /// ring (every slope `c`) exactly the ring Laplacian's `lambda_m`, `m = 1..=floor(N/2)`.
    /// With bounds, two: a lower bound of the smallest and an upper bound of the largest.
    pub lambdas: Vec<f64>,
    /// Whether `eigenvalues` are the eigenvalues (else bounds: the largest not understated, so
    /// `k_v*` is not overstated, and the smallest not overstated).
    pub exact: bool,
}

/// The spectrum, over the reference slope `c > 0`, of the loop of a ring whose gap `i` (from
/// vehicle `i` to `i + 1`) has range slope `slopes[i] > 0`, vehicles with `pinned[i]` flying
/// the common speed whatever is commanded. `None` for fewer than two vehicles, mismatched
/// lengths, a slope not in `(0, 1]` or every vehicle pinned (no loop).
pub fn loop_spectrum(c: f64, slopes: &[f64], pinned: &[bool]) -> Option<LoopSpectrum> {
    let n = slopes.len();
    let bad = |x: f64| x.is_nan() || x <= 0.0;
    if bad(c) || n < 2 || pinned.len() != n || slopes.iter().any(|&x| bad(x) || x > 1.0) {
        return None;
    }
    let free: Vec<usize> = (0..n).filter(|&i| !pinned[i]).collect();
    if free.is_empty() {
        return None;
    }
    if slopes.iter().all(|&s| s == c) && free.len() == n {
        // The circulant case in closed form: lambda_m, m = 1..floor(N/2), ascending.
        return Some(LoopSpectrum {
            lambdas: (1..=n / 2)
                .map(|m| ring_laplacian_eigenvalue(n, m))
                .collect(),
            exact: true,
        });
    }
    if free.len() > MAX_DENSE_VEHICLES {
        let mut b = bounds(slopes, pinned);
        b.lambdas.iter_mut().for_each(|m| *m /= c);
        return Some(b);
    }
    let k = stiffness(slopes, &free);
    let mut mu: Vec<f64> = k.symmetric_eigenvalues().iter().copied().collect();
    mu.sort_by(f64::total_cmp);
    if free.len() == n {
        mu.remove(0); // the translation
    }
    let scale = mu
        .last()
        .copied()
        .unwrap_or(0.0)
        .abs()
        .max(f64::MIN_POSITIVE);
    mu.iter_mut().for_each(|m| *m = m.max(0.0));
    mu.dedup_by(|b, a| (*b - *a).abs() <= 1e-9 * scale);
    Some(LoopSpectrum {
        lambdas: mu.iter().map(|m| m / c).collect(),
        exact: true,
    })
}

/// `K = D^T C D` of the ring with gap slopes `slopes`, restricted to the vehicles `free`
/// (ascending indices).
fn stiffness(slopes: &[f64], free: &[usize]) -> DMatrix<f64> {
    let n = slopes.len();
    let mut full = DMatrix::<f64>::zeros(n, n);
    for (i, &c) in slopes.iter().enumerate() {
        // Gap i joins vehicles i and i + 1: c (x_{i+1} - x_i)^2 / 2 in the energy.
        let j = (i + 1) % n;
        full[(i, i)] += c;
        full[(j, j)] += c;
        full[(i, j)] -= c;
        full[(j, i)] -= c;
    }
    DMatrix::from_fn(free.len(), free.len(), |a, b| full[(free[a], free[b])])
}

/// Bounds past [`MAX_DENSE_VEHICLES`]: the largest eigenvalue at most Gershgorin's
/// `max_i 2 (c_{i-1} + c_i)`, the smallest at least `min_i c_i` times the smallest of
/// `D^T D`'s (the ring's `lambda_1`, or with pins the path of the longest run of free
/// vehicles `k` between two pins, `2 - 2 cos(pi/(k + 1))`): `K >= c_min D^T D` and a
/// restriction to fewer free vehicles only raises the smallest eigenvalue.
fn bounds(slopes: &[f64], pinned: &[bool]) -> LoopSpectrum {
    let n = slopes.len();
    let top = (0..n)
        .filter(|&i| !pinned[i])
        .map(|i| 2.0 * (slopes[i] + slopes[(i + n - 1) % n]))
        .fold(0.0, f64::max);
    let c_min = slopes.iter().copied().fold(f64::INFINITY, f64::min);
    let base = if pinned.iter().any(|&p| p) {
        let start = (0..n).find(|&i| pinned[i]).unwrap_or(0);
        let (mut run, mut longest) = (0usize, 0usize);
        for k in 1..=n {
            if pinned[(start + k) % n] {
                run = 0;
            } else {
                run += 1;
                longest = longest.max(run);
            }
        }
        2.0 - 2.0 * (std::f64::consts::PI / (longest + 1) as f64).cos()
    } else {
        ring_laplacian_eigenvalue(n, 1)
    };
    LoopSpectrum {
        lambdas: vec![c_min * base, top],
        exact: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// One pin among N = 4 at equal slopes c: the Dirichlet path of three, eigenvalues
    /// `c (2 - 2 cos(pi m/4))`, m = 1, 2, 3 (att46-9's derivation).
    #[test]
    fn one_pin_is_the_dirichlet_path() {
        let c = (PI / 4.0).cos();
        let s = loop_spectrum(1.0, &[c; 4], &[true, false, false, false]).unwrap();
        assert!(s.exact);
        assert_eq!(s.lambdas.len(), 3);
        for (m, mu) in s.lambdas.iter().enumerate() {
            let want = c * (2.0 - 2.0 * (PI * (m + 1) as f64 / 4.0).cos());
            assert!((mu - want).abs() < 1e-12, "{mu} vs {want}");
        }
    }

    /// Unequal slopes, no pin, N = 3: the gaps' matrix `L C` by hand, its characteristic
    /// polynomial `mu^2 - 2 (c0 + c1 + c2) mu + 3 (c0 c1 + c1 c2 + c2 c0)` (the zero divided out).
    #[test]
    fn unequal_slopes_of_three_by_the_characteristic_polynomial() {
        let c = [0.128, 0.751, 0.559];
        let s = loop_spectrum(0.5, &c, &[false; 3]).unwrap();
        let b = 2.0 * (c[0] + c[1] + c[2]);
        let p = 3.0 * (c[0] * c[1] + c[1] * c[2] + c[2] * c[0]);
        let d = (b * b - 4.0 * p).sqrt();
        let want = [(b - d) / 2.0, (b + d) / 2.0];
        assert_eq!(s.lambdas.len(), 2);
        for (lambda, w) in s.lambdas.iter().zip(want) {
            assert!((0.5 * lambda - w).abs() < 1e-12, "{lambda} vs {w}");
        }
    }

    /// Bounds past the dense cap hold the dense eigenvalues between them (checked on a small
    /// ring through `bounds` directly).
    #[test]
    fn bounds_hold_the_eigenvalues() {
        let c: Vec<f64> = (0..9).map(|i| 0.3 + 0.07 * i as f64).collect();
        let mut pins = vec![false; 9];
        pins[2] = true;
        pins[6] = true;
        for p in [vec![false; 9], pins] {
            let exact = loop_spectrum(1.0, &c, &p).unwrap().lambdas;
            let b = bounds(&c, &p).lambdas;
            assert!(b[0] <= exact[0] + 1e-12 && exact[exact.len() - 1] <= b[1] + 1e-12);
        }
    }
}
