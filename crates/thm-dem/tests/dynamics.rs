//! Whole-step dynamics: rebound, damping, bond breakage in a run, walls, gravity, plane
//! constraint, thermal expansion, parity across thread counts, save/restore.

mod common;
use common::*;
use thm_dem::*;

fn cohesionless() -> CohesiveFrictional {
    CohesiveFrictionalParams {
        cohesion: 0.0,
        tensile_strength: 0.0,
        ..CohesiveFrictionalParams::paper_a_table_1()
    }
    .validate()
    .unwrap()
}

/// Head-on collision of two equal spheres; returns kinetic energy before and after.
fn rebound(damping: f64, kin: Kinematics) -> (f64, f64, Vec3, Vec3) {
    rebound_dt(damping, kin, 0.02)
}

fn rebound_dt(damping: f64, kin: Kinematics, dt_fraction: f64) -> (f64, f64, Vec3, Vec3) {
    let r = 1e-3;
    let mut state = DemState::new(two_spheres(kin, r, r, 1e-5), vec![]);
    state.particles.velocity[0] = Vec3::new(0.05, 0.0, 0.0);
    state.particles.velocity[1] = Vec3::new(-0.05, 0.0, 0.0);
    let law = cohesionless();
    let dt = dt_fraction * critical_time_step(&state, &law);
    let e0 = state.particles.kinetic_energy();
    let p0 = state.particles.momentum();
    let mut stepper = Stepper::new(law, stepper_params(dt, damping).validate().unwrap());
    let mut touched = false;
    for _ in 0..1_000_000 {
        stepper.step(&mut state).unwrap();
        let active = state.contacts.active_count() > 0;
        touched |= active;
        if touched && !active {
            break;
        }
    }
    assert!(touched);
    assert_eq!(state.contacts.active_count(), 0);
    (
        e0,
        state.particles.kinetic_energy(),
        p0,
        state.particles.momentum(),
    )
}

#[test]
fn elastic_rebound_conserves_energy_without_damping() {
    // Leapfrog is symplectic and second order: what comes out after the contact is the energy
    // that went in, up to an error that falls as Δt² (from the contact opening and closing
    // between steps).
    for kin in [
        Kinematics::Spheres3d,
        Kinematics::SpheresInPlane,
        Kinematics::Disks,
    ] {
        let mut errors = Vec::new();
        for fraction in [0.04, 0.02, 0.01] {
            let (e0, e1, p0, p1) = rebound_dt(0.0, kin, fraction);
            errors.push((e1 - e0).abs() / e0);
            assert!((p1 - p0).norm() <= 1e-15 * p0.norm().max(1e-3));
        }
        eprintln!("{kin:?}: relative energy errors {errors:?}");
        // Bound 0.1 (ω Δt)² with ω² = 2k/m of the pair, Δt = f Δt_crit = f √(m/(k_n + k_s)).
        for (fraction, err) in [0.04, 0.02, 0.01].iter().zip(&errors) {
            let omega_dt_sq = 2.0 * fraction * fraction / 1.3;
            assert!(*err <= 0.1 * omega_dt_sq, "{kin:?}: {errors:?}");
        }
    }
}

#[test]
fn cundall_damping_removes_the_predicted_share() {
    // Approach: |F| amplified by (1 + α); rebound: reduced by (1 − α). With a linear spring the
    // kinetic energy returns in the ratio (1 − α)/(1 + α).
    for alpha in [0.08, 0.3] {
        let (e0, e1, _, _) = rebound(alpha, Kinematics::Spheres3d);
        let expected = (1.0 - alpha) / (1.0 + alpha);
        assert!(
            (e1 / e0 - expected).abs() <= 2e-3 * expected,
            "α = {alpha}: {} vs {expected}",
            e1 / e0
        );
    }
}

#[test]
fn bond_breaks_in_a_run_at_t_r_squared_and_is_reported() {
    let (ra, rb) = (1.5e-3, 2.5e-3);
    let mut state = DemState::new(
        two_spheres(Kinematics::SpheresInPlane, ra, rb, 2e-6),
        vec![],
    );
    assert_eq!(state.install_bonds(1e-5).unwrap(), 1);
    // Grips: both particles move apart at prescribed velocity.
    let v = 1e-3;
    state.particles.fixed = vec![true, true];
    state.particles.velocity[0] = Vec3::new(-v, 0.0, 0.0);
    state.particles.velocity[1] = Vec3::new(v, 0.0, 0.0);
    let law = table1();
    let dt = 1e-7;
    let mut stepper = Stepper::new(law, stepper_params(dt, 0.08).validate().unwrap());
    let kn = law
        .properties(&PairInput {
            radius_a: ra,
            radius_b: rb,
            temperature: 300.0,
        })
        .normal_stiffness;
    let limit = 30e6 * ra * ra;
    let mut carried: f64 = 0.0;
    while state.bond_breaks.is_empty() {
        stepper.step(&mut state).unwrap();
        if state.bond_breaks.is_empty() {
            carried = carried.max(-state.contacts.report[0].normal_force);
            // Force on the grip = tension of the bond (Newton's third law).
            assert!(
                (state.particles.force[1].x - state.contacts.report[0].normal_force).abs() < 1e-9
            );
            // The contact's force as the list reports it is the force the particles received.
            assert_eq!(state.contacts.force_on_b(0), state.particles.force[1]);
            assert_eq!(-state.contacts.force_on_b(0), state.particles.force[0]);
        }
        assert!(state.step < 10_000_000);
    }
    let ev = state.bond_breaks[0];
    assert_eq!((ev.a, ev.b, ev.mode), (0, 1, BreakMode::Tension));
    let increment = kn * 2.0 * v * dt;
    assert!(
        carried <= limit && carried >= limit - increment * 1.0001,
        "{carried} vs {limit}"
    );
    assert_eq!(state.contacts.broken_bond_count(), 1);
    // The bond was stress-free at creation across its 2 µm gap: it broke after stretching by
    // T R²/K_n, not at once.
    let stretch = 2.0 * v * (state.step - 1) as f64 * dt;
    assert!((stretch - limit / kn).abs() <= 2.0 * v * dt * 1.0001);
}

#[test]
fn sphere_settles_on_a_wall_under_gravity() {
    let r = 2e-3;
    let p = ParticleState::new(
        Kinematics::Spheres3d,
        2600.0,
        300.0,
        &[Vec3::new(0.0, 0.0, 1.05 * r)],
        &[r],
    )
    .unwrap();
    let floor = Wall::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)).unwrap();
    let mut state = DemState::new(p, vec![floor]);
    let law = cohesionless();
    let dt = 0.2 * critical_time_step(&state, &law);
    let mut params = stepper_params(dt, 0.3);
    params.gravity = [0.0, 0.0, -9.81];
    let mut stepper = Stepper::new(law, params.validate().unwrap());
    stepper.run(&mut state, 200_000).unwrap();
    let weight = state.particles.mass[0] * 9.81;
    assert!(
        (state.walls[0].force.z + weight).abs() <= 1e-6 * weight,
        "{:?} vs {weight}",
        state.walls[0].force
    );
    let kn = law
        .properties(&PairInput {
            radius_a: r,
            radius_b: r,
            temperature: 300.0,
        })
        .normal_stiffness;
    let overlap = r - state.particles.position[0].z;
    assert!((overlap - weight / kn).abs() <= 1e-6 * weight / kn);
}

#[test]
fn moving_plate_pushes_a_sphere_and_feels_the_reaction() {
    let r = 2e-3;
    let p = ParticleState::new(
        Kinematics::SpheresInPlane,
        2600.0,
        300.0,
        &[Vec3::new(0.0, 3e-3, 0.0)],
        &[r],
    )
    .unwrap();
    let mut plate = Wall::new(Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0)).unwrap();
    plate.velocity = Vec3::new(0.0, 0.02, 0.0);
    let mut state = DemState::new(p, vec![plate]);
    let law = cohesionless();
    let dt = 0.1 * critical_time_step(&state, &law);
    let mut stepper = Stepper::new(law, stepper_params(dt, 0.0).validate().unwrap());
    // Momentum given to the sphere = impulse of the plate force (Newton's third law).
    let mut impulse = Vec3::ZERO;
    for _ in 0..400_000 {
        stepper.step(&mut state).unwrap();
        impulse -= state.walls[0].force * dt;
    }
    let momentum = state.particles.momentum();
    assert!(momentum.y > 0.0);
    assert!((momentum - impulse).norm() <= 1e-9 * momentum.norm());
    assert_eq!(state.particles.position[0].z, 0.0);
}

#[test]
fn plane_constraint_keeps_motion_in_the_plane() {
    let mut p = jittered_lattice(Kinematics::SpheresInPlane, 6, 6, 1, 3, 0.01);
    for (i, f) in p.external_force.iter_mut().enumerate() {
        *f = Vec3::new(1e-3, -2e-3, 5e-3 * (i as f64 - 18.0));
    }
    for t in p.external_torque.iter_mut() {
        *t = Vec3::new(1e-6, 1e-6, 1e-7);
    }
    let mut state = DemState::new(p, vec![]);
    let law = table1();
    let dt = 0.2 * critical_time_step(&state, &law);
    let mut stepper = Stepper::new(law, stepper_params(dt, 0.0).validate().unwrap());
    stepper.run(&mut state, 500).unwrap();
    let p = &state.particles;
    assert!(p.position.iter().all(|x| x.z == 0.0));
    assert!(p.velocity.iter().all(|v| v.z == 0.0));
    assert!(p.angular_velocity.iter().all(|w| w.x == 0.0 && w.y == 0.0));
    assert!(p.angular_velocity.iter().any(|w| w.z != 0.0));
}

#[test]
fn heating_a_bonded_pair_builds_the_thermal_contact_force() {
    let (ra, rb) = (2e-3, 3e-3);
    let mut state = DemState::new(two_spheres(Kinematics::SpheresInPlane, ra, rb, 0.0), vec![]);
    state.install_bonds(1e-6).unwrap();
    state.particles.fixed = vec![true, true];
    let law = table1();
    let alpha = 8e-6;
    let d_t = 30.0;
    let t0 = state.particles.temperature[0];
    // A-Eq. 55 in 30 increments of 1 K vs B-Eq. 37 in one go.
    let mut incremental = state.particles.clone();
    for k in 1..=30 {
        incremental
            .expand_incremental(alpha, &[t0 + k as f64, t0 + k as f64])
            .unwrap();
    }
    state
        .particles
        .expand_from_reference(alpha, t0, &[t0 + d_t; 2])
        .unwrap();
    for i in 0..2 {
        let r0 = state.particles.reference_radius[i];
        assert!((state.particles.radius[i] - r0 * (1.0 + alpha * d_t)).abs() <= 1e-15 * r0);
        // Compounded increments differ from the linear law by ≈ r0 (α ΔT)² / 2 · (1 − 1/30).
        let diff = incremental.radius[i] - state.particles.radius[i];
        let second_order = r0 * (alpha * d_t).powi(2) / 2.0 * (1.0 - 1.0 / 30.0);
        assert!(
            (diff - second_order).abs() <= 1e-3 * second_order,
            "{diff} vs {second_order}"
        );
    }
    let mut stepper = Stepper::new(law, stepper_params(1e-7, 0.0).validate().unwrap());
    stepper.step(&mut state).unwrap();
    let (ra1, rb1) = (state.particles.radius[0], state.particles.radius[1]);
    let kn = 3.36e9 * 2.0 * ra1 * rb1 / (ra1 + rb1);
    let expected = kn * alpha * d_t * (ra + rb);
    let fnorm = state.contacts.report[0].normal_force;
    assert!(
        (fnorm - expected).abs() <= 1e-9 * expected,
        "{fnorm} vs {expected}"
    );
}

fn run_lattice(threads: usize, kin: Kinematics) -> DemState {
    let (nx, ny, nz) = if kin.is_planar() {
        (40, 40, 1)
    } else {
        (12, 12, 12)
    };
    run_lattice_of(threads, kin, [nx, ny, nz], 300)
}

fn run_lattice_of(
    threads: usize,
    kin: Kinematics,
    [nx, ny, nz]: [usize; 3],
    steps: u64,
) -> DemState {
    let p = jittered_lattice(kin, nx, ny, nz, 7, 0.5);
    let mut state = DemState::new(
        p,
        vec![Wall::new(Vec3::new(0.0, -1e-3, 0.0), Vec3::new(0.0, 1.0, 0.0)).unwrap()],
    );
    state.install_bonds(5e-5).unwrap();
    // Weak bonds so that some break within the run.
    let law = CohesiveFrictionalParams {
        tensile_strength: 1e5,
        cohesion: 5e5,
        ..CohesiveFrictionalParams::paper_a_table_1()
    }
    .validate()
    .unwrap();
    let dt = 0.5 * critical_time_step(&state, &law);
    let mut params = stepper_params(dt, 0.08);
    params.gravity = [0.0, -9.81e4, 0.0];
    params.verlet_skin = 1e-5; // frequent neighbour searches and history merges
    let mut stepper = Stepper::new(law, params.validate().unwrap());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| stepper.run(&mut state, steps)).unwrap();
    state
}

/// The bits of every position, velocity, angular velocity and stored shear force.
fn state_bits(s: &DemState) -> Vec<u64> {
    let p = &s.particles;
    p.position
        .iter()
        .chain(&p.velocity)
        .chain(&p.angular_velocity)
        .chain(s.contacts.history.iter().map(|h| &h.shear_force))
        .flat_map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
        .collect()
}

#[test]
fn one_and_two_threads_give_identical_bits() {
    for kin in [Kinematics::SpheresInPlane, Kinematics::Spheres3d] {
        let a = run_lattice(1, kin);
        let b = run_lattice(2, kin);
        assert!(a.contacts.len() > 1000);
        assert!(
            !a.bond_breaks.is_empty(),
            "the test should exercise breakage"
        );
        assert_eq!(state_bits(&a), state_bits(&b));
        assert_eq!(a, b);
    }
}

/// From 16 384 particles on the stepper's blocks hold 512 particles instead of 256: the same
/// bits on 1, 2 and 3 threads there too.
#[test]
fn one_two_and_three_threads_give_identical_bits_with_long_blocks() {
    let a = run_lattice_of(1, Kinematics::Spheres3d, [26, 26, 26], 30);
    assert!(a.particles.len() >= 16_384 && a.contacts.len() > 40_000);
    assert!(
        !a.bond_breaks.is_empty(),
        "the test should exercise breakage"
    );
    for threads in [2, 3] {
        let b = run_lattice_of(threads, Kinematics::Spheres3d, [26, 26, 26], 30);
        assert_eq!(state_bits(&a), state_bits(&b), "{threads} threads");
        assert_eq!(a, b);
    }
}

#[test]
fn save_restore_round_trip_continues_bit_for_bit() {
    let p = jittered_lattice(Kinematics::SpheresInPlane, 20, 20, 1, 11, 0.5);
    let mut state = DemState::new(p, vec![]);
    state.install_bonds(5e-5).unwrap();
    let law = table1();
    let dt = 0.5 * critical_time_step(&state, &law);
    let params = StepperParams {
        verlet_skin: 1e-5,
        ..stepper_params(dt, 0.08)
    }
    .validate()
    .unwrap();
    let mut stepper = Stepper::new(law, params);
    stepper.run(&mut state, 150).unwrap();
    let saved = serde_json::to_string(&state).unwrap();
    stepper.run(&mut state, 150).unwrap();
    let mut restored: DemState = serde_json::from_str(&saved).unwrap();
    let mut fresh = Stepper::new(law, params);
    fresh.run(&mut restored, 150).unwrap();
    assert_eq!(restored, state);
}

#[test]
fn unstable_time_step_stops_with_place_and_step() {
    // A sphere squeezed between two walls, stepped far above the critical time step.
    let p =
        ParticleState::new(Kinematics::Spheres3d, 2600.0, 300.0, &[Vec3::ZERO], &[1e-3]).unwrap();
    let walls = vec![
        Wall::new(Vec3::new(-0.99e-3, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)).unwrap(),
        Wall::new(Vec3::new(0.99e-3, 0.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)).unwrap(),
    ];
    let mut state = DemState::new(p, walls);
    state.particles.velocity[0] = Vec3::new(1e-3, 0.0, 0.0);
    let law = cohesionless();
    let dt = 50.0 * critical_time_step(&state, &law);
    let mut stepper = Stepper::new(law, stepper_params(dt, 0.0).validate().unwrap());
    let err = stepper.run(&mut state, 100_000).unwrap_err();
    assert!(matches!(err, DemError::NonFinite { .. }), "{err}");
}

#[test]
fn bad_parameters_are_rejected_with_the_field() {
    let e = StepperParams {
        time_step: -1.0,
        ..stepper_params(1.0, 0.0)
    }
    .validate()
    .unwrap_err();
    assert!(matches!(
        e,
        DemError::InvalidParameter {
            field: "time_step",
            ..
        }
    ));
    let e = StepperParams {
        damping: 1.0,
        ..stepper_params(1.0, 0.0)
    }
    .validate()
    .unwrap_err();
    assert!(matches!(
        e,
        DemError::InvalidParameter {
            field: "damping",
            ..
        }
    ));
    let e = CohesiveFrictionalParams {
        friction_angle_deg: f64::NAN,
        ..CohesiveFrictionalParams::paper_a_table_1()
    }
    .validate()
    .unwrap_err();
    assert!(matches!(
        e,
        DemError::InvalidParameter {
            field: "friction_angle_deg",
            ..
        }
    ));
    let e =
        ParticleState::new(Kinematics::Disks, 2600.0, 300.0, &[Vec3::ZERO], &[-1.0]).unwrap_err();
    assert!(matches!(
        e,
        DemError::InvalidParticle {
            index: 0,
            field: "radius",
            ..
        }
    ));
    let toml_like =
        r#"{"time_step":1e-7,"damping":0.1,"gravity":[0,0,0],"verlet_skin":1e-4,"extra":1}"#;
    assert!(serde_json::from_str::<StepperParams>(toml_like).is_err());
}

#[test]
fn friction_work_equals_the_kinetic_energy_lost_by_a_sliding_disk() {
    // A disk pressed onto a floor by gravity slides at 0.2 m/s; without damping, the kinetic
    // energy lost (translation + rotation) equals the friction work summed over the steps
    // (B-Eq. 32) up to the small elastic energy left in the springs at the end.
    let r = 2e-3;
    let p = ParticleState::new(
        Kinematics::Disks,
        2600.0,
        300.0,
        &[Vec3::new(0.0, r, 0.0)],
        &[r],
    )
    .unwrap();
    let floor = Wall::new(Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0)).unwrap();
    let mut state = DemState::new(p, vec![floor]);
    let law = LinearSpringParams {
        normal_stiffness: 1e5,
        tangential_stiffness: 4e4,
        friction_coefficient: 0.4,
        thermal_bond: None,
    }
    .validate()
    .unwrap();
    let dt = 0.05 * critical_time_step(&state, &law);
    let mut params = stepper_params(dt, 0.0);
    params.gravity = [0.0, -9.81, 0.0];
    let mut stepper = Stepper::new(law, params.validate().unwrap());
    // Settle vertically first (no sliding), then launch.
    let m = state.particles.mass[0];
    let g = 9.81;
    state.particles.position[0].y = r - m * g / 1e5;
    stepper.step(&mut state).unwrap();
    state.particles.velocity[0] = Vec3::new(1.0, 0.0, 0.0);
    let e0 = state.particles.kinetic_energy();
    let mut work = 0.0;
    for _ in 0..20_000 {
        stepper.step(&mut state).unwrap();
        work += state.wall_contacts.friction_work();
    }
    let e1 = state.particles.kinetic_energy();
    // Rolling without slip at the end: v = 2/3 v0 for a disk (I = mR²/2) ⇒ E1/E0 = 2/3, up
    // to the vibration of the stuck tangential spring.
    let v = state.particles.velocity[0].x;
    // Amplitude of that vibration: the friction force at sticking over √(k_t m_eff), with the
    // effective mass m I/(I + mR²) = m/3 of a rolling disk.
    let vibration = 0.4 * m * g / (4e4 * m / 3.0).sqrt();
    assert!(
        (v - 2.0 / 3.0).abs() <= vibration,
        "v = {v}, vibration amplitude {vibration}"
    );
    // Residual: elastic shear + normal vibration energy, bounded by F²/k terms.
    let elastic_bound = (0.4 * m * g).powi(2) / 4e4 + (m * g).powi(2) / 1e5;
    assert!(
        ((e0 - e1) - work).abs() <= elastic_bound,
        "lost {} vs work {work}",
        e0 - e1
    );
    assert!(work > 100.0 * elastic_bound);
}

/// The Verlet skin decides which pairs are listed and how often the list is rebuilt, never
/// the result: a lattice shaken hard enough that contacts open and close, under gravity on a
/// floor, with radii that grow and shrink (thermal expansion), gives the same bits with a
/// wide skin (few searches; listed pairs found apart are not looked at again until the drift
/// could have closed their gap; so few listed pairs carry force that the gather visits only
/// the particles that have one) as with a skin so thin that the list is rebuilt nearly every
/// step (and nearly every listed pair carries force).
#[test]
fn verlet_skin_and_skipped_pairs_do_not_change_a_bit() {
    let run = |skin: f64| -> DemState {
        let (mut state, law) = frictional_lattice_on_floor(5, 0.3);
        let dt = 0.2 * critical_time_step(&state, &law);
        let mut params = stepper_params(dt, 0.05);
        params.gravity = [0.0, 0.0, -9.81e3];
        params.verlet_skin = skin;
        let mut stepper = Stepper::new(law, params.validate().unwrap());
        let t0 = state.particles.temperature[0];
        for (k, rise) in [40.0, -30.0, 10.0, 0.0].into_iter().enumerate() {
            stepper.run(&mut state, 150).unwrap();
            let t = vec![t0 + rise; state.particles.len()];
            state.particles.expand_from_reference(1e-4, t0, &t).unwrap();
            if k == 0 {
                assert!(state.contacts.active_count() > 100);
            }
        }
        state
    };
    let wide = run(3e-4);
    let thin = run(1e-9);
    // The wide list holds many pairs that do not touch (so few carry force that the gather
    // skips the particles without one); the thin one holds little else and was rebuilt often.
    let (wide_active, thin_active) = (wide.contacts.active_count(), thin.contacts.active_count());
    assert!(wide.contacts.len() > 8 * wide_active && thin.contacts.len() < 4 * thin_active);
    assert!(wide.contact_generation < 60 && thin.contact_generation > 300);
    let bits = |s: &DemState| -> Vec<u64> {
        let p = &s.particles;
        p.position
            .iter()
            .chain(&p.velocity)
            .chain(&p.angular_velocity)
            .chain(&p.force)
            .flat_map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
            .collect()
    };
    assert_eq!(bits(&wide), bits(&thin));
}

/// A stepper holds only scratch: taking a saved state back (same contact generation, so the
/// stepper keeps its index and its record of pairs found apart, made on the states after the
/// saved one) and stepping on gives the bits of a fresh stepper.
#[test]
fn a_stepper_carries_nothing_from_one_state_to_another() {
    let (mut state, law) = frictional_lattice_on_floor(9, 0.05);
    let dt = 0.2 * critical_time_step(&state, &law);
    let mut params = stepper_params(dt, 0.05);
    params.gravity = [0.0, 0.0, -9.81];
    params.verlet_skin = 1e-3;
    let config = params.validate().unwrap();
    let mut stepper = Stepper::new(law, config);
    stepper.run(&mut state, 100).unwrap();
    // Save right after a search; continue while no other search happens.
    let generation = state.contact_generation;
    while state.contact_generation == generation {
        stepper.step(&mut state).unwrap();
    }
    let saved = state.clone();
    let mut steps = 0;
    while steps < 60 && state.contact_generation == saved.contact_generation {
        stepper.step(&mut state).unwrap();
        steps += 1;
    }
    let steps = steps - u64::from(state.contact_generation != saved.contact_generation);
    let mut again = saved.clone();
    stepper.run(&mut again, steps).unwrap();
    let mut first = saved.clone();
    Stepper::new(law, config).run(&mut first, steps).unwrap();
    assert!(steps >= 20, "{steps} steps without a search");
    assert_eq!(again.contact_generation, saved.contact_generation);
    assert!(first.contacts.len() > 4 * first.contacts.active_count());
    assert_eq!(again, first);
}

/// Taken back to a state in which a bond is still intact, a stepper that has since seen the
/// bond break and the pair open (and so holds a bound that says the pair stays apart for a
/// while) evaluates the bond again: the run gives the bits of a fresh stepper. Two spheres
/// on grips pulled apart; a neighbour search while the bond is stretched makes the opened
/// pair's bound exceed the drift of the saved state (same contact generation).
#[test]
fn a_stepper_taken_back_before_a_break_evaluates_the_bond_again() {
    let (ra, rb) = (1.5e-3, 2.5e-3);
    let mut state = DemState::new(two_spheres(Kinematics::Spheres3d, ra, rb, 2e-6), vec![]);
    assert_eq!(state.install_bonds(1e-5).unwrap(), 1);
    let v = 1e-3;
    state.particles.fixed = vec![true, true];
    state.particles.velocity[0] = Vec3::new(-v, 0.0, 0.0);
    state.particles.velocity[1] = Vec3::new(v, 0.0, 0.0);
    let law = table1();
    // The bond breaks at a stretch of T R²/K_n ≈ 1.07e-5 m (53 500 steps); a search every
    // 50 000 steps (half the skin over the grip speed).
    let config = StepperParams {
        verlet_skin: 1e-5,
        ..stepper_params(1e-7, 0.0)
    }
    .validate()
    .unwrap();
    let mut stepper = Stepper::new(law, config);
    stepper.step(&mut state).unwrap();
    let first_search = state.contact_generation;
    while state.contact_generation == first_search {
        stepper.step(&mut state).unwrap();
    }
    stepper.run(&mut state, 10).unwrap();
    let saved = state.clone();
    assert!(saved.bond_breaks.is_empty() && saved.contacts.report[0].normal_force < -30.0);
    while state.bond_breaks.is_empty() {
        stepper.step(&mut state).unwrap();
        assert!(state.step < 90_000);
    }
    stepper.run(&mut state, 1000).unwrap();
    assert!(!state.contacts.report[0].active);
    assert_eq!(state.contact_generation, saved.contact_generation);
    let steps = state.step - saved.step;
    let mut again = saved.clone();
    stepper.run(&mut again, steps).unwrap();
    let mut first = saved.clone();
    Stepper::new(law, config).run(&mut first, steps).unwrap();
    assert_eq!(first.bond_breaks.len(), 1);
    assert_eq!(again, first);
}

/// An 8 × 8 × 12 jittered lattice of spheres above a floor, with a linear spring + Coulomb law
/// (the setting of the Verlet-skin and stepper-reuse tests). 768 spheres: two blocks of the
/// contact pass (512 and 256), so that the contacts across the block boundary go through
/// their spill entries.
fn frictional_lattice_on_floor(seed: u64, jitter: f64) -> (DemState, LinearSpring) {
    let p = jittered_lattice(Kinematics::Spheres3d, 8, 8, 12, seed, jitter);
    let floor = Wall::new(Vec3::new(0.0, 0.0, -6e-4), Vec3::new(0.0, 0.0, 1.0)).unwrap();
    let law = LinearSpringParams {
        normal_stiffness: 2e4,
        tangential_stiffness: 1e4,
        friction_coefficient: 0.4,
        thermal_bond: None,
    }
    .validate()
    .unwrap();
    (DemState::new(p, vec![floor]), law)
}

/// A loose, unbonded granular gas, isolated: few of the listed pairs touch, so the gather
/// visits only the particles the contact pass stamped. Total momentum is conserved to
/// round-off (a particle missed by the stamps would lose its contact forces), and 1, 2 and 3
/// threads give the same bits.
#[test]
fn sparse_contacts_conserve_momentum_and_give_identical_bits() {
    let momentum = |s: &DemState| {
        let p = &s.particles;
        p.velocity
            .iter()
            .zip(&p.mass)
            .fold(Vec3::ZERO, |acc, (v, m)| acc + *v * *m)
    };
    let run = |threads: usize| {
        let p = jittered_lattice(Kinematics::Spheres3d, 14, 14, 8, 23, 2.0);
        let mut state = DemState::new(p, vec![]);
        let law = LinearSpringParams {
            normal_stiffness: 2e5,
            tangential_stiffness: 5e4,
            friction_coefficient: 0.5,
            thermal_bond: None,
        }
        .validate()
        .unwrap();
        let dt = 0.2 * critical_time_step(&state, &law);
        let mut stepper = Stepper::new(law, stepper_params(dt, 0.0).validate().unwrap());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let before = momentum(&state);
        pool.install(|| stepper.run(&mut state, 400)).unwrap();
        (state, before)
    };
    let (a, before) = run(1);
    let (active, listed) = (a.contacts.active_count(), a.contacts.len());
    assert!(
        active > 0 && 4 * active <= listed,
        "the case should be sparse: {active} of {listed} contacts active"
    );
    let scale: f64 = a
        .particles
        .velocity
        .iter()
        .zip(&a.particles.mass)
        .map(|(v, m)| v.norm() * m)
        .sum();
    let drift = (momentum(&a) - before).norm();
    assert!(
        drift <= 1e-12 * scale,
        "momentum drift {drift:e} of {scale:e}"
    );
    for threads in [2, 3] {
        let (b, _) = run(threads);
        assert_eq!(state_bits(&a), state_bits(&b), "{threads} threads");
    }
}

#[test]
fn a_contact_across_particle_blocks_leaves_no_force_once_it_opens() {
    // Particles 0 and 700 lie in different blocks of the contact pass (512 particles each), so
    // the force on 700 reaches it through the gather of the later block. They collide head
    // on and separate; from then on 700 must fly at constant velocity (no gravity, no damping,
    // nothing else near it). The other spheres form bonded pairs at rest, far away, so that
    // most listed contacts stay active and the gather reads every spill entry.
    let r = 1e-3;
    let n = 1100;
    let mut centres: Vec<Vec3> = (0..n)
        .map(|i| {
            let pair = (i as f64 / 2.0).floor();
            let side = if i % 2 == 0 { 0.0 } else { 2.0 * r };
            Vec3::new(side, 1.0 + 10.0 * r * pair, 0.0)
        })
        .collect();
    centres[0] = Vec3::ZERO;
    centres[700] = Vec3::new(2.0 * r + 1e-5, 0.0, 0.0);
    // 1 lost its partner 0: keep it alone, far from everything.
    centres[1] = Vec3::new(-1.0, 0.0, 0.0);
    centres[701] = Vec3::new(1.0, 0.0, 0.0);
    let radii = vec![r; n];
    let particles =
        ParticleState::new(Kinematics::Spheres3d, 2600.0, 293.15, &centres, &radii).unwrap();
    let mut state = DemState::new(particles, vec![]);
    state.install_bonds(1e-9).unwrap();
    state.particles.velocity[0] = Vec3::new(0.05, 0.0, 0.0);
    state.particles.velocity[700] = Vec3::new(-0.05, 0.0, 0.0);
    let law = table1();
    let dt = 0.02 * critical_time_step(&state, &law);
    let mut stepper = Stepper::new(law, stepper_params(dt, 0.0).validate().unwrap());
    stepper.step(&mut state).unwrap();
    let bonded = state.contacts.active_count();
    assert!(
        4 * bonded > state.contacts.len(),
        "{bonded} of {}",
        state.contacts.len()
    );
    let pair_active = |s: &DemState| {
        (0..s.contacts.len()).any(|k| s.contacts.pair[k] == [0, 700] && s.contacts.report[k].active)
    };
    let mut touched = false;
    let mut separated = false;
    for _ in 0..200_000 {
        stepper.step(&mut state).unwrap();
        let active = pair_active(&state);
        touched |= active;
        if touched && !active {
            separated = true;
            break;
        }
    }
    assert!(separated, "the pair never touched and separated");
    let v_apart = state.particles.velocity[700];
    assert!(v_apart.x > 0.04, "rebound: {v_apart:?}");
    stepper.run(&mut state, 200).unwrap();
    assert_eq!(state.particles.velocity[700], v_apart);
    assert_eq!(state.particles.force[700], Vec3::ZERO);
}

/// The contact pass of a block reads only the particles of its own and later blocks (the
/// parallel schedule relies on it): a pair edited in place to point back into an earlier
/// block (the contact index is not rebuilt, as nothing says the list changed) panics
/// instead of racing with that block's integration, with one thread as with several.
#[test]
fn a_pair_edited_to_point_into_an_earlier_block_panics() {
    for threads in [1, 2, 3] {
        let p = jittered_lattice(Kinematics::Spheres3d, 12, 12, 12, 7, 0.5);
        let mut state = DemState::new(p, Vec::new());
        state.install_bonds(5e-5).unwrap();
        let law = CohesiveFrictionalParams::paper_a_table_1()
            .validate()
            .unwrap();
        let dt = 0.5 * critical_time_step(&state, &law);
        let mut stepper = Stepper::new(law, stepper_params(dt, 0.08).validate().unwrap());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| stepper.run(&mut state, 2)).unwrap();
        let k = state
            .contacts
            .pair
            .iter()
            .position(|p| p[0] >= 1024)
            .expect("a contact of a later block");
        state.contacts.pair[k][1] = 0;
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| stepper.step(&mut state))
        }));
        assert!(r.is_err(), "{threads} threads");
    }
}
