//! The explicit update: a fixed sequence of named stages per sub-step.
//!
//! 1. [`channel_fluxes`]: phase mass flow rates in every channel (A-Eqs. 10–15, upwind).
//! 2. [`boundary_fluxes`]: phase mass flow rates through the boundary links.
//! 3. [`gather_pore_rates`]: net phase mass rate into every pore and its stable sub-step.
//! 4. [`advance_and_close`]: `m += Δt Σ M_f` (A-Eqs. 24, 26), `V += dV/dt Δt` (A-Eq. 25),
//!    then the closure (A-Eq. 29) for fraction, pressure and densities.

use crate::channel::two_layer_conductances;
use crate::error::{FlowError, Phase};
use crate::fluid::PoreFluid;
use crate::implicit::PressureLu;
use crate::network::{BoundaryCondition, Network, SECOND_END};
use crate::params::FlowConfig;
use crate::state::FlowState;
use rayon::prelude::*;

/// Pores or channels per parallel work item.
const CHUNK: usize = 2048;

/// The flow in one channel or boundary link during a sub-step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChannelFlux {
    /// Liquid mass flow rate [kg/s]; channels: positive from the first pore to the second;
    /// boundary links: positive into the domain.
    pub liquid: f64,
    /// Gas mass flow rate [kg/s], same sign convention.
    pub gas: f64,
    /// Bound on the total volumetric conductance `Q/ΔP` [m³/(Pa·s)] for either flow
    /// direction (used by the stable step).
    pub conductance: f64,
    /// Largest phase Reynolds number `ρ_k |Q_k| / μ_k` (Q per unit width).
    pub reynolds: f64,
}

/// Net rates of one pore during a sub-step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PoreRate {
    /// Net liquid mass rate into the pore [kg/s].
    pub liquid: f64,
    /// Net gas mass rate into the pore [kg/s].
    pub gas: f64,
}

/// What limits a sub-step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepLimit {
    /// The explicit stability bound (compressibility × conductance).
    Stability,
    /// A pore would lose too large a share of its liquid.
    LiquidPositivity,
    /// A pore would lose too large a share of its gas.
    GasPositivity,
}

impl StepLimit {
    fn name(self) -> &'static str {
        match self {
            StepLimit::Stability => "stability",
            StepLimit::LiquidPositivity => "liquid positivity",
            StepLimit::GasPositivity => "gas positivity",
        }
    }
}

/// The sub-step limit and the pore that sets it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubstepLimit {
    /// Largest phase Reynolds number of the channels and links (a diagnostic gathered in the
    /// same pass).
    pub max_reynolds: f64,
    /// Largest admissible sub-step \[s\] (infinite when nothing flows).
    pub dt: f64,
    /// What sets it.
    pub limit: StepLimit,
    /// The pore that sets it.
    pub pore: usize,
}

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

/// Stage 1: the phase mass flow rates of every channel.
///
/// The interface position and the transported densities come from the upwind pore (the one
/// at the higher pressure): liquid layer thickness `α_q,up h`, mass rates `ρ_k,up Q_k w`.
pub fn channel_fluxes(
    network: &Network,
    state: &FlowState,
    config: &FlowConfig,
    out: &mut [ChannelFlux],
) {
    let parts = network.parts();
    let w = network.width();
    let (mq, mp) = (config.liquid_viscosity(), config.gas_viscosity());
    out.par_iter_mut()
        .with_min_len(CHUNK)
        .enumerate()
        .for_each(|(c, o)| {
            let [i, j] = parts.channel_pores[c];
            let (i, j) = (i as usize, j as usize);
            let inv_len = 1.0 / parts.channel_length[c];
            let g = (state.pressure[i] - state.pressure[j]) * inv_len;
            let up = if g >= 0.0 { i } else { j };
            let alpha_min = state.liquid_fraction[i].min(state.liquid_fraction[j]);
            *o = pipe_flux(
                parts.channel_aperture[c],
                g,
                inv_len,
                w,
                state.liquid_fraction[up],
                alpha_min,
                state.liquid_density[up],
                state.gas_density[up],
                mq,
                mp,
            );
        });
}

/// Flux of one channel or link from its upwind state (`alpha_up`, `rho_q`, `rho_p`).
/// `alpha_other` is the liquid fraction of the other end: the conductance bound is the larger
/// of the total conductances at the two ends' fractions, so it holds whichever way the flow
/// turns during the sub-step (the conductance is monotone in `α_q`, `μ_q ≥ μ_p` not assumed).
#[allow(clippy::too_many_arguments)]
#[inline]
fn pipe_flux(
    h: f64,
    g: f64,
    inv_len: f64,
    w: f64,
    alpha_up: f64,
    alpha_other: f64,
    rho_q: f64,
    rho_p: f64,
    mq: f64,
    mp: f64,
) -> ChannelFlux {
    let (cq, cp) = two_layer_conductances(h, alpha_up, mq, mp);
    let (qq, qp) = (cq * g, cp * g);
    let c_up = cq + cp;
    let c_other = if alpha_other == alpha_up {
        c_up
    } else {
        let (oq, op) = two_layer_conductances(h, alpha_other, mq, mp);
        oq + op
    };
    ChannelFlux {
        liquid: rho_q * qq * w,
        gas: rho_p * qp * w,
        conductance: c_up.max(c_other) * w * inv_len,
        reynolds: (rho_q * qq.abs() / mq).max(rho_p * qp.abs() / mp),
    }
}

/// Per-group data of the boundary conditions for one outer step: the densities of the
/// fluid entering through prescribed-pressure groups (zero for other groups).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GroupInflow {
    /// Liquid density at the reservoir pressure and temperature [kg/m³].
    pub liquid_density: f64,
    /// Gas density at the reservoir pressure and temperature [kg/m³].
    pub gas_density: f64,
}

/// The densities of the fluid entering through each boundary group (see [`GroupInflow`]).
/// A failure of the fluid model names the group in the `pore` field.
pub fn group_inflows(
    network: &Network,
    fluid: &impl PoreFluid,
    step: u64,
) -> Result<Vec<GroupInflow>, FlowError> {
    let mut out = Vec::with_capacity(network.n_groups());
    for (g, bc) in network.parts().boundaries.iter().enumerate() {
        let mut gi = GroupInflow::default();
        if let BoundaryCondition::Pressure {
            pressure,
            temperature,
            ..
        } = *bc
        {
            let err = |cause| FlowError::Closure {
                pore: g,
                step,
                substep: 0,
                cause,
            };
            gi.liquid_density = fluid
                .density(Phase::Liquid, pressure, temperature)
                .map_err(err)?;
            gi.gas_density = fluid
                .density(Phase::Gas, pressure, temperature)
                .map_err(err)?;
        }
        out.push(gi);
    }
    Ok(out)
}

/// Stage 2: the phase mass flow rates through the boundary links (positive into the
/// domain). Prescribed pressure: a half-channel to the reservoir, upwind as in the channels
/// with the reservoir's composition and densities when fluid enters. Prescribed mass rate:
/// the group's rate times the link's share of the group's face length.
pub fn boundary_fluxes(
    network: &Network,
    state: &FlowState,
    config: &FlowConfig,
    inflow: &[GroupInflow],
    out: &mut [ChannelFlux],
) {
    let parts = network.parts();
    let w = network.width();
    let (mq, mp) = (config.liquid_viscosity(), config.gas_viscosity());
    let group_len = network.group_face_length();
    for (k, o) in out.iter_mut().enumerate() {
        let p = parts.link_pore[k] as usize;
        let g = parts.link_group[k] as usize;
        *o = match parts.boundaries[g] {
            BoundaryCondition::Pressure {
                pressure,
                entering_liquid_fraction,
                ..
            } => {
                let inv_len = 1.0 / parts.link_length[k];
                let grad = (pressure - state.pressure[p]) * inv_len;
                let (alpha_up, alpha_other, rq, rp) = if grad >= 0.0 {
                    (
                        entering_liquid_fraction,
                        state.liquid_fraction[p],
                        inflow[g].liquid_density,
                        inflow[g].gas_density,
                    )
                } else {
                    (
                        state.liquid_fraction[p],
                        entering_liquid_fraction,
                        state.liquid_density[p],
                        state.gas_density[p],
                    )
                };
                pipe_flux(
                    parts.link_aperture[k],
                    grad,
                    inv_len,
                    w,
                    alpha_up,
                    alpha_other,
                    rq,
                    rp,
                    mq,
                    mp,
                )
            }
            BoundaryCondition::MassRate {
                liquid_mass_rate,
                gas_mass_rate,
            } => {
                let share = parts.link_face_length[k] / group_len[g];
                ChannelFlux {
                    liquid: liquid_mass_rate * share,
                    gas: gas_mass_rate * share,
                    conductance: 0.0,
                    reynolds: 0.0,
                }
            }
            BoundaryCondition::Impermeable => ChannelFlux::default(),
        };
    }
}

/// Stage 3: net phase mass rates into each pore (a gather over the pore's channels and links
/// in a fixed order, so the result does not depend on the thread count) and the sub-step
/// limit: `Δt ≤ s / max_i (K_i/V_i Σ C)` (the Gershgorin bound of the linearised pressure
/// equation, with `K_i` the mixture bulk modulus) and `Δt ≤ s₊ m_k,i / (−ṁ_k,i)` for each
/// phase losing mass.
#[allow(clippy::too_many_arguments)]
pub fn gather_pore_rates(
    network: &Network,
    state: &FlowState,
    config: &FlowConfig,
    channel: &[ChannelFlux],
    link: &[ChannelFlux],
    out: &mut [PoreRate],
    substep: u32,
) -> Result<SubstepLimit, FlowError> {
    let s_stab = config.parameters().stability_safety;
    let s_pos = config.parameters().positivity_safety;
    let none = SubstepLimit {
        dt: f64::INFINITY,
        limit: StepLimit::Stability,
        pore: usize::MAX,
        max_reynolds: 0.0,
    };
    // Across chunks: the smaller limit (ties: the smaller pore index) and the larger Reynolds
    // number, both order-independent, so the reduction is deterministic.
    let better = |a: SubstepLimit, b: SubstepLimit| {
        let max_reynolds = a.max_reynolds.max(b.max_reynolds);
        let mut m = if b.dt < a.dt || (b.dt == a.dt && b.pore < a.pore) {
            b
        } else {
            a
        };
        m.max_reynolds = max_reynolds;
        m
    };
    out.par_chunks_mut(CHUNK)
        .enumerate()
        .map(
            |(chunk, rates)| -> Result<SubstepLimit, (usize, FlowError)> {
                let mut best = none;
                for (k, r) in rates.iter_mut().enumerate() {
                    let p = chunk * CHUNK + k;
                    let (mut lq, mut lp, mut cond) = (0.0, 0.0, 0.0);
                    let mut re = best.max_reynolds;
                    for &entry in network.pore_channels(p) {
                        let f = &channel[(entry & !SECOND_END) as usize];
                        if entry & SECOND_END != 0 {
                            lq += f.liquid;
                            lp += f.gas;
                        } else {
                            lq -= f.liquid;
                            lp -= f.gas;
                        }
                        cond += f.conductance;
                        re = re.max(f.reynolds);
                    }
                    for &l in network.pore_links(p) {
                        let f = &link[l as usize];
                        lq += f.liquid;
                        lp += f.gas;
                        cond += f.conductance;
                        re = re.max(f.reynolds);
                    }
                    best.max_reynolds = re;
                    for (quantity, v) in [("liquid mass rate", lq), ("gas mass rate", lp)] {
                        if !v.is_finite() {
                            return Err((
                                p,
                                FlowError::NonFinite {
                                    quantity,
                                    place: "pore",
                                    index: p,
                                    value: v,
                                    step: state.step,
                                    substep,
                                },
                            ));
                        }
                    }
                    *r = PoreRate {
                        liquid: lq,
                        gas: lp,
                    };
                    // Candidates in a fixed order; a strict `<` keeps the first (and, across
                    // pores of the chunk, the smallest) index on ties.
                    let a = state.pressure_stiffness[p] * cond;
                    if a > 0.0 && s_stab / a < best.dt {
                        best.dt = s_stab / a;
                        best.limit = StepLimit::Stability;
                        best.pore = p;
                    }
                    if lq < 0.0 {
                        let dt = s_pos * state.liquid_mass[p] / -lq;
                        if dt < best.dt {
                            best.dt = dt;
                            best.limit = StepLimit::LiquidPositivity;
                            best.pore = p;
                        }
                    }
                    if lp < 0.0 {
                        let dt = s_pos * state.gas_mass[p] / -lp;
                        if dt < best.dt {
                            best.dt = dt;
                            best.limit = StepLimit::GasPositivity;
                            best.pore = p;
                        }
                    }
                }
                Ok(best)
            },
        )
        .reduce(
            || Ok(none),
            |a, b| match (a, b) {
                (Ok(x), Ok(y)) => Ok(better(x, y)),
                (Err(e), Ok(_)) | (Ok(_), Err(e)) => Err(e),
                (Err(x), Err(y)) => Err(if x.0 <= y.0 { x } else { y }),
            },
        )
        .map_err(|(_, e)| e)
}

/// Stage 4: advances the phase masses and volumes of every pore by `dt` and closes them.
/// `dv_dt` is `dV/dt` per pore [m³/s] (empty: rigid pores). Also updates the pressure
/// stiffness `K/V` of each pore's mixture (`1/K = α_q/K_q + α_p/K_p`).
#[allow(clippy::too_many_arguments)]
pub fn advance_and_close(
    state: &mut FlowState,
    fluid: &impl PoreFluid,
    rates: &[PoreRate],
    dv_dt: &[f64],
    dt: f64,
    substep: u32,
) -> Result<(), FlowError> {
    let step = state.step;
    let FlowState {
        volume,
        temperature,
        liquid_mass,
        gas_mass,
        liquid_fraction,
        pressure,
        liquid_density,
        gas_density,
        pressure_stiffness,
        ..
    } = state;
    let result = (
        liquid_mass.par_chunks_mut(CHUNK),
        gas_mass.par_chunks_mut(CHUNK),
        volume.par_chunks_mut(CHUNK),
        liquid_fraction.par_chunks_mut(CHUNK),
        pressure.par_chunks_mut(CHUNK),
        liquid_density.par_chunks_mut(CHUNK),
        gas_density.par_chunks_mut(CHUNK),
        pressure_stiffness.par_chunks_mut(CHUNK),
    )
        .into_par_iter()
        .enumerate()
        .filter_map(|(chunk, (mq, mp, v, a, p, rq, rp, st))| {
            let base = chunk * CHUNK;
            for k in 0..mq.len() {
                let i = base + k;
                let r = rates.get(i).copied().unwrap_or_default();
                mq[k] += dt * r.liquid;
                mp[k] += dt * r.gas;
                if let Some(&dvdt) = dv_dt.get(i) {
                    v[k] += dvdt * dt;
                }
                if !(v[k].is_finite() && v[k] > 0.0) {
                    return Some((
                        i,
                        FlowError::NonPositiveVolume {
                            pore: i,
                            value: v[k],
                            step,
                            substep,
                        },
                    ));
                }
                let t = temperature[i];
                let closed = fluid
                    .close(mq[k], mp[k], v[k], t)
                    .and_then(|s| Ok((s, mixture_stiffness(fluid, &s, t, v[k])?)));
                match closed {
                    Ok((s, stiffness)) => {
                        a[k] = s.liquid_fraction;
                        p[k] = s.pressure;
                        rq[k] = s.liquid_density;
                        rp[k] = s.gas_density;
                        st[k] = stiffness;
                    }
                    Err(cause) => {
                        return Some((
                            i,
                            FlowError::Closure {
                                pore: i,
                                step,
                                substep,
                                cause,
                            },
                        ));
                    }
                }
                for (quantity, value, ok) in [
                    ("pressure", p[k], p[k].is_finite()),
                    (
                        "pressure stiffness",
                        st[k],
                        st[k].is_finite() && st[k] > 0.0,
                    ),
                ] {
                    if !ok {
                        return Some((
                            i,
                            FlowError::NonFinite {
                                quantity,
                                place: "pore",
                                index: i,
                                value,
                                step,
                                substep,
                            },
                        ));
                    }
                }
            }
            None
        })
        .min_by_key(|(i, _)| *i);
    match result {
        Some((_, e)) => Err(e),
        None => Ok(()),
    }
}

/// `K/V` of a pore's mixture, `1/K = α_q/K_q + α_p/K_p`.
fn mixture_stiffness(
    fluid: &impl PoreFluid,
    s: &crate::fluid::PoreState,
    temperature: f64,
    volume: f64,
) -> Result<f64, crate::error::ClosureFailure> {
    let a = s.liquid_fraction;
    let mut compliance = 0.0;
    if a > 0.0 {
        compliance += a / fluid.bulk_modulus(Phase::Liquid, s.liquid_density, temperature)?;
    }
    if a < 1.0 {
        compliance += (1.0 - a) / fluid.bulk_modulus(Phase::Gas, s.gas_density, temperature)?;
    }
    Ok(1.0 / (compliance * volume))
}

/// Closes every pore of `state` from its masses (no mass update).
pub fn close_pores(
    state: &mut FlowState,
    fluid: &impl PoreFluid,
    substep: u32,
) -> Result<(), FlowError> {
    advance_and_close(state, fluid, &[], &[], 0.0, substep)
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
