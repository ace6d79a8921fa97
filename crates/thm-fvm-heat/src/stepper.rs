//! The explicit finite-volume step (A-Eqs. 37–51) with its stability limit and sub-cycling.
//!
//! One outer step is the fixed sequence [`HeatStepper::prepare`] (input checks fused with the
//! cell properties in one pass over the cells, the interface laws, the S2S conductances) and
//! [`HeatStepper::stability_limit`], then, for each sub-step: [`HeatStepper::face_values`]
//! (interface and boundary faces only) → [`HeatStepper::gradients`] (gradient and limiter in
//! one pass over the cells) → [`HeatStepper::face_heat`] → [`HeatStepper::channel_heat`] →
//! [`HeatStepper::advance`] (with the finiteness check). [`HeatStepper::step`] folds the
//! stability limit into the first sub-step: its face pass
//! ([`HeatStepper::face_heat_and_conductances`]) also stores each face's conductance, and
//! one pass over the cells ([`HeatStepper::net_heat_and_stability_limit`]) sums both the net
//! heat and the conductances, so the limit, hence the sub-step length, is known before
//! [`HeatStepper::apply_net_heat`] updates the temperatures: one pass over the mesh fewer,
//! the same bits. Conductances of faces inside a
//! medium are not stored: λ_f is formed from the two cell conductivities where a face is
//! used, from the geometry cached in [`HeatGeometry`]. Every stage is a parallel map over
//! cells, faces or channels whose results are gathered per cell in a fixed order, so
//! 1-thread and N-thread runs give identical bits.

use rayon::prelude::*;
use thm_vpn_mesh::{ChannelKind, Channels, PoreMesh};

use crate::geometry::{
    BoundaryFace, CELL_FIRST, CELL_FLUID, CELL_INTERFACE, FACE_VALUE, FaceGeometry, GRAIN, dot,
    first_where, sub,
};
use crate::params::{GradientScheme, HeatModel, SideCondition};
use crate::properties::ExchangeFactors;
use crate::state::fluid_entry_ok;
use crate::{FlowInput, HeatError, HeatGeometry, HeatState};

pub use crate::geometry::MIN_FACE_COSINE;

/// Factor on the advective outflow in the stability limit. On a triangle the three face
/// excursions of a linear reconstruction sum to zero, so the Barth–Jespersen bound on the
/// largest one limits the outflow excursion to twice the room to the local maximum; the
/// update then stays within the neighbourhood bounds for (1 + 2) Δt Σ_out ṁ c_p ≤ C.
pub const ADVECTIVE_FACTOR: f64 = 3.0;

/// How heat crosses one fluid–solid interface face (case IV); computed once per outer step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct InterfaceLaw {
    /// Series conductance |A| h_f k_s / (h_f + k_s) \[W/K\], k_s = λ_s / d_{r,c}.
    pub g: f64,
    /// Weight of cell 0 in the interface temperature.
    pub w0: f64,
}

/// λ_f of A-Eq. 47 between cells of conductivity `l0` and `l1`: the harmonic mean weighted
/// by the distances d0, d1 of the centroids to the face, l0 l1 (d0 + d1) / (d1 l0 + d0 l1) =
/// l0 l1 / ((1 − w0) l0 + w0 l1) with `weight0` w0 = d0 / (d0 + d1) (the arithmetic mean
/// where the weighted sum vanishes). The face's primary conductance is λ_f times the
/// geometry's `conductance`, its cross term λ_f times `cross`.
#[inline]
pub(crate) fn face_conductivity(l0: f64, l1: f64, weight0: f64) -> f64 {
    let den = (1.0 - weight0) * l0 + weight0 * l1;
    if den > 0.0 {
        l0 * l1 / den
    } else {
        0.5 * (l0 + l1)
    }
}

/// x = ρ_eff v / μ_eff of A-Eqs. 43–45 for a fluid cell with mixture `mix` whose channels
/// are `channels` (pairs of channel index and side): v is the fastest channel speed
/// |ṁ| / (ρ_eff h b), so x = max |ṁ| / (h b) / μ_eff and the density cancels. The largest
/// |ṁ| / (h b) is found by cross-multiplication, so the cell makes one division, not one per
/// channel. Zero at rest, without open channels, or for a mixture of no density.
#[inline]
fn fastest_channel_x(
    channels: &[(u32, bool)],
    ch: &Channels,
    input: &FlowInput,
    thickness: f64,
    mix: &crate::properties::MixtureProperties,
) -> f64 {
    if mix.density <= 0.0 {
        return 0.0;
    }
    let (mut flux, mut area) = (0.0f64, 1.0f64);
    for &(k, _) in channels {
        let k = k as usize;
        let a = ch.aperture[k] * thickness;
        let m = input.channel_mass_flux[k].abs();
        if a > 0.0 && m * area > flux * a {
            (flux, area) = (m, a);
        }
    }
    if flux > 0.0 {
        flux / (area * mix.dynamic_viscosity)
    } else {
        0.0
    }
}

/// Pr^{1/3} of a fluid cell of liquid fraction `alpha` holding one phase only (a model
/// constant); `None` for a mixture.
#[inline]
fn pure_phase_prandtl_cbrt(model: &HeatModel, alpha: f64) -> Option<f64> {
    if alpha == 1.0 {
        Some(model.pure_prandtl_cbrt[0])
    } else if alpha == 0.0 {
        Some(model.pure_prandtl_cbrt[1])
    } else {
        None
    }
}

/// What one outer step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Number of explicit sub-steps.
    pub substeps: usize,
    /// Length of each sub-step \[s\].
    pub substep: f64,
    /// The stability limit of this step \[s\] (before the safety factor).
    pub stability_limit: f64,
}

/// The faces on the outer boundary, in face order, and the side of each (rebuilt when the
/// mesh size changes).
pub(crate) fn boundary_faces(geometry: &HeatGeometry, out: &mut Vec<u32>, sides: &mut Vec<u8>) {
    out.clear();
    sides.clear();
    for (f, g) in geometry.face.iter().enumerate() {
        if let FaceGeometry::Boundary { slot } = g {
            out.push(f as u32);
            sides.push(geometry.boundary[*slot as usize].side);
        }
    }
}

/// Scratch buffers of the explicit step. Holds no state between calls: every buffer is
/// recomputed from the geometry, the model, the flow input and the state.
#[derive(Debug, Clone, Default)]
pub struct HeatStepper {
    /// Energy \[J\] that entered through the outer boundary during the last step
    /// (conduction and advected enthalpy `ṁ c_p (T − T_ref)`).
    pub(crate) boundary_energy: f64,
    /// The same by boundary side (indexed as `HeatModel`'s sides: left, right, bottom, top,
    /// outline).
    pub(crate) boundary_energy_by_side: [f64; 5],
    /// Faces on the outer boundary.
    pub(crate) boundary_face_list: Vec<u32>,
    /// The side of each face of `boundary_face_list`.
    pub(crate) boundary_face_side: Vec<u8>,
    // Per cell.
    pub(crate) capacity: Vec<f64>,
    pub(crate) conductivity: Vec<f64>,
    pub(crate) specific_heat: Vec<f64>,
    exchange: Vec<ExchangeFactors>,
    pub(crate) gradient: Vec<[f64; 2]>,
    limiter: Vec<f64>,
    // Per interface face, in the order of the geometry's `interface` records.
    pub(crate) interface_law: Vec<InterfaceLaw>,
    // Per value face (interfaces and boundaries), in the geometry's `value_faces` order.
    face_value: Vec<f64>,
    // Per face: heat into the first cell, and the conductance in the stability limit.
    face_heat: Vec<f64>,
    face_conductance: Vec<f64>,
    // Per channel.
    pub(crate) channel_conductance: Vec<f64>,
    channel_heat: Vec<f64>,
    // Per cell: net heat inflow of the first sub-step [W].
    net_heat: Vec<f64>,
}

fn non_finite_temperature(state: &HeatState, cell: usize, time: f64) -> HeatError {
    HeatError::NonFinite {
        quantity: "temperature",
        cell,
        step: state.steps,
        time,
        value: state.temperature[cell],
    }
}

fn check_dt(dt: f64) -> Result<(), HeatError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(HeatError::ParameterOutOfRange {
            field: "dt".to_owned(),
            range: "> 0 s",
            value: dt,
        })
    }
}

impl HeatStepper {
    /// An empty stepper; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Advances `state` by `dt` \[s\]: prepares the coefficients once, then takes as many equal
    /// explicit sub-steps as the stability limit requires. `geometry` must have been built
    /// (or updated) for `mesh` as it is now.
    pub fn step(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        dt: f64,
    ) -> Result<StepReport, HeatError> {
        check_dt(dt)?;
        self.prepare(model, geometry, mesh, input, state)?;
        let t0 = state.time;
        // The heat rates of the first sub-step do not depend on its length, and the face pass
        // that computes them also gives the face conductances of the stability limit: one pass
        // over the mesh yields both, and the limit then sets the length.
        self.heat_rates(model, geometry, mesh, input, &state.temperature, t0, true);
        boundary_faces(
            geometry,
            &mut self.boundary_face_list,
            &mut self.boundary_face_side,
        );
        let limit = self.net_heat_and_stability_limit(geometry, mesh, input);
        let allowed = model.stability_safety * limit;
        let substeps = if allowed.is_finite() {
            ((dt / allowed).ceil() as usize).max(1)
        } else {
            1
        };
        let h = dt / substeps as f64;
        self.boundary_energy = h * self.boundary_heat_rate();
        self.boundary_energy_by_side = [0.0; 5];
        self.add_boundary_energy_by_side(h);
        if let Some(c) = self.apply_net_heat(&mut state.temperature, h) {
            return Err(non_finite_temperature(state, c, t0));
        }
        state.time = t0 + h;
        state.steps += 1;
        for k in 1..substeps {
            let t = t0 + k as f64 * h;
            self.substep(model, geometry, mesh, input, state, t, h)?;
            state.time = t0 + (k + 1) as f64 * h;
            state.steps += 1;
        }
        state.time = t0 + dt;
        Ok(StepReport {
            substeps,
            substep: h,
            stability_limit: limit,
        })
    }

    /// Energy \[J\] that entered the domain through its outer boundary during the last
    /// [`Self::step`] or [`Self::implicit_step`]: conduction (cases I–III) and the enthalpy
    /// `ṁ c_p (T − T_ref)` of the fluid that crossed it. With it, the change of
    /// `Σ C (T − T_ref)` over a step is accounted for to round-off.
    pub fn boundary_energy(&self) -> f64 {
        self.boundary_energy
    }

    /// [`Self::boundary_energy`] by boundary side, indexed left, right, bottom, top, outline
    /// (`thm_vpn_mesh::BoundarySide`'s order): the energy \[J\] that entered through each
    /// during the last step. Through a side held at a temperature at steady state it is the
    /// heat rate through the specimen times the step.
    pub fn boundary_energy_by_side(&self) -> [f64; 5] {
        self.boundary_energy_by_side
    }

    /// Adds `h` × the heat rate of the last face pass through each boundary side to
    /// `boundary_energy_by_side`.
    fn add_boundary_energy_by_side(&mut self, h: f64) {
        for (&f, &side) in self.boundary_face_list.iter().zip(&self.boundary_face_side) {
            self.boundary_energy_by_side[side as usize] += h * self.face_heat[f as usize];
        }
    }

    /// Σ over the boundary faces of the heat rate into the domain of the last face pass \[W\],
    /// in face order.
    fn boundary_heat_rate(&self) -> f64 {
        self.boundary_face_list
            .iter()
            .map(|&f| self.face_heat[f as usize])
            .sum()
    }

    /// The explicit stability limit \[s\] for this mesh, model and input (without the safety
    /// factor): min over cells of C_i / (Σ conductances + 3 Σ outflow ṁ c_p).
    pub fn stable_time_step(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &HeatState,
    ) -> Result<f64, HeatError> {
        self.prepare(model, geometry, mesh, input, state)?;
        Ok(self.stability_limit(model, geometry, mesh, input))
    }

    /// One explicit sub-step of length `h` from time `t` with the coefficients of the last
    /// [`Self::prepare`].
    #[allow(clippy::too_many_arguments)]
    fn substep(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        t: f64,
        h: f64,
    ) -> Result<(), HeatError> {
        self.heat_rates(model, geometry, mesh, input, &state.temperature, t, false);
        self.boundary_energy += h * self.boundary_heat_rate();
        self.add_boundary_energy_by_side(h);
        if let Some(c) = self.advance(geometry, mesh, &mut state.temperature, h) {
            return Err(non_finite_temperature(state, c, t));
        }
        Ok(())
    }

    /// Stages 1–4 at time `t`: face values, gradients and limiters, face heat (with the
    /// stability conductances where `conductances`), channel heat.
    #[allow(clippy::too_many_arguments)]
    fn heat_rates(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
        t: f64,
        conductances: bool,
    ) {
        self.face_values(model, geometry, mesh, temp, t);
        self.gradients(model, geometry, mesh, temp);
        if conductances {
            self.face_heat_and_conductances(model, geometry, mesh, input, temp, t);
        } else {
            self.face_heat(model, geometry, mesh, input, temp, t);
        }
        self.channel_heat(model, geometry, mesh, input, temp);
    }

    /// Stage 0: checks the geometry against the mesh, the state and the input, then computes
    /// the per-cell capacities and conductivities (A-Eqs. 32–36 in fluid cells) in the same
    /// pass over the cells as the range checks of the temperatures and the fluid entries, the
    /// laws of the fluid–solid interface faces (h_f of A-Eqs. 43–45) and the S2S channel
    /// conductances (A-Eq. 40). No allocation after the first call. Errors are those of the
    /// separate checks in their order: temperature, then [`FlowInput::validate`].
    pub fn prepare(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &HeatState,
    ) -> Result<(), HeatError> {
        geometry.check(mesh)?;
        let n = mesh.n_cells();
        if state.temperature.len() != n {
            return Err(HeatError::LengthMismatch {
                what: "temperature",
                expected: n,
                got: state.temperature.len(),
            });
        }
        let temp = &state.temperature;
        let temperature_error = |c: usize| HeatError::InputOutOfRange {
            quantity: "temperature",
            index: c,
            range: "finite and > 0 K",
            value: temp[c],
        };
        if let Err(e) = input.check_lengths(mesh) {
            if let Some(c) = first_where(n, |c| !temperature_ok(temp[c])) {
                return Err(temperature_error(c));
            }
            return Err(e);
        }
        let (bad_temperature, bad_fluid) = self.prepare_cells(model, geometry, mesh, input, temp);
        if let Some(c) = bad_temperature {
            return Err(temperature_error(c));
        }
        if let Some(c) = bad_fluid {
            return Err(input.fluid_entry_error(c));
        }
        input.check_fluxes(mesh)?;
        self.prepare_interfaces(geometry);
        self.prepare_channels(mesh);
        let nf = mesh.n_faces();
        self.gradient.resize(n, [0.0; 2]);
        self.limiter.resize(n, 1.0);
        self.face_value.resize(geometry.value_faces.len(), 0.0);
        self.face_heat.resize(nf, 0.0);
        self.face_conductance.resize(nf, 0.0);
        self.net_heat.resize(n, 0.0);
        self.channel_heat.resize(mesh.channels.len(), 0.0);
        Ok(())
    }

    /// Part of [`Self::prepare`] (sizes of `input` and `temp` checked against the mesh):
    /// capacity C = V (ρc), conductivity and specific heat of every cell (mixture A-Eqs. 32–36
    /// in fluid cells), and, for fluid cells with an interface face, their share of the
    /// interface coefficient (A-Eqs. 43–45) from the mixture and the fastest channel speed
    /// |ṁ| / (ρ_eff h b). Returns the first cell whose temperature is not finite and > 0 K,
    /// and the first fluid cell whose entries of `input` are out of range.
    pub fn prepare_cells(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
    ) -> (Option<usize>, Option<usize>) {
        let n = mesh.n_cells();
        self.capacity.resize(n, 0.0);
        self.conductivity.resize(n, 0.0);
        self.specific_heat.resize(n, 0.0);
        self.exchange.resize(n, ExchangeFactors::default());
        let b = mesh.thickness;
        let solid = model.solid;
        let start = &geometry.cell_channel_start;
        let cell_channel = &geometry.cell_channel;
        let flags = &geometry.cell_flags;
        let scale = &geometry.solid_capacity_scale;
        let ch = &mesh.channels;
        (
            self.capacity.par_chunks_mut(GRAIN),
            self.conductivity.par_chunks_mut(GRAIN),
            self.specific_heat.par_chunks_mut(GRAIN),
            self.exchange.par_chunks_mut(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .map(|(chunk, (cap, lam, cp, exchange))| {
                // Chunk-local views of the same length as the outputs.
                let (lo, len) = (chunk * GRAIN, cap.len());
                let temp = &temp[lo..lo + len];
                let area = &mesh.cell_area[lo..lo + len];
                let flags = &flags[lo..lo + len];
                let alpha = &input.liquid_fraction[lo..lo + len];
                let rho_q = &input.liquid_density[lo..lo + len];
                let rho_p = &input.gas_density[lo..lo + len];
                let (mut bad_temperature, mut bad_fluid) = (None, None);
                for i in 0..len {
                    if bad_temperature.is_none() && !temperature_ok(temp[i]) {
                        bad_temperature = Some(lo + i);
                    }
                    let volume = area[i] * b;
                    let flag = flags[i];
                    if flag & CELL_FLUID == 0 {
                        let f = scale.get(lo + i).copied().unwrap_or(1.0);
                        cap[i] = volume * solid.volumetric_heat_capacity() * f;
                        lam[i] = solid.conductivity;
                        cp[i] = solid.specific_heat;
                        continue;
                    }
                    let (a, rq, rp) = (alpha[i], rho_q[i], rho_p[i]);
                    if bad_fluid.is_none() && !fluid_entry_ok(a, rq, rp) {
                        bad_fluid = Some(lo + i);
                    }
                    let mix = model.fluid_mixture(a, rq, rp);
                    cap[i] = volume * mix.volumetric_heat_capacity;
                    lam[i] = mix.conductivity;
                    cp[i] = mix.specific_heat;
                    if flag & CELL_INTERFACE != 0 {
                        exchange[i] = ExchangeFactors::pending(
                            &mix,
                            fastest_channel_x(
                                &cell_channel[start[lo + i] as usize..start[lo + i + 1] as usize],
                                ch,
                                input,
                                b,
                                &mix,
                            ),
                            pure_phase_prandtl_cbrt(model, a),
                        );
                    }
                }
                for (e, &flag) in exchange.iter_mut().zip(flags) {
                    // Only fluid cells carry the interface flag.
                    if flag & CELL_INTERFACE != 0 {
                        e.complete_powers();
                    }
                }
                (bad_temperature, bad_fluid)
            })
            .reduce(|| (None, None), |a, b| (a.0.or(b.0), a.1.or(b.1)))
    }

    /// Part of [`Self::prepare`]: the law of every fluid–solid interface face (case IV) from
    /// the cell properties of [`Self::prepare_cells`]: h_f (A-Eq. 45) from the fluid cell's
    /// mixture and fastest channel speed, in series with the solid's half cell λ_s / d_{r,c}:
    /// with G_f = h_f |A| and G_s = λ_s |A| / d_{r,c} (cached in the geometry), the face
    /// conducts G_f G_s / (G_f + G_s) and the interface temperature weighs the fluid cell by
    /// G_f / (G_f + G_s).
    pub fn prepare_interfaces(&mut self, geometry: &HeatGeometry) {
        let faces = &geometry.interface;
        self.interface_law
            .resize(faces.len(), InterfaceLaw::default());
        let exchange = &self.exchange;
        let diameter = &geometry.sphere_diameter_powers;
        let porosity = geometry.porosity;
        self.interface_law
            .par_iter_mut()
            .with_min_len(GRAIN)
            .zip(faces.par_iter())
            .for_each(|(law, face)| {
                let dp = diameter
                    .get(face.owner as usize)
                    .copied()
                    .unwrap_or_default();
                let (gf, gs) = (
                    exchange[face.fluid_cell as usize].coefficient(porosity, &dp) * face.area,
                    face.solid_conductance,
                );
                let (g, wf) = if gf + gs > 0.0 {
                    let r = 1.0 / (gf + gs);
                    (gf * gs * r, gf * r)
                } else {
                    (0.0, 0.5)
                };
                let w0 = if face.fluid_first { wf } else { 1.0 - wf };
                *law = InterfaceLaw { g, w0 };
            });
    }

    /// Part of [`Self::prepare`]: S2S conductance λ_eff A_k / L_k with A_k = h b (A-Eq. 40),
    /// λ_eff the mean of the two cells; zero for T2T channels, whose diffusion is part of the
    /// face laws.
    pub fn prepare_channels(&mut self, mesh: &PoreMesh) {
        let ch = &mesh.channels;
        let lam = &self.conductivity;
        let b = mesh.thickness;
        self.channel_conductance.resize(ch.len(), 0.0);
        self.channel_conductance
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(k, g)| {
                *g = match ch.kind[k] {
                    ChannelKind::T2T => 0.0,
                    ChannelKind::S2S => {
                        let [a, c] = ch.cells[k];
                        let lambda = 0.5 * (lam[a as usize] + lam[c as usize]);
                        let l = ch.length[k];
                        if l > 0.0 {
                            lambda * ch.aperture[k] * b / l
                        } else {
                            0.0
                        }
                    }
                };
            });
    }

    /// The explicit stability limit \[s\] with the coefficients of the last [`Self::prepare`]
    /// (without the safety factor): min over cells of C_i / (Σ conductances + 3 Σ outflow
    /// ṁ c_p); a face conducts λ_f |A| / (ds n·e_s) inside a medium, the series conductance of
    /// an interface, and at a boundary the conductance of its case plus 2 ṁ c_p of an outflow.
    /// [`Self::step`] gets the same number from the face pass of its first sub-step
    /// ([`Self::face_heat_and_conductances`], [`Self::net_heat_and_stability_limit`]); this
    /// stage computes it alone.
    pub fn stability_limit(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
    ) -> f64 {
        self.face_conductance.resize(mesh.n_faces(), 0.0);
        let lam = &self.conductivity;
        let cp = &self.specific_heat;
        let law = &self.interface_law;
        (
            self.face_conductance.par_chunks_mut(GRAIN),
            mesh.face_cells.par_chunks(GRAIN),
            geometry.face.par_chunks(GRAIN),
            input.boundary_mass_flux.par_chunks(GRAIN),
        )
            .into_par_iter()
            .for_each(|(conductance, cells, faces, outflow)| {
                for (((g, &[c0, c1]), geo), &m) in
                    conductance.iter_mut().zip(cells).zip(faces).zip(outflow)
                {
                    *g = face_stability_conductance(
                        model,
                        geometry,
                        law,
                        geo,
                        lam,
                        cp,
                        c0 as usize,
                        c1,
                        m,
                    );
                }
            });
        self.cell_sums::<false>(geometry, mesh, input)
    }

    /// After [`Self::face_heat_and_conductances`] and [`Self::channel_heat`]: the net heat
    /// inflow of every cell (kept for [`Self::apply_net_heat`]) and, in the same pass over the
    /// cells, the stability limit of [`Self::stability_limit`] (the same bits).
    pub fn net_heat_and_stability_limit(
        &mut self,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
    ) -> f64 {
        self.cell_sums::<true>(geometry, mesh, input)
    }

    /// T ← T + h (net heat) / C with the net heat of [`Self::net_heat_and_stability_limit`]
    /// (the same update as [`Self::advance`]). Returns the first cell whose new temperature is
    /// not finite.
    pub fn apply_net_heat(&self, temp: &mut [f64], h: f64) -> Option<usize> {
        (
            temp.par_chunks_mut(GRAIN),
            self.net_heat.par_chunks(GRAIN),
            self.capacity.par_chunks(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .map(|(chunk, (temp, net, cap))| {
                let mut bad = None;
                for (i, ((t, &s), &cap)) in temp.iter_mut().zip(net).zip(cap).enumerate() {
                    *t += h * s / cap;
                    if bad.is_none() && !t.is_finite() {
                        bad = Some(chunk * GRAIN + i);
                    }
                }
                bad
            })
            .reduce(|| None, |a, b| a.or(b))
    }

    /// One pass over the cells: the stability limit from the face conductances (stored by
    /// the last face pass) and the channels, and, with `HEAT`, each cell's net heat inflow
    /// from the face and channel heat, gathered in the order of [`Self::advance`].
    fn cell_sums<const HEAT: bool>(
        &mut self,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
    ) -> f64 {
        let n = mesh.n_cells();
        self.net_heat.resize(n, 0.0);
        let start = &geometry.cell_channel_start;
        let cell_channel = &geometry.cell_channel;
        let (qf, qc, gf, gc) = (
            &self.face_heat,
            &self.channel_heat,
            &self.face_conductance,
            &self.channel_conductance,
        );
        let (cap, cp) = (&self.capacity, &self.specific_heat);
        let flux = &input.channel_mass_flux;
        (
            self.net_heat.par_chunks_mut(GRAIN),
            mesh.cell_faces.par_chunks(GRAIN),
            geometry.cell_flags.par_chunks(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .map(|(chunk, (net, faces, flags))| {
                let lo = chunk * GRAIN;
                let start = &start[lo..=lo + net.len()];
                let (cap, cp) = (&cap[lo..lo + net.len()], &cp[lo..lo + net.len()]);
                let mut best = f64::INFINITY;
                for (i, ((net, faces), &flag)) in net.iter_mut().zip(faces).zip(flags).enumerate() {
                    let (mut heat, mut conductance) = (0.0, 0.0);
                    for (j, &f) in faces.iter().enumerate() {
                        let f = f as usize;
                        conductance += gf[f];
                        if HEAT {
                            if flag & (CELL_FIRST << j) != 0 {
                                heat += qf[f];
                            } else {
                                heat -= qf[f];
                            }
                        }
                    }
                    for &(k, second) in &cell_channel[start[i] as usize..start[i + 1] as usize] {
                        let k = k as usize;
                        if HEAT {
                            if second {
                                heat += qc[k];
                            } else {
                                heat -= qc[k];
                            }
                        }
                        conductance += gc[k];
                        let m = flux[k];
                        let out = if second { -m } else { m };
                        if out > 0.0 {
                            conductance += ADVECTIVE_FACTOR * out * input.channel_cp(k, cp[i]);
                        }
                    }
                    if HEAT {
                        *net = heat;
                    }
                    // Capacities and conductances of checked input are finite and >= 0: the
                    // limit is a number or +∞, and `min` is exact and order-independent.
                    let limit = if conductance > 0.0 {
                        cap[i] / conductance
                    } else {
                        f64::INFINITY
                    };
                    best = best.min(limit);
                }
                best
            })
            .reduce(|| f64::INFINITY, f64::min)
    }

    /// Stage 1: the temperatures of the faces whose value enters the gradients and limiters
    /// in place of a neighbour cell: the interface temperature of case IV and the boundary
    /// values of cases I–III at time `t`. (Faces inside a medium use the neighbour cell in the
    /// least-squares stencil and the arithmetic mean A-Eq. 42 in Green–Gauss, formed where
    /// they are used.)
    pub fn face_values(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        temp: &[f64],
        t: f64,
    ) {
        let lam = &self.conductivity;
        let law = &self.interface_law;
        let boundary = &geometry.boundary;
        let sides: [f64; 5] = std::array::from_fn(|k| match &model.sides[k] {
            SideCondition::Temperature(s) => s.at(t),
            _ => 0.0,
        });
        self.face_value
            .par_iter_mut()
            .with_min_len(GRAIN)
            .zip(geometry.value_faces.par_iter())
            .for_each(|(tf, &f)| {
                let f = f as usize;
                let [c0, c1] = mesh.face_cells[f];
                let t0 = temp[c0 as usize];
                *tf = match geometry.face[f] {
                    FaceGeometry::Diffusive { .. } => 0.5 * (t0 + temp[c1 as usize]),
                    FaceGeometry::Interface { index, .. } => {
                        let w0 = law[index as usize].w0;
                        w0 * t0 + (1.0 - w0) * temp[c1 as usize]
                    }
                    FaceGeometry::Boundary { slot } => {
                        let bf = &boundary[slot as usize];
                        let (conductivity, normal_distance) =
                            (lam[c0 as usize], bf.normal_distance);
                        match &model.sides[bf.side as usize] {
                            SideCondition::Temperature(_) => sides[bf.side as usize],
                            SideCondition::HeatFlux(q) => {
                                if conductivity > 0.0 {
                                    t0 + normal_distance * q / conductivity
                                } else {
                                    t0
                                }
                            }
                            SideCondition::Convective {
                                coefficient,
                                ambient,
                            } => {
                                let k = conductivity / normal_distance;
                                if k + coefficient > 0.0 {
                                    (k * t0 + coefficient * ambient) / (k + coefficient)
                                } else {
                                    t0
                                }
                            }
                        }
                    }
                };
            });
    }

    /// Stage 2, one pass over the cells: the cell gradient and, in fluid cells, its
    /// Barth–Jespersen limiter ψ ∈ [0, 1]. Gradients: least squares (default; rows
    /// e_k · ∇T = ΔT_k / |d_k| with unit directions to the neighbour centroid in the same
    /// medium or to the face centroid for interface and boundary face values, and Neumann
    /// rows n · ∇T = q / λ on prescribed-flux faces; weights cached in the geometry) or
    /// Green–Gauss (A-Eq. 41) with the arithmetic face mean A-Eq. 42 inside a medium and the
    /// face values of stage 1 elsewhere. The limiter keeps the reconstruction A-Eq. 48 at
    /// every face centroid within the range of the cell, its stencil values (neighbour cells,
    /// interface and boundary face values) and its other channel partners (S2S).
    pub fn gradients(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        temp: &[f64],
    ) {
        let tv = &self.face_value;
        let source = &geometry.stencil_source;
        let weight = &geometry.stencil_weight;
        let offset = &geometry.stencil_offset;
        let flags = &geometry.cell_flags;
        let start = &geometry.extra_partner_start;
        let partner = &geometry.extra_partner;
        let scheme = model.gradient;
        (
            self.gradient.par_chunks_mut(GRAIN),
            self.limiter.par_chunks_mut(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(chunk, (gradient, limiter))| {
                let lo = chunk * GRAIN;
                let hi = lo + gradient.len();
                for (i, ((((((g, psi), &tc), src), w), offset), &flag)) in gradient
                    .iter_mut()
                    .zip(limiter.iter_mut())
                    .zip(&temp[lo..hi])
                    .zip(&source[lo..hi])
                    .zip(&weight[lo..hi])
                    .zip(&offset[lo..hi])
                    .zip(&flags[lo..hi])
                    .enumerate()
                {
                    let c = lo + i;
                    let v = src.map(|s| stencil_value(s, temp, tv));
                    let grad = match scheme {
                        GradientScheme::LeastSquares => {
                            let mut s = [0.0; 2];
                            for k in 0..3 {
                                let dt = v[k] - tc;
                                s[0] += w[k][0] * dt;
                                s[1] += w[k][1] * dt;
                            }
                            s
                        }
                        GradientScheme::GreenGauss => green_gauss(mesh, flag, c, tc, src, &v),
                    };
                    *g = grad;
                    *psi = if flag & CELL_FLUID == 0 {
                        1.0
                    } else {
                        let partners = &partner[start[c] as usize..start[c + 1] as usize];
                        limiter_of(tc, &v, partners, temp, grad, offset)
                    };
                }
            });
    }
}

/// Barth–Jespersen ψ ∈ [0, 1] of a fluid cell at `tc` with gradient `grad`: the bounds are
/// the cell, its stencil values `v` and the temperatures of its extra `partners`; `offset`
/// are the face centroids relative to the cell centroid.
#[inline]
fn limiter_of(
    tc: f64,
    v: &[f64; 3],
    partners: &[u32],
    temp: &[f64],
    grad: [f64; 2],
    offset: &[[f64; 2]; 3],
) -> f64 {
    let (mut lo, mut hi) = (tc, tc);
    for &value in v.iter() {
        lo = lo.min(value);
        hi = hi.max(value);
    }
    for &other in partners {
        let value = temp[other as usize];
        lo = lo.min(value);
        hi = hi.max(value);
    }
    let mut p = 1.0f64;
    for r in offset {
        let d = dot(grad, *r);
        if d > 0.0 {
            p = p.min((hi - tc) / d);
        } else if d < 0.0 {
            p = p.min((lo - tc) / d);
        }
    }
    p.clamp(0.0, 1.0)
}

impl HeatStepper {
    /// Stage 3: heat into the first cell of each face \[W\]: A-Eq. 47 inside a medium, the
    /// series conductance at fluid–solid interfaces, cases I–III and advection through open
    /// boundary faces.
    pub fn face_heat(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
        t: f64,
    ) {
        self.face_pass::<false>(model, geometry, mesh, input, temp, t);
    }

    /// Stage 3 of the first sub-step of [`Self::step`]: [`Self::face_heat`] and, in the same
    /// pass, each face's conductance in the stability limit (as in [`Self::stability_limit`]).
    pub fn face_heat_and_conductances(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
        t: f64,
    ) {
        self.face_pass::<true>(model, geometry, mesh, input, temp, t);
    }

    fn face_pass<const CONDUCTANCE: bool>(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
        t: f64,
    ) {
        let grad = &self.gradient;
        let psi = &self.limiter;
        let cp = &self.specific_heat;
        let lam = &self.conductivity;
        let law = &self.interface_law;
        let boundary = &geometry.boundary;
        let t_ref = model.reference_temperature;
        let sides: [f64; 5] = std::array::from_fn(|k| match &model.sides[k] {
            SideCondition::Temperature(s) => s.at(t),
            _ => 0.0,
        });
        // Written only with `CONDUCTANCE`; sized here so that the zip covers every face.
        self.face_conductance.resize(mesh.n_faces(), 0.0);
        (
            self.face_heat.par_chunks_mut(GRAIN),
            self.face_conductance.par_chunks_mut(GRAIN),
            mesh.face_cells.par_chunks(GRAIN),
            geometry.face.par_chunks(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(chunk, (heat, conductance, cells, faces))| {
                for (i, ((q, &[c0, c1]), geo)) in heat.iter_mut().zip(cells).zip(faces).enumerate()
                {
                    let f = chunk * GRAIN + i;
                    let c0 = c0 as usize;
                    let t0 = temp[c0];
                    if CONDUCTANCE {
                        conductance[i] = face_stability_conductance(
                            model,
                            geometry,
                            law,
                            geo,
                            lam,
                            cp,
                            c0,
                            c1,
                            input.boundary_mass_flux[f],
                        );
                    }
                    *q = match *geo {
                        FaceGeometry::Diffusive {
                            conductance,
                            cross,
                            weight0,
                        } => {
                            let c1 = c1 as usize;
                            let lf = face_conductivity(lam[c0], lam[c1], weight0);
                            let (g0, g1) = (grad[c0], grad[c1]);
                            let mean = [0.5 * (g0[0] + g1[0]), 0.5 * (g0[1] + g1[1])];
                            let two_point = lf * conductance * (temp[c1] - t0);
                            two_point
                                + limit_cross(
                                    dot([lf * cross[0], lf * cross[1]], mean),
                                    two_point,
                                    model.cross_limit,
                                )
                        }
                        FaceGeometry::Interface { index, .. } => {
                            law[index as usize].g * (temp[c1 as usize] - t0)
                        }
                        FaceGeometry::Boundary { slot } => {
                            let BoundaryFace {
                                side,
                                normal_distance,
                                area,
                                tangent,
                            } = boundary[slot as usize];
                            let conductivity = lam[c0];
                            let cond = &model.sides[side as usize];
                            // Temperature at the foot of the normal through the face centroid.
                            let t_foot = |outside: f64| {
                                t0 + boundary_correction(
                                    grad[c0],
                                    tangent,
                                    outside,
                                    t0,
                                    model.cross_limit,
                                )
                            };
                            let diffusive = match cond {
                                SideCondition::Temperature(_) => {
                                    let outside = sides[side as usize];
                                    conductivity * area / normal_distance
                                        * (outside - t_foot(outside))
                                }
                                SideCondition::HeatFlux(flux) => flux * area,
                                SideCondition::Convective { ambient, .. } => {
                                    boundary_conductance(cond, conductivity, normal_distance, area)
                                        * (ambient - t_foot(*ambient))
                                }
                            };
                            let m = input.boundary_mass_flux[f];
                            let advective = if m > 0.0 {
                                let r = sub(mesh.face_centroid[f], mesh.cell_centroid[c0]);
                                let tface = t0 + psi[c0] * dot(grad[c0], r);
                                -m * cp[c0] * (tface - t_ref)
                            } else if m < 0.0 {
                                let t_in = match cond {
                                    SideCondition::Temperature(_) => sides[side as usize],
                                    _ => t0,
                                };
                                -m * cp[c0] * (t_in - t_ref)
                            } else {
                                0.0
                            };
                            diffusive + advective
                        }
                    };
                }
            });
    }

    /// Stage 4: heat carried along each channel from its first to its second cell \[W\]:
    /// advection ṁ c_p (T_f − T_ref) with the limited second-order upwind value T_f (A-Eq. 48)
    /// at the shared face of T2T channels (first-order upwind in S2S channels, which have no
    /// face) and, in S2S channels, conduction λ_eff A_k (T_i − T_j) / L_k (A-Eq. 40).
    pub fn channel_heat(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
    ) {
        let grad = &self.gradient;
        let psi = &self.limiter;
        let cp = &self.specific_heat;
        let g = &self.channel_conductance;
        let points = &geometry.channel_point;
        let t_ref = model.reference_temperature;
        let ch = &mesh.channels;
        (
            self.channel_heat.par_chunks_mut(GRAIN),
            ch.cells.par_chunks(GRAIN),
            ch.kind.par_chunks(GRAIN),
            input.channel_mass_flux.par_chunks(GRAIN),
            points.par_chunks(GRAIN),
            g.par_chunks(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(chunk, (heat, cells, kinds, fluxes, points, g))| {
                for (i, (((((q, cells), kind), &m), point), &g)) in heat
                    .iter_mut()
                    .zip(cells)
                    .zip(kinds)
                    .zip(fluxes)
                    .zip(points)
                    .zip(g)
                    .enumerate()
                {
                    let [a, b] = cells.map(|c| c as usize);
                    let adv = if m != 0.0 {
                        let up = if m > 0.0 { a } else { b };
                        let tf = match kind {
                            ChannelKind::T2T => {
                                let r = sub(*point, mesh.cell_centroid[up]);
                                temp[up] + psi[up] * dot(grad[up], r)
                            }
                            // No face: first-order upwind.
                            ChannelKind::S2S => temp[up],
                        };
                        m * input.channel_cp(chunk * GRAIN + i, cp[up]) * (tf - t_ref)
                    } else {
                        0.0
                    };
                    *q = adv + g * (temp[a] - temp[b]);
                }
            });
    }

    /// Stage 5: T ← T + h (Σ heat in) / C per cell (A-Eqs. 39, 50), gathering face and channel
    /// heat in a fixed order. Returns the first cell whose new temperature is not finite.
    pub fn advance(
        &mut self,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        temp: &mut [f64],
        h: f64,
    ) -> Option<usize> {
        let qf = &self.face_heat;
        let qc = &self.channel_heat;
        let cap = &self.capacity;
        let flags = &geometry.cell_flags;
        let start = &geometry.cell_channel_start;
        let cell_channel = &geometry.cell_channel;
        (
            temp.par_chunks_mut(GRAIN),
            mesh.cell_faces.par_chunks(GRAIN),
            flags.par_chunks(GRAIN),
            cap.par_chunks(GRAIN),
        )
            .into_par_iter()
            .enumerate()
            .map(|(chunk, (temp, faces, flags, cap))| {
                let lo = chunk * GRAIN;
                let start = &start[lo..=lo + temp.len()];
                let mut bad = None;
                for (i, ((((t, faces), &flag), &cap), range)) in temp
                    .iter_mut()
                    .zip(faces)
                    .zip(flags)
                    .zip(cap)
                    .zip(start.windows(2))
                    .enumerate()
                {
                    let mut s = 0.0;
                    for (j, &f) in faces.iter().enumerate() {
                        if flag & (CELL_FIRST << j) != 0 {
                            s += qf[f as usize];
                        } else {
                            s -= qf[f as usize];
                        }
                    }
                    for &(k, second) in &cell_channel[range[0] as usize..range[1] as usize] {
                        let q = qc[k as usize];
                        if second {
                            s += q;
                        } else {
                            s -= q;
                        }
                    }
                    *t += h * s / cap;
                    if bad.is_none() && !t.is_finite() {
                        bad = Some(lo + i);
                    }
                }
                bad
            })
            .reduce(|| None, |a, b| a.or(b))
    }

    /// Total enthalpy Σ C_i (T_i − T_ref) \[J\] of all cells, with the capacities of the last
    /// [`Self::prepare`] (summed serially in cell order).
    pub fn total_enthalpy(&self, model: &HeatModel, temp: &[f64]) -> f64 {
        self.capacity
            .iter()
            .zip(temp)
            .map(|(c, t)| c * (t - model.reference_temperature))
            .sum()
    }

    /// Heat capacity C_i = V_i (ρ c)_i of each cell \[J/K\] from the last [`Self::prepare`].
    pub fn heat_capacity(&self) -> &[f64] {
        &self.capacity
    }
}

/// The non-orthogonal correction of a boundary face: the temperature difference
/// `∇T · t` between the face centroid and the foot of the normal through the cell centroid
/// (`t` the boundary face's tangential offset), limited as the cross term of a face inside a
/// medium ([`limit_cross`]) against the two-point difference `outside − cell` of the face.
/// Unlimited, a thin cell along the boundary whose gradient is steep (a sliver between a
/// circle and a box side, next to a held end) turned it into a flux that cooled the cell
/// below the held temperature.
#[inline]
pub(crate) fn boundary_correction(
    gradient: [f64; 2],
    tangent: [f64; 2],
    outside: f64,
    cell: f64,
    limit: Option<f64>,
) -> f64 {
    limit_cross(dot(gradient, tangent), outside - cell, limit)
}

/// The cross-diffusion heat rate `cross` of a face, capped at `limit` times the magnitude of
/// its two-point rate (`None`: as computed). See [`crate::CrossDiffusion`].
#[inline]
pub(crate) fn limit_cross(cross: f64, two_point: f64, limit: Option<f64>) -> f64 {
    match limit {
        None => cross,
        Some(ratio) => {
            let cap = ratio * two_point.abs();
            cross.clamp(-cap, cap)
        }
    }
}

/// Conductance \[W/K\] of one face in the stability limit: λ_f |A| / (ds n·e_s) inside a
/// medium (A-Eq. 47's primary term), the series conductance of a fluid–solid interface, and
/// at an outer boundary the conductance of its case plus 2 ṁ c_p where fluid flows out (`m`,
/// the face's boundary mass flux, positive outward).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn face_stability_conductance(
    model: &HeatModel,
    geometry: &HeatGeometry,
    law: &[InterfaceLaw],
    geo: &FaceGeometry,
    lam: &[f64],
    cp: &[f64],
    c0: usize,
    c1: u32,
    m: f64,
) -> f64 {
    match *geo {
        FaceGeometry::Diffusive {
            conductance,
            weight0,
            ..
        } => {
            // A limited cross term can add up to `ratio` times the two-point rate.
            face_conductivity(lam[c0], lam[c1 as usize], weight0)
                * conductance
                * (1.0 + model.cross_limit.unwrap_or(0.0))
        }
        FaceGeometry::Interface { index, .. } => law[index as usize].g,
        FaceGeometry::Boundary { slot } => {
            let bf = &geometry.boundary[slot as usize];
            let adv = if m > 0.0 { 2.0 * m * cp[c0] } else { 0.0 };
            adv + boundary_conductance(
                &model.sides[bf.side as usize],
                lam[c0],
                bf.normal_distance,
                bf.area,
            )
        }
    }
}

/// Green–Gauss gradient (A-Eq. 41) of cell `c` from its stencil values `v`: the arithmetic
/// mean A-Eq. 42 where the source is a neighbour cell, the face value otherwise.
fn green_gauss(
    mesh: &PoreMesh,
    flag: u8,
    c: usize,
    tc: f64,
    source: &[u32; 3],
    v: &[f64; 3],
) -> [f64; 2] {
    let mut s = [0.0; 2];
    for (k, &f) in mesh.cell_faces[c].iter().enumerate() {
        let f = f as usize;
        let tf = if source[k] & FACE_VALUE != 0 {
            v[k]
        } else {
            0.5 * (tc + v[k])
        };
        let sign = if flag & (CELL_FIRST << k) != 0 {
            1.0
        } else {
            -1.0
        };
        let w = sign * tf * mesh.face_length[f];
        s[0] += w * mesh.face_normal[f][0];
        s[1] += w * mesh.face_normal[f][1];
    }
    let inv = 1.0 / mesh.cell_area[c];
    [s[0] * inv, s[1] * inv]
}

#[inline]
fn temperature_ok(t: f64) -> bool {
    // Finite and > 0 K (false for NaN).
    (t > 0.0) & (t < f64::INFINITY)
}

#[inline]
fn stencil_value(source: u32, temp: &[f64], face_value: &[f64]) -> f64 {
    if source & FACE_VALUE != 0 {
        face_value[(source & !FACE_VALUE) as usize]
    } else {
        temp[source as usize]
    }
}

/// Conductance \[W/K\] between a boundary cell and its surroundings: λ|A|/d_n for case I,
/// |A| / (1/h_e + d_n/λ) for case III, 0 for case II (the flux is prescribed).
pub(crate) fn boundary_conductance(
    cond: &SideCondition,
    conductivity: f64,
    normal_distance: f64,
    area: f64,
) -> f64 {
    match cond {
        SideCondition::Temperature(_) => conductivity * area / normal_distance,
        SideCondition::HeatFlux(_) => 0.0,
        SideCondition::Convective { coefficient, .. } => {
            let k = conductivity / normal_distance;
            if k + coefficient > 0.0 {
                area * k * coefficient / (k + coefficient)
            } else {
                0.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HeatParams;
    use crate::properties::{REYNOLDS_SWITCH, interface_coefficient};
    use thm_vpn_mesh::{CellKind, NONE};

    /// The interface law of [`HeatStepper::prepare`] (factored coefficient, the fastest
    /// channel found by cross-multiplication, Pr^{1/3} of a pure phase from the model) equals
    /// A-Eqs. 43–45 evaluated directly, h_f in series with λ_s / d_{r,c}: pure liquid, pure
    /// gas and a mixture, at rest and in both Reynolds ranges.
    #[test]
    fn interface_law_matches_the_direct_correlations() {
        // Left square fluid (two triangles joined by one T2T channel), right square solid.
        let mesh = PoreMesh::structured_rectangle(2, 1, 0.008, 0.004, 0.008, 0.0115, |p| {
            if p[0] < 0.004 {
                CellKind::Fluid
            } else {
                CellKind::Solid { owner: 0 }
            }
        })
        .unwrap();
        let model = HeatModel::new(&HeatParams::paper_a_table_1(), &mesh).unwrap();
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        assert_eq!(geometry.interface.len(), 1);
        assert_eq!(mesh.channels.len(), 1);
        let f = geometry.interface[0].face as usize;
        let [c0, c1] = mesh.face_cells[f];
        assert_ne!(c1, NONE);
        let (cf, cs) = if mesh.cell_kind[c0 as usize].is_fluid() {
            (c0 as usize, c1 as usize)
        } else {
            (c1 as usize, c0 as usize)
        };
        let r = geometry.sphere_radius()[0];
        let (xf, xs) = (mesh.face_centroid[f], mesh.cell_centroid[cs]);
        let d = ((xf[0] - xs[0]).powi(2) + (xf[1] - xs[1]).powi(2)).sqrt();
        let area = mesh.face_length[f] * mesh.thickness;
        let channel_area = mesh.channels.aperture[0] * mesh.thickness;
        let state = HeatState {
            time: 0.0,
            steps: 0,
            temperature: vec![300.0; mesh.n_cells()],
        };
        let mut ranges = [0usize; 3];
        for alpha in [1.0, 0.0, 0.37] {
            for flux in [0.0, 1e-9, -3e-7, 2e-5, -4e-3] {
                let mut input = FlowInput::liquid_at_rest(&mesh, 998.0, 1.2);
                input.liquid_fraction.iter_mut().for_each(|a| *a = alpha);
                input.channel_mass_flux[0] = flux;
                let mut stepper = HeatStepper::new();
                stepper
                    .prepare(&model, &geometry, &mesh, &input, &state)
                    .unwrap();
                let mix = model.fluid_mixture(alpha, 998.0, 1.2);
                let speed = flux.abs() / (mix.density * channel_area);
                let re = mix.density * speed * 2.0 * r / mix.dynamic_viscosity;
                ranges[if re == 0.0 {
                    0
                } else if re <= REYNOLDS_SWITCH {
                    1
                } else {
                    2
                }] += 1;
                let h = interface_coefficient(&mix, geometry.porosity(), speed, r);
                let g = area / (1.0 / h + d / model.solid.conductivity);
                let law = stepper.interface_law[0];
                assert!(
                    (law.g - g).abs() <= 1e-12 * g,
                    "alpha {alpha}, flux {flux}: {} vs {g}",
                    law.g
                );
                let wf = h / (h + model.solid.conductivity / d);
                let w0 = if cf == c0 as usize { wf } else { 1.0 - wf };
                assert!((law.w0 - w0).abs() <= 1e-12, "{} vs {w0}", law.w0);
            }
        }
        assert!(ranges.iter().all(|&n| n > 0), "{ranges:?}");
    }
}
