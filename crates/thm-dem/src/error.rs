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
}

pub(crate) use crate::validate::{check_positive, check_range};
