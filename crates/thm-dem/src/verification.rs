//! Verification cases of this crate, collected by `cargo xtask verify` (feature
//! `verification`):
//!
//! - `dem/two_sphere_restitution`: a head-on rebound keeps the energy without damping and
//!   `(1 − α_d)/(1 + α_d)` of it with Cundall damping (A-Eq. 7);
//! - `dem/bond_tension_threshold`: a bond breaks when its tension reaches `T·R_min²`;
//! - `dem/uniaxial_tension_bar`: the uniaxial tension test of A-Sect. 3.1 ([`crate::tension`],
//!   whose module docs give the set-up, the choices and why the strength with A-Table 1's `T`
//!   stays below the paper's) on five packings, with `T` calibrated first
//!   ([`crate::calibration`]).

use crate::contact::CohesiveFrictionalParams;
use crate::error::DemError;
use crate::stepper::{Stepper, StepperParams, critical_time_step};
use crate::tension::TensionResult;
use crate::vec3::Vec3;
use thm_verify::{Case, CaseError, CaseOutput, Plot, Row, Series, SeriesRole};

/// All verification cases of this crate.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "dem/two_sphere_restitution",
            description: "head-on rebound of two spheres: energy kept without damping, \
                          (1 − α_d)/(1 + α_d) of it with Cundall damping (A-Eq. 7)",
            quick: true,
            run: run_restitution,
        },
        Case {
            name: "dem/bond_tension_threshold",
            description: "a bond pulled apart breaks when its tension reaches T·R_min² \
                          (A-Eq. 6, A-Table 1)",
            quick: true,
            run: run_bond_threshold,
        },
        Case {
            name: "dem/uniaxial_tension_bar",
            description: "uniaxial tension of the bonded 20 × 80 mm bar (A-Sect. 3.1), mean of \
                          five packings: bond strength T calibrated to the paper's 8.8 MPa \
                          (C = 5 T), then strength, strain at peak, modulus, broken bonds, \
                          coordination vs Krzaczek et al.; A-Table 1's T reported",
            quick: false,
            run: run_uniaxial_tension,
        },
    ]
}

/// Kinetic energy before and after a head-on collision of two 1 mm spheres at ±5 cm/s.
fn rebound(damping: f64) -> Result<(f64, f64), DemError> {
    let r = 1e-3;
    let particles = crate::state::ParticleState::new(
        crate::state::Kinematics::Spheres3d,
        2600.0,
        293.15,
        &[Vec3::ZERO, Vec3::new(2.0 * r + 1e-5, 0.0, 0.0)],
        &[r, r],
    )?;
    let mut state = crate::state::DemState::new(particles, Vec::new());
    state.particles.velocity[0] = Vec3::new(0.05, 0.0, 0.0);
    state.particles.velocity[1] = Vec3::new(-0.05, 0.0, 0.0);
    let law = CohesiveFrictionalParams {
        cohesion: 0.0,
        tensile_strength: 0.0,
        ..CohesiveFrictionalParams::paper_a_table_1()
    }
    .validate()?;
    let dt = 0.01 * critical_time_step(&state, &law);
    let params = StepperParams {
        time_step: dt,
        damping,
        gravity: [0.0; 3],
        verlet_skin: 1e-4,
    };
    let mut stepper = Stepper::new(law, params.validate()?);
    let e0 = state.particles.kinetic_energy();
    let mut touched = false;
    for _ in 0..10_000_000 {
        stepper.step(&mut state)?;
        let active = state.contacts.active_count() > 0;
        touched |= active;
        if touched && !active {
            break;
        }
    }
    Ok((e0, state.particles.kinetic_energy()))
}

fn run_restitution() -> Result<CaseOutput, CaseError> {
    let (e0, e1) = rebound(0.0).map_err(CaseError::from_display)?;
    let alpha = 0.08;
    let (d0, d1) = rebound(alpha).map_err(CaseError::from_display)?;
    Ok(CaseOutput {
        rows: vec![
            Row::relative("energy returned, α_d = 0", "", e1 / e0, 1.0, 1e-4),
            Row::relative("energy returned, α_d = 0.08", "", d1 / d0, (1.0 - alpha) / (1.0 + alpha), 2e-3),
        ],
        plots: Vec::new(),
        notes: vec![
            "Δt = 0.01 Δt_crit; the residual is the O(Δt²) error of contact opening and closing between steps.".into(),
        ],
    })
}

fn run_bond_threshold() -> Result<CaseOutput, CaseError> {
    use crate::contact::{ContactHistory, ContactKinematics, ContactLaw, PairInput};
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .map_err(CaseError::from_display)?;
    let (ra, rb) = (2.0e-3, 3.5e-3);
    let pair = PairInput {
        radius_a: ra,
        radius_b: rb,
        temperature: 293.15,
    };
    let mut h = ContactHistory::bonded_at(1e-5);
    let du = 1e-10;
    let mut carried: f64 = 0.0;
    for k in 0..10_000_000 {
        let pen = 1e-5 - du * k as f64;
        let kin = ContactKinematics::from_pair(
            Vec3::new(ra + rb - pen, 0.0, 0.0),
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::ZERO,
            ra,
            rb,
            1e-7,
        );
        let r = law.respond(&pair, &kin, &mut h);
        if r.broke.is_some() {
            break;
        }
        carried = carried.max(-r.normal_force);
    }
    let limit = 30e6 * ra * ra;
    Ok(CaseOutput {
        rows: vec![Row::relative(
            "largest tension carried by the bond",
            "N",
            carried,
            limit,
            1e-5,
        )],
        plots: Vec::new(),
        notes: vec![format!(
            "R_A = {} mm, R_B = {} mm, T = 30 MPa: the bond radius is the smaller one (as YADE), T·R² = {limit:.1} N; pulled in steps of {du:e} m (K_n Δu = {:.2e} N).",
            ra * 1e3,
            rb * 1e3,
            law.properties(&pair).normal_stiffness * du
        )],
    })
}

/// Packing seeds of the bar case.
const BAR_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

/// Mean and sample standard deviation.
fn mean_and_spread(values: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = values.clone().count() as f64;
    let mean = values.clone().sum::<f64>() / n;
    let var = values.map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, var.sqrt())
}

/// The stress–strain curves of a round, one series per packing, and the paper's line.
fn curves(results: &[TensionResult], label: &str) -> Vec<Series> {
    let (e_ref, peak_ref) = (3.5e9, 8.8e6);
    let mut series: Vec<Series> = results
        .iter()
        .zip(&BAR_SEEDS)
        .map(|(r, seed)| Series {
            label: format!("{label}, packing seed {seed}"),
            role: SeriesRole::Measured,
            x: r.strain.iter().map(|e| 100.0 * e).collect(),
            y: r.stress.iter().map(|s| s / 1e6).collect(),
        })
        .collect();
    series.push(Series {
        label: "paper: E = 3.5 GPa up to 8.8 MPa at 0.28 %".into(),
        role: SeriesRole::Reference,
        x: vec![0.0, 100.0 * peak_ref / e_ref, 0.28],
        y: vec![0.0, peak_ref / 1e6, peak_ref / 1e6],
    });
    series
}

fn run_uniaxial_tension() -> Result<CaseOutput, CaseError> {
    let settings = crate::calibration::StrengthCalibration {
        seeds: BAR_SEEDS.to_vec(),
        ..crate::calibration::StrengthCalibration::paper_a()
    };
    let calibration =
        crate::calibration::calibrate_bond_strength(&settings).map_err(CaseError::from_display)?;
    // The first round is A-Table 1's T = 30 MPa, C = 150 MPa (the calibration's first guess).
    let table_1 = &calibration.iterations[0];
    let calibrated = calibration.calibrated();
    let results = &calibrated.results;
    let stat = |f: fn(&TensionResult) -> f64| mean_and_spread(results.iter().map(f));
    let strength = stat(|r| r.strength);
    let modulus = stat(|r| r.young_modulus);
    let strain = stat(|r| r.strain_at_peak);
    let broken = stat(|r| r.broken_bonds as f64);
    let z0 = stat(|r| r.coordination_initial);
    let zf = stat(|r| r.coordination_at_failure);
    let porosity = stat(|r| r.area_porosity);
    let n = stat(|r| r.particle_count as f64).0;
    // 12 broken bonds lower z by 2·12/N: the self-consistent at-failure reference.
    let zf_reference = 6.53 - 2.0 * 12.0 / n;
    let k = BAR_SEEDS.len();
    let t_mpa = calibration.tensile_strength() / 1e6;
    let rows = vec![
        // A reported row: with A-Table 1's bond strengths the strength hangs on the reading of
        // R in T·R² (A-Eq. 6), which the paper leaves open (module doc, "Why the strength
        // stays below the paper's").
        Row::reported(
            format!("tensile strength, A-Table 1 T = 30 MPa, C = 150 MPa (mean of {k})"),
            "MPa",
            table_1.mean_strength / 1e6,
            8.8,
        ),
        Row::at_most(
            format!(
                "calibration of T (C = 5 T) converged: rounds of {k} tension tests to reach \
                 8.8 MPa within {} %",
                100.0 * settings.relative_tolerance
            ),
            "",
            calibration.iterations.len() as f64,
            settings.max_iterations as f64,
        ),
        Row::reported(
            "calibrated bond tensile strength T (A-Table 1: 30 MPa)",
            "MPa",
            t_mpa,
            30.0,
        ),
        Row::relative(
            format!("tensile strength, calibrated T = {t_mpa:.2} MPa (mean of {k})"),
            "MPa",
            strength.0 / 1e6,
            8.8,
            0.05,
        ),
        Row::relative(
            format!("Young's modulus, calibrated T (mean of {k})"),
            "GPa",
            modulus.0 / 1e9,
            3.5,
            0.30,
        ),
        Row::relative(
            format!("strain at peak, calibrated T (mean of {k})"),
            "%",
            100.0 * strain.0,
            0.28,
            0.30,
        ),
        Row::relative(
            format!("broken bonds at failure, calibrated T (mean of {k})"),
            "",
            broken.0,
            12.0,
            0.50,
        ),
        Row::relative(
            format!("coordination number, initial (mean of {k})"),
            "",
            z0.0,
            6.53,
            0.30,
        ),
        Row::relative(
            format!("coordination number, at failure (6.53 − 2·12/N, mean of {k})"),
            "",
            zf.0,
            zf_reference,
            0.30,
        ),
        Row::relative(
            format!("area porosity (mean of {k})"),
            "%",
            100.0 * porosity.0,
            10.0,
            0.15,
        ),
    ];
    let iterations = calibration
        .iterations
        .iter()
        .enumerate()
        .map(|(i, it)| {
            format!(
                "{i}: T = {:.3} MPa → {:.4} MPa",
                it.tensile_strength / 1e6,
                it.mean_strength / 1e6
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let mut notes = vec![
        format!(
            "Calibration (A-Sect. 3: \"DEM and CFD were separately calibrated\"): T with C = 5 T \
             such that the mean strength of the {k} packings is 8.8 MPa, secant from A-Table 1's \
             T = 30 MPa: {iterations}. Calibrated T = {t_mpa:.2} MPa, C = {:.1} MPa.",
            calibration.cohesion() / 1e6
        ),
        format!(
            "A-Table 1 bond strengths (T = 30 MPa, C = 150 MPa): strength {:.2} MPa, E {:.2} GPa, \
             strain at peak {:.3} %; the modulus does not depend on T, the strain at peak scales \
             with it.",
            table_1.mean_strength / 1e6,
            table_1.mean(|r| r.young_modulus) / 1e9,
            100.0 * table_1.mean(|r| r.strain_at_peak)
        ),
        format!(
            "Spread of the calibrated bar (sample standard deviation over {k} packings): strength {:.2} ± {:.2} MPa, E {:.2} ± {:.2} GPa, strain at peak {:.3} ± {:.3} %, broken bonds {:.1} ± {:.1}, z {:.2} ± {:.2} → {:.2} ± {:.2}, area porosity {:.1} ± {:.1} %.",
            strength.0 / 1e6, strength.1 / 1e6, modulus.0 / 1e9, modulus.1 / 1e9,
            100.0 * strain.0, 100.0 * strain.1, broken.0, broken.1, z0.0, z0.1, zf.0, zf.1,
            100.0 * porosity.0, 100.0 * porosity.1
        ),
        "Stress = mean plate force / (20 mm × 8 mm), the largest sphere diameter being the only thickness the paper states (A-Sect. 2.2); strength and modulus scale with its inverse, the strain at peak does not.".to_string(),
        "Bonds join surfaces closer than 4 mm, stress-free at that distance, T·R² and C·R² with R = min(R_A, R_B) as YADE; smooth plates at ±10 mm/s (±5 mm/s gives the same strength, modulus and strain at peak within 0.3 %), Δt = 2e-7 s, α_d = 0.08.".to_string(),
        "Strength with A-Table 1's T (a reported row): elastic–brittle, so strength ≈ E × strain at peak; the modulus agrees within 20 % and the shortfall is in the strain at peak (thickness-independent), i.e. in the bond strength per contact. With R = (R_A + R_B)/2 in T·R² the same packings give 7.2 MPa at 0.25 %. The paper's contact forces (max 69.2 N '= T·R²', below T·(2 mm)² = 120 N; mean 20.6 N) cannot be reproduced with T = 30 MPa on 2–4 mm radii under any reading. See the module docs of thm_dem::verification.".to_string(),
        "Post-peak reloads (seeds 2 and 3 in stress_strain_table_1): the first crack leaves a ligament of intact bonds that joins the two grips; every force across the crack is carried by intact bonds (see the module docs).".to_string(),
        "Broken-bond tolerance 50 %: a small count of a dynamic post-peak collapse. Area porosity tolerance 15 % (8.5–11.5 %): the paper says 'roughly 10 %'.".to_string(),
    ];
    notes.extend(results.iter().zip(&BAR_SEEDS).map(|(r, s)| {
        format!(
            "seed {s} (calibrated T): N = {}, area porosity {:.1} %, {:.2} MPa, {:.2} GPa, {:.3} %, {} broken ({} in tension), z {:.2} → {:.2}, largest tensile contact force before the peak {:.0} N, mean tensile contact force at the peak {:.0} N",
            r.particle_count,
            100.0 * r.area_porosity,
            r.strength / 1e6,
            r.young_modulus / 1e9,
            100.0 * r.strain_at_peak,
            r.broken_bonds,
            r.broken_in_tension,
            r.coordination_initial,
            r.coordination_at_failure,
            r.max_tensile_contact_force,
            r.mean_tensile_contact_force
        )
    }));
    Ok(CaseOutput {
        rows,
        plots: vec![
            Plot {
                name: "stress_strain".into(),
                title: format!(
                    "Uniaxial tension of the bonded bar (A-Sect. 3.1), calibrated T = {t_mpa:.1} MPa"
                ),
                x_label: "strain [%]".into(),
                y_label: "tensile stress [MPa]".into(),
                series: curves(results, "calibrated T"),
            },
            Plot {
                name: "stress_strain_table_1".into(),
                title: "Uniaxial tension of the bonded bar, A-Table 1 T = 30 MPa, C = 150 MPa"
                    .into(),
                x_label: "strain [%]".into(),
                y_label: "tensile stress [MPa]".into(),
                series: curves(&table_1.results, "T = 30 MPa"),
            },
        ],
        notes,
    })
}
