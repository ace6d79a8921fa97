//! Plain arrays for visualisation (VTU through the shared `thm-io` writer, PNG pictures).
//!
//! This crate writes no files: [`PoreMesh::vertices`] are the points, and the methods below
//! give the triangles and the per-cell labels in the integer types a VTU writer takes.
//! With `thm-io`: `UnstructuredGrid::triangles(&mesh.vertices, &tris)` plus the cell fields
//! `cell_type` ([`PoreMesh::cell_type_labels`]), `owner` ([`PoreMesh::cell_owner_labels`]) and
//! `area_m2` (`mesh.cell_area`).

use crate::mesh::{CellKind, FaceKind, PoreMesh};

/// Label of a fluid cell in [`PoreMesh::cell_type_labels`].
pub const FLUID_LABEL: i32 = 0;
/// Label of a solid cell in [`PoreMesh::cell_type_labels`].
pub const SOLID_LABEL: i32 = 1;

impl PoreMesh {
    /// Triangle corners as `usize` (VTK connectivity), counter-clockwise.
    pub fn triangles_usize(&self) -> Vec<[usize; 3]> {
        self.cell_vertices
            .iter()
            .map(|t| t.map(|v| v as usize))
            .collect()
    }

    /// Per cell: [`FLUID_LABEL`] or [`SOLID_LABEL`].
    pub fn cell_type_labels(&self) -> Vec<i32> {
        self.cell_kind
            .iter()
            .map(|k| {
                if k.is_fluid() {
                    FLUID_LABEL
                } else {
                    SOLID_LABEL
                }
            })
            .collect()
    }

    /// Per cell: the owner sphere id of a solid cell, −1 for a fluid cell (ids above
    /// `i32::MAX` are written as −2).
    pub fn cell_owner_labels(&self) -> Vec<i32> {
        self.cell_kind
            .iter()
            .map(|k| match *k {
                CellKind::Fluid => -1,
                CellKind::Solid { owner } => i32::try_from(owner).unwrap_or(-2),
            })
            .collect()
    }

    /// Faces on the interface between a fluid and a solid cell (case IV of A-Sect. 2.3).
    pub fn fluid_solid_faces(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n_faces()).filter(|&f| {
            let [a, b] = self.face_cells[f];
            self.face_kind[f] == FaceKind::Interior
                && self.cell_kind[a as usize].is_fluid() != self.cell_kind[b as usize].is_fluid()
        })
    }

    /// Faces between solid cells of two different owners: the contact faces along the cuts.
    pub fn contact_faces(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n_faces()).filter(|&f| {
            let [a, b] = self.face_cells[f];
            if self.face_kind[f] != FaceKind::Interior {
                return false;
            }
            match (self.cell_kind[a as usize], self.cell_kind[b as usize]) {
                (CellKind::Solid { owner: x }, CellKind::Solid { owner: y }) => x != y,
                _ => false,
            }
        })
    }
}
