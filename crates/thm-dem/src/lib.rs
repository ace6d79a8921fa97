//! # thm-dem
//!
//! (module documentation below is completed with the implementation)

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod contact;
pub mod error;
pub mod neighbour;
pub mod packing;
pub mod state;
pub mod stepper;
pub mod vec3;
pub mod verification;

pub use contact::{
    BondRadius, BondState, BreakMode, CohesiveFrictional, CohesiveFrictionalParams, ContactHistory,
    ContactKinematics, ContactLaw, ContactProperties, ContactResponse, LinearSpring,
    LinearSpringParams, PairInput, ThermalBondParams, update_contact,
};
pub use error::DemError;
pub use state::{BondBreak, ContactList, DemState, Kinematics, ParticleState, Wall};
pub use stepper::{Stepper, StepperConfig, StepperParams, critical_time_step};
pub use vec3::Vec3;
