//! # thm-mpm
//!
//! (module documentation: see the end of the implementation stage)

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod boundary;
pub mod config;
pub mod error;
pub mod grid;
pub mod material;
pub mod points;
pub mod reference;
pub mod shape;
pub mod stepper;
pub mod verification;

pub use boundary::{
    NodeSet, RigidWall, Side, SurfaceLoad, TemperatureCondition, VelocityCondition,
};
pub use config::{MpmConfig, MpmParameters};
pub use error::MpmError;
pub use grid::{Grid, GridParameters};
pub use material::{
    Constitutive, DruckerPrager, DruckerPragerParameters, DruckerPragerState, LinearThermoElastic,
    MaterialInput, MaterialResponse, StresslessConductor, ThermoElasticParameters,
};
pub use points::{MaterialPoints, PointProperties};
pub use stepper::{GridFields, Mpm, MpmState, NodeSums, TimeStepLimits};
