//! Remap exactness beyond conservation.

use thm_vpn_mesh::packing::{PackingSpec, overlap_contacts, random_packing};
use thm_vpn_mesh::remap::triangle_overlap_area;
use thm_vpn_mesh::*;

fn bar_mesh(seed: u64, n: u32) -> PackingMesh {
    let spec = PackingSpec::paper_bar(seed);
    let cs = random_packing(&spec);
    let s = MeshParams::new(
        Outline::Box {
            min: spec.box_min,
            max: spec.box_max,
        },
        n,
    )
    .validate()
    .unwrap();
    mesh_packing(&cs, &overlap_contacts(&cs, 1e7), &s).unwrap()
}

/// A mesh remapped onto itself gives back every cell's content.
#[test]
fn remap_onto_itself_is_the_identity() {
    let pm = bar_mesh(5, 24);
    let op = RemapOperator::new(&pm.mesh, &pm.mesh).unwrap();
    let q: Vec<f64> = (0..pm.mesh.n_cells())
        .map(|c| 1.0 + (c % 7) as f64)
        .collect();
    let mut out = vec![0.0; q.len()];
    op.apply(CellFilter::Any, &q, &mut out).unwrap();
    for (a, b) in q.iter().zip(&out) {
        assert!((a - b).abs() < 1e-12 * a, "{a} vs {b}");
    }
}

/// A uniform density (content ∝ cell area) stays uniform between two different meshes of the
/// same box: every new cell receives density × its own area (the overlaps tile each cell).
#[test]
fn uniform_density_is_reproduced() {
    let old = bar_mesh(5, 24);
    let new = bar_mesh(6, 40);
    let op = RemapOperator::new(&old.mesh, &new.mesh).unwrap();
    let rho = 2.5e3;
    let q: Vec<f64> = old.mesh.cell_area.iter().map(|a| rho * a).collect();
    let mut out = vec![0.0; new.mesh.n_cells()];
    op.apply(CellFilter::Any, &q, &mut out).unwrap();
    let mean = rho * new.mesh.cell_area.iter().sum::<f64>() / new.mesh.n_cells() as f64;
    for (c, v) in out.iter().enumerate() {
        let expect = rho * new.mesh.cell_area[c];
        assert!(
            (v - expect).abs() < 1e-10 * mean,
            "cell {c}: {v} vs {expect}"
        );
    }
}

/// Fluid content of old pores now covered by solid goes to fluid cells nearby, and the totals
/// hold.
#[test]
fn closed_pore_content_moves_to_nearest_fluid() {
    let old = bar_mesh(5, 24);
    let new = bar_mesh(6, 24);
    let op = RemapOperator::new(&old.mesh, &new.mesh).unwrap();
    let q: Vec<f64> = (0..old.mesh.n_cells())
        .map(|c| {
            if old.mesh.cell_kind[c].is_fluid() {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    let mut out = vec![0.0; new.mesh.n_cells()];
    op.apply(CellFilter::Fluid, &q, &mut out).unwrap();
    let (a, b): (f64, f64) = (q.iter().sum(), out.iter().sum());
    assert!((a - b).abs() < 1e-12 * a);
    assert!(
        out.iter()
            .zip(&new.mesh.cell_kind)
            .all(|(v, k)| *v == 0.0 || k.is_fluid())
    );
}

#[test]
fn triangle_overlap_of_known_shapes() {
    let a = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    assert!((triangle_overlap_area(&a, &a) - 0.5).abs() < 1e-16);
    // Half-shifted copy: overlap is a triangle of legs 0.5.
    let b = [[0.5, 0.0], [1.5, 0.0], [0.5, 1.0]];
    assert!((triangle_overlap_area(&a, &b) - 0.125).abs() < 1e-16);
    let far = [[5.0, 5.0], [6.0, 5.0], [5.0, 6.0]];
    assert_eq!(triangle_overlap_area(&a, &far), 0.0);
}
