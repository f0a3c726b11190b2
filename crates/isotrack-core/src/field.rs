//! Scalar-field traits.
//!
//! [`ScalarField`] is all a sensor may query: the value at a point. [`FieldDerivatives`] adds the
//! gradient and Hessian; only analysis (metrics, the paper's Prop. 2 check, tests) uses them,
//! never a coordinate-free controller, which by construction receives measurements only.

use crate::math::{Mat2, Vec2};

/// A (possibly time-varying) 2-D scalar field `F(t, p)`.
pub trait ScalarField {
    /// `F(t, p)` at time `t_s` (seconds) and position `p` (metres), or `None` where the field has
    /// no value (outside its domain, a no-data cell). A vehicle reaching such a point ends its run
    /// with the outcome `left_field`.
    fn value(&self, t_s: f64, p: Vec2) -> Option<f64>;

    /// [`value`](Self::value) at `N` points `(x[i], y[i])` (metres) at once, `NaN` where the
    /// field has no value: what a batched sweep asks for every step of `N` runs. The default asks
    /// each point in turn; a field whose formula vectorises (the analytic ones) overrides it
    /// with the same arithmetic in lanes, so the answers are those of `value` bit for bit.
    #[inline]
    fn value_lanes<const N: usize>(&self, t_s: f64, x: &[f64; N], y: &[f64; N]) -> [f64; N]
    where
        Self: Sized,
    {
        let mut out = [f64::NAN; N];
        for i in 0..N {
            out[i] = self.value(t_s, Vec2::new(x[i], y[i])).unwrap_or(f64::NAN);
        }
        out
    }
}

/// Spatial derivatives of a field, for analysis and metrics only.
pub trait FieldDerivatives: ScalarField {
    /// `grad F(t, p)` (field units per metre), `None` where the field has no value.
    fn gradient(&self, t_s: f64, p: Vec2) -> Option<Vec2>;
    /// The Hessian `d2F/dp2(t, p)` (field units per square metre), `None` where the field has no
    /// value or is not twice differentiable.
    fn hessian(&self, t_s: f64, p: Vec2) -> Option<Mat2>;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `F = x + 2y` on the half-plane `x >= 0` (no value elsewhere).
    struct HalfPlane;
    impl ScalarField for HalfPlane {
        fn value(&self, _t_s: f64, p: Vec2) -> Option<f64> {
            (p.x >= 0.0).then_some(p.x + 2.0 * p.y)
        }
    }

    /// The default `value_lanes` asks each point: its value, `NaN` where there is none.
    #[test]
    fn default_value_lanes_asks_each_point() {
        let v = HalfPlane.value_lanes(0.0, &[1.0, -1.0, 3.0], &[0.5, 0.0, -2.0]);
        assert_eq!(v[0], 2.0);
        assert!(v[1].is_nan());
        assert_eq!(v[2], -1.0);
    }
}
