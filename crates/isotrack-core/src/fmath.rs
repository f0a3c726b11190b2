//! Elementary functions for the `no_std` core: the platform's (`std`, i.e. the system libm,
//! several times faster for `tanh`) when the `std` feature is on, the pure-Rust `libm` crate
//! otherwise. Same results to within an ulp or two; bit-identity holds within one build.

#[cfg(feature = "std")]
mod imp {
    extern crate std;
    #[inline]
    pub fn tanh(x: f64) -> f64 {
        x.tanh()
    }
    #[inline]
    pub fn exp(x: f64) -> f64 {
        x.exp()
    }
    #[inline]
    pub fn sqrt(x: f64) -> f64 {
        x.sqrt()
    }
    #[inline]
    pub fn sincos(x: f64) -> (f64, f64) {
        x.sin_cos()
    }
    #[inline]
    pub fn round(x: f64) -> f64 {
        x.round()
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
    pub fn tanh(x: f64) -> f64 {
        libm::tanh(x)
    }
    #[inline]
    pub fn exp(x: f64) -> f64 {
        libm::exp(x)
    }
    #[inline]
    pub fn sqrt(x: f64) -> f64 {
        libm::sqrt(x)
    }
    #[inline]
    pub fn sincos(x: f64) -> (f64, f64) {
        libm::sincos(x)
    }
    #[inline]
    pub fn round(x: f64) -> f64 {
        libm::round(x)
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
        assert_eq!(
            (super::round(2.5), super::round(-2.5), super::round(1.4)),
            (3.0, -3.0, 1.0)
        );
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
