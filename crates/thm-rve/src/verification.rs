//! Verification cases of this crate, collected by `cargo xtask verify`.
//!
//! 1. Isotropic consolidation of 400 disks (radii in [0.25, 0.5] mm, `k_n = k_t = 10⁶ N/m`)
//!    to 100 kPa within 1 % (B-Sect. 5.2.2).
//! 2. Small-strain uniaxial (constrained) compression of that packing: `K + G = Δσ_yy/Δε_yy`,
//!    `K − G = Δσ_xx/Δε_yy`, `ν = (K − G)/(K + G)`, `E = 2K(1 − ν)` (2D, Meille & Garboczi
//!    2001). Recomputed from the paper's own increments (12.4 and 2.18 MPa): ν = 0.176,
//!    E = 12.02 MPa, as stated. Over five seeds; compared "of the paper's order".
//! 3. Dense (μ = 0.01) and loose (μ = 0.5) consolidation: void ratios against 0.165 / 0.236
//!    (B-Sect. 5.3.1).
//! 4. Friction heat: the heat the RVE returns through B-Eq. 33 equals the sliding work of
//!    B-Eq. 32 summed over contacts and steps; and the cell's energy balance without damping
//!    (boundary work = Δ elastic + Δ kinetic energy + friction heat), which the explicit
//!    time integration closes to first order in Δt only.

use crate::mat2::Mat2;
use crate::measure;
use crate::packing::{
    ConsolidationParams, ConsolidationReport, PackingParams, consolidate, random_packing,
};
use crate::params::{RveConfig, RveParams};
use crate::state::RveState;
use crate::stepper::{RveLoad, RveStepper};
use thm_verify::{Case, CaseError, CaseOutput, Row};

/// All verification cases of `thm-rve`.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "rve/isotropic_consolidation",
            description: "400 disks, radii [0.25, 0.5] mm, k_n = k_t = 1e6 N/m, servo to 100 kPa (B-Sect. 5.2.2)",
            quick: true,
            run: consolidation_case,
        },
        Case {
            name: "rve/uniaxial_compression_moduli",
            description: "E and ν of the consolidated packing from constrained compression, 5 seeds (B-Sect. 5.2.2: 12 MPa, 0.18)",
            quick: false,
            run: moduli_case,
        },
        Case {
            name: "rve/dense_loose_void_ratio",
            description: "void ratio after consolidation with μ = 0.01 (dense) and 0.5 (loose) (B-Sect. 5.3.1: 0.165, 0.236)",
            quick: false,
            run: void_ratio_case,
        },
        Case {
            name: "rve/friction_heat_balance",
            description: "heat returned (B-Eq. 33) = sliding work (B-Eq. 32); cell energy balance without damping",
            quick: true,
            run: heat_balance_case,
        },
    ]
}

fn err(e: impl std::fmt::Display) -> CaseError {
    CaseError::from_display(e)
}

/// A consolidated packing of B-Sect. 5.2.2 (or fewer disks) at 100 kPa with friction μ.
pub fn consolidated_packing(
    disk_count: usize,
    seed: u64,
    friction_coefficient: f64,
) -> Result<(RveConfig, RveState, ConsolidationReport), crate::RveError> {
    let config = RveParams::paper_b_table_1().validate()?;
    let mut packing = PackingParams::paper_b(seed);
    packing.disk_count = disk_count;
    let mut state = random_packing(&packing, &config)?;
    let report = consolidate(
        &mut state,
        &config,
        &ConsolidationParams::isotropic(1e5, friction_coefficient),
    )?;
    Ok((config, state, report))
}

fn consolidation_case() -> Result<CaseOutput, CaseError> {
    let (_, state, report) = consolidated_packing(400, 1, 0.001).map_err(err)?;
    let mut out = CaseOutput::default();
    out.rows.push(Row::relative(
        "σ_xx after consolidation",
        "Pa",
        report.stress.at(0, 0),
        1e5,
        0.01,
    ));
    out.rows.push(Row::relative(
        "σ_yy after consolidation",
        "Pa",
        report.stress.at(1, 1),
        1e5,
        0.01,
    ));
    out.rows.push(Row::at_most(
        "unbalanced-force ratio",
        "",
        report.unbalanced_ratio,
        1e-3,
    ));
    out.notes.push(format!(
        "{} steps of {:.3e} s; void ratio {:.4}; coordination number {:.2}; {} disks",
        report.steps,
        report.time_step,
        report.void_ratio,
        report.coordination_number,
        state.len()
    ));
    Ok(out)
}

/// Constrained compression `Δε_yy` (ε_xx = 0) of a consolidated packing with friction μ,
/// loaded slowly with damping and relaxed; returns `(K + G, K − G)` \[Pa\].
pub fn constrained_compression(
    config: &RveConfig,
    state: &mut RveState,
    time_step: f64,
    friction_coefficient: f64,
) -> Result<(f64, f64), crate::RveError> {
    let cfg = config
        .with_friction(friction_coefficient)?
        .with_damping(0.7)?;
    let thickness = cfg.params().thickness;
    let mut stepper = RveStepper::new(cfg);
    let s0 = measure::stress(state, thickness);
    let e0 = state.cell.strain().tensor;
    let (steps, strain) = (5000u32, 5e-4);
    let l = Mat2::diagonal(0.0, -strain / (f64::from(steps) * time_step));
    for _ in 0..steps {
        stepper.step(state, &l, time_step)?;
    }
    for _ in 0..3000 {
        stepper.step(state, &Mat2::ZERO, time_step)?;
    }
    let s1 = measure::stress(state, thickness);
    let de = e0.at(1, 1) - state.cell.strain().tensor.at(1, 1);
    Ok((
        (s1.at(1, 1) - s0.at(1, 1)) / de,
        (s1.at(0, 0) - s0.at(0, 0)) / de,
    ))
}

fn moduli_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    let (mut es, mut nus, mut affine_ratio) = (Vec::new(), Vec::new(), 0.0_f64);
    for seed in 1..=5 {
        let (config, mut state, report) = consolidated_packing(400, seed, 0.001).map_err(err)?;
        // B-Eq. 58 (affine, Voigt-type) estimate of Δσ_yy/Δε_yy: an upper bound.
        let d = measure::stiffness(&state, config.params());
        let affine = d[1][1][1][1];
        let (kpg, kmg) =
            constrained_compression(&config, &mut state, report.time_step, 0.5).map_err(err)?;
        let nu = kmg / kpg;
        let e = (kpg + kmg) * (1.0 - nu);
        out.notes.push(format!(
            "seed {seed}: K+G = {:.3} MPa, K−G = {:.3} MPa, ν = {nu:.3}, E = {:.3} MPa",
            kpg / 1e6,
            kmg / 1e6,
            e / 1e6
        ));
        es.push(e);
        nus.push(nu);
        affine_ratio = affine_ratio.max(kpg / affine);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let sd = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt()
    };
    out.rows.push(Row::relative(
        "E (mean of 5 seeds), same order as 12 MPa (±50 %)",
        "Pa",
        mean(&es),
        12e6,
        0.5,
    ));
    out.rows.push(Row::absolute(
        "ν (mean of 5 seeds), same order as 0.18 (±0.15)",
        "",
        mean(&nus),
        0.18,
        0.15,
    ));
    out.rows.push(Row::at_most(
        "largest (K+G) / D_yyyy of B-Eq. 58 (affine estimate bounds the modulus)",
        "",
        affine_ratio,
        1.0,
    ));
    out.notes.push(format!(
        "spread over 5 seeds: E sd {:.3} MPa, ν sd {:.3}",
        sd(&es) / 1e6,
        sd(&nus)
    ));
    out.notes.push(
        "consolidated with μ = 0.001 (B-Table 1), compressed with μ = 0.5; with μ = 0.001 during \
         compression the nearly frictionless packing is far softer in shear (ν ≈ 0.76 for seed 1)"
            .into(),
    );
    Ok(out)
}

fn void_ratio_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    for (label, mu, reference) in [
        ("dense, μ = 0.01", 0.01, 0.165),
        ("loose, μ = 0.5", 0.5, 0.236),
    ] {
        let (_, _, report) = consolidated_packing(400, 1, mu).map_err(err)?;
        out.rows.push(Row::relative(
            format!("void ratio {label} (±10 %)"),
            "",
            report.void_ratio,
            reference,
            0.1,
        ));
    }
    Ok(out)
}

/// Shears a consolidated packing (μ = 0.5, no damping) through `respond` calls of `substeps`
/// DEM steps; returns `(Σ Q V Δt, Σ E_f)` \[J\]: the heat returned by B-Eq. 33 and the sliding
/// work of B-Eq. 32 summed step by step.
pub fn heat_ledger(
    config: &RveConfig,
    state: &mut RveState,
    time_step: f64,
    calls: usize,
    substeps: u32,
) -> Result<(f64, f64), crate::RveError> {
    let cfg = config.with_friction(0.5)?.with_damping(0.0)?;
    let p = *cfg.params();
    let mut stepper = RveStepper::new(cfg);
    let load = RveLoad {
        velocity_gradient: Mat2::new(0.0, 1e-5 / time_step, 0.0, 0.0),
        temperature: p.reference_temperature,
        dt: time_step * f64::from(substeps),
        substeps,
    };
    let before = state.friction_heat_total;
    let mut returned = 0.0;
    for _ in 0..calls {
        let r = stepper.respond(state, &load)?;
        returned += r.heat_source * state.volume(p.thickness) * load.dt;
    }
    Ok((returned, state.friction_heat_total - before))
}

/// Shears a consolidated packing (μ = 0.5, no damping) by `steps` DEM steps of
/// `fraction · Δt` at the same shear rate; returns `(W, ΔE, D)` \[J\]: the boundary work
/// `−Σ_n (Σ_c f⊗b) : L Δt`, the change of elastic plus kinetic energy and the friction heat.
pub fn energy_ledger(
    config: &RveConfig,
    mut state: RveState,
    time_step: f64,
    fraction: f64,
) -> Result<(f64, f64, f64), crate::RveError> {
    let cfg = config.with_friction(0.5)?.with_damping(0.0)?;
    let p = *cfg.params();
    let mut stepper = RveStepper::new(cfg);
    // One evaluation without motion fixes the starting forces.
    stepper.step(&mut state, &Mat2::ZERO, 0.0)?;
    let e0 = measure::elastic_energy(&state, &p) + measure::kinetic_energy(&state);
    let l = Mat2::new(0.0, 1e-5 / time_step, 0.0, 0.0);
    let dt = time_step * fraction;
    let steps = (2000.0 / fraction).round() as usize;
    let (mut work, mut heat) = (0.0, 0.0);
    for _ in 0..steps {
        heat += stepper.step(&mut state, &l, dt)?;
        work -= state.contact_moment.contract(&l) * dt;
    }
    let e1 = measure::elastic_energy(&state, &p) + measure::kinetic_energy(&state);
    Ok((work, e1 - e0, heat))
}

fn heat_balance_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    let (config, state, report) = consolidated_packing(60, 3, 0.01).map_err(err)?;
    let mut sheared = state.clone();
    let (returned, sliding) =
        heat_ledger(&config, &mut sheared, report.time_step, 100, 20).map_err(err)?;
    out.rows.push(Row::relative(
        "heat returned Σ Q V Δt vs sliding work Σ E_f",
        "J",
        returned,
        sliding,
        1e-9,
    ));
    let mut residuals = Vec::new();
    for fraction in [1.0, 0.25] {
        let (w, de, d) =
            energy_ledger(&config, state.clone(), report.time_step, fraction).map_err(err)?;
        let residual = (w - de - d).abs() / w.abs();
        out.notes.push(format!(
            "Δt = {fraction} Δt₀: boundary work {w:.6e} J, Δ(elastic + kinetic) {de:.6e} J, friction heat {d:.6e} J, share dissipated {:.3}",
            d / w
        ));
        residuals.push(residual);
    }
    out.rows.push(Row::at_most(
        "cell energy balance |W − ΔE − D| / W at Δt₀",
        "",
        residuals[0],
        1e-3,
    ));
    out.rows.push(Row::at_most(
        "same at Δt₀/4 over residual at Δt₀ (first order: ≈ 0.25)",
        "",
        residuals[1] / residuals[0],
        0.5,
    ));
    Ok(out)
}
