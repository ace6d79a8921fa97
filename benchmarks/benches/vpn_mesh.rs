//! Virtual pore network mesh of a 10 000-circle single layer: full mesh, geometry update
//! without remesh, and conservative remap (one thread; the crate is serial).
//!
//! Run: `cargo bench -p thm-benchmarks --bench vpn_mesh`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use thm_vpn_mesh::packing::{PackingSpec, overlap_contacts, random_packing};
use thm_vpn_mesh::*;

fn packing() -> (Vec<Circle>, PackingSpec) {
    // 10 000 circles of 4-8 mm at 10 % porosity fill about 0.557 m × 0.557 m; the packing of
    // a slightly larger square is cut to exactly 10 000.
    let side = 0.558;
    let spec = PackingSpec {
        box_max: [side, side],
        sweeps: 300,
        ..PackingSpec::paper_bar(7)
    };
    let mut cs = random_packing(&spec);
    assert!(cs.len() >= 10_000, "only {} circles", cs.len());
    cs.truncate(10_000);
    (cs, spec)
}

fn bench(c: &mut Criterion) {
    let (cs, spec) = packing();
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
        let k = cs.len();
        let vel: Vec<[f64; 2]> = (0..k)
            .map(|i| [2e-5 * (i as f64).sin(), 2e-5 * (i as f64).cos()])
            .collect();
        let omega: Vec<f64> = (0..k).map(|i| 0.002 * (0.3 * i as f64).sin()).collect();
        let rdot = vec![1e-7; k];
        let centre: Vec<[f64; 2]> = cs
            .iter()
            .zip(&vel)
            .map(|(c, v)| [c.centre[0] + v[0], c.centre[1] + v[1]])
            .collect();
        let radius: Vec<f64> = cs.iter().map(|c| c.radius + 1e-7).collect();
        let rotation = omega.clone();
        let motion = CircleMotion {
            centre: &centre,
            radius: &radius,
            rotation: &rotation,
            velocity: &vel,
            angular_velocity: &omega,
            radius_rate: &rdot,
        };
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
                centre: centre[i],
                radius: radius[i],
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
