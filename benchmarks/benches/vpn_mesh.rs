//! Virtual pore network mesh of a 10 000-circle single layer: full mesh, geometry update
//! without remesh, and conservative remap (one thread; the crate is serial).
//!
//! Run: `cargo bench -p thm-benchmarks --bench vpn_mesh`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use thm_benchmarks::pore_layer::{SmallMotion, layer_10k};
use thm_vpn_mesh::packing::overlap_contacts;
use thm_vpn_mesh::*;

fn bench(c: &mut Criterion) {
    let (cs, spec) = layer_10k();
    let contacts = overlap_contacts(&cs, 1e7);
    let mut g = c.benchmark_group("vpn_mesh_10k");
    g.sample_size(10);
    for n in [16u32, 32] {
        let s = MeshParams::new(
            Outline::Box {
                min: spec.box_min,
                max: spec.box_max,
            },
            n,
        )
        .validate()
        .unwrap();
        let pm = mesh_packing(&cs, &contacts, &s).unwrap();
        eprintln!(
            "{} circles, {n} segments: {} vertices, {} cells, {} channels",
            cs.len(),
            pm.mesh.vertices.len(),
            pm.mesh.n_cells(),
            pm.mesh.channels.len()
        );
        g.bench_function(format!("full_mesh_{n}seg"), |b| {
            b.iter(|| mesh_packing(black_box(&cs), &contacts, &s).unwrap())
        });
        // Geometry update: every circle moved a little.
        let small = SmallMotion::of(&cs);
        let motion = small.motion();
        let mut moved = pm.clone();
        let mut mm = MeshMotion::new();
        mm.update(&mut moved, &motion).unwrap();
        g.bench_function(format!("geometry_update_{n}seg"), |b| {
            b.iter(|| mm.update(black_box(&mut moved), &motion).unwrap())
        });
        // Remap: the moved mesh onto the mesh of the moved circles.
        let moved_circles: Vec<Circle> = cs
            .iter()
            .enumerate()
            .map(|(i, c)| Circle {
                centre: small.centre[i],
                radius: small.radius[i],
                owner: c.owner,
            })
            .collect();
        let new = mesh_packing(&moved_circles, &overlap_contacts(&moved_circles, 1e7), &s).unwrap();
        let q: Vec<f64> = (0..moved.mesh.n_cells())
            .map(|c| {
                if moved.mesh.cell_kind[c].is_fluid() {
                    moved.mesh.cell_volume(c)
                } else {
                    0.0
                }
            })
            .collect();
        let mut out = vec![0.0; new.mesh.n_cells()];
        g.bench_function(format!("remap_{n}seg"), |b| {
            b.iter(|| {
                let op = RemapOperator::new(black_box(&moved.mesh), &new.mesh).unwrap();
                op.apply(CellFilter::Fluid, &q, &mut out).unwrap();
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
