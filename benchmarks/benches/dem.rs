//! Particle-steps per second of `thm-dem` on bonded packings (A-Table 1 cohesive law,
//! damping 0.08): 1 000, 10 000 and 100 000 particles, plane-constrained spheres and 3D
//! spheres, on 1 and 2 rayon threads.
//!
//! `cargo bench -p thm-benchmarks --bench dem` (criterion reports the median time per
//! iteration and, from the throughput, particle-steps per second).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::time::Duration;
use thm_dem::packing::lattice_packing;
use thm_dem::*;

const STEPS_PER_ITER: u64 = 10;

fn setup(kin: Kinematics, n: usize) -> (DemState, Stepper<CohesiveFrictional>) {
    let counts = match (kin.is_planar(), n) {
        (true, 1_000) => [40, 25, 1],
        (true, 10_000) => [100, 100, 1],
        (true, _) => [400, 250, 1],
        (false, 1_000) => [10, 10, 10],
        (false, 10_000) => [25, 20, 20],
        (false, _) => [50, 50, 40],
    };
    let packing = lattice_packing(kin, counts, 1e-3, 42).expect("packing");
    let mut state = packing.to_state(2600.0, 293.15).expect("state");
    // A shaken bonded solid: every bond works, some contacts open and close.
    for (i, v) in state.particles.velocity.iter_mut().enumerate() {
        let s = ((i * 7919) % 101) as f64 / 101.0 - 0.5;
        *v = Vec3::new(
            0.02 * s,
            -0.015 * s,
            if kin.is_planar() { 0.0 } else { 0.01 * s },
        );
    }
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .expect("law");
    let dt = 0.5 * critical_time_step(&state, &law);
    let params = StepperParams {
        time_step: dt,
        damping: 0.08,
        gravity: [0.0; 3],
        verlet_skin: 5e-5,
    };
    let mut stepper = Stepper::new(law, params.validate().expect("params"));
    stepper.run(&mut state, 20).expect("warm-up");
    (state, stepper)
}

fn bench_dem(c: &mut Criterion) {
    let sizes: Vec<usize> = match std::env::var("THM_DEM_BENCH_SIZES") {
        Ok(s) => s.split(',').filter_map(|x| x.trim().parse().ok()).collect(),
        Err(_) => vec![1_000, 10_000, 100_000],
    };
    for kin in [Kinematics::SpheresInPlane, Kinematics::Spheres3d] {
        let name = if kin.is_planar() {
            "dem_step/plane"
        } else {
            "dem_step/3d"
        };
        let mut group = c.benchmark_group(name);
        group
            .sample_size(10)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
        for &n in &sizes {
            let (state0, _) = setup(kin, n);
            group.throughput(Throughput::Elements(
                state0.particles.len() as u64 * STEPS_PER_ITER,
            ));
            for threads in [1usize, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("pool");
                let (mut state, mut stepper) = setup(kin, n);
                group.bench_with_input(BenchmarkId::new(format!("{threads}t"), n), &n, |b, _| {
                    b.iter(|| {
                        pool.install(|| stepper.run(&mut state, STEPS_PER_ITER))
                            .expect("step")
                    })
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, bench_dem);
criterion_main!(benches);
