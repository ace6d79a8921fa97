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

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// The area porosity lies in [0, 1], is not raised by adding a particle, and for disjoint
    /// disks inside the rectangle equals `1 − Σ πr²/A` within the grid error.
    #[test]
    fn area_porosity_is_a_covered_share(
        disks in proptest::collection::vec((1e-3..9e-3f64, 1e-3..9e-3f64, 2e-4..1.5e-3f64), 1..12),
        extra in (0.0..0.01f64, 0.0..0.01f64, 1e-4..3e-3f64),
    ) {
        use thm_dem::packing::{Packing, area_porosity};
        let make = |d: &[(f64, f64, f64)]| Packing {
            kinematics: Kinematics::SpheresInPlane,
            centres: d.iter().map(|&(x, y, _)| Vec3::new(x, y, 0.0)).collect(),
            radii: d.iter().map(|&(_, _, r)| r).collect(),
            bonds: Vec::new(),
        };
        let cell = 2e-5;
        let (lo, hi) = ([0.0, 0.0], [0.01, 0.01]);
        let phi = area_porosity(&make(&disks), lo, hi, cell).unwrap();
        prop_assert!((0.0..=1.0).contains(&phi));
        let mut more = disks.clone();
        more.push(extra);
        let phi_more = area_porosity(&make(&more), lo, hi, cell).unwrap();
        prop_assert!(phi_more <= phi);
        let inside = disks.iter().all(|&(x, y, r)| x - r > 0.0 && x + r < 0.01 && y - r > 0.0 && y + r < 0.01);
        let disjoint = disks.iter().enumerate().all(|(i, a)| {
            disks[i + 1..].iter().all(|b| ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt() > a.2 + b.2 + 2.0 * cell)
        });
        if inside && disjoint {
            let area: f64 = disks.iter().map(|d| std::f64::consts::PI * d.2 * d.2).sum();
            let perimeter: f64 = disks.iter().map(|d| 2.0 * std::f64::consts::PI * d.2).sum();
            prop_assert!((phi - (1.0 - area / 1e-4)).abs() <= perimeter * cell / 1e-4);
        }
    }
}
