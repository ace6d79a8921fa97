//! Per-stage times of the mesh geometry update on the 10 000-circle bench layer (16 segments),
//! medians of `REPS` repetitions each, one thread:
//!
//! `cargo run --profile bench -p thm-benchmarks --example mesh_stages [REPS]`

use std::hint::black_box;
use std::time::Instant;
use thm_benchmarks::pore_layer::{SmallMotion, layer_10k};
use thm_vpn_mesh::motion::{cell_area_rate, circle_frames, vertex_kinematics_in_frames};
use thm_vpn_mesh::packing::overlap_contacts;
use thm_vpn_mesh::*;

fn median_ms(reps: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..reps)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[reps / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let reps: usize = std::env::args().nth(1).map_or(Ok(200), |s| s.parse())?;
    let (cs, spec) = layer_10k();
    let contacts = overlap_contacts(&cs, 1e7);
    let s = MeshParams::new(
        Outline::Box {
            min: spec.box_min,
            max: spec.box_max,
        },
        16,
    )
    .validate()?;
    let mut pm = mesh_packing(&cs, &contacts, &s)?;
    let k = cs.len();
    let small = SmallMotion::of(&cs);
    let motion = small.motion();
    let mut mm = MeshMotion::new();
    mm.update(&mut pm, &motion)?;
    let full = median_ms(reps, || mm.update(black_box(&mut pm), &motion).unwrap());
    let valid = median_ms(reps, || motion.validate(k).unwrap());
    let mut frames = Vec::new();
    let fr = median_ms(reps, || circle_frames(black_box(&motion), &mut frames));
    let mut vel_v = vec![[0.0; 2]; pm.anchors.len()];
    let mut pos = pm.mesh.vertices.clone();
    let vk = median_ms(reps, || {
        vertex_kinematics_in_frames(&pm.anchors, &frames, &mut pos, &mut vel_v)
    });
    let mut rate = vec![0.0; pm.mesh.n_cells()];
    let cells = median_ms(reps, || {
        cell_area_rate(black_box(&pm.mesh), &vel_v, &mut rate).unwrap()
    });
    let faces = median_ms(reps, || pm.mesh.update_face_geometry());
    let channels = median_ms(reps, || pm.mesh.update_channel_geometry(Some(0.5.into())));
    println!(
        "{} vertices, {} cells, {} faces, {} channels",
        pm.mesh.vertices.len(),
        pm.mesh.n_cells(),
        pm.mesh.face_vertices.len(),
        pm.mesh.channels.len()
    );
    // A hash of the geometry after one update from the mesh state: a change of the stage
    // code that should keep the bits can be checked against the previous binary.
    let mut pm2 = mesh_packing(&cs, &contacts, &s)?;
    let mut mm2 = MeshMotion::new();
    mm2.update(&mut pm2, &motion)?;
    let m = &pm2.mesh;
    let bits = m
        .cell_area
        .iter()
        .chain(m.cell_centroid.iter().flatten())
        .chain(mm2.volume_rate())
        .chain(&m.face_length)
        .chain(m.face_normal.iter().flatten())
        .chain(m.face_centroid.iter().flatten())
        .chain(&m.channels.length)
        .chain(&m.channels.aperture)
        .fold(0xcbf2_9ce4_8422_2325u64, |h, x| {
            (h ^ x.to_bits()).wrapping_mul(0x0100_0000_01b3)
        });
    println!("geometry hash {bits:016x}");
    println!(
        "update {full:.3} ms: validate {valid:.3}, frames {fr:.3}, vertices {vk:.3}, cell rate {cells:.3}, faces {faces:.3}, channels {channels:.3}"
    );
    Ok(())
}
