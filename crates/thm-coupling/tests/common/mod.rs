//! A small bonded packing and the coupled configuration the tests share.
#![allow(dead_code)]

use thm_coupling::pore_scale::{
    FlowBoundary, HeatScheme, InitialFluid, PoreScaleConfig, PoreScaleParams, PoreScaleState,
    PoreScaleStepper, Skeleton,
};
use thm_dem::packing::lattice_packing;
use thm_dem::{CohesiveFrictionalParams, Kinematics, StepperParams};
use thm_eos::{Model, water_air_closure};
use thm_fvm_heat::HeatParams;
use thm_vpn_flow::{EosFluid, FlowParameters};
use thm_vpn_mesh::{MeshParams, Outline, RemeshCriteriaParams};

pub type Fluid = EosFluid<thm_eos::PengRobinson, thm_eos::PengRobinson>;

pub const SPACING: f64 = 2e-3;
pub const NX: usize = 4;
pub const NY: usize = 8;

pub fn fluid() -> Fluid {
    EosFluid(water_air_closure(Model::PrCorrected))
}

/// Parameters of a `NX × NY` lattice of bonded spheres in a closed box (no flow boundary,
/// adiabatic): skeleton and remesh criteria as given.
pub fn params(skeleton: Skeleton, remesh: RemeshCriteriaParams) -> PoreScaleParams {
    let h = 0.5 * SPACING;
    PoreScaleParams {
        skeleton,
        dem: StepperParams {
            time_step: 2e-7,
            damping: 0.08,
            gravity: [0.0; 3],
            verlet_skin: 0.05 * SPACING,
        },
        contact: CohesiveFrictionalParams::paper_a_table_1(),
        thermal_expansion: 8.3e-4,
        mesh: MeshParams::new(
            Outline::Box {
                min: [-h, -h],
                max: [(NX as f64 - 0.5) * SPACING, (NY as f64 - 0.5) * SPACING],
            },
            24,
        ),
        remesh,
        flow: FlowParameters::default(),
        flow_boundaries: Vec::<FlowBoundary>::new(),
        boundary_reduction_factor: 0.0115,
        heat: HeatParams::paper_a_table_1(),
        heat_scheme: HeatScheme::Explicit,
    }
}

/// The initial state: 80 % water, 20 % air at 100 kPa, temperatures rising linearly with y
/// from 300 K to 360 K (cells and spheres).
pub fn state(config: &PoreScaleConfig) -> PoreScaleState {
    let packing =
        lattice_packing(Kinematics::SpheresInPlane, [NX, NY, 1], SPACING, 7).expect("packing");
    let dem = packing.to_state(2600.0, 300.0).expect("dem state");
    PoreScaleState::new(
        config,
        dem,
        &fluid(),
        InitialFluid {
            pressure: 1e5,
            liquid_fraction: 0.8,
        },
        |p| 300.0 + 60.0 * (p[1] + 0.5 * SPACING) / (NY as f64 * SPACING),
    )
    .expect("initial state")
}

pub fn stepper(config: &PoreScaleConfig, state: &PoreScaleState) -> PoreScaleStepper<Fluid> {
    PoreScaleStepper::new(config.clone(), fluid(), state).expect("stepper")
}

/// Remesh criteria that fire on the first small change (to exercise the remap).
pub fn eager_remesh() -> RemeshCriteriaParams {
    RemeshCriteriaParams {
        max_displacement: 1e-4,
        max_rotation: 0.25,
        max_radius_change: 2e-4,
        max_overlap_change: 1e-3,
    }
}
