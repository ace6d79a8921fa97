//! Mesh-derived coefficients of the heat step, kept by the caller between steps.
//!
//! [`HeatGeometry`] holds everything the step needs that depends on the mesh and not on the
//! material properties or the flow: in two layers.
//!
//! - **Topology** (cell kinds, faces, channels, and from the model which boundary sides
//!   carry a prescribed flux and whether fluid–solid faces are case IV interfaces or
//!   conduct like faces inside one medium, [`crate::InterfaceModel`]): the class of every
//!   face (same medium, fluid–solid interface, boundary slot), the lists of interface faces
//!   and of faces whose temperature is a stencil value, per-cell flags (medium, has an
//!   interface face, first cell of each of its faces), the boundary-face table, the
//!   least-squares stencil sources, the cell → channel adjacency (CSR), the channel
//!   partners the limiter bounds need beyond the stencil, and the sphere owners. Built by [`HeatGeometry::new`] once per mesh (and again
//!   after every remesh).
//! - **Positions** (vertex coordinates, hence centroids, areas, normals): the A-Eq. 47 factors
//!   |A| / (ds n·e_s) and A − e_s |A| / (n·e_s) of every face, the distances of the harmonic
//!   face conductivity, boundary normal distances and tangential offsets, the interface
//!   distances d_{r,c}, the least-squares gradient weights and reconstruction offsets, the
//!   channel face points, the sphere radii and the porosity. Recomputed by
//!   [`HeatGeometry::update_positions`] in one parallel pass without allocation when the
//!   vertices have moved but the topology has not.
//!
//! What depends on the properties and the flow (conductivities, capacities, h_f of A-Eq. 45,
//! the stability limit) is recomputed every outer step by [`crate::HeatStepper::prepare`] and
//! [`crate::HeatStepper::stability_limit`].

use rayon::prelude::*;
use thm_vpn_mesh::{CellKind, ChannelKind, FaceKind, NONE, PoreMesh};

use crate::HeatError;
use crate::params::{HeatModel, InterfaceModel, SideCondition, side_index};
use crate::properties::DiameterPowers;

/// Smallest admissible cosine between a face normal and the centroid link (A-Eq. 47).
pub const MIN_FACE_COSINE: f64 = 1e-3;

/// Rayon granularity: items per task.
pub(crate) const GRAIN: usize = 2048;

/// The first index `i < n` with `bad(i)`, found in parallel chunks of [`GRAIN`] scanned
/// serially and combined in index order (the same answer as a serial scan, for any number of
/// threads, without a shared atomic per item).
pub(crate) fn first_where(n: usize, bad: impl Fn(usize) -> bool + Sync) -> Option<usize> {
    (0..n.div_ceil(GRAIN))
        .into_par_iter()
        .map(|k| {
            let lo = k * GRAIN;
            (lo..(lo + GRAIN).min(n)).find(|&i| bad(i))
        })
        .reduce(|| None, |a, b| a.or(b))
}

/// Cell flag: a fluid cell.
pub(crate) const CELL_FLUID: u8 = 1;
/// Cell flag: a fluid cell with a case IV interface face.
pub(crate) const CELL_INTERFACE: u8 = 2;
/// Cell flag (shifted left by the face's position k): the cell is the face's first cell.
pub(crate) const CELL_FIRST: u8 = 4;

/// Marks a stencil source as a face temperature (the low bits are the index into
/// [`HeatGeometry::value_faces`]).
pub(crate) const FACE_VALUE: u32 = 1 << 31;

#[inline]
pub(crate) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[inline]
pub(crate) fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// Property-free part of a face's law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FaceGeometry {
    /// Two cells of the same medium: A-Eq. 47 with λ_f factored out. `conductance` =
    /// |A| / (ds n·e_s) \[m\], `cross` = A − e_s |A| / (n·e_s) \[m²\], and `weight0` =
    /// d0 / (d0 + d1), the share of cell 0 in the link, with d0, d1 the distances of the two
    /// centroids to the face along e_s (harmonic face conductivity; d0 + d1 ≥ ds > 0).
    Diffusive {
        conductance: f64,
        cross: [f64; 2],
        weight0: f64,
    },
    /// Fluid–solid interface (case IV): the position of its record in
    /// [`HeatGeometry::interface`] and of its per-step law.
    Interface { index: u32 },
    /// Outer boundary: index into [`HeatGeometry::boundary`].
    Boundary { slot: u32 },
}

/// One fluid–solid interface face (case IV): what the per-step law needs, packed in one
/// 32-byte record per face, in face order.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct InterfaceFace {
    /// The face.
    pub face: u32,
    /// |A| \[m²\].
    pub area: f64,
    /// Conductance λ_s |A| / d_{r,c} of the solid half cell \[W/K\] (d_{r,c} the solid cell's
    /// centroid-to-face-centroid distance; 0 where it vanishes).
    pub solid_conductance: f64,
    /// The fluid cell.
    pub fluid_cell: u32,
    /// The sphere owning the solid cell.
    pub owner: u32,
    /// Whether the fluid cell is cell 0 of the face.
    pub fluid_first: bool,
}

// The per-face records the step streams through stay this small.
const _: () = assert!(std::mem::size_of::<FaceGeometry>() == 40);
const _: () = assert!(std::mem::size_of::<InterfaceFace>() == 32);

/// One outer boundary face (cases I–III).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BoundaryFace {
    /// Index into `HeatModel::sides`.
    pub side: u8,
    /// Normal distance of the cell centroid to the face \[m\].
    pub normal_distance: f64,
    /// |A| \[m²\].
    pub area: f64,
    /// Part of centroid → face centroid parallel to the face \[m\] (non-orthogonal correction).
    pub tangent: [f64; 2],
}

/// The mesh-derived coefficients of the heat step for one mesh topology (see the module
/// docs). Build with [`HeatGeometry::new`]; after the vertices move (same topology) call
/// [`HeatGeometry::update_positions`]; after a remesh build a new one.
#[derive(Debug, Clone, Default)]
pub struct HeatGeometry {
    n_cells: usize,
    // Interior faces whose centroid link is nearly parallel to the face (minimum correction).
    sliver_faces: usize,
    // Per cell: factor on ρ_s c_s V of a solid cell (empty: 1 everywhere).
    pub(crate) solid_capacity_scale: Vec<f64>,
    n_faces: usize,
    n_channels: usize,
    pub(crate) face: Vec<FaceGeometry>,
    pub(crate) boundary: Vec<BoundaryFace>,
    // Faces of class `Interface`, in face order (their per-step law is stored in this order).
    pub(crate) interface: Vec<InterfaceFace>,
    // Faces whose temperature is a stencil value (interfaces and boundaries), in face order.
    pub(crate) value_faces: Vec<u32>,
    // Per cell: fluid (bit 0), fluid with a case IV interface face (bit 1, needs the h_f
    // factors), and bit 2 + k set where the cell is the first cell of its face k.
    pub(crate) cell_flags: Vec<u8>,
    // Per cell, per face k: where the neighbour value comes from (a cell index, or
    // `FACE_VALUE | v` for the temperature of `value_faces[v]`), its least-squares gradient
    // weight, and the offset face centroid − cell centroid.
    pub(crate) stencil_source: Vec<[u32; 3]>,
    pub(crate) stencil_weight: Vec<[[f64; 2]; 3]>,
    pub(crate) stencil_offset: Vec<[[f64; 2]; 3]>,
    // Per sphere.
    pub(crate) sphere_radius: Vec<f64>,
    pub(crate) sphere_diameter_powers: Vec<DiameterPowers>,
    pub(crate) porosity: f64,
    // Cell → channels (CSR): channel index and whether the cell is the channel's second cell,
    // and the cell at the other end.
    pub(crate) cell_channel_start: Vec<u32>,
    pub(crate) cell_channel: Vec<(u32, bool)>,
    pub(crate) cell_channel_partner: Vec<u32>,
    // Cell → channel partners that are not already one of the cell's stencil cells (CSR):
    // the extra values of the limiter's neighbourhood bounds (the S2S partners).
    pub(crate) extra_partner_start: Vec<u32>,
    pub(crate) extra_partner: Vec<u32>,
    // Per channel: where the advected value is reconstructed (T2T: the shared face centroid).
    pub(crate) channel_point: Vec<[f64; 2]>,
}

impl HeatGeometry {
    /// Topology and positions of `mesh` for `model` (the model's boundary kinds decide which
    /// boundary faces are Neumann rows of the least-squares gradient).
    pub fn new(model: &HeatModel, mesh: &PoreMesh) -> Result<Self, HeatError> {
        let mut g = Self::default();
        g.build_topology(model, mesh)?;
        g.update_positions(model, mesh)?;
        Ok(g)
    }

    /// Number of cells, faces and channels of the mesh this geometry was built for.
    pub fn sizes(&self) -> [usize; 3] {
        [self.n_cells, self.n_faces, self.n_channels]
    }

    /// Interior faces whose centroid link is nearly parallel to the face (cos ≤
    /// [`MIN_FACE_COSINE`], sliver triangles between nearly touching circles): their
    /// conduction uses the minimum-correction two-point flux `λ A cos / |d|` without the
    /// cross term of A-Eq. 47.
    pub fn sliver_faces(&self) -> usize {
        self.sliver_faces
    }

    /// Scales the heat capacity `ρ_s c_s V` of every solid cell by `per_sphere[owner]`, e.g.
    /// so that a sphere whose cross-section shrank with its temperature (A-Eq. 55) keeps the
    /// heat capacity of its unchanged mass. Errors when a cell's owner has no entry or a
    /// factor is not finite and positive. [`HeatGeometry::new`] starts with 1 everywhere.
    pub fn set_solid_capacity_scale(
        &mut self,
        mesh: &PoreMesh,
        per_sphere: &[f64],
    ) -> Result<(), HeatError> {
        if let Some((k, &f)) = per_sphere
            .iter()
            .enumerate()
            .find(|(_, f)| !(f.is_finite() && **f > 0.0))
        {
            return Err(HeatError::InputOutOfRange {
                quantity: "solid capacity scale of sphere",
                index: k,
                range: "finite and > 0",
                value: f,
            });
        }
        self.solid_capacity_scale.clear();
        for (c, kind) in mesh.cell_kind.iter().enumerate() {
            let f = match *kind {
                CellKind::Solid { owner } => {
                    *per_sphere
                        .get(owner as usize)
                        .ok_or(HeatError::InputOutOfRange {
                            quantity: "solid capacity scale: owner of cell",
                            index: c,
                            range: "an owner below the number of factors",
                            value: f64::from(owner),
                        })?
                }
                CellKind::Fluid => 1.0,
            };
            self.solid_capacity_scale.push(f);
        }
        Ok(())
    }

    /// Mesh porosity: fluid area / total area.
    pub fn porosity(&self) -> f64 {
        self.porosity
    }

    /// Radius of the circle with the area of each sphere's solid cells \[m\].
    pub fn sphere_radius(&self) -> &[f64] {
        &self.sphere_radius
    }

    /// Checks that `mesh` has the sizes this geometry was built for.
    pub(crate) fn check(&self, mesh: &PoreMesh) -> Result<(), HeatError> {
        for (what, expected, got) in [
            (
                "geometry cells (mesh changed: rebuild HeatGeometry)",
                self.n_cells,
                mesh.n_cells(),
            ),
            (
                "geometry faces (mesh changed: rebuild HeatGeometry)",
                self.n_faces,
                mesh.n_faces(),
            ),
            (
                "geometry channels (mesh changed: rebuild HeatGeometry)",
                self.n_channels,
                mesh.channels.len(),
            ),
        ] {
            if expected != got {
                return Err(HeatError::LengthMismatch {
                    what,
                    expected,
                    got,
                });
            }
        }
        Ok(())
    }

    /// Topology: face classes, boundary table, stencil sources, channel adjacency, sphere
    /// count. Sizes every position-dependent buffer.
    fn build_topology(&mut self, model: &HeatModel, mesh: &PoreMesh) -> Result<(), HeatError> {
        let (n, nf, nch) = (mesh.n_cells(), mesh.n_faces(), mesh.channels.len());
        self.n_cells = n;
        self.n_faces = nf;
        self.n_channels = nch;
        for (what, len, expected) in [
            ("cell_kind", mesh.cell_kind.len(), n),
            ("cell_area", mesh.cell_area.len(), n),
            ("cell_centroid", mesh.cell_centroid.len(), n),
            ("cell_faces", mesh.cell_faces.len(), n),
            ("face_cells", mesh.face_cells.len(), nf),
            ("face_length", mesh.face_length.len(), nf),
            ("face_normal", mesh.face_normal.len(), nf),
            ("face_centroid", mesh.face_centroid.len(), nf),
            ("face_kind", mesh.face_kind.len(), nf),
        ] {
            if len != expected {
                return Err(HeatError::LengthMismatch {
                    what,
                    expected,
                    got: len,
                });
            }
        }
        // Faces: class, and a slot per boundary face in face order.
        self.face.clear();
        self.boundary.clear();
        self.interface.clear();
        self.value_faces.clear();
        let continuous = model.interface == InterfaceModel::Continuous;
        // Position of each face in `value_faces` (NONE for faces inside a medium).
        let mut value_index = vec![NONE; nf];
        for (f, vi) in value_index.iter_mut().enumerate() {
            let [c0, c1] = mesh.face_cells[f];
            if c1 == NONE {
                let side = match mesh.face_kind[f] {
                    FaceKind::Boundary(s) => side_index(s) as u8,
                    FaceKind::Interior => side_index(thm_vpn_mesh::BoundarySide::Outline) as u8,
                };
                self.face.push(FaceGeometry::Boundary {
                    slot: self.boundary.len() as u32,
                });
                self.boundary.push(BoundaryFace {
                    side,
                    normal_distance: 0.0,
                    area: 0.0,
                    tangent: [0.0; 2],
                });
                *vi = self.value_faces.len() as u32;
                self.value_faces.push(f as u32);
                continue;
            }
            let (k0, k1) = (mesh.cell_kind[c0 as usize], mesh.cell_kind[c1 as usize]);
            if continuous || k0.is_fluid() == k1.is_fluid() {
                self.face.push(FaceGeometry::Diffusive {
                    conductance: 0.0,
                    cross: [0.0; 2],
                    weight0: 0.0,
                });
            } else {
                let solid = if k0.is_fluid() { k1 } else { k0 };
                let owner = match solid {
                    CellKind::Solid { owner } => owner,
                    CellKind::Fluid => 0,
                };
                self.face.push(FaceGeometry::Interface {
                    index: self.interface.len() as u32,
                });
                self.interface.push(InterfaceFace {
                    face: f as u32,
                    fluid_cell: if k0.is_fluid() { c0 } else { c1 },
                    owner,
                    fluid_first: k0.is_fluid(),
                    ..InterfaceFace::default()
                });
                *vi = self.value_faces.len() as u32;
                self.value_faces.push(f as u32);
            }
        }
        // Stencil sources: the neighbour cell in the same medium, else the face value.
        self.stencil_source.clear();
        self.stencil_source.extend((0..n).map(|c| {
            mesh.cell_faces[c].map(|f| match self.face[f as usize] {
                FaceGeometry::Diffusive { .. } => {
                    let [c0, c1] = mesh.face_cells[f as usize];
                    if c0 == c as u32 { c1 } else { c0 }
                }
                _ => FACE_VALUE | value_index[f as usize],
            })
        }));
        // Cell flags: medium, interface, and the side of each face.
        self.cell_flags.clear();
        self.cell_flags.extend((0..n).map(|c| {
            let mut flags = 0u8;
            if mesh.cell_kind[c].is_fluid() {
                flags |= CELL_FLUID;
                if mesh.cell_faces[c]
                    .iter()
                    .any(|&f| matches!(self.face[f as usize], FaceGeometry::Interface { .. }))
                {
                    flags |= CELL_INTERFACE;
                }
            }
            for (k, &f) in mesh.cell_faces[c].iter().enumerate() {
                if mesh.face_cells[f as usize][0] == c as u32 {
                    flags |= CELL_FIRST << k;
                }
            }
            flags
        }));
        self.stencil_weight.clear();
        self.stencil_weight.resize(n, [[0.0; 2]; 3]);
        self.stencil_offset.clear();
        self.stencil_offset.resize(n, [[0.0; 2]; 3]);
        // Spheres.
        let n_spheres = crate::spheres::sphere_count(mesh);
        self.sphere_radius.clear();
        self.sphere_radius.resize(n_spheres, 0.0);
        self.sphere_diameter_powers.clear();
        self.sphere_diameter_powers
            .resize(n_spheres, DiameterPowers::default());
        // Channels: cell → channel CSR, filled in channel order (each list sorted).
        let ch = &mesh.channels;
        for (what, len) in [
            ("channels.cells", ch.cells.len()),
            ("channels.face", ch.face.len()),
            ("channels.length", ch.length.len()),
            ("channels.aperture", ch.aperture.len()),
        ] {
            if len != nch {
                return Err(HeatError::LengthMismatch {
                    what,
                    expected: nch,
                    got: len,
                });
            }
        }
        self.cell_channel_start.clear();
        self.cell_channel_start.resize(n + 1, 0);
        for cells in &ch.cells {
            for &c in cells {
                if c as usize >= n {
                    return Err(HeatError::InputOutOfRange {
                        quantity: "channels.cells",
                        index: c as usize,
                        range: "a cell index of the mesh",
                        value: f64::from(c),
                    });
                }
                self.cell_channel_start[c as usize + 1] += 1;
            }
        }
        for c in 0..n {
            self.cell_channel_start[c + 1] += self.cell_channel_start[c];
        }
        let total = self.cell_channel_start[n] as usize;
        self.cell_channel.clear();
        self.cell_channel.resize(total, (NONE, false));
        self.cell_channel_partner.clear();
        self.cell_channel_partner.resize(total, NONE);
        let mut next = self.cell_channel_start[..n].to_vec();
        for (k, cells) in ch.cells.iter().enumerate() {
            for (side, &c) in cells.iter().enumerate() {
                let slot = &mut next[c as usize];
                self.cell_channel[*slot as usize] = (k as u32, side == 1);
                self.cell_channel_partner[*slot as usize] = cells[1 - side];
                *slot += 1;
            }
        }
        // Limiter bounds: channel partners that are not already a stencil cell.
        self.extra_partner_start.clear();
        self.extra_partner.clear();
        self.extra_partner_start.push(0);
        for c in 0..n {
            let (lo, hi) = (
                self.cell_channel_start[c] as usize,
                self.cell_channel_start[c + 1] as usize,
            );
            for &other in &self.cell_channel_partner[lo..hi] {
                if !self.stencil_source[c].contains(&other) {
                    self.extra_partner.push(other);
                }
            }
            self.extra_partner_start
                .push(self.extra_partner.len() as u32);
        }
        self.channel_point.clear();
        self.channel_point.resize(nch, [0.0; 2]);
        Ok(())
    }

    /// Recomputes every position-dependent coefficient from the current vertex positions of
    /// `mesh` (same topology as at [`Self::new`]): one parallel pass over faces, one over
    /// cells, one over channels; no allocation. Faces whose normal and centroid link are
    /// (nearly) perpendicular are a typed error.
    pub fn update_positions(
        &mut self,
        model: &HeatModel,
        mesh: &PoreMesh,
    ) -> Result<(), HeatError> {
        self.check(mesh)?;
        self.update_faces(model, mesh)?;
        self.update_stencils(model, mesh);
        self.update_channels(mesh);
        self.update_spheres(mesh);
        Ok(())
    }

    fn update_faces(&mut self, model: &HeatModel, mesh: &PoreMesh) -> Result<(), HeatError> {
        let b = mesh.thickness;
        let solid_lambda = model.solid.conductivity;
        // Boundary faces (few; in slot order).
        let mut slot = 0usize;
        for f in 0..mesh.n_faces() {
            let [c0, c1] = mesh.face_cells[f];
            if c1 != NONE {
                continue;
            }
            let n = mesh.face_normal[f];
            let r = sub(mesh.face_centroid[f], mesh.cell_centroid[c0 as usize]);
            let dn = dot(r, n);
            let bf = &mut self.boundary[slot];
            bf.normal_distance = dn;
            bf.area = mesh.face_length[f] * b;
            bf.tangent = [r[0] - dn * n[0], r[1] - dn * n[1]];
            slot += 1;
        }
        // Interior faces. A link nearly parallel to its face (a sliver triangle, cos ≤
        // MIN_FACE_COSINE) falls back to the minimum-correction two-point flux λ A cos/|d|
        // with no cross term: bounded, conservative and monotone, and counted; a non-finite
        // link is an error reported at the lowest face index.
        let (worst, degenerate) = self
            .face
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .map(|(f, geo)| {
                let [c0, c1] = mesh.face_cells[f];
                if c1 == NONE {
                    return (None, 0usize);
                }
                let (c0, c1) = (c0 as usize, c1 as usize);
                let n = mesh.face_normal[f];
                let area = mesh.face_length[f] * b;
                let xf = mesh.face_centroid[f];
                let (x0, x1) = (mesh.cell_centroid[c0], mesh.cell_centroid[c1]);
                let d = sub(x1, x0);
                let ds = dot(d, d).sqrt();
                let cos = if ds > 0.0 { dot(n, d) / ds } else { f64::NAN };
                if !cos.is_finite() {
                    return (Some((f, cos)), 0);
                }
                let sliver = cos <= MIN_FACE_COSINE;
                match geo {
                    FaceGeometry::Diffusive {
                        conductance,
                        cross,
                        weight0,
                    } => {
                        let es = [d[0] / ds, d[1] / ds];
                        if sliver {
                            *conductance = area * cos.max(0.0) / ds;
                            *cross = [0.0, 0.0];
                        } else {
                            *conductance = area / (ds * cos);
                            *cross = [
                                area * n[0] - es[0] * area / cos,
                                area * n[1] - es[1] * area / cos,
                            ];
                        }
                        let d0 = dot(sub(xf, x0), es).max(0.0);
                        let d1 = dot(sub(x1, xf), es).max(0.0);
                        // d0 + d1 ≥ (x1 − x0)·e_s = ds > 0 (the clamps only add).
                        *weight0 = d0 / (d0 + d1);
                    }
                    FaceGeometry::Interface { .. } | FaceGeometry::Boundary { .. } => {}
                }
                (None, usize::from(sliver))
            })
            .reduce(|| (None, 0), |a, b| (a.0.or(b.0), a.1 + b.1));
        self.sliver_faces = degenerate;
        // `reduce` keeps the left operand: the first (lowest) non-finite face.
        if let Some((face, cosine)) = worst {
            return Err(HeatError::DegenerateFace {
                face,
                cosine,
                minimum: MIN_FACE_COSINE,
            });
        }
        // Interface faces: area and the solid half cell's conductance.
        self.interface
            .par_iter_mut()
            .with_min_len(GRAIN)
            .for_each(|face| {
                let f = face.face as usize;
                let [c0, c1] = mesh.face_cells[f];
                let solid = if face.fluid_first { c1 } else { c0 } as usize;
                let r = sub(mesh.face_centroid[f], mesh.cell_centroid[solid]);
                let solid_distance = dot(r, r).sqrt();
                face.area = mesh.face_length[f] * b;
                face.solid_conductance = if solid_distance > 0.0 {
                    solid_lambda * face.area / solid_distance
                } else {
                    0.0
                };
            });
        Ok(())
    }

    /// Least-squares weights: rows e_k · ∇T = ΔT_k / |d_k| (unit e_k towards the neighbour
    /// centroid in the same medium, or to the face centroid for interface and boundary face
    /// values), and Neumann rows n · ∇T = q / λ on prescribed-flux faces, written as weights
    /// on the face value T_f − T_c = d_n q / λ (stage 1), so the gradient stage is one sum.
    fn update_stencils(&mut self, model: &HeatModel, mesh: &PoreMesh) {
        // A Neumann row exists where the cell's medium can conduct (q / λ defined).
        let fluid_conducts = model.liquid.conductivity > 0.0 || model.gas.conductivity > 0.0;
        let solid_conducts = model.solid.conductivity > 0.0;
        let faces = &self.face;
        let boundary = &self.boundary;
        (
            &mut self.stencil_weight,
            &mut self.stencil_offset,
            &self.stencil_source,
        )
            .into_par_iter()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(c, (weight, offset, source))| {
                let xc = mesh.cell_centroid[c];
                let conducts = if mesh.cell_kind[c].is_fluid() {
                    fluid_conducts
                } else {
                    solid_conducts
                };
                let mut dir = [[0.0; 2]; 3];
                let mut scale = [0.0; 3];
                let (mut m00, mut m01, mut m11) = (0.0, 0.0, 0.0);
                for (k, &f) in mesh.cell_faces[c].iter().enumerate() {
                    let f = f as usize;
                    offset[k] = sub(mesh.face_centroid[f], xc);
                    let neumann = match faces[f] {
                        FaceGeometry::Boundary { slot } => {
                            let bf = &boundary[slot as usize];
                            matches!(model.sides[bf.side as usize], SideCondition::HeatFlux(_))
                                .then_some(bf.normal_distance)
                        }
                        _ => None,
                    };
                    let e = match neumann {
                        Some(dn) => {
                            if !conducts || dn <= 0.0 {
                                continue;
                            }
                            scale[k] = 1.0 / dn;
                            mesh.face_normal[f]
                        }
                        None => {
                            let d = if source[k] & FACE_VALUE != 0 {
                                offset[k]
                            } else {
                                sub(mesh.cell_centroid[source[k] as usize], xc)
                            };
                            let len = dot(d, d).sqrt();
                            if len > 0.0 {
                                scale[k] = 1.0 / len;
                                [d[0] / len, d[1] / len]
                            } else {
                                [0.0; 2]
                            }
                        }
                    };
                    dir[k] = e;
                    m00 += e[0] * e[0];
                    m01 += e[0] * e[1];
                    m11 += e[1] * e[1];
                }
                let det = m00 * m11 - m01 * m01;
                if det.abs() <= 1e-12 * (m00 + m11).powi(2) {
                    *weight = [[0.0; 2]; 3];
                    return;
                }
                let inv = [[m11 / det, -m01 / det], [-m01 / det, m00 / det]];
                for k in 0..3 {
                    let v = dir[k];
                    let w = [
                        inv[0][0] * v[0] + inv[0][1] * v[1],
                        inv[1][0] * v[0] + inv[1][1] * v[1],
                    ];
                    weight[k] = [w[0] * scale[k], w[1] * scale[k]];
                }
            });
    }

    fn update_channels(&mut self, mesh: &PoreMesh) {
        let ch = &mesh.channels;
        self.channel_point
            .par_iter_mut()
            .with_min_len(GRAIN)
            .enumerate()
            .for_each(|(k, p)| {
                let [a, b] = ch.cells[k].map(|c| c as usize);
                let (pa, pb) = (mesh.cell_centroid[a], mesh.cell_centroid[b]);
                let f = ch.face[k];
                *p = match ch.kind[k] {
                    ChannelKind::T2T if f != NONE => mesh.face_centroid[f as usize],
                    _ => [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])],
                };
            });
    }

    fn update_spheres(&mut self, mesh: &PoreMesh) {
        let (mut fluid, mut total) = (0.0, 0.0);
        self.sphere_radius.iter_mut().for_each(|r| *r = 0.0);
        for (c, k) in mesh.cell_kind.iter().enumerate() {
            let a = mesh.cell_area[c];
            total += a;
            match k {
                CellKind::Fluid => fluid += a,
                CellKind::Solid { owner } => self.sphere_radius[*owner as usize] += a,
            }
        }
        self.porosity = if total > 0.0 { fluid / total } else { 0.0 };
        // Radius of the circle with the cross-section area of the sphere's solid cells.
        for (r, p) in self
            .sphere_radius
            .iter_mut()
            .zip(&mut self.sphere_diameter_powers)
        {
            *r = (*r / std::f64::consts::PI).sqrt();
            *p = DiameterPowers::new(*r);
        }
    }
}
