//! The true isoline, for the distance metric: how far the vehicle is from `F = s_d`.
//!
//! * Gridded fields: marching squares over the interpolant sampled on a refined lattice
//!   (`refine` points per grid cell), giving line segments; the distance is to the nearest
//!   segment, found through a bucket index. Written by hand rather than with the `contour` crate
//!   because only unstitched segments are needed and no-data cells must simply produce none
//!   (`contour`, a d3 port, has no no-data handling).
//! * Analytic fields: root finding from the query point along the gradient (Newton's method on
//!   `F(p) - s_d` in the gradient direction), which converges to the foot of the gradient line on
//!   the isoline: the distance to the isoline to first order, exact for circles and lines.

use crate::grid::GridField;
use isotrack_core::{FieldDerivatives, ScalarField, Vec2};

/// Line segments of the level set with a bucket index for nearest-segment queries.
#[derive(Clone, Debug)]
pub struct IsolineSegments {
    segments: Vec<(Vec2, Vec2)>,
    origin: Vec2,
    cell: f64,
    nbx: usize,
    nby: usize,
    buckets: Vec<Vec<u32>>,
}

/// Crossing of `level` on the edge from `(pa, va)` to `(pb, vb)`, if the edge straddles it.
fn crossing(pa: Vec2, va: f64, pb: Vec2, vb: f64, level: f64) -> Option<Vec2> {
    let (a, b) = (va - level, vb - level);
    if (a < 0.0) == (b < 0.0) {
        return None;
    }
    let t = a / (a - b);
    Some(pa + (pb - pa) * t)
}

impl IsolineSegments {
    /// Marching squares on values `f(x0 + i*h, y0 + j*h)` over `nx x ny` samples; `None`
    /// samples (no value) produce no segments in their cells.
    pub fn from_samples(
        origin: Vec2,
        h: f64,
        nx: usize,
        ny: usize,
        level: f64,
        f: impl Fn(Vec2) -> Option<f64>,
    ) -> Self {
        let mut vals = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                vals.push(f(origin + Vec2::new(i as f64 * h, j as f64 * h)).unwrap_or(f64::NAN));
            }
        }
        let p = |i: usize, j: usize| origin + Vec2::new(i as f64 * h, j as f64 * h);
        let mut segments = Vec::new();
        for j in 0..ny.saturating_sub(1) {
            for i in 0..nx.saturating_sub(1) {
                let c = [
                    (p(i, j), vals[j * nx + i]),
                    (p(i + 1, j), vals[j * nx + i + 1]),
                    (p(i + 1, j + 1), vals[(j + 1) * nx + i + 1]),
                    (p(i, j + 1), vals[(j + 1) * nx + i]),
                ];
                if c.iter().any(|(_, v)| v.is_nan()) {
                    continue;
                }
                let mut pts = [Vec2::default(); 4];
                let mut n = 0;
                for e in 0..4 {
                    let (a, b) = (c[e], c[(e + 1) % 4]);
                    if let Some(q) = crossing(a.0, a.1, b.0, b.1, level) {
                        pts[n] = q;
                        n += 1;
                    }
                }
                match n {
                    2 => segments.push((pts[0], pts[1])),
                    4 => {
                        // Saddle (c0, c2 on one side, c1, c3 on the other): the cell-centre
                        // value decides which diagonal is connected. Centre on c0's side: c0 and
                        // c2 join through the middle, so the segments cut off the corners c1
                        // (edges 0 and 1) and c3 (edges 2 and 3); otherwise they cut off c0
                        // (edges 3 and 0) and c2 (edges 1 and 2).
                        let centre = 0.25 * c.iter().map(|(_, v)| v).sum::<f64>();
                        let first_above = c[0].1 >= level;
                        if (centre >= level) == first_above {
                            segments.push((pts[0], pts[1]));
                            segments.push((pts[2], pts[3]));
                        } else {
                            segments.push((pts[0], pts[3]));
                            segments.push((pts[1], pts[2]));
                        }
                    }
                    _ => {}
                }
            }
        }
        Self::index(
            segments,
            origin,
            h * 4.0,
            nx.div_ceil(4).max(1),
            ny.div_ceil(4).max(1),
        )
    }

    /// The level set of a gridded field, refined `refine` times per cell (>= 1).
    pub fn for_grid(field: &GridField, level: f64, refine: usize) -> Self {
        let g = field.grid();
        let refine = refine.max(1);
        let [dx, dy] = g.spacing_m();
        let h = dx.min(dy) / refine as f64;
        let [x0, x1, y0, y1] = g.extent_m();
        let nx = ((x1 - x0) / h).floor() as usize + 1;
        let ny = ((y1 - y0) / h).floor() as usize + 1;
        Self::from_samples(Vec2::new(x0, y0), h, nx, ny, level, |p| field.value(0.0, p))
    }

    fn index(segments: Vec<(Vec2, Vec2)>, origin: Vec2, cell: f64, nbx: usize, nby: usize) -> Self {
        let mut buckets = vec![Vec::new(); nbx * nby];
        for (k, (a, b)) in segments.iter().enumerate() {
            let m = (*a + *b) * 0.5;
            let bx = (((m.x - origin.x) / cell).floor().max(0.0) as usize).min(nbx - 1);
            let by = (((m.y - origin.y) / cell).floor().max(0.0) as usize).min(nby - 1);
            buckets[by * nbx + bx].push(k as u32);
        }
        Self {
            segments,
            origin,
            cell,
            nbx,
            nby,
            buckets,
        }
    }

    /// The segments.
    pub fn segments(&self) -> &[(Vec2, Vec2)] {
        &self.segments
    }

    /// Distance from `p` to the nearest segment, `None` if there are none.
    pub fn distance(&self, p: Vec2) -> Option<f64> {
        if self.segments.is_empty() {
            return None;
        }
        let seg_dist = |(a, b): (Vec2, Vec2)| {
            let ab = b - a;
            let l2 = ab.dot(ab);
            let t = if l2 > 0.0 {
                ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (a + ab * t - p).norm()
        };
        let bx = ((p.x - self.origin.x) / self.cell).floor();
        let by = ((p.y - self.origin.y) / self.cell).floor();
        let mut best = f64::INFINITY;
        let max_ring = self.nbx.max(self.nby) as i64 + 1;
        for ring in 0..=max_ring {
            // Every segment in ring r+1 or beyond is at least (r - 1) cells (minus half a segment)
            // away; stop once the best found beats that.
            if best.is_finite() && best < (ring as f64 - 1.5).max(0.0) * self.cell {
                break;
            }
            for j in -ring..=ring {
                for i in -ring..=ring {
                    if i.abs() != ring && j.abs() != ring {
                        continue;
                    }
                    let (x, y) = (bx as i64 + i, by as i64 + j);
                    if x < 0 || y < 0 || x >= self.nbx as i64 || y >= self.nby as i64 {
                        continue;
                    }
                    for &k in &self.buckets[y as usize * self.nbx + x as usize] {
                        best = best.min(seg_dist(self.segments[k as usize]));
                    }
                }
            }
        }
        best.is_finite().then_some(best)
    }
}

/// Distance from `p` to the level set of an analytic field by Newton steps along the gradient:
/// `p_{n+1} = p_n - (F(p_n) - level) grad F / |grad F|^2`. `None` if it does not converge (flat
/// region, no value).
pub fn newton_distance<F: FieldDerivatives + ?Sized>(
    field: &F,
    t_s: f64,
    p: Vec2,
    level: f64,
) -> Option<f64> {
    let mut q = p;
    for _ in 0..60 {
        let v = field.value(t_s, q)?;
        let g = field.gradient(t_s, q)?;
        let g2 = g.dot(g);
        if g2.is_nan() || g2 <= 0.0 {
            return None;
        }
        let step = g * ((v - level) / g2);
        q = q - step;
        if step.norm() < 1e-12 * (1.0 + q.norm()) {
            let d = (q - p).norm();
            return d.is_finite().then_some(d);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analytic::{AnalyticField, AnalyticKind, RadialExp};
    use crate::grid::{Grid2, Interpolation};

    #[test]
    fn newton_distance_is_exact_on_circles() {
        let f = AnalyticField::new(AnalyticKind::RadialExp(RadialExp::paper()));
        let r = 10.0 * std::f64::consts::LN_2;
        for (d, a) in [(3.0, 0.2), (6.5, 1.0), (9.0, 2.0), (15.0, -1.0)] {
            let dist = newton_distance(&f, 0.0, Vec2::from_angle(a) * d, 10.0).unwrap();
            assert!((dist - (d - r).abs()).abs() < 1e-9, "{d}: {dist}");
        }
    }

    #[test]
    fn grid_segments_give_circle_distance() {
        let field = |p: Vec2| 20.0 * (-0.1 * p.norm()).exp();
        let g = Grid2::from_fn(81, 81, Vec2::new(-20.0, -20.0), [0.5, 0.5], field).unwrap();
        let gf = GridField::new(g, Interpolation::Bicubic);
        let iso = IsolineSegments::for_grid(&gf, 10.0, 4);
        let r = 10.0 * std::f64::consts::LN_2;
        for k in 0..50 {
            let a = k as f64 * 0.125;
            let d = 2.0 + (k % 13) as f64;
            let got = iso.distance(Vec2::from_angle(a) * d).unwrap();
            assert!((got - (d - r).abs()).abs() < 2e-3, "{d}: {got}");
        }
    }

    /// One unit cell with corner values `v` (c0 = (0,0), c1 = (1,0), c2 = (1,1), c3 = (0,1)).
    fn saddle_cell(v: [f64; 4], level: f64) -> IsolineSegments {
        IsolineSegments::from_samples(Vec2::default(), 1.0, 2, 2, level, move |p| {
            Some(match (p.x as i32, p.y as i32) {
                (0, 0) => v[0],
                (1, 0) => v[1],
                (1, 1) => v[2],
                _ => v[3],
            })
        })
    }

    /// The corners a cell's segments cut off, sorted.
    fn cut_corners(iso: IsolineSegments) -> Vec<(f64, f64)> {
        let mut c: Vec<(f64, f64)> = iso
            .segments()
            .iter()
            .map(|&s| cut_corner(s))
            .map(|c| (c.x, c.y))
            .collect();
        c.sort_by(|a, b| a.partial_cmp(b).unwrap());
        c
    }

    /// The corner a segment cuts off: the one both of its end points' edges touch.
    fn cut_corner(seg: (Vec2, Vec2)) -> Vec2 {
        let corners = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ];
        let on_edge_of = |p: Vec2, c: Vec2| (p.x - c.x).abs() < 1e-12 || (p.y - c.y).abs() < 1e-12;
        *corners
            .iter()
            .find(|&&c| on_edge_of(seg.0, c) && on_edge_of(seg.1, c))
            .expect("a saddle segment joins two edges sharing a corner")
    }

    #[test]
    fn saddle_cells_join_by_the_centre_value() {
        // One cell, corners c0 = (0,0), c1 = (1,0), c2 = (1,1), c3 = (0,1); c0 and c2 high,
        // c1 and c3 low: a saddle for level 0.
        // Centre (2 - 1 + 2 - 1)/4 = 0.5 >= 0: on c0's side, c0 and c2 connect, the segments
        // cut off c1 = (1, 0) and c3 = (0, 1).
        assert_eq!(
            cut_corners(saddle_cell([2.0, -1.0, 2.0, -1.0], 0.0)),
            vec![(0.0, 1.0), (1.0, 0.0)]
        );
        // Centre (1 - 2 + 1 - 2)/4 = -0.5 < 0: on c1's side, the segments cut off c0 and c2.
        assert_eq!(
            cut_corners(saddle_cell([1.0, -2.0, 1.0, -2.0], 0.0)),
            vec![(0.0, 0.0), (1.0, 1.0)]
        );
    }

    #[test]
    fn no_segments_in_nodata() {
        let g = Grid2::new(
            3,
            3,
            Vec2::default(),
            [1.0, 1.0],
            vec![0.0, 1.0, f64::NAN, 0.0, 1.0, 2.0, 0.0, 1.0, 2.0],
        )
        .unwrap();
        let iso = IsolineSegments::from_samples(Vec2::default(), 1.0, 3, 3, 1.5, |p| {
            GridField::new(g.clone(), Interpolation::Bilinear).value(0.0, p)
        });
        // Only the top-right cell (all valid) crosses 1.5.
        assert_eq!(iso.segments().len(), 1);
        assert!(
            IsolineSegments::from_samples(Vec2::default(), 1.0, 3, 3, 99.0, |_| Some(0.0))
                .distance(Vec2::default())
                .is_none()
        );
    }

    /// A ramp `F = x` sampled on a 41 x 21 lattice of 0.5 m from (-3, 1): the level-4.3 set is
    /// the line `x = 4.3`, so every distance is `|x - 4.3|`, near and far (the ring search),
    /// inside and outside the sampled box.
    #[test]
    fn straight_isoline_distances_by_hand() {
        let origin = Vec2::new(-3.0, 1.0);
        let iso = IsolineSegments::from_samples(origin, 0.5, 41, 21, 4.3, |p| Some(p.x));
        // One segment per row of cells, each on the line, spanning its cell's height.
        assert_eq!(iso.segments().len(), 20);
        for &(a, b) in iso.segments() {
            assert!((a.x - 4.3).abs() < 1e-12 && (b.x - 4.3).abs() < 1e-12);
            assert!(((a.y - b.y).abs() - 0.5).abs() < 1e-12);
            assert!(a.y >= 1.0 - 1e-12 && a.y <= 11.0 + 1e-12);
        }
        for (x, y) in [
            (4.3, 5.0),
            (4.0, 2.2),
            (-3.0, 1.0),
            (17.0, 10.9),
            (-2.5, 8.0),
            (10.0, 6.0),
            (5.1, 1.0),
        ] {
            let d = iso.distance(Vec2::new(x, y)).unwrap();
            assert!((d - (x - 4.3f64).abs()).abs() < 1e-12, "({x}, {y}): {d}");
        }
        // Beyond the box's top: the distance to the line's end point.
        let d = iso.distance(Vec2::new(4.3 + 3.0, 15.0)).unwrap();
        assert!((d - 5.0).abs() < 1e-12, "{d}");
        // The same line from a grid through `for_grid` (its extent and refinement): a ramp of
        // 2 per metre in x over [10, 18] x [-4, 4], level 30 at x = 15.
        let g = Grid2::from_fn(5, 3, Vec2::new(10.0, -4.0), [2.0, 4.0], |p| 2.0 * p.x).unwrap();
        let gf = GridField::new(g, Interpolation::Bilinear);
        let iso = IsolineSegments::for_grid(&gf, 30.0, 4);
        // h = min(2, 4)/4 = 0.5: 17 x 17 samples, 16 rows of cells crossing x = 15.
        assert_eq!(iso.segments().len(), 16);
        for (x, y) in [(15.0, 0.0), (11.0, -3.9), (18.0, 4.0), (14.2, 1.3)] {
            let d = iso.distance(Vec2::new(x, y)).unwrap();
            assert!((d - (x - 15.0f64).abs()).abs() < 1e-12, "({x}, {y}): {d}");
        }
    }

    /// A node exactly at the level counts as above it (`F >= level`), so an isoline through a
    /// row of nodes is found once, not twice or never.
    #[test]
    fn a_level_through_nodes_is_crossed_once() {
        let iso = IsolineSegments::from_samples(Vec2::default(), 1.0, 3, 2, 1.0, |p| Some(p.x));
        // Level 1 passes through the middle column of nodes: the left cell's right edge.
        assert_eq!(iso.segments().len(), 1, "{:?}", iso.segments());
        let (a, b) = iso.segments()[0];
        assert_eq!((a.x, b.x), (1.0, 1.0));
    }

    /// Newton on a steeper circular field (`|grad F| = 10` on the isoline, where a step of
    /// `(F - level) * grad F` instead of `/ |grad F|^2` overshoots), and a flat field (no
    /// gradient: no answer).
    #[test]
    fn newton_distance_on_a_steep_field_and_a_flat_one() {
        let f = AnalyticField::new(AnalyticKind::RadialExp(RadialExp {
            i0: 200.0,
            decay_per_m: 0.1,
            center_m: Vec2::new(0.0, 0.0),
        }));
        let r = 10.0 * std::f64::consts::LN_2;
        for (d, a) in [(3.0, 0.2), (8.0, 1.0), (12.0, -2.0)] {
            let dist = newton_distance(&f, 0.0, Vec2::from_angle(a) * d, 100.0).unwrap();
            assert!((dist - (d - r).abs()).abs() < 1e-9, "{d}: {dist}");
        }
        let flat = AnalyticField::new(AnalyticKind::LinearRamp(crate::analytic::LinearRamp {
            offset: 3.0,
            gradient_per_m: Vec2::new(0.0, 0.0),
        }));
        assert_eq!(newton_distance(&flat, 0.0, Vec2::new(1.0, 1.0), 5.0), None);
    }

    /// Saddles decided by the centre's value where only the mean (not a sum or a quotient)
    /// gives the right side: sum -0.1 (mean -0.025 below level 0) and, at level 1, sum 4.2
    /// (mean 1.05 above).
    #[test]
    fn saddle_centre_is_the_mean_of_the_corners() {
        // Mean -0.025 < 0 = level: c1's side, the corners c0 and c2 are cut off.
        assert_eq!(
            cut_corners(saddle_cell([0.9, -1.0, 0.9, -0.9], 0.0)),
            vec![(0.0, 0.0), (1.0, 1.0)]
        );
        // Mean 1.05 >= 1: c0's side, c1 and c3 are cut off.
        assert_eq!(
            cut_corners(saddle_cell([1.6, 0.4, 1.8, 0.4], 1.0)),
            vec![(0.0, 1.0), (1.0, 0.0)]
        );
    }

    /// The bucket index answers what a search of every segment answers: a circle of radius 7
    /// sampled on a 0.25 m lattice, queried inside, outside and far away.
    #[test]
    fn indexed_distance_equals_brute_force() {
        let f = |p: Vec2| Some(p.norm());
        let iso = IsolineSegments::from_samples(Vec2::new(-10.0, -9.0), 0.25, 81, 73, 7.0, f);
        let brute = |p: Vec2| {
            iso.segments()
                .iter()
                .map(|&(a, b)| {
                    let ab = b - a;
                    let t = ((p - a).dot(ab) / ab.dot(ab)).clamp(0.0, 1.0);
                    (a + ab * t - p).norm()
                })
                .fold(f64::INFINITY, f64::min)
        };
        for k in 0..60 {
            let a = k as f64 * 0.37;
            let r = 0.5 + 0.3 * k as f64;
            let p = Vec2::from_angle(a) * r + Vec2::new(0.3, -0.2);
            let d = iso.distance(p).unwrap();
            assert_eq!(d, brute(p), "{p:?}");
            assert!((d - (p.norm() - 7.0).abs()).abs() < 0.01, "{p:?}: {d}");
        }
    }

    /// `for_grid` samples the grid to its last column: a level 0.1 m inside the east edge
    /// (x = 17.8 of [10, 18]) is found.
    #[test]
    fn for_grid_reaches_the_last_column() {
        let g = Grid2::from_fn(5, 3, Vec2::new(10.0, -4.0), [2.0, 4.0], |p| 2.0 * p.x).unwrap();
        let gf = GridField::new(g, Interpolation::Bilinear);
        let iso = IsolineSegments::for_grid(&gf, 35.6, 4);
        assert_eq!(iso.segments().len(), 16);
        let d = iso.distance(Vec2::new(17.0, 0.0)).unwrap();
        assert!((d - 0.8).abs() < 1e-12, "{d}");
    }
}
