//! The crate's error type: every variant names the field or quantity, the value and the allowed
//! range (or the place and step of an instability).

use thiserror::Error;

/// Errors of `thm-rve`.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RveError {
    /// A parameter is outside its allowed range (or not finite).
    #[error("parameter `{field}` = {value} is outside the allowed range {allowed}")]
    InvalidParameter {
        /// Parameter name (serde key path).
        field: &'static str,
        /// The offending value.
        value: f64,
        /// The allowed range, in words.
        allowed: &'static str,
    },
    /// The cell matrix is degenerate or inverted: `det H ≤ 0` (or not finite).
    #[error("cell matrix `{field}` has det H = {determinant}, allowed (0, ∞)")]
    DegenerateCell {
        /// Which cell matrix (`cell`, `cell after step n`, ...).
        field: &'static str,
        /// The determinant \[m²\].
        determinant: f64,
    },
    /// The cell became too narrow for the periodic search: a pair could touch two images.
    #[error(
        "cell width {width} m across axis {axis} is below the allowed minimum {minimum} m (2 × (2 R_max + skin))"
    )]
    CellTooSmall {
        /// Axis (0 or 1) across which the cell is too narrow.
        axis: usize,
        /// Perpendicular width of the cell \[m\].
        width: f64,
        /// The smallest allowed width \[m\].
        minimum: f64,
    },
    /// A radius range with `r_min > r_max` or non-positive radii.
    #[error(
        "radii out of order: min_radius = {min_radius} m, max_radius = {max_radius} m (need 0 < min ≤ max)"
    )]
    RadiiOutOfOrder {
        /// Smallest radius \[m\].
        min_radius: f64,
        /// Largest radius \[m\].
        max_radius: f64,
    },
    /// A consolidation target that the contacts cannot carry at small overlaps.
    #[error(
        "target stress {target} Pa is not reachable: allowed range (0, {max_reachable}] Pa (mean overlap below 10 % of the smallest radius)"
    )]
    UnreachableTargetStress {
        /// The requested stress \[Pa\].
        target: f64,
        /// The largest stress the packing can carry with overlaps below 10 % of `r_min` \[Pa\].
        max_reachable: f64,
    },
    /// The servo did not reach the target stress within the allowed number of steps.
    #[error(
        "consolidation to {target} Pa stopped after {steps} steps at mean stress {reached} Pa (tolerance {tolerance})"
    )]
    ConsolidationNotConverged {
        /// Target \[Pa\].
        target: f64,
        /// Mean stress reached \[Pa\].
        reached: f64,
        /// Steps taken.
        steps: u64,
        /// Relative tolerance asked for.
        tolerance: f64,
    },
    /// The simulation became unstable: a non-finite value appeared.
    #[error("non-finite {quantity} at disk {index} in step {step} (time step too large?)")]
    NonFinite {
        /// What became non-finite.
        quantity: &'static str,
        /// Disk index (or contact index for contact quantities).
        index: usize,
        /// Step number.
        step: u64,
    },
    /// Two inputs of a batch call have different lengths.
    #[error("batch input `{field}` has length {len}, expected {expected}")]
    LengthMismatch {
        /// Input name.
        field: &'static str,
        /// Its length.
        len: usize,
        /// The expected length.
        expected: usize,
    },
    /// An error from the particle layer of `thm-dem`.
    #[error("disk state: {0}")]
    Dem(#[from] thm_dem::DemError),
}

impl From<thm_dem::OutOfRange> for RveError {
    fn from(e: thm_dem::OutOfRange) -> Self {
        Self::InvalidParameter {
            field: e.field,
            value: e.value,
            allowed: e.allowed,
        }
    }
}

pub(crate) use thm_dem::validate::{check_positive, check_range};
