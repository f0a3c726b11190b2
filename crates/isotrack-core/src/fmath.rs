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
