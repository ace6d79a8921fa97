//! The `thm-eos` closure (Peng–Robinson, A-Eqs. 16–29) as this crate's [`PoreFluid`].

use crate::error::{ClosureFailure, Phase};
use crate::fluid::{PoreFluid, PoreState};
use thm_eos::{Branch, EosError, EquationOfState, PoreClosure, TwoPhaseClosure};

/// A liquid and a gas described by `thm-eos` equations of state, closed by its two-phase
/// closure (A-Eq. 29). Paper A: `EosFluid(thm_eos::water_air_closure(Model::PrCorrected))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EosFluid<L, G>(pub TwoPhaseClosure<L, G>);

fn model_error(e: EosError) -> ClosureFailure {
    ClosureFailure::Model {
        message: e.to_string(),
    }
}

impl<L, G> PoreFluid for EosFluid<L, G>
where
    L: EquationOfState + Sync,
    G: EquationOfState + Sync,
    TwoPhaseClosure<L, G>: PoreClosure,
{
    fn close(
        &self,
        liquid_mass: f64,
        gas_mass: f64,
        volume: f64,
        temperature: f64,
    ) -> Result<PoreState, ClosureFailure> {
        let s = self
            .0
            .close(temperature, volume, liquid_mass, gas_mass)
            .map_err(model_error)?;
        Ok(PoreState {
            liquid_fraction: s.liquid_fraction,
            pressure: s.pressure,
            liquid_density: s.liquid_density,
            gas_density: s.gas_density,
        })
    }

    fn density(
        &self,
        phase: Phase,
        pressure: f64,
        temperature: f64,
    ) -> Result<f64, ClosureFailure> {
        match phase {
            Phase::Liquid => self.0.liquid.density(temperature, pressure, Branch::Liquid),
            Phase::Gas => self.0.gas.density(temperature, pressure, Branch::Gas),
        }
        .map_err(model_error)
    }

    fn bulk_modulus(
        &self,
        phase: Phase,
        density: f64,
        temperature: f64,
    ) -> Result<f64, ClosureFailure> {
        let dp_drho = match phase {
            Phase::Liquid => self.0.liquid.dp_drho(temperature, density),
            Phase::Gas => self.0.gas.dp_drho(temperature, density),
        }
        .map_err(model_error)?;
        Ok(density * dp_drho)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{FlowConfig, FlowParameters, FlowState, FlowStepper, Network, NetworkParts};
    use thm_eos::{Model, water_air_closure};

    #[test]
    fn peng_robinson_pores_conserve_both_masses_through_steps() {
        let fluid = EosFluid(water_air_closure(Model::PrCorrected));
        let n = 6;
        let net = Network::new(NetworkParts {
            n_pores: n,
            width: 8e-3,
            channel_pores: (0..n as u32 - 1).map(|i| [i, i + 1]).collect(),
            channel_length: vec![2e-3; n - 1],
            channel_aperture: vec![3e-6; n - 1],
            ..Default::default()
        })
        .unwrap();
        let pressure: Vec<f64> = (0..n).map(|i| 1e6 + 4e5 * i as f64).collect();
        let alpha: Vec<f64> = (0..n).map(|i| [1.0, 0.5, 0.0][i % 3]).collect();
        let mut state = FlowState::from_pressure(
            &net,
            vec![1e-9; n],
            vec![293.15; n],
            &pressure,
            &alpha,
            &fluid,
        )
        .unwrap();
        for (closed, set) in state.pressure.iter().zip(&pressure) {
            assert!((closed - set).abs() <= 1e-6 * set);
        }
        let (q0, g0) = (state.total_liquid_mass(), state.total_gas_mass());
        let mut stepper = FlowStepper::new(FlowConfig::new(FlowParameters::default()).unwrap());
        for _ in 0..5 {
            stepper.step(&net, &mut state, &fluid, &[], 1e-4).unwrap();
        }
        assert!((state.total_liquid_mass() - q0).abs() <= 1e-13 * q0);
        assert!((state.total_gas_mass() - g0).abs() <= 1e-13 * g0);
        // The pressures moved towards each other.
        assert!(state.pressure[n - 1] - state.pressure[0] < pressure[n - 1] - pressure[0]);
    }
}
