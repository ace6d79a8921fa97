//! The explicit finite-volume step (A-Eqs. 37–51) with its stability limit and sub-cycling.
//!
//! One outer step is the fixed sequence [`HeatStepper::prepare`] (input checks, cell
//! properties, face and channel conductances from the cached [`HeatGeometry`]) and then, for
//! each sub-step: [`HeatStepper::face_temperatures`] → [`HeatStepper::gradients`] →
//! [`HeatStepper::limiters`] → [`HeatStepper::face_heat`] → [`HeatStepper::channel_heat`] →
//! [`HeatStepper::advance`]. Every stage is a parallel map over cells, faces or channels
//! whose results are gathered per cell in a fixed order, so 1-thread and N-thread runs give
//! identical bits.

use rayon::prelude::*;
use thm_vpn_mesh::{ChannelKind, PoreMesh};

use crate::geometry::{BoundaryFace, FACE_VALUE, FaceGeometry, GRAIN, dot, first_where, sub};
use crate::params::{GradientScheme, HeatModel, SideCondition};
use crate::properties::ExchangeFactors;
use crate::{FlowInput, HeatError, HeatGeometry, HeatState};

pub use crate::geometry::MIN_FACE_COSINE;

/// Factor on the advective outflow in the stability limit. On a triangle the three face
/// excursions of a linear reconstruction sum to zero, so the Barth–Jespersen bound on the
/// largest one limits the outflow excursion to twice the room to the local maximum; the
/// update then stays within the neighbourhood bounds for (1 + 2) Δt Σ_out ṁ c_p ≤ C.
pub const ADVECTIVE_FACTOR: f64 = 3.0;

/// How heat crosses one face; coefficients computed once per outer step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FaceLaw {
    /// Two cells of the same medium (fluid–fluid or solid–solid): A-Eq. 47 with the primary
    /// conductance `g` = λ_f |A| / (ds n·e_s) [W/K] and `cross` = λ_f (A − e_s |A|/(n·e_s))
    /// [W m/K], dotted with the mean of the two cell gradients.
    Diffusive { g: f64, cross: [f64; 2] },
    /// Fluid–solid interface (case IV): series conductance `g` = |A| h_f k_s / (h_f + k_s),
    /// k_s = λ_s / d_{r,c}; face temperature weight `w0` of cell 0.
    Interface { g: f64, w0: f64 },
    /// Outer boundary (cases I–III): index into the geometry's boundary table; the
    /// conductivity is the cell's.
    Boundary { slot: u32 },
}

/// What one outer step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Number of explicit sub-steps.
    pub substeps: usize,
    /// Length of each sub-step [s].
    pub substep: f64,
    /// The stability limit of this step [s] (before the safety factor).
    pub stability_limit: f64,
}

/// Scratch buffers of the explicit step. Holds no state between calls: every buffer is
/// recomputed from the geometry, the model, the flow input and the state.
#[derive(Debug, Clone, Default)]
pub struct HeatStepper {
    // Per cell.
    pub(crate) capacity: Vec<f64>,
    pub(crate) conductivity: Vec<f64>,
    specific_heat: Vec<f64>,
    exchange: Vec<ExchangeFactors>,
    pub(crate) gradient: Vec<[f64; 2]>,
    limiter: Vec<f64>,
    // Per face.
    pub(crate) face_law: Vec<FaceLaw>,
    face_temperature: Vec<f64>,
    face_heat: Vec<f64>,
    // Per channel.
    pub(crate) channel_conductance: Vec<f64>,
    channel_heat: Vec<f64>,
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

    /// Advances `state` by `dt` [s]: prepares the coefficients once, then takes as many equal
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
        let limit = self.stability_limit(model, geometry, mesh, input);
        let allowed = model.stability_safety * limit;
        let substeps = if allowed.is_finite() {
            ((dt / allowed).ceil() as usize).max(1)
        } else {
            1
        };
        let h = dt / substeps as f64;
        let t0 = state.time;
        for k in 0..substeps {
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

    /// The explicit stability limit [s] for this mesh, model and input (without the safety
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
        self.face_temperatures(model, geometry, mesh, &state.temperature, t);
        self.gradients(model, geometry, mesh, &state.temperature);
        self.limiters(geometry, mesh, &state.temperature);
        self.face_heat(model, geometry, mesh, input, &state.temperature, t);
        self.channel_heat(model, geometry, mesh, input, &state.temperature);
        self.advance(geometry, mesh, &mut state.temperature, h);
        let temp = &state.temperature;
        if let Some(c) = first_where(temp.len(), |c| !temp[c].is_finite()) {
            return Err(HeatError::NonFinite {
                quantity: "temperature",
                cell: c,
                step: state.steps,
                time: t,
                value: state.temperature[c],
            });
        }
        Ok(())
    }

    /// Stage 0: checks the geometry against the mesh, the state and the input, then computes
    /// the per-cell capacities and conductivities (A-Eqs. 32–36 in fluid cells), every face's
    /// law (A-Eq. 47 conductances, h_f of A-Eqs. 43–45 at interfaces) and the S2S channel
    /// conductances (A-Eq. 40). Three parallel passes, no allocation after the first call.
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
        if let Some(c) = first_where(n, |c| !(temp[c].is_finite() && temp[c] > 0.0)) {
            return Err(HeatError::InputOutOfRange {
                quantity: "temperature",
                index: c,
                range: "finite and > 0 K",
                value: state.temperature[c],
            });
        }
        input.validate(mesh)?;
        self.prepare_cells(model, geometry, mesh, input);
        self.prepare_faces(model, geometry, mesh);
        self.prepare_channels(mesh);
        let nf = mesh.n_faces();
        self.gradient.resize(n, [0.0; 2]);
        self.limiter.resize(n, 1.0);
        self.face_temperature.resize(nf, 0.0);
        self.face_heat.resize(nf, 0.0);
        self.channel_heat.resize(mesh.channels.len(), 0.0);
        Ok(())
    }

    /// Part of [`Self::prepare`]: capacity C = V (ρc), conductivity and specific heat of every
    /// cell (mixture A-Eqs. 32–36 in fluid cells), and each fluid cell's share of the
    /// interface coefficient (A-Eqs. 43–45) from its mixture and its fastest channel speed
    /// |ṁ| / (ρ_eff h b).
    pub fn prepare_cells(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
    ) {
        let n = mesh.n_cells();
        self.capacity.resize(n, 0.0);
        self.conductivity.resize(n, 0.0);
        self.specific_heat.resize(n, 0.0);
        self.exchange.resize(n, ExchangeFactors::default());
        let b = mesh.thickness;
        let solid = model.solid;
        let start = &geometry.cell_channel_start;
        let cell_channel = &geometry.cell_channel;
        let ch = &mesh.channels;
        (
            &mut self.capacity,
            &mut self.conductivity,
            &mut self.specific_heat,
            &mut self.exchange,
        )
            .into_par_iter()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, (cap, lam, cp, exchange))| {
                let volume = mesh.cell_area[c] * b;
                if mesh.cell_kind[c].is_fluid() {
                    let mix = model.fluid_mixture(
                        input.liquid_fraction[c],
                        input.liquid_density[c],
                        input.gas_density[c],
                    );
                    *cap = volume * mix.volumetric_heat_capacity;
                    *lam = mix.conductivity;
                    *cp = mix.specific_heat;
                    let mut speed = 0.0f64;
                    for &(k, _) in &cell_channel[start[c] as usize..start[c + 1] as usize] {
                        let k = k as usize;
                        let a = ch.aperture[k] * b;
                        if a > 0.0 && mix.density > 0.0 {
                            speed = speed.max(input.channel_mass_flux[k].abs() / (mix.density * a));
                        }
                    }
                    *exchange = ExchangeFactors::new(&mix, speed);
                } else {
                    *cap = volume * solid.volumetric_heat_capacity();
                    *lam = solid.conductivity;
                    *cp = solid.specific_heat;
                }
            });
    }

    /// Part of [`Self::prepare`]: every face's law from its geometry and the cell
    /// conductivities of [`Self::prepare_cells`]. Inside a medium λ_f is the harmonic mean
    /// weighted by the distances along e_s; at a fluid–solid interface h_f (A-Eq. 45) uses
    /// the fluid cell's mixture and its fastest channel speed |ṁ| / (ρ_eff h b).
    pub fn prepare_faces(&mut self, model: &HeatModel, geometry: &HeatGeometry, mesh: &PoreMesh) {
        let nf = mesh.n_faces();
        self.face_law.resize(nf, FaceLaw::Boundary { slot: 0 });
        let lam = &self.conductivity;
        let exchange = &self.exchange;
        let diameter = &geometry.sphere_diameter_powers;
        let porosity = geometry.porosity;
        let solid_lambda = model.solid.conductivity;
        (&mut self.face_law, &geometry.face)
            .into_par_iter()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(f, (law, geo))| {
                *law = match *geo {
                    FaceGeometry::Diffusive {
                        conductance,
                        cross,
                        d0,
                        d1,
                    } => {
                        let [c0, c1] = mesh.face_cells[f];
                        let (l0, l1) = (lam[c0 as usize], lam[c1 as usize]);
                        let den = d1 * l0 + d0 * l1;
                        let lf = if den > 0.0 {
                            l0 * l1 * (d0 + d1) / den
                        } else {
                            0.5 * (l0 + l1)
                        };
                        FaceLaw::Diffusive {
                            g: lf * conductance,
                            cross: [lf * cross[0], lf * cross[1]],
                        }
                    }
                    FaceGeometry::Interface {
                        area,
                        solid_distance,
                        fluid_first,
                        owner,
                    } => {
                        let [c0, c1] = mesh.face_cells[f];
                        let cf = if fluid_first { c0 } else { c1 } as usize;
                        let dp = diameter.get(owner as usize).copied().unwrap_or_default();
                        let h = exchange[cf].coefficient(porosity, &dp);
                        let ks = if solid_distance > 0.0 {
                            solid_lambda / solid_distance
                        } else {
                            0.0
                        };
                        let (g, wf) = if h + ks > 0.0 {
                            (area * h * ks / (h + ks), h / (h + ks))
                        } else {
                            (0.0, 0.5)
                        };
                        let w0 = if fluid_first { wf } else { 1.0 - wf };
                        FaceLaw::Interface { g, w0 }
                    }
                    FaceGeometry::Boundary { slot } => FaceLaw::Boundary { slot },
                };
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

    /// Per-cell sum of conductances and of the advective outflow, and the resulting limit.
    fn stability_limit(
        &self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        input: &FlowInput,
    ) -> f64 {
        let start = &geometry.cell_channel_start;
        (0..mesh.n_cells())
            .into_par_iter()
            .with_min_len(GRAIN)
            .map(|c| {
                let mut s = 0.0;
                for &f in &mesh.cell_faces[c] {
                    let f = f as usize;
                    s += match self.face_law[f] {
                        FaceLaw::Diffusive { g, .. } | FaceLaw::Interface { g, .. } => g,
                        FaceLaw::Boundary { slot } => {
                            let bf = &geometry.boundary[slot as usize];
                            let m = input.boundary_mass_flux[f];
                            let adv = if m > 0.0 {
                                2.0 * m * self.specific_heat[c]
                            } else {
                                0.0
                            };
                            adv + boundary_conductance(
                                &model.sides[bf.side as usize],
                                self.conductivity[c],
                                bf.normal_distance,
                                bf.area,
                            )
                        }
                    };
                }
                for &(k, second) in &geometry.cell_channel[start[c] as usize..start[c + 1] as usize]
                {
                    let k = k as usize;
                    s += self.channel_conductance[k];
                    let m = input.channel_mass_flux[k];
                    let out = if second { -m } else { m };
                    if out > 0.0 {
                        s += ADVECTIVE_FACTOR * out * self.specific_heat[c];
                    }
                }
                if s > 0.0 {
                    self.capacity[c] / s
                } else {
                    f64::INFINITY
                }
            })
            .min_by(|a, b| a.total_cmp(b))
            .unwrap_or(f64::INFINITY)
    }

    /// Stage 1: face temperatures T̄_f for the Green–Gauss gradients: the arithmetic mean
    /// A-Eq. 42 inside a medium, the interface temperature of case IV, and the boundary values
    /// of cases I–III at time `t`.
    pub fn face_temperatures(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        temp: &[f64],
        t: f64,
    ) {
        let lam = &self.conductivity;
        let boundary = &geometry.boundary;
        let sides: [f64; 5] = std::array::from_fn(|k| match &model.sides[k] {
            SideCondition::Temperature(s) => s.at(t),
            _ => 0.0,
        });
        self.face_temperature
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .zip(self.face_law.par_iter())
            .for_each(|((f, tf), law)| {
                let [c0, c1] = mesh.face_cells[f];
                let t0 = temp[c0 as usize];
                *tf = match *law {
                    FaceLaw::Diffusive { .. } => 0.5 * (t0 + temp[c1 as usize]),
                    FaceLaw::Interface { w0, .. } => w0 * t0 + (1.0 - w0) * temp[c1 as usize],
                    FaceLaw::Boundary { slot } => {
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

    /// Stage 2: cell gradients from the cell and face temperatures: least squares (default;
    /// rows e_k · ∇T = ΔT_k / |d_k| with unit directions to the neighbour centroid in the same
    /// medium or to the face centroid for interface and boundary face values, and Neumann
    /// rows n · ∇T = q / λ on prescribed-flux faces; weights precomputed in `prepare`) or
    /// Green–Gauss (A-Eq. 41) with the face values of stage 1.
    pub fn gradients(
        &mut self,
        model: &HeatModel,
        geometry: &HeatGeometry,
        mesh: &PoreMesh,
        temp: &[f64],
    ) {
        let tf = &self.face_temperature;
        let source = &geometry.stencil_source;
        let weight = &geometry.stencil_weight;
        let scheme = model.gradient;
        self.gradient
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, g)| {
                *g = match scheme {
                    GradientScheme::GreenGauss => green_gauss(mesh, tf, c),
                    GradientScheme::LeastSquares => {
                        let tc = temp[c];
                        let mut s = [0.0; 2];
                        for k in 0..3 {
                            let dt = stencil_value(source[c][k], temp, tf) - tc;
                            s[0] += weight[c][k][0] * dt;
                            s[1] += weight[c][k][1] * dt;
                        }
                        s
                    }
                };
            });
    }

    /// Stage 3: Barth–Jespersen limiter ψ ∈ [0, 1] of each fluid cell's gradient, so that the
    /// reconstruction A-Eq. 48 at every face centroid stays within the range of the cell, its
    /// face neighbours (face values at interfaces and boundaries) and its S2S partners.
    pub fn limiters(&mut self, geometry: &HeatGeometry, mesh: &PoreMesh, temp: &[f64]) {
        let tf = &self.face_temperature;
        let grad = &self.gradient;
        let start = &geometry.cell_channel_start;
        let partner = &geometry.cell_channel_partner;
        let source = &geometry.stencil_source;
        let offset = &geometry.stencil_offset;
        self.limiter
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, psi)| {
                if !mesh.cell_kind[c].is_fluid() {
                    *psi = 1.0;
                    return;
                }
                let tc = temp[c];
                let (mut lo, mut hi) = (tc, tc);
                for &src in &source[c] {
                    let v = stencil_value(src, temp, tf);
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                for &other in &partner[start[c] as usize..start[c + 1] as usize] {
                    let v = temp[other as usize];
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                let g = grad[c];
                let mut p = 1.0f64;
                for r in &offset[c] {
                    let d = dot(g, *r);
                    if d > 0.0 {
                        p = p.min((hi - tc) / d);
                    } else if d < 0.0 {
                        p = p.min((lo - tc) / d);
                    }
                }
                *psi = p.clamp(0.0, 1.0);
            });
    }

    /// Stage 4: heat into the first cell of each face [W]: A-Eq. 47 inside a medium, the
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
        let grad = &self.gradient;
        let psi = &self.limiter;
        let cp = &self.specific_heat;
        let lam = &self.conductivity;
        let boundary = &geometry.boundary;
        let t_ref = model.reference_temperature;
        let sides: [f64; 5] = std::array::from_fn(|k| match &model.sides[k] {
            SideCondition::Temperature(s) => s.at(t),
            _ => 0.0,
        });
        self.face_heat
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .zip(self.face_law.par_iter())
            .for_each(|((f, q), law)| {
                let [c0, c1] = mesh.face_cells[f];
                let c0 = c0 as usize;
                let t0 = temp[c0];
                *q = match *law {
                    FaceLaw::Diffusive { g, cross } => {
                        let c1 = c1 as usize;
                        let (g0, g1) = (grad[c0], grad[c1]);
                        let mean = [0.5 * (g0[0] + g1[0]), 0.5 * (g0[1] + g1[1])];
                        g * (temp[c1] - t0) + dot(cross, mean)
                    }
                    FaceLaw::Interface { g, .. } => g * (temp[c1 as usize] - t0),
                    FaceLaw::Boundary { slot } => {
                        let BoundaryFace {
                            side,
                            normal_distance,
                            area,
                            tangent,
                        } = boundary[slot as usize];
                        let conductivity = lam[c0];
                        let cond = &model.sides[side as usize];
                        // Temperature at the foot of the normal through the face centroid.
                        let t_foot = t0 + dot(grad[c0], tangent);
                        let diffusive = match cond {
                            SideCondition::Temperature(_) => {
                                conductivity * area / normal_distance
                                    * (sides[side as usize] - t_foot)
                            }
                            SideCondition::HeatFlux(flux) => flux * area,
                            SideCondition::Convective { ambient, .. } => {
                                boundary_conductance(cond, conductivity, normal_distance, area)
                                    * (ambient - t_foot)
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
            });
    }

    /// Stage 5: heat carried along each channel from its first to its second cell [W]:
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
        self.channel_heat
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(k, q)| {
                let [a, b] = ch.cells[k].map(|c| c as usize);
                let m = input.channel_mass_flux[k];
                let adv = if m != 0.0 {
                    let up = if m > 0.0 { a } else { b };
                    let tf = match ch.kind[k] {
                        ChannelKind::T2T => {
                            let r = sub(points[k], mesh.cell_centroid[up]);
                            temp[up] + psi[up] * dot(grad[up], r)
                        }
                        // No face: first-order upwind.
                        ChannelKind::S2S => temp[up],
                    };
                    m * cp[up] * (tf - t_ref)
                } else {
                    0.0
                };
                *q = adv + g[k] * (temp[a] - temp[b]);
            });
    }

    /// Stage 6: T ← T + h (Σ heat in) / C per cell (A-Eqs. 39, 50), gathering face and channel
    /// heat in a fixed order.
    pub fn advance(&mut self, geometry: &HeatGeometry, mesh: &PoreMesh, temp: &mut [f64], h: f64) {
        let qf = &self.face_heat;
        let qc = &self.channel_heat;
        let cap = &self.capacity;
        let start = &geometry.cell_channel_start;
        let cell_channel = &geometry.cell_channel;
        temp.par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, t)| {
                let mut s = 0.0;
                for &f in &mesh.cell_faces[c] {
                    let f = f as usize;
                    if mesh.face_cells[f][0] == c as u32 {
                        s += qf[f];
                    } else {
                        s -= qf[f];
                    }
                }
                for &(k, second) in &cell_channel[start[c] as usize..start[c + 1] as usize] {
                    let q = qc[k as usize];
                    if second {
                        s += q;
                    } else {
                        s -= q;
                    }
                }
                *t += h * s / cap[c];
            });
    }

    /// Total enthalpy Σ C_i (T_i − T_ref) [J] of all cells, with the capacities of the last
    /// [`Self::prepare`] (summed serially in cell order).
    pub fn total_enthalpy(&self, model: &HeatModel, temp: &[f64]) -> f64 {
        self.capacity
            .iter()
            .zip(temp)
            .map(|(c, t)| c * (t - model.reference_temperature))
            .sum()
    }

    /// Heat capacity C_i = V_i (ρ c)_i of each cell [J/K] from the last [`Self::prepare`].
    pub fn heat_capacity(&self) -> &[f64] {
        &self.capacity
    }
}

fn green_gauss(mesh: &PoreMesh, tf: &[f64], c: usize) -> [f64; 2] {
    let mut s = [0.0; 2];
    for &f in &mesh.cell_faces[c] {
        let f = f as usize;
        let sign = if mesh.face_cells[f][0] == c as u32 {
            1.0
        } else {
            -1.0
        };
        let w = sign * tf[f] * mesh.face_length[f];
        s[0] += w * mesh.face_normal[f][0];
        s[1] += w * mesh.face_normal[f][1];
    }
    let inv = 1.0 / mesh.cell_area[c];
    [s[0] * inv, s[1] * inv]
}

#[inline]
fn stencil_value(source: u32, temp: &[f64], face_temperature: &[f64]) -> f64 {
    if source & FACE_VALUE != 0 {
        face_temperature[(source & !FACE_VALUE) as usize]
    } else {
        temp[source as usize]
    }
}

/// Conductance [W/K] between a boundary cell and its surroundings: λ|A|/d_n for case I,
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
