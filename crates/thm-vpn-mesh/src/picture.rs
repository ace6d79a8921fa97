//! A PNG picture of a mesh for the documentation, drawn by the shared `thm-io` writer.
//!
//! Fluid cells (virtual pores) are light blue; solid cells take one of a few sand shades by
//! owner, chosen so that spheres whose cells touch get different shades (greedy colouring of
//! the owner adjacency across faces, in owner order, so the picture is reproducible).
//! Triangle edges are drawn a little darker than their cell, and the fluid channels can be
//! drawn as dark blue segments between the centroids of the cells they join.

use std::collections::BTreeMap;
use std::path::Path;

use thm_io::{FilledPolygon, Picture, Segment};

use crate::error::MeshError;
use crate::mesh::{CellKind, NONE, PoreMesh};

/// Fill of fluid cells.
pub const FLUID_COLOUR: [u8; 3] = [178, 214, 240];
/// Fills of solid cells, one per owner colour class.
pub const SOLID_COLOURS: [[u8; 3]; 5] = [
    [214, 184, 140],
    [176, 146, 110],
    [232, 212, 178],
    [150, 128, 104],
    [196, 164, 120],
];
/// Colour of the channel segments.
pub const CHANNEL_COLOUR: [u8; 3] = [20, 60, 150];

/// How to draw a mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct PictureStyle {
    /// Title above the picture.
    pub title: String,
    /// Image width \[px\]; the height follows at equal axis scales.
    pub width_px: u32,
    /// Draw the fluid channels (T2T and S2S) between cell centroids.
    pub channels: bool,
}

fn darker(c: [u8; 3]) -> [u8; 3] {
    c.map(|x| (x as u16 * 4 / 5) as u8)
}

/// Colour class of every owner: greedy over owners in increasing order, avoiding the classes
/// of owners already coloured whose solid cells share a face with it.
fn owner_classes(mesh: &PoreMesh) -> BTreeMap<u32, usize> {
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    for cells in &mesh.face_cells {
        if cells[1] == NONE {
            continue;
        }
        if let (CellKind::Solid { owner: a }, CellKind::Solid { owner: b }) = (
            mesh.cell_kind[cells[0] as usize],
            mesh.cell_kind[cells[1] as usize],
        ) && a != b
        {
            pairs.push((a.min(b), a.max(b)));
        }
    }
    pairs.sort_unstable();
    pairs.dedup();
    let mut neighbours: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for k in &mesh.cell_kind {
        if let CellKind::Solid { owner } = *k {
            neighbours.entry(owner).or_default();
        }
    }
    for &(a, b) in &pairs {
        neighbours.entry(a).or_default().push(b);
        neighbours.entry(b).or_default().push(a);
    }
    let mut class: BTreeMap<u32, usize> = BTreeMap::new();
    for (&owner, near) in &neighbours {
        let used: Vec<usize> = near.iter().filter_map(|n| class.get(n).copied()).collect();
        let pick = (0..SOLID_COLOURS.len())
            .find(|c| !used.contains(c))
            .unwrap_or(owner as usize % SOLID_COLOURS.len());
        class.insert(owner, pick);
    }
    class
}

/// The picture of `mesh` (cells and, if asked, channels) for the `thm-io` PNG writer.
pub fn mesh_picture(mesh: &PoreMesh, style: &PictureStyle) -> Picture {
    let class = owner_classes(mesh);
    let polygons = mesh
        .cell_vertices
        .iter()
        .zip(&mesh.cell_kind)
        .map(|(t, k)| {
            let fill = match *k {
                CellKind::Fluid => FLUID_COLOUR,
                CellKind::Solid { owner } => SOLID_COLOURS[class.get(&owner).copied().unwrap_or(0)],
            };
            FilledPolygon {
                corners: t.iter().map(|&v| mesh.vertices[v as usize]).collect(),
                fill,
                outline: Some(darker(fill)),
            }
        })
        .collect();
    let segments = if style.channels {
        mesh.channels
            .cells
            .iter()
            .map(|c| Segment {
                ends: c.map(|i| mesh.cell_centroid[i as usize]),
                colour: CHANNEL_COLOUR,
            })
            .collect()
    } else {
        Vec::new()
    };
    Picture {
        title: style.title.clone(),
        width_px: style.width_px,
        background: [255, 255, 255],
        polygons,
        segments,
        colour_bars: Vec::new(),
        length_scale: None,
    }
}

/// Writes the picture of `mesh` to `path` as PNG (atomically).
pub fn write_mesh_png(mesh: &PoreMesh, style: &PictureStyle, path: &Path) -> Result<(), MeshError> {
    thm_io::write_picture_png(&mesh_picture(mesh, style), path).map_err(|e| MeshError::Output {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two solid owners side by side get different shades; fluid cells are light blue.
    #[test]
    fn touching_owners_get_different_shades() {
        let m = PoreMesh::structured_rectangle(4, 2, 4.0, 2.0, 1.0, 1.0, |c| {
            if c[0] < 1.0 {
                CellKind::Fluid
            } else if c[0] < 2.5 {
                CellKind::Solid { owner: 7 }
            } else {
                CellKind::Solid { owner: 3 }
            }
        })
        .unwrap();
        let pic = mesh_picture(
            &m,
            &PictureStyle {
                title: String::new(),
                width_px: 100,
                channels: true,
            },
        );
        let fill_of = |kind: CellKind| {
            let c = m.cell_kind.iter().position(|k| *k == kind).unwrap();
            pic.polygons[c].fill
        };
        assert_eq!(fill_of(CellKind::Fluid), FLUID_COLOUR);
        assert_ne!(
            fill_of(CellKind::Solid { owner: 7 }),
            fill_of(CellKind::Solid { owner: 3 })
        );
        assert_eq!(pic.segments.len(), m.channels.len());
        assert!(thm_io::render_picture_png(&pic).is_ok());
    }
}
