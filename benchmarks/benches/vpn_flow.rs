//! One fluid sub-step of `thm-vpn-flow` (channel fluxes, pore update, closure) on a network of
//! about 100 000 pores, on 1 and 2 threads.
//!
//! Run: `cargo bench -p thm-benchmarks --bench vpn_flow`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use thm_vpn_flow::{
    FlowConfig, FlowParameters, FlowState, FlowStepper, LinearLiquidIdealGas,
    LinearLiquidIdealGasParameters, Network,
};
use thm_vpn_mesh::{CellKind, PoreMesh};

fn setup() -> (Network, FlowState, LinearLiquidIdealGas) {
    // 224 × 224 squares, two triangles each: 100 352 pores, ~150 000 T2T channels.
    let n = 224;
    let mesh = PoreMesh::structured_rectangle(n, n, 0.2, 0.2, 8e-3, 0.002, |_| CellKind::Fluid)
        .expect("mesh");
    let net = Network::from_mesh(&mesh, &[], 0.002).expect("network");
    let fluid =
        LinearLiquidIdealGas::new(LinearLiquidIdealGasParameters::water_air()).expect("fluid");
    let np = net.n_pores();
    // A pressure gradient and a mix of saturated, dry and two-phase pores so that every branch
    // of the channel model runs.
    let pressure: Vec<f64> = (0..np).map(|i| 1e6 + 1e3 * (i % 97) as f64).collect();
    let alpha: Vec<f64> = (0..np)
        .map(|i| match i % 3 {
            0 => 1.0,
            1 => 0.0,
            _ => 0.5,
        })
        .collect();
    let state = FlowState::from_pressure(
        &net,
        net.pore_volumes(&mesh),
        vec![293.15; np],
        &pressure,
        &alpha,
        &fluid,
    )
    .expect("state");
    (net, state, fluid)
}

fn bench(c: &mut Criterion) {
    let (net, state0, fluid) = setup();
    let config = FlowConfig::new(FlowParameters::default()).expect("config");
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let mut stepper = FlowStepper::new(config);
        let mut state = state0.clone();
        // A quarter of the initial stable sub-step: the state relaxes slowly over the
        // iterations and every call stays one sub-step (asserted).
        let dt = 0.25
            * pool
                .install(|| stepper.stable_substep(&net, &state, &fluid))
                .expect("limit")
                .dt;
        c.bench_function(
            &format!("vpn_flow/one_substep_100k_pores/{threads}_threads"),
            |b| {
                b.iter(|| {
                    let r = pool
                        .install(|| stepper.step(&net, &mut state, &fluid, &[], dt))
                        .expect("step");
                    assert_eq!(r.substeps, 1);
                    black_box(state.pressure[0])
                })
            },
        );
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
