//! Property tests of the invariants the crate promises.

mod common;
use common::*;
use proptest::prelude::*;
use thm_dem::*;

fn vec3(range: f64) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Per contact: A receives −F (Newton's third law) and the torques close the angular
    /// momentum balance `d × F + τ_A + τ_B = 0` to round-off.
    #[test]
    fn contact_forces_balance_linear_and_angular_momentum(
        ra in 0.5e-3..4e-3f64,
        rb in 0.5e-3..4e-3f64,
        dir in vec3(1.0),
        overlap in -2e-6..2e-5f64,
        vrel in vec3(0.5),
        wa in vec3(100.0),
        wb in vec3(100.0),
        bonded in any::<bool>(),
        pre_shear in vec3(5.0),
    ) {
        prop_assume!(dir.norm() > 0.1);
        let branch = dir / dir.norm() * (ra + rb - overlap);
        let kin = ContactKinematics::from_pair(branch, vrel, wa, wb, ra, rb, 1e-7);
        let law = table1();
        let mut h = if bonded { ContactHistory::bonded_at(0.0) } else { ContactHistory::UNBONDED };
        let n = branch / branch.norm();
        h.shear_force = pre_shear - n * pre_shear.dot(n);
        h.normal = n;
        let r = law.respond(&PairInput { radius_a: ra, radius_b: rb, temperature: 300.0 }, &kin, &mut h);
        let f = r.force_on_b;
        let moment = branch.cross(f) + r.torque_on_a + r.torque_on_b;
        prop_assert!(moment.norm() <= 1e-12 * (f.norm() * branch.norm()).max(1e-300));
        // Admissible forces: shear on the tangent plane; no tension without an intact bond;
        // Coulomb limit without a bond.
        let fs = f - n * f.dot(n);
        prop_assert!((f.dot(n) - r.normal_force).abs() <= 1e-9 * f.norm().max(1e-300));
        if h.bond != BondState::Intact {
            prop_assert!(r.normal_force >= 0.0);
            let tan = 18f64.to_radians().tan();
            prop_assert!(fs.norm() <= r.normal_force * tan * (1.0 + 1e-12) + 1e-300);
        } else {
            prop_assert!(r.broke.is_none());
        }
    }

    /// An isolated, undamped system without gravity conserves linear momentum to round-off,
    /// bonds breaking or not.
    #[test]
    fn isolated_system_conserves_momentum(seed in 0u64..1000, planar in any::<bool>(), speed in 0.01..2.0f64) {
        let kin = if planar { Kinematics::SpheresInPlane } else { Kinematics::Spheres3d };
        let (nx, ny, nz) = if planar { (6, 5, 1) } else { (3, 3, 3) };
        let p = jittered_lattice(kin, nx, ny, nz, seed, speed);
        let mut state = DemState::new(p, vec![]);
        state.install_bonds(3e-5).unwrap();
        let law = CohesiveFrictionalParams { tensile_strength: 1e5, cohesion: 4e5, ..CohesiveFrictionalParams::paper_a_table_1() }
            .validate()
            .unwrap();
        let dt = 0.5 * critical_time_step(&state, &law);
        let p0 = state.particles.momentum();
        let scale: f64 = state.particles.mass.iter().zip(&state.particles.velocity).map(|(m, v)| m * v.norm()).sum();
        let mut stepper = Stepper::new(law, stepper_params(dt, 0.0).validate().unwrap());
        stepper.run(&mut state, 200).unwrap();
        let p1 = state.particles.momentum();
        prop_assert!((p1 - p0).norm() <= 1e-12 * scale, "{:?} vs {:?}", p0, p1);
    }
}
