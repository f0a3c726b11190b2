//! Projection of a position onto a closed isoline: its arc coordinate, for the team metrics
//! (gaps, revisit times) and the `arc_reference` spacing law. Ground truth: never for a
//! coordinate-free law.
//!
//! Two implementations: [`CircleArc`] (analytic, the circular field's isolines) and
//! [`PolylineArc`] (a closed polyline, e.g. an isoline extracted from a sampled field by
//! marching squares and stitched into closed loops:
//! `isotrack_fields::isoline::IsolineSegments::closed_loops`).

use isotrack_core::Vec2;

/// A point's place on a closed isoline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcPoint {
    /// Arc coordinate of the nearest isoline point, m, in `[0, length)`, increasing
    /// counter-clockwise for a circle (along the polyline's vertex order for a polyline).
    pub s_m: f64,
    /// Unit tangent there, in the direction `s` increases.
    pub tangent: Vec2,
}

/// A closed isoline onto which positions are projected.
pub trait ArcProjection: Sync {
    /// The isoline's length `L`, m (> 0).
    fn length_m(&self) -> f64;
    /// The place of the isoline point nearest to `p` (`None` where undefined: a circle's centre).
    fn project(&self, p: Vec2) -> Option<ArcPoint>;
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
}

/// A closed polyline `v_0, v_1, ..., v_{n-1}, v_0`: the nearest point over all segments (a
/// linear scan, `O(n)` per query), its arc coordinate the length along the polyline from `v_0`.
#[derive(Clone, Debug, PartialEq)]
pub struct PolylineArc {
    vertices: Vec<Vec2>,
    /// `cum[i]`: arc length from `v_0` to `v_i`; `cum[n]` the total.
    cum: Vec<f64>,
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
        Ok(Self { vertices, cum })
    }

    /// The vertices (without the closing repeat).
    pub fn vertices(&self) -> &[Vec2] {
        &self.vertices
    }
}

impl ArcProjection for PolylineArc {
    fn length_m(&self) -> f64 {
        self.cum[self.vertices.len()]
    }

    fn project(&self, p: Vec2) -> Option<ArcPoint> {
        if !p.is_finite() {
            return None;
        }
        let n = self.vertices.len();
        let mut best: Option<(f64, f64, Vec2)> = None;
        for i in 0..n {
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
        let s = if s >= l { s - l } else { s };
        Some(ArcPoint { s_m: s, tangent })
    }
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
}
