//! The small bonded packing of `thm_coupling::verification`, shared by the tests.
#![allow(dead_code)]

pub use thm_coupling::bar::{WaterAir as Fluid, water_air as fluid};
use thm_coupling::pore_scale::{
    PoreScaleConfig, PoreScaleParams, PoreScaleState, PoreScaleStepper, Skeleton,
};
pub use thm_coupling::verification::eager_remesh;
use thm_vpn_mesh::RemeshCriteriaParams;

pub const SPACING: f64 = thm_coupling::verification::LATTICE_SPACING;
pub const NX: usize = thm_coupling::verification::LATTICE_COUNTS[0];
pub const NY: usize = thm_coupling::verification::LATTICE_COUNTS[1];

pub fn params(skeleton: Skeleton, remesh: RemeshCriteriaParams) -> PoreScaleParams {
    thm_coupling::verification::lattice_params(skeleton, remesh)
}

pub fn state(config: &PoreScaleConfig) -> PoreScaleState {
    thm_coupling::verification::lattice_state(config).expect("initial state")
}

pub fn stepper(config: &PoreScaleConfig, state: &PoreScaleState) -> PoreScaleStepper<Fluid> {
    PoreScaleStepper::new(config.clone(), fluid(), state).expect("stepper")
}
