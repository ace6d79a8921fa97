//! Material-point updates per second of `thm-mpm` on a 2D granular column collapse:
//! 10⁴ and 10⁵ points (2 × 2 per cell), three materials behind the constitutive seam
//! (Drucker–Prager, linear thermo-elastic, stress-free conductor = grid cost only),
//! 1 and 2 threads. One criterion iteration = one full explicit step (P2G, grid update,
//! G2P, constitutive update, time-step check), so elements/s = point-steps/s.
//!
//! Run: `cargo bench -p thm-benchmarks --bench mpm`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use thm_benchmarks::mpm_column::column;
use thm_mpm::{
    Constitutive, DruckerPrager, DruckerPragerParameters, LinearThermoElastic, StresslessConductor,
    ThermoElasticParameters,
};

const DT: f64 = 1e-4;

fn bench_material<M: Constitutive>(c: &mut Criterion, name: &str, material: &M) {
    let mut group = c.benchmark_group(format!("mpm_column/{name}"));
    group.sample_size(10);
    group.warm_up_time(std::time::Duration::from_secs(1));
    group.measurement_time(std::time::Duration::from_secs(4));
    for side in [50usize, 158] {
        let (mpm0, state0) = column(side, material);
        let n = state0.points.len();
        group.throughput(Throughput::Elements(n as u64));
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            let mut mpm = mpm0.clone();
            let mut state = state0.clone();
            group.bench_function(
                BenchmarkId::new(format!("{n}pts"), format!("{threads}t")),
                |b| {
                    pool.install(|| {
                        b.iter(|| {
                            mpm.step(&mut state, material, DT).expect("stable step");
                            black_box(&state.points.position[0]);
                        })
                    })
                },
            );
        }
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    let dp = DruckerPrager::new(&DruckerPragerParameters {
        youngs_modulus: 1e6,
        poisson_ratio: 0.3,
        friction_angle_deg: 30.0,
        dilatancy_angle_deg: 0.0,
        cohesion: 0.0,
        thermal_expansion: 0.0,
        conductivity: [1.0, 1.0, 0.0],
    })
    .expect("valid");
    bench_material(c, "drucker_prager", &dp);
    let el = LinearThermoElastic::new(&ThermoElasticParameters {
        youngs_modulus: 1e6,
        poisson_ratio: 0.3,
        thermal_expansion: 1e-5,
        conductivity: [1.0, 1.0, 0.0],
    })
    .expect("valid");
    bench_material(c, "elastic", &el);
    let cheap = StresslessConductor::new([1.0, 1.0, 0.0]).expect("valid");
    bench_material(c, "stressless", &cheap);
}

criterion_group!(mpm_benches, benches);
criterion_main!(mpm_benches);
