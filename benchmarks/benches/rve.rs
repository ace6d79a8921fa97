//! Disk-steps per second of a batch of RVEs (B-Sect. 5.3.1: 800 RVEs × 400 disks), 1 and 2
//! threads. Each iteration advances every RVE by one macroscopic step of `SUBSTEPS` DEM steps
//! under a slow simple shear; throughput is counted in disk-steps.
//!
//! `cargo bench -p thm-benchmarks --bench rve`; `RVE_BENCH_COUNT` sets the number of RVEs.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use thm_rve::verification::consolidated_packing;
use thm_rve::{Mat2, RveBatch, RveLoad, RveState};

const SUBSTEPS: u32 = 10;

fn bench_batch(c: &mut Criterion) {
    let count: usize = std::env::var("RVE_BENCH_COUNT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(800);
    let (config, packing, report) = consolidated_packing(400, 1, 0.01).unwrap();
    let config = config
        .with_friction(0.5)
        .unwrap()
        .with_damping(0.1)
        .unwrap();
    let dt = report.time_step;
    let disks = packing.len();
    let load = RveLoad {
        velocity_gradient: Mat2::new(0.0, 1e-6 / dt, 0.0, 0.0),
        temperature: config.params().reference_temperature,
        dt: dt * f64::from(SUBSTEPS),
        substeps: SUBSTEPS,
    };
    let loads = vec![load; count];
    let mut group = c.benchmark_group("rve_batch");
    group.sample_size(10);
    group.throughput(Throughput::Elements(
        (count * disks) as u64 * u64::from(SUBSTEPS),
    ));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut states: Vec<RveState> = vec![packing.clone(); count];
        let mut batch = RveBatch::new(config, count);
        // Warm the neighbour lists once.
        pool.install(|| batch.respond(&mut states, &loads).unwrap());
        if threads == 1 {
            let bytes: usize = states.iter().map(|s| s.heap_bytes()).sum();
            let per_disk = |b: usize| b as f64 / (count * disks) as f64;
            eprintln!(
                "rve_batch: {count} RVEs x {disks} disks, {} contacts listed per RVE, heap {:.0} bytes per disk in the states + {:.0} in the batch scratch",
                states[0].contacts.len(),
                per_disk(bytes),
                per_disk(batch.heap_bytes())
            );
        }
        group.bench_function(format!("{count}x{disks}/threads={threads}"), |b| {
            b.iter(|| {
                pool.install(|| black_box(batch.respond(&mut states, &loads).unwrap()));
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_batch);
criterion_main!(benches);
