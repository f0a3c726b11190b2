//! Regular grids of field values and their interpolation.
//!
//! Layout (the same as the bundled `data/`): `values[iy*nx + ix]`, row `iy = 0` is the southernmost,
//! column `ix = 0` the westernmost; node `(ix, iy)` sits at
//! `(origin_m.x + ix*dx, origin_m.y + iy*dy)` (cell centres). `NaN` marks no-data.

mod interp;
mod series;

pub use interp::{GridField, Interpolation};
pub use series::{AfterLastFrame, GridSeries, SeriesError, TimeInterpolation};

use isotrack_core::math::Vec2;

/// Why a grid cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GridError {
    /// Fewer than 2 x 2 nodes.
    #[error("the grid has {nx} x {ny} nodes; at least 2 x 2 are needed")]
    TooSmall {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// `values.len() != nx*ny`.
    #[error("{len} values do not fill {nx} x {ny} nodes")]
    SizeMismatch {
        /// Values given.
        len: usize,
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
    /// Non-positive or non-finite spacing, or non-finite origin.
    #[error("invalid georeference: spacing {spacing_m:?} m (must be > 0), origin {origin_m:?} m")]
    BadGeoreference {
        /// Spacing.
        spacing_m: [f64; 2],
        /// Origin.
        origin_m: [f64; 2],
    },
    /// Every value is no-data.
    #[error("every value is NaN / no-data")]
    AllNoData,
    /// A value is infinite.
    #[error("infinite value at column {ix}, row {iy}")]
    Infinite {
        /// Column.
        ix: usize,
        /// Row.
        iy: usize,
    },
    /// A value beyond [`MAX_ABS_VALUE`].
    #[error("value {value:e} at column {ix}, row {iy} is beyond +-{max:e}: the interpolation's differences and products would overflow; rescale the data", max = MAX_ABS_VALUE)]
    TooLarge {
        /// Column.
        ix: usize,
        /// Row.
        iy: usize,
        /// The value.
        value: f64,
    },
    /// More nodes than [`MAX_NODES`].
    #[error("{nx} x {ny} nodes is more than the {max} a grid may hold ({gib} GiB of values)", max = MAX_NODES, gib = (MAX_NODES * 8) >> 30)]
    TooManyNodes {
        /// Columns.
        nx: usize,
        /// Rows.
        ny: usize,
    },
}

/// The most nodes a grid may hold: 2^28 (16384 x 16384), 2 GiB of values.
pub const MAX_NODES: usize = 1 << 28;

/// The largest `|value|` a grid may hold: bicubic weights, gradients and Hessians multiply and
/// subtract values, and `1e308 - (-1e308)` is already infinite.
pub const MAX_ABS_VALUE: f64 = 1.0e100;

/// A regular 2-D grid of values.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid2 {
    nx: usize,
    ny: usize,
    origin_m: Vec2,
    spacing_m: [f64; 2],
    values: Vec<f64>,
}

impl Grid2 {
    /// A grid of `nx` columns and `ny` rows, row-major from the south-west node.
    pub fn new(
        nx: usize,
        ny: usize,
        origin_m: Vec2,
        spacing_m: [f64; 2],
        values: Vec<f64>,
    ) -> Result<Self, GridError> {
        if nx < 2 || ny < 2 {
            return Err(GridError::TooSmall { nx, ny });
        }
        if nx.checked_mul(ny).is_none_or(|n| n > MAX_NODES) {
            return Err(GridError::TooManyNodes { nx, ny });
        }
        if values.len() != nx * ny {
            return Err(GridError::SizeMismatch {
                len: values.len(),
                nx,
                ny,
            });
        }
        if !(spacing_m.iter().all(|s| s.is_finite() && *s > 0.0) && origin_m.is_finite()) {
            return Err(GridError::BadGeoreference {
                spacing_m,
                origin_m: [origin_m.x, origin_m.y],
            });
        }
        if let Some(i) = values.iter().position(|v| v.is_infinite()) {
            return Err(GridError::Infinite {
                ix: i % nx,
                iy: i / nx,
            });
        }
        if let Some(i) = values.iter().position(|v| v.abs() > MAX_ABS_VALUE) {
            return Err(GridError::TooLarge {
                ix: i % nx,
                iy: i / nx,
                value: values[i],
            });
        }
        if values.iter().all(|v| v.is_nan()) {
            return Err(GridError::AllNoData);
        }
        Ok(Self {
            nx,
            ny,
            origin_m,
            spacing_m,
            values,
        })
    }

    /// A grid sampled from a function at the nodes (tests, station interpolation).
    pub fn from_fn(
        nx: usize,
        ny: usize,
        origin_m: Vec2,
        spacing_m: [f64; 2],
        f: impl Fn(Vec2) -> f64,
    ) -> Result<Self, GridError> {
        if nx.checked_mul(ny).is_none_or(|n| n > MAX_NODES) {
            return Err(GridError::TooManyNodes { nx, ny });
        }
        let mut values = Vec::with_capacity(nx * ny);
        for iy in 0..ny {
            for ix in 0..nx {
                values.push(f(Vec2::new(
                    origin_m.x + ix as f64 * spacing_m[0],
                    origin_m.y + iy as f64 * spacing_m[1],
                )));
            }
        }
        Self::new(nx, ny, origin_m, spacing_m, values)
    }

    /// Columns.
    pub fn nx(&self) -> usize {
        self.nx
    }
    /// Rows.
    pub fn ny(&self) -> usize {
        self.ny
    }
    /// Position of node (0, 0), m.
    pub fn origin_m(&self) -> Vec2 {
        self.origin_m
    }
    /// Node spacing `[dx, dy]`, m.
    pub fn spacing_m(&self) -> [f64; 2] {
        self.spacing_m
    }
    /// The values, row-major from the south-west node.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// The value at node `(ix, iy)` (`NaN` for no-data).
    #[inline]
    pub fn at(&self, ix: usize, iy: usize) -> f64 {
        self.values[iy * self.nx + ix]
    }
    /// Position of node `(ix, iy)`, m.
    pub fn node_m(&self, ix: usize, iy: usize) -> Vec2 {
        Vec2::new(
            self.origin_m.x + ix as f64 * self.spacing_m[0],
            self.origin_m.y + iy as f64 * self.spacing_m[1],
        )
    }
    /// `[x_min, x_max, y_min, y_max]` of the nodes, m.
    pub fn extent_m(&self) -> [f64; 4] {
        let far = self.node_m(self.nx - 1, self.ny - 1);
        [self.origin_m.x, far.x, self.origin_m.y, far.y]
    }
    /// Smallest and largest value, ignoring no-data.
    pub fn value_range(&self) -> (f64, f64) {
        self.values
            .iter()
            .filter(|v| !v.is_nan())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(*v), hi.max(*v))
            })
    }
    /// Count of no-data nodes.
    pub fn nodata_count(&self) -> usize {
        self.values.iter().filter(|v| v.is_nan()).count()
    }
    /// Replaces the georeference.
    pub fn with_georeference(
        mut self,
        origin_m: Vec2,
        spacing_m: [f64; 2],
    ) -> Result<Self, GridError> {
        if !(spacing_m.iter().all(|s| s.is_finite() && *s > 0.0) && origin_m.is_finite()) {
            return Err(GridError::BadGeoreference {
                spacing_m,
                origin_m: [origin_m.x, origin_m.y],
            });
        }
        self.origin_m = origin_m;
        self.spacing_m = spacing_m;
        Ok(self)
    }
    /// Applies `f` to every value (no-data stays no-data); a non-finite result becomes no-data.
    pub fn map_values(mut self, f: impl Fn(f64) -> f64) -> Result<Self, GridError> {
        for v in &mut self.values {
            if !v.is_nan() {
                let w = f(*v);
                *v = if w.is_finite() { w } else { f64::NAN };
            }
        }
        if self.values.iter().all(|v| v.is_nan()) {
            return Err(GridError::AllNoData);
        }
        Ok(self)
    }
    /// The sub-grid of columns `ix0..=ix1` and rows `iy0..=iy1` (node positions unchanged).
    pub fn crop(&self, ix0: usize, ix1: usize, iy0: usize, iy1: usize) -> Result<Self, GridError> {
        let ix1 = ix1.min(self.nx - 1);
        let iy1 = iy1.min(self.ny - 1);
        if ix0 >= ix1 || iy0 >= iy1 {
            return Err(GridError::TooSmall {
                nx: ix1.saturating_sub(ix0) + 1,
                ny: iy1.saturating_sub(iy0) + 1,
            });
        }
        let mut values = Vec::with_capacity((ix1 - ix0 + 1) * (iy1 - iy0 + 1));
        for iy in iy0..=iy1 {
            values.extend_from_slice(&self.values[iy * self.nx + ix0..=iy * self.nx + ix1]);
        }
        Self::new(
            ix1 - ix0 + 1,
            iy1 - iy0 + 1,
            self.node_m(ix0, iy0),
            self.spacing_m,
            values,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `v(ix, iy) = 10 iy + ix` on a 4 x 3 grid at (100, 200) with 2 m x 5 m cells.
    fn grid() -> Grid2 {
        Grid2::from_fn(4, 3, Vec2::new(100.0, 200.0), [2.0, 5.0], |p| {
            (p.y - 200.0) / 5.0 * 10.0 + (p.x - 100.0) / 2.0
        })
        .unwrap()
    }

    #[test]
    fn nodes_extent_and_range_by_hand() {
        let g = grid();
        assert_eq!(g.at(3, 2), 23.0);
        assert_eq!(g.at(1, 2), 21.0);
        assert_eq!(g.node_m(3, 1), Vec2::new(106.0, 205.0));
        assert_eq!(g.extent_m(), [100.0, 106.0, 200.0, 210.0]);
        assert_eq!(g.value_range(), (0.0, 23.0));
        let mut v = g.values().to_vec();
        v[0] = f64::NAN;
        v[11] = f64::NAN;
        let h = Grid2::new(4, 3, g.origin_m(), g.spacing_m(), v).unwrap();
        assert_eq!(h.value_range(), (1.0, 22.0));
        assert_eq!(h.nodata_count(), 2);
    }

    #[test]
    fn too_many_nodes_is_an_error() {
        let e = Grid2::from_fn(MAX_NODES / 2 + 1, 2, Vec2::default(), [1.0, 1.0], |_| 0.0);
        assert!(matches!(e, Err(GridError::TooManyNodes { .. })));
        let e = Grid2::from_fn(usize::MAX, 2, Vec2::default(), [1.0, 1.0], |_| 0.0);
        assert!(matches!(e, Err(GridError::TooManyNodes { .. })));
    }

    #[test]
    fn georeference_is_replaced_or_refused() {
        let g = grid()
            .with_georeference(Vec2::new(-1.0, 2.0), [0.5, 0.25])
            .unwrap();
        assert_eq!(g.node_m(2, 2), Vec2::new(0.0, 2.5));
        assert_eq!(g.at(2, 2), 22.0);
        for (o, s) in [
            (Vec2::new(0.0, 0.0), [0.0, 1.0]),
            (Vec2::new(0.0, 0.0), [1.0, -1.0]),
            (Vec2::new(0.0, 0.0), [f64::INFINITY, 1.0]),
            (Vec2::new(f64::NAN, 0.0), [1.0, 1.0]),
        ] {
            assert!(
                matches!(
                    grid().with_georeference(o, s),
                    Err(GridError::BadGeoreference { .. })
                ),
                "{o:?} {s:?}"
            );
        }
    }

    #[test]
    fn map_values_keeps_nodata_and_drops_non_finite() {
        let mut v = grid().values().to_vec();
        v[5] = f64::NAN;
        let g = Grid2::new(4, 3, Vec2::default(), [1.0, 1.0], v).unwrap();
        // 1/(v - 1): v = 1 (node (1, 0)) gives infinity, which becomes no-data.
        let m = g.map_values(|x| 1.0 / (x - 1.0)).unwrap();
        assert_eq!(m.at(0, 0), -1.0);
        assert!(m.at(1, 0).is_nan(), "infinite -> no-data");
        assert!(m.at(1, 1).is_nan(), "no-data stays");
        assert_eq!(m.at(3, 2), 1.0 / 22.0);
        assert_eq!(m.nodata_count(), 2);
        assert!(matches!(
            grid().map_values(|_| f64::NAN),
            Err(GridError::AllNoData)
        ));
    }

    #[test]
    fn crop_by_hand() {
        let g = grid();
        let c = g.crop(1, 2, 1, 2).unwrap();
        assert_eq!((c.nx(), c.ny()), (2, 2));
        assert_eq!(c.values(), &[11.0, 12.0, 21.0, 22.0]);
        assert_eq!(c.origin_m(), Vec2::new(102.0, 205.0));
        assert_eq!(c.spacing_m(), [2.0, 5.0]);
        // Upper bounds past the grid are clamped to its last node.
        let c = g.crop(2, 99, 0, 99).unwrap();
        assert_eq!((c.nx(), c.ny()), (2, 3));
        assert_eq!(c.values(), &[2.0, 3.0, 12.0, 13.0, 22.0, 23.0]);
        // The error names the size asked for: 1 x 3 nodes.
        assert!(matches!(
            g.crop(2, 2, 0, 2),
            Err(GridError::TooSmall { nx: 1, ny: 3 })
        ));
        assert!(matches!(
            g.crop(0, 3, 2, 2),
            Err(GridError::TooSmall { nx: 4, ny: 1 })
        ));
        for (a, b, c_, d) in [(2, 2, 0, 2), (0, 3, 1, 1), (3, 1, 0, 2), (4, 9, 0, 2)] {
            assert!(
                matches!(g.crop(a, b, c_, d), Err(GridError::TooSmall { .. })),
                "{a} {b} {c_} {d}"
            );
        }
    }
}
