//! The network view the solver runs on: pores, channels, boundary links and wall faces, with
//! a compressed pore → channel adjacency for allocation-free, deterministic gathers.

use crate::error::FlowError;
use serde::{Deserialize, Serialize};
use thm_vpn_mesh::{BoundarySide, CellKind, FaceKind, NONE, PoreMesh};

/// A boundary condition on a group of boundary links.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "snake_case")]
pub enum BoundaryCondition {
    /// A reservoir at a prescribed pressure. Fluid flows through half-channels between the
    /// boundary pores and the reservoir; fluid that enters has the reservoir's composition.
    Pressure {
        /// Reservoir pressure \[Pa\] (> 0).
        pressure: f64,
        /// Reservoir temperature \[K\] (> 0): sets the density of the fluid that enters.
        temperature: f64,
        /// Liquid fraction `α_q ∈ [0, 1]` of the fluid that enters (1: water, 0: air).
        entering_liquid_fraction: f64,
    },
    /// Prescribed mass flow rates into the domain [kg/s] (negative: out of it), shared among
    /// the group's links in proportion to their face lengths.
    MassRate {
        /// Liquid mass flow rate into the domain [kg/s].
        liquid_mass_rate: f64,
        /// Gas mass flow rate into the domain [kg/s].
        gas_mass_rate: f64,
    },
    /// No flow (equivalent to a zero mass rate; the group keeps no links).
    Impermeable,
}

impl BoundaryCondition {
    fn validate(&self) -> Result<(), FlowError> {
        let bad = |name, range, value: f64| FlowError::OutOfRange { name, range, value };
        match *self {
            BoundaryCondition::Pressure {
                pressure,
                temperature,
                entering_liquid_fraction,
            } => {
                if !(pressure.is_finite() && pressure > 0.0) {
                    return Err(bad("boundary pressure", "> 0 Pa", pressure));
                }
                if !(temperature.is_finite() && temperature > 0.0) {
                    return Err(bad("boundary temperature", "> 0 K", temperature));
                }
                if !(0.0..=1.0).contains(&entering_liquid_fraction) {
                    return Err(bad(
                        "entering_liquid_fraction",
                        "in [0, 1]",
                        entering_liquid_fraction,
                    ));
                }
            }
            BoundaryCondition::MassRate {
                liquid_mass_rate,
                gas_mass_rate,
            } => {
                if !liquid_mass_rate.is_finite() {
                    return Err(bad("liquid_mass_rate", "finite", liquid_mass_rate));
                }
                if !gas_mass_rate.is_finite() {
                    return Err(bad("gas_mass_rate", "finite", gas_mass_rate));
                }
            }
            BoundaryCondition::Impermeable => {}
        }
        Ok(())
    }
}

/// A hand-made network in plain arrays (everything [`Network`] needs), validated by
/// [`Network::new`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NetworkParts {
    /// Number of pores.
    pub n_pores: usize,
    /// Out-of-plane width of every channel \[m\] (paper A: the largest sphere diameter).
    pub width: f64,
    /// The two pores each channel joins.
    pub channel_pores: Vec<[u32; 2]>,
    /// Channel lengths \[m\] (> 0).
    pub channel_length: Vec<f64>,
    /// Channel apertures \[m\] (≥ 0).
    pub channel_aperture: Vec<f64>,
    /// Unit vector from the first pore's centroid to the second's (for shear forces; may be
    /// empty, then zero).
    pub channel_direction: Vec<[f64; 2]>,
    /// For S2S channels, the index of the sphere contact they cross; [`NONE`] otherwise (may
    /// be empty: no S2S channel).
    pub channel_contact: Vec<u32>,
    /// The boundary conditions, one per group.
    pub boundaries: Vec<BoundaryCondition>,
    /// Pore of each boundary link.
    pub link_pore: Vec<u32>,
    /// Group of each boundary link (index into `boundaries`).
    pub link_group: Vec<u32>,
    /// Link length: pore centroid to boundary face centre \[m\] (> 0).
    pub link_length: Vec<f64>,
    /// Link aperture \[m\] (≥ 0).
    pub link_aperture: Vec<f64>,
    /// Length of the boundary face of the link \[m\] (> 0; weights mass-rate conditions).
    pub link_face_length: Vec<f64>,
    /// Pore of each fluid–solid wall face.
    pub wall_pore: Vec<u32>,
    /// Sphere owning the solid side of each wall face.
    pub wall_sphere: Vec<u32>,
    /// Unit normal of each wall face, pointing from the fluid into the solid.
    pub wall_normal: Vec<[f64; 2]>,
    /// Wall face lengths `e_k` \[m\].
    pub wall_length: Vec<f64>,
}

/// A validated network (see [`NetworkParts`] for the meaning of the arrays).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Network {
    parts: NetworkParts,
    group_face_length: Vec<f64>,
    pore_channel_start: Vec<u32>,
    /// Incident channels of each pore; the top bit is set where the pore is the channel's
    /// second end (the flux, positive first → second, enters it).
    pore_channel: Vec<u32>,
    pore_link_start: Vec<u32>,
    pore_link: Vec<u32>,
    pore_cell: Vec<u32>,
    /// For each boundary link, the mesh face it crosses (empty for a hand-made network).
    #[serde(default)]
    link_face: Vec<u32>,
}

/// Flag bit in [`Network::pore_channels`] entries: the pore is the channel's second end.
pub const SECOND_END: u32 = 1 << 31;

fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), FlowError> {
    if expected == got {
        Ok(())
    } else {
        Err(FlowError::LengthMismatch {
            what,
            expected,
            got,
        })
    }
}

fn csr(n: usize, entries: impl Iterator<Item = (usize, u32)> + Clone) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; n + 1];
    for (p, _) in entries.clone() {
        start[p + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut list = vec![0u32; start[n] as usize];
    for (p, item) in entries {
        list[fill[p] as usize] = item;
        fill[p] += 1;
    }
    (start, list)
}

impl Network {
    /// Validates the parts and builds the adjacency. Errors name the offending channel, link
    /// or wall face: a negative aperture, a non-positive length, a pore index out of range.
    pub fn new(mut parts: NetworkParts) -> Result<Self, FlowError> {
        let np = parts.n_pores;
        let nc = parts.channel_pores.len();
        if !(parts.width.is_finite() && parts.width > 0.0) {
            return Err(FlowError::OutOfRange {
                name: "width",
                range: "> 0 m",
                value: parts.width,
            });
        }
        if parts.channel_direction.is_empty() {
            parts.channel_direction = vec![[0.0; 2]; nc];
        }
        if parts.channel_contact.is_empty() {
            parts.channel_contact = vec![NONE; nc];
        }
        if nc >= SECOND_END as usize {
            return Err(FlowError::OutOfRange {
                name: "number of channels",
                range: "< 2^31",
                value: nc as f64,
            });
        }
        check_len("channel_length", nc, parts.channel_length.len())?;
        check_len("channel_aperture", nc, parts.channel_aperture.len())?;
        check_len("channel_direction", nc, parts.channel_direction.len())?;
        check_len("channel_contact", nc, parts.channel_contact.len())?;
        for c in 0..nc {
            let [a, b] = parts.channel_pores[c];
            for p in [a, b] {
                if p as usize >= np {
                    return Err(FlowError::BadPoreIndex {
                        what: "channel",
                        index: c,
                        pore: p as usize,
                        n_pores: np,
                    });
                }
            }
            if a == b {
                return Err(FlowError::BadPoreIndex {
                    what: "channel",
                    index: c,
                    pore: a as usize,
                    n_pores: np,
                });
            }
            let h = parts.channel_aperture[c];
            if !(h.is_finite() && h >= 0.0) {
                return Err(FlowError::NegativeAperture {
                    channel: c,
                    value: h,
                });
            }
            let l = parts.channel_length[c];
            if !(l.is_finite() && l > 0.0) {
                return Err(FlowError::NonPositiveLength {
                    what: "channel",
                    index: c,
                    value: l,
                });
            }
        }
        let nl = parts.link_pore.len();
        check_len("link_group", nl, parts.link_group.len())?;
        check_len("link_length", nl, parts.link_length.len())?;
        check_len("link_aperture", nl, parts.link_aperture.len())?;
        check_len("link_face_length", nl, parts.link_face_length.len())?;
        for bc in &parts.boundaries {
            bc.validate()?;
        }
        let ng = parts.boundaries.len();
        let mut group_face_length = vec![0.0; ng];
        for k in 0..nl {
            let p = parts.link_pore[k] as usize;
            if p >= np {
                return Err(FlowError::BadPoreIndex {
                    what: "boundary link",
                    index: k,
                    pore: p,
                    n_pores: np,
                });
            }
            let g = parts.link_group[k] as usize;
            if g >= ng {
                return Err(FlowError::OutOfRange {
                    name: "link_group",
                    range: "< number of boundary conditions",
                    value: g as f64,
                });
            }
            let h = parts.link_aperture[k];
            if !(h.is_finite() && h >= 0.0) {
                return Err(FlowError::NegativeLinkAperture { link: k, value: h });
            }
            for (what, v) in [
                ("boundary link", parts.link_length[k]),
                ("boundary face", parts.link_face_length[k]),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(FlowError::NonPositiveLength {
                        what,
                        index: k,
                        value: v,
                    });
                }
            }
            group_face_length[g] += parts.link_face_length[k];
        }
        let nw = parts.wall_pore.len();
        check_len("wall_sphere", nw, parts.wall_sphere.len())?;
        check_len("wall_normal", nw, parts.wall_normal.len())?;
        check_len("wall_length", nw, parts.wall_length.len())?;
        for k in 0..nw {
            if parts.wall_pore[k] as usize >= np {
                return Err(FlowError::BadPoreIndex {
                    what: "wall face",
                    index: k,
                    pore: parts.wall_pore[k] as usize,
                    n_pores: np,
                });
            }
        }
        let (pore_channel_start, pore_channel) = csr(
            np,
            parts.channel_pores.iter().enumerate().flat_map(|(c, p)| {
                [
                    (p[0] as usize, c as u32),
                    (p[1] as usize, c as u32 | SECOND_END),
                ]
            }),
        );
        let (pore_link_start, pore_link) = csr(
            np,
            parts
                .link_pore
                .iter()
                .enumerate()
                .map(|(k, &p)| (p as usize, k as u32)),
        );
        Ok(Self {
            pore_cell: (0..np as u32).collect(),
            link_face: Vec::new(),
            parts,
            group_face_length,
            pore_channel_start,
            pore_channel,
            pore_link_start,
            pore_link,
        })
    }

    /// Builds the network of a [`PoreMesh`]: one pore per fluid cell (numbered in cell
    /// order), its T2T and S2S channels, a boundary link for every boundary face of a fluid
    /// cell whose side has a condition in `boundaries` (a half-channel from the cell centroid
    /// to the face centre, aperture `γ e sin ω` as A-Eq. 9 with `γ = boundary_reduction_factor`),
    /// and a wall face for every face between a fluid cell and a solid cell. The channel width
    /// is the mesh thickness (A-Sect. 2.2: the largest sphere diameter). Sides without a
    /// condition are impermeable.
    pub fn from_mesh(
        mesh: &PoreMesh,
        boundaries: &[(BoundarySide, BoundaryCondition)],
        boundary_reduction_factor: f64,
    ) -> Result<Self, FlowError> {
        if !(boundary_reduction_factor.is_finite() && boundary_reduction_factor > 0.0) {
            return Err(FlowError::OutOfRange {
                name: "boundary_reduction_factor",
                range: "> 0",
                value: boundary_reduction_factor,
            });
        }
        let nc = mesh.n_cells();
        let mut cell_pore = vec![NONE; nc];
        let mut pore_cell = Vec::new();
        for (c, (slot, kind)) in cell_pore.iter_mut().zip(&mesh.cell_kind).enumerate() {
            if kind.is_fluid() {
                *slot = pore_cell.len() as u32;
                pore_cell.push(c as u32);
            }
        }
        let mut link_face = Vec::new();
        let mut parts = NetworkParts {
            n_pores: pore_cell.len(),
            width: mesh.thickness,
            boundaries: boundaries.iter().map(|b| b.1).collect(),
            ..Default::default()
        };
        let ch = &mesh.channels;
        for k in 0..ch.len() {
            let [a, b] = ch.cells[k];
            let (pa, pb) = (cell_pore[a as usize], cell_pore[b as usize]);
            if pa == NONE || pb == NONE {
                return Err(FlowError::BadPoreIndex {
                    what: "channel",
                    index: k,
                    pore: if pa == NONE { a as usize } else { b as usize },
                    n_pores: parts.n_pores,
                });
            }
            let (ca, cb) = (
                mesh.cell_centroid[a as usize],
                mesh.cell_centroid[b as usize],
            );
            let d = [cb[0] - ca[0], cb[1] - ca[1]];
            let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let inv = if len > 0.0 { 1.0 / len } else { 0.0 };
            parts.channel_pores.push([pa, pb]);
            parts.channel_length.push(ch.length[k]);
            parts.channel_aperture.push(ch.aperture[k]);
            parts.channel_direction.push([d[0] * inv, d[1] * inv]);
            parts.channel_contact.push(ch.contact[k]);
        }
        for f in 0..mesh.n_faces() {
            let [c0, c1] = mesh.face_cells[f];
            match mesh.face_kind[f] {
                FaceKind::Boundary(side) => {
                    let p = cell_pore[c0 as usize];
                    if p == NONE {
                        continue;
                    }
                    let Some(g) = boundaries.iter().position(|b| b.0 == side) else {
                        continue;
                    };
                    if matches!(boundaries[g].1, BoundaryCondition::Impermeable) {
                        continue;
                    }
                    let cc = mesh.cell_centroid[c0 as usize];
                    let fc = mesh.face_centroid[f];
                    let d = [fc[0] - cc[0], fc[1] - cc[1]];
                    let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
                    let n = mesh.face_normal[f];
                    let sin_omega = if length > 0.0 {
                        (n[0] * d[0] + n[1] * d[1]).abs() / length
                    } else {
                        0.0
                    };
                    link_face.push(f as u32);
                    parts.link_pore.push(p);
                    parts.link_group.push(g as u32);
                    parts.link_length.push(length);
                    parts
                        .link_aperture
                        .push(boundary_reduction_factor * mesh.face_length[f] * sin_omega);
                    parts.link_face_length.push(mesh.face_length[f]);
                }
                FaceKind::Interior => {
                    let (k0, k1) = (mesh.cell_kind[c0 as usize], mesh.cell_kind[c1 as usize]);
                    let (fluid, sphere, sign) = match (k0, k1) {
                        (CellKind::Fluid, CellKind::Solid { owner }) => (c0, owner, 1.0),
                        (CellKind::Solid { owner }, CellKind::Fluid) => (c1, owner, -1.0),
                        _ => continue,
                    };
                    let n = mesh.face_normal[f];
                    parts.wall_pore.push(cell_pore[fluid as usize]);
                    parts.wall_sphere.push(sphere);
                    parts.wall_normal.push([sign * n[0], sign * n[1]]);
                    parts.wall_length.push(mesh.face_length[f]);
                }
            }
        }
        let mut net = Self::new(parts)?;
        net.pore_cell = pore_cell;
        net.link_face = link_face;
        Ok(net)
    }

    /// Pore volumes `area × thickness` \[m³\] of a mesh's fluid cells, in pore order.
    pub fn pore_volumes(&self, mesh: &PoreMesh) -> Vec<f64> {
        self.pore_cell
            .iter()
            .map(|&c| mesh.cell_volume(c as usize))
            .collect()
    }

    /// For each boundary link, the mesh face it crosses (built by [`Self::from_mesh`]; empty
    /// for a network made by hand with [`Self::new`]).
    pub fn link_faces(&self) -> &[u32] {
        &self.link_face
    }

    /// Picks the values of the fluid cells, in pore order, from a per-cell array (e.g. `dV/dt`
    /// of every mesh cell from the solid motion, or cell temperatures from the heat solver).
    pub fn cells_to_pores(&self, cell_values: &[f64], out: &mut [f64]) -> Result<(), FlowError> {
        check_len("pore values", self.n_pores(), out.len())?;
        for (o, &c) in out.iter_mut().zip(&self.pore_cell) {
            *o = *cell_values
                .get(c as usize)
                .ok_or(FlowError::LengthMismatch {
                    what: "cell values",
                    expected: c as usize + 1,
                    got: cell_values.len(),
                })?;
        }
        Ok(())
    }

    /// Number of pores.
    pub fn n_pores(&self) -> usize {
        self.parts.n_pores
    }
    /// Number of channels.
    pub fn n_channels(&self) -> usize {
        self.parts.channel_pores.len()
    }
    /// Number of boundary links.
    pub fn n_links(&self) -> usize {
        self.parts.link_pore.len()
    }
    /// Number of boundary groups (conditions).
    pub fn n_groups(&self) -> usize {
        self.parts.boundaries.len()
    }
    /// Channel width (out-of-plane thickness) \[m\].
    pub fn width(&self) -> f64 {
        self.parts.width
    }
    /// The validated arrays.
    pub fn parts(&self) -> &NetworkParts {
        &self.parts
    }
    /// The mesh cell of each pore (identity for hand-made networks).
    pub fn pore_cell(&self) -> &[u32] {
        &self.pore_cell
    }
    /// Total face length of each boundary group \[m\].
    pub fn group_face_length(&self) -> &[f64] {
        &self.group_face_length
    }
    /// The channels incident to pore `p`, each with [`SECOND_END`] set where `p` is the
    /// channel's second pore (mask it off with `!SECOND_END` for the channel index).
    pub fn pore_channels(&self, p: usize) -> &[u32] {
        let (a, b) = (
            self.pore_channel_start[p] as usize,
            self.pore_channel_start[p + 1] as usize,
        );
        &self.pore_channel[a..b]
    }
    /// The boundary links of pore `p`.
    pub fn pore_links(&self, p: usize) -> &[u32] {
        let (a, b) = (
            self.pore_link_start[p] as usize,
            self.pore_link_start[p + 1] as usize,
        );
        &self.pore_link[a..b]
    }
    /// Replaces the channel apertures (e.g. S2S apertures after a contact-stress update),
    /// validating them.
    pub fn set_channel_apertures(&mut self, apertures: &[f64]) -> Result<(), FlowError> {
        check_len("channel apertures", self.n_channels(), apertures.len())?;
        for (c, &h) in apertures.iter().enumerate() {
            if !(h.is_finite() && h >= 0.0) {
                return Err(FlowError::NegativeAperture {
                    channel: c,
                    value: h,
                });
            }
        }
        self.parts.channel_aperture.copy_from_slice(apertures);
        Ok(())
    }
}
