//! # thm-vpn-mesh — the virtual pore network mesh
//!
//! The mesh of Krzaczek, Nitka & Tejchman (2023), Sect. 2.2 and 2.4: spheres of a single layer
//! are projected on the mid-plane as circles; the pore space between them and the circles
//! themselves are triangulated; pore triangles are virtual pores (fluid cells), circle
//! triangles are solid cells owned by one sphere; fluid cells are linked by T2T channels
//! (A-Eq. 9) and S2S channels (A-Eq. 8).
//!
//! ## Public seam
//!
//! [`PoreMesh`] (struct-of-arrays cells, faces and channels with their geometry) is what the
//! flow (`thm-vpn-flow`) and heat (`thm-fvm-heat`) solvers consume. Lengths in m, areas in m²,
//! volumes `area × thickness` in m³.
//!
//! The mesher from circles (constrained Delaunay on `spade`, alpha-shape outline), the motion
//! of the mesh with the spheres and the conservative remap arrive with the crate's full
//! version; [`PoreMesh::from_triangles`] and [`PoreMesh::structured_rectangle`] already build
//! valid meshes for the solvers.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod error;
pub mod export;
mod mesh;
pub mod mesher;
pub mod motion;
pub mod packing;
pub mod remap;

pub use error::MeshError;
pub use mesh::{
    BoundarySide, CellKind, ChannelKind, Channels, FaceKind, NONE, PoreMesh, TopologyError,
};
pub use mesher::{
    Chords, Circle, Contact, MeshParams, MeshSettings, Outline, PackingMesh, S2sApertureParams,
    mesh_packing,
};
pub use motion::{
    CircleMotion, MeshMotion, RemeshCriteria, RemeshCriteriaParams, RemeshReason, VertexAnchors,
    VertexConstraint, remesh_needed,
};
pub use remap::{CellFilter, RemapOperator};

pub mod verification;
