//! # thm-rve — thermo-mechanical DEM representative volume elements in periodic cells
//!
//! The RVE of Zhao, Zhao, Liang & Niu (2022), Sect. 3 (paper "B"): about 400 disks in a
//! periodic parallelogram cell, deformed by the velocity gradient of a material point and
//! heated to its temperature, returning the homogenised stress, the friction heat source and a
//! fabric-based conductivity tensor.
//!
//! ## Physics (by equation)
//!
//! - Periodic cell: cell matrix **H**, its inverse, periodic images and shifts (B-Eqs. 41–45);
//!   strain control by a prescribed velocity gradient **L**, `Ḣ = L·H` (B-Eq. 46); affine plus
//!   fluctuating velocities; the strain measure of B-Eqs. 47–48.
//! - Contacts: the linear spring + Coulomb law (B-Eqs. 35–36) and the thermally sensitive bond
//!   (B-Eqs. 38–40), taken from `thm-dem` (one implementation of each law in the workspace).
//! - Homogenised stress from contact forces and fluctuating velocities (B-Eq. 49) and the
//!   stiffness tensor (B-Eq. 58).
//! - Friction heat per step and the volumetric heat source (B-Eqs. 32–33); fabric conductivity
//!   tensor (B-Eq. 34); thermal expansion of disks from a reference radius (B-Eq. 37).
//!
//! ## Units
//!
//! SI. Two-dimensional quantities per unit thickness are turned into volumes with a fictitious
//! out-of-plane thickness, a documented parameter.
//!
//! ## Public seam
//!
//! `respond(velocity_gradient, temperature, dt, substeps) → (stress, heat source, conductivity
//! tensor)` per RVE, with state kept per RVE, and a batch that steps many RVEs in parallel with
//! results identical for 1 and 2 threads. `thm-coupling` adapts it to `thm-mpm`'s constitutive
//! trait.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod batch;
pub mod cell;
pub mod error;
pub mod mat2;
pub mod measure;
pub mod neighbour;
pub mod packing;
pub mod params;
pub mod state;
pub mod stepper;
pub mod verification;

pub use batch::RveBatch;
pub use cell::{CellStrain, PeriodicCell};
pub use error::RveError;
pub use mat2::Mat2;
pub use packing::{
    ConsolidationParams, ConsolidationReport, PackingParams, consolidate, random_packing,
};
pub use params::{RveConfig, RveParams};
pub use state::{PeriodicContacts, RveState};
pub use stepper::{RveLoad, RveResponse, RveStepper};
