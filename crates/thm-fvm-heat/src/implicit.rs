//! Backward-Euler step on a sparse system (`faer` sparse Cholesky for conduction alone, LU
//! when mass flows), for the long runs where explicit sub-steps are wasteful.
//!
//! (C/Δt + K) T^{n+1} = C/Δt T^n + b^{n+1} + s^n, with K the two-point conductances of every
//! face law (A-Eq. 47 primary term, fluid–solid interface, cases I and III) and of the S2S
//! channels (A-Eq. 40), b the boundary data at t^{n+1}, and s the non-orthogonal cross terms
//! and boundary tangential corrections evaluated at T^n (deferred correction; they are
//! antisymmetric between the two cells of a face, so energy stays conserved). K has zero row
//! sums apart from the boundary conductances and is symmetric, so the matrix is SPD.
//! Advection adds first-order upwind terms m c_p,up T_up^{n+1} (non-symmetric): with
//! divergence-free fluxes the matrix stays an M-matrix, so temperatures stay bounded.

use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use thm_vpn_mesh::{NONE, PoreMesh};

use crate::geometry::{BoundaryFace, FaceGeometry};
use crate::params::{HeatModel, SideCondition};
use crate::stepper::{boundary_conductance, boundary_correction, face_conductivity, limit_cross};
use crate::{FlowInput, HeatError, HeatGeometry, HeatState, HeatStepper};

#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

impl HeatStepper {
    /// One backward-Euler step of length `dt` \[s\]: conduction as in the module doc and,
    /// where `input` carries mass fluxes, first-order upwind advection (the explicit step's
    /// A-Eq. 48 reconstruction is not used here), solved by sparse LU instead of Cholesky.
    pub fn implicit_step(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        dt: f64,
    ) -> Result<(), HeatError> {
        self.implicit_step_inner(model, geometry, mesh, input, state, None, dt)
    }

    /// [`Self::implicit_step`] for cells whose heat capacity changed over the step (fluid
    /// that flowed in or out, a cell that moved): the energy balance is
    /// `C^{n+1} (T^{n+1} − T_ref) − C^n (T^n − T_ref) = dt × (fluxes at T^{n+1})`, with
    /// `C^{n+1}` from `input`, `C^n = old_capacity` \[J/K\] and `T_ref` the model's reference
    /// temperature (the one the advected enthalpy uses). With first-order upwind advection at
    /// T^{n+1}, a cell that only loses mass keeps its temperature.
    #[allow(clippy::too_many_arguments)]
    pub fn implicit_step_with_old_capacity(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        old_capacity: &[f64],
        dt: f64,
    ) -> Result<(), HeatError> {
        if old_capacity.len() != mesh.n_cells() {
            return Err(HeatError::LengthMismatch {
                what: "old_capacity",
                expected: mesh.n_cells(),
                got: old_capacity.len(),
            });
        }
        if let Some(c) = old_capacity
            .iter()
            .position(|c| !(c.is_finite() && *c >= 0.0))
        {
            return Err(HeatError::InputOutOfRange {
                quantity: "old_capacity",
                index: c,
                range: "finite and >= 0 J/K",
                value: old_capacity[c],
            });
        }
        self.implicit_step_inner(model, geometry, mesh, input, state, Some(old_capacity), dt)
    }

    #[allow(clippy::too_many_arguments)]
    fn implicit_step_inner(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        old: Option<&[f64]>,
        dt: f64,
    ) -> Result<(), HeatError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(HeatError::ParameterOutOfRange {
                field: "dt".to_owned(),
                range: "> 0 s",
                value: dt,
            });
        }
        self.prepare(model, geometry, mesh, input, state)?;
        let t_old = state.time;
        let t_new = t_old + dt;
        // Gradients at T^n for the deferred corrections.
        self.face_values(model, geometry, mesh, &state.temperature, t_old);
        self.gradients(model, geometry, mesh, &state.temperature);

        let n = mesh.n_cells();
        let temp = &state.temperature;
        let mut rhs: Vec<f64> = match old {
            None => (0..n).map(|c| self.capacity[c] / dt * temp[c]).collect(),
            Some(c_old) => {
                let t_ref = model.reference_temperature;
                (0..n)
                    .map(|c| (c_old[c] * (temp[c] - t_ref) + self.capacity[c] * t_ref) / dt)
                    .collect()
            }
        };
        let mut diag: Vec<f64> = (0..n).map(|c| self.capacity[c] / dt).collect();
        let mut off: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(mesh.n_faces() + n);
        // Advection entries (both triangles), only when something flows.
        let mut full: Vec<Triplet<usize, usize, f64>> = Vec::new();
        let mut couple = |a: usize, b: usize, g: f64, diag: &mut [f64]| {
            if g == 0.0 {
                return;
            }
            diag[a] += g;
            diag[b] += g;
            let (r, c) = if a > b { (a, b) } else { (b, a) };
            off.push(Triplet::new(r, c, -g));
        };
        let t_bc: [f64; 5] = std::array::from_fn(|k| match &model.sides[k] {
            SideCondition::Temperature(s) => s.at(t_new),
            _ => 0.0,
        });
        for f in 0..mesh.n_faces() {
            let [c0, c1] = mesh.face_cells[f];
            let c0 = c0 as usize;
            match geometry.face[f] {
                FaceGeometry::Diffusive {
                    conductance,
                    cross,
                    weight0,
                } => {
                    let c1 = c1 as usize;
                    let lf =
                        face_conductivity(self.conductivity[c0], self.conductivity[c1], weight0);
                    couple(c0, c1, lf * conductance, &mut diag);
                    let cross = [lf * cross[0], lf * cross[1]];
                    let (g0, g1) = (self.gradient[c0], self.gradient[c1]);
                    let s = limit_cross(
                        dot(cross, [0.5 * (g0[0] + g1[0]), 0.5 * (g0[1] + g1[1])]),
                        lf * conductance * (temp[c1] - temp[c0]),
                        model.cross_limit,
                    );
                    rhs[c0] += s;
                    rhs[c1] -= s;
                }
                FaceGeometry::Interface { index, .. } => couple(
                    c0,
                    c1 as usize,
                    self.interface_law[index as usize].g,
                    &mut diag,
                ),
                FaceGeometry::Boundary { slot } => {
                    let BoundaryFace {
                        side,
                        normal_distance,
                        area,
                        tangent,
                    } = geometry.boundary[slot as usize];
                    let conductivity = self.conductivity[c0];
                    let cond = &model.sides[side as usize];
                    match cond {
                        SideCondition::HeatFlux(q) => rhs[c0] += q * area,
                        SideCondition::Temperature(_) | SideCondition::Convective { .. } => {
                            let g = boundary_conductance(cond, conductivity, normal_distance, area);
                            let outside = match cond {
                                SideCondition::Convective { ambient, .. } => *ambient,
                                _ => t_bc[side as usize],
                            };
                            let correction = boundary_correction(
                                self.gradient[c0],
                                tangent,
                                outside,
                                temp[c0],
                                model.cross_limit,
                            );
                            diag[c0] += g;
                            rhs[c0] += g * (outside - correction);
                        }
                    }
                }
            }
            debug_assert!(c1 != NONE || matches!(geometry.face[f], FaceGeometry::Boundary { .. }));
        }
        for k in 0..mesh.channels.len() {
            let [a, b] = mesh.channels.cells[k].map(|c| c as usize);
            couple(a, b, self.channel_conductance[k], &mut diag);
        }
        // Advection, first-order upwind at T^{n+1}: a channel carries m c_p,up (T_up − T_ref)
        // from its upwind cell to the other; a boundary face carries its outflow at the cell
        // temperature and its inflow at the side's prescribed temperature (case I) or else at
        // the cell temperature. Each transfer leaves one row as it enters the other, so
        // energy stays conserved; the matrix is no longer symmetric.
        let t_ref = model.reference_temperature;
        let cp = &self.specific_heat;
        let mut advected = false;
        for (k, &m) in input.channel_mass_flux.iter().enumerate() {
            if m == 0.0 {
                continue;
            }
            advected = true;
            let [a, b] = mesh.channels.cells[k].map(|c| c as usize);
            let (up, down) = if m > 0.0 { (a, b) } else { (b, a) };
            let rate = m.abs() * input.channel_cp(k, cp[up]);
            diag[up] += rate;
            rhs[up] += rate * t_ref;
            full.push(Triplet::new(down, up, -rate));
            rhs[down] -= rate * t_ref;
        }
        for (f, &m) in input.boundary_mass_flux.iter().enumerate() {
            if m == 0.0 {
                continue;
            }
            let FaceGeometry::Boundary { slot } = geometry.face[f] else {
                continue;
            };
            advected = true;
            let c = mesh.face_cells[f][0] as usize;
            let rate = m.abs() * cp[c];
            let side = geometry.boundary[slot as usize].side as usize;
            match (m > 0.0, &model.sides[side]) {
                // Outflow at the cell temperature.
                (true, _) => {
                    diag[c] += rate;
                    rhs[c] += rate * t_ref;
                }
                (false, SideCondition::Temperature(_)) => {
                    rhs[c] += rate * (t_bc[side] - t_ref);
                }
                // Inflow at the cell temperature.
                (false, _) => {
                    diag[c] -= rate;
                    rhs[c] -= rate * t_ref;
                }
            }
        }
        for (c, d) in diag.iter().enumerate() {
            off.push(Triplet::new(c, c, *d));
        }
        let solver = |e: &dyn std::fmt::Debug| HeatError::Solver {
            message: format!("{e:?}"),
        };
        let rhs_mat = faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1);
        if advected {
            // The conduction part as a full (both triangles) matrix plus the advection.
            for t in &off {
                if t.row != t.col {
                    full.push(Triplet::new(t.col, t.row, t.val));
                }
            }
            full.extend_from_slice(&off);
            let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &full)
                .map_err(|e| solver(&e))?;
            let lu = matrix.sp_lu().map_err(|e| solver(&e))?;
            lu.solve_in_place(rhs_mat);
        } else {
            let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &off)
                .map_err(|e| solver(&e))?;
            let llt = matrix.sp_cholesky(Side::Lower).map_err(|e| solver(&e))?;
            llt.solve_in_place(rhs_mat);
        }
        if let Some(c) = rhs.iter().position(|t| !t.is_finite()) {
            return Err(HeatError::NonFinite {
                quantity: "temperature",
                cell: c,
                step: state.steps,
                time: t_old,
                value: rhs[c],
            });
        }
        // Energy through the boundary over the step, with the terms the matrix used.
        crate::stepper::boundary_faces(
            geometry,
            &mut self.boundary_face_list,
            &mut self.boundary_face_side,
        );
        let mut entered = 0.0;
        let mut by_side = [0.0; 5];
        for &f in &self.boundary_face_list {
            let f = f as usize;
            let FaceGeometry::Boundary { slot } = geometry.face[f] else {
                continue;
            };
            let BoundaryFace {
                side,
                normal_distance,
                area,
                tangent,
            } = geometry.boundary[slot as usize];
            let c = mesh.face_cells[f][0] as usize;
            let tc = rhs[c];
            let cond = &model.sides[side as usize];
            let before = entered;
            entered += match cond {
                SideCondition::HeatFlux(q) => q * area,
                SideCondition::Temperature(_) | SideCondition::Convective { .. } => {
                    let g = boundary_conductance(cond, self.conductivity[c], normal_distance, area);
                    let outside = match cond {
                        SideCondition::Convective { ambient, .. } => *ambient,
                        _ => t_bc[side as usize],
                    };
                    let correction = boundary_correction(
                        self.gradient[c],
                        tangent,
                        outside,
                        state.temperature[c],
                        model.cross_limit,
                    );
                    g * (outside - correction - tc)
                }
            };
            let m = input.boundary_mass_flux[f];
            let rate = m.abs() * cp[c];
            entered += match (m > 0.0, cond) {
                _ if m == 0.0 => 0.0,
                (true, _) => -rate * (tc - t_ref),
                (false, SideCondition::Temperature(_)) => rate * (t_bc[side as usize] - t_ref),
                (false, _) => rate * (tc - t_ref),
            };
            by_side[side as usize] += (entered - before) * dt;
        }
        self.boundary_energy = entered * dt;
        self.boundary_energy_by_side = by_side;
        state.temperature.copy_from_slice(&rhs);
        state.time = t_new;
        state.steps += 1;
        Ok(())
    }
}
