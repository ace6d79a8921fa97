//! The linearly implicit pressure step: conservation, stability far beyond the explicit
//! limit, agreement with the explicit step as the sub-step shrinks, and the steady state
//! between two reservoirs.

mod common;

use common::{config, random_closed_network, water_air};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thm_vpn_flow::{BoundaryCondition, FlowState, FlowStepper, Network, NetworkParts};

/// A chain of `n` pores (2 mm channels of aperture 3 µm), with a pressure reservoir at
/// each end when `reservoirs` is given (liquid enters).
fn chain(n: usize, reservoirs: Option<[f64; 2]>) -> Network {
    let mut parts = NetworkParts {
        n_pores: n,
        width: 8e-3,
        channel_pores: (0..n - 1).map(|i| [i as u32, i as u32 + 1]).collect(),
        channel_length: vec![2e-3; n - 1],
        channel_aperture: vec![3e-6; n - 1],
        ..Default::default()
    };
    if let Some([left, right]) = reservoirs {
        parts.boundaries = [left, right]
            .map(|pressure| BoundaryCondition::Pressure {
                pressure,
                temperature: 293.15,
                entering_liquid_fraction: 1.0,
            })
            .to_vec();
        parts.link_pore = vec![0, n as u32 - 1];
        parts.link_group = vec![0, 1];
        // Half a channel to each reservoir: the chain is a uniform resistor ladder.
        parts.link_length = vec![1e-3; 2];
        parts.link_aperture = vec![3e-6; 2];
        parts.link_face_length = vec![1e-3; 2];
    }
    Network::new(parts).unwrap()
}

fn check_conservation(seed: u64, n: usize, volume_rate_scale: f64) {
    let (net, mut state) = random_closed_network(seed, n);
    let fluid = water_air();
    let mut stepper = FlowStepper::new(config());
    let explicit_limit = stepper.stable_substep(&net, &state, &fluid).unwrap().dt;
    let (q0, p0) = (state.total_liquid_mass(), state.total_gas_mass());
    let gas_start = state.gas_mass.clone();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let dv_dt: Vec<f64> = (0..n)
        .map(|i| rng.random_range(-1.0..1.0) * volume_rate_scale * state.volume[i])
        .collect();
    // Outer steps of 1000 explicit limits.
    let dt = 1e3 * explicit_limit;
    for _ in 0..5 {
        stepper
            .implicit_step(&net, &mut state, &fluid, &dv_dt, dt)
            .unwrap();
    }
    let (q1, p1) = (state.total_liquid_mass(), state.total_gas_mass());
    let tol = 64.0 * n as f64 * f64::EPSILON;
    assert!((q1 - q0).abs() <= tol * q0, "liquid {q0} -> {q1}");
    assert!((p1 - p0).abs() <= tol * p0, "gas {p0} -> {p1}");
    for p in 0..n {
        assert!(state.liquid_mass[p] >= 0.0 && state.gas_mass[p] >= 0.0);
        assert!((0.0..=1.0).contains(&state.liquid_fraction[p]));
        assert!(state.pressure[p].is_finite() && state.pressure[p] > 0.0);
    }
    assert!(gas_start.iter().zip(&state.gas_mass).any(|(a, b)| a != b));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Phase masses of a closed network with moving walls are conserved to round-off by
    /// implicit steps 1000 times the explicit limit, and stay non-negative.
    #[test]
    fn implicit_step_conserves_mass_per_phase(
        seed in 0u64..1_000_000,
        n in 3usize..60,
        rate in 0.0f64..1e-3,
    ) {
        check_conservation(seed, n, rate);
    }
}

#[test]
fn water_pores_relax_monotonically_with_steps_far_beyond_the_explicit_limit() {
    let net = chain(2, None);
    let fluid = water_air();
    let mut state = FlowState::from_pressure(
        &net,
        vec![1e-9, 2e-9],
        vec![293.15; 2],
        &[5e6, 1e6],
        &[1.0, 1.0],
        &fluid,
    )
    .unwrap();
    let mut stepper = FlowStepper::new(config());
    let explicit = stepper.stable_substep(&net, &state, &fluid).unwrap().dt;
    let dt = 0.1;
    assert!(dt > 1e3 * explicit, "explicit limit {explicit} s");
    let mut last_gap = state.pressure[0] - state.pressure[1];
    for _ in 0..20 {
        let r = stepper
            .implicit_step(&net, &mut state, &fluid, &[], dt)
            .unwrap();
        assert_eq!(r.substeps, 1);
        let gap = state.pressure[0] - state.pressure[1];
        // Backward Euler with a step 2000 times the relaxation time lands on the common
        // pressure (gap/(1 + h/τ) ≈ 2 kPa after the first step, then far less), and the
        // Newton iterations make the closure agree with it to 1e-9 of P.
        assert!(
            gap.abs() <= 1e-3 * last_gap.abs() || gap.abs() < 1e-2,
            "gap {gap} after {last_gap}"
        );
        last_gap = gap;
    }
    assert!(
        last_gap.abs() < 1.0,
        "pressures not equalised: gap {last_gap} Pa"
    );
}

/// Pressures of a chain of 12 pores between reservoirs at 3 and 1 MPa, every third pore
/// 30 % air when `two_phase`, after `t_end` with implicit sub-steps of `h` (`None`: explicit
/// outer steps of 10⁻⁶ s).
fn chain_pressures(h: Option<f64>, t_end: f64, two_phase: bool) -> Vec<f64> {
    let n = 12;
    let net = chain(n, Some([3e6, 1e6]));
    let fluid = water_air();
    let alpha: Vec<f64> = (0..n)
        .map(|i| if two_phase && i % 3 == 2 { 0.7 } else { 1.0 })
        .collect();
    let mut state = FlowState::from_pressure(
        &net,
        vec![1e-9; n],
        vec![293.15; n],
        &vec![2e6; n],
        &alpha,
        &fluid,
    )
    .unwrap();
    let mut stepper = FlowStepper::new(config());
    let dt = h.unwrap_or(1e-6);
    for _ in 0..(t_end / dt).round() as usize {
        match h {
            Some(h) => stepper.implicit_step(&net, &mut state, &fluid, &[], h),
            None => stepper.step(&net, &mut state, &fluid, &[], dt),
        }
        .unwrap();
    }
    state.pressure
}

#[test]
fn implicit_step_converges_to_the_explicit_solution_at_first_order() {
    let t_end = 2e-3;
    // Explicit reference with outer steps of 1e-6 s (its sub-steps, ≤ 1e-6 s, are 40 times
    // shorter than the finest implicit step).
    let reference = chain_pressures(None, t_end, true);
    let error = |h: f64| {
        chain_pressures(Some(h), t_end, true)
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let (e1, e2, e3) = (error(1e-4), error(5e-5), error(2.5e-5));
    // Backward Euler: the error halves with the step (observed order within 0.8..1.3).
    for (a, b) in [(e1, e2), (e2, e3)] {
        let order = (a / b).log2();
        assert!((0.8..1.3).contains(&order), "errors {e1} {e2} {e3} Pa");
    }
    assert!(e3 < 2e4, "error {e3} Pa at h = 2.5e-5 s");
}

#[test]
fn long_implicit_steps_reach_the_steady_state_between_two_reservoirs() {
    let p = chain_pressures(Some(0.05), 1.0, false);
    let n = p.len();
    // A uniform ladder (half resistances to the reservoirs): P falls linearly from 3 MPa
    // to 1 MPa, up to the liquid's compressibility. The mass rate is uniform, so each drop
    // scales with 1/ρ_up, and ρ varies by Δρ/ρ = ΔP/K ≈ 9e-4 along the chain: the profile
    // bows by at most ΔP (Δρ/ρ) / 4 ≈ 450 Pa.
    for (i, pi) in p.iter().enumerate() {
        let exact = 3e6 - 2e6 * (i as f64 + 0.5) / n as f64;
        assert!(
            (pi - exact).abs() < 450.0,
            "pore {i}: {pi} Pa vs {exact} Pa"
        );
    }
}

#[test]
fn implicit_runs_on_1_and_2_threads_give_identical_bits() {
    let (net, state0) = random_closed_network(11, 400);
    let fluid = water_air();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut state = state0.clone();
            let mut stepper = FlowStepper::new(config());
            let dv: Vec<f64> = state.volume.iter().map(|v| 1e-4 * v).collect();
            for _ in 0..2 {
                stepper
                    .implicit_step(&net, &mut state, &fluid, &dv, 1e-3)
                    .unwrap();
            }
            state
        })
    };
    let (a, b) = (run(1), run(2));
    for (x, y) in [
        (&a.liquid_mass, &b.liquid_mass),
        (&a.gas_mass, &b.gas_mass),
        (&a.pressure, &b.pressure),
        (&a.liquid_fraction, &b.liquid_fraction),
    ] {
        assert!(x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits()));
    }
}

/// When the implicit sub-steps run out, the error names the pore and the reason of the last
/// rejected sub-step (it named no pore). A tiny pore of gas at 5 MPa beside a large one at
/// 1 MPa: the first sub-step of 0.1 s would take all its gas out (gas positivity); with one
/// sub-step allowed, that ends the step.
#[test]
fn running_out_of_sub_steps_names_the_pore_and_the_reason() {
    use thm_vpn_flow::{FlowConfig, FlowError, FlowParameters};
    let net = chain(2, None);
    let fluid = water_air();
    let mut state = FlowState::from_pressure(
        &net,
        vec![1e-9, 1e-15],
        vec![293.15; 2],
        &[1e6, 5e6],
        &[1.0, 0.0],
        &fluid,
    )
    .unwrap();
    let config = FlowConfig::new(FlowParameters {
        max_substeps: 1,
        ..FlowParameters::default()
    })
    .unwrap();
    let mut stepper = FlowStepper::new(config);
    let err = stepper
        .implicit_step(&net, &mut state, &fluid, &[], 0.1)
        .unwrap_err();
    let FlowError::TooManySubsteps { pore, limit, .. } = &err else {
        panic!("expected TooManySubsteps, got {err}")
    };
    assert_eq!((*pore, *limit), (1, "gas positivity"), "{err}");
}
