//! Pore pressure through the cell corners (`thm_coupling::pore_scale::pore_forces`): the
//! volume gradient against the mesh's own volume rate, the undrained response against the
//! closure, and a coupled run with the option on (conservation, thread parity).

mod common;

use common::*;
use thm_coupling::pore_scale::pore_forces::{PoreVolumeGradient, UndrainedPores};
use thm_coupling::pore_scale::{PoreScaleState, PressureForce, Skeleton};
use thm_vpn_flow::PoreFluid;
use thm_vpn_mesh::{CircleMotion, MeshMotion, RemeshCriteriaParams};

/// A fixed pseudo-random field in [-1, 1]² (a 64-bit LCG; no global or unseeded state).
fn field(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    (0..n).map(|_| [next(), next()]).collect()
}

#[test]
fn the_corner_gradient_is_the_volume_rate_of_the_mesh_motion() {
    // dV_i/dt of the mesh motion (vertex kinematics, side constraints) for centre velocities
    // v_s and no turn or growth must equal Σ_s (∂V_i/∂c_s) · v_s for every pore.
    let config = params(Skeleton::Free, RemeshCriteriaParams::default())
        .validate()
        .expect("params");
    let mut s = state(&config);
    let st = stepper(&config, &s);
    let pore_cell = st.network().pore_cell().to_vec();
    let mut g = PoreVolumeGradient::default();
    g.build(&s.mesh, &pore_cell).expect("gradient");
    assert_eq!(g.n_pores(), pore_cell.len());
    let p = &s.dem.particles;
    let n = p.len();
    let centre: Vec<[f64; 2]> = p.position.iter().map(|x| [x.x, x.y]).collect();
    let zero = vec![0.0; n];
    for seed in 1..=4 {
        let velocity = field(n, seed);
        let mut motion = MeshMotion::new();
        motion
            .update(
                &mut s.mesh,
                &CircleMotion {
                    centre: &centre,
                    radius: &p.radius,
                    rotation: &s.rotation,
                    velocity: &velocity,
                    angular_velocity: &zero,
                    radius_rate: &zero,
                },
            )
            .expect("motion");
        let rate = motion.volume_rate();
        let scale = rate.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        assert!(scale > 0.0);
        let mut checked = 0;
        for (i, &cell) in pore_cell.iter().enumerate() {
            let (spheres, grad) = g.row(i);
            let predicted: f64 = spheres
                .iter()
                .zip(grad)
                .map(|(&t, g)| g[0] * velocity[t as usize][0] + g[1] * velocity[t as usize][1])
                .sum();
            let actual = rate[cell as usize];
            assert!(
                (predicted - actual).abs() <= 1e-12 * scale,
                "seed {seed}, pore {i}: Σ g·v = {predicted:e}, mesh dV/dt = {actual:e}"
            );
            checked += usize::from(actual.abs() > 1e-6 * scale);
        }
        assert!(
            checked > pore_cell.len() / 2,
            "only {checked} pores changed"
        );
    }
}

#[test]
fn uniform_pressure_through_the_corners_does_the_work_of_the_pore_volume_change() {
    // Σ_s F_s · δc_s = P Σ_i δV_i: with one pressure in every pore the corner forces are the
    // gradient of P × (total pore volume), checked along a displacement of every sphere.
    let config = params(Skeleton::Free, RemeshCriteriaParams::default())
        .validate()
        .expect("params");
    let s = state(&config);
    let st = stepper(&config, &s);
    let pore_cell = st.network().pore_cell().to_vec();
    let mut g = PoreVolumeGradient::default();
    g.build(&s.mesh, &pore_cell).expect("gradient");
    let p = 3.0e5;
    let n = s.dem.particles.len();
    let mut force = vec![[0.0; 2]; n];
    g.add_forces(&vec![p; pore_cell.len()], &mut force);
    let d = field(n, 9);
    let work: f64 = force
        .iter()
        .zip(&d)
        .map(|(f, d)| f[0] * d[0] + f[1] * d[1])
        .sum();
    let dv: f64 = (0..g.n_pores())
        .map(|i| {
            let (sp, gr) = g.row(i);
            sp.iter()
                .zip(gr)
                .map(|(&t, g)| g[0] * d[t as usize][0] + g[1] * d[t as usize][1])
                .sum::<f64>()
        })
        .sum();
    assert!(
        (work - p * dv).abs() <= 1e-12 * p * dv.abs().max(1e-12),
        "{work:e} vs {:e}",
        p * dv
    );
}

#[test]
fn the_undrained_pressure_follows_the_closure_to_second_order() {
    // Move every free sphere by ε d; the undrained two-phase spring must agree with the
    // closure (A-Eq. 29) of the same masses in the moved mesh's volumes to within 5 % of the
    // pressure change, and the gap must shrink as O(ε²). At ε = 2e-7 m a pore of 8e-12 m³
    // loses 45 % of its gas: a response linear in ΔV is off by 45 % there.
    let config = params(Skeleton::Free, RemeshCriteriaParams::default())
        .validate()
        .expect("params");
    let s0 = state(&config);
    let st = stepper(&config, &s0);
    let pore_cell = st.network().pore_cell().to_vec();
    let fluid = fluid();
    let n = s0.dem.particles.len();
    let d = field(n, 5);
    let mut gaps = Vec::new();
    for eps in [2e-7, 1e-7] {
        let mut s = s0.clone();
        let mut u = UndrainedPores::default();
        u.begin(
            &s.mesh,
            &pore_cell,
            &s.flow,
            &fluid,
            &s.dem,
            &vec![[0.0; 2]; n],
        )
        .expect("begin");
        let p = &mut s.dem.particles;
        for (i, x) in p.position.iter_mut().enumerate() {
            if !p.fixed[i] {
                x.x += eps * d[i][0];
                x.y += eps * d[i][1];
            }
        }
        u.apply(&mut s.dem, 0).expect("apply");
        let p = &s.dem.particles;
        let centre: Vec<[f64; 2]> = p.position.iter().map(|x| [x.x, x.y]).collect();
        let zero = vec![0.0; n];
        let still = vec![[0.0; 2]; n];
        MeshMotion::new()
            .update(
                &mut s.mesh,
                &CircleMotion {
                    centre: &centre,
                    radius: &p.radius,
                    rotation: &s.rotation,
                    velocity: &still,
                    angular_velocity: &zero,
                    radius_rate: &zero,
                },
            )
            .expect("motion");
        let (mut worst_gap, mut worst_change) = (0.0f64, 0.0f64);
        for (i, &cell) in pore_cell.iter().enumerate() {
            let f = &s0.flow;
            let closed = fluid
                .close(
                    f.liquid_mass[i],
                    f.gas_mass[i],
                    s.mesh.mesh.cell_volume(cell as usize),
                    f.temperature[i],
                )
                .expect("closure");
            let change = closed.pressure - f.pressure[i];
            worst_change = worst_change.max(change.abs());
            worst_gap = worst_gap.max((u.pressures()[i] - closed.pressure).abs());
        }
        assert!(worst_change > 0.0);
        assert!(
            worst_gap <= 0.05 * worst_change,
            "ε = {eps}: gap {worst_gap:e} Pa against a change of {worst_change:e} Pa"
        );
        gaps.push(worst_gap);
    }
    let order = (gaps[0] / gaps[1]).log2();
    assert!(order > 1.7, "gap shrinks with order {order}: {gaps:?}");
}

fn corner_params() -> thm_coupling::pore_scale::PoreScaleParams {
    let mut p = params(Skeleton::Free, eager_remesh());
    p.pressure_force = PressureForce::CellCorners;
    p
}

fn run_corners(steps: usize) -> PoreScaleState {
    let config = corner_params().validate().expect("params");
    let mut s = state(&config);
    let mut st = stepper(&config, &s);
    for _ in 0..steps {
        st.step(&mut s, 1e-5).expect("step");
    }
    s
}

#[test]
fn a_coupled_run_with_corner_forces_keeps_the_phase_masses_and_threads_agree() {
    let config = corner_params().validate().expect("params");
    let s0 = state(&config);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("pool")
    };
    let one = pool(1).install(|| run_corners(6));
    let two = pool(2).install(|| run_corners(6));
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(rel(one.liquid_mass(), s0.liquid_mass()) < 1e-12);
    assert!(rel(one.gas_mass(), s0.gas_mass()) < 1e-12);
    assert!(one.remeshes > 0);
    let p1 = &one.dem.particles;
    assert!(p1.position != s0.dem.particles.position);
    let bits = |s: &PoreScaleState| {
        let p = &s.dem.particles;
        p.position
            .iter()
            .chain(&p.velocity)
            .flat_map(|x| [x.x.to_bits(), x.y.to_bits()])
            .chain(s.flow.pressure.iter().map(|x| x.to_bits()))
            .chain(s.heat.temperature.iter().map(|x| x.to_bits()))
            .collect::<Vec<u64>>()
    };
    assert_eq!(bits(&one), bits(&two));
}

/// The implicit pore springs: after `implicit_correction` the correction `δ = v* − v` solves
/// `(M + h² K) δ = h² K v*` (`K = Σ_i k_i g_i g_iᵀ` rebuilt here from the public gradient
/// and tangents) to 10⁻¹⁰ of the right-hand side, the positions moved by `−h δ`, held spheres
/// untouched; at rest it changes no bit.
#[test]
fn the_implicit_pore_springs_solve_the_backward_euler_system() {
    let config = corner_params().validate().expect("params");
    let mut s = state(&config);
    let st = stepper(&config, &s);
    let pore_cell = st.network().pore_cell().to_vec();
    let fluid = fluid();
    let n = s.dem.particles.len();
    let mut u = UndrainedPores::default();
    u.begin(
        &s.mesh,
        &pore_cell,
        &s.flow,
        &fluid,
        &s.dem,
        &vec![[0.0; 2]; n],
    )
    .expect("begin");
    // Squeeze: every free sphere moved by up to 0.1 µm, so the tangents differ from pore to
    // pore; then velocities up to 1 mm/s.
    let d = field(n, 11);
    let v = field(n, 12);
    let p = &mut s.dem.particles;
    for ((x, d), &fixed) in p.position.iter_mut().zip(&d).zip(&p.fixed) {
        if !fixed {
            x.x += 1e-7 * d[0];
            x.y += 1e-7 * d[1];
        }
    }
    u.apply(&mut s.dem, 0).expect("apply");
    let at_rest = s.clone();
    u.implicit_correction(&mut s.dem, 2e-6, 0).expect("rest");
    assert_eq!(s.dem.particles.position, at_rest.dem.particles.position);
    for (x, v) in s.dem.particles.velocity.iter_mut().zip(&v) {
        x.x = 1e-3 * v[0];
        x.y = 1e-3 * v[1];
    }
    let before = s.dem.particles.clone();
    // A sub-step at which the stiffest pores dominate their spheres' inertia (h² k g² ≫ m).
    let h = 1e-4;
    u.implicit_correction(&mut s.dem, h, 0).expect("correction");
    let after = &s.dem.particles;
    let mut g = PoreVolumeGradient::default();
    g.build(&s.mesh, &pore_cell).expect("gradient");
    let k_times = |x: &[[f64; 2]]| {
        let mut out = vec![[0.0; 2]; n];
        for (i, &k) in u.tangents().iter().enumerate() {
            let (sph, gr) = g.row(i);
            let dot: f64 = sph
                .iter()
                .zip(gr)
                .filter(|(s, _)| !before.fixed[**s as usize])
                .map(|(&s, g)| g[0] * x[s as usize][0] + g[1] * x[s as usize][1])
                .sum();
            for (&s, g) in sph.iter().zip(gr) {
                if !before.fixed[s as usize] {
                    out[s as usize][0] += k * dot * g[0];
                    out[s as usize][1] += k * dot * g[1];
                }
            }
        }
        out
    };
    let v_star: Vec<[f64; 2]> = before.velocity.iter().map(|v| [v.x, v.y]).collect();
    let delta: Vec<[f64; 2]> = (0..n)
        .map(|i| {
            [
                before.velocity[i].x - after.velocity[i].x,
                before.velocity[i].y - after.velocity[i].y,
            ]
        })
        .collect();
    let (k_delta, k_v) = (k_times(&delta), k_times(&v_star));
    let (mut residual, mut rhs, mut moved) = (0.0f64, 0.0f64, 0usize);
    for i in 0..n {
        if before.fixed[i] {
            assert_eq!(after.position[i], before.position[i]);
            assert_eq!(after.velocity[i], before.velocity[i]);
            continue;
        }
        for a in 0..2 {
            let lhs = before.mass[i] * delta[i][a] + h * h * k_delta[i][a];
            residual = residual.max((lhs - h * h * k_v[i][a]).abs());
            rhs = rhs.max((h * h * k_v[i][a]).abs());
        }
        let dx = [
            after.position[i].x - before.position[i].x,
            after.position[i].y - before.position[i].y,
        ];
        for a in 0..2 {
            assert!(
                (dx[a] + h * delta[i][a]).abs() <= 1e-15 * before.position[i].x.abs().max(1e-3)
            );
        }
        moved += usize::from(delta[i] != [0.0; 2]);
    }
    assert!(rhs > 0.0 && moved > 0);
    assert!(residual <= 1e-10 * rhs, "residual {residual:e} of {rhs:e}");
}
