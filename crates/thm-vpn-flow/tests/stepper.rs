//! Behaviour of the explicit stepper: exact channel rates, conservation, boundary conditions,
//! forces, parity, save/restore and typed errors.

mod common;

use common::{config, random_closed_network, water_air};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use thm_vpn_flow::channel::{poiseuille_flow_rate, two_layer_flow};
use thm_vpn_flow::stepper::{ChannelFlux, channel_fluxes};
use thm_vpn_flow::{
    BoundaryCondition, ClosureFailure, FlowError, FlowState, FlowStepper, Network, NetworkParts,
    Phase, PoreFluid, add_sphere_forces,
};
use thm_vpn_mesh::{BoundarySide, CellKind, PoreMesh};

fn two_pores(aperture: f64) -> Network {
    Network::new(NetworkParts {
        n_pores: 2,
        width: 8e-3,
        channel_pores: vec![[0, 1]],
        channel_length: vec![2e-3],
        channel_aperture: vec![aperture],
        channel_direction: vec![[1.0, 0.0]],
        channel_contact: vec![0],
        ..Default::default()
    })
    .unwrap()
}

#[test]
fn single_channel_rate_is_poiseuille_times_width() {
    let net = two_pores(3e-6);
    let fluid = water_air();
    let mut state = FlowState::from_pressure(
        &net,
        vec![1e-9; 2],
        vec![293.15; 2],
        &[5e6, 1e5],
        &[1.0, 1.0],
        &fluid,
    )
    .unwrap();
    let mut stepper = FlowStepper::new(config());
    let limit = stepper.stable_substep(&net, &state, &fluid).unwrap();
    let f = stepper.channel_fluxes()[0];
    let g = (state.pressure[0] - state.pressure[1]) / 2e-3;
    let expected = state.liquid_density[0] * poiseuille_flow_rate(3e-6, g, 10.02e-4) * 8e-3;
    assert!((f.liquid - expected).abs() <= 1e-14 * expected);
    assert_eq!(f.gas, 0.0);
    // One stable sub-step moves exactly rate × dt from pore 0 to pore 1.
    let (m0, m1) = (state.liquid_mass[0], state.liquid_mass[1]);
    let r = stepper
        .step(&net, &mut state, &fluid, &[], limit.dt)
        .unwrap();
    assert_eq!(r.substeps, 1);
    assert!((m0 - state.liquid_mass[0] - expected * limit.dt).abs() <= 1e-15 * m0);
    assert!((state.liquid_mass[1] - m1 - expected * limit.dt).abs() <= 1e-15 * m1);
}

#[test]
fn two_pores_relax_stably_to_a_common_pressure() {
    let net = two_pores(3e-6);
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
    let mut last_gap = state.pressure[0] - state.pressure[1];
    for _ in 0..50 {
        stepper.step(&net, &mut state, &fluid, &[], 1e-3).unwrap();
        let gap = state.pressure[0] - state.pressure[1];
        // Stable: the gap decays (it may change sign once it is at round-off of P).
        assert!(
            gap.abs() <= last_gap.abs() || gap.abs() <= 1e-11 * state.pressure[0],
            "gap {gap} after {last_gap}"
        );
        last_gap = gap;
    }
    assert!(last_gap < 1.0, "pressures not equalised: gap {last_gap} Pa");
}

fn check_conservation(seed: u64, n: usize, steps: usize, volume_rate_scale: f64) {
    let (net, mut state) = random_closed_network(seed, n);
    let fluid = water_air();
    let mut stepper = FlowStepper::new(config());
    let (q0, p0) = (state.total_liquid_mass(), state.total_gas_mass());
    let gas_start = state.gas_mass.clone();
    // Moving walls: a random dV/dt per pore, small enough to keep pure-liquid pores in
    // compression.
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let dv_dt: Vec<f64> = (0..n)
        .map(|i| rng.random_range(-1.0..1.0) * volume_rate_scale * state.volume[i])
        .collect();
    let mut substeps = 0;
    for _ in 0..steps {
        substeps += stepper
            .step(&net, &mut state, &fluid, &dv_dt, 1e-4)
            .unwrap()
            .substeps;
    }
    let (q1, p1) = (state.total_liquid_mass(), state.total_gas_mass());
    // Round-off: every transfer is added to one pore and subtracted from another, so each
    // sub-step changes a phase's total only by the roundings of its pore updates, at most
    // ε/2 of each pore's mass, i.e. ε/2 of the total; the final sums of n terms add n·ε.
    // Bound: (substeps/2 + n)·ε relative (one seed ran 3 205 sub-steps and drifted 530 ε).
    let tol = (substeps as f64 / 2.0 + n as f64) * f64::EPSILON;
    assert!((q1 - q0).abs() <= tol * q0, "liquid {q0} -> {q1}");
    assert!((p1 - p0).abs() <= tol * p0, "gas {p0} -> {p1}");
    // Positivity and range invariants.
    for p in 0..n {
        assert!(state.liquid_mass[p] >= 0.0 && state.gas_mass[p] >= 0.0);
        assert!((0.0..=1.0).contains(&state.liquid_fraction[p]));
    }
    // Gas did move between pores (the test is not vacuous).
    assert!(gas_start.iter().zip(&state.gas_mass).any(|(a, b)| a != b));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn mass_per_phase_is_conserved_on_closed_networks_with_moving_walls(
        seed in 0u64..1_000_000,
        n in 3usize..60,
        rate in 0.0f64..1e-3,
    ) {
        check_conservation(seed, n, 5, rate);
    }
}

#[test]
fn pores_closed_after_a_step_satisfy_the_closure() {
    let (net, mut state) = random_closed_network(7, 40);
    let fluid = water_air();
    let mut stepper = FlowStepper::new(config());
    for _ in 0..5 {
        stepper.step(&net, &mut state, &fluid, &[], 1e-4).unwrap();
    }
    for p in 0..40 {
        let a = state.liquid_fraction[p];
        assert!((0.0..=1.0).contains(&a));
        let v = state.volume[p];
        assert!(
            (a * state.liquid_density[p] * v - state.liquid_mass[p]).abs()
                <= 1e-13 * state.liquid_mass[p].max(1e-30)
        );
        assert!(
            ((1.0 - a) * state.gas_density[p] * v - state.gas_mass[p]).abs()
                <= 1e-13 * state.gas_mass[p].max(1e-30)
        );
        let pq = fluid
            .density(Phase::Gas, state.pressure[p], state.temperature[p])
            .unwrap();
        if a < 1.0 {
            assert!((pq - state.gas_density[p]).abs() <= 1e-9 * pq);
        }
    }
}

#[test]
fn serial_and_parallel_runs_give_identical_bits() {
    let (net, state0) = random_closed_network(11, 5000);
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
                let r = stepper.step(&net, &mut state, &fluid, &dv, 2e-6).unwrap();
                assert!(r.substeps >= 2, "exercise sub-cycling");
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

#[test]
fn save_restore_round_trip_continues_identically() {
    let (net, mut state) = random_closed_network(5, 50);
    let fluid = water_air();
    let mut stepper = FlowStepper::new(config());
    for _ in 0..3 {
        stepper.step(&net, &mut state, &fluid, &[], 1e-4).unwrap();
    }
    let json = serde_json::to_string(&state).unwrap();
    let mut restored: FlowState = serde_json::from_str(&json).unwrap();
    assert_eq!(restored, state);
    let net_json = serde_json::to_string(&net).unwrap();
    let net2: Network = serde_json::from_str(&net_json).unwrap();
    let mut stepper2 = FlowStepper::new(config());
    for _ in 0..3 {
        stepper.step(&net, &mut state, &fluid, &[], 1e-4).unwrap();
        stepper2
            .step(&net2, &mut restored, &fluid, &[], 1e-4)
            .unwrap();
    }
    assert_eq!(restored, state);
}

#[test]
fn prescribed_mass_rate_adds_exactly_rate_times_time() {
    let parts = NetworkParts {
        n_pores: 3,
        width: 8e-3,
        channel_pores: vec![[0, 1], [1, 2]],
        channel_length: vec![2e-3; 2],
        channel_aperture: vec![2e-6; 2],
        boundaries: vec![BoundaryCondition::MassRate {
            liquid_mass_rate: 1e-9,
            gas_mass_rate: 2e-12,
        }],
        link_pore: vec![0, 0],
        link_group: vec![0, 0],
        link_length: vec![1e-3; 2],
        link_aperture: vec![2e-6; 2],
        link_face_length: vec![1e-3, 3e-3],
        ..Default::default()
    };
    let net = Network::new(parts).unwrap();
    let fluid = water_air();
    let mut state = FlowState::from_pressure(
        &net,
        vec![1e-9; 3],
        vec![293.15; 3],
        &[1e6; 3],
        &[0.5; 3],
        &fluid,
    )
    .unwrap();
    let (q0, p0) = (state.total_liquid_mass(), state.total_gas_mass());
    let mut stepper = FlowStepper::new(config());
    for _ in 0..10 {
        let r = stepper.step(&net, &mut state, &fluid, &[], 1e-3).unwrap();
        assert!((r.boundary_liquid_rate[0] - 1e-9).abs() <= 1e-24);
    }
    let added_q = state.total_liquid_mass() - q0;
    let added_p = state.total_gas_mass() - p0;
    assert!((added_q - 1e-11).abs() <= 1e-12 * q0, "{added_q}");
    assert!((added_p - 2e-14).abs() <= 1e-12 * p0, "{added_p}");
    assert!((state.boundary_liquid_inflow[0] - 1e-11).abs() <= 1e-24);
}

#[test]
fn prescribed_pressure_drives_the_pore_to_the_reservoir_and_brings_its_phase() {
    // One gas pore with a water reservoir at higher pressure: water enters, the pore
    // pressure rises towards the reservoir's.
    let parts = NetworkParts {
        n_pores: 1,
        width: 8e-3,
        boundaries: vec![BoundaryCondition::Pressure {
            pressure: 2e6,
            temperature: 293.15,
            entering_liquid_fraction: 1.0,
        }],
        link_pore: vec![0],
        link_group: vec![0],
        link_length: vec![1e-3],
        link_aperture: vec![3e-6],
        link_face_length: vec![2e-3],
        ..Default::default()
    };
    let net = Network::new(parts).unwrap();
    let fluid = water_air();
    let mut state =
        FlowState::from_pressure(&net, vec![1e-9], vec![293.15], &[1e6], &[0.0], &fluid).unwrap();
    let gas0 = state.gas_mass[0];
    let mut stepper = FlowStepper::new(config());
    for _ in 0..20 {
        stepper.step(&net, &mut state, &fluid, &[], 1e-2).unwrap();
    }
    assert!(state.liquid_mass[0] > 0.0);
    assert_eq!(
        state.gas_mass[0], gas0,
        "no gas may enter from a water reservoir"
    );
    assert!(
        (state.pressure[0] - 2e6).abs() < 1e3,
        "P = {}",
        state.pressure[0]
    );
    assert!(
        (state.boundary_liquid_inflow[0] - state.liquid_mass[0]).abs()
            <= 1e-12 * state.liquid_mass[0]
    );
}

#[test]
fn bad_input_is_a_typed_error_naming_the_place() {
    let mut parts = NetworkParts {
        n_pores: 2,
        width: 8e-3,
        channel_pores: vec![[0, 1], [1, 0]],
        channel_length: vec![1e-3, 1e-3],
        channel_aperture: vec![1e-6, -1e-7],
        ..Default::default()
    };
    assert_eq!(
        Network::new(parts.clone()).unwrap_err(),
        FlowError::NegativeAperture {
            channel: 1,
            value: -1e-7
        }
    );
    parts.channel_aperture[1] = 1e-6;
    parts.channel_length[0] = 0.0;
    assert!(matches!(
        Network::new(parts.clone()).unwrap_err(),
        FlowError::NonPositiveLength { index: 0, .. }
    ));
    parts.channel_length[0] = 1e-3;
    let mut with_links = parts.clone();
    with_links.boundaries = vec![BoundaryCondition::Impermeable];
    with_links.link_pore = vec![0, 1];
    with_links.link_group = vec![0, 0];
    with_links.link_length = vec![1e-3; 2];
    with_links.link_aperture = vec![1e-6, -2e-6];
    with_links.link_face_length = vec![1e-3; 2];
    assert_eq!(
        Network::new(with_links).unwrap_err(),
        FlowError::NegativeLinkAperture {
            link: 1,
            value: -2e-6
        }
    );
    let mut net = Network::new(parts).unwrap();
    // Apertures replaced later (e.g. S2S apertures from contact stresses) are checked too.
    let e = net.set_channel_apertures(&[1e-6, f64::NAN]).unwrap_err();
    assert!(
        matches!(e, FlowError::NegativeAperture { channel: 1, .. }),
        "{e}"
    );
    assert_eq!(net.parts().channel_aperture, [1e-6, 1e-6]);
    let fluid = water_air();
    let e = FlowState::from_masses(
        &net,
        vec![1e-9, 0.0],
        vec![293.15; 2],
        vec![1e-6; 2],
        vec![0.0; 2],
        &fluid,
    )
    .unwrap_err();
    assert!(matches!(e, FlowError::NonPositiveVolume { pore: 1, .. }));
    // A pure-water pore stretched far below its reference density has no closure.
    let e = FlowState::from_masses(
        &net,
        vec![1e-9, 1e-9],
        vec![293.15; 2],
        vec![1e-6, 0.9e-6],
        vec![0.0; 2],
        &fluid,
    )
    .unwrap_err();
    assert!(matches!(
        e,
        FlowError::Closure {
            pore: 1,
            cause: ClosureFailure::NoSolution { .. },
            ..
        }
    ));
    // A wall closing a sealed pore within the step: the stepper stops naming the pore.
    let sealed = two_pores(0.0);
    let mut state = FlowState::from_pressure(
        &sealed,
        vec![1e-9; 2],
        vec![293.15; 2],
        &[1e6; 2],
        &[1.0; 2],
        &fluid,
    )
    .unwrap();
    let mut stepper = FlowStepper::new(config());
    let e = stepper
        .step(&sealed, &mut state, &fluid, &[0.0, -2e-9], 1.0)
        .unwrap_err();
    assert!(
        matches!(e, FlowError::NonPositiveVolume { pore: 1, .. }),
        "{e}"
    );
}

#[test]
fn pressure_forces_balance_on_a_sphere_in_uniform_pressure_and_shear_carries_the_drop() {
    // A structured square with a solid "sphere" in the middle cells: uniform pressure gives
    // zero net force (closed outline ⇒ Σ n e = 0).
    let mesh = PoreMesh::structured_rectangle(6, 6, 6e-3, 6e-3, 8e-3, 0.01, |c| {
        if (2e-3..4e-3).contains(&c[0]) && (2e-3..4e-3).contains(&c[1]) {
            CellKind::Solid { owner: 0 }
        } else {
            CellKind::Fluid
        }
    })
    .unwrap();
    let net = Network::from_mesh(&mesh, &[], 0.01).unwrap();
    assert!(!net.parts().wall_pore.is_empty());
    assert!(net.parts().wall_sphere.iter().all(|&s| s == 0));
    assert_eq!(net.n_pores(), 72 - 8);
    let fluid = water_air();
    let n = net.n_pores();
    let state = FlowState::from_pressure(
        &net,
        net.pore_volumes(&mesh),
        vec![293.15; n],
        &vec![3e6; n],
        &vec![1.0; n],
        &fluid,
    )
    .unwrap();
    let mut f = vec![[0.0; 2]; 1];
    add_sphere_forces(&net, &state, &config(), &[], &mut f).unwrap();
    let scale = 3e6 * 2e-3 * 8e-3;
    assert!(
        f[0][0].abs() < 1e-12 * scale && f[0][1].abs() < 1e-12 * scale,
        "{f:?}"
    );

    // S2S shear: the two spheres of the contact together receive ΔP·h·w along the channel.
    let net = two_pores(3e-6);
    let state = FlowState::from_pressure(
        &net,
        vec![1e-9; 2],
        vec![293.15; 2],
        &[4e6, 1e6],
        &[0.4, 0.7],
        &fluid,
    )
    .unwrap();
    let mut f = vec![[0.0; 2]; 2];
    add_sphere_forces(&net, &state, &config(), &[[0, 1]], &mut f).unwrap();
    let dp = state.pressure[0] - state.pressure[1];
    let total = f[0][0] + f[1][0];
    assert!((total - dp * 3e-6 * 8e-3).abs() <= 1e-12 * dp * 3e-6 * 8e-3);
    assert_eq!(f[0][1], 0.0);
}

#[test]
fn mesh_network_has_links_only_on_sides_with_conditions() {
    let mesh = PoreMesh::structured_rectangle(4, 8, 4e-3, 8e-3, 8e-3, 0.0115, |_| CellKind::Fluid)
        .unwrap();
    let top = BoundaryCondition::Pressure {
        pressure: 1e5,
        temperature: 293.15,
        entering_liquid_fraction: 1.0,
    };
    let net = Network::from_mesh(
        &mesh,
        &[
            (BoundarySide::Top, top),
            (BoundarySide::Left, BoundaryCondition::Impermeable),
        ],
        0.0115,
    )
    .unwrap();
    assert_eq!(net.n_links(), 4);
    assert!((net.group_face_length()[0] - 4e-3).abs() < 1e-15);
    assert_eq!(net.n_pores(), 64);
    assert_eq!(net.n_channels(), mesh.channels.len());
    // Per-cell values map to pores through the fluid cells.
    let cell_values: Vec<f64> = (0..mesh.n_cells()).map(|c| c as f64).collect();
    let mut pore_values = vec![0.0; net.n_pores()];
    net.cells_to_pores(&cell_values, &mut pore_values).unwrap();
    for (p, &c) in net.pore_cell().iter().enumerate() {
        assert_eq!(pore_values[p], c as f64);
        assert!(mesh.cell_kind[c as usize].is_fluid());
    }
}

#[test]
fn channel_interface_and_densities_come_from_the_upwind_pore() {
    let net = two_pores(4e-6);
    let fluid = water_air();
    let cfg = config();
    for (pressures, alphas, up) in [
        ([3e6, 1e6], [0.3, 0.8], 0usize),
        ([1e6, 3e6], [0.3, 0.8], 1usize),
    ] {
        let state = FlowState::from_pressure(
            &net,
            vec![1e-9; 2],
            vec![293.15; 2],
            &pressures,
            &alphas,
            &fluid,
        )
        .unwrap();
        let mut out = [ChannelFlux::default()];
        channel_fluxes(&net, &state, &cfg, &mut out);
        let g = (state.pressure[0] - state.pressure[1]) / 2e-3;
        let f = two_layer_flow(4e-6, state.liquid_fraction[up], g, 10.02e-4, 2.0507e-5);
        let expect_q = state.liquid_density[up] * f.liquid_flow_rate * 8e-3;
        let expect_p = state.gas_density[up] * f.gas_flow_rate * 8e-3;
        assert!((out[0].liquid - expect_q).abs() <= 1e-14 * expect_q.abs());
        assert!((out[0].gas - expect_p).abs() <= 1e-14 * expect_p.abs());
        // Flow goes from high to low pressure.
        assert_eq!(out[0].liquid.signum(), g.signum());
    }
}

#[test]
fn non_finite_and_closure_failures_stop_the_step_naming_the_pore() {
    let net = two_pores(3e-6);
    let fluid = water_air();
    let mut state = FlowState::from_pressure(
        &net,
        vec![1e-9; 2],
        vec![293.15; 2],
        &[2e6, 1e6],
        &[1.0, 1.0],
        &fluid,
    )
    .unwrap();
    let mut stepper = FlowStepper::new(config());
    let mut bad = state.clone();
    bad.pressure[1] = f64::NAN;
    let e = stepper.step(&net, &mut bad, &fluid, &[], 1e-4).unwrap_err();
    assert!(
        matches!(
            e,
            FlowError::NonFinite {
                place: "pore",
                index: 0,
                step: 0,
                ..
            }
        ),
        "{e}"
    );
    // A sealed pure-water pore whose wall moves out stretches the water below zero pressure:
    // no closure exists.
    let sealed = two_pores(0.0);
    state.step = 3;
    let e = stepper
        .step(&sealed, &mut state, &fluid, &[0.0, 1e-12], 1.0)
        .unwrap_err();
    assert!(
        matches!(
            e,
            FlowError::Closure {
                pore: 1,
                step: 3,
                cause: ClosureFailure::NoSolution { .. },
                ..
            }
        ),
        "{e}"
    );
}

/// The liquid speed of every channel is the liquid mass rate of stage 1 over the upwind
/// liquid density, layer thickness and width (the same layer), and in channels full of
/// liquid the plane Poiseuille mean speed `h² |ΔP| / (12 μ L)`.
#[test]
fn channel_liquid_speeds_carry_stage_one_liquid_flux() {
    let (net, mut state) = random_closed_network(7, 24);
    let cfg = config();
    for full in [false, true] {
        if full {
            state.liquid_fraction.fill(1.0);
        }
        let speeds = thm_vpn_flow::stages::channel_liquid_speeds(&net, &state, &cfg);
        let mut flux = vec![ChannelFlux::default(); net.n_channels()];
        channel_fluxes(&net, &state, &cfg, &mut flux);
        let parts = net.parts();
        let mut checked = 0;
        for (c, (&v, f)) in speeds.iter().zip(&flux).enumerate() {
            let [i, j] = parts.channel_pores[c];
            let (i, j) = (i as usize, j as usize);
            let up = if state.pressure[i] >= state.pressure[j] {
                i
            } else {
                j
            };
            let (h, len) = (parts.channel_aperture[c], parts.channel_length[c]);
            let layer = state.liquid_fraction[up] * h;
            if layer == 0.0 {
                assert_eq!(v, 0.0);
                continue;
            }
            let from_flux = f.liquid.abs() / (state.liquid_density[up] * layer * net.width());
            assert!((v - from_flux).abs() <= 1e-12 * from_flux.max(1e-30), "{c}");
            if full {
                let dp = (state.pressure[i] - state.pressure[j]).abs();
                let poiseuille = h * h * dp / (12.0 * cfg.liquid_viscosity() * len);
                assert!((v - poiseuille).abs() <= 1e-12 * poiseuille, "{c}");
            }
            checked += 1;
        }
        assert!(checked > 10);
    }
}
