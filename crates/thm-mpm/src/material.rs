//! The constitutive seam and the materials shipped with the crate.
//!
//! A material point hands its velocity gradient `L`, temperature, temperature rate, current
//! stress and the time step to a [`Constitutive`] model and gets back the new stress, a heat
//! source `Q_t` (W/m³, B-Eq. 1) and a 2 × 2 conductivity tensor `k_ij` (B-Eq. 3; anisotropic
//! allowed). History lives in a per-point `PointState` owned by the caller's
//! [`crate::MpmState`], so a model may be anything from linear elasticity to a DEM RVE.

use crate::error::MpmError;
use crate::points::{Mat2, Sym2};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// What a material point hands to its material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialInput {
    /// Index of the point (for error messages).
    pub point: usize,
    /// Velocity gradient `L_ij = ∂v_i/∂x_j` at the point, row-major `[xx, xy, yx, yy]` (1/s).
    pub velocity_gradient: Mat2,
    /// Deformation gradient after this step (row-major).
    pub deformation_gradient: Mat2,
    /// Remapped (smooth) temperature after this step, B-Eq. 29.
    pub temperature: f64,
    /// Temperature rate `Ṫ = Σ_I φ_Ip T_I,t` of this step (K/s), consistent with B-Eq. 28.
    pub temperature_rate: f64,
    /// Stress at the start of the step `[σxx, σyy, σxy]` (Pa).
    pub stress: Sym2,
    /// Current mass density `m_p / V_p` (kg/m³).
    pub density: f64,
    /// Time step (s).
    pub dt: f64,
}

/// What a material returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialResponse {
    /// Stress at the end of the step `[σxx, σyy, σxy]` (Pa).
    pub stress: Sym2,
    /// Heat source `Q_t` (W/m³), e.g. friction heat of an RVE.
    pub heat_source: f64,
    /// Conductivity tensor `[kxx, kyy, kxy]` (W/(m K)), symmetric positive semi-definite.
    pub conductivity: Sym2,
}

/// A constitutive model behind the seam.
pub trait Constitutive: Sync {
    /// Per-point history (plastic strain, an RVE, ...). Owned by the caller's state.
    type PointState: Clone + Send + Sync + std::fmt::Debug + Serialize + DeserializeOwned;

    /// The history of a fresh point.
    fn initial_state(&self) -> Self::PointState;

    /// Advances one point by one step.
    fn respond(
        &self,
        state: &mut Self::PointState,
        input: &MaterialInput,
    ) -> Result<MaterialResponse, MpmError>;

    /// The modulus that sets the mechanical time-step limit B-Eq. 30 (Pa): `Δt < l_e/√(M/ρ)`.
    fn wave_modulus(&self, state: &Self::PointState) -> f64;

    /// The conductivity of a fresh point `[kxx, kyy, kxy]` (W/(m K)).
    fn initial_conductivity(&self) -> Sym2;
}

/// Parameters of [`LinearThermoElastic`] (serde form).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermoElasticParameters {
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, in (−1, 0.5).
    pub poisson_ratio: f64,
    /// Linear thermal expansion coefficient β (1/K).
    pub thermal_expansion: f64,
    /// Conductivity tensor `[kxx, kyy, kxy]` (W/(m K)).
    pub conductivity: Sym2,
}

/// Linear isotropic thermo-elasticity, B-Eqs. 50–51, plane strain, Jaumann stress rate:
///
/// ```text
/// ε̇ = sym(L) − β Ṫ I₂,   σ_{n+1} = σ_n + Δt [ λ tr(ε̇) I₂ + 2 G ε̇ + W σ_n − σ_n W ]
/// ```
///
/// with `λ = Eν/((1+ν)(1−2ν))`, `G = E/(2(1+ν))`, `W = skew(L)`. `I₂` is the in-plane unit
/// tensor (the literal reading of B-Eq. 51 in 2D; see the crate docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LinearThermoElastic {
    lambda: f64,
    shear_modulus: f64,
    thermal_expansion: f64,
    conductivity: Sym2,
}

/// Checks that a conductivity tensor is finite, symmetric positive semi-definite.
pub fn validate_conductivity(name: &str, k: Sym2) -> Result<(), MpmError> {
    if !(k.iter().all(|v| v.is_finite()) && k[0] >= 0.0 && k[1] >= 0.0) || k[0] * k[1] < k[2] * k[2]
    {
        return Err(MpmError::InvalidParameter {
            name: name.into(),
            value: k[0].min(k[1]),
            allowed: "symmetric positive semi-definite [kxx, kyy, kxy] W/(m K)",
        });
    }
    Ok(())
}

impl LinearThermoElastic {
    /// Validates the parameters.
    pub fn new(p: &ThermoElasticParameters) -> Result<Self, MpmError> {
        if !(p.youngs_modulus.is_finite() && p.youngs_modulus > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "youngs_modulus".into(),
                value: p.youngs_modulus,
                allowed: "(0, inf) Pa",
            });
        }
        if !(p.poisson_ratio > -1.0 && p.poisson_ratio < 0.5) {
            return Err(MpmError::InvalidParameter {
                name: "poisson_ratio".into(),
                value: p.poisson_ratio,
                allowed: "(-1, 0.5)",
            });
        }
        if !p.thermal_expansion.is_finite() {
            return Err(MpmError::InvalidParameter {
                name: "thermal_expansion".into(),
                value: p.thermal_expansion,
                allowed: "finite 1/K",
            });
        }
        validate_conductivity("conductivity", p.conductivity)?;
        let (e, nu) = (p.youngs_modulus, p.poisson_ratio);
        Ok(Self {
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            shear_modulus: e / (2.0 * (1.0 + nu)),
            thermal_expansion: p.thermal_expansion,
            conductivity: p.conductivity,
        })
    }

    /// Lamé's first parameter λ (Pa).
    pub fn lambda(&self) -> f64 {
        self.lambda
    }
    /// Shear modulus G (Pa).
    pub fn shear_modulus(&self) -> f64 {
        self.shear_modulus
    }
}

/// Jaumann co-rotational term `(W σ − σ W)` for `W = skew(L)`, as `[xx, yy, xy]`.
#[inline]
pub fn jaumann_spin_term(l: Mat2, s: Sym2) -> Sym2 {
    let w = 0.5 * (l[1] - l[2]); // W_xy
    [2.0 * w * s[2], -2.0 * w * s[2], w * (s[1] - s[0])]
}

impl Constitutive for LinearThermoElastic {
    type PointState = ();

    fn initial_state(&self) {}

    #[inline]
    fn respond(&self, _: &mut (), input: &MaterialInput) -> Result<MaterialResponse, MpmError> {
        let l = input.velocity_gradient;
        let th = self.thermal_expansion * input.temperature_rate;
        let exx = l[0] - th;
        let eyy = l[3] - th;
        let exy = 0.5 * (l[1] + l[2]);
        let tr = exx + eyy;
        let g2 = 2.0 * self.shear_modulus;
        let s = input.stress;
        let j = jaumann_spin_term(l, s);
        let dt = input.dt;
        Ok(MaterialResponse {
            stress: [
                s[0] + dt * (self.lambda * tr + g2 * exx + j[0]),
                s[1] + dt * (self.lambda * tr + g2 * eyy + j[1]),
                s[2] + dt * (g2 * exy + j[2]),
            ],
            heat_source: 0.0,
            conductivity: self.conductivity,
        })
    }

    fn wave_modulus(&self, _: &()) -> f64 {
        self.lambda + 2.0 * self.shear_modulus
    }

    fn initial_conductivity(&self) -> Sym2 {
        self.conductivity
    }
}

/// A material with no stiffness: zero stress, constant conductivity. Pure heat conduction in
/// a medium that flows freely, and the cheapest possible constitutive call (benchmarks).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StresslessConductor {
    conductivity: Sym2,
}

impl StresslessConductor {
    /// Validates the conductivity tensor.
    pub fn new(conductivity: Sym2) -> Result<Self, MpmError> {
        validate_conductivity("conductivity", conductivity)?;
        Ok(Self { conductivity })
    }
}

impl Constitutive for StresslessConductor {
    type PointState = ();
    fn initial_state(&self) {}
    #[inline]
    fn respond(&self, _: &mut (), _: &MaterialInput) -> Result<MaterialResponse, MpmError> {
        Ok(MaterialResponse {
            stress: [0.0; 3],
            heat_source: 0.0,
            conductivity: self.conductivity,
        })
    }
    fn wave_modulus(&self, _: &()) -> f64 {
        0.0
    }
    fn initial_conductivity(&self) -> Sym2 {
        self.conductivity
    }
}
