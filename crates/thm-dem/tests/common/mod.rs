#![allow(dead_code)]
use thm_dem::*;

pub fn table1() -> CohesiveFrictional {
    CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .unwrap()
}

pub fn stepper_params(dt: f64, damping: f64) -> StepperParams {
    StepperParams {
        time_step: dt,
        damping,
        gravity: [0.0; 3],
        verlet_skin: 2e-4,
    }
}

/// Two spheres on the x axis with surfaces `gap` apart (negative = overlap).
pub fn two_spheres(kin: Kinematics, ra: f64, rb: f64, gap: f64) -> ParticleState {
    ParticleState::new(
        kin,
        2600.0,
        293.15,
        &[Vec3::ZERO, Vec3::new(ra + rb + gap, 0.0, 0.0)],
        &[ra, rb],
    )
    .unwrap()
}

/// A jittered square/cubic lattice of polydisperse spheres (radius 0.45–0.55 of the spacing),
/// deterministic from `seed`, with random velocities.
pub fn jittered_lattice(
    kin: Kinematics,
    nx: usize,
    ny: usize,
    nz: usize,
    seed: u64,
    speed: f64,
) -> ParticleState {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let h = 1e-3;
    let mut c = Vec::new();
    let mut r = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let jitter = |rng: &mut rand_chacha::ChaCha8Rng| rng.random_range(-0.03..0.03) * h;
                let z = if kin.is_planar() {
                    0.0
                } else {
                    k as f64 * h + jitter(&mut rng)
                };
                c.push(Vec3::new(
                    i as f64 * h + jitter(&mut rng),
                    j as f64 * h + jitter(&mut rng),
                    z,
                ));
                r.push(h * rng.random_range(0.47..0.53));
            }
        }
    }
    let mut p = ParticleState::new(kin, 2600.0, 293.15, &c, &r).unwrap();
    for v in p.velocity.iter_mut() {
        *v = Vec3::new(
            rng.random_range(-speed..speed),
            rng.random_range(-speed..speed),
            if kin.is_planar() {
                0.0
            } else {
                rng.random_range(-speed..speed)
            },
        );
    }
    p
}
