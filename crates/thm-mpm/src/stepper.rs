//! The explicit step: a fixed sequence of named stages over caller-owned state.
//!
//! ```text
//! check_time_step      B-Eqs. 30–31
//! reset_grid
//! particle_to_grid     stencils, strips, active node spans
//!                      pass 1: M_I, p_I, C_I, C_I T_I, f_int, f_ext, Q_ext (B-Eqs. 17–19)
//!                      nodal temperature T_I, prescribed temperatures
//!                      pass 2: Q_int (needs T_I)                       (B-Eq. 17)
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
//! embarrassingly parallel; node updates visit only the active node spans (per node row, the
//! columns the stencils touch), and the 1D weights and gradients of every point are computed
//! once per step and shared by both scatter passes and the gather.

use crate::config::MpmConfig;
use crate::error::MpmError;
use crate::grid::Grid;
use crate::material::{Constitutive, MaterialInput};
use crate::points::{Mat2, MaterialPoints, Sym2};
use crate::shape::Stencil;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Node rows per scatter strip (≥ 2 keeps same-colour strips disjoint).
pub const STRIP_ROWS: usize = 2;

/// Points per parallel work item of the point stages (gather, constitutive update).
const POINT_CHUNK: usize = 512;

/// Points per binning chunk: fixed, so that the binning does not depend on the thread count.
const BIN_CHUNK: usize = 4096;

/// Temperature of an empty node: the prescribed value, or 0 (a node with zero mass carries
/// no heat). Only nodes of zero mass are empty, so that no force is ever dropped and momentum
/// is conserved to round-off; nearly empty nodes at the edge of a GIMP support get large
/// accelerations, but a point sees them weighted by `φ_Ip ∝ M_I`, which keeps its update
/// bounded.
#[inline]
fn empty_temperature(fixed: f64) -> f64 {
    if fixed.is_nan() { 0.0 } else { fixed }
}

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

/// Accumulated nodal sums of the scatter passes: eight values, one 64-byte cache line.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
#[repr(C, align(64))]
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

/// A half-open range `[lo, hi)` of node columns in one node row.
type Span = [u32; 2];

/// The empty span.
const NO_SPAN: Span = [u32::MAX, 0];

/// The smallest span containing `a` and `b`.
#[inline]
fn hull(a: Span, b: Span) -> Span {
    [a[0].min(b[0]), a[1].max(b[1])]
}

/// Column range of a span clipped to a row of `len` nodes (empty for [`NO_SPAN`]).
#[inline]
fn columns(s: Span, len: usize) -> std::ops::Range<usize> {
    let hi = (s[1] as usize).min(len);
    (s[0] as usize).min(hi)..hi
}

/// The stepper: configuration and scratch buffers only.
///
/// Only the nodes that points touch are visited: per node row, the span of columns covered
/// by the stencils of this step (`active`). Nodes outside it hold the empty-node values
/// (zero sums and velocities, the prescribed temperature or 0, zero rate): `reset_grid`
/// zeroes the sums where the last scatter wrote (`sums_dirty`), `grid_update` restores the
/// empty-node values where the last update wrote and no point is now (`fields_dirty`).
#[derive(Debug, Clone)]
pub struct Mpm {
    config: MpmConfig,
    grid_fields: GridFields,
    /// Mapped nodal temperature before prescribed values were imposed.
    temperature_mapped: Vec<f64>,
    stencils: Vec<Stencil>,
    /// Scatter strip of each point.
    strip_of: Vec<u32>,
    /// Points per strip, per binning chunk (`chunks × strips`).
    chunk_counts: Vec<u32>,
    /// Column span of the stencils by stencil base row, per binning chunk (`chunks × rows`).
    chunk_spans: Vec<Span>,
    strip_order: Vec<u32>,
    strip_start: Vec<usize>,
    /// Next free slot of each strip during the counting sort.
    strip_fill: Vec<usize>,
    /// Columns touched by this step's stencils, per node row.
    active: Vec<Span>,
    /// Columns whose sums may be non-zero, per node row.
    sums_dirty: Vec<Span>,
    /// Columns whose updated fields may differ from the empty-node values, per node row.
    fields_dirty: Vec<Span>,
    velocity_gradient: Vec<Mat2>,
    temperature_rate: Vec<f64>,
    wall_reactions: Vec<[f64; 2]>,
    /// Wall reactions per node row (`rows × max(walls, 1)`), summed in row order.
    row_reactions: Vec<[f64; 2]>,
    /// Step counter of the state this stepper advanced last (`None` before the first step).
    last_step: Option<u64>,
}

/// Mutable fields of one node row (grid update).
struct NodeRow<'a> {
    velocity_old: &'a mut [[f64; 2]],
    velocity: &'a mut [[f64; 2]],
    acceleration: &'a mut [[f64; 2]],
    temperature_old: &'a mut [f64],
    temperature: &'a mut [f64],
    temperature_rate: &'a mut [f64],
    temperature_mapped: &'a mut [f64],
    reactions: &'a mut [[f64; 2]],
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
        let walls = config.params.walls.len();
        Self {
            grid_fields: GridFields {
                sums: vec![NodeSums::default(); n],
                velocity_old: vec![[0.0; 2]; n],
                velocity: vec![[0.0; 2]; n],
                acceleration: vec![[0.0; 2]; n],
                temperature_old: config
                    .fixed_temperature
                    .iter()
                    .map(|t| empty_temperature(*t))
                    .collect(),
                temperature: config
                    .fixed_temperature
                    .iter()
                    .map(|t| empty_temperature(*t))
                    .collect(),
                temperature_rate: vec![0.0; n],
            },
            temperature_mapped: vec![0.0; n],
            stencils: Vec::new(),
            strip_of: Vec::new(),
            chunk_counts: Vec::new(),
            chunk_spans: Vec::new(),
            strip_order: Vec::new(),
            strip_start: vec![0; strips + 1],
            strip_fill: Vec::with_capacity(strips),
            active: vec![NO_SPAN; ny],
            sums_dirty: vec![NO_SPAN; ny],
            fields_dirty: vec![NO_SPAN; ny],
            velocity_gradient: Vec::new(),
            temperature_rate: Vec::new(),
            wall_reactions: vec![[0.0; 2]; walls],
            row_reactions: vec![[0.0; 2]; ny * walls.max(1)],
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

    /// True when every point satisfies B-Eqs. 30–31 with a relative margin of 1e-9, tested
    /// without divisions or square roots: `Δt² M V < l_e² m` and `Δt b k̄ V < l_e² m c`. When it
    /// is false the limits are computed exactly ([`Mpm::time_step_limits`]), so the outcome of
    /// [`Mpm::check_time_step`] is that of the exact limits.
    fn time_step_clearly_stable<M: Constitutive>(
        &self,
        state: &MpmState<M::PointState>,
        material: &M,
        dt: f64,
    ) -> bool {
        const SAFE: f64 = 1.0 - 1e-9;
        let pts = &state.points;
        let le = self.config.grid.cell_size();
        let mech = dt * dt;
        let therm = dt * self.config.params.thermal_time_step_factor;
        let bound = SAFE * le * le;
        pts.mass
            .par_iter()
            .zip(pts.volume.par_iter())
            .zip(pts.specific_heat.par_iter())
            .zip(pts.conductivity.par_iter())
            .zip(state.material.par_iter())
            .with_min_len(4096)
            .all(|((((m, v), c), k), ms)| {
                let modulus = material.wave_modulus(ms);
                let kbar = 0.5 * (k[0] + k[1]);
                let room = bound * m;
                (modulus <= 0.0 || modulus.is_nan() || mech * modulus * v <= room)
                    && (kbar <= 0.0 || kbar.is_nan() || therm * kbar * v <= room * c)
            })
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
        if self.time_step_clearly_stable(state, material, dt) {
            return Ok(());
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

    /// Stage: zero the nodal sums (only where the last scatter wrote).
    pub fn reset_grid(&mut self) {
        let row_len = self.config.grid.nodes()[0];
        self.grid_fields
            .sums
            .par_chunks_mut(row_len)
            .zip(self.sums_dirty.par_iter_mut())
            .for_each(|(row, span)| {
                row[columns(*span, row_len)].fill(NodeSums::default());
                *span = NO_SPAN;
            });
    }

    /// Computes stencils, bins points into strips and finds the active node spans (part of
    /// P2G). Stencils, strip counts and spans are computed per chunk of [`BIN_CHUNK`] points
    /// in parallel and merged in chunk order; the strip order lists each strip's points in
    /// index order.
    fn bin_points(&mut self, points: &MaterialPoints) {
        let n = points.len();
        let grid = &self.config.grid;
        let ny = grid.nodes()[1];
        let strips = self.strip_start.len() - 1;
        let chunks = n.div_ceil(BIN_CHUNK);
        self.stencils.resize(n, Stencil::default());
        self.strip_of.resize(n, 0);
        self.chunk_counts.clear();
        self.chunk_counts.resize(chunks * strips, 0);
        self.chunk_spans.clear();
        self.chunk_spans.resize(chunks * ny, NO_SPAN);
        self.stencils
            .par_chunks_mut(BIN_CHUNK)
            .zip(self.strip_of.par_chunks_mut(BIN_CHUNK))
            .zip(points.position.par_chunks(BIN_CHUNK))
            .zip(points.half_size.par_chunks(BIN_CHUNK))
            .zip(self.chunk_counts.par_chunks_mut(strips))
            .zip(self.chunk_spans.par_chunks_mut(ny))
            .for_each(|(((((st, so), x), l), counts), spans)| {
                for (((st, so), x), l) in st.iter_mut().zip(so).zip(x).zip(l) {
                    *st = Stencil::new(grid, *x, *l);
                    let strip = st.y.base / STRIP_ROWS;
                    *so = strip as u32;
                    counts[strip] += 1;
                    let bx = st.x.base as u32;
                    spans[st.y.base] = hull(spans[st.y.base], [bx, bx + 3]);
                }
            });
        // Strip starts, and node-row spans from the stencil base rows r−2, r−1, r.
        self.strip_start.fill(0);
        for counts in self.chunk_counts.chunks(strips) {
            for (s, c) in counts.iter().enumerate() {
                self.strip_start[s + 1] += *c as usize;
            }
        }
        for s in 0..strips {
            self.strip_start[s + 1] += self.strip_start[s];
        }
        self.active.fill(NO_SPAN);
        for spans in self.chunk_spans.chunks(ny) {
            for (r, span) in spans.iter().enumerate() {
                for row in &mut self.active[r..(r + 3).min(ny)] {
                    *row = hull(*row, *span);
                }
            }
        }
        for (d, a) in self.sums_dirty.iter_mut().zip(&self.active) {
            *d = hull(*d, *a);
        }
        // Counting sort of the point indices by strip (serial: one pass over 4-byte ids).
        self.strip_order.resize(n, 0);
        self.strip_fill.clear();
        self.strip_fill
            .extend_from_slice(&self.strip_start[..strips]);
        for (p, s) in self.strip_of.iter().enumerate() {
            let slot = &mut self.strip_fill[*s as usize];
            self.strip_order[*slot] = p as u32;
            *slot += 1;
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

    /// Stage: particle to grid. Pass 1 maps mass, momentum, heat capacity, heat content,
    /// internal forces and external loads; the nodal temperature follows with prescribed
    /// values imposed; pass 2 maps the conduction heat loads, which need it.
    pub fn particle_to_grid(&mut self, points: &MaterialPoints, step: u64) -> Result<(), MpmError> {
        self.bin_points(points);
        let params = &self.config.params;
        let row_len = self.config.grid.nodes()[0];
        let loads = &params.surface_loads;
        let stencils = &self.stencils;

        // Pass 1. Per node (a, b): φ = wx[a] wy[b], ∇φ = (gx[a] wy[b], wx[a] gy[b]); the
        // factors of row b are taken out of the inner loop.
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
                let s = points.stress[p];
                let (mvx, mvy) = (m * v[0], m * v[1]);
                let vs = [vol * s[0], vol * s[1], vol * s[2]];
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
                let first = (st.y.base - row0) * row_len + st.x.base;
                for b in 0..3 {
                    let (wy, gy) = (st.y.w[b], st.y.g[b]);
                    let (rm, rmvx, rmvy, rmc, rmct) =
                        (wy * m, wy * mvx, wy * mvy, wy * mc, wy * mct);
                    // −σ·∇φ V: x row (σxx ∇φx + σxy ∇φy), y row (σxy ∇φx + σyy ∇φy).
                    let (fxg, fxw, fyg, fyw) = (wy * vs[0], gy * vs[2], wy * vs[2], gy * vs[1]);
                    let start = first + b * row_len;
                    let row = &mut nodes[start..start + 3];
                    for (a, n) in row.iter_mut().enumerate() {
                        let (wx, gx) = (st.x.w[a], st.x.g[a]);
                        n.mass += wx * rm;
                        n.momentum[0] += wx * rmvx;
                        n.momentum[1] += wx * rmvy;
                        n.capacity += wx * rmc;
                        n.heat_content += wx * rmct;
                        n.force[0] -= gx * fxg + wx * fxw;
                        n.force[1] -= gx * fyg + wx * fyw;
                    }
                }
                if loaded {
                    for b in 0..3 {
                        let start = first + b * row_len;
                        let row = &mut nodes[start..start + 3];
                        for (wx, n) in st.x.w.iter().zip(row) {
                            let w = wx * st.y.w[b];
                            n.force[0] += w * f[0];
                            n.force[1] += w * f[1];
                            n.heat_load += w * q;
                        }
                    }
                }
            },
        );

        // Nodal temperature and prescribed temperatures, on the active nodes.
        let fixed = &self.config.fixed_temperature;
        let sums = &self.grid_fields.sums;
        let bad = self
            .grid_fields
            .temperature_old
            .par_chunks_mut(row_len)
            .zip(self.temperature_mapped.par_chunks_mut(row_len))
            .zip(sums.par_chunks(row_len))
            .zip(fixed.par_chunks(row_len))
            .zip(self.active.par_iter())
            .enumerate()
            .filter_map(|(j, ((((t, tm), s), tf), span))| {
                let cols = columns(*span, row_len);
                let first = j * row_len + cols.start;
                let mut bad = None;
                for (i, (((t, tm), s), tf)) in t[cols.clone()]
                    .iter_mut()
                    .zip(&mut tm[cols.clone()])
                    .zip(&s[cols.clone()])
                    .zip(&tf[cols])
                    .enumerate()
                {
                    let mapped = if s.capacity > 0.0 {
                        s.heat_content / s.capacity
                    } else {
                        0.0
                    };
                    *tm = mapped;
                    *t = if tf.is_nan() { mapped } else { *tf };
                    if bad.is_none() && !t.is_finite() {
                        bad = Some(first + i);
                    }
                }
                bad
            })
            .min();
        if let Some(i) = bad {
            return Err(MpmError::NonFinite {
                quantity: "nodal temperature",
                place: "grid node",
                index: i,
                stage: "particle_to_grid",
                step,
            });
        }

        // Pass 2: Q_int = −V_p ∇φ_Ip · k ∇T_p with ∇T_p = Σ_J ∇φ_Jp T_J.
        let temp = &self.grid_fields.temperature_old;
        Self::scatter(
            &mut self.grid_fields.sums,
            row_len,
            &self.strip_start,
            &self.strip_order,
            |nodes, row0, p| {
                let k = points.conductivity[p];
                if k == [0.0; 3] {
                    return;
                }
                let st = &stencils[p];
                let vol = points.volume[p];
                let origin = st.y.base * row_len + st.x.base;
                let mut gt = [0.0; 2];
                for b in 0..3 {
                    let start = origin + b * row_len;
                    let t = &temp[start..start + 3];
                    let mut tg = 0.0;
                    let mut tw = 0.0;
                    for ((g, w), t) in st.x.g.iter().zip(&st.x.w).zip(t) {
                        tg += g * t;
                        tw += w * t;
                    }
                    gt[0] += st.y.w[b] * tg;
                    gt[1] += st.y.g[b] * tw;
                }
                let kg = [
                    vol * (k[0] * gt[0] + k[2] * gt[1]),
                    vol * (k[2] * gt[0] + k[1] * gt[1]),
                ];
                let first = (st.y.base - row0) * row_len + st.x.base;
                for b in 0..3 {
                    let (cg, cw) = (st.y.w[b] * kg[0], st.y.g[b] * kg[1]);
                    let start = first + b * row_len;
                    let row = &mut nodes[start..start + 3];
                    for (a, n) in row.iter_mut().enumerate() {
                        n.heat_load -= st.x.g[a] * cg + st.x.w[a] * cw;
                    }
                }
            },
        );
        Ok(())
    }

    /// Stage: grid update (B-Eqs. 20–22) with velocity conditions, prescribed temperatures
    /// and walls, on the active nodes; nodes that points left get the empty-node values.
    /// `time` is the time at the start of the step. Rows are updated in parallel; the wall
    /// reactions are summed per row, then over rows in row order.
    pub fn grid_update(&mut self, dt: f64, time: f64, step: u64) -> Result<(), MpmError> {
        let grid = &self.config.grid;
        let row_len = grid.nodes()[0];
        let gf = &mut self.grid_fields;
        let mask = &self.config.velocity_mask;
        let fixed = &self.config.fixed_temperature;
        let gravity = self.config.params.gravity;
        let walls = &self.config.params.walls;
        let per_row = walls.len().max(1);
        let inv_dt = 1.0 / dt;
        let rows = gf
            .velocity_old
            .par_chunks_mut(row_len)
            .zip(gf.velocity.par_chunks_mut(row_len))
            .zip(gf.acceleration.par_chunks_mut(row_len))
            .zip(gf.temperature_old.par_chunks_mut(row_len))
            .zip(gf.temperature.par_chunks_mut(row_len))
            .zip(gf.temperature_rate.par_chunks_mut(row_len))
            .zip(self.temperature_mapped.par_chunks_mut(row_len))
            .zip(self.row_reactions.par_chunks_mut(per_row))
            .map(|(((((((vo, v), a), to), t), tr), tm), reactions)| NodeRow {
                velocity_old: vo,
                velocity: v,
                acceleration: a,
                temperature_old: to,
                temperature: t,
                temperature_rate: tr,
                temperature_mapped: tm,
                reactions,
            });
        let bad = rows
            .zip(gf.sums.par_chunks(row_len))
            .zip(mask.par_chunks(row_len).zip(fixed.par_chunks(row_len)))
            .zip(self.active.par_iter().zip(self.fields_dirty.par_iter_mut()))
            .enumerate()
            .filter_map(|(j, (((row, sums), (mask, fixed)), (active, dirty)))| {
                row.reactions.fill([0.0; 2]);
                let cols = columns(*active, row_len);
                for i in columns(*dirty, row_len) {
                    if !cols.contains(&i) {
                        row.velocity_old[i] = [0.0; 2];
                        row.velocity[i] = [0.0; 2];
                        row.acceleration[i] = [0.0; 2];
                        row.temperature_old[i] = empty_temperature(fixed[i]);
                        row.temperature[i] = empty_temperature(fixed[i]);
                        row.temperature_rate[i] = 0.0;
                        row.temperature_mapped[i] = 0.0;
                    }
                }
                *dirty = *active;
                let mut bad = None;
                for i in cols {
                    let s = &sums[i];
                    let (v0, v1) = if s.mass > 0.0 {
                        let inv_m = 1.0 / s.mass;
                        let mut v0 = [s.momentum[0] * inv_m, s.momentum[1] * inv_m];
                        let mut v1 = [
                            v0[0] + (s.force[0] * inv_m + gravity[0]) * dt,
                            v0[1] + (s.force[1] * inv_m + gravity[1]) * dt,
                        ];
                        if mask[i] & 1 != 0 {
                            v0[0] = 0.0;
                            v1[0] = 0.0;
                        }
                        if mask[i] & 2 != 0 {
                            v0[1] = 0.0;
                            v1[1] = 0.0;
                        }
                        let x = grid.node_position(i, j);
                        for (wall, r) in walls.iter().zip(row.reactions.iter_mut()) {
                            if wall.active(time) && wall.distance(x, time) <= 0.0 {
                                let c = wall.constrain(v1);
                                r[0] -= s.mass * (c[0] - v1[0]) * inv_dt;
                                r[1] -= s.mass * (c[1] - v1[1]) * inv_dt;
                                v1 = c;
                            }
                        }
                        (v0, v1)
                    } else {
                        ([0.0; 2], [0.0; 2])
                    };
                    row.velocity_old[i] = v0;
                    row.velocity[i] = v1;
                    row.acceleration[i] = [(v1[0] - v0[0]) * inv_dt, (v1[1] - v0[1]) * inv_dt];
                    let tf = fixed[i];
                    let to = row.temperature_old[i];
                    let (rate, t1) = if !tf.is_nan() {
                        let rate = if s.mass > 0.0 {
                            (tf - row.temperature_mapped[i]) * inv_dt
                        } else {
                            0.0
                        };
                        (rate, tf)
                    } else if s.capacity > 0.0 && s.mass > 0.0 {
                        let rate = s.heat_load / s.capacity;
                        (rate, to + rate * dt)
                    } else {
                        (0.0, to)
                    };
                    row.temperature_rate[i] = rate;
                    row.temperature[i] = t1;
                    if bad.is_none() && !(v1[0].is_finite() && v1[1].is_finite() && t1.is_finite())
                    {
                        bad = Some(j * row_len + i);
                    }
                }
                bad
            })
            .min();
        for (w, reaction) in self.wall_reactions.iter_mut().enumerate() {
            *reaction = [0.0; 2];
            for r in self.row_reactions.chunks(per_row) {
                reaction[0] += r[w][0];
                reaction[1] += r[w][1];
            }
        }
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
    /// gradient `L_p = Σ_I v_I^{t+Δt} ⊗ ∇φ_Ip` for the constitutive stage. The FLIP increment
    /// `Δt Σ_I φ_Ip a_I` is gathered as `Σ_I φ_Ip (v_I^{t+Δt} − v_I^t)`.
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
        let grid = &self.config.grid;
        let (lo, hi) = (grid.origin(), grid.upper());
        let row_len = grid.nodes()[0];
        let gf = &self.grid_fields;
        let stencils = &self.stencils;
        // Chunks of points in parallel, each a plain loop; per chunk the first point with a
        // non-finite value and the first point outside the grid.
        const C: usize = POINT_CHUNK;
        let (non_finite, outside) = points
            .position
            .par_chunks_mut(C)
            .zip(points.velocity.par_chunks_mut(C))
            .zip(points.temperature.par_chunks_mut(C))
            .zip(points.remapped_temperature.par_chunks_mut(C))
            .zip(
                self.velocity_gradient
                    .par_chunks_mut(C)
                    .zip(self.temperature_rate.par_chunks_mut(C))
                    .zip(stencils.par_chunks(C).zip(points.half_size.par_chunks(C))),
            )
            .enumerate()
            .map(|(c, ((((x, v), t), tr), ((l, tdot), (st, half))))| {
                let mut bad = (usize::MAX, usize::MAX);
                let rows = x
                    .iter_mut()
                    .zip(v.iter_mut())
                    .zip(t.iter_mut())
                    .zip(tr.iter_mut())
                    .zip(l.iter_mut().zip(tdot.iter_mut()).zip(st.iter().zip(half)));
                for (j, ((((x, v), t), tr), ((l, tdot), (st, half)))) in rows.enumerate() {
                    let mut v_old = [0.0; 2];
                    let mut v_new = [0.0; 2];
                    let mut rate = 0.0;
                    let mut t_new = 0.0;
                    let mut lg = [0.0; 4];
                    let origin = st.y.base * row_len + st.x.base;
                    for b in 0..3 {
                        let start = origin + b * row_len;
                        let vo = &gf.velocity_old[start..start + 3];
                        let vn = &gf.velocity[start..start + 3];
                        let tn = &gf.temperature[start..start + 3];
                        let rn = &gf.temperature_rate[start..start + 3];
                        // Row sums weighted by wx and by gx, then by wy and gy.
                        let mut s = [0.0; 8];
                        for a in 0..3 {
                            let (wx, gx) = (st.x.w[a], st.x.g[a]);
                            s[0] += wx * vo[a][0];
                            s[1] += wx * vo[a][1];
                            s[2] += wx * vn[a][0];
                            s[3] += wx * vn[a][1];
                            s[4] += wx * rn[a];
                            s[5] += wx * tn[a];
                            s[6] += gx * vn[a][0];
                            s[7] += gx * vn[a][1];
                        }
                        let (wy, gy) = (st.y.w[b], st.y.g[b]);
                        v_old[0] += wy * s[0];
                        v_old[1] += wy * s[1];
                        v_new[0] += wy * s[2];
                        v_new[1] += wy * s[3];
                        rate += wy * s[4];
                        t_new += wy * s[5];
                        lg[0] += wy * s[6];
                        lg[1] += gy * s[2];
                        lg[2] += wy * s[7];
                        lg[3] += gy * s[3];
                    }
                    let vp = *v;
                    let v1 = [
                        vp[0] + (v_new[0] - v_old[0]) - (a_pic + a_p) * vp[0]
                            + (a_pic - a_g) * v_old[0],
                        vp[1] + (v_new[1] - v_old[1]) - (a_pic + a_p) * vp[1]
                            + (a_pic - a_g) * v_old[1],
                    ];
                    x[0] += dt * v_new[0] - 0.5 * dt * (v1[0] - vp[0]);
                    x[1] += dt * v_new[1] - 0.5 * dt * (v1[1] - vp[1]);
                    *v = v1;
                    *t += rate * dt;
                    *tr = t_new;
                    *l = lg;
                    *tdot = rate;
                    let finite = x[0].is_finite()
                        && x[1].is_finite()
                        && v1[0].is_finite()
                        && v1[1].is_finite()
                        && t.is_finite();
                    let inside = x[0] - half[0] >= lo[0]
                        && x[0] + half[0] <= hi[0]
                        && x[1] - half[1] >= lo[1]
                        && x[1] + half[1] <= hi[1];
                    let i = c * C + j;
                    if !finite {
                        bad.0 = bad.0.min(i);
                    } else if !inside {
                        bad.1 = bad.1.min(i);
                    }
                }
                bad
            })
            .reduce(
                || (usize::MAX, usize::MAX),
                |a, b| (a.0.min(b.0), a.1.min(b.1)),
            );
        // Non-finite values are reported before a point outside the grid.
        if non_finite != usize::MAX {
            return Err(MpmError::NonFinite {
                quantity: "point position, velocity or temperature",
                place: "material point",
                index: non_finite,
                stage: "grid_to_particle",
                step,
            });
        }
        if outside != usize::MAX {
            return points.check_inside(grid, outside, step + 1);
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
        let update = |i: usize,
                      f: &mut Mat2,
                      vol: &mut f64,
                      eps: &mut Sym2,
                      sig: &mut Sym2,
                      q: &mut f64,
                      k: &mut Sym2,
                      ms: &mut M::PointState,
                      (l, tdot, t, m, v0): (&Mat2, f64, f64, f64, f64)|
         -> Result<(), MpmError> {
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
                return Err(MpmError::InvalidPoint {
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
                temperature: t,
                temperature_rate: tdot,
                stress: *sig,
                density: m / *vol,
                dt,
            };
            let r = material.respond(ms, &input)?;
            if !(r.stress.iter().all(|s| s.is_finite())
                && r.heat_source.is_finite()
                && r.conductivity.iter().all(|c| c.is_finite()))
            {
                return Err(MpmError::NonFinite {
                    quantity: "stress, heat source or conductivity",
                    place: "material point",
                    index: i,
                    stage: "constitutive_update",
                    step,
                });
            }
            *sig = r.stress;
            // Constant for most materials: stores skipped, lines stay clean.
            if *q != r.heat_source {
                *q = r.heat_source;
            }
            if *k != r.conductivity {
                *k = r.conductivity;
            }
            Ok(())
        };
        // Chunks of points in parallel, each a plain loop that keeps its first error; the
        // error of the lowest point index is reported.
        const C: usize = POINT_CHUNK;
        let err = pts
            .deformation_gradient
            .par_chunks_mut(C)
            .zip(pts.volume.par_chunks_mut(C))
            .zip(pts.strain.par_chunks_mut(C))
            .zip(pts.stress.par_chunks_mut(C))
            .zip(pts.heat_source.par_chunks_mut(C))
            .zip(pts.conductivity.par_chunks_mut(C))
            .zip(
                state
                    .material
                    .par_chunks_mut(C)
                    .zip(self.velocity_gradient.par_chunks(C))
                    .zip(self.temperature_rate.par_chunks(C))
                    .zip(
                        pts.remapped_temperature
                            .par_chunks(C)
                            .zip(pts.mass.par_chunks(C))
                            .zip(pts.initial_volume.par_chunks(C)),
                    ),
            )
            .enumerate()
            .filter_map(
                |(c, ((((((f, vol), eps), sig), q), k), (((ms, l), tdot), ((t, m), v0))))| {
                    let mut first = None;
                    let rows = f
                        .iter_mut()
                        .zip(vol.iter_mut())
                        .zip(eps.iter_mut())
                        .zip(sig.iter_mut())
                        .zip(q.iter_mut())
                        .zip(k.iter_mut())
                        .zip(ms.iter_mut())
                        .zip(l.iter().zip(tdot).zip(t.iter().zip(m).zip(v0)));
                    for (j, (((((((f, vol), eps), sig), q), k), ms), ((l, tdot), ((t, m), v0)))) in
                        rows.enumerate()
                    {
                        let i = c * C + j;
                        let r = update(i, f, vol, eps, sig, q, k, ms, (l, *tdot, *t, *m, *v0));
                        if let Err(e) = r {
                            first.get_or_insert(e);
                        }
                    }
                    first
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
