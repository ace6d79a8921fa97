//! The bar cases of A-Sects. 4–6 on the A-Fig. 8 packing: set-up, a few coupled steps of
//! case b, and the stop with a named pore when single-phase water goes into tension.

use thm_coupling::bar::water_air;
use thm_coupling::bar::{
    BarCase, BarEnds, PAPER_BAR, bar_packing, bar_params, bar_params_sized, bar_state,
    bar_state_sized, centreline_cells,
};
use thm_coupling::pore_scale::{CouplingError, PoreScaleStepper};

const CASES: [BarCase; 4] = [
    BarCase::Cooling,
    BarCase::Advection {
        pressure_drop: 0.9e6,
    },
    BarCase::Advection {
        pressure_drop: 9.9e6,
    },
    BarCase::ContractionFixed,
];

#[test]
fn every_case_sets_up_on_the_paper_bar() {
    let dem = bar_packing(1, 300.0).expect("packing");
    let n = dem.particles.radius.len();
    assert!((40..80).contains(&n), "{n} spheres");
    // Every overlapping pair is bonded: the packing is one bonded body.
    assert!(
        dem.contacts.pair.len() >= n,
        "{} bonds",
        dem.contacts.pair.len()
    );
    for case in CASES {
        let config = bar_params(case, 16).validate().expect("parameters");
        let s = bar_state(case, &config, 1, &water_air()).expect("state");
        let alpha = case.initial_fluid().liquid_fraction;
        assert!(
            s.flow
                .liquid_fraction
                .iter()
                .all(|a| (a - alpha).abs() < 1e-9)
        );
        assert!(
            s.heat
                .temperature
                .iter()
                .all(|&t| t == case.initial_temperature())
        );
        assert!(!centreline_cells(&s.mesh.mesh).is_empty());
    }
}

#[test]
fn case_b_steps_conserve_both_phases_and_stay_between_the_end_and_initial_temperatures() {
    let case = BarCase::ContractionFixed;
    let config = bar_params(case, 16).validate().expect("parameters");
    let mut s = bar_state(case, &config, 1, &water_air()).expect("state");
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
    let (q0, p0) = (s.liquid_mass(), s.gas_mass());
    for _ in 0..5 {
        stepper.step(&mut s, 0.1).expect("step");
    }
    assert!(((s.liquid_mass() - q0) / q0).abs() < 1e-12);
    assert!(((s.gas_mass() - p0) / p0).abs() < 1e-12);
    let (lo, hi) = (case.end_temperature(), case.initial_temperature());
    for &t in &s.heat.temperature {
        assert!(t >= lo - 1e-9 && t <= hi + 1e-9, "T = {t} K");
    }
    // The ends cooled, the gas cushions the contraction: pressures fell below 100 kPa but
    // stay positive.
    assert!(s.heat.temperature.iter().any(|&t| t < hi - 1.0));
    assert!(s.flow.pressure.iter().all(|&p| p > 0.0 && p < 1e5 + 1.0));
}

#[test]
fn sealed_water_goes_into_tension_which_stops_the_run_unless_allowed() {
    // A-Sect. 4 with film ends: water only, 0.1 MPa reservoirs at both ends. The 40 pores of
    // this mesh that
    // no channel connects to a reservoir cool at fixed mass, and water contracts: without
    // `liquid_tension` the run stops at the flow stage naming the pore; with it, those pores
    // hold a negative pressure and keep their mass while the connected ones are refilled.
    let case = BarCase::Cooling;
    let mut params = bar_params_sized(case, 32, PAPER_BAR, BarEnds::Film);
    assert!(params.liquid_tension, "the water cases allow tension");
    params.liquid_tension = false;
    let config = params.validate().expect("parameters");
    let mut s =
        bar_state_sized(case, &config, 1, &water_air(), PAPER_BAR, BarEnds::Film).expect("state");
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
    let mut stopped = None;
    for _ in 0..20 {
        if let Err(e) = stepper.step(&mut s, 1.0) {
            stopped = Some(e);
            break;
        }
    }
    match stopped {
        Some(CouplingError::Unphysical {
            stage,
            quantity,
            place,
            value,
            ..
        }) => {
            assert_eq!((stage, quantity, place), ("flow", "pressure", "pore"));
            assert!(value < 0.0);
        }
        other => panic!("expected a stop on negative pressure, got {other:?}"),
    }
    let config = bar_params_sized(case, 32, PAPER_BAR, BarEnds::Film)
        .validate()
        .expect("parameters");
    let mut s =
        bar_state_sized(case, &config, 1, &water_air(), PAPER_BAR, BarEnds::Film).expect("state");
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
    let m0 = s.liquid_mass();
    for _ in 0..20 {
        stepper.step(&mut s, 1.0).expect("step with tension");
    }
    assert!(s.flow.pressure.iter().any(|&p| p < 0.0));
    let inflow: f64 = s.flow.boundary_liquid_inflow.iter().sum();
    assert!(inflow > 0.0, "the contraction draws water in");
    assert!(((s.liquid_mass() - m0 - inflow) / m0).abs() < 1e-12);
}

/// Pore masses, pressures, fractions and cell temperatures, as bits.
fn fluid_heat_bits(s: &thm_coupling::pore_scale::PoreScaleState) -> Vec<u64> {
    [
        &s.flow.liquid_mass,
        &s.flow.gas_mass,
        &s.flow.pressure,
        &s.flow.liquid_fraction,
        &s.heat.temperature,
    ]
    .iter()
    .flat_map(|v| v.iter().map(|x| x.to_bits()))
    .collect()
}

#[test]
fn implicit_bar_steps_give_the_same_bits_on_1_and_2_threads_and_after_a_restore() {
    // Case b: the implicit pressure (Newton, sparse LU) and implicit heat (LU with
    // advection) paths, which the lattice parity test does not take.
    let case = BarCase::ContractionFixed;
    let config = bar_params(case, 16).validate().expect("parameters");
    let start = bar_state(case, &config, 1, &water_air()).expect("state");
    let run = |threads: usize, steps: usize, s: &thm_coupling::pore_scale::PoreScaleState| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            let mut s = s.clone();
            let mut stepper =
                PoreScaleStepper::new(config.clone(), water_air(), &s).expect("stepper");
            for _ in 0..steps {
                stepper.step(&mut s, 0.1).expect("step");
            }
            s
        })
    };
    let one = run(1, 4, &start);
    let two = run(2, 4, &start);
    assert_eq!(fluid_heat_bits(&one), fluid_heat_bits(&two));
    // Saved after 2 steps and restored into a fresh stepper: the same bits after 4.
    let half = run(1, 2, &start);
    let saved = serde_json::to_string(&half).expect("save");
    let restored: thm_coupling::pore_scale::PoreScaleState =
        serde_json::from_str(&saved).expect("load");
    let resumed = run(1, 2, &restored);
    assert_eq!(fluid_heat_bits(&one), fluid_heat_bits(&resumed));
    assert!(one.heat.temperature != start.heat.temperature);
}

/// A coupled step far above the explicit flow limit of water-filled pores (~1e-8 s): with the
/// explicit flow scheme the flow sub-cycles under its own limit, and when the sub-steps
/// allowed (`flow.max_substeps`) cannot cover Δt_C the step stops with an error that names
/// the limit, its value and the pore that sets it (the state is then part-way through the
/// flow stage, as `PoreScaleStepper::step` documents: a run restores its last checkpoint).
/// The implicit scheme takes the same step from the same start.
#[test]
fn a_coupled_step_above_the_explicit_flow_limit_names_the_limit_and_the_pore() {
    let case = BarCase::Cooling;
    let mut params = bar_params(case, 16);
    params.flow_scheme = thm_coupling::pore_scale::FlowScheme::Explicit;
    params.flow.max_substeps = 50;
    let config = params.validate().expect("parameters");
    let mut s = bar_state(case, &config, 1, &water_air()).expect("state");
    let start = s.clone();
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
    let err = stepper
        .step(&mut s, 1.0)
        .expect_err("1 s is ~1e8 explicit limits");
    let CouplingError::Flow(thm_vpn_flow::FlowError::TooManySubsteps {
        substeps,
        dt_limit,
        pore,
        ..
    }) = &err
    else {
        panic!("unexpected error {err}");
    };
    assert_eq!(*substeps, 50);
    assert!(*dt_limit < 1e-5 && *pore < s.flow.pressure.len(), "{err}");
    let message = err.to_string();
    assert!(
        message.contains("pore") && message.contains("sub-step"),
        "{message}"
    );
    let mut s = start;
    let config = bar_params(case, 16).validate().expect("parameters");
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
    stepper
        .step(&mut s, 1.0)
        .expect("implicit flow takes the step");
}

/// Case a holds the spheres within 1 mm of either end (both ends get some) and frees the
/// rest: after coupled steps with a free skeleton, the held spheres have not moved at all,
/// while the fluid and contact forces move the others.
#[test]
fn case_a_holds_the_end_spheres_and_frees_the_others() {
    use thm_coupling::bar::{BAR_LENGTH, END_HOLD_DEPTH};
    let case = BarCase::ContractionFree;
    let config = bar_params(case, 16).validate().expect("parameters");
    let mut s = bar_state(case, &config, 1, &water_air()).expect("state");
    let p = &s.dem.particles;
    let held: Vec<usize> = (0..p.len()).filter(|&i| p.fixed[i]).collect();
    let near = |i: usize, bottom: bool| {
        if bottom {
            p.position[i].y - p.radius[i] < END_HOLD_DEPTH
        } else {
            p.position[i].y + p.radius[i] > BAR_LENGTH - END_HOLD_DEPTH
        }
    };
    assert!(held.iter().any(|&i| near(i, true)) && held.iter().any(|&i| near(i, false)));
    assert!(held.iter().all(|&i| near(i, true) || near(i, false)));
    assert!((0..p.len()).all(|i| p.fixed[i] || !(near(i, true) || near(i, false))));
    let start = p.position.clone();
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
    for _ in 0..2 {
        stepper.step(&mut s, 1e-4).expect("step");
    }
    let p = &s.dem.particles;
    for (i, (now, before)) in p.position.iter().zip(&start).enumerate() {
        assert_eq!(now != before, !p.fixed[i], "sphere {i}");
    }
}

/// No pore of the shipped bars (cut and film ends, seeds 1–5, 32 points per circle, as the
/// scenarios and `cargo run -p thm-benchmarks --bin bar_ends` mesh them) is sealed: every pore
/// is joined to a reservoir of the cooling bar by some chain of channels.
#[test]
fn no_pore_of_the_shipped_bars_is_sealed() {
    let case = BarCase::Cooling;
    let sealed = |seed: u64, ends: BarEnds| {
        let config = bar_params_sized(case, 32, PAPER_BAR, ends)
            .validate()
            .expect("parameters");
        let s = bar_state_sized(case, &config, seed, &water_air(), PAPER_BAR, ends).expect("state");
        let stepper = PoreScaleStepper::new(config, water_air(), &s).expect("stepper");
        thm_coupling::pore_scale::unconnected_pores(stepper.network())
    };
    // Film ends: before the gaps were chained through junctions (S2S channels ending where
    // three circles overlap), 40 / 0 / 10 / 0 / 11 pores of seeds 1-5 were sealed in the
    // pockets between a side wall and two overlapping circles.
    for seed in 1..=5 {
        assert_eq!(sealed(seed, BarEnds::Cut), 0, "cut, seed {seed}");
        assert_eq!(sealed(seed, BarEnds::Film), 0, "film, seed {seed}");
    }
}
