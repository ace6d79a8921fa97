//! The crate's error type.

use std::path::PathBuf;

/// Everything that can go wrong while writing or reading a result file.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// A file or folder could not be created, written, renamed or read.
    #[error("{path}: {action} failed: {source}")]
    File {
        /// The file or folder concerned.
        path: PathBuf,
        /// What was being done (`create`, `write`, `rename`, `read`).
        action: &'static str,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A data array has the wrong number of tuples for its grid.
    #[error("field `{field}` has {len} {location} values, the grid has {expected} {location}s")]
    FieldLength {
        /// Name of the field.
        field: String,
        /// `point` or `cell`.
        location: &'static str,
        /// Number of tuples given.
        len: usize,
        /// Number of points or cells of the grid.
        expected: usize,
    },
    /// Two fields of the same location share a name.
    #[error("field name `{field}` is used twice for {location} data")]
    DuplicateField {
        /// The repeated name.
        field: String,
        /// `point` or `cell`.
        location: &'static str,
    },
    /// A cell refers to a point that does not exist.
    #[error(
        "cell {cell} refers to point {index}, the grid has {n_points} points (allowed 0..{n_points})"
    )]
    CellIndex {
        /// Index of the cell.
        cell: usize,
        /// The offending point index.
        index: usize,
        /// Number of points of the grid.
        n_points: usize,
    },
    /// A time, coordinate or spacing that must be finite (or positive) is not.
    #[error("{quantity} must be {requirement}, got {value}")]
    BadValue {
        /// What the value is.
        quantity: &'static str,
        /// The allowed range, in words.
        requirement: &'static str,
        /// The value given.
        value: f64,
    },
    /// A CSV row has the wrong number of values.
    #[error("{path}: a row has {len} values, the header names {expected} columns")]
    RowLength {
        /// The CSV file.
        path: PathBuf,
        /// Values given.
        len: usize,
        /// Columns in the header.
        expected: usize,
    },
    /// An existing file does not have the expected content (CSV header, PVD collection).
    #[error("{path}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file is not a checkpoint of this program.
    #[error("{path}: not a thm checkpoint ({message})")]
    NotACheckpoint {
        /// The file.
        path: PathBuf,
        /// What the decoder reported.
        message: String,
    },
    /// A checkpoint written by another version of the checkpoint container format.
    #[error(
        "{path}: checkpoint format version {found} (written by {writer}), this program reads version {expected}; resume it with the program that wrote it"
    )]
    CheckpointFormatVersion {
        /// The file.
        path: PathBuf,
        /// Version found in the file.
        found: u32,
        /// Version this program reads.
        expected: u32,
        /// The program that wrote the file, as its header says.
        writer: String,
    },
    /// A checkpoint that ends early: its writer was stopped before the file was complete.
    #[error(
        "{path}: checkpoint is truncated ({len} bytes; {message}); it was not completely written, resume from an earlier checkpoint"
    )]
    CheckpointTruncated {
        /// The file.
        path: PathBuf,
        /// Its length \[bytes\].
        len: u64,
        /// What shows it is incomplete.
        message: String,
    },
    /// A complete checkpoint whose checksum does not match its content.
    #[error(
        "{path}: checkpoint checksum mismatch (stored {stored:08x}, computed {computed:08x}): the file was altered or damaged; resume from another checkpoint"
    )]
    CheckpointChecksum {
        /// The file.
        path: PathBuf,
        /// The CRC-32 stored in the file.
        stored: u32,
        /// The CRC-32 of the content read.
        computed: u32,
    },
    /// A checkpoint of another kind of state (another scenario kind or crate).
    #[error("{path}: checkpoint holds a `{found}` state, expected `{expected}`")]
    CheckpointKind {
        /// The file.
        path: PathBuf,
        /// Kind tag found in the file.
        found: String,
        /// Kind tag expected by the caller.
        expected: String,
    },
    /// A checkpoint of the right kind but another version of its state layout.
    #[error(
        "{path}: `{kind}` checkpoint has state version {found} (written by {writer}), this program reads version {expected}"
    )]
    CheckpointStateVersion {
        /// The file.
        path: PathBuf,
        /// Kind tag.
        kind: String,
        /// Version found in the file.
        found: u32,
        /// Version this program reads.
        expected: u32,
        /// The program that wrote the file, as its header says.
        writer: String,
    },
    /// The checkpoint header matched but the state could not be decoded.
    #[error("{path}: checkpoint state does not decode: {message}")]
    CheckpointState {
        /// The file.
        path: PathBuf,
        /// What the decoder reported.
        message: String,
    },
    /// A plot could not be drawn.
    #[error("plot `{plot}`: {message}")]
    Plot {
        /// Name of the plot.
        plot: String,
        /// What went wrong.
        message: String,
    },
}

impl IoError {
    pub(crate) fn file(
        path: &std::path::Path,
        action: &'static str,
        source: std::io::Error,
    ) -> Self {
        Self::File {
            path: path.to_path_buf(),
            action,
            source,
        }
    }
}
