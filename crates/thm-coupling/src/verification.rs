//! Verification cases of this crate, collected by `cargo xtask verify`, and the small bonded
//! packing they (and the tests) run on.
//!
//! 1. `coupling/pore_scale_closed_conservation`: a closed, adiabatic packing of bonded spheres
//!    (4 × 8, 2 mm lattice, 80 % water / 20 % air at 100 kPa, a 60 K temperature gradient),
//!    free skeleton with thermal expansion (A-Eq. 55) and the mesh rebuilt on every small
//!    change, then the same packing with a fixed skeleton: liquid mass, gas mass and thermal
//!    energy `Σ C (T − T_ref)` constant to 10⁻¹² relative through every step and remap.

use thm_dem::packing::lattice_packing;
use thm_dem::{CohesiveFrictionalParams, Kinematics, StepperParams};
use thm_eos::{Model, PengRobinson, water_air_closure};
use thm_fvm_heat::HeatParams;
use thm_verify::{Case, CaseError, CaseOutput, Row};
use thm_vpn_flow::{EosFluid, FlowParameters};
use thm_vpn_mesh::{MeshParams, Outline, RemeshCriteriaParams};

use crate::pore_scale::{
    CouplingError, FlowScheme, HeatScheme, InitialFluid, PoreScaleConfig, PoreScaleParams,
    PoreScaleState, PoreScaleStepper, Skeleton,
};

/// All verification cases of `thm-coupling`.
pub fn cases() -> Vec<Case> {
    vec![Case {
        name: "coupling/pore_scale_closed_conservation",
        description: "closed adiabatic bonded packing, free skeleton with remeshes and fixed skeleton: liquid and gas mass and thermal energy constant (A-Eqs. 24-29, 39, 50)",
        quick: true,
        run: closed_conservation_case,
    }]
}

/// Paper A's fluids: Peng–Robinson water with the volume correction and air (A-Eqs. 16–29).
pub type WaterAir = EosFluid<PengRobinson, PengRobinson>;

/// Paper A's water–air closure (A-Eqs. 16–29, Table 1).
pub fn water_air() -> WaterAir {
    EosFluid(water_air_closure(Model::PrCorrected))
}

/// Lattice spacing of the test packing \[m\].
pub const LATTICE_SPACING: f64 = 2e-3;
/// Spheres across and along the test packing.
pub const LATTICE_COUNTS: [usize; 2] = [4, 8];

/// The parameters of the test packing: a `4 × 8` jittered lattice of bonded spheres
/// (A-Table 1 contacts, 2 mm spacing) in a closed box (no flow boundary, adiabatic sides),
/// A-Table 1 heat properties, α_exp = 8.3·10⁻⁴ 1/K (A-Sect. 6), Δt_D = 2·10⁻⁷ s.
pub fn lattice_params(skeleton: Skeleton, remesh: RemeshCriteriaParams) -> PoreScaleParams {
    let (s, [nx, ny]) = (LATTICE_SPACING, LATTICE_COUNTS);
    PoreScaleParams {
        skeleton,
        dem: StepperParams {
            time_step: 2e-7,
            damping: 0.08,
            gravity: [0.0; 3],
            verlet_skin: 0.05 * s,
        },
        contact: CohesiveFrictionalParams::paper_a_table_1(),
        thermal_expansion: 8.3e-4,
        mesh: MeshParams::new(
            Outline::Box {
                min: [-0.5 * s, -0.5 * s],
                max: [(nx as f64 - 0.5) * s, (ny as f64 - 0.5) * s],
            },
            24,
        ),
        remesh,
        flow: FlowParameters::default(),
        flow_scheme: FlowScheme::Explicit,
        flow_boundaries: Vec::new(),
        boundary_reduction_factor: 0.0115,
        heat: HeatParams::paper_a_table_1(),
        heat_scheme: HeatScheme::Explicit,
    }
}

/// The initial state of the test packing: 80 % water and 20 % air at 100 kPa (A-Sect. 6),
/// temperatures rising linearly along y from 300 K to 360 K.
pub fn lattice_state(config: &PoreScaleConfig) -> Result<PoreScaleState, CouplingError> {
    let (s, [nx, ny]) = (LATTICE_SPACING, LATTICE_COUNTS);
    let packing = lattice_packing(Kinematics::SpheresInPlane, [nx, ny, 1], s, 7)
        .map_err(CouplingError::Dem)?;
    let dem = packing
        .to_state(2600.0, 300.0)
        .map_err(CouplingError::Dem)?;
    PoreScaleState::new(
        config,
        dem,
        &water_air(),
        InitialFluid {
            pressure: 1e5,
            liquid_fraction: 0.8,
        },
        |p| 300.0 + 60.0 * (p[1] + 0.5 * s) / (ny as f64 * s),
    )
}

/// Remesh criteria that fire on the first small change (to exercise the remap every step).
pub fn eager_remesh() -> RemeshCriteriaParams {
    RemeshCriteriaParams {
        max_displacement: 1e-4,
        max_rotation: 0.25,
        max_radius_change: 2e-4,
        max_overlap_change: 1e-3,
    }
}

/// Largest relative drift of liquid mass, gas mass and thermal energy over `steps` coupled
/// steps of `dt`, and the number of remeshes.
fn drift(
    skeleton: Skeleton,
    implicit: bool,
    steps: usize,
    dt: f64,
) -> Result<([f64; 3], u64), CouplingError> {
    let mut params = lattice_params(skeleton, eager_remesh());
    if implicit {
        params.flow_scheme = FlowScheme::Implicit;
        params.heat_scheme = HeatScheme::Implicit;
    }
    let config = params.validate()?;
    let heat = config.params().heat.clone();
    let mut s = lattice_state(&config)?;
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s)?;
    let start = [s.liquid_mass(), s.gas_mass(), s.thermal_energy(&heat)];
    let mut worst = [0.0f64; 3];
    for _ in 0..steps {
        stepper.step(&mut s, dt)?;
        let now = [s.liquid_mass(), s.gas_mass(), s.thermal_energy(&heat)];
        for k in 0..3 {
            worst[k] = worst[k].max(((now[k] - start[k]) / start[k]).abs());
        }
    }
    Ok((worst, s.remeshes))
}

fn closed_conservation_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    for (label, skeleton, implicit, steps, dt) in [
        ("free skeleton", Skeleton::Free, false, 20, 1e-5),
        ("fixed skeleton", Skeleton::Fixed, false, 20, 1e-4),
        (
            "free skeleton, implicit flow and heat",
            Skeleton::Free,
            true,
            20,
            1e-5,
        ),
        (
            "fixed skeleton, implicit flow and heat",
            Skeleton::Fixed,
            true,
            20,
            0.1,
        ),
    ] {
        let (worst, remeshes) =
            drift(skeleton, implicit, steps, dt).map_err(CaseError::from_display)?;
        for (k, what) in ["liquid mass", "gas mass", "thermal energy"]
            .iter()
            .enumerate()
        {
            out.rows.push(Row::at_most(
                format!("{label}: max |Δ{what}| / {what}, {steps} steps of {dt} s"),
                "",
                worst[k],
                1e-12,
            ));
        }
        if skeleton == Skeleton::Free {
            out.rows.push(Row::at_least(
                format!("{label}: remeshes (conservative remap exercised)"),
                "",
                remeshes as f64,
                10.0,
            ));
        }
    }
    out.notes = vec![
        "Closed box (no flow boundary) and adiabatic sides: nothing enters or leaves, so both phase masses and Σ C (T − T_ref) (fluid capacity m_q c_q + m_p c_p, solid ρ_s c_s V) must stay constant. The free skeleton moves under contact and fluid forces and expands with A-Eq. 55 (α_exp = 8.3e-4 1/K, A-Sect. 6), with remesh thresholds small enough that the mesh is rebuilt and every field remapped almost every step.".into(),
    ];
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_conservation_case_passes() {
        let out = closed_conservation_case().expect("case runs");
        for row in &out.rows {
            assert!(row.pass, "{row:?}");
        }
    }
}
