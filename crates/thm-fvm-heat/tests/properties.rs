//! Property tests: energy conservation (explicit and implicit), serial-vs-parallel parity
//! and save/restore round trips on random meshes.

mod common;

use common::{random_input, random_mesh, random_temperatures, table1_params};
use proptest::prelude::*;
use thm_fvm_heat::{
    BoundaryCondition, BoundaryParams, CrossDiffusion, FlowInput, HeatGeometry, HeatModel,
    HeatState, HeatStepper, TemperatureSchedule,
};
use thm_vpn_mesh::BoundarySide;
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

    /// `step` takes its stability limit from the face pass of its first sub-step and applies
    /// that sub-step's net heat after: the same bits as the plain stage sequence (prepare,
    /// stability limit alone, then face values → gradients → face heat → channel heat →
    /// advance per sub-step), for the limit and for the temperatures after several sub-steps.
    #[test]
    fn fused_first_substep_equals_the_stage_sequence(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let (mesh, model, input, state) = setup(seed, nx, ny, 2e-4);
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let mut plain = HeatStepper::new();
        let limit = plain.stable_time_step(&model, &geometry, &mesh, &input, &state).unwrap();
        prop_assert!(limit.is_finite() && limit > 0.0);
        let dt = 3.5 * limit;
        let mut fused = state.clone();
        let report = HeatStepper::new().step(&model, &geometry, &mesh, &input, &mut fused, dt).unwrap();
        prop_assert_eq!(report.stability_limit.to_bits(), limit.to_bits());
        prop_assert!(report.substeps >= 4);
        let mut t = state.temperature.clone();
        for k in 0..report.substeps {
            let time = k as f64 * report.substep;
            plain.face_values(&model, &geometry, &mesh, &t, time);
            plain.gradients(&model, &geometry, &mesh, &t);
            plain.face_heat(&model, &geometry, &mesh, &input, &t, time);
            plain.channel_heat(&model, &geometry, &mesh, &input, &t);
            prop_assert!(plain.advance(&geometry, &mesh, &mut t, report.substep).is_none());
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!(bits(&fused.temperature), bits(&t));
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

    /// Limited cross diffusion (`ratio` ≤ 1): every face carries heat from hot to cold at no
    /// more than (1 + ratio) times its two-point rate, and the stability limit counts that
    /// factor, so an explicit conduction sub-step is a convex combination of neighbour
    /// temperatures: no new extrema. The limited face rate is still antisymmetric, so energy
    /// is conserved, explicitly and with the backward-Euler step.
    #[test]
    fn limited_cross_diffusion_conserves_energy_and_creates_no_extrema(
        seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7, ratio in 0.0f64..=1.0,
    ) {
        let mesh = random_mesh(seed, nx, ny);
        let mut params = table1_params();
        params.cross_diffusion = CrossDiffusion::Limited { ratio };
        // The whole limit: the bound must hold without the default safety margin.
        params.stability_safety = 1.0;
        let model = HeatModel::new(&params, &mesh).unwrap();
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let input = random_input(seed, &mesh, 0.0);
        let mut state = HeatState {
            time: 0.0,
            steps: 0,
            temperature: random_temperatures(seed, mesh.n_cells()),
        };
        let range = |t: &[f64]| t.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        let (lo, hi) = range(&state.temperature);
        let mut stepper = HeatStepper::new();
        stepper.prepare(&model, &geometry, &mesh, &input, &state).unwrap();
        let (e0, scale) = energy(&stepper, &state.temperature);
        let report = stepper.step(&model, &geometry, &mesh, &input, &mut state, 50.0).unwrap();
        let (e1, _) = energy(&stepper, &state.temperature);
        let tol = 1e-14 * scale * (report.substeps as f64 + 1.0) * mesh.n_cells() as f64;
        prop_assert!((e1 - e0).abs() <= tol, "explicit dE = {} J, tol {} J", e1 - e0, tol);
        let (a, b) = range(&state.temperature);
        prop_assert!(a >= lo - 1e-9 && b <= hi + 1e-9, "range [{a}, {b}] left [{lo}, {hi}]");
        stepper.implicit_step(&model, &geometry, &mesh, &input, &mut state, 500.0).unwrap();
        let (e2, _) = energy(&stepper, &state.temperature);
        prop_assert!((e2 - e0).abs() <= 1e-11 * scale, "implicit dE = {} J of {} J", e2 - e0, scale);
    }

    /// Backward Euler with advection by arbitrary channel mass fluxes (closed, adiabatic):
    /// every advected transfer leaves one row as it enters another, so Σ C_i T_i is unchanged
    /// up to round-off, for a step far beyond the explicit limit.
    #[test]
    fn implicit_step_with_advection_conserves_energy(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let (mesh, model, input, mut state) = setup(seed, nx, ny, 2e-4);
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let mut stepper = HeatStepper::new();
        let limit = stepper.stable_time_step(&model, &geometry, &mesh, &input, &state).unwrap();
        let (e0, scale) = energy(&stepper, &state.temperature);
        let h = if limit.is_finite() { 100.0 * limit } else { 1e3 };
        stepper.implicit_step(&model, &geometry, &mesh, &input, &mut state, h).unwrap();
        let (e1, _) = energy(&stepper, &state.temperature);
        prop_assert!((e1 - e0).abs() <= 1e-11 * scale, "dE = {} J of {} J", e1 - e0, scale);
    }

    /// Implicit pure advection (λ = 0, uniform single-phase fluid, divergence-free fluxes):
    /// the first-order upwind matrix is an M-matrix with zero row sums, so each new
    /// temperature is a convex combination of old ones: no new extrema, for any step.
    #[test]
    fn implicit_pure_advection_creates_no_new_extrema(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
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
        let limit = stepper.stable_time_step(&model, &geometry, &mesh, &input, &state).unwrap();
        // 50 explicit limits (infinite when no cell has an outflow: then any long step).
        let h = if limit.is_finite() { 50.0 * limit } else { 1e3 };
        for _ in 0..3 {
            stepper.implicit_step(&model, &geometry, &mesh, &input, &mut state, h).unwrap();
            let (a, b) = range(&state.temperature);
            prop_assert!(a >= lo - 1e-9 && b <= hi + 1e-9, "range [{a}, {b}] left [{lo}, {hi}]");
        }
    }

    /// Open boundaries (a held temperature on the left, a heat flux on the right): the change
    /// of Σ C_i T_i over a step, explicit or implicit, equals the energy the stepper reports
    /// through the boundary, to round-off.
    #[test]
    fn energy_change_equals_the_boundary_energy(seed in any::<u64>(), nx in 2usize..7, ny in 2usize..7) {
        let mesh = random_mesh(seed, nx, ny);
        let mut params = table1_params();
        params.boundaries = vec![
            BoundaryParams {
                side: BoundarySide::Left,
                condition: BoundaryCondition::Temperature {
                    temperature: TemperatureSchedule::Constant(350.0),
                },
            },
            BoundaryParams {
                side: BoundarySide::Right,
                condition: BoundaryCondition::HeatFlux { flux: 2e3 },
            },
        ];
        let model = HeatModel::new(&params, &mesh).unwrap();
        let geometry = HeatGeometry::new(&model, &mesh).unwrap();
        let input = random_input(seed, &mesh, 0.0);
        let mut state = HeatState {
            time: 0.0,
            steps: 0,
            temperature: random_temperatures(seed, mesh.n_cells()),
        };
        let mut stepper = HeatStepper::new();
        stepper.prepare(&model, &geometry, &mesh, &input, &state).unwrap();
        let (e0, scale) = energy(&stepper, &state.temperature);
        let report = stepper.step(&model, &geometry, &mesh, &input, &mut state, 50.0).unwrap();
        let (e1, _) = energy(&stepper, &state.temperature);
        let q = stepper.boundary_energy();
        prop_assert!(q != 0.0);
        let tol = 1e-14 * scale * (report.substeps as f64 + 1.0) * mesh.n_cells() as f64;
        prop_assert!((e1 - e0 - q).abs() <= tol, "explicit: dE {} J, boundary {} J", e1 - e0, q);
        stepper.implicit_step(&model, &geometry, &mesh, &input, &mut state, 500.0).unwrap();
        let (e2, _) = energy(&stepper, &state.temperature);
        let q = stepper.boundary_energy();
        prop_assert!((e2 - e1 - q).abs() <= 1e-11 * scale, "implicit: dE {} J, boundary {} J", e2 - e1, q);
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

/// On a mesh large enough that every parallel pass splits into several tasks (more than
/// twice the rayon grain of 2048 items), 1 and 2 threads give identical bits: the geometry
/// (built and refreshed inside each pool), the explicit step with advection, and the
/// implicit step.
#[test]
fn serial_and_parallel_runs_are_bitwise_equal_on_a_large_mesh() {
    let (mut mesh, model, input, state) = setup(11, 48, 64, 2e-4);
    assert!(mesh.n_cells() > 2 * 2048 && mesh.n_faces() > 2 * 2048);
    // Move the interior vertices a little: update_positions must follow.
    let moved: Vec<[f64; 2]> = mesh
        .vertices
        .iter()
        .map(|&[x, y]| {
            let interior = x > 1e-9 && x < 0.02 - 1e-9 && y > 1e-9 && y < 0.03 - 1e-9;
            if interior {
                [x + 2e-6 * (y * 900.0).sin(), y + 2e-6 * (x * 700.0).cos()]
            } else {
                [x, y]
            }
        })
        .collect();
    let run = |threads: usize, mesh: &PoreMesh| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let geometry = HeatGeometry::new(&model, mesh).unwrap();
            let mut s = state.clone();
            let mut stepper = HeatStepper::new();
            stepper
                .step(&model, &geometry, mesh, &input, &mut s, 0.05)
                .unwrap();
            let no_flux = FlowInput {
                channel_mass_flux: vec![0.0; input.channel_mass_flux.len()],
                ..input.clone()
            };
            let mut s2 = s.clone();
            stepper
                .implicit_step(&model, &geometry, mesh, &no_flux, &mut s2, 100.0)
                .unwrap();
            (s, s2)
        })
    };
    let bits = |s: &HeatState| {
        s.temperature
            .iter()
            .map(|t| t.to_bits())
            .collect::<Vec<_>>()
    };
    let (a1, b1) = run(1, &mesh);
    let (a2, b2) = run(2, &mesh);
    assert_eq!(bits(&a1), bits(&a2));
    assert_eq!(bits(&b1), bits(&b2));
    mesh.vertices = moved;
    mesh.update_geometry();
    let (c1, _) = run(1, &mesh);
    let (c2, _) = run(2, &mesh);
    assert_eq!(bits(&c1), bits(&c2));
    assert_ne!(
        bits(&c1),
        bits(&a1),
        "the moved mesh must change the result"
    );
}

/// After the vertices move, refreshing the positions of a geometry gives the same bits as a
/// geometry built from scratch on the moved mesh; a geometry of another mesh is a typed
/// error, not a panic.
#[test]
fn updated_geometry_equals_a_fresh_one() {
    let (mut mesh, model, input, state) = setup(5, 6, 8, 2e-4);
    let mut geometry = HeatGeometry::new(&model, &mesh).unwrap();
    for v in &mut mesh.vertices {
        let [x, y] = *v;
        if x > 1e-9 && x < 0.02 - 1e-9 && y > 1e-9 && y < 0.03 - 1e-9 {
            *v = [x + 1e-4 * (y * 300.0).sin(), y];
        }
    }
    mesh.update_geometry();
    geometry.update_positions(&model, &mesh).unwrap();
    let fresh = HeatGeometry::new(&model, &mesh).unwrap();
    let step = |g: &HeatGeometry| {
        let mut s = state.clone();
        HeatStepper::new()
            .step(&model, g, &mesh, &input, &mut s, 20.0)
            .unwrap();
        s.temperature
            .iter()
            .map(|t| t.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(step(&geometry), step(&fresh));
    assert_eq!(geometry.porosity().to_bits(), fresh.porosity().to_bits());

    let other = random_mesh(6, 5, 8);
    let other_model = HeatModel::new(&table1_params(), &other).unwrap();
    let other_geometry = HeatGeometry::new(&other_model, &other).unwrap();
    let mut s = state.clone();
    assert!(matches!(
        HeatStepper::new().step(&model, &other_geometry, &mesh, &input, &mut s, 1.0),
        Err(thm_fvm_heat::HeatError::LengthMismatch { .. })
    ));
}
