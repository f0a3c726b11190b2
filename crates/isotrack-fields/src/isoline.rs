//! The true isoline, for the distance metric: how far the vehicle is from `F = s_d`.
//!
//! * Gridded fields: marching squares over the interpolant sampled on a refined lattice
//!   (`refine` points per grid cell), giving line segments; the distance is to the nearest
//!   segment, found through an R*-tree of the segments (`rstar`), so a query costs
//!   `O(log n)` however far the point is from the isoline. The marching squares are written
//!   by hand rather than with the `contour` crate
//!   because only unstitched segments are needed and no-data cells must simply produce none
//!   (`contour`, a d3 port, has no no-data handling).
//! * Analytic fields: root finding from the query point along the gradient (Newton's method on
//!   `F(p) - s_d` in the gradient direction), which converges to the foot of the gradient line on
//!   the isoline: the distance to the isoline to first order, exact for circles and lines.

use crate::grid::GridField;
use isotrack_core::{FieldDerivatives, ScalarField, Vec2};
use rstar::{PointDistance, RTree, RTreeObject, AABB};
use std::sync::OnceLock;

/// Line segments of the level set with a spatial index (an R*-tree, built on the first
/// distance query) for nearest-segment queries.
#[derive(Clone, Debug)]
pub struct IsolineSegments {
    segments: Vec<(Vec2, Vec2)>,
    /// For segments from marching squares: the lattice edges each end lies on (an edge's
    /// index, [`lattice_edge`]), so that [`closed_loops`](Self::closed_loops) joins ends by
    /// the edge they share, not by distance. Empty for segments given as they are.
    edges: Vec<(u64, u64)>,
    /// The tree and the largest coordinate magnitude of the end points (m), built on first use.
    tree: OnceLock<(RTree<Indexed>, f64)>,
}

/// A segment in the tree: its end points.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Indexed {
    a: Vec2,
    b: Vec2,
}

/// The point of segment `a`-`b` nearest `p`, minus `p`: the foot of the perpendicular,
/// clamped to the segment (its start for a segment of zero length).
fn to_segment(a: Vec2, b: Vec2, p: Vec2) -> Vec2 {
    let ab = b - a;
    let l2 = ab.dot(ab);
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    a + ab * t - p
}

impl RTreeObject for Indexed {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners([self.a.x, self.a.y], [self.b.x, self.b.y])
    }
}

impl PointDistance for Indexed {
    /// `|d|^2` as `d.x^2 + d.y^2`, the radicand of [`Vec2::norm`]: the square root of the
    /// smallest of these is the smallest distance, bit for bit.
    fn distance_2(&self, p: &[f64; 2]) -> f64 {
        let d = to_segment(self.a, self.b, Vec2::new(p[0], p[1]));
        d.x * d.x + d.y * d.y
    }
}

/// The index of a lattice edge of an `nx`-wide lattice: the edge from sample `(i, j)` to
/// `(i + 1, j)` (`vertical` false) or to `(i, j + 1)` (true). Two cells sharing an edge name it
/// alike.
fn lattice_edge(i: usize, j: usize, nx: usize, vertical: bool) -> u64 {
    2 * (j as u64 * nx as u64 + i as u64) + u64::from(vertical)
}

/// Crossing of `level` on the edge from `(pa, va)` to `(pb, vb)`, if the edge straddles it.
///
/// The tie rule: a sample equal to the level counts as above it (`v >= level`, as if it
/// were `level + 0`: a symbolic perturbation), so every edge is straddled or not, alike from
/// both cells that share it, and a level equal to samples (a DEM's integer elevations, their
/// interpolated quarter steps) gives the isoline of the level raised by an infinitesimal: its
/// crossings at such a sample are the sample itself (`t = 0`), and segments of zero length
/// join the crossings on either side of it. [`IsolineSegments::closed_loops`] joins them by
/// their lattice edges, so those loops close.
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
    /// samples (no value) produce no segments in their cells. As
    /// [`from_samples_xy`](Self::from_samples_xy) with `h` along both axes.
    pub fn from_samples(
        origin: Vec2,
        h: f64,
        nx: usize,
        ny: usize,
        level: f64,
        f: impl Fn(Vec2) -> Option<f64>,
    ) -> Self {
        Self::from_samples_xy(origin, [h, h], nx, ny, level, f)
    }

    /// Marching squares on values `f(x0 + i*hx, y0 + j*hy)` over `nx x ny` samples; `None`
    /// samples (no value) produce no segments in their cells. The lattice is walked one row of
    /// cells at a time, holding two rows of samples (`16 nx` bytes): the memory is that of the
    /// segments found (32 bytes each), never of the lattice, however many samples it has.
    pub fn from_samples_xy(
        origin: Vec2,
        [hx, hy]: [f64; 2],
        nx: usize,
        ny: usize,
        level: f64,
        f: impl Fn(Vec2) -> Option<f64>,
    ) -> Self {
        let p = |i: usize, j: usize| origin + Vec2::new(i as f64 * hx, j as f64 * hy);
        let row =
            |j: usize| -> Vec<f64> { (0..nx).map(|i| f(p(i, j)).unwrap_or(f64::NAN)).collect() };
        let mut segments = Vec::new();
        let mut edges = Vec::new();
        let mut below = if ny > 0 { row(0) } else { Vec::new() };
        for j in 0..ny.saturating_sub(1) {
            let above = row(j + 1);
            for i in 0..nx.saturating_sub(1) {
                let c = [
                    (p(i, j), below[i]),
                    (p(i + 1, j), below[i + 1]),
                    (p(i + 1, j + 1), above[i + 1]),
                    (p(i, j + 1), above[i]),
                ];
                if c.iter().any(|(_, v)| v.is_nan()) {
                    continue;
                }
                let mut pts = [Vec2::default(); 4];
                let mut ids = [0u64; 4];
                // The cell's edges 0..4: bottom, right, top, left.
                let cell_edges = [
                    lattice_edge(i, j, nx, false),
                    lattice_edge(i + 1, j, nx, true),
                    lattice_edge(i, j + 1, nx, false),
                    lattice_edge(i, j, nx, true),
                ];
                let mut n = 0;
                for e in 0..4 {
                    let (a, b) = (c[e], c[(e + 1) % 4]);
                    if let Some(q) = crossing(a.0, a.1, b.0, b.1, level) {
                        pts[n] = q;
                        ids[n] = cell_edges[e];
                        n += 1;
                    }
                }
                match n {
                    2 => {
                        segments.push((pts[0], pts[1]));
                        edges.push((ids[0], ids[1]));
                    }
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
                            edges.extend([(ids[0], ids[1]), (ids[2], ids[3])]);
                        } else {
                            segments.push((pts[0], pts[3]));
                            segments.push((pts[1], pts[2]));
                            edges.extend([(ids[0], ids[3]), (ids[1], ids[2])]);
                        }
                    }
                    _ => {}
                }
            }
            below = above;
        }
        Self {
            segments,
            edges,
            tree: OnceLock::new(),
        }
    }

    /// Segments as given (`(start, end)` pairs), indexed for [`Self::distance`].
    pub fn new(segments: Vec<(Vec2, Vec2)>) -> Self {
        Self {
            segments,
            edges: Vec::new(),
            tree: OnceLock::new(),
        }
    }

    /// The level set of a gridded field, refined `refine` times per cell (>= 1), on the
    /// lattice [`grid_lattice`] plans (at most [`MAX_ISOLINE_SAMPLES`] samples): the work is
    /// bounded by that count and the memory by the segments found (see
    /// [`from_samples_xy`](Self::from_samples_xy)), whatever the grid's shape or spacing.
    pub fn for_grid(field: &GridField, level: f64, refine: usize) -> Self {
        let g = field.grid();
        let [x0, x1, y0, y1] = g.extent_m();
        let lattice = grid_lattice(g.nx(), g.ny(), g.spacing_m(), [x0, x1, y0, y1], refine);
        Self::from_samples_xy(
            Vec2::new(x0, y0),
            lattice.step_m,
            lattice.nx,
            lattice.ny,
            level,
            |p| field.value(0.0, p),
        )
    }

    /// The segments.
    pub fn segments(&self) -> &[(Vec2, Vec2)] {
        &self.segments
    }

    /// The segments stitched into closed loops (each a list of vertices, the closing one not
    /// repeated, consecutive equal vertices merged, at least 3). Segments from marching
    /// squares are joined by the lattice edge their ends lie on (each crossed edge inside the
    /// lattice is an end of exactly two segments, one per cell, under [`crossing`]'s tie rule),
    /// so a loop closes even where the level equals samples and several ends meet at one
    /// point. Segments given as they are ([`new`](Self::new)): end points closer than
    /// `tolerance_m` are joined (marching squares computes a point on an edge shared by two
    /// cells from either side, equal to rounding), each matched through a hash of the
    /// `tolerance_m` lattice cell and its 8 neighbours. Chains that do not close (the isoline
    /// leaves the sampled domain or a no-data region) are left out. `O(n)` (`O(n log n)` by
    /// edges) for `n` segments. For the arc coordinate of a team's metrics
    /// (`isotrack_sim::team::arc::PolylineArc`).
    pub fn closed_loops(&self, tolerance_m: f64) -> Vec<Vec<Vec2>> {
        let Some(partners) = self.end_partners(tolerance_m) else {
            return Vec::new();
        };
        walk_loops(self.segments.len(), &|e| self.end(e), |e| partners[e])
    }

    /// The segments stitched into open chains: the isoline's pieces that leave the sampled
    /// domain (or a no-data region) at both ends, each a list of vertices from one free end
    /// (an end point joined to no other) to the other, consecutive equal vertices merged, at
    /// least 2. Ends are joined as by [`closed_loops`](Self::closed_loops) (by lattice edge for
    /// marching squares, else within `tolerance_m`); segments of closed loops are left out.
    /// Chains are listed in the order of their lowest free end. `O(n)` (`O(n log n)` by edges).
    /// For the arc coordinate along an open isoline (`isotrack_sim::team::arc::PolylineArc::open`).
    pub fn open_chains(&self, tolerance_m: f64) -> Vec<Vec<Vec2>> {
        let Some(partners) = self.end_partners(tolerance_m) else {
            return Vec::new();
        };
        walk_chains(self.segments.len(), &|e| self.end(e), &partners)
    }

    /// End point `e` of the segments: `2k` is segment `k`'s first, `2k + 1` its second.
    fn end(&self, e: usize) -> Vec2 {
        let (a, b) = self.segments[e / 2];
        if e.is_multiple_of(2) {
            a
        } else {
            b
        }
    }

    /// For each end point `e` (numbered as by [`end`](Self::end)), the end it is joined to, as
    /// [`closed_loops`](Self::closed_loops) and [`open_chains`](Self::open_chains) join them:
    /// by the lattice edge both lie on for marching squares, else the nearest other segment's
    /// end within `tolerance_m`. `None` when there is nothing to join: no segments, or segments
    /// given as they are with a tolerance not positive and finite.
    fn end_partners(&self, tolerance_m: f64) -> Option<Vec<Option<usize>>> {
        let n = self.segments.len();
        let by_edge = self.edges.len() == n;
        if n == 0 || !(by_edge || (tolerance_m > 0.0 && tolerance_m.is_finite())) {
            return None;
        }
        Some(if by_edge {
            self.partners_by_edge()
        } else {
            self.partners_within(tolerance_m)
        })
    }

    /// Partners by lattice edge: end `e` lies on edge `edges[e / 2]` (first or second), and the
    /// two ends on an edge are partners (an edge with one end, or more than two, joins none).
    fn partners_by_edge(&self) -> Vec<Option<usize>> {
        let n = self.segments.len();
        let edge_of = |e: usize| {
            if e.is_multiple_of(2) {
                self.edges[e / 2].0
            } else {
                self.edges[e / 2].1
            }
        };
        let mut order: Vec<(u64, usize)> = (0..2 * n).map(|e| (edge_of(e), e)).collect();
        order.sort_unstable();
        let mut partners: Vec<Option<usize>> = vec![None; 2 * n];
        for run in order.chunk_by(|a, b| a.0 == b.0) {
            if let [(_, a), (_, b)] = run {
                partners[*a] = Some(*b);
                partners[*b] = Some(*a);
            }
        }
        partners
    }

    /// Partners by distance: the end joined to end `e` is the nearest end of another segment
    /// within `tolerance_m` (ties to the lower end number), found through a hash of the
    /// `tolerance_m` lattice cell and its 8 neighbours; ends that are not finite join none.
    fn partners_within(&self, tolerance_m: f64) -> Vec<Option<usize>> {
        use std::collections::HashMap;
        let n = self.segments.len();
        let cell = |p: Vec2| {
            (
                (p.x / tolerance_m).floor() as i64,
                (p.y / tolerance_m).floor() as i64,
            )
        };
        let mut buckets: HashMap<(i64, i64), Vec<usize>> = HashMap::with_capacity(2 * n);
        for e in 0..2 * n {
            let p = self.end(e);
            if p.x.is_finite() && p.y.is_finite() {
                buckets.entry(cell(p)).or_default().push(e);
            }
        }
        let partner = |e: usize| -> Option<usize> {
            let p = self.end(e);
            if !(p.x.is_finite() && p.y.is_finite()) {
                return None;
            }
            let (cx, cy) = cell(p);
            let mut best: Option<(f64, usize)> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for &o in buckets.get(&(cx + dx, cy + dy)).into_iter().flatten() {
                        if o / 2 == e / 2 {
                            continue;
                        }
                        let d = (self.end(o) - p).norm();
                        if d <= tolerance_m && best.is_none_or(|(bd, bo)| (d, o) < (bd, bo)) {
                            best = Some((d, o));
                        }
                    }
                }
            }
            best.map(|(_, o)| o)
        };
        (0..2 * n).map(partner).collect()
    }

    /// Distance from `p` to the nearest segment, `None` if there are none (or `p` is not
    /// finite): `min_k |to_segment(a_k, b_k, p)|`, found in `O(log n)` through the tree.
    ///
    /// The tree orders candidates by their squared distance but prunes by bounding boxes,
    /// whose distances are rounded differently; so candidates are taken, nearest first, until
    /// one is farther than the first by more than any rounding (a relative 1e-9 plus 1e-9 of
    /// the coordinates' magnitude) and the least of them is the answer: the same value as a
    /// search of every segment, bit for bit.
    pub fn distance(&self, p: Vec2) -> Option<f64> {
        if self.segments.is_empty() || !(p.x.is_finite() && p.y.is_finite()) {
            return None;
        }
        let (tree, magnitude) = self.tree.get_or_init(|| {
            let magnitude = self
                .segments
                .iter()
                .map(|(a, b)| a.x.abs().max(a.y.abs()).max(b.x.abs()).max(b.y.abs()))
                .fold(0.0, f64::max);
            let items = self
                .segments
                .iter()
                .map(|&(a, b)| Indexed { a, b })
                .collect();
            (RTree::bulk_load(items), magnitude)
        });
        let mut near = tree.nearest_neighbor_iter_with_distance_2([p.x, p.y]);
        let (mut best, mut best2) = near.next()?;
        let first = best2.sqrt();
        let slack = 1e-9 * (first + p.x.abs().max(p.y.abs()) + magnitude);
        let cutoff = (first + slack) * (first + slack);
        for (s, d2) in near {
            if d2 > cutoff {
                break;
            }
            if d2 < best2 {
                (best, best2) = (s, d2);
            }
        }
        let d = to_segment(best.a, best.b, p).norm();
        d.is_finite().then_some(d)
    }
}

/// The closed loops of `n` segments whose end `e` (`2k`: segment `k`'s first, `2k + 1`: its
/// second) is at `end(e)` and is joined to end `partner(e)`: each walk starts at the lowest
/// segment not yet used and goes from its second end until back at its first; a chain that
/// breaks is left out. Consecutive equal vertices (a segment of zero length, at a sample equal
/// to the level) are merged.
fn walk_loops(
    n: usize,
    end: &dyn Fn(usize) -> Vec2,
    partner: impl Fn(usize) -> Option<usize>,
) -> Vec<Vec<Vec2>> {
    let mut used = vec![false; n];
    let mut loops = Vec::new();
    for start in 0..n {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut pts = vec![end(2 * start)];
        // Walk from the start segment's second end until back at its first.
        let mut e = 2 * start + 1;
        let closed = loop {
            let p = end(e);
            if pts.last() != Some(&p) {
                pts.push(p);
            }
            let Some(o) = partner(e) else {
                break false;
            };
            if o / 2 == start {
                break o == 2 * start;
            }
            if used[o / 2] {
                break false;
            }
            used[o / 2] = true;
            e = o ^ 1;
        };
        if closed {
            // The last point is the start's (joined, equal or within the tolerance; merged
            // already if equal to the one before): not repeated.
            pts.pop();
            if pts.len() >= 3 {
                loops.push(pts);
            }
        }
    }
    loops
}

/// The open chains of `n` segments whose end `e` is at `end(e)` and joined to `partners[e]`
/// (numbered as for [`walk_loops`]): each walk starts at a free end (joined to none) of a
/// segment not yet used, lowest first, and goes through its segment and on until an end joined
/// to none (or, where ends pair unevenly, a segment already used). Consecutive equal vertices
/// are merged; chains of fewer than 2 vertices are left out.
fn walk_chains(
    n: usize,
    end: &dyn Fn(usize) -> Vec2,
    partners: &[Option<usize>],
) -> Vec<Vec<Vec2>> {
    let mut used = vec![false; n];
    let mut chains = Vec::new();
    for free in 0..2 * n {
        if used[free / 2] || partners[free].is_some() {
            continue;
        }
        let mut pts = vec![end(free)];
        let mut e = free;
        loop {
            used[e / 2] = true;
            let p = end(e ^ 1);
            if pts.last() != Some(&p) {
                pts.push(p);
            }
            match partners[e ^ 1] {
                Some(o) if !used[o / 2] => e = o,
                _ => break,
            }
        }
        if pts.len() >= 2 {
            chains.push(pts);
        }
    }
    chains
}

/// The most samples [`IsolineSegments::for_grid`] takes of a grid: 2^22 (about 4.2 million
/// field evaluations; at most 2^23 segments, 256 MiB, on a field that crosses the level in
/// every cell, and a few thousand on a smooth one).
pub const MAX_ISOLINE_SAMPLES: usize = 1 << 22;

/// Where [`IsolineSegments::for_grid`] samples a grid: `nx x ny` points `step_m` apart from the
/// grid's south-west corner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Spacing of the samples along x and y, m.
    pub step_m: [f64; 2],
    /// Samples along x.
    pub nx: usize,
    /// Samples along y.
    pub ny: usize,
}

impl Lattice {
    /// Samples in all, `nx * ny`.
    pub fn samples(&self) -> usize {
        self.nx.saturating_mul(self.ny)
    }
}

/// The sampling lattice of a grid of `cols x rows` nodes `spacing_m = [dx, dy]` apart over
/// `extent_m = [x0, x1, y0, y1]`, refined `refine` times per cell, within
/// [`MAX_ISOLINE_SAMPLES`]:
///
/// 1. a square lattice of `h = min(dx, dy) / refine` over the extent, when it fits (every
///    grid of up to 2^22 / refine^2 nodes of equal spacing);
/// 2. otherwise each axis at its own spacing, `dx / r` and `dy / r` (`(cols - 1) r + 1` by
///    `(rows - 1) r + 1` samples), for the largest `r` of `refine, refine/2, ..., 1` that
///    fits (an anisotropic grid, `dx >> dy`, would take `dx/dy` times more samples square);
/// 3. otherwise every `s`-th node along each axis, `s` the smallest power of two that fits
///    (grids of more than 2^22 nodes: the isoline is that of the grid thinned `s` times,
///    documented in the README's limits).
///
/// With `refine` a power of two (the callers' 4) every `r` and `s` is one, and the samples
/// fall on the grid's own nodes and cell fractions exactly (`i (dx/r)` rounds as `(i/r) dx`),
/// so the last column and row are sampled.
pub fn grid_lattice(
    cols: usize,
    rows: usize,
    [dx, dy]: [f64; 2],
    [x0, x1, y0, y1]: [f64; 4],
    refine: usize,
) -> Lattice {
    let cap = MAX_ISOLINE_SAMPLES as f64;
    let refine = refine.max(1);
    let h = dx.min(dy) / refine as f64;
    let (nx, ny) = (((x1 - x0) / h).floor() + 1.0, ((y1 - y0) / h).floor() + 1.0);
    if nx.is_finite() && ny.is_finite() && nx >= 1.0 && ny >= 1.0 && nx * ny <= cap {
        return Lattice {
            step_m: [h, h],
            nx: nx as usize,
            ny: ny as usize,
        };
    }
    let (cx, cy) = (cols.saturating_sub(1), rows.saturating_sub(1));
    let mut r = refine;
    loop {
        let (nx, ny) = (cx * r + 1, cy * r + 1);
        if (nx as f64) * (ny as f64) <= cap {
            return Lattice {
                step_m: [dx / r as f64, dy / r as f64],
                nx,
                ny,
            };
        }
        if r == 1 {
            break;
        }
        r /= 2;
    }
    let mut s = 2usize;
    while ((cx / s + 1) as f64) * ((cy / s + 1) as f64) > cap {
        s *= 2;
    }
    Lattice {
        step_m: [dx * s as f64, dy * s as f64],
        nx: cx / s + 1,
        ny: cy / s + 1,
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

    /// The level-10 isoline of the paper's circular field (radius 10 ln 2), sampled every
    /// 0.25 m: one closed loop, its length within 0.5 % of 2 pi R, every vertex within 2 cm of
    /// the circle; a segment cut out leaves no closed loop.
    #[test]
    fn closed_loop_of_a_circle() {
        let r = 10.0 * std::f64::consts::LN_2;
        let f = |p: Vec2| Some(20.0 * (-0.1 * p.norm()).exp());
        let segs = IsolineSegments::from_samples(Vec2::new(-10.0, -10.0), 0.25, 81, 81, 10.0, f);
        let loops = segs.closed_loops(1e-6);
        assert_eq!(loops.len(), 1);
        let l = &loops[0];
        let len: f64 = (0..l.len())
            .map(|i| (l[(i + 1) % l.len()] - l[i]).norm())
            .sum();
        let circ = 2.0 * std::f64::consts::PI * r;
        assert!((len / circ - 1.0).abs() < 5e-3, "{len} vs {circ}");
        assert!(l.iter().all(|p| (p.norm() - r).abs() < 0.02));
        let mut cut = segs.segments().to_vec();
        cut.remove(3);
        assert!(IsolineSegments::new(cut.clone())
            .closed_loops(1e-6)
            .is_empty());
        // The loop cut open is one open chain of every other segment, from one side of the cut
        // to the other; the whole loop has none.
        assert!(segs.open_chains(1e-6).is_empty());
        let chains = IsolineSegments::new(cut.clone()).open_chains(1e-6);
        assert_eq!(chains.len(), 1);
        let c = &chains[0];
        let open_len: f64 = c.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        let removed = (segs.segments()[3].1 - segs.segments()[3].0).norm();
        assert!((open_len - (len - removed)).abs() < 1e-9, "{open_len}");
    }

    /// The level-1.1 isoline of the plane `F = x + y` over `[0, 4]^2` is the line
    /// `x + y = 1.1` from `(1.1, 0)` to `(0, 1.1)`: one open chain between those two boundary
    /// points, of length `1.1 sqrt 2` (marching squares interpolates a plane exactly), and no
    /// closed loop.
    #[test]
    fn open_chain_of_a_plane() {
        let segs = IsolineSegments::from_samples(Vec2::new(0.0, 0.0), 0.25, 17, 17, 1.1, |p| {
            Some(p.x + p.y)
        });
        assert!(segs.closed_loops(1e-9).is_empty());
        let chains = segs.open_chains(1e-9);
        assert_eq!(chains.len(), 1);
        let c = &chains[0];
        let ends = [c[0], c[c.len() - 1]];
        let want = [Vec2::new(1.1, 0.0), Vec2::new(0.0, 1.1)];
        assert!(
            want.iter()
                .all(|w| ends.iter().any(|e| (*e - *w).norm() < 1e-12)),
            "{ends:?}"
        );
        let len: f64 = c.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        assert!((len - 1.1 * 2f64.sqrt()).abs() < 1e-12, "{len}");
        assert!(c.iter().all(|p| (p.x + p.y - 1.1).abs() < 1e-12));
    }

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

    /// A level equal to samples: `|x| + |y|` on the integer lattice at level 3. The tie rule
    /// (a sample at the level counts as above) makes the isoline the diamond `|x| + |y| = 3`
    /// through the 12 lattice points on it, some crossings at a tied sample of zero length
    /// (at (1, 2) four segment ends meet: two edges, each crossed at the sample). Joined by
    /// lattice edges the loop closes: 12 vertices, each on the diamond, perimeter `4 * 3
    /// sqrt(2)`, area `2 * 3^2`. Stitched by distance (the segments as given, no edges) the
    /// ends at such a point are paired ambiguously and the loop is lost.
    #[test]
    fn a_level_equal_to_samples_closes_its_loop() {
        let iso = IsolineSegments::from_samples(Vec2::new(-5.0, -5.0), 1.0, 11, 11, 3.0, |p| {
            Some(p.x.abs() + p.y.abs())
        });
        let loops = iso.closed_loops(1e-9);
        assert_eq!(loops.len(), 1, "{loops:?}");
        let l = &loops[0];
        assert_eq!(l.len(), 12, "{l:?}");
        let n = l.len();
        let (mut per, mut area2) = (0.0, 0.0);
        for k in 0..n {
            let (a, b) = (l[k], l[(k + 1) % n]);
            assert!((a.x.abs() + a.y.abs() - 3.0).abs() < 1e-12, "{a:?}");
            per += (b - a).norm();
            area2 += a.x * b.y - b.x * a.y;
        }
        assert!(
            (per - 12.0 * std::f64::consts::SQRT_2).abs() < 1e-9,
            "{per}"
        );
        assert!((area2.abs() - 36.0).abs() < 1e-9, "{area2}");
        let by_distance = IsolineSegments::new(iso.segments().to_vec()).closed_loops(1e-9);
        assert!(by_distance.iter().all(|l| l.len() < 12), "{by_distance:?}");
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

    /// Distance to the nearest of `segs` by a search of every one, written independently of
    /// the module (the foot of the perpendicular by projection, clamped to the segment).
    fn brute_force(segs: &[(Vec2, Vec2)], p: Vec2) -> f64 {
        segs.iter()
            .map(|&(a, b)| {
                let ab = b - a;
                let l2 = ab.dot(ab);
                let t = if l2 > 0.0 {
                    ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (a + ab * t - p).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Far from the isoline, where the old bucket-ring search grew with the cube of the
    /// distance and, past the lattice's own size, found nothing (`None`): a circle of radius 7
    /// sampled on a 0.25 m lattice over a 20 m square, queried 50 m to 1e6 m from it in every
    /// direction. Each answer is the search of every segment's, bit for bit, and `|p| - 7`
    /// within the lattice's chord error.
    #[test]
    fn far_points_get_the_exact_nearest_segment() {
        let iso = IsolineSegments::from_samples(Vec2::new(-10.0, -10.0), 0.25, 81, 81, 7.0, |p| {
            Some(p.norm())
        });
        for k in 0..200 {
            let r = 50.0 * 1.07f64.powi(k);
            let p = Vec2::from_angle(k as f64 * 2.399) * r.min(1e6);
            let d = iso.distance(p).expect("a distance however far");
            assert_eq!(d, brute_force(iso.segments(), p), "{p:?}");
            assert!(
                (d - (p.norm() - 7.0)).abs() < 0.01 + 1e-12 * r,
                "{p:?}: {d}"
            );
        }
    }

    /// Ties and degenerate segments: a square's four sides given twice, one of them reversed,
    /// plus zero-length segments at its corners; a point on a side, at a corner, at the
    /// centre (all four sides 1 m away) and outside a corner (the corner's distance,
    /// sqrt(2)). Non-finite points have no distance.
    #[test]
    fn ties_and_degenerate_segments() {
        let c = [
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(0.0, 2.0),
        ];
        let mut segs: Vec<(Vec2, Vec2)> = (0..4).map(|k| (c[k], c[(k + 1) % 4])).collect();
        segs.extend((0..4).map(|k| (c[(k + 1) % 4], c[k])));
        segs.extend(c.iter().map(|&q| (q, q)));
        let iso = IsolineSegments::new(segs.clone());
        for (p, want) in [
            (Vec2::new(1.0, 0.0), 0.0),
            (Vec2::new(2.0, 2.0), 0.0),
            (Vec2::new(1.0, 1.0), 1.0),
            (Vec2::new(3.0, 3.0), std::f64::consts::SQRT_2),
            (Vec2::new(-0.5, 1.3), 0.5),
        ] {
            let d = iso.distance(p).unwrap();
            assert_eq!(d, brute_force(&segs, p), "{p:?}");
            assert!((d - want).abs() < 1e-15, "{p:?}: {d}");
        }
        assert_eq!(iso.distance(Vec2::new(f64::NAN, 0.0)), None);
        assert_eq!(iso.distance(Vec2::new(0.0, f64::INFINITY)), None);
        assert_eq!(IsolineSegments::new(vec![]).distance(Vec2::default()), None);
    }

    /// Many random queries against a wiggly isoline (many segments of every direction, some
    /// near-ties): the tree's answer is the search of every segment's, bit for bit.
    #[test]
    fn random_queries_equal_brute_force() {
        use rand::{RngExt, SeedableRng};
        let f = |p: Vec2| Some((0.7 * p.x).sin() + (0.5 * p.y).cos() + 0.05 * p.x);
        let iso = IsolineSegments::from_samples(Vec2::new(-30.0, -20.0), 0.3, 200, 140, 0.4, f);
        assert!(iso.segments().len() > 1000, "{}", iso.segments().len());
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..2000 {
            let s = if rng.random_bool(0.5) { 40.0 } else { 4000.0 };
            let p = Vec2::new(rng.random_range(-s..s), rng.random_range(-s..s));
            assert_eq!(
                iso.distance(p).unwrap(),
                brute_force(iso.segments(), p),
                "{p:?}"
            );
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

    /// The hostile review's reproducer (issue 30): a grid 2 km wide and 2 um high. Sampled
    /// square at `min(dx, dy)/4` it took 8e9 x 9 samples (a 576 GB allocation, an abort);
    /// each axis at its own spacing it takes 9 x 9, and the isoline of `F = x` at 1600 is the
    /// line x = 1600, one segment per row of cells.
    #[test]
    fn an_anisotropic_grid_is_sampled_per_axis() {
        let g = Grid2::from_fn(3, 3, Vec2::new(0.0, 0.0), [1000.0, 1e-6], |p| p.x).unwrap();
        let gf = GridField::new(g, Interpolation::Bilinear);
        let iso = IsolineSegments::for_grid(&gf, 1600.0, 4);
        assert_eq!(iso.segments().len(), 8);
        for &(a, b) in iso.segments() {
            assert!((a.x - 1600.0).abs() < 1e-9 && (b.x - 1600.0).abs() < 1e-9);
        }
        let d = iso.distance(Vec2::new(100.0, 1e-6)).unwrap();
        assert!((d - 1500.0).abs() < 1e-9, "{d}");
    }

    /// The lattices planned for grids at and beyond the documented limits stay within
    /// [`MAX_ISOLINE_SAMPLES`] = 4 194 304; counts worked by hand.
    #[test]
    fn lattices_stay_within_the_sample_budget() {
        let ext = |cols: usize, rows: usize, [dx, dy]: [f64; 2]| {
            [0.0, (cols - 1) as f64 * dx, 0.0, (rows - 1) as f64 * dy]
        };
        let plan = |cols, rows, sp| grid_lattice(cols, rows, sp, ext(cols, rows, sp), 4);
        // Small and square: unchanged, h = 0.5/4 over 40 m: 321 x 321.
        let l = plan(81, 81, [0.5, 0.5]);
        assert_eq!((l.step_m, l.nx, l.ny), ([0.125, 0.125], 321, 321));
        // 3 x 3 nodes 1000 m by 0.01 m: per axis, 9 x 9 samples.
        let l = plan(3, 3, [1000.0, 0.01]);
        assert_eq!((l.step_m, l.nx, l.ny), ([250.0, 0.0025], 9, 9));
        // 1025^2: square 4097^2 and per-axis r = 2 (2049^2 = 4 198 401) exceed 2^22; r = 1.
        let l = plan(1025, 1025, [1.0, 1.0]);
        assert_eq!((l.step_m, l.nx, l.ny), ([1.0, 1.0], 1025, 1025));
        // 4000^2 (the 128 MB .npy): 4000^2 = 1.6e7 nodes > 2^22; every 2nd node, 2000^2.
        let l = plan(4000, 4000, [1.0, 1.0]);
        assert_eq!((l.step_m, l.nx, l.ny), ([2.0, 2.0], 2000, 2000));
        // 16384^2 (2^28 nodes): every 8th node, 2048^2 = 2^22 exactly.
        let l = plan(16384, 16384, [30.0, 30.0]);
        assert_eq!((l.step_m, l.nx, l.ny), ([240.0, 240.0], 2048, 2048));
        // 1 x 2^28: every 64th node, (2^28 - 1)/64 + 1 = 2^22.
        let l = plan(1, 1 << 28, [1.0, 1.0]);
        assert_eq!((l.nx, l.ny), (1, 1 << 22));
        for l in [
            plan(16000, 16000, [1.0, 1.0]),
            plan(2, 1 << 27, [5.0, 1e-3]),
            plan(1 << 14, 1 << 14, [1e-3, 1e3]),
        ] {
            assert!(l.samples() <= MAX_ISOLINE_SAMPLES, "{l:?}");
            assert!(l.samples() > MAX_ISOLINE_SAMPLES / 8, "{l:?}");
        }
    }

    /// The work is the lattice's samples, each evaluated once: 7 x 5 calls of `f`.
    #[test]
    fn every_sample_is_evaluated_once() {
        let calls = std::cell::Cell::new(0usize);
        let iso = IsolineSegments::from_samples_xy(Vec2::default(), [1.0, 2.0], 7, 5, 2.5, |p| {
            calls.set(calls.get() + 1);
            Some(p.x)
        });
        assert_eq!(calls.get(), 35);
        // x = 2.5 crosses the 4 rows of cells, each 2 m high.
        assert_eq!(iso.segments().len(), 4);
        assert!(iso
            .segments()
            .iter()
            .all(|&(a, b)| a.x == 2.5 && b.x == 2.5 && (a.y - b.y).abs() == 2.0));
    }
}
