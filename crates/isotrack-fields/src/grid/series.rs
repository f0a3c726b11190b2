//! A gridded field that changes with time: frames of one geometry at given times, interpolated
//! in space as [`GridField`] and in time between frames.
//!
//! Field time `tau = time_origin_s + time_scale * t` (run time `t`): `time_scale` plays a day of
//! weather to a slow robot in minutes. Between frames `k` and `k+1` (times `t_k`, `t_k+1`, weight
//! `w = (tau - t_k)/(t_k+1 - t_k)`):
//! - `Nearest`: the frame whose time is nearest (`w < 1/2` picks `k`);
//! - `Linear`: `(1 - w) F_k + w F_k+1`, exact for a field linear in time;
//! - `Cubic`: Catmull-Rom in time over `F_k-1 .. F_k+2` (frames at the ends repeated), C1 in
//!   time and exact for a field quadratic in time on uniform frame times.
//!
//! Gradients and Hessians in space are the same blend of the frames' analytic ones; the time
//! derivative `dF/dt` (per second of run time) is the blend's derivative in `w`.
//! Before the first frame the first holds; past the last, [`AfterLastFrame`] decides.

use super::{GridField, Interpolation};
use isotrack_core::math::{Mat2, Vec2};
use isotrack_core::{FieldDerivatives, ScalarField};

/// Interpolation between frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimeInterpolation {
    /// The nearest frame in time.
    Nearest,
    /// Linear between the two frames around the time (the default).
    #[default]
    Linear,
    /// Catmull-Rom over four frames.
    Cubic,
}

/// What the field is past its last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AfterLastFrame {
    /// The last frame holds (the default).
    #[default]
    Hold,
    /// The field has no value: the run ends (`left_field`, the data ended).
    End,
}

/// Frames of one geometry at increasing times (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct GridSeries {
    frames: Vec<GridField>,
    times_s: Vec<f64>,
    interpolation: TimeInterpolation,
    time_origin_s: f64,
    time_scale: f64,
    after_last: AfterLastFrame,
}

/// Why frames cannot make a series.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SeriesError {
    /// No frames, or a time count that does not match.
    #[error("{frames} frames and {times} frame times")]
    Count {
        /// Frames.
        frames: usize,
        /// Times.
        times: usize,
    },
    /// Times not finite and strictly increasing.
    #[error("frame times must be finite and strictly increasing (frame {0})")]
    Times(usize),
    /// Frames of different geometry.
    #[error("frame {0} differs from frame 0 in size, origin or spacing")]
    Geometry(usize),
    /// Bad time mapping.
    #[error("time_scale must be finite and > 0 and time_origin_s finite")]
    Mapping,
}

/// The frame-time weights of `tau`: `(index of the first frame used, weights of up to four
/// frames, their derivatives in tau)`, or `None` past the end with [`AfterLastFrame::End`].
type Weights = (usize, [f64; 4], [f64; 4], usize);

impl GridSeries {
    /// Frames at `times_s` (field time, s), interpolated in space by `interpolation` and in time
    /// by `time_interp`.
    pub fn new(
        frames: Vec<super::Grid2>,
        times_s: Vec<f64>,
        interpolation: Interpolation,
        time_interp: TimeInterpolation,
        time_origin_s: f64,
        time_scale: f64,
        after_last: AfterLastFrame,
    ) -> Result<Self, SeriesError> {
        if frames.is_empty() || frames.len() != times_s.len() {
            return Err(SeriesError::Count {
                frames: frames.len(),
                times: times_s.len(),
            });
        }
        for k in 0..times_s.len() {
            if !times_s[k].is_finite() || (k > 0 && times_s[k] <= times_s[k - 1]) {
                return Err(SeriesError::Times(k));
            }
        }
        let g0 = &frames[0];
        for (k, g) in frames.iter().enumerate() {
            if g.nx() != g0.nx()
                || g.ny() != g0.ny()
                || g.origin_m() != g0.origin_m()
                || g.spacing_m() != g0.spacing_m()
            {
                return Err(SeriesError::Geometry(k));
            }
        }
        if !(time_scale.is_finite() && time_scale > 0.0 && time_origin_s.is_finite()) {
            return Err(SeriesError::Mapping);
        }
        Ok(Self {
            frames: frames
                .into_iter()
                .map(|g| GridField::new(g, interpolation))
                .collect(),
            times_s,
            interpolation: time_interp,
            time_origin_s,
            time_scale,
            after_last,
        })
    }

    /// The frames.
    pub fn frames(&self) -> &[GridField] {
        &self.frames
    }
    /// Frame times (field time), s.
    pub fn times_s(&self) -> &[f64] {
        &self.times_s
    }
    /// Field time at run time `t_s`: `time_origin_s + time_scale * t_s`.
    pub fn field_time_s(&self, t_s: f64) -> f64 {
        self.time_origin_s + self.time_scale * t_s
    }
    /// Seconds of field time per second of run time.
    pub fn field_time_scale(&self) -> f64 {
        self.time_scale
    }
    /// The run time at which the last frame is reached, s.
    pub fn last_frame_run_time_s(&self) -> f64 {
        (self.times_s[self.times_s.len() - 1] - self.time_origin_s) / self.time_scale
    }
    /// Space interpolation.
    pub fn interpolation(&self) -> Interpolation {
        self.frames[0].interpolation()
    }
    /// `[x_min, x_max, y_min, y_max]` of the nodes, m.
    pub fn extent_m(&self) -> [f64; 4] {
        self.frames[0].grid().extent_m()
    }

    /// Frame weights at run time `t_s` (see [`Weights`]).
    fn weights(&self, t_s: f64) -> Option<Weights> {
        let tau = self.field_time_s(t_s);
        let t = &self.times_s;
        let n = t.len();
        if n == 1 || tau < t[0] {
            return Some((0, [1.0, 0.0, 0.0, 0.0], [0.0; 4], 1));
        }
        if tau > t[n - 1] {
            return match self.after_last {
                AfterLastFrame::Hold => Some((n - 1, [1.0, 0.0, 0.0, 0.0], [0.0; 4], 1)),
                AfterLastFrame::End => None,
            };
        }
        // The bracketing frames k, k+1 (the last interval at the last frame's time).
        let k = (t.partition_point(|&x| x <= tau) - 1).min(n - 2);
        let h = t[k + 1] - t[k];
        // (origin - t_k) + scale*t rather than tau - t_k: the same data on another time base
        // (frame times from 0 or from an epoch) gives the same weights bit for bit.
        let w = ((self.time_origin_s - t[k]) + self.time_scale * t_s) / h;
        // d/dt of the weights: dw/dt = time_scale / h.
        let dw = self.time_scale / h;
        Some(match self.interpolation {
            TimeInterpolation::Nearest => {
                if w < 0.5 {
                    (k, [1.0, 0.0, 0.0, 0.0], [0.0; 4], 1)
                } else {
                    (k + 1, [1.0, 0.0, 0.0, 0.0], [0.0; 4], 1)
                }
            }
            TimeInterpolation::Linear => (k, [1.0 - w, w, 0.0, 0.0], [-dw, dw, 0.0, 0.0], 2),
            TimeInterpolation::Cubic => {
                // Catmull-Rom over frames k-1, k, k+1, k+2 (clamped at the ends: a repeated
                // frame), as weights on the four indices from k-1 (which may be -1).
                let (a, da, _) = super::interp::keys_weights(w);
                (k.wrapping_sub(1), a, da.map(|x| x * dw), 4)
            }
        })
    }

    /// Runs `f` on each weighted frame and sums: `sum_j weight_j * f(frame_j)`.
    fn blend<T: Copy + core::ops::Add<Output = T> + core::ops::Mul<f64, Output = T>>(
        &self,
        t_s: f64,
        deriv: bool,
        f: impl Fn(&GridField) -> Option<T>,
    ) -> Option<T> {
        let (first, w, dw, m) = self.weights(t_s)?;
        let n = self.frames.len();
        let ws = if deriv { dw } else { w };
        let mut acc: Option<T> = None;
        for (j, wj) in ws.iter().enumerate().take(m) {
            // Index first + j, clamped to the frames (cubic repeats the end frames).
            let idx = (first as isize + j as isize).clamp(0, n as isize - 1) as usize;
            if *wj == 0.0 && m > 1 {
                // Skip exact zeros, but still require the value to exist at used frames.
                continue;
            }
            let v = f(&self.frames[idx])? * *wj;
            acc = Some(match acc {
                Some(a) => a + v,
                None => v,
            });
        }
        acc.or_else(|| f(&self.frames[first.min(n - 1)]).map(|v| v * 0.0))
    }

    /// `dF/dt` at `(t_s, p)`, field units per second of run time (`None` where the field has no
    /// value).
    pub fn time_derivative(&self, t_s: f64, p: Vec2) -> Option<f64> {
        self.blend(t_s, true, |g| g.value(0.0, p))
    }

    /// The interpolated grid at run time `t_s` (node values blended as the field is), for the
    /// isoline metric and plots; `None` past the end with [`AfterLastFrame::End`].
    pub fn grid_at(&self, t_s: f64) -> Option<super::Grid2> {
        let g0 = self.frames[0].grid();
        let (nx, ny) = (g0.nx(), g0.ny());
        let mut values = vec![0.0; nx * ny];
        let (first, w, _, m) = self.weights(t_s)?;
        let n = self.frames.len();
        for (j, wj) in w.iter().enumerate().take(m) {
            let idx = (first as isize + j as isize).clamp(0, n as isize - 1) as usize;
            let g = self.frames[idx].grid();
            for iy in 0..ny {
                for ix in 0..nx {
                    values[iy * nx + ix] += wj * g.at(ix, iy);
                }
            }
        }
        super::Grid2::new(nx, ny, g0.origin_m(), g0.spacing_m(), values).ok()
    }
}

impl ScalarField for GridSeries {
    fn value(&self, t_s: f64, p: Vec2) -> Option<f64> {
        self.blend(t_s, false, |g| g.value(0.0, p))
    }
}

impl FieldDerivatives for GridSeries {
    fn gradient(&self, t_s: f64, p: Vec2) -> Option<Vec2> {
        self.blend(t_s, false, |g| g.gradient(0.0, p))
    }
    fn hessian(&self, t_s: f64, p: Vec2) -> Option<Mat2> {
        let m = self.blend(t_s, false, |g| g.hessian(0.0, p).map(M4::from))?;
        Some([[m.0[0], m.0[1]], [m.0[2], m.0[3]]])
    }
}

/// A 2 x 2 matrix as four numbers, so the frame blend can add and scale it.
#[derive(Clone, Copy)]
struct M4([f64; 4]);

impl From<Mat2> for M4 {
    fn from(m: Mat2) -> Self {
        M4([m[0][0], m[0][1], m[1][0], m[1][1]])
    }
}

impl core::ops::Add for M4 {
    type Output = M4;
    fn add(self, o: M4) -> M4 {
        M4([
            self.0[0] + o.0[0],
            self.0[1] + o.0[1],
            self.0[2] + o.0[2],
            self.0[3] + o.0[3],
        ])
    }
}

impl core::ops::Mul<f64> for M4 {
    type Output = M4;
    fn mul(self, k: f64) -> M4 {
        M4(self.0.map(|x| x * k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid2;

    /// Frames of `F(x, y, tau) = a(tau) + x + 2 y` on a 6 x 5 grid at `times`.
    fn frames(times: &[f64], a: impl Fn(f64) -> f64) -> Vec<Grid2> {
        times
            .iter()
            .map(|&t| {
                Grid2::from_fn(6, 5, Vec2::new(0.0, 0.0), [1.0, 1.0], |p| {
                    a(t) + p.x + 2.0 * p.y
                })
                .unwrap()
            })
            .collect()
    }

    fn series(times: &[f64], a: impl Fn(f64) -> f64, ti: TimeInterpolation) -> GridSeries {
        GridSeries::new(
            frames(times, a),
            times.to_vec(),
            Interpolation::Bicubic,
            ti,
            0.0,
            1.0,
            AfterLastFrame::Hold,
        )
        .unwrap()
    }

    /// Linear interpolation reproduces a field linear in time exactly (uneven frame times),
    /// with its time derivative.
    #[test]
    fn linear_in_time_is_exact() {
        let times = [0.0, 10.0, 25.0, 60.0];
        let s = series(&times, |t| 3.0 * t, TimeInterpolation::Linear);
        let p = Vec2::new(2.3, 1.7);
        for t in [0.0, 3.0, 10.0, 17.5, 40.0, 59.9] {
            let want = 3.0 * t + 2.3 + 3.4;
            assert!((s.value(t, p).unwrap() - want).abs() < 1e-12, "t = {t}");
            assert!(
                (s.time_derivative(t, p).unwrap() - 3.0).abs() < 1e-12,
                "t = {t}"
            );
            let g = s.gradient(t, p).unwrap();
            assert!((g.x - 1.0).abs() < 1e-12 && (g.y - 2.0).abs() < 1e-12);
        }
        // Past the last frame: held.
        assert!((s.value(100.0, p).unwrap() - (180.0 + 5.7)).abs() < 1e-12);
        assert_eq!(s.time_derivative(100.0, p), Some(0.0));
    }

    /// Cubic (Catmull-Rom) in time is exact for a quadratic on uniform frames, away from the
    /// ends; nearest picks the closer frame.
    #[test]
    fn cubic_is_exact_for_quadratics_and_nearest_snaps() {
        let times: Vec<f64> = (0..8).map(|k| 10.0 * k as f64).collect();
        let s = series(&times, |t| 0.01 * t * t, TimeInterpolation::Cubic);
        let p = Vec2::new(1.0, 1.0);
        for t in [12.0, 25.0, 33.3, 47.0] {
            let want = 0.01 * t * t + 3.0;
            assert!((s.value(t, p).unwrap() - want).abs() < 1e-9, "t = {t}");
            assert!(
                (s.time_derivative(t, p).unwrap() - 0.02 * t).abs() < 1e-9,
                "t = {t}"
            );
        }
        let n = series(&times, |t| t, TimeInterpolation::Nearest);
        assert_eq!(n.value(14.9, p), Some(10.0 + 3.0));
        assert_eq!(n.value(15.1, p), Some(20.0 + 3.0));
    }

    /// The accessors; a later interval on an offset time base (frames at 1 h, 2 h, 3 h, the
    /// run starting at field time 1.5 h, 60 s of field time per run second); a single frame
    /// read at exactly its own time.
    #[test]
    fn accessors_later_intervals_and_a_single_frame() {
        let times = [3600.0, 7200.0, 10800.0];
        let s = GridSeries::new(
            frames(&times, |t| t / 3600.0),
            times.to_vec(),
            Interpolation::Bilinear,
            TimeInterpolation::Linear,
            5400.0,
            60.0,
            AfterLastFrame::Hold,
        )
        .unwrap();
        assert_eq!(s.frames().len(), 3);
        assert_eq!(s.times_s(), &times);
        assert_eq!(s.field_time_scale(), 60.0);
        assert_eq!(s.interpolation(), Interpolation::Bilinear);
        assert_eq!(s.extent_m(), [0.0, 5.0, 0.0, 4.0]);
        assert_eq!(s.field_time_s(30.0), 7200.0);
        let p = Vec2::new(1.0, 2.0);
        // Run 0 s: 1.5 h, halfway between the first two frames; run 45 s: 7200 + 900 s into
        // the second interval (a = 2.25 h).
        assert!((s.value(0.0, p).unwrap() - (1.5 + 5.0)).abs() < 1e-12);
        assert!((s.value(45.0, p).unwrap() - (2.25 + 5.0)).abs() < 1e-12);
        assert!((s.time_derivative(45.0, p).unwrap() - 60.0 / 3600.0).abs() < 1e-15);
        let one = GridSeries::new(
            frames(&[50.0], |_| 4.0),
            vec![50.0],
            Interpolation::Bicubic,
            TimeInterpolation::Cubic,
            50.0,
            1.0,
            AfterLastFrame::Hold,
        )
        .unwrap();
        for t in [0.0, 10.0] {
            assert!((one.value(t, p).unwrap() - 9.0).abs() < 1e-12, "t = {t}");
        }
    }

    /// The blended grid and Hessian: frames of `F = a(t) + b(t) (x^2 + 3 x y - y^2)` (bicubic is
    /// exact for quadratics) blend linearly in time, node by node and in the Hessian
    /// `b(t) [[2, 3], [3, -2]]`; cubic in time repeats the end frames (clamped indices).
    #[test]
    fn blended_grids_and_hessians() {
        let times = [0.0, 10.0, 20.0, 30.0];
        let (a, b) = (|t: f64| 1.0 + 0.1 * t, |t: f64| 2.0 - 0.05 * t);
        let quad = |p: Vec2| p.x * p.x + 3.0 * p.x * p.y - p.y * p.y;
        let frames: Vec<Grid2> = times
            .iter()
            .map(|&t| {
                Grid2::from_fn(7, 6, Vec2::new(-3.0, -2.0), [1.0, 1.0], |p| {
                    a(t) + b(t) * quad(p)
                })
                .unwrap()
            })
            .collect();
        let s = GridSeries::new(
            frames,
            times.to_vec(),
            Interpolation::Bicubic,
            TimeInterpolation::Linear,
            0.0,
            1.0,
            AfterLastFrame::Hold,
        )
        .unwrap();
        let p = Vec2::new(0.4, 0.7);
        for t in [0.0, 4.0, 15.0, 27.5] {
            let h = s.hessian(t, p).unwrap();
            let want = [[2.0 * b(t), 3.0 * b(t)], [3.0 * b(t), -2.0 * b(t)]];
            for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                assert!(
                    (h[i][j] - want[i][j]).abs() < 1e-9,
                    "t {t}: {h:?} vs {want:?}"
                );
            }
            let g = s.grid_at(t).unwrap();
            for (ix, iy) in [(0, 0), (3, 2), (6, 5), (2, 4)] {
                let q = g.node_m(ix, iy);
                let want = a(t) + b(t) * quad(q);
                assert!(
                    (g.at(ix, iy) - want).abs() < 1e-9,
                    "t {t} node ({ix}, {iy})"
                );
            }
        }
        // Cubic in time, in the first interval: frame -1 is frame 0 repeated; a field linear in
        // time is then still reproduced at the frames themselves.
        let frames = |k: f64| {
            Grid2::from_fn(4, 4, Vec2::new(0.0, 0.0), [1.0, 1.0], move |p| k + p.x).unwrap()
        };
        let c = GridSeries::new(
            vec![frames(0.0), frames(1.0), frames(2.0)],
            vec![0.0, 1.0, 2.0],
            Interpolation::Bilinear,
            TimeInterpolation::Cubic,
            0.0,
            1.0,
            AfterLastFrame::Hold,
        )
        .unwrap();
        let p = Vec2::new(1.5, 1.5);
        for (t, want) in [(0.0, 1.5), (1.0, 2.5), (2.0, 3.5)] {
            assert!((c.value(t, p).unwrap() - want).abs() < 1e-12, "t = {t}");
            assert!((c.grid_at(t).unwrap().at(1, 1) - (want - 0.5)).abs() < 1e-12);
        }
    }

    /// Time origin and scale map run time to field time; `End` ends the field past its last
    /// frame.
    #[test]
    fn origin_scale_and_end() {
        let times = [0.0, 3600.0, 7200.0];
        let s = GridSeries::new(
            frames(&times, |t| t / 3600.0),
            times.to_vec(),
            Interpolation::Bilinear,
            TimeInterpolation::Linear,
            1800.0,
            60.0,
            AfterLastFrame::End,
        )
        .unwrap();
        let p = Vec2::new(0.0, 0.0);
        // Run time 15 s = field time 1800 + 900 = 2700 s = 0.75 h.
        assert!((s.value(15.0, p).unwrap() - 0.75).abs() < 1e-12);
        // d/dt (run) = 60 * (1 / 3600).
        assert!((s.time_derivative(15.0, p).unwrap() - 60.0 / 3600.0).abs() < 1e-15);
        assert_eq!(s.last_frame_run_time_s(), 90.0);
        assert!(s.value(90.0, p).is_some());
        assert!(s.value(90.01, p).is_none());
        assert!(GridSeries::new(
            frames(&[0.0, 0.0], |t| t),
            vec![0.0, 0.0],
            Interpolation::Bilinear,
            TimeInterpolation::Linear,
            0.0,
            1.0,
            AfterLastFrame::Hold
        )
        .is_err());
    }
}
