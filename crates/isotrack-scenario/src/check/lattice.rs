//! Field bounds over regions of a lattice, for Prop. 2's `gamma1..3` and the sampled check's
//! slope range.
//!
//! The field is sampled on an `n x n` lattice over the operating region. A lattice *cell* belongs
//! to a level band `[lo, hi]` when the range of its four corner values meets the band: a band
//! thinner than the change across one cell still marks the cells it passes through, so a flood
//! fill over cells (4-neighbours sharing an edge) cannot split a thin tube the way a fill over
//! lattice points can. The bounds are taken over the corners of the cells of a component, with a
//! margin for what lies between lattice points (see [`Bounds`]).

use crate::field::FieldModel;
use isotrack_core::math::{sym_spectral_norm, Vec2};
use isotrack_core::{FieldDerivatives, ScalarField};

/// The field sampled on the lattice.
pub(crate) struct Lattice<'a> {
    field: &'a FieldModel,
    region: [f64; 4],
    /// Lattice points per side.
    n: usize,
    values: Vec<f64>,
}

/// Bounds on the field over a set of cells, with margins: with `d` the half-diagonal of a cell
/// (the farthest any point is from a sampled corner), `gamma1 = min|grad F| - g3 d` and
/// `gamma2 = max|grad F| + g3 d` (the gradient is `g3`-Lipschitz when `||hess F|| <= g3`), and
/// `gamma3 = max||hess F|| + L d`, where `L` is the largest change of `||hess F||` per metre
/// between neighbouring lattice points (a finite-difference estimate of the third derivative).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub gamma1: f64,
    pub gamma2: f64,
    /// `None` when the field has no Hessian (bilinear grids).
    pub gamma3: Option<f64>,
    /// Lattice points the bounds were taken over.
    pub points: usize,
    /// `[min, max]` of the field's sampled values at those points (no margin: what the field
    /// was seen to take there, not a bound between the points).
    pub values: [f64; 2],
}

impl<'a> Lattice<'a> {
    /// Samples `field` on `n x n` points (`n >= 3`) over `region` `[x0, x1, y0, y1]`.
    pub(crate) fn new(field: &'a FieldModel, region: [f64; 4], n: usize) -> Self {
        let n = n.max(3);
        let mut values = Vec::with_capacity(n * n);
        for j in 0..n {
            match field {
                // An analytic field answers eight points at once with `value`'s numbers bit
                // for bit (`ScalarField::value_lanes`): the lattice of `check` and of every
                // run's warnings is 601 x 601 points.
                FieldModel::Analytic(a) => {
                    const L: usize = 8;
                    let mut i = 0;
                    while i < n {
                        let (mut x, mut y) = ([0.0; L], [0.0; L]);
                        let m = L.min(n - i);
                        for k in 0..L {
                            // Lanes past the row's end repeat its last point (not kept).
                            let p = Self::point_in(region, n, i + k.min(m - 1), j);
                            (x[k], y[k]) = (p.x, p.y);
                        }
                        values.extend_from_slice(&a.value_lanes(0.0, &x, &y)[..m]);
                        i += m;
                    }
                }
                _ => {
                    for i in 0..n {
                        let p = Self::point_in(region, n, i, j);
                        values.push(field.value(0.0, p).unwrap_or(f64::NAN));
                    }
                }
            }
        }
        Self {
            field,
            region,
            n,
            values,
        }
    }

    fn point_in(region: [f64; 4], n: usize, i: usize, j: usize) -> Vec2 {
        Vec2::new(
            region[0] + (region[1] - region[0]) * i as f64 / (n - 1) as f64,
            region[2] + (region[3] - region[2]) * j as f64 / (n - 1) as f64,
        )
    }

    pub(crate) fn point(&self, i: usize, j: usize) -> Vec2 {
        Self::point_in(self.region, self.n, i, j)
    }

    /// Half the diagonal of a cell, m.
    pub(crate) fn half_diagonal_m(&self) -> f64 {
        let hx = (self.region[1] - self.region[0]) / (self.n - 1) as f64;
        let hy = (self.region[3] - self.region[2]) / (self.n - 1) as f64;
        0.5 * hx.hypot(hy)
    }

    /// Range of the corner values of cell `(i, j)` (`None` if a corner has no value).
    fn cell_range(&self, i: usize, j: usize) -> Option<(f64, f64)> {
        let c = [
            self.values[j * self.n + i],
            self.values[j * self.n + i + 1],
            self.values[(j + 1) * self.n + i],
            self.values[(j + 1) * self.n + i + 1],
        ];
        if c.iter().any(|v| v.is_nan()) {
            return None;
        }
        Some(
            c.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                }),
        )
    }

    fn cell_in_band(&self, i: usize, j: usize, lo: f64, hi: f64) -> bool {
        self.cell_range(i, j)
            .is_some_and(|(a, b)| b >= lo && a <= hi)
    }

    /// The cell containing `p`, if it lies inside the lattice.
    pub(crate) fn cell_of(&self, p: Vec2) -> Option<(usize, usize)> {
        let fx = (p.x - self.region[0]) / (self.region[1] - self.region[0]) * (self.n - 1) as f64;
        let fy = (p.y - self.region[2]) / (self.region[3] - self.region[2]) * (self.n - 1) as f64;
        if !(fx >= 0.0 && fy >= 0.0 && fx <= (self.n - 1) as f64 && fy <= (self.n - 1) as f64) {
            return None;
        }
        Some(((fx as usize).min(self.n - 2), (fy as usize).min(self.n - 2)))
    }

    /// The band's cell nearest `p` (by cell centre); of cells at the same distance, the first in
    /// row-major order (lowest `j`, then lowest `i`), so the choice never depends on rounding luck.
    pub(crate) fn nearest_band_cell(&self, p: Vec2, lo: f64, hi: f64) -> Option<(usize, usize)> {
        let mut best: Option<((usize, usize), f64)> = None;
        for j in 0..self.n - 1 {
            for i in 0..self.n - 1 {
                if self.cell_in_band(i, j, lo, hi) {
                    let c = (self.point(i, j) + self.point(i + 1, j + 1)) * 0.5;
                    let d = (c - p).norm();
                    if best.is_none_or(|(_, b)| d < b) {
                        best = Some(((i, j), d));
                    }
                }
            }
        }
        best.map(|(c, _)| c)
    }

    /// The cells of the band `[lo, hi]` connected to `seed` (4-neighbours), as a mask over
    /// cells; empty if the seed cell is not in the band.
    pub(crate) fn component(&self, seed: (usize, usize), lo: f64, hi: f64) -> Vec<bool> {
        let m = self.n - 1;
        let mut seen = vec![false; m * m];
        if !self.cell_in_band(seed.0, seed.1, lo, hi) {
            return seen;
        }
        let mut stack = vec![seed];
        seen[seed.1 * m + seed.0] = true;
        while let Some((i, j)) = stack.pop() {
            let mut visit = |i: usize, j: usize| {
                if !seen[j * m + i] && self.cell_in_band(i, j, lo, hi) {
                    seen[j * m + i] = true;
                    stack.push((i, j));
                }
            };
            if i > 0 {
                visit(i - 1, j);
            }
            if i + 1 < m {
                visit(i + 1, j);
            }
            if j > 0 {
                visit(i, j - 1);
            }
            if j + 1 < m {
                visit(i, j + 1);
            }
        }
        seen
    }

    /// The lattice points that are corners of the cells in `cells`.
    fn corner_mask(&self, cells: &[bool]) -> Vec<bool> {
        let m = self.n - 1;
        let mut pts = vec![false; self.n * self.n];
        for j in 0..m {
            for i in 0..m {
                if cells[j * m + i] {
                    for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        pts[(j + b) * self.n + i + a] = true;
                    }
                }
            }
        }
        pts
    }

    /// `|grad F|` at every corner of the cells in `cells`.
    pub(crate) fn slopes(&self, cells: &[bool]) -> Vec<f64> {
        let pts = self.corner_mask(cells);
        (0..self.n * self.n)
            .filter(|&k| pts[k])
            .filter_map(|k| self.field.gradient(0.0, self.point(k % self.n, k / self.n)))
            .map(|g| g.norm())
            .filter(|g| g.is_finite())
            .collect()
    }

    /// `|grad F|` where the isoline `F = level` crosses an edge of a cell in `cells` (the
    /// crossing placed by linear interpolation between the edge's two corners): the slopes on
    /// the isoline itself, as against [`Lattice::slopes`] over the whole band.
    pub(crate) fn isoline_slopes(&self, cells: &[bool], level: f64) -> Vec<f64> {
        let m = self.n - 1;
        let value = |i: usize, j: usize| self.values[j * self.n + i] - level;
        let mut out = vec![];
        for j in 0..m {
            for i in 0..m {
                if !cells[j * m + i] {
                    continue;
                }
                for (a, b) in [
                    ((i, j), (i + 1, j)),
                    ((i, j + 1), (i + 1, j + 1)),
                    ((i, j), (i, j + 1)),
                    ((i + 1, j), (i + 1, j + 1)),
                ] {
                    let (fa, fb) = (value(a.0, a.1), value(b.0, b.1));
                    if !(fa * fb <= 0.0 && fa != fb) {
                        continue;
                    }
                    let (pa, pb) = (self.point(a.0, a.1), self.point(b.0, b.1));
                    let p = pa + (pb - pa) * (fa / (fa - fb));
                    if let Some(g) = self.field.gradient(0.0, p) {
                        out.push(g.norm());
                    }
                }
            }
        }
        out.retain(|g| g.is_finite());
        out
    }

    /// Bounds over the corners of the cells in `cells`, with margins (see [`Bounds`]);
    /// `has_hessian = false` leaves `gamma3` out (and the gradient margin with it).
    pub(crate) fn bounds(&self, cells: &[bool], has_hessian: bool) -> Option<Bounds> {
        let pts = self.corner_mask(cells);
        let mut hess_norm = vec![f64::NAN; self.n * self.n];
        let (mut g1, mut g2, mut g3, mut n) = (f64::INFINITY, 0.0f64, 0.0f64, 0usize);
        let mut values = [f64::INFINITY, f64::NEG_INFINITY];
        for k in (0..self.n * self.n).filter(|&k| pts[k]) {
            let p = self.point(k % self.n, k / self.n);
            let Some(g) = self.field.gradient(0.0, p) else {
                continue;
            };
            n += 1;
            // `f64::min`/`max` pass over a NaN value.
            values = [values[0].min(self.values[k]), values[1].max(self.values[k])];
            g1 = g1.min(g.norm());
            g2 = g2.max(g.norm());
            if has_hessian {
                if let Some(h) = self.field.hessian(0.0, p) {
                    hess_norm[k] = sym_spectral_norm(&h);
                    g3 = g3.max(hess_norm[k]);
                }
            }
        }
        if n == 0 {
            return None;
        }
        let d = self.half_diagonal_m();
        if !has_hessian {
            return Some(Bounds {
                gamma1: g1,
                gamma2: g2,
                gamma3: None,
                points: n,
                values,
            });
        }
        // Largest change of ||hess F|| per metre between neighbouring points of the set.
        let hx = (self.region[1] - self.region[0]) / (self.n - 1) as f64;
        let hy = (self.region[3] - self.region[2]) / (self.n - 1) as f64;
        let mut lip = 0.0f64;
        for j in 0..self.n {
            for i in 0..self.n {
                let a = hess_norm[j * self.n + i];
                if a.is_nan() {
                    continue;
                }
                // A neighbour outside the set has a NaN norm, so its difference is NaN, which
                // `f64::max` passes over (it returns the other argument).
                if i + 1 < self.n {
                    lip = lip.max((hess_norm[j * self.n + i + 1] - a).abs() / hx);
                }
                if j + 1 < self.n {
                    lip = lip.max((hess_norm[(j + 1) * self.n + i] - a).abs() / hy);
                }
            }
        }
        let gamma3 = g3 + lip * d;
        Some(Bounds {
            gamma1: (g1 - gamma3 * d).max(0.0),
            gamma2: g2 + gamma3 * d,
            gamma3: Some(gamma3),
            points: n,
            values,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isotrack_fields::{AnalyticField, AnalyticKind, LinearRamp, RadialExp};
    use std::collections::BTreeSet;

    fn ramp() -> FieldModel {
        // F = 3 + 2x - y: |grad F| = sqrt(5) everywhere, no curvature.
        FieldModel::Analytic(AnalyticField::new(AnalyticKind::LinearRamp(LinearRamp {
            offset: 3.0,
            gradient_per_m: Vec2::new(2.0, -1.0),
        })))
    }

    /// On a 5 x 5 lattice over [0, 4]^2 (1 m cells), cell (i, j) spans F in
    /// [2 + 2i - j, 5 + 2i - j], so it meets the band [6, 6.5] iff 1 <= 2i - j <= 4: eight
    /// cells, one component. Its bounds are the ramp's slope exactly (no curvature, no margin).
    #[test]
    fn a_ramps_band_cells_and_bounds_by_hand() {
        let f = ramp();
        let l = Lattice::new(&f, [0.0, 4.0, 0.0, 4.0], 5);
        assert_eq!(l.point(0, 0), Vec2::new(0.0, 0.0));
        assert_eq!(l.point(4, 2), Vec2::new(4.0, 2.0));
        assert!((l.half_diagonal_m() - 0.5 * 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(l.cell_of(Vec2::new(2.5, 1.2)), Some((2, 1)));
        assert_eq!(
            l.cell_of(Vec2::new(4.0, 4.0)),
            Some((3, 3)),
            "the last edge is in"
        );
        assert_eq!(l.cell_of(Vec2::new(-0.1, 1.0)), None);
        assert_eq!(l.cell_of(Vec2::new(1.0, 4.1)), None);
        assert_eq!(l.cell_of(Vec2::new(4.1, 1.0)), None, "past the last column");
        assert_eq!(l.cell_of(Vec2::new(4.9, 4.9)), None);
        let (lo, hi) = (6.0, 6.5);
        let by_hand: BTreeSet<(usize, usize)> = (0..4)
            .flat_map(|i| (0..4).map(move |j| (i, j)))
            .filter(|&(i, j)| (1..=4).contains(&(2 * i as i64 - j as i64)))
            .collect();
        assert_eq!(by_hand.len(), 8);
        let mask = l.component((2, 1), lo, hi);
        let got: BTreeSet<(usize, usize)> = (0..16)
            .filter(|&k| mask[k])
            .map(|k| (k % 4, k / 4))
            .collect();
        assert_eq!(got, by_hand);
        // The same component from a seed in the top row (whose index is not its mirror's).
        let from_corner = l.component((3, 3), lo, hi);
        assert_eq!(from_corner, mask);
        // Not in the band: an empty component, and no bounds over it.
        let none = l.component((0, 3), lo, hi);
        assert!(none.iter().all(|&c| !c));
        assert_eq!(l.bounds(&none, true), None);
        // The band cell nearest the origin, by cell centre: (1, 0), centre (1.5, 0.5).
        assert_eq!(
            l.nearest_band_cell(Vec2::new(0.0, 0.0), lo, hi),
            Some((1, 0))
        );
        assert_eq!(
            l.nearest_band_cell(Vec2::new(4.0, 4.0), lo, hi),
            Some((3, 3))
        );
        assert_eq!(l.nearest_band_cell(Vec2::new(0.0, 0.0), 100.0, 101.0), None);
        // Bounds over the corners of the eight cells.
        let corners: BTreeSet<(usize, usize)> = by_hand
            .iter()
            .flat_map(|&(i, j)| [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)])
            .collect();
        let b = l.bounds(&mask, true).unwrap();
        let s5 = 5f64.sqrt();
        assert_eq!(b.points, corners.len());
        assert!(
            (b.gamma1 - s5).abs() < 1e-12 && (b.gamma2 - s5).abs() < 1e-12,
            "{b:?}"
        );
        assert_eq!(b.gamma3, Some(0.0));
        let b = l.bounds(&mask, false).unwrap();
        assert_eq!(b.gamma3, None);
        let slopes = l.slopes(&mask);
        assert_eq!(slopes.len(), corners.len());
        assert!(slopes.iter().all(|s| (s - s5).abs() < 1e-12));
    }

    /// The margins by hand on the paper's field `F = 20 e^{-r/10}`: at a corner `|grad F| = F/10`
    /// and `||hess F|| = max(F/100, F/(10 r))` (radial and tangential curvatures); `lip` is the
    /// largest change of `||hess F||` per metre between corners next to each other,
    /// `gamma3 = max ||hess F|| + lip d`, `gamma1 = min |grad F| - gamma3 d`,
    /// `gamma2 = max |grad F| + gamma3 d`, `d` half a cell's diagonal.
    #[test]
    fn margins_by_hand_on_the_circular_field() {
        let f = FieldModel::Analytic(AnalyticField::new(AnalyticKind::RadialExp(
            RadialExp::paper(),
        )));
        let n = 7;
        // 1 m square cells and 0.5 m x 1 m cells across the isoline in x, then 1 m x 0.5 m cells
        // across it in y (where ||hess F|| changes fastest per metre along y, so the y spacing
        // sets `lip`).
        for (region, seed, y_sets_lip) in [
            ([2.0, 8.0, -3.0, 3.0], Vec2::new(6.93, 0.0), false),
            ([4.0, 7.0, -3.0, 3.0], Vec2::new(6.93, 0.0), false),
            ([-3.0, 3.0, 4.0, 7.0], Vec2::new(0.0, 6.93), true),
        ] {
            margins_by_hand_on(&f, n, region, seed, y_sets_lip);
        }
    }

    fn margins_by_hand_on(
        f: &FieldModel,
        n: usize,
        region: [f64; 4],
        seed: Vec2,
        y_sets_lip: bool,
    ) {
        let l = Lattice::new(f, region, n);
        let mask = l.component(l.cell_of(seed).unwrap(), 8.0, 12.0);
        let b = l.bounds(&mask, true).unwrap();
        let (hx, hy) = (
            (region[1] - region[0]) / (n - 1) as f64,
            (region[3] - region[2]) / (n - 1) as f64,
        );
        let value = |i: usize, j: usize| {
            let (x, y) = (region[0] + hx * i as f64, region[2] + hy * j as f64);
            let r = x.hypot(y);
            (20.0 * (-r / 10.0).exp(), r)
        };
        let corner = |i: usize, j: usize| {
            let cell = |a: usize, b: usize| a < n - 1 && b < n - 1 && mask[b * (n - 1) + a];
            cell(i, j)
                || (i > 0 && cell(i - 1, j))
                || (j > 0 && cell(i, j - 1))
                || (i > 0 && j > 0 && cell(i - 1, j - 1))
        };
        let hess = |i: usize, j: usize| {
            let (v, r) = value(i, j);
            (v / 100.0).max(v / (10.0 * r))
        };
        let (mut g1, mut g2, mut g3, mut lip_x, mut lip_y, mut count) =
            (f64::INFINITY, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0);
        for j in 0..n {
            for i in 0..n {
                if !corner(i, j) {
                    continue;
                }
                count += 1;
                let g = value(i, j).0 / 10.0;
                (g1, g2, g3) = (g1.min(g), g2.max(g), g3.max(hess(i, j)));
                if i + 1 < n && corner(i + 1, j) {
                    lip_x = lip_x.max((hess(i + 1, j) - hess(i, j)).abs() / hx);
                }
                if j + 1 < n && corner(i, j + 1) {
                    lip_y = lip_y.max((hess(i, j + 1) - hess(i, j)).abs() / hy);
                }
            }
        }
        assert_eq!(lip_y > lip_x, y_sets_lip, "lip x {lip_x}, y {lip_y}");
        let lip = lip_x.max(lip_y);
        let d = 0.5 * hx.hypot(hy);
        let gamma3 = g3 + lip * d;
        assert_eq!(b.points, count);
        assert!(count > 8 && lip > 0.0, "{count} corners, lip {lip}");
        assert!(
            g1 - gamma3 * d > 0.1,
            "the margin leaves gamma1 positive here"
        );
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        assert!(close(b.gamma3.unwrap(), gamma3), "{b:?} vs {gamma3}");
        assert!(close(b.gamma1, (g1 - gamma3 * d).max(0.0)), "{b:?}");
        assert!(close(b.gamma2, g2 + gamma3 * d), "{b:?}");
        // The slopes are |grad F| = F/10 at exactly those corners (as a sorted list).
        let mut by_hand: Vec<f64> = (0..n * n)
            .filter(|&k| corner(k % n, k / n))
            .map(|k| value(k % n, k / n).0 / 10.0)
            .collect();
        let mut got = l.slopes(&mask);
        by_hand.sort_by(f64::total_cmp);
        got.sort_by(f64::total_cmp);
        assert_eq!(got.len(), by_hand.len());
        for (a, b) in got.iter().zip(&by_hand) {
            assert!(close(*a, *b), "{got:?} vs {by_hand:?}");
        }
    }

    /// A cell's range is the min and max of its four corners: on `F = x + 2y` over [0, 4]^2
    /// (1 m cells) cell (i, j) spans `[i + 2j, i + 2j + 3]`, the top from its far corner and the
    /// bottom from its near one; on `F = -x - 2y` the other way round.
    #[test]
    fn a_cells_range_is_its_corners_min_and_max() {
        for sign in [1.0, -1.0] {
            let f =
                FieldModel::Analytic(AnalyticField::new(AnalyticKind::LinearRamp(LinearRamp {
                    offset: 0.0,
                    gradient_per_m: Vec2::new(sign, 2.0 * sign),
                })));
            let l = Lattice::new(&f, [0.0, 4.0, 0.0, 4.0], 5);
            for j in 0..4 {
                for i in 0..4 {
                    let near = (i + 2 * j) as f64;
                    let want = if sign > 0.0 {
                        (near, near + 3.0)
                    } else {
                        (-near - 3.0, -near)
                    };
                    assert_eq!(l.cell_range(i, j), Some(want), "cell ({i}, {j})");
                }
            }
        }
    }

    /// The nearest band cell against a brute-force search over cell centres
    /// `((i + 1/2) h, (j + 1/2) h)` worked out here, probed on a quarter-metre grid that puts many
    /// points exactly halfway between two centres: ties go to the first cell in row-major order.
    #[test]
    fn nearest_band_cell_by_centre_ties_to_the_first() {
        let f = ramp();
        let l = Lattice::new(&f, [0.0, 4.0, 0.0, 4.0], 5);
        let (lo, hi) = (6.0, 6.5);
        let band: Vec<(usize, usize)> = (0..4)
            .flat_map(|j| (0..4).map(move |i| (i, j)))
            .filter(|&(i, j)| (1..=4).contains(&(2 * i as i64 - j as i64)))
            .collect();
        let mut ties = 0;
        for u in -4..=20 {
            for v in -4..=20 {
                let p = Vec2::new(u as f64 * 0.25, v as f64 * 0.25);
                let d = |&(i, j): &(usize, usize)| {
                    (i as f64 + 0.5 - p.x).powi(2) + (j as f64 + 0.5 - p.y).powi(2)
                };
                let best = band.iter().map(d).fold(f64::INFINITY, f64::min);
                let first = *band.iter().find(|c| d(c) == best).unwrap();
                ties += usize::from(band.iter().filter(|c| d(c) == best).count() > 1);
                assert_eq!(l.nearest_band_cell(p, lo, hi), Some(first), "probe {p:?}");
            }
        }
        assert!(ties > 20, "only {ties} probes were ties");
    }

    /// On a curved field and a coarse lattice, the bounds with their margins hold between the
    /// lattice points: over a dense sampling of the component's cells, min |grad F| >= gamma1,
    /// max |grad F| <= gamma2 and max ||hess F|| <= gamma3 (the paper's field, 1 m cells, a
    /// band away from the source, where `||hess F||` is smooth enough for its finite-difference
    /// Lipschitz estimate).
    #[test]
    fn margins_cover_what_lies_between_lattice_points() {
        let f = FieldModel::Analytic(AnalyticField::new(AnalyticKind::RadialExp(
            RadialExp::paper(),
        )));
        let l = Lattice::new(&f, [-15.5, 16.5, -15.5, 16.5], 33);
        let (lo, hi) = (9.0, 11.0);
        let seed = l.cell_of(Vec2::new(6.93, 0.0)).unwrap();
        let mask = l.component(seed, lo, hi);
        let b = l.bounds(&mask, true).unwrap();
        let g3 = b.gamma3.unwrap();
        assert!(g3 > 0.0 && b.gamma1 < b.gamma2);
        let (mut gmin, mut gmax, mut hmax) = (f64::INFINITY, 0.0f64, 0.0f64);
        for (k, _) in mask.iter().enumerate().filter(|c| *c.1) {
            let (i, j) = (k % 32, k / 32);
            let (a, c) = (l.point(i, j), l.point(i + 1, j + 1));
            for u in 0..=20 {
                for v in 0..=20 {
                    let p = Vec2::new(
                        a.x + (c.x - a.x) * u as f64 / 20.0,
                        a.y + (c.y - a.y) * v as f64 / 20.0,
                    );
                    if let Some(g) = f.gradient(0.0, p) {
                        gmin = gmin.min(g.norm());
                        gmax = gmax.max(g.norm());
                    }
                    if let Some(h) = f.hessian(0.0, p) {
                        hmax = hmax.max(sym_spectral_norm(&h));
                    }
                }
            }
        }
        assert!(b.gamma1 <= gmin, "gamma1 {} > min {gmin}", b.gamma1);
        assert!(b.gamma2 >= gmax, "gamma2 {} < max {gmax}", b.gamma2);
        assert!(g3 >= hmax, "gamma3 {g3} < max {hmax}");
    }
}
