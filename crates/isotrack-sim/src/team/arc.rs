//! Projection of a position onto an isoline: its arc coordinate, for the team metrics
//! (gaps, revisit times) and the `arc_reference` spacing law. Ground truth: never for a
//! coordinate-free law.
//!
//! Two implementations: [`CircleArc`] (analytic, the circular field's isolines) and
//! [`PolylineArc`] (a closed polyline, e.g. an isoline extracted from a sampled field by
//! marching squares and stitched into closed loops:
//! `isotrack_fields::isoline::IsolineSegments::closed_loops`; or an open one,
//! [`PolylineArc::open`], an isoline that leaves the field: `open_chains`).

use isotrack_core::Vec2;

/// A point's place on an isoline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcPoint {
    /// Arc coordinate of the nearest isoline point, m, in `[0, length)` (`[0, length]` on an
    /// open isoline), increasing counter-clockwise for a circle (along the polyline's vertex
    /// order for a polyline).
    pub s_m: f64,
    /// Unit tangent there, in the direction `s` increases.
    pub tangent: Vec2,
}

/// An isoline onto which positions are projected: closed (a loop, arc coordinates modulo its
/// length) or open (a curve with two ends, arc coordinates from its first end, no wrap-around).
pub trait ArcProjection: Sync {
    /// The isoline's length `L`, m (> 0).
    fn length_m(&self) -> f64;
    /// The place of the isoline point nearest to `p` (`None` where undefined: a circle's centre).
    fn project(&self, p: Vec2) -> Option<ArcPoint>;
    /// Whether the isoline is a closed loop (the default) or an open curve.
    fn is_closed(&self) -> bool {
        true
    }
    /// The point of the isoline at arc coordinate `s_m` (wrapped into `[0, length)` on a loop,
    /// clamped to the ends of an open curve); `None` where the projection does not know its
    /// points (the default) or `s_m` is not finite. The team metrics along a moving isoline
    /// carry each revisit bin's last pass from one extraction to the next through its point.
    fn point_at(&self, _s_m: f64) -> Option<Vec2> {
        None
    }
}

/// A circle of radius `radius_m` about `center_m`: `s = R * atan2(y - y0, x - x0)` wrapped to
/// `[0, 2 pi R)`, tangent `(-sin, cos)` (counter-clockwise). Exact: the nearest point of a
/// circle lies on the ray from its centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CircleArc {
    /// Centre, m.
    pub center_m: Vec2,
    /// Radius, m (> 0).
    pub radius_m: f64,
}

impl ArcProjection for CircleArc {
    fn length_m(&self) -> f64 {
        2.0 * core::f64::consts::PI * self.radius_m
    }

    fn project(&self, p: Vec2) -> Option<ArcPoint> {
        let d = p - self.center_m;
        let n = d.norm();
        if !n.is_finite() || n <= 0.0 {
            return None;
        }
        let mut th = d.y.atan2(d.x);
        if th < 0.0 {
            th += 2.0 * core::f64::consts::PI;
        }
        let s = (th * self.radius_m).min(self.length_m().next_down());
        Some(ArcPoint {
            s_m: s,
            tangent: Vec2::new(-d.y / n, d.x / n),
        })
    }

    fn point_at(&self, s_m: f64) -> Option<Vec2> {
        if !(s_m.is_finite() && self.radius_m > 0.0) {
            return None;
        }
        let th = s_m / self.radius_m;
        Some(self.center_m + Vec2::new(self.radius_m * th.cos(), self.radius_m * th.sin()))
    }
}

/// A closed polyline `v_0, v_1, ..., v_{n-1}, v_0` ([`PolylineArc::new`]) or an open one
/// `v_0, ..., v_{n-1}` ([`PolylineArc::open`]): the nearest point over all segments (a
/// linear scan, `O(n)` per query), its arc coordinate the length along the polyline from `v_0`.
#[derive(Clone, Debug, PartialEq)]
pub struct PolylineArc {
    vertices: Vec<Vec2>,
    /// `cum[i]`: arc length from `v_0` to `v_i`; the last entry the total (`cum[n]` closed,
    /// `cum[n - 1]` open).
    cum: Vec<f64>,
    /// Whether the last vertex joins back to the first.
    closed: bool,
}

/// Why points do not make a [`PolylineArc`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PolylineError {
    /// Fewer than 3 distinct vertices, a non-finite one, or zero length.
    #[error(
        "a closed isoline needs at least 3 finite vertices and a positive length \
         (got {0} vertices)"
    )]
    Degenerate(usize),
    /// An open polyline of fewer than 2 vertices, a non-finite one, or zero length.
    #[error(
        "an open isoline needs at least 2 finite vertices and a positive length \
         (got {0} vertices)"
    )]
    DegenerateOpen(usize),
}

impl PolylineArc {
    /// The closed polyline through `vertices` (the last joined back to the first; a repeated
    /// closing vertex is dropped).
    pub fn new(mut vertices: Vec<Vec2>) -> Result<Self, PolylineError> {
        if vertices.len() > 1 && vertices.first() == vertices.last() {
            vertices.pop();
        }
        let n = vertices.len();
        if n < 3 || vertices.iter().any(|v| !v.is_finite()) {
            return Err(PolylineError::Degenerate(n));
        }
        let mut cum = Vec::with_capacity(n + 1);
        let mut acc = 0.0;
        cum.push(0.0);
        for i in 0..n {
            acc += (vertices[(i + 1) % n] - vertices[i]).norm();
            cum.push(acc);
        }
        if !(acc > 0.0 && acc.is_finite()) {
            return Err(PolylineError::Degenerate(n));
        }
        Ok(Self {
            vertices,
            cum,
            closed: true,
        })
    }

    /// The open polyline through `vertices` (`v_0` to `v_{n-1}`, not joined back): an isoline
    /// that leaves the field. Arc coordinates run from `0` at `v_0` to the length at `v_{n-1}`;
    /// a point beyond an end projects onto that end.
    pub fn open(vertices: Vec<Vec2>) -> Result<Self, PolylineError> {
        let n = vertices.len();
        if n < 2 || vertices.iter().any(|v| !v.is_finite()) {
            return Err(PolylineError::DegenerateOpen(n));
        }
        let mut cum = Vec::with_capacity(n);
        let mut acc = 0.0;
        cum.push(0.0);
        for i in 0..n - 1 {
            acc += (vertices[i + 1] - vertices[i]).norm();
            cum.push(acc);
        }
        if !(acc > 0.0 && acc.is_finite()) {
            return Err(PolylineError::DegenerateOpen(n));
        }
        Ok(Self {
            vertices,
            cum,
            closed: false,
        })
    }

    /// The vertices (without the closing repeat).
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }
}

impl ArcProjection for PolylineArc {
    fn length_m(&self) -> f64 {
        self.cum[self.cum.len() - 1]
    }

    fn is_closed(&self) -> bool {
        self.closed
    }

    fn project(&self, p: Vec2) -> Option<ArcPoint> {
        if !p.is_finite() {
            return None;
        }
        let n = self.vertices.len();
        let mut best: Option<(f64, f64, Vec2)> = None;
        let segments = if self.closed { n } else { n - 1 };
        for i in 0..segments {
            let a = self.vertices[i];
            let seg = self.vertices[(i + 1) % n] - a;
            let len2 = seg.dot(seg);
            if len2 == 0.0 {
                continue;
            }
            let u = ((p - a).dot(seg) / len2).clamp(0.0, 1.0);
            let q = a + seg * u;
            let d2 = (p - q).dot(p - q);
            if best.is_none_or(|(bd, _, _)| d2 < bd) {
                let len = len2.sqrt();
                best = Some((d2, self.cum[i] + u * len, seg * (1.0 / len)));
            }
        }
        let (_, s, tangent) = best?;
        let l = self.length_m();
        let s = if self.closed && s >= l { s - l } else { s };
        Some(ArcPoint { s_m: s, tangent })
    }

    fn point_at(&self, s_m: f64) -> Option<Vec2> {
        if !s_m.is_finite() {
            return None;
        }
        let l = self.length_m();
        let s = if self.closed {
            wrap_arc(s_m, l)
        } else {
            s_m.clamp(0.0, l)
        };
        let n = self.vertices.len();
        let segments = if self.closed { n } else { n - 1 };
        // The segment `i` with `cum[i] <= s < cum[i + 1]` (the last one at the end).
        let i = (self.cum.partition_point(|c| *c <= s).max(1) - 1).min(segments - 1);
        let (a, b) = (self.vertices[i], self.vertices[(i + 1) % n]);
        let len = self.cum[i + 1] - self.cum[i];
        let u = if len > 0.0 {
            ((s - self.cum[i]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Some(a + (b - a) * u)
    }
}

impl PolylineArc {
    /// Twice the signed area enclosed (the shoelace sum `sum x_i y_{i+1} - x_{i+1} y_i`):
    /// positive for counter-clockwise vertices.
    pub fn twice_signed_area_m2(&self) -> f64 {
        let v = &self.vertices;
        let n = v.len();
        (0..n)
            .map(|i| {
                let (a, b) = (v[i], v[(i + 1) % n]);
                a.x * b.y - b.x * a.y
            })
            .sum()
    }

    /// The closed polyline through `vertices` oriented counter-clockwise (as [`CircleArc`]'s
    /// `s`) and, given the isoline of the last extraction `previous`, started at the vertex
    /// nearest to `previous`'s first vertex: the arc coordinate of a point of an isoline that
    /// moves and deforms a little between extractions then changes a little (marching squares
    /// starts a loop anywhere). `O(vertices)`.
    pub fn aligned(
        mut vertices: Vec<Vec2>,
        previous: Option<&PolylineArc>,
    ) -> Result<Self, PolylineError> {
        let probe = Self::new(vertices.clone())?;
        if probe.twice_signed_area_m2() < 0.0 {
            vertices.reverse();
        }
        if let Some(start) = previous.and_then(|p| p.vertices.first().copied()) {
            let mut nearest = (0usize, f64::INFINITY);
            for (i, v) in vertices.iter().enumerate() {
                let d = (*v - start).dot(*v - start);
                if d < nearest.1 {
                    nearest = (i, d);
                }
            }
            let nearest = nearest.0;
            vertices.rotate_left(nearest);
        }
        Self::new(vertices)
    }
}

/// The distance from `p` to the closed polyline `loop_m` (vertices, the last joined to the
/// first), m.
pub fn distance_to_loop(loop_m: &[Vec2], p: Vec2) -> f64 {
    let n = loop_m.len();
    let mut best = f64::INFINITY;
    for i in 0..n {
        best = best.min(squared_distance_to_segment(
            loop_m[i],
            loop_m[(i + 1) % n],
            p,
        ));
    }
    best.sqrt()
}

/// The distance from `p` to the open polyline `chain_m` (vertices, not joined back), m.
pub fn distance_to_chain(chain_m: &[Vec2], p: Vec2) -> f64 {
    let mut best = f64::INFINITY;
    for w in chain_m.windows(2) {
        best = best.min(squared_distance_to_segment(w[0], w[1], p));
    }
    best.sqrt()
}

/// The squared distance from `p` to the segment from `a` to `b`, m^2: to the point
/// `a + u (b - a)` with `u` the projection clamped to [0, 1] (`u = 0` for a zero-length segment).
fn squared_distance_to_segment(a: Vec2, b: Vec2, p: Vec2) -> f64 {
    let seg = b - a;
    let len2 = seg.dot(seg);
    let u = if len2 > 0.0 {
        ((p - a).dot(seg) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let q = a + seg * u;
    (p - q).dot(p - q)
}

/// Which piece of an isoline the team is on, of its closed `loops` and its open `chains`
/// (pieces that leave the field): each of (at most [`MAX_LOOP_VOTERS`], evenly picked)
/// `positions` votes for the piece nearest to it; the piece with the most votes (a tie: the
/// longer, then a loop before a chain, then the first). `Ok(i)`: loop `i`; `Err(j)`: chain
/// `j`. `None` without pieces or positions. With no chains it is [`pick_loop`].
pub fn pick_piece(
    loops: &[Vec<Vec2>],
    chains: &[Vec<Vec2>],
    positions: &[Vec2],
) -> Option<Result<usize, usize>> {
    if chains.is_empty() {
        return pick_loop(loops, positions).map(Ok);
    }
    let finite: Vec<Vec2> = positions
        .iter()
        .copied()
        .filter(|p| p.is_finite())
        .collect();
    if finite.is_empty() {
        return None;
    }
    let pieces = loops.len() + chains.len();
    let distance = |j: usize, p: Vec2| {
        if j < loops.len() {
            distance_to_loop(&loops[j], p)
        } else {
            distance_to_chain(&chains[j - loops.len()], p)
        }
    };
    let length = |j: usize| -> f64 {
        if j < loops.len() {
            let l = &loops[j];
            (0..l.len())
                .map(|i| (l[(i + 1) % l.len()] - l[i]).norm())
                .sum()
        } else {
            chains[j - loops.len()]
                .windows(2)
                .map(|w| (w[1] - w[0]).norm())
                .sum()
        }
    };
    let stride = finite.len().div_ceil(MAX_LOOP_VOTERS);
    let mut votes = vec![0usize; pieces];
    for p in finite.iter().step_by(stride) {
        let mut best = (f64::INFINITY, 0usize);
        for j in 0..pieces {
            let d = distance(j, *p);
            if d < best.0 {
                best = (d, j);
            }
        }
        votes[best.1] += 1;
    }
    let mut pick = 0;
    for j in 1..pieces {
        if votes[j] > votes[pick] || (votes[j] == votes[pick] && length(j) > length(pick)) {
            pick = j;
        }
    }
    Some(if pick < loops.len() {
        Ok(pick)
    } else {
        Err(pick - loops.len())
    })
}

/// Most vehicles that vote in [`pick_loop`]: the choice costs `O(min(N, 64) x vertices)`.
pub const MAX_LOOP_VOTERS: usize = 64;

/// Which of several closed loops of an isoline the team is on: each of (at most
/// [`MAX_LOOP_VOTERS`], evenly picked) `positions` votes for the loop nearest to it; the loop
/// with the most votes (a tie: the longer, then the first). `None` without loops or positions.
pub fn pick_loop(loops: &[Vec<Vec2>], positions: &[Vec2]) -> Option<usize> {
    if loops.is_empty() {
        return None;
    }
    if loops.len() == 1 {
        return Some(0);
    }
    let finite: Vec<Vec2> = positions
        .iter()
        .copied()
        .filter(|p| p.is_finite())
        .collect();
    if finite.is_empty() {
        return None;
    }
    let stride = finite.len().div_ceil(MAX_LOOP_VOTERS);
    let mut votes = vec![0usize; loops.len()];
    for p in finite.iter().step_by(stride) {
        let mut best = (f64::INFINITY, 0usize);
        for (j, l) in loops.iter().enumerate() {
            let d = distance_to_loop(l, *p);
            if d < best.0 {
                best = (d, j);
            }
        }
        votes[best.1] += 1;
    }
    let length = |l: &[Vec2]| -> f64 {
        (0..l.len())
            .map(|i| (l[(i + 1) % l.len()] - l[i]).norm())
            .sum()
    };
    let mut pick = 0;
    for j in 1..loops.len() {
        let better = votes[j] > votes[pick]
            || (votes[j] == votes[pick] && length(&loops[j]) > length(&loops[pick]));
        if better {
            pick = j;
        }
    }
    Some(pick)
}

/// An isoline that moves (a time series of frames, a puff plume): the team metrics measure
/// along the isoline of the time, extracted again only when [`version`](Self::version)
/// changes (once per frame or per period, never per vehicle).
pub trait MovingArc: Sync {
    /// Which isoline is in force at `t_s` (the same number: the same isoline, not extracted
    /// again); `None` where there is none (the field has ended).
    fn version(&self, t_s: f64) -> Option<i64>;
    /// The closed loops of the isoline of `version` (each its vertices, at least 3, the
    /// closing one not repeated); open chains (leaving the field) are left out.
    fn loops(&self, version: i64) -> Vec<Vec<Vec2>>;
}

/// `x mod l` in `[0, l)`.
#[inline]
pub(crate) fn wrap_arc(x: f64, l: f64) -> f64 {
    let r = x % l;
    let r = if r < 0.0 { r + l } else { r };
    if r >= l {
        0.0
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// The circle's arc coordinate is `R theta`; a polyline of 3600 chords of the same circle
    /// agrees to the chord's sagitta.
    #[test]
    fn circle_and_polyline_agree() {
        let c = CircleArc {
            center_m: Vec2::new(1.0, -2.0),
            radius_m: 5.0,
        };
        assert!((c.length_m() - 10.0 * PI).abs() < 1e-12);
        let m = 3600;
        let poly = PolylineArc::new(
            (0..m)
                .map(|i| {
                    let th = 2.0 * PI * i as f64 / m as f64;
                    Vec2::new(1.0 + 5.0 * th.cos(), -2.0 + 5.0 * th.sin())
                })
                .collect(),
        )
        .unwrap();
        // Perimeter of the inscribed 3600-gon: 2 m R sin(pi/m).
        let per = 2.0 * m as f64 * 5.0 * (PI / m as f64).sin();
        assert!((poly.length_m() - per).abs() < 1e-9);
        for th in [0.1, 1.0, 2.5, 4.0, 6.2] {
            let p = Vec2::new(1.0 + 6.0 * f64::cos(th), -2.0 + 6.0 * f64::sin(th));
            let a = c.project(p).unwrap();
            assert!((a.s_m - 5.0 * th).abs() < 1e-9);
            assert!((a.tangent.x + th.sin()).abs() < 1e-12);
            let b = poly.project(p).unwrap();
            assert!((a.s_m - b.s_m).abs() < 2e-3, "{} vs {}", a.s_m, b.s_m);
            assert!((a.tangent.dot(b.tangent) - 1.0).abs() < 1e-5);
        }
        assert_eq!(c.project(Vec2::new(1.0, -2.0)), None);
        assert!(PolylineArc::new(vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0)]).is_err());
        assert!((wrap_arc(-1.0, 10.0) - 9.0).abs() < 1e-15);
        assert!((wrap_arc(23.0, 10.0) - 3.0).abs() < 1e-12);
    }

    /// A clockwise square is turned counter-clockwise (the shoelace area `2 a^2` positive) and
    /// started at the vertex nearest to the last loop's start; of two loops, the one most
    /// points are nearest to is picked (a tie: the longer).
    #[test]
    fn aligned_and_picked() {
        let sq = |c: Vec2, a: f64| {
            vec![
                c + Vec2::new(0.0, 0.0),
                c + Vec2::new(0.0, a),
                c + Vec2::new(a, a),
                c + Vec2::new(a, 0.0),
            ]
        };
        let o = Vec2::new(0.0, 0.0);
        let p = PolylineArc::aligned(sq(o, 2.0), None).unwrap();
        assert!((p.twice_signed_area_m2() - 8.0).abs() < 1e-12);
        assert_eq!(p.vertices()[0], Vec2::new(2.0, 0.0));
        let prev = PolylineArc::new(vec![
            Vec2::new(2.1, 2.1),
            Vec2::new(0.0, 2.0),
            Vec2::new(0.0, 0.0),
        ])
        .unwrap();
        let q = PolylineArc::aligned(sq(o, 2.0), Some(&prev)).unwrap();
        assert_eq!(q.vertices()[0], Vec2::new(2.0, 2.0));
        assert!(q.twice_signed_area_m2() > 0.0);
        // The point (2, 1) has s = 1 on a square started at (2, 0) going counter-clockwise.
        assert!((p.project(Vec2::new(2.5, 1.0)).unwrap().s_m - 1.0).abs() < 1e-12);
        let loops = vec![sq(o, 1.0), sq(Vec2::new(10.0, 0.0), 1.0)];
        let pts = [
            Vec2::new(10.5, 0.5),
            Vec2::new(11.5, 0.2),
            Vec2::new(0.5, 0.5),
        ];
        assert_eq!(pick_loop(&loops, &pts), Some(1));
        let loops = vec![sq(o, 1.0), sq(Vec2::new(10.0, 0.0), 3.0)];
        assert_eq!(
            pick_loop(&loops, &[Vec2::new(0.5, 0.5), Vec2::new(11.0, 1.0)]),
            Some(1)
        );
        assert_eq!(pick_loop(&[], &pts), None);
        assert!((distance_to_loop(&sq(o, 1.0), Vec2::new(3.0, 0.5)) - 2.0).abs() < 1e-12);
    }
}
