//! The flow state: struct-of-arrays per pore, owned by the caller.

use crate::error::{FlowError, Phase};
use crate::fluid::PoreFluid;
use crate::network::Network;
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
    /// A state from phase masses, closed with `fluid`.
    pub fn from_masses(
        network: &Network,
        volume: Vec<f64>,
        temperature: Vec<f64>,
        liquid_mass: Vec<f64>,
        gas_mass: Vec<f64>,
        fluid: &impl PoreFluid,
    ) -> Result<Self, FlowError> {
        let n = network.n_pores();
        for (what, v) in [
            ("volume", &volume),
            ("temperature", &temperature),
            ("liquid_mass", &liquid_mass),
            ("gas_mass", &gas_mass),
        ] {
            if v.len() != n {
                return Err(FlowError::LengthMismatch {
                    what,
                    expected: n,
                    got: v.len(),
                });
            }
        }
        for (p, &v) in volume.iter().enumerate() {
            if !(v.is_finite() && v > 0.0) {
                return Err(FlowError::NonPositiveVolume {
                    pore: p,
                    value: v,
                    step: 0,
                    substep: 0,
                });
            }
        }
        let ng = network.n_groups();
        let mut s = Self {
            step: 0,
            time: 0.0,
            volume,
            temperature,
            liquid_mass,
            gas_mass,
            liquid_fraction: vec![0.0; n],
            pressure: vec![0.0; n],
            liquid_density: vec![0.0; n],
            gas_density: vec![0.0; n],
            pressure_stiffness: vec![0.0; n],
            boundary_liquid_inflow: vec![0.0; ng],
            boundary_gas_inflow: vec![0.0; ng],
        };
        crate::stepper::close_pores(&mut s, fluid, 0)?;
        Ok(s)
    }

    /// A state from pressure and liquid fraction per pore: the masses are
    /// `α_q ρ_q(P, T) V` and `(1 − α_q) ρ_p(P, T) V`, then closed with `fluid`.
    pub fn from_pressure(
        network: &Network,
        volume: Vec<f64>,
        temperature: Vec<f64>,
        pressure: &[f64],
        liquid_fraction: &[f64],
        fluid: &impl PoreFluid,
    ) -> Result<Self, FlowError> {
        let n = network.n_pores();
        for (what, len) in [
            ("pressure", pressure.len()),
            ("liquid_fraction", liquid_fraction.len()),
            ("volume", volume.len()),
            ("temperature", temperature.len()),
        ] {
            if len != n {
                return Err(FlowError::LengthMismatch {
                    what,
                    expected: n,
                    got: len,
                });
            }
        }
        let mut mq = vec![0.0; n];
        let mut mp = vec![0.0; n];
        for p in 0..n {
            let a = liquid_fraction[p];
            if !(0.0..=1.0).contains(&a) {
                return Err(FlowError::OutOfRange {
                    name: "liquid_fraction",
                    range: "in [0, 1]",
                    value: a,
                });
            }
            let closure = |cause| FlowError::Closure {
                pore: p,
                step: 0,
                substep: 0,
                cause,
            };
            let rq = fluid
                .density(Phase::Liquid, pressure[p], temperature[p])
                .map_err(closure)?;
            let rp = fluid
                .density(Phase::Gas, pressure[p], temperature[p])
                .map_err(closure)?;
            mq[p] = a * rq * volume[p];
            mp[p] = (1.0 - a) * rp * volume[p];
        }
        Self::from_masses(network, volume, temperature, mq, mp, fluid)
    }

    /// Recomputes fraction, pressure and densities of every pore from its masses, volume and
    /// temperature (A-Eq. 29). Call after changing masses or volumes outside the stepper
    /// (e.g. after a remap); the stepper keeps the state closed itself.
    pub fn close(&mut self, fluid: &impl PoreFluid) -> Result<(), FlowError> {
        crate::stepper::close_pores(self, fluid, 0)
    }

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
