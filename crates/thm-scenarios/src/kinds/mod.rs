//! The scenario kinds, one module each: a kind reads its sections of the scenario file into
//! a physics of the workspace, steps it and observes it through [`crate::scenario::Scenario`].
//! [`multiscale`] is the skeleton the MPM×DEM kinds share (the biaxial test, the column
//! collapse and the silo discharge are a protocol and a recorder on it).

pub mod dem_uniaxial_tension_bar;
pub mod lumped_cooling;
pub mod mpm_dem_biaxial;
pub mod mpm_dem_column;
pub mod mpm_dem_rod;
pub mod mpm_dem_silo;
pub mod mpm_dem_square;
pub mod mpm_semi_infinite_bar;
pub mod multiscale;
pub mod pore_scale_bar;
