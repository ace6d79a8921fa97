//! Physics of the periodic cell against closed-form results: strain measure, affine motion,
//! Love stress of a single contact across the boundary, thermal expansion, conductivity,
//! stiffness and thermally sensitive bonds.

use thm_dem::{LinearSpringParams, ThermalBondParams, Vec3};
use thm_rve::*;

fn params() -> RveParams {
    RveParams::paper_b_table_1()
}

/// Two disks touching across the right face of a 10 mm × 10 mm cell, overlap `delta`.
fn pair_across_boundary(delta: f64, p: &RveParams) -> RveState {
    let (w, r) = (10e-3, 0.5e-3);
    let cell = PeriodicCell::rectangle(w, w).unwrap();
    let x_a = 0.2e-3;
    // b sits left of the right face; its image at x_b − w touches a from the left.
    let x_b = x_a + w - (2.0 * r - delta);
    let centres = [Vec3::new(x_a, 5e-3, 0.0), Vec3::new(x_b, 5e-3, 0.0)];
    RveState::new(
        cell,
        &centres,
        &[r, r],
        p.density,
        p.thickness,
        p.reference_temperature,
    )
    .unwrap()
}

#[test]
fn strain_measure_of_stretch_and_shear_follows_b_eqs_47_48() {
    let mut cell = PeriodicCell::rectangle(2.0, 1.0).unwrap();
    cell.set_matrix(Mat2::new(2.02, 0.0, 0.0, 0.99)).unwrap();
    let s = cell.strain();
    assert!((s.tensor.at(0, 0) - 0.01).abs() < 1e-14);
    assert!((s.tensor.at(1, 1) + 0.01).abs() < 1e-14);
    assert!(s.volumetric.abs() < 1e-14);
    // ε' = diag(0.01, −0.01): ε_q = √(2 · 2e-4) = 0.02.
    assert!((s.deviatoric - 0.02).abs() < 1e-14);
    // Simple shear γ: E_xy = γ/2, no volume change.
    cell.set_matrix(Mat2::new(2.0, 0.004, 0.0, 1.0)).unwrap();
    let s = cell.strain();
    assert!((s.tensor.at(0, 1) - 0.002).abs() < 1e-15);
    assert!(s.volumetric.abs() < 1e-15);
}

#[test]
fn affine_motion_leaves_reduced_coordinates_unchanged() {
    let p = params();
    let config = p.validate().unwrap();
    let cell = PeriodicCell::rectangle(20e-3, 20e-3).unwrap();
    let centres: Vec<Vec3> = (0..9)
        .map(|i| {
            Vec3::new(
                2e-3 + 6e-3 * (i % 3) as f64,
                3e-3 + 6e-3 * (i / 3) as f64,
                0.0,
            )
        })
        .collect();
    let mut s = RveState::new(cell, &centres, &[0.5e-3; 9], p.density, p.thickness, 300.0).unwrap();
    let reduced0: Vec<Vec3> = centres.iter().map(|&x| s.cell.to_reduced(x)).collect();
    let l = Mat2::new(-0.3, 0.8, 0.2, 0.1);
    let mut stepper = RveStepper::new(config);
    let mut h = *s.cell.matrix();
    for _ in 0..200 {
        stepper.step(&mut s, &l, 1e-3).unwrap();
        h = h.add_scaled(&l.mul(&h), 1e-3);
    }
    for (x, x0) in s.disks.position.iter().zip(&reduced0) {
        let r = s.cell.to_reduced(*x);
        // Wrapped into the cell: equal up to a whole period.
        let d = r - *x0;
        assert!((d.x - d.x.round()).abs() < 1e-12 && (d.y - d.y.round()).abs() < 1e-12);
    }
    assert!(s.disks.velocity.iter().all(|v| *v == Vec3::ZERO));
    for i in 0..2 {
        for j in 0..2 {
            assert!((s.cell.matrix().at(i, j) - h.at(i, j)).abs() < 1e-15);
        }
    }
}

#[test]
fn single_contact_across_boundary_gives_love_stress_conductivity_and_stiffness() {
    let p = params();
    let config = p.validate().unwrap();
    let delta = 1e-6;
    let mut s = pair_across_boundary(delta, &p);
    RveStepper::new(config)
        .step(&mut s, &Mat2::ZERO, 0.0)
        .unwrap();
    let v = s.volume(p.thickness);
    let l = 1e-3 - delta;
    let f = p.contact.normal_stiffness * delta;
    let sigma = measure::stress(&s, p.thickness);
    assert!((sigma.at(0, 0) - f * l / v).abs() <= 1e-9 * f * l / v);
    assert!(sigma.at(1, 1).abs() < 1e-12 && sigma.at(0, 1).abs() < 1e-12);
    let k = measure::conductivity(&s, &p);
    let expected = l / (p.thermal_resistance * v);
    assert!((k.at(0, 0) - expected).abs() <= 1e-12 * expected);
    assert_eq!(k.at(1, 1), 0.0);
    let d = measure::stiffness(&s, &p);
    let kn = p.contact.normal_stiffness * l * l / v;
    assert!((d[0][0][0][0] - kn).abs() <= 1e-12 * kn);
    // Tangential part: t = ŷ, so D_yxyx = k_t l² / V.
    assert!((d[1][0][1][0] - kn).abs() <= 1e-12 * kn);
}

#[test]
fn thermal_expansion_raises_contact_force_by_k_n_beta_dt_sum_of_radii() {
    let p = params();
    let config = p.validate().unwrap();
    let delta = 1e-6;
    let mut s = pair_across_boundary(delta, &p);
    let mut stepper = RveStepper::new(config);
    let dtemp = 20.0;
    stepper
        .set_temperature(&mut s, p.reference_temperature + dtemp)
        .unwrap();
    for (r, r0) in s.disks.radius.iter().zip(&s.disks.reference_radius) {
        assert!((r - r0 * (1.0 + p.thermal_expansion_coefficient * dtemp)).abs() < 1e-18);
    }
    stepper.step(&mut s, &Mat2::ZERO, 0.0).unwrap();
    let f = s.contacts.force_on_b[0].norm();
    let expected = p.contact.normal_stiffness
        * (delta + p.thermal_expansion_coefficient * dtemp * 2.0 * 0.5e-3);
    assert!((f - expected).abs() <= 1e-9 * expected, "{f} vs {expected}");
    // Back to the reference temperature: back to the reference radii, exactly.
    stepper
        .set_temperature(&mut s, p.reference_temperature)
        .unwrap();
    assert_eq!(s.disks.radius, s.disks.reference_radius);
}

#[test]
fn thermally_sensitive_bond_breaks_at_beta_b_k_n_r_and_melts_above_threshold() {
    let mut p = params();
    let bond = ThermalBondParams {
        strength_coefficient: 0.01,
        threshold_temperature_rise: 10.0,
        reference_temperature: p.reference_temperature,
        shear_ratio: 0.5,
    };
    p.contact = LinearSpringParams {
        thermal_bond: Some(bond),
        ..p.contact
    };
    p.thermal_expansion_coefficient = 0.0;
    let config = p.validate().unwrap();
    let r = 0.5e-3;
    for (rise, expected_strength) in [(0.0, 0.01 * 1e6 * r), (5.0, 0.005 * 1e6 * r), (12.0, 0.0)] {
        let mut s = pair_across_boundary(1e-7, &p);
        let mut stepper = RveStepper::new(config);
        stepper
            .set_temperature(&mut s, p.reference_temperature + rise)
            .unwrap();
        stepper.step(&mut s, &Mat2::ZERO, 0.0).unwrap();
        assert_eq!(s.install_bonds(), 1);
        // Quasi-static opening: disks too heavy to respond to the bond force.
        s.disks.mass.iter_mut().for_each(|m| *m = 1e30);
        s.disks.inertia.iter_mut().for_each(|i| *i = 1e30);
        // Stretch the cell along x: the contact opens at 1 nm per step.
        let dt = 1e-6;
        // Strain 10⁻⁶ per step opens the 1 mm branch by 1 nm per step.
        let rate = 1e-6 / dt;
        let l = Mat2::diagonal(rate, 0.0);
        let mut max_tension: f64 = 0.0;
        for _ in 0..20_000 {
            stepper.step(&mut s, &l, dt).unwrap();
            let h = s.contacts.history[0];
            let f = s.contacts.force_on_b[0];
            let b = s.contacts.branch[0];
            max_tension = max_tension.max(-f.dot(b) / b.norm());
            if h.bond == thm_dem::BondState::Broken {
                break;
            }
        }
        assert_eq!(s.contacts.history[0].bond, thm_dem::BondState::Broken);
        // The bond held up to its strength, within one step's force increment (k_n · 1 nm).
        assert!(
            max_tension <= expected_strength + 1e-12,
            "{max_tension} > {expected_strength}"
        );
        assert!(max_tension >= expected_strength - 1e6 * 1e-9 - 1e-12);
    }
}
