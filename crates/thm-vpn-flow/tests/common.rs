//! Helpers shared by the integration tests: random closed networks.
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thm_vpn_flow::{
    FlowConfig, FlowParameters, FlowState, LinearLiquidIdealGas, LinearLiquidIdealGasParameters,
    Network, NetworkParts,
};

pub fn water_air() -> LinearLiquidIdealGas {
    LinearLiquidIdealGas::new(LinearLiquidIdealGasParameters::water_air()).unwrap()
}

pub fn config() -> FlowConfig {
    FlowConfig::new(FlowParameters::default()).unwrap()
}

/// A random connected closed network: a ring through all pores plus random chords, random
/// apertures (1–5 µm), lengths (1–3 mm), volumes, pressures (1–3 MPa) and liquid fractions
/// (a third pure liquid, a third pure gas, a third mixed; the pore at the highest pressure
/// holds gas).
pub fn random_closed_network(seed: u64, n: usize) -> (Network, FlowState) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pores = Vec::new();
    for i in 0..n {
        pores.push([i as u32, ((i + 1) % n) as u32]);
    }
    for _ in 0..n {
        let a = rng.random_range(0..n as u32);
        let b = rng.random_range(0..n as u32);
        if a != b {
            pores.push([a, b]);
        }
    }
    let nc = pores.len();
    let parts = NetworkParts {
        n_pores: n,
        width: 6e-3,
        channel_length: (0..nc).map(|_| rng.random_range(1e-3..3e-3)).collect(),
        channel_aperture: (0..nc).map(|_| rng.random_range(1e-6..5e-6)).collect(),
        channel_pores: pores,
        ..Default::default()
    };
    let net = Network::new(parts).unwrap();
    let volume: Vec<f64> = (0..n).map(|_| rng.random_range(0.5e-9..2e-9)).collect();
    let pressure: Vec<f64> = (0..n).map(|_| rng.random_range(1e6..3e6)).collect();
    let mut alpha: Vec<f64> = (0..n)
        .map(|_| match rng.random_range(0..3) {
            0 => 1.0,
            1 => 0.0,
            _ => rng.random_range(0.05..0.95),
        })
        .collect();
    // The pore at the highest pressure holds gas: it is upwind of all its channels, so gas
    // certainly moves (the conservation tests are not vacuous).
    let highest = (0..n)
        .max_by(|&a, &b| pressure[a].total_cmp(&pressure[b]))
        .unwrap();
    alpha[highest] = alpha[highest].min(0.5);
    let state = FlowState::from_pressure(
        &net,
        volume,
        vec![293.15; n],
        &pressure,
        &alpha,
        &water_air(),
    )
    .unwrap();
    (net, state)
}
