//! The explicit step: a fixed sequence of named stages over caller-owned state.
//!
//! ```text
//! check_time_step      B-Eqs. 30–31
//! reset_grid
//! particle_to_grid     pass 1: M_I, p_I, C_I, C_I T_I, f_ext, Q_ext   (B-Eqs. 17–19)
//!                      nodal temperature T_I, prescribed temperatures
//!                      pass 2: f_int, Q_int                            (B-Eqs. 17–18)
//! grid_update          a_I, v_I, Ṫ_I, T_I (B-Eqs. 20–22), velocity conditions, walls
//! grid_to_particle     v_p, x_p, T_p, remapped T_p, L_p (B-Eqs. 26–29)
//! constitutive_update  F, V, ε, material → σ, Q_t, k_ij                (B-Eqs. 50–51)
//! ```
//!
//! Scatter (particle → grid) is parallel and deterministic: points are binned into horizontal
//! strips of [`STRIP_ROWS`] node rows by the first row of their 3 × 3 stencil; the even strips
//! scatter concurrently (their node rows are disjoint), then the odd strips. Every node sums
//! its contributions in the same order whatever the number of threads, so results are
//! bit-identical for any thread count. Gathers (grid → particle) and node updates are
//! embarrassingly parallel.

use crate::config::MpmConfig;
use crate::error::MpmError;
use crate::grid::Grid;
use crate::material::{Constitutive, MaterialInput};
use crate::points::{Mat2, MaterialPoints};
use crate::shape::Stencil;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Node rows per scatter strip (≥ 2 keeps same-colour strips disjoint).
pub const STRIP_ROWS: usize = 2;

/// Nodes whose mass is at most this fraction of the largest point mass are treated as empty.
/// Zero: only nodes that no point touches are skipped, so that no force is ever dropped and
/// momentum is conserved to round-off. Nearly empty nodes at the edge of a GIMP support get
/// large accelerations, but a point sees them weighted by `φ_Ip ∝ M_I`, which keeps its
/// update bounded.
const EMPTY_NODE_FRACTION: f64 = 0.0;

/// The caller-owned simulation state: material points, per-point material history, time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MpmState<S> {
    /// The material points.
    pub points: MaterialPoints,
    /// Per-point history of the constitutive model.
    pub material: Vec<S>,
    /// Simulated time (s).
    pub time: f64,
    /// Completed steps.
    pub step: u64,
}

impl<S> MpmState<S> {
    /// A state at time 0 whose material history is the model's initial state, and whose
    /// conductivity is the model's initial conductivity.
    pub fn new<M: Constitutive<PointState = S>>(mut points: MaterialPoints, material: &M) -> Self {
        let k = material.initial_conductivity();
        for c in &mut points.conductivity {
            *c = k;
        }
        let n = points.len();
        Self {
            points,
            material: (0..n).map(|_| material.initial_state()).collect(),
            time: 0.0,
            step: 0,
        }
    }
}

/// Accumulated nodal sums of the scatter passes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NodeSums {
    /// `M_I = Σ m_p φ_Ip` (kg), B-Eq. 19.
    pub mass: f64,
    /// `Σ m_p φ_Ip v_p` (kg m/s).
    pub momentum: [f64; 2],
    /// `C_I = Σ m_p c_p φ_Ip` (J/K), B-Eq. 19.
    pub capacity: f64,
    /// `Σ m_p c_p φ_Ip T_p` (J).
    pub heat_content: f64,
    /// `f_int` plus the surface-layer tractions (N), B-Eq. 18; the body force `M_I b` is
    /// added in the grid update.
    pub force: [f64; 2],
    /// `Q_ext + Q_int` (W), B-Eq. 17.
    pub heat_load: f64,
}

/// Nodal fields after the grid update (for output and inspection).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GridFields {
    /// Accumulated sums.
    pub sums: Vec<NodeSums>,
    /// Velocity at the start of the step `v_I^t = p_I / M_I` (after velocity conditions).
    pub velocity_old: Vec<[f64; 2]>,
    /// Velocity at the end of the step `v_I^{t+Δt}` (after velocity conditions and walls).
    pub velocity: Vec<[f64; 2]>,
    /// Acceleration `(v_I^{t+Δt} − v_I^t)/Δt` consistent with the conditions.
    pub acceleration: Vec<[f64; 2]>,
    /// Nodal temperature at the start of the step (prescribed values applied).
    pub temperature_old: Vec<f64>,
    /// Nodal temperature at the end of the step, B-Eq. 21.
    pub temperature: Vec<f64>,
    /// Nodal temperature rate `T_I,t`.
    pub temperature_rate: Vec<f64>,
}

/// The stepper: configuration and scratch buffers only.
#[derive(Debug, Clone)]
pub struct Mpm {
    config: MpmConfig,
    grid_fields: GridFields,
    /// Mapped nodal temperature before prescribed values were imposed.
    temperature_mapped: Vec<f64>,
    stencils: Vec<Stencil>,
    strip_order: Vec<u32>,
    strip_start: Vec<usize>,
    velocity_gradient: Vec<Mat2>,
    temperature_rate: Vec<f64>,
    wall_reactions: Vec<[f64; 2]>,
    empty_node_mass: f64,
    /// Step counter of the state this stepper advanced last (`None` before the first step).
    last_step: Option<u64>,
}

/// Smallest limits of B-Eqs. 30–31 over the points, with the points that set them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeStepLimits {
    /// Mechanical limit `l_e / √(M/ρ)` (s), `inf` for a stiffness-free material.
    pub mechanical: f64,
    /// The point that sets it.
    pub mechanical_point: usize,
    /// Thermal limit `l_e² ρ c / (b k̄)` (s), `inf` without conduction.
    pub thermal: f64,
    /// The point that sets it.
    pub thermal_point: usize,
}

impl TimeStepLimits {
    /// The smaller of the two.
    pub fn min(&self) -> f64 {
        self.mechanical.min(self.thermal)
    }
}

fn min_with_index(a: (f64, usize), b: (f64, usize)) -> (f64, usize) {
    if b.0 < a.0 || (b.0 == a.0 && b.1 < a.1) {
        b
    } else {
        a
    }
}

impl Mpm {
    /// A stepper for a validated configuration.
    pub fn new(config: MpmConfig) -> Self {
        let n = config.grid.node_count();
        let ny = config.grid.nodes()[1];
        let strips = ny.div_ceil(STRIP_ROWS);
        Self {
            grid_fields: GridFields {
                sums: vec![NodeSums::default(); n],
                velocity_old: vec![[0.0; 2]; n],
                velocity: vec![[0.0; 2]; n],
                acceleration: vec![[0.0; 2]; n],
                temperature_old: vec![0.0; n],
                temperature: vec![0.0; n],
                temperature_rate: vec![0.0; n],
            },
            temperature_mapped: vec![0.0; n],
            stencils: Vec::new(),
            strip_order: Vec::new(),
            strip_start: vec![0; strips + 1],
            velocity_gradient: Vec::new(),
            temperature_rate: Vec::new(),
            wall_reactions: vec![[0.0; 2]; config.params.walls.len()],
            empty_node_mass: 0.0,
            last_step: None,
            config,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &MpmConfig {
        &self.config
    }
    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.config.grid
    }
    /// Nodal fields of the last step.
    pub fn grid_fields(&self) -> &GridFields {
        &self.grid_fields
    }
    /// Force exerted by the material on each wall during the last step (N per metre of
    /// thickness), `Σ_I M_I Δv_I / Δt` over the nodes the wall corrected, with the sign of the
    /// force on the wall.
    pub fn wall_reactions(&self) -> &[[f64; 2]] {
        &self.wall_reactions
    }
    /// Velocity gradients of the last step (row-major), one per point.
    pub fn velocity_gradients(&self) -> &[Mat2] {
        &self.velocity_gradient
    }

    /// Limits B-Eqs. 30–31 for the current state.
    pub fn time_step_limits<M: Constitutive>(
        &self,
        state: &MpmState<M::PointState>,
        material: &M,
    ) -> TimeStepLimits {
        let pts = &state.points;
        let le = self.config.grid.cell_size();
        let b = self.config.params.thermal_time_step_factor;
        let (mech, th) = (0..pts.len())
            .into_par_iter()
            .map(|p| {
                let rho = pts.mass[p] / pts.volume[p];
                let modulus = material.wave_modulus(&state.material[p]);
                let mech = if modulus > 0.0 {
                    le / (modulus / rho).sqrt()
                } else {
                    f64::INFINITY
                };
                let k = pts.conductivity[p];
                let kbar = 0.5 * (k[0] + k[1]);
                let th = if kbar > 0.0 {
                    le * le * rho * pts.specific_heat[p] / (b * kbar)
                } else {
                    f64::INFINITY
                };
                ((mech, p), (th, p))
            })
            .reduce(
                || ((f64::INFINITY, usize::MAX), (f64::INFINITY, usize::MAX)),
                |a, b| (min_with_index(a.0, b.0), min_with_index(a.1, b.1)),
            );
        TimeStepLimits {
            mechanical: mech.0,
            mechanical_point: mech.1,
            thermal: th.0,
            thermal_point: th.1,
        }
    }

    /// Validates a state against this grid and a material: array lengths, positive mass,
    /// volume, density and heat capacity, domains inside the grid.
    pub fn validate_state<S>(&self, state: &MpmState<S>) -> Result<(), MpmError> {
        state.points.validate(&self.config.grid, state.step)?;
        if state.material.len() != state.points.len() {
            return Err(MpmError::MaterialStateCount {
                states: state.material.len(),
                points: state.points.len(),
            });
        }
        Ok(())
    }

    /// Stage 0: error if `dt` is not positive or breaks B-Eq. 30 or 31.
    pub fn check_time_step<M: Constitutive>(
        &self,
        state: &MpmState<M::PointState>,
        material: &M,
        dt: f64,
    ) -> Result<(), MpmError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "dt".into(),
                value: dt,
                allowed: "(0, inf) s",
            });
        }
        let lim = self.time_step_limits(state, material);
        if dt >= lim.mechanical {
            return Err(MpmError::TimeStepTooLarge {
                dt,
                limit: lim.mechanical,
                criterion: "mechanical (B-Eq. 30)",
                point: lim.mechanical_point,
            });
        }
        if dt >= lim.thermal {
            return Err(MpmError::TimeStepTooLarge {
                dt,
                limit: lim.thermal,
                criterion: "thermal (B-Eq. 31)",
                point: lim.thermal_point,
            });
        }
        Ok(())
    }

    /// One explicit step of length `dt` (s). The state is fully validated
    /// ([`Mpm::validate_state`]) on the first step of this stepper and whenever its step
    /// counter is not the one this stepper produced last (a restored or foreign state); a
    /// caller that edits points between consecutive steps should call `validate_state` itself.
    pub fn step<M: Constitutive>(
        &mut self,
        state: &mut MpmState<M::PointState>,
        material: &M,
        dt: f64,
    ) -> Result<(), MpmError> {
        if state.material.len() != state.points.len() {
            return Err(MpmError::MaterialStateCount {
                states: state.material.len(),
                points: state.points.len(),
            });
        }
        if self.last_step != Some(state.step) {
            self.validate_state(state)?;
        }
        // Cleared until the step succeeds: a failed step forces validation next time.
        self.last_step = None;
        self.check_time_step(state, material, dt)?;
        self.reset_grid();
        self.particle_to_grid(&state.points, state.step)?;
        self.grid_update(dt, state.time, state.step)?;
        self.grid_to_particle(&mut state.points, dt, state.step)?;
        self.constitutive_update(state, material, dt)?;
        state.time += dt;
        state.step += 1;
        self.last_step = Some(state.step);
        Ok(())
    }

    /// Stage: zero the nodal sums.
    pub fn reset_grid(&mut self) {
        self.grid_fields
            .sums
            .par_iter_mut()
            .for_each(|s| *s = NodeSums::default());
    }

    /// Computes stencils and bins points into strips (part of P2G).
    fn bin_points(&mut self, points: &MaterialPoints) {
        let n = points.len();
        let grid = &self.config.grid;
        self.stencils.resize(n, Stencil::default());
        self.stencils
            .par_iter_mut()
            .zip(points.position.par_iter().zip(points.half_size.par_iter()))
            .with_min_len(1024)
            .for_each(|(st, (x, l))| *st = Stencil::new(grid, *x, *l));
        let strips = self.strip_start.len() - 1;
        self.strip_start.iter_mut().for_each(|c| *c = 0);
        for st in &self.stencils {
            self.strip_start[st.y.base / STRIP_ROWS + 1] += 1;
        }
        for s in 0..strips {
            self.strip_start[s + 1] += self.strip_start[s];
        }
        self.strip_order.resize(n, 0);
        let mut fill: Vec<usize> = self.strip_start[..strips].to_vec();
        for (p, st) in self.stencils.iter().enumerate() {
            let s = st.y.base / STRIP_ROWS;
            self.strip_order[fill[s]] = p as u32;
            fill[s] += 1;
        }
    }

    /// Runs `f(node_chunk, first_row_of_chunk, point)` for every point, strip by strip, even
    /// strips concurrently then odd strips, each strip in point order.
    fn scatter<F>(
        sums: &mut [NodeSums],
        row_len: usize,
        strip_start: &[usize],
        strip_order: &[u32],
        f: F,
    ) where
        F: Fn(&mut [NodeSums], usize, usize) + Sync,
    {
        let strips = strip_start.len() - 1;
        let chunk = 2 * STRIP_ROWS * row_len;
        for parity in 0..2 {
            let offset = (parity * STRIP_ROWS * row_len).min(sums.len());
            let (_, rest) = sums.split_at_mut(offset);
            rest.par_chunks_mut(chunk)
                .enumerate()
                .for_each(|(k, nodes)| {
                    let s = 2 * k + parity;
                    if s >= strips {
                        return;
                    }
                    let row0 = s * STRIP_ROWS;
                    for &p in &strip_order[strip_start[s]..strip_start[s + 1]] {
                        f(nodes, row0, p as usize);
                    }
                });
        }
    }

    /// Stage: particle to grid. Pass 1 maps mass, momentum, heat capacity, heat content and
    /// external loads; the nodal temperature follows with prescribed values imposed; pass 2
    /// maps internal forces and heat loads.
    pub fn particle_to_grid(&mut self, points: &MaterialPoints, step: u64) -> Result<(), MpmError> {
        self.bin_points(points);
        let params = &self.config.params;
        let grid = &self.config.grid;
        let row_len = grid.nodes()[0];
        let loads = &params.surface_loads;
        let stencils = &self.stencils;
        self.empty_node_mass =
            EMPTY_NODE_FRACTION * points.mass.iter().fold(0.0, |a: f64, &m| a.max(m));

        // Pass 1.
        Self::scatter(
            &mut self.grid_fields.sums,
            row_len,
            &self.strip_start,
            &self.strip_order,
            |nodes, row0, p| {
                let st = &stencils[p];
                let m = points.mass[p];
                let v = points.velocity[p];
                let mc = m * points.specific_heat[p];
                let mct = mc * points.temperature[p];
                let vol = points.volume[p];
                // Gravity enters in `grid_update` as M_I b (= Σ_p φ_Ip m_p b, B-Eq. 18).
                let mut f = [0.0; 2];
                let mut q = vol * points.heat_source[p];
                for load in loads {
                    if load.contains(points.position[p]) {
                        let s = vol / load.layer_thickness;
                        f[0] += s * load.traction[0];
                        f[1] += s * load.traction[1];
                        q += s * load.inward_heat_flux;
                    }
                }
                let loaded = f[0] != 0.0 || f[1] != 0.0 || q != 0.0;
                for b in 0..3 {
                    let row = (st.y.base + b - row0) * row_len + st.x.base;
                    let wy = st.y.w[b];
                    for a in 0..3 {
                        let w = st.x.w[a] * wy;
                        let n = &mut nodes[row + a];
                        let wm = w * m;
                        n.mass += wm;
                        n.momentum[0] += wm * v[0];
                        n.momentum[1] += wm * v[1];
                        n.capacity += w * mc;
                        n.heat_content += w * mct;
                        if loaded {
                            n.force[0] += w * f[0];
                            n.force[1] += w * f[1];
                            n.heat_load += w * q;
                        }
                    }
                }
            },
        );

        // Nodal temperature and prescribed temperatures.
        let fixed = &self.config.fixed_temperature;
        self.grid_fields
            .temperature_old
            .par_iter_mut()
            .zip(self.temperature_mapped.par_iter_mut())
            .zip(self.grid_fields.sums.par_iter().zip(fixed.par_iter()))
            .with_min_len(4096)
            .for_each(|((t, tm), (s, tf))| {
                let mapped = if s.capacity > 0.0 {
                    s.heat_content / s.capacity
                } else {
                    0.0
                };
                *tm = mapped;
                *t = if tf.is_nan() { mapped } else { *tf };
            });
        if let Some(i) = self
            .grid_fields
            .temperature_old
            .par_iter()
            .position_first(|t| !t.is_finite())
        {
            return Err(MpmError::NonFinite {
                quantity: "nodal temperature",
                place: "grid node",
                index: i,
                stage: "particle_to_grid",
                step,
            });
        }

        // Pass 2.
        let temp = &self.grid_fields.temperature_old;
        Self::scatter(
            &mut self.grid_fields.sums,
            row_len,
            &self.strip_start,
            &self.strip_order,
            |nodes, row0, p| {
                let st = &stencils[p];
                let vol = points.volume[p];
                let s = points.stress[p];
                let k = points.conductivity[p];
                // Temperature gradient at the point from nodal temperatures.
                let mut gt = [0.0; 2];
                for b in 0..3 {
                    let row = (st.y.base + b) * row_len + st.x.base;
                    for a in 0..3 {
                        let g = st.gradient(a, b);
                        let t = temp[row + a];
                        gt[0] += g[0] * t;
                        gt[1] += g[1] * t;
                    }
                }
                // k ∇T scaled by the volume.
                let kg = [
                    vol * (k[0] * gt[0] + k[2] * gt[1]),
                    vol * (k[2] * gt[0] + k[1] * gt[1]),
                ];
                let vs = [vol * s[0], vol * s[1], vol * s[2]];
                for b in 0..3 {
                    let row = (st.y.base + b - row0) * row_len + st.x.base;
                    for a in 0..3 {
                        let g = st.gradient(a, b);
                        let n = &mut nodes[row + a];
                        n.force[0] -= vs[0] * g[0] + vs[2] * g[1];
                        n.force[1] -= vs[2] * g[0] + vs[1] * g[1];
                        n.heat_load -= g[0] * kg[0] + g[1] * kg[1];
                    }
                }
            },
        );
        Ok(())
    }

    /// Stage: grid update (B-Eqs. 20–22) with velocity conditions, prescribed temperatures
    /// and walls. `time` is the time at the start of the step.
    pub fn grid_update(&mut self, dt: f64, time: f64, step: u64) -> Result<(), MpmError> {
        let empty = self.empty_node_mass;
        let gf = &mut self.grid_fields;
        let mask = &self.config.velocity_mask;
        let fixed = &self.config.fixed_temperature;
        let gravity = self.config.params.gravity;
        let inv_dt = 1.0 / dt;
        gf.velocity_old
            .par_iter_mut()
            .zip(gf.velocity.par_iter_mut())
            .zip(gf.temperature.par_iter_mut())
            .zip(gf.temperature_rate.par_iter_mut())
            .zip(
                gf.sums
                    .par_iter()
                    .zip(gf.temperature_old.par_iter())
                    .zip(self.temperature_mapped.par_iter())
                    .zip(mask.par_iter().zip(fixed.par_iter())),
            )
            .with_min_len(4096)
            .for_each(|((((vo, vn), tn), tr), (((s, to), tm), (mk, tf)))| {
                if s.mass > empty {
                    let inv_m = 1.0 / s.mass;
                    let mut v0 = [s.momentum[0] * inv_m, s.momentum[1] * inv_m];
                    let mut v1 = [
                        v0[0] + (s.force[0] * inv_m + gravity[0]) * dt,
                        v0[1] + (s.force[1] * inv_m + gravity[1]) * dt,
                    ];
                    if mk & 1 != 0 {
                        v0[0] = 0.0;
                        v1[0] = 0.0;
                    }
                    if mk & 2 != 0 {
                        v0[1] = 0.0;
                        v1[1] = 0.0;
                    }
                    *vo = v0;
                    *vn = v1;
                } else {
                    *vo = [0.0; 2];
                    *vn = [0.0; 2];
                }
                if !tf.is_nan() {
                    *tn = *tf;
                    *tr = (*tf - *tm) * inv_dt;
                } else if s.capacity > 0.0 && s.mass > empty {
                    let rate = s.heat_load / s.capacity;
                    *tr = rate;
                    *tn = *to + rate * dt;
                } else {
                    *tr = 0.0;
                    *tn = *to;
                }
            });

        // Walls: serial over nodes so that reactions sum in a fixed order.
        let grid = &self.config.grid;
        let [nx, ny] = grid.nodes();
        for (w, wall) in self.config.params.walls.iter().enumerate() {
            let mut reaction = [0.0; 2];
            if wall.active(time) {
                for j in 0..ny {
                    for i in 0..nx {
                        let n = grid.node_index(i, j);
                        let m = gf.sums[n].mass;
                        if m <= empty || wall.distance(grid.node_position(i, j), time) > 0.0 {
                            continue;
                        }
                        let v = gf.velocity[n];
                        let c = wall.constrain(v);
                        reaction[0] -= m * (c[0] - v[0]) * inv_dt;
                        reaction[1] -= m * (c[1] - v[1]) * inv_dt;
                        gf.velocity[n] = c;
                    }
                }
            }
            self.wall_reactions[w] = reaction;
        }

        gf.acceleration
            .par_iter_mut()
            .zip(gf.velocity.par_iter().zip(gf.velocity_old.par_iter()))
            .with_min_len(4096)
            .for_each(|(a, (v1, v0))| {
                *a = [(v1[0] - v0[0]) * inv_dt, (v1[1] - v0[1]) * inv_dt];
            });

        let bad = gf
            .velocity
            .par_iter()
            .zip(gf.temperature.par_iter())
            .position_first(|(v, t)| !(v[0].is_finite() && v[1].is_finite() && t.is_finite()));
        if let Some(i) = bad {
            return Err(MpmError::NonFinite {
                quantity: "nodal velocity or temperature",
                place: "grid node",
                index: i,
                stage: "grid_update",
                step,
            });
        }
        Ok(())
    }

    /// Stage: grid to particle. Velocity by the damped FLIP/PIC blend B-Eq. 26, position by
    /// the second-order update B-Eq. 27 (sign as discussed in the crate docs), tracked
    /// temperature by increments B-Eq. 28, remapped temperature B-Eq. 29, and the velocity
    /// gradient `L_p = Σ_I v_I^{t+Δt} ⊗ ∇φ_Ip` for the constitutive stage.
    pub fn grid_to_particle(
        &mut self,
        points: &mut MaterialPoints,
        dt: f64,
        step: u64,
    ) -> Result<(), MpmError> {
        let n = points.len();
        self.velocity_gradient.resize(n, [0.0; 4]);
        self.temperature_rate.resize(n, 0.0);
        let p = &self.config.params;
        let (a_pic, a_g, a_p) = (p.pic_fraction, p.grid_damping, p.particle_damping);
        let row_len = self.config.grid.nodes()[0];
        let gf = &self.grid_fields;
        let stencils = &self.stencils;
        points
            .position
            .par_iter_mut()
            .zip(points.velocity.par_iter_mut())
            .zip(points.temperature.par_iter_mut())
            .zip(points.remapped_temperature.par_iter_mut())
            .zip(
                self.velocity_gradient
                    .par_iter_mut()
                    .zip(self.temperature_rate.par_iter_mut())
                    .zip(stencils.par_iter()),
            )
            .with_min_len(512)
            .for_each(|((((x, v), t), tr), ((l, tdot), st))| {
                let mut v_old = [0.0; 2];
                let mut v_new = [0.0; 2];
                let mut acc = [0.0; 2];
                let mut rate = 0.0;
                let mut t_new = 0.0;
                let mut lg = [0.0; 4];
                for b in 0..3 {
                    let row = (st.y.base + b) * row_len + st.x.base;
                    for a in 0..3 {
                        let node = row + a;
                        let w = st.weight(a, b);
                        let g = st.gradient(a, b);
                        let vo = gf.velocity_old[node];
                        let vn = gf.velocity[node];
                        let ac = gf.acceleration[node];
                        v_old[0] += w * vo[0];
                        v_old[1] += w * vo[1];
                        v_new[0] += w * vn[0];
                        v_new[1] += w * vn[1];
                        acc[0] += w * ac[0];
                        acc[1] += w * ac[1];
                        rate += w * gf.temperature_rate[node];
                        t_new += w * gf.temperature[node];
                        lg[0] += vn[0] * g[0];
                        lg[1] += vn[0] * g[1];
                        lg[2] += vn[1] * g[0];
                        lg[3] += vn[1] * g[1];
                    }
                }
                let vp = *v;
                let v1 = [
                    vp[0] + acc[0] * dt - (a_pic + a_p) * vp[0] + (a_pic - a_g) * v_old[0],
                    vp[1] + acc[1] * dt - (a_pic + a_p) * vp[1] + (a_pic - a_g) * v_old[1],
                ];
                x[0] += dt * v_new[0] - 0.5 * dt * (v1[0] - vp[0]);
                x[1] += dt * v_new[1] - 0.5 * dt * (v1[1] - vp[1]);
                *v = v1;
                *t += rate * dt;
                *tr = t_new;
                *l = lg;
                *tdot = rate;
            });
        let grid = &self.config.grid;
        let bad = (0..n).into_par_iter().with_min_len(4096).find_first(|&i| {
            let x = points.position[i];
            let v = points.velocity[i];
            !(x[0].is_finite()
                && x[1].is_finite()
                && v[0].is_finite()
                && v[1].is_finite()
                && points.temperature[i].is_finite())
        });
        if let Some(i) = bad {
            return Err(MpmError::NonFinite {
                quantity: "point position, velocity or temperature",
                place: "material point",
                index: i,
                stage: "grid_to_particle",
                step,
            });
        }
        let outside = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .find_first(|&i| points.check_inside(grid, i, step + 1).is_err());
        if let Some(i) = outside {
            return points.check_inside(grid, i, step + 1);
        }
        Ok(())
    }

    /// Stage: constitutive update. `F ← (I + L Δt) F`, `V = V_0 det F`, `ε += sym(L) Δt`, and
    /// the material's stress, heat source and conductivity.
    pub fn constitutive_update<M: Constitutive>(
        &mut self,
        state: &mut MpmState<M::PointState>,
        material: &M,
        dt: f64,
    ) -> Result<(), MpmError> {
        let pts = &mut state.points;
        let step = state.step;
        let err = pts
            .deformation_gradient
            .par_iter_mut()
            .zip(pts.volume.par_iter_mut())
            .zip(pts.strain.par_iter_mut())
            .zip(pts.stress.par_iter_mut())
            .zip(pts.heat_source.par_iter_mut())
            .zip(pts.conductivity.par_iter_mut())
            .zip(
                state
                    .material
                    .par_iter_mut()
                    .zip(self.velocity_gradient.par_iter())
                    .zip(self.temperature_rate.par_iter())
                    .zip(
                        pts.remapped_temperature
                            .par_iter()
                            .zip(pts.mass.par_iter())
                            .zip(pts.initial_volume.par_iter()),
                    ),
            )
            .enumerate()
            .with_min_len(256)
            .filter_map(
                |(i, ((((((f, vol), eps), sig), q), k), (((ms, l), tdot), ((t, m), v0))))| {
                    let fo = *f;
                    let a = [1.0 + l[0] * dt, l[1] * dt, l[2] * dt, 1.0 + l[3] * dt];
                    let fnew = [
                        a[0] * fo[0] + a[1] * fo[2],
                        a[0] * fo[1] + a[1] * fo[3],
                        a[2] * fo[0] + a[3] * fo[2],
                        a[2] * fo[1] + a[3] * fo[3],
                    ];
                    let det = fnew[0] * fnew[3] - fnew[1] * fnew[2];
                    if !(det > 0.0 && det.is_finite()) {
                        return Some(MpmError::InvalidPoint {
                            index: i,
                            field: "det F",
                            value: det,
                            allowed: "(0, inf)",
                        });
                    }
                    *f = fnew;
                    *vol = v0 * det;
                    eps[0] += l[0] * dt;
                    eps[1] += l[3] * dt;
                    eps[2] += 0.5 * (l[1] + l[2]) * dt;
                    let input = MaterialInput {
                        point: i,
                        velocity_gradient: *l,
                        deformation_gradient: fnew,
                        temperature: *t,
                        temperature_rate: *tdot,
                        stress: *sig,
                        density: m / *vol,
                        dt,
                    };
                    match material.respond(ms, &input) {
                        Ok(r) => {
                            if !(r.stress.iter().all(|s| s.is_finite())
                                && r.heat_source.is_finite()
                                && r.conductivity.iter().all(|c| c.is_finite()))
                            {
                                return Some(MpmError::NonFinite {
                                    quantity: "stress, heat source or conductivity",
                                    place: "material point",
                                    index: i,
                                    stage: "constitutive_update",
                                    step,
                                });
                            }
                            *sig = r.stress;
                            *q = r.heat_source;
                            *k = r.conductivity;
                            None
                        }
                        Err(e) => Some(e),
                    }
                },
            )
            .min_by_key(|e| match e {
                MpmError::InvalidPoint { index, .. } | MpmError::NonFinite { index, .. } => *index,
                MpmError::Material { point, .. } => *point,
                _ => 0,
            });
        match err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}
