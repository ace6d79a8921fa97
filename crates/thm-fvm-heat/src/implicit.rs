//! Backward-Euler conduction step on a sparse symmetric positive-definite system (`faer`
//! sparse Cholesky), for the long cooling runs where explicit sub-steps are wasteful.
//!
//! (C/Δt + K) T^{n+1} = C/Δt T^n + b^{n+1} + s^n, with K the two-point conductances of every
//! face law (A-Eq. 47 primary term, fluid–solid interface, cases I and III) and of the S2S
//! channels (A-Eq. 40), b the boundary data at t^{n+1}, and s the non-orthogonal cross terms
//! and boundary tangential corrections evaluated at T^n (deferred correction; they are
//! antisymmetric between the two cells of a face, so energy stays conserved). K has zero row
//! sums apart from the boundary conductances and is symmetric, so the matrix is SPD.

use faer::Side;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use thm_vpn_mesh::{NONE, PoreMesh};

use crate::geometry::{BoundaryFace, FaceGeometry};
use crate::params::{HeatModel, SideCondition};
use crate::stepper::{boundary_conductance, face_conductivity, limit_cross};
use crate::{FlowInput, HeatError, HeatGeometry, HeatState, HeatStepper};

#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

impl HeatStepper {
    /// One backward-Euler conduction step of length `dt` \[s\]. Advection is not part of this
    /// step: any non-zero mass flux in `input` is an error.
    pub fn implicit_step(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
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
        for (what, fluxes) in [
            ("channel_mass_flux", &input.channel_mass_flux),
            ("boundary_mass_flux", &input.boundary_mass_flux),
        ] {
            if let Some(k) = fluxes.iter().position(|&m| m != 0.0) {
                return Err(HeatError::AdvectionInImplicitStep {
                    what,
                    index: k,
                    value: fluxes[k],
                });
            }
        }
        let t_old = state.time;
        let t_new = t_old + dt;
        // Gradients at T^n for the deferred corrections.
        self.face_values(model, geometry, mesh, &state.temperature, t_old);
        self.gradients(model, geometry, mesh, &state.temperature);

        let n = mesh.n_cells();
        let temp = &state.temperature;
        let mut rhs: Vec<f64> = (0..n).map(|c| self.capacity[c] / dt * temp[c]).collect();
        let mut diag: Vec<f64> = (0..n).map(|c| self.capacity[c] / dt).collect();
        let mut off: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(mesh.n_faces() + n);
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
                    let correction = dot(self.gradient[c0], tangent);
                    match cond {
                        SideCondition::HeatFlux(q) => rhs[c0] += q * area,
                        SideCondition::Temperature(_) | SideCondition::Convective { .. } => {
                            let g = boundary_conductance(cond, conductivity, normal_distance, area);
                            let outside = match cond {
                                SideCondition::Convective { ambient, .. } => *ambient,
                                _ => t_bc[side as usize],
                            };
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
        for (c, d) in diag.iter().enumerate() {
            off.push(Triplet::new(c, c, *d));
        }
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &off).map_err(|e| {
                HeatError::Solver {
                    message: format!("{e:?}"),
                }
            })?;
        let llt = matrix
            .sp_cholesky(Side::Lower)
            .map_err(|e| HeatError::Solver {
                message: format!("{e:?}"),
            })?;
        llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut rhs, n, 1));
        if let Some(c) = rhs.iter().position(|t| !t.is_finite()) {
            return Err(HeatError::NonFinite {
                quantity: "temperature",
                cell: c,
                step: state.steps,
                time: t_old,
                value: rhs[c],
            });
        }
        state.temperature.copy_from_slice(&rhs);
        state.time = t_new;
        state.steps += 1;
        Ok(())
    }
}
