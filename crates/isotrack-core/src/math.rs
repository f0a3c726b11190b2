//! Small 2-D geometry helpers (SI units: metres, radians).

use core::ops::{Add, Mul, Neg, Sub};

/// A 2-D vector or point in metres (x east, y north), or any 2-D quantity such as a gradient.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Vec2 {
    /// East component.
    pub x: f64,
    /// North component.
    pub y: f64,
}

impl Vec2 {
    /// Builds a vector from its components.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
    /// The unit vector at angle `angle_rad` counter-clockwise from +x.
    pub fn from_angle(angle_rad: f64) -> Self {
        let (s, c) = crate::fmath::sincos(angle_rad);
        Self { x: c, y: s }
    }
    /// Dot product.
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// z component of the cross product `self x o`.
    pub fn cross(self, o: Self) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Euclidean norm `sqrt(x^2 + y^2)`. (Not `hypot`: it is several times slower, and its
    /// overflow protection only matters beyond 1e154 m.)
    pub fn norm(self) -> f64 {
        crate::fmath::sqrt(self.x * self.x + self.y * self.y)
    }
    /// `self` rotated by +90 degrees (counter-clockwise).
    pub fn perp(self) -> Self {
        Self::new(-self.y, self.x)
    }
    /// Both components are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

impl Add for Vec2 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y)
    }
}
impl Sub for Vec2 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y)
    }
}
impl Mul<f64> for Vec2 {
    type Output = Self;
    fn mul(self, k: f64) -> Self {
        Self::new(self.x * k, self.y * k)
    }
}
impl Neg for Vec2 {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y)
    }
}

/// A symmetric 2x2 matrix (a Hessian), row-major `[[xx, xy], [yx, yy]]`.
pub type Mat2 = [[f64; 2]; 2];

/// Spectral norm (largest singular value) of a symmetric 2x2 matrix: the largest |eigenvalue|.
///
/// For `[[a, b], [b, c]]` the eigenvalues are `(a + c)/2 +- sqrt(((a - c)/2)^2 + b^2)`.
pub fn sym_spectral_norm(m: &Mat2) -> f64 {
    let a = m[0][0];
    let c = m[1][1];
    let b = 0.5 * (m[0][1] + m[1][0]);
    let mean = 0.5 * (a + c);
    let r = libm::hypot(0.5 * (a - c), b);
    libm::fabs(mean) + r
}

/// A planar pose: position in metres and heading (course over ground) in radians,
/// counter-clockwise from +x (east).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Pose2 {
    /// Position, metres.
    pub position: Vec2,
    /// Heading, radians counter-clockwise from +x.
    pub heading_rad: f64,
}

impl Pose2 {
    /// All components are finite.
    pub fn is_finite(&self) -> bool {
        self.position.is_finite() && self.heading_rad.is_finite()
    }
}

/// Wraps an angle to `(-pi, pi]`.
#[inline]
pub fn wrap_angle(angle_rad: f64) -> f64 {
    use core::f64::consts::{PI, TAU};
    let mut a = angle_rad - TAU * crate::lanes::round(angle_rad / TAU);
    if a <= -PI {
        a += TAU;
    } else if a > PI {
        a -= TAU;
    }
    a
}

/// Clamps `x` to `[-limit, limit]`; `None` means no limit. A NaN input stays NaN.
pub fn saturate(x: f64, limit: Option<f64>) -> f64 {
    match limit {
        Some(l) if x > l => l,
        Some(l) if x < -l => -l,
        _ => x,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use core::f64::consts::PI;

    #[test]
    fn wrap_angle_range() {
        assert_relative_eq!(wrap_angle(3.0 * PI), PI, epsilon = 1e-12);
        assert_relative_eq!(wrap_angle(-3.0 * PI), PI, epsilon = 1e-12);
        assert_relative_eq!(wrap_angle(0.5), 0.5);
        assert_relative_eq!(wrap_angle(-0.5 - 4.0 * PI), -0.5, epsilon = 1e-12);
    }

    #[test]
    fn spectral_norm_matches_eigenvalues() {
        // diag(3, -5): norm 5.
        assert_relative_eq!(sym_spectral_norm(&[[3.0, 0.0], [0.0, -5.0]]), 5.0);
        // [[2,1],[1,2]]: eigenvalues 1 and 3.
        assert_relative_eq!(sym_spectral_norm(&[[2.0, 1.0], [1.0, 2.0]]), 3.0);
    }

    #[test]
    fn saturate_limits() {
        assert_eq!(saturate(2.0, Some(1.0)), 1.0);
        assert_eq!(saturate(-2.0, Some(1.0)), -1.0);
        assert_eq!(saturate(0.3, Some(1.0)), 0.3);
        assert_eq!(saturate(5.0, None), 5.0);
    }

    /// Vec2's operations on numbers worked by hand.
    #[test]
    fn vec2_operations_by_hand() {
        let (a, b) = (Vec2::new(3.0, 4.0), Vec2::new(-2.0, 5.0));
        assert_eq!(a.dot(b), 3.0 * -2.0 + 4.0 * 5.0);
        assert_eq!(a.cross(b), 3.0 * 5.0 - 4.0 * -2.0);
        assert_eq!(b.cross(a), -23.0);
        assert_eq!(a.norm(), 5.0);
        assert_eq!(a.perp(), Vec2::new(-4.0, 3.0));
        assert_eq!(a.perp().dot(a), 0.0);
        let u = Vec2::from_angle(core::f64::consts::FRAC_PI_3);
        assert!((u.x - 0.5).abs() < 1e-15 && (u.y - 0.75f64.sqrt()).abs() < 1e-15);
        assert!(a.is_finite());
        assert!(
            !Vec2::new(f64::NAN, 0.0).is_finite() && !Vec2::new(0.0, f64::INFINITY).is_finite()
        );
    }

    /// Vector arithmetic, pose finiteness, angle wrapping and saturation at their edges.
    #[test]
    fn arithmetic_wrapping_and_saturation_edges() {
        let (a, b) = (Vec2::new(3.0, 4.0), Vec2::new(-2.0, 5.0));
        assert_eq!(a + b, Vec2::new(1.0, 9.0));
        assert_eq!(a - b, Vec2::new(5.0, -1.0));
        assert_eq!(-a, Vec2::new(-3.0, -4.0));
        assert_eq!(a * 2.0, Vec2::new(6.0, 8.0));
        let ok = Pose2 {
            position: a,
            heading_rad: 1.0,
        };
        assert!(ok.is_finite());
        assert!(!Pose2 {
            heading_rad: f64::NAN,
            ..ok
        }
        .is_finite());
        assert!(!Pose2 {
            position: Vec2::new(f64::NAN, 0.0),
            ..ok
        }
        .is_finite());
        let pi = core::f64::consts::PI;
        assert!((wrap_angle(3.0 * pi + 0.25) - (-pi + 0.25)).abs() < 1e-12);
        assert!((wrap_angle(-3.0 * pi - 0.25) - (pi - 0.25)).abs() < 1e-12);
        assert!((wrap_angle(7.0) - (7.0 - 2.0 * pi)).abs() < 1e-12);
        assert_eq!(saturate(1.0, Some(1.0)), 1.0);
        assert_eq!(saturate(-1.0, Some(1.0)), -1.0);
        assert_eq!(saturate(1.5, Some(1.0)), 1.0);
        assert_eq!(saturate(-1.5, Some(1.0)), -1.0);
        assert_eq!(saturate(-1.5, None), -1.5);
    }
}
