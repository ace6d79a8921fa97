//! Parameters of an RVE as read from a file, validated once into [`RveConfig`].

use crate::error::{RveError, check_positive, check_range};
use serde::{Deserialize, Serialize};
use thm_dem::{LinearSpring, LinearSpringParams};

/// Material and numerical parameters of an RVE (SI units), as read from a file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RveParams {
    /// Linear spring + Coulomb contact law with the optional thermally sensitive bond
    /// (B-Eqs. 35–40; `thm-dem`).
    pub contact: LinearSpringParams,
    /// Solid density ρ \[kg/m³\].
    pub density: f64,
    /// Fictitious out-of-plane thickness `z_p` \[m\] (Zhao et al. 2022 use 75 mm): the RVE
    /// volume is `V = det H · z_p` and a disk's mass `ρ π R² z_p`.
    pub thickness: f64,
    /// Linear thermal expansion coefficient β \[1/K\] (B-Eq. 37).
    pub thermal_expansion_coefficient: f64,
    /// Temperature at which the disks have their reference radii \[K\] (B-Eq. 37).
    pub reference_temperature: f64,
    /// Thermal resistance per length of a heat pipe α \[K/(W m)\] (B-Eq. 34).
    pub thermal_resistance: f64,
    /// Cundall's local non-viscous damping ∈ [0, 1) on the fluctuating motion (0 for the
    /// energy balance; consolidation sets its own).
    pub local_damping: f64,
    /// Verlet skin as a fraction of the smallest reference radius (pairs closer than
    /// `R_a + R_b + skin` are listed).
    pub verlet_skin_ratio: f64,
}

impl RveParams {
    /// The DEM parameters of B-Table 1 (`k_n = k_t = 10⁶ N/m`, μ = 0.001, ρ = 2650 kg/m³,
    /// β = 10⁻⁴ /K, conductivity set through α = 10³ K/(W m) of B-Sect. 5.3.1), the 75 mm
    /// fictitious thickness of B-Sect. 5.2.1, no damping, a reference temperature of
    /// 273.15 K (0 °C).
    pub fn paper_b_table_1() -> Self {
        Self {
            contact: LinearSpringParams {
                normal_stiffness: 1e6,
                tangential_stiffness: 1e6,
                friction_coefficient: 0.001,
                thermal_bond: None,
            },
            density: 2650.0,
            thickness: 0.075,
            thermal_expansion_coefficient: 1e-4,
            reference_temperature: 273.15,
            thermal_resistance: 1e3,
            local_damping: 0.0,
            verlet_skin_ratio: 0.2,
        }
    }

    /// Validates into a configuration.
    pub fn validate(&self) -> Result<RveConfig, RveError> {
        let law = self.contact.validate()?;
        check_positive("density", self.density)?;
        check_positive("thickness", self.thickness)?;
        check_range(
            "thermal_expansion_coefficient",
            self.thermal_expansion_coefficient,
            -1e-2,
            1e-2,
            "[-0.01, 0.01] 1/K",
        )?;
        check_positive("reference_temperature", self.reference_temperature)?;
        check_positive("thermal_resistance", self.thermal_resistance)?;
        check_range(
            "local_damping",
            self.local_damping,
            0.0,
            0.999_999,
            "[0, 1)",
        )?;
        check_range(
            "verlet_skin_ratio",
            self.verlet_skin_ratio,
            1e-3,
            1.0,
            "[0.001, 1]",
        )?;
        Ok(RveConfig { params: *self, law })
    }
}

/// Validated [`RveParams`] with the contact law built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RveConfig {
    params: RveParams,
    law: LinearSpring,
}

impl RveConfig {
    /// The validated parameters.
    #[inline]
    pub fn params(&self) -> &RveParams {
        &self.params
    }

    /// The contact law.
    #[inline]
    pub fn law(&self) -> &LinearSpring {
        &self.law
    }

    /// The same configuration with another friction coefficient (the dense/loose protocol
    /// consolidates with one μ and shears with another).
    pub fn with_friction(&self, friction_coefficient: f64) -> Result<Self, RveError> {
        let mut p = self.params;
        p.contact.friction_coefficient = friction_coefficient;
        p.validate()
    }

    /// The same configuration with another local damping.
    pub fn with_damping(&self, local_damping: f64) -> Result<Self, RveError> {
        let mut p = self.params;
        p.local_damping = local_damping;
        p.validate()
    }
}
