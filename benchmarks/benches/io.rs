//! Writing one VTU frame of 10⁶ particles with five fields (radius, velocity, angular
//! velocity, temperature, mass), appended raw and appended base64.
//!
//! Target: under 0.5 s per frame and no more than twice the bytes of the raw data
//! (positions + fields as f64). The file-to-raw byte ratio is printed once per encoding.

use criterion::{Criterion, criterion_group, criterion_main};
use thm_io::{Encoding, FieldValues, UnstructuredGrid};

const N: usize = 1_000_000;

fn frame(c: &mut Criterion) {
    let pos: Vec<[f64; 3]> = (0..N)
        .map(|i| {
            let t = i as f64;
            [t.sin(), t.cos(), 1e-6 * t]
        })
        .collect();
    let radius: Vec<f64> = (0..N)
        .map(|i| 1e-3 * (1.0 + (i % 7) as f64 * 0.1))
        .collect();
    let vel: Vec<[f64; 3]> = pos.iter().map(|p| [p[1], -p[0], 0.1]).collect();
    let omega: Vec<[f64; 3]> = pos.iter().map(|p| [0.0, 0.0, p[2]]).collect();
    let temp: Vec<f64> = (0..N).map(|i| 293.15 + (i % 100) as f64).collect();
    let mass: Vec<f64> = radius
        .iter()
        .map(|r| 2650.0 * 4.0 / 3.0 * std::f64::consts::PI * r * r * r)
        .collect();
    let grid = UnstructuredGrid::particles(&pos)
        .with_point_field("radius [m]", FieldValues::Scalar(&radius))
        .with_point_field("velocity [m/s]", FieldValues::Vector3(&vel))
        .with_point_field("angular_velocity [rad/s]", FieldValues::Vector3(&omega))
        .with_point_field("temperature [K]", FieldValues::Scalar(&temp))
        .with_point_field("mass [kg]", FieldValues::Scalar(&mass));
    let raw_bytes = N * 8 * (3 + 1 + 3 + 3 + 1 + 1);
    let dir = std::env::temp_dir().join(format!("thm-io-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).ok();
    let mut g = c.benchmark_group("io_vtu_1e6_particles_5_fields");
    g.sample_size(10);
    for (enc, name) in [(Encoding::Raw, "raw"), (Encoding::Base64, "base64")] {
        let path = dir.join(format!("frame_{name}.vtu"));
        if let Err(e) = grid.write_vtu(&path, enc) {
            eprintln!("cannot write {}: {e}", path.display());
            return;
        }
        let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        eprintln!(
            "{name}: file {bytes} B, raw data {raw_bytes} B, ratio {:.3}",
            bytes as f64 / raw_bytes as f64
        );
        g.bench_function(name, |b| {
            b.iter(|| grid.write_vtu(&path, enc).is_ok());
        });
    }
    g.finish();
    std::fs::remove_dir_all(&dir).ok();
}

criterion_group!(benches, frame);
criterion_main!(benches);
