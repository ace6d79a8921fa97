//! The crate's error type: every variant names the offending point, node or parameter, the
//! value found and the allowed range.

use thiserror::Error;

/// Everything that can go wrong when building or stepping an MPM model.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MpmError {
    /// A scalar parameter is outside its allowed range.
    #[error("parameter `{name}` = {value} is outside the allowed range {allowed}")]
    InvalidParameter {
        /// Parameter name (the serde key path where there is one).
        name: String,
        /// The value given.
        value: f64,
        /// The allowed range, in words (e.g. "(0, inf)").
        allowed: &'static str,
    },
    /// A material point property (mass, volume, density, half-size, ...) is invalid.
    #[error("material point {index}: `{field}` = {value} is outside the allowed range {allowed}")]
    InvalidPoint {
        /// Index of the point.
        index: usize,
        /// Which field.
        field: &'static str,
        /// The value found.
        value: f64,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// The arrays of a material-point set do not all have the same length.
    #[error("material points: array `{field}` has length {len}, expected {expected}")]
    LengthMismatch {
        /// Which array.
        field: &'static str,
        /// Its length.
        len: usize,
        /// The number of points (length of `position`).
        expected: usize,
    },
    /// A material point's domain (centre ± half-size) is not inside the background grid.
    #[error(
        "material point {index} at ({x}, {y}) m with half-size ({lx}, {ly}) m leaves the grid \
         [{x_min}, {x_max}] x [{y_min}, {y_max}] m (step {step})"
    )]
    PointOutsideGrid {
        /// Index of the point.
        index: usize,
        /// Position x (m).
        x: f64,
        /// Position y (m).
        y: f64,
        /// Half-size along x (m).
        lx: f64,
        /// Half-size along y (m).
        ly: f64,
        /// Grid bounds (m).
        x_min: f64,
        /// Grid bounds (m).
        x_max: f64,
        /// Grid bounds (m).
        y_min: f64,
        /// Grid bounds (m).
        y_max: f64,
        /// Step counter when it was found (0 = initial state).
        step: u64,
    },
    /// The time step exceeds a stability limit (B-Eq. 30 or 31).
    #[error(
        "time step {dt} s exceeds the {criterion} limit {limit} s set by material point {point}"
    )]
    TimeStepTooLarge {
        /// The requested time step (s).
        dt: f64,
        /// The limit (s).
        limit: f64,
        /// `"mechanical (B-Eq. 30)"` or `"thermal (B-Eq. 31)"`.
        criterion: &'static str,
        /// The point that sets the limit.
        point: usize,
    },
    /// A non-finite value appeared: the run is unstable.
    #[error("non-finite {quantity} at {place} {index} in stage `{stage}` of step {step}")]
    NonFinite {
        /// Which quantity (e.g. "stress", "nodal velocity").
        quantity: &'static str,
        /// "material point" or "grid node".
        place: &'static str,
        /// Index of the point or node.
        index: usize,
        /// Stage name.
        stage: &'static str,
        /// Step counter.
        step: u64,
    },
    /// The state's material-state vector does not match the number of points.
    #[error("state holds {states} material states for {points} points")]
    MaterialStateCount {
        /// Number of material states.
        states: usize,
        /// Number of points.
        points: usize,
    },
    /// A constitutive model rejected its input.
    #[error("material at point {point}: {message}")]
    Material {
        /// The point.
        point: usize,
        /// The model's message.
        message: String,
    },
}
