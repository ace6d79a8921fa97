//! Invariants the crate promises: frame indifference of the stress invariants, periodicity,
//! a symmetric positive definite conductivity, thread-count independence and save/restore.

#![allow(clippy::needless_range_loop)] // tensor indices read as in B-Eq. 58

use proptest::prelude::*;
use std::sync::OnceLock;
use thm_rve::verification::consolidated_packing;
use thm_rve::*;

/// A small consolidated packing (48 disks, 100 kPa, μ = 0.01) shared by the tests.
fn packing() -> &'static (RveConfig, RveState, f64) {
    static P: OnceLock<(RveConfig, RveState, f64)> = OnceLock::new();
    P.get_or_init(|| {
        let (config, state, report) = consolidated_packing(48, 7, 0.01).unwrap();
        (config.with_friction(0.5).unwrap(), state, report.time_step)
    })
}

/// Evaluates forces at the present configuration (no motion) and returns the stress.
fn evaluated_stress(config: &RveConfig, state: &mut RveState) -> Mat2 {
    let mut stepper = RveStepper::new(*config);
    stepper.step(state, &Mat2::ZERO, 0.0).unwrap();
    measure::stress(state, config.params().thickness)
}

fn close(a: f64, b: f64, scale: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * scale
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// A rigid rotation Q of the whole RVE maps σ to Q σ Qᵀ: mean stress and maximum shear
    /// stress unchanged; and shearing the rotated RVE by Q L Qᵀ keeps them unchanged.
    #[test]
    fn rigid_rotation_changes_no_stress_invariant(angle in 0.0..std::f64::consts::TAU) {
        let (config, base, dt) = packing();
        let mut a = base.clone();
        let mut b = base.clone();
        b.rotate_rigidly(angle).unwrap();
        let sa = evaluated_stress(config, &mut a);
        let sb = evaluated_stress(config, &mut b);
        let q = Mat2::rotation(angle);
        let expected = q.mul(&sa).mul(&q.transpose());
        let scale = sa.max_abs();
        for i in 0..2 { for j in 0..2 {
            prop_assert!(close(sb.at(i, j), expected.at(i, j), scale, 1e-11));
        }}
        // Shear both for 200 steps, the rotated one in its rotated frame.
        let l = Mat2::new(0.0, 2e-5 / dt, 0.0, -1e-5 / dt);
        let lq = q.mul(&l).mul(&q.transpose());
        let mut sa_stepper = RveStepper::new(*config);
        let mut sb_stepper = RveStepper::new(*config);
        for _ in 0..200 {
            sa_stepper.step(&mut a, &l, *dt).unwrap();
            sb_stepper.step(&mut b, &lq, *dt).unwrap();
        }
        let t = config.params().thickness;
        let (pa, ta) = measure::stress(&a, t).invariants_2d();
        let (pb, tb) = measure::stress(&b, t).invariants_2d();
        prop_assert!(close(pa, pb, pa.abs(), 1e-8), "p {pa} vs {pb}");
        prop_assert!(close(ta, tb, pa.abs(), 1e-8), "τ {ta} vs {tb}");
        prop_assert!(close(a.friction_heat_total, b.friction_heat_total, a.friction_heat_total.abs().max(1e-30), 1e-6));
    }

    /// Moving every disk by a lattice vector H·s changes no stress, heat or conductivity.
    #[test]
    fn periodic_shift_by_lattice_vector_changes_nothing(sx in -3i32..=3, sy in -3i32..=3) {
        let (config, base, dt) = packing();
        let mut a = base.clone();
        let mut b = base.clone();
        b.shift_by_lattice_vector([sx, sy]);
        let load = RveLoad {
            velocity_gradient: Mat2::new(-1e-5 / dt, 1e-5 / dt, 0.0, 0.0),
            temperature: config.params().reference_temperature,
            dt: 50.0 * dt,
            substeps: 50,
        };
        let ra = RveStepper::new(*config).respond(&mut a, &load).unwrap();
        let rb = RveStepper::new(*config).respond(&mut b, &load).unwrap();
        let scale = ra.stress.max_abs();
        for i in 0..2 { for j in 0..2 {
            prop_assert!(close(ra.stress.at(i, j), rb.stress.at(i, j), scale, 1e-9));
            prop_assert!(close(ra.conductivity.at(i, j), rb.conductivity.at(i, j), ra.conductivity.max_abs(), 1e-12));
        }}
        prop_assert!(close(ra.heat_source, rb.heat_source, ra.heat_source.abs().max(1e-30), 1e-6));
    }

    /// Without damping, contact forces are pairwise equal and opposite, so the total
    /// fluctuating momentum `Σ m v_f` is conserved (here: stays zero) under any velocity
    /// gradient.
    #[test]
    fn fluctuating_momentum_is_conserved_without_damping(
        lxx in -1.0..1.0f64, lxy in -1.0..1.0f64, lyx in -1.0..1.0f64, lyy in -1.0..1.0f64,
    ) {
        let (config, base, dt) = packing();
        let config = config.with_damping(0.0).unwrap();
        let mut s = base.clone();
        s.disks.velocity.iter_mut().for_each(|v| *v = thm_dem::Vec3::ZERO);
        let l = Mat2::new(lxx, lxy, lyx, lyy).scale(2e-5 / dt);
        let mut stepper = RveStepper::new(config);
        let mut scale = 0.0_f64;
        for _ in 0..300 {
            stepper.step(&mut s, &l, *dt).unwrap();
            for (m, v) in s.disks.mass.iter().zip(&s.disks.velocity) {
                scale = scale.max(m * v.norm());
            }
        }
        let p = s.disks.momentum();
        prop_assert!(scale > 0.0);
        prop_assert!(p.norm() <= 1e-12 * scale * s.len() as f64, "momentum {p:?} vs scale {scale}");
    }

    /// The fabric conductivity tensor of a connected (consolidated) packing is symmetric and
    /// positive definite, whatever its orientation.
    #[test]
    fn conductivity_is_symmetric_positive_definite(angle in 0.0..std::f64::consts::TAU) {
        let (config, base, _) = packing();
        let mut s = base.clone();
        s.rotate_rigidly(angle).unwrap();
        evaluated_stress(config, &mut s);
        let k = measure::conductivity(&s, config.params());
        prop_assert_eq!(k.at(0, 1).to_bits(), k.at(1, 0).to_bits());
        let [lo, hi] = k.symmetric_eigenvalues();
        prop_assert!(lo > 0.0 && hi >= lo, "eigenvalues {lo} {hi}");
        // Connected packing: anisotropy bounded (both principal values of one order).
        prop_assert!(lo > 0.2 * hi);
    }
}

/// The stiffness tensor of B-Eq. 58 has the major symmetry `D_αβγφ = D_γφαβ`, and with
/// `k_n = k_t` its `xxyy` entry vanishes (each contact's `n⊗n + t⊗t = I`).
#[test]
fn stiffness_tensor_has_major_symmetry() {
    let (config, base, _) = packing();
    let mut s = base.clone();
    evaluated_stress(config, &mut s);
    let d = measure::stiffness(&s, config.params());
    let scale = d[0][0][0][0].abs();
    assert!(scale > 0.0);
    for a in 0..2 {
        for b in 0..2 {
            for g in 0..2 {
                for p in 0..2 {
                    assert!((d[a][b][g][p] - d[g][p][a][b]).abs() <= 1e-12 * scale);
                }
            }
        }
    }
    assert!(d[0][0][1][1].abs() <= 1e-12 * scale);
}

fn batch_run(threads: usize) -> (Vec<RveState>, Vec<RveResponse>) {
    let (config, base, dt) = packing();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut states: Vec<RveState> = vec![base.clone(); 5];
    let loads: Vec<RveLoad> = (0..5)
        .map(|i| RveLoad {
            velocity_gradient: Mat2::new(-1e-5 / dt, (i as f64) * 1e-5 / dt, 0.0, 1e-6 / dt),
            temperature: config.params().reference_temperature + 2.0 * i as f64,
            dt: 40.0 * dt,
            substeps: 40,
        })
        .collect();
    let mut batch = RveBatch::new(*config, 5);
    let mut last = Vec::new();
    pool.install(|| {
        for _ in 0..3 {
            last = batch.respond(&mut states, &loads).unwrap();
        }
    });
    (states, last)
}

/// One and two threads give the same bits: every RVE is stepped serially by its own stepper.
#[test]
fn one_and_two_threads_give_identical_bits() {
    let (s1, r1) = batch_run(1);
    let (s2, r2) = batch_run(2);
    assert_eq!(
        serde_json::to_string(&s1).unwrap(),
        serde_json::to_string(&s2).unwrap()
    );
    for (a, b) in r1.iter().zip(&r2) {
        for i in 0..2 {
            for j in 0..2 {
                assert_eq!(a.stress.at(i, j).to_bits(), b.stress.at(i, j).to_bits());
                assert_eq!(
                    a.conductivity.at(i, j).to_bits(),
                    b.conductivity.at(i, j).to_bits()
                );
            }
        }
        assert_eq!(a.heat_source.to_bits(), b.heat_source.to_bits());
    }
    // The RVEs were loaded differently, so they must differ (the test can fail).
    assert_ne!(r1[0].stress, r1[4].stress);
}

/// A state saved mid-run and restored continues to exactly the same bits.
#[test]
fn save_restore_round_trip_continues_identically() {
    let (config, base, dt) = packing();
    let mut a = base.clone();
    let mut stepper = RveStepper::new(*config);
    let l = Mat2::new(0.0, 1e-5 / dt, 0.0, 0.0);
    for _ in 0..100 {
        stepper.step(&mut a, &l, *dt).unwrap();
    }
    let saved = serde_json::to_string(&a).unwrap();
    let mut b: RveState = serde_json::from_str(&saved).unwrap();
    assert_eq!(a, b);
    let mut stepper_b = RveStepper::new(*config);
    for _ in 0..100 {
        stepper.step(&mut a, &l, *dt).unwrap();
        stepper_b.step(&mut b, &l, *dt).unwrap();
    }
    assert_eq!(a, b);
    // Parameters round-trip too, and unknown fields are refused.
    let p = serde_json::to_string(config.params()).unwrap();
    let q: RveParams = serde_json::from_str(&p).unwrap();
    assert_eq!(&q, config.params());
    let bad = p.replacen('{', "{\"nonsense\":1,", 1);
    assert!(serde_json::from_str::<RveParams>(&bad).is_err());
}

/// A cell sheared until its basis is skewed, then reduced to a less skewed basis of the same
/// lattice: the stress is unchanged at once and after 200 more shearing steps (the two runs
/// differ only by the rounding of the shifted image positions), and the reduced cell is
/// wider across both axes.
#[test]
fn cell_reduction_changes_nothing_physical() {
    let (config, base, dt) = packing();
    let mut a = base.clone();
    let mut stepper = RveStepper::new(*config);
    // Simple shear γ̇ dt = 2e-3 per step: 400 steps give γ = 0.8, h₁·h₂/|h₁|² ≈ 0.8.
    let l = Mat2::new(0.0, 2e-3 / dt, 0.0, 0.0);
    for _ in 0..400 {
        stepper.step(&mut a, &l, *dt).unwrap();
    }
    let mut b = a.clone();
    let widths = |s: &RveState| s.cell.width(0).min(s.cell.width(1));
    assert!(b.reduce_cell().unwrap(), "a cell sheared by 0.8 is reduced");
    assert!(widths(&b) > widths(&a), "{} vs {}", widths(&b), widths(&a));
    assert!((b.cell.area() - a.cell.area()).abs() <= 1e-12 * a.cell.area());
    let strain_a = a.cell.strain();
    let strain_b = b.cell.strain();
    assert!((strain_a.deviatoric - strain_b.deviatoric).abs() <= 1e-9);
    let t = config.params().thickness;
    let sa = evaluated_stress(config, &mut a);
    let sb = evaluated_stress(config, &mut b);
    let scale = sa.max_abs();
    for i in 0..2 {
        for j in 0..2 {
            assert!(close(sa.at(i, j), sb.at(i, j), scale, 1e-10), "σ{i}{j}");
        }
    }
    let mut sb_stepper = RveStepper::new(*config);
    let l_slow = Mat2::new(0.0, 2e-5 / dt, 0.0, -1e-5 / dt);
    for _ in 0..200 {
        stepper.step(&mut a, &l_slow, *dt).unwrap();
        sb_stepper.step(&mut b, &l_slow, *dt).unwrap();
    }
    let (pa, ta) = measure::stress(&a, t).invariants_2d();
    let (pb, tb) = measure::stress(&b, t).invariants_2d();
    assert!(close(pa, pb, pa.abs(), 1e-8), "p {pa} vs {pb}");
    assert!(close(ta, tb, pa.abs(), 1e-8), "τ {ta} vs {tb}");
    assert_eq!(
        a.contacts.intact_bond_count(),
        b.contacts.intact_bond_count()
    );
    assert!(!b.reduce_cell().unwrap(), "a reduced cell stays reduced");
}
