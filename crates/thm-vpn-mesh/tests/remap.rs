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

fn area(t: &[[f64; 2]; 3]) -> f64 {
    0.5 * ((t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]))
}

/// A counter-clockwise triangle from three points (`None` if nearly degenerate).
fn ccw(p: [[f64; 2]; 3]) -> Option<[[f64; 2]; 3]> {
    let a = area(&p);
    let scale = (0..3)
        .map(|k| (p[k][0] - p[(k + 1) % 3][0]).hypot(p[k][1] - p[(k + 1) % 3][1]))
        .fold(0.0, f64::max);
    if a.abs() < 1e-3 * scale * scale {
        None
    } else if a > 0.0 {
        Some(p)
    } else {
        Some([p[0], p[2], p[1]])
    }
}

fn point() -> impl proptest::strategy::Strategy<Value = [f64; 2]> {
    use proptest::prelude::*;
    (-1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, y)| [x, y])
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(400))]

    /// The overlap area is symmetric (clipping `a` by `b` and `b` by `a` are different
    /// computations), bounded by both areas, additive when `b` is split in two along a line
    /// from a corner, and the same after moving both triangles far from the origin.
    #[test]
    fn overlap_area_is_a_measure(
        pa in [point(), point(), point()],
        pb in [point(), point(), point()],
        split in 0.05f64..0.95,
        shift in (-1e3f64..1e3, -1e3f64..1e3),
    ) {
        let (Some(a), Some(b)) = (ccw(pa), ccw(pb)) else { return Ok(()) };
        let tol = 1e-13;
        let ab = triangle_overlap_area(&a, &b);
        let ba = triangle_overlap_area(&b, &a);
        proptest::prop_assert!((ab - ba).abs() <= tol, "{ab} vs {ba}");
        proptest::prop_assert!(ab >= 0.0 && ab <= area(&a).min(area(&b)) + tol);
        // b = b1 ∪ b2, split at a point on the edge b1–b2.
        let m = [
            b[1][0] + split * (b[2][0] - b[1][0]),
            b[1][1] + split * (b[2][1] - b[1][1]),
        ];
        let (b1, b2) = ([b[0], b[1], m], [b[0], m, b[2]]);
        let parts = triangle_overlap_area(&a, &b1) + triangle_overlap_area(&a, &b2);
        proptest::prop_assert!((ab - parts).abs() <= tol, "{ab} vs {parts}");
        // Far from the origin the result keeps its absolute accuracy.
        let mv = |t: [[f64; 2]; 3]| t.map(|p| [p[0] + shift.0, p[1] + shift.1]);
        let far = triangle_overlap_area(&mv(a), &mv(b));
        proptest::prop_assert!((ab - far).abs() <= 1e-12 * (1.0 + shift.0.abs().max(shift.1.abs())), "{ab} vs {far}");
        proptest::prop_assert!((triangle_overlap_area(&a, &a) - area(&a)).abs() <= tol);
    }
}

/// The overlaps do not depend on how the new cells are numbered: the seed walks start from the
/// previous old cell's seed, and with the new cells in reverse order (the walks then start in
/// the far corner, and walk the other way) every new cell still receives the same content.
#[test]
fn remap_does_not_depend_on_new_cell_order() {
    let old = bar_mesh(5, 24);
    let new = bar_mesh(6, 40).mesh;
    let n = new.n_cells();
    let reversed = PoreMesh::from_triangles(
        new.vertices.clone(),
        new.vertex_sphere.clone(),
        new.cell_vertices.iter().rev().copied().collect(),
        new.cell_kind.iter().rev().copied().collect(),
        new.thickness,
        1e-12,
        0.5,
    )
    .unwrap();
    let q: Vec<f64> = (0..old.mesh.n_cells())
        .map(|c| old.mesh.cell_area[c] * (1.0 + (c % 5) as f64))
        .collect();
    let (mut out, mut out_rev) = (vec![0.0; n], vec![0.0; n]);
    RemapOperator::new(&old.mesh, &new)
        .unwrap()
        .apply(CellFilter::Any, &q, &mut out)
        .unwrap();
    RemapOperator::new(&old.mesh, &reversed)
        .unwrap()
        .apply(CellFilter::Any, &q, &mut out_rev)
        .unwrap();
    let scale = q.iter().sum::<f64>() / n as f64;
    for c in 0..n {
        let (a, b) = (out[c], out_rev[n - 1 - c]);
        assert!((a - b).abs() < 1e-12 * scale, "cell {c}: {a} vs {b}");
    }
}
