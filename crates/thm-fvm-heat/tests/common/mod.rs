//! Random meshes, parameters and inputs for the property tests.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thm_fvm_heat::{FlowInput, HeatParams};
use thm_vpn_mesh::{CellKind, ChannelKind, NONE, PoreMesh};

/// A structured rectangle with perturbed interior vertices, random fluid/solid kinds (solid
/// cells owned by one of four spheres) and a few S2S channels between random fluid cells.
pub fn random_mesh(seed: u64, nx: usize, ny: usize) -> PoreMesh {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (lx, ly) = (0.02, 0.03);
    let base =
        PoreMesh::structured_rectangle(nx, ny, lx, ly, 0.008, 1.0, |_| CellKind::Fluid).unwrap();
    let (hx, hy) = (lx / nx as f64, ly / ny as f64);
    let vertices = base
        .vertices
        .iter()
        .map(|&[x, y]| {
            let interior = x > 1e-12 && x < lx - 1e-12 && y > 1e-12 && y < ly - 1e-12;
            if interior {
                [
                    x + hx * rng.random_range(-0.15..0.15),
                    y + hy * rng.random_range(-0.15..0.15),
                ]
            } else {
                [x, y]
            }
        })
        .collect();
    let kinds = (0..base.n_cells())
        .map(|_| {
            if rng.random_bool(0.5) {
                CellKind::Fluid
            } else {
                CellKind::Solid {
                    owner: rng.random_range(0..4),
                }
            }
        })
        .collect();
    let mut mesh = PoreMesh::from_triangles(
        vertices,
        base.vertex_sphere.clone(),
        base.cell_vertices.clone(),
        kinds,
        base.thickness,
        1e-12,
        0.0115,
    )
    .unwrap();
    let fluid: Vec<u32> = (0..mesh.n_cells() as u32)
        .filter(|&c| mesh.cell_kind[c as usize].is_fluid())
        .collect();
    if fluid.len() >= 2 {
        for _ in 0..3 {
            let a = fluid[rng.random_range(0..fluid.len())];
            let b = fluid[rng.random_range(0..fluid.len())];
            if a == b {
                continue;
            }
            let (pa, pb) = (
                mesh.cell_centroid[a as usize],
                mesh.cell_centroid[b as usize],
            );
            let ch = &mut mesh.channels;
            ch.kind.push(ChannelKind::S2S);
            ch.cells.push([a, b]);
            ch.length
                .push(((pb[0] - pa[0]).powi(2) + (pb[1] - pa[1]).powi(2)).sqrt());
            ch.aperture.push(5e-5);
            ch.face.push(NONE);
            ch.contact.push(0);
        }
    }
    mesh
}

/// Table 1 properties (solid, water, air), no boundary conditions (all adiabatic).
pub fn table1_params() -> HeatParams {
    HeatParams::paper_a_table_1()
}

/// Random phase fractions and densities; random divergence-free channel mass fluxes of size
/// up to about `flux_scale` kg/s from a discrete stream function on the vertices (zero on
/// vertices that touch a solid cell or the boundary, so no flux leaves the fluid); none in
/// S2S channels and no boundary mass flux.
pub fn random_input(seed: u64, mesh: &PoreMesh, flux_scale: f64) -> FlowInput {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let mut input = FlowInput::liquid_at_rest(mesh, 1000.0, 1.2);
    for c in 0..mesh.n_cells() {
        input.liquid_fraction[c] = rng.random_range(0.0..=1.0);
        input.liquid_density[c] = rng.random_range(950.0..1050.0);
        input.gas_density[c] = rng.random_range(0.8..2.0);
    }
    let mut pinned = vec![false; mesh.vertices.len()];
    for (c, t) in mesh.cell_vertices.iter().enumerate() {
        if !mesh.cell_kind[c].is_fluid() {
            t.iter().for_each(|&v| pinned[v as usize] = true);
        }
    }
    for f in 0..mesh.n_faces() {
        if mesh.face_cells[f][1] == NONE {
            mesh.face_vertices[f]
                .iter()
                .for_each(|&v| pinned[v as usize] = true);
        }
    }
    let psi: Vec<f64> = pinned
        .iter()
        .map(|&p| {
            let r = flux_scale * rng.random_range(-1.0..1.0);
            if p { 0.0 } else { r }
        })
        .collect();
    for k in 0..mesh.channels.len() {
        let f = mesh.channels.face[k];
        input.channel_mass_flux[k] = if f == NONE {
            0.0
        } else {
            // Edge (a, b) runs counter-clockwise around the face's first cell, which is the
            // channel's first cell: the flux out of it is ψ_b − ψ_a.
            let [a, b] = mesh.face_vertices[f as usize];
            psi[b as usize] - psi[a as usize]
        };
    }
    input
}

/// Random temperatures in [280, 360] K.
pub fn random_temperatures(seed: u64, n: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7e30);
    (0..n).map(|_| rng.random_range(280.0..360.0)).collect()
}
