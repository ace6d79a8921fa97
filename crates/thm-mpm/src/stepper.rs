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
//! its contributions in the same order (strip by strip, each strip in point index order)
//! whatever the number of threads, so results are bit-identical for any thread count. The
//! binning is parallel too: each chunk of points sorts its own points by strip, and a strip
//! visits the chunks in order. A sweep over the strips of one colour is split recursively into
//! runs of equal point count, so two threads get equal shares however the points are spread.
//! Gathers (grid → particle) and node updates are embarrassingly parallel; node updates visit
//! only the active node spans (per node row, the columns the stencils touch), and the 1D
//! weights and gradients of every point are computed once per step and shared by both scatter
//! passes and the gather.
//!
//! [`Mpm::step`] runs the stages fused into six parallel sweeps (fewer joins of the threads,
//! and each point's data is loaded fewer times): the binning carries the time-step test; the
//! even strips of pass 1 zero their rows before scattering; once an odd strip has scattered,
//! its rows are complete, so pass 1 of the odd strips computes their nodal temperatures and
//! pass 2 of the odd strips updates their nodes; the gather and the constitutive update run
//! on each chunk of points in turn. The public stage functions remain, for callers that run
//! or time the stages apart, with the same results.

use crate::boundary::{RigidWall, SurfaceLoad};
use crate::config::MpmConfig;
use crate::error::MpmError;
use crate::grid::Grid;
use crate::material::{BatchConstitutive, Constitutive, MaterialInput, MaterialResponse};
use crate::points::{Mat2, MaterialPoints, Sym2};
use crate::shape::{PackedStencil, Stencil};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Node rows per scatter strip (≥ 2 keeps same-colour strips disjoint).
pub const STRIP_ROWS: usize = 2;

/// Points per chunk of the point stages (gather, constitutive update). Rayon splits their
/// sweeps down to one or two chunks per task, so that a thread that is descheduled (on a
/// shared machine) holds little work that the other threads cannot take over.
const POINT_CHUNK: usize = 512;

/// Points per binning chunk (and per work item of the time-step test). Each chunk sorts its
/// own points by strip and a strip visits the chunks in order, so the scatter order is the
/// point index order for any chunk size.
const BIN_CHUNK: usize = 1024;

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
/// (zero sums and velocities, the prescribed temperature or 0, zero rate): the scatter zeroes
/// the sums where the last scatter wrote (`sums_dirty`) before it adds to them, and the grid
/// update restores the empty-node values where the last update wrote and no point is now
/// (`fields_dirty`).
#[derive(Debug, Clone)]
pub struct Mpm {
    config: MpmConfig,
    grid_fields: GridFields,
    /// Mapped nodal temperature before prescribed values were imposed.
    temperature_mapped: Vec<f64>,
    /// The stencil of each point, computed once per step (binning) for both scatter passes
    /// and the gather.
    stencils: Vec<PackedStencil>,
    /// Number of scatter strips.
    strips: usize,
    /// The point indices of each binning chunk, sorted by strip (index order within a strip),
    /// in the chunk's own part of the array.
    strip_order: Vec<u32>,
    /// Per binning chunk, where each strip's points start in the chunk's part of
    /// `strip_order`, and the chunk's length (`chunks × (strips + 1)`).
    chunk_starts: Vec<u32>,
    /// Column span of the stencils by stencil base row, per binning chunk (`chunks × rows`).
    chunk_spans: Vec<Span>,
    /// Points per strip.
    strip_points: Vec<usize>,
    /// Cumulative work (points + 1) of the scatter units of the even and the odd colour
    /// ([`Units`]), to split a sweep into halves of equal work.
    unit_work: [Vec<usize>; 2],
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
    /// Inputs of the batched constitutive update, one per point.
    inputs: Vec<MaterialInput>,
    /// Responses of the batched constitutive update, one per point.
    responses: Vec<MaterialResponse>,
}

/// Placeholder entry of the batched inputs (overwritten before use).
const EMPTY_INPUT: MaterialInput = MaterialInput {
    point: 0,
    velocity_gradient: [0.0; 4],
    deformation_gradient: [1.0, 0.0, 0.0, 1.0],
    temperature: 0.0,
    temperature_rate: 0.0,
    stress: [0.0; 3],
    density: 0.0,
    dt: 0.0,
};

/// Placeholder entry of the batched responses (overwritten before use).
const EMPTY_RESPONSE: MaterialResponse = MaterialResponse {
    stress: [0.0; 3],
    heat_source: 0.0,
    conductivity: [0.0; 3],
};

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

/// The scatter units of one colour. Unit `u` owns the node rows `start(u)..start(u + 1)` and
/// scatters the points of strip `2u − parity` (none for unit 0 of the odd colour, which owns
/// rows `0..STRIP_ROWS` only), whose stencils lie in those rows. The units of a colour tile
/// all node rows, so a sweep over them can finish a row as soon as its unit has scattered,
/// when no later sweep writes the row.
#[derive(Debug, Clone, Copy)]
struct Units {
    parity: usize,
    rows: usize,
}

impl Units {
    /// Number of units.
    fn count(self) -> usize {
        (self.rows.div_ceil(STRIP_ROWS) + self.parity).div_ceil(2)
    }
    /// First node row of unit `u` (`rows` for `u = count()`).
    fn start(self, u: usize) -> usize {
        ((2 * u).saturating_sub(self.parity) * STRIP_ROWS).min(self.rows)
    }
    /// The strip unit `u` scatters.
    fn strip(self, u: usize) -> Option<usize> {
        (2 * u).checked_sub(self.parity)
    }
}

/// Node data of the rows `first_row..first_row + sums_dirty.len()`: one scatter unit or a run
/// of them.
struct Band<'a> {
    first_row: usize,
    sums: &'a mut [NodeSums],
    velocity_old: &'a mut [[f64; 2]],
    velocity: &'a mut [[f64; 2]],
    acceleration: &'a mut [[f64; 2]],
    temperature_old: &'a mut [f64],
    temperature: &'a mut [f64],
    temperature_rate: &'a mut [f64],
    temperature_mapped: &'a mut [f64],
    sums_dirty: &'a mut [Span],
    fields_dirty: &'a mut [Span],
    reactions: &'a mut [[f64; 2]],
}

impl<'a> Band<'a> {
    /// Number of node rows.
    fn rows(&self) -> usize {
        self.sums_dirty.len()
    }

    /// The first `rows` rows and the rest.
    fn split(self, rows: usize, row_len: usize, per_row: usize) -> (Band<'a>, Band<'a>) {
        let k = rows * row_len;
        let (s0, s1) = self.sums.split_at_mut(k);
        let (vo0, vo1) = self.velocity_old.split_at_mut(k);
        let (v0, v1) = self.velocity.split_at_mut(k);
        let (a0, a1) = self.acceleration.split_at_mut(k);
        let (to0, to1) = self.temperature_old.split_at_mut(k);
        let (t0, t1) = self.temperature.split_at_mut(k);
        let (tr0, tr1) = self.temperature_rate.split_at_mut(k);
        let (tm0, tm1) = self.temperature_mapped.split_at_mut(k);
        let (sd0, sd1) = self.sums_dirty.split_at_mut(rows);
        let (fd0, fd1) = self.fields_dirty.split_at_mut(rows);
        let (r0, r1) = self.reactions.split_at_mut(rows * per_row);
        (
            Band {
                first_row: self.first_row,
                sums: s0,
                velocity_old: vo0,
                velocity: v0,
                acceleration: a0,
                temperature_old: to0,
                temperature: t0,
                temperature_rate: tr0,
                temperature_mapped: tm0,
                sums_dirty: sd0,
                fields_dirty: fd0,
                reactions: r0,
            },
            Band {
                first_row: self.first_row + rows,
                sums: s1,
                velocity_old: vo1,
                velocity: v1,
                acceleration: a1,
                temperature_old: to1,
                temperature: t1,
                temperature_rate: tr1,
                temperature_mapped: tm1,
                sums_dirty: sd1,
                fields_dirty: fd1,
                reactions: r1,
            },
        )
    }
}

/// Runs `task(u, band)` for the units `lo..hi` of one colour, `band` holding exactly their
/// rows: the run is split where its cumulative work `work` is halved and the halves run in
/// parallel (`rayon::join`). Every unit does the same work whatever the split, and the
/// results are merged with `combine`, which must be associative and commutative (a minimum),
/// so the outcome does not depend on the number of threads.
#[allow(clippy::too_many_arguments)]
fn run_units<R, T, C>(
    band: Band<'_>,
    units: Units,
    lo: usize,
    hi: usize,
    work: &[usize],
    shape: (usize, usize),
    task: &T,
    combine: &C,
) -> R
where
    R: Send,
    T: Fn(usize, Band<'_>) -> R + Sync,
    C: Fn(R, R) -> R + Sync,
{
    if hi - lo <= 1 {
        return task(lo, band);
    }
    let half = work[lo] + (work[hi] - work[lo]) / 2;
    let mid = (lo + 1 + work[lo + 1..hi].partition_point(|&w| w < half)).min(hi - 1);
    let (a, b) = band.split(units.start(mid) - units.start(lo), shape.0, shape.1);
    let (ra, rb) = rayon::join(
        || run_units(a, units, lo, mid, work, shape, task, combine),
        || run_units(b, units, mid, hi, work, shape, task, combine),
    );
    combine(ra, rb)
}

/// The smaller of two optional indices.
fn first_of(a: Option<usize>, b: Option<usize>) -> Option<usize> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

/// Calls `f(p)` for the points of strip `s` in index order: chunk by chunk, each chunk's
/// points of the strip in index order.
#[inline]
fn for_strip(
    order: &[u32],
    chunk_starts: &[u32],
    strips: usize,
    s: usize,
    mut f: impl FnMut(usize),
) {
    for (c, starts) in chunk_starts.chunks_exact(strips + 1).enumerate() {
        let base = c * BIN_CHUNK;
        for &p in &order[base + starts[s] as usize..base + starts[s + 1] as usize] {
            f(p as usize);
        }
    }
}

/// Pass 1 of the scatter for point `p` into `nodes` (node rows from `row0`): mass, momentum,
/// heat capacity, heat content, internal forces and external loads. Per node (a, b):
/// φ = wx[a] wy[b], ∇φ = (gx[a] wy[b], wx[a] gy[b]); the factors of row b are taken out of the
/// inner loop.
#[inline]
fn scatter_pass1(
    nodes: &mut [NodeSums],
    row0: usize,
    row_len: usize,
    st: &Stencil,
    points: &MaterialPoints,
    loads: &[SurfaceLoad],
    p: usize,
) {
    let m = points.mass[p];
    let v = points.velocity[p];
    let mc = m * points.specific_heat[p];
    let mct = mc * points.temperature[p];
    let vol = points.volume[p];
    let s = points.stress[p];
    let (mvx, mvy) = (m * v[0], m * v[1]);
    let vs = [vol * s[0], vol * s[1], vol * s[2]];
    // Gravity enters in the grid update as M_I b (= Σ_p φ_Ip m_p b, B-Eq. 18).
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
        let (rm, rmvx, rmvy, rmc, rmct) = (wy * m, wy * mvx, wy * mvy, wy * mc, wy * mct);
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
}

/// Pass 2 of the scatter for point `p`: `Q_int = −V_p ∇φ_Ip · k ∇T_p` with
/// `∇T_p = Σ_J ∇φ_Jp T_J`; `nodes` and `temp` hold the node rows from `row0`.
#[inline]
fn scatter_pass2(
    nodes: &mut [NodeSums],
    temp: &[f64],
    row0: usize,
    row_len: usize,
    st: &Stencil,
    points: &MaterialPoints,
    p: usize,
) {
    let k = points.conductivity[p];
    if k == [0.0; 3] {
        return;
    }
    let vol = points.volume[p];
    let first = (st.y.base - row0) * row_len + st.x.base;
    let mut gt = [0.0; 2];
    for b in 0..3 {
        let start = first + b * row_len;
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
    for b in 0..3 {
        let (cg, cw) = (st.y.w[b] * kg[0], st.y.g[b] * kg[1]);
        let start = first + b * row_len;
        let row = &mut nodes[start..start + 3];
        for (a, n) in row.iter_mut().enumerate() {
            n.heat_load -= st.x.g[a] * cg + st.x.w[a] * cw;
        }
    }
}

/// Nodal temperature of the columns `cols` of one row: the mapped `Σ m c T / C_I` (0 where
/// empty) into `tm`, and into `t` that or the prescribed value. Returns the first column whose
/// temperature is not finite.
#[inline]
fn nodal_temperature_row(
    t: &mut [f64],
    tm: &mut [f64],
    sums: &[NodeSums],
    fixed: &[f64],
    cols: std::ops::Range<usize>,
) -> Option<usize> {
    let first = cols.start;
    let mut bad = None;
    for (i, (((t, tm), s), tf)) in t[cols.clone()]
        .iter_mut()
        .zip(&mut tm[cols.clone()])
        .zip(&sums[cols.clone()])
        .zip(&fixed[cols])
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
}

/// The partner of a small-mass node `k` of a row (`0 < m_k ≤ tol`): the heavier of its two
/// row neighbours within `cols` whose mass is above `tol` (the left one on a tie), if any.
fn small_mass_partner(
    sums: &[NodeSums],
    cols: std::ops::Range<usize>,
    k: usize,
    tol: f64,
) -> Option<usize> {
    let m = |n: usize| sums[n].mass;
    if !(m(k) > 0.0 && m(k) <= tol) {
        return None;
    }
    let left = (k > cols.start).then(|| k - 1).filter(|&n| m(n) > tol);
    let right = (k + 1 < cols.end).then_some(k + 1).filter(|&n| m(n) > tol);
    match (left, right) {
        (Some(l), Some(r)) => Some(if m(r) > m(l) { r } else { l }),
        (l, r) => l.or(r),
    }
}

/// Force and mass of node `i` merged with the small-mass nodes of its row that it partners
/// ([`small_mass_partner`]), or of a small-mass `i` merged with its partner and the partner's
/// other small-mass neighbour: every node of a merged group takes the group's acceleration,
/// so the group's momentum changes by its total force. `None` when `i` is in no group.
fn merged_sums(
    sums: &[NodeSums],
    cols: std::ops::Range<usize>,
    i: usize,
    tol: f64,
) -> Option<([f64; 2], f64)> {
    let head = if sums[i].mass > tol {
        i
    } else {
        small_mass_partner(sums, cols.clone(), i, tol)?
    };
    let mut force = sums[head].force;
    let mut mass = sums[head].mass;
    let mut any = false;
    for k in [head.wrapping_sub(1), head + 1] {
        if cols.contains(&k) && small_mass_partner(sums, cols.clone(), k, tol) == Some(head) {
            force[0] += sums[k].force[0];
            force[1] += sums[k].force[1];
            mass += sums[k].mass;
            any = true;
        }
    }
    any.then_some((force, mass))
}

/// Fixed inputs of the grid update.
struct UpdateInputs<'a> {
    grid: &'a Grid,
    walls: &'a [RigidWall],
    gravity: [f64; 2],
    node_mass_tolerance: f64,
    merge_small_mass_nodes: bool,
    local_damping: f64,
    dt: f64,
    time: f64,
}

/// Grid update (B-Eqs. 20–22) of node row `j`: velocity conditions, prescribed temperatures
/// and walls on the active columns, the empty-node values where the last update wrote and no
/// point is now; the wall reactions of the row into `row.reactions`. Returns the flat index of
/// the first node with a non-finite velocity or temperature.
#[allow(clippy::too_many_arguments)]
fn update_row(
    j: usize,
    row: NodeRow<'_>,
    sums: &[NodeSums],
    mask: &[u8],
    fixed: &[f64],
    active: Span,
    dirty: &mut Span,
    inp: &UpdateInputs<'_>,
) -> Option<usize> {
    let row_len = sums.len();
    let (dt, time, gravity) = (inp.dt, inp.time, inp.gravity);
    let inv_dt = 1.0 / dt;
    row.reactions.fill([0.0; 2]);
    let cols = columns(active, row_len);
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
    *dirty = active;
    let mut bad = None;
    for i in cols.clone() {
        let s = &sums[i];
        let merged = if inp.merge_small_mass_nodes {
            merged_sums(sums, cols.clone(), i, inp.node_mass_tolerance)
        } else {
            None
        };
        let updated = s.mass > inp.node_mass_tolerance || (merged.is_some() && s.mass > 0.0);
        let (v0, v1) = if updated {
            let inv_own = 1.0 / s.mass;
            let mut v0 = [s.momentum[0] * inv_own, s.momentum[1] * inv_own];
            // The force and mass the velocity update uses: the node's own, or those of the
            // node merged with its small-mass neighbours (the same acceleration for both).
            let (force, mass) = merged.unwrap_or((s.force, s.mass));
            let inv_m = 1.0 / mass;
            let x = inp.grid.node_position(i, j);
            // A node a wall holds is not damped: the wall's reaction is its undamped force.
            let mut v1 = if inp.local_damping > 0.0 && !inp.walls.iter().any(|w| w.acts_on(x, time))
            {
                let a = inp.local_damping;
                let mut f = [force[0] + mass * gravity[0], force[1] + mass * gravity[1]];
                for (f, v) in f.iter_mut().zip(v0) {
                    if v != 0.0 {
                        *f -= a * f.abs() * v.signum();
                    }
                }
                [v0[0] + f[0] * inv_m * dt, v0[1] + f[1] * inv_m * dt]
            } else {
                [
                    v0[0] + (force[0] * inv_m + gravity[0]) * dt,
                    v0[1] + (force[1] * inv_m + gravity[1]) * dt,
                ]
            };
            if mask[i] & 1 != 0 {
                v0[0] = 0.0;
                v1[0] = 0.0;
            }
            if mask[i] & 2 != 0 {
                v0[1] = 0.0;
                v1[1] = 0.0;
            }
            for (wall, r) in inp.walls.iter().zip(row.reactions.iter_mut()) {
                if wall.acts_on(x, time) {
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
        if bad.is_none() && !(v1[0].is_finite() && v1[1].is_finite() && t1.is_finite()) {
            bad = Some(j * row_len + i);
        }
    }
    bad
}

/// Inputs of the divide-free time-step test ([`Mpm::check_time_step`]).
#[derive(Debug, Clone, Copy)]
struct StableTest {
    /// `Δt²`.
    mech: f64,
    /// `Δt b`.
    therm: f64,
    /// `(1 − 1e-9) l_e²`.
    bound: f64,
}

impl StableTest {
    fn new(config: &MpmConfig, dt: f64) -> Self {
        const SAFE: f64 = 1.0 - 1e-9;
        let le = config.grid.cell_size();
        Self {
            mech: dt * dt,
            therm: dt * config.params.thermal_time_step_factor,
            bound: SAFE * le * le,
        }
    }

    /// True when the point clearly satisfies B-Eqs. 30–31: `Δt² M V < l_e² m` and
    /// `Δt b k̄ V < l_e² m c`, with a relative margin of 1e-9.
    #[inline]
    fn point(&self, modulus: f64, (m, v, c, k): (f64, f64, f64, Sym2)) -> bool {
        let kbar = 0.5 * (k[0] + k[1]);
        let room = self.bound * m;
        (modulus <= 0.0 || modulus.is_nan() || self.mech * modulus * v <= room)
            && (kbar <= 0.0 || kbar.is_nan() || self.therm * kbar * v <= room * c)
    }

    /// True when every point of `range` clearly satisfies both limits; `modulus(ms)` is the
    /// wave modulus of a point's material state.
    fn range<S, F: Fn(&S) -> f64>(
        &self,
        pts: &MaterialPoints,
        ms: &[S],
        modulus: F,
        range: std::ops::Range<usize>,
    ) -> bool {
        let r = range;
        pts.mass[r.clone()]
            .iter()
            .zip(&pts.volume[r.clone()])
            .zip(&pts.specific_heat[r.clone()])
            .zip(&pts.conductivity[r.clone()])
            .zip(&ms[r])
            .all(|((((m, v), c), k), ms)| self.point(modulus(ms), (*m, *v, *c, *k)))
    }
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
        let units = |parity| Units { parity, rows: ny }.count() + 1;
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
            strips,
            strip_order: Vec::new(),
            chunk_starts: Vec::new(),
            chunk_spans: Vec::new(),
            strip_points: vec![0; strips],
            unit_work: [vec![0; units(0)], vec![0; units(1)]],
            active: vec![NO_SPAN; ny],
            sums_dirty: vec![NO_SPAN; ny],
            fields_dirty: vec![NO_SPAN; ny],
            velocity_gradient: Vec::new(),
            temperature_rate: Vec::new(),
            wall_reactions: vec![[0.0; 2]; walls],
            row_reactions: vec![[0.0; 2]; ny * walls.max(1)],
            last_step: None,
            inputs: Vec::new(),
            responses: Vec::new(),
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
    /// Replaces the surface loads (validated as in [`MpmConfig::new`]) from the next step on,
    /// for loads that follow the material (e.g. a confining pressure on a bulging side, one
    /// load per boundary point). Everything else of the stepper is kept.
    pub fn set_surface_loads(&mut self, loads: Vec<SurfaceLoad>) -> Result<(), MpmError> {
        crate::config::check_surface_loads(&loads)?;
        self.config.params.surface_loads = loads;
        Ok(())
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
        self.time_step_limits_with(&state.points, |p| material.wave_modulus(&state.material[p]))
    }

    /// Limits B-Eqs. 30–31 for points whose wave modulus is `wave_modulus(p)` (Pa) (any
    /// material, e.g. a [`BatchConstitutive`] one).
    pub fn time_step_limits_with<F: Fn(usize) -> f64 + Sync>(
        &self,
        pts: &MaterialPoints,
        wave_modulus: F,
    ) -> TimeStepLimits {
        let le = self.config.grid.cell_size();
        let b = self.config.params.thermal_time_step_factor;
        let (mech, th) = (0..pts.len())
            .into_par_iter()
            .map(|p| {
                let rho = pts.mass[p] / pts.volume[p];
                let modulus = wave_modulus(p);
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
        let test = StableTest::new(&self.config, dt);
        let pts = &state.points;
        let ms = &state.material;
        (0..pts.len().div_ceil(BIN_CHUNK)).into_par_iter().all(|c| {
            test.range(
                pts,
                ms,
                |s| material.wave_modulus(s),
                c * BIN_CHUNK..((c + 1) * BIN_CHUNK).min(pts.len()),
            )
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
        check_dt(dt)?;
        if self.time_step_clearly_stable(state, material, dt) {
            return Ok(());
        }
        self.check_time_step_exactly(state, material, dt)
    }

    /// The exact test of B-Eqs. 30–31.
    fn check_time_step_exactly<M: Constitutive>(
        &self,
        state: &MpmState<M::PointState>,
        material: &M,
        dt: f64,
    ) -> Result<(), MpmError> {
        Self::check_limits(self.time_step_limits(state, material), dt)
    }

    /// Error when `dt` reaches either limit.
    fn check_limits(lim: TimeStepLimits, dt: f64) -> Result<(), MpmError> {
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
    ///
    /// The stages run fused into six parallel sweeps, with the results of the stage sequence
    /// in the module docs: binning with the time-step test; pass 1 of the even strips (each
    /// zeroing its rows first); pass 1 of the odd strips with the nodal temperature of their
    /// rows; pass 2 of the even strips; pass 2 of the odd strips with the grid update of their
    /// rows; gather and constitutive update per chunk of points.
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
        check_dt(dt)?;
        let test = StableTest::new(&self.config, dt);
        let (pts, ms) = (&state.points, &state.material);
        if !self.bin_points(pts, |r| {
            test.range(pts, ms, |s| material.wave_modulus(s), r)
        }) {
            self.check_time_step_exactly(state, material, dt)?;
        }
        self.scatter_sweeps(&state.points, state.step, Some((dt, state.time)))?;
        self.gather_and_respond(state, material, dt)?;
        state.time += dt;
        state.step += 1;
        self.last_step = Some(state.step);
        Ok(())
    }

    /// One explicit step with a [`BatchConstitutive`] material: the stages of [`Mpm::step`]
    /// up to the gather, then [`Mpm::constitutive_update_batch`], which hands every point to
    /// the material in one call. With [`crate::PerPoint`] it gives the same bits as
    /// [`Mpm::step`] with the wrapped model (tested).
    pub fn step_batch<M: BatchConstitutive>(
        &mut self,
        state: &mut MpmState<M::PointState>,
        material: &mut M,
        dt: f64,
    ) -> Result<(), M::Error> {
        if state.material.len() != state.points.len() {
            return Err(MpmError::MaterialStateCount {
                states: state.material.len(),
                points: state.points.len(),
            }
            .into());
        }
        if self.last_step != Some(state.step) {
            self.validate_state(state)?;
        }
        self.last_step = None;
        check_dt(dt)?;
        let test = StableTest::new(&self.config, dt);
        let (pts, ms) = (&state.points, &state.material);
        let model = &*material;
        if !self.bin_points(pts, |r| test.range(pts, ms, |s| model.wave_modulus(s), r)) {
            let lim = self.time_step_limits_with(pts, |p| model.wave_modulus(&ms[p]));
            Self::check_limits(lim, dt)?;
        }
        self.scatter_sweeps(&state.points, state.step, Some((dt, state.time)))?;
        self.grid_to_particle(&mut state.points, dt, state.step)?;
        self.constitutive_update_batch(state, material, dt)?;
        state.time += dt;
        state.step += 1;
        self.last_step = Some(state.step);
        Ok(())
    }

    /// Stage: constitutive update through the batched seam. Per point (in parallel chunks)
    /// `F ← (I + L Δt) F`, `V = V_0 det F`, `ε += sym(L) Δt` and the [`MaterialInput`]; then
    /// one call of [`BatchConstitutive::respond_batch`] for all points; then stress, heat
    /// source and conductivity are checked for finiteness and stored. A point whose `det F`
    /// leaves `(0, ∞)` stops the step before the material is called (lowest point named).
    pub fn constitutive_update_batch<M: BatchConstitutive>(
        &mut self,
        state: &mut MpmState<M::PointState>,
        material: &mut M,
        dt: f64,
    ) -> Result<(), M::Error> {
        let pts = &mut state.points;
        let step = state.step;
        let n = pts.len();
        self.velocity_gradient.resize(n, [0.0; 4]);
        self.temperature_rate.resize(n, 0.0);
        self.inputs.resize(n, EMPTY_INPUT);
        self.responses.resize(n, EMPTY_RESPONSE);
        const C: usize = POINT_CHUNK;
        let bad = (
            (
                pts.deformation_gradient.par_chunks_mut(C),
                pts.volume.par_chunks_mut(C),
                pts.strain.par_chunks_mut(C),
                self.inputs.par_chunks_mut(C),
            ),
            (
                self.velocity_gradient.par_chunks(C),
                self.temperature_rate.par_chunks(C),
                pts.remapped_temperature.par_chunks(C),
                pts.stress.par_chunks(C),
                pts.mass.par_chunks(C),
                pts.initial_volume.par_chunks(C),
            ),
        )
            .into_par_iter()
            .with_max_len(2)
            .enumerate()
            .filter_map(|(c, ((f, vol, eps, inputs), (l, tdot, t, sig, m, v0)))| {
                let rows = f
                    .iter_mut()
                    .zip(vol.iter_mut())
                    .zip(eps.iter_mut())
                    .zip(inputs.iter_mut())
                    .zip(
                        l.iter()
                            .zip(tdot)
                            .zip(t.iter().zip(sig).zip(m.iter().zip(v0))),
                    );
                for (j, ((((f, vol), eps), input), ((l, tdot), ((t, sig), (m, v0))))) in
                    rows.enumerate()
                {
                    let i = c * C + j;
                    if let Err(det) = advance_kinematics(f, vol, eps, l, *v0, dt) {
                        return Some((i, det));
                    }
                    *input = MaterialInput {
                        point: i,
                        velocity_gradient: *l,
                        deformation_gradient: *f,
                        temperature: *t,
                        temperature_rate: *tdot,
                        stress: *sig,
                        density: m / *vol,
                        dt,
                    };
                }
                None
            })
            .min_by_key(|(i, _)| *i);
        if let Some((index, value)) = bad {
            return Err(MpmError::InvalidPoint {
                index,
                field: "det F",
                value,
                allowed: "(0, inf)",
            }
            .into());
        }
        material.respond_batch(&mut state.material, &self.inputs, &mut self.responses)?;
        let bad = self.responses.iter().position(|r| {
            !(r.stress.iter().all(|s| s.is_finite())
                && r.heat_source.is_finite()
                && r.conductivity.iter().all(|c| c.is_finite()))
        });
        if let Some(index) = bad {
            return Err(MpmError::NonFinite {
                quantity: "stress, heat source or conductivity",
                place: "material point",
                index,
                stage: "constitutive_update_batch",
                step,
            }
            .into());
        }
        for (((sig, q), k), r) in pts
            .stress
            .iter_mut()
            .zip(pts.heat_source.iter_mut())
            .zip(pts.conductivity.iter_mut())
            .zip(&self.responses)
        {
            *sig = r.stress;
            *q = r.heat_source;
            *k = r.conductivity;
        }
        Ok(())
    }

    /// Stage: zero the nodal sums (only where the last scatter wrote). The scatter does this
    /// itself; the stage is kept for callers that time the stages apart.
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
    /// P2G); returns whether `stable(range)` held for every chunk of points. Per chunk of
    /// [`BIN_CHUNK`] points, in parallel: the stencils, a counting sort of the chunk's points
    /// by strip (each strip in index order) and the column spans by stencil base row; then,
    /// serially, the spans and strip sizes are merged over the chunks.
    fn bin_points<F>(&mut self, points: &MaterialPoints, stable: F) -> bool
    where
        F: Fn(std::ops::Range<usize>) -> bool + Sync,
    {
        let n = points.len();
        let grid = &self.config.grid;
        let ny = grid.nodes()[1];
        let strips = self.strips;
        let chunks = n.div_ceil(BIN_CHUNK);
        self.stencils.resize(n, PackedStencil::default());
        self.strip_order.resize(n, 0);
        self.chunk_starts.clear();
        self.chunk_starts.resize(chunks * (strips + 1), 0);
        self.chunk_spans.clear();
        self.chunk_spans.resize(chunks * ny, NO_SPAN);
        let all_stable = (
            self.stencils.par_chunks_mut(BIN_CHUNK),
            self.strip_order.par_chunks_mut(BIN_CHUNK),
            points.position.par_chunks(BIN_CHUNK),
            points.half_size.par_chunks(BIN_CHUNK),
            self.chunk_starts.par_chunks_mut(strips + 1),
            self.chunk_spans.par_chunks_mut(ny),
        )
            .into_par_iter()
            .with_max_len(1)
            .enumerate()
            .map(|(c, (st, order, x, l, starts, spans))| {
                for ((st, x), l) in st.iter_mut().zip(x).zip(l) {
                    let s = Stencil::new(grid, *x, *l);
                    *st = PackedStencil::pack(&s);
                    starts[s.y.base / STRIP_ROWS] += 1;
                    let bx = s.x.base as u32;
                    spans[s.y.base] = hull(spans[s.y.base], [bx, bx + 3]);
                }
                // Inclusive prefix sums make `starts[s]` the end of strip s; placing the points
                // backwards moves it to the strip's start and keeps each strip in index order.
                let mut end = 0;
                for s in starts[..strips].iter_mut() {
                    end += *s;
                    *s = end;
                }
                starts[strips] = end;
                let first = c * BIN_CHUNK;
                for (j, st) in st.iter().enumerate().rev() {
                    let slot = &mut starts[st.base_row() / STRIP_ROWS];
                    *slot -= 1;
                    order[*slot as usize] = (first + j) as u32;
                }
                stable(first..first + st.len())
            })
            .reduce(|| true, |a, b| a && b);
        // Points per strip, and the cumulative work of the scatter units of each colour.
        self.strip_points.fill(0);
        for starts in self.chunk_starts.chunks_exact(strips + 1) {
            for (n, w) in self.strip_points.iter_mut().zip(starts.windows(2)) {
                *n += (w[1] - w[0]) as usize;
            }
        }
        for (parity, work) in self.unit_work.iter_mut().enumerate() {
            let units = Units { parity, rows: ny };
            for u in 0..units.count() {
                let points = units.strip(u).map_or(0, |s| self.strip_points[s]);
                work[u + 1] = work[u] + points + 1;
            }
        }
        // Node-row spans: the hull over the chunks by stencil base row, then over the base
        // rows r−2, r−1, r of each row r (in place, from the top row down).
        self.active.fill(NO_SPAN);
        for spans in self.chunk_spans.chunks_exact(ny) {
            for (a, s) in self.active.iter_mut().zip(spans) {
                *a = hull(*a, *s);
            }
        }
        for r in (0..ny).rev() {
            let lo = r.saturating_sub(2);
            let h = self.active[lo..r]
                .iter()
                .fold(self.active[r], |h, s| hull(h, *s));
            self.active[r] = h;
        }
        all_stable
    }

    /// Stage: particle to grid. Pass 1 maps mass, momentum, heat capacity, heat content,
    /// internal forces and external loads (after zeroing the sums); the nodal temperature
    /// follows with prescribed values imposed; pass 2 maps the conduction heat loads, which
    /// need it.
    pub fn particle_to_grid(&mut self, points: &MaterialPoints, step: u64) -> Result<(), MpmError> {
        self.bin_points(points, |_| true);
        self.scatter_sweeps(points, step, None)
    }

    /// The four scatter sweeps of P2G over the units of alternating colours (even strips, then
    /// odd strips, per pass), with the grid update (`update = Some((dt, time))`) fused into the
    /// last: a row is complete once the odd unit that owns it has scattered.
    fn scatter_sweeps(
        &mut self,
        points: &MaterialPoints,
        step: u64,
        update: Option<(f64, f64)>,
    ) -> Result<(), MpmError> {
        let grid = &self.config.grid;
        let [row_len, rows] = grid.nodes();
        let walls = &self.config.params.walls[..];
        let per_row = walls.len().max(1);
        let shape = (row_len, per_row);
        let loads = &self.config.params.surface_loads[..];
        let fixed = &self.config.fixed_temperature[..];
        let mask = &self.config.velocity_mask[..];
        let (stencils, order, starts) = (
            &self.stencils[..],
            &self.strip_order[..],
            &self.chunk_starts[..],
        );
        let strips = self.strips;
        let active = &self.active[..];
        let (even, odd) = (Units { parity: 0, rows }, Units { parity: 1, rows });
        let (work_even, work_odd) = (&self.unit_work[0][..], &self.unit_work[1][..]);
        let gf = &mut self.grid_fields;
        macro_rules! band {
            () => {
                Band {
                    first_row: 0,
                    sums: &mut gf.sums,
                    velocity_old: &mut gf.velocity_old,
                    velocity: &mut gf.velocity,
                    acceleration: &mut gf.acceleration,
                    temperature_old: &mut gf.temperature_old,
                    temperature: &mut gf.temperature,
                    temperature_rate: &mut gf.temperature_rate,
                    temperature_mapped: &mut self.temperature_mapped,
                    sums_dirty: &mut self.sums_dirty,
                    fields_dirty: &mut self.fields_dirty,
                    reactions: &mut self.row_reactions,
                }
            };
        }

        // Sweep 1: pass 1 of the even strips; each unit first zeroes its rows where the last
        // scatter wrote (no other unit of this sweep writes them, and this sweep is the first).
        run_units(
            band!(),
            even,
            0,
            even.count(),
            work_even,
            shape,
            &|u, b: Band<'_>| {
                let row0 = b.first_row;
                for (r, d) in b.sums_dirty.iter_mut().enumerate() {
                    b.sums[r * row_len..(r + 1) * row_len][columns(*d, row_len)]
                        .fill(NodeSums::default());
                    *d = active[row0 + r];
                }
                if let Some(s) = even.strip(u) {
                    for_strip(order, starts, strips, s, |p| {
                        scatter_pass1(
                            b.sums,
                            row0,
                            row_len,
                            &stencils[p].unpack(),
                            points,
                            loads,
                            p,
                        )
                    });
                }
            },
            &|(), ()| (),
        );

        // Sweep 2: pass 1 of the odd strips, then the nodal temperature of the unit's rows,
        // which no later pass-1 scatter writes.
        let bad = run_units(
            band!(),
            odd,
            0,
            odd.count(),
            work_odd,
            shape,
            &|u, b: Band<'_>| {
                let row0 = b.first_row;
                if let Some(s) = odd.strip(u) {
                    for_strip(order, starts, strips, s, |p| {
                        scatter_pass1(
                            b.sums,
                            row0,
                            row_len,
                            &stencils[p].unpack(),
                            points,
                            loads,
                            p,
                        )
                    });
                }
                let mut bad = None;
                for r in 0..b.rows() {
                    let (j, n) = (row0 + r, r * row_len..(r + 1) * row_len);
                    let cols = columns(active[j], row_len);
                    let tf = &fixed[j * row_len..(j + 1) * row_len];
                    let (t, tm) = (
                        &mut b.temperature_old[n.clone()],
                        &mut b.temperature_mapped[n.clone()],
                    );
                    if let Some(i) = nodal_temperature_row(t, tm, &b.sums[n], tf, cols) {
                        bad = bad.or(Some(j * row_len + i));
                    }
                }
                bad
            },
            &first_of,
        );
        if let Some(i) = bad {
            return Err(MpmError::NonFinite {
                quantity: "nodal temperature",
                place: "grid node",
                index: i,
                stage: "particle_to_grid",
                step,
            });
        }

        // Sweep 3: pass 2 of the even strips.
        run_units(
            band!(),
            even,
            0,
            even.count(),
            work_even,
            shape,
            &|u, b: Band<'_>| {
                if let Some(s) = even.strip(u) {
                    let row0 = b.first_row;
                    for_strip(order, starts, strips, s, |p| {
                        scatter_pass2(
                            b.sums,
                            b.temperature_old,
                            row0,
                            row_len,
                            &stencils[p].unpack(),
                            points,
                            p,
                        )
                    });
                }
            },
            &|(), ()| (),
        );

        // Sweep 4: pass 2 of the odd strips, then the grid update of the unit's rows.
        let inputs = update.map(|(dt, time)| UpdateInputs {
            grid,
            walls,
            gravity: self.config.params.gravity,
            node_mass_tolerance: self.config.params.node_mass_tolerance,
            merge_small_mass_nodes: self.config.params.merge_small_mass_nodes,
            local_damping: self.config.params.local_damping,
            dt,
            time,
        });
        let bad = run_units(
            band!(),
            odd,
            0,
            odd.count(),
            work_odd,
            shape,
            &|u, b: Band<'_>| {
                let row0 = b.first_row;
                if let Some(s) = odd.strip(u) {
                    for_strip(order, starts, strips, s, |p| {
                        scatter_pass2(
                            b.sums,
                            b.temperature_old,
                            row0,
                            row_len,
                            &stencils[p].unpack(),
                            points,
                            p,
                        )
                    });
                }
                let inp = inputs.as_ref()?;
                let mut bad = None;
                for r in 0..b.rows() {
                    let (j, n) = (row0 + r, r * row_len..(r + 1) * row_len);
                    let jn = j * row_len..(j + 1) * row_len;
                    let row = NodeRow {
                        velocity_old: &mut b.velocity_old[n.clone()],
                        velocity: &mut b.velocity[n.clone()],
                        acceleration: &mut b.acceleration[n.clone()],
                        temperature_old: &mut b.temperature_old[n.clone()],
                        temperature: &mut b.temperature[n.clone()],
                        temperature_rate: &mut b.temperature_rate[n.clone()],
                        temperature_mapped: &mut b.temperature_mapped[n.clone()],
                        reactions: &mut b.reactions[r * per_row..(r + 1) * per_row],
                    };
                    let (sums, dirty) = (&b.sums[n], &mut b.fields_dirty[r]);
                    let found = update_row(
                        j,
                        row,
                        sums,
                        &mask[jn.clone()],
                        &fixed[jn],
                        active[j],
                        dirty,
                        inp,
                    );
                    bad = bad.or(found);
                }
                bad
            },
            &first_of,
        );
        if update.is_some() {
            self.sum_wall_reactions();
            if let Some(i) = bad {
                return Err(grid_update_error(i, step));
            }
        }
        Ok(())
    }

    /// Wall reactions: the row sums in row order.
    fn sum_wall_reactions(&mut self) {
        let per_row = self.wall_reactions.len().max(1);
        for (w, reaction) in self.wall_reactions.iter_mut().enumerate() {
            *reaction = [0.0; 2];
            for r in self.row_reactions.chunks(per_row) {
                reaction[0] += r[w][0];
                reaction[1] += r[w][1];
            }
        }
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
        let per_row = self.config.params.walls.len().max(1);
        let inputs = UpdateInputs {
            grid,
            walls: &self.config.params.walls,
            gravity: self.config.params.gravity,
            node_mass_tolerance: self.config.params.node_mass_tolerance,
            merge_small_mass_nodes: self.config.params.merge_small_mass_nodes,
            local_damping: self.config.params.local_damping,
            dt,
            time,
        };
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
                update_row(j, row, sums, mask, fixed, *active, dirty, &inputs)
            })
            .min();
        self.sum_wall_reactions();
        if let Some(i) = bad {
            return Err(grid_update_error(i, step));
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
        let g = GatherInputs::new(&self.config, &self.grid_fields, dt);
        // Chunks of points in parallel, each a plain loop.
        const C: usize = POINT_CHUNK;
        let (non_finite, outside) = (
            points.position.par_chunks_mut(C),
            points.velocity.par_chunks_mut(C),
            points.temperature.par_chunks_mut(C),
            points.remapped_temperature.par_chunks_mut(C),
            self.velocity_gradient.par_chunks_mut(C),
            self.temperature_rate.par_chunks_mut(C),
            self.stencils.par_chunks(C),
            points.half_size.par_chunks(C),
        )
            .into_par_iter()
            .with_max_len(2)
            .enumerate()
            .map(|(c, (x, v, t, tr, l, tdot, st, half))| {
                let chunk = GatherChunk {
                    x,
                    v,
                    t,
                    tr,
                    l,
                    tdot,
                    st,
                    half,
                };
                gather_chunk(c * C, chunk, &g)
            })
            .reduce(
                || (usize::MAX, usize::MAX),
                |a, b| (a.0.min(b.0), a.1.min(b.1)),
            );
        gather_outcome(points, &self.config.grid, non_finite, outside, step)
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
        // Chunks of points in parallel, each a plain loop that keeps its first error; the
        // error of the lowest point index is reported.
        const C: usize = POINT_CHUNK;
        let err = (
            (
                pts.deformation_gradient.par_chunks_mut(C),
                pts.volume.par_chunks_mut(C),
                pts.strain.par_chunks_mut(C),
                pts.stress.par_chunks_mut(C),
                pts.heat_source.par_chunks_mut(C),
                pts.conductivity.par_chunks_mut(C),
                state.material.par_chunks_mut(C),
            ),
            (
                self.velocity_gradient.par_chunks(C),
                self.temperature_rate.par_chunks(C),
                pts.remapped_temperature.par_chunks(C),
                pts.mass.par_chunks(C),
                pts.initial_volume.par_chunks(C),
            ),
        )
            .into_par_iter()
            .with_max_len(2)
            .enumerate()
            .filter_map(|(c, ((f, vol, eps, sig, q, k, ms), (l, tdot, t, m, v0)))| {
                let chunk = RespondChunk {
                    f,
                    vol,
                    eps,
                    sig,
                    q,
                    k,
                    ms,
                    l,
                    tdot,
                    t,
                    m,
                    v0,
                };
                respond_chunk(c * C, chunk, material, dt, step)
            })
            .min_by_key(error_point);
        match err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// [`Mpm::grid_to_particle`] and [`Mpm::constitutive_update`] fused: each chunk of points
    /// is gathered and then handed to the material while it is in cache. The errors are those
    /// of the two stages in turn: the gather's (lowest point first) before the material's; a
    /// chunk with a gather error is not handed to the material.
    fn gather_and_respond<M: Constitutive>(
        &mut self,
        state: &mut MpmState<M::PointState>,
        material: &M,
        dt: f64,
    ) -> Result<(), MpmError> {
        let pts = &mut state.points;
        let step = state.step;
        let n = pts.len();
        self.velocity_gradient.resize(n, [0.0; 4]);
        self.temperature_rate.resize(n, 0.0);
        let g = GatherInputs::new(&self.config, &self.grid_fields, dt);
        const C: usize = POINT_CHUNK;
        let none = || (usize::MAX, usize::MAX, None);
        let (non_finite, outside, err) = (
            (
                pts.position.par_chunks_mut(C),
                pts.velocity.par_chunks_mut(C),
                pts.temperature.par_chunks_mut(C),
                pts.remapped_temperature.par_chunks_mut(C),
                self.velocity_gradient.par_chunks_mut(C),
                self.temperature_rate.par_chunks_mut(C),
                self.stencils.par_chunks(C),
                pts.half_size.par_chunks(C),
            ),
            (
                pts.deformation_gradient.par_chunks_mut(C),
                pts.volume.par_chunks_mut(C),
                pts.strain.par_chunks_mut(C),
                pts.stress.par_chunks_mut(C),
                pts.heat_source.par_chunks_mut(C),
                pts.conductivity.par_chunks_mut(C),
                state.material.par_chunks_mut(C),
                pts.mass.par_chunks(C),
                pts.initial_volume.par_chunks(C),
            ),
        )
            .into_par_iter()
            .with_max_len(2)
            .enumerate()
            .map(
                |(c, ((x, v, t, tr, l, tdot, st, half), (f, vol, eps, sig, q, k, ms, m, v0)))| {
                    let gather = GatherChunk {
                        x,
                        v,
                        t,
                        tr: &mut *tr,
                        l: &mut *l,
                        tdot: &mut *tdot,
                        st,
                        half,
                    };
                    let (bad, out) = gather_chunk(c * C, gather, &g);
                    if bad != usize::MAX || out != usize::MAX {
                        return (bad, out, None);
                    }
                    let respond = RespondChunk {
                        f,
                        vol,
                        eps,
                        sig,
                        q,
                        k,
                        ms,
                        l,
                        tdot,
                        t: tr,
                        m,
                        v0,
                    };
                    (bad, out, respond_chunk(c * C, respond, material, dt, step))
                },
            )
            .reduce(none, |a, b| {
                let err = match (a.2, b.2) {
                    (Some(x), Some(y)) => Some(if error_point(&y) < error_point(&x) {
                        y
                    } else {
                        x
                    }),
                    (x, None) => x,
                    (None, y) => y,
                };
                (a.0.min(b.0), a.1.min(b.1), err)
            });
        gather_outcome(pts, &self.config.grid, non_finite, outside, step)?;
        match err {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The point an error of the point stages names (for reporting the lowest).
fn error_point(e: &MpmError) -> usize {
    match e {
        MpmError::InvalidPoint { index, .. } | MpmError::NonFinite { index, .. } => *index,
        MpmError::Material { point, .. } => *point,
        _ => 0,
    }
}

/// Error unless `dt` is positive and finite.
fn check_dt(dt: f64) -> Result<(), MpmError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(MpmError::InvalidParameter {
            name: "dt".into(),
            value: dt,
            allowed: "(0, inf) s",
        })
    }
}

/// The error of a grid update that produced a non-finite value at node `index`.
fn grid_update_error(index: usize, step: u64) -> MpmError {
    MpmError::NonFinite {
        quantity: "nodal velocity or temperature",
        place: "grid node",
        index,
        stage: "grid_update",
        step,
    }
}

/// Fixed inputs of the gather.
struct GatherInputs<'a> {
    gf: &'a GridFields,
    row_len: usize,
    lo: [f64; 2],
    hi: [f64; 2],
    a_pic: f64,
    a_g: f64,
    a_p: f64,
    dt: f64,
}

impl<'a> GatherInputs<'a> {
    fn new(config: &MpmConfig, gf: &'a GridFields, dt: f64) -> Self {
        let p = &config.params;
        let grid = &config.grid;
        Self {
            gf,
            row_len: grid.nodes()[0],
            lo: grid.origin(),
            hi: grid.upper(),
            a_pic: p.pic_fraction,
            a_g: p.grid_damping,
            a_p: p.particle_damping,
            dt,
        }
    }
}

/// The gather's per-point fields of one chunk of points.
struct GatherChunk<'a> {
    x: &'a mut [[f64; 2]],
    v: &'a mut [[f64; 2]],
    t: &'a mut [f64],
    /// Remapped temperature (B-Eq. 29).
    tr: &'a mut [f64],
    l: &'a mut [Mat2],
    tdot: &'a mut [f64],
    st: &'a [PackedStencil],
    half: &'a [[f64; 2]],
}

/// Gathers one chunk of points, the first of which is point `first`. Returns the first point
/// with a non-finite value and the first point outside the grid (`usize::MAX` for none).
fn gather_chunk(first: usize, c: GatherChunk<'_>, g: &GatherInputs<'_>) -> (usize, usize) {
    let (gf, row_len, dt) = (g.gf, g.row_len, g.dt);
    let (a_pic, a_g, a_p) = (g.a_pic, g.a_g, g.a_p);
    let (lo, hi) = (g.lo, g.hi);
    let mut bad = (usize::MAX, usize::MAX);
    let rows =
        c.x.iter_mut()
            .zip(c.v.iter_mut())
            .zip(c.t.iter_mut())
            .zip(c.tr.iter_mut())
            .zip(
                c.l.iter_mut()
                    .zip(c.tdot.iter_mut())
                    .zip(c.st.iter().zip(c.half)),
            );
    for (j, ((((x, v), t), tr), ((l, tdot), (st, half)))) in rows.enumerate() {
        let mut v_old = [0.0; 2];
        let mut v_new = [0.0; 2];
        let mut rate = 0.0;
        let mut t_new = 0.0;
        let mut lg = [0.0; 4];
        let st = &st.unpack();
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
            vp[0] + (v_new[0] - v_old[0]) - (a_pic + a_p) * vp[0] + (a_pic - a_g) * v_old[0],
            vp[1] + (v_new[1] - v_old[1]) - (a_pic + a_p) * vp[1] + (a_pic - a_g) * v_old[1],
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
        let i = first + j;
        if !finite {
            bad.0 = bad.0.min(i);
        } else if !inside {
            bad.1 = bad.1.min(i);
        }
    }
    bad
}

/// The gather's error: non-finite values are reported before a point outside the grid.
fn gather_outcome(
    points: &MaterialPoints,
    grid: &Grid,
    non_finite: usize,
    outside: usize,
    step: u64,
) -> Result<(), MpmError> {
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

/// The constitutive update's per-point fields of one chunk of points.
struct RespondChunk<'a, S> {
    f: &'a mut [Mat2],
    vol: &'a mut [f64],
    eps: &'a mut [Sym2],
    sig: &'a mut [Sym2],
    q: &'a mut [f64],
    k: &'a mut [Sym2],
    ms: &'a mut [S],
    l: &'a [Mat2],
    tdot: &'a [f64],
    /// Remapped temperature (B-Eq. 29).
    t: &'a [f64],
    m: &'a [f64],
    v0: &'a [f64],
}

/// The kinematic part of the constitutive update of one point: `F ← (I + L Δt) F`,
/// `V = V_0 det F`, `ε += sym(L) Δt`. Errors with the new `det F` (nothing changed) when it
/// would leave `(0, ∞)`.
#[inline]
fn advance_kinematics(
    f: &mut Mat2,
    vol: &mut f64,
    eps: &mut Sym2,
    l: &Mat2,
    v0: f64,
    dt: f64,
) -> Result<(), f64> {
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
        return Err(det);
    }
    *f = fnew;
    *vol = v0 * det;
    eps[0] += l[0] * dt;
    eps[1] += l[3] * dt;
    eps[2] += 0.5 * (l[1] + l[2]) * dt;
    Ok(())
}

/// Constitutive update of one chunk of points, the first of which is point `first`; the
/// chunk's first error.
fn respond_chunk<M: Constitutive>(
    first: usize,
    c: RespondChunk<'_, M::PointState>,
    material: &M,
    dt: f64,
    step: u64,
) -> Option<MpmError> {
    let mut err = None;
    let rows =
        c.f.iter_mut()
            .zip(c.vol.iter_mut())
            .zip(c.eps.iter_mut())
            .zip(c.sig.iter_mut())
            .zip(c.q.iter_mut())
            .zip(c.k.iter_mut())
            .zip(c.ms.iter_mut())
            .zip(c.l.iter().zip(c.tdot).zip(c.t.iter().zip(c.m).zip(c.v0)));
    for (j, (((((((f, vol), eps), sig), q), k), ms), ((l, tdot), ((t, m), v0)))) in rows.enumerate()
    {
        let i = first + j;
        if let Err(det) = advance_kinematics(f, vol, eps, l, *v0, dt) {
            err.get_or_insert(MpmError::InvalidPoint {
                index: i,
                field: "det F",
                value: det,
                allowed: "(0, inf)",
            });
            continue;
        }
        let input = MaterialInput {
            point: i,
            velocity_gradient: *l,
            deformation_gradient: *f,
            temperature: *t,
            temperature_rate: *tdot,
            stress: *sig,
            density: m / *vol,
            dt,
        };
        let r = match material.respond(ms, &input) {
            Ok(r) => r,
            Err(e) => {
                err.get_or_insert(e);
                continue;
            }
        };
        if !(r.stress.iter().all(|s| s.is_finite())
            && r.heat_source.is_finite()
            && r.conductivity.iter().all(|c| c.is_finite()))
        {
            err.get_or_insert(MpmError::NonFinite {
                quantity: "stress, heat source or conductivity",
                place: "material point",
                index: i,
                stage: "constitutive_update",
                step,
            });
            continue;
        }
        *sig = r.stress;
        // Constant for most materials: stores skipped, lines stay clean.
        if *q != r.heat_source {
            *q = r.heat_source;
        }
        if *k != r.conductivity {
            *k = r.conductivity;
        }
    }
    err
}
