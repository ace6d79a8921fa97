//! The explicit update: a fixed sequence of named stages per sub-step.
//!
//! 1. [`channel_fluxes`]: phase mass flow rates in every channel (A-Eqs. 10–15, upwind).
//! 2. [`boundary_fluxes`]: phase mass flow rates through the boundary links.
//! 3. [`gather_pore_rates`]: net phase mass rate into every pore and its stable sub-step.
//! 4. [`advance_and_close`]: `m += Δt Σ M_f` (A-Eqs. 24, 26), `V += dV/dt Δt` (A-Eq. 25),
//!    then the closure (A-Eq. 29) for fraction, pressure and densities.
//!
//! The stages are in [`crate::stages`]; this module holds the stepper (scratch only) that runs
//! them and its report. `implicit` is the implicit scheme of the same stepper: an
//! `impl FlowStepper` over the same stages whose factorisation (`PressureLu`) the stepper
//! keeps between steps, so the two files are one unit (split for length).

use crate::error::FlowError;
use crate::fluid::PoreFluid;
use crate::implicit::PressureLu;
use crate::network::Network;
use crate::params::FlowConfig;
pub use crate::stages::{
    ChannelFlux, GroupInflow, PoreRate, StepLimit, SubstepLimit, advance_and_close,
    boundary_fluxes, channel_fluxes, close_pores, gather_pore_rates, group_inflows,
};
use crate::state::FlowState;

/// Diagnostics of one outer step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    /// Sub-steps taken.
    pub substeps: u32,
    /// Smallest sub-step \[s\].
    pub smallest_substep: f64,
    /// Largest phase Reynolds number in any channel or link during the step.
    pub max_reynolds: f64,
    /// Liquid mass rate into the domain through each boundary group in the last sub-step
    /// [kg/s].
    pub boundary_liquid_rate: Vec<f64>,
    /// Gas mass rate into the domain through each boundary group in the last sub-step [kg/s].
    pub boundary_gas_rate: Vec<f64>,
}

/// The explicit stepper: scratch buffers only (the state is the caller's).
#[derive(Debug, Clone)]
pub struct FlowStepper {
    pub(crate) config: FlowConfig,
    pub(crate) channel: Vec<ChannelFlux>,
    pub(crate) link: Vec<ChannelFlux>,
    pub(crate) rates: Vec<PoreRate>,
    pub(crate) inflow: Vec<GroupInflow>,
    pub(crate) channel_mass: Vec<f64>,
    pub(crate) channel_liquid_mass: Vec<f64>,
    pub(crate) link_mass: Vec<f64>,
    /// The implicit step's sparse LU, kept while the matrix pattern holds.
    pub(crate) lu: PressureLu,
}

impl FlowStepper {
    /// A stepper with the given configuration.
    pub fn new(config: FlowConfig) -> Self {
        Self {
            config,
            channel: Vec::new(),
            link: Vec::new(),
            rates: Vec::new(),
            inflow: Vec::new(),
            channel_mass: Vec::new(),
            channel_liquid_mass: Vec::new(),
            link_mass: Vec::new(),
            lu: PressureLu::default(),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &FlowConfig {
        &self.config
    }

    /// The channel fluxes of the last sub-step.
    pub fn channel_fluxes(&self) -> &[ChannelFlux] {
        &self.channel
    }

    /// The boundary link fluxes of the last sub-step.
    pub fn link_fluxes(&self) -> &[ChannelFlux] {
        &self.link
    }

    /// Mass (both phases) carried through each channel during the last [`Self::step`] \[kg\],
    /// positive from the channel's first pore to its second: `Σ_sub h (ṁ_q + ṁ_p)` over the
    /// sub-steps. Divided by the outer step it is the mean mass rate a heat solver advects
    /// with, consistent with the mass the pores exchanged.
    pub fn channel_mass_transfer(&self) -> &[f64] {
        &self.channel_mass
    }

    /// The liquid part of [`Self::channel_mass_transfer`] \[kg\]: `Σ_sub h ṁ_q`, same sign
    /// convention. With it a heat solver advects each phase's heat capacity
    /// (`M_q c_q + (M − M_q) c_p`), which is what the pores' capacities changed by.
    pub fn channel_liquid_transfer(&self) -> &[f64] {
        &self.channel_liquid_mass
    }

    /// Mass (both phases) that entered the domain through each boundary link during the last
    /// [`Self::step`] \[kg\] (negative: it left).
    pub fn link_mass_transfer(&self) -> &[f64] {
        &self.link_mass
    }

    pub(crate) fn prepare(
        &mut self,
        network: &Network,
        state: &FlowState,
        fluid: &impl PoreFluid,
        dv_dt: &[f64],
    ) -> Result<(), FlowError> {
        let np = network.n_pores();
        for (what, len) in [
            ("state volume", state.volume.len()),
            ("state temperature", state.temperature.len()),
            ("state liquid_mass", state.liquid_mass.len()),
            ("state gas_mass", state.gas_mass.len()),
            ("state liquid_fraction", state.liquid_fraction.len()),
            ("state pressure", state.pressure.len()),
            ("state liquid_density", state.liquid_density.len()),
            ("state gas_density", state.gas_density.len()),
            ("state pressure_stiffness", state.pressure_stiffness.len()),
        ] {
            if len != np {
                return Err(FlowError::LengthMismatch {
                    what,
                    expected: np,
                    got: len,
                });
            }
        }
        if !dv_dt.is_empty() && dv_dt.len() != np {
            return Err(FlowError::LengthMismatch {
                what: "dv_dt",
                expected: np,
                got: dv_dt.len(),
            });
        }
        let ng = network.n_groups();
        if state.boundary_liquid_inflow.len() != ng || state.boundary_gas_inflow.len() != ng {
            return Err(FlowError::LengthMismatch {
                what: "state boundary groups",
                expected: ng,
                got: state.boundary_liquid_inflow.len(),
            });
        }
        self.channel
            .resize(network.n_channels(), ChannelFlux::default());
        self.link.resize(network.n_links(), ChannelFlux::default());
        self.rates.resize(np, PoreRate::default());
        self.inflow = group_inflows(network, fluid, state.step)?;
        Ok(())
    }

    /// Checks `dt`, sizes the buffers for `state` and clears the step's mass transfers: the
    /// start of [`Self::step`] and [`Self::implicit_step`].
    pub(crate) fn begin_step(
        &mut self,
        network: &Network,
        state: &FlowState,
        fluid: &impl PoreFluid,
        dv_dt: &[f64],
        dt: f64,
    ) -> Result<StepReport, FlowError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(FlowError::OutOfRange {
                name: "dt",
                range: "> 0 s",
                value: dt,
            });
        }
        self.prepare(network, state, fluid, dv_dt)?;
        self.channel_mass.clear();
        self.channel_mass.resize(network.n_channels(), 0.0);
        self.channel_liquid_mass.clear();
        self.channel_liquid_mass.resize(network.n_channels(), 0.0);
        self.link_mass.clear();
        self.link_mass.resize(network.n_links(), 0.0);
        let ng = network.n_groups();
        Ok(StepReport {
            substeps: 0,
            smallest_substep: f64::INFINITY,
            max_reynolds: 0.0,
            boundary_liquid_rate: vec![0.0; ng],
            boundary_gas_rate: vec![0.0; ng],
        })
    }

    /// Records an accepted sub-step of `h` moved by the stepper's channel and link fluxes:
    /// the boundary rates of `report`, the channel and link mass transfers, the state's
    /// cumulative boundary inflows (serial over the links, fixed order) and the sub-step
    /// count.
    pub(crate) fn record_substep(
        &mut self,
        network: &Network,
        state: &mut FlowState,
        report: &mut StepReport,
        h: f64,
    ) {
        report.boundary_liquid_rate.fill(0.0);
        report.boundary_gas_rate.fill(0.0);
        for (k, f) in self.link.iter().enumerate() {
            let g = network.parts().link_group[k] as usize;
            report.boundary_liquid_rate[g] += f.liquid;
            report.boundary_gas_rate[g] += f.gas;
        }
        for ((m, q), f) in self
            .channel_mass
            .iter_mut()
            .zip(&mut self.channel_liquid_mass)
            .zip(&self.channel)
        {
            *m += h * (f.liquid + f.gas);
            *q += h * f.liquid;
        }
        for (m, f) in self.link_mass.iter_mut().zip(&self.link) {
            *m += h * (f.liquid + f.gas);
        }
        for g in 0..network.n_groups() {
            state.boundary_liquid_inflow[g] += h * report.boundary_liquid_rate[g];
            state.boundary_gas_inflow[g] += h * report.boundary_gas_rate[g];
        }
        report.substeps += 1;
        report.smallest_substep = report.smallest_substep.min(h);
    }

    /// The largest stable sub-step \[s\] for the current state (stages 1–3 without update).
    pub fn stable_substep(
        &mut self,
        network: &Network,
        state: &FlowState,
        fluid: &impl PoreFluid,
    ) -> Result<SubstepLimit, FlowError> {
        self.prepare(network, state, fluid, &[])?;
        channel_fluxes(network, state, &self.config, &mut self.channel);
        boundary_fluxes(network, state, &self.config, &self.inflow, &mut self.link);
        gather_pore_rates(
            network,
            state,
            &self.config,
            &self.channel,
            &self.link,
            &mut self.rates,
            0,
        )
    }

    /// Advances `state` by the outer step `dt` \[s\], sub-cycling with the stable sub-step.
    /// `dv_dt` is `dV/dt` of every pore [m³/s] from the solid motion, constant over the outer
    /// step (empty: rigid pores).
    ///
    /// On error the state is left where the failure happened (possibly part-way through a
    /// sub-step): restore it from a saved copy before retrying with a smaller step.
    pub fn step(
        &mut self,
        network: &Network,
        state: &mut FlowState,
        fluid: &impl PoreFluid,
        dv_dt: &[f64],
        dt: f64,
    ) -> Result<StepReport, FlowError> {
        let mut report = self.begin_step(network, state, fluid, dv_dt, dt)?;
        let max_substeps = self.config.parameters().max_substeps;
        let mut remaining = dt;
        while remaining > 0.0 {
            let substep = report.substeps;
            channel_fluxes(network, state, &self.config, &mut self.channel);
            boundary_fluxes(network, state, &self.config, &self.inflow, &mut self.link);
            let limit = gather_pore_rates(
                network,
                state,
                &self.config,
                &self.channel,
                &self.link,
                &mut self.rates,
                substep,
            )?;
            if substep >= max_substeps || limit.dt.is_nan() || limit.dt <= 0.0 {
                return Err(FlowError::TooManySubsteps {
                    step: state.step,
                    substeps: substep,
                    dt_limit: limit.dt,
                    limit: limit.limit.name(),
                    pore: limit.pore,
                });
            }
            let h = if limit.dt >= remaining {
                remaining
            } else {
                remaining / (remaining / limit.dt).ceil()
            };
            report.max_reynolds = report.max_reynolds.max(limit.max_reynolds);
            self.record_substep(network, state, &mut report, h);
            advance_and_close(state, fluid, &self.rates, dv_dt, h, substep)?;
            remaining = if h >= remaining { 0.0 } else { remaining - h };
        }
        state.step += 1;
        state.time += dt;
        Ok(report)
    }
}
