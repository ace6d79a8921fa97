//! Once the pair list of an RVE is warm, its time step does not touch the heap: neither the
//! DEM steps (neighbour rebuilds included) nor the homogenised measures of `respond`. The
//! only test in this binary, so no other test allocates meanwhile.

use stats_alloc::{INSTRUMENTED_SYSTEM, Region, StatsAlloc};
use std::alloc::System;
use thm_rve::verification::consolidated_packing;
use thm_rve::*;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

#[test]
fn warm_rve_steps_do_not_allocate() {
    let (config, mut state, report) = consolidated_packing(48, 3, 0.01).unwrap();
    let config = config.with_friction(0.5).unwrap();
    let dt = report.time_step;
    // A fast simple shear (10⁻⁴ per step) with heating, so that the count includes pair-list
    // rebuilds, disks wrapped across the cell boundary and radii changing.
    let load = |k: u32| RveLoad {
        velocity_gradient: Mat2::new(0.0, 1e-4 / dt, 0.0, 0.0),
        temperature: config.params().reference_temperature + f64::from(k % 3),
        dt: 20.0 * dt,
        substeps: 20,
    };
    let mut stepper = RveStepper::new(config);
    for k in 0..30 {
        stepper.respond(&mut state, &load(k)).unwrap();
    }
    let anchor_before = state.anchor.cell;
    let region = Region::new(GLOBAL);
    for k in 0..30 {
        std::hint::black_box(stepper.respond(&mut state, &load(k)).unwrap());
    }
    let stats = region.change();
    assert_ne!(
        state.anchor.cell, anchor_before,
        "the count should include pair-list rebuilds"
    );
    assert_eq!(
        (stats.allocations, stats.reallocations),
        (0, 0),
        "{stats:?}"
    );
}
