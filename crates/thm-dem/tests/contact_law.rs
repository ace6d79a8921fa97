//! Contact-law thresholds and frame rotation, driven through the pure law functions.

mod common;
use common::table1;
use thm_dem::*;

const RA: f64 = 1.0e-3;
const RB: f64 = 2.0e-3;

fn pair() -> PairInput {
    PairInput {
        radius_a: RA,
        radius_b: RB,
        temperature: 293.15,
    }
}

/// Kinematics of a pair along x with the given penetration and shear increment.
fn along_x(penetration: f64, shear_increment: Vec3) -> ContactKinematics {
    let n = Vec3::new(1.0, 0.0, 0.0);
    ContactKinematics {
        normal: n,
        penetration,
        shear_increment,
        twist_angle: 0.0,
        arm_a: RA - 0.5 * penetration,
        arm_b: RB - 0.5 * penetration,
    }
}

#[test]
fn stiffnesses_follow_a_eq_3() {
    let props = table1().properties(&pair());
    let kn = 3.36e9 * 2.0 * RA * RB / (RA + RB);
    assert!((props.normal_stiffness - kn).abs() <= 1e-12 * kn);
    assert!((props.shear_stiffness - 0.3 * kn).abs() <= 1e-12 * kn);
    assert!((props.friction_coefficient - 18f64.to_radians().tan()).abs() < 1e-15);
}

/// Pulls a bond apart in small increments; returns (largest tension carried, tension that
/// broke it, index of the breaking increment).
fn pull_until_break(law: &CohesiveFrictional, u0: f64, du: f64) -> (f64, f64, BreakMode) {
    let mut h = ContactHistory::bonded_at(u0);
    let mut carried: f64 = 0.0;
    for k in 0..100_000 {
        let pen = u0 - du * k as f64;
        let r = law.respond(&pair(), &along_x(pen, Vec3::ZERO), &mut h);
        if let Some(mode) = r.broke {
            assert_eq!(h.bond, BondState::Broken);
            assert_eq!(r.normal_force, 0.0, "a broken bond carries no tension");
            let props = law.properties(&pair());
            return (carried, -props.normal_stiffness * (pen - u0), mode);
        }
        carried = carried.max(-r.normal_force);
    }
    panic!("bond never broke");
}

#[test]
fn bond_breaks_when_tension_reaches_t_r_min_squared() {
    let law = table1();
    let kn = law.properties(&pair()).normal_stiffness;
    let du = 1e-9;
    // Stress-free at a small overlap and across a gap: the threshold does not move.
    for u0 in [2e-6, 0.0, -3e-6] {
        let (carried, breaking, mode) = pull_until_break(&law, u0, du);
        let limit = 30e6 * RA * RA; // T·R², R = min(R_A, R_B)
        assert_eq!(mode, BreakMode::Tension);
        assert!(
            carried <= limit && carried > limit - kn * du * 1.000001,
            "carried {carried} vs {limit}"
        );
        assert!(breaking > limit && breaking <= limit + kn * du * 1.000001);
    }
    // With the mean radius the threshold is T·((R_A+R_B)/2)².
    let mean = CohesiveFrictionalParams {
        bond_radius: BondRadius::Mean,
        ..CohesiveFrictionalParams::paper_a_table_1()
    }
    .validate()
    .unwrap();
    let (carried, _, _) = pull_until_break(&mean, 0.0, du);
    let limit = 30e6 * (0.5 * (RA + RB)).powi(2);
    assert!(carried <= limit && carried > limit - kn * du * 1.000001);
}

#[test]
fn bond_breaks_in_shear_at_cohesion_plus_friction() {
    let law = table1();
    let props = law.properties(&pair());
    let overlap = 5e-6;
    let fn_ = props.normal_stiffness * overlap;
    let limit = 150e6 * RA * RA + fn_ * 18f64.to_radians().tan();
    let du = 1e-9;
    let mut h = ContactHistory::bonded_at(0.0);
    let mut carried = 0.0;
    let mut broke_at = None;
    for k in 0..200_000 {
        let r = law.respond(&pair(), &along_x(overlap, Vec3::new(0.0, du, 0.0)), &mut h);
        if r.broke.is_some() {
            assert_eq!(r.broke, Some(BreakMode::Shear));
            broke_at = Some(k);
            // After breakage: frictional, capped at F_n tan μ (A-Eq. 5).
            let cap = fn_ * props.friction_coefficient;
            assert!((h.shear_force.norm() - cap).abs() <= 1e-12 * cap);
            break;
        }
        carried = h.shear_force.norm();
    }
    assert!(broke_at.is_some());
    let ks = props.shear_stiffness;
    assert!(
        carried <= limit && carried > limit - ks * du * 1.000001,
        "carried {carried} limit {limit}"
    );
    // Tension lowers the shear strength (modified Mohr–Coulomb, signed F_n).
    let mut h = ContactHistory::bonded_at(0.0);
    let tension = -2e-6;
    let f_t = props.normal_stiffness * tension;
    let limit_t = 150e6 * RA * RA + f_t * props.friction_coefficient;
    let mut carried_t = 0.0;
    for _ in 0..200_000 {
        let r = law.respond(&pair(), &along_x(tension, Vec3::new(0.0, 0.0, du)), &mut h);
        if r.broke.is_some() {
            break;
        }
        carried_t = h.shear_force.norm();
    }
    assert!(carried_t <= limit_t && carried_t > limit_t - ks * du * 1.000001);
}

#[test]
fn sliding_starts_at_coulomb_limit_and_dissipates_the_slip_work() {
    let law = table1();
    let props = law.properties(&pair());
    let overlap = 4e-6;
    let fn_ = props.normal_stiffness * overlap;
    let cap = fn_ * props.friction_coefficient;
    let du = 2e-9;
    let steps = 20_000;
    let mut h = ContactHistory::UNBONDED;
    let mut work = 0.0;
    let mut first_slip = None;
    for k in 0..steps {
        let r = law.respond(&pair(), &along_x(overlap, Vec3::new(0.0, du, 0.0)), &mut h);
        assert!((r.normal_force - fn_).abs() <= 1e-12 * fn_);
        if r.friction_work > 0.0 && first_slip.is_none() {
            first_slip = Some(k);
        }
        work += r.friction_work;
        assert!(h.shear_force.norm() <= cap * (1.0 + 1e-14));
    }
    // Elastic up to F_s = F_n tan μ: slip begins at the first increment that would exceed it.
    let k_slip = first_slip.unwrap() as f64;
    let expected = (cap / (props.shear_stiffness * du)).floor();
    assert_eq!(k_slip, expected);
    // Shear force on B opposes B's motion (−y).
    assert!((h.shear_force.y + cap).abs() <= 1e-12 * cap);
    // Dissipated work = cap × slip distance (total travel minus the elastic part).
    let slip = steps as f64 * du - cap / props.shear_stiffness;
    assert!(
        (work - cap * slip).abs() <= 1e-9 * cap * slip,
        "work {work} vs {}",
        cap * slip
    );
}

#[test]
fn contact_frame_rotation_carries_the_shear_force() {
    let law = table1();
    let (ra, rb) = (RA, RB);
    let d = ra + rb - 3e-6;
    let mut h = ContactHistory::bonded_at(0.0);
    let input = pair();
    // Load the contact in shear: B moves +y relative to A.
    let n0 = Vec3::new(1.0, 0.0, 0.0);
    let kin = ContactKinematics::from_pair(
        n0 * d,
        Vec3::new(0.0, 0.1, 0.0),
        Vec3::ZERO,
        Vec3::ZERO,
        ra,
        rb,
        1e-6,
    );
    law.respond(&input, &kin, &mut h);
    let f0 = h.shear_force;
    assert!(f0.y < 0.0 && f0.norm() > 0.0);
    // Rigid rotation about z by π/2 in 10⁴ steps: spin Ω, centres advanced by the velocity as
    // an integrator does (relative velocity = chord / Δt).
    let steps = 10_000;
    let dt = 1e-5;
    let omega = std::f64::consts::FRAC_PI_2 / (steps as f64 * dt);
    let w = Vec3::new(0.0, 0.0, omega);
    for k in 1..=steps {
        let th = omega * dt * k as f64;
        let branch = Vec3::new(th.cos(), th.sin(), 0.0) * d;
        let thp = th - omega * dt;
        let vrel = (branch - Vec3::new(thp.cos(), thp.sin(), 0.0) * d) / dt;
        let kin = ContactKinematics::from_pair(branch, vrel, w, w, ra, rb, dt);
        law.respond(&input, &kin, &mut h);
    }
    // f0 = (0, −|f0|, 0) rotated by +π/2 about z is (+|f0|, 0, 0).
    let expected = Vec3::new(-f0.y, f0.x, 0.0);
    // The frame rotation itself is exact; the only error is the chord-vs-arc slip of the
    // discrete kinematics, d (Δθ − sin Δθ) ≈ d Δθ³/6 per step, loaded through K_s.
    let dtheta = omega * dt;
    let ks = law.properties(&input).shear_stiffness;
    let bound = steps as f64 * ks * d * dtheta.powi(3) / 6.0;
    let err = (h.shear_force - expected).norm();
    assert!(
        err <= 1.2 * bound && bound < 1e-3 * f0.norm(),
        "{:?} vs {:?}: {err} > {bound}",
        h.shear_force,
        expected
    );
    // Spin of both spheres about the normal (twist) turns the shear force about the normal.
    let mut h = ContactHistory::bonded_at(0.0);
    law.respond(&input, &kin_x(d), &mut h);
    let g0 = Vec3::new(0.0, -1.0, 0.0) * h.shear_force.norm();
    h.shear_force = g0;
    let spin = Vec3::new(omega, 0.0, 0.0);
    for _ in 0..steps {
        let kin = ContactKinematics::from_pair(n0 * d, Vec3::ZERO, spin, spin, ra, rb, dt);
        law.respond(&input, &kin, &mut h);
    }
    let expected = Vec3::new(0.0, 0.0, -g0.norm());
    assert!((h.shear_force - expected).norm() <= 1e-9 * g0.norm());
}

fn kin_x(d: f64) -> ContactKinematics {
    ContactKinematics::from_pair(
        Vec3::new(d, 0.0, 0.0),
        Vec3::new(0.0, 1e-3, 0.0),
        Vec3::ZERO,
        Vec3::ZERO,
        RA,
        RB,
        1e-6,
    )
}

#[test]
fn thermal_bond_strength_follows_b_eqs_38_to_40() {
    let bond = ThermalBondParams {
        strength_coefficient: 0.02,
        threshold_temperature_rise: 10.0,
        reference_temperature: 273.15,
        shear_ratio: 0.5,
    };
    let law = LinearSpringParams {
        normal_stiffness: 1e6,
        tangential_stiffness: 5e5,
        friction_coefficient: 0.5,
        thermal_bond: Some(bond),
    }
    .validate()
    .unwrap();
    let r_mean = 0.5 * (RA + RB);
    for (t, beta) in [
        (273.15, 0.02),
        (278.15, 0.01),
        (283.15, 0.0),
        (300.0, 0.0),
        (263.15, 0.04),
    ] {
        let p = law.properties(&PairInput {
            temperature: t,
            ..pair()
        });
        let fnb = beta * 1e6 * r_mean;
        assert!(
            (p.bond_tensile_strength - fnb).abs() <= 1e-12 * 1e6 * r_mean,
            "T = {t}"
        );
        assert!((p.bond_shear_strength - 0.5 * fnb).abs() <= 1e-12 * 1e6 * r_mean);
        assert!(!p.friction_adds_to_bond_shear);
    }
    // A bond held at a fixed tension breaks during heating exactly when β_b k_n R̄ drops below
    // the tension: tension = k_n·1e-6 ⇒ β_b = 1e-6 / R̄ ⇒ ΔT = T_s (1 − β_b/β_a).
    let stretch = 1e-6;
    let beta_break = stretch / r_mean;
    let dt_break = 10.0 * (1.0 - beta_break / 0.02);
    let mut h = ContactHistory::bonded_at(0.0);
    let d_temp = 1e-3;
    let mut broke_at = None;
    for k in 0..20_000 {
        let t = 273.15 + d_temp * k as f64;
        let r = law.respond(
            &PairInput {
                temperature: t,
                ..pair()
            },
            &along_x(-stretch, Vec3::ZERO),
            &mut h,
        );
        if r.broke == Some(BreakMode::Tension) {
            broke_at = Some(d_temp * k as f64);
            break;
        }
    }
    let rise = broke_at.unwrap();
    assert!(
        rise >= dt_break && rise <= dt_break + d_temp * 1.0001,
        "{rise} vs {dt_break}"
    );
}

#[test]
fn a_bond_at_rest_carries_no_force() {
    let law = table1();
    for u0 in [-5e-6, 0.0, 7e-6] {
        let mut h = ContactHistory::bonded_at(u0);
        let r = law.respond(&pair(), &along_x(u0, Vec3::ZERO), &mut h);
        assert_eq!(r.force_on_b, Vec3::ZERO);
        assert!(r.active);
    }
}
