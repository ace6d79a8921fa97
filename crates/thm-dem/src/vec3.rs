//! A small 3-vector of `f64` (positions, velocities, forces, torques).
//!
//! Disks and plane-constrained spheres use the same type with `z = 0` (and angular quantities
//! along `z` only), so every contact law has one implementation for both.

use serde::{Deserialize, Serialize};
use std::ops::{Add, AddAssign, Div, Mul, Neg, Sub, SubAssign};

/// A vector in ℝ³ (SI units of whatever it holds).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Vec3 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0);

    /// A vector from its components.
    #[inline]
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }

    /// Dot product.
    #[inline]
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product `self × o`.
    #[inline]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Squared Euclidean norm.
    #[inline]
    pub fn norm_squared(self) -> f64 {
        self.dot(self)
    }

    /// Euclidean norm.
    #[inline]
    pub fn norm(self) -> f64 {
        self.norm_squared().sqrt()
    }

    /// Largest absolute component.
    #[inline]
    pub fn max_abs(self) -> f64 {
        self.x.abs().max(self.y.abs()).max(self.z.abs())
    }

    /// True when all components are finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Component `k` (0 = x, 1 = y, otherwise z).
    #[inline]
    pub fn component(self, k: usize) -> f64 {
        match k {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }

    /// Applies `f` to each component.
    #[inline]
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Self::new(f(self.x), f(self.y), f(self.z))
    }

    /// Component-wise product.
    #[inline]
    pub fn component_mul(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}

impl Add for Vec3 {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vec3 {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Neg for Vec3 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl Mul<f64> for Vec3 {
    type Output = Self;
    #[inline]
    fn mul(self, s: f64) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Mul<Vec3> for f64 {
    type Output = Vec3;
    #[inline]
    fn mul(self, v: Vec3) -> Vec3 {
        v * self
    }
}

impl Div<f64> for Vec3 {
    type Output = Self;
    #[inline]
    fn div(self, s: f64) -> Self {
        Self::new(self.x / s, self.y / s, self.z / s)
    }
}

impl AddAssign for Vec3 {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl SubAssign for Vec3 {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

/// Rotates `v` by the smallest rotation that carries the unit vector `from` onto the unit
/// vector `to` (Rodrigues' formula without trigonometric calls):
/// `v' = c v + k × v + k (k·v) / (1 + c)`, `k = from × to`, `c = from · to`.
///
/// Exact for any angle below π; for antiparallel `from`/`to` (c ≤ −1 + 1e-12, a contact
/// normal cannot flip in one step) `v` is returned unchanged.
#[inline]
pub fn rotate_minimal(v: Vec3, from: Vec3, to: Vec3) -> Vec3 {
    let c = from.dot(to);
    if c <= -1.0 + 1e-12 {
        return v;
    }
    let k = from.cross(to);
    v * c + k.cross(v) + k * (k.dot(v) / (1.0 + c))
}

/// Rotates `v` about the unit `axis` by `angle` (radians, right-handed).
#[inline]
pub fn rotate_about(v: Vec3, axis: Vec3, angle: f64) -> Vec3 {
    if angle == 0.0 {
        return v;
    }
    let (s, c) = sin_cos(angle);
    v * c + axis.cross(v) * s + axis * (axis.dot(v) * (1.0 - c))
}

/// `(sin, cos)` of an angle. Contact frames turn by far less than a milliradian per step:
/// there the Taylor series (truncation below 1e-17 relative) replaces the costlier `sin_cos`.
#[inline]
pub(crate) fn sin_cos(angle: f64) -> (f64, f64) {
    let a2 = angle * angle;
    if angle.abs() < 1e-3 {
        (
            angle * (1.0 - a2 / 6.0 * (1.0 - a2 / 20.0)),
            1.0 - a2 / 2.0 * (1.0 - a2 / 12.0),
        )
    } else {
        angle.sin_cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimal_rotation_maps_from_onto_to_and_keeps_length() {
        let from = Vec3::new(1.0, 0.0, 0.0);
        let a = 0.7_f64;
        let to = Vec3::new(a.cos(), a.sin(), 0.0);
        let r = rotate_minimal(from, from, to);
        assert!((r - to).norm() < 1e-15);
        let v = Vec3::new(0.0, 1.0, 0.3);
        let w = rotate_minimal(v, from, to);
        assert!((w.norm() - v.norm()).abs() < 1e-15);
        // The in-plane part rotates by the same angle, the axis component stays.
        assert!((w.z - 0.3).abs() < 1e-15);
        assert!((w.x + a.sin()).abs() < 1e-15 && (w.y - a.cos()).abs() < 1e-15);
    }

    #[test]
    fn small_angle_series_matches_sin_cos() {
        let axis = Vec3::new(0.0, 0.0, 1.0);
        let v = Vec3::new(1.0, 0.5, 0.2);
        for angle in [1e-9, -3e-6, 2e-4, -9.99e-4] {
            let (s, c) = f64::sin_cos(angle);
            let exact = v * c + axis.cross(v) * s + axis * (axis.dot(v) * (1.0 - c));
            assert!((rotate_about(v, axis, angle) - exact).norm() <= 1e-16);
        }
    }

    #[test]
    fn rotation_about_axis_is_right_handed() {
        let v = Vec3::new(1.0, 0.0, 0.0);
        let w = rotate_about(v, Vec3::new(0.0, 0.0, 1.0), std::f64::consts::FRAC_PI_2);
        assert!((w - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-15);
    }
}
