//! The field behind a picture of paths: values on a grid round the paths and the target
//! isoline, as the benchmark's page and the run report draw it.

use isotrack_core::{ScalarField, Vec2};
use isotrack_fields::isoline::IsolineSegments;
use isotrack_scenario::Scenario;
use serde::{Deserialize, Serialize};

/// The field behind a picture of paths: values on a grid over the paths (at t = 0) and the
/// target isoline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FieldPicture {
    /// `[x_min, y_min, x_max, y_max]`, m.
    pub bounds_m: [f64; 4],
    /// Samples per row and column.
    pub n: usize,
    /// Values, row 0 at `y_min`, `None` where the field has none.
    pub values: Vec<Option<f64>>,
    /// The isoline `s_d` as segments `[x0, y0, x1, y1]`, m.
    pub isoline: Vec<[f64; 4]>,
    /// The level.
    pub level: f64,
}

impl FieldPicture {
    /// The field of `scenario` at t = 0 on an `n x n` grid over a square round `points` (their
    /// bounding box, widened by 15 %, at least 2 m across), with its isoline `s_d`; `None` when
    /// no point is finite.
    pub fn around(
        scenario: &Scenario,
        points: impl IntoIterator<Item = [f64; 2]>,
        n: usize,
    ) -> Option<FieldPicture> {
        let (mut x0, mut y0, mut x1, mut y1) =
            (f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY);
        for [x, y] in points
            .into_iter()
            .filter(|p| p[0].is_finite() && p[1].is_finite())
        {
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
        if !(x0.is_finite() && y0.is_finite()) {
            return None;
        }
        // A square with a margin, so the isoline around the paths shows.
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let half = (0.5 * (x1 - x0).max(y1 - y0)).max(1.0) * 1.15;
        let (x0, y0) = (cx - half, cy - half);
        let h = 2.0 * half / (n - 1) as f64;
        let field = scenario.field();
        let at = |p: Vec2| field.value(0.0, p).filter(|v| v.is_finite());
        let mut values = Vec::with_capacity(n * n);
        for j in 0..n {
            for i in 0..n {
                values.push(at(Vec2::new(x0 + i as f64 * h, y0 + j as f64 * h)));
            }
        }
        let level = scenario.level();
        let iso = IsolineSegments::from_samples(Vec2::new(x0, y0), h, n, n, level, at);
        Some(FieldPicture {
            bounds_m: [x0, y0, x0 + 2.0 * half, y0 + 2.0 * half],
            n,
            values,
            isoline: iso
                .segments()
                .iter()
                .map(|(a, b)| [a.x, a.y, b.x, b.y])
                .collect(),
            level,
        })
    }
}
