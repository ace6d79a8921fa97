//! The flow state: struct-of-arrays per pore, owned by the caller. Its constructors, which
//! close every pore, are with the closure stage in [`crate::stages`].

use serde::{Deserialize, Serialize};

/// The state of every pore (arrays indexed by pore) and the boundary mass counters.
///
/// The phase masses are the conserved unknowns; fraction, pressure and densities are their
/// closure (A-Eq. 29) and are kept consistent by the stepper.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlowState {
    /// Outer steps taken.
    pub step: u64,
    /// Simulated time \[s\].
    pub time: f64,
    /// Pore volumes `V` \[m³\].
    pub volume: Vec<f64>,
    /// Pore temperatures \[K\] (input from the heat solver).
    pub temperature: Vec<f64>,
    /// Liquid mass `α_q ρ_q V` \[kg\].
    pub liquid_mass: Vec<f64>,
    /// Gas mass `α_p ρ_p V` \[kg\].
    pub gas_mass: Vec<f64>,
    /// Liquid fraction `α_q` [-].
    pub liquid_fraction: Vec<f64>,
    /// Common pressure \[Pa\].
    pub pressure: Vec<f64>,
    /// Liquid density [kg/m³].
    pub liquid_density: Vec<f64>,
    /// Gas density [kg/m³].
    pub gas_density: Vec<f64>,
    /// Pressure stiffness `K/V` of each pore's mixture [Pa/m³] (`1/K = α_q/K_q + α_p/K_p`,
    /// `K_k = ρ_k ∂P/∂ρ_k`): the pressure rise per unit volume of fluid added. Part of the
    /// closure; sets the stable sub-step.
    pub pressure_stiffness: Vec<f64>,
    /// Liquid mass that entered through each boundary group since the start \[kg\].
    pub boundary_liquid_inflow: Vec<f64>,
    /// Gas mass that entered through each boundary group since the start \[kg\].
    pub boundary_gas_inflow: Vec<f64>,
}

impl FlowState {
    /// Number of pores.
    pub fn n_pores(&self) -> usize {
        self.volume.len()
    }

    /// Total liquid mass in the pores \[kg\] (summed in pore order).
    pub fn total_liquid_mass(&self) -> f64 {
        self.liquid_mass.iter().sum()
    }

    /// Total gas mass in the pores \[kg\] (summed in pore order).
    pub fn total_gas_mass(&self) -> f64 {
        self.gas_mass.iter().sum()
    }
}
