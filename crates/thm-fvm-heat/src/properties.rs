//! Effective mixture properties (A-Eqs. 32–36) and the fluid–solid heat transfer coefficient
//! from Nusselt correlations (A-Eqs. 43–45).

use crate::params::{HeatModel, Phase};

/// Effective properties of the homogenised two-phase fluid in one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MixtureProperties {
    /// ρ_eff = α_q ρ_q + α_p ρ_p (A-Eq. 32) [kg/m³].
    pub density: f64,
    /// Volumetric heat capacity Σ α_k ρ_k c_p,k [J/(m³ K)].
    pub volumetric_heat_capacity: f64,
    /// Mass-weighted specific heat c_p,eff = Σ α_k ρ_k c_p,k / ρ_eff [J/(kg K)] (our reading
    /// of A-Eq. 36; see the crate docs).
    pub specific_heat: f64,
    /// λ_eff = Σ α_k λ_k (A-Eq. 34) [W/(m K)].
    pub conductivity: f64,
    /// μ_eff = Σ α_k μ_k (A-Eq. 35) [Pa s].
    pub dynamic_viscosity: f64,
}

/// Mixture properties from the liquid fraction and the phase densities.
pub fn mixture(
    liquid: &Phase,
    gas: &Phase,
    liquid_fraction: f64,
    liquid_density: f64,
    gas_density: f64,
) -> MixtureProperties {
    let (aq, ap) = (liquid_fraction, 1.0 - liquid_fraction);
    let density = aq * liquid_density + ap * gas_density;
    let rho_c = aq * liquid_density * liquid.specific_heat + ap * gas_density * gas.specific_heat;
    MixtureProperties {
        density,
        volumetric_heat_capacity: rho_c,
        specific_heat: if density > 0.0 { rho_c / density } else { 0.0 },
        conductivity: aq * liquid.conductivity + ap * gas.conductivity,
        dynamic_viscosity: aq * liquid.dynamic_viscosity + ap * gas.dynamic_viscosity,
    }
}

/// Reynolds number above which A-Eq. 44 (Wakao & Kaguei) replaces A-Eq. 43 (Tavassoli et al.).
pub const REYNOLDS_SWITCH: f64 = 100.0;

/// Nusselt number of the fluid–particle exchange: A-Eq. 43 for Re ≤ 100, A-Eq. 44 above.
pub fn nusselt(porosity: f64, reynolds: f64, prandtl: f64) -> f64 {
    let (e, re) = (porosity, reynolds.max(0.0));
    let pr3 = prandtl.max(0.0).cbrt();
    if re <= REYNOLDS_SWITCH {
        (7.0 - 10.0 * e + 5.0 * e * e) * (1.0 + 0.1 * re.powf(0.2) * pr3)
            + (1.33 - 2.19 * e + 1.15 * e * e) * re.powf(0.7) * pr3
    } else {
        2.0 + 1.1 * re.powf(0.6) * pr3
    }
}

/// Fluid-side heat transfer coefficient h_f = Nu λ_eff / (2 r) (A-Eq. 45) [W/(m² K)], with
/// Re = ρ_eff v (2 r) / μ_eff and Pr = c_p,eff μ_eff / λ_eff.
pub fn interface_coefficient(
    mix: &MixtureProperties,
    porosity: f64,
    speed: f64,
    sphere_radius: f64,
) -> f64 {
    if mix.conductivity <= 0.0 || sphere_radius <= 0.0 {
        return 0.0;
    }
    let d = 2.0 * sphere_radius;
    let re = mix.density * speed * d / mix.dynamic_viscosity;
    let pr = mix.specific_heat * mix.dynamic_viscosity / mix.conductivity;
    nusselt(porosity, re, pr) * mix.conductivity / d
}

impl HeatModel {
    /// Mixture properties of a fluid cell.
    pub fn fluid_mixture(
        &self,
        liquid_fraction: f64,
        liquid_density: f64,
        gas_density: f64,
    ) -> MixtureProperties {
        mixture(
            &self.liquid,
            &self.gas,
            liquid_fraction,
            liquid_density,
            gas_density,
        )
    }
}
