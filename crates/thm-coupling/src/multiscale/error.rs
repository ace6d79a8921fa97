//! Errors of the MPM×DEM coupling: every variant names the field or the material point, the
//! MPM step, the value and the allowed range.

use thiserror::Error;
use thm_mpm::MpmError;
use thm_rve::RveError;

/// Errors of [`crate::multiscale`].
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MultiscaleError {
    /// A coupling parameter is outside its allowed range (or not finite).
    #[error("parameter `{field}` = {value} is outside the allowed range {allowed}")]
    InvalidParameter {
        /// The parameter's key path.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// The RVE parameters or the template packing are invalid.
    #[error("RVE set-up: {0}")]
    RveSetup(RveError),
    /// The RVE of a material point failed (degenerate or too narrow cell, non-finite disk
    /// motion, a temperature below 0 K, ...). The state of the step before is the caller's
    /// last checkpoint.
    #[error(
        "RVE of material point {point} failed in MPM step {step} at cell strain \
         eps_v = {volumetric_strain}, eps_q = {deviatoric_strain} (B-Eq. 48): {source}"
    )]
    Rve {
        /// The material point.
        point: usize,
        /// The MPM step (steps completed before the failing one).
        step: u64,
        /// Volumetric strain of the RVE cell (B-Eq. 48).
        volumetric_strain: f64,
        /// Deviatoric strain of the RVE cell (B-Eq. 48).
        deviatoric_strain: f64,
        /// What the RVE reported.
        #[source]
        source: RveError,
    },
    /// An RVE left the quasi-static range set by the parameters.
    #[error(
        "RVE of material point {point} is not quasi-static after MPM step {step}: \
         {quantity} = {value}, allowed [0, {limit}]"
    )]
    NotQuasiStatic {
        /// The material point.
        point: usize,
        /// The MPM step.
        step: u64,
        /// `"inertial number"` or `"kinetic/elastic energy ratio"`.
        quantity: &'static str,
        /// The value measured.
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// A packing does not match the parameters it is used with.
    #[error("packing field `{field}` = {value} does not match the parameters: expected {expected}")]
    PackingMismatch {
        /// Which property.
        field: &'static str,
        /// The packing's value.
        value: f64,
        /// The value the parameters imply.
        expected: f64,
    },
    /// A process of a distributed run failed in its block of RVEs (every process returns
    /// this, with the failing process's message; see [`super::distributed`]).
    #[error("process {process} failed in exchange {exchange}: {message}")]
    Distributed {
        /// The lowest failing process.
        process: usize,
        /// The exchange (MPM step of this material, counted from the start of this run).
        exchange: u64,
        /// That process's error, in words.
        message: String,
    },
    /// The processes of a distributed run disagree on the RVEs they hold (a synchronisation
    /// could not be completed).
    #[error("distributed RVE stage: {detail}")]
    DistributedState {
        /// What does not fit.
        detail: String,
    },
    /// An error of the MPM stepper.
    #[error("MPM: {0}")]
    Mpm(#[from] MpmError),
}
