//! The mesh data types shared with the flow and heat solvers: [`PoreMesh`] and its parts.
//!
//! A `PoreMesh` is a planar triangulation of the specimen's mid-plane (the projection of a
//! single layer of spheres). Every triangle is a *cell*: a fluid cell (a virtual pore, VP) or a
//! solid cell owned by one sphere. Cell volumes are `area × thickness`. Every triangle edge is a
//! *face*. Fluid cells are linked by *channels*: T2T channels across the edge two fluid cells
//! share (aperture A-Eq. 9) and S2S channels across a sphere–sphere contact (aperture A-Eq. 8).
//!
//! Storage is struct-of-arrays; indices are `u32`, with [`NONE`] for "no such entity".

use serde::{Deserialize, Serialize};

/// Index value meaning "none" (e.g. the missing second cell of a boundary face).
pub const NONE: u32 = u32::MAX;

/// What a triangle is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum CellKind {
    /// A virtual pore: carries fluid.
    Fluid,
    /// Part of a sphere's cross-section.
    Solid {
        /// Index of the sphere (circle) that owns the cell.
        owner: u32,
    },
}

impl CellKind {
    /// True for fluid cells (virtual pores).
    pub fn is_fluid(self) -> bool {
        matches!(self, CellKind::Fluid)
    }
}

/// Which part of the specimen's outer boundary a boundary face lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoundarySide {
    /// Smallest x.
    Left,
    /// Largest x.
    Right,
    /// Smallest y.
    Bottom,
    /// Largest y.
    Top,
    /// On the outline but not on one of the four sides of the bounding box.
    Outline,
}

/// Whether a face is shared by two cells or lies on the outer boundary.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FaceKind {
    /// Shared by two cells.
    Interior,
    /// On the outer boundary (only `face_cells[f][0]` is set).
    Boundary(BoundarySide),
}

/// Kind of a fluid channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ChannelKind {
    /// Triangle-to-triangle: across the edge shared by two fluid cells (A-Eq. 9).
    T2T,
    /// Sphere-to-sphere: across a contact between two spheres (A-Eq. 8).
    S2S,
}

/// Fluid channels (struct-of-arrays).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Channels {
    /// T2T or S2S.
    pub kind: Vec<ChannelKind>,
    /// The two fluid cells the channel joins.
    pub cells: Vec<[u32; 2]>,
    /// Distance between the centroids of the two cells \[m\].
    pub length: Vec<f64>,
    /// Hydraulic aperture h \[m\].
    pub aperture: Vec<f64>,
    /// For T2T: the shared face; for S2S: [`NONE`].
    pub face: Vec<u32>,
    /// For S2S: the index of the contact in the caller's contact list; for T2T: [`NONE`].
    pub contact: Vec<u32>,
}

impl Channels {
    /// Number of channels.
    pub fn len(&self) -> usize {
        self.kind.len()
    }

    /// True when there is no channel.
    pub fn is_empty(&self) -> bool {
        self.kind.is_empty()
    }
}

/// The virtual pore network mesh.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PoreMesh {
    /// Out-of-plane thickness \[m\] that turns areas into volumes (paper A: the largest sphere
    /// diameter).
    pub thickness: f64,
    /// Vertex positions \[m\].
    pub vertices: Vec<[f64; 2]>,
    /// For vertices on a circle: the sphere index; otherwise [`NONE`].
    pub vertex_sphere: Vec<u32>,
    /// Triangle corners, counter-clockwise.
    pub cell_vertices: Vec<[u32; 3]>,
    /// Fluid or solid (with owner).
    pub cell_kind: Vec<CellKind>,
    /// Cell areas \[m²\].
    pub cell_area: Vec<f64>,
    /// Cell centroids \[m\].
    pub cell_centroid: Vec<[f64; 2]>,
    /// For each cell, its three faces: face `k` joins corners `k` and `k+1`.
    pub cell_faces: Vec<[u32; 3]>,
    /// Face end points.
    pub face_vertices: Vec<[u32; 2]>,
    /// The cells on either side; `[c, NONE]` on the boundary.
    pub face_cells: Vec<[u32; 2]>,
    /// Face lengths \[m\].
    pub face_length: Vec<f64>,
    /// Unit normals pointing from `face_cells[f][0]` towards `face_cells[f][1]` (outward on the
    /// boundary).
    pub face_normal: Vec<[f64; 2]>,
    /// Face mid-points \[m\].
    pub face_centroid: Vec<[f64; 2]>,
    /// Interior or boundary (with side).
    pub face_kind: Vec<FaceKind>,
    /// Fluid channels.
    pub channels: Channels,
}

/// Errors of mesh construction from triangles.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TopologyError {
    /// A triangle refers to a vertex that does not exist.
    #[error("cell {cell}: vertex index {vertex} out of range (mesh has {n_vertices} vertices)")]
    VertexOutOfRange {
        /// Cell index.
        cell: usize,
        /// Offending vertex index.
        vertex: u32,
        /// Number of vertices.
        n_vertices: usize,
    },
    /// A triangle has zero or negative area (after orientation it must be counter-clockwise).
    #[error("cell {cell}: degenerate triangle (area {area:e} m²)")]
    DegenerateCell {
        /// Cell index.
        cell: usize,
        /// Its signed area.
        area: f64,
    },
    /// An edge is shared by more than two triangles.
    #[error("edge ({a}, {b}) is shared by more than two cells")]
    NonManifoldEdge {
        /// First vertex.
        a: u32,
        /// Second vertex.
        b: u32,
    },
    /// Lengths of the input arrays disagree.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A non-finite coordinate or parameter.
    #[error("{what} {index}: non-finite value {value}")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A parameter outside its range.
    #[error("{name}: must be {range}, got {value}")]
    OutOfRange {
        /// Parameter name.
        name: &'static str,
        /// Allowed range, in words.
        range: &'static str,
        /// The value.
        value: f64,
    },
}

/// One third (centroids are `(a + b + c) · ⅓`).
const THIRD: f64 = 1.0 / 3.0;

fn signed_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
}

/// How many faces or channels the geometry stages treat together (two `f64` lanes of the
/// baseline x86-64 vector unit).
const LANES: usize = 2;

/// Length, unit normal and mid-point of the `L` faces `f` (see
/// [`PoreMesh::update_face_geometry`]).
#[inline(always)]
fn face_lanes<const L: usize>(
    vx: &[[f64; 2]],
    f: &[[u32; 2]; L],
    length: &mut [f64; L],
    normal: &mut [[f64; 2]; L],
    centroid: &mut [[f64; 2]; L],
) {
    let mut pa = [[0.0; 2]; L];
    let mut pb = [[0.0; 2]; L];
    for k in 0..L {
        pa[k] = vx[f[k][0] as usize];
        pb[k] = vx[f[k][1] as usize];
    }
    let dx: [f64; L] = std::array::from_fn(|k| pb[k][0] - pa[k][0]);
    let dy: [f64; L] = std::array::from_fn(|k| pb[k][1] - pa[k][1]);
    let len: [f64; L] = std::array::from_fn(|k| (dx[k] * dx[k] + dy[k] * dy[k]).sqrt());
    let inv: [f64; L] = std::array::from_fn(|k| reciprocal_or_zero(len[k]));
    for k in 0..L {
        length[k] = len[k];
        // Edge (a, b) is traversed counter-clockwise by its first cell, so the outward normal
        // of that cell is the edge direction rotated clockwise.
        normal[k] = [dy[k] * inv[k], -dx[k] * inv[k]];
        centroid[k] = [0.5 * (pa[k][0] + pb[k][0]), 0.5 * (pa[k][1] + pb[k][1])];
    }
}

/// `1 / x` for `x > 0`, else 0, as a selection rather than a jump (the quotient is always
/// computed; the test on `x` does not stall the stage).
#[inline(always)]
fn reciprocal_or_zero(x: f64) -> f64 {
    std::hint::select_unpredictable(x > 0.0, 1.0 / x, 0.0)
}

/// The T2T aperture law: A-Eq. 9, `h = γ · e · sin ω`, with an optional floor for the faces
/// that cross a narrow gap.
///
/// A T2T face shorter than `narrow_gap_length` joins two triangles across a gap between two
/// circles that is narrower than that length (its end points lie on the two circles). Such a
/// gap is, for the fluid, the same thing as a contact: A-Eq. 9 makes it nearly sealed
/// (`γ e` with the calibrated `γ = 0.0115` is 10⁻⁸ m for a 1 µm gap), so the triangles of
/// one gap, which the spheres' motion reshapes much more than it changes their sum, keep
/// separate pressures, and a liquid-filled one squeezed by a neighbour's corner builds
/// pressures of 10⁸–10¹² Pa that act on no sphere that squeezed it. With the floor, such a
/// face carries at least `narrow_gap_aperture` (the S2S aperture of A-Eq. 8 at zero stress,
/// the paper's aperture of two spheres that touch without load), so the triangles of a
/// narrow gap share their pressure. `narrow_gap_length = 0` is A-Eq. 9 alone.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct T2tApertureLaw {
    /// γ of A-Eq. 9 [-] (> 0).
    pub reduction_factor: f64,
    /// Faces shorter than this \[m\] (≥ 0; 0: none) get at least `narrow_gap_aperture`.
    pub narrow_gap_length: f64,
    /// The aperture floor of those faces \[m\] (≥ 0).
    pub narrow_gap_aperture: f64,
}

impl From<f64> for T2tApertureLaw {
    /// A-Eq. 9 with reduction factor γ and no narrow-gap floor.
    fn from(reduction_factor: f64) -> Self {
        Self {
            reduction_factor,
            narrow_gap_length: 0.0,
            narrow_gap_aperture: 0.0,
        }
    }
}

impl T2tApertureLaw {
    /// The aperture of the face from `pa` to `pb` between cells whose centroids are `d` apart
    /// (`len = |d|`): with the unit face normal `n = (e_y, −e_x) / e`,
    /// `e · sin ω = e · |n · d| / |d| = |e × d| / |d|`, which needs neither the normal nor the
    /// face length (0 when the centroids coincide); then the narrow-gap floor.
    #[inline(always)]
    pub fn aperture(&self, pa: [f64; 2], pb: [f64; 2], d: [f64; 2], len: f64) -> f64 {
        let e = [pb[0] - pa[0], pb[1] - pa[1]];
        let eq_9 = self.reduction_factor * (e[0] * d[1] - e[1] * d[0]).abs() / len;
        let narrow = e[0] * e[0] + e[1] * e[1] < self.narrow_gap_length * self.narrow_gap_length;
        let h = std::hint::select_unpredictable(narrow, eq_9.max(self.narrow_gap_aperture), eq_9);
        std::hint::select_unpredictable(len > 0.0, h, 0.0)
    }
}

/// What the channel stage reads of the cells, faces and vertices.
struct ChannelInputs<'a> {
    centroid: &'a [[f64; 2]],
    face_vertices: &'a [[u32; 2]],
    vertices: &'a [[f64; 2]],
}

/// Length and, with `Some(law)`, T2T aperture ([`T2tApertureLaw::aperture`]) of the `L` channels
/// given by their kind, cells and face (see [`PoreMesh::update_channel_geometry`]).
#[inline(always)]
fn channel_lanes<const L: usize>(
    g: &ChannelInputs<'_>,
    t2t: Option<T2tApertureLaw>,
    kind: &[ChannelKind; L],
    cells: &[[u32; 2]; L],
    face: &[u32; L],
    length: &mut [f64; L],
    aperture: &mut [f64; L],
) {
    let mut d = [[0.0; 2]; L];
    for k in 0..L {
        let (p0, p1) = (
            g.centroid[cells[k][0] as usize],
            g.centroid[cells[k][1] as usize],
        );
        d[k] = [p1[0] - p0[0], p1[1] - p0[1]];
    }
    let len: [f64; L] = std::array::from_fn(|k| (d[k][0] * d[k][0] + d[k][1] * d[k][1]).sqrt());
    *length = len;
    let Some(law) = t2t else {
        return;
    };
    // The end points of the T2T lanes' faces (S2S channels have no face).
    for k in 0..L {
        if kind[k] == ChannelKind::T2T {
            let [a, b] = g.face_vertices[face[k] as usize];
            let (pa, pb) = (g.vertices[a as usize], g.vertices[b as usize]);
            aperture[k] = law.aperture(pa, pb, d[k], len[k]);
        }
    }
}

impl PoreMesh {
    /// Builds a mesh from vertices, triangles and cell kinds: orients triangles
    /// counter-clockwise, creates faces (edges) with their two cells, tags boundary faces by
    /// the side of the bounding box they lie on (within `side_tolerance` m), computes all
    /// geometry, and creates a T2T channel for every face shared by two fluid cells with the
    /// aperture of A-Eq. 9 using the reduction factor `t2t_reduction_factor` (γ).
    ///
    /// S2S channels are added separately (they need the contacts).
    pub fn from_triangles(
        vertices: Vec<[f64; 2]>,
        vertex_sphere: Vec<u32>,
        mut triangles: Vec<[u32; 3]>,
        cell_kind: Vec<CellKind>,
        thickness: f64,
        side_tolerance: f64,
        t2t_reduction_factor: f64,
    ) -> Result<Self, TopologyError> {
        let nv = vertices.len();
        if vertex_sphere.len() != nv {
            return Err(TopologyError::LengthMismatch {
                what: "vertex_sphere",
                expected: nv,
                got: vertex_sphere.len(),
            });
        }
        if cell_kind.len() != triangles.len() {
            return Err(TopologyError::LengthMismatch {
                what: "cell_kind",
                expected: triangles.len(),
                got: cell_kind.len(),
            });
        }
        if !(thickness.is_finite() && thickness > 0.0) {
            return Err(TopologyError::OutOfRange {
                name: "thickness",
                range: "> 0 m",
                value: thickness,
            });
        }
        if !(t2t_reduction_factor.is_finite() && t2t_reduction_factor > 0.0) {
            return Err(TopologyError::OutOfRange {
                name: "t2t_reduction_factor",
                range: "> 0",
                value: t2t_reduction_factor,
            });
        }
        for (i, v) in vertices.iter().enumerate() {
            for &x in v {
                if !x.is_finite() {
                    return Err(TopologyError::NonFinite {
                        what: "vertex",
                        index: i,
                        value: x,
                    });
                }
            }
        }
        for (c, t) in triangles.iter_mut().enumerate() {
            for &v in t.iter() {
                if v as usize >= nv {
                    return Err(TopologyError::VertexOutOfRange {
                        cell: c,
                        vertex: v,
                        n_vertices: nv,
                    });
                }
            }
            let a = signed_area(
                vertices[t[0] as usize],
                vertices[t[1] as usize],
                vertices[t[2] as usize],
            );
            if a < 0.0 {
                t.swap(1, 2);
            } else if a <= 0.0 {
                return Err(TopologyError::DegenerateCell { cell: c, area: a });
            }
        }

        // Faces in order of first appearance. Edges are found through a per-vertex list of
        // the edges whose smaller end is that vertex (a few entries each).
        let nc = triangles.len();
        let mut start = vec![0u32; nv + 1];
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                start[a.min(b) as usize + 1] += 1;
            }
        }
        for v in 0..nv {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        // (other end, face) per slot; slots past `fill` are unused.
        let mut slots: Vec<(u32, u32)> = vec![(NONE, NONE); start[nv] as usize];
        let mut face_vertices: Vec<[u32; 2]> = Vec::with_capacity(nc * 3 / 2 + 2);
        let mut face_cells: Vec<[u32; 2]> = Vec::with_capacity(nc * 3 / 2 + 2);
        let mut cell_faces = vec![[NONE; 3]; nc];
        for (c, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (lo, hi) = (a.min(b), a.max(b));
                let (s0, s1) = (start[lo as usize] as usize, fill[lo as usize] as usize);
                let f = match slots[s0..s1].iter().find(|e| e.0 == hi) {
                    Some(&(_, f)) => {
                        let fc = &mut face_cells[f as usize];
                        if fc[1] != NONE {
                            return Err(TopologyError::NonManifoldEdge { a: lo, b: hi });
                        }
                        fc[1] = c as u32;
                        f
                    }
                    None => {
                        let f = face_vertices.len() as u32;
                        slots[s1] = (hi, f);
                        fill[lo as usize] += 1;
                        face_vertices.push([a, b]);
                        face_cells.push([c as u32, NONE]);
                        f
                    }
                };
                cell_faces[c][k] = f;
            }
        }
        let nf = face_vertices.len();
        let mut mesh = PoreMesh {
            thickness,
            vertices,
            vertex_sphere,
            cell_vertices: triangles,
            cell_kind,
            cell_area: vec![0.0; nc],
            cell_centroid: vec![[0.0; 2]; nc],
            cell_faces,
            face_vertices,
            face_cells,
            face_length: vec![0.0; nf],
            face_normal: vec![[0.0; 2]; nf],
            face_centroid: vec![[0.0; 2]; nf],
            face_kind: vec![FaceKind::Interior; nf],
            channels: Channels::default(),
        };
        mesh.update_geometry();
        mesh.tag_boundary_sides(side_tolerance);
        mesh.build_t2t_channels(t2t_reduction_factor);
        Ok(mesh)
    }

    /// A structured triangulation of the rectangle `[0, lx] × [0, ly]` with `nx × ny` squares,
    /// each split into two triangles along alternating diagonals; `kind(centroid)` sets each
    /// cell's kind. Useful for verification of the flow and heat solvers.
    #[allow(clippy::too_many_arguments)]
    pub fn structured_rectangle(
        nx: usize,
        ny: usize,
        lx: f64,
        ly: f64,
        thickness: f64,
        t2t_reduction_factor: f64,
        kind: impl Fn([f64; 2]) -> CellKind,
    ) -> Result<Self, TopologyError> {
        if nx == 0 || ny == 0 {
            return Err(TopologyError::OutOfRange {
                name: "nx, ny",
                range: ">= 1",
                value: nx.min(ny) as f64,
            });
        }
        for (name, v) in [("lx", lx), ("ly", ly)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(TopologyError::OutOfRange {
                    name,
                    range: "> 0 m",
                    value: v,
                });
            }
        }
        let mut vertices = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                vertices.push([lx * i as f64 / nx as f64, ly * j as f64 / ny as f64]);
            }
        }
        let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let mut tris = Vec::with_capacity(2 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if (i + j) % 2 == 0 {
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                } else {
                    tris.push([a, b, d]);
                    tris.push([b, c, d]);
                }
            }
        }
        let kinds = tris
            .iter()
            .map(|t| {
                let p = t.map(|v| vertices[v as usize]);
                kind([
                    (p[0][0] + p[1][0] + p[2][0]) / 3.0,
                    (p[0][1] + p[1][1] + p[2][1]) / 3.0,
                ])
            })
            .collect();
        let nvert = vertices.len();
        let tol = 1e-9 * lx.max(ly);
        Self::from_triangles(
            vertices,
            vec![NONE; nvert],
            tris,
            kinds,
            thickness,
            tol,
            t2t_reduction_factor,
        )
    }

    /// Number of cells.
    pub fn n_cells(&self) -> usize {
        self.cell_vertices.len()
    }

    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.face_vertices.len()
    }

    /// Cell volume `area × thickness` \[m³\].
    pub fn cell_volume(&self, cell: usize) -> f64 {
        self.cell_area[cell] * self.thickness
    }

    /// Total area of the fluid cells \[m²\].
    pub fn fluid_area(&self) -> f64 {
        self.cell_area
            .iter()
            .zip(&self.cell_kind)
            .filter(|(_, k)| k.is_fluid())
            .map(|(a, _)| a)
            .sum()
    }

    /// Total area of the solid cells \[m²\].
    pub fn solid_area(&self) -> f64 {
        self.cell_area
            .iter()
            .zip(&self.cell_kind)
            .filter(|(_, k)| !k.is_fluid())
            .map(|(a, _)| a)
            .sum()
    }

    /// Recomputes cell areas and centroids, face lengths, normals and mid-points, and channel
    /// lengths from the current vertex positions (after the vertices moved; topology
    /// unchanged). T2T apertures are refreshed by [`Self::update_t2t_apertures`].
    pub fn update_geometry(&mut self) {
        self.update_cell_geometry();
        self.update_face_geometry();
        self.update_channel_geometry(None);
    }

    /// Stage "cells": area and centroid of every cell, one pass over the triangles.
    pub fn update_cell_geometry(&mut self) {
        let vx = &self.vertices;
        for ((t, area), centroid) in self
            .cell_vertices
            .iter()
            .zip(&mut self.cell_area)
            .zip(&mut self.cell_centroid)
        {
            let [pa, pb, pc] = t.map(|v| vx[v as usize]);
            *area = signed_area(pa, pb, pc);
            *centroid = [
                (pa[0] + pb[0] + pc[0]) * THIRD,
                (pa[1] + pb[1] + pc[1]) * THIRD,
            ];
        }
    }

    /// Stage "cells" with the area rate: area, centroid and `dA/dt · rate_scale` of every
    /// cell from the vertex velocities `vel`, in one pass (`dA/dt` is the exact derivative of
    /// the triangle area, see [`crate::motion`]). `vel` has one entry per vertex and `rate`
    /// one per cell (checked by the caller).
    pub(crate) fn update_cell_geometry_and_rate(
        &mut self,
        vel: &[[f64; 2]],
        rate_scale: f64,
        rate: &mut [f64],
    ) {
        let vx = &self.vertices;
        for (((t, area), centroid), rate) in self
            .cell_vertices
            .iter()
            .zip(&mut self.cell_area)
            .zip(&mut self.cell_centroid)
            .zip(rate.iter_mut())
        {
            let [a, b, c] = t.map(|v| v as usize);
            let (pa, pb, pc) = (vx[a], vx[b], vx[c]);
            let (ua, ub, uc) = (vel[a], vel[b], vel[c]);
            *area = signed_area(pa, pb, pc);
            *centroid = [
                (pa[0] + pb[0] + pc[0]) * THIRD,
                (pa[1] + pb[1] + pc[1]) * THIRD,
            ];
            let e1 = [pb[0] - pa[0], pb[1] - pa[1]];
            let e2 = [pc[0] - pa[0], pc[1] - pa[1]];
            let d1 = [ub[0] - ua[0], ub[1] - ua[1]];
            let d2 = [uc[0] - ua[0], uc[1] - ua[1]];
            *rate = rate_scale
                * (0.5 * ((d1[0] * e2[1] - d1[1] * e2[0]) + (e1[0] * d2[1] - e1[1] * d2[0])));
        }
    }

    /// Stage "faces": length, unit normal and mid-point of every face, one pass.
    ///
    /// Faces go `LANES` at a time through the same arithmetic, so the square roots run as
    /// one packed instruction per pair (the compiler keeps the divisions scalar; square roots
    /// and divisions share the divider that bounds this stage); every face's result is the
    /// same bits as computed alone.
    pub fn update_face_geometry(&mut self) {
        let vx = &self.vertices;
        let n = self
            .face_vertices
            .len()
            .min(self.face_length.len())
            .min(self.face_normal.len())
            .min(self.face_centroid.len());
        let (fv, fv_tail) = self.face_vertices[..n].as_chunks::<LANES>();
        let (length, len_tail) = self.face_length[..n].as_chunks_mut::<LANES>();
        let (normal, nrm_tail) = self.face_normal[..n].as_chunks_mut::<LANES>();
        let (centroid, cen_tail) = self.face_centroid[..n].as_chunks_mut::<LANES>();
        for (((f, l), nn), c) in fv.iter().zip(length).zip(normal).zip(centroid) {
            face_lanes(vx, f, l, nn, c);
        }
        let tail = fv_tail.iter().zip(len_tail).zip(nrm_tail).zip(cen_tail);
        for (((f, l), nn), c) in tail {
            face_lanes::<1>(
                vx,
                std::array::from_ref(f),
                std::array::from_mut(l),
                std::array::from_mut(nn),
                std::array::from_mut(c),
            );
        }
    }

    /// Stage "channels": the length of every channel (distance between the two cell
    /// centroids) and, with `Some(law)`, the T2T apertures of A-Eq. 9 (and the law's narrow-gap
    /// floor), one pass (after the cell stage). The aperture is taken from the face's end
    /// points ([`T2tApertureLaw::aperture`]), not from
    /// its normal and length, so the pass reads the small vertex array instead of two large
    /// per-face ones.
    pub fn update_channel_geometry(&mut self, t2t: Option<T2tApertureLaw>) {
        let ch = &mut self.channels;
        let geometry = ChannelInputs {
            centroid: &self.cell_centroid,
            face_vertices: &self.face_vertices,
            vertices: &self.vertices,
        };
        let n = ch
            .kind
            .len()
            .min(ch.cells.len())
            .min(ch.face.len())
            .min(ch.length.len())
            .min(ch.aperture.len());
        let (kind, kind_tail) = ch.kind[..n].as_chunks::<LANES>();
        let (cells, cells_tail) = ch.cells[..n].as_chunks::<LANES>();
        let (face, face_tail) = ch.face[..n].as_chunks::<LANES>();
        let (length, length_tail) = ch.length[..n].as_chunks_mut::<LANES>();
        let (aperture, aperture_tail) = ch.aperture[..n].as_chunks_mut::<LANES>();
        let groups = kind.iter().zip(cells).zip(face).zip(length).zip(aperture);
        for ((((k, c), f), l), h) in groups {
            channel_lanes(&geometry, t2t, k, c, f, l, h);
        }
        let tail = kind_tail
            .iter()
            .zip(cells_tail)
            .zip(face_tail)
            .zip(length_tail)
            .zip(aperture_tail);
        for ((((k, c), f), l), h) in tail {
            channel_lanes::<1>(
                &geometry,
                t2t,
                std::array::from_ref(k),
                std::array::from_ref(c),
                std::array::from_ref(f),
                std::array::from_mut(l),
                std::array::from_mut(h),
            );
        }
    }

    fn tag_boundary_sides(&mut self, tol: f64) {
        if self.vertices.is_empty() {
            return;
        }
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for v in &self.vertices {
            x0 = x0.min(v[0]);
            x1 = x1.max(v[0]);
            y0 = y0.min(v[1]);
            y1 = y1.max(v[1]);
        }
        for f in 0..self.face_vertices.len() {
            if self.face_cells[f][1] != NONE {
                continue;
            }
            let [a, b] = self.face_vertices[f];
            let (pa, pb) = (self.vertices[a as usize], self.vertices[b as usize]);
            let on = |u: f64, v: f64, s: f64| (u - s).abs() <= tol && (v - s).abs() <= tol;
            let side = if on(pa[0], pb[0], x0) {
                BoundarySide::Left
            } else if on(pa[0], pb[0], x1) {
                BoundarySide::Right
            } else if on(pa[1], pb[1], y0) {
                BoundarySide::Bottom
            } else if on(pa[1], pb[1], y1) {
                BoundarySide::Top
            } else {
                BoundarySide::Outline
            };
            self.face_kind[f] = FaceKind::Boundary(side);
        }
    }

    /// Recomputes the aperture (A-Eq. 9, `law` a γ or a [`T2tApertureLaw`]) of every existing
    /// T2T channel (and every channel length) from the current geometry, in place (channel
    /// order and indices unchanged; call after [`Self::update_geometry`]).
    pub fn update_t2t_apertures(&mut self, law: impl Into<T2tApertureLaw>) {
        self.update_channel_geometry(Some(law.into()));
    }

    /// Rebuilds all T2T channels (dropping existing ones of that kind) with aperture
    /// `h = γ · e · cos(90° − ω)` (A-Eq. 9), where `e` is the shared edge length and `ω` the
    /// angle between the edge and the line joining the two centroids (`law` a γ or a
    /// [`T2tApertureLaw`] with its narrow-gap floor).
    pub fn build_t2t_channels(&mut self, law: impl Into<T2tApertureLaw>) {
        let law = law.into();
        let keep: Vec<usize> = (0..self.channels.len())
            .filter(|&i| self.channels.kind[i] != ChannelKind::T2T)
            .collect();
        let old = std::mem::take(&mut self.channels);
        for i in keep {
            self.channels.kind.push(old.kind[i]);
            self.channels.cells.push(old.cells[i]);
            self.channels.length.push(old.length[i]);
            self.channels.aperture.push(old.aperture[i]);
            self.channels.face.push(old.face[i]);
            self.channels.contact.push(old.contact[i]);
        }
        for f in 0..self.face_vertices.len() {
            let [c0, c1] = self.face_cells[f];
            if c1 == NONE
                || !self.cell_kind[c0 as usize].is_fluid()
                || !self.cell_kind[c1 as usize].is_fluid()
            {
                continue;
            }
            let (p0, p1) = (
                self.cell_centroid[c0 as usize],
                self.cell_centroid[c1 as usize],
            );
            let d = [p1[0] - p0[0], p1[1] - p0[1]];
            let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let [a, b] = self.face_vertices[f];
            let (pa, pb) = (self.vertices[a as usize], self.vertices[b as usize]);
            self.channels.kind.push(ChannelKind::T2T);
            self.channels.cells.push([c0, c1]);
            self.channels.length.push(length);
            self.channels.aperture.push(law.aperture(pa, pb, d, length));
            self.channels.face.push(f as u32);
            self.channels.contact.push(NONE);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn structured_rectangle_areas_and_faces() {
        let m =
            PoreMesh::structured_rectangle(4, 3, 2.0, 1.5, 0.1, 1.0, |_| CellKind::Fluid).unwrap();
        assert_eq!(m.n_cells(), 24);
        // Euler: F = E - V + 1 (for a disk) -> E = V + F - 1.
        assert_eq!(m.n_faces(), 20 + 24 - 1);
        assert!((m.fluid_area() - 3.0).abs() < 1e-14);
        let n_boundary = m
            .face_kind
            .iter()
            .filter(|k| matches!(k, FaceKind::Boundary(_)))
            .count();
        assert_eq!(n_boundary, 2 * (4 + 3));
        // Sum over each cell of outward normal × length vanishes (closed polygon).
        for c in 0..m.n_cells() {
            let mut s = [0.0; 2];
            for &f in &m.cell_faces[c] {
                let sign = if m.face_cells[f as usize][0] == c as u32 {
                    1.0
                } else {
                    -1.0
                };
                for (sk, nk) in s.iter_mut().zip(m.face_normal[f as usize]) {
                    *sk += sign * nk * m.face_length[f as usize];
                }
            }
            assert!(s[0].abs() < 1e-14 && s[1].abs() < 1e-14);
        }
        // Every interior face joins two fluid cells: one T2T channel each.
        assert_eq!(m.channels.len(), m.n_faces() - n_boundary);
    }

    /// The T2T aperture from the cross product equals A-Eq. 9 written with the unit normal,
    /// `γ · e · |n · d| / |d|`, to round-off, on a skewed mesh.
    #[test]
    fn t2t_aperture_is_eq_9() {
        let mut m =
            PoreMesh::structured_rectangle(5, 4, 1.0, 0.8, 1.0, 0.7, |_| CellKind::Fluid).unwrap();
        for (v, p) in m.vertices.iter_mut().enumerate() {
            let s = (v as f64 * 0.37).sin();
            *p = [p[0] + 0.3 * p[1] * p[1] + 0.01 * s, p[1] + 0.05 * p[0] * s];
        }
        m.update_geometry();
        m.update_t2t_apertures(0.7);
        let mut checked = 0;
        for c in 0..m.channels.len() {
            let f = m.channels.face[c] as usize;
            let [c0, c1] = m.channels.cells[c].map(|i| m.cell_centroid[i as usize]);
            let d = [c1[0] - c0[0], c1[1] - c0[1]];
            let n = m.face_normal[f];
            let expect = 0.7 * m.face_length[f] * (n[0] * d[0] + n[1] * d[1]).abs()
                / (d[0] * d[0] + d[1] * d[1]).sqrt();
            let got = m.channels.aperture[c];
            assert!(
                (got - expect).abs() <= 1e-15 * expect,
                "channel {c}: {got} vs {expect}"
            );
            checked += 1;
        }
        assert!(checked > 20);
    }

    #[test]
    fn outward_normals_point_away_from_first_cell() {
        let m =
            PoreMesh::structured_rectangle(2, 2, 1.0, 1.0, 1.0, 1.0, |_| CellKind::Fluid).unwrap();
        for f in 0..m.n_faces() {
            let c = m.face_cells[f][0] as usize;
            let d = [
                m.face_centroid[f][0] - m.cell_centroid[c][0],
                m.face_centroid[f][1] - m.cell_centroid[c][1],
            ];
            assert!(d[0] * m.face_normal[f][0] + d[1] * m.face_normal[f][1] > 0.0);
        }
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let e = PoreMesh::from_triangles(
            vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
            vec![NONE; 3],
            vec![[0, 1, 2]],
            vec![CellKind::Fluid],
            1.0,
            1e-9,
            1.0,
        )
        .unwrap_err();
        assert!(matches!(e, TopologyError::DegenerateCell { cell: 0, .. }));
        let e = PoreMesh::from_triangles(
            vec![[0.0, 0.0]],
            vec![NONE],
            vec![[0, 1, 2]],
            vec![CellKind::Fluid],
            1.0,
            1e-9,
            1.0,
        )
        .unwrap_err();
        assert!(matches!(e, TopologyError::VertexOutOfRange { .. }));
        // Three triangles on one edge.
        let e = PoreMesh::from_triangles(
            vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [0.5, -1.0], [0.5, 2.0]],
            vec![NONE; 5],
            vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
            vec![CellKind::Fluid; 3],
            1.0,
            1e-9,
            1.0,
        )
        .unwrap_err();
        assert_eq!(e, TopologyError::NonManifoldEdge { a: 0, b: 1 });
    }
}
