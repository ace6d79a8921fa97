//! The mesher: circles and contacts to a [`PackingMesh`].
//!
//! Stages (each a function below):
//! 1. [`validate_input`]: finite centres, positive radii, valid contacts.
//! 2. [`overlapping_pairs`]: every pair of overlapping circles (uniform grid search).
//! 3. `solid_polygon` per circle: the circle's *power cell* (intersection of the half-planes
//!    bounded by the radical lines — the chords — of its overlapping neighbours, and of the box)
//!    intersected with the disc, its boundary arcs discretised with the uniform angular grid of
//!    the circle. Shared vertices (chord ends, radical centres, box crossings) have canonical
//!    keys and coordinates computed once per key, so neighbouring polygons share them exactly.
//! 4. `snap_vertices`: vertices closer than the snap tolerance are merged (tangent circles).
//!    With `MeshParams::side_points`, Steiner points cut the stretches of the box sides that
//!    no circle covers into pieces no longer than an arc segment (`side_points`).
//! 5. Constrained Delaunay triangulation (`spade`) with every polygon edge (and the box sides)
//!    as a constraint.
//! 6. Classification: a triangle whose centroid lies in the polygon of circle `i` is a solid
//!    cell of `i`, every other triangle is fluid; with an alpha-shape outline, fluid triangles
//!    reachable from the convex hull through fluid triangles of circumradius > α are removed.
//! 7. Locality order: the triangles are sorted along a Z-order (Morton) curve of their
//!    centroids ([`locality_order`]), and vertices are numbered in order of first use by the
//!    sorted triangles within groups of the same kinematics, the free one-anchor vertices
//!    first ([`crate::circles::VertexAnchors::kinematics_order`]). Faces and channels are
//!    then created in that order too, so cells, vertices and faces that are close in space
//!    are close in memory: every later pass (the geometry update, the heat and flow
//!    stencils, the remap) gathers from a few cache lines instead of from all over the mesh.
//! 8. [`PoreMesh::from_triangles`] (faces, geometry, T2T channels A-Eq. 9), then S2S channels
//!    (A-Eq. 8) across the contacts, between the fluid cells at the two ends of each contact's
//!    chord. Where three or more circles overlap, a chord ends inside a third circle: the gaps
//!    that meet there are one path, and their open ends are chained through the junction
//!    (`junction_channels`), so that a pocket between a wall and two overlapping circles is
//!    not sealed by construction (it was in 40 pores of the film-ended bar of seed 1, and
//!    4 of 12 Darcy-test packings had no pore path before).

use std::collections::HashMap;

use serde::{Deserialize, Serialize};
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

pub use crate::circles::{Circle, Contact};
use crate::circles::{VertexAnchors, VertexConstraint};
use crate::error::MeshError;
use crate::mesh::{CellKind, ChannelKind, NONE, PoreMesh, T2tApertureLaw};

/// The outer boundary of the meshed domain.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Outline {
    /// The rectangle `[min, max]`; circles are clipped by it.
    Box {
        /// Lower-left corner \[m\].
        min: [f64; 2],
        /// Upper-right corner \[m\].
        max: [f64; 2],
    },
    /// The alpha shape of the packing: fluid triangles reachable from the convex hull through
    /// fluid triangles whose circumradius exceeds `alpha` \[m\] are outside the specimen.
    AlphaShape {
        /// α \[m\].
        alpha: f64,
    },
}

/// Parameters of the S2S aperture law A-Eq. 8:
/// `h = β (h_inf + (h_0 − h_inf) exp(−c σ_n))`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct S2sApertureParams {
    /// Aperture coefficient β [-] (paper A, Table 1: 1.2).
    pub beta: f64,
    /// Hydraulic aperture at infinite normal stress h_inf \[m\] (Table 1: 5.75e-7).
    pub aperture_infinite_stress: f64,
    /// Hydraulic aperture at zero normal stress h_0 \[m\] (Table 1: 3.25e-6).
    pub aperture_zero_stress: f64,
    /// Stress decay coefficient c [1/Pa] (A-Eq. 8: 1.5e-7).
    pub stress_decay: f64,
}

impl Default for S2sApertureParams {
    fn default() -> Self {
        Self {
            beta: 1.2,
            aperture_infinite_stress: 5.75e-7,
            aperture_zero_stress: 3.25e-6,
            stress_decay: 1.5e-7,
        }
    }
}

impl S2sApertureParams {
    /// Hydraulic aperture of an S2S channel (A-Eq. 8) \[m\]. Tensile stress (σ_n < 0) is taken
    /// as zero: an opened contact has the zero-stress aperture h_0 times β.
    pub fn aperture(&self, normal_stress: f64) -> f64 {
        let s = normal_stress.max(0.0);
        self.beta
            * (self.aperture_infinite_stress
                + (self.aperture_zero_stress - self.aperture_infinite_stress)
                    * (-self.stress_decay * s).exp())
    }
}

/// Mesher parameters (serde form). Validate with [`MeshParams::validate`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshParams {
    /// Points of the uniform angular grid on each full circle (boundary resolution), ≥ 6.
    pub segments_per_circle: u32,
    /// The outer boundary.
    pub outline: Outline,
    /// Out-of-plane thickness \[m\]; `None` = the largest circle diameter (paper A, Sect. 2.4).
    pub thickness: Option<f64>,
    /// T2T reduction factor γ of A-Eq. 9 [-] (Table 1: 0.0115).
    pub t2t_reduction_factor: f64,
    /// S2S aperture law A-Eq. 8.
    pub s2s: S2sApertureParams,
    /// Vertices closer than `snap_tolerance × r` are merged, and vertices that close to a box
    /// side are put on it, `r` being the radius of the smallest circle the vertices belong to,
    /// at most the mean radius [-] (default 1e-6).
    pub snap_tolerance: f64,
    /// T2T faces shorter than this \[m\] cross a gap between two circles narrower than it and
    /// carry at least the S2S aperture of A-Eq. 8 at zero stress, `β h₀` (see
    /// [`crate::T2tApertureLaw`]); 0 (the default) is A-Eq. 9 alone.
    #[serde(default)]
    pub narrow_gap_length: f64,
    /// Steiner points on the box sides, spaced at most one arc segment of the mean circle
    /// (`2π r̄ / segments_per_circle`) wherever no circle covers a side (see the module docs,
    /// stage 4). Off (the default), a gap between the circles and a side is triangulated from
    /// the circles' crossings and the corners alone: a fluid cell can then run along the side
    /// from one crossing to the next, many radii long, nearly flat, and its one temperature
    /// carries heat along the side (a steady conduction run through a bar packing measured
    /// 14 W/(m K) for spheres of 3.7 W/(m K)).
    #[serde(default)]
    pub side_points: bool,
}

impl MeshParams {
    /// Paper A defaults (Table 1) for the given outline and resolution.
    pub fn new(outline: Outline, segments_per_circle: u32) -> Self {
        Self {
            segments_per_circle,
            outline,
            thickness: None,
            t2t_reduction_factor: 0.0115,
            s2s: S2sApertureParams::default(),
            snap_tolerance: 1e-6,
            narrow_gap_length: 0.0,
            side_points: false,
        }
    }

    /// Checks every parameter once; the result cannot hold invalid values.
    pub fn validate(&self) -> Result<MeshSettings, MeshError> {
        let p = |name, range, value: f64, ok: bool| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(MeshError::Parameter { name, range, value })
            }
        };
        p(
            "segments_per_circle",
            "6..=100000",
            self.segments_per_circle as f64,
            (6..=100_000).contains(&self.segments_per_circle),
        )?;
        match self.outline {
            Outline::Box { min, max } => {
                for k in 0..2 {
                    p("outline.min", "finite", min[k], true)?;
                    p("outline.max", "finite and > min", max[k], max[k] > min[k])?;
                }
            }
            Outline::AlphaShape { alpha } => p("outline.alpha", "> 0 m", alpha, alpha > 0.0)?,
        }
        if let Some(t) = self.thickness {
            p("thickness", "> 0 m", t, t > 0.0)?;
        }
        let g = self.t2t_reduction_factor;
        p("t2t_reduction_factor", "> 0", g, g > 0.0)?;
        let s = &self.s2s;
        p("s2s.beta", "> 0", s.beta, s.beta > 0.0)?;
        p(
            "s2s.aperture_infinite_stress",
            ">= 0 m",
            s.aperture_infinite_stress,
            s.aperture_infinite_stress >= 0.0,
        )?;
        p(
            "s2s.aperture_zero_stress",
            ">= aperture_infinite_stress",
            s.aperture_zero_stress,
            s.aperture_zero_stress >= s.aperture_infinite_stress,
        )?;
        p(
            "s2s.stress_decay",
            ">= 0 1/Pa",
            s.stress_decay,
            s.stress_decay >= 0.0,
        )?;
        p(
            "snap_tolerance",
            "in [0, 1e-3]",
            self.snap_tolerance,
            (0.0..=1e-3).contains(&self.snap_tolerance),
        )?;
        p(
            "narrow_gap_length",
            ">= 0 m and finite",
            self.narrow_gap_length,
            self.narrow_gap_length >= 0.0,
        )?;
        Ok(MeshSettings { p: *self })
    }
}

/// Validated mesher parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshSettings {
    p: MeshParams,
}

impl MeshSettings {
    /// The validated parameters.
    pub fn params(&self) -> &MeshParams {
        &self.p
    }
}

/// A chord: the straight cut between two overlapping circles (a segment of their radical line).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Chords {
    /// The two circles (indices into the circle list), `[a, b]` with `a < b`.
    pub circles: Vec<[u32; 2]>,
    /// Overlap `r_a + r_b − d` at mesh time \[m\].
    pub overlap: Vec<f64>,
    /// End vertices of the cut in the mesh (`[NONE, NONE]` where the cut vanished).
    pub ends: Vec<[u32; 2]>,
    /// The solid–solid face along the cut (the contact face), or [`NONE`].
    pub face: Vec<u32>,
}

/// A mesh of a packing: the [`PoreMesh`] plus what links it to the circles (for motion,
/// remesh decisions and forces).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PackingMesh {
    /// The mesh consumed by the flow and heat solvers.
    pub mesh: PoreMesh,
    /// The circles at mesh time.
    pub circles: Vec<Circle>,
    /// How each vertex follows the circles.
    pub anchors: VertexAnchors,
    /// Cuts between overlapping circles.
    pub chords: Chords,
    /// For each input contact: its S2S channel index in `mesh.channels`, or [`NONE`].
    pub contact_channel: Vec<u32>,
    /// Solid cells of each circle (CSR offsets into `circle_cells`, length `n_circles + 1`).
    pub circle_cell_offsets: Vec<u32>,
    /// Solid cells grouped by circle.
    pub circle_cells: Vec<u32>,
    /// For each solid cell, the circle (index into `circles`) it belongs to; [`NONE`] for fluid.
    pub cell_circle: Vec<u32>,
    /// The T2T reduction factor γ the mesh was built with (A-Eq. 9), used to refresh the T2T
    /// apertures as the mesh moves.
    pub t2t_reduction_factor: f64,
    /// The narrow-gap floor of the T2T apertures: faces shorter than `[0]` \[m\] carry at
    /// least `[1]` \[m\] ([`crate::T2tApertureLaw`]; `[0, 0]`: A-Eq. 9 alone).
    #[serde(default)]
    pub narrow_gap: [f64; 2],
}

impl PackingMesh {
    /// The law the T2T apertures follow (A-Eq. 9 and the narrow-gap floor).
    pub fn t2t_law(&self) -> T2tApertureLaw {
        T2tApertureLaw {
            reduction_factor: self.t2t_reduction_factor,
            narrow_gap_length: self.narrow_gap[0],
            narrow_gap_aperture: self.narrow_gap[1],
        }
    }

    /// Solid cells of circle `i`.
    pub fn cells_of_circle(&self, i: usize) -> &[u32] {
        let a = self.circle_cell_offsets[i] as usize;
        let b = self.circle_cell_offsets[i + 1] as usize;
        &self.circle_cells[a..b]
    }

    /// Sets the S2S apertures (A-Eq. 8) from the current normal stress of each contact (same
    /// order as the contacts given to the mesher) \[Pa\], between remeshes.
    pub fn update_s2s_apertures(
        &mut self,
        normal_stress: &[f64],
        law: &S2sApertureParams,
    ) -> Result<(), MeshError> {
        if normal_stress.len() != self.contact_channel.len() {
            return Err(MeshError::LengthMismatch {
                what: "normal_stress (one per contact at mesh time)",
                expected: self.contact_channel.len(),
                got: normal_stress.len(),
            });
        }
        for (k, (&ch, &s)) in self.contact_channel.iter().zip(normal_stress).enumerate() {
            if !s.is_finite() {
                return Err(MeshError::NonFiniteStress {
                    contact: k,
                    value: s,
                });
            }
            if ch != NONE {
                self.mesh.channels.aperture[ch as usize] = law.aperture(s);
            }
        }
        Ok(())
    }

    /// Total solid area of circle `i` \[m²\].
    pub fn circle_solid_area(&self, i: usize) -> f64 {
        self.cells_of_circle(i)
            .iter()
            .map(|&c| self.mesh.cell_area[c as usize])
            .sum()
    }
}

/// A small multiplicative hasher for the integer keys of the mesher (the default SipHash is
/// several times slower and its DoS resistance is not needed here).
#[derive(Debug, Default, Clone, Copy)]
struct KeyHasher(u64);

impl KeyHasher {
    #[inline]
    fn add(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl std::hash::Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.add(u64::from(b));
        }
    }
    fn write_u8(&mut self, i: u8) {
        self.add(u64::from(i));
    }
    fn write_u32(&mut self, i: u32) {
        self.add(u64::from(i));
    }
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }
    fn write_isize(&mut self, i: isize) {
        self.add(i as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type KeyMap<K, V> = HashMap<K, V, std::hash::BuildHasherDefault<KeyHasher>>;

/// What a vertex is, geometrically; the key that makes shared vertices identical.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum VKey {
    /// Grid point `k` of circle `i`.
    Arc(u32, u32),
    /// Intersection of circles `a < b`; `s` = side of the line from `a` to `b` (0 left, 1 right).
    CircleCircle(u32, u32, u8),
    /// Radical centre of circles `a < b < c`.
    Radical(u32, u32, u32),
    /// Radical line of `a < b` on box side `s`.
    PairSide(u32, u32, u8),
    /// Circle `i` crossing box side `s`; `t` = which of the two crossings (0 lower coordinate).
    CircleSide(u32, u8, u8),
    /// Box corner (sides `s1 < s2`).
    Corner(u8, u8),
    /// A vertex of the bounding square (never part of the mesh in practice).
    Unique(u32),
    /// Point `k` of the Steiner points on box side `s` (see `side_points`).
    SidePoint(u8, u32),
    /// Centre of circle `i` (a Steiner point that makes the solid cells wedges).
    Centre(u32),
}

/// A line bounding a power cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Line {
    /// Box side: 0 left, 1 right, 2 bottom, 3 top.
    Side(u8),
    /// Radical line of circles `a < b`.
    Pair(u32, u32),
    /// Bounding square edge.
    Bound,
    /// A circular arc (outgoing edge of an exit point).
    Arc,
}

#[derive(Debug, Clone, Copy)]
struct PVert {
    p: [f64; 2],
    key: VKey,
    /// Line of the edge from this vertex to the next one.
    out: Line,
}

#[inline]
fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
#[inline]
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
#[inline]
fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Stage 1: validates circles and contacts.
pub fn validate_input(circles: &[Circle], contacts: &[Contact]) -> Result<(), MeshError> {
    for (i, c) in circles.iter().enumerate() {
        for &x in &c.centre {
            if !x.is_finite() {
                return Err(MeshError::NonFiniteCentre {
                    circle: i,
                    value: x,
                });
            }
        }
        if !(c.radius.is_finite() && c.radius > 0.0) {
            return Err(MeshError::InvalidRadius {
                circle: i,
                value: c.radius,
            });
        }
    }
    for (k, c) in contacts.iter().enumerate() {
        for &i in &c.circles {
            if i as usize >= circles.len() {
                return Err(MeshError::ContactOutOfRange {
                    contact: k,
                    circle: i,
                    n_circles: circles.len(),
                });
            }
        }
        if c.circles[0] == c.circles[1] {
            return Err(MeshError::SelfContact {
                contact: k,
                circle: c.circles[0],
            });
        }
        if !c.normal_stress.is_finite() {
            return Err(MeshError::NonFiniteStress {
                contact: k,
                value: c.normal_stress,
            });
        }
    }
    Ok(())
}

/// A uniform grid over circles for neighbour and point queries.
struct CircleGrid {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl CircleGrid {
    fn new(circles: &[Circle]) -> Self {
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        let mut rmax: f64 = 0.0;
        for c in circles {
            for k in 0..2 {
                lo[k] = lo[k].min(c.centre[k] - c.radius);
                hi[k] = hi[k].max(c.centre[k] + c.radius);
            }
            rmax = rmax.max(c.radius);
        }
        if circles.is_empty() {
            lo = [0.0; 2];
            hi = [1.0; 2];
            rmax = 0.5;
        }
        let cell = 2.0 * rmax;
        let nx = (((hi[0] - lo[0]) / cell).floor() as usize + 1).min(1 << 12);
        let ny = (((hi[1] - lo[1]) / cell).floor() as usize + 1).min(1 << 12);
        let cell = cell
            .max((hi[0] - lo[0]) / nx as f64)
            .max((hi[1] - lo[1]) / ny as f64);
        let mut grid = Self {
            origin: lo,
            cell,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            items: Vec::new(),
        };
        let idx: Vec<usize> = circles.iter().map(|c| grid.bin(c.centre)).collect();
        for &b in &idx {
            grid.start[b + 1] += 1;
        }
        for b in 0..nx * ny {
            grid.start[b + 1] += grid.start[b];
        }
        let mut fill = grid.start.clone();
        grid.items = vec![0; circles.len()];
        for (i, &b) in idx.iter().enumerate() {
            grid.items[fill[b] as usize] = i as u32;
            fill[b] += 1;
        }
        grid
    }

    fn coords(&self, p: [f64; 2]) -> (usize, usize) {
        let fx = ((p[0] - self.origin[0]) / self.cell).floor();
        let fy = ((p[1] - self.origin[1]) / self.cell).floor();
        let ix = if fx.is_finite() && fx > 0.0 {
            (fx as usize).min(self.nx - 1)
        } else {
            0
        };
        let iy = if fy.is_finite() && fy > 0.0 {
            (fy as usize).min(self.ny - 1)
        } else {
            0
        };
        (ix, iy)
    }

    fn bin(&self, p: [f64; 2]) -> usize {
        let (ix, iy) = self.coords(p);
        iy * self.nx + ix
    }

    /// Calls `f` for every circle whose centre bin neighbours the bin of `p` (the 3×3 block);
    /// since the bin size is ≥ the largest diameter this covers every circle within that
    /// distance of `p`.
    fn for_near(&self, p: [f64; 2], mut f: impl FnMut(u32)) {
        let (ix, iy) = self.coords(p);
        for jy in iy.saturating_sub(1)..=(iy + 1).min(self.ny - 1) {
            for jx in ix.saturating_sub(1)..=(ix + 1).min(self.nx - 1) {
                let b = jy * self.nx + jx;
                for &i in &self.items[self.start[b] as usize..self.start[b + 1] as usize] {
                    f(i);
                }
            }
        }
    }
}

/// Stage 2: all pairs `(a, b)`, `a < b`, of circles that overlap (`d < r_a + r_b`), sorted.
pub fn overlapping_pairs(circles: &[Circle]) -> Vec<[u32; 2]> {
    let grid = CircleGrid::new(circles);
    let mut pairs = Vec::new();
    for (i, ci) in circles.iter().enumerate() {
        grid.for_near(ci.centre, |j| {
            if (j as usize) > i {
                let cj = &circles[j as usize];
                let d = sub(cj.centre, ci.centre);
                let rr = ci.radius + cj.radius;
                if dot(d, d) < rr * rr {
                    pairs.push([i as u32, j]);
                }
            }
        });
    }
    pairs.sort_unstable();
    pairs
}

/// The power-cell half-plane of circle `i` against circle `j`: `f(x) <= 0` inside, with
/// `f(x) = 2 e·(x − c_i) − (|e|² + r_i² − r_j²)`, `e = c_j − c_i`. Returns `None` when the
/// centres coincide (then the half-plane is everything or nothing, see [`coincident_wins`]).
fn pair_halfplane(ci: &Circle, cj: &Circle) -> Option<([f64; 2], f64)> {
    let e = sub(cj.centre, ci.centre);
    if e[0] == 0.0 && e[1] == 0.0 {
        return None;
    }
    Some((
        [2.0 * e[0], 2.0 * e[1]],
        dot(e, e) + ci.radius * ci.radius - cj.radius * cj.radius,
    ))
}

/// For coincident centres: circle `i` keeps the region if it is larger, or equal and first.
fn coincident_wins(i: u32, ci: &Circle, j: u32, cj: &Circle) -> bool {
    ci.radius > cj.radius || (ci.radius == cj.radius && i < j)
}

/// Canonical position of a keyed vertex (computed from the key alone, so every polygon that
/// refers to the key gets the same bits).
fn key_position(key: VKey, circles: &[Circle], bx: &[f64; 4], fallback: [f64; 2]) -> [f64; 2] {
    let side_val = |s: u8| bx[s as usize];
    match key {
        VKey::CircleCircle(a, b, s) => {
            let (ca, cb) = (&circles[a as usize], &circles[b as usize]);
            let e = sub(cb.centre, ca.centre);
            let d2 = dot(e, e);
            if d2 == 0.0 {
                return fallback;
            }
            let t = 0.5 * (d2 + ca.radius * ca.radius - cb.radius * cb.radius) / d2;
            let h2 = ca.radius * ca.radius / d2 - t * t;
            let h = h2.max(0.0).sqrt();
            let sg = if s == 0 { 1.0 } else { -1.0 };
            [
                ca.centre[0] + t * e[0] - sg * h * e[1],
                ca.centre[1] + t * e[1] + sg * h * e[0],
            ]
        }
        VKey::Radical(a, b, c) => {
            let (ca, cb, cc) = (
                &circles[a as usize],
                &circles[b as usize],
                &circles[c as usize],
            );
            match (pair_halfplane(ca, cb), pair_halfplane(ca, cc)) {
                (Some((n1, b1)), Some((n2, b2))) => {
                    let det = cross(n1, n2);
                    if det == 0.0 {
                        return fallback;
                    }
                    let x = (b1 * n2[1] - b2 * n1[1]) / det;
                    let y = (n1[0] * b2 - n2[0] * b1) / det;
                    [ca.centre[0] + x, ca.centre[1] + y]
                }
                _ => fallback,
            }
        }
        VKey::PairSide(a, b, s) => {
            let (ca, cb) = (&circles[a as usize], &circles[b as usize]);
            let Some((n, rhs)) = pair_halfplane(ca, cb) else {
                return fallback;
            };
            let v = side_val(s);
            if s < 2 {
                let x = v - ca.centre[0];
                if n[1] == 0.0 {
                    return fallback;
                }
                [v, ca.centre[1] + (rhs - n[0] * x) / n[1]]
            } else {
                let y = v - ca.centre[1];
                if n[0] == 0.0 {
                    return fallback;
                }
                [ca.centre[0] + (rhs - n[1] * y) / n[0], v]
            }
        }
        VKey::CircleSide(i, s, t) => {
            let c = &circles[i as usize];
            let v = side_val(s);
            let sg = if t == 0 { -1.0 } else { 1.0 };
            if s < 2 {
                let dx = v - c.centre[0];
                let h = (c.radius * c.radius - dx * dx).max(0.0).sqrt();
                [v, c.centre[1] + sg * h]
            } else {
                let dy = v - c.centre[1];
                let h = (c.radius * c.radius - dy * dy).max(0.0).sqrt();
                [c.centre[0] + sg * h, v]
            }
        }
        VKey::Corner(s1, s2) => [side_val(s1), side_val(s2)],
        VKey::Arc(..) | VKey::Unique(..) | VKey::Centre(..) | VKey::SidePoint(..) => fallback,
    }
}

fn sorted3(a: u32, b: u32, c: u32) -> (u32, u32, u32) {
    let mut v = [a, b, c];
    v.sort_unstable();
    (v[0], v[1], v[2])
}

/// Key of the intersection of two cell lines of circle `i`.
fn line_line_key(l1: Line, l2: Line, uniq: &mut u32) -> VKey {
    match (l1, l2) {
        (Line::Pair(a, b), Line::Pair(c, d)) => {
            let mut v = [a, b, c, d];
            v.sort_unstable();
            // The two pairs share circle i; the three distinct circles.
            let (x, y, z) = if v[0] == v[1] {
                (v[0], v[2], v[3])
            } else if v[1] == v[2] {
                (v[0], v[1], v[3])
            } else {
                (v[0], v[1], v[2])
            };
            let (x, y, z) = sorted3(x, y, z);
            VKey::Radical(x, y, z)
        }
        (Line::Pair(a, b), Line::Side(s)) | (Line::Side(s), Line::Pair(a, b)) => {
            VKey::PairSide(a, b, s)
        }
        (Line::Side(s1), Line::Side(s2)) => VKey::Corner(s1.min(s2), s1.max(s2)),
        _ => {
            *uniq += 1;
            VKey::Unique(*uniq)
        }
    }
}

/// Half-plane of a line for circle `i`: `f(x) = n·(x − o) − rhs <= 0` inside.
fn line_function(
    line: Line,
    i: u32,
    circles: &[Circle],
    bx: &[f64; 4],
) -> ([f64; 2], [f64; 2], f64) {
    match line {
        Line::Side(0) => ([-1.0, 0.0], [bx[0], 0.0], 0.0),
        Line::Side(1) => ([1.0, 0.0], [bx[1], 0.0], 0.0),
        Line::Side(2) => ([0.0, -1.0], [0.0, bx[2]], 0.0),
        Line::Side(_) => ([0.0, 1.0], [0.0, bx[3]], 0.0),
        Line::Pair(a, b) => {
            let j = if a == i { b } else { a };
            let (ci, cj) = (&circles[i as usize], &circles[j as usize]);
            match pair_halfplane(ci, cj) {
                Some((n, rhs)) => (n, ci.centre, rhs),
                None => ([0.0, 0.0], ci.centre, 0.0),
            }
        }
        Line::Bound | Line::Arc => ([0.0, 0.0], [0.0, 0.0], 0.0),
    }
}

/// Clips the convex polygon `poly` by the half-plane of `line` (Sutherland–Hodgman).
fn clip(
    poly: &[PVert],
    line: Line,
    i: u32,
    circles: &[Circle],
    bx: &[f64; 4],
    out: &mut Vec<PVert>,
    uniq: &mut u32,
) {
    out.clear();
    let (n, o, rhs) = line_function(line, i, circles, bx);
    let f = |p: [f64; 2]| dot(n, sub(p, o)) - rhs;
    let m = poly.len();
    for k in 0..m {
        let (p, q) = (poly[k], poly[(k + 1) % m]);
        let (fp, fq) = (f(p.p), f(q.p));
        let (pin, qin) = (fp <= 0.0, fq <= 0.0);
        if pin {
            out.push(p);
        }
        if pin != qin {
            let t = fp / (fp - fq);
            let x = [
                p.p[0] + t * (q.p[0] - p.p[0]),
                p.p[1] + t * (q.p[1] - p.p[1]),
            ];
            let key = line_line_key(p.out, line, uniq);
            if pin {
                // Leaving: the last pushed vertex's edge continues on p.out to x, then along
                // the clipping line.
                out.push(PVert {
                    p: x,
                    key,
                    out: line,
                });
            } else {
                out.push(PVert {
                    p: x,
                    key,
                    out: p.out,
                });
            }
        }
    }
}

/// The solid polygon of one circle: boundary vertices in counter-clockwise order.
#[derive(Debug, Clone, Default)]
struct SolidPolygon {
    verts: Vec<PVert>,
}

/// Stage 3: the discretised solid region of circle `i` (power cell ∩ disc ∩ box).
#[allow(clippy::too_many_arguments)]
fn solid_polygon(
    i: u32,
    circles: &[Circle],
    neighbours: &[u32],
    bx: Option<&[f64; 4]>,
    n_seg: u32,
    uniq: &mut u32,
    scratch: &mut (Vec<PVert>, Vec<PVert>),
) -> SolidPolygon {
    let c = circles[i as usize];
    let r = c.radius;
    let (cx, cy) = (c.centre[0], c.centre[1]);
    let b2 = 2.0 * r;
    let bounds = [cx - b2, cx + b2, cy - b2, cy + b2];
    let bxv = bx.copied().unwrap_or(bounds);
    let (a, b) = (&mut scratch.0, &mut scratch.1);
    a.clear();
    let corner = |x: f64, y: f64, uniq: &mut u32| {
        *uniq += 1;
        PVert {
            p: [x, y],
            key: VKey::Unique(*uniq),
            out: Line::Bound,
        }
    };
    a.push(corner(bounds[0], bounds[2], uniq));
    a.push(corner(bounds[1], bounds[2], uniq));
    a.push(corner(bounds[1], bounds[3], uniq));
    a.push(corner(bounds[0], bounds[3], uniq));
    if bx.is_some() {
        for s in 0..4u8 {
            clip(a, Line::Side(s), i, circles, &bxv, b, uniq);
            std::mem::swap(a, b);
        }
    }
    for &j in neighbours {
        let cj = &circles[j as usize];
        if pair_halfplane(&c, cj).is_none() {
            if coincident_wins(i, &c, j, cj) {
                continue;
            }
            return SolidPolygon::default();
        }
        let line = Line::Pair(i.min(j), i.max(j));
        clip(a, line, i, circles, &bxv, b, uniq);
        std::mem::swap(a, b);
        if a.is_empty() {
            return SolidPolygon::default();
        }
    }
    if a.len() < 3 {
        return SolidPolygon::default();
    }
    // Canonical coordinates for keyed vertices.
    for v in a.iter_mut() {
        v.p = key_position(v.key, circles, &bxv, v.p);
    }
    // Walk the cell boundary, keeping the parts inside the disc and replacing the parts
    // outside by arcs.
    let rr = r * r;
    let inside = |p: [f64; 2]| {
        let d = sub(p, c.centre);
        dot(d, d) < rr
    };
    // Items: (vertex, Some(angle) if the vertex is a circle crossing, exit flag).
    let mut items: Vec<(PVert, Option<f64>, bool)> = Vec::with_capacity(a.len() + 4);
    let m = a.len();
    for k in 0..m {
        let (p, q) = (a[k], a[(k + 1) % m]);
        let (pin, qin) = (inside(p.p), inside(q.p));
        if pin {
            items.push((p, None, false));
        }
        let d = sub(q.p, p.p);
        let w = sub(p.p, c.centre);
        let qa = dot(d, d);
        if qa == 0.0 {
            continue;
        }
        let qb = dot(w, d);
        let qc = dot(w, w) - rr;
        let disc = qb * qb - qa * qc;
        if disc <= 0.0 {
            continue;
        }
        let sq = disc.sqrt();
        let (t0, t1) = ((-qb - sq) / qa, (-qb + sq) / qa);
        let mut crossing = |t: f64, exit: bool, items: &mut Vec<(PVert, Option<f64>, bool)>| {
            let x = [p.p[0] + t * d[0], p.p[1] + t * d[1]];
            let key = match p.out {
                Line::Pair(a_, b_) => {
                    let (ca, cb) = (&circles[a_ as usize], &circles[b_ as usize]);
                    let side = cross(sub(cb.centre, ca.centre), sub(x, ca.centre));
                    VKey::CircleCircle(a_, b_, u8::from(side < 0.0))
                }
                Line::Side(s) => {
                    let along = if s < 2 { x[1] - cy } else { x[0] - cx };
                    VKey::CircleSide(i, s, u8::from(along >= 0.0))
                }
                _ => {
                    *uniq += 1;
                    VKey::Unique(*uniq)
                }
            };
            let xp = key_position(key, circles, &bxv, x);
            let ang = (xp[1] - cy).atan2(xp[0] - cx);
            let out = if exit { Line::Arc } else { p.out };
            items.push((PVert { p: xp, key, out }, Some(ang), exit));
        };
        match (pin, qin) {
            (true, false) => crossing(t1.clamp(0.0, 1.0), true, &mut items),
            (false, true) => crossing(t0.clamp(0.0, 1.0), false, &mut items),
            (false, false) => {
                if t0 > 0.0 && t1 < 1.0 && t0 < t1 {
                    crossing(t0, false, &mut items);
                    crossing(t1, true, &mut items);
                }
            }
            (true, true) => {}
        }
    }
    let step = std::f64::consts::TAU / n_seg as f64;
    let margin = 0.25 * step;
    let mut verts = Vec::with_capacity(items.len() + n_seg as usize);
    let arc_point = |k: i64| {
        let kk = k.rem_euclid(n_seg as i64) as u32;
        let th = step * kk as f64;
        PVert {
            p: [cx + r * th.cos(), cy + r * th.sin()],
            key: VKey::Arc(i, kk),
            out: Line::Arc,
        }
    };
    let has_crossing = items.iter().any(|it| it.1.is_some());
    if !has_crossing {
        if !items.is_empty() {
            // The whole cell lies inside the disc.
            return SolidPolygon {
                verts: items.into_iter().map(|it| it.0).collect(),
            };
        }
        // No cell vertex in the disc and no crossing: the disc is inside the cell or outside.
        let centre_in = (0..m).all(|k| {
            let (p, q) = (a[k].p, a[(k + 1) % m].p);
            cross(sub(q, p), sub(c.centre, p)) >= 0.0
        });
        if centre_in {
            return SolidPolygon {
                verts: (0..n_seg as i64).map(arc_point).collect(),
            };
        }
        return SolidPolygon::default();
    }
    let ni = items.len();
    for k in 0..ni {
        let (v, ang, exit) = items[k];
        verts.push(v);
        if exit {
            let (_, next_ang, next_exit) = items[(k + 1) % ni];
            let (Some(a0), Some(a1)) = (ang, next_ang) else {
                continue;
            };
            if next_exit {
                continue;
            }
            let mut span = a1 - a0;
            if span <= 0.0 {
                span += std::f64::consts::TAU;
            }
            let k0 = ((a0 + margin) / step).ceil() as i64;
            let mut kk = k0;
            while (kk as f64) * step < a0 + span - margin {
                verts.push(arc_point(kk));
                kk += 1;
            }
        }
    }
    SolidPolygon { verts }
}

/// Stage 7: the permutation that sorts triangles along the Z-order (Morton) curve of their
/// centroids, each coordinate quantised to 16 bits over the bounding box of the centroids
/// (ties keep the input order, so the result is deterministic).
pub fn locality_order(tris: &[[u32; 3]], points: &[[f64; 2]]) -> Vec<u32> {
    let centroid = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| points[v as usize]);
        [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]
    };
    let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
    for t in tris {
        let g = centroid(t);
        for k in 0..2 {
            lo[k] = lo[k].min(g[k]);
            hi[k] = hi[k].max(g[k]);
        }
    }
    let scale: [f64; 2] = std::array::from_fn(|k| {
        let span = hi[k] - lo[k];
        if span.is_finite() && span > 0.0 {
            65535.0 / span
        } else {
            0.0
        }
    });
    // Spreads the 16 low bits of `x` to the even bit positions.
    let spread = |x: u32| {
        let mut x = x & 0xffff;
        x = (x | (x << 8)) & 0x00ff_00ff;
        x = (x | (x << 4)) & 0x0f0f_0f0f;
        x = (x | (x << 2)) & 0x3333_3333;
        (x | (x << 1)) & 0x5555_5555
    };
    let mut keyed: Vec<(u32, u32)> = tris
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let g = centroid(t);
            // `as` saturates (NaN to 0), so the quantised coordinate is always in 0..=65535.
            let q: [u32; 2] = std::array::from_fn(|k| ((g[k] - lo[k]) * scale[k]) as u32);
            (spread(q[0]) | (spread(q[1]) << 1), i as u32)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

/// Stage 4: merges vertices `a`, `b` closer than `min(tol[a], tol[b])` in each coordinate
/// (sort-and-sweep). Returns for every vertex its representative (the lowest index of its
/// cluster). No merging at all where every tolerance is zero.
fn snap_vertices(points: &[[f64; 2]], tol: &[f64]) -> Vec<u32> {
    let n = points.len();
    let mut rep: Vec<u32> = (0..n as u32).collect();
    if tol.iter().all(|&t| t <= 0.0) || n < 2 {
        return rep;
    }
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_unstable_by(|&a, &b| points[a as usize][0].total_cmp(&points[b as usize][0]));
    fn find(rep: &mut [u32], mut x: u32) -> u32 {
        while rep[x as usize] != x {
            let p = rep[rep[x as usize] as usize];
            rep[x as usize] = p;
            x = p;
        }
        x
    }
    for s in 0..n {
        let a = order[s] as usize;
        for &bb in &order[s + 1..] {
            let b = bb as usize;
            let dx = points[b][0] - points[a][0];
            // Sorted by x: no later b is within tol[a] ≥ min(tol[a], tol[b]) either.
            if dx > tol[a] {
                break;
            }
            let t = tol[a].min(tol[b]);
            if dx <= t && (points[b][1] - points[a][1]).abs() <= t {
                let (ra, rb) = (find(&mut rep, a as u32), find(&mut rep, b as u32));
                if ra != rb {
                    let (lo, hi) = (ra.min(rb), ra.max(rb));
                    rep[hi as usize] = lo;
                }
            }
        }
    }
    for v in 0..n as u32 {
        let r = find(&mut rep, v);
        rep[v as usize] = r;
    }
    rep
}

/// The snap distance of a point at `p` scaled by `radius`: `tolerance × radius`, but at least
/// 8 ulps of the point's largest coordinate (0 when `tolerance` is 0: no snapping).
fn snap_distance(tolerance: f64, radius: f64, p: [f64; 2]) -> f64 {
    if tolerance > 0.0 {
        (tolerance * radius).max(8.0 * f64::EPSILON * p[0].abs().max(p[1].abs()))
    } else {
        0.0
    }
}

fn circumradius(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    let (ab, bc, ca) = (sub(b, a), sub(c, b), sub(a, c));
    let area2 = cross(ab, sub(c, a)).abs();
    if area2 == 0.0 {
        return f64::INFINITY;
    }
    (dot(ab, ab) * dot(bc, bc) * dot(ca, ca)).sqrt() / (2.0 * area2)
}

/// Anchors of every vertex from the keys merged into it.
fn anchors_from_keys<I: Iterator<Item = VKey>>(
    used_old: &[u32],
    keys_of: impl Fn(u32) -> I,
    pos: &[[f64; 2]],
    circles: &[Circle],
    bx: Option<[f64; 4]>,
) -> VertexAnchors {
    let mut anchors = VertexAnchors::default();
    for (v, &old) in used_old.iter().enumerate() {
        let mut list = [NONE; 3];
        let mut n_list = 0usize;
        let mut constraint = VertexConstraint::Free;
        for k in keys_of(old) {
            let (circ, con): (&[u32], VertexConstraint) = match k {
                VKey::Arc(i, _) | VKey::Centre(i) => (&[i], VertexConstraint::Free),
                VKey::CircleCircle(a, b, _) => (&[a, b], VertexConstraint::Free),
                VKey::Radical(a, b, c) => (&[a, b, c], VertexConstraint::Free),
                VKey::PairSide(a, b, s) => (&[a, b], VertexConstraint::OnSide(s)),
                VKey::CircleSide(i, s, _) => (&[i], VertexConstraint::OnSide(s)),
                VKey::Corner(..) | VKey::Unique(_) | VKey::SidePoint(..) => {
                    (&[], VertexConstraint::Fixed)
                }
            };
            // Combine `circ` into the list.
            for &i in circ {
                if !list[..n_list].contains(&i) && n_list < 3 {
                    list[n_list] = i;
                    n_list += 1;
                }
            }
            constraint = match (constraint, con) {
                (VertexConstraint::Fixed, _) | (_, VertexConstraint::Fixed) => {
                    VertexConstraint::Fixed
                }
                (VertexConstraint::OnSide(a), VertexConstraint::OnSide(b)) if a != b => {
                    VertexConstraint::Fixed
                }
                (VertexConstraint::OnSide(a), _) | (_, VertexConstraint::OnSide(a)) => {
                    VertexConstraint::OnSide(a)
                }
                _ => VertexConstraint::Free,
            };
        }
        if n_list == 0 {
            constraint = VertexConstraint::Fixed;
        }
        // Any vertex exactly on a box side (e.g. the grid point of a circle touching it)
        // stays on it.
        if let Some(b) = bx {
            let mut on = [0u8; 4];
            let mut n_on = 0;
            for s in 0..4u8 {
                if pos[v][usize::from(s >= 2)] == b[s as usize] {
                    on[n_on] = s;
                    n_on += 1;
                }
            }
            constraint = match (n_on, constraint) {
                (0, c) => c,
                (1, VertexConstraint::Free) => VertexConstraint::OnSide(on[0]),
                (1, VertexConstraint::OnSide(s)) if s == on[0] => VertexConstraint::OnSide(s),
                _ => VertexConstraint::Fixed,
            };
        }
        anchors.push(pos[v], &list[..n_list], constraint, circles);
    }
    anchors
}

/// Adds Steiner points on each box side (keys `SidePoint`) wherever the points already on it
/// (corners, circle crossings, points snapped onto it) leave a gap longer than `spacing` that
/// no circle covers (a covered gap is an edge of that circle's solid polygon): the gap is cut
/// into equal parts no longer than `spacing`.
fn side_points(
    b: &[f64; 4],
    spacing: f64,
    circles: &[Circle],
    points: &mut Vec<[f64; 2]>,
    keys: &mut Vec<VKey>,
) {
    if !(spacing.is_finite() && spacing > 0.0) {
        return;
    }
    for s in 0..4u8 {
        let (normal, along) = if s < 2 { (0, 1) } else { (1, 0) };
        let side = b[s as usize];
        let (lo, hi) = if s < 2 { (b[2], b[3]) } else { (b[0], b[1]) };
        // The circles that reach the side.
        let near: Vec<&Circle> = circles
            .iter()
            .filter(|c| (c.centre[normal] - side).abs() < c.radius)
            .collect();
        let covered = |x: f64| {
            let mut p = [0.0; 2];
            p[normal] = side;
            p[along] = x;
            near.iter().any(|c| {
                let d = sub(p, c.centre);
                dot(d, d) < c.radius * c.radius
            })
        };
        let mut on: Vec<f64> = points
            .iter()
            .filter(|p| p[normal] == side && p[along] >= lo && p[along] <= hi)
            .map(|p| p[along])
            .collect();
        on.sort_unstable_by(f64::total_cmp);
        on.dedup();
        let mut k = 0u32;
        for w in on.windows(2) {
            let gap = w[1] - w[0];
            let parts = (gap / spacing).ceil();
            if !(2.0..=1e6).contains(&parts) || covered(0.5 * (w[0] + w[1])) {
                continue;
            }
            for j in 1..parts as u32 {
                let mut p = [0.0; 2];
                p[normal] = side;
                p[along] = w[0] + gap * f64::from(j) / parts;
                points.push(p);
                keys.push(VKey::SidePoint(s, k));
                k += 1;
            }
        }
    }
}

/// Meshes a packing of circles (see the module docs for the stages).
pub fn mesh_packing(
    circles: &[Circle],
    contacts: &[Contact],
    settings: &MeshSettings,
) -> Result<PackingMesh, MeshError> {
    let prm = settings.params();
    validate_input(circles, contacts)?;
    let bx = match prm.outline {
        Outline::Box { min, max } => Some([min[0], max[0], min[1], max[1]]),
        Outline::AlphaShape { .. } => {
            if circles.is_empty() {
                return Err(MeshError::NoCircles);
            }
            None
        }
    };
    let nc = circles.len();
    let thickness = match prm.thickness {
        Some(t) => t,
        None => {
            let dmax = circles.iter().map(|c| 2.0 * c.radius).fold(0.0, f64::max);
            if dmax > 0.0 {
                dmax
            } else {
                match bx {
                    Some(b) => (b[1] - b[0]).max(b[3] - b[2]),
                    None => 1.0,
                }
            }
        }
    };

    // Stage 2: overlapping pairs and neighbour lists.
    let pairs = overlapping_pairs(circles);
    let mut nb_start = vec![0u32; nc + 1];
    for p in &pairs {
        nb_start[p[0] as usize + 1] += 1;
        nb_start[p[1] as usize + 1] += 1;
    }
    for i in 0..nc {
        nb_start[i + 1] += nb_start[i];
    }
    let mut nb = vec![0u32; nb_start[nc] as usize];
    let mut fill = nb_start.clone();
    for p in &pairs {
        nb[fill[p[0] as usize] as usize] = p[1];
        fill[p[0] as usize] += 1;
        nb[fill[p[1] as usize] as usize] = p[0];
        fill[p[1] as usize] += 1;
    }

    // Stage 3: solid polygons; vertices deduplicated by key.
    let mut uniq = 0u32;
    let mut scratch = (Vec::new(), Vec::new());
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut keys: Vec<VKey> = Vec::new();
    let mut key_id: KeyMap<VKey, u32> = KeyMap::default();
    let mut poly_start: Vec<u32> = vec![0];
    let mut poly_verts: Vec<u32> = Vec::new();
    let mut poly_out: Vec<Line> = Vec::new();
    let n_seg = prm.segments_per_circle;
    for i in 0..nc {
        let nbs = &mut nb[nb_start[i] as usize..nb_start[i + 1] as usize];
        nbs.sort_unstable();
        let poly = solid_polygon(
            i as u32,
            circles,
            nbs,
            bx.as_ref(),
            n_seg,
            &mut uniq,
            &mut scratch,
        );
        for v in &poly.verts {
            let id = match v.key {
                VKey::Arc(..) => {
                    points.push(v.p);
                    keys.push(v.key);
                    (points.len() - 1) as u32
                }
                k => *key_id.entry(k).or_insert_with(|| {
                    points.push(v.p);
                    keys.push(k);
                    (points.len() - 1) as u32
                }),
            };
            poly_verts.push(id);
            poly_out.push(v.out);
        }
        poly_start.push(poly_verts.len() as u32);
        // The centre, when well inside the polygon, splits the solid into wedges.
        if !poly.verts.is_empty() {
            let c = &circles[i];
            let m = poly.verts.len();
            let clear = (0..m).all(|k| {
                let (a, b) = (poly.verts[k].p, poly.verts[(k + 1) % m].p);
                let e = sub(b, a);
                let len = dot(e, e).sqrt();
                len > 0.0 && cross(e, sub(c.centre, a)) >= 0.25 * c.radius * len
            });
            if clear {
                points.push(c.centre);
                keys.push(VKey::Centre(i as u32));
            }
        }
    }
    if let Some(b) = bx {
        for (s1, s2) in [(0u8, 2u8), (1, 2), (1, 3), (0, 3)] {
            let k = VKey::Corner(s1, s2);
            key_id.entry(k).or_insert_with(|| {
                points.push([b[s1 as usize], b[s2 as usize]]);
                keys.push(k);
                (points.len() - 1) as u32
            });
        }
    }
    let mean_r = if nc > 0 {
        circles.iter().map(|c| c.radius).sum::<f64>() / nc as f64
    } else {
        1.0
    };
    // Snap distance of each point: snap_tolerance × the radius of the smallest circle it belongs
    // to, at most the mean radius (corners: the mean radius). Scaled by the mean radius alone, a
    // circle many decades smaller than the others had its own grid points (2πr/n apart) within
    // the snap distance, and the merges, chained, moved its solid vertices by nearly its
    // radius. Never below the round-off of the coordinates, so tangent points still meet.
    let radius = |i: u32| circles[i as usize].radius;
    let snap: Vec<f64> = points
        .iter()
        .zip(&keys)
        .map(|(p, k)| {
            let r = match *k {
                VKey::Arc(i, _) | VKey::Centre(i) | VKey::CircleSide(i, _, _) => radius(i),
                VKey::CircleCircle(a, b, _) | VKey::PairSide(a, b, _) => radius(a).min(radius(b)),
                VKey::Radical(a, b, c) => radius(a).min(radius(b)).min(radius(c)),
                VKey::Corner(..) | VKey::Unique(_) | VKey::SidePoint(..) => mean_r,
            };
            snap_distance(prm.snap_tolerance, r.min(mean_r), *p)
        })
        .collect();
    for (p, &snap) in points.iter_mut().zip(&snap) {
        for x in p.iter_mut() {
            if x.abs() < 1e-40 {
                *x = 0.0;
            }
        }
        // Points within the snap distance of a box side go onto it (circles touching a side).
        if let Some(b) = bx {
            for (s, &side) in b.iter().enumerate() {
                let k = usize::from(s >= 2);
                if (p[k] - side).abs() <= snap {
                    p[k] = side;
                }
            }
        }
    }
    let mut snap = snap;
    if let (Some(b), true) = (bx, prm.side_points && nc > 0) {
        // Steiner points on the box sides, so that no fluid cell between a side and the
        // circles near it runs along the side from one circle crossing to the next (a sliver
        // many radii long, whose one temperature short-circuits the heat path along the side).
        let spacing = std::f64::consts::TAU * mean_r / f64::from(prm.segments_per_circle.max(3));
        let before = points.len();
        side_points(&b, spacing, circles, &mut points, &mut keys);
        snap.extend(
            (before..points.len()).map(|v| snap_distance(prm.snap_tolerance, mean_r, points[v])),
        );
    }

    // Stage 4: snapping.
    let rep = snap_vertices(&points, &snap);
    let mut new_id = vec![NONE; points.len()];
    let mut vpos: Vec<[f64; 2]> = Vec::new();
    // Keys of each merged vertex: the first one, plus the rare extra ones of merged points.
    let mut vkey_first: Vec<VKey> = Vec::with_capacity(points.len());
    let mut vkey_extra: Vec<(u32, VKey)> = Vec::new();
    for v in 0..points.len() {
        let r = rep[v] as usize;
        if new_id[r] == NONE {
            new_id[r] = vpos.len() as u32;
            vpos.push(points[r]);
            vkey_first.push(keys[r]);
        }
        new_id[v] = new_id[r];
        if v != r {
            vkey_extra.push((new_id[v], keys[v]));
        }
    }
    vkey_extra.sort_by_key(|e| e.0);
    // Polygons in new ids, consecutive duplicates removed.
    let mut polys: Vec<Vec<(u32, Line)>> = Vec::with_capacity(nc);
    for i in 0..nc {
        let (s, e) = (poly_start[i] as usize, poly_start[i + 1] as usize);
        let mut pv: Vec<(u32, Line)> = Vec::with_capacity(e - s);
        for k in s..e {
            let id = new_id[poly_verts[k] as usize];
            if pv.last().map(|l| l.0) != Some(id) {
                pv.push((id, poly_out[k]));
            }
        }
        while pv.len() > 1 && pv.first().map(|f| f.0) == pv.last().map(|l| l.0) {
            pv.pop();
        }
        if pv.len() < 3 {
            pv.clear();
        }
        polys.push(pv);
    }

    // Constraint edges: polygon edges and the box sides.
    let mut edges: Vec<[usize; 2]> = Vec::new();
    for pv in &polys {
        for k in 0..pv.len() {
            let (a, b) = (pv[k].0 as usize, pv[(k + 1) % pv.len()].0 as usize);
            edges.push([a.min(b), a.max(b)]);
        }
    }
    if let Some(b) = bx {
        for (s, &side_value) in b.iter().enumerate() {
            let along = if s < 2 { 1 } else { 0 };
            let coord = if s < 2 { 0 } else { 1 };
            let mut on: Vec<u32> = (0..vpos.len() as u32)
                .filter(|&v| vpos[v as usize][coord] == side_value)
                .collect();
            on.sort_unstable_by(|&x, &y| {
                vpos[x as usize][along].total_cmp(&vpos[y as usize][along])
            });
            for w in on.windows(2) {
                edges.push([w[0].min(w[1]) as usize, w[0].max(w[1]) as usize]);
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges.retain(|e| e[0] != e[1]);

    // Stage 5: constrained Delaunay triangulation.
    let spade_pts: Vec<Point2<f64>> = vpos.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let mut conflicts = 0usize;
    let cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::try_bulk_load_cdt(spade_pts, edges, |_| conflicts += 1)
            .map_err(|e| MeshError::Triangulation {
            reason: format!("{e:?}"),
        })?;
    if conflicts > 0 {
        return Err(MeshError::ConstraintConflict { count: conflicts });
    }
    if cdt.num_vertices() != vpos.len() {
        return Err(MeshError::Triangulation {
            reason: format!(
                "{} of {} vertices were duplicates after snapping",
                vpos.len() - cdt.num_vertices(),
                vpos.len()
            ),
        });
    }
    let mut tris: Vec<[u32; 3]> = cdt
        .inner_faces()
        .map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    drop(cdt);

    // Stage 6: classification. Solid polygons are convex and constrained, and the only vertex
    // inside one is its circle's centre, so a triangle is a solid cell of circle `i` exactly
    // when its three corners are vertices of polygon `i` (or its centre).
    let nvp = vpos.len();
    let mut member_start = vec![0u32; nvp + 1];
    let centre_of = |v: usize| match vkey_first[v] {
        VKey::Centre(i) => Some(i),
        _ => None,
    };
    for pv in &polys {
        for &(v, _) in pv {
            member_start[v as usize + 1] += 1;
        }
    }
    for v in 0..nvp {
        if centre_of(v).is_some() {
            member_start[v + 1] += 1;
        }
    }
    for v in 0..nvp {
        member_start[v + 1] += member_start[v];
    }
    let mut member = vec![0u32; member_start[nvp] as usize];
    let mut mfill = member_start.clone();
    for (i, pv) in polys.iter().enumerate() {
        for &(v, _) in pv {
            member[mfill[v as usize] as usize] = i as u32;
            mfill[v as usize] += 1;
        }
    }
    for v in 0..nvp {
        if let Some(i) = centre_of(v) {
            member[mfill[v] as usize] = i;
            mfill[v] += 1;
        }
    }
    let members = |v: u32| &member[member_start[v as usize] as usize..mfill[v as usize] as usize];
    let mut tri_circle: Vec<u32> = Vec::with_capacity(tris.len());
    for t in &tris {
        let (m1, m2) = (members(t[1]), members(t[2]));
        let owner = members(t[0])
            .iter()
            .copied()
            .find(|i| m1.contains(i) && m2.contains(i))
            .unwrap_or(NONE);
        tri_circle.push(owner);
    }

    // Alpha-shape outline: peel fluid triangles from the hull.
    if let Outline::AlphaShape { alpha } = prm.outline {
        let nt = tris.len();
        let mut edge_tris: KeyMap<(u32, u32), [u32; 2]> =
            KeyMap::with_capacity_and_hasher(nt * 2, Default::default());
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let e = edge_tris
                    .entry((a.min(b), a.max(b)))
                    .or_insert([NONE, NONE]);
                if e[0] == NONE {
                    e[0] = ti as u32;
                } else {
                    e[1] = ti as u32;
                }
            }
        }
        let mut removed = vec![false; nt];
        let peelable = |ti: usize| {
            let p = tris[ti].map(|v| vpos[v as usize]);
            tri_circle[ti] == NONE && circumradius(p[0], p[1], p[2]) > alpha
        };
        let mut stack: Vec<u32> = Vec::new();
        for e in edge_tris.values() {
            if e[1] == NONE && peelable(e[0] as usize) && !removed[e[0] as usize] {
                removed[e[0] as usize] = true;
                stack.push(e[0]);
            }
        }
        while let Some(ti) = stack.pop() {
            let t = tris[ti as usize];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if let Some(e) = edge_tris.get(&(a.min(b), a.max(b))) {
                    for &o in e {
                        if o != NONE && !removed[o as usize] && peelable(o as usize) {
                            removed[o as usize] = true;
                            stack.push(o);
                        }
                    }
                }
            }
        }
        let mut k = 0;
        tris.retain(|_| {
            k += 1;
            !removed[k - 1]
        });
        let mut k = 0;
        tri_circle.retain(|_| {
            k += 1;
            !removed[k - 1]
        });
    }

    // Stage 7: locality order of the triangles (vertices follow below).
    let order = locality_order(&tris, &vpos);
    let mut tris: Vec<[u32; 3]> = order.iter().map(|&t| tris[t as usize]).collect();
    let tri_circle: Vec<u32> = order.iter().map(|&t| tri_circle[t as usize]).collect();

    // Drop vertices no triangle uses.
    let mut used = vec![NONE; vpos.len()];
    let mut vertices = Vec::with_capacity(vpos.len());
    let mut used_old: Vec<u32> = Vec::with_capacity(vpos.len());
    for t in tris.iter_mut() {
        for v in t.iter_mut() {
            if used[*v as usize] == NONE {
                used[*v as usize] = vertices.len() as u32;
                vertices.push(vpos[*v as usize]);
                used_old.push(*v);
            }
            *v = used[*v as usize];
        }
    }
    let keys_of = |v: u32| {
        let lo = vkey_extra.partition_point(|e| e.0 < v);
        let hi = vkey_extra.partition_point(|e| e.0 <= v);
        std::iter::once(vkey_first[v as usize]).chain(vkey_extra[lo..hi].iter().map(|e| e.1))
    };
    let anchors = anchors_from_keys(&used_old, keys_of, &vertices, circles, bx);
    // Vertices grouped by their kinematics (free on one circle, most of them, first; then two
    // and three anchors; then the constrained ones), each group in order of first use: the
    // vertex kinematics then takes the same branches for a whole group, and cells still read
    // their corners from a few streams that all advance with the cell order.
    let vertex_order = anchors.kinematics_order();
    let mut renumber = vec![0u32; vertex_order.len()];
    for (new, &old) in vertex_order.iter().enumerate() {
        renumber[old as usize] = new as u32;
    }
    let anchors = anchors.permuted(&vertex_order);
    let vertices: Vec<[f64; 2]> = vertex_order.iter().map(|&v| vertices[v as usize]).collect();
    let used_old: Vec<u32> = vertex_order.iter().map(|&v| used_old[v as usize]).collect();
    for v in tris.iter_mut().flatten() {
        *v = renumber[*v as usize];
    }
    for u in used.iter_mut().filter(|u| **u != NONE) {
        *u = renumber[*u as usize];
    }
    let vertex_sphere: Vec<u32> = used_old
        .iter()
        .map(|&v| {
            keys_of(v)
                .find_map(|k| match k {
                    VKey::Arc(i, _) | VKey::CircleSide(i, _, _) => Some(i),
                    VKey::CircleCircle(a, _, _) => Some(a),
                    _ => None,
                })
                .map_or(NONE, |i| circles[i as usize].owner)
        })
        .collect();
    let cell_kind: Vec<CellKind> = tri_circle
        .iter()
        .map(|&i| {
            if i == NONE {
                CellKind::Fluid
            } else {
                CellKind::Solid {
                    owner: circles[i as usize].owner,
                }
            }
        })
        .collect();
    let scale = match bx {
        Some(b) => (b[1] - b[0]).max(b[3] - b[2]),
        None => mean_r,
    };
    let mut mesh = PoreMesh::from_triangles(
        vertices,
        vertex_sphere,
        tris,
        cell_kind,
        thickness,
        1e-12 * scale,
        prm.t2t_reduction_factor,
    )?;
    let narrow_gap = if prm.narrow_gap_length > 0.0 {
        [prm.narrow_gap_length, prm.s2s.aperture(0.0)]
    } else {
        [0.0; 2]
    };
    if prm.narrow_gap_length > 0.0 {
        mesh.update_t2t_apertures(T2tApertureLaw {
            reduction_factor: prm.t2t_reduction_factor,
            narrow_gap_length: narrow_gap[0],
            narrow_gap_aperture: narrow_gap[1],
        });
    }

    // Chords: the polygon edge of circle a on line Pair(a, b).
    let mut chords = Chords::default();
    // Cells around each vertex.
    let nv = mesh.vertices.len();
    let mut vc_start = vec![0u32; nv + 1];
    for t in &mesh.cell_vertices {
        for &v in t {
            vc_start[v as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        vc_start[v + 1] += vc_start[v];
    }
    let mut vc = vec![0u32; vc_start[nv] as usize];
    let mut fill = vc_start.clone();
    for (c, t) in mesh.cell_vertices.iter().enumerate() {
        for &v in t {
            vc[fill[v as usize] as usize] = c as u32;
            fill[v as usize] += 1;
        }
    }
    let face_between = |u: u32, v: u32| -> u32 {
        for &c in &vc[vc_start[u as usize] as usize..vc_start[u as usize + 1] as usize] {
            for &f in &mesh.cell_faces[c as usize] {
                let [a, b] = mesh.face_vertices[f as usize];
                if (a == u && b == v) || (a == v && b == u) {
                    return f;
                }
            }
        }
        NONE
    };
    for p in &pairs {
        let (a, b) = (p[0], p[1]);
        let (ca, cb) = (&circles[a as usize], &circles[b as usize]);
        let d = sub(cb.centre, ca.centre);
        let overlap = ca.radius + cb.radius - dot(d, d).sqrt();
        let mut ends = [NONE, NONE];
        let pv = &polys[a as usize];
        for k in 0..pv.len() {
            if pv[k].1 == Line::Pair(a, b) {
                let (u, v) = (pv[k].0, pv[(k + 1) % pv.len()].0);
                ends = [
                    used.get(u as usize).copied().unwrap_or(NONE),
                    used.get(v as usize).copied().unwrap_or(NONE),
                ];
            }
        }
        let face = if ends[0] != NONE && ends[1] != NONE && ends[0] != ends[1] {
            face_between(ends[0], ends[1])
        } else {
            NONE
        };
        chords.circles.push([a, b]);
        chords.overlap.push(overlap);
        chords.ends.push(ends);
        chords.face.push(face);
    }

    // S2S channels.
    let fluid_at = |v: u32| -> u32 {
        let x = mesh.vertices[v as usize];
        let mut best = (f64::MAX, NONE);
        for &c in &vc[vc_start[v as usize] as usize..vc_start[v as usize + 1] as usize] {
            if mesh.cell_kind[c as usize].is_fluid() {
                let d = sub(mesh.cell_centroid[c as usize], x);
                let d2 = dot(d, d);
                if d2 < best.0 {
                    best = (d2, c);
                }
            }
        }
        best.1
    };
    let mut contact_channel = vec![NONE; contacts.len()];
    let mut new_channels: Vec<(usize, [u32; 2], f64)> = Vec::new();
    // Gaps that end in a junction, a chord end inside a third circle where three (or more)
    // circles overlap: (junction vertex, fluid cell at the other end, contact), and gaps
    // between two junctions.
    let mut dangling: Vec<(u32, u32, usize)> = Vec::new();
    let mut junction_links: Vec<[u32; 2]> = Vec::new();
    for (k, ct) in contacts.iter().enumerate() {
        let (a, b) = (
            ct.circles[0].min(ct.circles[1]),
            ct.circles[0].max(ct.circles[1]),
        );
        let Ok(ch) = chords.circles.binary_search(&[a, b]) else {
            continue;
        };
        let ends = chords.ends[ch];
        if ends[0] == NONE || ends[1] == NONE {
            continue;
        }
        let (f0, f1) = (fluid_at(ends[0]), fluid_at(ends[1]));
        match (f0 == NONE, f1 == NONE) {
            (false, false) if f0 != f1 => {
                new_channels.push((k, [f0, f1], prm.s2s.aperture(ct.normal_stress)));
            }
            (false, true) => dangling.push((ends[1], f0, k)),
            (true, false) => dangling.push((ends[0], f1, k)),
            (true, true) => junction_links.push(ends),
            _ => {}
        }
    }
    // The gaps that meet in one junction (or in junctions joined by gaps) are one flow
    // path: chain their fluid ends, each link carrying the contact of its first end.
    new_channels.extend(junction_channels(&dangling, &junction_links, |k| {
        prm.s2s.aperture(contacts[k].normal_stress)
    }));
    // In the order of their first cell (ties in contact order), so that passes over the
    // channels gather cell data from nearby memory, as they do for the T2T channels.
    new_channels.sort_by_key(|&(_, cells, _)| cells[0]);
    for (k, cells, h) in new_channels {
        let (p0, p1) = (
            mesh.cell_centroid[cells[0] as usize],
            mesh.cell_centroid[cells[1] as usize],
        );
        let d = sub(p1, p0);
        contact_channel[k] = mesh.channels.len() as u32;
        mesh.channels.kind.push(ChannelKind::S2S);
        mesh.channels.cells.push(cells);
        mesh.channels.length.push(dot(d, d).sqrt());
        mesh.channels.aperture.push(h);
        mesh.channels.face.push(NONE);
        mesh.channels.contact.push(k as u32);
    }

    // Cells of each circle.
    let cell_circle = tri_circle;
    let mut circle_cell_offsets = vec![0u32; nc + 1];
    for &i in &cell_circle {
        if i != NONE {
            circle_cell_offsets[i as usize + 1] += 1;
        }
    }
    for i in 0..nc {
        circle_cell_offsets[i + 1] += circle_cell_offsets[i];
    }
    let mut circle_cells = vec![0u32; circle_cell_offsets[nc] as usize];
    let mut fill = circle_cell_offsets.clone();
    for (c, &i) in cell_circle.iter().enumerate() {
        if i != NONE {
            circle_cells[fill[i as usize] as usize] = c as u32;
            fill[i as usize] += 1;
        }
    }
    Ok(PackingMesh {
        mesh,
        circles: circles.to_vec(),
        anchors,
        chords,
        contact_channel,
        circle_cell_offsets,
        circle_cells,
        cell_circle,
        t2t_reduction_factor: prm.t2t_reduction_factor,
        narrow_gap,
    })
}
/// S2S channels through junctions (mesher step 8): where three or more circles overlap, the
/// chord of a contact ends inside a third circle and has a fluid cell at one end only. The
/// gaps of the contacts that meet there (A-Eq. 8) are one path: `dangling` lists each such
/// gap as (junction vertex, fluid cell at its open end, contact), `junction_links` the gaps
/// closed at both ends, which join their junctions. Within every group of joined junctions
/// the distinct fluid cells, in increasing order, are chained by channels `(c_i, c_{i+1})`,
/// each carrying the contact (and so the aperture `aperture(contact)`) of the first gap that
/// reaches `c_i`. A group with one fluid cell adds nothing: its pore is enclosed by solid.
/// Deterministic: the result depends only on the order-free content of the inputs.
fn junction_channels(
    dangling: &[(u32, u32, usize)],
    junction_links: &[[u32; 2]],
    aperture: impl Fn(usize) -> f64,
) -> Vec<(usize, [u32; 2], f64)> {
    // Union-find over the junction vertices, numbered densely in increasing order.
    let mut junctions: Vec<u32> = dangling
        .iter()
        .map(|d| d.0)
        .chain(junction_links.iter().flatten().copied())
        .collect();
    junctions.sort_unstable();
    junctions.dedup();
    let index = |v: u32| junctions.binary_search(&v).unwrap_or(0);
    let mut parent: Vec<usize> = (0..junctions.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for &[u, v] in junction_links {
        let (ru, rv) = (root(&mut parent, index(u)), root(&mut parent, index(v)));
        if ru != rv {
            parent[ru.max(rv)] = ru.min(rv);
        }
    }
    // (group, fluid cell, contact), sorted: each group's cells in increasing order, each
    // cell's smallest contact first.
    let mut ends: Vec<(usize, u32, usize)> = dangling
        .iter()
        .map(|&(v, cell, k)| (root(&mut parent, index(v)), cell, k))
        .collect();
    ends.sort_unstable();
    ends.dedup_by_key(|e| (e.0, e.1));
    ends.windows(2)
        .filter(|w| w[0].0 == w[1].0)
        .map(|w| (w[0].2, [w[0].1, w[1].1], aperture(w[0].2)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::junction_channels;

    /// Three gaps meeting in one junction (vertex 7) with open ends in cells 30, 10 and 20:
    /// the cells are chained in increasing order, each link carrying the contact that reaches
    /// its first cell; a gap closed at both ends joins a second junction (vertex 9) whose one
    /// open gap (cell 40) joins the chain; a junction with one open gap adds nothing.
    #[test]
    fn gaps_meeting_in_joined_junctions_are_chained_and_a_lone_gap_is_not() {
        let dangling = [(7, 30, 2), (7, 10, 0), (7, 20, 1), (9, 40, 3), (5, 50, 4)];
        let links = [[9, 7]];
        let aperture = |k: usize| 1e-6 * (k + 1) as f64;
        let got = junction_channels(&dangling, &links, aperture);
        assert_eq!(
            got,
            vec![
                (0, [10, 20], 1e-6),
                (1, [20, 30], 2e-6),
                (2, [30, 40], 3e-6)
            ]
        );
        // The order of the inputs does not matter.
        let mut reversed = dangling;
        reversed.reverse();
        assert_eq!(junction_channels(&reversed, &[[7, 9]], aperture), got);
        // Two gaps of one junction into the same cell: no channel from the cell to itself.
        assert!(junction_channels(&[(1, 8, 0), (1, 8, 1)], &[], aperture).is_empty());
    }
}
