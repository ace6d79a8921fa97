//! Solver parameters (serde) and their validated form.

use crate::error::FlowError;
use serde::{Deserialize, Serialize};

/// Parameters of the flow solver, as read from a scenario file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlowParameters {
    /// Dynamic viscosity of the liquid `μ_q` [Pa·s] (Table 1: water 10.02e-4).
    pub liquid_viscosity: f64,
    /// Dynamic viscosity of the gas `μ_p` [Pa·s] (Table 1: air 2.0507e-5).
    pub gas_viscosity: f64,
    /// Fraction of the stability limit used as sub-step, in (0, 1].
    pub stability_safety: f64,
    /// Fraction of a phase's mass a pore may lose in one sub-step, in (0, 1).
    pub positivity_safety: f64,
    /// Largest number of sub-steps inside one outer step (≥ 1).
    pub max_substeps: u32,
}

impl Default for FlowParameters {
    /// Water and air of Table 1, 0.9 of the stability limit, at most half of a phase's mass
    /// out of a pore per sub-step, 100 000 sub-steps.
    fn default() -> Self {
        Self {
            liquid_viscosity: 10.02e-4,
            gas_viscosity: 2.0507e-5,
            stability_safety: 0.9,
            positivity_safety: 0.5,
            max_substeps: 100_000,
        }
    }
}

/// Validated [`FlowParameters`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FlowConfig {
    p: FlowParameters,
}

impl FlowConfig {
    /// Validates the parameters.
    pub fn new(p: FlowParameters) -> Result<Self, FlowError> {
        let bad = |name, range, value: f64| FlowError::OutOfRange { name, range, value };
        if !(p.liquid_viscosity.is_finite() && p.liquid_viscosity > 0.0) {
            return Err(bad("liquid_viscosity", "> 0 Pa s", p.liquid_viscosity));
        }
        if !(p.gas_viscosity.is_finite() && p.gas_viscosity > 0.0) {
            return Err(bad("gas_viscosity", "> 0 Pa s", p.gas_viscosity));
        }
        if !(p.stability_safety > 0.0 && p.stability_safety <= 1.0) {
            return Err(bad("stability_safety", "in (0, 1]", p.stability_safety));
        }
        if !(p.positivity_safety > 0.0 && p.positivity_safety < 1.0) {
            return Err(bad("positivity_safety", "in (0, 1)", p.positivity_safety));
        }
        if p.max_substeps == 0 {
            return Err(bad("max_substeps", ">= 1", 0.0));
        }
        Ok(Self { p })
    }

    /// The parameters.
    pub fn parameters(&self) -> &FlowParameters {
        &self.p
    }
    /// `μ_q` [Pa·s].
    pub fn liquid_viscosity(&self) -> f64 {
        self.p.liquid_viscosity
    }
    /// `μ_p` [Pa·s].
    pub fn gas_viscosity(&self) -> f64 {
        self.p.gas_viscosity
    }
}
