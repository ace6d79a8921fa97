//! The crate's error type.

use crate::mesh::TopologyError;

/// Errors of the mesher, the motion update and the remap.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A circle centre coordinate is NaN or infinite.
    #[error("circle {circle}: centre coordinate is not finite ({value})")]
    NonFiniteCentre {
        /// Circle index.
        circle: usize,
        /// The value.
        value: f64,
    },
    /// A circle radius is not a finite positive number.
    #[error("circle {circle}: radius must be finite and > 0 m, got {value}")]
    InvalidRadius {
        /// Circle index.
        circle: usize,
        /// The value.
        value: f64,
    },
    /// A contact names a circle that does not exist.
    #[error("contact {contact}: circle index {circle} out of range (0..{n_circles})")]
    ContactOutOfRange {
        /// Contact index.
        contact: usize,
        /// The offending circle index.
        circle: u32,
        /// Number of circles.
        n_circles: usize,
    },
    /// A contact joins a circle to itself.
    #[error("contact {contact}: joins circle {circle} to itself")]
    SelfContact {
        /// Contact index.
        contact: usize,
        /// The circle.
        circle: u32,
    },
    /// A contact normal stress is NaN or infinite.
    #[error("contact {contact}: normal stress is not finite ({value})")]
    NonFiniteStress {
        /// Contact index.
        contact: usize,
        /// The value.
        value: f64,
    },
    /// A parameter outside its allowed range.
    #[error("parameter {name}: must be {range}, got {value}")]
    Parameter {
        /// Parameter name.
        name: &'static str,
        /// Allowed range in words.
        range: &'static str,
        /// The value.
        value: f64,
    },
    /// The alpha-shape outline needs at least one circle.
    #[error("the alpha-shape outline needs at least one circle, got none")]
    NoCircles,
    /// The triangulation rejected a vertex (coordinates out of its supported range).
    #[error("triangulation rejected vertex input: {reason}")]
    Triangulation {
        /// Reason given by the triangulation.
        reason: String,
    },
    /// Constraint edges crossed each other (near-degenerate input that snapping did not
    /// resolve).
    #[error("{count} boundary edges cross each other; the input is too close to degenerate")]
    ConstraintConflict {
        /// Number of conflicting constraint edges.
        count: usize,
    },
    /// Lengths of per-circle (or per-cell) input arrays disagree with the mesh.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A non-finite value in a motion state or a field.
    #[error("{what} {index}: non-finite value {value}")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The remap could not place an old cell's content: no admissible cell in the new mesh.
    #[error(
        "remap: old cell {cell} holds {value} of a {filter} field but the new mesh has no {filter} cell"
    )]
    NoTargetCell {
        /// Old cell index.
        cell: usize,
        /// Its content.
        value: f64,
        /// The target filter in words.
        filter: &'static str,
    },
    /// A picture or another output file could not be written.
    #[error("{path}: cannot write: {message}")]
    Output {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// Mesh construction from triangles failed.
    #[error(transparent)]
    Topology(#[from] TopologyError),
}
