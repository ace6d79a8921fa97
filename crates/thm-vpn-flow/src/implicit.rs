//! The implicit pressure step ([`FlowStepper::implicit_step`]): backward Euler in the phase
//! masses, solved by Newton iterations on the pore closure.
//!
//! The explicit update is limited by the compressibility of the pore fluid: for water-filled
//! pores `K/V Σ C` is so large that the stable sub-step is ~10⁻⁸ s. A sub-step of length `h`
//! here seeks the masses `m^{n+1} = m^n + h F(P^{n+1})` whose closure (A-Eq. 29) gives the
//! pressures `P^{n+1}` that drive the fluxes `F` (A-Eqs. 10–15, 24). Each iteration
//! linearises the closure about the current iterate `(m, P)`,
//!
//! ```text
//! V_i/K_i (P_i* − P_i)/h = d_i/h + Σ_c C'_c (P_j* − P_i*) + Σ_links C'_l (P_b − P_i*) + S_i
//! ```
//!
//! with `d_i = Σ_k (m_k^n − m_k)/ρ_k − (V^{n+1} − V)` the volume the iterate lacks (at the
//! first iterate `−h dV/dt`), `C'` each phase's conductance at the upwind fraction times its
//! upwind density over its density in pore `i` (the volume the transported mass takes up
//! there), `S_i` the volume rate of the prescribed mass rates and `K_i` the mixture bulk
//! modulus; a sparse system solved by LU. The phase mass fluxes at `P*` (same channel law
//! and upwinding as the explicit step) then give the next iterate `m = m^n + h F(P*)`,
//! closed. The iterations stop when the closure pressures agree with `P*` to 10⁻⁹ of the
//! largest pressure and no channel changed its upwind end; mass is conserved to round-off
//! at every iterate, so the tolerance affects accuracy only. A sub-step that would take more
//! than `positivity_safety` of a phase out of a pore, whose closure fails, or that does not
//! converge in 12 iterations is halved.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};

use crate::channel::two_layer_conductances;
use crate::error::FlowError;
use crate::fluid::PoreFluid;
use crate::network::{BoundaryCondition, Network};
use crate::state::FlowState;
use crate::stepper::{
    FlowStepper, StepReport, SubstepLimit, advance_and_close, boundary_fluxes, channel_fluxes,
    gather_pore_rates,
};

/// Newton iterations of one sub-step before it is halved.
const MAX_NEWTON_ITERATIONS: usize = 12;
/// Largest |P_closure − P*| of a converged sub-step, relative to the largest |P| (at least
/// [`ATMOSPHERIC_PRESSURE`]).
const NEWTON_TOLERANCE: f64 = 1e-9;
/// Pressure scale floor of the convergence test \[Pa\].
const ATMOSPHERIC_PRESSURE: f64 = 101_325.0;

/// Buffers of the Newton iterations of one sub-step.
struct NewtonScratch {
    /// The state at the start of the sub-step.
    start: FlowState,
    /// Per pore: the volume the iterate lacks (see [`FlowStepper::newton_substep`]).
    defect: Vec<f64>,
}

/// Whether every channel and pressure link has the same upwind end under pressures `a` and
/// `b` (the tie rule of the explicit fluxes: `P_i ≥ P_j` → `i`), ignoring those whose drive
/// under `b` is within `tolerance` \[Pa\] of zero (their flux is round-off either way).
fn same_directions(network: &Network, a: &[f64], b: &[f64], tolerance: f64) -> bool {
    let parts = network.parts();
    let agree = |a0: f64, a1: f64, b0: f64, b1: f64| {
        (a0 >= a1) == (b0 >= b1) || (b0 - b1).abs() <= tolerance
    };
    let channels = parts.channel_pores.iter().all(|&[i, j]| {
        let (i, j) = (i as usize, j as usize);
        agree(a[i], a[j], b[i], b[j])
    });
    let links = (0..network.n_links()).all(|k| {
        let p = parts.link_pore[k] as usize;
        match parts.boundaries[parts.link_group[k] as usize] {
            BoundaryCondition::Pressure { pressure, .. } => agree(pressure, a[p], pressure, b[p]),
            _ => true,
        }
    });
    channels && links
}

/// The shortest implicit sub-step, as a fraction of the step: below it the step fails
/// (a pore that no sub-step can keep positive and closed, e.g. a cell collapsing).
pub const MIN_SUBSTEP_FRACTION: f64 = 1e-12;

impl FlowStepper {
    /// Advances `state` by `dt` \[s\] with backward-Euler sub-steps (see the module doc): one
    /// sub-step of `dt` unless it is rejected, then halved until it is accepted and doubled
    /// again after each accepted one (at most `max_substeps` tries in all, none shorter than
    /// [`MIN_SUBSTEP_FRACTION`] of `dt`). `dv_dt` as in [`Self::step`]. The report's
    /// `smallest_substep` is the shortest accepted sub-step.
    pub fn implicit_step(
        &mut self,
        network: &Network,
        state: &mut FlowState,
        fluid: &impl PoreFluid,
        dv_dt: &[f64],
        dt: f64,
    ) -> Result<StepReport, FlowError> {
        let mut report = self.begin_step(network, state, fluid, dv_dt, dt)?;
        let max_tries = self.config.parameters().max_substeps;
        let mut tries = 0u32;
        let mut remaining = dt;
        let mut h = dt;
        let mut scratch = NewtonScratch {
            start: state.clone(),
            defect: Vec::with_capacity(network.n_pores()),
        };
        while remaining > 0.0 {
            h = h.min(remaining);
            // The floor applies to halved sub-steps, not to a round-off leftover of `dt`.
            if tries >= max_tries || (h < MIN_SUBSTEP_FRACTION * dt && h < remaining) {
                return Err(FlowError::TooManySubsteps {
                    step: state.step,
                    substeps: report.substeps,
                    dt_limit: h,
                    limit: "implicit sub-step rejected (positivity, closure or convergence)",
                    pore: usize::MAX,
                });
            }
            tries += 1;
            match self.newton_substep(
                network,
                state,
                fluid,
                dv_dt,
                h,
                &mut scratch,
                report.substeps,
            )? {
                Some(limit) => report.max_reynolds = report.max_reynolds.max(limit.max_reynolds),
                None => {
                    h *= 0.5;
                    continue;
                }
            }
            self.record_substep(network, state, &mut report, h);
            remaining = if h >= remaining { 0.0 } else { remaining - h };
            // A rejection was local in time: try a longer sub-step again.
            h *= 2.0;
        }
        state.step += 1;
        state.time += dt;
        Ok(report)
    }

    /// One backward-Euler sub-step of length `h` by Newton iterations on the closure (module
    /// doc). On success `state` holds the closed end state, the stepper's channel, link and
    /// pore rates are those that took it there, and the result is their flux diagnostics;
    /// `None` (with `state` restored) asks for a shorter sub-step: a pore would lose more
    /// than `positivity_safety` of a phase, a closure failed, or the iterations did not
    /// converge.
    #[allow(clippy::too_many_arguments)]
    fn newton_substep(
        &mut self,
        network: &Network,
        state: &mut FlowState,
        fluid: &impl PoreFluid,
        dv_dt: &[f64],
        h: f64,
        scratch: &mut NewtonScratch,
        substep: u32,
    ) -> Result<Option<SubstepLimit>, FlowError> {
        let s_pos = self.config.parameters().positivity_safety;
        scratch.start.clone_from(state);
        let mut upwind = state.pressure.clone();
        for _ in 0..MAX_NEWTON_ITERATIONS {
            // Volume the iterate lacks: Σ_k (m_k^n − m_k)/ρ_k − (V^{n+1} − V), so that the
            // linearisation is about the iterate but the balance is from the sub-step start.
            let start = &scratch.start;
            scratch.defect.clear();
            scratch.defect.extend((0..network.n_pores()).map(|i| {
                let phase =
                    |m0: f64, m: f64, rho: f64| if rho > 0.0 { (m0 - m) / rho } else { 0.0 };
                let v_end = start.volume[i] + dv_dt.get(i).map_or(0.0, |dv| dv * h);
                phase(
                    start.liquid_mass[i],
                    state.liquid_mass[i],
                    state.liquid_density[i],
                ) + phase(start.gas_mass[i], state.gas_mass[i], state.gas_density[i])
                    - (v_end - state.volume[i])
            }));
            let p_star = self.solve_pressure(network, state, &upwind, &scratch.defect, h)?;
            // Fluxes at P* with the iterate's fractions and densities.
            let p_iterate = std::mem::replace(&mut state.pressure, p_star);
            channel_fluxes(network, state, &self.config, &mut self.channel);
            boundary_fluxes(network, state, &self.config, &self.inflow, &mut self.link);
            let gathered = gather_pore_rates(
                network,
                state,
                &self.config,
                &self.channel,
                &self.link,
                &mut self.rates,
                substep,
            );
            let p_star = std::mem::replace(&mut state.pressure, p_iterate);
            let limit = gathered?;
            let start = &scratch.start;
            let too_much = self.rates.iter().enumerate().any(|(p, r)| {
                (r.liquid < 0.0 && -r.liquid * h > s_pos * start.liquid_mass[p])
                    || (r.gas < 0.0 && -r.gas * h > s_pos * start.gas_mass[p])
            });
            if too_much {
                state.clone_from(&scratch.start);
                return Ok(None);
            }
            state.clone_from(&scratch.start);
            match advance_and_close(state, fluid, &self.rates, dv_dt, h, substep) {
                Ok(()) => {}
                Err(FlowError::Closure { .. }) => {
                    state.clone_from(&scratch.start);
                    return Ok(None);
                }
                Err(e) => return Err(e),
            }
            // Converged when the closure agrees with the linear solve and the flow
            // directions it was assembled with are those of P*.
            let scale = state
                .pressure
                .iter()
                .fold(ATMOSPHERIC_PRESSURE, |a, p| a.max(p.abs()));
            let agree = state
                .pressure
                .iter()
                .zip(&p_star)
                .all(|(p, q)| (p - q).abs() <= NEWTON_TOLERANCE * scale);
            if agree && same_directions(network, &upwind, &p_star, NEWTON_TOLERANCE * scale) {
                return Ok(Some(limit));
            }
            upwind = p_star;
        }
        state.clone_from(&scratch.start);
        Ok(None)
    }

    /// The pressures `P*` of the linearised pressure equation over a sub-step `h` (module
    /// doc), from the current (closed) state, with channels and links upwinded by
    /// `upwind_pressure`.
    fn solve_pressure(
        &self,
        network: &Network,
        state: &FlowState,
        upwind_pressure: &[f64],
        defect: &[f64],
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
        for (r, d) in rhs.iter_mut().zip(defect) {
            *r += d / h;
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
