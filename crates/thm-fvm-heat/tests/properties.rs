//! Property tests: energy conservation (explicit and implicit), serial-vs-parallel parity
//! and save/restore round trips on random meshes.

mod common;

use common::{random_input, random_mesh, random_temperatures, table1_params};
use proptest::prelude::*;
use thm_fvm_heat::{FlowInput, HeatGeometry, HeatModel, HeatState, HeatStepper};
use thm_vpn_mesh::PoreMesh;

fn energy(stepper: &HeatStepper, t: &[f64]) -> (f64, f64) {
    // Σ C T and Σ C |T| (the round-off scale), in cell order.
    let c = stepper.heat_capacity();
    let e: f64 = c.iter().zip(t).map(|(c, t)| c * t).sum();
    let s: f64 = c.iter().zip(t).map(|(c, t)| (c * t).abs()).sum();
    (e, s)
}

fn setup(
    seed: u64,
    nx: usize,
    ny: usize,
    flux: f64,
) -> (PoreMesh, HeatModel, FlowInput, HeatState) {
    let mesh = random_mesh(seed, nx, ny);
    let model = HeatModel::new(&table1_params(), &mesh).unwrap();
    let input = random_input(seed, &mesh, flux);
    let state = HeatState {
        time: 0.0,
        steps: 0,
        temperature: random_temperatures(seed, mesh.n_cells()),
    };
    (mesh, model, input, state)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Adiabatic boundaries, no sources: Σ C_i T_i is unchanged by an explicit step (with
    /// advection by arbitrary channel mass fluxes, conduction, interfaces and S2S channels)
    /// up to round-off.
    #[test]
    fn explicit_step_conserves_energy(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let (mesh, model, input, mut state) = setup(seed, nx, ny, 2e-4);
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let mut stepper = HeatStepper::new();
        stepper.prepare(&model, &geometry, &mesh, &input, &state).unwrap();
        let (e0, scale) = energy(&stepper, &state.temperature);
        let report = stepper.step(&model, &geometry, &mesh, &input, &mut state, 50.0).unwrap();
        let (e1, _) = energy(&stepper, &state.temperature);
        let tol = 1e-14 * scale * (report.substeps as f64 + 1.0) * mesh.n_cells() as f64;
        prop_assert!((e1 - e0).abs() <= tol, "dE = {} J, tol {} J, {} substeps", e1 - e0, tol, report.substeps);
        // Something happened: the field is not frozen.
        prop_assert!(report.substeps >= 1);
    }

    /// Pure advection (λ = 0, uniform single-phase fluid, divergence-free channel fluxes) on
    /// random meshes: fluid temperatures stay within their initial range (the Barth–Jespersen
    /// limiter and the advective stability factor keep the scheme local-extremum diminishing).
    #[test]
    fn pure_advection_creates_no_new_extrema(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let mesh = random_mesh(seed, nx, ny);
        let mut params = table1_params();
        params.liquid.conductivity = 0.0;
        let model = HeatModel::new(&params, &mesh).unwrap();
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let mut input = random_input(seed, &mesh, 2e-4);
        input.liquid_fraction.iter_mut().for_each(|a| *a = 1.0);
        input.liquid_density.iter_mut().for_each(|r| *r = 1000.0);
        let mut state = HeatState {
            time: 0.0,
            steps: 0,
            temperature: random_temperatures(seed, mesh.n_cells()),
        };
        let fluid: Vec<usize> = (0..mesh.n_cells()).filter(|&c| mesh.cell_kind[c].is_fluid()).collect();
        let range = |t: &[f64]| fluid.iter().fold((f64::MAX, f64::MIN), |(a, b), &c| (a.min(t[c]), b.max(t[c])));
        let (lo, hi) = range(&state.temperature);
        let mut stepper = HeatStepper::new();
        for _ in 0..5 {
            stepper.step(&model, &geometry, &mesh, &input, &mut state, 20.0).unwrap();
            let (a, b) = range(&state.temperature);
            prop_assert!(a >= lo - 1e-9 && b <= hi + 1e-9, "range [{a}, {b}] left [{lo}, {hi}]");
        }
    }

    /// The same for the backward-Euler conduction step (no mass fluxes), with a long step.
    #[test]
    fn implicit_step_conserves_energy(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let (mesh, model, input, mut state) = setup(seed, nx, ny, 0.0);
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let mut stepper = HeatStepper::new();
        stepper.prepare(&model, &geometry, &mesh, &input, &state).unwrap();
        let (e0, scale) = energy(&stepper, &state.temperature);
        stepper.implicit_step(&model, &geometry, &mesh, &input, &mut state, 500.0).unwrap();
        let (e1, _) = energy(&stepper, &state.temperature);
        prop_assert!((e1 - e0).abs() <= 1e-11 * scale, "dE = {} J of {} J", e1 - e0, scale);
    }

    /// 1 and 2 rayon threads give identical bits (explicit step with advection).
    #[test]
    fn serial_and_parallel_runs_are_bitwise_equal(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let (mesh, model, input, state) = setup(seed, nx, ny, 2e-4);
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut s = state.clone();
                let mut stepper = HeatStepper::new();
                stepper.step(&model, &geometry, &mesh, &input, &mut s, 50.0).unwrap();
                let mut s2 = s.clone();
                let no_flux = FlowInput { channel_mass_flux: vec![0.0; input.channel_mass_flux.len()], ..input.clone() };
                stepper.implicit_step(&model, &geometry, &mesh, &no_flux, &mut s2, 100.0).unwrap();
                (s, s2)
            })
        };
        let (a1, b1) = run(1);
        let (a2, b2) = run(2);
        let bits = |s: &HeatState| s.temperature.iter().map(|t| t.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!(bits(&a1), bits(&a2));
        prop_assert_eq!(bits(&b1), bits(&b2));
    }
}

/// Stopping after one step, writing the state to JSON and reading it back gives the same bits
/// after the next step as running straight through; parameters round-trip too.
#[test]
fn save_restore_round_trip() {
    let (mesh, model, input, state) = setup(7, 5, 6, 2e-4);
    let geometry = HeatGeometry::new(&model, &mesh).unwrap();
    let mut stepper = HeatStepper::new();
    let mut straight = state.clone();
    stepper
        .step(&model, &geometry, &mesh, &input, &mut straight, 20.0)
        .unwrap();
    stepper
        .step(&model, &geometry, &mesh, &input, &mut straight, 20.0)
        .unwrap();

    let mut first = state.clone();
    stepper
        .step(&model, &geometry, &mesh, &input, &mut first, 20.0)
        .unwrap();
    let text = serde_json::to_string(&first).unwrap();
    let mut restored: HeatState = serde_json::from_str(&text).unwrap();
    assert_eq!(restored, first);
    let mut fresh = HeatStepper::new();
    fresh
        .step(&model, &geometry, &mesh, &input, &mut restored, 20.0)
        .unwrap();
    assert_eq!(restored.steps, straight.steps);
    for (a, b) in restored.temperature.iter().zip(&straight.temperature) {
        assert_eq!(a.to_bits(), b.to_bits());
    }

    let params = table1_params();
    let text = serde_json::to_string(&params).unwrap();
    let back: thm_fvm_heat::HeatParams = serde_json::from_str(&text).unwrap();
    assert_eq!(back, params);
    let input_text = serde_json::to_string(&input).unwrap();
    let input_back: FlowInput = serde_json::from_str(&input_text).unwrap();
    assert_eq!(input_back, input);
}
