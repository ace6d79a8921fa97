//! The periodic parallelogram cell (B-Eqs. 41–48).
//!
//! The columns of the cell matrix **H** are the two basis vectors of the cell; a point has
//! global coordinates `x = H·X` and reduced (local, oblique) coordinates `X = H⁻¹·x`
//! (B-Eq. 41). In reduced coordinates the cell is the unit square, so the base lengths `l_j`
//! of B-Eq. 44 are 1 and the period shift of an image is an integer vector
//! `P = ⌊X(p')⌋` (B-Eqs. 43–44). The cell deforms with a prescribed velocity gradient
//! `Ḣ = L·H` (B-Eq. 46), integrated by the same explicit step as the disk centres so that
//! reduced coordinates are unchanged by the affine motion.

use crate::error::RveError;
use crate::mat2::Mat2;
use serde::{Deserialize, Serialize};
use thm_dem::Vec3;

/// A periodic parallelogram cell with its inverse and its reference configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeriodicCell {
    h: Mat2,
    h_inv: Mat2,
    h_reference: Mat2,
}

/// Strain measures of the cell relative to its reference configuration (B-Eqs. 47–48).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CellStrain {
    /// `E = ½ (H' + H'ᵀ) − I` with `H' = H·H_ref⁻¹` (B-Eq. 47).
    pub tensor: Mat2,
    /// Volumetric strain `ε_v = ε_ii` (B-Eq. 48a).
    pub volumetric: f64,
    /// Deviatoric strain `ε_q = √(2/3^{n−2} ε'_ij ε'_ij)`, `n = 2` (B-Eq. 48b).
    pub deviatoric: f64,
}

impl PeriodicCell {
    /// A cell from its matrix (columns = basis vectors \[m\]); the reference configuration is the
    /// given one. Fails with [`RveError::DegenerateCell`] when `det H ≤ 0` or not finite.
    pub fn new(h: Mat2) -> Result<Self, RveError> {
        let h_inv = Self::checked_inverse(&h, "cell")?;
        Ok(Self {
            h,
            h_inv,
            h_reference: h,
        })
    }

    /// A rectangular cell `width × height` \[m\].
    pub fn rectangle(width: f64, height: f64) -> Result<Self, RveError> {
        Self::new(Mat2::diagonal(width, height))
    }

    fn checked_inverse(h: &Mat2, field: &'static str) -> Result<Mat2, RveError> {
        let determinant = h.det();
        if !(determinant.is_finite() && determinant > 0.0 && h.is_finite()) {
            return Err(RveError::DegenerateCell { field, determinant });
        }
        h.inverse()
            .ok_or(RveError::DegenerateCell { field, determinant })
    }

    /// The cell matrix **H** \[m\].
    #[inline]
    pub fn matrix(&self) -> &Mat2 {
        &self.h
    }

    /// Its inverse **H⁻¹** \[1/m\].
    #[inline]
    pub fn inverse(&self) -> &Mat2 {
        &self.h_inv
    }

    /// The reference cell matrix of the strain measure.
    #[inline]
    pub fn reference(&self) -> &Mat2 {
        &self.h_reference
    }

    /// Makes the current configuration the reference of the strain measure.
    pub fn reset_reference(&mut self) {
        self.h_reference = self.h;
    }

    /// Area `det H` \[m²\].
    #[inline]
    pub fn area(&self) -> f64 {
        self.h.det()
    }

    /// Perpendicular width of the cell across reduced axis `k` (distance between the faces
    /// `X_k = 0` and `X_k = 1`) \[m\].
    #[inline]
    pub fn width(&self, k: usize) -> f64 {
        1.0 / self.h_inv.row(k).norm()
    }

    /// Reduced coordinates `X = H⁻¹ x` (B-Eq. 41b).
    #[inline]
    pub fn to_reduced(&self, x: Vec3) -> Vec3 {
        self.h_inv.apply(x)
    }

    /// Global coordinates `x = H X` (B-Eq. 41a).
    #[inline]
    pub fn to_global(&self, reduced: Vec3) -> Vec3 {
        self.h.apply(reduced)
    }

    /// The lattice vector `H·s` of an integer image shift `s` \[m\].
    #[inline]
    pub fn lattice_vector(&self, shift: [i32; 2]) -> Vec3 {
        self.h
            .apply(Vec3::new(f64::from(shift[0]), f64::from(shift[1]), 0.0))
    }

    /// The period number `⌊X⌋` of a point per reduced axis (B-Eq. 44b with `l_j = 1`):
    /// subtracting it brings the point back into the cell (B-Eq. 43).
    #[inline]
    pub fn period_of(&self, x: Vec3) -> [i32; 2] {
        let r = self.to_reduced(x);
        [r.x.floor() as i32, r.y.floor() as i32]
    }

    /// The image shift `s` that makes `x_b + H s − x_a` the shortest periodic branch vector,
    /// in the reduced metric (exact for any pair closer than half the cell width).
    #[inline]
    pub fn nearest_image_shift(&self, x_a: Vec3, x_b: Vec3) -> [i32; 2] {
        let d = self.to_reduced(x_b - x_a);
        [-(d.x.round() as i32), -(d.y.round() as i32)]
    }

    /// Advances the cell by `Ḣ = L·H` (B-Eq. 46) over `dt` with an explicit step,
    /// `H ← H + dt L H`, the same step the affine part of the disk motion takes.
    pub fn deform(&mut self, velocity_gradient: &Mat2, dt: f64) -> Result<(), RveError> {
        let h = self.h.add_scaled(&velocity_gradient.mul(&self.h), dt);
        self.h_inv = Self::checked_inverse(&h, "cell after deformation")?;
        self.h = h;
        Ok(())
    }

    /// Sets the cell matrix (e.g. a rigid rotation in a test), keeping the reference.
    pub fn set_matrix(&mut self, h: Mat2) -> Result<(), RveError> {
        self.h_inv = Self::checked_inverse(&h, "cell")?;
        self.h = h;
        Ok(())
    }

    /// Strain of the cell relative to the reference configuration (B-Eqs. 47–48).
    pub fn strain(&self) -> CellStrain {
        // Deformation gradient with respect to the reference configuration.
        let f = match self.h_reference.inverse() {
            Some(inv) => self.h.mul(&inv),
            None => Mat2::IDENTITY,
        };
        let tensor = f.symmetric().add_scaled(&Mat2::IDENTITY, -1.0);
        let volumetric = tensor.trace();
        let dev = tensor.add_scaled(&Mat2::IDENTITY, -0.5 * volumetric);
        // n = 2: 2 / 3^{n−2} = 2.
        let deviatoric = (2.0 * dev.contract(&dev)).sqrt();
        CellStrain {
            tensor,
            volumetric,
            deviatoric,
        }
    }
}
