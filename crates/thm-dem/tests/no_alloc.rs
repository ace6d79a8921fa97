//! Once the contact lists are warm, a time step does not touch the heap (serial and parallel
//! paths). The only test in this binary, so no other test allocates meanwhile.

use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};
use std::alloc::System;
use thm_dem::packing::lattice_packing;
use thm_dem::*;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn warm_state(kin: Kinematics, counts: [usize; 3]) -> (DemState, Stepper<CohesiveFrictional>) {
    let packing = lattice_packing(kin, counts, 1e-3, 3).unwrap();
    let mut state = packing.to_state(2600.0, 293.15).unwrap();
    for (i, v) in state.particles.velocity.iter_mut().enumerate() {
        let s = ((i * 7919) % 13) as f64 / 13.0 - 0.5;
        *v = Vec3::new(
            0.02 * s,
            -0.01 * s,
            if kin.is_planar() { 0.0 } else { 0.015 * s },
        );
    }
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .unwrap();
    let dt = 0.5 * critical_time_step(&state, &law);
    // A small skin so that neighbour searches (and history merges) happen during the count.
    let params = StepperParams {
        time_step: dt,
        damping: 0.0,
        gravity: [0.0, -9.81, 0.0],
        verlet_skin: 1e-7,
    };
    let mut stepper = Stepper::new(law, params.validate().unwrap());
    stepper.run(&mut state, 200).unwrap();
    (state, stepper)
}

#[test]
fn warm_steps_do_not_allocate() {
    for (kin, counts) in [
        (Kinematics::SpheresInPlane, [20, 20, 1]), // serial path
        (Kinematics::SpheresInPlane, [60, 60, 1]), // parallel path
        (Kinematics::Spheres3d, [12, 12, 12]),
    ] {
        let (mut state, mut stepper) = warm_state(kin, counts);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| {
            // Warm rayon's work queues as well as the contact lists.
            stepper.run(&mut state, 300).unwrap();
            let generation = state.contact_generation;
            let region = Region::new(GLOBAL);
            stepper.run(&mut state, 300).unwrap();
            let stats = region.change();
            assert!(
                state.contact_generation > generation,
                "{kin:?}: the count should include neighbour searches"
            );
            assert_eq!(
                (stats.allocations, stats.reallocations),
                (0, 0),
                "{kin:?} {counts:?}: {stats:?}"
            );
        });
    }
}
