//! A 2 × 2 matrix of `f64` (cell matrix, velocity gradient, stress, conductivity).

use serde::{Deserialize, Serialize};
use thm_dem::{Vec2, Vec3};

/// A 2 × 2 matrix, row-major: `m.0[i][j]` is row `i`, column `j`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Mat2(pub [[f64; 2]; 2]);

impl Mat2 {
    /// The zero matrix.
    pub const ZERO: Self = Self([[0.0; 2]; 2]);
    /// The identity.
    pub const IDENTITY: Self = Self([[1.0, 0.0], [0.0, 1.0]]);

    /// A matrix from its rows.
    #[inline]
    pub const fn new(xx: f64, xy: f64, yx: f64, yy: f64) -> Self {
        Self([[xx, xy], [yx, yy]])
    }

    /// A diagonal matrix.
    #[inline]
    pub const fn diagonal(xx: f64, yy: f64) -> Self {
        Self::new(xx, 0.0, 0.0, yy)
    }

    /// The rotation by `angle` (counter-clockwise, radians).
    pub fn rotation(angle: f64) -> Self {
        let (s, c) = angle.sin_cos();
        Self::new(c, -s, s, c)
    }

    /// Entry `(i, j)`.
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> f64 {
        self.0[i][j]
    }

    /// Determinant.
    #[inline]
    pub fn det(&self) -> f64 {
        let m = &self.0;
        m[0][0] * m[1][1] - m[0][1] * m[1][0]
    }

    /// Inverse, `None` when singular or not finite.
    pub fn inverse(&self) -> Option<Self> {
        let d = self.det();
        if !(d.is_finite() && d != 0.0) {
            return None;
        }
        let m = &self.0;
        Some(Self::new(
            m[1][1] / d,
            -m[0][1] / d,
            -m[1][0] / d,
            m[0][0] / d,
        ))
    }

    /// Transpose.
    #[inline]
    pub fn transpose(&self) -> Self {
        let m = &self.0;
        Self::new(m[0][0], m[1][0], m[0][1], m[1][1])
    }

    /// Matrix product `self · o`.
    #[inline]
    pub fn mul(&self, o: &Self) -> Self {
        let (a, b) = (&self.0, &o.0);
        Self::new(
            a[0][0] * b[0][0] + a[0][1] * b[1][0],
            a[0][0] * b[0][1] + a[0][1] * b[1][1],
            a[1][0] * b[0][0] + a[1][1] * b[1][0],
            a[1][0] * b[0][1] + a[1][1] * b[1][1],
        )
    }

    /// `self + s · o`.
    #[inline]
    pub fn add_scaled(&self, o: &Self, s: f64) -> Self {
        let (a, b) = (&self.0, &o.0);
        Self::new(
            a[0][0] + s * b[0][0],
            a[0][1] + s * b[0][1],
            a[1][0] + s * b[1][0],
            a[1][1] + s * b[1][1],
        )
    }

    /// `s · self`.
    #[inline]
    pub fn scale(&self, s: f64) -> Self {
        Self::ZERO.add_scaled(self, s)
    }

    /// Trace.
    #[inline]
    pub fn trace(&self) -> f64 {
        self.0[0][0] + self.0[1][1]
    }

    /// Symmetric part `½ (M + Mᵀ)`.
    #[inline]
    pub fn symmetric(&self) -> Self {
        self.add_scaled(&self.transpose(), 1.0).scale(0.5)
    }

    /// Double contraction `M : N = M_ij N_ij`.
    #[inline]
    pub fn contract(&self, o: &Self) -> f64 {
        let (a, b) = (&self.0, &o.0);
        a[0][0] * b[0][0] + a[0][1] * b[0][1] + a[1][0] * b[1][0] + a[1][1] * b[1][1]
    }

    /// Largest absolute entry.
    pub fn max_abs(&self) -> f64 {
        self.0.iter().flatten().fold(0.0_f64, |m, v| m.max(v.abs()))
    }

    /// True when every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.0.iter().flatten().all(|v| v.is_finite())
    }

    /// `M · v` for the in-plane part of `v` (the result has `z = 0`).
    #[inline]
    pub fn apply(&self, v: Vec3) -> Vec3 {
        let m = &self.0;
        Vec3::new(
            m[0][0] * v.x + m[0][1] * v.y,
            m[1][0] * v.x + m[1][1] * v.y,
            0.0,
        )
    }

    /// `M · v` for a plane vector.
    #[inline]
    pub fn apply_vec2(&self, v: Vec2) -> Vec2 {
        let m = &self.0;
        Vec2::new(m[0][0] * v.x + m[0][1] * v.y, m[1][0] * v.x + m[1][1] * v.y)
    }

    /// The outer product `a ⊗ b` of two plane vectors.
    #[inline]
    pub fn outer_vec2(a: Vec2, b: Vec2) -> Self {
        Self::new(a.x * b.x, a.x * b.y, a.y * b.x, a.y * b.y)
    }

    /// Column `j` as an in-plane vector.
    #[inline]
    pub fn column(&self, j: usize) -> Vec3 {
        Vec3::new(self.0[0][j], self.0[1][j], 0.0)
    }

    /// Row `i` as an in-plane vector.
    #[inline]
    pub fn row(&self, i: usize) -> Vec3 {
        Vec3::new(self.0[i][0], self.0[i][1], 0.0)
    }

    /// The outer product `a ⊗ b` of the in-plane parts.
    #[inline]
    pub fn outer(a: Vec3, b: Vec3) -> Self {
        Self::new(a.x * b.x, a.x * b.y, a.y * b.x, a.y * b.y)
    }

    /// Invariants of the symmetric part in 2D: the mean `p = (σ₁ + σ₂)/2` and the largest
    /// shear `τ_max = |σ₁ − σ₂|/2`, returned as `(p, τ_max)`.
    pub fn invariants_2d(&self) -> (f64, f64) {
        let s = self.symmetric();
        let p = 0.5 * s.trace();
        let d = 0.5 * (s.0[0][0] - s.0[1][1]);
        (p, (d * d + s.0[0][1] * s.0[0][1]).sqrt())
    }

    /// Eigenvalues of the symmetric part, ascending.
    pub fn symmetric_eigenvalues(&self) -> [f64; 2] {
        let (p, t) = self.invariants_2d();
        [p - t, p + t]
    }
}
