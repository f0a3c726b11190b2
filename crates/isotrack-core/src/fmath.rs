//! Elementary functions for the `no_std` core. `exp`, `tanh` and `sin_cos` are those of
//! [`crate::lanes`] on every build (one set of numbers for a run stepped alone and in a batch);
//! the others are the platform's (`std`) when the `std` feature is on, the pure-Rust `libm`
//! crate otherwise: the same results to within an ulp, bit-identity within one build.

#[cfg(feature = "std")]
mod imp {
    extern crate std;
    #[inline]
    pub fn sqrt(x: f64) -> f64 {
        x.sqrt()
    }
    #[inline]
    pub fn ln(x: f64) -> f64 {
        x.ln()
    }
    #[inline]
    pub fn atan2(y: f64, x: f64) -> f64 {
        y.atan2(x)
    }
    #[inline]
    pub fn floor(x: f64) -> f64 {
        x.floor()
    }
}

#[cfg(not(feature = "std"))]
mod imp {
    #[inline]
    pub fn sqrt(x: f64) -> f64 {
        libm::sqrt(x)
    }
    #[inline]
    pub fn ln(x: f64) -> f64 {
        libm::log(x)
    }
    #[inline]
    pub fn atan2(y: f64, x: f64) -> f64 {
        libm::atan2(y, x)
    }
    #[inline]
    pub fn floor(x: f64) -> f64 {
        libm::floor(x)
    }
}

pub use imp::*;

// exp, tanh and sin_cos are the branch-free ones of `lanes` on both paths: the same numbers as
// a batched run's lanes, and faster than the platform's (no call, inlined).
pub use crate::lanes::{exp, sin_cos as sincos, tanh};

#[cfg(test)]
mod tests {
    /// Each function against values known to 15 digits, on either math path (`std` or `libm`).
    #[test]
    fn elementary_functions_by_value() {
        let close = |a: f64, b: f64| (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0);
        assert!(close(super::tanh(0.5), 0.462_117_157_260_009_8));
        assert!(close(super::exp(1.0), core::f64::consts::E));
        assert!(close(super::exp(-2.0), 0.135_335_283_236_612_7));
        assert!(close(super::sqrt(2.0), core::f64::consts::SQRT_2));
        let (s, c) = super::sincos(core::f64::consts::FRAC_PI_6);
        assert!(close(s, 0.5) && close(c, 0.866_025_403_784_438_6));
        let (s, c) = super::sincos(-2.0);
        assert!(close(s, -0.909_297_426_825_681_7) && close(c, -0.416_146_836_547_142_4));
        assert!(
            close(super::ln(core::f64::consts::E), 1.0)
                && close(super::ln(10.0), core::f64::consts::LN_10)
        );
        assert!(close(super::atan2(1.0, 1.0), core::f64::consts::FRAC_PI_4));
        assert!(close(
            super::atan2(1.0, -1.0),
            3.0 * core::f64::consts::FRAC_PI_4
        ));
        assert_eq!((super::floor(-1.5), super::floor(2.7)), (-2.0, 2.0));
    }
}
