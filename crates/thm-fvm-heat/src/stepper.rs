//! The explicit finite-volume step (A-Eqs. 37–51) with its stability limit and sub-cycling.
//!
//! One outer step is the fixed sequence [`HeatStepper::prepare`] (cell properties, sphere
//! radii and porosity, channel adjacency, face laws) and then, for each sub-step:
//! [`HeatStepper::face_temperatures`] → [`HeatStepper::gradients`] →
//! [`HeatStepper::limiters`] → [`HeatStepper::face_heat`] → [`HeatStepper::channel_heat`] →
//! [`HeatStepper::advance`]. Every stage is a parallel map over cells, faces or channels
//! whose results are gathered per cell in a fixed order, so 1-thread and N-thread runs give
//! identical bits.

use rayon::prelude::*;
use thm_vpn_mesh::{CellKind, ChannelKind, FaceKind, NONE, PoreMesh};

use crate::params::{GradientScheme, HeatModel, SideCondition, side_index};
use crate::properties::{MixtureProperties, interface_coefficient};
use crate::{FlowInput, HeatError, HeatState};

/// Smallest admissible cosine between a face normal and the centroid link (A-Eq. 47).
pub const MIN_FACE_COSINE: f64 = 1e-3;

/// Factor on the advective outflow in the stability limit. On a triangle the three face
/// excursions of a linear reconstruction sum to zero, so the Barth–Jespersen bound on the
/// largest one limits the outflow excursion to twice the room to the local maximum; the
/// update then stays within the neighbourhood bounds for (1 + 2) Δt Σ_out ṁ c_p ≤ C.
pub const ADVECTIVE_FACTOR: f64 = 3.0;

/// Rayon granularity: items per task.
const GRAIN: usize = 2048;

#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[inline]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

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
    /// Outer boundary (cases I–III) on side `side`; `conductivity` of the cell, normal
    /// distance `normal_distance` of its centroid to the face, `area` |A| [m²], `tangent`:
    /// the part of centroid→face-centroid parallel to the face (non-orthogonal correction).
    Boundary {
        side: u8,
        conductivity: f64,
        normal_distance: f64,
        area: f64,
        tangent: [f64; 2],
    },
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
/// recomputed from the mesh, the model, the flow input and the state.
#[derive(Debug, Clone, Default)]
pub struct HeatStepper {
    // Per cell.
    pub(crate) capacity: Vec<f64>,
    pub(crate) conductivity: Vec<f64>,
    specific_heat: Vec<f64>,
    mixture: Vec<MixtureProperties>,
    speed: Vec<f64>,
    pub(crate) gradient: Vec<[f64; 2]>,
    limiter: Vec<f64>,
    // Per sphere.
    sphere_radius: Vec<f64>,
    porosity: f64,
    // Per face.
    pub(crate) face_law: Vec<FaceLaw>,
    face_temperature: Vec<f64>,
    face_heat: Vec<f64>,
    // Per channel.
    pub(crate) channel_conductance: Vec<f64>,
    channel_point: Vec<[f64; 2]>,
    channel_heat: Vec<f64>,
    // Cell → channels (CSR): channel index and whether the cell is the channel's second cell.
    cell_channel_start: Vec<u32>,
    cell_channel: Vec<(u32, bool)>,
}

impl HeatStepper {
    /// An empty stepper; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Advances `state` by `dt` [s]: prepares the coefficients once, then takes as many equal
    /// explicit sub-steps as the stability limit requires.
    pub fn step(
        &mut self,
        model: &HeatModel,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        dt: f64,
    ) -> Result<StepReport, HeatError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(HeatError::ParameterOutOfRange {
                field: "dt".to_owned(),
                range: "> 0 s",
                value: dt,
            });
        }
        self.prepare(model, mesh, input, state)?;
        let limit = self.stability_limit(model, mesh, input);
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
            self.substep(model, mesh, input, state, t, h)?;
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
    /// factor): min over cells of C_i / (Σ conductances + 2 Σ outflow ṁ c_p).
    pub fn stable_time_step(
        &mut self,
        model: &HeatModel,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &HeatState,
    ) -> Result<f64, HeatError> {
        self.prepare(model, mesh, input, state)?;
        Ok(self.stability_limit(model, mesh, input))
    }

    fn substep(
        &mut self,
        model: &HeatModel,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &mut HeatState,
        t: f64,
        h: f64,
    ) -> Result<(), HeatError> {
        self.face_temperatures(model, mesh, &state.temperature, t);
        self.gradients(model, mesh, &state.temperature);
        self.limiters(mesh, &state.temperature);
        self.face_heat(model, mesh, input, &state.temperature, t);
        self.channel_heat(model, mesh, input, &state.temperature);
        self.advance(mesh, &mut state.temperature, h);
        if let Some(c) = state
            .temperature
            .par_iter()
            .position_first(|x| !x.is_finite())
        {
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

    /// Stage 0: validates the input and the state, computes per-cell capacities and
    /// conductivities (A-Eqs. 32–36 in fluid cells), sphere radii and porosity, the channel
    /// adjacency and every face's law.
    pub fn prepare(
        &mut self,
        model: &HeatModel,
        mesh: &PoreMesh,
        input: &FlowInput,
        state: &HeatState,
    ) -> Result<(), HeatError> {
        let n = mesh.n_cells();
        if state.temperature.len() != n {
            return Err(HeatError::LengthMismatch {
                what: "temperature",
                expected: n,
                got: state.temperature.len(),
            });
        }
        if let Some(c) = state
            .temperature
            .iter()
            .position(|t| !(t.is_finite() && *t > 0.0))
        {
            return Err(HeatError::InputOutOfRange {
                quantity: "temperature",
                index: c,
                range: "finite and > 0 K",
                value: state.temperature[c],
            });
        }
        input.validate(mesh)?;
        self.prepare_cells(model, mesh, input);
        self.prepare_spheres(mesh);
        self.prepare_channels(mesh);
        self.prepare_faces(model, mesh)?;
        let nf = mesh.n_faces();
        self.gradient.resize(n, [0.0; 2]);
        self.limiter.resize(n, 1.0);
        self.face_temperature.resize(nf, 0.0);
        self.face_heat.resize(nf, 0.0);
        self.channel_heat.resize(mesh.channels.len(), 0.0);
        Ok(())
    }

    fn prepare_cells(&mut self, model: &HeatModel, mesh: &PoreMesh, input: &FlowInput) {
        let n = mesh.n_cells();
        self.capacity.resize(n, 0.0);
        self.conductivity.resize(n, 0.0);
        self.specific_heat.resize(n, 0.0);
        self.speed.resize(n, 0.0);
        let zero = crate::properties::mixture(&model.liquid, &model.gas, 1.0, 0.0, 0.0);
        self.mixture.resize(n, zero);
        let b = mesh.thickness;
        let solid = model.solid;
        (
            &mut self.capacity,
            &mut self.conductivity,
            &mut self.specific_heat,
            &mut self.mixture,
        )
            .into_par_iter()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, (cap, lam, cp, mix))| {
                let volume = mesh.cell_area[c] * b;
                if mesh.cell_kind[c].is_fluid() {
                    *mix = model.fluid_mixture(
                        input.liquid_fraction[c],
                        input.liquid_density[c],
                        input.gas_density[c],
                    );
                    *cap = volume * mix.volumetric_heat_capacity;
                    *lam = mix.conductivity;
                    *cp = mix.specific_heat;
                } else {
                    *mix = zero;
                    *cap = volume * solid.volumetric_heat_capacity();
                    *lam = solid.conductivity;
                    *cp = solid.specific_heat;
                }
            });
        // Fluid speed per cell: the largest channel speed |ṁ| / (ρ_eff h b) of its channels.
        self.speed.iter_mut().for_each(|v| *v = 0.0);
        for k in 0..mesh.channels.len() {
            let m = input.channel_mass_flux[k].abs();
            let area = mesh.channels.aperture[k] * b;
            for &c in &mesh.channels.cells[k] {
                let c = c as usize;
                let rho = self.mixture[c].density;
                if area > 0.0 && rho > 0.0 {
                    self.speed[c] = self.speed[c].max(m / (rho * area));
                }
            }
        }
    }

    fn prepare_spheres(&mut self, mesh: &PoreMesh) {
        let mut n_spheres = 0usize;
        let (mut fluid, mut total) = (0.0, 0.0);
        for (c, k) in mesh.cell_kind.iter().enumerate() {
            total += mesh.cell_area[c];
            match k {
                CellKind::Fluid => fluid += mesh.cell_area[c],
                CellKind::Solid { owner } => n_spheres = n_spheres.max(*owner as usize + 1),
            }
        }
        self.porosity = if total > 0.0 { fluid / total } else { 0.0 };
        self.sphere_radius.clear();
        self.sphere_radius.resize(n_spheres, 0.0);
        for (c, k) in mesh.cell_kind.iter().enumerate() {
            if let CellKind::Solid { owner } = k {
                self.sphere_radius[*owner as usize] += mesh.cell_area[c];
            }
        }
        // Radius of the circle with the cross-section area of the sphere's solid cells.
        for r in &mut self.sphere_radius {
            *r = (*r / std::f64::consts::PI).sqrt();
        }
    }

    fn prepare_channels(&mut self, mesh: &PoreMesh) {
        let n = mesh.n_cells();
        let ch = &mesh.channels;
        self.cell_channel_start.clear();
        self.cell_channel_start.resize(n + 1, 0);
        for cells in &ch.cells {
            for &c in cells {
                self.cell_channel_start[c as usize + 1] += 1;
            }
        }
        for c in 0..n {
            self.cell_channel_start[c + 1] += self.cell_channel_start[c];
        }
        self.cell_channel.clear();
        self.cell_channel
            .resize(self.cell_channel_start[n] as usize, (NONE, false));
        // Fill in channel order: each cell's list is sorted by channel index.
        let mut next: Vec<u32> = self.cell_channel_start[..n].to_vec();
        for (k, cells) in ch.cells.iter().enumerate() {
            for (side, &c) in cells.iter().enumerate() {
                let slot = &mut next[c as usize];
                self.cell_channel[*slot as usize] = (k as u32, side == 1);
                *slot += 1;
            }
        }
        let nch = ch.len();
        self.channel_conductance.resize(nch, 0.0);
        self.channel_point.resize(nch, [0.0; 2]);
        for k in 0..nch {
            let [a, b] = ch.cells[k].map(|c| c as usize);
            let (pa, pb) = (mesh.cell_centroid[a], mesh.cell_centroid[b]);
            match ch.kind[k] {
                ChannelKind::T2T => {
                    // Diffusion across the shared face is part of the face laws.
                    self.channel_conductance[k] = 0.0;
                    let f = ch.face[k];
                    self.channel_point[k] = if f == NONE {
                        [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]
                    } else {
                        mesh.face_centroid[f as usize]
                    };
                }
                ChannelKind::S2S => {
                    // A-Eq. 40: λ_eff A_k / L_k with A_k = h b.
                    let lambda = 0.5 * (self.conductivity[a] + self.conductivity[b]);
                    let l = ch.length[k];
                    self.channel_conductance[k] = if l > 0.0 {
                        lambda * ch.aperture[k] * mesh.thickness / l
                    } else {
                        0.0
                    };
                    self.channel_point[k] = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
                }
            }
        }
    }

    fn prepare_faces(&mut self, model: &HeatModel, mesh: &PoreMesh) -> Result<(), HeatError> {
        let nf = mesh.n_faces();
        // Degenerate links first (deterministic: the lowest face index).
        if let Some(f) = (0..nf).into_par_iter().position_first(|f| {
            let [c0, c1] = mesh.face_cells[f];
            if c1 == NONE {
                return false;
            }
            face_cosine(mesh, f, c0 as usize, c1 as usize) <= MIN_FACE_COSINE
        }) {
            let [c0, c1] = mesh.face_cells[f];
            return Err(HeatError::DegenerateFace {
                face: f,
                cosine: face_cosine(mesh, f, c0 as usize, c1 as usize),
                minimum: MIN_FACE_COSINE,
            });
        }
        self.face_law
            .resize(nf, FaceLaw::Interface { g: 0.0, w0: 0.5 });
        let b = mesh.thickness;
        let lam = &self.conductivity;
        let mix = &self.mixture;
        let speed = &self.speed;
        let radius = &self.sphere_radius;
        let porosity = self.porosity;
        let solid_lambda = model.solid.conductivity;
        self.face_law
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(f, law)| {
                let [c0, c1] = mesh.face_cells[f];
                let c0 = c0 as usize;
                let n = mesh.face_normal[f];
                let area = mesh.face_length[f] * b;
                let xf = mesh.face_centroid[f];
                let x0 = mesh.cell_centroid[c0];
                if c1 == NONE {
                    let r = sub(xf, x0);
                    let dn = dot(r, n);
                    let side = match mesh.face_kind[f] {
                        FaceKind::Boundary(s) => side_index(s) as u8,
                        FaceKind::Interior => side_index(thm_vpn_mesh::BoundarySide::Outline) as u8,
                    };
                    *law = FaceLaw::Boundary {
                        side,
                        conductivity: lam[c0],
                        normal_distance: dn,
                        area,
                        tangent: [r[0] - dn * n[0], r[1] - dn * n[1]],
                    };
                    return;
                }
                let c1 = c1 as usize;
                let (k0, k1) = (mesh.cell_kind[c0], mesh.cell_kind[c1]);
                let x1 = mesh.cell_centroid[c1];
                if k0.is_fluid() == k1.is_fluid() {
                    let d = sub(x1, x0);
                    let ds = dot(d, d).sqrt();
                    let es = [d[0] / ds, d[1] / ds];
                    let cos = dot(n, es);
                    // Harmonic face conductivity weighted by the distances along e_s.
                    let d0 = dot(sub(xf, x0), es).max(0.0);
                    let d1 = dot(sub(x1, xf), es).max(0.0);
                    let (l0, l1) = (lam[c0], lam[c1]);
                    let den = d1 * l0 + d0 * l1;
                    let lf = if den > 0.0 {
                        l0 * l1 * (d0 + d1) / den
                    } else {
                        0.5 * (l0 + l1)
                    };
                    let g = lf * area / (ds * cos);
                    let cross = [
                        lf * (area * n[0] - es[0] * area / cos),
                        lf * (area * n[1] - es[1] * area / cos),
                    ];
                    *law = FaceLaw::Diffusive { g, cross };
                } else {
                    let (cf, cs) = if k0.is_fluid() { (c0, c1) } else { (c1, c0) };
                    let owner = match mesh.cell_kind[cs] {
                        CellKind::Solid { owner } => owner as usize,
                        CellKind::Fluid => 0,
                    };
                    let r = radius.get(owner).copied().unwrap_or(0.0);
                    let h = interface_coefficient(&mix[cf], porosity, speed[cf], r);
                    let ds = dot(
                        sub(xf, mesh.cell_centroid[cs]),
                        sub(xf, mesh.cell_centroid[cs]),
                    )
                    .sqrt();
                    let ks = if ds > 0.0 { solid_lambda / ds } else { 0.0 };
                    let (g, wf) = if h + ks > 0.0 {
                        (area * h * ks / (h + ks), h / (h + ks))
                    } else {
                        (0.0, 0.5)
                    };
                    let w0 = if cf == c0 { wf } else { 1.0 - wf };
                    *law = FaceLaw::Interface { g, w0 };
                }
            });
        Ok(())
    }

    /// Per-cell sum of conductances and twice the advective outflow, and the resulting limit.
    fn stability_limit(&self, model: &HeatModel, mesh: &PoreMesh, input: &FlowInput) -> f64 {
        let start = &self.cell_channel_start;
        (0..mesh.n_cells())
            .into_par_iter()
            .with_min_len(GRAIN)
            .map(|c| {
                let mut s = 0.0;
                for &f in &mesh.cell_faces[c] {
                    let f = f as usize;
                    s += match self.face_law[f] {
                        FaceLaw::Diffusive { g, .. } | FaceLaw::Interface { g, .. } => g,
                        FaceLaw::Boundary {
                            side,
                            conductivity,
                            normal_distance,
                            area,
                            ..
                        } => {
                            let m = input.boundary_mass_flux[f];
                            let adv = if m > 0.0 {
                                2.0 * m * self.specific_heat[c]
                            } else {
                                0.0
                            };
                            adv + boundary_conductance(
                                &model.sides[side as usize],
                                conductivity,
                                normal_distance,
                                area,
                            )
                        }
                    };
                }
                for &(k, second) in &self.cell_channel[start[c] as usize..start[c + 1] as usize] {
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
    pub fn face_temperatures(&mut self, model: &HeatModel, mesh: &PoreMesh, temp: &[f64], t: f64) {
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
                    FaceLaw::Boundary {
                        side,
                        conductivity,
                        normal_distance,
                        ..
                    } => match &model.sides[side as usize] {
                        SideCondition::Temperature(_) => sides[side as usize],
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
                    },
                };
            });
    }

    /// Stage 2: cell gradients from the cell and face temperatures: weighted least squares
    /// (default) or Green–Gauss (A-Eq. 41) with the face values of stage 1.
    pub fn gradients(&mut self, model: &HeatModel, mesh: &PoreMesh, temp: &[f64]) {
        let tf = &self.face_temperature;
        let laws = &self.face_law;
        let scheme = model.gradient;
        self.gradient
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, g)| {
                *g = match scheme {
                    GradientScheme::GreenGauss => green_gauss(mesh, tf, c),
                    GradientScheme::LeastSquares => least_squares(model, mesh, laws, tf, temp, c),
                };
            });
    }

    /// Stage 3: Barth–Jespersen limiter ψ ∈ [0, 1] of each fluid cell's gradient, so that the
    /// reconstruction A-Eq. 48 at every face centroid stays within the range of the cell, its
    /// face neighbours (face values at interfaces and boundaries) and its S2S partners.
    pub fn limiters(&mut self, mesh: &PoreMesh, temp: &[f64]) {
        let tf = &self.face_temperature;
        let grad = &self.gradient;
        let start = &self.cell_channel_start;
        let cell_channel = &self.cell_channel;
        let ch = &mesh.channels;
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
                for &f in &mesh.cell_faces[c] {
                    let f = f as usize;
                    let [c0, c1] = mesh.face_cells[f];
                    let other = if c0 == c as u32 { c1 } else { c0 };
                    let v = if other != NONE && mesh.cell_kind[other as usize].is_fluid() {
                        temp[other as usize]
                    } else {
                        tf[f]
                    };
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                let list = &cell_channel[start[c] as usize..start[c + 1] as usize];
                for &(k, second) in list {
                    let [a, b] = ch.cells[k as usize];
                    let other = if second { a } else { b };
                    let v = temp[other as usize];
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                let g = grad[c];
                let xc = mesh.cell_centroid[c];
                let mut p = 1.0f64;
                let mut limit = |x: [f64; 2]| {
                    let d = dot(g, sub(x, xc));
                    let r = if d > 0.0 {
                        (hi - tc) / d
                    } else if d < 0.0 {
                        (lo - tc) / d
                    } else {
                        1.0
                    };
                    p = p.min(r.min(1.0));
                };
                for &f in &mesh.cell_faces[c] {
                    limit(mesh.face_centroid[f as usize]);
                }
                *psi = p.max(0.0);
            });
    }

    /// Stage 4: heat into the first cell of each face [W]: A-Eq. 47 inside a medium, the
    /// series conductance at fluid–solid interfaces, cases I–III and advection through open
    /// boundary faces.
    pub fn face_heat(
        &mut self,
        model: &HeatModel,
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
        t: f64,
    ) {
        let grad = &self.gradient;
        let psi = &self.limiter;
        let cp = &self.specific_heat;
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
                    FaceLaw::Boundary {
                        side,
                        conductivity,
                        normal_distance,
                        area,
                        tangent,
                    } => {
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
        mesh: &PoreMesh,
        input: &FlowInput,
        temp: &[f64],
    ) {
        let grad = &self.gradient;
        let psi = &self.limiter;
        let cp = &self.specific_heat;
        let g = &self.channel_conductance;
        let points = &self.channel_point;
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
    pub fn advance(&mut self, mesh: &PoreMesh, temp: &mut [f64], h: f64) {
        let qf = &self.face_heat;
        let qc = &self.channel_heat;
        let cap = &self.capacity;
        let start = &self.cell_channel_start;
        let cell_channel = &self.cell_channel;
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

/// Least-squares gradient: rows e · ∇T = ΔT / |d| with unit directions e = d / |d| to the
/// neighbour centroid (same medium) or to the face centroid (interface and boundary face
/// values), and e = n, rhs = q / λ for prescribed-flux faces (Neumann rows).
fn least_squares(
    model: &HeatModel,
    mesh: &PoreMesh,
    laws: &[FaceLaw],
    tf: &[f64],
    temp: &[f64],
    c: usize,
) -> [f64; 2] {
    let xc = mesh.cell_centroid[c];
    let tc = temp[c];
    let (mut m00, mut m01, mut m11, mut r0, mut r1) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut row = |e: [f64; 2], rhs: f64| {
        m00 += e[0] * e[0];
        m01 += e[0] * e[1];
        m11 += e[1] * e[1];
        r0 += e[0] * rhs;
        r1 += e[1] * rhs;
    };
    for &f in &mesh.cell_faces[c] {
        let f = f as usize;
        let [c0, c1] = mesh.face_cells[f];
        let (d, dt) = match laws[f] {
            FaceLaw::Diffusive { .. } => {
                let other = if c0 == c as u32 { c1 } else { c0 } as usize;
                (sub(mesh.cell_centroid[other], xc), temp[other] - tc)
            }
            FaceLaw::Interface { .. } => (sub(mesh.face_centroid[f], xc), tf[f] - tc),
            FaceLaw::Boundary {
                side, conductivity, ..
            } => match &model.sides[side as usize] {
                SideCondition::HeatFlux(q) => {
                    if conductivity > 0.0 {
                        row(mesh.face_normal[f], q / conductivity);
                    }
                    continue;
                }
                _ => (sub(mesh.face_centroid[f], xc), tf[f] - tc),
            },
        };
        let len = dot(d, d).sqrt();
        if len > 0.0 {
            row([d[0] / len, d[1] / len], dt / len);
        }
    }
    let det = m00 * m11 - m01 * m01;
    if det.abs() <= 1e-12 * (m00 + m11).powi(2) {
        return [0.0; 2];
    }
    [(m11 * r0 - m01 * r1) / det, (m00 * r1 - m01 * r0) / det]
}

fn face_cosine(mesh: &PoreMesh, f: usize, c0: usize, c1: usize) -> f64 {
    let d = sub(mesh.cell_centroid[c1], mesh.cell_centroid[c0]);
    let ds = dot(d, d).sqrt();
    if ds > 0.0 {
        dot(mesh.face_normal[f], d) / ds
    } else {
        0.0
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
