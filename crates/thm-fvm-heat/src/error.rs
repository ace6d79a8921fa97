//! The crate's error type.

use thm_vpn_mesh::BoundarySide;

/// Everything that can go wrong in this crate: invalid parameters, inputs that do not fit the
/// mesh, and a run that went unstable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeatError {
    /// A parameter outside its allowed range.
    #[error("{field}: must be {range}, got {value}")]
    ParameterOutOfRange {
        /// Parameter path, e.g. `"solid.conductivity"` or `"boundaries[1].temperature[0]"`.
        field: String,
        /// Allowed range, in words.
        range: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A boundary condition names a side on which the mesh has no boundary face.
    #[error("boundaries[{index}]: side {side:?} has no boundary face on this mesh")]
    BoundaryNotOnMesh {
        /// Index in the `boundaries` list.
        index: usize,
        /// The side.
        side: BoundarySide,
    },
    /// Two boundary conditions for the same side.
    #[error("boundaries[{index}]: side {side:?} already has a condition")]
    DuplicateBoundary {
        /// Index of the second condition in the `boundaries` list.
        index: usize,
        /// The side.
        side: BoundarySide,
    },
    /// A per-cell, per-face or per-channel array has the wrong length.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// An input value (from the flow solver or the caller) outside its allowed range.
    #[error("{quantity}[{index}]: must be {range}, got {value}")]
    InputOutOfRange {
        /// Which quantity, e.g. `"liquid_fraction"`.
        quantity: &'static str,
        /// Cell, face or channel index.
        index: usize,
        /// Allowed range, in words.
        range: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A face whose centroid link is not finite (coincident centroids or non-finite
    /// coordinates); links that are merely nearly parallel use the minimum correction (see
    /// `HeatGeometry::sliver_faces`).
    #[error("face {face}: cos(angle between normal and centroid link) = {cosine} is not finite")]
    DegenerateFace {
        /// Face index.
        face: usize,
        /// `n · e_s`.
        cosine: f64,
        /// The smallest admissible value.
        minimum: f64,
    },
    /// The run went unstable: a non-finite temperature.
    #[error("non-finite {quantity} in cell {cell} at step {step} (t = {time} s): {value}")]
    NonFinite {
        /// Which quantity.
        quantity: &'static str,
        /// Cell index.
        cell: usize,
        /// Sub-step counter of the state when it happened.
        step: u64,
        /// Time at the start of the failing sub-step \[s\].
        time: f64,
        /// The value.
        value: f64,
    },
    /// The sparse solver of the implicit step failed.
    #[error("implicit step: sparse solver failed: {message}")]
    Solver {
        /// The solver's message.
        message: String,
    },
}
