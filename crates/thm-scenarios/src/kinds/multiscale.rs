//! The skeleton the MPM×DEM kinds share.

use crate::error::{RunError, physics_error};

/// Brings every process's copy of `points` up to date when `material` is distributed (see
/// `thm_coupling::multiscale::distributed`); nothing otherwise.
pub(crate) fn synchronise_points(
    material: &thm_coupling::multiscale::RveMaterial,
    points: &mut [thm_coupling::multiscale::RvePoint],
    step: u64,
    time: f64,
) -> Result<(), RunError> {
    match material.distribution() {
        Some(d) => thm_coupling::multiscale::distributed::lock(d)
            .synchronise(points)
            .map_err(physics_error(step, time)),
        None => Ok(()),
    }
}
