//! The adaptive coupled step (`PoreScaleStepper::advance`): it bounds each step's sphere
//! motion, ends exactly at the end of the interval, conserves through rejected steps, and a
//! restored run takes the same steps.

mod common;

use common::*;
use thm_coupling::pore_scale::{
    CouplingError, CouplingStepParams, PoreScaleState, PressureForce, Skeleton,
    largest_displacement,
};

fn rule(max_step: f64, min_step: f64, max_displacement: f64) -> CouplingStepParams {
    CouplingStepParams {
        max_step,
        min_step,
        max_displacement,
        growth: 1.5,
    }
}

fn smallest_radius(s: &PoreScaleState) -> f64 {
    s.dem
        .particles
        .radius
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
}

/// How far the spheres of the closed test packing move in one plain step of `h` from the
/// start, as a fraction of the smallest radius.
fn one_step_motion(h: f64) -> f64 {
    let config = params(Skeleton::Free, eager_remesh())
        .validate()
        .expect("params");
    let s0 = state(&config);
    let mut s = s0.clone();
    stepper(&config, &s).step(&mut s, h).expect("step");
    largest_displacement(&s0, &s).1 / smallest_radius(&s0)
}

#[test]
fn steps_that_move_a_sphere_too_far_are_taken_again_shorter_conserving_mass_and_energy() {
    let (h, interval) = (4e-5, 1.2e-4);
    // Allow a third of what one long step moves: the first step must be rejected.
    let allowed = one_step_motion(h) / 3.0;
    assert!(allowed > 0.0);
    let config = params(Skeleton::Free, eager_remesh())
        .validate()
        .expect("params");
    let heat = config.params().heat.clone();
    let mut s = state(&config);
    let (mq0, mp0, e0) = (s.liquid_mass(), s.gas_mass(), s.thermal_energy(&heat));
    let t0 = s.time;
    let mut st = stepper(&config, &s);
    let rule = rule(h, 1e-9, allowed).validate().expect("rule");
    let r = st.advance(&mut s, interval, &rule).expect("advance");
    assert!(r.rejected >= 1, "{r:?}");
    assert!(r.steps > 3, "{r:?}");
    assert!(r.shortest < h, "{r:?}");
    assert!(
        r.largest_displacement <= allowed * smallest_radius(&s) * (1.0 + 1e-9),
        "{r:?}"
    );
    assert!(((s.time - t0) - interval).abs() <= 1e-15, "{}", s.time - t0);
    assert_eq!(s.step, r.steps);
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    assert!(rel(s.liquid_mass(), mq0) < 1e-12);
    assert!(rel(s.gas_mass(), mp0) < 1e-12);
    let de = (s.thermal_energy(&heat) - e0).abs() / e0.abs();
    assert!(de < 1e-12, "energy {de}");
}

#[test]
fn a_restored_run_takes_the_same_adaptive_steps_bit_for_bit() {
    let h = 4e-5;
    let allowed = one_step_motion(h) / 3.0;
    let config = params(Skeleton::Free, eager_remesh())
        .validate()
        .expect("params");
    let rule = rule(h, 1e-9, allowed).validate().expect("rule");
    let mut s = state(&config);
    let mut st = stepper(&config, &s);
    st.advance(&mut s, 6e-5, &rule).expect("advance");
    let saved = serde_json::to_string(&s).expect("save");
    st.advance(&mut s, 6e-5, &rule).expect("advance");
    let mut r: PoreScaleState = serde_json::from_str(&saved).expect("load");
    stepper(&config, &r)
        .advance(&mut r, 6e-5, &rule)
        .expect("advance");
    assert_eq!(s, r);
}

#[test]
fn a_rule_that_no_step_can_meet_is_an_error_naming_the_sphere_and_keeps_the_state() {
    let config = params(Skeleton::Free, eager_remesh())
        .validate()
        .expect("params");
    let s0 = state(&config);
    let mut s = s0.clone();
    let mut st = stepper(&config, &s);
    let rule = rule(4e-5, 1e-5, 1e-12).validate().expect("rule");
    match st.advance(&mut s, 4e-5, &rule) {
        Err(CouplingError::CouplingStepTooSmall {
            displacement,
            limit,
            step_length,
            ..
        }) => {
            assert!(displacement > limit);
            assert_eq!(step_length, 1e-5);
        }
        other => panic!("expected CouplingStepTooSmall, got {other:?}"),
    }
    // Everything but the rule's next step length is as it was.
    assert_eq!(s.coupling_step, 1e-5);
    s.coupling_step = s0.coupling_step;
    assert_eq!(s, s0);
}

#[test]
fn bad_rules_name_the_field() {
    let good = rule(1e-3, 1e-6, 0.01);
    for (bad, field) in [
        (
            CouplingStepParams {
                max_step: 0.0,
                ..good
            },
            "max_step",
        ),
        (
            CouplingStepParams {
                min_step: 2e-3,
                ..good
            },
            "min_step",
        ),
        (
            CouplingStepParams {
                min_step: f64::NAN,
                ..good
            },
            "min_step",
        ),
        (
            CouplingStepParams {
                max_displacement: 1.5,
                ..good
            },
            "max_displacement",
        ),
        (
            CouplingStepParams {
                growth: 0.5,
                ..good
            },
            "growth",
        ),
    ] {
        match bad.validate() {
            Err(CouplingError::Parameter { field: f, .. }) => assert_eq!(f, field),
            other => panic!("{field}: {other:?}"),
        }
    }
    let text = r#"{"max_step": 1e-3, "min_step": 1e-6, "max_displacement": 0.01, "growth": 1.5, "speed": 2}"#;
    let err = serde_json::from_str::<CouplingStepParams>(text).expect_err("unknown field");
    assert!(err.to_string().contains("speed"), "{err}");
}

/// The test packing with bonds a thousand times weaker than A-Table 1's, so that the fluid
/// forces and the thermal gradient break some within a few steps.
fn weak_bonds() -> thm_coupling::pore_scale::PoreScaleConfig {
    weak_bonds_pushed(PressureForce::WallFaces)
}

/// [`weak_bonds`] with the pore pressures pushing as `force` says.
fn weak_bonds_pushed(force: PressureForce) -> thm_coupling::pore_scale::PoreScaleConfig {
    let mut p = params(Skeleton::Free, eager_remesh());
    p.contact.tensile_strength *= 1e-3;
    p.contact.cohesion *= 1e-3;
    p.pressure_force = force;
    p.validate().expect("params")
}

fn broken(s: &PoreScaleState) -> usize {
    s.dem
        .contacts
        .history
        .iter()
        .filter(|h| h.bond == thm_dem::BondState::Broken)
        .count()
}

/// Runs the weak-bond packing for `intervals` intervals of 2·10⁻⁵ s under the adaptive rule.
fn run_breaking(s: &mut PoreScaleState, intervals: usize, force: PressureForce) {
    let config = weak_bonds_pushed(force);
    let rule = rule(1e-5, 1e-9, 0.02).validate().expect("rule");
    let mut st = stepper(&config, s);
    for _ in 0..intervals {
        st.advance(s, 2e-5, &rule).expect("advance");
    }
}

/// Both pressure forces: A-Eqs. 52–53, and the cell corners with the implicit undrained
/// springs (case a's).
#[test]
fn through_breakage_and_remeshing_one_and_two_threads_and_a_restore_give_the_same_bits() {
    for force in [PressureForce::WallFaces, PressureForce::CellCorners] {
        breakage_parity(force);
    }
}

fn breakage_parity(force: PressureForce) {
    let config = weak_bonds_pushed(force);
    let s0 = state(&config);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .expect("pool")
    };
    let run = |threads: usize| {
        pool(threads).install(|| {
            let mut s = s0.clone();
            run_breaking(&mut s, 3, force);
            let half = (broken(&s), serde_json::to_string(&s).expect("save"));
            run_breaking(&mut s, 3, force);
            (half, s)
        })
    };
    let ((broken_half, saved), one) = run(1);
    let (_, two) = run(2);
    assert!(
        broken(&one) > broken_half && broken_half > 0,
        "{force:?}: bonds must break before and after the save: {broken_half} then {}",
        broken(&one)
    );
    assert!(one.remeshes > 0);
    assert_eq!(one, two);
    let mut restored: PoreScaleState = serde_json::from_str(&saved).expect("load");
    run_breaking(&mut restored, 3, force);
    assert_eq!(one, restored);
}

/// A-Eq. 55 over a run with bond breakage and remeshing: each sphere's radius equals its
/// initial radius times Π(1 + α_exp ΔT_avg) over the coupled steps, to round-off. The remap
/// keeps each sphere's energy and capacity, hence its mean temperature, so a remesh adds no
/// factor; it did (10⁻¹¹ relative per remesh here) while a new mesh took the thickness of
/// the spheres as they were (their largest diameter), which changed every cell's volume.
#[test]
fn each_radius_is_its_initial_radius_times_the_product_of_its_expansions() {
    let config = weak_bonds();
    let alpha = config.params().thermal_expansion;
    let mut s = state(&config);
    let mut expected = s.dem.particles.radius.clone();
    let mut st = stepper(&config, &s);
    for _ in 0..30 {
        let before = s.dem.particles.temperature.clone();
        st.step(&mut s, 2e-6).expect("step");
        for ((r, t), t0) in expected
            .iter_mut()
            .zip(&s.dem.particles.temperature)
            .zip(&before)
        {
            *r *= 1.0 + alpha * (t - t0);
        }
    }
    assert!(
        broken(&s) > 0 && s.remeshes > 0,
        "{} broken, {} remeshes",
        broken(&s),
        s.remeshes
    );
    let worst = s
        .dem
        .particles
        .radius
        .iter()
        .zip(&expected)
        .map(|(r, e)| ((r - e) / e).abs())
        .fold(0.0, f64::max);
    let grown = s
        .dem
        .particles
        .radius
        .iter()
        .zip(&state(&config).dem.particles.radius)
        .map(|(r, r0)| ((r - r0) / r0).abs())
        .fold(0.0, f64::max);
    assert!(grown > 1e-8, "no sphere changed size ({grown})");
    assert!(
        worst <= 1e-14,
        "radius off the product by {worst} (relative)"
    );
}
