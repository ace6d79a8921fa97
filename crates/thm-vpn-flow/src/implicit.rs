//! The linearly implicit pressure step ([`FlowStepper::implicit_step`]).
//!
//! The explicit update is limited by the compressibility of the pore fluid: for water-filled
//! pores `K/V Σ C` is so large that the stable sub-step is ~10⁻⁸ s. The implicit step removes
//! that limit by solving the linearised pressure equation of every pore at the end of the
//! sub-step,
//!
//! ```text
//! V_i/K_i (P_i* − P_i)/h = Σ_c C_c (P_j* − P_i*) + Σ_links C_l (P_b − P_i*) + S_i − dV_i/dt
//! ```
//!
//! (`C` the volumetric conductances of the channels and pressure links at the upwind
//! fractions, each phase's weighted by its upwind density over its density in pore `i` (the
//! volume the transported mass takes up there), `S_i` the volume rate of the prescribed mass
//! rates at the pore's densities, `K_i` the mixture bulk modulus), a sparse system solved by
//! LU. The density ratios make its fixed point the state where every pore's mass balances
//! (a steady flow between reservoirs at different pressures), not only its volume. It is the volume balance `Σ_k dm_k/ρ_k − V/K dP = dV` of A-Eqs. 24–29
//! linearised about the current state. The phase mass fluxes are then evaluated at `P*` with
//! the same channel law as the explicit step (A-Eqs. 10–15, upwind at `P*`), the masses are
//! advanced conservatively (A-Eq. 24) and closed (A-Eq. 29): the closure, not the linear
//! solve, sets the new pressure, so mass is conserved to round-off whatever the
//! linearisation error. A sub-step in which a pore would lose more than
//! `positivity_safety` of a phase's mass is rejected and halved.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};

use crate::channel::two_layer_conductances;
use crate::error::FlowError;
use crate::fluid::PoreFluid;
use crate::network::{BoundaryCondition, Network};
use crate::state::FlowState;
use crate::stepper::{
    FlowStepper, StepReport, advance_and_close, boundary_fluxes, channel_fluxes, gather_pore_rates,
};

/// Re-solves of one sub-step when the flow direction of a channel or link changed.
const MAX_UPWIND_ITERATIONS: usize = 8;

/// Whether every channel and pressure link has the same upwind end under pressures `a` and
/// `b` (the tie rule of the explicit fluxes: `P_i ≥ P_j` → `i`).
fn same_directions(network: &Network, a: &[f64], b: &[f64]) -> bool {
    let parts = network.parts();
    let channels = parts.channel_pores.iter().all(|&[i, j]| {
        let (i, j) = (i as usize, j as usize);
        (a[i] >= a[j]) == (b[i] >= b[j])
    });
    let links = (0..network.n_links()).all(|k| {
        let p = parts.link_pore[k] as usize;
        match parts.boundaries[parts.link_group[k] as usize] {
            BoundaryCondition::Pressure { pressure, .. } => {
                (pressure >= a[p]) == (pressure >= b[p])
            }
            _ => true,
        }
    });
    channels && links
}

impl FlowStepper {
    /// Advances `state` by `dt` \[s\] with linearly implicit pressure sub-steps (see the
    /// module doc): one sub-step of `dt` unless a pore would lose more than
    /// `positivity_safety` of a phase's mass, then halved until it does not (at most
    /// `max_substeps` tries in all). `dv_dt` as in [`Self::step`]. The report's
    /// `smallest_substep` is the shortest accepted sub-step.
    pub fn implicit_step(
        &mut self,
        network: &Network,
        state: &mut FlowState,
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
        self.link_mass.clear();
        self.link_mass.resize(network.n_links(), 0.0);
        let ng = network.n_groups();
        let mut report = StepReport {
            substeps: 0,
            smallest_substep: f64::INFINITY,
            max_reynolds: 0.0,
            boundary_liquid_rate: vec![0.0; ng],
            boundary_gas_rate: vec![0.0; ng],
        };
        let max_tries = self.config.parameters().max_substeps;
        let s_pos = self.config.parameters().positivity_safety;
        let mut tries = 0u32;
        let mut remaining = dt;
        let mut h = dt;
        let mut p_old = Vec::with_capacity(network.n_pores());
        let mut upwind_pressure = Vec::with_capacity(network.n_pores());
        let mut backup = state.clone();
        while remaining > 0.0 {
            h = h.min(remaining);
            if tries >= max_tries {
                return Err(FlowError::TooManySubsteps {
                    step: state.step,
                    substeps: report.substeps,
                    dt_limit: h,
                    limit: "implicit positivity",
                    pore: usize::MAX,
                });
            }
            tries += 1;
            // Upwind directions from the current pressures; re-solved with those of P* until
            // the channels the matrix saw are the ones the fluxes will use.
            upwind_pressure.clear();
            upwind_pressure.extend_from_slice(&state.pressure);
            let mut p_star = self.solve_pressure(network, state, &upwind_pressure, dv_dt, h)?;
            for _ in 0..MAX_UPWIND_ITERATIONS {
                if same_directions(network, &upwind_pressure, &p_star) {
                    break;
                }
                upwind_pressure.copy_from_slice(&p_star);
                p_star = self.solve_pressure(network, state, &upwind_pressure, dv_dt, h)?;
            }
            p_old.clear();
            p_old.extend_from_slice(&state.pressure);
            state.pressure.copy_from_slice(&p_star);
            channel_fluxes(network, state, &self.config, &mut self.channel);
            boundary_fluxes(network, state, &self.config, &self.inflow, &mut self.link);
            let gathered = gather_pore_rates(
                network,
                state,
                &self.config,
                &self.channel,
                &self.link,
                &mut self.rates,
                report.substeps,
            );
            state.pressure.copy_from_slice(&p_old);
            let limit = gathered?;
            let too_much = self.rates.iter().enumerate().any(|(p, r)| {
                (r.liquid < 0.0 && -r.liquid * h > s_pos * state.liquid_mass[p])
                    || (r.gas < 0.0 && -r.gas * h > s_pos * state.gas_mass[p])
            });
            if too_much {
                h *= 0.5;
                continue;
            }
            // A closure the linearisation overshot (e.g. a liquid pore pulled below zero
            // pressure) rejects the sub-step too.
            backup.clone_from(state);
            match advance_and_close(state, fluid, &self.rates, dv_dt, h, report.substeps) {
                Ok(()) => {}
                Err(FlowError::Closure { .. }) => {
                    state.clone_from(&backup);
                    h *= 0.5;
                    continue;
                }
                Err(e) => return Err(e),
            }
            report.max_reynolds = report.max_reynolds.max(limit.max_reynolds);
            report.boundary_liquid_rate.fill(0.0);
            report.boundary_gas_rate.fill(0.0);
            for (k, f) in self.link.iter().enumerate() {
                let g = network.parts().link_group[k] as usize;
                report.boundary_liquid_rate[g] += f.liquid;
                report.boundary_gas_rate[g] += f.gas;
            }
            for (m, f) in self.channel_mass.iter_mut().zip(&self.channel) {
                *m += h * (f.liquid + f.gas);
            }
            for (m, f) in self.link_mass.iter_mut().zip(&self.link) {
                *m += h * (f.liquid + f.gas);
            }
            for g in 0..ng {
                state.boundary_liquid_inflow[g] += h * report.boundary_liquid_rate[g];
                state.boundary_gas_inflow[g] += h * report.boundary_gas_rate[g];
            }
            report.substeps += 1;
            report.smallest_substep = report.smallest_substep.min(h);
            remaining = if h >= remaining { 0.0 } else { remaining - h };
        }
        state.step += 1;
        state.time += dt;
        Ok(report)
    }

    /// The pressures `P*` of the linearised pressure equation over a sub-step `h` (module
    /// doc), from the current (closed) state, with channels and links upwinded by
    /// `upwind_pressure`.
    fn solve_pressure(
        &self,
        network: &Network,
        state: &FlowState,
        upwind_pressure: &[f64],
        dv_dt: &[f64],
        h: f64,
    ) -> Result<Vec<f64>, FlowError> {
        let parts = network.parts();
        let n = network.n_pores();
        let w = network.width();
        let (mq, mp) = (self.config.liquid_viscosity(), self.config.gas_viscosity());
        // Volume rate into pore `i` per pascal of the channel's drive: each phase's
        // conductance times the ratio of its transported (upwind) density to its density in
        // `i` (the volume it takes up there).
        let coefficient = |aperture: f64, alpha: f64, length: f64, up: [f64; 2], i: usize| {
            let (cq, cp) = two_layer_conductances(aperture, alpha, mq, mp);
            let ratio = |rho_up: f64, rho_i: f64| if rho_i > 0.0 { rho_up / rho_i } else { 1.0 };
            (cq * ratio(up[0], state.liquid_density[i]) + cp * ratio(up[1], state.gas_density[i]))
                * w
                / length
        };
        // V/(K h) on the diagonal, its pressure and the volume rates on the right.
        let mut diag: Vec<f64> = state
            .pressure_stiffness
            .iter()
            .map(|st| 1.0 / (st * h))
            .collect();
        let mut rhs: Vec<f64> = diag
            .iter()
            .zip(&state.pressure)
            .map(|(d, p)| d * p)
            .collect();
        if !dv_dt.is_empty() {
            for (r, dv) in rhs.iter_mut().zip(dv_dt) {
                *r -= dv;
            }
        }
        let mut entries: Vec<Triplet<usize, usize, f64>> =
            Vec::with_capacity(n + 2 * network.n_channels());
        for c in 0..network.n_channels() {
            let [i, j] = parts.channel_pores[c].map(|p| p as usize);
            let up = if upwind_pressure[i] >= upwind_pressure[j] {
                i
            } else {
                j
            };
            let rho_up = [state.liquid_density[up], state.gas_density[up]];
            let (aperture, alpha, length) = (
                parts.channel_aperture[c],
                state.liquid_fraction[up],
                parts.channel_length[c],
            );
            for (row, col) in [(i, j), (j, i)] {
                let g = coefficient(aperture, alpha, length, rho_up, row);
                if g > 0.0 {
                    diag[row] += g;
                    entries.push(Triplet::new(row, col, -g));
                }
            }
        }
        let group_len = network.group_face_length();
        for k in 0..network.n_links() {
            let p = parts.link_pore[k] as usize;
            let g = parts.link_group[k] as usize;
            match parts.boundaries[g] {
                BoundaryCondition::Pressure {
                    pressure,
                    entering_liquid_fraction,
                    ..
                } => {
                    let (alpha, rho_up) = if pressure >= upwind_pressure[p] {
                        (
                            entering_liquid_fraction,
                            [self.inflow[g].liquid_density, self.inflow[g].gas_density],
                        )
                    } else {
                        (
                            state.liquid_fraction[p],
                            [state.liquid_density[p], state.gas_density[p]],
                        )
                    };
                    let c = coefficient(
                        parts.link_aperture[k],
                        alpha,
                        parts.link_length[k],
                        rho_up,
                        p,
                    );
                    diag[p] += c;
                    rhs[p] += c * pressure;
                }
                BoundaryCondition::MassRate {
                    liquid_mass_rate,
                    gas_mass_rate,
                } => {
                    let share = parts.link_face_length[k] / group_len[g];
                    let volume_rate = |rate: f64, rho: f64| {
                        if rate != 0.0 && rho > 0.0 {
                            rate / rho
                        } else {
                            0.0
                        }
                    };
                    rhs[p] += share
                        * (volume_rate(liquid_mass_rate, state.liquid_density[p])
                            + volume_rate(gas_mass_rate, state.gas_density[p]));
                }
                BoundaryCondition::Impermeable => {}
            }
        }
        // Every row divided by its diagonal: the diagonal spans many decades between gas-
        // and water-filled pores.
        for t in &mut entries {
            *t = Triplet::new(t.row, t.col, t.val / diag[t.row]);
        }
        for c in 0..n {
            entries.push(Triplet::new(c, c, 1.0));
            rhs[c] /= diag[c];
        }
        let solver_error = |message: String| FlowError::Solver {
            step: state.step,
            message,
        };
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &entries)
            .map_err(|e| solver_error(format!("{e:?}")))?;
        let lu = matrix.sp_lu().map_err(|e| solver_error(format!("{e:?}")))?;
        lu.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1));
        if let Some(p) = rhs.iter().position(|x| !x.is_finite()) {
            return Err(FlowError::NonFinite {
                quantity: "implicit pressure",
                place: "pore",
                index: p,
                value: rhs[p],
                step: state.step,
                substep: 0,
            });
        }
        Ok(rhs)
    }
}
