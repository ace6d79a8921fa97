//! # thm-vpn-flow
//!
//! (module documentation completed below)

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod channel;
mod error;
pub mod fluid;
mod forces;
mod network;
mod params;
mod state;
pub mod stepper;
pub mod verification;

pub use error::{ClosureFailure, FlowError, Phase};
pub use fluid::{LinearLiquidIdealGas, LinearLiquidIdealGasParameters, PoreFluid, PoreState};
pub use forces::add_sphere_forces;
pub use network::{BoundaryCondition, Network, NetworkParts};
pub use params::{FlowConfig, FlowParameters};
pub use state::FlowState;
pub use stepper::{FlowStepper, StepReport};
