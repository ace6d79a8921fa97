//! The crate's error type: every variant names the field or quantity, the place and the
//! allowed range.

use thiserror::Error;

/// Errors of `thm-dem`.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DemError {
    /// A parameter is outside its allowed range (or not finite).
    #[error("parameter `{field}` = {value} is outside the allowed range {allowed}")]
    InvalidParameter {
        /// Parameter name (TOML/serde key).
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// A per-particle value is outside its allowed range (or not finite).
    #[error("particle {index}: `{field}` = {value} is outside the allowed range {allowed}")]
    InvalidParticle {
        /// Particle index.
        index: usize,
        /// Field name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// The arrays of the particle state have different lengths.
    #[error("particle array `{field}` has length {len}, expected {expected}")]
    LengthMismatch {
        /// Array name.
        field: &'static str,
        /// Its length.
        len: usize,
        /// The number of particles.
        expected: usize,
    },
    /// A contact or bond names a particle that does not exist, or a particle twice, or a
    /// contact list is not sorted by pair.
    #[error("contact {index}: particles ({a}, {b}) invalid for {particle_count} particles")]
    InvalidContact {
        /// Contact index.
        index: usize,
        /// First particle.
        a: usize,
        /// Second particle.
        b: usize,
        /// Number of particles.
        particle_count: usize,
    },
    /// The simulation became unstable: a non-finite value appeared.
    #[error("non-finite {quantity} at particle {index} in step {step} (time step too large?)")]
    NonFinite {
        /// What became non-finite.
        quantity: &'static str,
        /// Particle index.
        index: usize,
        /// Step number.
        step: u64,
    },
    /// A packing could not be generated with the requested parameters.
    #[error("packing: {reason}")]
    Packing {
        /// What went wrong.
        reason: String,
    },
    /// A packing file could not be read or written.
    #[error("packing file line {line}: {reason}")]
    PackingFile {
        /// 1-based line number (0 for I/O errors).
        line: usize,
        /// What went wrong.
        reason: String,
    },
    /// A calibration target that no parameter within the search range reaches.
    #[error(
        "calibration: no {parameter} in [{lower:e}, {upper:e}] gives `{field}` = {target:e}; \
         the values reached span [{reached_min:e}, {reached_max:e}]"
    )]
    CalibrationUnreachable {
        /// The target's name (the key a user gives it by).
        field: &'static str,
        /// The target value.
        target: f64,
        /// The parameter searched.
        parameter: &'static str,
        /// Lower end of the parameter's search range.
        lower: f64,
        /// Upper end of the parameter's search range.
        upper: f64,
        /// Smallest value of the target quantity reached.
        reached_min: f64,
        /// Largest value of the target quantity reached.
        reached_max: f64,
    },
    /// A calibration that brackets its target but does not meet the tolerance.
    #[error(
        "calibration: `{field}` = {target:e} not reached within a relative tolerance of \
         {tolerance:e} in {iterations} iterations (last {parameter} = {parameter_value:e} gave \
         {value:e})"
    )]
    CalibrationNotConverged {
        /// The target's name.
        field: &'static str,
        /// The target value.
        target: f64,
        /// The relative tolerance asked for.
        tolerance: f64,
        /// Iterations done.
        iterations: usize,
        /// The parameter searched.
        parameter: &'static str,
        /// Its last value.
        parameter_value: f64,
        /// The target quantity at that value.
        value: f64,
    },
}

pub(crate) use crate::validate::{check_positive, check_range};
