//! The stages of one flow sub-step, functions over the caller's [`FlowState`] that the
//! explicit stepper ([`crate::stepper`]) runs in this order and the implicit one
//! (`implicit`) reuses:
//!
//! 1. [`channel_fluxes`]: phase mass flow rates in every channel (A-Eqs. 10–15, upwind).
//! 2. [`boundary_fluxes`]: phase mass flow rates through the boundary links.
//! 3. [`gather_pore_rates`]: net phase mass rate into every pore and its stable sub-step.
//! 4. [`advance_and_close`]: `m += Δt Σ M_f` (A-Eqs. 24, 26), `V += dV/dt Δt` (A-Eq. 25),
//!    then the closure (A-Eq. 29) for fraction, pressure and densities.
//!
//! A state is built closed: [`FlowState::from_masses`], [`FlowState::from_pressure`] and
//! [`FlowState::close`] run the closure of stage 4 (here, so that `state` holds data only).

use crate::channel::two_layer_conductances;
use crate::error::{FlowError, Phase};
use crate::fluid::PoreFluid;
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
    pub(crate) fn name(self) -> &'static str {
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

/// The mean liquid speed in every channel at the state's pressures \[m/s\]: the liquid
/// layer's flow rate per unit width over its thickness, `|Q_q| / (α_q,up h)`, with the layer
/// of the upwind pore as in [`channel_fluxes`] (A-Eqs. 10–15). Zero where the upwind pore
/// holds no liquid, the channel is closed or the pressures are equal.
pub fn channel_liquid_speeds(
    network: &Network,
    state: &FlowState,
    config: &FlowConfig,
) -> Vec<f64> {
    let parts = network.parts();
    let (mq, mp) = (config.liquid_viscosity(), config.gas_viscosity());
    (0..network.n_channels())
        .map(|c| {
            let [i, j] = parts.channel_pores[c];
            let (i, j) = (i as usize, j as usize);
            let g = (state.pressure[i] - state.pressure[j]) / parts.channel_length[c];
            let up = if g >= 0.0 { i } else { j };
            let h = parts.channel_aperture[c];
            let layer = state.liquid_fraction[up] * h;
            if layer <= 0.0 {
                return 0.0;
            }
            let (cq, _) = two_layer_conductances(h, state.liquid_fraction[up], mq, mp);
            (cq * g).abs() / layer
        })
        .collect()
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

/// Construction of a closed state (the closure of stage 4).
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
        close_pores(&mut s, fluid, 0)?;
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
        close_pores(self, fluid, 0)
    }
}
