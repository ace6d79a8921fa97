//! # thm-fvm-heat
//!
//! (module documentation: see the end of the work; written below)

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod error;
mod implicit;
pub mod params;
pub mod properties;
pub mod spheres;
mod state;
pub mod stepper;
pub mod verification;

pub use error::HeatError;
pub use params::{
    BoundaryCondition, BoundaryParams, GradientScheme, HeatModel, HeatParams, PhaseParams,
    SolidParams, TemperatureSchedule,
};
pub use spheres::sphere_mean_temperatures;
pub use state::{FlowInput, HeatState};
pub use stepper::{HeatStepper, StepReport};
